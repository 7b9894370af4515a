//! A library lens's parameter bias and its atoms' phase errors where its pupil is sampled on the
//! FFT path: a radial layout off axis, whose imaging order is its radial pupil seen by the
//! oblique wave, and a 2-D layout on and off axis, whose imaging order is its site map
//! (docs/physics.md, "Gradients: a library's parameter bias", "… a library's atoms' phase
//! errors" and "Gradients: 2-D pupils (the FFT path)").
//!
//! The key moves each atom's field, so each order's amplitude and phase profiles or its atoms'
//! table ([`optics::LensModel::order_derivatives`]: `∂a(q)`, `∂W(q)` or `∂t_u`, `∂τ_o`, `∂T`), on the value's own
//! engine: forward mode through the FFT with the complex lane
//! ([`optics::WavefrontDirection::OrderField`]) at the value's sampling levels, spectral nodes,
//! frequencies and azimuths, so that the derivative is that of the value's discrete rule.

use super::{BiasPartials, Parameter};
use crate::evaluate::Evaluation;
use crate::{Error, Scene};

/// `(∂ln N, ∂ln N_T, ∂M̄)` with respect to the library lens's parameter `index` (its bias, or
/// the atoms' phase errors' σ with [`optics::ATOM_PHASE_ERROR`]) where the value's engine is
/// the FFT path: the mean over azimuth's derivative on the value's own pass
/// ([`optics::Polychromatic::mean_mtf_over_azimuth_and_gradient`], under a noise spectrum
/// `noise` its weighted twin), and on the same engine's spectral nodes (weights `ρ Σ_o τ_o`)
/// `∂ln N = Σ w ∂τ / Σ w τ` and `∂ln N_T = Σ w ∂T / Σ w T` (SI eq. S8, S14), `τ = Σ_o τ_o`.
/// Refused where the engine is not the FFT path or the lens gives no order derivatives there
/// (the exact pupil mapping; linear rows).
pub(super) fn library_bias_on_fft_path(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    index: usize,
    noise: Option<&optics::NoiseShape>,
) -> Result<BiasPartials, Error> {
    let not_smooth = |reason: &str| Error::NotDifferentiable { parameter: p.describe(), reason: reason.to_owned() };
    if !e.numerics.engine.starts_with("fft") {
        return Err(not_smooth(
            "a library lens off axis, or with a 2-D layout, is sampled on the FFT path, where its lanes are \
             computed; this evaluation's engine is another",
        ));
    }
    let lens = scene.lens();
    let detected = crate::evaluate::detected_spectrum(scene);
    let field = scene.field();
    super::with_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let first = field.y_rad.atan2(field.x_rad);
        let directions = [optics::WavefrontDirection::OrderField(index)];
        let found = match noise {
            None => poly.mean_mtf_over_azimuth_and_gradient(first, &directions)?,
            Some(n) => poly.mean_mtf_over_azimuth_over_noise_and_gradient(first, &directions, n)?,
        };
        let Some((_, d_mtf)) = found else {
            return Err(not_smooth(
                "the FFT path did not carry the lens's order derivatives here: they are computed for a radial pupil \
                 (a radial layout off axis) and a 2-D layout's site map, not for the lens's exact pupil mapping",
            ));
        };
        // ∂ln N and ∂ln N_T on the engine's spectral nodes, weighted ρ τ
        let mut missing = false;
        let mut rates = |l: f64| -> [f64; 3] {
            let tau: f64 = lens.orders(l, field).iter().map(|o| o.efficiency).sum();
            match lens.order_derivatives(l, index) {
                Some(d) if tau > 0.0 => {
                    [d.efficiencies.iter().sum::<f64>() / tau, d.transmission / tau, lens.transmission(l) / tau]
                }
                _ => {
                    missing = true;
                    [0.0; 3]
                }
            }
        };
        // each node's three rates once, then read back in the nodes' order
        let mut at_nodes: Vec<[f64; 3]> = Vec::new();
        let d_ln_n = poly.spectral_average(|l, _| {
            let r = rates(l);
            at_nodes.push(r);
            r[0]
        });
        let [d_t, t] = [1, 2].map(|k| {
            let mut read = at_nodes.iter();
            poly.spectral_average(|_, _| read.next().map_or(0.0, |r| r[k]))
        });
        if missing || t <= 0.0 {
            return Err(not_smooth("the lens gives no derivative of its orders at a spectral node of the value"));
        }
        Ok(BiasPartials { ln_photoelectrons: d_ln_n, ln_transmitted: d_t / t, mean_mtf: d_mtf[0] })
    })
}
