//! The design wavelength's gradient on the value's own rules (the closed form's lane along
//! `δW020 = (λ/λ0) f0/(8F#²)`, the per-frequency product rule's `∂H/∂w δw_o + δτ_o H_o`, a
//! line's order lane; docs/physics.md, "Gradients: the design wavelength") against the slow
//! reference rule (Gauss–Legendre panels in λ and ν split at the OTF's sign changes).

use crate::line_lane::scene_with;

/// `∂M̄/∂ln λ0` on the value's rule (scene tolerance 1e-6) against the reference rule at the
/// tolerance 1e-9, within 10× 1e-6 of `max(|∂M̄|, M̄)`: the paper's chromatic lens (the closed
/// form) at a 50 nm band, the N-BK7 singlet at a 100 nm band, a harmonic lens of design order 5
/// (six orders, their efficiencies moving) at a 50 nm band and under a line at 803 nm.
#[test]
fn the_design_lane_on_the_value_rule_matches_the_reference_rule() {
    let singlet = "model = \"refractive\"\nglass = \"N-BK7\"\nelements = 1";
    let harmonic = "model = \"harmonic\"\ndesign_order = 5\nefficiency = 0.15\ntransmission = 0.55";
    let line = ["spectrum.shape=\"line\"", "spectrum.center_nm=803", "spectrum.range_nm=1"];
    let cases: [(Option<&str>, &[&str]); 4] = [
        (None, &["spectrum.range_nm=50"]),
        (Some(singlet), &["spectrum.range_nm=100"]),
        (Some(harmonic), &["spectrum.range_nm=50"]),
        (Some(harmonic), &line),
    ];
    for (model, set) in cases {
        let scene = scene_with(model, set);
        let e = metric::evaluate(&scene).unwrap();
        let ours = metric::design_wavelength_mean_mtf_partial(&scene, &e, false)
            .unwrap()
            .expect("the value's engine carries the design wavelength's lane");
        let mut tight = set.to_vec();
        tight.push("options.tolerance=1e-9");
        let reference_scene = scene_with(model, &tight);
        let reference_e = metric::evaluate(&reference_scene).unwrap();
        let reference =
            metric::design_wavelength_mean_mtf_partial(&reference_scene, &reference_e, true).unwrap().unwrap();
        println!("{model:?} {set:?}: ∂M̄/∂ln λ0 {ours:.9} (reference {reference:.9}), M̄ {:.6}", e.mean_mtf);
        let bound = 10.0 * 1e-6 * reference.abs().max(e.mean_mtf);
        assert!((ours - reference).abs() <= bound, "{model:?} {set:?}: {ours} vs {reference}");
    }
}
