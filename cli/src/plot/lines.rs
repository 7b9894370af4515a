//! Line overlays (`asnr plot`, `asnr compare --plot`, sweeps over one key): lines with shaded
//! runs, marked maxima and vertical marks, on linear or logarithmic axes.

use super::*;

/// Writes lines `series` (at least one point in all), with vertical `marks`, shaded regions
/// where a series' points are flagged, and with `mark_best` a dot at each line's maximum (see
/// [`peak`]; its x and y in the legend). SVG or PNG by the file's extension; errors name `flag`.
pub fn lines_plot(
    flag: &str,
    path: &Path,
    figure: &Figure,
    labels: &Labels,
    series: &[Series],
    marks: &[Mark],
    mark_best: bool,
) -> Result<()> {
    if series.iter().all(|s| s.points.is_empty()) {
        bail!("{flag} {}: nothing to plot (no points)", path.display());
    }
    render(flag, path, figure, &LinesPlot { labels, series, marks, mark_best })
}

/// Line charts of `asnr plot` and one-key sweeps.
pub(super) struct LinesPlot<'a> {
    pub(super) labels: &'a Labels<'a>,
    pub(super) series: &'a [Series],
    pub(super) marks: &'a [Mark],
    pub(super) mark_best: bool,
}

/// Width of a line where no later line lies on it, points; each later line lying on it there
/// widens it by [`COVER_PT`], so the line under shows on both sides of the one over.
pub(super) const LINE_PT: f64 = 1.6;
pub(super) const COVER_PT: f64 = 1.3;
/// A line lies on an earlier one where they are closer than this fraction of the y axis (about a
/// line's width at the default figure size).
pub(super) const COINCIDENT: f64 = 0.01;

/// Series as drawn, the x range and the y range ([`LinesPlot::view`]).
pub(super) type View<'a> = (std::borrow::Cow<'a, [Series]>, (f64, f64), (f64, f64));

/// A run of a line's segments drawn alike: (dashed, lines over it) and its points.
pub(super) type Run = ((bool, usize), Vec<(f64, f64)>);

impl LinesPlot<'_> {
    pub(super) fn stroke(i: usize) -> Stroke {
        Stroke::solid(PALETTE[i % PALETTE.len()], LINE_PT)
    }

    /// For each point of each series (see [`LinesPlot::view`] for `series` and `y`), how many
    /// later series pass within [`COINCIDENT`] of it (linear between their points): the lines
    /// drawn over it there.
    pub(super) fn covers(series: &[Series], y: (f64, f64)) -> Vec<Vec<usize>> {
        let close = (y.1 - y.0) * COINCIDENT;
        let near = |(x, v): (f64, f64), over: &Series| {
            let p = &over.points;
            let (Some(first), Some(last)) = (p.first(), p.last()) else { return false };
            if x < first.0 || x > last.0 {
                return false;
            }
            let j = p.partition_point(|q| q.0 < x).min(p.len() - 1);
            let at = if j == 0 || p[j].0 == x {
                p[j].1
            } else {
                p[j - 1].1 + (p[j].1 - p[j - 1].1) * (x - p[j - 1].0) / (p[j].0 - p[j - 1].0)
            };
            (v - at).abs() <= close
        };
        series
            .iter()
            .enumerate()
            .map(|(i, s)| s.points.iter().map(|&q| series[i + 1..].iter().filter(|o| near(q, o)).count()).collect())
            .collect()
    }

    pub(super) fn shaded(&self) -> bool {
        self.series.iter().any(|s| s.shaded.iter().any(|&f| f))
    }

    /// The series as drawn (log10 of their positive values on a log axis), the x range and the
    /// y range of the axes.
    pub(super) fn view(&self) -> View<'_> {
        let (log_x, log_y) = (self.labels.log_x, self.labels.log_y);
        let series: std::borrow::Cow<'_, [Series]> = if log_x || log_y {
            let log = |(x, y): (f64, f64)| {
                let x = if log_x { (x > 0.0).then(|| x.log10())? } else { x };
                let y = if log_y { (y > 0.0).then(|| y.log10())? } else { y };
                Some((x, y))
            };
            self.series
                .iter()
                .map(|s| Series {
                    label: s.label.clone(),
                    points: s.points.iter().copied().filter_map(log).collect(),
                    shaded: if s.points.iter().all(|&p| log(p).is_some()) { s.shaded.clone() } else { Vec::new() },
                    best: s.best.as_ref().and_then(|(p, how)| log(*p).map(|p| (p, how.clone()))),
                })
                .collect::<Vec<_>>()
                .into()
        } else {
            self.series.into()
        };
        let all = || series.iter().flat_map(|s| s.points.iter());
        let (mut x0, mut x1) = extent(all().map(|p| p.0));
        if x1 <= x0 {
            (x0, x1) = (x0 - 0.5, x1 + 0.5);
        }
        let (lo, hi) = extent(all().map(|p| p.1));
        let y = if log_y {
            // whole decades around the data, or 4 % of the span beyond it where that is tighter
            let pad = 0.04 * (hi - lo).max(1.0);
            ((lo - pad).max(lo.floor()), (hi + pad).min(hi.ceil().max(hi + 1e-9)))
        } else {
            let (lo, hi) = (lo.min(0.0), hi.max(0.0));
            // 6 % of the span above (and below, for negative values); all zeros span 0 to 1
            let span = if hi - lo > 1e-12 * hi.abs().max(lo.abs()) { hi - lo } else { hi.abs().max(1.0) / 0.06 };
            let pad = 0.06 * span;
            (if lo < 0.0 { lo - pad } else { 0.0 }, hi + pad)
        };
        (series, (x0, x1), y)
    }
}

/// One legend entry per distinct label of `marks`, with `stroke`.
pub(super) fn mark_entries(marks: &[Mark], stroke: Stroke) -> Vec<Entry> {
    let mut entries: Vec<Entry> = Vec::new();
    for label in marks.iter().filter_map(|m| m.label.as_deref()) {
        if !entries.iter().any(|e| e.label == label) {
            entries.push(Entry { label: label.to_owned(), swatch: Swatch::Line(stroke) });
        }
    }
    entries
}

impl Plot for LinesPlot<'_> {
    fn title(&self) -> &str {
        self.labels.title
    }

    fn entries(&self) -> Vec<Entry> {
        let mut entries: Vec<Entry> = self
            .series
            .iter()
            .enumerate()
            .map(|(i, s)| match s.best.clone().or_else(|| peak(&s.points).map(|p| (p, String::new()))) {
                Some(((x, y), given)) if self.mark_best => {
                    let unit =
                        if self.labels.x_unit.is_empty() { String::new() } else { format!(" {}", self.labels.x_unit) };
                    // how the maximum was found: refined between grid points, or a grid point at an end
                    let at_end =
                        s.points.first().is_some_and(|p| p.0 == x) || s.points.last().is_some_and(|p| p.0 == x);
                    let how = if !given.is_empty() {
                        given.as_str()
                    } else if at_end {
                        "grid point at the end of the range"
                    } else {
                        "parabola between grid points"
                    };
                    Entry {
                        label: format!("{}: max {} at {}{unit} ({how})", s.label, significant(y), significant(x)),
                        swatch: Swatch::Dot(Self::stroke(i), Self::stroke(i).colour),
                    }
                }
                _ => Entry { label: s.label.clone(), swatch: Swatch::Line(Self::stroke(i)) },
            })
            .collect();
        entries.extend(mark_entries(self.marks, MARK));
        if self.shaded() && !self.labels.shade.is_empty() {
            let line = Stroke::solid(RGBColor(60, 60, 60), 1.0).with_dashes();
            entries.push(Entry {
                label: self.labels.shade.to_owned(),
                swatch: Swatch::Patch { base: None, fill: (SHADE.0, SHADE.1 * 2.0), line: Some(line) },
            });
        }
        entries
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        // on a log axis the series are drawn as log10 of their positive values
        let (series, (x0, x1), y) = self.view();
        let (log_x, log_y) = (self.labels.log_x, self.labels.log_y);
        let covers = Self::covers(&series, y);
        let axes = Axes {
            x: (x0, x1),
            y,
            x_desc: self.labels.x,
            y_desc: self.labels.y,
            grid: true,
            y_log: self.labels.log_y,
            x_log: self.labels.log_x,
        };
        let (mut chart, _) = axes.build(area, ctx, 0)?;
        axes.label_between_decades(area, &chart, ctx)?;
        minor_decades(&mut chart, ctx, (x0, x1), y, (log_x, log_y))?;
        // shading first, under everything: each series' flagged points, layered in translucent grey
        for s in series.iter().filter(|s| s.shaded.iter().any(|&f| f)) {
            let xs: Vec<f64> = s.points.iter().map(|p| p.0).collect();
            let edges = cell_edges(&xs);
            let shaded = |i: usize| s.shaded.get(i).copied().unwrap_or(false);
            let mut rects = Vec::new();
            let mut i = 0;
            while i < xs.len() {
                let start = i;
                while i < xs.len() && shaded(i) {
                    i += 1;
                }
                if i > start {
                    rects.push(Rectangle::new([(edges[start], y.0), (edges[i], y.1)], SHADE.0.mix(SHADE.1).filled()));
                } else {
                    i += 1;
                }
            }
            chart.draw_series(rects).map_err(|e| fail(&e))?;
        }
        for (i, (s, cover)) in series.iter().zip(&covers).enumerate() {
            let stroke = Self::stroke(i);
            let dashed = |j: usize| s.shaded.get(j).copied().unwrap_or(false);
            // where later lines lie on this one, it is drawn wider under them
            let widened = |j: usize| cover.get(j).copied().unwrap_or(0).min(cover.get(j + 1).copied().unwrap_or(0));
            // runs of segments, solid, or dashed where they end in a shaded point, and as wide
            let mut runs: Vec<Run> = Vec::new();
            for (j, w) in s.points.windows(2).enumerate() {
                let kind = (dashed(j + 1), widened(j));
                match runs.last_mut() {
                    Some((k, run)) if *k == kind => run.push(w[1]),
                    _ => runs.push((kind, vec![w[0], w[1]])),
                }
            }
            if runs.is_empty() {
                runs.push(((false, 0), s.points.clone()));
            }
            for ((dashes, under), run) in runs {
                let stroke = Stroke { width: LINE_PT + COVER_PT * under as f64, ..stroke };
                draw_curve(&mut chart, ctx, &run, if dashes { stroke.with_dashes() } else { stroke })?;
            }
        }
        // the maxima over all the lines, each dot wider by a ring for each later dot over it
        let bests: Vec<Option<(f64, f64)>> = series
            .iter()
            .map(|s| s.best.as_ref().map(|b| b.0).or_else(|| peak(&s.points)).filter(|_| self.mark_best))
            .collect();
        let pixels: Vec<Option<(i32, i32)>> = bests.iter().map(|b| b.map(|p| chart.backend_coord(&p))).collect();
        for (i, best) in bests.iter().enumerate() {
            let stroke = Self::stroke(i);
            if let (Some(best), Some((x, y))) = (*best, pixels[i]) {
                let over = pixels[i + 1..]
                    .iter()
                    .flatten()
                    .filter(|&&(qx, qy)| f64::from(qx - x).hypot(f64::from(qy - y)) < f64::from(ctx.px(5.0)))
                    .count();
                let (r, ring) = (ctx.px(2.5 + 1.3 * over as f64), WHITE.stroke_width(ctx.stroke(0.5)));
                chart
                    .draw_series([Circle::new(best, r, stroke.colour.filled()), Circle::new(best, r, ring)])
                    .map_err(|e| fail(&e))?;
            }
        }
        // reference lines last, on top
        for mark in self.marks {
            draw_curve(&mut chart, ctx, &[(mark.x, y.0), (mark.x, y.1)], MARK)?;
        }
        axes.frame(&mut chart, ctx)
    }
}

/// On log axes (`log`: x, y), light lines at 2–9 × 10^k between the decades' grid lines.
pub(super) fn minor_decades<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    ctx: Ctx,
    x: (f64, f64),
    y: (f64, f64),
    log: (bool, bool),
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let between = |(lo, hi): (f64, f64)| {
        ((lo.floor() as i32)..=(hi.ceil() as i32))
            .flat_map(|decade| (2..=9).map(move |k| f64::from(decade) + f64::from(k).log10()))
            .filter(move |&v| v > lo && v < hi)
    };
    let minor = Stroke::solid(MINOR_GRID, 0.3);
    if log.0 {
        for v in between(x) {
            draw_curve(chart, ctx, &[(v, y.0), (v, y.1)], minor)?;
        }
    }
    if log.1 {
        for v in between(y) {
            draw_curve(chart, ctx, &[(x.0, v), (x.1, v)], minor)?;
        }
    }
    Ok(())
}
