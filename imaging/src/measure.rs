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

/// The measured ASNR (paper eq. 1 with measured factors, as the paper's Fig. 2b set it beside
/// the simulated one): `ASNR = SNR · mean MTF`, the SNR of [`measure`] and the mean MTF to
/// Nyquist of a slanted edge ([`crate::sfr()`]) or a table, with the standard error propagated
/// (independent factors): `σ_A / A = √((σ_SNR/SNR)² + (σ_M/M)²)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MeasuredAsnr {
    /// The measured SNR (eq. 4).
    pub snr: f64,
    /// Its standard error.
    pub snr_sigma: f64,
    /// The measured mean MTF from 0 to Nyquist.
    pub mean_mtf: f64,
    /// Its standard error (0 for a table given without one).
    pub mean_mtf_sigma: f64,
    /// SNR × mean MTF.
    pub asnr: f64,
    /// Its standard error.
    pub asnr_sigma: f64,
}

impl MeasuredAsnr {
    /// The product of the two measured factors and its propagated standard error.
    pub fn new(snr: f64, snr_sigma: f64, mean_mtf: f64, mean_mtf_sigma: f64) -> MeasuredAsnr {
        let asnr = snr * mean_mtf;
        let relative = |v: f64, s: f64| if v == 0.0 { 0.0 } else { s / v };
        let asnr_sigma = asnr.abs() * relative(snr, snr_sigma).hypot(relative(mean_mtf, mean_mtf_sigma));
        MeasuredAsnr { snr, snr_sigma, mean_mtf, mean_mtf_sigma, asnr, asnr_sigma }
    }
}

/// The mean of a tabulated MTF from 0 to `nyquist_cyc_per_mm`: the trapezoid rule on the
/// table's points (linear between them), the last interval cut at Nyquist.
///
/// # Errors
/// [`Error::Edge`] (naming `path`) for frequencies that are not finite, ≥ 0 and increasing, an
/// MTF that is not finite, or a table that does not reach Nyquist.
pub fn mean_mtf_of_table(
    path: &std::path::Path,
    frequency_cyc_per_mm: &[f64],
    mtf: &[f64],
    nyquist_cyc_per_mm: f64,
) -> Result<f64, Error> {
    let bad = |message: String| Err(Error::Edge { path: path.to_owned(), message });
    if frequency_cyc_per_mm.len() != mtf.len() || mtf.len() < 2 {
        return bad(format!(
            "{} frequencies and {} MTF values: expected two or more rows",
            frequency_cyc_per_mm.len(),
            mtf.len()
        ));
    }
    for (i, w) in frequency_cyc_per_mm.windows(2).enumerate() {
        if !(w[0].is_finite() && w[1].is_finite() && w[0] >= 0.0 && w[1] > w[0]) {
            return bad(format!(
                "frequency_cyc_per_mm {} then {} (rows {} and {}): expected finite frequencies ≥ 0, increasing",
                w[0],
                w[1],
                i + 1,
                i + 2
            ));
        }
    }
    if let Some(m) = mtf.iter().find(|m| !m.is_finite()) {
        return bad(format!("an MTF of {m}: expected finite values"));
    }
    let last = frequency_cyc_per_mm[frequency_cyc_per_mm.len() - 1];
    if frequency_cyc_per_mm[0] > 0.0 || last < nyquist_cyc_per_mm {
        return bad(format!(
            "frequencies {} to {last} cycles/mm: the table must run from 0 to at least Nyquist, {nyquist_cyc_per_mm:.4} cycles/mm",
            frequency_cyc_per_mm[0]
        ));
    }
    let mut integral = 0.0;
    for i in 0..mtf.len() - 1 {
        let (f0, f1) = (frequency_cyc_per_mm[i], frequency_cyc_per_mm[i + 1]);
        if f0 >= nyquist_cyc_per_mm {
            break;
        }
        let end = f1.min(nyquist_cyc_per_mm);
        let at_end = mtf[i] + (mtf[i + 1] - mtf[i]) * (end - f0) / (f1 - f0);
        integral += (end - f0) * (mtf[i] + at_end) / 2.0;
    }
    Ok(integral / nyquist_cyc_per_mm)
}
