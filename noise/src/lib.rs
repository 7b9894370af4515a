//! Noise, veiling glare and measured SNR for the ASNR toolkit (paper "How good is your
//! metalens?", eq. 2–4 and SI eq. S9–S14; EMVA 1288 Release 4.0 Linear for the camera model):
//! the SNR₀ that multiplies the MTF area, predicted for a camera or measured from frames.
//!
//! - **Predicted**: a validated [`Sensor`] (read noise, dark current, full well, conversion gain,
//!   ADC bits; [`Sensor::ideal`] is the paper's shot-noise limited detector) and [`budget`], the
//!   [`NoiseBudget`] of one exposure: shot, dark, read and quantization variances, the EMVA 1288
//!   SNR `μ_e/√(μ_e + μ_bg + μ_d + σ_r² + σ_q²/K²)`, and full-well saturation (clipped, flagged).
//! - **Glare**: [`veiling_glare`] (S10), [`modulation`] (S11), [`modulation_from_glare`] (S12) and
//!   [`glare_from_modulation`], [`buralli_morris_modulation`] `M0 = τ1/T` (S13), and
//!   [`snr_with_glare`] `S/√S_N` (S14), the same as a budget whose background is the light of the
//!   spurious orders.
//! - **Measured**: [`measured_snr`] and [`measured_snr_regions`] from stacks of frames:
//!   signal = white − black (eq. 2), σ_s² = σ_w² − σ_b² (eq. 3), SNR = signal/σ_s (eq. 4), and
//!   the glare-inclusive signal/σ_w (SI).
//! - **Camera characterization** (SI): [`photon_transfer_gain`] (EMVA 1288 conversion gain K)
//!   and [`log_slope`] (signal transfer slope ≈ 1 = linear, photon transfer slope ≈ 0.5 =
//!   shot-noise limited).
//!
//! # Example
//! ```
//! use noise::{budget, buralli_morris_modulation, glare_from_modulation, measured_snr, Sensor};
//!
//! // The paper's lens: τ1 = 0.15, T = 0.55 → M0 = 0.27, VG = 57 % (SI, "Analytic estimate of VG").
//! let m0 = buralli_morris_modulation(0.15, 0.55);
//! assert!((m0 - 0.2727).abs() < 1e-4);
//! assert!((glare_from_modulation(m0) - 0.5714).abs() < 1e-4);
//!
//! // 1000 e⁻ on a camera with σ_r = 5 e⁻, 100 e⁻/s dark current, K = 0.5 DN/e⁻, 12 bits, 0.1 s:
//! // variance 1000 + 10 + 25 + (1/12)/0.5² = 1035.33 e⁻², SNR = 31.08 (√1000 = 31.62 if ideal).
//! let camera = Sensor::new(5.0, 100.0, 20_000.0, 0.5, 12)?;
//! let b = budget(&camera, 1000.0, 0.0, 0.1)?;
//! assert!((b.snr - 31.0785).abs() < 1e-4 && !b.saturated);
//! // Glare: 2667 e⁻ of spurious-order light (T/τ1 − 1 = 2.67) on the ideal detector, eq. S14.
//! let glare = budget(&Sensor::ideal(), 1000.0, 1000.0 * (0.55 / 0.15 - 1.0), 0.1)?;
//! assert!((glare.snr - 16.514).abs() < 1e-3);
//!
//! // Measured (eq. 2–4): one white and one black pixel over three frames.
//! let m = measured_snr(&[10.0, 12.0, 14.0], &[1.0, 2.0, 3.0])?;
//! assert!((m.snr - 10.0 / 3f64.sqrt()).abs() < 1e-12); // signal 10, σ_s = √(4 − 1)
//! assert_eq!(m.snr_with_glare, 5.0); // σ_s = σ_w = 2
//! # Ok::<(), noise::Error>(())
//! ```
//!
//! # Units and conventions
//! - Predicted quantities in photoelectrons: charges in e⁻, variances in e⁻², time in s, dark
//!   current in e⁻/s, conversion gain K in DN/e⁻. Measured frames and transfer curves in grey
//!   levels (DN) and DN²; the SNR is dimensionless either way.
//! - Noise sources are independent: their variances add. Shot noise is Poissonian (variance =
//!   mean) for signal, background and dark electrons alike; quantization is σ_q² = 1/12 DN²,
//!   [`QUANTIZATION_VARIANCE_DN2`], referred to the input as σ_q²/K².
//! - "Background" is light that adds shot noise but no signal (veiling glare, spurious orders,
//!   stray light); the glare-free SNR of the paper's main analysis is a budget without it.
//! - Saturation is never silent: charges beyond [`Sensor::saturation_e`] are clipped and
//!   [`NoiseBudget::saturated`] is set.
//! - Measured standard deviations are temporal (per pixel, over frames) sample standard
//!   deviations with divisor n − 1, averaged over the pixels of a region as the paper did.
//! - Constructors and the measurement and fitting functions validate and return [`Error`];
//!   [`budget`] returns an [`Error`] for negative or non-finite inputs and for budgets too large to
//!   represent (never a non-finite number); the glare ratios (S10–S14) do not
//!   validate (NaN in, NaN out).

mod budget;
mod error;
mod glare;
mod measured;
mod transfer;

pub use budget::{NoiseBudget, QUANTIZATION_VARIANCE_DN2, Sensor, SnrPartials, budget};
pub use error::Error;
pub use glare::{
    buralli_morris_modulation, glare_from_modulation, modulation, modulation_from_glare, snr_with_glare, veiling_glare,
};
pub use measured::{MeasuredSnr, measured_snr, measured_snr_regions};
pub use transfer::{log_slope, photon_transfer_gain};
