//! Spectra and the radiometric chain of the ASNR metric (paper "How good is your metalens?",
//! supporting information eq. S1–S9): from a measured relative spectrum and a power-meter
//! reading to target radiance, camera-plane irradiance, photoelectrons per pixel and the
//! shot-noise SNR₀ that multiplies the MTF area.
//!
//! ```
//! use radiometry::{camera_irradiance, photoelectrons, shot_noise_snr, Gaussian, Spectrum};
//! use radiometry::constants::{PLANCK, SPEED_OF_LIGHT};
//!
//! // Target spectral radiance: a Gaussian of spectral range 2√2σ = 50 nm at 800 nm, peak
//! // 1e7 W/(m² sr m) = 0.01 W/(m² sr nm).
//! let radiance = Gaussian::from_range(800e-9, 50e-9, 1e7)?;
//! // Camera plane (eq. S7), lens efficiency τ₁ = 0.15 and NA = 0.2 at every wavelength.
//! let peak = camera_irradiance(radiance.peak(), 0.15, 0.2);
//! let e_cam = Gaussian::new(radiance.center(), radiance.sigma(), peak)?;
//! // Photoelectrons (eq. S8): 5.2 µm pixel, 10 ms, QE 0.5.
//! let area = 5.2e-6 * 5.2e-6;
//! let n = photoelectrons(area, 10e-3, &Spectrum::Gaussian(e_cam), &Spectrum::Constant(0.5));
//! // Far from λ = 0 the integral of λ·G(λ) is center × peak σ√(2π).
//! let by_hand = area * 10e-3 * 0.5 / (PLANCK * SPEED_OF_LIGHT)
//!     * 800e-9 * e_cam.peak() * e_cam.sigma() * (2.0 * std::f64::consts::PI).sqrt();
//! assert!((n / by_hand - 1.0).abs() < 1e-12);
//! let snr0 = shot_noise_snr(n); // eq. S9: √N, here ≈ 67
//! assert!((snr0 - 67.0).abs() < 1.0);
//! # Ok::<(), radiometry::Error>(())
//! ```
//!
//! # Units and conventions
//! - SI throughout, `f64`: wavelengths in **metres** (never nm), spectral quantities per metre of
//!   wavelength (W/(m² m) = 1e-9 W/(m² nm)), radiance per steradian. Names or docs carry the unit.
//! - A [`Sampled`] table is piecewise linear between samples and exactly 0 outside; its integrals
//!   are exact for that model. Every [`Spectrum`] is 0 at λ ≤ 0.
//! - A Gaussian's "spectral range" is 2√2·σ (paper, Results), not the FWHM. A Gaussian is
//!   truncated at λ ≤ 0 and [`Spectrum::truncations`] reports any non-negligible loss.
//! - A [`Line`] is a narrow band the optics treats as one wavelength: integrals and quadrature
//!   nodes put its weight `peak × equivalent width` at its centre (every other factor evaluated
//!   there, [`Spectrum::as_line`]); as a function it is its equivalent band.
//! - [`normalize`] gives unit area per metre (eq. S1): values in 1/m.
//! - Constants are CODATA exact ([`constants`]).
//! - Constructors validate and return [`Error`]; evaluation and integration never fail
//!   afterwards. The eq. S2–S9 scalar functions do not validate: NaN in, NaN out.
//!
//! # Equations
//! [`normalize`] S1, [`fiber_irradiance`] S2, [`broadband_correction`] S3,
//! [`corrected_irradiance`] S4, [`absolute_spectral_irradiance`] S5, [`target_radiance`] S6,
//! [`camera_irradiance`] S7, [`photoelectrons_monochromatic`] and [`photoelectrons`] S8,
//! [`shot_noise_snr`] S9.

pub mod constants;

mod analytic;
mod chain;
mod error;
mod quadrature;
mod sampled;
mod spectrum;

pub use analytic::{Blackbody, Gaussian, Line, MIN_RELATIVE_SIGMA, TopHat};
pub use chain::{
    RadianceMeter, RadianceMeterSteps, absolute_spectral_irradiance, broadband_correction, camera_irradiance,
    corrected_irradiance, fiber_irradiance, normalize, photoelectrons, photoelectrons_monochromatic,
    photon_flux_per_watt, radiance_meter, shot_noise_snr, target_radiance,
};
pub use error::Error;
pub use sampled::Sampled;
pub use spectrum::{
    GAUSSIAN_WINDOW_SIGMAS, GaussianPolynomial, MAX_PIECE_DEGREE, MEMO_ENTRIES, MEMO_MIN_SAMPLES,
    NEGLIGIBLE_TRUNCATION, PiecewisePolynomial, QuadratureNode, Spectrum, Truncation, forget_remembered,
};
