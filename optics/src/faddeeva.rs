//! A fast scaled complementary error function `erfcx(z) = e^{z²} erfc(z)` for `Re z ≥ 0`, the
//! closed-form engine's inner kernel, by Weideman's rational series (J. A. C. Weideman,
//! "Computation of the complex error function", SIAM J. Numer. Anal. 31 (1994) 1497–1518):
//!
//! ```text
//! w(ζ) = 2 p(Z)/(L − iζ)² + 1/(√π (L − iζ)),   Z = (L + iζ)/(L − iζ),   Im ζ ≥ 0,
//! ```
//!
//! with `p` a polynomial of degree `N − 1` whose coefficients are the Fourier coefficients of
//! `(L² + t²) e^{−t²}`, `t = L tan(θ/2)`, and `L = 2^{−1/4} √N`; `erfcx(z) = w(iz)`. With
//! `N = 36` the series is one complex division and a 36-term complex Horner sum (2.4e-14 from
//! the package over |z| ≤ 12), about a quarter of the cost of the general algorithm of the
//! `errorfunctions` crate (S. G. Johnson's Faddeeva package, the reference the tests check
//! against). Beyond `|z| = 12`, where the series' relative error grows, the asymptotic series
//! (12 terms) takes over.

use std::f64::consts::{FRAC_2_SQRT_PI, PI};
use std::sync::OnceLock;

use num_complex::Complex64;

use crate::complex4::{Complexes, Lanes, mul_add_fused, mul_fused};

/// Most terms of the series (the full-accuracy one).
const N: usize = 36;

/// The series' orders and their relative error bounds over `|z| ≤ SERIES_RADIUS`, `Re z ≥ 0`
/// (measured against the Faddeeva package on a polar grid: 1.4e-8, 4.2e-10, 1.2e-11, 3.1e-13 and
/// 2.0e-14, the bounds stated here with a margin of 2.5–5; the test
/// `every_order_meets_its_bound` checks them). Each order is a multiple of four (four Horner
/// chains); the error falls about tenfold per 2.3 terms.
const ORDERS: [(usize, f64); 5] = [(20, 5e-8), (24, 2e-9), (28, 5e-11), (32, 1e-12), (36, 1e-13)];
const _: () = {
    let mut i = 0;
    while i < ORDERS.len() {
        assert!(ORDERS[i].0.is_multiple_of(4) && ORDERS[i].0 <= N, "four Horner chains");
        i += 1;
    }
};

/// Beyond this `|z|` the asymptotic series is used.
const SERIES_RADIUS: f64 = 12.0;

/// Terms of the asymptotic series beyond [`SERIES_RADIUS`]: the first omitted one is
/// `(2K−1)!!/(2|z|²)^K` = 1e-18 at `K = 12`, `|z| = 12`.
const ASYMPTOTIC_TERMS: usize = 12;

/// Weideman's series of one order: `erfcx` to a stated relative error, for a caller whose
/// error budget allows fewer terms than the full-accuracy [`erfcx`] (the closed form at a
/// tolerance of 1e-6 or 1e-7, see `closed::GaussianDefocus::otf_estimated`).
#[derive(Debug)]
pub struct Erfcx {
    l: f64,
    /// `b_k = a_{k+1}`: `p(Z) = Σ_k b_k Z^k`, the first `terms` used
    coefficients: [f64; N],
    terms: usize,
    relative_error: f64,
}

fn orders() -> &'static [Erfcx; ORDERS.len()] {
    static SERIES: OnceLock<[Erfcx; ORDERS.len()]> = OnceLock::new();
    SERIES.get_or_init(|| {
        ORDERS.map(|(terms, relative_error)| {
            // Weideman's `cef`: M = 2N, θ_k = kπ/M (k = −M+1 … M−1), f_k = e^{−t²}(L² + t²),
            // a_n = Re(Σ_k f_k e^{−inθ_k}) / (2M) (the FFT of the shifted samples, done directly)
            let m = 2 * terms;
            let l = (terms as f64 / 2f64.sqrt()).sqrt();
            let mut coefficients = [0.0; N];
            for (n, slot) in coefficients[..terms].iter_mut().enumerate() {
                let mut sum = 0.0;
                for k in -(m as i64) + 1..m as i64 {
                    let theta = k as f64 * PI / m as f64;
                    let t = l * (0.5 * theta).tan();
                    let f = (-t * t).exp() * (l * l + t * t);
                    sum += f * ((n + 1) as f64 * theta).cos();
                }
                *slot = sum / (2 * m) as f64;
            }
            Erfcx { l, coefficients, terms, relative_error }
        })
    })
}

impl Erfcx {
    /// The series of fewest terms whose relative error is within `relative_error` (the full one,
    /// 1e-13, where none is).
    pub fn within(relative_error: f64) -> &'static Erfcx {
        let all = orders();
        all.iter().find(|s| s.relative_error <= relative_error).unwrap_or(&all[all.len() - 1])
    }

    /// The bound on its relative error over the half-plane `Re z ≥ 0`.
    pub fn relative_error(&self) -> f64 {
        self.relative_error
    }

    /// `erfcx(z)` for `Re z ≥ 0`, to [`relative_error`](Self::relative_error).
    pub fn eval(&self, z: Complex64) -> Complex64 {
        debug_assert!(z.re >= 0.0, "erfcx series used for Re z < 0: {z}");
        if z.norm_sqr() > SERIES_RADIUS * SERIES_RADIUS {
            return asymptotic(z);
        }
        // ζ = iz
        let zeta = Complex64::new(-z.im, z.re);
        let denominator = Complex64::new(self.l + zeta.im, -zeta.re); // L − iζ
        let inv = denominator.inv();
        // (the complex products and sums in fused multiply-adds, `complex4::mul_fused` and
        // `mul_add_fused`: four operations a product where `num_complex` takes six, and a product
        // and a sum in four where it takes eight)
        let big_z = mul_fused(Complex64::new(self.l - zeta.im, zeta.re), inv); // (L + iζ)/(L − iζ)
        // p(Z) = Σ_j Z^j P_j(Z⁴), four independent Horner chains (the single chain is latency-bound)
        let z2 = mul_fused(big_z, big_z);
        let y = mul_fused(z2, z2);
        let mut chains = [Complex64::new(0.0, 0.0); 4];
        for block in self.coefficients[..self.terms].chunks_exact(4).rev() {
            for (acc, &b) in chains.iter_mut().zip(block) {
                *acc = horner_step(*acc, y, b);
            }
        }
        // p = (c0 + Z c1) + Z² (c2 + Z c3)
        let p =
            mul_add_fused(z2, mul_add_fused(big_z, chains[3], chains[2]), mul_add_fused(big_z, chains[1], chains[0]));
        // 2p/(L − iζ)² + 1/(√π (L − iζ)) (1/√π as a product: a division costs as much as four
        // terms of the series)
        mul_add_fused(mul_fused(2.0 * p, inv), inv, inv * (0.5 * FRAC_2_SQRT_PI))
    }
}

impl Erfcx {
    /// [`eval`](Self::eval) at four or eight points (the lanes of `V`), by the same operations in
    /// the same order on each lane (each lane is the scalar value to the last bit); `None` where
    /// a lane lies beyond `SERIES_RADIUS` (the asymptotic series: the caller takes the lanes one
    /// by one).
    #[inline(always)]
    pub(crate) fn eval_lanes<V: Lanes>(&self, z: Complexes<V>) -> Option<Complexes<V>> {
        if z.norm_sqr().simd_gt(V::splat(SERIES_RADIUS * SERIES_RADIUS)).any() {
            return None;
        }
        let l = V::splat(self.l);
        // ζ = iz; L − iζ and (L + iζ)/(L − iζ)
        let (zeta_re, zeta_im) = (-z.im, z.re);
        let denominator = Complexes { re: l + zeta_im, im: -zeta_re };
        let inv = denominator.inv();
        let big_z = Complexes { re: l - zeta_im, im: zeta_re }.mul_fused(inv);
        let z2 = big_z.mul_fused(big_z);
        let y = z2.mul_fused(z2);
        let mut chains = [Complexes::<V>::ZERO; 4];
        for block in self.coefficients[..self.terms].chunks_exact(4).rev() {
            for (acc, &b) in chains.iter_mut().zip(block) {
                *acc = acc.mul_add_real(y, V::splat(b));
            }
        }
        let p = z2.mul_add(big_z.mul_add(chains[3], chains[2]), big_z.mul_add(chains[1], chains[0]));
        let twice_p_inv = p.scale(V::splat(2.0)).mul_fused(inv);
        Some(twice_p_inv.mul_add(inv, inv.scale(V::splat(0.5 * FRAC_2_SQRT_PI))))
    }
}

/// One step `acc × y + b` (`b` real) of the series' Horner sums in fused multiply-adds where the
/// target has them ([`crate::complex4::fused`]): `re = re_a re_y − im_a im_y + b` with one
/// rounding a product pair instead of three, `im = re_a im_y + im_a re_y` with two instead of
/// three; four operations instead of seven (the complex product and the sum). Its rounding is
/// no larger than the unfused step's (a few ulp of the terms), far below the orders' bounds
/// (test `every_order_meets_its_bound`); [`Complexes::mul_add_real`] is it lane by lane.
#[inline(always)]
fn horner_step(acc: Complex64, y: Complex64, b: f64) -> Complex64 {
    use crate::complex4::fused;
    Complex64::new(fused(acc.re, y.re, fused(-acc.im, y.im, b)), fused(acc.re, y.im, acc.im * y.re))
}

/// `erfcx(z) = e^{z²} erfc(z)` for `Re z ≥ 0` (bounded by 1 there), to about 1e-13 relative.
pub fn erfcx(z: Complex64) -> Complex64 {
    let all = orders();
    all[all.len() - 1].eval(z)
}

/// `erfcx(z) ~ (1/(z√π)) Σ_k (−1)^k (2k−1)!!/(2z²)^k` (Abramowitz & Stegun 7.1.23), valid for
/// `|arg z| < 3π/4`, so on the whole half-plane `Re z ≥ 0`; the test checks it against the
/// package to 1e-13 for `12 ≤ |z| ≤ 1.2e7` there.
fn asymptotic(z: Complex64) -> Complex64 {
    let inv_2z2 = (2.0 * z * z).inv();
    let mut term = Complex64::new(1.0, 0.0);
    let mut sum = term;
    for k in 1..ASYMPTOTIC_TERMS {
        term *= -inv_2z2 * (2 * k - 1) as f64;
        sum += term;
    }
    sum / (z * PI.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use errorfunctions::erfcx_with_relerror;

    #[test]
    fn series_matches_the_faddeeva_package_over_the_right_half_plane() {
        // a polar grid over |z| ≤ SERIES_RADIUS, Re z ≥ 0, dense near the axes and the origin
        let mut worst: f64 = 0.0;
        for i in 0..=400 {
            let r = SERIES_RADIUS * (i as f64 / 400.0).powi(2);
            for j in 0..=180 {
                let angle = -0.5 * PI + PI * j as f64 / 180.0;
                let z = Complex64::from_polar(r, angle);
                let z = Complex64::new(z.re.max(0.0), z.im);
                let fast = erfcx(z);
                let exact = erfcx_with_relerror(z, 1e-15);
                worst = worst.max((fast - exact).norm() / exact.norm());
            }
        }
        assert!(worst < 1e-13, "worst relative error {worst:e}");
    }

    /// Each order of [`Erfcx`] within its stated relative error of the package over the polar
    /// grid of the test above (|z| ≤ SERIES_RADIUS) and beyond it (the asymptotic series), and
    /// [`Erfcx::within`] picks the fewest terms that meet the error asked.
    #[test]
    fn every_order_meets_its_bound() {
        for &(terms, bound) in &ORDERS {
            let series = Erfcx::within(bound);
            assert_eq!(series.terms, terms);
            let mut worst: f64 = 0.0;
            for i in 0..=200 {
                let r = 1.5 * SERIES_RADIUS * (i as f64 / 200.0).powi(2);
                for j in 0..=90 {
                    let z = Complex64::from_polar(r, -0.5 * PI + PI * j as f64 / 90.0);
                    let z = Complex64::new(z.re.max(0.0), z.im);
                    let exact = erfcx_with_relerror(z, 1e-15);
                    worst = worst.max((series.eval(z) - exact).norm() / exact.norm());
                }
            }
            println!("{terms} terms: worst relative error {worst:.1e} (bound {bound:e})");
            assert!(worst <= bound, "{terms} terms: {worst:e} > {bound:e}");
            // the bound is not vacuous: within 10× of the measured error
            assert!(worst > 0.1 * bound, "{terms} terms: {worst:e} far below {bound:e}");
        }
        assert_eq!(Erfcx::within(2e-9).terms, 24);
        assert_eq!(Erfcx::within(1e-9).terms, 28);
        assert_eq!(Erfcx::within(1e-20).terms, N);
    }

    #[test]
    fn asymptotic_series_matches_the_faddeeva_package_beyond_its_radius() {
        let mut worst: f64 = 0.0;
        for i in 0..=200 {
            let r = SERIES_RADIUS * 10f64.powf(6.0 * i as f64 / 200.0);
            for j in 0..=180 {
                let z = Complex64::from_polar(r, -0.5 * PI + PI * j as f64 / 180.0);
                let z = Complex64::new(z.re.max(0.0), z.im);
                let exact = erfcx_with_relerror(z, 1e-15);
                worst = worst.max((erfcx(z) - exact).norm() / exact.norm());
            }
        }
        assert!(worst < 1e-13, "worst relative error {worst:e}");
    }

    #[test]
    fn known_values() {
        // erfcx(0) = 1; erfcx(x) for real x: erfcx(1) = 0.427583576155807 (A&S 7.1; libm erfc)
        assert!((erfcx(Complex64::new(0.0, 0.0)) - 1.0).norm() < 1e-15);
        let x = 1.0_f64;
        let expected = (x * x).exp() * libm::erfc(x);
        assert!((erfcx(Complex64::new(x, 0.0)).re - expected).abs() < 1e-14);
        // on the imaginary axis erfcx(iy) = e^{−y²} − (2i/√π) F(y), F Dawson's integral:
        // F(3) = 0.178271030610558 (A&S table 7.5)
        let y = 3.0_f64;
        let v = erfcx(Complex64::new(0.0, y));
        assert!((v.re - (-y * y).exp()).abs() < 1e-14, "{v}");
        assert!((v.im + 2.0 / PI.sqrt() * 0.178_271_030_610_558).abs() < 1e-13, "{v}");
    }
}
