//! The noise power spectrum (NPS) of a stack of flat-field frames, separated as EMVA 1288
//! (Release 4.0 Linear, §8) separates the variances: a temporal part, from each frame's
//! difference to the stack's mean frame, and a spatial part (the fixed pattern, DSNU/PRNU), from
//! the mean frame with the temporal part's share `NPS_t/L` taken off. Both are unbiased:
//!
//! - `NPS_t(ν) = L/(L − 1) · (1/L) Σ_l |DFT(y_l − ȳ)|² / (M N)` (the residuals from the mean of
//!   `L` frames carry `(L − 1)/L` of the temporal variance);
//! - `NPS_s(ν) = |DFT(ȳ − ⟨ȳ⟩)|² / (M N) − NPS_t(ν)/L` (the mean frame keeps `1/L` of the
//!   temporal noise).
//!
//! Normalization: `|DFT|²/(M N)` of an `M × N` frame, frequencies in cycles/pixel, so that white
//! noise of variance σ² (DN²) has the flat NPS σ² (DN² pixel²) and the NPS's mean over the
//! Nyquist square is the variance (Parseval). No window: flat frames have no edges to leak; a
//! gradient of the illumination across the frame shows in the spatial part's lowest bins (the
//! mean alone is taken off). The 2-D spectra are averaged over rings of width `1/min(M, N)`
//! cycles/pixel (the zero frequency left out), up to the square's corner.
//!
//! [`measured_metrics`] then forms the measured NEQ and information capacity from it and an MTF
//! (docs/physics.md, "The noise power spectrum of flat frames").

use std::sync::Arc;

use num_complex::Complex64;
use serde::Serialize;

use crate::{Error, Frame};

/// The NPS of a flat-field stack, radially averaged.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Nps {
    /// The frames' size, pixels.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Frames in the stack.
    pub frames: usize,
    /// Mean grey level of the stack, less the dark frame's mean where one was given, DN.
    pub mean_dn: f64,
    /// Temporal variance σ_t² (the NPS_t's mean over the square), DN².
    pub temporal_variance_dn2: f64,
    /// Spatial (fixed-pattern) variance σ_s², DN².
    pub spatial_variance_dn2: f64,
    /// Ring centres, cycles/pixel.
    pub frequency_cyc_per_px: Vec<f64>,
    /// Temporal NPS per ring, DN² pixel².
    pub temporal: Vec<f64>,
    /// Spatial NPS per ring, DN² pixel² (may be slightly negative where there is no fixed pattern:
    /// the estimate is unbiased, not clipped).
    pub spatial: Vec<f64>,
    /// The 2-D frequencies per ring, how many went into each.
    pub counts: Vec<usize>,
}

impl Nps {
    /// Temporal plus spatial NPS per ring: the noise of a single frame.
    pub fn total(&self) -> Vec<f64> {
        self.temporal.iter().zip(&self.spatial).map(|(t, s)| t + s).collect()
    }
}

/// `|DFT(x)|²/(M N)` of a `width × height` real image (row-major), by rows then columns.
fn power(width: usize, height: usize, data: &[f64], planner: &mut rustfft::FftPlanner<f64>) -> Vec<f64> {
    let rows: Arc<dyn rustfft::Fft<f64>> = planner.plan_fft_forward(width);
    let cols: Arc<dyn rustfft::Fft<f64>> = planner.plan_fft_forward(height);
    let mut grid: Vec<Complex64> = data.iter().map(|&v| Complex64::new(v, 0.0)).collect();
    for row in grid.chunks_mut(width) {
        rows.process(row);
    }
    let mut column = vec![Complex64::new(0.0, 0.0); height];
    for x in 0..width {
        for (y, c) in column.iter_mut().enumerate() {
            *c = grid[y * width + x];
        }
        cols.process(&mut column);
        for (y, c) in column.iter().enumerate() {
            grid[y * width + x] = *c;
        }
    }
    let n = (width * height) as f64;
    grid.iter().map(|c| c.norm_sqr() / n).collect()
}

/// The NPS of the flat frames `flats`, each less the mean of the `darks` where given (their
/// temporal noise then adds to the flats' as `1/L_dark` of its NPS; take many dark frames).
///
/// # Errors
/// [`Error::TooFewFrames`] for fewer than two flat frames, [`Error::SizeMismatch`] /
/// [`Error::DepthMismatch`] (via [`crate::frames::same_format`]) for frames of another size or
/// depth, [`Error::TooSmall`] for frames under 8 × 8 pixels.
pub fn nps(flats: &[Frame], darks: &[Frame]) -> Result<Nps, Error> {
    if flats.len() < 2 {
        return Err(Error::TooFewFrames { what: "flat frames", frames: flats.len() });
    }
    let first = &flats[0];
    for f in flats.iter().chain(darks) {
        crate::frames::same_format(first, f)?;
    }
    let (width, height) = (first.width, first.height);
    if width < 8 || height < 8 {
        return Err(Error::TooSmall { path: first.path.clone(), width, height, min: 8 });
    }
    let pixels = width * height;
    let dark: Vec<f64> = if darks.is_empty() {
        vec![0.0; pixels]
    } else {
        (0..pixels).map(|i| darks.iter().map(|d| d.data[i]).sum::<f64>() / darks.len() as f64).collect()
    };
    let l = flats.len() as f64;
    let mean_frame: Vec<f64> =
        (0..pixels).map(|i| flats.iter().map(|f| f.data[i]).sum::<f64>() / l - dark[i]).collect();
    let mean_dn = mean_frame.iter().sum::<f64>() / pixels as f64;
    let mut planner = rustfft::FftPlanner::new();
    let mut temporal = vec![0.0; pixels];
    for f in flats {
        let residual: Vec<f64> = (0..pixels).map(|i| f.data[i] - dark[i] - mean_frame[i]).collect();
        for (t, p) in temporal.iter_mut().zip(power(width, height, &residual, &mut planner)) {
            *t += p / (l - 1.0);
        }
    }
    let centred: Vec<f64> = mean_frame.iter().map(|v| v - mean_dn).collect();
    let spatial: Vec<f64> =
        power(width, height, &centred, &mut planner).iter().zip(&temporal).map(|(m, t)| m - t / l).collect();
    // the variances: the mean of each NPS over the square (Parseval), the zero frequency of the
    // spatial part aside (the mean was taken off: its DC bin holds only the −NPS_t/L share)
    let temporal_variance = temporal.iter().sum::<f64>() / pixels as f64;
    let spatial_variance = spatial.iter().skip(1).sum::<f64>() / pixels as f64;
    // rings of width 1/min(M, N) up to the corner √2/2
    let step = 1.0 / width.min(height) as f64;
    let rings = (std::f64::consts::FRAC_1_SQRT_2 / step).ceil() as usize + 1;
    let (mut t_sum, mut s_sum, mut counts) = (vec![0.0; rings], vec![0.0; rings], vec![0_usize; rings]);
    let signed = |k: usize, n: usize| if k <= n / 2 { k as f64 / n as f64 } else { k as f64 / n as f64 - 1.0 };
    for y in 0..height {
        for x in 0..width {
            if x == 0 && y == 0 {
                continue;
            }
            let nu = signed(x, width).hypot(signed(y, height));
            let ring = (nu / step).round() as usize;
            t_sum[ring] += temporal[y * width + x];
            s_sum[ring] += spatial[y * width + x];
            counts[ring] += 1;
        }
    }
    let keep: Vec<usize> = (0..rings).filter(|&r| counts[r] > 0).collect();
    Ok(Nps {
        width,
        height,
        frames: flats.len(),
        mean_dn,
        temporal_variance_dn2: temporal_variance,
        spatial_variance_dn2: spatial_variance,
        frequency_cyc_per_px: keep.iter().map(|&r| r as f64 * step).collect(),
        temporal: keep.iter().map(|&r| t_sum[r] / counts[r] as f64).collect(),
        spatial: keep.iter().map(|&r| s_sum[r] / counts[r] as f64).collect(),
        counts: keep.iter().map(|&r| counts[r]).collect(),
    })
}

/// The measured NEQ and information capacity from an NPS and an MTF.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeasuredMetrics {
    /// Frequencies of the NEQ, cycles/pixel (the NPS's rings up to Nyquist).
    pub frequency_cyc_per_px: Vec<f64>,
    /// `NEQ(ν) = S² MTF(ν)² / NPS(ν)`, equivalent quanta per pixel.
    pub neq: Vec<f64>,
    /// Its mean to Nyquist (the rings' values, trapezoidal in ν).
    pub mean_neq: f64,
    /// The SNR the capacity is referred to: `S/σ` with σ² the NPS's mean over the square.
    pub snr0: f64,
    /// The information capacity, bits per pixel, for a flat object of contrast `contrast`.
    pub capacity_bits_per_pixel: f64,
    /// Its estimated quadrature error, bits per pixel.
    pub capacity_error_bits: f64,
    /// The object's contrast.
    pub contrast: f64,
    /// Which NPS: `"total"` (temporal + spatial: one frame's noise) or `"temporal"`.
    pub noise: &'static str,
}

/// Linear interpolation of `(x, y)` (x increasing) at `t`, the end values held beyond.
fn interpolate(x: &[f64], y: &[f64], t: f64) -> f64 {
    match x.iter().position(|&v| v >= t) {
        Some(0) => y[0],
        Some(i) => y[i - 1] + (y[i] - y[i - 1]) * (t - x[i - 1]) / (x[i] - x[i - 1]),
        None => y[y.len() - 1],
    }
}

/// The measured NEQ and capacity: `NEQ(ν) = S² MTF(ν)²/NPS(ν)` with `S` the stack's mean level
/// (DN above the dark), the radially averaged NPS (`temporal_only`: its temporal part alone,
/// for a frame averaged over many exposures; otherwise temporal + spatial, one frame's noise),
/// and the MTF `mtf` at frequencies `frequency_cyc_per_px` (interpolated linearly, its last value
/// held beyond its end); the capacity over the Nyquist square by [`metric::square_metrics`]
/// (radial symmetry assumed of both) for a flat object of contrast `contrast`.
pub fn measured_metrics(
    nps: &Nps,
    frequency_cyc_per_px: &[f64],
    mtf: &[f64],
    contrast: f64,
    temporal_only: bool,
) -> Result<MeasuredMetrics, Error> {
    let noise: Vec<f64> = if temporal_only { nps.temporal.clone() } else { nps.total() };
    if let Some(i) = noise.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(Error::Measurement {
            message: format!(
                "the NPS is {:e} DN² at {:.4} cycles/pixel: a non-positive noise power (too few frames, or a stack without noise) leaves the NEQ undefined",
                noise[i], nps.frequency_cyc_per_px[i]
            ),
        });
    }
    let variance =
        if temporal_only { nps.temporal_variance_dn2 } else { nps.temporal_variance_dn2 + nps.spatial_variance_dn2 };
    let snr0 = nps.mean_dn / variance.sqrt();
    let nu = &nps.frequency_cyc_per_px;
    let m = |f: f64| interpolate(frequency_cyc_per_px, mtf, f);
    let n = |f: f64| interpolate(nu, &noise, f);
    let keep: Vec<usize> = (0..nu.len()).filter(|&i| nu[i] <= 0.5 + 1e-12).collect();
    let neq: Vec<f64> = keep.iter().map(|&i| nps.mean_dn.powi(2) * m(nu[i]).powi(2) / noise[i]).collect();
    let xs: Vec<f64> = keep.iter().map(|&i| nu[i]).collect();
    let mean_neq = xs.windows(2).zip(neq.windows(2)).map(|(x, y)| 0.5 * (x[1] - x[0]) * (y[0] + y[1])).sum::<f64>()
        / (xs[xs.len() - 1] - xs[0]).max(f64::MIN_POSITIVE);
    let options = metric::MetricsOptions { contrast, ..metric::MetricsOptions::default() };
    options.validate().map_err(|e| Error::Measurement { message: e.to_string() })?;
    let relative = |f: f64| n(f) / variance;
    let square = metric::square_metrics(
        &|f, _| m(f),
        Some(&relative),
        snr0,
        1.0,
        &options,
        metric::Quadrature { symmetry: metric::Symmetry::Radial, cutoff: f64::INFINITY, tolerance: 1e-6 },
    );
    Ok(MeasuredMetrics {
        frequency_cyc_per_px: xs,
        neq,
        mean_neq,
        snr0,
        capacity_bits_per_pixel: square.capacity_bits_per_pixel,
        capacity_error_bits: square.capacity_error_bits,
        contrast,
        noise: if temporal_only { "temporal" } else { "total" },
    })
}
