//! A line whose orders are on FFT grids (the line engine with grids: an annulus, Seidel terms on
//! the full circle or through an iris, Zernike terms): the F-number, the focal length, the design
//! wavelength and the line's wavelength on the line's own grids (docs/physics.md, "Gradients: the
//! F-number, the focal length and the wavelengths under a line on the grids").

use std::sync::Arc;

use super::{Error, Scene, with_value_engine};

/// `f` on the value's engine where it is a line's FFT grids on axis, every order the full circle,
/// an aperture or a radial pupil without an image shift, and a lens that gives no aperture
/// directions of its own (a phase lens's ride on the radial engine) and gives its orders' rates
/// in λ ([`wavelength_rates`]: the chromatic, refractive, harmonic and interleaved lenses, whose
/// defocus is `K = f0/(8F#²)` times a function of λ; not a dispersion-engineered lens, whose
/// aperture keys move its group delay too, "Gradients: the dispersion-engineered lens");
/// `Ok(None)` elsewhere.
fn with_line_grids<T>(
    scene: &Scene,
    f: impl FnOnce(&optics::Polychromatic<'_>) -> Result<Option<T>, Error>,
) -> Result<Option<T>, Error> {
    let detected = crate::evaluate::detected_spectrum(scene);
    let Some(c) = detected.line().map(|l| l.center()) else { return Ok(None) };
    let lens = scene.lens();
    let field = scene.field();
    if !field.is_on_axis() || lens.aperture_directions(c).is_some() || wavelength_rates(scene, c).is_none() {
        return Ok(None);
    }
    let orders = lens.orders(c, field);
    let sampled = !orders.is_empty()
        && orders.iter().all(|o| {
            o.wavefront.image_shift_m == [0.0, 0.0]
                && matches!(o.pupil, optics::Pupil::Full | optics::Pupil::Aperture(_) | optics::Pupil::Radial(_))
        });
    if !sampled {
        return Ok(None);
    }
    with_value_engine(scene, &detected, scene.options().settings(), |poly| {
        if !matches!(poly.engine(), optics::Engine::Monochromatic { fft: Some(_) }) {
            return Ok(None);
        }
        f(poly)
    })
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` under a line on its FFT grids: the pupil (obscuration, iris,
/// Seidel and Zernike coefficients) is fixed in units of the aperture's radius, so at a fixed
/// defocus `W020 ∝ K = f0/(8F#²)` the F-number moves each grid's reading `s = νcF#` alone (the
/// frequency-scale lane `D_s` on the value's fixed rule,
/// [`optics::Polychromatic::line_mean_mtf_over_azimuth_scale_lane`]) and `K` every order's
/// defocus by itself (`D_K`, [`optics::WavefrontDirection::Defocus`] by forward mode through the
/// line's grids): `∂M̄/∂ln F# = D_s − 2 D_K`, `∂M̄/∂ln f0 = D_K`. `None` where the scene is not
/// that.
pub(super) fn aperture_on_line_grids(scene: &Scene) -> Result<Option<(f64, f64)>, Error> {
    with_line_grids(scene, |poly| {
        let directions = [optics::WavefrontDirection::Defocus];
        let Some((_, lanes)) = poly.line_mean_mtf_over_azimuth_and_gradient(0.0, &directions, None)? else {
            return Ok(None);
        };
        let Some(d_s) = poly.line_mean_mtf_over_azimuth_scale_lane(0.0) else { return Ok(None) };
        Ok(Some((d_s - 2.0 * lanes[0], lanes[0])))
    })
}

/// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` under a line on its FFT grids: λ0 moves each order's defocus by
/// `∂W020/∂ln λ0` and its efficiency by `∂τ/∂ln λ0` (`LensModel::design_wavelength_rates`), the
/// lane `D_λ0` ([`optics::WavefrontDirection::DesignWavelength`] on the line's grids) and
/// `∂M̄ = D_λ0 − r M̄`, `r = ∂ln N/∂ln λ0` on the line's node. Under a noise spectrum (`noise`)
/// each frequency's weight divided by `n(ν)` and `M̄` the weighted mean, as the value's. `None`
/// where the scene is not that or the lens gives no rates.
pub(super) fn design_wavelength_on_line_grids(
    scene: &Scene,
    noise: Option<&optics::NoiseShape>,
) -> Result<Option<(f64, f64)>, Error> {
    with_line_grids(scene, |poly| {
        let Some(rate) = poly.design_signal_rate() else { return Ok(None) };
        let directions = [optics::WavefrontDirection::DesignWavelength];
        let Some((mean, lanes)) = poly.line_mean_mtf_over_azimuth_and_gradient(0.0, &directions, noise)? else {
            return Ok(None);
        };
        Ok(Some((rate, lanes[0] - rate * mean.mean)))
    })
}

/// Each order's `[c ∂W020_o/∂c, c ∂τ_o/∂c]` at the line's wavelength `c` and `∂ln T/∂c`, from
/// the lens's own rates (`LensModel::defocus_rates` for one order, `order_wavelength_rates` for
/// several); `None` where it gives none.
fn wavelength_rates(scene: &Scene, c: f64) -> Option<(Vec<[f64; 2]>, f64)> {
    let lens = scene.lens();
    let field = scene.field();
    let orders = lens.orders(c, field);
    if let [o] = &orders[..]
        && let Some(r) = lens.defocus_rates(c, field)
    {
        return Some((vec![[c * r.defocus, c * r.ln_efficiency * o.efficiency]], r.ln_transmission));
    }
    let rates = lens.order_wavelength_rates(c, field)?;
    if rates.orders.len() != orders.len() {
        return None;
    }
    Some((rates.orders.iter().map(|[w, t]| [c * w, c * t]).collect(), rates.ln_transmission))
}

/// The lens with its design-wavelength rates replaced by the line's wavelength's own
/// (`[c ∂W020_o/∂c, c ∂τ_o/∂c]` per order), so that the FFT grids'
/// [`optics::WavefrontDirection::DesignWavelength`] lane carries `∂/∂ln c` of the orders'
/// defocus and efficiencies; everything else the lens's own.
#[derive(Debug)]
struct LineRates {
    inner: Arc<dyn optics::LensModel>,
    rates: Vec<[f64; 2]>,
}

impl optics::LensModel for LineRates {
    fn f_number(&self) -> f64 {
        self.inner.f_number()
    }
    fn focal_length(&self) -> f64 {
        self.inner.focal_length()
    }
    fn orders(&self, wavelength_m: f64, field: optics::Field) -> Vec<optics::Order> {
        self.inner.orders(wavelength_m, field)
    }
    fn orders_into(&self, wavelength_m: f64, field: optics::Field, out: &mut Vec<optics::Order>) {
        self.inner.orders_into(wavelength_m, field, out)
    }
    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.inner.efficiency(wavelength_m)
    }
    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.inner.transmission(wavelength_m)
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.inner.breakpoints()
    }
    fn numerical_aperture(&self) -> f64 {
        self.inner.numerical_aperture()
    }
    fn design_wavelength(&self) -> Option<f64> {
        self.inner.design_wavelength()
    }
    fn design_wavelength_rates(&self, _wavelength_m: f64, _field: optics::Field) -> Option<Vec<[f64; 2]>> {
        Some(self.rates.clone())
    }
    fn defocus_rates(&self, wavelength_m: f64, field: optics::Field) -> Option<optics::DefocusRates> {
        self.inner.defocus_rates(wavelength_m, field)
    }
    fn order_wavelength_rates(&self, wavelength_m: f64, field: optics::Field) -> Option<optics::OrderWavelengthRates> {
        self.inner.order_wavelength_rates(wavelength_m, field)
    }
    fn describe(&self) -> String {
        self.inner.describe()
    }
}

/// `(∂ln N/∂c, ∂ln N_T/∂c, ∂M̄/∂c)` of a line's wavelength `c` on the line's FFT grids, per m,
/// `d_ln_n` the line weight's own rate. Each order's field is `P = A exp(2πi W/c)` read at
/// `s = νcF#`, `W = W020_o(c) ρ² + W_S + W_Z` (the Seidel and Zernike terms fixed in metres), so
/// per unit `ln c`:
/// - the reading moves as under the F-number: `D_s` on the value's fixed rule;
/// - the orders move by `c ∂W020_o/∂c` and `c ∂τ_o/∂c`: the lane `D_c`
///   ([`optics::WavefrontDirection::DesignWavelength`] on the lens with those rates, its node
///   weights `w ∂τ_o`) less `r M̄`, `r = Σ c ∂τ_o/Σ τ_o`;
/// - the waves `W/c` scale down: `−D_W`, `D_W = D_K + Σ_t s_t D_t + Σ_j z_j D_j` the defocus lane and
///   each Seidel and Zernike term's lane times its coefficient (µm), the whole sampled OPD;
///
/// so `∂M̄/∂ln c = D_s + D_c − r M̄ − D_W` and `∂ln N/∂c = ∂ln w/∂c + r/c`. `Ok(None)` where the
/// scene is not a line on its grids or the lens gives no rates.
pub(super) fn line_center_on_grids(scene: &Scene, c: f64, d_ln_n: f64) -> Result<Option<(f64, f64, f64)>, Error> {
    use optics::{SeidelTerm, WavefrontDirection as D};
    let lens = scene.lens();
    let Some((rates, ln_transmission)) = wavelength_rates(scene, c) else { return Ok(None) };
    let orders = lens.orders(c, scene.field());
    // the fixed terms' directions and coefficients (µm): every order carries the same terms
    let mut directions = vec![D::DesignWavelength, D::Defocus];
    let mut weights = vec![0.0, 0.0];
    if let Some(o) = orders.first() {
        let w = &o.wavefront;
        for (term, value) in [
            (SeidelTerm::Spherical, w.spherical_m),
            (SeidelTerm::Coma, w.coma_m),
            (SeidelTerm::Astigmatism, w.astigmatism_m),
            (SeidelTerm::FieldCurvature, w.field_curvature_m),
        ] {
            if value != 0.0 {
                directions.push(D::Seidel(term));
                weights.push(value * 1e6);
            }
        }
        if let optics::Pupil::Radial(radial) = &o.pupil {
            for &(j, value) in radial.zernike_noll_m() {
                if value != 0.0 {
                    directions.push(D::Zernike(j));
                    weights.push(value * 1e6);
                }
            }
        }
    }
    let same = |o: &optics::Order| {
        let w = &o.wavefront;
        let first = &orders[0].wavefront;
        [w.spherical_m, w.coma_m, w.astigmatism_m, w.field_curvature_m]
            == [first.spherical_m, first.coma_m, first.astigmatism_m, first.field_curvature_m]
    };
    if !orders.iter().all(same) {
        return Ok(None);
    }
    let moved = scene.clone().with_lens(Arc::new(LineRates { inner: scene.lens_arc(), rates }));
    with_line_grids(&moved, |poly| {
        let Some(rate) = poly.design_signal_rate() else { return Ok(None) };
        let Some((mean, lanes)) = poly.line_mean_mtf_over_azimuth_and_gradient(0.0, &directions, None)? else {
            return Ok(None);
        };
        let Some(d_s) = poly.line_mean_mtf_over_azimuth_scale_lane(0.0) else { return Ok(None) };
        let d_w: f64 = lanes[1] + lanes.iter().zip(&weights).skip(2).map(|(d, w)| d * w).sum::<f64>();
        let d_log_c = d_s + lanes[0] - rate * mean.mean - d_w;
        Ok(Some((d_ln_n + rate / c, d_ln_n + ln_transmission, d_log_c / c)))
    })
}
