//! End-to-end tests of `asnr plot`: sweep CSVs replotted as overlaid lines (grouped, shaded,
//! marked) or as a heatmap, and bad input.
//!
//! Every bad-input case asserts exit code 1, no panic, and a message that names the file, the
//! column (or option), the value and what is accepted.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn asnr(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asnr")).args(args).output().expect("the asnr binary runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `asnr` expecting success.
fn succeeds(args: &[&str]) {
    let out = asnr(args);
    assert!(out.status.success(), "args {args:?}: {}", stderr(&out));
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

/// A scratch directory unique to one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("asnr-plot-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `text` to `dir/name` and returns the path as a string.
fn file(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

const HEADER: &str = "lens.f_number,spectrum.range_nm,mean_mtf,snr0,asnr,photoelectrons,fraunhofer_valid\n";

/// A 2 × 3 grid in sweep order, the last range beyond Fraunhofer validity at F/1.5.
fn grid_csv() -> String {
    let mut text = format!("# a comment line\n{HEADER}");
    for (f, r, asnr, valid) in [
        (1.5, 10.0, 9.0, true),
        (1.5, 50.0, 11.0, true),
        (1.5, 300.0, 8.0, false),
        (2.5, 10.0, 7.0, true),
        (2.5, 50.0, 10.0, true),
        (2.5, 300.0, 7.5, true),
    ] {
        text.push_str(&format!("{f},{r},0.5,20,{asnr},400,{valid}\n"));
    }
    text
}

/// The contents of the SVG's `<text>` elements, trimmed.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t.split_once('>')?.1.split_once("</text>")?.0.trim().to_owned()))
        .collect()
}

fn svg(path: &Path) -> String {
    let text = std::fs::read_to_string(path).expect("the plot was written");
    assert!(text.starts_with("<svg"), "{}", &text[..text.len().min(200)]);
    text
}

#[test]
fn overlays_labelled_csvs_with_marks_and_best_points() {
    let dir = scratch("overlay");
    let theory = file(&dir, "theory.csv", "spectrum.range_nm,asnr\n10,8\n30,10.5\n50,10.3\n");
    let simulated = file(&dir, "sim.csv", "spectrum.range_nm,asnr\n50,9.2\n10,7.5\n30,9.6\n"); // unsorted is fine
    let out = dir.join("fig.svg");
    succeeds(&[
        "plot",
        &format!("{theory}=theory"),
        &simulated,
        "--x",
        "spectrum.range_nm",
        "--y",
        "asnr",
        "--mark-best",
        "--mark-x",
        "10=filters",
        "--mark-x",
        "40=filters",
        "--title",
        "Fig. 2b test",
        "-o",
        out.to_str().unwrap(),
    ]);
    let text = svg(&out);
    // the maxima are refined by the parabola through the best sample and its neighbours
    for needle in ["Fig. 2b test", "theory: max 10.7449 at 38.5185", "sim: max 9.7445 at 36.8", "filters"] {
        assert!(text.contains(needle), "missing {needle:?}");
    }
    // marks with the same label share one legend entry
    assert_eq!(texts(&text).iter().filter(|t| *t == "filters").count(), 1, "{:?}", texts(&text));
}

#[test]
fn groups_one_csv_into_lines_and_shades_invalid_points() {
    let dir = scratch("group");
    let csv = file(&dir, "grid.csv", &grid_csv());
    let out = dir.join("s9.png");
    succeeds(&[
        "plot",
        &csv,
        "--x",
        "spectrum.range_nm",
        "--y",
        "asnr",
        "--group",
        "lens.f_number",
        "--group-label",
        "F/{}",
        "--shade-invalid",
        "--output",
        out.to_str().unwrap(),
    ]);
    assert_eq!(&std::fs::read(&out).unwrap()[..4], b"\x89PNG");
    let out = dir.join("s9.svg");
    succeeds(&[
        "plot",
        &csv,
        "--x",
        "spectrum.range_nm",
        "--y",
        "asnr",
        "--group",
        "lens.f_number",
        "--group-label",
        "F/{}",
        "--shade-invalid",
        "--output",
        out.to_str().unwrap(),
    ]);
    let texts = texts(&svg(&out));
    for needle in ["F/1.5", "F/2.5", "Fraunhofer approximation not valid (SI eq. S15)"] {
        assert!(texts.iter().any(|t| t == needle), "missing {needle:?} in {texts:?}");
    }
}

#[test]
fn heatmap_of_a_sweep_csv_with_ridge_mark_and_shading() {
    let dir = scratch("heatmap");
    let csv = file(&dir, "grid.csv", &grid_csv());
    let out = dir.join("fig2a.svg");
    succeeds(&[
        "plot",
        &csv,
        "--x",
        "lens.f_number",
        "--y",
        "spectrum.range_nm",
        "--z",
        "asnr",
        "--x-label",
        "F-number",
        "--z-label",
        "ASNR",
        "--mark-x",
        "2.5=F/2.5",
        "--shade-invalid",
        "-o",
        out.to_str().unwrap(),
    ]);
    let texts = texts(&svg(&out));
    for needle in [
        "max ASNR for each F-number",
        "F/2.5",
        "Fraunhofer approximation not valid (SI eq. S15)",
        "ASNR vs F-number and spectrum.range_nm",
    ] {
        assert!(texts.iter().any(|t| t == needle), "missing {needle:?} in {texts:?}");
    }
}

#[test]
fn replots_what_sweep_writes() {
    let dir = scratch("sweep");
    let out = asnr(&["sweep", "--over", "spectrum.range_nm=10:50:3", "--csv"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let csv = file(&dir, "sweep.csv", &String::from_utf8(out.stdout).unwrap());
    let svg_path = dir.join("sweep.svg");
    succeeds(&["plot", &csv, "--x", "spectrum.range_nm", "--y", "mean_mtf", "-o", svg_path.to_str().unwrap()]);
    assert!(svg(&svg_path).contains("mean_mtf vs spectrum.range_nm"));
}

#[test]
fn bad_files_and_columns_are_named() {
    let dir = scratch("bad");
    let out = dir.join("x.svg");
    let out = out.to_str().unwrap();
    let grid = file(&dir, "grid.csv", &grid_csv());

    let missing = dir.join("missing.csv");
    let err = fails(&["plot", missing.to_str().unwrap(), "--x", "a", "--y", "b", "-o", out]);
    assert!(err.contains("missing.csv: cannot read the CSV file"), "{err}");

    let err = fails(&["plot", &grid, "--x", "spectrum.range", "--y", "asnr", "-o", out]);
    assert!(err.contains("grid.csv: no column `spectrum.range` (--x); the columns are: lens.f_number,"), "{err}");

    let bad = file(&dir, "bad-number.csv", "spectrum.range_nm,asnr\n10,8\n30,abc\n");
    let err = fails(&["plot", &bad, "--x", "spectrum.range_nm", "--y", "asnr", "-o", out]);
    assert!(
        err.contains("bad-number.csv line 3, column `asnr`: `abc` is not a finite number; expected a number"),
        "{err}"
    );

    let bad = file(&dir, "bad-flag.csv", "x,asnr,fraunhofer_valid\n10,8,true\n30,9,yes\n");
    let err = fails(&["plot", &bad, "--x", "x", "--y", "asnr", "--shade-invalid", "-o", out]);
    assert!(err.contains("bad-flag.csv line 3, column `fraunhofer_valid`: `yes`; expected true or false"), "{err}");

    let plain = file(&dir, "plain.csv", "x,asnr\n10,8\n30,9\n");
    let err = fails(&["plot", &plain, "--x", "x", "--y", "asnr", "--shade-invalid", "-o", out]);
    assert!(err.contains("plain.csv: no column `fraunhofer_valid` (--shade-invalid)"), "{err}");

    let ragged = file(&dir, "ragged.csv", "x,asnr\n10,8\n30\n");
    let err = fails(&["plot", &ragged, "--x", "x", "--y", "asnr", "-o", out]);
    assert!(err.contains("ragged.csv line 3:") && err.contains("expected 2 comma-separated fields"), "{err}");

    let empty = file(&dir, "empty.csv", "x,asnr\n");
    let err = fails(&["plot", &empty, "--x", "x", "--y", "asnr", "-o", out]);
    assert!(err.contains("empty.csv: no data rows"), "{err}");

    // a two-key sweep drawn as lines without --group repeats x
    let err = fails(&["plot", &grid, "--x", "spectrum.range_nm", "--y", "asnr", "-o", out]);
    assert!(err.contains("grid.csv: column `spectrum.range_nm` (--x) has the value 10 twice"), "{err}");
    assert!(err.contains("--group COLUMN"), "{err}");

    let err = fails(&["plot", &plain, "--x", "x", "--y", "asnr", "-o", "/tmp/asnr-plot.pdf"]);
    assert!(err.contains("--output /tmp/asnr-plot.pdf: expected a file name ending in .svg or .png"), "{err}");

    let err = fails(&["plot", &plain, "--x", "x", "--y", "asnr", "--mark-x", "ten=filters", "-o", out]);
    assert!(err.contains("--mark-x ten=filters: `ten` is not a finite number; expected X or X=LABEL"), "{err}");
}

#[test]
fn bad_heatmap_grids_are_named() {
    let dir = scratch("bad-grid");
    let out = dir.join("x.svg");
    let out = out.to_str().unwrap();
    let heat = ["--x", "lens.f_number", "--y", "spectrum.range_nm", "--z", "asnr", "-o", out];

    let text = grid_csv();
    let incomplete = file(&dir, "incomplete.csv", &text[..text.trim_end().rfind('\n').unwrap()]);
    let err = fails(&[&["plot", incomplete.as_str()], &heat[..]].concat());
    assert!(
        err.contains(
            "incomplete.csv: the grid of lens.f_number × spectrum.range_nm is incomplete: no row for \
             lens.f_number = 2.5, spectrum.range_nm = 300"
        ),
        "{err}"
    );

    let twice = file(&dir, "twice.csv", &format!("{text}1.5,10,0.5,20,9,400,true\n"));
    let err = fails(&[&["plot", twice.as_str()], &heat[..]].concat());
    assert!(
        err.contains("twice.csv: lens.f_number = 1.5, spectrum.range_nm = 10 appears twice (lines 3 and 9)"),
        "{err}"
    );

    let grid = file(&dir, "grid.csv", &text);
    let err = fails(&[&["plot", grid.as_str(), grid.as_str()], &heat[..]].concat());
    assert!(err.contains("--z asnr: a heatmap is drawn from one CSV; got 2 files"), "{err}");
}
