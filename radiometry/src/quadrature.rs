//! Composite Gauss–Legendre quadrature on panels (internal).

use std::sync::OnceLock;

/// Nodes per panel. A rule with n nodes integrates polynomials of degree ≤ 2n − 1 exactly.
pub(crate) const ORDER: usize = 16;

/// Highest polynomial degree integrated exactly on one panel.
#[cfg(test)]
const EXACT_DEGREE: usize = 2 * ORDER - 1;

struct Rule {
    nodes: [f64; ORDER],
    weights: [f64; ORDER],
}

/// Gauss–Legendre nodes and weights on [−1, 1], ascending, from `gauss-quad` (Bogaert's O(n)
/// algorithm, accurate to rounding; the project's one Gauss–Legendre source, as in `optics::quad`),
/// `ORDER` even.
fn rule() -> &'static Rule {
    static RULE: OnceLock<Rule> = OnceLock::new();
    RULE.get_or_init(|| {
        let n = std::num::NonZeroUsize::new(ORDER).unwrap_or(std::num::NonZeroUsize::MIN);
        let mut pairs = gauss_quad::legendre::GaussLegendre::new(n).as_node_weight_pairs().to_vec();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        // the upper half mirrored: nodes exactly symmetric, as the rule is
        let mut nodes = [0.0; ORDER];
        let mut weights = [0.0; ORDER];
        for i in ORDER / 2..ORDER.min(pairs.len()) {
            let (x, w) = pairs[i];
            (nodes[i], weights[i]) = (x, w);
            (nodes[ORDER - 1 - i], weights[ORDER - 1 - i]) = (-x, w);
        }
        Rule { nodes, weights }
    })
}

/// The Gauss–Legendre rule of `points` (1 to 8) on [−1, 1]: (node, weight) pairs, from
/// `gauss-quad` (the project's one Gauss–Legendre source), made once.
pub(crate) fn gauss_legendre(points: usize) -> &'static [(f64, f64)] {
    static RULES: OnceLock<Vec<Vec<(f64, f64)>>> = OnceLock::new();
    let rules = RULES.get_or_init(|| {
        (1..=8)
            .map(|n| {
                let n = std::num::NonZeroUsize::new(n).unwrap_or(std::num::NonZeroUsize::MIN);
                gauss_quad::legendre::GaussLegendre::new(n).as_node_weight_pairs().to_vec()
            })
            .collect()
    });
    &rules[points.clamp(1, 8) - 1]
}

/// Calls `visit(x, w)` for each node x of the rule mapped to [a, b], with its weight w
/// (already multiplied by the panel half-width).
pub(crate) fn for_each_node(a: f64, b: f64, mut visit: impl FnMut(f64, f64)) {
    let r = rule();
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    for (x, w) in r.nodes.iter().zip(&r.weights) {
        visit(mid + half * x, half * w);
    }
}

/// ∫_a^b f by one Gauss–Legendre panel.
pub(crate) fn panel(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let mut sum = 0.0;
    for_each_node(a, b, |x, w| sum += w * f(x));
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_two_and_nodes_are_symmetric_and_inside() {
        let r = rule();
        let s: f64 = r.weights.iter().sum();
        assert!((s - 2.0).abs() < 1e-14, "sum of weights {s}");
        for i in 0..ORDER {
            assert!(r.nodes[i].abs() < 1.0);
            assert_eq!(r.nodes[i], -r.nodes[ORDER - 1 - i]);
            assert!(r.weights[i] > 0.0);
        }
        for w in r.nodes.windows(2) {
            assert!(w[0] < w[1]);
        }
    }

    #[test]
    fn integrates_monomials_exactly_up_to_degree_2n_minus_1() {
        // ∫_0^1 x^k dx = 1/(k+1) for every k ≤ 31; degree 32 is no longer exact.
        for k in 0..=EXACT_DEGREE {
            let got = panel(0.0, 1.0, |x| x.powi(k as i32));
            let want = 1.0 / (k as f64 + 1.0);
            assert!((got - want).abs() < 1e-14, "degree {k}: {got} vs {want}");
        }
        let k = EXACT_DEGREE + 1;
        let got = panel(-1.0, 1.0, |x| x.powi(k as i32));
        assert!((got - 2.0 / (k as f64 + 1.0)).abs() > 1e-12);
    }
}
