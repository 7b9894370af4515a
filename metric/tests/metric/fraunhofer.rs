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

/// A tabulated lens of `rows` (one per wavelength, m) of the paper lens's exact signed OTF at
/// `freqs` (cycles/m): the chromatic lens as data.
fn chromatic_table(wavelengths: &[f64], freqs: &[f64]) -> optics::OtfTable {
    let f_number = 2.5;
    let rows = wavelengths
        .iter()
        .map(|&l| {
            // W020 = (1 − λ/λ0) f0/(8F#²) (docs/physics.md, "Chromatic lens"), in waves at λ
            let w = (1.0 - l / LAMBDA0) * F0 / (8.0 * f_number * f_number) / l;
            freqs.iter().map(|&nu| optics::defocus_otf((nu * l * f_number).min(1.0), w)).collect()
        })
        .collect();
    optics::OtfTable::new(wavelengths.to_vec(), freqs.to_vec(), rows, None).unwrap()
}

fn tabulated_scene(table: optics::OtfTable, filter: Spectrum, design: Option<f64>) -> metric::Scene {
    let mut lens = lenses::Tabulated::new(2.5, F0, table, Curve::Constant(0.15), Curve::Constant(0.55), None).unwrap();
    if let Some(l0) = design {
        lens = lens.with_design_wavelength(l0).unwrap();
    }
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), filter]);
    let camera = metric::Camera::new(5.2e-6, Spectrum::Constant(0.2), false).unwrap();
    metric::Scene::new(std::sync::Arc::new(lens), radiance, camera, 1.23e-3, metric::Options::default()).unwrap()
}

/// A table's blur is known over its rows only: under a top-hat band wider than the table, the
/// light outside counts as beyond the threshold, exactly its share `∫ λ dλ` of the band (flat
/// source, constant QE and efficiency), and the largest shift is the distance to the table's
/// nearer end (from the design wavelength, or without one from the mean detected wavelength).
#[test]
fn a_tables_light_outside_it_is_beyond() {
    let freqs: Vec<f64> = (0..=400).map(|k| 2e3 * k as f64).collect();
    let table = chromatic_table(&[770e-9, 800e-9, 830e-9], &freqs);
    let band = || Spectrum::TopHat(TopHat::new(700e-9, 900e-9, 1.0).unwrap());
    let e = metric::evaluate(&tabulated_scene(table.clone(), band(), Some(LAMBDA0))).unwrap();
    let square = |x: f64, y: f64| y * y - x * x;
    let exact = (square(700e-9, 770e-9) + square(830e-9, 900e-9)) / square(700e-9, 900e-9);
    let f = &e.fraunhofer;
    assert!((f.fraction_outside - exact).abs() < 1e-12, "{} vs {exact}", f.fraction_outside);
    assert!(!f.valid && e.warnings.iter().any(|w| w.contains("Fraunhofer")), "{f:?}");
    assert_eq!(f.table_nm, Some([770.0, 830.0]));
    assert!((f.max_shift_nm.unwrap() - 30.0).abs() < 1e-6, "{f:?}");
    assert!((f.reference_nm.unwrap() - 800.0).abs() < 1e-9);
    // no design wavelength: the shift is measured from the mean detected wavelength
    let narrow = || Spectrum::TopHat(TopHat::new(780e-9, 810e-9, 1.0).unwrap());
    let e = metric::evaluate(&tabulated_scene(table, narrow(), None)).unwrap();
    let f = &e.fraunhofer;
    let mean = e.mean_wavelength_nm;
    assert!((f.reference_nm.unwrap() - mean).abs() < 1e-9 && f.valid && f.fraction_outside == 0.0, "{f:?}");
    assert!((f.max_shift_nm.unwrap() - (830.0 - mean).min(mean - 770.0)).abs() < 1e-6, "{f:?}");
}

/// The paper lens as a table of its exact OTFs (every 5 nm, 200–1400 nm) under a 600 nm Gaussian
/// range: with its frequencies 0.25 cycles/mm apart (up to 100 cycles/mm) the blur its rows imply
/// puts the same share of the signal beyond 0.25 mm as the lens's own defocus (eq. S15:
/// |λ − λ0| > 297.6 nm; measured 0.16043 against 0.16062, held to 0.5 %) and the largest shift
/// agrees to 0.1 nm (297.64 nm). With 2 cycles/mm between frequencies the table cannot resolve a
/// 0.25 mm blur (its OTF falls to one half at 1.41 cycles/mm, before the first sample) and the
/// linear interpolation overestimates it: 0.209 beyond, more than the lens, never less.
#[test]
fn a_table_of_the_chromatic_lens_is_as_blurred_as_the_lens() {
    let wavelengths: Vec<f64> = (0..=240).map(|k| (200.0 + 5.0 * k as f64) * 1e-9).collect();
    let filter = || Spectrum::Gaussian(Gaussian::from_range(LAMBDA0, 600e-9, 1.0).unwrap());
    let lens = lens(2.5);
    let beyond = |step: f64, count: usize| {
        let freqs: Vec<f64> = (0..=count).map(|k| step * k as f64).collect();
        let table = tabulated_scene(chromatic_table(&wavelengths, &freqs), filter(), Some(LAMBDA0));
        let spectrum = metric::detected_spectrum(&table);
        let poly = Polychromatic::new(table.lens(), &spectrum, Field::ON_AXIS, NYQUIST, None).unwrap();
        let shift = optics::fraunhofer::max_wavelength_shift(table.lens(), LAMBDA0, 0.25e-3).unwrap();
        let poly_lens = Polychromatic::new(&lens, &spectrum, Field::ON_AXIS, NYQUIST, None).unwrap();
        (poly.fraction_blurred_beyond(0.25e-3), poly_lens.fraction_blurred_beyond(0.25e-3), shift)
    };
    let (got, want, got_shift) = beyond(250.0, 400);
    assert!((got / want - 1.0).abs() < 0.005, "{got} vs {want}");
    assert!((got_shift - shift(2.5, 0.25e-3)).abs() < 0.1e-9, "{got_shift:e}");
    let (coarse, want, coarse_shift) = beyond(2e3, 50);
    assert!(coarse > want && (coarse - 0.209).abs() < 0.001, "{coarse} vs {want}");
    assert!(coarse_shift < got_shift, "{coarse_shift:e}");
}
