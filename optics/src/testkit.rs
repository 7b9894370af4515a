//! Conformance checks for [`LensModel`] implementations (feature `testkit`).
//!
//! A downstream lens family calls [`check_lens`] from its tests: whatever the lens does, its
//! polychromatic MTF must be 1 at zero frequency, within `[0, 1]`, zero past the cutoff of the
//! shortest wavelength, and finite everywhere.

use radiometry::Spectrum;

use crate::{Field, LensModel, Polychromatic};

/// Checks the transfer-function invariants of `lens` over the `detected` spectrum.
/// Returns a description of the first violation.
pub fn check_lens(lens: &dyn LensModel, detected: &Spectrum) -> Result<(), String> {
    let f_number = lens.f_number();
    if !(f_number.is_finite() && f_number > 0.0) {
        return Err(format!("f_number() = {f_number}: expected finite and > 0"));
    }
    let cutoff =
        crate::highest_cutoff(lens, detected).map_err(|e| format!("cannot prepare the polychromatic OTF: {e}"))?;
    let poly = Polychromatic::new(lens, detected, Field::ON_AXIS, cutoff, None)
        .map_err(|e| format!("cannot prepare the polychromatic OTF: {e}"))?;
    let at_zero = poly.mtf(0.0);
    if (at_zero - 1.0).abs() > 1e-12 {
        return Err(format!("MTF(0) = {at_zero}, expected 1"));
    }
    for k in 0..=50 {
        let nu = cutoff * k as f64 / 50.0;
        let m = poly.mtf(nu);
        if !m.is_finite() || !(-1e-12..=1.0 + 1e-12).contains(&m) {
            return Err(format!("MTF({nu:e} cycles/m) = {m}: expected finite, in [0, 1]"));
        }
    }
    for factor in [1.0 + 1e-9, 1.5, 4.0] {
        let m = poly.mtf(cutoff * factor);
        if m != 0.0 {
            return Err(format!("MTF = {m} at {factor} × the cutoff {cutoff:e} cycles/m: expected 0"));
        }
    }
    Ok(())
}
