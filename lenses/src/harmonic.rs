//! The harmonic (multi-order) diffractive lens.

use optics::{Field, LensModel, Order, OrderWavelengthRates, Pupil, Wavefront};

use crate::Error;
use crate::chromatic::{Curve, check, check_efficiency_below_transmission, check_fraction};

/// Orders farther than this from `α = pλ0/λ` are not modelled (their light is background).
pub const HARMONIC_ORDER_REACH: f64 = 3.0;

/// `sinc x = sin(πx)/(πx)`, exactly 0 at the non-zero integers and 1 at 0.
pub fn sinc(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else if x.fract() == 0.0 {
        0.0
    } else {
        let px = std::f64::consts::PI * x;
        px.sin() / px
    }
}

/// A harmonic (multi-order) diffractive lens of design order `p`: its phase wraps at `2πp` at
/// the design wavelength λ0, so light of wavelength λ sees the phase depth `α(λ) = pλ0/λ` waves
/// and diffracts into the orders `m` with scalar efficiency `τ_m = τ_base sinc²(α − m)`
/// (docs/physics.md, "Lens families"). Order `m` focuses at `f_m(λ) = f0 pλ0/(mλ)`, so with the
/// detector at `f0`
/// `W020_m(λ) = (1 − mλ/(pλ0)) f0/(8F#²)` (docs/physics.md, "Sign of the wavefront": `W020 > 0`
/// behind the detector). At λ0 order `p` carries `τ_base` in focus; `p = 1` is the chromatic lens
/// ([`crate::ChromaticMetalens`] with `τ1(λ) = τ_base sinc²(λ0/λ − 1)`).
///
/// The orders modelled are `m ≥ 1` with `|m − α| ≤ 3` ([`HARMONIC_ORDER_REACH`]); they hold at
/// least 93.3 % of `Σ_m sinc²(α − m) = 1` when `α ≥ 4` (the least at half-integer `α`), the rest,
/// and the zero and negative orders, is background within `T`. Off axis each order has the
/// lateral colour of its focal length behind a remote stop, `f0 tan θ (pλ0/(mλ) − 1)`, as the
/// chromatic lens. The total transmission `T(λ)` is an input with `T ≥ τ_base`, which bounds
/// `Σ τ_m` at every wavelength.
#[derive(Clone, Debug)]
pub struct Harmonic {
    f_number: f64,
    focal_length: f64,
    design_wavelength: f64,
    design_order: u32,
    base_efficiency: f64,
    transmission: Curve,
}

impl Harmonic {
    /// A harmonic lens of working F-number `f_number` (≥ 0.5), focal length `focal_length_m` at
    /// `design_wavelength_m`, design order `design_order` (1 to 1000), peak efficiency
    /// `base_efficiency` (a fraction) and total transmission `transmission` (fractions,
    /// `τ_base ≤ T`).
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        design_wavelength_m: f64,
        design_order: u32,
        base_efficiency: f64,
        transmission: Curve,
    ) -> Result<Self, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        check("design_wavelength", design_wavelength_m, design_wavelength_m > 0.0, "a finite wavelength > 0 m")?;
        let p = f64::from(design_order);
        check("design_order", p, (1.0..=1000.0).contains(&p), "a whole number from 1 to 1000")?;
        check("base_efficiency", base_efficiency, (0.0..=1.0).contains(&base_efficiency), "a fraction in [0, 1]")?;
        check_fraction("transmission", &transmission)?;
        check_efficiency_below_transmission(&|_| base_efficiency, &[], &transmission, design_wavelength_m)?;
        Ok(Harmonic {
            f_number,
            focal_length: focal_length_m,
            design_wavelength: design_wavelength_m,
            design_order,
            base_efficiency,
            transmission,
        })
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "harmonic"
    }

    /// The phase depth in waves at `wavelength_m`: `α = pλ0/λ`.
    pub fn phase_depth(&self, wavelength_m: f64) -> f64 {
        f64::from(self.design_order) * self.design_wavelength / wavelength_m
    }

    /// The orders modelled at `wavelength_m`: `m ≥ 1`, `|m − α| ≤ 3`.
    pub fn order_range(&self, wavelength_m: f64) -> std::ops::RangeInclusive<u32> {
        let alpha = self.phase_depth(wavelength_m);
        let lo = (alpha - HARMONIC_ORDER_REACH).ceil().max(1.0);
        let hi = (alpha + HARMONIC_ORDER_REACH).floor().max(0.0);
        // bounded: α ≤ p λ0/λ is finite for λ > 0, and order numbers beyond u32 carry nothing
        (lo.min(f64::from(u32::MAX)) as u32)..=(hi.min(f64::from(u32::MAX)) as u32)
    }

    /// Efficiency of order `m` at `wavelength_m`: `τ_base sinc²(α − m)`.
    pub fn order_efficiency(&self, m: u32, wavelength_m: f64) -> f64 {
        self.base_efficiency * sinc(self.phase_depth(wavelength_m) - f64::from(m)).powi(2)
    }

    /// Defocus of order `m` at `wavelength_m`: `W020_m = (1 − mλ/(pλ0)) f0/(8F#²)`.
    pub fn order_defocus(&self, m: u32, wavelength_m: f64) -> f64 {
        let ratio = f64::from(m) * wavelength_m / (f64::from(self.design_order) * self.design_wavelength);
        (1.0 - ratio) * self.focal_length / (8.0 * self.f_number * self.f_number)
    }
}

impl LensModel for Harmonic {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        let alpha = self.phase_depth(wavelength_m);
        self.order_range(wavelength_m)
            .map(|m| {
                // lateral colour of order m: h = f_m tan θ against h0 = f0 tan θ
                let k = alpha / f64::from(m) - 1.0;
                let [dx, dy] = [self.focal_length * field.x_rad.tan() * k, self.focal_length * field.y_rad.tan() * k];
                let wavefront = Wavefront::defocus(self.order_defocus(m, wavelength_m)).shifted(dx, dy);
                Order::new(self.order_efficiency(m, wavelength_m), Pupil::Full, wavefront)
            })
            .collect()
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.transmission.value(wavelength_m)
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.design_wavelength)
    }

    /// Each order's lateral colour `Δ = f0 tan θ (α/m − 1)` on each axis (as
    /// [`orders`](LensModel::orders) forms it) moves as `∂Δx/∂θx = f0 sec²θx (α/m − 1)` (and the
    /// same in y); the orders' defocus, efficiency and full pupil are the same at every field
    /// point (docs/physics.md, "Gradients: the field point"). One entry per order of
    /// [`orders`](LensModel::orders), in its order.
    fn image_shift_field_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        let alpha = self.phase_depth(wavelength_m);
        let sec2 = |angle: f64| 1.0 / (angle.cos() * angle.cos());
        let (sx, sy) = (self.focal_length * sec2(field.x_rad), self.focal_length * sec2(field.y_rad));
        Some(
            self.order_range(wavelength_m)
                .map(|m| {
                    let k = alpha / f64::from(m) - 1.0;
                    [sx * k, sy * k]
                })
                .collect(),
        )
    }

    /// Each order's `W020_m = (1 − mλ/(pλ0)) f0/(8F#²)` moves as `−m/(pλ0) f0/(8F#²)` and its
    /// `τ_m = τ_base sinc²(α − m)`, `α = pλ0/λ`, as `2 τ_base sinc(x) sinc′(x) ∂α/∂λ` with
    /// `x = α − m`, `∂α/∂λ = −α/λ`, `sinc′(x) = (cos πx − sinc x)/x` (`−π²x/3` near 0); one entry
    /// per order of [`orders`](LensModel::orders), in its order. The orders entering or leaving
    /// the range `|m − α| ≤ 3` do so at `sinc²(±3) = 0` with a zero slope, so the sum stays C¹.
    /// `None` with a transmission table (its slope is not followed) and off axis (lateral colour).
    fn order_wavelength_rates(&self, wavelength_m: f64, field: Field) -> Option<OrderWavelengthRates> {
        if !field.is_on_axis() || !matches!(self.transmission, Curve::Constant(_)) {
            return None;
        }
        let alpha = self.phase_depth(wavelength_m);
        let d_alpha = -alpha / wavelength_m;
        let p_lambda0 = f64::from(self.design_order) * self.design_wavelength;
        let k = self.focal_length / (8.0 * self.f_number * self.f_number);
        let orders = self
            .order_range(wavelength_m)
            .map(|m| {
                let x = alpha - f64::from(m);
                let slope = if x.abs() < 1e-4 {
                    -std::f64::consts::PI.powi(2) * x / 3.0
                } else {
                    ((std::f64::consts::PI * x).cos() - sinc(x)) / x
                };
                [-f64::from(m) / p_lambda0 * k, 2.0 * self.base_efficiency * sinc(x) * slope * d_alpha]
            })
            .collect();
        Some(OrderWavelengthRates { orders, ln_transmission: 0.0 })
    }

    /// Each order's `W020_m = (1 − mλ/(pλ0)) f0/(8F#²)` moves as `∂W020_m/∂ln λ0 =
    /// (mλ/(pλ0)) f0/(8F#²)` and its `τ_m = τ_base sinc²(α − m)`, `α = pλ0/λ`, as
    /// `2 τ_base sinc(x) sinc′(x) α` with `x = α − m` (`∂α/∂ln λ0 = α`), `sinc′` as in
    /// [`order_wavelength_rates`](LensModel::order_wavelength_rates); T does not depend on λ0. The
    /// orders entering or leaving the range `|m − α| ≤ 3` do so at `sinc²(±3) = 0` with a zero
    /// slope, so the sum stays C¹. The same at every field point: off axis each order's lateral
    /// colour `Δ_m = f0 tan θ (α/m − 1)` moves as `Δ_m + f0 tan θ` (`LensModel::design_wavelength_rates`).
    fn design_wavelength_rates(&self, wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        let alpha = self.phase_depth(wavelength_m);
        let p_lambda0 = f64::from(self.design_order) * self.design_wavelength;
        let k = self.focal_length / (8.0 * self.f_number * self.f_number);
        Some(
            self.order_range(wavelength_m)
                .map(|m| {
                    let x = alpha - f64::from(m);
                    let slope = if x.abs() < 1e-4 {
                        -std::f64::consts::PI.powi(2) * x / 3.0
                    } else {
                        ((std::f64::consts::PI * x).cos() - sinc(x)) / x
                    };
                    [f64::from(m) * wavelength_m / p_lambda0 * k, 2.0 * self.base_efficiency * sinc(x) * slope * alpha]
                })
                .collect(),
        )
    }

    /// With a transmission table: one part (no efficiency table: the orders' efficiencies are
    /// smooth), the lens with transmission 1, so that the table's rows cut no spectral panel.
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        crate::chromatic::factor_one_curve(&Curve::Constant(1.0), &self.transmission, 1.0, |_, transmission| {
            std::sync::Arc::new(Harmonic { transmission, ..self.clone() })
        })
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.transmission.breakpoints().to_vec()
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        format!(
            "harmonic diffractive lens F/{} f0 = {} mm at λ0 = {} nm, design order p = {}, τ_base = {}",
            r(self.f_number),
            r(self.focal_length * 1e3),
            r(self.design_wavelength * 1e9),
            self.design_order,
            r(self.base_efficiency)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens(p: u32) -> Harmonic {
        Harmonic::new(2.5, 3.36e-3, 800e-9, p, 0.4, Curve::Constant(0.6)).unwrap()
    }

    /// `design_wavelength_rates` against central differences of each order's defocus and
    /// efficiency of lenses built at λ0 ± h (relative step 1e-6), at wavelengths where the order
    /// range is the same on both sides; off axis the same, and each order's lateral colour's rate
    /// `Δ_m + f0 tan θ` against differences of the orders' image shifts.
    #[test]
    fn design_wavelength_rates_match_differences() {
        let at = |l0: f64| Harmonic::new(2.5, 3.36e-3, l0, 5, 0.4, Curve::Constant(0.6)).unwrap();
        let h = 1e-6;
        let (up, down) = (at(800e-9 * (1.0 + h)), at(800e-9 * (1.0 - h)));
        let step = (1.0 + h).ln() - (1.0 - h).ln();
        for l in [760e-9, 803e-9, 845e-9] {
            let rates = lens(5).design_wavelength_rates(l, Field::ON_AXIS).unwrap();
            let orders: Vec<u32> = lens(5).order_range(l).collect();
            assert_eq!(rates.len(), orders.len());
            for (&m, [d_w, d_tau]) in orders.iter().zip(rates) {
                let w = (up.order_defocus(m, l) - down.order_defocus(m, l)) / step;
                let t = (up.order_efficiency(m, l) - down.order_efficiency(m, l)) / step;
                assert!((d_w - w).abs() <= 1e-7 * w.abs(), "{l} m = {m}: {d_w} vs {w}");
                assert!((d_tau - t).abs() <= 1e-7 * t.abs().max(1e-3), "{l} m = {m}: {d_tau} vs {t}");
            }
        }
        // off axis: the same rates, and each order's lateral colour moves as Δ_m + f0 tan θ
        let field = Field::new(0.05, -0.03);
        for l in [760e-9, 845e-9] {
            assert_eq!(lens(5).design_wavelength_rates(l, field), lens(5).design_wavelength_rates(l, Field::ON_AXIS));
            let (hi, lo, own) = (up.orders(l, field), down.orders(l, field), at(800e-9).orders(l, field));
            assert_eq!((hi.len(), lo.len()), (own.len(), own.len()));
            for ((u, d), o) in hi.iter().zip(&lo).zip(&own) {
                for (a, angle) in [field.x_rad, field.y_rad].into_iter().enumerate() {
                    let rate = (u.wavefront.image_shift_m[a] - d.wavefront.image_shift_m[a]) / step;
                    let want = o.wavefront.image_shift_m[a] + 3.36e-3 * angle.tan();
                    assert!((rate - want).abs() <= 1e-7 * want.abs(), "{l} axis {a}: {rate} vs {want}");
                }
            }
        }
    }

    #[test]
    fn sinc_squared_sums_to_one_and_the_truncation_keeps_most() {
        // Σ over all integers m of sinc²(α − m) = 1; ±200 000 terms leave a tail below 2e-6
        let mut least_kept: f64 = 1.0;
        for k in 0..=40 {
            let alpha = 4.0 + k as f64 / 40.0;
            let all: f64 = (-200_000..=200_000).map(|m| sinc(alpha - f64::from(m)).powi(2)).sum();
            assert!((all - 1.0).abs() < 2e-6, "α {alpha}: {all}");
            let l = lens(5);
            let lambda = 5.0 * 800e-9 / alpha;
            let kept: f64 = l.order_range(lambda).map(|m| sinc(alpha - f64::from(m)).powi(2)).sum();
            least_kept = least_kept.min(kept);
        }
        // the least at α half-integer: 1 − (2/π²) Σ_{j ≥ 3} 1/(j + 1/2)²
        // = 1 − (2/π²)(π²/2 − 4 − 4/9 − 4/25) = 0.933056
        assert!((least_kept - 0.933056).abs() < 1e-5, "{least_kept}");
    }

    #[test]
    fn design_order_is_in_focus_at_the_design_wavelength() {
        for p in [1, 2, 5] {
            let l = lens(p);
            let orders = l.orders(800e-9, Field::ON_AXIS);
            let m_lo = p.saturating_sub(3).max(1);
            assert_eq!(orders.len() as u32, p + 3 - m_lo + 1);
            for (m, o) in l.order_range(800e-9).zip(&orders) {
                if m == p {
                    assert_eq!((o.efficiency, o.wavefront.defocus_m), (0.4, 0.0));
                } else {
                    assert_eq!(o.efficiency, 0.0, "p {p}, m {m}");
                }
            }
            assert_eq!(l.efficiency(800e-9), 0.4);
        }
    }

    #[test]
    fn first_order_of_p1_is_the_chromatic_lens() {
        let h = lens(1);
        let waves: Vec<f64> = (0..=40).map(|k| 600e-9 + 10e-9 * f64::from(k)).collect();
        let tau1: Vec<f64> = waves.iter().map(|&l| 0.4 * sinc(800e-9 / l - 1.0).powi(2)).collect();
        let table = radiometry::Sampled::new(waves.clone(), tau1).unwrap();
        let c = crate::ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Table(table), Curve::Constant(0.6)).unwrap();
        let field = Field::new(0.1, -0.05);
        for &lambda in &waves {
            let first = h.orders(lambda, field).into_iter().next().unwrap();
            let chromatic = &c.orders(lambda, field)[0];
            assert_eq!(first.wavefront.defocus_m, c.defocus(lambda), "{lambda}");
            assert!((first.efficiency - chromatic.efficiency).abs() < 1e-15, "{lambda}");
            for i in 0..2 {
                let (a, b) = (first.wavefront.image_shift_m[i], chromatic.wavefront.image_shift_m[i]);
                assert!((a - b).abs() < 1e-18, "{lambda}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn higher_orders_focus_in_front_of_the_detector() {
        // p = 2 at λ0: order 3 focuses at f0 2/3, in front, W020 = (1 − 3/2) k < 0
        let l = lens(2);
        let k = 3.36e-3 / 50.0;
        assert!((l.order_defocus(3, 800e-9) + 0.5 * k).abs() < 1e-18);
        assert!((l.order_defocus(1, 800e-9) - 0.5 * k).abs() < 1e-18);
        // at λ = 2λ0/3 (α = 3) order 3 is in focus with τ_base
        let lambda = 2.0 * 800e-9 / 3.0;
        assert!(l.order_defocus(3, lambda).abs() < 1e-18);
        assert!((l.order_efficiency(3, lambda) - 0.4).abs() < 1e-15);
    }

    #[test]
    fn rejects_out_of_range_parameters() {
        let e = Harmonic::new(2.5, 3e-3, 800e-9, 0, 0.4, Curve::Constant(0.6)).unwrap_err();
        assert!(e.to_string().contains("design_order = 0 is out of range"), "{e}");
        let e = Harmonic::new(2.5, 3e-3, 800e-9, 1, 1.2, Curve::Constant(0.6)).unwrap_err();
        assert!(e.to_string().contains("base_efficiency = 1.2"), "{e}");
        let e = Harmonic::new(2.5, 3e-3, 800e-9, 1, 0.7, Curve::Constant(0.6)).unwrap_err();
        assert!(e.to_string().contains("τ1 = 0.7 exceeds transmission T = 0.6"), "{e}");
        let e = Harmonic::new(2.5, 3e-3, f64::NAN, 1, 0.4, Curve::Constant(0.6)).unwrap_err();
        assert!(e.to_string().contains("design_wavelength = NaN"), "{e}");
    }

    /// Each order's rates against central differences of `order_defocus` and
    /// `order_efficiency` (step 1e-3 nm: truncation ~1e-12 of the slopes).
    #[test]
    fn order_wavelength_rates_match_differences() {
        let l = lens(5);
        for &lambda in &[760e-9, 803e-9, 800e-9 * 5.0 / 4.5, 850e-9] {
            let rates = l.order_wavelength_rates(lambda, Field::ON_AXIS).unwrap();
            let range: Vec<u32> = l.order_range(lambda).collect();
            assert_eq!(rates.orders.len(), range.len());
            let h = 1e-12;
            for (&m, [d_w020, d_tau]) in range.iter().zip(&rates.orders) {
                let dw = (l.order_defocus(m, lambda + h) - l.order_defocus(m, lambda - h)) / (2.0 * h);
                let dt = (l.order_efficiency(m, lambda + h) - l.order_efficiency(m, lambda - h)) / (2.0 * h);
                assert!((d_w020 - dw).abs() <= 1e-7 * dw.abs(), "m {m}: {d_w020} vs {dw}");
                assert!((d_tau - dt).abs() <= 1e-6 * dt.abs().max(1e3), "λ {lambda}, m {m}: {d_tau} vs {dt}");
            }
        }
    }

    #[test]
    fn describes_itself() {
        assert_eq!(
            lens(3).describe(),
            "harmonic diffractive lens F/2.5 f0 = 3.36 mm at λ0 = 800 nm, design order p = 3, τ_base = 0.4"
        );
        assert_eq!(lens(3).kind(), "harmonic");
    }
}
