//! The flat lens's exact pupil map (`lenses::ExactPupilMap`, docs/physics.md "The flat lens's
//! exact image") against references written here: the Rayleigh–Sommerfeld integral over the lens
//! plane onto the flat detector (the PSF), and the 2-D autocorrelation of the pupil in direction
//! cosines (the OTF), both by plain quadrature. A small, fast lens (F/1, f0 = 5 mm) a little off
//! its design wavelength (a geometric-phase hyperbola at 1002 nm designed for 1000 nm: 1.2 waves
//! of defocus and spherical aberration at the rim), where the paraxial map is 10 % off.

use std::f64::consts::TAU;

use lenses::{Curve, Dispersion, ExactPupilMap, PhaseLens};
use num_complex::Complex64;
use optics::quad::for_each_node;
use optics::radial::RadialOrder;
use optics::{Field, LensModel, Pupil};

const Z: f64 = 5e-3;
const F_NUMBER: f64 = 1.0;
const LAMBDA0: f64 = 1e-6;
const LAMBDA: f64 = 1.002e-6;

fn radius() -> f64 {
    0.5 * Z / F_NUMBER
}

/// The lens's OPD against the exact reference sphere at lens radius `r`:
/// `W = (λ/2π) φ0 + √(r² + z²) − z` with the hyperbola `φ0 = −(2π/λ0)(√(r² + z²) − z)`.
fn opd(r: f64) -> f64 {
    (1.0 - LAMBDA / LAMBDA0) * r * r / ((r * r + Z * Z).sqrt() + Z)
}

/// The detector field at `(h, 0, z)` by the Rayleigh–Sommerfeld integral of the first kind over
/// the lens plane, `u ∝ ∫ U e^{iφ} ∂/∂z (e^{ikd}/d) dX` with `∂/∂z(e^{ikd}/d) = (z/d)(ik − 1/d)
/// e^{ikd}/d`: no approximation but the quadrature (16-point Gauss–Legendre panels in r, the
/// trapezoid rule, spectrally accurate for a periodic integrand, in the azimuth). The phase
/// `φ0 + kd` is written as `kW(r) + k(d − d0)`, `d0 = √(r² + z²)`, without cancellation.
fn rayleigh_sommerfeld(h: f64) -> Complex64 {
    let k = TAU / LAMBDA;
    let azimuths = 256;
    let mut sum = Complex64::new(0.0, 0.0);
    for_each_node(0.0, radius(), 12, |r, w| {
        let d0 = (r * r + Z * Z).sqrt();
        let mut ring = Complex64::new(0.0, 0.0);
        for j in 0..azimuths {
            let phi = TAU * j as f64 / azimuths as f64;
            let d = (d0 * d0 + h * h - 2.0 * r * h * phi.cos()).sqrt();
            let phase = k * opd(r) + k * (h * h - 2.0 * r * h * phi.cos()) / (d + d0);
            ring += Complex64::from_polar(Z / (d * d), phase) * Complex64::new(-1.0 / d, k);
        }
        sum += ring * (w * r * TAU / azimuths as f64);
    });
    sum
}

/// A pupil in direction cosines `e`: `(field, largest |e|)`.
struct Model {
    field: fn(f64) -> Complex64,
    rim: f64,
}

/// The exact map: the lens point `r = z e/c` (`c² = 1 − e²`), field `e^{ikW(r)}/c²`.
fn exact_field(e: f64) -> Complex64 {
    let c2 = 1.0 - e * e;
    let r = Z * e / c2.sqrt();
    Complex64::from_polar(1.0 / c2, TAU / LAMBDA * opd(r))
}

/// The paraxial map: `r = z e`, no amplitude factor.
fn paraxial_field(e: f64) -> Complex64 {
    Complex64::from_polar(1.0, TAU / LAMBDA * opd(Z * e))
}

fn exact() -> Model {
    let na0 = radius() / Z;
    Model { field: exact_field, rim: na0 / (1.0 + na0 * na0).sqrt() }
}

fn paraxial() -> Model {
    Model { field: paraxial_field, rim: radius() / Z }
}

/// The detector field at `(h, 0)` of a pupil in direction cosines: `∫ P̃(e) e^{−ik e_x h} d²e`.
fn fraunhofer(model: &Model, h: f64) -> Complex64 {
    let k = TAU / LAMBDA;
    let azimuths = 256;
    let mut sum = Complex64::new(0.0, 0.0);
    for_each_node(0.0, model.rim, 12, |e, w| {
        let p = (model.field)(e);
        let ring: Complex64 = (0..azimuths)
            .map(|j| Complex64::from_polar(1.0, -k * e * h * (TAU * j as f64 / azimuths as f64).cos()))
            .sum();
        sum += p * ring * (w * e * TAU / azimuths as f64);
    });
    sum
}

/// The OTF at the lag `d` (direction cosines, `d = λν`) of a pupil in direction cosines: the 2-D
/// autocorrelation `Re ∫ P̃(e + d/2) P̃*(e − d/2) d²e / ∫|P̃|² d²e` over the overlap of the two
/// discs, Gauss–Legendre in y and, on each line, over the x interval both discs cover.
fn autocorrelation(model: &Model, d: f64) -> f64 {
    let a = model.rim;
    let half = 0.5 * d;
    let y_max = (a * a - half * half).max(0.0).sqrt();
    let mut overlap = 0.0;
    for_each_node(-y_max, y_max, 64, |y, wy| {
        let x_max = (a * a - y * y).max(0.0).sqrt() - half;
        for_each_node(-x_max, x_max, 8, |x, wx| {
            let p = (model.field)(((x + half).powi(2) + y * y).sqrt());
            let q = (model.field)(((x - half).powi(2) + y * y).sqrt());
            overlap += wy * wx * (p * q.conj()).re;
        });
    });
    let mut power = 0.0;
    for_each_node(0.0, a, 16, |e, w| power += w * TAU * e * (model.field)(e).norm_sqr());
    overlap / power
}

fn phase_lens() -> PhaseLens {
    let r = radius();
    let coefficients = lenses::hyperbolic_binary2(Z, LAMBDA0, r, 40);
    let phase = lenses::binary2_profile(&coefficients, 1.0, r, r).unwrap();
    PhaseLens::new(
        F_NUMBER,
        Z,
        LAMBDA0,
        std::sync::Arc::new(phase),
        None,
        Dispersion::GeometricPhase,
        Curve::Constant(0.5),
        Curve::Constant(0.5),
        "hyperbola, 40 Binary 2 terms".to_string(),
    )
    .unwrap()
}

/// The radial engine's OTF of `lens`'s one order at the paraxial normalized frequency `s`.
fn engine_otf(lens: &dyn LensModel, s: f64) -> f64 {
    let orders = lens.orders(LAMBDA, Field::ON_AXIS);
    assert_eq!(orders.len(), 1);
    let Pupil::Radial(pupil) = &orders[0].pupil else { panic!("a radial pupil") };
    RadialOrder::new(pupil.clone(), orders[0].wavefront.defocus_m, LAMBDA).otf(s, 1e-10)
}

#[test]
fn the_pupil_in_direction_cosines_is_the_rayleigh_sommerfeld_field() {
    // the PSF's shape, I(h)/I(0), over the core and the first rings (the Airy radius is 1.4 µm):
    // the Fraunhofer approximation about the image point leaves about k h² NA²/(2z) ≈ 1e-3 rad
    let (rs0, ex0, px0) = (rayleigh_sommerfeld(0.0), fraunhofer(&exact(), 0.0), fraunhofer(&paraxial(), 0.0));
    let (mut exact_worst, mut paraxial_worst) = (0.0_f64, 0.0_f64);
    for j in 1..=12 {
        let h = 0.25e-6 * j as f64;
        let rs = rayleigh_sommerfeld(h).norm_sqr() / rs0.norm_sqr();
        let ex = fraunhofer(&exact(), h).norm_sqr() / ex0.norm_sqr();
        let px = fraunhofer(&paraxial(), h).norm_sqr() / px0.norm_sqr();
        exact_worst = exact_worst.max((ex - rs).abs());
        paraxial_worst = paraxial_worst.max((px - rs).abs());
    }
    eprintln!("PSF I(h)/I(0) against Rayleigh–Sommerfeld: exact map {exact_worst:.2e}, paraxial {paraxial_worst:.2e}");
    assert!(exact_worst < 2e-3, "exact map {exact_worst:e}");
    assert!(paraxial_worst > 5e-2, "paraxial {paraxial_worst:e}");
}

#[test]
fn exact_mode_gives_the_autocorrelation_in_direction_cosines() {
    let paraxial_lens = phase_lens();
    let exact_lens = ExactPupilMap::new(phase_lens(), LAMBDA).unwrap();
    let (mut exact_worst, mut paraxial_worst) = (0.0_f64, 0.0_f64);
    // s = ν λ F# (paraxial); the lag in direction cosines is λν = s/F#; the exact cutoff is at
    // s = 1/√(1 + NA0²) = 0.894
    for s in [0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.85, 0.9] {
        let lag = s / F_NUMBER;
        let reference = autocorrelation(&exact(), lag);
        let got = engine_otf(&exact_lens, s);
        let old = engine_otf(&paraxial_lens, s);
        // the reference's own paraxial autocorrelation agrees with the engine's paraxial mode
        let paraxial_reference = autocorrelation(&paraxial(), lag);
        assert!((old - paraxial_reference).abs() < 1e-6, "paraxial s = {s}: {old} vs {paraxial_reference}");
        eprintln!("s = {s}: exact {got:.8} reference {reference:.8}, paraxial {old:.8}");
        exact_worst = exact_worst.max((got - reference).abs());
        paraxial_worst = paraxial_worst.max((old - reference).abs());
    }
    assert!(exact_worst < 1e-6, "exact {exact_worst:e}");
    assert!(paraxial_worst > 1e-2, "paraxial {paraxial_worst:e}");
}
