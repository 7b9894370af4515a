//! 2-D phase maps against the radial engine: the hyperbolic metalens of the phase-map tests
//! (F/2.5, f0 = 125 µm, R = 25 µm, λ0 = 800 nm; the paper's 50 nm Gaussian band, 5.2 µm pixels)
//! drawn as maps of 256², 1024² and 2048² cells across its diameter, each cell holding the
//! hyperbola's phase at its centre (`model = "phase"` with `phase_map`, docs/physics.md, "Phase
//! maps"), evaluated in this process at the default tolerances (the FFT path's sampling chosen
//! from 1e-4), against the same hyperbola as a radial Binary 2 profile on the radial engine.

use std::f64::consts::PI;
use std::sync::Arc;
use std::time::Instant;

use lenses::{Curve, Dispersion, PhaseLens, PhaseMapLens};
use metric::{Camera, Evaluation, Options, Scene, evaluate};
use optics::LensModel;
use optics::map::MapAperture;
use radiometry::{Gaussian, Spectrum};

use crate::sections::Tools;

const F_NUMBER: f64 = 2.5;
const F0: f64 = 125e-6;
const LAMBDA0: f64 = 800e-9;
const PIXEL: f64 = 5.2e-6;
const RADIUS: f64 = 0.5 * F0 / F_NUMBER;

fn evaluate_lens(lens: impl LensModel + 'static) -> Evaluation {
    let band = Spectrum::Gaussian(Gaussian::from_range(LAMBDA0, 50e-9, 1.0).unwrap());
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), band]);
    let camera = Camera::new(PIXEL, Spectrum::Constant(0.2), false).unwrap();
    evaluate(&Scene::new(Arc::new(lens), radiance, camera, 1.23e-3, Options::default()).unwrap()).unwrap()
}

/// The hyperbolic phase `−k0 (√(x² + y² + f0²) − f0)` at the centres of `n × n` cells spanning
/// the diameter (`PhaseMapLens::sampled_hyperbola`), as a lens.
fn map_lens(n: usize) -> PhaseMapLens {
    let pitch = 2.0 * RADIUS / n as f64;
    let map = PhaseMapLens::sampled_hyperbola(n, pitch, MapAperture::Circle, RADIUS, F0, LAMBDA0, |_, _| 0.0).unwrap();
    PhaseMapLens::new(
        F_NUMBER,
        F0,
        LAMBDA0,
        Arc::new(map),
        Dispersion::GeometricPhase,
        Curve::Constant(0.15),
        Curve::Constant(0.55),
        "hyperbolic map".into(),
    )
    .unwrap()
}

/// The stated cell error `2 (1 − S_min)`: `S` the design-order amplitude `sinc(g_x p/λ) sinc(g_y p/λ)`
/// of a cell of `pitch`, smallest at the aperture's edge on a diagonal (docs/physics.md, "Phase maps").
fn cell_bound(pitch: f64) -> f64 {
    let sinc = |u: f64| (PI * u).sin() / (PI * u);
    let corner = RADIUS / 2f64.sqrt();
    let r = (2.0 * corner * corner + F0 * F0).sqrt();
    let u = pitch / LAMBDA0 * corner / r;
    2.0 * (1.0 - sinc(u) * sinc(u))
}

/// The section (`--only phase-maps`).
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let coefficients = lenses::hyperbolic_binary2(F0, LAMBDA0, RADIUS, 6);
    let profile = lenses::binary2_profile(&coefficients, 1.0, RADIUS, RADIUS).ok()?;
    let radial = PhaseLens::new(
        F_NUMBER,
        F0,
        LAMBDA0,
        Arc::new(profile),
        None,
        Dispersion::GeometricPhase,
        Curve::Constant(0.15),
        Curve::Constant(0.55),
        "hyperbolic".into(),
    )
    .ok()?;
    let started = Instant::now();
    let reference = evaluate_lens(radial);
    let radial_s = started.elapsed().as_secs_f64();
    eprintln!("phase maps: radial engine {:.7} in {radial_s:.2} s ({})", reference.mean_mtf, reference.numerics.engine);
    let load = crate::load_average();
    let sizes: &[usize] = if tools.quick { &[256, 1024] } else { &[256, 1024, 2048] };
    let mut rows = String::new();
    for &n in sizes {
        let pitch = 2.0 * RADIUS / n as f64;
        let started = Instant::now();
        let lens = map_lens(n);
        let build_s = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let e = evaluate_lens(lens);
        let evaluate_s = started.elapsed().as_secs_f64();
        let error = (e.mean_mtf - reference.mean_mtf).abs() / reference.mean_mtf;
        eprintln!(
            "  {n}² cells of {:.4} µm: mean MTF {:.7} ({error:.1e}), map {build_s:.2} s, evaluate {evaluate_s:.2} s ({})",
            pitch * 1e6,
            e.mean_mtf,
            e.numerics.engine
        );
        rows.push_str(&format!(
            "| {n}² | {:.4} | {:.3} | {:.3} | {:.7} | {error:.1e} | {:.1e} | {} |\n",
            pitch * 1e6,
            build_s,
            evaluate_s,
            e.mean_mtf,
            cell_bound(pitch),
            e.numerics.engine
        ));
    }
    Some(format!(
        "## 2-D phase maps against the radial engine\n\n\
         The hyperbolic metalens of the phase-map tests (F/2.5, f0 = 125 µm, R = 25 µm, λ0 = 800 nm, \
         the paper's 50 nm Gaussian band, 5.2 µm pixels, geometric phase) drawn as a `phase_map` of n × n \
         cells across its diameter, each cell holding the hyperbola's phase at its centre, and evaluated \
         in one process at the default tolerances (the FFT path's pupil sampling chosen from 1e-4 for the \
         mean MTF averaged over azimuth). The reference is the same hyperbola as a radial Binary 2 profile \
         on the radial engine: mean MTF {:.7} in {radial_s:.3} s. \"Map\" is the time to fill and check \
         the map (`PhaseMap::new`, `PhaseMapLens::new`), \"evaluate\" the whole evaluation; the error falls \
         as the pitch squared (the cells' staircase) until the FFT path's own tolerance. The bound is the \
         stated cell error 2 (1 − S_min) (docs/physics.md, \"Phase maps\"). Load average at the start: \
         {load}.\n\n\
         | map | cell, µm | map, s | evaluate, s | mean MTF | error vs radial | stated bound | engine |\n\
         |---|---|---|---|---|---|---|---|\n{rows}\n\
         Generated by `cargo xtask accuracy --only phase-maps`.\n",
        reference.mean_mtf
    ))
}
