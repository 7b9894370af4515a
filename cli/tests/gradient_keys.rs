//! `asnr gradient` over the freeform spline's knots and the Zernike terms: the keys are
//! accepted, and a bad spline (fewer than 3 knots, a NaN knot) is refused naming the key, with a
//! non-zero exit and no panic.

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
