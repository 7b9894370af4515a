//! The SNR, veiling glare and modulation measured from a stack (paper eq. 2–4; SI eq. S10–S12
//! and "ASNR metric that includes VG effect").

use serde::Serialize;

use crate::{Error, Frame};

/// A rectangle of pixels: `x, y` its top-left corner (column, row from the top), `width × height`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Region {
    /// First column.
    pub x: usize,
    /// First row (from the top).
    pub y: usize,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

impl Region {
    /// Parses `X,Y,W,H` (non-negative integers, `W, H ≥ 1`); `name` names it in the message.
    ///
    /// # Errors
    /// [`Error::Region`] naming what was given and what is accepted.
    pub fn parse(name: &'static str, text: &str) -> Result<Region, Error> {
        let bad = |message: String| Error::Region { name, text: text.to_owned(), message };
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let [x, y, w, h] = parts[..] else {
            return Err(bad(format!(
                "{} values; expected X,Y,W,H (pixels: corner column and row, width, height)",
                parts.len()
            )));
        };
        let number = |what: &str, v: &str| {
            v.parse::<usize>().map_err(|_| bad(format!("{what} = `{v}` is not a whole number of pixels ≥ 0")))
        };
        let region = Region { x: number("X", x)?, y: number("Y", y)?, width: number("W", w)?, height: number("H", h)? };
        if region.width == 0 || region.height == 0 {
            return Err(bad("W and H must be at least 1 pixel".to_owned()));
        }
        Ok(region)
    }

    /// Checks that the region lies inside frames of `width × height` pixels.
    pub(crate) fn check(&self, name: &'static str, width: usize, height: usize) -> Result<(), Error> {
        // in u128: x + w cannot wrap around
        let (right, bottom) = (self.x as u128 + self.width as u128, self.y as u128 + self.height as u128);
        if right > width as u128 || bottom > height as u128 {
            return Err(Error::Region {
                name,
                text: format!("{},{},{},{}", self.x, self.y, self.width, self.height),
                message: format!(
                    "reaches column {} and row {}, outside the {width} × {height} frames (columns 0…{}, rows 0…{})",
                    right - 1,
                    bottom - 1,
                    width.saturating_sub(1),
                    height.saturating_sub(1)
                ),
            });
        }
        Ok(())
    }

    /// Each pixel's time series over `frames`.
    pub(crate) fn series(&self, frames: &[Frame]) -> Vec<Vec<f64>> {
        let mut out = Vec::with_capacity(self.width * self.height);
        for y in self.y..self.y + self.height {
            for x in self.x..self.x + self.width {
                out.push(frames.iter().map(|f| f.at(x, y)).collect());
            }
        }
        out
    }
}

/// What [`measure`] found. Levels and σ in grey levels (DN).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// Frames in the stack.
    pub frames: usize,
    /// Pixels in the white and the black region.
    pub pixels: Pixels,
    /// White level: mean over frames and pixels.
    pub white: f64,
    /// Black level.
    pub black: f64,
    /// Signal = white − black (eq. 2).
    pub signal: f64,
    /// σ_w: √ of the per-pixel temporal sample variance averaged over the white pixels (variances
    /// averaged: unbiased, EMVA 1288; see `noise::measured_snr_regions`).
    pub sigma_white: f64,
    /// σ_b: the same over the black pixels.
    pub sigma_black: f64,
    /// σ_s = √(σ_w² − σ_b²) (eq. 3), or σ_w with `include_glare` (SI).
    pub sigma_signal: f64,
    /// SNR = signal/σ_s (eq. 4), with the σ_s above.
    pub snr: f64,
    /// The standard error of the SNR (the frames' temporal noise; `noise::measured_snr_regions`).
    pub snr_sigma: f64,
    /// Whether σ_s = σ_w (glare and camera noise counted: the SI's glare-inclusive SNR).
    pub include_glare: bool,
    /// The capped-black level (mean of the capped-black frames over the black region), when given.
    pub capped_black: Option<f64>,
    /// Veiling glare VG = (black − capped)/(white − capped) (SI eq. S10), when capped-black frames are given.
    pub vg: Option<f64>,
    /// Zero-frequency modulation M = (1 − VG)/(1 + VG) (SI eq. S11–S12).
    pub modulation: Option<f64>,
}

/// Pixel counts of the two regions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Pixels {
    /// In the white region.
    pub white: usize,
    /// In the black region.
    pub black: usize,
}

/// Measures a stack (at least two frames of one size, [`crate::read_stack`]): the white and the
/// black region's statistics (eq. 2–4; `include_glare`: σ_s = σ_w), and with `capped` frames
/// (the camera capped, same size) VG and M from their mean level over the black region.
///
/// # Errors
/// [`Error::Region`] for a region outside the frames, [`Error::TooFewFrames`],
/// [`Error::SizeMismatch`] or [`Error::DepthMismatch`] between any two frames, [`Error::Statistics`] (no signal: white not
/// above black; no signal noise: σ_w ≤ σ_b), [`Error::CappedBlack`] for a capped black not
/// below both levels.
pub fn measure(
    frames: &[Frame],
    white: Region,
    black: Region,
    capped: Option<&[Frame]>,
    include_glare: bool,
) -> Result<Measurement, Error> {
    let Some(first) = frames.first() else { return Err(Error::TooFewFrames { what: "frames", frames: 0 }) };
    if frames.len() < 2 {
        return Err(Error::TooFewFrames { what: "frames", frames: frames.len() });
    }
    for f in &frames[1..] {
        crate::frames::same_format(first, f)?;
    }
    white.check("white", first.width, first.height)?;
    black.check("black", first.width, first.height)?;
    let stats = noise::measured_snr_regions(&white.series(frames), &black.series(frames))?;
    let (sigma_signal, snr, snr_sigma) = if include_glare {
        (stats.white_sigma, stats.snr_with_glare, stats.snr_with_glare_sigma)
    } else {
        (stats.signal_sigma, stats.snr, stats.snr_sigma)
    };
    let (capped_black, vg, modulation) = match capped {
        None => (None, None, None),
        Some(capped) => {
            if capped.is_empty() {
                return Err(Error::TooFewFrames { what: "capped-black frames", frames: 0 });
            }
            for c in capped {
                crate::frames::same_format(first, c)?;
            }
            let series = black.series(capped);
            let level = series.iter().flatten().sum::<f64>() / (series.len() * capped.len()) as f64;
            for (region, value) in [("white", stats.white_level), ("black", stats.black_level)] {
                if level >= value {
                    return Err(Error::CappedBlack { capped: level, region, level: value });
                }
            }
            let vg = (stats.black_level - level) / (stats.white_level - level);
            (Some(level), Some(vg), Some((1.0 - vg) / (1.0 + vg)))
        }
    };
    Ok(Measurement {
        frames: frames.len(),
        pixels: Pixels { white: stats.white_pixels, black: stats.black_pixels },
        white: stats.white_level,
        black: stats.black_level,
        signal: stats.signal,
        sigma_white: stats.white_sigma,
        sigma_black: stats.black_sigma,
        sigma_signal,
        snr,
        snr_sigma,
        include_glare,
        capped_black,
        vg,
        modulation,
    })
}
