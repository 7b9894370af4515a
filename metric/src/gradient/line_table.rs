//! A line's wavelength on a lens whose one imaging order is a table against wavelength
//! (`optics::Pupil::Table`: a PSF stack, a tabulated OTF; docs/physics.md, "Gradients: a line's
//! wavelength and a blackbody's temperature", a line's wavelength on a table).
//!
//! The table is linear in λ between its wavelengths (a stack's slices, a table's rows), and so
//! are the efficiency and transmission curves between their rows: the lens's breakpoints
//! (`LensModel::breakpoints`). Between two of them, `a < c < b`, each is its interpolation, so
//! at the line's wavelength `c`
//! - the OTF at a fixed frequency (the table's frequencies are absolute, at the detector: no
//!   frequency scale moves with c) moves by the interpolation's slope on the stack's own OTFs,
//!   `∂T/∂c = (T(λ_k, ν, φ) − T(λ_{k−1}, ν, φ))/(λ_k − λ_{k−1})` for the slices `λ_{k−1} < c < λ_k`
//!   beside it, read on the same frequency nodes and azimuths as the value, and the one order's
//!   `|O| = |T|` (its image shift turns the OTF's phase alone) by `sign(T) ∂T/∂c`;
//! - `τ` and `T` by their slopes `(τ(b) − τ(a))/(b − a)`.
//!
//! At a breakpoint the value has a kink (the slopes on either side differ): refused, naming it.
//! Beyond the outermost breakpoints every factor is constant (the end slices' OTF standing, a
//! curve's table zero beyond its rows): each slope is 0 there.

use super::Parameter;
use crate::{Error, Scene};

/// What a line's wavelength moves on a tabulated order: `(∂ln τ/∂c, ∂ln T/∂c, ∂G/∂c)`, per m,
/// `G` the mean MTF (or, with `noise`, its mean with each frequency's weight divided by `n(ν)`).
pub(super) struct OnTable {
    pub ln_efficiency: f64,
    pub ln_transmission: f64,
    pub mean: f64,
}

/// The line's partials on one tabulated order at its wavelength `c` (module docs); `None` where
/// the lens's orders at `c` are not one table (another rule applies). Refused, naming why, at a
/// breakpoint, or where the value's engine gives no lane (the FFT path).
pub(super) fn line_on_table(
    scene: &Scene,
    c: f64,
    noise: Option<&optics::NoiseShape>,
) -> Result<Option<OnTable>, Error> {
    let lens = scene.lens();
    let field = scene.field();
    let orders = lens.orders(c, field);
    let table = match &orders[..] {
        [o] => match &o.pupil {
            optics::Pupil::Table(t) => std::sync::Arc::clone(t),
            _ => return Ok(None),
        },
        _ => return Ok(None),
    };
    let p = Parameter::SpectrumCenter;
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let family = lens.describe();
    let breakpoints = lens.breakpoints();
    // a breakpoint at c, to the rounding of the keys' nm → m
    if let Some(b) = breakpoints.iter().find(|&&b| (b - c).abs() <= 1e-12 * c) {
        return Err(not_smooth(format!(
            "{family}: the line's wavelength {} nm is a breakpoint of the OTF's interpolation in λ (a slice's or a \
             table row's wavelength, or a row of the efficiency or transmission curve): the OTF and the curves are \
             linear on either side with different slopes, so the ASNR has a kink there; a line between two \
             breakpoints is differentiable",
            optics::round_for_display(b * 1e9)
        )));
    }
    // the curves' slopes between the breakpoints beside c (0 beyond the outermost)
    let below = breakpoints.iter().copied().filter(|&b| b < c).fold(f64::NAN, f64::max);
    let above = breakpoints.iter().copied().filter(|&b| b > c).fold(f64::NAN, f64::min);
    let efficiency = |l: f64| lens.orders(l, field).first().map_or(0.0, |o| o.efficiency);
    let slope = |f: &dyn Fn(f64) -> f64| {
        if below.is_nan() || above.is_nan() { 0.0 } else { (f(above) - f(below)) / (above - below) }
    };
    let (tau, t) = (orders[0].efficiency, lens.transmission(c));
    let ln_efficiency = if tau > 0.0 { slope(&efficiency) / tau } else { 0.0 };
    let ln_transmission = if t > 0.0 { slope(&|l| lens.transmission(l)) / t } else { 0.0 };
    // the slices beside c: the table's interpolation slope (0 beyond its ends)
    let w = table.wavelengths();
    let slices = match w.partition_point(|&x| x <= c) {
        k if k == 0 || k == w.len() => None,
        k => Some((w[k - 1], w[k])),
    };
    let along_field = field.y_rad.atan2(field.x_rad);
    let lane = |nu: f64, azimuth: f64| -> f64 {
        let Some((lo, hi)) = slices else { return 0.0 };
        let from_field = azimuth - along_field;
        let at = table.value(c, nu, from_field);
        if at == 0.0 {
            return 0.0;
        }
        let d = (table.value(hi, nu, from_field) - table.value(lo, nu, from_field)) / (hi - lo);
        at.signum() * d
    };
    let detected = crate::evaluate::detected_spectrum(scene);
    let found = super::on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        poly.mean_mtf_and_modulus_lane(along_field, noise, &lane)
    });
    let Some((_, mean, _)) = found else {
        return Err(not_smooth(format!(
            "{family}: a line's wavelength on a tabulated order is followed on the value's adaptive frequency rule \
             (the line's exact 1-D engine); this scene's engine is not that"
        )));
    };
    Ok(Some(OnTable { ln_efficiency, ln_transmission, mean }))
}

/// Why a line at `c` on a lens with a design band (the dispersion-engineered lens) is not
/// differentiable, where it sits on a band edge or outside the band: the efficiency's window has
/// its kink at each edge (docs/physics.md, "Gradients: the dispersion-engineered lens"), and no
/// light is imaged outside. `None` strictly inside the band, or without one.
pub(super) fn off_design_band(lens: &dyn optics::LensModel, c: f64) -> Option<String> {
    let (lo, hi) = lens.design_band()?;
    let nm = |x: f64| optics::round_for_display(x * 1e9);
    let on_edge = [lo, hi].into_iter().find(|&x| (x - c).abs() <= 1e-12 * c);
    match on_edge {
        Some(x) => Some(format!(
            "the line's wavelength {} nm is an edge of the design band {}–{} nm, where the efficiency's window \
             has its kink (the lens images nothing outside the band): the ASNR is not differentiable there; a line \
             strictly inside the band is",
            nm(x),
            nm(lo),
            nm(hi)
        )),
        None if c < lo || c > hi => Some(format!(
            "the line's wavelength {} nm is outside the design band {}–{} nm, where the lens images nothing",
            nm(c),
            nm(lo),
            nm(hi)
        )),
        None => None,
    }
}
