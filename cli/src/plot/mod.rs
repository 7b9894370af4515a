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

mod design;
mod fit;
mod heatmap;
mod lines;
mod mtf;
mod output;
mod style;
mod sweep;

pub use design::*;
pub use fit::*;
pub use heatmap::*;
pub use lines::*;
pub use mtf::*;
use output::*;
pub(crate) use style::*;
pub use sweep::*;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

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

/// Plain number for legends: up to four decimals, trailing zeros dropped.
pub use report::number;

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
