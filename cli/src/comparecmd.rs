//! `asnr compare`: its arguments, its output (table, CSV, JSON) and its plot. The comparison
//! itself is `report::compare`, which the Python package's `asnr.compare` runs too.

use std::path::PathBuf;

use anyhow::Result;

use report::compare::{KEY, Report, compare, csv, gradient_table, gradients, sig, table};
use scene::Comparison;

// The arguments of `asnr compare`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct CompareArgs {
    /// Comparison file (TOML with [[designs]]). Without it, the embedded comparison of the lens
    /// families (examples/designs.toml).
    pub scene: Option<PathBuf>,
    /// Override a key by its dotted path: shared (spectrum.range_nm=20) or one design's
    /// (designs[1].lens.f_number=4) (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Print one JSON object instead of the table.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Print CSV, one row per design.
    #[arg(long)]
    pub csv: bool,
    /// Draw the ASNR against the spectral range, one line per design (.svg or .png).
    #[arg(long, value_name = "FILE.svg|png")]
    pub plot: Option<PathBuf>,
    /// Width of the plot, pixels (default 900); the height follows.
    #[arg(long, value_name = "PX", requires = "plot")]
    pub width: Option<u32>,
    /// Resolution of the plot, dots per inch (default: the width over 6 inches).
    #[arg(long, value_name = "N", requires = "plot")]
    pub dpi: Option<f64>,
    /// The grid of spectral ranges searched for each design's best band, N points log-spaced
    /// from LO to HI nm (default spectrum.range_nm=2:300:16; at most 1000 points).
    #[arg(long, value_name = "spectrum.range_nm=LO:HI:N")]
    pub over: Option<String>,
    /// Worker threads (0 = all cores). The results do not depend on it.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub threads: usize,
    /// Relative error allowed in each ASNR (sets options.tolerance; default 1e-6).
    #[arg(long, value_name = "REL")]
    pub tolerance: Option<f64>,
    /// A key to take each design's exact gradient over at the scene band (repeatable; as
    /// `asnr gradient --wrt`): the table adds ∂ln ASNR/∂ln key, --json each design's `gradient`.
    #[arg(long, value_name = "KEY")]
    pub wrt: Vec<String>,
}

/// Runs `asnr compare`.
pub fn run(args: CompareArgs) -> Result<()> {
    let figure = crate::plot::Figure::new(args.width, args.dpi)?;
    let bar = Bar(crate::sweep::progress_bar(0, "evaluations")?);
    let (base, mut report) =
        compare(args.scene.as_deref(), &args.set, args.tolerance, args.over.as_deref(), args.threads, &bar)?;
    gradients(args.scene.as_deref(), &args.set, args.tolerance, &args.wrt, &mut report)?;
    crate::warn(&base.warnings);
    if let Some(path) = &args.plot {
        plot(path, &figure, &base, &report)?;
    }
    for d in &report.designs {
        for w in &d.warnings {
            eprintln!("warning: {}: {w}", d.name);
        }
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else if args.csv {
        out!("{}", csv(&report)?);
    } else {
        out!("{}", table(&report));
        if !args.wrt.is_empty() {
            out!("{}", gradient_table(&report));
        }
    }
    Ok(())
}

/// ASNR against the spectral range, one line per design, the best points marked.
fn plot(path: &std::path::Path, figure: &crate::plot::Figure, base: &Comparison, r: &Report) -> Result<()> {
    let series: Vec<crate::plot::Series> = r
        .designs
        .iter()
        .map(|d| crate::plot::Series {
            label: d.name.clone(),
            points: d.curve.iter().map(|p| (p[0], p[1])).collect(),
            shaded: Vec::new(),
            // the best the comparison found (golden section between grid points), as its table says
            best: Some((
                (d.best_range_nm, d.best_asnr),
                if d.best_at_bound {
                    "grid point at the end of the range"
                } else {
                    "golden section between grid points"
                }
                .to_owned(),
            )),
        })
        .collect();
    let x = crate::plot::axis_label(KEY);
    let title = base.title.clone().unwrap_or_default();
    // the designs' ASNRs span orders of magnitude (the refractive reference against a small
    // achromat): a log axis keeps every design readable
    let labels =
        crate::plot::Labels { title: &title, x: &x, y: "ASNR", x_unit: "nm", log_y: true, ..Default::default() };
    let mark = crate::plot::Mark { x: r.range_nm, label: Some(format!("scene band, {} nm", sig(r.range_nm, 4))) };
    crate::plot::lines_plot("--plot", path, figure, &labels, &series, &[mark], true)
}

/// The terminal's progress bar as the comparison's [`report::Progress`].
pub(crate) struct Bar(pub(crate) indicatif::ProgressBar);

impl report::Progress for Bar {
    fn start(&self, total: u64) {
        self.0.set_length(total);
    }
    fn advance(&self, steps: u64) {
        self.0.inc(steps);
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}
