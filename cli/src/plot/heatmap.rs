//! Heatmaps and images: a value over two keys with its colour bar, ridge and marks (sweeps and
//! maps), and the square images of `asnr psf` and `asnr otf`.

use super::*;

/// Writes a heatmap of `grid` with a colour bar, the ridge (for each x the y of the largest
/// value, see [`peak`]; a white line), vertical `marks` (dashed red) and shaded cells. SVG or PNG
/// by the file's extension; errors name `flag`.
pub fn heatmap_plot(
    flag: &str,
    path: &Path,
    figure: &Figure,
    labels: &Labels,
    grid: &Grid,
    marks: &[Mark],
) -> Result<()> {
    if grid.xs.is_empty() || grid.ys.is_empty() || grid.z.len() != grid.xs.len() * grid.ys.len() {
        bail!("{flag} {}: the heatmap grid is empty or incomplete", path.display());
    }
    render(flag, path, figure, &HeatmapPlot { labels, grid, marks, path: &[], square: false })
}

/// Writes `grid` as an image: a heatmap whose x and y are the same quantity (a PSF over the
/// detector, an OTF over frequency), one unit as long on both axes, with its colour bar and no
/// ridge. SVG or PNG by the file's extension; errors name `flag`.
pub fn image_plot(flag: &str, path: &Path, figure: &Figure, labels: &Labels, grid: &Grid) -> Result<()> {
    if grid.xs.is_empty() || grid.ys.is_empty() || grid.z.len() != grid.xs.len() * grid.ys.len() {
        bail!("{flag} {}: the image grid is empty or incomplete", path.display());
    }
    let labels = Labels { ridge: "", ..*labels };
    render(flag, path, figure, &HeatmapPlot { labels: &labels, grid, marks: &[], path: &[], square: true })
}

/// matplotlib's viridis for `t` in [0, 1] (plotters' table of eight stops, linear between).
pub(super) fn colour(t: f64) -> RGBColor {
    plotters::style::colors::colormaps::ViridisRGB::get_color(t.clamp(0.0, 1.0))
}

/// Heatmaps of `asnr plot --z` and two-key sweeps.
pub(super) struct HeatmapPlot<'a> {
    pub(super) labels: &'a Labels<'a>,
    pub(super) grid: &'a Grid,
    pub(super) marks: &'a [Mark],
    /// A path drawn over the map (an optimizer's points in order), with its legend entry; empty
    /// for none.
    pub(super) path: &'a [(f64, f64)],
    /// x and y in the same unit: the plotting area is as many pixels per unit on both axes
    /// (within a pixel), and taller than a chart's
    pub(super) square: bool,
}

/// The axes block of an image ([`HeatmapPlot::square`]) over the figure's width: room for a
/// square plotting area beside the colour bar at the default size.
pub(super) const IMAGE_ASPECT: f64 = 0.8;

/// An optimizer's path over a heatmap.
pub(super) const PATH: Stroke = Stroke::solid(RGBColor(230, 30, 30), 1.2);

/// The white veil over shaded heatmap cells.
pub(super) const VEIL: (RGBColor, f64) = (RGBColor(255, 255, 255), 0.55);

impl HeatmapPlot<'_> {
    /// `(lo, hi)` of the values, `hi > lo`.
    pub(super) fn range(&self) -> (f64, f64) {
        let (lo, hi) = extent(self.grid.z.iter().copied());
        if hi > lo { (lo, hi) } else { (lo - 0.5, hi + 0.5) }
    }
}

impl Plot for HeatmapPlot<'_> {
    fn title(&self) -> &str {
        self.labels.title
    }

    fn aspect(&self) -> f64 {
        if self.square { IMAGE_ASPECT } else { ASPECT }
    }

    fn entries(&self) -> Vec<Entry> {
        let mut entries = Vec::new();
        if !self.labels.ridge.is_empty() {
            entries.push(Entry { label: self.labels.ridge.to_owned(), swatch: Swatch::Line(RIDGE) });
        }
        entries.extend(mark_entries(self.marks, HEAT_MARK));
        if !self.path.is_empty() {
            entries.push(Entry {
                label: "the search's path (its last point the optimum)".to_owned(),
                swatch: Swatch::Line(PATH),
            });
        }
        if self.grid.shaded.iter().any(|&s| s) && !self.labels.shade.is_empty() {
            entries.push(Entry {
                label: self.labels.shade.to_owned(),
                swatch: Swatch::Patch { base: Some(colour(0.3)), fill: VEIL, line: None },
            });
        }
        entries
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let grid = self.grid;
        let (ex, ey) = (cell_edges(&grid.xs), cell_edges(&grid.ys));
        let ny = grid.ys.len();
        let (lo, hi) = self.range();
        drawable("colour bar", (lo, hi))?;
        let span = hi - lo;
        let (x0, x1, y0, y1) = (ex[0], ex[ex.len() - 1], ey[0], ey[ey.len() - 1]);
        // the colour bar's room on the right: gap, bar, ticks, labels, description
        let (_, area_h) = area.dim_in_pixel();
        let bar_n = tick_count(ctx, i32::try_from(area_h).unwrap_or(i32::MAX) * 3 / 4, TICK_PT * 2.5);
        let bar_ticks = ticks((lo, hi), bar_n);
        let bar_format = TickFormat::of(&bar_ticks);
        let bar_labels = bar_ticks.iter().map(|&v| ctx.text_width(TICK_PT, &bar_format.write(v))).max().unwrap_or(0);
        let bar_label_area = ctx.px(5.0) + bar_labels + ctx.px(4.0) + ctx.px(DESC_PT * 1.6);
        let bar_w = ctx.px(12.0) + ctx.px(10.0) + bar_label_area + ctx.px(MARGIN_PT);
        let axes = Axes {
            x: (x0, x1),
            y: (y0, y1),
            x_desc: self.labels.x,
            y_desc: self.labels.y,
            grid: false,
            y_log: false,
            x_log: false,
        };
        // an image: the area trimmed on both sides (or above and below) to the plotting area whose
        // width over height is the data's
        let (w, h) = area.dim_in_pixel();
        let (w, h) = (i32::try_from(w).unwrap_or(i32::MAX), i32::try_from(h).unwrap_or(i32::MAX));
        let m = axes.margins(ctx, (w, h), bar_w);
        let (pw, ph) = (w - m.left - m.right - m.y_labels, h - m.top - m.bottom - m.x_labels);
        let wide = f64::from(ph) * (x1 - x0) / (y1 - y0);
        let (trim_x, trim_y) = match self.square {
            false => (0, 0),
            true if wide <= f64::from(pw) => ((f64::from(pw) - wide) as i32 / 2, 0),
            true => (0, (f64::from(ph) - f64::from(pw) * (y1 - y0) / (x1 - x0)) as i32 / 2),
        };
        let area = &area.margin(trim_y, trim_y, trim_x, trim_x);
        let (mut chart, margins) = axes.build(area, ctx, bar_w)?;
        let cell = |i: usize, j: usize| [(ex[i], ey[j]), (ex[i + 1], ey[j + 1])];
        // each cell reaches halfway into the next (which is drawn later and covers it), so no
        // anti-aliased seam shows between cells whose edges fall between pixels
        let beyond = |edges: &[f64], i: usize| edges.get(i + 2).map_or(edges[i + 1], |e| 0.5 * (edges[i + 1] + e));
        let overlapping = |i: usize, j: usize| [(ex[i], ey[j]), (beyond(&ex, i), beyond(&ey, j))];
        let cells = (0..grid.xs.len()).flat_map(|i| (0..ny).map(move |j| (i, j)));
        chart
            .draw_series(
                cells
                    .clone()
                    .map(|(i, j)| Rectangle::new(overlapping(i, j), colour((grid.z[i * ny + j] - lo) / span).filled())),
            )
            .map_err(|e| fail(&e))?;
        let shaded = |i: usize, j: usize| grid.shaded.get(i * ny + j).copied().unwrap_or(false);
        if grid.shaded.iter().any(|&s| s) {
            chart
                .draw_series(
                    cells
                        .filter(|&(i, j)| shaded(i, j))
                        .map(|(i, j)| Rectangle::new(cell(i, j), VEIL.0.mix(VEIL.1).filled())),
                )
                .map_err(|e| fail(&e))?;
        }
        // the ridge: for each x, the y with the largest value
        let ridge: Vec<(f64, f64)> = grid
            .z
            .chunks(ny)
            .zip(&grid.xs)
            .filter_map(|(column, &x)| {
                let samples: Vec<(f64, f64)> = grid.ys.iter().copied().zip(column.iter().copied()).collect();
                Some((x, peak(&samples)?.0))
            })
            .collect();
        if !self.labels.ridge.is_empty() {
            draw_curve(&mut chart, ctx, &ridge, RIDGE)?;
        }
        // a dot at each sample of the ridge, when they are at least 8 pt apart
        let plot_w = f64::from(chart.plotting_area().dim_in_pixel().0) / ctx.k;
        if !self.labels.ridge.is_empty() && ridge.len() as f64 * 8.0 <= plot_w {
            let (r, ring) = (ctx.px(1.8), RGBColor(30, 30, 30).stroke_width(ctx.stroke(0.5)));
            chart
                .draw_series(ridge.iter().flat_map(|&p| [Circle::new(p, r, WHITE.filled()), Circle::new(p, r, ring)]))
                .map_err(|e| fail(&e))?;
        }
        // reference lines last, on top
        for mark in self.marks {
            draw_curve(&mut chart, ctx, &[(mark.x, y0), (mark.x, y1)], HEAT_MARK)?;
        }
        if let Some(&last) = self.path.last() {
            draw_curve(&mut chart, ctx, self.path, PATH)?;
            let r = ctx.px(3.0);
            chart
                .draw_series([
                    Circle::new(last, r, PATH.colour.filled()),
                    Circle::new(last, r, INK.stroke_width(ctx.stroke(0.6))),
                ])
                .map_err(|e| fail(&e))?;
        }
        axes.frame(&mut chart, ctx)?;
        // the colour bar, level with the plotting area, labelled on its right
        let (w, _) = area.dim_in_pixel();
        let (_, bar) = area.split_horizontally(i32::try_from(w).unwrap_or(i32::MAX) - bar_w);
        let mut scale = ChartBuilder::on(&bar)
            .margin_top(margins.top)
            .margin_bottom(margins.bottom + margins.x_labels)
            .margin_left(ctx.px(12.0))
            .margin_right(ctx.px(MARGIN_PT))
            .right_y_label_area_size(bar_label_area)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(|e| fail(&e))?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_labels(bar_n)
            .y_desc(self.labels.z)
            .y_label_formatter(&|v| bar_format.write(*v))
            .axis_style(INK.stroke_width(ctx.stroke(0.6)))
            .set_all_tick_mark_size(ctx.px(3.0))
            .label_style(ctx.font(TICK_PT))
            .axis_desc_style(ctx.font(DESC_PT))
            .draw()
            .map_err(|e| fail(&e))?;
        let steps = 100;
        scale
            .draw_series((0..steps).map(|i| {
                // each step reaches halfway into the next, drawn over it, so no seams show
                let a = lo + span * i as f64 / steps as f64;
                let b = lo + span * ((i + 1) as f64 + if i + 1 < steps { 0.5 } else { 0.0 }) / steps as f64;
                Rectangle::new([(0.0, a), (1.0, b)], colour(i as f64 / (steps - 1) as f64).filled())
            }))
            .map_err(|e| fail(&e))?;
        scale
            .draw_series([PathElement::new(outline((0.0, lo), (1.0, hi)), INK.stroke_width(ctx.stroke(0.6)))])
            .map(|_| ())
            .map_err(|e| fail(&e))
    }
}
