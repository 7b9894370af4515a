//! The accuracy-versus-time report (`cargo xtask accuracy`): for each way of computing the mean
//! MTF of a scene, its relative error against a converged reference and its time per ASNR point;
//! writes `BENCHMARKS.md` and `docs/benchmarks/accuracy.svg` (error against time, log–log).
//!
//! Methods: the closed-form spectral engine and the spectral-quadrature engine at tolerances
//! 1e-2 … 1e-12, and the FFT path at 64 … 1024 pupil samples. The reference is the slow
//! independent integrator of `optics::reference` (printed y-form OTF, adaptive Gauss–Kronrod in
//! every dimension) at 1e-12. Times are medians of repeated single-threaded `evaluate` calls in
//! this (release) process.
//!
//! Run: `cargo run --release -p metric --example accuracy -- [--quick] [OUT_DIR]`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, Options, Scene, evaluate};
use optics::reference::{ReferenceScene, mean_mtf};
use plotters::prelude::*;
use radiometry::{Gaussian, Spectrum};

const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;
static FONT: &[u8] = include_bytes!("../../cli/assets/DejaVuSans.ttf");

struct Case {
    name: &'static str,
    f_number: f64,
    range_m: f64,
}

struct Row {
    case: &'static str,
    method: String,
    setting: String,
    mean_mtf: f64,
    error: f64,
    micros: f64,
    work: String,
}

fn scene(case: &Case, aperture: bool, options: Options) -> Scene {
    let mut lens =
        ChromaticMetalens::new(case.f_number, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
    if aperture {
        lens = lens.with_aperture(optics::fft::Aperture::circle());
    }
    let filter = Gaussian::from_range(LAMBDA0, case.range_m, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(5.2e-6, Spectrum::Constant(0.2), false).unwrap();
    Scene::new(Arc::new(lens), radiance, camera, 1.23e-3, options).unwrap()
}

fn reference(case: &Case) -> f64 {
    let sigma = case.range_m / (2.0 * 2f64.sqrt());
    let density = move |l: f64| l * (-0.5 * ((l - LAMBDA0) / sigma).powi(2)).exp();
    mean_mtf(
        &ReferenceScene {
            density: &density,
            lambda_min: (LAMBDA0 - 12.0 * sigma).max(1e-3 * LAMBDA0),
            lambda_max: LAMBDA0 + 12.0 * sigma,
            breakpoints: &[],
            f_number: case.f_number,
            focal_length_m: F0,
            design_wavelength_m: LAMBDA0,
            pixel_pitch_m: 5.2e-6,
            pixel_mtf: false,
        },
        1e-12,
    )
}

/// Median time of `evaluate(scene)` over repeats filling about `budget`.
fn time(scene: &Scene, budget: Duration) -> (f64, metric::Evaluation) {
    let first = Instant::now();
    let result = evaluate(scene).unwrap();
    let once = first.elapsed();
    let repeats = ((budget.as_secs_f64() / once.as_secs_f64().max(1e-7)) as usize).clamp(3, 2001);
    let mut samples: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(evaluate(std::hint::black_box(scene)).unwrap());
            t.elapsed().as_secs_f64()
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    (samples[samples.len() / 2] * 1e6, result)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let out = args.iter().find(|a| !a.starts_with("--")).map_or_else(|| PathBuf::from("."), PathBuf::from);
    let budget = Duration::from_millis(if quick { 50 } else { 400 });
    let cases = [
        Case { name: "paper: F/2.5, 50 nm", f_number: 2.5, range_m: 50e-9 },
        Case { name: "hard: F/1.4, 200 nm", f_number: 1.4, range_m: 200e-9 },
    ];
    let tolerances: &[f64] = if quick { &[1e-3, 1e-6, 1e-9] } else { &[1e-2, 1e-4, 1e-6, 1e-7, 1e-8, 1e-10, 1e-12] };
    let samples: &[usize] = if quick { &[64, 128] } else { &[64, 128, 256, 512, 1024] };
    let mut rows = Vec::new();
    for case in &cases {
        let exact = reference(case);
        eprintln!("{}: reference mean MTF {exact:.15}", case.name);
        let mut push = |method: &str, setting: String, (micros, e): (f64, metric::Evaluation)| {
            let n = &e.numerics;
            let work = if n.engine.starts_with("closed") {
                format!("{} OTF values, {} E(c)", n.otf_evaluations, n.closed_form_evaluations)
            } else {
                format!("{} OTF values, {} spectral nodes", n.otf_evaluations, n.spectral_nodes)
            };
            let error = (e.mean_mtf - exact).abs() / exact;
            eprintln!("  {method:<22} {setting:<14} error {error:.2e}  {micros:>12.1} µs");
            rows.push(Row {
                case: case.name,
                method: method.into(),
                setting,
                mean_mtf: e.mean_mtf,
                error,
                micros,
                work,
            });
        };
        for &t in tolerances {
            let options = Options { tolerance: t, ..Options::default() };
            push("closed form", format!("tol {t:e}"), time(&scene(case, false, options), budget));
        }
        for &t in tolerances {
            let options = Options { tolerance: t, closed_form: false, ..Options::default() };
            push("spectral quadrature", format!("tol {t:e}"), time(&scene(case, false, options), budget));
        }
        if case.f_number >= 2.0 {
            for &n in samples {
                let options = Options { pupil_samples: n, ..Options::default() };
                push("FFT pupil", format!("N = {n}"), time(&scene(case, true, options), budget));
            }
        }
    }
    let md = report(&rows, quick);
    std::fs::create_dir_all(&out).unwrap();
    let path = out.join("BENCHMARKS.md");
    std::fs::write(&path, md).unwrap();
    let svg = out.join("docs/benchmarks/accuracy.svg");
    std::fs::create_dir_all(svg.parent().unwrap()).unwrap();
    plot(&svg, &rows);
    eprintln!("wrote {} and {}", path.display(), svg.display());
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines().find(|l| l.starts_with("model name")).map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| "unknown CPU".to_owned());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} cores available, {} {}", std::env::consts::OS, std::env::consts::ARCH)
}

fn report(rows: &[Row], quick: bool) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Benchmarks: accuracy against time\n");
    let _ = writeln!(
        s,
        "Regenerate with `cargo xtask accuracy` (this file and `docs/benchmarks/accuracy.svg`){}.\n",
        if quick { " — this copy is from the reduced `--quick` grid" } else { "" }
    );
    let _ = writeln!(
        s,
        "Machine: {}. Times are medians of single-threaded `metric::evaluate` calls (one ASNR point,",
        machine()
    );
    let _ =
        writeln!(s, "everything included: photoelectrons, glare, Fraunhofer check, mean MTF) in a release build.\n");
    let _ = writeln!(
        s,
        "Error: relative error of the mean MTF (hence of the ASNR) against `optics::reference` at 1e-12 (printed \
         y-form OTF, adaptive Gauss–Kronrod in ν, λ and y). The spectral quadrature keeps the Gaussian to ±7σ, \
         so it cannot go below ~2e-12; the reference's own error is ~1e-12.\n"
    );
    let _ = writeln!(s, "![error against time](docs/benchmarks/accuracy.svg)\n");
    let _ = writeln!(s, "| scene | method | setting | mean MTF | relative error | time per point | work |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.12} | {:.1e} | {} | {} |",
            r.case,
            r.method,
            r.setting,
            r.mean_mtf,
            r.error,
            if r.micros >= 1000.0 { format!("{:.2} ms", r.micros / 1000.0) } else { format!("{:.1} µs", r.micros) },
            r.work
        );
    }
    s.push_str(TARGETS);
    s
}

/// The targets and where they stand (kept in sync with the measured table by hand).
const TARGETS: &str = include_str!("accuracy-targets.md");

fn plot(path: &Path, rows: &[Row]) {
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).unwrap();
    let (tmin, tmax) = rows.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(r.micros), b.max(r.micros)));
    let mut chart = ChartBuilder::on(&root)
        .caption("Mean-MTF error against time per ASNR point", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((tmin * 0.5..tmax * 2.0).log_scale(), (1e-16..1.0).log_scale())
        .unwrap();
    chart
        .configure_mesh()
        .x_desc("time per point, µs (median, one core)")
        .y_desc("relative error")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_label_formatter(&|v| format!("{v:.0}"))
        .draw()
        .unwrap();
    let series: Vec<(String, RGBColor)> = {
        let mut v: Vec<(String, RGBColor)> = Vec::new();
        let palette = [
            RGBColor(0, 114, 178),
            RGBColor(213, 94, 0),
            RGBColor(0, 158, 115),
            RGBColor(204, 121, 167),
            RGBColor(86, 180, 233),
            RGBColor(230, 159, 0),
        ];
        for r in rows {
            let key = format!("{} — {}", r.method, r.case);
            if !v.iter().any(|(k, _)| *k == key) {
                let c = palette[v.len() % palette.len()];
                v.push((key, c));
            }
        }
        v
    };
    for (i, (key, colour)) in series.iter().enumerate() {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| format!("{} — {}", r.method, r.case) == *key)
            .map(|r| (r.micros, r.error.max(1e-16)))
            .collect();
        let style = ShapeStyle::from(colour).stroke_width(2);
        let dashed = i % 2 == 1;
        chart
            .draw_series(LineSeries::new(points.clone(), if dashed { style.stroke_width(1) } else { style }))
            .unwrap()
            .label(key.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, style.filled()))).unwrap();
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 14))
        .draw()
        .unwrap();
    root.present().unwrap();
}
