//! The ideal refractive reference lens.

use optics::{AffineDefocus, Field, LensModel, Order, Pupil, Wavefront};

use crate::Error;
use crate::chromatic::check;

/// The three-term Sellmeier dispersion formula of a glass,
/// `n²(λ) = 1 + Σᵢ Bᵢ λ²/(λ² − Cᵢ)` with λ in µm and `Cᵢ` in µm², valid over a stated
/// wavelength range (docs/physics.md, "Lens families").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sellmeier {
    b: [f64; 3],
    c_um2: [f64; 3],
    range_m: (f64, f64),
}

impl Sellmeier {
    /// Schott N-BK7 (B = 1.03961212, 0.231792344, 1.01046945; C = 0.00600069867, 0.0200179144,
    /// 103.560653 µm²), valid from 300 nm to 2.5 µm: `n_d(587.56 nm) = 1.5168`.
    pub const N_BK7: Sellmeier = Sellmeier {
        b: [1.03961212, 0.231792344, 1.01046945],
        c_um2: [0.00600069867, 0.0200179144, 103.560653],
        range_m: (300e-9, 2.5e-6),
    };

    /// A glass with coefficients `b` and `c_um2` (µm²), valid over `range_m` (m): every
    /// coefficient finite and ≥ 0, no pole `λ² = Cᵢ` inside the range, and `n > 1` across it.
    pub fn new(b: [f64; 3], c_um2: [f64; 3], range_m: (f64, f64)) -> Result<Sellmeier, Error> {
        for v in b {
            check("sellmeier.b", v, v >= 0.0, "a finite coefficient ≥ 0")?;
        }
        for v in c_um2 {
            check("sellmeier.c", v, v >= 0.0, "a finite coefficient ≥ 0 µm²")?;
        }
        let (lo, hi) = range_m;
        check("sellmeier.range.min", lo, lo > 0.0, "a finite wavelength > 0 m")?;
        check("sellmeier.range.max", hi, hi > lo, "a finite wavelength above the range's minimum, m")?;
        let (lo_um2, hi_um2) = ((lo * 1e6).powi(2), (hi * 1e6).powi(2));
        for v in c_um2 {
            if v >= lo_um2 && v <= hi_um2 {
                return Err(Error::OutOfRange {
                    name: "sellmeier.c",
                    value: v,
                    expected: "a pole λ² = C (µm²) outside the glass's stated wavelength range",
                });
            }
        }
        let glass = Sellmeier { b, c_um2, range_m };
        // without a pole in the range n² is continuous there; n > 1 is checked on a fine grid
        for k in 0..=256 {
            let lambda = lo + (hi - lo) * k as f64 / 256.0;
            let n2 = glass.index_squared(lambda);
            check("sellmeier", n2, n2 > 1.0, "coefficients giving a refractive index n > 1 over the range")?;
        }
        Ok(glass)
    }

    fn index_squared(&self, wavelength_m: f64) -> f64 {
        let l2 = (wavelength_m * 1e6).powi(2);
        1.0 + self.b.iter().zip(&self.c_um2).map(|(b, c)| b * l2 / (l2 - c)).sum::<f64>()
    }

    /// Refractive index at `wavelength_m`, `None` outside the stated range.
    pub fn index(&self, wavelength_m: f64) -> Option<f64> {
        let (lo, hi) = self.range_m;
        (wavelength_m >= lo && wavelength_m <= hi).then(|| self.index_squared(wavelength_m).sqrt())
    }

    /// `dn/dλ` (per m) at `wavelength_m`, `None` outside the stated range: from
    /// `n² = 1 + Σ B_i l²/(l² − C_i)` (l in µm), `dn/dλ = (1/2n) Σ −B_i C_i/(l² − C_i)² · 2l dl/dλ`.
    pub fn index_derivative(&self, wavelength_m: f64) -> Option<f64> {
        let n = self.index(wavelength_m)?;
        let l = wavelength_m * 1e6;
        let l2 = l * l;
        let d_n2_d_l2: f64 = self.b.iter().zip(&self.c_um2).map(|(b, c)| -b * c / ((l2 - c) * (l2 - c))).sum();
        Some(d_n2_d_l2 * 2.0 * l * 1e6 / (2.0 * n))
    }

    /// The wavelength range (m) where the formula holds.
    pub fn range(&self) -> (f64, f64) {
        self.range_m
    }
}

/// The lens material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Glass {
    /// A dispersion-free glass of index `n` (≥ 1): the focal length is the same at every wavelength.
    Constant(f64),
    /// A dispersive glass: the focal length follows `n(λ)`.
    Sellmeier(Sellmeier),
}

/// The lens surfaces' reflection loss.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surfaces {
    /// Bare glass: Fresnel reflectance at normal incidence, `R = ((n − 1)/(n + 1))²` per surface.
    Uncoated,
    /// An anti-reflection coating with this reflectance per surface (a fraction in `[0, 1)`), the
    /// same at every wavelength.
    Coated(f64),
}

/// An ideal refractive lens: one imaging order through the full aperture, no aberration at the
/// design wavelength, all transmitted light in focus (`τ = T`).
///
/// - Without dispersion ([`Glass::Constant`]) `W = 0` at every wavelength.
/// - With a [`Sellmeier`] glass the thin lens' power scales with `n − 1`:
///   `f(λ) = f0 (n0 − 1)/(n(λ) − 1)`, `n0 = n(λ0)`, and with the detector at `f0`
///   `W020(λ) = (D²/8)(1/f0 − 1/f(λ)) = f0/(8F#²) · (n0 − n(λ))/(n0 − 1)` (docs/physics.md,
///   "Lens families" and "Sign of the wavefront"). Normal dispersion (n falls with λ) moves the
///   focus of longer wavelengths behind the detector: `W020 > 0` for `λ > λ0`, the opposite sign
///   to a diffractive lens. Outside the glass's stated range the lens is not characterized and
///   transmits nothing (`τ = T = 0`; the empty order keeps the wavefront of the range's end).
/// - Transmission: each of `elements` thin elements has two surfaces, so
///   `τ = T = (1 − R)^(2 elements)` with `R` the surfaces' reflectance ([`Surfaces`]); uncoated
///   N-BK7 (`n = 1.5168`) loses `R = 4.22 %` per surface, `T = 0.9174` per element. Absorption
///   is neglected. The stop is at the lens: no lateral colour.
#[derive(Clone, Debug)]
pub struct Refractive {
    f_number: f64,
    focal_length: f64,
    design_wavelength: f64,
    glass: Glass,
    elements: u32,
    surfaces: Surfaces,
}

/// Fresnel reflectance at normal incidence of a glass of index `n` in air:
/// `R = ((n − 1)/(n + 1))²` (docs/physics.md, "Lens families").
pub fn fresnel_reflectance(n: f64) -> f64 {
    ((n - 1.0) / (n + 1.0)).powi(2)
}

impl Refractive {
    /// An ideal refractive lens of working F-number `f_number` (≥ 0.5), focal length
    /// `focal_length_m` at `design_wavelength_m` (inside a Sellmeier glass's range), made of
    /// `elements` (1 to 100) thin elements of `glass` with `surfaces`.
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        design_wavelength_m: f64,
        glass: Glass,
        elements: u32,
        surfaces: Surfaces,
    ) -> Result<Self, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        check("design_wavelength", design_wavelength_m, design_wavelength_m > 0.0, "a finite wavelength > 0 m")?;
        match glass {
            Glass::Constant(n) => check("glass.index", n, n >= 1.0, "a finite refractive index ≥ 1")?,
            Glass::Sellmeier(s) => {
                let (lo, hi) = s.range();
                let inside = design_wavelength_m >= lo && design_wavelength_m <= hi;
                check(
                    "design_wavelength",
                    design_wavelength_m,
                    inside,
                    "a wavelength inside the glass's Sellmeier range",
                )?;
                let n0 = s.index(design_wavelength_m).unwrap_or(f64::NAN);
                check("glass.index", n0, n0 > 1.0, "a glass with n(λ0) > 1")?;
            }
        }
        let e = f64::from(elements);
        check("elements", e, (1.0..=100.0).contains(&e), "a whole number of elements from 1 to 100")?;
        if let Surfaces::Coated(r) = surfaces {
            check("reflectance", r, (0.0..1.0).contains(&r), "a reflectance per surface in [0, 1)")?;
        }
        Ok(Refractive {
            f_number,
            focal_length: focal_length_m,
            design_wavelength: design_wavelength_m,
            glass,
            elements,
            surfaces,
        })
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "refractive"
    }

    /// Refractive index at `wavelength_m` (`None` outside a Sellmeier glass's range).
    pub fn index(&self, wavelength_m: f64) -> Option<f64> {
        match self.glass {
            Glass::Constant(n) => Some(n),
            Glass::Sellmeier(s) => s.index(wavelength_m),
        }
    }

    /// Focal length at `wavelength_m`: `f(λ) = f0 (n0 − 1)/(n(λ) − 1)` (`f0` without dispersion,
    /// `None` outside the glass's range).
    pub fn focal_length_at(&self, wavelength_m: f64) -> Option<f64> {
        let n0 = self.index(self.design_wavelength)?;
        let n = self.index(wavelength_m)?;
        Some(if n == n0 { self.focal_length } else { self.focal_length * (n0 - 1.0) / (n - 1.0) })
    }

    /// Defocus at the pupil edge with the detector at `f0`, m:
    /// `W020(λ) = (D²/8)(1/f0 − 1/f(λ)) = f0/(8F#²) (n0 − n(λ))/(n0 − 1)`; positive (focus behind
    /// the detector) where the index is below `n0`. `None` outside the glass's range.
    pub fn defocus(&self, wavelength_m: f64) -> Option<f64> {
        let n0 = self.index(self.design_wavelength)?;
        let n = self.index(wavelength_m)?;
        if n == n0 {
            return Some(0.0);
        }
        Some(self.focal_length / (8.0 * self.f_number * self.f_number) * (n0 - n) / (n0 - 1.0))
    }

    /// Transmission `(1 − R)^(2 elements)` at `wavelength_m` (0 outside the glass's range).
    fn through(&self, wavelength_m: f64) -> f64 {
        let r = match (self.surfaces, self.index(wavelength_m)) {
            (_, None) => return 0.0,
            (Surfaces::Coated(r), _) => r,
            (Surfaces::Uncoated, Some(n)) => fresnel_reflectance(n),
        };
        (1.0 - r).powi(2 * self.elements as i32)
    }
}

impl LensModel for Refractive {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, _field: Field) -> Vec<Order> {
        // Outside a glass's range the order carries no light; its wavefront is the one at the
        // nearest end of the range, so that W020 stays continuous in λ (the spectral quadrature
        // refines its panels on the change of W020 and a jump would never resolve).
        let w020 = match self.glass {
            Glass::Sellmeier(s) => self.defocus(wavelength_m.clamp(s.range().0, s.range().1)),
            Glass::Constant(_) => self.defocus(wavelength_m),
        };
        vec![Order::new(self.through(wavelength_m), Pupil::Full, Wavefront::defocus(w020.unwrap_or(0.0)))]
    }

    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.through(wavelength_m)
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.through(wavelength_m)
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.design_wavelength)
    }

    /// The lens is its own stop with the image at `f0 tan θ` at every wavelength in this model
    /// (no lateral colour: [`orders`](LensModel::orders) does not read the field), so its one
    /// order does not move with the field angle: rate 0 on both axes (docs/physics.md,
    /// "Gradients: the field point").
    fn image_shift_field_rates(&self, _wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        Some(vec![[0.0, 0.0]])
    }

    fn breakpoints(&self) -> Vec<f64> {
        match self.glass {
            Glass::Constant(_) => Vec::new(),
            Glass::Sellmeier(s) => vec![s.range().0, s.range().1],
        }
    }

    /// `W020 = f0/(8F#²) (n0 − n(λ))/(n0 − 1)` moves as `−f0/(8F#²) n′/(n0 − 1)`; the
    /// transmission `τ = T = (1 − R)^(2e)` of uncoated surfaces as
    /// `∂ln τ/∂λ = −2e R′/(1 − R)` with `R = ((n − 1)/(n + 1))²`,
    /// `R′ = 4 (n − 1)/(n + 1)³ n′` (coated: a constant `R`). `None` outside the glass's range.
    fn defocus_rates(&self, wavelength_m: f64, _field: Field) -> Option<optics::DefocusRates> {
        let n0 = self.index(self.design_wavelength)?;
        let n = self.index(wavelength_m)?;
        let slope = match self.glass {
            Glass::Constant(_) => 0.0,
            Glass::Sellmeier(s) => s.index_derivative(wavelength_m)?,
        };
        let defocus = -self.focal_length / (8.0 * self.f_number * self.f_number) * slope / (n0 - 1.0);
        let ln_through = match self.surfaces {
            Surfaces::Coated(_) => 0.0,
            Surfaces::Uncoated => {
                let r = fresnel_reflectance(n);
                let r_slope = 4.0 * (n - 1.0) / (n + 1.0).powi(3) * slope;
                -2.0 * f64::from(self.elements) * r_slope / (1.0 - r)
            }
        };
        Some(optics::DefocusRates { defocus, ln_efficiency: ln_through, ln_transmission: ln_through })
    }

    /// `W020 = f0/(8F#²) (n0 − n(λ))/(n0 − 1)` with `n0 = n(λ0)` moves as
    /// `∂W020/∂ln λ0 = f0/(8F#²) λ0 n′(λ0) (n(λ) − 1)/(n0 − 1)²`; τ = T does not depend on λ0
    /// (0 without dispersion). `None` outside the glass's range (the order carries no light
    /// there, its wavefront the range's end's) and where the index's slope is not given.
    fn design_wavelength_rates(&self, wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        let n0 = self.index(self.design_wavelength)?;
        let slope = match self.glass {
            Glass::Constant(_) => return Some(vec![[0.0, 0.0]]),
            Glass::Sellmeier(s) => s.index_derivative(self.design_wavelength)?,
        };
        let Some(n) = self.index(wavelength_m) else { return Some(vec![[0.0, 0.0]]) };
        let k = self.focal_length / (8.0 * self.f_number * self.f_number);
        Some(vec![[k * self.design_wavelength * slope * (n - 1.0) / ((n0 - 1.0) * (n0 - 1.0)), 0.0]])
    }

    fn affine_defocus(&self, _field: Field) -> Option<AffineDefocus> {
        // no dispersion: W020 ≡ 0 and a constant τ = T at every field point
        let Glass::Constant(_) = self.glass else { return None };
        let t = self.through(self.design_wavelength);
        Some(AffineDefocus { efficiency: t, transmission: t, w020_intercept_m: 0.0, w020_slope: 0.0 })
    }

    fn describe(&self) -> String {
        let glass = match self.glass {
            Glass::Constant(n) => format!("n = {} (no dispersion)", optics::round_for_display(n)),
            Glass::Sellmeier(s) if s == Sellmeier::N_BK7 => "N-BK7".to_string(),
            Glass::Sellmeier(_) => "a Sellmeier glass".to_string(),
        };
        let surfaces = match self.surfaces {
            Surfaces::Uncoated => "uncoated".to_string(),
            Surfaces::Coated(r) => format!("AR R = {} %", optics::round_for_display(r * 100.0)),
        };
        format!(
            "refractive lens F/{} f0 = {} mm at λ0 = {} nm, {}, {} element{} {}",
            optics::round_for_display(self.f_number),
            optics::round_for_display(self.focal_length * 1e3),
            optics::round_for_display(self.design_wavelength * 1e9),
            glass,
            self.elements,
            if self.elements == 1 { "" } else { "s" },
            surfaces
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `dn/dλ` of N-BK7 against central differences of `index` written here (step 1e-5 of λ:
    /// truncation ~1e-10, rounding ~1e-11 of n′), across its range; `None` outside it.
    #[test]
    fn sellmeier_index_derivative_matches_differences() {
        let g = Sellmeier::N_BK7;
        for l in [400e-9, 546.07e-9, 803e-9, 1500e-9] {
            let h = 1e-5 * l;
            let differences = (g.index(l + h).unwrap() - g.index(l - h).unwrap()) / (2.0 * h);
            let exact = g.index_derivative(l).unwrap();
            assert!((exact - differences).abs() <= 1e-8 * exact.abs(), "{l}: {exact} vs {differences}");
        }
        assert!(g.index_derivative(10e-6).is_none());
    }

    /// The lens's defocus and transmission rates (`LensModel::defocus_rates`) against central
    /// differences of `defocus` and of the order's efficiency (step 1e-5 of λ).
    #[test]
    fn defocus_rates_match_differences() {
        let lens = bk7();
        for l in [480e-9, 650e-9, 803e-9] {
            let h = 1e-5 * l;
            let rates = lens.defocus_rates(l, Field::ON_AXIS).unwrap();
            let w = (lens.defocus(l + h).unwrap() - lens.defocus(l - h).unwrap()) / (2.0 * h);
            let tau = |x: f64| lens.efficiency(x).ln();
            let t = (tau(l + h) - tau(l - h)) / (2.0 * h);
            assert!((rates.defocus - w).abs() <= 1e-7 * w.abs(), "{l}: {} vs {w}", rates.defocus);
            assert!((rates.ln_efficiency - t).abs() <= 1e-7 * t.abs(), "{l}: {} vs {t}", rates.ln_efficiency);
            assert_eq!(rates.ln_transmission, rates.ln_efficiency);
        }
    }

    /// `design_wavelength_rates` against central differences of the defocus of singlets built at
    /// λ0 ± h (relative step 1e-5), in and at the design wavelength; 0 without dispersion.
    #[test]
    fn design_wavelength_rates_match_differences() {
        let at = |l0: f64| {
            Refractive::new(2.5, 3.36e-3, l0, Glass::Sellmeier(Sellmeier::N_BK7), 1, Surfaces::Uncoated).unwrap()
        };
        let (l0, h) = (546.07e-9, 1e-5);
        for l in [480e-9, 546.07e-9, 650e-9, 803e-9] {
            let [[d_w, d_tau]] = bk7().design_wavelength_rates(l, Field::ON_AXIS).unwrap()[..] else { panic!() };
            let w = (at(l0 * (1.0 + h)).defocus(l).unwrap() - at(l0 * (1.0 - h)).defocus(l).unwrap())
                / ((1.0 + h).ln() - (1.0 - h).ln());
            assert!((d_w - w).abs() <= 1e-7 * w.abs(), "{l}: {d_w} vs {w}");
            assert_eq!(d_tau, 0.0);
        }
        let constant = Refractive::new(2.5, 3.36e-3, l0, Glass::Constant(1.5168), 1, Surfaces::Uncoated).unwrap();
        assert_eq!(constant.design_wavelength_rates(650e-9, Field::ON_AXIS), Some(vec![[0.0, 0.0]]));
    }

    fn bk7() -> Refractive {
        Refractive::new(2.5, 3.36e-3, 546.07e-9, Glass::Sellmeier(Sellmeier::N_BK7), 1, Surfaces::Uncoated).unwrap()
    }

    #[test]
    fn n_bk7_matches_the_catalogue() {
        // Schott catalogue: n_F' (486.13 nm) 1.52238, n_d (587.56 nm) 1.51680, n_C (656.27 nm) 1.51432
        let g = Sellmeier::N_BK7;
        for (lambda, n) in [(486.13e-9, 1.52238), (587.56e-9, 1.51680), (656.27e-9, 1.51432)] {
            assert!((g.index(lambda).unwrap() - n).abs() < 1e-5, "{lambda}");
        }
        assert_eq!(g.index(250e-9), None);
        assert_eq!(g.index(3e-6), None);
    }

    #[test]
    fn uncoated_element_transmits_the_fresnel_loss_twice() {
        // R = (0.5168/2.5168)² = 0.042165, T = (1 − R)² = 0.917449
        assert!((fresnel_reflectance(1.5168) - 0.042165).abs() < 1e-6);
        let lens = Refractive::new(2.5, 3.36e-3, 587.56e-9, Glass::Constant(1.5168), 1, Surfaces::Uncoated).unwrap();
        assert!((lens.transmission(700e-9) - 0.917449).abs() < 1e-6);
        assert_eq!(lens.efficiency(700e-9), lens.transmission(700e-9));
        let three =
            Refractive::new(2.5, 3.36e-3, 587.56e-9, Glass::Constant(1.5168), 3, Surfaces::Coated(0.005)).unwrap();
        assert!((three.transmission(700e-9) - 0.995f64.powi(6)).abs() < 1e-15);
    }

    #[test]
    fn without_dispersion_the_wavefront_is_flat() {
        let lens = Refractive::new(2.5, 3.36e-3, 800e-9, Glass::Constant(1.5), 1, Surfaces::Uncoated).unwrap();
        for lambda in [400e-9, 800e-9, 1200e-9] {
            let orders = lens.orders(lambda, Field::new(0.1, 0.0));
            assert_eq!(orders.len(), 1);
            assert_eq!(orders[0].wavefront, Wavefront::default());
        }
        let a = lens.affine_defocus(Field::ON_AXIS).unwrap();
        assert_eq!((a.w020_intercept_m, a.w020_slope), (0.0, 0.0));
    }

    #[test]
    fn dispersion_moves_long_wavelengths_behind_the_detector() {
        let lens = bk7();
        assert_eq!(lens.defocus(546.07e-9), Some(0.0));
        for lambda in [400e-9, 500e-9, 546e-9, 546.2e-9, 656.27e-9, 900e-9] {
            let w = lens.defocus(lambda).unwrap();
            let f = lens.focal_length_at(lambda).unwrap();
            assert_eq!(w > 0.0, lambda > 546.07e-9, "{lambda}: {w}");
            assert_eq!(f > 3.36e-3, lambda > 546.07e-9, "{lambda}: {f}");
            // the thin-lens sag difference
            let d: f64 = 3.36e-3 / 2.5;
            let direct = d * d / 8.0 * (1.0 / 3.36e-3 - 1.0 / f);
            assert!((w - direct).abs() < 1e-18, "{lambda}: {w} vs {direct}");
        }
        let outside = lens.orders(250e-9, Field::ON_AXIS);
        assert_eq!(outside[0].efficiency, 0.0);
        assert_eq!(outside[0].wavefront.defocus_m, lens.defocus(300e-9).unwrap());
        assert_eq!(lens.transmission(250e-9), 0.0);
    }

    #[test]
    fn rejects_out_of_range_parameters() {
        let e =
            Refractive::new(2.5, 3e-3, 200e-9, Glass::Sellmeier(Sellmeier::N_BK7), 1, Surfaces::Uncoated).unwrap_err();
        assert!(e.to_string().contains("design_wavelength = 0.0000002 is out of range"), "{e}");
        let e = Refractive::new(2.5, 3e-3, 500e-9, Glass::Constant(0.9), 1, Surfaces::Uncoated).unwrap_err();
        assert!(e.to_string().contains("glass.index = 0.9"), "{e}");
        let e = Refractive::new(2.5, 3e-3, 500e-9, Glass::Constant(1.5), 0, Surfaces::Uncoated).unwrap_err();
        assert!(e.to_string().contains("elements = 0"), "{e}");
        let e = Refractive::new(2.5, 3e-3, 500e-9, Glass::Constant(1.5), 1, Surfaces::Coated(1.0)).unwrap_err();
        assert!(e.to_string().contains("reflectance = 1 is out of range: expected a reflectance"), "{e}");
        let e = Refractive::new(0.2, 3e-3, 500e-9, Glass::Constant(1.5), 1, Surfaces::Uncoated).unwrap_err();
        assert!(e.to_string().contains("f_number = 0.2"), "{e}");
        // a pole inside the range, and an index below 1
        let e = Sellmeier::new([1.0, 0.0, 0.0], [0.25, 0.0, 0.0], (400e-9, 700e-9)).unwrap_err();
        assert!(e.to_string().contains("sellmeier.c = 0.25"), "{e}");
        assert!(Sellmeier::new([0.0; 3], [0.0; 3], (400e-9, 700e-9)).is_err());
        assert!(Sellmeier::new([1.0, 0.0, f64::NAN], [0.0; 3], (400e-9, 700e-9)).is_err());
        assert!(Sellmeier::new([1.0, 0.0, 0.0], [0.0; 3], (400e-9, 700e-9)).is_ok());
    }

    #[test]
    fn describes_itself() {
        let d = bk7().describe();
        assert_eq!(d, "refractive lens F/2.5 f0 = 3.36 mm at λ0 = 546.07 nm, N-BK7, 1 element uncoated");
        assert_eq!(bk7().kind(), "refractive");
    }
}
