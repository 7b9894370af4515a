//! End-to-end tests of the last bad inputs a new user tried: each is answered or refused with the
//! key, option, column or file named, no panic, no NaN, infinity or `null` in any output.

use std::path::PathBuf;

mod common;

use common::{asnr, fails, json, stderr};

const EXAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples");

fn example(name: &str) -> String {
    format!("{EXAMPLES}/{name}")
}

/// A scratch directory unique to one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("asnr-inputs-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A radiance beyond the largest double is too much light, not none.
#[test]
fn source_scale_overflow_is_named() {
    let err = fails(&["evaluate", &example("tabulated.toml"), "--set", "source.scale=1e300"]);
    assert!(err.contains("overflows") && err.contains("source.scale") && !err.contains("no detected signal"), "{err}");
}

/// USAF groups whose coarsest bars lie above Nyquist (2^2000 cycles/mm printed `null` in the
/// JSON), or whose bars are wider than any target, are refused naming `--groups`.
#[test]
fn render_groups_the_camera_cannot_resolve_are_refused() {
    let dir = scratch("render");
    let out = dir.to_str().unwrap();
    let err = fails(&["render", "--groups", "2000:2001", "--out", out, "--json"]);
    assert!(err.contains("--groups 2000:2001") && err.contains("above the camera's Nyquist frequency"), "{err}");
    let err = fails(&["render", "--groups", "7:8", "--out", out, "--json"]);
    assert!(err.contains("group 7's coarsest bars (128 cycles/mm)") && err.contains("at most 6"), "{err}");
    let err = fails(&["render", "--groups=-2000:-1999", "--out", out, "--json"]);
    assert!(err.contains("--groups -2000:-1999") && err.contains("pixels wide"), "{err}");
}

/// `asnr psf` over a band reaching 0 nm named an internal `max_frequency = inf`.
#[test]
fn psf_of_a_band_reaching_zero_names_the_band() {
    let dir = scratch("psf");
    let err = fails(&["psf", "--set", "spectrum.range_nm=1000", "--out", dir.to_str().unwrap()]);
    assert!(
        err.contains("reaches λ = 0 nm") && err.contains("spectrum.range_nm") && !err.contains("max_frequency"),
        "{err}"
    );
}

/// A CSV header naming a column twice, and values an axis cannot span, are refused naming the
/// CSV and the column (not `--output`, not `inf`).
#[test]
fn plot_refuses_a_column_named_twice_and_values_beyond_an_axis() {
    let dir = scratch("plot");
    let twice = dir.join("twice.csv");
    std::fs::write(&twice, "a,b,b\n1,2,3\n2,3,4\n").unwrap();
    let output = dir.join("p.svg");
    let output = output.to_str().unwrap();
    let err = fails(&["plot", twice.to_str().unwrap(), "--x", "a", "--y", "b", "-o", output]);
    assert!(err.contains("twice.csv: the header names column `b` twice (fields 2 and 3)"), "{err}");
    let big = dir.join("big.csv");
    std::fs::write(&big, "a,b\n1,1e300\n2,1.7e308\n3,-1.7e308\n").unwrap();
    let err = fails(&["plot", big.to_str().unwrap(), "--x", "a", "--y", "b", "-o", output]);
    assert!(
        err.contains("big.csv line 3, column `b` (--y): 1.7e308") && !err.contains("--output") && !err.contains("inf"),
        "{err}"
    );
    // the same values on x, and ordinary ones, plot
    let err = fails(&["plot", big.to_str().unwrap(), "--x", "b", "--y", "a", "-o", output]);
    assert!(err.contains("column `b` (--x)"), "{err}");
    let fine = dir.join("fine.csv");
    std::fs::write(&fine, "a,b\n1,1e300\n2,-1e306\n").unwrap();
    let out = asnr(&["plot", fine.to_str().unwrap(), "--x", "a", "--y", "b", "-o", output]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// `asnr mtf --plot` names the field point in its title, and `mtf`, `psf` and `otf` take
/// `--tolerance` as `evaluate` does (the same option, validated the same way).
#[test]
fn mtf_plot_names_its_field_point_and_every_mtf_command_takes_tolerance() {
    let dir = scratch("mtf");
    let svg = dir.join("m.svg");
    let out = asnr(&["mtf", "--set", "field.x_deg=5", "--plot", svg.to_str().unwrap(), "--tolerance", "1e-5"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("(5°, 0°)"), "the title names no field point");
    let out = asnr(&["mtf", "--plot", svg.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("on axis"), "the title names no field point");
    // the option reaches the scene's options.tolerance, validated there
    let out = dir.to_str().unwrap();
    for args in [&["mtf"][..], &["psf", "--out", out], &["otf", "--out", out]] {
        let err = fails(&[args, &["--tolerance", "5"]].concat());
        assert!(err.contains("options.tolerance = 5: expected a relative error"), "{args:?}: {err}");
    }
    let loose = json(&["mtf", "--json", "--points", "5", "--tolerance", "1e-3"]);
    assert!(loose["mtf"].as_array().is_some_and(|m| m.iter().all(|v| v.as_f64().is_some_and(f64::is_finite))));
    let out = asnr(&["otf", "--size", "16", "--tolerance", "1e-4", "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// The search's sizes are refused before anything is allocated from them (1e12 evaluations
/// aborted on a 56 TB allocation, 2⁶⁴ − 1 starts on a capacity overflow), and an empty key
/// of `--over` is blamed on `--over`, not `--set`.
#[test]
fn optimize_refuses_huge_budgets_and_blames_over() {
    let two = ["optimize", "--over", "lens.f_number=2:3", "--over", "spectrum.range_nm=10:100"];
    let err = fails(&[&two[..], &["--max-evaluations", "1000000000000"]].concat());
    assert!(err.contains("--max-evaluations 1000000000000: expected at most 1000000"), "{err}");
    let err = fails(&[&two[..], &["--starts", "18446744073709551615"]].concat());
    assert!(err.contains("--starts 18446744073709551615: expected at most 1000000"), "{err}");
    let err = fails(&["optimize", "--over", "=0.5:1", "--over", "spectrum.range_nm=10:100"]);
    assert!(err.contains("--over =0.5:1: `` is not a dotted key") && !err.contains("--set"), "{err}");
    let err = fails(&["sweep", "--over", "=0.5:1:3"]);
    assert!(err.contains("--over =0.5:1:3") && !err.contains("--set"), "{err}");
}

/// `seed` draws integers in [0, 2³²): refused for a key that is not a seed (a wavelength drawn
/// in [0, 2³²) nm).
#[test]
fn tolerance_seed_only_for_seed_keys() {
    let err = fails(&[
        "tolerance",
        &example("phase-binary2.toml"),
        "--vary",
        "lens.design_wavelength_nm=seed",
        "--samples",
        "4",
    ]);
    assert!(err.contains("`lens.design_wavelength_nm` is not a seed key"), "{err}");
}

/// Lengths so small that a derived number overflows name their key, not an internal table.
#[test]
fn tiny_lengths_name_their_key() {
    let err = fails(&["evaluate", &example("phase-binary2.toml"), "--set", "lens.norm_radius_mm=1e-300"]);
    assert!(err.contains("lens.norm_radius_mm = 1e-300: expected") && !err.contains("-inf"), "{err}");
    let err = fails(&["evaluate", &example("psf-stack.toml"), "--set", "lens.psf_pitch_um=1e-304"]);
    assert!(err.contains("lens.psf_pitch_um = 1e-304: expected") && !err.contains("= inf"), "{err}");
}

/// A `.npy` (format 1.0) of little-endian f64 `values` with `shape`.
fn npy(shape: &[usize], values: &[f64]) -> Vec<u8> {
    scene::npy::npy_f64(shape, values).expect("as many values as the shape holds")
}

/// A one-wavelength PSF stack (a 2-D `.npy`, or one slice of a 3-D one, psf_wavelengths_nm =
/// [800]) under a line spectrum at 800 nm: it was always refused ("100 % of the signal …
/// outside the stack's 800–800 nm"). Reference: a Gaussian PSF of σ = 3 µm sampled at 1 µm on
/// 64 × 64 has the MTF exp(−2π²σ²ν²) (its samples' aliasing, exp(−2π²σ²/p²) ≈ e^{−178}, and its
/// cut tails beyond 10σ are far below the tolerance), whose mean over 0–96.15 cycles/mm (the
/// camera's Nyquist) is taken here by Simpson's rule; 1e-3 holds the OTF's interpolation in ν
/// between the padded grid's frequencies.
#[test]
fn one_wavelength_psf_stack_under_a_line() {
    let dir = scratch("one-slice");
    let (n, sigma_um) = (64_usize, 3.0);
    let psf: Vec<f64> = (0..n * n)
        .map(|k| {
            let (y, x) = ((k / n) as f64 - (n / 2) as f64, (k % n) as f64 - (n / 2) as f64);
            (-(x * x + y * y) / (2.0 * sigma_um * sigma_um)).exp()
        })
        .collect();
    std::fs::write(dir.join("flat.npy"), npy(&[n, n], &psf)).unwrap();
    std::fs::write(dir.join("slice.npy"), npy(&[1, n, n], &psf)).unwrap();
    let nyquist = 1e3 / (2.0 * 5.2); // cycles/mm
    let steps = 2000;
    let mtf = |nu: f64| (-2.0 * std::f64::consts::PI.powi(2) * (sigma_um * 1e-3 * nu).powi(2)).exp();
    let simpson: f64 = (0..=steps)
        .map(|i| {
            let w = if i == 0 || i == steps {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * mtf(nyquist * i as f64 / steps as f64)
        })
        .sum::<f64>()
        / (3.0 * steps as f64);
    for file in ["flat.npy", "slice.npy"] {
        let scene = dir.join(format!("{file}.toml"));
        let text = std::fs::read_to_string(example("psf-stack.toml")).unwrap();
        let text: String = text
            .lines()
            .map(|l| match l.split(" =").next().unwrap_or_default() {
                "psf" => format!("psf = \"{file}\""),
                "psf_pitch_um" => "psf_pitch_um = 1".to_owned(),
                "psf_wavelengths_nm" => "psf_wavelengths_nm = [800]".to_owned(),
                _ => l.to_owned(),
            })
            .collect::<Vec<_>>()
            .join("\n");
        std::fs::write(&scene, text).unwrap();
        let v = json(&["evaluate", scene.to_str().unwrap(), "--set", "spectrum.shape=line", "--json"]);
        let mean = v["mean_mtf"].as_f64().unwrap();
        assert!((mean - simpson).abs() < 1e-3, "{file}: mean MTF {mean} against the Gaussian's {simpson}");
        // a band around the slice is still refused: the one slice cannot stand for 50 nm
        let err = fails(&["evaluate", scene.to_str().unwrap()]);
        assert!(err.contains("lens.psf_wavelengths_nm") && err.contains("of the signal"), "{err}");
    }
}

/// A phase table's amplitude is shape only: a uniform column of 1e-200 is the same lens as no
/// column (it gave a mean MTF of 0.878 where the table alone gives 0.441).
#[test]
fn phase_table_amplitude_is_shape_only() {
    let dir = scratch("amplitude");
    let table = std::fs::read_to_string(example("data/phase-hyperbolic-f2.5.csv")).unwrap();
    let mut lines = table.lines().filter(|l| !l.starts_with('#'));
    assert_eq!(lines.next(), Some("r_mm,phase_rad"));
    let tiny: Vec<String> = lines.map(|l| format!("{l},1e-200")).collect();
    std::fs::write(dir.join("tiny.csv"), format!("r_mm,phase_rad,amplitude\n{}\n", tiny.join("\n"))).unwrap();
    let scene = std::fs::read_to_string(example("phase-table.toml"))
        .unwrap()
        .replace("data/phase-hyperbolic-f2.5.csv", dir.join("tiny.csv").to_str().unwrap());
    std::fs::write(dir.join("tiny.toml"), scene).unwrap();
    // at one wavelength (a line), where a table with an amplitude column costs a second in debug
    let mean =
        |path: &str| json(&["evaluate", path, "--set", "spectrum.shape=line", "--json"])["mean_mtf"].as_f64().unwrap();
    let (with, without) = (mean(dir.join("tiny.toml").to_str().unwrap()), mean(&example("phase-table.toml")));
    assert!((with - without).abs() < 1e-5 * without, "amplitude 1e-200: {with}, no amplitude: {without}");
}

/// A phase or library lens at 80° or more: its oblique wave is modelled below 80°, and beyond it
/// the lens fell back to the axis (85° returned the on-axis mean MTF 0.4411 with no warning).
#[test]
fn phase_and_library_lenses_refuse_fields_beyond_their_oblique_model() {
    for scene in ["phase-binary2.toml", "phase-table.toml", "library.toml"] {
        let err = fails(&["evaluate", &example(scene), "--set", "field.x_deg=85"]);
        assert!(err.contains("field.x_deg = 85: expected an angle in degrees within ±80"), "{scene}: {err}");
        let err = fails(&["evaluate", &example(scene), "--set", "field.y_deg=-80"]);
        assert!(err.contains("field.y_deg = -80: expected"), "{scene}: {err}");
    }
}

/// Profiles whose work is far beyond seconds are refused up front, before any rule is built,
/// naming the key: a defocus phase `8π F# ν |W020|` beyond the budget at every sampled
/// wavelength (`lens.binary2 = [1e8]` grew to 10.7 GB in 60 s; `[1e300]`, `A1 = 1e7`,
/// `norm_radius_mm = 0.01`, a table of phase 1e300), and a phase beyond the defocus whose slope
/// turns the radial engine's integrand too far (Z11 = 10 µm did not finish in 120 s; 500 terms
/// of 1e-3 rad in 30 s). Run under the memory cap they answer alike (no allocation).
#[test]
fn hopeless_profiles_are_refused_up_front() {
    let phase = example("phase-binary2.toml");
    for set in ["lens.binary2=[1e8]", "lens.binary2=[1e300]", "lens.binary2=[1e7]", "lens.norm_radius_mm=0.01"] {
        // the defocus check, or (1e300: rounding leaves a residual of 4e287 rad) the radial one
        let up_front =
            |e: &str| (e.contains("the defocus") || e.contains("radial engine")) && e.contains("lens.binary2");
        let err = fails(&["evaluate", &phase, "--set", set]);
        assert!(up_front(&err), "{set}: {err}");
        let err = fails(&["mtf", &phase, "--set", set]);
        assert!(up_front(&err), "mtf {set}: {err}");
    }
    let dir = scratch("hopeless");
    let table = std::fs::read_to_string(example("data/phase-hyperbolic-f2.5.csv")).unwrap();
    let rows: Vec<String> = table
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| format!("{},1e300", l.split(',').next().unwrap()))
        .collect();
    std::fs::write(dir.join("huge.csv"), format!("r_mm,phase_rad\n{}\n", rows.join("\n"))).unwrap();
    let scene = std::fs::read_to_string(example("phase-table.toml"))
        .unwrap()
        .replace("data/phase-hyperbolic-f2.5.csv", dir.join("huge.csv").to_str().unwrap());
    std::fs::write(dir.join("huge.toml"), scene).unwrap();
    let err = fails(&["evaluate", dir.join("huge.toml").to_str().unwrap()]);
    assert!((err.contains("the defocus") || err.contains("radial engine")) && err.contains("lens.phase_csv"), "{err}");
    // beyond the defocus: Z11 (its slope in ρ² runs over 12√5 c, 2.1e3 rad at 10 µm and 800 nm)
    for scene in [&phase, &example("paper-theory.toml")] {
        let z11 = "lens.zernike_noll_rms_um=[0,0,0,0,0,0,0,0,0,0,10]";
        let err = fails(&["evaluate", scene, "--set", z11]);
        assert!(
            err.contains("lens.zernike_noll_rms_um = Zernike terms (Noll, RMS): Z11 = 10 µm")
                && err.contains("turns the phase by 2.105e3 rad at 800 nm"),
            "{err}"
        );
    }
    let many = format!("lens.binary2=[-527.7875658030853, 5.277875658030851, {}]", vec!["1e-3"; 500].join(", "));
    let err = fails(&["evaluate", &phase, "--set", &many]);
    assert!(err.contains("lens.binary2 = [502 coefficients]") && err.contains("with 502 terms"), "{err}");
    // and what the engine does in seconds still runs: Z11 = 1 µm, 200 terms (on a line)
    let few = format!("lens.binary2=[-527.7875658030853, 5.277875658030851, {}]", vec!["1e-3"; 200].join(", "));
    for set in ["lens.zernike_noll_rms_um=[0,0,0,0,0,0,0,0,0,0,1]", few.as_str()] {
        let v = json(&["evaluate", &phase, "--set", set, "--set", "spectrum.shape=line", "--json"]);
        assert!(v["mean_mtf"].as_f64().is_some_and(|m| m > 0.0 && m < 1.0), "{set}: {v}");
    }
}

/// `options.pupil_mapping`: the report says which map was used and how far the paraxial map is
/// from the flat lens's exact image (the other map evaluated at tolerance 1e-1, and at 1e-3 where
/// that cannot tell the side of 1 %); `"exact"` is refused, naming the key, where the map does
/// not apply (another family, off axis) and a value that is neither is named.
#[test]
fn pupil_mapping_is_reported_and_refused_where_it_does_not_apply() {
    let phase = example("phase-binary2.toml");
    let line = ["--set", "spectrum.shape=line", "--tolerance", "1e-4", "--json"];
    let run = |mapping: &str| {
        let mut args = vec!["evaluate", &phase, "--set"];
        let set = format!("options.pupil_mapping={mapping}");
        args.push(&set);
        args.extend(line);
        json(&args)
    };
    let (paraxial, exact) = (run("paraxial"), run("exact"));
    let used = |r: &serde_json::Value| r["pupil_mapping"]["used"].as_str().unwrap().to_owned();
    assert_eq!((used(&paraxial), used(&exact)), ("paraxial".to_owned(), "exact".to_owned()));
    let (p, e) = (paraxial["mean_mtf"].as_f64().unwrap(), exact["mean_mtf"].as_f64().unwrap());
    // at F/2.5 on a line at λ0 the exact image is below the paraxial one (a cutoff 2 % lower)
    assert!(e < p, "exact {e}, paraxial {p}");
    // each report's estimate of the other map agrees with the other run (both at 1e-4)
    let error = paraxial["pupil_mapping"]["paraxial_relative_error"].as_f64().unwrap();
    assert!((error - (p - e) / e).abs() < 1e-3, "{error} vs {}", (p - e) / e);
    assert!((exact["pupil_mapping"]["other_mean_mtf"].as_f64().unwrap() - p).abs() < 1e-3 * p);
    let err = fails(&["evaluate", "--set", "options.pupil_mapping=exact"]);
    assert!(err.contains("options.pupil_mapping = \"exact\": expected \"paraxial\" for this lens"), "{err}");
    let err = fails(&["evaluate", &phase, "--set", "options.pupil_mapping=exact", "--set", "field.x_deg=5"]);
    assert!(err.contains("options.pupil_mapping = \"exact\": expected \"paraxial\" off axis"), "{err}");
    let err = fails(&["evaluate", &phase, "--set", "options.pupil_mapping=sphere"]);
    assert!(err.contains("options.pupil_mapping = \"sphere\": expected \"paraxial\" (the default"), "{err}");
    // a pupil with a Zernike term off m = 0 (coma, Z8): the exact map is radial, so the paraxial
    // report evaluates without the check and says so (it had failed as a whole), and "exact"
    // is refused saying why
    let coma = "lens.zernike_noll_rms_um=[0,0,0,0,0,0,0,0.02]";
    let out = asnr(&["evaluate", &phase, "--set", coma, "--set", "spectrum.shape=line", "--json"]);
    let warned = stderr(&out);
    assert!(out.status.success(), "{warned}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report.get("pupil_mapping").is_none(), "{report}");
    assert!(report["mean_mtf"].as_f64().is_some_and(|m| m > 0.0 && m < 1.0), "{report}");
    assert!(warned.contains("not estimated for this lens: the exact pupil map is radial on axis only"), "{warned}");
    let err = fails(&["evaluate", &phase, "--set", coma, "--set", "options.pupil_mapping=exact"]);
    assert!(
        err.contains("options.pupil_mapping") && err.contains("Zernike terms that are not radially symmetric"),
        "{err}"
    );
}

/// The mapping check's warning: where the paraxial map is more than 1 % off the exact image and
/// only there. Hyperbolic Binary 2 lenses (f0 = 3.36 mm, 800 nm, on a line at λ0), their
/// coefficients the binomial series of the hyperbola written here, `A_n = −(2π/λ0) f0 C(1/2, n)
/// (R/f0)^{2n}` with `R_norm = R` (12 terms: beyond them below 1e-4 rad at F/1.25): at F/1.25
/// (NA0 = 0.4, the frequency scale alone √(1 + NA0²) − 1 = 7.7 %) the check warns, at F/10
/// (NA0 = 0.05: 0.12 %) it does not; the example's band (F/2.5, +1.68 %) warns.
#[test]
fn the_mapping_check_warns_where_the_maps_differ_by_more_than_one_percent() {
    let (f0_mm, lambda0_mm) = (3.36, 800e-6);
    let hyperbola = |f_number: f64| {
        let r = f0_mm / (2.0 * f_number);
        let (mut c, mut terms) = (1.0, Vec::new());
        for n in 1..=12_i32 {
            // C(1/2, n) = C(1/2, n − 1) (1/2 − (n − 1))/n
            c *= (0.5 - f64::from(n - 1)) / f64::from(n);
            let a = -std::f64::consts::TAU / lambda0_mm * f0_mm * c * (r / f0_mm).powi(2 * n);
            terms.push(format!("{a:e}"));
        }
        [
            format!("lens.f_number={f_number}"),
            format!("lens.norm_radius_mm={r}"),
            format!("lens.binary2=[{}]", terms.join(", ")),
        ]
    };
    let phase = example("phase-binary2.toml");
    let run = |f_number: f64| {
        let mut args = vec!["evaluate".to_owned(), phase.clone(), "--json".to_owned()];
        for set in hyperbola(f_number).into_iter().chain(["spectrum.shape=line".to_owned()]) {
            args.extend(["--set".to_owned(), set]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = asnr(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (v["pupil_mapping"]["paraxial_relative_error"].as_f64().unwrap(), stderr(&out))
    };
    let warning = "the paraxial pupil map is +";
    let (fast, fast_err) = run(1.25);
    assert!(fast > 0.01 && fast_err.contains(warning), "F/1.25: {fast} {fast_err}");
    let (slow, slow_err) = run(10.0);
    assert!(slow.abs() < 0.01 && !slow_err.contains("pupil map"), "F/10: {slow} {slow_err}");
    let out = asnr(&["evaluate", &phase]);
    let err = stderr(&out);
    assert!(out.status.success() && err.contains("the paraxial pupil map is +1.68 % off"), "{err}");
}

/// A library lens's per-atom phase errors of σ = 3 rad (did not finish in 60 s) and 1.5 rad
/// (49 s of CPU) leave a first order whose phase and amplitude turn too fast for the radial
/// engine: refused up front by the library's work budget, naming the key.
#[test]
fn library_atom_phase_errors_beyond_the_budget_are_refused_up_front() {
    for sigma in ["3", "1.5"] {
        let set = format!("lens.atom_phase_error_rad={sigma}");
        let err = fails(&["evaluate", &example("library.toml"), "--set", &set]);
        assert!(
            err.contains(&format!(
                "lens.atom_phase_error_rad = {sigma}: expected a profile the radial engine integrates in seconds"
            )) && err.contains("beyond the 60 allowed"),
            "{sigma}: {err}"
        );
    }
}

/// A layout whose atoms are all alike (every diameter 200 nm in examples/library.toml's layout: a
/// flat plate) did not finish in 100 s: its constant design phase was fitted as a polynomial of
/// degree 10 whose coefficients (up to 5e-3 rad) cancelled to the constant, and the radial engine
/// integrated their rounding-sized wiggles. A flat plate focuses nothing (its design phase has no
/// zones, so no imaging order): refused, naming the layout, before any integral.
#[test]
fn a_flat_plate_library_layout_is_refused_naming_the_layout() {
    let dir = scratch("flat-plate");
    let layout = std::fs::read_to_string(example("data/layout-paper-lens.csv")).unwrap();
    let flat: String = layout
        .lines()
        .map(|l| match l.split_once(',') {
            Some((r, _)) if !l.starts_with('#') && !l.starts_with("r_mm") => format!("{r},200.0\n"),
            _ => format!("{l}\n"),
        })
        .collect();
    assert_eq!(flat.matches(",200.0").count(), 1680, "{flat}");
    std::fs::write(dir.join("flat.csv"), flat).unwrap();
    let scene = std::fs::read_to_string(example("library.toml"))
        .unwrap()
        .replace("data/library-tio2-like.csv", &example("data/library-tio2-like.csv"))
        .replace("data/layout-paper-lens.csv", "flat.csv");
    std::fs::write(dir.join("flat.toml"), scene).unwrap();
    let path = dir.join("flat.toml");
    for interpolation in ["linear", "cubic"] {
        let set = format!("lens.library_interpolation=\"{interpolation}\"");
        let err = fails(&["evaluate", path.to_str().unwrap(), "--set", &set]);
        assert!(err.contains("lens.layout") && err.contains("flat plate"), "{err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A nearly flat library layout (all 1680 atoms alike but one, a 150 nm pillar among 200 nm
/// ones) did not finish in 40 s: with no zone its "first order" is the zero order's plane wave,
/// about 84 waves out of focus at the detector (beyond the Fraunhofer model: 100 % of the signal
/// blurred past 0.25 mm, 1.1 s of CPU at one wavelength), whose OTFs the radial engine integrated
/// at every node of the band. Its fitted design phase turns less than 2π across the aperture:
/// refused before any integral, naming the layout, the phase it spans and the zones f0 asks.
#[test]
fn a_nearly_flat_library_layout_is_refused_naming_the_layout() {
    let dir = scratch("nearly-flat");
    let layout = std::fs::read_to_string(example("data/layout-paper-lens.csv")).unwrap();
    let mut row = 0;
    let nearly: String = layout
        .lines()
        .map(|l| match l.split_once(',') {
            Some((r, _)) if !l.starts_with('#') && !l.starts_with("r_mm") => {
                row += 1;
                format!("{r},{}\n", if row == 840 { "150.0" } else { "200.0" })
            }
            _ => format!("{l}\n"),
        })
        .collect();
    assert_eq!((nearly.matches(",200.0").count(), nearly.matches(",150.0").count()), (1679, 1), "{nearly}");
    std::fs::write(dir.join("nearly.csv"), nearly).unwrap();
    let scene = std::fs::read_to_string(example("library.toml"))
        .unwrap()
        .replace("data/library-tio2-like.csv", &example("data/library-tio2-like.csv"))
        .replace("data/layout-paper-lens.csv", "nearly.csv");
    std::fs::write(dir.join("nearly.toml"), scene).unwrap();
    let path = dir.join("nearly.toml");
    for interpolation in ["linear", "cubic"] {
        let set = format!("lens.library_interpolation=\"{interpolation}\"");
        let err = fails(&["evaluate", path.to_str().unwrap(), "--set", &set]);
        assert!(
            err.contains("lens.layout")
                && err.contains("less than one zone (2π; 1 of the 1680 atoms")
                && err.contains("about 84.0 zones"),
            "{err}"
        );
    }
    // the layout the example gives (84 zones) still builds and evaluates
    let v = json(&["evaluate", &example("library.toml"), "--set", "spectrum.shape=line", "--json"]);
    assert!(v["mean_mtf"].as_f64().is_some_and(|m| m > 0.1), "{v}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `asnr mtf` names a PSF stack's 2-D OTF as the stack's (examples/psf-stack.toml is not round,
/// so its MTF is the mean over azimuth), and a phase map's as a sampled 2-D pupil's.
#[test]
fn mtf_names_the_source_of_a_2d_otf() {
    let out = asnr(&["mtf", &example("psf-stack.toml")]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("mean over azimuth (on axis; a PSF stack: the OTF depends on direction)"), "{text}");
    assert!(!text.contains("sampled 2-D pupil"), "{text}");
}

/// A harmonic lens with Zernike terms (examples/harmonic.toml with Z4 = 0.02 µm, Z8 = 0.01 µm):
/// its orders beside the design order carry a defocus whose phase `k|W020|` is beyond what the
/// overlap engine's t rule resolves (docs/physics.md, "Zernike terms on the overlap engine"), so
/// the FFT path takes the scene; it had stopped with the t rule's work budget. Its mean MTF
/// agrees with the same path at a finer fixed sampling within ten times the scene's tolerance.
#[test]
fn a_harmonic_lens_with_zernike_terms_takes_the_fft_path() {
    let harmonic = example("harmonic.toml");
    let terms = "lens.zernike_noll_rms_um=[0,0,0,0.02,0,0,0,0.01]";
    let v = json(&["evaluate", &harmonic, "--set", terms, "--json"]);
    let engine = v["numerics"]["engine"].as_str().unwrap();
    assert!(engine.starts_with("fft"), "{engine}");
    let fine = json(&["evaluate", &harmonic, "--set", terms, "--set", "options.pupil_samples=192", "--json"]);
    let (m, reference) = (v["mean_mtf"].as_f64().unwrap(), fine["mean_mtf"].as_f64().unwrap());
    let tolerance = v["numerics"]["tolerance"].as_f64().unwrap();
    assert!((m - reference).abs() <= 10.0 * tolerance * reference, "{m} against {reference} at {tolerance}");
}
