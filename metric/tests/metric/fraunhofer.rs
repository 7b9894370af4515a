//! The Fraunhofer fraction (paper SI eq. S15) on the spectral-quadrature path: exact against
//! closed forms written here, against the closed-form engine, and continuous in a sweep.
//!
//! For the chromatic lens `W020(λ) = (1 − λ/λ0) f0/(8F#²)` (docs/physics.md), so the blur radius
//! `2|W020|/NA` exceeds `x` exactly where `|λ − λ0| > Δ = 2 x λ0 F#/f0` (eq. S15 solved for Δλ:
//! 297.619 nm for the paper's lens and 0.25 mm).

use lenses::{ChromaticMetalens, Curve};
use optics::{Field, Polychromatic, Settings};
use radiometry::{Gaussian, Spectrum, TopHat};

const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;
const NYQUIST: f64 = 0.5 / 5.2e-6;

fn lens(f_number: f64) -> ChromaticMetalens {
    ChromaticMetalens::new(f_number, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap()
}

/// Detected photon density before the lens: flat source × `filter` × λ (paper SI eq. S8).
fn detected(filter: Spectrum) -> Spectrum {
    Spectrum::product(vec![Spectrum::Constant(2.5e7), filter, Spectrum::Linear { slope: 1.0 }])
}

fn gaussian(centre: f64, range: f64) -> Spectrum {
    detected(Spectrum::Gaussian(Gaussian::from_range(centre, range, 1.0).unwrap()))
}

fn settings(closed_form: bool) -> Settings {
    Settings { closed_form, ..Settings::default() }
}

/// Eq. S15 solved for the wavelength shift: `Δ = 2 x λ0 F#/f0`.
fn shift(f_number: f64, radius: f64) -> f64 {
    2.0 * radius * LAMBDA0 * f_number / F0
}

/// Flat source × top-hat [a, b] × λ: the fraction beyond is a ratio of `∫ λ dλ` over the parts of
/// the band outside `λ0 ± Δ`, `(λ² /2)` differences.
#[test]
fn top_hat_fraction_is_the_ratio_of_lambda_integrals() {
    let cases = [
        // (F#, band nm, radius mm)
        (2.5, (400.0, 1300.0), 0.25),
        (2.5, (650.0, 1200.0), 0.25),
        (2.5, (780.0, 900.0), 0.02),
        (1.4, (500.0, 820.0), 0.1),
        (4.0, (300.0, 1400.0), 0.3),
    ];
    for (f_number, (a_nm, b_nm), radius_mm) in cases {
        let (a, b, radius) = (a_nm * 1e-9, b_nm * 1e-9, radius_mm * 1e-3);
        let lens = lens(f_number);
        let spectrum = detected(Spectrum::TopHat(TopHat::new(a, b, 0.8).unwrap()));
        let poly =
            Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, NYQUIST, None, settings(true)).unwrap();
        assert_eq!(poly.engine(), optics::Engine::Exact1d);
        let delta = shift(f_number, radius);
        let (lo, hi) = (LAMBDA0 - delta, LAMBDA0 + delta);
        let square = |x: f64, y: f64| if y > x { y * y - x * x } else { 0.0 };
        let exact = (square(a, lo.min(b)) + square(hi.max(a), b)) / square(a, b);
        let got = poly.fraction_blurred_beyond(radius);
        eprintln!("F/{f_number} [{a_nm}, {b_nm}] nm, {radius_mm} mm: {got:.15} vs {exact:.15}");
        assert!((got - exact).abs() < 1e-13, "F/{f_number} [{a_nm}, {b_nm}] nm: {got} vs {exact}");
        assert!(exact > 0.0 && exact < 1.0, "the case should straddle the limit: {exact}");
    }
}

/// The spectral quadrature's fraction against the closed-form engine's (complementary error
/// functions of the Gaussian × polynomial): they agree to the ±7σ window of the quadrature.
#[test]
fn quadrature_fraction_matches_the_closed_form() {
    for (f_number, centre_nm, range_nm, radius_mm) in [
        (2.5, 800.0, 600.0, 0.25),
        (2.5, 850.0, 400.0, 0.25),
        (1.5, 800.0, 300.0, 0.25),
        (4.5, 760.0, 900.0, 0.25),
        (2.5, 800.0, 50.0, 0.01),
    ] {
        let lens = lens(f_number);
        let spectrum = gaussian(centre_nm * 1e-9, range_nm * 1e-9);
        let make = |closed| {
            Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, NYQUIST, None, settings(closed)).unwrap()
        };
        let (closed, quadrature) = (make(true), make(false));
        assert_eq!(closed.engine(), optics::Engine::ClosedForm);
        assert_eq!(quadrature.engine(), optics::Engine::Exact1d);
        let radius = radius_mm * 1e-3;
        let (a, b) = (closed.fraction_blurred_beyond(radius), quadrature.fraction_blurred_beyond(radius));
        eprintln!(
            "F/{f_number} {centre_nm} nm ± {range_nm} nm: closed {a:.15} quadrature {b:.15} ({:.1e})",
            (a - b).abs()
        );
        assert!((a - b).abs() < 1e-10, "F/{f_number} {centre_nm} nm, {range_nm} nm: {a} vs {b}");
        assert!(a > 1e-6, "the case should have signal beyond the limit: {a}");
    }
}

/// A sweep over the range: the fraction is monotone (a Gaussian centred on λ0 only widens past
/// the fixed limits) and follows the closed form at every point. The node sum of the step that
/// this replaces, `spectral_average` of an indicator, is computed alongside: it lands on nodes
/// and is off by up to percents, which is what made the Fig. S9 shading flicker.
#[test]
fn range_sweep_has_no_flicker() {
    let lens = lens(2.5);
    let radius = 0.25e-3;
    let na = 0.2;
    let (mut previous, mut worst_exact, mut worst_nodes): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for k in 0..=60 {
        let range = (300.0 + 10.0 * f64::from(k)) * 1e-9;
        let spectrum = gaussian(LAMBDA0, range);
        let closed =
            Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, NYQUIST, None, settings(true)).unwrap();
        let quadrature =
            Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, NYQUIST, None, settings(false)).unwrap();
        let exact = closed.fraction_blurred_beyond(radius);
        let got = quadrature.fraction_blurred_beyond(radius);
        let nodes = quadrature.spectral_average(|_, w020| if 2.0 * w020.abs() / na > radius { 1.0 } else { 0.0 });
        assert!(got >= previous, "range {:.0} nm: {got} after {previous}", range * 1e9);
        previous = got;
        worst_exact = worst_exact.max((got - exact).abs());
        worst_nodes = worst_nodes.max((nodes - exact).abs());
    }
    eprintln!("worst |quadrature − closed form| {worst_exact:.1e}, node sum of the step {worst_nodes:.1e}");
    assert!(worst_exact < 1e-10, "{worst_exact:e}");
    assert!(previous > 0.2, "the sweep should reach well past the limit: {previous}");
    // the test has teeth: the node sum it replaces is far off somewhere in the sweep
    assert!(worst_nodes > 1e-4, "{worst_nodes:e}");
}
