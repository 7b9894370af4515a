//! The charts of a design: `asnr optimize` (convergence and landscape) and `asnr tolerance`
//! (the histogram of the ASNR over the samples).

use super::*;

/// Writes the plots of `asnr optimize` over several keys: the convergence (the objective at each
/// evaluation and the best so far, against the evaluation's number, the start of COBYLA marked)
/// into `path`. Points outside the Fraunhofer model are drawn at their penalized score, 0.
pub fn optimize_plots(
    path: &Path,
    figure: &Figure,
    outcome: &report::optimize::Outcome,
    many: &report::optimize::ManyOptimum,
) -> Result<()> {
    let label = outcome.objective.label();
    let each: Vec<(f64, f64)> = many.history.iter().enumerate().map(|(i, e)| ((i + 1) as f64, e.score())).collect();
    let mut best = f64::NEG_INFINITY;
    let running: Vec<(f64, f64)> = each
        .iter()
        .map(|&(i, v)| {
            best = best.max(v);
            (i, best)
        })
        .collect();
    let series = [
        Series { label: format!("{label} at each evaluation"), points: each, shaded: Vec::new(), best: None },
        Series { label: format!("best {label} so far"), points: running, shaded: Vec::new(), best: None },
    ];
    let marks = [Mark { x: many.start_count() as f64 + 0.5, label: Some("COBYLA starts".to_owned()) }];
    let title = format!("{}: {} over {} keys", outcome.label, label, many.ranges.len());
    let labels = Labels { title: &title, x: "evaluation", y: label, ..Labels::default() };
    lines_plot("--plot", path, figure, &labels, &series, &marks, false)
}

/// `<stem>-landscape.<ext>` beside `path`.
pub fn landscape_path(path: &Path) -> std::path::PathBuf {
    let stem = path.file_stem().map_or_else(|| "plot".into(), |s| s.to_string_lossy().into_owned());
    let ext = path.extension().map_or_else(String::new, |e| format!(".{}", e.to_string_lossy()));
    path.with_file_name(format!("{stem}-landscape{ext}"))
}

/// Writes the landscape of a search over two keys: the objective on the grid `(xs, ys, z)` (z
/// penalized as the search scores it) as a heatmap with its ridge, and the search's points in
/// order over it, the optimum last.
pub fn landscape_plot(
    path: &Path,
    figure: &Figure,
    outcome: &report::optimize::Outcome,
    many: &report::optimize::ManyOptimum,
    (xs, ys, z): (Vec<f64>, Vec<f64>, Vec<f64>),
) -> Result<()> {
    let [first, second] = &many.ranges[..] else { bail!("--plot: a landscape takes two keys") };
    let grid = Grid { xs, ys, z, shaded: Vec::new() };
    // the path: the start set's best, then COBYLA's points in order, ending at the optimum
    let mut points: Vec<(f64, f64)> = std::iter::once(&many.history[many.best_start])
        .chain(many.history.iter().filter(|e| e.stage == "local"))
        .map(|e| (e.values[0], e.values[1]))
        .collect();
    let best = many.best();
    points.push((best.values[0], best.values[1]));
    let (x, y) = (axis_label(&first.key), axis_label(&second.key));
    let ridge = format!("best {} for each {}", quantity(&second.key).0, quantity(&first.key).0);
    let title =
        format!("{}: {} ({} × {} grid)", outcome.label, outcome.objective.label(), grid.xs.len(), grid.ys.len());
    let labels =
        Labels { title: &title, x: &x, y: &y, z: outcome.objective.label(), ridge: &ridge, ..Labels::default() };
    if grid.xs.is_empty() || grid.ys.is_empty() || grid.z.len() != grid.xs.len() * grid.ys.len() {
        bail!("--plot {}: the heatmap grid is empty or incomplete", path.display());
    }
    render(
        "--plot",
        path,
        figure,
        &HeatmapPlot { labels: &labels, grid: &grid, marks: &[], path: &points, square: false },
    )
}

/// Writes the histogram of a tolerance run's samples (40 bins over their range, drawn as steps),
/// the nominal value and the 5th, 50th and 95th percentiles marked.
pub fn tolerance_plot(path: &Path, figure: &Figure, t: &report::tolerance::Tolerance) -> Result<()> {
    const BINS: usize = 40;
    let s = &t.statistics;
    let (lo, hi) = if s.max > s.min { (s.min, s.max) } else { (s.min - 0.5, s.max + 0.5) };
    let width = (hi - lo) / BINS as f64;
    let mut counts = vec![0usize; BINS];
    for sample in &t.samples {
        counts[(((sample.asnr - lo) / width) as usize).min(BINS - 1)] += 1;
    }
    let mut steps = Vec::with_capacity(2 * BINS + 2);
    steps.push((lo, 0.0));
    for (i, &c) in counts.iter().enumerate() {
        let x0 = lo + width * i as f64;
        steps.push((x0, c as f64));
        steps.push((x0 + width, c as f64));
    }
    steps.push((hi, 0.0));
    let label = t.objective.label();
    let series =
        [Series { label: format!("samples per bin ({BINS} bins)"), points: steps, shaded: Vec::new(), best: None }];
    let marks = [
        Mark { x: t.nominal.value, label: Some(format!("nominal {}", number(t.nominal.value))) },
        Mark { x: s.p5, label: Some("5th, 50th, 95th percentiles".to_owned()) },
        Mark { x: s.p50, label: Some("5th, 50th, 95th percentiles".to_owned()) },
        Mark { x: s.p95, label: Some("5th, 50th, 95th percentiles".to_owned()) },
    ];
    let keys: Vec<String> = t.keys.iter().map(|k| format!("{} {}", k.key, k.distribution)).collect();
    let title = format!("{}: {} samples, {}", t.label, t.samples.len(), keys.join(", "));
    let labels = Labels { title: &title, x: label, y: "samples", ..Labels::default() };
    lines_plot("--plot", path, figure, &labels, &series, &marks, false)
}
