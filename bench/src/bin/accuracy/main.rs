//! The accuracy-versus-time report (`cargo xtask accuracy`): for every way of computing the
//! mean MTF of a scene and every way of computing the monochromatic OTF, its error against a
//! converged reference and its time; writes `BENCHMARKS.md` and `docs/benchmarks/accuracy.svg`
//! (error against time, log–log, one panel per table).
//!
//! Mean MTF of one ASNR point (paper scene F/2.5, 50 nm and hard scene F/1.4, 200 nm), against
//! `optics::reference::mean_mtf` at 1e-12 (computed once per scene):
//! - the production engines through `metric::evaluate`: closed form and spectral quadrature at
//!   tolerances 1e-2 … 1e-12, FFT pupils of 64 … 1024 samples, and the spectral quadrature of a
//!   tabulated spectrum (`Spectrum::Sampled`, 1 nm and finer);
//! - spectral rules with the production monochromatic OTF at each node and one fixed, converged
//!   frequency rule ([`spectral`]): uniform nodes over ±kσ and Gauss–Hermite.
//!
//! OTF kernels ([`kernels`]): `optics::defocus_otf`, fixed Gauss–Legendre node counts, Hopkins'
//! series cut after K terms and the geometric approximation, against
//! `optics::reference::otf_defocus`, per defocus from 0.25 to 300 waves.
//!
//! Tolerance ladders ([`tolerance`]): scenes read from the example scene files and evaluated with
//! the default settings at tolerances 1e-2 … 1e-10 — the spectrometer table (against the
//! per-interval spectral rule at 1e-12, with the numpy baseline `xtask/baselines/numpy_table.py`
//! beside it), the decentred iris 0.15 (against the exact reduction of [`iris`]) and coma 0.5 µm
//! (against a Richardson extrapolation) — the 40 × 100 map and a 384 × 384 × 45 PSF stack through
//! the release `asnr` ([`map`], and the stand-alone section [`psf_stack`]),
//! and the targets against them ([`targets`]).
//!
//! Times are medians of repeated single-threaded calls in this (release) process.
//!
//! Run: `cargo run --release -p asnr-bench --bin accuracy -- [--quick] [--designs] [--asnr BIN]
//! [--python PY] [OUT_DIR]` (`--designs`: the rows of the designs given as data alone, written to
//! `OUT_DIR/target/BENCHMARKS-designs.md`, not BENCHMARKS.md; `--sweep`: the sweep against numpy
//! and the 5000-row efficiency table ([`sweep`]) alone, into `OUT_DIR/target/BENCHMARKS-sweep.md`): `--asnr` the release `asnr` binary for the map, `--python` an interpreter with
//! numpy for the baseline (`cargo xtask accuracy` builds the one and prepares the other); the
//! map or the numpy rows are skipped, and the report says so, without them. `--only NAME[,NAME]`:
//! only the named stand-alone sections ([`sections`]), each replacing its own section of the
//! existing `OUT_DIR/BENCHMARKS.md`.

mod closed_ladder;
mod design;
mod exact_map;
mod fft_azimuth;
mod freeform;
mod gds_scale;
mod gradients;
mod gradients_aperture;
mod gradients_bias;
mod gradients_design;
mod gradients_families;
mod gradients_keys;
mod iris;
mod kernels;
mod map;
mod map_numpy;
mod otf_paths;
mod phase_maps;
mod plot;
mod process;
mod psf_stack;
mod report;
mod sections;
mod sfr;
mod spectral;
mod sweep;
mod table_rule;
mod tables;
mod targets;
mod tolerance;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::time::{Duration, Instant};

use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, Evaluation, Options, Scene, evaluate};
use optics::reference::{ReferenceScene, mean_mtf};
use radiometry::{Gaussian, Sampled, Spectrum};

/// Design focal length of the paper's lens (docs/physics.md, "The metric"), m.
const F0: f64 = 3.36e-3;
/// Design wavelength, m.
const LAMBDA0: f64 = 800e-9;
/// Pixel pitch, m.
const PIXEL_PITCH: f64 = 5.2e-6;

/// A scene of the report: the paper's lens at an F-number, a Gaussian spectrum of a range.
struct Case {
    name: &'static str,
    f_number: f64,
    range_m: f64,
}

impl Case {
    /// σ of the Gaussian: the spectral range is 2√2 σ (docs/physics.md, "Spectra").
    fn sigma(&self) -> f64 {
        self.range_m / (2.0 * 2f64.sqrt())
    }

    /// Defocus in waves at the pupil edge of the chromatic lens at `lambda` (docs/physics.md,
    /// "Chromatic lens"): `W020 = (1 − λ/λ0) f0/(8 F#²)`, `w = W020/λ`.
    fn waves(&self, lambda: f64) -> f64 {
        (1.0 - lambda / LAMBDA0) * F0 / (8.0 * self.f_number * self.f_number) / lambda
    }
}

/// How a mean-MTF row was computed: one colour and marker each in the plot.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Family {
    ClosedForm,
    Quadrature,
    Fft,
    /// The FFT path through the iris of SI Fig. S3, decentred by 10 % of the radius.
    FftDecentred,
    Table,
    /// Uniform (trapezoid) nodes over ±k σ.
    Uniform(u32),
    Hermite,
    /// `metric::evaluate` of a scene file with the default settings but the tolerance.
    Default,
    /// The numpy baseline script.
    Numpy,
}

impl Family {
    fn name(self) -> String {
        match self {
            Family::ClosedForm => "closed form".into(),
            Family::Quadrature => "spectral quadrature".into(),
            Family::Fft => "FFT pupil".into(),
            Family::FftDecentred => "FFT, decentred iris".into(),
            Family::Table => "tabulated spectrum".into(),
            Family::Uniform(k) => format!("uniform ±{k}σ"),
            Family::Hermite => "Gauss–Hermite".into(),
            Family::Default => "default settings".into(),
            Family::Numpy => "numpy baseline".into(),
        }
    }
}

/// One mean-MTF row: a method and setting on a scene.
struct Row {
    case: &'static str,
    family: Family,
    setting: String,
    mean_mtf: f64,
    error: f64,
    micros: f64,
    repeats: usize,
    work: String,
}

/// A measured row: median µs, timed runs, mean MTF, work done.
type Measured = (f64, usize, f64, String);

/// Median wall time of `f` in µs over repeats filling about `budget`, the number of timed runs,
/// and the first run's result. At least `min_repeats` runs follow the first, or one if the first
/// took over a second; when the first alone exceeds the budget and `min_repeats` is 0, it is the
/// only sample.
///
/// Each call starts with nothing remembered of a measured spectrum (`optics::forget_remembered`:
/// a sweep's points share a table's polynomial and moments, one evaluation does not).
fn time<T>(budget: Duration, min_repeats: usize, mut f: impl FnMut() -> T) -> (f64, usize, T) {
    let mut f = move || {
        optics::forget_remembered();
        f()
    };
    let first = Instant::now();
    let result = f();
    let once = first.elapsed().as_secs_f64();
    let floor = if once > 1.0 { min_repeats.min(1) } else { min_repeats };
    let repeats = ((budget.as_secs_f64() / once.max(1e-7)) as usize).clamp(floor, 2001);
    let mut samples: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed().as_secs_f64()
        })
        .collect();
    if samples.is_empty() {
        samples.push(once);
    }
    samples.sort_by(f64::total_cmp);
    (samples[samples.len() / 2] * 1e6, samples.len(), result)
}

/// The paper's chromatic lens at the case's F-number (τ1 = 0.15, T = 0.55), optionally through
/// an explicit circular aperture (which sends it down the FFT path).
fn lens(case: &Case, aperture: bool) -> ChromaticMetalens {
    let lens =
        ChromaticMetalens::new(case.f_number, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
    if aperture { lens.with_aperture(optics::fft::Aperture::circle()) } else { lens }
}

/// The case through the paper's iris decentred by 10 % of the pupil radius (SI Fig. S3): only
/// the FFT path can compute it.
fn decentred_scene(case: &Case, pupil_samples: usize) -> Scene {
    let iris = optics::fft::Aperture::circle().decentred(0.1, 0.0).unwrap();
    let lens =
        ChromaticMetalens::new(case.f_number, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
    let filter = Gaussian::from_range(LAMBDA0, case.range_m, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(5.2e-6, Spectrum::Constant(0.2), false).unwrap();
    let options = Options { pupil_samples: Some(pupil_samples), exact_irises: false, ..Options::default() };
    Scene::new(Arc::new(lens.with_aperture(iris)), radiance, camera, 1.23e-3, options).unwrap()
}

/// A flat source behind the Gaussian filter of the case (docs/physics.md, "The metric": photon count
/// ∝ range), QE 0.2, 5.2 µm pixels.
fn scene(case: &Case, aperture: bool, options: Options) -> Scene {
    let filter = Gaussian::from_range(LAMBDA0, case.range_m, 1.0).unwrap();
    scene_with(case, aperture, Spectrum::Gaussian(filter), options)
}

/// [`scene()`] with the Gaussian filter tabulated every `spacing_m` over ±7σ (the production
/// window of a Gaussian factor, 2.6e-12 of its area outside): piecewise linear between samples.
/// The λ of eq. S8 is applied by `evaluate`, as for every scene. Returns the sample count too.
fn table_scene(case: &Case, spacing_m: f64, options: Options) -> (Scene, usize) {
    let filter = Gaussian::from_range(LAMBDA0, case.range_m, 1.0).unwrap();
    let half = (7.0 * case.sigma() / spacing_m).ceil() as i64;
    let wavelengths: Vec<f64> = (-half..=half).map(|j| LAMBDA0 + j as f64 * spacing_m).collect();
    let values = wavelengths.iter().map(|&l| filter.value(l)).collect();
    let samples = wavelengths.len();
    let table = Sampled::new(wavelengths, values).unwrap();
    (scene_with(case, false, Spectrum::Sampled(table), options), samples)
}

fn scene_with(case: &Case, aperture: bool, filter: Spectrum, options: Options) -> Scene {
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), filter]);
    let camera = Camera::new(PIXEL_PITCH, Spectrum::Constant(0.2), false).unwrap();
    Scene::new(Arc::new(lens(case, aperture)), radiance, camera, 1.23e-3, options).unwrap()
}

/// The converged mean MTF of the case: `optics::reference::mean_mtf` at 1e-12 with the detected
/// density `λ · G(λ)` over ±12σ.
fn reference(case: &Case) -> f64 {
    let sigma = case.sigma();
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
            pixel_pitch_m: PIXEL_PITCH,
            pixel_mtf: false,
        },
        1e-12,
    )
}

/// What the report measured besides the rows: for its header.
struct Context {
    quick: bool,
    /// Per case: (name, reference mean MTF, seconds the reference took).
    references: Vec<(&'static str, f64, f64)>,
    /// Per case: the fixed frequency rule of the spectral-rule rows.
    frequency_rules: Vec<(&'static str, spectral::FrequencyRule)>,
    /// The decentred-iris reference of the fixed-N rows: (case, exact reference, Richardson
    /// extrapolation, observed order).
    decentred: Option<(&'static str, f64, f64, f64)>,
    /// The references of the tolerance ladders.
    notes: tolerance::Notes,
    /// The map, when the `asnr` binary was given.
    map: Option<map::Map>,
    /// The design search and tolerance run, when the `asnr` binary was given (not with --quick).
    design: Option<design::DesignBench>,
    /// The sweep against numpy and the 5000-row efficiency table.
    sweep: Option<sweep::SweepBench>,
    /// The Binary 2 metalens as a whole process against numpy's script, when the `asnr` binary
    /// and Python were given.
    binary2_process: Option<process::ProcessBench>,
    /// The load average (1, 5, 15 min) at the start and at the end of the run.
    load: (String, String),
}

/// Settings of one run: the full report or the `--quick` smoke run.
struct Grid {
    budget: Duration,
    min_repeats: usize,
    tolerances: &'static [f64],
    pupil_samples: &'static [usize],
    /// Table spacings (m) for the paper scene and the hard scene.
    table_spacings: [&'static [f64]; 2],
    uniform_sigmas: &'static [u32],
    uniform_nodes: &'static [usize],
    hermite_nodes: &'static [usize],
    /// Tolerances of the spectrometer ladder.
    ladder: &'static [f64],
    /// numpy settings (nλ, nν, nt) and the time budget of each, s.
    numpy_settings: &'static [(usize, usize, usize)],
    numpy_seconds: f64,
    /// numpy radial baseline settings (nλ, nν, nt, nv).
    numpy_radial_settings: &'static [(usize, usize, usize, usize)],
    /// Tolerances of the decentred-iris rows.
    iris_tolerances: &'static [f64],
    /// Fixed pupil samplings of the coma reference (coarse, mid, fine) and the tolerances.
    coma_reference: &'static [usize],
    coma_tolerances: &'static [f64],
    /// Runs of the map at the default tolerance.
    map_runs: usize,
}

const FULL: Grid = Grid {
    budget: Duration::from_millis(400),
    min_repeats: 3,
    tolerances: &[1e-2, 1e-4, 1e-6, 1e-7, 1e-8, 1e-10, 1e-12],
    pupil_samples: &[64, 128, 256, 512, 1024],
    table_spacings: [&[1e-9, 0.1e-9], &[2e-9, 1e-9]],
    uniform_sigmas: &[3, 5, 7],
    uniform_nodes: &[8, 16, 32, 64, 128, 256, 512],
    hermite_nodes: &[4, 8, 16, 32, 64, 128],
    ladder: &[1e-2, 1e-4, 1e-6, 1e-8, 1e-10],
    numpy_settings: &[(96, 32, 32), (128, 48, 48)],
    numpy_seconds: 2.0,
    numpy_radial_settings: &[(24, 16, 24, 6), (28, 20, 28, 6), (32, 24, 32, 8), (48, 32, 48, 12)],
    iris_tolerances: &[1e-4, 1e-6, 1e-8],
    coma_reference: &[256, 512, 1024],
    coma_tolerances: &[1e-2, 1e-3, 1e-4, 1e-5],
    map_runs: 3,
};

const QUICK: Grid = Grid {
    budget: Duration::from_millis(20),
    min_repeats: 0,
    // the targets' tolerances (1e-7 on the paper point, 1e-6 on the hard one) and a loose one
    tolerances: &[1e-2, 1e-6, 1e-7],
    pupil_samples: &[64],
    table_spacings: [&[2e-9], &[]],
    uniform_sigmas: &[3, 7],
    uniform_nodes: &[16, 64],
    hermite_nodes: &[8, 32],
    ladder: &[1e-2, 1e-6],
    numpy_settings: &[(96, 32, 32)],
    numpy_seconds: 0.5,
    numpy_radial_settings: &[(32, 24, 32, 8)],
    iris_tolerances: &[1e-6],
    coma_reference: &[64, 128, 256],
    coma_tolerances: &[1e-3, 1e-4],
    map_runs: 1,
};

fn main() {
    let (mut quick, mut asnr, mut python, mut out) = (false, None, None, PathBuf::from("."));
    let mut designs_only = false;
    let mut sweep_only = false;
    let mut asnr_python: Option<PathBuf> = None;
    let mut only: Option<String> = None;
    let mut keys: Option<String> = None;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--quick" => quick = true,
            "--designs" => designs_only = true,
            "--sweep" => sweep_only = true,
            "--asnr" => asnr = Some(PathBuf::from(args.next().expect("--asnr BIN"))),
            "--python" => python = Some(PathBuf::from(args.next().expect("--python PY"))),
            "--asnr-python" => asnr_python = Some(PathBuf::from(args.next().expect("--asnr-python PY"))),
            "--only" => only = Some(args.next().expect("--only NAME[,NAME]")),
            "--keys" => keys = Some(args.next().expect("--keys CASE[,CASE]")),
            flag if flag.starts_with("--") => panic!("unknown flag {flag}"),
            _ => out = PathBuf::from(arg),
        }
    }
    let grid = if quick { QUICK } else { FULL };
    let tools = sections::Tools {
        asnr: asnr.clone(),
        python: python.clone(),
        asnr_python: asnr_python.clone(),
        root: out.clone(),
        quick,
    };
    if let Some(names) = keys {
        // the gradient's cost rows of the named cases (gradients_keys: a part of their names),
        // in a file beside BENCHMARKS.md
        let names: Vec<&str> = names.split(',').map(str::trim).filter(|n| !n.is_empty()).collect();
        let md = gradients_keys::markdown_of(&tools, &names).unwrap_or_default();
        let path = out.join("target/BENCHMARKS-keys.md");
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, md).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    if let Some(names) = only {
        // the named stand-alone sections alone, spliced into the existing BENCHMARKS.md
        let chosen = sections::select(&names).unwrap_or_else(|e| {
            eprintln!("accuracy: {e}");
            std::process::exit(2)
        });
        let path = sections::benchmarks(&out);
        let mut md = std::fs::read_to_string(&path).unwrap_or_default();
        sections::render_into(&mut md, &chosen, &tools);
        std::fs::write(&path, md).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let load_at_start = load_average();
    let cases = [
        Case { name: "paper: F/2.5, 50 nm", f_number: 2.5, range_m: 50e-9 },
        Case { name: "hard: F/1.4, 200 nm", f_number: 1.4, range_m: 200e-9 },
    ];
    let mut rows = Vec::new();
    let mut context = Context {
        quick,
        references: Vec::new(),
        frequency_rules: Vec::new(),
        decentred: None,
        notes: tolerance::Notes::new(),
        map: None,
        design: None,
        sweep: None,
        binary2_process: None,
        load: (String::new(), String::new()),
    };
    if sweep_only {
        // the sweep section alone, in a file beside BENCHMARKS.md
        let Some(bin) = asnr.as_deref() else { panic!("--sweep needs --asnr BIN") };
        context.sweep = sweep::measure(bin, python.as_deref(), &out, grid.map_runs);
        context.load = (load_at_start, load_average());
        let md = report::markdown(&rows, &[], &context);
        let path = out.join("target/BENCHMARKS-sweep.md");
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, md).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    if designs_only {
        // the designs' rows alone, in a file beside BENCHMARKS.md (their section and targets)
        tolerance::designs(&grid, python.as_deref(), &mut rows, &mut context.notes);
        context.binary2_process = binary2_process(asnr.as_deref(), python.as_deref(), &out, &rows, &context.notes);
        context.load = (load_at_start, load_average());
        let md = report::markdown(&rows, &[], &context);
        std::fs::create_dir_all(&out).unwrap();
        let path = out.join("target/BENCHMARKS-designs.md");
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, md).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let mut decentred_rows = Vec::new();
    let mut decentred_exact = None;
    for (index, case) in cases.iter().enumerate() {
        let started = Instant::now();
        let exact = reference(case);
        let seconds = started.elapsed().as_secs_f64();
        eprintln!("{}: reference mean MTF {exact:.15} ({seconds:.1} s)", case.name);
        context.references.push((case.name, exact, seconds));
        let mut push = |family: Family, setting: String, (micros, repeats, mean, work): Measured| {
            let error = (mean - exact).abs() / exact;
            eprintln!("  {:<22} {setting:<16} error {error:.2e}  {micros:>12.1} µs", family.name());
            rows.push(Row { case: case.name, family, setting, mean_mtf: mean, error, micros, repeats, work });
        };
        let production = |scene: &Scene, work: &dyn Fn(&Evaluation) -> String| -> Measured {
            let (micros, repeats, e) = time(grid.budget, grid.min_repeats, || evaluate(scene).unwrap());
            (micros, repeats, e.mean_mtf, work(&e))
        };
        let nodes_work = |e: &Evaluation| {
            let n = &e.numerics;
            if n.spectral_evaluations > 0 {
                format!("{} OTF values, {} single-wavelength OTFs", n.otf_evaluations, n.spectral_evaluations)
            } else {
                format!("{} OTF values, {} spectral nodes", n.otf_evaluations, n.spectral_nodes)
            }
        };
        for &t in grid.tolerances {
            let options = Options { tolerance: t, ..Options::default() };
            let closed_work = |e: &Evaluation| {
                let n = &e.numerics;
                format!("{} OTF values, {} E(c)", n.otf_evaluations, n.closed_form_evaluations)
            };
            push(Family::ClosedForm, format!("tol {t:e}"), production(&scene(case, false, options), &closed_work));
        }
        // the hard scene's spectral quadrature takes about a second a point: not in a smoke run
        let tolerances = if quick && index == 1 { &[] } else { grid.tolerances };
        for &t in tolerances {
            let options = Options { tolerance: t, closed_form: false, ..Options::default() };
            push(Family::Quadrature, format!("tol {t:e}"), production(&scene(case, false, options), &nodes_work));
        }
        if case.f_number >= 2.0 {
            for &n in grid.pupil_samples {
                // (the circle sampled on the FFT path, not reduced to the exact one)
                let options = Options { pupil_samples: Some(n), exact_irises: false, ..Options::default() };
                push(Family::Fft, format!("N = {n}"), production(&scene(case, true, options), &nodes_work));
            }
        }
        if case.f_number >= 2.0 {
            // the decentred iris 0.15 of examples/decentred-iris.toml at the default settings,
            // and the exact reference of the iris 0.1 below (iris.rs: the centred pupil with a
            // tilt), both against this case's sagittal (centred) reference
            decentred_exact =
                Some(tolerance::decentred_iris(&grid, case, exact, &mut decentred_rows, &mut context.notes));
        }
        if case.f_number >= 2.0 && grid.pupil_samples.len() >= 3 {
            // the iris decentred by 0.1 at fixed samplings, against the exact reference; the
            // Richardson extrapolation of the three finest samplings (observed order p from their
            // differences), the reference before the exact one existed, is reported beside it
            let mut measured = Vec::new();
            for &n in grid.pupil_samples {
                measured.push((n, production(&decentred_scene(case, n), &nodes_work)));
            }
            let m: Vec<f64> = measured.iter().rev().take(3).map(|(_, r)| r.2).collect();
            let (fine, mid, coarse) = (m[0], m[1], m[2]);
            let p = ((coarse - mid) / (mid - fine)).abs().log2();
            let extrapolated = fine + (fine - mid) / (2f64.powf(p) - 1.0);
            let exact = decentred_exact.expect("computed above");
            eprintln!(
                "  decentred iris 0.1: exact reference {exact:.12}, Richardson {extrapolated:.12} (observed order {p:.2})"
            );
            context.decentred = Some((case.name, exact, extrapolated, p));
            for (n, (micros, repeats, mean, work)) in measured {
                let error = (mean - exact).abs() / exact;
                let setting = format!("N = {n}");
                eprintln!("  {:<22} {setting:<16} error {error:.2e}  {micros:>12.1} µs", Family::FftDecentred.name());
                decentred_rows.push(Row {
                    case: case.name,
                    family: Family::FftDecentred,
                    setting,
                    mean_mtf: mean,
                    error,
                    micros,
                    repeats,
                    work,
                });
            }
        }
        for &spacing in grid.table_spacings[index] {
            let options = Options { closed_form: false, ..Options::default() };
            let (table, samples) = table_scene(case, spacing, options);
            let work = |e: &Evaluation| format!("{samples} table samples; {}", nodes_work(e));
            push(Family::Table, format!("{} nm", spacing * 1e9), production(&table, &work));
        }
        // spectral rules with one fixed frequency rule, converged on the finest of them
        let finest: Vec<Vec<spectral::Node>> = [
            grid.uniform_sigmas.iter().max().map(|&k| spectral::uniform(case, k, max(grid.uniform_nodes))),
            Some(spectral::hermite(case, &optics::quad::gauss_hermite(max(grid.hermite_nodes)))),
        ]
        .into_iter()
        .flatten()
        .collect();
        let rule = spectral::FrequencyRule::converged(case, &finest);
        eprintln!("  frequency rule: {} panels (last doubling changed the mean by {:.1e})", rule.panels, rule.change);
        for &k in grid.uniform_sigmas {
            for &n in grid.uniform_nodes {
                let (micros, repeats, (mean, evaluations)) =
                    time(grid.budget, grid.min_repeats, || rule.mean_mtf(case, &spectral::uniform(case, k, n)));
                let work = format!("{n} spectral nodes × {evaluations} ν = {} OTF values", n * evaluations);
                push(Family::Uniform(k), format!("n = {n}"), (micros, repeats, mean, work));
            }
        }
        for &n in grid.hermite_nodes {
            // the standard rule is computed once, as the production caches its Gauss–Legendre rule
            let standard = optics::quad::gauss_hermite(n);
            let (micros, repeats, (mean, evaluations)) =
                time(grid.budget, grid.min_repeats, || rule.mean_mtf(case, &spectral::hermite(case, &standard)));
            let used = spectral::hermite(case, &standard).len();
            let work = format!("{used} spectral nodes × {evaluations} ν = {} OTF values", used * evaluations);
            push(Family::Hermite, format!("n = {n}"), (micros, repeats, mean, work));
        }
        context.frequency_rules.push((case.name, rule));
    }
    rows.extend(decentred_rows);
    tolerance::spectrometer(&grid, python.as_deref(), &mut rows, &mut context.notes);
    tolerance::coma(&grid, &mut rows, &mut context.notes);
    tolerance::designs(&grid, python.as_deref(), &mut rows, &mut context.notes);
    context.binary2_process = binary2_process(asnr.as_deref(), python.as_deref(), &out, &rows, &context.notes);
    context.map = asnr.as_deref().map(|bin| {
        let mut m = map::measure(bin, grid.map_runs);
        m.python = asnr_python.as_deref().and_then(|py| map::measure_python(py, bin, &out, grid.map_runs));
        m
    });
    if !quick {
        context.design = asnr.as_deref().and_then(|bin| design::measure(bin, &out));
        context.sweep = asnr.as_deref().and_then(|bin| sweep::measure(bin, python.as_deref(), &out, grid.map_runs));
    }
    let kernel_rows = kernels::measure(quick);
    context.load = (load_at_start, load_average());
    let mut md = report::markdown(&rows, &kernel_rows, &context);
    let every: Vec<&sections::Section> = sections::SECTIONS.iter().collect();
    sections::render_into(&mut md, &every, &tools);
    std::fs::create_dir_all(&out).unwrap();
    let path = sections::benchmarks(&out);
    std::fs::write(&path, md).unwrap();
    let svg = out.join("docs/benchmarks/accuracy.svg");
    std::fs::create_dir_all(svg.parent().unwrap()).unwrap();
    let names: Vec<&str> = cases
        .iter()
        .map(|c| c.name)
        .chain([tolerance::SPECTROMETER, tolerance::IRIS, tolerance::COMA, tolerance::BINARY2])
        .collect();
    plot::draw(&svg, &rows, &kernel_rows, &names);
    eprintln!("wrote {} and {}", path.display(), svg.display());
}

/// The Binary 2 metalens as a whole process against numpy's script ([`process`]), when the
/// binary, Python and the designs' reference are there.
fn binary2_process(
    asnr: Option<&Path>,
    python: Option<&Path>,
    root: &Path,
    rows: &[Row],
    notes: &tolerance::Notes,
) -> Option<process::ProcessBench> {
    let reference = notes.binary2.as_ref()?.0;
    process::measure(asnr?, python?, root, rows, reference)
}

/// `/proc/loadavg`'s 1, 5 and 15 minute averages, or "unknown".
pub(crate) fn load_average() -> String {
    std::fs::read_to_string(Path::new("/proc/loadavg"))
        .ok()
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".to_owned())
}

fn max(values: &[usize]) -> usize {
    values.iter().copied().max().unwrap_or(1)
}

/// The CPU time (user + system) of this process's waited-for children so far, s: fields 16 and
/// 17 (`cutime`, `cstime`) of `/proc/self/stat` in clock ticks, over `getconf CLK_TCK`. None
/// where either is not there.
pub(crate) fn children_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // the fields after the command name in parentheses start at field 3
    let fields: Vec<&str> = stat[stat.rfind(')')? + 1..].split_whitespace().collect();
    let ticks = fields.get(13)?.parse::<f64>().ok()? + fields.get(14)?.parse::<f64>().ok()?;
    let output = Command::new("getconf").arg("CLK_TCK").output().ok()?;
    let per_second: f64 = String::from_utf8_lossy(&output.stdout).trim().parse().ok()?;
    (per_second > 0.0).then(|| ticks / per_second)
}

/// The median of `v` (the upper one of an even count); `v` is not empty.
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
