//! A line spectrum through a lens with two imaging orders: one node per order, no spectral
//! panels, and the OTF the efficiency-weighted complex sum of the orders' exact OTFs.

use std::f64::consts::PI;

use num_complex::Complex64;
use optics::{Engine, Field, LensModel, Order, Polychromatic, Pupil, Wavefront, defocus_otf};
use radiometry::{Line, Spectrum};

/// Two orders at every wavelength: τ = 0.3 with 1 µm of defocus and its image 2 µm along x,
/// τ = 0.1 with −3 µm of defocus, centred. F/2, so NA = 0.25.
#[derive(Debug)]
struct TwoOrders;

const SHIFT: f64 = 2e-6;

impl LensModel for TwoOrders {
    fn f_number(&self) -> f64 {
        2.0
    }
    fn focal_length(&self) -> f64 {
        5e-3
    }
    fn orders(&self, _: f64, _: Field) -> Vec<Order> {
        vec![
            Order::new(0.3, Pupil::Full, Wavefront::defocus(1e-6).shifted(SHIFT, 0.0)),
            Order::new(0.1, Pupil::Full, Wavefront::defocus(-3e-6)),
        ]
    }
}

fn line_spectrum(peak: f64) -> Spectrum {
    Spectrum::product(vec![Spectrum::Line(Line::new(700e-9, 5e-9, peak).unwrap()), Spectrum::Linear { slope: 1.0 }])
}

#[test]
fn two_orders_at_one_wavelength() {
    let spectrum = line_spectrum(1.0);
    let lambda = 700e-9;
    let cutoff = 1.0 / (lambda * 2.0);
    let poly = Polychromatic::new(&TwoOrders, &spectrum, Field::ON_AXIS, 0.8 * cutoff, None).unwrap();
    assert_eq!(poly.engine(), Engine::Monochromatic { fft: None });
    assert!(poly.direction_dependent());
    // weight: 5 nm × 700 nm × (0.3 + 0.1)
    let weight = 5e-9 * 700e-9 * 0.4;
    assert!((poly.total_weight() - weight).abs() < 1e-15 * weight);
    assert_eq!(poly.max_cutoff(), cutoff);
    assert_eq!(optics::highest_cutoff(&TwoOrders, &spectrum).unwrap(), cutoff);
    for k in 1..20 {
        let nu = cutoff * f64::from(k) / 20.0;
        for azimuth in [0.0, 0.7, 0.5 * PI] {
            let s = nu * lambda * 2.0;
            let phase = -2.0 * PI * nu * SHIFT * f64::cos(azimuth);
            let direct = (Complex64::from_polar(0.3 * defocus_otf(s, 1e-6 / lambda), phase)
                + 0.1 * defocus_otf(s, -3e-6 / lambda))
                / 0.4;
            let got = poly.otf_along(nu, azimuth);
            assert!((got - direct).norm() < 1e-15, "ν = {nu}, azimuth {azimuth}: {got} vs {direct}");
        }
        let mono = optics::monochromatic_mtf(&TwoOrders, lambda, Field::ON_AXIS, &[nu], 64).unwrap()[0];
        assert!((poly.mtf_along(nu, 0.0) - mono).abs() < 1e-15, "{nu}");
    }
    assert_eq!(poly.otf_along(1.0001 * cutoff, 0.3), Complex64::new(0.0, 0.0));
    let (_, work) = poly.mean_mtf_along(0.0);
    assert_eq!((work.spectral_nodes, work.spectral_panels), (2, 0));
    // blur radius 2|W020|/NA: 8 µm and 24 µm; a 16 µm limit leaves the second order's 0.1/0.4 beyond
    assert!((poly.fraction_blurred_beyond(16e-6) - 0.25).abs() < 1e-15);
    assert_eq!(poly.fraction_blurred_beyond(4e-6), 1.0);
    assert_eq!(poly.fraction_blurred_beyond(30e-6), 0.0);
    assert!((poly.spectral_average(|l, _| l) - lambda).abs() < 1e-15 * lambda);
}

#[test]
fn a_dark_line_is_an_error_not_nan() {
    let spectrum = line_spectrum(0.0);
    let err = Polychromatic::new(&TwoOrders, &spectrum, Field::ON_AXIS, 1e5, None).unwrap_err();
    assert!(err.to_string().contains("no detected signal"), "{err}");
}
