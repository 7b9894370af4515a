//! The ASNR metric (paper eq. 1) and the scene it is evaluated on.
//!
//! `ASNR = SNR0 · (1/ν_N) ∫_0^{ν_N} MTF(ν) dν`: the zero-frequency SNR times the mean of the
//! polychromatic MTF up to the camera's Nyquist frequency `ν_N = 1/(2p)`. The integral form as
//! printed in the paper, `SNR0 · ∫_0^{ν_N} MTF dν` (cycles/mm), is reported too; for one camera
//! both rank designs identically.
//!
//! A [`Scene`] holds a lens (any [`optics::LensModel`]), the spectral radiance reaching it, a
//! camera, an exposure and options; [`evaluate`] returns an [`Evaluation`] with the ASNR and the
//! numbers behind it: photoelectrons (paper SI eq. S7–S8), SNR0 (S9), mean MTF, Fraunhofer
//! validity (S15) and veiling glare (S12–S13).
//!
//! # Example
//! ```
//! use std::sync::Arc;
//! use metric::{Camera, Options, Scene, evaluate};
//! use radiometry::{Gaussian, Spectrum};
//! # use optics::{Field, LensModel, Order, Pupil, Wavefront};
//! # #[derive(Debug)] struct Ideal;
//! # impl LensModel for Ideal {
//! #     fn f_number(&self) -> f64 { 2.5 }
//! #     fn focal_length(&self) -> f64 { 3.36e-3 }
//! #     fn orders(&self, _: f64, _: Field) -> Vec<Order> {
//! #         vec![Order::new(0.15, Pupil::Full, Wavefront::default())]
//! #     }
//! # }
//! // a flat 0.025 W/(m² sr nm) source behind a Gaussian filter, 800 nm, 50 nm range
//! let filter = Gaussian::from_range(800e-9, 50e-9, 1.0).unwrap();
//! let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
//! let camera = Camera::new(5.2e-6, Spectrum::Constant(0.2), false).unwrap();
//! let scene = Scene::new(Arc::new(Ideal), radiance, camera, 1.23e-3, Options::default()).unwrap();
//! let result = evaluate(&scene).unwrap();
//! // a diffraction-limited lens: the mean MTF up to Nyquist is high, SNR0 = √N
//! assert!(result.mean_mtf > 0.8 && result.mean_mtf < 1.0);
//! assert!((result.snr0 - result.photoelectrons.sqrt()).abs() < 1e-9);
//! ```
//!
//! Units: SI inside (m, s, W); reports use nm, mm and cycles/mm as their field names say.

mod evaluate;
mod gradient;
mod illumination;
mod metrics;
mod scene;

pub use evaluate::{
    Evaluation, FieldCurve, FieldPoint, Fraunhofer, FrequencyRange, Glare, MAX_DEFOCUS_WAVES, MtfCurve, NoiseReport,
    Numerics, detected_spectrum, evaluate, mtf_at, mtf_curve,
};
pub use gradient::{
    Gradient, Parameter, aperture_mean_mtf_partials, channel_efficiency_gradient, channel_gradients,
    channel_wavelength_gradient, design_wavelength_mean_mtf_partial, gradient, library_bias_mean_mtf_partials,
    zernike_m0_place, zone_key_gradient,
};
pub use illumination::{IlluminationReport, RelativeIllumination};
pub use metrics::{
    Detectability, DiskTask, IdealLens, Metrics, MetricsOptions, NeqCurve, ObjectSpectrum, Quadrature, SquareMetrics,
    Symmetry, jinc, metrics, power_law_mean, square_metrics,
};
/// The Seidel terms a [`Parameter::Seidel`] names.
pub use optics::{ATOM_PHASE_ERROR, ATOM_TRANSMISSION_ERROR, SeidelTerm, ZoneKey};
pub use scene::{Camera, GlareMode, MetricForm, Options, Scene};

/// What can go wrong building or evaluating a scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A scene parameter is outside its physical range.
    #[error("{name} = {value} is out of range: expected {expected}")]
    OutOfRange {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// The scene detects no light: the radiance and the quantum efficiency do not overlap, or
    /// their product is zero.
    #[error("no detected signal: {reason}")]
    NoLight {
        /// Which spectra, and their ranges in nm.
        reason: String,
    },
    /// A number computed from the scene exceeds the largest finite number (about 1.8e308).
    #[error("{quantity} overflows: {detail}")]
    Overflow {
        /// What overflowed.
        quantity: &'static str,
        /// The values that drive it and the scene keys that set them.
        detail: String,
    },
    /// The defocus is beyond what the MTF integration can resolve.
    #[error(
        "the defocus reaches {waves:.3e} waves (W020 = {w020_m:.3e} m, at the mean wavelength {wavelength_nm:.1} nm): beyond the \
         {limit:e} waves the MTF integration resolves (the blur is far beyond the Fraunhofer threshold, paper SI \
         eq. S15); reduce lens.focal_length_mm, the distance of the spectrum from lens.design_wavelength_nm, or \
         the spectral range; for a lens given as data, check its profile (lens.binary2 with lens.norm_radius_mm, \
         lens.phase_csv, the layout)"
    )]
    Defocus {
        /// Largest defocus, waves.
        waves: f64,
        /// Its W020, m.
        w020_m: f64,
        /// The mean detected wavelength the waves are counted at, nm.
        wavelength_nm: f64,
        /// The limit, waves.
        limit: f64,
    },
    /// The defocus phase at the frequency limit is beyond the work budget.
    #[error(
        "the defocus phase at the frequency limit reaches {phase:.3e} rad (8π F# ν W020, W020 = {w020_m:.3e} m): \
         beyond the {limit:e} rad the MTF integration does in seconds (its work grows as the square of that \
         phase; the blur is far beyond the Fraunhofer threshold, paper SI eq. S15); reduce \
         lens.focal_length_mm, the distance of the spectrum from lens.design_wavelength_nm, the spectral \
         range, or camera.pixel_pitch_um's Nyquist frequency; for a lens given as data, check its profile \
         (lens.binary2 with lens.norm_radius_mm, lens.phase_csv, the layout)"
    )]
    DefocusPhase {
        /// `8π F# ν_N |W020|`, rad.
        phase: f64,
        /// The largest |W020|, m.
        w020_m: f64,
        /// The budget, rad.
        limit: f64,
    },
    /// An engine stopped at its work budget before the mean MTF converged.
    #[error(
        "{reason}; reduce lens.focal_length_mm, the distance of the spectrum from lens.design_wavelength_nm or \
         the spectral range"
    )]
    WorkBudget {
        /// What the engine said.
        reason: String,
    },
    /// The spectral rule's work is beyond the budget.
    #[error(
        "the spectral rule needs {nodes} wavelength nodes at a defocus phase of {phase:.3e} rad at the frequency \
         limit: about {seconds:.0} s of work, beyond the 5 s budget; reduce lens.focal_length_mm, the distance of \
         the spectrum from lens.design_wavelength_nm or the spectral range, loosen options.tolerance, or (with \
         options.spectral_rule = \"panels\", which takes nodes at every table sample) use the default \
         product integration"
    )]
    SpectralWork {
        /// Spectral nodes.
        nodes: usize,
        /// `8π F# ν_N |W020|`, rad.
        phase: f64,
        /// The estimated time, s.
        seconds: f64,
    },
    /// The value is not differentiable in a parameter at this scene (a kink, or a dependence the
    /// gradient does not follow yet).
    #[error("the ASNR is not differentiable with respect to {parameter} here: {reason}")]
    NotDifferentiable {
        /// What the derivative was asked against.
        parameter: &'static str,
        /// Why not.
        reason: String,
    },
    /// The noise budget could not be formed.
    #[error(transparent)]
    Noise(#[from] noise::Error),
    /// The optics could not be evaluated.
    #[error(transparent)]
    Optics(#[from] optics::Error),
    /// A spectrum could not be built.
    #[error(transparent)]
    Radiometry(#[from] radiometry::Error),
}
