//! The noise of one exposure of one pixel: a validated [`Sensor`] and its [`NoiseBudget`].
//!
//! The model is EMVA 1288 Release 4.0 Linear, §2.1–2.4 (linear signal model, noise model, SNR,
//! saturation), written in photoelectrons: every variance is in e⁻², the quantization noise of
//! the ADC referred to the input by dividing by K².

use crate::error::{Error, check, non_negative, positive};

/// Variance of an ideal uniform quantizer, σ_q² = 1/12 DN² (EMVA 1288 Release 4.0 Linear, §2.2).
pub const QUANTIZATION_VARIANCE_DN2: f64 = 1.0 / 12.0;

/// The largest value whose square is finite (about 1.3e154): read noises and inverse gains
/// beyond it have no finite variance.
const MAX_SQUARABLE: f64 = 1.3e154;

/// The camera's temporal noise sources and limits (EMVA 1288 Release 4.0 Linear, §2.2 and §2.4):
/// read noise σ_r (e⁻ rms), dark current (e⁻/s), full-well capacity (e⁻), and, when the camera
/// digitizes, the conversion gain K (DN/e⁻) and the ADC resolution (bits).
///
/// Built by [`Sensor::new`] (digitizing camera), [`Sensor::without_adc`] (photoelectron counts
/// read without quantization) or [`Sensor::ideal`] (shot-noise limited, paper SI eq. S9).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensor {
    read_noise_e: f64,
    dark_current_e_per_s: f64,
    full_well_e: f64,
    adc: Option<Adc>,
}

/// Conversion gain and resolution of the analogue-to-digital conversion.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Adc {
    gain_dn_per_e: f64,
    bits: u32,
    black_level_dn: f64,
}

impl Sensor {
    /// A digitizing camera: read noise `read_noise_e` (e⁻ rms, finite ≥ 0), dark current
    /// `dark_current_e_per_s` (e⁻/s, finite ≥ 0), full-well capacity `full_well_e` (e⁻, > 0;
    /// `f64::INFINITY` for no well limit), conversion gain `gain_dn_per_e` K (DN/e⁻, finite > 0)
    /// and an ADC of `adc_bits` bits (1 to 32), whose largest output 2^bits − 1 DN also limits
    /// the signal (see [`Sensor::saturation_e`]).
    pub fn new(
        read_noise_e: f64,
        dark_current_e_per_s: f64,
        full_well_e: f64,
        gain_dn_per_e: f64,
        adc_bits: u32,
    ) -> Result<Sensor, Error> {
        let mut sensor = Sensor::without_adc(read_noise_e, dark_current_e_per_s, full_well_e)?;
        positive("gain", gain_dn_per_e, "DN/e⁻")?;
        // quantization noise referred to the input is (1/12)/K²: finite for K ≥ 1/MAX_SQUARABLE
        check(
            "gain",
            gain_dn_per_e,
            gain_dn_per_e >= 1.0 / MAX_SQUARABLE,
            format!("at least {:e} DN/e⁻ (the quantization variance (1/12)/K² must be finite)", 1.0 / MAX_SQUARABLE),
        )?;
        check("adc_bits", f64::from(adc_bits), (1..=32).contains(&adc_bits), "an integer from 1 to 32 bits")?;
        sensor.adc = Some(Adc { gain_dn_per_e, bits: adc_bits, black_level_dn: 0.0 });
        Ok(sensor)
    }

    /// A sensor read without quantization (photoelectron counts, no ADC): read noise
    /// `read_noise_e` (e⁻ rms, finite ≥ 0), dark current `dark_current_e_per_s` (e⁻/s, finite
    /// ≥ 0) and full-well capacity `full_well_e` (e⁻, > 0; `f64::INFINITY` for no limit).
    pub fn without_adc(read_noise_e: f64, dark_current_e_per_s: f64, full_well_e: f64) -> Result<Sensor, Error> {
        non_negative("read_noise", read_noise_e, "e⁻ rms")?;
        // the budget adds σ_r²: a read noise whose square overflows has no finite variance
        check(
            "read_noise",
            read_noise_e,
            read_noise_e < MAX_SQUARABLE,
            format!("below {MAX_SQUARABLE:e} e⁻ rms (its square, the read variance σ_r², must be finite)"),
        )?;
        non_negative("dark_current", dark_current_e_per_s, "e⁻/s")?;
        check("full_well", full_well_e, full_well_e > 0.0, "> 0 e⁻ (inf for no limit)")?;
        Ok(Sensor { read_noise_e, dark_current_e_per_s, full_well_e, adc: None })
    }

    /// The shot-noise limited detector of the paper's theory (SI eq. S9, SNR = √N): no read
    /// noise, no dark current, an infinite well, no quantization.
    pub fn ideal() -> Sensor {
        Sensor { read_noise_e: 0.0, dark_current_e_per_s: 0.0, full_well_e: f64::INFINITY, adc: None }
    }

    /// The same camera with a black level (dark offset) of `black_level_dn` DN: the ADC reads
    /// `round(K e + black_level_dn)`, clipped to `[0, 2^bits − 1]` (EMVA 1288 Release 4.0 Linear,
    /// §2.2: μ_y = K (μ_e + μ_d) + μ_y.dark offset). With an offset of a few σ of the dark
    /// noise, dark frames are not clipped at 0 DN and their variance is the camera's dark noise;
    /// it cancels in every difference (eq. 2, the photon transfer) and lowers the ADC's range
    /// above it ([`Sensor::saturation_e`]).
    ///
    /// # Errors
    /// No ADC ([`Sensor::without_adc`], [`Sensor::ideal`]), or an offset that is not finite, below
    /// 0 or at least the largest output 2^bits − 1 DN.
    pub fn with_black_level(mut self, black_level_dn: f64) -> Result<Sensor, Error> {
        let Some(adc) = self.adc.as_mut() else {
            return Err(Error::InvalidParameter {
                name: "black_level",
                value: black_level_dn,
                accepted: "a level only with an ADC (a conversion gain and bits)".to_owned(),
            });
        };
        let top = ((1_u64 << adc.bits) - 1) as f64;
        check(
            "black_level",
            black_level_dn,
            black_level_dn.is_finite() && (0.0..top).contains(&black_level_dn),
            format!("a level ≥ 0 DN and below the ADC's largest output {top} DN"),
        )?;
        adc.black_level_dn = black_level_dn;
        Ok(self)
    }

    /// The black level (dark offset), DN; 0 without an ADC or when none was set.
    pub fn black_level_dn(&self) -> f64 {
        self.adc.map_or(0.0, |adc| adc.black_level_dn)
    }

    /// Read noise σ_r, e⁻ rms.
    pub fn read_noise_e(&self) -> f64 {
        self.read_noise_e
    }

    /// Dark current, e⁻/s.
    pub fn dark_current_e_per_s(&self) -> f64 {
        self.dark_current_e_per_s
    }

    /// Full-well capacity, e⁻ (`f64::INFINITY` when unlimited).
    pub fn full_well_e(&self) -> f64 {
        self.full_well_e
    }

    /// Conversion gain K, DN/e⁻, or `None` without an ADC.
    pub fn gain_dn_per_e(&self) -> Option<f64> {
        self.adc.map(|adc| adc.gain_dn_per_e)
    }

    /// ADC resolution, bits, or `None` without an ADC.
    pub fn adc_bits(&self) -> Option<u32> {
        self.adc.map(|adc| adc.bits)
    }

    /// Saturation capacity μ_e.sat, e⁻: the full well, or the charge `(2^bits − 1 − B)/K` that
    /// drives the ADC from its black level B ([`Sensor::with_black_level`], 0 by default) to its
    /// largest output if that is smaller (EMVA 1288 Release 4.0 Linear, §2.4: saturation is where
    /// the output stops following the input, whichever limit comes first).
    pub fn saturation_e(&self) -> f64 {
        match self.adc {
            Some(adc) => {
                let adc_range_e = (((1_u64 << adc.bits) - 1) as f64 - adc.black_level_dn) / adc.gain_dn_per_e;
                self.full_well_e.min(adc_range_e)
            }
            None => self.full_well_e,
        }
    }

    /// Quantization noise referred to the input, σ_q²/K² with σ_q² = 1/12 DN², e⁻²
    /// (EMVA 1288 Release 4.0 Linear, §2.2); 0 without an ADC.
    pub fn quantization_variance_e2(&self) -> f64 {
        match self.adc {
            Some(adc) => QUANTIZATION_VARIANCE_DN2 / (adc.gain_dn_per_e * adc.gain_dn_per_e),
            None => 0.0,
        }
    }
}

/// The noise budget of one exposure of one pixel, from [`budget`]. All charges in e⁻, all
/// variances in e⁻².
///
/// Charges are as collected: when the pixel saturates (`saturated`), the well holds exactly
/// [`Sensor::saturation_e`] and the signal is what remains above the black level (dark +
/// background), as eq. 2 (signal = white − black) would measure it; `unclipped_signal_e` keeps
/// the signal asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct NoiseBudget {
    /// Exposure time, s.
    pub exposure_s: f64,
    /// Signal μ_e: photoelectrons from the imaging order, after clipping, e⁻.
    pub signal_e: f64,
    /// The signal asked for, before clipping, e⁻ (equal to `signal_e` unless `saturated`).
    pub unclipped_signal_e: f64,
    /// Background photoelectrons (veiling glare, stray light: shot noise but no signal), after
    /// clipping, e⁻.
    pub background_e: f64,
    /// Dark electrons, dark current × exposure, after clipping, e⁻.
    pub dark_e: f64,
    /// The saturation capacity the charges were clipped to, e⁻ ([`Sensor::saturation_e`]).
    pub saturation_e: f64,
    /// Whether signal + background + dark exceeded the saturation capacity and were clipped.
    pub saturated: bool,
    /// Shot noise of the light, signal + background (Poisson: variance = mean), e⁻².
    pub shot_variance_e2: f64,
    /// Shot noise of the dark current, dark_e, e⁻².
    pub dark_variance_e2: f64,
    /// Read noise σ_r², e⁻².
    pub read_variance_e2: f64,
    /// Quantization noise σ_q²/K², e⁻² (0 without an ADC).
    pub quantization_variance_e2: f64,
    /// The sum of the four variances above, e⁻².
    pub total_variance_e2: f64,
    /// `signal_e/√total_variance_e2` (0 when there is no signal).
    pub snr: f64,
}

impl NoiseBudget {
    /// Total temporal noise σ, e⁻ rms.
    pub fn noise_e(&self) -> f64 {
        self.total_variance_e2.sqrt()
    }

    /// The partial derivatives of `snr = S/√V`, `V = S + B + D + σ_r² + σ_q²/K²`, with respect to
    /// the signal S and to each variance term (docs/physics.md, "Gradients"):
    /// `∂SNR/∂S = (2V − S)/(2V^{3/2})` and `∂SNR/∂X = −S/(2V^{3/2})` for X = B, D, σ_r², σ_q²/K²
    /// (with σ_r alone, `∂SNR/∂S = (S + 2σ_r²)/(2(S + σ_r²)^{3/2})`; shot noise alone, `1/(2√S)`).
    ///
    /// `None` where the SNR is not differentiable in its charges: a saturated pixel (the charges
    /// are clipped, a kink at the well) or no signal.
    pub fn snr_partials(&self) -> Option<SnrPartials> {
        if self.saturated || self.signal_e <= 0.0 {
            return None;
        }
        let v = self.total_variance_e2;
        let v32 = v * v.sqrt();
        let variance = -self.signal_e / (2.0 * v32);
        Some(SnrPartials { signal: (2.0 * v - self.signal_e) / (2.0 * v32), variance })
    }
}

/// The partial derivatives of a [`NoiseBudget`]'s SNR ([`NoiseBudget::snr_partials`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnrPartials {
    /// `∂SNR/∂S`, per e⁻ of signal (the signal's own shot noise included).
    pub signal: f64,
    /// `∂SNR/∂X`, per e⁻² of any other variance term X (background or dark shot noise, σ_r²,
    /// σ_q²/K²): `−S/(2V^{3/2})`.
    pub variance: f64,
}

/// The noise budget of `signal_e` photoelectrons from the imaging order on top of
/// `background_e` photoelectrons of glare or stray light, in an exposure of `exposure_s`
/// seconds on `sensor`.
///
/// `SNR = μ_e/√(μ_e + μ_bg + μ_d + σ_r² + σ_q²/K²)`: the EMVA 1288 SNR (Release 4.0 Linear, §2.3,
/// with its dark variance σ_d² split into dark shot noise μ_d and read noise σ_r²) with the
/// background's shot noise added (paper SI eq. S14, S_N = S + background). Special cases:
/// - [`Sensor::ideal`] and no background: `√N` (paper SI eq. S9; exact when N is a perfect square,
///   to rounding otherwise);
/// - [`Sensor::ideal`] and `background_e = (T/τ1 − 1)·S`: `S/√S_N` (paper SI eq. S14,
///   [`snr_with_glare`](crate::snr_with_glare)), bit for bit when `S + background` is exact.
///
/// Saturation: when signal + background + dark exceeds [`Sensor::saturation_e`], the charges are
/// clipped (dark first, then background, then signal: the black level fills the well before the
/// signal above it), `saturated` is set, and the variances are those of the clipped charges, so
/// the SNR never exceeds EMVA's `SNR_max = √μ_e.sat` (§2.4). Check `saturated`: a clipped budget
/// is a ceiling, not a prediction.
///
/// # Errors
/// [`Error::InvalidParameter`] if `signal_e`, `background_e` or `exposure_s` is negative, NaN
/// or infinite; [`Error::Overflow`] if the dark charge (dark current × exposure) or the sum of
/// the variances exceeds the largest finite number, so that no finite budget exists.
pub fn budget(sensor: &Sensor, signal_e: f64, background_e: f64, exposure_s: f64) -> Result<NoiseBudget, Error> {
    non_negative("signal", signal_e, "e⁻")?;
    non_negative("background", background_e, "e⁻")?;
    non_negative("exposure", exposure_s, "s")?;
    let unclipped_dark_e = sensor.dark_current_e_per_s * exposure_s;
    if !unclipped_dark_e.is_finite() {
        return Err(Error::Overflow {
            quantity: "dark charge",
            detail: format!(
                "dark current {:e} e⁻/s × exposure {exposure_s:e} s exceeds {:e} e⁻",
                sensor.dark_current_e_per_s,
                f64::MAX
            ),
        });
    }
    let saturation_e = sensor.saturation_e();
    let saturated = signal_e + background_e + unclipped_dark_e > saturation_e;
    let (signal, background, dark) = if saturated {
        let dark = unclipped_dark_e.min(saturation_e);
        let background = background_e.min(saturation_e - dark);
        let signal = signal_e.min(saturation_e - dark - background).max(0.0);
        (signal, background, dark)
    } else {
        (signal_e, background_e, unclipped_dark_e)
    };
    let shot = signal + background;
    let read = sensor.read_noise_e * sensor.read_noise_e;
    let quantization = sensor.quantization_variance_e2();
    let total = shot + dark + read + quantization;
    if !total.is_finite() {
        return Err(Error::Overflow {
            quantity: "total noise variance",
            detail: format!(
                "shot {shot:e} + dark {dark:e} + read {read:e} + quantization {quantization:e} e⁻² exceeds {:e} e⁻²",
                f64::MAX
            ),
        });
    }
    // total ≥ signal, so total = 0 only without signal: 0, never 0/0.
    let snr = if signal > 0.0 { signal / total.sqrt() } else { 0.0 };
    Ok(NoiseBudget {
        exposure_s,
        signal_e: signal,
        unclipped_signal_e: signal_e,
        background_e: background,
        dark_e: dark,
        saturation_e,
        saturated,
        shot_variance_e2: shot,
        dark_variance_e2: dark,
        read_variance_e2: read,
        quantization_variance_e2: quantization,
        total_variance_e2: total,
        snr,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The SNR's partials against central differences of the budget itself (step 1e-3 e⁻: the
    /// truncation h²|f‴|/6 is far below the 1e-9 asked) and against the closed form with read
    /// noise alone (docs/physics.md, "Gradients").
    #[test]
    fn snr_partials_match_differences_and_the_closed_form() {
        let sensor = Sensor::new(3.0, 50.0, 1e6, 0.5, 16).unwrap();
        let (s, b, t) = (2500.0, 400.0, 0.01);
        let p = budget(&sensor, s, b, t).unwrap().snr_partials().unwrap();
        let h = 1e-3;
        let d_s = (budget(&sensor, s + h, b, t).unwrap().snr - budget(&sensor, s - h, b, t).unwrap().snr) / (2.0 * h);
        let d_b = (budget(&sensor, s, b + h, t).unwrap().snr - budget(&sensor, s, b - h, t).unwrap().snr) / (2.0 * h);
        assert!((p.signal - d_s).abs() < 1e-9 * d_s.abs(), "{} vs {d_s}", p.signal);
        assert!((p.variance - d_b).abs() < 1e-9 * d_b.abs(), "{} vs {d_b}", p.variance);
        // read noise alone: ∂SNR/∂N = (N + 2σ_r²)/(2(N + σ_r²)^{3/2})
        let read = Sensor::without_adc(3.0, 0.0, f64::INFINITY).unwrap();
        let p = budget(&read, s, 0.0, t).unwrap().snr_partials().unwrap();
        let closed = (s + 18.0) / (2.0 * (s + 9.0_f64).powf(1.5));
        assert!((p.signal - closed).abs() < 1e-15, "{} vs {closed}", p.signal);
        // saturated or dark: no derivative
        assert!(budget(&sensor, 2e6, 0.0, t).unwrap().snr_partials().is_none());
        assert!(budget(&sensor, 0.0, 0.0, t).unwrap().snr_partials().is_none());
    }

    #[test]
    fn adc_range_limits_saturation() {
        // 8 bits, K = 0.1 DN/e⁻: 255 DN ↔ 2550 e⁻ < 10 000 e⁻ full well
        let sensor = Sensor::new(2.0, 0.0, 10_000.0, 0.1, 8).unwrap();
        assert!((sensor.saturation_e() - 2550.0).abs() < 1e-9);
        // 32 bits: the ADC range (4.29e10 e⁻) is far above the well
        let sensor = Sensor::new(2.0, 0.0, 10_000.0, 0.1, 32).unwrap();
        assert_eq!(sensor.saturation_e(), 10_000.0);
    }

    #[test]
    fn ideal_has_no_noise_floor() {
        let ideal = Sensor::ideal();
        assert_eq!(ideal.saturation_e(), f64::INFINITY);
        assert_eq!(ideal.quantization_variance_e2(), 0.0);
        assert_eq!((ideal.gain_dn_per_e(), ideal.adc_bits()), (None, None));
        // no light: SNR 0, not 0/0
        let b = budget(&ideal, 0.0, 0.0, 1.0).unwrap();
        assert_eq!((b.snr, b.total_variance_e2, b.saturated), (0.0, 0.0, false));
    }

    #[test]
    fn rejects_out_of_range_parameters() {
        for (sensor, name) in [
            (Sensor::new(-1.0, 0.0, 1e4, 1.0, 12), "read_noise"),
            (Sensor::new(1.0, f64::NAN, 1e4, 1.0, 12), "dark_current"),
            (Sensor::new(1.0, 0.0, 0.0, 1.0, 12), "full_well"),
            (Sensor::new(1.0, 0.0, 1e4, 0.0, 12), "gain"),
            (Sensor::new(1.0, 0.0, 1e4, 1.0, 0), "adc_bits"),
            (Sensor::new(1.0, 0.0, 1e4, 1.0, 33), "adc_bits"),
        ] {
            match sensor {
                Err(Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{name}: expected InvalidParameter, got {other:?}"),
            }
        }
    }
}
