//! End-to-end test of `asnr evaluate --compare-design SCENE`: the intended design's ASNR and
//! mean MTF printed beside the scene's, as text and in the JSON's `compare_design` object.

mod common;

use common::{asnr, fails, json, stderr};

fn example(name: &str) -> String {
    format!("{}/../examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The Binary 2 phase lens (as drawn) against the paper's chromatic lens (the design): the
/// `compare_design` object holds the design's own `asnr evaluate --json` numbers, and the
/// differences are the drawn lens's against them (relative for the ASNR, absolute for the mean
/// MTF); `--set` changes the drawn scene only, never the design; the text table prints the same
/// numbers to its digits.
#[test]
fn compare_design_sets_the_design_beside_the_drawn_lens() {
    let (drawn, design) = (example("phase-binary2.toml"), example("paper-theory.toml"));
    let alone = json(&["evaluate", &design, "--json"]);
    let (design_asnr, design_mtf) = (alone["asnr"].as_f64().unwrap(), alone["mean_mtf"].as_f64().unwrap());
    let v = json(&["evaluate", &drawn, "--json", "--compare-design", &design]);
    let (asnr_drawn, mtf_drawn) = (v["asnr"].as_f64().unwrap(), v["mean_mtf"].as_f64().unwrap());
    let c = &v["compare_design"];
    assert_eq!(c["scene"].as_str(), Some(design.as_str()), "{c}");
    assert_eq!(c["asnr"].as_f64(), Some(design_asnr), "{c}");
    assert_eq!(c["mean_mtf"].as_f64(), Some(design_mtf), "{c}");
    let relative = c["asnr_relative_difference"].as_f64().unwrap();
    assert!((relative - (asnr_drawn / design_asnr - 1.0)).abs() < 1e-15, "{c}");
    let difference = c["mean_mtf_difference"].as_f64().unwrap();
    assert!((difference - (mtf_drawn - design_mtf)).abs() < 1e-15, "{c}");
    assert!(relative.abs() > 1e-3, "two different lenses: {relative}");
    // without --compare-design the report has no such object
    assert!(json(&["evaluate", &drawn, "--json"]).get("compare_design").is_none());

    // --set applies to the drawn scene alone: the paper scene at F/2 against itself as designed
    let v = json(&["evaluate", &design, "--json", "--set", "lens.f_number=2", "--compare-design", &design]);
    assert_eq!(v["compare_design"]["asnr"].as_f64(), Some(design_asnr), "{v}");
    assert_ne!(v["asnr"].as_f64(), Some(design_asnr), "{v}");

    // the text table: the header naming the design, then its rows
    let out = asnr(&["evaluate", &drawn, "--compare-design", &design]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let at = text.find(&format!("As drawn against the design ({design}):")).unwrap_or_else(|| panic!("{text}"));
    let rows: Vec<Vec<&str>> = text[at..].lines().skip(2).take(3).map(|l| l.split_whitespace().collect()).collect();
    let row = |name: &str| rows.iter().find(|r| r.join(" ").starts_with(name)).unwrap_or_else(|| panic!("{text}"));
    let last = |r: &Vec<&str>, k: usize| r[r.len() - k].trim_end_matches('%').parse::<f64>().unwrap();
    assert!((last(row("as drawn"), 2) - asnr_drawn).abs() <= 5.001e-4, "{text}");
    assert!((last(row("as drawn"), 1) - mtf_drawn).abs() <= 5e-5, "{text}");
    assert!((last(row("design"), 2) - design_asnr).abs() <= 5.001e-4, "{text}");
    assert!((last(row("design"), 1) - design_mtf).abs() <= 5e-5, "{text}");
    assert!((last(row("difference"), 2) - 100.0 * relative).abs() <= 5e-3, "{text}");
    assert!((last(row("difference"), 1) - difference).abs() <= 5e-5, "{text}");
}

/// A design scene that cannot be read is refused naming the option and the file, exit 1.
#[test]
fn a_missing_design_scene_is_refused_naming_it() {
    let err = fails(&["evaluate", "--compare-design", "no-such-design.toml"]);
    assert!(err.contains("no-such-design.toml"), "{err}");
}
