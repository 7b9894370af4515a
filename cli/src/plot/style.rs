//! What every chart shares: the layout (title, axes, legend below), the axes with their ticks
//! and labels, strokes, colours, legend swatches and curves, and the [`Plot`] trait each chart
//! implements.

use super::*;

/// Cell edges around increasing centres: midpoints between neighbours, the outer cells clipped at
/// the first and last centre so the axis spans exactly the data (±0.5 around a single value).
pub(super) fn cell_edges(centres: &[f64]) -> Vec<f64> {
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

/// Refuses an axis whose ends or span are not finite (values near the largest double, whose
/// padded range overflows): its ticks could not be placed (plotters looped for ever on them).
pub(super) fn drawable(axis: &str, (lo, hi): (f64, f64)) -> Result<(), String> {
    if lo.is_finite() && hi.is_finite() && (hi - lo).is_finite() {
        return Ok(());
    }
    Err(format!(
        "the {axis} axis would run from {lo:e} to {hi:e}, a span beyond the largest number (about 1.8e308); expected values whose range, with the axis' margin, is finite (below about 1e307)"
    ))
}

/// `(lo, hi)` of finite values, `(0, 1)` for none.
pub(super) fn extent(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
    if lo.is_finite() && hi.is_finite() { (lo, hi) } else { (0.0, 1.0) }
}

/// `v` to four significant digits, trailing zeros dropped: "10.57", "34.39", "0.001234".
pub(super) fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return number(v);
    }
    let decimals = (3 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { &s };
    if s == "-0" { "0".to_owned() } else { s.to_owned() }
}

/// How tick labels are written: fixed with this many decimals, or in scientific notation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum TickFormat {
    Fixed(usize),
    Scientific,
    /// A log10 axis: the tick `v` is written as the value `10^v`.
    Decades,
}

impl TickFormat {
    /// The fewest decimals that write every tick exactly (to a millionth of the step); scientific
    /// for ticks of more than eight decimals or of a million or more.
    pub(super) fn of(ticks: &[f64]) -> Self {
        let step = ticks.windows(2).map(|w| (w[1] - w[0]).abs()).fold(f64::INFINITY, f64::min);
        let step =
            if step.is_finite() && step > 0.0 { step } else { ticks.first().map_or(1.0, |t| t.abs().max(1e-300)) };
        if ticks.iter().any(|t| t.abs() >= 1e6) {
            return Self::Scientific;
        }
        (0..=8)
            .find(|&d| {
                let scale = 10f64.powi(d as i32);
                ticks.iter().all(|t| ((t * scale).round() / scale - t).abs() <= 1e-6 * step)
            })
            .map_or(Self::Scientific, Self::Fixed)
    }

    pub(super) fn write(self, v: f64) -> String {
        let s = match self {
            Self::Fixed(d) => format!("{v:.d$}"),
            Self::Scientific => format!("{v:.2e}"),
            Self::Decades => {
                let value = 10f64.powf(v.round());
                if (1e-4..1e6).contains(&value) { number(value) } else { format!("{value:.0e}") }
            }
        };
        match s.strip_prefix('-') {
            Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
            _ => s,
        }
    }
}

/// The tick values plotters draws on `lo..hi` for at most `n` labels.
pub(super) fn ticks((lo, hi): (f64, f64), n: usize) -> Vec<f64> {
    // plotters loops for ever on a span that is not finite (axes are checked by `drawable`)
    if !(hi - lo).is_finite() {
        return Vec::new();
    }
    RangedCoordf64::from(lo..hi).key_points(n)
}

/// Device pixels per point, the scale every size is drawn at.
#[derive(Clone, Copy, Debug)]
pub(super) struct Ctx {
    pub(super) k: f64,
}

impl Ctx {
    /// `pt` points in device pixels.
    pub(super) fn px(self, pt: f64) -> i32 {
        (pt * self.k).round() as i32
    }

    /// A stroke `pt` points wide, at least one pixel.
    pub(super) fn stroke(self, pt: f64) -> u32 {
        ((pt * self.k).round() as u32).max(1)
    }

    /// The embedded font at `pt` points.
    pub(super) fn font(self, pt: f64) -> FontDesc<'static> {
        ("sans-serif", pt * self.k * FONT_SCALE).into_font()
    }

    /// Width of `text` at `pt` points, device pixels.
    pub(super) fn text_width(self, pt: f64, text: &str) -> i32 {
        self.font(pt).box_size(text).map_or(0, |(w, _)| i32::try_from(w).unwrap_or(i32::MAX))
    }
}

/// How a curve is stroked: colour, width (points), dashes (on, off; points), and an optional
/// wider outline under it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Stroke {
    pub(super) colour: RGBColor,
    pub(super) width: f64,
    pub(super) dash: Option<(f64, f64)>,
    pub(super) halo: Option<(RGBColor, f64)>,
}

impl Stroke {
    pub(super) const fn solid(colour: RGBColor, width: f64) -> Self {
        Self { colour, width, dash: None, halo: None }
    }

    pub(super) const fn dashed(colour: RGBColor, width: f64, on: f64, off: f64) -> Self {
        Self { colour, width, dash: Some((on, off)), halo: None }
    }

    /// The same stroke, dashed: the shaded parts of a line.
    pub(super) const fn with_dashes(self) -> Self {
        Self { dash: Some((4.0, 2.5)), ..self }
    }
}

/// The picture beside a legend entry.
#[derive(Clone, Copy, Debug)]
pub(super) enum Swatch {
    /// A stretch of the line, with its stroke.
    Line(Stroke),
    /// A stretch of the line with a dot (fill colour) in its middle.
    Dot(Stroke, RGBColor),
    /// A hollow dot: a ring of this colour.
    Ring(RGBColor),
    /// A patch: `base` colour under a translucent `fill`, optionally with a line across.
    Patch { base: Option<RGBColor>, fill: (RGBColor, f64), line: Option<Stroke> },
}

/// One legend entry.
#[derive(Clone, Debug)]
pub(super) struct Entry {
    pub(super) label: String,
    pub(super) swatch: Swatch,
}

/// Axis, frame and text colour.
pub(super) const INK: RGBColor = RGBColor(0, 0, 0);
/// Grid lines.
pub(super) const GRID: RGBColor = RGBColor(222, 222, 222);
/// The lighter lines between decades on a log axis.
pub(super) const MINOR_GRID: RGBColor = RGBColor(238, 238, 238);
/// The legend box's edge.
pub(super) const LEGEND_EDGE: RGBColor = RGBColor(150, 150, 150);
/// Reference curves: the diffraction limit.
pub(super) const REFERENCE: Stroke = Stroke::dashed(RGBColor(0, 0, 0), 1.0, 4.0, 2.0);
/// Vertical reference lines (Nyquist, `--mark-x` on lines).
pub(super) const MARK: Stroke = Stroke::dashed(RGBColor(60, 60, 60), 0.9, 1.5, 1.5);
/// Vertical reference lines on heatmaps.
pub(super) const HEAT_MARK: Stroke = Stroke::dashed(RGBColor(230, 30, 30), 1.2, 4.0, 2.0);
/// The heatmap ridge: white on a dark outline.
pub(super) const RIDGE: Stroke =
    Stroke { colour: RGBColor(255, 255, 255), width: 1.0, dash: None, halo: Some((RGBColor(30, 30, 30), 2.2)) };
/// Shading of points or cells beyond validity: grey, translucent.
pub(super) const SHADE: (RGBColor, f64) = (RGBColor(110, 110, 110), 0.14);

/// Series colours: blue, red, amber (the paper's Fig. 2b order: theory, simulated, measured),
/// then green, purple, teal, brown, grey.
pub(super) const PALETTE: [RGBColor; 8] = [
    RGBColor(20, 80, 200),
    RGBColor(215, 40, 40),
    RGBColor(235, 160, 0),
    RGBColor(40, 160, 70),
    RGBColor(150, 60, 170),
    RGBColor(0, 150, 160),
    RGBColor(140, 80, 30),
    RGBColor(90, 90, 90),
];

pub(super) type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

pub(super) fn fail(e: &dyn std::fmt::Display) -> String {
    e.to_string()
}

/// A kind of plot: its title, its legend, and how it draws its axes and data.
pub(super) trait Plot {
    fn title(&self) -> &str;
    fn entries(&self) -> Vec<Entry>;
    /// Height of the axes block over the figure's width.
    fn aspect(&self) -> f64 {
        ASPECT
    }
    /// Draws the axes and the data into `area` (the figure less title and legend).
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static;
}

/// The figure's layout, device pixels: the title's lines, the heights of the title, axes and
/// legend blocks, and the legend's grid of entries.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    pub(super) width: i32,
    pub(super) title: Vec<String>,
    pub(super) title_h: i32,
    pub(super) axes_h: i32,
    pub(super) legend: Option<LegendLayout>,
}

#[derive(Clone, Debug)]
pub(super) struct LegendLayout {
    /// Each entry's lines of text (long labels are wrapped), column and first row.
    pub(super) placed: Vec<(Vec<String>, usize, usize)>,
    /// Width of each column.
    pub(super) columns: Vec<i32>,
    pub(super) box_w: i32,
    pub(super) box_h: i32,
}

/// Margin around the figure, points.
pub(super) const MARGIN_PT: f64 = 6.0;
/// Legend metrics, points: swatch length, swatch-to-text gap, column gap, row height, padding.
pub(super) const SWATCH_PT: f64 = 20.0;
pub(super) const SWATCH_GAP_PT: f64 = 5.0;
pub(super) const COLUMN_GAP_PT: f64 = 14.0;
pub(super) const ROW_PT: f64 = LEGEND_PT * 1.6;
pub(super) const PAD_PT: f64 = 5.0;

impl Layout {
    pub(super) fn new(ctx: Ctx, width: i32, title: &str, entries: &[Entry], aspect: f64) -> Self {
        let margin = ctx.px(MARGIN_PT);
        let title = wrap(ctx, TITLE_PT, title, width - 2 * margin);
        let title_h = if title.is_empty() { 0 } else { ctx.px(TITLE_PT * 1.3) * title.len() as i32 + ctx.px(4.0) };
        let axes_h = (f64::from(width) * aspect).round() as i32;
        let legend = (!entries.is_empty()).then(|| {
            let available = width - 2 * margin - 2 * ctx.px(PAD_PT);
            let swatch = ctx.px(SWATCH_PT) + ctx.px(SWATCH_GAP_PT);
            let lines: Vec<Vec<String>> = entries
                .iter()
                .map(|e| {
                    if ctx.text_width(LEGEND_PT, &e.label) <= available - swatch {
                        vec![e.label.clone()]
                    } else {
                        wrap(ctx, LEGEND_PT, &e.label, available - swatch)
                    }
                })
                .collect();
            let items: Vec<i32> = lines
                .iter()
                .map(|l| swatch + l.iter().map(|t| ctx.text_width(LEGEND_PT, t)).max().unwrap_or(0))
                .collect();
            // entries fill the columns top to bottom, left to right
            let per_column = |n: usize| items.len().div_ceil(n);
            let columns_of = |n: usize| -> Vec<i32> {
                items.chunks(per_column(n)).map(|c| c.iter().copied().max().unwrap_or(0)).collect()
            };
            let total =
                |columns: &[i32]| columns.iter().sum::<i32>() + ctx.px(COLUMN_GAP_PT) * (columns.len() as i32 - 1);
            let n = (1..=items.len()).rev().find(|&n| n == 1 || total(&columns_of(n)) <= available).unwrap_or(1);
            let (k, columns) = (per_column(n), columns_of(n));
            let mut placed = Vec::with_capacity(lines.len());
            let mut rows = 0;
            for (i, text) in lines.into_iter().enumerate() {
                let row = if i % k == 0 {
                    0
                } else {
                    placed.last().map_or(0, |(t, _, r): &(Vec<String>, usize, usize)| r + t.len())
                };
                rows = rows.max(row + text.len());
                placed.push((text, i / k, row));
            }
            LegendLayout {
                placed,
                box_w: total(&columns) + 2 * ctx.px(PAD_PT),
                box_h: rows as i32 * ctx.px(ROW_PT) + 2 * ctx.px(PAD_PT),
                columns,
            }
        });
        Self { width, title, title_h, axes_h, legend }
    }

    /// Height of the figure, device pixels.
    pub(super) fn height(&self, ctx: Ctx) -> i32 {
        let legend = self.legend.as_ref().map_or(0, |l| l.box_h + ctx.px(MARGIN_PT));
        ctx.px(MARGIN_PT) + self.title_h + self.axes_h + legend + ctx.px(MARGIN_PT)
    }
}

/// `text` broken into lines at spaces so each is at most `width` pixels wide at `pt` points (a
/// single word wider than that is a line of its own).
pub(super) fn wrap(ctx: Ctx, pt: f64, text: &str, width: i32) -> Vec<String> {
    wrap_words(text, |line| ctx.text_width(pt, line) <= width)
}

/// `text` broken into lines at spaces, each as long as `fits` allows (a single word that does
/// not fit is a line of its own).
pub(crate) fn wrap_words(text: &str, fits: impl Fn(&str) -> bool) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let longer = if line.is_empty() { word.to_owned() } else { format!("{line} {word}") };
        if line.is_empty() || fits(&longer) {
            line = longer;
        } else {
            lines.push(std::mem::replace(&mut line, word.to_owned()));
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// Draws the whole figure: white ground, title, the plot's axes and data, and the legend below.
pub(super) fn compose<DB: DrawingBackend, P: Plot>(
    root: &DrawingArea<DB, Shift>,
    ctx: Ctx,
    layout: &Layout,
    plot: &P,
    entries: &[Entry],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let margin = ctx.px(MARGIN_PT);
    let style = ctx.font(TITLE_PT).color(&INK).pos(Pos::new(HPos::Center, VPos::Top));
    for (i, line) in layout.title.iter().enumerate() {
        let y = margin + ctx.px(TITLE_PT * 1.3) * i as i32;
        root.draw(&Text::new(line.clone(), (layout.width / 2, y), style.clone())).map_err(|e| fail(&e))?;
    }
    let (_, rest) = root.split_vertically(margin + layout.title_h);
    let (axes, below) = rest.split_vertically(layout.axes_h);
    plot.draw(&axes, ctx)?;
    if let Some(legend) = &layout.legend {
        draw_legend(&below, ctx, layout.width, legend, entries)?;
    }
    root.present().map_err(|e| fail(&e))
}

/// The legend: a white box with a grey edge, centred below the axes, its entries row by row.
pub(super) fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    ctx: Ctx,
    width: i32,
    legend: &LegendLayout,
    entries: &[Entry],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let (x0, y0) = ((width - legend.box_w) / 2, ctx.px(MARGIN_PT));
    let (x1, y1) = (x0 + legend.box_w, y0 + legend.box_h);
    area.draw(&Rectangle::new([(x0, y0), (x1, y1)], WHITE.filled())).map_err(|e| fail(&e))?;
    let edge = LEGEND_EDGE.stroke_width(ctx.stroke(0.5));
    area.draw(&PathElement::new(outline((x0, y0), (x1, y1)), edge)).map_err(|e| fail(&e))?;
    let style = ctx.font(LEGEND_PT).color(&INK).pos(Pos::new(HPos::Left, VPos::Center));
    let row_y = |row: usize| y0 + ctx.px(PAD_PT) + row as i32 * ctx.px(ROW_PT) + ctx.px(ROW_PT) / 2;
    for (entry, (lines, column, row)) in entries.iter().zip(&legend.placed) {
        let x = x0
            + ctx.px(PAD_PT)
            + legend.columns[..*column].iter().sum::<i32>()
            + ctx.px(COLUMN_GAP_PT) * *column as i32;
        draw_swatch(area, ctx, (x, row_y(*row)), &entry.swatch)?;
        for (i, line) in lines.iter().enumerate() {
            let text = (x + ctx.px(SWATCH_PT) + ctx.px(SWATCH_GAP_PT), row_y(row + i));
            area.draw(&Text::new(line.clone(), text, style.clone())).map_err(|e| fail(&e))?;
        }
    }
    Ok(())
}

/// The closed outline of the rectangle with corners `a` and `b`, a stroke's path: its first side
/// drawn twice so the first corner is joined like the others (SVG and plotters' rectangles
/// ignore the stroke width).
pub(super) fn outline<T: Copy>(a: (T, T), b: (T, T)) -> Vec<(T, T)> {
    vec![a, (b.0, a.1), b, (a.0, b.1), a, (b.0, a.1)]
}

/// A segment from `from` to `to` (device pixels) with stroke `s`: the halo, then the line,
/// dashed with its own pattern.
pub(super) fn draw_segment<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    ctx: Ctx,
    from: (i32, i32),
    to: (i32, i32),
    s: Stroke,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    if let Some((colour, width)) = s.halo {
        area.draw(&PathElement::new(vec![from, to], colour.stroke_width(ctx.stroke(width)))).map_err(|e| fail(&e))?;
    }
    let style = s.colour.stroke_width(ctx.stroke(s.width));
    match s.dash {
        None => area.draw(&PathElement::new(vec![from, to], style)),
        Some((on, off)) => area.draw(&DashedPathElement::new(vec![from, to], ctx.px(on), ctx.px(off), style)),
    }
    .map_err(|e| fail(&e))
}

/// The swatch of a legend entry, its left end at `(x, y)`.
pub(super) fn draw_swatch<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    ctx: Ctx,
    (x, y): (i32, i32),
    swatch: &Swatch,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let end = (x + ctx.px(SWATCH_PT), y);
    match *swatch {
        Swatch::Line(s) => draw_segment(area, ctx, (x, y), end, s),
        Swatch::Dot(s, fill) => {
            draw_segment(area, ctx, (x, y), end, s)?;
            let (centre, r) = ((x + ctx.px(SWATCH_PT) / 2, y), ctx.px(2.5).unsigned_abs());
            area.draw(&Circle::new(centre, r, fill.filled())).map_err(|e| fail(&e))?;
            area.draw(&Circle::new(centre, r, WHITE.stroke_width(ctx.stroke(0.5)))).map_err(|e| fail(&e))
        }
        Swatch::Ring(colour) => {
            let (centre, r) = ((x + ctx.px(SWATCH_PT) / 2, y), ctx.px(2.6).unsigned_abs());
            area.draw(&Circle::new(centre, r, colour.stroke_width(ctx.stroke(1.0)))).map_err(|e| fail(&e))
        }
        Swatch::Patch { base, fill: (colour, alpha), line } => {
            let h = ctx.px(LEGEND_PT * 0.6);
            let corners = [(x, y - h), (x + ctx.px(SWATCH_PT), y + h)];
            if let Some(base) = base {
                area.draw(&Rectangle::new(corners, base.filled())).map_err(|e| fail(&e))?;
            }
            area.draw(&Rectangle::new(corners, colour.mix(alpha).filled())).map_err(|e| fail(&e))?;
            match line {
                Some(s) => draw_segment(area, ctx, (x, y), end, s),
                None => Ok(()),
            }
        }
    }
}

/// A curve in data coordinates with stroke `s`.
pub(super) fn draw_curve<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    ctx: Ctx,
    points: &[(f64, f64)],
    s: Stroke,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    if let Some((colour, width)) = s.halo {
        chart
            .draw_series(LineSeries::new(points.iter().copied(), colour.stroke_width(ctx.stroke(width))))
            .map_err(|e| fail(&e))?;
    }
    let style = s.colour.stroke_width(ctx.stroke(s.width));
    match s.dash {
        None => chart.draw_series(LineSeries::new(points.iter().copied(), style)).map(|_| ()),
        Some((on, off)) => {
            chart.draw_series(DashedLineSeries::new(points.iter().copied(), ctx.px(on), ctx.px(off), style)).map(|_| ())
        }
    }
    .map_err(|e| fail(&e))
}

/// The axes of one chart: ranges, descriptions, and the room they need, device pixels.
pub(super) struct Axes<'a> {
    pub(super) x: (f64, f64),
    pub(super) y: (f64, f64),
    pub(super) x_desc: &'a str,
    pub(super) y_desc: &'a str,
    pub(super) grid: bool,
    /// y holds log10 of the values: ticks at whole decades, written as the values
    pub(super) y_log: bool,
    /// x holds log10 of the values, as `y_log`
    pub(super) x_log: bool,
}

/// Space around the plotting area of a chart, device pixels.
#[derive(Clone, Copy, Debug)]
pub(super) struct Margins {
    pub(super) top: i32,
    pub(super) bottom: i32,
    pub(super) left: i32,
    pub(super) right: i32,
    pub(super) x_labels: i32,
    pub(super) y_labels: i32,
}

/// How many tick labels fit along `length` pixels when each takes `each` points.
pub(super) fn tick_count(ctx: Ctx, length: i32, each: f64) -> usize {
    usize::try_from(length / ctx.px(each).max(1)).unwrap_or(0).clamp(3, 12)
}

impl Axes<'_> {
    /// Tick counts and formats for a plotting area about `(w, h)` pixels.
    pub(super) fn ticks(&self, ctx: Ctx, (w, h): (i32, i32)) -> ((usize, TickFormat), (usize, TickFormat)) {
        // a log axis: one tick per whole decade, as many labels as decades, so the nice step is 1
        let decades = |(lo, hi): (f64, f64)| ((hi.floor() - lo.ceil()).max(0.0) as usize + 1).max(2);
        let x = if self.x_log {
            (decades(self.x), TickFormat::Decades)
        } else {
            let nx = tick_count(ctx, w, TICK_PT * 4.0);
            (nx, TickFormat::of(&ticks(self.x, nx)))
        };
        if self.y_log {
            return (x, (decades(self.y), TickFormat::Decades));
        }
        let ny = tick_count(ctx, h, TICK_PT * 2.5);
        (x, (ny, TickFormat::of(&ticks(self.y, ny))))
    }

    pub(super) fn margins(&self, ctx: Ctx, (w, h): (i32, i32), right_extra: i32) -> Margins {
        let ((nx, fx), (ny, fy)) = self.ticks(ctx, (w, h));
        let y_tick_w = ticks(self.y, ny).iter().map(|&v| ctx.text_width(TICK_PT, &fy.write(v))).max().unwrap_or(0);
        let last_x = ticks(self.x, nx).last().map_or(0, |&v| ctx.text_width(TICK_PT, &fx.write(v)));
        let mark = ctx.px(3.0) + ctx.px(2.0);
        Margins {
            top: ctx.px(TICK_PT * 0.8),
            bottom: ctx.px(2.0),
            left: ctx.px(MARGIN_PT),
            right: (last_x / 2 + ctx.px(2.0)).max(ctx.px(MARGIN_PT)) + right_extra,
            x_labels: mark + ctx.px(TICK_PT * 1.3) + ctx.px(DESC_PT * 1.5),
            y_labels: mark + y_tick_w + ctx.px(3.0) + ctx.px(DESC_PT * 1.4),
        }
    }

    /// Builds the chart on `area` with its mesh, axis labels and ticks; `right_extra` pixels are
    /// kept free on the right (a colour bar).
    pub(super) fn build<'a, DB: DrawingBackend>(
        &self,
        area: &'a DrawingArea<DB, Shift>,
        ctx: Ctx,
        right_extra: i32,
    ) -> Result<(Chart<'a, DB>, Margins), String>
    where
        DB::ErrorType: 'static,
    {
        drawable("x", self.x)?;
        drawable("y", self.y)?;
        let (w, h) = area.dim_in_pixel();
        let (w, h) = (i32::try_from(w).unwrap_or(i32::MAX), i32::try_from(h).unwrap_or(i32::MAX));
        let m0 = self.margins(ctx, (w, h), right_extra);
        let plot = (w - m0.left - m0.right - m0.y_labels, h - m0.top - m0.bottom - m0.x_labels);
        let m = self.margins(ctx, plot, right_extra);
        let ((nx, fx), (ny, fy)) = self.ticks(ctx, plot);
        let mut chart = ChartBuilder::on(area)
            .margin_top(m.top)
            .margin_bottom(m.bottom)
            .margin_left(m.left)
            .margin_right(m.right)
            .x_label_area_size(m.x_labels)
            .y_label_area_size(m.y_labels)
            .build_cartesian_2d(self.x.0..self.x.1, self.y.0..self.y.1)
            .map_err(|e| fail(&e))?;
        let (x_format, y_format) = (|v: &f64| fx.write(*v), |v: &f64| fy.write(*v));
        let mut mesh = chart.configure_mesh();
        mesh.x_labels(nx)
            .y_labels(ny)
            .x_desc(self.x_desc)
            .y_desc(self.y_desc)
            .x_label_formatter(&x_format)
            .y_label_formatter(&y_format)
            .max_light_lines(0)
            .bold_line_style(GRID.stroke_width(ctx.stroke(0.4)))
            .axis_style(INK.stroke_width(ctx.stroke(0.6)))
            .set_all_tick_mark_size(ctx.px(3.0))
            .label_style(ctx.font(TICK_PT))
            .axis_desc_style(ctx.font(DESC_PT));
        if !self.grid {
            mesh.disable_mesh();
        }
        mesh.draw().map_err(|e| fail(&e))?;
        Ok((chart, m))
    }

    /// On a log axis with fewer than three labelled decades, labels (and tick marks) at 2 and
    /// 5 × 10^k too, so that a short axis is readable; `area` is the one the chart was built on.
    pub(super) fn label_between_decades<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        chart: &Chart<'_, DB>,
        ctx: Ctx,
    ) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let between = |(lo, hi): (f64, f64)| -> Vec<f64> {
            if hi.floor() - lo.ceil() + 1.0 >= 3.0 {
                return Vec::new();
            }
            ((lo.floor() as i32)..=(hi.ceil() as i32))
                .flat_map(|d| [2f64, 5.0].map(|m| f64::from(d) + m.log10()))
                .filter(|&v| v > lo && v < hi)
                .collect()
        };
        let (bx, by) = area.get_base_pixel();
        let (mark, gap, ink) = (ctx.px(3.0), ctx.px(3.0), INK.stroke_width(ctx.stroke(0.6)));
        let label = |v: f64| number(10f64.powf(v));
        if self.y_log {
            let style = ctx.font(TICK_PT).color(&INK).pos(Pos::new(HPos::Right, VPos::Center));
            for v in between(self.y) {
                let (px, py) = chart.backend_coord(&(self.x.0, v));
                let (x, y) = (px - bx, py - by);
                area.draw(&PathElement::new(vec![(x - mark, y), (x, y)], ink)).map_err(|e| fail(&e))?;
                area.draw(&Text::new(label(v), (x - mark - gap, y), style.clone())).map_err(|e| fail(&e))?;
            }
        }
        if self.x_log {
            let style = ctx.font(TICK_PT).color(&INK).pos(Pos::new(HPos::Center, VPos::Top));
            for v in between(self.x) {
                let (px, py) = chart.backend_coord(&(v, self.y.0));
                let (x, y) = (px - bx, py - by);
                area.draw(&PathElement::new(vec![(x, y), (x, y + mark)], ink)).map_err(|e| fail(&e))?;
                area.draw(&Text::new(label(v), (x, y + mark + gap), style.clone())).map_err(|e| fail(&e))?;
            }
        }
        Ok(())
    }

    /// The frame around the plotting area, drawn over the data's edges.
    pub(super) fn frame<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let path = outline((self.x.0, self.y.0), (self.x.1, self.y.1));
        chart.draw_series([PathElement::new(path, INK.stroke_width(ctx.stroke(0.6)))]).map(|_| ()).map_err(|e| fail(&e))
    }
}
