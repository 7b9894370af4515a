//! `asnr optimize`: the values of numeric scene keys that maximize the ASNR: one key by a scan and
//! golden-section search ([`maximize`]), several by COBYLA from the best of a Halton start set
//! ([`maximize_many`]).

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
    let key = key.trim();
    if key.is_empty() {
        bail!("--over {arg}: no key before `=`; expected {form} with a dotted key, e.g. --over lens.f_number=2:4");
    }
    // one spelling per entry: lens.binary2[01] is lens.binary2[1]
    let key = scene::canonical_key(key)
        .with_context(|| format!("--over {arg}: `{key}` is not a dotted key or a list entry (e.g. lens.binary2[1])"))?;
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
    Ok(Range { key, lo, hi, points })
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
    /// What was maximized (written only when it is not the ASNR).
    #[serde(skip_serializing_if = "is_asnr")]
    pub objective: crate::objective::Objective,
}

fn is_asnr(o: &crate::objective::Objective) -> bool {
    *o == crate::objective::Objective::Asnr
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
        "best {} = {:.6} (±{:.2e}, golden-section search after a {SCAN_POINTS}-point scan) → {} {:.6}   [{} evaluations over {}…{}]{}\n",
        o.key,
        o.best,
        o.tolerance,
        o.objective.label(),
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
        objective: crate::objective::Objective::Asnr,
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
        let same = |k: &str| scene::canonical_key(k).is_some_and(|k| k == r.key);
        if let Some(s) = set.iter().find(|s| s.split_once('=').is_some_and(|(k, _)| same(k))) {
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

// ---- several keys ----

/// How [`maximize_many`] finds `best` (the JSON's `method`).
pub const METHOD_MANY: &str = "COBYLA (Powell 1994, bounded, NLopt 2.7.1's) from the best of a Halton start set";

/// The most keys one search varies (the Halton start set takes one prime base per key).
pub const MAX_KEYS: usize = 16;

/// The most keys the gradient search varies ([`maximize_many_gradient`]): a freeform profile of
/// tens of terms or knots.
pub const MAX_KEYS_GRADIENT: usize = 64;

/// The first [`MAX_KEYS_GRADIENT`] primes: the bases of the Halton sequence, one per key.
const PRIMES: [u64; MAX_KEYS_GRADIENT] = [
    2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97, 101, 103, 107, 109,
    113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193, 197, 199, 211, 223, 227, 229, 233, 239,
    241, 251, 257, 263, 269, 271, 277, 281, 283, 293, 307, 311,
];

/// Settings of a search over several keys.
#[derive(Clone, Debug, PartialEq)]
pub struct Search {
    /// The search stops when COBYLA's steps fall below this fraction of each key's range.
    pub xtol: f64,
    /// Points of the Halton start set (0: [`Search::default_starts`]).
    pub starts: usize,
    /// The most evaluations, start set included.
    pub max_evaluations: usize,
}

impl Search {
    /// The default start set: 10 points per key.
    pub fn default_starts(keys: usize) -> usize {
        10 * keys
    }

    /// The default evaluation limit.
    pub const DEFAULT_MAX_EVALUATIONS: usize = 500;
}

/// `u` in [0, 1) at `index` of the Halton sequence in `base` (the radical inverse).
pub fn halton(mut index: u64, base: u64) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while index > 0 {
        f /= base as f64;
        r += f * (index % base) as f64;
        index /= base;
    }
    r
}

/// One evaluated point of a search.
#[derive(Clone, Debug, Serialize)]
pub struct Evaluated {
    /// The keys' values.
    pub values: Vec<f64>,
    /// The objective there.
    pub asnr: f64,
    /// Whether the Fraunhofer model holds there (SI eq. S15); where it does not, the search
    /// counts the point as ASNR 0 (penalized).
    pub fraunhofer_valid: bool,
    /// `scene` (the design's own values), `start` (the Halton set) or `local` (COBYLA).
    pub stage: &'static str,
}

impl Evaluated {
    /// What the search maximizes: the objective, or 0 where the Fraunhofer model fails.
    pub fn score(&self) -> f64 {
        if self.fraunhofer_valid && self.asnr.is_finite() { self.asnr } else { 0.0 }
    }
}

/// The result of [`maximize_many`].
#[derive(Clone, Debug)]
pub struct ManyOptimum {
    /// The ranges searched.
    pub ranges: Vec<Range>,
    /// Every point evaluated, in order: the start set, then COBYLA's.
    pub history: Vec<Evaluated>,
    /// The index in `history` of the best point (the highest score).
    pub best: usize,
    /// The index in `history` of the best start point (COBYLA's first point).
    pub best_start: usize,
    /// How COBYLA stopped.
    pub stopped: String,
    /// Whether it stopped by converging (not at the evaluation limit).
    pub converged: bool,
    /// Per key: whether the best value is within [`ManyOptimum::bound_tolerance`] of a bound.
    pub at_bound: Vec<bool>,
    /// The settings.
    pub search: Search,
    /// How the local search ran: [`METHOD_MANY`] or [`METHOD_GRADIENT`].
    pub method: &'static str,
    /// The gradient search only: the gradient at the best point (per unit of each key) and the
    /// largest component of its projection on the box (per whole range of each key).
    pub gradient: Option<(Vec<f64>, f64)>,
    /// How well the data determine the optimum ([`determination`]).
    pub determination: Determination,
}

/// Points whose objective is within this fraction of the best are near-equal: a difference the
/// evaluations' own tolerance (10⁻⁴ of the mean MTF for the README's searches) can hide.
pub const NEAR_EQUAL: f64 = 1e-4;

/// A key is ill-determined when its near-equal points span more than this many times the
/// search's step tolerance (`--xtol` of its range), and more than [`ILL_DETERMINED_FRACTION`]
/// of its range: the optimum's value of the key is not known to the resolution the search
/// reports it with.
pub const ILL_DETERMINED_XTOLS: f64 = 10.0;

/// The smallest span (a fraction of a key's range) that makes a key ill-determined: near a
/// smooth maximum the points within [`NEAR_EQUAL`] of it lie within about √NEAR_EQUAL = 1 % of
/// the peak's width, which is no ridge.
pub const ILL_DETERMINED_FRACTION: f64 = 0.01;

/// The span (a fraction of a key's range) beyond which a key is ill-determined.
pub fn ill_determined_span(xtol: f64) -> f64 {
    (ILL_DETERMINED_XTOLS * xtol).max(ILL_DETERMINED_FRACTION)
}

/// How well a search's evaluations determine its optimum (issue of a flat ridge): the points
/// whose objective is within [`NEAR_EQUAL`] of the best, the span of each key over them, and
/// for the gradient search the flattest direction of the curvature L-BFGS estimated.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Determination {
    /// The fraction of the best objective within which points are near-equal.
    pub near_equal: f64,
    /// Near-equal points (the best among them).
    pub points: usize,
    /// Per key: the smallest and largest value over the near-equal points.
    pub spread: Vec<[f64; 2]>,
    /// Per key: whether its spread exceeds [`ill_determined_span`] of its range.
    pub ill_determined: Vec<bool>,
    /// The gradient search only: the direction (per unit of each key, unit length in ranges) in
    /// which the objective is flattest by the L-BFGS curvature, and how far along it (in units
    /// of the ranges) the objective falls by [`NEAR_EQUAL`] of itself.
    pub weak_direction: Option<(Vec<f64>, f64)>,
}

/// The near-equal points of `history` around its best point `best` over `ranges` (module
/// [`Determination`]).
pub fn determination(ranges: &[Range], history: &[Evaluated], best: usize, xtol: f64) -> Determination {
    let top = history[best].score();
    let threshold = top - NEAR_EQUAL * top.abs();
    let near: Vec<&Evaluated> = history.iter().filter(|e| e.score() >= threshold && e.score() > 0.0).collect();
    let spread: Vec<[f64; 2]> = (0..ranges.len())
        .map(|k| {
            near.iter()
                .map(|e| e.values[k])
                .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], v| [lo.min(v), hi.max(v)])
        })
        .collect();
    let ill_determined =
        spread.iter().zip(ranges).map(|([lo, hi], r)| hi - lo > ill_determined_span(xtol) * (r.hi - r.lo)).collect();
    Determination { near_equal: NEAR_EQUAL, points: near.len(), spread, ill_determined, weak_direction: None }
}

/// The flattest direction of the curvature whose inverse is `inverse` (rows, in the ranges'
/// scaled coordinates): the eigenvector of its largest eigenvalue μ (the inverse curvature),
/// and the distance `√(2 δ μ)` along it where a quadratic with that curvature falls by
/// `δ = NEAR_EQUAL × |value|`.
fn weak_direction(inverse: &[Vec<f64>], value: f64) -> Option<(Vec<f64>, f64)> {
    let n = inverse.len();
    let m = nalgebra::DMatrix::from_fn(n, n, |i, j| 0.5 * (inverse[i][j] + inverse[j][i]));
    let eigen = m.symmetric_eigen();
    let (k, mu) = eigen.eigenvalues.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    if !(mu.is_finite() && *mu > 0.0) {
        return None;
    }
    let v: Vec<f64> = eigen.eigenvectors.column(k).iter().copied().collect();
    // a sign convention: the largest component positive
    let sign = v.iter().copied().max_by(|a, b| a.abs().total_cmp(&b.abs())).map_or(1.0, f64::signum);
    Some((v.iter().map(|x| sign * x).collect(), (2.0 * NEAR_EQUAL * value.abs() * mu).sqrt()))
}

impl ManyOptimum {
    /// A value within this fraction of its range from a bound is at the bound: 10 × xtol, at
    /// least 1e-6 (COBYLA steps to a bound, but stops within about xtol of where it aims).
    pub fn bound_tolerance(&self) -> f64 {
        (10.0 * self.search.xtol).max(1e-6)
    }

    /// For each key, whether the best point's value is within
    /// [`bound_tolerance`](Self::bound_tolerance) of its range from either bound.
    fn at_bounds(&self) -> Vec<bool> {
        let tol = self.bound_tolerance();
        self.ranges
            .iter()
            .zip(&self.best().values)
            .map(|(r, &x)| x - r.lo <= tol * (r.hi - r.lo) || r.hi - x <= tol * (r.hi - r.lo))
            .collect()
    }

    /// The best point.
    pub fn best(&self) -> &Evaluated {
        &self.history[self.best]
    }

    /// Evaluations before COBYLA's: the Halton set, and the scene's own values when inside the
    /// bounds.
    pub fn start_count(&self) -> usize {
        self.history.iter().filter(|e| e.stage != "local").count()
    }

    /// Evaluations where the Fraunhofer model fails (counted as ASNR 0).
    pub fn penalized(&self) -> usize {
        self.history.iter().filter(|e| !e.fraunhofer_valid).count()
    }
}

/// Maximizes `f` over the box of `ranges`: `f` at a Halton start set of [`Search::starts`] points
/// (in parallel, collected in order), then COBYLA (Powell's linear-approximation trust region,
/// which keeps to the bounds) from the best of them in coordinates scaled to [0, 1] per key,
/// until its step is below `xtol` or the evaluations reach `max_evaluations`. A point where the
/// Fraunhofer model fails scores 0 ([`Evaluated::score`]). Repeated points are evaluated once.
/// Deterministic: the same ranges and settings give the same points.
pub fn maximize_many(
    ranges: &[Range],
    search: &Search,
    f: &(dyn Fn(&[f64]) -> Result<crate::objective::Value> + Sync),
    progress: &dyn crate::Progress,
) -> Result<ManyOptimum> {
    maximize_many_from(ranges, search, None, f, progress)
}

/// The start set of a search over several keys: the scene's own values `initial` when inside
/// the bounds (stage `scene`), then [`Search::starts`] points of the Halton sequence (default 10
/// per key), evaluated in parallel and collected in order; the search's settings with the start
/// count filled in. Refused: no keys, more than `max_keys`, an evaluation limit the start set
/// fills.
fn start_set(
    ranges: &[Range],
    search: &Search,
    initial: Option<&[f64]>,
    max_keys: usize,
    f: &(dyn Fn(&[f64]) -> Result<crate::objective::Value> + Sync),
    progress: &dyn crate::Progress,
) -> Result<(Search, Vec<Evaluated>)> {
    use rayon::prelude::*;
    let d = ranges.len();
    if d == 0 || d > max_keys {
        bail!("--over: {d} keys; expected 1 to {max_keys}");
    }
    let starts = if search.starts == 0 { Search::default_starts(d) } else { search.starts };
    if search.max_evaluations <= starts.saturating_add(1) {
        bail!(
            "--max-evaluations {}: expected more than the {starts} points of the start set (--starts) and the scene's own",
            search.max_evaluations
        );
    }
    let search = Search { starts, ..search.clone() };
    let to_key = |u: &[f64]| -> Vec<f64> {
        ranges.iter().zip(u).map(|(r, &u)| (r.lo + u.clamp(0.0, 1.0) * (r.hi - r.lo)).clamp(r.lo, r.hi)).collect()
    };
    progress.start(search.max_evaluations as u64);
    let inside = initial.filter(|x| x.len() == d && ranges.iter().zip(*x).all(|(r, &v)| (r.lo..=r.hi).contains(&v)));
    let start_points: Vec<Vec<f64>> = inside
        .map(<[f64]>::to_vec)
        .into_iter()
        .chain((1..=starts as u64).map(|i| to_key(&PRIMES[..d].iter().map(|&b| halton(i, b)).collect::<Vec<_>>())))
        .collect();
    let stages = std::iter::repeat_n("scene", usize::from(inside.is_some())).chain(std::iter::repeat("start"));
    let evaluated: Vec<Result<crate::objective::Value>> = start_points
        .par_iter()
        .map(|x| {
            let v = f(x);
            progress.advance(1);
            v
        })
        .collect();
    let mut history = Vec::with_capacity(start_points.len());
    for ((x, v), stage) in start_points.into_iter().zip(evaluated).zip(stages) {
        let v = v.inspect_err(|_| progress.finish())?;
        history.push(Evaluated { values: x, asnr: v.value, fraunhofer_valid: v.fraunhofer_valid, stage });
    }
    Ok((search, history))
}

/// [`maximize_many`] with `initial`, the design's own values of the keys, among the start points
/// when it lies inside the bounds (first, as stage `scene`): the search then never ends below
/// the design it started from.
pub fn maximize_many_from(
    ranges: &[Range],
    search: &Search,
    initial: Option<&[f64]>,
    f: &(dyn Fn(&[f64]) -> Result<crate::objective::Value> + Sync),
    progress: &dyn crate::Progress,
) -> Result<ManyOptimum> {
    let d = ranges.len();
    let (search, history) = start_set(ranges, search, initial, MAX_KEYS, f, progress)?;
    let to_key = |u: &[f64]| -> Vec<f64> {
        ranges.iter().zip(u).map(|(r, &u)| (r.lo + u.clamp(0.0, 1.0) * (r.hi - r.lo)).clamp(r.lo, r.hi)).collect()
    };
    let starts = search.starts;
    let first_local = history.len();
    let best_of = |h: &[Evaluated]| {
        h.iter().enumerate().fold(0, |best, (i, e)| if e.score() > h[best].score() { i } else { best })
    };
    let best_start = best_of(&history);
    let x0: Vec<f64> =
        ranges.iter().zip(&history[best_start].values).map(|(r, &x)| (x - r.lo) / (r.hi - r.lo)).collect();

    let state = std::cell::RefCell::new((history, None::<anyhow::Error>));
    let objective = |u: &[f64], _: &mut ()| -> f64 {
        let x = to_key(u);
        let mut s = state.borrow_mut();
        if s.1.is_some() {
            return 0.0;
        }
        if let Some(seen) = s.0.iter().find(|e| e.values == x) {
            return -seen.score();
        }
        match f(&x) {
            Ok(v) => {
                progress.advance(1);
                let e = Evaluated { values: x, asnr: v.value, fraunhofer_valid: v.fraunhofer_valid, stage: "local" };
                let score = e.score();
                s.0.push(e);
                -score
            }
            Err(e) => {
                s.1 = Some(e);
                0.0
            }
        }
    };
    // the first step: about half the spacing of the start set, at most a quarter of each range
    let rho = (0.5 * (starts as f64).powf(-1.0 / d as f64)).min(0.25).max(4.0 * search.xtol);
    let tolerances = cobyla::StopTols { xtol_abs: vec![search.xtol; d], ..cobyla::StopTols::default() };
    let no_constraints: Vec<&dyn cobyla::Func<()>> = Vec::new();
    let outcome = cobyla::minimize(
        objective,
        &x0,
        &vec![(0.0, 1.0); d],
        &no_constraints,
        (),
        search.max_evaluations - first_local,
        cobyla::RhoBeg::All(rho),
        Some(tolerances),
    );
    progress.finish();
    let (history, error) = state.into_inner();
    if let Some(e) = error {
        return Err(e);
    }
    let (stopped, converged) = match outcome {
        Ok((cobyla::SuccessStatus::XtolReached | cobyla::SuccessStatus::Success, _, _)) => {
            ("converged: COBYLA's step fell below --xtol × each key's range".to_owned(), true)
        }
        Ok((cobyla::SuccessStatus::MaxEvalReached, _, _)) => (
            format!(
                "not converged: stopped at --max-evaluations {} (raise it, or loosen --xtol)",
                search.max_evaluations
            ),
            false,
        ),
        Ok((status, _, _)) => (format!("stopped: {status:?}"), true),
        Err((cobyla::FailStatus::RoundoffLimited, _, _)) => {
            ("converged to roundoff: the ASNR's own numerical noise limits the step".to_owned(), true)
        }
        Err((status, _, _)) => bail!("internal error: COBYLA failed ({status:?})"),
    };
    let best = best_of(&history);
    if history[best].score() <= 0.0 {
        bail!(
            "no point of the search has a positive ASNR inside the Fraunhofer model (SI eq. S15): {} of {} points fail it; narrow the --over ranges to designs the model holds for",
            history.iter().filter(|e| !e.fraunhofer_valid).count(),
            history.len()
        );
    }
    let mut optimum = ManyOptimum {
        ranges: ranges.to_vec(),
        history,
        best,
        best_start,
        stopped,
        converged,
        at_bound: Vec::new(),
        search,
        method: METHOD_MANY,
        gradient: None,
        determination: Determination::default(),
    };
    optimum.determination = determination(ranges, &optimum.history, best, optimum.search.xtol);
    optimum.at_bound = optimum.at_bounds();
    Ok(optimum)
}

/// How [`maximize_many_gradient`] finds `best` (the JSON's `method`).
pub const METHOD_GRADIENT: &str =
    "projected L-BFGS (bounded quasi-Newton, Armijo along the projected path) from the best of a Halton start set";

/// The gradient search's stopping tolerance on the projected gradient, relative to the
/// objective: its largest component (per whole range of a key) below this fraction of the best
/// start's value.
pub const GRADIENT_GTOL: f64 = 1e-7;

/// The objective and its gradient (per unit of each key) at a point of a search.
pub type ValueAndGradient<'a> = dyn FnMut(&[f64]) -> Result<(crate::objective::Value, Vec<f64>)> + 'a;

/// Maximizes over the box of `ranges` by a bounded quasi-Newton search: `value` at the start
/// set ([`Search::starts`] Halton points and `initial`, in parallel, as [`maximize_many_from`]),
/// then projected L-BFGS ([`crate::quasi_newton::maximize`]) from the best of them with
/// `value_and_gradient` (the objective and its gradient per unit of each key), in coordinates
/// scaled to [0, 1] per key, until the projected gradient is below [`GRADIENT_GTOL`] of the
/// objective, a step below `xtol` of each range, an iteration's rise below the objective's
/// rounding, or the evaluations reach `max_evaluations` (each gradient evaluation counts once).
/// A point where the Fraunhofer model fails is stepped back from. Up to [`MAX_KEYS_GRADIENT`]
/// keys. The result carries the gradient at the optimum, its projection's size, and the
/// curvature's flattest direction ([`Determination::weak_direction`]).
pub fn maximize_many_gradient(
    ranges: &[Range],
    search: &Search,
    initial: Option<&[f64]>,
    value: &(dyn Fn(&[f64]) -> Result<crate::objective::Value> + Sync),
    value_and_gradient: &mut ValueAndGradient<'_>,
    progress: &dyn crate::Progress,
) -> Result<ManyOptimum> {
    let d = ranges.len();
    let (search, mut history) = start_set(ranges, search, initial, MAX_KEYS_GRADIENT, value, progress)?;
    let best_of = |h: &[Evaluated]| {
        h.iter().enumerate().fold(0, |best, (i, e)| if e.score() > h[best].score() { i } else { best })
    };
    let best_start = best_of(&history);
    if history[best_start].score() <= 0.0 {
        progress.finish();
        bail!(
            "no start point has a positive ASNR inside the Fraunhofer model (SI eq. S15): {} of {} points fail it; narrow the --over ranges to designs the model holds for",
            history.iter().filter(|e| !e.fraunhofer_valid).count(),
            history.len()
        );
    }
    let width: Vec<f64> = ranges.iter().map(|r| r.hi - r.lo).collect();
    let to_key = |u: &[f64]| -> Vec<f64> {
        ranges.iter().zip(u).map(|(r, &u)| (r.lo + u.clamp(0.0, 1.0) * (r.hi - r.lo)).clamp(r.lo, r.hi)).collect()
    };
    let u0: Vec<f64> =
        ranges.iter().zip(&history[best_start].values).map(|(r, &x)| (x - r.lo) / (r.hi - r.lo)).collect();
    let scale = history[best_start].score().abs().max(f64::MIN_POSITIVE);
    let settings = crate::quasi_newton::Settings {
        gtol: GRADIENT_GTOL * scale,
        xtol: search.xtol,
        ftol: 1e-12,
        first_step: 0.1,
        max_evaluations: search.max_evaluations - history.len(),
        ..crate::quasi_newton::Settings::default()
    };
    let mut local: Vec<Evaluated> = Vec::new();
    let found = crate::quasi_newton::maximize(&vec![0.0; d], &vec![1.0; d], &u0, &settings, |u| {
        let x = to_key(u);
        let (v, g) = value_and_gradient(&x)?;
        progress.advance(1);
        let e = Evaluated { values: x, asnr: v.value, fraunhofer_valid: v.fraunhofer_valid, stage: "local" };
        let score = (e.fraunhofer_valid && e.asnr.is_finite()).then_some(e.asnr);
        local.push(e);
        Ok(score.map(|s| (s, g.iter().zip(&width).map(|(g, w)| g * w).collect())))
    });
    progress.finish();
    let found = found?;
    history.extend(local);
    let best = best_of(&history);
    let gradient: Vec<f64> = found.gradient.iter().zip(&width).map(|(g, w)| g / w).collect();
    let mut optimum = ManyOptimum {
        ranges: ranges.to_vec(),
        history,
        best,
        best_start,
        stopped: found.stop.describe().to_owned(),
        converged: found.stop.converged(),
        at_bound: Vec::new(),
        search,
        method: METHOD_GRADIENT,
        gradient: Some((gradient, found.projected_gradient)),
        determination: Determination::default(),
    };
    optimum.determination = determination(ranges, &optimum.history, best, optimum.search.xtol);
    // only where the pairs span the keys: elsewhere L-BFGS's curvature is its scaling, a guess
    if found.pairs >= d {
        optimum.determination.weak_direction = weak_direction(&found.inverse_curvature, found.value);
    }
    optimum.at_bound = optimum.at_bounds();
    Ok(optimum)
}

/// A JSON object of keys to values, in the keys' order.
struct KeyMap<'a, T: Serialize>(&'a [Range], Vec<T>);

impl<T: Serialize> Serialize for KeyMap<'_, T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (r, v) in self.0.iter().zip(&self.1) {
            map.serialize_entry(&r.key, v)?;
        }
        map.end()
    }
}

/// The JSON report of a search over several keys (`asnr optimize --json` with two or more
/// `--over`): `best` and `at_bound` are objects keyed by the dotted keys.
pub fn many_json(
    label: &str,
    objective: crate::objective::Objective,
    scene_value: &crate::objective::Value,
    o: &ManyOptimum,
) -> Result<String> {
    #[derive(Serialize)]
    struct Json<'a> {
        scene: &'a str,
        objective: &'static str,
        method: &'static str,
        best: KeyMap<'a, f64>,
        asnr: f64,
        fraunhofer_valid: bool,
        at_bound: KeyMap<'a, bool>,
        evaluations: usize,
        start_points: usize,
        stopped: &'a str,
        converged: bool,
        scene_asnr: f64,
        scene_fraunhofer_valid: bool,
        best_start: KeyMap<'a, f64>,
        best_start_asnr: f64,
        penalized: usize,
        penalty: &'static str,
        ranges: KeyMap<'a, [f64; 2]>,
        xtol: f64,
        bound_tolerance: f64,
        #[serde(skip_serializing_if = "Option::is_none")]
        gradient: Option<KeyMap<'a, f64>>,
        #[serde(skip_serializing_if = "Option::is_none")]
        projected_gradient: Option<f64>,
        determination: DeterminationJson<'a>,
        history: &'a [Evaluated],
    }
    #[derive(Serialize)]
    struct DeterminationJson<'a> {
        ill_determined: bool,
        near_equal: f64,
        near_equal_points: usize,
        spread: KeyMap<'a, [f64; 2]>,
        ill_determined_keys: Vec<&'a str>,
        #[serde(skip_serializing_if = "Option::is_none")]
        weak_direction: Option<KeyMap<'a, f64>>,
        #[serde(skip_serializing_if = "Option::is_none")]
        weak_direction_reach: Option<f64>,
    }
    let best = o.best();
    let json = Json {
        scene: label,
        objective: objective.name(),
        method: o.method,
        best: KeyMap(&o.ranges, best.values.clone()),
        asnr: best.asnr,
        fraunhofer_valid: best.fraunhofer_valid,
        at_bound: KeyMap(&o.ranges, o.at_bound.clone()),
        evaluations: o.history.len(),
        start_points: o.start_count(),
        stopped: &o.stopped,
        converged: o.converged,
        scene_asnr: scene_value.value,
        scene_fraunhofer_valid: scene_value.fraunhofer_valid,
        best_start: KeyMap(&o.ranges, o.history[o.best_start].values.clone()),
        best_start_asnr: o.history[o.best_start].asnr,
        penalized: o.penalized(),
        penalty: PENALTY,
        ranges: KeyMap(&o.ranges, o.ranges.iter().map(|r| [r.lo, r.hi]).collect()),
        xtol: o.search.xtol,
        bound_tolerance: o.bound_tolerance(),
        gradient: o.gradient.as_ref().map(|(g, _)| KeyMap(&o.ranges, g.clone())),
        projected_gradient: o.gradient.as_ref().map(|(_, p)| *p),
        determination: DeterminationJson {
            ill_determined: o.determination.ill_determined.iter().any(|b| *b),
            near_equal: o.determination.near_equal,
            near_equal_points: o.determination.points,
            spread: KeyMap(&o.ranges, o.determination.spread.clone()),
            ill_determined_keys: o
                .ranges
                .iter()
                .zip(&o.determination.ill_determined)
                .filter(|(_, b)| **b)
                .map(|(r, _)| r.key.as_str())
                .collect(),
            weak_direction: o.determination.weak_direction.as_ref().map(|(v, _)| KeyMap(&o.ranges, v.clone())),
            weak_direction_reach: o.determination.weak_direction.as_ref().map(|(_, r)| *r),
        },
        history: &o.history,
    };
    Ok(serde_json::to_string_pretty(&json)?)
}

/// How a search treats a point outside the Fraunhofer model.
pub const PENALTY: &str = "points where the Fraunhofer model fails (SI eq. S15) are penalized: counted as ASNR 0";

/// The text report of a search over several keys.
pub fn many_report(
    label: &str,
    objective: crate::objective::Objective,
    scene_value: &crate::objective::Value,
    o: &ManyOptimum,
) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let best = o.best();
    let _ = writeln!(
        s,
        "{label}: the {} maximized over {} keys ({}, {} start points)",
        objective.label(),
        o.ranges.len(),
        o.method,
        o.search.starts
    );
    let width = o.ranges.iter().map(|r| r.key.chars().count()).max().unwrap_or(3).max(3);
    let _ = writeln!(s, "  {:<width$}  {:>14}  {:>14}  {:>14}", "key", "best", "LO", "HI");
    for ((r, &x), &bound) in o.ranges.iter().zip(&best.values).zip(&o.at_bound) {
        let side = if x - r.lo <= r.hi - x { "LO" } else { "HI" };
        let _ = writeln!(
            s,
            "  {:<width$}  {:>14.6}  {:>14}  {:>14}{}",
            r.key,
            x,
            r.lo,
            r.hi,
            if bound { format!("   AT THE BOUND {side}: the maximum may lie outside") } else { String::new() }
        );
    }
    let _ = writeln!(
        s,
        "{} {:.6} at the optimum{}   (the scene as given: {:.6}{}; the best start point: {:.6})",
        objective.label(),
        best.asnr,
        if best.fraunhofer_valid { "" } else { " (outside the Fraunhofer model)" },
        scene_value.value,
        if scene_value.fraunhofer_valid { "" } else { ", outside the Fraunhofer model" },
        o.history[o.best_start].asnr
    );
    let local = o.history.iter().filter(|e| e.stage == "local").count();
    let own =
        if o.history.first().is_some_and(|e| e.stage == "scene") { ", the scene's own values among them" } else { "" };
    let _ = writeln!(
        s,
        "{} evaluations ({} start points{own} + {local} by {}); {}",
        o.history.len(),
        o.start_count(),
        if o.method == METHOD_GRADIENT { "L-BFGS" } else { "COBYLA" },
        o.stopped
    );
    let _ =
        writeln!(s, "{} of {} evaluations outside the Fraunhofer model ({PENALTY})", o.penalized(), o.history.len());
    if let Some((gradient, projected)) = &o.gradient {
        let list: Vec<String> = o.ranges.iter().zip(gradient).map(|(r, g)| format!("{} {g:.3e}", r.key)).collect();
        let _ = writeln!(
            s,
            "gradient at the optimum (per unit of each key): {}; its projection on the box, largest component per whole range: {projected:.2e}",
            list.join(", ")
        );
    }
    s.push_str(&determination_report(o));
    s
}

/// The text on how well the optimum is determined: the near-equal points' spread of each
/// ill-determined key, and the gradient search's flattest direction.
pub fn determination_report(o: &ManyOptimum) -> String {
    use std::fmt::Write as _;
    let d = &o.determination;
    let mut s = String::new();
    let loose: Vec<String> = o
        .ranges
        .iter()
        .zip(&d.spread)
        .zip(&d.ill_determined)
        .filter(|(_, b)| **b)
        .map(|((r, [lo, hi]), _)| {
            format!("{} from {lo:.4} to {hi:.4} ({:.1} % of its range)", r.key, 100.0 * (hi - lo) / (r.hi - r.lo))
        })
        .collect();
    if loose.is_empty() {
        let _ = writeln!(
            s,
            "well determined: the {} points within {:.0e} of the best objective span at most {} % of each key's range",
            d.points,
            d.near_equal,
            100.0 * ill_determined_span(o.search.xtol)
        );
    } else {
        let _ = writeln!(
            s,
            "ILL-DETERMINED: {} of the evaluated points are within {:.0e} of the best objective (a difference the evaluations' tolerance can hide), and they span {}: the optimum lies on a flat ridge, and these keys' best values mean nothing finer than that span",
            d.points,
            d.near_equal,
            loose.join(", ")
        );
    }
    if let Some((v, reach)) = &d.weak_direction {
        let list: Vec<String> = o.ranges.iter().zip(v).map(|(r, x)| format!("{x:+.3} {}", r.key)).collect();
        let _ = writeln!(
            s,
            "flattest direction of the L-BFGS curvature (in units of each key's range): {}; along it the objective falls by {:.0e} of itself only {reach:.3} of the ranges away",
            list.join(", "),
            d.near_equal
        );
    }
    s
}

/// The warnings of a search over several keys: each key whose best value is at a bound.
pub fn many_bound_warnings(o: &ManyOptimum) -> Vec<String> {
    let best = o.best();
    o.ranges
        .iter()
        .zip(&best.values)
        .zip(&o.at_bound)
        .filter(|(_, b)| **b)
        .map(|((r, &x), _)| {
            let (end, value) = if x - r.lo <= r.hi - x { ("LO", r.lo) } else { ("HI", r.hi) };
            format!(
                "the best {} = {x} is at the bound {end} = {value} of --over {}={}:{}: the maximum may lie outside LO:HI; widen the range",
                r.key, r.key, r.lo, r.hi
            )
        })
        .collect()
}

/// Points per axis of [`landscape`].
pub const LANDSCAPE_POINTS: usize = 21;

/// The objective of a search over two keys on a [`LANDSCAPE_POINTS`]² grid of their ranges (the
/// first key slowest, `scene::sweep::axis` values), penalized as the search scores it
/// ([`Evaluated::score`]), in parallel and collected in order: the map behind the search's path.
pub fn landscape(
    source: &scene::Source,
    overrides: &[String],
    objective: crate::objective::Objective,
    ranges: &[Range],
    progress: &dyn crate::Progress,
) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    use rayon::prelude::*;
    let [x, y] = ranges else { bail!("a landscape takes two keys, not {}", ranges.len()) };
    let keys = [x.key.clone(), y.key.clone()];
    let target = crate::objective::Target::new(source.clone(), overrides.to_vec(), objective, &keys)?;
    let (xs, ys) = (scene::sweep::axis(x.lo, x.hi, LANDSCAPE_POINTS), scene::sweep::axis(y.lo, y.hi, LANDSCAPE_POINTS));
    progress.start((xs.len() * ys.len()) as u64);
    let z: Vec<Result<f64>> = (0..xs.len() * ys.len())
        .into_par_iter()
        .map(|i| {
            let v = target.value(&keys, &[xs[i / ys.len()], ys[i % ys.len()]]);
            progress.advance(1);
            v.map(|v| {
                Evaluated { values: Vec::new(), asnr: v.value, fraunhofer_valid: v.fraunhofer_valid, stage: "" }.score()
            })
        })
        .collect();
    progress.finish();
    Ok((xs, ys, z.into_iter().collect::<Result<_>>()?))
}

// ---- one search of a scene, as the command line and the Python package run it ----

/// What [`search_scene`] found: one key's golden-section optimum, or several keys' COBYLA one.
#[derive(Clone, Debug)]
pub enum Found {
    /// One key ([`maximize`]).
    One(Optimum),
    /// Several keys ([`maximize_many`]).
    Many(ManyOptimum),
}

/// A search of a scene: the objective, its value at the scene as given, and the optimum.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// How the scene is named.
    pub label: String,
    /// What was maximized.
    pub objective: crate::objective::Objective,
    /// The objective at the scene as given (its own values of the keys).
    pub scene_value: crate::objective::Value,
    /// The optimum.
    pub found: Found,
}

/// Refuses an `--xtol` outside [1e-12, 1): a finer bracket is below the float spacing.
pub fn check_xtol(xtol: f64) -> Result<()> {
    if !(1e-12..1.0).contains(&xtol) {
        // as typed: 1e-17, not 0.00000000000000001
        let xtol = if xtol != 0.0 && xtol.abs() < 1e-4 { format!("{xtol:e}") } else { format!("{xtol}") };
        bail!(
            "--xtol {xtol}: expected a fraction of the range in [1e-12, 1) (a finer bracket is below the float spacing of the range's values)"
        );
    }
    Ok(())
}

/// The local search of `asnr optimize --method` over the keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// COBYLA, derivative-free ([`maximize_many`]): up to [`MAX_KEYS`] keys, any objective.
    Cobyla,
    /// Projected L-BFGS on the engines' exact gradient ([`maximize_many_gradient`]): up to
    /// [`MAX_KEYS_GRADIENT`] keys, the smooth objectives (`asnr`, `asnr_glare`, `fov_mean`) and the
    /// keys `asnr gradient` differentiates.
    Gradient,
}

impl Method {
    /// `cobyla` or `gradient`, as `--method` takes it.
    pub fn parse(name: &str) -> Result<Method> {
        match name.trim() {
            "cobyla" => Ok(Method::Cobyla),
            "gradient" => Ok(Method::Gradient),
            other => bail!("--method {other}: expected cobyla (derivative-free, the default) or gradient"),
        }
    }

    /// The name `--method` takes.
    pub fn name(self) -> &'static str {
        match self {
            Method::Cobyla => "cobyla",
            Method::Gradient => "gradient",
        }
    }
}

/// Maximizes `objective` of the scene `source` with `overrides` over `ranges`: one key by
/// [`maximize`] (a scan and golden section to `search.xtol` of the range, every point counted,
/// as `asnr optimize` always did), several by [`maximize_many`]. The command line and the Python
/// package's `asnr.optimize` both call it, so they print the same numbers.
pub fn search_scene(
    source: scene::Source,
    overrides: Vec<String>,
    ranges: &[Range],
    objective: crate::objective::Objective,
    search: &Search,
    progress: &dyn crate::Progress,
) -> Result<Outcome> {
    search_scene_by(source, overrides, ranges, objective, search, None, progress)
}

/// [`search_scene`] by `method` when given: [`Method::Cobyla`] runs [`maximize_many`] even over
/// one key, [`Method::Gradient`] [`maximize_many_gradient`] with
/// [`crate::objective::Target::value_and_gradient`]. Without a method one key is searched by golden
/// section and several by COBYLA. The gradient method first takes the gradient once at the
/// centre of the box, so that an objective or a key without a gradient is refused, named, before
/// any search.
pub fn search_scene_by(
    source: scene::Source,
    overrides: Vec<String>,
    ranges: &[Range],
    objective: crate::objective::Objective,
    search: &Search,
    method: Option<Method>,
    progress: &dyn crate::Progress,
) -> Result<Outcome> {
    check_xtol(search.xtol)?;
    check_over_keys(&overrides, ranges)?;
    let keys: Vec<String> = ranges.iter().map(|r| r.key.clone()).collect();
    let label = source.label().to_owned();
    let target = crate::objective::Target::new(source, overrides, objective, &keys)?;
    if method == Some(Method::Gradient) {
        if ranges.len() > MAX_KEYS_GRADIENT {
            bail!("--over: {} keys; expected 1 to {MAX_KEYS_GRADIENT} with --method gradient", ranges.len());
        }
        let centre: Vec<f64> = ranges.iter().map(|r| 0.5 * (r.lo + r.hi)).collect();
        target.value_and_gradient(&keys, &centre).map_err(|e| {
            // the gradient's messages name its own flag; here the keys come from --over
            anyhow::anyhow!("--method gradient: {}", format!("{e:#}").replace("--wrt ", "--over "))
        })?;
    }
    let scene_value = target.value(&[], &[])?;
    let found = if let (None, [range]) = (method, ranges) {
        if search.starts != 0 || search.max_evaluations != Search::DEFAULT_MAX_EVALUATIONS {
            bail!(
                "--starts and --max-evaluations apply to a search over several keys; one key is searched by a {SCAN_POINTS}-point scan and golden section"
            );
        }
        let mut best = maximize(range, search.xtol * (range.hi - range.lo), |x| {
            Ok(target.value(std::slice::from_ref(&range.key), &[x])?.value)
        })?;
        best.objective = objective;
        Found::One(best)
    } else {
        // the design's own values of the keys, where the scene has them (a key it lacks is set by
        // the search alone); an element past the end of a list the scene has is 0, as `--set`
        // and `--over` extend a list with zeros: the scene as given is that point (a Binary 2
        // profile searched with terms it lacks starts from its own profile too)
        let own = |k: &String| {
            crate::objective::number_at(target.source(), target.overrides(), k).ok().or_else(|| {
                let (list, _) = k.strip_suffix(']')?.rsplit_once('[')?;
                crate::objective::number_at(target.source(), target.overrides(), &format!("{list}[0]"))
                    .ok()
                    .map(|_| 0.0)
            })
        };
        let initial: Option<Vec<f64>> = keys.iter().map(own).collect();
        let value = |x: &[f64]| target.value(&keys, x);
        Found::Many(match method {
            Some(Method::Gradient) => maximize_many_gradient(
                ranges,
                search,
                initial.as_deref(),
                &value,
                &mut |x: &[f64]| target.value_and_gradient(&keys, x),
                progress,
            )?,
            None | Some(Method::Cobyla) => maximize_many_from(ranges, search, initial.as_deref(), &value, progress)?,
        })
    };
    Ok(Outcome { label, objective, scene_value, found })
}

/// The JSON of a search: one key's as `asnr optimize --json` always printed it, several keys'
/// by [`many_json`].
pub fn outcome_json(o: &Outcome) -> Result<String> {
    match &o.found {
        Found::One(best) => Ok(serde_json::to_string_pretty(best)?),
        Found::Many(many) => many_json(&o.label, o.objective, &o.scene_value, many),
    }
}

/// The text report of a search.
pub fn outcome_report(o: &Outcome) -> String {
    match &o.found {
        Found::One(best) => report(best),
        Found::Many(many) => many_report(&o.label, o.objective, &o.scene_value, many),
    }
}

/// The warnings of a search: each key whose best value is at a bound.
pub fn outcome_warnings(o: &Outcome) -> Vec<String> {
    match &o.found {
        Found::One(best) => bound_warning(best).into_iter().collect(),
        Found::Many(many) => many_bound_warnings(many),
    }
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

    fn value(v: f64) -> Result<crate::objective::Value> {
        Ok(crate::objective::Value { value: v, fraunhofer_valid: true })
    }

    fn ranges(bounds: &[(f64, f64)]) -> Vec<Range> {
        bounds.iter().enumerate().map(|(i, &(lo, hi))| Range { key: format!("k{i}"), lo, hi, points: None }).collect()
    }

    const SEARCH: Search = Search { xtol: 1e-6, starts: 0, max_evaluations: 2000 };

    /// A quadratic bowl in three keys: the optimum to about xtol, inside the bounds, converged.
    #[test]
    fn several_keys_find_the_maximum_of_a_quadratic() {
        let f = |x: &[f64]| value(5.0 - (x[0] - 1.0).powi(2) - 2.0 * (x[1] + 0.5).powi(2) - 0.5 * (x[2] - 3.0).powi(2));
        let o = maximize_many(&ranges(&[(-5.0, 5.0), (-5.0, 5.0), (0.0, 10.0)]), &SEARCH, &f, &()).unwrap();
        let best = &o.best().values;
        for (x, want, range) in [(best[0], 1.0, 10.0), (best[1], -0.5, 10.0), (best[2], 3.0, 10.0)] {
            assert!((x - want).abs() < 1e-3 * range, "{best:?}");
        }
        assert!(o.converged && o.at_bound.iter().all(|b| !b), "{} {:?}", o.stopped, o.at_bound);
        assert_eq!(o.history.iter().filter(|e| e.stage == "start").count(), 30);
        assert!(o.history.len() < 400, "{}", o.history.len());
    }

    /// Two peaks (the higher of the two bumps, so each peak is exactly where its bump is): the
    /// start set finds the basin of the higher one, narrower and farther from the centre, which a
    /// local search from the centre would miss.
    #[test]
    fn the_start_set_finds_the_higher_of_two_peaks() {
        let f = |x: &[f64]| {
            let bump = |cx: f64, cy: f64, w: f64| (-((x[0] - cx).powi(2) + (x[1] - cy).powi(2)) / w).exp();
            value((2.0 * bump(0.8, 0.15, 0.01)).max(bump(0.45, 0.55, 0.2)))
        };
        let o = maximize_many(&ranges(&[(0.0, 1.0), (0.0, 1.0)]), &SEARCH, &f, &()).unwrap();
        let best = &o.best().values;
        assert!((best[0] - 0.8).abs() < 1e-4 && (best[1] - 0.15).abs() < 1e-4, "{best:?}");
        assert!((o.best().asnr - 2.0).abs() < 1e-6, "{}", o.best().asnr);
    }

    /// A maximum on a bound is found there and flagged, key by key.
    #[test]
    fn a_maximum_on_a_bound_is_flagged() {
        let f = |x: &[f64]| value(x[0] - (x[1] - 0.3).powi(2));
        let o = maximize_many(&ranges(&[(1.0, 2.0), (0.0, 1.0)]), &SEARCH, &f, &()).unwrap();
        assert_eq!(o.at_bound, vec![true, false]);
        assert!((o.best().values[0] - 2.0).abs() < 1e-5, "{:?}", o.best().values);
        let w = many_bound_warnings(&o);
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("the best k0 = ") && w[0].contains("at the bound HI = 2"), "{w:?}");
        let scene = crate::objective::Value { value: 1.0, fraunhofer_valid: true };
        let text = many_report("toy", crate::objective::Objective::Asnr, &scene, &o);
        assert!(text.contains("AT THE BOUND HI"), "{text}");
        let json: serde_json::Value =
            serde_json::from_str(&many_json("toy", crate::objective::Objective::Asnr, &scene, &o).unwrap()).unwrap();
        assert_eq!(json["at_bound"]["k0"], true);
        assert_eq!(json["at_bound"]["k1"], false);
        assert!((json["best"]["k1"].as_f64().unwrap() - 0.3).abs() < 1e-4, "{json}");
        assert_eq!(json["evaluations"].as_u64().unwrap() as usize, o.history.len());
    }

    /// Points outside the Fraunhofer model score 0: the higher ASNR beyond x = 0.5 is not taken.
    #[test]
    fn points_outside_the_fraunhofer_model_are_penalized() {
        let f = |x: &[f64]| Ok(crate::objective::Value { value: 1.0 + x[0] + x[1], fraunhofer_valid: x[0] <= 0.5 });
        let o = maximize_many(&ranges(&[(0.0, 1.0), (0.0, 1.0)]), &SEARCH, &f, &()).unwrap();
        assert!(o.best().fraunhofer_valid && o.best().values[0] <= 0.5, "{:?}", o.best());
        assert!((o.best().values[0] - 0.5).abs() < 1e-3, "{:?}", o.best().values);
        assert!(o.penalized() > 0);
        let all_invalid = |_: &[f64]| Ok(crate::objective::Value { value: 1.0, fraunhofer_valid: false });
        let e = maximize_many(&ranges(&[(0.0, 1.0), (0.0, 1.0)]), &SEARCH, &all_invalid, &()).unwrap_err();
        assert!(e.to_string().contains("inside the Fraunhofer model"), "{e}");
    }

    /// An evaluation's error stops the search and is returned, the point named by the caller.
    #[test]
    fn an_evaluation_error_is_returned() {
        let f = |x: &[f64]| if x[0] > 0.9 { Err(anyhow::anyhow!("at k0={}: bad", x[0])) } else { value(x[0]) };
        let e = maximize_many(&ranges(&[(0.0, 1.0), (0.0, 1.0)]), &SEARCH, &f, &()).unwrap_err();
        assert!(e.to_string().contains(": bad"), "{e}");
        let few = Search { max_evaluations: 21, ..SEARCH };
        let e = maximize_many(&ranges(&[(0.0, 1.0), (0.0, 1.0)]), &few, &f, &()).unwrap_err();
        assert!(
            e.to_string().contains("--max-evaluations 21: expected more than the 20 points of the start set"),
            "{e}"
        );
    }

    /// The gradient search on a concave quadratic in 20 keys (more than COBYLA's 16), its
    /// maximum inside the box but for two keys cut off by a bound: the optimum to 2.5e-5 of each
    /// range (the projected gradient's tolerance, 1e-7 of the objective), the two at their bounds and flagged, the projected gradient small, the gradient
    /// reported per unit of each key, the near-equal points bracketing it; a flat direction (one
    /// key the objective ignores) is reported as ill-determined by the near-equal points' spread.
    #[test]
    fn the_gradient_search_finds_a_bounded_optimum_in_twenty_keys() {
        let d = 20;
        let centre: Vec<f64> = (0..d).map(|i| if i < 2 { 3.0 } else { 0.1 * i as f64 - 0.5 }).collect();
        let weight: Vec<f64> = (0..d).map(|i| 1.0 + 0.25 * i as f64).collect();
        let f =
            |x: &[f64]| 1000.0 - x.iter().zip(&centre).zip(&weight).map(|((x, c), w)| w * (x - c).powi(2)).sum::<f64>();
        let grad = |x: &[f64]| -> Vec<f64> {
            x.iter().zip(&centre).zip(&weight).map(|((x, c), w)| -2.0 * w * (x - c)).collect()
        };
        let r = ranges(&vec![(-2.0, 2.0); d]);
        let mut with_gradient =
            |x: &[f64]| Ok((crate::objective::Value { value: f(x), fraunhofer_valid: true }, grad(x)));
        let o = maximize_many_gradient(&r, &SEARCH, None, &|x: &[f64]| value(f(x)), &mut with_gradient, &()).unwrap();
        let best = &o.best().values;
        for (i, (x, c)) in best.iter().zip(&centre).enumerate() {
            let want = c.clamp(-2.0, 2.0);
            assert!((x - want).abs() < 1e-4, "key {i}: {x} vs {want} ({})", o.stopped);
            assert_eq!(o.at_bound[i], i < 2, "key {i}");
        }
        assert!(o.converged && o.method == METHOD_GRADIENT, "{}", o.stopped);
        let (g, projected) = o.gradient.clone().unwrap();
        // the projected gradient below GRADIENT_GTOL of the objective (1e-4 per range here)
        assert!((g[0] - 2.0).abs() < 1e-3 && projected < 1e-4, "{g:?} {projected}");
        assert!(o.history.len() < 400, "{} evaluations", o.history.len());
        // the near-equal points (within 1e-4 of 1000: 0.1) bracket the optimum; the keys at a
        // bound are pinned there
        for (i, [lo, hi]) in o.determination.spread.iter().enumerate() {
            assert!(*lo <= best[i] && best[i] <= *hi, "key {i}");
            assert_eq!(
                o.determination.ill_determined[i],
                i >= 2 && hi - lo > ill_determined_span(SEARCH.xtol) * 4.0,
                "key {i}"
            );
        }
        let text = many_report(
            "toy",
            crate::objective::Objective::Asnr,
            &crate::objective::Value { value: 1.0, fraunhofer_valid: true },
            &o,
        );
        assert!(text.contains("projected L-BFGS") && text.contains("gradient at the optimum"), "{text}");

        // a ridge: near-equal points (within 1e-4 of the best) spread along the second key
        let r = ranges(&[(0.0, 1.0), (0.0, 1.0)]);
        let point =
            |x: f64, y: f64, v: f64| Evaluated { values: vec![x, y], asnr: v, fraunhofer_valid: true, stage: "local" };
        let history =
            vec![point(0.3, 0.2, 0.99995), point(0.3, 0.5, 1.0), point(0.3001, 0.8, 0.99992), point(0.6, 0.5, 0.9)];
        let d = determination(&r, &history, 1, 1e-3);
        assert_eq!((d.points, d.ill_determined.clone()), (3, vec![false, true]), "{d:?}");
        assert_eq!(d.spread[1], [0.2, 0.8]);
        let o = ManyOptimum {
            ranges: r,
            history,
            best: 1,
            best_start: 1,
            at_bound: vec![false, false],
            gradient: Some((vec![0.0, 0.0], 0.0)),
            determination: d,
            ..o
        };
        let text = determination_report(&o);
        assert!(
            text.contains("ILL-DETERMINED") && text.contains("k1 from 0.2000 to 0.8000") && text.contains("flat ridge"),
            "{text}"
        );
        let json: serde_json::Value = serde_json::from_str(
            &many_json(
                "toy",
                crate::objective::Objective::Asnr,
                &crate::objective::Value { value: 1.0, fraunhofer_valid: true },
                &o,
            )
            .unwrap(),
        )
        .unwrap();
        assert_eq!(json["determination"]["ill_determined"], true, "{json}");
        assert_eq!(json["determination"]["ill_determined_keys"][0], "k1", "{json}");
        assert!(json["gradient"]["k0"].as_f64().unwrap().abs() < 1e-3, "{json}");
    }

    /// The same search twice gives the same points, bit for bit.
    #[test]
    fn a_search_is_deterministic() {
        let f = |x: &[f64]| value((3.0 * x[0]).sin() * (2.0 * x[1]).cos());
        let run = || maximize_many(&ranges(&[(0.0, 2.0), (-1.0, 1.0)]), &SEARCH, &f, &()).unwrap();
        let (a, b) = (run(), run());
        let bits =
            |o: &ManyOptimum| o.history.iter().flat_map(|e| e.values.clone()).map(f64::to_bits).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(halton(1, 2), 0.5);
        assert!((halton(5, 3) - 7.0 / 9.0).abs() < 1e-15);
    }

    /// `--method gradient` refuses a key without a gradient and an objective without one before
    /// the search evaluates anything (no progress started), naming the flag and the key; the same
    /// search by COBYLA runs.
    #[test]
    fn the_gradient_method_refuses_before_searching() {
        struct Count(std::sync::atomic::AtomicU64);
        impl crate::Progress for Count {
            fn start(&self, _: u64) {
                self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
            fn advance(&self, steps: u64) {
                self.0.fetch_add(steps, std::sync::atomic::Ordering::Relaxed);
            }
        }
        let source = scene::read(None).unwrap();
        let r = [
            Range { key: "camera.pixel_pitch_um".into(), lo: 2.0, hi: 8.0, points: None },
            Range { key: "lens.design_wavelength_nm".into(), lo: 790.0, hi: 810.0, points: None },
        ];
        let search = Search { xtol: 1e-4, starts: 0, max_evaluations: Search::DEFAULT_MAX_EVALUATIONS };
        let asnr = crate::objective::Objective::Asnr;
        let count = Count(0.into());
        // a library lens: its design wavelength chooses its atoms (piecewise), no gradient
        let library =
            scene::read(Some(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/library.toml")))
                .unwrap();
        let e = search_scene_by(library, vec![], &r, asnr, &search, Some(Method::Gradient), &count).unwrap_err();
        let e = format!("{e:#}");
        assert!(
            e.starts_with("--method gradient: --over lens.design_wavelength_nm: not differentiable here yet"),
            "{e}"
        );
        assert_eq!(count.0.load(std::sync::atomic::Ordering::Relaxed), 0);
        let capacity = crate::objective::Objective::Capacity;
        let one = &r[..1];
        let e = search_scene_by(source.clone(), vec![], one, capacity, &search, Some(Method::Gradient), &count);
        let e = format!("{:#}", e.unwrap_err());
        assert!(e.starts_with("--method gradient: --objective capacity"), "{e}");
        assert_eq!(count.0.load(std::sync::atomic::Ordering::Relaxed), 0);
        let o = search_scene_by(source, vec![], &r, asnr, &search, Some(Method::Cobyla), &count).unwrap();
        assert!(matches!(o.found, Found::Many(ref m) if m.method == METHOD_MANY));
        assert!(count.0.load(std::sync::atomic::Ordering::Relaxed) > 0);
    }

    #[test]
    fn methods_parse_by_name() {
        assert_eq!(Method::parse("gradient").unwrap(), Method::Gradient);
        assert_eq!(Method::parse(Method::Cobyla.name()).unwrap(), Method::Cobyla);
        let e = Method::parse("lbfgs").unwrap_err().to_string();
        assert!(e.contains("--method lbfgs: expected cobyla") && e.contains("gradient"), "{e}");
    }
}
