//! The gradient with respect to one channel's wavelength λ_j of an interleaved multiplexed lens
//! (`lens.channels_nm[j]`), on axis and off (docs/physics.md, "Gradients: the multiplexed lens").
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
//!
//! Off axis λ_j also moves channel `j`'s lateral colour `Δ_j = f0 tan θ (λ_j/λ − 1)` alone, by
//! `∂Δ_j/∂ln λ_j = f0 tan θ λ_j/λ`: one order's shift against the others', carried on the exact
//! 1-D engine as the field angles' lanes with that order's shift rates ([`channel_off_axis`]).
//!
//! On axis every channel's wavelength and efficiency lanes are taken in one pass
//! ([`channel_gradients`]): the lens seen with each order's rates of its own channel
//! ([`AllChannels`]), each order's share of the design lane and its own weight kept apart.

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

/// The lens's own orders, efficiencies, aperture and description, read through a wrapper's
/// `lens` field ([`OneChannel`], [`AllChannels`]: each replaces only its rates).
macro_rules! forward_to_lens {
    () => {
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
    };
}

/// A lens of channels in the interleaved lens's form, its design-wavelength rates those of
/// channel `channel` alone, as `moving` moves it.
#[derive(Debug)]
struct OneChannel {
    lens: Arc<dyn LensModel>,
    channel: usize,
    moving: Moving,
    /// Off axis, for the channel's wavelength: the image shifts' rates are the channel's own
    /// `∂Δ_j/∂ln λ_j` (see [`channel_off_axis`]) in place of the field's.
    shifts: bool,
}

impl LensModel for OneChannel {
    forward_to_lens!();

    /// With `shifts`, for channel `j`'s wavelength off axis: order `j`'s
    /// `∂Δ_j/∂ln λ_j = f0 tan θ λ_j/λ` on each axis (its lateral colour
    /// `Δ_j = f0 tan θ (λ_j/λ − 1)`), `[0, 0]` for the others; else the lens's own field rates.
    fn image_shift_field_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        let (true, Moving::Wavelength(lambda_j)) = (self.shifts, self.moving) else {
            return self.lens.image_shift_field_rates(wavelength_m, field);
        };
        let count = self.lens.orders(wavelength_m, field).len();
        let scale = self.lens.focal_length() * lambda_j / wavelength_m;
        let rates = [scale * field.x_rad.tan(), scale * field.y_rad.tan()];
        Some((0..count).map(|o| if o == self.channel { rates } else { [0.0, 0.0] }).collect())
    }

    /// For order `j`: `[(λ/λ_j) K, 0]` for its wavelength, `[0, τ_j]` for its own efficiency;
    /// `[0, 0]` for the others (the defocus and weight alone: off axis the lateral colour's
    /// share is [`channel_off_axis`]'s lane of one order's shift). `None` off axis unless the
    /// view is [`channel_off_axis`]'s, or where order `j` is not the full circle with a defocus
    /// alone, or with Zernike terms alone ([`own_defocus`]; for the wavelength: `(1 − λ/λ_j) K`).
    fn design_wavelength_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        if !field.is_on_axis() && !self.off_axis_view() {
            return None;
        }
        let orders = self.lens.orders(wavelength_m, field);
        let f_number = self.lens.f_number();
        let k = self.lens.focal_length() / (8.0 * f_number * f_number);
        let order = orders.get(self.channel)?;
        let own = own_defocus(order)?;
        let rates = match self.moving {
            Moving::Wavelength(lambda_j) => {
                let expected = (1.0 - wavelength_m / lambda_j) * k;
                if (own - expected).abs() > 1e-12 * k {
                    return None;
                }
                [k * wavelength_m / lambda_j, 0.0]
            }
            Moving::Efficiency => [0.0, order.efficiency],
        };
        Some((0..orders.len()).map(|o| if o == self.channel { rates } else { [0.0, 0.0] }).collect())
    }
}

/// The order's own defocus `W020` (m) where it is the full circle with a defocus alone, or a
/// pupil of Zernike terms alone over it (`lenses::WithZernike`: the terms are µm RMS, keys of
/// their own that a channel's wavelength leaves as they are; the order's `defocus_m` carries
/// the pupil's best-fit defocus besides its own, left out here); `None` for another order.
fn own_defocus(order: &Order) -> Option<f64> {
    if !order.wavefront.is_defocus_only() {
        return None;
    }
    match &order.pupil {
        optics::Pupil::Full => Some(order.wavefront.defocus_m),
        optics::Pupil::Radial(p) if p.is_zernike_only() => Some(order.wavefront.defocus_m - p.fitted_defocus_m()),
        _ => None,
    }
}

impl OneChannel {
    /// Whether this view is [`channel_off_axis`]'s (its shift rates the channel's own for a
    /// wavelength; for an efficiency, whose shifts do not move, every such view).
    fn off_axis_view(&self) -> bool {
        self.shifts || matches!(self.moving, Moving::Efficiency)
    }
}

/// The evaluation of `scene` and the derivatives of its ASNR, mean MTF, SNR0 and photoelectrons
/// with respect to `ln λ_j` of the interleaved lens's channel `channel` at `wavelength_m` (m):
/// the design wavelength's gradient of the scene with its lens seen through a view that moves
/// that channel alone (`OneChannel`).
///
/// # Errors
/// The evaluation's, and [`Error::NotDifferentiable`] off axis where the value is not on the
/// exact 1-D engine over a band, and where the design wavelength's gradient is refused (naming
/// why); over a field-of-view list, any point's.
pub fn channel_wavelength_gradient(scene: &Scene, channel: usize, wavelength_m: f64) -> Result<Gradient, Error> {
    one_channel(scene, channel, Moving::Wavelength(wavelength_m))
}

/// As [`channel_wavelength_gradient`], with respect to `ln η_j` of channel `channel`'s own
/// efficiency (`τ_j = η_j/N²`, a constant): the lane with the rates `[0, τ_j]` of its order.
///
/// # Errors
/// As [`channel_wavelength_gradient`]'s.
pub fn channel_efficiency_gradient(scene: &Scene, channel: usize) -> Result<Gradient, Error> {
    one_channel(scene, channel, Moving::Efficiency)
}

/// The design wavelength's gradient of `scene` with its lens seen through [`OneChannel`]; off
/// axis [`channel_off_axis`]'s; over a `[[fields]]` list [`over_fields`]'s.
fn one_channel(scene: &Scene, channel: usize, moving: Moving) -> Result<Gradient, Error> {
    if !scene.fields().is_empty() {
        return over_fields(scene, channel, moving);
    }
    if !scene.field().is_on_axis() {
        return channel_off_axis(scene, channel, moving);
    }
    let lens: Arc<dyn LensModel> = Arc::new(OneChannel { lens: scene.lens_arc(), channel, moving, shifts: false });
    let seen = scene.clone().with_lens(lens);
    super::gradient(&seen, &[Parameter::DesignWavelength])
}

/// Over a `[[fields]]` list: the value is the weighted mean of the points' values (evaluate's
/// relative weights), so its derivative is the weighted mean of each point's, each point's on
/// axis or off as at a single `[field]` point.
fn over_fields(scene: &Scene, channel: usize, moving: Moving) -> Result<Gradient, Error> {
    let evaluation = crate::evaluate(scene)?;
    let largest = scene.fields().iter().map(|f| f.1).fold(0.0, f64::max);
    let total: f64 = scene.fields().iter().map(|f| f.1 / largest).sum();
    let mut sum = [0.0; 4];
    for &(field, weight) in scene.fields() {
        let g = one_channel(&scene.single_field(field), channel, moving)?;
        let share = weight / largest / total;
        for (s, d) in sum.iter_mut().zip([g.asnr[0], g.mean_mtf[0], g.snr0[0], g.photoelectrons[0]]) {
            *s += share * d;
        }
    }
    let [asnr, mean_mtf, snr0, photoelectrons] = sum.map(|d| vec![d]);
    Ok(Gradient { evaluation, asnr, mean_mtf, snr0, photoelectrons })
}

/// The interleaved lens seen with every channel's own rates at once: order `o`'s
/// `design_wavelength_rates` those of its own wavelength `λ_o` (`[(λ/λ_o) K, 0]`), so that the
/// design wavelength's lane restricted to order `o` is channel `o`'s ([`channel_gradients`]).
#[derive(Debug)]
struct AllChannels {
    lens: Arc<dyn LensModel>,
    /// each channel's wavelength λ_o (m), order `o`'s
    channels: Vec<f64>,
}

impl LensModel for AllChannels {
    forward_to_lens!();

    /// Order `o`'s `[(λ/λ_o) K, 0]`, each order [`OneChannel`]'s for its own channel; `None` on
    /// axis unless every order's own defocus ([`own_defocus`]) is `(1 − λ/λ_o) K`, and off axis.
    fn design_wavelength_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        if !field.is_on_axis() {
            return None;
        }
        let orders = self.lens.orders(wavelength_m, field);
        let f_number = self.lens.f_number();
        let k = self.lens.focal_length() / (8.0 * f_number * f_number);
        if orders.len() != self.channels.len() {
            return None;
        }
        orders
            .iter()
            .zip(&self.channels)
            .map(|(order, &lambda_o)| {
                let expected = (1.0 - wavelength_m / lambda_o) * k;
                own_defocus(order)
                    .filter(|own| (own - expected).abs() <= 1e-12 * k)
                    .map(|_| [k * wavelength_m / lambda_o, 0.0])
            })
            .collect()
    }
}

/// The evaluation of `scene` and the derivatives of its ASNR, mean MTF, SNR0 and photoelectrons
/// with respect to each of `wanted` (`(j, true)`: `ln λ_j` of channel `j`'s wavelength; `(j,
/// false)`: `ln η_j` of its own efficiency), in their order, for the interleaved lens whose
/// channels are at `channels` (m, order `o` channel `o`'s), all in one pass on the value's own
/// engine and rules: the mean with, beside each OTF value, each order's design lane (the
/// design wavelength's lane of that order alone, its rates `[(λ/λ_j) K, 0]`: channel `j`'s
/// wavelength) and each order's own weight `τ_j H_j` (its efficiency), each less `O` times its
/// normalization's rate ([`optics::Polychromatic::mean_mtf_and_order_lanes`]); the same lanes
/// [`channel_wavelength_gradient`] and [`channel_efficiency_gradient`] take one at a time
/// (docs/physics.md, "Gradients: the multiplexed lens"). With `aperture`, after them the
/// derivatives with respect to `ln F#` and then `ln f0` from the same OTFs: every channel's
/// defocus `W020_o = (1 − λ/λ_o) f0/(8F#²)` moves with `K = f0/(8F#²)`, so the defocus lane
/// `D_K` (the summed `τ_o w_o ∂H/∂w_o` beside each OTF value) and the pixel's `P_ν` give
/// `∂M̄/∂ln F# = P(ν_N)|O(ν_N)| − M̄ − P_ν − 2 D_K` and `∂M̄/∂ln f0 = D_K` as on the value's
/// own rule (`defocus_on_value_rule`), `N` and the stray light `∝ 1/F#²`. `evaluation`: the
/// scene's, where the caller has it. `None` where that engine does not give them (off axis, a
/// `[[fields]]` list, a noise spectrum, an engine other than the per-frequency product rule):
/// the one-at-a-time functions and the scene's gradient take the keys then.
///
/// # Errors
/// The evaluation's, and [`Error::NotDifferentiable`] where the pixel saturates or there is no
/// signal.
pub fn channel_gradients(
    scene: &Scene,
    channels: &[f64],
    wanted: &[(usize, bool)],
    aperture: bool,
    evaluation: Option<crate::Evaluation>,
) -> Result<Option<Gradient>, Error> {
    if (wanted.is_empty() && !aperture)
        || wanted.iter().any(|&(j, _)| j >= channels.len())
        || !scene.fields().is_empty()
        || !scene.field().is_on_axis()
        || scene.camera().noise_spectrum().is_some()
    {
        return Ok(None);
    }
    let view = AllChannels { lens: scene.lens_arc(), channels: channels.to_vec() };
    let seen = scene.clone().with_lens(Arc::new(view));
    let detected = crate::evaluate::detected_spectrum(&seen);
    if detected.as_line().is_some() {
        return Ok(None);
    }
    let n = channels.len();
    let camera = seen.camera();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let Some((lanes, rates, d_aperture)) =
        super::on_value_engine(&seen, &detected, seen.options().settings(), |poly| {
            let (mean, lanes, _) = poly.mean_mtf_and_order_lanes(n)?;
            // ∂ln N/∂ln η_j = ∫ρ τ_j / ∫ρ Σ τ_o on the normalization's nodes
            let rates = poly.order_signal_shares(n)?;
            // the F-number's and focal length's lanes from the same OTFs (`defocus_on_value_rule`'s
            // forms, by parts in ν): the end term this engine's own
            let (d_k, pixel_slope) = (lanes[2 * n], lanes[2 * n + 1]);
            let d_aperture = aperture.then(|| {
                let edge = crate::evaluate::nyquist_edge(poly, camera.nyquist(), pixel);
                (edge - mean - pixel_slope - 2.0 * d_k, d_k)
            });
            Some((lanes, rates, d_aperture))
        })
    else {
        return Ok(None);
    };
    let e = match evaluation {
        Some(e) => e,
        None => crate::evaluate(scene)?,
    };
    let not_smooth =
        |reason: &str| Error::NotDifferentiable { parameter: "a channel's key", reason: reason.to_owned() };
    let chain = SignalChain::new(&seen, &e, not_smooth)?;
    let mut out = Gradient { asnr: vec![], mean_mtf: vec![], snr0: vec![], photoelectrons: vec![], evaluation: e };
    for &(j, wavelength) in wanted {
        // λ_j moves the OTF alone; η_j order j's weight, so N by its share (T held: the stray
        // light N_T − N by −∂N)
        let (d_mtf, rate) = match wavelength {
            true => (lanes[j], 0.0),
            false => (lanes[n + j], rates[j]),
        };
        chain.push(&mut out, rate, d_mtf, d_mtf);
    }
    if let Some((d_f_number, d_focal_length)) = d_aperture {
        // N and N_T ∝ NA² = 1/(4F#²): ∂ln/∂ln F# = −2 for both, so the stray light N_T − N too
        chain.push_moves(&mut out, -2.0, -2.0, d_f_number);
        chain.push_moves(&mut out, 0.0, 0.0, d_focal_length);
    }
    Ok(Some(out))
}

/// The share of the scene's tolerance the off-axis lanes are taken at ([`channel_off_axis`]).
const LANE_TOLERANCE_SHARE: f64 = 1e-2;

/// Off axis (docs/physics.md, "Gradients: the multiplexed lens"): along each azimuth φ each
/// node's OTF is `q τ_o H(νλF#, W020_o/λ) exp(−2πi ν u·Δ_o)` over `W = Σ q τ_o`, and channel
/// `j`'s wavelength moves order `j` alone: its defocus by `(λ/λ_j) K` and its lateral colour by
/// `∂Δ_j/∂ln λ_j = f0 tan θ λ_j/λ` (on each axis), a shift of one order against the others'
/// (not the design wavelength's scale of every order's shift). So
/// `∂M̄/∂ln λ_j = D_λ0 + D_Δj`, `D_λ0` the design wavelength's lane with order `j`'s rates and
/// `D_Δj` the field angles' lanes with order `j`'s shift rates, both on the exact 1-D engine's
/// nodes and the value's adaptive rule over azimuth
/// ([`optics::Polychromatic::mean_mtf_over_azimuth_and_design_shift_lanes`]); N does not move.
/// A channel's own efficiency moves order `j`'s weight alone, its shift held:
/// `∂M̄/∂ln η_j = D_λ0 − r M̄` with the rates `[0, τ_j]` and `r = ∂ln N/∂ln η_j`
/// ([`optics::Polychromatic::design_signal_rate`]). Under a noise spectrum each frequency's
/// weight divided by `n(ν)`, `M̄` the weighted mean. Then `∂SNR0 = (∂SNR0/∂N) ∂N` (the stray
/// light `N_T − N` by `−∂N`, T held) and `∂ASNR = ∂SNR0 G + SNR0 ∂G`, as every key's.
fn channel_off_axis(scene: &Scene, channel: usize, moving: Moving) -> Result<Gradient, Error> {
    let parameter = match moving {
        Moving::Wavelength(_) => "a channel's wavelength",
        Moving::Efficiency => "a channel's own efficiency",
    };
    let not_smooth = |reason: &str| Error::NotDifferentiable { parameter, reason: reason.to_owned() };
    let refused = || {
        not_smooth(
            "off axis a channel's lane is computed on the exact 1-D engine over a band (every channel the full \
             circle with a defocus alone, turned by its lateral colour); this scene's value is on another engine or \
             rule (a line spectrum, options.spectral_rule or a fixed frequency rule)",
        )
    };
    let e = crate::evaluate(scene)?;
    let view = OneChannel { lens: scene.lens_arc(), channel, moving, shifts: matches!(moving, Moving::Wavelength(_)) };
    let seen = scene.clone().with_lens(Arc::new(view));
    let field = seen.field();
    let detected = crate::evaluate::detected_spectrum(&seen);
    if detected.as_line().is_some() {
        return Err(refused());
    }
    let orders = seen.lens().orders(e.mean_wavelength_nm * 1e-9, field);
    let plain = orders.iter().all(|o| matches!(o.pupil, optics::Pupil::Full) && o.wavefront.is_defocus_only());
    if orders.len() <= channel || !plain {
        return Err(refused());
    }
    let camera = seen.camera();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(seen.lens(), &detected);
    let parts = folded.parts();
    // the lanes on the value's engine at a hundredth of its tolerance: channel j's shift lane
    // carries 2πν u·δΔ_j with δΔ_j = f0 tan θ λ_j/λ, the whole displacement (not the small
    // lateral colour Δ_j), which turns much faster than |O| and is not resolved to the
    // tolerance by the rule that converges |O| (measured at 1e-6 on the interleaved design at
    // 3°: 1e-5 of the gradient's norm; at a hundredth, within it)
    let mut settings = seen.options().settings();
    settings.tolerance *= LANE_TOLERANCE_SHARE;
    let poly =
        optics::Polychromatic::with_parts(seen.lens(), &detected, &parts, field, camera.nyquist(), pixel, settings)
            .map_err(|_| refused())?;
    if poly.engine() != optics::Engine::Exact1d || poly.has_pupil_grid() {
        return Err(refused());
    }
    let rate = poly.design_signal_rate().ok_or_else(refused)?;
    let along_field = field.y_rad.atan2(field.x_rad);
    // ∂M̄ (white, or over the noise spectrum)
    let d_mean = |noise: Option<&optics::NoiseShape>| -> Result<f64, Error> {
        match moving {
            Moving::Wavelength(_) => {
                let (mean, design, shift) =
                    poly.mean_mtf_over_azimuth_and_design_shift_lanes(along_field, noise).ok_or_else(refused)?;
                Ok(design - rate * mean + shift)
            }
            Moving::Efficiency => {
                let (mean, design, _, _) =
                    poly.mean_mtf_over_azimuth_and_design_lanes(along_field, noise).ok_or_else(refused)?;
                Ok(design - rate * mean)
            }
        }
    };
    let d_mtf = d_mean(None)?;
    let d_weighted = match camera.noise_spectrum() {
        Some(shape) => d_mean(Some(shape))?,
        None => d_mtf,
    };
    one_key(&seen, e, rate, d_mtf, d_weighted, not_smooth)
}

/// The gradient along one key of `scene`'s evaluation `e` that moves the detected signal N at the
/// relative rate `rate` (`∂ln N`) and the mean MTF by `d_mtf` (white) and `d_weighted` (the
/// noise-weighted mean the ASNR reads): SNR0 through the noise budget exactly as `evaluate`
/// forms it (the stray light moving with N where the glare is included), the ASNR = SNR0 ·
/// G. Refused (`not_smooth`) where the pixel saturates or there is no signal.
pub(super) fn one_key(
    scene: &Scene,
    e: crate::Evaluation,
    rate: f64,
    d_mtf: f64,
    d_weighted: f64,
    not_smooth: impl Fn(&str) -> Error,
) -> Result<Gradient, Error> {
    let chain = SignalChain::new(scene, &e, not_smooth)?;
    let mut out = Gradient { asnr: vec![], mean_mtf: vec![], snr0: vec![], photoelectrons: vec![], evaluation: e };
    chain.push(&mut out, rate, d_mtf, d_weighted);
    Ok(out)
}

/// SNR0's partials in the charges of an evaluation's noise budget, formed exactly as `evaluate`
/// forms it, for the keys [`one_key`] and [`channel_gradients`] chain through it.
struct SignalChain<'a> {
    scene: &'a Scene,
    partials: noise::SnrPartials,
    /// Whether the stray light `N_T − N` is in the budget (moving by `−∂N`, T held).
    stray: bool,
    /// The stray light `N_T − N` in the budget (0 without it).
    background: f64,
}

impl<'a> SignalChain<'a> {
    /// The budget of `scene`'s evaluation `e`; refused (`not_smooth`) where the pixel saturates
    /// or there is no signal.
    fn new(scene: &'a Scene, e: &crate::Evaluation, not_smooth: impl Fn(&str) -> Error) -> Result<Self, Error> {
        let n = e.photoelectrons;
        let background = match scene.options().glare {
            crate::GlareMode::FirstOrder => 0.0,
            crate::GlareMode::Included => (e.transmitted_photoelectrons - n).max(0.0),
        };
        let budget = noise::budget(scene.camera().sensor(), n, background, scene.exposure())?;
        let Some(partials) = budget.snr_partials() else {
            return Err(not_smooth(if budget.saturated {
                "the pixel saturates: the charges are clipped at the well, where the SNR has a kink"
            } else {
                "there is no signal"
            }));
        };
        let stray = matches!(scene.options().glare, crate::GlareMode::Included) && background > 0.0;
        Ok(SignalChain { scene, partials, stray, background })
    }

    /// One key's derivatives appended to `out` where N moves at the relative rate `rate` and the
    /// stray light `N_T − N` at its own `stray_rate` (the aperture's keys: N_T and N alike), the
    /// mean MTF by `d_mtf` (white: no noise spectrum); `∂ASNR = ∂SNR0 G + SNR0 ∂G`.
    fn push_moves(&self, out: &mut Gradient, rate: f64, stray_rate: f64, d_mtf: f64) {
        let d_n = out.evaluation.photoelectrons * rate;
        let d_b = if self.stray { self.background * stray_rate } else { 0.0 };
        self.push_with(out, d_n, d_b, d_mtf, d_mtf);
    }

    /// One key's derivatives appended to `out` (whose evaluation the budget is): N moving at the
    /// relative rate `rate`, the mean MTF by `d_mtf` (white) and `d_weighted` (the mean the ASNR
    /// reads); `∂ASNR = ∂SNR0 G + SNR0 ∂G`.
    fn push(&self, out: &mut Gradient, rate: f64, d_mtf: f64, d_weighted: f64) {
        let d_n = out.evaluation.photoelectrons * rate;
        self.push_with(out, d_n, if self.stray { -d_n } else { 0.0 }, d_mtf, d_weighted);
    }

    /// One key's derivatives appended to `out`: N moving by `d_n`, the stray light by `d_b`, the
    /// mean MTF by `d_mtf` (white) and `d_weighted` (the mean the ASNR reads).
    fn push_with(&self, out: &mut Gradient, d_n: f64, d_b: f64, d_mtf: f64, d_weighted: f64) {
        let e = &out.evaluation;
        let d_snr0 = self.partials.signal * d_n + self.partials.variance * d_b;
        let d_g = super::d_g_from_mean_mtf(self.scene, e, d_weighted);
        let d_asnr = d_snr0 * (e.asnr / e.snr0) + e.snr0 * d_g;
        out.asnr.push(d_asnr);
        out.mean_mtf.push(d_mtf);
        out.snr0.push(d_snr0);
        out.photoelectrons.push(d_n);
    }
}
