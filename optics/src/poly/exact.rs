//! The exact 1-D engine: centred circular pupils with defocus (and lateral shifts), and
//! tabulated OTFs, summed over the spectral nodes (docs/physics.md, "Polychromatic OTF").

use std::f64::consts::PI;

use num_complex::Complex64;

use super::spectral::{Node, Nodes, Scene, clipped_nodes, node_otfs};
use super::{Engine, FrequencyRule, OtfEngine, WavefrontDirection};

/// Spectral nodes read through the exact 1-D OTF of each order.
#[derive(Debug)]
pub(super) struct Quadrature<'a> {
    pub scene: Scene<'a>,
    pub nodes: Nodes,
}

/// Calls `visit(weight × OTF(s, w), node)` for every spectral node of `nodes` that passes
/// `frequency`; a tabulated order is read along `azimuth_from_field` (radians from the field
/// direction). Panels of the reference rule that straddle the cutoff are clipped there
/// ([`clipped_nodes`]); product-integration nodes never straddle it (the rule is only chosen
/// where every covered wavelength passes the frequency limit).
pub(super) fn contributions(
    scene: &Scene<'_>,
    nodes: &Nodes,
    frequency: f64,
    azimuth_from_field: f64,
    mut visit: impl FnMut(f64, &Node),
) {
    let nu = frequency.abs();
    let nuf = nu * scene.f_number;
    let cut = if nu > 0.0 { 1.0 / nuf } else { f64::INFINITY };
    let mut term = |n: &super::spectral::Node| {
        if n.lambda < cut {
            visit(n.weight * n.otf(nuf * n.lambda, nu, azimuth_from_field), n);
        }
    };
    if nodes.line.is_some() || nodes.interpolated {
        // every node's OTF at once (`node_otfs`), then visited in order
        let passing: Vec<&super::spectral::Node> = nodes.nodes.iter().filter(|n| n.lambda < cut).collect();
        for (n, value) in passing.iter().zip(node_otfs(&passing, nu, scene.f_number, azimuth_from_field)) {
            visit(n.weight * value, n);
        }
        return;
    }
    for p in &nodes.panels {
        if p.hi <= cut {
            nodes.nodes[p.start..p.end].iter().for_each(&mut term);
        } else if p.lo < cut {
            clipped_nodes(scene, p.lo, cut, |n| term(&n));
        }
    }
}

/// The complex OTF of the exact nodes along `azimuth` (radians from x): each term times
/// `exp(−2πi ν u·Δ)` for its image displacement Δ.
pub(super) fn exact_along(scene: &Scene<'_>, nodes: &Nodes, frequency: f64, azimuth: f64) -> Complex64 {
    let (sin_a, cos_a) = azimuth.sin_cos();
    let k = -2.0 * PI * frequency;
    let mut sum = Complex64::new(0.0, 0.0);
    contributions(scene, nodes, frequency, azimuth - scene.field_direction(), |v, n| {
        let [dx, dy] = n.shift;
        if dx == 0.0 && dy == 0.0 {
            sum.re += v;
        } else {
            let (s, c) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
            sum += Complex64::new(v * c, v * s);
        }
    });
    sum / nodes.total_weight
}

/// [`exact_along`] and, into `gradient`, its derivative with respect to each of `directions`,
/// which must all be field angles ([`WavefrontDirection::FieldAngle`]; docs/physics.md,
/// "Gradients: the field point"): each node's turned value `v e^{ik u·Δ}` (k = −2πν) times
/// `i k u_a ∂Δ_a/∂θ_a`, on the same nodes. `None` for another direction or a node without its
/// shift's rates.
pub(super) fn exact_along_and_field_gradient(
    scene: &Scene<'_>,
    nodes: &Nodes,
    frequency: f64,
    azimuth: f64,
    directions: &[WavefrontDirection],
    gradient: &mut [Complex64],
) -> Option<Complex64> {
    // 0, 1: the field angles; 2: the azimuth
    let axes: Vec<usize> = directions
        .iter()
        .map(|d| match d {
            WavefrontDirection::FieldAngle(a) if *a < 2 => Some(*a),
            WavefrontDirection::Azimuth => Some(2),
            _ => None,
        })
        .collect::<Option<_>>()?;
    let fields = axes.iter().any(|&a| a < 2);
    gradient.iter_mut().for_each(|g| *g = Complex64::new(0.0, 0.0));
    let (sin_a, cos_a) = azimuth.sin_cos();
    let k = -2.0 * PI * frequency;
    let mut sum = Complex64::new(0.0, 0.0);
    let mut missing = false;
    contributions(scene, nodes, frequency, azimuth - scene.field_direction(), |v, n| {
        let [dx, dy] = n.shift;
        let (s, c) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
        let turned = Complex64::new(v * c, v * s);
        sum += turned;
        let [rx, ry] = match n.shift_rate {
            Some(r) => r,
            None => {
                missing = true;
                [0.0; 2]
            }
        };
        for (g, &axis) in gradient.iter_mut().zip(&axes) {
            let rate = match axis {
                0 => k * rx * cos_a,
                1 => k * ry * sin_a,
                _ => k * (dy * cos_a - dx * sin_a),
            };
            *g += Complex64::new(0.0, rate) * turned;
        }
    });
    if missing && fields {
        return None;
    }
    gradient.iter_mut().for_each(|g| *g /= nodes.total_weight);
    Some(sum / nodes.total_weight)
}

impl OtfEngine for Quadrature<'_> {
    fn engine(&self) -> Engine {
        Engine::Exact1d
    }

    fn nodes(&self) -> &Nodes {
        &self.nodes
    }

    fn f_number(&self) -> f64 {
        self.scene.f_number
    }

    fn otf(&self, frequency: f64) -> f64 {
        let mut sum = 0.0;
        // along +x: a tabulated order's direction relative to the field's
        contributions(&self.scene, &self.nodes, frequency, -self.scene.field_direction(), |v, _| sum += v);
        sum / self.nodes.total_weight
    }

    fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64 {
        exact_along(&self.scene, &self.nodes, frequency, azimuth)
    }

    /// The field angles' lanes ([`exact_along_and_field_gradient`]).
    fn otf_along_and_gradient(
        &self,
        frequency: f64,
        azimuth: f64,
        directions: &[WavefrontDirection],
        gradient: &mut [Complex64],
    ) -> Option<Complex64> {
        exact_along_and_field_gradient(&self.scene, &self.nodes, frequency, azimuth, directions, gradient)
    }

    fn frequency_rule(&self) -> FrequencyRule {
        FrequencyRule::Adaptive { min_panels: 1.0 }
    }
}
