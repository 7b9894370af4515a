//! `asnr gradient` over the freeform spline's knots, the Zernike terms, the F-number and the
//! focal length: the keys are accepted and spelled canonically in the JSON, and a bad spline
//! (fewer than 3 knots, a NaN knot) or a family whose F-number is not smooth (the library lens) is refused naming
//! the key, with a non-zero exit and no panic.

mod common;

use common::{fails, json};

/// The phase-lens example with a spline added: every knot has a finite derivative, and the
/// JSON spells each knot's key canonically.
#[test]
fn spline_knots_and_defocus_have_a_gradient() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/phase-binary2.toml");
    let g = json(&[
        "gradient",
        scene,
        "--set",
        "lens.phase_spline_rad=[0.0, 0.3, -0.2, 0.1]",
        "--set",
        "lens.zernike_noll_rms_um=[0, 0, 0, 0.02]",
        "--wrt",
        "lens.phase_spline_rad",
        "--wrt",
        "lens.zernike_noll_rms_um[3]",
        "--json",
    ]);
    let gradient = g["gradient"].as_object().unwrap();
    for i in 0..4 {
        let key = format!("lens.phase_spline_rad[{i}]");
        assert!(gradient[&key].as_f64().unwrap().is_finite(), "{key}: {g}");
    }
    assert!(gradient["lens.zernike_noll_rms_um[3]"].as_f64().unwrap() != 0.0, "{g}");
}

/// Fewer than 3 knots, or a NaN knot, is refused naming `lens.phase_spline_rad`.
#[test]
fn a_bad_spline_is_refused_naming_the_key() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/phase-binary2.toml");
    let e = fails(&["gradient", scene, "--set", "lens.phase_spline_rad=[0.0, 0.3]", "--wrt", "lens.phase_spline_rad"]);
    assert!(e.contains("lens.phase_spline_rad") && e.contains("3 to 1024 knots"), "{e}");
    let e = fails(&[
        "gradient",
        scene,
        "--set",
        "lens.phase_spline_rad=[0.0, nan, 0.3]",
        "--wrt",
        "lens.phase_spline_rad[0]",
    ]);
    assert!(e.contains("lens.phase_spline_rad[1]") && e.contains("finite"), "{e}");
    // an m = 0 Zernike term of a family other than the phase lens, on a pupil that stays
    // rotationally symmetric (the radial engine follows the phase lens's terms only), is refused
    // by name with the reason
    let paper = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/paper-theory.toml");
    let e = fails(&[
        "gradient",
        paper,
        "--set",
        "lens.zernike_noll_rms_um=[0, 0, 0, 0.02]",
        "--wrt",
        "lens.zernike_noll_rms_um[3]",
    ]);
    assert!(e.contains("Noll 4") && e.contains("radial engine"), "{e}");
}

/// A Zernike term that is not rotationally symmetric (Noll 5) has its gradient on the FFT path.
#[test]
fn a_term_with_m_not_zero_has_a_gradient() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/phase-binary2.toml");
    let g = json(&[
        "gradient",
        scene,
        "--set",
        "lens.zernike_noll_rms_um=[0, 0, 0, 0, 0.05]",
        "--set",
        "options.tolerance=1e-3",
        "--wrt",
        "lens.zernike_noll_rms_um[4]",
        "--json",
    ]);
    let d = g["mean_mtf_gradient"]["lens.zernike_noll_rms_um[4]"].as_f64().unwrap();
    assert!(d.is_finite() && d < 0.0, "{g}");
}

/// The paper's lens: `lens.f_number` and `lens.focal_length_mm` in every JSON object, spelled as
/// given; N ∝ NA² = 1/(4F#²) (SI eq. S7), so ∂ln N/∂ln F# = −2 exactly and the focal length does
/// not move N; the same for the phase lens (on the radial engine's lanes); the library lens's
/// F-number is refused naming its family and why.
#[test]
fn f_number_and_focal_length_have_a_gradient() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/paper-theory.toml");
    let g = json(&["gradient", scene, "--wrt", "lens.f_number", "--wrt", "lens.focal_length_mm", "--json"]);
    for field in ["gradient", "mean_mtf_gradient", "snr0_gradient", "photoelectrons_gradient"] {
        let object = g[field].as_object().unwrap();
        let keys: Vec<&String> = object.keys().collect();
        assert_eq!(keys, ["lens.f_number", "lens.focal_length_mm"], "{field}: {g}");
    }
    let n = g["photoelectrons"].as_f64().unwrap();
    let d_n = g["photoelectrons_gradient"]["lens.f_number"].as_f64().unwrap();
    assert!((d_n * 2.5 / n + 2.0).abs() < 1e-12, "∂ln N/∂ln F# = {}: {g}", d_n * 2.5 / n);
    assert_eq!(g["photoelectrons_gradient"]["lens.focal_length_mm"].as_f64().unwrap(), 0.0, "{g}");
    assert!(
        g["mean_mtf_gradient"]["lens.focal_length_mm"].as_f64().unwrap() < 0.0,
        "a longer lens defocuses more: {g}"
    );
    // the phase lens: on the radial engine's lanes, the same spelling and the same ∂ln N/∂ln F#
    let phase = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/phase-binary2.toml");
    let g = json(&["gradient", phase, "--wrt", "lens.f_number", "--wrt", "lens.focal_length_mm", "--json"]);
    for field in ["gradient", "mean_mtf_gradient", "snr0_gradient", "photoelectrons_gradient"] {
        let keys: Vec<&String> = g[field].as_object().unwrap().keys().collect();
        assert_eq!(keys, ["lens.f_number", "lens.focal_length_mm"], "{field}: {g}");
    }
    let n = g["photoelectrons"].as_f64().unwrap();
    let d_n = g["photoelectrons_gradient"]["lens.f_number"].as_f64().unwrap();
    assert!((d_n * 2.5 / n + 2.0).abs() < 1e-12, "∂ln N/∂ln F# = {}: {g}", d_n * 2.5 / n);
    assert_eq!(g["photoelectrons_gradient"]["lens.focal_length_mm"].as_f64().unwrap(), 0.0, "{g}");
    // the library lens: refused naming the key and why (its value jumps where the aperture
    // radius crosses a ring centre)
    let library = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/library.toml");
    let e = fails(&["gradient", library, "--wrt", "lens.f_number"]);
    assert!(e.contains("--wrt lens.f_number") && e.contains("lens.model = \"library\"") && e.contains("ring"), "{e}");
}
