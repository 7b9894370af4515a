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
    pub plot: Option<PathBuf>,
    pub json: bool,
}

/// Runs `asnr optimize` with several `--over` keys, or one with an `--objective` other than the
/// ASNR.
pub(crate) fn optimize(args: OptimizeArgs, tolerance: Option<f64>) -> Result<()> {
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
    let outcome = optimize::search_scene(source, set, &ranges, args.objective, &search, &bar)?;
    for w in optimize::outcome_warnings(&outcome) {
        eprintln!("warning: {w}");
    }
    if let (Some(path), Found::Many(many)) = (&args.plot, &outcome.found) {
        crate::plot::optimize_plots(path, &figure, &outcome, many)?;
    }
    if args.json {
        outln!("{}", optimize::outcome_json(&outcome)?);
    } else {
        out!("{}", optimize::outcome_report(&outcome));
    }
    Ok(())
}
