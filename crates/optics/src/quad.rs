//! Composite Gauss–Legendre quadrature with a fixed rule per panel.
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
        let n = NonZeroUsize::new(ORDER).expect("ORDER > 0");
        let gl = gauss_quad::legendre::GaussLegendre::new(n);
        let mut pairs: Vec<(f64, f64)> = gl.as_node_weight_pairs().to_vec();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut out = [(0.0, 0.0); ORDER];
        out.copy_from_slice(&pairs);
        out
    })
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
    fn oscillatory_panel_budget_holds() {
        // ∫_0^L cos(x) dx = sin(L): one panel turning through MAX_PANEL_PHASE radians.
        let l = MAX_PANEL_PHASE;
        let v = composite(0.0, l, 1, f64::cos);
        assert!((v - l.sin()).abs() < 1e-14, "{v} vs {}", l.sin());
    }
}
