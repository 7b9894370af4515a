//! Camera characterization (paper SI "Camera characterization"; EMVA 1288 Release 4.0 Linear,
//! §2.2 and §6.4): the conversion gain from the photon transfer curve, and log–log slopes of the
//! signal and photon transfer curves.

use crate::error::Error;

/// Conversion gain K, DN/e⁻, by the photon transfer method (EMVA 1288 Release 4.0 Linear, §2.2
/// and §6.4): for a linear camera `σ²_y − σ²_y.dark = K (μ_y − μ_y.dark)`, so K is the
/// least-squares slope **through the origin** of `y_i = var_dn[i] − dark_var_dn` against
/// `x_i = mean_dn[i] − dark_mean_dn`: `K = Σ x_i y_i / Σ x_i²`.
///
/// `mean_dn[i]` and `var_dn[i]` are the mean grey level (DN) and its temporal variance (DN²) at
/// illumination level i; `dark_mean_dn`, `dark_var_dn` the same with no light (the capped black).
/// Quantization noise (1/12 DN²) and read noise are in both variances and cancel. Pass only
/// points in the linear range (EMVA fits up to 70 % of saturation).
///
/// # Errors
/// Lengths differ, no points, a non-finite input, all means at the dark level, or a fitted K
/// that is not > 0 (variance not growing with the signal).
pub fn photon_transfer_gain(
    mean_dn: &[f64],
    var_dn: &[f64],
    dark_mean_dn: f64,
    dark_var_dn: f64,
) -> Result<f64, Error> {
    const FIT: &str = "photon_transfer_gain";
    same_length("mean_dn", mean_dn, "var_dn", var_dn)?;
    if mean_dn.is_empty() {
        return Err(Error::TooFewPoints { fit: FIT, needed: 1, count: 0 });
    }
    finite("mean_dn", mean_dn)?;
    finite("var_dn", var_dn)?;
    finite("dark_mean_dn", &[dark_mean_dn])?;
    finite("dark_var_dn", &[dark_var_dn])?;
    let (mut xy, mut xx) = (0.0, 0.0);
    for (&mean, &var) in mean_dn.iter().zip(var_dn) {
        let (x, y) = (mean - dark_mean_dn, var - dark_var_dn);
        xy += x * y;
        xx += x * x;
    }
    if xx == 0.0 {
        return Err(Error::DegenerateFit {
            fit: FIT,
            reason: format!("every mean equals the dark mean {dark_mean_dn:?} DN, so the slope is undetermined"),
        });
    }
    let gain = xy / xx;
    if !(gain.is_finite() && gain > 0.0) {
        return Err(Error::DegenerateFit {
            fit: FIT,
            reason: format!(
                "the fitted gain must be finite and > 0 DN/e⁻ (variance growing with the signal), got {gain:?}"
            ),
        });
    }
    Ok(gain)
}

/// Least-squares slope (with intercept) of `ln y` against `ln x`: the exponent p of a power law
/// `y ∝ x^p`. Paper SI "Camera characterization": the signal transfer curve (signal against
/// input) has slope ≈ 1 for a linear camera; the photon transfer curve (noise σ against signal)
/// has slope ≈ 0.5 where the camera is shot-noise limited, flattening towards 0 where dark noise
/// dominates. Subtract the capped black before fitting (the paper's Fig. S8): the mean from the
/// signal, the dark variance from the noise variance.
///
/// # Errors
/// Lengths differ, fewer than 2 points, a value that is not finite and > 0 (its logarithm), or all
/// x equal.
pub fn log_slope(x: &[f64], y: &[f64]) -> Result<f64, Error> {
    const FIT: &str = "log_slope";
    same_length("x", x, "y", y)?;
    if x.len() < 2 {
        return Err(Error::TooFewPoints { fit: FIT, needed: 2, count: x.len() });
    }
    let lx = logarithms("x", x)?;
    let ly = logarithms("y", y)?;
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (a, b) in lx.iter().zip(&ly) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
    }
    if sxx == 0.0 {
        return Err(Error::DegenerateFit { fit: FIT, reason: "all x are equal, so the slope is undetermined".into() });
    }
    Ok(sxy / sxx)
}

fn same_length(first: &'static str, a: &[f64], second: &'static str, b: &[f64]) -> Result<(), Error> {
    if a.len() == b.len() {
        Ok(())
    } else {
        Err(Error::LengthMismatch { first, first_len: a.len(), second, second_len: b.len() })
    }
}

fn finite(quantity: &'static str, values: &[f64]) -> Result<(), Error> {
    match values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        Some((index, &value)) => Err(Error::InvalidSample { quantity, index, value, accepted: "finite" }),
        None => Ok(()),
    }
}

fn logarithms(quantity: &'static str, values: &[f64]) -> Result<Vec<f64>, Error> {
    values
        .iter()
        .enumerate()
        .map(|(index, &value)| {
            if value.is_finite() && value > 0.0 {
                Ok(value.ln())
            } else {
                Err(Error::InvalidSample {
                    quantity,
                    index,
                    value,
                    accepted: "finite and > 0 (its logarithm is taken)",
                })
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_model_gives_exact_gain() {
        // K = 0.25 DN/e⁻, dark: 100 DN, variance K²·10² + 1/12 = 6.3333 DN²; light adds K·μ_e DN to the
        // mean and K²·μ_e DN² to the variance, i.e. K·(μ_y − μ_dark): slope exactly K
        let (k, dark_mean, dark_var) = (0.25, 100.0, 0.0625 * 100.0 + 1.0 / 12.0);
        let mean: Vec<f64> = [1e3, 2e3, 4e3, 8e3].iter().map(|e| dark_mean + k * e).collect();
        let var: Vec<f64> = [1e3, 2e3, 4e3, 8e3].iter().map(|e| dark_var + k * k * e).collect();
        let fitted = photon_transfer_gain(&mean, &var, dark_mean, dark_var).unwrap();
        assert!((fitted - k).abs() < 1e-14, "{fitted}");
    }

    #[test]
    fn power_law_exponents() {
        // y = 3 x^0.5 and y = 2 x: slopes 0.5 and 1 to rounding
        let x = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0];
        let sqrt: Vec<f64> = x.iter().map(|v: &f64| 3.0 * v.sqrt()).collect();
        let linear: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
        assert!((log_slope(&x, &sqrt).unwrap() - 0.5).abs() < 1e-14);
        assert!((log_slope(&x, &linear).unwrap() - 1.0).abs() < 1e-14);
    }
}
