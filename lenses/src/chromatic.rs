//! The chromatic metalens / diffractive lens.

use std::sync::Arc;

use optics::fft::Aperture;
use optics::{
    AffineDefocus, DefocusRates, FactoredEfficiency, FactoredPart, Field, LensModel, Order, Pupil, Wavefront,
};
use radiometry::{Sampled, Spectrum};

use crate::Error;

/// A quantity of the lens that is constant or tabulated against wavelength (piecewise linear
/// between samples, zero outside the table: a lens is not characterized where it was not
/// measured).
#[derive(Clone, Debug, PartialEq)]
pub enum Curve {
    /// The same value at every wavelength.
    Constant(f64),
    /// Samples against wavelength (m).
    Table(Sampled),
}

/// The factoring ([`LensModel::factored_efficiency`]) of a lens whose orders all carry the one
/// efficiency curve `efficiency` and whose transmission is `scale × transmission`: `None` where
/// both are constants (nothing to fold); else one part, the efficiency's table (or 1 where it
/// is a constant) with `relative`, the lens rebuilt by `rebuild(efficiency, transmission)` with
/// that table divided out (efficiency 1, or the constant) and transmission 1.
pub(crate) fn factor_one_curve(
    efficiency: &Curve,
    transmission: &Curve,
    scale: f64,
    rebuild: impl FnOnce(Curve, Curve) -> Arc<dyn LensModel>,
) -> Option<FactoredEfficiency> {
    if matches!((efficiency, transmission), (Curve::Constant(_), Curve::Constant(_))) {
        return None;
    }
    let (table, relative) = match efficiency {
        Curve::Table(t) => (Spectrum::Sampled(t.clone()), Curve::Constant(1.0)),
        Curve::Constant(c) => (Spectrum::Constant(1.0), Curve::Constant(*c)),
    };
    Some(FactoredEfficiency {
        parts: vec![FactoredPart { table, relative: rebuild(relative, Curve::Constant(1.0)) }],
        transmission: curve_spectrum(scale, transmission),
    })
}

/// `scale ×` a curve (a transmission, or an efficiency table a part multiplies) as a spectrum
/// factor: a constant, or the table times the scale.
pub(crate) fn curve_spectrum(scale: f64, curve: &Curve) -> Spectrum {
    match curve {
        Curve::Constant(t) => Spectrum::Constant(scale * t),
        Curve::Table(t) if scale == 1.0 => Spectrum::Sampled(t.clone()),
        Curve::Table(t) => Spectrum::product(vec![Spectrum::Constant(scale), Spectrum::Sampled(t.clone())]),
    }
}

/// The samples of a lens's efficiency and transmission curves with `extra` (a table's
/// wavelengths, band edges), sorted, each once: the breakpoints of a lens with such curves.
pub(crate) fn curve_breakpoints(
    efficiency: &Curve,
    transmission: &Curve,
    extra: impl IntoIterator<Item = f64>,
) -> Vec<f64> {
    let mut b: Vec<f64> =
        efficiency.breakpoints().iter().chain(transmission.breakpoints()).copied().chain(extra).collect();
    b.sort_by(f64::total_cmp);
    b.dedup();
    b
}

impl Curve {
    /// The value at `wavelength_m`.
    pub fn value(&self, wavelength_m: f64) -> f64 {
        match self {
            Curve::Constant(v) => *v,
            Curve::Table(t) => t.value(wavelength_m),
        }
    }

    pub(crate) fn breakpoints(&self) -> &[f64] {
        match self {
            Curve::Constant(_) => &[],
            Curve::Table(t) => t.wavelengths(),
        }
    }

    pub(crate) fn range(&self) -> (f64, f64) {
        match self {
            Curve::Constant(v) => (*v, *v),
            Curve::Table(t) => (t.min_value(), t.max_value()),
        }
    }
}

/// A chromatic (uncorrected) metalens or diffractive lens: `f(λ) = f0 λ0/λ`, the detector at
/// `f0`, one imaging order (the first diffraction order) with efficiency τ1(λ) through the full
/// circular aperture, total transmission T(λ) into all orders.
///
/// Wavefront sign (docs/physics.md, "Sign of the wavefront"; the convention of [`optics::Wavefront`]):
/// `W` is the optical path of the actual wavefront relative to the reference sphere centred on
/// the detector point, `W020 > 0` a focus behind the detector. Longer wavelengths focus in front
/// of the detector (`f(λ) < f0`), so their defocus is negative:
/// `W020(λ) = (1 − λ/λ0) f0/(8 F#²)` ([`defocus`](Self::defocus)). The Seidel terms of
/// [`with_seidel`](Self::with_seidel) carry the same sign and add to it.
#[derive(Clone, Debug)]
pub struct ChromaticMetalens {
    f_number: f64,
    focal_length: f64,
    design_wavelength: f64,
    efficiency: Curve,
    transmission: Curve,
    /// the iris when it is not the centred full circle (decentred, obscured, a sector)
    aperture: Option<Arc<Aperture>>,
    /// the iris' area as a fraction of the full aperture's (1 without an iris): it scales τ1 and T
    area_fraction: f64,
    /// Seidel terms (m at the pupil edge) besides the chromatic defocus: W040, W131, W222, W220
    seidel: [f64; 4],
}

/// `Ok` when `value` is finite and `ok`, else [`Error::OutOfRange`] naming the parameter.
pub(crate) fn check(name: &'static str, value: f64, ok: bool, expected: &'static str) -> Result<(), Error> {
    if value.is_finite() && ok { Ok(()) } else { Err(Error::OutOfRange { name, value, expected }) }
}

/// `Ok` when every value of `curve` is a fraction in `[0, 1]`.
pub(crate) fn check_fraction(name: &'static str, curve: &Curve) -> Result<(), Error> {
    let (lo, hi) = curve.range();
    check(name, lo, lo >= 0.0, "a fraction in [0, 1]")?;
    check(name, hi, hi <= 1.0, "a fraction in [0, 1]")
}

/// `Ok` when the total imaging efficiency `efficiency(λ)` (a sum of the piecewise-linear
/// `parts`) is at most `transmission(λ)` everywhere: both sides are piecewise linear with kinks
/// only at the curves' samples, so checking there (and anywhere, here at `anywhere_m`, for
/// constants) suffices.
pub(crate) fn check_efficiency_below_transmission(
    efficiency: &dyn Fn(f64) -> f64,
    parts: &[&Curve],
    transmission: &Curve,
    anywhere_m: f64,
) -> Result<(), Error> {
    let probes = parts.iter().flat_map(|c| c.breakpoints()).chain(transmission.breakpoints()).copied();
    for lambda in probes.chain(std::iter::once(anywhere_m)) {
        let (e, t) = (efficiency(lambda), transmission.value(lambda));
        if e > t * (1.0 + 1e-12) {
            return Err(Error::EfficiencyAboveTransmission {
                wavelength_nm: optics::round_for_display(lambda * 1e9),
                efficiency: e,
                transmission: t,
            });
        }
    }
    Ok(())
}

impl ChromaticMetalens {
    /// A chromatic lens of working F-number `f_number` (`f0/D`, ≥ 0.5 so that the paraxial
    /// `NA = 1/(2F#)` ≤ 1), design focal length `focal_length_m` at `design_wavelength_m`, with
    /// first-order efficiency `efficiency` and total transmission `transmission` (both in
    /// `[0, 1]`, `τ1 ≤ T` at every wavelength).
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        design_wavelength_m: f64,
        efficiency: Curve,
        transmission: Curve,
    ) -> Result<Self, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        check("design_wavelength", design_wavelength_m, design_wavelength_m > 0.0, "a finite wavelength > 0 m")?;
        check_fraction("efficiency", &efficiency)?;
        check_fraction("transmission", &transmission)?;
        check_efficiency_below_transmission(
            &|l| efficiency.value(l),
            &[&efficiency],
            &transmission,
            design_wavelength_m,
        )?;
        Ok(ChromaticMetalens {
            f_number,
            focal_length: focal_length_m,
            design_wavelength: design_wavelength_m,
            efficiency,
            transmission,
            aperture: None,
            area_fraction: 1.0,
            seidel: [0.0; 4],
        })
    }

    /// This lens imaging through `aperture` (in units of the full aperture's radius) instead of
    /// the centred full circle: a decentred iris (paper SI Fig. S3), an obscuration, a sector.
    /// Such a lens is computed on the FFT path.
    ///
    /// Photon counts follow the pupil (docs/physics.md, "Lens families": a sub-aperture,
    /// obscuration or sector carries its area fraction in τ): the efficiency τ1(λ) and the
    /// transmission T(λ) given to [`new`](Self::new) are those of the full clear aperture, and
    /// through `aperture` both are multiplied by its area fraction `a`
    /// ([`Aperture::area_fraction`], exact for discs, annuli and sectors, measured for a mask):
    /// a 10° sector collects `1/36` of the light, an annulus of obscuration ε `1 − ε²`, and a
    /// decentred iris of full size all of it. Light the iris stops is neither signal nor
    /// background: it never reaches the detector.
    pub fn with_aperture(self, aperture: Aperture) -> Self {
        let area_fraction = aperture.area_fraction();
        ChromaticMetalens { aperture: Some(Arc::new(aperture)), area_fraction, ..self }
    }

    /// The area fraction of the iris ([`with_aperture`](Self::with_aperture)), 1 without one.
    pub fn area_fraction(&self) -> f64 {
        self.area_fraction
    }

    /// This lens with Seidel aberrations at the scene's field point (m at the pupil edge, the
    /// field along +x): spherical `W040 ρ⁴`, coma `W131 ρ³ cos φ`, astigmatism `W222 ρ² cos² φ`,
    /// field curvature `W220 ρ²`, with the sign of the chromatic defocus (docs/physics.md, "Optics:
    /// the OTF"): `W040 > 0` focuses the marginal zone behind the paraxial focus, `W220 > 0` moves
    /// the focus of the field point behind the detector, and `W220` adds to `W020(λ)`: with
    /// `W220 > 0` the sharpest wavelength is the one with `W020(λ) = −W220`, above λ0.
    pub fn with_seidel(self, spherical_m: f64, coma_m: f64, astigmatism_m: f64, field_curvature_m: f64) -> Self {
        ChromaticMetalens { seidel: [spherical_m, coma_m, astigmatism_m, field_curvature_m], ..self }
    }

    /// Focal length at `wavelength_m`: `f(λ) = f0 λ0/λ` (docs/physics.md, "Lens families").
    pub fn focal_length_at(&self, wavelength_m: f64) -> f64 {
        self.focal_length * self.design_wavelength / wavelength_m
    }

    /// Defocus at the pupil edge with the detector at `f0`, m:
    /// `W020(λ) = (D²/8)(1/f0 − 1/f(λ)) = (1 − λ/λ0) f0/(8 F#²)` (docs/physics.md, "Optics: the
    /// OTF"). Negative for `λ > λ0`: `f(λ) < f0` puts the focus in front of the detector.
    pub fn defocus(&self, wavelength_m: f64) -> f64 {
        (1.0 - wavelength_m / self.design_wavelength) * self.focal_length / (8.0 * self.f_number * self.f_number)
    }
}

impl ChromaticMetalens {
    /// Lateral colour: displacement (m) on the detector of the image of `field` at
    /// `wavelength_m` from its design-wavelength position. A diffractive lens behind a remote
    /// aperture stop (the wide-field metalens of the paper's ref. 13) forms its image at a height
    /// proportional to its focal length, `h(λ) = f(λ) tan θ`, so relative to `h0 = f0 tan θ` the
    /// shift is `h0 (λ0/λ − 1)`, along the field direction. Field curvature and the other
    /// off-axis aberrations are not modelled here.
    pub fn lateral_colour(&self, wavelength_m: f64, field: Field) -> [f64; 2] {
        let k = self.design_wavelength / wavelength_m - 1.0;
        // tan(±0) = ±0 without the library call: on axis (every spectral node of a scene
        // without a field angle asks) the call was 1 % of a spectrometer evaluation
        let tan = |angle: f64| if angle == 0.0 { angle } else { angle.tan() };
        [self.focal_length * tan(field.x_rad) * k, self.focal_length * tan(field.y_rad) * k]
    }
}

impl LensModel for ChromaticMetalens {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        let mut orders = Vec::with_capacity(1);
        self.orders_into(wavelength_m, field, &mut orders);
        orders
    }

    fn orders_into(&self, wavelength_m: f64, field: Field, out: &mut Vec<Order>) {
        let [dx, dy] = self.lateral_colour(wavelength_m, field);
        let mut wavefront = Wavefront::defocus(self.defocus(wavelength_m)).shifted(dx, dy);
        [wavefront.spherical_m, wavefront.coma_m, wavefront.astigmatism_m, wavefront.field_curvature_m] = self.seidel;
        let pupil = self.aperture.as_ref().map_or(Pupil::Full, |a| Pupil::Aperture(a.clone()));
        out.push(Order::new(self.efficiency(wavelength_m), pupil, wavefront));
    }

    /// τ1(λ) times the iris' area fraction ([`with_aperture`](Self::with_aperture)).
    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.area_fraction * self.efficiency.value(wavelength_m)
    }

    /// T(λ) times the iris' area fraction.
    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.area_fraction * self.transmission.value(wavelength_m)
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.design_wavelength)
    }

    /// The lateral colour's `Δ = f0 tan θ (λ0/λ − 1)` on each axis
    /// ([`lateral_colour`](Self::lateral_colour)) moves as `∂Δx/∂θx = f0 sec²θx (λ0/λ − 1)`
    /// (and the same in y); the defocus, the Seidel terms, the pupil and the efficiency are the
    /// same at every field point.
    fn image_shift_field_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        let k = self.design_wavelength / wavelength_m - 1.0;
        let sec2 = |angle: f64| 1.0 / (angle.cos() * angle.cos());
        Some(vec![[self.focal_length * sec2(field.x_rad) * k, self.focal_length * sec2(field.y_rad) * k]])
    }

    /// `W020 = (1 − λ/λ0) f0/(8F#²)` moves as `∂W020/∂λ = −f0/(8F#² λ0)` at every field point and
    /// through an iris (the order's defocus is the pupil's; an iris keeps a disc of it and its
    /// area fraction, constant in λ); τ1 and T constant curves. The Seidel terms are given in
    /// metres and do not move with λ (the callers that follow the defocus alone check the order
    /// is defocus only). `None` with an efficiency or transmission table (whose slope has kinks
    /// at its rows).
    fn defocus_rates(&self, _wavelength_m: f64, _field: Field) -> Option<DefocusRates> {
        let (Curve::Constant(_), Curve::Constant(_)) = (&self.efficiency, &self.transmission) else {
            return None;
        };
        let k = self.focal_length / (8.0 * self.f_number * self.f_number);
        Some(DefocusRates { defocus: -k / self.design_wavelength, ln_efficiency: 0.0, ln_transmission: 0.0 })
    }

    /// `W020 = (1 − λ/λ0) f0/(8F#²)` moves as `∂W020/∂ln λ0 = (λ/λ0) f0/(8F#²)`; τ1(λ) and T(λ)
    /// do not depend on λ0, nor on the field point. Off axis the lateral colour
    /// `Δ = f0 tan θ (λ0/λ − 1)` moves as `Δ + f0 tan θ` (`LensModel::design_wavelength_rates`).
    fn design_wavelength_rates(&self, wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        let k = self.focal_length / (8.0 * self.f_number * self.f_number);
        Some(vec![[k * wavelength_m / self.design_wavelength, 0.0]])
    }

    /// With τ1 or T a table: τ1's table (or 1) factored out of the one order (`relative` has
    /// τ1 = 1 × the iris' area fraction, or τ1 itself where it is a constant), T as a spectrum.
    fn factored_efficiency(&self) -> Option<FactoredEfficiency> {
        factor_one_curve(&self.efficiency, &self.transmission, self.area_fraction, |efficiency, transmission| {
            Arc::new(ChromaticMetalens { efficiency, transmission, ..self.clone() })
        })
    }

    fn breakpoints(&self) -> Vec<f64> {
        curve_breakpoints(&self.efficiency, &self.transmission, [])
    }

    fn affine_defocus(&self, field: Field) -> Option<AffineDefocus> {
        // W020 = (1 − λ/λ0) f0/(8F#²) = k − (k/λ0) λ: affine; on axis no lateral colour; the
        // full pupil with no Seidel terms; and both efficiency curves constant
        let (Curve::Constant(efficiency), Curve::Constant(transmission)) = (&self.efficiency, &self.transmission)
        else {
            return None;
        };
        let k = self.focal_length / (8.0 * self.f_number * self.f_number);
        (self.aperture.is_none() && self.seidel == [0.0; 4] && field.is_on_axis()).then_some(AffineDefocus {
            efficiency: *efficiency,
            transmission: *transmission,
            w020_intercept_m: k,
            w020_slope: -k / self.design_wavelength,
        })
    }

    fn describe(&self) -> String {
        format!(
            "chromatic metalens F/{} f0 = {} mm at λ0 = {} nm",
            optics::round_for_display(self.f_number),
            optics::round_for_display(self.focal_length * 1e3),
            optics::round_for_display(self.design_wavelength * 1e9)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> ChromaticMetalens {
        ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap()
    }

    /// `design_wavelength_rates` against central differences of the defocus of lenses built at
    /// λ0 ± h (relative step 1e-5: truncation ~1e-10), on axis; off axis the same, and the
    /// lateral colour's rate `Δ + f0 tan θ` against differences of the orders' image shifts.
    #[test]
    fn design_wavelength_rates_match_differences() {
        let at =
            |l0: f64| ChromaticMetalens::new(2.5, 3.36e-3, l0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
        let h = 1e-5;
        for l in [750e-9, 800e-9, 850e-9] {
            let [[d_w, d_tau]] = paper().design_wavelength_rates(l, Field::ON_AXIS).unwrap()[..] else { panic!() };
            let w = (at(800e-9 * (1.0 + h)).defocus(l) - at(800e-9 * (1.0 - h)).defocus(l))
                / ((1.0 + h).ln() - (1.0 - h).ln());
            assert!((d_w - w).abs() <= 1e-8 * w.abs(), "{l}: {d_w} vs {w}");
            assert_eq!(d_tau, 0.0);
        }
        // off axis: the same rates, and the lateral colour moves as Δ + f0 tan θ (its own scale
        // and a translation common to every wavelength)
        let field = Field::new(0.05, -0.03);
        let shift = |lens: &ChromaticMetalens, l: f64| lens.orders(l, field)[0].wavefront.image_shift_m;
        for l in [750e-9, 850e-9] {
            assert_eq!(paper().design_wavelength_rates(l, field), paper().design_wavelength_rates(l, Field::ON_AXIS));
            let (up, down) = (shift(&at(800e-9 * (1.0 + h)), l), shift(&at(800e-9 * (1.0 - h)), l));
            let own = shift(&paper(), l);
            for (a, angle) in [field.x_rad, field.y_rad].into_iter().enumerate() {
                let d = (up[a] - down[a]) / ((1.0 + h).ln() - (1.0 - h).ln());
                let want = own[a] + 3.36e-3 * angle.tan();
                assert!((d - want).abs() <= 1e-8 * want.abs(), "{l} axis {a}: {d} vs {want}");
            }
        }
    }

    #[test]
    fn focal_length_scales_inversely_with_wavelength() {
        let lens = paper();
        // f(λ) = f0 λ0/λ: at 400 nm the focal length doubles
        assert!((lens.focal_length_at(400e-9) - 6.72e-3).abs() < 1e-15);
        assert_eq!(lens.defocus(800e-9), 0.0);
    }

    #[test]
    fn defocus_matches_the_thin_lens_sag_difference() {
        // The sag of the converging reference sphere of radius f0 minus that of the actual wave
        // converging at f(λ): W020 = (D²/8)(1/f0 − 1/f(λ)), D = f0/F# = 1.344 mm
        let lens = paper();
        let d: f64 = 3.36e-3 / 2.5;
        for lambda in [700e-9, 790e-9, 900e-9] {
            let direct = d * d / 8.0 * (1.0 / 3.36e-3 - 1.0 / lens.focal_length_at(lambda));
            assert!((lens.defocus(lambda) - direct).abs() < 1e-18, "{lambda}");
        }
    }

    /// The sign convention (docs/physics.md, "Sign of the wavefront"): a focus `Δz` behind the
    /// detector is `W020 = Δz/(8 F#²) > 0`. Below λ0 the focal length grows (`f(λ) > f0`: the
    /// focus behind the detector, W020 > 0), above λ0 it shrinks (in front, W020 < 0), and
    /// paraxially `W020 ≈ (f(λ) − f0)/(8 F#²)`.
    #[test]
    fn defocus_is_negative_when_the_focus_is_in_front_of_the_detector() {
        let lens = paper();
        let k = 3.36e-3 / (8.0 * 2.5 * 2.5);
        for lambda in [700e-9, 790e-9, 799.9e-9, 800.1e-9, 850e-9, 1000e-9] {
            let w020 = lens.defocus(lambda);
            assert_eq!(w020 < 0.0, lambda > 800e-9, "{lambda}: {w020}");
            assert_eq!(w020 < 0.0, lens.focal_length_at(lambda) < 3.36e-3, "{lambda}");
            assert!((w020 - (1.0 - lambda / 800e-9) * k).abs() < 1e-20, "{lambda}: {w020}");
            // the order reports the same defocus
            assert_eq!(lens.orders(lambda, Field::ON_AXIS)[0].wavefront.defocus_m, w020);
        }
        // 850 nm: f = 3.16235 mm, 0.19765 mm in front; W020 = −0.0625 k = −4.2 µm
        assert!((lens.defocus(850e-9) + 4.2e-6).abs() < 1e-15);
        let dz = lens.focal_length_at(790e-9) - 3.36e-3;
        assert!((lens.defocus(790e-9) - dz / 50.0).abs() < 0.02 * dz / 50.0, "{dz}");
    }

    /// The closed form's affine coefficients reproduce `defocus` (intercept `+k`, slope `−k/λ0`).
    #[test]
    fn affine_defocus_follows_the_sign() {
        let lens = paper();
        let a = lens.affine_defocus(Field::ON_AXIS).unwrap();
        for lambda in [500e-9, 800e-9, 850e-9] {
            let w = a.w020_intercept_m + a.w020_slope * lambda;
            assert!((w - lens.defocus(lambda)).abs() < 1e-18, "{lambda}: {w}");
        }
        assert!(a.w020_intercept_m > 0.0 && a.w020_slope < 0.0);
    }

    #[test]
    fn lateral_colour_scales_with_focal_length() {
        // 8° field: h0 = 3.36 mm × tan 8° = 0.47222 mm; at 850 nm h = h0 × 800/850, shift = h0 (800/850 − 1)
        let lens = paper();
        let field = Field::new(8f64.to_radians(), 0.0);
        let [dx, dy] = lens.lateral_colour(850e-9, field);
        let h0 = 3.36e-3 * 8f64.to_radians().tan();
        assert!((dx - h0 * (800.0 / 850.0 - 1.0)).abs() < 1e-18 && dy == 0.0);
        assert_eq!(lens.lateral_colour(800e-9, field), [0.0, 0.0]);
        assert_eq!(lens.lateral_colour(850e-9, Field::ON_AXIS), [0.0, 0.0]);
    }

    #[test]
    fn rejects_efficiency_above_transmission() {
        let e = ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(0.6), Curve::Constant(0.55)).unwrap_err();
        assert!(e.to_string().contains("τ1 = 0.6 exceeds transmission T = 0.55"), "{e}");
    }

    #[test]
    fn rejects_out_of_range_parameters() {
        let e = ChromaticMetalens::new(0.3, 3.36e-3, 800e-9, Curve::Constant(0.1), Curve::Constant(0.5)).unwrap_err();
        assert!(e.to_string().contains("f_number = 0.3 is out of range"), "{e}");
        let e = ChromaticMetalens::new(2.5, f64::NAN, 800e-9, Curve::Constant(0.1), Curve::Constant(0.5)).unwrap_err();
        assert!(e.to_string().contains("focal_length = NaN"), "{e}");
        let e = ChromaticMetalens::new(2.5, 3e-3, 800e-9, Curve::Constant(0.1), Curve::Constant(1.5)).unwrap_err();
        assert!(e.to_string().contains("transmission = 1.5"), "{e}");
    }

    /// Photon counts follow the pupil: a 10° sector passes 1/36 of τ1 and T, an annulus of
    /// obscuration 0.5 three quarters, a decentred full-size iris all of it (area fractions of
    /// the shapes by hand: angle/2π, 1 − ε²).
    #[test]
    fn an_aperture_scales_efficiency_and_transmission_by_its_area() {
        let sector = Aperture::sector(0.0, 10f64.to_radians()).unwrap();
        let annulus = Aperture::annulus(0.5).unwrap();
        let iris = Aperture::circle().decentred(0.2, -0.1).unwrap();
        for (aperture, area) in [(sector, 1.0 / 36.0), (annulus, 0.75), (iris, 1.0)] {
            let lens = paper().with_aperture(aperture);
            assert!((lens.area_fraction() - area).abs() < 1e-15, "{area}");
            for lambda in [700e-9, 800e-9] {
                assert!((lens.efficiency(lambda) - 0.15 * area).abs() < 1e-15, "{area}");
                assert!((lens.transmission(lambda) - 0.55 * area).abs() < 1e-15, "{area}");
                let order = &lens.orders(lambda, Field::ON_AXIS)[0];
                assert_eq!(order.efficiency, lens.efficiency(lambda));
                assert!((order.pupil.area_fraction() - area).abs() < 1e-15);
            }
        }
        assert_eq!(paper().area_fraction(), 1.0);
    }
}
