//! The F-number and the focal length of a lens whose imaging order is a composite pupil of
//! zones on the FFT path (a segmented multiplexed lens, `optics::Pupil::Zones`), on and off axis
//! (docs/physics.md, "Gradients: the multiplexed lens").
//!
//! Zone `j`'s wavefront is its own defocus `W020_j = (1 − λ/λ_j) K`, `K = f0/(8F#²)`, and its
//! own tilt `t_j = Δ_j NA` for its image shift `Δ_j = f0 tan θ (λ_j/λ − 1)` (the lateral
//! colour), in full-aperture coordinates; the zones' outlines do not depend on F# or f0. So at
//! fixed `K` and `Δ_j` the OTF is a function of `s = νλF#` and of `νΔ_j`, as the chromatic
//! lens's off axis ("Gradients: the F-number and the focal length off axis"), with the lanes
//! per zone: `D_K` ([`optics::WavefrontDirection::Defocus`], every zone's defocus moving by
//! itself) and `D_Δ` ([`optics::WavefrontDirection::ImageShift`], every zone's tilt by itself),
//! forward mode through the FFT on the value's own grids, levels, frequencies and azimuths:
//!
//! `∂M̄/∂ln F# = D_s − 2 D_K − D_Δ`, `∂M̄/∂ln f0 = D_K + D_Δ`, with `D_s` the frequency
//! scale's term at fixed pupils: each grid read at `s = νλF#` moving with F# along the value's
//! fixed rule (`optics::Polychromatic::mean_mtf_over_azimuth_scale_lane`), the discrete rule's
//! exact derivative (by parts it is `P(ν_N)|O(ν_N)|‾ − M̄ − P_ν`, the continuous rule's
//! identity, which the fixed rule on the interpolated grids holds only to its own error's rate).

use super::Parameter;
use crate::evaluate::Evaluation;
use crate::{Error, Scene};

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` (module docs) where the value's engine is the FFT path and an
/// imaging order of the scene's lens is a composite pupil of zones; `None` where it is not
/// (another pupil, or another engine: those keys' other rules apply). Refused (naming why)
/// where the FFT path does not carry the zones' lanes: a zone whose wavefront is more than a
/// defocus, an order-level image shift.
pub(super) fn aperture_on_zones(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<Option<(f64, f64)>, Error> {
    let lens = scene.lens();
    let field = scene.field();
    let lambda = e.mean_wavelength_nm * 1e-9;
    let zoned = lens.orders(lambda, field).iter().any(|o| matches!(o.pupil, optics::Pupil::Zones(_)));
    if !zoned {
        return Ok(None);
    }
    let not_smooth = |reason: &str| Error::NotDifferentiable { parameter: p.describe(), reason: reason.to_owned() };
    let detected = crate::evaluate::detected_spectrum(scene);
    if !e.numerics.engine.starts_with("fft") || detected.as_line().is_some() {
        return Err(not_smooth(
            "a composite pupil of zones is differentiated on the FFT path of a band (each zone's defocus and tilt \
             lanes); this evaluation's engine is another (a line spectrum's grids)",
        ));
    }
    super::with_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let first = field.y_rad.atan2(field.x_rad);
        // on axis no zone is tilted: the shift lane is 0 (not computed)
        let directions: &[optics::WavefrontDirection] = if field.is_on_axis() {
            &[optics::WavefrontDirection::Defocus]
        } else {
            &[optics::WavefrontDirection::Defocus, optics::WavefrontDirection::ImageShift]
        };
        let Some((_, lanes)) = poly.mean_mtf_over_azimuth_and_gradient(first, directions)? else {
            return Err(not_smooth(
                "the FFT path did not carry the zones' defocus and tilt lanes here: they are computed for zones whose \
                 wavefront is a defocus (and a tilt for the zone's image shift), through an order without an image \
                 shift of its own",
            ));
        };
        let d_k = lanes[0];
        let d_shift = lanes.get(1).copied().unwrap_or(0.0);
        // the frequency scale s = νλF# at fixed pupils: each grid's reading moving with F# on the
        // value's own rule (the discrete rule's exact term, where by parts it would be
        // P(ν_N)|O(ν_N)|‾ − M̄ − P_ν, the continuous rule's)
        let Some(d_s) = poly.mean_mtf_over_azimuth_scale_lane(first) else {
            return Err(not_smooth("the FFT path did not give the frequency scale's lane s = νλF# here"));
        };
        Ok(Some((d_s - 2.0 * d_k - d_shift, d_k + d_shift)))
    })
}
