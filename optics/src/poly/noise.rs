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

    /// The table's frequencies (cycles/m, strictly increasing): where `n` has its kinks.
    pub fn rows(&self) -> &[f64] {
        &self.frequencies
    }

    /// `dn/d|ν|` at `frequency` (cycles/m, sign ignored): the slope of the row interval that
    /// holds it (the one above where it is a row), 0 beyond the table's ends, where `n` is
    /// constant. `n` has a kink at each row, so the slope is piecewise constant.
    pub fn slope(&self, frequency: f64) -> f64 {
        let nu = frequency.abs();
        let (x, y) = (&self.frequencies, &self.relative);
        let i = x.partition_point(|&f| f <= nu);
        if i == 0 || i == x.len() {
            return 0.0;
        }
        (y[i] - y[i - 1]) / (x[i] - x[i - 1])
    }
}

#[cfg(test)]
mod tests {
    use super::NoiseShape;

    /// `slope` against central differences of `value` inside each row interval (exact for the
    /// linear pieces, to rounding), the interval above at a row, and 0 beyond the table's ends.
    #[test]
    fn slope_is_the_derivative_of_the_pieces() {
        let shape = NoiseShape::new(vec![1e4, 3e4, 7e4], vec![1.0, 1.4, 3.0]).unwrap();
        for nu in [1.5e4, 2.9e4, 3.1e4, 6.5e4] {
            let h = 10.0;
            let theirs = (shape.value(nu + h) - shape.value(nu - h)) / (2.0 * h);
            assert!((shape.slope(nu) - theirs).abs() <= 1e-12 * theirs.abs(), "{nu}: {} vs {theirs}", shape.slope(nu));
            assert_eq!(shape.slope(-nu), shape.slope(nu));
        }
        assert!((shape.slope(3e4) - 1.6 / 4e4).abs() <= 1e-15 / 4e4, "{}", shape.slope(3e4));
        assert_eq!((shape.slope(5e3), shape.slope(7e4), shape.slope(9e4)), (0.0, 0.0, 0.0));
        assert_eq!(shape.rows(), &[1e4, 3e4, 7e4]);
    }
}
