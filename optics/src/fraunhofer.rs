//! Validity of the Fraunhofer (far-field) model of a defocused image, paper SI eq. S15.
//!
//! The paper checked that the Fraunhofer MTF of its chromatic-defocus PSFs is valid while the
//! geometric blur radius `x = |Δf| · NA` stays below a threshold (0.25 mm for its lens). With
//! `W020 = Δz NA²/2` the blur radius of any order is `2 |W020| / NA`; for the chromatic lens,
//! `Δf = f0 Δλ/λ0` gives eq. S15, `x = f0 (Δλ/λ0) NA`.
//!
//! A tabulated order ([`Pupil::Table`]: an MTF table, a PSF stack) has no defocus to read: its
//! blur is the one its OTF implies ([`table_blur_radius`]), and outside the table's wavelengths
//! it is not known, so that light counts as blurred beyond any threshold.

use crate::OtfTable;
use crate::lens::{Field, LensModel, Order, Pupil};
use crate::quad;

/// The argument `u` at which the OTF of the geometric blur disk, `2 J1(u)/u` (docs/physics.md,
/// "Geometric limit"), falls to one half: `2 J1(u)/u = 1/2` (the root by bisection on the
/// power series of J1, tested).
pub const BLUR_DISK_HALF: f64 = 2.215_089_367_724_233;

/// The geometric blur radius (m) a tabulated OTF implies at `wavelength_m` (docs/physics.md,
/// "Fraunhofer validity"): the radius `r = u½/(2π ν½)` of the uniform blur disk whose OTF
/// `2 J1(π d ν)/(π d ν)` (`d = 2r`) falls to one half ([`BLUR_DISK_HALF`]) at the lowest
/// frequency `ν½` where the table's does, along the tangential or the sagittal direction (the
/// table linear between its frequencies). For a defocused order this is its geometric blur
/// `2|W020|/NA` to the accuracy of the geometric limit (0.23 % at 10 waves, tested); for an
/// in-focus one, 0.87 λF#, a fraction of the Airy radius. A table that stays above one half up to its last
/// frequency implies at most the radius for that frequency, which is returned. Outside the
/// table's wavelengths (the end rows are held, not known): infinite.
pub fn table_blur_radius(table: &OtfTable, wavelength_m: f64) -> f64 {
    let w = table.wavelengths();
    if !(wavelength_m >= w[0] && wavelength_m <= w[w.len() - 1]) {
        return f64::INFINITY;
    }
    let azimuths: &[f64] = if table.is_direction_dependent() { &[0.0, std::f64::consts::FRAC_PI_2] } else { &[0.0] };
    let freqs = table.frequencies();
    let mut half = table.max_frequency();
    for &azimuth in azimuths {
        let mut previous = (freqs[0], table.value(wavelength_m, freqs[0], azimuth));
        for &nu in &freqs[1..] {
            if nu >= half {
                break;
            }
            let v = table.value(wavelength_m, nu, azimuth);
            if v <= 0.5 {
                let (nu0, v0) = previous;
                let at = if v0 > v { nu0 + (nu - nu0) * (v0 - 0.5) / (v0 - v) } else { nu };
                half = half.min(at.max(nu0));
                break;
            }
            previous = (nu, v);
        }
    }
    BLUR_DISK_HALF / (2.0 * std::f64::consts::PI * half)
}

/// The `|W020|` (m) whose geometric blur `2|W020|/NA` is an order's for the Fraunhofer check: its
/// [`order_defocus`] (signed, as the crossings of `±limit` are located), or for a tabulated order
/// the larger of that and the blur its table implies ([`table_blur_radius`] × NA/2, ≥ 0,
/// infinite outside the table's wavelengths).
pub(crate) fn order_blur_w020(order: &Order, wavelength_m: f64, na: f64) -> f64 {
    let own = order_defocus(order);
    match &order.pupil {
        Pupil::Table(t) => own.abs().max(0.5 * na * table_blur_radius(t, wavelength_m)),
        _ => own,
    }
}

/// [`order_blur_w020`] of a spectral node: its W020 and its table, if any.
pub(crate) fn node_blur_w020(w020: f64, table: Option<&OtfTable>, wavelength_m: f64, na: f64) -> f64 {
    match table {
        Some(t) => w020.abs().max(0.5 * na * table_blur_radius(t, wavelength_m)),
        None => w020,
    }
}

/// The defocus (m) that sets an order's blur: its `W020`, or for a composite pupil of zones
/// ([`Pupil::Zones`]) the zone defocus of largest size if that is larger (the order's `defocus_m`
/// should already be it; a lens that leaves it at 0 is not taken for focused). A tabulated order
/// ([`Pupil::Table`]) has the `defocus_m` its lens gives it (0: always within the limit). Signed:
/// the value of largest size.
pub(crate) fn order_defocus(order: &Order) -> f64 {
    let own = order.wavefront.defocus_m;
    match &order.pupil {
        Pupil::Zones(zones) => zones
            .iter()
            .filter(|z| z.amplitude > 0.0)
            .map(|z| z.wavefront.defocus_m)
            .fold(own, |m, w| if w.abs() > m.abs() { w } else { m }),
        _ => own,
    }
}

/// Geometric blur radius (m) of the worst imaging order at `wavelength_m`: `2 |W020| / NA`, with
/// the largest zone defocus of a composite pupil ([`Pupil::Zones`]) and the blur a tabulated
/// order's OTF implies ([`table_blur_radius`]; infinite outside its wavelengths).
pub fn blur_radius(lens: &dyn LensModel, wavelength_m: f64) -> f64 {
    let na = lens.numerical_aperture();
    lens.orders(wavelength_m, Field::ON_AXIS)
        .iter()
        .map(|o| 2.0 * order_blur_w020(o, wavelength_m, na).abs() / na)
        .fold(0.0, f64::max)
}

/// The wavelengths `(first, last)`, m, that the tabulated orders of `lens` at `wavelength_m`
/// cover together (the lowest first, the highest last); `None` for a lens without one.
pub fn table_range(lens: &dyn LensModel, wavelength_m: f64, field: Field) -> Option<(f64, f64)> {
    lens.orders(wavelength_m, field)
        .iter()
        .filter_map(|o| match &o.pupil {
            Pupil::Table(t) => Some((t.wavelengths()[0], t.wavelengths()[t.wavelengths().len() - 1])),
            _ => None,
        })
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// The largest wavelength shift from `reference_m` (usually the design wavelength) on either side
/// whose blur radius stays within `threshold_m`: eq. S15 solved for `Δλ`, by bisection on
/// [`blur_radius`], so it holds for any lens model with a blur radius that grows with the shift.
///
/// Returns `None` when the blur stays within the threshold over the searched range
/// (`0 < λ ≤ 10 λ_ref`), i.e. no limit applies.
pub fn max_wavelength_shift(lens: &dyn LensModel, reference_m: f64, threshold_m: f64) -> Option<f64> {
    if let Some(affine) = lens.affine_defocus(Field::ON_AXIS) {
        return affine_wavelength_shift(&affine, lens.numerical_aperture(), reference_m, threshold_m);
    }
    bisected_wavelength_shift(lens, reference_m, threshold_m)
}

/// [`max_wavelength_shift`] of a lens whose one order has the defocus `W020 = w0 + w1 λ`
/// ([`LensModel::affine_defocus`]): the blur `2 |w0 + w1 λ|/NA` is within the threshold
/// between the two roots `λ± = (±x NA/2 − w0)/w1`, so each side's shift is the distance to
/// the root on that side, in the bisection's range (`0 < λ ≤ 10 λ_ref`) and 0 where the
/// reference itself is blurred beyond it. The bisection's answer in closed form (tested
/// against it): it cost a map 4 % of its time, fifty blur radii a side.
fn affine_wavelength_shift(affine: &crate::AffineDefocus, na: f64, reference_m: f64, threshold_m: f64) -> Option<f64> {
    let (w0, w1) = (affine.w020_intercept_m, affine.w020_slope);
    let limit = 0.5 * threshold_m * na;
    if 2.0 * (w0 + w1 * reference_m).abs() / na > threshold_m {
        return Some(0.0);
    }
    if w1 == 0.0 {
        return None;
    }
    let (a, b) = ((limit - w0) / w1, (-limit - w0) / w1);
    let below = reference_m - a.min(b);
    let above = a.max(b) - reference_m;
    // the bisection's ranges: below down to λ = 1e-9 λ_ref, above up to 10 λ_ref
    let below = (below < reference_m * (1.0 - 1e-9)).then_some(below.max(0.0));
    let above = (above < 9.0 * reference_m).then_some(above.max(0.0));
    match (below, above) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// [`max_wavelength_shift`] by bisection on [`blur_radius`], for any lens.
fn bisected_wavelength_shift(lens: &dyn LensModel, reference_m: f64, threshold_m: f64) -> Option<f64> {
    let exceeds = |shift: f64, sign: f64| blur_radius(lens, reference_m + sign * shift) > threshold_m;
    let side = |sign: f64, max_shift: f64| -> Option<f64> {
        if !exceeds(max_shift, sign) {
            return None;
        }
        let (mut lo, mut hi) = (0.0, max_shift);
        if exceeds(0.0, sign) {
            return Some(0.0);
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if exceeds(mid, sign) {
                hi = mid;
            } else {
                lo = mid;
            }
            if hi - lo <= 1e-15 * reference_m {
                break;
            }
        }
        Some(0.5 * (lo + hi))
    };
    let below = side(-1.0, reference_m * (1.0 - 1e-9));
    let above = side(1.0, 9.0 * reference_m);
    match (below, above) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Equal sub-intervals per spectral panel at which [`weight_defocused_beyond`] samples W020 to
/// bracket its crossings of the limit. A W020 that crosses the limit and returns within 1/16 of a
/// panel is missed; W020 monotone within a panel (every chromatic lens: it is affine in λ) is
/// handled exactly.
pub(crate) const CROSSING_SAMPLES: usize = 16;

/// `Σ_orders ∫ ρ(λ) τ_o(λ) dλ` over the wavelengths where order `o` is defocused beyond
/// `limit_m`, `|W020_o(λ)| > limit_m` (W020 of [`order_defocus`]: a composite pupil's largest
/// zone defocus; for the blur radius `x = 2|W020|/NA` of eq. S15,
/// `limit_m = x NA/2`), on the spectral `panels` `[lo, hi]` inside each of which `ρ` (`density`)
/// and the lens are smooth.
///
/// Per panel and per order, W020 is sampled at [`CROSSING_SAMPLES`] + 1 points, every sign change
/// of `W020 ∓ limit` is bracketed and located by the Illinois method to 1e-14 of λ, and the
/// sub-intervals beyond the limit are integrated by one 16-point Gauss–Legendre panel each (the
/// rule the spectral quadrature itself uses on the whole panel, which the sub-intervals tile).
/// The step at the crossing therefore never lands between nodes: the result is exact to rounding
/// for the integrands the panels integrate exactly, and continuous in every parameter.
pub(crate) fn weight_defocused_beyond(
    lens: &dyn LensModel,
    field: Field,
    density: &dyn Fn(f64) -> f64,
    panels: &[(f64, f64)],
    limit_m: f64,
) -> f64 {
    let order = |lambda: f64, k: usize| lens.orders(lambda, field).into_iter().nth(k);
    let na = lens.numerical_aperture();
    let mut total = 0.0;
    for &(lo, hi) in panels {
        if hi <= lo {
            continue;
        }
        let h = (hi - lo) / CROSSING_SAMPLES as f64;
        let grid: Vec<f64> =
            (0..=CROSSING_SAMPLES).map(|i| if i == CROSSING_SAMPLES { hi } else { lo + h * i as f64 }).collect();
        let sampled: Vec<Vec<Order>> = grid.iter().map(|&l| lens.orders(l, field)).collect();
        let orders: Vec<Vec<f64>> = sampled
            .iter()
            .zip(&grid)
            .map(|(list, &l)| list.iter().map(|o| order_blur_w020(o, l, na)).collect())
            .collect();
        let count = orders.iter().map(Vec::len).max().unwrap_or(0);
        for k in 0..count {
            let w020 = |l: f64| order(l, k).map_or(f64::NAN, |o| order_blur_w020(&o, l, na));
            let mut cuts = vec![lo, hi];
            // a tabulated order's blur is not known beyond its table's wavelengths (infinite
            // there): the ends of the table are cuts, and no crossing is sought across them
            for list in &sampled {
                if let Some(Pupil::Table(t)) = list.get(k).map(|o| &o.pupil) {
                    let w = t.wavelengths();
                    cuts.extend([w[0], w[w.len() - 1]].into_iter().filter(|&e| e > lo && e < hi));
                }
            }
            for target in [-limit_m, limit_m] {
                for (i, pair) in grid.windows(2).enumerate() {
                    let (Some(&w0), Some(&w1)) = (orders[i].get(k), orders[i + 1].get(k)) else { continue };
                    let (f0, f1) = (w0 - target, w1 - target);
                    if f0 * f1 < 0.0 && f0.is_finite() && f1.is_finite() {
                        cuts.push(quad::illinois(
                            &mut |l| w020(l) - target,
                            pair[0],
                            f0,
                            pair[1],
                            f1,
                            1e-14 * pair[0].abs().max(pair[1].abs()),
                        ));
                    }
                }
            }
            cuts.sort_by(f64::total_cmp);
            for pair in cuts.windows(2) {
                let (a, b) = (pair[0], pair[1]);
                // NaN (the order missing at the midpoint) is not beyond
                let beyond = b > a && w020(0.5 * (a + b)).abs() > limit_m;
                if !beyond {
                    continue;
                }
                quad::for_each_node(a, b, 1, |lambda, q| {
                    if let Some(o) = order(lambda, k) {
                        total += q * density(lambda) * o.efficiency;
                    }
                });
            }
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::{Order, Pupil, Wavefront};

    /// Two orders: one with an affine defocus through zero at 800 nm, one with a parabolic
    /// defocus (a focus extremum inside the band, so W020 crosses each limit twice).
    #[derive(Debug)]
    struct TwoOrders;
    impl LensModel for TwoOrders {
        fn f_number(&self) -> f64 {
            2.0
        }
        fn focal_length(&self) -> f64 {
            5e-3
        }
        fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
            let x = (lambda - 800e-9) / 100e-9;
            vec![
                Order::new(0.3, Pupil::Full, Wavefront::defocus(2e-6 * x)),
                Order::new(0.1, Pupil::Full, Wavefront::defocus(3e-6 * x * x - 1e-6)),
            ]
        }
    }

    #[test]
    fn crossings_of_every_order_are_located() {
        // flat density on [600, 1000] nm split into uneven panels; limit 1 µm:
        // order 1: |2x| > 1 ⇔ |x| > 1/2: outside 750–850 nm → 300 nm of the 400 nm band;
        // order 2: |3x² − 1| > 1 ⇔ x² > 2/3: |λ − 800| > 81.6497 nm → 400 − 163.2993 nm.
        let panels = [(600e-9, 640e-9), (640e-9, 790e-9), (790e-9, 1000e-9)];
        let got = weight_defocused_beyond(&TwoOrders, Field::ON_AXIS, &|_| 1.0, &panels, 1e-6);
        let exact = 0.3 * 300e-9 + 0.1 * (400e-9 - 2.0 * 100e-9 * (2.0f64 / 3.0).sqrt());
        assert!((got - exact).abs() < 1e-14 * exact, "{got:e} vs {exact:e}");
        // nothing beyond a limit above every |W020| of the band (≤ 4 µm and 11 µm)
        assert_eq!(weight_defocused_beyond(&TwoOrders, Field::ON_AXIS, &|_| 1.0, &panels, 20e-6), 0.0);
    }

    /// A segmented lens whose order leaves `defocus_m` at 0: its blur is its largest zone's;
    /// a tabulated order's is the `defocus_m` its lens sets.
    #[derive(Debug)]
    struct Zoned;
    impl LensModel for Zoned {
        fn f_number(&self) -> f64 {
            2.0
        }
        fn focal_length(&self) -> f64 {
            5e-3
        }
        fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
            use std::sync::Arc;
            let x = (lambda - 800e-9) / 100e-9;
            let half = |a: f64| Arc::new(crate::fft::Aperture::sector(a, a + std::f64::consts::PI).unwrap());
            let zones = vec![
                crate::Zone::new(half(0.0), 0.9, Wavefront::defocus(2e-6 * x)),
                crate::Zone::new(half(std::f64::consts::PI), 0.9, Wavefront::defocus(-1e-6 * x)),
                // dark: does not count
                crate::Zone::new(half(0.0), 0.0, Wavefront::defocus(9e-6)),
            ];
            // the table covers the band (outside it the blur is not known) and implies a blur
            // of 2.215/(2π 5e5) = 0.705 µm, W020 = 0.088 µm: its own 0.5 µm is larger
            let rows = vec![vec![1.0, 0.0], vec![1.0, 0.0]];
            let table = crate::OtfTable::new(vec![500e-9, 1100e-9], vec![0.0, 1e6], rows, None).unwrap();
            vec![
                Order::new(0.4, Pupil::Zones(Arc::from(zones)), Wavefront::default()),
                Order::new(0.1, Pupil::Table(Arc::new(table)), Wavefront::defocus(0.5e-6)),
            ]
        }
    }

    #[test]
    fn zones_blur_by_their_largest_defocus_and_tables_by_theirs() {
        let na = Zoned.numerical_aperture();
        // at 900 nm the zones' defocus is 2 µm and −1 µm: the 2 µm zone sets the blur
        assert!((blur_radius(&Zoned, 900e-9) - 2.0 * 2e-6 / na).abs() < 1e-18);
        // at 800 nm the zones are in focus: the table's 0.5 µm
        assert!((blur_radius(&Zoned, 800e-9) - 2.0 * 0.5e-6 / na).abs() < 1e-18);
        // limit 1 µm over 600–1000 nm: the zones beyond where |2x| > 1 (outside 750–850 nm),
        // 300 nm of 400; the table never
        let panels = [(600e-9, 1000e-9)];
        let got = weight_defocused_beyond(&Zoned, Field::ON_AXIS, &|_| 1.0, &panels, 1e-6);
        let exact = 0.4 * 300e-9;
        assert!((got - exact).abs() < 1e-14 * exact, "{got:e} vs {exact:e}");
        let got = weight_defocused_beyond(&Zoned, Field::ON_AXIS, &|_| 1.0, &panels, 0.4e-6);
        // the table's 0.5 µm is beyond 0.4 µm everywhere; the zones outside 780–820 nm
        let exact = 0.1 * 400e-9 + 0.4 * 360e-9;
        assert!((got - exact).abs() < 1e-14 * exact, "{got:e} vs {exact:e}");
    }

    /// One order with `W020 = w0 + w1 λ`, promised as affine.
    #[derive(Debug)]
    struct Affine(f64, f64);
    impl LensModel for Affine {
        fn f_number(&self) -> f64 {
            2.5
        }
        fn focal_length(&self) -> f64 {
            3.36e-3
        }
        fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
            vec![Order::new(0.15, Pupil::Full, Wavefront::defocus(self.0 + self.1 * lambda))]
        }
        fn affine_defocus(&self, _: Field) -> Option<crate::AffineDefocus> {
            Some(crate::AffineDefocus {
                efficiency: 0.15,
                transmission: 0.5,
                w020_intercept_m: self.0,
                w020_slope: self.1,
            })
        }
    }

    /// The closed form of an affine defocus gives the bisection's shifts to 1e-12 of the
    /// reference: focus at, beside and far from the reference, thresholds from inside the
    /// reference's own blur (0) to beyond the searched range (none), both signs of the slope.
    #[test]
    fn affine_shift_is_the_bisections() {
        let reference = 800e-9;
        for &(w0, w1) in &[
            (-0.0168e-3, 0.021),
            (0.0168e-3, -0.021),
            (-0.017e-3, 0.021),
            (-0.02e-3, 0.021),
            (1e-6, 0.0),
            (-2e-6, 1e-3),
        ] {
            let lens = Affine(w0, w1);
            for &threshold in &[1e-7, 1e-6, 1e-5, 1e-4, 2.5e-4, 1e-3, 1e-2, 1.0] {
                let fast = max_wavelength_shift(&lens, reference, threshold);
                let slow = bisected_wavelength_shift(&lens, reference, threshold);
                match (fast, slow) {
                    (Some(f), Some(s)) => {
                        assert!((f - s).abs() <= 1e-12 * reference, "({w0}, {w1}) {threshold}: {f} vs {s}")
                    }
                    (f, s) => assert_eq!(f, s, "({w0}, {w1}) {threshold}"),
                }
            }
        }
    }

    /// The constant is the root of `2 J1(u)/u = 1/2`, by the power series of J1.
    #[test]
    fn the_blur_disk_falls_to_one_half_at_its_constant() {
        let disk = |u: f64| {
            // 2 J1(u)/u = Σ (−1)^k (u/2)^{2k} / (k! (k+1)!)
            let (mut term, mut sum) = (1.0, 1.0);
            for k in 1..40 {
                term *= -(u / 2.0).powi(2) / (k as f64 * (k + 1) as f64);
                sum += term;
            }
            sum
        };
        assert!((disk(BLUR_DISK_HALF) - 0.5).abs() < 1e-15, "{}", disk(BLUR_DISK_HALF));
        assert!(disk(BLUR_DISK_HALF - 1e-9) > 0.5 && disk(BLUR_DISK_HALF + 1e-9) < 0.5);
    }

    /// A table of exact defocused OTFs (w waves at F/2.5, 800 nm) implies the geometric blur
    /// `2|W020|/NA = 4 w λ F#` to the accuracy of the geometric limit (measured 0.23 % low at 10
    /// waves, 0.05 % at 30; held to 0.5 % and 0.1 %); an in-focus row implies a fraction of the
    /// Airy radius (0.8727 λF#: s½ = 0.4040 of the diffraction-limited MTF); a
    /// table that stays above one half, the bound of its last frequency; outside: infinite.
    #[test]
    fn a_tables_blur_is_its_defocus_in_the_geometric_limit() {
        let (f_number, lambda) = (2.5, 800e-9);
        let cutoff = 1.0 / (lambda * f_number);
        let freqs: Vec<f64> = (0..=2000).map(|k| cutoff * k as f64 / 2000.0).collect();
        let row = |w: f64| freqs.iter().map(|nu| crate::otf::defocus_otf(nu / cutoff, w)).collect::<Vec<_>>();
        let table = crate::OtfTable::new(
            vec![700e-9, 800e-9, 900e-9],
            freqs.clone(),
            vec![row(0.0), row(10.0), row(30.0)],
            None,
        )
        .unwrap();
        for (l, w, tolerance) in [(800e-9, 10.0, 0.005), (900e-9, 30.0, 0.001)] {
            let geometric = 4.0 * w * lambda * f_number;
            let got = table_blur_radius(&table, l);
            assert!((got / geometric - 1.0).abs() < tolerance, "{w} waves: {got:e} vs {geometric:e}");
        }
        let focused = table_blur_radius(&table, 700e-9) / (lambda * f_number);
        assert!((focused - 0.8727).abs() < 1e-3, "{focused}");
        assert_eq!(table_blur_radius(&table, 699e-9), f64::INFINITY);
        assert_eq!(table_blur_radius(&table, 901e-9), f64::INFINITY);
        let flat = crate::OtfTable::new(vec![800e-9], vec![0.0, 1e5], vec![vec![1.0, 0.9]], None).unwrap();
        let bound = BLUR_DISK_HALF / (2.0 * std::f64::consts::PI * 1e5);
        assert!((table_blur_radius(&flat, 800e-9) - bound).abs() < 1e-20);
    }

    /// A lens given as a table: the light outside the table's wavelengths counts as blurred
    /// beyond any threshold (exactly its share of a flat density), the light inside as its rows'
    /// blur says; the largest shift stops at the table's nearer end.
    #[test]
    fn light_outside_a_table_is_beyond() {
        #[derive(Debug)]
        struct Tabled(std::sync::Arc<crate::OtfTable>);
        impl LensModel for Tabled {
            fn f_number(&self) -> f64 {
                2.5
            }
            fn focal_length(&self) -> f64 {
                3.36e-3
            }
            fn orders(&self, _: f64, _: Field) -> Vec<Order> {
                vec![Order::new(0.2, Pupil::Table(self.0.clone()), Wavefront::default())]
            }
        }
        let rows = vec![vec![1.0, 0.8, 0.2]; 2];
        let table = crate::OtfTable::new(vec![770e-9, 830e-9], vec![0.0, 1e5, 2e5], rows, None).unwrap();
        let lens = Tabled(std::sync::Arc::new(table));
        // the rows cross one half at 1.5e5 cycles/m: r = 2.35 µm, far under 0.25 mm
        let panels = [(700e-9, 780e-9), (780e-9, 900e-9)];
        let got = weight_defocused_beyond(&lens, Field::ON_AXIS, &|_| 1.0, &panels, 0.5 * 0.25e-3 * 0.2);
        let exact = 0.2 * (70e-9 + 70e-9);
        assert!((got - exact).abs() < 1e-14 * exact, "{got:e} vs {exact:e}");
        // a threshold under the rows' blur: everything
        let got = weight_defocused_beyond(&lens, Field::ON_AXIS, &|_| 1.0, &panels, 0.5 * 1e-6 * 0.2);
        assert!((got - 0.2 * 200e-9).abs() < 1e-14 * 0.2 * 200e-9, "{got:e}");
        let shift = max_wavelength_shift(&lens, 800e-9, 0.25e-3).unwrap();
        assert!((shift - 30e-9).abs() < 1e-15, "{shift:e}");
        assert_eq!(blur_radius(&lens, 850e-9), f64::INFINITY);
        assert_eq!(table_range(&lens, 800e-9, Field::ON_AXIS), Some((770e-9, 830e-9)));
    }

    #[test]
    fn illinois_converges_to_rounding() {
        let root = quad::illinois(&mut |x: f64| x * x * x - 2.0, 1.0, -1.0, 2.0, 6.0, 2e-14);
        assert!((root - 2f64.cbrt()).abs() < 1e-14, "{root}");
    }
}
