//! The fast OTF paths against identities, each other and the reference, and the polychromatic
//! engine's invariants on physical ranges (property tests with a fixed seed).

use std::f64::consts::PI;

use optics::{
    Field, LensModel, Order, Polychromatic, Pupil, Wavefront, defocus_otf, defocus_otf_bessel, defocus_otf_quadrature,
    mtf_diffraction_limited, quad, reference,
};
use proptest::prelude::*;
use radiometry::{Gaussian, Spectrum};

/// `2 ∫_0^1 OTF(s, w) s ds`, with `s = 1 − u²` to remove the `(1 − s)^{3/2}` edge.
fn strehl_quarter(w: f64) -> f64 {
    2.0 * quad::composite(0.0, 1.0, 64, |u| {
        let s = 1.0 - u * u;
        defocus_otf(s, w) * s * 2.0 * u
    })
}

/// docs/physics.md identities: ∫_0^1 MTF_0 ds = 4/(3π) and 2 ∫_0^1 OTF(s, w) s ds = Strehl/4 with
/// Strehl = [sin(πw)/(πw)]² for pure defocus, to 1e-9. docs/physics.md quotes the identity's value,
/// Strehl/4: w = 0.25 → 0.20264, w = 0.5 → 0.10132.
#[test]
fn identities_hold_to_1e9() {
    let area = quad::composite(0.0, 1.0, 64, |u| mtf_diffraction_limited(1.0 - u * u) * 2.0 * u);
    assert!((area - 4.0 / (3.0 * PI)).abs() < 1e-9, "{area}");
    for w in [0.25_f64, 0.5, 1.0, 3.0] {
        let strehl = ((PI * w).sin() / (PI * w)).powi(2);
        let got = strehl_quarter(w);
        assert!((got - strehl / 4.0).abs() < 1e-9, "w = {w}: {got} vs {}", strehl / 4.0);
    }
    assert!((strehl_quarter(0.25) - 0.20264).abs() < 1e-5);
    assert!((strehl_quarter(0.5) - 0.10132).abs() < 1e-5);
}

/// The fast OTF against the independent reference (printed y-form, adaptive Gauss–Kronrod).
#[test]
fn fast_otf_matches_the_reference() {
    let mut worst: f64 = 0.0;
    for &w in &[0.0, 0.1, 0.5, 1.0, 2.0, 5.0, 20.0, 80.0] {
        for i in 1..40 {
            let s = i as f64 / 40.0;
            worst = worst.max((defocus_otf(s, w) - reference::otf_defocus(s, w)).abs());
        }
    }
    assert!(worst < 1e-10, "largest difference {worst:e}");
}

/// Geometric limit (docs/physics.md): for large defocus OTF → 2 J1(x)/x, x = π d ν, with the blur
/// diameter d = 2|Δz| NA. In normalized units x = 8π w s... precisely: Δz = 8 F#² W020,
/// d ν = 2 · 8 F#² W020 / (2 F#) · s/(λ F#) = 8 w s, so x = 8π w s = a.
#[test]
fn geometric_limit_at_large_defocus() {
    let w = 200.0;
    for s in [0.002, 0.005, 0.01] {
        let geometric = reference::otf_geometric(s, w);
        let exact = defocus_otf(s, w);
        assert!((exact - geometric).abs() < 0.02, "s = {s}: {exact} vs {geometric}");
    }
}

#[derive(Debug)]
struct Chromatic {
    f_number: f64,
}

impl LensModel for Chromatic {
    fn f_number(&self) -> f64 {
        self.f_number
    }
    fn focal_length(&self) -> f64 {
        3.36e-3
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        // W020 = (1 − λ/λ0) f0/(8 F#²) (docs/physics.md, "Sign of the wavefront")
        let w020 = (1.0 - lambda / 800e-9) * 3.36e-3 / (8.0 * self.f_number * self.f_number);
        vec![Order::new(0.15, Pupil::Full, Wavefront::defocus(w020))]
    }
}

fn band(centre: f64, range: f64) -> Spectrum {
    Spectrum::product(vec![
        Spectrum::Gaussian(Gaussian::from_range(centre, range, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ])
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(20261122), ..ProptestConfig::default() })]

    /// The two monochromatic evaluations agree, and the OTF is bounded and even in defocus.
    #[test]
    fn otf_paths_agree(s in 0.001f64..0.999, w in 0.0f64..400.0) {
        let q = defocus_otf_quadrature(s, w);
        prop_assert!(q.abs() <= 1.0 + 1e-14);
        prop_assert!((defocus_otf(s, w) - defocus_otf(s, -w)).abs() < 1e-15);
        let a = 8.0 * PI * w * s;
        if a >= 1.0 {
            prop_assert!((defocus_otf_bessel(s, a) - q).abs() < 1e-12);
        }
    }

    /// 0 ≤ MTF ≤ MTF(0) = 1, and zero past the cutoff of the shortest wavelength.
    #[test]
    fn polychromatic_mtf_is_bounded(f in 1.4f64..5.0, range_nm in 1.0f64..200.0, centre_nm in 700.0f64..900.0, frac in 0.0f64..1.0) {
        let lens = Chromatic { f_number: f };
        let spectrum = band(centre_nm * 1e-9, range_nm * 1e-9);
        let poly = Polychromatic::new(&lens, &spectrum, Field::ON_AXIS, 1e5, None).unwrap();
        prop_assert!((poly.mtf(0.0) - 1.0).abs() < 1e-12);
        let m = poly.mtf(frac * 1e5);
        prop_assert!(m.is_finite() && (0.0..=1.0 + 1e-12).contains(&m));
        prop_assert_eq!(poly.mtf(poly.max_cutoff() * 1.001), 0.0);
    }

    /// As the range shrinks the polychromatic OTF becomes the monochromatic one at the centre.
    #[test]
    fn narrow_band_is_monochromatic(f in 1.4f64..5.0, centre_nm in 750.0f64..850.0, frac in 0.0f64..0.9) {
        let lens = Chromatic { f_number: f };
        let centre = centre_nm * 1e-9;
        let spectrum = band(centre, 1e-13);
        let nu = frac / (centre * f);
        let poly = Polychromatic::new(&lens, &spectrum, Field::ON_AXIS, 1e5, None).unwrap();
        let w020 = (1.0 - centre / 800e-9) * 3.36e-3 / (8.0 * f * f);
        let mono = defocus_otf(nu * centre * f, w020 / centre);
        prop_assert!((poly.otf(nu) - mono).abs() < 1e-6, "{} vs {}", poly.otf(nu), mono);
    }
}

/// Hopkins' 1955 Bessel series (libm Bessel functions) against the fast path: a third
/// independent evaluation of the same OTF.
#[test]
fn hopkins_series_agrees_with_the_fast_path() {
    let mut worst: f64 = 0.0;
    for &w in &[0.05, 0.25, 1.0, 3.0, 12.0, 60.0] {
        for i in 1..50 {
            let s = i as f64 / 50.0;
            worst = worst.max((reference::otf_hopkins(s, w) - defocus_otf(s, w)).abs());
        }
    }
    assert!(worst < 1e-11, "largest difference {worst:e}");
    for (s, w, expected) in reference::PHYSICS_TEST_VECTORS {
        assert!((reference::otf_hopkins(s, w) - expected).abs() < 1e-5, "({s}, {w})");
    }
}
