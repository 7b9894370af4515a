//! The gradient with respect to one channel's wavelength λ_j of an interleaved multiplexed lens
//! (`lens.channels_nm[j]`), on axis (docs/physics.md, "Gradients: the multiplexed lens").
//!
//! Channel `j` is the lens's order `j`, through the full circular pupil with the defocus
//! `W020_j(λ) = (1 − λ/λ_j) K`, `K = f0/(8F#²)`, and an efficiency that does not depend on λ_j.
//! So λ_j moves that order alone, `∂W020_j/∂ln λ_j = (λ/λ_j) K`, the other orders and every
//! efficiency held: the design wavelength's lane (`optics::LensModel::design_wavelength_rates`,
//! docs/physics.md "Gradients: the design wavelength") with the rates of the one order. The
//! lens is seen through [`OneChannel`], which gives those rates and is the lens in everything
//! else, and the design wavelength's gradient is taken of the scene with it.
//!
//! A channel's own efficiency η_j (`lens.channel_efficiencies[j]`, `τ_j = η_j/N²`) likewise
//! moves that order's weight alone, `∂τ_j/∂ln η_j = τ_j`, its defocus and the transmission
//! held: the same lane with the rates `[0, τ_j]` of order `j` (the OTF's weights and
//! `N ∝ ∫ ρ Σ τ_o`, the stray light `N_T − N` by `−∂N`).

use std::sync::Arc;

use optics::{Field, LensModel, Order};

use super::{Error, Gradient, Parameter};
use crate::Scene;

/// What of one channel moves.
#[derive(Clone, Copy, Debug)]
enum Moving {
    /// Its wavelength λ_j (m).
    Wavelength(f64),
    /// Its own efficiency η_j.
    Efficiency,
}

/// A lens of channels in the interleaved lens's form, its design-wavelength rates those of
/// channel `channel` alone, as `moving` moves it.
#[derive(Debug)]
struct OneChannel {
    lens: Arc<dyn LensModel>,
    channel: usize,
    moving: Moving,
}

impl LensModel for OneChannel {
    fn f_number(&self) -> f64 {
        self.lens.f_number()
    }
    fn focal_length(&self) -> f64 {
        self.lens.focal_length()
    }
    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        self.lens.orders(wavelength_m, field)
    }
    fn orders_into(&self, wavelength_m: f64, field: Field, out: &mut Vec<Order>) {
        self.lens.orders_into(wavelength_m, field, out)
    }
    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.lens.efficiency(wavelength_m)
    }
    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.lens.transmission(wavelength_m)
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.lens.breakpoints()
    }
    fn numerical_aperture(&self) -> f64 {
        self.lens.numerical_aperture()
    }
    fn design_wavelength(&self) -> Option<f64> {
        self.lens.design_wavelength()
    }
    fn describe(&self) -> String {
        self.lens.describe()
    }

    /// On axis, for order `j`: `[(λ/λ_j) K, 0]` for its wavelength, `[0, τ_j]` for its own
    /// efficiency; `[0, 0]` for the others. `None` off axis (a channel's wavelength moves its
    /// lateral colour too, a lane of one order's shift not carried) or where order `j` is not
    /// the full circle with a defocus alone (for the wavelength: `(1 − λ/λ_j) K`).
    fn design_wavelength_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        if !field.is_on_axis() {
            return None;
        }
        let orders = self.lens.orders(wavelength_m, field);
        let f_number = self.lens.f_number();
        let k = self.lens.focal_length() / (8.0 * f_number * f_number);
        let order = orders.get(self.channel)?;
        if !(matches!(order.pupil, optics::Pupil::Full) && order.wavefront.is_defocus_only()) {
            return None;
        }
        let rates = match self.moving {
            Moving::Wavelength(lambda_j) => {
                let expected = (1.0 - wavelength_m / lambda_j) * k;
                if (order.wavefront.defocus_m - expected).abs() > 1e-12 * k {
                    return None;
                }
                [k * wavelength_m / lambda_j, 0.0]
            }
            Moving::Efficiency => [0.0, order.efficiency],
        };
        Some((0..orders.len()).map(|o| if o == self.channel { rates } else { [0.0, 0.0] }).collect())
    }
}

/// The evaluation of `scene` and the derivatives of its ASNR, mean MTF, SNR0 and photoelectrons
/// with respect to `ln λ_j` of the interleaved lens's channel `channel` at `wavelength_m` (m):
/// the design wavelength's gradient of the scene with its lens seen through a view that moves
/// that channel alone (`OneChannel`).
///
/// # Errors
/// The evaluation's, and [`Error::NotDifferentiable`] off axis, over a field-of-view list, and
/// where the design wavelength's gradient is refused (naming why).
pub fn channel_wavelength_gradient(scene: &Scene, channel: usize, wavelength_m: f64) -> Result<Gradient, Error> {
    one_channel(scene, channel, Moving::Wavelength(wavelength_m))
}

/// As [`channel_wavelength_gradient`], with respect to `ln η_j` of channel `channel`'s own
/// efficiency (`τ_j = η_j/N²`, a constant): the lane with the rates `[0, τ_j]` of its order.
///
/// # Errors
/// The evaluation's, and [`Error::NotDifferentiable`] off axis, over a field-of-view list, and
/// where the design wavelength's gradient is refused (naming why).
pub fn channel_efficiency_gradient(scene: &Scene, channel: usize) -> Result<Gradient, Error> {
    one_channel(scene, channel, Moving::Efficiency)
}

/// The design wavelength's gradient of `scene` with its lens seen through [`OneChannel`].
fn one_channel(scene: &Scene, channel: usize, moving: Moving) -> Result<Gradient, Error> {
    if !scene.field().is_on_axis() || !scene.fields().is_empty() {
        let (parameter, reason) = match moving {
            Moving::Wavelength(_) => (
                "a channel's wavelength",
                "off axis a channel's wavelength λ_j moves its lateral colour f0 tan θ (λ_j/λ − 1) alone, one order's \
                 image shift against the others', a lane the engines do not carry yet (on axis it is computed)",
            ),
            Moving::Efficiency => (
                "a channel's own efficiency",
                "off axis its lane (the design wavelength's with one order's weight moving) is not carried: the \
                 design wavelength's lanes there move every order's image shift (on axis it is computed)",
            ),
        };
        return Err(Error::NotDifferentiable { parameter, reason: reason.to_owned() });
    }
    let lens: Arc<dyn LensModel> = Arc::new(OneChannel { lens: scene.lens_arc(), channel, moving });
    let seen = scene.clone().with_lens(lens);
    super::gradient(&seen, &[Parameter::DesignWavelength])
}
