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

use num_complex::{Complex32, Complex64};

use crate::Error;
use crate::radial::Oblique;

/// Nanoseconds spent building pupil fields from maps and layouts ([`MapPupil::field`]), summed
/// over every thread since the process started.
static FIELD_NANOS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// The time spent building pupil fields from maps and layouts ([`MapPupil::field`]: the cells
/// or sites resampled to the pupil grid at a wavelength), summed over every thread since the
/// process started: a timing accumulator for benchmarks, which read it before and after an
/// evaluation to split the field's share from the OTFs' (it does not touch any value).
pub fn field_build_time() -> std::time::Duration {
    std::time::Duration::from_nanos(FIELD_NANOS.load(std::sync::atomic::Ordering::Relaxed))
}

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

/// Weighted least-squares fits `c ρ²` (with a constant) of a phase `p` and of the sphere's path `s`
/// against `q = ρ²`: the sums the phase map's and the site map's fits accumulate cell by cell.
#[derive(Default)]
struct RhoSquaredFit {
    sw: f64,
    sq: f64,
    sqq: f64,
    sp: f64,
    sqp: f64,
    ss: f64,
    sqs: f64,
}

impl RhoSquaredFit {
    /// One cell of weight `w` at `q = ρ²` with phase `p` and sphere path `s`.
    fn add(&mut self, w: f64, q: f64, p: f64, s: f64) {
        self.sw += w;
        self.sq += w * q;
        self.sqq += w * q * q;
        self.sp += w * p;
        self.sqp += w * q * p;
        self.ss += w * s;
        self.sqs += w * q * s;
    }

    /// The slopes `(c_p, c_s)`; `(0, 0)` where the cells do not determine them.
    fn solve(&self) -> (f64, f64) {
        let var = self.sqq * self.sw - self.sq * self.sq;
        if var.is_nan() || var <= 0.0 {
            return (0.0, 0.0);
        }
        ((self.sqp * self.sw - self.sq * self.sp) / var, (self.sqs * self.sw - self.sq * self.ss) / var)
    }
}
/// The reference sphere's path `√(x² + y² + z²) − z` (m) at `(x, y)` metres, `z` the focal
/// distance (written so that it keeps its digits near the axis).
fn sphere_path(x: f64, y: f64, z: f64) -> f64 {
    let r2 = x * x + y * y;
    r2 / ((r2 + z * z).sqrt() + z)
}

/// A map of `nx × ny` cells of `pitch_m` must reach the aperture's bounding square: its shorter
/// half extent (`name` in the error) at least the aperture radius.
fn covers(name: &'static str, nx: usize, ny: usize, pitch_m: f64, radius_m: f64) -> Result<(), Error> {
    let short = 0.5 * nx.min(ny) as f64 * pitch_m;
    if short < radius_m * (1.0 - 1e-12) {
        return Err(Error::InvalidParameter {
            name,
            value: short,
            expected: "at least the aperture radius (the map must cover the aperture)",
        });
    }
    Ok(())
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

/// A length of a designer's map that [`MapPupil::scale_derivative`] moves, per relative change,
/// the other two held (docs/physics.md, "Gradients: a phase map's pitch and aperture").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MapScale {
    /// The cell pitch `p`: the cells' edges move across the pupil (units of `R`) with
    /// `ρ = p/R`, and each cell's centre `X_c ∝ p` with its reference sphere and share.
    Pitch,
    /// The aperture radius `R`: the cells' edges move with `ρ = p/R`, against the pitch's.
    Radius,
    /// The detector distance `z` (the focal length): each cell's reference sphere and share.
    Distance,
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
        covers("phase map half width", nx, ny, pitch_m, radius_m)?;
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
        sphere_path(x, y, self.distance)
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
        let mut fit = RhoSquaredFit::default();
        for j in 0..self.ny {
            for i in 0..self.nx {
                let [x, y] = self.centre(i, j);
                if !self.aperture.contains(x / self.radius, y / self.radius) {
                    continue;
                }
                let w = self.amplitude.as_ref().map_or(1.0, |a| a[j * self.nx + i].powi(2));
                let q = (x * x + y * y) / (self.radius * self.radius);
                let (p, s) = (self.phase[j * self.nx + i], self.sphere(x, y));
                fit.add(w, q, p, s);
            }
        }
        fit.solve()
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

/// A lattice of sites, each holding one of a few atoms (a meta-atom layout; docs/physics.md,
/// "2-D library layouts" and "Resampling a layout to the pupil grid"): `nx × ny` cells of
/// `pitch` centred on the axis as a [`PhaseMap`]'s, site `c` holding atom `u(c)` of a table the
/// lens gives per wavelength (`t_u(λ)`, its complex transmission), and a fixed phase factor
/// `e^{i(k0 S(X_c) + γ_c)}` (the reference sphere at λ0 and a geometric phase `γ_c`). The site's
/// field against the reference sphere at λ is `t_{u(c)}(λ) e^{i(k0 S(X_c) + γ_c)}` times the
/// chromatic defocus `e^{ik(1 − λ/λ0) S(X_c)}` (and the oblique wave off axis): a pass over the
/// sites is a gather from the atoms' table, not a new map per wavelength.
#[derive(Clone, Debug)]
pub struct SiteMap {
    nx: usize,
    ny: usize,
    pitch: f64,
    radius: f64,
    distance: f64,
    design_wavelength: f64,
    /// each cell's atom, `[y][x]`
    atoms: Vec<u32>,
    /// the atoms in the table (`atoms[c] < table`)
    table: usize,
    /// each cell's `e^{i(k0 S(X_c) + γ_c)}`
    reference: Vec<Complex32>,
    /// the cells inside the aperture (centre in the circle) per block of [`BLOCK`]² cells: per
    /// block `table` counts (row-major blocks, atom fastest) and the block's centroid (m)
    block_counts: Vec<u32>,
    block_centroid: Vec<[f64; 2]>,
}

/// The side, in cells, of the blocks over which [`SiteMap::powers`] holds the cells' design-order
/// share constant (docs/physics.md: its error is below 1e-6 of τ1).
const BLOCK: usize = 16;

/// The most cells the per-wavelength fit of [`MapPupil::fitted_defocus_m`] visits on a site map
/// (every `s`-th row and column beyond it: the fit sizes panels, it is not the value).
const FIT_CELLS: usize = 1 << 16;

impl SiteMap {
    /// A site map of `nx × ny` cells of `pitch_m` (`[y][x]`, centred as a [`PhaseMap`]'s), cell
    /// `c` holding atom `atoms[c]` of a table of `table` atoms and the geometric phase
    /// `geometric[c]` (radians; none: 0), in the circle of radius `radius_m` with the detector at
    /// `distance_m`, designed at `design_wavelength_m`.
    ///
    /// # Errors
    /// Sizes that disagree, fewer than 2 × 2 or more than [`MAP_MAX_CELLS`] cells, an atom index
    /// past the table, a map that does not cover the aperture, a non-finite length or phase.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        nx: usize,
        ny: usize,
        pitch_m: f64,
        atoms: Vec<u32>,
        table: usize,
        geometric: Option<&[f64]>,
        radius_m: f64,
        distance_m: f64,
        design_wavelength_m: f64,
    ) -> Result<SiteMap, Error> {
        let bad =
            |name: &'static str, value: f64, expected: &'static str| Error::InvalidParameter { name, value, expected };
        if nx < 2 || ny < 2 || nx.saturating_mul(ny) > MAP_MAX_CELLS || atoms.len() != nx * ny {
            return Err(bad("site map size", (nx * ny) as f64, "at least 2 × 2 cells, at most 2^26, one atom a cell"));
        }
        if geometric.is_some_and(|g| g.len() != atoms.len()) {
            return Err(bad("geometric phase map size", geometric.map_or(0, <[f64]>::len) as f64, "one a cell"));
        }
        if let Some(&u) = atoms.iter().find(|&&u| u as usize >= table) {
            return Err(bad("site atom index", f64::from(u), "an index into the atoms' table"));
        }
        for (name, v) in [
            ("site pitch", pitch_m),
            ("aperture radius", radius_m),
            ("focal length", distance_m),
            ("design wavelength", design_wavelength_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(name, v, "a finite length > 0 m"));
            }
        }
        if let Some(v) = geometric.and_then(|g| g.iter().find(|v| !v.is_finite())) {
            return Err(bad("geometric phase", *v, "finite radians"));
        }
        covers("site map half width", nx, ny, pitch_m, radius_m)?;
        let mut map = SiteMap {
            nx,
            ny,
            pitch: pitch_m,
            radius: radius_m,
            distance: distance_m,
            design_wavelength: design_wavelength_m,
            atoms,
            table,
            reference: Vec::new(),
            block_counts: Vec::new(),
            block_centroid: Vec::new(),
        };
        let k0 = 2.0 * PI / design_wavelength_m;
        let mut reference = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            let y = map.y(j);
            for i in 0..nx {
                let x = map.x(i);
                let g = geometric.map_or(0.0, |g| g[j * nx + i]);
                // k0 S reduced mod 2π in f64 before the f32 factor: its phase is good to 1e-7
                let v = k0 * map.sphere(x, y) + g;
                let (s, c) = (v - 2.0 * PI * (v / (2.0 * PI)).round()).sin_cos();
                reference.push(Complex32::new(c as f32, s as f32));
            }
        }
        map.reference = reference;
        // the blocks' counts and centroids of the cells inside the aperture
        let (bx, by) = (nx.div_ceil(BLOCK), ny.div_ceil(BLOCK));
        let mut counts = vec![0u32; bx * by * table];
        let mut sums = vec![[0.0f64; 3]; bx * by];
        for j in 0..ny {
            let Some((i0, i1)) = map.inside_columns(j) else { continue };
            let y = map.y(j);
            for i in i0..i1 {
                let b = (j / BLOCK) * bx + i / BLOCK;
                counts[b * table + map.atoms[j * nx + i] as usize] += 1;
                let s = &mut sums[b];
                s[0] += map.x(i);
                s[1] += y;
                s[2] += 1.0;
            }
        }
        map.block_counts = counts;
        map.block_centroid =
            sums.iter().map(|s| if s[2] > 0.0 { [s[0] / s[2], s[1] / s[2]] } else { [0.0, 0.0] }).collect();
        Ok(map)
    }

    fn x(&self, i: usize) -> f64 {
        (i as f64 - 0.5 * (self.nx as f64 - 1.0)) * self.pitch
    }

    fn y(&self, j: usize) -> f64 {
        (j as f64 - 0.5 * (self.ny as f64 - 1.0)) * self.pitch
    }

    /// The columns `[i0, i1)` of row `j` whose cell centre is inside the aperture (none: `None`).
    fn inside_columns(&self, j: usize) -> Option<(usize, usize)> {
        let y = self.y(j);
        let r2 = self.radius * self.radius - y * y;
        if r2 < 0.0 {
            return None;
        }
        // x_i = (i − c) p with c = (nx − 1)/2: |x_i| ≤ √r2 ⇔ c − √r2/p ≤ i ≤ c + √r2/p
        let c = 0.5 * (self.nx as f64 - 1.0);
        let w = r2.sqrt() / self.pitch;
        let lo = (c - w).ceil().max(0.0) as usize;
        let hi = ((c + w).floor() + 1.0).clamp(0.0, self.nx as f64) as usize;
        // the boundary cells to the exact test (rounding at the rim)
        let inside = |i: usize| {
            let x = self.x(i);
            x * x + y * y <= self.radius * self.radius
        };
        let (mut lo, mut hi) = (lo, hi);
        while lo < hi && !inside(lo) {
            lo += 1;
        }
        while hi > lo && !inside(hi - 1) {
            hi -= 1;
        }
        while lo > 0 && inside(lo - 1) {
            lo -= 1;
        }
        while hi < self.nx && inside(hi) {
            hi += 1;
        }
        (lo < hi).then_some((lo, hi))
    }

    /// The reference sphere's path `√(x² + y² + z²) − z` (m) at `(x, y)` metres.
    fn sphere(&self, x: f64, y: f64) -> f64 {
        sphere_path(x, y, self.distance)
    }

    /// `(Σ |t_c|² S_c, Σ |t_c|²)` over the cells whose centre is in the aperture at
    /// `wavelength_m`, with the atoms' table `t` and `S_c = sinc²(g_x p/λ) sinc²(g_y p/λ)` the
    /// cell's design-order share on axis (`g = X/√(|X|² + z²)`), held constant over each block
    /// of 16² cells at the centroid of its cells (docs/physics.md: `(π p b/(λ z))²/18` of the sum
    /// to leading order, b the block's side; 5e-7 on the paper's lens).
    ///
    /// # Panics
    /// If `t` is not the table's length.
    pub fn powers(&self, t: &[Complex64], wavelength_m: f64) -> (f64, f64) {
        assert_eq!(t.len(), self.table, "an atoms' table of {} for {} atoms", t.len(), self.table);
        let power: Vec<f64> = t.iter().map(|v| v.norm_sqr()).collect();
        self.powers_of(&power, wavelength_m)
    }

    /// The derivative of [`powers`](Self::powers) where the atoms' table `t` moves by `dt`
    /// (docs/physics.md, "Gradients: a library's parameter bias"): the same sums with each
    /// atom's `|t|²` replaced by `∂|t|² = 2 Re(t̄ ∂t)` (the blocks' shares do not move).
    ///
    /// # Panics
    /// If `t` or `dt` is not the table's length.
    pub fn power_rates(&self, t: &[Complex64], dt: &[Complex64], wavelength_m: f64) -> (f64, f64) {
        assert!(
            t.len() == self.table && dt.len() == self.table,
            "an atoms' table of {} for {} atoms",
            dt.len(),
            self.table
        );
        let rate: Vec<f64> = t.iter().zip(dt).map(|(v, d)| 2.0 * (v.conj() * d).re).collect();
        self.powers_of(&rate, wavelength_m)
    }

    /// [`powers`](Self::powers) with each atom's power `power[a]` given.
    fn powers_of(&self, power: &[f64], wavelength_m: f64) -> (f64, f64) {
        let u = self.pitch / wavelength_m;
        let (mut design, mut all) = (0.0, 0.0);
        for (b, counts) in self.block_counts.chunks_exact(self.table).enumerate() {
            let p: f64 = counts.iter().zip(power).map(|(&n, &a)| f64::from(n) * a).sum();
            if p == 0.0 {
                continue;
            }
            let [x, y] = self.block_centroid[b];
            let r = (x * x + y * y + self.distance * self.distance).sqrt();
            all += p;
            design += p * (sinc(u * x / r) * sinc(u * y / r)).powi(2);
        }
        (design, all)
    }

    /// `Σ_c w[a_c]` over the cells whose centre is in the aperture, `a_c` the cell's atom: a
    /// per-atom quantity (e.g. a fin's unconverted power `|t_co|²`) summed over the layout.
    ///
    /// # Panics
    /// If `w` is not the table's length.
    pub fn count_weighted(&self, w: &[f64]) -> f64 {
        assert_eq!(w.len(), self.table, "a weights' table of {} for {} atoms", w.len(), self.table);
        self.block_counts
            .chunks_exact(self.table)
            .flat_map(|counts| counts.iter().zip(w))
            .map(|(&n, &a)| f64::from(n) * a)
            .sum()
    }

    /// `(nx, ny)`.
    pub fn shape(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// The cell pitch, m.
    pub fn pitch(&self) -> f64 {
        self.pitch
    }

    /// The aperture radius, m.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The atoms in the table.
    pub fn table(&self) -> usize {
        self.table
    }

    /// Least-squares `c ρ²` fits `(c_ψ, c_S)` of the residual phase `ψ_c = arg(t_c e^{i(k0 S_c +
    /// γ_c)})` (wrapped) and of the sphere `S` over the aperture's cells (`|t_c|²` weighted), on
    /// every `s`-th row and column so that at most [`FIT_CELLS`] are visited.
    fn fit(&self, t: &[Complex64]) -> (f64, f64) {
        let stride = ((self.nx * self.ny) as f64 / FIT_CELLS as f64).sqrt().ceil().max(1.0) as usize;
        let mut fit = RhoSquaredFit::default();
        for j in (0..self.ny).step_by(stride) {
            let Some((i0, i1)) = self.inside_columns(j) else { continue };
            let y = self.y(j);
            for i in (i0.div_ceil(stride) * stride..i1).step_by(stride) {
                let c = j * self.nx + i;
                let r = self.reference[c];
                let f = t[self.atoms[c] as usize] * Complex64::new(f64::from(r.re), f64::from(r.im));
                let w = f.norm_sqr();
                let x = self.x(i);
                let q = (x * x + y * y) / (self.radius * self.radius);
                let (p, s) = (f.arg(), self.sphere(x, y));
                fit.add(w, q, p, s);
            }
        }
        fit.solve()
    }
}

/// What a [`MapPupil`] reads its cells from.
#[derive(Clone, Debug)]
enum Cells {
    /// A designer's map: phase and amplitude per cell.
    Map(Arc<PhaseMap>),
    /// A layout: atoms per site and the atoms' table at the pupil's wavelength.
    Sites { sites: Arc<SiteMap>, table: Arc<[Complex64]> },
}

/// One order's view of a [`PhaseMap`] or a [`SiteMap`]: the wavefront `W = path_per_radian·Φ +
/// sphere_factor·S (+ the oblique wave's path off axis)` with `Φ` the stored phase
/// ([`StoredPhase`]); for a site map `k Φ path_per_radian` is the sites' own phase
/// `arg(t_{u(c)} e^{i(k0 S_c + γ_c)})`.
#[derive(Clone, Debug)]
pub struct MapPupil {
    cells: Cells,
    path_per_radian: f64,
    sphere_factor: f64,
    oblique: Option<Oblique>,
    /// `(c_Φ, c_S)`: the map's fits, or a site map's at the table's wavelength
    fits: (f64, f64),
    /// Zernike terms added to the wavefront ([`MapPupil::with_zernike`]): their evaluation
    /// form (in units of `R`) and their least-squares `ρ²` slope, m
    zernike: Option<(Arc<crate::fft::Compiled>, f64)>,
}

impl MapPupil {
    /// The order of `map` whose wavefront is `path_per_radian_m · Φ + sphere_factor · S` with
    /// the oblique incidence `oblique` off axis.
    pub fn new(map: Arc<PhaseMap>, path_per_radian_m: f64, sphere_factor: f64, oblique: Option<Oblique>) -> MapPupil {
        let fits = map.fits;
        MapPupil {
            cells: Cells::Map(map),
            path_per_radian: path_per_radian_m,
            sphere_factor,
            oblique,
            fits,
            zernike: None,
        }
    }

    /// The design order of the layout `sites` at `wavelength_m`, its atoms transmitting `table`
    /// (`t_u(λ)`, one per atom of the site map), with the oblique incidence `oblique` off axis:
    /// the sites' field `t_{u(c)} e^{i(k0 S_c + γ_c)}` times `e^{ik(1 − λ/λ0) S}`, each cell's
    /// design order its mean against the reference sphere (module docs).
    ///
    /// # Panics
    /// If `table` is not the site map's table length.
    pub fn sites(
        sites: Arc<SiteMap>,
        table: Arc<[Complex64]>,
        wavelength_m: f64,
        oblique: Option<Oblique>,
    ) -> MapPupil {
        assert_eq!(table.len(), sites.table, "an atoms' table of {} for {} atoms", table.len(), sites.table);
        let fits = sites.fit(&table);
        let path_per_radian = wavelength_m / (2.0 * PI);
        let sphere_factor = 1.0 - wavelength_m / sites.design_wavelength;
        MapPupil { cells: Cells::Sites { sites, table }, path_per_radian, sphere_factor, oblique, fits, zernike: None }
    }

    /// This order with Zernike terms `(Noll index, metres RMS)` added to its wavefront (Noll
    /// 1976, over the circle of radius `R`: a fabrication or alignment error on top of the map).
    /// Each cell takes the terms' path at its centre (as the sphere's and the oblique wave's);
    /// on samples coarser than the cells the terms join the smooth phase taken linear across the
    /// sample (docs/physics.md, "Resampling a layout to the pupil grid"). Their `ρ²` slope (the
    /// least-squares fit over the disk: `2√3 c_4`, the other terms orthogonal to `1` and `ρ²`)
    /// joins [`MapPupil::fitted_defocus_m`].
    ///
    /// # Errors
    /// A Noll index outside `1..=`[`crate::fft::MAX_NOLL_INDEX`] or a non-finite coefficient.
    pub fn with_zernike(mut self, zernike_noll_m: &[(usize, f64)]) -> Result<MapPupil, Error> {
        let aberrations =
            crate::fft::Aberrations { zernike_noll_m: zernike_noll_m.to_vec(), ..crate::fft::Aberrations::default() };
        aberrations.validate()?;
        if zernike_noll_m.iter().all(|&(_, c)| c == 0.0) {
            self.zernike = None;
            return Ok(self);
        }
        let slope: f64 = zernike_noll_m.iter().filter(|&&(j, _)| j == 4).map(|&(_, c)| 2.0 * 3f64.sqrt() * c).sum();
        self.zernike = Some((Arc::new(crate::fft::Compiled::new(&aberrations)), slope));
        Ok(self)
    }

    /// The added Zernike terms' path (m) at `(u, v)` (units of `R`), 0 without terms.
    fn zernike_m(&self, u: f64, v: f64) -> f64 {
        self.zernike.as_ref().map_or(0.0, |(z, _)| z.opd_m(u, v))
    }

    /// The map's aperture (a site map's is the circle).
    pub fn aperture(&self) -> MapAperture {
        match &self.cells {
            Cells::Map(m) => m.aperture,
            Cells::Sites { .. } => MapAperture::Circle,
        }
    }

    /// The phase map, if the pupil is one (not a site map).
    pub fn phase_map(&self) -> Option<&PhaseMap> {
        match &self.cells {
            Cells::Map(m) => Some(m),
            Cells::Sites { .. } => None,
        }
    }

    /// The best-fit defocus `W020` (m) of the order's wavefront on axis (least squares against
    /// `ρ²` over the aperture): sizes the spectral panels and the Fraunhofer check.
    pub fn fitted_defocus_m(&self) -> f64 {
        let (phase, sphere) = self.fits;
        self.path_per_radian * phase + self.sphere_factor * sphere + self.zernike.as_ref().map_or(0.0, |z| z.1)
    }

    /// The oblique wave's path (m) at `(u, v)` (units of `R`), 0 on axis.
    fn oblique_m(&self, u: f64, v: f64) -> f64 {
        self.oblique.map_or(0.0, |o| o.opd_m(u, v))
    }

    /// The reference path's gradient `(g_x, g_y)` at `(cx, cy)` metres (sphere and oblique wave)
    /// for cells of `pitch` in an aperture of `radius` with the detector at `distance`.
    fn gradient(&self, cx: f64, cy: f64, pitch: f64, radius: f64, distance: f64) -> (f64, f64) {
        let r = (cx * cx + cy * cy + distance * distance).sqrt();
        let (ux, uy) = (cx / radius, cy / radius);
        let d = 0.5 * pitch / radius;
        match self.oblique {
            None => (cx / r, cy / r),
            Some(_) => (
                cx / r + (self.oblique_m(ux + d, uy) - self.oblique_m(ux - d, uy)) / pitch,
                cy / r + (self.oblique_m(ux, uy + d) - self.oblique_m(ux, uy - d)) / pitch,
            ),
        }
    }

    /// The design-order field on `n × n` samples of `[−1, 1]²` (units of `R`), each sample
    /// times its transmitting area fraction `area` (the circle's edge pixels), at `lambda`, and
    /// its power `Σ |field|²` (the OTF's normalization; for a site map sampled coarser than
    /// its cells, the cells' mean power: docs/physics.md, "Resampling a layout to the pupil
    /// grid").
    pub fn field(&self, n: usize, area: &[f64], lambda: f64) -> (Vec<Complex64>, f64) {
        let start = std::time::Instant::now();
        let out = match &self.cells {
            Cells::Map(map) => self.map_field(map, n, area, lambda),
            Cells::Sites { sites, table } => {
                let power: Vec<f64> = table.iter().map(|t| t.norm_sqr()).collect();
                self.sites_field(sites, table, &power, n, area, lambda)
            }
        };
        let nanos = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        FIELD_NANOS.fetch_add(nanos, std::sync::atomic::Ordering::Relaxed);
        out
    }

    /// The derivative of [`field`](Self::field) of a site map's order where its atoms' table
    /// moves by `d_table` (docs/physics.md, "Gradients: a library's parameter bias"): the field
    /// is linear in the table, so its derivative is the same sampling with the table replaced by
    /// `∂t` (point and block paths alike), and the power's is the same sum with each atom's `|t|²`
    /// replaced by `2 Re(t̄ ∂t)`. The site fits do not enter the sampled field (only
    /// [`fitted_defocus_m`](Self::fitted_defocus_m), which sizes the rule). `None` for a
    /// designer's map or a table of another length.
    pub fn field_derivative(
        &self,
        n: usize,
        area: &[f64],
        lambda: f64,
        d_table: &[Complex64],
    ) -> Option<(Vec<Complex64>, f64)> {
        let Cells::Sites { sites, table } = &self.cells else { return None };
        if d_table.len() != table.len() {
            return None;
        }
        let rate: Vec<f64> = table.iter().zip(d_table).map(|(t, d)| 2.0 * (t.conj() * d).re).collect();
        Some(self.sites_field(sites, d_table, &rate, n, area, lambda))
    }

    /// The derivative of [`field`](Self::field) of a designer's map on axis along `scale` per
    /// relative change (docs/physics.md, "Gradients: a phase map's pitch and aperture"): the
    /// field `P_j = A_j f_c` (the cell `c` holding the sample's centre, `f_c = a_c s_c e^{i k w_c}`
    /// its design-order value) and its power `Σ A_j |f_c|²`, as `(∂P, ∂power)`. Two parts:
    /// - *the cells' values*, the edges held: the pitch moves each centre `X_c ∝ p`, the distance
    ///   `z` the sphere `S(X_c) = √(|X_c|² + z²) − z` (`X·∇S = |X|²/r`, `z ∂S/∂z = z²/r − z`,
    ///   `r = √(|X|² + z²)`) and with it a residual's stored phase `ψ = φ0 + k0 S`, and both the
    ///   share's arguments `a = p g/λ`, `g = X/r` (`∂ln a = 1 + z²/r²` along `ln p`, `−z²/r²`
    ///   along `ln z`, `∂sinc a = (cos πa − sinc a) ∂ln a`): `∂P_j = A_j ∂f_c`;
    /// - *the cells' edges*: in the pupil's units the edges sit at `e = (i − n/2) ρ`, `ρ = p/R`,
    ///   and move at `∂e/∂ln ρ = e` (`+1` per `ln p`, `−1` per `ln R`), so the field moves by the
    ///   line measure `e (f_before − f_after)` on every edge between two cells inside the
    ///   aperture (the cells' jump times the edge's normal velocity); each sample takes its
    ///   mean over the sample, `(1/h²) ∫ e (f_before − f_after) dl` over the edges' pieces inside
    ///   the sample and the aperture (exact lengths: the edges are straight, the aperture's
    ///   boundary a circle or the square's sides), and the power moves by the same integrals of
    ///   `|f_before|² − |f_after|²`. The map's outermost edges are not between two cells (the
    ///   map is clamped there), so they carry nothing.
    ///
    /// `None` for a site map, off axis or with Zernike terms added (their paths are not
    /// followed here).
    pub fn scale_derivative(
        &self,
        n: usize,
        area: &[f64],
        lambda: f64,
        scale: MapScale,
    ) -> Option<(Vec<Complex64>, f64)> {
        let Cells::Map(map) = &self.cells else { return None };
        if self.oblique.is_some() || self.zernike.is_some() {
            return None;
        }
        let k = 2.0 * PI / lambda;
        let u = map.pitch / lambda;
        let z = map.distance;
        let residual = map.stored == StoredPhase::Residual;
        let k0 = 2.0 * PI / map.design_wavelength;
        // a cell's design amplitude and phase (as `map_field`), and their rates along `scale`
        let cell = |i: usize, j: usize| -> (f64, f64, f64, f64) {
            let c = j * map.nx + i;
            let [cx, cy] = map.centre(i, j);
            let a = map.amplitude.as_ref().map_or(1.0, |v| v[c]);
            let r = (cx * cx + cy * cy + z * z).sqrt();
            let (ax, ay) = (u * cx / r, u * cy / r);
            let (sx, sy) = (sinc(ax), sinc(ay));
            let design = a * sx * sy;
            let w = self.path_per_radian * map.phase[c] + self.sphere_factor * map.sphere(cx, cy);
            // (∂S, ∂ln a) along the scale
            let (d_sphere, d_ln_a) = match scale {
                MapScale::Pitch => ((cx * cx + cy * cy) / r, 1.0 + z * z / (r * r)),
                MapScale::Distance => (z * z / r - z, -z * z / (r * r)),
                MapScale::Radius => (0.0, 0.0),
            };
            let d_sinc = |a: f64, s: f64| ((PI * a).cos() - s) * d_ln_a;
            let d_design = a * (d_sinc(ax, sx) * sy + sx * d_sinc(ay, sy));
            let d_phase = if residual { k0 * d_sphere } else { 0.0 };
            let d_w = self.path_per_radian * d_phase + self.sphere_factor * d_sphere;
            (design, k * w, d_design, k * d_w)
        };
        let value = |i: usize, j: usize| {
            let (design, phase, _, _) = cell(i, j);
            (Complex64::from_polar(design, phase), design * design)
        };
        let mut moved = vec![Complex64::new(0.0, 0.0); n * n];
        let mut d_power = 0.0;
        let offset = [0.5 * map.nx as f64, 0.5 * map.ny as f64];
        let holding =
            |v: f64, o: f64, len: usize| ((v * map.radius / map.pitch + o).floor().max(0.0) as usize).min(len - 1);
        if scale != MapScale::Radius {
            for (idx, x, y) in crate::fft::transmitting_pixels(n, area) {
                let (ci, cj) = (holding(x, offset[0], map.nx), holding(y, offset[1], map.ny));
                let (design, phase, d_design, d_phase) = cell(ci, cj);
                moved[idx] = Complex64::new(d_design, design * d_phase) * Complex64::from_polar(area[idx], phase);
                d_power += area[idx] * 2.0 * design * d_design;
            }
        }
        let speed = match scale {
            MapScale::Pitch => 1.0,
            MapScale::Radius => -1.0,
            MapScale::Distance => return Some((moved, d_power)),
        };
        let h = 2.0 / n as f64;
        let rho = map.pitch / map.radius;
        let aperture = map.aperture;
        // the half length of the line at `e` (across) inside the aperture
        let half = |e: f64| match aperture {
            MapAperture::Circle => (1.0 - e * e).max(0.0).sqrt(),
            MapAperture::Square => 1.0,
        };
        // along a line at `e` (units of R) from −l to l: the pieces between the samples' and the
        // cells' boundaries, each `(sample, cell, length)`
        let pieces = |l: f64, cells: usize, visit: &mut dyn FnMut(usize, usize, f64)| {
            // the end of cell `c` along the line (the last cell is clamped: no end)
            let cell_end = |c: usize| {
                if c + 1 < cells { (c as f64 + 1.0 - 0.5 * cells as f64) * rho } else { f64::INFINITY }
            };
            let mut s = (((1.0 - l) / h).floor().max(0.0) as usize).min(n - 1);
            let mut c = ((-l / rho + 0.5 * cells as f64).floor().max(0.0) as usize).min(cells - 1);
            let mut t = -l;
            loop {
                let (sample_end, end) = (-1.0 + (s + 1) as f64 * h, cell_end(c));
                let next = sample_end.min(end).min(l);
                if next > t {
                    visit(s, c, next - t);
                }
                if next >= l {
                    break;
                }
                // (each turn passes a sample's or a cell's end: the walk ends)
                if sample_end <= next && s + 1 < n {
                    s += 1;
                }
                if end <= next && c + 1 < cells {
                    c += 1;
                }
                t = next;
            }
        };
        let unit = speed / (h * h);
        // the edges between columns i − 1 and i (x = e), then between rows j − 1 and j (y = e)
        for across in [true, false] {
            let (count, along) = if across { (map.nx, map.ny) } else { (map.ny, map.nx) };
            for edge in 1..count {
                let e = (edge as f64 - 0.5 * count as f64) * rho;
                if e.abs() >= 1.0 {
                    continue;
                }
                let line = (((e + 1.0) / h).floor().max(0.0) as usize).min(n - 1);
                let l = half(e);
                pieces(l, along, &mut |s, c, length| {
                    let ((before, p0), (after, p1)) = if across {
                        (value(edge - 1, c), value(edge, c))
                    } else {
                        (value(c, edge - 1), value(c, edge))
                    };
                    let idx = if across { s * n + line } else { line * n + s };
                    moved[idx] += (before - after) * (unit * e * length);
                    d_power += unit * e * length * (p0 - p1);
                });
            }
        }
        Some((moved, d_power))
    }

    /// A site map's field with the atoms' table `table` and their powers `power` (the point or
    /// the block path by the samples' size against the cells).
    fn sites_field(
        &self,
        sites: &SiteMap,
        table: &[Complex64],
        power: &[f64],
        n: usize,
        area: &[f64],
        lambda: f64,
    ) -> (Vec<Complex64>, f64) {
        if 2.0 * sites.radius / n as f64 >= sites.pitch {
            self.sites_block_field(sites, table, power, n, area, lambda)
        } else {
            self.sites_point_field(sites, table, power, n, area, lambda)
        }
    }

    fn map_field(&self, map: &PhaseMap, n: usize, area: &[f64], lambda: f64) -> (Vec<Complex64>, f64) {
        let k = 2.0 * PI / lambda;
        let mut field = vec![Complex64::new(0.0, 0.0); n * n];
        let mut weight = 0.0;
        let offset = [0.5 * map.nx as f64, 0.5 * map.ny as f64];
        for (idx, x, y) in crate::fft::transmitting_pixels(n, area) {
            // the cell holding this sample (the map covers the aperture: clamped at its edge)
            let cell =
                |v: f64, o: f64, len: usize| ((v * map.radius / map.pitch + o).floor().max(0.0) as usize).min(len - 1);
            let (ci, cj) = (cell(x, offset[0], map.nx), cell(y, offset[1], map.ny));
            let [cx, cy] = map.centre(ci, cj);
            let a = map.amplitude.as_ref().map_or(1.0, |v| v[cj * map.nx + ci]);
            // the reference path's gradient across the cell (sphere and oblique wave)
            let (gx, gy) = self.gradient(cx, cy, map.pitch, map.radius, map.distance);
            let u = map.pitch / lambda;
            let design = a * sinc(u * gx) * sinc(u * gy);
            let w = self.path_per_radian * map.phase[cj * map.nx + ci]
                + self.sphere_factor * map.sphere(cx, cy)
                + self.oblique_m(cx / map.radius, cy / map.radius)
                + self.zernike_m(cx / map.radius, cy / map.radius);
            let amp = area[idx] * design;
            weight += area[idx] * design * design;
            field[idx] = Complex64::from_polar(amp, k * w);
        }
        (field, weight)
    }

    /// A site map on samples finer than its cells: each sample takes the cell holding it (as
    /// [`map_field`](Self::map_field)).
    fn sites_point_field(
        &self,
        sites: &SiteMap,
        table: &[Complex64],
        power: &[f64],
        n: usize,
        area: &[f64],
        lambda: f64,
    ) -> (Vec<Complex64>, f64) {
        let mut field = vec![Complex64::new(0.0, 0.0); n * n];
        let mut weight = 0.0;
        for (idx, x, y) in crate::fft::transmitting_pixels(n, area) {
            let (v, p) = self.site_at(sites, table, power, x, y, lambda);
            field[idx] = v * area[idx];
            weight += area[idx] * p;
        }
        (field, weight)
    }

    /// The design-order field of the cell holding `(x, y)` (units of `R`; clamped at the map's
    /// edge) and its power (the atom's `power` times the share²).
    fn site_at(
        &self,
        sites: &SiteMap,
        table: &[Complex64],
        power: &[f64],
        x: f64,
        y: f64,
        lambda: f64,
    ) -> (Complex64, f64) {
        let cell = |v: f64, len: usize| {
            ((v * sites.radius / sites.pitch + 0.5 * len as f64).floor().max(0.0) as usize).min(len - 1)
        };
        let (ci, cj) = (cell(x, sites.nx), cell(y, sites.ny));
        let (cx, cy) = (sites.x(ci), sites.y(cj));
        let c = cj * sites.nx + ci;
        let (gx, gy) = self.gradient(cx, cy, sites.pitch, sites.radius, sites.distance);
        let u = sites.pitch / lambda;
        let s = sinc(u * gx) * sinc(u * gy);
        let r = sites.reference[c];
        let atom = sites.atoms[c] as usize;
        let t = table[atom];
        let k = 2.0 * PI / lambda;
        let (u_c, v_c) = (cx / sites.radius, cy / sites.radius);
        let w = self.sphere_factor * sites.sphere(cx, cy) + self.oblique_m(u_c, v_c) + self.zernike_m(u_c, v_c);
        let v = t * Complex64::new(f64::from(r.re), f64::from(r.im)) * Complex64::from_polar(s, k * w);
        (v, power[atom] * s * s)
    }

    /// A site map on samples at least one cell wide: each sample is the mean of the design-order
    /// fields of the cells whose centre is in it and in the aperture, `t_{u(c)} e^{i(k0 S_c +
    /// γ_c)} e^{iφ(X_c)}`, with the smooth phase `φ = k((1 − λ/λ0) S + oblique + Zernike terms)` taken linear
    /// across the sample (its gradient at the sample's centre: separable, one factor a cell
    /// column and one a cell row), times the design order's share at the sample's centre; the
    /// power is the cells' mean `|t|²` times the share² (docs/physics.md, "Resampling a layout to
    /// the pupil grid"). Rows of samples in parallel; the weight summed in row order.
    fn sites_block_field(
        &self,
        sites: &SiteMap,
        table: &[Complex64],
        power: &[f64],
        n: usize,
        area: &[f64],
        lambda: f64,
    ) -> (Vec<Complex64>, f64) {
        use rayon::prelude::*;
        let h = 2.0 / n as f64;
        let radius = sites.radius;
        // each cell column's (row's) sample, or n past the grid
        let bin = |v: f64| {
            let s = ((v / radius + 1.0) / h).floor();
            if s >= 0.0 && s < n as f64 { s as usize } else { n }
        };
        let columns: Vec<usize> = (0..sites.nx).map(|i| bin(sites.x(i))).collect();
        let rows: Vec<usize> = (0..sites.ny).map(|j| bin(sites.y(j))).collect();
        // the cell rows of each sample row (rows are monotone in j)
        let mut first = vec![sites.ny; n + 1];
        let mut last = vec![0usize; n + 1];
        for (j, &r) in rows.iter().enumerate() {
            first[r] = first[r].min(j);
            last[r] = last[r].max(j + 1);
        }
        let k = 2.0 * PI / lambda;
        let u = sites.pitch / lambda;
        let centre = |i: usize| (-1.0 + (i as f64 + 0.5) * h) * radius;
        // the smooth phase φ (radians) at (x, y) metres
        let smooth = |x: f64, y: f64| {
            let (u, v) = (x / radius, y / radius);
            k * (self.sphere_factor * sites.sphere(x, y) + self.oblique_m(u, v) + self.zernike_m(u, v))
        };
        let mut field = vec![Complex64::new(0.0, 0.0); n * n];
        let weights: Vec<f64> = field
            .par_chunks_mut(n)
            .enumerate()
            .map(|(js, out)| {
                if first[js] >= last[js] {
                    return 0.0;
                }
                let ys = centre(js);
                // φ and its gradient at each sample's centre (central differences over a cell)
                let d = 0.5 * sites.pitch;
                let phase: Vec<[f64; 3]> = (0..n)
                    .map(|i| {
                        let xs = centre(i);
                        [
                            smooth(xs, ys),
                            (smooth(xs + d, ys) - smooth(xs - d, ys)) / (2.0 * d),
                            (smooth(xs, ys + d) - smooth(xs, ys - d)) / (2.0 * d),
                        ]
                    })
                    .collect();
                // each cell column's factor e^{i φ_x (x_c − x_s)} within its sample
                let column: Vec<Complex64> = (0..sites.nx)
                    .map(|i| match columns[i] {
                        s if s < n => Complex64::from_polar(1.0, phase[s][1] * (sites.x(i) - centre(s))),
                        _ => Complex64::new(0.0, 0.0),
                    })
                    .collect();
                let mut sum = vec![Complex64::new(0.0, 0.0); n];
                let mut row_sum = vec![Complex64::new(0.0, 0.0); n];
                let mut pow = vec![0.0f64; n];
                let mut count = vec![0u32; n];
                for j in first[js]..last[js] {
                    let Some((i0, i1)) = sites.inside_columns(j) else { continue };
                    let (s0, s1) = (columns[i0], columns[i1 - 1]);
                    let cells = j * sites.nx;
                    for i in i0..i1 {
                        let s = columns[i];
                        if s == n {
                            continue;
                        }
                        let c = cells + i;
                        let a = sites.atoms[c] as usize;
                        let r = sites.reference[c];
                        row_sum[s] += table[a] * Complex64::new(f64::from(r.re), f64::from(r.im)) * column[i];
                        pow[s] += power[a];
                        count[s] += 1;
                    }
                    // each sample's row factor e^{i φ_y (y_c − y_s)}
                    let dy = sites.y(j) - ys;
                    for s in s0.min(n - 1)..=s1.min(n - 1) {
                        sum[s] += row_sum[s] * Complex64::from_polar(1.0, phase[s][2] * dy);
                        row_sum[s] = Complex64::new(0.0, 0.0);
                    }
                }
                let mut weight = 0.0;
                for (i, v) in out.iter_mut().enumerate() {
                    let a = area[js * n + i];
                    if a <= 0.0 {
                        continue;
                    }
                    let x = -1.0 + (i as f64 + 0.5) * h;
                    if count[i] == 0 {
                        // an edge sample without a cell centre in the aperture: its cell
                        let (f, p) = self.site_at(sites, table, power, x, ys / radius, lambda);
                        *v = f * a;
                        weight += a * p;
                        continue;
                    }
                    let (gx, gy) = self.gradient(x * radius, ys, sites.pitch, radius, sites.distance);
                    let share = sinc(u * gx) * sinc(u * gy);
                    let inv = 1.0 / f64::from(count[i]);
                    *v = sum[i] * Complex64::from_polar(a * share * inv, phase[i][0]);
                    weight += a * share * share * pow[i] * inv;
                }
                weight
            })
            .collect();
        (field, weights.iter().sum())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each sample's area fraction of `aperture` on `n × n` samples of `[−1, 1]²` (exact).
    fn areas(n: usize, aperture: MapAperture) -> Vec<f64> {
        let h = 2.0 / n as f64;
        let circle = crate::fft::Aperture::circle();
        let mut out = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                let (x0, y0) = (-1.0 + i as f64 * h, -1.0 + j as f64 * h);
                out.push(match aperture {
                    MapAperture::Circle => circle.area_in(x0, x0 + h, y0, y0 + h) / (h * h),
                    MapAperture::Square => 1.0,
                });
            }
        }
        out
    }

    /// A 6 × 6 map of 1 µm cells with an uneven phase, in the aperture of radius 2.7 µm (the
    /// cells' edges at multiples of ρ = 0.37 of the radius), at λ = 820 nm, designed at 800 nm.
    fn six_by_six(aperture: MapAperture, radius: f64, distance: f64, stored: StoredPhase) -> Arc<PhaseMap> {
        let phase: Vec<f64> = (0..36).map(|c| 0.9 * (c as f64 * 0.7).sin() + 0.13 * c as f64).collect();
        Arc::new(PhaseMap::new(6, 6, 1e-6, phase, None, aperture, radius, distance, 800e-9, stored).unwrap())
    }

    /// The cells' edges (`MapScale::Radius`), summed over the samples, `h² Σ ∂P_j` and
    /// `h² ∂power`, against central differences (step 1e-5 in ln R) of the continuous pupil's
    /// `Σ_c f_c |c ∩ aperture|` and `Σ_c |f_c|² |c ∩ aperture|`, each cell's value `f_c` held and
    /// its area in the aperture exact (the circle's by `fft::Aperture::area_in`; the map's outer
    /// cells reach past the aperture): the edge measure's integral is the area's derivative.
    #[test]
    fn map_edges_move_the_cells_areas() {
        let lambda = 820e-9;
        for aperture in [MapAperture::Circle, MapAperture::Square] {
            let (radius, distance) = (2.7e-6, 12e-6);
            let map = six_by_six(aperture, radius, distance, StoredPhase::Residual);
            let pupil = MapPupil::new(map.clone(), lambda / (2.0 * PI), 1.0 - lambda / 800e-9, None);
            // each cell's value as the field takes it (sampled at a point inside the cell, every
            // sample open)
            let n = 96;
            let area = areas(n, aperture);
            let (field, _) = pupil.field(n, &vec![1.0; n * n], lambda);
            let rho = map.pitch() / radius;
            let cell_value = |i: usize, j: usize| {
                let at = |c: usize| ((c as f64 - 3.0 + 0.5) * rho + 1.0) / (2.0 / n as f64);
                let idx = at(j) as usize * n + at(i) as usize;
                field[idx]
            };
            let continuous = |ln_r: f64| {
                let rho = map.pitch() / (radius * ln_r.exp());
                let edge = |c: usize| (c as f64 - 3.0) * rho;
                let (mut sum, mut power) = (Complex64::new(0.0, 0.0), 0.0);
                let circle = crate::fft::Aperture::circle();
                for j in 0..6 {
                    for i in 0..6 {
                        let span =
                            |c: usize| (if c == 0 { -2.0 } else { edge(c) }, if c == 5 { 2.0 } else { edge(c + 1) });
                        let ((x0, x1), (y0, y1)) = (span(i), span(j));
                        let a = match aperture {
                            MapAperture::Circle => circle.area_in(x0, x1, y0, y1),
                            MapAperture::Square => (x1.min(1.0) - x0.max(-1.0)) * (y1.min(1.0) - y0.max(-1.0)),
                        };
                        let f = cell_value(i, j);
                        sum += f * a;
                        power += f.norm_sqr() * a;
                    }
                }
                (sum, power)
            };
            let d = 1e-5;
            let ((up, up_power), (down, down_power)) = (continuous(d), continuous(-d));
            let (reference, reference_power) = ((up - down) / (2.0 * d), (up_power - down_power) / (2.0 * d));
            let (moved, d_power) = pupil.scale_derivative(n, &area, lambda, MapScale::Radius).unwrap();
            let h2 = (2.0 / n as f64).powi(2);
            let total: Complex64 = moved.iter().sum::<Complex64>() * h2;
            assert!((total - reference).norm() <= 1e-8 * reference.norm(), "{aperture:?}: {total} vs {reference}");
            assert!(
                (d_power * h2 - reference_power).abs() <= 1e-8 * reference.norm(),
                "{aperture:?}: {} vs {reference_power}",
                d_power * h2
            );
            // the pitch's edges move the other way (its cells' values move too)
            let (pitch_moved, _) = pupil.scale_derivative(n, &area, lambda, MapScale::Pitch).unwrap();
            assert!(pitch_moved.iter().zip(&moved).any(|(p, r)| (p + r).norm() > 0.0));
        }
    }

    /// The cells' values along the detector distance (`MapScale::Distance`: the sphere, the
    /// residual's stored phase and the share move, the edges do not) against central differences
    /// (relative step 1e-5) of the sampled field and its power, sample by sample: at a fixed
    /// sampling the field is smooth in the distance.
    #[test]
    fn map_distance_moves_the_cells_values() {
        let lambda = 820e-9;
        let (n, radius, distance) = (64, 2.7e-6, 12e-6);
        let area = areas(n, MapAperture::Circle);
        let sampled = |z: f64| {
            let map = six_by_six(MapAperture::Circle, radius, z, StoredPhase::Residual);
            MapPupil::new(map, lambda / (2.0 * PI), 1.0 - lambda / 800e-9, None).field(n, &area, lambda)
        };
        let d: f64 = 1e-5;
        let ((up, up_power), (down, down_power)) = (sampled(distance * d.exp()), sampled(distance * (-d).exp()));
        let map = six_by_six(MapAperture::Circle, radius, distance, StoredPhase::Residual);
        let pupil = MapPupil::new(map, lambda / (2.0 * PI), 1.0 - lambda / 800e-9, None);
        let (moved, d_power) = pupil.scale_derivative(n, &area, lambda, MapScale::Distance).unwrap();
        let largest = moved.iter().map(|v| v.norm()).fold(0.0, f64::max);
        assert!(largest > 0.1, "{largest}");
        for (idx, m) in moved.iter().enumerate() {
            let reference = (up[idx] - down[idx]) / (2.0 * d);
            assert!((m - reference).norm() <= 1e-7 * largest, "sample {idx}: {m} vs {reference}");
        }
        let reference_power = (up_power - down_power) / (2.0 * d);
        assert!((d_power - reference_power).abs() <= 1e-7 * up_power, "{d_power} vs {reference_power}");
        // off axis the lane is not computed
        let map = six_by_six(MapAperture::Circle, radius, distance, StoredPhase::Residual);
        let oblique = Oblique::new(radius, distance, 0.05, 0.0).unwrap();
        let off = MapPupil::new(map, lambda / (2.0 * PI), 1.0 - lambda / 800e-9, Some(oblique));
        assert!(off.scale_derivative(n, &area, lambda, MapScale::Distance).is_none());
    }
}
