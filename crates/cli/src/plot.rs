//! MTF plots, SVG or PNG, drawn by plotters' pure-Rust backends. PNG text is rasterized with
//! DejaVu Sans embedded in the binary (`assets/`, Bitstream Vera licence), so no system font or
//! fontconfig is needed.

use std::path::Path;
use std::sync::Once;

use anyhow::{Result, anyhow, bail};
use metric::MtfCurve;
use plotters::coord::Shift;
use plotters::prelude::*;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Plot size, pixels.
const SIZE: (u32, u32) = (900, 560);

/// Writes the MTF curve as a line chart, SVG or PNG by the file's extension: the polychromatic
/// MTF, the diffraction limit, the monochromatic curves, and the Nyquist frequency when the axis
/// extends past it.
pub fn mtf_plot(path: &Path, title: &str, curve: &MtfCurve) -> Result<()> {
    let err = |e: &dyn std::fmt::Display| anyhow!("--plot {}: {e}", path.display());
    // both backends measure text with the registered font (the PNG one also rasterizes it)
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // the font is a valid TrueType file compiled into the binary
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("svg") => draw(SVGBackend::new(path, SIZE).into_drawing_area(), title, curve).map_err(|e| err(&e)),
        Some("png") => draw(BitMapBackend::new(path, SIZE).into_drawing_area(), title, curve).map_err(|e| err(&e)),
        _ => bail!("--plot {}: expected a file name ending in .svg or .png", path.display()),
    }
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
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(180, 180, 180))
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
