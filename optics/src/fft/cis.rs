//! `a e^{iφ}` for a row of pupil samples at once (the pupil field of every FFT grid), and the
//! sine and cosine behind it (also the exact OTF's quadrature in the pupil angle, and the
//! closed form's pupil angle and complex exponentials, `closed.rs`).
//!
//! glibc's `sincos` costs ~20 ns a call (it saves and restores the rounding mode around its
//! range reduction), a third of the FFT path's time. A row of the pupil field ([`fill`]) is
//! computed four samples at a time by the `wide` crate's `f64x4::sin_cos` (Agner Fog's vector
//! class library: Cody–Waite reduction, minimax polynomials), 2.4 times the speed of the scalar
//! [`sin_cos`] here at the same accuracy (`cargo bench -p asnr-optics --bench sincos`). The
//! scalar one serves single phases: the reduction is Cody–Waite's with π/2 in three parts and the
//! sine and cosine are fdlibm's minimax polynomials on `|r| ≤ π/4` of degrees 13 and 12 in `r`
//! (truncation within 2⁻⁵⁸; Horner's rule in fused multiply-adds), without branches. Both are
//! accurate to a few ulp of 1 for `|φ| ≤ 1e5` rad, the defocus-phase budget (tested against
//! `f64::sin_cos`).

use num_complex::Complex64;

/// π/2 in three parts (each exact in fewer bits, so `q · part` is exact for `|q| < 2^20`).
const PIO2_1: f64 = 1.570_796_326_734_125_6;
const PIO2_2: f64 = 6.077_100_506_303_966e-11;
const PIO2_3: f64 = 2.022_266_248_795_950_6e-21;

/// Adding and subtracting this rounds to the nearest integer (for magnitudes below 2^51).
const ROUND: f64 = 6_755_399_441_055_744.0;

/// `(sin φ, cos φ)`, branch-free (module docs): within 4e-16 of `f64::sin_cos` for
/// `|φ| < 1e3` rad and 1e-16 relative to `|φ|` up to 1e6. Public for the benchmark against the
/// `wide` crate's vector sine and cosine (`cargo bench -p asnr-optics --bench sincos`).
#[inline(always)]
pub fn sin_cos(phi: f64) -> (f64, f64) {
    let q = (phi * std::f64::consts::FRAC_2_PI + ROUND) - ROUND;
    let r = ((phi - q * PIO2_1) - q * PIO2_2) - q * PIO2_3;
    let (s, c) = kernel(r, crate::complex4::fused, |x| x);
    // the quadrant: φ = q π/2 + r
    let quadrant = (q as i64) & 3;
    let (sin, cos) = if quadrant & 1 == 0 { (s, c) } else { (c, -s) };
    let flip = if quadrant & 2 == 0 { 1.0 } else { -1.0 };
    (flip * sin, flip * cos)
}

/// fdlibm's minimax polynomials for the sine and cosine on `|r| ≤ π/4` (`k_sin.c`,
/// `k_cos.c`, Sun Microsystems 1993; FreeBSD `lib/msun/src`): `sin r ≈ r + r³ S(r²)` and
/// `cos r ≈ 1 − r²/2 + r⁴ C(r²)`, each of degree five in `r²`, their truncation within 2⁻⁵⁸ of
/// the functions there (docs/physics.md, "The sine and cosine").
const SIN: [f64; 6] = [
    -0.16666666666666632,
    0.00833333333332249,
    -0.0001984126982985795,
    2.7557313707070068e-06,
    -2.5050760253406863e-08,
    1.58969099521155e-10,
];
/// See [`SIN`].
const COS: [f64; 6] = [
    0.0416666666666666,
    -0.001388888888887411,
    2.480158728947673e-05,
    -2.7557314351390663e-07,
    2.087572321298175e-09,
    -1.1359647557788195e-11,
];

/// `(sin r, cos r)` for the reduced `|r| ≤ π/4` by [`SIN`] and [`COS`] in Horner's rule, each
/// step one `fused` multiply-add (one rounding where the target has FMA): the scalar
/// [`sin_cos`] and each lane of [`sin_cos_lanes`] by the same operations in the same order.
#[inline(always)]
fn kernel<T: Copy + std::ops::Mul<Output = T>>(r: T, fused: impl Fn(T, T, T) -> T, k: impl Fn(f64) -> T) -> (T, T) {
    let z = r * r;
    let mut s = k(SIN[5]);
    let mut c = k(COS[5]);
    for i in (0..5).rev() {
        s = fused(s, z, k(SIN[i]));
        c = fused(c, z, k(COS[i]));
    }
    // r + r³ S, and 1 − z/2 + z² C (1 − z/2 rounded once: within half an ulp of 1)
    (fused(r * z, s, r), fused(z * z, c, fused(z, k(-0.5), k(1.0))))
}

/// [`sin_cos`] on four lanes, by the same operations in the same order on each (the quadrant
/// `q mod 4` computed exactly in floating point), so each lane is the scalar result to the last
/// bit: the closed form's pupil angle and complex exponentials at four nodes at once.
#[inline(always)]
pub(crate) fn sin_cos4(phi: wide::f64x4) -> (wide::f64x4, wide::f64x4) {
    sin_cos_lanes(phi)
}

/// [`sin_cos`] on the lanes of `V` (four or eight), by the same operations in the same order on
/// each lane.
#[inline(always)]
pub(crate) fn sin_cos_lanes<V: crate::complex4::Lanes>(phi: V) -> (V, V) {
    let k = V::splat;
    let q = (phi * k(std::f64::consts::FRAC_2_PI) + k(ROUND)) - k(ROUND);
    let r = ((phi - q * k(PIO2_1)) - q * k(PIO2_2)) - q * k(PIO2_3);
    let (s, c) = kernel(r, |a: V, b: V, c: V| a.fused(b, c), k);
    // the quadrant q mod 4 ∈ {0, 1, 2, 3} (exact: q is an integer below 2^51, and so are its
    // quarter's floor and four times it), as `(q as i64) & 3` for either sign of q
    let quadrant = q - k(4.0) * (q * k(0.25)).floor();
    let odd = quadrant.simd_eq(k(1.0)) | quadrant.simd_eq(k(3.0));
    let (sin, cos) = (odd.select(c, s), odd.select(-s, c));
    let flip = quadrant.simd_ge(k(2.0)).select(k(-1.0), k(1.0));
    (flip * sin, flip * cos)
}

/// `out[i] = a[i] e^{i k w[i]}` where `a[i] > 0`, else 0: four samples at a time by the `wide`
/// crate's `f64x4::sin_cos` (2.4 times the speed of [`sin_cos`] over a row, as accurate:
/// `cargo bench -p asnr-optics --bench sincos`, ARCHITECTURE.md), the last `len % 4` by
/// [`sin_cos`].
pub(crate) fn fill(out: &mut [Complex64], amplitude: &[f64], k: f64, opd: &[f64]) {
    let n = out.len().min(amplitude.len()).min(opd.len());
    let (out, amplitude, opd) = (&mut out[..n], &amplitude[..n], &opd[..n]);
    let split = n - n % 4;
    let k4 = wide::f64x4::splat(k);
    for ((o, a), w) in out[..split].chunks_exact_mut(4).zip(amplitude.chunks_exact(4)).zip(opd.chunks_exact(4)) {
        let (s, c) = (k4 * wide::f64x4::new([w[0], w[1], w[2], w[3]])).sin_cos();
        let a = wide::f64x4::new([a[0], a[1], a[2], a[3]]).max(wide::f64x4::ZERO);
        let (re, im) = ((a * c).to_array(), (a * s).to_array());
        for l in 0..4 {
            o[l] = Complex64::new(re[l], im[l]);
        }
    }
    for ((o, &a), &w) in out[split..].iter_mut().zip(&amplitude[split..]).zip(&opd[split..]) {
        let (s, c) = sin_cos(k * w);
        let a = if a > 0.0 { a } else { 0.0 };
        *o = Complex64::new(a * c, a * s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against `f64::sin_cos` over the phases the FFT path meets and far beyond: within 4e-16
    /// absolute below 1e3 rad, and within the reduction's 1e-16 relative to |φ| up to 1e6.
    #[test]
    fn matches_the_library_sin_cos() {
        let mut worst_small: f64 = 0.0;
        let mut worst_large: f64 = 0.0;
        let mut x: f64 = 0.123_456_789;
        for i in 0..200_000 {
            // spread over ±1e6 rad, denser near 0
            let phi = if i % 2 == 0 { (x - 0.5) * 2e3 } else { (x - 0.5) * 2e6 };
            x = (x * 3.987_654_321 + 0.314_159).fract();
            let (s, c) = sin_cos(phi);
            let (s0, c0) = phi.sin_cos();
            let d = (s - s0).abs().max((c - c0).abs());
            if phi.abs() < 1e3 {
                worst_small = worst_small.max(d);
            } else {
                worst_large = worst_large.max(d / phi.abs());
            }
        }
        assert!(worst_small < 4e-16, "{worst_small:e}");
        assert!(worst_large < 1e-16, "{worst_large:e}");
        for phi in [0.0, -0.0, std::f64::consts::FRAC_PI_4, std::f64::consts::FRAC_PI_2, std::f64::consts::PI, -3.0] {
            let ((s, c), (s0, c0)) = (sin_cos(phi), phi.sin_cos());
            assert!((s - s0).abs() < 3e-16 && (c - c0).abs() < 3e-16, "{phi}");
        }
    }

    /// The row kernel (four lanes by `wide`, the rest by [`sin_cos`]) against `a e^{iφ}` by
    /// the standard library, on rows of every length 0–11 (each remainder) with opaque samples,
    /// NaN-free at a negative amplitude, phases to 1e5 rad.
    #[test]
    fn fill_matches_the_library_on_every_row_length() {
        for n in 0..12 {
            let amplitude: Vec<f64> = (0..n).map(|i| [0.7, 0.0, -0.2, 1.0][i % 4]).collect();
            let opd: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37 - 1.1) * 1e-6).collect();
            let k = 1e11;
            let mut out = vec![Complex64::new(9.0, 9.0); n];
            fill(&mut out, &amplitude, k, &opd);
            for i in 0..n {
                let want =
                    if amplitude[i] > 0.0 { Complex64::from_polar(amplitude[i], k * opd[i]) } else { 0.0.into() };
                assert!((out[i] - want).norm() < 1e-15, "n = {n}, i = {i}: {} vs {want}", out[i]);
            }
        }
    }

    #[test]
    fn fill_zeroes_the_opaque_samples() {
        let mut out = vec![Complex64::new(9.0, 9.0); 3];
        fill(&mut out, &[1.0, 0.0, 0.5], 2.0, &[0.25, 1.0, -0.5]);
        assert!((out[0] - Complex64::from_polar(1.0, 0.5)).norm() < 1e-16);
        assert_eq!(out[1], Complex64::new(0.0, 0.0));
        assert!((out[2] - Complex64::from_polar(0.5, -1.0)).norm() < 1e-16);
    }
}
