//! The refractive reference never loses to a metalens of equal aperture and efficiency, and
//! every family passes the conformance checks.

use std::sync::Arc;

use lenses::{ChromaticMetalens, Curve, Glass, Harmonic, Refractive, Surfaces, preset, preset_names};
use metric::{Camera, Options, Scene, evaluate};
use optics::fft::Aperture;
use optics::testkit::check_lens;
use proptest::prelude::*;
use radiometry::{Gaussian, Spectrum};

use crate::{F_NUMBER, F0, LAMBDA0, band};

fn scene(lens: Arc<dyn optics::LensModel>, centre_m: f64, range_m: f64) -> Scene {
    let filter = Gaussian::from_range(centre_m, range_m, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(3e-6, Spectrum::Constant(0.5), true).unwrap();
    Scene::new(lens, radiance, camera, 1.23e-3, Options::default()).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// A dispersion-free refractive lens with `τ = T = η` (one element, AR reflectance
    /// `R = 1 − √η` per surface) against a chromatic metalens with `τ1 = T = η` of the same
    /// F-number and focal length: equal photons, and the refractive lens is diffraction limited
    /// at every wavelength, so its mean MTF and ASNR are at least the metalens's, over F/1.5 to
    /// F/10, bands of 1 to 300 nm centred at 450 to 1000 nm, the metalens designed anywhere in
    /// the band.
    #[test]
    fn refractive_reference_never_loses_to_a_metalens_of_equal_efficiency(
        f_number in 1.5f64..10.0,
        centre_nm in 450.0f64..1000.0,
        range_nm in 1.0f64..300.0,
        design_offset in -0.5f64..0.5,
        eta in 0.05f64..0.95,
    ) {
        let (centre, range) = (centre_nm * 1e-9, range_nm * 1e-9);
        let design = centre + design_offset * range;
        let reflectance = 1.0 - eta.sqrt();
        let refractive =
            Refractive::new(f_number, F0, design, Glass::Constant(1.5), 1, Surfaces::Coated(reflectance)).unwrap();
        let metalens = ChromaticMetalens::new(f_number, F0, design, Curve::Constant(eta), Curve::Constant(eta)).unwrap();
        let r = evaluate(&scene(Arc::new(refractive), centre, range)).unwrap();
        let m = evaluate(&scene(Arc::new(metalens), centre, range)).unwrap();
        prop_assert!((r.photoelectrons - m.photoelectrons).abs() <= 1e-9 * m.photoelectrons);
        // the tolerance of each mean MTF (1e-6 relative)
        prop_assert!(r.mean_mtf >= m.mean_mtf * (1.0 - 2e-6), "F/{f_number}: {} vs {}", r.mean_mtf, m.mean_mtf);
        prop_assert!(r.asnr >= m.asnr * (1.0 - 2e-6), "F/{f_number}: {} vs {}", r.asnr, m.asnr);
    }
}

/// The families not checked elsewhere: the harmonic lens, the chromatic lens through a sector,
/// and the presets over their bands.
#[test]
fn harmonic_stopped_and_preset_lenses_conform() {
    let harmonic = Harmonic::new(F_NUMBER, F0, LAMBDA0, 2, 0.5, Curve::Constant(0.8)).unwrap();
    check_lens(&harmonic, &band(800.0, 1.0)).unwrap();
    check_lens(&harmonic, &band(600.0, 10.0)).unwrap();
    let sector = ChromaticMetalens::new(F_NUMBER, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55))
        .unwrap()
        .with_aperture(Aperture::sector(0.0, 1.0).unwrap());
    check_lens(&sector, &band(800.0, 2.0)).unwrap();
    for (name, centre) in [
        ("paper-chromatic", 800.0),
        ("chen2019", 580.0),
        ("wang2018", 530.0),
        ("ndao2020-reduced", 900.0),
        ("n-bk7-singlet", 800.0),
    ] {
        assert!(preset_names().contains(&name));
        let lens = preset(name).unwrap();
        check_lens(lens.as_ref(), &band(centre, 20.0)).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}
