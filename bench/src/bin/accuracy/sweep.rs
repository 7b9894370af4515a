//! A sweep point and a long efficiency table (issue "Correct under every input"): the
//! measured-spectrum sweep `asnr sweep examples/spectrometer.toml --over lens.f_number=2:4:1000`
//! against the numpy product-integration script over the same 1000 F-numbers
//! (`xtask/baselines/numpy_table.py --sweep-f-numbers`), each a whole process timed from outside,
//! run alternately; and one `metric::evaluate` of the paper scene with a 5000-row τ1 table
//! (0.08 nm), and of multi-order lenses whose every order's table has 5000 rows (an interleaved
//! lens of three channels, a harmonic lens's transmission), in this process.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;
use std::sync::Arc;

use lenses::{Channel, ChromaticMetalens, Curve, Harmonic, Interleaved};
use metric::{Camera, Options, Scene, evaluate};
use radiometry::{Gaussian, Spectrum};

use crate::tables::rows;
use crate::{F0, LAMBDA0, PIXEL_PITCH};

/// The sweep, after the binary (run from the workspace root).
const SWEEP: [&str; 7] =
    ["sweep", "examples/spectrometer.toml", "--over", "lens.f_number=2:4:1000", "--threads", "1", "--csv"];

/// numpy's settings: nλ = 112 is its cheapest λ rule within 1e-6 at F/2, where the sweep's
/// defocus is largest (nλ = 104 errs by 1.0e-5 there, its default 96 by 1.1e-4).
const NUMPY: [&str; 9] = ["--sweep-f-numbers", "2:4:1000", "--nl", "112", "--nnu", "32", "--nt", "32", ""];

/// What was measured.
pub(crate) struct SweepBench {
    /// Whole-process wall times, s, medians of the runs: ours and numpy's.
    pub ours_s: f64,
    pub numpy_s: f64,
    pub runs: usize,
    /// Relative errors of the first point (F/2) against `asnr evaluate … --tolerance 1e-12`.
    pub ours_error: f64,
    pub numpy_error: f64,
    pub numpy_version: String,
    /// One evaluation with the 5000-row table: median µs, repeats.
    pub table_micros: f64,
    pub table_repeats: usize,
    /// One evaluation of the interleaved lens with a 5000-row table per channel, and of the
    /// harmonic lens with a 5000-row transmission table: median µs, repeats.
    pub interleaved_micros: f64,
    pub interleaved_repeats: usize,
    pub harmonic_micros: f64,
    pub harmonic_repeats: usize,
}

fn value(text: &str, key: &str) -> Option<String> {
    text.lines().find_map(|l| l.strip_prefix(key).and_then(|v| v.strip_prefix('=')).map(str::to_owned))
}

/// The paper scene with a 5000-row τ1 table (0.08 nm from 600 to 1000 nm).
fn table_scene() -> Scene {
    let lens = ChromaticMetalens::new(2.5, F0, LAMBDA0, rows(0.12, 1.0), Curve::Constant(0.55)).unwrap();
    paper_scene(Arc::new(lens))
}

/// The paper scene through an interleaved lens of three channels (775, 800, 825 nm), each
/// with its own 5000-row efficiency table.
fn interleaved_scene() -> Scene {
    let channels = [(775e-9, 0.7, 0.8), (800e-9, 0.8, 1.0), (825e-9, 0.75, 1.3)]
        .iter()
        .map(|&(wavelength_m, mean, stretch)| Channel { wavelength_m, efficiency: rows(mean, stretch) })
        .collect();
    paper_scene(Arc::new(Interleaved::new(2.5, F0, channels, Curve::Constant(0.9)).unwrap()))
}

/// The paper scene through the harmonic lens of examples/harmonic.toml (p = 5, τ_base 0.15)
/// whose transmission is a 5000-row table.
fn harmonic_scene() -> Scene {
    paper_scene(Arc::new(Harmonic::new(2.5, F0, LAMBDA0, 5, 0.15, rows(0.5, 1.0)).unwrap()))
}

/// The paper's source and camera (F/2.5, 50 nm Gaussian at 800 nm) through `lens`.
fn paper_scene(lens: Arc<dyn optics::LensModel>) -> Scene {
    let filter = Gaussian::from_range(LAMBDA0, 50e-9, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(PIXEL_PITCH, Spectrum::Constant(0.2), false).unwrap();
    Scene::new(lens, radiance, camera, 1.23e-3, Options::default()).unwrap()
}

/// Runs everything from the workspace `root`; None (and a note on stderr) when a run fails.
pub(crate) fn measure(asnr: &Path, python: Option<&Path>, root: &Path, runs: usize) -> Option<SweepBench> {
    let scene = table_scene();
    let (table_micros, table_repeats, _) =
        crate::time(std::time::Duration::from_millis(500), 3, || evaluate(&scene).unwrap());
    eprintln!("5000-row τ1 table: {table_micros:.1} µs an evaluation");
    let scene = interleaved_scene();
    let (interleaved_micros, interleaved_repeats, _) =
        crate::time(std::time::Duration::from_millis(500), 3, || evaluate(&scene).unwrap());
    eprintln!("interleaved lens, a 5000-row table per channel: {interleaved_micros:.1} µs an evaluation");
    let scene = harmonic_scene();
    let (harmonic_micros, harmonic_repeats, _) =
        crate::time(std::time::Duration::from_millis(500), 3, || evaluate(&scene).unwrap());
    eprintln!("harmonic lens, a 5000-row transmission table: {harmonic_micros:.1} µs an evaluation");
    let python = python?;
    let timed = |command: &mut Command| crate::process::timed(command, root);
    let script = root.join("xtask/baselines/numpy_table.py");
    let table = root.join("examples/data/spectrometer-825-52.csv");
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    let (mut our_first, mut numpy_text) = (None, String::new());
    for _ in 0..runs.max(1) {
        let (csv, wall) = timed(Command::new(asnr).args(SWEEP))?;
        ours.push(wall);
        // the first data row's mean MTF (column 2)
        our_first = csv.lines().nth(1).and_then(|l| l.split(',').nth(1)).and_then(|v| v.parse::<f64>().ok());
        let (text, wall) =
            timed(Command::new(python).arg(&script).arg(&table).args(NUMPY.iter().filter(|a| !a.is_empty())).envs([
                ("OMP_NUM_THREADS", "1"),
                ("OPENBLAS_NUM_THREADS", "1"),
                ("MKL_NUM_THREADS", "1"),
            ]))?;
        theirs.push(wall);
        numpy_text = text;
        eprintln!("  sweep: ours {:.2} s, numpy {wall:.2} s", ours.last().unwrap_or(&0.0));
    }
    let (reference, _) = timed(Command::new(asnr).args([
        "evaluate",
        "examples/spectrometer.toml",
        "--set",
        "lens.f_number=2",
        "--tolerance",
        "1e-12",
        "--json",
    ]))?;
    let reference = crate::design::json_field(&reference, "mean_mtf")?;
    let numpy_first: f64 = value(&numpy_text, "first_mean_mtf")?.parse().ok()?;
    Some(SweepBench {
        ours_s: crate::median(ours),
        numpy_s: crate::median(theirs),
        runs: runs.max(1),
        ours_error: (our_first? - reference).abs() / reference,
        numpy_error: (numpy_first - reference).abs() / reference,
        numpy_version: value(&numpy_text, "numpy")?,
        table_micros,
        table_repeats,
        interleaved_micros,
        interleaved_repeats,
        harmonic_micros,
        harmonic_repeats,
    })
}

/// The section of BENCHMARKS.md.
pub(crate) fn markdown(b: &SweepBench) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## A sweep against numpy, and a 5000-row efficiency table\n");
    let _ = writeln!(
        s,
        "The sweep: `asnr {}` against `python3 xtask/baselines/numpy_table.py examples/data/spectrometer-825-52.csv {}` \
         (numpy {}: the same 1000 F-numbers, product integration as in the spectrometer rows above, in one process), \
         each a whole process timed from outside, run alternately, medians of {}. Error: the first point's (F/2, the \
         largest defocus) mean MTF against `asnr evaluate examples/spectrometer.toml --set lens.f_number=2 \
         --tolerance 1e-12`. numpy's nλ = 112 is its cheapest λ rule within 1e-6 there (nλ = 104 errs by 1.0e-5, its \
         default 96 by 1.1e-4). The table: one `metric::evaluate` of the paper scene (F/2.5, 50 nm) whose τ1 is a \
         5000-row table (0.08 nm, 600–1000 nm), folded into the detected spectrum's exact moments (before, its rows \
         cut 52 598 spectral nodes and the work budget refused it), median of {} calls in this process. Every \
         order's table is folded too (`optics::Polychromatic::with_parts`: each part's orders with the moments of \
         its own spectrum): the same scene through an interleaved lens of three channels (775, 800 and 825 nm), each \
         channel's efficiency its own 5000-row table (medians of {} calls), and through the harmonic lens of \
         examples/harmonic.toml (p = 5, τ_base = 0.15) whose transmission is a 5000-row table (medians of {} \
         calls).\n",
        SWEEP.join(" "),
        NUMPY.join(" ").trim(),
        b.numpy_version,
        b.runs,
        b.table_repeats,
        b.interleaved_repeats,
        b.harmonic_repeats
    );
    let _ = writeln!(s, "| target | measured | status |");
    let _ = writeln!(s, "|---|---|---|");
    let ratio = b.numpy_s / b.ours_s;
    let _ = writeln!(
        s,
        "| measured-spectrum sweep, 1000 points, whole process: ≥ 20× the numpy script at equal or better accuracy | \
         {ratio:.1}× faster: {:.2} s (error {:.1e}) against numpy's {:.2} s (error {:.1e}) | {} |",
        b.ours_s,
        b.ours_error,
        b.numpy_s,
        b.numpy_error,
        if ratio >= 20.0 && b.ours_error <= b.numpy_error.max(1e-6) {
            "met".to_owned()
        } else {
            format!("missed ({ratio:.1}× of 20×)")
        }
    );
    let status = |micros: f64| {
        if micros <= 1e4 { format!("met ({:.2}× the bound)", micros / 1e4) } else { "missed".into() }
    };
    let rows = [
        ("5000-row τ1 table", b.table_micros),
        ("interleaved lens, three channels, a 5000-row table each", b.interleaved_micros),
        ("harmonic lens (p = 5), 5000-row transmission table", b.harmonic_micros),
    ];
    for (name, micros) in rows {
        let _ = writeln!(s, "| {name}, one evaluation: ≤ 10 ms | {:.2} ms | {} |", micros * 1e-3, status(micros));
    }
    let _ = writeln!(s);
    s
}
