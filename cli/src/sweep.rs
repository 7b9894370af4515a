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
    let bar = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} points, eta {eta}")
            .map_err(|e| anyhow!("progress bar template: {e}"))?
            .progress_chars("=> "),
    );
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

/// CSV: one column per swept key (its dotted key), then the results.
pub fn csv(ranges: &[Range], points: &[Point]) -> String {
    let mut s = String::new();
    for r in ranges {
        let _ = write!(s, "{},", r.key);
    }
    s.push_str("mean_mtf,snr0,asnr,photoelectrons,fraunhofer_valid\n");
    for p in points {
        for v in &p.values {
            let _ = write!(s, "{v},");
        }
        let _ = writeln!(s, "{},{},{},{},{}", p.mean_mtf, p.snr0, p.asnr, p.photoelectrons, p.fraunhofer_valid);
    }
    s
}

/// The best point and, for small grids, every point.
pub fn table(label: &str, ranges: &[Range], points: &[Point]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "scene      {label}");
    let _ = writeln!(
        s,
        "swept      {} points over {}",
        points.len(),
        ranges.iter().map(|r| r.key.as_str()).collect::<Vec<_>>().join(" × ")
    );
    if let Some(best) = points.iter().max_by(|a, b| a.asnr.total_cmp(&b.asnr)) {
        let at: Vec<String> = ranges.iter().zip(&best.values).map(|(r, v)| format!("{} = {v:.6}", r.key)).collect();
        let _ = writeln!(s, "best       ASNR {:.6} at {}", best.asnr, at.join(", "));
    }
    if points.len() <= 60 {
        let _ = writeln!(s);
        for r in ranges {
            let _ = write!(s, "  {:>20}", r.key);
        }
        let _ = writeln!(s, "  {:>10}  {:>10}  {:>10}", "mean MTF", "SNR0", "ASNR");
        for p in points {
            for v in &p.values {
                let _ = write!(s, "  {v:>20.6}");
            }
            let _ = writeln!(s, "  {:>10.6}  {:>10.4}  {:>10.6}", p.mean_mtf, p.snr0, p.asnr);
        }
    } else {
        let _ = writeln!(s, "(use --csv or --json for all {} points)", points.len());
    }
    s
}
