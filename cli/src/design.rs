//! `asnr optimize` over several keys (or with another objective than the ASNR) and
//! `asnr tolerance`: the searches and samples are the `report` library's, shared with the Python
//! package; here are the arguments, the progress bar, the output and the plots.

use std::path::PathBuf;

use anyhow::Result;

use report::objective::Objective;
use report::optimize::{self, Found, Search};

/// The arguments of `asnr optimize` that reach the search over several keys.
pub(crate) struct OptimizeArgs {
    pub scene: Option<PathBuf>,
    pub set: Vec<String>,
    pub over: Vec<String>,
    pub objective: Objective,
    pub xtol: f64,
    pub starts: Option<usize>,
    pub max_evaluations: Option<usize>,
    pub method: Option<optimize::Method>,
    pub plot: Option<PathBuf>,
    pub json: bool,
}

/// The most evaluations `--max-evaluations` (and points `--starts`) may ask for: a thousand
/// times the default budget, and the search's history, allocated for all of them, stays bounded.
const MAX_EVALUATIONS: usize = 1_000_000;

/// Runs `asnr optimize` with several `--over` keys, or one with an `--objective` other than the
/// ASNR or a `--method`.
pub(crate) fn optimize(args: OptimizeArgs, tolerance: Option<f64>) -> Result<()> {
    // checked before the search sizes anything from them: its history is allocated for the
    // whole budget (1e12 evaluations asked for 56 TB), and the start set's capacity overflowed
    if let Some(n) = args.max_evaluations.filter(|&n| n > MAX_EVALUATIONS) {
        anyhow::bail!(
            "--max-evaluations {n}: expected at most {MAX_EVALUATIONS} evaluations (default {})",
            Search::DEFAULT_MAX_EVALUATIONS
        );
    }
    if let Some(n) = args.starts.filter(|&n| n > MAX_EVALUATIONS) {
        anyhow::bail!("--starts {n}: expected at most {MAX_EVALUATIONS} start points (default 10 per key)");
    }
    let set = crate::with_tolerance(args.set, tolerance);
    let ranges = args.over.iter().map(|o| optimize::parse_range(o, false)).collect::<Result<Vec<_>>>()?;
    crate::check_over_keys(&set, &ranges)?;
    if args.plot.is_some() && ranges.len() < 2 {
        anyhow::bail!(
            "--plot: draws a search over several keys; for one key, asnr sweep --over KEY=LO:HI:N --plot FILE draws the curve"
        );
    }
    let figure = crate::plot::Figure::new(None, None)?;
    scene::check_overrides(args.scene.as_deref(), &set)?;
    let source = scene::read(args.scene.as_deref())?;
    // the scene's plausibility warnings, once
    let loaded = scene::build_with_warnings(&source, &set)?;
    crate::warn(&loaded.warnings);
    let search = Search {
        xtol: args.xtol,
        starts: args.starts.unwrap_or(0),
        max_evaluations: args.max_evaluations.unwrap_or(Search::DEFAULT_MAX_EVALUATIONS),
    };
    if args.starts == Some(0) {
        anyhow::bail!("--starts 0: expected at least 1 start point (default 10 per key)");
    }
    let bar = crate::comparecmd::Bar(crate::sweep::progress_bar(0, "evaluations")?);
    let overrides = set.clone();
    let outcome = optimize::search_scene_by(source.clone(), set, &ranges, args.objective, &search, args.method, &bar)?;
    for w in optimize::outcome_warnings(&outcome) {
        eprintln!("warning: {w}");
    }
    if let (Some(path), Found::Many(many)) = (&args.plot, &outcome.found) {
        crate::plot::optimize_plots(path, &figure, &outcome, many)?;
        if many.ranges.len() == 2 {
            let bar = crate::comparecmd::Bar(crate::sweep::progress_bar(0, "landscape points")?);
            let grid = optimize::landscape(&source, &overrides, args.objective, &ranges, &bar)?;
            crate::plot::landscape_plot(&crate::plot::landscape_path(path), &figure, &outcome, many, grid)?;
        }
    }
    if args.json {
        outln!("{}", optimize::outcome_json(&outcome)?);
    } else {
        out!("{}", optimize::outcome_report(&outcome));
    }
    Ok(())
}

// The arguments of `asnr tolerance`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct ToleranceArgs {
    /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
    scene: Option<PathBuf>,
    /// Override a scene key by its dotted path (repeatable): the nominal design.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// A key to draw around its nominal value (repeatable): KEY=normal:SIGMA (the key's units),
    /// KEY=normal:SIGMA% (of its value) or KEY=uniform:LO:HI, e.g. --vary lens.binary2[1]=normal:2%.
    #[arg(long, value_name = "KEY=DIST", required = true)]
    vary: Vec<String>,
    /// Samples drawn.
    #[arg(long, default_value_t = 1000, value_name = "N")]
    samples: usize,
    /// Seed of the draws: the same seed gives the same samples and results, on any number of threads.
    #[arg(long, default_value_t = 1, value_name = "N")]
    seed: u64,
    /// What to sample: asnr, asnr_glare (SI eq. S14), fov_mean or worst_channel.
    #[arg(long, default_value = "asnr", value_name = "NAME")]
    objective: String,
    /// Refuse a run estimated (from the nominal evaluation's time) to take longer, seconds.
    #[arg(long, default_value_t = report::tolerance::DEFAULT_BUDGET_S, value_name = "SECONDS")]
    budget: f64,
    /// Worker threads (0 = all cores). The results do not depend on it.
    #[arg(long, default_value_t = 0, value_name = "N")]
    threads: usize,
    /// Relative error allowed in each ASNR evaluated (sets options.tolerance).
    #[arg(long, value_name = "REL")]
    tolerance: Option<f64>,
    /// Print one JSON object.
    #[arg(long, conflicts_with = "csv")]
    json: bool,
    /// Print the samples as CSV (sample, the keys, asnr, fraunhofer_valid).
    #[arg(long)]
    csv: bool,
    /// Draw the histogram of the samples' ASNR, the nominal and the percentiles marked (.svg or .png).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
}

/// Runs `asnr tolerance`.
pub(crate) fn tolerance(args: ToleranceArgs) -> Result<()> {
    let figure = crate::plot::Figure::new(None, None)?;
    let objective = Objective::parse(&args.objective)?;
    let max_threads = report::optimize::max_threads();
    if args.threads > max_threads {
        anyhow::bail!(
            "--threads {}: expected 0 (all cores) to {max_threads} (4 × the {} available cores)",
            args.threads,
            max_threads / 4
        );
    }
    let varies = args.vary.iter().map(|v| report::tolerance::parse_vary(v)).collect::<Result<Vec<_>>>()?;
    let set = crate::with_tolerance(args.set, args.tolerance);
    scene::check_overrides(args.scene.as_deref(), &set)?;
    let source = scene::read(args.scene.as_deref())?;
    let loaded = scene::build_with_warnings(&source, &set)?;
    crate::warn(&loaded.warnings);
    let keys: Vec<String> = varies.iter().map(|v| v.key.clone()).collect();
    let target = report::objective::Target::new(source, set, objective, &keys)?;
    let settings = report::tolerance::Settings {
        samples: args.samples,
        seed: args.seed,
        budget_s: args.budget,
        threads: args.threads,
    };
    let bar = crate::comparecmd::Bar(crate::sweep::progress_bar(0, "samples")?);
    let t = report::tolerance::tolerance(&target, &varies, &settings, &bar)?;
    if t.invalid() > 0 {
        eprintln!(
            "warning: {} of {} samples are outside the Fraunhofer model (SI eq. S15); they are kept in the statistics",
            t.invalid(),
            t.samples.len()
        );
    }
    if let Some(path) = &args.plot {
        crate::plot::tolerance_plot(path, &figure, &t)?;
    }
    if args.json {
        outln!("{}", report::tolerance::json(&t)?);
    } else if args.csv {
        out!("{}", report::tolerance::csv(&t));
    } else {
        out!("{}", report::tolerance::report(&t));
    }
    Ok(())
}
