//! End-to-end tests of the `asnr` binary: the paper scene, `--set`, `--json`, and bad input.
//!
//! Every bad-input case asserts a non-zero exit, no panic, and a message that names the file (or
//! the `--set`), the key, the value and what is accepted.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;

use common::{asnr, fails, json, stderr};

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/paper-theory.toml");
const TABULATED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/tabulated.toml");
const MONOCHROMATIC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/monochromatic.toml");

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
    assert!(err.contains("scene.toml: lens.fnumber: unknown field `fnumber`: did you mean `f_number`?"), "{err}");
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
    assert!(err.contains("--wavelengths: -5 nm: expected wavelengths from 1 nm to 1e6 nm"), "{err}");
    // 1e-300 nm printed null in the JSON and NaN in the table
    let err = fails(&["mtf", "--wavelengths", "1e-300", "--json"]);
    assert!(err.contains("--wavelengths: 1e-300 nm: expected"), "{err}");
    // a band reaching 0 nm: the cutoff is infinite (the message said `max_frequency = inf`)
    let err = fails(&["mtf", "--to-cutoff", "--set", "spectrum.range_nm=3000"]);
    assert!(
        err.contains("cutoff 1/(λ F#)") && err.contains("reaches λ = 0 nm") && !err.contains("max_frequency"),
        "{err}"
    );
    // internal names: `sigma` for spectrum.range_nm; NaN reported as no signal
    let err = fails(&["evaluate", "--set", "spectrum.range_nm=1e-300"]);
    assert!(
        err.contains("spectrum.range_nm = 1e-300: expected a width of at least") && !err.contains("sigma"),
        "{err}"
    );
    let err = fails(&["evaluate", "--set", "spectrum.range_nm=1e200"]);
    assert!(err.contains("overflows") && !err.contains("no detected signal"), "{err}");
    // an --over point named as --over, not as --set
    let err = fails(&["sweep", "--over", "lens.f_number=0.1:2:3"]);
    assert!(err.contains("(--over lens.f_number=0.1:2:3 at lens.f_number=0.1)") && !err.contains("--set"), "{err}");
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
fn off_axis_field_reports_the_tangential_sagittal_split() {
    let v = json(&["evaluate", "--set", "field.x_deg=8", "--json"]);
    let (r, t) = (v["mean_mtf_tangential"].as_f64().unwrap(), v["mean_mtf_sagittal"].as_f64().unwrap());
    let on_axis = json(&["evaluate", "--json"])["mean_mtf"].as_f64().unwrap();
    // off axis the spectral quadrature (±7σ window), on axis the closed form: 2.4e-12 apart
    assert!(r < t && (t - on_axis).abs() < 1e-9, "{r} {t} {on_axis}");
    let out = asnr(&["mtf", "--csv", "--points", "3", "--set", "field.x_deg=8"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.starts_with("frequency_cyc_per_mm,otf,mtf,diffraction_limited,mtf_tangential,mtf_sagittal\n"),
        "{text}"
    );
    let err = fails(&["evaluate", "--set", "field.x_deg=95"]);
    assert!(err.contains("field.x_deg = 95: expected an angle in degrees, within ±90"), "{err}");
}

#[test]
fn decentred_iris_example_is_exact_and_splits_x_and_y() {
    // the decentred circular iris on a defocus-only lens: the centred circle with a tilt, on the
    // exact path, with the tilt's lateral shift making the OTF complex
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/decentred-iris.toml");
    let v = json(&["evaluate", scene, "--json"]);
    assert_eq!(v["numerics"]["engine"], "exact-1d, complex sum with lateral colour");
    assert!(v["mean_mtf_tangential"].as_f64().unwrap() < v["mean_mtf_sagittal"].as_f64().unwrap());
    let out = asnr(&["mtf", scene, "--csv", "--points", "5"]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.starts_with("frequency_cyc_per_mm,otf,mtf,diffraction_limited,mtf_tangential,mtf_sagittal\n"),
        "{text}"
    );
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
    assert!(err.contains("--xtol 2: expected a fraction of the range in [1e-12, 1)"), "{err}");
    // a bracket below the float spacing could never close: refused at once, not run for ever
    let err = fails(&["optimize", "--over", "spectrum.range_nm=1:200", "--xtol", "1e-17"]);
    assert!(err.contains("--xtol 1e-17: expected a fraction of the range in [1e-12, 1)"), "{err}");
}

// ---- asnr gradient ----

/// `asnr gradient --json` has the documented fields, its ASNR is `asnr evaluate`'s, and with
/// shot noise alone ∂ASNR/∂t = ASNR/(2t) (SNR0 = √N, N ∝ t).
#[test]
fn gradient_json_has_the_documented_fields() {
    let t = 2.0;
    let set = ["--set", "exposure.time_ms=2"];
    let v = json(
        &[&["gradient", "--wrt", "exposure.time_ms", "--wrt", "camera.pixel_pitch_um", "--json"][..], &set].concat(),
    );
    let evaluated = json(&[&["evaluate", "--json"][..], &set].concat());
    assert_eq!(v["asnr"], evaluated["asnr"]);
    for field in ["mean_mtf", "snr0", "photoelectrons"] {
        assert!(v[field].is_f64(), "{field}: {v}");
    }
    for field in ["gradient", "mean_mtf_gradient", "snr0_gradient", "photoelectrons_gradient"] {
        assert_eq!(v[field].as_object().unwrap().len(), 2, "{field}: {v}");
    }
    let d = v["gradient"]["exposure.time_ms"].as_f64().unwrap();
    let value = v["asnr"].as_f64().unwrap();
    assert!((d - value / (2.0 * t)).abs() < 1e-12 * d, "{d} vs {}", value / (2.0 * t));
    let text = asnr(&["gradient", "--wrt", "exposure.time_ms"]);
    let out = String::from_utf8_lossy(&text.stdout);
    assert!(out.contains("exposure.time_ms") && out.contains("0.500000"), "{out}");
}

#[test]
fn bad_gradient_keys_are_refused_naming_the_key() {
    let err = fails(&["gradient", "--wrt", "lens.colour"]);
    assert!(err.contains("--wrt lens.colour") && err.contains("no such key"), "{err}");
    let err = fails(&["gradient", "--wrt", "exposure.time_ms", "--wrt", "exposure.time_ms"]);
    assert!(err.contains("exposure.time_ms is given twice"), "{err}");
    let library = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/library.toml");
    let err = fails(&["gradient", library, "--wrt", "lens.design_wavelength_nm"]);
    assert!(err.contains("--wrt lens.design_wavelength_nm: not differentiable here yet"), "{err}");
    let err = fails(&["gradient", "--wrt", "options.tolerance"]);
    assert!(err.contains("--wrt options.tolerance: not differentiable"), "{err}");
    let err = fails(&["gradient", "--wrt", "camera.read_noise_e", "--set", "lens.colour=1"]);
    assert!(err.contains("colour"), "{err}");
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
    assert_eq!(lines[0], "lens.f_number,spectrum.range_nm,mean_mtf,snr0,asnr,photoelectrons,fraunhofer_valid,warnings");
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
    // the ADC's black level: below its largest output, and only with an ADC
    let err = fails(&[
        "evaluate",
        "--set",
        "camera.gain_dn_per_e=0.5",
        "--set",
        "camera.adc_bits=12",
        "--set",
        "camera.black_level_dn=5000",
    ]);
    assert!(
        err.contains(
            "camera.black_level_dn = 5000: expected a black level ≥ 0 DN and below the ADC's largest output 4095 DN"
        ),
        "{err}"
    );
    let err = fails(&["evaluate", "--set", "camera.black_level_dn=10"]);
    assert!(err.contains("a black level needs an ADC"), "{err}");
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

// ---- labels ----

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `asnr` expecting success; returns (stdout, stderr).
fn succeeds(args: &[&str]) -> (String, String) {
    let out = asnr(args);
    assert!(out.status.success(), "args {args:?}: {}", stderr(&out));
    (stdout(&out), stderr(&out))
}

/// With read noise (and dark current) the SNR0 line names the terms that went into it and the
/// budget, never "shot-noise limited"; JSON says which terms; the ideal sensor keeps SI eq. S9.
#[test]
fn labels_snr0_names_the_noise_terms() {
    let read = ["--set", "camera.read_noise_e=3", "--set", "camera.dark_current_e_per_s=100"];
    let (text, _) = succeeds(&[&["evaluate", "--explain"][..], &read].concat());
    assert!(!text.contains("shot-noise limited"), "{text}");
    assert!(text.contains("SNR0 = N/√(N + σ_r² + D·t)") && text.contains("shot + read 3.0 e⁻ + dark 0.123"), "{text}");
    assert!(text.contains("noise budget, e⁻²") && text.contains("read 9.000 ("), "{text}");
    assert!(text.contains("noise        white noise: ASNR = SNR0 · mean MTF (eq. 1)"), "{text}");
    let v = json(&[&["evaluate", "--json"][..], &read].concat());
    assert_eq!(v["noise"]["shot_noise_limited"], false);
    assert_eq!(v["noise"]["terms"], serde_json::json!(["shot", "read", "dark"]));
    assert_eq!(v["noise"]["read_noise_e"], 3.0);
    let n = v["photoelectrons"].as_f64().unwrap();
    let total = v["noise"]["total_variance_e2"].as_f64().unwrap();
    assert!(
        (total - (n + 9.0 + 0.123)).abs() < 1e-9 * total
            && (v["snr0"].as_f64().unwrap() - n / total.sqrt()).abs() < 1e-12
    );
    // glare included (SI eq. S14) with read noise: its own line, also naming the read noise
    let (text, _) = succeeds(&["evaluate", "--set", "camera.read_noise_e=3", "--set", "options.glare=included"]);
    assert!(
        text.contains("SNR0 = N/√(N_T + σ_r²)") && text.contains("SI eq. S14") && text.contains("read 3.0 e⁻"),
        "{text}"
    );
    // the ideal sensor: shot-noise limited, as before
    let (text, _) = succeeds(&["evaluate", "--explain"]);
    assert!(text.contains("SNR0 = √N") && text.contains("shot-noise limited (SI eq. S9)"), "{text}");
    assert!(!text.contains("noise budget"), "{text}");
    assert_eq!(json(&["evaluate", "--json"])["noise"]["shot_noise_limited"], true);
}

/// Zemax and Code V's names: off axis, lateral colour degrades the TANGENTIAL MTF (frequencies
/// along the field direction); the sagittal one (across it) equals the on-axis MTF
/// (README: 0.439 on axis, 0.295 along the field at 8°).
#[test]
fn labels_tangential_is_along_the_field() {
    let v = json(&["evaluate", "--set", "field.x_deg=8", "--json"]);
    let (t, s) = (v["mean_mtf_tangential"].as_f64().unwrap(), v["mean_mtf_sagittal"].as_f64().unwrap());
    let on_axis = json(&["evaluate", "--json"])["mean_mtf"].as_f64().unwrap();
    assert!(t < s - 0.1 && (s - on_axis).abs() < 1e-9, "{t} {s} {on_axis}");
    assert!((t - 0.295).abs() < 1e-3 && (on_axis - 0.439).abs() < 1e-3, "{t} {on_axis}");
    assert!(v.get("mean_mtf_radial").is_none(), "{v}");
    let (text, _) = succeeds(&["evaluate", "--set", "field.x_deg=8"]);
    assert!(text.contains("tangential / sagittal       0.294743   / 0.438848"), "{text}");
    let c = json(&["mtf", "--json", "--points", "5", "--set", "field.x_deg=8"]);
    let at = |k: &str| c[k][4].as_f64().unwrap();
    assert!(at("mtf_tangential") < at("mtf_sagittal"), "{c}");
    assert!(c.get("mtf_radial").is_none());
    let (text, _) = succeeds(&["mtf", "--points", "5", "--set", "field.x_deg=8"]);
    assert!(text.contains("tangential") && text.contains("sagittal"), "{text}");
    // the headline curve is the mean over azimuth, as the mean MTF is, its source named
    assert!(text.contains("mean over azimuth at field (8°, 0°) (images shifted apart by wavelength"), "{text}");
}

/// A Gaussian cut by a source table's range is reported with that range, and the fraction lost
/// below and above it (σ = 200/(2√2) nm: Φ(−70/σ) = 0.1611, Φ(−60/σ) = 0.1981), not as λ ≤ 0.
#[test]
fn labels_truncation_by_a_table_names_its_range() {
    let dir = scratch("labels-led");
    let mut csv = String::from("wavelength_nm,radiance\n");
    for w in (470..=600).step_by(10) {
        csv.push_str(&format!("{w},0.02\n"));
    }
    std::fs::write(dir.join("led.csv"), csv).unwrap();
    let text = std::fs::read_to_string(PAPER)
        .unwrap()
        .replacen("kind = \"flat\"", "kind = \"table\"\ncsv = \"led.csv\"", 1)
        .replacen("radiance_w_m2_sr_nm = 0.025", "", 1)
        .replacen("center_nm = 800.0", "center_nm = 540.0", 1)
        .replacen("range_nm = 50.0", "range_nm = 200.0", 1);
    let scene = dir.join("led.toml");
    std::fs::write(&scene, text).unwrap();
    let (_, err) = succeeds(&["evaluate", scene.to_str().unwrap()]);
    assert!(!err.contains("λ ≤ 0"), "{err}");
    assert!(err.contains("the radiance's Gaussian factor (centre 540.0 nm, σ 70.7 nm)"), "{err}");
    assert!(err.contains("is cut to the 470.0–600.0 nm the radiance covers"), "{err}");
    assert!(
        err.contains("3.592e-1 of its area was cut off (1.611e-1 below 470.0 nm, 1.981e-1 above 600.0 nm)"),
        "{err}"
    );
}

/// The scene title: in the text report, the JSON, and the MTF plot's caption (falling back to
/// the lens without a title); a sweep's plot says what was swept instead.
#[test]
fn labels_scene_title_is_shown() {
    let (text, _) = succeeds(&["evaluate"]);
    assert!(text.contains("\ntitle      Paper theory model: chromatic metalens F/2.5"), "{text}");
    let v = json(&["evaluate", "--set", "title=\"Labels caption\"", "--json"]);
    assert_eq!(v["title"], "Labels caption");
    let m = json(&["mtf", "--json", "--points", "3", "--set", "title=\"Labels caption\""]);
    assert_eq!(m["title"], "Labels caption");
    assert_eq!(m["mtf_is"], "on axis");
    let dir = scratch("labels-title");
    let svg = dir.join("mtf.svg");
    succeeds(&["mtf", "--points", "11", "--set", "title=\"Labels caption\"", "--plot", svg.to_str().unwrap()]);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("Labels caption"));
    let svg = dir.join("sweep.svg");
    let over = ["--over", "spectrum.range_nm=10:50:3"];
    succeeds(&[&["sweep", "--set", "title=\"Labels caption\"", "--plot", svg.to_str().unwrap()][..], &over].concat());
    // a sweep's plot is captioned by what it swept (the scene's title states the one band or
    // F-number the sweep replaces)
    let drawn = std::fs::read_to_string(&svg).unwrap();
    assert!(drawn.contains("ASNR over spectral range 10–50 nm") && !drawn.contains("Labels caption"), "{drawn}");
    // no title: null in the JSON; the MTF plot is captioned with the lens, never a file path
    let untitled = edited_paper(&dir, "title = \"Paper theory model", "# title = \"Paper theory model");
    assert_eq!(json(&["evaluate", untitled.to_str().unwrap(), "--json"])["title"], serde_json::Value::Null);
    let svg = dir.join("untitled.svg");
    succeeds(&["mtf", untitled.to_str().unwrap(), "--points", "11", "--plot", svg.to_str().unwrap()]);
    let drawn = std::fs::read_to_string(&svg).unwrap();
    assert!(drawn.contains("chromatic metalens F/2.5") && !drawn.contains("scene.toml"), "{drawn}");
}

/// `mtf` on a `[[fields]]` scene shows every field point's curves and says the headline curve is
/// their weighted mean.
#[test]
fn labels_mtf_over_fields_keeps_every_field_point() {
    let dir = scratch("labels-fields");
    let fields = "[[fields]]\nx_deg = 0\nweight = 1\n\n[[fields]]\nx_deg = 8\nweight = 3\n\n[camera]";
    let scene = edited_paper(&dir, "[camera]", fields);
    let scene = scene.to_str().unwrap();
    let c = json(&["mtf", scene, "--json", "--points", "5"]);
    let points = c["field_points"].as_array().unwrap();
    assert_eq!(points.len(), 2);
    assert_eq!(points[1]["field_deg"], serde_json::json!([8.0, 0.0]));
    assert!(c["mtf_is"].as_str().unwrap().starts_with("weighted mean over 2 field points"), "{}", c["mtf_is"]);
    let f = |v: &serde_json::Value| v[4].as_f64().unwrap();
    assert!(points[0]["mtf_tangential"].is_null());
    assert!(f(&points[1]["mtf_tangential"]) < f(&points[1]["mtf_sagittal"]));
    let mean = 0.25 * f(&points[0]["mtf"]) + 0.75 * f(&points[1]["mtf"]);
    assert!((f(&c["mtf"]) - mean).abs() < 1e-12, "{} vs {mean}", c["mtf"]);
    let (text, _) = succeeds(&["mtf", scene, "--csv", "--points", "3"]);
    assert!(
        text.starts_with(
            "frequency_cyc_per_mm,otf,mtf,diffraction_limited,mtf_tangential,mtf_sagittal,fields[0].mtf,\
             fields[1].mtf,fields[1].mtf_tangential,fields[1].mtf_sagittal\n"
        ),
        "{text}"
    );
    let (text, _) = succeeds(&["mtf", scene, "--points", "3"]);
    assert!(text.contains("MTF: weighted mean over 2 field points"), "{text}");
    assert!(
        text.contains("fields[1] (8°, 0°) × 3") && text.contains("[1] tang.") && text.contains("[0] MTF"),
        "{text}"
    );
    let svg = dir.join("fields.svg");
    succeeds(&["mtf", scene, "--points", "11", "--plot", svg.to_str().unwrap()]);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("weighted mean of 2 field points"));
    // evaluate lists each point's tangential and sagittal means
    let (text, _) = succeeds(&["evaluate", scene]);
    assert!(text.contains("(tangential 0.294743 / sagittal 0.438848)"), "{text}");
}

/// The sweep table marks Fraunhofer-invalid points, stderr carries the points' warnings (the
/// first five and a count), CSV and JSON carry validity and warnings.
#[test]
fn labels_sweep_marks_invalid_points_and_warns() {
    let over = ["--over", "spectrum.range_nm=50:650:2"];
    let (text, err) = succeeds(&[&["sweep"][..], &over].concat());
    assert!(text.contains("* invalid") && text.contains("Fraunhofer 1 of the 2 points NOT valid"), "{text}");
    assert!(err.contains("warning: at spectrum.range_nm=650: ") && err.contains("Fraunhofer threshold"), "{err}");
    assert!(!err.contains("spectrum.range_nm=50:"), "{err}");
    let (csv, _) = succeeds(&[&["sweep", "--csv"][..], &over].concat());
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].ends_with(",fraunhofer_valid,warnings"), "{csv}");
    assert!(lines[1].ends_with(",true,") && lines[2].contains(",false,\"") && lines[2].contains("Fraunhofer"), "{csv}");
    let v = json(&[&["sweep", "--json"][..], &over].concat());
    assert_eq!(v[0]["warnings"], serde_json::json!([]));
    assert!(v[1]["fraunhofer_valid"] == false && !v[1]["warnings"].as_array().unwrap().is_empty(), "{v}");
    // many warnings: the first five, then a count
    let (_, err) = succeeds(&["sweep", "--over", "spectrum.range_nm=600:700:4"]);
    assert_eq!(err.lines().filter(|l| l.starts_with("warning: at ")).count(), 5, "{err}");
    assert!(err.contains("… and 3 more warnings (4 of the 4 points have warnings"), "{err}");
}

/// `optimize` warns (stderr, JSON `at_bound`) when the best value is on the search bound, and
/// says how it found it.
#[test]
fn labels_optimize_warns_at_the_bound() {
    let out = asnr(&["optimize", "--over", "spectrum.range_nm=1:10", "--xtol", "1e-3"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("at the bound HI = 10") && err.contains("the maximum may lie outside LO:HI"), "{err}");
    let text = stdout(&out);
    assert!(text.contains("golden-section search after a 17-point scan") && text.contains("AT THE BOUND"), "{text}");
    let v = json(&["optimize", "--over", "spectrum.range_nm=1:10", "--xtol", "1e-3", "--json"]);
    assert_eq!(v["at_bound"], true);
    assert!(v["method"].as_str().unwrap().starts_with("golden-section search"), "{v}");
    let out = asnr(&["optimize", "--over", "spectrum.range_nm=1:200", "--xtol", "1e-3", "--json"]);
    assert!(!stderr(&out).contains("warning"), "{}", stderr(&out));
    assert_eq!(serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()["at_bound"], false);
}

/// The three "best" values of one curve are named apart: the sweep's best grid point, its
/// parabola refinement (also the plot legend's), and optimize's golden section.
#[test]
fn labels_best_values_say_how_they_were_found() {
    let dir = scratch("labels-best");
    let svg = dir.join("line.svg");
    let (text, _) = succeeds(&["sweep", "--over", "spectrum.range_nm=10:100:7", "--plot", svg.to_str().unwrap()]);
    assert!(text.contains("best of the grid points                 ASNR"), "{text}");
    assert!(text.contains("refined between grid points (parabola) ASNR"), "{text}");
    assert!(std::fs::read_to_string(&svg).unwrap().contains("(parabola between grid points)"));
    // the grid's best at an end of the range is flagged
    let (text, _) = succeeds(&["sweep", "--over", "spectrum.range_nm=1:10:3"]);
    assert!(text.contains("(at the end of the spectrum.range_nm range: the maximum may lie outside it)"), "{text}");
    assert!(!text.contains("refined between grid points"), "{text}");
}

// ---- scene input ----

/// `asnr scene` prints the scene as read, every default filled in and CSV paths resolved, and
/// that text loads again to the same ASNR (from another folder: the paths are absolute).
#[test]
fn scene_prints_the_resolved_scene_and_it_loads_to_the_same_asnr() {
    let dir = scratch("resolved");
    for (name, scene) in [("paper", PAPER), ("tabulated", TABULATED)] {
        let out = asnr(&["scene", scene]);
        assert!(out.status.success(), "{}", stderr(&out));
        let text = String::from_utf8(out.stdout).unwrap();
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, &text).unwrap();
        let again = json(&["evaluate", path.to_str().unwrap(), "--json"]);
        let direct = json(&["evaluate", scene, "--json"]);
        assert_eq!(again["asnr"], direct["asnr"], "{name}:\n{text}");
        assert_eq!(again["mean_mtf"], direct["mean_mtf"], "{name}");
        for line in [
            "model = \"chromatic\"",
            "pixel_mtf = false",
            "form = \"mean\"",
            "glare = \"first_order\"",
            "# tolerance: not set, so 1e-6 (and 1e-4 on the FFT path)",
            "fraunhofer_threshold_mm = 0.25",
            "fraunhofer_max_fraction = 0.01",
            "# pupil_samples: not set, so the FFT path chooses its sampling from the tolerance",
            "iris_decentre_x = 0.0",
            "x_deg = 0.0",
            "y_deg = 0.0",
        ] {
            assert!(text.lines().any(|l| l == line), "{name}: no `{line}` in\n{text}");
        }
    }
    // the paper: transmission given, peak filled in
    let text = String::from_utf8(asnr(&["scene", PAPER, "--set", "lens.f_number=2.8"]).stdout).unwrap();
    assert!(text.contains("\nf_number = 2.8\n") && text.contains("\npeak = 1.0\n"), "{text}");
    // transmission defaults to the efficiency; a CSV path resolves against the scene's folder
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/data/cmos-qe.csv");
    let data = std::path::absolute(data).unwrap();
    let out = asnr(&["scene", PAPER, "--set", "lens.transmission=0.15"]);
    assert!(String::from_utf8(out.stdout).unwrap().contains("\ntransmission = 0.15\n"));
    let text = String::from_utf8(asnr(&["scene", TABULATED]).stdout).unwrap();
    let qe = format!("quantum_efficiency = \"{}\"", data.display());
    assert!(text.contains(&qe), "no `{qe}` in\n{text}");
}

/// `--set lens.f_number 2.8` (no `=`): clap takes `2.8` as the scene path; the message says to
/// write `--set lens.f_number=2.8` instead of "cannot read the scene file 2.8".
#[test]
fn set_without_equals_is_named_before_the_scene_is_read() {
    let expected = "--set lens.f_number: expected KEY=VALUE (write --set lens.f_number=2.8)";
    for cmd in [
        vec!["evaluate", "--set", "lens.f_number", "2.8"],
        vec!["scene", "--set", "lens.f_number", "2.8"],
        vec!["mtf", "--set", "lens.f_number", "2.8"],
        vec!["sweep", "--set", "lens.f_number", "2.8", "--over", "spectrum.range_nm=10:20:2"],
        vec!["optimize", "--set", "lens.f_number", "2.8", "--over", "spectrum.range_nm=10:20"],
    ] {
        let err = fails(&cmd);
        assert!(err.contains(expected) && !err.contains("cannot read"), "{cmd:?}: {err}");
    }
}

/// A string with a unit where a number belongs (`800nm`, in the file or by --set) says which
/// number to write, in the key's unit; `15%` for a fraction says 0.15.
#[test]
fn a_number_with_its_unit_says_what_to_write() {
    let err = fails(&["evaluate", "--set", "spectrum.center_nm=800nm"]);
    assert!(
        err.contains(
            "(--set spectrum.center_nm=800nm): spectrum.center_nm = \"800nm\": expected a number in nm (write 800, not \"800nm\")"
        ),
        "{err}"
    );
    let dir = scratch("unit-string");
    let path = edited_paper(&dir, "pixel_pitch_um = 5.2", "pixel_pitch_um = \"5.2 um\"");
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(
        err.contains(
            "scene.toml: camera.pixel_pitch_um = \"5.2 um\": expected a number in µm (write 5.2, not \"5.2 um\")"
        ),
        "{err}"
    );
    let err = fails(&["evaluate", "--set", "exposure.time_ms=1.23ms"]);
    assert!(err.contains("expected a number in ms (write 1.23, not \"1.23ms\")"), "{err}");
    let err = fails(&["evaluate", "--set", "lens.efficiency=15%"]);
    assert!(
        err.contains("lens.efficiency = \"15%\": expected a fraction in [0, 1] (write 0.15, not \"15%\")"),
        "{err}"
    );
}

/// The iris decentre accepts the open interval (−1, 1) on both sides (−1 was accepted, +1
/// refused); a decentre of 0 is the default pupil, on the exact path (it went to the FFT path).
#[test]
fn iris_decentre_is_open_on_both_sides_and_zero_is_the_default() {
    for key in ["lens.iris_decentre_x", "lens.iris_decentre_y"] {
        for v in ["-1", "1"] {
            let err = fails(&["evaluate", "--set", &format!("{key}={v}")]);
            assert!(
                err.contains(&format!("{key} = {v}: expected a fraction of the aperture radius in (−1, 1)")),
                "{err}"
            );
        }
    }
    let default = json(&["evaluate", "--json"]);
    let zero = json(&["evaluate", "--set", "lens.iris_decentre_x=0", "--set", "lens.obscuration=0", "--json"]);
    assert_eq!(zero["asnr"], default["asnr"]);
    assert_eq!(zero["numerics"]["engine"], default["numerics"]["engine"]);
}

/// Values that are valid but almost surely a unit slip load with a warning naming key, value
/// and the likely unit; the paper scene has none.
#[test]
fn unit_slips_are_warned_about() {
    for (set, warning) in [
        ("camera.pixel_pitch_um=0.0052", "camera.pixel_pitch_um = 0.0052: below 0.1 µm: looks like mm (5.2 µm?)"),
        ("camera.pixel_pitch_um=5200", "camera.pixel_pitch_um = 5200: above 100 µm: looks like nm (5.2 µm?)"),
        ("lens.focal_length_mm=0.00336", "lens.focal_length_mm = 0.00336: below 0.01 mm: looks like m (3.36 mm?)"),
        ("lens.design_wavelength_nm=0.8", "lens.design_wavelength_nm = 0.8: below 100 nm: looks like µm (800 nm?)"),
        ("spectrum.center_nm=8e-7", "spectrum.center_nm = 8e-7: below 100 nm: looks like m (800 nm?)"),
        ("exposure.time_ms=1230000000", "exposure.time_ms = 1230000000: above 10000000 ms (2.8 h): looks like µs"),
    ] {
        let out = asnr(&["scene", "--set", set]);
        let err = stderr(&out);
        assert!(out.status.success(), "{set}: {err}");
        assert!(err.contains(&format!("warning: embedded paper scene (--set {set}): {warning}")), "{set}: {err}");
    }
    let out = asnr(&["scene"]);
    assert!(out.status.success() && out.stderr.is_empty(), "{}", stderr(&out));
}

/// CSV tables: a first row that starts with a number is data (`700,nan` was dropped as a
/// header); a semicolon- or tab-separated table is named as such (it said "1 columns").
#[test]
fn csv_first_rows_and_separators() {
    let dir = scratch("csv-input");
    let path = edited_paper(&dir, "quantum_efficiency = 0.2", "quantum_efficiency = \"qe.csv\"");
    for (table, needle) in [
        ("700,nan\n800,0.2\n900,0.2\n", "line 1: `700,nan` is not a pair of finite numbers: `nan` is not finite"),
        ("700,0.1S\n800,0.2\n900,0.2\n", "line 1: `700,0.1S` is not a pair of finite numbers: `0.1S` is not a number"),
        ("wavelength_nm;qe\n700;0.2\n800;0.2\n", "line 1: `wavelength_nm;qe` is separated by ';'"),
        ("700\t0.2\n800\t0.2\n", "is separated by tab; expected comma-separated `wavelength_nm, value`"),
    ] {
        std::fs::write(dir.join("qe.csv"), table).unwrap();
        let err = fails(&["evaluate", path.to_str().unwrap()]);
        assert!(
            err.contains("scene.toml: camera.quantum_efficiency = \"qe.csv\": ") && err.contains("qe.csv: line"),
            "{err}"
        );
        assert!(err.contains(needle), "{table:?}: {err}");
    }
}

/// A 30 MB one-line garbage scene echoed 60 MB to stderr; a binary file gave "stream did not
/// contain valid UTF-8". Both now give a short message naming the file.
#[test]
fn long_and_binary_scene_files_give_short_messages() {
    let dir = scratch("garbage");
    let path = dir.join("garbage.toml");
    std::fs::write(&path, "x".repeat(30_000_000)).unwrap();
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.len() < 400, "{} bytes", err.len());
    assert!(
        err.contains("garbage.toml: malformed TOML at line 1") && err.contains("(a line of 30000000 bytes)"),
        "{err}"
    );
    let text = std::fs::read_to_string(PAPER)
        .unwrap()
        .replace("shape = \"gaussian\"", &format!("shape = \"{}\"", "g".repeat(1 << 20)));
    std::fs::write(&path, text).unwrap();
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(err.len() < 400 && err.contains("spectrum.shape = \"ggg") && err.contains("… (1048576 bytes)\""), "{err}");
    let path = dir.join("image.toml");
    std::fs::write(&path, b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR").unwrap();
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    assert!(
        err.contains("image.toml: not a text file") && err.contains("expected a scene file in UTF-8 text"),
        "{err}"
    );
    // an endless file is refused after 64 MiB, not read until the memory is full
    if Path::new("/dev/zero").exists() {
        let err = fails(&["evaluate", "/dev/zero"]);
        assert!(err.contains("/dev/zero: more than 64 MiB: expected a scene file"), "{err}");
    }
}

/// `--set lens.f_number=2.8#x` is TOML with a comment: the `#x` was dropped silently.
#[test]
fn set_with_a_trailing_comment_is_refused() {
    let err = fails(&["evaluate", "--set", "lens.f_number=2.8 # faster"]);
    assert!(err.contains("--set lens.f_number=2.8 # faster: `#` starts a TOML comment"), "{err}");
    let v = json(&["evaluate", "--set", "title=\"F/2.8 # one\"", "--json"]);
    assert!(v["asnr"].as_f64().is_some());
}

/// A key given twice (two --set, or --set and --tolerance/--over) kept the last silently.
#[test]
fn a_key_given_twice_is_refused() {
    let err = fails(&["evaluate", "--set", "lens.f_number=2", "--set", "lens.f_number=3"]);
    assert!(
        err.contains("--set lens.f_number=3: lens.f_number is given twice (also by --set lens.f_number=2)"),
        "{err}"
    );
    let err = fails(&["evaluate", "--set", "options.tolerance=1e-4", "--tolerance", "1e-3"]);
    assert!(err.contains("options.tolerance is given twice"), "{err}");
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

// ---- asnr compare ----

const DESIGNS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/designs.toml");
const HARMONIC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/harmonic.toml");
/// A small grid of spectral ranges: the tests run in a debug build.
const SMALL_GRID: &str = "spectrum.range_nm=10:200:4";
/// The tolerance of the comparisons' tests (`--tolerance`): each design's evaluations on the
/// same engines and rules as at the default 1e-6, in fewer panels and pupil samples. Of the
/// embedded comparison's time in a debug build nearly all is two designs' (`asnr compare FILE
/// --threads 1` of each design alone): the tabulated lens (80 % of it reading its table,
/// `OtfTable::blend` and `interpolate`, at every frequency and wavelength node; 14 of its 18
/// evaluations the golden section's about its best band, 47 nm) and the segmented lens (the FFT
/// path, three channels each searched beside the scene's band); the five others take 0.1 s
/// together. At 1e-4 the comparison over [`SMALL_GRID`] takes 5.9–6.9 s of CPU against
/// 9.4–10.2 s at 1e-6 (`asnr compare examples/designs.toml --json --over spectrum.range_nm=10:200:4`,
/// debug build, two runs each under a load of 10–15).
const COMPARE_TOLERANCE: &str = "1e-4";

/// The paper scene with its `[lens]` table replaced by `lens`, written into `dir` as `name`.
fn with_lens(dir: &Path, name: &str, lens: &str) -> PathBuf {
    let text = std::fs::read_to_string(PAPER).unwrap();
    let (start, end) = (text.find("[lens]").unwrap(), text.find("[source]").unwrap());
    let path = dir.join(name);
    std::fs::write(&path, format!("{}[lens]\n{lens}\n{}", &text[..start], &text[end..])).unwrap();
    path
}

const REFRACTIVE_LENS: &str =
    "model = \"refractive\"\nf_number = 2.5\nfocal_length_mm = 3.36\ndesign_wavelength_nm = 800\nglass = \"N-BK7\"";
const ACHROMAT_LENS: &str = "model = \"dispersion-engineered\"\naperture_diameter_mm = 0.2\nfocal_length_mm = 3.36\ndesign_band_nm = [750, 850]\ngroup_delay_range_fs = 5\nefficiency = 0.15\ntransmission = 0.55";
const SEGMENTED_LENS: &str = "model = \"multiplexed\"\nlayout = \"segmented\"\nzones = \"concentric\"\nf_number = 2.5\nfocal_length_mm = 3.36\nchannels_nm = [800, 750, 850]\narea_fractions = [0.5, 0.25, 0.25]\nother_channels = \"signal\"\nefficiency = 0.15\ntransmission = 0.55";
const TABULATED_LENS: &str = concat!(
    "model = \"tabulated\"\nmtf = \"",
    env!("CARGO_MANIFEST_DIR"),
    "/../examples/data/paper-chromatic-mtf.csv\"\nf_number = 2.5\nfocal_length_mm = 3.36\ndesign_wavelength_nm = 800\nefficiency = 0.15\ntransmission = 0.55"
);
const INTERLEAVED_LENS: &str = "model = \"multiplexed\"\nlayout = \"interleaved\"\nf_number = 2.5\nfocal_length_mm = 3.36\nchannels_nm = [750, 800, 850]\nefficiency = 0.15\ntransmission = 0.55";

/// Every family loads from a scene file, evaluates, and `asnr scene` writes it back to the same
/// ASNR, bit for bit.
#[test]
fn compare_every_family_loads_evaluates_and_resolves() {
    let dir = scratch("families");
    let files = [
        with_lens(&dir, "refractive.toml", REFRACTIVE_LENS),
        with_lens(&dir, "achromat.toml", ACHROMAT_LENS),
        with_lens(&dir, "interleaved.toml", INTERLEAVED_LENS),
        with_lens(&dir, "segmented.toml", SEGMENTED_LENS),
        with_lens(&dir, "tabulated.toml", TABULATED_LENS),
        PathBuf::from(HARMONIC),
    ];
    for file in &files {
        let file = file.to_str().unwrap();
        // the harmonic lens's six orders are slow in a debug build: a narrow band
        let narrow = ["--set", "spectrum.range_nm=5"];
        // the concentric zones' coherent ring edges make the FFT path converge as 1/N: the
        // default 1e-4 would need N ≈ 3000 (tens of seconds) and is refused within the time
        // budget; 1e-3 takes N ≈ 300
        let loose = ["--set", "options.tolerance=1e-3"];
        let set: &[&str] = if file.ends_with("harmonic.toml") {
            &narrow
        } else if file.ends_with("segmented.toml") {
            &loose
        } else {
            &[]
        };
        let direct = json(&[&["evaluate", file, "--json"], set].concat());
        assert!(direct["asnr"].as_f64().unwrap() > 0.0, "{file}");
        let (text, _) = succeeds(&[&["scene", file], set].concat());
        let again = dir.join("again.toml");
        std::fs::write(&again, &text).unwrap();
        let reloaded = json(&["evaluate", again.to_str().unwrap(), "--json"]);
        assert_eq!(reloaded["asnr"], direct["asnr"], "{file}:\n{text}");
    }
    // the preset fills in the keys not given, and asnr scene says which
    let preset = with_lens(&dir, "preset.toml", "preset = \"paper-chromatic\"\nf_number = 2.8");
    let (text, _) = succeeds(&["scene", preset.to_str().unwrap()]);
    assert!(text.contains("# preset \"paper-chromatic\": design_wavelength_nm, efficiency, focal_length_mm, model, transmission from the preset"), "{text}");
    assert!(text.contains("\nf_number = 2.8\n"), "{text}");
    let direct = json(&["evaluate", "--json", "--set", "lens.f_number=2.8"]);
    assert_eq!(json(&["evaluate", preset.to_str().unwrap(), "--json"])["asnr"], direct["asnr"]);
}

/// Keys out of range, of another family, or unknown: refused naming the key, the value, the
/// model and what is accepted.
#[test]
fn compare_lens_keys_are_refused_with_their_message() {
    let dir = scratch("lens-keys");
    let refractive = with_lens(&dir, "refractive.toml", REFRACTIVE_LENS);
    let r = refractive.to_str().unwrap();
    let cases: [(&[&str], &str); 14] = [
        (
            &["--set", "lens.model=fresnel"],
            "lens.model = \"fresnel\": expected \"chromatic\", \"refractive\", \"dispersion-engineered\", \"harmonic\", \"multiplexed\" (layout \"interleaved\" or \"segmented\"), \"tabulated\" (an MTF table)",
        ),
        (&["--set", "lens.model=fresnel"], "\"psf\" (a PSF stack)"),
        (&["--set", "lens.design_order=3"], "lens.design_order does not apply to lens.model = \"chromatic\""),
        (
            &["--set", "lens.aperture_diameter_mm=1"],
            "lens.f_number and lens.aperture_diameter_mm both given: give one (F# = f0/D)",
        ),
        (&["--set", "lens.channels_nm=[800]"], "lens.channels_nm does not apply to lens.model = \"chromatic\""),
        (&["--set", "lens.glass=N-BK7"], "lens.glass does not apply to lens.model = \"chromatic\""),
        (&["--set", "lens.preset=mine"], "lens.preset = \"mine\": expected the name of a preset: \"paper-chromatic\""),
        (&["--set", "lens.model=harmonic"], "lens.design_order is missing: expected a whole number from 1 to 1000"),
        (
            &["--set", "lens.model=harmonic", "--set", "lens.design_order=0"],
            "lens.design_order = 0: expected a whole number from 1 to 1000",
        ),
        (
            &["--set", "lens.model=dispersion-engineered"],
            "lens.design_wavelength_nm does not apply to lens.model = \"dispersion-engineered\"",
        ),
        (
            &["--set", "lens.model=multiplexed"],
            "lens.design_wavelength_nm does not apply to lens.model = \"multiplexed\"",
        ),
        (&["--set", "lens.model=tabulated"], "lens.mtf is missing: expected the path of an MTF table"),
        (
            &["--set", "lens.iris_decentre_x=0.1", "--set", "lens.model=harmonic"],
            "does not apply to lens.model = \"harmonic\"",
        ),
        (&["--set", "lens.colour=1"], "lens.colour: unknown field `colour`"),
    ];
    for (set, expected) in cases {
        let err = fails(&[&["evaluate", PAPER], set].concat());
        assert!(err.contains(expected), "{set:?}: {err}");
    }
    let refractive_cases: [(&str, &str); 6] = [
        ("lens.glass=F2", "lens.glass = \"F2\": expected \"N-BK7\""),
        ("lens.elements=0", "lens.elements = 0: expected a whole number of thin elements from 1 to 100"),
        ("lens.coating_reflectance=1", "lens.coating_reflectance = 1: expected a reflectance per surface in [0, 1)"),
        ("lens.refractive_index=1.5", "lens.glass and lens.refractive_index both given: give one"),
        ("lens.design_wavelength_nm=3000", "lens.design_wavelength_nm = 3000: expected a wavelength in 300–2500 nm"),
        ("lens.efficiency=0.5", "lens.efficiency does not apply to lens.model = \"refractive\""),
    ];
    for (set, expected) in refractive_cases {
        let err = fails(&["evaluate", r, "--set", set]);
        assert!(err.contains(expected), "{set}: {err}");
    }
    let achromat = with_lens(&dir, "achromat.toml", ACHROMAT_LENS);
    let a = achromat.to_str().unwrap();
    for (set, expected) in [
        (
            "lens.design_band_nm=[850, 750]",
            "lens.design_band_nm = [850, 750]: expected [λ_min, λ_max] in nm, 0 < λ_min < λ_max",
        ),
        (
            "lens.group_delay_range_fs=-1",
            "lens.group_delay_range_fs = -1: expected the meta-atom library's group-delay range > 0 fs",
        ),
        ("lens.delay_overflow=wrap", "lens.delay_overflow = \"wrap\": expected \"reject\""),
        (
            "lens.aperture_diameter_mm=7",
            "lens.aperture_diameter_mm = 7: expected a diameter > 0 mm and ≤ 2 f0 = 6.72 mm",
        ),
    ] {
        let err = fails(&["evaluate", a, "--set", set]);
        assert!(err.contains(expected), "{set}: {err}");
    }
    let interleaved = with_lens(&dir, "interleaved.toml", INTERLEAVED_LENS);
    let i = interleaved.to_str().unwrap();
    for (set, expected) in [
        (
            "lens.channels_nm=[800, 750]",
            "lens.channels_nm[1] = 750: expected 1 to 16 channel wavelengths in nm, each > 0, increasing",
        ),
        (
            "lens.layout=stacked",
            "lens.layout = \"stacked\": expected \"segmented\" (zones side by side) or \"interleaved\"",
        ),
        ("lens.zones=sectors", "lens.zones does not apply to lens.layout = \"interleaved\""),
        ("lens.other_channels=background", "lens.other_channels = \"background\": expected \"signal\""),
        ("lens.channel_efficiencies=[0.1, 0.2]", "lens.efficiency and lens.channel_efficiencies both given"),
        ("lens.transmission=0.01", "exceeds transmission T = 0.01"),
    ] {
        let err = fails(&["evaluate", i, "--set", set]);
        assert!(err.contains(expected), "{set}: {err}");
    }
    let segmented = with_lens(&dir, "segmented.toml", SEGMENTED_LENS);
    let g = segmented.to_str().unwrap();
    for (set, expected) in [
        (
            "lens.area_fractions=[0.5, 0.5, 0.5]",
            "lens.area_fractions = a list summing to 1.5: expected one area fraction per channel",
        ),
        ("lens.area_fractions=[0.5, 0.5]", "lens.area_fractions = a list of 2: expected one area fraction per channel"),
        ("lens.zones=mask", "lens.zone_mask is missing: expected the path of a zone-mask file"),
        (
            "lens.zones=hexagons",
            "lens.zones = \"hexagons\": expected \"concentric\" (rings, the first channel innermost), \"sectors\" (wedges) or \"mask\"",
        ),
        ("lens.zone_mask=zones.txt", "lens.zone_mask does not apply to lens.zones other than \"mask\""),
        ("lens.other_channels=noise", "lens.other_channels = \"noise\": expected \"signal\""),
        (
            "lens.channels_nm=[800, 800, 850]",
            "lens.channels_nm[1] = 800: expected 1 to 16 distinct channel wavelengths",
        ),
    ] {
        let err = fails(&["evaluate", g, "--set", set]);
        assert!(err.contains(expected), "{set}: {err}");
    }
    // other channels as background: the scene builds and evaluates in few spectral panels
    let (text, _) = succeeds(&["scene", g, "--set", "lens.other_channels=background"]);
    assert!(text.contains("\nother_channels = \"background\"\n"), "{text}");
    succeeds(&["evaluate", g, "--set", "lens.other_channels=background", "--set", "options.pupil_samples=64"]);
    // a zone mask: a square grid of zone numbers over the aperture, checked cell by cell
    let masked = SEGMENTED_LENS.replace("zones = \"concentric\"", "zones = \"mask\"\nzone_mask = \"zones.txt\"");
    let masked = with_lens(&dir, "masked.toml", &masked.replace("area_fractions = [0.5, 0.25, 0.25]\n", ""));
    let m = masked.to_str().unwrap();
    let zones = |text: &str| std::fs::write(dir.join("zones.txt"), text).unwrap();
    // left half 800 nm, right half 750 nm, a square core 850 nm
    zones("# a 4 × 4 map over the aperture's square\n1 1 2 2\n1 3 3 2\n1 3 3 2\n1 1 2 2\n");
    let (json, _) = succeeds(&["evaluate", m, "--json", "--set", "options.pupil_samples=64"]);
    assert!(json.contains("\"asnr\""), "{json}");
    let (text, _) = succeeds(&["scene", m]);
    assert!(text.contains("zones = \"mask\"") && text.contains("zones.txt\""), "{text}");
    let err = fails(&["evaluate", m, "--set", "lens.area_fractions=[0.5, 0.25, 0.25]"]);
    assert!(err.contains("lens.area_fractions does not apply to lens.zones = \"mask\""), "{err}");
    for (text, expected) in [
        ("# one row\n1 2 3\n", "1 grid rows: expected a square grid of 2 to 4096 rows"),
        ("1 1 2\n1 3 2\n", "line 1: 3 cells: expected 2, as many as the grid has rows"),
        ("1 1 2\n1 3\n1 3 2\n", "line 2: 2 cells: expected 3, as many as the grid has rows"),
        ("1 4\n2 3\n", "cell 4: expected a zone number 1 to 3"),
        ("1 1\n2 2\n", "the grid's largest zone number is 2 for 3 channels"),
    ] {
        zones(text);
        let err = fails(&["evaluate", m]);
        assert!(err.contains(expected), "{text}: {err}");
    }
    let tabulated = with_lens(&dir, "tabulated.toml", TABULATED_LENS);
    let t = tabulated.to_str().unwrap();
    for (set, expected) in [
        ("lens.mtf=no-such.csv", "lens.mtf = \"no-such.csv\": cannot read the MTF table"),
        ("lens.mtf_includes_pixel_um=-5", "lens.mtf_includes_pixel_um = -5: expected the pitch > 0 µm"),
        ("lens.glass=N-BK7", "lens.glass does not apply to lens.model = \"tabulated\""),
    ] {
        let err = fails(&["evaluate", t, "--set", set]);
        assert!(err.contains(expected), "{set}: {err}");
    }
}

/// The paper's lens as a dispersion-engineered design at 5 fs is refused, with the delay it
/// needs and the largest aperture the library allows; "reduced" accepts it with its β.
#[test]
fn compare_paper_aperture_achromat_is_refused_with_the_group_delay_numbers() {
    let dir = scratch("achromat-reject");
    let lens = ACHROMAT_LENS.replace("aperture_diameter_mm = 0.2", "f_number = 2.5");
    let path = with_lens(&dir, "paper-achromat.toml", &lens);
    let err = fails(&["evaluate", path.to_str().unwrap()]);
    for needle in [
        "lens.group_delay_range_fs = 5: expected at least ΔT_req = 221.96 fs",
        "allows at most D_max = 200.8 µm (F/16.74)",
        "lens.delay_overflow = \"reduced\"",
    ] {
        assert!(err.contains(needle), "no `{needle}` in {err}");
    }
    let reduced = json(&["evaluate", path.to_str().unwrap(), "--json", "--set", "lens.delay_overflow=reduced"]);
    assert!(reduced["asnr"].as_f64().unwrap() > 0.0);
}

/// The JSON has every design with the documented fields; the ranking is one a designer can act
/// on: the refractive reference bounds the chromatic lens of equal aperture, and the reduced
/// achromat is reported with its β and group delays.
#[test]
fn compare_json_fields_kinds_and_ranking() {
    let v = json(&["compare", DESIGNS, "--json", "--over", SMALL_GRID, "--tolerance", COMPARE_TOLERANCE]);
    let designs = v["designs"].as_array().unwrap();
    let kinds = [
        "chromatic",
        "dispersion-engineered",
        "harmonic",
        "multiplexed-segmented",
        "multiplexed-interleaved",
        "refractive",
        "tabulated",
    ];
    for d in designs {
        for key in [
            "name",
            "kind",
            "asnr",
            "mean_mtf",
            "snr0",
            "best_range_nm",
            "best_asnr",
            "photoelectrons",
            "m0",
            "fresnel_zones",
            "twin_band_nm",
            "twin_asnr",
            "asnr_glare_free",
            "asnr_glare_inclusive",
            "rank",
            "curve",
        ] {
            assert!(!d[key].is_null(), "{key} missing in {d}");
        }
        assert!(kinds.contains(&d["kind"].as_str().unwrap()), "{d}");
        assert!(d["asnr_glare_inclusive"].as_f64().unwrap() <= d["asnr_glare_free"].as_f64().unwrap() + 1e-12);
    }
    let by_name = |n: &str| designs.iter().find(|d| d["name"].as_str().unwrap().starts_with(n)).unwrap();
    let (chromatic, refractive) = (by_name("paper chromatic"), by_name("N-BK7 singlet"));
    // the paper's scene at the comparison's tolerance: the same evaluation, bit for bit
    let tolerance = format!("options.tolerance={COMPARE_TOLERANCE}");
    let paper = json(&["evaluate", "--json", "--set", &tolerance]);
    assert_eq!(chromatic["asnr"].as_f64().unwrap(), paper["asnr"].as_f64().unwrap());
    assert!(refractive["asnr"].as_f64().unwrap() >= chromatic["asnr"].as_f64().unwrap());
    assert_eq!(refractive["rank"], 1);
    // the chromatic lens is its own twin; N_z = 84, twin band 4.762 nm
    assert_eq!(chromatic["twin_asnr"], chromatic["asnr"]);
    assert!((chromatic["fresnel_zones"].as_f64().unwrap() - 84.0).abs() < 1e-9);
    let reduced = by_name("achromat F/2.5");
    let notes = reduced["notes"].to_string();
    assert!(notes.contains("ΔT_req = 221.96 fs > ΔT_lib = 5 fs, β = ΔT_lib/ΔT_req = 0.0225"), "{notes}");
    let interleaved = by_name("interleaved");
    assert_eq!(interleaved["kind"], "multiplexed-interleaved");
    assert_eq!(interleaved["channels"].as_array().unwrap().len(), 3);
    assert_eq!(v["ranking"][0], refractive["name"]);
}

/// The table names what was computed; CSV has one row per design; the plot is written; the
/// embedded comparison is the example file.
#[test]
fn compare_table_csv_plot_and_embedded() {
    let dir = scratch("compare-out");
    let svg = dir.join("compare.svg");
    let (table, _) = succeeds(&[
        "compare",
        DESIGNS,
        "--over",
        SMALL_GRID,
        "--tolerance",
        COMPARE_TOLERANCE,
        "--plot",
        svg.to_str().unwrap(),
    ]);
    for needle in [
        "At the scene band",
        "ASNR",
        "mean MTF",
        "SNR0",
        "N (e⁻)",
        "M0",
        "glare-incl.",
        "twin ASNR",
        "best range nm",
        "N_z",
        "λ0/(2N_z) nm",
        "Ranking by ASNR at the scene band: 1. N-BK7 singlet",
        "β = ΔT_lib/ΔT_req",
    ] {
        assert!(table.contains(needle), "no `{needle}` in\n{table}");
    }
    let svg = std::fs::read_to_string(&svg).unwrap();
    assert!(svg.contains("<svg") && svg.contains("paper chromatic F/2.5") && svg.contains("ASNR"));
    // the embedded comparison as CSV: its rows and their order do not depend on the grid, so
    // two points (each design's best at a grid point: no golden section) at the same tolerance
    let (csv, _) =
        succeeds(&["compare", "--csv", "--over", "spectrum.range_nm=10:200:2", "--tolerance", COMPARE_TOLERANCE]);
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("index,name,kind,asnr,mean_mtf,snr0,"), "{csv}");
    let designs = std::fs::read_to_string(DESIGNS).unwrap().matches("[[designs]]").count();
    assert_eq!(lines.len(), 1 + designs, "{csv}");
    // each row's index is its design's place in the file, `designs[i]`, whatever its rank
    for (i, line) in lines[1..].iter().enumerate() {
        assert!(line.starts_with(&format!("{i},")), "row {i}: {line}");
    }
    // the table shows that index beside the rank: the best design is not designs[0]
    assert!(table.contains("[i]: the design's place in the file"), "{table}");
    let first = table.lines().find(|l| l.split_whitespace().next() == Some("1")).expect("a row ranked 1");
    assert_eq!(first.split_whitespace().nth(1), Some("[1]"), "{first}\n{table}");
    assert!(first.contains("N-BK7 singlet"), "{first}\n{table}");
}

#[test]
fn compare_files_and_arguments_are_checked() {
    let dir = scratch("compare-bad");
    // the copies live elsewhere: their table path made absolute
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/data/");
    let text = std::fs::read_to_string(DESIGNS).unwrap().replace("\"data/", &format!("\"{data}"));
    // one design at another focal length
    let other = dir.join("focal.toml");
    std::fs::write(&other, text.replacen("focal_length_mm = 3.36", "focal_length_mm = 4", 1)).unwrap();
    let err = fails(&["compare", other.to_str().unwrap(), "--over", SMALL_GRID]);
    assert!(
        err.contains("a fair comparison keeps the focal length")
            && err.contains("allow_different_focal_lengths = true"),
        "{err}"
    );
    // a design's key by index, refused with its full path; an index past the end
    let err = fails(&["compare", "--set", "designs[1].lens.f_number=0.1", "--over", SMALL_GRID]);
    assert!(err.contains("designs[1].lens.f_number = 0.1: expected a number ≥ 0.5"), "{err}");
    let err = fails(&["compare", "--set", "designs[9].lens.f_number=4"]);
    assert!(err.contains("`designs[9]`: `designs` has"), "{err}");
    let err = fails(&["compare", "--set", "designs[0].lens.design_order=2"]);
    assert!(
        err.contains("designs[0].lens.design_order does not apply to designs[0].lens.model = \"chromatic\""),
        "{err}"
    );
    let err = fails(&["compare", "--over", "lens.f_number=1:4:3"]);
    assert!(err.contains("compare searches the spectral range only"), "{err}");
    // over the limit: refused at once with the numbers (10 000 points used to run for 40 minutes)
    let err = fails(&["compare", "--over", "spectrum.range_nm=2:300:10000"]);
    assert!(err.contains("10000 points; expected at most 1000") && err.contains("some 50 minutes"), "{err}");
    let err = fails(&["compare", "--set", "lens.f_number=2"]);
    assert!(err.contains("a [lens] table would apply to no design"), "{err}");
    // a scene file is not a comparison, and a comparison not a scene
    let err = fails(&["compare", PAPER]);
    assert!(err.contains("a [lens] table would apply to no design"), "{err}");
    let err = fails(&["evaluate", DESIGNS]);
    assert!(err.contains("read it with asnr compare"), "{err}");
    // a design without a name, or two with one name
    let unnamed = dir.join("unnamed.toml");
    std::fs::write(&unnamed, text.replacen("name = \"paper chromatic F/2.5\"", "", 1)).unwrap();
    assert!(fails(&["compare", unnamed.to_str().unwrap()]).contains("designs[0].name is missing"));
    let twice = dir.join("twice.toml");
    std::fs::write(&twice, text.replacen("N-BK7 singlet F/2.5", "paper chromatic F/2.5", 1)).unwrap();
    assert!(fails(&["compare", twice.to_str().unwrap()]).contains("expected a name no other design has"));
}

/// A Zemax FFT MTF listing (as Zemax writes it, UTF-16 LE with a byte-order mark) of a
/// diffraction-limited lens at `wavelength_um`, F/2.5, on axis and at 5°.
fn zemax_export(wavelength_um: f64) -> Vec<u8> {
    use std::fmt::Write as _;
    let mut t = String::from("Listing of FFT MTF Data\r\n\r\nFile : C:\\Lenses\\lens.zmx\r\nTitle: test\r\n\r\n");
    let _ = write!(t, "Data for {wavelength_um:.4} µm.\r\nSpatial Frequency units are cycles per mm.\r\n");
    let cutoff = 1.0 / (wavelength_um * 1e-3 * 2.5);
    for field in ["0.0000 (deg)", "5.0000 (deg)"] {
        let _ = write!(t, "\r\nField: {field}\r\n  Spatial frequency      Tangential        Sagittal\r\n");
        for k in 0..=40 {
            let nu = 10.0 * f64::from(k);
            let s = (nu / cutoff).min(1.0);
            let mtf = 2.0 / std::f64::consts::PI * (s.acos() - s * (1.0 - s * s).sqrt());
            let _ = write!(t, "{nu:>16.6}{mtf:>16.6}{mtf:>16.6}\r\n");
        }
    }
    [0xFF, 0xFE].into_iter().chain(t.encode_utf16().flat_map(u16::to_le_bytes)).collect()
}

/// `lens.mtf` takes one Zemax export or a list of them, one per wavelength (the table holds the
/// wavelengths in their order); a diffraction-limited table gives about the ideal refractive
/// lens's mean MTF; a CSV inside a list is refused by name.
#[test]
fn tabulated_lens_reads_a_list_of_zemax_exports() {
    let dir = scratch("zemax-list");
    // 700–900 nm: the paper scene's 50 nm range (σ = 17.7 nm) has 1.5e-8 of its signal beyond
    // (750–850 nm would leave 0.47 % outside the table, refused)
    for (name, um) in [("z700.txt", 0.7), ("z750.txt", 0.75), ("z800.txt", 0.8), ("z850.txt", 0.85), ("z900.txt", 0.9)]
    {
        std::fs::write(dir.join(name), zemax_export(um)).unwrap();
    }
    let lens = "model = \"tabulated\"\nmtf = [\"z850.txt\", \"z700.txt\", \"z750.txt\", \"z900.txt\", \"z800.txt\"]\nf_number = 2.5\nfocal_length_mm = 3.36\nefficiency = 0.15\ntransmission = 0.55";
    let file = with_lens(&dir, "zemax.toml", lens);
    let f = file.to_str().unwrap();
    let err = fails(&["evaluate", f, "--set", "lens.mtf=[\"z750.txt\", \"z800.txt\", \"z850.txt\"]"]);
    assert!(err.contains("0.4678 % of the signal") && err.contains("outside the table's 750–850 nm"), "{err}");
    let mean = json(&["evaluate", f, "--json"])["mean_mtf"].as_f64().unwrap();
    // the diffraction-limited mean over 0–96 cycles/mm at F/2.5 near 800 nm is 0.876 (the N-BK7
    // singlet of the comparison: 0.87597); the table's 10 cycles/mm rows interpolate it linearly
    assert!((mean - 0.876).abs() < 2e-3, "{mean}");
    let (text, _) = succeeds(&["scene", f]);
    assert!(text.contains("mtf = [\"") && text.contains("z850.txt\", \""), "{text}");
    std::fs::write(dir.join("t.csv"), "wavelength_nm,frequency_cyc_per_mm,mtf\n800,0,1\n800,100,0.5\n").unwrap();
    let err = fails(&["evaluate", f, "--set", "lens.mtf=[\"z750.txt\", \"t.csv\"]"]);
    assert!(err.contains("lens.mtf[1] = \"t.csv\": expected a Zemax export"), "{err}");
    // the 5° field block (index 1) of the same exports: here the same curves, the same result
    let at_field = json(&["evaluate", f, "--json", "--set", "lens.mtf_field=1"])["mean_mtf"].as_f64().unwrap();
    assert_eq!(at_field, mean);
    let (text, _) = succeeds(&["scene", f, "--set", "lens.mtf_field=1"]);
    assert!(text.contains("\nmtf_field = 1\n"), "{text}");
    let err = fails(&["evaluate", f, "--set", "lens.mtf_field=2"]);
    assert!(err.contains("field index = 2") && err.contains("field blocks"), "{err}");
    let err = fails(&["evaluate", f, "--set", "lens.mtf_field=0", "--set", "lens.mtf=t.csv"]);
    assert!(err.contains("lens.mtf_field = 0: expected no field index with a CSV table"), "{err}");
    let err = fails(&["evaluate", f, "--set", "lens.mtf=[\"z750.txt\", \"missing.txt\"]"]);
    assert!(err.contains("lens.mtf[1]") && err.contains("missing.txt"), "{err}");
}

/// A 16-bit grayscale PNG whose left half reads `white` and right half `black`, each plus a
/// deterministic ±`noise` pattern (a third of it on the black half) that changes with `k`.
fn measure_frame(path: &Path, k: usize, white: f64, black: f64, noise: f64) {
    let (w, h) = (32usize, 16usize);
    let mut rng: rand_pcg::Pcg64Mcg = rand::SeedableRng::seed_from_u64(k as u64);
    let bytes: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            let u = rand::RngExt::random::<f64>(&mut rng) - 0.5;
            let level = if i % w < w / 2 { white + 2.0 * noise * u } else { black + 2.0 * noise / 3.0 * u };
            (level.round() as u16).to_be_bytes()
        })
        .collect();
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    encoder.write_header().unwrap().write_image_data(&bytes).unwrap();
}

/// `asnr measure` on a directory of frames: the JSON keys, eq. 2 and 4 against the levels
/// written, VG from capped-black frames; the table names eq. 3's noise terms; bad input exits 1.
#[test]
fn measure_reads_a_stack_and_reports_snr_and_glare() {
    let dir = scratch("measure");
    let stack = dir.join("stack");
    std::fs::create_dir_all(&stack).unwrap();
    for k in 0..10 {
        measure_frame(&stack.join(format!("f{k:02}.png")), k, 30_000.0, 5_000.0, 300.0);
    }
    let capped = dir.join("capped.png");
    measure_frame(&capped, 99, 1_000.0, 1_000.0, 0.0);
    let stack_arg = stack.to_str().unwrap();
    let capped_arg = capped.to_str().unwrap();
    let regions = ["--white", "2,2,12,12", "--black", "18,2,12,12"];
    let v = json(&[&["measure", stack_arg], &regions[..], &["--capped-black", capped_arg, "--json"]].concat());
    for key in ["signal", "sigma_white", "sigma_black", "sigma_signal", "snr", "vg", "frames", "pixels"] {
        assert!(v.get(key).is_some(), "{key} missing: {v}");
    }
    assert_eq!(v["frames"], 10);
    assert_eq!(v["pixels"]["white"], 144);
    let signal = v["signal"].as_f64().unwrap();
    assert!((signal - 25_000.0).abs() < 50.0, "{v}");
    let (sw, sb) = (v["sigma_white"].as_f64().unwrap(), v["sigma_black"].as_f64().unwrap());
    let snr = v["snr"].as_f64().unwrap();
    assert!((snr - signal / (sw * sw - sb * sb).sqrt()).abs() < 1e-9 * snr, "{v}");
    let vg = v["vg"].as_f64().unwrap();
    assert!((vg - 4_000.0 / 29_000.0).abs() < 2e-3, "{v}");
    let (table, _) = succeeds(&[&["measure", stack_arg], &regions[..], &["--include-glare"]].concat());
    assert!(table.contains("σ_s = σ_w: glare and camera noise included") && table.contains("SNR"), "{table}");
    // bad input: a region outside, one frame, no such file
    let err = fails(&[&["measure", stack_arg], &["--white", "2,2,12,12", "--black", "30,2,12,12"][..]].concat());
    assert!(err.contains("black region `30,2,12,12`") && err.contains("32 × 16"), "{err}");
    let one = stack.join("f00.png");
    let err = fails(&[&["measure", one.to_str().unwrap()], &regions[..]].concat());
    assert!(err.contains("1 frame(s)"), "{err}");
    let err = fails(&[&["measure", "/nonexistent/frame.png", "/nonexistent/frame.png"], &regions[..]].concat());
    assert!(err.contains("/nonexistent/frame.png"), "{err}");
}

/// `asnr characterize` on a series file of PNG stacks (frames by `measure_frame`, the left half
/// read: level 100 + K N, variance K² N + σ_d²): K, the slopes, and the table; a level without
/// illumination exits 1 naming it.
#[test]
fn characterize_reads_a_series_file() {
    let dir = scratch("characterize");
    let (k, read_dn) = (0.5, 3.0);
    let mut toml = String::from("region = \"0,0,16,16\"\n");
    for (i, electrons) in [0.0, 100.0, 200.0, 400.0, 800.0, 1600.0, 3200.0].iter().enumerate() {
        let stack = dir.join(format!("s{i}"));
        std::fs::create_dir_all(&stack).unwrap();
        let variance: f64 = k * k * electrons + read_dn * read_dn;
        // uniform noise of half-width a has variance a²/3
        let a = (3.0 * variance).sqrt();
        for f in 0..12 {
            measure_frame(&stack.join(format!("f{f:02}.png")), 1000 * i + f, 100.0 + k * electrons, 100.0, a);
        }
        if i == 0 {
            toml.push_str(&format!("[dark]\nframes = [\"s{i}\"]\n"));
        } else {
            toml.push_str(&format!("[[levels]]\nillumination = {electrons}\nframes = [\"s{i}/*.png\"]\n"));
        }
    }
    let series = dir.join("series.toml");
    std::fs::write(&series, &toml).unwrap();
    let v = json(&["characterize", series.to_str().unwrap(), "--json"]);
    let gain = v["conversion_gain"].as_f64().unwrap();
    assert!((gain / k - 1.0).abs() < 0.1, "{v}");
    assert!((v["stf"]["slope"].as_f64().unwrap() - 1.0).abs() < 0.02, "{v}");
    assert!((v["ptc"]["slope"].as_f64().unwrap() - 0.5).abs() < 0.05, "{v}");
    assert_eq!(v["saturation"], 5, "{v}");
    let (table, _) = succeeds(&["characterize", series.to_str().unwrap()]);
    assert!(table.contains("conversion gain K") && table.contains("0.5 = shot-noise limited"), "{table}");
    // --plot: the STF and PTC panels (SI Fig. S7–S8), each fit's slope in the legend as the JSON has it
    let svg = dir.join("transfer.svg");
    succeeds(&["characterize", series.to_str().unwrap(), "--plot", svg.to_str().unwrap()]);
    let text = std::fs::read_to_string(&svg).unwrap();
    for caption in
        ["(a) signal transfer (STF)", "(b) photon transfer (PTC)", "mean signal (DN)", "temporal noise σ (DN)"]
    {
        assert!(text.contains(caption), "{caption} missing");
    }
    let slope = format!("STF, μ − μ_dark (capped black subtracted): slope {:.4}", v["stf"]["slope"].as_f64().unwrap());
    assert!(text.contains(&slope), "{slope} missing");
    let slope = format!("PTC, raw σ vs μ: slope {:.4}", v["ptc_raw"]["slope"].as_f64().unwrap());
    assert!(text.contains(&slope), "{slope} missing");
    // one filled or hollow dot per level and set: 6 levels × 4 sets, each dot drawn twice (fill and ring)
    assert!(text.matches("<circle").count() >= 48, "{}", text.matches("<circle").count());
    let png = dir.join("transfer.png");
    succeeds(&["characterize", series.to_str().unwrap(), "--plot", png.to_str().unwrap()]);
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    let err = fails(&["characterize", series.to_str().unwrap(), "--plot", dir.join("t.pdf").to_str().unwrap()]);
    assert!(err.contains("--plot") && err.contains("expected a file name ending in .svg or .png"), "{err}");
    std::fs::write(&series, toml.replacen("illumination = 100\n", "", 1)).unwrap();
    let err = fails(&["characterize", series.to_str().unwrap()]);
    assert!(err.contains("levels[0].illumination is missing"), "{err}");
}

/// `asnr render` end to end: every file it announces, the panel, contrast.csv, render.json;
/// its frames measured by `asnr measure` at the regions it prints recover SNR0 (eq. 4; 30
/// frames of 1024 pixels) within 3 of measure's stated standard errors (0.4 %), and bad input.
#[test]
fn render_writes_images_whose_frames_measure_the_scenes_snr0() {
    let dir = scratch("render");
    let out = dir.to_str().unwrap();
    let v = json(&["render", "--out", out, "--ranges", "50,10", "--frames", "30", "--no-glare", "--json"]);
    let ranges = v["ranges"].as_array().unwrap();
    assert_eq!(ranges.len(), 2);
    for name in ["panel.png", "contrast.csv", "render.json", "raw-50nm.png", "restored-10nm-16bit.png"] {
        assert!(dir.join(name).is_file(), "{name} missing");
    }
    let csv = std::fs::read_to_string(dir.join("contrast.csv")).unwrap();
    assert!(csv.starts_with("range_nm,group,element,frequency_cyc_per_mm,orientation"), "{csv}");
    assert_eq!(csv.lines().count(), 1 + 2 * 48, "two ranges × 4 groups × 6 elements × 2 orientations");
    let region = |key: &str| {
        let r = &v[key];
        format!("{},{},{},{}", r["x"], r["y"], r["width"], r["height"])
    };
    let (white, black) = (region("white_region"), region("black_region"));
    let frames = dir.join("frames-50nm");
    let m = json(&["measure", frames.to_str().unwrap(), "--white", &white, "--black", &black, "--json"]);
    assert_eq!(m["frames"], 30);
    let snr0 = ranges[0]["snr0"].as_f64().unwrap();
    let snr = m["snr"].as_f64().unwrap();
    let sigma = m["snr_sigma"].as_f64().unwrap();
    assert!(sigma > 0.0 && sigma < 0.01 * snr0, "{m}");
    assert!((snr - snr0).abs() < 3.0 * sigma, "measured {snr} ± {sigma} against SNR0 {snr0}");
    // bad input names the option, the value and what is accepted
    let err = fails(&["render", "--out", out, "--target", "bars.txt"]);
    assert!(
        err.contains("--target bars.txt") && err.contains("usaf, usaf-negative, slanted-edge or a grayscale .png"),
        "{err}"
    );
    let err = fails(&["render", "--out", out, "--oversample", "2"]);
    assert!(err.contains("oversampling 2") && err.contains("odd"), "{err}");
    let err = fails(&["render", "--out", out, "--groups", "6:x"]);
    assert!(err.contains("--groups 6:x") && err.contains("FIRST:LAST"), "{err}");
    // a group range too large to draw is blamed on --groups, not on an image
    let err = fails(&["render", "--out", out, "--groups", "0:6", "--oversample", "9"]);
    assert!(
        err.contains("--groups 0:6:") && err.contains("a higher first group") && !err.contains("smaller image"),
        "{err}"
    );
    let err = fails(&["render", "--out", out, "--groups", "9:3"]);
    assert!(err.contains("--groups 9:3: USAF groups 9 to 3"), "{err}");
    // an ADC without a black level: the dark areas clip at 0 DN, and render says so; with one
    // (camera.black_level_dn, the scene key) it does not
    let adc = ["--set", "camera.read_noise_e=5", "--set", "camera.gain_dn_per_e=0.5", "--set", "camera.adc_bits=12"];
    let clipped = asnr(&[&["render", "--out", out, "--no-glare", "--target", "usaf-negative"][..], &adc[..]].concat());
    assert!(clipped.status.success(), "{}", stderr(&clipped));
    assert!(
        stderr(&clipped).contains("read 0 DN") && stderr(&clipped).contains("camera.black_level_dn"),
        "{}",
        stderr(&clipped)
    );
    let offset = asnr(
        &[
            &["render", "--out", out, "--no-glare", "--target", "usaf-negative", "--set", "camera.black_level_dn=100"]
                [..],
            &adc[..],
        ]
        .concat(),
    );
    assert!(offset.status.success() && !stderr(&offset).contains("read 0 DN"), "{}", stderr(&offset));
    let err = fails(&["render", "--out", out, "--frames", "0"]);
    assert!(err.contains("--frames 0") && err.contains("1 to 1000"), "{err}");
    let err = fails(&["render", "--out", out, "--ranges=-5"]);
    assert!(err.contains("-5 nm") && err.contains("> 0 nm"), "{err}");
    let err = fails(&["render", "--out", out, "--target", dir.join("none.png").to_str().unwrap()]);
    assert!(err.contains("none.png"), "{err}");
}

/// `asnr psf` and `asnr otf`: the PSF sums to 1, and the OTF's centre row is the polychromatic
/// OTF along x at the grid's frequencies (the scene's own engine, to the 2-D sampling's
/// interpolation error).
#[test]
fn psf_and_otf_export_the_scenes_2d_transfer() {
    let dir = scratch("psf");
    let out = dir.to_str().unwrap();
    let v = json(&["psf", "--out", out, "--size", "64"]);
    assert!((v["sum"].as_f64().unwrap() - 1.0).abs() < 1e-9, "{v}");
    let psf = std::fs::read_to_string(dir.join("psf.csv")).unwrap();
    assert_eq!(psf.lines().count(), 64);
    // the image is a figure (axes, colour bar: RGB, the default 900 px wide), not the bare grid
    let png = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(dir.join("psf.png")).unwrap()));
    let info = png.read_info().unwrap();
    assert_eq!((info.info().width, info.info().color_type), (900, png::ColorType::Rgb));
    let v = json(&["otf", "--out", out, "--size", "64"]);
    let step = v["frequency_step_cyc_per_mm"].as_f64().unwrap() * 1e3;
    let real = std::fs::read_to_string(dir.join("otf-real.csv")).unwrap();
    let centre_row: Vec<f64> = real.lines().nth(32).unwrap().split(',').map(|x| x.parse().unwrap()).collect();
    let scene = scene::load(None, &[]).unwrap();
    let detected = metric::detected_spectrum(&scene);
    let poly = optics::Polychromatic::new(scene.lens(), &detected, scene.field(), 40.0 * step, None).unwrap();
    for k in [0_usize, 3, 10, 25] {
        let expected = poly.otf(k as f64 * step);
        assert!((centre_row[32 + k] - expected).abs() < 1e-5, "k = {k}: {} against {expected}", centre_row[32 + k]);
    }
    let err = fails(&["otf", "--out", out, "--size", "15"]);
    assert!(err.contains("--size 15") && err.contains("even"), "{err}");
    let err = fails(&["psf", "--out", out, "--spacing-um", "0"]);
    assert!(err.contains("--spacing-um 0"), "{err}");
}

/// `[source] kind = "radiance_meter"` end to end (SI eq. S1–S6). A meter whose readings are
/// those a flat 0.025 W/(m² sr nm) target behind the spectrometer table would give — the same
/// table as its relative spectrum, a flat responsivity (corr = 1, S3), a relay of T = 1,
/// D = 10 mm, f = 50 mm ((D/2f)² = 0.01), and the power S6 and S2 predict,
/// P = π T (D/2f)² · 0.025 W/(m² sr nm) · ∫T dλ · π (200 µm)² — puts the same photoelectrons in a
/// pixel as `examples/spectrometer.toml` (flat source × that table), to 1e-9. `--explain` prints
/// each step's value; `examples/radiance-meter.toml` runs.
#[test]
fn radiance_meter_source_end_to_end() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let table = std::fs::read_to_string(root.join("examples/data/spectrometer-825-52.csv")).unwrap();
    let rows: Vec<(f64, f64)> = table
        .lines()
        .filter_map(|l| {
            let (a, b) = l.split_once(',')?;
            Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
        })
        .collect();
    assert_eq!(rows.len(), 1601);
    // ∫T dλ by the trapezoid rule, exact for the piecewise-linear table (nm)
    let area_nm: f64 = rows.windows(2).map(|w| 0.5 * (w[1].0 - w[0].0) * (w[0].1 + w[1].1)).sum();
    let pi = std::f64::consts::PI;
    let power_nw = pi * 0.01 * 0.025 * area_nm * pi * 200e-6 * 200e-6 * 1e9;
    let dir = scratch("radiance-meter");
    std::fs::write(dir.join("flat.csv"), "400,1\n1100,1\n").unwrap();
    let scene = root.join("examples/radiance-meter.toml");
    let scene = scene.to_str().unwrap();
    let (power, flat) = (
        format!("source.power_nw={power_nw:e}"),
        format!("source.responsivity_csv=\"{}\"", dir.join("flat.csv").display()),
    );
    let args = ["evaluate", scene, "--json", "--set", &power, "--set", &flat, "--set", "source.relay_transmission=1"];
    let meter = json(&args);
    let reference = json(&["evaluate", root.join("examples/spectrometer.toml").to_str().unwrap(), "--json"]);
    let (a, b) = (meter["photoelectrons"].as_f64().unwrap(), reference["photoelectrons"].as_f64().unwrap());
    assert!((a / b - 1.0).abs() < 1e-9, "radiance meter {a} vs flat source × table {b}");

    // --explain: every step, with the example's values worked by hand:
    // S2 E = 4.6 nW/(π (200 µm)²) = 0.036606 W/m²; S6 (2·50/10)²/(π · 0.95) = 33.506 /sr
    let (text, _) = succeeds(&["evaluate", scene, "--explain"]);
    for step in [
        "    S1  ∫E_rel dλ",
        "    S2  E = P/A_fiber = 4.600 nW / 1.257e-7 m²",
        "    S3  corr = ",
        "    S4  E_accurate",
        "    S5  E_λ",
        "    S6  L_λ",
    ] {
        assert!(text.contains(step), "{step} missing:\n{text}");
    }
    assert!(text.contains("= 0.03661 W/m²") && text.contains("E_λ × 33.51 /sr"), "{text}");
    // with --json the steps are lines of the `explain` field
    let v = json(&["evaluate", scene, "--json", "--explain"]);
    let explain = v["explain"].as_array().unwrap();
    assert!(explain.iter().any(|l| l.as_str().unwrap().contains("S3  corr = ∫E_norm R(λ_cal)/R(λ) dλ")), "{v}");
    // other sources print no such steps
    let (text, _) = succeeds(&["evaluate", "--explain"]);
    assert!(!text.contains("S1  ∫E_rel"), "{text}");
    // bad values: exit 1, the key and what is accepted
    let err = fails(&["evaluate", scene, "--set", "source.relay_iris_mm=-3"]);
    assert!(err.contains("source.relay_iris_mm = -3: expected the relay iris diameter > 0 mm"), "{err}");
    let err = fails(&["evaluate", scene, "--set", "source.relative_spectrum_csv=missing.csv"]);
    assert!(err.contains("source.relative_spectrum_csv = \"missing.csv\"") && err.contains("cannot read"), "{err}");
}

/// `asnr sweep --shard I/N` writes every point once across the shards, its index first, and
/// `asnr merge` joins the shards (given in any order) into the single-process CSV byte for byte;
/// a `--points` file listing the grid's points gives the same CSV too.
#[test]
fn shards_merge_into_the_single_process_csv_and_points_files_match_the_grid() {
    let dir = scratch("shards");
    let grid = ["sweep", "--over", "lens.f_number=1.4:5:6", "--over", "spectrum.range_nm=2:300:7"];
    let single = asnr(&[&grid[..], &["--csv"]].concat());
    assert!(single.status.success(), "{}", stderr(&single));
    let mut files = Vec::new();
    let mut rows = 0;
    for i in [3, 1, 2] {
        let shard = format!("{i}/3");
        let out = asnr(&[&grid[..], &["--shard", &shard, "--threads", "2"]].concat());
        assert!(out.status.success(), "{}", stderr(&out));
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(text.starts_with("index,lens.f_number,spectrum.range_nm,mean_mtf,"), "{text}");
        // strided: shard i holds the indices ≡ i − 1 (mod 3)
        for line in text.lines().skip(1) {
            let index: usize = line.split(',').next().unwrap().parse().unwrap();
            assert_eq!(index % 3, i - 1, "{line}");
            rows += 1;
        }
        let path = dir.join(format!("shard-{i}.csv"));
        std::fs::write(&path, text).unwrap();
        files.push(path.display().to_string());
    }
    assert_eq!(rows, 42);
    let merged = asnr(&[&["merge"][..], &files.iter().map(String::as_str).collect::<Vec<_>>()].concat());
    assert!(merged.status.success(), "{}", stderr(&merged));
    assert_eq!(merged.stdout, single.stdout, "merged shards differ from the single-process CSV");

    // a points file of the grid's own values gives the same CSV
    let text = String::from_utf8(single.stdout.clone()).unwrap();
    let points: String = text.lines().map(|l| l.splitn(3, ',').take(2).collect::<Vec<_>>().join(",") + "\n").collect();
    let path = dir.join("points.csv");
    std::fs::write(&path, points).unwrap();
    let listed = asnr(&["sweep", "--points", path.to_str().unwrap(), "--csv"]);
    assert!(listed.status.success(), "{}", stderr(&listed));
    assert_eq!(listed.stdout, single.stdout);

    // bad input: a shard missing, a shard given twice, a file that is not a shard, a bad I/N,
    // a value in a points file that is not a number
    let err = fails(&["merge", &files[0], &files[1]]);
    assert!(err.contains("points missing (indices"), "{err}");
    let err = fails(&["merge", &files[0], &files[1], &files[2], &files[0]]);
    assert!(err.contains("expected each point once"), "{err}");
    let err = fails(&["merge", &files[0], &files[1], &files[2], "--expect", "50"]);
    assert!(err.contains("8 of the 50 points missing (indices 42, 43"), "{err}");
    let err = fails(&["merge", path.to_str().unwrap()]);
    assert!(err.contains("expected `index`"), "{err}");
    for bad in ["0/3", "4/3", "1/0", "x/2", "2"] {
        let err = fails(&[&grid[..], &["--shard", bad]].concat());
        assert!(err.contains(&format!("--shard {bad}: expected I/N")), "{err}");
    }
    std::fs::write(&path, "lens.f_number\n2.5\nF/4\n").unwrap();
    let err = fails(&["sweep", "--points", path.to_str().unwrap()]);
    assert!(err.contains("points.csv: line 3: lens.f_number = `F/4`: expected a finite number"), "{err}");
    std::fs::write(&path, "lens.f_number\n0.1\n").unwrap();
    let err = fails(&["sweep", "--points", path.to_str().unwrap()]);
    assert!(err.contains("lens.f_number = 0.1: expected a number ≥ 0.5"), "{err}");
    // a points file without its header: its first row is not taken for keys
    std::fs::write(&path, "2.5,50\n4,100\n").unwrap();
    let err = fails(&["sweep", "--points", path.to_str().unwrap()]);
    assert!(err.contains("points.csv: line 1: header `2.5,50`: `2.5` is a number, not a scene key"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `asnr … | head`: the reader closes the pipe after a line; the command stops quietly (exit 0,
/// no panic, no error message) instead of panicking in `println!`.
#[test]
fn a_closed_output_pipe_stops_the_command_quietly() {
    use std::io::{BufRead, BufReader};
    for args in [
        vec!["sweep", "--over", "lens.f_number=1.4:5:40", "--over", "spectrum.range_nm=2:300:100", "--csv"],
        vec!["sweep", "--over", "lens.f_number=1.4:5:40", "--over", "spectrum.range_nm=2:300:100", "--shard", "1/2"],
        vec!["mtf", "--csv", "--points", "100000"],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_asnr"))
            .args(&args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut first).unwrap();
        // the reader is dropped here: the pipe is closed
        let out = child.wait_with_output().unwrap();
        let err = stderr(&out);
        assert!(!first.is_empty(), "{args:?}");
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        assert!(!err.contains("panicked") && !err.contains("error"), "{args:?}: {err}");
    }
}

/// The Done-when round trip: the paper's chromatic lens exported by `asnr psf --stack` at fine
/// sampling (0.9 µm, the shortest wavelength's cutoff at the grid's Nyquist frequency; 160 × 160
/// samples, float64) over 735–865 nm, imported as `[lens] model = "psf"` with the keys the export
/// prints, reproduces the embedded scene's mean MTF and ASNR within the stack's sampling error.
/// That error is the linear interpolation of the OTF between the stack's wavelengths (the
/// defocus changes by 0.4 waves every 5 nm): it falls as h² with the step h — 0.36 % at 5 nm,
/// 0.075 % at 2.5 nm (a ratio near 4); the rest (the export's interpolation of the OTF onto the
/// grid, the table's linear interpolation in frequency, the 2.4e-4 of the Gaussian spectrum
/// outside 735–865 nm held at the end slices) stays below 1e-4 (a 1 nm stack: 7e-5).
#[test]
fn a_psf_stack_exported_and_imported_reproduces_the_scene() {
    let dir = scratch("psf-stack");
    let reference = json(&["evaluate", "--json"]);
    let paper = std::fs::read_to_string(PAPER).unwrap();
    let rest = &paper[paper.find("[source]").unwrap()..];
    let mut errors = Vec::new();
    for step in ["5", "2.5"] {
        let file = dir.join(format!("stack-{step}.npy"));
        let out = json(&[
            "psf",
            "--stack",
            file.to_str().unwrap(),
            "--wavelengths-nm",
            &format!("735:865:{step}"),
            "--size",
            "160",
            "--spacing-um",
            "0.9",
            "--dtype",
            "f8",
        ]);
        assert_eq!(out["shape"][1].as_u64(), Some(160), "{out}");
        let keys = out["lens_keys"].as_str().unwrap();
        let scene = dir.join(format!("stack-{step}.toml"));
        std::fs::write(&scene, format!("[lens]\n{keys}efficiency = 0.15\ntransmission = 0.55\n\n{rest}")).unwrap();
        let v = json(&["evaluate", scene.to_str().unwrap(), "--json"]);
        let relative = |k: &str| (v[k].as_f64().unwrap() / reference[k].as_f64().unwrap()) - 1.0;
        assert!((relative("asnr") - relative("mean_mtf")).abs() < 1e-9, "SNR0 is the same: {v}");
        eprintln!("{step} nm steps: mean MTF {}, relative error {:+.2e}", v["mean_mtf"], relative("mean_mtf"));
        errors.push(relative("mean_mtf"));
    }
    let (coarse, fine) = (errors[0].abs(), errors[1].abs());
    assert!(coarse < 5e-3 && fine < 1e-3, "{errors:?}");
    assert!(coarse / fine > 3.0 && coarse / fine < 6.0, "the error falls as h²: {errors:?}");
    let err = fails(&["psf", "--stack", "x.npy", "--wavelengths-nm", "800:700:5"]);
    assert!(err.contains("--wavelengths-nm 800:700:5") && err.contains("increasing"), "{err}");
    let err = fails(&["psf", "--stack", "x.npy", "--wavelengths-nm", "800", "--dtype", "f2"]);
    assert!(err.contains("--dtype f2"), "{err}");
}

/// examples/data/psf-paper-lens.npy is what the command in examples/psf-stack.toml writes (to
/// the float32 rounding, 1e-6 of each slice's peak, should another machine's FFT round
/// differently), and the example loads.
#[test]
fn the_example_psf_stack_is_what_its_command_writes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let example = std::fs::read_to_string(root.join("examples/psf-stack.toml")).unwrap();
    let command = example.lines().find(|l| l.contains("cargo asnr psf --stack")).unwrap();
    let args: Vec<&str> = command.trim_start_matches('#').split_whitespace().skip(2).collect();
    let file = scratch("psf-example").join("again.npy");
    let mut args: Vec<String> = args.iter().map(|a| a.to_string()).collect();
    args[2] = file.to_str().unwrap().to_owned();
    json(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let values = |bytes: Vec<u8>| -> Vec<f32> {
        let header = 10 + u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        bytes[header..].chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
    };
    let committed = values(std::fs::read(root.join("examples/data/psf-paper-lens.npy")).unwrap());
    let again = values(std::fs::read(&file).unwrap());
    assert_eq!(committed.len(), again.len());
    for (a, b) in committed.chunks(136 * 136).zip(again.chunks(136 * 136)) {
        let peak = a.iter().copied().fold(0.0, f32::max);
        assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-6 * peak));
    }
    let v = json(&["evaluate", root.join("examples/psf-stack.toml").to_str().unwrap(), "--json"]);
    // the stack is not round within 1e-6 (its 136-sample window and square grid), so its mean MTF
    // is averaged over azimuth: 0.437349, where its x and y cuts give 0.437296 (the value before,
    // the samples' exact transform along the axes; 0.437290 when it was linear in ν between the
    // 4×-padded grid's frequencies)
    assert!((v["mean_mtf"].as_f64().unwrap() - 0.437349).abs() < 1e-6, "{v}");
    assert!((v["mean_mtf_tangential"].as_f64().unwrap() - 0.437296).abs() < 1e-6, "{v}");
}
