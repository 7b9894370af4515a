//! The polychromatic OTF and its mean up to a frequency limit, on the exact 1-D path.
//!
//! docs/physics.md, "Polychromatic OTF": the signed monochromatic OTFs are summed with the
//! detected-photoelectron weights `ρ(λ) τ(λ)` (source × filter × QE × λ, times the order's
//! efficiency), each at its own `s = ν λ F#`, and the MTF is the modulus of the sum:
//!
//! ```text
//! OTF_poly(ν) = Σ_orders ∫ ρ(λ) τ_o(λ) OTF(ν λ F#, W020_o(λ)/λ) dλ  /  Σ_orders ∫ ρ(λ) τ_o(λ) dλ
//! mean MTF    = (1/ν_max) ∫_0^{ν_max} P(ν) |OTF_poly(ν)| dν,   P = pixel MTF or 1
//! ```
//!
//! Numerics (each piece tested against [`crate::reference`]):
//! - **Spectral panels.** The wavelength axis is cut at every kink of the spectrum and of the lens
//!   tables, Gaussian factors are kept to ±[`GAUSSIAN_HALF_WIDTH_SIGMAS`] σ (the rest weighs
//!   2.6e-12), and panels are split until each is at most 2σ wide and the defocus phase at the
//!   highest frequency turns by at most [`quad::MAX_PANEL_PHASE`] across it.
//! - **Cutoff.** A wavelength contributes only while `s < 1`, i.e. `λ < 1/(ν F#)`. The panel that
//!   straddles that limit is clipped there and integrated in `u` with `λ = λ_cut − L u²`, which
//!   turns the `(1 − s)^{3/2}` edge of the OTF into a smooth integrand.
//! - **Frequency panels.** `[0, ν_max]` is cut where any spectral panel edge reaches its cutoff,
//!   and integrated by adaptive Gauss–Kronrod (7/15). Where `OTF_poly` changes sign inside a
//!   panel, the root is located (Illinois method) and the panel split there, so `|OTF_poly|` is
//!   only integrated where it is smooth.
//! - **Several orders.** The panels resolve the defocus phase of every order (and every zone of
//!   a composite pupil), matched between neighbouring wavelengths (`largest_turn`), not only the
//!   order of largest defocus, whose sign jumps between the channels of a multiplexed lens.
//! - **Tabulated orders** ([`Pupil::Table`]) are read at ν (T/S along the azimuth from the field
//!   direction) in place of the defocused OTF, on the exact path or beside the FFT layer's grids;
//!   composite pupils of zones ([`Pupil::Zones`]) get one FFT grid per node, of their coherent
//!   field (`fft::SampledZones`).
//! - **Line spectra** ([`Spectrum::as_line`]) skip all of the spectral part: the sum over λ is one
//!   term per imaging order at the line's wavelength ([`Engine::Monochromatic`]), whose cutoff is
//!   the one frequency cut.

use std::f64::consts::PI;

use std::cell::Cell;
use std::sync::Arc;

use num_complex::Complex64;
use radiometry::Spectrum;

use crate::closed::GaussianDefocus;
use crate::fft::{Aperture, Otf, OtfPlan, SampledPupil};

use crate::fft::{SampledZones, ZoneField};
use crate::lens::{Field, LensModel, Order, Pupil};
use crate::otf::{defocus_otf, pixel_mtf};
use crate::table::OtfTable;
use crate::{Error, quad};

/// Half-width, in standard deviations, kept of each Gaussian spectral factor: the area beyond
/// ±7σ is `erfc(7/√2)` = 2.6e-12 of the total, so neither the photoelectron count nor the
/// normalized polychromatic OTF moves by more than that (the OTF is bounded by 1). Wider windows
/// cost: the widest kept wavelength sets the largest defocus, and the work grows as its cube.
pub const GAUSSIAN_HALF_WIDTH_SIGMAS: f64 = 7.0;

/// The most initial frequency panels of one interval (the adaptive rule bisects further where
/// needed): a bound, so that no finite input asks for more panels than memory and time allow.
const MAX_PANELS: f64 = (1 << 20) as f64;

/// Memory the FFT path may hold in OTF grids, bytes (4 GiB: a sixth of the 24 GiB machines the
/// project is built for, so that a parallel sweep on two cores stays within memory). A scene
/// that needs more stops with [`Error::WorkBudget`] before allocating.
pub const FFT_MEMORY_BUDGET: f64 = 4.0 * (1u64 << 30) as f64;

/// Pupil samples across the diameter on the FFT path: the mean MTF of a defocused circle is then
/// within 2.5e-5 of the exact path (`fft` module convergence table; 1e-4 needs N ≥ 128).
pub const DEFAULT_PUPIL_SAMPLES: usize = 256;

/// How the OTF is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// The exact 1-D integral: centred circular pupils with defocus (and lateral shifts) only,
    /// and tabulated OTFs ([`Pupil::Table`]).
    Exact1d,
    /// The spectral integral in closed form ([`GaussianDefocus`]): a Gaussian × polynomial
    /// spectrum through one full pupil with defocus affine in λ; one adaptive integral left.
    ClosedForm,
    /// Sampled pupils by FFT: `pupil_samples` across the diameter, padded to `padded` points.
    Fft {
        /// Pupil samples across the diameter.
        pupil_samples: usize,
        /// FFT length after padding.
        padded: usize,
    },
    /// A line spectrum ([`Spectrum::as_line`]): one wavelength, one node per imaging order, no
    /// spectral quadrature. The OTF is the efficiency-weighted sum of the orders' exact OTFs
    /// there (complex with lateral shifts), each by the 1-D integral or, where its pupil or
    /// wavefront needs it, by FFT.
    Monochromatic {
        /// `Some((pupil samples across the diameter, FFT length after padding))` when some
        /// order goes through the FFT; `None` when every order is on the exact 1-D path.
        fft: Option<(usize, usize)>,
    },
}

struct FftNode {
    lambda: f64,
    weight: f64,
    shift: [f64; 2],
    kind: FftKind,
}

/// How an order's OTF is read on the FFT layer.
enum FftKind {
    /// A complex OTF grid: a sampled pupil or a composite of zones.
    Grid(Otf),
    /// A tabulated OTF ([`Pupil::Table`]), read at ν directly.
    Table(Arc<OtfTable>),
}

/// The FFT layer: one complex OTF grid per spectral node and order.
struct FftPath {
    nodes: Vec<FftNode>,
    pupil_samples: usize,
    padded: usize,
}

impl std::fmt::Debug for FftPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "FftPath {{ {} nodes, N = {}, M = {} }}", self.nodes.len(), self.pupil_samples, self.padded)
    }
}

/// Weight fraction below which a spectral node does not count towards the largest defocus.
const SIGNIFICANT_WEIGHT: f64 = 1e-13;

/// Bisection depth limit of the adaptive frequency integration.
const MAX_DEPTH: u32 = 40;

#[derive(Clone, Debug)]
struct Node {
    lambda: f64,
    /// quadrature weight × ρ(λ) × order efficiency
    weight: f64,
    /// W020 of the order, m
    w020: f64,
    /// image displacement on the detector, m
    shift: [f64; 2],
    /// the order's OTF table ([`Pupil::Table`]), read instead of the defocused OTF
    table: Option<Arc<OtfTable>>,
}

impl Node {
    /// The node of `order` at `lambda` with `weight` (quadrature weight × ρ × efficiency).
    fn of(order: &Order, lambda: f64, weight: f64) -> Node {
        Node {
            lambda,
            weight,
            // the largest zone defocus of a composite pupil (the frequency rule's statistics and
            // the Fraunhofer check of a line); the defocused OTF uses it only for a full pupil
            w020: crate::fraunhofer::order_defocus(order),
            shift: order.wavefront.image_shift_m,
            table: match &order.pupil {
                Pupil::Table(t) => Some(t.clone()),
                _ => None,
            },
        }
    }

    /// The real OTF of this node's order at `s = ν λ F#` (`s < 1`) along the direction at
    /// `azimuth_from_field` from the field direction (a table's T/S; the defocused OTF of a
    /// centred circle does not depend on it).
    fn otf(&self, s: f64, frequency: f64, azimuth_from_field: f64) -> f64 {
        match &self.table {
            None => defocus_otf(s, self.w020 / self.lambda),
            Some(t) => t.value(self.lambda, frequency, azimuth_from_field),
        }
    }
}

/// Whether `order` needs the FFT layer: a pupil other than the full circle (an aperture, a
/// composite of zones), or a wavefront beyond defocus; a tabulated OTF is read directly.
fn needs_grid(order: &Order) -> bool {
    match &order.pupil {
        Pupil::Full => !order.wavefront.is_defocus_only(),
        Pupil::Table(_) => false,
        _ => true,
    }
}

/// Efficiency, relative to the sum over the orders, below which an order does not count in the
/// spectral panels' phase-turn rule (it cannot move the OTF by more than that).
const NEGLIGIBLE_EFFICIENCY: f64 = 1e-9;

/// Efficiency, relative to the sum over the orders, up to which an order may be present at one
/// end of a spectral panel and absent at the other without counting as a jump ([`largest_turn`]):
/// an order entering or leaving the window of a harmonic lens (`sinc²(3 − δ) ≈ δ²/9` at the window
/// edge), whose weight jumps by no more than that whatever the panel.
const VANISHING_EFFICIENCY: f64 = 1e-3;

/// One order's defocus at one wavelength for the phase-turn rule, with whether its efficiency
/// is small enough to appear or vanish between neighbouring wavelengths.
#[derive(Clone, Copy, Debug)]
struct PhaseEntry {
    w020: f64,
    vanishing: bool,
}

/// The defocus values whose phase the spectral panels must resolve at `lambda`, sorted: one per
/// order of non-negligible efficiency, one per zone (of non-zero amplitude) of a composite pupil
/// (each with its order's efficiency), none for a tabulated OTF (its rows are interpolated
/// linearly in λ and the panels are cut at them).
fn phase_defocus(lens: &dyn LensModel, lambda: f64, field: Field) -> Vec<PhaseEntry> {
    let orders = lens.orders(lambda, field);
    let total: f64 = orders.iter().map(|o| o.efficiency.abs()).sum();
    let mut out = Vec::new();
    for o in orders.iter().filter(|o| o.efficiency.abs() > NEGLIGIBLE_EFFICIENCY * total) {
        let vanishing = o.efficiency.abs() <= VANISHING_EFFICIENCY * total;
        match &o.pupil {
            Pupil::Table(_) => {}
            Pupil::Zones(zones) => out.extend(
                zones
                    .iter()
                    .filter(|z| z.amplitude > 0.0)
                    .map(|z| PhaseEntry { w020: z.wavefront.defocus_m, vanishing }),
            ),
            _ => out.push(PhaseEntry { w020: o.wavefront.defocus_m, vanishing }),
        }
    }
    out.sort_by(|a, b| a.w020.total_cmp(&b.w020));
    out
}

/// The largest change of one order's defocus between two neighbouring wavelengths whose defocus
/// lists ([`phase_defocus`], sorted) are `from` and `to`.
///
/// Orders carry no identity across wavelengths, so they are matched: by the monotone alignment
/// of the sorted lists that leaves the fewest orders of non-vanishing efficiency unmatched, and
/// among those the smallest largest change (a bottleneck alignment, by dynamic programming). An
/// order entering or leaving the window of a harmonic lens, with an efficiency near zero there,
/// stays unmatched (its weight jumps by that little, which no panel refines away), while the
/// channels of a multiplexed lens, all bright, are matched one to one in W020 order, which is
/// their own order since their defocus curves do not cross: a shift of every channel by one
/// channel spacing across a panel counts as that large change, not as none. Measuring the
/// largest-|W020| order alone jumped between orders of opposite sign, and matching by list
/// index alone mistook a shifted window (orders 1–6 → 2–7) for a jump of every order; both
/// refined without end (the panel bound, 2^20 panels, for an interleaved or harmonic lens over
/// 50–200 nm).
fn largest_turn(from: &[PhaseEntry], to: &[PhaseEntry]) -> f64 {
    let (n, m) = (from.len(), to.len());
    // cost[i][j]: (unmatched bright orders, largest change) aligning from[..i] with to[..j],
    // compared lexicographically (the sum in the first and the maximum in the second are both
    // monotone, so the cell-wise minimum is the optimum)
    let mut cost = vec![(usize::MAX, f64::INFINITY); (n + 1) * (m + 1)];
    let at = |i: usize, j: usize| i * (m + 1) + j;
    cost[at(0, 0)] = (0, 0.0);
    let better = |a: (usize, f64), b: (usize, f64)| a.0 < b.0 || (a.0 == b.0 && a.1 < b.1);
    for i in 0..=n {
        for j in 0..=m {
            let mut best = cost[at(i, j)];
            if i > 0 && cost[at(i - 1, j)].0 != usize::MAX {
                let (c, t) = cost[at(i - 1, j)];
                let candidate = (c + usize::from(!from[i - 1].vanishing), t);
                if better(candidate, best) {
                    best = candidate;
                }
            }
            if j > 0 && cost[at(i, j - 1)].0 != usize::MAX {
                let (c, t) = cost[at(i, j - 1)];
                let candidate = (c + usize::from(!to[j - 1].vanishing), t);
                if better(candidate, best) {
                    best = candidate;
                }
            }
            if i > 0 && j > 0 && cost[at(i - 1, j - 1)].0 != usize::MAX {
                let (c, t) = cost[at(i - 1, j - 1)];
                let candidate = (c, t.max((from[i - 1].w020 - to[j - 1].w020).abs()));
                if better(candidate, best) {
                    best = candidate;
                }
            }
            cost[at(i, j)] = best;
        }
    }
    cost[at(n, m)].1
}

#[derive(Clone, Copy, Debug)]
struct Panel {
    lo: f64,
    hi: f64,
    /// nodes[start..end] of the unclipped panel
    start: usize,
    end: usize,
}

/// Counts of what an evaluation did, for `--explain` and the accuracy report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Work {
    /// Spectral panels (each with [`quad::ORDER`] nodes per imaging order).
    pub spectral_panels: usize,
    /// Spectral nodes, summed over orders.
    pub spectral_nodes: usize,
    /// Frequency panels after splitting at sign changes.
    pub frequency_panels: usize,
    /// Evaluations of the polychromatic OTF.
    pub otf_evaluations: usize,
    /// Sign changes of the polychromatic OTF located below the frequency limit.
    pub sign_changes: usize,
    /// Evaluations of the closed-form spectral integral `E(c)` (closed-form engine only).
    pub closed_form_evaluations: usize,
}

/// A non-white noise spectrum: the noise amplitude at spatial frequency ν relative to the
/// white level that SNR0 uses, `n(ν)` (1 = white), piecewise linear between its samples and
/// constant beyond its ends.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseShape {
    frequencies: Vec<f64>,
    relative: Vec<f64>,
}

impl NoiseShape {
    /// `relative[i]` at `frequencies[i]` (cycles/m, ≥ 0, strictly increasing, at least two);
    /// every relative amplitude finite and > 0.
    pub fn new(frequencies: Vec<f64>, relative: Vec<f64>) -> Result<NoiseShape, Error> {
        let bad = |name, value, expected| Err(Error::InvalidParameter { name, value, expected });
        if frequencies.len() < 2 || frequencies.len() != relative.len() {
            return bad(
                "noise spectrum samples",
                frequencies.len() as f64,
                "at least two (frequency, amplitude) pairs",
            );
        }
        for (i, &f) in frequencies.iter().enumerate() {
            if !(f.is_finite() && f >= 0.0) || (i > 0 && f <= frequencies[i - 1]) {
                return bad("noise spectrum frequency", f, "finite, ≥ 0 and strictly increasing cycles/m");
            }
        }
        if let Some(&v) = relative.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return bad("relative noise amplitude", v, "finite and > 0 (1 = the white level)");
        }
        Ok(NoiseShape { frequencies, relative })
    }

    /// `n(ν)` at `frequency` (cycles/m, sign ignored).
    pub fn value(&self, frequency: f64) -> f64 {
        let nu = frequency.abs();
        let (x, y) = (&self.frequencies, &self.relative);
        let i = x.partition_point(|&f| f <= nu);
        if i == 0 {
            return y[0];
        }
        if i == x.len() {
            return y[x.len() - 1];
        }
        let t = (nu - x[i - 1]) / (x[i] - x[i - 1]);
        y[i - 1] + t * (y[i] - y[i - 1])
    }
}

/// How a [`Polychromatic`] is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Pupil samples across the diameter on the FFT path: `None` lets the tolerance choose
    /// them; `Some(n)` fixes them (the result then has the FFT path's error at `n`, whatever
    /// the tolerance).
    pub pupil_samples: Option<usize>,
    /// Relative error allowed in the mean MTF.
    pub tolerance: f64,
    /// Whether the closed-form engine may be used where it applies.
    pub closed_form: bool,
    /// The spectral rule of the quadrature engines.
    pub spectral_rule: SpectralRule,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            pupil_samples: None,
            tolerance: DEFAULT_TOLERANCE,
            closed_form: true,
            spectral_rule: SpectralRule::default(),
        }
    }
}

/// How the integral over wavelength is done where no closed form applies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpectralRule {
    /// Product integration: the OTF, smooth in λ, is interpolated at nodes whose number follows
    /// its defocus phase and the tolerance; the weights are the exact moments of the detected
    /// spectrum against the interpolation basis, so kinks of a measured spectrum cost nothing.
    #[default]
    Interpolated,
    /// The per-interval rule, kept as the reference: 16-point Gauss–Legendre panels cut at every
    /// kink of the spectrum and of the lens and refined until the defocus phase turns by at most
    /// 12 rad per panel; exact to rounding whatever the tolerance, at a cost that grows with
    /// the number of table samples.
    Panels,
}

/// Default relative tolerance of the mean MTF.
pub const DEFAULT_TOLERANCE: f64 = 1e-6;

/// A prepared polychromatic evaluation: spectral nodes and weights for one lens, detected
/// spectrum and field point, valid for frequencies up to `max_frequency`.
#[derive(Debug)]
pub struct Polychromatic<'a> {
    lens: &'a dyn LensModel,
    detected: &'a Spectrum,
    field: Field,
    f_number: f64,
    max_frequency: f64,
    pixel_pitch: Option<f64>,
    nodes: Vec<Node>,
    /// (λ, quadrature weight × ρ(λ)) at every unclipped spectral node, before the lens
    samples: Vec<(f64, f64)>,
    panels: Vec<Panel>,
    total_weight: f64,
    /// largest |W020| among significant nodes, m
    w020_max: f64,
    /// weighted RMS of W020, m
    w020_rms: f64,
    /// whether any node's image is displaced (the OTF is then complex off the shift-free axis)
    shifted: bool,
    /// whether some tabulated order has different tangential and sagittal curves
    directional_tables: bool,
    /// set while emitting nodes if some order needs a sampled pupil
    needs_fft: Cell<bool>,
    /// the FFT layer, when some order's pupil or wavefront is beyond the exact path
    fft: Option<FftPath>,
    /// the closed-form spectral integral, when it applies
    closed: Option<GaussianDefocus>,
    /// relative tolerance of the mean MTF
    tolerance: f64,
    /// absolute tolerance of one closed-form OTF value (set by the mean)
    otf_tolerance: Cell<f64>,
    /// closed-form E(c) evaluations so far
    closed_evaluations: Cell<usize>,
}

impl<'a> Polychromatic<'a> {
    /// Prepares the spectral quadrature for `lens` seen through the `detected` spectrum.
    ///
    /// `detected` is the spectral density of detected photons *before* the lens efficiency:
    /// source radiance × filter × quantum efficiency × λ (paper SI eq. S8), any scale.
    /// `max_frequency` (cycles/m) is the upper end of the mean, usually the Nyquist frequency
    /// `1/(2p)`; `pixel_pitch` (m), if given, multiplies the MTF by the pixel-aperture MTF.
    pub fn new(
        lens: &'a dyn LensModel,
        detected: &'a Spectrum,
        field: Field,
        max_frequency: f64,
        pixel_pitch: Option<f64>,
    ) -> Result<Self, Error> {
        Self::with_pupil_samples(lens, detected, field, max_frequency, pixel_pitch, DEFAULT_PUPIL_SAMPLES)
    }

    /// [`new`](Self::new) with `pupil_samples` across the diameter for orders that need the FFT
    /// path (ignored on the exact path).
    pub fn with_pupil_samples(
        lens: &'a dyn LensModel,
        detected: &'a Spectrum,
        field: Field,
        max_frequency: f64,
        pixel_pitch: Option<f64>,
        pupil_samples: usize,
    ) -> Result<Self, Error> {
        let settings = Settings { pupil_samples: Some(pupil_samples), ..Settings::default() };
        Self::with_settings(lens, detected, field, max_frequency, pixel_pitch, settings)
    }

    /// [`new`](Self::new) with explicit [`Settings`]: the tolerance, the pupil sampling of the
    /// FFT path, and whether the closed-form engine may be used.
    ///
    /// The closed-form engine is chosen when the detected spectrum is a Gaussian times a
    /// polynomial ([`Spectrum::gaussian_polynomial`]) and the lens promises an affine defocus
    /// ([`LensModel::affine_defocus`]) that its [`orders`](LensModel::orders) confirm. A line
    /// spectrum ([`Spectrum::as_line`]) is one wavelength ([`Engine::Monochromatic`]): one node
    /// per imaging order, no spectral quadrature.
    pub fn with_settings(
        lens: &'a dyn LensModel,
        detected: &'a Spectrum,
        field: Field,
        max_frequency: f64,
        pixel_pitch: Option<f64>,
        settings: Settings,
    ) -> Result<Self, Error> {
        let pupil_samples = settings.pupil_samples.unwrap_or(DEFAULT_PUPIL_SAMPLES);
        if !(settings.tolerance.is_finite() && settings.tolerance > 0.0 && settings.tolerance < 1.0) {
            return Err(Error::InvalidParameter {
                name: "tolerance",
                value: settings.tolerance,
                expected: "a relative error in (0, 1), e.g. 1e-6",
            });
        }
        let f_number = lens.f_number();
        if !(max_frequency.is_finite() && max_frequency > 0.0) {
            return Err(Error::InvalidParameter {
                name: "max_frequency",
                value: max_frequency,
                expected: "finite and > 0 cycles/m",
            });
        }
        if let Some(line) = detected.as_line() {
            return Self::monochromatic(lens, detected, field, max_frequency, pixel_pitch, settings, line);
        }
        let (lo, hi) = spectral_extent(detected)?;
        let mut cuts: Vec<f64> = detected
            .breakpoints()
            .into_iter()
            .chain(lens.breakpoints())
            .chain(table_wavelengths(lens, field, lo, hi))
            .filter(|&b| b > lo && b < hi)
            .collect();
        cuts.push(lo);
        cuts.push(hi);
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        let sigma_min = detected.gaussians().iter().map(|g| g.sigma()).fold(f64::INFINITY, f64::min);

        let mut this = Self::empty(lens, detected, field, max_frequency, pixel_pitch, settings);
        if settings.closed_form
            && let Some((closed, affine)) = closed_form(lens, detected, field)
        {
            this.closed_nodes(&closed, affine);
            this.closed = Some(closed);
            return Ok(this);
        }
        // no wavelength contributes past its cutoff: the highest frequency that matters is the
        // cutoff of the shortest wavelength covered, when it is below max_frequency
        let highest = max_frequency.min(highest_cutoff(lens, detected)?);
        let phase_per_w020 = 8.0 * PI * f_number * highest;
        for pair in cuts.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let mut n = ((b - a) / (2.0 * sigma_min)).ceil().max(1.0) as usize;
            // refine until the defocus phase at max_frequency turns ≤ MAX_PANEL_PHASE per panel
            loop {
                let h = (b - a) / n as f64;
                let mut worst: f64 = 0.0;
                // the interval's ends are read just inside it: a lens may jump at its own
                // breakpoints (the band edges of a multiplexed lens whose other channels are
                // background), which are the interval's ends, and a jump there is no turn of
                // the phase inside (the quadrature nodes never reach the ends)
                let inside = 1e-9 * (b - a);
                let mut prev = phase_defocus(lens, a + inside, field);
                for k in 1..=n {
                    let x = if k == n { b - inside } else { a + h * k as f64 };
                    let cur = phase_defocus(lens, x, field);
                    let mid = phase_defocus(lens, x - 0.5 * h, field);
                    // per order (docs/physics.md, "Spectral quadrature": the OTF turns with the
                    // defocus in waves at each s), the change of W020 across the panel plus the
                    // change of s = ν λ F# times the largest |W020|
                    let largest = cur.iter().chain(&prev).map(|e| e.w020.abs()).fold(0.0, f64::max);
                    let turn =
                        largest_turn(&prev, &cur).max(largest_turn(&prev, &mid)) + largest * highest * f_number * h;
                    worst = worst.max(turn * phase_per_w020);
                    prev = cur;
                }
                if worst <= quad::MAX_PANEL_PHASE || n > 1 << 20 {
                    break;
                }
                n = (n as f64 * (worst / quad::MAX_PANEL_PHASE).min(64.0)).ceil() as usize + 1;
            }
            let h = (b - a) / n as f64;
            for k in 0..n {
                let (plo, phi) = (a + h * k as f64, a + h * (k + 1) as f64);
                let start = this.nodes.len();
                let (mut nodes, mut samples) = (Vec::new(), Vec::new());
                quad::for_each_node(plo, phi, 1, |lambda, q| {
                    samples.push((lambda, q * detected.value(lambda)));
                    this.emit_orders(lambda, q, &mut |node| nodes.push(node));
                });
                this.nodes.extend(nodes);
                this.samples.extend(samples);
                this.panels.push(Panel { lo: plo, hi: phi, start, end: this.nodes.len() });
            }
        }
        // summed panel by panel, in the order `otf` sums, so that OTF(0) is exactly 1
        this.total_weight =
            this.panels.iter().map(|p| this.nodes[p.start..p.end].iter().map(|n| n.weight).sum::<f64>()).sum();
        this.finish(pupil_samples)
    }

    /// The common end of the node-based constructors, once the nodes and the total weight are
    /// set: a signal must be there; the defocus statistics, the lateral-shift flag and, where
    /// some order needs it, the FFT layer.
    fn finish(mut self, pupil_samples: usize) -> Result<Self, Error> {
        if !(self.total_weight > 0.0 && self.total_weight.is_finite()) {
            return Err(Error::NoSignal { total: self.total_weight });
        }
        self.defocus_statistics();
        self.shifted = self.nodes.iter().any(|n| n.shift != [0.0, 0.0]);
        self.directional_tables =
            self.nodes.iter().any(|n| n.table.as_ref().is_some_and(|t| t.is_direction_dependent()));
        if self.needs_fft.get() {
            self.fft = Some(self.build_fft(pupil_samples)?);
        }
        Ok(self)
    }

    /// The evaluation of a line spectrum (`line` = [`Spectrum::as_line`] of `detected`): one node
    /// per imaging order at the line's wavelength, weighted by the line's weight × the order's
    /// efficiency; no spectral panels, no clipping at the cutoff (the wavelength passes a
    /// frequency or not), and an FFT grid per order only where a pupil needs one.
    fn monochromatic(
        lens: &'a dyn LensModel,
        detected: &'a Spectrum,
        field: Field,
        max_frequency: f64,
        pixel_pitch: Option<f64>,
        settings: Settings,
        line: radiometry::QuadratureNode,
    ) -> Result<Self, Error> {
        let lambda = line.wavelength_m;
        let mut this = Self::empty(lens, detected, field, max_frequency, pixel_pitch, settings);
        this.samples = vec![(lambda, line.weight)];
        for order in lens.orders(lambda, field) {
            if needs_grid(&order) {
                this.needs_fft.set(true);
            }
            this.nodes.push(Node::of(&order, lambda, line.weight * order.efficiency));
        }
        this.total_weight = this.nodes.iter().map(|n| n.weight).sum();
        this.finish(settings.pupil_samples.unwrap_or(DEFAULT_PUPIL_SAMPLES))
    }

    /// The wavelength of a line spectrum ([`Engine::Monochromatic`]): the only case without
    /// spectral panels (the quadrature has at least one, the closed form one for its averages).
    fn line(&self) -> Option<f64> {
        if self.panels.is_empty() { self.samples.first().map(|s| s.0) } else { None }
    }

    /// A preparation with no nodes yet, for the constructors to fill.
    fn empty(
        lens: &'a dyn LensModel,
        detected: &'a Spectrum,
        field: Field,
        max_frequency: f64,
        pixel_pitch: Option<f64>,
        settings: Settings,
    ) -> Self {
        Polychromatic {
            lens,
            detected,
            field,
            f_number: lens.f_number(),
            max_frequency,
            pixel_pitch,
            nodes: Vec::new(),
            samples: Vec::new(),
            panels: Vec::new(),
            total_weight: 0.0,
            w020_max: 0.0,
            w020_rms: 0.0,
            shifted: false,
            directional_tables: false,
            needs_fft: Cell::new(false),
            fft: None,
            closed: None,
            tolerance: settings.tolerance,
            otf_tolerance: Cell::new(0.05 * settings.tolerance),
            closed_evaluations: Cell::new(0),
        }
    }

    /// The spectral nodes of the closed-form engine: not for the OTF (its spectral integral is
    /// exact) but for the averages over the spectrum ([`detected_integral`](Self::detected_integral),
    /// [`spectral_average`](Self::spectral_average)): 8 Gauss–Legendre panels over μ ± 10σ,
    /// exact to rounding for the smooth functions they are used with.
    fn closed_nodes(&mut self, closed: &GaussianDefocus, affine: crate::AffineDefocus) {
        let (mu, sigma) = (closed.center(), closed.sigma());
        let (lo, hi) = ((mu - 10.0 * sigma).max(0.0), mu + 10.0 * sigma);
        let (mut samples, mut nodes) = (Vec::new(), Vec::new());
        quad::for_each_node(lo, hi, 8, |lambda, q| {
            let q_rho = q * self.detected.value(lambda);
            samples.push((lambda, q_rho));
            nodes.push(Node {
                lambda,
                weight: q_rho * affine.efficiency,
                w020: affine.w020_intercept_m + affine.w020_slope * lambda,
                shift: [0.0, 0.0],
                table: None,
            });
        });
        self.panels.push(Panel { lo, hi, start: 0, end: nodes.len() });
        self.samples = samples;
        self.nodes = nodes;
        self.total_weight = closed.total_weight();
        self.defocus_statistics();
    }

    /// The largest |W020| among the nodes that carry weight, and the weighted RMS of W020 (the
    /// frequency rule's initial panels), once the nodes and the total weight are known.
    fn defocus_statistics(&mut self) {
        let threshold = SIGNIFICANT_WEIGHT * self.total_weight;
        self.w020_max =
            self.nodes.iter().filter(|n| n.weight.abs() > threshold).map(|n| n.w020.abs()).fold(0.0, f64::max);
        self.w020_rms = self.spectral_average(|_, w020| w020 * w020).sqrt();
    }

    /// Emits the nodes of `[lo, cut]` in `u`, `λ = cut − (cut − lo) u²`, for the clipped panel.
    fn clipped_nodes(&self, lo: f64, cut: f64, mut emit: impl FnMut(Node)) {
        let len = cut - lo;
        quad::for_each_node(0.0, 1.0, 1, |u, q| {
            self.emit_orders(cut - len * u * u, q * 2.0 * len * u, &mut emit);
        });
    }

    fn emit_orders(&self, lambda: f64, q: f64, emit: &mut impl FnMut(Node)) {
        let rho = self.detected.value(lambda);
        if rho == 0.0 {
            return;
        }
        for order in self.lens.orders(lambda, self.field) {
            if needs_grid(&order) {
                self.needs_fft.set(true);
            }
            emit(Node::of(&order, lambda, q * rho * order.efficiency));
        }
    }

    /// One complex OTF grid per unclipped spectral node and order, from one reused plan (a
    /// tabulated order is read directly); sampled pupils and zones are cached while their
    /// apertures (the same `Arc`s) stay the same.
    fn build_fft(&self, pupil_samples: usize) -> Result<FftPath, Error> {
        let lambda_max = self.samples.iter().map(|s| s.0).fold(0.0, f64::max);
        let s_max = (self.max_frequency * lambda_max * self.f_number).min(1.0);
        let mut layer = FftLayer::new(pupil_samples, s_max, self.lens.numerical_aperture())?;
        // memory budget: one (2K + 1)² complex grid per spectral node and order on the grid path,
        // counted before any is made (a 300 nm band at 1024 samples would hold 12 GB)
        let side = 2 * layer.plan.max_lag() + 1;
        let grid_bytes = (side * side * std::mem::size_of::<Complex64>()) as f64;
        // (the unclipped nodes are those orders, one per order at each sample of the spectrum;
        // a tabulated order is read directly)
        let grids = self.nodes.iter().filter(|n| n.table.is_none()).count();
        if grids as f64 * grid_bytes > FFT_MEMORY_BUDGET {
            return Err(Error::WorkBudget {
                grids,
                grid_mb: grid_bytes / 1e6,
                total_gib: grids as f64 * grid_bytes / f64::from(1u32 << 30),
                budget_gib: FFT_MEMORY_BUDGET / f64::from(1u32 << 30),
                pupil_samples,
            });
        }
        let mut nodes = Vec::new();
        for &(lambda, q_rho) in &self.samples {
            if q_rho == 0.0 {
                continue;
            }
            for order in self.lens.orders(lambda, self.field) {
                nodes.push(FftNode {
                    lambda,
                    weight: q_rho * order.efficiency,
                    shift: order.wavefront.image_shift_m,
                    kind: layer.kind(&order, lambda)?,
                });
            }
        }
        Ok(FftPath { nodes, pupil_samples, padded: layer.plan.padded_len() })
    }

    /// The OTF engine in use.
    pub fn engine(&self) -> Engine {
        if self.closed.is_some() {
            return Engine::ClosedForm;
        }
        if self.line().is_some() {
            return Engine::Monochromatic { fft: self.fft.as_ref().map(|f| (f.pupil_samples, f.padded)) };
        }
        match &self.fft {
            Some(f) => Engine::Fft { pupil_samples: f.pupil_samples, padded: f.padded },
            None => Engine::Exact1d,
        }
    }

    /// Whether the OTF depends on direction (lateral colour, or a non-symmetric pupil or
    /// wavefront): the MTF must then be read along an azimuth.
    pub fn direction_dependent(&self) -> bool {
        self.shifted || self.fft.is_some() || self.directional_tables
    }

    /// `∫ ρ(λ) τ(λ) dλ` summed over the imaging orders: the detected-signal integral in the units
    /// of the `detected` spectrum.
    pub fn total_weight(&self) -> f64 {
        self.total_weight
    }

    /// `∫ ρ(λ) f(λ) dλ` over the detected spectrum *before* the lens (no efficiency factor),
    /// with the same quadrature.
    pub fn detected_integral(&self, mut f: impl FnMut(f64) -> f64) -> f64 {
        self.samples.iter().map(|&(lambda, q_rho)| q_rho * f(lambda)).sum()
    }

    /// Weighted average of `f(λ, W020)` over the detected spectrum (weights `ρ τ`).
    pub fn spectral_average(&self, mut f: impl FnMut(f64, f64) -> f64) -> f64 {
        self.nodes.iter().map(|n| n.weight * f(n.lambda, n.w020)).sum::<f64>() / self.total_weight
    }

    /// Calls `visit(weight × OTF(s, w), shift)` for every spectral node that passes `frequency`.
    /// A tabulated order is read along `azimuth_from_field` (radians from the field direction).
    fn contributions(&self, frequency: f64, azimuth_from_field: f64, mut visit: impl FnMut(f64, [f64; 2])) {
        let nu = frequency.abs();
        let nuf = nu * self.f_number;
        let cut = if nu > 0.0 { 1.0 / nuf } else { f64::INFINITY };
        let mut term = |n: &Node| visit(n.weight * n.otf(nuf * n.lambda, nu, azimuth_from_field), n.shift);
        if let Some(lambda) = self.line() {
            // one wavelength: it passes this frequency or not
            if lambda < cut {
                self.nodes.iter().for_each(&mut term);
            }
            return;
        }
        for p in &self.panels {
            if p.hi <= cut {
                self.nodes[p.start..p.end].iter().for_each(&mut term);
            } else if p.lo < cut {
                self.clipped_nodes(p.lo, cut, |n| term(&n));
            }
        }
    }

    /// Signed polychromatic OTF at `frequency` (cycles/m), normalized to 1 at zero frequency, of
    /// the rotationally symmetric system: image displacements are ignored (see
    /// [`otf_along`](Self::otf_along) for the complex OTF with lateral colour).
    pub fn otf(&self, frequency: f64) -> f64 {
        if frequency == 0.0 {
            return 1.0;
        }
        if let Some(closed) = &self.closed {
            let (value, evaluations) = closed.otf(frequency, self.otf_tolerance.get());
            self.closed_evaluations.set(self.closed_evaluations.get() + evaluations);
            return value;
        }
        if self.fft.is_some() {
            // no rotational symmetry to rely on: the real part along +x
            return self.otf_along(frequency, 0.0).re;
        }
        let mut sum = 0.0;
        // along +x: a tabulated order's direction relative to the field's
        self.contributions(frequency, -self.field_direction(), |v, _| sum += v);
        sum / self.total_weight
    }

    /// Complex polychromatic OTF at `frequency` (cycles/m) along the direction `azimuth` (radians
    /// from the detector's x axis): each wavelength's OTF times `exp(−2πi ν u·Δ)` for its image
    /// displacement Δ (docs/physics.md: in the general case sum complex OTFs, then take the modulus).
    pub fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64 {
        if frequency == 0.0 {
            return Complex64::new(1.0, 0.0);
        }
        if self.closed.is_some() {
            // on axis, rotationally symmetric and real
            return Complex64::new(self.otf(frequency), 0.0);
        }
        let (sin_a, cos_a) = azimuth.sin_cos();
        let k = -2.0 * PI * frequency;
        let mut sum = Complex64::new(0.0, 0.0);
        if let Some(fft) = &self.fft {
            let nuf = frequency.abs() * self.f_number;
            // OTF(−ν) = OTF(ν)*: read the grid at |ν| along the azimuth turned by π
            let azimuth = if frequency < 0.0 { azimuth + PI } else { azimuth };
            let from_field = azimuth - self.field_direction();
            for n in &fft.nodes {
                let s = nuf * n.lambda;
                if s >= 1.0 {
                    continue;
                }
                let mut v = match &n.kind {
                    FftKind::Grid(otf) if s <= otf.s_max() => otf.at(s, azimuth) * n.weight,
                    FftKind::Grid(_) => continue,
                    FftKind::Table(t) => Complex64::new(t.value(n.lambda, frequency, from_field) * n.weight, 0.0),
                };
                let [dx, dy] = n.shift;
                if dx != 0.0 || dy != 0.0 {
                    let (ps, pc) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
                    v *= Complex64::new(pc, ps);
                }
                sum += v;
            }
            return sum / self.total_weight;
        }
        self.contributions(frequency, azimuth - self.field_direction(), |v, [dx, dy]| {
            if dx == 0.0 && dy == 0.0 {
                sum.re += v;
            } else {
                let (s, c) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
                sum += Complex64::new(v * c, v * s);
            }
        });
        sum / self.total_weight
    }

    /// The field direction on the detector, radians from `+x`: `atan2(y, x)` of the field
    /// angles, `+x` on axis (docs/physics.md, "Off-axis MTFs: tangential and sagittal"); a
    /// tabulated order's tangential curve lies along it.
    fn field_direction(&self) -> f64 {
        self.field.y_rad.atan2(self.field.x_rad)
    }

    /// Whether some wavelength's image is displaced, so that the OTF is complex and depends on
    /// the direction.
    pub fn has_lateral_shifts(&self) -> bool {
        self.shifted
    }

    /// Polychromatic MTF along `azimuth`: `|OTF|` times the pixel MTF along a pixel axis.
    pub fn mtf_along(&self, frequency: f64, azimuth: f64) -> f64 {
        self.otf_along(frequency, azimuth).norm() * self.pixel_factor(frequency)
    }

    /// Polychromatic MTF at `frequency`: `|OTF_poly|`, times the pixel MTF if enabled.
    pub fn mtf(&self, frequency: f64) -> f64 {
        self.otf(frequency).abs() * self.pixel_factor(frequency)
    }

    fn pixel_factor(&self, frequency: f64) -> f64 {
        self.pixel_pitch.map_or(1.0, |p| pixel_mtf(p, frequency))
    }

    /// Frequencies in `(0, max_frequency)` where `OTF_poly` may have a kink: a spectral panel edge
    /// reaching its cutoff.
    fn frequency_cuts(&self) -> Vec<f64> {
        let mut cuts = vec![0.0, self.max_frequency];
        if let Some(closed) = &self.closed {
            // the closed form is exact across the spectrum: no panel edges, no kinks; but where
            // the cutoffs 1/(λ F#) of the Gaussian's centre and flanks lie below max_frequency, the
            // OTF is non-zero on a small part of the range only, which one panel's nodes can miss
            // entirely (F/1e4: cutoff at 1/770 of Nyquist): cut there
            let (mu, sigma) = (closed.center(), closed.sigma());
            for k in 0..=GAUSSIAN_HALF_WIDTH_SIGMAS as usize {
                let lambda = mu - k as f64 * sigma;
                let nu = 1.0 / (lambda * self.f_number);
                if lambda > 0.0 && nu < self.max_frequency {
                    cuts.push(nu);
                }
            }
            // and where the OTF vanishes altogether (the averages' shortest wavelength)
            if self.max_cutoff() < self.max_frequency {
                cuts.push(self.max_cutoff());
            }
            cuts.sort_by(f64::total_cmp);
            cuts.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * a.abs().max(b.abs()));
            return cuts;
        }
        // panel edges, or the one wavelength of a line, reaching their cutoffs (merged when within
        // 1e-12 of each other, relative to themselves: a 1e-206 m pixel puts Nyquist 1e200 times
        // above them)
        let ends = self.panels.iter().flat_map(|p| [p.lo, p.hi]);
        for lambda in ends.chain(self.line()) {
            if lambda > 0.0 {
                let nu = 1.0 / (lambda * self.f_number);
                if nu < self.max_frequency {
                    cuts.push(nu);
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * a.abs().max(b.abs()));
        cuts
    }

    /// The mean of the MTF over `[0, max_frequency]` and what it took.
    ///
    /// Adaptive Gauss–Kronrod (7/15) on frequency panels: a panel is accepted when the Kronrod
    /// and Gauss sums of `P |OTF_poly|` differ by less than the tolerance of the
    /// frequency range times its share of the range, and bisected otherwise. A panel whose
    /// samples change sign is split at the located zeros first, so `|OTF_poly|` is only ever
    /// integrated where it is smooth. The initial panels are sized by the weighted-RMS defocus.
    pub fn mean_mtf(&self) -> (f64, Work) {
        if self.direction_dependent() {
            return self.mean_mtf_along(0.0);
        }
        self.mean_of(&|nu| self.otf(nu))
    }

    /// The mean of the MTF along `azimuth` (radians from the x axis) over `[0, max_frequency]`:
    /// [`mean_mtf`](Self::mean_mtf) for the complex OTF of a system with lateral colour. Without
    /// image displacements it equals [`mean_mtf`](Self::mean_mtf).
    pub fn mean_mtf_along(&self, azimuth: f64) -> (f64, Work) {
        if !self.direction_dependent() {
            return self.mean_mtf();
        }
        // |OTF| ≥ 0: no sign changes to split at, only isolated zeros the adaptive rule resolves
        self.mean_of(&|nu| self.otf_along(nu, azimuth).norm())
    }

    /// The mean over `[0, max_frequency]` of `P(ν) |OTF(ν)| / n(ν)` for a non-white noise
    /// spectrum `n` (paper eq. 1 text: "if this is not the case, the SNR can be placed inside the
    /// integral"): times SNR0 it is the ASNR with the noise amplitude `n(ν) σ` at each frequency.
    /// Along `azimuth` when the OTF depends on direction.
    pub fn mean_mtf_over_noise(&self, noise: &NoiseShape, azimuth: f64) -> (f64, Work) {
        if self.direction_dependent() {
            self.mean_of(&|nu| self.otf_along(nu, azimuth).norm() / noise.value(nu))
        } else {
            self.mean_of(&|nu| self.otf(nu) / noise.value(nu))
        }
    }

    /// Adaptive mean over `[0, max_frequency]` of `P(ν) |value(ν)|`, where `value` is a signed
    /// OTF (split at its sign changes) or a modulus.
    fn mean_of(&self, value: &dyn Fn(f64) -> f64) -> (f64, Work) {
        let mut work = if self.closed.is_some() {
            Work::default()
        } else {
            Work { spectral_panels: self.panels.len(), spectral_nodes: self.nodes.len(), ..Work::default() }
        };
        if let Some(fft) = &self.fft {
            // The interpolated grid is only continuous across its cells (kinks at every grid line
            // of every node): a fixed composite rule at a quarter of the finest cell, not an
            // adaptive one, integrates it to well below the FFT path's own error.
            let cell = fft
                .nodes
                .iter()
                .filter_map(|n| match &n.kind {
                    FftKind::Grid(otf) => Some(1.0 / (otf.n() as f64 * n.lambda * self.f_number)),
                    FftKind::Table(_) => None,
                })
                .fold(f64::INFINITY, f64::min);
            // over [0, highest cutoff] where that is below max_frequency: the OTF is zero beyond
            let top = self.active_top();
            let panels = ((4.0 * top / cell).ceil() as usize).clamp(8, 1 << 16);
            work.frequency_panels = panels;
            work.otf_evaluations = panels * quad::ORDER;
            let total = quad::composite(0.0, top, panels, |nu| value(nu).abs() * self.pixel_factor(nu));
            return (total / self.max_frequency, work);
        }
        // The tolerance is relative to the mean, which is not known before it is computed: the
        // first pass assumes a mean of at least `guess`; a smaller result is recomputed with its
        // own value as the guess (absolute error ≤ tolerance × mean, never below 1e-15).
        // Where the highest cutoff lies below max_frequency, the mean is at most the fraction
        // `active` of the range the OTF is non-zero on: the guesses scale with it, and the error
        // budget, spent on that fraction only, is divided by it, so that the tolerance stays
        // relative to the OTF there (a 1e-206 m pixel puts the fraction at 1e-200: the budget of
        // the whole range asked 1e-15 of the OTF, its rounding noise, for 6000 sign changes)
        let active = (self.active_top() / self.max_frequency).clamp(f64::MIN_POSITIVE, 1.0);
        let mut guess = 0.25 * active;
        loop {
            let closed_before = self.closed_evaluations.get();
            let (mean, pass) = self.mean_pass(value, self.tolerance * guess / active);
            work.frequency_panels += pass.frequency_panels;
            work.otf_evaluations += pass.otf_evaluations;
            work.sign_changes += pass.sign_changes;
            work.closed_form_evaluations += self.closed_evaluations.get() - closed_before;
            if mean >= 0.5 * guess || guess <= 1e-9 * active {
                return (mean, work);
            }
            guess = mean.max(1e-9 * active);
        }
    }

    /// One adaptive pass of [`mean_of`](Self::mean_of) to an absolute error `absolute` of the mean
    /// over the range where the OTF is non-zero (the whole range unless the highest cutoff is
    /// below `max_frequency`).
    fn mean_pass(&self, value: &dyn Fn(f64) -> f64, absolute: f64) -> (f64, Work) {
        let mut work = Work::default();
        // each closed-form OTF value may be off by half the budget: the mean is a weighted
        // average of them (and the ν rule below treats differences within that as their noise)
        self.otf_tolerance.set(0.5 * absolute);
        // panel errors are budgeted per unit width: Σ tolerance × (b − a) = absolute × ν_max
        let tolerance = absolute;
        // defocus phase rate in ν: d/dν [8π F# ν W020 (cos t − ν λ F#)] = 8π F# W020 (cos t − 2s)
        let phase_rate = 8.0 * PI * self.f_number * self.w020_rms;
        let min_panels = if self.closed.is_some() { 1.0 } else { 4.0 };
        let mut total = 0.0;
        for pair in self.frequency_cuts().windows(2) {
            let (a, b) = (pair[0], pair[1]);
            // at least 4 panels over the whole range, not per interval between cutoff cuts
            // (2 on the closed-form engine, whose OTF has no kinks)
            let floor = (min_panels * (b - a) / self.max_frequency).ceil();
            // beyond the highest cutoff the OTF is zero: one panel (a range up to 1e199 cycles/m
            // past it, from a 1e-206 m pixel, would otherwise ask for more panels than exist)
            let n = if a >= self.max_cutoff() {
                1
            } else {
                ((b - a) * phase_rate / quad::MAX_PANEL_PHASE).ceil().max(floor).clamp(1.0, MAX_PANELS) as usize
            };
            let h = (b - a) / n as f64;
            let mut left = (a, value(a));
            work.otf_evaluations += 1;
            for k in 0..n {
                let hi = if k + 1 == n { b } else { a + h * (k + 1) as f64 };
                let right = (hi, value(hi));
                work.otf_evaluations += 1;
                total += self.integrate_panel(value, left, right, tolerance, 0, &mut work);
                left = right;
            }
        }
        (total / self.max_frequency, work)
    }

    /// `∫ P(ν) |OTF_poly(ν)| dν` over one panel whose end values are known: split at sign
    /// changes, bisected until the Gauss–Kronrod error estimate is below `tolerance × width`.
    fn integrate_panel(
        &self,
        value: &dyn Fn(f64) -> f64,
        left: (f64, f64),
        right: (f64, f64),
        tolerance: f64,
        depth: u32,
        work: &mut Work,
    ) -> f64 {
        let (a, b) = (left.0, right.0);
        let half = 0.5 * (b - a);
        let mut samples = [(0.0, 0.0); 17];
        samples[0] = left;
        samples[16] = right;
        let nodes = quad::GK15.nodes(a, b);
        for (i, &nu) in nodes[..15].iter().enumerate() {
            samples[i + 1] = (nu, value(nu));
        }
        work.otf_evaluations += 15;
        // sign changes between consecutive non-zero samples (exact zeros, e.g. past the cutoff
        // where the OTF vanishes identically, are not sign changes)
        let mut edges = Vec::new();
        let mut last: Option<(f64, f64)> = None;
        for &(x, f) in &samples {
            if f == 0.0 {
                continue;
            }
            if let Some((x0, f0)) = last
                && f0 * f < 0.0
            {
                // a zero of OTF_poly (Illinois), to 1e-14 of the frequency limit (or of the highest cutoff)
                let mut counted = |nu: f64| {
                    work.otf_evaluations += 1;
                    value(nu)
                };
                let zero = quad::illinois(&mut counted, x0, f0, x, f, 1e-14 * self.active_top());
                edges.push((zero, 0.0));
            }
            last = Some((x, f));
        }
        if !edges.is_empty() && depth < MAX_DEPTH {
            work.sign_changes += edges.len();
            let mut total = 0.0;
            let mut from = left;
            for to in edges.into_iter().chain(std::iter::once(right)) {
                total += self.integrate_panel(value, from, to, tolerance, depth + 1, work);
                from = to;
            }
            return total;
        }
        let mut values = [0.0; 15];
        for (v, &(nu, f)) in values.iter_mut().zip(&samples[1..16]) {
            *v = f.abs() * self.pixel_factor(nu);
        }
        let panel = quad::GK15.sums(half, &values);
        let kronrod = panel.kronrod;
        // Accept at the tolerance, or where no refinement can help: the Kronrod–Gauss difference
        // at the rounding level of the sums themselves (near the cutoff the OTF is tiny and its
        // evaluation noise does not shrink with the panel), or a panel below 1e-9 of the range.
        let rounding = 1e3 * f64::EPSILON * kronrod.abs().max(tolerance * (b - a));
        // closed-form OTF values are themselves computed to `otf_tolerance`: a Kronrod–Gauss
        // difference within twice that per unit width is their noise, which no bisection removes
        // (at thousands of waves the rule otherwise bisected at the noise level without end)
        let noise = if self.closed.is_some() { 2.0 * self.otf_tolerance.get() * (b - a) } else { 0.0 };
        // QUADPACK's estimate: the asymptotic one (|K − G|^1.64 of the variation, trusted below
        // 1e-3 of it) accepted a panel holding a hidden dip of the OTF to zero, 180× over the
        // tolerance (F/12.9, 21.5 nm, 2 µm pixels; test closed_form_engine_meets_the_requested_tolerance)
        let error = panel.error();
        if error <= tolerance * (b - a)
            || error <= rounding
            || (panel.kronrod - panel.gauss).abs() <= noise
            || b - a <= 1e-9 * self.active_top()
            || depth >= MAX_DEPTH
        {
            work.frequency_panels += 1;
            return kronrod;
        }
        let centre = samples[8];
        self.integrate_panel(value, left, centre, tolerance, depth + 1, work)
            + self.integrate_panel(value, centre, right, tolerance, depth + 1, work)
    }

    /// The end of the frequency range where the OTF can be non-zero: `max_frequency`, or the
    /// highest cutoff if that is below it (the frequency rule's lengths scale with it: a 1e-206 m
    /// pixel puts `max_frequency` 1e200 times above it).
    fn active_top(&self) -> f64 {
        self.max_cutoff().min(self.max_frequency)
    }

    /// Cutoff frequency (cycles/m) of the shortest wavelength covered: `OTF_poly` is zero beyond.
    pub fn max_cutoff(&self) -> f64 {
        let lo = self.line().or(self.panels.first().map(|p| p.lo)).unwrap_or(0.0);
        1.0 / (lo * self.f_number)
    }

    /// Largest |W020| (m) among the spectral nodes that carry weight.
    pub fn max_defocus(&self) -> f64 {
        self.w020_max
    }

    /// Photoelectron-weighted fraction of the detected signal whose geometric blur radius
    /// `2|W020|/NA` exceeds `radius_m` (Fraunhofer validity, paper SI eq. S15), exact on every
    /// engine: in closed form on the closed-form engine
    /// ([`GaussianDefocus::fraction_defocused_beyond`]); on the spectral quadrature, the
    /// wavelengths where each order's `|W020|` crosses `radius_m NA/2` are located in every
    /// spectral panel and the weight beyond them integrated by Gauss–Legendre on the
    /// sub-intervals (`fraunhofer::weight_defocused_beyond`), so the step never falls between
    /// nodes and the fraction is continuous in every parameter.
    pub fn fraction_blurred_beyond(&self, radius_m: f64) -> f64 {
        let na = self.lens.numerical_aperture();
        let limit = 0.5 * radius_m * na;
        if let Some(closed) = &self.closed {
            return closed.fraction_defocused_beyond(limit);
        }
        if self.line().is_some() {
            // one wavelength: each order is beyond or not (0 or 1 for a single order)
            return self.spectral_average(|_, w020| if w020.abs() > limit { 1.0 } else { 0.0 });
        }
        let panels: Vec<(f64, f64)> = self.panels.iter().map(|p| (p.lo, p.hi)).collect();
        let density = |lambda: f64| self.detected.value(lambda);
        let beyond = crate::fraunhofer::weight_defocused_beyond(self.lens, self.field, &density, &panels, limit);
        (beyond / self.total_weight).clamp(0.0, 1.0)
    }
}

/// The wavelengths of the OTF tables of `lens`'s orders, found at five wavelengths across
/// `[lo, hi]`: a table is linear in λ between its rows, so the spectral panels are cut there.
fn table_wavelengths(lens: &dyn LensModel, field: Field, lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 0..5 {
        let lambda = lo + (hi - lo) * k as f64 / 4.0;
        if lambda <= 0.0 {
            continue;
        }
        for order in lens.orders(lambda, field) {
            if let Pupil::Table(t) = &order.pupil {
                out.extend_from_slice(t.wavelengths());
            }
        }
    }
    out.sort_by(f64::total_cmp);
    out.dedup();
    out
}

/// Cache size of sampled pupils and zone sets on the FFT layer (a lens has a few apertures).
const SAMPLED_CACHE: usize = 8;

/// The FFT layer's state while its grids are computed: one plan, and the sampled pupils and
/// zone sets of the apertures seen so far (kept while the lens hands out the same `Arc`s).
struct FftLayer {
    n: usize,
    plan: OtfPlan,
    numerical_aperture: f64,
    circle: Arc<Aperture>,
    pupils: Vec<(Arc<Aperture>, SampledPupil)>,
    zones: Vec<SampledZones>,
    fields: Vec<ZoneField>,
}

impl FftLayer {
    fn new(n: usize, s_max: f64, numerical_aperture: f64) -> Result<FftLayer, Error> {
        Ok(FftLayer {
            n,
            plan: OtfPlan::new(n, s_max)?,
            numerical_aperture,
            circle: Arc::new(Aperture::circle()),
            pupils: Vec::new(),
            zones: Vec::new(),
            fields: Vec::new(),
        })
    }

    /// How `order`'s OTF at `lambda` is read: a grid of its sampled pupil, of its composite of
    /// zones, or its table.
    fn kind(&mut self, order: &Order, lambda: f64) -> Result<FftKind, Error> {
        let aperture = match &order.pupil {
            Pupil::Table(t) => return Ok(FftKind::Table(t.clone())),
            Pupil::Zones(zones) => return self.zones_grid(zones, lambda).map(FftKind::Grid),
            Pupil::Aperture(a) => a.clone(),
            _ => self.circle.clone(),
        };
        let aberrations = order.wavefront.aberrations();
        let slot = match self.pupils.iter().position(|(a, _)| Arc::ptr_eq(a, &aperture)) {
            Some(i) => {
                self.pupils[i].1.set_aberrations(&aberrations)?;
                i
            }
            None => {
                let p = SampledPupil::new(self.n, &aperture, &aberrations)?;
                if self.pupils.len() == SAMPLED_CACHE {
                    self.pupils.remove(0);
                }
                self.pupils.push((aperture, p));
                self.pupils.len() - 1
            }
        };
        let mut otf = Otf::new();
        self.plan.otf(&self.pupils[slot].1, lambda, &mut otf);
        Ok(FftKind::Grid(otf))
    }

    /// The OTF of one composite pupil (docs/physics.md, "General pupils"; `fft::SampledZones`):
    /// the zones' fields add coherently, each with its amplitude, its wavefront and, for its own
    /// image shift Δ, the tilt `W += (Δx x + Δy y) NA` (x, y in units of the full aperture's
    /// radius), which multiplies its part of the OTF by `exp(−2πi ν·Δ)` as an order's shift does.
    fn zones_grid(&mut self, zones: &[crate::Zone], lambda: f64) -> Result<Otf, Error> {
        let apertures = || zones.iter().map(|z| &z.aperture);
        let slot = match self.zones.iter().position(|s| s.is_sampling_of(apertures())) {
            Some(i) => i,
            None => {
                let list: Vec<Arc<Aperture>> = apertures().cloned().collect();
                if self.zones.len() == SAMPLED_CACHE {
                    self.zones.remove(0);
                }
                self.zones.push(SampledZones::new(self.n, &list)?);
                self.zones.len() - 1
            }
        };
        let na = self.numerical_aperture;
        self.fields.clear();
        self.fields.extend(zones.iter().map(|z| ZoneField {
            amplitude: z.amplitude,
            aberrations: z.wavefront.aberrations(),
            tilt_m: [z.wavefront.image_shift_m[0] * na, z.wavefront.image_shift_m[1] * na],
        }));
        let sampled = &mut self.zones[slot];
        sampled.set_field(&self.fields, lambda)?;
        let mut otf = Otf::new();
        self.plan.otf_of_field(sampled.field(), sampled.weight(), &mut otf);
        Ok(otf)
    }
}

/// Monochromatic MTF of `lens` at one wavelength along +x, at each of `frequencies` (cycles/m):
/// the modulus of the efficiency-weighted sum of its orders' OTFs (with their lateral-shift
/// phases), normalized to 1 at zero frequency (all zeros if no order transmits). Orders beyond
/// the exact path get one FFT grid each, with `pupil_samples` across the diameter (a composite
/// pupil of zones one grid of its coherent field); a tabulated order is read at ν, along +x
/// measured from the field direction.
pub fn monochromatic_mtf(
    lens: &dyn LensModel,
    wavelength_m: f64,
    field: Field,
    frequencies: &[f64],
    pupil_samples: usize,
) -> Result<Vec<f64>, Error> {
    let to_s = |nu: f64| nu.abs() * wavelength_m * lens.f_number();
    let s_max = frequencies.iter().map(|&nu| to_s(nu)).fold(0.0, f64::max).clamp(1e-6, 1.0);
    let mut sum = vec![Complex64::new(0.0, 0.0); frequencies.len()];
    let mut total = 0.0;
    let mut layer: Option<FftLayer> = None;
    // along +x: a tabulated order's direction relative to the field's
    let from_field = -field.y_rad.atan2(field.x_rad);
    for order in lens.orders(wavelength_m, field) {
        total += order.efficiency;
        let kind = if needs_grid(&order) {
            let layer = match &mut layer {
                Some(l) => l,
                slot => slot.insert(FftLayer::new(pupil_samples, s_max, lens.numerical_aperture())?),
            };
            Some(layer.kind(&order, wavelength_m)?)
        } else {
            None
        };
        let node = Node::of(&order, wavelength_m, order.efficiency);
        for (acc, &nu) in sum.iter_mut().zip(frequencies) {
            let s = to_s(nu);
            if s >= 1.0 {
                continue;
            }
            let otf = match &kind {
                Some(FftKind::Grid(g)) => g.at(s.min(g.s_max()), 0.0),
                _ => Complex64::new(node.otf(s, nu, from_field), 0.0),
            };
            let phase = -2.0 * PI * nu * order.wavefront.image_shift_m[0];
            *acc += otf * Complex64::from_polar(order.efficiency, phase);
        }
    }
    Ok(sum.iter().map(|z| if total > 0.0 { z.norm() / total } else { 0.0 }).collect())
}

/// Cutoff frequency (cycles/m) of the shortest wavelength the spectral quadrature covers for
/// `lens` and `detected`: every polychromatic OTF is zero beyond it. Needs no OTF work.
pub fn highest_cutoff(lens: &dyn LensModel, detected: &Spectrum) -> Result<f64, Error> {
    let lo = match detected.as_line() {
        Some(line) => line.wavelength_m,
        None => spectral_extent(detected)?.0,
    };
    Ok(if lo > 0.0 { 1.0 / (lo * lens.f_number()) } else { f64::INFINITY })
}

/// The wavelength interval the spectral quadrature covers: the spectrum's support, with Gaussian
/// factors cut at ±[`GAUSSIAN_HALF_WIDTH_SIGMAS`] σ.
/// The closed-form engine for `lens` seen through `detected` at `field`, when it applies: a
/// Gaussian × polynomial spectrum and a lens whose [`LensModel::affine_defocus`] promise is
/// confirmed by its [`orders`](LensModel::orders) at three wavelengths.
fn closed_form(
    lens: &dyn LensModel,
    detected: &Spectrum,
    field: Field,
) -> Option<(GaussianDefocus, crate::AffineDefocus)> {
    let affine = lens.affine_defocus(field)?;
    let gp = detected.gaussian_polynomial()?;
    if affine.efficiency.is_nan() || affine.efficiency <= 0.0 || gp.coefficients.len() > crate::closed::MAX_TERMS {
        return None;
    }
    for lambda in [gp.center_m - gp.sigma_m, gp.center_m, gp.center_m + 2.0 * gp.sigma_m] {
        if lambda <= 0.0 {
            continue;
        }
        let orders = lens.orders(lambda, field);
        let [order] = orders.as_slice() else { return None };
        let w020 = affine.w020_intercept_m + affine.w020_slope * lambda;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()) + 1e-18;
        if !matches!(order.pupil, Pupil::Full)
            || !order.wavefront.is_defocus_only()
            || order.wavefront.image_shift_m != [0.0, 0.0]
            || !close(order.efficiency, affine.efficiency)
            || !close(order.wavefront.defocus_m, w020)
        {
            return None;
        }
    }
    let closed = GaussianDefocus::new(
        gp.center_m,
        gp.sigma_m,
        &gp.coefficients,
        affine.efficiency,
        affine.w020_intercept_m,
        affine.w020_slope,
        lens.f_number(),
    );
    Some((closed, affine))
}

pub(crate) fn spectral_extent(detected: &Spectrum) -> Result<(f64, f64), Error> {
    let (mut lo, mut hi) = detected.support();
    for g in detected.gaussians() {
        lo = lo.max(g.center() - GAUSSIAN_HALF_WIDTH_SIGMAS * g.sigma());
        hi = hi.min(g.center() + GAUSSIAN_HALF_WIDTH_SIGMAS * g.sigma());
    }
    lo = lo.max(0.0);
    if !(hi.is_finite() && hi > lo) {
        return Err(Error::UnboundedSpectrum { lo, hi });
    }
    Ok((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bright(w: &[f64]) -> Vec<PhaseEntry> {
        w.iter().map(|&w020| PhaseEntry { w020, vanishing: false }).collect()
    }

    /// The matching of orders between neighbouring wavelengths, against the changes worked out
    /// by hand.
    #[test]
    fn orders_are_matched_by_their_defocus() {
        // three bright channels each moving by one channel spacing (1.0) across the panel: the
        // nearest-neighbour pairs would see 0.1, the true change is 1.0
        let from = bright(&[-1.0, 0.0, 1.0]);
        let to = bright(&[-2.0, -1.1, 0.0]);
        assert_eq!(largest_turn(&from, &to), 1.1);
        // a harmonic window shifting by one order (same count): the order leaving at one end
        // and the one entering at the other are near zero efficiency and stay unmatched
        let mut from = bright(&[1.0, 2.0, 3.0, 4.0]);
        from[0].vanishing = true;
        let mut to = bright(&[2.05, 3.05, 4.05, 5.05]);
        to[3].vanishing = true;
        assert!((largest_turn(&from, &to) - 0.05).abs() < 1e-12);
        // the same shift with bright end orders is a jump of every order (no vanishing order to
        // leave out): matched one to one
        assert!(
            (largest_turn(&bright(&[1.0, 2.0, 3.0, 4.0]), &bright(&[2.05, 3.05, 4.05, 5.05])) - 1.05).abs() < 1e-12
        );
        // an order appearing (the counts differ): the others are matched, whatever its brightness
        assert!((largest_turn(&bright(&[1.0, 2.0]), &bright(&[1.1, 2.1, 3.0])) - 0.1).abs() < 1e-12);
        assert!((largest_turn(&bright(&[0.0, 1.0, 2.0]), &bright(&[1.2, 2.2])) - 0.2).abs() < 1e-12);
        // nothing to match
        assert_eq!(largest_turn(&[], &bright(&[1.0])), 0.0);
        assert_eq!(largest_turn(&[], &[]), 0.0);
    }
}
