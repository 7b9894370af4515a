//! `asnr compare`: lens designs side by side under one scene (a comparison file, or the embedded
//! comparison of the families, examples/designs.toml).
//!
//! For each design: the ASNR at the scene's band (glare-free and glare-inclusive, paper SI
//! eq. S9 and S14), its chromatic twin's, and the spectral range that maximizes its ASNR: the
//! best of a log grid, refined by golden section between the grid neighbours. A multiplexed
//! design also gets the best range of each channel, the spectrum centred at its wavelength.
//! Every grid point is an independent evaluation, run in parallel and collected in grid order.

use std::fmt::Write as _;

use anyhow::{Context, Result, anyhow, bail};
use rayon::prelude::*;
use serde::Serialize;

use crate::Progress;
use crate::optimize::{Range, assignment, parse_range};
use metric::{Evaluation, GlareMode};
use scene::{Comparison, Source};

/// The swept key: the spectral range of the shared spectrum.
pub const KEY: &str = "spectrum.range_nm";
/// The default grid of `--over`: 16 points, log-spaced from 2 to 300 nm (ratio 1.40 between
/// neighbours; the golden section refines the best).
const DEFAULT_GRID: (f64, f64, usize) = (2.0, 300.0, 16);
/// The golden-section refinement stops when the bracket is this narrow in ln(range): 1 % of the
/// range (the ASNR is flat near its maximum: 1 % of the range moves it by far less).
const REFINE_TOLERANCE: f64 = 1e-2;

/// The best spectral range found for a design (or one channel of it).
#[derive(Clone, Debug, Serialize)]
pub struct Best {
    /// The range, nm.
    pub range_nm: f64,
    /// The ASNR there.
    pub asnr: f64,
    /// Whether it is at an end of the grid (the maximum may lie outside it).
    pub at_bound: bool,
}

/// One channel of a multiplexed design: the spectrum centred at its wavelength.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelBest {
    /// The channel's wavelength (the spectrum's centre), nm.
    pub wavelength_nm: f64,
    /// The best range there.
    pub best: Best,
}

/// One design's results.
#[derive(Clone, Debug, Serialize)]
pub struct DesignReport {
    /// The design's place in the file: `designs[index]` (the key `--set designs[N].…` uses).
    pub index: usize,
    /// The design's name.
    pub name: String,
    /// Its family.
    pub kind: &'static str,
    /// The lens, described.
    pub lens: String,
    /// ASNR at the scene's band, with the scene's options.
    pub asnr: f64,
    /// Mean MTF up to Nyquist.
    pub mean_mtf: f64,
    /// Zero-frequency SNR.
    pub snr0: f64,
    /// Signal photoelectrons per pixel.
    pub photoelectrons: f64,
    /// `M0 = τ1/T` (SI eq. S13).
    pub m0: f64,
    /// Veiling glare `(1 − M0)/(1 + M0)` (SI eq. S12).
    pub vg: f64,
    /// ASNR with the imaging order's shot noise only (options.glare = "first_order", SI eq. S9).
    pub asnr_glare_free: f64,
    /// ASNR with the noise of all transmitted light (options.glare = "included", SI eq. S14).
    pub asnr_glare_inclusive: f64,
    /// Whether the Fraunhofer model holds at the scene band (SI eq. S15).
    pub fraunhofer_valid: bool,
    /// The Fresnel zones `N_z = f0/(8F#²λ0)`.
    pub fresnel_zones: f64,
    /// λ0 of `fresnel_zones`, nm.
    pub design_wavelength_nm: f64,
    /// The band a chromatic lens of this aperture keeps sharp, `λ0/(2N_z)`, nm.
    pub twin_band_nm: f64,
    /// The chromatic twin's ASNR at the scene band (absent when the twin detects no light).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub twin_asnr: Option<f64>,
    /// The best spectral range, nm.
    pub best_range_nm: f64,
    /// The ASNR at the best range.
    pub best_asnr: f64,
    /// Whether the best range is at an end of the grid.
    pub best_at_bound: bool,
    /// Mean NEQ to Nyquist at the scene band, quanta per pixel (`metric::metrics`).
    pub mean_neq: f64,
    /// Information capacity at the scene band, bits per pixel (flat object, contrast 1).
    pub capacity_bits_per_pixel: f64,
    /// The ASNR over that of the ideal lens of the same aperture.
    pub ideal_lens_ratio: f64,
    /// Rank by ASNR at the scene band (1 = best).
    pub rank: usize,
    /// Rank by ASNR at each design's best band.
    pub rank_at_best: usize,
    /// A multiplexed design's channels, each with its best range.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<ChannelBest>,
    /// Facts of the design.
    pub notes: Vec<String>,
    /// The evaluation's warnings at the scene band.
    pub warnings: Vec<String>,
    /// The ASNR at each grid range, `[range_nm, asnr]`.
    pub curve: Vec<[f64; 2]>,
    /// With `--wrt`: the exact gradient at the scene band over the named keys
    /// ([`crate::gradient::Gradient`]: `gradient` {KEY: ∂ASNR/∂KEY}, …), if this design has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gradient: Option<crate::gradient::Gradient>,
    /// With `--wrt`: why this design has no gradient (the refusal, naming the key).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gradient_note: Option<String>,
}

/// The whole comparison.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The file (or the embedded comparison).
    pub scene: String,
    /// Its title.
    pub title: Option<String>,
    /// The shared spectrum's centre, nm.
    pub center_nm: f64,
    /// The shared spectrum's range, nm (the scene band).
    pub range_nm: f64,
    /// How the best band was found.
    pub method: String,
    /// The designs, in file order.
    pub designs: Vec<DesignReport>,
    /// Design names by ASNR at the scene band, best first.
    pub ranking: Vec<String>,
    /// Design names by ASNR at their best band, best first.
    pub ranking_at_best: Vec<String>,
    /// Design names by each other metric at the scene band, best first: `mean_neq`,
    /// `capacity_bits_per_pixel`, `ideal_lens_ratio`.
    pub rankings: Vec<MetricRanking>,
}

/// The designs ranked by one metric.
#[derive(Clone, Debug, Serialize)]
pub struct MetricRanking {
    /// The metric, as the design's field names it.
    pub metric: &'static str,
    /// Design names, best first.
    pub ranking: Vec<String>,
    /// Whether this ranking differs from the ASNR's at the scene band.
    pub differs: bool,
}

/// A design at the scene band: its evaluation, the glare-free and glare-inclusive ASNR, and its
/// chromatic twin's ASNR (None when the twin detects no light).
type AtScene = (Evaluation, f64, f64, Option<f64>);

/// The best range of a search and every `(range, ASNR)` evaluated, in order of range.
type Refined = (Best, Vec<(f64, f64)>);

/// The most points `--over` may have: each evaluates every design (10 000 points ran for 40
/// minutes; 1000 take some 5).
const MAX_POINTS: usize = 1000;

/// N points log-spaced from `lo` to `hi` inclusive.
fn log_axis(range: &Range) -> Vec<f64> {
    let n = range.points.unwrap_or(2).max(1);
    if n == 1 {
        return vec![range.lo];
    }
    let (a, b) = (range.lo.ln(), range.hi.ln());
    (0..n)
        .map(|i| match i {
            0 => range.lo,
            i if i + 1 == n => range.hi,
            i => (a + (b - a) * i as f64 / (n - 1) as f64).exp(),
        })
        .collect()
}

/// The comparison of the designs of `scene` (None: the embedded comparison of the lens
/// families) with the overrides `set` and the relative `tolerance` of each ASNR, the best band
/// searched over `over` (`spectrum.range_nm=LO:HI:N`, log-spaced; default 2–300 nm, 16 points)
/// on `threads` threads (0 = all cores), each evaluation counted by `progress`: what
/// `asnr compare` prints (and the Python package's `asnr.compare` returns), with the comparison
/// it was built from (whose `warnings` the caller shows).
pub fn compare(
    scene: Option<&std::path::Path>,
    set: &[String],
    tolerance: Option<f64>,
    over: Option<&str>,
    threads: usize,
    progress: &dyn Progress,
) -> Result<(Comparison, Report)> {
    let mut set = set.to_vec();
    if let Some(t) = tolerance {
        set.push(format!("options.tolerance={t}"));
    }
    let range = match over {
        Some(o) => parse_range(o, true)?,
        None => Range { key: KEY.to_owned(), lo: DEFAULT_GRID.0, hi: DEFAULT_GRID.1, points: Some(DEFAULT_GRID.2) },
    };
    if range.key != KEY {
        bail!("--over {}: compare searches the spectral range only; expected --over {KEY}=LO:HI:N", range.key);
    }
    if range.lo <= 0.0 {
        bail!("--over {KEY}={}:{}: expected LO > 0 nm (the grid is log-spaced)", range.lo, range.hi);
    }
    if let Some(n) = range.points.filter(|&n| n > MAX_POINTS) {
        bail!(
            "--over {KEY}: {n} points; expected at most {MAX_POINTS}: each point evaluates every design (about 0.3 s a point on two cores for the embedded designs, so {n} points would take some {} minutes)",
            (n as f64 * 0.3 / 60.0).ceil()
        );
    }
    crate::optimize::check_over_keys(&set, std::slice::from_ref(&range))?;
    let max_threads = crate::optimize::max_threads();
    if threads > max_threads {
        bail!("--threads {}: expected 0 (all cores) to {max_threads} (4 × the available cores)", threads);
    }
    scene::check_overrides(scene, &set)?;
    let source = scene::read_comparison(scene)?;
    let base = scene::build_comparison(&source, &set)?;
    let Some((center_nm, range_nm)) = base.band_nm else {
        bail!(
            "{}: the shared [spectrum] has no center_nm and range_nm: compare needs a band-pass spectrum (shape \"gaussian\", \"tophat\" or \"line\") to search the best band",
            base.label
        );
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let report = pool.install(|| compute(&source, &set, &range, &base, center_nm, range_nm, progress))?;
    Ok((base, report))
}

/// Evaluates a scene, the error naming the design.
fn evaluate(name: &str, scene: &metric::Scene) -> Result<Evaluation> {
    metric::evaluate(scene).map_err(|e| anyhow!("design \"{name}\": {e}"))
}

/// The ASNR of design `index` with the extra overrides `extra`.
fn asnr_with(source: &Source, set: &[String], extra: &[String], index: usize) -> Result<f64> {
    let mut all = set.to_vec();
    all.extend_from_slice(extra);
    let comparison = scene::build_comparison(source, &all)?;
    let design = &comparison.designs[index];
    Ok(evaluate(&design.name, &design.scene)?.asnr)
}

/// One search of the best range: the design, the channel's centre (None: the scene's).
#[derive(Clone, Copy)]
struct Search {
    design: usize,
    centre_nm: Option<f64>,
}

impl Search {
    fn overrides(&self, range_nm: f64) -> Vec<String> {
        let mut extra = vec![assignment(KEY, range_nm)];
        if let Some(c) = self.centre_nm {
            extra.push(assignment("spectrum.center_nm", c));
        }
        extra
    }
}

fn compute(
    source: &Source,
    set: &[String],
    range: &Range,
    base: &Comparison,
    center_nm: f64,
    range_nm: f64,
    progress: &dyn Progress,
) -> Result<Report> {
    let grid = log_axis(range);
    let mut searches: Vec<Search> = (0..base.designs.len()).map(|design| Search { design, centre_nm: None }).collect();
    for (design, d) in base.designs.iter().enumerate() {
        searches.extend(d.channels_nm.iter().map(|&c| Search { design, centre_nm: Some(c) }));
    }
    let tasks: Vec<(usize, usize)> = (0..searches.len()).flat_map(|s| (0..grid.len()).map(move |k| (s, k))).collect();
    let total = tasks.len() + 3 * base.designs.len();
    progress.start(total as u64);
    // the scene band: the scene's options, glare-free and glare-inclusive, and the twin
    let at_scene: Vec<Result<AtScene>> = base
        .designs
        .par_iter()
        .map(|d| {
            let r = evaluate(&d.name, &d.scene)?;
            let other = match r.glare_mode {
                GlareMode::FirstOrder => GlareMode::Included,
                GlareMode::Included => GlareMode::FirstOrder,
            };
            let options = metric::Options { glare: other, ..d.scene.options().clone() };
            let scene = d.scene.clone().with_options(options).map_err(|e| anyhow!("design \"{}\": {e}", d.name))?;
            let o = evaluate(&d.name, &scene)?.asnr;
            let (free, inclusive) = if r.glare_mode == GlareMode::FirstOrder { (r.asnr, o) } else { (o, r.asnr) };
            let twin = metric::evaluate(&d.twin).ok().map(|t| t.asnr);
            progress.advance(3);
            Ok((r, free, inclusive, twin))
        })
        .collect();
    let values: Vec<Result<f64>> = tasks
        .par_iter()
        .map(|&(s, k)| {
            let search = searches[s];
            let v = asnr_with(source, set, &search.overrides(grid[k]), search.design)
                .with_context(|| format!("at {KEY}={}", grid[k]));
            progress.advance(1);
            v
        })
        .collect();
    progress.finish();
    let values: Vec<f64> = values.into_iter().collect::<Result<_>>()?;
    let curves: Vec<Vec<(f64, f64)>> = (0..searches.len())
        .map(|s| grid.iter().copied().zip(values[s * grid.len()..][..grid.len()].iter().copied()).collect())
        .collect();
    let bests: Vec<Result<Refined>> = searches
        .par_iter()
        .zip(curves.par_iter())
        .map(|(search, curve)| refine(curve, |x| asnr_with(source, set, &search.overrides(x), search.design)))
        .collect();
    let bests: Vec<Refined> = bests.into_iter().collect::<Result<_>>()?;

    let mut designs = Vec::new();
    for (i, (d, scene_result)) in base.designs.iter().zip(at_scene).enumerate() {
        let (r, free, inclusive, twin) = scene_result?;
        let (best, curve) = &bests[i];
        let options = metric::MetricsOptions { points: 2, ..metric::MetricsOptions::default() };
        let m = metric::metrics(&d.scene, &r, &options).map_err(|e| anyhow::anyhow!("design {}: {e}", d.name))?;
        let channels = searches
            .iter()
            .zip(&bests)
            .filter(|(s, _)| s.design == i && s.centre_nm.is_some())
            .map(|(s, (b, _))| ChannelBest { wavelength_nm: s.centre_nm.unwrap_or_default(), best: b.clone() })
            .collect();
        designs.push(DesignReport {
            index: i,
            name: d.name.clone(),
            kind: d.kind,
            lens: d.scene.lens().describe(),
            asnr: r.asnr,
            mean_mtf: r.mean_mtf,
            snr0: r.snr0,
            photoelectrons: r.photoelectrons,
            m0: r.glare.m0,
            vg: r.glare.vg,
            asnr_glare_free: free,
            asnr_glare_inclusive: inclusive,
            fraunhofer_valid: r.fraunhofer.valid,
            fresnel_zones: d.fresnel_zones,
            design_wavelength_nm: d.design_wavelength_nm,
            twin_band_nm: d.twin_band_nm,
            twin_asnr: twin,
            best_range_nm: best.range_nm,
            best_asnr: best.asnr,
            best_at_bound: best.at_bound,
            mean_neq: m.mean_neq,
            capacity_bits_per_pixel: m.capacity_bits_per_pixel,
            ideal_lens_ratio: m.ideal_lens.ratio,
            rank: 0,
            rank_at_best: 0,
            channels,
            notes: d.notes.clone(),
            warnings: r.warnings.clone(),
            curve: curve.iter().map(|&(x, y)| [x, y]).collect(),
            gradient: None,
            gradient_note: None,
        });
    }
    let order = |key: &dyn Fn(&DesignReport) -> f64| -> Vec<usize> {
        let mut idx: Vec<usize> = (0..designs.len()).collect();
        idx.sort_by(|&a, &b| key(&designs[b]).total_cmp(&key(&designs[a])));
        idx
    };
    let ranking = order(&|d| d.asnr);
    let ranking_at_best = order(&|d| d.best_asnr);
    let by_neq = order(&|d| d.mean_neq);
    let by_capacity = order(&|d| d.capacity_bits_per_pixel);
    let by_ratio = order(&|d| d.ideal_lens_ratio);
    for (place, &i) in ranking.iter().enumerate() {
        designs[i].rank = place + 1;
    }
    for (place, &i) in ranking_at_best.iter().enumerate() {
        designs[i].rank_at_best = place + 1;
    }
    let names = |idx: &[usize]| idx.iter().map(|&i| designs[i].name.clone()).collect::<Vec<_>>();
    let rankings = [("mean_neq", by_neq), ("capacity_bits_per_pixel", by_capacity), ("ideal_lens_ratio", by_ratio)]
        .into_iter()
        .map(|(metric, idx)| MetricRanking { metric, differs: idx != ranking, ranking: names(&idx) })
        .collect();
    let (ranking, ranking_at_best) = (names(&ranking), names(&ranking_at_best));
    Ok(Report {
        scene: base.label.clone(),
        title: base.title.clone(),
        center_nm,
        range_nm,
        method: format!(
            "best of a {}-point log grid of {KEY} from {} to {} nm, refined by golden section between its neighbours (to {} of the range)",
            grid.len(),
            range.lo,
            range.hi,
            REFINE_TOLERANCE
        ),
        designs,
        ranking,
        ranking_at_best,
        rankings,
    })
}

/// The best range of a sampled curve: its largest sample, refined by golden section (in log
/// range) between its two neighbours; the curve returned with the points evaluated, in order.
fn refine(curve: &[(f64, f64)], mut f: impl FnMut(f64) -> Result<f64>) -> Result<Refined> {
    let j = (0..curve.len()).max_by(|&a, &b| curve[a].1.total_cmp(&curve[b].1)).context("an empty grid")?;
    let mut points = curve.to_vec();
    let mut best = curve[j];
    if j > 0 && j + 1 < curve.len() {
        // in ln(range): the grid is log-spaced
        let (a, b) = (curve[j - 1].0.ln(), curve[j + 1].0.ln());
        let (found, _) = crate::optimize::golden_section(a, b, REFINE_TOLERANCE, |x| f(x.exp()))?;
        points.extend(found.into_iter().map(|(x, y)| (x.exp(), y)));
        for &(x, y) in &points {
            if y > best.1 {
                best = (x, y);
            }
        }
    }
    points.sort_by(|p, q| p.0.total_cmp(&q.0));
    points.dedup_by(|p, q| p.0 == q.0);
    let at_bound = j == 0 || j + 1 == curve.len();
    Ok((Best { range_nm: best.0, asnr: best.1, at_bound }, points))
}

/// A number to `digits` significant digits, without exponent for ordinary magnitudes.
pub fn sig(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let magnitude = v.abs().log10().floor() as i32;
    let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
    format!("{v:.decimals$}")
}

/// The human-readable report.
pub fn table(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "comparison {}", r.scene);
    if let Some(t) = &r.title {
        let _ = writeln!(s, "title      {t}");
    }
    let _ = writeln!(
        s,
        "scene band spectrum centred at {} nm, range {} nm ({KEY})",
        crate::number(r.center_nm),
        crate::number(r.range_nm)
    );
    let _ = writeln!(s, "best band  {}", r.method);
    let w = r.designs.iter().map(|d| d.name.chars().count()).max().unwrap_or(6).max(6);
    let k = r.designs.iter().map(|d| d.kind.len()).max().unwrap_or(4).max(4);
    // `[i]`: the design's index in the file (`--set designs[i].…`), beside its rank `#`
    let n = format!("[{}]", r.designs.len().saturating_sub(1)).len().max(3);
    let _ = writeln!(
        s,
        "\nAt the scene band (ASNR = SNR0 × mean MTF up to Nyquist; glare-incl.: SNR0 with the noise of all transmitted light, SI eq. S14)"
    );
    let _ = writeln!(
        s,
        "  #  {:>n$}  {:w$}  {:k$}  {:>8}  {:>8}  {:>7}  {:>8}  {:>6}  {:>11}  {:>9}",
        "[i]", "design", "kind", "ASNR", "mean MTF", "SNR0", "N (e⁻)", "M0", "glare-incl.", "twin ASNR"
    );
    for d in &r.designs {
        let _ = writeln!(
            s,
            "  {:>1}  {:>n$}  {:w$}  {:k$}  {:>8}  {:>8.5}  {:>7.3}  {:>8}  {:>6.4}  {:>11}  {:>9}",
            d.rank,
            format!("[{}]", d.index),
            d.name,
            d.kind,
            format!("{:.4}", d.asnr),
            d.mean_mtf,
            d.snr0,
            sig(d.photoelectrons, 4),
            d.m0,
            format!("{:.4}", d.asnr_glare_inclusive),
            d.twin_asnr.map_or("no light".to_owned(), |t| format!("{t:.4}")),
        );
    }
    let _ =
        writeln!(s, "  #: rank by ASNR; [i]: the design's place in the file, as in --set designs[i].lens.f_number=4");
    let _ = writeln!(
        s,
        "\nBest band and aperture (N_z = f0/(8F#²λ0) Fresnel zones; a chromatic lens of this aperture keeps λ0/(2N_z) sharp)"
    );
    let _ = writeln!(
        s,
        "  #  {:>n$}  {:w$}  {:>13}  {:>10}  {:>9}  {:>12}",
        "[i]", "design", "best range nm", "ASNR there", "N_z", "λ0/(2N_z) nm"
    );
    for d in &r.designs {
        let _ = writeln!(
            s,
            "  {:>1}  {:>n$}  {:w$}  {:>13}  {:>10.4}  {:>9}  {:>12}",
            d.rank_at_best,
            format!("[{}]", d.index),
            d.name,
            format!("{}{}", sig(d.best_range_nm, 4), if d.best_at_bound { " *" } else { "" }),
            d.best_asnr,
            sig(d.fresnel_zones, 4),
            sig(d.twin_band_nm, 4),
        );
    }
    if r.designs.iter().any(|d| d.best_at_bound) {
        let _ = writeln!(s, "  * at an end of the grid: the maximum may lie outside it (widen --over)");
    }
    let channels: Vec<&DesignReport> = r.designs.iter().filter(|d| !d.channels.is_empty()).collect();
    if !channels.is_empty() {
        let _ = writeln!(s, "\nChannels (the spectrum centred at each channel's wavelength, its range searched)");
        for d in channels {
            let each: Vec<String> = d
                .channels
                .iter()
                .map(|c| {
                    format!(
                        "{} nm: best range {} nm, ASNR {:.4}{}",
                        crate::number(c.wavelength_nm),
                        sig(c.best.range_nm, 4),
                        c.best.asnr,
                        if c.best.at_bound { " *" } else { "" }
                    )
                })
                .collect();
            let _ = writeln!(s, "  {}: {}", d.name, each.join("; "));
        }
    }
    let _ = writeln!(s, "\nRanking by ASNR at the scene band: {}", numbered(&r.ranking));
    if r.ranking_at_best != r.ranking {
        let _ = writeln!(s, "At each design's best band the ranking differs: {}", numbered(&r.ranking_at_best));
    } else {
        let _ = writeln!(s, "At each design's best band the ranking is the same.");
    }
    for m in &r.rankings {
        let what = match m.metric {
            "mean_neq" => "mean NEQ",
            "capacity_bits_per_pixel" => "information capacity",
            _ => "ASNR / ideal lens",
        };
        if m.differs {
            let _ = writeln!(s, "By {what} the ranking differs: {}", numbered(&m.ranking));
        } else {
            let _ = writeln!(s, "By {what} the ranking is the same.");
        }
    }
    let noted: Vec<&DesignReport> = r.designs.iter().filter(|d| !d.notes.is_empty()).collect();
    if !noted.is_empty() {
        let _ = writeln!(s, "\nNotes");
        for d in noted {
            let _ = writeln!(s, "  {}: {}", d.name, d.notes.join("; "));
        }
    }
    s
}

/// Design `index` of the comparison file `source` as a scene of its own: the shared tables with
/// the design's lens as `[lens]`; of the overrides `set`, the shared ones kept, this design's
/// (`designs[index].lens.KEY`) as `lens.KEY`, the other designs' left out. Refused for a design
/// with keys besides `name` and `lens`.
fn design_source(source: &Source, set: &[String], index: usize) -> Result<(Source, Vec<String>)> {
    let mut table: toml::Table = source.text().parse().map_err(|e| anyhow!("{}: not TOML: {e}", source.label()))?;
    let designs = match table.remove("designs") {
        Some(toml::Value::Array(list)) => list,
        _ => bail!("{}: no [[designs]]", source.label()),
    };
    table.remove("allow_different_focal_lengths");
    let Some(toml::Value::Table(design)) = designs.get(index) else {
        bail!("{}: no designs[{index}]", source.label());
    };
    if let Some(other) = design.keys().find(|k| *k != "name" && *k != "lens") {
        bail!("designs[{index}].{other}: a design with keys besides name and lens has no gradient here yet");
    }
    let lens = design.get("lens").cloned().ok_or_else(|| anyhow!("designs[{index}]: no lens"))?;
    table.insert("lens".to_owned(), lens);
    let text = toml::to_string(&table).map_err(|e| anyhow!("designs[{index}]: {e}"))?;
    let own = format!("designs[{index}].");
    let overrides = set
        .iter()
        .filter_map(|o| match o.trim_start().strip_prefix(&own) {
            Some(rest) => Some(rest.to_owned()),
            None if o.trim_start().starts_with("designs[") => None,
            None => Some(o.clone()),
        })
        .collect();
    Ok((Source::from_text(text, format!("{} designs[{index}]", source.label()), source.dir()), overrides))
}

/// `compare --wrt KEY…`: each design's exact gradient at the scene band over `wrt`
/// ([`crate::gradient::gradient`]), put into `report`; a design where it is refused gets the
/// refusal as its `gradient_note` instead.
pub fn gradients(
    scene: Option<&std::path::Path>,
    set: &[String],
    tolerance: Option<f64>,
    wrt: &[String],
    report: &mut Report,
) -> Result<()> {
    if wrt.is_empty() {
        return Ok(());
    }
    let mut set = set.to_vec();
    if let Some(t) = tolerance {
        set.push(format!("options.tolerance={t}"));
    }
    let source = scene::read_comparison(scene)?;
    for d in &mut report.designs {
        let result = design_source(&source, &set, d.index)
            .and_then(|(s, overrides)| crate::gradient::gradient(&s, &overrides, wrt));
        match result {
            Ok(g) => d.gradient = Some(g),
            Err(e) => d.gradient_note = Some(format!("{e:#}")),
        }
    }
    Ok(())
}

/// The `--wrt` part of the table: each design's `∂ln ASNR/∂ln key` at the scene band.
pub fn gradient_table(r: &Report) -> String {
    let mut s = String::from("\n∂ln ASNR/∂ln key at the scene band (exact gradient)\n");
    for d in &r.designs {
        match (&d.gradient, &d.gradient_note) {
            (Some(g), _) => {
                let parts: Vec<String> =
                    g.keys.iter().enumerate().map(|(i, k)| format!("{k} {:+.6}", g.relative(i))).collect();
                let _ = writeln!(s, "  {}: {}", d.name, parts.join(", "));
            }
            (None, Some(note)) => {
                let _ = writeln!(s, "  {}: none ({note})", d.name);
            }
            (None, None) => {}
        }
    }
    s
}

fn numbered(names: &[String]) -> String {
    names.iter().enumerate().map(|(i, n)| format!("{}. {n}", i + 1)).collect::<Vec<_>>().join(", ")
}

/// CSV, one row per design, written by the `csv` crate (fields quoted where RFC 4180 needs it).
pub fn csv(r: &Report) -> Result<String> {
    let mut out = csv::WriterBuilder::new().terminator(csv::Terminator::Any(b'\n')).from_writer(Vec::new());
    out.write_record([
        "index",
        "name",
        "kind",
        "asnr",
        "mean_mtf",
        "snr0",
        "photoelectrons",
        "m0",
        "asnr_glare_free",
        "asnr_glare_inclusive",
        "twin_asnr",
        "fresnel_zones",
        "twin_band_nm",
        "best_range_nm",
        "best_asnr",
        "rank",
        "rank_at_best",
        "notes",
    ])?;
    for d in &r.designs {
        out.write_record([
            d.index.to_string(),
            d.name.clone(),
            d.kind.to_owned(),
            d.asnr.to_string(),
            d.mean_mtf.to_string(),
            d.snr0.to_string(),
            d.photoelectrons.to_string(),
            d.m0.to_string(),
            d.asnr_glare_free.to_string(),
            d.asnr_glare_inclusive.to_string(),
            d.twin_asnr.map_or(String::new(), |t| t.to_string()),
            d.fresnel_zones.to_string(),
            d.twin_band_nm.to_string(),
            d.best_range_nm.to_string(),
            d.best_asnr.to_string(),
            d.rank.to_string(),
            d.rank_at_best.to_string(),
            d.notes.join(" | "),
        ])?;
    }
    Ok(String::from_utf8(out.into_inner().map_err(|e| anyhow!("CSV: {e}"))?)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn design(index: usize, name: &str, notes: &[&str]) -> DesignReport {
        DesignReport {
            index,
            name: name.to_owned(),
            kind: "chromatic",
            lens: "a lens".to_owned(),
            asnr: 10.5,
            mean_mtf: 0.5,
            snr0: 21.0,
            photoelectrons: 441.0,
            m0: 0.25,
            vg: 0.6,
            asnr_glare_free: 10.5,
            asnr_glare_inclusive: 5.25,
            fraunhofer_valid: true,
            fresnel_zones: 84.0,
            design_wavelength_nm: 800.0,
            twin_band_nm: 4.76,
            twin_asnr: None,
            best_range_nm: 33.0,
            best_asnr: 10.6,
            best_at_bound: false,
            mean_neq: 100.0,
            capacity_bits_per_pixel: 2.5,
            ideal_lens_ratio: 0.2,
            rank: 2 - index,
            rank_at_best: 2 - index,
            channels: Vec::new(),
            notes: notes.iter().map(|n| (*n).to_owned()).collect(),
            warnings: Vec::new(),
            curve: Vec::new(),
            gradient: None,
            gradient_note: None,
        }
    }

    #[test]
    fn csv_quotes_what_needs_it_and_reads_back() {
        let report = Report {
            scene: "x.toml".to_owned(),
            title: None,
            center_nm: 800.0,
            range_nm: 50.0,
            method: String::new(),
            designs: vec![design(0, "plain", &[]), design(1, "F/2.5, \"reduced\"", &["a, b", "line\nbreak"])],
            ranking: Vec::new(),
            ranking_at_best: Vec::new(),
            rankings: Vec::new(),
        };
        let text = csv(&report).unwrap();
        assert!(text.starts_with("index,name,kind,asnr,"), "{text}");
        assert!(text.contains("\n0,plain,chromatic,10.5,"), "{text}");
        let mut reader = ::csv::Reader::from_reader(text.as_bytes());
        let rows: Vec<::csv::StringRecord> = reader.records().map(Result::unwrap).collect();
        assert_eq!(rows.len(), 2);
        assert_eq!(&rows[1][0], "1");
        assert_eq!(&rows[1][1], "F/2.5, \"reduced\"");
        assert_eq!(&rows[1][10], "", "no twin: an empty field");
        assert_eq!(&rows[1][17], "a, b | line\nbreak");
    }
}
