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
//!
//! A channel's wavelength λ_j and own efficiency η_j move zone `j` alone
//! ([`zone_key_gradient`]): its defocus `∂W020_j/∂ln λ_j = (λ/λ_j) K` and tilt
//! `∂Δ_j/∂ln λ_j = f0 tan θ λ_j/λ`, or its amplitude `∂√η_j/∂ln η_j = √η_j/2` and the order's
//! efficiency `∂τ/∂ln η_j = a_j η_j` (`optics::LensModel::zone_rates`), a lane with a rate on
//! zone `j` and 0 elsewhere on the value's FFT path ([`optics::WavefrontDirection::Zone`]).
//! The field angles ride [`optics::WavefrontDirection::FieldAngle`] with every zone's own rate
//! `f0 sec²θ (λ_j/λ − 1)` (the value's grid lanes, `Parameter::FieldAngle`). A zone's area
//! fraction a_j moves the zones' edges from zone `j` on (rings' radii `√c_k`, wedges' angles
//! `2π c_k`, `c_k = Σ_{i≤k} a_i`) and the order's efficiency by `a_j η_j` per `ln a_j`: a lane
//! with each zone's edge rates, every edge pixel's area fraction moving by its edge's length
//! (`optics::fft::SampledZones::rates_derivative`).

use super::{Gradient, Parameter};
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

/// The evaluation of `scene` and the derivatives of its ASNR, mean MTF, SNR0 and photoelectrons
/// with respect to `key` (per unit of the key: `ln λ_j` or `ln η_j` of one channel of a
/// segmented lens), where an imaging order of the lens is a composite pupil of zones on the FFT
/// path (module docs; docs/physics.md, "Gradients: the multiplexed lens"): `∂M̄` the zone lane on
/// the value's grids, levels, frequencies and azimuths, the normalization's motion `Σ w ∂τ_o`
/// included; `∂N = N ∂ln(∫ρ Σ τ_o)` on the engine's nodes
/// ([`optics::Polychromatic::zone_signal_rate`]); `∂SNR0 = (∂SNR0/∂N) ∂N` (the stray light
/// `N_T − N` by `−∂N`, T held) and `∂ASNR = ∂SNR0 G + SNR0 ∂G`, as every key's. Over a
/// `[[fields]]` list the weighted mean of each point's.
///
/// # Errors
/// The evaluation's, and [`Error::NotDifferentiable`] where the lens gives no zone rates for
/// `key` (naming why), the value is not on the FFT path of a band, under a noise spectrum, or
/// where the pixel saturates or there is no signal.
pub fn zone_key_gradient(scene: &Scene, key: optics::ZoneKey) -> Result<Gradient, Error> {
    let parameter = match key {
        optics::ZoneKey::ChannelWavelength(_) => "a channel's wavelength",
        optics::ZoneKey::ChannelEfficiency(_) => "a channel's own efficiency",
        optics::ZoneKey::FieldAngle(_) => "a field angle",
        optics::ZoneKey::AreaFraction(_) => "a zone's area fraction",
    };
    let not_smooth = |reason: &str| Error::NotDifferentiable { parameter, reason: reason.to_owned() };
    if !scene.fields().is_empty() {
        let evaluation = crate::evaluate(scene)?;
        let largest = scene.fields().iter().map(|f| f.1).fold(0.0, f64::max);
        let total: f64 = scene.fields().iter().map(|f| f.1 / largest).sum();
        let mut sum = [0.0; 4];
        for &(field, weight) in scene.fields() {
            let g = zone_key_gradient(&scene.single_field(field), key)?;
            let share = weight / largest / total;
            for (s, d) in sum.iter_mut().zip([g.asnr[0], g.mean_mtf[0], g.snr0[0], g.photoelectrons[0]]) {
                *s += share * d;
            }
        }
        let [asnr, mean_mtf, snr0, photoelectrons] = sum.map(|d| vec![d]);
        return Ok(Gradient { evaluation, asnr, mean_mtf, snr0, photoelectrons });
    }
    let field = scene.field();
    // (the lens's refusals do not depend on the wavelength: asked before the evaluation)
    let lambda = scene.lens().design_wavelength().unwrap_or(5.5e-7);
    if scene.lens().zone_rates(lambda, field, key).is_none() {
        if let optics::ZoneKey::AreaFraction(_) = key {
            return Err(not_smooth(
                "the lens gives no zones' rates for it here: the last zone's area fraction where the fractions sum \
                 to 1 (the zones fill the aperture: its growth would leave it, and every other fraction's change is \
                 absorbed by it), or a mask layout's zone (its areas are measured from the map, not parameters)",
            ));
        }
        return Err(not_smooth(
            "the lens gives no zones' rates for it here: a channel's wavelength with lens.other_channels = \
             \"background\" moves the channels' band edges, where each zone's light switches between signal and \
             background (kinks of the integrand over λ, not carried), and a channel's own efficiency at 0 (√η has no \
             derivative there)",
        ));
    }
    let e = crate::evaluate(scene)?;
    let detected = crate::evaluate::detected_spectrum(scene);
    if !e.numerics.engine.starts_with("fft") || detected.as_line().is_some() {
        return Err(not_smooth(
            "a composite pupil of zones is differentiated on the FFT path of a band (a lane on the zone's field); \
             this evaluation's engine is another (a line spectrum's grids)",
        ));
    }
    if scene.camera().noise_spectrum().is_some() {
        return Err(not_smooth(
            "the zones' lanes are taken on the white mean MTF; with camera.noise_spectrum the weighted mean's \
             lane is not computed for a composite pupil of zones",
        ));
    }
    let (d_mtf, rate) = super::with_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let first = field.y_rad.atan2(field.x_rad);
        let lane = poly.mean_mtf_over_azimuth_and_gradient(first, &[optics::WavefrontDirection::Zone(key)])?;
        let (Some((_, lanes)), Some(rate)) = (lane, poly.zone_signal_rate(key)) else {
            return Err(not_smooth(
                "the FFT path did not carry the zone's lane here: it is computed for zones whose wavefront is a \
                 defocus (and a tilt for the zone's image shift), through an order without an image shift of its own",
            ));
        };
        Ok((lanes[0], rate))
    })?;
    super::multiplexed::one_key(scene, e, rate, d_mtf, d_mtf, not_smooth)
}
