//! Plots, SVG or PNG, drawn by plotters' pure-Rust backends: MTF curves, sweeps, and the
//! general line overlays and heatmaps of `asnr plot`. PNG text is rasterized with DejaVu Sans
//! embedded in the binary (`assets/`, Bitstream Vera licence), so no system font or fontconfig is
//! needed.

use std::path::Path;
use std::sync::Once;

use anyhow::{Result, anyhow, bail};
use metric::MtfCurve;

use crate::optimize::Range;
use crate::sweep::Point;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Plot size, pixels.
const SIZE: (u32, u32) = (900, 560);

/// Registers the embedded font (both backends measure text with it; PNG also rasterizes it).
fn register_font() {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // the font is a valid TrueType file compiled into the binary
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Draws with `$draw(root)` into `$path` on the backend its extension names (.svg or .png);
/// errors name the option `$flag` that gave the path.
macro_rules! render {
    ($flag:expr, $path:expr, $draw:expr) => {{
        let (flag, path): (&str, &Path) = ($flag, $path);
        let err = |e: &dyn std::fmt::Display| anyhow!("{flag} {}: {e}", path.display());
        register_font();
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("svg") => $draw(SVGBackend::new(path, SIZE).into_drawing_area()).map_err(|e| err(&e)),
            Some("png") => $draw(BitMapBackend::new(path, SIZE).into_drawing_area()).map_err(|e| err(&e)),
            _ => bail!("{flag} {}: expected a file name ending in .svg or .png", path.display()),
        }
    }};
}

/// How many times larger SVGs of [`lines_plot`] and [`heatmap_plot`] are drawn than shown.
/// Plotters rounds SVG coordinates to whole pixels, which makes smooth curves visibly stepped;
/// drawn at `FINE × SIZE` and shown at `SIZE` (the viewBox keeps the drawing's coordinates), the
/// steps are a fraction of a pixel.
const FINE: u32 = 2;

/// Like `render!`, with `$draw(root, k)` scaling its pixel sizes (fonts, margins, strokes) by
/// `k`: SVGs are drawn at [`FINE`] times [`SIZE`] and shown at `SIZE`; PNGs at `SIZE`, `k = 1`.
macro_rules! render_fine {
    ($flag:expr, $path:expr, $draw:expr) => {{
        let (flag, path): (&str, &Path) = ($flag, $path);
        let err = |e: &dyn std::fmt::Display| anyhow!("{flag} {}: {e}", path.display());
        register_font();
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("svg") => {
                let fine = (SIZE.0 * FINE, SIZE.1 * FINE);
                let mut text = String::new();
                $draw(SVGBackend::with_string(&mut text, fine).into_drawing_area(), FINE as i32)
                    .map_err(|e| err(&e))?;
                let text = text.replacen(
                    &format!("<svg width=\"{}\" height=\"{}\"", fine.0, fine.1),
                    &format!("<svg width=\"{}\" height=\"{}\"", SIZE.0, SIZE.1),
                    1,
                );
                std::fs::write(path, text).map_err(|e| err(&e))
            }
            Some("png") => $draw(BitMapBackend::new(path, SIZE).into_drawing_area(), 1).map_err(|e| err(&e)),
            _ => bail!("{flag} {}: expected a file name ending in .svg or .png", path.display()),
        }
    }};
}

/// Writes the MTF curve as a line chart, SVG or PNG by the file's extension: the polychromatic
/// MTF, the diffraction limit, the monochromatic curves, and the Nyquist frequency when the axis
/// extends past it.
pub fn mtf_plot(path: &Path, title: &str, curve: &MtfCurve) -> Result<()> {
    render!("--plot", path, |root| draw(root, title, curve))
}

/// Writes a sweep's ASNR: a line against the key for one swept key, a heatmap with the ridge of
/// the optimum (the best second key for each value of the first) for two.
pub fn sweep_plot(path: &Path, title: &str, ranges: &[Range], points: &[Point]) -> Result<()> {
    match ranges {
        [range] => {
            let series = Series {
                label: "ASNR".to_owned(),
                points: points.iter().map(|p| (p.values[0], p.asnr)).collect(),
                shaded: Vec::new(),
            };
            let labels = Labels { title, x: &range.key, y: "ASNR", ..Labels::default() };
            lines_plot("--plot", path, &labels, &[series], &[], true)
        }
        [first, second] => {
            let grid = Grid {
                xs: crate::sweep::axis(first),
                ys: crate::sweep::axis(second),
                z: points.iter().map(|p| p.asnr).collect(),
                shaded: Vec::new(),
            };
            let ridge = format!("best {} for each {}", second.key, first.key);
            let labels = Labels { title, x: &first.key, y: &second.key, z: "ASNR", ridge: &ridge, shade: "" };
            heatmap_plot("--plot", path, &labels, &grid, &[])
        }
        _ => bail!("--plot: a sweep over {} keys; plots take one key (a line) or two (a heatmap)", ranges.len()),
    }
}

/// The texts of a plot: title, axis descriptions, and the legend entries of the heatmap ridge and
/// of shaded regions (used only when something is shaded).
#[derive(Clone, Copy, Debug, Default)]
pub struct Labels<'a> {
    /// Caption above the chart.
    pub title: &'a str,
    /// Description of the x axis.
    pub x: &'a str,
    /// Description of the y axis.
    pub y: &'a str,
    /// Heatmaps: description of the colour bar (the plotted value).
    pub z: &'a str,
    /// Heatmaps: legend entry of the ridge, the y with the largest value for each x.
    pub ridge: &'a str,
    /// Legend entry of shaded points or cells.
    pub shade: &'a str,
}

/// One line of an overlay plot.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend entry.
    pub label: String,
    /// `(x, y)` in increasing `x`.
    pub points: Vec<(f64, f64)>,
    /// Points to shade and draw dashed, one flag per point; empty for none.
    pub shaded: Vec<bool>,
}

/// A complete rectangular grid of values `z(x, y)` for a heatmap.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Distinct x values, increasing.
    pub xs: Vec<f64>,
    /// Distinct y values, increasing.
    pub ys: Vec<f64>,
    /// The value at `(xs[i], ys[j])` is `z[i * ys.len() + j]`.
    pub z: Vec<f64>,
    /// Cells to shade, in the layout of `z`; empty for none.
    pub shaded: Vec<bool>,
}

/// A vertical line at `x`; marks with the same label share one legend entry, unlabelled marks
/// have none.
#[derive(Clone, Debug, PartialEq)]
pub struct Mark {
    /// Where, in x-axis units.
    pub x: f64,
    /// Legend entry.
    pub label: Option<String>,
}

/// Series colours: blue, red, amber (the paper's Fig. 2b order: theory, simulated, measured),
/// then green, purple, teal, brown, grey.
const PALETTE: [RGBColor; 8] = [
    RGBColor(20, 80, 200),
    RGBColor(215, 40, 40),
    RGBColor(235, 160, 0),
    RGBColor(40, 160, 70),
    RGBColor(150, 60, 170),
    RGBColor(0, 150, 160),
    RGBColor(140, 80, 30),
    RGBColor(90, 90, 90),
];

/// Writes lines `series` (at least one point in all), with vertical `marks`, shaded regions
/// where a series' points are flagged, and with `mark_best` a dot at each line's maximum (see
/// [`peak`]; its x and y in the legend). SVG or PNG by the file's extension; errors name `flag`.
pub fn lines_plot(
    flag: &str,
    path: &Path,
    labels: &Labels,
    series: &[Series],
    marks: &[Mark],
    mark_best: bool,
) -> Result<()> {
    if series.iter().all(|s| s.points.is_empty()) {
        bail!("{flag} {}: nothing to plot (no points)", path.display());
    }
    render_fine!(flag, path, |root, k| draw_lines(root, k, labels, series, marks, mark_best))
}

/// Writes a heatmap of `grid` with a colour bar, the ridge (for each x the y of the largest
/// value, see [`peak`]; a white line), vertical `marks` (dashed red) and shaded cells. SVG or PNG
/// by the file's extension; errors name `flag`.
pub fn heatmap_plot(flag: &str, path: &Path, labels: &Labels, grid: &Grid, marks: &[Mark]) -> Result<()> {
    if grid.xs.is_empty() || grid.ys.is_empty() || grid.z.len() != grid.xs.len() * grid.ys.len() {
        bail!("{flag} {}: the heatmap grid is empty or incomplete", path.display());
    }
    render_fine!(flag, path, |root, k| draw_heatmap(root, k, labels, grid, marks))
}

/// The maximum of sampled `(x, y)` (increasing x): the largest sample, refined by the vertex of
/// the parabola through it and its two neighbours when it is interior, so a ridge or optimum is
/// not quantized to the grid step. `None` for no points.
pub fn peak(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let j = (0..points.len()).max_by(|&a, &b| points[a].1.total_cmp(&points[b].1))?;
    if j == 0 || j + 1 == points.len() {
        return Some(points[j]);
    }
    let ((x0, y0), (x1, y1), (x2, y2)) = (points[j - 1], points[j], points[j + 1]);
    let (a, b) = (x1 - x0, x1 - x2);
    let den = a * (y1 - y2) - b * (y1 - y0);
    let num = a * a * (y1 - y2) - b * b * (y1 - y0);
    let x = (x1 - 0.5 * num / den).clamp(x0, x2);
    if !x.is_finite() || den == 0.0 {
        return Some(points[j]);
    }
    // the parabola at x, in Lagrange form
    let y = y0 * (x - x1) * (x - x2) / ((x0 - x1) * (x0 - x2))
        + y1 * (x - x0) * (x - x2) / ((x1 - x0) * (x1 - x2))
        + y2 * (x - x0) * (x - x1) / ((x2 - x0) * (x2 - x1));
    Some((x, y.max(y1)))
}

/// Cell edges around increasing centres: midpoints between neighbours, the outer cells clipped at
/// the first and last centre so the axis spans exactly the data (±0.5 around a single value).
fn cell_edges(centres: &[f64]) -> Vec<f64> {
    match centres {
        [] => vec![0.0, 1.0],
        [c] => vec![c - 0.5, c + 0.5],
        [first, .., last] => {
            let mut edges = vec![*first];
            edges.extend(centres.windows(2).map(|w| 0.5 * (w[0] + w[1])));
            edges.push(*last);
            edges
        }
    }
}

/// `(lo, hi)` of finite values, `(0, 1)` for none.
fn extent(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
    if lo.is_finite() && hi.is_finite() { (lo, hi) } else { (0.0, 1.0) }
}

/// Plain number for legends and ticks: up to four decimals, trailing zeros dropped.
pub fn number(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".to_owned() } else { s.to_owned() }
}

/// The embedded font at `size` pixels times the scale `k`.
fn font(size: i32, k: i32) -> (&'static str, i32) {
    ("sans-serif", size * k)
}

/// A stroke `width` pixels wide times the scale `k`.
fn px(width: i32, k: i32) -> u32 {
    (width * k).unsigned_abs()
}

/// Draws the vertical marks over `y_range` in `colour`, dashed and `width` pixels wide (times
/// the scale `k`); one legend entry per distinct label.
fn draw_marks<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    k: i32,
    marks: &[Mark],
    (y0, y1): (f64, f64),
    (colour, width): (RGBColor, i32),
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let style = colour.stroke_width(px(width, k));
    let mut labelled: Vec<&str> = Vec::new();
    for mark in marks {
        let series = chart
            .draw_series(DashedLineSeries::new(vec![(mark.x, y0), (mark.x, y1)], 8 * k, 5 * k, style))
            .map_err(|e| e.to_string())?;
        if let Some(label) = mark.label.as_deref().filter(|l| !labelled.contains(l)) {
            labelled.push(label);
            series.label(label).legend(move |(x, y)| {
                plotters::element::DashedPathElement::new(vec![(x, y), (x + 20 * k, y)], 5 * k, 3 * k, style)
            });
        }
    }
    Ok(())
}

fn draw_lines<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    k: i32,
    labels: &Labels,
    series: &[Series],
    marks: &[Mark],
    mark_best: bool,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1) = extent(all().map(|p| p.0));
    if x1 <= x0 {
        (x0, x1) = (x0 - 0.5, x1 + 0.5);
    }
    let (lo, hi) = extent(all().map(|p| p.1));
    let (lo, hi) = (lo.min(0.0), hi.max(0.0));
    let pad = 0.08 * (hi - lo).max(1e-12);
    let (y0, y1) = (if lo < 0.0 { lo - pad } else { 0.0 }, hi + pad);
    let mut chart = ChartBuilder::on(&root)
        .caption(labels.title, font(20, k))
        .margin(16 * k)
        .margin_right(28 * k)
        .x_label_area_size(48 * k)
        .y_label_area_size(64 * k)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .x_label_formatter(&|v| number(*v))
        .y_label_formatter(&|v| number(*v))
        .max_light_lines(1)
        .bold_line_style(RGBColor(205, 205, 205).stroke_width(px(1, k)))
        .light_line_style(RGBColor(240, 240, 240).stroke_width(px(1, k)))
        .axis_style(BLACK.stroke_width(px(1, k)))
        .set_all_tick_mark_size(5 * k)
        .label_style(font(14, k))
        .axis_desc_style(font(16, k))
        .draw()
        .map_err(|e| err(&e))?;
    // shading first, under everything: each series' flagged points, layered in translucent grey
    let grey = RGBColor(110, 110, 110);
    let mut shade_legend = !labels.shade.is_empty();
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
                rects.push(Rectangle::new([(edges[start], y0), (edges[i], y1)], grey.mix(0.12).filled()));
            } else {
                i += 1;
            }
        }
        let drawn = chart.draw_series(rects).map_err(|e| err(&e))?;
        if shade_legend {
            shade_legend = false;
            drawn.label(labels.shade).legend(move |(x, y)| {
                Rectangle::new([(x, y - 6 * k), (x + 20 * k, y + 6 * k)], grey.mix(0.3).filled())
            });
        }
    }
    draw_marks(&mut chart, k, marks, (y0, y1), (RGBColor(100, 100, 100), 1))?;
    for (i, s) in series.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let style = colour.stroke_width(px(3, k));
        let dashed = |j: usize| s.shaded.get(j).copied().unwrap_or(false);
        let best = peak(&s.points);
        let label = match best {
            Some((x, y)) if mark_best => {
                format!("{}: max {} at {} (parabola between grid points)", s.label, number(y), number(x))
            }
            _ => s.label.clone(),
        };
        // runs of segments, solid, or dashed where they end in a shaded point
        let mut runs: Vec<(bool, Vec<(f64, f64)>)> = Vec::new();
        for (j, w) in s.points.windows(2).enumerate() {
            match runs.last_mut() {
                Some((kind, run)) if *kind == dashed(j + 1) => run.push(w[1]),
                _ => runs.push((dashed(j + 1), vec![w[0], w[1]])),
            }
        }
        if runs.is_empty() {
            runs.push((false, s.points.clone()));
        }
        for (j, (kind, run)) in runs.into_iter().enumerate() {
            let drawn = if kind {
                let thin = colour.stroke_width(px(2, k));
                chart.draw_series(DashedLineSeries::new(run, 7 * k, 5 * k, thin)).map_err(|e| err(&e))?
            } else {
                chart.draw_series(LineSeries::new(run, style)).map_err(|e| err(&e))?
            };
            if j == 0 {
                let label = label.clone();
                drawn.label(label).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20 * k, y)], style));
            }
        }
        if let (Some(best), true) = (best, mark_best) {
            let (r, ring) = (5 * k, WHITE.stroke_width(px(1, k)));
            chart
                .draw_series([Circle::new(best, r, colour.filled()), Circle::new(best, r, ring)])
                .map_err(|e| err(&e))?;
        }
    }
    legend(&mut chart, k, 14)?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The series legend, top right, on a translucent white box, its text `size` pixels; pixel sizes
/// times the scale `k`.
fn legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    k: i32,
    size: i32,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .margin(10 * k)
        .legend_area_size(30 * k)
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(180, 180, 180).stroke_width(px(1, k)))
        .label_font(font(size, k))
        .draw()
        .map_err(|e| e.to_string())
}

/// Viridis-like colour for `t` in [0, 1] (five stops of matplotlib's viridis, linear between).
fn colour(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 5] = [(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + (f64::from(b) - f64::from(a)) * f).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

fn draw_heatmap<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    k: i32,
    labels: &Labels,
    grid: &Grid,
    marks: &[Mark],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (ex, ey) = (cell_edges(&grid.xs), cell_edges(&grid.ys));
    let ny = grid.ys.len();
    let (lo, hi) = extent(grid.z.iter().copied());
    let span = (hi - lo).max(1e-300);
    let (x0, x1, y0, y1) = (ex[0], ex[ex.len() - 1], ey[0], ey[ey.len() - 1]);
    let width = i32::try_from(root.dim_in_pixel().0).unwrap_or(i32::MAX);
    let (plot, bar) = root.split_horizontally(width - 120 * k);
    let mut chart = ChartBuilder::on(&plot)
        .caption(labels.title, font(20, k))
        .margin(16 * k)
        .x_label_area_size(48 * k)
        .y_label_area_size(64 * k)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .x_label_formatter(&|v| number(*v))
        .y_label_formatter(&|v| number(*v))
        .axis_style(BLACK.stroke_width(px(1, k)))
        .set_all_tick_mark_size(5 * k)
        .label_style(font(14, k))
        .axis_desc_style(font(16, k))
        .draw()
        .map_err(|e| err(&e))?;
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
        .map_err(|e| err(&e))?;
    let shaded = |i: usize, j: usize| grid.shaded.get(i * ny + j).copied().unwrap_or(false);
    if grid.shaded.iter().any(|&s| s) {
        let veil = WHITE.mix(0.55);
        let drawn = chart
            .draw_series(cells.filter(|&(i, j)| shaded(i, j)).map(|(i, j)| Rectangle::new(cell(i, j), veil.filled())))
            .map_err(|e| err(&e))?;
        if !labels.shade.is_empty() {
            drawn.label(labels.shade).legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + Rectangle::new([(0, -6 * k), (20 * k, 6 * k)], colour(0.3).filled())
                    + Rectangle::new([(0, -6 * k), (20 * k, 6 * k)], veil.filled())
            });
        }
    }
    draw_marks(&mut chart, k, marks, (y0, y1), (RGBColor(230, 30, 30), 2))?;
    // the ridge: for each x, the y with the largest value; white on a dark outline
    let ridge: Vec<(f64, f64)> = grid
        .z
        .chunks(ny)
        .zip(&grid.xs)
        .filter_map(|(column, &x)| {
            let samples: Vec<(f64, f64)> = grid.ys.iter().copied().zip(column.iter().copied()).collect();
            Some((x, peak(&samples)?.0))
        })
        .collect();
    let dark = RGBColor(30, 30, 30);
    let (outline, line) = (dark.stroke_width(px(4, k)), WHITE.stroke_width(px(2, k)));
    chart.draw_series(LineSeries::new(ridge.clone(), outline)).map_err(|e| err(&e))?;
    let drawn = chart.draw_series(LineSeries::new(ridge.clone(), line)).map_err(|e| err(&e))?;
    if !labels.ridge.is_empty() {
        drawn.label(labels.ridge).legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (20 * k, 0)], outline)
                + PathElement::new(vec![(0, 0), (20 * k, 0)], line)
        });
    }
    if ridge.len() <= 60 {
        let ring = dark.stroke_width(px(1, k));
        chart
            .draw_series(
                ridge.iter().flat_map(|&p| [Circle::new(p, 3 * k, WHITE.filled()), Circle::new(p, 3 * k, ring)]),
            )
            .map_err(|e| err(&e))?;
    }
    legend(&mut chart, k, 14)?;
    // colour bar, labelled on its right
    let mut scale = ChartBuilder::on(&bar)
        .margin_top(52 * k)
        .margin_bottom(64 * k)
        .margin_left(8 * k)
        .right_y_label_area_size(64 * k)
        .build_cartesian_2d(0.0..1.0, lo..hi + span * 1e-9)
        .map_err(|e| err(&e))?;
    scale
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(labels.z)
        .y_label_formatter(&|v| number(*v))
        .axis_style(BLACK.stroke_width(px(1, k)))
        .set_all_tick_mark_size(5 * k)
        .label_style(font(14, k))
        .axis_desc_style(font(16, k))
        .draw()
        .map_err(|e| err(&e))?;
    let steps = 100;
    scale
        .draw_series((0..steps).map(|i| {
            // each step reaches halfway into the next, drawn over it, so no seams show
            let a = lo + span * i as f64 / steps as f64;
            let b = lo + span * ((i + 1) as f64 + if i + 1 < steps { 0.5 } else { 0.0 }) / steps as f64;
            Rectangle::new([(0.0, a), (1.0, b)], colour(i as f64 / (steps - 1) as f64).filled())
        }))
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, title: &str, curve: &MtfCurve) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let x_max = curve.frequency_cyc_per_mm.last().copied().unwrap_or(1.0).max(1e-12);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..x_max, 0.0..1.05)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("spatial frequency (cycles/mm)")
        .y_desc(if curve.pixel_mtf { "MTF (lens × pixel)" } else { "MTF" })
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| err(&e))?;
    let xs = &curve.frequency_cyc_per_mm;
    let series = |ys: &[f64]| xs.iter().copied().zip(ys.iter().copied()).collect::<Vec<_>>();

    chart
        .draw_series(DashedLineSeries::new(series(&curve.diffraction_limited), 6, 4, BLACK.stroke_width(1)))
        .map_err(|e| err(&e))?
        .label(format!("diffraction limit at {:.1} nm", curve.mean_wavelength_nm))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    let palette = [RGBColor(230, 120, 20), RGBColor(40, 160, 70), RGBColor(170, 60, 170), RGBColor(200, 40, 40)];
    for (i, (wl, ys)) in curve.wavelengths_nm.iter().zip(&curve.monochromatic).enumerate() {
        let colour = palette[i % palette.len()];
        chart
            .draw_series(LineSeries::new(series(ys), colour.stroke_width(1)))
            .map_err(|e| err(&e))?
            .label(format!("{wl:.1} nm"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
    }
    if let (Some(r), Some(t)) = (&curve.mtf_tangential, &curve.mtf_sagittal) {
        for (ys, name, colour) in [
            (r, "tangential: along the field (x on axis)", RGBColor(90, 150, 240)),
            (t, "sagittal: across it (y on axis)", RGBColor(20, 40, 120)),
        ] {
            chart
                .draw_series(DashedLineSeries::new(series(ys), 8, 4, colour.stroke_width(2)))
                .map_err(|e| err(&e))?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        }
    }
    let blue = RGBColor(20, 80, 200);
    chart
        .draw_series(LineSeries::new(series(&curve.mtf), blue.stroke_width(3)))
        .map_err(|e| err(&e))?
        .label(match (curve.field_points.len(), curve.mtf_tangential.is_some()) {
            (0, false) => "polychromatic MTF".to_owned(),
            (0, true) => "polychromatic MTF (mean of both)".to_owned(),
            (n, _) => format!("polychromatic MTF, weighted mean of {n} field points"),
        })
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(3)));
    if curve.nyquist_cyc_per_mm < x_max * 0.999 {
        let n = curve.nyquist_cyc_per_mm;
        chart
            .draw_series(LineSeries::new(vec![(n, 0.0), (n, 1.05)], RGBColor(120, 120, 120).stroke_width(1)))
            .map_err(|e| err(&e))?
            .label(format!("Nyquist {n:.1} cycles/mm"))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(120, 120, 120)));
    }
    legend(&mut chart, 1, 12)?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_is_exact_for_a_parabola_and_a_sample_at_the_ends() {
        let parabola: Vec<(f64, f64)> = (0..8).map(|i| (f64::from(i), 5.0 - (f64::from(i) - 3.3).powi(2))).collect();
        let (x, y) = peak(&parabola).unwrap();
        assert!((x - 3.3).abs() < 1e-12 && (y - 5.0).abs() < 1e-12, "{x} {y}");
        // non-uniform spacing
        let uneven: Vec<(f64, f64)> = [1.0, 2.0, 4.5, 5.0].iter().map(|&x| (x, 1.0 - (x - 2.7_f64).powi(2))).collect();
        let (x, _) = peak(&uneven).unwrap();
        assert!((x - 2.7).abs() < 1e-12, "{x}");
        assert_eq!(peak(&[(1.0, 3.0), (2.0, 2.0), (3.0, 1.0)]), Some((1.0, 3.0)));
        assert_eq!(peak(&[(1.0, 3.0)]), Some((1.0, 3.0)));
        assert_eq!(peak(&[]), None);
        // a flat top between two samples: the vertex lies between them
        let (x, _) = peak(&[(1.0, 1.0), (2.0, 2.0), (3.0, 2.0), (4.0, 1.0)]).unwrap();
        assert!((2.0..=3.0).contains(&x), "{x}");
    }

    #[test]
    fn cells_span_exactly_the_data() {
        assert_eq!(cell_edges(&[1.0, 2.0, 4.0]), vec![1.0, 1.5, 3.0, 4.0]);
        assert_eq!(cell_edges(&[2.0]), vec![1.5, 2.5]);
        assert_eq!(number(2.50000000001), "2.5");
        assert_eq!(number(-0.00001), "0");
    }
}
