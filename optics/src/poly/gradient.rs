//! The derivative of the polychromatic mean MTF with respect to a lens's Binary 2 coefficients
//! (docs/physics.md, "Gradients"), from the radial engine's OTF derivatives
//! ([`RadialOrder::otf_and_derivatives`]) summed on its own product rule: no finite differences.
//!
//! `M̄ = (1/ν_max) ∫_0^{ν_max} |O(ν)| dν` with `O(ν) = Σ_λ w_λ OTF_λ(ν λ F#) / Σ_λ w_λ` (the
//! weights `ρ(λ) τ(λ)` of the detected photons, which the coefficients do not move), so
//! `∂M̄/∂A_j = (1/ν_max) ∫ sign(O) Σ_λ w_λ ∂OTF_λ/∂A_j / Σ w dν`. The rule: in λ, 16-point
//! Gauss–Legendre on panels between the spectrum's ends and breakpoints and the lens's; in ν,
//! 16-point Gauss–Legendre on panels of `[0, ν_max]`, each split where `O` changes sign (the
//! kink of `|O|`, found by bisection), so the integrand is smooth on every piece. The panels
//! start at [`SPECTRAL_PANELS`] × [`FREQUENCY_PANELS`] and double together until the gradient
//! moves by at most the tolerance times its norm (at most [`MAX_SPECTRAL_PANELS`] in λ); the
//! result is checked against central differences of converged evaluations in the report's tests.

use radiometry::Spectrum;

use crate::lens::{Field, LensModel};
use crate::radial::RadialOrder;
use crate::{Error, quad};

use super::spectral::{Node, spectral_extent};

/// Gauss–Legendre panels across the spectral band (between breakpoints) of the first rule.
const SPECTRAL_PANELS: usize = 2;

/// Gauss–Legendre panels across `[0, ν_max]` (each split at a sign change of the OTF) of the
/// first rule.
const FREQUENCY_PANELS: usize = 4;

/// The most spectral panels: the rule stops doubling there.
const MAX_SPECTRAL_PANELS: usize = 128;

/// One wavelength's radial order, its weight, and its derivative directions.
struct Sample {
    lambda: f64,
    weight: f64,
    order: std::sync::Arc<RadialOrder>,
    directions: Vec<crate::radial::RadialProfile>,
}

/// `∂M̄/∂A_j` for each Binary 2 coefficient of `lens` ([`LensModel::binary2_directions`]) of the
/// mean of `|O|` over `[0, max_frequency]` (cycles/m, no pixel MTF), seen through `detected`
/// at `field`, each OTF to `accuracy` (absolute). `None` where this rule does not apply: the
/// lens has no Binary 2 coefficients, the field is off axis, or an order is not a radially
/// symmetric pupil on the exact radial engine.
///
/// # Errors
/// A spectrum without a band limit ([`Error::UnboundedSpectrum`]) and [`Error::NoSignal`].
pub fn binary2_mean_mtf_gradient(
    lens: &dyn LensModel,
    detected: &Spectrum,
    field: Field,
    max_frequency: f64,
    tolerance: f64,
) -> Result<Option<Vec<f64>>, Error> {
    let accuracy = (1e-2 * tolerance).max(1e-13);
    let (mut spectral, mut frequency) = (SPECTRAL_PANELS, FREQUENCY_PANELS);
    let rule = |s, f| on_rule(lens, detected, field, max_frequency, accuracy, s, f);
    let Some(mut previous) = rule(spectral, frequency)? else { return Ok(None) };
    while spectral < MAX_SPECTRAL_PANELS {
        spectral *= 2;
        frequency *= 2;
        let Some(next) = rule(spectral, frequency)? else { return Ok(None) };
        let norm = next.iter().map(|x| x * x).sum::<f64>().sqrt();
        let change = next.iter().zip(&previous).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
        previous = next;
        if change <= tolerance * norm {
            break;
        }
    }
    Ok(Some(previous))
}

/// The gradient on one rule: `spectral_panels` in λ, `frequency_panels` in ν.
#[allow(clippy::too_many_arguments)]
fn on_rule(
    lens: &dyn LensModel,
    detected: &Spectrum,
    field: Field,
    max_frequency: f64,
    accuracy: f64,
    spectral_panels: usize,
    frequency_panels: usize,
) -> Result<Option<Vec<f64>>, Error> {
    if !field.is_on_axis() {
        return Ok(None);
    }
    let (lo, hi) = match detected.as_line() {
        Some(line) => (line.wavelength_m, line.wavelength_m),
        None => spectral_extent(detected)?,
    };
    // the spectral rule's (λ, rule weight × ρ(λ)) nodes
    let mut lambdas: Vec<(f64, f64)> = Vec::new();
    if let Some(line) = detected.as_line() {
        lambdas.push((line.wavelength_m, line.weight));
    } else {
        let mut cuts: Vec<f64> = vec![lo, hi];
        cuts.extend(detected.breakpoints().into_iter().chain(lens.breakpoints()).filter(|&x| x > lo && x < hi));
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        let rule = quad::rule();
        for w in cuts.windows(2) {
            let h = (w[1] - w[0]) / spectral_panels as f64;
            for p in 0..spectral_panels {
                let c = w[0] + (p as f64 + 0.5) * h;
                for &(x, wx) in rule.iter() {
                    let lambda = c + 0.5 * h * x;
                    lambdas.push((lambda, 0.5 * h * wx * detected.value(lambda)));
                }
            }
        }
    }
    let mut samples = Vec::new();
    let mut count = None;
    for (lambda, rho) in lambdas {
        if rho == 0.0 {
            continue;
        }
        let Some(directions) = lens.binary2_directions(lambda) else { return Ok(None) };
        let orders = lens.orders(lambda, field);
        if orders.len() != directions.len() {
            return Ok(None);
        }
        for (order, directions) in orders.iter().zip(directions) {
            if *count.get_or_insert(directions.len()) != directions.len() {
                return Ok(None);
            }
            let node = Node::of(order, lambda, rho * order.efficiency, None);
            let Some(radial) = node.radial.clone() else { return Ok(None) };
            if node.shift != [0.0, 0.0] || node.table.is_some() {
                return Ok(None);
            }
            samples.push(Sample { lambda, weight: node.weight, order: radial, directions });
        }
    }
    let Some(k) = count else { return Ok(None) };
    let total: f64 = samples.iter().map(|s| s.weight).sum();
    if !(total.is_finite() && total > 0.0) {
        return Err(Error::NoSignal { total });
    }
    let f_number = lens.f_number();
    // the polychromatic OTF alone (for the sign changes)
    let otf = |nu: f64| -> f64 {
        samples.iter().map(|s| s.weight * s.order.otf(nu * f_number * s.lambda, accuracy)).sum::<f64>() / total
    };
    // the ν pieces: panel ends and the sign changes between them
    let mut ends = vec![0.0];
    let h = max_frequency / frequency_panels as f64;
    let mut previous = (0.0, 1.0);
    for p in 1..=frequency_panels {
        let nu = if p == frequency_panels { max_frequency } else { p as f64 * h };
        let value = otf(nu);
        if value * previous.1 < 0.0 {
            let (mut a, mut b, fa) = (previous.0, nu, previous.1);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if b - a <= 1e-15 * b {
                    break;
                }
                if otf(m) * fa > 0.0 {
                    a = m;
                } else {
                    b = m;
                }
            }
            ends.push(0.5 * (a + b));
        }
        ends.push(nu);
        previous = (nu, value);
    }
    let rule = quad::rule();
    let mut gradient = vec![0.0; k];
    let mut d = vec![0.0; k];
    let mut sum = vec![0.0; k];
    for w in ends.windows(2) {
        let half = 0.5 * (w[1] - w[0]);
        if half <= 0.0 {
            continue;
        }
        let centre = 0.5 * (w[0] + w[1]);
        for &(x, wx) in rule.iter() {
            let nu = centre + half * x;
            sum.iter_mut().for_each(|v| *v = 0.0);
            let mut value = 0.0;
            for s in &samples {
                value +=
                    s.weight * s.order.otf_and_derivatives(nu * f_number * s.lambda, accuracy, &s.directions, &mut d);
                for (v, dj) in sum.iter_mut().zip(&d) {
                    *v += s.weight * dj;
                }
            }
            let sign = if value < 0.0 { -1.0 } else { 1.0 };
            for (g, v) in gradient.iter_mut().zip(&sum) {
                *g += half * wx * sign * v / total;
            }
        }
    }
    gradient.iter_mut().for_each(|g| *g /= max_frequency);
    Ok(Some(gradient))
}
