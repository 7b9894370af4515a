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
    /// The FFT path cannot reach the tolerance asked within its pupil-sampling limit (the cap
    /// [`crate::fft::MAX_CHOSEN_SAMPLES`] or the memory budget [`crate::FFT_MEMORY_BUDGET`]
    /// for the grids held): see [`crate::fft::pupil_samples_for`].
    #[error(
        "the FFT path cannot reach a tolerance of {tolerance:e} on the mean MTF: its extrapolated error falls as 1/N with the pupil samples N across the diameter, and {tolerance:e} would need N ≈ {needed}, beyond the {limit} it may use here (the 2048-sample cap, the memory budget for this many spectral nodes, or about three seconds of grids per sampling); at N = {limit} it reaches about {reachable:.1e}: ask for that tolerance or a coarser one"
    )]
    PupilSampling {
        /// The relative tolerance asked.
        tolerance: f64,
        /// Pupil samples it would need (predicted).
        needed: usize,
        /// The largest pupil sampling allowed.
        limit: usize,
        /// The relative error reachable at `limit` (predicted).
        reachable: f64,
    },
    /// The FFT path would need more memory than its budget ([`crate::FFT_MEMORY_BUDGET`]): it
    /// stops before allocating instead of exhausting the machine.
    #[error(
        "the FFT path would hold {grids} complex OTF grids of {grid_mb:.1} MB ({total_gib:.1} GiB, over the {budget_gib:.0} GiB budget) for {pupil_samples} pupil samples across the diameter: lower the pupil sampling (each halving divides the memory by about 4) or narrow the spectrum (fewer spectral nodes)"
    )]
    WorkBudget {
        /// OTF grids needed (spectral nodes × orders on the FFT path).
        grids: usize,
        /// Size of one grid, MB.
        grid_mb: f64,
        /// Their total, GiB.
        total_gib: f64,
        /// The budget, GiB.
        budget_gib: f64,
        /// Pupil samples across the diameter.
        pupil_samples: usize,
    },
}
