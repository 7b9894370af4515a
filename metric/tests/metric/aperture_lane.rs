//! The F-number and focal-length gradient of the refractive and harmonic lenses on the value's
//! own per-frequency product rule (the defocus lane `w ∂H/∂w` beside each OTF; docs/physics.md,
//! "Gradients: the F-number and the focal length on the value's rule") against the slow
//! reference rule (Gauss–Legendre panels in λ and ν split at the OTF's sign changes).

/// The paper's scene with `model` in place of its chromatic lens's model, efficiency and
/// transmission lines, and `set`.
fn scene_with(model: &str, set: &[&str]) -> metric::Scene {
    let paper = scene::read(None).unwrap();
    let lines: Vec<&str> =
        paper.text().lines().filter(|l| !(l.starts_with("efficiency") || l.starts_with("transmission"))).collect();
    let text = lines.join("\n").replace("model = \"chromatic\"", model);
    let source = scene::Source::from_text(text, "scene written in the test", ".");
    let set: Vec<String> = set.iter().map(|s| (*s).to_owned()).collect();
    scene::build_from(&source, &set).unwrap()
}

/// `∂M̄/∂ln F#` and `∂M̄/∂ln f0` on the value's rule (scene tolerance 1e-6) against the reference
/// rule at the tolerance 1e-9, within 10× 1e-6 of the mean MTF: the N-BK7 singlet at a 50 and a
/// 100 nm band, and a harmonic lens of design order 5 (six orders).
#[test]
fn the_lane_on_the_value_rule_matches_the_reference_rule() {
    let singlet = "model = \"refractive\"\nglass = \"N-BK7\"\nelements = 1";
    let harmonic = "model = \"harmonic\"\ndesign_order = 5\nefficiency = 0.15\ntransmission = 0.55";
    let cases =
        [(singlet, "spectrum.range_nm=50"), (singlet, "spectrum.range_nm=100"), (harmonic, "spectrum.range_nm=50")];
    for (model, band) in cases {
        let scene = scene_with(model, &[band]);
        let e = metric::evaluate(&scene).unwrap();
        let (f, k) = metric::aperture_mean_mtf_partials(&scene, &e, false)
            .unwrap()
            .expect("the per-frequency rule carries the defocus lane");
        let reference_scene = scene_with(model, &[band, "options.tolerance=1e-9"]);
        let reference_e = metric::evaluate(&reference_scene).unwrap();
        let (f_ref, k_ref) = metric::aperture_mean_mtf_partials(&reference_scene, &reference_e, true).unwrap().unwrap();
        println!("{band}: ∂M̄/∂ln F# {f:.9} (reference {f_ref:.9}), ∂M̄/∂ln f0 {k:.9} (reference {k_ref:.9})");
        for (ours, theirs) in [(f, f_ref), (k, k_ref)] {
            assert!((ours - theirs).abs() <= 10.0 * 1e-6 * e.mean_mtf, "{band}: {ours} vs {theirs}");
        }
    }
}
