//! The crate's error type.

/// Everything that can go wrong when building spectra or running the power-meter chain.
///
/// Each message names the offending quantity, its value and the accepted range, e.g.
/// `sigma must be finite and > 0 m, got -1e-9`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A scalar parameter is out of its accepted range.
    #[error("{name} must be {accepted}, got {value:?}")]
    InvalidParameter {
        /// Name of the parameter, with its unit in `accepted`.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// The accepted range, with unit (e.g. "finite and > 0 m").
        accepted: String,
    },
    /// One sample of a table is out of range.
    #[error("{quantity}[{index}] must be {accepted}, got {value:?}")]
    InvalidSample {
        /// `"wavelength"` or `"value"`.
        quantity: &'static str,
        /// Index of the bad sample.
        index: usize,
        /// The rejected value.
        value: f64,
        /// The accepted range, with unit.
        accepted: &'static str,
    },
    /// Table wavelengths are not strictly increasing.
    #[error(
        "wavelengths must be strictly increasing, got wavelength[{index}] = {value:?} m after \
         wavelength[{previous_index}] = {previous:?} m"
    )]
    NotIncreasing {
        /// Index of the sample that is not larger than its predecessor.
        index: usize,
        /// Index of the predecessor (`index - 1`).
        previous_index: usize,
        /// Wavelength of the predecessor, m.
        previous: f64,
        /// Offending wavelength, m.
        value: f64,
    },
    /// Wavelength and value vectors differ in length.
    #[error(
        "wavelengths and values must have the same length, got {wavelengths} wavelengths and \
         {values} values"
    )]
    LengthMismatch {
        /// Number of wavelengths.
        wavelengths: usize,
        /// Number of values.
        values: usize,
    },
    /// A table has fewer than two samples.
    #[error("a sampled spectrum needs at least 2 samples, got {count}")]
    TooFewSamples {
        /// Number of samples given.
        count: usize,
    },
    /// The relative spectrum cannot be normalized (paper SI eq. S1).
    #[error("the integral of the relative spectrum must be finite and > 0, got {value:?}")]
    NotNormalizable {
        /// The integral found.
        value: f64,
    },
    /// The responsivity vanishes where the normalized spectrum does not (paper SI eq. S3).
    #[error(
        "responsivity must be > 0 wherever the normalized spectrum is > 0, got 0 at \
         {wavelength_m:?} m"
    )]
    ZeroResponsivity {
        /// A wavelength (m) where the responsivity is 0 and the spectrum is positive.
        wavelength_m: f64,
    },
}

/// `Ok(x)` when `x` passes `ok`, else an [`Error::InvalidParameter`].
pub(crate) fn check(name: &'static str, value: f64, ok: bool, accepted: impl Into<String>) -> Result<f64, Error> {
    if ok { Ok(value) } else { Err(Error::InvalidParameter { name, value, accepted: accepted.into() }) }
}

/// Finite and > 0, with the given unit in the message (written only when it fails: a sweep
/// builds its spectra at every point).
pub(crate) fn positive(name: &'static str, value: f64, unit: &str) -> Result<f64, Error> {
    if value.is_finite() && value > 0.0 {
        return Ok(value);
    }
    check(name, value, false, format!("finite and > 0{}", unit_suffix(unit)))
}

/// Finite and >= 0, with the given unit in the message (written only when it fails).
pub(crate) fn non_negative(name: &'static str, value: f64, unit: &str) -> Result<f64, Error> {
    if value.is_finite() && value >= 0.0 {
        return Ok(value);
    }
    check(name, value, false, format!("finite and >= 0{}", unit_suffix(unit)))
}

fn unit_suffix(unit: &str) -> String {
    if unit.is_empty() { String::new() } else { format!(" {unit}") }
}
