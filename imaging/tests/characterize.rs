//! `imaging::characterize` on a series made by an EMVA 1288 camera simulated here (independent of
//! the project's sensor model): electrons Gaussian with variance = mean (shot noise), read noise,
//! conversion gain K, a dark offset, 1-DN quantization and clipping at the full well. K, the read
//! noise, the slopes (STF 1, PTC 0.5 with the capped black subtracted) and the saturation point
//! are recovered within the stated tolerances.

use imaging::{Frame, Region, characterize, fit_line, level_of};

/// Standard normal deviates from the project's one generator family (PCG-64 MCG, seeded;
/// rand_distr's standard normal); the camera model around them is written here.
struct Normal(rand_pcg::Pcg64Mcg);

impl Normal {
    fn new(seed: u64) -> Normal {
        Normal(rand::SeedableRng::seed_from_u64(seed))
    }
    fn sample(&mut self) -> f64 {
        rand_distr::Distribution::sample(&rand_distr::StandardNormal, &mut self.0)
    }
}

const K: f64 = 0.4; // DN per electron
const OFFSET: f64 = 100.0; // DN
const READ_E: f64 = 6.0; // electrons rms
const FULL_WELL_E: f64 = 9000.0;
const SIDE: usize = 24;

/// Eight frames of SIDE × SIDE pixels at `electrons` mean signal per pixel.
fn stack(electrons: f64, normal: &mut Normal) -> Vec<Frame> {
    (0..8)
        .map(|_| {
            let data = (0..SIDE * SIDE)
                .map(|_| {
                    let e = (electrons + electrons.sqrt() * normal.sample()).min(FULL_WELL_E);
                    let dn = OFFSET + K * (e + READ_E * normal.sample());
                    dn.round().clamp(0.0, 4095.0)
                })
                .collect();
            Frame { path: "synthetic".into(), width: SIDE, height: SIDE, bit_depth: 16, data }
        })
        .collect()
}

#[test]
fn recovers_gain_read_noise_slopes_and_saturation() {
    let mut normal = Normal::new(0x5851_f42d_4c95_7f2d);
    let region = Region::parse("characterization", &format!("0,0,{SIDE},{SIDE}")).unwrap();
    let dark = level_of(&stack(0.0, &mut normal), region, 0.0).unwrap();
    // illumination in photons per pixel, quantum efficiency 0.5: 20 … 30 000 electrons
    let levels: Vec<_> = (0..17)
        .map(|k| {
            let electrons = 20.0 * 1.6f64.powi(k);
            level_of(&stack(electrons, &mut normal), region, electrons / 0.5).unwrap()
        })
        .collect();
    let c = characterize(dark, &levels).unwrap();
    assert!((c.conversion_gain / K - 1.0).abs() < 0.03, "K = {} ± {}", c.conversion_gain, c.conversion_gain_sigma);
    assert!(c.conversion_gain_sigma > 0.0 && c.conversion_gain_sigma < 0.02 * K, "{}", c.conversion_gain_sigma);
    // σ_dark² = (K σ_read)² + 1/12 (quantization, subtracted as EMVA 1288 does): 6 e⁻
    assert!((c.read_noise_e / READ_E - 1.0).abs() < 0.05, "read noise {} e", c.read_noise_e);
    assert!((c.stf.slope - 1.0).abs() < 0.01, "{:?}", c.stf);
    assert!((c.ptc.slope - 0.5).abs() < 0.02, "{:?}", c.ptc);
    // without the capped black subtracted, its 100 DN offset bends the STF below slope 1
    assert!(c.stf_raw.slope < 0.95 && c.ptc_raw.points == c.ptc.points, "{:?} vs {:?}", c.stf_raw, c.stf);
    // the largest variance is the last level below the full well (20 · 1.6^9 = 5498 e⁻ … 8796 e⁻ at k = 10)
    let sat_e = 20.0 * 1.6f64.powi(c.saturation as i32);
    assert!((5000.0..FULL_WELL_E).contains(&sat_e), "saturation at level {} ({sat_e} e⁻)", c.saturation);
    assert!(c.stf.points >= 8, "{:?}", c.stf);
    // `fitted` names the levels the fits used: as many as each fit counts, none at or past saturation
    assert_eq!(c.fitted.len(), levels.len());
    assert_eq!(c.fitted.iter().filter(|&&f| f).count(), c.stf.points);
    assert!(c.fitted[c.saturation..].iter().all(|&f| !f), "{:?}", c.fitted);
}

#[test]
fn line_fit_and_its_errors() {
    // exact line: zero residual, zero standard errors
    let f = fit_line(&[1.0, 2.0, 3.0, 4.0], &[3.0, 5.0, 7.0, 9.0]).unwrap();
    assert!((f.slope - 2.0).abs() < 1e-12 && (f.intercept - 1.0).abs() < 1e-12 && f.slope_sigma < 1e-12);
    // by hand: x̄ = ȳ = 1.5, Sxy = 3, Sxx = 5: slope 0.6, intercept 1.5 − 0.6 · 1.5 = 0.6
    let f = fit_line(&[0.0, 1.0, 2.0, 3.0], &[1.0, 0.0, 3.0, 2.0]).unwrap();
    assert!((f.slope - 0.6).abs() < 1e-12 && (f.intercept - 0.6).abs() < 1e-12, "{f:?}");
    // residuals 0.4, −1.2, 1.2, −0.4: s² = 3.2/2, σ_slope = √(s²/Sxx) = √(1.6/5)
    assert!((f.slope_sigma - (1.6f64 / 5.0).sqrt()).abs() < 1e-12, "{f:?}");
    assert!(fit_line(&[1.0], &[1.0]).is_none());
    assert!(fit_line(&[2.0, 2.0, 2.0], &[1.0, 2.0, 3.0]).is_none());
    // too few usable levels: a clear error
    let region = Region::parse("characterization", "0,0,2,2").unwrap();
    let frame = |v: f64| Frame { path: "x".into(), width: 2, height: 2, bit_depth: 8, data: vec![v; 4] };
    let e = level_of(&[frame(1.0)], region, 1.0).unwrap_err();
    assert!(e.to_string().contains("1 frame(s)"), "{e}");
    let dark = level_of(&[frame(1.0), frame(2.0)], region, 0.0).unwrap();
    let e = characterize(dark, &[dark]).unwrap_err();
    assert!(e.to_string().contains("positive"), "{e}");
}

/// A series of render's sensor model (`imaging::render::expose`): a dark stack and 8 levels of
/// 100 · 1.8^k photoelectrons, 6 frames of 32 × 32 pixels each, every stack its own seeds.
fn rendered_series(sensor: &noise::Sensor, seed: u64) -> (imaging::Level, Vec<imaging::Level>) {
    let region = Region { x: 0, y: 0, width: 32, height: 32 };
    let stack = |electrons: f64, stack_seed: u64| -> Vec<Frame> {
        (0..6)
            .map(|k| Frame {
                path: "rendered".into(),
                width: 32,
                height: 32,
                bit_depth: 16,
                data: imaging::render::expose(&[electrons; 32 * 32], sensor, stack_seed * 64 + k).unwrap(),
            })
            .collect()
    };
    let dark = level_of(&stack(0.0, seed * 100), region, 0.0).unwrap();
    let levels = (0..8)
        .map(|k| {
            let electrons = 100.0 * 1.8f64.powi(k);
            level_of(&stack(electrons, seed * 100 + 1 + k as u64), region, electrons).unwrap()
        })
        .collect();
    (dark, levels)
}

/// On render's frames of a camera with a black level (σ_r = 5 e⁻, K = 0.5 DN/e⁻, 100 DN offset)
/// the read noise is recovered within 3 of its stated errors (and 5 %); without the black level
/// the dark noise is clipped at 0 DN, the read noise reads low and a warning says why.
#[test]
fn recovers_the_read_noise_of_rendered_frames_and_warns_on_clipped_darks() {
    let camera = noise::Sensor::new(5.0, 0.0, f64::INFINITY, 0.5, 12).unwrap();
    let (dark, levels) = rendered_series(&camera.with_black_level(100.0).unwrap(), 1);
    let c = characterize(dark, &levels).unwrap();
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    assert!((c.read_noise_e - 5.0).abs() < 3.0 * c.read_noise_sigma_e, "{} ± {}", c.read_noise_e, c.read_noise_sigma_e);
    assert!((c.read_noise_e / 5.0 - 1.0).abs() < 0.05, "{}", c.read_noise_e);
    assert!(
        (c.conversion_gain - 0.5).abs() < 3.0 * c.conversion_gain_sigma,
        "{} ± {}",
        c.conversion_gain,
        c.conversion_gain_sigma
    );
    let (dark, levels) = rendered_series(&camera, 1);
    let c = characterize(dark, &levels).unwrap();
    assert!(c.read_noise_e < 4.0, "{}", c.read_noise_e);
    assert!(
        c.warnings.len() == 1 && c.warnings[0].contains("read 0 DN") && c.warnings[0].contains("black level"),
        "{:?}",
        c.warnings
    );
}

/// The stated error of K is the scatter of K over 30 independent series (render's sensor model):
/// their ratio is 1 within 0.65–1.5 (its own sampling error is 1/√58 = 13 %).
#[test]
fn the_stated_gain_error_matches_the_scatter_over_repeated_series() {
    let camera = noise::Sensor::new(5.0, 0.0, f64::INFINITY, 0.5, 12).unwrap().with_black_level(100.0).unwrap();
    let runs: Vec<(f64, f64)> = (0..30)
        .map(|seed| {
            let (dark, levels) = rendered_series(&camera, 10 + seed);
            let c = characterize(dark, &levels).unwrap();
            (c.conversion_gain, c.conversion_gain_sigma)
        })
        .collect();
    let count = runs.len() as f64;
    let mean = runs.iter().map(|r| r.0).sum::<f64>() / count;
    let scatter = (runs.iter().map(|r| (r.0 - mean).powi(2)).sum::<f64>() / (count - 1.0)).sqrt();
    let stated = runs.iter().map(|r| r.1).sum::<f64>() / count;
    assert!((0.65..1.5).contains(&(scatter / stated)), "K scatter {scatter:e} vs stated {stated:e} (mean K {mean})");
    assert!((mean - 0.5).abs() < 3.0 * scatter / count.sqrt(), "{mean}");
}

/// Decreasing illumination, a level of another frame size: refused with the level named.
#[test]
fn decreasing_illumination_and_mixed_sizes_are_refused() {
    let camera = noise::Sensor::new(5.0, 0.0, f64::INFINITY, 0.5, 12).unwrap().with_black_level(100.0).unwrap();
    let (dark, mut levels) = rendered_series(&camera, 2);
    let mut reversed = levels.clone();
    let illuminations: Vec<f64> = reversed.iter().map(|l| l.illumination).rev().collect();
    for (l, i) in reversed.iter_mut().zip(illuminations) {
        l.illumination = i;
    }
    let e = characterize(dark, &reversed).unwrap_err();
    assert!(e.to_string().contains("levels[1]: illumination") && e.to_string().contains("increasing"), "{e}");
    levels[3].width = 31;
    let e = characterize(dark, &levels).unwrap_err();
    assert!(e.to_string().contains("levels[3]: frames of 31 × 32 pixels, but the dark frames are 32 × 32"), "{e}");
}
