//! SNR measured from stacks of frames (paper eq. 2–4 and SI "ASNR metric that includes VG
//! effect").

use crate::error::Error;

/// The SNR measured from the temporal statistics of a white and a black region, from
/// [`measured_snr`] or [`measured_snr_regions`]. Levels and standard deviations are in the
/// frames' unit (grey levels, DN), capped black included or not: it cancels in eq. 2 and adds no
/// variance.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct MeasuredSnr {
    /// Frames per pixel (the paper grabbed 30).
    pub frames: usize,
    /// Pixels in the white region.
    pub white_pixels: usize,
    /// Pixels in the black region.
    pub black_pixels: usize,
    /// White level: mean over frames and pixels.
    pub white_level: f64,
    /// Black level: mean over frames and pixels.
    pub black_level: f64,
    /// σ_w: per-pixel temporal sample standard deviation (n − 1), averaged over the white pixels.
    pub white_sigma: f64,
    /// σ_b: the same over the black pixels.
    pub black_sigma: f64,
    /// Signal = white level − black level (paper eq. 2).
    pub signal: f64,
    /// σ_s = √(σ_w² − σ_b²), the shot noise of the signal alone (paper eq. 3).
    pub signal_sigma: f64,
    /// SNR = signal/σ_s (paper eq. 4), the first-order SNR the paper compared with √N.
    pub snr: f64,
    /// SNR = signal/σ_w: eq. 3 becomes σ_s = σ_w, so glare and camera noise count (paper SI,
    /// "ASNR metric that includes VG effect").
    pub snr_with_glare: f64,
}

/// The measured SNR of one white pixel and one black pixel, each given as its time series over
/// a stack of frames (at least 2, the same number for both). See [`measured_snr_regions`].
pub fn measured_snr(white: &[f64], black: &[f64]) -> Result<MeasuredSnr, Error> {
    measured_snr_regions(&[white], &[black])
}

/// The measured SNR of a white and a black region, as the paper measured it: each region is a
/// list of pixels, each pixel its time series over one stack of frames (every pixel of both
/// regions has the same number of frames, at least 2; the regions may differ in pixel count).
///
/// Per pixel: the temporal mean and the **sample** standard deviation (divisor n − 1). Per region:
/// both averaged over its pixels (paper: "the signal and noise were then averaged over many
/// pixels"). Then signal = white − black (eq. 2), σ_s² = σ_w² − σ_b² (eq. 3), SNR = signal/σ_s
/// (eq. 4), and the glare-inclusive SNR = signal/σ_w (SI).
///
/// Averaging σ rather than σ² follows the paper; the mean sample σ is biased low by the factor
/// c4(n) ≈ 1 − 1/(4n) (0.9914 for the paper's n = 30), so both SNRs read high by 1/c4(n)
/// (0.87 % at n = 30).
///
/// # Errors
/// An empty region, a pixel with fewer than 2 frames, pixels with different frame counts, a
/// non-finite grey level, a white level not above the black level (no signal), or σ_w² ≤ σ_b²
/// (no signal noise).
pub fn measured_snr_regions<W: AsRef<[f64]>, B: AsRef<[f64]>>(white: &[W], black: &[B]) -> Result<MeasuredSnr, Error> {
    let frames = match white.first() {
        Some(pixel) => pixel.as_ref().len(),
        None => return Err(Error::EmptyRegion { region: "white" }),
    };
    if black.is_empty() {
        return Err(Error::EmptyRegion { region: "black" });
    }
    if frames < 2 {
        return Err(Error::TooFewFrames { region: "white", pixel: 0, frames });
    }
    let (white_level, white_sigma) = region_statistics("white", white, frames)?;
    let (black_level, black_sigma) = region_statistics("black", black, frames)?;
    let signal = white_level - black_level;
    if signal <= 0.0 {
        return Err(Error::NoSignal { white: white_level, black: black_level });
    }
    let (white_variance, black_variance) = (white_sigma * white_sigma, black_sigma * black_sigma);
    let signal_variance = white_variance - black_variance;
    if signal_variance <= 0.0 {
        return Err(Error::NoSignalNoise { white_variance, black_variance });
    }
    let signal_sigma = signal_variance.sqrt();
    Ok(MeasuredSnr {
        frames,
        white_pixels: white.len(),
        black_pixels: black.len(),
        white_level,
        black_level,
        white_sigma,
        black_sigma,
        signal,
        signal_sigma,
        snr: signal / signal_sigma,
        snr_with_glare: signal / white_sigma,
    })
}

/// Mean level and mean temporal sample σ over the pixels of one region, after checking every
/// pixel has `frames` finite samples.
fn region_statistics<P: AsRef<[f64]>>(region: &'static str, pixels: &[P], frames: usize) -> Result<(f64, f64), Error> {
    let (mut level_sum, mut sigma_sum) = (0.0, 0.0);
    for (pixel, series) in pixels.iter().enumerate() {
        let series = series.as_ref();
        if series.len() != frames {
            return Err(Error::StackMismatch { region, pixel, frames: series.len(), expected: frames });
        }
        if let Some((frame, &value)) = series.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::NonFiniteFrame { region, pixel, frame, value });
        }
        let n = frames as f64;
        let mean = series.iter().sum::<f64>() / n;
        // two-pass sample variance, divisor n − 1
        let variance = series.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
        level_sum += mean;
        sigma_sum += variance.sqrt();
    }
    let count = pixels.len() as f64;
    Ok((level_sum / count, sigma_sum / count))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_worked_single_pixel() {
        // white 10, 12, 14: mean 12, s² = (4 + 0 + 4)/2 = 4; black 1, 2, 3: mean 2, s² = 1.
        // signal 10 (eq. 2), σ_s² = 4 − 1 = 3 (eq. 3), SNR = 10/√3 = 5.773503 (eq. 4); glare: 10/2 = 5
        let m = measured_snr(&[10.0, 12.0, 14.0], &[1.0, 2.0, 3.0]).unwrap();
        assert_eq!((m.signal, m.white_sigma, m.black_sigma), (10.0, 2.0, 1.0));
        assert!((m.snr - 10.0 / 3f64.sqrt()).abs() < 1e-14);
        assert_eq!(m.snr_with_glare, 5.0);
    }

    #[test]
    fn region_averages_sigma_not_variance() {
        // two white pixels with σ = 2 and σ = 4 (series m ± σ over 3 frames with middle m: s = σ):
        // averaged σ_w = 3 (not √10); black pixel σ = 1 → σ_s = √8
        let white = [vec![8.0, 10.0, 12.0], vec![16.0, 20.0, 24.0]];
        let black = [vec![0.0, 1.0, 2.0]];
        let m = measured_snr_regions(&white, &black).unwrap();
        assert_eq!((m.white_level, m.black_level, m.white_sigma), (15.0, 1.0, 3.0));
        assert!((m.signal_sigma - 8f64.sqrt()).abs() < 1e-14);
    }
}
