//! Optics for the ASNR toolkit: transfer functions of lenses, monochromatic and polychromatic,
//! and the [`LensModel`] trait that lens families implement.
//!
//! # What is here
//! - [`defocus_otf`]: the exact OTF of a centred circular pupil with defocus (a 1-D integral,
//!   composite Gauss–Legendre with panel counts that grow with defocus), [`mtf_diffraction_limited`],
//!   [`pixel_mtf`].
//! - [`Polychromatic`]: the signed polychromatic OTF with photoelectron weights, its modulus, and
//!   its mean up to the Nyquist frequency (the quantity in paper eq. 1).
//! - [`LensModel`] with its vocabulary ([`Order`], [`Pupil`], [`Wavefront`], [`Field`]).
//! - [`fft`]: the general-pupil engine — sampled apertures (decentred, annular, sector, any mask;
//!   edge pixels weighted by their exact area), Seidel and Zernike wavefronts, the complex 2-D OTF
//!   by FFT with reusable plans and only `Q ≥ 1 + s_max` padding, slices and azimuthal averages.
//! - [`fraunhofer`]: the validity check of paper SI eq. S15.
//! - [`reference`](mod@reference): slow, independent references the fast paths are tested against.
//!
//! # Conventions
//! SI units everywhere (wavelengths and lengths in m, spatial frequencies in cycles/m).
//! `s = ν/ν_c(λ)` with `ν_c = 1/(λ F#)`; defocus `w = W020/λ` waves at the pupil edge.
//! OTFs are normalized to 1 at zero frequency; a polychromatic OTF is the weighted sum of the
//! signed monochromatic OTFs, each at its own `s` (docs/physics.md, "Polychromatic OTF").
//!
//! # Example
//! ```
//! use optics::{defocus_otf, mtf_diffraction_limited};
//! // Test vector of docs/physics.md ("Test vectors and identities"): OTF(s = 0.1, w = 0.5 waves) = 0.74209
//! assert!((defocus_otf(0.1, 0.5) - 0.74209).abs() < 1e-5);
//! // no defocus: the diffraction-limited MTF
//! assert!((defocus_otf(0.3, 0.0) - mtf_diffraction_limited(0.3)).abs() < 1e-15);
//! ```

mod closed;
mod complex4;
mod error;
mod expo;
pub mod faddeeva;
pub mod fft;
pub mod fraunhofer;
mod lens;
pub mod map;
mod otf;
mod plane;
mod poly;
pub mod quad;
pub mod radial;
pub mod reference;
mod table;
#[cfg(feature = "testkit")]
pub mod testkit;

pub use closed::GaussianDefocus;
pub use error::Error;
pub use lens::{
    ATOM_PHASE_ERROR, ATOM_TRANSMISSION_ERROR, AffineDefocus, ApertureDirections, DefocusRates, FactoredEfficiency,
    FactoredPart, Field, LensModel, Order, OrderDerivatives, OrderWavelengthRates, Pupil, Wavefront,
    WavelengthDirections, Zone, ZoneKey, ZoneRate, ZoneRates, round_for_display,
};
pub use otf::{
    ASYMPTOTIC_MIN_PHASE, BESSEL_SERIES_MIN_A, cutoff_frequency, defocus_otf, defocus_otf_and_log_derivative,
    defocus_otf_asymptotic, defocus_otf_asymptotic_and_log_derivative, defocus_otf_bessel, defocus_otf_log_derivative,
    defocus_otf_many, defocus_otf_many_and_log_derivative_within, defocus_otf_many_within, defocus_otf_panels,
    defocus_otf_quadrature, mtf_diffraction_limited, mtf_diffraction_limited_mean, pixel_mtf,
};
pub use plane::{PLANE_TAU, PLANE_WIDTH, SampledPlane};
pub use poly::{
    AZIMUTH_SHARE, AzimuthalMean, DEFAULT_FFT_TOLERANCE, DEFAULT_PUPIL_SAMPLES, DEFAULT_TOLERANCE, DefocusDerivative,
    DesignAndEdgeLanes, Engine, FFT_MEMORY_BUDGET, FIRST_AZIMUTHS, GAUSSIAN_HALF_WIDTH_SIGMAS, MAX_AZIMUTHS,
    NoiseShape, Part, Polychromatic, SeidelTerm, Settings, SharedGrids, SpectralRule, WavefrontDirection, Work,
    forget_remembered, highest_cutoff, monochromatic_mtf,
};
pub use table::{OtfTable, SampledLine, TABLE_ZERO_FREQUENCY_TOLERANCE};
