//! The rows of the issue "every engine does only the work its tolerance needs": scenes read from
//! the example scene files (as `asnr evaluate` reads them) and evaluated by `metric::evaluate`
//! with the default settings at a ladder of tolerances, each graded against a reference named in
//! the report:
//!
//! - the spectrometer table (`examples/spectrometer.toml`: 1601 samples at 0.25 nm) against the
//!   same scene through `optics::Polychromatic` with `SpectralRule::Panels` (the per-interval
//!   rule) at tolerance 1e-12, and the numpy baseline `xtask/baselines/numpy_table.py` beside it;
//! - the decentred iris 0.15 (`examples/decentred-iris.toml`) against the exact reduction of
//!   [`crate::iris`];
//! - coma 0.5 µm on the paper scene (FFT path) against the Richardson extrapolation of fixed
//!   pupil samplings.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use metric::{Evaluation, Scene, evaluate};
use optics::{Polychromatic, Settings, SpectralRule};
use radiometry::Spectrum;

use crate::{Case, Family, Grid, Measured, Row, iris, time};

/// The designs given as data (issue "Your metalens"): a Binary 2 metalens and a meta-atom
/// library lens, with the numpy radial baseline beside the first.
pub(crate) const BINARY2: &str = "Binary 2 metalens: F/2.5, 50 nm";
pub(crate) const LIBRARY: &str = "library lens: F/2.5, 50 nm";
pub(crate) const NUMPY_RADIAL: &str = "xtask/baselines/numpy_radial.py";

/// Scene names of the rows (the table's first column).
pub(crate) const SPECTROMETER: &str = "spectrometer: F/2.5, 52 nm table";
pub(crate) const IRIS: &str = "decentred iris 0.15: F/2.5, 50 nm";
pub(crate) const COMA: &str = "coma 0.5 µm: F/2.5, 50 nm";

/// The spectrometer table and the numpy script, relative to the workspace root.
pub(crate) const TABLE: &str = "examples/data/spectrometer-825-52.csv";
pub(crate) const NUMPY_SCRIPT: &str = "xtask/baselines/numpy_table.py";

/// Iris decentre of `examples/decentred-iris.toml`, radii.
const IRIS_DECENTRE: f64 = 0.15;

/// Pupil samplings and the mean MTF at each.
pub(crate) type Samplings = Vec<(usize, f64)>;

/// What the report says about the references of these rows.
pub(crate) struct Notes {
    /// Spectrometer: (reference mean MTF, seconds, its work).
    pub spectrometer: Option<(f64, f64, String)>,
    /// numpy: the interpreter used and the version, or why the row was skipped.
    pub numpy: Result<(String, String), String>,
    /// Decentred iris 0.15: (reference, tangential, sagittal, seconds, check at decentre 0).
    pub iris: Option<(f64, f64, f64, f64, f64)>,
    /// Coma: (extrapolated reference, observed order, the samplings and their means).
    pub coma: Option<(f64, f64, Samplings)>,
    /// Binary 2 metalens: (reference mean MTF, seconds, its work); library lens: (mean, seconds).
    pub binary2: Option<(f64, f64, String)>,
    pub library: Option<(f64, f64, String)>,
    /// numpy radial baseline: the numpy version, or why the row was skipped.
    pub numpy_radial: Result<String, String>,
}

impl Notes {
    pub(crate) fn new() -> Notes {
        Notes {
            spectrometer: None,
            numpy: Err("numpy row not run".to_owned()),
            iris: None,
            coma: None,
            binary2: None,
            library: None,
            numpy_radial: Err("numpy radial row not run".to_owned()),
        }
    }
}

/// The workspace root (inputs are read from the repository, whatever the output folder).
pub(crate) fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("bench is one level below the root").to_path_buf()
}

/// A scene file of the repository with `--set` overrides, as `asnr evaluate` reads it.
fn load(file: &str, overrides: &[String]) -> Scene {
    let path = root().join(file);
    scene::load(Some(&path), overrides).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn work(e: &Evaluation) -> String {
    let n = &e.numerics;
    let engine = if n.engine.starts_with("fft") { format!("{}; ", n.engine) } else { String::new() };
    if n.spectral_evaluations > 0 {
        // per-frequency product integration: each OTF value chose its own spectral points
        return format!(
            "{engine}{} spectral panels, {} OTF values, {} single-wavelength OTFs",
            n.spectral_panels, n.otf_evaluations, n.spectral_evaluations
        );
    }
    format!(
        "{engine}{} spectral panels, {} spectral nodes, {} OTF values",
        n.spectral_panels, n.spectral_nodes, n.otf_evaluations
    )
}

fn measure(grid: &Grid, scene: &Scene) -> Measured {
    let (micros, repeats, e) = time(grid.budget, grid.min_repeats, || evaluate(scene).unwrap());
    (micros, repeats, e.mean_mtf, work(&e))
}

fn row(case: &'static str, family: Family, setting: String, reference: f64, measured: Measured) -> Row {
    let (micros, repeats, mean, work) = measured;
    let error = (mean - reference).abs() / reference;
    eprintln!("  {:<22} {setting:<16} error {error:.2e}  {micros:>12.1} µs", family.name());
    Row { case, family, setting, mean_mtf: mean, error, micros, repeats, work }
}

/// The spectrometer rows and the numpy rows beside them.
pub(crate) fn spectrometer(grid: &Grid, python: Option<&Path>, rows: &mut Vec<Row>, notes: &mut Notes) {
    eprintln!("{SPECTROMETER}:");
    // the reference: the same scene, today's per-interval rule at 1e-12, straight through optics
    // (the detected spectrum built as metric::evaluate builds it, radiance × QE × λ, paper SI
    // eq. S8, and the optics called directly: the reference's mean is the optics' alone)
    let (reference, seconds, reference_work) = panels_reference("examples/spectrometer.toml");
    eprintln!("  reference (Panels, 1e-12) {reference:.15} in {seconds:.1} s ({reference_work})");
    notes.spectrometer = Some((reference, seconds, reference_work));
    for &t in grid.ladder {
        let scene = load("examples/spectrometer.toml", &[format!("options.tolerance={t:e}")]);
        rows.push(row(SPECTROMETER, Family::Default, format!("tol {t:e}"), reference, measure(grid, &scene)));
    }
    notes.numpy = match python {
        None => Err("numpy not available: row skipped (run `cargo xtask accuracy`, which prepares it)".to_owned()),
        Some(python) => numpy(grid, python, reference, rows),
    };
    if let Err(why) = &notes.numpy {
        eprintln!("  {why}");
    }
}

/// The reference of a scene file: its detected spectrum (radiance × QE × λ, as
/// `metric::evaluate` builds it) through `optics::Polychromatic` with the per-interval spectral
/// rule at 1e-12; (mean, seconds, work).
fn panels_reference(file: &str) -> (f64, f64, String) {
    let scene = load(file, &[]);
    let camera = scene.camera();
    let detected = Spectrum::product(vec![
        scene.radiance().clone(),
        camera.quantum_efficiency().clone(),
        Spectrum::Linear { slope: 1.0 },
    ]);
    let settings = Settings { spectral_rule: SpectralRule::Panels, tolerance: 1e-12, ..Settings::default() };
    let started = Instant::now();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let poly = Polychromatic::with_settings(scene.lens(), &detected, scene.field(), camera.nyquist(), pixel, settings)
        .unwrap();
    let (reference, w) = poly.mean_mtf();
    let seconds = started.elapsed().as_secs_f64();
    let work = format!(
        "{} spectral panels, {} spectral nodes, {} OTF values, {} sign changes",
        w.spectral_panels, w.spectral_nodes, w.otf_evaluations, w.sign_changes
    );
    (reference, seconds, work)
}

/// The rows of the designs given as data: the Binary 2 metalens (`examples/phase-binary2.toml`)
/// at the ladder's tolerances against the per-interval rule at 1e-12, the numpy radial baseline
/// beside it, and the meta-atom library lens (`examples/library.toml`) at the default tolerance
/// against its own per-interval reference.
pub(crate) fn designs(grid: &Grid, python: Option<&Path>, rows: &mut Vec<Row>, notes: &mut Notes) {
    eprintln!("{BINARY2}:");
    let (reference, seconds, work) = panels_reference("examples/phase-binary2.toml");
    eprintln!("  reference (Panels, 1e-12) {reference:.15} in {seconds:.1} s ({work})");
    notes.binary2 = Some((reference, seconds, work));
    for &t in grid.ladder {
        let scene = load("examples/phase-binary2.toml", &[format!("options.tolerance={t:e}")]);
        rows.push(row(BINARY2, Family::Default, format!("tol {t:e}"), reference, measure(grid, &scene)));
    }
    notes.numpy_radial = match python {
        None => {
            Err("numpy not available: radial row skipped (run `cargo xtask accuracy`, which prepares it)".to_owned())
        }
        Some(python) => numpy_radial(grid, python, reference, rows),
    };
    eprintln!("{LIBRARY}:");
    let (reference, seconds, work) = panels_reference("examples/library.toml");
    eprintln!("  reference (Panels, 1e-12) {reference:.15} in {seconds:.1} s ({work})");
    notes.library = Some((reference, seconds, work));
    let scene = load("examples/library.toml", &[]);
    rows.push(row(LIBRARY, Family::Default, "tol 1e-6".to_owned(), reference, measure(grid, &scene)));
}

/// The numpy radial script at each of its settings (nλ, nν, nt, nv); its numpy version, or why not.
fn numpy_radial(grid: &Grid, python: &Path, reference: f64, rows: &mut Vec<Row>) -> Result<String, String> {
    let mut version = String::new();
    for &(nl, nnu, nt, nv) in grid.numpy_radial_settings {
        let args = [
            "--nl".to_owned(),
            nl.to_string(),
            "--nnu".to_owned(),
            nnu.to_string(),
            "--nt".to_owned(),
            nt.to_string(),
            "--nv".to_owned(),
            nv.to_string(),
            "--seconds".to_owned(),
            format!("{}", grid.numpy_seconds),
        ];
        let run = baseline(python, NUMPY_RADIAL, &args, "numpy radial row skipped")?;
        let (mean, millis, runs) = (run.mean, run.millis, run.runs);
        version = run.version;
        let work = format!("{nl} λ × {nnu} ν × {nt} t × {nv} v = {} integrand values", nl * nnu * nt * nv);
        rows.push(row(
            BINARY2,
            Family::Numpy,
            format!("nλ = {nl}, nν = {nnu}, nt = {nt}, nv = {nv}"),
            reference,
            (millis * 1e3, runs, mean, work),
        ));
    }
    Ok(version)
}

/// What a baseline script printed: its mean MTF, median time (ms), runs and numpy version.
struct Baseline {
    mean: f64,
    millis: f64,
    runs: usize,
    version: String,
}

/// Runs the baseline `script` (relative to the root) with `args`, numpy's BLAS held to one
/// thread, and reads its `key=value` lines; a message starting with `skipped` if it cannot.
fn baseline(python: &Path, script: &str, args: &[String], skipped: &str) -> Result<Baseline, String> {
    let output = Command::new(python)
        .arg(root().join(script))
        .args(args)
        .envs([("OMP_NUM_THREADS", "1"), ("OPENBLAS_NUM_THREADS", "1"), ("MKL_NUM_THREADS", "1")])
        .output()
        .map_err(|e| format!("numpy not available: {skipped} ({} could not be started: {e})", python.display()))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        return Err(format!(
            "numpy not available: {skipped} ({script} failed: {})",
            stderr.lines().last().unwrap_or("no message")
        ));
    }
    let text = String::from_utf8_lossy(&output.stdout);
    let value = |key: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
            .map(str::to_owned)
            .ok_or_else(|| format!("{skipped}: {script} printed no `{key}=`"))
    };
    let number =
        |key: &str| -> Result<f64, String> { value(key)?.parse().map_err(|e| format!("{skipped}: {key}: {e}")) };
    Ok(Baseline {
        mean: number("mean_mtf")?,
        millis: number("median_ms")?,
        runs: value("runs")?.parse().map_err(|e| format!("{skipped}: runs: {e}"))?,
        version: value("numpy")?,
    })
}

/// Runs the numpy script at each of its settings; the interpreter and numpy version, or why not.
fn numpy(grid: &Grid, python: &Path, reference: f64, rows: &mut Vec<Row>) -> Result<(String, String), String> {
    let mut version = String::new();
    for &(nl, nnu, nt) in grid.numpy_settings {
        let args = [
            root().join(TABLE).display().to_string(),
            "--nl".to_owned(),
            nl.to_string(),
            "--nnu".to_owned(),
            nnu.to_string(),
            "--nt".to_owned(),
            nt.to_string(),
            "--seconds".to_owned(),
            format!("{}", grid.numpy_seconds),
        ];
        let run = baseline(python, NUMPY_SCRIPT, &args, "numpy row skipped")?;
        let (mean, millis, runs) = (run.mean, run.millis, run.runs);
        version = run.version;
        let work = format!("{nl} λ nodes × {nnu} ν × {nt} t = {} kernel values", nl * nnu * nt);
        rows.push(row(
            SPECTROMETER,
            Family::Numpy,
            format!("nλ = {nl}, nν = {nnu}, nt = {nt}"),
            reference,
            (millis * 1e3, runs, mean, work),
        ));
    }
    Ok((python.display().to_string(), version))
}

/// The decentred-iris rows (0.15, default settings) against the exact reduction; `sagittal` is
/// the centred lens's reference mean MTF of `case` (the paper case). Also returns the exact
/// reference at decentre 0.1 for the fixed-N FFT rows.
pub(crate) fn decentred_iris(grid: &Grid, case: &Case, sagittal: f64, rows: &mut Vec<Row>, notes: &mut Notes) -> f64 {
    eprintln!("{IRIS}:");
    let started = Instant::now();
    let tangential = iris::tangential_mean_mtf(case, IRIS_DECENTRE, 1e-12);
    let seconds = started.elapsed().as_secs_f64();
    let reference = 0.5 * (tangential + sagittal);
    // the reduction's own check: at decentre 0 it is the centred lens, optics::reference::mean_mtf
    let centred = iris::tangential_mean_mtf(case, 0.0, 1e-12);
    let check = (centred - sagittal).abs() / sagittal;
    eprintln!(
        "  reference {reference:.15} (tangential {tangential:.15}, sagittal {sagittal:.15}) in {seconds:.1} s; \
         at decentre 0: {check:.1e} from optics::reference::mean_mtf"
    );
    notes.iris = Some((reference, tangential, sagittal, seconds, check));
    for &t in grid.iris_tolerances {
        let scene = load("examples/decentred-iris.toml", &[format!("options.tolerance={t:e}")]);
        rows.push(row(IRIS, Family::Default, format!("tol {t:e}"), reference, measure(grid, &scene)));
    }
    0.5 * (iris::tangential_mean_mtf(case, 0.1, 1e-12) + sagittal)
}

/// The coma rows (default settings: the overlap quadrature) against the Richardson
/// extrapolation of fixed FFT samplings.
pub(crate) fn coma(grid: &Grid, rows: &mut Vec<Row>, notes: &mut Notes) {
    eprintln!("{COMA}:");
    let coma = |extra: String| load("examples/paper-theory.toml", &["lens.coma_um=0.5".to_owned(), extra]);
    let mut samplings = Vec::new();
    for &n in grid.coma_reference {
        let started = Instant::now();
        let mean = evaluate(&coma(format!("options.pupil_samples={n}"))).unwrap().mean_mtf;
        eprintln!("  N = {n}: {mean:.15} ({:.1} s)", started.elapsed().as_secs_f64());
        samplings.push((n, mean));
    }
    let [(_, coarse), (_, mid), (_, fine)] = samplings[..] else { panic!("three samplings") };
    let order = ((coarse - mid) / (mid - fine)).abs().log2();
    let reference = fine + (fine - mid) / (2f64.powf(order) - 1.0);
    eprintln!("  reference (Richardson) {reference:.15}, observed order {order:.2}");
    notes.coma = Some((reference, order, samplings));
    for &t in grid.coma_tolerances {
        let scene = coma(format!("options.tolerance={t:e}"));
        rows.push(row(COMA, Family::Default, format!("tol {t:e}"), reference, measure(grid, &scene)));
    }
}
