//! End-to-end tests of the `asnr` binary: the paper scene, `--set`, `--json`, and bad input.
//!
//! Every bad-input case asserts a non-zero exit, no panic, and a message that names the file (or
//! the `--set`), the key, the value and what is accepted.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/paper-theory.toml");
const TABULATED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/tabulated.toml");
const MONOCHROMATIC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/monochromatic.toml");

fn asnr(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asnr")).args(args).output().expect("the asnr binary runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `asnr` expecting failure; returns stderr after checking the exit code and that it did not panic.
fn fails(args: &[&str]) -> String {
    let out = asnr(args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "args {args:?}: expected exit 1, stderr: {err}");
    assert!(!err.contains("panicked"), "args {args:?} panicked: {err}");
    assert!(err.starts_with("error: "), "args {args:?}: {err}");
    err
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = asnr(args);
    assert!(out.status.success(), "args {args:?}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("one JSON object on stdout")
}

/// A scratch directory unique to one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("asnr-cli-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The paper scene with `from` replaced by `to`, written into `dir`.
fn edited_paper(dir: &Path, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(PAPER).unwrap();
    assert!(text.contains(from), "the paper scene has no `{from}`");
    let path = dir.join("scene.toml");
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
    path
}

#[test]
fn embedded_scene_prints_the_table() {
    let out = asnr(&["evaluate"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    for needle in ["embedded paper scene", "ASNR", "SNR0 = √N", "mean MTF", "Fraunhofer", "M0 = τ1/T"] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
}

#[test]
fn embedded_scene_is_the_example_file() {
    let a = json(&["evaluate", "--json"]);
    let b = json(&["evaluate", PAPER, "--json"]);
    assert_eq!(a["asnr"], b["asnr"]);
    assert_eq!(a["mean_mtf"], b["mean_mtf"]);
}

#[test]
fn json_has_the_documented_keys_and_they_hang_together() {
    let v = json(&["evaluate", PAPER, "--set", "lens.f_number=2.5", "--set", "spectrum.range_nm=50", "--json"]);
    for key in ["mean_mtf", "mtf_integral_cyc_per_mm", "snr0", "photoelectrons", "asnr"] {
        assert!(v[key].as_f64().is_some_and(f64::is_finite), "{key}: {}", v[key]);
    }
    let f = |k: &str| v[k].as_f64().unwrap();
    assert!((f("snr0") - f("photoelectrons").sqrt()).abs() < 1e-9 * f("snr0"));
    assert!((f("asnr") - f("snr0") * f("mean_mtf")).abs() < 1e-12 * f("asnr"));
    // ∫MTF dν = mean × ν_N, ν_N = 1/(2 × 5.2 µm) = 96.1538 cycles/mm
    assert!((f("mtf_integral_cyc_per_mm") - f("mean_mtf") * 1e3 / (2.0 * 5.2)).abs() < 1e-9);
    assert_eq!(v["fraunhofer"]["valid"], serde_json::Value::Bool(true));
    // eq. S15: Δλ = 0.25 mm × 800 nm / (3.36 mm × 0.2) = 297.619 nm
    let shift = v["fraunhofer"]["max_shift_nm"].as_f64().unwrap();
    assert!((shift - 0.25 * 800.0 / (3.36 * 0.2)).abs() < 1e-6, "{shift}");
    // eq. S13, S12: M0 = 0.15/0.55 = 0.2727, VG = 0.5714 (paper SI: 0.27, 57 %)
    assert!((v["glare"]["m0"].as_f64().unwrap() - 0.15 / 0.55).abs() < 1e-12);
    assert!((v["glare"]["vg"].as_f64().unwrap() - 4.0 / 7.0).abs() < 1e-12);
}

#[test]
fn photoelectrons_grow_with_the_range_and_set_overrides_apply() {
    // paper theory: photon count ∝ spectral range (flat source behind a Gaussian filter)
    let n = |range: &str| {
        json(&["evaluate", "--set", &format!("spectrum.range_nm={range}"), "--json"])["photoelectrons"]
            .as_f64()
            .unwrap()
    };
    let (n10, n100) = (n("10"), n("100"));
    // ∫ λ G dλ = peak σ √(2π) (c + 0), σ ∝ range: the ratio is 10 to within the λ-weighting
    assert!((n100 / n10 - 10.0).abs() < 1e-6, "{n10} {n100}");
}

#[test]
fn integral_form_reports_cycles_per_mm() {
    let v = json(&["evaluate", "--set", "options.form=integral", "--json"]);
    assert_eq!(v["form"], "integral");
    assert_eq!(v["asnr"], v["asnr_integral_cyc_per_mm"]);
}

#[test]
fn tabulated_example_runs() {
    let v = json(&["evaluate", TABULATED, "--json"]);
    let m = v["mean_mtf"].as_f64().unwrap();
    assert!(m > 0.0 && m < 1.0, "{m}");
    assert!(v["glare"]["efficiency"].as_f64().unwrap() < v["glare"]["transmission"].as_f64().unwrap());
}

#[test]
fn spectrum_reaching_zero_wavelength_is_reported_not_hidden() {
    // large pixels keep the frequency range (and the run time) small: every wavelength here is
    // defocused by nearly the whole aperture
    let out = asnr(&[
        "evaluate",
        "--set",
        "spectrum.center_nm=40",
        "--set",
        "spectrum.range_nm=100",
        "--set",
        "camera.pixel_pitch_um=50",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("reaches λ ≤ 0") && err.contains("was cut off"), "{err}");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("NaN"));
}

// ---- bad input: one test per kind, each asserting the message ----

#[test]
fn bad_value_out_of_range() {
    let err = fails(&["evaluate", PAPER, "--set", "lens.f_number=-2"]);
    assert!(
        err.contains("paper-theory.toml (--set lens.f_number=-2): lens.f_number = -2: expected a number ≥ 0.5"),
        "{err}"
    );
}

#[test]
fn bad_value_not_finite() {
    let err = fails(&["evaluate", PAPER, "--set", "spectrum.range_nm=nan"]);
    assert!(err.contains("spectrum.range_nm = NaN: expected a width > 0 nm"), "{err}");
    let err = fails(&["evaluate", PAPER, "--set", "camera.pixel_pitch_um=inf"]);
    assert!(err.contains("camera.pixel_pitch_um = inf: expected a length > 0 µm"), "{err}");
}

#[test]
fn bad_unknown_key_in_file() {
    let dir = scratch("unknown-key");
    let path = edited_paper(&dir, "f_number = 2.5", "f_number = 2.5\nfnumber = 2.8");
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.contains("scene.toml: lens.fnumber: unknown field `fnumber`, expected one of"), "{err}");
}

#[test]
fn bad_unknown_key_by_set() {
    let err = fails(&["evaluate", PAPER, "--set", "camera.gain=2"]);
    assert!(err.contains("(--set camera.gain=2): camera.gain: unknown field `gain`"), "{err}");
}

#[test]
fn bad_wrong_type() {
    let err = fails(&["evaluate", PAPER, "--set", "lens.f_number=fast"]);
    assert!(err.contains("lens.f_number: invalid type: string \"fast\", expected f64"), "{err}");
}

#[test]
fn bad_malformed_toml() {
    let dir = scratch("malformed");
    let path = dir.join("broken.toml");
    std::fs::write(&path, "[lens\nf_number = 2.5\n").unwrap();
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.contains("broken.toml: malformed TOML") && err.contains("line 1"), "{err}");
}

#[test]
fn bad_missing_file() {
    let err = fails(&["evaluate", "/nonexistent/scene.toml"]);
    assert!(err.contains("cannot read the scene file /nonexistent/scene.toml"), "{err}");
}

#[test]
fn bad_empty_file() {
    let dir = scratch("empty");
    let path = dir.join("empty.toml");
    std::fs::write(&path, "  \n").unwrap();
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.contains("empty.toml: the scene file is empty"), "{err}");
}

#[test]
fn bad_missing_key() {
    let dir = scratch("missing-key");
    let path = edited_paper(&dir, "time_ms = 1.23", "");
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.contains("exposure: missing field `time_ms`"), "{err}");
}

#[test]
fn bad_efficiency_above_transmission() {
    let err = fails(&["evaluate", PAPER, "--set", "lens.efficiency=0.7"]);
    assert!(err.contains("efficiency τ1 = 0.7 exceeds transmission T = 0.55 at 800 nm: expected τ1 ≤ T ≤ 1"), "{err}");
}

#[test]
fn bad_fraction_above_one() {
    let err = fails(&["evaluate", PAPER, "--set", "camera.quantum_efficiency=1.5"]);
    assert!(err.contains("camera.quantum_efficiency = 1.5: expected a fraction in [0, 1] or a CSV path"), "{err}");
}

#[test]
fn bad_unreadable_csv() {
    let err = fails(&["evaluate", PAPER, "--set", "lens.efficiency=no-such-table.csv"]);
    assert!(err.contains("lens.efficiency = \"no-such-table.csv\": cannot read the CSV file"), "{err}");
}

#[test]
fn bad_csv_non_increasing_wavelengths() {
    let dir = scratch("non-increasing");
    std::fs::write(dir.join("eff.csv"), "wavelength_nm,efficiency\n800,0.1\n790,0.12\n").unwrap();
    let path = edited_paper(&dir, "efficiency = 0.15", "efficiency = \"eff.csv\"");
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.contains("scene.toml: lens.efficiency = \"eff.csv\""), "{err}");
    assert!(err.contains("line 3: wavelength 790 nm does not exceed the previous 800 nm"), "{err}");
}

#[test]
fn bad_csv_not_numeric_and_too_short() {
    let dir = scratch("csv-garbage");
    std::fs::write(dir.join("qe.csv"), "wavelength_nm,qe\n800,0.2\n810,abc\n").unwrap();
    let path = edited_paper(&dir, "quantum_efficiency = 0.2", "quantum_efficiency = \"qe.csv\"");
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.contains("line 3: `810,abc` is not a pair of finite numbers"), "{err}");
    std::fs::write(dir.join("qe.csv"), "wavelength_nm,qe\n800,0.2\n").unwrap();
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.contains("1 data rows; expected at least two rows"), "{err}");
}

#[test]
fn bad_csv_value_out_of_range() {
    let dir = scratch("csv-range");
    std::fs::write(dir.join("f.csv"), "700,0.5\n800,1.2\n900,0.5\n").unwrap();
    let text = std::fs::read_to_string(PAPER).unwrap();
    let start = text.find("[spectrum]").unwrap();
    let end = text.find("[camera]").unwrap();
    let scene = format!("{}[spectrum]\nshape = \"table\"\ncsv = \"f.csv\"\n\n{}", &text[..start], &text[end..]);
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(
        err.contains("spectrum.csv = \"f.csv\"")
            && err.contains("line 2: transmission 1.2 is out of range; expected [0, 1]"),
        "{err}"
    );
}

#[test]
fn bad_choice_and_inapplicable_key() {
    let err = fails(&["evaluate", PAPER, "--set", "spectrum.shape=lorentzian"]);
    assert!(
        err.contains("spectrum.shape = \"lorentzian\": expected \"gaussian\", \"tophat\", \"line\" (one wavelength), \"table\" or \"none\""),
        "{err}"
    );
    let err = fails(&["evaluate", PAPER, "--set", "source.temperature_k=3000"]);
    assert!(err.contains("source.temperature_k does not apply to source.kind = \"flat\""), "{err}");
}

#[test]
fn bad_set_syntax() {
    let err = fails(&["evaluate", PAPER, "--set", "lens.f_number"]);
    assert!(err.contains("--set lens.f_number: expected key=value"), "{err}");
    let err = fails(&["evaluate", PAPER, "--set", "lens..f_number=2"]);
    assert!(err.contains("is not a dotted key"), "{err}");
    let err = fails(&["evaluate", PAPER, "--set", "lens.f_number.x=2"]);
    assert!(err.contains("`lens.f_number` is a value, not a table"), "{err}");
}

#[test]
fn bad_zero_signal_is_an_error_not_nan() {
    let err = fails(&["evaluate", PAPER, "--set", "lens.efficiency=0"]);
    assert!(err.contains("no detected signal"), "{err}");
}

// ---- asnr mtf ----

#[test]
fn mtf_csv_has_one_row_per_point_and_starts_at_one() {
    let out = asnr(&["mtf", "--csv", "--points", "11", "--wavelengths", "790,810"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "frequency_cyc_per_mm,otf,mtf,diffraction_limited,mtf_790nm,mtf_810nm");
    assert_eq!(lines.len(), 12);
    assert_eq!(lines[1], "0,1,1,1,1,1");
    // last row at Nyquist 1/(2 × 5.2 µm) = 96.1538 cycles/mm, MTF below the diffraction limit
    let last: Vec<f64> = lines[11].split(',').map(|v| v.parse().unwrap()).collect();
    assert!((last[0] - 1e3 / 10.4).abs() < 1e-9, "{last:?}");
    assert!(last[2] < last[3] && last[2] > 0.0, "{last:?}");
}

#[test]
fn mtf_mean_of_the_curve_agrees_with_evaluate() {
    // trapezoid over 2001 points of the smooth paper-scene MTF vs the adaptive mean: 1e-6
    let curve = json(&["mtf", "--json", "--points", "2001"]);
    let mtf: Vec<f64> = curve["mtf"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let n = mtf.len() - 1;
    let trapezoid = (mtf.iter().sum::<f64>() - 0.5 * (mtf[0] + mtf[n])) / n as f64;
    let mean = json(&["evaluate", "--json"])["mean_mtf"].as_f64().unwrap();
    assert!((trapezoid - mean).abs() < 1e-6, "{trapezoid} vs {mean}");
}

#[test]
fn mtf_to_cutoff_reaches_zero_and_plots() {
    let dir = scratch("mtf-plot");
    let svg = dir.join("mtf.svg");
    let out = asnr(&["mtf", "--to-cutoff", "--json", "--plot", svg.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mtf = v["mtf"].as_array().unwrap();
    // the highest cutoff is that of the spectrum's ±7σ window; the closed-form engine keeps the
    // Gaussian's tail beyond it, worth ~1e-16 there
    assert!(mtf.last().unwrap().as_f64().unwrap().abs() < 1e-12);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("polychromatic MTF") && text.contains("Nyquist"));
}

#[test]
fn bad_mtf_arguments() {
    let err = fails(&["mtf", "--points", "1"]);
    assert!(err.contains("--points 1: expected a whole number from 2 to 100000"), "{err}");
    let err = fails(&["mtf", "--wavelengths", "800,-5"]);
    assert!(err.contains("--wavelengths: -5 nm: expected wavelengths > 0 nm"), "{err}");
    let err = fails(&["mtf", "--plot", "/tmp/asnr-plot.pdf"]);
    assert!(err.contains("--plot /tmp/asnr-plot.pdf: expected a file name ending in .svg or .png"), "{err}");
}

#[test]
fn mtf_png_plot_is_a_png() {
    let dir = scratch("mtf-png");
    let png = dir.join("mtf.png");
    let out = asnr(&["mtf", "--csv", "--points", "21", "--plot", png.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert!(bytes.len() > 10_000, "a 900 × 560 chart, {} bytes", bytes.len());
}

#[test]
fn off_axis_field_reports_the_radial_tangential_split() {
    let v = json(&["evaluate", "--set", "field.x_deg=8", "--json"]);
    let (r, t) = (v["mean_mtf_radial"].as_f64().unwrap(), v["mean_mtf_tangential"].as_f64().unwrap());
    let on_axis = json(&["evaluate", "--json"])["mean_mtf"].as_f64().unwrap();
    // off axis the spectral quadrature (±7σ window), on axis the closed form: 2.4e-12 apart
    assert!(r < t && (t - on_axis).abs() < 1e-9, "{r} {t} {on_axis}");
    let out = asnr(&["mtf", "--csv", "--points", "3", "--set", "field.x_deg=8"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("frequency_cyc_per_mm,otf,mtf,diffraction_limited,mtf_radial,mtf_tangential\n"), "{text}");
    let err = fails(&["evaluate", "--set", "field.x_deg=95"]);
    assert!(err.contains("field.x_deg = 95: expected an angle in degrees, within ±90"), "{err}");
}

#[test]
fn decentred_iris_example_uses_the_fft_path_and_splits_x_and_y() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/decentred-iris.toml");
    let v = json(&["evaluate", scene, "--json"]);
    assert!(v["numerics"]["engine"].as_str().unwrap().starts_with("fft:"), "{}", v["numerics"]["engine"]);
    assert!(v["mean_mtf_radial"].as_f64().unwrap() < v["mean_mtf_tangential"].as_f64().unwrap());
    let out = asnr(&["mtf", scene, "--csv", "--points", "5"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("frequency_cyc_per_mm,otf,mtf,diffraction_limited,mtf_radial,mtf_tangential\n"), "{text}");
}

// ---- asnr optimize ----

#[test]
fn optimize_finds_an_interior_maximum_of_the_spectral_range() {
    let v = json(&["optimize", "--over", "spectrum.range_nm=1:200", "--xtol", "1e-3", "--json"]);
    let (best, asnr) = (v["best"].as_f64().unwrap(), v["asnr"].as_f64().unwrap());
    assert!(best > 10.0 && best < 100.0, "{best}");
    // the maximum beats both ends and the paper's 50 nm
    for range in ["1", "200", "50"] {
        let at =
            json(&["evaluate", "--set", &format!("spectrum.range_nm={range}"), "--json"])["asnr"].as_f64().unwrap();
        assert!(asnr >= at, "{asnr} < {at} at {range} nm");
    }
}

#[test]
fn bad_optimize_arguments() {
    let err = fails(&["optimize", "--over", "spectrum.range_nm=200:1"]);
    assert!(err.contains("LO = 200 must be below HI = 1"), "{err}");
    let err = fails(&["optimize", "--over", "lens.colour=1:2"]);
    assert!(err.contains("lens.colour: unknown field `colour`"), "{err}");
    let err = fails(&["optimize", "--over", "spectrum.range_nm=1:200", "--xtol", "2"]);
    assert!(err.contains("--xtol 2: expected a fraction of the range in (0, 1)"), "{err}");
}

// ---- asnr sweep ----

/// Issue 4: a 4,000-point sweep (40 F-numbers × 100 spectral ranges, the grid of Fig. 2a) gives
/// byte-identical CSV with 1 and 2 threads.
#[test]
fn sweep_csv_is_identical_with_one_and_two_threads() {
    let args = |threads: &'static str| {
        vec![
            "sweep",
            "--over",
            "lens.f_number=1:10:40",
            "--over",
            "spectrum.range_nm=2:200:100",
            "--csv",
            "--threads",
            threads,
        ]
    };
    let one = asnr(&args("1"));
    let two = asnr(&args("2"));
    assert!(one.status.success() && two.status.success(), "{}", stderr(&one));
    assert_eq!(one.stdout, two.stdout);
    let text = String::from_utf8(one.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "lens.f_number,spectrum.range_nm,mean_mtf,snr0,asnr,photoelectrons,fraunhofer_valid");
    assert_eq!(lines.len(), 4001);
    // the first key varies slowest; the grid includes both ends
    assert!(lines[1].starts_with("1,2,") && lines[100].starts_with("1,200,") && lines[4000].starts_with("10,200,"));
}

/// `--tolerance` reaches the evaluation (reported back), `--explain` prints the plan, and a
/// tolerance out of range is refused with the key and what is accepted.
#[test]
fn tolerance_and_explain() {
    let v = json(&["evaluate", "--tolerance", "1e-9", "--json"]);
    assert_eq!(v["numerics"]["tolerance"], 1e-9);
    let loose = json(&["evaluate", "--tolerance", "1e-3", "--json"]);
    let tight = v["mean_mtf"].as_f64().unwrap();
    assert!((loose["mean_mtf"].as_f64().unwrap() - tight).abs() < 1e-3 * tight);
    let out = asnr(&["evaluate", "--explain"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("How this was computed") && text.contains("closed-form"), "{text}");
    let out = asnr(&["evaluate", "--explain", "--set", "lens.efficiency=0.55"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("no stray light (T = τ1)"), "{text}");
    let err = fails(&["evaluate", "--tolerance", "0.5"]);
    assert!(err.contains("options.tolerance = 0.5") && err.contains("from 1e-14 to 0.1"), "{err}");
}

/// A non-white noise spectrum from CSV (frequency_cyc_per_mm, relative amplitude): a flat 2
/// halves the ASNR; a bad row is reported with file, line and value.
#[test]
fn noise_spectrum_from_csv() {
    let dir = std::env::temp_dir().join(format!("asnr-noise-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    let base = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/paper-theory.toml")).unwrap();
    std::fs::write(&scene, base.replace("[camera]", "[camera]\nnoise_spectrum = \"nps.csv\"")).unwrap();
    std::fs::write(dir.join("nps.csv"), "frequency_cyc_per_mm,relative\n0,2\n100,2\n").unwrap();
    let white = json(&["evaluate", "--json"])["asnr"].as_f64().unwrap();
    let shaped = json(&["evaluate", scene.to_str().unwrap(), "--json"])["asnr"].as_f64().unwrap();
    assert!((shaped - 0.5 * white).abs() < 1e-6 * white, "{shaped} vs {white}");
    std::fs::write(dir.join("nps.csv"), "0,1\n50,-1\n").unwrap();
    let err = fails(&["evaluate", scene.to_str().unwrap()]);
    assert!(err.contains("nps.csv") && err.contains("line 2") && err.contains("-1"), "{err}");
}

#[test]
fn sweep_points_match_evaluate_and_plot() {
    let dir = scratch("sweep-plot");
    let png = dir.join("heat.png");
    let out = asnr(&[
        "sweep",
        "--over",
        "spectrum.range_nm=10:50:3",
        "--over",
        "camera.pixel_pitch_um=4:6:2",
        "--json",
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let points: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let p = &points[2]; // range 10 + 20 × 1 = 30 nm, pitch 4 µm
    assert_eq!(p["values"], serde_json::json!([30.0, 4.0]));
    let direct = json(&["evaluate", "--set", "spectrum.range_nm=30", "--set", "camera.pixel_pitch_um=4", "--json"]);
    assert_eq!(p["asnr"], direct["asnr"]);
    assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
}

#[test]
fn bad_sweep_arguments() {
    let err = fails(&["sweep", "--over", "spectrum.range_nm=1:200"]);
    assert!(err.contains("expected KEY=LO:HI:N"), "{err}");
    let err = fails(&["sweep", "--over", "spectrum.range_nm=1:200:0"]);
    assert!(err.contains("N `0` is not a whole number from 1 to 1000000"), "{err}");
    let err = fails(&["sweep", "--over", "lens.f_number=0.1:1:3"]);
    assert!(err.contains("lens.f_number = 0.1: expected a number ≥ 0.5"), "{err}");
    let err = fails(&["sweep", "--over", "a.b=1:2:2", "--over", "c.d=1:2:2", "--over", "e.f=1:2:2", "--plot", "x.svg"]);
    assert!(err.contains("unknown field"), "{err}");
}

#[test]
fn sensor_keys_saturation_warning_and_bad_values() {
    let out = asnr(&["evaluate", "--set", "camera.full_well_e=400", "--set", "camera.read_noise_e=10"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("warning: the pixel saturates: 559 e⁻"), "{}", stderr(&out));
    // clipped to 400 e⁻: SNR0 = 400/√(400 + 10²) = 17.8885
    let v = json(&["evaluate", "--set", "camera.full_well_e=400", "--set", "camera.read_noise_e=10", "--json"]);
    assert!((v["snr0"].as_f64().unwrap() - 400.0 / 500f64.sqrt()).abs() < 1e-9);
    assert_eq!(v["noise"]["saturated"], serde_json::Value::Bool(true));
    let err = fails(&["evaluate", "--set", "camera.read_noise_e=-1"]);
    assert!(err.contains("camera.read_noise_e = -1: expected a read noise ≥ 0 e⁻ rms"), "{err}");
    let err = fails(&["evaluate", "--set", "camera.adc_bits=12"]);
    assert!(err.contains("camera.adc_bits needs camera.gain_dn_per_e too"), "{err}");
}

#[test]
fn field_list_averages_and_rejects_mixed_forms() {
    let dir = scratch("fov");
    let text = std::fs::read_to_string(PAPER).unwrap();
    let path = dir.join("fov.toml");
    std::fs::write(&path, format!("{text}\n[[fields]]\nx_deg = 0\nweight = 2\n\n[[fields]]\nx_deg = 8\n")).unwrap();
    let v = json(&["evaluate", path.to_str().unwrap(), "--json"]);
    let on = json(&["evaluate", "--json"])["asnr"].as_f64().unwrap();
    let off = json(&["evaluate", "--set", "field.x_deg=8", "--json"])["asnr"].as_f64().unwrap();
    assert!((v["asnr"].as_f64().unwrap() - (2.0 * on + off) / 3.0).abs() < 1e-9, "{}", v["asnr"]);
    let err = fails(&["evaluate", path.to_str().unwrap(), "--set", "field.x_deg=3"]);
    assert!(err.contains("[field] and [[fields]] both given"), "{err}");
}

// ---- line spectra (one wavelength) ----

/// The example scene: one wavelength, no spectral quadrature, named in the JSON and by --explain;
/// the photons of the band's equivalent width (1 nm of a 50 nm-range Gaussian's σ√(2π) = 44.31 nm).
#[test]
fn line_example_is_monochromatic() {
    let v = json(&["evaluate", MONOCHROMATIC, "--json"]);
    assert_eq!(v["numerics"]["engine"], "monochromatic (line spectrum): exact-1d");
    assert_eq!(v["numerics"]["spectral_nodes"], 1);
    assert_eq!(v["numerics"]["spectral_panels"], 0);
    assert!((v["mean_wavelength_nm"].as_f64().unwrap() - 800.0).abs() < 1e-9, "{}", v["mean_wavelength_nm"]);
    // at the design wavelength: the diffraction-limited mean over [0, s_N], s_N = ν_N λ0 F# = 0.19231
    let s_n: f64 = 800e-9 * 2.5 / (2.0 * 5.2e-6);
    let theta = s_n.acos();
    // ∫_0^x (2/π)(acos s − s√(1−s²)) ds = (2/π)[x acos x − √(1−x²) + 1 + ((1−x²)^{3/2} − 1)/3]
    let mean = 2.0 / std::f64::consts::PI
        * (s_n * theta - (1.0 - s_n * s_n).sqrt() + 1.0 + ((1.0 - s_n * s_n).powf(1.5) - 1.0) / 3.0)
        / s_n;
    let got = v["mean_mtf"].as_f64().unwrap();
    assert!((got - mean).abs() < 1e-6, "{got} vs {mean}");
    let paper = json(&["evaluate", "--json"]);
    let ratio = v["photoelectrons"].as_f64().unwrap() / paper["photoelectrons"].as_f64().unwrap();
    let expected = 1.0 / (50.0 / (2.0 * 2f64.sqrt()) * (2.0 * std::f64::consts::PI).sqrt());
    assert!((ratio - expected).abs() < 1e-9, "{ratio} vs {expected}");
    let out = asnr(&["evaluate", MONOCHROMATIC, "--explain", "--set", "spectrum.center_nm=850"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("no spectral quadrature") && text.contains("850.0000 nm"), "{text}");
    assert!(text.contains("engine       monochromatic (line spectrum): exact-1d"), "{text}");
}

/// The line's keys: center_nm and range_nm required, peak optional in (0, 1], no csv; every
/// message names the file, the key, the value and what is accepted.
#[test]
fn bad_line_keys() {
    let dir = scratch("line-keys");
    let text = std::fs::read_to_string(MONOCHROMATIC).unwrap();
    for (key, needle) in [
        ("center_nm = 800.0", "spectrum.center_nm is missing: expected the line's wavelength > 0 nm"),
        ("range_nm = 1.0", "spectrum.range_nm is missing: expected the equivalent width > 0 nm"),
    ] {
        let path = dir.join("scene.toml");
        std::fs::write(&path, text.replacen(key, "", 1)).unwrap();
        let err = fails(&["evaluate", path.to_str().unwrap()]);
        assert!(err.contains(path.to_str().unwrap()) && err.contains(needle), "{err}");
    }
    let err = fails(&["evaluate", MONOCHROMATIC, "--set", "spectrum.range_nm=0"]);
    assert!(
        err.contains("(--set spectrum.range_nm=0): spectrum.range_nm = 0: expected the equivalent width > 0 nm"),
        "{err}"
    );
    let err = fails(&["evaluate", MONOCHROMATIC, "--set", "spectrum.range_nm=1600"]);
    assert!(
        err.contains("spectrum.range_nm = 1600: expected an equivalent width under twice spectrum.center_nm"),
        "{err}"
    );
    let err = fails(&["evaluate", MONOCHROMATIC, "--set", "spectrum.center_nm=-5"]);
    assert!(err.contains("spectrum.center_nm = -5: expected the line's wavelength > 0 nm"), "{err}");
    let err = fails(&["evaluate", MONOCHROMATIC, "--set", "spectrum.peak=1.5"]);
    assert!(err.contains("spectrum.peak = 1.5: expected a transmission in (0, 1]"), "{err}");
    let err = fails(&["evaluate", MONOCHROMATIC, "--set", "spectrum.csv=filter.csv"]);
    assert!(err.contains("spectrum.csv does not apply to spectrum.shape = \"line\""), "{err}");
    let err = fails(&["evaluate", MONOCHROMATIC, "--set", "spectrum.center_nm=inf"]);
    assert!(err.contains("spectrum.center_nm = inf"), "{err}");
    // the paper scene turned into a line by --set alone
    let v = json(&["evaluate", "--set", "spectrum.shape=line", "--json"]);
    assert!(v["numerics"]["engine"].as_str().unwrap().starts_with("monochromatic"), "{}", v["numerics"]["engine"]);
    // peak defaults to 1: the example states it, removing it changes nothing
    let path = dir.join("no-peak.toml");
    std::fs::write(&path, text.replacen("peak = 1.0", "", 1)).unwrap();
    assert_eq!(
        json(&["evaluate", path.to_str().unwrap(), "--json"])["asnr"],
        json(&["evaluate", MONOCHROMATIC, "--json"])["asnr"]
    );
}

/// A sweep over the line's wavelength: each point is the evaluation at that wavelength, and the
/// ASNR peaks at the design wavelength (the one without defocus; photons ∝ λ grow only 5 %).
#[test]
fn sweep_over_the_line_wavelength() {
    let out = asnr(&["sweep", MONOCHROMATIC, "--over", "spectrum.center_nm=760:840:5", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let points: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let points = points.as_array().unwrap();
    assert_eq!(points.len(), 5);
    let asnr_at = |i: usize| points[i]["asnr"].as_f64().unwrap();
    assert_eq!(points[2]["values"], serde_json::json!([800.0]));
    for i in [0, 1, 3, 4] {
        assert!(asnr_at(i) < asnr_at(2), "{i}: {} vs {}", asnr_at(i), asnr_at(2));
    }
    let direct = json(&["evaluate", MONOCHROMATIC, "--set", "spectrum.center_nm=780", "--json"]);
    assert_eq!(points[1]["asnr"], direct["asnr"]);
}

// ---- robustness ----

/// Photon counts beyond f64 are refused with the keys that drive them (it was a panic,
/// `signal_e must be finite`); counts that stay finite are reported, with no `null` in the JSON.
#[test]
fn overflowing_photoelectrons_are_refused_not_a_panic() {
    let err = fails(&["evaluate", "--set", "exposure.time_ms=1e308"]);
    for needle in ["photoelectrons per pixel N", "exposure.time_ms", "camera.pixel_pitch_um", "full well"] {
        assert!(err.contains(needle), "missing {needle:?} in {err}");
    }
    let out = asnr(&["evaluate", "--set", "exposure.time_ms=1e300", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(!text.contains("null"), "{text}");
}

/// A read noise whose square overflows is refused by name (the JSON carried `null` variances).
#[test]
fn read_noise_whose_variance_overflows_is_refused() {
    let err = fails(&["evaluate", "--set", "camera.read_noise_e=1e200", "--json"]);
    assert!(
        err.contains("camera.read_noise_e=1e200") && err.contains("read_noise must be below 1.3e154 e⁻ rms"),
        "{err}"
    );
}

/// `--over` grids: a point count that overflows is refused with the product (four axes of 65536
/// wrapped to 0 points and an empty CSV), a key given twice or also given by `--set` is refused
/// by name, and generated values beyond TOML's integers are passed as floats (1e20 failed on its
/// own `50000000000000000000`).
#[test]
fn sweep_grids_are_checked_and_generated_values_parse_back() {
    let axes = ["lens.f_number=2:3:65536", "camera.pixel_pitch_um=2:3:65536", "exposure.time_ms=1:2:65536"];
    let mut args = vec!["sweep", "--csv"];
    for a in axes.iter().chain(&["spectrum.range_nm=1:2:65536"]) {
        args.extend(["--over", a]);
    }
    let err = fails(&args);
    assert!(err.contains("65536 × 65536 × 65536 × 65536 = 1.8446744073709552e19 grid points"), "{err}");
    let err = fails(&["sweep", "--over", "lens.f_number=2:3:2", "--over", "lens.f_number=4:5:2", "--csv"]);
    assert!(err.contains("--over lens.f_number: the key is given to --over twice"), "{err}");
    let err = fails(&["sweep", "--set", "lens.f_number=2", "--over", "lens.f_number=2:3:2", "--csv"]);
    assert!(err.contains("also given by --set lens.f_number=2"), "{err}");
    let err = fails(&["optimize", "--tolerance", "1e-6", "--over", "options.tolerance=1e-7:1e-5"]);
    assert!(err.contains("--over options.tolerance") && err.contains("--tolerance"), "{err}");
    let out = asnr(&["sweep", "--over", "camera.full_well_e=1e3:1e20:3", "--csv"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(String::from_utf8(out.stdout).unwrap().lines().count(), 4);
}

/// `--threads` is bounded by 4 × the available cores.
#[test]
fn sweep_threads_are_bounded() {
    let err = fails(&["sweep", "--over", "lens.f_number=2:3:2", "--threads", "10000", "--csv"]);
    assert!(err.contains("--threads 10000: expected 0 (all cores) to"), "{err}");
}

/// `--json --explain`: stdout is one JSON document, the explanation its `explain` field.
#[test]
fn json_with_explain_is_one_document() {
    let v = json(&["evaluate", "--json", "--explain"]);
    let lines = v["explain"].as_array().expect("an explain array");
    assert!(lines[0].as_str().unwrap().contains("How this was computed"), "{lines:?}");
    assert!(v["asnr"].is_f64());
}
