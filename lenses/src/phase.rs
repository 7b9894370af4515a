//! A lens given by its phase profile: a designer's metalens or diffractive lens (Zemax Binary 2
//! coefficients or a radial phase table), evaluated against the exact reference sphere.

use std::sync::Arc;

use optics::radial::{Oblique, RadialProfile, RadialPupil};
use optics::{Field, LensModel, Order, Wavefront};

use crate::Error;
use crate::chromatic::{Curve, check, check_efficiency_below_transmission, check_fraction, curve_breakpoints};
use crate::harmonic::{HARMONIC_ORDER_REACH, sinc};
use crate::refractive::Sellmeier;

/// How the phase given at the design wavelength λ0 behaves at other wavelengths
/// (docs/physics.md, "Designs given as data"). There is no default: a profile alone does not say.
#[derive(Clone, Debug, PartialEq)]
pub enum Dispersion {
    /// The radian phase is the same at every wavelength (a geometric / Pancharatnam–Berry
    /// metalens, the idealized chromatic metalens): one focusing order, `f ∝ 1/λ`,
    /// `W_λ = (λ/2π) φ0 + sag`.
    GeometricPhase,
    /// A kinoform wrapped every `2π p` at λ0 (a height profile without material dispersion): the
    /// orders `m ≥ 1` with `|m − pλ0/λ| ≤ 3` carry `τ_m = τ sinc²(pλ0/λ − m)` and the phase
    /// `(m/p) φ0` (the harmonic family generalized to any profile; `p = 1` is the ordinary
    /// diffractive lens).
    Diffractive {
        /// The design order `p` (1 to 1000).
        design_order: u32,
    },
    /// The optical path is fixed (a refractive surface): `W_λ = (λ0/2π) φ0 g(λ) + sag`, with
    /// `g = (n(λ) − 1)/(n(λ0) − 1)` for a glass, 1 without.
    Refractive {
        /// The glass whose dispersion scales the path, if any.
        glass: Option<Sellmeier>,
    },
}

impl Dispersion {
    /// The name used in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            Dispersion::GeometricPhase => "geometric-phase",
            Dispersion::Diffractive { .. } => "diffractive",
            Dispersion::Refractive { .. } => "refractive",
        }
    }

    /// How a lens's description names it: the design order of a diffractive lens, the glass of
    /// a refractive one.
    pub(crate) fn describe(&self) -> String {
        match self {
            Dispersion::Diffractive { design_order } => format!("diffractive, design order p = {design_order}"),
            Dispersion::Refractive { glass: Some(_) } => "refractive, glass dispersion".to_string(),
            other => other.name().to_string(),
        }
    }
}

/// A lens given by its phase `φ0(ρ)` at the design wavelength (radians, `ρ = r/R` with `R` the
/// aperture radius `f0/(2F#)`), its wavelength behaviour ([`Dispersion`]), an optional field
/// amplitude profile, and its efficiency τ(λ) and transmission T(λ) (fractions of the light on
/// the aperture; the profile carries the shape of the pupil field, not its power).
///
/// Wavefront (docs/physics.md, "Designs given as data"; the sign of [`optics::Wavefront`]): the
/// detector at `z = f0`, the field after the lens `A(ρ) exp(i φ_λ(ρ))` on an on-axis plane wave,
/// and `W_λ(ρ) = (λ/2π) φ_λ(ρ) + (√(R²ρ² + z²) − z)` against the **exact** reference sphere. The
/// hyperbolic profile `φ0 = −(2π/λ0)(√(r² + f0²) − f0)` is diffraction-limited at λ0; the
/// quadratic one carries spherical aberration. Each order goes through
/// [`optics::Pupil::Radial`]: the radial engine on axis, the FFT path off axis, where the
/// oblique wave adds the field's coma, astigmatism and field curvature ([`Oblique`]: the
/// aperture is the stop, so the chief ray crosses the lens centre undeviated).
#[derive(Clone, Debug)]
pub struct PhaseLens {
    f_number: f64,
    focal_length: f64,
    design_wavelength: f64,
    /// the phase at λ0 as a sum of profiles (a Binary 2 polynomial or a table, and a spline)
    phase: Vec<Arc<RadialProfile>>,
    amplitude: Option<Arc<RadialProfile>>,
    sphere: Arc<RadialProfile>,
    dispersion: Dispersion,
    efficiency: Curve,
    transmission: Curve,
    zernike_noll_m: Vec<(usize, f64)>,
    /// the phase at λ0 per unit of each Binary 2 coefficient: `M (R/R_norm)^{2j}` on `q^j`
    /// (`j = 1, 2, …`), empty without Binary 2 coefficients
    binary2_terms: Vec<f64>,
    /// the number of knots of the freeform spline (`lens.phase_spline_rad`), whose cardinal
    /// basis functions are the gradient's directions after the Binary 2 ones; 0 without a spline
    spline_knots: usize,
    /// the wavefront (m) per µm RMS of each `m = 0` Zernike term the gradient follows (Noll
    /// 1, 4, 11, … up to the scene's list), after the spline's directions
    zernike_directions: Vec<RadialProfile>,
    /// the phase's change at λ0 (radians, in `ρ`) per unit `ln R` of the aperture radius, the
    /// focal length held (`R ∂φ0/∂R`: the parts given in `r`, a Binary 2 polynomial with its own
    /// `R_norm` or a table in `r_mm`, move; those given in `ρ` do not), when the scene recorded
    /// it ([`with_aperture_motion`](PhaseLens::with_aperture_motion)), or why it is not
    aperture_motion: Result<RadialProfile, String>,
    /// how the profile was given, for reports
    source: String,
}

impl PhaseLens {
    /// A phase lens of working F-number `f_number` (≥ 0.5) with the detector at
    /// `focal_length_m`, design wavelength `design_wavelength_m`, phase `phase` (radians at λ0
    /// against `ρ = r/R`), optional field `amplitude` (shape only), `dispersion`, efficiency and
    /// transmission (fractions, τ ≤ T), and `source` (how the profile was given, for reports).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        design_wavelength_m: f64,
        phase: Arc<RadialProfile>,
        amplitude: Option<Arc<RadialProfile>>,
        dispersion: Dispersion,
        efficiency: Curve,
        transmission: Curve,
        source: String,
    ) -> Result<PhaseLens, Error> {
        check_design(f_number, focal_length_m, design_wavelength_m, &dispersion)?;
        check_fraction("efficiency", &efficiency)?;
        check_fraction("transmission", &transmission)?;
        let eff = efficiency.clone();
        check_efficiency_below_transmission(&|l| eff.value(l), &[&efficiency], &transmission, design_wavelength_m)?;
        let radius = 0.5 * focal_length_m / f_number;
        let sphere = Arc::new(RadialProfile::reference_sphere(radius, focal_length_m).map_err(optics_error)?);
        Ok(PhaseLens {
            f_number,
            focal_length: focal_length_m,
            design_wavelength: design_wavelength_m,
            phase: vec![phase],
            amplitude,
            sphere,
            dispersion,
            efficiency,
            transmission,
            zernike_noll_m: Vec::new(),
            binary2_terms: Vec::new(),
            spline_knots: 0,
            zernike_directions: Vec::new(),
            aperture_motion: Err("the lens's phase was not given with its units (r or ρ)".to_owned()),
            source,
        })
    }

    /// This lens with Zernike terms `(Noll index, metres RMS)` added to every order's wavefront
    /// (an alignment or fabrication error on top of the design).
    pub fn with_zernike(mut self, zernike_noll_m: Vec<(usize, f64)>) -> Result<PhaseLens, Error> {
        RadialPupil::new(None, vec![], zernike_noll_m.clone()).map_err(optics_error)?;
        self.zernike_noll_m = zernike_noll_m;
        Ok(self)
    }

    /// This lens with `profile` (radians at λ0 against `ρ = r/R`, as the phase of
    /// [`PhaseLens::new`]) added to its phase, `what` added to how the profile was given: a
    /// freeform spline ([`spline_profile`]) on top of a Binary 2 polynomial or a table.
    pub fn with_added_phase(mut self, profile: Arc<RadialProfile>, what: &str) -> PhaseLens {
        self.phase.push(profile);
        self.source = format!("{} + {what}", self.source);
        self
    }

    /// This lens with its phase's Binary 2 structure recorded: `terms[j]` is the phase at λ0
    /// (radians) per unit of the coefficient `A_{j+1}`, on `q^{j+1}` (`M (R/R_norm)^{2(j+1)}`, as
    /// [`binary2_profile`] forms it), so that [`LensModel::binary2_directions`] gives the
    /// wavefront's change per coefficient.
    pub fn with_binary2_terms(mut self, terms: Vec<f64>) -> PhaseLens {
        self.binary2_terms = terms;
        self
    }

    /// This lens with the freeform spline of `knots` knots ([`spline_profile`]) recorded, so
    /// that [`LensModel::binary2_directions`] gives, after the Binary 2 coefficients', the
    /// wavefront's change per radian of each knot: the profile is linear in the knots, so the
    /// direction of knot `i` is the same spline through the unit vector `e_i` (its cardinal
    /// basis function), times the order's path per radian.
    pub fn with_spline_knots(mut self, knots: usize) -> PhaseLens {
        self.spline_knots = knots;
        self
    }

    /// This lens with the `m = 0` Zernike terms of a list of `terms` coefficients (Noll 1 to
    /// `terms`, µm RMS: `lens.zernike_noll_rms_um`) recorded as directions of
    /// [`LensModel::binary2_directions`], after the spline's: each term adds `c √(n+1) R_n^0(ρ)`
    /// metres to every order's wavefront (Noll 1976), so its direction per µm is
    /// `1e-6 √(n+1) R_n^0`, the same for every order and wavelength.
    pub fn with_zernike_directions(mut self, terms: usize) -> PhaseLens {
        self.zernike_directions = zernike_directions(terms);
        self
    }

    /// This lens with the phase's change with the aperture radius recorded: `motion` is
    /// `R ∂φ0/∂R` at λ0 (radians, in `ρ`; the focal length held), so that
    /// [`LensModel::aperture_directions`] gives each order's `[P, T, S]`
    /// (`P = path per radian × motion`). A profile given in `ρ` (a spline, a Binary 2
    /// polynomial normalized to the aperture itself) does not move: zero. `Err(why)` where
    /// something the directions do not follow moves with `R` (a table's amplitude column in
    /// `r_mm`).
    pub fn with_aperture_motion(mut self, motion: Result<RadialProfile, String>) -> PhaseLens {
        self.aperture_motion = motion;
        self
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "phase"
    }

    /// The dispersion model.
    pub fn dispersion(&self) -> &Dispersion {
        &self.dispersion
    }

    /// The aperture radius `R = f0/(2F#)`, m.
    pub fn aperture_radius(&self) -> f64 {
        0.5 * self.focal_length / self.f_number
    }

    /// The phase at λ0 (radians) at normalized radius `rho`.
    pub fn phase_at(&self, rho: f64) -> f64 {
        self.phase.iter().map(|p| p.value(rho * rho)).sum()
    }

    /// `(m, efficiency, metres of path per radian of φ0)` of each order at `wavelength_m`.
    fn order_list(&self, wavelength_m: f64) -> Vec<(i64, f64, f64)> {
        order_list(&self.dispersion, self.design_wavelength, self.efficiency.value(wavelength_m), wavelength_m)
    }

    /// The pupil of one order: the phase term scaled to metres, the reference sphere, the
    /// amplitude, the Zernike terms, and off axis the oblique incidence.
    fn pupil(&self, path_per_radian: f64, field: Field) -> RadialPupil {
        let mut terms: Vec<(f64, Arc<RadialProfile>)> =
            self.phase.iter().map(|p| (path_per_radian, p.clone())).collect();
        terms.push((1.0, self.sphere.clone()));
        // validated at construction: the terms are finite, the Zernike indices in range
        let pupil = RadialPupil::new(self.amplitude.clone(), terms, self.zernike_noll_m.clone()).unwrap_or_default();
        if field.is_on_axis() {
            return pupil;
        }
        match Oblique::new(self.aperture_radius(), self.focal_length, field.x_rad, field.y_rad) {
            Ok(o) => pupil.with_oblique(o),
            Err(_) => pupil,
        }
    }
}

/// `(m, efficiency, metres of path per radian of φ0)` of each order at `wavelength_m` of a phase
/// given at `design_wavelength` with `dispersion` and efficiency `tau` there (docs/physics.md,
/// "Designs given as data").
pub(crate) fn order_list(
    dispersion: &Dispersion,
    design_wavelength: f64,
    tau: f64,
    wavelength_m: f64,
) -> Vec<(i64, f64, f64)> {
    let per_radian = wavelength_m / std::f64::consts::TAU;
    match dispersion {
        Dispersion::GeometricPhase => vec![(1, tau, per_radian)],
        Dispersion::Refractive { glass } => {
            let g = glass.as_ref().map_or(1.0, |g| {
                let n0 = g.index(design_wavelength).unwrap_or(1.5);
                g.index(wavelength_m).map_or(1.0, |n| (n - 1.0) / (n0 - 1.0))
            });
            vec![(1, tau, design_wavelength / std::f64::consts::TAU * g)]
        }
        Dispersion::Diffractive { design_order } => {
            let p = f64::from(*design_order);
            let alpha = p * design_wavelength / wavelength_m;
            let lo = (alpha - HARMONIC_ORDER_REACH).ceil().max(1.0);
            let hi = (alpha + HARMONIC_ORDER_REACH).floor();
            let mut out = Vec::new();
            let mut m = lo;
            while m <= hi {
                out.push((m as i64, tau * sinc(alpha - m).powi(2), per_radian * m / p));
                m += 1.0;
            }
            out
        }
    }
}

pub(crate) fn optics_error(e: optics::Error) -> Error {
    Error::Pupil(e)
}

impl LensModel for PhaseLens {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        self.order_list(wavelength_m)
            .into_iter()
            .map(|(_, efficiency, per_radian)| {
                Order::radial(efficiency, Arc::new(self.pupil(per_radian, field)), Wavefront::default())
            })
            .collect()
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.transmission.value(wavelength_m)
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.design_wavelength)
    }

    /// A geometric phase: each order's path is `λ/2π` per radian of the profile (given in
    /// radians), its sphere and Zernike terms in metres, its efficiency and transmission curves
    /// in λ: λ0 enters none of them (only the checks at construction and the reports).
    fn design_wavelength_inert(&self) -> bool {
        matches!(self.dispersion, Dispersion::GeometricPhase)
    }

    /// Per order, the path per radian of φ0 times each coefficient's phase term: the order's
    /// wavefront is `path_per_radian · φ0(q)` (plus the sphere and the Zernike terms, which do
    /// not move), so `∂W/∂A_j = path_per_radian · M (R/R_norm)^{2j} q^j` (docs/physics.md,
    /// "Gradients": geometric phase `λ/2π`, refractive `λ0/2π` times the glass factor,
    /// diffractive `(m/p) λ/2π`).
    ///
    /// After them, each spline knot's (`path_per_radian` times the spline's cardinal basis
    /// function, [`with_spline_knots`](PhaseLens::with_spline_knots)), then each `m = 0` Zernike
    /// term's ([`with_zernike_directions`](PhaseLens::with_zernike_directions)).
    fn binary2_directions(&self, wavelength_m: f64) -> Option<Vec<Vec<RadialProfile>>> {
        let lanes = self.binary2_terms.len() + self.spline_knots + self.zernike_directions.len();
        if lanes == 0 {
            return None;
        }
        let orders = self.order_list(wavelength_m);
        let mut out = Vec::with_capacity(orders.len());
        for (_, _, per_radian) in orders {
            let mut order = Vec::with_capacity(lanes);
            for (j, &term) in self.binary2_terms.iter().enumerate() {
                let mut poly = vec![0.0; j + 2];
                poly[j + 1] = per_radian * term;
                order.push(RadialProfile::even_polynomial(poly).ok()?);
            }
            let mut unit = vec![0.0; self.spline_knots];
            for i in 0..self.spline_knots {
                unit[i] = per_radian;
                order.push(spline_profile(&unit).ok()?);
                unit[i] = 0.0;
            }
            order.extend(self.zernike_directions.iter().cloned());
            out.push(order);
        }
        Some(out)
    }

    /// Per order `[P, T, S]` ([`LensModel::aperture_directions`]): `P` the path per radian
    /// times the recorded motion of the phase (`R ∂φ0/∂R`,
    /// [`with_aperture_motion`](PhaseLens::with_aperture_motion)), `T = R ∂S/∂R` and `S` of the
    /// exact reference sphere `S = √(R²q + f0²) − f0` (the Zernike terms, given in `ρ`, do not
    /// move). On axis: off axis the oblique wave moves with `R` too.
    fn aperture_directions(&self, wavelength_m: f64) -> Option<optics::ApertureDirections> {
        let motion = match &self.aperture_motion {
            Ok(m) => m,
            Err(why) => return Some(Err(why.clone())),
        };
        let sphere_slope = self.sphere.radius_log_derivative()?;
        let mut out = Vec::new();
        for (_, _, per_radian) in self.order_list(wavelength_m) {
            out.push([motion.scaled(per_radian)?, sphere_slope.clone(), (*self.sphere).clone()]);
        }
        Some(Ok(out))
    }

    /// The wavefront's rate `δW = ∂W/∂λ − W/λ` ([`LensModel::wavelength_directions`]) of
    /// `W_λ = a(λ) φ0 + S + Z` (a the path per radian, S the exact reference sphere, Z the
    /// `m = 0` Zernike terms, both fixed in metres): `δW = (a′ − a/λ) φ0 − (S + Z)/λ`. For a
    /// geometric phase `a = λ/2π`, so `a′ − a/λ = 0` (the radian phase is the same at every
    /// wavelength: only the sphere's and the Zernike terms' phase `2π(S + Z)/λ` turns); for a
    /// refractive profile `a = (λ0/2π) g(λ)`, `g = (n − 1)/(n0 − 1)` (1 without a glass), so
    /// `a′ − a/λ = (λ0/2π)(n′/(n0 − 1) − g/λ)`. As lanes: each part of φ0, the sphere and each
    /// Zernike term, with their coefficients. Refused for the diffractive dispersion (its
    /// orders' efficiencies `τ sinc²(pλ0/λ − m)` move with λ against each other), an
    /// efficiency or transmission table (its slope is not followed), and a Zernike term with
    /// `m ≠ 0` (not on the radial engine).
    fn wavelength_directions(&self, wavelength_m: f64) -> Option<optics::WavelengthDirections> {
        let l = wavelength_m;
        if !matches!((&self.efficiency, &self.transmission), (Curve::Constant(_), Curve::Constant(_))) {
            return Some(Err(
                "lens.efficiency or lens.transmission is a table, whose slope in λ is not followed".to_owned()
            ));
        }
        let phase = match &self.dispersion {
            Dispersion::GeometricPhase => 0.0,
            Dispersion::Refractive { glass } => {
                let g = glass.as_ref().map_or(Some((1.0, 0.0)), |g| {
                    let n0 = g.index(self.design_wavelength)?;
                    Some(((g.index(l)? - 1.0) / (n0 - 1.0), g.index_derivative(l)? / (n0 - 1.0)))
                });
                let Some((g, g_slope)) = g else {
                    return Some(Err(format!("{:.3} nm is outside the glass's stated range", l * 1e9)));
                };
                self.design_wavelength / std::f64::consts::TAU * (g_slope - g / l)
            }
            Dispersion::Diffractive { .. } => {
                return Some(Err(
                    "lens.dispersion = \"diffractive\": its orders' efficiencies τ sinc²(pλ0/λ − m) move with λ against \
                     each other, whose derivative is not followed yet"
                        .to_owned(),
                ));
            }
        };
        let mut coefficients = Vec::new();
        let mut profiles = Vec::new();
        if phase != 0.0 {
            for p in &self.phase {
                coefficients.push(phase);
                profiles.push((**p).clone());
            }
        }
        coefficients.push(-1.0 / l);
        profiles.push((*self.sphere).clone());
        for &(j, c) in &self.zernike_noll_m {
            let (n, m) = optics::fft::noll_to_nm(j);
            if m != 0 {
                return Some(Err(format!("the Zernike term Noll {j} (m = {m}) takes the pupil off the radial engine")));
            }
            coefficients.push(-1.0 / l);
            profiles.push(optics::radial::zernike_radial_profile(n, c));
        }
        // one order: every dispersion but the diffractive one
        let orders = self.order_list(l).len();
        Some(Ok((coefficients, vec![profiles; orders])))
    }

    /// An efficiency or transmission table factored out (`crate::chromatic::factor_one_curve`).
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        crate::chromatic::factor_one_curve(&self.efficiency, &self.transmission, 1.0, |efficiency, transmission| {
            std::sync::Arc::new(PhaseLens { efficiency, transmission, ..self.clone() })
        })
    }

    fn breakpoints(&self) -> Vec<f64> {
        curve_breakpoints(&self.efficiency, &self.transmission, [])
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        let dispersion = self.dispersion.describe();
        let zernike: String = self.zernike_noll_m.iter().map(|(j, c)| format!(", Z{j} = {} µm", r(c * 1e6))).collect();
        format!(
            "phase-profile lens F/{} f0 = {} mm at λ0 = {} nm ({}; {dispersion}{zernike}), against the exact reference sphere",
            r(self.f_number),
            r(self.focal_length * 1e3),
            r(self.design_wavelength * 1e9),
            self.source,
        )
    }
}

/// The hyperbolic phase `φ0(r) = −(2π/λ0)(√(r² + f0²) − f0)` as Zemax Binary 2 coefficients
/// `A_1 … A_terms` (radians, `ρ = r/R_norm`): the Taylor series of the hyperbola in `r²`,
/// `A_i = −(2π/λ0) C(1/2, i) R_norm^{2i} / f0^{2i−1}` (docs/physics.md: four terms reach it to
/// ~1e-11 m at the paper's aperture).
pub fn hyperbolic_binary2(focal_length_m: f64, design_wavelength_m: f64, norm_radius_m: f64, terms: usize) -> Vec<f64> {
    let k = std::f64::consts::TAU / design_wavelength_m;
    let mut out = Vec::with_capacity(terms);
    // √(f² + r²) − f = f Σ_{i≥1} C(1/2, i) (r²/f²)^i
    let mut binom = 1.0; // C(1/2, 0)
    for i in 1..=terms {
        let fi = i as f64;
        binom *= (0.5 - (fi - 1.0)) / fi;
        out.push(-k * binom * norm_radius_m.powi(2 * i as i32) / focal_length_m.powi(2 * i as i32 - 1));
    }
    out
}

/// A Zemax Binary 2 phase `M Σ_i A_i (r/R_norm)^{2i}` as a profile in `ρ = r/R` of the aperture
/// radius `aperture_radius_m`: `coefficients[i] = M A_i (R/R_norm)^{2i}`.
pub fn binary2_profile(
    coefficients: &[f64],
    diffraction_order: f64,
    norm_radius_m: f64,
    aperture_radius_m: f64,
) -> Result<RadialProfile, Error> {
    check("norm_radius", norm_radius_m, norm_radius_m > 0.0, "a finite length > 0 m")?;
    check("diffraction_order", diffraction_order, diffraction_order != 0.0, "a finite, non-zero number")?;
    let scale = (aperture_radius_m / norm_radius_m).powi(2);
    let mut poly = vec![0.0];
    let mut power = 1.0;
    for &a in coefficients {
        power *= scale;
        poly.push(diffraction_order * a * power);
    }
    RadialProfile::even_polynomial(poly).map_err(optics_error)
}

/// The fewest knots of a [`spline_profile`]: the axis, one inside the aperture, the edge.
pub const SPLINE_MIN_KNOTS: usize = 3;

/// The most knots of a [`spline_profile`] (a freeform profile for a gradient search has tens).
pub const SPLINE_MAX_KNOTS: usize = 1024;

/// A freeform phase profile (`lens.phase_spline_rad`, docs/physics.md, "Designs given as data"):
/// `knots_rad[i]` is the phase (radians at λ0) at `ρ_i = i/N`, `N + 1` knots equally spaced from
/// the axis to the aperture's edge, read through the cubic spline of a phase table
/// ([`RadialProfile::table`]: zero slope on the axis, as a radially symmetric profile has, and
/// zero curvature at the edge, the natural end). At least [`SPLINE_MIN_KNOTS`], at most
/// [`SPLINE_MAX_KNOTS`], every one finite.
///
/// The profile is linear in the knots (a spline's values solve a linear system whose right-hand
/// side is the data): the profile of `knots` is `Σ knots[i] b_i(ρ)` with `b_i` the spline
/// through the unit vector `e_i`, so a knot's derivative is the profile of `e_i`.
///
/// [`RadialProfile::table`] takes four knots or more; three (`ρ = 0, ½, 1`) are given to it with
/// a fourth at `ρ = ¾` on the same spline, its value from the spline's two-piece solution (a
/// spline stays the same spline when a knot is added on it: the added knot carries no jump).
pub fn spline_profile(knots_rad: &[f64]) -> Result<RadialProfile, Error> {
    let n = knots_rad.len();
    check(
        "phase_spline_rad knots",
        n as f64,
        (SPLINE_MIN_KNOTS..=SPLINE_MAX_KNOTS).contains(&n),
        "3 to 1024 knots (the phase at equally spaced radii from the axis to the edge)",
    )?;
    for &v in knots_rad {
        check("phase_spline_rad", v, true, "a finite phase in radians")?;
    }
    let (rho, values) = if n == 3 {
        let [y0, y1, y2] = [knots_rad[0], knots_rad[1], knots_rad[2]];
        // knots 0, h, 2h (h = ½), second derivatives m0, m1, m2 = 0 (natural end):
        // zero slope at 0:  (h/3) m0 + (h/6) m1 = (y1 − y0)/h
        // C² at h:          (h/6) m0 + (2h/3) m1 = (y2 − 2y1 + y0)/h
        // so m1 = 12 (d1 − d0/2) / (7h); the piece on [h, 2h] at its middle ¾ is
        // (y1 + y2)/2 − m1 h²/16 (the cubic spline's piece at a = b = ½, m2 = 0)
        let h = 0.5;
        let (d0, d1) = ((y1 - y0) / h, (y2 - 2.0 * y1 + y0) / h);
        let m1 = 12.0 * (d1 - 0.5 * d0) / (7.0 * h);
        (vec![0.0, 0.5, 0.75, 1.0], vec![y0, y1, 0.5 * (y1 + y2) - m1 * h * h / 16.0, y2])
    } else {
        let last = (n - 1) as f64;
        ((0..n).map(|i| i as f64 / last).collect(), knots_rad.to_vec())
    };
    RadialProfile::table(rho, values).map_err(optics_error)
}

/// The wavefront (m) per µm RMS of each `m = 0` Zernike term among Noll 1 to `terms`, in Noll
/// order: `1e-6 √(n+1) R_n^0(ρ)` (Noll 1976; [`optics::radial::zernike_radial_profile`]).
pub(crate) fn zernike_directions(terms: usize) -> Vec<RadialProfile> {
    (1..=terms)
        .filter_map(|j| {
            let (n, m) = optics::fft::noll_to_nm(j);
            (m == 0).then(|| optics::radial::zernike_radial_profile(n, 1e-6))
        })
        .collect()
}

/// Any lens with Zernike terms `(Noll index, metres RMS)` added to every order's wavefront: an
/// alignment or fabrication error, or a designer's residual, on top of a family. Orders through
/// the full aperture become [`optics::Pupil::Radial`] pupils carrying the terms (the radial
/// engine where every term has `m = 0` and the order no other Seidel term, the FFT path
/// otherwise); an order through another pupil (an iris, zones, a table) is refused at
/// construction, as the terms are defined over the full aperture.
#[derive(Debug)]
pub struct WithZernike<L> {
    inner: L,
    pupil: Arc<RadialPupil>,
}

impl<L: LensModel> WithZernike<L> {
    /// `inner` with `zernike_noll_m` on every order; refused where an order of `inner` at
    /// `probe_wavelength_m` on axis goes through a pupil other than the full aperture.
    pub fn new(inner: L, zernike_noll_m: Vec<(usize, f64)>, probe_wavelength_m: f64) -> Result<Self, Error> {
        let pupil = Arc::new(RadialPupil::new(None, vec![], zernike_noll_m).map_err(optics_error)?);
        for order in inner.orders(probe_wavelength_m, Field::ON_AXIS) {
            if !matches!(order.pupil, optics::Pupil::Full | optics::Pupil::Radial(_)) {
                return Err(Error::OutOfRange {
                    name: "zernike_noll_rms_um",
                    value: f64::NAN,
                    expected: "a lens whose orders go through the full aperture (Zernike terms are defined over it; not with an iris, zones or a table)",
                });
            }
        }
        Ok(WithZernike { inner, pupil })
    }
}

impl<L: LensModel> LensModel for WithZernike<L> {
    fn f_number(&self) -> f64 {
        self.inner.f_number()
    }

    fn focal_length(&self) -> f64 {
        self.inner.focal_length()
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        self.inner
            .orders(wavelength_m, field)
            .into_iter()
            .map(|order| match &order.pupil {
                optics::Pupil::Full => Order::radial(order.efficiency, self.pupil.clone(), order.wavefront),
                optics::Pupil::Radial(p) => {
                    let own = order.wavefront.defocus_m - p.fitted_defocus_m();
                    match p.with_zernike(self.pupil.zernike_noll_m()) {
                        Ok(merged) => {
                            let mut wavefront = order.wavefront;
                            wavefront.defocus_m = own;
                            Order::radial(order.efficiency, Arc::new(merged), wavefront)
                        }
                        Err(_) => order,
                    }
                }
                _ => order,
            })
            .collect()
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.inner.transmission(wavelength_m)
    }

    /// The inner lens's factoring, each part's relative lens carrying the same terms.
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        let mut factored = self.inner.factored_efficiency()?;
        for part in &mut factored.parts {
            part.relative = Arc::new(WithZernike { inner: part.relative.clone(), pupil: self.pupil.clone() });
        }
        Some(factored)
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.inner.breakpoints()
    }

    fn design_wavelength(&self) -> Option<f64> {
        self.inner.design_wavelength()
    }

    /// The inner lens's band: the terms are on every order's pupil and leave its efficiency,
    /// 0 outside the band, as it is.
    fn design_band(&self) -> Option<(f64, f64)> {
        self.inner.design_band()
    }

    /// The inner lens's rates, order for order: the terms are fixed on the pupil, so the field
    /// moves each order's image shift as it moves the inner lens's (docs/physics.md, "Gradients:
    /// the field point").
    fn image_shift_field_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        self.inner.image_shift_field_rates(wavelength_m, field)
    }

    /// The inner lens's rates: the Zernike terms are given in metres RMS, so the design
    /// wavelength moves each order's own defocus and efficiency alone (the pupil's best-fit
    /// defocus added to `defocus_m` stays).
    fn design_wavelength_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
        self.inner.design_wavelength_rates(wavelength_m, field)
    }

    /// The inner lens's rates in λ: the terms are given in metres, fixed on the pupil, so a
    /// wavelength moves each order's own defocus and efficiency alone (a line's wavelength on
    /// the FFT grids, docs/physics.md, "Gradients: the F-number, the focal length and the
    /// wavelengths under a line on the grids").
    fn defocus_rates(&self, wavelength_m: f64, field: Field) -> Option<optics::DefocusRates> {
        self.inner.defocus_rates(wavelength_m, field)
    }

    /// As [`defocus_rates`](Self::defocus_rates), order for order.
    fn order_wavelength_rates(&self, wavelength_m: f64, field: Field) -> Option<optics::OrderWavelengthRates> {
        self.inner.order_wavelength_rates(wavelength_m, field)
    }

    fn describe(&self) -> String {
        let terms: Vec<String> = self
            .pupil
            .zernike_noll_m()
            .iter()
            .map(|(j, c)| format!("Z{j} = {} µm", optics::round_for_display(c * 1e6)))
            .collect();
        format!("{} + Zernike (Noll, RMS) {}", self.inner.describe(), terms.join(", "))
    }
}

/// The checks a phase lens's design takes, whether its phase is radial or a 2-D map: the
/// F-number (NA ≤ 1), the focal length, the design wavelength (inside the glass's Sellmeier range
/// for a refractive lens on a glass) and a diffractive lens's design order.
pub(crate) fn check_design(
    f_number: f64,
    focal_length_m: f64,
    design_wavelength_m: f64,
    dispersion: &Dispersion,
) -> Result<(), Error> {
    check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
    check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
    check("design_wavelength", design_wavelength_m, design_wavelength_m > 0.0, "a finite wavelength > 0 m")?;
    if let Dispersion::Diffractive { design_order } = *dispersion {
        let p = f64::from(design_order);
        check("design_order", p, (1.0..=1000.0).contains(&p), "a whole number from 1 to 1000")?;
    }
    if let Dispersion::Refractive { glass: Some(g) } = dispersion
        && g.index(design_wavelength_m).is_none()
    {
        return Err(Error::OutOfRange {
            name: "design_wavelength",
            value: design_wavelength_m,
            expected: "inside the glass's Sellmeier range",
        });
    }
    Ok(())
}
