//! Designing with the ASNR through the whole release process: the README's search of a Binary 2
//! metalens (`asnr optimize` over A2, A3 and the band, "Designing with the ASNR") and a
//! 1000-sample `asnr tolerance` of the paper scene, each timed from outside (wall clock, one run:
//! the search takes about a minute), with the evaluations and results their JSON reports.

use std::path::Path;
use std::process::Command;

/// The README's search, after the binary (run from the workspace root).
pub(crate) const SEARCH: [&str; 13] = [
    "optimize",
    "examples/phase-binary2.toml",
    "--over",
    "lens.binary2[1]=-20:30",
    "--over",
    "lens.binary2[2]=-10:10",
    "--over",
    "spectrum.range_nm=10:300",
    "--tolerance",
    "1e-4",
    "--xtol",
    "1e-3",
    "--json",
];

/// The paper scene's tolerance run, after the binary.
pub(crate) const TOLERANCE: [&str; 9] = [
    "tolerance",
    "--vary",
    "lens.f_number=normal:2%",
    "--vary",
    "spectrum.range_nm=uniform:40:60",
    "--samples",
    "1000",
    "--json",
    "--threads=2",
];

/// The measured runs.
pub(crate) struct DesignBench {
    /// The search: wall time, s; evaluations; the ASNR found; the start set's size.
    pub search_s: f64,
    pub evaluations: f64,
    pub asnr: f64,
    pub starts: f64,
    /// The tolerance run: wall time, s; mean and σ of its ASNR.
    pub tolerance_s: f64,
    pub mean: f64,
    pub std: f64,
}

pub(crate) fn json_field(text: &str, name: &str) -> Option<f64> {
    let at = text.find(&format!("\"{name}\":"))? + name.len() + 3;
    text[at..].split([',', '}', '\n']).next()?.trim().parse().ok()
}

/// Runs both from the workspace `root`; None (and a note on stderr) when one fails.
pub(crate) fn measure(asnr: &Path, root: &Path) -> Option<DesignBench> {
    let run = |args: &[&str]| -> Option<(String, f64)> {
        eprintln!("design: {} {}", asnr.display(), args.join(" "));
        let (stdout, wall) = crate::process::timed(Command::new(asnr).args(args), root)?;
        eprintln!("  {wall:.2} s wall");
        Some((stdout, wall))
    };
    let (search, search_s) = run(&SEARCH)?;
    let (tolerance, tolerance_s) = run(&TOLERANCE)?;
    Some(DesignBench {
        search_s,
        evaluations: json_field(&search, "evaluations")?,
        asnr: json_field(&search, "asnr")?,
        starts: json_field(&search, "start_points")?,
        tolerance_s,
        mean: json_field(&tolerance, "mean")?,
        std: json_field(&tolerance, "std")?,
    })
}

/// The report's section.
pub(crate) fn markdown(d: &DesignBench) -> String {
    format!(
        "## Designing with the ASNR: a search and a tolerance run, whole process\n\n\
         Release binary, timed from outside, one run each. The README's search (\"Designing with the \
         ASNR\"): `asnr {}`, COBYLA from the best of a Halton start set over three keys, each point a \
         Binary 2 metalens evaluated at `--tolerance 1e-4`. The tolerance run: `asnr {}` on the paper \
         scene (closed-form engine).\n\n\
         | run | evaluations | wall | result |\n|---|---|---|---|\n\
         | `optimize` over A2, A3 and the band (README) | {:.0} ({:.0} start points, {:.0} by COBYLA) | {:.1} s | ASNR {:.4} |\n\
         | `tolerance`, paper scene, 1000 samples, 2 threads | 1001 (the nominal and the samples) | {:.2} s | mean ASNR {:.4} ± {:.4} |\n\n",
        SEARCH.join(" "),
        TOLERANCE.join(" "),
        d.evaluations,
        d.starts,
        d.evaluations - d.starts,
        d.search_s,
        d.asnr,
        d.tolerance_s,
        d.mean,
        d.std,
    )
}
