//! The noise-weighted parts of the keys that move the OTF's frequency scale (the F-number, a
//! line's wavelength) or the pixel's sinc under a non-white noise
//! spectrum `n(ν)` (`camera.noise_spectrum`; docs/physics.md, "Gradients under a noise
//! spectrum"). `G = (1/ν_N) ∫_0^{ν_N} P |O| / n dν` with `n` fixed in cycles/mm: where a key
//! scales the OTF's frequency, the integration by parts that turns `ν ∂_ν|O|` into one value at
//! Nyquist takes the derivative of `νP/n`, so besides `P(ν_N)|O(ν_N)|/n(ν_N)` and `G` it leaves
//! `(1/ν_N) ∫ P |O| (νP′/P − νn′/n)/n dν`, which is integrated here on panels split at the
//! table's rows (where `n′` jumps) and at the sign changes of `O` (the kinks of `|O|`).

use super::{DirectionalRule, Parameter, noise_row_ends, on_value_engine, seidel_lane_at_zero, seidel_terms_zero};
use crate::evaluate::Evaluation;
use crate::{Error, Scene};

/// `νP′(ν)/P(ν) = x cot x − 1` of the pixel MTF `P = sinc(x)`, `x = πpν` (`pitch` p in m, ν in
/// cycles/m; docs/physics.md, "Gradients: the pixel pitch with the pixel MTF"): its series
/// `−x²/3 − x⁴/45` below `x = 1e-3`, where the quotient loses digits.
fn pixel_log_slope(pitch: f64, nu: f64) -> f64 {
    let x = std::f64::consts::PI * pitch * nu;
    if x.abs() < 1e-3 {
        let x2 = x * x;
        -x2 / 3.0 - x2 * x2 / 45.0
    } else {
        x / x.tan() - 1.0
    }
}

/// `(1/ν_N) ∫_0^{ν_N} P(ν) |O(ν)| w(ν) dν` on the value's own engine (metric's `evaluate`: its
/// lens, spectrum, field and settings; `P` the pixel MTF where the camera applies it), averaged
/// over the value's directions where the OTF depends on direction ([`DirectionalRule`], its
/// panels on each interval between the table's rows, where `w` jumps). Where the OTF is rotationally symmetric:
/// composite 16-point Gauss–Legendre panels on each interval between the noise table's rows
/// (where `w` has its kinks), each panel split at a sign change of `O` (the kink of `|O|`,
/// bracketed to 1e-15 of its frequency), from 4 panels an interval doubled until the integral
/// moves by at most the tolerance times `max(|integral|, scale)`, or 1024 panels. Refused,
/// naming `p`, where the engine is not built.
pub(super) fn weighted_mtf_integral(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    scale: f64,
    weight: &dyn Fn(f64) -> f64,
) -> Result<f64, Error> {
    let camera = scene.camera();
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let tolerance = scene.options().settings().tolerance;
    let detected = crate::evaluate::detected_spectrum(scene);
    let pix = |nu: f64| pixel.map_or(1.0, |pitch| optics::pixel_mtf(pitch, nu));
    on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        if poly.has_pupil_grid() || poly.direction_dependent() {
            let rule = DirectionalRule::of(scene, poly, tolerance);
            // pieces between the table's rows (where `w` jumps with n′)
            let ends = noise_row_ends(camera.noise_spectrum(), nyquist);
            let [m, _, _] = rule.mean_split(&ends, [1.0, 0.0, 0.0], &|nu, azimuth| {
                [pix(nu) * poly.otf_along(nu, azimuth).norm() * weight(nu), 0.0, 0.0]
            });
            return Some(m);
        }
        let ends = noise_row_ends(camera.noise_spectrum(), nyquist);
        let piece = |a: f64, b: f64| -> f64 {
            let mut sum = 0.0;
            for &(x, wx) in optics::quad::rule() {
                let half = 0.5 * (b - a);
                let nu = 0.5 * (a + b) + half * x;
                sum += half * wx * pix(nu) * poly.otf(nu).abs() * weight(nu);
            }
            sum
        };
        let integrate = |panels: usize| -> f64 {
            let mut sum = 0.0;
            for w in ends.windows(2) {
                let h = (w[1] - w[0]) / panels as f64;
                let mut previous = (w[0], poly.otf(w[0]));
                for i in 1..=panels {
                    let nu = if i == panels { w[1] } else { w[0] + h * i as f64 };
                    let value = poly.otf(nu);
                    if value * previous.1 < 0.0 {
                        let (mut lo, mut hi) = (previous.0, nu);
                        while hi - lo > 1e-15 * hi {
                            let m = 0.5 * (lo + hi);
                            if poly.otf(m) * previous.1 > 0.0 {
                                lo = m;
                            } else {
                                hi = m;
                            }
                        }
                        let zero = 0.5 * (lo + hi);
                        sum += piece(previous.0, zero) + piece(zero, nu);
                    } else {
                        sum += piece(previous.0, nu);
                    }
                    previous = (nu, value);
                }
            }
            sum / nyquist
        };
        let mut panels = 4;
        let mut previous = integrate(panels);
        loop {
            panels *= 2;
            let next = integrate(panels);
            let change = (next - previous).abs();
            previous = next;
            if change <= tolerance * next.abs().max(scale) || panels >= 1024 {
                return Some(next);
            }
        }
    })
    .ok_or_else(|| Error::NotDifferentiable {
        parameter: p.describe(),
        reason: "with camera.noise_spectrum the frequency scale's term of the integration by parts is taken on the \
                 value's engine, which was not built here"
            .to_owned(),
    })
}

/// The noise-weighted mean `G = (1/ν_N) ∫ P |O| / n dν` the evaluation took.
fn weighted_mean(e: &Evaluation) -> f64 {
    e.asnr_mean / e.snr0
}

/// The pixel's sinc term of the white mean, `P_ν = (1/ν_N) ∫ ν P′ |O| dν` (0 without the pixel
/// MTF), on the value's own engine ([`weighted_mtf_integral`] with `νP′/P` as the weight): the
/// term of the integration by parts in ν that `∂M̄/∂ln F#` takes where its defocus lane is on
/// the reference rule (a wavelength's cutoff inside the frequency band).
pub(super) fn pixel_slope_white(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<f64, Error> {
    let camera = scene.camera();
    if !camera.pixel_mtf() {
        return Ok(0.0);
    }
    let pitch = camera.pixel_pitch();
    weighted_mtf_integral(scene, e, p, e.mean_mtf, &|nu| pixel_log_slope(pitch, nu))
}

/// The pixel's sinc term under the noise weight, `P̃_ν = (1/ν_N) ∫ ν P′ |O| / n dν` (0 without
/// the pixel MTF): with the pixel MTF, `∂G/∂ln p = G − MTF(ν_N)/n(ν_N) + P̃_ν` for the pixel
/// pitch (the sinc fixed in `ν/ν_N`, `O` and `n` in cycles/mm: by parts in `x = ν/ν_N`, no `n′`).
pub(super) fn pixel_slope_over_noise(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<f64, Error> {
    let camera = scene.camera();
    let (Some(shape), true) = (camera.noise_spectrum(), camera.pixel_mtf()) else {
        return Ok(0.0);
    };
    let pitch = camera.pixel_pitch();
    weighted_mtf_integral(scene, e, p, weighted_mean(e), &|nu| pixel_log_slope(pitch, nu) / shape.value(nu))
}

/// `∂G/∂ln s` where the OTF's frequency scales, `O(ν) → O(sν)` at `s = 1`, with the pixel MTF
/// `P`, the noise `n` and `ν_N` held (the F-number's normalized frequency `νλF#` at a fixed
/// wavefront, a line's `νcF#`): `(1/ν_N) ∫ P ν ∂_ν|O| / n dν`, by parts
///
/// ```text
/// P(ν_N)|O(ν_N)|/n(ν_N) − G − (1/ν_N) ∫ P |O| (νP′/P − νn′/n)/n dν
/// ```
///
/// (`νP/n` is continuous with `n`, its derivative jumping at the table's rows; `|O|` continuous
/// through its kinks), `edge` the system's `P(ν_N)|O(ν_N)|` as `mtf_at` gives it (averaged over
/// the directions where the OTF depends on direction). Without the noise spectrum it is the
/// white `edge − M̄ − P_ν`.
pub(super) fn frequency_scale_over_noise(scene: &Scene, e: &Evaluation, p: Parameter, edge: f64) -> Result<f64, Error> {
    let camera = scene.camera();
    let Some(shape) = camera.noise_spectrum() else {
        return Err(Error::NotDifferentiable {
            parameter: p.describe(),
            reason: "the scene has a white noise spectrum (camera.noise_spectrum not given)".to_owned(),
        });
    };
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let g = weighted_mean(e);
    let interior = weighted_mtf_integral(scene, e, p, g, &|nu| {
        let n = shape.value(nu);
        (pixel.map_or(0.0, |pitch| pixel_log_slope(pitch, nu)) - nu * shape.slope(nu) / n) / n
    })?;
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    Ok(edge / shape.value(nyquist) - g - interior)
}

/// `(∂G/∂ln F#, ∂G/∂ln f0)` under the noise spectrum, the weighted counterparts of
/// `aperture_lane_partials` and `aperture_partials_by_own_rule`: the frequency scale's term
/// ([`frequency_scale_over_noise`]) and the wavefront's lanes, each frequency's weight divided by
/// `n(ν)` — a phase lens's `[P, T, S]` on the value's noise-weighted pass of the radial engine
/// (`base`: where they start among its wavefront directions), `∂G/∂ln F# = S − (D̃_P + D̃_T)`,
/// `∂G/∂ln f0 = D̃_P + D̃_S`; otherwise `D̃_K` on the reference rule of the defocus lane, on axis,
/// every order the full circle with a defocus alone, `∂G/∂ln F# = S − 2 D̃_K`, `∂G/∂ln f0 = D̃_K`.
///
/// Where the phase lens's value is on the FFT path (`on_grid` > 0: off axis, or on axis with
/// Zernike terms of m ≠ 0), its lanes `[P, T, S]` and, off axis, the oblique wave's two
/// (`aperture_grid_directions`) are taken on the value's noise-weighted pass over azimuth:
/// `∂G/∂ln F# = S − (D̃_P + D̃_T + D̃_OR)`, `∂G/∂ln f0 = D̃_P + D̃_S + D̃_O`.
pub(super) fn aperture_over_noise(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    base: Option<usize>,
    on_grid: usize,
) -> Result<(f64, f64), Error> {
    let edge = crate::evaluate::mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
    let scale = frequency_scale_over_noise(scene, e, p, edge)?;
    if let (Some(b), true) = (base, on_grid > 0) {
        let directions = super::aperture_grid_directions(b, on_grid > 3);
        let lanes = crate::evaluate::noise_weighted_lanes(scene, false, &directions)?;
        let found = match &lanes.grid {
            crate::evaluate::GridGradient::Computed(all) => match *all.as_slice() {
                [d_p, d_t, d_s] => Some([d_p, d_t, d_s, 0.0, 0.0]),
                [d_p, d_t, d_s, d_or, d_o] => Some([d_p, d_t, d_s, d_or, d_o]),
                _ => None,
            },
            _ => None,
        };
        let Some([d_p, d_t, d_s, d_or, d_o]) = found else {
            return Err(Error::NotDifferentiable {
                parameter: p.describe(),
                reason: "with camera.noise_spectrum the FFT path's noise-weighted pass did not carry the \
                         aperture's lanes here"
                    .to_owned(),
            });
        };
        return Ok((scale - (d_p + d_t + d_or), d_p + d_s + d_o));
    }
    if let Some(b) = base {
        let lanes = crate::evaluate::noise_weighted_lanes(scene, true, &[])?;
        let Some(&[d_p, d_t, d_s]) = lanes.binary2.as_deref().and_then(|a| a.get(b..b + 3)) else {
            return Err(Error::NotDifferentiable {
                parameter: p.describe(),
                reason: "with camera.noise_spectrum the radial engine's noise-weighted pass did not carry the \
                         aperture's lanes here (an order through an iris, zones, a map or a table, or the FFT path)"
                    .to_owned(),
            });
        };
        return Ok((scale - (d_p + d_t), d_p + d_s));
    }
    if let Some((d_k, d_shift)) = aperture_lanes_over_noise(scene, shape_of(scene)) {
        return Ok((scale - 2.0 * d_k - d_shift, d_k + d_shift));
    }
    // (off axis the parts' `ν ∂_ν` turns each node's lateral-colour phase too: `− D̃_Δ`, as above)
    if let Some((d_k, d_shift)) = defocus_lane_on_grids_over_noise(scene, e, shape_of(scene))? {
        return Ok((scale - 2.0 * d_k - d_shift, d_k + d_shift));
    }
    let d_k = weighted_defocus_lane(scene, e, p)?;
    Ok((scale - 2.0 * d_k, d_k))
}

/// The scene's noise spectrum (the callers run under one).
fn shape_of(scene: &Scene) -> Option<&optics::NoiseShape> {
    scene.camera().noise_spectrum()
}

/// `(D̃_K, D̃_Δ)`, the defocus lane and the image shifts' lane with each frequency's weight
/// divided by `n(ν)`, where the white `∂M̄/∂ln F#` rides on them (metric's `aperture_through_iris`
/// and `aperture_off_axis`): a band on the exact 1-D engine whose OTF depends on direction (every
/// order a circular iris, decentred or not, or the full circle, with a defocus alone: the iris's
/// tilt `Δ_iris = 4 F# W020 d` in the defocus lane, the lateral colour in the shifts' lane, 0 on
/// axis), or on the overlap engine (Seidel terms, on axis and off axis); on the value's noise-weighted rules
/// over azimuth ([`optics::Polychromatic::mean_mtf_over_azimuth_over_noise_and_aperture_lanes`];
/// docs/physics.md, "Gradients under a noise spectrum", "Gradients: the iris"). `None` elsewhere.
fn aperture_lanes_over_noise(scene: &Scene, noise: Option<&optics::NoiseShape>) -> Option<(f64, f64)> {
    let noise = noise?;
    let detected = crate::evaluate::detected_spectrum(scene);
    if detected.as_line().is_some() {
        return None;
    }
    let field = scene.field();
    // a centred iris smaller than the aperture leaves the OTF symmetric, on the same engine
    let (lo, hi) = detected.support();
    let lambda = scene.lens().design_wavelength().unwrap_or(0.5 * (lo + hi));
    let iris = scene.lens().orders(lambda, field).iter().any(|o| matches!(o.pupil, optics::Pupil::Aperture(_)));
    on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let taken = match poly.engine() {
            optics::Engine::Exact1d => (poly.direction_dependent() || iris) && !poly.has_pupil_grid(),
            // on axis the full circle with Seidel terms, as the white lane (`defocus_lane_on_overlap`)
            optics::Engine::Overlap { .. } => !field.is_on_axis() || super::defocus_lane_on_overlap(scene),
            _ => false,
        };
        if !taken {
            return None;
        }
        let (_, d_k, d_shift) =
            poly.mean_mtf_over_azimuth_over_noise_and_aperture_lanes(field.y_rad.atan2(field.x_rad), noise)?;
        Some((d_k, d_shift))
    })
}

/// `(D̃_K, D̃_Δ)`, the defocus lane and (off axis, 0 on axis) the image shifts' scale lane with
/// each frequency's weight divided by `n(ν)`, on the FFT grids of a sampled pupil where the
/// white lanes are taken there (metric's `aperture_on_grids`: an annulus, Seidel terms through
/// an iris, Zernike terms), on the value's noise-weighted rules over azimuth from the field
/// direction ([`optics::Polychromatic::mean_mtf_over_azimuth_over_noise_and_gradient`] along
/// [`optics::WavefrontDirection::Defocus`]; docs/physics.md, "Gradients under a noise spectrum",
/// "Gradients: the F-number and the focal length on the FFT grids"). `None` elsewhere.
fn defocus_lane_on_grids_over_noise(
    scene: &Scene,
    e: &Evaluation,
    noise: Option<&optics::NoiseShape>,
) -> Result<Option<(f64, f64)>, Error> {
    let Some(noise) = noise else { return Ok(None) };
    let (first, directions) = super::grid_lanes(scene, optics::WavefrontDirection::Defocus);
    super::with_sampled_grids(scene, e, |poly| {
        Ok(poly
            .mean_mtf_over_azimuth_over_noise_and_gradient(first, &directions, noise)?
            .map(|(_, lanes)| (lanes[0], lanes.get(1).copied().unwrap_or(0.0))))
    })
}

/// `D̃_K`, the defocus lane with each frequency's weight divided by `n(ν)`, on the reference rule
/// of `aperture_partials_by_own_rule`; its refusals say that this is the rule taken here.
fn weighted_defocus_lane(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<f64, Error> {
    super::defocus_lane_by_own_rule(scene, e, p, scene.camera().noise_spectrum()).map_err(|error| match error {
        Error::NotDifferentiable { parameter, reason } => Error::NotDifferentiable {
            parameter,
            reason: format!(
                "with camera.noise_spectrum the weighted defocus lane is taken on the reference rule, on axis: {reason}"
            ),
        },
        other => other,
    })
}

/// `∂G/∂c` for the wavelength `c` of the scene's line under the noise spectrum, the weighted
/// counterpart of `line_center_partials`' `∂M̄/∂c`: the OTF is the lens's at `c` alone, moved by
/// its normalized frequency `νcF#` (the frequency scale's term per unit `ln c`,
/// [`frequency_scale_over_noise`] over `c`) and by its wavefront — a phase lens's wavelength
/// directions on the value's noise-weighted pass of the radial engine (`base`: where they start),
/// or, for one order that is the full pupil with a defocus alone, `D̃_K ∂ln w/∂c` with `D̃_K` on
/// the reference rule of the defocus lane, each frequency's weight divided by `n(ν)`. Off axis
/// the chromatic lens's one order is the on-axis OTF times a phase (its `|O|` the same): taken
/// on axis. Several orders moving by their own rates (the harmonic lens's order lane): on axis
/// [`order_lane_over_noise`], off axis [`line_center_orders_off_axis_over_noise`]; others are
/// refused, naming why.
pub(super) fn line_center_over_noise(scene: &Scene, e: &Evaluation, base: Option<usize>) -> Result<f64, Error> {
    let p = Parameter::SpectrumCenter;
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let detected = crate::evaluate::detected_spectrum(scene);
    let Some(line) = detected.line() else {
        return Err(not_smooth("the detected spectrum has no line".to_owned()));
    };
    let c = line.center();
    let lens = scene.lens();
    let field = scene.field();
    // one tabulated order: the table's slope in λ, each frequency's weight divided by n(ν)
    if base.is_none()
        && let Some(t) = super::line_table::line_on_table(scene, c, shape_of(scene))?
    {
        return Ok(t.mean);
    }
    // one order through a circular iris: the line engine's defocus lane over azimuth, each
    // frequency's weight divided by n(ν) (docs/physics.md, "Gradients: a line's wavelength
    // through an iris")
    if base.is_none()
        && let Some(iris) = super::line_through_iris(scene, shape_of(scene))
    {
        return Ok(frequency_scale_over_noise(scene, e, p, iris.edge)? / c + iris.defocus * iris.alpha);
    }
    // several orders off axis, each turned by its own lateral colour (the harmonic lens)
    if !field.is_on_axis() && base.is_none() && lens.orders(c, field).len() > 1 {
        return line_center_orders_off_axis_over_noise(scene, e, c).ok_or_else(|| {
            not_smooth(format!(
                "spectrum.center_nm: {}: with camera.noise_spectrum a line's wavelength on several orders off axis is \
                 followed where every order is the full circle with a defocus alone, turned by its own lateral \
                 colour, and depends on the wavelength through λ/λ0 alone (the harmonic lens), on the line's exact \
                 1-D engine; this scene's orders are not that",
                lens.describe()
            ))
        })?;
    }
    if !field.is_on_axis() && base.is_none() && lens.image_shift_field_rates(c, field).is_some() {
        return line_center_over_noise(&scene.single_field(optics::Field::ON_AXIS), e, None);
    }
    let edge = crate::evaluate::mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
    let scale = frequency_scale_over_noise(scene, e, p, edge)? / c;
    if let Some(b) = base {
        let Some(Ok((coefficients, _))) = lens.wavelength_directions(c) else {
            return Err(not_smooth("the lens gives no wavelength directions here".to_owned()));
        };
        let lanes = crate::evaluate::noise_weighted_lanes(scene, true, &[])?;
        let Some(lanes) = lanes.binary2.as_deref().and_then(|a| a.get(b..b + coefficients.len())) else {
            return Err(not_smooth(
                "with camera.noise_spectrum the radial engine's noise-weighted pass did not carry the wavelength's \
                 lanes here (off axis, an order through an iris, zones, a map or a table, or the FFT path)"
                    .to_owned(),
            ));
        };
        let along: f64 = coefficients.iter().zip(lanes).map(|(k, d)| k * d).sum();
        return Ok(scale + along);
    }
    let orders = lens.orders(c, field);
    if orders.len() != 1 {
        return match order_lane_over_noise(scene, c, weighted_mean(e)) {
            Some(d) => Ok(scale + d),
            None => Err(not_smooth(format!(
                "spectrum.center_nm: {}: with camera.noise_spectrum a line's wavelength is followed for one order \
                 with a defocus alone (the chromatic and refractive lenses), a phase lens on the radial engine, and \
                 several orders that are each the full circle with a defocus alone and whose rates the lens gives \
                 (the harmonic lens on axis); this scene's {} orders are not that (another pupil, an aberration \
                 beyond defocus, or no rates), so their order lane has nothing to weigh",
                lens.describe(),
                orders.len()
            ))),
        };
    }
    // (one order with a defocus alone: Seidel or Zernike terms scale as 1/c in waves too)
    if !orders[0].wavefront.is_defocus_only() || matches!(orders[0].pupil, optics::Pupil::Radial(_)) {
        return Err(not_smooth(format!(
            "spectrum.center_nm: {}: with camera.noise_spectrum a line's wavelength is followed for one order with a \
             defocus alone; this scene's order has Seidel or Zernike terms",
            lens.describe()
        )));
    }
    let rates = match lens.affine_defocus(field) {
        Some(a) => Some(a.w020_slope),
        None => lens.defocus_rates(c, field).map(|r| r.defocus),
    };
    let Some(rate) = rates else {
        return Err(not_smooth(format!("{}: the lens gives no rate of its defocus in λ here", lens.describe())));
    };
    let w020 = orders[0].wavefront.defocus_m;
    // ∂H/∂w = 0 at w = 0 (H is even in w)
    if w020 == 0.0 {
        return Ok(scale);
    }
    let d_k = weighted_defocus_lane(scene, e, p)?;
    Ok(scale + d_k * (rate / w020 - 1.0 / c))
}

/// `∂G/∂c` for the wavelength `c` of a line off axis on several orders, each the full circle
/// with a defocus alone turned by its own lateral colour (the harmonic lens), under the noise
/// spectrum: the weighted counterpart of metric's `line_center_orders_off_axis` (docs/physics.md,
/// "Gradients: several orders under a line off axis", "Gradients under a noise spectrum"). The
/// orders depend on the wavelength through `λ/λ0` alone (checked on the lens's rates, as there),
/// so moving `c` and `λ0` together holds them and moves only `s = νcF#` and `w_o = W020_o/c`:
///
/// ```text
/// ∂G/∂ln c = S̃ − D̃_K − D̃_λ0 + r G − 2 D̃_Δ
/// ```
///
/// with `S̃ = P(ν_N)⟨|O(ν_N)|⟩/n(ν_N) − G − (1/ν_N) ∫ P ⟨|O|⟩ (νP′/P − νn′/n)/n dν` the
/// frequency scale's term by parts under the weight ([`frequency_scale_over_noise`], `⟨·⟩` the
/// mean over azimuth; with the turn of each order's phase, whose share `D̃_Δ` is taken out
/// once more), and `D̃_K`, `D̃_λ0`, `D̃_Δ`, `G` the line engine's lanes and weighted mean over
/// azimuth with each frequency's weight divided by `n(ν)` (metric's `line_orders_off_axis`),
/// `r = ∂ln N/∂ln λ0`. Per m. `None` where the scene is not that.
fn line_center_orders_off_axis_over_noise(scene: &Scene, e: &Evaluation, c: f64) -> Option<Result<f64, Error>> {
    let noise = scene.camera().noise_spectrum()?;
    if !super::orders_of_wavelength_ratio(scene, c) {
        return None;
    }
    let field = scene.field();
    let found = super::line_orders_off_axis(scene, Some(noise))?;
    // P(ν_N) ⟨|O(ν_N, φ)|⟩ over azimuth on the value's engine, as the white end term
    let detected = crate::evaluate::detected_spectrum(scene);
    let nyquist = scene.camera().nyquist();
    let along_field = field.y_rad.atan2(field.x_rad);
    let edge = on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        Some(poly.mtf_over_azimuth(nyquist, along_field))
    })?;
    let scale = match frequency_scale_over_noise(scene, e, Parameter::SpectrumCenter, edge) {
        Ok(s) => s,
        Err(error) => return Some(Err(error)),
    };
    let d_log_c = scale - found.defocus - found.design + found.rate * found.mean - 2.0 * found.shift;
    Some(Ok(d_log_c / c))
}

/// `D̃ = (1/ν_N) ∫ P sign(O) L / n dν`, the order lane of a line at `c` on several orders under
/// the noise spectrum (docs/physics.md, "Gradients under a noise spectrum", "Gradients: a line's
/// wavelength"): every order the full circle with a defocus alone, `O = Σ_o τ_o H(νcF#, w_o) /
/// Σ_o τ_o` at the line's one wavelength, each moving by its rates `[α_o, γ_o]` (metric's
/// `order_lane_rates`: `α_o = ∂ln w_o/∂c`, `γ_o = ∂τ_o/∂c`), so at a fixed normalized frequency
/// `L = (Σ_o [τ_o α_o w_o ∂H/∂w_o + γ_o H_o] − O Σ_o γ_o) / Σ_o τ_o`, the white order lane's
/// integrand; `P` the pixel MTF where the camera applies it. On 16-point Gauss–Legendre panels
/// split at the sign changes of `O`, doubled until it moves by at most the tolerance times
/// `max(|D̃|, G)` (`g`: the table's kinks integrated across as the panels double). `None` where the
/// orders are not that, or the lens gives no rates.
fn order_lane_over_noise(scene: &Scene, c: f64, g: f64) -> Option<f64> {
    let noise = scene.camera().noise_spectrum()?;
    let lens = scene.lens();
    let field = scene.field();
    if !field.is_on_axis() {
        return None;
    }
    let orders = lens.orders(c, field);
    let plain = orders.iter().all(|o| matches!(o.pupil, optics::Pupil::Full) && o.wavefront.is_defocus_only());
    let rates = super::order_lane_rates(scene, c)?;
    if !plain || rates.len() != orders.len() {
        return None;
    }
    let f_number = lens.f_number();
    let total: f64 = orders.iter().map(|o| o.efficiency).sum();
    let moved: f64 = rates.iter().map(|r| r[1]).sum();
    let camera = scene.camera();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let nyquist = camera.nyquist();
    let otf = |nu: f64| -> f64 {
        let s = nu * c * f_number;
        orders.iter().map(|o| o.efficiency * optics::defocus_otf(s, o.wavefront.defocus_m / c)).sum::<f64>() / total
    };
    let at = |nu: f64| -> (f64, [f64; 1]) {
        let s = nu * c * f_number;
        let (mut o, mut lane) = (0.0, 0.0);
        for (order, [alpha, gamma]) in orders.iter().zip(&rates) {
            let w = order.wavefront.defocus_m / c;
            let h = optics::defocus_otf(s, w);
            o += order.efficiency * h;
            lane += order.efficiency * alpha * optics::defocus_otf_log_derivative(s, w) + gamma * h;
        }
        let o = o / total;
        let weight = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) / noise.value(nu);
        (o, [weight * (lane - o * moved) / total])
    };
    let tolerance = scene.options().settings().tolerance;
    let [d] =
        super::sign_split_mean(nyquist, 8, otf, at, |change, next| change[0].abs() <= tolerance * next[0].abs().max(g));
    Some(d)
}

/// `∂G/∂W` of Seidel term `t` (per µm) where every Seidel term is zero, under the noise
/// spectrum `noise`: the weighted counterpart of metric's `seidel_at_zero` (on axis, the OTF
/// rotationally symmetric: spherical aberration's and field curvature's lanes along one azimuth,
/// astigmatism's half field curvature's, coma's 0 by symmetry) and `seidel_at_zero_off_axis`
/// (off axis: the term's lane over azimuth from the field direction), each on the overlap engine
/// run again with the terms at zero (`optics::Settings::overlap_always`), the value's
/// noise-weighted rules there (each `∂|O|` divided by `n(ν)`, the frequency rule cut at the
/// table's rows; docs/physics.md, "Gradients under a noise spectrum", "Gradients: Seidel terms
/// at zero"). Error control as theirs: first at the engine's tolerance, again at
/// `max(q, 10⁻⁴) ε` where the lanes are small against their bound `L G` (`q = |∂G|/(L G)`).
/// `None` where some term is not zero or the overlap engine does not take the scene (an iris,
/// `options.overlap = false`, `options.pupil_samples`).
pub(super) fn seidel_at_zero_over_noise(
    scene: &Scene,
    e: &Evaluation,
    t: optics::SeidelTerm,
    noise: &optics::NoiseShape,
) -> Result<Option<f64>, Error> {
    use optics::SeidelTerm::{Astigmatism, Coma, FieldCurvature};
    let field = scene.field();
    if !seidel_terms_zero(scene, e) {
        return Ok(None);
    }
    let on_axis = field.is_on_axis();
    if on_axis && t == Coma {
        // c and −c are one pupil turned by π: G is even in it
        return Ok(Some(0.0));
    }
    let first = field.y_rad.atan2(field.x_rad);
    // on axis astigmatism's defocus part is half field curvature's (x² = ρ²/2 + ρ² cos 2φ/2, the
    // cos 2φ part 0 by symmetry)
    let (direction, share) = match t {
        Astigmatism if on_axis => (FieldCurvature, 0.5),
        t => (t, 1.0),
    };
    let directions = [optics::WavefrontDirection::Seidel(direction)];
    let lane = seidel_lane_at_zero(scene, e, &|poly| match on_axis {
        true => poly.mean_mtf_along_over_noise_and_gradient(0.0, &directions, noise).map(|(m, _, d)| (m, d[0])),
        false => poly
            .mean_mtf_over_azimuth_over_noise_and_overlap_gradient(first, &directions, noise)
            .map(|(m, d)| (m.mean, d[0])),
    })?;
    Ok(lane.map(|lane| share * lane))
}

#[cfg(test)]
mod tests {
    use super::pixel_log_slope;

    /// `x cot x − 1` against central differences of `ln sinc` in `ln ν`, across the series'
    /// switch at `x = 1e-3` and up to Nyquist (`x = π/2`).
    #[test]
    fn pixel_log_slope_is_the_sinc_s_log_derivative() {
        let pitch = 5.2e-6;
        for x in [1e-4, 9.9e-4, 1.01e-3, 0.3, 1.0, 1.5] {
            let nu = x / (std::f64::consts::PI * pitch);
            let h = 1e-5;
            let ln_p = |nu: f64| optics::pixel_mtf(pitch, nu).ln();
            let theirs = (ln_p(nu * (1.0 + h)) - ln_p(nu * (1.0 - h))) / ((1.0 + h).ln() - (1.0 - h).ln());
            let ours = pixel_log_slope(pitch, nu);
            assert!((ours - theirs).abs() <= 1e-9 + 1e-8 * theirs.abs(), "x = {x}: {ours} vs {theirs}");
        }
    }
}
