//! A slow, obviously correct reference for the paper's lens behind a decentred iris (SI Fig. S3),
//! written for the report (optics::reference has none; this is where it would go).
//!
//! The chromatic lens is defocus only, `W = W020(λ) ρ²` with ρ measured from the lens axis in
//! units of the pupil radius R. A full-size iris decentred by `d` along x (`Aperture::circle()
//! .decentred(d, 0)`) passes the points `ρ = (d, 0) + u` with `|u| ≤ 1`, where
//! `W = W020 (d² + 2 d u_x + |u|²)`: a piston, a tilt `2 d W020 u_x` and the same defocus
//! `W020 |u|²` on a centred circle of radius R. So the iris is exactly the centred circular pupil
//! with defocus plus a wavelength-dependent tilt, which shifts the image by
//! `Δ(λ) = −(f0/R) · 2 d W020(λ) = −4 d F# W020(λ)` along x, and multiplies the OTF along x by
//! `exp(−2πi ν Δ)`; with `a = 8π w s = π ν f0 (1 − λ/λ0)/F#` the argument of the defocus OTF,
//! that phase is `−d · a`. Along y the phase is 0 and the OTF is the centred lens's.
//!
//! The tangential (along x) mean MTF is then
//! `(1/ν_N) ∫_0^{ν_N} |∫ ρ(λ) OTF(ν λ F#, w(λ)) e^{i d a(λ, ν)} dλ| dν / ∫ ρ dλ`,
//! computed here by nested adaptive Gauss–Kronrod (`optics::reference::integrate`, G10–K21)
//! with the printed y-form OTF `optics::reference::otf_defocus` (1e-13 absolute) at every node:
//! the real and imaginary parts of the inner integral separately, initial λ panels of two periods
//! of the combined oscillation `(1 + d) |∂a/∂λ|`. The sagittal mean is the centred lens's
//! `optics::reference::mean_mtf`, and `metric::evaluate` reports their average.

use std::f64::consts::PI;

use optics::reference::{GK21, integrate, otf_defocus};

use crate::{Case, F0, LAMBDA0, PIXEL_PITCH};

/// Smallest absolute tolerance of the inner integral, normalized OTF units (the y-form OTF is
/// itself accurate to 1e-13).
const MIN_INNER_TOL: f64 = 2e-13;

/// The tangential mean MTF of the case through the iris decentred by `decentre` radii, to about
/// `rel_tol` relative (not below ~1e-12).
pub(crate) fn tangential_mean_mtf(case: &Case, decentre: f64, rel_tol: f64) -> f64 {
    let sigma = case.sigma();
    let density = |l: f64| l * (-0.5 * ((l - LAMBDA0) / sigma).powi(2)).exp();
    let (lo, hi) = ((LAMBDA0 - 12.0 * sigma).max(1e-3 * LAMBDA0), LAMBDA0 + 12.0 * sigma);
    let pieces: Vec<f64> = (0..=64).map(|k| lo + (hi - lo) * f64::from(k) / 64.0).collect();
    let norm = integrate(GK21, density, &pieces, 0.0, 1e-14).value;
    let fnum = case.f_number;
    let nyquist = 0.5 / PIXEL_PITCH;
    let inner_tol = (0.05 * rel_tol).max(MIN_INNER_TOL);
    // the complex polychromatic OTF along x at ν, normalized: its modulus
    let modulus = |nu: f64| -> f64 {
        if nu == 0.0 {
            return 1.0;
        }
        let top = hi.min(1.0 / (nu * fnum));
        if top <= lo {
            return 0.0;
        }
        let slope = PI * nu * F0 / (fnum * LAMBDA0) * (1.0 + decentre.abs());
        let mut points = vec![top];
        for w in [lo, LAMBDA0.clamp(lo, top), top].windows(2) {
            if w[1] <= w[0] {
                continue;
            }
            let n = ((slope * (w[1] - w[0]) / (2.0 * PI) * 0.5).ceil() as usize).max(8);
            points.extend((0..n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        }
        let part = |phase: fn(f64) -> f64| {
            let f = |l: f64| {
                let s = nu * l * fnum;
                let w = case.waves(l);
                let a = PI * nu * F0 * (1.0 - l / LAMBDA0) / fnum;
                density(l) * otf_defocus(s, w) * phase(decentre * a)
            };
            integrate(GK21, f, &points, inner_tol * norm, 0.0).value / norm
        };
        let (re, im) = (part(f64::cos), part(f64::sin));
        re.hypot(im)
    };
    let points: Vec<f64> = (0..=4).map(|k| nyquist * f64::from(k) / 4.0).collect();
    integrate(GK21, modulus, &points, 0.1 * inner_tol * nyquist, 0.5 * rel_tol).value / nyquist
}
