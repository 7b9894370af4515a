//! Composite Gauss–Legendre quadrature with a fixed rule per panel, and single Gauss–Legendre
//! and Gauss–Hermite rules of any order (for the accuracy report's fixed-order comparisons).
//!
//! Every integral in the fast path is a sum of panels, each integrated with the same
//! [`ORDER`]-point Gauss–Legendre rule (nodes from `gauss-quad`, Bogaert's algorithm). The
//! panel count, not the rule order, grows with the oscillation of the integrand: that keeps
//! the error bound uniform (a panel whose integrand turns through at most [`MAX_PANEL_PHASE`]
//! radians is integrated to about 1e-16) and the nodes cacheable.

use std::num::NonZeroUsize;
use std::sync::OnceLock;

/// Points of the Gauss–Legendre rule used on every panel.
pub const ORDER: usize = 16;

/// Largest phase (radians) of an oscillatory factor `cos(phase)` across one panel.
///
/// A 16-point Gauss–Legendre rule integrates `exp(i k x)` on `[-1, 1]` with an error of about
/// `(e k / 32)^32`; a panel phase of 12 rad is `k = 6`, an error below 1e-18.
pub const MAX_PANEL_PHASE: f64 = 12.0;

/// The [`ORDER`]-point rule on `[-1, 1]`: `(node, weight)` pairs, nodes ascending.
pub fn rule() -> &'static [(f64, f64); ORDER] {
    static RULE: OnceLock<[(f64, f64); ORDER]> = OnceLock::new();
    RULE.get_or_init(|| {
        let mut out = [(0.0, 0.0); ORDER];
        out.copy_from_slice(&gauss_legendre(ORDER));
        out
    })
}

/// The `n`-point Gauss–Legendre rule on `[-1, 1]` (`n ≥ 1`; 0 is taken as 1): `(node, weight)`
/// pairs, nodes ascending, exact for polynomials of degree `2n − 1`. Nodes and weights from
/// `gauss-quad` (Bogaert's O(n) algorithm, accurate to rounding for any `n`).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let n = NonZeroUsize::new(n).unwrap_or(NonZeroUsize::MIN);
    let mut pairs = gauss_quad::legendre::GaussLegendre::new(n).as_node_weight_pairs().to_vec();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs
}

/// The `n`-point Gauss–Hermite rule for `∫_{−∞}^{∞} e^{−x²} f(x) dx ≈ Σ wᵢ f(xᵢ)` (`n ≥ 1`; 0 is
/// taken as 1): `(node, weight)` pairs, nodes ascending, exact for polynomials `f` of degree
/// `2n − 1`. A Gaussian spectrum of centre μ and standard deviation σ takes the nodes
/// `λᵢ = μ + √2 σ xᵢ`.
///
/// Golub–Welsch (the eigenvalues of the Jacobi matrix, from `gauss-quad`) gives the nodes to a
/// few ulps of the largest; each is then polished by Newton's method on the orthonormal Hermite
/// recurrence (Press et al., *Numerical Recipes*, 3rd ed., §4.6, `gauher`)
///
/// ```text
/// p₀ = π^{−1/4},  p₁ = √2 x p₀,  pⱼ = √(2/j) x pⱼ₋₁ − √((j−1)/j) pⱼ₋₂,  pₙ' = √(2n) pₙ₋₁,
/// ```
///
/// and the weight taken from the same recurrence, `wᵢ = 2/pₙ'(xᵢ)²`, which keeps its relative
/// accuracy even for the outermost nodes (weights down to 1e-300), where the eigenvector form of
/// Golub–Welsch only has absolute accuracy. The recurrence is run on `pⱼ e^{−x²/2}`, which stays
/// of order one, so nothing overflows for `n` up to several hundred.
pub fn gauss_hermite(n: usize) -> Vec<(f64, f64)> {
    let n = NonZeroUsize::new(n).unwrap_or(NonZeroUsize::MIN);
    let m = n.get();
    // (pₙ, pₙ₋₁) e^{−x²/2}
    let scaled = |x: f64| {
        let (mut prev, mut cur) = (0.0, std::f64::consts::PI.powf(-0.25) * (-0.5 * x * x).exp());
        for j in 1..=m {
            let j = j as f64;
            let next = (2.0 / j).sqrt() * x * cur - ((j - 1.0) / j).sqrt() * prev;
            prev = cur;
            cur = next;
        }
        (cur, prev)
    };
    let initial = gauss_quad::hermite::GaussHermite::new(n);
    let mut pairs: Vec<(f64, f64)> = initial
        .as_node_weight_pairs()
        .iter()
        .map(|&(x0, _)| {
            let mut x = x0;
            for _ in 0..8 {
                let (p, q) = scaled(x);
                let step = p / ((2.0 * m as f64).sqrt() * q);
                x -= step;
                if step.abs() <= 4.0 * f64::EPSILON * x.abs().max(1.0) {
                    break;
                }
            }
            // wᵢ = 2/pₙ'² = 2/(2n pₙ₋₁²) = e^{−x²}/(n (pₙ₋₁ e^{−x²/2})²)
            let q = scaled(x).1;
            (x, (-x * x).exp() / (m as f64 * q * q))
        })
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs
}

/// Integrates `f` over `[a, b]` with `panels` equal panels of the [`ORDER`]-point rule.
pub fn composite<F: FnMut(f64) -> f64>(a: f64, b: f64, panels: usize, mut f: F) -> f64 {
    let panels = panels.max(1);
    let h = (b - a) / panels as f64;
    let rule = rule();
    let mut total = 0.0;
    for p in 0..panels {
        let lo = a + h * p as f64;
        let mid = lo + 0.5 * h;
        let mut sum = 0.0;
        for &(x, w) in rule {
            sum += w * f(mid + 0.5 * h * x);
        }
        total += 0.5 * h * sum;
    }
    total
}

/// Calls `visit(x, weight)` for every node of `panels` equal panels on `[a, b]`.
pub fn for_each_node<F: FnMut(f64, f64)>(a: f64, b: f64, panels: usize, mut visit: F) {
    let panels = panels.max(1);
    let h = (b - a) / panels as f64;
    for p in 0..panels {
        let mid = a + h * (p as f64 + 0.5);
        for &(x, w) in rule() {
            visit(mid + 0.5 * h * x, 0.5 * h * w);
        }
    }
}

/// Gauss–Kronrod 15-point nodes on [−1, 1], ascending (QUADPACK `qk15`).
#[allow(clippy::excessive_precision)] // QUADPACK's published digits
pub const KRONROD_NODES: [f64; 15] = [
    -0.991_455_371_120_812_639_206_854_697_526_329,
    -0.949_107_912_342_758_524_526_189_684_047_851,
    -0.864_864_423_359_769_072_789_712_788_640_926,
    -0.741_531_185_599_394_439_863_864_773_280_788,
    -0.586_087_235_467_691_130_294_144_845_693_013,
    -0.405_845_151_377_397_166_906_606_412_076_961,
    -0.207_784_955_007_898_467_600_689_403_773_245,
    0.0,
    0.207_784_955_007_898_467_600_689_403_773_245,
    0.405_845_151_377_397_166_906_606_412_076_961,
    0.586_087_235_467_691_130_294_144_845_693_013,
    0.741_531_185_599_394_439_863_864_773_280_788,
    0.864_864_423_359_769_072_789_712_788_640_926,
    0.949_107_912_342_758_524_526_189_684_047_851,
    0.991_455_371_120_812_639_206_854_697_526_329,
];

/// Kronrod weights for [`KRONROD_NODES`].
#[allow(clippy::excessive_precision)] // QUADPACK's published digits
pub const KRONROD_WEIGHTS: [f64; 15] = [
    0.022_935_322_010_529_224_963_732_008_058_970,
    0.063_092_092_629_978_553_290_700_663_189_204,
    0.104_790_010_322_250_183_839_876_322_541_518,
    0.140_653_259_715_525_918_745_189_590_510_238,
    0.169_004_726_639_267_902_826_583_426_598_550,
    0.190_350_578_064_785_409_913_256_402_421_014,
    0.204_432_940_075_298_892_414_161_999_234_649,
    0.209_482_141_084_727_828_012_999_174_891_714,
    0.204_432_940_075_298_892_414_161_999_234_649,
    0.190_350_578_064_785_409_913_256_402_421_014,
    0.169_004_726_639_267_902_826_583_426_598_550,
    0.140_653_259_715_525_918_745_189_590_510_238,
    0.104_790_010_322_250_183_839_876_322_541_518,
    0.063_092_092_629_978_553_290_700_663_189_204,
    0.022_935_322_010_529_224_963_732_008_058_970,
];

/// The embedded 7-point Gauss weights, at the odd-indexed Kronrod nodes (zero elsewhere).
#[allow(clippy::excessive_precision)] // QUADPACK's published digits
pub const GAUSS_WEIGHTS: [f64; 15] = [
    0.0,
    0.129_484_966_168_869_693_270_611_432_679_082,
    0.0,
    0.279_705_391_489_276_667_901_467_771_423_780,
    0.0,
    0.381_830_050_505_118_944_950_369_775_488_975,
    0.0,
    0.417_959_183_673_469_387_755_102_040_816_327,
    0.0,
    0.381_830_050_505_118_944_950_369_775_488_975,
    0.0,
    0.279_705_391_489_276_667_901_467_771_423_780,
    0.0,
    0.129_484_966_168_869_693_270_611_432_679_082,
    0.0,
];

/// One Gauss–Kronrod 7/15 panel (QUADPACK `qk15`), from the integrand's values at the
/// [`KRONROD_NODES`] mapped to a panel of half-width `half`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Qk15 {
    /// The 15-point Kronrod sum: the panel's integral.
    pub kronrod: f64,
    /// The embedded 7-point Gauss sum.
    pub gauss: f64,
    /// QUADPACK's `resasc`: the Kronrod integral of `|f − mean|`, the panel's variation.
    pub resasc: f64,
}

impl Qk15 {
    /// The sums of `values` (at the Kronrod nodes, in order) on a panel of half-width `half`.
    pub fn new(values: &[f64; 15], half: f64) -> Qk15 {
        let (mut kronrod, mut gauss) = (0.0, 0.0);
        for (i, &v) in values.iter().enumerate() {
            kronrod += KRONROD_WEIGHTS[i] * v;
            gauss += GAUSS_WEIGHTS[i] * v;
        }
        let (kronrod, gauss) = (kronrod * half, gauss * half);
        let mean = kronrod / (2.0 * half);
        let resasc = half * values.iter().enumerate().map(|(i, &v)| KRONROD_WEIGHTS[i] * (v - mean).abs()).sum::<f64>();
        Qk15 { kronrod, gauss, resasc }
    }

    /// QUADPACK's error estimate `resasc · min(1, scale(200 |K − G| / resasc))`: `|K − G|`
    /// overstates the Kronrod error on smooth panels, where it falls as a power of the ratio
    /// (`scale(r) = r^1.5` in QUADPACK).
    pub fn error(&self, scale: impl Fn(f64) -> f64) -> f64 {
        let error = (self.kronrod - self.gauss).abs();
        if self.resasc > 0.0 && error > 0.0 { self.resasc * scale(200.0 * error / self.resasc).min(1.0) } else { error }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rule_weights_sum_to_two_and_are_symmetric() {
        let r = rule();
        let sum: f64 = r.iter().map(|p| p.1).sum();
        assert!((sum - 2.0).abs() < 1e-14, "sum of weights {sum}");
        for i in 0..ORDER {
            assert!((r[i].0 + r[ORDER - 1 - i].0).abs() < 1e-15);
            assert!((r[i].1 - r[ORDER - 1 - i].1).abs() < 1e-15);
        }
    }

    #[test]
    fn integrates_polynomials_of_degree_31_exactly() {
        // ∫_0^1 x^31 dx = 1/32
        let v = composite(0.0, 1.0, 1, |x| x.powi(31));
        assert!((v - 1.0 / 32.0).abs() < 1e-15, "{v}");
    }

    #[test]
    fn gauss_legendre_rules_are_exact_to_degree_2n_minus_1() {
        // ∫_{−1}^{1} x^{2k} dx = 2/(2k + 1); odd powers integrate to 0 by the symmetric nodes
        for n in [1, 2, 3, 8, 16, 37, 128] {
            let r = gauss_legendre(n);
            assert_eq!(r.len(), n);
            assert!(r.windows(2).all(|p| p[0].0 < p[1].0));
            for k in 0..n {
                let exact = 2.0 / (2 * k + 1) as f64;
                let got: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * k as i32)).sum();
                assert!((got / exact - 1.0).abs() < 1e-13, "n {n}, x^{}: {got} vs {exact}", 2 * k);
            }
            // one degree too many: x^{2n} is not integrated exactly (the error falls as 4^{−n},
            // so it is visible for small n only)
            if n <= 8 {
                let got: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * n as i32)).sum();
                assert!((got * (2 * n + 1) as f64 / 2.0 - 1.0).abs() > 1e-6, "n {n}");
            }
        }
        assert_eq!(&gauss_legendre(ORDER)[..], &rule()[..]);
        assert_eq!(gauss_legendre(0), gauss_legendre(1));
    }

    #[test]
    fn gauss_hermite_rules_integrate_even_moments_exactly() {
        // ∫ x^{2k} e^{−x²} dx = Γ(k + ½) = √π (2k − 1)!!/2^k, built up by Γ(k + 3/2) = (k + ½) Γ(k + ½)
        for n in [1, 2, 5, 16, 33, 64, 128] {
            let r = gauss_hermite(n);
            assert_eq!(r.len(), n);
            assert!(r.windows(2).all(|p| p[0].0 < p[1].0));
            let mut exact = std::f64::consts::PI.sqrt();
            for k in 0..n {
                let got: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * k as i32)).sum();
                assert!((got / exact - 1.0).abs() < 1e-12, "n {n}, x^{}: {got} vs {exact}", 2 * k);
                // odd moments vanish: nodes and weights symmetric
                let odd: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * k as i32 + 1)).sum();
                let scale: f64 = r.iter().map(|&(x, w)| (w * x.powi(2 * k as i32 + 1)).abs()).sum();
                assert!(odd.abs() <= 1e-13 * scale, "n {n}, x^{}: {odd}", 2 * k + 1);
                exact *= k as f64 + 0.5;
            }
            // x^{2n} is past the rule's degree: its moment comes out low by √π n!/2^n, a
            // relative √(πn)/2^n, visible for small n
            if n <= 5 {
                let got: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * n as i32)).sum();
                assert!((got / exact - 1.0).abs() > 1e-2, "n {n}");
            }
        }
    }

    #[test]
    fn gauss_hermite_matches_a_closed_form_transform() {
        // ∫ e^{−x²} cos(k x) dx = √π e^{−k²/4}: an entire integrand, converged at 40 nodes
        for k in [0.5, 2.0, 6.0] {
            let got: f64 = gauss_hermite(40).iter().map(|&(x, w)| w * (k * x).cos()).sum();
            let exact = std::f64::consts::PI.sqrt() * (-k * k / 4.0).exp();
            assert!((got - exact).abs() < 1e-14, "k {k}: {got} vs {exact}");
        }
    }

    #[test]
    fn oscillatory_panel_budget_holds() {
        // ∫_0^L cos(x) dx = sin(L): one panel turning through MAX_PANEL_PHASE radians.
        let l = MAX_PANEL_PHASE;
        let v = composite(0.0, l, 1, f64::cos);
        assert!((v - l.sin()).abs() < 1e-14, "{v} vs {}", l.sin());
    }
}
