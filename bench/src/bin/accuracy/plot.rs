//! `docs/benchmarks/accuracy.svg`: error against time, log–log, one panel per table (the mean
//! MTF of an ASNR point above, the OTF kernels below). Text in DejaVu Sans, embedded.

use std::path::Path;

use plotters::prelude::*;

use crate::Family;
use crate::Row;
use crate::kernels::{DEFOCUS_WAVES, Kernel, KernelRow};
use crate::tolerance::{COMA, IRIS, SPECTROMETER};

static FONT: &[u8] = include_bytes!("../../../../cli/assets/DejaVuSans.ttf");

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// Errors are drawn no lower than this (the axis floor).
const FLOOR: f64 = 1e-16;

/// Okabe–Ito colours (colour-blind safe), with black and grey for the seventh and eighth.
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(230, 159, 0),
    RGBColor(0, 0, 0),
    RGBColor(128, 128, 128),
];

#[derive(Clone, Copy, Debug, PartialEq)]
enum Marker {
    Circle,
    Square,
    Triangle,
    Diamond,
    Cross,
}

/// Colour and marker of a mean-MTF method family.
fn family_style(family: Family) -> (RGBColor, Marker) {
    match family {
        Family::ClosedForm => (PALETTE[0], Marker::Circle),
        Family::Quadrature => (PALETTE[1], Marker::Square),
        Family::Fft => (PALETTE[2], Marker::Triangle),
        Family::FftDecentred => (PALETTE[2], Marker::Square),
        Family::Table => (PALETTE[3], Marker::Diamond),
        Family::Uniform(3) => (PALETTE[4], Marker::Cross),
        Family::Uniform(5) => (PALETTE[5], Marker::Cross),
        Family::Uniform(_) => (PALETTE[7], Marker::Cross),
        Family::Hermite => (PALETTE[6], Marker::Circle),
        Family::Default => (PALETTE[6], Marker::Square),
        Family::Numpy => (NAVY, Marker::Diamond),
    }
}

/// Colours of the tolerance ladders, one per scene (beyond the Okabe–Ito eight).
const PURPLE: RGBColor = RGBColor(117, 63, 160);
const RED: RGBColor = RGBColor(200, 30, 30);
const BROWN: RGBColor = RGBColor(150, 100, 30);
const NAVY: RGBColor = RGBColor(30, 40, 120);

/// Colour, marker and key text of a family on a scene: the default-settings ladders get one
/// colour per scene.
fn style(case: &str, family: Family) -> (RGBColor, Marker, String) {
    let ladder = |colour, name: &str| (colour, Marker::Square, format!("default settings: {name}"));
    match (family, case) {
        (Family::Default, SPECTROMETER) => ladder(PURPLE, "spectrometer"),
        (Family::Default, IRIS) => ladder(RED, "decentred iris 0.15"),
        (Family::Default, COMA) => ladder(BROWN, "coma 0.5 µm"),
        (Family::Numpy, _) => (NAVY, Marker::Diamond, "numpy baseline: spectrometer".to_owned()),
        _ => {
            let (colour, marker) = family_style(family);
            (colour, marker, family.name())
        }
    }
}

/// Colour of an OTF kernel family.
fn kernel_colour(kernel: Kernel) -> RGBColor {
    match kernel {
        Kernel::Production => PALETTE[6],
        Kernel::ProductionQuadrature => PALETTE[7],
        Kernel::GaussLegendre(_) => PALETTE[0],
        Kernel::Hopkins(Some(_)) => PALETTE[1],
        Kernel::Hopkins(None) => PALETTE[3],
        Kernel::Geometric => PALETTE[2],
    }
}

/// Marker of a defocus in the kernel panel.
fn defocus_marker(index: usize) -> Marker {
    [Marker::Circle, Marker::Square, Marker::Triangle, Marker::Diamond, Marker::Cross][index % 5]
}

/// The outline of a diamond marker around `(x, y)` (backend pixels).
fn diamond(x: i32, y: i32) -> Vec<(i32, i32)> {
    vec![(x, y - 6), (x + 6, y), (x, y + 6), (x - 6, y), (x, y - 6)]
}

/// Draws `points` with `marker`, filled or outlined by `style`.
fn markers<DB: DrawingBackend>(chart: &mut Chart<'_, DB>, points: &[(f64, f64)], marker: Marker, style: ShapeStyle) {
    let cross = style.stroke_width(2);
    match marker {
        Marker::Circle => chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, style))),
        Marker::Square => {
            chart.draw_series(points.iter().map(|&p| EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], style)))
        }
        Marker::Triangle => chart.draw_series(points.iter().map(|&p| TriangleMarker::new(p, 5, style))),
        Marker::Diamond if style.filled => {
            chart.draw_series(points.iter().map(|&p| EmptyElement::at(p) + Polygon::new(diamond(0, 0), style)))
        }
        Marker::Diamond => {
            chart.draw_series(points.iter().map(|&p| EmptyElement::at(p) + PathElement::new(diamond(0, 0), style)))
        }
        Marker::Cross => chart.draw_series(points.iter().map(|&p| Cross::new(p, 4, cross))),
    }
    .unwrap();
}

/// The key beside a chart: one line per entry, a short line in the entry's colour (if any), its
/// marker (if any) and its text.
struct Key<'a, DB: DrawingBackend> {
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    y: i32,
}

impl<DB: DrawingBackend> Key<'_, DB> {
    fn entry(&mut self, text: &str, line: Option<ShapeStyle>, marker: Option<(Marker, ShapeStyle)>) {
        let (x, y) = (22, self.y);
        if let Some(style) = line {
            self.area.draw(&PathElement::new(vec![(x - 14, y), (x + 14, y)], style)).unwrap();
        }
        if let Some((marker, style)) = marker {
            let cross = style.stroke_width(2);
            match marker {
                Marker::Circle => self.area.draw(&Circle::new((x, y), 4, style)),
                Marker::Square => self.area.draw(&Rectangle::new([(x - 4, y - 4), (x + 4, y + 4)], style)),
                Marker::Triangle => self.area.draw(&TriangleMarker::new((x, y), 5, style)),
                Marker::Diamond if style.filled => self.area.draw(&Polygon::new(diamond(x, y), style)),
                Marker::Diamond => self.area.draw(&PathElement::new(diamond(x, y), style)),
                Marker::Cross => self.area.draw(&Cross::new((x, y), 4, cross)),
            }
            .unwrap();
        }
        let font = ("sans-serif", 13).into_font().color(&BLACK);
        self.area.draw(&Text::new(text.to_owned(), (x + 22, y - 7), font)).unwrap();
        self.y += 22;
    }

    fn gap(&mut self) {
        self.y += 10;
    }
}

fn chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    x_desc: &str,
    x: (f64, f64),
) -> Chart<'a, DB> {
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 19))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((x.0 * 0.5..x.1 * 2.0).log_scale(), (FLOOR * 0.5..10.0).log_scale())
        .unwrap();
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("error")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_label_formatter(&|v| if *v >= 1e5 { format!("{v:.0e}") } else { format!("{v:.0}") })
        .draw()
        .unwrap();
    chart
}

/// Width of the figure and of the key column beside each chart, pixels.
const WIDTH: u32 = 1180;
const KEY_WIDTH: u32 = 240;

/// The two panels; `cases` orders the scenes (the first drawn filled, the second outlined; the
/// tolerance ladders after them filled, each in its own colour).
pub(crate) fn draw(path: &Path, rows: &[Row], kernels: &[KernelRow], cases: &[&str]) {
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    draw_on(SVGBackend::new(path, (WIDTH, 1240)).into_drawing_area(), rows, kernels, cases);
}

fn draw_on<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    rows: &[Row],
    kernels: &[KernelRow],
    cases: &[&str],
) {
    root.fill(&WHITE).unwrap();
    let (upper, lower) = root.split_vertically(640);
    let (upper, upper_key) = upper.split_horizontally(WIDTH - KEY_WIDTH);
    let (lower, lower_key) = lower.split_horizontally(WIDTH - KEY_WIDTH);

    // mean MTF of an ASNR point: colour and marker per method, filled for the first scene
    let range = rows.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(r.micros), b.max(r.micros)));
    let mut top =
        chart(&upper, "Mean-MTF error against time per ASNR point", "time per point, µs (median, one core)", range);
    let mut key = Key { area: &upper_key, y: 70 };
    let mut keyed: Vec<String> = Vec::new();
    for (index, &case) in cases.iter().enumerate() {
        let filled = index != 1;
        let mut families: Vec<Family> = Vec::new();
        for r in rows.iter().filter(|r| r.case == case) {
            if !families.contains(&r.family) {
                families.push(r.family);
            }
        }
        for family in families {
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.case == case && r.family == family)
                .map(|r| (r.micros, r.error.max(FLOOR)))
                .collect();
            let (colour, marker, name) = style(case, family);
            let line = ShapeStyle::from(colour).stroke_width(if filled { 2 } else { 1 });
            top.draw_series(LineSeries::new(points.clone(), line)).unwrap();
            markers(&mut top, &points, marker, if filled { line.filled() } else { line });
            if !keyed.contains(&name) {
                key.entry(&name, Some(ShapeStyle::from(colour).stroke_width(2)), Some((marker, colour.filled())));
                keyed.push(name);
            }
        }
    }
    key.gap();
    for (index, case) in cases.iter().take(2).enumerate() {
        let style = if index == 0 { BLACK.filled() } else { ShapeStyle::from(BLACK).stroke_width(1) };
        key.entry(case, None, Some((Marker::Circle, style)));
    }

    // OTF kernels: colour per method, marker per defocus, lines through a method's settings
    let range = kernels
        .iter()
        .flat_map(|k| k.cells.iter())
        .fold((f64::INFINITY, 0.0f64), |(a, b), c| (a.min(c.nanos), b.max(c.nanos)));
    let mut bottom = chart(
        &lower,
        "OTF kernels: largest error over s against time per OTF value",
        "time per OTF value, ns (median)",
        range,
    );
    let mut key = Key { area: &lower_key, y: 70 };
    let mut colours: Vec<RGBColor> = Vec::new();
    for row in kernels {
        let colour = kernel_colour(row.kernel);
        if colours.contains(&colour) {
            continue;
        }
        colours.push(colour);
        let style = ShapeStyle::from(colour).stroke_width(2);
        let family: Vec<&KernelRow> = kernels.iter().filter(|k| kernel_colour(k.kernel) == colour).collect();
        for (index, _) in DEFOCUS_WAVES.iter().enumerate() {
            let points: Vec<(f64, f64)> =
                family.iter().map(|k| (k.cells[index].nanos, k.cells[index].abs.max(FLOOR))).collect();
            bottom.draw_series(LineSeries::new(points.clone(), ShapeStyle::from(colour).stroke_width(1))).unwrap();
            markers(&mut bottom, &points, defocus_marker(index), style.filled());
        }
        let name = match row.kernel {
            Kernel::Hopkins(None) => "Hopkins series, all terms".to_owned(),
            Kernel::Hopkins(Some(_)) => "Hopkins series, K terms".to_owned(),
            Kernel::GaussLegendre(_) => "Gauss–Legendre, n nodes".to_owned(),
            k => k.name().to_owned(),
        };
        key.entry(&name, Some(style), None);
    }
    key.gap();
    for (index, w) in DEFOCUS_WAVES.iter().enumerate() {
        key.entry(&format!("w = {w} waves"), None, Some((defocus_marker(index), BLACK.filled())));
    }
    root.present().unwrap();
}
