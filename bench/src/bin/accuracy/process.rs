//! The Binary 2 metalens as a whole process (issue "Your metalens"): `asnr evaluate
//! examples/phase-binary2.toml --tolerance 1e-6 --json` against the numpy radial script run once
//! (`xtask/baselines/numpy_radial.py … --once`: the interpreter's start, numpy's import and one
//! evaluation, as a user runs it), at numpy's cheapest setting within 1e-6 in this run's rows,
//! each timed from outside, run alternately.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

use crate::tolerance::{BINARY2, NUMPY_RADIAL};
use crate::{Family, Row};

/// Our command, after the binary (run from the workspace root).
pub(crate) const OURS: [&str; 5] = ["evaluate", "examples/phase-binary2.toml", "--tolerance", "1e-6", "--json"];

/// Alternate runs of each command: short processes, so more than the map's three.
const RUNS: usize = 15;

/// What was measured.
pub(crate) struct ProcessBench {
    /// Whole-process wall times, s, medians: ours and numpy's.
    pub ours_s: f64,
    pub numpy_s: f64,
    pub runs: usize,
    /// Relative errors of the two means against the reference.
    pub ours_error: f64,
    pub numpy_error: f64,
    /// numpy's setting (`--nl … --nv …`), as its row names it.
    pub numpy_args: Vec<String>,
    pub numpy_setting: String,
}

/// `command` run from the workspace `root` as a whole process: its standard output and wall
/// time, s; None (and its standard error on ours) when it fails.
pub(crate) fn timed(command: &mut Command, root: &Path) -> Option<(String, f64)> {
    let started = Instant::now();
    let output = command.current_dir(root).stderr(Stdio::piped()).output().ok()?;
    let wall = started.elapsed().as_secs_f64();
    if !output.status.success() {
        eprintln!("  failed: {}", String::from_utf8_lossy(&output.stderr));
        return None;
    }
    Some((String::from_utf8_lossy(&output.stdout).into_owned(), wall))
}

/// `evaluate` and `gradient` as whole processes: one run of each first (the file cache), then
/// `repeats` of each alternately; `[value's median, value's fastest, both's median, both's
/// fastest]`, s, or None when a run fails.
pub(crate) fn value_and_gradient_alternately(
    evaluate: &dyn Fn() -> Command,
    gradient: &dyn Fn() -> Command,
    root: &Path,
    repeats: usize,
) -> Option<[f64; 4]> {
    timed(&mut evaluate(), root)?;
    timed(&mut gradient(), root)?;
    let (mut values, mut boths) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        values.push(timed(&mut evaluate(), root)?.1);
        boths.push(timed(&mut gradient(), root)?.1);
    }
    let least = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let (value_min, both_min) = (least(&values), least(&boths));
    Some([crate::median(values), value_min, crate::median(boths), both_min])
}

/// numpy's cheapest Binary 2 row within 1e-6, as the script's arguments.
fn cheapest_numpy(rows: &[Row]) -> Option<(Vec<String>, String)> {
    let row = rows
        .iter()
        .filter(|r| r.case == BINARY2 && r.family == Family::Numpy && r.error <= 1e-6)
        .min_by(|a, b| a.micros.total_cmp(&b.micros))?;
    // "nλ = 28, nν = 20, nt = 28, nv = 6"
    let numbers: Vec<&str> = row.setting.split(", ").filter_map(|p| p.split(" = ").nth(1)).collect();
    let [nl, nnu, nt, nv] = numbers.as_slice() else { return None };
    let args = ["--nl", nl, "--nnu", nnu, "--nt", nt, "--nv", nv].iter().map(|s| (*s).to_owned()).collect();
    Some((args, row.setting.clone()))
}

/// Runs both from the workspace `root` against `reference` (the per-interval rule's mean); None
/// (and a note on stderr) when a run fails or no numpy row is within 1e-6.
pub(crate) fn measure(asnr: &Path, python: &Path, root: &Path, rows: &[Row], reference: f64) -> Option<ProcessBench> {
    let (numpy_args, numpy_setting) = cheapest_numpy(rows)?;
    let timed = |command: &mut Command| timed(command, root);
    let script = root.join(NUMPY_RADIAL);
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    let (mut our_mean, mut numpy_mean) = (f64::NAN, f64::NAN);
    for _ in 0..RUNS {
        let (json, wall) = timed(Command::new(asnr).args(OURS))?;
        ours.push(wall);
        our_mean = crate::design::json_field(&json, "mean_mtf")?;
        let (text, wall) = timed(Command::new(python).arg(&script).args(&numpy_args).arg("--once").envs([
            ("OMP_NUM_THREADS", "1"),
            ("OPENBLAS_NUM_THREADS", "1"),
            ("MKL_NUM_THREADS", "1"),
        ]))?;
        theirs.push(wall);
        numpy_mean = text.lines().find_map(|l| l.strip_prefix("mean_mtf="))?.parse().ok()?;
    }
    let b = ProcessBench {
        ours_s: crate::median(ours),
        numpy_s: crate::median(theirs),
        runs: RUNS,
        ours_error: (our_mean - reference).abs() / reference,
        numpy_error: (numpy_mean - reference).abs() / reference,
        numpy_args,
        numpy_setting,
    };
    eprintln!("Binary 2, whole process: ours {:.2} ms, numpy {:.1} ms", 1e3 * b.ours_s, 1e3 * b.numpy_s);
    Some(b)
}

/// The paragraph and table of BENCHMARKS.md's designs section.
pub(crate) fn markdown(b: &ProcessBench) -> String {
    format!(
        "Whole process: `asnr {}` against `python3 {NUMPY_RADIAL} {} --once` (numpy's cheapest setting within 1e-6 \
         in the rows above; `--once`: one evaluation, no timing loop), each timed from outside as a user runs it \
         (process start, and for numpy the interpreter's start and numpy's import, included), run alternately, \
         medians of {}. Errors against the reference above.\n\n\
         | command | wall, median | mean MTF error |\n|---|---|---|\n\
         | `asnr evaluate` (tol 1e-6) | {:.2} ms | {:.1e} |\n\
         | numpy radial script ({}) | {:.1} ms | {:.1e} |\n",
        OURS.join(" "),
        b.numpy_args.join(" "),
        b.runs,
        1e3 * b.ours_s,
        b.ours_error,
        b.numpy_setting,
        1e3 * b.numpy_s,
        b.numpy_error,
    )
}
