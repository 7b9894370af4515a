//! scratch
use optics::reference::*;
use std::time::Instant;

fn gauss_scene_run(f: f64, range_nm: f64, pitch_um: f64, pix: bool, tol: f64) -> (f64, f64) {
    let c = 800e-9;
    let sigma = range_nm * 1e-9 / (2.0 * 2f64.sqrt());
    let dens = move |l: f64| l * (-(l - c) * (l - c) / (2.0 * sigma * sigma)).exp();
    let scene = ReferenceScene {
        density: &dens,
        lambda_min: (c - 12.0 * sigma).max(1e-9),
        lambda_max: c + 12.0 * sigma,
        breakpoints: &[],
        f_number: f,
        focal_length_m: 3.36e-3,
        design_wavelength_m: 800e-9,
        pixel_pitch_m: pitch_um * 1e-6,
        pixel_mtf: pix,
    };
    let t = Instant::now();
    let q = mean_mtf_quadrature(&scene, tol);
    let dt = t.elapsed().as_secs_f64();
    println!("F/{f} {range_nm}nm {pitch_um}um pix={pix} tol={tol:e}: {:.15} err {:e} evals {} conv {} {dt:.3}s", q.value, q.error, q.evaluations, q.converged);
    (q.value, dt)
}

#[test]
fn scratch_otf() {
    for (s, w, v) in [(0.1, 0.0, 0.87289), (0.1, 0.5, 0.74209), (0.1, 1.0, 0.42665), (0.2, 1.0, -0.01441), (0.5, 0.25, 0.28747), (0.05, 2.0, 0.41297), (0.1, 2.0, -0.08396)] {
        println!("{s} {w} {} {v}", otf_defocus(s, w));
    }
}
#[test]
fn scratch_paper() {
    for tol in [1e-6, 1e-9, 1e-10, 1e-11] {
        gauss_scene_run(2.5, 50.0, 5.2, false, tol);
    }
    gauss_scene_run(2.5, 10.0, 5.2, false, 1e-9);
    gauss_scene_run(2.5, 100.0, 5.2, false, 1e-9);
    gauss_scene_run(2.5, 200.0, 5.2, false, 1e-9);
}
#[test]
fn scratch_hard1() {
    gauss_scene_run(1.4, 50.0, 2.0, false, 1e-9);
}
#[test]
fn scratch_hard2() {
    gauss_scene_run(1.4, 200.0, 2.0, false, 1e-9);
}
