//! The spatially multiplexed (interleaved) metalens.

use std::sync::Arc;

use optics::{Field, LensModel, Order, OrderWavelengthRates, Pupil, Wavefront};

use crate::Error;
use crate::chromatic::{Curve, check, check_efficiency_below_transmission, check_fraction};

/// One channel of an [`Interleaved`] lens: a chromatic lens designed for `wavelength_m` with
/// element efficiency η(λ) (a fraction).
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The channel's design wavelength λ_j, m.
    pub wavelength_m: f64,
    /// Its efficiency η_j(λ) as if it filled the whole aperture.
    pub efficiency: Curve,
}

/// The samples of the channels' efficiency curves and of the transmission, with `extra` (band
/// edges), sorted and deduplicated: the breakpoints of a multiplexed lens.
pub(crate) fn channel_breakpoints(
    channels: &[Channel],
    transmission: &Curve,
    extra: impl IntoIterator<Item = f64>,
) -> Vec<f64> {
    let mut b: Vec<f64> = channels
        .iter()
        .flat_map(|c| c.efficiency.breakpoints().iter().copied())
        .chain(transmission.breakpoints().iter().copied())
        .chain(extra)
        .collect();
    b.sort_by(f64::total_cmp);
    b.dedup();
    b
}

/// A spatially multiplexed metalens of N interleaved channels: channel `j` is a chromatic lens
/// wave designed to focus λ_j at `f0` across the full aperture, its meta-atoms interleaved with
/// the other channels' (docs/physics.md, "Lens families").
///
/// Scalar mask model: each channel fills `1/N` of the aperture, finely interleaved, so its
/// focused field is `1/N` of a full-aperture lens's and its focused power
/// `τ_j(λ) = η_j(λ)/N²` of the light incident on the aperture; its pupil is the full aperture
/// (the interleaving is far finer than the aperture). The rest is background within `T(λ)`.
/// Channel j's focal length is `f_j(λ) = f0 λ_j/λ`, so with the detector at `f0`
/// `W020_j(λ) = (1 − λ/λ_j) f0/(8F#²)` (docs/physics.md, "Sign of the wavefront": `W020 > 0`
/// behind the detector), zero at λ_j, and off axis its lateral colour behind a remote stop is
/// `f0 tan θ (λ_j/λ − 1)` as the chromatic lens's.
#[derive(Clone, Debug)]
pub struct Interleaved {
    f_number: f64,
    focal_length: f64,
    channels: Vec<Channel>,
    transmission: Curve,
}

impl Interleaved {
    /// A multiplexed lens of working F-number `f_number` (≥ 0.5) and focal length
    /// `focal_length_m` with 1 to 16 `channels` (design wavelengths finite, > 0 and
    /// increasing; efficiencies fractions) and total transmission `transmission` (a fraction,
    /// `Σ τ_j ≤ T`).
    pub fn new(f_number: f64, focal_length_m: f64, channels: Vec<Channel>, transmission: Curve) -> Result<Self, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        let n = channels.len() as f64;
        check("channels", n, (1.0..=16.0).contains(&n), "1 to 16 channels")?;
        let mut prev = 0.0;
        for c in &channels {
            let l = c.wavelength_m;
            check("channels.wavelength", l, l > prev, "finite wavelengths > 0 m in increasing order")?;
            prev = l;
            check_fraction("channels.efficiency", &c.efficiency)?;
        }
        check_fraction("transmission", &transmission)?;
        let lens = Interleaved { f_number, focal_length: focal_length_m, channels, transmission };
        let parts: Vec<&Curve> = lens.channels.iter().map(|c| &c.efficiency).collect();
        check_efficiency_below_transmission(&|l| lens.efficiency(l), &parts, &lens.transmission, lens.centre())?;
        Ok(lens)
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "multiplexed-interleaved"
    }

    /// The channels.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    fn centre(&self) -> f64 {
        let (first, last) = (self.channels[0].wavelength_m, self.channels[self.channels.len() - 1].wavelength_m);
        0.5 * (first + last)
    }

    /// Focused efficiency of channel `j` at `wavelength_m`: `τ_j = η_j(λ)/N²`.
    pub fn channel_efficiency(&self, j: usize, wavelength_m: f64) -> f64 {
        let n = self.channels.len() as f64;
        self.channels[j].efficiency.value(wavelength_m) / (n * n)
    }

    /// Defocus of channel `j` at `wavelength_m`: `W020_j = (1 − λ/λ_j) f0/(8F#²)`.
    pub fn channel_defocus(&self, j: usize, wavelength_m: f64) -> f64 {
        (1.0 - wavelength_m / self.channels[j].wavelength_m) * self.focal_length / (8.0 * self.f_number * self.f_number)
    }
}

impl LensModel for Interleaved {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        (0..self.channels.len())
            .map(|j| {
                let k = self.channels[j].wavelength_m / wavelength_m - 1.0;
                let [dx, dy] = [self.focal_length * field.x_rad.tan() * k, self.focal_length * field.y_rad.tan() * k];
                let wavefront = Wavefront::defocus(self.channel_defocus(j, wavelength_m)).shifted(dx, dy);
                Order::new(self.channel_efficiency(j, wavelength_m), Pupil::Full, wavefront)
            })
            .collect()
    }

    fn efficiency(&self, wavelength_m: f64) -> f64 {
        (0..self.channels.len()).map(|j| self.channel_efficiency(j, wavelength_m)).sum()
    }

    /// Each channel's lateral colour `Δ_j = f0 tan θ (λ_j/λ − 1)` moves as
    /// `∂Δ_j/∂θ = f0 sec²θ (λ_j/λ − 1)`; its defocus and efficiency do not move with the field
    /// (docs/physics.md, "Gradients: the multiplexed lens").
    fn image_shift_field_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        let sec2 = |angle: f64| 1.0 / (angle.cos() * angle.cos());
        let (sx, sy) = (self.focal_length * sec2(field.x_rad), self.focal_length * sec2(field.y_rad));
        Some(
            self.channels
                .iter()
                .map(|c| {
                    let k = c.wavelength_m / wavelength_m - 1.0;
                    [sx * k, sy * k]
                })
                .collect(),
        )
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.transmission.value(wavelength_m)
    }

    /// On axis, each channel's order `W020_j = (1 − λ/λ_j) f0/(8F#²)` moves as
    /// `∂W020_j/∂λ = −f0/(8F#² λ_j)` and its `τ_j = η_j/N²` not at all, where every η_j and T
    /// are constants (docs/physics.md, "Gradients: a line's wavelength"; a table's slope has
    /// kinks at its rows: `None`). Off axis each channel's lateral colour moves with λ by its own
    /// `λ_j/λ`: `None`.
    fn order_wavelength_rates(&self, _wavelength_m: f64, field: Field) -> Option<OrderWavelengthRates> {
        let constant = self.channels.iter().all(|c| matches!(c.efficiency, Curve::Constant(_)))
            && matches!(self.transmission, Curve::Constant(_));
        if !field.is_on_axis() || !constant {
            return None;
        }
        let k = self.focal_length / (8.0 * self.f_number * self.f_number);
        let orders = self.channels.iter().map(|c| [-k / c.wavelength_m, 0.0]).collect();
        Some(OrderWavelengthRates { orders, ln_transmission: 0.0 })
    }

    /// Every channel's wavelength scaled together (`λ_j → (1 + ε) λ_j`, the design wavelength
    /// [`design_wavelength`](LensModel::design_wavelength), their range's centre, with them):
    /// `W020_j = (1 − λ/λ_j) f0/(8F#²)` moves as `∂W020_j/∂ln λ0 = (λ/λ_j) f0/(8F#²)`, τ_j and T
    /// not (they do not depend on λ_j); off axis each channel's lateral colour
    /// `Δ_j = f0 tan θ (λ_j/λ − 1)` moves as `Δ_j + f0 tan θ`. The orders depend on λ through
    /// each `λ/λ_j` alone, which a line's wavelength off axis follows (docs/physics.md,
    /// "Gradients: several orders under a line off axis").
    fn design_wavelength_rates(&self, wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        let k = self.focal_length / (8.0 * self.f_number * self.f_number);
        Some(self.channels.iter().map(|c| [k * wavelength_m / c.wavelength_m, 0.0]).collect())
    }

    /// The centre of the channels' range, `(λ_1 + λ_N)/2`.
    fn design_wavelength(&self) -> Option<f64> {
        Some(self.centre())
    }

    /// With some table: one part per distinct efficiency curve among the channels (those
    /// channels alone, efficiency 1, the table `η k²/N²` for `k` of the `N` channels: a part's
    /// lens divides by its own `k²`), so that channels on one table (`lens.efficiency` a CSV)
    /// share one part; one part (the lens with transmission 1) where only the transmission is.
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        let channel_tables = self.channels.iter().any(|c| matches!(c.efficiency, Curve::Table(_)));
        if !channel_tables {
            return crate::chromatic::factor_one_curve(
                &Curve::Constant(1.0),
                &self.transmission,
                1.0,
                |_, transmission| Arc::new(Interleaved { transmission, ..self.clone() }),
            );
        }
        let mut groups: Vec<(&Curve, Vec<f64>)> = Vec::new();
        for c in &self.channels {
            match groups.iter_mut().find(|(curve, _)| **curve == c.efficiency) {
                Some((_, waves)) => waves.push(c.wavelength_m),
                None => groups.push((&c.efficiency, vec![c.wavelength_m])),
            }
        }
        let n = self.channels.len() as f64;
        let parts = groups
            .into_iter()
            .map(|(curve, waves)| {
                let k = waves.len() as f64;
                optics::FactoredPart {
                    table: crate::chromatic::curve_spectrum(k * k / (n * n), curve),
                    relative: Arc::new(Interleaved {
                        channels: waves
                            .into_iter()
                            .map(|wavelength_m| Channel { wavelength_m, efficiency: Curve::Constant(1.0) })
                            .collect(),
                        transmission: Curve::Constant(1.0),
                        ..self.clone()
                    }),
                }
            })
            .collect();
        Some(optics::FactoredEfficiency {
            parts,
            transmission: crate::chromatic::curve_spectrum(1.0, &self.transmission),
        })
    }

    fn breakpoints(&self) -> Vec<f64> {
        channel_breakpoints(&self.channels, &self.transmission, [])
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        let waves: Vec<String> = self.channels.iter().map(|c| format!("{}", r(c.wavelength_m * 1e9))).collect();
        format!(
            "interleaved multiplexed metalens F/{} f0 = {} mm, {} channel{} at {} nm",
            r(self.f_number),
            r(self.focal_length * 1e3),
            self.channels.len(),
            if self.channels.len() == 1 { "" } else { "s" },
            waves.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channels(waves_nm: &[f64], eta: f64) -> Vec<Channel> {
        waves_nm.iter().map(|&w| Channel { wavelength_m: w * 1e-9, efficiency: Curve::Constant(eta) }).collect()
    }

    fn rgb() -> Interleaved {
        Interleaved::new(2.5, 3.36e-3, channels(&[450.0, 550.0, 650.0], 0.8), Curve::Constant(0.9)).unwrap()
    }

    #[test]
    fn efficiency_scales_as_one_over_n_squared() {
        for (n, waves) in [(1usize, vec![550.0]), (2, vec![500.0, 600.0]), (3, vec![450.0, 550.0, 650.0])] {
            let lens = Interleaved::new(2.5, 3.36e-3, channels(&waves, 0.8), Curve::Constant(0.9)).unwrap();
            let orders = lens.orders(520e-9, Field::ON_AXIS);
            assert_eq!(orders.len(), n);
            for o in &orders {
                assert!((o.efficiency - 0.8 / (n * n) as f64).abs() < 1e-15, "N {n}");
            }
            assert!((lens.efficiency(520e-9) - 0.8 / n as f64).abs() < 1e-15, "N {n}");
        }
    }

    #[test]
    fn each_channel_is_in_focus_at_its_wavelength() {
        let lens = rgb();
        let k = 3.36e-3 / 50.0;
        for j in 0..3 {
            let lambda = lens.channels()[j].wavelength_m;
            let orders = lens.orders(lambda, Field::new(0.1, 0.0));
            assert_eq!(orders[j].wavefront.defocus_m, 0.0);
            assert_eq!(orders[j].wavefront.image_shift_m, [0.0, 0.0]);
            for (i, o) in orders.iter().enumerate() {
                let want = (1.0 - lambda / lens.channels()[i].wavelength_m) * k;
                assert!((o.wavefront.defocus_m - want).abs() < 1e-20, "{i} at {lambda}");
                // shorter-wavelength channels focus λ in front of the detector, longer behind
                assert_eq!(o.wavefront.defocus_m < 0.0, i < j, "{i} at {lambda}");
            }
        }
        assert_eq!(lens.design_wavelength(), Some(550e-9));
    }

    /// Each channel's `∂Δ_j/∂θ` against central differences of the orders' image shifts
    /// (step 1e-5 rad, relative error of order 1e-10), along x and y at (3°, −2°).
    #[test]
    fn image_shift_field_rates_are_the_shifts_derivatives() {
        let lens = rgb();
        let (tx, ty, h) = (3f64.to_radians(), (-2f64).to_radians(), 1e-5);
        for lambda in [430e-9, 550e-9, 700e-9] {
            let rates = lens.image_shift_field_rates(lambda, Field::new(tx, ty)).unwrap();
            let shifts = |x: f64, y: f64| -> Vec<[f64; 2]> {
                lens.orders(lambda, Field::new(x, y)).iter().map(|o| o.wavefront.image_shift_m).collect()
            };
            let (up_x, down_x) = (shifts(tx + h, ty), shifts(tx - h, ty));
            let (up_y, down_y) = (shifts(tx, ty + h), shifts(tx, ty - h));
            assert_eq!(rates.len(), 3);
            for j in 0..3 {
                let want = [(up_x[j][0] - down_x[j][0]) / (2.0 * h), (up_y[j][1] - down_y[j][1]) / (2.0 * h)];
                for axis in 0..2 {
                    let error = (rates[j][axis] - want[axis]).abs();
                    assert!(
                        error <= 1e-8 * want[axis].abs().max(1e-9),
                        "{j} {axis} at {lambda}: {rates:?} vs {want:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn rejects_out_of_range_parameters() {
        let e = Interleaved::new(2.5, 3e-3, Vec::new(), Curve::Constant(0.9)).unwrap_err();
        assert!(e.to_string().contains("channels = 0 is out of range: expected 1 to 16 channels"), "{e}");
        let e = Interleaved::new(2.5, 3e-3, channels(&[550.0, 450.0], 0.8), Curve::Constant(0.9)).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("channels.wavelength = 0.00000045") && text.contains("increasing order"), "{e}");
        let e = Interleaved::new(2.5, 3e-3, channels(&[550.0], 1.2), Curve::Constant(0.9)).unwrap_err();
        assert!(e.to_string().contains("channels.efficiency = 1.2"), "{e}");
        // Σ τ_j = 0.8/2 = 0.4 above T = 0.3
        let e = Interleaved::new(2.5, 3e-3, channels(&[450.0, 550.0], 0.8), Curve::Constant(0.3)).unwrap_err();
        assert!(e.to_string().contains("= 0.4 exceeds transmission T = 0.3"), "{e}");
        assert!(Interleaved::new(2.5, 3e-3, channels(&[450.0, 550.0], 0.8), Curve::Constant(0.4)).is_ok());
    }

    #[test]
    fn describes_itself() {
        assert_eq!(
            rgb().describe(),
            "interleaved multiplexed metalens F/2.5 f0 = 3.36 mm, 3 channels at 450, 550, 650 nm"
        );
        assert_eq!(rgb().kind(), "multiplexed-interleaved");
    }
}
