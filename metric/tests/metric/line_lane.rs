//! A line's wavelength on the value's own pass (docs/physics.md, "Gradients: a line's wavelength
//! and a blackbody's temperature"): the line engine reads each OTF value from the value's own
//! forms with the defocus lane `w ∂H/∂w` (one order) or the order lane (the harmonic lens's
//! orders, each with its own `∂ln w_o/∂λ` and `∂τ_o/∂λ`) beside it, so the evaluation a gradient
//! carries is the evaluation itself, bit for bit.

use metric::Parameter;

/// The paper's scene with `model` in place of its chromatic lens's model, efficiency and
/// transmission lines (none: the paper's lens), and `set` (also the design lane's scenes).
pub(crate) fn scene_with(model: Option<&str>, set: &[&str]) -> metric::Scene {
    let paper = scene::read(None).unwrap();
    let text = match model {
        None => paper.text().to_owned(),
        Some(model) => {
            let lines: Vec<&str> = paper
                .text()
                .lines()
                .filter(|l| !(l.starts_with("efficiency") || l.starts_with("transmission")))
                .collect();
            lines.join("\n").replace("model = \"chromatic\"", model)
        }
    };
    let source = scene::Source::from_text(text, "scene written in the test", ".");
    let set: Vec<String> = set.iter().map(|s| (*s).to_owned()).collect();
    scene::build_from(&source, &set).unwrap()
}

/// The evaluation of a gradient with respect to a line's wavelength (alone, with the F-number,
/// and the F-number alone) equal to `metric::evaluate` (every number, the work included), on the
/// paper's lens (one order, the defocus lane) and the harmonic lens of design order 5 (six
/// orders, the order lane), plain and with the pixel MTF, read noise and the stray light.
#[test]
fn the_evaluation_with_the_line_lane_is_the_evaluation() {
    let harmonic = "model = \"harmonic\"\ndesign_order = 5\nefficiency = 0.15\ntransmission = 0.55";
    let line = ["spectrum.shape=\"line\"", "spectrum.center_nm=803", "spectrum.range_nm=1"];
    let extra = ["camera.pixel_mtf=true", "camera.read_noise_e=2", "options.glare=\"included\""];
    for model in [None, Some(harmonic)] {
        for with in [&[][..], &extra[..]] {
            let set: Vec<&str> = line.iter().chain(with).copied().collect();
            let scene = scene_with(model, &set);
            let e = metric::evaluate(&scene).unwrap();
            for keys in [
                &[Parameter::SpectrumCenter][..],
                &[Parameter::FNumber, Parameter::SpectrumCenter][..],
                &[Parameter::FNumber][..],
            ] {
                let g = metric::gradient(&scene, keys).unwrap();
                assert_eq!(g.evaluation, e, "{model:?} {set:?} {keys:?}");
                assert_eq!(g.evaluation.mean_mtf.to_bits(), e.mean_mtf.to_bits());
                assert!(g.mean_mtf.iter().all(|d| d.is_finite()), "{:?}", g.mean_mtf);
            }
        }
    }
}

/// With the F-number and the wavelength asked together, each derivative is the one asked
/// alone: on the harmonic lens the order lane rides on the value's pass and the F-number's
/// `∂O/∂ln K` on its own mean (the same rules), on the paper's lens one lane serves both.
#[test]
fn the_line_lane_and_the_f_number_together_are_each_alone() {
    let harmonic = "model = \"harmonic\"\ndesign_order = 5\nefficiency = 0.15\ntransmission = 0.55";
    let line = ["spectrum.shape=\"line\"", "spectrum.center_nm=803", "spectrum.range_nm=1"];
    for model in [None, Some(harmonic)] {
        let scene = scene_with(model, &line);
        let both = metric::gradient(&scene, &[Parameter::FNumber, Parameter::SpectrumCenter]).unwrap();
        let f = metric::gradient(&scene, &[Parameter::FNumber]).unwrap();
        let c = metric::gradient(&scene, &[Parameter::SpectrumCenter]).unwrap();
        for (ours, alone) in [(both.asnr[0], f.asnr[0]), (both.asnr[1], c.asnr[0])] {
            assert!((ours - alone).abs() <= 1e-12 * alone.abs(), "{model:?}: {ours} vs {alone}");
        }
    }
}
