//! A lens given by a 2-D phase map (docs/physics.md, "Phase maps"): a designer's phase
//! `φ0[y, x]` at the design wavelength, each sample held over its cell, in a circular or square
//! aperture, with the dispersion models of [`PhaseLens`](crate::PhaseLens).

use std::sync::Arc;

use optics::map::{MapAperture, MapPupil, PhaseMap, StoredPhase};
use optics::radial::Oblique;
use optics::{Field, LensModel, Order};

use crate::Error;
use crate::chromatic::curve_breakpoints;
use crate::chromatic::{Curve, check, check_efficiency_below_transmission, check_fraction};
use crate::phase::{Dispersion, check_design, order_list};

/// A lens given by a 2-D phase map ([`optics::map::PhaseMap`]): working F-number `f0/D` (`D` the
/// circle's diameter or the square's side), the detector at `f0`, the dispersion, and the
/// efficiency τ(λ) and transmission T(λ) as fractions of the light on the aperture (circle or
/// square). Against the circle of eq. S7 the square collects `4/π` of the light: its orders'
/// efficiencies and its transmission are the given ones times `4/π`
/// ([`optics::Pupil::area_fraction`]).
///
/// Every order goes through [`optics::Pupil::Map`] with the wavefront
/// `W_λ = (path per radian)·φ0 + S` (geometric phase: `(λ/2π) φ0`; refractive: `(λ0/2π) φ0 g`;
/// diffractive order m: `(λ/2π)(m/p) φ0`) against the exact reference sphere `S`; off axis the
/// oblique wave adds its path ([`Oblique`]). With a geometric phase the map may be wrapped
/// (it is held as its residual against the sphere, exact mod 2π).
#[derive(Clone, Debug)]
pub struct PhaseMapLens {
    f_number: f64,
    focal_length: f64,
    design_wavelength: f64,
    map: Arc<PhaseMap>,
    dispersion: Dispersion,
    efficiency: Curve,
    transmission: Curve,
    source: String,
}

impl PhaseMapLens {
    /// A lens of working F-number `f_number` (≥ 0.5) with the detector at `focal_length_m`,
    /// the phase map `map` (built with [`PhaseMapLens::stored_phase`] for `dispersion`, its
    /// aperture radius `f0/(2F#)` and detector distance `f0`), efficiency and transmission
    /// (fractions of the light on the map's aperture, τ ≤ T), and `source` (for reports).
    ///
    /// # Errors
    /// A parameter out of range, or a map built for another aperture, distance or storage.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        design_wavelength_m: f64,
        map: Arc<PhaseMap>,
        dispersion: Dispersion,
        efficiency: Curve,
        transmission: Curve,
        source: String,
    ) -> Result<PhaseMapLens, Error> {
        check_design(f_number, focal_length_m, design_wavelength_m, &dispersion)?;
        let radius = 0.5 * focal_length_m / f_number;
        check(
            "phase map aperture radius",
            map.radius(),
            (map.radius() - radius).abs() <= 1e-12 * radius,
            "the lens's aperture radius f0/(2F#)",
        )?;
        if map.stored() != Self::stored_phase(&dispersion) {
            return Err(Error::OutOfRange {
                name: "phase map storage",
                value: f64::NAN,
                expected: "the residual against the sphere for a geometric phase, the phase as given otherwise",
            });
        }
        check_fraction("efficiency", &efficiency)?;
        check_fraction("transmission", &transmission)?;
        let eff = efficiency.clone();
        check_efficiency_below_transmission(&|l| eff.value(l), &[&efficiency], &transmission, design_wavelength_m)?;
        Ok(PhaseMapLens {
            f_number,
            focal_length: focal_length_m,
            design_wavelength: design_wavelength_m,
            map,
            dispersion,
            efficiency,
            transmission,
            source,
        })
    }

    /// How a map must be stored for `dispersion`: its residual against the reference sphere for
    /// a geometric phase (a wrapped map is then exact), as given otherwise.
    pub fn stored_phase(dispersion: &Dispersion) -> StoredPhase {
        match dispersion {
            Dispersion::GeometricPhase => StoredPhase::Residual,
            _ => StoredPhase::Given,
        }
    }

    /// The hyperbolic design `−k0 (√(x² + y² + f0²) − f0)` (`k0 = 2π/λ0`, aberration-free at
    /// λ0 on axis) plus `extra(x, y)` (radians), sampled at the centres of `n × n` cells of
    /// `pitch_m` centred on the axis, stored for a geometric phase ([`stored_phase`](Self::stored_phase)):
    /// the map a designer exports from a hyperbolic metalens, and the one the phase-map tests and
    /// the benchmark compare with the same hyperbola on the radial engine.
    pub fn sampled_hyperbola(
        n: usize,
        pitch_m: f64,
        aperture: MapAperture,
        radius_m: f64,
        f0_m: f64,
        lambda0_m: f64,
        extra: impl Fn(f64, f64) -> f64,
    ) -> Result<PhaseMap, optics::Error> {
        let stored = Self::stored_phase(&Dispersion::GeometricPhase);
        if n.saturating_mul(n) > optics::map::MAP_MAX_CELLS {
            // refused by the map's own size check, before any sample is computed
            return PhaseMap::new(n, n, pitch_m, Vec::new(), None, aperture, radius_m, f0_m, lambda0_m, stored);
        }
        let k0 = 2.0 * std::f64::consts::PI / lambda0_m;
        let centre = 0.5 * (n as f64 - 1.0);
        let mut phase = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                let (x, y) = ((i as f64 - centre) * pitch_m, (j as f64 - centre) * pitch_m);
                phase.push(-k0 * ((x * x + y * y + f0_m * f0_m).sqrt() - f0_m) + extra(x, y));
            }
        }
        PhaseMap::new(n, n, pitch_m, phase, None, aperture, radius_m, f0_m, lambda0_m, stored)
    }

    /// The phase map.
    pub fn map(&self) -> &PhaseMap {
        &self.map
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "phase"
    }

    /// The aperture radius `R = f0/(2F#)` (half the square's side), m.
    pub fn aperture_radius(&self) -> f64 {
        0.5 * self.focal_length / self.f_number
    }
}

impl LensModel for PhaseMapLens {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        let area = self.map.aperture().area_fraction();
        let oblique = if field.is_on_axis() {
            None
        } else {
            Oblique::new(self.aperture_radius(), self.focal_length, field.x_rad, field.y_rad).ok()
        };
        // a geometric phase is held as its residual ψ0 = φ0 + k0 S: W = (λ/2π) ψ0 + (1 − λ/λ0) S
        let sphere = match self.dispersion {
            Dispersion::GeometricPhase => 1.0 - wavelength_m / self.design_wavelength,
            _ => 1.0,
        };
        order_list(&self.dispersion, self.design_wavelength, self.efficiency.value(wavelength_m), wavelength_m)
            .into_iter()
            .map(|(_, efficiency, per_radian)| {
                Order::map(area * efficiency, Arc::new(MapPupil::new(self.map.clone(), per_radian, sphere, oblique)))
            })
            .collect()
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.map.aperture().area_fraction() * self.transmission.value(wavelength_m)
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.design_wavelength)
    }

    fn breakpoints(&self) -> Vec<f64> {
        curve_breakpoints(&self.efficiency, &self.transmission, [])
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        let dispersion = self.dispersion.describe();
        let (nx, ny) = self.map.shape();
        let aperture = match self.map.aperture() {
            MapAperture::Circle => "circular aperture",
            MapAperture::Square => "square aperture (4/π of the circle's light)",
        };
        format!(
            "phase-map lens F/{} f0 = {} mm at λ0 = {} nm ({}: {nx} × {ny} cells of {} µm, {aperture}; {dispersion}; \
             the cells' staircase keeps {:.2} % of the light in the design order), against the exact reference sphere",
            r(self.f_number),
            r(self.focal_length * 1e3),
            r(self.design_wavelength * 1e9),
            self.source,
            r(self.map.pitch() * 1e6),
            100.0 * self.map.design_share(),
        )
    }
}
