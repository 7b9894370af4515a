//! The dispersion-engineered (achromatic) metalens.

use optics::{Field, LensModel, Order, Pupil, Wavefront};

use crate::Error;
use crate::chromatic::{Curve, check, check_efficiency_below_transmission, check_fraction};

/// Speed of light in vacuum, m/s.
const C: f64 = 299_792_458.0;

/// What a dispersion-engineered lens does when its aperture needs more group delay than its
/// meta-atom library provides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DelayOverflow {
    /// Refuse the design ([`Error::GroupDelayExceeded`]).
    Reject,
    /// Accept it with the achromatism reduced: the fraction `β = ΔT_lib/ΔT_req` of the path is
    /// true delay, the rest is wrapped phase and disperses like a chromatic lens.
    Reduced,
}

/// Group delay (s) an achromatic flat lens of focal length `focal_length_m` and aperture
/// `diameter_m` must add at its centre relative to its edge: the path difference between the
/// marginal and the axial ray to the focus, divided by c,
/// `ΔT_req = (F/c)(1/√(1 − NA²) − 1)` with `NA = R/√(R² + F²)`, `R = D/2`, i.e.
/// `(√(R² + F²) − F)/c`, evaluated as `R²/(c (√(R² + F²) + F))` (docs/physics.md, "Lens
/// families"). The paper's lens (F = 3.36 mm, D = 1.344 mm) needs 221.96 fs.
pub fn required_group_delay(focal_length_m: f64, diameter_m: f64) -> f64 {
    let (r, f) = (0.5 * diameter_m, focal_length_m);
    r * r / (C * (r.hypot(f) + f))
}

/// The largest aperture diameter (m) a library of group-delay range `delay_s` allows at focal
/// length `focal_length_m`: `ΔT_req = ΔT_lib` solved for R, `R_max = √(2F c ΔT_lib + (c ΔT_lib)²)`,
/// `D_max = 2 R_max` (docs/physics.md, "Lens families"). 5 fs at F = 3.36 mm: 200.8 µm (F/16.74).
pub fn max_diameter(focal_length_m: f64, delay_s: f64) -> f64 {
    let l = C * delay_s;
    2.0 * (2.0 * focal_length_m * l + l * l).sqrt()
}

/// A dispersion-engineered (achromatic) metalens: its meta-atoms supply the group delay that
/// makes the focal length the same over a design band `[λ_min, λ_max]`.
///
/// - The aperture must fit the library: [`required_group_delay`] `ΔT_req ≤ ΔT_lib`, else the
///   constructor rejects the design (with [`DelayOverflow::Reject`]) naming both delays, the
///   largest diameter [`max_diameter`] the library allows and its F-number.
/// - Inside the design band: one order through the full aperture with efficiency τ(λ) (an input)
///   and `W020(λ) = δf(λ)/(8F#²)` from an optional residual focal shift δf (`δf > 0` behind the
///   detector; docs/physics.md, "Sign of the wavefront"), zero for the ideal achromat.
/// - Outside the band the phase profile is not designed: the lens focuses nothing there
///   (τ = 0), and the light it transmits, `T(λ)` as given, is background only (paper SI eq. S14).
/// - [`DelayOverflow::Reduced`]: with `β = ΔT_lib/ΔT_req < 1` the wrapped part of the path
///   behaves as a chromatic lens, so the band sees `W020(λ) = (1 − β)(1 − λ/λ0) f0/(8F#²)` on top
///   of the residual, λ0 the band's centre.
///
/// No lateral colour is modelled.
#[derive(Clone, Debug)]
pub struct DispersionEngineered {
    f_number: f64,
    focal_length: f64,
    band: (f64, f64),
    delay_library: f64,
    delay_required: f64,
    overflow: DelayOverflow,
    efficiency: Curve,
    transmission: Curve,
    /// residual focal shift δf (m) against wavelength (m), piecewise linear, covering the band;
    /// empty: none
    focal_shift: Vec<(f64, f64)>,
}

impl DispersionEngineered {
    /// An achromat of working F-number `f_number` (≥ 0.5) and focal length `focal_length_m`,
    /// designed for `band_m = (λ_min, λ_max)` (0 < λ_min < λ_max), with a meta-atom library of
    /// group-delay range `delay_library_s` (s, > 0), imaging efficiency `efficiency` inside the
    /// band and total transmission `transmission` (fractions, `τ ≤ T`), and what to do when the
    /// aperture needs more delay than the library has.
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        band_m: (f64, f64),
        delay_library_s: f64,
        efficiency: Curve,
        transmission: Curve,
        overflow: DelayOverflow,
    ) -> Result<Self, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        let (lo, hi) = band_m;
        check("band.min", lo, lo > 0.0, "a finite wavelength > 0 m")?;
        check("band.max", hi, hi > lo, "a finite wavelength above band.min, m")?;
        check("delay_library", delay_library_s, delay_library_s > 0.0, "a finite group-delay range > 0 s")?;
        check_fraction("efficiency", &efficiency)?;
        check_fraction("transmission", &transmission)?;
        check_efficiency_below_transmission(&|l| efficiency.value(l), &[&efficiency], &transmission, 0.5 * (lo + hi))?;
        let delay_required = required_group_delay(focal_length_m, focal_length_m / f_number);
        if overflow == DelayOverflow::Reject && delay_required > delay_library_s {
            let d_max = max_diameter(focal_length_m, delay_library_s);
            return Err(Error::GroupDelayExceeded {
                required_fs: delay_required * 1e15,
                library_fs: delay_library_s * 1e15,
                max_diameter_um: d_max * 1e6,
                max_f_number: focal_length_m / d_max,
            });
        }
        Ok(DispersionEngineered {
            f_number,
            focal_length: focal_length_m,
            band: band_m,
            delay_library: delay_library_s,
            delay_required,
            overflow,
            efficiency,
            transmission,
            focal_shift: Vec::new(),
        })
    }

    /// This lens with a residual focal shift `δf(λ)` inside the design band, tabulated at
    /// `wavelengths_m` (at least 2, increasing, the first ≤ λ_min and the last ≥ λ_max so that
    /// the table covers the band) as `shifts_m` (m, `δf > 0` behind the detector, |δf| < f0),
    /// piecewise linear between samples: `W020 = δf/(8F#²)`.
    pub fn with_focal_shift(self, wavelengths_m: &[f64], shifts_m: &[f64]) -> Result<Self, Error> {
        let n = wavelengths_m.len() as f64;
        check("focal_shift.wavelengths", n, n >= 2.0, "at least 2 samples")?;
        let m = shifts_m.len() as f64;
        check("focal_shift.shifts", m, m == n, "as many shifts as wavelengths")?;
        let mut prev = 0.0;
        for &l in wavelengths_m {
            check("focal_shift.wavelengths", l, l > prev, "finite wavelengths > 0 m in increasing order")?;
            prev = l;
        }
        let (first, last) = (wavelengths_m[0], prev);
        check("focal_shift.wavelengths", first, first <= self.band.0, "a table starting at or below band.min")?;
        check("focal_shift.wavelengths", last, last >= self.band.1, "a table ending at or above band.max")?;
        let f0 = self.focal_length;
        for &v in shifts_m {
            check(
                "focal_shift.shifts",
                v,
                v.abs() < f0,
                "a finite focal shift smaller in size than the focal length, m",
            )?;
        }
        let table = wavelengths_m.iter().copied().zip(shifts_m.iter().copied()).collect();
        Ok(DispersionEngineered { focal_shift: table, ..self })
    }

    /// The residual focal shift at `wavelength_m` inside the table (0 without one).
    fn shift_at(&self, wavelength_m: f64) -> f64 {
        let t = &self.focal_shift;
        let Some(i) = t.windows(2).position(|w| wavelength_m <= w[1].0) else {
            return t.last().map_or(0.0, |p| p.1);
        };
        let ((l0, s0), (l1, s1)) = (t[i], t[i + 1]);
        let u = ((wavelength_m - l0) / (l1 - l0)).clamp(0.0, 1.0);
        s0 + u * (s1 - s0)
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "dispersion-engineered"
    }

    /// Group delay the aperture needs, `ΔT_req` (s).
    pub fn required_delay(&self) -> f64 {
        self.delay_required
    }

    /// The fraction of the path that is true delay: `β = min(1, ΔT_lib/ΔT_req)`.
    pub fn true_delay_fraction(&self) -> f64 {
        if self.delay_required <= self.delay_library { 1.0 } else { self.delay_library / self.delay_required }
    }

    /// Whether `wavelength_m` is inside the design band.
    pub fn in_band(&self, wavelength_m: f64) -> bool {
        wavelength_m >= self.band.0 && wavelength_m <= self.band.1
    }

    fn centre(&self) -> f64 {
        0.5 * (self.band.0 + self.band.1)
    }

    /// Defocus at the pupil edge, m: `δf(λ)/(8F#²)` plus, in the reduced mode, the wrapped part's
    /// chromatic defocus `(1 − β)(1 − λ/λ0) f0/(8F#²)`. Outside the band the value at the
    /// nearest band edge (the lens images nothing there; W020 stays continuous in λ for the
    /// spectral quadrature).
    pub fn defocus(&self, wavelength_m: f64) -> f64 {
        let lambda = wavelength_m.clamp(self.band.0, self.band.1);
        let k = 1.0 / (8.0 * self.f_number * self.f_number);
        let chromatic = (1.0 - self.true_delay_fraction()) * (1.0 - lambda / self.centre()) * self.focal_length;
        k * (self.shift_at(lambda) + chromatic)
    }
}

impl LensModel for DispersionEngineered {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, _field: Field) -> Vec<Order> {
        vec![Order::new(self.efficiency(wavelength_m), Pupil::Full, Wavefront::defocus(self.defocus(wavelength_m)))]
    }

    fn efficiency(&self, wavelength_m: f64) -> f64 {
        if self.in_band(wavelength_m) { self.efficiency.value(wavelength_m) } else { 0.0 }
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.transmission.value(wavelength_m)
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.centre())
    }

    fn design_band(&self) -> Option<(f64, f64)> {
        Some(self.band)
    }

    /// No lateral colour and no oblique aberration: the one order is the same at every field
    /// point (docs/physics.md, "Gradients: the dispersion-engineered lens").
    fn turns_with_field(&self) -> bool {
        true
    }

    /// No image shift at any field point (no lateral colour modelled), so every rate is 0: the
    /// OTF off axis is the one on axis, and the lanes of the F-number, focal length and design
    /// wavelength are taken as on axis (as the refractive lens's, its stop at the lens).
    fn image_shift_field_rates(&self, _wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        Some(vec![[0.0, 0.0]])
    }

    /// How the one order moves with the band's centre λ0: the wrapped part's defocus
    /// `(1 − β)(1 − λ/λ0) f0/(8F#²)` by `∂W020/∂ln λ0 = (1 − β)(λ/λ0) f0/(8F#²)` (λ clamped to
    /// the band as [`defocus`](DispersionEngineered::defocus) is; 0 for a true achromat and for
    /// the residual focal shift, a table in λ), the efficiency not at all (docs/physics.md,
    /// "Gradients: the dispersion-engineered lens"). The band's edges move the efficiency's
    /// window too: that is the edges' own term, not λ0's.
    fn design_wavelength_rates(&self, wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        let lambda = wavelength_m.clamp(self.band.0, self.band.1);
        let k = 1.0 / (8.0 * self.f_number * self.f_number);
        let rate = k * (1.0 - self.true_delay_fraction()) * (lambda / self.centre()) * self.focal_length;
        Some(vec![[rate, 0.0]])
    }

    /// How the one order moves with a line's wavelength λ strictly inside the design band
    /// (docs/physics.md, "Gradients: the dispersion-engineered lens"): `W020 = (δf(λ) + (1 − β)
    /// (1 − λ/λ0) f0)/(8F#²)` by `∂W020/∂λ = (δf′(λ) − (1 − β) f0/λ0)/(8F#²)` (`δf′` the residual
    /// focal shift table's segment slope, 0 beyond its rows; 0 for a true achromat without one),
    /// the efficiency and transmission by their tables' segment slopes (0 for constants). `None`
    /// at or outside a band edge (the efficiency's window: a kink, or no light) and on a row of
    /// a table (a kink).
    fn defocus_rates(&self, wavelength_m: f64, _field: Field) -> Option<optics::DefocusRates> {
        let l = wavelength_m;
        if !(l > self.band.0 && l < self.band.1) {
            return None;
        }
        let t = &self.focal_shift;
        let shift_slope = match t.iter().position(|p| p.0 >= l) {
            _ if t.iter().any(|p| p.0 == l) => return None,
            None | Some(0) => 0.0,
            Some(i) => (t[i].1 - t[i - 1].1) / (t[i].0 - t[i - 1].0),
        };
        let k = 1.0 / (8.0 * self.f_number * self.f_number);
        let defocus = k * (shift_slope - (1.0 - self.true_delay_fraction()) * self.focal_length / self.centre());
        Some(optics::DefocusRates {
            defocus,
            ln_efficiency: curve_log_slope(&self.efficiency, l)?,
            ln_transmission: curve_log_slope(&self.transmission, l)?,
        })
    }

    /// An efficiency or transmission table factored out (`crate::chromatic::factor_one_curve`).
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        crate::chromatic::factor_one_curve(&self.efficiency, &self.transmission, 1.0, |efficiency, transmission| {
            std::sync::Arc::new(DispersionEngineered { efficiency, transmission, ..self.clone() })
        })
    }

    fn breakpoints(&self) -> Vec<f64> {
        let band = [self.band.0, self.band.1].into_iter();
        crate::chromatic::curve_breakpoints(
            &self.efficiency,
            &self.transmission,
            band.chain(self.focal_shift.iter().map(|p| p.0)),
        )
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        let mode = match self.overflow {
            DelayOverflow::Reject => String::new(),
            DelayOverflow::Reduced if self.true_delay_fraction() < 1.0 => {
                format!(", reduced achromatism β = {:.3}", self.true_delay_fraction())
            }
            DelayOverflow::Reduced => String::new(),
        };
        format!(
            "dispersion-engineered metalens F/{} f0 = {} mm, achromatic {}–{} nm, group delay {:.2} fs of {:.2} fs{}",
            r(self.f_number),
            r(self.focal_length * 1e3),
            r(self.band.0 * 1e9),
            r(self.band.1 * 1e9),
            self.delay_required * 1e15,
            self.delay_library * 1e15,
            mode
        )
    }
}

/// `∂ln c/∂λ` of a curve at `l`: 0 for a constant, a table's segment slope over its value
/// (piecewise linear); `None` on a row (a kink), outside the table or where its value is 0.
fn curve_log_slope(curve: &Curve, l: f64) -> Option<f64> {
    let Curve::Table(t) = curve else { return Some(0.0) };
    let (w, v) = (t.wavelengths(), t.values());
    let i = w.iter().position(|&x| x >= l)?;
    if i == 0 || w[i] == l {
        return None;
    }
    let value = curve.value(l);
    (value > 0.0).then(|| (v[i] - v[i - 1]) / (w[i] - w[i - 1]) / value)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FS: f64 = 1e-15;

    /// F and D of a lens given by its NA (`NA = R/√(R² + F²)`) and diameter.
    fn from_na(na: f64, diameter: f64) -> (f64, f64) {
        let r = 0.5 * diameter;
        (r * (1.0 - na * na).sqrt() / na, diameter)
    }

    #[test]
    fn group_delay_of_published_lenses() {
        // the paper's lens: F = 3.36 mm, D = 1.344 mm
        assert!((required_group_delay(3.36e-3, 1.344e-3) / FS - 221.96).abs() < 0.01);
        // the direct form (F/c)(1/√(1 − NA²) − 1)
        let (r, f) = (0.672e-3, 3.36e-3);
        let na: f64 = r / f64::hypot(r, f);
        let direct = f / C * (1.0 / (1.0 - na * na).sqrt() - 1.0);
        assert!((required_group_delay(f, 2.0 * r) - direct).abs() < 1e-9 * direct);
        // Chen et al. 2019: NA 0.2, D = 26.4 µm; Ndao et al. 2020: NA 0.12, D = 10 µm
        let (f, d) = from_na(0.2, 26.4e-6);
        assert!((required_group_delay(f, d) / FS - 4.45).abs() < 0.005, "{}", required_group_delay(f, d) / FS);
        let (f, d) = from_na(0.12, 10e-6);
        assert!((required_group_delay(f, d) / FS - 1.00).abs() < 0.005, "{}", required_group_delay(f, d) / FS);
    }

    #[test]
    fn largest_aperture_of_a_library() {
        let d = max_diameter(3.36e-3, 5.0 * FS);
        assert!((d - 200.8e-6).abs() < 0.05e-6, "{d}");
        assert!((3.36e-3 / d - 16.74).abs() < 0.005);
        // the inverse of required_group_delay
        assert!((required_group_delay(3.36e-3, d) - 5.0 * FS).abs() < 1e-9 * FS);
    }

    fn achromat(
        f_number: f64,
        f0: f64,
        library_s: f64,
        overflow: DelayOverflow,
    ) -> Result<DispersionEngineered, Error> {
        DispersionEngineered::new(
            f_number,
            f0,
            (700e-9, 900e-9),
            library_s,
            Curve::Constant(0.3),
            Curve::Constant(0.6),
            overflow,
        )
    }

    #[test]
    fn rejects_an_aperture_beyond_the_library() {
        let e = achromat(2.5, 3.36e-3, 5.0 * FS, DelayOverflow::Reject).unwrap_err();
        let Error::GroupDelayExceeded { required_fs, library_fs, max_diameter_um, max_f_number } = e.clone() else {
            panic!("{e:?}")
        };
        assert!((required_fs - 221.96).abs() < 0.01 && (library_fs - 5.0).abs() < 1e-12);
        assert!((max_diameter_um - 200.8).abs() < 0.05 && (max_f_number - 16.74).abs() < 0.005);
        let text = e.to_string();
        for part in ["221.96 fs", "5.00 fs", "D = 200.8 µm", "F/16.74", "delay_overflow = reduced"] {
            assert!(text.contains(part), "{part}: {text}");
        }
        // Ndao et al. 2020 against its library's 0.97 fs
        let (f, d) = from_na(0.12, 10e-6);
        let e = achromat(f / d, f, 0.97 * FS, DelayOverflow::Reject).unwrap_err();
        assert!(e.to_string().contains("1.00 fs") && e.to_string().contains("0.97 fs"), "{e}");
        // an aperture within the library is accepted: F/16.74 needs ≤ 5 fs
        assert!(achromat(16.75, 3.36e-3, 5.0 * FS, DelayOverflow::Reject).is_ok());
    }

    #[test]
    fn ideal_achromat_is_in_focus_across_its_band_only() {
        let lens = achromat(16.75, 3.36e-3, 5.0 * FS, DelayOverflow::Reject).unwrap();
        for lambda in [700e-9, 800e-9, 900e-9] {
            let o = &lens.orders(lambda, Field::ON_AXIS)[0];
            assert_eq!((o.efficiency, o.wavefront.defocus_m), (0.3, 0.0));
        }
        for lambda in [699e-9, 901e-9] {
            assert_eq!(lens.efficiency(lambda), 0.0);
            assert_eq!(lens.transmission(lambda), 0.6);
        }
        assert_eq!(lens.true_delay_fraction(), 1.0);
        assert_eq!(lens.design_wavelength(), Some(800e-9));
        assert_eq!(lens.breakpoints(), vec![700e-9, 900e-9]);
    }

    #[test]
    fn residual_focal_shift_has_the_wavefront_sign() {
        let lens = achromat(2.5, 3.36e-3, 300.0 * FS, DelayOverflow::Reject)
            .unwrap()
            .with_focal_shift(&[650e-9, 800e-9, 900e-9], &[-15e-6, 0.0, 10e-6])
            .unwrap();
        // 10 µm behind the detector at 900 nm: W020 = 10 µm/(8 × 6.25) = +0.2 µm
        assert!((lens.defocus(900e-9) - 0.2e-6).abs() < 1e-18);
        // 700 nm: δf = −15 µm + (50/150) 15 µm = −10 µm, in front of the detector
        assert!((lens.defocus(700e-9) + 0.2e-6).abs() < 1e-18);
        assert!(lens.defocus(800e-9).abs() < 1e-18);
        assert!((lens.defocus(850e-9) - 0.1e-6).abs() < 1e-18);
        // continuous past the band edge
        assert_eq!(lens.defocus(950e-9), lens.defocus(900e-9));
        let base = || achromat(2.5, 3.36e-3, 300.0 * FS, DelayOverflow::Reject).unwrap();
        let e = base().with_focal_shift(&[700e-9, 900e-9], &[0.0, f64::INFINITY]).unwrap_err();
        assert!(e.to_string().contains("focal_shift.shifts = inf"), "{e}");
        let e = base().with_focal_shift(&[750e-9, 900e-9], &[0.0, 0.0]).unwrap_err();
        assert!(
            e.to_string().contains("focal_shift.wavelengths = 0.00000075 is out of range: expected a table starting"),
            "{e}"
        );
        let e = base().with_focal_shift(&[700e-9, 650e-9, 900e-9], &[0.0; 3]).unwrap_err();
        assert!(e.to_string().contains("increasing order"), "{e}");
        assert!(base().with_focal_shift(&[700e-9, 900e-9], &[0.0]).is_err());
    }

    #[test]
    fn reduced_mode_keeps_the_wrapped_part_chromatic() {
        let lens = achromat(2.5, 3.36e-3, 5.0 * FS, DelayOverflow::Reduced).unwrap();
        let beta = lens.true_delay_fraction();
        assert!((beta - 5.0 / 221.958).abs() < 1e-4, "{beta}");
        let chromatic =
            crate::ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(0.3), Curve::Constant(0.6)).unwrap();
        for lambda in [700e-9, 760e-9, 800e-9, 850e-9, 900e-9] {
            let want = (1.0 - beta) * chromatic.defocus(lambda);
            assert!((lens.defocus(lambda) - want).abs() < 1e-18, "{lambda}");
        }
        assert!(lens.describe().contains("reduced achromatism β = 0.023"), "{}", lens.describe());
    }

    /// A line's rates (`LensModel::defocus_rates`) against central differences of the order's
    /// defocus inside the band (step 1e-6 of λ: W020 is piecewise linear, so the difference is
    /// exact to rounding), in the reduced mode and for a true achromat with a residual focal
    /// shift table; at a band edge and on a table row, `None` (a kink).
    #[test]
    fn defocus_rates_are_the_derivative_of_the_defocus() {
        let reduced = achromat(2.5, 3.36e-3, 5.0 * FS, DelayOverflow::Reduced).unwrap();
        let shifted = achromat(16.75, 3.36e-3, 5.0 * FS, DelayOverflow::Reject)
            .unwrap()
            .with_focal_shift(&[650e-9, 780e-9, 950e-9], &[2e-6, -1e-6, 3e-6])
            .unwrap();
        for lens in [&reduced, &shifted] {
            for l in [720e-9, 803e-9, 870e-9] {
                let h = 1e-6 * l;
                let differences = (lens.defocus(l + h) - lens.defocus(l - h)) / (2.0 * h);
                let rates = lens.defocus_rates(l, Field::ON_AXIS).unwrap();
                assert!(
                    (rates.defocus - differences).abs() <= 1e-7 * differences.abs(),
                    "{l}: {rates:?} {differences}"
                );
                assert_eq!((rates.ln_efficiency, rates.ln_transmission), (0.0, 0.0));
            }
            assert!(lens.defocus_rates(700e-9, Field::ON_AXIS).is_none());
            assert!(lens.defocus_rates(900e-9, Field::ON_AXIS).is_none());
        }
        assert!(shifted.defocus_rates(780e-9, Field::ON_AXIS).is_none());
    }

    #[test]
    fn design_wavelength_rates_are_the_derivative_of_the_defocus() {
        // ∂W020/∂ln λ0 against a central difference of the defocus in the band's centre (both
        // edges moved by the same δ), in the reduced mode and for the true achromat
        for (f_number, overflow) in [(2.5, DelayOverflow::Reduced), (16.75, DelayOverflow::Reject)] {
            let at = |shift: f64| {
                DispersionEngineered::new(
                    f_number,
                    3.36e-3,
                    (700e-9 + shift, 900e-9 + shift),
                    5.0 * FS,
                    Curve::Constant(0.3),
                    Curve::Constant(0.6),
                    overflow,
                )
                .unwrap()
            };
            let lens = at(0.0);
            assert_eq!(lens.design_band(), Some((700e-9, 900e-9)));
            assert!(lens.turns_with_field());
            assert_eq!(lens.image_shift_field_rates(800e-9, Field::new(0.05, 0.0)), Some(vec![[0.0; 2]]));
            let h = 1e-12;
            for lambda in [720e-9, 800e-9, 880e-9] {
                let rate = lens.design_wavelength_rates(lambda, Field::ON_AXIS).unwrap()[0];
                let diff = (at(h).defocus(lambda) - at(-h).defocus(lambda)) / (2.0 * h) * 800e-9;
                assert!((rate[0] - diff).abs() <= 1e-7 * lens.defocus(700e-9).abs().max(1e-12), "{rate:?} {diff}");
                assert_eq!(rate[1], 0.0);
            }
        }
    }

    #[test]
    fn rejects_out_of_range_parameters() {
        let bad = |band: (f64, f64), lib: f64, e: f64, t: f64| {
            DispersionEngineered::new(
                2.5,
                3e-3,
                band,
                lib,
                Curve::Constant(e),
                Curve::Constant(t),
                DelayOverflow::Reduced,
            )
            .unwrap_err()
            .to_string()
        };
        assert!(bad((0.0, 900e-9), FS, 0.1, 0.5).contains("band.min = 0 is out of range"));
        assert!(bad((800e-9, 700e-9), FS, 0.1, 0.5).contains("band.max = 0.0000007 is out of range"));
        assert!(bad((700e-9, 900e-9), -FS, 0.1, 0.5).contains("delay_library = -0.000000000000001"));
        assert!(bad((700e-9, 900e-9), FS, 0.6, 0.5).contains("exceeds transmission T = 0.5"));
        assert!(bad((700e-9, 900e-9), FS, 0.1, 1.5).contains("transmission = 1.5"));
    }

    #[test]
    fn describes_itself() {
        let lens = achromat(16.75, 3.36e-3, 5.0 * FS, DelayOverflow::Reject).unwrap();
        assert_eq!(
            lens.describe(),
            "dispersion-engineered metalens F/16.75 f0 = 3.36 mm, achromatic 700–900 nm, group delay 4.99 fs of 5.00 fs"
        );
        assert_eq!(lens.kind(), "dispersion-engineered");
    }
}
