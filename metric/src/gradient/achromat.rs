//! The edges of a lens's design band (a dispersion-engineered lens's `lens.design_band_nm`):
//! limits of the signal's integrals over λ (docs/physics.md, "Gradients: the
//! dispersion-engineered lens").

use crate::{Error, Scene};

use std::cell::RefCell;
use std::collections::HashMap;

use super::{
    DirectionalRule, Parameter, modulus_derivative, noise_row_ends, on_value_engine, product_rule_on_axis,
    sign_split_mean,
};

/// `(∂ln N/∂x, ∂M̄/∂x)` (per m) for the edge `x` of the lens's design band
/// ([`optics::LensModel::design_band`]; `edge` 0 its short end λ_min, 1 its long end λ_max),
/// outside which every order's efficiency is 0 and the transmitted light is background alone.
/// The signal's integrals run over the band: with `D = ∫_{λ_min}^{λ_max} ρ Σ_o τ_o dλ` the
/// detected weight and `T_x = ρ(x) Σ_o τ_o(x)` its density at the edge (the orders' efficiency
/// there, the band's own), Leibniz's rule gives
/// - `∂ln N/∂λ_max = T_x/D`, `∂ln N/∂λ_min = −T_x/D`;
/// - the normalized OTF `O = ∫ ρ Σ_o τ_o H_o dλ / D` moves as `±(T_x/D)(O_x − O)`, `O_x` the OTF
///   at the single wavelength `x`, so `∂M̄/∂x = ±(T_x/D)((1/ν_N) ∫ P sign(O) O_x dν − M̄)`;
/// - where the OTF depends on direction, `∂|O| = ±(T_x/D)(Re(O* O_x)/|O| − |O|)` on the value's
///   rule over directions.
///
/// As a top-hat spectrum's edges are (`top_hat_partials`, docs/physics.md "Gradients: a top-hat's
/// edges"), with the lens's window in place of the spectrum's: the total transmission `T` does
/// not move (the caller's `∂B = −∂N` with the stray light). The integrals in ν on 16-point
/// Gauss–Legendre panels split at the sign changes of `O`, doubled until they move by at most the
/// tolerance times `M̄`; `M̄` on the same rule; the band's OTF and both means again at
/// `max(q, 1e-4)` times the tolerance where `I_x − M̄` is `q < 1` of `M̄`. Under a noise spectrum (`noise`) each frequency's weight divided by
/// `n(ν)`, `M̄` the weighted mean on the same rule. The band's OTF is computed once per
/// frequency (the sign and the lane read the same value). Where the value's engine is the
/// per-frequency product rule on axis (no noise spectrum), the lane rides on that engine's own
/// pass instead, the band's window on the spectrum ([`band_edge_on_value_rule`]).
/// Refused where the lens has no design band.
pub(super) fn band_edge_partials(
    scene: &Scene,
    e: &crate::Evaluation,
    p: Parameter,
    edge: usize,
    noise: Option<&optics::NoiseShape>,
) -> Result<(f64, f64), Error> {
    let lens = scene.lens();
    let Some((lo, hi)) = lens.design_band() else {
        return Err(Error::NotDifferentiable {
            parameter: p.describe(),
            reason: format!("{}: the lens has no design band", lens.describe()),
        });
    };
    let (x, sign) = if edge == 0 { (lo, -1.0) } else { (hi, 1.0) };
    let field = scene.field();
    let detected = crate::evaluate::detected_spectrum(scene);
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    let settings = scene.options().settings();
    let camera = scene.camera();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let over_noise = |nu: f64| noise.map_or(1.0, |n| 1.0 / n.value(nu));
    // T_x/D: the detected density times the orders' efficiency at the edge, over the weight
    let efficiency: f64 = lens.orders(x, field).iter().map(|o| o.efficiency).sum();
    if detected.value(x) * efficiency == 0.0 {
        // no detected light at the edge: neither N nor the OTF's weights move
        return Ok((0.0, 0.0));
    }
    if noise.is_none()
        && let Some(found) = band_edge_on_value_rule(scene, e, &detected, (lo, hi), edge)
    {
        return Ok(found);
    }
    // the edge's single wavelength (a line of any weight: its OTF is normalized)
    let line = radiometry::Spectrum::Line(radiometry::Line::new(x, 1e-9, 1.0)?);
    // (T_x/D, I_x, M̄) with the band's OTF and both means held to `tolerance` relative to M̄
    let means = |tolerance: f64| -> Result<(f64, f64, f64), Error> {
        let settings = optics::Settings { tolerance, ..settings };
        let whole = optics::Polychromatic::with_settings(lens, &detected, field, nyquist, None, settings)?;
        let at_x = optics::Polychromatic::with_settings(lens, &line, field, nyquist, None, settings)?;
        let density = detected.value(x) * efficiency / whole.total_weight();
        if whole.direction_dependent() || at_x.direction_dependent() {
            let rule = DirectionalRule::of(scene, &whole, tolerance);
            let [j, i_x, _] = rule.mean_split(&noise_row_ends(noise, nyquist), [1.0; 3], &|nu, azimuth| {
                let o = whole.otf_along(nu, azimuth);
                let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) * over_noise(nu);
                let o_x = at_x.otf_along(nu, azimuth);
                [pix * o.norm(), pix * modulus_derivative([o.re, o.im], [o_x.re, o_x.im]), 0.0]
            });
            return Ok((density, i_x, j));
        }
        // the band's OTF once per frequency: the sign changes' search, the sign and the lane
        // read the same values
        let known: RefCell<HashMap<u64, f64>> = RefCell::new(HashMap::new());
        let band_otf = |nu: f64| -> f64 {
            if let Some(&o) = known.borrow().get(&nu.to_bits()) {
                return o;
            }
            let o = whole.otf(nu);
            known.borrow_mut().insert(nu.to_bits(), o);
            o
        };
        let [i_x, j] = sign_split_mean(
            nyquist,
            8,
            band_otf,
            |nu| {
                let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) * over_noise(nu);
                let o = band_otf(nu);
                (o, [pix * at_x.otf(nu), pix * o])
            },
            |change, next| change[0].abs().max(change[1].abs()) <= tolerance * next[1].abs(),
        );
        Ok((density, i_x, j))
    };
    // I_x − M̄ is a difference of two means each held to the tolerance relative to M̄: where it
    // is q = |I_x − M̄|/M̄ < 1 of M̄, both again at max(q, 1e-4) times the tolerance, so that the
    // difference keeps the tolerance relative to itself (as the field angles' lanes do)
    let (mut density, mut i_x, mut j) = means(settings.tolerance)?;
    let q = (i_x - j).abs() / j.abs().max(f64::MIN_POSITIVE);
    if q < 1.0 {
        (density, i_x, j) = means(settings.tolerance * q.max(1e-4))?;
    }
    // M̄ on the same rule as I_x (white, or the weighted G under a noise spectrum)
    Ok((sign * density, sign * density * (i_x - j)))
}

/// [`band_edge_partials`] on the value's own engine, where it is the per-frequency product rule on
/// axis, built for the detected spectrum with the band's window on it (the same integrand, the
/// orders' efficiency being 0 outside the band), so that its spectral panels end at the design
/// band's edges (docs/physics.md, "Gradients: the dispersion-engineered lens"): as a top-hat's
/// edges on the value's rule
/// (`top_hat_on_value_rule`), the Chebyshev–Lobatto points of every spectral level include the
/// panels' ends, so the value's own sums there give the edge's OTF `O_x` (times the detected
/// density and the orders' efficiency), and each OTF value carries `±(T_x/D)(O_x − O)` beside it
/// ([`optics::Polychromatic::mean_mtf_and_spectral_lanes`] with its edge lanes), integrated with
/// the frequency rule's accepted weights: the lane held to the value's own error control. `∂ln N
/// = ±T_x/D` as there. `None` on the other engines, off axis, or where the engine's ends are not
/// the band's (a Gaussian's ±7σ inside the band): the caller's rule.
fn band_edge_on_value_rule(
    scene: &Scene,
    e: &crate::Evaluation,
    detected: &radiometry::Spectrum,
    (lo, hi): (f64, f64),
    edge: usize,
) -> Option<(f64, f64)> {
    if !product_rule_on_axis(scene, e) {
        return None;
    }
    // the detected spectrum with the band's window on it: the same integrand (the orders'
    // efficiency is 0 outside the band), its support the band, so the engine's spectral panels
    // end at the band's edges
    let window = radiometry::Spectrum::TopHat(radiometry::TopHat::new(lo, hi, 1.0).ok()?);
    let windowed = radiometry::Spectrum::product(vec![detected.clone(), window]);
    on_value_engine(scene, &windowed, scene.options().settings(), |poly| {
        let (a, b) = poly.spectral_ends()?;
        if (a - lo).abs() > 1e-12 * lo || (b - hi).abs() > 1e-12 * hi {
            return None;
        }
        let (_, lanes, _) = poly.mean_mtf_and_spectral_lanes(None, true)?;
        if poly.over_budget().is_some() {
            return None;
        }
        let x = if edge == 0 { a } else { b };
        let efficiency: f64 = scene.lens().orders(x, scene.field()).iter().map(|o| o.efficiency).sum();
        let density = windowed.value(x) * efficiency / poly.total_weight();
        Some((if edge == 0 { -density } else { density }, lanes[edge]))
    })
}
