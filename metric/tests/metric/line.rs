//! Line spectra (`radiometry::Line`, engine `monochromatic`): one wavelength for the optics, the
//! photons of the band's equivalent width for the radiometry.
//!
//! - the mean MTF equals the mean of `|defocus_otf|` at that wavelength, computed directly here
//!   (zeros located by bisection, Gauss–Legendre between them);
//! - a Gaussian band converges to it as its range shrinks, the error falling as range²;
//! - photoelectrons, glare and the Fraunhofer check (a fraction of 0 or 1) by hand;
//! - the FFT path and lateral colour at one wavelength.

use std::f64::consts::PI;

use optics::Field;
use std::sync::Arc;

use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, Evaluation, Options, Scene, evaluate};
use optics::{defocus_otf, quad};
use proptest::prelude::*;
use radiometry::constants::{PLANCK, SPEED_OF_LIGHT};
use radiometry::{Gaussian, Line, Spectrum};

const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;
const RADIANCE: f64 = 0.025e9;
const QE: f64 = 0.2;
const TAU1: f64 = 0.15;
const EXPOSURE: f64 = 1.23e-3;

fn lens(f_number: f64) -> ChromaticMetalens {
    ChromaticMetalens::new(f_number, F0, LAMBDA0, Curve::Constant(TAU1), Curve::Constant(0.55)).unwrap()
}

/// A flat source behind `filter`, seen through `lens` by a camera with `pixel_m` pixels.
fn scene_with(lens: ChromaticMetalens, filter: Spectrum, pixel_m: f64, tolerance: f64) -> Scene {
    let radiance = Spectrum::product(vec![Spectrum::Constant(RADIANCE), filter]);
    let camera = Camera::new(pixel_m, Spectrum::Constant(QE), false).unwrap();
    let options = Options { tolerance, ..Options::default() };
    Scene::new(Arc::new(lens), radiance, camera, EXPOSURE, options).unwrap()
}

fn line(centre: f64, width: f64, peak: f64) -> Spectrum {
    Spectrum::Line(Line::new(centre, width, peak).unwrap())
}

/// Mean over [0, ν_N] of |OTF(ν λ F#, W020(λ)/λ)| for the chromatic lens at one wavelength,
/// written from docs/physics.md ("Exact defocused OTF"), with `defocus_otf` only: zeros bracketed on a 4000-point grid and
/// bisected to rounding, 8 Gauss–Legendre panels between consecutive zeros; a piece that ends at
/// the cutoff is integrated in u with ν = ν_c − (ν_c − a) u², which smooths the (1 − s)^{3/2} edge.
fn direct_mean(f_number: f64, lambda: f64, pixel_m: f64) -> f64 {
    let nyquist = 0.5 / pixel_m;
    let cutoff = 1.0 / (lambda * f_number);
    let top = nyquist.min(cutoff);
    // w = (1 − λ/λ0) f0/(8 F#² λ) (docs/physics.md, "Sign of the wavefront")
    let w = (1.0 - lambda / LAMBDA0) * F0 / (8.0 * f_number * f_number) / lambda;
    let otf = |nu: f64| defocus_otf(nu * lambda * f_number, w);
    let mut cuts = vec![0.0];
    let n = 4000;
    let grid = |i: usize| top * i as f64 / n as f64;
    for i in 0..n {
        let (mut a, mut b) = (grid(i), grid(i + 1));
        if otf(a) * otf(b) < 0.0 {
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if otf(a) * otf(m) <= 0.0 { b = m } else { a = m }
            }
            cuts.push(0.5 * (a + b));
        }
    }
    cuts.push(top);
    let mut total = 0.0;
    for pair in cuts.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        total += if b == cutoff {
            quad::composite(0.0, 1.0, 8, |u| otf(b - (b - a) * u * u).abs() * 2.0 * (b - a) * u)
        } else {
            quad::composite(a, b, 8, |nu| otf(nu).abs())
        };
    }
    total / nyquist
}

#[test]
fn line_equals_the_monochromatic_mean_mtf() {
    // (F#, λ, pixel): in focus, defocused by 4.9 waves (zeros below Nyquist), fast, and F/5 on
    // 2 µm pixels with the cutoff (244 cycles/mm) below Nyquist (250 cycles/mm)
    for (f_number, lambda, pixel) in
        [(2.5, 800e-9, 5.2e-6), (2.5, 850e-9, 5.2e-6), (1.4, 780e-9, 3e-6), (5.0, 820e-9, 2e-6), (2.5, 700e-9, 10e-6)]
    {
        let r = evaluate(&scene_with(lens(f_number), line(lambda, 10e-9, 1.0), pixel, 1e-13)).unwrap();
        let direct = direct_mean(f_number, lambda, pixel);
        let err = (r.mean_mtf - direct).abs();
        eprintln!(
            "F/{f_number} {:.0} nm {:.1} µm: mean MTF {:.15} direct {direct:.15} ({err:.1e}), {} sign changes",
            lambda * 1e9,
            pixel * 1e6,
            r.mean_mtf,
            r.numerics.sign_changes
        );
        assert!(err < 1e-12, "F/{f_number} {lambda} m: {} vs {direct} ({err:e})", r.mean_mtf);
        assert_eq!(r.numerics.engine, "monochromatic (line spectrum): exact-1d");
        assert_eq!((r.numerics.spectral_nodes, r.numerics.spectral_panels), (1, 0));
    }
}

/// `|mean MTF(Gaussian of range r) − mean MTF(line)|` for the paper lens at `centre`.
fn gaussian_error(f_number: f64, centre: f64, range: f64, mono: f64) -> f64 {
    let g = Spectrum::Gaussian(Gaussian::from_range(centre, range, 1.0).unwrap());
    let r = evaluate(&scene_with(lens(f_number), g, 5.2e-6, 1e-12)).unwrap();
    (r.mean_mtf - mono).abs()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, rng_seed: proptest::test_runner::RngSeed::Fixed(0x11e), failure_persistence: None, ..ProptestConfig::default() })]

    /// Polychromatic → monochromatic as the range → 0: the Gaussian's mean MTF tends to the
    /// line's, and (the spectrum being symmetric) the error is second order: halving the range
    /// quarters it.
    #[test]
    fn narrow_gaussians_converge_to_the_line_as_range_squared(
        f_number in 1.4f64..5.0,
        centre_nm in 760.0f64..860.0,
    ) {
        let centre = centre_nm * 1e-9;
        let mono = evaluate(&scene_with(lens(f_number), line(centre, 1e-9, 1.0), 5.2e-6, 1e-12)).unwrap().mean_mtf;
        let errors: Vec<f64> = [0.4e-9, 0.2e-9, 0.1e-9].iter().map(|&r| gaussian_error(f_number, centre, r, mono)).collect();
        eprintln!("F/{f_number:.2} {centre_nm:.1} nm: errors {errors:?}, ratios {:.3} {:.3}", errors[0] / errors[1], errors[1] / errors[2]);
        for pair in errors.windows(2) {
            let ratio = pair[0] / pair[1];
            prop_assert!((3.8..4.2).contains(&ratio), "error ratio {ratio} for half the range: {errors:?}");
        }
        prop_assert!(errors[2] < 1e-3, "{errors:?}");
    }
}

/// Paper SI eq. S7–S8 for one wavelength: `N = A t π NA² /(h c) · L · peak · width · η · τ1 · λ`,
/// the photons of a band of the line's equivalent width; SNR0 = √N (S9).
#[test]
fn photoelectrons_of_a_line_by_hand() {
    let (centre, width, peak, pixel) = (850e-9, 10e-9, 0.7, 5.2e-6);
    let r = evaluate(&scene_with(lens(2.5), line(centre, width, peak), pixel, 1e-6)).unwrap();
    let na: f64 = 0.2;
    let by_hand = pixel * pixel * EXPOSURE * PI * na * na / (PLANCK * SPEED_OF_LIGHT)
        * RADIANCE
        * peak
        * width
        * QE
        * TAU1
        * centre;
    assert!((r.photoelectrons - by_hand).abs() < 1e-12 * by_hand, "{} vs {by_hand}", r.photoelectrons);
    assert!((r.snr0 - by_hand.sqrt()).abs() < 1e-12 * r.snr0);
    // N ∝ width: twice the width, twice the photons, same MTF
    let wide = evaluate(&scene_with(lens(2.5), line(centre, 2.0 * width, peak), pixel, 1e-6)).unwrap();
    assert!((wide.photoelectrons / r.photoelectrons - 2.0).abs() < 1e-12);
    assert_eq!(wide.mean_mtf, r.mean_mtf);
    // glare of the paper lens (eq. S12–S13), transmitted light τ1 → T
    assert!((r.glare.m0 - TAU1 / 0.55).abs() < 1e-12, "{:?}", r.glare);
    assert!((r.transmitted_photoelectrons / r.photoelectrons - 0.55 / TAU1).abs() < 1e-12);
}

/// Eq. S15 at one wavelength: the whole signal is beyond the 0.25 mm limit or none of it, as the
/// line sits outside or inside λ0 ± 297.619 nm.
#[test]
fn fraunhofer_fraction_of_a_line_is_zero_or_one() {
    let at = |centre: f64| -> Evaluation {
        evaluate(&scene_with(lens(2.5), line(centre, 10e-9, 1.0), 10e-6, 1e-6)).unwrap()
    };
    for centre in [800e-9, 1090e-9, 510e-9] {
        let r = at(centre);
        assert_eq!(r.fraunhofer.fraction_outside, 0.0, "{centre}");
        assert!(r.fraunhofer.valid && r.warnings.is_empty(), "{centre}: {:?}", r.warnings);
    }
    for centre in [1100e-9, 500e-9] {
        let r = at(centre);
        assert_eq!(r.fraunhofer.fraction_outside, 1.0, "{centre}");
        assert!(!r.fraunhofer.valid && r.warnings.iter().any(|w| w.contains("Fraunhofer")), "{centre}");
    }
}

/// At one wavelength lateral colour is a pure phase, `|e^{iφ} OTF| = |OTF|`: off axis the tangential
/// and sagittal means equal the on-axis one. The FFT of the sampled pupil (the full circle
/// given as an aperture) agrees with the exact 1-D OTF to its sampling error (fft module table:
/// ~5e-5 at 256 samples).
#[test]
fn line_off_axis_and_on_the_fft_path() {
    let on_axis = evaluate(&scene_with(lens(2.5), line(850e-9, 10e-9, 1.0), 5.2e-6, 1e-10)).unwrap();
    let off = scene_with(lens(2.5), line(850e-9, 10e-9, 1.0), 5.2e-6, 1e-10)
        .at_field(Field::new(8f64.to_radians(), 0.0))
        .unwrap();
    let off = evaluate(&off).unwrap();
    assert_eq!(off.numerics.engine, "monochromatic (line spectrum): exact-1d, complex sum with lateral colour");
    for m in [off.mean_mtf_tangential, off.mean_mtf_sagittal] {
        assert!((m - on_axis.mean_mtf).abs() < 1e-9, "{m} vs {}", on_axis.mean_mtf);
    }
    // (the full circle as a sector of the full turn: a circle would be reduced to the exact path)
    let circle = lens(2.5).with_aperture(optics::fft::Aperture::mask(|x, y| x * x + y * y <= 1.0));
    let fft = evaluate(&scene_with(circle, line(850e-9, 10e-9, 1.0), 5.2e-6, 1e-6)).unwrap();
    assert!(
        fft.numerics.engine.starts_with("monochromatic (line spectrum): fft: 256 pupil samples"),
        "{}",
        fft.numerics.engine
    );
    assert_eq!(fft.numerics.spectral_nodes, 1);
    let err = (fft.mean_mtf - on_axis.mean_mtf).abs();
    eprintln!("FFT line {} vs exact {} ({err:.1e})", fft.mean_mtf, on_axis.mean_mtf);
    assert!(err < 1e-4, "{} vs {} ({err:e})", fft.mean_mtf, on_axis.mean_mtf);
    // (the mask's area is its sampled estimate, not π exactly: the photon count follows it)
    let photons = (fft.photoelectrons - on_axis.photoelectrons).abs() / on_axis.photoelectrons;
    assert!(photons < 1e-3, "{} vs {}", fft.photoelectrons, on_axis.photoelectrons);
}
