//! `asnr sweep`: the ASNR over a grid of one or more scene keys, in parallel.
//!
//! Every grid point is an independent evaluation of the scene with its keys overridden, and the
//! results are collected in grid order, so the output is identical whatever the thread count.

use std::fmt::Write;
use std::sync::Mutex;

use anyhow::{Result, anyhow};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
pub use scene::sweep::Point;
use scene::sweep::{Grid, PointError, Points};

use crate::optimize::Range;
use scene::Source;

/// Grid values of one range: `N` points from `LO` to `HI` inclusive (`LO` alone for `N = 1`).
pub fn axis(range: &Range) -> Vec<f64> {
    scene::sweep::axis(range.lo, range.hi, range.points.unwrap_or(2))
}

/// The points of a sweep: the cartesian product of `--over` ranges, or the rows of a `--points`
/// file; each point has an index (its position), which shards and merges keep.
#[derive(Clone, Debug)]
pub enum Design {
    /// `--over` ranges' product, the first key varying slowest.
    Grid(Grid),
    /// `--points FILE.csv` rows, in file order.
    List(Vec<Vec<f64>>),
}

impl Design {
    /// The grid of `ranges`.
    pub fn grid(ranges: &[Range]) -> Design {
        Design::Grid(Grid::new(ranges.iter().map(axis).collect()))
    }

    /// Its number of points.
    pub fn len(&self) -> usize {
        match self {
            Design::Grid(g) => g.len(),
            Design::List(rows) => rows.len(),
        }
    }

    /// The values of point `index`.
    pub fn values(&self, index: usize) -> Vec<f64> {
        match self {
            Design::Grid(g) => g.values(index),
            Design::List(rows) => rows[index].clone(),
        }
    }
}

/// A sweep: the scene, the `--set` overrides, the swept keys and their points.
pub struct Sweep<'a> {
    /// The scene file (or the embedded scene).
    pub source: &'a Source,
    /// `--set` overrides, applied before the swept keys.
    pub overrides: &'a [String],
    /// The swept keys, in `--over` (or points-file column) order.
    pub keys: Vec<String>,
    /// Their points.
    pub design: Design,
    /// How each key was given (`--over KEY=LO:HI:N`, `--points FILE`), for the messages.
    pub origins: Vec<String>,
}

/// `message` with each swept key's `(--set KEY=V)` origin renamed to the option that gave it,
/// `origins[i]` for `keys[i]` (the scene loader sees a point's values as overrides).
pub fn relabel(message: &str, keys: &[String], values: &[f64], origins: &[String]) -> String {
    let mut out = message.to_owned();
    for ((k, v), origin) in keys.iter().zip(values).zip(origins) {
        let assignment = scene::sweep::assignment(k, *v);
        out = out.replace(&format!("--set {assignment}"), &format!("{origin} at {assignment}"));
    }
    out
}

impl Sweep<'_> {
    /// Its points' evaluator (the scene file read once for all of them).
    fn points(&self) -> Points<'_> {
        Points::new(self.source, self.overrides, &self.keys)
    }

    /// Evaluates point `index` (of `points`, [`Sweep::points`]); an error names where it is.
    fn point(&self, points: &Points, index: usize) -> Result<Point> {
        let values = self.design.values(index);
        points.evaluate(&values).map_err(|e: PointError| {
            let at: Vec<String> = self.keys.iter().zip(&values).map(|(k, v)| format!("{k}={v}")).collect();
            anyhow!(relabel(&e.to_string(), &self.keys, &values, &self.origins))
                .context(format!("at sweep point {} (index {index})", at.join(", ")))
        })
    }
}

/// Evaluates every point on `threads` threads (0 = all cores), with a progress bar on stderr
/// when it is a terminal; the points come back in index order, so the output is identical
/// whatever the thread count.
pub fn run(sweep: &Sweep, threads: usize) -> Result<Vec<Point>> {
    let total = sweep.design.len();
    let bar = progress_bar(total as u64, "points")?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let points = sweep.points();
    let results: Vec<Result<Point>> = pool.install(|| {
        (0..total)
            .into_par_iter()
            .map(|i| {
                let p = sweep.point(&points, i);
                bar.inc(1);
                p
            })
            .collect()
    });
    bar.finish_and_clear();
    results.into_iter().collect()
}

/// Evaluates the points `indices` on `threads` threads and writes each one's CSV line, its index
/// first, to `out` as soon as it is done (completion order: `asnr merge` sorts by index). The
/// header is written first. Stops at the first point that cannot be evaluated; the lines written
/// before stay.
pub fn stream(sweep: &Sweep, indices: &[usize], threads: usize, out: &mut (dyn std::io::Write + Send)) -> Result<()> {
    out.write_all(scene::sweep::csv_header(&sweep.keys, true).as_bytes())?;
    out.flush()?;
    let bar = progress_bar(indices.len() as u64, "points")?;
    let out = Mutex::new(out);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let points = sweep.points();
    pool.install(|| {
        indices.par_iter().try_for_each(|&i| -> Result<()> {
            let point = sweep.point(&points, i)?;
            let line = scene::sweep::csv_row(&point, Some(i));
            let mut out = out.lock().map_err(|_| anyhow!("internal error: the output lock is poisoned"))?;
            out.write_all(line.as_bytes())?;
            out.flush()?;
            bar.inc(1);
            Ok(())
        })
    })?;
    bar.finish_and_clear();
    Ok(())
}

/// At most this many of the points' warnings are printed; the rest are counted.
const SHOWN_WARNINGS: usize = 5;

/// The warnings of the sweep for stderr: each point's, prefixed with where it is, the first
/// [`SHOWN_WARNINGS`] of them and a count of the rest (all are in `--json` and `--csv`).
pub fn warnings(keys: &[String], points: &[Point]) -> Vec<String> {
    // (only the shown ones written: the rest are counted)
    let mut shown: Vec<String> = points
        .iter()
        .filter(|p| !p.warnings.is_empty())
        .flat_map(|p| {
            let at = at(keys, &p.values);
            p.warnings.iter().map(move |w| format!("warning: at {at}: {w}"))
        })
        .take(SHOWN_WARNINGS)
        .collect();
    let all: usize = points.iter().map(|p| p.warnings.len()).sum();
    if all > SHOWN_WARNINGS {
        let with = points.iter().filter(|p| !p.warnings.is_empty()).count();
        shown.push(format!(
            "warning: … and {} more warnings ({} of the {} points have warnings; --json or --csv lists them all)",
            all - SHOWN_WARNINGS,
            with,
            points.len()
        ));
    }
    shown
}

/// `key = value, …` of one grid point.
fn at(keys: &[String], values: &[f64]) -> String {
    keys.iter().zip(values).map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(", ")
}

/// CSV: one column per swept key (its dotted key), then the results, the Fraunhofer validity and
/// the point's warnings (joined by ` | `, quoted when needed), in index order.
pub fn csv(keys: &[String], points: &[Point]) -> String {
    let mut s = scene::sweep::csv_header(keys, false);
    for p in points {
        s.push_str(&scene::sweep::csv_row(p, None));
    }
    s
}

/// The best point of the grid, and for one key the maximum refined between grid points (the
/// parabola through the best point and its two neighbours, as the plot's legend gives it), and
/// for small grids every point, the Fraunhofer-invalid ones marked `*`.
pub fn table(label: &str, title: Option<&str>, ranges: &[Range], points: &[Point]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "scene      {label}");
    if let Some(title) = title {
        let _ = writeln!(s, "title      {title}");
    }
    let _ = writeln!(
        s,
        "swept      {} points over {}",
        points.len(),
        ranges.iter().map(|r| r.key.as_str()).collect::<Vec<_>>().join(" × ")
    );
    let invalid = points.iter().filter(|p| !p.fraunhofer_valid).count();
    if let Some(best) = points.iter().max_by(|a, b| a.asnr.total_cmp(&b.asnr)) {
        let at: Vec<String> = ranges.iter().zip(&best.values).map(|(r, v)| format!("{} = {v:.6}", r.key)).collect();
        let edge = ranges
            .iter()
            .zip(&best.values)
            .filter(|(r, v)| r.points.unwrap_or(2) > 1 && (**v == r.lo || **v == r.hi))
            .map(|(r, _)| r.key.as_str())
            .collect::<Vec<_>>();
        let _ = writeln!(
            s,
            "best of the grid points                 ASNR {:.6} at {}{}{}",
            best.asnr,
            at.join(", "),
            if best.fraunhofer_valid { "" } else { " *" },
            if edge.is_empty() {
                String::new()
            } else {
                format!(" (at the end of the {} range: the maximum may lie outside it)", edge.join(", "))
            }
        );
    }
    if let [range] = ranges
        && range.points.is_some_and(|n| n > 1)
    {
        let samples: Vec<(f64, f64)> = points.iter().map(|p| (p.values[0], p.asnr)).collect();
        let best = (0..samples.len()).max_by(|&a, &b| samples[a].1.total_cmp(&samples[b].1));
        let interior = best.is_some_and(|j| j > 0 && j + 1 < samples.len());
        if let Some((x, y)) = crate::plot::peak(&samples).filter(|_| interior) {
            let _ = writeln!(
                s,
                "refined between grid points (parabola) ASNR {y:.6} at {} = {x:.6} (as the plot's legend gives it)",
                range.key
            );
        }
    }
    if invalid > 0 {
        let _ = writeln!(
            s,
            "Fraunhofer {invalid} of the {} points NOT valid (SI eq. S15): the MTF model does not hold there",
            points.len()
        );
    }
    if points.len() <= 60 {
        let _ = writeln!(s);
        for r in ranges {
            let _ = write!(s, "  {:>20}", r.key);
        }
        let _ = writeln!(s, "  {:>10}  {:>10}  {:>10}  {:>10}", "mean MTF", "SNR0", "ASNR", "Fraunhofer");
        for p in points {
            for v in &p.values {
                let _ = write!(s, "  {v:>20.6}");
            }
            let _ = writeln!(
                s,
                "  {:>10.6}  {:>10.4}  {:>10.6}  {:>10}",
                p.mean_mtf,
                p.snr0,
                p.asnr,
                if p.fraunhofer_valid { "valid" } else { "* invalid" }
            );
        }
        if invalid > 0 {
            let _ = writeln!(s, "  * the Fraunhofer model is not valid at this point (SI eq. S15)");
        }
    } else {
        let _ = writeln!(s, "(use --csv or --json for all {} points)", points.len());
    }
    s
}

/// A progress bar on stderr for `total` steps counted in `unit` (drawn only on a terminal).
pub fn progress_bar(total: u64, unit: &str) -> Result<ProgressBar> {
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(&format!("{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {unit}, eta {{eta}}"))
            .map_err(|e| anyhow!("progress bar template: {e}"))?
            .progress_chars("=> "),
    );
    Ok(bar)
}

/// A spinner on stderr with the elapsed time and `message`, for a computation whose steps are
/// not counted (drawn only on a terminal; `finish_and_clear` removes it).
pub fn spinner(message: String) -> Result<ProgressBar> {
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed_precise} {msg}")
            .map_err(|e| anyhow!("progress spinner template: {e}"))?,
    );
    bar.set_message(message);
    bar.enable_steady_tick(std::time::Duration::from_millis(250));
    Ok(bar)
}
