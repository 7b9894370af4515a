//! The built-in lens families pass the `optics::testkit` conformance checks.

use lenses::{ChromaticMetalens, Curve};
use optics::testkit::check_lens;
use radiometry::{Gaussian, Sampled, Spectrum};

fn band(centre_nm: f64, range_nm: f64) -> Spectrum {
    Spectrum::product(vec![
        Spectrum::Gaussian(Gaussian::from_range(centre_nm * 1e-9, range_nm * 1e-9, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ])
}

#[test]
fn chromatic_metalens_conforms() {
    for f_number in [1.4, 2.5, 5.0] {
        let lens =
            ChromaticMetalens::new(f_number, 3.36e-3, 800e-9, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
        for (c, r) in [(800.0, 1.0), (800.0, 50.0), (850.0, 20.0)] {
            check_lens(&lens, &band(c, r)).unwrap_or_else(|e| panic!("F/{f_number}, {c} nm ± {r} nm: {e}"));
        }
    }
}

#[test]
fn tabulated_efficiency_conforms() {
    let eff = Sampled::new(vec![700e-9, 800e-9, 900e-9], vec![0.05, 0.15, 0.08]).unwrap();
    let lens = ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Table(eff), Curve::Constant(0.55)).unwrap();
    check_lens(&lens, &band(800.0, 100.0)).unwrap();
}

#[test]
fn conformance_check_catches_a_broken_lens() {
    // a lens that claims an efficiency but reports a NaN defocus must fail the check
    #[derive(Debug)]
    struct Broken;
    impl optics::LensModel for Broken {
        fn f_number(&self) -> f64 {
            2.0
        }
        fn focal_length(&self) -> f64 {
            1e-2
        }
        fn orders(&self, _: f64, _: optics::Field) -> Vec<optics::Order> {
            vec![optics::Order::new(0.5, optics::Pupil::Full, optics::Wavefront::defocus(f64::NAN))]
        }
    }
    assert!(check_lens(&Broken, &band(800.0, 10.0)).is_err());
}
