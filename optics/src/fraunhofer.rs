//! Validity of the Fraunhofer (far-field) model of a defocused image, paper SI eq. S15.
//!
//! The paper checked that the Fraunhofer MTF of its chromatic-defocus PSFs is valid while the
//! geometric blur radius `x = |Δf| · NA` stays below a threshold (0.25 mm for its lens). With
//! `W020 = Δz NA²/2` the blur radius of any order is `2 |W020| / NA`; for the chromatic lens,
//! `Δf = f0 Δλ/λ0` gives eq. S15, `x = f0 (Δλ/λ0) NA`.

use crate::lens::{Field, LensModel, Order, Pupil};
use crate::quad;

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
/// the largest zone defocus of a composite pupil ([`Pupil::Zones`]).
pub fn blur_radius(lens: &dyn LensModel, wavelength_m: f64) -> f64 {
    let na = lens.numerical_aperture();
    lens.orders(wavelength_m, Field::ON_AXIS).iter().map(|o| 2.0 * order_defocus(o).abs() / na).fold(0.0, f64::max)
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
    let mut total = 0.0;
    for &(lo, hi) in panels {
        if hi <= lo {
            continue;
        }
        let h = (hi - lo) / CROSSING_SAMPLES as f64;
        let grid: Vec<f64> =
            (0..=CROSSING_SAMPLES).map(|i| if i == CROSSING_SAMPLES { hi } else { lo + h * i as f64 }).collect();
        let orders: Vec<Vec<f64>> =
            grid.iter().map(|&l| lens.orders(l, field).iter().map(order_defocus).collect()).collect();
        let count = orders.iter().map(Vec::len).max().unwrap_or(0);
        for k in 0..count {
            let w020 = |l: f64| order(l, k).map_or(f64::NAN, |o| order_defocus(&o));
            let mut cuts = vec![lo, hi];
            for target in [-limit_m, limit_m] {
                for (i, pair) in grid.windows(2).enumerate() {
                    let (Some(&w0), Some(&w1)) = (orders[i].get(k), orders[i + 1].get(k)) else { continue };
                    let (f0, f1) = (w0 - target, w1 - target);
                    if f0 * f1 < 0.0 {
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
            let table = crate::OtfTable::new(vec![800e-9], vec![0.0, 1e6], vec![vec![1.0, 0.0]], None).unwrap();
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

    #[test]
    fn illinois_converges_to_rounding() {
        let root = quad::illinois(&mut |x: f64| x * x * x - 2.0, 1.0, -1.0, 2.0, 6.0, 2e-14);
        assert!((root - 2f64.cbrt()).abs() < 1e-14, "{root}");
    }
}
