//! Convergence of the FFT path against the exact 1-D path.

use std::time::Instant;

use super::{Aberrations, Aperture, Otf, OtfPlan, SampledPupil};
use crate::{defocus_otf, mtf_diffraction_limited_mean, reference};

/// The exact mean MTF `(1/s_max) ∫_0^{s_max} |OTF(s, w)| ds` of a centred circular pupil with
/// defocus `w` waves, from [`defocus_otf`] by adaptive Gauss–Kronrod split at the OTF's sign
/// changes ([`reference::integrate_modulus`]), to about 1e-13; closed form for `w = 0`.
pub fn defocus_mean_mtf(w: f64, s_max: f64) -> f64 {
    if w == 0.0 {
        return mtf_diffraction_limited_mean(s_max);
    }
    let upper = s_max.min(1.0);
    let q = reference::integrate_modulus(reference::GK21, |s| defocus_otf(s, w), |_| 1.0, &[0.0, upper], 1e-15, 1e-13);
    q.value / s_max
}

/// Error of the FFT path's mean MTF along the `+x` slice against [`defocus_mean_mtf`], for a
/// centred circle with defocus `defocus_waves`, up to `s_max`, for each pupil sampling in
/// `sizes`: `(N, |error|, seconds per evaluation)`. The time is the best of three runs of
/// [`OtfPlan::otf`] + [`Otf::mean_mtf`] (plan creation and pupil sampling excluded: both are
/// done once per lens, not per wavelength).
pub fn convergence_table(defocus_waves: f64, s_max: f64, sizes: &[usize]) -> Vec<(usize, f64, f64)> {
    let wavelength = 1e-6;
    let exact = defocus_mean_mtf(defocus_waves, s_max);
    let mut out = Vec::new();
    for &n in sizes {
        let Ok(mut plan) = OtfPlan::new(n, s_max) else { continue };
        let Ok(pupil) = SampledPupil::new(n, &Aperture::circle(), &Aberrations::defocus(defocus_waves * wavelength))
        else {
            continue;
        };
        let mut otf = Otf::new();
        let mut best = f64::INFINITY;
        let mut mean = 0.0;
        for _ in 0..3 {
            let t = Instant::now();
            plan.otf(&pupil, wavelength, &mut otf);
            mean = otf.mean_mtf(0.0, s_max);
            best = best.min(t.elapsed().as_secs_f64());
        }
        out.push((n, (mean - exact).abs(), best));
    }
    out
}
