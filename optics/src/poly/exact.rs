//! The exact 1-D engine: centred circular pupils with defocus (and lateral shifts), and
//! tabulated OTFs, summed over the spectral nodes (docs/physics.md, "Polychromatic OTF").

use std::f64::consts::PI;

use num_complex::Complex64;

use super::spectral::{Nodes, Scene, clipped_nodes, node_otfs};
use super::{Engine, FrequencyRule, OtfEngine};

/// Spectral nodes read through the exact 1-D OTF of each order.
#[derive(Debug)]
pub(super) struct Quadrature<'a> {
    pub scene: Scene<'a>,
    pub nodes: Nodes,
}

/// Calls `visit(weight × OTF(s, w), shift)` for every spectral node of `nodes` that passes
/// `frequency`; a tabulated order is read along `azimuth_from_field` (radians from the field
/// direction). Panels of the reference rule that straddle the cutoff are clipped there
/// ([`clipped_nodes`]); product-integration nodes never straddle it (the rule is only chosen
/// where every covered wavelength passes the frequency limit).
pub(super) fn contributions(
    scene: &Scene<'_>,
    nodes: &Nodes,
    frequency: f64,
    azimuth_from_field: f64,
    mut visit: impl FnMut(f64, [f64; 2]),
) {
    let nu = frequency.abs();
    let nuf = nu * scene.f_number;
    let cut = if nu > 0.0 { 1.0 / nuf } else { f64::INFINITY };
    let mut term = |n: &super::spectral::Node| {
        if n.lambda < cut {
            visit(n.weight * n.otf(nuf * n.lambda, nu, azimuth_from_field), n.shift);
        }
    };
    if nodes.line.is_some() || nodes.interpolated {
        // every node's OTF at once (`node_otfs`), then visited in order
        let passing: Vec<&super::spectral::Node> = nodes.nodes.iter().filter(|n| n.lambda < cut).collect();
        for (n, value) in passing.iter().zip(node_otfs(&passing, nu, scene.f_number, azimuth_from_field)) {
            visit(n.weight * value, n.shift);
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
    contributions(scene, nodes, frequency, azimuth - scene.field_direction(), |v, [dx, dy]| {
        if dx == 0.0 && dy == 0.0 {
            sum.re += v;
        } else {
            let (s, c) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
            sum += Complex64::new(v * c, v * s);
        }
    });
    sum / nodes.total_weight
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

    fn frequency_rule(&self) -> FrequencyRule {
        FrequencyRule::Adaptive { min_panels: 1.0 }
    }
}
