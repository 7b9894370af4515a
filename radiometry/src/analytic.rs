//! Analytic spectra: truncated Gaussian, top-hat, Planck blackbody.

use crate::Error;
use crate::constants::{BOLTZMANN, PLANCK, SECOND_RADIATION_CONSTANT, SPEED_OF_LIGHT, STEFAN_BOLTZMANN};
use crate::error::{check, non_negative, positive};
use core::f64::consts::{PI, SQRT_2};

/// √(2π).
const SQRT_2PI: f64 = 2.506_628_274_631_000_7;

/// The narrowest Gaussian accepted, σ as a fraction of its centre wavelength (1e-10: 8e-17 m at
/// 800 nm, some 1e7 floating-point steps across ±12σ).
pub const MIN_RELATIVE_SIGMA: f64 = 1e-10;

/// A Gaussian spectrum `peak · exp(−(λ − center)²/(2σ²))`, truncated to 0 at λ ≤ 0.
///
/// The paper's "spectral range" of a Gaussian spectrum is 2√2·σ (paper, Results), **not** the
/// FWHM (2.355σ): see [`Gaussian::from_range`] and [`Gaussian::range`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gaussian {
    center_m: f64,
    sigma_m: f64,
    peak: f64,
}

impl Gaussian {
    /// Its numbers' bits (center, σ, peak): equal only for the very same Gaussian.
    pub(crate) fn bits(&self) -> [u64; 3] {
        [self.center_m, self.sigma_m, self.peak].map(f64::to_bits)
    }

    /// Validates: `center_m` finite and > 0 m, `sigma_m` finite and > 0 m, `peak` finite and ≥ 0.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad parameter.
    pub fn new(center_m: f64, sigma_m: f64, peak: f64) -> Result<Self, Error> {
        positive("center", center_m, "m")?;
        positive("sigma", sigma_m, "m")?;
        // narrower than this, center ± a few σ are the same few floating-point numbers and no
        // quadrature resolves the peak: such a band is a line (Spectrum::Line)
        // (the message written only when it fails: a sweep builds its band at every point)
        let resolved = sigma_m >= MIN_RELATIVE_SIGMA * center_m;
        if !resolved {
            check(
                "sigma",
                sigma_m,
                false,
                format!(
                    "at least {MIN_RELATIVE_SIGMA:e} × center (= {:e} m) for the wavelength grid to resolve it; a narrower band is a line",
                    MIN_RELATIVE_SIGMA * center_m
                ),
            )?;
        }
        non_negative("peak", peak, "")?;
        Ok(Gaussian { center_m, sigma_m, peak })
    }

    /// From the paper's spectral range (m): σ = range/(2√2) (paper, Results).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad parameter (`range` for the range).
    pub fn from_range(center_m: f64, range_m: f64, peak: f64) -> Result<Self, Error> {
        positive("range", range_m, "m")?;
        Gaussian::new(center_m, range_m / (2.0 * SQRT_2), peak)
    }

    /// Center wavelength, m.
    pub fn center(&self) -> f64 {
        self.center_m
    }

    /// Standard deviation σ, m.
    pub fn sigma(&self) -> f64 {
        self.sigma_m
    }

    /// Peak value (the value at the center).
    pub fn peak(&self) -> f64 {
        self.peak
    }

    /// The paper's spectral range 2√2·σ, m.
    pub fn range(&self) -> f64 {
        2.0 * SQRT_2 * self.sigma_m
    }

    /// `peak · exp(−(λ − center)²/(2σ²))` for λ > 0, exactly 0 for λ ≤ 0, NaN for NaN.
    pub fn value(&self, wavelength_m: f64) -> f64 {
        let l = wavelength_m;
        if l.is_nan() {
            return f64::NAN;
        }
        if l <= 0.0 {
            return 0.0;
        }
        let d = (l - self.center_m) / self.sigma_m;
        self.peak * (-0.5 * d * d).exp()
    }

    /// Fraction of the untruncated Gaussian's area at λ ≤ 0: ½·erfc(center/(σ√2)). Underflows to
    /// exactly 0 once center/σ exceeds about 38.
    pub fn truncated_fraction(&self) -> f64 {
        0.5 * libm::erfc(self.center_m / (self.sigma_m * SQRT_2))
    }

    /// Fraction of the untruncated Gaussian's area outside [lo, hi] (m).
    pub(crate) fn fraction_outside(&self, lo: f64, hi: f64) -> f64 {
        let s = self.sigma_m * SQRT_2;
        let below = 0.5 * libm::erfc((self.center_m - lo) / s);
        let above = 0.5 * libm::erfc((hi - self.center_m) / s);
        below + above
    }

    /// Exact area of the truncated Gaussian, value unit × m:
    /// `peak · σ√(2π) · ½·erfc(−center/(σ√2))` (the erfc form avoids the cancellation of
    /// `1 − truncated_fraction` for wide spectra).
    pub fn integral(&self) -> f64 {
        self.peak * self.sigma_m * SQRT_2PI * 0.5 * libm::erfc(-self.center_m / (self.sigma_m * SQRT_2))
    }
}

/// A top-hat (ideal band-pass) spectrum: `value` on [lo, hi] (both edges included), 0 outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TopHat {
    lo_m: f64,
    hi_m: f64,
    value: f64,
}

impl TopHat {
    /// Its numbers' bits (lo, hi, value): equal only for the very same band.
    pub(crate) fn bits(&self) -> [u64; 3] {
        [self.lo_m, self.hi_m, self.value].map(f64::to_bits)
    }

    /// Validates: `lo_m` finite and ≥ 0 m, `hi_m` finite and > `lo_m`, `value` finite and ≥ 0.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad parameter.
    pub fn new(lo_m: f64, hi_m: f64, value: f64) -> Result<Self, Error> {
        non_negative("lo", lo_m, "m")?;
        check("hi", hi_m, hi_m.is_finite() && hi_m > lo_m, format!("finite and > lo (= {lo_m:?}) m"))?;
        non_negative("value", value, "")?;
        Ok(TopHat { lo_m, hi_m, value })
    }

    /// Lower edge, m.
    pub fn lo(&self) -> f64 {
        self.lo_m
    }

    /// Upper edge, m.
    pub fn hi(&self) -> f64 {
        self.hi_m
    }

    /// Value inside the band, as `value(l)` is taken: see [`TopHat::value`].
    pub fn height(&self) -> f64 {
        self.value
    }

    /// The height on [lo, hi], 0 outside, NaN for NaN.
    pub fn value(&self, wavelength_m: f64) -> f64 {
        let l = wavelength_m;
        if l.is_nan() {
            f64::NAN
        } else if l >= self.lo_m && l <= self.hi_m {
            self.value
        } else {
            0.0
        }
    }

    /// Exact area `value · (hi − lo)`, value unit × m.
    pub fn integral(&self) -> f64 {
        self.value * (self.hi_m - self.lo_m)
    }
}

/// A spectral line: a band narrow enough for the optics to treat as one wavelength, with the
/// photon count of its full width.
///
/// As a measure (what [`Spectrum::integral`](crate::Spectrum::integral) and
/// [`Spectrum::quadrature_nodes`](crate::Spectrum::quadrature_nodes) integrate) it is
/// `peak · width · δ(λ − center)`: every other factor of a product is evaluated at the centre,
/// and the band counts `peak × width`, the area of a filter of equivalent width `width`
/// (∫ T dλ / T_peak) and peak transmission `peak`. Photoelectrons therefore scale with the width
/// exactly as for the other filters (paper, Results: the photon count is proportional to the
/// spectral range), and a line equals a top-hat of the same width and peak for every factor
/// linear in λ across the band (flat source, constant QE, the λ of SI eq. S8).
///
/// As a function ([`value`](Line::value)) it is that equivalent band: `peak` on
/// `[center − width/2, center + width/2]`, 0 outside (what the filter transmits, for plots and
/// support checks).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    center_m: f64,
    width_m: f64,
    peak: f64,
}

impl Line {
    /// Its numbers' bits (center, width, peak): equal only for the very same line.
    pub(crate) fn bits(&self) -> [u64; 3] {
        [self.center_m, self.width_m, self.peak].map(f64::to_bits)
    }

    /// Validates: `center_m` finite and > 0 m, `width_m` (the equivalent width) finite, > 0 and
    /// < 2 `center_m` (the band stays at λ > 0), `peak` finite and ≥ 0.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad parameter.
    pub fn new(center_m: f64, width_m: f64, peak: f64) -> Result<Self, Error> {
        positive("center", center_m, "m")?;
        check(
            "width",
            width_m,
            width_m.is_finite() && width_m > 0.0 && width_m < 2.0 * center_m,
            format!("finite, > 0 and < 2 × center (= {:?}) m, so the band stays at λ > 0", 2.0 * center_m),
        )?;
        non_negative("peak", peak, "")?;
        Ok(Line { center_m, width_m, peak })
    }

    /// The wavelength the optics sees, m.
    pub fn center(&self) -> f64 {
        self.center_m
    }

    /// Equivalent width `∫ T dλ / T_peak`, m.
    pub fn width(&self) -> f64 {
        self.width_m
    }

    /// Peak value (transmission of a filter).
    pub fn peak(&self) -> f64 {
        self.peak
    }

    /// Lower edge of the equivalent band, m.
    pub fn lo(&self) -> f64 {
        self.center_m - 0.5 * self.width_m
    }

    /// Upper edge of the equivalent band, m.
    pub fn hi(&self) -> f64 {
        self.center_m + 0.5 * self.width_m
    }

    /// The equivalent band: `peak` on [lo, hi] (edges included), 0 outside, NaN for NaN.
    pub fn value(&self, wavelength_m: f64) -> f64 {
        let l = wavelength_m;
        if l.is_nan() {
            f64::NAN
        } else if l >= self.lo() && l <= self.hi() {
            self.peak
        } else {
            0.0
        }
    }

    /// The line's weight `peak · width` (value unit × m): its integral, all at the centre.
    pub fn integral(&self) -> f64 {
        self.peak * self.width_m
    }
}

/// A Planck blackbody at a temperature (K).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blackbody {
    temperature_k: f64,
}

impl Blackbody {
    /// Its temperature's bits: equal only for the very same blackbody.
    pub(crate) fn bits(&self) -> u64 {
        self.temperature_k.to_bits()
    }

    /// Highest accepted temperature, K. It keeps the spectral radiance (peak ≈ 4.1e-6·T⁵
    /// W/(m² sr m)) finite at every wavelength.
    pub const MAX_TEMPERATURE_K: f64 = 1e12;

    /// Validates: temperature finite and in (0, 1e12] K.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `temperature`.
    pub fn new(temperature_k: f64) -> Result<Self, Error> {
        check(
            "temperature",
            temperature_k,
            temperature_k > 0.0 && temperature_k <= Self::MAX_TEMPERATURE_K,
            "finite and in (0, 1e12] K",
        )?;
        Ok(Blackbody { temperature_k })
    }

    /// Temperature, K.
    pub fn temperature(&self) -> f64 {
        self.temperature_k
    }

    /// Wavelength of peak spectral radiance (per unit wavelength), m: Wien's displacement law
    /// λ_max = b/T with b = hc/(k·x₀), x₀ = 4.965114231744276 (root of x = 5(1 − e^−x)).
    pub fn peak_wavelength(&self) -> f64 {
        const WIEN_X: f64 = 4.965_114_231_744_276;
        SECOND_RADIATION_CONSTANT / (WIEN_X * self.temperature_k)
    }

    /// Planck spectral radiance B_λ(T) = 2hc²/λ⁵ / (exp(hc/(λkT)) − 1), W/(m² sr m).
    ///
    /// Uses `expm1`; finite for every λ > 0 (switching to a logarithmic form where λ⁵ or the
    /// exponential would over- or underflow), exactly 0 for λ ≤ 0, NaN for NaN.
    pub fn spectral_radiance(&self, wavelength_m: f64) -> f64 {
        let l = wavelength_m;
        if l.is_nan() {
            return f64::NAN;
        }
        if l <= 0.0 {
            return 0.0;
        }
        let t = self.temperature_k;
        let x = SECOND_RADIATION_CONSTANT / l / t;
        let l5 = l * l * l * l * l;
        let em1 = x.exp_m1();
        let den = l5 * em1;
        if l5.is_normal() && em1.is_normal() && den.is_normal() {
            let b = 2.0 * PLANCK * SPEED_OF_LIGHT * SPEED_OF_LIGHT / den;
            if b.is_finite() {
                return b;
            }
        }
        // B = (2ckT/λ⁴) · x/(eˣ − 1), in logarithms.
        if x.is_infinite() {
            return 0.0;
        }
        let ln_ratio = if x == 0.0 {
            0.0
        } else if x < 1e-5 {
            // x/(eˣ − 1) = 1 − x/2 + x²/12 − ...
            (-0.5 * x + x * x / 12.0).ln_1p()
        } else if x <= 700.0 {
            x.ln() - em1.ln()
        } else {
            x.ln() - x - (-(-x).exp()).ln_1p()
        };
        let ln_b = (2.0 * SPEED_OF_LIGHT * BOLTZMANN).ln() + t.ln() - 4.0 * l.ln() + ln_ratio;
        ln_b.exp()
    }

    /// The logarithmic derivatives of Planck's B_λ(T) = 2hc²/λ⁵ / (eˣ − 1), x = hc/(λkT), at
    /// `wavelength_m` (> 0): `(∂ln B/∂λ, ∂ln B/∂T) = ((f − 5)/λ, f/T)` with
    /// `f = x eˣ/(eˣ − 1) = x/(1 − e⁻ˣ)` (f → 1 as x → 0, the Rayleigh–Jeans limit; f → x as
    /// x → ∞, Wien's), per m and per K.
    pub fn log_derivatives(&self, wavelength_m: f64) -> (f64, f64) {
        let x = SECOND_RADIATION_CONSTANT / wavelength_m / self.temperature_k;
        let f = if x < 1e-8 { 1.0 + 0.5 * x } else { x / -(-x).exp_m1() };
        ((f - 5.0) / wavelength_m, f / self.temperature_k)
    }

    /// `∂ln g/∂λ` of Planck's temperature rate `g = ∂ln B/∂T = f/T` at `wavelength_m` (> 0), per
    /// m: with `x = hc/(λkT)`, `∂ln f/∂x = 1/x − 1/(eˣ − 1)` and `∂x/∂λ = −x/λ`, so
    /// `∂ln g/∂λ = −(1 − x/(eˣ − 1))/λ` (→ 0 as x → 0, → −1/λ as x → ∞).
    pub fn temperature_rate_log_slope(&self, wavelength_m: f64) -> f64 {
        let x = SECOND_RADIATION_CONSTANT / wavelength_m / self.temperature_k;
        let ratio = if x < 1e-8 { 1.0 - 0.5 * x } else { x / x.exp_m1() };
        -(1.0 - ratio) / wavelength_m
    }

    /// Exact radiance integral ∫₀^∞ B_λ dλ = σT⁴/π, W/(m² sr) (Stefan–Boltzmann).
    pub fn integral(&self) -> f64 {
        let t2 = self.temperature_k * self.temperature_k;
        STEFAN_BOLTZMANN * t2 * t2 / PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Planck's log-derivatives against central differences of `spectral_radiance` written here
    /// (relative step 1e-5: truncation ~1e-10, rounding ~1e-11), in the Wien and Rayleigh–Jeans
    /// regimes and between.
    #[test]
    fn blackbody_log_derivatives_match_differences_of_the_radiance() {
        for (t, l) in [(3000.0, 803e-9), (300.0, 500e-9), (5e6, 10e-6), (6000.0, 2e-6)] {
            let b = Blackbody::new(t).unwrap();
            let (d_l, d_t) = b.log_derivatives(l);
            let h = 1e-5;
            let by_l =
                ((b.spectral_radiance(l * (1.0 + h))).ln() - (b.spectral_radiance(l * (1.0 - h))).ln()) / (2.0 * h * l);
            let (up, down) = (Blackbody::new(t * (1.0 + h)).unwrap(), Blackbody::new(t * (1.0 - h)).unwrap());
            let by_t = (up.spectral_radiance(l).ln() - down.spectral_radiance(l).ln()) / (2.0 * h * t);
            assert!((d_l - by_l).abs() <= 1e-8 * d_l.abs().max(1.0 / l), "{t} K {l}: {d_l} vs {by_l}");
            assert!((d_t - by_t).abs() <= 1e-8 * d_t.abs(), "{t} K {l}: {d_t} vs {by_t}");
        }
    }

    #[test]
    fn gaussian_range_is_two_sqrt_two_sigma() {
        let g = Gaussian::from_range(800e-9, 50e-9, 1.0).unwrap();
        assert!((g.sigma() - 50e-9 / (2.0 * 2f64.sqrt())).abs() < 1e-22);
        assert!((g.range() - 50e-9).abs() < 1e-22);
    }

    #[test]
    fn gaussian_value() {
        let g = Gaussian::new(800e-9, 10e-9, 2.0).unwrap();
        assert_eq!(g.value(800e-9), 2.0);
        // One sigma away: 2 exp(-1/2) = 1.2130613194252668.
        assert!((g.value(810e-9) - 1.213_061_319_425_266_8).abs() < 1e-12);
        assert_eq!(g.value(0.0), 0.0);
        assert_eq!(g.value(-800e-9), 0.0);
        assert!(g.value(f64::NAN).is_nan());
    }

    #[test]
    fn top_hat() {
        let t = TopHat::new(750e-9, 850e-9, 0.5).unwrap();
        assert_eq!(t.value(750e-9), 0.5);
        assert_eq!(t.value(850e-9), 0.5);
        assert_eq!(t.value(851e-9), 0.0);
        // 0.5 × 100e-9 = 5e-8.
        assert!((t.integral() - 5e-8).abs() < 1e-22);
        assert!(TopHat::new(850e-9, 750e-9, 1.0).is_err());
        assert!(TopHat::new(-1e-9, 750e-9, 1.0).is_err());
    }

    #[test]
    fn line() {
        let l = Line::new(800e-9, 10e-9, 0.5).unwrap();
        assert_eq!((l.center(), l.width(), l.peak()), (800e-9, 10e-9, 0.5));
        // the equivalent band 795–805 nm
        assert_eq!(l.value(795e-9), 0.5);
        assert_eq!(l.value(805.1e-9), 0.0);
        assert!(l.value(f64::NAN).is_nan());
        // 0.5 × 10 nm
        assert!((l.integral() - 5e-9).abs() < 1e-24);
        let e = Line::new(800e-9, 1600e-9, 1.0).unwrap_err().to_string();
        assert!(e.contains("width must be finite, > 0 and < 2 × center"), "{e}");
        assert!(Line::new(800e-9, 0.0, 1.0).is_err());
        assert!(Line::new(0.0, 1e-9, 1.0).is_err());
        assert!(Line::new(800e-9, 1e-9, -1.0).is_err());
        assert!(Line::new(800e-9, f64::NAN, 1.0).is_err());
    }

    #[test]
    fn planck_log_form_matches_direct_form() {
        // Compare the logarithmic branch (forced by evaluating its formula) with the direct one.
        let b = Blackbody::new(300.0).unwrap();
        for &l in &[1e-6, 1e-5, 1e-4, 1e-3] {
            let x = SECOND_RADIATION_CONSTANT / l / 300.0;
            let log_form = (2.0 * SPEED_OF_LIGHT * BOLTZMANN * 300.0 / l.powi(4)) * x / x.exp_m1();
            let direct = b.spectral_radiance(l);
            assert!((log_form / direct - 1.0).abs() < 1e-13, "{l}: {log_form} vs {direct}");
        }
    }

    #[test]
    fn planck_finite_everywhere() {
        for &t in &[1e-300, 1e-3, 300.0, 5778.0, 1e12] {
            let b = Blackbody::new(t).unwrap();
            for e in -320..=300 {
                let l = 10f64.powi(e);
                let v = b.spectral_radiance(l);
                assert!(v.is_finite() && v >= 0.0, "T = {t}, l = {l}: {v}");
            }
            assert!(b.spectral_radiance(f64::MIN_POSITIVE / 4.0).is_finite());
            assert!(b.spectral_radiance(f64::MAX).is_finite());
            assert!(b.spectral_radiance(b.peak_wavelength()).is_finite());
            assert_eq!(b.spectral_radiance(0.0), 0.0);
            assert_eq!(b.spectral_radiance(-1.0), 0.0);
        }
    }

    #[test]
    fn planck_rayleigh_jeans_limit() {
        // Long wavelengths: B → 2ckT/λ⁴. At 1 m and 300 K, x = 4.8e-5 so the relative correction
        // is x/2 = 2.4e-5.
        let b = Blackbody::new(300.0).unwrap();
        let l = 1.0;
        let rj = 2.0 * SPEED_OF_LIGHT * BOLTZMANN * 300.0 / l;
        let x = SECOND_RADIATION_CONSTANT / l / 300.0;
        assert!((b.spectral_radiance(l) / rj - (1.0 - x / 2.0)).abs() < 1e-9);
    }
}
