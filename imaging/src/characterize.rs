//! Camera characterization from a series of stacks at increasing illumination (paper SI Fig.
//! S6–S8; EMVA 1288's photon transfer): the signal transfer function (STF: mean output against
//! illumination) and the photon transfer curve (PTC: temporal noise against mean output), their
//! log-log slopes (≈ 1: linear; ≈ 0.5: shot-noise limited), with and without the capped black
//! subtracted, and EMVA 1288's conversion gain `K` from `σ² − σ_dark² = K (μ − μ_dark)`, the
//! read noise `√(σ²_dark − 1/12 DN²)/K` in electrons and the saturation point (the largest
//! variance), each with its standard error.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::measure::Region;
use crate::{Error, Frame};

/// One stack's statistics over a region: the temporal mean and sample variance of each pixel,
/// averaged over the region's pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Level {
    /// The illumination (any unit proportional to the photons per pixel: irradiance × exposure);
    /// 0 for the capped (dark) stack.
    pub illumination: f64,
    /// μ: mean grey level, DN.
    pub mean: f64,
    /// σ²: mean temporal variance, DN².
    pub variance: f64,
    /// The standard error of σ² for temporally Gaussian noise, independent from pixel to pixel:
    /// a pixel's sample variance s² over n frames varies by 2σ⁴/(n − 1), estimated without bias
    /// by 2 s⁴/(n + 1), and the region's mean over P pixels by Σ 2 s⁴/(n + 1)/P², DN².
    pub variance_sigma: f64,
    /// The fraction of the samples at 0 DN: near 1/2 or above, the ADC clips the noise at its
    /// lowest code and the variance reads low.
    pub at_zero: f64,
    /// Frames in the stack.
    pub frames: usize,
    /// Pixels in the region.
    pub pixels: usize,
    /// The frames' width, pixels.
    pub width: usize,
    /// The frames' height, pixels.
    pub height: usize,
}

/// The [`Level`] of `frames` over `region` at `illumination`.
///
/// # Errors
/// [`Error::TooFewFrames`] below two frames, [`Error::SizeMismatch`] for frames of different
/// sizes, [`Error::Region`] outside the frames.
pub fn level_of(frames: &[Frame], region: Region, illumination: f64) -> Result<Level, Error> {
    if frames.len() < 2 {
        return Err(Error::TooFewFrames { what: "stack", frames: frames.len() });
    }
    let first = &frames[0];
    if let Some(f) = frames.iter().find(|f| (f.width, f.height) != (first.width, first.height)) {
        return Err(Error::SizeMismatch {
            path: f.path.clone(),
            width: f.width,
            height: f.height,
            first: first.path.clone(),
            first_width: first.width,
            first_height: first.height,
        });
    }
    region.check("characterization", first.width, first.height)?;
    let series = region.series(frames);
    let n = frames.len() as f64;
    let (mut mean, mut variance, mut fourth, mut zeros) = (0.0, 0.0, 0.0, 0_usize);
    for pixel in &series {
        let m = pixel.iter().sum::<f64>() / n;
        let s2 = pixel.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0);
        mean += m;
        variance += s2;
        fourth += s2 * s2;
        zeros += pixel.iter().filter(|&&v| v == 0.0).count();
    }
    let pixels = series.len();
    let p = pixels as f64;
    Ok(Level {
        illumination,
        mean: mean / p,
        variance: variance / p,
        variance_sigma: (2.0 * fourth / (n + 1.0)).sqrt() / p,
        at_zero: zeros as f64 / (p * n),
        frames: frames.len(),
        pixels,
        width: first.width,
        height: first.height,
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

/// The weighted least-squares line through `(x, y)`, each `y` with its standard error `sigma`
/// (weights 1/σ²; nalgebra's SVD solve of the weighted design matrix), or `None` with fewer than
/// two points, all `x` equal, or a σ that is not finite and > 0. The standard errors come from
/// the stated σ (the inverse of the weighted normal matrix), scaled up by the Birge ratio
/// √(χ²/(n − 2)) when the points scatter more than their σ say (never down): an honest error
/// whether the σ or the residuals are the larger.
pub fn fit_line_weighted(x: &[f64], y: &[f64], sigma: &[f64]) -> Option<Fit> {
    let n = x.len().min(y.len()).min(sigma.len());
    if n < 2 || sigma[..n].iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return None;
    }
    let design = DMatrix::from_fn(n, 2, |i, j| if j == 0 { 1.0 / sigma[i] } else { x[i] / sigma[i] });
    let target = DVector::from_fn(n, |i, _| y[i] / sigma[i]);
    let svd = design.clone().svd(true, true);
    if svd.singular_values.min() <= 1e-12 * svd.singular_values.max() {
        return None;
    }
    let beta = svd.solve(&target, 1e-14).ok()?;
    let chi2 = (&target - &design * &beta).norm_squared();
    let birge = if n > 2 { (chi2 / (n as f64 - 2.0)).max(1.0) } else { 1.0 };
    let covariance = (design.transpose() * &design).try_inverse()? * birge;
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
    /// The photon transfer line σ² − σ²_dark against μ − μ_dark, weighted by each variance's
    /// standard error ([`fit_line_weighted`]): its slope is K (DN/e⁻).
    pub photon_transfer: Fit,
    /// K, DN per electron (EMVA 1288).
    pub conversion_gain: f64,
    /// Its standard error: from the variances' standard errors ([`Level::variance_sigma`]),
    /// raised by the Birge ratio when the levels scatter more ([`fit_line_weighted`]). The dark
    /// level's error is common to every point and moves only the intercept.
    pub conversion_gain_sigma: f64,
    /// The temporal dark noise in electrons, σ_d = √(σ²_dark − σ²_q)/K with σ²_q = 1/12 DN², the
    /// quantization noise (EMVA 1288 Release 4.0 Linear, §2.2: σ²_y.dark = K² σ²_d + σ²_q); 0 when
    /// σ²_dark ≤ 1/12 DN² (the quantization hides it).
    pub read_noise_e: f64,
    /// Its standard error, from those of σ²_dark and K.
    pub read_noise_sigma_e: f64,
    /// μ − μ_dark at saturation, in electrons: (μ_sat − μ_dark)/K.
    pub saturation_e: f64,
    /// What makes the numbers doubtful (most dark samples at 0 DN: clipped dark noise).
    pub warnings: Vec<String>,
}

/// Characterizes a camera from its capped stack's `dark` level and illuminated `levels` (at least
/// three below saturation, in increasing illumination, frames of the dark stack's size): the fits
/// use the levels below the saturation point with a signal above the dark level.
///
/// # Errors
/// [`Error::Characterization`] with fewer than three usable levels, a non-positive
/// illumination, an illumination not above the one before it, frames of another size than the
/// dark stack's, a mean level falling as the illumination rises, or a conversion gain that is not
/// positive.
pub fn characterize(dark: Level, levels: &[Level]) -> Result<Characterization, Error> {
    let bad = |message: String| Error::Characterization { message };
    if let Some((i, l)) = levels.iter().enumerate().find(|(_, l)| !(l.illumination > 0.0 && l.illumination.is_finite()))
    {
        return Err(bad(format!(
            "levels[{i}]: illumination {} of an illuminated stack; expected a positive number",
            l.illumination
        )));
    }
    if let Some(i) = (1..levels.len()).find(|&i| levels[i].illumination <= levels[i - 1].illumination) {
        return Err(bad(format!(
            "levels[{i}]: illumination {} is not above levels[{}]'s {}; list the levels in increasing illumination, each at its own",
            levels[i].illumination,
            i - 1,
            levels[i - 1].illumination
        )));
    }
    if let Some((i, l)) = levels.iter().enumerate().find(|(_, l)| (l.width, l.height) != (dark.width, dark.height)) {
        return Err(bad(format!(
            "levels[{i}]: frames of {} × {} pixels, but the dark frames are {} × {}; every stack of a series must have the same size",
            l.width, l.height, dark.width, dark.height
        )));
    }
    let mut warnings = Vec::new();
    if dark.at_zero >= 0.5 {
        warnings.push(format!(
            "{:.0} % of the dark samples read 0 DN: the camera clips its dark noise at the lowest code, so the dark variance and the read noise read low; raise the camera's black level (offset), or in a scene camera.black_level_dn",
            100.0 * dark.at_zero
        ));
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
    if stf.slope.is_nan() || stf.slope <= 0.0 {
        return Err(bad(format!(
            "the mean level falls as the illumination rises (STF slope {:.3}); check each level's illumination",
            stf.slope
        )));
    }
    // a zero standard error (a constant stack) weighs as the smallest non-zero one
    let floor = usable.iter().map(|l| l.variance_sigma).filter(|s| *s > 0.0).fold(f64::INFINITY, f64::min);
    let floor = if floor.is_finite() { floor } else { 1.0 };
    let photon_transfer = fit_line_weighted(
        &column(&|l| l.mean - dark.mean),
        &column(&|l| l.variance - dark.variance),
        &column(&|l| l.variance_sigma.max(floor)),
    )
    .ok_or_else(|| bad("the photon transfer fit is degenerate (all levels at one mean?)".to_owned()))?;
    let k = photon_transfer.slope;
    if k.is_nan() || k <= 0.0 {
        return Err(bad(format!(
            "conversion gain K = {k:e} DN/e⁻ from the photon transfer fit; expected a positive value"
        )));
    }
    let dark_noise_dn2 = (dark.variance - noise::QUANTIZATION_VARIANCE_DN2).max(0.0);
    let read_noise_e = dark_noise_dn2.sqrt() / k;
    let read_noise_sigma_e = if dark_noise_dn2 > 0.0 {
        read_noise_e
            * ((dark.variance_sigma / (2.0 * dark_noise_dn2)).powi(2) + (photon_transfer.slope_sigma / k).powi(2))
                .sqrt()
    } else {
        dark.variance_sigma.sqrt() / k
    };
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
        read_noise_e,
        read_noise_sigma_e,
        saturation_e: (sat_mean - dark.mean) / k,
        warnings,
    })
}
