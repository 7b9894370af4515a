//! Monochromatic transfer functions of a circular pupil: the exact defocused OTF, the
//! aberration-free MTF and the pixel-aperture MTF.
//!
//! Conventions (docs/physics.md, "The OTF"): `s = ν/ν_c(λ)` is the frequency
//! normalized to the incoherent cutoff `ν_c = 1/(λ F#)`; `w = W020/λ` is the defocus in waves at
//! the pupil edge. The OTF is normalized to 1 at `s = 0`, is real for a centred circular pupil
//! with defocus only, may be negative, and is zero for `s ≥ 1`.

use std::f64::consts::{FRAC_2_PI, PI};

use crate::quad;

/// Aberration-free MTF of a circular pupil: `MTF_0(s) = (2/π)[acos s − s √(1 − s²)]`.
///
/// Returns 1 for `s ≤ 0` and 0 for `s ≥ 1` (docs/physics.md: limit `a → 0` of the defocused OTF).
pub fn mtf_diffraction_limited(s: f64) -> f64 {
    if s <= 0.0 {
        1.0
    } else if s >= 1.0 {
        0.0
    } else {
        FRAC_2_PI * (s.acos() - s * (1.0 - s * s).sqrt())
    }
}

/// Mean of [`mtf_diffraction_limited`] over `[0, s_max]` in closed form.
///
/// `∫ acos s ds = s acos s − √(1 − s²)` and `∫ s √(1 − s²) ds = −(1 − s²)^{3/2}/3`, so
/// `∫_0^x MTF_0 ds = (2/π)[x acos x − √(1 − x²) + 1 − (1 − (1 − x²)^{3/2})/3]`, which is
/// `4/(3π)` at `x = 1` (docs/physics.md, "Test vectors and identities"). Past the cutoff the MTF is zero.
pub fn mtf_diffraction_limited_mean(s_max: f64) -> f64 {
    if s_max <= 0.0 {
        return 1.0;
    }
    let x = s_max.min(1.0);
    let r = (1.0 - x * x).sqrt();
    let area = FRAC_2_PI * (x * x.acos() - r + 1.0 - (1.0 - r * r * r) / 3.0);
    area / s_max
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
/// docs/physics.md gives `OTF(s, w) = 4/(π a) ∫_0^{acos s} sin[a(cos t − s)] cos t dt` with `a = 8π w s`.
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
    if a.abs() >= BESSEL_SERIES_MIN_A {
        return defocus_otf_bessel(s, a);
    }
    defocus_otf_quadrature(s, w)
}

/// `|a|` from which [`defocus_otf`] sums the Bessel series instead of integrating: there the
/// series costs a few multiply-adds per term where the quadrature costs a sine and a cosine
/// per node, and the two agree to rounding error (tested).
pub const BESSEL_SERIES_MIN_A: f64 = 24.0;

/// [`defocus_otf`] by composite Gauss–Legendre quadrature of
/// `(4/π) ∫_0^{acos s} sin²t cos[a(cos t − s)] dt` with [`defocus_otf_panels`] panels, for any `a`.
pub fn defocus_otf_quadrature(s: f64, w: f64) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let a = 8.0 * PI * w * s;
    let theta = s.acos();
    let panels = defocus_otf_panels(s, w);
    let integral = quad::composite(0.0, theta, panels, |t| {
        let (sin_t, cos_t) = t.sin_cos();
        sin_t * sin_t * (a * (cos_t - s)).cos()
    });
    (4.0 / PI) * integral
}

/// [`defocus_otf`] by the Jacobi–Anger expansion `e^{i a cos t} = J0(a) + 2 Σ_{n≥1} iⁿ Jn(a) cos nt`
/// (the route of Hopkins' Bessel series), integrated term by term:
///
/// ```text
/// OTF = (4/π) [ cos(a s) (J0 C0 + 2 Σ_{n even} (−1)^{n/2} Jn Cn) + sin(a s) 2 Σ_{n odd} (−1)^{(n−1)/2} Jn Cn ]
/// Cn  = ∫_0^θ sin²t cos nt dt = ½ S(n) − ¼ [S(n+2) + S(n−2)],  S(m) = sin(mθ)/m, S(0) = θ,  θ = acos s
/// ```
///
/// `Jn(a)` for all `n` by Miller's backward recurrence normalized with `J0 + 2 Σ J2k = 1`,
/// started where `Jn(a) < 1e-17`; `sin(mθ)` by the Chebyshev recurrence. For `|a| ≥ 1`.
pub fn defocus_otf_bessel(s: f64, a: f64) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let x = a.abs();
    // Jn(x) < 1e-17 for n ≥ x + 12 x^{1/3} + 24 (the Debye decay past the turning point n = x)
    let n_max = (x + 12.0 * x.cbrt() + 24.0) as usize;
    let start = n_max + 16;
    let mut j = vec![0.0_f64; start + 2];
    j[start] = 1e-300;
    let two_over_x = 2.0 / x;
    for n in (1..=start).rev() {
        let next = (n as f64) * two_over_x * j[n] - j[n + 1];
        j[n - 1] = next;
        if next.abs() > 1e250 {
            for v in &mut j[n - 1..] {
                *v *= 1e-250;
            }
        }
    }
    let norm = j[0] + 2.0 * j[2..=start].iter().step_by(2).sum::<f64>();
    let theta = s.acos();
    let two_cos = 2.0 * s; // 2 cos θ
    // S(m) = sin(mθ)/m for m = 0..=n_max+2, with S(0) = θ
    let (mut sin_prev, mut sin_cur) = (0.0_f64, theta.sin()); // sin(0·θ), sin(1·θ)
    let mut sines = Vec::with_capacity(n_max + 3);
    sines.push(0.0);
    sines.push(sin_cur);
    for _ in 2..=n_max + 2 {
        let next = two_cos * sin_cur - sin_prev;
        sin_prev = sin_cur;
        sin_cur = next;
        sines.push(next);
    }
    let big_s = |m: usize| if m == 0 { theta } else { sines[m] / m as f64 };
    let c = |n: usize| 0.5 * big_s(n) - 0.25 * (big_s(n + 2) + big_s(n.abs_diff(2)));
    let (mut even, mut odd) = (j[0] * c(0), 0.0);
    for (n, &jn) in j.iter().enumerate().take(n_max + 1).skip(1) {
        let term = 2.0 * jn * c(n);
        match n % 4 {
            0 => even += term,
            1 => odd += term,
            2 => even -= term,
            _ => odd -= term,
        }
    }
    // odd terms change sign with a (Jn(−x) = (−1)ⁿ Jn(x)); sin(a s) does too: the product is even
    let (sin_as, cos_as) = (x * s).sin_cos();
    (4.0 / PI) * (cos_as * even + sin_as * odd) / norm
}

/// Pixel-aperture MTF `|sinc(p ν)| = |sin(π p ν)/(π p ν)|` of a square pixel of pitch `p` with
/// 100 % fill factor, along a pixel axis (`p` in m, `ν` in cycles/m).
pub fn pixel_mtf(pixel_pitch_m: f64, frequency: f64) -> f64 {
    let x = PI * pixel_pitch_m * frequency;
    if x.abs() < 1e-8 { 1.0 - x * x / 6.0 } else { (x.sin() / x).abs() }
}

/// Incoherent cutoff frequency `ν_c = 1/(λ F#)` in cycles/m.
pub fn cutoff_frequency(wavelength_m: f64, f_number: f64) -> f64 {
    1.0 / (wavelength_m * f_number)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn physics_test_vectors_hold_to_1e5() {
        for (s, w, expected) in crate::reference::PHYSICS_TEST_VECTORS {
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
    fn diffraction_limited_mean_closed_form() {
        // ∫_0^1 MTF_0 ds = 4/(3π) (docs/physics.md, "Test vectors and identities")
        assert!((mtf_diffraction_limited_mean(1.0) - 4.0 / (3.0 * PI)).abs() < 1e-15);
        // against quadrature of MTF_0 on [0, 0.37] (smooth there)
        let x = 0.37;
        let q = quad::composite(0.0, x, 4, mtf_diffraction_limited) / x;
        assert!((mtf_diffraction_limited_mean(x) - q).abs() < 1e-14);
        // past the cutoff the area stays 4/(3π)
        assert!((mtf_diffraction_limited_mean(2.0) - 2.0 / (3.0 * PI)).abs() < 1e-15);
    }

    #[test]
    fn bessel_series_matches_quadrature() {
        // two independent evaluations of the same integral, over the regime where both apply
        let mut worst: f64 = 0.0;
        for &w in &[0.05, 0.5, 2.0, 7.3, 31.0, 150.0, 1200.0] {
            for i in 1..60 {
                let s = i as f64 / 60.0;
                let a = 8.0 * PI * w * s;
                if a < 1.0 {
                    continue;
                }
                let d = (defocus_otf_bessel(s, a) - defocus_otf_quadrature(s, w)).abs();
                worst = worst.max(d);
            }
        }
        assert!(worst < 1e-12, "largest difference {worst:e}");
    }

    #[test]
    fn bessel_series_is_even_in_a() {
        assert!((defocus_otf_bessel(0.3, 40.0) - defocus_otf_bessel(0.3, -40.0)).abs() < 1e-15);
    }

    #[test]
    fn pixel_mtf_values() {
        // p ν = 1/2 (Nyquist): sinc = sin(π/2)/(π/2) = 2/π
        assert!((pixel_mtf(5.2e-6, 1.0 / (2.0 * 5.2e-6)) - 2.0 / PI).abs() < 1e-15);
        assert_eq!(pixel_mtf(5.2e-6, 0.0), 1.0);
    }
}
