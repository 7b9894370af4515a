//! End-to-end tests of designing with the ASNR: `asnr optimize` over several keys (or with
//! another objective) and `asnr tolerance`, on the embedded paper scene (its closed-form engine
//! evaluates a point in well under a millisecond).

mod common;

use common::{asnr, asnr_at, fails, json, stderr};

// ---- asnr optimize over several keys ----

/// The paper scene's best band (33.1 nm by the one-key search, README "Optimize") is found again
/// with the band's centre searched jointly (its best, 800 nm: the lens's design wavelength), and
/// the optimum inside the bounds is a local maximum: each key ±1 % of its range gives no higher
/// ASNR.
#[test]
fn several_keys_find_the_paper_scenes_best_band_and_a_local_maximum() {
    let one = json(&["optimize", "--over", "spectrum.range_nm=1:200", "--json"]);
    let (one_best, one_tolerance) = (one["best"].as_f64().unwrap(), one["tolerance"].as_f64().unwrap());
    assert!((one_best - 33.1).abs() < 0.1, "{one}");
    let over = ["spectrum.range_nm=1:200", "spectrum.center_nm=700:900"];
    let v = json(&["optimize", "--over", over[0], "--over", over[1], "--json"]);
    let range = v["best"]["spectrum.range_nm"].as_f64().unwrap();
    let centre = v["best"]["spectrum.center_nm"].as_f64().unwrap();
    assert!((range - one_best).abs() < 0.2 + one_tolerance, "{v}");
    assert!((centre - 800.0).abs() < 0.5, "{v}");
    assert_eq!(v["at_bound"]["spectrum.range_nm"], false);
    assert_eq!(v["at_bound"]["spectrum.center_nm"], false);
    assert_eq!(v["converged"], true);
    let best = v["asnr"].as_f64().unwrap();
    let at = |r: f64, c: f64| asnr_at(&[format!("spectrum.range_nm={r}"), format!("spectrum.center_nm={c}")]);
    assert_eq!(at(range, centre), best, "the reported ASNR is the evaluation's at the reported point");
    for (dr, dc) in [(2.0, 0.0), (-2.0, 0.0), (0.0, 2.0), (0.0, -2.0)] {
        assert!(at(range + dr, centre + dc) <= best, "higher ASNR at ({}, {})", range + dr, centre + dc);
    }
    assert!(v["scene_asnr"].as_f64().unwrap() < best);
    assert!(v["evaluations"].as_u64().unwrap() > v["start_points"].as_u64().unwrap());
    assert_eq!(v["history"].as_array().unwrap().len() as u64, v["evaluations"].as_u64().unwrap());
}

/// A key whose best value is on a bound is flagged in the table, on stderr and in the JSON.
#[test]
fn a_bound_optimum_is_flagged() {
    let over = ["optimize", "--over", "spectrum.range_nm=1:200", "--over", "lens.f_number=2:6"];
    let out = asnr(&over);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(text.contains("AT THE BOUND LO"), "{text}");
    assert!(stderr(&out).contains("the best lens.f_number = 2 is at the bound LO = 2"), "{}", stderr(&out));
    let v = json(&[&over[..], &["--json"]].concat());
    assert_eq!(v["at_bound"]["lens.f_number"], true);
    assert_eq!(v["at_bound"]["spectrum.range_nm"], false);
}

/// Bad input to `optimize`: a key twice, LO ≥ HI, an unknown objective, a non-numeric key,
/// start settings for one key.
#[test]
fn bad_multi_key_optimize_arguments() {
    let err = fails(&["optimize", "--over", "lens.f_number=2:3", "--over", "lens.f_number=2:4"]);
    assert!(err.contains("--over lens.f_number: the key is given to --over twice"), "{err}");
    let err = fails(&["optimize", "--over", "lens.f_number=2:3", "--over", "spectrum.range_nm=50:50"]);
    assert!(err.contains("LO = 50 must be below HI = 50"), "{err}");
    let err = fails(&["optimize", "--over", "lens.f_number=2:3", "--objective", "sharpness"]);
    assert!(err.contains("--objective sharpness: expected asnr"), "{err}");
    let err = fails(&["optimize", "--over", "lens.f_number=2:3", "--over", "lens.model=1:2"]);
    assert!(err.contains("lens.model"), "{err}");
    let err = fails(&["optimize", "--over", "lens.f_number=2:3", "--starts", "5"]);
    assert!(err.contains("--starts: applies to a search over several keys"), "{err}");
    let err = fails(&[
        "optimize",
        "--over",
        "lens.f_number=2:3",
        "--over",
        "spectrum.range_nm=1:9",
        "--max-evaluations",
        "10",
    ]);
    assert!(err.contains("--max-evaluations 10: expected more than the 20 points"), "{err}");
    let err = fails(&["optimize", "--over", "lens.f_number=2:3", "--objective", "fov_mean"]);
    assert!(err.contains("single field point"), "{err}");
}

/// The glare-inclusive objective with one key: the golden-section search of today, the objective
/// named in the table and the JSON.
#[test]
fn another_objective_with_one_key() {
    let v = json(&["optimize", "--over", "spectrum.range_nm=1:200", "--objective", "asnr_glare", "--json"]);
    assert_eq!(v["objective"], "asnr_glare");
    let best = v["best"].as_f64().unwrap();
    let at = asnr_at(&[format!("spectrum.range_nm={best}"), "options.glare=\"included\"".to_owned()]);
    assert_eq!(v["asnr"].as_f64().unwrap(), at);
}

// ---- asnr tolerance ----

/// The same seed gives the same CSV and JSON byte for byte, on 1 or 2 threads; another seed
/// other samples. The nominal ASNR is `asnr evaluate`'s.
#[test]
fn tolerance_seeds_reproduce_byte_for_byte() {
    let args = ["tolerance", "--vary", "lens.f_number=normal:2%", "--vary", "spectrum.range_nm=uniform:40:60"];
    let run = |extra: &[&str]| {
        let out = asnr(&[&args[..], extra].concat());
        assert!(out.status.success(), "{}", stderr(&out));
        out.stdout
    };
    let csv = run(&["--samples", "200", "--seed", "5", "--csv", "--threads", "1"]);
    assert_eq!(csv, run(&["--samples", "200", "--seed", "5", "--csv", "--threads", "2"]));
    assert_ne!(csv, run(&["--samples", "200", "--seed", "6", "--csv"]));
    let text = String::from_utf8(csv).unwrap();
    assert!(text.starts_with("sample,lens.f_number,spectrum.range_nm,asnr,fraunhofer_valid\n0,"), "{text}");
    assert_eq!(text.lines().count(), 201);
    let json1 = run(&["--samples", "200", "--seed", "5", "--json", "--threads", "1"]);
    assert_eq!(json1, run(&["--samples", "200", "--seed", "5", "--json", "--threads", "2"]));
    let v: serde_json::Value = serde_json::from_slice(&json1).unwrap();
    assert_eq!(v["nominal_asnr"].as_f64().unwrap(), asnr_at(&[]));
    let (p5, p50, p95) = (v["p5"].as_f64().unwrap(), v["p50"].as_f64().unwrap(), v["p95"].as_f64().unwrap());
    assert!(p5 < p50 && p50 < p95, "{v}");
    assert_eq!(v["keys"][0]["sigma"].as_f64().unwrap(), 0.05);
    // a faster lens gathers more light: the ASNR falls with the F-number
    assert!(v["keys"][0]["sensitivity_per_sigma"].as_f64().unwrap() < 0.0, "{v}");
}

/// Bad input to `tolerance`: a key twice, an unknown distribution, a non-numeric key, a key also
/// given by --set, too many samples for the time budget.
#[test]
fn bad_tolerance_arguments() {
    let err = fails(&["tolerance", "--vary", "lens.f_number=normal:1%", "--vary", "lens.f_number=uniform:2:3"]);
    assert!(err.contains("--vary lens.f_number: the key is given to --vary twice"), "{err}");
    let err = fails(&["tolerance", "--vary", "lens.f_number=poisson:3"]);
    assert!(err.contains("unknown distribution `poisson`"), "{err}");
    let err = fails(&["tolerance", "--vary", "lens.model=normal:1"]);
    assert!(err.contains("lens.model = \"chromatic\": not a number"), "{err}");
    let err = fails(&["tolerance", "--vary", "lens.f_number=normal:1%", "--set", "lens.f_number=3"]);
    assert!(err.contains("also given by --set lens.f_number=3"), "{err}");
    let err = fails(&["tolerance", "--vary", "lens.f_number=normal:1%", "--samples", "1000000", "--budget", "0.001"]);
    assert!(err.contains("--samples 1000000: about") && err.contains("beyond the --budget of 0.001 s"), "{err}");
    let err = fails(&["tolerance", "--vary", "lens.f_number=normal:1%", "--samples", "0"]);
    assert!(err.contains("--samples 0: expected 1 to 1000000"), "{err}");
}

/// `--plot` with two keys writes the convergence and, beside it, the landscape with the path;
/// `tolerance --plot` the histogram.
#[test]
fn the_plots_of_a_search_and_a_tolerance_run() {
    let dir = std::env::temp_dir().join(format!("asnr-design-plots-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("search.svg");
    let out = asnr(&[
        "optimize",
        "--over",
        "spectrum.range_nm=1:200",
        "--over",
        "lens.f_number=2:6",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let convergence = std::fs::read_to_string(&svg).unwrap();
    assert!(convergence.contains("best ASNR so far") && convergence.contains("COBYLA starts"), "convergence plot");
    let landscape = std::fs::read_to_string(dir.join("search-landscape.svg")).unwrap();
    assert!(landscape.contains("the search&apos;s path") || landscape.contains("the search's path"), "landscape plot");
    assert!(landscape.contains("21 × 21 grid"));
    let hist = dir.join("tolerance.svg");
    let out =
        asnr(&["tolerance", "--vary", "lens.f_number=normal:2%", "--samples", "100", "--plot", hist.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&hist).unwrap();
    assert!(text.contains("samples per bin") && text.contains("5th, 50th, 95th percentiles"), "histogram");
    let err = fails(&["optimize", "--over", "spectrum.range_nm=1:200", "--plot", dir.join("x.svg").to_str().unwrap()]);
    assert!(err.contains("--plot: draws a search over several keys"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---- a library lens's fabrication errors ----

/// The example library lens (examples/library.toml).
fn library_scene() -> String {
    format!("{}/../examples/library.toml", env!("CARGO_MANIFEST_DIR"))
}

/// The library scene's ASNR with `set`.
fn library_asnr(set: &[&str]) -> f64 {
    let scene = library_scene();
    let mut args = vec!["evaluate", scene.as_str(), "--json"];
    for s in set {
        args.extend(["--set", s]);
    }
    json(&args)["asnr"].as_f64().unwrap()
}

/// σ = 0 and a bias of 0 give the nominal ASNR bit for bit; a phase error lowers it, and its
/// seed picks another draw; a bias that leaves the library is refused with the numbers. The
/// evaluations on a 10 nm band (a third of the time of the example's 50 nm; the atoms and their
/// errors the same).
#[test]
fn library_fabrication_errors_from_the_scene() {
    let library_asnr = |set: &[&str]| library_asnr(&[&["spectrum.range_nm=10"][..], set].concat());
    let nominal = library_asnr(&[]);
    let zero =
        library_asnr(&["lens.atom_phase_error_rad=0", "lens.atom_transmission_error=0", "lens.atom_error_seed=9"]);
    assert_eq!(zero.to_bits(), nominal.to_bits());
    assert_eq!(library_asnr(&["lens.parameter_bias=[0]"]).to_bits(), nominal.to_bits());
    let a = library_asnr(&["lens.atom_phase_error_rad=0.5", "lens.atom_error_seed=1"]);
    assert_eq!(a.to_bits(), library_asnr(&["lens.atom_phase_error_rad=0.5", "lens.atom_error_seed=1"]).to_bits());
    assert_ne!(a, library_asnr(&["lens.atom_phase_error_rad=0.5", "lens.atom_error_seed=2"]));
    assert!(a < nominal, "{a} vs {nominal}");
    let scene = library_scene();
    let err = fails(&["evaluate", &scene, "--set", "lens.parameter_bias=[500]"]);
    assert!(
        err.contains("lens.parameter_bias = [500]")
            && err.contains("1680 of 1680 atoms leave the library's range [100, 300] of diameter_nm"),
        "{err}"
    );
    let err = fails(&["evaluate", &scene, "--set", "lens.parameter_bias=[1, 2]"]);
    assert!(err.contains("one bias per library parameter column, 1 (diameter_nm)"), "{err}");
    let err = fails(&["evaluate", &scene, "--set", "lens.atom_transmission_error=0.5"]);
    assert!(err.contains("in [0, 0.5)"), "{err}");
    let err = fails(&["evaluate", "--set", "lens.atom_phase_error_rad=0.1"]);
    assert!(err.contains("lens.atom_phase_error_rad"), "{err}");
}

/// `lens.library_interpolation = "cubic"` on the example library (41 diameters, 5 nm apart:
/// dense, so the cubic and linear lenses differ little) with the atoms between rows gives an
/// ASNR within 1e-3 of linear's but not the same, and with the atoms on the rows the same to
/// rounding; `asnr scene` prints the key (and says linear when it is not given); a bad
/// value, and the key on a lens that has no library, are refused naming it.
#[test]
fn a_library_interpolated_by_cubics() {
    // the layout's atoms sit on the library's rows (where the two agree, to rounding): a bias of
    // half a row's step moves them between rows
    let half = "lens.parameter_bias=[2.5]";
    let linear = library_asnr(&[half]);
    let cubic = library_asnr(&[half, "lens.library_interpolation=\"cubic\""]);
    println!("ASNR with the bias: linear {linear}, cubic {cubic}");
    assert!(
        ((cubic - linear) / linear).abs() > 1e-8 && ((cubic - linear) / linear).abs() < 1e-3,
        "{cubic} vs {linear}"
    );
    let on_rows = library_asnr(&["lens.library_interpolation=\"cubic\""]);
    assert!(((on_rows - library_asnr(&[])) / on_rows).abs() < 1e-9, "{on_rows}");
    assert_eq!(library_asnr(&["lens.library_interpolation=\"linear\""]).to_bits(), library_asnr(&[]).to_bits());
    let scene = library_scene();
    let printed = |set: &[&str]| {
        let mut args = vec!["scene", scene.as_str()];
        for s in set {
            args.extend(["--set", s]);
        }
        let out = asnr(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8(out.stdout).unwrap()
    };
    let text = printed(&[]);
    assert!(
        text.contains("# library_interpolation not given: linear")
            && text.contains("library_interpolation = \"linear\""),
        "{text}"
    );
    let text = printed(&["lens.library_interpolation=\"cubic\""]);
    assert!(text.contains("library_interpolation = \"cubic\""), "{text}");
    let err = fails(&["evaluate", &scene, "--set", "lens.library_interpolation=\"spline\""]);
    assert!(
        err.contains("lens.library_interpolation") && err.contains("\"linear\"") && err.contains("\"cubic\""),
        "{err}"
    );
    let err = fails(&["evaluate", "--set", "lens.library_interpolation=\"cubic\""]);
    assert!(err.contains("lens.library_interpolation"), "{err}");
}

/// `--vary lens.atom_error_seed=seed` draws a new set of atom errors each sample: the samples
/// are the same on 1 or 2 threads byte for byte, their seeds whole numbers, their ASNR spread;
/// the seed has no σ and no sensitivity. On a 10 nm band (each run a third of the time over
/// the example's 50 nm; the atom errors drawn and spread the same way).
#[test]
fn tolerance_of_a_library_lens_with_atom_errors() {
    let scene = library_scene();
    let args = [
        "tolerance",
        scene.as_str(),
        "--set",
        "lens.atom_phase_error_rad=0.3",
        "--set",
        "spectrum.range_nm=10",
        "--vary",
        "lens.atom_error_seed=seed",
        "--samples",
        "6",
        "--seed",
        "3",
    ];
    let run = |extra: &[&str]| {
        let out = asnr(&[&args[..], extra].concat());
        assert!(out.status.success(), "{}", stderr(&out));
        out.stdout
    };
    let csv = run(&["--csv", "--threads", "1"]);
    assert_eq!(csv, run(&["--csv", "--threads", "2"]));
    let text = String::from_utf8(csv).unwrap();
    let rows: Vec<Vec<f64>> =
        text.lines().skip(1).map(|l| l.split(',').take(3).map(|v| v.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 6);
    for r in &rows {
        assert!(r[1].fract() == 0.0 && (0.0..4_294_967_296.0).contains(&r[1]), "{text}");
    }
    assert!(rows.iter().any(|r| r[2] != rows[0][2]), "{text}");
    let v: serde_json::Value = serde_json::from_slice(&run(&["--json"])).unwrap();
    assert_eq!(v["keys"][0]["distribution"], "seed");
    assert!(v["keys"][0]["sensitivity_per_sigma"].is_null(), "{v}");
    let err = fails(&["tolerance", "--vary", "lens.f_number=seed"]);
    assert!(err.contains("`lens.f_number` is not a seed key"), "{err}");
}

/// A small 2-D layout (a `.npy` grid of the example library's pillars, F/2.5, f0 = 125 µm,
/// R = 25 µm on a 400 nm lattice: each site the diameter whose field at 800 nm is nearest the
/// hyperbolic phase at its centre, among those 10 nm inside the library's range) and its scene in
/// `dir`.
fn small_grid_scene(dir: &std::path::Path) -> String {
    let library = format!("{}/../examples/data/library-tio2-like.csv", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&library).unwrap();
    let mut rows = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#') && !l.starts_with("diameter")) {
        let v: Vec<f64> = line.split(',').map(|s| s.trim().parse().unwrap()).collect();
        if v[1] == 800.0 {
            rows.push((v[0], v[2] * v[3].cos(), v[2] * v[3].sin()));
        }
    }
    let (pitch, f0, half) = (400.0f64, 125e3f64, 64usize);
    let n = 2 * half + 1;
    let mut grid = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let (x, y) = ((i as f64 - half as f64) * pitch, (j as f64 - half as f64) * pitch);
            let target = -std::f64::consts::TAU / 800.0 * ((x * x + y * y + f0 * f0).sqrt() - f0);
            let (tx, ty) = (target.cos(), target.sin());
            let d = |r: &(f64, f64, f64)| (r.1 - tx).powi(2) + (r.2 - ty).powi(2);
            // atoms 10 nm inside the library's 100–300 nm, room for a bias
            let inner = rows.iter().filter(|r| (110.0..=290.0).contains(&r.0));
            grid.push(inner.min_by(|a, b| d(a).total_cmp(&d(b))).unwrap().0);
        }
    }
    std::fs::write(dir.join("lens.npy"), scene::npy::npy_f64(&[n, n], &grid).unwrap()).unwrap();
    let scene = format!(
        r#"[lens]
model = "library"
f_number = 2.5
focal_length_mm = 0.125
design_wavelength_nm = 800.0
library = "{library}"
layout_grid = "lens.npy"
lattice_pitch_um = 0.4
parameter_bias = [0.0]
zernike_noll_rms_um = [0, 0, 0, 0, 0, 0, 0]

[source]
kind = "flat"
radiance_w_m2_sr_nm = 0.025

[spectrum]
shape = "line"
center_nm = 800.0
range_nm = 50.0
peak = 1.0

[camera]
pixel_pitch_um = 5.2
pixel_mtf = false
quantum_efficiency = 0.2

[exposure]
time_ms = 1.23

[options]
pupil_samples = 128
"#
    );
    let path = dir.join("grid.toml");
    std::fs::write(&path, scene).unwrap();
    path.to_str().unwrap().to_owned()
}

/// A 2-D layout reads `lens.library_interpolation` too: the small grid's mean MTF with cubic rows
/// is within 1e-3 of linear's, not the same (and `asnr evaluate` runs on a 2-D layout: its
/// pupil is 2-D, so the paraxial map's check against the exact one, which is radial, is not run).
#[test]
fn a_2d_layout_with_cubic_rows() {
    let dir = std::env::temp_dir().join(format!("asnr-grid-cubic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = small_grid_scene(&dir);
    // the grid's atoms sit on the library's rows (where the two agree): a bias of half a row's step
    // moves them between rows
    let mean = |set: &str| {
        json(&["evaluate", &scene, "--json", "--set", set, "--set", "lens.parameter_bias=[2.5]"])["mean_mtf"]
            .as_f64()
            .unwrap()
    };
    let linear = mean("lens.library_interpolation=\"linear\"");
    let cubic = mean("lens.library_interpolation=\"cubic\"");
    assert!(cubic != linear && ((cubic - linear) / linear).abs() < 1e-3, "{cubic} vs {linear}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `asnr tolerance` on a 2-D layout varies its fabrication-error keys (a parameter bias, the
/// atoms' random phase and amplitude errors, a Zernike coma term): every key gets a finite
/// sensitivity and the samples' ASNR spread; a seed key is refused for the layout, which takes
/// the atoms' errors in expectation.
#[test]
fn tolerance_of_a_2d_layout_varies_its_fabrication_errors() {
    let dir = std::env::temp_dir().join(format!("asnr-grid-tolerance-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = small_grid_scene(&dir);
    let keys = [
        "lens.parameter_bias[0]=uniform:-5:5",
        "lens.atom_phase_error_rad=uniform:0:0.4",
        "lens.atom_transmission_error=uniform:0:0.2",
        "lens.zernike_noll_rms_um[6]=normal:0.03",
    ];
    let mut args = vec!["tolerance", scene.as_str(), "--samples", "6", "--seed", "2"];
    for k in &keys {
        args.extend(["--vary", k]);
    }
    let v = json(&[&args[..], &["--json"]].concat());
    let listed = v["keys"].as_array().unwrap();
    assert_eq!(listed.len(), keys.len(), "{v}");
    for k in listed {
        assert!(k["sensitivity_per_sigma"].as_f64().is_some_and(f64::is_finite), "{k}");
    }
    let csv = asnr(&[&args[..], &["--csv"]].concat());
    assert!(csv.status.success(), "{}", stderr(&csv));
    let text = String::from_utf8(csv.stdout).unwrap();
    // columns: sample, the keys, asnr, fraunhofer_valid
    let asnr_column: Vec<f64> =
        text.lines().skip(1).map(|l| l.split(',').nth(1 + keys.len()).unwrap().parse().unwrap()).collect();
    assert_eq!(asnr_column.len(), 6, "{text}");
    assert!(asnr_column.iter().any(|a| (a - asnr_column[0]).abs() > 1e-6), "{text}");
    let err = fails(&["tolerance", &scene, "--vary", "lens.atom_error_seed=seed", "--samples", "2"]);
    // the layout's resolved scene has no seed key (`asnr scene` says why: no draws)
    assert!(err.contains("lens.atom_error_seed") && err.contains("has no such key"), "{err}");
    let out = asnr(&["scene", &scene]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("# no atom_error_seed"), "{}", stderr(&out));
    std::fs::remove_dir_all(&dir).ok();
}
