//! Non-white noise spectra for the mean of MTF over noise.

use crate::Error;

/// A non-white noise spectrum: the noise amplitude at spatial frequency ν relative to the
/// white level that SNR0 uses, `n(ν)` (1 = white), piecewise linear between its samples and
/// constant beyond its ends.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseShape {
    frequencies: Vec<f64>,
    relative: Vec<f64>,
}

impl NoiseShape {
    /// `relative[i]` at `frequencies[i]` (cycles/m, ≥ 0, strictly increasing, at least two);
    /// every relative amplitude finite and > 0.
    pub fn new(frequencies: Vec<f64>, relative: Vec<f64>) -> Result<NoiseShape, Error> {
        let bad = |name, value, expected| Err(Error::InvalidParameter { name, value, expected });
        if frequencies.len() < 2 || frequencies.len() != relative.len() {
            return bad(
                "noise spectrum samples",
                frequencies.len() as f64,
                "at least two (frequency, amplitude) pairs",
            );
        }
        for (i, &f) in frequencies.iter().enumerate() {
            if !(f.is_finite() && f >= 0.0) || (i > 0 && f <= frequencies[i - 1]) {
                return bad("noise spectrum frequency", f, "finite, ≥ 0 and strictly increasing cycles/m");
            }
        }
        if let Some(&v) = relative.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return bad("relative noise amplitude", v, "finite and > 0 (1 = the white level)");
        }
        Ok(NoiseShape { frequencies, relative })
    }

    /// `n(ν)` at `frequency` (cycles/m, sign ignored).
    pub fn value(&self, frequency: f64) -> f64 {
        let nu = frequency.abs();
        let (x, y) = (&self.frequencies, &self.relative);
        let i = x.partition_point(|&f| f <= nu);
        if i == 0 {
            return y[0];
        }
        if i == x.len() {
            return y[x.len() - 1];
        }
        let t = (nu - x[i - 1]) / (x[i] - x[i - 1]);
        y[i - 1] + t * (y[i] - y[i - 1])
    }
}
