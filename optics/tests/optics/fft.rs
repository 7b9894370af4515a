//! The FFT OTF path against the exact 1-D path (`defocus_otf`), Hopkins' Bessel series, closed
//! forms for the annulus and the half disc, and its own invariants: conjugate symmetry,
//! Parseval, unit weight, decentre as a pure tilt, coma and tilt phases.
//!
//! Tolerances, established by measurement (module docs of `optics::fft`):
//! - a slice, at grid samples and between them, `s ≤ 0.6`, `w ≤ 2` waves: `0.2/N` (the worst
//!   point is the first lag, where the pixel-smoothed cone gives `−0.09/N`);
//! - the mean MTF over `[0, s_max]`: [`MEAN_TOLERANCE`] (`O(N⁻² log N)`).

use std::f64::consts::{FRAC_PI_2, PI};

use num_complex::Complex64;
use optics::fft::{
    Aberrations, Aperture, Otf, OtfPlan, SampledPupil, convergence_table, defocus_mean_mtf, pupil_samples_for,
    reduce_decentred_circle,
};
use optics::{defocus_otf, mtf_diffraction_limited, mtf_diffraction_limited_mean, reference};

/// Any wavelength: the OTF depends on `W/λ` only.
const LAMBDA: f64 = 0.8e-6;

/// `(N, tolerance)` on the mean MTF against the exact path (measured: 3.4e-4, 1.06e-4, 3.2e-5 at
/// worst over `w ∈ {0, 0.5, 1, 2}` with `N ≥ 50 w`, `s_max ∈ {0.2, 0.6}`, azimuths 0 and 0.5 rad).
const MEAN_TOLERANCE: [(usize, f64); 3] = [(64, 4e-4), (128, 1.2e-4), (256, 4e-5)];

/// Pointwise tolerance on a slice (see the file docs).
fn slice_tolerance(n: usize) -> f64 {
    0.2 / n as f64
}

fn otf_of(n: usize, s_max: f64, aperture: &Aperture, aberrations: &Aberrations) -> Otf {
    let mut plan = OtfPlan::new(n, s_max).unwrap();
    let pupil = SampledPupil::new(n, aperture, aberrations).unwrap();
    let mut otf = Otf::new();
    plan.otf(&pupil, LAMBDA, &mut otf);
    otf
}

fn defocus(w: f64) -> Aberrations {
    Aberrations::defocus(w * LAMBDA)
}

/// Largest error of the `+x` grid samples and of interpolated points along 0.7 rad, `s ≤ 0.6`.
fn slice_error(otf: &Otf, exact: impl Fn(f64) -> f64) -> f64 {
    let n = otf.n();
    let mut worst: f64 = 0.0;
    for k in 1..=(0.6 * n as f64) as i64 {
        let s = k as f64 / n as f64;
        worst = worst.max((otf.sample(k, 0) - Complex64::new(exact(s), 0.0)).norm());
    }
    for i in 0..240 {
        let s = 0.6 * (i as f64 + 0.5) / 240.0;
        worst = worst.max((otf.at(s, 0.7) - Complex64::new(exact(s), 0.0)).norm());
    }
    worst
}

#[test]
fn centred_defocus_slices_match_the_exact_path_and_improve_with_n() {
    for w in [0.0, 0.5, 2.0] {
        let mut errors = Vec::new();
        for n in [64, 128, 256] {
            let otf = otf_of(n, 0.6, &Aperture::circle(), &defocus(w));
            let e = slice_error(&otf, |s| defocus_otf(s, w));
            let e_hopkins = slice_error(&otf, |s| reference::otf_hopkins(s, w));
            assert!(e < slice_tolerance(n), "w = {w}, N = {n}: {e:e}");
            assert!(e_hopkins < slice_tolerance(n), "w = {w}, N = {n}: Hopkins {e_hopkins:e}");
            errors.push(e);
        }
        assert!(errors[2] < errors[0] / 3.0, "w = {w}: no convergence {errors:?}");
    }
}

#[test]
fn mean_mtf_matches_the_exact_path() {
    for (n, tol) in MEAN_TOLERANCE {
        for s_max in [0.2, 0.6] {
            let circle = otf_of(n, s_max, &Aperture::circle(), &Aberrations::default());
            let exact = mtf_diffraction_limited_mean(s_max);
            for azimuth in [0.0, 0.5] {
                let got = circle.mean_mtf(azimuth, s_max);
                assert!((got - exact).abs() < tol, "N = {n}, s_max = {s_max}, az {azimuth}: {got} vs {exact}");
            }
            // the sampling rule of the module docs, N ≳ 50 w
            for w in [0.5, 1.0, 2.0].into_iter().filter(|&w| n as f64 >= 50.0 * w) {
                let otf = otf_of(n, s_max, &Aperture::circle(), &defocus(w));
                let exact = defocus_mean_mtf(w, s_max);
                for azimuth in [0.0, 0.5] {
                    let got = otf.mean_mtf(azimuth, s_max);
                    assert!((got - exact).abs() < tol, "N = {n}, w = {w}, s_max = {s_max}: {got} vs {exact}");
                }
            }
        }
    }
}

/// The table of the module docs, for small N (errors only; times are printed, never asserted).
#[test]
fn convergence_table_errors_fall_with_sampling() {
    for w in [0.0, 1.0] {
        let table = convergence_table(w, 0.2, &[32, 64, 128, 256]);
        for (n, error, seconds) in &table {
            println!("w = {w}, N = {n}: mean-MTF error {error:.2e}, {seconds:.1e} s");
        }
        assert_eq!(table.len(), 4);
        for pair in table.windows(2) {
            assert!(pair[1].1 < pair[0].1, "w = {w}: {table:?}");
        }
        assert!(table[2].1 < 1e-4, "the issue's 1e-4 at N = 128: {table:?}");
    }
}

#[test]
fn azimuthal_average_of_a_centred_circle_is_the_radial_otf() {
    let w = 0.5;
    let otf = otf_of(128, 0.6, &Aperture::circle(), &defocus(w));
    for s in [0.1, 0.3, 0.55] {
        let exact = defocus_otf(s, w);
        assert!((otf.azimuthal_mean_mtf(s) - exact.abs()).abs() < slice_tolerance(128), "s = {s}");
        assert!((otf.azimuthal_mean_otf(s) - exact).abs() < slice_tolerance(128), "s = {s}");
    }
}

/// Annulus, no aberration: `[L(1,1) − 2 L(1,ε) + L(ε,ε)](2s) / (π(1 − ε²))` with `L(r1, r2)(d)`
/// the overlap area of two discs of radii `r1`, `r2` at distance `d`.
#[test]
fn annulus_matches_the_disc_overlap_formula() {
    fn overlap(r1: f64, r2: f64, d: f64) -> f64 {
        if d <= (r1 - r2).abs() {
            return PI * r1.min(r2).powi(2);
        }
        if d >= r1 + r2 {
            return 0.0;
        }
        r2 * r2 * ((d * d + r2 * r2 - r1 * r1) / (2.0 * d * r2)).acos()
            + r1 * r1 * ((d * d + r1 * r1 - r2 * r2) / (2.0 * d * r1)).acos()
            - 0.5 * ((-d + r1 + r2) * (d + r2 - r1) * (d - r2 + r1) * (d + r1 + r2)).sqrt()
    }
    let eps = 0.4;
    let exact = |s: f64| {
        (overlap(1.0, 1.0, 2.0 * s) - 2.0 * overlap(1.0, eps, 2.0 * s) + overlap(eps, eps, 2.0 * s))
            / (PI * (1.0 - eps * eps))
    };
    for n in [64, 128] {
        let otf = otf_of(n, 0.6, &Aperture::annulus(eps).unwrap(), &Aberrations::default());
        let e = slice_error(&otf, exact);
        // two edges: twice the circle's cone error
        assert!(e < 2.0 * slice_tolerance(n), "N = {n}: {e:e}");
    }
}

/// The half disc `y ≥ 0` (sector [0, π]): along `x` the overlap is half the circle's lens,
/// `OTF = MTF_0(s)`; along `y` it is the segment above the chord `y = 2s`, `OTF = MTF_0(2s)`.
#[test]
fn half_disc_sector_matches_its_closed_form_in_both_directions() {
    for n in [64, 128] {
        let otf = otf_of(n, 0.45, &Aperture::sector(0.0, PI).unwrap(), &Aberrations::default());
        let mut worst: f64 = 0.0;
        for k in 1..=(0.45 * n as f64) as i64 {
            let s = k as f64 / n as f64;
            worst = worst.max((otf.sample(k, 0) - Complex64::new(mtf_diffraction_limited(s), 0.0)).norm());
            worst = worst.max((otf.sample(0, k) - Complex64::new(mtf_diffraction_limited(2.0 * s), 0.0)).norm());
        }
        assert!(worst < slice_tolerance(n), "N = {n}: {worst:e}");
    }
}

#[test]
fn masked_circle_matches_the_exact_circle() {
    let mask = Aperture::mask(|x, y| x * x + y * y <= 1.0);
    let otf = otf_of(128, 0.2, &mask, &Aberrations::default());
    let got = otf.mean_mtf(0.0, 0.2);
    assert!((got - mtf_diffraction_limited_mean(0.2)).abs() < 1.2e-4, "{got}");
}

fn coma_like() -> (Aperture, Aberrations) {
    let aperture = Aperture::circle().decentred(0.3, -0.1).unwrap();
    let aberrations = Aberrations {
        w020_m: 0.4 * LAMBDA,
        w040_m: 0.6 * LAMBDA,
        w131_m: 0.3 * LAMBDA,
        w222_m: 0.2 * LAMBDA,
        field: 0.7,
        zernike_noll_m: vec![(7, 0.05 * LAMBDA), (12, 0.03 * LAMBDA)],
        ..Aberrations::default()
    };
    (aperture, aberrations)
}

#[test]
fn conjugate_symmetry_holds_on_the_grid_and_between_samples() {
    let (aperture, aberrations) = coma_like();
    let otf = otf_of(96, 0.3, &aperture, &aberrations);
    let k = otf.max_lag() as i64;
    let mut worst: f64 = 0.0;
    for ky in -k..=k {
        for kx in -k..=k {
            worst = worst.max((otf.sample(-kx, -ky) - otf.sample(kx, ky).conj()).norm());
        }
    }
    for (s, az) in [(0.05, 0.2), (0.17, 1.9), (0.29, 4.0)] {
        worst = worst.max((otf.at(s, az + PI) - otf.at(s, az).conj()).norm());
    }
    assert!(worst < 1e-13, "{worst:e}");
}

/// Parseval: `Σ PSF = M² Σ |P|²`; and the PSF peak over `(Σ A)²` is the Strehl ratio,
/// `[sin(πw)/(πw)]²` for pure defocus (docs/physics.md).
#[test]
fn parseval_between_pupil_and_psf() {
    let (aperture, aberrations) = coma_like();
    let mut plan = OtfPlan::new(64, 0.2).unwrap();
    let pupil = SampledPupil::new(64, &aperture, &aberrations).unwrap();
    let mut psf = Vec::new();
    plan.psf(&pupil, LAMBDA, &mut psf);
    let m = plan.padded_len() as f64;
    let pupil_energy: f64 = pupil.amplitude().iter().map(|a| a * a).sum();
    let psf_energy: f64 = psf.iter().sum();
    assert!((psf_energy / (m * m * pupil_energy) - 1.0).abs() < 1e-12, "{psf_energy} vs {}", m * m * pupil_energy);

    let w = 0.25;
    let pupil = SampledPupil::new(128, &Aperture::circle(), &defocus(w)).unwrap();
    let mut plan = OtfPlan::new(128, 0.2).unwrap();
    plan.psf(&pupil, LAMBDA, &mut psf);
    let sum_a: f64 = pupil.amplitude().iter().sum();
    let strehl = psf[0] / (sum_a * sum_a);
    let exact = ((PI * w).sin() / (PI * w)).powi(2);
    assert!((strehl - exact).abs() < 1e-4, "{strehl} vs {exact}");
}

#[test]
fn otf_at_zero_is_exactly_one() {
    let (aperture, aberrations) = coma_like();
    let shapes = [
        (Aperture::circle(), defocus(3.0)),
        (aperture, aberrations),
        (Aperture::disc(0.3, Some((0.5, 2.0))).unwrap(), defocus(1.0)),
        (Aperture::mask(|x, y| x.abs() + y.abs() < 0.9), Aberrations::default()),
    ];
    for (aperture, aberrations) in &shapes {
        let otf = otf_of(48, 0.3, aperture, aberrations);
        assert_eq!(otf.sample(0, 0), Complex64::new(1.0, 0.0), "{aperture:?}");
        assert_eq!(otf.at(0.0, 1.234), Complex64::new(1.0, 0.0), "{aperture:?}");
        assert_eq!(otf.mean_mtf(0.0, 0.0), 1.0);
    }
}

/// A decentred iris on a defocused lens is the centred pupil with a tilt `2 w dx x`: the OTF is
/// the centred one times `e^{−i 8π w (dx sx + dy sy)}` (a PSF shift of `4 w d λF#` toward `+d`),
/// exactly on the grid; with zero decentre it is the centred result bit for bit.
#[test]
fn decentred_defocus_is_a_pure_shift_and_zero_decentre_is_centred() {
    let (n, w, dx, dy) = (64, 0.7, 0.25, -0.15);
    let centred = otf_of(n, 0.4, &Aperture::circle(), &defocus(w));
    let zero = otf_of(n, 0.4, &Aperture::circle().decentred(0.0, 0.0).unwrap(), &defocus(w));
    assert_eq!(centred, zero);
    let shifted = otf_of(n, 0.4, &Aperture::circle().decentred(dx, dy).unwrap(), &defocus(w));
    let k = centred.max_lag() as i64;
    let mut worst: f64 = 0.0;
    for ky in -k..=k {
        for kx in -k..=k {
            let (sx, sy) = (kx as f64 / n as f64, ky as f64 / n as f64);
            let phase = Complex64::from_polar(1.0, -8.0 * PI * w * (dx * sx + dy * sy));
            worst = worst.max((shifted.sample(kx, ky) - centred.sample(kx, ky) * phase).norm());
        }
    }
    assert!(worst < 1e-12, "{worst:e}");
}

/// Spherical aberration seen through a decentred iris becomes coma and astigmatism: the OTF is
/// complex, its `0°` and `180°` slices differ in phase and its `0°` and `90°` slices in modulus,
/// and it differs from the centred pupil's.
#[test]
fn decentred_spherical_gives_a_complex_asymmetric_otf() {
    let lens = Aberrations { w040_m: 0.75 * LAMBDA, ..Aberrations::default() };
    let decentred = otf_of(96, 0.3, &Aperture::circle().decentred(0.4, 0.0).unwrap(), &lens);
    let centred = otf_of(96, 0.3, &Aperture::circle(), &lens);
    let (mut phase, mut modulus, mut vs_centred, mut centred_imag) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    for i in 1..=30 {
        let s = 0.01 * i as f64;
        let (a, b, c) = (decentred.at(s, 0.0), decentred.at(s, PI), decentred.at(s, FRAC_PI_2));
        phase = phase.max((a.arg() - b.arg()).abs());
        modulus = modulus.max((a.norm() - c.norm()).abs());
        vs_centred = vs_centred.max((a.norm() - centred.at(s, 0.0).norm()).abs());
        centred_imag = centred_imag.max(centred.at(s, 0.3).im.abs());
    }
    assert!(phase > 0.1, "0° vs 180° phase difference {phase}");
    assert!(modulus > 0.01, "0° vs 90° modulus difference {modulus}");
    assert!(vs_centred > 0.01, "decentre ignored? {vs_centred}");
    assert!(centred_imag < 1e-13, "centred spherical must be real: {centred_imag:e}");
}

/// Coma `W131 H ρ³ cos φ` along `x`: a non-zero imaginary part along `x`; along `y` the pupil
/// is symmetric (`W(x, −y) = W(x, y)`), so the OTF is real there.
#[test]
fn coma_gives_an_imaginary_part_along_its_axis_only() {
    let coma = Aberrations { w131_m: 0.5 * LAMBDA, field: 1.0, ..Aberrations::default() };
    let otf = otf_of(96, 0.4, &Aperture::circle(), &coma);
    let along_x = (1..40).map(|i| otf.at(0.01 * i as f64, 0.0).im.abs()).fold(0.0, f64::max);
    let along_y = (1..40).map(|i| otf.at(0.01 * i as f64, FRAC_PI_2).im.abs()).fold(0.0, f64::max);
    assert!(along_x > 0.05, "{along_x}");
    assert!(along_y < 1e-13, "{along_y:e}");
}

/// Noll `Z4 = √3 (2ρ² − 1)` with coefficient `c` is defocus `W020 = 2√3 c` plus piston, and
/// `Z2 = 2ρ cos φ` is a tilt: `|OTF|` unchanged, phase `−8π (c/λ) sx`.
#[test]
fn zernike_defocus_and_tilt_are_the_seidel_terms() {
    let (n, c) = (64, 0.2 * LAMBDA);
    let z4 = otf_of(n, 0.3, &Aperture::circle(), &Aberrations { zernike_noll_m: vec![(4, c)], ..Default::default() });
    let seidel = otf_of(n, 0.3, &Aperture::circle(), &Aberrations::defocus(2.0 * 3f64.sqrt() * c));
    let plain = otf_of(n, 0.3, &Aperture::circle(), &Aberrations::default());
    let z2 = otf_of(n, 0.3, &Aperture::circle(), &Aberrations { zernike_noll_m: vec![(2, c)], ..Default::default() });
    let k = z4.max_lag() as i64;
    let (mut e4, mut e2) = (0.0_f64, 0.0_f64);
    for ky in -k..=k {
        for kx in -k..=k {
            e4 = e4.max((z4.sample(kx, ky) - seidel.sample(kx, ky)).norm());
            let phase = Complex64::from_polar(1.0, -8.0 * PI * (c / LAMBDA) * kx as f64 / n as f64);
            e2 = e2.max((z2.sample(kx, ky) - plain.sample(kx, ky) * phase).norm());
        }
    }
    assert!(e4 < 1e-12 && e2 < 1e-12, "Z4 {e4:e}, Z2 {e2:e}");
}

/// The plan's buffers carry nothing from one evaluation to the next.
#[test]
fn reused_plan_gives_the_fresh_result() {
    let (aperture, aberrations) = coma_like();
    let first = SampledPupil::new(64, &aperture, &aberrations).unwrap();
    let second = SampledPupil::new(64, &Aperture::sector(0.2, 2.5).unwrap(), &defocus(1.5)).unwrap();
    let mut plan = OtfPlan::new(64, 0.25).unwrap();
    let mut reused = Otf::new();
    plan.otf(&first, LAMBDA, &mut reused);
    plan.otf(&second, LAMBDA, &mut reused);
    let mut fresh = Otf::new();
    OtfPlan::new(64, 0.25).unwrap().otf(&second, LAMBDA, &mut fresh);
    assert_eq!(reused, fresh);
    // and a clone (one per thread) computes the same
    let mut cloned = Otf::new();
    plan.clone().otf(&second, LAMBDA, &mut cloned);
    assert_eq!(cloned, fresh);
}

/// Interpolation alone: the exact OTF tabulated on the grid, read between samples.
#[test]
fn interpolation_error_away_from_the_origin_is_fourth_order() {
    let mut errors = Vec::new();
    for n in [64, 128] {
        let otf = Otf::tabulate(n, 0.3, |sx, sy| Complex64::new(defocus_otf(sx.hypot(sy), 1.0), 0.0));
        let mut worst: f64 = 0.0;
        for i in 0..500 {
            let s = 0.05 + 0.25 * (i as f64 + 0.5) / 500.0;
            worst = worst.max((otf.at(s, 0.6).re - defocus_otf(s, 1.0)).abs());
        }
        errors.push(worst);
    }
    assert!(errors[1] < 1e-5, "{errors:?}");
    assert!(errors[1] < errors[0] / 10.0, "not fourth order: {errors:?}");
}

#[test]
fn constructors_reject_unphysical_parameters() {
    assert!(OtfPlan::new(4, 0.2).is_err());
    assert!(OtfPlan::new(64, 0.0).is_err());
    assert!(OtfPlan::new(64, 1.5).is_err());
    assert!(Aperture::annulus(1.0).is_err());
    assert!(Aperture::annulus(-0.1).is_err());
    assert!(Aperture::sector(1.0, 1.0).is_err());
    assert!(Aperture::sector(0.0, 7.0).is_err());
    assert!(Aperture::circle().decentred(f64::NAN, 0.0).is_err());
    let bad_field = Aberrations { field: 1.5, ..Aberrations::default() };
    assert!(SampledPupil::new(32, &Aperture::circle(), &bad_field).is_err());
    let bad_noll = Aberrations { zernike_noll_m: vec![(0, 1e-7)], ..Aberrations::default() };
    assert!(SampledPupil::new(32, &Aperture::circle(), &bad_noll).is_err());
    assert!(SampledPupil::new(32, &Aperture::circle(), &Aberrations::defocus(f64::INFINITY)).is_err());
    assert!(SampledPupil::new(4, &Aperture::circle(), &Aberrations::default()).is_err());
}

#[test]
fn engine_choice_flags_the_exact_case() {
    let exact = SampledPupil::new(16, &Aperture::circle(), &defocus(1.0)).unwrap();
    assert!(exact.is_centred_defocus());
    let (aperture, aberrations) = coma_like();
    assert!(!SampledPupil::new(16, &aperture, &defocus(1.0)).unwrap().is_centred_defocus());
    assert!(!SampledPupil::new(16, &Aperture::circle(), &aberrations).unwrap().is_centred_defocus());
}

/// A lens through a sector on the FFT path, for the memory budget.
#[derive(Debug)]
struct SectorLens(std::sync::Arc<Aperture>);

impl optics::LensModel for SectorLens {
    fn f_number(&self) -> f64 {
        2.5
    }
    fn focal_length(&self) -> f64 {
        3.36e-3
    }
    fn orders(&self, wavelength_m: f64, _: optics::Field) -> Vec<optics::Order> {
        let w020 = (1.0 - wavelength_m / 800e-9) * 3.36e-3 / 50.0;
        let pupil = optics::Pupil::Aperture(self.0.clone());
        vec![optics::Order::new(0.15 * self.0.area_fraction(), pupil, optics::Wavefront::defocus(w020))]
    }
}

/// A scene whose OTF grids would exceed the memory budget stops before allocating them, with the
/// numbers (a 300 nm band at 2048 pupil samples would hold tens of GiB), and the same scene at a
/// coarse sampling is prepared.
#[test]
fn fft_path_refuses_scenes_over_its_memory_budget() {
    let lens = SectorLens(std::sync::Arc::new(Aperture::sector(0.0, 2.0).unwrap()));
    let band = radiometry::Spectrum::Gaussian(radiometry::Gaussian::from_range(800e-9, 300e-9, 1.0).unwrap());
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let settings = |n| optics::Settings { pupil_samples: Some(n), ..optics::Settings::default() };
    let e = optics::Polychromatic::with_settings(&lens, &band, optics::Field::ON_AXIS, nyquist, None, settings(2048))
        .unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, optics::Error::WorkBudget { .. }), "{message}");
    assert!(message.contains("over the 4 GiB budget") && message.contains("2048 pupil samples"), "{message}");
    assert!(
        optics::Polychromatic::with_settings(&lens, &band, optics::Field::ON_AXIS, nyquist, None, settings(32)).is_ok()
    );
}

// ---- A decentred circle with defocus is a centred circle with a shift (`reduce_decentred_circle`)

/// What [`Aperture::as_circle`] sees: one circle, centred or decentred, of any radius; nothing
/// else.
#[test]
fn as_circle_recognizes_exactly_one_circle() {
    assert_eq!(Aperture::circle().as_circle(), Some(([0.0, 0.0], 1.0)));
    assert_eq!(Aperture::circle().decentred(0.1, -0.15).unwrap().as_circle(), Some(([0.1, -0.15], 1.0)));
    // the scene's iris: `disc(0, None).decentred(dx, dy)`
    let iris = Aperture::disc(0.0, None).unwrap().decentred(0.15, 0.0).unwrap();
    assert_eq!(iris.as_circle(), Some(([0.15, 0.0], 1.0)));
    let zone = Aperture::ring(0.0, 0.6, None).unwrap().decentred(0.2, 0.3).unwrap();
    assert_eq!(zone.as_circle(), Some(([0.2, 0.3], 0.6)));
    // a full turn is no sector
    assert_eq!(Aperture::sector(0.3, 0.3 + 2.0 * PI).unwrap().as_circle(), Some(([0.0, 0.0], 1.0)));
    assert_eq!(Aperture::annulus(0.3).unwrap().as_circle(), None);
    assert_eq!(Aperture::sector(0.0, PI).unwrap().as_circle(), None);
    assert_eq!(Aperture::ring(0.2, 0.6, None).unwrap().as_circle(), None);
    assert_eq!(Aperture::mask(|x, y| x * x + y * y <= 1.0).as_circle(), None);
}

/// The reduction's numbers: radius kept, defocus `W020 r²`, shift `2 W020 d/NA`, validated inputs.
#[test]
fn reduced_circle_numbers_and_validation() {
    let reduced = reduce_decentred_circle([0.3, -0.2], 0.5, 2e-6, 0.2).unwrap();
    assert_eq!(reduced.radius, 0.5);
    assert!((reduced.defocus_m - 0.5e-6).abs() < 1e-22);
    // F/2.5: Δ = 4 F# W020 d = 4 · 2.5 · 2 µm · (0.3, −0.2) = (6, −4) µm
    assert!((reduced.image_shift_m[0] - 6e-6).abs() < 1e-18 && (reduced.image_shift_m[1] + 4e-6).abs() < 1e-18);
    for (centre, radius, w020, na) in [
        ([0.0, 0.0], 0.0, 1e-6, 0.2),
        ([0.0, 0.0], 1.1, 1e-6, 0.2),
        ([f64::NAN, 0.0], 1.0, 1e-6, 0.2),
        ([0.0, 0.0], 1.0, f64::INFINITY, 0.2),
        ([0.0, 0.0], 1.0, 1e-6, 0.0),
        ([0.0, 0.0], 1.0, 1e-6, 1.0),
    ] {
        assert!(reduce_decentred_circle(centre, radius, w020, na).is_err(), "{centre:?} {radius} {w020} {na}");
    }
}

/// The FFT grid of a decentred circle of radius `r = ½` with defocus `W020`, sampled with `N`
/// across the full aperture, is **sample for sample** the grid of the reduced description: the
/// centred unit circle sampled with `rN` across it (the same pixels: the frequency axis scales
/// by `1/r`, lag `k` is `s = k/N` there and `s' = k/(rN) = s/r` here) with defocus `W020 r²` and
/// the tilt `2 W020 d·u` as Noll `Z2`, `Z3` (coefficients `W020 r d_x`, `W020 r d_y`). Only the
/// piston differs, which no OTF sees: the two agree to rounding, for both signs of the defocus.
#[test]
fn decentred_circle_grid_is_the_reduced_circle_grid() {
    let (n, r, s_max) = (128, 0.5, 0.2);
    for (w, dx, dy) in [(1.5, 0.3, -0.2), (-0.8, -0.1, 0.25), (2.0, 0.0, 0.0)] {
        let w020 = w * LAMBDA;
        let decentred = Aperture::ring(0.0, r, None).unwrap().decentred(dx, dy).unwrap();
        let grid = otf_of(n, s_max, &decentred, &defocus(w));
        let reduced = reduce_decentred_circle([dx, dy], r, w020, 0.2).unwrap();
        let tilt = Aberrations {
            w020_m: reduced.defocus_m,
            zernike_noll_m: vec![(2, w020 * r * dx), (3, w020 * r * dy)],
            ..Aberrations::default()
        };
        let n_reduced = (r * n as f64) as usize;
        let reduced_grid = otf_of(n_reduced, s_max / r, &Aperture::circle(), &tilt);
        assert_eq!(grid.max_lag(), reduced_grid.max_lag());
        let k = grid.max_lag() as i64;
        let mut worst: f64 = 0.0;
        for ky in -k..=k {
            for kx in -k..=k {
                worst = worst.max((grid.sample(kx, ky) - reduced_grid.sample(kx, ky)).norm());
            }
        }
        assert!(worst < 1e-12, "w = {w}, d = ({dx}, {dy}): {worst:e}");
    }
}

/// The reduced description against the exact 1-D path: the FFT OTF of a decentred circle
/// (radius `r`, centre `d`, defocus `w` waves) equals `defocus_otf(s/r, w r²) exp(−2πi ν·Δ)`,
/// `ν·Δ = 4 w s·d` in the full aperture's normalized frequency, along several azimuths, to the
/// FFT path's pointwise accuracy `0.2/(rN)` (file docs: the pupil has `rN` samples across).
#[test]
fn decentred_circle_is_the_exact_otf_with_the_reduced_shift() {
    let n = 256;
    let s_max = 0.2;
    // F/2.5: any F-number; the phase in normalized frequency does not depend on it
    let na = 0.2;
    let f_number = 0.5 / na;
    for (w, dx, dy, r) in [(0.5, 0.1, 0.0, 1.0), (2.0, 0.15, 0.0, 1.0), (-1.0, 0.1, -0.15, 1.0), (1.0, -0.2, 0.3, 0.7)]
    {
        let aperture = Aperture::ring(0.0, r, None).unwrap().decentred(dx, dy).unwrap();
        let otf = otf_of(n, s_max, &aperture, &defocus(w));
        let (centre, radius) = aperture.as_circle().unwrap();
        let reduced = reduce_decentred_circle(centre, radius, w * LAMBDA, na).unwrap();
        let w_reduced = reduced.defocus_m / LAMBDA;
        let tolerance = slice_tolerance((r * n as f64) as usize);
        let mut worst: f64 = 0.0;
        for azimuth in [0.0, 0.7, FRAC_PI_2, 2.5, 4.0] {
            let (sin, cos) = f64::sin_cos(azimuth);
            for i in 1..=40 {
                let s = s_max * i as f64 / 40.0;
                let nu = s / (LAMBDA * f_number);
                let [ex, ey] = reduced.image_shift_m;
                let phase = Complex64::from_polar(1.0, -2.0 * PI * nu * (ex * cos + ey * sin));
                let exact = defocus_otf(s / radius, w_reduced) * phase;
                worst = worst.max((otf.at(s, azimuth) - exact).norm());
            }
        }
        assert!(worst < tolerance, "w = {w}, d = ({dx}, {dy}), r = {r}: {worst:e} (tolerance {tolerance:e})");
    }
}

/// The sign of the shift, where its direction matters: an image shift `−Δ` given explicitly
/// (the order's `image_shift_m`, whose convention the polychromatic sum applies) cancels the
/// decentred iris' own shift `Δ`, so the OTF is real and equals the centred one; `+Δ` doubles
/// it instead. A two-wavelength sum shows it in the modulus too: the iris' shifts of opposite
/// defocus cancel the given ones only with the right sign.
#[test]
fn the_decentred_shift_has_the_sign_that_cancels_an_opposite_image_shift() {
    let (n, s_max, na) = (256, 0.2, 0.2);
    let f_number = 0.5 / na;
    let iris = Aperture::circle().decentred(0.15, -0.05).unwrap();
    let (centre, radius) = iris.as_circle().unwrap();
    let shift_phase = |shift: [f64; 2], s: f64, azimuth: f64| {
        let nu = s / (LAMBDA * f_number);
        Complex64::from_polar(1.0, -2.0 * PI * nu * (shift[0] * azimuth.cos() + shift[1] * azimuth.sin()))
    };
    let mut grids = Vec::new();
    for w in [1.2, -0.7] {
        let otf = otf_of(n, s_max, &iris, &defocus(w));
        let reduced = reduce_decentred_circle(centre, radius, w * LAMBDA, na).unwrap();
        grids.push((w, otf, reduced.image_shift_m));
    }
    let tolerance = slice_tolerance(n);
    let (mut cancelled, mut wrong_sign, mut sum_right, mut sum_wrong): (f64, f64, f64, f64) = (0.0, 0.0, 0.0, 0.0);
    for azimuth in [0.0, 1.0, 2.0] {
        for i in 1..=20 {
            let s = s_max * i as f64 / 20.0;
            let mut right = Complex64::new(0.0, 0.0);
            let mut wrong = Complex64::new(0.0, 0.0);
            let mut centred = 0.0;
            for (w, otf, shift) in &grids {
                let z = otf.at(s, azimuth);
                let exact = defocus_otf(s, *w);
                // the order's explicit shift −Δ undoes the iris' Δ: real, the centred OTF
                let undone = z * shift_phase([-shift[0], -shift[1]], s, azimuth);
                cancelled = cancelled.max((undone - exact).norm());
                // +Δ on top of the iris' Δ: the phase of a 2Δ shift
                let doubled = z * shift_phase(*shift, s, azimuth);
                wrong_sign = wrong_sign.max((doubled - exact).norm());
                right += undone;
                wrong += doubled;
                centred += exact;
            }
            sum_right = sum_right.max((right.norm() - centred.abs()).abs());
            sum_wrong = sum_wrong.max((wrong.norm() - centred.abs()).abs());
        }
    }
    assert!(cancelled < tolerance, "{cancelled:e}");
    assert!(wrong_sign > 0.2, "{wrong_sign}");
    assert!(sum_right < 2.0 * tolerance, "{sum_right:e}");
    assert!(sum_wrong > 0.1, "{sum_wrong}");
}

/// A chromatic lens (`f(λ) = f0 λ0/λ`, paper lens F/2.5) through a decentred iris: on the FFT
/// path, or as its reduction on the exact path (F-number `F#/r`, defocus `W020 r²` and the
/// image shift `Δ(λ)` per wavelength). Their polychromatic mean MTFs agree to the FFT path's
/// error at `N = 256` (BENCHMARKS.md: 5.4e-5 relative for the 10 % iris; measured here 4.9e-5
/// to 7.6e-5, the smaller iris having `0.8 N` samples across).
#[derive(Debug)]
struct IrisLens {
    reduced: bool,
    iris: std::sync::Arc<Aperture>,
}

impl IrisLens {
    const F_NUMBER: f64 = 2.5;
    const F0: f64 = 3.36e-3;
    const LAMBDA0: f64 = 800e-9;

    fn w020(lambda: f64) -> f64 {
        (1.0 - lambda / Self::LAMBDA0) * Self::F0 / (8.0 * Self::F_NUMBER * Self::F_NUMBER)
    }
}

impl optics::LensModel for IrisLens {
    fn f_number(&self) -> f64 {
        let (_, r) = self.iris.as_circle().unwrap();
        if self.reduced { Self::F_NUMBER / r } else { Self::F_NUMBER }
    }
    fn focal_length(&self) -> f64 {
        Self::F0
    }
    fn orders(&self, lambda: f64, _: optics::Field) -> Vec<optics::Order> {
        let w020 = Self::w020(lambda);
        let efficiency = 0.15 * self.iris.area_fraction();
        if self.reduced {
            let (centre, radius) = self.iris.as_circle().unwrap();
            let reduced = reduce_decentred_circle(centre, radius, w020, 0.5 / Self::F_NUMBER).unwrap();
            let [dx, dy] = reduced.image_shift_m;
            let wavefront = optics::Wavefront::defocus(reduced.defocus_m).shifted(dx, dy);
            vec![optics::Order::new(efficiency, optics::Pupil::Full, wavefront)]
        } else {
            let pupil = optics::Pupil::Aperture(self.iris.clone());
            vec![optics::Order::new(efficiency, pupil, optics::Wavefront::defocus(w020))]
        }
    }
}

#[test]
fn decentred_iris_lens_matches_its_reduction_on_the_exact_path() {
    let band = radiometry::Spectrum::Gaussian(radiometry::Gaussian::from_range(800e-9, 50e-9, 1.0).unwrap());
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let settings = optics::Settings { pupil_samples: Some(256), exact_irises: false, ..optics::Settings::default() };
    for iris in [
        Aperture::circle().decentred(0.15, 0.0).unwrap(),
        Aperture::ring(0.0, 0.8, None).unwrap().decentred(0.05, 0.1).unwrap(),
    ] {
        let iris = std::sync::Arc::new(iris);
        let mean = |reduced: bool, azimuth: f64| {
            let lens = IrisLens { reduced, iris: iris.clone() };
            let poly =
                optics::Polychromatic::with_settings(&lens, &band, optics::Field::ON_AXIS, nyquist, None, settings)
                    .unwrap();
            assert_eq!(matches!(poly.engine(), optics::Engine::Fft { .. }), !reduced);
            poly.mean_mtf_along(azimuth).0
        };
        for azimuth in [0.0, FRAC_PI_2] {
            let (fft, exact) = (mean(false, azimuth), mean(true, azimuth));
            assert!(((fft - exact) / exact).abs() < 1.5e-4, "{iris:?} at {azimuth}: {fft} vs {exact}");
        }
    }
}

// ---- Choosing the pupil sampling from the tolerance (`pupil_samples_for`)

/// The plan: at least 128 samples, even, more for a tighter tolerance, the largest `N` of its
/// padded length; the paper scene at 1e-4 starts at `(64, 128)`.
#[test]
fn sampling_plan_follows_the_tolerance() {
    let s_max = 0.22;
    let mut last = 0;
    for tolerance in [1e-2, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5] {
        let plan = pupil_samples_for(tolerance, s_max, 40).unwrap();
        assert!(plan.samples >= optics::fft::MIN_CHOSEN_SAMPLES && plan.samples.is_multiple_of(2), "{plan:?}");
        assert!(plan.samples >= last, "{tolerance}: {plan:?}");
        // the extrapolated error's model with its safety factor meets the tolerance at the start
        let (c, q) = optics::fft::EXTRAPOLATED_MODEL;
        assert!(optics::fft::SAFETY * c * (plan.samples as f64).powf(-q) <= tolerance, "{plan:?}");
        assert_eq!(optics::fft::reachable(plan.samples), optics::fft::SAFETY * c * (plan.samples as f64).powf(-q));
        // one more pair of samples would need a longer FFT
        let k = |n: usize| (s_max * n as f64).ceil() as usize + 2;
        let m = |n: usize| optics::fft::fast_fft_len(n + k(n));
        assert_eq!(m(plan.samples), OtfPlan::new(plan.samples, s_max).unwrap().padded_len());
        assert!(m(plan.samples + 2) > m(plan.samples), "{plan:?}");
        last = plan.samples;
    }
    let plan = pupil_samples_for(1e-4, s_max, 40).unwrap();
    assert_eq!((plan.coarse(), plan.samples, plan.limit), (64, 128, 2048));
    let refined = plan.refine(2e-4).unwrap();
    assert_eq!((refined.coarse(), refined.samples), (128, 256));
    for (tolerance, s_max, grids) in [(0.0, 0.2, 1), (1.0, 0.2, 1), (1e-4, 0.0, 1), (1e-4, 1.5, 1), (1e-4, 0.2, 0)] {
        assert!(
            matches!(pupil_samples_for(tolerance, s_max, grids), Err(optics::Error::InvalidParameter { .. })),
            "{tolerance} {s_max} {grids}"
        );
    }
}

/// Beyond reach: a tolerance the 2048-sample cap cannot meet, a memory budget that caps `N`
/// lower for many grids, and a refinement past the limit all stop with the numbers: the
/// tolerance asked, the `N` needed, the limit and the error reachable there.
#[test]
fn sampling_beyond_reach_is_refused_with_the_numbers() {
    let e = pupil_samples_for(1e-7, 0.22, 40).unwrap_err();
    let optics::Error::PupilSampling { tolerance, needed, limit, reachable } = e.clone() else { panic!("{e}") };
    assert_eq!((tolerance, limit), (1e-7, 2048));
    assert!(needed > 10_000 && reachable > 1e-7 && reachable < 1e-5, "{e}");
    let message = e.to_string();
    assert!(message.contains("1e-7") && message.contains(&needed.to_string()) && message.contains("2048"), "{message}");
    // 20 000 grids (a 300 nm band with several orders) of up to 4 GiB: N is capped far lower
    let plan = pupil_samples_for(1e-3, 0.22, 20_000).unwrap();
    assert!(plan.limit < 400 && plan.limit >= plan.samples, "{plan:?}");
    let side = 2 * ((0.22 * plan.limit as f64).ceil() as usize + 2) + 1;
    assert!(20_000.0 * (side * side * 16) as f64 <= optics::FFT_MEMORY_BUDGET);
    assert!(matches!(pupil_samples_for(1e-5, 0.22, 20_000), Err(optics::Error::PupilSampling { .. })));
    // a refinement past the limit
    let e = plan.refine(1e-2).unwrap_err();
    assert!(e.to_string().contains(&format!("N = {}", plan.limit)), "{e}");
}

/// The plan end to end on the paper lens through the iris decentred by 10 %: the mean MTF at
/// `N/2` and `N`, extrapolated, is within the tolerance of the exact value (the iris' reduction
/// on the exact path), and the estimate is no smaller than the true error of `M_N` by more than
/// the study's margin.
#[test]
fn richardson_plan_meets_the_tolerance_on_the_decentred_iris() {
    let band = radiometry::Spectrum::Gaussian(radiometry::Gaussian::from_range(800e-9, 50e-9, 1.0).unwrap());
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let iris = std::sync::Arc::new(Aperture::circle().decentred(0.1, 0.0).unwrap());
    let mean = |reduced: bool, n: Option<usize>| {
        let lens = IrisLens { reduced, iris: iris.clone() };
        let settings =
            optics::Settings { pupil_samples: n, tolerance: 1e-8, exact_irises: false, ..optics::Settings::default() };
        let poly = optics::Polychromatic::with_settings(&lens, &band, optics::Field::ON_AXIS, nyquist, None, settings)
            .unwrap();
        poly.mean_mtf_along(0.0).0
    };
    let exact = mean(true, None);
    let tolerance = 2e-4;
    // s_max at the longest wavelength the spectral rule keeps (λ0 + 7σ)
    let s_max = nyquist * (800e-9 + 7.0 * 50e-9 / 8f64.sqrt()) * IrisLens::F_NUMBER;
    let plan = pupil_samples_for(tolerance, s_max, 192).unwrap();
    let (coarse, fine) = (mean(false, Some(plan.coarse())), mean(false, Some(plan.samples)));
    let estimate = plan.extrapolate(coarse, fine);
    assert!(estimate.converged, "{plan:?}: {estimate:?}");
    let error_fine = ((fine - exact) / exact).abs();
    let error_value = ((estimate.value - exact) / exact).abs();
    assert!(error_value <= tolerance && error_value < 0.2 * error_fine, "{error_value:e} vs {error_fine:e}");
    // the correction estimates the error of M_N; the error, scaled by the two models,
    // estimates the extrapolated value's to within the models' safety factor, and the model
    // with it bounds that error at N
    assert!(estimate.correction > 0.8 * error_fine, "{estimate:?} vs {error_fine:e}");
    assert!(optics::fft::SAFETY * estimate.error >= error_value, "{estimate:?} vs {error_value:e}");
    assert!(optics::fft::reachable(plan.samples) >= error_value, "{plan:?}: {error_value:e}");
    let gain = optics::fft::extrapolation_gain(plan.samples);
    assert!((estimate.error - estimate.correction * gain).abs() <= 1e-15 * estimate.error, "{estimate:?}");
}

/// On the FFT path the spectral nodes (one grid each) follow the FFT tolerance, not a tighter
/// overall one: the decentred iris with the overall tolerance at 1e-9 takes fewer nodes when the
/// FFT path is asked for 1e-3 than for 1e-6, and the two means, on the same 64-sample grids,
/// agree within the looser tolerance's spectral share.
#[test]
fn fft_path_spectral_nodes_follow_its_tolerance() {
    let band = radiometry::Spectrum::Gaussian(radiometry::Gaussian::from_range(800e-9, 100e-9, 1.0).unwrap());
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let lens = IrisLens { reduced: false, iris: std::sync::Arc::new(Aperture::circle().decentred(0.1, 0.0).unwrap()) };
    let run = |fft_tolerance: f64| {
        let settings = optics::Settings {
            pupil_samples: Some(64),
            tolerance: 1e-9,
            fft_tolerance: Some(fft_tolerance),
            exact_irises: false,
            ..optics::Settings::default()
        };
        optics::Polychromatic::with_settings(&lens, &band, optics::Field::ON_AXIS, nyquist, None, settings)
            .unwrap()
            .mean_mtf_along(0.0)
    };
    let ((loose, loose_work), (tight, tight_work)) = (run(1e-3), run(1e-6));
    assert!(loose_work.spectral_interpolated && tight_work.spectral_interpolated, "{loose_work:?}");
    assert!(loose_work.spectral_nodes < tight_work.spectral_nodes, "{loose_work:?} vs {tight_work:?}");
    assert!(((loose - tight) / tight).abs() <= 1e-3, "{loose} vs {tight}");
}
