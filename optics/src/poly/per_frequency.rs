//! Product integration per frequency ([`PerFrequency`]): the spectral rule of
//! [`interpolated`](super::spectral::interpolated) — Chebyshev–Lobatto points on panels that
//! follow the lens, weights the exact moments of the detected spectrum — with its point count
//! chosen at each frequency, not once at the frequency limit.
//!
//! The lens's part `g(ν, λ) = Σ_o τ_o(λ) OTF_o(ν, λ)` varies in λ through the defocus phase
//! `8π ν F# W020(λ)(cos t − s)`, which grows with ν: at Nyquist a panel of the spectrometer scene
//! needs 33 points, at a quarter of it 9. So at each frequency each panel climbs the nested
//! levels (3, 5, 9, 17, … points; each level's points are the next one's even points, so
//! climbing wastes no evaluation) until the product integral is within its share of the OTF
//! value's tolerance, judged as [`Interpolant::refine`](super::spectral) judges it at the
//! limit: the nested estimate ([`nested_error`](super::nested_error)) once the level resolves the
//! panel's phase at that frequency ([`POINTS_PER_RADIAN`] × phase + 1 points), two consecutive
//! moves within the share before; or, once resolved, the tail of the level's own Chebyshev
//! coefficients ([`Levelled::tail_error`]), which credits the faster-than-geometric fall the
//! nested estimate cannot see (33 points where it asked for 65). The tolerance of a value comes
//! from the frequency rule ([`OtfEngine::set_value_tolerance`]), as on the closed-form engine:
//! [`VALUE_SHARE`] of its absolute budget per value, shared equally between the panels that
//! carry weight, so the values' errors and the frequency rule's add up to at most the requested
//! one; each single-wavelength OTF is computed only to a tenth of its panel's share
//! ([`crate::otf::defocus_otf_many_within`]).
//! A panel whose finest level (129 points) does not settle is halved, as at the limit.
//!
//! The engine applies where every order is a centred circle with defocus (the exact 1-D OTF; no
//! tables, no image shifts, no FFT grids): there the OTF is real and direction-independent.

use std::cell::{Cell, RefCell};
use std::sync::Arc;

use num_complex::Complex64;

use super::spectral::{
    FIRST_MOMENT_DEGREE, Interpolant, LEBESGUE, LEVELS, Node, Nodes, Panel, Scene, Start, lobatto_lambdas,
    lobatto_weights,
};
use super::{Engine, FrequencyRule, OtfEngine, level_error, nested_error};
use crate::quad;

/// The level whose points carry the averages over the spectrum (`detected_integral`,
/// `spectral_average`: the photon count, the mean wavelength, the RMS defocus): 17 points per
/// panel, with exact moments, for functions as smooth as a lens's efficiency and defocus.
const AVERAGE_LEVEL: usize = 3;

/// Points per radian of a panel's defocus phase from which the nested estimate and the Chebyshev
/// tail are trusted: about
/// κ = phase/2 points resolve `e^{iκx}` on Chebyshev points (Trefethen, ATAP ch. 8). The limit's
/// own rule trusts 0.3 per radian, then checks the count it keeps against the accepted level
/// (`Interpolant::trim`); here nothing checks a level after it, and at 0.3 a panel of the
/// spectrometer scene at half of Nyquist (21 rad) was accepted at 9 points on a chance agreement
/// of 5 and 9 (moves 4.9e-3, 6.9e-6), 3e-4 from the converged value.
const POINTS_PER_RADIAN: f64 = 0.5;

/// Share of the frequency rule's per-value budget one OTF value's spectral sum may spend: a
/// tenth (on the closed-form engine, half). The spectral sums change level from one frequency
/// to the next, so each value carries its own error; near the OTF's zeros that noise makes sign
/// changes the frequency rule then locates (a top-hat at 600–660 nm, F/1.4, 2 µm pixels: 177
/// zeros located at 1e-3 with half, against the 156 of the exact curve with a tenth: 156 at
/// 1e-3 and 1e-7, 154 at 1e-5, where one lobe of the OTF between two close zeros stays within
/// the tolerance, the mean 2.8e-10 off). The spectrometer scene pays 7 % more single-wavelength
/// OTFs for it.
const VALUE_SHARE: f64 = 0.1;

/// Narrowest panel, relative to the band, that a frequency's unsettled finest level halves.
const NARROWEST_PANEL: f64 = 1e-9;

/// One order at one wavelength, as the exact 1-D OTF reads it.
#[derive(Clone, Debug)]
struct OrderAt {
    /// `λ F# / r`: `s = ν` times this (r the pupil's radius relative to the full aperture)
    s_per_frequency: f64,
    /// defocus in waves, `W020/λ`
    waves: f64,
    efficiency: f64,
    /// a radially symmetric pupil given as data, computed by the radial engine instead
    radial: Option<Arc<crate::radial::RadialOrder>>,
}

/// The lens at the points a level adds: their orders one after the other, and where each
/// point's end (one allocation a level, not one a point).
#[derive(Clone, Debug, Default)]
struct Fresh {
    orders: Vec<OrderAt>,
    ends: Vec<usize>,
    /// per order, the change of its wavefront per unit of each Binary 2 coefficient
    /// (`LensModel::binary2_directions`), made when a gradient first climbs to the level; `None`
    /// before, `Some(None)` where the lens or an order has none (no gradient on this engine)
    directions: Option<Option<Vec<Vec<crate::radial::RadialProfile>>>>,
    /// per order, its derivatives along each parameter of a field gradient
    /// (`LensModel::order_derivatives`: `(∂τ_o, ∂A_o, ∂W_o)`), made when such a gradient first
    /// climbs to the level, for the parameters `field_parameters`; `Some(None)` where the lens or
    /// an order has none
    fields: Option<Option<Vec<Vec<FieldLane>>>>,
    field_parameters: Vec<usize>,
    /// per order, its rates along the design wavelength `[∂w_o/∂ln λ0, ∂τ_o/∂ln λ0]` (`w_o` in
    /// waves: `LensModel::design_wavelength_rates`' `∂W020_o` over λ), made when the design
    /// wavelength's lane first climbs to the level; `Some(None)` where the lens gives none
    design: Option<Option<Vec<[f64; 2]>>>,
    /// the wavelength of each new point
    lambdas: Vec<f64>,
    /// a spectral rate lane's `r(λ)` at each new point ([`Lanes::Rate`]), with the address of
    /// the rate it was made for
    rates: Option<(usize, Vec<f64>)>,
}

/// One order's derivative along one parameter: `(∂τ_o, ∂A_o, ∂W_o)` ([`Fresh::fields`]).
type FieldLane = (f64, crate::radial::RadialProfile, crate::radial::RadialProfile);

impl Fresh {
    /// Where the orders of point `k` of the level's new ones stand in `orders` (and their OTFs
    /// in the level's list of them).
    fn range(&self, k: usize) -> std::ops::Range<usize> {
        (if k == 0 { 0 } else { self.ends[k - 1] })..self.ends[k]
    }
}

/// A panel with its levels: the product-integration weights and the lens at the points each
/// level adds, filled when a frequency first climbs there.
struct Levelled {
    panel: Interpolant,
    weights: Vec<Vec<f64>>,
    /// per level, what an error δ in every OTF moves its product integral by, per unit of the
    /// panel's weight and of δ: `Σ_k |w_k| / |mass|` (about 1 for a positive weight, at most the
    /// Lebesgue constant) times the largest `Σ_o |τ_o|` of the level's new points
    amplification: Vec<f64>,
    /// the points level ℓ adds to level ℓ − 1 (all three for level 0)
    fresh: Vec<Fresh>,
    /// the lens at the wavelengths whose nodes the engine already made (the averages' level):
    /// a level's point found here is not prepared again (a radial pupil's preparation is the
    /// costly part of a wavelength)
    known: Vec<(f64, Vec<OrderAt>)>,
    scratch: Scratch,
}

/// Buffers one OTF value's climb reuses: the `(s, w)` of the new points' orders, their OTFs,
/// and `g(ν, λ)` on the current level's points (k = 0 at b).
#[derive(Default)]
struct Scratch {
    pairs: Vec<(f64, f64)>,
    otfs: Vec<f64>,
    values: Vec<f64>,
    /// with a gradient: `∂g/∂A_j` on the current level's points, point after point (`lanes`
    /// each, k = 0 at b), and one OTF's derivatives
    derivatives: Vec<f64>,
    one: Vec<f64>,
}

/// What a climb carries beside each value.
#[derive(Clone, Copy)]
enum Lanes<'p> {
    /// the value alone
    None,
    /// the derivatives along the lens's directions (`LensModel::binary2_directions`), this many
    Directions(usize),
    /// one lane: `Σ_o τ_o w_o ∂H/∂w_o`, the derivative with respect to a common relative change
    /// of every order's defocus (`crate::otf::defocus_otf_many_and_log_derivative_within`)
    Defocus,
    /// one lane per parameter of the lens's order derivatives (`LensModel::order_derivatives`:
    /// a library lens's parameter bias): `Σ_o (∂τ_o H_o + τ_o ∂H_o)`, `∂H_o` the radial
    /// engine's amplitude and phase lane (`RadialOrder::otf_and_field_derivatives`)
    Fields(&'p [usize]),
    /// one lane: `r(λ) g(ν, λ)`, the value re-weighted by a rate of the detected spectrum
    /// (`∂ln ρ = r`: a blackbody's temperature, docs/physics.md "Gradients: a line's wavelength
    /// and a blackbody's temperature"), the value's own OTFs
    Rate(&'p dyn Fn(f64) -> f64),
    /// one lane: `Σ_o [τ_o ∂H/∂w δw_o + δτ_o H_o]`, the orders moving with the design wavelength
    /// ([`Fresh::design`]; docs/physics.md, "Gradients: the design wavelength")
    Design,
    /// two lanes on one climb: [`Lanes::Design`]'s, then [`Lanes::Defocus`]'s (the design
    /// wavelength and the F-number's defocus of a lens with a design band from the same OTFs)
    DesignAndDefocus,
    /// `2n + 1` lanes for `n` orders at every point: each order's own share of
    /// [`Lanes::Design`]'s sum, `τ_o ∂H/∂w δw_o + δτ_o H_o`, then each order's `τ_o H_o` (its
    /// efficiency moving by itself), then [`Lanes::Defocus`]'s `Σ_o τ_o w_o ∂H/∂w_o` from the
    /// same `w ∂H/∂w` (the F-number and focal length; docs/physics.md, "Gradients: the
    /// multiplexed lens")
    Orders(usize),
}

impl std::fmt::Debug for Lanes<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Lanes::None => write!(f, "None"),
            Lanes::Directions(n) => write!(f, "Directions({n})"),
            Lanes::Defocus => write!(f, "Defocus"),
            Lanes::Fields(p) => write!(f, "Fields({p:?})"),
            Lanes::Rate(_) => write!(f, "Rate"),
            Lanes::Design => write!(f, "Design"),
            Lanes::DesignAndDefocus => write!(f, "DesignAndDefocus"),
            Lanes::Orders(n) => write!(f, "Orders({n})"),
        }
    }
}

impl Lanes<'_> {
    /// Derivatives a point.
    fn count(self) -> usize {
        match self {
            Lanes::None => 0,
            Lanes::Directions(n) => n,
            Lanes::Defocus => 1,
            Lanes::Fields(p) => p.len(),
            Lanes::Rate(_) => 1,
            Lanes::Design => 1,
            Lanes::DesignAndDefocus => 2,
            Lanes::Orders(n) => 2 * n + 1,
        }
    }
}

impl std::fmt::Debug for Levelled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let p = &self.panel;
        write!(f, "Levelled {{ [{}, {}] m, phase {}, mass {} }}", p.a, p.b, p.phase, p.mass)
    }
}

impl Levelled {
    fn new(panel: Interpolant) -> Levelled {
        Levelled {
            panel,
            weights: vec![Vec::new(); LEVELS.len()],
            amplification: vec![f64::NAN; LEVELS.len()],
            fresh: vec![Fresh::default(); LEVELS.len()],
            known: Vec::new(),
            scratch: Scratch::default(),
        }
    }

    /// Makes level `level`'s product-integration weights ready.
    fn prepare_weights(&mut self, scene: &Scene<'_>, level: usize) {
        if self.weights[level].is_empty() {
            let points = LEVELS[level];
            self.weights[level] = lobatto_weights(self.panel.moments(scene.detected, points - 1), points);
        }
    }

    /// Makes level `level`'s weights and points ready.
    fn prepare(&mut self, scene: &Scene<'_>, level: usize) {
        let points = LEVELS[level];
        self.prepare_weights(scene, level);
        if self.fresh[level].ends.is_empty() {
            let lambdas = lobatto_lambdas(self.panel.a, self.panel.b, points);
            let fresh = &mut self.fresh[level];
            let new_points = if level == 0 { points } else { points / 2 };
            fresh.orders.reserve(new_points);
            fresh.ends.reserve(new_points);
            // one buffer for the lens's orders at every point (`LensModel::orders_into`)
            let mut orders = Vec::new();
            for k in (0..points).filter(|&k| level == 0 || k % 2 == 1) {
                let lambda = lambdas[k];
                fresh.lambdas.push(lambda);
                if let Some((_, known)) = self.known.iter().find(|(l, _)| *l == lambda) {
                    fresh.orders.extend_from_slice(known);
                    fresh.ends.push(fresh.orders.len());
                    continue;
                }
                orders.clear();
                scene.lens.orders_into(lambda, scene.field, &mut orders);
                fresh.orders.extend(orders.iter().map(|o| {
                    let node = Node::of(o, lambda, 0.0, scene.irises, scene.table_rule);
                    OrderAt {
                        s_per_frequency: scene.f_number * lambda / node.scale,
                        waves: node.w020 / lambda,
                        efficiency: o.efficiency,
                        radial: node.radial.clone(),
                    }
                }));
                fresh.ends.push(fresh.orders.len());
            }
        }
        if self.amplification[level].is_nan() {
            let spread = self.weights[level].iter().map(|w| w.abs()).sum::<f64>() / self.panel.mass.abs();
            let spread = if spread.is_finite() { spread.clamp(1.0, LEBESGUE) } else { LEBESGUE };
            let fresh = &self.fresh[level];
            let efficiency = (0..fresh.ends.len())
                .map(|k| fresh.orders[fresh.range(k)].iter().map(|o| o.efficiency.abs()).sum::<f64>())
                .fold(0.0, f64::max);
            self.amplification[level] = spread * efficiency.max(f64::MIN_POSITIVE);
        }
    }

    /// Makes level `level`'s derivative directions ready ([`Fresh::directions`]); whether every
    /// order of its points has `lanes` of them on the radial engine.
    fn prepare_directions(&mut self, scene: &Scene<'_>, level: usize, lanes: usize) -> bool {
        let points = LEVELS[level];
        let fresh = &mut self.fresh[level];
        if fresh.directions.is_none() {
            let lambdas = lobatto_lambdas(self.panel.a, self.panel.b, points);
            let mut all = Vec::with_capacity(fresh.orders.len());
            let mut ok = true;
            for (point, k) in (0..points).filter(|&k| level == 0 || k % 2 == 1).enumerate() {
                let range = fresh.range(point);
                match scene.lens.binary2_directions(lambdas[k]) {
                    Some(d) if d.len() == range.len() && fresh.orders[range].iter().all(|o| o.radial.is_some()) => {
                        ok &= d.iter().all(|d| d.len() == lanes);
                        all.extend(d);
                    }
                    _ => ok = false,
                }
            }
            fresh.directions = Some(ok.then_some(all));
        }
        matches!(fresh.directions, Some(Some(_)))
    }

    /// Makes level `level`'s rates along the design wavelength ready ([`Fresh::design`]);
    /// whether the lens gives them for every order of its points.
    fn prepare_design(&mut self, scene: &Scene<'_>, level: usize) -> bool {
        let fresh = &mut self.fresh[level];
        if fresh.design.is_none() {
            let mut all = Vec::with_capacity(fresh.orders.len());
            let mut ok = true;
            for (point, &lambda) in fresh.lambdas.iter().enumerate() {
                let range = fresh.range(point);
                // the full pupil (an iris scales the pupil and its defocus: not this lane)
                let full = fresh.orders[range.clone()].iter().all(|o| o.s_per_frequency == scene.f_number * lambda);
                match scene.lens.design_wavelength_rates(lambda, scene.field) {
                    Some(r) if full && r.len() == range.len() => {
                        all.extend(r.iter().map(|&[d_w, d_tau]| [d_w / lambda, d_tau]));
                    }
                    _ => {
                        ok = false;
                        break;
                    }
                }
            }
            fresh.design = Some(ok.then_some(all));
        }
        matches!(fresh.design, Some(Some(_)))
    }

    /// Makes level `level`'s field derivatives along `parameters` ready ([`Fresh::fields`]);
    /// whether every order of its points has them, on the radial engine.
    fn prepare_fields(&mut self, scene: &Scene<'_>, level: usize, parameters: &[usize]) -> bool {
        let points = LEVELS[level];
        let fresh = &mut self.fresh[level];
        if fresh.fields.is_none() || fresh.field_parameters != parameters {
            let lambdas = lobatto_lambdas(self.panel.a, self.panel.b, points);
            let mut all: Vec<Vec<FieldLane>> = Vec::with_capacity(fresh.orders.len());
            let mut ok = true;
            for (point, k) in (0..points).filter(|&k| level == 0 || k % 2 == 1).enumerate() {
                let range = fresh.range(point);
                if !fresh.orders[range.clone()].iter().all(|o| o.radial.is_some()) {
                    ok = false;
                    break;
                }
                let mut per_order: Vec<Vec<FieldLane>> = vec![Vec::with_capacity(parameters.len()); range.len()];
                for &p in parameters {
                    match scene.lens.order_derivatives(lambdas[k], p) {
                        Some(d) if d.efficiencies.len() == range.len() && d.fields.len() == range.len() => {
                            for ((lane, &d_tau), (d_a, d_w)) in per_order.iter_mut().zip(&d.efficiencies).zip(d.fields)
                            {
                                lane.push((d_tau, d_a, d_w));
                            }
                        }
                        _ => ok = false,
                    }
                }
                all.extend(per_order);
            }
            fresh.fields = Some(ok.then_some(all));
            fresh.field_parameters = parameters.to_vec();
        }
        matches!(fresh.fields, Some(Some(_)))
    }

    /// `g(ν, λ)` at the points level `level` adds, into `values` at their slots (all three for
    /// level 0, the odd ones above; `values` holds the level's points).
    /// Each OTF to a tenth of `allowed` (per unit weight) over the level's amplification: an
    /// error δ per OTF moves the product integral by at most δ Σ τ_o Σ|w_k|.
    fn fresh_values(&mut self, level: usize, nu: f64, allowed: f64, evaluations: &Cell<usize>, lanes: Lanes<'_>) {
        let Scratch { pairs, otfs, values, derivatives, one } = &mut self.scratch;
        let fresh = &self.fresh[level];
        pairs.clear();
        pairs.extend(fresh.orders.iter().map(|o| (nu * o.s_per_frequency, o.waves)));
        otfs.clear();
        otfs.resize(pairs.len(), 0.0);
        let accuracy = 0.1 * allowed / self.amplification[level];
        let (first, step) = if level == 0 { (0, 1) } else { (1, 2) };
        if let Lanes::Orders(n) = lanes {
            // each order's design lane and its own weight, beside its OTF on the defocus lane's
            // forms (the values those of the value alone, bit for bit)
            one.clear();
            one.resize(pairs.len(), 0.0);
            crate::otf::defocus_otf_many_and_log_derivative_within(pairs, otfs, one, accuracy);
            evaluations.set(evaluations.get() + pairs.len());
            let Some(Some(rates)) = &fresh.design else { return };
            for (k, point) in (first..).step_by(step).zip(0..fresh.ends.len()) {
                let range = fresh.range(point);
                let orders = &fresh.orders[range.clone()];
                values[k] = orders.iter().zip(&otfs[range.clone()]).map(|(o, v)| o.efficiency * v).sum();
                let slot = &mut derivatives[k * (2 * n + 1)..(k + 1) * (2 * n + 1)];
                slot.iter_mut().for_each(|d| *d = 0.0);
                for (o, i) in range.enumerate().take(n) {
                    let (order, d, h, [d_w, d_tau]) = (&fresh.orders[i], one[i], otfs[i], rates[i]);
                    let slope = if order.waves == 0.0 { 0.0 } else { d / order.waves };
                    slot[o] = order.efficiency * slope * d_w + d_tau * h;
                    slot[n + o] = order.efficiency * h;
                    // the defocus lane, summed as `Lanes::Defocus` sums it
                    slot[2 * n] += order.efficiency * d;
                }
            }
            return;
        }
        if matches!(lanes, Lanes::Defocus | Lanes::Design | Lanes::DesignAndDefocus) {
            // the defocus lane: each order's w ∂H/∂w beside its OTF on the same forms
            // (`defocus_otf_many_and_log_derivative_within`), summed per point as the values are
            one.clear();
            one.resize(pairs.len(), 0.0);
            crate::otf::defocus_otf_many_and_log_derivative_within(pairs, otfs, one, accuracy);
            evaluations.set(evaluations.get() + pairs.len());
            let design = match (lanes, &fresh.design) {
                (Lanes::Design | Lanes::DesignAndDefocus, Some(Some(d))) => Some(d),
                (Lanes::Design | Lanes::DesignAndDefocus, _) => return,
                _ => None,
            };
            let both = matches!(lanes, Lanes::DesignAndDefocus);
            for (k, point) in (first..).step_by(step).zip(0..fresh.ends.len()) {
                let range = fresh.range(point);
                let orders = &fresh.orders[range.clone()];
                values[k] = orders.iter().zip(&otfs[range.clone()]).map(|(o, v)| o.efficiency * v).sum();
                let defocus = || orders.iter().zip(&one[range.clone()]).map(|(o, d)| o.efficiency * d).sum::<f64>();
                let Some(rates) = design else {
                    derivatives[k] = defocus();
                    continue;
                };
                // τ_o ∂H/∂w δw_o + δτ_o H_o, ∂H/∂w = (w ∂H/∂w)/w (0 at w = 0: H is even in w)
                let moved = orders
                    .iter()
                    .zip(&one[range.clone()])
                    .zip(&otfs[range.clone()])
                    .zip(&rates[range.clone()])
                    .map(|(((o, d), h), [d_w, d_tau])| {
                        let slope = if o.waves == 0.0 { 0.0 } else { d / o.waves };
                        o.efficiency * slope * d_w + d_tau * h
                    })
                    .sum();
                if both {
                    // the design lane, then the defocus lane from the same w ∂H/∂w
                    derivatives[2 * k] = moved;
                    derivatives[2 * k + 1] = defocus();
                } else {
                    derivatives[k] = moved;
                }
            }
            return;
        }
        if let Lanes::Fields(parameters) = lanes {
            // the field lanes: each order's OTF as the value's (the same radial engine, bit for
            // bit) with its derivatives from the same nodes and phases, summed per point as the
            // values are: `Σ_o (∂τ_o H_o + τ_o ∂H_o)`
            let Some(Some(fields)) = &fresh.fields else { return };
            let lanes = parameters.len();
            one.resize(lanes, 0.0);
            let mut profiles = Vec::with_capacity(lanes);
            for (k, point) in (first..).step_by(step).zip(0..fresh.ends.len()) {
                let range = fresh.range(point);
                let slot = &mut derivatives[k * lanes..(k + 1) * lanes];
                slot.iter_mut().for_each(|d| *d = 0.0);
                for i in range.clone() {
                    let (o, (s, _)) = (&fresh.orders[i], pairs[i]);
                    let Some(radial) = &o.radial else { continue };
                    profiles.clear();
                    profiles.extend(fields[i].iter().map(|(_, a, w)| (a, w)));
                    otfs[i] = radial.otf_and_field_derivatives(s, accuracy, &profiles, one);
                    for ((d, x), (d_tau, _, _)) in slot.iter_mut().zip(one.iter()).zip(&fields[i]) {
                        *d += d_tau * otfs[i] + o.efficiency * x;
                    }
                }
                values[k] = fresh.orders[range.clone()].iter().zip(&otfs[range]).map(|(o, v)| o.efficiency * v).sum();
            }
            evaluations.set(evaluations.get() + pairs.len());
            return;
        }
        if let Lanes::Directions(lanes) = lanes
            && lanes > 0
        {
            // the gradient's lanes: each order's OTF and its derivatives on the same rule
            // (`RadialOrder::otf_and_derivatives`), summed per point as the values are
            let Some(Some(directions)) = &fresh.directions else { return };
            one.resize(lanes, 0.0);
            for (k, point) in (first..).step_by(step).zip(0..fresh.ends.len()) {
                let (mut value, slot) = (0.0, &mut derivatives[k * lanes..(k + 1) * lanes]);
                slot.iter_mut().for_each(|d| *d = 0.0);
                for i in fresh.range(point) {
                    let (o, (s, _)) = (&fresh.orders[i], pairs[i]);
                    let Some(radial) = &o.radial else { continue };
                    value += o.efficiency * radial.otf_and_derivatives(s, accuracy, &directions[i], one);
                    for (d, x) in slot.iter_mut().zip(one.iter()) {
                        *d += o.efficiency * x;
                    }
                }
                values[k] = value;
            }
            evaluations.set(evaluations.get() + pairs.len());
            return;
        }
        if fresh.orders.iter().any(|o| o.radial.is_some()) {
            // radial pupils one at a time (the radial engine), the rest as a batch
            for ((o, &(s, w)), otf) in fresh.orders.iter().zip(pairs.iter()).zip(otfs.iter_mut()) {
                *otf = match &o.radial {
                    Some(r) => r.otf(s, accuracy),
                    None => crate::otf::defocus_otf(s, w),
                };
            }
        } else {
            crate::otf::defocus_otf_many_within(pairs, otfs, accuracy);
        }
        evaluations.set(evaluations.get() + pairs.len());
        for (k, point) in (first..).step_by(step).zip(0..fresh.ends.len()) {
            let range = fresh.range(point);
            values[k] = fresh.orders[range.clone()].iter().zip(&otfs[range]).map(|(o, v)| o.efficiency * v).sum();
        }
        if let Lanes::Rate(rate) = lanes {
            // the value's own sums, re-weighted by the rate at each point (made once a level)
            let key = (rate as *const dyn Fn(f64) -> f64).cast::<()>() as usize;
            let fresh = &mut self.fresh[level];
            if fresh.rates.as_ref().is_none_or(|(k, _)| *k != key) {
                fresh.rates = Some((key, fresh.lambdas.iter().map(|&l| rate(l)).collect()));
            }
            let Some((_, rates)) = &fresh.rates else { return };
            for (k, r) in (first..).step_by(step).zip(rates) {
                derivatives[k] = r * values[k];
            }
        }
    }

    /// The error per unit weight of the product integral on the current level's values (k = 0
    /// at b), from the coefficients its interpolant cannot hold: with the last ones of size `c`
    /// falling at `r` a degree ([`quad::chebyshev_tail_parts`]), the coefficient of degree
    /// `m + i` is taken as `c rⁱ`, and the integral of the level's `m + 1` points misses
    /// `Σ_{j>m} c_j (μ_j − μ_{2m−j})` (each aliased onto degree `2m − j`; μ the panel weight's
    /// Chebyshev moments), so the error is at most `c Σ_i rⁱ (|μ_{m+i}| + |μ_{m−i}|)`: the
    /// moments the panel has (to degree 32 without a rebuild), and beyond them the largest of
    /// the upper half of those the level uses (the weight is smooth, or a table whose moments
    /// fall as its kinks allow). For the defocus phase the coefficients fall super-geometrically
    /// once the points resolve it (a panel of the spectrometer scene at Nyquist: 3e-6 at degree
    /// 24, 1.5e-10 at 32), where the nested estimate, which sees the level below's error, asks
    /// for the level above; and the moments near degree m are far below the panel's mass (the
    /// Binary 2 metalens's centre panel at 17 points: an estimate within its 5e-10 where the
    /// nested one said 6e-8, the integral 5e-12 from the 33-point one).
    fn tail_error(&mut self, scene: &Scene<'_>) -> f64 {
        let Some((size, rate)) = quad::chebyshev_tail_parts(&self.scratch.values) else {
            return f64::INFINITY;
        };
        if size == 0.0 {
            return 0.0;
        }
        if rate >= quad::TAIL_MAX_RATE {
            return f64::INFINITY;
        }
        let m = self.scratch.values.len() - 1;
        let mass = self.panel.mass.abs();
        let top = (2 * m).min(FIRST_MOMENT_DEGREE.max(m));
        let moments = self.panel.moments(scene.detected, top);
        let upper = moments[m / 2..=m].iter().fold(0.0_f64, |acc, mu| acc.max(mu.abs()));
        let (mut sum, mut power) = (0.0, 1.0);
        for i in 1..=m {
            power *= rate;
            let above = if m + i <= top { moments[m + i].abs() } else { upper };
            sum += power * (above + moments[m - i].abs());
        }
        size * sum / mass
    }

    /// `∫ ρ g(ν, ·)` over the panel to within `allowed` per unit of its weight, or, where the
    /// finest level does not settle, `Err` with that level's integral. With `gradient` (one lane
    /// per Binary 2 coefficient), `∫ ρ ∂g/∂A_j` into it on the level the value accepts: the
    /// value's own nodes and weights (docs/physics.md, "Gradients"); the caller has made the
    /// directions ready ([`prepare_directions`](Self::prepare_directions)).
    fn integral(
        &mut self,
        scene: &Scene<'_>,
        nu: f64,
        allowed: f64,
        evaluations: &Cell<usize>,
        gradient: Option<&mut [f64]>,
        lanes: Lanes<'_>,
    ) -> Result<f64, f64> {
        let result = self.climb(scene, nu, allowed, evaluations, lanes);
        let lanes = lanes.count();
        if let Some(gradient) = gradient {
            let weights = &self.weights[LEVELS.iter().position(|&p| p == self.scratch.values.len()).unwrap_or(0)];
            gradient.iter_mut().for_each(|g| *g = 0.0);
            for (w, point) in weights.iter().zip(self.scratch.derivatives.chunks_exact(lanes)) {
                for (g, d) in gradient.iter_mut().zip(point) {
                    *g += w * d;
                }
            }
        }
        result
    }

    /// [`integral`](Self::integral)'s climb through the levels, `lanes` derivatives a point
    /// beside each value.
    fn climb(
        &mut self,
        scene: &Scene<'_>,
        nu: f64,
        allowed: f64,
        evaluations: &Cell<usize>,
        kind: Lanes<'_>,
    ) -> Result<f64, f64> {
        let lanes = kind.count();
        let mass = self.panel.mass.abs();
        // the phase the points must resolve at this frequency (∝ ν: the defocus phase is)
        let resolved = POINTS_PER_RADIAN * self.panel.phase * nu / scene.max_frequency + 1.0;
        // a panel too light to matter takes the quadratic (|g| ≤ 1 per unit efficiency: its
        // interpolant is within the Lebesgue constant of that)
        let first = if 2.0 * LEBESGUE <= allowed { 0 } else { 1 };
        let mut previous: Option<f64> = None;
        // the moves between consecutive levels (at most one a level; no allocation per value)
        let (mut moves, mut counted) = ([0.0; LEVELS.len()], 0);
        for (level, &points) in LEVELS.iter().enumerate() {
            self.prepare(scene, level);
            match kind {
                Lanes::Directions(_) if !self.prepare_directions(scene, level, lanes) => return Err(f64::NAN),
                Lanes::Fields(parameters) if !self.prepare_fields(scene, level, parameters) => return Err(f64::NAN),
                // a radial pupil (given as data) has no defocus lane on this engine
                Lanes::Defocus | Lanes::Design | Lanes::DesignAndDefocus
                    if self.fresh[level].orders.iter().any(|o| o.radial.is_some()) =>
                {
                    return Err(f64::NAN);
                }
                Lanes::Design | Lanes::DesignAndDefocus if !self.prepare_design(scene, level) => {
                    return Err(f64::NAN);
                }
                Lanes::Orders(_) if self.fresh[level].orders.iter().any(|o| o.radial.is_some()) => {
                    return Err(f64::NAN);
                }
                // every point with the same n orders, each with its rates
                Lanes::Orders(n)
                    if !self.prepare_design(scene, level)
                        || (0..self.fresh[level].ends.len()).any(|k| self.fresh[level].range(k).len() != n) =>
                {
                    return Err(f64::NAN);
                }
                _ => {}
            }
            // the level below's points to the even slots (from the top down), the new ones between
            let Scratch { values, derivatives, .. } = &mut self.scratch;
            values.resize(points, 0.0);
            derivatives.resize(points * lanes, 0.0);
            if level > 0 {
                for k in (0..=points / 2).rev() {
                    values[2 * k] = values[k];
                    derivatives.copy_within(k * lanes..(k + 1) * lanes, 2 * k * lanes);
                }
            }
            self.fresh_values(level, nu, allowed, evaluations, kind);
            let values = &self.scratch.values;
            let integral = quad::dot(values, &self.weights[level]);
            if level < first {
                previous = Some(integral);
                continue;
            }
            if level == 0 {
                return Ok(integral);
            }
            let is_resolved = points as f64 >= resolved;
            if let Some(before) = previous {
                moves[counted] = (integral - before).abs() / mass;
                counted += 1;
                if level_error(&moves[..counted], is_resolved, nested_error) <= allowed {
                    return Ok(integral);
                }
            }
            if is_resolved && self.tail_error(scene) <= allowed {
                return Ok(integral);
            }
            previous = Some(integral);
        }
        Err(previous.unwrap_or(0.0))
    }
}

/// Product-integration panels read per frequency through the exact 1-D OTF.
#[derive(Debug)]
pub(super) struct PerFrequency<'a> {
    scene: Scene<'a>,
    /// the 17-point level of every panel, for the averages over the spectrum
    nodes: Nodes,
    panels: RefCell<Vec<Levelled>>,
    total_mass: f64,
    /// absolute tolerance of one OTF value (set by the frequency rule; before it, for single
    /// values, 5 % of the relative tolerance)
    otf_tolerance: Cell<f64>,
    /// single-wavelength OTFs computed so far
    evaluations: Cell<usize>,
    /// the parameters of a field gradient and `∫ρ Σ_o ∂τ_o dλ` along each on the averages'
    /// nodes (the derivative of `nodes.total_weight`), made when first asked
    field_total: RefCell<Option<(Vec<usize>, Vec<f64>)>>,
    /// `∫ρ Σ_o ∂τ_o/∂ln λ0 dλ` on the averages' nodes ([`design_total`](Self::design_total)),
    /// made when first asked
    design_total: Cell<Option<f64>>,
    /// [`order_totals`](Self::order_totals), made when first asked, with its count of orders
    order_totals: RefCell<Option<(usize, Vec<f64>)>>,
    /// the band the panels cover, `[lo, hi]` (the spectrum's support, or a Gaussian's ±7σ)
    lo: f64,
    hi: f64,
}

impl<'a> PerFrequency<'a> {
    /// The engine for `scene` over `[lo, hi]`, where product integration applies and every
    /// order is a centred circle with defocus; else `None`.
    pub fn new(scene: Scene<'a>, lo: f64, hi: f64, tolerance: f64) -> Option<PerFrequency<'a>> {
        let Start { panels, total_mass } = super::spectral::start(&scene, lo, hi)?;
        let mut panels: Vec<Levelled> = panels.into_iter().map(Levelled::new).collect();
        let mut nodes = Nodes { interpolated: true, ..Nodes::default() };
        for p in &mut panels {
            if p.panel.mass == 0.0 {
                continue;
            }
            let points = LEVELS[AVERAGE_LEVEL];
            let part = p.panel.part;
            let part_scene = scene.part(part);
            p.prepare_weights(&part_scene, AVERAGE_LEVEL);
            let start = nodes.nodes.len();
            let lambdas = lobatto_lambdas(p.panel.a, p.panel.b, points);
            for (&lambda, &w) in lambdas.iter().zip(&p.weights[AVERAGE_LEVEL]) {
                nodes.samples.push((lambda, w, part));
                if w != 0.0 {
                    let first = nodes.nodes.len();
                    nodes.emit(&part_scene, lambda, w, part);
                    // the same orders as `prepare` reads them (the efficiency from the node's
                    // weight `w τ_o`), so that the levels do not prepare these wavelengths again
                    let orders = nodes.nodes[first..]
                        .iter()
                        .map(|n| OrderAt {
                            s_per_frequency: scene.f_number * lambda / n.scale,
                            waves: n.w020 / lambda,
                            efficiency: n.weight / w,
                            radial: n.radial.clone(),
                        })
                        .collect();
                    p.known.push((lambda, orders));
                }
            }
            p.prepare(&part_scene, AVERAGE_LEVEL);
            nodes.panels.push(Panel { lo: p.panel.a, hi: p.panel.b, start, end: nodes.nodes.len(), part });
        }
        // only centred circles with defocus, or radially symmetric pupils (the radial engine):
        // no FFT grid, no table, no image shift
        if nodes.needs_grid || nodes.shifted() || nodes.nodes.iter().any(|n| n.table.is_some()) {
            return None;
        }
        nodes.sum_weights();
        Some(PerFrequency {
            scene,
            nodes,
            panels: RefCell::new(panels),
            total_mass,
            otf_tolerance: Cell::new(0.05 * tolerance),
            evaluations: Cell::new(0),
            field_total: RefCell::new(None),
            design_total: Cell::new(None),
            order_totals: RefCell::new(None),
            lo,
            hi,
        })
    }

    /// The OTF at `frequency` and, with `gradient`, its derivative with respect to each Binary 2
    /// coefficient into it (or, with `defocus`, its one lane `∂O/∂ln K`: every order's defocus
    /// scaled together), on the same spectral levels ([`Levelled::integral`]); `None` where the
    /// lens has no such derivatives on this engine.
    fn value(&self, frequency: f64, gradient: Option<&mut [f64]>, kind: Lanes<'_>) -> Option<f64> {
        self.value_and_edges(frequency, gradient, kind, None)
    }

    /// [`value`](Self::value), and with `edges` the band's ends as the value reads them:
    /// `[E_lo, T_lo, E_hi, T_hi]`, `E_x = Σ_p ρ_p(x) g_p(ν, x)` and `T_x = Σ_p ρ_p(x) Σ_o τ_o(x)`
    /// over the panels that end at `x` (one a part), `g_p` the value's own sum at the panel's
    /// end point (a Chebyshev–Lobatto point of every level, 1e-12 of the panel inside it).
    fn value_and_edges(
        &self,
        frequency: f64,
        mut gradient: Option<&mut [f64]>,
        kind: Lanes<'_>,
        mut edges: Option<&mut [f64; 4]>,
    ) -> Option<f64> {
        let nu = frequency.abs();
        let budget = self.otf_tolerance.get();
        let mut panels = self.panels.borrow_mut();
        'restart: loop {
            // the budget shared equally between the panels that carry weight: per unit of a
            // panel's weight, `budget / (panels × share)`. A panel's points grow with the log of
            // its accuracy (the Chebyshev tail falls geometrically and faster), so equal shares
            // of the error minimize their sum (Lagrange); a light panel far from focus takes a
            // looser rule, not the heavy one's (the spectrometer scene at 1e-6: 6 % fewer
            // single-wavelength OTFs than shares in proportion to √weight, the same error)
            let weighted = panels.iter().filter(|p| p.panel.mass != 0.0).count().max(1) as f64;
            let mut sum = 0.0;
            let lanes = gradient.as_ref().map_or(0, |g| g.len());
            let mut part_gradient = vec![0.0; lanes];
            if let Some(g) = gradient.as_deref_mut() {
                g.iter_mut().for_each(|g| *g = 0.0);
            }
            for k in 0..panels.len() {
                let share = panels[k].panel.mass.abs() / self.total_mass;
                if share == 0.0 {
                    continue;
                }
                let allowed = budget * self.nodes.total_weight.abs() / self.total_mass / (weighted * share);
                let part = self.scene.part(panels[k].panel.part);
                let lanes_of_panel = gradient.is_some().then_some(part_gradient.as_mut_slice());
                let result = panels[k].integral(&part, nu, allowed, &self.evaluations, lanes_of_panel, kind);
                if let Err(v) = result
                    && v.is_nan()
                {
                    // an order without derivative directions: no gradient here
                    return None;
                }
                let kept = result.is_ok() || panels[k].panel.b - panels[k].panel.a <= NARROWEST_PANEL * self.band();
                if let Some(g) = gradient.as_deref_mut()
                    && kept
                {
                    for (g, d) in g.iter_mut().zip(&part_gradient) {
                        *g += d;
                    }
                }
                match result {
                    Ok(v) => sum += v,
                    // the narrowest panel: its finest level's value, whatever its error
                    Err(v) if panels[k].panel.b - panels[k].panel.a <= NARROWEST_PANEL * self.band() => sum += v,
                    Err(_) => {
                        // halve the panel (its phase halves with it) and start this value again
                        let (low, high) = panels.remove(k).panel.halves(part.detected);
                        panels.insert(k, Levelled::new(high));
                        panels.insert(k, Levelled::new(low));
                        continue 'restart;
                    }
                }
            }
            let value = sum / self.nodes.total_weight;
            if let Some(edges) = edges.as_deref_mut() {
                *edges = [0.0; 4];
                for p in panels.iter().filter(|p| p.panel.mass != 0.0) {
                    let values = &p.scratch.values;
                    let lambdas = lobatto_lambdas(p.panel.a, p.panel.b, values.len());
                    let detected = self.scene.part(p.panel.part).detected;
                    // the level-0 points: k = 0 at b, k = 2 at a
                    let fresh = &p.fresh[0];
                    let efficiency =
                        |point: usize| fresh.orders[fresh.range(point)].iter().map(|o| o.efficiency).sum::<f64>();
                    if p.panel.a == self.lo {
                        let (lambda, v) = (lambdas[values.len() - 1], values[values.len() - 1]);
                        let rho = detected.value(lambda);
                        edges[0] += rho * v;
                        edges[1] += rho * efficiency(2);
                    }
                    if p.panel.b == self.hi {
                        let rho = detected.value(lambdas[0]);
                        edges[2] += rho * values[0];
                        edges[3] += rho * efficiency(0);
                    }
                }
            }
            if let Some(g) = gradient {
                match kind {
                    // O = Σ/∫ρΣτ: ∂O = (∂Σ − O ∂∫ρΣτ)/∫ρΣτ, the normalization's derivative
                    // on its own nodes
                    Lanes::Fields(parameters) => {
                        let d_total = self.field_total(parameters)?;
                        for (g, d) in g.iter_mut().zip(&d_total) {
                            *g = (*g - value * d) / self.nodes.total_weight;
                        }
                    }
                    Lanes::Design => {
                        let d_total = self.design_total()?;
                        g.iter_mut().for_each(|g| *g = (*g - value * d_total) / self.nodes.total_weight);
                    }
                    // the design lane less O times the normalization's rate; the defocus lane
                    // moves no efficiency
                    Lanes::DesignAndDefocus => {
                        let d_total = self.design_total()?;
                        g[0] = (g[0] - value * d_total) / self.nodes.total_weight;
                        g[1] /= self.nodes.total_weight;
                    }
                    // each order's lanes less O times its normalization's rate; the defocus
                    // lane (last) moves no efficiency
                    Lanes::Orders(n) => {
                        let totals = self.order_totals(n)?;
                        for (g, d) in g.iter_mut().zip(totals.iter().chain([&0.0])) {
                            *g = (*g - value * d) / self.nodes.total_weight;
                        }
                    }
                    _ => g.iter_mut().for_each(|g| *g /= self.nodes.total_weight),
                }
            }
            return Some(value);
        }
    }

    /// `∂(∫ρ Σ_o τ_o dλ)` along each of `parameters` on the nodes that make `nodes.total_weight`
    /// (the averages' level: `Σ w Σ_o ∂τ_o(λ)` over its samples, `LensModel::order_derivatives`);
    /// `None` where the lens gives no order derivatives there.
    fn field_total(&self, parameters: &[usize]) -> Option<Vec<f64>> {
        if let Some((p, d)) = self.field_total.borrow().as_ref()
            && p == parameters
        {
            return Some(d.clone());
        }
        let mut d_total = vec![0.0; parameters.len()];
        for &(lambda, w, part) in &self.nodes.samples {
            if w == 0.0 {
                continue;
            }
            let lens = self.scene.part(part).lens;
            for (d, &p) in d_total.iter_mut().zip(parameters) {
                *d += w * lens.order_derivatives(lambda, p)?.efficiencies.iter().sum::<f64>();
            }
        }
        *self.field_total.borrow_mut() = Some((parameters.to_vec(), d_total.clone()));
        Some(d_total)
    }

    /// `∂(∫ρ Σ_o τ_o dλ)/∂ln λ0 = Σ w Σ_o ∂τ_o/∂ln λ0` on the nodes that make
    /// `nodes.total_weight` (`LensModel::design_wavelength_rates`); `None` where the lens gives
    /// no rates there.
    pub(super) fn design_total(&self) -> Option<f64> {
        if let Some(d) = self.design_total.get() {
            return Some(d);
        }
        let mut d_total = 0.0;
        for &(lambda, w, part) in &self.nodes.samples {
            if w == 0.0 {
                continue;
            }
            let lens = self.scene.part(part).lens;
            d_total += w * lens.design_wavelength_rates(lambda, self.scene.field)?.iter().map(|r| r[1]).sum::<f64>();
        }
        self.design_total.set(Some(d_total));
        Some(d_total)
    }

    /// Per order `o` of `n`, `Σ w ∂τ_o/∂ln λ0` (its rates alone) and then `Σ w τ_o`, on the
    /// nodes that make `nodes.total_weight`: the normalization's rates of
    /// [`Lanes::Orders`]' lanes. `None` where the lens gives no rates or another count of orders.
    fn order_totals(&self, n: usize) -> Option<Vec<f64>> {
        if let Some((m, totals)) = self.order_totals.borrow().as_ref()
            && *m == n
        {
            return Some(totals.clone());
        }
        let mut totals = vec![0.0; 2 * n];
        for &(lambda, w, part) in &self.nodes.samples {
            if w == 0.0 {
                continue;
            }
            let lens = self.scene.part(part).lens;
            let rates = lens.design_wavelength_rates(lambda, self.scene.field)?;
            let orders = lens.orders(lambda, self.scene.field);
            if rates.len() != n || orders.len() != n {
                return None;
            }
            for (o, ([_, d_tau], order)) in rates.iter().zip(&orders).enumerate() {
                totals[o] += w * d_tau;
                totals[n + o] += w * order.efficiency;
            }
        }
        *self.order_totals.borrow_mut() = Some((n, totals.clone()));
        Some(totals)
    }

    /// The band's extent, for the narrowest panel a split may make.
    fn band(&self) -> f64 {
        let panels = &self.nodes.panels;
        match (panels.first(), panels.last()) {
            (Some(first), Some(last)) => last.hi - first.lo,
            _ => 0.0,
        }
    }
}

impl OtfEngine for PerFrequency<'_> {
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
        self.value(frequency, None, Lanes::None).unwrap_or(f64::NAN)
    }

    fn otf_and_gradient(&self, frequency: f64, gradient: &mut [f64]) -> Option<f64> {
        let lanes = Lanes::Directions(gradient.len());
        self.value(frequency, Some(gradient), lanes)
    }

    /// The OTF at `frequency` as [`otf`](OtfEngine::otf), bit for bit, and into `gradient` its
    /// derivative along each of `parameters` of the lens's order derivatives (a library lens's
    /// parameter bias): `∂O = (∫ρ Σ_o (∂τ_o H_o + τ_o ∂H_o) − O ∫ρ Σ_o ∂τ_o) / ∫ρ Σ_o τ_o`, the
    /// first integral with the weights of the level each panel accepts for the value, the second
    /// on the nodes of the normalization (docs/physics.md, "Gradients: a library's parameter
    /// bias"); `None` where an order has no derivatives or is not a radial pupil.
    fn otf_and_field_gradient(&self, frequency: f64, parameters: &[usize], gradient: &mut [f64]) -> Option<f64> {
        self.value(frequency, Some(gradient), Lanes::Fields(parameters))
    }

    /// `(O, ∂O/∂ln K)`: the defocus lane `Σ τ_o w_o ∂H/∂w_o` of every point beside its value,
    /// integrated with the weights of the level the value accepts (docs/physics.md, "Gradients:
    /// the F-number and the focal length on the value's rule"); `None` where an order is a
    /// radial pupil given as data.
    fn otf_and_defocus_derivative(&self, frequency: f64) -> Option<(f64, f64)> {
        let mut lane = [0.0];
        let value = self.value(frequency, Some(&mut lane), Lanes::Defocus)?;
        Some((value, lane[0]))
    }

    /// `(O, ∂O/∂ln λ0)`: the design wavelength's lane `Σ_o [τ_o ∂H/∂w δw_o + δτ_o H_o]` of every
    /// point beside its value (the defocus lane's forms), integrated with the weights of the
    /// level the value accepts, less `O` times the normalization's own rate
    /// ([`design_total`](PerFrequency::design_total)) (docs/physics.md, "Gradients: the design
    /// wavelength"); `None` where an order is a radial pupil or the lens gives no rates.
    fn otf_and_design_lane(&self, frequency: f64) -> Option<(f64, f64)> {
        let mut lane = [0.0];
        let value = self.value(frequency, Some(&mut lane), Lanes::Design)?;
        Some((value, lane[0]))
    }

    /// The OTF at `frequency` as [`otf`](OtfEngine::otf), bit for bit, and each order's design
    /// lane and efficiency lane, then the defocus lane `∂O/∂ln K` ([`Lanes::Orders`]),
    /// integrated with the weights of the level the value accepts, each order's less `O` times
    /// its normalization's rate
    /// ([`order_totals`](PerFrequency::order_totals)); `None` where an order is a radial pupil,
    /// the lens gives no rates or some wavelength has another count of orders.
    fn otf_and_order_lanes(&self, frequency: f64, lanes: &mut [f64]) -> Option<f64> {
        if lanes.len() < 3 || lanes.len().is_multiple_of(2) {
            return None;
        }
        let n = lanes.len() / 2;
        self.value(frequency, Some(lanes), Lanes::Orders(n))
    }

    /// The OTF at `frequency` as [`otf`](OtfEngine::otf), bit for bit (the same climb: the
    /// lanes read the value's own sums), with the spectral lanes (docs/physics.md, "Gradients: a
    /// line's wavelength and a blackbody's temperature", "Gradients: a top-hat's edges"):
    /// - with `rate = (r, ⟨r⟩)`, the detected spectrum moving as `∂ln ρ = r(λ)`:
    ///   `∂O = Σ w r g / W − O ⟨r⟩` (`W = ∫ρ Σ_o τ_o`, `⟨r⟩` on the averages' nodes, the
    ///   normalization's own), the first sum with the weights of the level each panel accepts;
    /// - with `edges`, the band's ends `lo`, `hi` moving (the integrals' limits: Leibniz's rule),
    ///   `∂O/∂hi = (E_hi − O T_hi)/W` and `∂O/∂lo = −(E_lo − O T_lo)/W`, `E_x`, `T_x` the density
    ///   times the value's own sum and the orders' efficiency at the end point
    ///   ([`value_and_edges`](Self::value_and_edges)).
    fn otf_and_spectral_lanes(
        &self,
        frequency: f64,
        rate: Option<(&dyn Fn(f64) -> f64, f64)>,
        edges: bool,
        lanes: &mut [f64],
    ) -> Option<f64> {
        let mut raw = [0.0];
        let mut ends = [0.0; 4];
        let (kind, gradient) = match rate {
            Some((r, _)) => (Lanes::Rate(r), Some(&mut raw[..])),
            None => (Lanes::None, None),
        };
        let value = self.value_and_edges(frequency, gradient, kind, edges.then_some(&mut ends))?;
        let total = self.nodes.total_weight;
        let mut out = lanes.iter_mut();
        if let Some((_, mean)) = rate {
            *out.next()? = raw[0] - value * mean;
        }
        if edges {
            *out.next()? = -(ends[0] - value * ends[1]) / total;
            *out.next()? = (ends[2] - value * ends[3]) / total;
        }
        Some(value)
    }

    /// `(O, [∂O/∂ln λ0, ∂O/∂lo, ∂O/∂hi, ∂O/∂ln K])` on one climb: the design wavelength's lane
    /// as [`otf_and_design_lane`](OtfEngine::otf_and_design_lane), the band's edges as
    /// [`otf_and_spectral_lanes`](OtfEngine::otf_and_spectral_lanes) and the defocus lane as
    /// [`otf_and_defocus_derivative`](OtfEngine::otf_and_defocus_derivative) give them (the same
    /// `w ∂H/∂w` beside each OTF), the value bit for bit [`otf`](OtfEngine::otf)'s.
    fn otf_and_design_and_edge_lanes(&self, frequency: f64, lanes: &mut [f64; 4]) -> Option<f64> {
        let mut design = [0.0; 2];
        let mut ends = [0.0; 4];
        let value = self.value_and_edges(frequency, Some(&mut design), Lanes::DesignAndDefocus, Some(&mut ends))?;
        let total = self.nodes.total_weight;
        *lanes = [design[0], -(ends[0] - value * ends[1]) / total, (ends[2] - value * ends[3]) / total, design[1]];
        Some(value)
    }

    /// The band `[lo, hi]` the panels cover, whose ends the edge lanes of
    /// [`otf_and_spectral_lanes`](OtfEngine::otf_and_spectral_lanes) move.
    fn spectral_ends(&self) -> Option<(f64, f64)> {
        Some((self.lo, self.hi))
    }

    fn otf_along(&self, frequency: f64, _azimuth: f64) -> Complex64 {
        // centred circles without image shifts: real and the same along every direction
        Complex64::new(self.otf(frequency), 0.0)
    }

    fn direction_dependent(&self) -> bool {
        false
    }

    fn frequency_rule(&self) -> FrequencyRule {
        FrequencyRule::Adaptive { min_panels: 1.0 }
    }

    fn set_value_tolerance(&self, absolute: f64) {
        self.otf_tolerance.set(VALUE_SHARE * absolute);
    }

    fn value_noise(&self) -> f64 {
        self.otf_tolerance.get()
    }

    fn value_evaluations(&self) -> usize {
        self.evaluations.get()
    }
}
