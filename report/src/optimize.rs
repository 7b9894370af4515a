//! `asnr optimize`: the value of one numeric scene key that maximizes the ASNR.

use anyhow::{Context, Result, bail};
use serde::Serialize;

/// Points of the coarse scan that brackets the maximum before the golden-section search.
pub const SCAN_POINTS: usize = 17;

/// A `KEY=LO:HI` range.
#[derive(Clone, Debug, PartialEq)]
pub struct Range {
    /// Dotted scene key.
    pub key: String,
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Grid points (sweeps only).
    pub points: Option<usize>,
}

/// Parses `KEY=LO:HI` (and `KEY=LO:HI:N` when `with_points`).
pub fn parse_range(arg: &str, with_points: bool) -> Result<Range> {
    let form = if with_points { "KEY=LO:HI:N" } else { "KEY=LO:HI" };
    let Some((key, spec)) = arg.split_once('=') else {
        bail!(
            "--over {arg}: expected {form}, e.g. --over spectrum.range_nm=1:200{}",
            if with_points { ":50" } else { "" }
        );
    };
    let parts: Vec<&str> = spec.split(':').collect();
    let expected = if with_points { 3 } else { 2 };
    if parts.len() != expected {
        bail!("--over {arg}: expected {form}");
    }
    let num = |s: &str, what: &str| -> Result<f64> {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .with_context(|| format!("--over {arg}: {what} `{s}` is not a finite number"))
    };
    let (lo, hi) = (num(parts[0], "LO")?, num(parts[1], "HI")?);
    if lo >= hi {
        bail!("--over {arg}: LO = {lo} must be below HI = {hi}");
    }
    if !(hi - lo).is_finite() {
        bail!("--over {arg}: HI − LO = {hi:e} − {lo:e} overflows; expected a range narrower than {:e}", f64::MAX);
    }
    let points =
        if with_points {
            let n: usize =
                parts[2].trim().parse().ok().filter(|n| (1..=1_000_000).contains(n)).with_context(|| {
                    format!("--over {arg}: N `{}` is not a whole number from 1 to 1000000", parts[2])
                })?;
            Some(n)
        } else {
            None
        };
    Ok(Range { key: key.trim().to_owned(), lo, hi, points })
}

/// How [`maximize`] finds `best` (the JSON's `method`), to tell it from a sweep's best grid point
/// and the plot's parabola through it.
pub const METHOD: &str = "golden-section search to ±tolerance, after a 17-point scan";

pub use scene::sweep::assignment;

/// The maximum found.
#[derive(Clone, Debug, Serialize)]
pub struct Optimum {
    /// The key varied.
    pub key: String,
    /// The best value of the key, by [`METHOD`].
    pub best: f64,
    /// How `best` was found: [`METHOD`].
    pub method: &'static str,
    /// The ASNR there.
    pub asnr: f64,
    /// The search interval.
    pub lo: f64,
    /// The search interval.
    pub hi: f64,
    /// `best` is within this of the true maximizer of a unimodal ASNR on the bracket.
    pub tolerance: f64,
    /// ASNR evaluations used.
    pub evaluations: usize,
    /// Whether `best` is within `tolerance` of `lo` or `hi`: the maximum may lie outside the range.
    pub at_bound: bool,
}

/// The warning when the best value is on a bound of the search range.
pub fn bound_warning(o: &Optimum) -> Option<String> {
    if !o.at_bound {
        return None;
    }
    let (end, value) = if o.best - o.lo <= o.hi - o.best { ("LO", o.lo) } else { ("HI", o.hi) };
    Some(format!(
        "the best {} = {} is at the bound {end} = {value} of --over {}={}:{}: the maximum may lie outside LO:HI; widen the range",
        o.key, o.best, o.key, o.lo, o.hi
    ))
}

/// The text report: the value found, by which method, and how many evaluations it took.
pub fn report(o: &Optimum) -> String {
    format!(
        "best {} = {:.6} (±{:.2e}, golden-section search after a {SCAN_POINTS}-point scan) → ASNR {:.6}   [{} evaluations over {}…{}]{}\n",
        o.key,
        o.best,
        o.tolerance,
        o.asnr,
        o.evaluations,
        o.lo,
        o.hi,
        if o.at_bound { "   AT THE BOUND: the maximum may lie outside" } else { "" }
    )
}

/// Golden-section search for a maximum of `f` in `[a, b]` until the bracket is at most
/// `tolerance` wide, or at the float spacing of its ends (a tolerance below that would loop for
/// ever): every point evaluated, in order, and the final bracket's width.
pub fn golden_section(
    mut a: f64,
    mut b: f64,
    tolerance: f64,
    mut f: impl FnMut(f64) -> Result<f64>,
) -> Result<(Vec<(f64, f64)>, f64)> {
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - ratio * (b - a), a + ratio * (b - a));
    let (mut fc, mut fd) = (f(c)?, f(d)?);
    let mut points = vec![(c, fc), (d, fd)];
    while b - a > tolerance && b - a > 8.0 * f64::EPSILON * a.abs().max(b.abs()) {
        if fc >= fd {
            (b, d, fd) = (d, c, fc);
            c = b - ratio * (b - a);
            fc = f(c)?;
            points.push((c, fc));
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + ratio * (b - a);
            fd = f(d)?;
            points.push((d, fd));
        }
    }
    Ok((points, b - a))
}

/// Maximizes `f` on `[lo, hi]`: a scan of [`SCAN_POINTS`] brackets the best point, then
/// golden-section search narrows the bracket to `tolerance` (absolute, in the key's units).
pub fn maximize(range: &Range, tolerance: f64, mut f: impl FnMut(f64) -> Result<f64>) -> Result<Optimum> {
    let (lo, hi) = (range.lo, range.hi);
    let step = (hi - lo) / (SCAN_POINTS - 1) as f64;
    let mut evaluations = 0;
    let mut best = (lo, f64::NEG_INFINITY);
    let mut best_index = 0;
    for i in 0..SCAN_POINTS {
        let x = if i + 1 == SCAN_POINTS { hi } else { lo + step * i as f64 };
        let y = f(x)?;
        evaluations += 1;
        if y > best.1 {
            best = (x, y);
            best_index = i;
        }
    }
    let a = lo + step * best_index.saturating_sub(1) as f64;
    let b = (lo + step * (best_index + 1) as f64).min(hi);
    let (points, width) = golden_section(a, b, tolerance, &mut f)?;
    evaluations += points.len();
    for &(x, y) in &points {
        if y > best.1 {
            best = (x, y);
        }
    }
    let tolerance = width.max(tolerance);
    Ok(Optimum {
        key: range.key.clone(),
        best: best.0,
        method: METHOD,
        asnr: best.1,
        lo,
        hi,
        tolerance,
        evaluations,
        at_bound: best.0 - lo <= tolerance || hi - best.0 <= tolerance,
    })
}

/// The most sweep worker threads: 4 × the available cores (more only add contention).
pub fn max_threads() -> usize {
    4 * std::thread::available_parallelism().map_or(1, std::num::NonZero::get)
}

/// Refuses a key given twice to `--over`, or given to both `--set` (or `--tolerance`, which is
/// `options.tolerance`) and `--over`: one value of it would silently be ignored.
pub fn check_over_keys(set: &[String], ranges: &[Range]) -> Result<()> {
    check_keys("--over", set, ranges)
}

/// [`check_over_keys`] for keys swept by `what` (`--over`, or `--points FILE`).
pub fn check_keys(what: &str, set: &[String], ranges: &[Range]) -> Result<()> {
    for (i, r) in ranges.iter().enumerate() {
        if ranges[..i].iter().any(|earlier| earlier.key == r.key) {
            anyhow::bail!("{what} {}: the key is given to {what} twice; give each key once", r.key);
        }
        if let Some(s) = set.iter().find(|s| s.split_once('=').is_some_and(|(k, _)| k.trim() == r.key)) {
            let given =
                if r.key == "options.tolerance" { format!("--set {s} or --tolerance") } else { format!("--set {s}") };
            anyhow::bail!(
                "{what} {}: the key is also given by {given}; {what} would override it: give it in one place",
                r.key
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_maximum_of_a_parabola() {
        let range = Range { key: "x".into(), lo: 0.0, hi: 10.0, points: None };
        let o = maximize(&range, 1e-8, |x| Ok(-(x - 3.3) * (x - 3.3))).unwrap();
        assert!((o.best - 3.3).abs() < 1e-8, "{}", o.best);
        assert!(o.evaluations < 80);
    }

    /// A tolerance below the float spacing of the bracket's ends stops at that spacing (it looped
    /// for ever) with the maximum found to it.
    #[test]
    fn a_tolerance_below_the_float_spacing_stops_there() {
        let range = Range { key: "x".into(), lo: 1.0, hi: 200.0, points: None };
        let o = maximize(&range, 0.0, |x| Ok(-(x - 100.3) * (x - 100.3))).unwrap();
        assert!((o.best - 100.3).abs() < 1e-6, "{}", o.best);
        assert!(o.evaluations < 200, "{}", o.evaluations);
    }

    #[test]
    fn maximum_at_an_end_of_the_range() {
        let range = Range { key: "x".into(), lo: 1.0, hi: 2.0, points: None };
        let o = maximize(&range, 1e-9, Ok).unwrap();
        assert!((o.best - 2.0).abs() < 1e-8, "{}", o.best);
        assert!(o.at_bound);
        let warning = bound_warning(&o).unwrap();
        assert!(warning.contains("at the bound HI = 2") && warning.contains("may lie outside LO:HI"), "{warning}");
        assert!(report(&o).contains("AT THE BOUND"));
        let o = maximize(&range, 1e-9, |x| Ok(-x)).unwrap();
        assert!(o.at_bound && bound_warning(&o).unwrap().contains("at the bound LO = 1"));
    }

    #[test]
    fn an_interior_maximum_is_not_at_the_bound() {
        let range = Range { key: "x".into(), lo: 0.0, hi: 10.0, points: None };
        let o = maximize(&range, 1e-6, |x| Ok(-(x - 3.3) * (x - 3.3))).unwrap();
        assert!(!o.at_bound && bound_warning(&o).is_none());
        assert!(report(&o).contains("golden-section search after a 17-point scan"), "{}", report(&o));
    }

    #[test]
    fn parses_ranges() {
        assert_eq!(
            parse_range("spectrum.range_nm=1:200", false).unwrap(),
            Range { key: "spectrum.range_nm".into(), lo: 1.0, hi: 200.0, points: None }
        );
        assert_eq!(parse_range("lens.f_number=1.4:5:40", true).unwrap().points, Some(40));
        assert!(parse_range("a=2:1", false).unwrap_err().to_string().contains("LO = 2 must be below HI = 1"));
        assert!(parse_range("a=1:x", false).unwrap_err().to_string().contains("HI `x` is not a finite number"));
        assert!(parse_range("a", false).unwrap_err().to_string().contains("expected KEY=LO:HI"));
        assert!(parse_range("a=-1e308:1e308", false).unwrap_err().to_string().contains("overflows"));
    }
}
