//! Validity of the Fraunhofer (far-field) model of a defocused image, paper SI eq. S15.
//!
//! The paper checked that the Fraunhofer MTF of its chromatic-defocus PSFs is valid while the
//! geometric blur radius `x = |Δf| · NA` stays below a threshold (0.25 mm for its lens). With
//! `W020 = Δz NA²/2` the blur radius of any order is `2 |W020| / NA`; for the chromatic lens,
//! `Δf = f0 Δλ/λ0` gives eq. S15, `x = f0 (Δλ/λ0) NA`.

use crate::lens::{Field, LensModel};

/// Geometric blur radius (m) of the worst imaging order at `wavelength_m`: `2 |W020| / NA`.
pub fn blur_radius(lens: &dyn LensModel, wavelength_m: f64) -> f64 {
    let na = lens.numerical_aperture();
    lens.orders(wavelength_m, Field::ON_AXIS).iter().map(|o| 2.0 * o.wavefront.defocus_m.abs() / na).fold(0.0, f64::max)
}

/// The largest wavelength shift from `reference_m` (usually the design wavelength) on either side
/// whose blur radius stays within `threshold_m`: eq. S15 solved for `Δλ`, by bisection on
/// [`blur_radius`], so it holds for any lens model with a blur radius that grows with the shift.
///
/// Returns `None` when the blur stays within the threshold over the searched range
/// (`0 < λ ≤ 10 λ_ref`), i.e. no limit applies.
pub fn max_wavelength_shift(lens: &dyn LensModel, reference_m: f64, threshold_m: f64) -> Option<f64> {
    let exceeds = |shift: f64, sign: f64| blur_radius(lens, reference_m + sign * shift) > threshold_m;
    let side = |sign: f64, max_shift: f64| -> Option<f64> {
        if !exceeds(max_shift, sign) {
            return None;
        }
        let (mut lo, mut hi) = (0.0, max_shift);
        if exceeds(0.0, sign) {
            return Some(0.0);
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if exceeds(mid, sign) {
                hi = mid;
            } else {
                lo = mid;
            }
            if hi - lo <= 1e-15 * reference_m {
                break;
            }
        }
        Some(0.5 * (lo + hi))
    };
    let below = side(-1.0, reference_m * (1.0 - 1e-9));
    let above = side(1.0, 9.0 * reference_m);
    match (below, above) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}
