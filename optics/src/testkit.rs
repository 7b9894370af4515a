//! Conformance checks for [`LensModel`] implementations (feature `testkit`).
//!
//! [`check_lens`] is the check a downstream lens family calls from its tests (enable the
//! feature in its dev-dependencies: `optics = { …, features = ["testkit"] }`):
//!
//! ```text
//! optics::testkit::check_lens(&my_lens, &detected_spectrum)?;
//! ```
//!
//! It checks what the engine relies on and cannot check itself while it computes:
//!
//! - the description, on a grid of 33 wavelengths over the detected spectrum's extent (its
//!   one wavelength for a line), on axis and at one off-axis field point
//!   ([`OFF_AXIS_FIELD`]): [`orders_into`](LensModel::orders_into) appends what
//!   [`orders`](LensModel::orders) returns; every order's efficiency finite and ≥ 0; the sum of the
//!   efficiencies ≤ the transmission ≤ 1 (relative 1e-12; docs/physics.md, "Lens families":
//!   τ and T are fractions of the power incident on the full clear aperture, and the background
//!   `T − Σ τ` is ≥ 0); each order's efficiency ≤ its pupil's
//!   [`area_fraction`](crate::Pupil::area_fraction) (photon counts follow the pupil area: a
//!   10° sector cannot collect the light of the full lens); every wavefront coefficient and
//!   image shift finite, the zones' too, and every zone amplitude finite and ≥ 0;
//! - where the lens factors its tables out ([`LensModel::factored_efficiency`]), on the same
//!   grid and field points: the parts' relative orders, each efficiency times its part's table,
//!   are the lens's orders in some order, those of zero efficiency aside (efficiency within
//!   1e-12 relative, the same wavefront and image shift, the same kind of pupil); the
//!   transmission spectrum is the lens's transmission (1e-12); no part's relative lens has
//!   breakpoints at most of its table's rows (they would cut the spectral panels the fold
//!   exists to spare);
//! - the polychromatic MTF on axis (at [`CHECK_TOLERANCE`]): 1 at zero frequency, within
//!   `[0, 1]` and finite up to the cutoff of the shortest wavelength, and zero beyond it.
//!
//! The first violation is returned with the wavelength, field point, order and numbers involved.

use std::sync::Arc;

use radiometry::Spectrum;

use crate::fft::Aperture;
use crate::{Field, LensModel, Order, Polychromatic, Pupil, Wavefront};

/// Wavelengths of the description checks, evenly over the detected spectrum's extent.
pub const CHECK_WAVELENGTHS: usize = 33;

/// The off-axis field point of the description checks, radians: 5° along x and 2° along y (an
/// oblique field, so that a lens mixing up x and y shows).
pub const OFF_AXIS_FIELD: Field = Field { x_rad: 0.087_266_462_599_716_48, y_rad: 0.034_906_585_039_886_59 };

/// Relative tolerance of the polychromatic MTF whose invariants [`check_lens`] checks (they do
/// not depend on it: the engines' accuracy is tested against references elsewhere).
pub const CHECK_TOLERANCE: f64 = 1e-3;

/// Relative slack of the efficiency and transmission bounds (rounding of sums and products).
const RELATIVE_SLACK: f64 = 1e-12;

/// Checks the description and the transfer-function invariants of `lens` over the `detected`
/// spectrum (module docs). Returns a description of the first violation.
pub fn check_lens(lens: &dyn LensModel, detected: &Spectrum) -> Result<(), String> {
    let f_number = lens.f_number();
    if !(f_number.is_finite() && f_number > 0.0) {
        return Err(format!("f_number() = {f_number}: expected finite and > 0"));
    }
    check_description(lens, detected)?;
    check_factoring(lens, detected)?;
    let cutoff =
        crate::highest_cutoff(lens, detected).map_err(|e| format!("cannot prepare the polychromatic OTF: {e}"))?;
    // the invariants below hold at any accuracy of the engines (the OTF normalized at zero
    // frequency, a sampled autocorrelation's modulus within [0, 1], nothing past the cutoff): a
    // loose tolerance keeps the check of a 2-D pupil (the FFT path, its azimuths) to a second
    let settings = crate::Settings { tolerance: CHECK_TOLERANCE, ..crate::Settings::default() };
    let poly = Polychromatic::with_settings(lens, detected, Field::ON_AXIS, cutoff, None, settings)
        .map_err(|e| format!("cannot prepare the polychromatic OTF: {e}"))?;
    let at_zero = poly.mtf(0.0);
    if (at_zero - 1.0).abs() > 1e-12 {
        return Err(format!("MTF(0) = {at_zero}, expected 1"));
    }
    for k in 0..=50 {
        let nu = cutoff * k as f64 / 50.0;
        let m = poly.mtf(nu);
        if !m.is_finite() || !(-1e-12..=1.0 + 1e-12).contains(&m) {
            return Err(format!("MTF({nu:e} cycles/m) = {m}: expected finite, in [0, 1]"));
        }
    }
    for factor in [1.0 + 1e-9, 1.5, 4.0] {
        let m = poly.mtf(cutoff * factor);
        if m != 0.0 {
            return Err(format!("MTF = {m} at {factor} × the cutoff {cutoff:e} cycles/m: expected 0"));
        }
    }
    Ok(())
}

/// The factoring of `lens`'s tables, where it has one, against its own orders over the
/// `detected` spectrum's extent (module docs; part of [`check_lens`], alone for a lens whose
/// polychromatic checks cost more than a test should spend, a composite pupil on the FFT path).
pub fn check_factoring(lens: &dyn LensModel, detected: &Spectrum) -> Result<(), String> {
    let Some(factored) = lens.factored_efficiency() else { return Ok(()) };
    if factored.parts.is_empty() {
        return Err("factored_efficiency() has no parts: expected at least one".into());
    }
    for (p, part) in factored.parts.iter().enumerate() {
        let rows = part.table.breakpoints();
        let cut = part.relative.breakpoints().iter().filter(|b| rows.contains(b)).count();
        // (a few may coincide: a band edge of the relative lens on a row)
        if rows.len() > 4 && 2 * cut > rows.len() {
            return Err(format!(
                "factored part {p}: its relative lens has {cut} breakpoints at its table's {} rows: expected the table divided out",
                rows.len()
            ));
        }
    }
    let close = |a: f64, b: f64| (a - b).abs() <= RELATIVE_SLACK * a.abs().max(b.abs()) + 1e-300;
    for lambda in check_wavelengths(detected)? {
        let nm = lambda * 1e9;
        let t = factored.transmission.value(lambda);
        if !close(t, lens.transmission(lambda)) {
            return Err(format!(
                "at λ = {nm} nm: the factored transmission {t} differs from transmission() = {}",
                lens.transmission(lambda)
            ));
        }
        for field in [Field::ON_AXIS, OFF_AXIS_FIELD] {
            // (orders of zero efficiency aside: a part may keep an order where it carries no light)
            let whole: Vec<Order> = lens.orders(lambda, field).into_iter().filter(|o| o.efficiency != 0.0).collect();
            let mut parts = Vec::new();
            for part in &factored.parts {
                let table = part.table.value(lambda);
                let lit = part.relative.orders(lambda, field).into_iter().filter(|o| table * o.efficiency != 0.0);
                parts.extend(lit.map(|o| (table, o)));
            }
            if parts.len() != whole.len() {
                return Err(format!(
                    "at λ = {nm} nm, field {field:?}: the factored parts have {} orders, the lens {}",
                    parts.len(),
                    whole.len()
                ));
            }
            // each of the lens's orders matched to one of the parts' (in any order: a part may
            // gather orders that are not neighbours in the lens's list)
            let mut unused: Vec<(f64, Order)> = parts;
            for (k, order) in whole.iter().enumerate() {
                let same = |(table, part): &(f64, Order)| {
                    close(table * part.efficiency, order.efficiency)
                        && part.wavefront.defocus_m == order.wavefront.defocus_m
                        && part.wavefront.image_shift_m == order.wavefront.image_shift_m
                        && std::mem::discriminant(&part.pupil) == std::mem::discriminant(&order.pupil)
                };
                match unused.iter().position(same) {
                    Some(found) => {
                        unused.swap_remove(found);
                    }
                    None => {
                        let offered: Vec<String> = unused
                            .iter()
                            .map(|(t, o)| {
                                format!("(efficiency {}, W020 {} m)", t * o.efficiency, o.wavefront.defocus_m)
                            })
                            .collect();
                        return Err(format!(
                            "at λ = {nm} nm, field {field:?}, order {k}: the lens's order (efficiency {}, W020 {} m, shift {:?} m) is not among the factored parts' orders through the same kind of pupil (each its table × its efficiency: {})",
                            order.efficiency,
                            order.wavefront.defocus_m,
                            order.wavefront.image_shift_m,
                            offered.join(", ")
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

/// The wavelengths the description is checked at: [`CHECK_WAVELENGTHS`] over the spectral
/// extent the engine integrates, or the line's one wavelength.
fn check_wavelengths(detected: &Spectrum) -> Result<Vec<f64>, String> {
    if let Some(line) = detected.as_line() {
        return Ok(vec![line.wavelength_m]);
    }
    let (lo, hi) =
        crate::poly::spectral_extent(detected).map_err(|e| format!("cannot find the spectrum's extent: {e}"))?;
    let lo = if lo > 0.0 { lo } else { 1e-3 * hi };
    Ok((0..CHECK_WAVELENGTHS).map(|k| lo + (hi - lo) * k as f64 / (CHECK_WAVELENGTHS - 1) as f64).collect())
}

/// The area fractions of the apertures seen so far (a mask's is measured on a 512² grid: once).
#[derive(Default)]
struct Areas(Vec<(Arc<Aperture>, f64)>);

impl Areas {
    fn of(&mut self, aperture: &Arc<Aperture>) -> f64 {
        if let Some((_, a)) = self.0.iter().find(|(k, _)| Arc::ptr_eq(k, aperture)) {
            return *a;
        }
        let a = aperture.area_fraction();
        self.0.push((aperture.clone(), a));
        a
    }

    /// [`Pupil::area_fraction`], with the apertures' areas cached.
    fn pupil(&mut self, pupil: &Pupil) -> f64 {
        match pupil {
            Pupil::Aperture(a) => self.of(a),
            Pupil::Zones(zones) => zones.iter().map(|z| z.amplitude * z.amplitude * self.of(&z.aperture)).sum(),
            other => other.area_fraction(),
        }
    }
}

fn check_description(lens: &dyn LensModel, detected: &Spectrum) -> Result<(), String> {
    let mut areas = Areas::default();
    for lambda in check_wavelengths(detected)? {
        let nm = lambda * 1e9;
        let transmission = lens.transmission(lambda);
        // a pupil larger than the full circle (a square of side D: 4/π) collects more light
        let largest = lens.orders(lambda, Field::ON_AXIS).iter().map(|o| areas.pupil(&o.pupil)).fold(1.0, f64::max);
        if !(transmission.is_finite() && (0.0..=largest * (1.0 + RELATIVE_SLACK)).contains(&transmission)) {
            return Err(format!(
                "at λ = {nm} nm: transmission() = {transmission}, expected finite, in [0, 1] (in [0, a] for a pupil of area fraction a > 1)"
            ));
        }
        for field in [Field::ON_AXIS, OFF_AXIS_FIELD] {
            let at = format!("at λ = {nm} nm, field ({}, {}) rad", field.x_rad, field.y_rad);
            let orders = lens.orders(lambda, field);
            // `orders_into` appends the same orders (twice into one buffer: appended, not replaced)
            let mut buffer = Vec::new();
            lens.orders_into(lambda, field, &mut buffer);
            lens.orders_into(lambda, field, &mut buffer);
            let twice: Vec<&Order> = orders.iter().chain(&orders).collect();
            if format!("{:?}", buffer.iter().collect::<Vec<_>>()) != format!("{twice:?}") {
                return Err(format!(
                    "{at}: orders_into appended {} orders twice, not what orders() returns twice ({:?}, expected {:?})",
                    buffer.len() / 2,
                    buffer,
                    orders
                ));
            }
            let count = orders.len();
            let mut sum = 0.0;
            for (k, order) in orders.iter().enumerate() {
                let which = format!("{at}, order {} of {count}", k + 1);
                check_order(order, &which, &mut areas)?;
                sum += order.efficiency;
            }
            if sum > transmission * (1.0 + RELATIVE_SLACK) {
                return Err(format!(
                    "{at}: the orders' efficiencies sum to {sum}, more than the transmission {transmission} \
                     (τ and T are fractions of the light on the full aperture, docs/physics.md \"Lens families\")"
                ));
            }
        }
    }
    Ok(())
}

fn check_order(order: &Order, which: &str, areas: &mut Areas) -> Result<(), String> {
    let eta = order.efficiency;
    if !(eta.is_finite() && eta >= 0.0) {
        return Err(format!("{which}: efficiency {eta}, expected finite and ≥ 0"));
    }
    check_wavefront(&order.wavefront, which)?;
    if let Pupil::Zones(zones) = &order.pupil {
        for (j, zone) in zones.iter().enumerate() {
            let zone_which = format!("{which}, zone {} of {}", j + 1, zones.len());
            if !(zone.amplitude.is_finite() && zone.amplitude >= 0.0) {
                return Err(format!("{zone_which}: amplitude {}, expected finite and ≥ 0", zone.amplitude));
            }
            check_wavefront(&zone.wavefront, &zone_which)?;
        }
    }
    let area = areas.pupil(&order.pupil);
    if eta > area * (1.0 + RELATIVE_SLACK) {
        return Err(format!(
            "{which}: efficiency {eta} exceeds its pupil's area fraction {area} (photon counts follow the \
             pupil area: put the area in the efficiency, docs/physics.md \"Lens families\")"
        ));
    }
    Ok(())
}

fn check_wavefront(w: &Wavefront, which: &str) -> Result<(), String> {
    let terms = [
        ("defocus_m", w.defocus_m),
        ("image_shift_m[0]", w.image_shift_m[0]),
        ("image_shift_m[1]", w.image_shift_m[1]),
        ("spherical_m", w.spherical_m),
        ("coma_m", w.coma_m),
        ("astigmatism_m", w.astigmatism_m),
        ("field_curvature_m", w.field_curvature_m),
    ];
    match terms.iter().find(|(_, v)| !v.is_finite()) {
        Some((name, v)) => Err(format!("{which}: wavefront {name} = {v}, expected finite")),
        None => Ok(()),
    }
}

/// `(1/to) ∫_0^to f(ν) dν` by composite Simpson's rule on 2000 intervals: the plain, independent
/// mean a test holds an engine's mean MTF against (its integrands are smooth on `[0, to]`).
pub fn simpson_mean(to: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    const INTERVALS: u32 = 2000;
    let h = to / f64::from(INTERVALS);
    let sum: f64 = (0..=INTERVALS)
        .map(|i| {
            let w = if i == 0 || i == INTERVALS {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * f(f64::from(i) * h)
        })
        .sum();
    sum * h / 3.0 / to
}

#[cfg(test)]
mod tests {
    use std::f64::consts::TAU;

    use radiometry::{Gaussian, Spectrum};

    use super::*;
    use crate::Zone;

    fn band() -> Spectrum {
        Spectrum::Gaussian(Gaussian::new(800e-9, 10e-9, 1.0).unwrap())
    }

    /// A lens whose orders are given by a closure of (λ, field); transmission `t`.
    struct Described<F> {
        orders: F,
        transmission: f64,
    }

    impl<F> std::fmt::Debug for Described<F> {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("Described")
        }
    }

    impl<F: Fn(f64, Field) -> Vec<Order> + Send + Sync> LensModel for Described<F> {
        fn f_number(&self) -> f64 {
            2.5
        }
        fn focal_length(&self) -> f64 {
            3.36e-3
        }
        fn orders(&self, lambda: f64, field: Field) -> Vec<Order> {
            (self.orders)(lambda, field)
        }
        fn transmission(&self, _: f64) -> f64 {
            self.transmission
        }
    }

    fn lens<F: Fn(f64, Field) -> Vec<Order> + Send + Sync>(transmission: f64, orders: F) -> Described<F> {
        Described { orders, transmission }
    }

    fn fails_with(lens: &dyn LensModel, words: &[&str]) {
        let e = check_lens(lens, &band()).expect_err("the check must fail");
        for w in words {
            assert!(e.contains(w), "{e:?} should name {w:?}");
        }
    }

    fn sector(degrees: f64) -> Arc<Aperture> {
        Arc::new(Aperture::sector(0.0, degrees.to_radians()).unwrap())
    }

    #[test]
    fn a_sound_lens_passes() {
        // a segmented lens: three sectors with their area in the efficiency, and an order
        // through a 10° sector with 1/36 of the light
        let thirds: Vec<Arc<Aperture>> = (0..3)
            .map(|j| Arc::new(Aperture::sector(j as f64 * TAU / 3.0, (j + 1) as f64 * TAU / 3.0).unwrap()))
            .collect();
        let small = sector(10.0);
        let good = lens(0.95, move |lambda, _| {
            let zones: Vec<Zone> = thirds
                .iter()
                .enumerate()
                .map(|(j, a)| Zone::new(a.clone(), 0.8f64.sqrt(), Wavefront::defocus((j as f64 - 1.0) * 1e-7)))
                .collect();
            vec![
                Order::new(0.8 * 0.9, Pupil::Zones(Arc::from(zones)), Wavefront::defocus(1e-7 * (lambda / 800e-9))),
                Order::new(0.1 / 36.0, Pupil::Aperture(small.clone()), Wavefront::defocus(0.0)),
            ]
        });
        check_lens(&good, &band()).unwrap();
    }

    #[test]
    fn a_negative_or_nan_efficiency_fails() {
        let negative = lens(0.9, |lambda, _| {
            let eta = if lambda > 810e-9 { -0.1 } else { 0.5 };
            vec![Order::new(eta, Pupil::Full, Wavefront::default())]
        });
        fails_with(&negative, &["efficiency -0.1", "order 1 of 1", "λ = 8"]);
        let nan = lens(0.9, |_, field: Field| {
            let eta = if field.is_on_axis() { 0.5 } else { f64::NAN };
            vec![Order::new(0.1, Pupil::Full, Wavefront::default()), Order::new(eta, Pupil::Full, Wavefront::default())]
        });
        fails_with(&nan, &["efficiency NaN", "order 2 of 2", "field (0.08"]);
    }

    #[test]
    fn efficiencies_above_the_transmission_or_a_transmission_above_one_fail() {
        let over = lens(0.5, |_, _| {
            vec![Order::new(0.3, Pupil::Full, Wavefront::default()), Order::new(0.3, Pupil::Full, Wavefront::default())]
        });
        fails_with(&over, &["sum to 0.6", "transmission 0.5"]);
        let above_one = lens(1.2, |_, _| vec![Order::new(0.5, Pupil::Full, Wavefront::default())]);
        fails_with(&above_one, &["transmission() = 1.2"]);
    }

    #[test]
    fn an_efficiency_above_the_pupil_area_fails() {
        // a 10° sector that collects the full lens's light
        let a = sector(10.0);
        let greedy = lens(0.9, move |_, _| vec![Order::new(0.8, Pupil::Aperture(a.clone()), Wavefront::default())]);
        fails_with(&greedy, &["efficiency 0.8", "area fraction 0.0277"]);
        // zones: the efficiency above Σ amplitude² × area
        let a = sector(90.0);
        let zoned = lens(0.9, move |_, _| {
            let zones: Arc<[Zone]> = Arc::from(vec![Zone::new(a.clone(), 1.0, Wavefront::default())]);
            vec![Order::new(0.5, Pupil::Zones(zones), Wavefront::default())]
        });
        fails_with(&zoned, &["efficiency 0.5", "area fraction 0.25"]);
    }

    #[test]
    fn a_non_finite_wavefront_fails() {
        let tilted = lens(0.9, |_, field: Field| {
            let shift = if field.is_on_axis() { 0.0 } else { f64::INFINITY };
            vec![Order::new(0.5, Pupil::Full, Wavefront::defocus(1e-7).shifted(0.0, shift))]
        });
        fails_with(&tilted, &["image_shift_m[1] = inf"]);
        let coma = lens(0.9, |_, _| {
            vec![Order::new(0.5, Pupil::Full, Wavefront { coma_m: f64::NAN, ..Wavefront::default() })]
        });
        fails_with(&coma, &["coma_m = NaN"]);
    }

    #[test]
    fn a_bad_zone_fails() {
        let a = sector(180.0);
        let b = sector(90.0);
        let negative = lens(0.9, move |_, _| {
            let zones =
                vec![Zone::new(a.clone(), 0.5, Wavefront::default()), Zone::new(a.clone(), -0.5, Wavefront::default())];
            vec![Order::new(0.1, Pupil::Zones(Arc::from(zones)), Wavefront::default())]
        });
        fails_with(&negative, &["zone 2 of 2", "amplitude -0.5"]);
        let nan = lens(0.9, move |_, _| {
            let zones = vec![Zone::new(b.clone(), f64::NAN, Wavefront::default())];
            vec![Order::new(0.1, Pupil::Zones(Arc::from(zones)), Wavefront::default())]
        });
        fails_with(&nan, &["zone 1 of 1", "amplitude NaN"]);
        let c = sector(90.0);
        let defocus = lens(0.9, move |_, _| {
            let zones = vec![Zone::new(c.clone(), 0.5, Wavefront::defocus(f64::NAN))];
            vec![Order::new(0.01, Pupil::Zones(Arc::from(zones)), Wavefront::default())]
        });
        fails_with(&defocus, &["zone 1 of 1", "defocus_m = NaN"]);
    }
}
