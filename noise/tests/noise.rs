//! Integration tests of the noise crate: the noise budget against hand-worked numbers and the
//! paper's identities (SI eq. S9, S14), saturation, the measured SNR (eq. 2–4) and the camera
//! characterization (SI, EMVA 1288) on synthetic data from a fixed-seed generator, and property
//! tests on physical ranges.

use noise::{
    Error, MeasuredSnr, Sensor, budget, log_slope, measured_snr, measured_snr_regions, photon_transfer_gain,
    snr_with_glare,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// Closed-form arithmetic: a few roundings of numbers of order 1e3.
const TIGHT: f64 = 1e-12;
/// Identities that hold to rounding: a few units in the last place, relative.
const ULPS: f64 = 4.0 * f64::EPSILON;

// ---------------------------------------------------------------------------------------------
// A deterministic normal generator: the project's one family (PCG-64 MCG from rand_pcg, seeded;
// rand_distr's standard normal).

struct Normal(rand_pcg::Pcg64Mcg);

impl Normal {
    fn new(seed: u64) -> Normal {
        Normal(rand::SeedableRng::seed_from_u64(seed))
    }

    /// A standard normal deviate.
    fn sample(&mut self) -> f64 {
        rand_distr::Distribution::sample(&rand_distr::StandardNormal, &mut self.0)
    }
}

/// `pixels` time series of `frames` samples, mean `level`, standard deviation `sigma`.
fn stack(normal: &mut Normal, pixels: usize, frames: usize, level: f64, sigma: f64) -> Vec<Vec<f64>> {
    (0..pixels).map(|_| (0..frames).map(|_| level + sigma * normal.sample()).collect()).collect()
}

// ---------------------------------------------------------------------------------------------
// Noise budget

#[test]
fn budget_hand_worked() {
    // N = 1000 e⁻, σ_r = 5 e⁻, dark 100 e⁻/s × 0.1 s = 10 e⁻, K = 0.5 DN/e⁻ (12 bits: 8190 e⁻ range):
    // shot 1000, dark 10, read 25, quantization (1/12)/0.25 = 0.333…; total 1035.333… e⁻²;
    // SNR = 1000/√1035.333… = 31.078489 (EMVA 1288 §2.3)
    let sensor = Sensor::new(5.0, 100.0, 20_000.0, 0.5, 12).unwrap();
    let b = budget(&sensor, 1000.0, 0.0, 0.1).unwrap();
    assert!(!b.saturated);
    assert_eq!((b.signal_e, b.background_e, b.shot_variance_e2, b.read_variance_e2), (1000.0, 0.0, 1000.0, 25.0));
    assert!((b.dark_e - 10.0).abs() < TIGHT && (b.dark_variance_e2 - 10.0).abs() < TIGHT);
    assert!((b.quantization_variance_e2 - 1.0 / 3.0).abs() < TIGHT);
    assert!((b.total_variance_e2 - 1035.0 - 1.0 / 3.0).abs() < TIGHT, "{}", b.total_variance_e2);
    assert!((b.snr - 31.078_489_423).abs() < 1e-8, "{}", b.snr);
    assert!((b.noise_e() - 32.176_596).abs() < 1e-6, "{}", b.noise_e());
}

#[test]
fn budget_with_background_adds_its_shot_noise_only() {
    // 1000 e⁻ signal + 500 e⁻ background on the camera above: total 1535.333…, SNR = 25.5216
    let sensor = Sensor::new(5.0, 100.0, 20_000.0, 0.5, 12).unwrap();
    let b = budget(&sensor, 1000.0, 500.0, 0.1).unwrap();
    assert_eq!((b.signal_e, b.shot_variance_e2), (1000.0, 1500.0));
    assert!((b.snr - 1000.0 / (1535.0f64 + 1.0 / 3.0).sqrt()).abs() < TIGHT);
}

#[test]
fn ideal_sensor_gives_sqrt_n() {
    // paper SI eq. S9: SNR = √N. Exact for perfect squares (N/√N with √N exact) …
    for (n, root) in [(1.0, 1.0), (1024.0, 32.0), (1e6, 1e3), (2.25e8, 1.5e4)] {
        assert_eq!(budget(&Sensor::ideal(), n, 0.0, 1.0).unwrap().snr, root);
    }
    // … and to rounding otherwise
    for n in [2.0, 1000.0, 12_345.678, 3.3e9] {
        let snr = budget(&Sensor::ideal(), n, 0.0, 1.0).unwrap().snr;
        assert!((snr / n.sqrt() - 1.0).abs() <= ULPS, "N = {n}: {snr}");
    }
}

#[test]
fn ideal_sensor_with_glare_background_is_s14() {
    // paper SI eq. S14 with S_N = S·T/τ1, i.e. background = (T/τ1 − 1)·S.
    // τ1 = 0.25, T = 0.75: background 2S, S_N = 3S exactly, so bit for bit
    for s in [1.0, 1000.0, 4321.5] {
        let b = budget(&Sensor::ideal(), s, (0.75 / 0.25 - 1.0) * s, 0.0).unwrap();
        assert_eq!(b.snr, snr_with_glare(s, 3.0 * s));
    }
    // the paper's τ1 = 0.15, T = 0.55: S = 1000, S_N = 3666.67, SNR = 16.514 (glare tests in lib)
    let s = 1000.0;
    let b = budget(&Sensor::ideal(), s, (0.55 / 0.15 - 1.0) * s, 0.0).unwrap();
    assert!((b.snr / snr_with_glare(s, s * 0.55 / 0.15) - 1.0).abs() <= ULPS);
    assert!((b.snr - 16.514).abs() < 1e-3);
}

#[test]
fn full_well_clips_the_signal_and_says_so() {
    // well 10 000 e⁻ (16-bit ADC at K = 0.5: 131 070 e⁻, not limiting), dark 10 e⁻, signal 12 000:
    // collected 12 010 > 10 000 → dark 10, signal 9990; total 9990 + 10 + 25 + 1/3 = 10 025.333,
    // SNR = 9990/√10 025.333 = 99.7734
    let sensor = Sensor::new(5.0, 100.0, 10_000.0, 0.5, 16).unwrap();
    let b = budget(&sensor, 12_000.0, 0.0, 0.1).unwrap();
    assert!(b.saturated);
    assert_eq!((b.unclipped_signal_e, b.saturation_e), (12_000.0, 10_000.0));
    assert!((b.signal_e - 9990.0).abs() < TIGHT && (b.dark_e - 10.0).abs() < TIGHT);
    assert!((b.signal_e + b.background_e + b.dark_e - 10_000.0).abs() < TIGHT);
    assert!((b.snr - 9990.0 / (10_025.0f64 + 1.0 / 3.0).sqrt()).abs() < TIGHT, "{}", b.snr);
    assert!(b.snr < 10_000f64.sqrt()); // EMVA SNR_max = √μ_e.sat = 100
    // exactly full: not saturated
    assert!(!budget(&sensor, 9990.0, 0.0, 0.1).unwrap().saturated);
}

#[test]
fn background_alone_can_fill_the_well() {
    // glare 20 000 e⁻ in a 10 000 e⁻ well: the black level saturates, no signal is left (eq. 2)
    let sensor = Sensor::without_adc(3.0, 0.0, 10_000.0).unwrap();
    let b = budget(&sensor, 1000.0, 20_000.0, 1.0).unwrap();
    assert!(b.saturated);
    assert_eq!((b.signal_e, b.background_e, b.snr), (0.0, 10_000.0, 0.0));
}

#[test]
fn adc_range_clips_before_the_well() {
    // 8 bits, K = 0.1 DN/e⁻: 255 DN = 2550 e⁻ < 10 000 e⁻ well; 3000 e⁻ of signal → 2550
    let sensor = Sensor::new(0.0, 0.0, 10_000.0, 0.1, 8).unwrap();
    let b = budget(&sensor, 3000.0, 0.0, 0.0).unwrap();
    assert!(b.saturated);
    assert!((b.signal_e - 2550.0).abs() < TIGHT);
}

#[test]
fn sensor_errors_name_parameter_value_and_range() {
    let err = Sensor::new(-1.0, 0.0, 1e4, 0.5, 12).unwrap_err();
    assert_eq!(err.to_string(), "read_noise must be finite and >= 0 e⁻ rms, got -1.0");
    let err = Sensor::new(1.0, 0.0, 1e4, 0.5, 40).unwrap_err();
    assert_eq!(err.to_string(), "adc_bits must be an integer from 1 to 32 bits, got 40.0");
    let err = Sensor::without_adc(1.0, 0.0, -5.0).unwrap_err();
    assert_eq!(err.to_string(), "full_well must be > 0 e⁻ (inf for no limit), got -5.0");
    assert!(Sensor::without_adc(1.0, 0.0, f64::INFINITY).is_ok());
}

// ---------------------------------------------------------------------------------------------
// Measured SNR (paper eq. 2–4)

#[test]
fn measured_snr_recovers_a_known_snr() {
    // black 20 DN, σ_b = 3; white 120 DN, σ_w = 5 → signal 100, σ_s = √(25 − 9) = 4: SNR = 25,
    // glare-inclusive 100/5 = 20, without bias (variances averaged). The stated standard errors
    // by hand, 300 pixels a region: δσ²_w = 25 √(2/(29·300)) = 0.379, δσ²_b = 0.137, so
    // δD/D = 0.403/16 = 2.52 %, δSNR/SNR = 1.26 %: 0.315 of 25; glare: 0.76 %, 0.152 of 20.
    // Tolerance: 4 stated errors, at 2, 5 and 30 frames (the mean σ read 27 %, 7 % and 0.9 %
    // high at these).
    let mut normal = Normal::new(0x5EED_2024);
    for frames in [2, 5, 30] {
        let white = stack(&mut normal, 300, frames, 120.0, 5.0);
        let black = stack(&mut normal, 300, frames, 20.0, 3.0);
        let m: MeasuredSnr = measured_snr_regions(&white, &black).unwrap();
        assert_eq!((m.frames, m.white_pixels, m.black_pixels), (frames, 300, 300));
        let expected =
            25.0 * (2.0 / ((frames - 1) as f64 * 300.0)).sqrt() * (25.0f64.powi(2) + 9.0f64.powi(2)).sqrt() / 32.0;
        assert!((m.snr_sigma / expected - 1.0).abs() < 0.5, "{frames}: {} vs {expected}", m.snr_sigma);
        assert!((m.snr - 25.0).abs() < 4.0 * m.snr_sigma, "{frames}: {} ± {}", m.snr, m.snr_sigma);
        assert!((m.snr_with_glare - 20.0).abs() < 4.0 * m.snr_with_glare_sigma, "{frames}: {}", m.snr_with_glare);
    }
}

#[test]
fn measured_snr_of_a_single_pixel_matches_the_region_form() {
    let mut normal = Normal::new(7);
    let white = stack(&mut normal, 1, 30, 200.0, 15.0);
    let black = stack(&mut normal, 1, 30, 40.0, 4.0);
    assert_eq!(measured_snr(&white[0], &black[0]).unwrap(), measured_snr_regions(&white, &black).unwrap());
}

#[test]
fn measured_snr_errors() {
    let two = [vec![1.0, 2.0], vec![3.0, 5.0]];
    let empty: [Vec<f64>; 0] = [];
    assert_eq!(measured_snr(&[5.0], &[1.0]), Err(Error::TooFewFrames { region: "white", pixel: 0, frames: 1 }));
    assert_eq!(measured_snr_regions(&empty, &two), Err(Error::EmptyRegion { region: "white" }));
    assert_eq!(measured_snr_regions(&two, &empty), Err(Error::EmptyRegion { region: "black" }));
    assert_eq!(
        measured_snr_regions(&two, &[vec![0.0, 1.0, 2.0]]),
        Err(Error::StackMismatch { region: "black", pixel: 0, frames: 3, expected: 2 })
    );
    assert!(matches!(
        measured_snr(&[10.0, f64::NAN], &[0.0, 1.0]),
        Err(Error::NonFiniteFrame { region: "white", pixel: 0, frame: 1, value }) if value.is_nan()
    ));
    // σ_w = σ_b: eq. 3 gives no signal noise
    let err = measured_snr(&[10.0, 12.0, 14.0], &[0.0, 2.0, 4.0]).unwrap_err();
    assert_eq!(err, Error::NoSignalNoise { white_variance: 4.0, black_variance: 4.0 });
    assert_eq!(
        err.to_string(),
        "the white variance must exceed the black variance (paper eq. 3), got σ_w² = 4.0 and σ_b² = 4.0"
    );
    // swapped regions: no signal (eq. 2)
    assert_eq!(measured_snr(&[0.0, 2.0], &[10.0, 14.0]), Err(Error::NoSignal { white: 1.0, black: 12.0 }));
}

// ---------------------------------------------------------------------------------------------
// Camera characterization (paper SI; EMVA 1288 §6.4)

#[test]
fn photon_transfer_recovers_the_gain_from_simulated_frames() {
    // K = 0.25 DN/e⁻, dark noise σ_d = 10 e⁻, offset 50 DN, output rounded to whole DN (σ_q² =
    // 1/12 DN², in the dark variance too, so it cancels). Levels μ_e = 1000·i e⁻, i = 1..10, and a
    // dark level; 4000 samples each, Gaussian shot noise (Poisson at μ ≥ 1000).
    // Spread: each sample variance has relative sd √(2/3999) = 2.2 %; the through-origin slope
    // weights them by x², giving sd(K)/K ≈ 2.2 % · √(Σi⁴)/Σi² = 2.2 % · 0.413 = 0.93 %. Tolerance
    // 4 sd ≈ 4 %.
    let (k, sigma_d, offset, samples) = (0.25, 10.0, 50.0, 4000);
    let mut normal = Normal::new(1288);
    let mut level = |mu_e: f64| {
        let y: Vec<f64> = (0..samples)
            .map(|_| (offset + k * (mu_e + mu_e.sqrt() * normal.sample() + sigma_d * normal.sample())).round())
            .collect();
        let mean = y.iter().sum::<f64>() / samples as f64;
        let var = y.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (samples - 1) as f64;
        (mean, var)
    };
    let (dark_mean, dark_var) = level(0.0);
    let (means, vars): (Vec<f64>, Vec<f64>) = (1..=10).map(|i| level(1000.0 * f64::from(i))).unzip();
    let fitted = photon_transfer_gain(&means, &vars, dark_mean, dark_var).unwrap();
    assert!((fitted / k - 1.0).abs() < 0.04, "K = {fitted}");
}

#[test]
fn transfer_curve_slopes() {
    // Model camera (EMVA 1288 §2.2): μ_y − μ_dark = K μ_e, σ_y² = K²(σ_d² + μ_e) + 1/12 DN²,
    // K = 0.25, σ_d = 20 e⁻, μ_e = 100 · 2^i e⁻, i = 0..9.
    let (k, sigma_d) = (0.25, 20.0);
    let input: Vec<f64> = (0..10).map(|i| 100.0 * f64::from(1 << i)).collect();
    let signal: Vec<f64> = input.iter().map(|e| k * e).collect();
    let var: Vec<f64> = input.iter().map(|e| k * k * (sigma_d * sigma_d + e) + 1.0 / 12.0).collect();
    let dark_var = k * k * sigma_d * sigma_d + 1.0 / 12.0;
    // signal transfer: exactly linear, slope 1
    assert!((log_slope(&input, &signal).unwrap() - 1.0).abs() < TIGHT);
    // photon transfer, dark noise included: flattened below 0.5 at low signal (paper Fig. S7b)
    let noise: Vec<f64> = var.iter().map(|v| v.sqrt()).collect();
    let raw = log_slope(&signal, &noise).unwrap();
    assert!(raw > 0.3 && raw < 0.45, "{raw}");
    // capped black subtracted (Fig. S8b): √(σ_y² − σ_dark²) = K√μ_e, slope 0.5
    let shot: Vec<f64> = var.iter().map(|v| (v - dark_var).sqrt()).collect();
    assert!((log_slope(&signal, &shot).unwrap() - 0.5).abs() < 1e-10);
}

#[test]
fn characterization_errors() {
    assert_eq!(
        photon_transfer_gain(&[1.0, 2.0], &[1.0], 0.0, 0.0),
        Err(Error::LengthMismatch { first: "mean_dn", first_len: 2, second: "var_dn", second_len: 1 })
    );
    assert_eq!(
        photon_transfer_gain(&[], &[], 0.0, 0.0),
        Err(Error::TooFewPoints { fit: "photon_transfer_gain", needed: 1, count: 0 })
    );
    assert!(matches!(photon_transfer_gain(&[5.0, 5.0], &[1.0, 2.0], 5.0, 0.5), Err(Error::DegenerateFit { .. })));
    // variance falling with the mean: K < 0 is refused
    assert!(matches!(photon_transfer_gain(&[10.0, 20.0], &[1.0, 1.0], 0.0, 3.0), Err(Error::DegenerateFit { .. })));
    assert_eq!(log_slope(&[1.0], &[1.0]), Err(Error::TooFewPoints { fit: "log_slope", needed: 2, count: 1 }));
    let err = log_slope(&[1.0, 0.0], &[1.0, 2.0]).unwrap_err();
    assert_eq!(err.to_string(), "x[1] must be finite and > 0 (its logarithm is taken), got 0.0");
    assert!(matches!(log_slope(&[3.0, 3.0], &[1.0, 2.0]), Err(Error::DegenerateFit { .. })));
}

// ---------------------------------------------------------------------------------------------
// Properties on physical ranges

fn config() -> Config {
    Config { cases: 96, rng_seed: RngSeed::Fixed(2024_0604), failure_persistence: None, ..Config::default() }
}

proptest! {
    #![proptest_config(config())]

    /// Shot-noise limit (paper SI eq. S9): the signal grows as t, the SNR as √t.
    #[test]
    fn snr_grows_as_sqrt_t_in_the_shot_noise_limit(rate in 1e2..1e8f64, t in 1e-4..1.0f64, factor in 1.0..100.0f64) {
        let short = budget(&Sensor::ideal(), rate * t, 0.0, t).unwrap().snr;
        let long = budget(&Sensor::ideal(), rate * t * factor, 0.0, t * factor).unwrap().snr;
        prop_assert!((long / short / factor.sqrt() - 1.0).abs() < 1e-12, "{short} {long}");
    }

    /// Any camera, any background: SNR ≤ √N (shot noise alone) and ≤ √μ_e.sat (EMVA SNR_max),
    /// finite and ≥ 0; it equals the ideal only when nothing else adds noise.
    #[test]
    fn snr_never_exceeds_sqrt_n(
        read in 0.0..30.0f64, dark in 0.0..1e3f64, well in 1e3..1e6f64, gain in 0.01..10.0f64,
        bits in 8u32..17, signal in 0.0..2e6f64, background in 0.0..1e6f64, t in 0.0..1.0f64,
    ) {
        let sensor = Sensor::new(read, dark, well, gain, bits).unwrap();
        let b = budget(&sensor, signal, background, t).unwrap();
        prop_assert!(b.snr.is_finite() && b.snr >= 0.0);
        prop_assert!(b.snr <= signal.sqrt() * (1.0 + ULPS), "{} > √{signal}", b.snr);
        prop_assert!(b.snr <= sensor.saturation_e().sqrt() * (1.0 + ULPS));
        prop_assert!(b.signal_e + b.background_e + b.dark_e <= sensor.saturation_e() * (1.0 + ULPS));
        if !b.saturated {
            prop_assert_eq!((b.signal_e, b.background_e), (signal, background));
        }
        let ideal = budget(&Sensor::ideal(), signal, 0.0, t).unwrap().snr;
        prop_assert!(b.snr <= ideal * (1.0 + ULPS));
    }
}

// ---------------------------------------------------------------------------------------------
// Robustness: no panic, no non-finite number

#[test]
fn budget_refuses_bad_inputs_and_overflow_instead_of_panicking() {
    // a negative or infinite charge is an error naming it, not a panic
    for (signal, background, t, name) in
        [(-1.0, 0.0, 1.0, "signal"), (f64::INFINITY, 0.0, 1.0, "signal"), (1.0, f64::NAN, 1.0, "background")]
    {
        match budget(&Sensor::ideal(), signal, background, t) {
            Err(Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: expected InvalidParameter, got {other:?}"),
        }
    }
    // dark current × exposure beyond f64::MAX, and variances whose sum overflows
    let dark = Sensor::without_adc(0.0, 1e300, f64::INFINITY).unwrap();
    let err = budget(&dark, 1.0, 0.0, 1e10).unwrap_err();
    assert!(err.to_string().contains("dark charge overflows"), "{err}");
    let err = budget(&Sensor::ideal(), 1.5e308, 1.5e308, 1.0).unwrap_err();
    assert!(err.to_string().contains("total noise variance overflows"), "{err}");
}

#[test]
fn sensor_refuses_noise_whose_variance_is_not_finite() {
    // σ_r = 1e200 e⁻: σ_r² = inf; K = 1e-200 DN/e⁻: (1/12)/K² = inf
    let err = Sensor::without_adc(1e200, 0.0, 1e4).unwrap_err();
    assert!(err.to_string().contains("read_noise must be below 1.3e154 e⁻ rms"), "{err}");
    let err = Sensor::new(1.0, 0.0, 1e4, 1e-200, 12).unwrap_err();
    assert!(err.to_string().starts_with("gain must be at least"), "{err}");
}

proptest! {
    #![proptest_config(Config { cases: 64, ..config() })]

    /// Over decades of every input: a sensor and a budget are either refused or entirely finite.
    #[test]
    fn budgets_are_finite_or_refused(
        read_exp in -3.0..200.0f64, dark_exp in -3.0..300.0f64, well_exp in 0.0..300.0f64,
        gain_exp in -200.0..200.0f64, bits in 1u32..33, signal_exp in -300.0..308.0f64,
        background_exp in -300.0..308.0f64, t_exp in -300.0..300.0f64,
    ) {
        let p = |e: f64| 10f64.powf(e);
        let Ok(sensor) = Sensor::new(p(read_exp), p(dark_exp), p(well_exp), p(gain_exp), bits) else {
            return Ok(());
        };
        if let Ok(b) = budget(&sensor, p(signal_exp), p(background_exp), p(t_exp)) {
            for v in [b.signal_e, b.background_e, b.dark_e, b.shot_variance_e2, b.dark_variance_e2,
                      b.read_variance_e2, b.quantization_variance_e2, b.total_variance_e2, b.snr] {
                prop_assert!(v.is_finite() && v >= 0.0, "{b:?}");
            }
        }
    }
}
