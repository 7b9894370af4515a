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
