//! Tests of the slow reference (`optics::reference`): its quadrature, the defocus OTF against the
//! docs/physics.md test vectors, identities and an independent formula, and the mean MTF against closed
//! forms and independent quadratures.
//!
//! Every golden value states its source and tolerance. Nothing here uses the fast path.

use optics::reference::{
    GK21, GK61, ReferenceScene, integrate, integrate_modulus, mean_mtf, mean_mtf_quadrature, otf_defocus,
    otf_geometric, otf_hopkins, otf_hopkins_terms, polychromatic_otf,
};
use std::f64::consts::PI;

/// Closed-form diffraction-limited MTF, `MTF_0(s) = (2/π)[acos s − s√(1−s²)]` (docs/physics.md).
fn mtf0(s: f64) -> f64 {
    if s >= 1.0 {
        return 0.0;
    }
    (2.0 / PI) * (s.acos() - s * (1.0 - s * s).sqrt())
}

/// Closed form of `∫_0^x MTF_0(s) ds` for `0 ≤ x ≤ 1`.
///
/// Derivation: `MTF_0 = (2/π)[acos s − s√(1−s²)]`.
/// * `∫ acos s ds = s acos s − √(1−s²)` (by parts: `d/ds acos s = −1/√(1−s²)`), so
///   `∫_0^x acos s ds = x acos x − √(1−x²) + 1`.
/// * `∫ s√(1−s²) ds = −(1−s²)^{3/2}/3`, so `∫_0^x s√(1−s²) ds = [1 − (1−x²)^{3/2}]/3`.
///
/// Hence `∫_0^x MTF_0 = (2/π)[x acos x + 2/3 − √(1−x²) + (1−x²)^{3/2}/3]`; at `x = 1` this is
/// `4/(3π)`, the docs/physics.md identity. Past the cutoff (`x > 1`) the integral stays at `4/(3π)`.
fn mtf0_integral(x: f64) -> f64 {
    let x = x.min(1.0);
    let r = (1.0 - x * x).sqrt();
    (2.0 / PI) * (x * x.acos() + 2.0 / 3.0 - r + r * r * r / 3.0)
}

/// Paper lens (docs/physics.md "The metric"): f0 = 3.36 mm, λ0 = 800 nm.
const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;

/// Gaussian photoelectron density `λ exp(−(λ−c)²/(2σ²))`, σ = range/(2√2) (docs/physics.md), with
/// range `c ± 12σ` clipped to positive wavelengths. Returns (σ, λ_min, λ_max).
fn gaussian(range_m: f64) -> (f64, f64, f64) {
    let sigma = range_m / (2.0 * 2f64.sqrt());
    (sigma, (LAMBDA0 - 12.0 * sigma).max(1e-9), LAMBDA0 + 12.0 * sigma)
}

/// Runs `body` with a reference scene for a Gaussian spectrum centred at λ0.
fn with_gaussian_scene<R>(
    range_nm: f64,
    f_number: f64,
    pitch_m: f64,
    pixel_mtf: bool,
    body: impl FnOnce(&ReferenceScene<'_>) -> R,
) -> R {
    let (sigma, lo, hi) = gaussian(range_nm * 1e-9);
    let density = move |l: f64| l * (-(l - LAMBDA0) * (l - LAMBDA0) / (2.0 * sigma * sigma)).exp();
    let scene = ReferenceScene {
        density: &density,
        lambda_min: lo,
        lambda_max: hi,
        breakpoints: &[],
        f_number,
        focal_length_m: F0,
        design_wavelength_m: LAMBDA0,
        pixel_pitch_m: pitch_m,
        pixel_mtf,
    };
    body(&scene)
}

/// The paper's lens and camera (F/2.5, f0 = 3.36 mm, λ0 = 800 nm, 5.2 µm, no pixel MTF) over
/// `[lo, hi]` with the photoelectron `density`.
fn paper_scene(density: &dyn Fn(f64) -> f64, lo: f64, hi: f64) -> ReferenceScene<'_> {
    ReferenceScene {
        density,
        lambda_min: lo,
        lambda_max: hi,
        breakpoints: &[],
        f_number: 2.5,
        focal_length_m: F0,
        design_wavelength_m: LAMBDA0,
        pixel_pitch_m: 5.2e-6,
        pixel_mtf: false,
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

// ---------------------------------------------------------------------------------------------
// Quadrature
// ---------------------------------------------------------------------------------------------

#[test]
fn gauss_kronrod_rules_are_exact_to_their_degree() {
    // K15 is exact for degree ≤ 22 and its G7 part (odd: the centre is a Gauss node) for ≤ 13;
    // K21 for ≤ 31 and its G10 part for ≤ 19; K61 for ≤ 91, G30 for ≤ 59.
    // Exact: ∫_0^1 x^k dx = 1/(k + 1). Tolerance: rounding, 1e-14 relative.
    for (rule, kronrod_degree, gauss_degree) in [(optics::quad::GK15, 22, 13), (GK21, 31, 19), (GK61, 91, 59)] {
        for k in 0..=kronrod_degree {
            let (v, _) = rule.panel(|x: f64| x.powi(k), 0.0, 1.0);
            assert!(rel(v, 1.0 / f64::from(k + 1)) < 1e-14, "{} pts, x^{k}: {v}", rule.points());
        }
        // Up to the Gauss degree, Kronrod and Gauss agree and the error estimate is rounding.
        let (_, e) = rule.panel(|x: f64| x.powi(gauss_degree), 0.0, 1.0);
        assert!(e < 1e-14, "{e}");
        // On a function neither rule integrates well (poles at ±0.1i) the estimate is not rounding.
        let (_, e) = rule.panel(|x: f64| 1.0 / (1.0 + 100.0 * x * x), -1.0, 1.0);
        assert!(e > 1e-12, "{e}");
    }
}

#[test]
fn adaptive_quadrature_known_integrals() {
    // ∫_0^π sin = 2 (exact).
    let q = integrate(GK21, f64::sin, &[0.0, PI], 1e-13, 0.0);
    assert!((q.value - 2.0).abs() < 1e-14 && q.converged, "{q:?}");
    // Endpoint singularity: ∫_0^1 √x dx = 2/3, by bisection towards 0.
    let q = integrate(GK21, f64::sqrt, &[0.0, 1.0], 1e-13, 0.0);
    assert!((q.value - 2.0 / 3.0).abs() < 1e-13 && q.converged, "{q:?}");
    // Oscillatory: ∫_0^100 cos(10x) dx = sin(1000)/10, from a single starting panel.
    let q = integrate(GK61, |x: f64| (10.0 * x).cos(), &[0.0, 100.0], 1e-13, 0.0);
    assert!((q.value - 1000f64.sin() / 10.0).abs() < 1e-12, "{q:?}");
    // Kink at a breakpoint: ∫_0^1 |x − 1/3| dx = 5/18.
    let q = integrate(GK21, |x: f64| (x - 1.0 / 3.0).abs(), &[1.0, 1.0 / 3.0, 0.0], 1e-15, 0.0);
    assert!((q.value - 5.0 / 18.0).abs() < 1e-15);
    // Relative tolerance: ∫_1^2 1e30/x dx = 1e30 ln 2.
    let q = integrate(GK21, |x: f64| 1e30 / x, &[1.0, 2.0], 0.0, 1e-13);
    assert!(rel(q.value, 1e30 * 2f64.ln()) < 1e-13);
}

#[test]
fn modulus_quadrature_splits_at_sign_changes() {
    // ∫_0^10 |sin x| dx = 6 + ∫_{3π}^{10} (−sin x) dx = 7 + cos 10 (sign changes at π, 2π, 3π).
    let q = integrate_modulus(GK21, f64::sin, |_| 1.0, &[0.0, 10.0], 1e-14, 0.0);
    assert!((q.value - (7.0 + 10f64.cos())).abs() < 1e-13, "{q:?}");
    // With a weight: ∫_{-1}^{1} e^x |x| dx = ∫_0^1 x e^x + ∫_{-1}^0 (−x) e^x = 1 + (1 − 2/e).
    let q = integrate_modulus(GK21, |x| x, f64::exp, &[-1.0, 1.0], 1e-15, 0.0);
    assert!((q.value - (2.0 - 2.0 / std::f64::consts::E)).abs() < 1e-14, "{q:?}");
}

// ---------------------------------------------------------------------------------------------
// Monochromatic OTF
// ---------------------------------------------------------------------------------------------

#[test]
fn otf_matches_physics_md_test_vectors() {
    // Source: docs/physics.md "Test vectors and identities" (s, w → OTF), printed to 5 decimals:
    // tolerance 1e-5.
    for (s, w, expected) in optics::reference::PHYSICS_TEST_VECTORS {
        let v = otf_defocus(s, w);
        assert!((v - expected).abs() < 1e-5, "OTF({s}, {w}) = {v}, expected {expected}");
    }
}

#[test]
fn otf_without_defocus_is_the_closed_form_mtf0() {
    // Closed form MTF_0 (docs/physics.md), also for a → 0 (w tiny): 1e-12 absolute, near both ends.
    let ss = [1e-12, 1e-9, 1e-6, 1e-3, 0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.999, 1.0 - 1e-6, 1.0 - 1e-9];
    for s in ss {
        for w in [0.0, 1e-12, -1e-12] {
            let v = otf_defocus(s, w);
            assert!((v - mtf0(s)).abs() < 1e-12, "s = {s}, w = {w}: {v} vs {}", mtf0(s));
        }
    }
}

#[test]
fn otf_limits_and_symmetries() {
    for w in [0.0, 0.3, 7.0, 150.0] {
        assert_eq!(otf_defocus(0.0, w), 1.0);
        assert_eq!(otf_defocus(1.0, w), 0.0);
        assert_eq!(otf_defocus(1.5, w), 0.0);
        for s in [0.01, 0.3, 0.8] {
            let v = otf_defocus(s, w);
            assert_eq!(v, otf_defocus(-s, w));
            assert_eq!(v, otf_defocus(s, -w));
            assert!(v.abs() <= mtf0(s) + 1e-12, "|OTF| ≤ MTF_0 (Hopkins): s {s} w {w}");
        }
    }
}

/// Independent form of the same OTF (Hopkins): integrating the overlap of the two shifted pupils
/// over `y` first instead of `x`, `OTF = (4/π) ∫_0^{1−s} cos(a x) √(1 − (x + s)²) dx`, `a = 8π w s`.
/// (The phase difference of the two sheared defocused pupils is `2π w [(x+s)² − (x−s)²] = a x`.)
fn otf_hopkins_x_form(s: f64, w: f64) -> f64 {
    let a = 8.0 * PI * w * s;
    let top = 1.0 - s;
    let n = (a * top / PI).ceil().max(1.0) as usize + 1;
    let pts: Vec<f64> = (0..=n).map(|k| top * k as f64 / n as f64).collect();
    let f = |x: f64| (a * x).cos() * ((1.0 - (x + s)) * (1.0 + x + s)).max(0.0).sqrt();
    4.0 / PI * integrate(GK21, f, &pts, 1e-15, 0.0).value
}

#[test]
fn otf_agrees_with_the_x_form_to_1e12() {
    for w in [0.3, 2.0, 20.0, 200.0] {
        for s in [0.003, 0.1, 0.37, 0.8, 0.99] {
            let (v, h) = (otf_defocus(s, w), otf_hopkins_x_form(s, w));
            assert!((v - h).abs() < 1e-12, "s {s} w {w}: {v} vs {h}");
        }
    }
}

#[test]
fn otf_integral_identities() {
    // ∫_0^1 MTF_0 ds = 4/(3π) (docs/physics.md), tolerance 1e-12.
    let q = integrate(GK21, |s| otf_defocus(s, 0.0), &[0.0, 0.5, 1.0], 1e-14, 0.0);
    assert!((q.value - 4.0 / (3.0 * PI)).abs() < 1e-12, "{}", q.value);
    // 2∫_0^1 OTF(s, w) s ds = Strehl/4, Strehl = [sin(πw)/(πw)]² (docs/physics.md), tolerance 1e-9.
    // The values printed next to it (w = 0.25 → 0.20264, w = 0.5 → 0.10132) are Strehl/4, i.e.
    // 2∫ OTF s ds (Strehl itself is 0.81057 and 0.40528): checked to 1e-5.
    for (w, printed) in [(0.25, 0.20264), (0.5, 0.10132), (3.3, f64::NAN)] {
        let strehl = ((PI * w).sin() / (PI * w)).powi(2);
        let pts: Vec<f64> = (0..=16).map(|k| f64::from(k) / 16.0).collect();
        let q = integrate(GK21, |s| s * otf_defocus(s, w), &pts, 1e-13, 0.0);
        let from_otf = 8.0 * q.value;
        assert!((from_otf - strehl).abs() < 1e-9, "w {w}: {from_otf} vs {strehl}");
        if printed.is_finite() {
            assert!((from_otf / 4.0 - printed).abs() < 1e-5, "{from_otf}");
        }
    }
}

#[test]
fn otf_tends_to_the_geometric_limit() {
    // Geometric limit (docs/physics.md): OTF → 2 J1(x)/x, x = π d ν, d = 2|Δz| NA. With Δz = 8 F#² w λ,
    // NA = 1/(2F#) and ν = s/(λ F#): x = 8π w s = a. The worst deviation over s ∈ (0, 0.5]
    // shrinks as w grows (measured: 6.4e-2, 2.5e-2, 1.1e-2, 2.8e-3 for w = 3, 10, 30, 100).
    let worst = |w: f64| {
        (1..=200)
            .map(|k| {
                let s = 0.5 * f64::from(k) / 200.0;
                (otf_defocus(s, w) - otf_geometric(s, w)).abs()
            })
            .fold(0.0, f64::max)
    };
    let devs: Vec<f64> = [3.0, 10.0, 30.0, 100.0].map(worst).to_vec();
    assert!(devs.windows(2).all(|d| d[1] < d[0]), "{devs:?}");
    assert!(devs[3] < 1e-2, "{devs:?}");
    // and it is only an approximation: at small defocus it is far off (w = 0.5, s = 0.3:
    // 2 J1(3.77)/3.77 = −0.01 against an OTF of 0.3)
    assert!((otf_defocus(0.3, 0.5) - otf_geometric(0.3, 0.5)).abs() > 0.1);
    // limits: 1 at zero frequency or zero defocus, 0 past the cutoff
    assert_eq!(otf_geometric(0.0, 5.0), 1.0);
    assert_eq!(otf_geometric(0.4, 0.0), 1.0);
    assert_eq!(otf_geometric(1.0, 5.0), 0.0);
}

/// Hopkins' series cut after `terms` terms: converged (to the reference's 1e-12) once the Bessel
/// orders it reaches, `2 terms`, pass `a + 12 a^{1/3} + 30` (where `Jn(a)` < 1e-17), identical to
/// the full series with its own term count, and visibly truncated with too few terms.
#[test]
fn hopkins_series_truncated_converges_to_the_full_series() {
    for w in [0.25, 1.0, 5.0, 30.0] {
        for s in [0.05, 0.3, 0.6, 0.9] {
            let a = 8.0 * PI * w * s;
            let enough = ((a + 12.0 * a.cbrt() + 30.0) / 2.0).ceil() as usize;
            let full = otf_hopkins(s, w);
            let cut = otf_hopkins_terms(s, w, enough);
            assert!((cut - otf_defocus(s, w)).abs() < 1e-12, "s {s} w {w}: {cut} vs {}", otf_defocus(s, w));
            assert!((cut - full).abs() < 1e-14, "s {s} w {w}: {cut} vs {full}");
            assert_eq!(otf_hopkins_terms(s, w, (a + 12.0 * a.cbrt() + 30.0) as usize + 1), full);
        }
    }
    // a = 8π · 1 · 0.5 = 12.6: five terms reach J10 only (measured error 2.2e-3)
    assert!((otf_hopkins_terms(0.5, 1.0, 5) - otf_defocus(0.5, 1.0)).abs() > 1e-4);
    // a = 8π · 30 · 0.6 = 452: the error only falls once 2 terms passes a (measured 4.4e-6,
    // 1.5e-10, 3e-18 at 150, 240, 300 terms)
    let (s, w) = (0.6, 30.0);
    let errors: Vec<f64> = [150, 240, 300].map(|k| (otf_hopkins_terms(s, w, k) - otf_defocus(s, w)).abs()).to_vec();
    assert!(errors[0] > 1e-6 && errors[1] < 1e-9 && errors[2] < 1e-12, "{errors:?}");
}

// ---------------------------------------------------------------------------------------------
// Polychromatic OTF and mean MTF
// ---------------------------------------------------------------------------------------------

#[test]
fn polychromatic_otf_basic_properties() {
    with_gaussian_scene(50.0, 2.5, 5.2e-6, false, |scene| {
        assert!((polychromatic_otf(scene, 0.0, 1e-10) - 1.0).abs() < 1e-13);
        let nu = 6.0e4;
        let v = polychromatic_otf(scene, nu, 1e-10);
        assert_eq!(v, polychromatic_otf(scene, -nu, 1e-10));
        assert!(v.abs() < 1.0);
        // Past the cutoff of the shortest wavelength everything is zero.
        assert_eq!(polychromatic_otf(scene, 1.01 / (scene.lambda_min * 2.5), 1e-10), 0.0);
    });
}

#[test]
fn polychromatic_otf_agrees_with_a_composite_simpson_sum() {
    // Independent wavelength quadrature: composite Simpson with 40 000 intervals over the whole
    // range (h = 0.011 nm against a 17.7 nm σ and a ≈ 12 nm oscillation period at this ν).
    // Tolerance 1e-9 absolute.
    with_gaussian_scene(50.0, 2.5, 5.2e-6, false, |scene| {
        let nu = 0.5 * scene.nyquist();
        let (lo, hi) = (scene.lambda_min, scene.lambda_max);
        let num = simpson(
            |l| (scene.density)(l) * otf_defocus(nu * l * scene.f_number, scene.defocus_waves(l)),
            lo,
            hi,
            40_000,
        );
        let simpson = num / simpson(|l| (scene.density)(l), lo, hi, 40_000);
        let v = polychromatic_otf(scene, nu, 1e-10);
        assert!((v - simpson).abs() < 1e-9, "{v} vs {simpson}");
    });
}

#[test]
fn monochromatic_mean_mtf_is_the_closed_form_mean_of_mtf0() {
    // A 1e-3 nm Gaussian at λ0 is monochromatic: mean_mtf = (1/s_N) ∫_0^{s_N} MTF_0 ds with
    // s_N = ν_N λ0 F# (closed form, `mtf0_integral`). Tolerance 3e-9 relative: the residual
    // defocus (w ≈ 4e-5 waves at 1σ) lowers the OTF by O(w²) ≈ 1e-9 (measured −1.3e-10 to
    // −9.2e-10), and the density's width is only 3.5e9 float steps of λ.
    for (f_number, pitch) in [(2.5, 5.2e-6), (5.0, 2e-6), (1.4, 10e-6), (3.0, 2.6e-6)] {
        with_gaussian_scene(1e-3, f_number, pitch, false, |scene| {
            let s_n = scene.nyquist() * LAMBDA0 * f_number;
            let expected = mtf0_integral(s_n) / s_n;
            let m = mean_mtf(scene, 1e-10);
            assert!(rel(m, expected) < 3e-9, "F/{f_number} p {pitch}: {m} vs {expected}");
        });
    }
}

#[test]
fn pixel_mtf_mean_agrees_with_an_independent_integral() {
    // Monochromatic with the pixel aperture: (1/ν_N) ∫ MTF_0(ν λ0 F#) |sinc(p ν)| dν by a plain
    // adaptive integral of closed forms. Same tolerance reasoning as above (3e-9 relative).
    let (f_number, p) = (2.5, 5.2e-6);
    with_gaussian_scene(1e-3, f_number, p, true, |scene| {
        let nu_n = scene.nyquist();
        let f = |nu: f64| {
            let x = PI * p * nu;
            let sinc = if x == 0.0 { 1.0 } else { x.sin() / x };
            mtf0(nu * LAMBDA0 * f_number) * sinc.abs()
        };
        let expected = integrate(GK21, f, &[0.0, nu_n], 1e-14, 0.0).value / nu_n;
        let m = mean_mtf(scene, 1e-10);
        assert!(rel(m, expected) < 3e-9, "{m} vs {expected}");
    });
}

#[test]
fn mean_mtf_bounds_and_pixel_mtf() {
    for (range, f_number, p) in [(10.0, 2.5, 5.2e-6), (100.0, 1.4, 10e-6), (50.0, 5.0, 2e-6)] {
        let off = with_gaussian_scene(range, f_number, p, false, |s| mean_mtf(s, 1e-8));
        let on = with_gaussian_scene(range, f_number, p, true, |s| mean_mtf(s, 1e-8));
        assert!(0.0 < on && on < off && off <= 1.0, "{range} nm F/{f_number}: {on} {off}");
        // The pixel MTF is at least sinc(1/2) = 2/π at Nyquist.
        assert!(on > 2.0 / PI * off);
    }
}

#[test]
fn mean_mtf_is_independent_of_the_density_scale() {
    let (sigma, lo, hi) = gaussian(50e-9);
    let m = |scale: f64| {
        let density = move |l: f64| scale * l * (-(l - LAMBDA0).powi(2) / (2.0 * sigma * sigma)).exp();
        let scene = paper_scene(&density, lo, hi);
        mean_mtf(&scene, 1e-10)
    };
    assert!(rel(m(1e25), m(1.0)) < 1e-12);
}

#[test]
fn paper_scene_golden_values() {
    // Source: this reference (F/2.5, f0 3.36 mm, λ0 800 nm, λ × Gaussian at 800 nm, 5.2 µm
    // pixels, no pixel MTF). Convergence: unchanged to ≤ 2e-15 when the tolerance runs from 1e-6
    // to 1e-11, when the initial λ and y meshes are made 2–4× finer or coarser, and when the
    // frequency integral uses G30–K61 instead of G10–K21. Tolerance 1e-9 relative.
    for (range, golden) in
        [(10.0, 0.809_351_611_595_459), (50.0, 0.438_848_221_668_729), (100.0, 0.282_524_216_168_544)]
    {
        let q = with_gaussian_scene(range, 2.5, 5.2e-6, false, |s| mean_mtf_quadrature(s, 1e-10));
        assert!(q.converged);
        assert!(rel(q.value, golden) < 1e-9, "{range} nm: {} vs {golden}", q.value);
    }
    // Paper (Results, Fig. 2): with photon count ∝ range, ASNR ∝ √range · mean MTF is best near
    // 50 nm among 10, 50 and 100 nm.
    let asnr = |r: f64, m: f64| r.sqrt() * m;
    assert!(asnr(50.0, 0.438_848) > asnr(10.0, 0.809_352));
    assert!(asnr(50.0, 0.438_848) > asnr(100.0, 0.282_524));
}

#[test]
fn mean_mtf_agrees_with_a_composite_simpson_over_frequency() {
    // Independent frequency quadrature: composite Simpson with 200 intervals of
    // |polychromatic_otf| (no sign change in this scene, so |OTF_poly| is smooth).
    // Tolerance 1e-8 relative (Simpson's h⁴ error).
    with_gaussian_scene(10.0, 2.5, 5.2e-6, false, |scene| {
        let nu_n = scene.nyquist();
        let simpson = simpson(|nu| polychromatic_otf(scene, nu, 1e-11).abs(), 0.0, nu_n, 200) / nu_n;
        let m = mean_mtf(scene, 1e-10);
        assert!(rel(m, simpson) < 1e-8, "{m} vs {simpson}");
    });
}

#[test]
fn top_hat_spectrum() {
    // A flat spectrum over 775–825 nm (jumps at the ends, which are the integration limits).
    let flat = |l: f64| {
        if (775e-9..=825e-9).contains(&l) { 1.0 } else { 0.0 }
    };
    let scene = paper_scene(&flat, 775e-9, 825e-9);
    let m_flat = mean_mtf(&scene, 1e-9);
    assert!(0.0 < m_flat && m_flat < 1.0);
    // Narrowing a flat band towards λ0 tends to the monochromatic value.
    let narrow = |l: f64| {
        if (l - LAMBDA0).abs() <= 0.5e-12 { 1.0 } else { 0.0 }
    };
    let scene_narrow =
        ReferenceScene { density: &narrow, lambda_min: LAMBDA0 - 0.5e-12, lambda_max: LAMBDA0 + 0.5e-12, ..scene };
    let s_n = scene.nyquist() * LAMBDA0 * 2.5;
    assert!(rel(mean_mtf(&scene_narrow, 1e-10), mtf0_integral(s_n) / s_n) < 3e-9);
    // A ramp from 0.5 (below 790 nm) to 1.5 (above 810 nm): kinks at 790 and 810 nm.
    let tent = |l: f64| ((l - 790e-9) / 20e-9).clamp(0.0, 1.0) + 0.5;
    let bps = [790e-9, 810e-9];
    let scene_tent = ReferenceScene { density: &tent, breakpoints: &bps, ..scene };
    let q = mean_mtf_quadrature(&scene_tent, 1e-9);
    assert!(q.converged && 0.0 < q.value && q.value < 1.0);
}

#[test]
fn mean_mtf_with_sign_changes_agrees_with_piecewise_simpson() {
    // A narrow spectrum away from focus (Gaussian at 850 nm, range 10 nm, F/2.5, 5.2 µm: about
    // 2.4 waves of defocus) has an OTF_poly that changes sign six times below Nyquist.
    // Independent check: roots by plain bisection from a 400-point scan, then composite Simpson
    // (200 intervals) on each piece between roots. Tolerance 1e-9 relative (measured 2e-12 with
    // 400 intervals per piece).
    let centre = 850e-9;
    let sigma = 10e-9 / (2.0 * 2f64.sqrt());
    let density = move |l: f64| l * (-(l - centre) * (l - centre) / (2.0 * sigma * sigma)).exp();
    let scene = paper_scene(&density, centre - 12.0 * sigma, centre + 12.0 * sigma);
    let nu_n = scene.nyquist();
    let g = |nu: f64| polychromatic_otf(&scene, nu, 1e-11);
    let n = 400;
    let grid: Vec<f64> = (0..=n).map(|k| nu_n * f64::from(k) / f64::from(n)).collect();
    let vals: Vec<f64> = grid.iter().map(|&x| g(x)).collect();
    let mut cuts = vec![0.0];
    for k in 0..grid.len() - 1 {
        if (vals[k] > 0.0) != (vals[k + 1] > 0.0) {
            let (mut lo, mut hi) = (grid[k], grid[k + 1]);
            for _ in 0..50 {
                let m = 0.5 * (lo + hi);
                if (g(m) > 0.0) == (vals[k] > 0.0) {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            cuts.push(0.5 * (lo + hi));
        }
    }
    cuts.push(nu_n);
    assert_eq!(cuts.len() - 2, 6, "{cuts:?}");
    let mut total = 0.0;
    for w in cuts.windows(2) {
        total += simpson(|nu| g(nu).abs(), w[0], w[1], 200);
    }
    let expected = total / nu_n;
    let q = mean_mtf_quadrature(&scene, 1e-10);
    assert!(q.converged);
    assert!(rel(q.value, expected) < 1e-9, "{} vs {expected}", q.value);
}

/// Composite Simpson's rule with `n` (even) intervals on `[a, b]`: the plain independent check.
fn simpson(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, n: u32) -> f64 {
    let h = (b - a) / f64::from(n);
    let mut sum = 0.0;
    for k in 0..=n {
        let c = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        sum += c * f(a + h * f64::from(k));
    }
    sum * h / 3.0
}
