//! Integration tests: hand-worked paper SI eq. S1–S9 examples, exact integrals, golden values,
//! input validation and property tests.
//!
//! Golden values were evaluated with mpmath at 30 significant digits from the formulas and the
//! CODATA exact constants unless another source is named.

use approx::assert_relative_eq;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use radiometry::constants::{PLANCK, SPEED_OF_LIGHT};
use radiometry::*;
use std::f64::consts::{PI, SQRT_2};

/// Relative tolerance for closed-form results (a few ulps of accumulated rounding).
const EXACT: f64 = 1e-13;
/// Relative tolerance for Gauss–Legendre results on smooth non-polynomial integrands.
const QUADRATURE: f64 = 1e-10;

fn nm(x: f64) -> f64 {
    x / 1e9
}

fn table(w_nm: &[f64], v: &[f64]) -> Sampled {
    Sampled::new(w_nm.iter().map(|&w| nm(w)).collect(), v.to_vec()).unwrap()
}

fn err_text<T: std::fmt::Debug>(r: Result<T, Error>) -> String {
    r.unwrap_err().to_string()
}

// ---------------------------------------------------------------- S1–S9, worked by hand

#[test]
fn s1_normalize_triangle() {
    // Triangle 0 → 2 → 0 over 700..900 nm: area = 200e-9 × 2 / 2 = 2e-7 m, so the normalized
    // peak is 2 / 2e-7 = 1e7 per m and the area becomes 1.
    let rel = table(&[700.0, 800.0, 900.0], &[0.0, 2.0, 0.0]);
    let n = normalize(&rel).unwrap();
    assert_relative_eq!(n.values()[1], 1e7, max_relative = EXACT);
    assert_relative_eq!(n.integral(), 1.0, max_relative = EXACT);
    assert_eq!(n.wavelengths(), rel.wavelengths());
}

#[test]
fn s1_zero_spectrum_is_an_error() {
    let zero = table(&[700.0, 900.0], &[0.0, 0.0]);
    assert_eq!(err_text(normalize(&zero)), "the integral of the relative spectrum must be finite and > 0, got 0.0");
}

#[test]
fn s2_fiber_irradiance() {
    // P = 1 mW on a 400 µm core: E = 1e-3 / (π (200e-6)²) = 7957.747154594767 W/m².
    assert_relative_eq!(fiber_irradiance(1e-3, 400e-6), 7_957.747_154_594_767, max_relative = EXACT);
}

#[test]
fn s3_flat_responsivity_gives_one() {
    // R constant: corr = ∫ E_norm dλ × R/R = 1.
    let e = normalize(&table(&[700.0, 800.0, 900.0], &[0.0, 2.0, 0.0])).unwrap();
    let r = table(&[400.0, 1100.0], &[0.3, 0.3]);
    assert_relative_eq!(broadband_correction(&e, &r, nm(800.0)).unwrap(), 1.0, max_relative = EXACT);
}

#[test]
fn s3_ramp_responsivity() {
    // E_norm flat 1/(200 nm) = 5e6 per m on 700..900 nm; R ramps 1 → 2, so R(800 nm) = 1.5 and
    // corr = 5e6 × 1.5 × ∫ dλ/R = 5e6 × 1.5 × 200e-9 × ln 2 = 1.5 ln 2 = 1.0397207708399179.
    let e = table(&[700.0, 900.0], &[5e6, 5e6]);
    let r = table(&[700.0, 900.0], &[1.0, 2.0]);
    let corr = broadband_correction(&e, &r, nm(800.0)).unwrap();
    assert_relative_eq!(corr, 1.039_720_770_839_917_9, max_relative = EXACT);
    // The same responsivity with an extra sample on the line: same result.
    let r3 = table(&[700.0, 750.0, 900.0], &[1.0, 1.25, 2.0]);
    assert_relative_eq!(broadband_correction(&e, &r3, nm(800.0)).unwrap(), corr, max_relative = EXACT);
}

#[test]
fn s3_steep_responsivity_closed_form_branch() {
    // R ramps 0.1 → 1 (a factor 10 in one panel), R(800 nm) = 0.55:
    // corr = 0.55 × ∫_0^1 dt / (0.1 + 0.9 t) = 0.55 ln(10) / 0.9 = 1.4071353346074724.
    let e = table(&[700.0, 900.0], &[5e6, 5e6]);
    let r = table(&[700.0, 900.0], &[0.1, 1.0]);
    let corr = broadband_correction(&e, &r, nm(800.0)).unwrap();
    assert_relative_eq!(corr, 1.407_135_334_607_472_4, max_relative = EXACT);
}

#[test]
fn s3_errors() {
    let e = table(&[700.0, 900.0], &[5e6, 5e6]);
    // Responsivity table too short: R = 0 above 850 nm where E_norm > 0.
    let short = table(&[600.0, 850.0], &[1.0, 1.0]);
    assert_eq!(
        err_text(broadband_correction(&e, &short, nm(800.0))),
        "responsivity must be > 0 wherever the normalized spectrum is > 0, got 0 at 8.5e-7 m"
    );
    // Responsivity reaching 0 inside the band.
    let dip = table(&[700.0, 800.0, 900.0], &[1.0, 0.0, 1.0]);
    assert_eq!(
        err_text(broadband_correction(&e, &dip, nm(750.0))),
        "responsivity must be > 0 wherever the normalized spectrum is > 0, got 0 at 8e-7 m"
    );
    let r = table(&[700.0, 900.0], &[1.0, 1.0]);
    assert_eq!(
        err_text(broadband_correction(&e, &r, nm(1000.0))),
        "responsivity at the calibration wavelength must be > 0 (calibration wavelength inside \
         the responsivity table), got 0.0"
    );
    assert_eq!(
        err_text(broadband_correction(&e, &r, f64::NAN)),
        "calibration wavelength must be finite and > 0 m, got NaN"
    );
    // R = 0 only where E_norm = 0 too is fine.
    let tri = table(&[700.0, 800.0, 900.0], &[0.0, 1e7, 0.0]);
    let vanishing = table(&[700.0, 800.0, 900.0], &[0.0, 1.0, 0.0]);
    assert_relative_eq!(
        broadband_correction(&tri, &vanishing, nm(800.0)).unwrap(),
        // E/R = 1e7 on the whole band: corr = 1 × 1e7 × 200e-9 = 2.
        2.0,
        max_relative = EXACT
    );
}

#[test]
fn s4_s5_absolute_spectral_irradiance() {
    // corr 1.5 ln 2 on 1 mW through a 400 µm core:
    // E_accurate = 1.0397207708399179 × 7957.747154594767 = 8273.835005724435 W/m².
    let e_acc = corrected_irradiance(1.039_720_770_839_917_9, fiber_irradiance(1e-3, 400e-6));
    assert_relative_eq!(e_acc, 8_273.835_005_724_435, max_relative = EXACT);
    // S5 on the normalized triangle (peak 1e7 per m): peak 8.273835e10 W/(m² m), area = E_acc.
    let n = normalize(&table(&[700.0, 800.0, 900.0], &[0.0, 2.0, 0.0])).unwrap();
    let abs = absolute_spectral_irradiance(&n, e_acc);
    assert_relative_eq!(abs.values()[1], 8.273_835_005_724_435e10, max_relative = EXACT);
    assert_relative_eq!(abs.integral(), e_acc, max_relative = EXACT);
}

#[test]
fn s6_target_radiance() {
    // E = 1 W/(m² nm) = 1e9 W/(m² m), T = 0.9, f = 50 mm, D = 10 mm: (2f/D)² = 100,
    // L = 1e9 / (π 0.9) × 100 = 3.5367765131532297e10 W/(m² sr m).
    assert_relative_eq!(target_radiance(1e9, 0.9, 50e-3, 10e-3), 3.536_776_513_153_229_7e10, max_relative = EXACT);
}

#[test]
fn s7_camera_irradiance() {
    // L = 1e10 W/(m² sr m), τ1 = 0.15, NA = 0.2: π × 1e10 × 0.15 × 0.04 = 1.8849555921538759e8.
    assert_relative_eq!(camera_irradiance(1e10, 0.15, 0.2), 1.884_955_592_153_875_9e8, max_relative = EXACT);
}

#[test]
fn s6_then_s7_round_trip_through_a_unit_relay() {
    // Relay with T = 1 and f/D = 1/(2 NA): E → L → E again when τ1 = 1 (eq. S6 inverts S7).
    let na = 0.2;
    let l = target_radiance(123.0, 1.0, 1.0, 2.0 * na);
    assert_relative_eq!(camera_irradiance(l, 1.0, na), 123.0, max_relative = EXACT);
}

#[test]
fn s8_photon_flux_and_monochromatic_count() {
    // λ/(hc) at 800 nm = 800e-9 / (6.62607015e-34 × 299792458) = 4.027293254034167e18 per J.
    assert_relative_eq!(photon_flux_per_watt(800e-9), 4.027_293_254_034_167e18, max_relative = EXACT);
    // 5.2 µm pixel (A = 2.704e-11 m²), t = 10 ms, η = 0.5, E = 1 mW/m² at 800 nm:
    // N = 2.704e-11 × 1e-2 × 0.5 × 1e-3 × 4.027293254034167e18 = 544.4900479454194.
    assert_relative_eq!(
        photoelectrons_monochromatic(5.2e-6 * 5.2e-6, 1e-2, 0.5, 800e-9, 1e-3),
        544.490_047_945_419_4,
        max_relative = EXACT
    );
}

#[test]
fn s8_top_hat_band() {
    // E_cam = 1e6 W/(m² m) on 750..850 nm, η = 0.5:
    // N = A t η E / (hc) × (850² − 750²)/2 × 1e-18 = 54449.00479454194 (100× the 1 mW/m² count
    // above, since the band carries 0.1 W/m² centred on 800 nm).
    let e = Spectrum::TopHat(TopHat::new(nm(750.0), nm(850.0), 1e6).unwrap());
    let n = photoelectrons(5.2e-6 * 5.2e-6, 1e-2, &e, &Spectrum::Constant(0.5));
    assert_relative_eq!(n, 54_449.004_794_541_94, max_relative = EXACT);
}

#[test]
fn s8_tables_are_integrated_exactly() {
    // E_cam = 1e6 flat on 700..900 nm; η ramps 0.2 → 0.6. With t = (λ − 700 nm)/200 nm:
    // ∫ η λ E dλ = 1e6 × 200e-9 × ∫_0^1 (0.2 + 0.4t)(700 + 200t)e-9 dt
    //            = 0.2 × (140 + 160 + 80/3) e-9 = 6.533333333e-8 W/m² · m.
    let e = Spectrum::Sampled(table(&[700.0, 900.0], &[1e6, 1e6]));
    let qe = Spectrum::Sampled(table(&[700.0, 900.0], &[0.2, 0.6]));
    let a = 2.704e-11;
    let n = photoelectrons(a, 1e-2, &e, &qe);
    let want = a * 1e-2 / (PLANCK * SPEED_OF_LIGHT) * 6.533_333_333_333_333e-8;
    assert_relative_eq!(n, want, max_relative = EXACT);
}

#[test]
fn s9_shot_noise() {
    // √10000 = 100.
    assert_eq!(shot_noise_snr(10_000.0), 100.0);
    assert!(shot_noise_snr(-1.0).is_nan());
}

#[test]
fn full_chain_matches_closed_form() {
    // S1–S8 on a flat 700..900 nm spectrum, flat responsivity, relay T = 0.9, f = 50 mm,
    // D = 10 mm, τ1 = 0.15, NA = 0.2, η = 0.5, 5.2 µm pixel, 10 ms, P = 1 µW on 400 µm:
    // E_λ = 7.957747e-3 W/m² / 200e-9 m; L = E_λ/(0.9π)·100; E_cam = π L 0.15 0.04;
    // N = A t η / (hc) × E_cam × (900² − 700²)/2 × 1e-18.
    let n_rel = normalize(&table(&[700.0, 900.0], &[3.0, 3.0])).unwrap();
    let r = table(&[700.0, 900.0], &[0.2, 0.2]);
    let corr = broadband_correction(&n_rel, &r, nm(800.0)).unwrap();
    let e_acc = corrected_irradiance(corr, fiber_irradiance(1e-6, 400e-6));
    let e_lambda = absolute_spectral_irradiance(&n_rel, e_acc);
    let radiance: Vec<f64> = e_lambda.values().iter().map(|&e| target_radiance(e, 0.9, 50e-3, 10e-3)).collect();
    let cam: Vec<f64> = radiance.iter().map(|&l| camera_irradiance(l, 0.15, 0.2)).collect();
    let cam = Sampled::new(e_lambda.wavelengths().to_vec(), cam).unwrap();
    let n = photoelectrons(2.704e-11, 1e-2, &Spectrum::Sampled(cam), &Spectrum::Constant(0.5));

    let e_flat = 1e-6 / (PI * 200e-6 * 200e-6) / 200e-9;
    let e_cam = PI * (e_flat / (0.9 * PI) * 100.0) * 0.15 * 0.04;
    let want =
        2.704e-11 * 1e-2 * 0.5 / (PLANCK * SPEED_OF_LIGHT) * e_cam * (nm(900.0).powi(2) - nm(700.0).powi(2)) / 2.0;
    assert_relative_eq!(n, want, max_relative = EXACT);
}

/// The radiance meter's readings of the hand-worked example below.
fn hand_worked_meter() -> RadianceMeter {
    RadianceMeter {
        relative_spectrum: table(&[800.0, 810.0, 820.0], &[2.0, 4.0, 2.0]),
        power_w: 10e-9,
        fiber_core_diameter_m: 400e-6,
        responsivity: table(&[800.0, 810.0, 820.0], &[0.5, 0.5, 1.0]),
        calibration_wavelength_m: nm(810.0),
        relay_transmission: 0.8,
        relay_iris_m: 10e-3,
        relay_focal_length_m: 50e-3,
    }
}

#[test]
fn radiance_meter_s1_to_s6_worked_by_hand() {
    // A triangle spectrum E_rel = 2, 4, 2 at 800, 810, 820 nm; 10 nW on a 400 µm core; R = 0.5,
    // 0.5, 1.0 A/W at the same wavelengths, calibrated at 810 nm; relay T = 0.8, f = 50 mm,
    // D = 10 mm. Every step on paper:
    let s = radiance_meter(&hand_worked_meter()).unwrap();
    // S1: ∫E_rel dλ = 10 nm·(2 + 4)/2 + 10 nm·(4 + 2)/2 = 60 nm = 6e-8 m;
    //     E_norm(810 nm) = 4/6e-8 m = 6.666…e7 /m (0.0667 /nm), and ∫E_norm dλ = 1.
    assert_relative_eq!(s.relative_integral, 6e-8, max_relative = EXACT);
    assert_relative_eq!(s.normalized.value(nm(810.0)), 4.0 / 6e-8, max_relative = EXACT);
    assert_relative_eq!(s.normalized.integral(), 1.0, max_relative = EXACT);
    // S2: A = π (200 µm)² = 4π e-8 m² = 1.2566e-7 m²; E = 1e-8 W / 4π e-8 m² = 1/(4π)
    //     = 0.0795775 W/m².
    assert_relative_eq!(s.fiber_area_m2, 4.0 * PI * 1e-8, max_relative = EXACT);
    assert_relative_eq!(s.fiber_irradiance_w_m2, 1.0 / (4.0 * PI), max_relative = EXACT);
    // S3: corr = R(810)·∫E_norm/R dλ = 0.5/60 nm · ∫E_rel/R dλ. On 800–810 nm R = 0.5:
    //     ∫ = 30 nm/0.5 = 60 nm. On 810–820 nm, t = (λ − 810 nm)/10 nm, E = 4 − 2t,
    //     R = 0.5(1 + t): ∫ = 10 nm · 2∫_0^1 (4 − 2t)/(1 + t) dt = 20 nm ∫_0^1 (6/(1 + t) − 2) dt
    //     = 20 nm (6 ln 2 − 2) = (120 ln 2 − 40) nm. Sum (20 + 120 ln 2) nm, so
    //     corr = 0.5 (20 + 120 ln 2)/60 = 1/6 + ln 2 = 0.8598138.
    assert_relative_eq!(s.calibration_responsivity, 0.5, max_relative = EXACT);
    assert_relative_eq!(s.correction, 1.0 / 6.0 + 2f64.ln(), max_relative = EXACT);
    // S4: E_accurate = corr · E = 0.8598138/(4π) = 0.0684218 W/m².
    let e_acc = (1.0 / 6.0 + 2f64.ln()) / (4.0 * PI);
    assert_relative_eq!(s.corrected_irradiance_w_m2, e_acc, max_relative = EXACT);
    assert_relative_eq!(e_acc, 0.068_421_811_962_487_5, max_relative = 1e-15);
    // S5: E_λ(810 nm) = E_norm(810) · E_accurate = 6.6667e7 /m × 0.0684218 W/m²
    //     = 4.561454e6 W/(m² m) (4.561e-3 W/(m² nm)); zero at the ends' neighbours outside.
    assert_relative_eq!(s.spectral_irradiance.value(nm(810.0)), 4.0 / 6e-8 * e_acc, max_relative = EXACT);
    assert_relative_eq!(s.spectral_irradiance.value(nm(810.0)), 4.561_454_130_832_501e6, max_relative = 1e-14);
    assert_relative_eq!(s.spectral_irradiance.integral(), e_acc, max_relative = EXACT);
    // S6: (2f/D)² = (100 mm/10 mm)² = 100; /(π · 0.8) = 125/π = 39.78874 /sr;
    //     L(810 nm) = 4.561454e6 × 39.78874 = 1.814945e8 W/(m² sr m) (0.1815 W/(m² sr nm)).
    assert_relative_eq!(s.relay_factor_per_sr, 125.0 / PI, max_relative = EXACT);
    assert_relative_eq!(s.radiance.value(nm(810.0)), 1.814_944_931_522_343_8e8, max_relative = 1e-14);
    assert_relative_eq!(s.radiance.value(nm(805.0)), 0.75 * 1.814_944_931_522_343_8e8, max_relative = 1e-14);
    assert_eq!(s.radiance.wavelengths(), s.normalized.wavelengths());
}

#[test]
fn radiance_meter_refuses_bad_readings() {
    let with = |f: fn(&mut RadianceMeter)| {
        let mut m = hand_worked_meter();
        f(&mut m);
        err_text(radiance_meter(&m))
    };
    assert_eq!(with(|m| m.power_w = 0.0), "power must be finite and > 0 W, got 0.0");
    assert_eq!(with(|m| m.fiber_core_diameter_m = f64::NAN), "fiber core diameter must be finite and > 0 m, got NaN");
    assert_eq!(with(|m| m.relay_transmission = 1.5), "relay transmission must be in (0, 1], got 1.5");
    assert_eq!(with(|m| m.relay_iris_m = -1.0), "relay iris diameter must be finite and > 0 m, got -1.0");
    assert_eq!(with(|m| m.relay_focal_length_m = 0.0), "relay focal length must be finite and > 0 m, got 0.0");
    assert!(with(|m| m.calibration_wavelength_m = nm(900.0)).contains("responsivity at the calibration wavelength"));
    assert!(with(|m| m.relative_spectrum = table(&[800.0, 820.0], &[0.0, 0.0])).contains("relative spectrum"));
    // the responsivity table ends at 815 nm where the spectrum is still > 0
    assert!(with(|m| m.responsivity = table(&[800.0, 815.0], &[0.5, 0.5])).contains("responsivity must be > 0"));
}

// ---------------------------------------------------------------- tables

#[test]
fn table_integrals_exact_against_analytic() {
    // value(λ) = λ/1 µm on 1..3 µm sampled at 1, 1.5, 3 µm (a straight line, so exact):
    // ∫ = (3² − 1²)/2 µm = 4e-6 m; from 1.2 to 2.5 µm: (2.5² − 1.2²)/2 = 2.405e-6 m.
    let s = Sampled::new(vec![1e-6, 1.5e-6, 3e-6], vec![1.0, 1.5, 3.0]).unwrap();
    assert_relative_eq!(s.integral(), 4e-6, max_relative = EXACT);
    assert_relative_eq!(s.integral_between(1.2e-6, 2.5e-6), 2.405e-6, max_relative = EXACT);
    assert_relative_eq!(s.value(2.2e-6), 2.2, max_relative = EXACT);
}

#[test]
fn products_of_tables_exact_against_analytic_polynomial() {
    // t(λ) = λ/1 µm on 1..2 µm (two samples). ∫ t² dλ = 1e-6 × (2³ − 1³)/3 = 7/3 × 1e-6 m;
    // ∫ t² λ dλ = 1e-6 × 1e-6 × (2⁴ − 1⁴)/4 = 3.75e-12 m².
    let t = Spectrum::Sampled(Sampled::new(vec![1e-6, 2e-6], vec![1.0, 2.0]).unwrap());
    let t2 = Spectrum::product(vec![t.clone(), t.clone()]);
    assert_relative_eq!(t2.integral(), 7.0 / 3.0 * 1e-6, max_relative = EXACT);
    let t2l = Spectrum::product(vec![t2, Spectrum::Linear { slope: 1.0 }]);
    assert_relative_eq!(t2l.integral(), 3.75e-12, max_relative = EXACT);
}

/// Slow reference: ∫ a·b·λ dλ for two tables, by Simpson's rule (exact for cubics) on every
/// segment of the merged grid, where each table is either one straight line or absent.
fn reference_product_integral(a: &Sampled, b: &Sampled) -> f64 {
    let mut grid: Vec<f64> = a.wavelengths().iter().chain(b.wavelengths()).copied().collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let on = |t: &Sampled, x0: f64, x1: f64, x: f64| {
        let (first, last) = t.range();
        if x0 >= first && x1 <= last { t.value(x) } else { 0.0 }
    };
    grid.windows(2)
        .map(|w| {
            let (x0, x1) = (w[0], w[1]);
            let f = |x: f64| on(a, x0, x1, x) * on(b, x0, x1, x) * x;
            (x1 - x0) / 6.0 * (f(x0) + 4.0 * f(0.5 * (x0 + x1)) + f(x1))
        })
        .sum()
}

// ---------------------------------------------------------------- Gaussian

#[test]
fn gaussian_range_and_integral() {
    // Spectral range = 2√2 σ (paper, Results): 50 nm ↔ σ = 17.677669529663685 nm.
    let g = Gaussian::from_range(nm(800.0), nm(50.0), 2.0).unwrap();
    assert_relative_eq!(g.sigma(), 17.677_669_529_663_685e-9, max_relative = EXACT);
    assert_relative_eq!(g.range(), 2.0 * SQRT_2 * g.sigma(), max_relative = EXACT);
    // Far from λ = 0: area = peak σ √(2π).
    assert_relative_eq!(g.integral(), 2.0 * g.sigma() * (2.0 * PI).sqrt(), max_relative = EXACT);
    assert_eq!(g.truncated_fraction(), 0.0);
}

#[test]
fn gaussian_truncated_at_zero() {
    // center 10 nm, σ 20 nm: fraction = ½ erfc(0.5/√2) = 0.3085375387259869 (Φ(−0.5)),
    // area = σ√(2π)(1 − 0.30853...) = 3.4664787125507689e-8 m for peak 1.
    let g = Gaussian::new(nm(10.0), nm(20.0), 1.0).unwrap();
    assert_relative_eq!(g.truncated_fraction(), 0.308_537_538_725_986_9, max_relative = EXACT);
    assert_relative_eq!(g.integral(), 3.466_478_712_550_769e-8, max_relative = EXACT);
    let s = Spectrum::Gaussian(g);
    let t = s.truncations();
    assert_eq!(t.len(), 1);
    assert_eq!((t[0].center_m, t[0].sigma_m), (nm(10.0), nm(20.0)));
    assert_relative_eq!(t[0].fraction, 0.308_537_538_725_986_9, max_relative = EXACT);
    // Numerical path (forced by a top-hat factor that removes nothing) agrees with erfc.
    let forced = Spectrum::product(vec![s, TopHat::new(0.0, 1e-6, 1.0).unwrap().into()]);
    assert_relative_eq!(forced.integral(), g.integral(), max_relative = QUADRATURE);
}

#[test]
fn gaussian_times_linear_is_center_times_area() {
    // ∫ λ G(λ) dλ = center × peak σ√(2π) for an untruncated Gaussian.
    let g = Gaussian::new(nm(800.0), nm(20.0), 3.0).unwrap();
    let s = Spectrum::product(vec![g.into(), Spectrum::Linear { slope: 1.0 }]);
    assert_relative_eq!(s.integral(), nm(800.0) * g.integral(), max_relative = QUADRATURE);
    // Quadrature nodes carry the same total weight.
    let total: f64 = s.quadrature_nodes().iter().map(|n| n.weight).sum();
    assert_relative_eq!(total, s.integral(), max_relative = EXACT);
}

// ---------------------------------------------------------------- Planck

#[test]
fn planck_golden_values() {
    // 10 µm, 300 K: 9.924 W/(m² sr µm) (textbook thermal-IR value); 30-digit value
    // 9.92403333007069466e6 W/(m² sr m).
    let room = Blackbody::new(300.0).unwrap();
    assert_relative_eq!(room.spectral_radiance(10e-6), 9.924_033_330_070_695e6, max_relative = 1e-12);
    // 500 nm, 5778 K (solar photosphere): 2.6375669866614797e13 W/(m² sr m).
    let sun = Blackbody::new(5778.0).unwrap();
    assert_relative_eq!(sun.spectral_radiance(500e-9), 2.637_566_986_661_479_7e13, max_relative = 1e-12);
}

#[test]
fn planck_peak_follows_wien() {
    // Wien's displacement constant b = 2.897771955e-3 m K (CODATA 2018): λ_max(5778 K) =
    // 501.518 nm. Located here by golden-section search on B, tolerance 1e-6 relative.
    let sun = Blackbody::new(5778.0).unwrap();
    let (mut a, mut b) = (300e-9, 800e-9);
    let r = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let c = b - r * (b - a);
        let d = a + r * (b - a);
        if sun.spectral_radiance(c) > sun.spectral_radiance(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let wien = 2.897_771_955e-3 / 5778.0;
    assert_relative_eq!(0.5 * (a + b), wien, max_relative = 1e-6);
    assert_relative_eq!(sun.peak_wavelength(), wien, max_relative = 1e-9);
}

#[test]
fn stefan_boltzmann_by_quadrature() {
    // π ∫ B dλ = σ T⁴ with σ = 5.670374419e-8 W/(m² K⁴) (CODATA 2018), to 1e-6; the numerical
    // quadrature (panels around the peak and a 1/λ tail map) against the closed form to 1e-10.
    for &t in &[300.0, 5778.0, 3000.0] {
        let s = Spectrum::from(Blackbody::new(t).unwrap());
        let numeric: f64 = s.quadrature_nodes().iter().map(|n| n.weight).sum();
        let sigma_t4 = 5.670_374_419e-8 * t.powi(4);
        assert_relative_eq!(PI * numeric, sigma_t4, max_relative = 1e-6);
        assert_relative_eq!(numeric, s.integral(), max_relative = QUADRATURE);
    }
}

// ---------------------------------------------------------------- bad input

#[test]
fn bad_input_messages() {
    assert_eq!(err_text(Gaussian::new(800e-9, -1e-9, 1.0)), "sigma must be finite and > 0 m, got -1e-9");
    assert_eq!(err_text(Gaussian::new(f64::NAN, 1e-9, 1.0)), "center must be finite and > 0 m, got NaN");
    assert_eq!(err_text(Gaussian::new(800e-9, 1e-9, -2.0)), "peak must be finite and >= 0, got -2.0");
    assert_eq!(err_text(Gaussian::from_range(800e-9, 0.0, 1.0)), "range must be finite and > 0 m, got 0.0");
    assert_eq!(
        err_text(Sampled::new(vec![700e-9, f64::NAN], vec![1.0, 1.0])),
        "wavelength[1] must be finite and > 0 m, got NaN"
    );
    assert_eq!(
        err_text(Sampled::new(vec![700e-9, 800e-9, 800e-9], vec![1.0, 1.0, 1.0])),
        "wavelengths must be strictly increasing, got wavelength[2] = 8e-7 m after wavelength[1] = \
         8e-7 m"
    );
    assert_eq!(err_text(Sampled::new(vec![700e-9], vec![1.0])), "a sampled spectrum needs at least 2 samples, got 1");
    assert_eq!(
        err_text(Sampled::new(vec![700e-9, 800e-9], vec![1.0, -0.5])),
        "value[1] must be finite and >= 0, got -0.5"
    );
    assert_eq!(
        err_text(Sampled::new(vec![700e-9, 800e-9], vec![1.0])),
        "wavelengths and values must have the same length, got 2 wavelengths and 1 values"
    );
    assert_eq!(
        err_text(Sampled::new(vec![-7e-7, 800e-9], vec![1.0, 1.0])),
        "wavelength[0] must be finite and > 0 m, got -7e-7"
    );
    assert_eq!(err_text(TopHat::new(800e-9, 700e-9, 1.0)), "hi must be finite and > lo (= 8e-7) m, got 7e-7");
    assert_eq!(err_text(Blackbody::new(-3.0)), "temperature must be finite and in (0, 1e12] K, got -3.0");
    assert_eq!(err_text(Spectrum::constant(f64::INFINITY)), "constant must be finite and >= 0, got inf");
    let s = table(&[700.0, 900.0], &[1.0, 1.0]);
    assert_eq!(err_text(s.try_scaled(-1.0)), "scale factor must be finite and >= 0, got -1.0");
}

// ---------------------------------------------------------------- properties

fn config() -> Config {
    Config { cases: 256, rng_seed: RngSeed::Fixed(0x5EED_A5A1), ..Config::default() }
}

/// A random table on visible–NIR wavelengths: 2..40 samples, increasing steps 0.1..50 nm, values
/// in [0, 10].
fn arb_table() -> impl Strategy<Value = Sampled> {
    (300.0..900.0f64, prop::collection::vec((0.1..50.0f64, 0.0..10.0f64), 2..40)).prop_map(|(start, steps)| {
        let mut w = Vec::with_capacity(steps.len());
        let mut l = start;
        for (dl, _) in &steps {
            l += dl;
            w.push(nm(l));
        }
        let v = steps.iter().map(|(_, v)| *v).collect();
        Sampled::new(w, v).unwrap()
    })
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn integral_between_is_additive(s in arb_table(), a in 250.0..2000.0f64,
                                    b in 250.0..2000.0f64, c in 250.0..2000.0f64) {
        let (a, b, c) = (nm(a), nm(b), nm(c));
        let whole = s.integral_between(a, c);
        let parts = s.integral_between(a, b) + s.integral_between(b, c);
        prop_assert!((whole - parts).abs() <= 1e-12 * s.integral() + 1e-30);
        let all = s.integral_between(0.0, 1.0);
        prop_assert!((all - s.integral()).abs() <= 1e-12 * s.integral());
    }

    #[test]
    fn normalize_gives_unit_area(s in arb_table()) {
        prop_assume!(s.integral() > 0.0);
        let n = normalize(&s).unwrap();
        prop_assert!((n.integral() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn table_product_quadrature_is_exact(a in arb_table(), b in arb_table()) {
        let want = reference_product_integral(&a, &b);
        let s = Spectrum::product(vec![a.clone().into(), b.clone().into(),
                                       Spectrum::Linear { slope: 1.0 }]);
        let got = s.integral();
        prop_assert!((got - want).abs() <= 1e-12 * want.abs() + 1e-40, "{} vs {}", got, want);
    }

    #[test]
    fn gaussian_quadrature_matches_erfc(center in 5.0..1500.0f64, range in 1.0..300.0f64,
                                        peak in 0.1..10.0f64) {
        let g = Gaussian::from_range(nm(center), nm(range), peak).unwrap();
        let forced = Spectrum::product(vec![g.into(), TopHat::new(0.0, 1e-5, 1.0).unwrap().into()]);
        prop_assert!((forced.integral() / g.integral() - 1.0).abs() < QUADRATURE);
        prop_assert!(g.integral() <= peak * g.sigma() * (2.0 * PI).sqrt() * (1.0 + EXACT));
    }

    #[test]
    fn broadband_correction_bounded_by_responsivity_ratios(e in arb_table(), r_lo in 0.05..1.0f64,
                                                           r_hi in 0.05..1.0f64) {
        // With R linear between r_lo and r_hi over E's band, corr lies between
        // R(λ_cal)/max R and R(λ_cal)/min R.
        prop_assume!(e.integral() > 0.0);
        let n = normalize(&e).unwrap();
        let (lo, hi) = (n.wavelengths()[0], *n.wavelengths().last().unwrap());
        let r = Sampled::new(vec![lo, hi], vec![r_lo, r_hi]).unwrap();
        let cal = 0.5 * (lo + hi);
        let corr = broadband_correction(&n, &r, cal).unwrap();
        let rc = r.value(cal);
        let (min, max) = (r_lo.min(r_hi), r_lo.max(r_hi));
        prop_assert!(corr >= rc / max * (1.0 - 1e-12) && corr <= rc / min * (1.0 + 1e-12));
    }
}

/// A Gaussian narrower than 1e-10 of its centre is refused by name (centre ± σ are a handful of
/// floating-point numbers: the scene detected "no light" or "the spectrum extends over [8e-7,
/// 8e-7] m" for `spectrum.range_nm = 1e-200`).
#[test]
fn gaussians_below_the_wavelength_resolution_are_refused() {
    let err = Gaussian::from_range(800e-9, 1e-209, 1.0).unwrap_err().to_string();
    assert!(err.contains("sigma must be at least 1e-10 × center"), "{err}");
    assert!(Gaussian::from_range(800e-9, 1e-12, 1.0).is_ok(), "0.001 nm at 800 nm is resolved");
}
