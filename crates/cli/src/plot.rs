//! MTF plots, SVG or PNG, drawn by plotters' pure-Rust backends. PNG text is rasterized with
//! DejaVu Sans embedded in the binary (`assets/`, Bitstream Vera licence), so no system font or
//! fontconfig is needed.

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

/// Draws with `$draw(root)` into `$path` on the backend its extension names (.svg or .png).
macro_rules! render {
    ($path:expr, $draw:expr) => {{
        let path: &Path = $path;
        let err = |e: &dyn std::fmt::Display| anyhow!("--plot {}: {e}", path.display());
        register_font();
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("svg") => $draw(SVGBackend::new(path, SIZE).into_drawing_area()).map_err(|e| err(&e)),
            Some("png") => $draw(BitMapBackend::new(path, SIZE).into_drawing_area()).map_err(|e| err(&e)),
            _ => bail!("--plot {}: expected a file name ending in .svg or .png", path.display()),
        }
    }};
}

/// Writes the MTF curve as a line chart, SVG or PNG by the file's extension: the polychromatic
/// MTF, the diffraction limit, the monochromatic curves, and the Nyquist frequency when the axis
/// extends past it.
pub fn mtf_plot(path: &Path, title: &str, curve: &MtfCurve) -> Result<()> {
    render!(path, |root| draw(root, title, curve))
}

/// Writes a sweep's ASNR: a line against the key for one swept key, a heatmap with the ridge of
/// the optimum (the best second key for each value of the first) for two.
pub fn sweep_plot(path: &Path, title: &str, ranges: &[Range], points: &[Point]) -> Result<()> {
    match ranges.len() {
        1 => render!(path, |root| draw_line(root, title, &ranges[0], points)),
        2 => render!(path, |root| draw_heatmap(root, title, ranges, points)),
        n => bail!("--plot: a sweep over {n} keys; plots take one key (a line) or two (a heatmap)"),
    }
}

fn draw_line<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    range: &Range,
    points: &[Point],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let y_max = points.iter().map(|p| p.asnr).fold(0.0, f64::max) * 1.08 + 1e-12;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(range.lo..range.hi, 0.0..y_max)
        .map_err(|e| err(&e))?;
    chart.configure_mesh().x_desc(range.key.as_str()).y_desc("ASNR").draw().map_err(|e| err(&e))?;
    let blue = RGBColor(20, 80, 200);
    chart
        .draw_series(LineSeries::new(points.iter().map(|p| (p.values[0], p.asnr)), blue.stroke_width(3)))
        .map_err(|e| err(&e))?;
    if let Some(best) = points.iter().max_by(|a, b| a.asnr.total_cmp(&b.asnr)) {
        chart
            .draw_series(std::iter::once(Circle::new((best.values[0], best.asnr), 6, RED.filled())))
            .map_err(|e| err(&e))?
            .label(format!("best {} = {:.4}, ASNR {:.4}", range.key, best.values[0], best.asnr))
            .legend(|(x, y)| Circle::new((x + 10, y), 5, RED.filled()));
        legend(&mut chart)?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The series legend, top right, on a translucent white box.
fn legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(180, 180, 180))
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
    title: &str,
    ranges: &[Range],
    points: &[Point],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: &dyn std::fmt::Display| e.to_string();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (xs, ys) = (crate::sweep::axis(&ranges[0]), crate::sweep::axis(&ranges[1]));
    let (lo, hi) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p.asnr), h.max(p.asnr)));
    let span = (hi - lo).max(1e-300);
    let half = |axis: &[f64]| if axis.len() > 1 { 0.5 * (axis[1] - axis[0]) } else { 0.5 };
    let (hx, hy) = (half(&xs), half(&ys));
    let (plot, bar) = root.split_horizontally(SIZE.0 - 110);
    let mut chart = ChartBuilder::on(&plot)
        .caption(title, ("sans-serif", 20))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(xs[0] - hx..xs[xs.len() - 1] + hx, ys[0] - hy..ys[ys.len() - 1] + hy)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(ranges[0].key.as_str())
        .y_desc(ranges[1].key.as_str())
        .draw()
        .map_err(|e| err(&e))?;
    chart
        .draw_series(points.iter().map(|p| {
            let (x, y) = (p.values[0], p.values[1]);
            Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], colour((p.asnr - lo) / span).filled())
        }))
        .map_err(|e| err(&e))?;
    // the ridge: for each value of the first key, the second key with the highest ASNR
    let ridge: Vec<(f64, f64)> = points
        .chunks(ys.len())
        .filter_map(|column| column.iter().max_by(|a, b| a.asnr.total_cmp(&b.asnr)))
        .map(|p| (p.values[0], p.values[1]))
        .collect();
    chart
        .draw_series(LineSeries::new(ridge.clone(), WHITE.stroke_width(2)))
        .map_err(|e| err(&e))?
        .label(format!("best {} for each {}", ranges[1].key, ranges[0].key))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    chart.draw_series(ridge.iter().map(|&p| Circle::new(p, 3, WHITE.filled()))).map_err(|e| err(&e))?;
    legend(&mut chart)?;
    // colour bar
    let mut scale = ChartBuilder::on(&bar)
        .margin_top(56)
        .margin_bottom(60)
        .margin_right(10)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..1.0, lo..hi + span * 1e-9)
        .map_err(|e| err(&e))?;
    scale
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc("ASNR")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(|e| err(&e))?;
    let steps = 100;
    scale
        .draw_series((0..steps).map(|i| {
            let (a, b) = (lo + span * i as f64 / steps as f64, lo + span * (i + 1) as f64 / steps as f64);
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
    if let (Some(r), Some(t)) = (&curve.mtf_radial, &curve.mtf_tangential) {
        for (ys, name, colour) in [
            (r, "along the field (x on axis)", RGBColor(90, 150, 240)),
            (t, "across it (y on axis)", RGBColor(20, 40, 120)),
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
        .label(if curve.mtf_radial.is_some() { "polychromatic MTF (mean of both)" } else { "polychromatic MTF" })
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(3)));
    if curve.nyquist_cyc_per_mm < x_max * 0.999 {
        let n = curve.nyquist_cyc_per_mm;
        chart
            .draw_series(LineSeries::new(vec![(n, 0.0), (n, 1.05)], RGBColor(120, 120, 120).stroke_width(1)))
            .map_err(|e| err(&e))?
            .label(format!("Nyquist {n:.1} cycles/mm"))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(120, 120, 120)));
    }
    legend(&mut chart)?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
