//! The optics crate's error type.

/// What can go wrong when preparing an optical computation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter is outside its physical range.
    #[error("{name} = {value:e} is out of range: expected {expected}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// The spectrum never falls to zero, so no finite quadrature covers it.
    #[error(
        "the spectrum extends over [{lo:e}, {hi:e}] m: it needs a band limit (a filter table, a top-hat or a Gaussian factor)"
    )]
    UnboundedSpectrum {
        /// Lower end, m.
        lo: f64,
        /// Upper end, m.
        hi: f64,
    },
    /// No light reaches the detector through any imaging order.
    #[error("no detected signal: the spectrum times the lens efficiency integrates to {total:e}")]
    NoSignal {
        /// The integral found.
        total: f64,
    },
}
