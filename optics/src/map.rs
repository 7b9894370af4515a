//! Pupils given as a 2-D map of cells (docs/physics.md, "Phase maps"): a designer's phase
//! `φ0[y, x]` (radians at the design wavelength λ0) and optional amplitude on a square grid of
//! pitch `p` centred on the axis, each sample held over its cell as a meta-atom is, in a
//! circular or a square aperture. Computed on the FFT path ([`crate::Pupil::Map`]).
//!
//! The field after the lens is `a_c exp(i φ_c)` in cell `c`, constant over the cell. Against the
//! exact reference sphere (the detector at `z`, `S(X) = √(|X|² + z²) − z`, plus the oblique
//! wave's path off axis, [`crate::radial::Oblique`]) the reference's phase turns across the cell
//! by its gradient `g`: the cell is a blazed staircase step whose design-order (zeroth Fourier)
//! component is `a_c sinc(g_x p/λ) sinc(g_y p/λ) exp(i(φ_c + k S(X_c)))` (the cell's mean,
//! `sinc u = sin πu/(πu)`; docs/physics.md, "Designs given as data": the local periodic
//! approximation) and the rest leaves at angles `≥ λ/p` from the design direction, stray light.
//! The pupil field of the design order is that value held over the cell; its OTF is the
//! normalized autocorrelation on the FFT path.

use std::f64::consts::PI;
use std::sync::Arc;

use num_complex::Complex64;

use crate::Error;
use crate::radial::Oblique;

/// The most cells a map may hold (2^26, 0.5 GiB of phase and amplitude as `f64`).
pub const MAP_MAX_CELLS: usize = 1 << 26;

/// The aperture a map is seen through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapAperture {
    /// The circle of radius `R` (diameter `f0/F#`).
    Circle,
    /// The square of side `2R` (the circle's diameter): it collects `4/π` of the circle's light.
    Square,
}

impl MapAperture {
    /// Its area over the circle's `π R²`: 1, or `4/π` for the square.
    pub fn area_fraction(self) -> f64 {
        match self {
            MapAperture::Circle => 1.0,
            MapAperture::Square => 4.0 / PI,
        }
    }

    /// Whether the point `(x, y)` (units of `R`) is inside.
    pub fn contains(self, x: f64, y: f64) -> bool {
        match self {
            MapAperture::Circle => x * x + y * y <= 1.0,
            MapAperture::Square => x.abs() <= 1.0 && y.abs() <= 1.0,
        }
    }
}

/// How the stored phase of a [`PhaseMap`] relates to the map the designer gave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoredPhase {
    /// `φ0` as given (unwrapped: a refractive or diffractive lens scales it with λ).
    Given,
    /// The residual at λ0, `ψ0 = φ0 + k0 S` wrapped to `(−π, π]`: for a radian phase fixed in λ
    /// (geometric phase) `φ0 + k S ≡ ψ0 + (k − k0) S (mod 2π)` at every λ, so a map wrapped
    /// mod 2π is exact, and `ψ0` is smooth where the design focuses.
    Residual,
}

/// A phase map in its aperture: the cells, the pitch, the aperture and the detector distance.
#[derive(Clone, Debug)]
pub struct PhaseMap {
    nx: usize,
    ny: usize,
    pitch: f64,
    radius: f64,
    distance: f64,
    design_wavelength: f64,
    aperture: MapAperture,
    stored: StoredPhase,
    /// The stored phase (radians), C order `[y][x]`, row `j` at `y_j = (j − (ny − 1)/2) p`.
    phase: Vec<f64>,
    amplitude: Option<Vec<f64>>,
    /// Least-squares fits `(c_Φ, c_S)` of the stored phase (radians) and of the sphere `S`
    /// (metres) by `c ρ² + piston` over the aperture's cells (amplitude² weighted).
    fits: (f64, f64),
    /// `Σ a² sinc²` over `Σ a²` inside the aperture at λ0 on axis: the design order's share.
    design_share: f64,
}

/// Where a map fails a check: the cell, its position and the numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// Column and row of the cell (`x` index, `y` index).
    pub index: [usize; 2],
    /// Its centre, metres from the axis.
    pub centre_m: [f64; 2],
    /// The number that failed (a phase step in radians, or the value).
    pub value: f64,
}

fn sinc(u: f64) -> f64 {
    if u.abs() < 1e-8 { 1.0 - (PI * u).powi(2) / 6.0 } else { (PI * u).sin() / (PI * u) }
}

impl PhaseMap {
    /// A map of `nx × ny` cells of `pitch_m` (C order `[y][x]`, row `j` at
    /// `y = (j − (ny − 1)/2) p`, column `i` at `x = (i − (nx − 1)/2) p`), phase `phase` (radians
    /// at `design_wavelength_m`) and optional `amplitude` (≥ 0, shape only), seen through
    /// `aperture` of radius `radius_m` (half the square's side) with the detector at
    /// `distance_m`. `stored` says whether the phase is kept as given or as its residual
    /// against the reference sphere ([`StoredPhase`]).
    ///
    /// # Errors
    /// Sizes that disagree, more than [`MAP_MAX_CELLS`], a non-finite or negative value, a
    /// map that does not cover the aperture ([`Error::InvalidParameter`] with the numbers).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        nx: usize,
        ny: usize,
        pitch_m: f64,
        phase: Vec<f64>,
        amplitude: Option<Vec<f64>>,
        aperture: MapAperture,
        radius_m: f64,
        distance_m: f64,
        design_wavelength_m: f64,
        stored: StoredPhase,
    ) -> Result<PhaseMap, Error> {
        let bad =
            |name: &'static str, value: f64, expected: &'static str| Error::InvalidParameter { name, value, expected };
        if nx < 2 || ny < 2 || nx.saturating_mul(ny) > MAP_MAX_CELLS || phase.len() != nx * ny {
            return Err(bad(
                "phase map size",
                (nx * ny) as f64,
                "at least 2 × 2 cells, at most 2^26, as many values as cells",
            ));
        }
        if amplitude.as_ref().is_some_and(|a| a.len() != phase.len()) {
            return Err(bad(
                "amplitude map size",
                amplitude.as_ref().map_or(0, Vec::len) as f64,
                "the phase map's shape",
            ));
        }
        for (name, v) in [("phase map pitch", pitch_m), ("aperture radius", radius_m), ("focal length", distance_m)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(name, v, "a finite length > 0 m"));
            }
        }
        if !(design_wavelength_m.is_finite() && design_wavelength_m > 0.0) {
            return Err(bad("design wavelength", design_wavelength_m, "a finite wavelength > 0 m"));
        }
        // the map's half extent must reach the aperture's bounding square
        let half = [0.5 * nx as f64 * pitch_m, 0.5 * ny as f64 * pitch_m];
        let short = half[0].min(half[1]);
        if short < radius_m * (1.0 - 1e-12) {
            return Err(bad(
                "phase map half width",
                short,
                "at least the aperture radius (the map must cover the aperture)",
            ));
        }
        let mut map = PhaseMap {
            nx,
            ny,
            pitch: pitch_m,
            radius: radius_m,
            distance: distance_m,
            design_wavelength: design_wavelength_m,
            aperture,
            stored,
            phase,
            amplitude,
            fits: (0.0, 0.0),
            design_share: 1.0,
        };
        if let Some(c) = map.first_cell(|i, j| !map.phase[j * nx + i].is_finite()) {
            return Err(bad(
                "phase map value (NaN or infinite) at a cell inside the aperture",
                c.centre_m[0],
                "finite radians",
            ));
        }
        if let Some(a) = &map.amplitude
            && let Some(c) = map.first_cell(|i, j| !(a[j * nx + i].is_finite() && a[j * nx + i] >= 0.0))
        {
            return Err(bad("amplitude map value inside the aperture", c.value, "finite and ≥ 0"));
        }
        if stored == StoredPhase::Residual {
            let k0 = 2.0 * PI / design_wavelength_m;
            for j in 0..ny {
                for i in 0..nx {
                    let c = map.centre(i, j);
                    let v = map.phase[j * nx + i] + k0 * map.sphere(c[0], c[1]);
                    map.phase[j * nx + i] = v - 2.0 * PI * (v / (2.0 * PI)).round();
                }
            }
        }
        map.fits = map.fit();
        map.design_share = map.share();
        Ok(map)
    }

    /// The centre of cell `(i, j)`, metres.
    pub fn centre(&self, i: usize, j: usize) -> [f64; 2] {
        [(i as f64 - 0.5 * (self.nx as f64 - 1.0)) * self.pitch, (j as f64 - 0.5 * (self.ny as f64 - 1.0)) * self.pitch]
    }

    /// Whether cell `(i, j)` reaches into the aperture (its nearest point inside).
    fn touches(&self, i: usize, j: usize) -> bool {
        let [x, y] = self.centre(i, j);
        let h = 0.5 * self.pitch;
        let near = |c: f64| (c.abs() - h).max(0.0);
        self.aperture.contains(near(x) / self.radius, near(y) / self.radius)
    }

    /// The first cell inside the aperture (row by row) where `fails(i, j)`.
    pub fn first_cell(&self, fails: impl Fn(usize, usize) -> bool) -> Option<Cell> {
        for j in 0..self.ny {
            for i in 0..self.nx {
                if self.touches(i, j) && fails(i, j) {
                    return Some(Cell {
                        index: [i, j],
                        centre_m: self.centre(i, j),
                        value: self.phase[j * self.nx + i],
                    });
                }
            }
        }
        None
    }

    /// The reference sphere's path `√(x² + y² + z²) − z` (m) at `(x, y)` metres.
    fn sphere(&self, x: f64, y: f64) -> f64 {
        let r2 = x * x + y * y;
        r2 / ((r2 + self.distance * self.distance).sqrt() + self.distance)
    }

    /// The largest step of the reference sphere's phase `k0 S` between neighbouring cells inside
    /// the aperture at λ0 and where it is (the focusing phase any map must follow: more than π
    /// a cell aliases it), as `(radians, cell)`.
    pub fn largest_sphere_step(&self) -> (f64, Cell) {
        // largest at the aperture's farthest corner or rim point along x (or y)
        let k0 = 2.0 * PI / self.design_wavelength;
        let mut worst = (0.0, Cell { index: [0, 0], centre_m: [0.0, 0.0], value: 0.0 });
        for j in 0..self.ny {
            for i in 0..self.nx {
                if !self.touches(i, j) {
                    continue;
                }
                let [x, y] = self.centre(i, j);
                let r = (x * x + y * y + self.distance * self.distance).sqrt();
                let step = k0 * self.pitch * x.abs().max(y.abs()) / r;
                if step > worst.0 {
                    worst = (step, Cell { index: [i, j], centre_m: [x, y], value: step });
                }
            }
        }
        worst
    }

    /// The first pair of neighbouring cells inside the aperture whose phases differ by more
    /// than π (an unwrapped map needed by a refractive or diffractive lens, or cells too coarse
    /// for the phase's gradient), the second cell and the step.
    pub fn first_jump(&self) -> Option<Cell> {
        let nx = self.nx;
        for j in 0..self.ny {
            for i in 0..nx {
                if !self.touches(i, j) {
                    continue;
                }
                let here = self.phase[j * nx + i];
                for (ni, nj) in [(i + 1, j), (i, j + 1)] {
                    if ni < nx && nj < self.ny && self.touches(ni, nj) {
                        let step = self.phase[nj * nx + ni] - here;
                        if step.abs() > PI {
                            return Some(Cell { index: [ni, nj], centre_m: self.centre(ni, nj), value: step });
                        }
                    }
                }
            }
        }
        None
    }

    /// Least-squares `c ρ²` fits of the stored phase and of the sphere over the aperture's cells.
    fn fit(&self) -> (f64, f64) {
        let (mut sw, mut sq, mut sqq, mut sp, mut sqp, mut ss, mut sqs) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for j in 0..self.ny {
            for i in 0..self.nx {
                let [x, y] = self.centre(i, j);
                if !self.aperture.contains(x / self.radius, y / self.radius) {
                    continue;
                }
                let w = self.amplitude.as_ref().map_or(1.0, |a| a[j * self.nx + i].powi(2));
                let q = (x * x + y * y) / (self.radius * self.radius);
                let (p, s) = (self.phase[j * self.nx + i], self.sphere(x, y));
                sw += w;
                sq += w * q;
                sqq += w * q * q;
                sp += w * p;
                sqp += w * q * p;
                ss += w * s;
                sqs += w * q * s;
            }
        }
        let var = sqq * sw - sq * sq;
        if var.is_nan() || var <= 0.0 {
            return (0.0, 0.0);
        }
        ((sqp * sw - sq * sp) / var, (sqs * sw - sq * ss) / var)
    }

    /// The design order's share of the light at λ0 on axis: `Σ a² sinc²(g_x p/λ) sinc²(g_y p/λ)
    /// / Σ a²` over the cells inside the aperture.
    fn share(&self) -> f64 {
        let (mut kept, mut all) = (0.0, 0.0);
        for j in 0..self.ny {
            for i in 0..self.nx {
                let [x, y] = self.centre(i, j);
                if !self.aperture.contains(x / self.radius, y / self.radius) {
                    continue;
                }
                let a2 = self.amplitude.as_ref().map_or(1.0, |a| a[j * self.nx + i].powi(2));
                let r = (x * x + y * y + self.distance * self.distance).sqrt();
                let u = self.pitch / self.design_wavelength;
                kept += a2 * (sinc(u * x / r) * sinc(u * y / r)).powi(2);
                all += a2;
            }
        }
        if all > 0.0 { kept / all } else { 1.0 }
    }

    /// The design order's share of the light at λ0 on axis (the staircase of the cells against
    /// the reference sphere; the rest is stray light at angles `≥ λ/p`).
    pub fn design_share(&self) -> f64 {
        self.design_share
    }

    /// The aperture.
    pub fn aperture(&self) -> MapAperture {
        self.aperture
    }

    /// `(nx, ny)`.
    pub fn shape(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// The cell pitch, m.
    pub fn pitch(&self) -> f64 {
        self.pitch
    }

    /// How the phase is stored.
    pub fn stored(&self) -> StoredPhase {
        self.stored
    }

    /// The aperture radius `R` (half the square's side), m.
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

/// One order's view of a [`PhaseMap`]: the wavefront `W = path_per_radian·Φ + sphere_factor·S
/// (+ the oblique wave's path off axis)` with `Φ` the stored phase ([`StoredPhase`]).
#[derive(Clone, Debug)]
pub struct MapPupil {
    map: Arc<PhaseMap>,
    path_per_radian: f64,
    sphere_factor: f64,
    oblique: Option<Oblique>,
}

impl MapPupil {
    /// The order of `map` whose wavefront is `path_per_radian_m · Φ + sphere_factor · S` with
    /// the oblique incidence `oblique` off axis.
    pub fn new(map: Arc<PhaseMap>, path_per_radian_m: f64, sphere_factor: f64, oblique: Option<Oblique>) -> MapPupil {
        MapPupil { map, path_per_radian: path_per_radian_m, sphere_factor, oblique }
    }

    /// The map.
    pub fn map(&self) -> &PhaseMap {
        &self.map
    }

    /// The best-fit defocus `W020` (m) of the order's wavefront on axis (least squares against
    /// `ρ²` over the aperture): sizes the spectral panels and the Fraunhofer check.
    pub fn fitted_defocus_m(&self) -> f64 {
        let (phase, sphere) = self.map.fits;
        self.path_per_radian * phase + self.sphere_factor * sphere
    }

    /// The design-order field on `n × n` samples of `[−1, 1]²` (units of `R`), each sample
    /// times its transmitting area fraction `area` (the circle's edge pixels), at `lambda`, and
    /// its power `Σ |field|²` (the OTF's normalization).
    pub fn field(&self, n: usize, area: &[f64], lambda: f64) -> (Vec<Complex64>, f64) {
        let map = &*self.map;
        let h = 2.0 / n as f64;
        let k = 2.0 * PI / lambda;
        let mut field = vec![Complex64::new(0.0, 0.0); n * n];
        let mut weight = 0.0;
        let offset = [0.5 * map.nx as f64, 0.5 * map.ny as f64];
        for j in 0..n {
            let y = -1.0 + (j as f64 + 0.5) * h;
            for i in 0..n {
                let idx = j * n + i;
                if area[idx] <= 0.0 {
                    continue;
                }
                let x = -1.0 + (i as f64 + 0.5) * h;
                // the cell holding this sample (the map covers the aperture: clamped at its edge)
                let cell = |v: f64, o: f64, len: usize| {
                    ((v * map.radius / map.pitch + o).floor().max(0.0) as usize).min(len - 1)
                };
                let (ci, cj) = (cell(x, offset[0], map.nx), cell(y, offset[1], map.ny));
                let [cx, cy] = map.centre(ci, cj);
                let a = map.amplitude.as_ref().map_or(1.0, |v| v[cj * map.nx + ci]);
                let (ux, uy) = (cx / map.radius, cy / map.radius);
                let oblique = |u: f64, v: f64| self.oblique.map_or(0.0, |o| o.opd_m(u, v));
                // the reference path's gradient across the cell (sphere and oblique wave)
                let r = (cx * cx + cy * cy + map.distance * map.distance).sqrt();
                let d = 0.5 * map.pitch / map.radius;
                let (gx, gy) = match self.oblique {
                    None => (cx / r, cy / r),
                    Some(_) => (
                        cx / r + (oblique(ux + d, uy) - oblique(ux - d, uy)) / map.pitch,
                        cy / r + (oblique(ux, uy + d) - oblique(ux, uy - d)) / map.pitch,
                    ),
                };
                let u = map.pitch / lambda;
                let design = a * sinc(u * gx) * sinc(u * gy);
                let w = self.path_per_radian * map.phase[cj * map.nx + ci]
                    + self.sphere_factor * map.sphere(cx, cy)
                    + oblique(ux, uy);
                let amp = area[idx] * design;
                weight += area[idx] * design * design;
                field[idx] = Complex64::from_polar(amp, k * w);
            }
        }
        (field, weight)
    }
}
