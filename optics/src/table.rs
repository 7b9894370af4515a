//! A transfer function given as a table: the OTF (or MTF) of one imaging order measured or
//! simulated at a few wavelengths, against spatial frequency at the detector.
//!
//! This is what the paper did with its Zemax and measured MTFs, and what an order of a
//! [`Pupil::Table`](crate::Pupil::Table) carries. Between tabulated wavelengths the value is
//! linear in λ; below the first and above the last wavelength it is the end row's (a table is
//! not extrapolated in λ: the lens that holds it states its wavelength range and efficiency).
//! Between tabulated frequencies it is linear in ν, and zero beyond the last frequency — unless
//! the table was made from sampled line spread functions ([`OtfTable::with_samples`], a PSF
//! stack): then the value at any ν is the exact transform of those samples (a trigonometric
//! polynomial in ν, summed directly), and only the wavelength is interpolated. Off
//! axis a table may give tangential (along the field) and sagittal curves; along an azimuth `φ`
//! measured from the field direction the value is `T cos²φ + S sin²φ` (the two are equal on
//! axis), unless the table holds each wavelength's whole PSF ([`OtfTable::with_planes`]): then
//! it is the PSF's 2-D transform along `φ` ([`crate::SampledPlane`]). Each row is normalized to 1 at zero frequency, as an OTF is by definition.

use crate::Error;
use crate::SampledPlane;

/// The OTF of one order against wavelength and frequency (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct OtfTable {
    wavelengths_m: Vec<f64>,
    frequencies: Vec<f64>,
    tangential: Vec<Vec<f64>>,
    sagittal: Vec<Vec<f64>>,
    /// whether the two curves differ somewhere (compared once: [`value`](OtfTable::value) is
    /// called for every spectral node and frequency)
    directional: bool,
    /// the sampled line spread functions whose exact transform the value is, when given
    samples: Option<Samples>,
}

/// One line spread function sampled at a pitch `p`: sample `j` at `x_j = (j − origin) p` from
/// the point its transform is taken about (a PSF's centroid), the samples summing to 1.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledLine {
    /// Where the transform's origin lies, in samples from sample 0 (fractional).
    pub origin: f64,
    /// The samples, summing to 1 (the transform is 1 at ν = 0).
    pub values: Vec<f64>,
}

impl SampledLine {
    /// The real part of the transform of the samples at `frequency` (cycles/m) for the pitch
    /// `pitch_m`: `Re Σ_j v_j e^{−2πi ν (j − origin) p}`, summed directly (Horner's scheme in
    /// `z = e^{−2πiνp}`: `n` complex multiply-adds, rounding error about `n ε Σ|v_j|`).
    pub fn transform(&self, pitch_m: f64, frequency: f64) -> f64 {
        let turns = frequency * pitch_m;
        let z = num_complex::Complex64::from_polar(1.0, -std::f64::consts::TAU * turns);
        let mut acc = num_complex::Complex64::new(0.0, 0.0);
        for &v in self.values.iter().rev() {
            acc = acc * z + v;
        }
        // e^{+2πi ν p origin}, its angle reduced to one turn before the sine and cosine
        let turn = std::f64::consts::TAU * (turns * self.origin).fract();
        (acc * num_complex::Complex64::from_polar(1.0, turn)).re
    }
}

/// The samples behind a table made from a PSF stack ([`OtfTable::with_samples`]).
#[derive(Clone, Debug, PartialEq)]
struct Samples {
    pitch_m: f64,
    /// per wavelength, the lines whose transforms are averaged (one, or the two axes' lines of a
    /// symmetric PSF)
    tangential: Vec<Vec<SampledLine>>,
    sagittal: Vec<Vec<SampledLine>>,
    /// per wavelength, the PSF's 2-D transform ([`OtfTable::with_planes`]): then the value along
    /// any azimuth is read from it, not `T cos²φ + S sin²φ`
    planes: Option<Vec<SampledPlane>>,
    /// the planes' values at the last frequency and azimuth read (every spectral node reads
    /// the same one, two slices each)
    cache: PlaneCache,
}

/// The last `(ν, φ)` read from the planes and each slice's value there (NaN: not yet read).
#[derive(Debug, Default)]
struct PlaneCache(std::sync::Mutex<Option<(u64, u64, Vec<f64>)>>);

impl Clone for PlaneCache {
    fn clone(&self) -> Self {
        PlaneCache::default()
    }
}

impl PartialEq for PlaneCache {
    /// A cache is no part of a table's value.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Samples {
    /// Slice `k`'s plane at `frequency` along `azimuth` (from +x, the field direction), through
    /// the cache when no other thread holds it.
    fn plane_value(&self, planes: &[SampledPlane], k: usize, frequency: f64, azimuth: f64) -> f64 {
        // the direction's sine and cosine only when a slice is read, not on every hit
        let read = || {
            let turns = frequency * self.pitch_m;
            let (sin, cos) = azimuth.sin_cos();
            planes[k].transform([turns * cos, turns * sin]).clamp(-1.0, 1.0)
        };
        let Ok(mut cache) = self.cache.0.try_lock() else { return read() };
        let key = (frequency.to_bits(), azimuth.to_bits());
        match cache.as_mut() {
            Some((f, a, values)) if (*f, *a) == key => {
                if values[k].is_nan() {
                    values[k] = read();
                }
                values[k]
            }
            _ => {
                let mut values = vec![f64::NAN; planes.len()];
                values[k] = read();
                let v = values[k];
                *cache = Some((key.0, key.1, values));
                v
            }
        }
    }

    fn value(&self, rows: &[Vec<SampledLine>], k: usize, frequency: f64) -> f64 {
        let lines = &rows[k];
        let sum: f64 = lines.iter().map(|l| l.transform(self.pitch_m, frequency)).sum();
        (sum / lines.len() as f64).clamp(-1.0, 1.0)
    }
}

fn bad<T>(name: &'static str, value: f64, expected: &'static str) -> Result<T, Error> {
    Err(Error::InvalidParameter { name, value, expected })
}

/// How far a row's value at zero frequency may be from 1 before the table is refused (it is then
/// not an OTF, or not normalized: a typing or unit slip).
pub const TABLE_ZERO_FREQUENCY_TOLERANCE: f64 = 0.02;

impl OtfTable {
    /// A table at `wavelengths_m` (≥ 1, finite, > 0, strictly increasing) and `frequencies`
    /// (cycles/m at the detector, ≥ 2, the first 0, strictly increasing), with
    /// `tangential[i][k]` the OTF at wavelength `i`, frequency `k` (finite, in `[−1, 1]`
    /// after normalization, within [`TABLE_ZERO_FREQUENCY_TOLERANCE`] of 1 at `ν = 0`), and
    /// optionally `sagittal` of the same shape (the tangential values are used for both when
    /// `None`). Each row is divided by its value at zero frequency.
    pub fn new(
        wavelengths_m: Vec<f64>,
        frequencies: Vec<f64>,
        tangential: Vec<Vec<f64>>,
        sagittal: Option<Vec<Vec<f64>>>,
    ) -> Result<OtfTable, Error> {
        if wavelengths_m.is_empty() {
            return bad("table wavelengths", 0.0, "at least one wavelength");
        }
        for (i, &l) in wavelengths_m.iter().enumerate() {
            if !(l.is_finite() && l > 0.0) || (i > 0 && l <= wavelengths_m[i - 1]) {
                return bad("table wavelength", l, "finite, > 0 m and strictly increasing");
            }
        }
        if frequencies.len() < 2 {
            return bad("table frequencies", frequencies.len() as f64, "at least two frequencies, the first 0");
        }
        if frequencies[0] != 0.0 {
            return bad("table first frequency", frequencies[0], "0 cycles/m (the OTF is 1 there)");
        }
        for (k, &f) in frequencies.iter().enumerate() {
            if !f.is_finite() || (k > 0 && f <= frequencies[k - 1]) {
                return bad("table frequency", f, "finite and strictly increasing cycles/m");
            }
        }
        let normalize = |rows: Vec<Vec<f64>>| -> Result<Vec<Vec<f64>>, Error> {
            if rows.len() != wavelengths_m.len() {
                return bad("table rows", rows.len() as f64, "one row per wavelength");
            }
            rows.into_iter()
                .map(|row| {
                    if row.len() != frequencies.len() {
                        return bad("table row length", row.len() as f64, "one value per frequency");
                    }
                    let at_zero = row[0];
                    if !(at_zero.is_finite() && (at_zero - 1.0).abs() <= TABLE_ZERO_FREQUENCY_TOLERANCE) {
                        return bad("table value at zero frequency", at_zero, "1 within 0.02 (an OTF is 1 at ν = 0)");
                    }
                    let row: Vec<f64> = row.iter().map(|v| v / at_zero).collect();
                    if let Some(&v) = row.iter().find(|v| !(v.is_finite() && v.abs() <= 1.0 + 1e-9)) {
                        return bad("table value", v, "finite, in [−1, 1] (an OTF, or an MTF in [0, 1])");
                    }
                    Ok(row.into_iter().map(|v| v.clamp(-1.0, 1.0)).collect())
                })
                .collect()
        };
        let tangential = normalize(tangential)?;
        let sagittal = match sagittal {
            Some(rows) => normalize(rows)?,
            None => tangential.clone(),
        };
        let directional = tangential != sagittal;
        Ok(OtfTable { wavelengths_m, frequencies, tangential, sagittal, directional, samples: None })
    }

    /// This table with the sampled line spread functions it was computed from (pitch `pitch_m`
    /// above 0, per wavelength one or more lines whose transforms are averaged, each line's samples
    /// summing to 1 within 1e-9): from then on [`value`](OtfTable::value) below the last
    /// frequency is the exact transform of those samples at the frequency asked, not the
    /// linear interpolation between the tabulated frequencies (which stay, for the callers that
    /// walk them). `sagittal` `None`: the tangential lines for both.
    pub fn with_samples(
        self,
        pitch_m: f64,
        tangential: Vec<Vec<SampledLine>>,
        sagittal: Option<Vec<Vec<SampledLine>>>,
    ) -> Result<OtfTable, Error> {
        if !(pitch_m.is_finite() && pitch_m > 0.0) {
            return bad("table sample pitch", pitch_m, "a finite pitch > 0 m");
        }
        let sagittal = sagittal.unwrap_or_else(|| tangential.clone());
        for rows in [&tangential, &sagittal] {
            if rows.len() != self.wavelengths_m.len() {
                return bad("table sampled rows", rows.len() as f64, "one set of lines per wavelength");
            }
            for line in rows.iter().flatten() {
                let sum: f64 = line.values.iter().sum();
                if !(line.origin.is_finite() && (sum - 1.0).abs() <= 1e-9) {
                    return bad("table sampled line sum", sum, "finite samples summing to 1 about a finite origin");
                }
            }
            if rows.iter().any(Vec::is_empty) {
                return bad("table sampled lines", 0.0, "at least one line per wavelength");
            }
        }
        Ok(OtfTable {
            samples: Some(Samples { pitch_m, tangential, sagittal, planes: None, cache: PlaneCache::default() }),
            ..self
        })
    }

    /// This table (made [`with_samples`](OtfTable::with_samples)) with each wavelength's PSF
    /// as a [`SampledPlane`] (one per wavelength): from then on the value along an azimuth `φ`
    /// from the field direction is the 2-D transform of the samples along that direction
    /// (within [`SampledPlane::error_bound`]), not `T cos²φ + S sin²φ`, and the table is
    /// direction dependent; the tabulated curves and the lines stay (the tangential and sagittal
    /// cuts, the same transform on the axes).
    pub fn with_planes(self, planes: Vec<SampledPlane>) -> Result<OtfTable, Error> {
        let Some(samples) = self.samples else {
            return bad("table planes", 0.0, "a table made with_samples first");
        };
        if planes.len() != self.wavelengths_m.len() {
            return bad("table planes", planes.len() as f64, "one plane per wavelength");
        }
        Ok(OtfTable { directional: true, samples: Some(Samples { planes: Some(planes), ..samples }), ..self })
    }

    /// Whether the value along an azimuth is read from the 2-D transform of each wavelength's
    /// PSF ([`with_planes`](OtfTable::with_planes)).
    pub fn is_two_dimensional(&self) -> bool {
        self.samples.as_ref().is_some_and(|s| s.planes.is_some())
    }

    /// The largest error bound of the planes' values ([`SampledPlane::error_bound`]); 0
    /// without planes.
    pub fn plane_error_bound(&self) -> f64 {
        let planes = self.samples.as_ref().and_then(|s| s.planes.as_deref()).unwrap_or(&[]);
        planes.iter().map(SampledPlane::error_bound).fold(0.0, f64::max)
    }

    /// Whether the values are the exact transforms of sampled lines ([`with_samples`](OtfTable::with_samples)).
    pub fn is_sampled(&self) -> bool {
        self.samples.is_some()
    }

    /// The tabulated wavelengths, m.
    pub fn wavelengths(&self) -> &[f64] {
        &self.wavelengths_m
    }

    /// The tabulated frequencies, cycles/m.
    pub fn frequencies(&self) -> &[f64] {
        &self.frequencies
    }

    /// The highest tabulated frequency, cycles/m: the OTF is zero beyond.
    pub fn max_frequency(&self) -> f64 {
        self.frequencies[self.frequencies.len() - 1]
    }

    /// Whether the tangential and sagittal curves differ somewhere.
    pub fn is_direction_dependent(&self) -> bool {
        self.directional
    }

    /// The OTF at `wavelength_m` and `frequency` (cycles/m, sign ignored) along the direction at
    /// angle `azimuth_from_field_rad` from the field direction: `T cos²φ + S sin²φ`, or with
    /// planes ([`with_planes`](OtfTable::with_planes)) the 2-D transform along that direction.
    pub fn value(&self, wavelength_m: f64, frequency: f64, azimuth_from_field_rad: f64) -> f64 {
        if let Some(samples) = &self.samples {
            let nu = frequency.abs();
            if nu > self.max_frequency() {
                return 0.0;
            }
            if let Some(planes) = &samples.planes {
                let azimuth = azimuth_from_field_rad;
                return self.blend(wavelength_m, |k| samples.plane_value(planes, k, nu, azimuth));
            }
            let t = self.blend(wavelength_m, |k| samples.value(&samples.tangential, k, nu));
            if !self.is_direction_dependent() {
                return t;
            }
            let s = self.blend(wavelength_m, |k| samples.value(&samples.sagittal, k, nu));
            let c2 = azimuth_from_field_rad.cos().powi(2);
            return t * c2 + s * (1.0 - c2);
        }
        let t = self.interpolate(&self.tangential, wavelength_m, frequency.abs());
        if !self.is_direction_dependent() {
            return t;
        }
        let s = self.interpolate(&self.sagittal, wavelength_m, frequency.abs());
        let c2 = azimuth_from_field_rad.cos().powi(2);
        t * c2 + s * (1.0 - c2)
    }

    fn interpolate(&self, rows: &[Vec<f64>], wavelength_m: f64, nu: f64) -> f64 {
        let f = &self.frequencies;
        if nu >= self.max_frequency() {
            return if nu == self.max_frequency() { self.row_at(rows, wavelength_m, f.len() - 1) } else { 0.0 };
        }
        let k = f.partition_point(|&x| x <= nu).max(1);
        let u = (nu - f[k - 1]) / (f[k] - f[k - 1]);
        let (a, b) = (self.row_at(rows, wavelength_m, k - 1), self.row_at(rows, wavelength_m, k));
        a + u * (b - a)
    }

    /// Column `k` of the rows, linear in wavelength, the end rows beyond the table.
    fn row_at(&self, rows: &[Vec<f64>], wavelength_m: f64, k: usize) -> f64 {
        self.blend(wavelength_m, |i| rows[i][k])
    }

    /// `row(i)` of the wavelength rows, linear in wavelength, the end rows beyond the table.
    fn blend(&self, wavelength_m: f64, row: impl Fn(usize) -> f64) -> f64 {
        let w = &self.wavelengths_m;
        if wavelength_m <= w[0] {
            return row(0);
        }
        if wavelength_m >= w[w.len() - 1] {
            return row(w.len() - 1);
        }
        let i = w.partition_point(|&x| x <= wavelength_m);
        let u = (wavelength_m - w[i - 1]) / (w[i] - w[i - 1]);
        let (a, b) = (row(i - 1), row(i));
        a + u * (b - a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> OtfTable {
        OtfTable::new(
            vec![500e-9, 600e-9],
            vec![0.0, 1e5, 2e5],
            vec![vec![1.0, 0.5, 0.1], vec![1.0, 0.7, 0.3]],
            Some(vec![vec![1.0, 0.3, 0.0], vec![1.0, 0.5, 0.1]]),
        )
        .unwrap()
    }

    #[test]
    fn interpolates_linearly_in_wavelength_and_frequency() {
        let t = table();
        assert_eq!(t.value(500e-9, 0.0, 0.0), 1.0);
        assert!((t.value(550e-9, 1e5, 0.0) - 0.6).abs() < 1e-15);
        assert!((t.value(500e-9, 1.5e5, 0.0) - 0.3).abs() < 1e-15);
        // sagittal across the field, the mean at 45°
        assert!((t.value(500e-9, 1e5, std::f64::consts::FRAC_PI_2) - 0.3).abs() < 1e-15);
        assert!((t.value(500e-9, 1e5, std::f64::consts::FRAC_PI_4) - 0.4).abs() < 1e-15);
        // end rows beyond the wavelengths, zero beyond the last frequency
        assert_eq!(t.value(400e-9, 1e5, 0.0), 0.5);
        assert_eq!(t.value(700e-9, 1e5, 0.0), 0.7);
        assert_eq!(t.value(600e-9, 2e5, 0.0), 0.3);
        assert_eq!(t.value(600e-9, 2.0001e5, 0.0), 0.0);
        assert_eq!(t.value(600e-9, -1e5, 0.0), 0.7);
    }

    /// A table with samples reads their exact transform (here two samples of 1/2 at ±p/2 about
    /// the origin: `cos(πνp)`, written out) between its frequencies, linear in λ between the
    /// wavelengths; bad samples are refused.
    #[test]
    fn sampled_tables_read_the_exact_transform() {
        let p = 1e-6;
        let line = |origin: f64| SampledLine { origin, values: vec![0.5, 0.5] };
        let frequencies = vec![0.0, 2.5e5, 5e5];
        let rows = vec![vec![1.0, 0.7, 0.0]; 2];
        let t = OtfTable::new(vec![5e-7, 6e-7], frequencies.clone(), rows.clone(), None).unwrap();
        let t = t.with_samples(p, vec![vec![line(0.5)], vec![line(0.5), line(0.0)]], None).unwrap();
        assert!(t.is_sampled());
        let nu = 1.7e5;
        let half = (std::f64::consts::PI * nu * p).cos();
        // the second wavelength averages the centred pair with the pair at 0 and p about 0:
        // Re(½ + ½ e^{−2πiνp}) = ½(1 + cos 2πνp)
        let shifted = 0.5 * (1.0 + (std::f64::consts::TAU * nu * p).cos());
        assert!((t.value(5e-7, nu, 0.0) - half).abs() < 1e-15);
        assert!((t.value(6e-7, nu, 1.0) - 0.5 * (half + shifted)).abs() < 1e-15);
        assert!((t.value(5.5e-7, -nu, 0.0) - 0.5 * (half + 0.5 * (half + shifted))).abs() < 1e-15);
        assert_eq!(t.value(5e-7, 5.0001e5, 0.0), 0.0);
        let base = OtfTable::new(vec![5e-7, 6e-7], frequencies, rows, None).unwrap();
        let e = base.clone().with_samples(p, vec![vec![line(0.5)]], None).unwrap_err();
        assert!(e.to_string().contains("one set of lines per wavelength"), "{e}");
        let bad_sum = SampledLine { origin: 0.0, values: vec![0.5, 0.6] };
        let e = base.clone().with_samples(p, vec![vec![line(0.5)], vec![bad_sum]], None).unwrap_err();
        assert!(e.to_string().contains("summing to 1"), "{e}");
        let e = base.with_samples(0.0, vec![vec![line(0.5)]; 2], None).unwrap_err();
        assert!(e.to_string().contains("pitch"), "{e}");
    }

    #[test]
    fn rows_are_normalized_and_bad_tables_refused() {
        let t = OtfTable::new(vec![5e-7], vec![0.0, 1.0], vec![vec![0.99, 0.495]], None).unwrap();
        assert_eq!(t.value(5e-7, 1.0, 0.0), 0.5);
        assert!(!t.is_direction_dependent());
        let e = OtfTable::new(vec![5e-7], vec![0.0, 1.0], vec![vec![100.0, 50.0]], None).unwrap_err();
        assert!(e.to_string().contains("table value at zero frequency"), "{e}");
        let e = OtfTable::new(vec![5e-7], vec![1.0, 2.0], vec![vec![1.0, 0.5]], None).unwrap_err();
        assert!(e.to_string().contains("first frequency"), "{e}");
        let e = OtfTable::new(vec![5e-7], vec![0.0, 1.0], vec![vec![1.0, f64::NAN]], None).unwrap_err();
        assert!(e.to_string().contains("table value"), "{e}");
        let e = OtfTable::new(vec![6e-7, 5e-7], vec![0.0, 1.0], vec![vec![1.0, 0.5]; 2], None).unwrap_err();
        assert!(e.to_string().contains("wavelength"), "{e}");
    }
}
