//! Photon counts follow the pupil (docs/physics.md, "Lens families"): a sector or an
//! obscuration scales the efficiency, and the metric's photoelectrons, by its area.

use std::sync::Arc;

use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, Options, Scene, evaluate};
use optics::LensModel;
use optics::fft::Aperture;
use radiometry::{Gaussian, Spectrum};

use crate::{F_NUMBER, F0, LAMBDA0};

fn scene(lens: ChromaticMetalens) -> Scene {
    let filter = Gaussian::from_range(LAMBDA0, 10e-9, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(5.2e-6, Spectrum::Constant(0.2), false).unwrap();
    let options = Options { pupil_samples: Some(64), ..Options::default() };
    Scene::new(Arc::new(lens), radiance, camera, 1.23e-3, options).unwrap()
}

/// A 90° sector collects a quarter of the light, an annulus of obscuration 0.5 three quarters,
/// a 10° sector 1/36, a decentred iris of full size all of it: in the lens' efficiency and
/// transmission and in the metric's signal and transmitted photoelectrons (to the spectral quadrature's rounding, measured 3e-12).
#[test]
fn a_sector_or_an_obscuration_scales_the_photon_count_by_its_area() {
    let lens = || ChromaticMetalens::new(F_NUMBER, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
    let full = evaluate(&scene(lens())).unwrap();
    let cases = [
        ("90° sector", Aperture::sector(0.0, std::f64::consts::FRAC_PI_2).unwrap(), 0.25),
        ("10° sector", Aperture::sector(0.3, 0.3 + 10f64.to_radians()).unwrap(), 1.0 / 36.0),
        ("annulus 0.5", Aperture::annulus(0.5).unwrap(), 0.75),
        ("decentred iris", Aperture::circle().decentred(0.1, 0.0).unwrap(), 1.0),
    ];
    for (name, aperture, area) in cases {
        let stopped = lens().with_aperture(aperture);
        assert!((stopped.efficiency(LAMBDA0) - 0.15 * area).abs() < 1e-15, "{name}");
        assert!((stopped.transmission(LAMBDA0) - 0.55 * area).abs() < 1e-15, "{name}");
        let e = evaluate(&scene(stopped)).unwrap();
        let ratio = e.photoelectrons / full.photoelectrons;
        let transmitted = e.transmitted_photoelectrons / full.transmitted_photoelectrons;
        eprintln!("{name}: photoelectrons × {ratio:.6} (area {area:.6}), mean MTF {:.4}", e.mean_mtf);
        assert!((ratio - area).abs() < 1e-10 * area, "{name}: {ratio} vs {area}");
        assert!((transmitted - area).abs() < 1e-10 * area, "{name}: {transmitted} vs {area}");
    }
}
