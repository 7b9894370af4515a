//! Camera frames and what the paper measured from them.
//!
//! - [`frames`](mod@frames): stacks of grayscale frames (8- and 16-bit PNG and TIFF), read and checked alike;
//! - [`measure`](mod@measure): the SNR of a white and a black region over a stack (paper eq. 2–4, and the
//!   glare-inclusive variant of the SI, σ_s = σ_w), and with capped-black frames the veiling
//!   glare `VG = black/white` (SI eq. S10, levels above the capped black) and the zero-frequency
//!   modulation `M = (1 − VG)/(1 + VG)` (S11–S12);
//! - [`characterize`](mod@characterize): a camera from stacks at increasing illumination (SI
//!   Fig. S6–S8, EMVA 1288): STF and PTC log-log slopes with their standard errors, with and
//!   without the capped black subtracted, the conversion gain K, read noise and saturation.
//!
//! - [`nps`](mod@nps): the noise power spectrum of flat frames, temporal and spatial parts
//!   (EMVA 1288), and the measured NEQ and information capacity from it and an MTF;
//! - [`sfr`](mod@sfr): the MTF from slanted-edge images, the e-SFR of ISO 12233 (4× oversampled
//!   ESF, windowed LSF, the derivative's and the bins' transfer divided out), with standard errors.
//!
//! - [`target`](mod@target): test objects, a procedural USAF-1951 target or a user's PNG, and the
//!   measured modulation of a bar set;
//! - [`render`](mod@render): the forward model of the paper's Fig. 4 (object → photoelectrons →
//!   the scene's 2-D polychromatic OTF → veiling glare → sensor noise) and the Wiener restoration.
//!
//! The statistics are `noise::measured_snr_regions`: per pixel the temporal mean and sample
//! standard deviation, averaged over each region's pixels, as the paper did.

pub mod characterize;
pub mod error;
pub mod frames;
pub mod measure;
pub mod nps;
pub mod render;
pub mod sfr;
pub mod target;

pub use characterize::{Characterization, Fit, Level, characterize, fit_line, fit_line_weighted, level_of};
pub use error::Error;
pub use frames::{Frame, read_frame, read_stack, write_png};
pub use measure::{MeasuredAsnr, Measurement, Region, measure};
pub use nps::{MeasuredMetrics, Nps, measured_metrics, nps};
pub use render::{Rendering, Transfer, render, transfer};
pub use sfr::{EdgeSfr, Sfr, sfr};
pub use target::{Polarity, Target};
