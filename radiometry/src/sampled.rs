//! Tabulated spectra, piecewise linear between samples and zero outside.

use crate::Error;

/// A tabulated spectrum: piecewise linear between samples, exactly zero outside
/// [first wavelength, last wavelength].
///
/// Invariants checked by [`Sampled::new`]: at least 2 samples; wavelengths (m) finite, > 0 and
/// strictly increasing; values finite and ≥ 0. The unit of the values is the caller's (relative
/// spectrum, W/(m² m), efficiency, ...). Integrals ([`integral`](Self::integral),
/// [`integral_between`](Self::integral_between)) are exact for this piecewise-linear model.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampled {
    wavelengths: Vec<f64>,
    values: Vec<f64>,
}

impl Sampled {
    /// Validates and builds a table from wavelengths (m) and values.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`], [`Error::TooFewSamples`], [`Error::InvalidSample`] (naming the
    /// index of a non-finite or non-positive wavelength, or of a non-finite or negative value),
    /// [`Error::NotIncreasing`].
    pub fn new(wavelengths_m: Vec<f64>, values: Vec<f64>) -> Result<Sampled, Error> {
        if wavelengths_m.len() != values.len() {
            return Err(Error::LengthMismatch { wavelengths: wavelengths_m.len(), values: values.len() });
        }
        if wavelengths_m.len() < 2 {
            return Err(Error::TooFewSamples { count: wavelengths_m.len() });
        }
        for (index, (&w, &v)) in wavelengths_m.iter().zip(&values).enumerate() {
            if !(w.is_finite() && w > 0.0) {
                return Err(Error::InvalidSample {
                    quantity: "wavelength",
                    index,
                    value: w,
                    accepted: "finite and > 0 m",
                });
            }
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::InvalidSample { quantity: "value", index, value: v, accepted: "finite and >= 0" });
            }
            if index > 0 && w <= wavelengths_m[index - 1] {
                return Err(Error::NotIncreasing {
                    index,
                    previous_index: index - 1,
                    previous: wavelengths_m[index - 1],
                    value: w,
                });
            }
        }
        Ok(Sampled { wavelengths: wavelengths_m, values })
    }

    /// Sample wavelengths, m (strictly increasing).
    pub fn wavelengths(&self) -> &[f64] {
        &self.wavelengths
    }

    /// Sample values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// First and last sample wavelengths, m.
    pub fn range(&self) -> (f64, f64) {
        (self.wavelengths[0], self.wavelengths[self.wavelengths.len() - 1])
    }

    /// Index i ≥ 1 of the segment [w[i−1], w[i]] holding `l` (clamped to the first/last segment).
    ///
    /// The proportional guess first (right at once on an evenly spaced table, as spectrometer
    /// tables are), checked against its ends; a binary search where it misses.
    fn segment(&self, l: f64) -> usize {
        let w = &self.wavelengths;
        let n = w.len();
        let (first, last) = (w[0], w[n - 1]);
        let guess = (((l - first) / (last - first) * (n - 1) as f64) as usize).saturating_add(1).clamp(1, n - 1);
        if w[guess - 1] <= l && (l < w[guess] || guess == n - 1) {
            return guess;
        }
        w.partition_point(|&x| x <= l).clamp(1, n - 1)
    }

    /// Linear interpolation on segment i (valid for l inside it).
    fn on_segment(&self, i: usize, l: f64) -> f64 {
        let (x0, x1) = (self.wavelengths[i - 1], self.wavelengths[i]);
        let (y0, y1) = (self.values[i - 1], self.values[i]);
        if l == x1 {
            return y1;
        }
        y0 + (y1 - y0) * ((l - x0) / (x1 - x0))
    }

    /// Value at `wavelength_m`: linear interpolation inside [first, last] (both ends included),
    /// exactly 0 outside, NaN for a NaN wavelength.
    pub fn value(&self, wavelength_m: f64) -> f64 {
        let l = wavelength_m;
        if l.is_nan() {
            return f64::NAN;
        }
        let (first, last) = self.range();
        if l < first || l > last {
            return 0.0;
        }
        self.on_segment(self.segment(l), l)
    }

    /// ∫ value dλ over the whole table (trapezoid rule, exact for the piecewise-linear model).
    /// Unit: value unit × m.
    pub fn integral(&self) -> f64 {
        self.wavelengths.windows(2).zip(self.values.windows(2)).map(|(x, y)| 0.5 * (x[1] - x[0]) * (y[0] + y[1])).sum()
    }

    /// ∫_lo^hi value dλ, exact for the piecewise-linear model (zero outside the table). Oriented:
    /// `integral_between(hi, lo) == -integral_between(lo, hi)`. Infinite bounds are allowed; a NaN
    /// bound gives NaN.
    pub fn integral_between(&self, lo: f64, hi: f64) -> f64 {
        if lo.is_nan() || hi.is_nan() {
            return f64::NAN;
        }
        if lo > hi {
            return -self.integral_between(hi, lo);
        }
        let (first, last) = self.range();
        let a = lo.max(first);
        let b = hi.min(last);
        if a >= b {
            return 0.0;
        }
        let mut sum = 0.0;
        let mut i = self.segment(a);
        while i < self.wavelengths.len() {
            let (x0, x1) = (self.wavelengths[i - 1], self.wavelengths[i]);
            let u = a.max(x0);
            let v = b.min(x1);
            if u < v {
                sum += 0.5 * (v - u) * (self.on_segment(i, u) + self.on_segment(i, v));
            }
            if x1 >= b {
                break;
            }
            i += 1;
        }
        sum
    }

    /// Largest sample value.
    pub fn max_value(&self) -> f64 {
        self.values.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }

    /// Smallest sample value (the spectrum itself is 0 outside the table).
    pub fn min_value(&self) -> f64 {
        self.values.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// The same table with every value multiplied by `k`.
    ///
    /// For finite `k ≥ 0` the result keeps every invariant of [`Sampled::new`] (unless a product
    /// overflows). Other `k` follow IEEE arithmetic (a negative `k` gives negative values, NaN
    /// propagates) rather than being silently replaced: validate user-supplied factors with
    /// [`Sampled::try_scaled`].
    pub fn scaled(&self, k: f64) -> Sampled {
        Sampled { wavelengths: self.wavelengths.clone(), values: self.values.iter().map(|v| v * k).collect() }
    }

    /// [`Sampled::scaled`] with validation: `k` must be finite and ≥ 0 and every scaled value
    /// finite.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a bad `k`, [`Error::InvalidSample`] if a product overflows.
    pub fn try_scaled(&self, k: f64) -> Result<Sampled, Error> {
        crate::error::non_negative("scale factor", k, "")?;
        let s = self.scaled(k);
        if let Some((index, &value)) = s.values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::InvalidSample { quantity: "value", index, value, accepted: "finite and >= 0" });
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Sampled {
        // Triangle 0 → 2 → 0 over 700..900 nm.
        Sampled::new(vec![700e-9, 800e-9, 900e-9], vec![0.0, 2.0, 0.0]).unwrap()
    }

    #[test]
    fn value_interpolates_and_is_zero_outside() {
        let s = tri();
        assert_eq!(s.value(700e-9), 0.0);
        assert_eq!(s.value(800e-9), 2.0);
        assert_eq!(s.value(900e-9), 0.0);
        assert!((s.value(750e-9) - 1.0).abs() < 1e-12);
        assert_eq!(s.value(699e-9), 0.0);
        assert_eq!(s.value(901e-9), 0.0);
        assert_eq!(s.value(-1.0), 0.0);
        assert!(s.value(f64::NAN).is_nan());
    }

    /// The proportional guess of `segment` finds the segment the binary search finds, on an
    /// evenly spaced and an uneven table, at every sample, between samples and outside.
    #[test]
    fn segment_guess_is_the_binary_search() {
        let even: Vec<f64> = (0..41).map(|k| 600e-9 + 0.25e-9 * f64::from(k)).collect();
        let uneven: Vec<f64> = (0..41).map(|k| 600e-9 + 1e-9 * f64::from(k * k)).collect();
        for w in [even, uneven] {
            let table = Sampled::new(w.clone(), vec![1.0; w.len()]).unwrap();
            let search = |l: f64| w.partition_point(|&x| x <= l).clamp(1, w.len() - 1);
            let mut probes = vec![0.0, 1e-9, w[0] - 1e-12, 2e-6, f64::INFINITY, f64::NEG_INFINITY];
            for pair in w.windows(2) {
                probes.extend([pair[0], 0.5 * (pair[0] + pair[1]), pair[1] - 1e-18, pair[1]]);
            }
            for l in probes {
                assert_eq!(table.segment(l), search(l), "{l:e}");
            }
        }
    }

    #[test]
    fn integral_of_triangle() {
        // Area = base × height / 2 = 200e-9 × 2 / 2 = 2e-7.
        let s = tri();
        assert!((s.integral() - 2e-7).abs() < 1e-22);
        assert!((s.integral_between(0.0, 1.0) - 2e-7).abs() < 1e-22);
        // Left half: 100e-9 × 2 / 2 = 1e-7; from 750 to 850 nm: 1e-7 × (1 - 2 × 1/8) = 1.5e-7.
        assert!((s.integral_between(700e-9, 800e-9) - 1e-7).abs() < 1e-22);
        assert!((s.integral_between(750e-9, 850e-9) - 1.5e-7).abs() < 1e-21);
        assert!((s.integral_between(850e-9, 750e-9) + 1.5e-7).abs() < 1e-21);
        assert_eq!(s.integral_between(1e-6, 2e-6), 0.0);
        assert_eq!(s.integral_between(f64::NEG_INFINITY, f64::INFINITY), s.integral());
        assert!(s.integral_between(f64::NAN, 1.0).is_nan());
    }

    #[test]
    fn min_max_and_scaled() {
        let s = tri();
        assert_eq!(s.max_value(), 2.0);
        assert_eq!(s.min_value(), 0.0);
        let t = s.scaled(3.0);
        assert_eq!(t.values(), &[0.0, 6.0, 0.0]);
        assert_eq!(t.wavelengths(), s.wavelengths());
        assert!(s.try_scaled(-1.0).is_err());
        assert!(s.try_scaled(f64::NAN).is_err());
        assert!(s.try_scaled(1e300).is_ok());
        let big = Sampled::new(vec![1e-6, 2e-6], vec![2.0, 2.0]).unwrap();
        assert!(big.try_scaled(f64::MAX).is_err());
    }
}
