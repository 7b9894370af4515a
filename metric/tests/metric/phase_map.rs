//! 2-D phase maps (`lenses::PhaseMapLens`, docs/physics.md "Phase maps"): each sample held over
//! its cell, the design order's field `a sinc(g_x p/λ) sinc(g_y p/λ) e^{iψ}` on the FFT path.
//!
//! - the hyperbolic design drawn as a map equals the radial engine's continuous profile within the
//!   stated cell error, `2 (1 − S_min)` (S the cells' design-order amplitude), plus the FFT path's
//!   tolerance;
//! - a square aperture with the separable cubic phase `α (x³ + y³)`: its 2-D OTF is the product of
//!   two 1-D OTFs, computed here by Gauss–Legendre, whose mean over azimuth the engine matches.

use std::f64::consts::PI;
use std::sync::Arc;

use lenses::{Curve, Dispersion, PhaseLens, PhaseMapLens};
use metric::{Camera, Evaluation, Options, Scene, evaluate};
use optics::LensModel;
use optics::map::{MapAperture, PhaseMap};
use optics::quad::gauss_legendre;
use radiometry::{Gaussian, Line, Spectrum};

/// A small lens (R = 25 µm, F/2.5) so that a fine map stays small: the OTF depends on the
/// normalized frequency `s = ν λ F#` only.
const F_NUMBER: f64 = 2.5;
const F0: f64 = 125e-6;
const LAMBDA0: f64 = 800e-9;
const PIXEL: f64 = 5.2e-6;

fn radius() -> f64 {
    0.5 * F0 / F_NUMBER
}

fn scene(lens: impl LensModel + 'static, filter: Spectrum) -> Evaluation {
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), filter]);
    let camera = Camera::new(PIXEL, Spectrum::Constant(0.2), false).unwrap();
    let options = Options { pupil_samples: Some(256), ..Options::default() };
    evaluate(&Scene::new(Arc::new(lens), radiance, camera, 1.23e-3, options).unwrap()).unwrap()
}

/// The hyperbolic phase plus `extra(x, y)` (radians) at the centres of `n × n` cells of `pitch`
/// centred on the axis (`PhaseMapLens::sampled_hyperbola`).
fn map(n: usize, pitch: f64, aperture: MapAperture, extra: impl Fn(f64, f64) -> f64) -> PhaseMap {
    PhaseMapLens::sampled_hyperbola(n, pitch, aperture, radius(), F0, LAMBDA0, extra).unwrap()
}

fn map_lens(map: PhaseMap) -> PhaseMapLens {
    PhaseMapLens::new(
        F_NUMBER,
        F0,
        LAMBDA0,
        Arc::new(map),
        Dispersion::GeometricPhase,
        Curve::Constant(0.15),
        Curve::Constant(0.55),
        "test map".into(),
    )
    .unwrap()
}

/// The smallest design-order amplitude of a cell of `pitch` in the aperture (at its farthest
/// point, where the sphere's gradient is largest), at λ0.
fn smallest_amplitude(pitch: f64, corner: f64) -> f64 {
    let sinc = |u: f64| (PI * u).sin() / (PI * u);
    let r = (2.0 * corner * corner + F0 * F0).sqrt();
    let u = pitch / LAMBDA0 * corner / r;
    sinc(u) * sinc(u)
}

/// The hyperbolic metalens as a 2-D map of 0.2 µm cells (250 × 250) on a 50 nm band: the mean
/// MTF equals the radial engine's (the continuous Binary 2 profile of the same hyperbola) within
/// `2 (1 − S_min)` plus 1e-4 (the FFT path at 256 samples); halving the pitch shrinks the
/// difference (the cell's staircase error goes as p²).
#[test]
fn radially_symmetric_map_equals_the_radial_engine() {
    let band = || Spectrum::Gaussian(Gaussian::from_range(LAMBDA0, 50e-9, 1.0).unwrap());
    let coefficients = lenses::hyperbolic_binary2(F0, LAMBDA0, radius(), 6);
    let profile = lenses::binary2_profile(&coefficients, 1.0, radius(), radius()).unwrap();
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
    .unwrap();
    let reference = scene(radial, band()).mean_mtf;
    let mut differences = Vec::new();
    for (n, pitch) in [(125, 0.4e-6), (250, 0.2e-6)] {
        let e = scene(map_lens(map(n, pitch, MapAperture::Circle, |_, _| 0.0)), band());
        assert!(e.numerics.engine.contains("fft"), "{}", e.numerics.engine);
        let bound = 2.0 * (1.0 - smallest_amplitude(pitch, radius() / 2f64.sqrt())) + 1e-4;
        let rel = (e.mean_mtf - reference).abs() / reference;
        eprintln!(
            "{n} × {n} cells of {} µm: mean {:.6} vs radial {reference:.6} ({rel:.1e}, bound {bound:.1e})",
            pitch * 1e6,
            e.mean_mtf
        );
        assert!(rel <= bound, "{} vs {reference}: {rel:e} > {bound:e}", e.mean_mtf);
        differences.push(rel);
    }
    assert!(differences[1] < differences[0], "{differences:?}");
}

/// The 1-D OTF of `w(x) = c x³` (metres) on `[−1, 1]` at lag `d`, normalized by the length 2:
/// `(1/2) ∫ exp(ik[w(x + d/2) − w(x − d/2)]) dx` over the overlap `|x| ≤ 1 − |d|/2`, with
/// `w(x + d/2) − w(x − d/2) = c (3 x² d + d³/4)`; 64 Gauss–Legendre points.
fn cubic_otf(d: f64, c: f64, k: f64, rule: &[(f64, f64)]) -> (f64, f64) {
    let half = 1.0 - 0.5 * d.abs();
    let (mut re, mut im) = (0.0, 0.0);
    for &(x, w) in rule {
        let u = half * x;
        let (sin, cos) = (k * c * (3.0 * u * u * d + d * d * d / 4.0)).sin_cos();
        re += w * cos;
        im += w * sin;
    }
    (re * half / 2.0, im * half / 2.0)
}

/// A square aperture (side 2R = f0/F#) with the hyperbolic focus and the cubic phase
/// `α ((x/R)³ + (y/R)³)`, α = 6 rad (about one wave at the corner), at one wavelength: the
/// pupil is separable, so its OTF is `O1(d_x) O1(d_y)` ([`cubic_otf`]); the mean over azimuth of
/// `|O1 O1|` (48 azimuths, 24 × 6 Gauss–Legendre in ν) is the engine's within `2 (1 − S_min)`
/// plus 1e-4. The square collects 4/π of the circle's light.
#[test]
fn square_cubic_map_is_the_product_of_two_one_dimensional_otfs() {
    let alpha = 6.0;
    let r = radius();
    let pitch = 0.2e-6;
    let cubic = move |x: f64, y: f64| alpha * ((x / r).powi(3) + (y / r).powi(3));
    let lens = map_lens(map(250, pitch, MapAperture::Square, cubic));
    let line = || Spectrum::Line(Line::new(LAMBDA0, 1e-9, 1.0).unwrap());
    let e = scene(lens, line());
    // W = (λ0/2π) α (x³ + y³) in metres at λ0
    let c = LAMBDA0 / (2.0 * PI) * alpha;
    let k = 2.0 * PI / LAMBDA0;
    let rule = gauss_legendre(64);
    let nyquist = 0.5 / PIXEL;
    let (panels, azimuths) = (24, 48);
    let in_nu = gauss_legendre(6);
    let mut reference = 0.0;
    for p in 0..panels {
        let (lo, hi) = (nyquist * p as f64 / panels as f64, nyquist * (p + 1) as f64 / panels as f64);
        for &(x, w) in &in_nu {
            let nu = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x;
            let s = nu * LAMBDA0 * F_NUMBER;
            let ring: f64 = (0..azimuths)
                .map(|j| {
                    let phi = PI * j as f64 / azimuths as f64;
                    let (a, b) =
                        (cubic_otf(2.0 * s * phi.cos(), c, k, &rule), cubic_otf(2.0 * s * phi.sin(), c, k, &rule));
                    (a.0 * a.0 + a.1 * a.1).sqrt() * (b.0 * b.0 + b.1 * b.1).sqrt()
                })
                .sum();
            reference += w * 0.5 * (hi - lo) * ring / azimuths as f64;
        }
    }
    reference /= nyquist;
    let bound = 2.0 * (1.0 - smallest_amplitude(pitch, r)) + 1e-4;
    let rel = (e.mean_mtf - reference).abs() / reference;
    eprintln!(
        "square cubic: mean {:.6} (T {:.6}, S {:.6}) vs product of 1-D OTFs {reference:.6} ({rel:.1e}, bound {bound:.1e})",
        e.mean_mtf, e.mean_mtf_tangential, e.mean_mtf_sagittal
    );
    assert!(rel <= bound, "{} vs {reference}: {rel:e} > {bound:e}", e.mean_mtf);
    // the square's light: 4/π of the circle's, through τ1 and T (eq. S7 with its solid angle)
    let circle = scene(map_lens(map(250, pitch, MapAperture::Circle, cubic)), line());
    let ratio = e.photoelectrons / circle.photoelectrons;
    assert!((ratio - 4.0 / PI).abs() < 1e-12, "{ratio}");
}
