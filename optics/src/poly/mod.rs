//! The polychromatic OTF and its mean up to a frequency limit.
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
//! # The map
//! [`Polychromatic`] is the one interface. Its constructor [`choose`]s an engine, a type
//! implementing [`OtfEngine`] (the OTF along an azimuth, its spectral nodes, its frequency rule
//! and its counters), the way RustFFT's planner hands out one `Arc<dyn Fft>`:
//! - `closed_form` — [`Engine::ClosedForm`]: the spectral integral in closed form.
//! - `exact` — [`Engine::Exact1d`]: spectral nodes through the exact 1-D OTF.
//! - `grid` — [`Engine::Fft`]: spectral nodes through FFT grids of sampled pupils.
//! - `line` — [`Engine::Monochromatic`]: a line spectrum, one node per order.
//!
//! The spectral nodes come from `spectral`: product integration (the default) or the
//! per-interval panels (the reference; [`SpectralRule`]). The frequency integration over any
//! engine is written once, in `frequency`. Each piece is tested against [`crate::reference`].
//!
//! - **Cutoff.** A wavelength contributes only while `s < 1`, i.e. `λ < 1/(ν F#)`. On the
//!   panels rule, the panel that straddles that limit is clipped there and integrated in `u`
//!   with `λ = λ_cut − L u²`, which turns the `(1 − s)^{3/2}` edge of the OTF into a smooth
//!   integrand; product integration is chosen only where no cutoff falls inside the band.
//! - **Frequency panels.** `[0, ν_max]` is cut where any spectral panel edge reaches its cutoff,
//!   and integrated by adaptive Gauss–Kronrod (7/15). Where `OTF_poly` changes sign inside a
//!   panel, the root is located (Illinois method) and the panel split there, so `|OTF_poly|` is
//!   only integrated where it is smooth.
//! - **Several orders.** The panels resolve the defocus phase of every order (and every zone of
//!   a composite pupil), matched between neighbouring wavelengths, not only the order of
//!   largest defocus, whose sign jumps between the channels of a multiplexed lens.
//! - **Tabulated orders** ([`Pupil::Table`](crate::Pupil)) are read at ν (T/S along the azimuth
//!   from the field direction) in place of the defocused OTF, on the exact path or beside the
//!   FFT layer's grids; composite pupils of zones get one FFT grid per node, of their coherent
//!   field (`fft::SampledZones`).
//! - **Line spectra** ([`Spectrum::as_line`]) skip all of the spectral part: the sum over λ is one
//!   term per imaging order at the line's wavelength, whose cutoff is the one frequency cut.

use num_complex::Complex64;
use radiometry::Spectrum;

use crate::Error;
use crate::lens::{Field, LensModel};

mod closed_form;
mod exact;
mod frequency;
pub(crate) use frequency::clenshaw_curtis;
mod grid;
mod line;
mod noise;
mod overlap;
mod per_frequency;
mod spectral;

pub use frequency::{
    AZIMUTH_SHARE, AzimuthalMean, DefocusDerivative, DesignAndEdgeLanes, FIRST_AZIMUTHS, MAX_AZIMUTHS,
};
pub use grid::{SharedGrids, WavefrontDirection, monochromatic_mtf};
pub use noise::NoiseShape;
pub use overlap::SeidelTerm;
pub use spectral::forget_remembered;
pub(crate) use spectral::spectral_extent;

use spectral::{Nodes, Scene};

/// One part of a lens whose efficiency tables are factored out
/// ([`crate::FactoredEfficiency`]), as [`Polychromatic::with_parts`] takes it: the part's
/// orders (`lens`, its relative lens) and the detected spectrum times the part's table
/// (`detected`, `ρ t_p`).
#[derive(Clone, Copy, Debug)]
pub struct Part<'a> {
    /// The part's orders, each efficiency relative to the part's table.
    pub lens: &'a dyn LensModel,
    /// The detected spectrum times the part's table, `ρ(λ) t_p(λ)`.
    pub detected: &'a Spectrum,
}

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

/// Pupil samples across the diameter on the FFT path when the settings fix none: the mean MTF
/// of a defocused circle is then within 2.5e-5 of the exact path (`fft` module convergence
/// table; 1e-4 needs N ≥ 128).
pub const DEFAULT_PUPIL_SAMPLES: usize = 256;

/// How the OTF is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// The exact 1-D integral: centred circular pupils with defocus (and lateral shifts) only,
    /// and tabulated OTFs ([`Pupil::Table`](crate::Pupil)).
    Exact1d,
    /// The spectral integral in closed form ([`GaussianDefocus`](crate::GaussianDefocus)): a
    /// Gaussian × polynomial spectrum through one full pupil with defocus affine in λ; one
    /// adaptive integral left.
    ClosedForm,
    /// Sampled pupils by FFT: `pupil_samples` across the diameter, padded to `padded` points.
    Fft {
        /// Pupil samples across the diameter.
        pupil_samples: usize,
        /// FFT length after padding.
        padded: usize,
        /// `Some(N/2)` when the tolerance chose the sampling (`fft::SamplingPlan`).
        coarse: Option<usize>,
        /// Whether the mean is the Richardson extrapolation of the means at `N/2` and `N`
        /// (single apertures); otherwise, with `coarse`, it is the mean at `N`, its error the
        /// observed convergence of `N/4`, `N/2` and `N` (composite pupils, `fft::ErrorRule`).
        extrapolated: bool,
    },
    /// A full circular pupil with Seidel terms beyond defocus, or Zernike terms (any Noll index;
    /// a [`Pupil::Radial`](crate::Pupil::Radial) carrying the terms alone), by quadrature over the two
    /// pupils' overlap at each frequency and azimuth the rules read (`overlap` module;
    /// docs/physics.md, "Analytic 2-D pupils by quadrature over the overlap"): the defocus
    /// integrated exactly across the lag, nested Clenshaw–Curtis along it.
    Overlap {
        /// Spectral nodes left out: the lightest, whose weights together are at most a
        /// thousandth of the tolerance.
        skipped: usize,
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

/// Weight fraction below which a spectral node does not count towards the largest defocus.
const SIGNIFICANT_WEIGHT: f64 = 1e-13;

/// Bisection depth limit of the adaptive frequency integration.
const MAX_DEPTH: u32 = 40;

/// Counts of what an evaluation did, for `--explain` and the accuracy report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Work {
    /// Spectral panels (each with [`quad::ORDER`](crate::quad::ORDER) nodes per imaging order).
    pub spectral_panels: usize,
    /// Spectral nodes, summed over orders.
    pub spectral_nodes: usize,
    /// Frequency panels after splitting at sign changes.
    pub frequency_panels: usize,
    /// Evaluations of the polychromatic OTF.
    pub otf_evaluations: usize,
    /// Sign changes of the polychromatic OTF located below the frequency limit.
    pub sign_changes: usize,
    /// Whether the spectral nodes are product-integration nodes ([`SpectralRule::Interpolated`])
    /// rather than quadrature panels.
    pub spectral_interpolated: bool,
    /// Evaluations of the closed-form spectral integral `E(c)` (closed-form engine only).
    pub closed_form_evaluations: usize,
    /// Single-wavelength OTFs summed by the per-frequency product integration (the exact 1-D
    /// engine on centred circles: each OTF value climbs its own nested spectral levels).
    pub spectral_evaluations: usize,
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
    /// Relative error allowed in the mean MTF on the FFT path, where it differs from
    /// `tolerance`: `None` follows `tolerance`. The default, [`DEFAULT_FFT_TOLERANCE`], is what
    /// the sampled pupil reaches in about a second (1e-6 would need ~6000 samples across it,
    /// beyond its 2048-sample cap); a tolerance beyond reach is refused with
    /// [`Error::PupilSampling`].
    pub fft_tolerance: Option<f64>,
    /// Whether the closed-form engine may be used where it applies.
    pub closed_form: bool,
    /// The spectral rule of the quadrature engines.
    pub spectral_rule: SpectralRule,
    /// Whether a circular iris (centred or decentred) on an order whose only aberration is
    /// defocus goes to the exact 1-D path, as the centred circle of its radius with the tilt that
    /// decentring adds (exact; docs/physics.md, "General pupils"); off, it is sampled on the FFT
    /// path, for cross-checks.
    pub exact_irises: bool,
    /// Whether full circular pupils with Seidel terms beyond defocus or Zernike terms are
    /// computed by the quadrature over the pupils' overlap ([`Engine::Overlap`]) where `pupil_samples` is
    /// `None`; off (or with `pupil_samples` set) they are sampled on the FFT path.
    pub overlap: bool,
    /// The spectral rule's own tolerance where it is tighter than `tolerance` (`None`: follow
    /// `tolerance`): a field angle's gradient on the overlap engine asks for it, its lanes being
    /// the value's times the lateral colour's rate (docs/physics.md, "Gradients: the field
    /// point").
    pub spectral_tolerance: Option<f64>,
    /// The adaptive frequency rule's own tolerance where it is tighter than `tolerance` (`None`:
    /// follow `tolerance`): a field angle's gradient on the exact 1-D engine asks for it beside
    /// `spectral_tolerance`, its panels accepting on the value alone (docs/physics.md,
    /// "Gradients: the field point").
    pub frequency_tolerance: Option<f64>,
    /// Whether every order that is the full circle with a polynomial wavefront goes to the
    /// overlap engine ([`Engine::Overlap`]), a defocus alone too (no closed form, no exact 1-D
    /// path; a line's one wavelength too, where no order needs the grids): the Seidel gradient
    /// at zero Seidel terms asks for it (docs/physics.md, "Gradients: Seidel terms at zero"), the
    /// value staying its own engine's. Off by default.
    pub overlap_always: bool,
    /// The radial engine's rule for a pupil with a table's knots (`options.table_rule`):
    /// [`TableRule::Tensor`](crate::radial::TableRule::Tensor) (default) or the rule split at the
    /// knots.
    pub table_rule: crate::radial::TableRule,
    /// Whether the FFT path computes, beside each grid of an order through an aperture of disc
    /// shape, the grid's derivative in the obscuration ε (the inner edge's motion,
    /// [`WavefrontDirection::Obscuration`](crate::WavefrontDirection::Obscuration)) in the value's own pass, from the value's pupil
    /// spectrum: the gradient with respect to `lens.obscuration` asks for it (docs/physics.md,
    /// "Gradients: the edge's motion on the FFT path"). The value is the same bit for bit with
    /// or without it. Off by default.
    pub edge_lane: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            pupil_samples: None,
            tolerance: DEFAULT_TOLERANCE,
            fft_tolerance: Some(DEFAULT_FFT_TOLERANCE),
            closed_form: true,
            spectral_rule: SpectralRule::default(),
            exact_irises: true,
            overlap: true,
            spectral_tolerance: None,
            frequency_tolerance: None,
            overlap_always: false,
            table_rule: crate::radial::TableRule::Tensor,
            edge_lane: false,
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

/// Default relative tolerance of the mean MTF on the FFT path ([`Settings::fft_tolerance`]).
pub const DEFAULT_FFT_TOLERANCE: f64 = 1e-4;

/// How the frequency integral is done over an engine.
#[derive(Clone, Copy, Debug, PartialEq)]
enum FrequencyRule {
    /// Adaptive Gauss–Kronrod, at least `min_panels` initial panels over the whole range.
    Adaptive {
        /// Initial panels over `[0, ν_max]` (at least).
        min_panels: f64,
    },
    /// A fixed composite rule at half of `cell` (cycles/m), the finest cell of the FFT
    /// grids, whose interpolation kinks at every cell edge.
    Fixed {
        /// The finest grid cell in ν, cycles/m.
        cell: f64,
    },
}

/// What every engine answers: the polychromatic OTF, normalized to 1 at ν = 0 (the caller
/// answers ν = 0 itself), the spectral nodes it sums (for the averages over the spectrum), how
/// its frequency integral is done, and its counters.
trait OtfEngine: std::fmt::Debug {
    /// Which engine this is, for `--explain`.
    fn engine(&self) -> Engine;
    /// The spectral nodes.
    fn nodes(&self) -> &Nodes;
    /// The signed OTF of the rotationally symmetric system along +x (image shifts ignored).
    fn otf(&self, frequency: f64) -> f64;
    /// The complex OTF along `azimuth` (radians from the detector's x axis).
    fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64;
    /// On the FFT path: the grids read now, the scene and the nodes' total weight
    /// ([`otf_along`](Self::otf_along) is the path's sum over that weight).
    fn fft_reading(&self) -> Option<(&grid::FftPath, &Scene<'_>, f64)> {
        None
    }
    /// Whether the OTF depends on direction, so that the MTF must be read along an azimuth.
    fn direction_dependent(&self) -> bool {
        self.nodes().direction_dependent()
    }
    /// How the frequency integral is done.
    fn frequency_rule(&self) -> FrequencyRule;
    /// Whether the OTF is smooth (analytic) in ν up to `max_frequency`, so that the nested
    /// Clenshaw–Curtis rules may take the frequency integral: product-integration nodes (chosen
    /// only where every wavelength passes the limit) without tables (kinks at their columns).
    fn smooth_in_frequency(&self, _max_frequency: f64) -> bool {
        let nodes = self.nodes();
        nodes.interpolated && !nodes.nodes.iter().any(|n| n.table.is_some())
    }
    /// Frequencies in `[0, max_frequency]` where the OTF may kink (with both ends): a spectral
    /// panel edge, or the one wavelength of a line, reaching its cutoff.
    fn frequency_cuts(&self, max_frequency: f64) -> Vec<f64> {
        let nodes = self.nodes();
        let f_number = self.f_number();
        let mut cuts = vec![0.0, max_frequency];
        let ends = nodes.panels.iter().flat_map(|p| [p.lo, p.hi]);
        for lambda in ends.chain(nodes.line) {
            if lambda > 0.0 {
                let nu = 1.0 / (lambda * f_number);
                if nu < max_frequency {
                    cuts.push(nu);
                }
            }
        }
        sort_cuts(cuts)
    }
    /// Where the engine knows that the defocus oscillations of the OTF in ν average out over
    /// the spectrum: `(ν_s, W̄)`, beyond `ν_s` (cycles/m) only the oscillation at the mean defocus
    /// `W̄` (m) survives, damped. The frequency rule then sizes its panels by `W̄` and the spread,
    /// damped (`Polychromatic::defocus_phase`), and integrates past `frequency::AVERAGED_DECAY ν_s`
    /// in `ln ν`; `None` (every other engine): panels by the nodes' RMS and most resolved
    /// defocus, in ν.
    fn averaged_defocus(&self) -> Option<(f64, f64)> {
        None
    }
    /// A bound on how much a field angle's lane amplifies the value: the largest
    /// `2π ν |∂Δ/∂θ|` (per radian) over the nodes and the frequencies read, where the engine
    /// carries the field angles' lanes as each node's value times `−2πi ν u·∂Δ/∂θ` (the overlap
    /// engine, the exact 1-D engine); `None` elsewhere.
    fn field_lane_bound(&self) -> Option<f64> {
        None
    }
    /// The F-number the nodes' `s = ν λ F#` use.
    fn f_number(&self) -> f64;
    /// Sets the absolute tolerance of one OTF value, where the engine computes each to a
    /// tolerance (closed form); others ignore it.
    fn set_value_tolerance(&self, _absolute: f64) {}
    /// The absolute noise of one OTF value (0 where values are exact to rounding).
    fn value_noise(&self) -> f64 {
        0.0
    }
    /// Evaluations of an inner integrand so far (closed form: E(c)).
    fn value_evaluations(&self) -> usize {
        0
    }
    /// The signed OTF at `frequency` as [`otf`](Self::otf), and into `gradient` its derivative
    /// with respect to each Binary 2 coefficient of the lens (`LensModel::binary2_directions`,
    /// one lane each), on the value's own spectral rule; `None` where the engine does not give
    /// them (the default).
    fn otf_and_gradient(&self, _frequency: f64, _gradient: &mut [f64]) -> Option<f64> {
        None
    }
    /// The signed OTF at `frequency` as [`otf`](Self::otf) and its derivative with respect to a
    /// common relative change of every order's defocus at fixed `s = νλF#` (`∂O/∂ln K`,
    /// `W020 ∝ K = f0/(8F#²)`), on the value's own rule; `None` where the engine does not give
    /// it (the default).
    fn otf_and_defocus_derivative(&self, _frequency: f64) -> Option<(f64, f64)> {
        None
    }
    /// The signed OTF at `frequency` as [`otf`](Self::otf), bit for bit, and the lane
    /// `(Σ_o [w_o α_o w∂H_o/∂w + q γ_o H_o] − O Σ_o q γ_o) / Σ_o w_o` of a line whose every order
    /// is a full centred circle with a defocus alone (`rates[o] = [α_o, γ_o]` per node, `w_o` the
    /// node's weight `q τ_o`): the derivative of `O` at fixed `s = νλF#` along a change of each
    /// order's `ln w020` by `α_o` and of its efficiency by `γ_o` (docs/physics.md, "Gradients: a
    /// line's wavelength and a blackbody's temperature"); `None` where the engine does not give
    /// it (the default).
    fn otf_and_order_lane(&self, _frequency: f64, _rates: &[[f64; 2]]) -> Option<(f64, f64)> {
        None
    }
    /// The signed OTF at `frequency` as [`otf`](Self::otf) and its derivative along the lens's
    /// design wavelength, `∂O/∂ln λ0` at fixed `s = νλF#`: each order's defocus and efficiency
    /// moving by `LensModel::design_wavelength_rates` (docs/physics.md, "Gradients: the design
    /// wavelength"), on the value's own rule; `None` where the engine does not give it (the
    /// default).
    fn otf_and_design_lane(&self, _frequency: f64) -> Option<(f64, f64)> {
        None
    }
    /// The signed OTF at `frequency` as [`otf`](Self::otf) and, into `lanes` (`2n + 1` for `n`
    /// orders at every wavelength), the design wavelength's lane of each order alone (order
    /// `o`'s rates from `LensModel::design_wavelength_rates`, the others' held), then each
    /// order's efficiency lane (`δτ_o = τ_o`), each less `O` times its normalization's rate,
    /// then the defocus lane `∂O/∂ln K` ([`otf_and_defocus_derivative`](Self::otf_and_defocus_derivative)'s),
    /// on the value's own rule (docs/physics.md, "Gradients: the multiplexed lens"); `None` where
    /// the engine does not give them (the default).
    fn otf_and_order_lanes(&self, _frequency: f64, _lanes: &mut [f64]) -> Option<f64> {
        None
    }
    /// The exact engine's quadrature, for the tests of its node cache (`None` for the others).
    #[cfg(test)]
    fn exact_quadrature(&self) -> Option<&exact::Quadrature<'_>> {
        None
    }
    /// The signed OTF at `frequency` as [`otf`](Self::otf) and into `gradient` its derivative
    /// along each of `parameters` of the lens's order derivatives
    /// (`LensModel::order_derivatives`: a library lens's parameter bias), on the value's own
    /// rule; `None` where the engine does not give them (the default).
    fn otf_and_field_gradient(&self, _frequency: f64, _parameters: &[usize], _gradient: &mut [f64]) -> Option<f64> {
        None
    }
    /// The signed OTF at `frequency` and into `lanes` its derivatives per metre along a
    /// spherical aberration `W040 ρ⁴` and a constant defocus `W220 ρ²` (field curvature) at
    /// zero, where every order carries a defocus alone (docs/physics.md, "Gradients: Seidel
    /// terms at zero"), on the value's own rule; `None` where the engine does not give them
    /// (the default).
    fn otf_and_seidel_lanes(&self, _frequency: f64, _lanes: &mut [f64; 2]) -> Option<f64> {
        None
    }
    /// The signed OTF at `frequency` as [`otf`](Self::otf) and into `lanes` its derivatives
    /// along a rate `r(λ)` of the detected spectrum (`rate = (r, ⟨r⟩)`, one lane) and along the
    /// band's ends (`edges`, two lanes: the lower, then the upper), on the value's own rule
    /// (the per-frequency product rule: docs/physics.md, "Gradients: a line's wavelength and a
    /// blackbody's temperature", "Gradients: a top-hat's edges"); `None` where the engine does
    /// not give them (the default).
    fn otf_and_spectral_lanes(
        &self,
        _frequency: f64,
        _rate: Option<(&dyn Fn(f64) -> f64, f64)>,
        _edges: bool,
        _lanes: &mut [f64],
    ) -> Option<f64> {
        None
    }
    /// The signed OTF at `frequency` as [`otf`](Self::otf), bit for bit, and into `lanes` the
    /// design wavelength's lane `∂O/∂ln λ0` ([`otf_and_design_lane`](Self::otf_and_design_lane)'s)
    /// and the band's two edge lanes ([`otf_and_spectral_lanes`](Self::otf_and_spectral_lanes)'s
    /// with `edges`), read on the same climb (docs/physics.md, "Gradients: the
    /// dispersion-engineered lens"); `None` where the engine does not give them (the default).
    fn otf_and_design_and_edge_lanes(&self, _frequency: f64, _lanes: &mut [f64; 4]) -> Option<f64> {
        None
    }
    /// The band `[lo, hi]` (m) whose ends the edge lanes of
    /// [`otf_and_spectral_lanes`](Self::otf_and_spectral_lanes) move; `None` where the engine
    /// gives no such lanes (the default).
    fn spectral_ends(&self) -> Option<(f64, f64)> {
        None
    }
    /// The sampling plan whose coarse level the engine also holds (the FFT engine when the
    /// tolerance chose its sampling): the frequency rule then extrapolates the two means.
    fn richardson(&self) -> Option<crate::fft::SamplingPlan> {
        None
    }
    /// Reads the OTF from the coarse level (`on`) or the fine one.
    fn read_coarse(&self, _on: bool) {}
    /// The means along `azimuth` at the coarse and fine levels, `(M_{N/2}, M_N)`, where the
    /// engine has already computed them by the fixed frequency rule (the FFT engine's sampling
    /// choice judges the same azimuths): the frequency rule extrapolates them instead of reading
    /// the grids again.
    fn means_along(&self, _azimuth: f64) -> Option<(f64, f64)> {
        None
    }
    /// The derivative of the mean MTF averaged over the `count` azimuths from `first` with
    /// respect to `ln F#` at fixed pupils (each grid read at `s = νλF#`, the frequencies in ν
    /// fixed) on the value's own rules (the FFT engine: `grid::FftPath::scale_over_azimuth`);
    /// `None` where the engine does not give it (the default).
    fn scale_over_azimuth(&self, _first: f64, _count: usize) -> Option<f64> {
        None
    }
    /// The derivative of the mean MTF averaged over the `count` azimuths from `first` with
    /// respect to each of `directions`, on the value's own rules (the FFT engine:
    /// `grid::FftPath::gradient_over_azimuth`); `Ok(None)` where the engine does not give it
    /// (the default).
    fn wavefront_gradient_over_azimuth(
        &self,
        _first: f64,
        _count: usize,
        _directions: &[WavefrontDirection],
    ) -> Result<Option<Vec<f64>>, Error> {
        Ok(None)
    }
    /// [`wavefront_gradient_over_azimuth`](Self::wavefront_gradient_over_azimuth) of the mean
    /// of `P |O| / n` under the non-white noise spectrum `noise` (each frequency's weight
    /// divided by `n(ν)`); `Ok(None)` where the engine does not give it (the default).
    fn wavefront_gradient_over_azimuth_over_noise(
        &self,
        _first: f64,
        _count: usize,
        _directions: &[WavefrontDirection],
        _noise: &NoiseShape,
    ) -> Result<Option<Vec<f64>>, Error> {
        Ok(None)
    }
    /// The complex OTF at `frequency` along `azimuth` ([`otf_along`](Self::otf_along)'s rule
    /// at the current value tolerance), and into `gradient` its derivative with respect to each
    /// of `directions`, forward mode on the same rule (the overlap engine's Seidel terms);
    /// `None` where the engine does not give them (the default).
    fn otf_along_and_gradient(
        &self,
        _frequency: f64,
        _azimuth: f64,
        _directions: &[WavefrontDirection],
        _gradient: &mut [Complex64],
    ) -> Option<Complex64> {
        None
    }
    /// Why the engine stopped before its result converged (a work budget), if it did.
    fn over_budget(&self) -> Option<String> {
        None
    }
    /// The spectral nodes of the defocus lane's own rule, where the engine takes the lane
    /// ([`WavefrontDirection::Defocus`]) on a finer spectral rule than the value's.
    fn defocus_lane_nodes(&self) -> Option<usize> {
        None
    }
    /// Cutoff frequency (cycles/m) of the shortest wavelength covered: the OTF is zero beyond.
    fn max_cutoff(&self) -> f64 {
        1.0 / (self.nodes().shortest() * self.f_number())
    }
    /// Photoelectron-weighted fraction of the signal whose `|W020|` exceeds `w020_limit`.
    /// `scene` is the [`Polychromatic`]'s (with its parts): each panel is integrated with its
    /// own part's lens and spectrum.
    fn fraction_blurred_beyond(&self, scene: &Scene<'_>, w020_limit: f64) -> f64 {
        let nodes = self.nodes();
        if nodes.line.is_some() {
            // one wavelength: each order is beyond or not (0 or 1 for a single order)
            let na = scene.lens.numerical_aperture();
            let beyond: f64 = nodes
                .nodes
                .iter()
                .filter(|n| {
                    crate::fraunhofer::node_blur_w020(n.w020, n.table.as_deref(), n.lambda, na).abs() > w020_limit
                })
                .map(|n| n.weight)
                .sum();
            return beyond / nodes.total_weight;
        }
        let mut beyond = 0.0;
        for part in nodes.parts() {
            let panels: Vec<(f64, f64)> =
                nodes.panels.iter().filter(|p| p.part == part).map(|p| (p.lo, p.hi)).collect();
            let part = scene.part(part);
            let density = |lambda: f64| part.detected.value(lambda);
            beyond += crate::fraunhofer::weight_defocused_beyond(part.lens, part.field, &density, &panels, w020_limit);
        }
        (beyond / nodes.total_weight).clamp(0.0, 1.0)
    }
}

/// The error of the last of a sequence of nested rules (each with twice the points of the one
/// before) from the differences `moves` between consecutive ones, last last: with the ratio
/// `r = d/d'` of the last two, the next difference is about `d r` (the ratio holding for one
/// more doubling). No credit is taken for an acceleration the moves show (`d r²`-like once the
/// convergence is geometric in the points): on the frequency panel [0, 12] cycles/mm of the
/// F/1.4, 200 nm scene the moves 318, 30.4, 0.0139 credited so predicted 3.0e-8, and the next
/// was 3.8e-6 (ratio 2.7e-4, below `r` = 4.6e-4); the mean was 3.5e-10 off at tolerance 1e-10.
/// With fewer than two moves: infinite.
fn nested_error(moves: &[f64]) -> f64 {
    match moves {
        [.., d1, d2] if *d1 > 0.0 => d2 * (d2 / d1).min(1.0),
        [.., _, d2] => *d2,
        _ => f64::INFINITY,
    }
}

/// The error of the last of a sequence of nested rules, once the last has the points that
/// resolve its integrand (`resolved`): the nested estimate `nested` ([`nested_error`] or
/// [`nested_error_accelerated`]); before, where a coarse pair can agree by chance, the larger of
/// the last two moves (two consecutive moves must both be within the budget). Infinite with
/// fewer moves than that needs.
fn level_error(moves: &[f64], resolved: bool, nested: fn(&[f64]) -> f64) -> f64 {
    if resolved {
        return nested(moves);
    }
    match moves {
        [.., a, b] => a.max(*b),
        _ => f64::INFINITY,
    }
}

/// [`nested_error`] crediting the acceleration the moves show: `d r min(1, r/r')` with `r'` the
/// ratio before (`d r²`-like once the convergence is geometric in the points). Only for the
/// spectral rule at the frequency limit, whose accepted level is then checked once more against
/// the counts between it and the level below (`Interpolant::trim`): a value accepted on it alone
/// may be off by far more than the estimate (see [`nested_error`]).
fn nested_error_accelerated(moves: &[f64]) -> f64 {
    match moves {
        [.., d0, d1, d2] if *d0 > 0.0 && *d1 > 0.0 => {
            let r = (d2 / d1).min(1.0);
            d2 * r * (r / (d1 / d0)).min(1.0)
        }
        _ => nested_error(moves),
    }
}

/// Sorted frequency cuts, merged when within 1e-12 of each other relative to themselves (a
/// 1e-206 m pixel puts Nyquist 1e200 times above them).
fn sort_cuts(mut cuts: Vec<f64>) -> Vec<f64> {
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * a.abs().max(b.abs()));
    cuts
}

/// A prepared polychromatic evaluation for one lens, detected spectrum and field point, valid
/// for frequencies up to `max_frequency`: the engine chosen for them, and what the
/// frequency integration needs.
#[derive(Debug)]
pub struct Polychromatic<'a> {
    /// the lens, the detected spectrum and the factored parts ([`with_parts`](Self::with_parts)),
    /// the field, the F-number, the frequency limit and the pixel pitch
    scene: Scene<'a>,
    /// the settings' tolerance, or their `frequency_tolerance` where tighter (the frequency rule's)
    asked_tolerance: f64,
    /// the tolerance the engine worked to ([`Polychromatic::tolerance`])
    engine_tolerance: f64,
    engine: Box<dyn OtfEngine + 'a>,
    /// largest |W020| among significant nodes, m
    w020_max: f64,
    /// weighted RMS of W020, m
    w020_rms: f64,
    /// the defocus beyond which the nodes' signal together could move the mean by at most a
    /// hundredth of the tolerance, m ([`resolved_defocus`]): the defocus phase a frequency rule
    /// must resolve
    w020_resolved: f64,
    /// while [`mean_mtf_and_binary2_gradient`](Polychromatic::mean_mtf_and_binary2_gradient)
    /// runs: the OTF's derivatives at every frequency the rule read, and the rule it accepted
    gradient: std::cell::RefCell<Option<frequency::Recording>>,
}

/// The defocus (m) the frequency rule must resolve: the largest `|W020|` such that the nodes at
/// that defocus and beyond carry more than `relevant` of the detected signal together (those
/// beyond it, at most `relevant`, move the mean by at most that much however their oscillation
/// is sampled: an OTF is at most 1).
///
/// A node's signal is its order's efficiency times the detected spectrum's mass around its
/// wavelength: the largest density at it and its two neighbours times half the distance between
/// them (an upper envelope of the spectrum over the node's share of the band). Not the node's
/// rule weight: product-integration weights of a panel on a Gaussian's tail alternate in sign
/// at ±1e-6 of the total where the spectrum holds 1e-9 (the Binary 2 metalens at 50 nm), and
/// read as weights they made the rule resolve the defocus at 7σ. A single wavelength (a line)
/// keeps its weight.
///
/// With parts ([`Polychromatic::with_parts`]), each node's signal is read from its own part's
/// samples and spectrum.
fn resolved_defocus(nodes: &Nodes, scene: &Scene<'_>, relevant: f64) -> f64 {
    let mut signal: Vec<(f64, f64)> = Vec::with_capacity(nodes.nodes.len());
    for part in nodes.parts() {
        part_signal(nodes, part, scene.part(part).detected, &mut signal);
    }
    defocus_beyond(signal, relevant)
}

/// The largest `|W020|` of `signal` (`(|W020|, signal)` pairs) such that the signal at that
/// defocus and beyond exceeds `relevant`; 0 where none does.
///
/// The pairs are taken in the order of a stable sort by `|W020|`, largest first (equal ones in
/// their order in `signal`), their signal summed in that order until it exceeds `relevant`.
/// Where `|W020|` first falls and then rises along `signal` (an affine defocus over ascending
/// wavelengths, the closed form's nodes: the sort was 2 % of a map point), the two runs are
/// merged from their large ends as far as the sum goes, the same pairs in the same order
/// (test `defocus_beyond_merges_as_the_sort_orders`); otherwise they are sorted.
fn defocus_beyond(mut signal: Vec<(f64, f64)>, relevant: f64) -> f64 {
    let n = signal.len();
    // `signal[..fall]` non-increasing in |W020|, then `signal[fall..]` non-decreasing
    let mut fall = 1.min(n);
    while fall < n && signal[fall].0.total_cmp(&signal[fall - 1].0).is_le() {
        fall += 1;
    }
    let rises = (fall + 1..n).all(|i| signal[i].0.total_cmp(&signal[i - 1].0).is_ge());
    if !rises {
        signal.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut beyond = 0.0;
        for (w020, mass) in signal {
            beyond += mass;
            if beyond > relevant {
                return w020;
            }
        }
        return 0.0;
    }
    let mut beyond = 0.0;
    // the next of the falling run, and the end (exclusive) of what is left of the rising one
    let (mut i, mut end) = (0, n);
    while i < fall || end > fall {
        if i < fall && (end == fall || signal[i].0.total_cmp(&signal[end - 1].0).is_ge()) {
            // (an equal |W020| of the falling run comes first: its index is the lower)
            let (w020, mass) = signal[i];
            i += 1;
            beyond += mass;
            if beyond > relevant {
                return w020;
            }
        } else {
            // the rising run's largest |W020|, its equal ones in their order
            let key = signal[end - 1].0;
            let mut start = end - 1;
            while start > fall && signal[start - 1].0.total_cmp(&key).is_eq() {
                start -= 1;
            }
            for &(w020, mass) in &signal[start..end] {
                beyond += mass;
                if beyond > relevant {
                    return w020;
                }
            }
            end = start;
        }
    }
    0.0
}

/// `(|W020|, signal)` of each node of `part` ([`resolved_defocus`]) appended to `signal`;
/// `detected` is the part's spectrum.
fn part_signal(nodes: &Nodes, part: usize, detected: &Spectrum, signal: &mut Vec<(f64, f64)>) {
    if part_signal_in_step(nodes, part, signal) {
        return;
    }
    let mut samples: Vec<(f64, f64)> = Vec::with_capacity(nodes.samples.len());
    samples.extend(nodes.samples.iter().filter(|s| s.2 == part && s.0.is_finite()).map(|s| (s.0, s.1)));
    // (the rules emit their samples in order: no sort then, the same order a stable sort keeps)
    if !samples.is_sorted_by(|a, b| a.0.total_cmp(&b.0).is_le()) {
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    // the densities the engine read already, where its samples are these, strictly ascending
    let known = nodes.densities.as_deref().filter(|d| {
        d.len() == samples.len()
            && samples.len() == nodes.samples.len()
            && samples.windows(2).all(|w| w[0].0 < w[1].0)
            && nodes.samples.iter().zip(&samples).all(|(s, t)| s.0 == t.0)
    });
    let mut lambdas: Vec<f64> = samples.iter().map(|s| s.0).collect();
    lambdas.dedup();
    // the index `partition_point(|x| x < lambda)` of an ascending slice, tried first at `hint`
    // (the nodes come in the samples' order: each one at the last one's index or the next)
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // (the negated predicate, as partition_point reads it, NaN included)
    fn first_not_below(values: &[f64], lambda: f64, hint: usize) -> usize {
        for i in [hint, hint + 1] {
            if i < values.len() && !(values[i] < lambda) && (i == 0 || values[i - 1] < lambda) {
                return i;
            }
        }
        values.partition_point(|&x| x < lambda)
    }
    let sample_lambdas: Vec<f64> = samples.iter().map(|s| s.0).collect();
    // a node's rule weight: the sample at its wavelength (one per wavelength)
    let mut sample_hint = 0;
    let mut rule_weight = |lambda: f64| {
        let i = first_not_below(&sample_lambdas, lambda, sample_hint);
        sample_hint = i;
        samples.get(i).filter(|s| s.0 == lambda).map_or(0.0, |s| s.1)
    };
    // the detected spectrum once per wavelength (each is read by its node and its two
    // neighbours: a third of the evaluations, 4 % of the paper point's time), or as the engine
    // read it
    let densities: Vec<f64> = if lambdas.len() < 3 {
        Vec::new()
    } else if let Some(known) = known {
        known.iter().map(|d| d.abs()).collect()
    } else {
        lambdas.iter().map(|&l| detected.value(l).abs()).collect()
    };
    let mut lambda_hint = 0;
    let mut mass_around = |lambda: f64| -> Option<f64> {
        if lambdas.len() < 3 {
            return None;
        }
        let i = first_not_below(&lambdas, lambda, lambda_hint);
        lambda_hint = i;
        if i >= lambdas.len() || lambdas[i] != lambda {
            return None;
        }
        let (lo, hi) = (i.saturating_sub(1), (i + 1).min(lambdas.len() - 1));
        let density = densities[lo..=hi].iter().copied().fold(0.0, f64::max);
        Some(density * 0.5 * (lambdas[hi] - lambdas[lo]))
    };
    for n in nodes.nodes.iter().filter(|n| n.part == part) {
        let w = rule_weight(n.lambda);
        let mass = match mass_around(n.lambda) {
            Some(m) if w != 0.0 && m.is_finite() => m * (n.weight / w).abs(),
            _ => n.weight.abs(),
        };
        signal.push((n.w020.abs(), mass));
    }
}

/// [`part_signal`] where the nodes and the samples go in step: one node a sample, at the
/// sample's wavelength, all of `part`, strictly ascending and finite, with the densities the
/// engine read (the closed form's nodes). Each node's signal is then its own density and its
/// neighbours', read by index: the same numbers in the same order as the searches of the
/// general way find them, without its four vectors (test `part_signal_shortcuts_match_the_reference`).
/// Returns `false`, having appended nothing, where the nodes are not so.
fn part_signal_in_step(nodes: &Nodes, part: usize, signal: &mut Vec<(f64, f64)>) -> bool {
    let (samples, list) = (&nodes.samples, &nodes.nodes);
    let n = samples.len();
    let Some(densities) = nodes.densities.as_deref().filter(|d| d.len() == n && list.len() == n && n >= 3) else {
        return false;
    };
    let in_step = samples.iter().zip(list).enumerate().all(|(i, (s, node))| {
        s.2 == part && node.part == part && s.0.is_finite() && node.lambda == s.0 && (i == 0 || samples[i - 1].0 < s.0)
    });
    if !in_step {
        return false;
    }
    signal.reserve(n);
    for (i, (s, node)) in samples.iter().zip(list).enumerate() {
        let w = s.1;
        let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
        let density = densities[lo..=hi].iter().map(|d| d.abs()).fold(0.0, f64::max);
        let m = density * 0.5 * (samples[hi].0 - samples[lo].0);
        let mass = if w != 0.0 && m.is_finite() { m * (node.weight / w).abs() } else { node.weight.abs() };
        signal.push((node.w020.abs(), mass));
    }
    true
}

/// The engine for a scene: the closed form where it applies (and is allowed), a line's engine
/// for a line spectrum, else spectral nodes (product integration, or the panels rule where a
/// cutoff falls inside the band or the settings ask for it) read through the exact 1-D OTF, or
/// through FFT grids where some order's pupil or wavefront needs them.
fn choose<'a>(scene: Scene<'a>, settings: Settings) -> Result<Box<dyn OtfEngine + 'a>, Error> {
    let pupil_samples = settings.pupil_samples.unwrap_or(DEFAULT_PUPIL_SAMPLES);
    if let Some(l) = scene.detected.as_line() {
        // (its grids carry the edge lane where asked, as a band's: the obscuration's gradient
        // under a line, docs/physics.md "Gradients: 2-D pupils under a line")
        let scene = scene.whole();
        let nodes = spectral::line(&scene, l);
        check_signal(&nodes)?;
        // the overlap engine asked for at the line's one wavelength (the Seidel gradient at zero
        // Seidel terms: docs/physics.md, "Gradients: Seidel terms at zero"), where no order
        // needs the grids; the value stays its own engine's
        if settings.overlap_always && settings.overlap && settings.pupil_samples.is_none() && !nodes.needs_grid {
            let tolerance = settings.fft_tolerance.unwrap_or(settings.tolerance).max(settings.tolerance);
            if let Some(engine) = overlap::Overlap::new(scene, nodes.clone(), tolerance) {
                return Ok(Box::new(engine));
            }
        }
        let fft = if nodes.needs_grid { Some(grid::FftPath::build(&scene, &nodes, pupil_samples)?) } else { None };
        return Ok(Box::new(line::Line { scene, nodes, fft }));
    }
    let (lo, hi) = spectral_extent(scene.detected)?;
    if settings.closed_form
        && !settings.overlap_always
        && scene.parts.is_empty()
        && let Some((closed, affine)) = closed_form::closed_form(scene.lens, scene.detected, scene.field)
    {
        let mut engine = closed_form::Closed::new(closed, affine, scene.detected, scene.f_number, settings.tolerance);
        engine.design = closed_form::design_direction(scene.lens, scene.field, &engine.closed);
        check_signal(&engine.nodes)?;
        return Ok(Box::new(engine));
    }
    // product integration read per frequency, where every order is a centred circle with defocus
    if settings.spectral_rule == SpectralRule::Interpolated
        && !settings.overlap_always
        && let Some(engine) = per_frequency::PerFrequency::new(scene, lo, hi, settings.tolerance)
    {
        check_signal(engine.nodes())?;
        return Ok(Box::new(engine));
    }
    // the spectral rule's tolerance: the engine's, or `spectral_tolerance` where tighter
    let spectral = |t: f64| settings.spectral_tolerance.map_or(t, |s| s.min(t));
    let interpolated = match settings.spectral_rule {
        SpectralRule::Interpolated => spectral::interpolated(&scene, lo, hi, spectral(settings.tolerance)),
        SpectralRule::Panels => None,
    };
    // the reference panels do not factor: the whole lens through the detected spectrum, cut
    // at every row of its tables
    let (scene, mut nodes) = match interpolated {
        Some(nodes) => (scene, nodes),
        None => (scene.whole(), spectral::panels(&scene.whole(), lo, hi)),
    };
    check_signal(&nodes)?;
    // the overlap engine asked for where no order needs it: its own tolerance and nodes as for
    // a Seidel pupil, or the exact path where some order is not the full circle
    if nodes.needs_grid || (settings.overlap_always && settings.overlap && settings.pupil_samples.is_none()) {
        let tolerance = settings.fft_tolerance.unwrap_or(settings.tolerance).max(settings.tolerance);
        // the FFT path's tolerance bounds the mean's accuracy: spectral nodes (one grid each)
        // finer than it buy nothing
        if nodes.interpolated
            && tolerance > settings.tolerance
            && let Some(coarser) = spectral::interpolated(&scene, lo, hi, spectral(tolerance))
        {
            nodes = coarser;
            check_signal(&nodes)?;
        }
        if settings.overlap
            && settings.pupil_samples.is_none()
            && let Some(engine) = overlap::Overlap::new(scene, nodes.clone(), tolerance)
        {
            return Ok(Box::new(engine));
        }
        if !nodes.needs_grid {
            return Ok(Box::new(exact::Quadrature::new(scene, nodes)));
        }
        return Ok(Box::new(grid::Grids::new(scene, nodes, settings.pupil_samples, tolerance)?));
    }
    Ok(Box::new(exact::Quadrature::new(scene, nodes)))
}

/// A signal must be there: the nodes' total weight positive and finite.
fn check_signal(nodes: &Nodes) -> Result<(), Error> {
    if nodes.total_weight > 0.0 && nodes.total_weight.is_finite() {
        Ok(())
    } else {
        Err(Error::NoSignal { total: nodes.total_weight })
    }
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
        Self::with_settings(lens, detected, field, max_frequency, pixel_pitch, Settings::default())
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
    /// FFT path, whether the closed-form engine may be used, and the spectral rule.
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
        Self::with_parts(lens, detected, &[], field, max_frequency, pixel_pitch, settings)
    }

    /// [`with_settings`](Self::with_settings) for a lens whose efficiency tables are factored
    /// out ([`crate::FactoredEfficiency`]): `lens` and `detected` as there, and `parts` the
    /// lens's parts, each its relative orders and `ρ t_p` ([`Part`]). Product integration (on
    /// the exact path, per frequency and on the FFT path) then integrates each part with the
    /// exact moments of its own spectrum, so that no table row cuts a spectral panel; the rules
    /// that do not factor (a line, the closed form, the reference panels) take `lens` and
    /// `detected` as they are. The parts' orders together must be the lens's orders, their
    /// efficiencies times the tables, or the results are those of the parts.
    pub fn with_parts(
        lens: &'a dyn LensModel,
        detected: &'a Spectrum,
        parts: &'a [Part<'a>],
        field: Field,
        max_frequency: f64,
        pixel_pitch: Option<f64>,
        settings: Settings,
    ) -> Result<Self, Error> {
        Self::prepared(lens, detected, parts, field, max_frequency, pixel_pitch, settings, None)
    }

    /// [`with_settings`](Self::with_settings), the FFT path's grids taken from `shared` where an
    /// engine of the same lens and field built there already made them (the same spectral node
    /// wavelength, order, pupil sampling and frequency extent: the same grid bit for bit) and
    /// put there otherwise ([`SharedGrids`]). Engines of one lens under several spectra (the
    /// spectral gradient's `ρ`, `ρλ`, `ρλ²`, whose product-integration nodes mostly coincide)
    /// then compute each pupil field and grid once. Results are those of
    /// [`with_settings`](Self::with_settings), bit for bit.
    pub fn with_shared_grids(
        lens: &'a dyn LensModel,
        detected: &'a Spectrum,
        field: Field,
        max_frequency: f64,
        pixel_pitch: Option<f64>,
        settings: Settings,
        shared: &'a SharedGrids,
    ) -> Result<Self, Error> {
        Self::prepared(lens, detected, &[], field, max_frequency, pixel_pitch, settings, Some(shared))
    }

    #[allow(clippy::too_many_arguments)]
    fn prepared(
        lens: &'a dyn LensModel,
        detected: &'a Spectrum,
        parts: &'a [Part<'a>],
        field: Field,
        max_frequency: f64,
        pixel_pitch: Option<f64>,
        settings: Settings,
        shared: Option<&'a SharedGrids>,
    ) -> Result<Self, Error> {
        if !(settings.tolerance.is_finite() && settings.tolerance > 0.0 && settings.tolerance < 1.0) {
            return Err(Error::InvalidParameter {
                name: "tolerance",
                value: settings.tolerance,
                expected: "a relative error in (0, 1), e.g. 1e-6",
            });
        }
        if !(max_frequency.is_finite() && max_frequency > 0.0) {
            return Err(Error::InvalidParameter {
                name: "max_frequency",
                value: max_frequency,
                expected: "finite and > 0 cycles/m",
            });
        }
        let f_number = lens.f_number();
        let irises = settings.exact_irises.then(|| lens.numerical_aperture());
        let table_rule = settings.table_rule;
        let edge_lane = settings.edge_lane;
        let scene = Scene {
            lens,
            detected,
            field,
            f_number,
            max_frequency,
            pixel_pitch,
            irises,
            table_rule,
            parts,
            edge_lane,
            shared,
        };
        let engine = choose(scene, settings)?;
        // the FFT path's spectral nodes and sampling work to the FFT tolerance where it is larger
        let engine_tolerance = match engine.engine() {
            Engine::Fft { .. } | Engine::Overlap { .. } => {
                settings.fft_tolerance.unwrap_or(settings.tolerance).max(settings.tolerance)
            }
            _ => settings.tolerance,
        };
        let mut this = Polychromatic {
            scene,
            asked_tolerance: settings.frequency_tolerance.map_or(settings.tolerance, |f| f.min(settings.tolerance)),
            engine_tolerance,
            engine,
            w020_max: 0.0,
            w020_rms: 0.0,
            w020_resolved: 0.0,
            gradient: std::cell::RefCell::new(None),
        };
        // the largest |W020| among the nodes that carry weight, and the weighted RMS of W020
        // (the frequency rule's initial panels)
        let nodes = this.engine.nodes();
        let threshold = SIGNIFICANT_WEIGHT * nodes.total_weight;
        this.w020_max =
            nodes.nodes.iter().filter(|n| n.weight.abs() > threshold).map(|n| n.w020.abs()).fold(0.0, f64::max);
        let relevant = 1e-2 * settings.tolerance * nodes.total_weight.abs();
        this.w020_resolved = resolved_defocus(nodes, &scene, relevant);
        // (product-integration weights may be negative: the average of W020² too, by rounding)
        this.w020_rms = this.spectral_average(|_, w020| w020 * w020).max(0.0).sqrt();
        Ok(this)
    }

    /// The relative tolerance of the mean MTF the engine worked to: the settings' `tolerance`,
    /// or on the FFT path ([`Engine::Fft`]) their `fft_tolerance` where it is larger (its
    /// spectral nodes and, unless the settings fix it, its pupil sampling follow it).
    pub fn tolerance(&self) -> f64 {
        self.engine_tolerance
    }

    /// The OTF engine in use.
    pub fn engine(&self) -> Engine {
        self.engine.engine()
    }

    /// The engine's bound on a field angle's lane relative to the value (the largest
    /// `2π ν |∂Δ/∂θ|` over its nodes up to the frequency limit, per radian), where its field
    /// lanes are the nodes' values times that factor (the overlap engine and the exact 1-D
    /// engine); `None` elsewhere.
    pub fn field_lane_bound(&self) -> Option<f64> {
        self.engine.field_lane_bound()
    }

    /// Whether the OTF depends on direction (lateral colour, or a non-symmetric pupil or
    /// wavefront): the MTF must then be read along an azimuth.
    pub fn direction_dependent(&self) -> bool {
        self.engine.direction_dependent()
    }

    /// `∫ ρ(λ) τ(λ) dλ` summed over the imaging orders: the detected-signal integral in the units
    /// of the `detected` spectrum.
    pub fn total_weight(&self) -> f64 {
        self.engine.nodes().total_weight
    }

    /// `∫ ρ(λ) f(λ) dλ` over the detected spectrum *before* the lens (no efficiency factor),
    /// with the same spectral rule; `None` where the nodes integrate the parts' spectra `ρ t_p`
    /// instead ([`with_parts`](Self::with_parts) on a product-integration engine).
    pub fn detected_integral(&self, mut f: impl FnMut(f64) -> f64) -> Option<f64> {
        let samples = &self.engine.nodes().samples;
        if !self.scene.parts.is_empty() && samples.iter().any(|s| s.2 != spectral::WHOLE) {
            return None;
        }
        Some(samples.iter().map(|&(lambda, w, _)| w * f(lambda)).sum())
    }

    /// [`detected_integral`](Self::detected_integral) of `N` functions in one pass over the
    /// nodes: `f(λ)` gives their values at a node. Each sum is taken in the nodes' order from
    /// −0 as `detected_integral`'s, so each is the same to the bit.
    pub fn detected_integrals<const N: usize>(&self, mut f: impl FnMut(f64) -> [f64; N]) -> Option<[f64; N]> {
        let samples = &self.engine.nodes().samples;
        if !self.scene.parts.is_empty() && samples.iter().any(|s| s.2 != spectral::WHOLE) {
            return None;
        }
        let mut sums = [-0.0; N];
        for &(lambda, w, _) in samples {
            for (sum, value) in sums.iter_mut().zip(f(lambda)) {
                *sum += w * value;
            }
        }
        Some(sums)
    }

    /// Weighted average of `f(λ, W020)` over the detected spectrum (weights `ρ τ`).
    pub fn spectral_average(&self, mut f: impl FnMut(f64, f64) -> f64) -> f64 {
        let nodes = self.engine.nodes();
        nodes.nodes.iter().map(|n| n.weight * f(n.lambda, n.w020)).sum::<f64>() / nodes.total_weight
    }

    /// The spectral nodes' mean wavelength `λ̄` (m) and variance `⟨(λ − λ̄)²⟩` (m²), weights
    /// `ρ τ` as [`spectral_average`](Self::spectral_average)'s: the centre about which the
    /// [`WavefrontDirection::SpectralMoment`] lanes re-weight the nodes.
    pub fn node_wavelength_moments(&self) -> (f64, f64) {
        self.engine.nodes().wavelength_moments()
    }

    /// Signed polychromatic OTF at `frequency` (cycles/m), normalized to 1 at zero frequency, of
    /// the rotationally symmetric system: image displacements are ignored (see
    /// [`otf_along`](Self::otf_along) for the complex OTF with lateral colour).
    pub fn otf(&self, frequency: f64) -> f64 {
        if frequency == 0.0 {
            return 1.0;
        }
        self.engine.otf(frequency)
    }

    /// Complex polychromatic OTF at `frequency` (cycles/m) along the direction `azimuth` (radians
    /// from the detector's x axis): each wavelength's OTF times `exp(−2πi ν u·Δ)` for its image
    /// displacement Δ (docs/physics.md: in the general case sum complex OTFs, then take the modulus).
    pub fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64 {
        if frequency == 0.0 {
            return Complex64::new(1.0, 0.0);
        }
        self.engine.otf_along(frequency, azimuth)
    }

    /// [`otf_along`](Self::otf_along) of each of `engines` at once, each the same to the bit:
    /// on the FFT path, engines built with one [`SharedGrids`]
    /// ([`with_shared_grids`](Self::with_shared_grids)) read each grid they share once.
    pub fn otf_along_together(engines: &[Polychromatic<'_>], frequency: f64, azimuth: f64) -> Vec<Complex64> {
        if frequency == 0.0 {
            return vec![Complex64::new(1.0, 0.0); engines.len()];
        }
        let reading: Option<Vec<_>> = engines.iter().map(|e| e.engine.fft_reading()).collect();
        match reading {
            Some(reading) if engines.len() > 1 => {
                let paths: Vec<_> = reading.iter().map(|(path, scene, _)| (*path, *scene)).collect();
                let sums = grid::FftPath::sums_along(&paths, frequency, azimuth);
                sums.into_iter().zip(&reading).map(|(sum, (_, _, total))| sum / *total).collect()
            }
            _ => engines.iter().map(|e| e.otf_along(frequency, azimuth)).collect(),
        }
    }

    /// Whether some wavelength's image is displaced, so that the OTF is complex and depends on
    /// the direction.
    pub fn has_lateral_shifts(&self) -> bool {
        self.engine.nodes().shifted()
    }

    /// Whether the OTF stays as it is when the field point moves: no image is displaced, and at
    /// every spectral node's wavelength the lens's orders change with the field only through
    /// image shifts whose rates ([`LensModel::image_shift_field_rates`]) are all zero (a lens
    /// whose stop is at the lens, without lateral colour; a line at the design wavelength), so
    /// the mean MTF's derivative with respect to a field angle is 0 (docs/physics.md,
    /// "Gradients: the field point").
    pub fn field_independent(&self) -> bool {
        let nodes = self.engine.nodes();
        !nodes.shifted()
            && !self.direction_dependent()
            && nodes.nodes.iter().all(|n| {
                self.scene
                    .lens
                    .image_shift_field_rates(n.lambda, self.scene.field)
                    .is_some_and(|rates| rates.iter().all(|r| *r == [0.0, 0.0]))
            })
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
        self.scene.pixel_pitch.map_or(1.0, |p| crate::otf::pixel_mtf(p, frequency))
    }

    /// Why the last mean stopped before it converged (a work budget), if it did: its value is
    /// then not the mean MTF, and the caller reports this instead.
    pub fn over_budget(&self) -> Option<String> {
        self.engine.over_budget()
    }

    /// The spectral nodes (over all imaging orders) of the defocus lane's own rule, where the
    /// engine takes [`WavefrontDirection::Defocus`] on a finer spectral rule than the value's (the
    /// overlap engine on product integration: each panel's next nested Chebyshev–Lobatto
    /// rule, docs/physics.md "Gradients: the F-number and the focal length with Seidel terms");
    /// `None` where the lane takes the value's nodes.
    pub fn defocus_lane_nodes(&self) -> Option<usize> {
        self.engine.defocus_lane_nodes()
    }

    /// The spectral nodes (over all imaging orders) the engine sums at each frequency.
    pub fn spectral_nodes(&self) -> usize {
        self.engine.nodes().nodes.len()
    }

    /// Largest |W020| (m) among the spectral nodes that carry weight.
    pub fn max_defocus(&self) -> f64 {
        self.w020_max
    }

    /// Photoelectron-weighted fraction of the detected signal whose geometric blur radius
    /// `2|W020|/NA` exceeds `radius_m` (Fraunhofer validity, paper SI eq. S15), exact on every
    /// engine: in closed form on the closed-form engine
    /// ([`GaussianDefocus::fraction_defocused_beyond`](crate::GaussianDefocus::fraction_defocused_beyond));
    /// on the spectral rules, the wavelengths where each order's `|W020|` crosses
    /// `radius_m NA/2` are located in every spectral panel and the weight beyond them integrated
    /// by Gauss–Legendre on the sub-intervals (`fraunhofer::weight_defocused_beyond`), so the
    /// step never falls between nodes and the fraction is continuous in every parameter.
    pub fn fraction_blurred_beyond(&self, radius_m: f64) -> f64 {
        let limit = 0.5 * radius_m * self.scene.lens.numerical_aperture();
        self.engine.fraction_blurred_beyond(&self.scene, limit)
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A spectral node of `part` at `lambda` with `weight`, its defocus `W020 = (λ − focus) × 1000`
    /// (1 mm of defocus per m of wavelength) and nothing else.
    fn defocused_node(lambda: f64, weight: f64, focus: f64, part: usize) -> spectral::Node {
        spectral::Node {
            lambda,
            weight,
            w020: (lambda - focus) * 1e3,
            scale: 1.0,
            shift: [0.0; 2],
            shift_rate: None,
            iris_shift: [0.0; 2],
            iris_rate: 0.0,
            iris_tilt: [0.0; 2],
            table: None,
            radial: None,
            part,
            order: 0,
            efficiency: 1.0,
        }
    }

    /// `part_signal` as first written: every sample sorted, every node's sample and neighbours
    /// found by binary search, every density read from the spectrum (the reference its
    /// hinted searches and an engine's densities must reproduce to the bit).
    fn part_signal_reference(nodes: &Nodes, part: usize, detected: &Spectrum) -> Vec<(f64, f64)> {
        let mut samples: Vec<(f64, f64)> =
            nodes.samples.iter().filter(|s| s.2 == part && s.0.is_finite()).map(|s| (s.0, s.1)).collect();
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut lambdas: Vec<f64> = samples.iter().map(|s| s.0).collect();
        lambdas.dedup();
        let rule_weight = |lambda: f64| {
            let i = samples.partition_point(|s| s.0 < lambda);
            samples.get(i).filter(|s| s.0 == lambda).map_or(0.0, |s| s.1)
        };
        let mass_around = |lambda: f64| -> Option<f64> {
            if lambdas.len() < 3 {
                return None;
            }
            let i = lambdas.partition_point(|&l| l < lambda);
            if i >= lambdas.len() || lambdas[i] != lambda {
                return None;
            }
            let (lo, hi) = (i.saturating_sub(1), (i + 1).min(lambdas.len() - 1));
            let density = (lo..=hi).map(|k| detected.value(lambdas[k]).abs()).fold(0.0, f64::max);
            Some(density * 0.5 * (lambdas[hi] - lambdas[lo]))
        };
        nodes
            .nodes
            .iter()
            .filter(|n| n.part == part)
            .map(|n| {
                let w = rule_weight(n.lambda);
                let mass = match mass_around(n.lambda) {
                    Some(m) if w != 0.0 && m.is_finite() => m * (n.weight / w).abs(),
                    _ => n.weight.abs(),
                };
                (n.w020.abs(), mass)
            })
            .collect()
    }

    /// `part_signal`'s shortcuts (no sort of ordered samples, the searches tried at the last
    /// node's index first, an engine's densities) against the reference, to the bit: nodes out of
    /// order, two orders a wavelength, samples of two parts interleaved, a node with no sample,
    /// and the closed-form engine's nodes with their densities.
    #[test]
    fn part_signal_shortcuts_match_the_reference() {
        let filter = radiometry::Gaussian::from_range(800e-9, 50e-9, 1.0).unwrap();
        let detected = Spectrum::Gaussian(filter);
        let node = |lambda: f64, weight: f64, part: usize| defocused_node(lambda, weight, 790e-9, part);
        let lambdas: Vec<f64> = (0..40).map(|k| 740e-9 + 3e-9 * k as f64).collect();
        // in order, two orders per wavelength (the second weaker)
        let mut ordered = Nodes::default();
        for &l in &lambdas {
            ordered.samples.push((l, detected.value(l) * 3e-9, 0));
            ordered.nodes.push(node(l, detected.value(l) * 3e-9, 0));
            ordered.nodes.push(node(l, 0.1 * detected.value(l) * 3e-9, 0));
        }
        // out of order (a fixed permutation), two parts interleaved, one node off the samples
        let mut shuffled = Nodes::default();
        for k in 0..lambdas.len() {
            let l = lambdas[(k * 17) % lambdas.len()];
            shuffled.samples.push((l, detected.value(l) * 3e-9, k % 2));
            shuffled.nodes.push(node(l, detected.value(l) * 3e-9, k % 2));
        }
        shuffled.nodes.push(node(801.5e-9, 1e-12, 1));
        for (nodes, parts) in [(&ordered, 1), (&shuffled, 2)] {
            for part in 0..parts {
                let mut signal = Vec::new();
                part_signal(nodes, part, &detected, &mut signal);
                assert_eq!(signal, part_signal_reference(nodes, part, &detected), "part {part}");
            }
        }
        // the closed form's nodes carry the densities it read
        #[derive(Debug)]
        struct Affine;
        impl LensModel for Affine {
            fn f_number(&self) -> f64 {
                2.5
            }
            fn focal_length(&self) -> f64 {
                3.36e-3
            }
            fn orders(&self, lambda: f64, _: Field) -> Vec<crate::Order> {
                vec![crate::Order::new(
                    0.15,
                    crate::Pupil::Full,
                    crate::Wavefront::defocus(-0.0168e-3 + 0.021 * lambda),
                )]
            }
            fn affine_defocus(&self, _: Field) -> Option<crate::AffineDefocus> {
                Some(crate::AffineDefocus {
                    efficiency: 0.15,
                    transmission: 0.5,
                    w020_intercept_m: -0.0168e-3,
                    w020_slope: 0.021,
                })
            }
        }
        let lens = Affine;
        let poly = Polychromatic::with_settings(
            &lens,
            &detected,
            Field::ON_AXIS,
            1.0 / (2.0 * 5.2e-6),
            None,
            Settings { tolerance: 1e-7, ..Settings::default() },
        )
        .unwrap();
        assert_eq!(poly.engine(), Engine::ClosedForm);
        let nodes = poly.engine.nodes();
        assert!(nodes.densities.is_some());
        let mut signal = Vec::new();
        part_signal(nodes, spectral::WHOLE, &detected, &mut signal);
        assert_eq!(signal, part_signal_reference(nodes, spectral::WHOLE, &detected));
        // (that by the nodes in step with their samples, read by index; the nodes above go the
        // general way: two orders a wavelength, out of order, no densities)
        let mut in_step = Vec::new();
        assert!(part_signal_in_step(nodes, spectral::WHOLE, &mut in_step));
        assert_eq!(in_step, signal);
        assert!(!part_signal_in_step(nodes, 1, &mut in_step));
        for others in [&ordered, &shuffled] {
            assert!(!part_signal_in_step(others, 0, &mut in_step));
        }
        let mut without = nodes.clone();
        without.densities = None;
        assert!(!part_signal_in_step(&without, spectral::WHOLE, &mut in_step));
        assert_eq!(in_step, signal, "nothing appended where the nodes are not in step");
        // (and the signal integrals in one pass are each `detected_integral`'s sum, to the bit)
        let three = |l: f64| [1.0, l * 1e6, (l * 1e7).sin()];
        let together = poly.detected_integrals(three).unwrap();
        for (k, sum) in together.iter().enumerate() {
            assert_eq!(sum.to_bits(), poly.detected_integral(|l| three(l)[k]).unwrap().to_bits(), "{k}");
        }
        // a second engine of the same band reads the densities this thread kept: the same nodes
        let again = Polychromatic::with_settings(
            &lens,
            &detected,
            Field::ON_AXIS,
            1.0 / (2.0 * 5.2e-6),
            None,
            Settings { tolerance: 1e-7, ..Settings::default() },
        )
        .unwrap();
        assert_eq!(again.engine.nodes().samples, nodes.samples);
        assert_eq!(again.engine.nodes().densities, nodes.densities);
        // (which are the spectrum's values at the nodes, read directly)
        let mut direct = Vec::new();
        crate::quad::for_each_node(nodes.panels[0].lo, nodes.panels[0].hi, 8, |l, _| direct.push(detected.value(l)));
        assert_eq!(again.engine.nodes().densities.as_deref(), Some(&direct[..]));
    }

    /// `defocus_beyond` as first written: the pairs sorted (stable, largest |W020| first), their
    /// signal summed in that order.
    fn defocus_beyond_reference(mut signal: Vec<(f64, f64)>, relevant: f64) -> f64 {
        signal.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut beyond = 0.0;
        for (w020, mass) in signal {
            beyond += mass;
            if beyond > relevant {
                return w020;
            }
        }
        0.0
    }

    /// `defocus_beyond`'s merge of a falling and a rising run of |W020| takes the pairs in the
    /// stable sort's order: the same answer, to the bit, as the sort, at every threshold from
    /// none to all of the signal, on runs with equal |W020| within and across them (the equal
    /// ones in their order in `signal`), one run alone, and pairs in no such order (sorted).
    #[test]
    fn defocus_beyond_merges_as_the_sort_orders() {
        // a fixed pseudo-random sequence (a 64-bit linear congruential generator)
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut cases: Vec<Vec<(f64, f64)>> = vec![vec![], vec![(1.0, 0.5)], vec![(0.0, 1.0), (0.0, 2.0)]];
        for len in [2, 3, 8, 40, 128] {
            for _ in 0..30 {
                // |W020| of an affine defocus over ascending wavelengths, rounded to a coarse
                // grid so that equal ones occur, with the zero inside, before or after the band
                let zero = -0.5 + 2.0 * next();
                let step = 0.01 + next();
                let grid = [0.05, 0.25, 1.0][(3.0 * next()) as usize];
                let v: Vec<(f64, f64)> = (0..len)
                    .map(|k| {
                        let w = ((k as f64 / len as f64 - zero) * step).abs();
                        ((w / grid).round() * grid, next() * 10f64.powi(-(6.0 * next()) as i32))
                    })
                    .collect();
                cases.push(v.clone());
                // no such order
                let mut mixed = v;
                for k in 0..len {
                    mixed.swap(k, (next() * len as f64) as usize % len);
                }
                cases.push(mixed);
            }
        }
        for signal in cases {
            let total: f64 = signal.iter().map(|p| p.1).sum();
            let mut partial = vec![0.0, -1.0, total, 2.0 * total];
            let mut sum = 0.0;
            let mut sorted = signal.clone();
            sorted.sort_by(|a, b| b.0.total_cmp(&a.0));
            for p in &sorted {
                sum += p.1;
                partial.extend([sum, sum * (1.0 - 1e-15), sum * (1.0 + 1e-15)]);
            }
            for relevant in partial {
                assert_eq!(
                    defocus_beyond(signal.clone(), relevant).to_bits(),
                    defocus_beyond_reference(signal.clone(), relevant).to_bits(),
                    "{signal:?} at {relevant:e}"
                );
            }
        }
    }

    /// [`resolved_defocus`] reads a node's signal from the spectrum around it, not from its rule
    /// weight: a Gaussian band's tail whose product weights alternate at ±1e-6 of the total
    /// (where the spectrum holds far less) does not make the outermost node's defocus the one to
    /// resolve. Reference: the defocus at which the Gaussian's two tails beyond hold the relevant
    /// share, from erfc (σ = 10 nm, W020 = (λ − 800 nm) × 1000).
    #[test]
    fn resolved_defocus_follows_the_spectrum_not_the_rule_weights() {
        let filter = radiometry::Gaussian::from_range(800e-9, 2.0 * 2f64.sqrt() * 10e-9, 1.0).unwrap();
        let detected = Spectrum::Gaussian(filter);
        // nodes every 2 nm over ±70 nm; weights: the density × 2 nm within ±40 nm, ±1e-6 of the
        // total beyond (as a tail panel's interpolatory weights are)
        let lambdas: Vec<f64> = (-35..=35).map(|k| 800e-9 + 2e-9 * k as f64).collect();
        let total: f64 = lambdas.iter().map(|&l| detected.value(l) * 2e-9).sum();
        let mut nodes = Nodes::default();
        for (k, &lambda) in lambdas.iter().enumerate() {
            let w = if (lambda - 800e-9).abs() > 40e-9 {
                if k % 2 == 0 { 1e-6 * total } else { -1e-6 * total }
            } else {
                detected.value(lambda) * 2e-9
            };
            nodes.samples.push((lambda, w, 0));
            nodes.nodes.push(defocused_node(lambda, w, 800e-9, 0));
        }
        nodes.sum_weights();
        let mut signal = Vec::new();
        part_signal(&nodes, 0, &detected, &mut signal);
        let resolved = defocus_beyond(signal.clone(), 1e-8 * total);
        assert_eq!(signal, part_signal_reference(&nodes, 0, &detected));
        // read as weights, every node beyond 40 nm is relevant: the outermost defocus, 70 µm
        assert!(resolved < 0.9 * 70e-9 * 1e3, "{resolved:e}");
        // the Gaussian's two tails beyond x σ hold erfc(x/√2) of the total, 1e-8 at x = 5.73;
        // the envelope (the largest density at a node and its two neighbours) errs on the side of
        // more signal, by up to two node spacings
        let want = 5.73 * 10e-9 * 1e3;
        let spacing = 2e-9 * 1e3;
        assert!(resolved >= want - 0.5 * spacing && resolved <= want + 2.5 * spacing, "{resolved:e} vs {want:e}");
    }

    /// The exact engine's nodes read once per frequency (`exact::NodeCache`): off axis, where
    /// each order's lateral colour turns its OTF by its own phase along each azimuth, the mean
    /// along an azimuth on an engine that has read every other azimuth first (its nodes' values
    /// kept from them, then with their defocus lanes beside them) is the mean on a fresh engine,
    /// to the bit; and the OTF there is the nodes' sum read without the cache.
    #[test]
    fn the_exact_engines_node_cache_gives_the_values_to_the_bit() {
        // three channels in the interleaved lens's form at 3° along x
        #[derive(Debug)]
        struct Channels;
        impl LensModel for Channels {
            fn f_number(&self) -> f64 {
                2.5
            }
            fn focal_length(&self) -> f64 {
                3.36e-3
            }
            fn orders(&self, lambda: f64, field: Field) -> Vec<crate::Order> {
                let k = 3.36e-3 / (8.0 * 2.5 * 2.5);
                [750e-9, 800e-9, 850e-9]
                    .iter()
                    .map(|&channel| {
                        let shift = 3.36e-3 * field.x_rad.tan() * (channel / lambda - 1.0);
                        let wavefront = crate::Wavefront::defocus((1.0 - lambda / channel) * k).shifted(shift, 0.0);
                        crate::Order::new(0.05, crate::Pupil::Full, wavefront)
                    })
                    .collect()
            }
        }
        let detected = Spectrum::Gaussian(radiometry::Gaussian::from_range(800e-9, 50e-9, 1.0).unwrap());
        let field = Field::new(3f64.to_radians(), 0.0);
        let nyquist = 1.0 / (2.0 * 5.2e-6);
        let settings = Settings { tolerance: 1e-6, ..Settings::default() };
        let engine = || Polychromatic::with_settings(&Channels, &detected, field, nyquist, None, settings).unwrap();
        let shared = engine();
        assert_eq!(shared.engine(), Engine::Exact1d);
        assert!(shared.direction_dependent() && shared.engine.nodes().interpolated);
        let azimuths = [0.0, 0.4, 1.3, 2.9];
        for &azimuth in &azimuths {
            shared.mean_mtf_along(azimuth);
        }
        // the defocus lanes join the kept values (read again with them, the same values)
        let (lanes, _) = shared.mean_mtf_over_azimuth_and_aperture_lanes(0.0).unwrap();
        for &azimuth in &azimuths {
            let (again, _) = shared.mean_mtf_along(azimuth);
            let (fresh, _) = engine().mean_mtf_along(azimuth);
            assert_eq!(again.to_bits(), fresh.to_bits(), "azimuth {azimuth}");
        }
        assert_eq!(
            lanes.mean.to_bits(),
            engine().mean_mtf_over_azimuth_and_aperture_lanes(0.0).unwrap().0.mean.to_bits()
        );
        // the sum over the nodes without the cache
        let Some(quadrature) = shared.engine.exact_quadrature() else { panic!("the exact engine's quadrature") };
        for nu in [1e3, 2.7e4, 9.6e4] {
            for azimuth in azimuths {
                let kept = shared.otf_along(nu, azimuth);
                let read = exact::exact_along(&quadrature.scene, &quadrature.nodes, None, nu, azimuth);
                assert_eq!(
                    (kept.re.to_bits(), kept.im.to_bits()),
                    (read.re.to_bits(), read.im.to_bits()),
                    "{nu} {azimuth}"
                );
            }
        }
    }
}
