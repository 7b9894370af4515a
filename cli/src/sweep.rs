//! `asnr sweep`: the ASNR over a grid of one or more scene keys, in parallel.
//!
//! Every grid point is an independent evaluation of the scene with its keys overridden, and the
//! results are collected in grid order, so the output is identical whatever the thread count.

use std::fmt::Write;

use anyhow::{Result, anyhow};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;

use crate::optimize::Range;
use scene::Source;

/// One evaluated grid point.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// The swept keys' values, in `--over` order.
    pub values: Vec<f64>,
    /// Mean MTF up to Nyquist.
    pub mean_mtf: f64,
    /// Zero-frequency SNR.
    pub snr0: f64,
    /// The ASNR (the scene's form).
    pub asnr: f64,
    /// Signal photoelectrons per pixel.
    pub photoelectrons: f64,
    /// Whether the Fraunhofer model is valid there (SI eq. S15).
    pub fraunhofer_valid: bool,
    /// The evaluation's warnings there (truncated spectra, saturation, validity).
    pub warnings: Vec<String>,
}

/// Grid values of one range: `N` points from `LO` to `HI` inclusive (`LO` alone for `N = 1`).
pub fn axis(range: &Range) -> Vec<f64> {
    let n = range.points.unwrap_or(2).max(1);
    if n == 1 {
        return vec![range.lo];
    }
    (0..n)
        .map(|i| if i + 1 == n { range.hi } else { range.lo + (range.hi - range.lo) * i as f64 / (n - 1) as f64 })
        .collect()
}

/// Evaluates the cartesian product of the ranges (the first key varies slowest) on `threads`
/// threads (0 = all cores), with a progress bar on stderr when it is a terminal.
pub fn run(source: &Source, overrides: &[String], ranges: &[Range], threads: usize) -> Result<Vec<Point>> {
    let axes: Vec<Vec<f64>> = ranges.iter().map(axis).collect();
    let total: usize = axes.iter().map(Vec::len).product();
    let grid: Vec<Vec<f64>> = (0..total)
        .map(|mut flat| {
            let mut values = vec![0.0; axes.len()];
            for (k, axis) in axes.iter().enumerate().rev() {
                values[k] = axis[flat % axis.len()];
                flat /= axis.len();
            }
            values
        })
        .collect();
    let bar = progress_bar(total as u64, "points")?;
    let evaluate = |values: &Vec<f64>| -> Result<Point> {
        let mut set = overrides.to_vec();
        for (range, v) in ranges.iter().zip(values) {
            set.push(crate::optimize::assignment(&range.key, *v));
        }
        let scene = scene::build_from(source, &set)?;
        let r = metric::evaluate(&scene).map_err(|e| anyhow!("{}: {e}", source.label()))?;
        bar.inc(1);
        Ok(Point {
            values: values.clone(),
            mean_mtf: r.mean_mtf,
            snr0: r.snr0,
            asnr: r.asnr,
            photoelectrons: r.photoelectrons,
            fraunhofer_valid: r.fraunhofer.valid,
            warnings: r.warnings,
        })
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let results: Vec<Result<Point>> = pool.install(|| grid.par_iter().map(evaluate).collect());
    bar.finish_and_clear();
    let mut points = Vec::with_capacity(total);
    for (values, r) in grid.iter().zip(results) {
        let point = r.map_err(|e| {
            let at: Vec<String> = ranges.iter().zip(values).map(|(k, v)| format!("{}={v}", k.key)).collect();
            e.context(format!("at sweep point {}", at.join(", ")))
        })?;
        points.push(point);
    }
    Ok(points)
}

/// At most this many of the points' warnings are printed; the rest are counted.
const SHOWN_WARNINGS: usize = 5;

/// The warnings of the sweep for stderr: each point's, prefixed with where it is, the first
/// [`SHOWN_WARNINGS`] of them and a count of the rest (all are in `--json` and `--csv`).
pub fn warnings(ranges: &[Range], points: &[Point]) -> Vec<String> {
    let all: Vec<String> = points
        .iter()
        .flat_map(|p| {
            let at = at(ranges, &p.values);
            p.warnings.iter().map(move |w| format!("warning: at {at}: {w}"))
        })
        .collect();
    let mut shown: Vec<String> = all.iter().take(SHOWN_WARNINGS).cloned().collect();
    if all.len() > SHOWN_WARNINGS {
        let with = points.iter().filter(|p| !p.warnings.is_empty()).count();
        shown.push(format!(
            "warning: … and {} more warnings ({} of the {} points have warnings; --json or --csv lists them all)",
            all.len() - SHOWN_WARNINGS,
            with,
            points.len()
        ));
    }
    shown
}

/// `key = value, …` of one grid point.
fn at(ranges: &[Range], values: &[f64]) -> String {
    ranges.iter().zip(values).map(|(r, v)| format!("{}={v}", r.key)).collect::<Vec<_>>().join(", ")
}

/// A CSV field, quoted when it holds a comma, a quote or a line break (RFC 4180).
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) { format!("\"{}\"", text.replace('"', "\"\"")) } else { text.to_owned() }
}

/// CSV: one column per swept key (its dotted key), then the results, the Fraunhofer validity and
/// the point's warnings (joined by ` | `, quoted).
pub fn csv(ranges: &[Range], points: &[Point]) -> String {
    let mut s = String::new();
    for r in ranges {
        let _ = write!(s, "{},", r.key);
    }
    s.push_str("mean_mtf,snr0,asnr,photoelectrons,fraunhofer_valid,warnings\n");
    for p in points {
        for v in &p.values {
            let _ = write!(s, "{v},");
        }
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            p.mean_mtf,
            p.snr0,
            p.asnr,
            p.photoelectrons,
            p.fraunhofer_valid,
            csv_field(&p.warnings.join(" | "))
        );
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
    if let [range] = ranges {
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
