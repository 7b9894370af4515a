//! The FFT path's sampling chosen from the tolerance and judged by the mean MTF averaged over
//! azimuth (docs/physics.md, "Pupils without rotational symmetry"): 0.5 µm of coma and 0.2 µm of
//! astigmatism (Noll Z6) on the paper scene at tolerances from 1e-3 down to 1e-5, each mean
//! against the Richardson extrapolation (order 1.5) of the fixed samplings 1024 and 2048, with
//! the pupil samples chosen and the time of the whole evaluation.

use std::sync::Arc;
use std::time::Instant;

use lenses::{ChromaticMetalens, Curve, WithZernike};
use metric::{Camera, Evaluation, Options, Scene, evaluate};
use optics::LensModel;
use radiometry::{Gaussian, Spectrum};

use crate::sections::Tools;

const LAMBDA0: f64 = 800e-9;

fn paper_lens() -> ChromaticMetalens {
    ChromaticMetalens::new(2.5, 3.36e-3, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap()
}

/// CPU seconds this thread has run (`/proc/thread-self/schedstat`, nanoseconds on the CPU), where
/// the system reports it: the evaluation runs on the calling thread, so its CPU time is the
/// difference, which a loaded machine inflates far less than the wall time.
fn thread_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = stat.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// The paper's theory scene (F/2.5, 50 nm Gaussian band at 800 nm, 5.2 µm pixels) with `lens`:
/// the evaluation, its wall time and its CPU time (seconds; the CPU time where the system
/// reports it).
fn run(lens: Arc<dyn LensModel>, options: Options) -> Option<(Evaluation, f64, Option<f64>)> {
    let band = Spectrum::Gaussian(Gaussian::from_range(LAMBDA0, 50e-9, 1.0).ok()?);
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), band]);
    let camera = Camera::new(5.2e-6, Spectrum::Constant(0.2), false).ok()?;
    let scene = Scene::new(lens, radiance, camera, 1.23e-3, options).ok()?;
    let (started, cpu) = (Instant::now(), thread_cpu_seconds());
    match evaluate(&scene) {
        Ok(e) => {
            let cpu = cpu.zip(thread_cpu_seconds()).map(|(a, b)| b - a);
            Some((e, started.elapsed().as_secs_f64(), cpu))
        }
        Err(e) => {
            eprintln!("  refused: {e}");
            None
        }
    }
}

/// The section (`--only fft-azimuth`).
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let lenses: [(&str, Arc<dyn LensModel>); 2] = [
        ("coma W131 = 0.5 µm", Arc::new(paper_lens().with_seidel(0.0, 0.5e-6, 0.0, 0.0))),
        ("astigmatism Z6 = 0.2 µm", Arc::new(WithZernike::new(paper_lens(), vec![(6, 0.2e-6)], LAMBDA0).ok()?)),
    ];
    let tolerances: &[f64] = if tools.quick { &[1e-3, 1e-4] } else { &[1e-3, 3e-4, 1e-4, 3e-5, 1e-5] };
    let load = crate::load_average();
    let mut rows = String::new();
    for (name, lens) in &lenses {
        let fixed = |n: usize| {
            run(lens.clone(), Options { pupil_samples: Some(n), tolerance: 1e-5, ..Options::default() })
                .map(|(e, _, _)| e.mean_mtf)
        };
        let (mid, fine) = (fixed(1024)?, fixed(2048)?);
        let reference = fine + (fine - mid) / (2f64.powf(1.5) - 1.0);
        eprintln!("fft over azimuth, {name}: reference {reference:.8} (1024: {mid:.8}, 2048: {fine:.8})");
        // the FFT path for both pupils (the coma's default is the overlap quadrature, `overlap`
        // off here), then the coma by the overlap quadrature
        let runs = tolerances
            .iter()
            .map(|&t| (t, false))
            .chain(tolerances.iter().filter(|_| name.starts_with("coma")).map(|&t| (t, true)));
        for (tolerance, overlap) in runs {
            let options = Options { tolerance, fft_tolerance: Some(tolerance), overlap, ..Options::default() };
            match run(lens.clone(), options) {
                Some((e, seconds, cpu)) => {
                    let error = (e.mean_mtf - reference).abs() / reference;
                    let cpu = cpu.map_or_else(|| "n/a".to_owned(), |c| format!("{c:.3}"));
                    eprintln!(
                        "  {tolerance:.0e}: {:.8} ({error:.1e}), {seconds:.2} s, CPU {cpu} s, {}",
                        e.mean_mtf, e.numerics.engine
                    );
                    let engine = if overlap { "overlap quadrature".to_owned() } else { e.numerics.engine.clone() };
                    rows.push_str(&format!(
                        "| {name} | {tolerance:.0e} | {:.8} | {error:.1e} | {seconds:.3} | {cpu} | {engine} |\n",
                        e.mean_mtf
                    ));
                }
                None => rows.push_str(&format!("| {name} | {tolerance:.0e} | refused | | | | |\n")),
            }
        }
    }
    Some(format!(
        "## The FFT path's sampling judged over azimuth\n\n\
         The paper's theory scene (F/2.5, 50 nm Gaussian band at 800 nm, 5.2 µm pixels) with 0.5 µm of \
         coma and with 0.2 µm of astigmatism (Noll Z6), on the FFT path with the pupil sampling chosen \
         from the tolerance (`options.tolerance`, the FFT tolerance set to the same), judged by the mean \
         MTF averaged over azimuth (docs/physics.md, \"Pupils without rotational symmetry\"). The error is \
         against the Richardson extrapolation (order 1.5) of the fixed samplings 1024 and 2048 (their own \
         difference bounds its error at about 2e-6); the tests hold the same means to 2-D quadratures \
         written in them (`cargo test -p asnr-metric --test metric fft_ -- --nocapture`). Time is the whole \
         evaluation in one process, wall and CPU (the evaluating thread's, from \
         `/proc/thread-self/schedstat`; a busy machine inflates the wall time far more). The last rows \
         take the same coma by the quadrature over the pupils' overlap, the default for a full pupil with \
         Seidel terms (docs/physics.md, \"Analytic 2-D pupils by quadrature over the overlap\"); the FFT \
         rows above turn it off (`metric::Options::overlap`). Load average at the start: {load}.\n\n\
         | pupil | tolerance | mean MTF | error | time, s | CPU, s | engine |\n\
         |---|---|---|---|---|---|---|\n{rows}\n\
         Generated by `cargo xtask accuracy --only fft-azimuth`.\n"
    ))
}
