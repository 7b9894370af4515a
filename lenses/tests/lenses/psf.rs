//! The PSF-stack lens through the conformance check every lens model passes.

use lenses::{Curve, PsfStack};
use optics::testkit::{check_lens, simpson_mean};

use crate::band;

/// Three slices of elliptical, shifted, slightly skewed Gaussians (lateral colour, a direction-
/// dependent OTF, a non-zero imaginary part) at 780, 800 and 820 nm, 1 µm samples, F/2.5:
/// MTF(0) = 1, bounds, finite everywhere, efficiency within the transmission, over a band
/// reaching past the stack (the end slices held).
#[test]
fn a_psf_stack_passes_the_conformance_check() {
    let n = 48;
    let c = (n / 2) as f64;
    let mut values = Vec::new();
    for (k, shift) in [-1.5, 0.0, 2.0].iter().enumerate() {
        let (sx, sy) = (2.0 + k as f64, 2.5);
        for i in 0..n * n {
            let (y, x) = ((i / n) as f64 - c, (i % n) as f64 - c - shift);
            let skew = 1.0 + 0.1 * (x / sx).tanh();
            values.push(skew * (-(x * x) / (2.0 * sx * sx) - y * y / (2.0 * sy * sy)).exp());
        }
    }
    let lens = PsfStack::new(
        2.5,
        3.36e-3,
        1e-6,
        vec![780e-9, 800e-9, 820e-9],
        [n, n],
        &values,
        Curve::Constant(0.3),
        Curve::Constant(0.6),
    )
    .unwrap();
    assert!(lens.table().is_direction_dependent());
    assert!(lens.report().imaginary.0 > 1e-3, "{:?}", lens.report().imaginary);
    check_lens(&lens, &band(800.0, 10.0)).unwrap();
    check_lens(&lens, &band(800.0, 100.0)).unwrap();
}

/// `I0(x)` by its series (x ≤ 10: 60 terms reach 1e-16).
fn bessel_i0(x: f64) -> f64 {
    let (mut term, mut sum) = (1.0, 1.0);
    for k in 1..60 {
        term *= (0.5 * x / k as f64).powi(2);
        sum += term;
    }
    sum
}

/// The engine's settings at a tolerance of 1e-7.
fn settings() -> optics::Settings {
    optics::Settings { tolerance: 1e-7, ..optics::Settings::default() }
}

/// Three identical slices (780, 800, 820 nm, 1 µm samples, 64 × 64) of the Gaussian PSF with
/// standard deviations `s1`, `s2` (m) along axes turned by `alpha` from +x.
fn elliptical_stack(s1: f64, s2: f64, alpha: f64) -> PsfStack {
    let (n, p) = (64, 1e-6);
    let c = (n / 2) as f64;
    let one: Vec<f64> = (0..n * n)
        .map(|i| {
            let (y, x) = (((i / n) as f64 - c) * p, ((i % n) as f64 - c) * p);
            let (u, v) = (x * alpha.cos() + y * alpha.sin(), -x * alpha.sin() + y * alpha.cos());
            (-(u * u) / (2.0 * s1 * s1) - v * v / (2.0 * s2 * s2)).exp()
        })
        .collect();
    let values = [one.clone(), one.clone(), one].concat();
    PsfStack::new(
        2.5,
        3.36e-3,
        p,
        vec![780e-9, 800e-9, 820e-9],
        [n, n],
        &values,
        Curve::Constant(0.3),
        Curve::Constant(0.6),
    )
    .unwrap()
}

/// The mean MTF over azimuth of a Gaussian PSF with σ1, σ2 (m) to `nu_max`, in closed form in
/// azimuth: `OTF(ν, φ) = exp(−2π²ν²(σ1² cos²ψ + σ2² sin²ψ))` (ψ = φ − α), whose mean over ψ is
/// `e^{−2π²ν²A} I0(2π²ν²B)`, `A = (σ1² + σ2²)/2`, `B = (σ1² − σ2²)/2`; Simpson's rule in ν.
fn closed_form_azimuthal_mean(s1: f64, s2: f64, nu_max: f64) -> f64 {
    let (a, b) = (0.5 * (s1 * s1 + s2 * s2), 0.5 * (s1 * s1 - s2 * s2));
    let k = 2.0 * std::f64::consts::PI.powi(2);
    simpson_mean(nu_max, |nu| (-k * nu * nu * a).exp() * bessel_i0(k * nu * nu * b))
}

/// An elliptical Gaussian stack (σ = 3 µm and 2 µm, turned 30°): the ASNR's mean MTF is the
/// mean over azimuth of its 2-D OTF, against the closed form written above to 1e-6 (the
/// samples' transform is the continuous Gaussian's to 1e-12 below a quarter of the sampling
/// rate, where ν_max = 100 cycles/mm lies); turned 0° and 90° it is the same, while the
/// average of the x and y cuts, `(T + S)/2`, changes with the turn.
#[test]
fn an_elliptical_stack_takes_the_mean_over_azimuth_whatever_its_turn() {
    let (s1, s2, nu_max) = (3e-6, 2e-6, 1e5);
    let want = closed_form_azimuthal_mean(s1, s2, nu_max);
    let detected = band(800.0, 5.0);
    let mut cuts = Vec::new();
    for alpha in [30f64, 0.0, 90.0] {
        let lens = elliptical_stack(s1, s2, alpha.to_radians());
        assert!(lens.table().is_two_dimensional());
        let poly =
            optics::Polychromatic::with_settings(&lens, &detected, optics::Field::ON_AXIS, nu_max, None, settings())
                .unwrap();
        assert!(poly.has_pupil_grid());
        let got = poly.mean_mtf_over_azimuth(0.0, None);
        let (t, s) = (poly.mean_mtf_along(0.0).0, poly.mean_mtf_along(std::f64::consts::FRAC_PI_2).0);
        eprintln!(
            "{alpha}°: over azimuth {:.9} ({} azimuths) vs {want:.9}: {:+.1e}; (T + S)/2 = {:.6}",
            got.mean,
            got.azimuths,
            got.mean - want,
            0.5 * (t + s)
        );
        assert!((got.mean - want).abs() < 1e-6 * want, "{alpha}°: {} vs {want}", got.mean);
        assert_eq!((got.tangential, got.sagittal), (t, s));
        cuts.push(0.5 * (t + s));
    }
    assert!((cuts[0] - cuts[1]).abs() > 1e-3, "the cuts' average depends on the turn: {cuts:?}");
}

/// A round Gaussian stack keeps the 1-D path (no planes), its mean MTF the closed form; one
/// whose σ along x is 1e-4 larger takes the 2-D path, and its mean over azimuth equals the old
/// `(T + S)/2` to 1e-8 (they differ by `e^{−aA}(cosh aB − I0(aB)) ≈ e^{−aA}(aB)²/4`, below
/// 1e-9 here).
#[test]
fn a_round_stack_keeps_the_average_of_its_cuts() {
    let (nu_max, detected) = (1e5, band(800.0, 5.0));
    let lens = elliptical_stack(2.5e-6, 2.5e-6, 0.3);
    assert!(!lens.table().is_two_dimensional() && !lens.table().is_direction_dependent());
    let poly = optics::Polychromatic::with_settings(&lens, &detected, optics::Field::ON_AXIS, nu_max, None, settings())
        .unwrap();
    assert!(!poly.has_pupil_grid());
    let round = poly.mean_mtf().0;
    let want = closed_form_azimuthal_mean(2.5e-6, 2.5e-6, nu_max);
    assert!((round - want).abs() < 1e-6 * want, "{round} vs {want}");
    let lens = elliptical_stack(2.5e-6 * (1.0 + 1e-4), 2.5e-6, 0.0);
    assert!(lens.table().is_two_dimensional());
    let poly = optics::Polychromatic::with_settings(&lens, &detected, optics::Field::ON_AXIS, nu_max, None, settings())
        .unwrap();
    let over = poly.mean_mtf_over_azimuth(0.0, None);
    let old = 0.5 * (over.tangential + over.sagittal);
    eprintln!("nearly round: over azimuth {:.10} vs (T + S)/2 {old:.10}", over.mean);
    assert!((over.mean - old).abs() < 1e-8, "{} vs {old}", over.mean);
}
