//! The gradient of the ASNR, mean MTF, SNR0 and photoelectrons with respect to scene quantities
//! (docs/physics.md, "Gradients"), from the evaluation's own numbers: no finite differences.
//!
//! `ASNR = SNR0 · G` with `G` the mean MTF (or its mean over a non-white noise spectrum, or the
//! MTF integral for `form = "integral"`), so `∂ASNR = ∂SNR0 · G + SNR0 · ∂G`. The radiometric,
//! exposure and sensor quantities change `N`, the stray light and the noise terms only:
//! `∂SNR0` follows from [`noise::NoiseBudget::snr_partials`], and `∂G = 0` because the OTF's
//! spectral weights are normalized (a factor constant in λ leaves them as they are). The pixel
//! pitch also moves the Nyquist frequency: `M̄ = (1/ν_N) ∫_0^{ν_N} |O| dν`, so by Leibniz'
//! rule `∂M̄/∂ν_N = (MTF(ν_N) − M̄)/ν_N`, one OTF value at ν_N.

use noise::SnrPartials;

use crate::evaluate::{Evaluation, evaluate_field_with, mtf_at};
use crate::{Error, GlareMode, MetricForm, Scene};

/// A scene quantity the ASNR can be differentiated against, and what each derivative is taken
/// with respect to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// A factor constant in wavelength on the radiance before the lens (a flat source's radiance,
    /// a blackbody's scale, a constant quantum efficiency, the spectrum's peak transmission): the
    /// signal and the stray light are proportional to it. Derivative per relative change,
    /// `∂/∂ln s`.
    SignalScale,
    /// The exposure time t: signal, stray light and dark charge are proportional to it. `∂/∂ln t`.
    Exposure,
    /// A constant imaging efficiency τ1: the signal is proportional to it, the transmitted light
    /// `N_T` (paper SI eq. S14) is not. `∂/∂ln τ1`.
    Efficiency,
    /// A constant total transmission T: `N_T` is proportional to it (it matters only with
    /// `glare = "included"`). `∂/∂ln T`.
    Transmission,
    /// The read noise σ_r: `∂/∂σ_r`, per e⁻ rms.
    ReadNoise,
    /// The dark current: `∂/∂(dark current)`, per e⁻/s.
    DarkCurrent,
    /// The conversion gain K (quantization noise `(1/12)/K²`): `∂/∂K`, per DN/e⁻.
    Gain,
    /// The pixel pitch p: `N ∝ p²` and `ν_N = 1/(2p)`. `∂/∂ln p`. Refused with the pixel MTF
    /// (its sinc moves with p inside the integral) or a non-white noise spectrum.
    PixelPitch,
    /// The lens's Binary 2 coefficient `A_{i+1}` (`lens.binary2[i]`, radians): it moves the
    /// wavefront of every order (`optics::LensModel::binary2_directions`), so the OTF, not the
    /// photon count. `∂/∂A`, per radian. On axis, on the radial engine, without the pixel MTF or
    /// a noise spectrum.
    Binary2(usize),
}

impl Parameter {
    /// What the derivative is taken against, for messages and docs.
    pub fn describe(self) -> &'static str {
        match self {
            Parameter::SignalScale => "a factor on the detected radiance",
            Parameter::Exposure => "the exposure time",
            Parameter::Efficiency => "a constant imaging efficiency",
            Parameter::Transmission => "a constant total transmission",
            Parameter::ReadNoise => "the read noise",
            Parameter::DarkCurrent => "the dark current",
            Parameter::Gain => "the conversion gain",
            Parameter::PixelPitch => "the pixel pitch",
            Parameter::Binary2(_) => "a Binary 2 coefficient of the lens's phase",
        }
    }
}

/// The evaluation and its derivatives, one entry per [`Parameter`] asked, in their order (each
/// taken as its parameter says: `∂/∂ln` for the scales, per unit for the noise terms).
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// The evaluation the derivatives are taken at ([`crate::evaluate`]'s numbers).
    pub evaluation: Evaluation,
    /// `∂ASNR` (in the scene's form).
    pub asnr: Vec<f64>,
    /// `∂` mean MTF.
    pub mean_mtf: Vec<f64>,
    /// `∂SNR0`.
    pub snr0: Vec<f64>,
    /// `∂N`, photoelectrons.
    pub photoelectrons: Vec<f64>,
}

/// The evaluation of `scene` ([`crate::evaluate`]) and the derivatives of its ASNR, mean MTF,
/// SNR0 and photoelectrons with respect to each of `parameters`. Over a field-of-view average,
/// the weighted mean of each point's derivatives, as the value is the weighted mean of the
/// points'.
///
/// # Errors
/// The evaluation's errors, and [`Error::NotDifferentiable`] where the value is not smooth in a
/// parameter there: a saturated pixel (the charges are clipped), the pixel pitch with the pixel
/// MTF or a noise spectrum, the conversion gain without an ADC.
pub fn gradient(scene: &Scene, parameters: &[Parameter]) -> Result<Gradient, Error> {
    let binary2 = parameters.iter().any(|p| matches!(p, Parameter::Binary2(_)));
    if scene.fields().is_empty() {
        // one pass: the evaluation and the Binary 2 derivatives of its mean MTF together
        let (evaluation, d_binary2) = evaluate_field_with(scene, binary2)?;
        let point = point_gradient(scene, &evaluation, parameters, d_binary2)?;
        return Ok(Gradient {
            evaluation,
            asnr: point.asnr,
            mean_mtf: point.mean_mtf,
            snr0: point.snr0,
            photoelectrons: point.photoelectrons,
        });
    }
    let evaluation = crate::evaluate(scene)?;
    // the weighted mean of the points' derivatives, with evaluate's relative weights
    let largest = scene.fields().iter().map(|f| f.1).fold(0.0, f64::max);
    let relative: Vec<f64> = scene.fields().iter().map(|f| f.1 / largest).collect();
    let total: f64 = relative.iter().sum();
    let zeros = vec![0.0; parameters.len()];
    let mut sum =
        PointGradient { asnr: zeros.clone(), mean_mtf: zeros.clone(), snr0: zeros.clone(), photoelectrons: zeros };
    for (&(field, _), w) in scene.fields().iter().zip(&relative) {
        let single = scene.single_field(field);
        let (e, d_binary2) = evaluate_field_with(&single, binary2)?;
        let point = point_gradient(&single, &e, parameters, d_binary2)?;
        for (s, p) in [
            (&mut sum.asnr, &point.asnr),
            (&mut sum.mean_mtf, &point.mean_mtf),
            (&mut sum.snr0, &point.snr0),
            (&mut sum.photoelectrons, &point.photoelectrons),
        ] {
            for (s, p) in s.iter_mut().zip(p) {
                *s += w * p / total;
            }
        }
    }
    Ok(Gradient {
        evaluation,
        asnr: sum.asnr,
        mean_mtf: sum.mean_mtf,
        snr0: sum.snr0,
        photoelectrons: sum.photoelectrons,
    })
}

struct PointGradient {
    asnr: Vec<f64>,
    mean_mtf: Vec<f64>,
    snr0: Vec<f64>,
    photoelectrons: Vec<f64>,
}

/// The derivatives at one field point whose evaluation is `e`; `d_binary2` the mean MTF's
/// Binary 2 derivatives computed with it, where they were.
fn point_gradient(
    scene: &Scene,
    e: &Evaluation,
    parameters: &[Parameter],
    d_binary2: Option<Vec<f64>>,
) -> Result<PointGradient, Error> {
    let camera = scene.camera();
    let sensor = camera.sensor();
    let exposure = scene.exposure();
    let n = e.photoelectrons;
    let transmitted = e.transmitted_photoelectrons;
    // the budget exactly as evaluate forms it
    let background = match scene.options().glare {
        GlareMode::FirstOrder => 0.0,
        GlareMode::Included => (transmitted - n).max(0.0),
    };
    let budget = noise::budget(sensor, n, background, exposure)?;
    let not_smooth =
        |parameter: Parameter, reason: String| Error::NotDifferentiable { parameter: parameter.describe(), reason };
    let partials: Option<SnrPartials> = budget.snr_partials();
    // G = ASNR / SNR0: the mean MTF (or its mean over the noise spectrum, or the MTF integral)
    let g = e.asnr / e.snr0;
    let mut out = PointGradient {
        asnr: Vec::with_capacity(parameters.len()),
        mean_mtf: Vec::with_capacity(parameters.len()),
        snr0: Vec::with_capacity(parameters.len()),
        photoelectrons: Vec::with_capacity(parameters.len()),
    };
    // the stray light B = max(N_T − N, 0) with glare included: its derivative where it is > 0
    let stray = matches!(scene.options().glare, GlareMode::Included) && background > 0.0;
    let binary2 = match parameters.iter().find(|p| matches!(p, Parameter::Binary2(_))) {
        Some(&p) => Some(binary2_mean_mtf(scene, p, d_binary2)?),
        None => None,
    };
    for &p in parameters {
        let Some(partials) = partials else {
            return Err(not_smooth(
                p,
                if budget.saturated {
                    "the pixel saturates: the charges are clipped at the well, where the SNR has a kink".to_owned()
                } else {
                    "there is no signal".to_owned()
                },
            ));
        };
        // ∂N, ∂B, ∂(dark charge), ∂σ_r², ∂(σ_q²/K²), and ∂G
        let (d_n, d_b, d_dark, d_read, d_quant, d_g, d_mtf) = match p {
            Parameter::SignalScale => (n, background, 0.0, 0.0, 0.0, 0.0, 0.0),
            Parameter::Exposure => (n, background, budget.dark_e, 0.0, 0.0, 0.0, 0.0),
            Parameter::Efficiency => (n, if stray { -n } else { 0.0 }, 0.0, 0.0, 0.0, 0.0, 0.0),
            Parameter::Transmission => (0.0, if stray { transmitted } else { 0.0 }, 0.0, 0.0, 0.0, 0.0, 0.0),
            Parameter::ReadNoise => (0.0, 0.0, 0.0, 2.0 * sensor.read_noise_e(), 0.0, 0.0, 0.0),
            Parameter::DarkCurrent => (0.0, 0.0, exposure, 0.0, 0.0, 0.0, 0.0),
            Parameter::Gain => {
                let Some(k) = sensor.gain_dn_per_e() else {
                    return Err(not_smooth(p, "the camera has no ADC (camera.gain_dn_per_e not given)".to_owned()));
                };
                (0.0, 0.0, 0.0, 0.0, -2.0 * budget.quantization_variance_e2 / k, 0.0, 0.0)
            }
            Parameter::PixelPitch => {
                if camera.pixel_mtf() {
                    return Err(not_smooth(
                        p,
                        "with camera.pixel_mtf = true the pixel's sinc moves with the pitch inside the MTF integral, \
                         which is not differentiated here yet"
                            .to_owned(),
                    ));
                }
                if camera.noise_spectrum().is_some() {
                    return Err(not_smooth(
                        p,
                        "with camera.noise_spectrum the noise moves with the Nyquist frequency inside the integral, \
                         which is not differentiated here yet"
                            .to_owned(),
                    ));
                }
                // ν_N = 1/(2p): ∂ν_N/∂ln p = −ν_N. Leibniz: ∂M̄/∂ν_N = (MTF(ν_N) − M̄)/ν_N, so
                // ∂M̄/∂ln p = M̄ − MTF(ν_N); the integral I = M̄ ν_N: ∂I/∂ln p = −ν_N MTF(ν_N)
                let edge = mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
                let d_mtf = e.mean_mtf - edge;
                let d_g = match scene.options().form {
                    MetricForm::Mean => d_mtf,
                    MetricForm::Integral => -e.nyquist_cyc_per_mm * edge,
                };
                (2.0 * n, 2.0 * background, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::Binary2(i) => {
                let all = binary2.as_deref().unwrap_or(&[]);
                let Some(&d_mtf) = all.get(i) else {
                    return Err(not_smooth(p, format!("the lens has {} Binary 2 coefficients (0-based)", all.len())));
                };
                let d_g = match scene.options().form {
                    MetricForm::Mean => d_mtf,
                    MetricForm::Integral => e.nyquist_cyc_per_mm * d_mtf,
                };
                (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
        };
        let d_snr0 = partials.signal * d_n + partials.variance * (d_b + d_dark + d_read + d_quant);
        out.photoelectrons.push(d_n);
        out.snr0.push(d_snr0);
        out.mean_mtf.push(d_mtf);
        out.asnr.push(d_snr0 * g + e.snr0 * d_g);
    }
    Ok(out)
}

/// `∂M̄/∂A_j` for every Binary 2 coefficient of the lens, as the evaluation computed them
/// (`d_binary2`: [`optics::Polychromatic::mean_mtf_and_binary2_gradient`], the radial engine's
/// OTF derivatives on the value's own spectral levels and frequency panels), or why there are
/// none.
fn binary2_mean_mtf(scene: &Scene, p: Parameter, d_binary2: Option<Vec<f64>>) -> Result<Vec<f64>, Error> {
    let not_smooth = |reason: &str| Error::NotDifferentiable { parameter: p.describe(), reason: reason.to_owned() };
    let camera = scene.camera();
    if camera.pixel_mtf() {
        return Err(not_smooth(
            "with camera.pixel_mtf = true the Binary 2 gradient is not computed here yet (set camera.pixel_mtf = false)",
        ));
    }
    if camera.noise_spectrum().is_some() {
        return Err(not_smooth("with camera.noise_spectrum the Binary 2 gradient is not computed here yet"));
    }
    d_binary2.ok_or_else(|| {
        not_smooth(
            "the Binary 2 gradient is computed on axis for a lens whose every order is a radially symmetric pupil \
             on the exact per-frequency engine (a band, not a line); this scene's lens, spectrum or field is not",
        )
    })
}
