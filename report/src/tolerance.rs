//! `asnr tolerance`: how a design's ASNR survives fabrication, by Monte Carlo over distributions
//! of its keys (as Zemax's tolerancing does for a lens prescription).
//!
//! Each `--vary KEY=DIST` draws the key around its nominal value (the scene's, every default
//! filled in): `normal:S` (σ = S in the key's units), `normal:S%` (σ = S % of the nominal
//! value) or `uniform:LO:HI` (the key's value uniform in [LO, HI]). All draws are made first, in
//! sample order, from one `rand_pcg::Pcg64` seeded by `--seed` ([`draw`]); the samples are then
//! evaluated in parallel and collected in order, so the results depend on the seed alone, not on
//! the number of threads. The report: the nominal ASNR, the samples' mean, standard deviation
//! and percentiles, and each key's sensitivity, the change of the ASNR per σ of the key (the
//! coefficients of the least-squares fit of the ASNR to the keys' standardized deviations:
//! exact for an ASNR linear in the keys).

use std::fmt::Write as _;

use anyhow::{Context, Result, bail};
use rand::SeedableRng;
use rand_distr::{Distribution as _, StandardNormal, Uniform};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use serde::Serialize;

use crate::Progress;
use crate::objective::{Target, Value};

/// The most samples one run draws.
pub const MAX_SAMPLES: usize = 1_000_000;

/// The default time budget of a run, seconds.
pub const DEFAULT_BUDGET_S: f64 = 600.0;

/// How a key is drawn.
#[derive(Clone, Debug, PartialEq)]
pub enum Distribution {
    /// Normal around the nominal value with standard deviation `sigma` (in the key's units; a
    /// percentage of the nominal value when `relative`).
    Normal {
        /// The standard deviation, or its percentage of the nominal value.
        sigma: f64,
        /// Whether `sigma` is a percentage of the nominal value.
        relative: bool,
    },
    /// Uniform in `[lo, hi]` (the key's values).
    Uniform {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// A fresh integer seed per sample, uniform in `[0, 2³²)` (`lens.atom_error_seed`: a new
    /// draw of a library lens's per-atom errors each sample); no sensitivity is fitted to it.
    Seed,
}

/// A `--vary KEY=DIST`.
#[derive(Clone, Debug, PartialEq)]
pub struct Vary {
    /// Dotted scene key.
    pub key: String,
    /// Its distribution.
    pub distribution: Distribution,
    /// The distribution as given (`normal:2%`).
    pub text: String,
}

/// The forms `--vary` takes.
const FORMS: &str = "KEY=normal:SIGMA (in the key's units), KEY=normal:SIGMA% (of the key's value), KEY=uniform:LO:HI or KEY=seed (a fresh integer seed per sample, e.g. lens.atom_error_seed)";

/// Parses `KEY=normal:S`, `KEY=normal:S%`, `KEY=uniform:LO:HI` or `KEY=seed`.
pub fn parse_vary(arg: &str) -> Result<Vary> {
    let Some((key, spec)) = arg.split_once('=') else {
        bail!("--vary {arg}: expected {FORMS}, e.g. --vary lens.f_number=normal:1%");
    };
    let key = key.trim();
    if key.is_empty() {
        bail!("--vary {arg}: no key; expected {FORMS}");
    }
    let parts: Vec<&str> = spec.trim().split(':').collect();
    let num = |s: &str, what: &str| -> Result<f64> {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .with_context(|| format!("--vary {arg}: {what} `{s}` is not a finite number"))
    };
    let distribution = match parts.as_slice() {
        ["normal", sigma] => {
            let (text, relative) = match sigma.trim().strip_suffix('%') {
                Some(s) => (s, true),
                None => (*sigma, false),
            };
            let sigma = num(text, "SIGMA")?;
            if sigma <= 0.0 {
                bail!("--vary {arg}: SIGMA = {sigma} must be above 0");
            }
            Distribution::Normal { sigma, relative }
        }
        ["uniform", lo, hi] => {
            let (lo, hi) = (num(lo, "LO")?, num(hi, "HI")?);
            if lo >= hi || !(hi - lo).is_finite() {
                bail!("--vary {arg}: LO = {lo} must be below HI = {hi}");
            }
            Distribution::Uniform { lo, hi }
        }
        ["seed"] => Distribution::Seed,
        [name, ..] if !["normal", "uniform", "seed"].contains(name) => {
            bail!("--vary {arg}: unknown distribution `{name}`; expected {FORMS}")
        }
        _ => bail!("--vary {arg}: expected {FORMS}"),
    };
    Ok(Vary { key: key.to_owned(), distribution, text: spec.trim().to_owned() })
}

/// A key's distribution around its nominal value.
#[derive(Clone, Debug, Serialize)]
pub struct Resolved {
    /// Dotted scene key.
    pub key: String,
    /// The distribution as given.
    pub distribution: String,
    /// The key's value in the scene.
    pub nominal: f64,
    /// The standard deviation of its draws, in the key's units (`(HI − LO)/√12` for uniform).
    pub sigma: f64,
    /// The mean of its draws (the nominal value for a normal, the centre for a uniform).
    #[serde(skip)]
    pub mean: f64,
    #[serde(skip)]
    distribution_kind: Distribution,
}

impl Resolved {
    /// `vary` around `nominal`: refused when a relative σ meets a nominal value of 0.
    pub fn new(vary: &Vary, nominal: f64) -> Result<Resolved> {
        let (sigma, mean) = match vary.distribution {
            Distribution::Normal { sigma, relative: false } => (sigma, nominal),
            Distribution::Normal { sigma, relative: true } => {
                if nominal == 0.0 {
                    bail!(
                        "--vary {}={}: a relative σ of a key whose value is 0; give σ in the key's units (normal:SIGMA)",
                        vary.key,
                        vary.text
                    );
                }
                (sigma / 100.0 * nominal.abs(), nominal)
            }
            Distribution::Uniform { lo, hi } => ((hi - lo) / 12f64.sqrt(), 0.5 * (lo + hi)),
            Distribution::Seed => {
                // a seed is drawn from [0, 2³²): a wavelength or a coefficient drawn there means
                // nothing, so only a seed key (its name ends in `seed`) takes it
                let name = vary.key.rsplit('.').next().unwrap_or_default();
                if !name.ends_with("seed") {
                    bail!(
                        "--vary {}=seed: `{}` is not a seed key; `seed` draws integers in [0, 2³²) for seed keys such as lens.atom_error_seed; vary this key by normal:SIGMA, normal:SIGMA% or uniform:LO:HI",
                        vary.key,
                        vary.key
                    );
                }
                if nominal.fract() != 0.0 || nominal < 0.0 {
                    bail!(
                        "--vary {}=seed: the key's value {nominal} is not a seed (an integer ≥ 0); `seed` is for integer seed keys such as lens.atom_error_seed",
                        vary.key
                    );
                }
                (0.0, nominal)
            }
        };
        Ok(Resolved {
            key: vary.key.clone(),
            distribution: vary.text.clone(),
            nominal,
            sigma,
            mean,
            distribution_kind: vary.distribution.clone(),
        })
    }
}

/// The seeds a `seed` key draws from: the integers in `[0, 2³²)`.
const SEEDS: f64 = 4_294_967_296.0;

/// `n` samples of the keys, sample-major: all drawn in order from one `Pcg64` seeded by `seed`
/// (per sample, each key in the given order: a standard normal, a uniform draw, or for a `seed`
/// key a uniform draw in `[0, 2³²)` rounded down to an integer).
pub fn draw(keys: &[Resolved], n: usize, seed: u64) -> Result<Vec<Vec<f64>>> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let uniforms: Vec<Option<Uniform<f64>>> = keys
        .iter()
        .map(|k| match k.distribution_kind {
            Distribution::Uniform { lo, hi } => {
                Uniform::new_inclusive(lo, hi).map(Some).map_err(|e| anyhow::anyhow!("--vary {}: {e}", k.key))
            }
            Distribution::Normal { .. } => Ok(None),
            Distribution::Seed => {
                Uniform::new(0.0, SEEDS).map(Some).map_err(|e| anyhow::anyhow!("--vary {}: {e}", k.key))
            }
        })
        .collect::<Result<_>>()?;
    Ok((0..n)
        .map(|_| {
            keys.iter()
                .zip(&uniforms)
                .map(|(k, u)| match u {
                    Some(u) if k.distribution_kind == Distribution::Seed => u.sample(&mut rng).floor(),
                    Some(u) => u.sample(&mut rng),
                    None => {
                        let z: f64 = StandardNormal.sample(&mut rng);
                        k.nominal + k.sigma * z
                    }
                })
                .collect()
        })
        .collect())
}

/// Mean, sample standard deviation and percentiles of a set of values.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Statistics {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (n − 1).
    pub std: f64,
    /// 5th percentile (linear interpolation between order statistics, numpy's default).
    pub p5: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

/// The `p`-th percentile (0–100) of sorted `values`: linear interpolation between the order
/// statistics at rank `p/100 (n − 1)` (Hyndman & Fan type 7, numpy's default).
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    let h = p / 100.0 * (sorted.len() - 1) as f64;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// The statistics of `values` (at least one).
pub fn statistics(values: &[f64]) -> Statistics {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = if values.len() > 1 { values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    Statistics {
        mean,
        std: var.sqrt(),
        p5: percentile(&sorted, 5.0),
        p50: percentile(&sorted, 50.0),
        p95: percentile(&sorted, 95.0),
        min: sorted[0],
        max: sorted[sorted.len() - 1],
    }
}

/// Each key's sensitivity: the coefficient `b_k` of the least-squares fit
/// `y ≈ b_0 + Σ b_k (x_k − mean_k)/σ_k` over the samples (the normal equations, solved by LU):
/// the change of `y` per σ of key `k`. `None` (not determined) with fewer samples than keys + 2.
pub fn sensitivities(keys: &[Resolved], samples: &[Vec<f64>], y: &[f64]) -> Vec<Option<f64>> {
    // a seed key has no σ: it is left out of the fit (its spread is in the samples' scatter)
    let fitted: Vec<usize> = (0..keys.len()).filter(|&j| keys[j].distribution_kind != Distribution::Seed).collect();
    if fitted.len() < keys.len() {
        let sub: Vec<Resolved> = fitted.iter().map(|&j| keys[j].clone()).collect();
        let xs: Vec<Vec<f64>> = samples.iter().map(|x| fitted.iter().map(|&j| x[j]).collect()).collect();
        let b = if sub.is_empty() { Vec::new() } else { sensitivities(&sub, &xs, y) };
        let mut out = vec![None; keys.len()];
        for (&j, v) in fitted.iter().zip(b) {
            out[j] = v;
        }
        return out;
    }
    let k = keys.len();
    if samples.len() < k + 2 {
        return vec![None; k];
    }
    let mut ata = nalgebra::DMatrix::<f64>::zeros(k + 1, k + 1);
    let mut aty = nalgebra::DVector::<f64>::zeros(k + 1);
    let mut row = vec![1.0; k + 1];
    for (x, &y) in samples.iter().zip(y) {
        for (j, key) in keys.iter().enumerate() {
            row[j + 1] = (x[j] - key.mean) / key.sigma;
        }
        for a in 0..=k {
            aty[a] += row[a] * y;
            for b in 0..=k {
                ata[(a, b)] += row[a] * row[b];
            }
        }
    }
    match ata.lu().solve(&aty) {
        Some(b) => (1..=k).map(|j| Some(b[j]).filter(|v| v.is_finite())).collect(),
        None => vec![None; k],
    }
}

/// One sample.
#[derive(Clone, Debug, Serialize)]
pub struct Sample {
    /// The keys' values.
    pub values: Vec<f64>,
    /// The objective there.
    pub asnr: f64,
    /// Whether the Fraunhofer model holds there.
    pub fraunhofer_valid: bool,
}

/// The result of a tolerance run.
#[derive(Clone, Debug)]
pub struct Tolerance {
    /// How the scene is named.
    pub label: String,
    /// What was sampled.
    pub objective: crate::objective::Objective,
    /// The keys, their nominal values and σ.
    pub keys: Vec<Resolved>,
    /// The seed.
    pub seed: u64,
    /// The objective at the nominal scene.
    pub nominal: Value,
    /// The samples, in order.
    pub samples: Vec<Sample>,
    /// The samples' statistics (all samples, Fraunhofer-valid or not).
    pub statistics: Statistics,
    /// Per key: the change of the objective per σ of the key.
    pub sensitivity: Vec<Option<f64>>,
    /// Per key: the linear sensitivity from the exact gradient at the nominal point,
    /// `∂objective/∂key × σ` (docs/physics.md, "Gradients"); `None` for a seed key or a key the
    /// gradient refuses.
    pub gradient_sensitivity: Vec<Option<f64>>,
    /// Why a key has no gradient sensitivity (the gradient's refusal, naming the key), if one
    /// has none.
    pub gradient_note: Option<String>,
}

impl Tolerance {
    /// Samples outside the Fraunhofer model (kept in the statistics, and counted).
    pub fn invalid(&self) -> usize {
        self.samples.iter().filter(|s| !s.fraunhofer_valid).count()
    }
}

/// The samples of `f` at `n` draws of `keys` from `seed` ([`draw`]), evaluated in parallel
/// (on the current rayon pool) and collected in order, with their statistics and sensitivities.
pub fn sample(
    keys: &[Resolved],
    n: usize,
    seed: u64,
    f: &(dyn Fn(&[f64]) -> Result<Value> + Sync),
    progress: &dyn Progress,
) -> Result<(Vec<Sample>, Statistics, Vec<Option<f64>>)> {
    if n == 0 || n > MAX_SAMPLES {
        bail!("--samples {n}: expected 1 to {MAX_SAMPLES}");
    }
    let draws = draw(keys, n, seed)?;
    progress.start(n as u64);
    let values: Vec<Result<Value>> = draws
        .par_iter()
        .map(|x| {
            let v = f(x);
            progress.advance(1);
            v
        })
        .collect();
    progress.finish();
    let mut samples = Vec::with_capacity(n);
    for (i, (x, v)) in draws.into_iter().zip(values).enumerate() {
        let v = v.with_context(|| format!("sample {i}"))?;
        samples.push(Sample { values: x, asnr: v.value, fraunhofer_valid: v.fraunhofer_valid });
    }
    let y: Vec<f64> = samples.iter().map(|s| s.asnr).collect();
    let stats = statistics(&y);
    let xs: Vec<Vec<f64>> = samples.iter().map(|s| s.values.clone()).collect();
    let sensitivity = sensitivities(keys, &xs, &y);
    Ok((samples, stats, sensitivity))
}

/// Refuses a run whose estimated time, `n` evaluations of `seconds_each` on `threads` threads,
/// is beyond `budget_s` seconds.
pub fn check_budget(n: usize, seconds_each: f64, threads: usize, budget_s: f64) -> Result<()> {
    let estimate = seconds_each * n as f64 / threads.max(1) as f64;
    if estimate > budget_s {
        bail!(
            "--samples {n}: about {estimate:.0} s of work ({n} samples × {:.3} ms per evaluation, the nominal scene's, on {threads} threads), beyond the --budget of {budget_s} s; lower --samples, loosen --tolerance, or raise --budget",
            seconds_each * 1e3
        );
    }
    Ok(())
}

/// Settings of a tolerance run.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Samples.
    pub samples: usize,
    /// The seed of the draws.
    pub seed: u64,
    /// The most seconds the run may take (estimated from the nominal evaluation's time).
    pub budget_s: f64,
    /// Worker threads (0: all cores).
    pub threads: usize,
}

/// A tolerance run of `target` (its objective sampled) with `varies`: checked (each key once,
/// not also overridden, numeric in the scene), the nominal scene evaluated and timed, the time
/// budget checked, then [`sample`]. The command line and the Python package's `asnr.tolerance`
/// both call it.
pub fn tolerance(target: &Target, varies: &[Vary], settings: &Settings, progress: &dyn Progress) -> Result<Tolerance> {
    if varies.is_empty() {
        bail!("--vary: no key to vary; expected at least one {FORMS}");
    }
    if settings.samples == 0 || settings.samples > MAX_SAMPLES {
        bail!("--samples {}: expected 1 to {MAX_SAMPLES}", settings.samples);
    }
    if !(settings.budget_s.is_finite() && settings.budget_s > 0.0) {
        bail!("--budget {}: expected a time in seconds above 0", settings.budget_s);
    }
    for (i, v) in varies.iter().enumerate() {
        if varies[..i].iter().any(|e| e.key == v.key) {
            bail!("--vary {}: the key is given to --vary twice; give each key once", v.key);
        }
        if let Some(s) = target.overrides().iter().find(|s| s.split_once('=').is_some_and(|(k, _)| k.trim() == v.key)) {
            bail!(
                "--vary {}: the key is also given by --set {s}; --vary draws it around the scene's value: give it in one place",
                v.key
            );
        }
    }
    let keys: Vec<Resolved> = varies
        .iter()
        .map(|v| {
            let nominal = crate::objective::number_at(target.source(), target.overrides(), &v.key)
                .with_context(|| format!("--vary {}={}", v.key, v.text))?;
            Resolved::new(v, nominal)
        })
        .collect::<Result<_>>()?;
    let names: Vec<String> = keys.iter().map(|k| k.key.clone()).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| anyhow::anyhow!("--threads {}: {e}", settings.threads))?;
    let started = std::time::Instant::now();
    let nominal = target.value(&[], &[])?;
    check_budget(settings.samples, started.elapsed().as_secs_f64(), pool.current_num_threads(), settings.budget_s)?;
    let (samples, statistics, sensitivity) =
        pool.install(|| sample(&keys, settings.samples, settings.seed, &|x| target.value(&names, x), progress))?;
    let (gradient_sensitivity, gradient_note) = gradient_sensitivities(target, &keys);
    Ok(Tolerance {
        gradient_sensitivity,
        gradient_note,
        label: target.source().label().to_owned(),
        objective: target.objective(),
        keys,
        seed: settings.seed,
        nominal,
        samples,
        statistics,
        sensitivity,
    })
}

/// Each key's linear sensitivity `∂objective/∂key × σ` from the exact gradient at the nominal
/// point: one gradient over every key that is not a seed; where that is refused (a key without a
/// gradient, an objective without one), each key alone, so that the others keep theirs. The
/// second value is the first refusal's message, for the report.
fn gradient_sensitivities(target: &Target, keys: &[Resolved]) -> (Vec<Option<f64>>, Option<String>) {
    let smooth: Vec<usize> = (0..keys.len()).filter(|&i| keys[i].distribution_kind != Distribution::Seed).collect();
    let mut out = vec![None; keys.len()];
    if smooth.is_empty() {
        return (out, None);
    }
    let names: Vec<String> = smooth.iter().map(|&i| keys[i].key.clone()).collect();
    let values: Vec<f64> = smooth.iter().map(|&i| keys[i].nominal).collect();
    match target.value_and_gradient(&names, &values) {
        Ok((_, g)) => {
            for (&i, d) in smooth.iter().zip(g) {
                out[i] = Some(d * keys[i].sigma);
            }
            (out, None)
        }
        Err(first) if smooth.len() == 1 => (out, Some(format!("{first:#}"))),
        Err(_) => {
            let mut note = None;
            for &i in &smooth {
                match target.value_and_gradient(std::slice::from_ref(&keys[i].key), &[keys[i].nominal]) {
                    Ok((_, g)) => out[i] = Some(g[0] * keys[i].sigma),
                    Err(e) => {
                        note.get_or_insert_with(|| format!("{e:#}"));
                    }
                }
            }
            (out, note)
        }
    }
}

/// What the gradient sensitivity is.
pub const GRADIENT_SENSITIVITY: &str = "∂ASNR/∂key × σ from the exact gradient at the nominal point (asnr gradient): the linear part of the least-squares slope";

/// The JSON report (without the samples: [`csv()`] has them).
pub fn json(t: &Tolerance) -> Result<String> {
    #[derive(Serialize)]
    struct Key<'a> {
        #[serde(flatten)]
        key: &'a Resolved,
        /// The change of the objective per σ.
        sensitivity_per_sigma: Option<f64>,
        /// ∂objective/∂key × σ from the exact gradient at the nominal point.
        gradient_per_sigma: Option<f64>,
    }
    #[derive(Serialize)]
    struct Json<'a> {
        scene: &'a str,
        objective: &'static str,
        samples: usize,
        seed: u64,
        nominal_asnr: f64,
        nominal_fraunhofer_valid: bool,
        mean: f64,
        std: f64,
        p5: f64,
        p50: f64,
        p95: f64,
        min: f64,
        max: f64,
        fraunhofer_invalid_samples: usize,
        keys: Vec<Key<'a>>,
        sensitivity: &'static str,
        gradient_sensitivity: &'static str,
        gradient_note: Option<&'a str>,
    }
    let s = &t.statistics;
    let json = Json {
        scene: &t.label,
        objective: t.objective.name(),
        samples: t.samples.len(),
        seed: t.seed,
        nominal_asnr: t.nominal.value,
        nominal_fraunhofer_valid: t.nominal.fraunhofer_valid,
        mean: s.mean,
        std: s.std,
        p5: s.p5,
        p50: s.p50,
        p95: s.p95,
        min: s.min,
        max: s.max,
        fraunhofer_invalid_samples: t.invalid(),
        keys: t
            .keys
            .iter()
            .zip(&t.sensitivity)
            .zip(&t.gradient_sensitivity)
            .map(|((key, s), g)| Key { key, sensitivity_per_sigma: *s, gradient_per_sigma: *g })
            .collect(),
        sensitivity: SENSITIVITY,
        gradient_sensitivity: GRADIENT_SENSITIVITY,
        gradient_note: t.gradient_note.as_deref(),
    };
    Ok(serde_json::to_string_pretty(&json)?)
}

/// What the sensitivity is.
pub const SENSITIVITY: &str = "the change of the ASNR per σ of the key: the least-squares fit of the samples' ASNR to the keys' standardized deviations";

/// The samples as CSV: `sample`, one column per key, `asnr`, `fraunhofer_valid`.
pub fn csv(t: &Tolerance) -> String {
    let header = std::iter::once("sample".to_owned())
        .chain(t.keys.iter().map(|k| k.key.clone()))
        .chain(["asnr".to_owned(), "fraunhofer_valid".to_owned()]);
    let mut s = scene::sweep::csv_line(header);
    for (i, sample) in t.samples.iter().enumerate() {
        let row = std::iter::once(i.to_string())
            .chain(sample.values.iter().map(|v| v.to_string()))
            .chain([sample.asnr.to_string(), sample.fraunhofer_valid.to_string()]);
        s.push_str(&scene::sweep::csv_line(row));
    }
    s
}

/// The text report.
pub fn report(t: &Tolerance) -> String {
    let s = &t.statistics;
    let mut out = String::new();
    let label = t.objective.label();
    let _ = writeln!(out, "{}: tolerance of the {label}, {} samples (seed {})", t.label, t.samples.len(), t.seed);
    let _ = writeln!(out, "  nominal          {:.6}", t.nominal.value);
    let _ = writeln!(out, "  mean ± std       {:.6} ± {:.6}", s.mean, s.std);
    let _ = writeln!(out, "  percentiles      5 %: {:.6}   50 %: {:.6}   95 %: {:.6}", s.p5, s.p50, s.p95);
    let _ = writeln!(out, "  range            {:.6} … {:.6}", s.min, s.max);
    let width = t.keys.iter().map(|k| k.key.chars().count()).max().unwrap_or(3).max(3);
    let _ = writeln!(
        out,
        "  {:<width$}  {:>14}  {:>12}  {:>14}  {:>14}  {:>14}",
        "key", "distribution", "nominal", "σ", "Δ per σ", "∂ASNR/∂key × σ"
    );
    for ((k, sens), exact) in t.keys.iter().zip(&t.sensitivity).zip(&t.gradient_sensitivity) {
        let sens = sens.map_or("–".to_owned(), |v| format!("{v:+.6}"));
        let exact = exact.map_or("–".to_owned(), |v| format!("{v:+.6}"));
        let sigma =
            if k.distribution_kind == Distribution::Seed { "–".to_owned() } else { format!("{:.6e}", k.sigma) };
        let _ = writeln!(
            out,
            "  {:<width$}  {:>14}  {:>12}  {:>14}  {:>14}  {:>14}",
            k.key, k.distribution, k.nominal, sigma, sens, exact
        );
    }
    let _ = writeln!(out, "  (Δ per σ: {SENSITIVITY})");
    let _ = writeln!(out, "  (∂ASNR/∂key × σ: {GRADIENT_SENSITIVITY})");
    if let Some(note) = &t.gradient_note {
        let _ = writeln!(out, "  (no gradient for some keys: {note})");
    }
    if t.invalid() > 0 {
        let _ = writeln!(
            out,
            "  {} of {} samples outside the Fraunhofer model (SI eq. S15), kept in the statistics",
            t.invalid(),
            t.samples.len()
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn resolved(arg: &str, nominal: f64) -> Resolved {
        Resolved::new(&parse_vary(arg).unwrap(), nominal).unwrap()
    }

    /// A model linear in its keys, `y = 3 + 2 x1 − 0.5 x2`, x1 normal (1, 0.1), x2 uniform on
    /// [0, 2]: the samples' mean and σ match the analytic 4.5 and √(2²·0.1² + 0.5²·2²/12) within
    /// five standard errors, and the sensitivities are the exact 2·0.1 and −0.5·2/√12.
    #[test]
    fn a_linear_model_matches_the_analytic_mean_and_sigma() {
        let keys = [resolved("x1=normal:10%", 1.0), resolved("x2=uniform:0:2", 1.0)];
        let f = |x: &[f64]| Ok(Value { value: 3.0 + 2.0 * x[0] - 0.5 * x[1], fraunhofer_valid: true });
        let n = 40_000;
        let (samples, stats, sens) = sample(&keys, n, 7, &f, &()).unwrap();
        assert_eq!(samples.len(), n);
        let sigma = (4.0 * 0.01 + 0.25 * 4.0 / 12.0_f64).sqrt();
        let se_mean = sigma / (n as f64).sqrt();
        assert!((stats.mean - 4.5).abs() < 5.0 * se_mean, "{} vs 4.5 ± {se_mean}", stats.mean);
        // σ's standard error is at most σ/√(2n)·√(1 + kurtosis excess/2) ≤ σ/√n here
        assert!((stats.std - sigma).abs() < 5.0 * sigma / (n as f64).sqrt(), "{} vs {sigma}", stats.std);
        assert!((sens[0].unwrap() - 0.2).abs() < 1e-9, "{sens:?}");
        assert!((sens[1].unwrap() + 0.5 * 2.0 / 12f64.sqrt()).abs() < 1e-9, "{sens:?}");
        assert!(stats.p5 < stats.p50 && stats.p50 < stats.p95);
    }

    /// One normal key: the percentiles of the linear model are the normal's, mean ∓ 1.645 σ.
    #[test]
    fn percentiles_of_a_normal() {
        let keys = [resolved("x=normal:0.5", 2.0)];
        let f = |x: &[f64]| Ok(Value { value: 10.0 - 4.0 * x[0], fraunhofer_valid: true });
        let (_, stats, _) = sample(&keys, 40_000, 3, &f, &()).unwrap();
        // mean 2, σ 2; the 5th and 95th percentiles at 2 ∓ 1.6449 · 2, to a few standard errors
        assert!((stats.p5 - (2.0 - 1.644_854 * 2.0)).abs() < 0.05, "{stats:?}");
        assert!((stats.p95 - (2.0 + 1.644_854 * 2.0)).abs() < 0.05, "{stats:?}");
        assert!((stats.p50 - 2.0).abs() < 0.05, "{stats:?}");
        assert_eq!(percentile(&[1.0, 2.0, 3.0, 4.0], 50.0), 2.5);
        assert_eq!(percentile(&[1.0, 2.0, 3.0, 4.0], 100.0), 4.0);
    }

    /// The draws depend on the seed alone: the same seed, the same bits, on 1 or 2 threads.
    #[test]
    fn seeds_reproduce_the_samples_bit_for_bit() {
        let keys = [resolved("a=normal:1%", 5.0), resolved("b=uniform:-1:1", 0.0)];
        let f = |x: &[f64]| Ok(Value { value: x[0] * x[1].cos(), fraunhofer_valid: true });
        let run = |threads: usize, seed: u64| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let (s, _, _) = pool.install(|| sample(&keys, 500, seed, &f, &())).unwrap();
            s.iter().flat_map(|s| s.values.iter().chain([&s.asnr]).map(|v| v.to_bits())).collect::<Vec<_>>()
        };
        assert_eq!(run(1, 11), run(2, 11));
        assert_ne!(run(1, 11), run(1, 12));
    }

    /// The gradient's linear sensitivity beside the least-squares slope, on the paper scene at
    /// small σ (0.2 % of the exposure, 0.5 nm of the range), where the ASNR is linear in the
    /// keys to about σ²: the two agree within 2 % (the fit of 400 samples of an ASNR curved at
    /// second order); the gradient's is ∂ASNR/∂key × σ from `asnr gradient`, to 1e-12, the
    /// design wavelength's too (the harmonic lens's several orders off axis under a line, on the
    /// line engine's lanes), and no key is left without one (no note).
    #[test]
    fn gradient_sensitivity_beside_the_fit() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/harmonic.toml");
        let source = scene::read(Some(&path)).unwrap();
        // the harmonic lens off axis under a line at 803 nm (its equivalent width the scene's
        // band; each order's image displaced by its own lateral colour)
        let pixel: Vec<String> =
            ["spectrum.shape=\"line\"", "spectrum.center_nm=803", "field.x_deg=5"].map(str::to_owned).to_vec();
        let target = Target::new(source.clone(), pixel.clone(), crate::objective::Objective::Asnr, &[]).unwrap();
        let varies = [
            parse_vary("exposure.time_ms=normal:0.2%").unwrap(),
            parse_vary("spectrum.range_nm=normal:0.5").unwrap(),
            parse_vary("lens.design_wavelength_nm=normal:0.05").unwrap(),
        ];
        let settings = Settings { samples: 400, seed: 1, budget_s: 600.0, threads: 1 };
        let t = tolerance(&target, &varies, &settings, &()).unwrap();
        let g = crate::gradient::gradient(
            &source,
            &pixel,
            &["exposure.time_ms".to_owned(), "spectrum.range_nm".to_owned(), "lens.design_wavelength_nm".to_owned()],
        )
        .unwrap();
        for i in 0..3 {
            let exact = t.gradient_sensitivity[i].unwrap();
            let want = g.d_asnr[i] * t.keys[i].sigma;
            assert!((exact - want).abs() <= 1e-12 * want.abs(), "{exact} vs {want}");
        }
        for i in 0..2 {
            let (exact, fit) = (t.gradient_sensitivity[i].unwrap(), t.sensitivity[i].unwrap());
            assert!((exact - fit).abs() <= 0.02 * exact.abs(), "{}: gradient {exact} vs fit {fit}", t.keys[i].key);
        }
        assert_eq!(t.gradient_note, None);
        let text = report(&t);
        assert!(text.contains("∂ASNR/∂key × σ") && !text.contains("no gradient for some keys"), "{text}");
        let json: serde_json::Value = serde_json::from_str(&json(&t).unwrap()).unwrap();
        assert_eq!(json["keys"][0]["gradient_per_sigma"].as_f64(), t.gradient_sensitivity[0]);
        assert_eq!(json["keys"][2]["gradient_per_sigma"].as_f64(), t.gradient_sensitivity[2]);
    }

    #[test]
    fn bad_distributions_are_refused() {
        let e = |arg: &str| parse_vary(arg).unwrap_err().to_string();
        assert!(e("k=lognormal:1").contains("unknown distribution `lognormal`"), "{}", e("k=lognormal:1"));
        assert!(e("k=normal:0").contains("SIGMA = 0 must be above 0"));
        assert!(e("k=normal:x%").contains("SIGMA `x` is not a finite number"));
        assert!(e("k=uniform:2:1").contains("LO = 2 must be below HI = 1"));
        assert!(e("k=uniform:1").contains("expected KEY=normal:SIGMA"));
        assert!(e("k=seed:3").contains("KEY=seed"), "{}", e("k=seed:3"));
        assert_eq!(parse_vary("k=seed").unwrap().distribution, Distribution::Seed);
        assert!(e("k").contains("expected KEY=normal:SIGMA"));
        // a wavelength drawn as a seed, in [0, 2³²) nm
        let seed =
            Resolved::new(&parse_vary("lens.design_wavelength_nm=seed").unwrap(), 800.0).unwrap_err().to_string();
        assert!(seed.contains("`lens.design_wavelength_nm` is not a seed key"), "{seed}");
        assert!(Resolved::new(&parse_vary("lens.atom_error_seed=seed").unwrap(), 3.0).is_ok());
        let zero = Resolved::new(&parse_vary("k=normal:2%").unwrap(), 0.0).unwrap_err().to_string();
        assert!(zero.contains("a relative σ of a key whose value is 0"), "{zero}");
        let budget = check_budget(1_000_000, 0.02, 2, 600.0).unwrap_err().to_string();
        assert!(
            budget.contains("about 10000 s of work") && budget.contains("beyond the --budget of 600 s"),
            "{budget}"
        );
        assert!(check_budget(1000, 0.02, 2, 600.0).is_ok());
    }
}
