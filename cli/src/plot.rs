//! Plots, SVG or PNG, drawn by plotters' pure-Rust backends: MTF curves, sweeps, and the
//! general line overlays and heatmaps of `asnr plot`. PNG text is rasterized with DejaVu Sans
//! embedded in the binary (`assets/`, Bitstream Vera licence), so no system font or fontconfig is
//! needed.
//!
//! Layout: the title (wrapped to the width), the axes with human labels and units taken from the
//! dotted keys ([`axis_label`]), and the legend in a box below the axes, never over the data.
//! Sizes are in points (1/72 inch) at the figure's resolution ([`Figure`]): a 3.5-inch figure at
//! 300 dpi has 8 pt tick labels and 9 pt axis labels. Reference curves (diffraction limit,
//! Nyquist, `--mark-x` lines) are dark and dashed and drawn last, on top of the data; each legend
//! swatch is drawn with its line's own stroke, dashes included. PNGs are rendered at two or three
//! times their size and box-filtered down, which anti-aliases lines, and carry their resolution
//! in a pHYs chunk; SVGs are drawn at twice their shown size so plotters' whole-pixel coordinates
//! do not make curves visibly stepped.

use std::path::Path;
use std::sync::Once;

use anyhow::{Result, anyhow, bail};
use metric::MtfCurve;

use crate::optimize::Range;
use crate::sweep::Point;
use plotters::coord::Shift;
use plotters::coord::ranged1d::Ranged;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Registers the embedded font (both backends measure text with it; PNG also rasterizes it).
pub(crate) fn register_font() {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // the font is a valid TrueType file compiled into the binary
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Default figure width, pixels.
pub const DEFAULT_WIDTH: u32 = 900;
/// Without `--dpi`, a figure is this many inches wide (900 px: 150 dpi).
const DEFAULT_INCHES: f64 = 6.0;
/// Accepted `--width`, pixels.
const WIDTHS: std::ops::RangeInclusive<u32> = 300..=4000;
/// Accepted `--dpi`.
const DPIS: std::ops::RangeInclusive<f64> = 30.0..=2400.0;
/// Accepted physical widths, `--width / --dpi`, inches: narrower leaves no room for the text.
const INCHES: std::ops::RangeInclusive<f64> = 2.0..=40.0;
/// Height of the axes block (plot, ticks and axis labels) over the width; the title and the
/// legend add to it.
const ASPECT: f64 = 0.56;

/// Title, axis-label, tick-label and legend text sizes, points.
const TITLE_PT: f64 = 10.0;
const DESC_PT: f64 = 9.0;
const TICK_PT: f64 = 8.0;
const LEGEND_PT: f64 = 8.0;
/// A plotters font size over the em size it draws in SVG (plotters writes `font-size = size / 1.24`).
const FONT_SCALE: f64 = 1.24;

/// SVGs are drawn at this many times their shown size (see the module docs).
const SVG_FINE: u32 = 2;
/// Largest supersampled PNG, pixels (3 bytes each).
const MAX_SUPERSAMPLED: u64 = 48_000_000;

/// Size and resolution of a plot: the width in pixels and the dots per inch that set the size
/// of text and lines (sizes are in points); the height follows from the width and the legend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Figure {
    width: u32,
    dpi: f64,
}

impl Default for Figure {
    fn default() -> Self {
        Self { width: DEFAULT_WIDTH, dpi: f64::from(DEFAULT_WIDTH) / DEFAULT_INCHES }
    }
}

impl Figure {
    /// The figure of `--width PX` and `--dpi N` (defaults: 900 px, a 6-inch figure).
    pub fn new(width: Option<u32>, dpi: Option<f64>) -> Result<Self> {
        let width = width.unwrap_or(DEFAULT_WIDTH);
        if !WIDTHS.contains(&width) {
            bail!("--width {width}: expected a whole number of pixels from {} to {}", WIDTHS.start(), WIDTHS.end());
        }
        let Some(dpi) = dpi else {
            return Ok(Self { width, dpi: f64::from(width) / DEFAULT_INCHES });
        };
        if !(dpi.is_finite() && DPIS.contains(&dpi)) {
            bail!("--dpi {dpi}: expected dots per inch from {} to {}", DPIS.start(), DPIS.end());
        }
        let inches = f64::from(width) / dpi;
        if !INCHES.contains(&inches) {
            bail!(
                "--dpi {dpi} with --width {width}: the figure would be {inches:.2} inches wide; expected --width / \
                 --dpi from {} to {} inches (e.g. --width 1050 --dpi 300 for a 3.5-inch column)",
                INCHES.start(),
                INCHES.end()
            );
        }
        Ok(Self { width, dpi })
    }

    /// Pixels per point (1/72 inch).
    fn px_per_pt(&self) -> f64 {
        self.dpi / 72.0
    }
}

/// Human name and unit of a scene key or result column: from a table of known keys, otherwise
/// the last segment of the dotted key with a unit suffix (`_nm`, `_um`, `_mm`, `_ms`, `_deg`,
/// `_k`, `_e`, `_cyc_per_mm`) taken off as the unit and underscores read as spaces.
pub fn quantity(key: &str) -> (String, Option<&'static str>) {
    const KNOWN: &[(&str, &str, Option<&str>)] = &[
        ("spectrum.range_nm", "spectral range", Some("nm")),
        ("spectrum.center_nm", "centre wavelength", Some("nm")),
        ("spectrum.peak", "filter peak transmission", None),
        ("lens.f_number", "F-number", None),
        ("lens.focal_length_mm", "focal length", Some("mm")),
        ("lens.design_wavelength_nm", "design wavelength", Some("nm")),
        ("lens.efficiency", "lens efficiency τ1", None),
        ("lens.transmission", "lens transmission", None),
        ("lens.spherical_um", "spherical aberration", Some("µm")),
        ("lens.field_curvature_um", "field curvature", Some("µm")),
        ("camera.pixel_pitch_um", "pixel pitch", Some("µm")),
        ("camera.quantum_efficiency", "quantum efficiency", None),
        ("camera.read_noise_e", "read noise", Some("e⁻")),
        ("camera.full_well_e", "full well", Some("e⁻")),
        ("camera.gain_dn_per_e", "gain", Some("DN/e⁻")),
        ("camera.adc_bits", "ADC bits", None),
        ("exposure.time_ms", "exposure time", Some("ms")),
        ("field.x_deg", "field angle x", Some("°")),
        ("field.y_deg", "field angle y", Some("°")),
        ("source.temperature_k", "source temperature", Some("K")),
        ("source.radiance_w_m2_sr_nm", "radiance", Some("W m⁻² sr⁻¹ nm⁻¹")),
        ("options.fraunhofer_threshold_mm", "Fraunhofer threshold", Some("mm")),
        ("asnr", "ASNR", None),
        ("mean_mtf", "mean MTF", None),
        ("snr0", "SNR0", None),
        ("photoelectrons", "photoelectrons per pixel", None),
        ("fraunhofer_valid", "Fraunhofer approximation valid", None),
        ("frequency_cyc_per_mm", "spatial frequency", Some("cycles/mm")),
        ("mtf", "MTF", None),
        ("diffraction_limited", "diffraction-limited MTF", None),
    ];
    const SUFFIXES: &[(&str, &str)] = &[
        ("_cyc_per_mm", "cycles/mm"),
        ("_nm", "nm"),
        ("_um", "µm"),
        ("_mm", "mm"),
        ("_ms", "ms"),
        ("_deg", "°"),
        ("_k", "K"),
        ("_e", "e⁻"),
    ];
    let key = key.trim();
    if let Some(&(_, name, unit)) = KNOWN.iter().find(|k| k.0 == key) {
        return (name.to_owned(), unit);
    }
    let last = key.rsplit('.').next().filter(|s| !s.is_empty()).unwrap_or(key);
    for &(suffix, unit) in SUFFIXES {
        if let Some(stem) = last.strip_suffix(suffix).filter(|s| !s.is_empty()) {
            return (stem.replace('_', " "), Some(unit));
        }
    }
    let name = last.replace('_', " ").trim().to_owned();
    (if name.is_empty() { key.to_owned() } else { name }, None)
}

/// The field point a scene's curves are computed at, for a plot's title: "on axis", "field
/// (5°, 0°)", or "3 field points (weighted)" for a scene's `[[fields]]`.
pub fn field_label(scene: &metric::Scene) -> String {
    let fields = scene.fields();
    if fields.len() > 1 {
        return format!("{} field points (weighted)", fields.len());
    }
    let field = fields.first().map_or(scene.field(), |f| f.0);
    if field.x_rad == 0.0 && field.y_rad == 0.0 {
        "on axis".to_owned()
    } else {
        format!(
            "field ({}°, {}°)",
            optics::round_for_display(field.x_rad.to_degrees()),
            optics::round_for_display(field.y_rad.to_degrees())
        )
    }
}

/// The axis label of a scene key or result column: its human name with the unit in parentheses,
/// e.g. `spectrum.range_nm` → "spectral range (nm)" (see [`quantity`]).
/// The title of a sweep's plot: what was swept, over which range, and the lens unless a lens key
/// is swept ("ASNR over spectral range 10–50 nm and exposure time 1–2 ms: chromatic metalens
/// F/2.5 …"); not the scene's title, whose band or F-number the sweep replaces.
pub fn sweep_title(ranges: &[Range], lens: &str, field: &str) -> String {
    let swept: Vec<String> = ranges
        .iter()
        .map(|r| {
            let (name, unit) = quantity(&r.key);
            format!("{name} {}–{}{}", number(r.lo), number(r.hi), unit.map_or(String::new(), |u| format!(" {u}")))
        })
        .collect();
    let title = format!("ASNR over {}", swept.join(" and "));
    let title = if ranges.iter().any(|r| r.key.starts_with("lens.")) { title } else { format!("{title}: {lens}") };
    // the field point, unless it is swept
    if ranges.iter().any(|r| r.key.starts_with("field.")) { title } else { format!("{title}, {field}") }
}

/// The axis label of a scene key: its name and unit, "spectral range (nm)".
pub fn axis_label(key: &str) -> String {
    match quantity(key) {
        (name, Some(unit)) => format!("{name} ({unit})"),
        (name, None) => name,
    }
}

/// Writes the MTF curve as a line chart, SVG or PNG by the file's extension: the polychromatic
/// MTF, the off-axis directional MTFs, the monochromatic curves, and on top the diffraction limit
/// and the Nyquist frequency (when the axis extends past it). An empty `title` is none.
pub fn mtf_plot(path: &Path, figure: &Figure, title: &str, curve: &MtfCurve) -> Result<()> {
    render("--plot", path, figure, &MtfPlot { title, curve })
}

/// Writes a sweep's ASNR: a line against the key for one swept key, a heatmap with the ridge of
/// the optimum (the best second key for each value of the first) for two. An empty `title` is
/// none.
pub fn sweep_plot(path: &Path, figure: &Figure, title: &str, ranges: &[Range], points: &[Point]) -> Result<()> {
    match ranges {
        [range] => {
            let series = Series {
                label: "ASNR".to_owned(),
                points: points.iter().map(|p| (p.values[0], p.asnr)).collect(),
                shaded: Vec::new(),
                best: None,
            };
            let x = axis_label(&range.key);
            let unit = quantity(&range.key).1.unwrap_or_default();
            let labels = Labels { title, x: &x, y: "ASNR", x_unit: unit, ..Labels::default() };
            lines_plot("--plot", path, figure, &labels, &[series], &[], true)
        }
        [first, second] => {
            let grid = Grid {
                xs: crate::sweep::axis(first),
                ys: crate::sweep::axis(second),
                z: points.iter().map(|p| p.asnr).collect(),
                shaded: Vec::new(),
            };
            let (x, y) = (axis_label(&first.key), axis_label(&second.key));
            let ridge = format!("best {} for each {}", quantity(&second.key).0, quantity(&first.key).0);
            let labels = Labels { title, x: &x, y: &y, z: "ASNR", ridge: &ridge, ..Labels::default() };
            heatmap_plot("--plot", path, figure, &labels, &grid, &[])
        }
        _ => bail!("--plot: a sweep over {} keys; plots take one key (a line) or two (a heatmap)", ranges.len()),
    }
}

/// The texts of a plot: title, axis descriptions, and the legend entries of the heatmap ridge and
/// of shaded regions (used only when something is shaded).
#[derive(Clone, Copy, Debug, Default)]
pub struct Labels<'a> {
    /// Caption above the chart; empty for none.
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
    /// Unit of x for the legend's maxima ("max 10.57 at 34.39 nm"); empty for none.
    pub x_unit: &'a str,
    /// Line plots: a logarithmic y axis (decades labelled, 2–9 × 10^k as light grid lines), for
    /// values spanning orders of magnitude; non-positive values are left out.
    pub log_y: bool,
    /// Line plots: a logarithmic x axis, as `log_y`.
    pub log_x: bool,
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
    /// The maximum as the caller found it (`(x, y)` and how, for the legend), marked instead of
    /// the parabola through the largest sample ([`peak`]); `None`: that parabola.
    pub best: Option<((f64, f64), String)>,
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

/// Refuses an axis whose ends or span are not finite (values near the largest double, whose
/// padded range overflows): its ticks could not be placed (plotters looped for ever on them).
fn drawable(axis: &str, (lo, hi): (f64, f64)) -> Result<(), String> {
    if lo.is_finite() && hi.is_finite() && (hi - lo).is_finite() {
        return Ok(());
    }
    Err(format!(
        "the {axis} axis would run from {lo:e} to {hi:e}, a span beyond the largest number (about 1.8e308); expected values whose range, with the axis' margin, is finite (below about 1e307)"
    ))
}

/// `(lo, hi)` of finite values, `(0, 1)` for none.
fn extent(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
    if lo.is_finite() && hi.is_finite() { (lo, hi) } else { (0.0, 1.0) }
}

/// Plain number for legends: up to four decimals, trailing zeros dropped.
pub use report::number;

/// `v` to four significant digits, trailing zeros dropped: "10.57", "34.39", "0.001234".
fn significant(v: f64) -> String {
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
enum TickFormat {
    Fixed(usize),
    Scientific,
    /// A log10 axis: the tick `v` is written as the value `10^v`.
    Decades,
}

impl TickFormat {
    /// The fewest decimals that write every tick exactly (to a millionth of the step); scientific
    /// for ticks of more than eight decimals or of a million or more.
    fn of(ticks: &[f64]) -> Self {
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

    fn write(self, v: f64) -> String {
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
fn ticks((lo, hi): (f64, f64), n: usize) -> Vec<f64> {
    // plotters loops for ever on a span that is not finite (axes are checked by `drawable`)
    if !(hi - lo).is_finite() {
        return Vec::new();
    }
    RangedCoordf64::from(lo..hi).key_points(n)
}

/// Device pixels per point, the scale every size is drawn at.
#[derive(Clone, Copy, Debug)]
struct Ctx {
    k: f64,
}

impl Ctx {
    /// `pt` points in device pixels.
    fn px(self, pt: f64) -> i32 {
        (pt * self.k).round() as i32
    }

    /// A stroke `pt` points wide, at least one pixel.
    fn stroke(self, pt: f64) -> u32 {
        ((pt * self.k).round() as u32).max(1)
    }

    /// The embedded font at `pt` points.
    fn font(self, pt: f64) -> FontDesc<'static> {
        ("sans-serif", pt * self.k * FONT_SCALE).into_font()
    }

    /// Width of `text` at `pt` points, device pixels.
    fn text_width(self, pt: f64, text: &str) -> i32 {
        self.font(pt).box_size(text).map_or(0, |(w, _)| i32::try_from(w).unwrap_or(i32::MAX))
    }
}

/// How a curve is stroked: colour, width (points), dashes (on, off; points), and an optional
/// wider outline under it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Stroke {
    colour: RGBColor,
    width: f64,
    dash: Option<(f64, f64)>,
    halo: Option<(RGBColor, f64)>,
}

impl Stroke {
    const fn solid(colour: RGBColor, width: f64) -> Self {
        Self { colour, width, dash: None, halo: None }
    }

    const fn dashed(colour: RGBColor, width: f64, on: f64, off: f64) -> Self {
        Self { colour, width, dash: Some((on, off)), halo: None }
    }

    /// The same stroke, dashed: the shaded parts of a line.
    const fn with_dashes(self) -> Self {
        Self { dash: Some((4.0, 2.5)), ..self }
    }
}

/// The picture beside a legend entry.
#[derive(Clone, Copy, Debug)]
enum Swatch {
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
struct Entry {
    label: String,
    swatch: Swatch,
}

/// Axis, frame and text colour.
const INK: RGBColor = RGBColor(0, 0, 0);
/// Grid lines.
const GRID: RGBColor = RGBColor(222, 222, 222);
/// The lighter lines between decades on a log axis.
const MINOR_GRID: RGBColor = RGBColor(238, 238, 238);
/// The legend box's edge.
const LEGEND_EDGE: RGBColor = RGBColor(150, 150, 150);
/// Reference curves: the diffraction limit.
const REFERENCE: Stroke = Stroke::dashed(RGBColor(0, 0, 0), 1.0, 4.0, 2.0);
/// Vertical reference lines (Nyquist, `--mark-x` on lines).
const MARK: Stroke = Stroke::dashed(RGBColor(60, 60, 60), 0.9, 1.5, 1.5);
/// Vertical reference lines on heatmaps.
const HEAT_MARK: Stroke = Stroke::dashed(RGBColor(230, 30, 30), 1.2, 4.0, 2.0);
/// The heatmap ridge: white on a dark outline.
const RIDGE: Stroke =
    Stroke { colour: RGBColor(255, 255, 255), width: 1.0, dash: None, halo: Some((RGBColor(30, 30, 30), 2.2)) };
/// Shading of points or cells beyond validity: grey, translucent.
const SHADE: (RGBColor, f64) = (RGBColor(110, 110, 110), 0.14);

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

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

fn fail(e: &dyn std::fmt::Display) -> String {
    e.to_string()
}

/// A kind of plot: its title, its legend, and how it draws its axes and data.
trait Plot {
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
struct Layout {
    width: i32,
    title: Vec<String>,
    title_h: i32,
    axes_h: i32,
    legend: Option<LegendLayout>,
}

#[derive(Clone, Debug)]
struct LegendLayout {
    /// Each entry's lines of text (long labels are wrapped), column and first row.
    placed: Vec<(Vec<String>, usize, usize)>,
    /// Width of each column.
    columns: Vec<i32>,
    box_w: i32,
    box_h: i32,
}

/// Margin around the figure, points.
const MARGIN_PT: f64 = 6.0;
/// Legend metrics, points: swatch length, swatch-to-text gap, column gap, row height, padding.
const SWATCH_PT: f64 = 20.0;
const SWATCH_GAP_PT: f64 = 5.0;
const COLUMN_GAP_PT: f64 = 14.0;
const ROW_PT: f64 = LEGEND_PT * 1.6;
const PAD_PT: f64 = 5.0;

impl Layout {
    fn new(ctx: Ctx, width: i32, title: &str, entries: &[Entry], aspect: f64) -> Self {
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
    fn height(&self, ctx: Ctx) -> i32 {
        let legend = self.legend.as_ref().map_or(0, |l| l.box_h + ctx.px(MARGIN_PT));
        ctx.px(MARGIN_PT) + self.title_h + self.axes_h + legend + ctx.px(MARGIN_PT)
    }
}

/// `text` broken into lines at spaces so each is at most `width` pixels wide at `pt` points (a
/// single word wider than that is a line of its own).
fn wrap(ctx: Ctx, pt: f64, text: &str, width: i32) -> Vec<String> {
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
fn compose<DB: DrawingBackend, P: Plot>(
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
fn draw_legend<DB: DrawingBackend>(
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
fn outline<T: Copy>(a: (T, T), b: (T, T)) -> Vec<(T, T)> {
    vec![a, (b.0, a.1), b, (a.0, b.1), a, (b.0, a.1)]
}

/// A segment from `from` to `to` (device pixels) with stroke `s`: the halo, then the line,
/// dashed with its own pattern.
fn draw_segment<DB: DrawingBackend>(
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
fn draw_swatch<DB: DrawingBackend>(
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
fn draw_curve<DB: DrawingBackend>(
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
struct Axes<'a> {
    x: (f64, f64),
    y: (f64, f64),
    x_desc: &'a str,
    y_desc: &'a str,
    grid: bool,
    /// y holds log10 of the values: ticks at whole decades, written as the values
    y_log: bool,
    /// x holds log10 of the values, as `y_log`
    x_log: bool,
}

/// Space around the plotting area of a chart, device pixels.
#[derive(Clone, Copy, Debug)]
struct Margins {
    top: i32,
    bottom: i32,
    left: i32,
    right: i32,
    x_labels: i32,
    y_labels: i32,
}

/// How many tick labels fit along `length` pixels when each takes `each` points.
fn tick_count(ctx: Ctx, length: i32, each: f64) -> usize {
    usize::try_from(length / ctx.px(each).max(1)).unwrap_or(0).clamp(3, 12)
}

impl Axes<'_> {
    /// Tick counts and formats for a plotting area about `(w, h)` pixels.
    fn ticks(&self, ctx: Ctx, (w, h): (i32, i32)) -> ((usize, TickFormat), (usize, TickFormat)) {
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

    fn margins(&self, ctx: Ctx, (w, h): (i32, i32), right_extra: i32) -> Margins {
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
    fn build<'a, DB: DrawingBackend>(
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
    fn label_between_decades<DB: DrawingBackend>(
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
    fn frame<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let path = outline((self.x.0, self.y.0), (self.x.1, self.y.1));
        chart.draw_series([PathElement::new(path, INK.stroke_width(ctx.stroke(0.6)))]).map(|_| ()).map_err(|e| fail(&e))
    }
}

/// Draws the SVG or PNG of `plot` into `path` (by its extension); errors name `flag`.
fn render<P: Plot>(flag: &str, path: &Path, figure: &Figure, plot: &P) -> Result<()> {
    let err = |e: &dyn std::fmt::Display| anyhow!("{flag} {}: {e}", path.display());
    // before any drawing: the folder the file goes in (the system's "No such file" named neither)
    if let Some(folder) = path.parent().filter(|f| !f.as_os_str().is_empty() && !f.is_dir()) {
        bail!("{flag} {}: the folder {} does not exist; create it first", path.display(), folder.display());
    }
    register_font();
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("svg") => std::fs::write(path, svg(figure, plot).map_err(|e| err(&e))?).map_err(|e| err(&e)),
        Some("png") => {
            let (size, rgb) = rasterize(figure, plot, supersampling(figure, plot)).map_err(|e| err(&e))?;
            write_png(path, size, &rgb, figure.dpi).map_err(|e| err(&e))
        }
        _ => bail!("{flag} {}: expected a file name ending in .svg or .png", path.display()),
    }
}

/// The SVG text of `plot`: drawn at [`SVG_FINE`] times the figure's size, shown at its size.
fn svg<P: Plot>(figure: &Figure, plot: &P) -> Result<String, String> {
    let ctx = Ctx { k: figure.px_per_pt() * f64::from(SVG_FINE) };
    let entries = plot.entries();
    let width = figure.width * SVG_FINE;
    let layout = Layout::new(ctx, i32::try_from(width).unwrap_or(i32::MAX), plot.title(), &entries, plot.aspect());
    let shown = (figure.width, layout.height(ctx).unsigned_abs().div_ceil(SVG_FINE));
    let fine = (width, shown.1 * SVG_FINE);
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, fine).into_drawing_area();
        compose(&root, ctx, &layout, plot, &entries)?;
    }
    Ok(text.replacen(
        &format!("<svg width=\"{}\" height=\"{}\"", fine.0, fine.1),
        &format!("<svg width=\"{}\" height=\"{}\"", shown.0, shown.1),
        1,
    ))
}

/// How many times larger a PNG is drawn than written: 3, or 2 for very large figures.
fn supersampling<P: Plot>(figure: &Figure, plot: &P) -> u32 {
    let ctx = Ctx { k: figure.px_per_pt() };
    let layout =
        Layout::new(ctx, i32::try_from(figure.width).unwrap_or(i32::MAX), plot.title(), &plot.entries(), plot.aspect());
    let pixels = u64::from(figure.width) * u64::from(layout.height(ctx).unsigned_abs());
    if pixels * 9 <= MAX_SUPERSAMPLED { 3 } else { 2 }
}

/// The RGB pixels of `plot` at the figure's size: drawn `s` times larger and box-filtered down.
fn rasterize<P: Plot>(figure: &Figure, plot: &P, s: u32) -> Result<((u32, u32), Vec<u8>), String> {
    let ctx = Ctx { k: figure.px_per_pt() * f64::from(s) };
    let entries = plot.entries();
    let width = figure.width * s;
    let layout = Layout::new(ctx, i32::try_from(width).unwrap_or(i32::MAX), plot.title(), &entries, plot.aspect());
    let size = (figure.width, layout.height(ctx).unsigned_abs().div_ceil(s));
    let big_size = (width, size.1 * s);
    let mut big = vec![255u8; big_size.0 as usize * big_size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut big, big_size).into_drawing_area();
        compose(&root, ctx, &layout, plot, &entries)?;
    }
    Ok((size, downsample(&big, size, s)))
}

/// `big` (RGB, `s` times `(w, h)`) averaged over `s × s` blocks.
fn downsample(big: &[u8], (w, h): (u32, u32), s: u32) -> Vec<u8> {
    let (w, h, s) = (w as usize, h as usize, s as usize);
    let n = (s * s) as u32;
    let mut out = vec![0u8; w * h * 3];
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0u32; 3];
            for dy in 0..s {
                let row = (y * s + dy) * w * s;
                for dx in 0..s {
                    let i = (row + x * s + dx) * 3;
                    for (c, total) in sum.iter_mut().enumerate() {
                        *total += u32::from(big[i + c]);
                    }
                }
            }
            for (c, total) in sum.iter().enumerate() {
                out[(y * w + x) * 3 + c] = ((total + n / 2) / n) as u8;
            }
        }
    }
    out
}

/// Writes RGB pixels as a PNG with its resolution, `dpi`, in a pHYs chunk (pixels per metre,
/// both axes), through the `png` encoder.
fn write_png(path: &Path, (w, h): (u32, u32), rgb: &[u8], dpi: f64) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| fail(&e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let ppm = (dpi / 0.0254).round() as u32;
    encoder.set_pixel_dims(Some(png::PixelDimensions { xppu: ppm, yppu: ppm, unit: png::Unit::Meter }));
    let mut writer = encoder.write_header().map_err(|e| fail(&e))?;
    writer.write_image_data(rgb).map_err(|e| fail(&e))?;
    writer.finish().map_err(|e| fail(&e))
}

/// Line charts of `asnr plot` and one-key sweeps.
struct LinesPlot<'a> {
    labels: &'a Labels<'a>,
    series: &'a [Series],
    marks: &'a [Mark],
    mark_best: bool,
}

/// Width of a line where no later line lies on it, points; each later line lying on it there
/// widens it by [`COVER_PT`], so the line under shows on both sides of the one over.
const LINE_PT: f64 = 1.6;
const COVER_PT: f64 = 1.3;
/// A line lies on an earlier one where they are closer than this fraction of the y axis (about a
/// line's width at the default figure size).
const COINCIDENT: f64 = 0.01;

/// Series as drawn, the x range and the y range ([`LinesPlot::view`]).
type View<'a> = (std::borrow::Cow<'a, [Series]>, (f64, f64), (f64, f64));

/// A run of a line's segments drawn alike: (dashed, lines over it) and its points.
type Run = ((bool, usize), Vec<(f64, f64)>);

impl LinesPlot<'_> {
    fn stroke(i: usize) -> Stroke {
        Stroke::solid(PALETTE[i % PALETTE.len()], LINE_PT)
    }

    /// For each point of each series (see [`LinesPlot::view`] for `series` and `y`), how many
    /// later series pass within [`COINCIDENT`] of it (linear between their points): the lines
    /// drawn over it there.
    fn covers(series: &[Series], y: (f64, f64)) -> Vec<Vec<usize>> {
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

    fn shaded(&self) -> bool {
        self.series.iter().any(|s| s.shaded.iter().any(|&f| f))
    }

    /// The series as drawn (log10 of their positive values on a log axis), the x range and the
    /// y range of the axes.
    fn view(&self) -> View<'_> {
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
fn mark_entries(marks: &[Mark], stroke: Stroke) -> Vec<Entry> {
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
fn minor_decades<DB: DrawingBackend>(
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

/// A set of measured points on a [`FitPanel`], with the straight line fitted to them in log-log
/// coordinates.
#[derive(Clone, Debug)]
pub struct FitSet {
    /// Legend entry (the fit's slope belongs in it).
    pub label: String,
    /// Measured `(x, y)`, both > 0 (others are left out).
    pub points: Vec<(f64, f64)>,
    /// Per point, whether the fit used it: drawn filled, the others hollow.
    pub fitted: Vec<bool>,
    /// `log10 y = intercept + slope · log10 x`: (slope, intercept), drawn over the fitted points.
    pub line: Option<(f64, f64)>,
    /// Colour index into the palette.
    pub colour: usize,
}

/// One log-log panel of measured points and fitted power laws (a camera's STF or PTC).
#[derive(Clone, Debug)]
pub struct FitPanel<'a> {
    /// Caption above the panel, e.g. "(a) signal transfer".
    pub caption: &'a str,
    /// Description of the x axis, with its unit.
    pub x: &'a str,
    /// Description of the y axis, with its unit.
    pub y: &'a str,
    /// The point sets.
    pub sets: Vec<FitSet>,
}

/// Writes `panels` side by side on log-log axes, each set's points (filled where fitted, hollow
/// where not) and fitted line, one legend below for all; SVG or PNG by the file's extension;
/// errors name `flag`.
pub fn fit_panels_plot(flag: &str, path: &Path, figure: &Figure, title: &str, panels: &[FitPanel]) -> Result<()> {
    if panels.iter().all(|p| p.sets.iter().all(|s| s.points.iter().all(|&(x, y)| !(x > 0.0 && y > 0.0)))) {
        bail!("{flag} {}: nothing to plot (no positive points)", path.display());
    }
    render(flag, path, figure, &FitPlot { title, panels })
}

/// The panels of [`fit_panels_plot`].
struct FitPlot<'a> {
    title: &'a str,
    panels: &'a [FitPanel<'a>],
}

impl FitPlot<'_> {
    fn stroke(set: &FitSet) -> Stroke {
        Stroke::solid(PALETTE[set.colour % PALETTE.len()], 1.3)
    }
}

impl Plot for FitPlot<'_> {
    fn title(&self) -> &str {
        self.title
    }

    fn entries(&self) -> Vec<Entry> {
        let mut entries = Vec::new();
        for set in self.panels.iter().flat_map(|p| &p.sets) {
            if !entries.iter().any(|e: &Entry| e.label == set.label) {
                let stroke = Self::stroke(set);
                entries.push(Entry { label: set.label.clone(), swatch: Swatch::Dot(stroke, stroke.colour) });
            }
        }
        if self.panels.iter().flat_map(|p| &p.sets).any(|s| s.fitted.iter().any(|f| !f)) {
            entries.push(Entry {
                label: "hollow: levels left out of the fits (dark-limited, or at or near saturation)".to_owned(),
                swatch: Swatch::Ring(RGBColor(90, 90, 90)),
            });
        }
        entries
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let cells = area.split_evenly((1, self.panels.len().max(1)));
        for (panel, cell) in self.panels.iter().zip(&cells) {
            let caption_h = ctx.px(DESC_PT * 1.8);
            let (top, below) = cell.split_vertically(caption_h);
            let (cw, _) = top.dim_in_pixel();
            let style = ctx.font(DESC_PT).color(&INK).pos(Pos::new(HPos::Center, VPos::Top));
            let centre = i32::try_from(cw / 2).unwrap_or(0);
            top.draw(&Text::new(panel.caption.to_owned(), (centre, ctx.px(2.0)), style)).map_err(|e| fail(&e))?;
            let log = |&(x, y): &(f64, f64)| (x > 0.0 && y > 0.0).then(|| (x.log10(), y.log10()));
            let all: Vec<(f64, f64)> = panel.sets.iter().flat_map(|s| s.points.iter().filter_map(log)).collect();
            if all.is_empty() {
                continue;
            }
            // whole decades around the data, or 5 % of the span beyond it where that is tighter
            let around = |(lo, hi): (f64, f64)| {
                let pad = 0.05 * (hi - lo).max(1.0);
                ((lo - pad).max(lo.floor()), (hi + pad).min(hi.ceil().max(hi + 1e-9)))
            };
            let x = around(extent(all.iter().map(|p| p.0)));
            let y = around(extent(all.iter().map(|p| p.1)));
            let axes = Axes { x, y, x_desc: panel.x, y_desc: panel.y, grid: true, y_log: true, x_log: true };
            let (mut chart, _) = axes.build(&below, ctx, 0)?;
            axes.label_between_decades(&below, &chart, ctx)?;
            minor_decades(&mut chart, ctx, x, y, (true, true))?;
            for set in &panel.sets {
                let stroke = Self::stroke(set);
                let points: Vec<((f64, f64), bool)> = set
                    .points
                    .iter()
                    .zip(set.fitted.iter().chain(std::iter::repeat(&true)))
                    .filter_map(|(p, &f)| log(p).map(|p| (p, f)))
                    .collect();
                if let Some((slope, intercept)) = set.line {
                    let fitted = || points.iter().filter(|(_, f)| *f).map(|(p, _)| p.0);
                    let (lo, hi) = (fitted().fold(f64::INFINITY, f64::min), fitted().fold(f64::NEG_INFINITY, f64::max));
                    if lo < hi {
                        // the line over the fitted points and a little beyond, inside the axes
                        let (a, b) = ((lo - 0.15 * (hi - lo)).max(x.0), (hi + 0.15 * (hi - lo)).min(x.1));
                        let line: Vec<(f64, f64)> = (0..=64)
                            .map(|i| a + (b - a) * f64::from(i) / 64.0)
                            .map(|v| (v, intercept + slope * v))
                            .filter(|p| p.1 >= y.0 && p.1 <= y.1)
                            .collect();
                        draw_curve(&mut chart, ctx, &line, stroke)?;
                    }
                }
                let r = ctx.px(2.6);
                for &(p, fitted) in &points {
                    if fitted {
                        chart
                            .draw_series([
                                Circle::new(p, r, stroke.colour.filled()),
                                Circle::new(p, r, WHITE.stroke_width(ctx.stroke(0.5))),
                            ])
                            .map_err(|e| fail(&e))?;
                    } else {
                        chart
                            .draw_series([
                                Circle::new(p, r, WHITE.filled()),
                                Circle::new(p, r, stroke.colour.stroke_width(ctx.stroke(1.0))),
                            ])
                            .map_err(|e| fail(&e))?;
                    }
                }
            }
            axes.frame(&mut chart, ctx)?;
        }
        Ok(())
    }
}

/// matplotlib's viridis for `t` in [0, 1] (plotters' table of eight stops, linear between).
fn colour(t: f64) -> RGBColor {
    plotters::style::colors::colormaps::ViridisRGB::get_color(t.clamp(0.0, 1.0))
}

/// Heatmaps of `asnr plot --z` and two-key sweeps.
struct HeatmapPlot<'a> {
    labels: &'a Labels<'a>,
    grid: &'a Grid,
    marks: &'a [Mark],
    /// A path drawn over the map (an optimizer's points in order), with its legend entry; empty
    /// for none.
    path: &'a [(f64, f64)],
    /// x and y in the same unit: the plotting area is as many pixels per unit on both axes
    /// (within a pixel), and taller than a chart's
    square: bool,
}

/// The axes block of an image ([`HeatmapPlot::square`]) over the figure's width: room for a
/// square plotting area beside the colour bar at the default size.
const IMAGE_ASPECT: f64 = 0.8;

/// An optimizer's path over a heatmap.
const PATH: Stroke = Stroke::solid(RGBColor(230, 30, 30), 1.2);

/// The white veil over shaded heatmap cells.
const VEIL: (RGBColor, f64) = (RGBColor(255, 255, 255), 0.55);

impl HeatmapPlot<'_> {
    /// `(lo, hi)` of the values, `hi > lo`.
    fn range(&self) -> (f64, f64) {
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

/// The MTF chart of `asnr mtf --plot`.
struct MtfPlot<'a> {
    title: &'a str,
    curve: &'a MtfCurve,
}

/// The polychromatic MTF.
const POLY: Stroke = Stroke::solid(RGBColor(20, 80, 200), 1.8);
/// Monochromatic curves: thin, in colours apart from the polychromatic blue.
const MONO: [RGBColor; 5] = [
    RGBColor(235, 140, 0),
    RGBColor(40, 160, 70),
    RGBColor(170, 60, 170),
    RGBColor(215, 40, 40),
    RGBColor(0, 150, 160),
];
/// The off-axis directional MTFs: along the field, across it.
const OFF_AXIS: [Stroke; 2] =
    [Stroke::dashed(RGBColor(90, 160, 240), 1.3, 5.0, 2.0), Stroke::dashed(RGBColor(10, 30, 110), 1.3, 2.0, 1.5)];

/// The off-axis MTFs of `curve` (frequencies along the field direction, then across it) with
/// their legend labels; `None` on axis. The only place that names the directional fields.
fn off_axis(curve: &MtfCurve) -> Option<[(&[f64], &'static str); 2]> {
    Some([
        (curve.mtf_tangential.as_deref()?, "tangential (along the field)"),
        (curve.mtf_sagittal.as_deref()?, "sagittal (across the field)"),
    ])
}

impl MtfPlot<'_> {
    fn mono(i: usize) -> Stroke {
        Stroke::solid(MONO[i % MONO.len()], 0.9)
    }

    /// Whether the axis extends past Nyquist, so the Nyquist line is drawn.
    fn nyquist(&self) -> Option<f64> {
        let x_max = self.curve.frequency_cyc_per_mm.last().copied().unwrap_or(1.0);
        let n = self.curve.nyquist_cyc_per_mm;
        (n.is_finite() && n < x_max * 0.999).then_some(n)
    }
}

impl Plot for MtfPlot<'_> {
    fn title(&self) -> &str {
        self.title
    }

    fn entries(&self) -> Vec<Entry> {
        let curve = self.curve;
        let poly = match (curve.field_points.len(), off_axis(curve).is_some()) {
            (0, false) => "polychromatic MTF".to_owned(),
            (0, true) => "polychromatic MTF (mean of both directions)".to_owned(),
            (n, _) => format!("polychromatic MTF, weighted mean of {n} field points"),
        };
        let mut entries = vec![Entry { label: poly, swatch: Swatch::Line(POLY) }];
        for ((ys, label), stroke) in off_axis(curve).into_iter().flatten().zip(OFF_AXIS) {
            // a directional curve on the mean (on axis in all but name): said, as the dashes
            // over the mean are all that show of it
            let apart = ys.iter().zip(&curve.mtf).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            let label = if apart < COINCIDENT {
                format!("{label}, within {:.3} of the mean", ((apart * 1e3).ceil() / 1e3).max(1e-3))
            } else {
                label.to_owned()
            };
            entries.push(Entry { label, swatch: Swatch::Line(stroke) });
        }
        for (i, wl) in curve.wavelengths_nm.iter().enumerate() {
            entries.push(Entry { label: format!("{wl:.1} nm"), swatch: Swatch::Line(Self::mono(i)) });
        }
        entries.push(Entry {
            label: format!("diffraction limit ({:.1} nm)", curve.mean_wavelength_nm),
            swatch: Swatch::Line(REFERENCE),
        });
        if let Some(n) = self.nyquist() {
            entries.push(Entry { label: format!("Nyquist ({n:.1} cycles/mm)"), swatch: Swatch::Line(MARK) });
        }
        entries
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let curve = self.curve;
        let x_max = curve.frequency_cyc_per_mm.last().copied().unwrap_or(1.0).max(1e-12);
        let y_desc = if curve.pixel_mtf { "MTF (lens × pixel)" } else { "MTF" };
        let x_desc = axis_label("frequency_cyc_per_mm");
        let axes =
            Axes { x: (0.0, x_max), y: (0.0, 1.05), x_desc: &x_desc, y_desc, grid: true, y_log: false, x_log: false };
        let (mut chart, _) = axes.build(area, ctx, 0)?;
        let xs = &curve.frequency_cyc_per_mm;
        let series = |ys: &[f64]| xs.iter().copied().zip(ys.iter().copied()).collect::<Vec<_>>();
        // the wide polychromatic line first, the thinner and dashed ones over it, so where they
        // coincide each still shows (the mean through the dashes' gaps)
        draw_curve(&mut chart, ctx, &series(&curve.mtf), POLY)?;
        for (i, ys) in curve.monochromatic.iter().enumerate() {
            draw_curve(&mut chart, ctx, &series(ys), Self::mono(i))?;
        }
        for ((ys, _), stroke) in off_axis(curve).into_iter().flatten().zip(OFF_AXIS) {
            draw_curve(&mut chart, ctx, &series(ys), stroke)?;
        }
        // references last, on top: the diffraction limit often coincides with the curve at the
        // design wavelength
        draw_curve(&mut chart, ctx, &series(&curve.diffraction_limited), REFERENCE)?;
        if let Some(n) = self.nyquist() {
            draw_curve(&mut chart, ctx, &[(n, 0.0), (n, 1.05)], MARK)?;
        }
        axes.frame(&mut chart, ctx)
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_under_a_later_one_is_covered_only_where_they_meet() {
        let line = |label: &str, f: &dyn Fn(f64) -> f64| Series {
            label: label.to_owned(),
            points: (0..=10).map(|i| (f64::from(i), f(f64::from(i)))).collect(),
            shaded: Vec::new(),
            best: None,
        };
        // b lies on a for x ≤ 4 (then 1 apart on an axis 10 high); c rises through both, its
        // samples between theirs (x + 0.5, where they are interpolated) and at least 0.5 off
        let a = line("a", &|_| 5.0);
        let b = line("b", &|x| if x <= 4.0 { 5.0 } else { 6.0 });
        let mut c = line("c", &|x| 5.0 + x);
        c.points.iter_mut().for_each(|p| p.0 += 0.5);
        let covers = LinesPlot::covers(&[a, b, c], (0.0, 10.0));
        assert_eq!(covers[0], [1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0]);
        assert_eq!(covers[1], [0; 11]);
        assert_eq!(covers[2], [0; 11]);
        let d = line("d", &|_| 5.0 + 0.05);
        let e = line("e", &|_| 5.0);
        let covers = LinesPlot::covers(&[d, e], (0.0, 10.0));
        assert_eq!(covers[0], [1; 11], "0.05 apart on an axis 10 high: within 1 %");
    }

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
        assert_eq!(significant(10.56981), "10.57");
        assert_eq!(significant(34.3947), "34.39");
        assert_eq!(significant(0.00123456), "0.001235");
        assert_eq!(significant(12345.6), "12346");
    }

    #[test]
    fn axis_labels_are_human_with_units() {
        for (key, label) in [
            ("spectrum.range_nm", "spectral range (nm)"),
            ("lens.f_number", "F-number"),
            ("camera.pixel_pitch_um", "pixel pitch (µm)"),
            ("exposure.time_ms", "exposure time (ms)"),
            ("asnr", "ASNR"),
            ("mean_mtf", "mean MTF"),
            ("snr0", "SNR0"),
            ("frequency_cyc_per_mm", "spatial frequency (cycles/mm)"),
            // the generic rule: last segment, unit suffix, underscores as spaces
            ("lens.coma_um", "coma (µm)"),
            ("lens.sector_deg", "sector (°)"),
            ("source.temperature_k", "source temperature (K)"),
            ("noise.dark_current_e", "dark current (e⁻)"),
            ("otf.cutoff_cyc_per_mm", "cutoff (cycles/mm)"),
            ("filter.width_mm", "width (mm)"),
            ("some.plain_name", "plain name"),
            ("x", "x"),
            // a bare suffix is a name, not a unit
            ("lens._nm", "nm"),
        ] {
            assert_eq!(axis_label(key), label, "{key}");
        }
        assert_eq!(quantity("camera.pixel_pitch_um"), ("pixel pitch".to_owned(), Some("µm")));
    }

    #[test]
    fn tick_formats_write_each_tick_exactly_once() {
        assert_eq!(TickFormat::of(&[0.0, 0.25, 0.5, 0.75]), TickFormat::Fixed(2));
        assert_eq!(TickFormat::of(&[0.0, 20.0, 40.0]), TickFormat::Fixed(0));
        assert_eq!(TickFormat::of(&[0.1, 0.2, 0.30000000000000004]), TickFormat::Fixed(1));
        assert_eq!(TickFormat::of(&[1e-9, 2e-9]), TickFormat::Scientific);
        assert_eq!(TickFormat::of(&[0.0, 2e6]), TickFormat::Scientific);
        assert_eq!(TickFormat::Fixed(1).write(-0.0), "0.0");
        assert_eq!(TickFormat::Fixed(2).write(0.25), "0.25");
        assert_eq!(TickFormat::Scientific.write(2e-9), "2.00e-9");
        // a log axis writes the values at whole decades
        assert_eq!(TickFormat::Decades.write(2.0), "100");
        assert_eq!(TickFormat::Decades.write(-1.0), "0.1");
        assert_eq!(TickFormat::Decades.write(0.0), "1");
        assert_eq!(TickFormat::Decades.write(7.0), "1e7");
    }

    /// A log-x axis from 0.3 to 2e4 (log10: −0.52 … 4.3): one tick per whole decade, 1 … 10000,
    /// written as the values, as on a log y axis.
    #[test]
    fn log_x_axis_ticks_are_whole_decades() {
        let axes = Axes {
            x: (0.3f64.log10(), 2e4f64.log10()),
            y: (0.0, 1.0),
            x_desc: "x",
            y_desc: "y",
            grid: true,
            y_log: false,
            x_log: true,
        };
        let ((nx, format), _) = axes.ticks(Ctx { k: 1.0 }, (400, 300));
        assert_eq!(format, TickFormat::Decades);
        let keys = ticks(axes.x, nx);
        assert_eq!(keys, vec![0.0, 1.0, 2.0, 3.0, 4.0], "{nx}");
        let written: Vec<String> = keys.iter().map(|&v| format.write(v)).collect();
        assert_eq!(written, ["1", "10", "100", "1000", "10000"]);
    }

    /// A log-y line plot of values from 0.2 to 120: its ticks are the decades 1, 10, 100, one
    /// each, the decades' key points are whole numbers, and a non-positive value is left out.
    #[test]
    fn log_axis_ticks_are_whole_decades() {
        let axes = Axes {
            x: (0.0, 1.0),
            y: (0.2f64.log10() - 0.1, 120f64.log10() + 0.1),
            x_desc: "x",
            y_desc: "y",
            grid: true,
            y_log: true,
            x_log: false,
        };
        let ((_, _), (ny, format)) = axes.ticks(Ctx { k: 1.0 }, (400, 300));
        assert_eq!(format, TickFormat::Decades);
        let keys = ticks(axes.y, ny);
        assert_eq!(keys, vec![0.0, 1.0, 2.0], "{ny}");
        let points = vec![(1.0, 0.2), (2.0, 0.0), (3.0, 12.0), (4.0, 120.0)];
        let series = vec![Series { label: "a".to_owned(), points, shaded: Vec::new(), best: None }];
        let labels = Labels { title: "t", x: "x", y: "ASNR", log_y: true, ..Default::default() };
        let text = svg(
            &Figure::new(None, None).unwrap(),
            &LinesPlot { labels: &labels, series: &series, marks: &[], mark_best: true },
        )
        .unwrap();
        for tick in [">\n1\n<", ">\n10\n<", ">\n100\n<"] {
            assert!(text.contains(tick), "{tick}");
        }
        assert!(text.contains("max 120 at 4"), "the legend gives the value, not its logarithm");
    }

    #[test]
    fn figure_sizes_are_validated() {
        assert_eq!(Figure::new(None, None).unwrap(), Figure::default());
        let f = Figure::new(Some(1050), Some(300.0)).unwrap();
        assert!((f.px_per_pt() - 300.0 / 72.0).abs() < 1e-12);
        let err = Figure::new(Some(100), None).unwrap_err().to_string();
        assert_eq!(err, "--width 100: expected a whole number of pixels from 300 to 4000");
        let err = Figure::new(None, Some(f64::NAN)).unwrap_err().to_string();
        assert_eq!(err, "--dpi NaN: expected dots per inch from 30 to 2400");
        let err = Figure::new(Some(300), Some(600.0)).unwrap_err().to_string();
        assert!(err.starts_with("--dpi 600 with --width 300: the figure would be 0.50 inches wide;"), "{err}");
    }

    #[test]
    fn png_records_its_resolution_and_pixels() {
        let path = std::env::temp_dir().join(format!("asnr-plot-phys-{}.png", std::process::id()));
        let rgb: Vec<u8> = (0..4 * 3 * 3).map(|i| (i * 7) as u8).collect();
        write_png(&path, (4, 3), &rgb, 300.0).unwrap();
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        // 300 dpi is 11 811 pixels per metre
        let dims = reader.info().pixel_dims.unwrap();
        assert_eq!((dims.xppu, dims.yppu, dims.unit), (11_811, 11_811, png::Unit::Meter));
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut pixels).unwrap();
        assert_eq!(pixels, rgb);
        std::fs::remove_file(&path).unwrap();
    }

    /// A straight line in many short segments, as curves are drawn.
    fn straight() -> Vec<Series> {
        let points = (0..=300).map(|i| f64::from(i) / 300.0).map(|x| (x, 0.1 + 0.37 * x)).collect();
        vec![Series { label: "a".to_owned(), points, shaded: Vec::new(), best: None }]
    }

    /// Pixels of `rgb` that are neither white, nor the line colour, nor grey: the blends of a
    /// blue line's edge with the white ground.
    fn blue_blends(rgb: &[u8]) -> std::collections::BTreeSet<[u8; 3]> {
        let RGBColor(r, g, b) = PALETTE[0];
        rgb.chunks(3)
            .map(|p| [p[0], p[1], p[2]])
            .filter(|p| *p != [r, g, b] && *p != [255, 255, 255] && p[2] > p[0].saturating_add(20))
            .collect()
    }

    /// How far the drawn centre of a straight blue line strays from straight: the RMS of the
    /// second differences of its centre (the coverage-weighted mean row), column by column over
    /// the middle half of the upper two thirds (the plot, not the legend). Zero for an exact
    /// line; vertices rounded to whole pixels kink it.
    fn wobble(rgb: &[u8], (w, h): (u32, u32)) -> f64 {
        let (w, h) = (w as usize, h as usize);
        let centres: Vec<f64> = (w / 4..3 * w / 4)
            .filter_map(|x| {
                let (mut sum, mut weight) = (0.0, 0.0);
                for y in 0..2 * h / 3 {
                    let p = &rgb[(y * w + x) * 3..][..3];
                    if p[2] > p[0].saturating_add(20) {
                        let d = (255.0 - f64::from(p[0])) / 235.0;
                        sum += d * y as f64;
                        weight += d;
                    }
                }
                (weight > 0.0).then(|| sum / weight)
            })
            .collect();
        let second: Vec<f64> = centres.windows(3).map(|c| c[2] - 2.0 * c[1] + c[0]).collect();
        (second.iter().map(|d| d * d).sum::<f64>() / second.len() as f64).sqrt()
    }

    #[test]
    fn png_lines_are_anti_aliased_by_supersampling() {
        register_font();
        let series = straight();
        let labels = Labels { x: "x", y: "y", ..Labels::default() };
        let plot = LinesPlot { labels: &labels, series: &series, marks: &[], mark_best: false };
        let figure = Figure::default();
        let (size, rgb) = rasterize(&figure, &plot, 3).unwrap();
        assert_eq!(size.0, DEFAULT_WIDTH);
        assert_eq!(rgb.len(), (size.0 * size.1 * 3) as usize);
        // the edges of the line blend its blue into white in many steps
        let smooth = blue_blends(&rgb).len();
        assert!(smooth >= 50, "{smooth} blended colours");
        // drawn directly at its size, as plotters draws a PNG, the line kinks at every vertex
        let (_, direct) = rasterize(&figure, &plot, 1).unwrap();
        let (soft, hard) = (wobble(&rgb, size), wobble(&direct, size));
        assert!(soft < 0.7 * hard, "wobble {soft} px supersampled, {hard} px directly");
    }

    #[test]
    fn legends_never_widen_past_the_figure_and_wrap_into_rows() {
        register_font();
        let ctx = Ctx { k: Figure::new(Some(1050), Some(300.0)).unwrap().px_per_pt() };
        let entries: Vec<Entry> =
            (0..8).map(|i| Entry { label: format!("entry {i}"), swatch: Swatch::Line(POLY) }).collect();
        let layout =
            Layout::new(ctx, 1050, "a title long enough to need two lines at this size, surely", &entries, ASPECT);
        let legend = layout.legend.unwrap();
        assert!(legend.box_w <= 1050 - 2 * ctx.px(MARGIN_PT), "{}", legend.box_w);
        assert!(legend.columns.len() >= 2 && legend.columns.len() < 8, "{:?}", legend.columns);
        assert_eq!(layout.title.len(), 2, "{:?}", layout.title);
        // a label wider than the figure is wrapped onto lines of its own
        let long = [Entry { label: "a very long legend entry indeed, ".repeat(4), swatch: Swatch::Line(POLY) }];
        let legend = Layout::new(ctx, 1050, "", &long, ASPECT).legend.unwrap();
        assert!(legend.box_w <= 1050 - 2 * ctx.px(MARGIN_PT), "{}", legend.box_w);
        assert!(legend.placed[0].0.len() >= 2, "{:?}", legend.placed);
    }
}
