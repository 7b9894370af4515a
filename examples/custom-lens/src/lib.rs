//! A lens family of one's own, written downstream with the public API only: a **hybrid
//! refractive–diffractive achromat** (a glass singlet with a diffractive surface whose power
//! cancels the glass's dispersion at the design wavelength), implemented as an
//! [`optics::LensModel`] and compared with the paper's chromatic metalens.
//!
//! `cargo run -p custom-lens` prints both lenses' ASNR over a few spectral ranges;
//! `cargo test -p custom-lens` runs the conformance check every `LensModel` should pass
//! (`optics::testkit::check_lens`, feature `testkit`).
//!
//! # The physics (docs/physics.md, "Lens families" and "Sign of the wavefront")
//! Thin-lens powers add: the glass contributes `φ_r(λ) = φ_r0 (n(λ) − 1)/(n0 − 1)`, the
//! diffractive surface `φ_d(λ) = φ_d0 λ/λ0` (its focal length scales as 1/λ, like a metalens).
//! With `a = λ0 n'(λ0)/(n0 − 1)` (negative: normal dispersion) the total power
//! `φ = φ_r + φ_d` is stationary at λ0 when `φ_r0 a + φ_d0 = 0`, so
//! `φ_r0 = φ0/(1 − a)` and `φ_d0 = −a φ0/(1 − a)`; what is left is the secondary spectrum,
//! quadratic in `λ − λ0`. With the detector at `f0 = 1/φ0`, the defocus at the pupil edge is
//! `W020(λ) = (D²/8)(φ0 − φ(λ))` (`W020 > 0` focuses behind the detector).
//!
//! The diffractive surface is a kinoform of one wave of phase depth at λ0: its first order takes
//! the scalar efficiency `sinc²(λ0/λ − 1)`, the other orders are background. The glass is
//! uncoated, `T = (1 − R)²` with `R = ((n0 − 1)/(n0 + 1))²`, and the imaging efficiency is
//! `τ(λ) = T sinc²(λ0/λ − 1)`. The glass index follows Cauchy's formula `n = A + B/λ²`.
//!
//! # The whole implementation
//! Three methods are required ([`f_number`](LensModel::f_number),
//! [`focal_length`](LensModel::focal_length), [`orders`](LensModel::orders)); the others have
//! defaults, and this lens overrides the two that carry its physics ([`transmission`](LensModel::transmission):
//! the light into all orders, for the glare and background terms; and
//! [`design_wavelength`](LensModel::design_wavelength): the Fraunhofer check's reference).
//!
//! ```
//! use optics::{Field, LensModel, Order, Pupil, Wavefront};
//!
//! /// A hybrid refractive–diffractive achromat (crate docs).
//! #[derive(Clone, Debug)]
//! pub struct HybridAchromat {
//!     f_number: f64,
//!     focal_length_m: f64,
//!     design_wavelength_m: f64,
//!     /// Cauchy coefficients of the glass: n = a + b/λ² (b in m²)
//!     cauchy: (f64, f64),
//! }
//!
//! impl HybridAchromat {
//!     fn index(&self, wavelength_m: f64) -> f64 {
//!         self.cauchy.0 + self.cauchy.1 / (wavelength_m * wavelength_m)
//!     }
//!
//!     /// Total power φ(λ), 1/m: glass and diffractive surface, stationary at λ0.
//!     pub fn power(&self, wavelength_m: f64) -> f64 {
//!         let (l0, phi0) = (self.design_wavelength_m, 1.0 / self.focal_length_m);
//!         let n0 = self.index(l0);
//!         let slope = -2.0 * self.cauchy.1 / (l0 * l0 * l0); // n'(λ0)
//!         let a = l0 * slope / (n0 - 1.0);
//!         let (refractive, diffractive) = (phi0 / (1.0 - a), -a * phi0 / (1.0 - a));
//!         refractive * (self.index(wavelength_m) - 1.0) / (n0 - 1.0) + diffractive * wavelength_m / l0
//!     }
//! }
//!
//! impl LensModel for HybridAchromat {
//!     fn f_number(&self) -> f64 {
//!         self.f_number
//!     }
//!
//!     fn focal_length(&self) -> f64 {
//!         self.focal_length_m
//!     }
//!
//!     fn orders(&self, wavelength_m: f64, _field: Field) -> Vec<Order> {
//!         // W020 = (D²/8)(φ0 − φ(λ)), D = f0/F#
//!         let d = self.focal_length_m / self.f_number;
//!         let w020 = d * d / 8.0 * (1.0 / self.focal_length_m - self.power(wavelength_m));
//!         let first_order = sinc(self.design_wavelength_m / wavelength_m - 1.0).powi(2);
//!         let efficiency = self.transmission(wavelength_m) * first_order;
//!         vec![Order::new(efficiency, Pupil::Full, Wavefront::defocus(w020))]
//!     }
//!
//!     fn transmission(&self, _wavelength_m: f64) -> f64 {
//!         // two uncoated surfaces at the design index
//!         let n0 = self.index(self.design_wavelength_m);
//!         let r = ((n0 - 1.0) / (n0 + 1.0)).powi(2);
//!         (1.0 - r) * (1.0 - r)
//!     }
//!
//!     fn design_wavelength(&self) -> Option<f64> {
//!         Some(self.design_wavelength_m)
//!     }
//! }
//!
//! fn sinc(x: f64) -> f64 {
//!     if x == 0.0 { 1.0 } else { (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x) }
//! }
//!
//! let lens = HybridAchromat {
//!     f_number: 2.5,
//!     focal_length_m: 3.36e-3,
//!     design_wavelength_m: 800e-9,
//!     cauchy: (1.5046, 4.2e-15),
//! };
//! // in focus at λ0, and far less defocus 50 nm away than the chromatic lens's −4.2 µm
//! assert_eq!(lens.orders(800e-9, Field::ON_AXIS)[0].wavefront.defocus_m, 0.0);
//! assert!(lens.orders(850e-9, Field::ON_AXIS)[0].wavefront.defocus_m.abs() < 0.1e-6);
//! ```
//!
//! The crate's [`HybridAchromat`] is this implementation with a validating constructor.

use std::f64::consts::PI;

use optics::{Field, LensModel, Order, Pupil, Wavefront};

/// N-BK7 fitted by Cauchy's formula over 450–900 nm (`A`, and `B` in m²): within 1e-3 of the
/// Sellmeier index there, enough for an illustration.
pub const BK7_CAUCHY: (f64, f64) = (1.5046, 4.2e-15);

/// A hybrid refractive–diffractive achromat (crate docs): a glass singlet of Cauchy index
/// `n = a + b/λ²` with a one-wave kinoform whose power cancels the glass's dispersion at λ0.
#[derive(Clone, Debug)]
pub struct HybridAchromat {
    f_number: f64,
    focal_length_m: f64,
    design_wavelength_m: f64,
    cauchy: (f64, f64),
}

/// What can be wrong with the lens's parameters: the parameter, its value and what is accepted.
#[derive(Clone, Debug, PartialEq)]
pub struct InvalidLens(pub String);

impl std::fmt::Display for InvalidLens {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InvalidLens {}

impl HybridAchromat {
    /// A hybrid achromat of working F-number `f_number` (≥ 0.5), focal length `focal_length_m`
    /// (> 0) at `design_wavelength_m` (> 0), of a glass with Cauchy coefficients `cauchy`
    /// (`n(λ0) > 1`, `b ≥ 0`: normal dispersion).
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        design_wavelength_m: f64,
        cauchy: (f64, f64),
    ) -> Result<Self, InvalidLens> {
        let check = |name: &str, v: f64, ok: bool, expected: &str| {
            if v.is_finite() && ok { Ok(()) } else { Err(InvalidLens(format!("{name} = {v}: expected {expected}"))) }
        };
        check("f_number", f_number, f_number >= 0.5, "a number ≥ 0.5")?;
        check("focal_length_m", focal_length_m, focal_length_m > 0.0, "a length > 0 m")?;
        check("design_wavelength_m", design_wavelength_m, design_wavelength_m > 0.0, "a wavelength > 0 m")?;
        check("cauchy.b", cauchy.1, cauchy.1 >= 0.0, "a coefficient ≥ 0 m² (normal dispersion)")?;
        let n0 = cauchy.0 + cauchy.1 / (design_wavelength_m * design_wavelength_m);
        check("n(λ0)", n0, n0 > 1.0, "an index > 1 at the design wavelength")?;
        Ok(HybridAchromat { f_number, focal_length_m, design_wavelength_m, cauchy })
    }

    fn index(&self, wavelength_m: f64) -> f64 {
        self.cauchy.0 + self.cauchy.1 / (wavelength_m * wavelength_m)
    }

    /// Total power φ(λ) (1/m): glass and diffractive surface, stationary at λ0 (crate docs).
    pub fn power(&self, wavelength_m: f64) -> f64 {
        let (l0, phi0) = (self.design_wavelength_m, 1.0 / self.focal_length_m);
        let n0 = self.index(l0);
        let slope = -2.0 * self.cauchy.1 / (l0 * l0 * l0);
        let a = l0 * slope / (n0 - 1.0);
        let (refractive, diffractive) = (phi0 / (1.0 - a), -a * phi0 / (1.0 - a));
        refractive * (self.index(wavelength_m) - 1.0) / (n0 - 1.0) + diffractive * wavelength_m / l0
    }

    /// The diffractive surface's first-order efficiency `sinc²(λ0/λ − 1)`.
    pub fn diffraction_efficiency(&self, wavelength_m: f64) -> f64 {
        let x = self.design_wavelength_m / wavelength_m - 1.0;
        if x == 0.0 { 1.0 } else { ((PI * x).sin() / (PI * x)).powi(2) }
    }
}

impl LensModel for HybridAchromat {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length_m
    }

    fn orders(&self, wavelength_m: f64, _field: Field) -> Vec<Order> {
        let d = self.focal_length_m / self.f_number;
        let w020 = d * d / 8.0 * (1.0 / self.focal_length_m - self.power(wavelength_m));
        let efficiency = self.transmission(wavelength_m) * self.diffraction_efficiency(wavelength_m);
        vec![Order::new(efficiency, Pupil::Full, Wavefront::defocus(w020))]
    }

    fn transmission(&self, _wavelength_m: f64) -> f64 {
        let n0 = self.index(self.design_wavelength_m);
        let r = ((n0 - 1.0) / (n0 + 1.0)).powi(2);
        (1.0 - r) * (1.0 - r)
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.design_wavelength_m)
    }

    fn describe(&self) -> String {
        format!(
            "hybrid refractive–diffractive achromat F/{} f0 = {} mm at λ0 = {} nm",
            optics::round_for_display(self.f_number),
            optics::round_for_display(self.focal_length_m * 1e3),
            optics::round_for_display(self.design_wavelength_m * 1e9)
        )
    }
}

/// The paper's scene (docs/physics.md; the `examples/paper-theory.toml` of the repository) with
/// `lens` and a Gaussian band of `range_m` at 800 nm: a flat 0.025 W/(m² sr nm) target, 5.2 µm
/// pixels with QE 0.2, 1.23 ms, shot-noise limited, lens MTF only.
pub fn paper_scene(
    lens: std::sync::Arc<dyn LensModel>,
    range_m: f64,
) -> Result<metric::Scene, Box<dyn std::error::Error>> {
    let filter = radiometry::Gaussian::from_range(800e-9, range_m, 1.0)?;
    let radiance = radiometry::Spectrum::product(vec![
        radiometry::Spectrum::Constant(0.025e9),
        radiometry::Spectrum::Gaussian(filter),
    ]);
    let camera = metric::Camera::new(5.2e-6, radiometry::Spectrum::Constant(0.2), false)?;
    Ok(metric::Scene::new(lens, radiance, camera, 1.23e-3, metric::Options::default())?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens() -> HybridAchromat {
        HybridAchromat::new(2.5, 3.36e-3, 800e-9, BK7_CAUCHY).unwrap()
    }

    /// The power is stationary at λ0 (a centred difference of the power vanishes to rounding)
    /// and the residual is the secondary spectrum: quadratic, the same sign on both sides.
    #[test]
    fn power_is_stationary_at_the_design_wavelength() {
        let l = lens();
        let phi0 = 1.0 / 3.36e-3;
        assert!((l.power(800e-9) - phi0).abs() < 1e-12 * phi0);
        let h = 1e-9;
        let slope = (l.power(800e-9 + h) - l.power(800e-9 - h)) / (2.0 * h);
        let chromatic_slope = phi0 / 800e-9;
        assert!(slope.abs() < 1e-5 * chromatic_slope, "{slope} vs {chromatic_slope}");
        let (below, above) = (l.power(750e-9) - phi0, l.power(850e-9) - phi0);
        assert!(below.signum() == above.signum(), "{below} {above}");
    }

    /// W020 against the thin-lens sag difference, and far below the chromatic lens's defocus.
    #[test]
    fn defocus_is_the_secondary_spectrum() {
        let l = lens();
        let d: f64 = 3.36e-3 / 2.5;
        for lambda in [700e-9, 850e-9] {
            let w = l.orders(lambda, Field::ON_AXIS)[0].wavefront.defocus_m;
            let direct = d * d / 8.0 * (1.0 / 3.36e-3 - l.power(lambda));
            assert!((w - direct).abs() < 1e-18);
            let chromatic = (1.0 - lambda / 800e-9) * 3.36e-3 / (8.0 * 2.5 * 2.5);
            assert!(w.abs() < 0.05 * chromatic.abs(), "{lambda}: {w} vs {chromatic}");
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        let e = HybridAchromat::new(0.3, 3.36e-3, 800e-9, BK7_CAUCHY).unwrap_err();
        assert!(e.to_string().contains("f_number = 0.3"), "{e}");
        let e = HybridAchromat::new(2.5, 3.36e-3, 800e-9, (0.5, 0.0)).unwrap_err();
        assert!(e.to_string().contains("n(λ0)"), "{e}");
    }
}
