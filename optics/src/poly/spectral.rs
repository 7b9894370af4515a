//! The spectral rules: where the polychromatic OTF is sampled in wavelength, and with what weights.
//!
//! Both rules turn the detected spectrum ρ(λ) and the lens into [`Nodes`]: one [`Node`] per
//! wavelength and imaging order, whose weight is the rule's weight × the order's efficiency, so
//! that every engine sums `Σ weight × OTF_order(ν, λ)` and divides by the same sum at ν = 0.
//!
//! - **Product integration** ([`interpolated`], the default; docs/physics.md, "Spectral
//!   quadrature"): the OTF at fixed ν is smooth in λ (for the chromatic lens its defocus phase is
//!   linear in λ); the detected weight is not (a measured table kinks at every sample). So the
//!   lens's part `g(ν, λ) = Σ_o τ_o(λ) OTF_o(ν, λ)` is interpolated in λ on Chebyshev–Lobatto
//!   points of each panel, and the weights are the exact moments of ρ against the Lagrange basis,
//!   computed once per scene from the Chebyshev moments `∫ ρ T_j` (Gauss–Legendre on the smooth
//!   pieces of ρ, in the angle θ of `x = cos θ`). The panels follow the lens (its breakpoints and
//!   its defocus phase), not the spectrum's samples; each panel's node count follows its phase
//!   and its share of the weight through the Chebyshev interpolation bound (Trefethen,
//!   *Approximation Theory and Approximation Practice*, Thm 8.2), checked a posteriori by the
//!   nested rule of half the points.
//! - **Panels** ([`panels`], the reference): 16-point Gauss–Legendre panels cut at every kink of
//!   the spectrum and the lens, refined until the defocus phase turns by at most
//!   [`quad::MAX_PANEL_PHASE`] across each; exact to rounding, at a cost that grows with the
//!   number of table samples. Its panels can be clipped at a cutoff inside the band (the exact
//!   engine does), which product integration cannot, so bands whose cutoffs fall below the
//!   frequency limit take this rule.

use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use num_complex::Complex64;
use radiometry::Spectrum;

use crate::lens::{Field, LensModel, Order, Pupil};
use crate::otf::{defocus_otf, pixel_mtf};
use crate::radial::{RadialOrder, TableRule};
use crate::table::OtfTable;
use crate::{Error, quad};

use super::GAUSSIAN_HALF_WIDTH_SIGMAS;

/// One wavelength of one imaging order.
#[derive(Clone, Debug)]
pub(super) struct Node {
    pub lambda: f64,
    /// rule weight × order efficiency (the rule weight is `q ρ(λ)` for a quadrature node and a
    /// moment of ρ for an interpolation node)
    pub weight: f64,
    /// W020 of the order at its pupil's edge, m
    pub w020: f64,
    /// the pupil's radius in units of the full aperture's: 1, or a decentred circular iris's
    /// (its frequencies scale by 1/r)
    pub scale: f64,
    /// image displacement on the detector, m
    pub shift: [f64; 2],
    /// `[∂Δx/∂θx, ∂Δy/∂θy]` (m per radian) off axis, where the lens gives it
    /// (`LensModel::image_shift_field_rates`): the field angles' lanes of the exact engine
    pub shift_rate: Option<[f64; 2]>,
    /// a decentred circular iris's share of `shift` ([`reduced_circle`]: `Δ = 2 W020 d/NA`),
    /// m, and its rate `∂Δ_a/∂d_a = 2 W020/NA` (m per unit of the decentre, a fraction of the
    /// radius): the iris decentre's and the defocus's lanes of the exact engine; 0 without one
    pub iris_shift: [f64; 2],
    pub iris_rate: f64,
    /// a decentred circular iris's tilt per metre of the order's `W020`: `iris_shift = W020
    /// iris_tilt`, `iris_tilt = 2d/NA` (0 without one): the design wavelength's lane through the
    /// iris, whose tilt moves with `W020` even where `W020` is 0
    pub iris_tilt: [f64; 2],
    /// the order's OTF table ([`Pupil::Table`]), read instead of the defocused OTF
    pub table: Option<Arc<OtfTable>>,
    /// the order's radially symmetric pupil ([`Pupil::Radial`]) prepared at this wavelength,
    /// computed by the radial engine instead of the defocused OTF (where it needs no grid)
    pub radial: Option<Arc<RadialOrder>>,
    /// the scene's part whose order this is ([`Scene::part`]; [`WHOLE`] for the whole lens)
    pub part: usize,
    /// the order's place among the lens's orders at `lambda` (`LensModel::orders`), and its
    /// efficiency τ (`weight` is the rule's weight times it): the design wavelength's lane
    /// reads the order's rates by them
    pub order: usize,
    pub efficiency: f64,
}

impl Node {
    /// The node of `order` at `lambda` with `weight` (rule weight × efficiency); with `irises`,
    /// the lens's numerical aperture, a circular iris (decentred or not) on a defocus-only order
    /// is reduced to the centred circle of its radius with a tilt ([`reduced_circle`]).
    /// A radial pupil takes `table_rule` where it has a table's knots.
    pub fn of(order: &Order, lambda: f64, weight: f64, irises: Option<f64>, table_rule: TableRule) -> Node {
        let mut node = Node {
            lambda,
            weight,
            // the largest zone defocus of a composite pupil (the frequency rule's statistics and
            // the Fraunhofer check of a line); the defocused OTF uses it only for a full pupil
            w020: crate::fraunhofer::order_defocus(order),
            scale: 1.0,
            shift: order.wavefront.image_shift_m,
            shift_rate: None,
            iris_shift: [0.0; 2],
            iris_rate: 0.0,
            iris_tilt: [0.0; 2],
            table: match &order.pupil {
                Pupil::Table(t) => Some(t.clone()),
                _ => None,
            },
            radial: match &order.pupil {
                Pupil::Radial(p) if !needs_grid(order, false) => Some(Arc::new(
                    RadialOrder::new(p.clone(), order.wavefront.defocus_m, lambda).with_table_rule(table_rule),
                )),
                _ => None,
            },
            part: WHOLE,
            order: 0,
            efficiency: order.efficiency,
        };
        if let Some(r) = irises.and_then(|na| reduced_circle(order, na)) {
            node.w020 = r.defocus_m;
            node.scale = r.radius;
            node.shift = [node.shift[0] + r.image_shift_m[0], node.shift[1] + r.image_shift_m[1]];
            node.iris_shift = r.image_shift_m;
            // `reduce_decentred_circle`'s tilt 2 W020 d/NA per unit W020
            if let (Pupil::Aperture(a), Some(na)) = (&order.pupil, irises)
                && let Some((centre, _)) = a.as_circle()
            {
                node.iris_tilt = [2.0 * centre[0] / na, 2.0 * centre[1] / na];
            }
        }
        // the full pupil is the iris of radius 1 at d = 0: a decentre's lane moves it as any
        // circular iris's (the scene's iris is the full circle moved)
        let circle = match &order.pupil {
            Pupil::Full => true,
            Pupil::Aperture(a) => a.as_circle().is_some(),
            _ => false,
        };
        if let Some(na) = irises.filter(|_| circle && order.wavefront.is_defocus_only()) {
            node.iris_rate = 2.0 * order.wavefront.defocus_m / na;
        }
        node
    }

    /// The real OTF of this node's order at `s = ν λ F#` (`s < 1`) along the direction at
    /// `azimuth_from_field` from the field direction (a table's T/S; the defocused OTF of a
    /// centred circle does not depend on it).
    pub fn otf(&self, s: f64, frequency: f64, azimuth_from_field: f64) -> f64 {
        match (&self.table, &self.radial) {
            (Some(t), _) => t.value(self.lambda, frequency, azimuth_from_field),
            (None, Some(r)) => r.otf(s, RADIAL_ACCURACY),
            (None, None) => defocus_otf(s / self.scale, self.w020 / self.lambda),
        }
    }

    /// Whether the node's OTF is the defocused circle's (neither a table nor a radial pupil).
    pub fn is_defocused_circle(&self) -> bool {
        self.table.is_none() && self.radial.is_none()
    }
}

/// Absolute accuracy of one radial pupil's OTF value (`radial::RadialOrder::otf`): well below
/// any tolerance of the mean, as the exact 1-D OTF is exact to rounding.
pub(super) const RADIAL_ACCURACY: f64 = 1e-12;

/// The `(s, w020/λ)` of each defocused circle among `nodes` at `nuf = ν F#`, in order: the
/// points [`node_otfs`] and [`node_otfs_and_lanes`] evaluate in one batch.
fn defocused_points(nodes: &[&Node], nuf: f64) -> Vec<(f64, f64)> {
    nodes.iter().filter(|n| n.is_defocused_circle()).map(|n| (nuf * n.lambda / n.scale, n.w020 / n.lambda)).collect()
}

/// [`Node::otf`] of each of `nodes` at `nu` (cycles/m; `f_number` of the lens, a table read along
/// `azimuth_from_field`), in order: the defocused ones all at once
/// ([`crate::otf::defocus_otf_many`], the Bessel series in interleaved lanes).
pub(super) fn node_otfs(nodes: &[&Node], nu: f64, f_number: f64, azimuth_from_field: f64) -> Vec<f64> {
    let nuf = nu * f_number;
    let points = defocused_points(nodes, nuf);
    let mut defocused = vec![0.0; points.len()];
    crate::otf::defocus_otf_many(&points, &mut defocused);
    let mut next = defocused.into_iter();
    nodes
        .iter()
        .map(|n| match n.is_defocused_circle() {
            true => next.next().unwrap_or(0.0),
            false => n.otf(nuf * n.lambda, nu, azimuth_from_field),
        })
        .collect()
}

/// [`node_otfs`] and each defocused node's lane `w ∂H/∂w` beside its value (`None` for a table
/// or a radial pupil): the values those of [`node_otfs`] bit for bit (the same points in the
/// same batches, [`crate::otf::defocus_otf_many_and_log_derivative_within`]).
pub(super) fn node_otfs_and_lanes(
    nodes: &[&Node],
    nu: f64,
    f_number: f64,
    azimuth_from_field: f64,
) -> (Vec<f64>, Vec<Option<f64>>) {
    let nuf = nu * f_number;
    let points = defocused_points(nodes, nuf);
    let (mut defocused, mut lanes) = (vec![0.0; points.len()], vec![0.0; points.len()]);
    crate::otf::defocus_otf_many_and_log_derivative_within(&points, &mut defocused, &mut lanes, 0.0);
    let mut next = defocused.into_iter().zip(lanes);
    nodes
        .iter()
        .map(|n| match n.is_defocused_circle() {
            true => next.next().map_or((0.0, Some(0.0)), |(v, d)| (v, Some(d))),
            false => (n.otf(nuf * n.lambda, nu, azimuth_from_field), None),
        })
        .unzip()
}

/// A circular iris, centred or decentred, on an order whose only aberration is defocus: exactly
/// the centred circle of the iris's radius `r` (F-number `F#/r`) with the defocus `W020 r²` at
/// its edge and the tilt `2 W020 d` that moves the image by `Δ = 2 W020 d/NA`
/// (`fft::reduce_decentred_circle`; docs/physics.md, "General pupils"), which the exact 1-D path
/// computes with the tilt's phase `exp(−2πi ν·Δ)`.
fn reduced_circle(order: &Order, na: f64) -> Option<crate::fft::ReducedCircle> {
    let Pupil::Aperture(aperture) = &order.pupil else { return None };
    if !order.wavefront.is_defocus_only() {
        return None;
    }
    let (centre, radius) = aperture.as_circle()?;
    crate::fft::reduce_decentred_circle(centre, radius, order.wavefront.defocus_m, na).ok()
}

/// Whether `order` needs the FFT layer: a pupil other than the full circle or (with `irises`) a
/// circular iris (an annulus, a sector, a mask, a composite of zones), or a wavefront beyond
/// defocus; a tabulated OTF is read directly.
pub(super) fn needs_grid(order: &Order, irises: bool) -> bool {
    match &order.pupil {
        Pupil::Full => !order.wavefront.is_defocus_only(),
        Pupil::Table(_) => false,
        Pupil::Radial(p) => !(p.is_symmetric() && order.wavefront.is_defocus_only()),
        Pupil::Aperture(a) => !(irises && order.wavefront.is_defocus_only() && a.as_circle().is_some()),
        _ => true,
    }
}

/// A spectral panel: its interval, its nodes `nodes[start..end]` and the scene's part they
/// belong to ([`Scene::part`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Panel {
    pub lo: f64,
    pub hi: f64,
    pub start: usize,
    pub end: usize,
    pub part: usize,
}

/// What a spectral rule produces.
#[derive(Clone, Debug, Default)]
pub(super) struct Nodes {
    pub nodes: Vec<Node>,
    /// (λ, rule weight, part) at every node wavelength, before the lens: `∫ ρ_p f ≈ Σ w f(λ)`
    /// over the samples of part p, `ρ_p` the part's spectrum ([`Scene::part`]; the detected
    /// spectrum for a scene of one part)
    pub samples: Vec<(f64, f64, usize)>,
    pub panels: Vec<Panel>,
    /// Σ node weights, panel by panel in the order the engines sum (so that OTF(0) is 1)
    pub total_weight: f64,
    /// whether some order needs the FFT layer
    pub needs_grid: bool,
    /// product-integration nodes: their weights are not `q ρ(λ)`, so a panel cannot be clipped
    /// at a cutoff inside it (the rule is only chosen where no cutoff falls inside the band)
    pub interpolated: bool,
    /// the wavelength of a line spectrum (one node per order, no panels)
    pub line: Option<f64>,
    /// The detected spectrum's value at each of `samples`' wavelengths, in their order, where
    /// the engine computed it already (the closed form's nodes, `q ρ(λ)`): the densities the
    /// frequency rule's `resolved_defocus` reads, not computed twice.
    pub densities: Option<Vec<f64>>,
}

impl Nodes {
    /// Appends the nodes of every order of the scene's lens at `lambda` with rule weight `q`,
    /// marked as of `part` (`scene` is that part's, [`Scene::part`]).
    pub fn emit(&mut self, scene: &Scene<'_>, lambda: f64, q: f64, part: usize) {
        let orders = scene.lens.orders(lambda, scene.field);
        let rates = shift_rates(scene, lambda, &orders);
        for (o, order) in orders.into_iter().enumerate() {
            self.needs_grid |= needs_grid(&order, scene.irises.is_some());
            let mut node = Node::of(&order, lambda, q * order.efficiency, scene.irises, scene.table_rule);
            node.part = part;
            node.shift_rate = rates.as_ref().and_then(|r| r.get(o)).copied();
            node.order = o;
            self.nodes.push(node);
        }
    }

    /// Whether the OTF of these nodes depends on direction: some image is displaced (lateral
    /// colour), or some tabulated order has different tangential and sagittal curves.
    pub fn direction_dependent(&self) -> bool {
        self.nodes.iter().any(|n| n.shift != [0.0, 0.0] || n.table.as_ref().is_some_and(|t| t.is_direction_dependent()))
    }

    /// Whether some node's image is displaced.
    pub fn shifted(&self) -> bool {
        self.nodes.iter().any(|n| n.shift != [0.0, 0.0])
    }

    /// The shortest wavelength covered: a line's, or the first panel's lower end.
    pub fn shortest(&self) -> f64 {
        self.line.or(self.panels.first().map(|p| p.lo)).unwrap_or(0.0)
    }

    /// The parts the samples (and so the nodes and panels) belong to, each once, in order.
    pub fn parts(&self) -> Vec<usize> {
        let mut parts: Vec<usize> = self.samples.iter().map(|s| s.2).collect();
        parts.sort_unstable();
        parts.dedup();
        parts
    }

    /// The nodes' mean wavelength `λ̄ = Σ w λ / Σ w` and variance `⟨u²⟩ = Σ w (λ − λ̄)² / Σ w`
    /// (node weights, efficiencies included): the centre of the
    /// [`WavefrontDirection::SpectralMoment`](super::WavefrontDirection::SpectralMoment) lanes.
    pub fn wavelength_moments(&self) -> (f64, f64) {
        let total = self.total_weight;
        let mean = self.nodes.iter().map(|n| n.weight * n.lambda).sum::<f64>() / total;
        let variance = self.nodes.iter().map(|n| n.weight * (n.lambda - mean).powi(2)).sum::<f64>() / total;
        (mean, variance)
    }

    pub fn sum_weights(&mut self) {
        self.total_weight =
            self.panels.iter().map(|p| self.nodes[p.start..p.end].iter().map(|n| n.weight).sum::<f64>()).sum();
    }
}

/// The part index of nodes and panels of the whole lens through the detected spectrum (the rules
/// that do not factor): [`Scene::part`] of it is the scene's whole lens and spectrum.
pub(super) const WHOLE: usize = usize::MAX;

/// The scene as the spectral rules see it.
#[derive(Clone, Copy)]
pub(super) struct Scene<'a> {
    pub lens: &'a dyn LensModel,
    pub detected: &'a Spectrum,
    pub field: Field,
    pub f_number: f64,
    pub max_frequency: f64,
    pub pixel_pitch: Option<f64>,
    /// the lens's numerical aperture where circular irises go to the exact path
    /// ([`Settings::exact_irises`](super::Settings::exact_irises)), else `None`
    pub irises: Option<f64>,
    /// the radial engine's rule for a pupil with a table's knots
    /// ([`Settings::table_rule`](super::Settings::table_rule))
    pub table_rule: crate::radial::TableRule,
    /// the lens's factored parts ([`Polychromatic::with_parts`](super::Polychromatic::with_parts)):
    /// product integration sums each part's orders with the moments of the part's own spectrum;
    /// empty, the lens and the detected spectrum are the one part
    pub parts: &'a [super::Part<'a>],
    /// whether the FFT path computes each aperture grid's obscuration lane in the value's pass
    /// ([`Settings::edge_lane`](super::Settings::edge_lane))
    pub edge_lane: bool,
    /// the FFT grids this engine shares with others of the same lens and field
    /// ([`Polychromatic::with_shared_grids`](super::Polychromatic::with_shared_grids))
    pub shared: Option<&'a super::SharedGrids>,
}

impl<'a> Scene<'a> {
    /// How many parts product integration sums ([`parts`](Self::parts); 1 without any).
    pub fn part_count(&self) -> usize {
        self.parts.len().max(1)
    }

    /// The scene of part `p`: its lens and spectrum, no parts; the scene itself without parts,
    /// and for [`WHOLE`].
    pub fn part(&self, p: usize) -> Scene<'a> {
        match self.parts.get(p) {
            Some(part) => Scene { lens: part.lens, detected: part.detected, parts: &[], ..*self },
            None => *self,
        }
    }

    /// The whole lens through the detected spectrum, as one part (the rules that do not
    /// factor: the reference panels, a line, the closed form).
    pub fn whole(&self) -> Scene<'a> {
        Scene { parts: &[], ..*self }
    }

    /// The field direction on the detector, radians from `+x`: `atan2(y, x)` of the field
    /// angles, `+x` on axis (docs/physics.md, "Off-axis MTFs: tangential and sagittal"); a
    /// tabulated order's tangential curve lies along it.
    pub fn field_direction(&self) -> f64 {
        self.field.y_rad.atan2(self.field.x_rad)
    }
}

impl std::fmt::Debug for Scene<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Scene {{ F# = {}, ν_max = {} }}", self.f_number, self.max_frequency)
    }
}

/// Efficiency, relative to the sum over the orders, below which an order does not count in the
/// spectral panels' phase-turn rule (it cannot move the OTF by more than that).
const NEGLIGIBLE_EFFICIENCY: f64 = 1e-9;

/// Efficiency, relative to the sum over the orders, up to which an order may be present at one
/// end of a spectral panel and absent at the other without counting as a jump ([`largest_turn`]):
/// an order entering or leaving the window of a harmonic lens (`sinc²(3 − δ) ≈ δ²/9` at the window
/// edge), whose weight jumps by no more than that whatever the panel.
const VANISHING_EFFICIENCY: f64 = 1e-3;

/// One order's defocus at one wavelength for the phase-turn rule, with whether its efficiency
/// is small enough to appear or vanish between neighbouring wavelengths.
#[derive(Clone, Copy, Debug)]
pub(super) struct PhaseEntry {
    pub w020: f64,
    pub vanishing: bool,
}

/// The defocus values whose phase the spectral panels must resolve at `lambda`, sorted: one per
/// order of non-negligible efficiency, one per zone (of non-zero amplitude) of a composite pupil
/// (each with its order's efficiency), none for a tabulated OTF (its rows are interpolated
/// linearly in λ and the panels are cut at them).
fn phase_defocus(lens: &dyn LensModel, lambda: f64, field: Field) -> Vec<PhaseEntry> {
    let orders = lens.orders(lambda, field);
    let total: f64 = orders.iter().map(|o| o.efficiency.abs()).sum();
    let mut out = Vec::new();
    for o in orders.iter().filter(|o| o.efficiency.abs() > NEGLIGIBLE_EFFICIENCY * total) {
        let vanishing = o.efficiency.abs() <= VANISHING_EFFICIENCY * total;
        match &o.pupil {
            Pupil::Table(_) => {}
            Pupil::Zones(zones) => out.extend(
                zones
                    .iter()
                    .filter(|z| z.amplitude > 0.0)
                    .map(|z| PhaseEntry { w020: z.wavefront.defocus_m, vanishing }),
            ),
            _ => out.push(PhaseEntry { w020: o.wavefront.defocus_m, vanishing }),
        }
    }
    out.sort_by(|a, b| a.w020.total_cmp(&b.w020));
    out
}

/// The largest change of one order's defocus between two neighbouring wavelengths whose defocus
/// lists ([`phase_defocus`], sorted) are `from` and `to`.
///
/// Orders carry no identity across wavelengths, so they are matched: by the monotone alignment
/// of the sorted lists that leaves the fewest orders of non-vanishing efficiency unmatched, and
/// among those the smallest largest change (a bottleneck alignment, by dynamic programming). An
/// order entering or leaving the window of a harmonic lens, with an efficiency near zero there,
/// stays unmatched (its weight jumps by that little, which no panel refines away), while the
/// channels of a multiplexed lens, all bright, are matched one to one in W020 order, which is
/// their own order since their defocus curves do not cross: a shift of every channel by one
/// channel spacing across a panel counts as that large change, not as none. Measuring the
/// largest-|W020| order alone jumped between orders of opposite sign, and matching by list
/// index alone mistook a shifted window (orders 1–6 → 2–7) for a jump of every order; both
/// refined without end (the panel bound, 2^20 panels, for an interleaved or harmonic lens over
/// 50–200 nm).
pub(super) fn largest_turn(from: &[PhaseEntry], to: &[PhaseEntry]) -> f64 {
    let (n, m) = (from.len(), to.len());
    // cost[i][j]: (unmatched bright orders, largest change) aligning from[..i] with to[..j],
    // compared lexicographically (the sum in the first and the maximum in the second are both
    // monotone, so the cell-wise minimum is the optimum)
    let mut cost = vec![(usize::MAX, f64::INFINITY); (n + 1) * (m + 1)];
    let at = |i: usize, j: usize| i * (m + 1) + j;
    cost[at(0, 0)] = (0, 0.0);
    let better = |a: (usize, f64), b: (usize, f64)| a.0 < b.0 || (a.0 == b.0 && a.1 < b.1);
    for i in 0..=n {
        for j in 0..=m {
            let mut best = cost[at(i, j)];
            if i > 0 && cost[at(i - 1, j)].0 != usize::MAX {
                let (c, t) = cost[at(i - 1, j)];
                let candidate = (c + usize::from(!from[i - 1].vanishing), t);
                if better(candidate, best) {
                    best = candidate;
                }
            }
            if j > 0 && cost[at(i, j - 1)].0 != usize::MAX {
                let (c, t) = cost[at(i, j - 1)];
                let candidate = (c + usize::from(!to[j - 1].vanishing), t);
                if better(candidate, best) {
                    best = candidate;
                }
            }
            if i > 0 && j > 0 && cost[at(i - 1, j - 1)].0 != usize::MAX {
                let (c, t) = cost[at(i - 1, j - 1)];
                let candidate = (c, t.max((from[i - 1].w020 - to[j - 1].w020).abs()));
                if better(candidate, best) {
                    best = candidate;
                }
            }
            cost[at(i, j)] = best;
        }
    }
    cost[at(n, m)].1
}

/// The defocus phase (rad, at frequency `highest`) that the OTF turns through across each of
/// `n` equal panels of `[a, b]`: per order (docs/physics.md, "Spectral quadrature": the OTF
/// turns with the defocus in waves at each s), the change of W020 across the panel plus the
/// change of s = ν λ F# times the largest |W020|, times `8π F# ν`.
///
/// The interval's ends are read just inside it: a lens may jump at its own breakpoints (the band
/// edges of a multiplexed lens whose other channels are background), which are the interval's
/// ends, and a jump there is no turn of the phase inside (no node reaches the ends).
fn panel_turns(scene: &Scene<'_>, highest: f64, a: f64, b: f64, n: usize) -> Vec<f64> {
    let (lens, field, f_number) = (scene.lens, scene.field, scene.f_number);
    let phase_per_w020 = 8.0 * PI * f_number * highest;
    let h = (b - a) / n as f64;
    let inside = 1e-9 * (b - a);
    let mut prev = phase_defocus(lens, a + inside, field);
    let mut out = Vec::with_capacity(n);
    for k in 1..=n {
        let x = if k == n { b - inside } else { a + h * k as f64 };
        let cur = phase_defocus(lens, x, field);
        let mid = phase_defocus(lens, x - 0.5 * h, field);
        let largest = cur.iter().chain(&prev).map(|e| e.w020.abs()).fold(0.0, f64::max);
        let turn = largest_turn(&prev, &cur).max(largest_turn(&prev, &mid)) + largest * highest * f_number * h;
        out.push(turn * phase_per_w020);
        prev = cur;
    }
    out
}

/// The most panels one interval may be cut into: a bound, so that no finite input asks for more
/// panels than memory and time allow.
const MAX_INTERVAL_PANELS: usize = 1 << 20;

/// The wavelengths where the lens may kink or jump inside `[lo, hi]`: its breakpoints and the
/// rows of its OTF tables, with `lo` and `hi`, sorted; with `spectrum`, the spectrum's kinks too.
fn cuts(scene: &Scene<'_>, lo: f64, hi: f64, spectrum: bool) -> Vec<f64> {
    let mut cuts: Vec<f64> = scene.lens.breakpoints();
    cuts.extend(table_wavelengths(scene.lens, scene.field, lo, hi));
    if spectrum {
        cuts.extend(scene.detected.breakpoints());
    }
    cuts.retain(|&b| b > lo && b < hi);
    cuts.push(lo);
    cuts.push(hi);
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    cuts
}

/// The highest frequency whose OTF the spectral rule must resolve: the frequency limit, or the
/// cutoff of the shortest wavelength covered when that is lower.
fn highest_frequency(scene: &Scene<'_>, lo: f64) -> f64 {
    let cutoff = if lo > 0.0 { 1.0 / (lo * scene.f_number) } else { f64::INFINITY };
    scene.max_frequency.min(cutoff)
}

/// The per-interval rule (the reference): 16-point Gauss–Legendre panels cut at every kink of
/// the spectrum and of the lens, each at most 2σ of the narrowest Gaussian factor wide and turned
/// through at most [`quad::MAX_PANEL_PHASE`] of defocus phase at the highest frequency.
pub(super) fn panels(scene: &Scene<'_>, lo: f64, hi: f64) -> Nodes {
    let detected = scene.detected;
    let sigma_min = detected.gaussians().iter().map(|g| g.sigma()).fold(f64::INFINITY, f64::min);
    let highest = highest_frequency(scene, lo);
    let mut out = Nodes::default();
    for pair in cuts(scene, lo, hi, true).windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let mut n = ((b - a) / (2.0 * sigma_min)).ceil().max(1.0) as usize;
        loop {
            let worst = panel_turns(scene, highest, a, b, n).into_iter().fold(0.0, f64::max);
            if worst <= quad::MAX_PANEL_PHASE || n > MAX_INTERVAL_PANELS {
                break;
            }
            n = (n as f64 * (worst / quad::MAX_PANEL_PHASE).min(64.0)).ceil() as usize + 1;
        }
        let h = (b - a) / n as f64;
        for k in 0..n {
            let (plo, phi) = (a + h * k as f64, a + h * (k + 1) as f64);
            let start = out.nodes.len();
            quad::for_each_node(plo, phi, 1, |lambda, q| {
                let q_rho = q * detected.value(lambda);
                out.samples.push((lambda, q_rho, WHOLE));
                if q_rho != 0.0 {
                    out.emit(scene, lambda, q_rho, WHOLE);
                }
            });
            out.panels.push(Panel { lo: plo, hi: phi, start, end: out.nodes.len(), part: WHOLE });
        }
    }
    out.sum_weights();
    out
}

/// The lens's image shift rates at `lambda` (`LensModel::image_shift_field_rates`) for its
/// `orders` there: the exact engine's field lanes. Off axis, and on axis where an order has an
/// iris (a decentred iris makes the OTF depend on direction there; docs/physics.md,
/// "Gradients: the iris"); on axis without one the OTF is rotationally symmetric and takes no
/// field lane.
fn shift_rates(scene: &Scene<'_>, lambda: f64, orders: &[Order]) -> Option<Vec<[f64; 2]>> {
    let iris = || scene.irises.is_some() && orders.iter().any(|o| matches!(o.pupil, Pupil::Aperture(_)));
    if scene.field.is_on_axis() && !iris() { None } else { scene.lens.image_shift_field_rates(lambda, scene.field) }
}

/// Emits the nodes of `[lo, cut]` in `u`, `λ = cut − (cut − lo) u²`, for a panel of the reference
/// rule clipped at the cutoff `cut` (the `(1 − s)^{3/2}` edge of the OTF becomes smooth in `u`).
pub(super) fn clipped_nodes(scene: &Scene<'_>, lo: f64, cut: f64, mut emit: impl FnMut(Node)) {
    let len = cut - lo;
    quad::for_each_node(0.0, 1.0, 1, |u, q| {
        let lambda = cut - len * u * u;
        let rho = scene.detected.value(lambda);
        if rho == 0.0 {
            return;
        }
        let q = q * 2.0 * len * u * rho;
        let orders = scene.lens.orders(lambda, scene.field);
        let rates = shift_rates(scene, lambda, &orders);
        for (o, order) in orders.into_iter().enumerate() {
            let mut node = Node::of(&order, lambda, q * order.efficiency, scene.irises, scene.table_rule);
            node.shift_rate = rates.as_ref().and_then(|r| r.get(o)).copied();
            node.order = o;
            emit(node);
        }
    });
}

/// The nodes of a line spectrum: one per imaging order at its wavelength, weighted by the line's
/// weight × the order's efficiency.
pub(super) fn line(scene: &Scene<'_>, line: radiometry::QuadratureNode) -> Nodes {
    let lambda = line.wavelength_m;
    let mut out = Nodes { line: Some(lambda), samples: vec![(lambda, line.weight, WHOLE)], ..Nodes::default() };
    out.emit(scene, lambda, line.weight, WHOLE);
    out.total_weight = out.nodes.iter().map(|n| n.weight).sum();
    out
}

/// Share of the tolerance that the spectral rule may spend (the frequency rule has the rest).
pub(super) const SPECTRAL_SHARE: f64 = 0.25;

/// Largest phase (rad, at the frequency limit) of one product-integration panel: its points
/// then start at about a third of that (`e^{iκx}` needs about κ points, κ = phase/2) and double
/// until the nested check passes.
const INTERPOLATION_PANEL_PHASE: f64 = 48.0;

/// The point counts of the nested Chebyshev–Lobatto rules: each level's points are the even
/// points of the next.
pub(super) const LEVELS: [usize; 7] = [3, 5, 9, 17, 33, 65, 129];

/// The degree a panel's moment rule is first built for: the levels up to 33 points (most
/// panels stop there; a finer level rebuilds it, [`Interpolant::moments`]).
pub(super) const FIRST_MOMENT_DEGREE: usize = 32;

/// Bound on the Lebesgue constant of Chebyshev–Lobatto interpolation up to 129 points
/// (`(2/π) ln(n) + 1` < 4): an interpolant of a function bounded by 1 is bounded by this, so a
/// panel whose weight share × 2 × this is within its budget needs no resolution at all.
pub(super) const LEBESGUE: f64 = 4.0;

/// The product-integration rule (see the module docs), or `None` where it does not apply: a
/// cutoff `1/(λ F#)` of some covered wavelength below the frequency limit (the OTF then has the
/// edge `(1 − s)^{3/2}` inside the band, which the panels rule clips at).
///
/// `tolerance` is the relative tolerance of the mean MTF; the rule spends [`SPECTRAL_SHARE`] of
/// it on the polychromatic OTF at the frequency limit, where its λ-dependence is fastest, shared
/// between the panels in proportion to the square root of their weight. A panel's points double (nested
/// Chebyshev–Lobatto rules) until the product integral of its part of the OTF there moves by
/// less than its share; the error of the accepted rule is then far below that difference. The
/// share is relative to the mean MTF, estimated from the OTF at ¼, ½ and 1 of the limit once
/// the nodes exist; where the estimate is below the first pass's guess of 1, the panels are
/// refined again to the smaller share. Last, each panel is cut back to the fewest
/// Chebyshev–Lobatto points within its share of the accepted level ([`Interpolant::trim`]).
pub(super) fn interpolated(scene: &Scene<'_>, lo: f64, hi: f64, tolerance: f64) -> Option<Nodes> {
    let top = scene.max_frequency;
    let Start { mut panels, total_mass } = start(scene, lo, hi)?;
    // the budget is shared in proportion to √(weight share): a panel of little weight may be
    // less accurate per unit weight, and the sum of the shares' errors stays within it
    let allowance = |panels: &[Interpolant], estimate: f64| {
        let budget = SPECTRAL_SHARE * tolerance * estimate;
        let roots: f64 = panels.iter().map(|p| (p.mass.abs() / total_mass).sqrt()).sum::<f64>().max(f64::MIN_POSITIVE);
        move |p: &Interpolant| {
            let share = p.mass.abs() / total_mass;
            budget * share.sqrt() / roots / share
        }
    };
    let mut estimate = 1.0;
    for _pass in 0..3 {
        let allowed_of = allowance(&panels, estimate);
        let mut k = 0;
        while k < panels.len() {
            let share = panels[k].mass.abs() / total_mass;
            if share == 0.0 {
                k += 1;
                continue;
            }
            let allowed = allowed_of(&panels[k]);
            let part = scene.part(panels[k].part);
            if panels[k].refine(&part, top, allowed) {
                k += 1;
            } else {
                // beyond the most points: halve the panel (its phase halves with it)
                let (low, high) = panels.remove(k).halves(part.detected);
                panels.insert(k, high);
                panels.insert(k, low);
            }
        }
        let nodes = emit(scene, &panels);
        let mean = mean_estimate(scene, &nodes, top).clamp(1e-9, 1.0);
        if mean >= 0.5 * estimate {
            estimate = estimate.min(mean);
            break;
        }
        estimate = mean;
    }
    // Every node costs the engine an OTF at each frequency of the mean (tens of exact OTFs, or an
    // FFT grid: a pupil field, two transforms, its autocorrelation, ~0.5 ms at 128 samples),
    // against one exact OTF per point tried here: each panel keeps the fewest
    // Chebyshev–Lobatto points, between its nested levels, that are within its share of the
    // accepted level's value.
    let allowed_of = allowance(&panels, estimate);
    for p in &mut panels {
        if p.mass != 0.0 {
            let allowed = allowed_of(p);
            p.trim(&scene.part(p.part), top, allowed);
        }
    }
    Some(emit(scene, &panels))
}

/// The defocus lane's own spectral rule beside the value's product-integration nodes (docs/physics.md,
/// "Gradients: the F-number and the focal length with Seidel terms"): on each of the value's
/// panels, whose `n` points are Chebyshev–Lobatto (a nested level, or the fewest points
/// [`Interpolant::trim`] kept), the `2n − 1` Chebyshev–Lobatto points of the next nested rule —
/// its even points are the value's, the same wavelengths bit for bit (`cos(π·2k/(2n − 2))` is
/// `cos(πk/(n − 1))`: the factor 2 is exact) — with the product-integration weights of the
/// panel's part's spectrum on them ([`lobatto_weights`] of its exact moments), as `(λ, weight,
/// part)`. `None` where the nodes are not product integration's or a panel's doubled rule
/// would pass the finest level ([`LEVELS`]: `n > 65`).
pub(super) fn doubled(scene: &Scene<'_>, nodes: &Nodes) -> Option<Vec<(f64, f64, usize)>> {
    if !nodes.interpolated || nodes.panels.is_empty() {
        return None;
    }
    let most = LEVELS[LEVELS.len() - 1];
    let mut out = Vec::new();
    for panel in &nodes.panels {
        let n = nodes.samples.iter().filter(|s| s.2 == panel.part && s.0 > panel.lo && s.0 < panel.hi).count();
        if n < 2 || 2 * n - 1 > most {
            return None;
        }
        let points = 2 * n - 1;
        let part = scene.part(panel.part);
        let density = Density::of(part.detected);
        let mut interpolant = Interpolant::new(part.detected, &density, panel.lo, panel.hi, 0.0, panel.part);
        let mu = interpolant.moments(part.detected, points - 1).to_vec();
        let weights = lobatto_weights(&mu, points);
        for (lambda, w) in lobatto_lambdas(panel.lo, panel.hi, points).into_iter().zip(weights) {
            out.push((lambda, w, panel.part));
        }
    }
    Some(out)
}

/// The product-integration panels of `[lo, hi]` before any point is placed, part by part
/// ([`Scene::part`]): cut at the part's lens's breakpoints and where its set of orders changes,
/// each turning by at most [`INTERPOLATION_PANEL_PHASE`] at the frequency limit, with their
/// moment rules of the part's spectrum; `None` where the rule does not apply (a cutoff
/// `1/(λ F#)` below the limit, or no weight in any part).
pub(super) struct Start {
    pub panels: Vec<Interpolant>,
    /// `Σ |∫ ρ_p|` over the panels
    pub total_mass: f64,
}

pub(super) fn start(scene: &Scene<'_>, lo: f64, hi: f64) -> Option<Start> {
    let top = scene.max_frequency;
    // s = ν λ F# < 1 on the whole band up to the limit
    if top * hi * scene.f_number >= 1.0 - 1e-6 || lo <= 0.0 {
        return None;
    }
    let mut panels: Vec<Interpolant> = Vec::new();
    for part in 0..scene.part_count() {
        part_panels(&scene.part(part), part, lo, hi, &mut panels);
    }
    let total_mass: f64 = panels.iter().map(|p| p.mass.abs()).sum();
    (total_mass > 0.0 && total_mass.is_finite()).then_some(Start { panels, total_mass })
}

/// [`start`]'s panels of one part (`scene` is the part's) appended to `panels`.
fn part_panels(scene: &Scene<'_>, part: usize, lo: f64, hi: f64, panels: &mut Vec<Interpolant>) {
    let top = scene.max_frequency;
    let density = Density::of(scene.detected);
    let mut lens_cuts = cuts(scene, lo, hi, false);
    lens_cuts.extend(order_changes(scene, &lens_cuts));
    lens_cuts.sort_by(f64::total_cmp);
    lens_cuts.dedup();
    for pair in lens_cuts.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let sub = 32;
        let turns = panel_turns(scene, top, a, b, sub);
        let total: f64 = turns.iter().sum();
        let n = ((total / INTERPOLATION_PANEL_PHASE).ceil() as usize).clamp(1, MAX_INTERVAL_PANELS);
        let h = (b - a) / n as f64;
        for k in 0..n {
            let (pa, pb) = (a + h * k as f64, if k + 1 == n { b } else { a + h * (k + 1) as f64 });
            let phase = overlap_sum(&turns, a, b, pa, pb);
            panels.push(Interpolant::new(scene.detected, &density, pa, pb, phase, part));
        }
    }
}

/// The nodes of the accepted rules, panel by panel.
fn emit(scene: &Scene<'_>, panels: &[Interpolant]) -> Nodes {
    let mut out = Nodes { interpolated: true, ..Nodes::default() };
    for p in panels {
        if p.mass == 0.0 {
            continue;
        }
        let start = out.nodes.len();
        let part = scene.part(p.part);
        for (&lambda, &w) in p.lambdas().iter().zip(&p.weights) {
            out.samples.push((lambda, w, p.part));
            if w != 0.0 {
                out.emit(&part, lambda, w, p.part);
            }
        }
        out.panels.push(Panel { lo: p.a, hi: p.b, start, end: out.nodes.len(), part: p.part });
    }
    out.sum_weights();
    out
}

/// The mean MTF estimated from the polychromatic OTF of `nodes` at ¼, ½ and 1 of `top` (a
/// three-point midpoint-like average, with the pixel MTF), for the spectral budget.
fn mean_estimate(scene: &Scene<'_>, nodes: &Nodes, top: f64) -> f64 {
    if !(nodes.total_weight > 0.0 && nodes.total_weight.is_finite()) {
        return 1.0;
    }
    let pixel = |nu: f64| scene.pixel_pitch.map_or(1.0, |p| pixel_mtf(p, nu));
    let mut sum = 0.0;
    for f in [0.25, 0.5, 1.0] {
        let nu = f * top;
        let all: Vec<&Node> = nodes.nodes.iter().collect();
        let mut g = Complex64::new(0.0, 0.0);
        for (n, value) in all.iter().zip(node_otfs(&all, nu, scene.f_number, 0.0)) {
            let shift = n.shift[0].hypot(n.shift[1]);
            g += Complex64::from_polar(n.weight * value, -2.0 * PI * nu * shift);
        }
        sum += (g / nodes.total_weight).norm() * pixel(nu);
    }
    sum / 3.0
}

/// The part `Σ_o τ_o OTF_o` of the OTF at `nu` of the lens's orders at each of `lambdas`, all
/// their orders' OTFs at once ([`node_otfs`]).
fn lens_values(scene: &Scene<'_>, lambdas: &[f64], nu: f64) -> Vec<Complex64> {
    let mut nodes: Vec<(usize, Node, f64)> = Vec::new();
    for (i, &lambda) in lambdas.iter().enumerate() {
        for o in scene.lens.orders(lambda, scene.field) {
            nodes.push((i, Node::of(&o, lambda, 0.0, scene.irises, scene.table_rule), o.efficiency));
        }
    }
    let all: Vec<&Node> = nodes.iter().map(|(_, n, _)| n).collect();
    let mut out = vec![Complex64::new(0.0, 0.0); lambdas.len()];
    for ((i, n, efficiency), value) in nodes.iter().zip(node_otfs(&all, nu, scene.f_number, 0.0)) {
        let shift = n.shift[0].hypot(n.shift[1]);
        out[*i] += Complex64::from_polar(value, -2.0 * PI * nu * shift) * efficiency;
    }
    out
}

/// The wavelengths of the `points` Chebyshev–Lobatto points of `[a, b]` (k = 0 at `b`), moved
/// 1e-12 of the panel inside its ends: a lens may jump at its own breakpoints, which are panel
/// ends.
pub(super) fn lobatto_lambdas(a: f64, b: f64, points: usize) -> Vec<f64> {
    let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
    let inside = 1e-12 * (b - a);
    (0..points)
        .map(|k| {
            let x = if points > 1 { (PI * k as f64 / (points - 1) as f64).cos() } else { 0.0 };
            (c + h * x).clamp(a + inside, b - inside)
        })
        .collect()
}

/// One product-integration panel: its moment rule, its current nested level, and the lens's
/// part of the OTF at the frequency limit on that level's points.
pub(super) struct Interpolant {
    pub a: f64,
    pub b: f64,
    /// the lens's defocus phase turn across the panel at the frequency limit, rad
    pub phase: f64,
    /// `∫ ρ_p` over the panel
    pub mass: f64,
    /// the scene's part whose spectrum weights the panel and whose orders it sums
    /// ([`Scene::part`])
    pub part: usize,
    rule: Arc<MomentRule>,
    /// the Chebyshev moments `μ_0 …` computed so far (see [`moments`](Self::moments))
    mu: Vec<f64>,
    /// the detected spectrum as the moment rules read it (for a rule of higher degree)
    density: Arc<Density>,
    /// index into [`LEVELS`] of the accepted (or current) rule; `None` before the first
    level: Option<usize>,
    /// the lens's OTF at the limit on the current level's points
    values: Vec<Complex64>,
    /// product-integration weights of the current level
    weights: Vec<f64>,
    /// the moves between consecutive levels so far (index: the finer level − 1)
    moves: Vec<f64>,
    /// the error estimate (per unit weight) of the accepted level
    error: f64,
}

impl Interpolant {
    pub fn new(detected: &Spectrum, density: &Arc<Density>, a: f64, b: f64, phase: f64, part: usize) -> Interpolant {
        let rule = density.rule(detected, a, b, FIRST_MOMENT_DEGREE);
        // all the moments the first levels will ask for, in the one pass over the breakpoints
        // that the mass alone would take (a second pass for them cost 2 % of a spectrometer
        // evaluation)
        let mu = density.moments(&rule, a, b, FIRST_MOMENT_DEGREE.min(rule.degree()));
        Interpolant {
            a,
            b,
            phase,
            mass: mu[0],
            part,
            rule,
            mu,
            density: density.clone(),
            level: None,
            values: Vec::new(),
            weights: Vec::new(),
            moves: Vec::new(),
            error: f64::INFINITY,
        }
    }

    /// `μ_0 … μ_degree` of the panel's weight, computed once up to the degree its moment rule
    /// was built for ([`FIRST_MOMENT_DEGREE`], enough for the levels to 33 points): a higher
    /// degree rebuilds the rule for the finest level (more points where its Chebyshev
    /// polynomials turn faster) and computes them all again.
    pub fn moments(&mut self, detected: &Spectrum, degree: usize) -> &[f64] {
        if degree > self.rule.degree() {
            let most = LEVELS[LEVELS.len() - 1] - 1;
            self.rule = self.density.rule(detected, self.a, self.b, most);
            self.mu.clear();
        }
        if self.mu.len() <= degree {
            // a quadrature rule's moments all at once up to its degree; exact ones as asked
            let up_to = match *self.rule {
                MomentRule::Points { degree: built, .. } => built,
                MomentRule::Exact { .. } => degree.max(FIRST_MOMENT_DEGREE),
            };
            self.mu = self.density.moments(&self.rule, self.a, self.b, up_to);
        }
        &self.mu[..=degree]
    }

    /// The panel's two halves, fresh (the phase halves with each), for a panel whose finest
    /// level does not settle; `detected` is the spectrum of its part.
    pub fn halves(&self, detected: &Spectrum) -> (Interpolant, Interpolant) {
        let mid = 0.5 * (self.a + self.b);
        let half = |a: f64, b: f64| Interpolant::new(detected, &self.density, a, b, 0.5 * self.phase, self.part);
        (half(self.a, mid), half(mid, self.b))
    }

    /// The wavelengths of the current level's points (k = 0 at `b`), moved 1e-12 of the panel
    /// inside its ends: a lens may jump at its own breakpoints, which are panel ends.
    fn lambdas(&self) -> Vec<f64> {
        lobatto_lambdas(self.a, self.b, self.weights.len())
    }

    /// Sets the level, evaluating the lens at its new points only (the old ones are its even
    /// points).
    fn set_level(&mut self, scene: &Scene<'_>, top: f64, level: usize) {
        let points = LEVELS[level];
        let old = std::mem::take(&mut self.values);
        let step = match self.level {
            Some(l) if l < level => (LEVELS[level] - 1) / (LEVELS[l] - 1),
            _ => 0,
        };
        self.weights = lobatto_weights(self.moments(scene.detected, points - 1), points);
        let lambdas = self.lambdas();
        let fresh: Vec<usize> = (0..points).filter(|&k| !(step > 0 && k % step == 0)).collect();
        let wanted: Vec<f64> = fresh.iter().map(|&k| lambdas[k]).collect();
        let mut computed = lens_values(scene, &wanted, top).into_iter();
        self.values = (0..points)
            .map(|k| if step > 0 && k % step == 0 { old[k / step] } else { computed.next().unwrap_or_default() })
            .collect();
        self.level = Some(level);
    }

    /// Refines until the panel's part of the OTF at the limit, per unit of the panel's weight,
    /// is within `allowed` of the converged value. `false` when even the finest rule does not
    /// settle.
    ///
    /// The estimate compares each nested level with the one below. Once the level has about
    /// 0.6 κ points (κ = phase/2: `e^{iκx}` is then resolved and the interpolation error falls
    /// geometrically, `C ρ^{−n}`), the accepted level's error is estimated from the moves by
    /// [`nested_error_accelerated`](super::nested_error_accelerated) (measured on the chromatic lens over
    /// 600–1000 nm: moves of 4.9e-3 and 8.9e-6 at 17 and 33 points, 4.5e-14 left); below that,
    /// where a coarse pair can agree by chance, two consecutive moves must both be within
    /// `allowed`.
    fn refine(&mut self, scene: &Scene<'_>, top: f64, allowed: f64) -> bool {
        let resolved = 0.3 * self.phase + 1.0;
        if self.level.is_none() {
            // a panel whose weight is too small to matter takes the quadratic; else the levels
            // are climbed from 5 points (the coarse levels' points are the finer ones' even
            // points: climbing costs no evaluation that the accepted level does not make)
            let first = if 2.0 * LEBESGUE <= allowed { 0 } else { 1 };
            self.set_level(scene, top, first);
            if first == 0 {
                self.error = 2.0 * LEBESGUE;
                return true;
            }
        }
        loop {
            let level = self.level.unwrap_or(0);
            if level == 0 && 2.0 * LEBESGUE <= allowed {
                self.error = 2.0 * LEBESGUE;
                return true;
            }
            let points = LEVELS[level];
            if level > 0 {
                let half = LEVELS[level - 1];
                let coarse = lobatto_weights(self.moments(scene.detected, half - 1), half);
                let full: Complex64 = self.values.iter().zip(&self.weights).map(|(v, w)| v * w).sum();
                let step = (points - 1) / (half - 1);
                let part: Complex64 = coarse.iter().enumerate().map(|(k, w)| self.values[k * step] * w).sum();
                if self.moves.len() < level {
                    self.moves.push((full - part).norm() / self.mass.abs());
                }
                let moves = &self.moves;
                // once resolved, the nested estimate; before, two consecutive moves within the
                // budget (a coarse pair can agree by chance)
                let error = super::level_error(moves, points as f64 >= resolved, super::nested_error_accelerated);
                if error <= allowed {
                    self.error = error;
                    return true;
                }
            }
            if level + 1 == LEVELS.len() {
                return false;
            }
            // the two finest levels only where the moves already fall geometrically: a panel
            // whose last doubling (to 33 or 65 points) cut its move by less than
            // [`FINEST_LEVEL_RATIO`] is halved instead, at every tolerance (else a loose
            // tolerance accepts 65 or 129 points that a tight one halves into two cheaper
            // panels: more work at the looser tolerance)
            if level + 3 >= LEVELS.len()
                && let [.., before, last] = self.moves[..]
                && last > FINEST_LEVEL_RATIO * before
            {
                return false;
            }
            self.set_level(scene, top, level + 1);
        }
    }
}

/// The largest ratio of the last two moves (at 33 and 17, or 65 and 33 points) for which a
/// panel climbs to the next level (65, 129 points) rather than being halved
/// ([`Interpolant::refine`]). Once
/// `e^{iκx}` is resolved the moves fall by far more per doubling (4.9e-3 to 8.9e-6 from 17 to
/// 33 points on the chromatic lens over 600–1000 nm); a ratio above 0.1 there is a panel
/// turning faster than its defocus phase says (lateral colour: moves 2.3e-2, 7.2e-3 at 17 and 33
/// points on the 5° field point's central panel), whose halves settle at 17 points.
const FINEST_LEVEL_RATIO: f64 = 0.1;

impl Interpolant {
    /// The product integral of the panel's part of the OTF at the limit on the current points.
    fn integral(&self) -> Complex64 {
        self.values.iter().zip(&self.weights).map(|(v, w)| v * w).sum()
    }

    /// After [`refine`](Self::refine) accepted a level of `P` points: the fewest points `n`
    /// between the level below and `P` (Chebyshev–Lobatto, not nested) whose product integral
    /// is within `allowed` (per unit weight) of the accepted one, less that one's own error
    /// estimate; `P` stays where none is. The interpolation error falls geometrically in `n`
    /// once resolved, so the search is a bisection from the resolved count up.
    fn trim(&mut self, scene: &Scene<'_>, top: f64, allowed: f64) {
        let Some(level) = self.level else { return };
        if level < 2 || !self.error.is_finite() {
            return;
        }
        let (full_points, reference) = (LEVELS[level], self.integral());
        let spare = allowed - self.error;
        if spare <= 0.0 {
            return;
        }
        let mass = self.mass.abs();
        let mu = self.moments(scene.detected, full_points - 1).to_vec();
        let at = |n: usize| -> (Vec<f64>, Vec<Complex64>, f64) {
            let weights = lobatto_weights(&mu[..n], n);
            let probe = Interpolant { weights: weights.clone(), ..self.shallow() };
            let values = lens_values(scene, &probe.lambdas(), top);
            let sum: Complex64 = values.iter().zip(&weights).map(|(v, w)| v * w).sum();
            (weights, values, (sum - reference).norm() / mass)
        };
        // the smallest n that is resolved (the geometric regime) and passes
        let resolved = (0.3 * self.phase + 1.0).ceil() as usize;
        let (mut lo, mut hi) = (LEVELS[level - 1].max(resolved.saturating_sub(1)), full_points);
        if lo + 1 >= hi {
            // the accepted level is the first resolved one: nothing between to try
            return;
        }
        let mut best: Option<(Vec<f64>, Vec<Complex64>)> = None;
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            let (weights, values, difference) = at(mid);
            if difference <= spare {
                hi = mid;
                best = Some((weights, values));
            } else {
                lo = mid;
            }
        }
        if let Some((weights, values)) = best {
            self.weights = weights;
            self.values = values;
            self.error += (self.integral() - reference).norm() / mass;
        }
    }

    /// A copy of the panel's interval and moment rule without its values (for [`lambdas`]).
    fn shallow(&self) -> Interpolant {
        Interpolant {
            a: self.a,
            b: self.b,
            phase: self.phase,
            mass: self.mass,
            part: self.part,
            rule: Arc::new(MomentRule::Points { cos: Vec::new(), weight: Vec::new(), degree: 0 }),
            mu: Vec::new(),
            density: self.density.clone(),
            level: self.level,
            values: Vec::new(),
            weights: Vec::new(),
            moves: Vec::new(),
            error: self.error,
        }
    }
}

/// Where the set of orders changes inside the intervals between `cuts`: an order entering or
/// leaving (the window of a harmonic lens), or the whole set shifting by one order at once (the
/// same count, every order one spacing further). The lens's part of the OTF is not smooth there
/// (the entering order's efficiency rises from a double zero), which interpolation across it
/// would pay for in points; the panels are cut there instead. Located on 64 samples per
/// interval, each change then by bisection to 1e-13 of the interval.
fn order_changes(scene: &Scene<'_>, cuts: &[f64]) -> Vec<f64> {
    let same = |a: &[PhaseEntry], b: &[PhaseEntry]| {
        if a.len() != b.len() {
            return false;
        }
        // matched by index, as against the best alignment: a shifted set moves every order by
        // a spacing by index, by almost nothing aligned
        let by_index = a.iter().zip(b).map(|(x, y)| (x.w020 - y.w020).abs()).fold(0.0, f64::max);
        by_index <= 2.0 * largest_turn(a, b) + 1e-15 * a.iter().map(|e| e.w020.abs()).fold(0.0, f64::max)
    };
    let (lens, field) = (scene.lens, scene.field);
    let mut out = Vec::new();
    for pair in cuts.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let inside = 1e-9 * (b - a);
        let n = 64;
        let at = |k: usize| {
            if k == n {
                b - inside
            } else if k == 0 {
                a + inside
            } else {
                a + (b - a) * k as f64 / n as f64
            }
        };
        let mut prev = phase_defocus(lens, at(0), field);
        if prev.len() <= 1 && phase_defocus(lens, at(n), field).len() <= 1 {
            // one order at both ends: no set to change (a lens whose count goes 1 → 0 → 1 inside
            // is cut at its own breakpoints)
            continue;
        }
        for k in 1..=n {
            let cur = phase_defocus(lens, at(k), field);
            if !same(&prev, &cur) {
                let (mut lo, mut hi) = (at(k - 1), at(k));
                let left = prev.clone();
                // to 1e-13 of the interval, or to the doubles between (an interval of 0.08 nm
                // has fewer than 1e13 of them near 800 nm: the bisection stops at adjacent
                // doubles, where it looped for ever)
                loop {
                    let mid = 0.5 * (lo + hi);
                    if hi - lo <= 1e-13 * (b - a) || mid <= lo || mid >= hi {
                        break;
                    }
                    if same(&left, &phase_defocus(lens, mid, field)) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                out.push(0.5 * (lo + hi));
            }
            prev = cur;
        }
    }
    out
}

/// The part of `Σ turns` over the equal sub-steps of `[a, b]` that lies in `[pa, pb]`.
fn overlap_sum(turns: &[f64], a: f64, b: f64, pa: f64, pb: f64) -> f64 {
    let h = (b - a) / turns.len() as f64;
    turns
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let (lo, hi) = (a + h * i as f64, a + h * (i + 1) as f64);
            let overlap = (hi.min(pb) - lo.max(pa)).max(0.0);
            t * overlap / h
        })
        .sum()
}

/// The shortest scale (m) on which the detected spectrum varies smoothly between its kinks: the
/// narrowest Gaussian factor's σ, else a tenth of the shortest wavelength a blackbody or a
/// power law can vary on (they are smooth on the scale of λ itself).
fn smoothness_scale(detected: &Spectrum) -> f64 {
    let sigma = detected.gaussians().iter().map(|g| g.sigma()).fold(f64::INFINITY, f64::min);
    let (lo, _) = detected.support();
    sigma.min(0.1 * lo.max(50e-9))
}

/// Gauss–Legendre rules of 1 to 24 points, on [−1, 1].
fn gauss_rule(points: usize) -> &'static [(f64, f64)] {
    static RULES: OnceLock<Vec<Vec<(f64, f64)>>> = OnceLock::new();
    let rules = RULES.get_or_init(|| (0..=24).map(quad::gauss_legendre).collect());
    &rules[points.clamp(1, 24)]
}

/// The detected spectrum as the moment rules read it: its kinks and smoothness scale (for the
/// quadrature form), and its [`PiecewisePolynomial`](radiometry::PiecewisePolynomial) where it
/// is one (for the exact form), found once per scene.
///
/// A piecewise-polynomial density is shared by every evaluation of the same spectrum (see
/// [`of`](Self::of)) and remembers its panels' exact moment rules and moments: the points of a
/// sweep that leaves the spectrum alone cut most of their panels where the points before did
/// (the panels of `[lo, hi]` are equal parts of it, and their count changes only now and then
/// along an F-number axis), and find those panels' moments made, the same numbers bit for bit.
#[derive(Debug)]
pub(super) struct Density {
    /// the breakpoints, where the quadrature form reads them (empty beside `pieces`, whose
    /// edges hold them: a 1601-sample table's were collected twice per evaluation)
    kinks: Vec<f64>,
    smooth: f64,
    pieces: Option<Arc<radiometry::PiecewisePolynomial>>,
    /// the exact moment rules of the panels `(a, b)` met so far (by their bits), and their
    /// moments `μ_0 … μ_n` by `n`
    exact: Mutex<Rules>,
}

/// The panels' exact moment rules a [`Density`] remembers, with the points they hold.
#[derive(Default)]
struct Rules {
    panels: HashMap<(u64, u64), Remembered>,
    /// the points (breakpoints and quadrature points) of the rules held and their moments
    points: usize,
}

/// One panel's exact moment rule and the moments asked of it so far.
struct Remembered {
    rule: Arc<MomentRule>,
    moments: Vec<(usize, Arc<[f64]>)>,
}

impl std::fmt::Debug for Rules {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Rules").field("panels", &self.panels.len()).field("points", &self.points).finish()
    }
}

/// The densities each thread remembers ([`Density::of`]): a sweep's detected spectrum, with and
/// without an efficiency table folded in.
const DENSITIES: usize = 4;

/// The numbers one density remembers, counted as its rules' points (breakpoints, quadrature
/// points: at most 7 `f64` each) and its moments (one each): past this it forgets them all and
/// starts again, so that it holds at most ~7 MB. A 1601-row table's panels take some 5000 per
/// evaluation (1600 breakpoints, 33 and 129 moments a panel): the bound keeps ~25 evaluations'.
const REMEMBERED_POINTS: usize = 1 << 17;

thread_local! {
    /// The densities this thread built for remembered piecewise polynomials ([`Density::of`]).
    static DENSITY_MEMO: std::cell::RefCell<Vec<Arc<Density>>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Forgets what this thread remembers of measured spectra (the densities with their panels'
/// moments, the closed form's bands' densities and its tail and reach, and radiometry's piecewise polynomials), so that the next evaluation makes its own:
/// for a time per evaluation measured by repeating one scene (the accuracy report).
pub fn forget_remembered() {
    DENSITY_MEMO.with_borrow_mut(Vec::clear);
    super::closed_form::forget_band_densities();
    crate::closed::forget_tail_and_reach();
    radiometry::forget_remembered();
}

impl Density {
    /// The density of `detected`: where it is a piecewise polynomial remembered by radiometry
    /// (`Spectrum::piecewise_polynomial` returns the same `Arc` for a spectrum of the same bits),
    /// the density this thread built for that polynomial before, with the moments it remembers
    /// (the last [`DENSITIES`] ones, per thread like radiometry's memo); else a new one.
    pub fn of(detected: &Spectrum) -> Arc<Density> {
        let pieces = detected.piecewise_polynomial();
        let build = |pieces: Option<Arc<radiometry::PiecewisePolynomial>>| {
            Arc::new(Density {
                kinks: if pieces.is_some() { Vec::new() } else { detected.breakpoints() },
                smooth: smoothness_scale(detected),
                pieces,
                exact: Mutex::new(Rules::default()),
            })
        };
        let Some(p) = pieces else { return build(None) };
        DENSITY_MEMO.with_borrow_mut(|memo| {
            // the same polynomial, the same spectrum: its smoothness scale too (a pure function
            // of it)
            if let Some(d) = memo.iter().find(|d| d.pieces.as_ref().is_some_and(|q| Arc::ptr_eq(q, &p))) {
                return d.clone();
            }
            let d = build(Some(p));
            memo.insert(0, d.clone());
            memo.truncate(DENSITIES);
            d
        })
    }

    /// [`MomentRule::new`] for the panel `[a, b]`: an exact rule remembered, a quadrature rule
    /// built (it depends on `degree`, and no measured spectrum takes it).
    fn rule(&self, detected: &Spectrum, a: f64, b: f64, degree: usize) -> Arc<MomentRule> {
        if self.pieces.is_none() {
            return Arc::new(MomentRule::new(detected, self, a, b, degree));
        }
        let key = (a.to_bits(), b.to_bits());
        if let Some(r) = self.exact.lock().unwrap_or_else(PoisonError::into_inner).panels.get(&key) {
            return r.rule.clone();
        }
        let rule = Arc::new(MomentRule::new(detected, self, a, b, degree));
        let mut exact = self.exact.lock().unwrap_or_else(PoisonError::into_inner);
        if exact.points + rule.held() > REMEMBERED_POINTS {
            *exact = Rules::default();
        }
        if let Some(r) = exact.panels.get(&key) {
            // another thread built it meanwhile: one panel, one rule
            return r.rule.clone();
        }
        exact.points += rule.held();
        exact.panels.insert(key, Remembered { rule: rule.clone(), moments: Vec::new() });
        rule
    }

    /// `rule.moments(degree)` of the panel `[a, b]` whose rule [`rule`](Self::rule) gave:
    /// remembered for an exact rule.
    fn moments(&self, rule: &Arc<MomentRule>, a: f64, b: f64, degree: usize) -> Vec<f64> {
        let key = (a.to_bits(), b.to_bits());
        let remembered = |exact: &Rules| {
            exact
                .panels
                .get(&key)
                .filter(|r| Arc::ptr_eq(&r.rule, rule))
                .and_then(|r| r.moments.iter().find(|(n, _)| *n == degree).map(|(_, mu)| mu.to_vec()))
        };
        if self.pieces.is_none() {
            return rule.moments(degree);
        }
        if let Some(mu) = remembered(&self.exact.lock().unwrap_or_else(PoisonError::into_inner)) {
            return mu;
        }
        let mu = rule.moments(degree);
        let mut exact = self.exact.lock().unwrap_or_else(PoisonError::into_inner);
        let held = exact.points + mu.len();
        if let Some(r) = exact.panels.get_mut(&key).filter(|r| Arc::ptr_eq(&r.rule, rule))
            && !r.moments.iter().any(|(n, _)| *n == degree)
            && held <= REMEMBERED_POINTS
        {
            r.moments.push((degree, mu.as_slice().into()));
            exact.points = held;
        }
        mu
    }
}

/// Size of a piece's coefficients in x, relative to its values at its ends, above which the
/// exact moments would lose more than ~1e-12 to cancellation: such a piece is integrated by
/// quadrature.
const ILL_CONDITIONED: f64 = 1e4;

/// Most coefficients of one piece of a piecewise-polynomial density.
const PIECE_TERMS: usize = radiometry::MAX_PIECE_DEGREE + 1;

/// `C(m, j)` for `m, j < PIECE_TERMS` (Pascal's triangle): the binomial expansion of a piece in
/// powers of x without a division or a `powi` call per term.
const BINOMIAL: [[f64; PIECE_TERMS]; PIECE_TERMS] = {
    let mut table = [[0.0; PIECE_TERMS]; PIECE_TERMS];
    let mut m = 0;
    while m < PIECE_TERMS {
        table[m][0] = 1.0;
        let mut j = 1;
        while j <= m {
            table[m][j] = table[m - 1][j - 1] + if j < m { table[m - 1][j] } else { 0.0 };
            j += 1;
        }
        m += 1;
    }
    table
};

/// One panel's Chebyshev moments `μ_j = ∫_a^b ρ(λ) T_j(x) dλ`, `x = (2λ − a − b)/(b − a)`.
///
/// - **Exact**, where ρ is a polynomial between breakpoints (a table × λ × constants; radiometry's
///   `Spectrum::piecewise_polynomial`): with `ρ = Σ_i c_i x^i` on each piece,
///   `x^i T_j = 2^{−i} Σ_r C(i, r) T_{|j−i+2r|}` and `∫ T_n = T_{n+1}/(2(n+1)) − T_{n−1}/(2(n−1))`,
///   so every moment is a sum over the breakpoints of the jumps `Δc_i` of the piece coefficients
///   times Chebyshev polynomials there (the constants of integration cancel: the jumps of each
///   coefficient sum to zero). One recurrence per breakpoint up to the degree asked, whatever
///   the degree: a 0.25 nm table in a 100 nm panel costs 400 breakpoints, not 2000 quadrature
///   points and a rebuild for the 129-point level. Where ρ is continuous (every table sample
///   inside the support) the jump `Δp_b(x) = Σ_i Δc_i x^i` vanishes at `x_b`, so
///   `Δp_b = (x − x_b) q_b` and `Δc_i = q_{i−1} − x_b q_i`; with the shift identity
///   `x T_n = (T_{n+1} + T_{|n−1|})/2`, `F_i(n) = Σ_b Δc_i T_n(x_b)` is
///   `G_{i−1}(n) − (G_i(n+1) + G_i(|n−1|))/2` in the sums `G_k(n) = Σ_b q_k(b) T_n(x_b)`: one
///   sum fewer per breakpoint. For a piecewise-linear table × a polynomial `Q` (a table × λ ×
///   constants) every `q_b` is `w_b Q`, and one sum `S(n) = Σ_b w_b T_n(x_b)` gives them all,
///   `G_k = Q_k S` (see [`Continuous`]); the breakpoints where ρ jumps (the support's ends, the
///   panel's, those of the quadrature pieces) keep their `terms` sums.
/// - **Points**: the points `cos θ_i` and weights `ρ(λ_i) h sin θ_i w_i` of a quadrature, with ρ
///   evaluated once, so that moments of any degree up to the one it was built for cost one
///   recurrence per point. In the angle θ of `x = cos θ` the integrand
///   `ρ(c + h cos θ) cos(jθ) h sin θ` is smooth between the kinks of ρ: each piece is cut into
///   sub-pieces over which `jθ` and ρ (varying on the scale `smooth`) turn by at most 4 rad, and
///   each sub-piece takes the fewest Gauss–Legendre points whose error bound `(e k/(2p))^{2p}`
///   (k half that phase; the bound behind [`quad::MAX_PANEL_PHASE`]) is below 1e-16 of its
///   share.
enum MomentRule {
    Points {
        /// the highest degree the rule integrates to its 1e-16 bound
        degree: usize,
        cos: Vec<f64>,
        weight: Vec<f64>,
    },
    Exact {
        /// half the panel's width, m (dλ = h dx)
        h: f64,
        /// coefficients per piece (the pieces' degree + 1)
        terms: usize,
        /// the breakpoints in x where ρ jumps, with the panel's ends (all of them in the
        /// reference form, [`exact_with`](Self::exact_with) unfactored)
        x: Vec<f64>,
        /// the jumps `Δc_i = c_i(left piece) − c_i(right piece)` there (0 beyond the support)
        jumps: Vec<[f64; PIECE_TERMS]>,
        /// the breakpoints where ρ is continuous, by the quotients of their jumps
        continuous: Continuous,
        /// quadrature points and weights of the pieces whose coefficients in x would cancel
        /// (a ramp of 1e-17 m in a 100 nm panel: |c_i| 1e9 times its values)
        cos: Vec<f64>,
        weight: Vec<f64>,
    },
}

impl MomentRule {
    fn new(detected: &Spectrum, density: &Density, a: f64, b: f64, degree: usize) -> MomentRule {
        match &density.pieces {
            Some(pieces) => Self::exact(pieces, a, b),
            None => Self::points(detected, &density.kinks, density.smooth, a, b, degree),
        }
    }

    /// The points it holds, breakpoints and quadrature points (for [`Density`]'s bound).
    fn held(&self) -> usize {
        match self {
            MomentRule::Points { cos, .. } => cos.len(),
            MomentRule::Exact { x, continuous, cos, .. } => {
                x.len()
                    + cos.len()
                    + match continuous {
                        Continuous::Parallel { x, .. } | Continuous::General { x, .. } => x.len(),
                    }
            }
        }
    }

    /// The highest degree the rule's moments are exact (or within 1e-16) to.
    fn degree(&self) -> usize {
        match self {
            MomentRule::Points { degree, .. } => *degree,
            MomentRule::Exact { .. } => usize::MAX,
        }
    }

    fn exact(pieces: &radiometry::PiecewisePolynomial, a: f64, b: f64) -> MomentRule {
        Self::exact_with(pieces, a, b, true)
    }

    /// [`exact`](Self::exact) with the continuous breakpoints `factored` (their jumps divided
    /// by `x − x_b`, see [`Continuous`]), or not: every breakpoint with its `terms` sums, the
    /// reference the tests hold the factored form to.
    fn exact_with(pieces: &radiometry::PiecewisePolynomial, a: f64, b: f64, factored: bool) -> MomentRule {
        let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
        let edges = &pieces.edges;
        let terms = (pieces.degree + 1).min(PIECE_TERMS);
        let mut h_powers = [1.0; PIECE_TERMS];
        for m in 1..PIECE_TERMS {
            h_powers[m] = h_powers[m - 1] * h;
        }
        let (mut x, mut jumps): (Vec<f64>, Vec<[f64; PIECE_TERMS]>) = (Vec::new(), Vec::new());
        // the pieces overlapping (a, b), each clipped to it, as polynomials in x
        let first = edges.partition_point(|&e| e <= a).saturating_sub(1);
        let mut previous = [0.0; PIECE_TERMS];
        let mut previous_end: Option<f64> = None;
        // the previous piece's size Σ|c_i| and value at its end
        let (mut previous_size, mut previous_ends) = (0.0, 0.0);
        let (mut cos, mut weight) = (Vec::new(), Vec::new());
        // the continuous breakpoints: x_b, the quotient q_b, the size of the two pieces (all
        // but a few of the pieces' starts)
        let count = edges[first..].partition_point(|&e| e < b);
        let (mut smooth_x, mut quotients, mut sizes) =
            (Vec::with_capacity(count), Vec::with_capacity(count), Vec::with_capacity(count));
        for i in first..pieces.pieces.len() {
            let (lo, hi) = (edges[i].max(a), edges[i + 1].min(b));
            if lo >= b {
                break;
            }
            if hi <= lo {
                continue;
            }
            // Σ_m r_m (λ − e_i)^m with λ − e_i = h (x − x_i): binomial expansion in powers of x
            let x_i = (edges[i] - c) / h;
            // (−x_i)^k, k < terms
            let mut minus_x = [1.0; PIECE_TERMS];
            for k in 1..terms {
                minus_x[k] = minus_x[k - 1] * -x_i;
            }
            let mut coefficients = [0.0; PIECE_TERMS];
            for (m, &r) in pieces.pieces[i].iter().enumerate().take(terms) {
                let scaled = r * h_powers[m];
                for j in 0..=m {
                    // C(m, j) (−x_i)^{m−j}
                    coefficients[j] += scaled * BINOMIAL[m][j] * minus_x[m - j];
                }
            }
            let (x_lo, x_hi) = (((lo - c) / h).clamp(-1.0, 1.0), ((hi - c) / h).clamp(-1.0, 1.0));
            let at = |x: f64| coefficients.iter().rev().fold(0.0, |acc, v| acc * x + v);
            // the piece's size Σ|c_i| and values at its ends
            let (mut size, mut starts, mut ends): (f64, f64, f64) =
                (coefficients.iter().map(|v| v.abs()).sum(), at(x_lo), at(x_hi));
            if size > ILL_CONDITIONED * starts.abs().max(ends.abs()) {
                // by quadrature instead, of the piece's own polynomial in λ; a zero piece in
                // the jumps
                let piece = &pieces.pieces[i];
                let rho = |l: f64| piece.iter().rev().fold(0.0, |acc, v| acc * (l - edges[i]) + v);
                let rate = (LEVELS[LEVELS.len() - 1] - 1) as f64;
                theta_points(x_lo.acos(), x_hi.acos(), rate, (c, h), rho, &mut cos, &mut weight);
                coefficients = [0.0; PIECE_TERMS];
                (size, starts, ends) = (0.0, 0.0, 0.0);
            }
            match previous_end {
                Some(end) if end == x_lo => {
                    let jump = std::array::from_fn(|j| previous[j] - coefficients[j]);
                    // the jump's remainder Δp_b(x_b): the left piece's value at its end less
                    // this one's at its start
                    let size = previous_size + size;
                    if factored && (previous_ends - starts).abs() <= CONTINUOUS * size {
                        smooth_x.push(x_lo);
                        quotients.push(quotient(&jump, x_lo));
                        sizes.push(size);
                    } else {
                        x.push(x_lo);
                        jumps.push(jump);
                    }
                }
                _ => {
                    // a gap (or the first piece): the previous piece ends, this one starts
                    if let Some(end) = previous_end {
                        x.push(end);
                        jumps.push(previous);
                    }
                    x.push(x_lo);
                    jumps.push(coefficients.map(|v| -v));
                }
            }
            previous = coefficients;
            previous_end = Some(x_hi);
            (previous_size, previous_ends) = (size, ends);
        }
        if let Some(end) = previous_end {
            x.push(end);
            jumps.push(previous);
        }
        let continuous = Continuous::of(smooth_x, quotients, &sizes, terms);
        MomentRule::Exact { h, terms, x, jumps, continuous, cos, weight }
    }

    fn points(detected: &Spectrum, kinks: &[f64], smooth: f64, a: f64, b: f64, degree: usize) -> MomentRule {
        let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
        // θ decreasing in λ: θ = π at a, 0 at b; pieces between the kinks inside (a, b)
        let from = kinks.partition_point(|&k| k <= a);
        let to = kinks.partition_point(|&k| k < b);
        let mut edges = Vec::with_capacity(to - from + 2);
        edges.push(PI);
        for &k in &kinks[from..to] {
            edges.push(((k - c) / h).clamp(-1.0, 1.0).acos());
        }
        edges.push(0.0);
        // ρ's phase per unit θ: dλ/dθ ≤ h, over its scale
        let rho_rate = if smooth.is_finite() { 2.0 * h / smooth } else { 0.0 };
        let rate = degree as f64 + rho_rate;
        let (mut cos, mut weights) = (Vec::new(), Vec::new());
        for pair in edges.windows(2) {
            theta_points(pair[0], pair[1], rate, (c, h), |l| detected.value(l), &mut cos, &mut weights);
        }
        MomentRule::Points { degree, cos, weight: weights }
    }

    /// `μ_0 … μ_degree`.
    fn moments(&self, degree: usize) -> Vec<f64> {
        match self {
            MomentRule::Points { cos, weight, .. } => point_moments(cos, weight, degree),
            MomentRule::Exact { h, terms, x, jumps, continuous, cos, weight } => {
                let points = point_moments(cos, weight, degree);
                // F_i(n) = Σ_b Δc_i(b) T_n(x_b); E_i(n) = the same with ∫T_n (constants dropped)
                let top = degree + terms + 1;
                // the first `k` of the coefficients per point: as many sums (a table × λ: three
                // for a jump, two for a quotient)
                fn sums<const K: usize>(x: &[f64], c: &[[f64; PIECE_TERMS]], top: usize) -> Vec<[f64; PIECE_TERMS]> {
                    let w: Vec<[f64; K]> = c.iter().map(|j| std::array::from_fn(|i| j[i])).collect();
                    let sums = chebyshev_sums::<K>(x, &w, top);
                    sums.into_iter().map(|v| std::array::from_fn(|i| if i < K { v[i] } else { 0.0 })).collect()
                }
                let sums_of = |k: usize, x: &[f64], c: &[[f64; PIECE_TERMS]], top: usize| match k {
                    1 => sums::<1>(x, c, top),
                    2 => sums::<2>(x, c, top),
                    3 => sums::<3>(x, c, top),
                    _ => sums::<PIECE_TERMS>(x, c, top),
                };
                let mut f = sums_of(*terms, x, jumps, top);
                // the continuous breakpoints: F_i(n) += G_{i−1}(n) − (G_i(n+1) + G_i(|n−1|))/2
                // (q_k = 0 for k < 0 and k ≥ terms − 1), G given to order top + 1
                fn add(f: &mut [[f64; PIECE_TERMS]], terms: usize, g: impl Fn(usize, usize) -> f64) {
                    for (n, f) in f.iter_mut().enumerate() {
                        for (i, f) in f.iter_mut().enumerate().take(terms) {
                            let shifted = 0.5 * (g(n + 1, i) + g(n.abs_diff(1), i));
                            *f += if i > 0 { g(n, i - 1) } else { 0.0 } - shifted;
                        }
                    }
                }
                match continuous {
                    Continuous::Parallel { x, q, w } if !x.is_empty() => {
                        // G_k(n) = Q_k S(n)
                        let s = chebyshev_sums::<1>(x, w, top + 1);
                        add(&mut f, *terms, |n, k| q[k] * s[n][0]);
                    }
                    Continuous::General { x, q } if !x.is_empty() => {
                        let g = sums_of(*terms - 1, x, q, top + 1);
                        add(&mut f, *terms, |n, k| g[n][k]);
                    }
                    _ => {}
                }
                let e = |i: usize, n: usize| -> f64 {
                    match n {
                        0 => f[1][i],
                        1 => 0.25 * f[2][i],
                        _ => f[n + 1][i] / (2.0 * (n + 1) as f64) - f[n - 1][i] / (2.0 * (n - 1) as f64),
                    }
                };
                (0..=degree)
                    .map(|j| {
                        let mut total = 0.0;
                        for i in 0..*terms {
                            // x^i T_j = 2^{−i} Σ_r C(i, r) T_{|j−i+2r|}
                            let mut binomial = 1.0;
                            let mut sum = 0.0;
                            for r in 0..=i {
                                sum += binomial * e(i, (j as i64 - i as i64 + 2 * r as i64).unsigned_abs() as usize);
                                binomial = binomial * (i - r) as f64 / (r + 1) as f64;
                            }
                            total += sum * 0.5f64.powi(i as i32);
                        }
                        h * total + points[j]
                    })
                    .collect()
            }
        }
    }
}

/// Largest remainder `|Δp_b(x_b)|` of a jump (the left piece's value at `x_b` less the right
/// one's), relative to the size `Σ_i |c_i|` of the two pieces' coefficients, at which the density
/// counts as continuous at `x_b` and the remainder is dropped (as is a quotient's departure from
/// `w_b Q`, [`Continuous::of`]). The coefficients in x carry rounding of a few ε of that size
/// (the binomial expansion, the evaluation), which is all the remainder of a continuous
/// breakpoint is; a true jump (a table's ends, a top-hat's, a quadrature piece's) is of the order
/// of ρ there. Dropping a remainder `r` moves each moment by at most `2h|r|` (the moments of a
/// step of height r): 1e-14 of the pieces' size, below the rounding that the unfactored sums
/// already carry (the spectrometer's table: remainders and departures at most 2e-16 of it, so
/// every breakpoint inside its support is factored).
const CONTINUOUS: f64 = 1e-14;

/// The quotient `q` of the jump `Δp(x) = Σ_i jump_i x^i` by `x − x_b`, by synthetic division
/// (`q_{i−1} = Δc_i + x_b q_i` from the top), the remainder `Δc_0 + x_b q_0` dropped: one
/// coefficient fewer than the jump.
fn quotient(jump: &[f64; PIECE_TERMS], x_b: f64) -> [f64; PIECE_TERMS] {
    let mut q = [0.0; PIECE_TERMS];
    let mut carry = 0.0;
    for i in (1..PIECE_TERMS).rev() {
        carry = jump[i] + x_b * carry;
        q[i - 1] = carry;
    }
    q
}

/// The breakpoints of an exact moment rule where the density is continuous, each by the
/// quotient `q_b = Δp_b/(x − x_b)` of its jump (`terms − 1` coefficients, [`MomentRule`]).
enum Continuous {
    /// every `q_b` is `w_b q` (a piecewise-linear table × a polynomial: the table's slope jumps
    /// × the polynomial): one sum per breakpoint
    Parallel { x: Vec<f64>, q: [f64; PIECE_TERMS], w: Vec<[f64; 1]> },
    /// the quotients as they are (a product of two tables): `terms − 1` sums per breakpoint
    General { x: Vec<f64>, q: Vec<[f64; PIECE_TERMS]> },
}

impl Continuous {
    /// The breakpoints `x` with their quotients `q` (of pieces of `terms` coefficients) and the
    /// sizes `Σ|c_i|` of the two pieces at each: [`Parallel`](Continuous::Parallel) when every
    /// quotient is within [`CONTINUOUS`] × its size of `w_b` times the largest one (`w_b` from
    /// the largest one's largest coefficient), else [`General`](Continuous::General).
    fn of(x: Vec<f64>, q: Vec<[f64; PIECE_TERMS]>, sizes: &[f64], terms: usize) -> Continuous {
        match terms {
            ..=2 => Self::of_k::<1>(x, q, sizes),
            3 => Self::of_k::<2>(x, q, sizes),
            4 => Self::of_k::<3>(x, q, sizes),
            _ => Self::of_k::<{ PIECE_TERMS - 1 }>(x, q, sizes),
        }
    }

    /// [`of`](Self::of) for quotients of `K` coefficients (the rest 0).
    fn of_k<const K: usize>(x: Vec<f64>, q: Vec<[f64; PIECE_TERMS]>, sizes: &[f64]) -> Continuous {
        let norm = |q: &[f64; PIECE_TERMS]| q[..K].iter().map(|v| v.abs()).sum::<f64>();
        let mut largest = [0.0; PIECE_TERMS];
        let mut most = 0.0;
        for q in &q {
            let n = norm(q);
            if n > most {
                (largest, most) = (*q, n);
            }
        }
        let at = (0..K).fold(0, |at, i| if largest[i].abs() > largest[at].abs() { i } else { at });
        if largest[at] == 0.0 {
            // every quotient 0 (or none): the pieces meet without a kink
            return Continuous::Parallel { x: Vec::new(), q: largest, w: Vec::new() };
        }
        let w: Vec<[f64; 1]> = q.iter().map(|q| [q[at] / largest[at]]).collect();
        let parallel =
            q.iter().zip(&w).zip(sizes).all(|((q, &[w]), &size)| {
                (0..K).map(|i| (q[i] - w * largest[i]).abs()).sum::<f64>() <= CONTINUOUS * size
            });
        if parallel { Continuous::Parallel { x, q: largest, w } } else { Continuous::General { x, q } }
    }
}

/// `Σ_b w_b T_n(x_b)` for `n = 0 … degree`.
fn point_moments(x: &[f64], w: &[f64], degree: usize) -> Vec<f64> {
    let w: Vec<[f64; 1]> = w.iter().map(|&w| [w]).collect();
    chebyshev_sums::<1>(x, &w, degree).into_iter().map(|[v]| v).collect()
}

/// `Σ_b w_b[i] T_n(x_b)` for `n = 0 … degree` and each of the `K` weights per point, by the
/// three-term recurrence `T_{n+1} = 2x T_n − T_{n−1}` at each point, [`MOMENT_LANES`] points at a
/// time (one recurrence alone is bound by its latency).
fn chebyshev_sums<const K: usize>(x: &[f64], w: &[[f64; K]], degree: usize) -> Vec<[f64; K]> {
    // per lane, summed across the lanes once at the end (a sum across them at every order
    // was a third of the moments' time); fewer points than lanes (the jumps kept beside the
    // factored breakpoints) go straight to the point-by-point loop
    let mut mu: Vec<[f64; K]> = if x.len() < MOMENT_LANES {
        vec![[0.0; K]; degree + 1]
    } else {
        let mut by_lane = vec![[[0.0; MOMENT_LANES]; K]; degree + 1];
        let lanes = x.chunks_exact(MOMENT_LANES).zip(w.chunks_exact(MOMENT_LANES));
        for (x, w) in lanes {
            let x: [f64; MOMENT_LANES] = x.try_into().expect("a chunk of MOMENT_LANES");
            let w: [[f64; MOMENT_LANES]; K] = std::array::from_fn(|k| std::array::from_fn(|l| w[l][k]));
            let add = |m: &mut [[f64; MOMENT_LANES]; K], t: &[f64; MOMENT_LANES]| {
                for (slot, w) in m.iter_mut().zip(&w) {
                    for l in 0..MOMENT_LANES {
                        slot[l] += w[l] * t[l];
                    }
                }
            };
            // T_0 = 1 and T_1 = x, then the recurrence
            let (mut prev, mut cur) = ([1.0; MOMENT_LANES], x);
            let mut orders = by_lane.iter_mut();
            if let Some(m) = orders.next() {
                add(m, &prev);
            }
            if let Some(m) = orders.next() {
                add(m, &cur);
            }
            for m in orders {
                let next: [f64; MOMENT_LANES] = std::array::from_fn(|l| 2.0 * x[l] * cur[l] - prev[l]);
                prev = cur;
                cur = next;
                add(m, &next);
            }
        }
        by_lane.iter().map(|m| m.map(|lanes| lanes.iter().sum())).collect()
    };
    let rest = x.len() - x.len() % MOMENT_LANES;
    for (&x, w) in x[rest..].iter().zip(&w[rest..]) {
        let (mut prev, mut cur) = (1.0, x);
        for (n, m) in mu.iter_mut().enumerate() {
            let t = match n {
                0 => 1.0,
                1 => x,
                _ => {
                    let next = 2.0 * x * cur - prev;
                    prev = cur;
                    cur = next;
                    next
                }
            };
            for (k, slot) in m.iter_mut().enumerate() {
                *slot += w[k] * t;
            }
        }
    }
    mu
}

/// Appends the quadrature points `cos θ` and weights `ρ(c + h cos θ) h sin θ w` of
/// `∫ ρ T_j dλ` over `θ ∈ [t0, t1]` (`x = cos θ`, `λ = c + h x`) where ρ is smooth: cut into
/// sub-pieces over which `rate × θ` turns by at most 4 rad, each with the fewest Gauss–Legendre
/// points whose error bound `(e k/(2p))^{2p}` (k half that phase) is below 1e-16 of its share.
fn theta_points(
    t1: f64,
    t0: f64,
    rate: f64,
    (c, h): (f64, f64),
    rho: impl Fn(f64) -> f64,
    cos: &mut Vec<f64>,
    weights: &mut Vec<f64>,
) {
    let length = t1 - t0;
    if length <= 0.0 {
        return;
    }
    let phase = rate * length;
    let subs = (phase / 4.0).ceil().max(1.0);
    let k = 0.5 * phase / subs;
    let mut p = 2;
    while p < 24 && (std::f64::consts::E * k / (2.0 * p as f64)).powi(2 * p as i32) > 1e-16 {
        p += 1;
    }
    let rule = gauss_rule(p);
    let sub_len = length / subs;
    for s in 0..subs as usize {
        let mid = t0 + sub_len * (s as f64 + 0.5);
        for &(x, w) in rule {
            let theta = mid + 0.5 * sub_len * x;
            let (sin, x) = crate::fft::cis::sin_cos(theta);
            let weight = rho(c + h * x) * h * sin * w * 0.5 * sub_len;
            if weight != 0.0 {
                cos.push(x);
                weights.push(weight);
            }
        }
    }
}

/// Points of a moment rule whose Chebyshev recurrences run side by side.
const MOMENT_LANES: usize = 8;

/// Product-integration weights on the `points` Chebyshev–Lobatto points `x_k = cos(πk/n)`,
/// n = points − 1 (k = 0 is x = 1): `w_k = ∫ ρ ℓ_k`, from the Chebyshev moments μ_0..μ_n. The
/// interpolant is `Σ_j c_j T_j` with `c_j = (2/n) Σ''_k f_k T_j(x_k)` (first and last terms of
/// both sums halved), so `∫ ρ p = Σ_k f_k (2/n) h_k Σ_j h_j μ_j cos(πjk/n)`.
pub(super) fn lobatto_weights(mu: &[f64], points: usize) -> Vec<f64> {
    let n = points - 1;
    let halve = |i: usize| if i == 0 || i == n { 0.5 } else { 1.0 };
    let scaled: Vec<f64> = (0..=n).map(|j| halve(j) * mu[j]).collect();
    (0..points).map(|k| 2.0 / n as f64 * halve(k) * quad::add_stepped_cosines(0.0, &scaled, 0, k, n)).collect()
}

/// The wavelengths of the OTF tables of `lens`'s orders, found at five wavelengths across
/// `[lo, hi]`: a table is linear in λ between its rows, so the spectral panels are cut there.
fn table_wavelengths(lens: &dyn LensModel, field: Field, lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 0..5 {
        let lambda = lo + (hi - lo) * k as f64 / 4.0;
        if lambda <= 0.0 {
            continue;
        }
        for order in lens.orders(lambda, field) {
            if let Pupil::Table(t) = &order.pupil {
                out.extend_from_slice(t.wavelengths());
            }
        }
    }
    out.sort_by(f64::total_cmp);
    out.dedup();
    out
}

/// The wavelength interval the spectral rules cover: the spectrum's support, with Gaussian
/// factors cut at ±[`GAUSSIAN_HALF_WIDTH_SIGMAS`] σ.
pub(crate) fn spectral_extent(detected: &Spectrum) -> Result<(f64, f64), Error> {
    extent_at(detected, GAUSSIAN_HALF_WIDTH_SIGMAS)
}

fn extent_at(detected: &Spectrum, sigmas: f64) -> Result<(f64, f64), Error> {
    let (mut lo, mut hi) = detected.support();
    for g in detected.gaussians() {
        lo = lo.max(g.center() - sigmas * g.sigma());
        hi = hi.min(g.center() + sigmas * g.sigma());
    }
    lo = lo.max(0.0);
    if !(hi.is_finite() && hi > lo) {
        return Err(Error::UnboundedSpectrum { lo, hi });
    }
    Ok((lo, hi))
}
#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform numbers in [−½, ½) from PCG-64 MCG seeded with `seed` (the project's one
    /// generator family): deterministic noise for test tables.
    fn uniform_noise(seed: u64) -> impl FnMut() -> f64 {
        let mut rng: rand_pcg::Pcg64Mcg = rand::SeedableRng::seed_from_u64(seed);
        move || rand::RngExt::random::<f64>(&mut rng) - 0.5
    }

    /// The spectrometer scene's kind of table: an 8th-power super-Gaussian band of 0.9 at
    /// 825 nm (26 nm half width) on a 0.002 floor with ±0.0005 of `noise`, 1601 samples at
    /// 0.25 nm over 600–1000 nm: (wavelengths, values).
    fn noisy_band(noise: &mut impl FnMut() -> f64) -> (Vec<f64>, Vec<f64>) {
        let wavelengths: Vec<f64> = (0..1601).map(|i| 600e-9 + 0.25e-9 * i as f64).collect();
        let values = wavelengths
            .iter()
            .map(|&l| 0.002 + 0.9 * (-((l - 825e-9) / 26e-9).powi(8)).exp() + 0.001 * noise())
            .map(|v: f64| v.max(0.0))
            .collect();
        (wavelengths, values)
    }

    /// The exact moments of a piecewise-polynomial density (a noisy 0.25 nm table × λ × a
    /// constant, kinks at every sample) against the quadrature form of the same density, to
    /// degree 128 (the finest level's), on panels inside the table, across one sample, and
    /// reaching beyond both ends of its support; relative to the panel's mass.
    #[test]
    fn exact_moments_match_the_quadrature() {
        let (wavelengths, values) = noisy_band(&mut uniform_noise(0x2545_f491_4f6c_dd1d));
        let table = radiometry::Sampled::new(wavelengths, values).unwrap();
        let detected =
            Spectrum::product(vec![Spectrum::Sampled(table), Spectrum::Linear { slope: 1.0 }, Spectrum::Constant(0.3)]);
        // and a band written as a table with 1e-17 m edges (slopes of 1e17 per m: those pieces'
        // coefficients in x would cancel, and go to quadrature)
        let edges =
            radiometry::Sampled::new(vec![700e-9 - 1e-17, 700e-9, 750e-9, 750e-9 + 1e-17], vec![0.0, 1.0, 1.0, 0.0]);
        let band = Spectrum::product(vec![Spectrum::Sampled(edges.unwrap()), Spectrum::Linear { slope: 1.0 }]);
        for (detected, panels) in [
            (&detected, &[(600e-9, 680e-9), (760e-9, 840e-9), (650.1e-9, 650.4e-9), (590e-9, 1010e-9)][..]),
            (&band, &[(690e-9, 760e-9), (700e-9, 750e-9)][..]),
        ] {
            let exact = Density::of(detected);
            assert!(exact.pieces.is_some());
            let quadrature = Density {
                pieces: None,
                kinks: detected.breakpoints(),
                smooth: exact.smooth,
                exact: Mutex::new(Rules::default()),
            };
            for &(a, b) in panels {
                let degree = 128;
                let want = MomentRule::new(detected, &quadrature, a, b, degree).moments(degree);
                let got = MomentRule::new(detected, &exact, a, b, degree).moments(degree);
                let scale = want[0].abs();
                for (j, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert!((g - w).abs() <= 1e-12 * scale, "[{a}, {b}] μ_{j}: {g} vs {w}");
                }
            }
        }
    }

    /// The remembered rules and moments: a spectrum of the same bits, built again (as each point
    /// of a sweep builds its scene), finds the same density, and a panel met before the same rule
    /// and moments, bit for bit those of a rule built afresh from the polynomial
    /// ([`MomentRule::exact`], the slow path, never remembered); a spectrum differing in one
    /// sample (a zero's sign) gets a density of its own, and a quadrature density remembers nothing.
    #[test]
    fn remembered_moments_are_the_fresh_ones() {
        let (wavelengths, values) = noisy_band(&mut uniform_noise(0x51_7cc1_b727_220a));
        let build = |values: &[f64]| {
            let table = radiometry::Sampled::new(wavelengths.clone(), values.to_vec()).unwrap();
            Spectrum::product(vec![Spectrum::Sampled(table), Spectrum::Linear { slope: 1.0 }, Spectrum::Constant(0.3)])
        };
        let (first, again) = (build(&values), build(&values));
        let density = Density::of(&first);
        assert!(Arc::ptr_eq(&density, &Density::of(&again)), "the same bits, the same density");
        let pieces = density.pieces.clone().expect("a piecewise polynomial");
        for (a, b) in [(600e-9, 680e-9), (650.1e-9, 650.4e-9), (590e-9, 1010e-9)] {
            let fresh = MomentRule::exact(&pieces, a, b);
            for degree in [FIRST_MOMENT_DEGREE, 128] {
                let want: Vec<u64> = fresh.moments(degree).iter().map(|v| v.to_bits()).collect();
                for _ in 0..2 {
                    let rule = density.rule(&again, a, b, FIRST_MOMENT_DEGREE);
                    assert!(Arc::ptr_eq(&rule, &density.rule(&first, a, b, FIRST_MOMENT_DEGREE)));
                    let got: Vec<u64> = density.moments(&rule, a, b, degree).iter().map(|v| v.to_bits()).collect();
                    assert_eq!(got, want, "[{a}, {b}] to degree {degree}");
                }
            }
        }
        // one sample 0 in one table and −0 in the other (equal by `==`): other bits, another
        // density; the first found again
        let (mut plus, mut minus) = (values.clone(), values.clone());
        (plus[800], minus[800]) = (0.0, -0.0);
        let zero = Density::of(&build(&plus));
        assert!(!Arc::ptr_eq(&zero, &Density::of(&build(&minus))));
        assert!(Arc::ptr_eq(&zero, &Density::of(&build(&plus))));
        // past its bound a density forgets its panels and starts again: it never holds more,
        // and what it gives stays the fresh moments
        for k in 0..120 {
            let (a, b) = (595e-9 + 1e-11 * f64::from(k), 1005e-9);
            let rule = density.rule(&first, a, b, FIRST_MOMENT_DEGREE);
            let got = density.moments(&rule, a, b, FIRST_MOMENT_DEGREE);
            assert!(density.exact.lock().unwrap().points <= REMEMBERED_POINTS);
            if k % 40 == 0 {
                assert_eq!(got, MomentRule::exact(&pieces, a, b).moments(FIRST_MOMENT_DEGREE), "[{a}, {b}]");
            }
        }
        assert!(density.exact.lock().unwrap().panels.len() < 120, "forgotten at the bound");
        // a Gaussian spectrum: quadrature rules, built each time
        let gaussian = Spectrum::Gaussian(radiometry::Gaussian::new(800e-9, 20e-9, 1.0).unwrap());
        let quadrature = Density::of(&gaussian);
        let rule = quadrature.rule(&gaussian, 700e-9, 900e-9, 16);
        assert!(!Arc::ptr_eq(&rule, &quadrature.rule(&gaussian, 700e-9, 900e-9, 16)));
        assert!(quadrature.exact.lock().unwrap().panels.is_empty());
    }

    /// The exact moments with the continuous breakpoints factored (one sum per breakpoint for a
    /// table × λ, `terms − 1` for a product of tables) against the unfactored sums, to degree
    /// 128, relative to the largest moment: (a) a noisy 0.25 nm table × λ × a constant (every
    /// quotient parallel), (b) the same table × a coarser table × λ (cubic pieces, quotients
    /// not parallel), (c) the table with a gap of 1e-17 m edges (quadrature pieces) × a top-hat
    /// inside it × λ (jumps inside the panel); on panels inside the tables, across their ends
    /// and clipping pieces. Both are sums of ~1600 terms much larger than the moments (a noise
    /// floor's slopes in x are ~100 × its values): merely reordering the unfactored sums moves
    /// them by up to 1e-13 of the largest moment on the floor alone, whence 2e-13 (measured:
    /// 1.6e-13 there for (b), ≤ 7e-14 elsewhere).
    #[test]
    fn factored_moments_match_the_unfactored_sums() {
        let mut noise = uniform_noise(0x9e37_79b9_7f4a_7c15);
        let (wavelengths, values) = noisy_band(&mut noise);
        let table = || Spectrum::Sampled(radiometry::Sampled::new(wavelengths.clone(), values.clone()).unwrap());
        // (b): a smooth 10 nm table (a QE curve) over 590–1010 nm
        let coarse: Vec<f64> = (0..43).map(|i| 590e-9 + 10e-9 * i as f64).collect();
        let qe: Vec<f64> =
            coarse.iter().map(|&l| 0.6 - 0.4 * ((l - 700e-9) / 300e-9).powi(2) + 0.01 * noise()).collect();
        let qe = Spectrum::Sampled(radiometry::Sampled::new(coarse, qe).unwrap());
        // (c): the table with a gap over 700–720 nm, its edges 1e-17 m wide
        let (mut gapped_w, mut gapped_v) = (Vec::new(), Vec::new());
        for (&l, &v) in wavelengths.iter().zip(&values) {
            if !(700e-9..=720e-9).contains(&l) {
                gapped_w.push(l);
                gapped_v.push(v);
            }
            if l == 700e-9 {
                gapped_w.extend([700e-9, 700e-9 + 1e-17, 720e-9 - 1e-17]);
                gapped_v.extend([v, 0.0, 0.0]);
            }
            if l == 720e-9 {
                gapped_w.push(720e-9);
                gapped_v.push(v);
            }
        }
        let gapped = Spectrum::Sampled(radiometry::Sampled::new(gapped_w, gapped_v).unwrap());
        let band = Spectrum::TopHat(radiometry::TopHat::new(650.1e-9, 950.1e-9, 2.0).unwrap());
        let linear = || Spectrum::Linear { slope: 1.0 };
        let panels = [(600e-9, 1000e-9), (600e-9, 680e-9), (760e-9, 840e-9), (650.1e-9, 650.4e-9), (590e-9, 1010e-9)];
        let gap_panels = [(600e-9, 1000e-9), (640e-9, 730e-9), (690e-9, 760e-9), (700e-9, 720e-9), (590e-9, 1010e-9)];
        let cases = [
            ("table × λ", Spectrum::product(vec![table(), linear(), Spectrum::Constant(0.3)]), &panels[..]),
            ("table × table × λ", Spectrum::product(vec![table(), qe, linear()]), &panels[..]),
            ("gapped table × top-hat × λ", Spectrum::product(vec![gapped, band, linear()]), &gap_panels[..]),
        ];
        for (name, detected, panels) in &cases {
            let pieces = Density::of(detected).pieces.clone().expect("a piecewise polynomial");
            for &(a, b) in *panels {
                let factored = MomentRule::exact_with(&pieces, a, b, true);
                let reference = MomentRule::exact_with(&pieces, a, b, false);
                let (MomentRule::Exact { x, continuous, .. }, MomentRule::Exact { x: all, .. }) =
                    (&factored, &reference)
                else {
                    panic!("{name}: not exact");
                };
                // the forms taken: the jumps kept are the panel's ends (or the support's) and the
                // gap's edges; a table × λ has one common quotient, a product of tables not
                let (smooth, parallel) = match continuous {
                    Continuous::Parallel { x, .. } => (x.len(), true),
                    Continuous::General { x, .. } => (x.len(), false),
                };
                let gap = name.starts_with("gapped") && a < 700e-9 && b > 720e-9;
                assert_eq!(x.len(), if gap { 4 } else { 2 }, "{name} [{a}, {b}]: jumps kept");
                assert!(x.len() + smooth <= all.len() && x.len() + smooth + 4 >= all.len(), "{name} [{a}, {b}]");
                if smooth > 1 {
                    assert_eq!(parallel, !name.contains("× table"), "{name} [{a}, {b}]: parallel");
                }
                for degree in [0, 1, 2, 32, 128] {
                    let want = reference.moments(degree);
                    let got = factored.moments(degree);
                    let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    for (j, (g, w)) in got.iter().zip(&want).enumerate() {
                        assert!((g - w).abs() <= 2e-13 * scale, "{name} [{a}, {b}] μ_{j}: {g} vs {w}");
                    }
                }
            }
        }
    }

    fn bright(w: &[f64]) -> Vec<PhaseEntry> {
        w.iter().map(|&w020| PhaseEntry { w020, vanishing: false }).collect()
    }

    /// The matching of orders between neighbouring wavelengths, against the changes worked out
    /// by hand.
    #[test]
    fn orders_are_matched_by_their_defocus() {
        // three bright channels each moving by one channel spacing (1.0) across the panel: the
        // nearest-neighbour pairs would see 0.1, the true change is 1.0
        let from = bright(&[-1.0, 0.0, 1.0]);
        let to = bright(&[-2.0, -1.1, 0.0]);
        assert_eq!(largest_turn(&from, &to), 1.1);
        // a harmonic window shifting by one order (same count): the order leaving at one end
        // and the one entering at the other are near zero efficiency and stay unmatched
        let mut from = bright(&[1.0, 2.0, 3.0, 4.0]);
        from[0].vanishing = true;
        let mut to = bright(&[2.05, 3.05, 4.05, 5.05]);
        to[3].vanishing = true;
        assert!((largest_turn(&from, &to) - 0.05).abs() < 1e-12);
        // the same shift with bright end orders is a jump of every order (no vanishing order to
        // leave out): matched one to one
        assert!(
            (largest_turn(&bright(&[1.0, 2.0, 3.0, 4.0]), &bright(&[2.05, 3.05, 4.05, 5.05])) - 1.05).abs() < 1e-12
        );
        // an order appearing (the counts differ): the others are matched, whatever its brightness
        assert!((largest_turn(&bright(&[1.0, 2.0]), &bright(&[1.1, 2.1, 3.0])) - 0.1).abs() < 1e-12);
        assert!((largest_turn(&bright(&[0.0, 1.0, 2.0]), &bright(&[1.2, 2.2])) - 0.2).abs() < 1e-12);
        // nothing to match
        assert_eq!(largest_turn(&[], &bright(&[1.0])), 0.0);
        assert_eq!(largest_turn(&[], &[]), 0.0);
    }
}
