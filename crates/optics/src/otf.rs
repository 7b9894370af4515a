//! Monochromatic transfer functions of a circular pupil: the exact defocused OTF, the
//! aberration-free MTF and the pixel-aperture MTF.
//!
//! Conventions (`shared/PHYSICS.md`, "Optics: the OTF"): `s = ν/ν_c(λ)` is the frequency
//! normalized to the incoherent cutoff `ν_c = 1/(λ F#)`; `w = W020/λ` is the defocus in waves at
//! the pupil edge. The OTF is normalized to 1 at `s = 0`, is real for a centred circular pupil
//! with defocus only, may be negative, and is zero for `s ≥ 1`.

use std::f64::consts::{FRAC_2_PI, PI};

use crate::quad;

/// Aberration-free MTF of a circular pupil: `MTF_0(s) = (2/π)[acos s − s √(1 − s²)]`.
///
/// Returns 1 for `s ≤ 0` and 0 for `s ≥ 1` (PHYSICS.md, limit `a → 0` of the defocused OTF).
pub fn mtf_diffraction_limited(s: f64) -> f64 {
    if s <= 0.0 {
        1.0
    } else if s >= 1.0 {
        0.0
    } else {
        FRAC_2_PI * (s.acos() - s * (1.0 - s * s).sqrt())
    }
}

/// Number of Gauss–Legendre panels [`defocus_otf`] uses at `(s, w)`.
///
/// With `y = cos t` in the pupil-overlap integral the phase is `φ(t) = a (cos t − s)`,
/// `a = 8π w s`, on `t ∈ [0, acos s]`; its rate is at most `|a| sin(acos s)`. The panel count keeps
/// the phase turned through by any panel under [`quad::MAX_PANEL_PHASE`], so it grows linearly
/// with defocus and the error stays at rounding level for any `w`.
pub fn defocus_otf_panels(s: f64, w: f64) -> usize {
    if !(s > 0.0 && s < 1.0) {
        return 0;
    }
    let a = 8.0 * PI * w * s;
    let theta = s.acos();
    let turn = a.abs() * theta.sin() * theta;
    (turn / quad::MAX_PANEL_PHASE).ceil().max(1.0) as usize
}

/// Exact OTF of a centred circular pupil with defocus `w` waves (`W020/λ`) at normalized
/// frequency `s`.
///
/// PHYSICS.md gives `OTF(s, w) = 4/(π a) ∫_0^{acos s} sin[a(cos t − s)] cos t dt` with `a = 8π w s`.
/// We integrate the same overlap integral before the integration by parts,
/// `OTF(s, w) = (4/π) ∫_0^{acos s} sin²t · cos[a(cos t − s)] dt`,
/// which has no `1/a` (so no special case at `a = 0`) and a smooth, bounded integrand: composite
/// Gauss–Legendre converges to rounding error with [`defocus_otf_panels`] panels.
/// The result is even in `w`, 1 at `s ≤ 0` and 0 at `s ≥ 1`.
pub fn defocus_otf(s: f64, w: f64) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let a = 8.0 * PI * w * s;
    // Largest phase reached: |a| (1 − s). Below 1e-8 the cosine is 1 to 5e-17.
    if a.abs() * (1.0 - s) < 1e-8 {
        return mtf_diffraction_limited(s);
    }
    let theta = s.acos();
    let panels = defocus_otf_panels(s, w);
    let integral = quad::composite(0.0, theta, panels, |t| {
        let (sin_t, cos_t) = t.sin_cos();
        sin_t * sin_t * (a * (cos_t - s)).cos()
    });
    (4.0 / PI) * integral
}

/// Pixel-aperture MTF `|sinc(p ν)| = |sin(π p ν)/(π p ν)|` of a square pixel of pitch `p` with
/// 100 % fill factor, along a pixel axis (`p` in m, `ν` in cycles/m).
pub fn pixel_mtf(pixel_pitch_m: f64, frequency: f64) -> f64 {
    let x = PI * pixel_pitch_m * frequency;
    if x.abs() < 1e-8 {
        1.0 - x * x / 6.0
    } else {
        (x.sin() / x).abs()
    }
}

/// Incoherent cutoff frequency `ν_c = 1/(λ F#)` in cycles/m.
pub fn cutoff_frequency(wavelength_m: f64, f_number: f64) -> f64 {
    1.0 / (wavelength_m * f_number)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PHYSICS.md test vectors (s, w → OTF), quoted to 5 decimals there.
    const VECTORS: [(f64, f64, f64); 7] = [
        (0.1, 0.0, 0.87289),
        (0.1, 0.5, 0.74209),
        (0.1, 1.0, 0.42665),
        (0.2, 1.0, -0.01441),
        (0.5, 0.25, 0.28747),
        (0.05, 2.0, 0.41297),
        (0.1, 2.0, -0.08396),
    ];

    #[test]
    fn physics_test_vectors_hold_to_1e5() {
        for (s, w, expected) in VECTORS {
            let got = defocus_otf(s, w);
            assert!((got - expected).abs() < 1e-5, "OTF({s}, {w}) = {got}, expected {expected}");
        }
    }

    #[test]
    fn zero_defocus_is_the_diffraction_limited_mtf() {
        for i in 1..100 {
            let s = i as f64 / 100.0;
            // a tiny but non-zero defocus takes the quadrature branch
            let q = defocus_otf(s, 1e-6);
            assert!((q - mtf_diffraction_limited(s)).abs() < 1e-11, "s = {s}");
        }
    }

    #[test]
    fn even_in_defocus_and_bounded() {
        for &w in &[0.1, 0.7, 3.0, 40.0] {
            for i in 0..=50 {
                let s = i as f64 / 50.0;
                let p = defocus_otf(s, w);
                assert_eq!(p, defocus_otf(s, -w));
                assert!(p.abs() <= 1.0 + 1e-15 && p.is_finite());
            }
        }
    }

    #[test]
    fn panel_count_grows_with_defocus() {
        assert_eq!(defocus_otf_panels(0.3, 0.0), 1);
        let small = defocus_otf_panels(0.3, 1.0);
        let large = defocus_otf_panels(0.3, 1000.0);
        assert!(large > 100 * small, "{small} → {large}");
    }

    #[test]
    fn pixel_mtf_values() {
        // p ν = 1/2 (Nyquist): sinc = sin(π/2)/(π/2) = 2/π
        assert!((pixel_mtf(5.2e-6, 1.0 / (2.0 * 5.2e-6)) - 2.0 / PI).abs() < 1e-15);
        assert_eq!(pixel_mtf(5.2e-6, 0.0), 1.0);
    }
}
