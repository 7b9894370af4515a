// Property tests of [`metric::evaluate`] on physical ranges, with fixed seeds:
//
// - bounds: every output finite, `0 ≤ mean MTF ≤ 1`, `ASNR = SNR0 × mean MTF ≤ SNR0`,
//   `SNR0 = √N` for a shot-noise-limited camera, for Gaussian, top-hat and blackbody light;
// - `SNR0 ∝ √(exposure)` (shot noise), with the MTF untouched;
// - invariance under a change of units: radiance × k with exposure / k changes nothing; every
//   length × k (wavelengths, focal length, pixel, blur threshold) keeps the MTF and multiplies
//   N by k⁴; the same spectrum as a Gaussian and as a dense table, a top-hat and its table;
// - a vanishing spectral range gives the monochromatic mean MTF.
//
// Case counts keep the whole file to a few seconds in the dev profile.

use std::sync::Arc;

use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, Evaluation, Options, Scene, evaluate};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use radiometry::{Blackbody, Gaussian, Sampled, Spectrum, TopHat};

/// The paper's lens and camera (docs/physics.md, "The metric").
const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;
const RADIANCE: f64 = 0.025e9;
const QE: f64 = 0.2;
const EXPOSURE: f64 = 1.23e-3;

fn config(cases: u32, seed: u64) -> ProptestConfig {
    ProptestConfig { cases, rng_seed: RngSeed::Fixed(seed), failure_persistence: None, ..ProptestConfig::default() }
}

/// `10^x`: log-uniform ranges for quantities spanning decades.
fn exp10(x: f64) -> f64 {
    10f64.powf(x)
}

fn lens(f_number: f64) -> ChromaticMetalens {
    ChromaticMetalens::new(f_number, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap()
}

/// A flat source of `RADIANCE` W/(m² sr m) behind `filter`.
fn behind(filter: Spectrum) -> Spectrum {
    Spectrum::product(vec![Spectrum::Constant(RADIANCE), filter])
}

fn gaussian(centre_m: f64, range_m: f64) -> Spectrum {
    Spectrum::Gaussian(Gaussian::from_range(centre_m, range_m, 1.0).unwrap())
}

fn scene(lens: ChromaticMetalens, radiance: Spectrum, pixel_m: f64, pixel_mtf: bool, exposure_s: f64) -> Scene {
    let camera = Camera::new(pixel_m, Spectrum::Constant(QE), pixel_mtf).unwrap();
    Scene::new(Arc::new(lens), radiance, camera, exposure_s, Options::default()).unwrap()
}

/// `|a/b − 1|`.
fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// The bounds every evaluation must satisfy.
fn check_bounds(e: &Evaluation) -> Result<(), TestCaseError> {
    for (name, v) in [
        ("asnr", e.asnr),
        ("mean_mtf", e.mean_mtf),
        ("snr0", e.snr0),
        ("photoelectrons", e.photoelectrons),
        ("mtf_integral", e.mtf_integral_cyc_per_mm),
    ] {
        prop_assert!(v.is_finite() && v >= 0.0, "{name} = {v}");
    }
    prop_assert!(e.mean_mtf <= 1.0 + 1e-12, "mean MTF {}", e.mean_mtf);
    prop_assert!(e.asnr <= e.snr0 * (1.0 + 1e-12), "ASNR {} > SNR0 {}", e.asnr, e.snr0);
    prop_assert!((e.asnr - e.snr0 * e.mean_mtf).abs() <= 1e-12 * e.snr0, "{} vs {}", e.asnr, e.snr0 * e.mean_mtf);
    // shot-noise-limited camera: SNR0 = √N (paper SI eq. S9)
    prop_assert!(rel(e.snr0, e.photoelectrons.sqrt()) < 1e-12, "{} vs √{}", e.snr0, e.photoelectrons);
    Ok(())
}

proptest! {
    #![proptest_config(config(12, 0x5eed_1001))]

    /// Bounds over F/1.4–F/10, three kinds of light (Gaussian 1–100 nm, a top-hat band, a
    /// 1000–6000 K blackbody behind the top-hat), pixels 1–20 µm, pixel MTF on and off.
    #[test]
    fn outputs_are_finite_and_bounded(
        log_f in 0.15f64..1.0,
        kind in 0usize..3,
        log_range_nm in 0.0f64..2.0,
        centre_nm in 650.0f64..950.0,
        temperature in 1000.0f64..6000.0,
        pixel_um in 1.0f64..20.0,
        pixel_mtf in any::<bool>(),
    ) {
        let (centre, range) = (centre_nm * 1e-9, exp10(log_range_nm) * 1e-9);
        let band = Spectrum::TopHat(TopHat::new(centre - 0.5 * range, centre + 0.5 * range, 1.0).unwrap());
        let radiance = match kind {
            0 => behind(gaussian(centre, range)),
            1 => behind(band),
            _ => Spectrum::product(vec![Spectrum::blackbody(Blackbody::new(temperature).unwrap(), 1.0).unwrap(), band]),
        };
        let e = evaluate(&scene(lens(exp10(log_f)), radiance, pixel_um * 1e-6, pixel_mtf, EXPOSURE)).unwrap();
        check_bounds(&e)?;
        prop_assert!(e.photoelectrons > 0.0 && e.mean_mtf > 0.0);
    }

    /// Shot noise: N ∝ t, so SNR0 and the ASNR go as √t; the MTF does not move.
    #[test]
    fn snr_scales_as_the_square_root_of_exposure(
        log_f in 0.3f64..0.9,
        log_range_nm in 0.0f64..1.8,
        pixel_um in 2.0f64..10.0,
        log_t in -4.0f64..-1.0,
        log_k in -3.0f64..3.0,
    ) {
        let (t, k) = (exp10(log_t), exp10(log_k));
        let radiance = behind(gaussian(LAMBDA0, exp10(log_range_nm) * 1e-9));
        let a = evaluate(&scene(lens(exp10(log_f)), radiance.clone(), pixel_um * 1e-6, false, t)).unwrap();
        let b = evaluate(&scene(lens(exp10(log_f)), radiance, pixel_um * 1e-6, false, k * t)).unwrap();
        check_bounds(&a)?;
        check_bounds(&b)?;
        prop_assert!(rel(b.photoelectrons / a.photoelectrons, k) < 1e-12);
        prop_assert!(rel(b.snr0 / a.snr0, k.sqrt()) < 1e-12, "{} vs √{k}", b.snr0 / a.snr0);
        prop_assert!(rel(b.asnr / a.asnr, k.sqrt()) < 1e-12);
        prop_assert_eq!(b.mean_mtf, a.mean_mtf);
    }

    /// Units of the light: radiance × k with the exposure / k is the same number of photons.
    #[test]
    fn radiance_times_k_over_exposure_times_k_changes_nothing(
        log_f in 0.3f64..0.9,
        log_range_nm in 0.0f64..1.8,
        log_k in -3.0f64..3.0,
    ) {
        let k = exp10(log_k);
        let filter = gaussian(LAMBDA0, exp10(log_range_nm) * 1e-9);
        let a = evaluate(&scene(lens(exp10(log_f)), behind(filter.clone()), 5.2e-6, false, EXPOSURE)).unwrap();
        let scaled = Spectrum::product(vec![Spectrum::Constant(k * RADIANCE), filter]);
        let b = evaluate(&scene(lens(exp10(log_f)), scaled, 5.2e-6, false, EXPOSURE / k)).unwrap();
        prop_assert!(rel(b.photoelectrons, a.photoelectrons) < 1e-12);
        prop_assert!(rel(b.snr0, a.snr0) < 1e-12);
        prop_assert!((b.mean_mtf - a.mean_mtf).abs() < 1e-9, "{} vs {}", b.mean_mtf, a.mean_mtf);
        prop_assert!(rel(b.asnr, a.asnr) < 1e-9);
    }

    /// Units of length: every length × k (centre and range of the band, λ0, f0, pixel, blur
    /// threshold) leaves the waves of defocus and the normalized frequencies, so the MTF and
    /// the Fraunhofer verdict; N = A t ∫ L λ … dλ goes as k² · k².
    #[test]
    fn scaling_every_length_keeps_the_mtf(
        log_f in 0.3f64..0.9,
        log_range_nm in 0.0f64..1.8,
        centre_nm in 700.0f64..900.0,
        pixel_um in 2.0f64..10.0,
        k in 0.5f64..2.0,
    ) {
        let f_number = exp10(log_f);
        let at = |k: f64| {
            let lens = ChromaticMetalens::new(f_number, k * F0, k * LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55))
                .unwrap();
            let radiance = behind(gaussian(k * centre_nm * 1e-9, k * exp10(log_range_nm) * 1e-9));
            let camera = Camera::new(k * pixel_um * 1e-6, Spectrum::Constant(QE), true).unwrap();
            let options = Options { fraunhofer_threshold: k * 0.25e-3, ..Options::default() };
            evaluate(&Scene::new(Arc::new(lens), radiance, camera, EXPOSURE, options).unwrap()).unwrap()
        };
        let (a, b) = (at(1.0), at(k));
        prop_assert!((b.mean_mtf - a.mean_mtf).abs() < 1e-9, "{} vs {}", b.mean_mtf, a.mean_mtf);
        prop_assert!(rel(b.photoelectrons / a.photoelectrons, k.powi(4)) < 1e-10);
        prop_assert!(rel(b.nyquist_cyc_per_mm * k, a.nyquist_cyc_per_mm) < 1e-12);
        prop_assert_eq!(b.fraunhofer.valid, a.fraunhofer.valid);
        prop_assert!((b.fraunhofer.fraction_outside - a.fraunhofer.fraction_outside).abs() < 1e-9);
    }
}

/// The Gaussian `G` of `centre`, `range` as a table: samples every σ/`per_sigma` over ±7σ.
fn tabulated_gaussian(centre: f64, range: f64, per_sigma: usize) -> Spectrum {
    let g = Gaussian::from_range(centre, range, 1.0).unwrap();
    let n = 14 * per_sigma;
    let h = g.sigma() / per_sigma as f64;
    let wavelengths: Vec<f64> = (0..=n).map(|i| centre - 7.0 * g.sigma() + h * i as f64).collect();
    let values = wavelengths.iter().map(|&l| g.value(l)).collect();
    Spectrum::Sampled(Sampled::new(wavelengths, values).unwrap())
}

proptest! {
    #![proptest_config(config(6, 0x5eed_1002))]

    /// The same physical spectrum written two ways: a Gaussian filter and its tables (σ/8 and
    /// σ/16 sampling over ±7σ: the piecewise-linear integral is the trapezoid rule, which is
    /// spectrally accurate for a Gaussian; the MTF sees the O(h²) interpolation error), and a
    /// top-hat and the table of the same band with 1e-8 nm edges.
    #[test]
    fn a_spectrum_as_a_formula_or_a_table_gives_the_same_result(
        log_f in 0.3f64..0.8,
        log_range_nm in 0.5f64..1.8,
        centre_nm in 760.0f64..840.0,
    ) {
        let (centre, range) = (centre_nm * 1e-9, exp10(log_range_nm) * 1e-9);
        let evaluate_with = |filter: Spectrum| {
            evaluate(&scene(lens(exp10(log_f)), behind(filter), 5.2e-6, false, EXPOSURE)).unwrap()
        };
        let formula = evaluate_with(gaussian(centre, range));
        let coarse = evaluate_with(tabulated_gaussian(centre, range, 8));
        let fine = evaluate_with(tabulated_gaussian(centre, range, 16));
        for table in [&coarse, &fine] {
            prop_assert!(rel(table.photoelectrons, formula.photoelectrons) < 1e-10, "{} vs {}", table.photoelectrons, formula.photoelectrons);
        }
        // the interpolation error is O(h²): small, and halving h divides it by 4 (measured
        // 3.996–4.000 on this grid)
        let (e8, e16) = ((coarse.mean_mtf - formula.mean_mtf).abs(), (fine.mean_mtf - formula.mean_mtf).abs());
        prop_assert!(e8 < 5e-4, "table error {e8:e} at σ/8");
        prop_assert!(e8 < 1e-9 || (e8 / e16 - 4.0).abs() < 0.2, "table errors {e8:e} (σ/8), {e16:e} (σ/16)");

        let (lo, hi, eps) = (centre - 0.5 * range, centre + 0.5 * range, 1e-17);
        let band = evaluate_with(Spectrum::TopHat(TopHat::new(lo, hi, 1.0).unwrap()));
        let edges = Sampled::new(vec![lo - eps, lo, hi, hi + eps], vec![0.0, 1.0, 1.0, 0.0]).unwrap();
        let band_table = evaluate_with(Spectrum::Sampled(edges));
        prop_assert!(rel(band_table.photoelectrons, band.photoelectrons) < 1e-8, "{} vs {}", band_table.photoelectrons, band.photoelectrons);
        prop_assert!((band_table.mean_mtf - band.mean_mtf).abs() < 1e-7, "{} vs {}", band_table.mean_mtf, band.mean_mtf);
    }

    /// A vanishing spectral range gives the monochromatic mean MTF at the centre wavelength:
    /// `(1/s_N) ∫_0^{s_N} |OTF(s, w)| ds`, `s_N = ν_N λ F#`, `w = W020(λ)/λ`.
    #[test]
    fn narrow_band_mean_mtf_is_the_monochromatic_mean(
        log_f in 0.15f64..1.0,
        centre_nm in 700.0f64..900.0,
        pixel_um in 1.0f64..10.0,
    ) {
        let (f_number, centre, pixel) = (exp10(log_f), centre_nm * 1e-9, pixel_um * 1e-6);
        let lens = lens(f_number);
        let w = lens.defocus(centre) / centre;
        let s_nyquist = 0.5 / pixel * centre * f_number;
        let expected = optics::fft::defocus_mean_mtf(w, s_nyquist);
        let e = evaluate(&scene(lens, behind(gaussian(centre, 1e-14)), pixel, false, EXPOSURE)).unwrap();
        prop_assert!((e.mean_mtf - expected).abs() < 1e-7, "{} vs {expected} (w = {w}, s_N = {s_nyquist})", e.mean_mtf);
    }
}
