//! `asnr optimize --method gradient`: the bounded quasi-Newton search on the engines' exact
//! gradient (docs/physics.md, "Gradients"), against COBYLA on the embedded paper scene, and its
//! refusals.

mod common;

use common::{asnr_at, fails, json};

/// Over the pixel pitch alone and jointly with the exposure time, the gradient method reaches the
/// optimum COBYLA reaches, within --xtol of each range (1e-4, the default). The ASNR rises with
/// both keys (a larger pixel lowers the Nyquist frequency and collects more light, a longer
/// exposure more photoelectrons: `asnr sweep --over camera.pixel_pitch_um=0.5:40:12` rises
/// throughout), so the optimum is the upper bounds: the gradient points out of the box there
/// (positive), its projection on the box is zero, and the ASNR reported is the evaluation's at
/// the point reported. The one-key golden section (no --method) agrees too.
#[test]
fn the_gradient_method_reaches_cobylas_optimum() {
    let golden = json(&["optimize", "--over", "camera.pixel_pitch_um=2:8", "--json"]);
    for over in [&["camera.pixel_pitch_um=2:8"][..], &["camera.pixel_pitch_um=2:8", "exposure.time_ms=0.5:2"]] {
        let run = |method: &str| {
            let mut args = vec!["optimize", "--method", method, "--json"];
            for o in over {
                args.extend(["--over", o]);
            }
            json(&args)
        };
        let (cobyla, gradient) = (run("cobyla"), run("gradient"));
        assert!(cobyla["method"].as_str().unwrap().starts_with("COBYLA"), "{cobyla}");
        assert!(gradient["method"].as_str().unwrap().starts_with("projected L-BFGS"), "{gradient}");
        assert_eq!(gradient["converged"], true, "{gradient}");
        let mut set = Vec::new();
        for o in over {
            let (key, bounds) = o.split_once('=').unwrap();
            let (lo, hi) = bounds.split_once(':').unwrap();
            let (lo, hi): (f64, f64) = (lo.parse().unwrap(), hi.parse().unwrap());
            let xtol = 1e-4 * (hi - lo);
            let (c, g) = (cobyla["best"][key].as_f64().unwrap(), gradient["best"][key].as_f64().unwrap());
            assert!((c - g).abs() <= xtol, "{key}: COBYLA {c}, gradient {g}");
            assert!((g - hi).abs() <= xtol, "{key}: {g}, expected the bound {hi}");
            assert_eq!(gradient["at_bound"][key], true);
            assert!(gradient["gradient"][key].as_f64().unwrap() > 0.0, "{gradient}");
            set.push(format!("{key}={g}"));
        }
        assert_eq!(gradient["projected_gradient"].as_f64().unwrap(), 0.0, "{gradient}");
        let best = gradient["asnr"].as_f64().unwrap();
        assert_eq!(asnr_at(&set), best, "the reported ASNR is the evaluation's at the reported point");
        let c = cobyla["asnr"].as_f64().unwrap();
        assert!((best - c).abs() <= 1e-3 * c, "gradient {best}, COBYLA {c}");
        assert!(best > gradient["best_start_asnr"].as_f64().unwrap(), "{gradient}");
        if over.len() == 1 {
            let b = golden["best"].as_f64().unwrap();
            let g = gradient["best"]["camera.pixel_pitch_um"].as_f64().unwrap();
            assert!((b - g).abs() <= golden["tolerance"].as_f64().unwrap() + 6e-4, "golden {b}, gradient {g}");
        }
    }
}

/// The text report names the method, counts the L-BFGS evaluations, and gives the gradient at the
/// optimum and its projection.
#[test]
fn the_text_report_names_the_gradient_search() {
    let out = common::asnr(&["optimize", "--over", "exposure.time_ms=0.5:2", "--method", "gradient"]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("projected L-BFGS") && text.contains("by L-BFGS"), "{text}");
    assert!(text.contains("gradient at the optimum (per unit of each key): exposure.time_ms"), "{text}");
}

/// Refused before any search, naming `--method gradient` and what has no gradient: keys the
/// engines do not differentiate yet (one beside a key they do, and one alone), the objectives without a gradient
/// (worst_channel is a minimum over channels; capacity and detectability not computed yet); an
/// unknown method.
#[test]
fn the_gradient_method_refuses_what_has_no_gradient() {
    let e = fails(&[
        "optimize",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/library.toml"),
        "--over",
        "camera.pixel_pitch_um=2:8",
        "--over",
        "lens.design_wavelength_nm=790:810",
        "--method",
        "gradient",
    ]);
    assert!(e.contains("--method gradient: --over lens.design_wavelength_nm: not differentiable here yet"), "{e}");
    // a blackbody's temperature over a band: the search runs on its gradient, with the stray
    // light included too (the transmitted light's own average of ∂ln B/∂T)
    let paper = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/paper-theory.toml")).unwrap();
    let blackbody = paper
        .replace("kind = \"flat\"", "kind = \"blackbody\"\ntemperature_k = 3000.0\nscale = 2e-3")
        .replace("radiance_w_m2_sr_nm = 0.025", "");
    let path = std::env::temp_dir().join(format!("asnr-gradient-blackbody-{}.toml", std::process::id()));
    std::fs::write(&path, blackbody).unwrap();
    let scene = path.to_str().unwrap();
    let over = ["optimize", scene, "--over", "source.temperature_k=2500:3500", "--method", "gradient"];
    let v = json(&[&over[..], &["--set", "options.glare=included", "--json", "--max-evaluations", "20"]].concat());
    assert!(v["asnr"].as_f64().unwrap() > 0.0, "{v}");
    for objective in ["capacity", "detectability:disk:20:0.1"] {
        let e =
            fails(&["optimize", "--over", "exposure.time_ms=1:2", "--objective", objective, "--method", "gradient"]);
        assert!(e.contains("--method gradient: --objective") && e.contains("gradient is not computed yet"), "{e}");
    }
    let dir = std::env::temp_dir().join(format!("asnr-gradient-method-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let paper = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/paper-theory.toml")).unwrap();
    let (start, end) = (paper.find("[lens]").unwrap(), paper.find("[source]").unwrap());
    let lens = "model = \"multiplexed\"\nlayout = \"interleaved\"\nf_number = 2.5\nfocal_length_mm = 3.36\n\
                channels_nm = [750, 800, 850]\nefficiency = 0.15\ntransmission = 0.55\n";
    let path = dir.join("interleaved.toml");
    std::fs::write(&path, format!("{}[lens]\n{lens}\n{}", &paper[..start], &paper[end..])).unwrap();
    let scene = path.to_str().unwrap();
    let args = ["optimize", scene, "--over", "exposure.time_ms=1:2", "--objective", "worst_channel"];
    let e = fails(&[&args[..], &["--method", "gradient"]].concat());
    assert!(e.contains("--method gradient: --objective worst_channel: a minimum over channels"), "{e}");
    // the same search by COBYLA runs
    let v = json(&[&args[..], &["--method", "cobyla", "--json", "--max-evaluations", "40"]].concat());
    assert!(v["asnr"].as_f64().unwrap() > 0.0, "{v}");
    let e = fails(&["optimize", "--over", "exposure.time_ms=1:2", "--method", "newton"]);
    assert!(e.contains("--method newton: expected cobyla (derivative-free, the default) or gradient"), "{e}");
}

/// `asnr tolerance` gives each key's ∂ASNR/∂key × σ from the exact gradient beside the fitted
/// slope: `gradient_per_sigma` is `asnr gradient --json`'s derivative times the key's σ, for
/// every key here (no `gradient_note`).
#[test]
fn tolerance_shows_the_gradient_sensitivity() {
    let t = json(&[
        "tolerance",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/harmonic.toml"),
        "--vary",
        "exposure.time_ms=normal:1%",
        "--vary",
        "spectrum.range_nm=normal:0.5",
        "--vary",
        "lens.design_wavelength_nm=normal:0.05",
        "--samples",
        "40",
        "--set",
        "spectrum.shape=\"line\"",
        "--set",
        "spectrum.center_nm=803",
        "--set",
        "field.x_deg=5",
        "--json",
    ]);
    // the harmonic lens off axis under a line: every key's gradient, the design wavelength's on
    // the line engine's lanes over azimuth
    let g = json(&[
        "gradient",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/harmonic.toml"),
        "--set",
        "spectrum.shape=\"line\"",
        "--set",
        "spectrum.center_nm=803",
        "--set",
        "field.x_deg=5",
        "--wrt",
        "exposure.time_ms",
        "--wrt",
        "spectrum.range_nm",
        "--wrt",
        "lens.design_wavelength_nm",
        "--json",
    ]);
    for (i, key) in ["exposure.time_ms", "spectrum.range_nm", "lens.design_wavelength_nm"].iter().enumerate() {
        let entry = &t["keys"][i];
        assert_eq!(entry["key"], *key, "{t}");
        let want = g["gradient"][key].as_f64().unwrap() * entry["sigma"].as_f64().unwrap();
        let got = entry["gradient_per_sigma"].as_f64().unwrap();
        assert!((got - want).abs() <= 1e-12 * want.abs(), "{key}: {got} vs {want}");
    }
    assert!(t["gradient_note"].is_null(), "{t}");
}

/// `asnr compare --wrt`: each design's exact gradient at the scene band, taken on the design as a
/// scene of its own (the shared tables with its lens): its ASNR is the comparison's for that
/// design, and every design has either a gradient over the keys or the refusal naming why.
#[test]
fn compare_gives_each_designs_gradient() {
    let v = json(&[
        "compare",
        "--over",
        "spectrum.range_nm=20:80:2",
        // each design's evaluations and gradients on the same engines and lanes as at the
        // default 1e-6, in fewer panels and pupil samples (the gradient's ASNR is compared with
        // its design's at the same tolerance)
        "--tolerance",
        "1e-4",
        "--wrt",
        "exposure.time_ms",
        "--wrt",
        "spectrum.range_nm",
        "--json",
    ]);
    let designs = v["designs"].as_array().unwrap();
    let mut with = 0;
    for d in designs {
        match d.get("gradient") {
            Some(g) => {
                with += 1;
                let (mine, theirs) = (g["asnr"].as_f64().unwrap(), d["asnr"].as_f64().unwrap());
                assert!((mine - theirs).abs() <= 1e-12 * theirs, "{}: {mine} vs {theirs}", d["name"]);
                assert!(g["gradient"]["spectrum.range_nm"].as_f64().unwrap().is_finite(), "{g}");
                assert!(g["gradient"]["exposure.time_ms"].as_f64().unwrap() > 0.0, "{g}");
            }
            None => {
                let note = d["gradient_note"].as_str().unwrap();
                assert!(note.contains("not differentiable"), "{}: {note}", d["name"]);
            }
        }
    }
    assert!(with >= 1, "{v}");
    assert!(designs[0].get("gradient").is_some(), "the paper's chromatic lens: {}", designs[0]);
}

/// The paper's best band by the gradient method (the Gaussian's range has an exact gradient)
/// and by golden section agree within --xtol of the range searched (1e-4 × 190 nm), over the
/// range and the exposure together.
#[test]
fn the_gradient_method_finds_the_best_band() {
    let golden = json(&["optimize", "--over", "spectrum.range_nm=10:200", "--json"]);
    let gradient = json(&[
        "optimize",
        "--over",
        "spectrum.range_nm=10:200",
        "--over",
        "exposure.time_ms=0.5:2",
        "--method",
        "gradient",
        "--json",
    ]);
    let (b, g) = (golden["best"].as_f64().unwrap(), gradient["best"]["spectrum.range_nm"].as_f64().unwrap());
    assert!((b - g).abs() <= 1e-4 * 190.0 * 2.0, "golden section {b} nm, gradient {g} nm");
}

/// The Binary 2 gradient over a 100 nm band (examples/phase-binary2.toml), where the frequency
/// rule integrates the MTF's decay in ln ν: it used to be refused there (the rule's end points,
/// exp(ln ν), missed the frequencies its derivatives were recorded at by a last bit). Against
/// central differences of evaluations converged at 1e-10, step 0.016 rad (the (3·tol/|f‴|)^{1/3}
/// rule for this lens, docs/physics.md "Gradients"): within 1e-5 of the gradient's norm.
#[test]
fn the_binary2_gradient_over_a_wide_band_matches_differences() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/phase-binary2.toml");
    let keys = ["lens.binary2[1]", "lens.binary2[2]", "lens.binary2[3]"];
    let mut args = vec!["gradient", scene, "--set", "spectrum.range_nm=100", "--tolerance", "1e-10", "--json"];
    for k in keys {
        args.extend(["--wrt", k]);
    }
    let exact = json(&args);
    let at = |key: &str, value: f64| {
        let set = format!("{key}={value}");
        json(&["evaluate", scene, "--set", "spectrum.range_nm=100", "--set", &set, "--tolerance", "1e-10", "--json"])
            ["asnr"]
            .as_f64()
            .unwrap()
    };
    let nominal = [5.277875658030851, -0.105557513160617, 0.002638937829015425];
    let h = 0.016;
    let mut norm = 0.0;
    let mut errors = Vec::new();
    for (key, x) in keys.iter().zip(nominal) {
        let g = exact["gradient"][*key].as_f64().unwrap();
        let difference = (at(key, x + h) - at(key, x - h)) / (2.0 * h);
        norm += g * g;
        errors.push((key, g, difference));
    }
    let norm = norm.sqrt();
    for (key, g, d) in errors {
        eprintln!(
            "{key}: gradient {g:.9e}, central difference {d:.9e}, error {:.1e} of the norm",
            (g - d).abs() / norm
        );
        assert!((g - d).abs() < 1e-5 * norm, "{key}: {g} vs {d}");
    }
}

/// A search over a list entry past the end of the scene's list (`lens.binary2[5]` of a 4-term
/// profile, which `--over` extends with zeros) starts from the scene as given: its own values,
/// 0 for the entry it lacks, are the first point of the history (stage `scene`), and their ASNR
/// is the scene's.
#[test]
fn a_search_over_terms_the_scene_lacks_starts_from_the_scene() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/phase-binary2.toml");
    let value = json(&[
        "optimize",
        scene,
        "--over",
        "lens.binary2[1]=0:10",
        "--over",
        "lens.binary2[5]=-1:1",
        "--starts",
        "2",
        "--max-evaluations",
        "6",
        "--tolerance",
        "1e-4",
        "--json",
    ]);
    let first = &value["history"][0];
    assert_eq!(first["stage"], "scene", "{value}");
    assert_eq!(first["values"][0].as_f64(), Some(5.277875658030851), "{first}");
    assert_eq!(first["values"][1].as_f64(), Some(0.0), "{first}");
    assert_eq!(first["asnr"].as_f64(), value["scene_asnr"].as_f64(), "{value}");
}
