//! The metric against independent references: the mean MTF against the slow reference of
//! `optics::reference` (printed y-form OTF, adaptive Gauss–Kronrod in every dimension, its own
//! spectral window of ±12σ), the photoelectron count against a hand-worked example.

use std::sync::Arc;

use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, Evaluation, MetricForm, Options, Scene, evaluate};
use optics::reference::{ReferenceScene, mean_mtf};
use proptest::prelude::*;
use radiometry::{Gaussian, Spectrum};

const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;

/// The paper theory scene with the given F-number, Gaussian range, pixel pitch and pixel MTF.
fn scene(f_number: f64, range_m: f64, pixel_m: f64, pixel_mtf: bool, centre_m: f64) -> Scene {
    let lens = ChromaticMetalens::new(f_number, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
    let filter = Gaussian::from_range(centre_m, range_m, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(pixel_m, Spectrum::Constant(0.2), pixel_mtf).unwrap();
    Scene::new(Arc::new(lens), radiance, camera, 1.23e-3, Options::default()).unwrap()
}

/// The reference mean MTF of the same scene: photoelectron density λ·G(λ) (flat source, constant
/// QE and efficiency), integrated over centre ± 12σ.
fn reference(f_number: f64, range_m: f64, pixel_m: f64, pixel_mtf: bool, centre_m: f64) -> f64 {
    let sigma = range_m / (2.0 * 2f64.sqrt());
    let density = move |l: f64| l * (-0.5 * ((l - centre_m) / sigma).powi(2)).exp();
    let scene = ReferenceScene {
        density: &density,
        lambda_min: (centre_m - 12.0 * sigma).max(1e-3 * centre_m),
        lambda_max: centre_m + 12.0 * sigma,
        breakpoints: &[],
        f_number,
        focal_length_m: F0,
        design_wavelength_m: LAMBDA0,
        pixel_pitch_m: pixel_m,
        pixel_mtf,
    };
    mean_mtf(&scene, 1e-10)
}

fn check(f_number: f64, range_nm: f64, pixel_um: f64, pixel_mtf: bool) -> (f64, f64) {
    let (range, pixel) = (range_nm * 1e-9, pixel_um * 1e-6);
    let fast = evaluate(&scene(f_number, range, pixel, pixel_mtf, LAMBDA0)).unwrap().mean_mtf;
    let slow = reference(f_number, range, pixel, pixel_mtf, LAMBDA0);
    let rel = (fast - slow).abs() / slow;
    eprintln!(
        "F/{f_number:<4} {range_nm:>6} nm {pixel_um:>5} µm pixel MTF {pixel_mtf:<5}: mean MTF {fast:.12}, relative error {rel:.1e}"
    );
    assert!(
        rel < 1e-6,
        "F/{f_number}, range {range_nm} nm, {pixel_um} µm, pixel MTF {pixel_mtf}: fast {fast:.12} vs reference {slow:.12} ({rel:.2e})"
    );
    (fast, rel)
}

/// The headline check: the paper scene at F/2.5, 50 nm, within 1e-6 of the reference.
#[test]
fn paper_scene_mean_mtf_matches_the_reference() {
    let (mean, rel) = check(2.5, 50.0, 5.2, false);
    assert!(mean > 0.4 && mean < 0.5, "{mean}");
    assert!(rel < 1e-8, "{rel:e}");
}

/// The corners and middle of F/1.4–F/5 × 1–200 nm × 2–10 µm, pixel MTF on and off.
/// (F/1.4 with 200 nm on 2 µm pixels, the costliest corner, is in `costly_corner` below.)
#[test]
fn scenes_across_the_design_space_match_the_reference() {
    let cases = [
        (1.4, 1.0, 2.0, false),
        (1.4, 1.0, 10.0, true),
        (1.4, 50.0, 5.2, true),
        (1.4, 200.0, 10.0, false),
        (2.5, 1.0, 5.2, true),
        (2.5, 10.0, 2.0, false),
        (2.5, 100.0, 5.2, false),
        (2.5, 200.0, 5.2, true),
        (3.5, 25.0, 3.0, true),
        (5.0, 1.0, 2.0, true),
        (5.0, 50.0, 2.0, false),
        (5.0, 200.0, 2.0, true),
        (5.0, 200.0, 10.0, false),
        (5.0, 10.0, 10.0, true),
    ];
    for (f, r, p, pix) in cases {
        check(f, r, p, pix);
    }
}

/// F/5 on 2 µm pixels puts the cutoff of every wavelength above ~800 nm below Nyquist: the
/// clipped spectral panels and the frequency cuts at the cutoffs are exercised there.
#[test]
fn cutoff_inside_the_nyquist_band_matches_the_reference() {
    check(5.0, 150.0, 2.0, false);
}

/// A spectrum centred off the design wavelength is defocused throughout: the polychromatic OTF
/// changes sign below Nyquist and the modulus has kinks.
#[test]
fn off_design_band_with_sign_changes_matches_the_reference() {
    let (f, range, pixel) = (2.5, 5e-9, 5.2e-6);
    let result = evaluate(&scene(f, range, pixel, false, 850e-9)).unwrap();
    assert!(result.numerics.sign_changes > 0, "expected zeros of the OTF below Nyquist");
    let slow = reference(f, range, pixel, false, 850e-9);
    let rel = (result.mean_mtf - slow).abs() / slow;
    assert!(rel < 1e-6, "fast {} vs reference {slow} ({rel:e})", result.mean_mtf);
}

#[test]
fn costly_corner() {
    check(1.4, 200.0, 2.0, false);
}

/// Paper SI eq. S7–S8 by hand, paper scene:
/// A = (5.2 µm)² = 2.704e-11 m², t = 1.23 ms, NA = 1/(2 × 2.5) = 0.2 → π NA² = 0.1256637,
/// L = 0.025 W/(m² sr nm) = 2.5e7 W/(m² sr m), η = 0.2, τ1 = 0.15,
/// σ = 50 nm/(2√2) = 17.6777 nm, ∫ λ G dλ = λc σ √(2π) = 800e-9 × 4.43113e-8 = 3.54491e-14 m²,
/// h c = 1.98644586e-25 J m:
/// N = A t π NA² L η τ1 ∫λG / (h c) = 559.3854 e⁻, SNR0 = √N = 23.65133.
#[test]
fn photoelectrons_hand_worked() {
    let r = evaluate(&scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0)).unwrap();
    assert!((r.photoelectrons - 559.385_398_3).abs() < 1e-6, "{}", r.photoelectrons);
    assert!((r.snr0 - 23.651_329_74).abs() < 1e-7, "{}", r.snr0);
    assert!((r.asnr - r.snr0 * r.mean_mtf).abs() < 1e-12);
}

/// The mean and integral forms of eq. 1 differ by the Nyquist frequency only.
#[test]
fn integral_form_is_mean_times_nyquist() {
    let mut s = scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0);
    let mean: Evaluation = evaluate(&s).unwrap();
    let lens = ChromaticMetalens::new(2.5, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
    let options = Options { form: MetricForm::Integral, ..Options::default() };
    s = Scene::new(Arc::new(lens), s.radiance().clone(), s.camera().clone(), s.exposure(), options).unwrap();
    let integral = evaluate(&s).unwrap();
    // ν_N = 1/(2 × 5.2 µm) = 96.153846 cycles/mm
    assert!((integral.asnr - mean.asnr * 1e3 / (2.0 * 5.2)).abs() < 1e-9 * integral.asnr);
    assert_eq!(integral.mean_mtf, mean.mean_mtf);
}

/// Eq. S15 for the paper's lens: Δλ = 0.25 mm × 800 nm / (3.36 mm × 0.2) = 297.619 nm; a 600 nm
/// range puts ~16 % of the signal beyond it (the paper: "a spectral width of 600 nm will contain
/// wavelengths that are shifted more than 300 nm"), 50 nm none.
#[test]
fn fraunhofer_validity() {
    let narrow = evaluate(&scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0)).unwrap();
    assert!(narrow.fraunhofer.valid);
    assert!((narrow.fraunhofer.max_shift_nm.unwrap() - 297.619_047_6).abs() < 1e-6);
    assert_eq!(narrow.fraunhofer.fraction_outside, 0.0);
    // 600 nm range, 10 µm pixels to keep the run short: σ = 212.13 nm, 297.6/212.13 = 1.403σ,
    // two-sided tail 2 Q(1.403) = 0.1606 of a Gaussian (the λ weighting shifts it slightly)
    let broad = evaluate(&scene(2.5, 600e-9, 10e-6, false, LAMBDA0)).unwrap();
    assert!(!broad.fraunhofer.valid);
    assert!((broad.fraunhofer.fraction_outside - 0.16).abs() < 0.01, "{}", broad.fraunhofer.fraction_outside);
    assert!(broad.warnings.iter().any(|w| w.contains("Fraunhofer")));
}

/// Buralli–Morris for the paper's lens (SI, "Analytic estimate of VG"): M0 = 0.27, VG = 57 %.
#[test]
fn glare_of_the_paper_lens() {
    let r = evaluate(&scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0)).unwrap();
    assert!((r.glare.m0 - 0.27).abs() < 0.005 && (r.glare.vg - 0.57).abs() < 0.005, "{:?}", r.glare);
}

/// As the range shrinks the polychromatic MTF tends to the monochromatic one at λ0: the
/// diffraction-limited mean over [0, s_N], s_N = ν_N λ0 F#.
#[test]
fn narrow_band_tends_to_the_diffraction_limit() {
    let r = evaluate(&scene(2.5, 1e-12, 5.2e-6, false, LAMBDA0)).unwrap();
    let s_n = 800e-9 * 2.5 / (2.0 * 5.2e-6);
    let exact = optics::mtf_diffraction_limited_mean(s_n);
    assert!((r.mean_mtf - exact).abs() < 1e-9, "{} vs {exact}", r.mean_mtf);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, rng_seed: proptest::test_runner::RngSeed::Fixed(800), ..ProptestConfig::default() })]

    /// Random scenes over the whole domain the issue names: F/1.4–F/5, ranges 1–200 nm
    /// (log-uniform), pixels 2–10 µm, pixel MTF on and off.
    #[test]
    fn random_scenes_match_the_reference(
        f in 1.4f64..5.0,
        log_range in 0.0f64..2.301,
        pixel in 2.0f64..10.0,
        pixel_mtf in proptest::bool::ANY,
    ) {
        check(f, 10f64.powf(log_range), pixel, pixel_mtf);
    }
}

/// Off axis, lateral colour (image height ∝ f(λ)) smears the image along the field direction:
/// the tangential MTF falls, the sagittal one is untouched (the shifts are perpendicular to it).
/// The tangential mean is checked against a direct complex sum written here from the geometry:
/// OTF(ν) = ∫ λ G(λ) OTF_1D(ν λ F#, w(λ)) exp(−2πi ν h0 (λ0/λ − 1)) dλ / ∫ λ G dλ,
/// h0 = f0 tan θ, on composite Gauss–Legendre panels unrelated to the engine's.
#[test]
fn lateral_colour_splits_tangential_and_sagittal() {
    let (f, range, pixel, centre) = (2.5, 20e-9, 5.2e-6, LAMBDA0);
    let theta = 8f64.to_radians();
    // on axis the closed-form engine, off axis the spectral quadrature with lateral colour: both
    // asked for 1e-11
    let tight = |s: Scene| s.with_options(Options { tolerance: 1e-11, ..Options::default() }).unwrap();
    let on_axis = evaluate(&tight(scene(f, range, pixel, false, centre))).unwrap();
    let off = evaluate(&tight(scene(f, range, pixel, false, centre)).at_field(optics::Field::new(theta, 0.0)).unwrap())
        .unwrap();
    assert!((off.mean_mtf_sagittal - on_axis.mean_mtf).abs() < 1e-10 * on_axis.mean_mtf);
    assert!(off.mean_mtf_tangential < on_axis.mean_mtf - 0.05, "{} vs {}", off.mean_mtf_tangential, on_axis.mean_mtf);
    // the ASNR's mean is the mean over azimuth (docs/physics.md, "Off-axis MTFs"): between the
    // two, and not their average (the shift seen along φ is its projection Δ cos φ)
    let halves = 0.5 * (off.mean_mtf_tangential + off.mean_mtf_sagittal);
    assert!(off.mean_mtf > off.mean_mtf_tangential && off.mean_mtf < off.mean_mtf_sagittal, "{}", off.mean_mtf);
    assert!((off.mean_mtf - halves).abs() > 1e-4 * halves, "{} vs {halves}", off.mean_mtf);

    let sigma = range / (2.0 * 2f64.sqrt());
    let h0 = F0 * theta.tan();
    let nyquist = 0.5 / pixel;
    let (lo, hi) = (centre - 8.0 * sigma, centre + 8.0 * sigma);
    let rho = |l: f64| l * (-0.5 * ((l - centre) / sigma).powi(2)).exp();
    let norm = optics::quad::composite(lo, hi, 64, rho);
    let tangential = |nu: f64| {
        let (mut re, mut im) = (0.0, 0.0);
        optics::quad::for_each_node(lo, hi, 64, |l, q| {
            // w = (1 − λ/λ0) f0/(8 F#² λ) (docs/physics.md, "Sign of the wavefront")
            let w = (1.0 - l / LAMBDA0) * F0 / (8.0 * f * f) / l;
            let v = q * rho(l) * optics::defocus_otf(nu * l * f, w);
            let phase = -2.0 * std::f64::consts::PI * nu * h0 * (LAMBDA0 / l - 1.0);
            re += v * phase.cos();
            im += v * phase.sin();
        });
        re.hypot(im) / norm
    };
    let direct = optics::quad::composite(0.0, nyquist, 48, tangential) / nyquist;
    let rel = (off.mean_mtf_tangential - direct).abs() / direct;
    assert!(rel < 1e-6, "engine {} vs direct {direct} ({rel:e})", off.mean_mtf_tangential);
}

fn paper_with(lens: ChromaticMetalens) -> Scene {
    let filter = Gaussian::from_range(LAMBDA0, 50e-9, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(5.2e-6, Spectrum::Constant(0.2), false).unwrap();
    Scene::new(Arc::new(lens), radiance, camera, 1.23e-3, Options::default()).unwrap()
}

fn paper_lens() -> ChromaticMetalens {
    ChromaticMetalens::new(2.5, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap()
}

/// Issue 3: the FFT path on the paper scene (the full circle given as a sampled aperture: a
/// sector of the full turn, which the engine does not reduce to the exact path as it does a
/// circular iris) agrees with the exact 1-D path within 1e-4 at the default FFT tolerance of
/// 1e-4 (the sampling judged by the mean over azimuth chose 512 with 256: measured 5.7e-6; the
/// mean along x alone chose 256 with 128, 5.5e-5).
#[test]
fn fft_path_matches_the_exact_path_on_the_paper_scene() {
    let exact = evaluate(&paper_with(paper_lens())).unwrap();
    let full_turn = optics::fft::Aperture::mask(|x, y| x * x + y * y <= 1.0);
    let fft = evaluate(&paper_with(paper_lens().with_aperture(full_turn))).unwrap();
    assert!(exact.numerics.engine.starts_with("closed-form"), "{}", exact.numerics.engine);
    assert!(fft.numerics.engine.starts_with("fft: "), "{}", fft.numerics.engine);
    let rel = (fft.mean_mtf - exact.mean_mtf).abs() / exact.mean_mtf;
    eprintln!("FFT {} vs exact {} ({rel:.1e})", fft.mean_mtf, exact.mean_mtf);
    assert!(rel < 1e-4, "FFT {} vs exact {} ({rel:e})", fft.mean_mtf, exact.mean_mtf);
    // a centred circle is symmetric: both directions agree to the grid's interpolation error
    assert!((fft.mean_mtf_tangential - fft.mean_mtf_sagittal).abs() < 1e-5);
}

/// Paper SI Fig. S3: the measured MTF fell below simulation because the mechanical iris was
/// decentred. A 10 % decentre along x lowers the mean MTF and makes it direction dependent
/// (lower along the decentre); ignoring the decentre would give the centred numbers exactly.
#[test]
fn decentred_iris_lowers_the_mtf_and_breaks_the_symmetry() {
    let centred = evaluate(&paper_with(paper_lens().with_aperture(optics::fft::Aperture::circle()))).unwrap();
    let iris = optics::fft::Aperture::circle().decentred(0.1, 0.0).unwrap();
    let decentred = evaluate(&paper_with(paper_lens().with_aperture(iris))).unwrap();
    assert!(decentred.mean_mtf < centred.mean_mtf - 1e-3, "{} vs {}", decentred.mean_mtf, centred.mean_mtf);
    assert!(
        decentred.mean_mtf_tangential < decentred.mean_mtf_sagittal - 1e-3,
        "x {} vs y {}",
        decentred.mean_mtf_tangential,
        decentred.mean_mtf_sagittal
    );
}

// ---- wavefront sign ----
// docs/physics.md, "Sign of the wavefront": W020 > 0 is a focus behind the detector, so the chromatic
// lens has W020(λ) = (1 − λ/λ0) f0/(8F#²) = (1 − λ/λ0) k, negative above λ0, and the Seidel terms
// carry the same sign. Pure defocus hides the sign (the OTF is even in W020); the checks below
// combine the chromatic defocus with a term that does not.

/// `optics::reference::mean_mtf` of the paper scene (F/2.5, 50 nm Gaussian at λ0, 5.2 µm) with
/// the constant defocus `c` (m) added to the chromatic one: `(1 − λ/λ0) k + c = (k + c)(1 − λ/λ0')`
/// with `λ0' = λ0 (k + c)/k`, i.e. the reference's chromatic lens with design wavelength `λ0'`
/// and focal length `f0 (k + c)/k` (the focal length enters its defocus only, through `k`).
fn paper_reference_with_defocus(c: f64) -> f64 {
    let k = F0 / (8.0 * 2.5 * 2.5);
    let sigma = 50e-9 / (2.0 * 2f64.sqrt());
    let density = move |l: f64| l * (-0.5 * ((l - LAMBDA0) / sigma).powi(2)).exp();
    let scene = ReferenceScene {
        density: &density,
        lambda_min: LAMBDA0 - 12.0 * sigma,
        lambda_max: LAMBDA0 + 12.0 * sigma,
        breakpoints: &[],
        f_number: 2.5,
        focal_length_m: F0 * (k + c) / k,
        design_wavelength_m: LAMBDA0 * (k + c) / k,
        pixel_pitch_m: 5.2e-6,
        pixel_mtf: false,
    };
    mean_mtf(&scene, 1e-10)
}

/// The acceptance check of the sign on the embedded paper scene (`asnr evaluate --set
/// lens.field_curvature_um=0.5 --set options.pupil_samples=512`, and `lens.spherical_um=0.5`).
/// Field curvature adds to the chromatic defocus, so the scene with `W220 = 0.5 µm` (FFT path,
/// 512 pupil samples) is the pure-defocus scene with `W020(λ) + W220`, sharpest where
/// `W020(λ) = −W220`, at 806 nm: its mean MTF is the 1-D reference's with that defocus, 0.426322
/// (the FFT path at 512 samples gives 0.426315).
/// Independently, quadrature of the pupil integral in numpy and prysm's FFT, with this sign
/// convention, gave 0.42632 for field curvature and 0.42525 for spherical aberration
/// `W040 = 0.5 µm`. With the opposite sign (the defect this checks) the field-curvature scene came
/// out 0.42291 (sharpest at 794 nm) and the spherical one 0.42230. The spherical scene runs at
/// the default 256 pupil samples (0.425221, against 0.425238 at 512), to keep the test short.
#[test]
fn seidel_terms_on_the_paper_scene_follow_the_wavefront_sign() {
    let run = |lens: ChromaticMetalens, pupil_samples: usize| {
        let options = Options { pupil_samples: Some(pupil_samples), ..Options::default() };
        evaluate(&paper_with(lens).with_options(options).unwrap()).unwrap()
    };

    let w220 = 0.5e-6;
    let curved = run(paper_lens().with_seidel(0.0, 0.0, 0.0, w220), 512);
    assert!(curved.numerics.engine.starts_with("fft: 512 pupil samples"), "{}", curved.numerics.engine);
    let same_sign = paper_reference_with_defocus(w220);
    let opposite = paper_reference_with_defocus(-w220);
    eprintln!("field curvature: {} (reference {same_sign}, opposite sign {opposite})", curved.mean_mtf);
    assert!((same_sign - 0.42632).abs() < 1e-5, "{same_sign}");
    assert!(same_sign - opposite > 3e-3, "{same_sign} vs {opposite}");
    assert!((curved.mean_mtf - same_sign).abs() < 5e-5, "{} vs {same_sign}", curved.mean_mtf);
    assert!((curved.mean_mtf - 0.42632).abs() < 2e-4, "{}", curved.mean_mtf);

    let spherical = run(paper_lens().with_seidel(0.5e-6, 0.0, 0.0, 0.0), 256);
    eprintln!("spherical: {}", spherical.mean_mtf);
    assert!((spherical.mean_mtf - 0.42525).abs() < 2e-4, "{}", spherical.mean_mtf);
}

/// A decentred iris off axis: the decentre tilts each wavelength's wave by `2 W020(λ) dx`
/// (normalized pupil), moving its image by `x_d(λ) = 4 W020(λ) dx F# = dx f0 (1 − λ/λ0)/(2F#)`
/// (toward −x above λ0 for dx > 0: the rays have crossed in front of the detector), while lateral
/// colour moves it by `h0 (λ0/λ − 1)`, `h0 = f0 tan θ`, also toward −x above λ0 for a field along
/// +x. The two add with an iris decentred toward the field and partly cancel with one decentred
/// away from it. The engine's tangential mean MTF (along the field) (FFT path) against a direct sum written here,
/// `OTF(ν) = ∫ λ G(λ) OTF_1D(ν λ F#, w(λ)) exp(−2πi ν (x_d(λ) + h0 (λ0/λ − 1))) dλ / ∫ λ G dλ`.
#[test]
fn decentred_iris_and_lateral_colour_shift_the_image_the_same_way() {
    let (f, pixel) = (2.5, 5.2e-6);
    let theta = 8f64.to_radians();
    let h0 = F0 * theta.tan();
    let sigma = 50e-9 / (2.0 * 2f64.sqrt());
    let (lo, hi) = (LAMBDA0 - 8.0 * sigma, LAMBDA0 + 8.0 * sigma);
    let rho = |l: f64| l * (-0.5 * ((l - LAMBDA0) / sigma).powi(2)).exp();
    let norm = optics::quad::composite(lo, hi, 64, rho);
    let nyquist = 0.5 / pixel;
    let direct = |dx: f64| {
        let tangential = |nu: f64| {
            let (mut re, mut im) = (0.0, 0.0);
            optics::quad::for_each_node(lo, hi, 64, |l, q| {
                let w = (1.0 - l / LAMBDA0) * F0 / (8.0 * f * f) / l;
                let v = q * rho(l) * optics::defocus_otf(nu * l * f, w);
                let shift = dx * F0 * (1.0 - l / LAMBDA0) / (2.0 * f) + h0 * (LAMBDA0 / l - 1.0);
                let phase = -2.0 * std::f64::consts::PI * nu * shift;
                re += v * phase.cos();
                im += v * phase.sin();
            });
            re.hypot(im) / norm
        };
        optics::quad::composite(0.0, nyquist, 48, tangential) / nyquist
    };
    let engine = |dx: f64| {
        let iris = optics::fft::Aperture::circle().decentred(dx, 0.0).unwrap();
        let scene = paper_with(paper_lens().with_aperture(iris)).at_field(optics::Field::new(theta, 0.0)).unwrap();
        evaluate(&scene).unwrap().mean_mtf_tangential
    };
    let (toward, away) = (engine(0.15), engine(-0.15));
    let (toward_direct, away_direct) = (direct(0.15), direct(-0.15));
    eprintln!("iris toward the field {toward} ({toward_direct}), away {away} ({away_direct})");
    assert!(away_direct - toward_direct > 0.02, "{toward_direct} vs {away_direct}");
    assert!((toward - toward_direct).abs() < 3e-4, "{toward} vs {toward_direct}");
    assert!((away - away_direct).abs() < 3e-4, "{away} vs {away_direct}");
}

/// Both glare modes (paper SI eq. S14). Paper scene: N = 559.3854 e⁻ from τ1 = 0.15; all
/// transmitted light N_T = N × 0.55/0.15 = 2051.0798 e⁻; SNR = N/√N_T = 559.3854/45.28885 = 12.35148.
/// The MTF (normalized) is the same in both modes.
#[test]
fn glare_modes() {
    let first = evaluate(&scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0)).unwrap();
    let lens = paper_lens();
    let options = Options { glare: metric::GlareMode::Included, ..Options::default() };
    let s = scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0);
    let with = Scene::new(Arc::new(lens), s.radiance().clone(), s.camera().clone(), s.exposure(), options).unwrap();
    let glare = evaluate(&with).unwrap();
    assert!((glare.transmitted_photoelectrons - 2051.0798).abs() < 1e-3, "{}", glare.transmitted_photoelectrons);
    assert!((glare.snr0 - 12.35148).abs() < 1e-4, "{}", glare.snr0);
    assert_eq!(glare.mean_mtf, first.mean_mtf);
    // T = τ1: no stray light, both modes agree
    let clean = ChromaticMetalens::new(2.5, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.15)).unwrap();
    let options = Options { glare: metric::GlareMode::Included, ..Options::default() };
    let no_stray =
        Scene::new(Arc::new(clean), s.radiance().clone(), s.camera().clone(), s.exposure(), options).unwrap();
    assert!((evaluate(&no_stray).unwrap().snr0 - first.snr0).abs() < 1e-9 * first.snr0);
}

/// A sensor with read noise moves SNR0 off √N (EMVA 1288 form): paper scene, N = 559.3854 e⁻,
/// σ_r = 10 e⁻: SNR0 = N/√(N + σ_r²) = 559.3854/25.67850 = 21.78419.
#[test]
fn read_noise_lowers_snr0() {
    let s = scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0);
    let sensor = noise::Sensor::without_adc(10.0, 0.0, f64::INFINITY).unwrap();
    let camera = s.camera().clone().with_sensor(sensor);
    let noisy =
        Scene::new(Arc::new(paper_lens()), s.radiance().clone(), camera, s.exposure(), Options::default()).unwrap();
    let r = evaluate(&noisy).unwrap();
    assert!((r.snr0 - 21.78419).abs() < 1e-5, "{}", r.snr0);
    assert_eq!(r.noise.read_variance_e2, 100.0);
    assert!(!r.noise.saturated && r.warnings.is_empty());
    // the report names the terms: not shot-noise limited any more
    assert!(!r.noise.shot_noise_limited);
    assert_eq!((r.noise.terms.as_slice(), r.noise.read_noise_e), (&["shot", "read"][..], 10.0));
    let ideal = evaluate(&s).unwrap();
    assert!(ideal.noise.shot_noise_limited && ideal.noise.terms == ["shot"]);
}

/// Over a field-of-view average, `mtf_curve` keeps every field point's curves, and its headline
/// curves are their weighted means (the on-axis point has no tangential–sagittal split).
#[test]
fn mtf_curve_over_fields_keeps_every_point() {
    let base = || scene(2.5, 20e-9, 5.2e-6, false, LAMBDA0);
    let off = optics::Field::new(8f64.to_radians(), 0.0);
    let points = vec![(optics::Field::ON_AXIS, 2.0), (off, 1.0)];
    let curve = |s: &Scene| metric::mtf_curve(s, metric::FrequencyRange::Nyquist, 9, &[]).unwrap();
    let fov = curve(&base().over_fields(points).unwrap());
    let (on, at8) = (curve(&base()), curve(&base().at_field(off).unwrap()));
    assert_eq!(fov.field_points.len(), 2);
    assert_eq!(fov.field_points[1].mtf_tangential, at8.mtf_tangential);
    assert!(fov.field_points[0].mtf_tangential.is_none());
    let (t8, s8) = (at8.mtf_tangential.as_ref().unwrap(), at8.mtf_sagittal.as_ref().unwrap());
    for k in 0..9 {
        let mean = (2.0 * on.mtf[k] + at8.mtf[k]) / 3.0;
        assert!((fov.mtf[k] - mean).abs() < 1e-14, "{k}: {} vs {mean}", fov.mtf[k]);
        let tangential = (2.0 * on.mtf[k] + t8[k]) / 3.0;
        assert!((fov.mtf_tangential.as_ref().unwrap()[k] - tangential).abs() < 1e-14);
        // lateral colour lowers the tangential MTF (along the field), not the sagittal one
        assert!(t8[k] <= s8[k] + 1e-12 && (s8[k] - on.mtf[k]).abs() < 1e-9, "{k}");
    }
}

/// Field-of-view average (paper SI, end of the VG section): the weighted mean of the ASNRs at
/// the field points, each with its own off-axis OTF.
#[test]
fn field_of_view_average_is_the_weighted_mean() {
    let base = || scene(2.5, 20e-9, 5.2e-6, false, LAMBDA0);
    let points = [(optics::Field::ON_AXIS, 2.0), (optics::Field::new(8f64.to_radians(), 0.0), 1.0)];
    let each: Vec<f64> = points.iter().map(|&(f, _)| evaluate(&base().at_field(f).unwrap()).unwrap().asnr).collect();
    let fov = evaluate(&base().over_fields(points.to_vec()).unwrap()).unwrap();
    let expected = (2.0 * each[0] + each[1]) / 3.0;
    assert!((fov.asnr - expected).abs() < 1e-12 * expected, "{} vs {expected}", fov.asnr);
    assert_eq!(fov.field_points.len(), 2);
    assert_eq!(fov.field_points[1].asnr, each[1]);
    assert!(base().over_fields(vec![(optics::Field::ON_AXIS, 0.0)]).is_err());
}

/// Regression: with the cutoff below Nyquist the OTF vanishes identically over part of the band;
/// those exact zeros once counted as sign changes and the adaptive rule split without end.
/// F/16 and F/50 (cutoff 78 and 25 cycles/mm against a Nyquist of 96) against the reference.
#[test]
fn cutoff_below_nyquist_is_fast_and_right() {
    check(16.0, 50.0, 5.2, false);
    check(50.0, 50.0, 5.2, true);
}

/// Regression: 0.3 µm pixels put Nyquist (1667 cycles/mm) far past every cutoff; near the cutoff
/// the OTF is tiny and its rounding noise once kept the adaptive rule bisecting without end.
/// Once Nyquist is past the cutoff of every wavelength (10 nm band: ±7σ reaches 775 nm, cutoff
/// 1/(775 nm × 2.5) = 516 cycles/mm), smaller pixels add only zeros: the MTF area ∫ MTF dν is the
/// same for 0.5 µm and 0.3 µm pixels (each within the default relative tolerance 1e-6 of it),
/// and below the diffraction limit's ν_c · 4/(3π).
#[test]
fn nyquist_far_past_the_cutoff_terminates() {
    let a = evaluate(&scene(2.5, 10e-9, 0.5e-6, false, LAMBDA0)).unwrap();
    let b = evaluate(&scene(2.5, 10e-9, 0.3e-6, false, LAMBDA0)).unwrap();
    let (area_a, area_b) = (a.mtf_integral_cyc_per_mm, b.mtf_integral_cyc_per_mm);
    let tolerance = optics::DEFAULT_TOLERANCE;
    assert!((area_a - area_b).abs() < 2.0 * tolerance * area_a, "{area_a} vs {area_b}");
    // diffraction limit at 775 nm: 516.1 cycles/mm × 0.42441 = 219.0 cycles/mm
    assert!(area_b < 219.0 && area_b > 100.0, "{area_b}");
    assert!(b.numerics.otf_evaluations < 50_000, "{}", b.numerics.otf_evaluations);
}

/// The closed-form spectral engine against the spectral quadrature (both at 1e-10) on scenes
/// that stress it: broad and narrow bands, off-centre bands (the phase then oscillates across
/// the spectrum), a QE linear in λ (a quadratic polynomial weight), and a Gaussian that reaches
/// λ ≤ 0 (the truncated lower tail).
#[test]
fn closed_form_engine_matches_the_spectral_quadrature() {
    let cases = [
        (2.5, 50e-9, LAMBDA0, false),
        (1.0, 200e-9, LAMBDA0, false),
        (4.0, 0.01e-9, LAMBDA0, false),
        (2.5, 60e-9, 850e-9, true),
        (1.4, 30e-9, 700e-9, true),
        (8.0, 900e-9, 500e-9, false),
    ];
    for (f, range, centre, linear_qe) in cases {
        let mut s = scene(f, range, 5.2e-6, true, centre);
        if linear_qe {
            let lens = ChromaticMetalens::new(f, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
            let filter = Gaussian::from_range(centre, range, 1.0).unwrap();
            let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
            let qe = Spectrum::product(vec![Spectrum::Constant(0.2), Spectrum::Linear { slope: 1.2e6 }]);
            let camera = Camera::new(5.2e-6, qe, true).unwrap();
            s = Scene::new(Arc::new(lens), radiance, camera, 1.23e-3, Options::default()).unwrap();
        }
        let with = |closed_form| {
            let options = Options { tolerance: 1e-10, closed_form, ..Options::default() };
            evaluate(&s.clone().with_options(options).unwrap()).unwrap()
        };
        let (closed, quadrature) = (with(true), with(false));
        assert!(closed.numerics.engine.starts_with("closed-form"), "{}", closed.numerics.engine);
        assert_eq!(quadrature.numerics.engine, "exact-1d");
        let rel = (closed.mean_mtf - quadrature.mean_mtf).abs() / quadrature.mean_mtf;
        eprintln!(
            "F/{f} {range:e} m at {centre:e} m: closed {} quadrature {} ({rel:.1e})",
            closed.mean_mtf, quadrature.mean_mtf
        );
        assert!(rel < 1e-9, "F/{f}, {range} m at {centre} m: {} vs {} ({rel:e})", closed.mean_mtf, quadrature.mean_mtf);
        let pe = (closed.photoelectrons - quadrature.photoelectrons).abs() / quadrature.photoelectrons;
        assert!(pe < 1e-10, "photoelectrons {} vs {}", closed.photoelectrons, quadrature.photoelectrons);
    }
}

/// The requested tolerance is met: at 1e-3, 1e-6 and 1e-8 the closed-form engine's mean MTF is
/// within that relative error of its own converged value (1e-13; the engine itself is checked
/// against the spectral quadrature above and the reference elsewhere), on easy and hard scenes:
/// the paper, broad bands at fast F-numbers (narrow, oscillating bumps in the pupil angle), a
/// slow narrow one, and pixels whose Nyquist frequency is far past the cutoff.
#[test]
fn closed_form_engine_meets_the_requested_tolerance() {
    let cases = [
        (2.5, 50e-9, 5.2e-6),
        (1.0, 200e-9, 5.2e-6),
        (1.4, 150e-9, 2e-6),
        (2.6, 170e-9, 5.2e-6),
        (10.0, 20e-9, 5.2e-6),
        (2.5, 10e-9, 0.3e-6),
        // Nyquist past the cutoff: the OTF dips to zero between the rule's nodes
        (12.889473684210527, 21.526315789473685e-9, 2e-6),
    ];
    for (f, range, pixel) in cases {
        let s = scene(f, range, pixel, false, LAMBDA0);
        let at = |tolerance| {
            let options = Options { tolerance, ..Options::default() };
            evaluate(&s.clone().with_options(options).unwrap()).unwrap().mean_mtf
        };
        let converged = at(1e-13);
        for tolerance in [1e-3, 1e-6, 1e-8] {
            let rel = (at(tolerance) - converged).abs() / converged;
            eprintln!("F/{f} {range:e} m, {pixel:e} m pixels, tolerance {tolerance:e}: error {rel:.1e}");
            assert!(rel <= tolerance, "F/{f}, {range} m, {pixel} m pixels: error {rel:e} at tolerance {tolerance:e}");
        }
    }
}

/// A non-white noise spectrum moves the SNR inside the integral (paper eq. 1 text): a flat
/// n = 2 halves the ASNR and leaves the mean MTF alone; a ramp n(ν) = 1 + 2ν/ν_N gives
/// SNR0 × mean(MTF/n), checked against a direct composite rule over the engine's own MTF.
#[test]
fn noise_spectrum_moves_the_snr_inside_the_integral() {
    let white = scene(2.5, 50e-9, 5.2e-6, true, LAMBDA0);
    let base = evaluate(&white).unwrap();
    let nyquist = 0.5 / 5.2e-6;
    let with = |shape: optics::NoiseShape| {
        let camera = white.camera().clone().with_noise_spectrum(shape);
        let s = Scene::new(white.lens_arc(), white.radiance().clone(), camera, white.exposure(), Options::default());
        evaluate(&s.unwrap()).unwrap()
    };
    let flat = with(optics::NoiseShape::new(vec![0.0, nyquist], vec![2.0, 2.0]).unwrap());
    assert!((flat.asnr - 0.5 * base.asnr).abs() < 1e-9 * base.asnr, "{} vs {}", flat.asnr, base.asnr);
    assert_eq!(flat.mean_mtf, base.mean_mtf);
    assert!(flat.numerics.noise_spectrum && !base.numerics.noise_spectrum);

    let ramp = with(optics::NoiseShape::new(vec![0.0, nyquist], vec![1.0, 3.0]).unwrap());
    let detected = Spectrum::product(vec![
        white.radiance().clone(),
        white.camera().quantum_efficiency().clone(),
        Spectrum::Linear { slope: 1.0 },
    ]);
    let poly =
        optics::Polychromatic::new(white.lens(), &detected, optics::Field::ON_AXIS, nyquist, Some(5.2e-6)).unwrap();
    let direct = optics::quad::composite(0.0, nyquist, 64, |nu| poly.mtf(nu) / (1.0 + 2.0 * nu / nyquist)) / nyquist;
    let rel = (ramp.asnr / ramp.snr0 - direct).abs() / direct;
    assert!(rel < 1e-7, "{} vs {direct} ({rel:e})", ramp.asnr / ramp.snr0);
    assert!(ramp.asnr < base.asnr && ramp.asnr > flat.asnr);
}

/// A noise table's rows cut the frequency rule (docs/physics.md, "Gradients under a noise
/// spectrum"): `1/n(ν)` has a kink at each row, so the noise-weighted mean of the paper scene at
/// 1e-8 under a table rising 1 → 3 over 0–130 cycles/mm (rows at 30 and 70 inside the band) is
/// within it of the reference written here (the reference OTF, `polychromatic_otf` at 1e-11, on
/// 16-point Gauss–Legendre panels between the rows), and takes at most 5× the OTF evaluations of
/// the white mean on the same engine (measured 51 against 17, the weighted mean 8.5e-13 off;
/// without the cuts the adaptive rule bisected around each kink: `asnr evaluate` on this scene
/// under that table at 1e-8 read 967 OTF values, the white 17).
#[test]
fn noise_table_rows_cut_the_frequency_rule() {
    let white = scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0);
    let nyquist = 0.5 / 5.2e-6;
    let shape = optics::NoiseShape::new(vec![0.0, 30e3, 70e3, 130e3], vec![1.0, 1.4, 2.2, 3.0]).unwrap();
    let detected = Spectrum::product(vec![
        white.radiance().clone(),
        white.camera().quantum_efficiency().clone(),
        Spectrum::Linear { slope: 1.0 },
    ]);
    let tolerance = 1e-8;
    let settings = optics::Settings { tolerance, ..optics::Settings::default() };
    let poly =
        optics::Polychromatic::with_settings(white.lens(), &detected, optics::Field::ON_AXIS, nyquist, None, settings)
            .unwrap();
    let (weighted, work) = poly.mean_mtf_over_noise(&shape, 0.0);
    let (_, white_work) = poly.mean_mtf();
    let sigma = 50e-9 / (2.0 * 2f64.sqrt());
    let density = move |l: f64| l * (-0.5 * ((l - LAMBDA0) / sigma).powi(2)).exp();
    let reference = ReferenceScene {
        density: &density,
        lambda_min: LAMBDA0 - 12.0 * sigma,
        lambda_max: LAMBDA0 + 12.0 * sigma,
        breakpoints: &[],
        f_number: 2.5,
        focal_length_m: F0,
        design_wavelength_m: LAMBDA0,
        pixel_pitch_m: 5.2e-6,
        pixel_mtf: false,
    };
    let ends = [0.0, 30e3, 70e3, nyquist];
    let direct = ends
        .windows(2)
        .map(|w| {
            optics::quad::composite(w[0], w[1], 8, |nu| {
                optics::reference::polychromatic_otf(&reference, nu, 1e-11).abs() / shape.value(nu)
            })
        })
        .sum::<f64>()
        / nyquist;
    let rel = (weighted - direct).abs() / direct;
    eprintln!(
        "mean(MTF/n) {weighted:.12} against {direct:.12} ({rel:.1e}); OTF evaluations {} against the white {}",
        work.otf_evaluations, white_work.otf_evaluations
    );
    assert!(rel <= tolerance, "{weighted} vs {direct} ({rel:e})");
    assert!(work.otf_evaluations <= 5 * white_work.otf_evaluations, "{work:?} vs {white_work:?}");
}

mod aperture_lane;
mod azimuth;
mod bias_lane;
mod design_lane;
mod factored;
mod fraunhofer;
mod line;
mod line_lane;
mod metrics;
mod phase_map;
mod properties;
mod robust;

/// Relative illumination (docs/physics.md, "Relative illumination"): cos⁴θ changes nothing on
/// axis; at 12° along x (and at (8°, 9°), θ from tan²θ = tan²8° + tan²9°) the signal is the
/// hand-worked N = 559.3854 e⁻ of the paper scene times cos⁴θ, SNR0 its square root, the mean MTF
/// unchanged; with σ_r = 10 e⁻ the noise is recomputed from the lower signal,
/// SNR0 = N'/√(N' + σ_r²). A table interpolates linearly in the angle.
#[test]
fn relative_illumination_scales_the_signal_by_cos4() {
    use metric::RelativeIllumination;
    let n = 559.385_398_3;
    let base = scene(2.5, 50e-9, 5.2e-6, false, LAMBDA0);
    let on_axis = evaluate(&base.clone().with_relative_illumination(RelativeIllumination::Cos4)).unwrap();
    assert_eq!(on_axis.photoelectrons, evaluate(&base).unwrap().photoelectrons);
    assert_eq!((on_axis.relative_illumination.model.as_str(), on_axis.relative_illumination.factor), ("cos4", 1.0));
    for (x_deg, y_deg) in [(12.0f64, 0.0f64), (8.0, 9.0)] {
        let field = optics::Field::new(x_deg.to_radians(), y_deg.to_radians());
        let plain = base.clone().at_field(field).unwrap();
        let none = evaluate(&plain).unwrap();
        let cos4 = evaluate(&plain.clone().with_relative_illumination(RelativeIllumination::Cos4)).unwrap();
        let theta = (x_deg.to_radians().tan().powi(2) + y_deg.to_radians().tan().powi(2)).sqrt().atan();
        let factor = theta.cos().powi(4);
        assert!((cos4.photoelectrons - n * factor).abs() < 1e-6, "{} vs {}", cos4.photoelectrons, n * factor);
        assert!((cos4.photoelectrons / none.photoelectrons - factor).abs() < 1e-15);
        assert!((cos4.snr0 - (n * factor).sqrt()).abs() < 1e-7);
        assert_eq!(cos4.mean_mtf, none.mean_mtf);
        assert!((cos4.asnr - cos4.snr0 * cos4.mean_mtf).abs() < 1e-12);
        assert!((cos4.relative_illumination.factor - factor).abs() < 1e-15);
    }
    // read noise: recomputed from the lower signal
    let field = optics::Field::new(20f64.to_radians(), 0.0);
    let sensor = noise::Sensor::without_adc(10.0, 0.0, f64::INFINITY).unwrap();
    let noisy = Scene::new(
        Arc::new(paper_lens()),
        base.radiance().clone(),
        base.camera().clone().with_sensor(sensor),
        base.exposure(),
        Options::default(),
    )
    .unwrap()
    .at_field(field)
    .unwrap()
    .with_relative_illumination(RelativeIllumination::Cos4);
    let r = evaluate(&noisy).unwrap();
    let signal = n * 20f64.to_radians().cos().powi(4);
    assert!((r.snr0 - signal / (signal + 100.0).sqrt()).abs() < 1e-7, "{}", r.snr0);
    // the lens's own table, 0.9 at 10°, 0.7 at 20°: 0.8 at 15°
    let table =
        RelativeIllumination::table("ri.csv", vec![0.0, 10f64.to_radians(), 20f64.to_radians()], vec![1.0, 0.9, 0.7])
            .unwrap();
    let at15 = base.clone().at_field(optics::Field::new(15f64.to_radians(), 0.0)).unwrap();
    let r = evaluate(&at15.clone().with_relative_illumination(table)).unwrap();
    assert!((r.photoelectrons - 0.8 * n).abs() < 1e-6, "{}", r.photoelectrons);
    assert!((r.relative_illumination.factor - 0.8).abs() < 1e-12);
    // over a field-of-view average each point has its own factor; the signal is their mean
    let fov = base
        .clone()
        .over_fields(vec![(optics::Field::ON_AXIS, 1.0), (optics::Field::new(12f64.to_radians(), 0.0), 1.0)])
        .unwrap()
        .with_relative_illumination(RelativeIllumination::Cos4);
    let r = evaluate(&fov).unwrap();
    let c = 12f64.to_radians().cos().powi(4);
    assert_eq!(r.field_points[0].relative_illumination, 1.0);
    assert!((r.field_points[1].relative_illumination - c).abs() < 1e-15);
    assert!((r.photoelectrons - n * (1.0 + c) / 2.0).abs() < 1e-6);
}
