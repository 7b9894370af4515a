//! The paper's radiometric chain, supporting information eq. S1–S9, as plain functions.
//!
//! Power meter → fiber → spectrometer gives the absolute spectral irradiance at the fiber
//! (S1–S5); the Lambertian relay takes it back to target radiance (S6); the lens takes it to the
//! camera (S7); the camera counts photoelectrons (S8), whose shot noise sets the SNR (S9).
//!
//! The scalar functions do not validate (they follow IEEE arithmetic: a NaN input gives a NaN
//! result); validate user input where it enters, e.g. when a scene is parsed.

use crate::Error;
use crate::constants::{PLANCK, SPEED_OF_LIGHT};
use crate::quadrature;
use crate::sampled::Sampled;
use crate::spectrum::Spectrum;
use core::f64::consts::PI;

/// Paper SI eq. S1: E_norm(λ) = E_rel(λ) / ∫E_rel dλ, so that ∫E_norm dλ = 1 (unit 1/m).
///
/// # Errors
/// [`Error::NotNormalizable`] when the integral is 0 (or not finite), or the result overflows.
pub fn normalize(relative: &Sampled) -> Result<Sampled, Error> {
    let area = relative.integral();
    if !(area.is_finite() && area > 0.0) {
        return Err(Error::NotNormalizable { value: area });
    }
    let values: Vec<f64> = relative.values().iter().map(|v| v / area).collect();
    if values.iter().any(|v| !v.is_finite()) {
        return Err(Error::NotNormalizable { value: area });
    }
    Sampled::new(relative.wavelengths().to_vec(), values)
}

/// Paper SI eq. S2: irradiance on the fiber face E = P / A, A = π d²/4, in W/m² for a power in
/// W and a core diameter in m.
pub fn fiber_irradiance(power_w: f64, fiber_core_diameter_m: f64) -> f64 {
    power_w / (0.25 * PI * fiber_core_diameter_m * fiber_core_diameter_m)
}

/// Paper SI eq. S3: broadband correction factor of a power meter calibrated at one wavelength,
/// corr = ∫ E_norm(λ) · R(λ_cal)/R(λ) dλ over the normalized spectrum's table (dimensionless;
/// 1 for a flat responsivity). `responsivity` may be in any unit (A/W, relative).
///
/// The integrand is linear over linear on each panel of the union of both tables' samples:
/// panels where R changes by less than a factor 2 use 16-node Gauss–Legendre (error far below
/// rounding), steeper panels the closed form w·[ΔE/ΔR + (E_a R_b − E_b R_a)/ΔR² · ln(R_b/R_a)].
///
/// # Errors
/// [`Error::InvalidParameter`] if the calibration wavelength is not finite and > 0, or if R is
/// not positive there; [`Error::ZeroResponsivity`] if R is 0 where E_norm > 0 (including outside the
/// responsivity table).
pub fn broadband_correction(
    normalized: &Sampled,
    responsivity: &Sampled,
    calibration_wavelength_m: f64,
) -> Result<f64, Error> {
    crate::error::positive("calibration wavelength", calibration_wavelength_m, "m")?;
    let r_cal = responsivity.value(calibration_wavelength_m);
    crate::error::check(
        "responsivity at the calibration wavelength",
        r_cal,
        r_cal > 0.0,
        "> 0 (calibration wavelength inside the responsivity table)",
    )?;
    let (e_lo, e_hi) = normalized.range();
    let (r_lo, r_hi) = responsivity.range();
    let mut cuts: Vec<f64> = normalized.wavelengths().to_vec();
    cuts.extend(responsivity.wavelengths().iter().filter(|&&w| w > e_lo && w < e_hi));
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let mut sum = 0.0;
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (ea, eb) = (normalized.value(a), normalized.value(b));
        if ea == 0.0 && eb == 0.0 {
            continue;
        }
        let inside = a >= r_lo && b <= r_hi;
        let (ra, rb) = if inside { (responsivity.value(a), responsivity.value(b)) } else { (0.0, 0.0) };
        // R and E are linear on the panel: find where R = 0 and E > 0.
        let bad = if ra == 0.0 && rb == 0.0 {
            Some(if ea > 0.0 { a } else { b })
        } else if ra == 0.0 && ea > 0.0 {
            Some(a)
        } else if rb == 0.0 && eb > 0.0 {
            Some(b)
        } else {
            None
        };
        if let Some(wavelength_m) = bad {
            return Err(Error::ZeroResponsivity { wavelength_m });
        }
        sum += ratio_integral(a, b, ea, eb, ra, rb);
    }
    Ok(r_cal * sum)
}

/// ∫_a^b E/R dλ for E, R linear between the given end values (R > 0 inside the panel).
fn ratio_integral(a: f64, b: f64, ea: f64, eb: f64, ra: f64, rb: f64) -> f64 {
    let width = b - a;
    let (lo, hi) = (ra.min(rb), ra.max(rb));
    if hi <= 2.0 * lo {
        return quadrature::panel(0.0, 1.0, |t| (ea + (eb - ea) * t) / (ra + (rb - ra) * t)) * width;
    }
    let de = eb - ea;
    let dr = rb - ra;
    let cross = ea * rb - eb * ra;
    let log_term = if cross == 0.0 { 0.0 } else { cross / (dr * dr) * (rb / ra).ln() };
    width * (de / dr + log_term)
}

/// Paper SI eq. S4: E_accurate = corr · E (same unit as `irradiance`, W/m²).
pub fn corrected_irradiance(correction: f64, irradiance: f64) -> f64 {
    correction * irradiance
}

/// Paper SI eq. S5: absolute spectral irradiance E_λ = E_norm(λ) · E_accurate, W/(m² m), for a
/// normalized spectrum (1/m) and an irradiance (W/m²). Scaling follows [`Sampled::scaled`].
pub fn absolute_spectral_irradiance(normalized: &Sampled, corrected_irradiance_w_m2: f64) -> Sampled {
    normalized.scaled(corrected_irradiance_w_m2)
}

/// Paper SI eq. S6: target spectral radiance seen through the Lambertian relay,
/// L = E/(π T) · (2f/D)², W/(m² sr m) from a spectral irradiance in W/(m² m), the relay lens
/// transmission T, the relay focal length f (m) and aperture D (m).
pub fn target_radiance(
    spectral_irradiance: f64,
    relay_transmission: f64,
    relay_focal_length_m: f64,
    relay_aperture_m: f64,
) -> f64 {
    let g = 2.0 * relay_focal_length_m / relay_aperture_m;
    spectral_irradiance / (PI * relay_transmission) * g * g
}

/// The readings of the paper's spectral radiance meter (SI section "Radiometric calculation"):
/// the spectrometer's relative spectrum through the fiber, the power meter's reading of the same
/// fiber, the meter's spectral responsivity and calibration wavelength, and the Lambertian relay
/// (lenses L1, L2 with an iris between them) that images the target onto the fiber face.
/// Wavelengths in m, lengths in m, power in W; the spectrum and the responsivity in any unit.
#[derive(Clone, Debug)]
pub struct RadianceMeter {
    /// E_rel(λ), the spectrometer's relative spectrum (any unit, ≥ 0).
    pub relative_spectrum: Sampled,
    /// P, the power meter's reading, W.
    pub power_w: f64,
    /// The fiber core diameter d, m (A_fiber = π d²/4).
    pub fiber_core_diameter_m: f64,
    /// R(λ), the power meter's spectral responsivity (A/W or relative).
    pub responsivity: Sampled,
    /// λ_cal, the wavelength the meter is calibrated at, m.
    pub calibration_wavelength_m: f64,
    /// T_lenses, the relay's transmission, in (0, 1].
    pub relay_transmission: f64,
    /// D, the iris between the relay lenses, m.
    pub relay_iris_m: f64,
    /// f, the focal length of the relay lens before the fiber (L2), m.
    pub relay_focal_length_m: f64,
}

/// Every step of [`radiance_meter`], SI eq. S1–S6, in SI units.
#[derive(Clone, Debug)]
pub struct RadianceMeterSteps {
    /// S1: ∫E_rel dλ (the relative spectrum's unit × m).
    pub relative_integral: f64,
    /// S1: E_norm = E_rel/∫E_rel dλ, 1/m (unit area).
    pub normalized: Sampled,
    /// S2: A_fiber = π d²/4, m².
    pub fiber_area_m2: f64,
    /// S2: E = P/A_fiber, W/m².
    pub fiber_irradiance_w_m2: f64,
    /// S3: R(λ_cal), in the responsivity's unit.
    pub calibration_responsivity: f64,
    /// S3: corr = ∫E_norm R(λ_cal)/R(λ) dλ (dimensionless).
    pub correction: f64,
    /// S4: E_accurate = corr · E, W/m².
    pub corrected_irradiance_w_m2: f64,
    /// S5: E_λ = E_norm · E_accurate, W/(m² m).
    pub spectral_irradiance: Sampled,
    /// S6: (2f/D)²/(π T_lenses), 1/sr: L_λ = this × E_λ.
    pub relay_factor_per_sr: f64,
    /// S6: L_λ, the target's spectral radiance, W/(m² sr m).
    pub radiance: Sampled,
}

/// Paper SI eq. S1–S6 in one go: the readings of a radiance meter → the target's spectral
/// radiance, with every intermediate value (for reports: `asnr evaluate --explain`).
///
/// # Errors
/// [`Error::InvalidParameter`] for a power, diameter, iris or focal length that is not finite
/// and positive, or a relay transmission outside (0, 1]; the errors of [`normalize`] and
/// [`broadband_correction`]; [`Error::InvalidSample`] if a value overflows.
pub fn radiance_meter(m: &RadianceMeter) -> Result<RadianceMeterSteps, Error> {
    use crate::error::{check, positive};
    positive("power", m.power_w, "W")?;
    positive("fiber core diameter", m.fiber_core_diameter_m, "m")?;
    check(
        "relay transmission",
        m.relay_transmission,
        m.relay_transmission > 0.0 && m.relay_transmission <= 1.0,
        "in (0, 1]",
    )?;
    positive("relay iris diameter", m.relay_iris_m, "m")?;
    positive("relay focal length", m.relay_focal_length_m, "m")?;
    let relative_integral = m.relative_spectrum.integral();
    let normalized = normalize(&m.relative_spectrum)?;
    let fiber_area_m2 = 0.25 * PI * m.fiber_core_diameter_m * m.fiber_core_diameter_m;
    let fiber_irradiance_w_m2 = fiber_irradiance(m.power_w, m.fiber_core_diameter_m);
    let correction = broadband_correction(&normalized, &m.responsivity, m.calibration_wavelength_m)?;
    let corrected_irradiance_w_m2 = corrected_irradiance(correction, fiber_irradiance_w_m2);
    let spectral_irradiance = normalized.try_scaled(corrected_irradiance_w_m2)?;
    let relay_factor_per_sr = target_radiance(1.0, m.relay_transmission, m.relay_focal_length_m, m.relay_iris_m);
    let radiance = spectral_irradiance.try_scaled(relay_factor_per_sr)?;
    Ok(RadianceMeterSteps {
        relative_integral,
        normalized,
        fiber_area_m2,
        fiber_irradiance_w_m2,
        calibration_responsivity: m.responsivity.value(m.calibration_wavelength_m),
        correction,
        corrected_irradiance_w_m2,
        spectral_irradiance,
        relay_factor_per_sr,
        radiance,
    })
}

/// Paper SI eq. S7: camera-plane spectral irradiance E_cam = π L τ₁ NA², W/(m² m) from a spectral
/// radiance in W/(m² sr m), the lens efficiency τ₁ and numerical aperture NA.
pub fn camera_irradiance(radiance: f64, efficiency: f64, numerical_aperture: f64) -> f64 {
    PI * radiance * efficiency * numerical_aperture * numerical_aperture
}

/// Photons per joule at a wavelength (m): λ/(h c).
pub fn photon_flux_per_watt(wavelength_m: f64) -> f64 {
    wavelength_m / (PLANCK * SPEED_OF_LIGHT)
}

/// Paper SI eq. S8 for one wavelength (or one narrow band): N = A t/(h c) · η · λ · E.
///
/// Pixel area in m², exposure in s, quantum efficiency η, wavelength in m. With an irradiance E in
/// W/m² the result is photoelectrons; with a spectral irradiance in W/(m² m) it is the S8
/// integrand, photoelectrons per m of wavelength, to be integrated by the caller.
pub fn photoelectrons_monochromatic(
    pixel_area_m2: f64,
    exposure_s: f64,
    quantum_efficiency: f64,
    wavelength_m: f64,
    camera_irradiance_w_m2: f64,
) -> f64 {
    pixel_area_m2 * exposure_s * quantum_efficiency * camera_irradiance_w_m2 * photon_flux_per_watt(wavelength_m)
}

/// Paper SI eq. S8: N = A t/(h c) ∫ η(λ) λ E_cam(λ) dλ, photoelectrons, for a pixel area (m²), an
/// exposure (s), the camera-plane spectral irradiance (W/(m² m)) and the quantum efficiency.
///
/// The integral is [`Spectrum::integral`] of the product `E_cam × η × Linear{slope: 1}`: exact
/// for tables, top-hats and constants, Gauss–Legendre accurate for Gaussian or blackbody factors.
pub fn photoelectrons(
    pixel_area_m2: f64,
    exposure_s: f64,
    camera_spectral_irradiance: &Spectrum,
    quantum_efficiency: &Spectrum,
) -> f64 {
    let integrand = Spectrum::product(vec![
        camera_spectral_irradiance.clone(),
        quantum_efficiency.clone(),
        Spectrum::Linear { slope: 1.0 },
    ]);
    pixel_area_m2 * exposure_s / (PLANCK * SPEED_OF_LIGHT) * integrand.integral()
}

/// Paper SI eq. S9: shot-noise-limited SNR = √N for N photoelectrons (NaN for N < 0).
pub fn shot_noise_snr(photoelectrons: f64) -> f64 {
    photoelectrons.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratio_integral_branches_agree_near_the_switch() {
        // R from 1 to 2 (GL branch) vs 1 to 2.0000001 (closed form): nearly the same integral.
        let gl = ratio_integral(0.0, 1.0, 1.0, 3.0, 1.0, 2.0);
        let cf = ratio_integral(0.0, 1.0, 1.0, 3.0, 1.0, 2.000_000_1);
        assert!((gl - cf).abs() < 1e-6, "{gl} vs {cf}");
        // Exact: ∫_0^1 (1 + 2t)/(1 + t) dt = 2 − ln 2.
        assert!((gl - (2.0 - 2f64.ln())).abs() < 1e-15);
    }

    #[test]
    fn ratio_integral_closed_form_with_varying_spectrum() {
        // ∫_0^1 (1 + 2t)/(1 + 9t) dt = 2/9 + (1·10 − 3·1)/81 · ln 10 = 0.4212110574192385,
        // checked against 1000 Gauss–Legendre panels.
        let cf = ratio_integral(0.0, 1.0, 1.0, 3.0, 1.0, 10.0);
        assert!((cf - (2.0 / 9.0 + 7.0 / 81.0 * 10f64.ln())).abs() < 1e-15);
        let fine: f64 = (0..1000)
            .map(|i| {
                let (a, b) = (f64::from(i) / 1000.0, f64::from(i + 1) / 1000.0);
                quadrature::panel(a, b, |t| (1.0 + 2.0 * t) / (1.0 + 9.0 * t))
            })
            .sum();
        assert!((cf - fine).abs() < 1e-14, "{cf} vs {fine}");
    }

    #[test]
    fn ratio_integral_vanishing_together_is_constant() {
        // E = 2(1 − t), R = 1 − t: ratio 2 everywhere, integral 2.
        assert!((ratio_integral(0.0, 1.0, 2.0, 0.0, 1.0, 0.0) - 2.0).abs() < 1e-15);
    }
}
