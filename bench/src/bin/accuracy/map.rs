//! The map: `asnr sweep` of 40 × 100 points (F/1.4–5 × 2–300 nm) of the paper scene, the whole
//! release process on 2 worker threads, timed from outside (wall clock, and the CPU time the
//! child used), and every point's ASNR against the same sweep at `--tolerance 1e-12`.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// The sweep's arguments after the binary.
pub(crate) const ARGS: [&str; 8] =
    ["sweep", "--over", "lens.f_number=1.4:5:40", "--over", "spectrum.range_nm=2:300:100", "--csv", "--threads", "2"];

/// The measured map.
pub(crate) struct Map {
    /// Median wall time of the default-tolerance sweep, s, and the runs it is the median of.
    pub wall_s: f64,
    pub runs: usize,
    /// Median CPU time (user + system) of those runs, s (0 where /proc is not readable).
    pub cpu_s: f64,
    /// Points of the sweep.
    pub points: usize,
    /// Largest relative difference of the ASNR and of the mean MTF from the 1e-12 sweep.
    pub asnr_error: f64,
    pub mean_mtf_error: f64,
    /// Wall time of the 1e-12 sweep, s.
    pub reference_wall_s: f64,
    /// The Python package's `evaluate_many` + `to_csv` on the same points in one process, and the
    /// command beside it in the same run: (Python s, command s), medians (`python/bench/map.py`).
    pub python: Option<(f64, f64)>,
}

/// One run: wall seconds, CPU seconds, (mean MTF, ASNR) per point in the CSV's order.
pub(crate) fn run(asnr: &Path, extra: &[&str]) -> (f64, f64, Vec<(f64, f64)>) {
    let cpu = crate::children_cpu_s().unwrap_or(0.0);
    let started = Instant::now();
    let output = Command::new(asnr).args(ARGS).args(extra).output().expect("asnr runs");
    let wall = started.elapsed().as_secs_f64();
    let cpu = crate::children_cpu_s().unwrap_or(0.0) - cpu;
    assert!(output.status.success(), "asnr sweep failed: {}", String::from_utf8_lossy(&output.stderr));
    let text = String::from_utf8(output.stdout).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (mean, asnr) = (column("mean_mtf"), column("asnr"));
    // the warnings are the last column: the numeric columns before it hold no commas
    let points = lines
        .map(|l| {
            let fields: Vec<&str> = l.split(',').collect();
            (fields[mean].parse().unwrap(), fields[asnr].parse().unwrap())
        })
        .collect();
    (wall, cpu, points)
}

/// Times `runs` sweeps at the default tolerance and one at 1e-12 with the release binary `asnr`.
pub(crate) fn measure(asnr: &Path, runs: usize) -> Map {
    eprintln!("map: {} {}", asnr.display(), ARGS.join(" "));
    let mut walls = Vec::new();
    let mut cpus = Vec::new();
    let mut points = Vec::new();
    for _ in 0..runs {
        let (wall, cpu, p) = run(asnr, &[]);
        eprintln!("  {wall:.2} s wall, {cpu:.2} s CPU");
        walls.push(wall);
        cpus.push(cpu);
        points = p;
    }
    let (reference_wall_s, _, reference) = run(asnr, &["--tolerance", "1e-12"]);
    assert_eq!(points.len(), reference.len());
    let relative = |a: f64, b: f64| if b == 0.0 { a.abs() } else { (a - b).abs() / b.abs() };
    let mean_mtf_error = points.iter().zip(&reference).map(|(p, r)| relative(p.0, r.0)).fold(0.0, f64::max);
    let asnr_error = points.iter().zip(&reference).map(|(p, r)| relative(p.1, r.1)).fold(0.0, f64::max);
    eprintln!(
        "  at 1e-12: {reference_wall_s:.2} s; largest error: ASNR {asnr_error:.1e}, mean MTF {mean_mtf_error:.1e}"
    );
    Map {
        wall_s: crate::median(walls),
        runs,
        cpu_s: crate::median(cpus),
        points: points.len(),
        asnr_error,
        mean_mtf_error,
        reference_wall_s,
        python: None,
    }
}

/// Runs `python/bench/map.py` (under `root`) with the interpreter `python` that has the package:
/// `evaluate_many` on the map's points against `asnr` (the release binary) side by side, the CSVs
/// checked equal by the script. None (and a note on stderr) when it fails.
pub(crate) fn measure_python(python: &Path, asnr: &Path, root: &Path, runs: usize) -> Option<(f64, f64)> {
    let script = root.join("python").join("bench").join("map.py");
    eprintln!("map (Python): {} {}", python.display(), script.display());
    let output = Command::new(python)
        .arg(&script)
        .arg("--asnr")
        .arg(asnr)
        .args(["--runs", &runs.max(3).to_string(), "--json"])
        .output()
        .ok()?;
    if !output.status.success() {
        eprintln!("  failed: {}", String::from_utf8_lossy(&output.stderr));
        return None;
    }
    let text = String::from_utf8_lossy(&output.stdout);
    let field = |name: &str| -> Option<f64> {
        let at = text.find(&format!("\"{name}\": "))? + name.len() + 4;
        text[at..].split([',', '}']).next()?.trim().parse().ok()
    };
    let (py, cli) = (field("python_s")?, field("cli_s")?);
    eprintln!("  evaluate_many {py:.2} s, asnr sweep {cli:.2} s");
    Some((py, cli))
}
