//! The crate's error type.

/// Everything that can go wrong when building a [`Sensor`](crate::Sensor) or analysing measured
/// frames and transfer curves.
///
/// Each message names the offending quantity, its value and what is accepted, e.g.
/// `read_noise must be finite and >= 0 e⁻ rms, got -1.0`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A scalar parameter is out of its accepted range.
    #[error("{name} must be {accepted}, got {value:?}")]
    InvalidParameter {
        /// Name of the parameter; its unit is in `accepted`.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// The accepted range, with unit (e.g. "finite and > 0 DN/e⁻").
        accepted: String,
    },
    /// A charge or variance of a noise budget exceeds the largest finite number.
    #[error("the {quantity} overflows: {detail}")]
    Overflow {
        /// What overflowed.
        quantity: &'static str,
        /// The terms that make it, with units.
        detail: String,
    },
    /// A region of a frame stack has no pixels.
    #[error("the {region} region must have at least 1 pixel, got 0")]
    EmptyRegion {
        /// `"white"` or `"black"`.
        region: &'static str,
    },
    /// A pixel's time series is too short for a sample standard deviation.
    #[error("{region} pixel {pixel} must have at least 2 frames for a sample standard deviation, got {frames}")]
    TooFewFrames {
        /// `"white"` or `"black"`.
        region: &'static str,
        /// Index of the pixel in its region.
        pixel: usize,
        /// Number of frames found.
        frames: usize,
    },
    /// The pixels of a frame stack do not all have the same number of frames.
    #[error("{region} pixel {pixel} must have {expected} frames like white pixel 0 (one stack), got {frames}")]
    StackMismatch {
        /// `"white"` or `"black"`.
        region: &'static str,
        /// Index of the pixel in its region.
        pixel: usize,
        /// Number of frames of this pixel.
        frames: usize,
        /// Number of frames of white pixel 0.
        expected: usize,
    },
    /// A grey level in a frame stack is NaN or infinite.
    #[error("{region} pixel {pixel} frame {frame} must be a finite grey level, got {value:?}")]
    NonFiniteFrame {
        /// `"white"` or `"black"`.
        region: &'static str,
        /// Index of the pixel in its region.
        pixel: usize,
        /// Index of the frame.
        frame: usize,
        /// The rejected value.
        value: f64,
    },
    /// The white level does not exceed the black level, so eq. 2 gives no signal.
    #[error("the white level must exceed the black level (paper eq. 2), got white {white:?} and black {black:?}")]
    NoSignal {
        /// Mean white level.
        white: f64,
        /// Mean black level.
        black: f64,
    },
    /// σ_w² ≤ σ_b², so eq. 3 gives no signal noise.
    #[error(
        "the white variance must exceed the black variance (paper eq. 3), got σ_w² = {white_variance:?} and \
         σ_b² = {black_variance:?}"
    )]
    NoSignalNoise {
        /// σ_w², squared mean temporal standard deviation of the white region.
        white_variance: f64,
        /// σ_b², squared mean temporal standard deviation of the black region.
        black_variance: f64,
    },
    /// Two paired inputs differ in length.
    #[error("{first} and {second} must have the same length, got {first_len} and {second_len}")]
    LengthMismatch {
        /// Name of the first input.
        first: &'static str,
        /// Its length.
        first_len: usize,
        /// Name of the second input.
        second: &'static str,
        /// Its length.
        second_len: usize,
    },
    /// A fit has too few points.
    #[error("{fit} needs at least {needed} points, got {count}")]
    TooFewPoints {
        /// The function doing the fit.
        fit: &'static str,
        /// Minimum number of points.
        needed: usize,
        /// Number of points given.
        count: usize,
    },
    /// One sample of a fit's input is out of range.
    #[error("{quantity}[{index}] must be {accepted}, got {value:?}")]
    InvalidSample {
        /// Name of the input.
        quantity: &'static str,
        /// Index of the bad sample.
        index: usize,
        /// The rejected value.
        value: f64,
        /// The accepted range.
        accepted: &'static str,
    },
    /// The data do not determine the fitted quantity.
    #[error("{fit}: {reason}")]
    DegenerateFit {
        /// The function doing the fit.
        fit: &'static str,
        /// What is wrong with the data.
        reason: String,
    },
}

/// `Ok(x)` when `x` passes `ok`, else an [`Error::InvalidParameter`].
pub(crate) fn check(name: &'static str, value: f64, ok: bool, accepted: impl Into<String>) -> Result<f64, Error> {
    if ok { Ok(value) } else { Err(Error::InvalidParameter { name, value, accepted: accepted.into() }) }
}

/// Finite and >= 0, with the given unit in the message (written only when it fails: a sweep
/// forms the noise budget at every point).
pub(crate) fn non_negative(name: &'static str, value: f64, unit: &str) -> Result<f64, Error> {
    if value.is_finite() && value >= 0.0 {
        return Ok(value);
    }
    check(name, value, false, format!("finite and >= 0 {unit}"))
}

/// Finite and > 0, with the given unit in the message (written only when it fails).
pub(crate) fn positive(name: &'static str, value: f64, unit: &str) -> Result<f64, Error> {
    if value.is_finite() && value > 0.0 {
        return Ok(value);
    }
    check(name, value, false, format!("finite and > 0 {unit}"))
}
