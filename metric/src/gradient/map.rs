//! The F-number and the focal length of a lens given as a designer's phase map
//! (`optics::Pupil::Map`, `lens.phase_map`) on the FFT path, on axis (docs/physics.md,
//! "Gradients: a phase map's pitch and aperture").
//!
//! The map's cells are fixed in metres (pitch p) and the aperture's radius is `R = f0/(2F#)`: in
//! the pupil's units (of R) the cells' edges sit at multiples of `ρ = p/R`, and the detector
//! distance `z = f0` sets each cell's reference sphere and design-order share. So at fixed p the
//! value moves with `R` through the cells' edges alone (`D_R`,
//! `optics::map::MapScale::Radius`: their motion `∂e/∂ln R = −e`, the cells' jumps along them),
//! with `z` through the cells' values alone (`D_z`, `optics::map::MapScale::Distance`), and with
//! `F#` through the frequency scale `s = νλF#` too (`D_s`, each grid's reading moving with F#
//! on the value's own fixed rule, `optics::Polychromatic::mean_mtf_over_azimuth_scale_lane`).
//! With `∂ln R/∂ln F# = −1` and `∂ln R/∂ln f0 = ∂ln z/∂ln f0 = 1`:
//!
//! `∂M̄/∂ln F# = D_s − D_R`, `∂M̄/∂ln f0 = D_R + D_z`; N ∝ 1/F#² as for every lens.

use super::Parameter;
use crate::evaluate::Evaluation;
use crate::{Error, Scene};

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` (module docs) where an imaging order of the scene's lens is a
/// designer's phase map; `None` where none is (another pupil: those keys' other rules apply).
/// Refused (naming why) off axis, under a line or a noise spectrum, or where the FFT path does not carry the map's
/// lanes.
pub(super) fn aperture_on_map(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<Option<(f64, f64)>, Error> {
    let lens = scene.lens();
    let field = scene.field();
    let lambda = e.mean_wavelength_nm * 1e-9;
    let mapped = lens.orders(lambda, field).iter().any(|o| match &o.pupil {
        optics::Pupil::Map(m) => m.phase_map().is_some(),
        _ => false,
    });
    if !mapped {
        return Ok(None);
    }
    let not_smooth = |reason: &str| Error::NotDifferentiable { parameter: p.describe(), reason: reason.to_owned() };
    let detected = crate::evaluate::detected_spectrum(scene);
    if scene.camera().noise_spectrum().is_some() {
        return Err(not_smooth(
            "a phase map's aperture is differentiated with a white noise spectrum only (its lanes under \
             camera.noise_spectrum are not checked yet)",
        ));
    }
    if !e.numerics.engine.starts_with("fft") || detected.as_line().is_some() || !field.is_on_axis() {
        return Err(not_smooth(
            "a phase map's aperture is differentiated on the FFT path of a band, on axis (its cells' edges moving \
             across the pupil with R = f0/(2F#), their values with the detector distance f0); this scene is not that \
             (off axis, or a line spectrum's grids)",
        ));
    }
    super::with_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let first = field.y_rad.atan2(field.x_rad);
        let directions = [
            optics::WavefrontDirection::MapScale(optics::map::MapScale::Radius),
            optics::WavefrontDirection::MapScale(optics::map::MapScale::Distance),
        ];
        let Some((_, lanes)) = poly.mean_mtf_over_azimuth_and_gradient(first, &directions)? else {
            return Err(not_smooth(
                "the FFT path did not carry the phase map's lanes here (they are computed on axis, for a designer's \
                 map without Zernike terms)",
            ));
        };
        let (d_radius, d_distance) = (lanes[0], lanes[1]);
        // the frequency scale s = νλF# at fixed pupils, on the value's own rule
        let Some(d_s) = poly.mean_mtf_over_azimuth_scale_lane(first) else {
            return Err(not_smooth("the FFT path did not give the frequency scale's lane s = νλF# here"));
        };
        Ok(Some((d_s - d_radius, d_radius + d_distance)))
    })
}
