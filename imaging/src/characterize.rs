//! Camera characterization from a series of stacks at increasing illumination (paper SI Fig.
//! S6–S8; EMVA 1288's photon transfer): the signal transfer function (STF: mean output against
//! illumination) and the photon transfer curve (PTC: temporal noise against mean output), their
//! log-log slopes (≈ 1: linear; ≈ 0.5: shot-noise limited), with and without the capped black
//! subtracted, and EMVA 1288's conversion gain `K` from `σ² − σ_dark² = K (μ − μ_dark)`, the
//! read noise `σ_dark/K` in electrons and the saturation point (the largest variance).

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::measure::Region;
use crate::{Error, Frame};

/// One stack's statistics over a region: the temporal mean and sample variance of each pixel,
/// averaged over the region's pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Level {
    /// The illumination (any unit proportional to the photons per pixel: irradiance × exposure);
    /// 0 for the capped (dark) stack.
    pub illumination: f64,
    /// μ: mean grey level, DN.
    pub mean: f64,
    /// σ²: mean temporal variance, DN².
    pub variance: f64,
    /// Frames in the stack.
    pub frames: usize,
    /// Pixels in the region.
    pub pixels: usize,
}

/// The [`Level`] of `frames` over `region` at `illumination`.
///
/// # Errors
/// [`Error::TooFewFrames`] below two frames, [`Error::Region`] outside the frames.
pub fn level_of(frames: &[Frame], region: Region, illumination: f64) -> Result<Level, Error> {
    if frames.len() < 2 {
        return Err(Error::TooFewFrames { what: "stack", frames: frames.len() });
    }
    region.check("characterization", frames[0].width, frames[0].height)?;
    let series = region.series(frames);
    let n = frames.len() as f64;
    let (mut mean, mut variance) = (0.0, 0.0);
    for pixel in &series {
        let m = pixel.iter().sum::<f64>() / n;
        mean += m;
        variance += pixel.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0);
    }
    let pixels = series.len();
    Ok(Level {
        illumination,
        mean: mean / pixels as f64,
        variance: variance / pixels as f64,
        frames: frames.len(),
        pixels,
    })
}

/// A straight line fitted by least squares, `y = intercept + slope x`, with the standard errors
/// from the residuals (n − 2 degrees of freedom; 0 with two points).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Fit {
    /// Slope.
    pub slope: f64,
    /// Its standard error.
    pub slope_sigma: f64,
    /// Intercept.
    pub intercept: f64,
    /// Its standard error.
    pub intercept_sigma: f64,
    /// Points fitted.
    pub points: usize,
}

/// The least-squares line through `(x, y)` (nalgebra's SVD solve of the design matrix), or
/// `None` with fewer than two points or all `x` equal.
pub fn fit_line(x: &[f64], y: &[f64]) -> Option<Fit> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let design = DMatrix::from_fn(n, 2, |i, j| if j == 0 { 1.0 } else { x[i] });
    let target = DVector::from_column_slice(&y[..n]);
    let svd = design.clone().svd(true, true);
    if svd.singular_values.min() <= 1e-12 * svd.singular_values.max() {
        return None;
    }
    let beta = svd.solve(&target, 1e-14).ok()?;
    let residual = &target - &design * &beta;
    let dof = n as f64 - 2.0;
    let s2 = if dof > 0.0 { residual.norm_squared() / dof } else { 0.0 };
    let covariance = (design.transpose() * &design).try_inverse()? * s2;
    Some(Fit {
        slope: beta[1],
        slope_sigma: covariance[(1, 1)].max(0.0).sqrt(),
        intercept: beta[0],
        intercept_sigma: covariance[(0, 0)].max(0.0).sqrt(),
        points: n,
    })
}

/// What [`characterize`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Characterization {
    /// The capped (dark) stack: μ_dark, σ²_dark.
    pub dark: Level,
    /// The illuminated stacks, in the order given.
    pub levels: Vec<Level>,
    /// Index into `levels` of the saturation point: the largest variance (EMVA 1288).
    pub saturation: usize,
    /// Per level, whether the fits used it (above the capped black, below 90 % of saturation).
    pub fitted: Vec<bool>,
    /// STF, log10 μ against log10 illumination (capped black not subtracted; SI Fig. S7a).
    pub stf_raw: Fit,
    /// STF with the capped black subtracted: log10 (μ − μ_dark) (SI Fig. S8a; ≈ 1 when linear).
    pub stf: Fit,
    /// PTC, log10 σ against log10 μ, not subtracted (SI Fig. S7b).
    pub ptc_raw: Fit,
    /// PTC with the capped black subtracted: log10 √(σ² − σ²_dark) against log10 (μ − μ_dark)
    /// (SI Fig. S8b; ≈ 0.5 when shot-noise limited).
    pub ptc: Fit,
    /// The photon transfer line σ² − σ²_dark against μ − μ_dark: its slope is K (DN/e⁻).
    pub photon_transfer: Fit,
    /// K, DN per electron (EMVA 1288).
    pub conversion_gain: f64,
    /// Its standard error.
    pub conversion_gain_sigma: f64,
    /// σ_dark / K: the dark (read) noise in electrons.
    pub read_noise_e: f64,
    /// μ − μ_dark at saturation, in electrons: (μ_sat − μ_dark)/K.
    pub saturation_e: f64,
}

/// Characterizes a camera from its capped stack's `dark` level and illuminated `levels` (at least
/// three below saturation, increasing illumination): the fits use the levels below the
/// saturation point with a signal above the dark level.
///
/// # Errors
/// [`Error::Characterization`] with fewer than three usable levels, a non-positive
/// illumination, or a conversion gain that is not positive.
pub fn characterize(dark: Level, levels: &[Level]) -> Result<Characterization, Error> {
    let bad = |message: String| Error::Characterization { message };
    if let Some(l) = levels.iter().find(|l| !(l.illumination > 0.0 && l.illumination.is_finite())) {
        return Err(bad(format!(
            "illumination {} of an illuminated stack; expected a positive number",
            l.illumination
        )));
    }
    let saturation =
        levels.iter().enumerate().max_by(|a, b| a.1.variance.total_cmp(&b.1.variance)).map_or(0, |(i, _)| i);
    let sat_mean = levels.get(saturation).map_or(f64::INFINITY, |l| l.mean);
    // below the saturation point (a level within 1 % of its mean is on the roll-off)
    let fitted: Vec<bool> = levels
        .iter()
        .map(|l| {
            l.mean - dark.mean > 0.0 && l.variance > dark.variance && l.mean < dark.mean + 0.9 * (sat_mean - dark.mean)
        })
        .collect();
    let usable: Vec<&Level> = levels.iter().zip(&fitted).filter(|(_, f)| **f).map(|(l, _)| l).collect();
    if usable.len() < 3 {
        return Err(bad(format!(
            "{} of {} levels are above the capped black and below saturation; at least 3 are needed for the fits",
            usable.len(),
            levels.len()
        )));
    }
    let lg = |v: f64| v.log10();
    let column = |f: &dyn Fn(&Level) -> f64| usable.iter().map(|l| f(l)).collect::<Vec<f64>>();
    let fit = |x: Vec<f64>, y: Vec<f64>, what: &str| {
        fit_line(&x, &y).ok_or_else(|| bad(format!("the {what} fit is degenerate (all levels at one illumination?)")))
    };
    let stf_raw = fit(column(&|l| lg(l.illumination)), column(&|l| lg(l.mean)), "STF")?;
    let stf = fit(column(&|l| lg(l.illumination)), column(&|l| lg(l.mean - dark.mean)), "STF")?;
    let ptc_raw = fit(column(&|l| lg(l.mean)), column(&|l| lg(l.variance.sqrt())), "PTC")?;
    let ptc = fit(column(&|l| lg(l.mean - dark.mean)), column(&|l| lg((l.variance - dark.variance).sqrt())), "PTC")?;
    let photon_transfer =
        fit(column(&|l| l.mean - dark.mean), column(&|l| l.variance - dark.variance), "photon transfer")?;
    let k = photon_transfer.slope;
    if k.is_nan() || k <= 0.0 {
        return Err(bad(format!(
            "conversion gain K = {k:e} DN/e⁻ from the photon transfer fit; expected a positive value"
        )));
    }
    Ok(Characterization {
        dark,
        levels: levels.to_vec(),
        saturation,
        fitted,
        stf_raw,
        stf,
        ptc_raw,
        ptc,
        photon_transfer,
        conversion_gain: k,
        conversion_gain_sigma: photon_transfer.slope_sigma,
        read_noise_e: dark.variance.sqrt() / k,
        saturation_e: (sat_mean - dark.mean) / k,
    })
}
