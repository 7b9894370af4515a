//! The exact 1-D engine: centred circular pupils with defocus (and lateral shifts), and
//! tabulated OTFs, summed over the spectral nodes (docs/physics.md, "Polychromatic OTF").

use std::f64::consts::PI;

use num_complex::Complex64;

use super::spectral::{Node, Nodes, Scene, clipped_nodes, node_otfs, node_otfs_and_lanes};
use super::{Engine, FrequencyRule, OtfEngine, WavefrontDirection};

/// A lens's design-wavelength rates at one wavelength (`LensModel::design_wavelength_rates`:
/// `[∂W020_o, ∂τ_o]` per order), `None` where it gives none.
type DesignRates = Option<Vec<[f64; 2]>>;

/// Spectral nodes read through the exact 1-D OTF of each order.
#[derive(Debug)]
pub(super) struct Quadrature<'a> {
    pub scene: Scene<'a>,
    pub nodes: Nodes,
    /// The nodes' real OTFs at each frequency read ([`NodeCache`]).
    pub cache: NodeCache,
}

impl<'a> Quadrature<'a> {
    pub fn new(scene: Scene<'a>, nodes: Nodes) -> Self {
        Quadrature { scene, nodes, cache: NodeCache::default() }
    }
}

/// The most numbers a [`NodeCache`] keeps (32 MB); past it, frequencies are read without it.
const NODE_CACHE_LIMIT: usize = 1 << 22;

/// Each passing node's real OTF `H(νλF#/r, W020/λ)` (and, once a lane asked it, its defocus
/// lane `w ∂H/∂w`) at each frequency read, by the frequency's bits: along every azimuth the
/// exact engine's OTF is the same real values turned by each node's own phase
/// `exp(−2πi ν u·Δ)`, so the rule over azimuth, which reads the same frequencies along each
/// azimuth (the frequency rule's panels do not depend on it), and the gradient's passes on the
/// same engine compute them once (docs/physics.md, "Gradients: the multiplexed lens"). The
/// values are the ones computed without it, bit for bit (the same batches of the same nodes);
/// only the product-integration nodes without a table are kept (a table is read along the
/// azimuth; a panel clipped at the cutoff makes its nodes as it reads them).
#[derive(Debug, Default)]
pub(super) struct NodeCache {
    entries: std::cell::RefCell<std::collections::HashMap<u64, std::rc::Rc<CachedOtfs>>>,
    kept: std::cell::Cell<usize>,
}

/// One frequency's [`NodeCache`] entry: the passing nodes' values in their order, and the
/// defocus lanes where some read asked them (`None` for a node that is not a defocused circle).
#[derive(Debug)]
struct CachedOtfs {
    values: Vec<f64>,
    lanes: Option<Vec<Option<f64>>>,
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
    contributions_with(scene, nodes, None, false, frequency, azimuth_from_field, |v, _, n| visit(v, n));
}

/// [`contributions`] reading each product-integration node's value from `cache` where it holds
/// the frequency (and keeping it there), with the node's defocus lane `weight × w ∂H/∂w`
/// beside it where `lanes` (`None` for a node that is not a defocused circle, or where the
/// nodes are not kept).
pub(super) fn contributions_with(
    scene: &Scene<'_>,
    nodes: &Nodes,
    cache: Option<&NodeCache>,
    lanes: bool,
    frequency: f64,
    azimuth_from_field: f64,
    mut visit: impl FnMut(f64, Option<f64>, &Node),
) {
    let nu = frequency.abs();
    let nuf = nu * scene.f_number;
    let cut = if nu > 0.0 { 1.0 / nuf } else { f64::INFINITY };
    let mut term = |n: &super::spectral::Node| {
        if n.lambda < cut {
            visit(n.weight * n.otf(nuf * n.lambda, nu, azimuth_from_field), None, n);
        }
    };
    if nodes.line.is_some() || nodes.interpolated {
        // every node's OTF at once (`node_otfs`), then visited in order
        let passing: Vec<&super::spectral::Node> = nodes.nodes.iter().filter(|n| n.lambda < cut).collect();
        let cache = cache.filter(|_| passing.iter().all(|n| n.table.is_none()));
        let Some(cache) = cache else {
            for (n, value) in passing.iter().zip(node_otfs(&passing, nu, scene.f_number, azimuth_from_field)) {
                visit(n.weight * value, None, n);
            }
            return;
        };
        let key = nu.to_bits();
        let found = cache.entries.borrow().get(&key).cloned();
        let entry = match found {
            Some(e) if !lanes || e.lanes.is_some() => e,
            _ => {
                let entry = std::rc::Rc::new(match lanes {
                    false => {
                        CachedOtfs { values: node_otfs(&passing, nu, scene.f_number, azimuth_from_field), lanes: None }
                    }
                    true => {
                        let (values, lanes) = node_otfs_and_lanes(&passing, nu, scene.f_number, azimuth_from_field);
                        CachedOtfs { values, lanes: Some(lanes) }
                    }
                });
                let size = entry.values.len() * if lanes { 3 } else { 1 };
                if cache.kept.get() + size <= NODE_CACHE_LIMIT {
                    cache.kept.set(cache.kept.get() + size);
                    cache.entries.borrow_mut().insert(key, entry.clone());
                }
                entry
            }
        };
        for (i, (n, value)) in passing.iter().zip(&entry.values).enumerate() {
            let lane = entry.lanes.as_ref().and_then(|l| l[i]).map(|d| n.weight * d);
            visit(n.weight * value, lane, n);
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
pub(super) fn exact_along(
    scene: &Scene<'_>,
    nodes: &Nodes,
    cache: Option<&NodeCache>,
    frequency: f64,
    azimuth: f64,
) -> Complex64 {
    let (sin_a, cos_a) = azimuth.sin_cos();
    let k = -2.0 * PI * frequency;
    let mut sum = Complex64::new(0.0, 0.0);
    contributions_with(scene, nodes, cache, false, frequency, azimuth - scene.field_direction(), |v, _, n| {
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

/// [`exact_along`] and, into `gradient`, its derivative with respect to each of `directions`:
/// field angles ([`WavefrontDirection::FieldAngle`]; docs/physics.md, "Gradients: the field
/// point"), the azimuth, a circular iris's decentre ([`WavefrontDirection::IrisDecentre`]) and
/// every order's defocus ([`WavefrontDirection::Defocus`]; "Gradients: the iris"). Each node's
/// turned value `v e^{ik u·Δ}` (k = −2πν) gains `i k u_a ∂Δ_a/∂θ_a` (a field angle),
/// `i k u_a ∂Δ_a/∂d_a` with `∂Δ_a/∂d_a = 2 W020/NA` (a decentre) times itself; the defocus lane
/// (`W020` scaled by `1 + ε`, `s` fixed) is `w ∂D/∂w` of the node's defocused OTF turned by its
/// phase, plus `i k u·Δ_iris` times the turned value (the iris's tilt scales with `W020`; a
/// lateral colour's shift does not). The spectral moments
/// ([`WavefrontDirection::SpectralMoment`]) re-weight each node's turned value by `u = λ − λ̄`
/// or `u² − ⟨u²⟩` ([`Nodes::wavelength_moments`](super::spectral::Nodes::wavelength_moments)).
/// The image shifts' scale ([`WavefrontDirection::ImageShift`]) gains `i k u·(Δ − Δ_iris)` times
/// the turned value (every shift but an iris's tilt scaled by `1 + ε`). The design wavelength
/// ([`WavefrontDirection::DesignWavelength`]) moves each order's defocus and efficiency by the
/// lens's rates (`LensModel::design_wavelength_rates`: `δW020`, `δτ` per `ln λ0`), the shifts
/// held: `(δτ/τ) v + q τ (∂H/∂w) δW020/λ` turned (`∂H/∂w = (w ∂H/∂w)/w`, 0 at `w = 0` where `H`
/// is even in `w`; through a circular iris of radius `r`, `w = W020 r²/λ` and its tilt
/// `Δ_iris = W020 (2d/NA)` gains `i k u·(2d/NA) δW020` times the turned value), the
/// normalization's rate left to the caller.
/// `None` for another direction, a field angle on a node without its shift's rates, the
/// defocus lane on a node that is not a defocused circle, or the design wavelength's on a node
/// that is not a circle (the full pupil or a circular iris) with a defocus alone or whose lens
/// gives no rates there.
pub(super) fn exact_along_and_field_gradient(
    scene: &Scene<'_>,
    nodes: &Nodes,
    cache: Option<&NodeCache>,
    frequency: f64,
    azimuth: f64,
    directions: &[WavefrontDirection],
    gradient: &mut [Complex64],
) -> Option<Complex64> {
    // 0, 1: the field angles; 3, 4: the iris's decentre; 5: the defocus; 6, 7: the spectral
    // moments; 8: the image shifts' scale; 9: the design wavelength
    let axes: Vec<usize> = directions
        .iter()
        .map(|d| match d {
            WavefrontDirection::FieldAngle(a) if *a < 2 => Some(*a),
            WavefrontDirection::IrisDecentre(a) if *a < 2 => Some(3 + *a),
            WavefrontDirection::Defocus => Some(5),
            WavefrontDirection::SpectralMoment(k) if (1..=2).contains(k) => Some(5 + *k),
            WavefrontDirection::ImageShift => Some(8),
            WavefrontDirection::DesignWavelength => Some(9),
            _ => None,
        })
        .collect::<Option<_>>()?;
    let (mean, variance) = if axes.iter().any(|&a| a == 6 || a == 7) { nodes.wavelength_moments() } else { (0.0, 0.0) };
    let fields = axes.iter().any(|&a| a < 2);
    let defocus = axes.contains(&5);
    let design = axes.contains(&9);
    // the lens's design rates at the last node's wavelength and part (the orders of one
    // wavelength are consecutive nodes)
    let mut rates: Option<((u64, usize), DesignRates)> = None;
    let mut no_rates = false;
    gradient.iter_mut().for_each(|g| *g = Complex64::new(0.0, 0.0));
    let (sin_a, cos_a) = azimuth.sin_cos();
    let k = -2.0 * PI * frequency;
    let nuf = frequency.abs() * scene.f_number;
    let mut sum = Complex64::new(0.0, 0.0);
    let mut missing = false;
    let mut not_circle = false;
    // the nodes' defocus lanes read with their values where a lane needs them
    let with_lanes = defocus || design;
    let from_field = azimuth - scene.field_direction();
    contributions_with(scene, nodes, cache, with_lanes, frequency, from_field, |v, cached, n| {
        let [dx, dy] = n.shift;
        let (s, c) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
        // w ∂H/∂w of the node's defocused circle (times its weight): kept beside its value, or
        // from the value's own series forms at this one point
        let log_lane = || match cached {
            Some(d) => d,
            None => {
                n.weight * crate::otf::defocus_otf_and_log_derivative(nuf * n.lambda / n.scale, n.w020 / n.lambda).1
            }
        };
        let turned = Complex64::new(v * c, v * s);
        sum += turned;
        let [rx, ry] = match n.shift_rate {
            Some(r) => r,
            None => {
                missing = true;
                [0.0; 2]
            }
        };
        // w ∂D/∂w of the node's defocused circle at its own frequency scale, turned: the
        // value's own series forms, to rounding (`defocus_otf_log_derivative`, the t-form
        // quadrature, is the independent reference the otf tests hold them against)
        let lane = if defocus && n.is_defocused_circle() {
            let d = log_lane();
            Complex64::new(d * c, d * s)
        } else {
            not_circle |= defocus;
            Complex64::new(0.0, 0.0)
        };
        let design_lane = if design {
            let key = (n.lambda.to_bits(), n.part);
            if rates.as_ref().is_none_or(|r| r.0 != key) {
                let lens = scene.part(n.part).lens;
                rates = Some((key, lens.design_wavelength_rates(n.lambda, scene.field)));
            }
            let rate = rates.as_ref().and_then(|r| r.1.as_ref()).and_then(|r| r.get(n.order)).copied();
            match rate {
                Some([d_w020, d_tau]) if n.is_defocused_circle() => {
                    // ∂H/∂w δw = (w ∂H/∂w) δW020/W020, 0 at w = 0 (H even in w); through a
                    // circular iris of radius r the node's W020 r² moves with the order's W020
                    let slope = if n.w020 == 0.0 { 0.0 } else { log_lane() * d_w020 * (n.scale * n.scale) / n.w020 };
                    let moved = if n.efficiency == 0.0 { 0.0 } else { v * d_tau / n.efficiency };
                    let d = moved + slope;
                    let lane = Complex64::new(d * c, d * s);
                    // a decentred iris's tilt W020 (2d/NA) moves with W020: i k u·δΔ_iris times
                    // the turned value (docs/physics.md, "Gradients: the design wavelength
                    // through an iris")
                    match n.iris_tilt {
                        [0.0, 0.0] => lane,
                        [tx, ty] => lane + Complex64::new(0.0, k * d_w020 * (tx * cos_a + ty * sin_a)) * turned,
                    }
                }
                _ => {
                    no_rates = true;
                    Complex64::new(0.0, 0.0)
                }
            }
        } else {
            Complex64::new(0.0, 0.0)
        };
        let [ix, iy] = n.iris_shift;
        let u = n.lambda - mean;
        for (g, &axis) in gradient.iter_mut().zip(&axes) {
            let rate = match axis {
                0 => k * rx * cos_a,
                1 => k * ry * sin_a,
                3 => k * n.iris_rate * cos_a,
                4 => k * n.iris_rate * sin_a,
                5 => {
                    *g += lane;
                    k * (ix * cos_a + iy * sin_a)
                }
                6 => {
                    *g += turned * u;
                    continue;
                }
                // the lateral colour's share of the shift, scaled (the iris's tilt is the
                // defocus lane's)
                8 => k * ((dx - ix) * cos_a + (dy - iy) * sin_a),
                9 => {
                    *g += design_lane;
                    continue;
                }
                _ => {
                    *g += turned * (u * u - variance);
                    continue;
                }
            };
            *g += Complex64::new(0.0, rate) * turned;
        }
    });
    if (missing && fields) || not_circle || no_rates {
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

    /// The largest `2π ν |∂Δ/∂θ|` over the nodes (each order at each wavelength its own rate,
    /// far orders included whatever their weight) and the frequencies read, as the overlap
    /// engine's: the field angles' lanes are each node's turned value times `i k u·∂Δ/∂θ`.
    fn field_lane_bound(&self) -> Option<f64> {
        let top = self.scene.max_frequency.min(self.max_cutoff());
        let mut largest = 0.0_f64;
        for node in &self.nodes.nodes {
            let [rx, ry] = node.shift_rate?;
            largest = largest.max(rx.abs()).max(ry.abs());
        }
        Some(2.0 * PI * top * largest)
    }

    fn otf(&self, frequency: f64) -> f64 {
        let mut sum = 0.0;
        // along +x: a tabulated order's direction relative to the field's
        contributions(&self.scene, &self.nodes, frequency, -self.scene.field_direction(), |v, _| sum += v);
        sum / self.nodes.total_weight
    }

    fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64 {
        exact_along(&self.scene, &self.nodes, Some(&self.cache), frequency, azimuth)
    }

    /// The field angles', the iris decentre's, the defocus's and the spectral moments' lanes
    /// ([`exact_along_and_field_gradient`]).
    fn otf_along_and_gradient(
        &self,
        frequency: f64,
        azimuth: f64,
        directions: &[WavefrontDirection],
        gradient: &mut [Complex64],
    ) -> Option<Complex64> {
        exact_along_and_field_gradient(
            &self.scene,
            &self.nodes,
            Some(&self.cache),
            frequency,
            azimuth,
            directions,
            gradient,
        )
    }

    fn frequency_rule(&self) -> FrequencyRule {
        FrequencyRule::Adaptive { min_panels: 1.0 }
    }

    #[cfg(test)]
    fn exact_quadrature(&self) -> Option<&Quadrature<'_>> {
        Some(self)
    }
}
