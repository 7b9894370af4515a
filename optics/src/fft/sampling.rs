//! Choosing the pupil sampling from a tolerance, and the Richardson estimate that verifies it.
//!
//! The rule, from the convergence study in the [`fft`](super) module docs ("Choosing the pupil
//! sampling"). Two error models were measured there, both relative errors of the polychromatic
//! mean MTF at `N` pupil samples across the diameter, every pupil of the study:
//!
//! - the plain mean `M_N`: `|M_N − M|/M ≈ C N^−q` ([`ERROR_MODEL`]: `C = 0.4`, `q = 1.6`);
//! - the Richardson extrapolation of `M_{N/2}` and `M_N` (the value this module returns): at
//!   most `C_R N^−q_R` ([`EXTRAPOLATED_MODEL`]: `C_R = 2.6e-3`, `q_R = 1`, the envelope of the
//!   study's `e_R` column: 2.3e-6 … 1.6e-5 at `N = 128`, 3.7e-6 … 5.6e-6 at 256, 3.0e-6 … 3.6e-6
//!   at 512, 0.95e-6 … 1.5e-6 at 1024). The extrapolation gains 10–70× at `N = 128` and 3–6× at
//!   1024: it cancels the leading `N^−1.6` term, and what is left falls more slowly.
//!
//! 1. **Start** at the smallest `N` whose extrapolated error, with a safety factor, is within
//!    the tolerance: `SAFETY · C_R · N^−q_R ≤ tolerance`, never below [`MIN_CHOSEN_SAMPLES`];
//!    then the largest even `N` with the same padded FFT length ([`fast_fft_len`]`(N + K)`),
//!    since the padding makes it free.
//! 2. **Compute** the mean MTF at `N/2` and `N` ([`SamplingPlan::coarse`],
//!    [`SamplingPlan::samples`]) and **extrapolate** ([`SamplingPlan::extrapolate`]) with the
//!    order [`RICHARDSON_ORDER`] `p = 1.5`:
//!
//!    ```text
//!    correction = |M_N − M_{N/2}| / (2^p − 1)        (the error of M_N)
//!    value      = M_N + (M_N − M_{N/2}) / (2^p − 1)  (the extrapolated mean)
//!    error      = correction · C_R N^−q_R / (C N^−q) (the error of value)
//!    ```
//!
//!    The correction was 0.9–1.3 times the true error of `M_N` for every polychromatic case of
//!    the study from `N = 128` on, so the scene's own correction, scaled by the ratio of the two
//!    models at its `N`, estimates the error of the extrapolated value: a pupil with more edge
//!    than the study's (a larger `C`) shows a larger correction and is refined accordingly.
//!    The plan accepts when `error ≤ tolerance` and the mean at `N/4` shows the pair in its
//!    asymptotic range: an observed order ([`observed_order`]) of at least 1, or levels that
//!    agree to a tenth of the tolerance; it returns `value`. Where the `N/4` level aliases the
//!    pupil phase of a single aperture (more than half a wave between neighbouring samples,
//!    [`SampledPupil::max_opd_step_m`](super::SampledPupil::max_opd_step_m)) it is not yet in
//!    that range, and the three levels need only move one way (`poly::grid`). (A composite pupil's ring edges can
//!    make `N/2` and `N` agree by chance: the concentric segmented lens's mean went 0.3104,
//!    0.3087, 0.3110, 0.3116 at `N` = 32 … 256, and settles at 0.3119 with order 1.9.)
//!
//!    The FFT engine (`poly::grid`) judges the mean MTF averaged over azimuth, the quantity the
//!    ASNR takes, and holds the correction itself to the tolerance rather than the correction
//!    times the gain: over azimuth the grids are read between their lines, whose interpolation
//!    error converges at another order than the study's means along x (astigmatism 0.2 µm:
//!    order 2.3 falling to 1.7, and `p = 1.5` overshot by 1.8e-4 at `N = 128` where the gain put
//!    the estimate at 4.7e-5); the correction bounds the extrapolated value's error for any order
//!    `≥ 1`.
//! 3. **Refine** otherwise ([`SamplingPlan::refine`]): `N → 2N`, the old `N` becoming the
//!    coarse level (its result is reused), until the estimate passes or the next `N` would
//!    exceed the limit: then [`Error::PupilSampling`] says what was asked, what `N` it would
//!    take, and what is reachable.
//!
//! The limit is the smaller of [`MAX_CHOSEN_SAMPLES`] and the largest `N` whose grids fit the
//! memory budget [`crate::FFT_MEMORY_BUDGET`].
//!
//! **Composite pupils** (zones, [`SampledZones`](super::SampledZones)) follow another rule
//! ([`ErrorRule::FinestLevel`]): their ring and sector edges cut the pixels at places that move
//! with `N`, so the mean converges at a high but irregular order (the concentric segmented lens
//! of the paper's scene, 50 nm band: relative errors 6.2e-3, 5.5e-4, 1.2e-4, 1.2e-5 at `N` = 64,
//! 128, 256, 512, observed orders 2.7–3.1) and the Richardson step of order 1.5 with the
//! single-aperture gain overshoots: at a tolerance of 1e-3 it returned a mean 2.6e-3 below the
//! converged one. The value is the mean at `N` itself, its error the grid convergence index of
//! the three levels (Roache 1998), `F_s |M_N − M_{N/2}| / ((2^p − 1) |M_N|)` with `F_s = 1.25`
//! and the observed order `p` held to `[1, 2]`, refined (`N → 2N`) until it is within the
//! tolerance (`cargo test -p asnr-optics --test optics composite_tolerance -- --nocapture`
//! prints the achieved errors against the semi-analytic reference of that test).
//!
//! **One grid alone** (a line spectrum, a monochromatic MTF) converges less regularly than a
//! polychromatic sum: with a few waves of defocus the mean-MTF error of a single grid is not
//! monotone in `N` below `N ≈ 1024` (the study's `w = 2` rows), and two levels can agree by
//! chance (the estimate was 0.12 of the true error at `N = 256`, `w = 2`). A monochromatic
//! caller should add the third level `N/4` and refine while the observed order
//! ([`observed_order`]) is outside `[1, 2.5]`.

use super::fast_fft_len;
use crate::Error;

/// The measured error model of the polychromatic mean MTF, `|M_N − M|/M ≈ C N^−q`: `(C, q)`.
/// Fitted on the study's polychromatic rows (`e_N N^1.6` = 0.37–0.40 from `N = 128` to `1024`,
/// for the circle as an aperture, the iris decentred by 0.10 and 0.15, and coma 0.5 µm).
/// Single grids of the study: 0.25–0.5 for circles, 0.7 for a 120° sector and an annulus, 2 for
/// three coherent rings (more edge).
pub const ERROR_MODEL: (f64, f64) = (0.4, 1.6);

/// The measured bound on the relative error of the Richardson-extrapolated polychromatic mean
/// MTF, `C_R N^−q_R`: `(C_R, q_R)`, the envelope of the study's `e_R` column from `N = 128` to
/// `1024` (module docs): `2.6e-3/N` is 2.0e-5, 1.0e-5, 5.1e-6, 2.5e-6 at `N` = 128 … 1024,
/// against the largest measured 1.6e-5, 5.6e-6, 3.6e-6, 1.5e-6.
pub const EXTRAPOLATED_MODEL: (f64, f64) = (2.6e-3, 1.0);

/// Factor on the model's prediction for the starting `N`: the largest ratio of the Richardson
/// estimate to the true error measured for polychromatic sums (1.3), so that the first pair
/// usually passes.
pub const SAFETY: f64 = 1.3;

/// The ratio of the extrapolated value's error to the error of `M_N` at `n` samples, from the
/// two measured models: `C_R n^−q_R / (C n^−q)` (0.12 at 128, 0.41 at 1024), at most 1.
pub fn extrapolation_gain(n: usize) -> f64 {
    let (c, q) = ERROR_MODEL;
    let (cr, qr) = EXTRAPOLATED_MODEL;
    let n = n.max(2) as f64;
    (cr * n.powf(-qr) / (c * n.powf(-q))).min(1.0)
}

/// The Richardson order `p`: the observed order of the polychromatic mean MTF was 1.4–1.65
/// between `N = 128` and `1024`; `p = 1.5` errs on the side of a larger estimate when the true
/// order is higher.
pub const RICHARDSON_ORDER: f64 = 1.5;

/// Smallest `N` the chooser uses: below it the pair `(N/2, N)` is not yet asymptotic (at
/// `N = 64` the estimate was 0.01–0.16 of the true error: the paper scene's spectral flanks
/// carry up to 13 waves of defocus, under-resolved at 32 samples).
pub const MIN_CHOSEN_SAMPLES: usize = 128;

/// Largest `N` the chooser goes to (one grid at 2048 samples takes about 0.25 s).
pub const MAX_CHOSEN_SAMPLES: usize = 2048;

/// How the error of a chosen sampling is estimated, and which value it stands for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ErrorRule {
    /// Single apertures: the Richardson extrapolation of `N/2` and `N` is the value, its error
    /// the scene's correction times [`extrapolation_gain`] (module docs, step 2).
    #[default]
    Richardson,
    /// Composite pupils of zones: the mean at `N` itself is the value, its error the grid
    /// convergence index of the three levels (module docs, "Composite pupils").
    FinestLevel,
}

/// Safety factor of the grid convergence index on three levels (Roache, *Verification and
/// Validation in Computational Science and Engineering*, 1998: 1.25 where the order is observed).
pub const FINEST_SAFETY: f64 = 1.25;

/// Highest order the composite rule credits: the observed order of a composite pupil's mean
/// swings with where the ring edges fall on the grid (2.7, 3.1, 2.6 from `N` = 64 to 512 on the
/// concentric segmented lens), so a high one is not trusted beyond the order of the edge
/// pixels' area error.
pub const FINEST_MAX_ORDER: f64 = 2.0;

/// The pupil samplings to compute and how to judge them (module docs): the mean MTF at
/// [`coarse`](Self::coarse) and [`samples`](Self::samples), then
/// [`extrapolate`](Self::extrapolate), and [`refine`](Self::refine) while it has not converged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplingPlan {
    /// Pupil samples `N` across the diameter of the fine level.
    pub samples: usize,
    /// The relative tolerance on the mean MTF.
    pub tolerance: f64,
    /// Largest `N` allowed (cap and memory budget).
    pub limit: usize,
    /// Highest normalized frequency read from the grids (sets `K` and the padding).
    pub s_max: f64,
    /// How the error is estimated and which value is returned.
    pub rule: ErrorRule,
}

/// The Richardson extrapolation of two levels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extrapolated {
    /// `M_N + (M_N − M_{N/2})/(2^p − 1)`: the value to use.
    pub value: f64,
    /// `|M_N − M_{N/2}|/(2^p − 1) / |M_N|`: the estimated relative error of `M_N` (module docs).
    pub correction: f64,
    /// The estimated relative error of [`value`](Self::value): the correction times
    /// [`extrapolation_gain`] at `N` (module docs, step 2).
    pub error: f64,
    /// Whether [`error`](Self::error) is within the plan's tolerance.
    pub converged: bool,
}

impl SamplingPlan {
    /// Pupil samples of the coarse level, `N/2`.
    pub fn coarse(&self) -> usize {
        self.samples / 2
    }

    /// The Richardson extrapolation of the mean MTFs at [`coarse`](Self::coarse) and
    /// [`samples`](Self::samples) (module docs, step 2).
    pub fn extrapolate(&self, coarse_mean: f64, fine_mean: f64) -> Extrapolated {
        let difference = (fine_mean - coarse_mean) / (2f64.powf(RICHARDSON_ORDER) - 1.0);
        let scale = fine_mean.abs().max(f64::MIN_POSITIVE);
        let correction = difference.abs() / scale;
        let error = correction * extrapolation_gain(self.samples);
        Extrapolated { value: fine_mean + difference, correction, error, converged: error <= self.tolerance }
    }

    /// The estimate of the three levels `N/4`, `N/2`, `N` by the plan's [`ErrorRule`]: the
    /// Richardson extrapolation of the last two, or the mean at `N` with its grid convergence
    /// index `F_s |M_N − M_{N/2}| / ((2^p − 1) |M_N|)`, `F_s` = [`FINEST_SAFETY`], `p` the
    /// observed order ([`observed_order`]) within `[1, FINEST_MAX_ORDER]`.
    pub fn estimate(&self, quarter_mean: f64, coarse_mean: f64, fine_mean: f64) -> Extrapolated {
        match self.rule {
            ErrorRule::Richardson => self.extrapolate(coarse_mean, fine_mean),
            ErrorRule::FinestLevel => {
                let order = observed_order(quarter_mean, coarse_mean, fine_mean);
                // NaN (three equal levels) credits the lowest order: the difference is 0 anyway
                let p = if order.is_nan() { 1.0 } else { order.clamp(1.0, FINEST_MAX_ORDER) };
                let scale = fine_mean.abs().max(f64::MIN_POSITIVE);
                let correction = FINEST_SAFETY * (fine_mean - coarse_mean).abs() / (2f64.powf(p) - 1.0) / scale;
                Extrapolated {
                    value: fine_mean,
                    correction,
                    error: correction,
                    converged: correction <= self.tolerance,
                }
            }
        }
    }

    /// The next level, `2N` (the current `N` becomes the coarse level: keep its mean), or
    /// [`Error::PupilSampling`] when `2N` exceeds the limit; `estimate` is the last
    /// [`Extrapolated::error`], from which the `N` needed is predicted (`N (e/tol)^{1/q_R}`).
    pub fn refine(&self, estimate: f64) -> Result<SamplingPlan, Error> {
        let next = 2 * self.samples;
        if next > self.limit {
            let ratio = (estimate / self.tolerance).max(1.0);
            let needed = (self.samples as f64 * ratio.powf(1.0 / EXTRAPOLATED_MODEL.1)).ceil() as usize;
            // what the scene's own estimate predicts at the limit (a pupil with more edge than
            // the study's converges more slowly than the model says)
            let at_limit = estimate * (self.samples as f64 / self.limit as f64).powf(EXTRAPOLATED_MODEL.1);
            return Err(self.unreachable(needed.max(next), at_limit.max(reachable(self.limit))));
        }
        Ok(SamplingPlan { samples: next, ..*self })
    }

    fn unreachable(&self, needed: usize, reachable: f64) -> Error {
        Error::PupilSampling { tolerance: self.tolerance, needed, limit: self.limit, reachable }
    }
}

/// The relative error the extrapolated mean reaches at `n` samples by the model, with its
/// safety factor: `SAFETY · C_R n^−q_R`.
pub fn reachable(n: usize) -> f64 {
    let (cr, qr) = EXTRAPOLATED_MODEL;
    SAFETY * cr * (n.max(2) as f64).powf(-qr)
}

/// Largest lag stored for `n` samples up to `s_max` (as [`OtfPlan`](super::OtfPlan)).
fn max_lag(n: usize, s_max: f64) -> usize {
    (s_max * n as f64).ceil() as usize + super::plan::STENCIL_MARGIN
}

/// Bytes of one OTF grid of `n` samples up to `s_max`.
fn grid_bytes(n: usize, s_max: f64) -> f64 {
    let side = 2 * max_lag(n, s_max) + 1;
    (side * side * std::mem::size_of::<num_complex::Complex64>()) as f64
}

/// The pupil sampling for a relative `tolerance` on the mean MTF, reading frequencies up to
/// `s_max` (normalized to the full aperture's cutoff), with `grids` OTF grids held at once (the
/// spectral nodes × orders of a polychromatic point): the plan of the module docs.
///
/// # Errors
/// [`Error::InvalidParameter`] for a tolerance outside `(0, 1)`, an `s_max` outside `(0, 1]` or
/// no grid; [`Error::PupilSampling`] when the starting `N` already exceeds the limit (the cap
/// [`MAX_CHOSEN_SAMPLES`] or the memory budget): its message gives the tolerance asked, the `N`
/// it would need and the error reachable at the limit.
///
/// # Example
/// ```
/// use optics::fft::pupil_samples_for;
/// // the paper scene: Nyquist at s = 0.19 (0.22 at the spectrum's longest wavelength), 40 nodes
/// let plan = pupil_samples_for(1e-4, 0.22, 40)?;
/// assert_eq!((plan.coarse(), plan.samples), (64, 128));
/// // the mean MTF at N/2 and N (here made up), then the verdict
/// let estimate = plan.extrapolate(0.43216, 0.43218);
/// assert!(estimate.converged && estimate.value > 0.43218);
/// // 1e-7 would need N ≈ 34 000: refused, with the numbers
/// let e = pupil_samples_for(1e-7, 0.22, 40).unwrap_err();
/// assert!(e.to_string().contains("1e-7"), "{e}");
/// # Ok::<(), optics::Error>(())
/// ```
pub fn pupil_samples_for(tolerance: f64, s_max: f64, grids: usize) -> Result<SamplingPlan, Error> {
    if !(tolerance > 0.0 && tolerance < 1.0) {
        return Err(Error::InvalidParameter { name: "tolerance", value: tolerance, expected: "in (0, 1)" });
    }
    if !(s_max > 0.0 && s_max <= 1.0) {
        return Err(Error::InvalidParameter { name: "s_max", value: s_max, expected: "in (0, 1]" });
    }
    if grids == 0 {
        return Err(Error::InvalidParameter { name: "OTF grids", value: 0.0, expected: "at least one" });
    }
    // the memory limit: the largest N whose `grids` grids fit the budget
    let mut limit = MAX_CHOSEN_SAMPLES;
    while limit > MIN_CHOSEN_SAMPLES && grids as f64 * grid_bytes(limit, s_max) > crate::FFT_MEMORY_BUDGET {
        limit -= 2;
    }
    let (cr, qr) = EXTRAPOLATED_MODEL;
    let wanted = ((SAFETY * cr / tolerance).powf(1.0 / qr).ceil() as usize).max(MIN_CHOSEN_SAMPLES);
    let wanted = wanted + wanted % 2;
    let plan = SamplingPlan { samples: wanted, tolerance, limit, s_max, rule: ErrorRule::Richardson };
    if wanted > limit || grids as f64 * grid_bytes(wanted, s_max) > crate::FFT_MEMORY_BUDGET {
        return Err(plan.unreachable(wanted, reachable(limit)));
    }
    // the largest even N with the same padded length: more accuracy for the same FFTs
    let padded = fast_fft_len(wanted + max_lag(wanted, s_max));
    let mut samples = wanted;
    while samples + 2 <= limit && fast_fft_len(samples + 2 + max_lag(samples + 2, s_max)) == padded {
        samples += 2;
    }
    Ok(SamplingPlan { samples, ..plan })
}

/// The observed convergence order of three levels `N/4, N/2, N`:
/// `log2(|M_{N/2} − M_{N/4}| / |M_N − M_{N/2}|)` (infinite when the last two agree exactly).
pub fn observed_order(quarter: f64, half: f64, full: f64) -> f64 {
    ((half - quarter).abs() / (full - half).abs()).log2()
}
