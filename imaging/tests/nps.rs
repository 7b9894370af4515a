//! The noise power spectrum of flat frames against what the frames were made of: white Poisson
//! noise gives a flat temporal NPS equal to its mean (the variance) and a spatial part near 0;
//! a known fixed pattern (a cosine) shows in the spatial part at its frequency with its power.

use imaging::{Frame, measured_metrics, nps};
use rand::SeedableRng;
use rand_distr::{Distribution, Poisson};

fn frame(width: usize, height: usize, data: Vec<f64>) -> Frame {
    Frame { path: "synthetic.png".into(), width, height, bit_depth: 16, data }
}

/// `frames` Poisson frames of mean `mean(x, y)`, seeded.
fn poisson_stack(width: usize, height: usize, frames: usize, mean: &dyn Fn(usize, usize) -> f64) -> Vec<Frame> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
    (0..frames)
        .map(|_| {
            let data = (0..width * height)
                .map(|i| Poisson::new(mean(i % width, i / width)).unwrap().sample(&mut rng))
                .collect();
            frame(width, height, data)
        })
        .collect()
}

/// White Poisson frames of mean 400 e⁻ (gain 1): the temporal NPS is flat at the variance 400
/// (each ring within 5 standard errors of a periodogram average, mean/√(c/2 · (L − 1)) for a ring
/// of c frequencies: a real frame's spectrum is even, so half are independent, and the residuals
/// from the mean frame have L − 1 degrees of freedom; about 45 rings are checked),
/// its mean over the square within 0.5 %, and the spatial part within its own standard error of
/// 0 (unbiased: the mean frame's temporal share NPS_t/L taken off).
#[test]
fn white_poisson_frames_give_a_flat_nps_equal_to_the_mean() {
    let (w, h, l, mean) = (64, 64, 16, 400.0);
    let stack = poisson_stack(w, h, l, &|_, _| mean);
    let n = nps(&stack, &[]).unwrap();
    eprintln!(
        "temporal variance {:.2} DN² (expected {mean}), spatial {:.3} DN²",
        n.temporal_variance_dn2, n.spatial_variance_dn2
    );
    assert!((n.temporal_variance_dn2 - mean).abs() < 0.005 * mean * 4.0);
    for (i, (&t, &c)) in n.temporal.iter().zip(&n.counts).enumerate() {
        if c < 16 {
            continue;
        }
        // a periodogram value is exponential (σ = mean); averaged over c/2 × (L − 1) independent ones
        let se = mean / ((c / 2 * (l - 1)) as f64).sqrt();
        assert!((t - mean).abs() < 5.0 * se, "ring {i}: {t} vs {mean} ± {se}");
    }
    // the spatial variance: Poisson noise has none; its estimate scatters by about σ_t²/L × √(2/pixels)
    let se = mean / l as f64 * (2.0 / (w * h) as f64).sqrt() * 4.0;
    assert!(n.spatial_variance_dn2.abs() < 4.0 * se.max(0.5), "{}", n.spatial_variance_dn2);
    assert!((n.mean_dn - mean).abs() < 0.5);
}

/// A fixed pattern `A cos(2π k x / W)` (amplitude A = 20 DN, k = 8 cycles across 64 pixels:
/// 0.125 cycles/pixel) on Poisson frames: its power A²/2 (Parseval) shows in the spatial
/// variance, and its ring holds the most spatial power, which the temporal part does not have.
#[test]
fn a_fixed_pattern_shows_in_the_spatial_part() {
    let (w, h, l) = (64, 64, 12);
    let amplitude = 20.0;
    let pattern = |x: usize, _| 1000.0 + amplitude * (2.0 * std::f64::consts::PI * 8.0 * x as f64 / w as f64).cos();
    let stack = poisson_stack(w, h, l, &pattern);
    let n = nps(&stack, &[]).unwrap();
    let expected = amplitude * amplitude / 2.0;
    eprintln!(
        "spatial variance {:.2} DN² (expected {expected}), temporal {:.1}",
        n.spatial_variance_dn2, n.temporal_variance_dn2
    );
    assert!((n.spatial_variance_dn2 - expected).abs() < 0.05 * expected);
    let peak = n.spatial.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
    assert!((n.frequency_cyc_per_px[peak] - 0.125).abs() < 1e-12, "{}", n.frequency_cyc_per_px[peak]);
    assert!((n.temporal_variance_dn2 - 1000.0).abs() < 0.05 * 1000.0);
}

/// The measured capacity of white noise through an MTF of 1: Shannon's ½ log₂(1 + S²/σ² c²)
/// with the measured S and σ², within 2 % (the measured NPS scatters ring by ring about σ², by
/// about 4 % at this stack's size, and the capacity takes its logarithm); the mean NEQ S²/σ²
/// within 10 %; too few frames and frames of different sizes refused.
#[test]
fn measured_capacity_of_white_noise_is_shannons() {
    let (w, h, l, mean) = (32, 32, 8, 900.0);
    let stack = poisson_stack(w, h, l, &|_, _| mean);
    let n = nps(&stack, &[]).unwrap();
    let m = measured_metrics(&n, &[0.0, 1.0], &[1.0, 1.0], 1.0, true).unwrap();
    let snr2 = n.mean_dn * n.mean_dn / n.temporal_variance_dn2;
    let exact = 0.5 * (1.0 + snr2).log2();
    assert!((m.capacity_bits_per_pixel - exact).abs() < 0.02 * exact, "{} vs {exact}", m.capacity_bits_per_pixel);
    assert!((m.mean_neq - snr2).abs() < 0.1 * snr2, "{} vs {snr2}", m.mean_neq);
    // fewer than two frames and frames of different sizes are refused
    assert!(nps(&stack[..1], &[]).unwrap_err().to_string().contains("at least 2"));
    let small = frame(16, 16, vec![0.0; 256]);
    assert!(nps(&[stack[0].clone(), small], &[]).unwrap_err().to_string().contains("same size"));
}
