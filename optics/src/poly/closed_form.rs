//! The closed-form engine ([`GaussianDefocus`]): a Gaussian × polynomial spectrum through one full
//! pupil with defocus affine in λ, the spectral integral done exactly; one integral (over the
//! pupil angle) is left per OTF value, to a tolerance the frequency rule sets.

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use num_complex::Complex64;
use radiometry::Spectrum;

use crate::closed::GaussianDefocus;
use crate::lens::{Field, LensModel, Pupil};
use crate::quad;

use super::spectral::{Node, Nodes, Panel, WHOLE};
use super::{Engine, FrequencyRule, GAUSSIAN_HALF_WIDTH_SIGMAS, OtfEngine};

/// Evaluations of the closed-form spectral integral E(c) one mean may take (100–180 ns each: about
/// 2 s), after which the engine stops and reports it (the valid but hopeless scenes of the stress
/// list, F/0.5 at f0 = 50 mm over 1000 nm, stop in under 3 s, the whole command included).
pub const CLOSED_FORM_BUDGET: usize = 12_000_000;

/// The hasher of [`Closed::values`]' keys, the bits of a frequency: one multiplication (Knuth's
/// multiplicative hashing by 2^64/φ, its well-mixed high half folded onto the low bits the table
/// indexes by), not the default SipHash,
/// whose keyed rounds cost more than the look-up they serve (the keys are the frequency rule's
/// own nodes, not input an adversary chooses).
#[derive(Default)]
pub(super) struct BitsHasher(u64);

impl Hasher for BitsHasher {
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 32)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }

    fn write_u64(&mut self, bits: u64) {
        self.0 = (self.0 ^ bits).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// An OTF value, its Seidel lanes at zero and its estimated error ([`Closed::seidel_values`]).
pub(super) type SeidelValue = (f64, [f64; 2], f64);

/// The closed-form engine and its counters.
#[derive(Debug)]
pub(super) struct Closed {
    pub closed: GaussianDefocus,
    pub nodes: Nodes,
    pub f_number: f64,
    /// absolute tolerance of one OTF value (set by the frequency rule; before it, for single
    /// OTF values, 5 % of the relative tolerance)
    pub otf_tolerance: Cell<f64>,
    /// E(c) evaluations so far
    pub evaluations: Cell<usize>,
    /// the spectrally weighted mean of W020, m
    pub mean_defocus: f64,
    /// The OTF values computed so far and their estimated errors ([`GaussianDefocus::otf_estimated`]),
    /// by the bits of ν: a mean redone to a tighter tolerance (its first pass found a smaller mean
    /// than it assumed) asks most of its frequencies again, and a value whose rule's own estimate
    /// is within the new tolerance is kept (see `otf`).
    pub values: RefCell<HashMap<u64, (f64, f64), BuildHasherDefault<BitsHasher>>>,
    /// The OTF values with their Seidel lanes at zero ([`GaussianDefocus::otf_and_seidel_lanes`])
    /// and their estimated errors, by the bits of ν, kept as [`values`](Self::values) are: a
    /// mean redone to a tighter tolerance reads a lane whose value's estimate meets it.
    pub seidel_values: RefCell<HashMap<u64, SeidelValue, BuildHasherDefault<BitsHasher>>>,
    /// How the defocus moves with the lens's design wavelength, `∂W020/∂ln λ0 = d0 + d1 λ`
    /// ([`design_direction`]); `None` where the lens gives no such affine rate.
    pub design: Option<[f64; 2]>,
}

/// `[d0, d1]` with `∂W020/∂ln λ0 = d0 + d1 λ` for the lens's one order
/// (`LensModel::design_wavelength_rates`), read at the Gaussian's centre and one σ either side
/// and kept where the three agree with a line (to 1e-12 of the largest) and the efficiency does
/// not move (the closed form's is a constant): the chromatic lens's `(λ/λ0) f0/(8F#²)`. `None`
/// otherwise.
pub(super) fn design_direction(lens: &dyn LensModel, field: Field, closed: &GaussianDefocus) -> Option<[f64; 2]> {
    let (mu, sigma) = (closed.center(), closed.sigma());
    let at = |lambda: f64| match lens.design_wavelength_rates(lambda, field)?[..] {
        [[d_w, d_tau]] if d_tau == 0.0 && d_w.is_finite() => Some(d_w),
        _ => None,
    };
    let (lo, hi) = ((mu - sigma).max(0.5 * mu), mu + sigma);
    let (r_lo, r_mu, r_hi) = (at(lo)?, at(mu)?, at(hi)?);
    let d1 = (r_hi - r_lo) / (hi - lo);
    let d0 = r_lo - d1 * lo;
    let size = r_lo.abs().max(r_mu.abs()).max(r_hi.abs());
    ((d0 + d1 * mu - r_mu).abs() <= 1e-12 * size).then_some([d0, d1])
}

impl Closed {
    /// The engine, with spectral nodes not for the OTF (its spectral integral is exact) but for
    /// the averages over the spectrum (`detected_integral`, `spectral_average`): 8 Gauss–Legendre
    /// panels over μ ± 10σ, exact to rounding for the smooth functions they are used with.
    pub fn new(
        closed: GaussianDefocus,
        affine: crate::AffineDefocus,
        detected: &Spectrum,
        f_number: f64,
        tolerance: f64,
    ) -> Closed {
        let (mu, sigma) = (closed.center(), closed.sigma());
        let (lo, hi) = ((mu - 10.0 * sigma).max(0.0), mu + 10.0 * sigma);
        let densities = band_densities(detected, lo, hi);
        // the nodes' wavelengths and rule weights first, then the samples and the nodes each
        // collected from them (written in place, where pushing a node at a time built each on
        // the stack and copied it: 4 % of the paper point)
        let mut at = [(0.0, 0.0); 8 * quad::ORDER];
        let mut count = 0;
        quad::for_each_node(lo, hi, 8, |lambda, q| {
            at[count] = (lambda, q * densities.get(count).copied().unwrap_or(f64::NAN));
            count += 1;
        });
        let at = &at[..count];
        let node = |&(lambda, q_rho): &(f64, f64)| Node {
            lambda,
            weight: q_rho * affine.efficiency,
            w020: affine.w020_intercept_m + affine.w020_slope * lambda,
            scale: 1.0,
            shift: [0.0, 0.0],
            shift_rate: None,
            iris_shift: [0.0; 2],
            iris_rate: 0.0,
            iris_tilt: [0.0; 2],
            table: None,
            radial: None,
            part: WHOLE,
            order: 0,
            efficiency: affine.efficiency,
        };
        let mut nodes = Nodes {
            nodes: at.iter().map(node).collect(),
            samples: at.iter().map(|&(lambda, q_rho)| (lambda, q_rho, WHOLE)).collect(),
            ..Nodes::default()
        };
        nodes.panels.push(Panel { lo, hi, start: 0, end: nodes.nodes.len(), part: WHOLE });
        nodes.densities = Some(densities.to_vec());
        nodes.total_weight = closed.total_weight();
        let weight: f64 = nodes.nodes.iter().map(|n| n.weight).sum();
        let mean_defocus = nodes.nodes.iter().map(|n| n.weight * n.w020).sum::<f64>() / weight;
        Closed {
            mean_defocus,
            closed,
            nodes,
            f_number,
            otf_tolerance: Cell::new(0.05 * tolerance),
            evaluations: Cell::new(0),
            // (room for the 52 values of the map's broadest bands without growing)
            values: RefCell::new(HashMap::with_capacity_and_hasher(64, BuildHasherDefault::default())),
            seidel_values: RefCell::new(HashMap::default()),
            design: None,
        }
    }
}

/// How many bands' densities [`band_densities`] keeps per thread (128 `f64` each, 1 kB); a
/// band's several spectra (other cameras, sources) count once.
pub(super) const BAND_DENSITIES_KEPT: usize = 256;

/// The bands whose densities this thread read at the closed form's spectral nodes, by the bits
/// of the nodes' range: the detected spectrum and the densities ([`band_densities`]).
type BandDensities = HashMap<[u64; 2], Vec<(Spectrum, std::sync::Arc<[f64]>)>, BuildHasherDefault<BitsHasher>>;

thread_local! {
    static BAND_DENSITIES: RefCell<BandDensities> = RefCell::new(HashMap::default());
}

/// The detected spectrum's values at the closed form's spectral nodes over `[lo, hi]` (8
/// Gauss–Legendre panels, in [`quad::for_each_node`]'s order). They depend on the band and the
/// camera, not on the lens: a sweep over the F-number reads the same ones at every F-number
/// (4 % of a map point). Each thread keeps up to [`BAND_DENSITIES_KEPT`] bands (then forgets
/// them all and starts again), found by the bits of `lo` and `hi` and an equal spectrum, so the
/// values are the ones `detected.value` gives there, to the bit; `forget_remembered` clears them.
fn band_densities(detected: &Spectrum, lo: f64, hi: f64) -> std::sync::Arc<[f64]> {
    let id = [lo.to_bits(), hi.to_bits()];
    let known = BAND_DENSITIES.with_borrow(|kept| {
        kept.get(&id).and_then(|same| same.iter().find(|(spectrum, _)| spectrum == detected).map(|k| k.1.clone()))
    });
    if let Some(densities) = known {
        return densities;
    }
    let mut densities = Vec::with_capacity(8 * quad::ORDER);
    quad::for_each_node(lo, hi, 8, |lambda, _| densities.push(detected.value(lambda)));
    let densities: std::sync::Arc<[f64]> = densities.into();
    BAND_DENSITIES.with_borrow_mut(|kept| {
        if kept.len() >= BAND_DENSITIES_KEPT {
            kept.clear();
        }
        kept.entry(id).or_default().push((detected.clone(), densities.clone()));
    });
    densities
}

/// Forgets the bands' densities this thread keeps ([`band_densities`]).
pub(super) fn forget_band_densities() {
    BAND_DENSITIES.with_borrow_mut(HashMap::clear);
}

impl OtfEngine for Closed {
    fn engine(&self) -> Engine {
        Engine::ClosedForm
    }

    fn nodes(&self) -> &Nodes {
        &self.nodes
    }

    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn otf(&self, frequency: f64) -> f64 {
        if frequency == 0.0 {
            return 1.0;
        }
        // past the work budget the remaining values are not computed (0): the caller reports
        // the budget instead of a mean ([`Polychromatic::over_budget`](super::Polychromatic::over_budget))
        if self.evaluations.get() > CLOSED_FORM_BUDGET {
            return 0.0;
        }
        let tolerance = self.otf_tolerance.get();
        // a value is kept where the nested rule's own estimate (the reported one without its
        // safety factor) meets the new tolerance: the criterion a fresh computation to that
        // tolerance accepts its pieces on (their estimates within their shares of it). Compared
        // with the factor included, a second pass (the mean below the first pass's guess, F/1.4,
        // 200 nm) recomputed every value: 2253 E(c) at 1e-6 where this keeps them, 1428.
        if let Some(&(value, error)) = self.values.borrow().get(&frequency.to_bits())
            && error <= crate::closed::ESTIMATE_SAFETY * tolerance
        {
            return value;
        }
        let (value, evaluations, error) = self.closed.otf_estimated(frequency, tolerance);
        self.evaluations.set(self.evaluations.get() + evaluations);
        self.values.borrow_mut().insert(frequency.to_bits(), (value, error));
        value
    }

    /// The closed form's defocus lane ([`GaussianDefocus::otf_and_log_derivative`]): the same
    /// pieces, levels and acceptance as the value, at the value's tolerance; its evaluations of
    /// E(c) count towards the budget.
    fn otf_and_defocus_derivative(&self, frequency: f64) -> Option<(f64, f64)> {
        if frequency == 0.0 {
            return Some((1.0, 0.0));
        }
        if self.evaluations.get() > CLOSED_FORM_BUDGET {
            return Some((0.0, 0.0));
        }
        let (value, derivative, evaluations, _) =
            self.closed.otf_and_log_derivative(frequency, self.otf_tolerance.get());
        self.evaluations.set(self.evaluations.get() + evaluations);
        Some((value, derivative))
    }

    /// The closed form's lane along the design wavelength
    /// ([`GaussianDefocus::otf_and_defocus_lane`] along [`Closed::design`]): the same pieces,
    /// levels and acceptance as the value, at the value's tolerance; its evaluations of E(c)
    /// count towards the budget. `None` without the lens's affine rate.
    fn otf_and_design_lane(&self, frequency: f64) -> Option<(f64, f64)> {
        let direction = self.design?;
        if frequency == 0.0 {
            return Some((1.0, 0.0));
        }
        if self.evaluations.get() > CLOSED_FORM_BUDGET {
            return Some((0.0, 0.0));
        }
        let (value, derivative, evaluations, _) =
            self.closed.otf_and_defocus_lane(frequency, self.otf_tolerance.get(), direction);
        self.evaluations.set(self.evaluations.get() + evaluations);
        Some((value, derivative))
    }

    /// The closed form's Seidel lanes at zero ([`GaussianDefocus::otf_and_seidel_lanes`]): the
    /// same pieces, levels and acceptance as the value, at the value's tolerance; its
    /// evaluations of E(c) count towards the budget.
    fn otf_and_seidel_lanes(&self, frequency: f64, lanes: &mut [f64; 2]) -> Option<f64> {
        *lanes = [0.0; 2];
        if frequency == 0.0 {
            return Some(1.0);
        }
        if self.evaluations.get() > CLOSED_FORM_BUDGET {
            return Some(0.0);
        }
        let tolerance = self.otf_tolerance.get();
        if let Some(&(value, found, error)) = self.seidel_values.borrow().get(&frequency.to_bits())
            && error <= crate::closed::ESTIMATE_SAFETY * tolerance
        {
            *lanes = found;
            return Some(value);
        }
        let (value, found, evaluations, error) = self.closed.otf_and_seidel_lanes(frequency, tolerance)?;
        self.evaluations.set(self.evaluations.get() + evaluations);
        self.seidel_values.borrow_mut().insert(frequency.to_bits(), (value, found, error));
        *lanes = found;
        Some(value)
    }

    fn over_budget(&self) -> Option<String> {
        (self.evaluations.get() > CLOSED_FORM_BUDGET).then(|| {
            format!(
                "the closed-form spectral integral passed its budget of {CLOSED_FORM_BUDGET:e} evaluations (about 2 s) \
                 before the mean MTF converged: the defocus is far beyond the Fraunhofer threshold (paper SI eq. S15)"
            )
        })
    }

    fn otf_along(&self, frequency: f64, _azimuth: f64) -> Complex64 {
        // on axis, rotationally symmetric and real
        Complex64::new(self.otf(frequency), 0.0)
    }

    fn direction_dependent(&self) -> bool {
        false
    }

    fn frequency_rule(&self) -> FrequencyRule {
        FrequencyRule::Adaptive { min_panels: 1.0 }
    }

    /// Smooth in ν where every wavelength of the Gaussian's ±7σ passes `max_frequency` (no
    /// cutoff inside the range; the weight beyond is 2.6e-12 of the area).
    fn smooth_in_frequency(&self, max_frequency: f64) -> bool {
        let longest = self.closed.center() + GAUSSIAN_HALF_WIDTH_SIGMAS * self.closed.sigma();
        max_frequency * longest * self.f_number < 1.0 - 1e-6
    }

    /// The closed form is exact across the spectrum: no panel edges, no kinks; but where the
    /// cutoffs 1/(λ F#) of the Gaussian's centre and flanks lie below `max_frequency`, the OTF is
    /// non-zero on a small part of the range only, which one panel's nodes can miss entirely
    /// (F/1e4: cutoff at 1/770 of Nyquist): cut there, and where the OTF vanishes altogether.
    /// Beyond `ν_s` ([`averaged_defocus`](OtfEngine::averaged_defocus)) the OTF decays about as
    /// `C/ν` and its oscillation is damped as `exp(−(ν/ν_s)²/2)`: cut at `AVERAGED_DECAY ν_s`
    /// (unless within half an octave of `max_frequency`), where that damping is 1e-14; the
    /// frequency rule takes the rest in `ln ν`. Over the 40 × 100 map: 5.8 million evaluations of
    /// E(c), against 7.4 with a cut per octave from `8 ν_s` on, 5.8 from `4 ν_s` (but the paper
    /// point split in two panels, 1500 instead of 1013) and 6.5 from `2 ν_s`.
    fn frequency_cuts(&self, max_frequency: f64) -> Vec<f64> {
        let mut cuts = vec![0.0, max_frequency];
        if let Some((averaging, _)) = self.averaged_defocus() {
            let decayed = super::frequency::AVERAGED_DECAY * averaging;
            if decayed < max_frequency / 1.5 {
                cuts.push(decayed);
            }
        }
        let (mu, sigma) = (self.closed.center(), self.closed.sigma());
        for k in 0..=GAUSSIAN_HALF_WIDTH_SIGMAS as usize {
            let lambda = mu - k as f64 * sigma;
            let nu = 1.0 / (lambda * self.f_number);
            if lambda > 0.0 && nu < max_frequency {
                cuts.push(nu);
            }
        }
        if self.max_cutoff() < max_frequency {
            cuts.push(self.max_cutoff());
        }
        super::sort_cuts(cuts)
    }

    /// With `W020 = w0 + w1 λ` and a Gaussian spectrum of σ, the monochromatic OTFs' oscillations
    /// `e^{i 8π F# W020 ν (c − s)}` average over the spectrum to the one at the mean defocus,
    /// damped by `exp(−(ν/ν_s)² (c − s)²/2)` with `ν_s = 1/(8π F# |w1| σ)` (the characteristic
    /// function of the Gaussian): beyond `ν_s` the OTF is a smooth decay (about `C/ν`) plus that
    /// damped oscillation, not the oscillation of its most defocused wavelengths.
    fn averaged_defocus(&self) -> Option<(f64, f64)> {
        let spread = (self.closed.defocus_slope() * self.closed.sigma()).abs();
        (spread > 0.0).then(|| (1.0 / (8.0 * std::f64::consts::PI * self.f_number * spread), self.mean_defocus))
    }

    fn set_value_tolerance(&self, absolute: f64) {
        self.otf_tolerance.set(absolute);
    }

    fn value_noise(&self) -> f64 {
        self.otf_tolerance.get()
    }

    fn value_evaluations(&self) -> usize {
        self.evaluations.get()
    }

    fn fraction_blurred_beyond(&self, _scene: &super::spectral::Scene<'_>, w020_limit: f64) -> f64 {
        self.closed.fraction_defocused_beyond(w020_limit)
    }
}

/// The closed-form engine for `lens` seen through `detected` at `field`, when it applies: a
/// Gaussian × polynomial spectrum and a lens whose [`LensModel::affine_defocus`] promise is
/// confirmed by its [`orders`](LensModel::orders) at three wavelengths.
pub(super) fn closed_form(
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
