//! The conformance check every `LensModel` should pass, and the comparison the crate prints.

use std::sync::Arc;

use custom_lens::{BK7_CAUCHY, HybridAchromat, paper_scene};
use lenses::{ChromaticMetalens, Curve};
use optics::LensModel;
use radiometry::{Gaussian, Spectrum};

#[test]
fn passes_the_lens_model_conformance_check() {
    let lens = HybridAchromat::new(2.5, 3.36e-3, 800e-9, BK7_CAUCHY).unwrap();
    for range_nm in [10.0, 50.0, 100.0] {
        let detected = Spectrum::Gaussian(Gaussian::from_range(800e-9, range_nm * 1e-9, 1.0).unwrap());
        optics::testkit::check_lens(&lens, &detected).unwrap_or_else(|e| panic!("{range_nm} nm: {e}"));
    }
}

/// Against its chromatic twin (same aperture, focal length and efficiency at λ0) the achromat
/// wins at every band, and by more as the band widens (the twin's defocus grows with the
/// band, the achromat's only with its square).
#[test]
fn beats_its_chromatic_twin_by_more_as_the_band_widens() {
    let hybrid = HybridAchromat::new(2.5, 3.36e-3, 800e-9, BK7_CAUCHY).unwrap();
    let (tau, t) = (hybrid.efficiency(800e-9), hybrid.transmission(800e-9));
    let twin = ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(tau), Curve::Constant(t)).unwrap();
    let (hybrid, twin): (Arc<dyn LensModel>, Arc<dyn LensModel>) = (Arc::new(hybrid), Arc::new(twin));
    let mut last_ratio = 0.0;
    for range_nm in [10.0, 50.0, 200.0] {
        let a = metric::evaluate(&paper_scene(hybrid.clone(), range_nm * 1e-9).unwrap()).unwrap();
        let b = metric::evaluate(&paper_scene(twin.clone(), range_nm * 1e-9).unwrap()).unwrap();
        let ratio = a.asnr / b.asnr;
        assert!(ratio > 1.0 && ratio > last_ratio, "{range_nm} nm: {} vs {}", a.asnr, b.asnr);
        last_ratio = ratio;
    }
}
