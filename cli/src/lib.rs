//! The `asnr` command line as a library: its subcommands (`evaluate`, `sweep`, `merge`,
//! `compare`, …), which the binary (`src/main.rs`) runs. Its public surface is what the binary
//! needs: [`Cli`] (the arguments), [`run`] and [`is_broken_pipe`]; the computations the Python
//! package shares with it live in the `report` library (`asnr-report`).
//!
//! Evaluates the ASNR (paper eq. 1) of a scene file, or of the paper's lens embedded in the
//! binary. Human-readable table by default, `--json` for scripts.

/// `print!` to standard output that returns the write's error instead of panicking: with
/// `asnr … | head` the pipe closes early, and the binary then exits quietly (see `main.rs`).
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::write_stdout(&format!($($arg)*))?
    };
}

/// `println!` as [`out!`] does it.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::write_stdout(&format!("{}\n", format_args!($($arg)*)))?
    };
}

mod characterize;
mod comparecmd;
mod design;
mod measure;
mod merge;
mod nps;
mod panel;
mod plot;
mod plotcmd;
mod psf;
mod render;
mod sfrcmd;
mod sweep;

// the reports shared with the Python package, under the names the subcommands use
use report::{optimize, output};

use optimize::{check_keys, check_over_keys, max_threads};

use std::path::PathBuf;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// How good is this metalens, really? The ASNR of a lens, light, camera and exposure.
#[derive(Parser)]
#[command(name = "asnr", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The subcommands. Each one's arguments are built only when it is the one run (`defer`):
/// building all seventeen commands' arguments took about 0.25 ms of CPU at every start
/// (ARCHITECTURE.md, "Where the time goes").
#[derive(Subcommand)]
#[command(defer = true)]
pub enum Command {
    /// Evaluate the ASNR of a scene (default: the paper's lens, embedded).
    Evaluate {
        /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
        scene: Option<PathBuf>,
        /// Override a scene key by its dotted path, e.g. --set lens.f_number=2.8 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
        /// Relative error allowed in the mean MTF (sets options.tolerance; default 1e-6, and 1e-4 on the FFT path).
        #[arg(long, value_name = "REL")]
        tolerance: Option<f64>,
        /// Print how the result is computed (engine, quadratures, error budget, work) after it.
        #[arg(long)]
        explain: bool,
        /// Also the NEQ, the information capacity per pixel, the ideal lens of the same aperture
        /// and the ASNR's ratio to it, and with --task the detectability d′ (docs/physics.md,
        /// "Metrics beyond the ASNR").
        #[arg(long)]
        metrics: bool,
        /// The object's power spectrum for the capacity: flat (default) or power-law:BETA (0 ≤ β < 2).
        #[arg(long, value_name = "flat|power-law:BETA", requires = "metrics")]
        object: Option<String>,
        /// The object's contrast for the capacity (default 1: a white/black target).
        #[arg(long, value_name = "C", requires = "metrics")]
        contrast: Option<f64>,
        /// A frame rate for the capacity per second, Hz.
        #[arg(long, value_name = "HZ", requires = "metrics")]
        frame_rate_hz: Option<f64>,
        /// A detection task for d′: disk:DIAMETER_UM:CONTRAST (diameter in the image plane).
        #[arg(long, value_name = "disk:DIAMETER_UM:CONTRAST", requires = "metrics")]
        task: Option<String>,
        /// The intended design's scene (e.g. the radial library lens or the phase design of a
        /// layout as drawn): its ASNR and mean MTF printed beside the scene's.
        #[arg(long, value_name = "SCENE")]
        compare_design: Option<PathBuf>,
    },
    /// The values of numeric scene keys that maximize the ASNR: one key by a scan and golden
    /// section, several by COBYLA (or, with --method gradient, projected L-BFGS on the exact
    /// gradient) from the best of a Halton start set.
    Optimize {
        /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
        scene: Option<PathBuf>,
        /// Override a scene key by its dotted path (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// A key to vary and its bounds, e.g. --over spectrum.range_nm=1:200 (repeatable: several
        /// keys are searched jointly).
        #[arg(long, value_name = "KEY=LO:HI", required = true)]
        over: Vec<String>,
        /// What to maximize: asnr, asnr_glare (SI eq. S14), fov_mean (over [[fields]]) or
        /// worst_channel (a multiplexed lens's lowest channel).
        #[arg(long, default_value = "asnr", value_name = "NAME")]
        objective: String,
        /// One key: stop when the bracket is narrower than this fraction of HI − LO. Several (or
        /// --method): stop when the local search's step is below this fraction of each key's range.
        #[arg(long, default_value_t = 1e-4, value_name = "FRACTION")]
        xtol: f64,
        /// Several keys: points of the Halton start set (default 10 per key).
        #[arg(long, value_name = "N")]
        starts: Option<usize>,
        /// Several keys: the most evaluations, start set included.
        #[arg(long, value_name = "N")]
        max_evaluations: Option<usize>,
        /// The local search after the Halton start set: cobyla (derivative-free, the default: any
        /// key, up to 16) or gradient (projected L-BFGS on the exact gradient, up to 64 keys, only
        /// the keys `asnr gradient` differentiates and the objectives asnr, asnr_glare, fov_mean).
        /// One key without --method: a scan and golden section.
        #[arg(long, value_name = "cobyla|gradient")]
        method: Option<String>,
        /// Several keys: draw the convergence (the ASNR of each evaluation and the best so far)
        /// into FILE.svg|png; for two keys also the landscape (the ASNR on a 21 × 21 grid, 441
        /// more evaluations) with the search's path, into FILE-landscape.svg|png.
        #[arg(long, value_name = "FILE")]
        plot: Option<PathBuf>,
        /// Relative error allowed in each ASNR evaluated (sets options.tolerance; default 1e-6, and 1e-4 on the FFT path).
        #[arg(long, value_name = "REL")]
        tolerance: Option<f64>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// The exact gradient of the ASNR, mean MTF, SNR0 and photoelectrons with respect to scene
    /// keys, computed by the engines (docs/physics.md, "Gradients"); keys not supported yet are
    /// refused, never differenced.
    Gradient {
        /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
        scene: Option<PathBuf>,
        /// A key to differentiate with respect to, e.g. --wrt exposure.time_ms (repeatable; a list
        /// key without an index, --wrt lens.binary2, means every entry).
        #[arg(long, value_name = "KEY", required = true)]
        wrt: Vec<String>,
        /// Override a scene key by its dotted path (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Relative error allowed in the mean MTF and its derivatives (sets options.tolerance;
        /// default 1e-6, and 1e-4 on the FFT path).
        #[arg(long, value_name = "REL")]
        tolerance: Option<f64>,
        /// Print one JSON object: asnr, mean_mtf, snr0, photoelectrons, and gradient,
        /// mean_mtf_gradient, snr0_gradient, photoelectrons_gradient as {KEY: derivative}.
        #[arg(long)]
        json: bool,
    },
    /// The ASNR over a grid of one or more keys (cartesian product), in parallel.
    Sweep {
        /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
        scene: Option<PathBuf>,
        /// Override a scene key by its dotted path (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// A key to sweep, N points from LO to HI (repeatable; the first varies slowest).
        #[arg(long, value_name = "KEY=LO:HI:N", required_unless_present = "points")]
        over: Vec<String>,
        /// Designs that are not a grid: a CSV whose header names scene keys and whose rows give
        /// their values, one design per row (instead of --over).
        #[arg(long, value_name = "FILE.csv", conflicts_with = "over")]
        points: Option<PathBuf>,
        /// Evaluate only shard I of N (1 ≤ I ≤ N): the points whose index is I − 1 modulo N, as CSV
        /// with an `index` column first, each row written as soon as it is done. `asnr merge`
        /// joins the N shards' files into the single-process CSV, byte for byte.
        #[arg(long, value_name = "I/N", conflicts_with_all = ["json", "plot"])]
        shard: Option<String>,
        /// Print CSV: one column per swept key, then mean_mtf, snr0, asnr, ….
        #[arg(long, conflicts_with = "json")]
        csv: bool,
        /// Print a JSON array of points.
        #[arg(long)]
        json: bool,
        /// Draw the ASNR (one key: a line; two keys: a heatmap with the optimum ridge), .svg or .png.
        #[arg(long, value_name = "FILE")]
        plot: Option<PathBuf>,
        /// Width of the plot, pixels (default 900); the height follows.
        #[arg(long, value_name = "PX", requires = "plot")]
        width: Option<u32>,
        /// Resolution of the plot, dots per inch: text and lines are sized in points at it, and
        /// PNGs record it (default: the width over 6 inches). E.g. --width 1050 --dpi 300.
        #[arg(long, value_name = "N", requires = "plot")]
        dpi: Option<f64>,
        /// Worker threads (0 = all cores). The results do not depend on it.
        #[arg(long, default_value_t = 0, value_name = "N")]
        threads: usize,
        /// Relative error allowed in each ASNR (sets options.tolerance; default 1e-6, and 1e-4 on the FFT path).
        #[arg(long, value_name = "REL")]
        tolerance: Option<f64>,
    },
    /// Join the CSVs of `asnr sweep --shard I/N` into the single-process `asnr sweep --csv` output.
    Merge(merge::MergeArgs),
    /// Lens designs side by side: ASNR at the scene band and at each design's best band, the
    /// chromatic twin, glare (default: the embedded comparison of the lens families).
    Compare(comparecmd::CompareArgs),
    /// The SNR of a stack of camera frames (eq. 2–4) from a white and a black region, and with
    /// capped-black frames the veiling glare and modulation (SI eq. S10–S12).
    Measure(measure::MeasureArgs),
    /// The noise power spectrum of flat frames, temporal and spatial (EMVA 1288), and with
    /// --mtf-csv the measured NEQ and information capacity.
    Nps(nps::NpsArgs),
    /// The MTF of slanted edges in camera frames (ISO 12233 e-SFR): the MTF to Nyquist and
    /// beyond, the mean MTF to Nyquist, MTF50 and MTF at Nyquist, with standard errors.
    Sfr(sfrcmd::SfrArgs),
    /// A camera's STF and PTC slopes, conversion gain, read noise and saturation from stacks at
    /// increasing illumination (SI Fig. S6–S8, EMVA 1288), listed in a series file.
    Characterize(characterize::CharacterizeArgs),
    /// How the ASNR survives fabrication: Monte Carlo over distributions of scene keys (seeded,
    /// parallel), with the nominal ASNR, the mean, σ, percentiles and each key's sensitivity.
    Tolerance(design::ToleranceArgs),
    /// Simulated and Wiener-restored images of a USAF-1951 target (or a PNG) through the scene,
    /// one per spectral range (the paper's Fig. 4), with the measured bar contrast.
    Render(render::RenderArgs),
    /// The scene's 2-D polychromatic PSF at its field point and pupil: PNG, CSV matrix, JSON.
    Psf(psf::GridArgs),
    /// The scene's 2-D polychromatic OTF (real and imaginary parts, MTF): PNG, CSV matrices, JSON.
    Otf(psf::GridArgs),
    /// Print the scene as read: TOML with every default filled in and CSV paths resolved.
    Scene {
        /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
        scene: Option<PathBuf>,
        /// Override a scene key by its dotted path, e.g. --set lens.f_number=2.8 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Replot sweep CSVs: lines overlaid, or one CSV as a heatmap (`cargo xtask figures` uses it).
    Plot(plotcmd::PlotArgs),
    /// The polychromatic MTF from 0 to Nyquist (or to the cutoff), with the diffraction limit.
    Mtf {
        /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
        scene: Option<PathBuf>,
        /// Override a scene key by its dotted path, e.g. --set spectrum.range_nm=100 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Print one JSON object instead of the table.
        #[arg(long, conflicts_with = "csv")]
        json: bool,
        /// Print CSV (one row per frequency) instead of the table.
        #[arg(long)]
        csv: bool,
        /// Also draw the curves into this file (.svg or .png).
        #[arg(long, value_name = "FILE.svg|png")]
        plot: Option<PathBuf>,
        /// Width of the plot, pixels (default 900); the height follows.
        #[arg(long, value_name = "PX", requires = "plot")]
        width: Option<u32>,
        /// Resolution of the plot, dots per inch: text and lines are sized in points at it, and
        /// PNGs record it (default: the width over 6 inches). E.g. --width 1050 --dpi 300.
        #[arg(long, value_name = "N", requires = "plot")]
        dpi: Option<f64>,
        /// Extend the axis to the cutoff of the shortest wavelength instead of stopping at Nyquist.
        #[arg(long)]
        to_cutoff: bool,
        /// Number of equally spaced frequencies, from 0 to the end of the axis.
        #[arg(long, default_value_t = 101, value_name = "N")]
        points: usize,
        /// Monochromatic curves at these wavelengths, nm (comma-separated, e.g. 780,800,820).
        #[arg(long, value_delimiter = ',', value_name = "NM")]
        wavelengths: Vec<f64>,
        /// Relative error allowed in the MTF (sets options.tolerance; default 1e-6, and 1e-4 on the FFT path).
        #[arg(long, value_name = "REL")]
        tolerance: Option<f64>,
    },
}

/// Runs the command line `cli`.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Evaluate {
            scene,
            set,
            json,
            tolerance,
            explain,
            metrics,
            object,
            contrast,
            frame_rate_hz,
            task,
            compare_design,
        } => {
            let label = scene.as_ref().map_or("embedded paper scene".to_owned(), |p| p.display().to_string());
            let metrics_options = metrics
                .then(|| report::metrics::options(object.as_deref(), contrast, frame_rate_hz, task.as_deref()))
                .transpose()?;
            let set = with_tolerance(set, tolerance);
            let read = scene::load_with_warnings(scene.as_deref(), &set)?;
            warn(&read.warnings);
            let mapping = read.pupil_mapping;
            let (loaded, meter) = (std::sync::Arc::new(read.scene), read.radiance_meter);
            // the pupil-mapping check is a second, independent evaluation: it runs beside this
            // one on a thread of its own, so the report waits for the slower of the two, not
            // their sum, when a second core is free (and by this thread after its own when none is)
            let other = mapping.map(|used| {
                let (loaded, set, scene) = (loaded.clone(), set.clone(), scene.clone());
                Beside::start(move || {
                    other_map_mean_mtf(&loaded, scene.as_deref(), &set, used, MAPPING_CHECK_TOLERANCE)
                })
            });
            let result = metric::evaluate(&loaded);
            let result = result.map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
            let mapping = mapping
                .zip(other)
                .map(|(used, other)| {
                    let first = MappingCheck::new(used, other.finish()?, result.mean_mtf, MAPPING_CHECK_TOLERANCE);
                    first.confirmed(result.mean_mtf, |tolerance| {
                        other_map_mean_mtf(&loaded, scene.as_deref(), &set, used, tolerance)
                    })
                })
                .transpose()
                .map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
            // the intended design, evaluated as given (without --set: it is another scene)
            let design = match &compare_design {
                Some(path) => {
                    let read = scene::load_with_warnings(Some(path), &[])?;
                    warn(&read.warnings);
                    let d = metric::evaluate(&read.scene)
                        .map_err(|e| anyhow::anyhow!("--compare-design {}: {e}", path.display()))?;
                    Some((path.display().to_string(), d))
                }
                None => None,
            };
            let metrics = metrics_options
                .map(|o| metric::metrics(&loaded, &result, &o))
                .transpose()
                .map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
            if json {
                let report = match &metrics {
                    Some(m) => report::metrics::json(&label, &loaded, &result, m)?,
                    None => output::json(&label, &loaded, &result)?,
                };
                // with --json, stdout stays one JSON document: the explanation is its `explain` field
                let report = if explain {
                    with_explain(&report, &output::explain(&loaded, &result, meter.as_ref()))?
                } else {
                    report
                };
                let report = match &mapping {
                    Some(m) => with_field(&report, "pupil_mapping", &m.json())?,
                    None => report,
                };
                let report = match &design {
                    Some((path, d)) => with_design(&report, path, d, &result)?,
                    None => report,
                };
                outln!("{report}");
                if let Some(w) = mapping.as_ref().and_then(MappingCheck::warning) {
                    eprintln!("warning: {w}");
                }
            } else {
                out!("{}", output::table(&label, &loaded, &result));
                if let Some(m) = &mapping {
                    outln!("{}", m.line());
                    if let Some(w) = m.warning() {
                        eprintln!("warning: {w}");
                    }
                }
                if let Some(m) = &metrics {
                    out!("{}", report::metrics::table(m, &result));
                }
                for w in &result.warnings {
                    eprintln!("warning: {w}");
                }
                if explain {
                    out!("{}", output::explain(&loaded, &result, meter.as_ref()));
                }
                if let Some((path, d)) = &design {
                    out!("{}", design_table(path, d, &result));
                }
            }
            Ok(())
        }
        Command::Optimize {
            scene,
            set,
            over,
            objective,
            xtol,
            starts,
            max_evaluations,
            method,
            plot,
            tolerance,
            json,
        } => {
            check_over_names(&over)?;
            let objective = report::objective::Objective::parse(&objective)?;
            let method = method.as_deref().map(optimize::Method::parse).transpose()?;
            if over.len() > 1 || objective != report::objective::Objective::Asnr || method.is_some() {
                let args = design::OptimizeArgs {
                    scene,
                    set,
                    over,
                    objective,
                    xtol,
                    starts,
                    max_evaluations,
                    method,
                    plot,
                    json,
                };
                return design::optimize(args, tolerance);
            }
            for (given, flag) in [(starts.is_some(), "--starts"), (max_evaluations.is_some(), "--max-evaluations")] {
                if given {
                    anyhow::bail!(
                        "{flag}: applies to a search over several keys; one key is searched by a {}-point scan and golden section",
                        optimize::SCAN_POINTS
                    );
                }
            }
            if plot.is_some() {
                anyhow::bail!(
                    "--plot: draws a search over several keys; for one key, asnr sweep --over KEY=LO:HI:N --plot FILE draws the curve"
                );
            }
            let over = &over[0];
            if !(1e-12..1.0).contains(&xtol) {
                // as typed: 1e-17, not 0.00000000000000001
                let xtol = if xtol != 0.0 && xtol.abs() < 1e-4 { format!("{xtol:e}") } else { format!("{xtol}") };
                anyhow::bail!(
                    "--xtol {xtol}: expected a fraction of the range in [1e-12, 1) (a finer bracket is below the float spacing of the range's values)"
                );
            }
            let set = with_tolerance(set, tolerance);
            let range = optimize::parse_range(over, false)?;
            check_over_keys(&set, std::slice::from_ref(&range))?;
            // validate the scene (and print its warnings) once, at the low end of the range
            let mut first = set.clone();
            first.push(optimize::assignment(&range.key, range.lo));
            let origin = [format!("--over {over}")];
            let keys = [range.key.clone()];
            load(scene.as_deref(), &first)
                .map_err(|e| anyhow::anyhow!(sweep::relabel(&e.to_string(), &keys, &[range.lo], &origin)))?;
            let asnr_at = |x: f64| -> Result<f64> {
                let mut overrides = set.clone();
                overrides.push(optimize::assignment(&range.key, x));
                let loaded = scene::load(scene.as_deref(), &overrides)?;
                Ok(metric::evaluate(&loaded)?.asnr)
            };
            let best = optimize::maximize(&range, xtol * (range.hi - range.lo), asnr_at)?;
            if let Some(warning) = optimize::bound_warning(&best) {
                eprintln!("warning: {warning}");
            }
            if json {
                outln!("{}", serde_json::to_string_pretty(&best)?);
            } else {
                out!("{}", optimize::report(&best));
            }
            Ok(())
        }
        Command::Gradient { scene, wrt, set, tolerance, json } => {
            let set = with_tolerance(set, tolerance);
            let source = scene::read(scene.as_deref())?;
            let gradient = report::gradient::gradient(&source, &set, &wrt)?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&gradient)?);
            } else {
                out!("{}", report::gradient::table(&gradient));
            }
            Ok(())
        }
        Command::Sweep { scene, set, over, points, shard, csv, json, plot, width, dpi, threads, tolerance } => {
            let figure = plot::Figure::new(width, dpi)?;
            let set = with_tolerance(set, tolerance);
            let shard = shard.as_deref().map(parse_shard).transpose()?;
            let (ranges, design, what, origins) = match &points {
                Some(path) => {
                    if plot.is_some() {
                        anyhow::bail!(
                            "--plot: a plot needs a grid (--over KEY=LO:HI:N); --points gives a list of designs"
                        );
                    }
                    let file = scene::sweep::read_points(path)?;
                    // the table's ranges: each column's extent (no grid, so no refinement)
                    let ranges = file
                        .keys
                        .iter()
                        .enumerate()
                        .map(|(k, key)| {
                            let column = file.rows.iter().map(|r| r[k]);
                            let lo = column.clone().fold(f64::INFINITY, f64::min);
                            let hi = column.fold(f64::NEG_INFINITY, f64::max);
                            optimize::Range { key: key.clone(), lo, hi, points: Some(1) }
                        })
                        .collect::<Vec<_>>();
                    let what = format!("--points {}", path.display());
                    let origins = vec![what.clone(); ranges.len()];
                    (ranges, sweep::Design::List(file.rows), what, origins)
                }
                None => {
                    check_over_names(&over)?;
                    let ranges = over.iter().map(|o| optimize::parse_range(o, true)).collect::<Result<Vec<_>>>()?;
                    // the product of the axes, checked: four axes of 65536 points wrap a usize to 0
                    let total = ranges.iter().try_fold(1_usize, |n, r| n.checked_mul(r.points.unwrap_or(1)));
                    if total.is_none_or(|t| t > MAX_GRID_POINTS) {
                        let product: f64 = ranges.iter().map(|r| r.points.unwrap_or(1) as f64).product();
                        let axes: Vec<String> = ranges.iter().map(|r| r.points.unwrap_or(1).to_string()).collect();
                        anyhow::bail!(
                            "--over: {} = {product:e} grid points; expected at most {MAX_GRID_POINTS}",
                            axes.join(" × ")
                        );
                    }
                    let design = sweep::Design::grid(&ranges);
                    let origins = over.iter().map(|o| format!("--over {o}")).collect();
                    (ranges, design, "--over".to_owned(), origins)
                }
            };
            check_keys(&what, &set, &ranges)?;
            let max_threads = max_threads();
            if threads > max_threads {
                anyhow::bail!(
                    "--threads {threads}: expected 0 (all cores) to {max_threads} (4 × the {} available cores)",
                    max_threads / 4
                );
            }
            scene::check_overrides(scene.as_deref(), &set)?;
            let source = scene::read(scene.as_deref())?;
            let keys: Vec<String> = ranges.iter().map(|r| r.key.clone()).collect();
            // validate the scene and the keys once before spending the grid
            let mut first = set.clone();
            let values = design.values(0);
            first.extend(keys.iter().zip(&values).map(|(k, v)| scene::sweep::assignment(k, *v)));
            let loaded = scene::build_with_warnings(&source, &first)
                .map_err(|e| anyhow::anyhow!(sweep::relabel(&e.to_string(), &keys, &values, &origins)))?;
            warn(&loaded.warnings);
            let built = loaded.scene;
            let sweep = sweep::Sweep { source: &source, overrides: &set, keys, design, origins };
            if let Some((i, n)) = shard {
                let indices: Vec<usize> = scene::sweep::shard_indices(i, n, sweep.design.len()).collect();
                return sweep::stream(&sweep, &indices, threads, &mut std::io::stdout());
            }
            let points = sweep::run(&sweep, threads)?;
            for line in sweep::warnings(&sweep.keys, &points) {
                eprintln!("{line}");
            }
            if let Some(path) = &plot {
                let title = plot::sweep_title(&ranges, &built.lens().describe(), &plot::field_label(&built));
                plot::sweep_plot(path, &figure, &title, &ranges, &points)?;
            }
            if json {
                outln!("{}", serde_json::to_string_pretty(&points)?);
            } else if csv {
                out!("{}", sweep::csv(&sweep.keys, &points));
            } else {
                out!("{}", sweep::table(source.label(), built.title(), &ranges, &points));
            }
            Ok(())
        }
        Command::Merge(args) => merge::run(&args),
        Command::Plot(args) => plotcmd::run(&args),
        Command::Compare(args) => comparecmd::run(args),
        Command::Measure(args) => measure::run(&args),
        Command::Nps(args) => nps::run(&args),
        Command::Sfr(args) => sfrcmd::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Psf(args) => psf::run(&args, psf::Kind::Psf),
        Command::Otf(args) => psf::run(&args, psf::Kind::Otf),
        Command::Characterize(args) => characterize::run(&args),
        Command::Tolerance(args) => design::tolerance(args),
        Command::Scene { scene, set } => {
            scene::check_overrides(scene.as_deref(), &set)?;
            let source = scene::read(scene.as_deref())?;
            let resolved = scene::resolved_toml(&source, &set)?;
            warn(&resolved.warnings);
            out!("{}", resolved.toml);
            Ok(())
        }
        Command::Mtf { scene, set, json, csv, plot, width, dpi, to_cutoff, points, wavelengths, tolerance } => {
            let figure = plot::Figure::new(width, dpi)?;
            let label = scene.as_ref().map_or("embedded paper scene".to_owned(), |p| p.display().to_string());
            if !(2..=100_000).contains(&points) {
                anyhow::bail!("--points {points}: expected a whole number from 2 to 100000");
            }
            // 1 nm to 1 mm: a wavelength of 1e-300 nm is a subnormal number of metres, whose cutoff
            // and JSON value are not finite
            if let Some(bad) = wavelengths.iter().find(|w| !(w.is_finite() && (1.0..=1e6).contains(*w))) {
                let bad = if *bad != 0.0 && (bad.abs() < 1e-4 || bad.abs() >= 1e9) {
                    format!("{bad:e}")
                } else {
                    bad.to_string()
                };
                anyhow::bail!("--wavelengths: {bad} nm: expected wavelengths from 1 nm to 1e6 nm (1 mm)");
            }
            let loaded = load(scene.as_deref(), &with_tolerance(set, tolerance))?;
            let range = if to_cutoff { metric::FrequencyRange::Cutoff } else { metric::FrequencyRange::Nyquist };
            let metres: Vec<f64> = wavelengths.iter().map(|w| w * 1e-9).collect();
            let curve =
                metric::mtf_curve(&loaded, range, points, &metres).map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
            if let Some(path) = &plot {
                let name = loaded.title().map_or_else(|| loaded.lens().describe(), str::to_owned);
                let title = format!("{name}, {}", plot::field_label(&loaded));
                plot::mtf_plot(path, &figure, &title, &curve)?;
            }
            if json {
                outln!("{}", output::mtf_json(&label, &loaded, &curve)?);
            } else if csv {
                out!("{}", output::mtf_csv(&curve));
            } else {
                out!("{}", output::mtf_table(&label, &loaded, &curve));
            }
            Ok(())
        }
    }
}

/// Loads a scene (the `--set`s checked before the file is read) and prints its plausibility
/// warnings to stderr.
fn load(scene: Option<&std::path::Path>, set: &[String]) -> Result<metric::Scene> {
    let loaded = scene::load_with_warnings(scene, set)?;
    warn(&loaded.warnings);
    Ok(loaded.scene)
}

/// Prints a scene's plausibility warnings (values that look like a unit slip) to stderr.
fn warn(warnings: &[scene::Warning]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}

/// The most grid points a sweep evaluates.
const MAX_GRID_POINTS: usize = 10_000_000;

/// The JSON object `report` with the `--explain` text as a last field `explain`, one string
/// per line.
/// The drawn lens's ASNR and mean MTF beside the intended design's (`--compare-design`).
fn design_table(path: &str, design: &metric::Evaluation, drawn: &metric::Evaluation) -> String {
    format!(
        "\nAs drawn against the design ({path}):\n  {:<10} {:>10} {:>10}\n  {:<10} {:>10.3} {:>10.4}\n  {:<10} {:>10.3} {:>10.4}\n  {:<10} {:>+9.2}% {:>+10.4}\n",
        "",
        "ASNR",
        "mean MTF",
        "as drawn",
        drawn.asnr,
        drawn.mean_mtf,
        "design",
        design.asnr,
        design.mean_mtf,
        "difference",
        100.0 * (drawn.asnr / design.asnr - 1.0),
        drawn.mean_mtf - design.mean_mtf,
    )
}

/// The JSON report with a `compare_design` object (`--compare-design`).
fn with_design(report: &str, path: &str, design: &metric::Evaluation, drawn: &metric::Evaluation) -> Result<String> {
    let Some(body) = report.trim_end().strip_suffix('}').map(str::trim_end) else {
        anyhow::bail!("internal error: the JSON report is not an object")
    };
    let object = serde_json::json!({
        "scene": path,
        "asnr": design.asnr,
        "mean_mtf": design.mean_mtf,
        "asnr_relative_difference": drawn.asnr / design.asnr - 1.0,
        "mean_mtf_difference": drawn.mean_mtf - design.mean_mtf,
    });
    let out = format!("{body},\n  \"compare_design\": {object}\n}}");
    serde_json::from_str::<serde_json::Value>(&out)?;
    Ok(out)
}

fn with_explain(report: &str, explain: &str) -> Result<String> {
    let body = report.trim_end().strip_suffix('}').map(str::trim_end);
    let Some(body) = body else { anyhow::bail!("internal error: the JSON report is not an object") };
    let lines: Vec<String> =
        explain.lines().filter(|l| !l.trim().is_empty()).map(serde_json::to_string).collect::<Result<_, _>>()?;
    let out = format!("{body},\n  \"explain\": [\n    {}\n  ]\n}}", lines.join(",\n    "));
    serde_json::from_str::<serde_json::Value>(&out)?;
    Ok(out)
}

/// Work started beside the calling thread: on a thread of its own, unless the calling thread
/// comes for the result before that thread has begun, as on a machine whose cores are all busy,
/// where a new thread may wait milliseconds for one: the caller then does the work itself, with
/// the core it has. The result is the same either way; only who computes it differs.
struct Beside<T> {
    /// the work, until one of the two threads takes it
    work: std::sync::Arc<std::sync::Mutex<Option<Work<T>>>>,
    /// the result, when the other thread took the work
    result: std::sync::mpsc::Receiver<T>,
    /// the other thread, for its panic (None when it could not be started)
    thread: Option<std::thread::JoinHandle<()>>,
}

/// The work a [`Beside`] holds.
type Work<T> = Box<dyn FnOnce() -> T + Send>;

impl<T: Send + 'static> Beside<T> {
    /// `work` offered to a new thread.
    fn start(work: impl FnOnce() -> T + Send + 'static) -> Self {
        Self::start_on(work, |run| std::thread::Builder::new().spawn(run).ok())
    }

    /// `work` offered to the thread that `spawn` starts (None: none could be).
    fn start_on(
        work: impl FnOnce() -> T + Send + 'static,
        spawn: impl FnOnce(Box<dyn FnOnce() + Send>) -> Option<std::thread::JoinHandle<()>>,
    ) -> Self {
        let work: Work<T> = Box::new(work);
        let work = std::sync::Arc::new(std::sync::Mutex::new(Some(work)));
        let (sender, result) = std::sync::mpsc::channel();
        let offered = work.clone();
        // not joined at the end: a thread that never took the work ends with the process
        let thread = spawn(Box::new(move || {
            let taken = offered.lock().map(|mut w| w.take()).unwrap_or(None);
            if let Some(work) = taken {
                // the receiver is gone only when the caller stopped waiting (an error)
                let _ = sender.send(work());
            }
        }));
        Beside { work, result, thread }
    }

    /// The work's result: computed here if the other thread has not taken the work (or could
    /// not be started), else awaited; the other thread's panic is resumed here.
    fn finish(self) -> T {
        let mine = self.work.lock().map(|mut w| w.take()).unwrap_or(None);
        if let Some(work) = mine {
            return work();
        }
        match self.result.recv() {
            Ok(result) => result,
            // the sender dropped without a result: the work panicked on the other thread
            Err(_) => match self.thread.map(std::thread::JoinHandle::join) {
                Some(Err(panic)) => std::panic::resume_unwind(panic),
                _ => unreachable!("the other thread took the work and ended without a result or a panic"),
            },
        }
    }
}

/// A flat lens's pupil mapping in a report (`options.pupil_mapping`, docs/physics.md "The flat
/// lens's exact image"): the map used, and the paraxial map's error estimated by evaluating the
/// scene again with the other map at tolerance [`MAPPING_CHECK_TOLERANCE`], and again at
/// [`MAPPING_CONFIRM_TOLERANCE`] when that estimate is within its error of the 1 % threshold.
struct MappingCheck {
    used: scene::PupilMapping,
    /// the other map's mean MTF
    other: f64,
    /// (paraxial − exact)/exact of the mean MTF
    paraxial_error: f64,
    /// the tolerance the other map's mean was asked at
    tolerance: f64,
}

/// The tolerance the other pupil map is evaluated at first for the report's comparison: the
/// loosest `options.tolerance` accepts. The check decides whether the two maps differ by more
/// than [`MAPPING_WARNING`] (1 %); the engine's rules at their resolution floor are far inside
/// this nominal tolerance (measured within [`MAPPING_CHECK_ERROR`] of the mean, with margin:
/// docs/physics.md "The flat lens's exact image").
const MAPPING_CHECK_TOLERANCE: f64 = 1e-1;

/// The relative error of the other map's mean at [`MAPPING_CHECK_TOLERANCE`] that the check
/// allows for: 11× the largest measured against the evaluation at 1e-3 (8.7e-5, over hyperbolic
/// Binary 2 lenses F/1.25–F/10 on a line and over 10–200 nm, defocused ones at F/2.5–F/5 and the
/// examples; docs/physics.md).
const MAPPING_CHECK_ERROR: f64 = 1e-3;

/// The tolerance of the check's second evaluation, where the first cannot decide: a mean within
/// 1e-3 of its value puts the printed difference within about ±0.1 % of 1 % (the earlier check,
/// done for every lens).
const MAPPING_CONFIRM_TOLERANCE: f64 = 1e-3;

/// The paraxial map's error above which the report warns.
const MAPPING_WARNING: f64 = 0.01;

/// The mean MTF with the other pupil map than `used`, at `tolerance`. From the
/// paraxial map: the loaded scene's lens (every term the scene file gave, as built) wrapped in
/// the exact map, as `options.pupil_mapping = "exact"` wraps it (no second parse and build).
/// From the exact map: the scene loaded again with the two keys replaced where they were set
/// (the wrapped lens keeps no paraxial twin).
fn other_map_mean_mtf(
    loaded: &metric::Scene,
    file: Option<&std::path::Path>,
    set: &[String],
    used: scene::PupilMapping,
    tolerance: f64,
) -> Result<f64> {
    let options = metric::Options { tolerance, ..loaded.options().clone() };
    if used == scene::PupilMapping::Paraxial {
        let lens = loaded.lens_arc();
        let probe = lens.design_wavelength().unwrap_or(550e-9);
        let mapped = lenses::ExactPupilMap::new(lens, probe)?;
        let other = loaded.clone().with_lens(std::sync::Arc::new(mapped)).with_options(options)?;
        return Ok(metric::evaluate(&other)?.mean_mtf);
    }
    let replaced = |o: &String| {
        let key = o.split_once('=').and_then(|(k, _)| scene::canonical_key(k));
        matches!(key.as_deref(), Some("options.pupil_mapping" | "options.tolerance"))
    };
    let mut set: Vec<String> = set.iter().filter(|o| !replaced(o)).cloned().collect();
    set.push(format!("options.pupil_mapping={}", used.other().name()));
    set.push(format!("options.tolerance={tolerance:e}"));
    Ok(metric::evaluate(&scene::load(file, &set)?)?.mean_mtf)
}

impl MappingCheck {
    /// The check from the used map's mean MTF and the other map's, evaluated at `tolerance`.
    fn new(used: scene::PupilMapping, other: f64, mean_mtf: f64, tolerance: f64) -> Self {
        let (paraxial, exact) = match used {
            scene::PupilMapping::Paraxial => (mean_mtf, other),
            scene::PupilMapping::Exact => (other, mean_mtf),
        };
        let paraxial_error = if exact > 0.0 { (paraxial - exact) / exact } else { 0.0 };
        MappingCheck { used, other, paraxial_error, tolerance }
    }

    /// Whether the first evaluation cannot tell which side of [`MAPPING_WARNING`] the paraxial
    /// map's error lies: the other map's mean within `MAPPING_CHECK_ERROR` (relative `η`) moves
    /// `(paraxial − exact)/exact = e` by at most `(1 + |e|) η/(1 − η)` (the exact mean is the
    /// other's from the paraxial map; from the exact map the paraxial mean divided by the exact
    /// one moves as much).
    fn undecided(&self) -> bool {
        let e = self.paraxial_error.abs();
        let reach = (1.0 + e) * MAPPING_CHECK_ERROR / (1.0 - MAPPING_CHECK_ERROR);
        (e - MAPPING_WARNING).abs() <= reach
    }

    /// This check, or where it is [`undecided`](Self::undecided), the check again from the used
    /// map's `mean_mtf` and the other map evaluated by `other` at [`MAPPING_CONFIRM_TOLERANCE`].
    fn confirmed(self, mean_mtf: f64, other: impl FnOnce(f64) -> Result<f64>) -> Result<Self> {
        if !self.undecided() {
            return Ok(self);
        }
        let other = other(MAPPING_CONFIRM_TOLERANCE)?;
        Ok(MappingCheck::new(self.used, other, mean_mtf, MAPPING_CONFIRM_TOLERANCE))
    }

    fn line(&self) -> String {
        format!(
            "pupil mapping: {} (with the {} map the mean MTF is {:.6}: the paraxial map is {:+.2} % off the flat lens's exact image, evaluated at tolerance {:e}; options.pupil_mapping)",
            self.used.name(),
            self.used.other().name(),
            self.other,
            100.0 * self.paraxial_error,
            self.tolerance
        )
    }

    fn warning(&self) -> Option<String> {
        (self.used == scene::PupilMapping::Paraxial && self.paraxial_error.abs() > MAPPING_WARNING).then(|| {
            format!(
                "the paraxial pupil map is {:+.2} % off the flat lens's exact image in the mean MTF (more than {} %): set options.pupil_mapping = \"exact\"",
                100.0 * self.paraxial_error,
                100.0 * MAPPING_WARNING
            )
        })
    }

    fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "used": self.used.name(),
            "other_mean_mtf": self.other,
            "paraxial_relative_error": self.paraxial_error,
            "check_tolerance": self.tolerance,
        })
    }
}

/// `report` (a JSON object) with `key: value` added.
fn with_field(report: &str, key: &str, value: &serde_json::Value) -> Result<String> {
    let body = report.trim_end().strip_suffix('}').map(str::trim_end);
    let Some(body) = body else { anyhow::bail!("internal error: the JSON report is not an object") };
    let out = format!("{body},\n  {}: {}\n}}", serde_json::to_string(key)?, serde_json::to_string(value)?);
    serde_json::from_str::<serde_json::Value>(&out)?;
    Ok(out)
}

/// Writes `text` to standard output and flushes it.
pub(crate) fn write_stdout(text: &str) -> std::io::Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()
}

/// Whether `error` is standard output's pipe closed by its reader (`asnr sweep --csv | head`):
/// not a failure of the command, which then stops quietly.
pub fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error
        .chain()
        .any(|e| e.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}

/// `--shard I/N`: shard `I` (1-based) of `N`.
fn parse_shard(arg: &str) -> Result<(usize, usize)> {
    let parsed =
        arg.split_once('/').and_then(|(i, n)| Some((i.trim().parse::<usize>().ok()?, n.trim().parse::<usize>().ok()?)));
    match parsed {
        Some((i, n)) if n >= 1 && (1..=n).contains(&i) => Ok((i, n)),
        _ => anyhow::bail!("--shard {arg}: expected I/N with whole numbers 1 ≤ I ≤ N, e.g. --shard 3/8 (shard 3 of 8)"),
    }
}

/// Refuses an `--over` whose key is empty or has an empty part (`--over =0.5:1`), as `--over`:
/// the key reaches the scene as an override, whose message would blame `--set`.
fn check_over_names(over: &[String]) -> Result<()> {
    for arg in over {
        let key = arg.split_once('=').map_or(arg.as_str(), |(k, _)| k).trim();
        if key.is_empty() || key.split('.').any(str::is_empty) {
            anyhow::bail!(
                "--over {arg}: `{key}` is not a dotted key; expected a scene key before `=`, e.g. spectrum.range_nm"
            );
        }
    }
    Ok(())
}

/// `--tolerance REL` as the override `options.tolerance=REL` (validated with the scene).
fn with_tolerance(mut set: Vec<String>, tolerance: Option<f64>) -> Vec<String> {
    if let Some(t) = tolerance {
        set.push(format!("options.tolerance={t}"));
    }
    set
}

#[cfg(test)]
mod mapping_tests {
    use super::{
        MAPPING_CHECK_TOLERANCE, MAPPING_CONFIRM_TOLERANCE, MAPPING_WARNING, MappingCheck, other_map_mean_mtf,
    };

    /// examples/phase-binary2.toml with `set`: the check as `asnr evaluate` makes it (first at
    /// [`MAPPING_CHECK_TOLERANCE`], confirmed at 1e-3 where undecided), and the reference: the
    /// other map evaluated at 1e-3 for every lens, as the check was made before.
    fn checks(set: &[&str]) -> (MappingCheck, MappingCheck) {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/phase-binary2.toml");
        let set: Vec<String> = set.iter().map(|s| (*s).to_owned()).collect();
        let read = scene::load_with_warnings(Some(&file), &set).unwrap();
        let used = read.pupil_mapping.expect("a phase lens on axis has a pupil mapping");
        let loaded = read.scene;
        let mean = metric::evaluate(&loaded).unwrap().mean_mtf;
        let other = |tolerance: f64| other_map_mean_mtf(&loaded, Some(&file), &set, used, tolerance);
        let first = MappingCheck::new(used, other(MAPPING_CHECK_TOLERANCE).unwrap(), mean, MAPPING_CHECK_TOLERANCE);
        let check = first.confirmed(mean, other).unwrap();
        let reference = MappingCheck::new(used, other(1e-3).unwrap(), mean, 1e-3);
        (check, reference)
    }

    /// The check warns exactly where the check at 1e-3 for every lens warned, with the same
    /// text, on lenses just below and just above 1 % (by F-number, band and detector distance:
    /// the reference's errors +0.991 %, +0.994 %, +1.037 %, +1.103 %), which the first
    /// evaluation at 1e-1 cannot all decide, and on lenses it decides alone (the example's
    /// +1.68 %, F/3.5's +0.82 %).
    #[test]
    fn the_mapping_check_warns_as_the_check_at_1e_3_did_on_both_sides_of_one_percent() {
        let cases: [(&[&str], bool, bool); 6] = [
            // (overrides, the reference warns, the first evaluation is confirmed at 1e-3)
            (&["lens.f_number=3.2"], false, true),
            (&["lens.f_number=3.2", "lens.focal_length_mm=3.34"], false, true),
            (&["lens.f_number=5", "lens.focal_length_mm=3.0"], true, true),
            (&["lens.f_number=3.2", "spectrum.range_nm=200"], true, false),
            (&[], true, false),
            (&["lens.f_number=3.5"], false, false),
        ];
        for (set, warns, confirmed) in cases {
            let (check, reference) = checks(set);
            assert_eq!(reference.warning().is_some(), warns, "{set:?}: reference {:+e}", reference.paraxial_error);
            assert!((reference.paraxial_error.abs() - MAPPING_WARNING).abs() < 0.008, "{set:?}: near 1 %");
            assert_eq!(check.warning(), reference.warning(), "{set:?}: {:+e}", check.paraxial_error);
            let asked = if confirmed { MAPPING_CONFIRM_TOLERANCE } else { MAPPING_CHECK_TOLERANCE };
            assert_eq!(check.tolerance, asked, "{set:?}");
            assert!((check.paraxial_error - reference.paraxial_error).abs() < 2e-4, "{set:?}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Beside;
    use std::sync::mpsc::channel;
    use std::thread::{self, ThreadId};

    /// The work of the tests: its thread and a sum.
    fn work() -> (ThreadId, u64) {
        (thread::current().id(), (1..=10).sum())
    }

    /// A thread that has taken the work: the caller waits for it and gets the work's result.
    #[test]
    fn the_result_comes_from_the_other_thread_when_it_took_the_work() {
        let (taken, told) = channel();
        let beside = Beside::start(move || {
            let out = work();
            taken.send(()).unwrap();
            out
        });
        told.recv().unwrap();
        let (id, sum) = beside.finish();
        assert_eq!(sum, 55);
        assert_ne!(id, thread::current().id());
    }

    /// A thread that has not begun when the caller comes (a busy machine: here it waits for a
    /// signal sent only after the result), or that could not be started: the caller computes the
    /// work itself, and the late thread finds nothing to do.
    #[test]
    fn the_caller_computes_the_work_when_the_other_thread_has_not_begun() {
        let (go, wait) = channel::<()>();
        let beside = Beside::start_on(work, |run| {
            Some(thread::spawn(move || {
                wait.recv().unwrap();
                run();
            }))
        });
        let (id, sum) = beside.finish();
        assert_eq!((id, sum), (thread::current().id(), 55));
        go.send(()).unwrap();
        let beside = Beside::start_on(work, |_| None);
        assert_eq!(beside.finish(), (thread::current().id(), 55));
    }

    /// A panic of the work on the other thread is the caller's panic, with its message.
    #[test]
    fn a_panic_on_the_other_thread_reaches_the_caller() {
        let (taken, told) = channel();
        let beside = Beside::start(move || -> u64 {
            taken.send(()).unwrap();
            panic!("the work failed")
        });
        told.recv().unwrap();
        let panic = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| beside.finish())).unwrap_err();
        assert_eq!(panic.downcast_ref::<&str>(), Some(&"the work failed"));
    }
}
