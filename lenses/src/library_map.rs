//! A metalens of meta-atoms from a [`Library`] placed on a 2-D square lattice ([`AtomGrid`]: a
//! `.npy` grid or a GDSII layout as drawn), in the local periodic approximation (docs/physics.md,
//! "2-D library layouts").
//!
//! Each lattice site's atom transmits its library field `t(p, λ)` (the interpolation of
//! [`Library::transmission`], the same as the radial [`crate::LibraryLens`]'s), held over its
//! cell; a fin adds the geometric phase `σ 2θ` of its angle θ (σ = +1 for left-, −1 for
//! right-circular light; docs/physics.md); a site without an atom transmits the lens's
//! `empty_cell`. At each wavelength the field becomes a [`PhaseMap`] on the FFT path
//! ([`optics::Pupil::Map`]): the cell's design-order component is its mean against the exact
//! reference sphere, `t_c sinc(g_x p/λ) sinc(g_y p/λ)` (the blazed staircase of the phase maps),
//! the rest stray light. `τ1(λ) = Σ_c |t_c|² sinc² sinc² p²/(πR²)` and
//! `T(λ) = Σ_c (|t_c|² + |t_co,c|²) p²/(πR²)` over the cells whose centre is in the aperture,
//! `|t_co|` a fin's unconverted light where the library gives it (`co_amplitude`: zero-order
//! light, stray).

use std::collections::HashMap;
use std::f64::consts::{PI, TAU};
use std::sync::{Arc, Mutex};

use num_complex::Complex64;
use optics::map::{MAP_MAX_CELLS, MapAperture, MapPupil, PhaseMap, StoredPhase};
use optics::radial::Oblique;
use optics::{Field, LensModel, Order};

use crate::atom_grid::AtomGrid;
use crate::chromatic::check;
use crate::{Error, Library, sinc};

/// The circular polarization a fin layout is lit with: the converted light carries `e^{iσ2θ}`,
/// σ = +1 for left-circular (LCP), −1 for right-circular (RCP) light (docs/physics.md, "2-D
/// library layouts": Jones calculus, `e^{i(kz − ωt)}`, handedness as the receiver sees it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handedness {
    /// Left-circular: `+2θ`.
    Lcp,
    /// Right-circular: `−2θ`.
    Rcp,
}

impl Handedness {
    /// The sign σ of the geometric phase `σ 2θ`.
    pub fn sign(self) -> f64 {
        match self {
            Handedness::Lcp => 1.0,
            Handedness::Rcp => -1.0,
        }
    }
}

/// A map cell without an atom.
const EMPTY: u32 = u32::MAX;

/// The most bytes of per-wavelength maps a lens keeps (each `16 B` a cell).
const MAP_CACHE_BYTES: usize = 1 << 30;

/// A wavelength's map: (λ bits, map).
type CachedMap = (u64, Arc<PhaseMap>);

/// A 2-D meta-atom library lens (see the module's documentation).
#[derive(Debug)]
pub struct LibraryMapLens {
    f_number: f64,
    focal_length: f64,
    design_wavelength: f64,
    library: Arc<Library>,
    pitch: f64,
    /// map cells along x and y (centred on the axis, covering the aperture)
    shape: (usize, usize),
    /// each map cell's atom (index into `unique`) or [`EMPTY`]
    cells: Vec<u32>,
    unique: Vec<Vec<f64>>,
    /// each map cell's geometric phase `σ 2θ` (fins)
    geometric: Option<Vec<f64>>,
    empty_cell: Complex64,
    /// the lattice's residual offset from the axis, m (at most a quarter pitch a direction)
    offset: (f64, f64),
    atoms_in_aperture: u64,
    empty_in_aperture: u64,
    clamped: u64,
    source: String,
    /// the layout's statistics, for the description
    layout: String,
    scalars: Mutex<Vec<(u64, f64, f64)>>,
    maps: Mutex<Vec<CachedMap>>,
}

impl Clone for LibraryMapLens {
    fn clone(&self) -> LibraryMapLens {
        LibraryMapLens {
            f_number: self.f_number,
            focal_length: self.focal_length,
            design_wavelength: self.design_wavelength,
            library: self.library.clone(),
            pitch: self.pitch,
            shape: self.shape,
            cells: self.cells.clone(),
            unique: self.unique.clone(),
            geometric: self.geometric.clone(),
            empty_cell: self.empty_cell,
            offset: self.offset,
            atoms_in_aperture: self.atoms_in_aperture,
            empty_in_aperture: self.empty_in_aperture,
            clamped: self.clamped,
            source: self.source.clone(),
            layout: self.layout.clone(),
            scalars: Mutex::new(Vec::new()),
            maps: Mutex::new(Vec::new()),
        }
    }
}

impl LibraryMapLens {
    /// A lens of working F-number `f_number` with the detector at `focal_length_m`, designed at
    /// `design_wavelength_m`, of the atoms of `grid` read in `library` (whose parameter columns
    /// are `library_columns`, each found by name among the grid's parameters). A site without an
    /// atom inside the aperture transmits `empty_cell` (required if there is one); fins (a grid
    /// with angles) need the `handedness`. Atoms outside the library's range by more than
    /// `range_tolerance` (in the parameters' units: the drawing's resolution) are refused with
    /// their count and the worst one; those within it are taken at the range's end and counted.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a parameter out of range, [`Error::Layout`] for a layout the
    /// lens cannot take (named above).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        design_wavelength_m: f64,
        library: Arc<Library>,
        library_columns: &[String],
        grid: &AtomGrid,
        empty_cell: Option<Complex64>,
        handedness: Option<Handedness>,
        range_tolerance: f64,
        source: String,
    ) -> Result<LibraryMapLens, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        check("design_wavelength", design_wavelength_m, design_wavelength_m > 0.0, "a finite wavelength > 0 m")?;
        let (lo, hi) = library.wavelength_range();
        check(
            "design_wavelength",
            design_wavelength_m,
            (lo..=hi).contains(&design_wavelength_m),
            "a wavelength inside the library's",
        )?;
        check("lattice pitch", grid.pitch_m, grid.pitch_m > 0.0, "a finite pitch > 0 m")?;
        let layout = |m: String| Err(Error::Layout(m));
        if library_columns.len() != library.dimensions() {
            return layout(format!(
                "{} library column names for a library of {} parameters",
                library_columns.len(),
                library.dimensions()
            ));
        }
        let mut index = Vec::with_capacity(library_columns.len());
        for c in library_columns {
            match grid.parameters.iter().position(|g| g == c) {
                Some(i) => index.push(i),
                None => {
                    return layout(format!(
                        "the library's parameter column `{c}` is not in the layout, which gives {}",
                        grid.parameters.join(", ")
                    ));
                }
            }
        }
        if grid.parameters.len() != library_columns.len() {
            return layout(format!(
                "the layout gives {} but the library's parameter columns are {}",
                grid.parameters.join(", "),
                library_columns.join(", ")
            ));
        }
        match (&grid.theta_deg, handedness) {
            (Some(_), None) => return layout("fins carry a geometric phase ±2θ: give the handedness".into()),
            (None, Some(_)) => {
                return layout("a handedness is for fins (atom = \"fin\"): these atoms have no angle".into());
            }
            _ => {}
        }
        if grid.theta_deg.is_none() && library.has_co_amplitude() {
            return layout("the library's co_amplitude column is a fin's unconverted light (atom = \"fin\"): these atoms have no angle".into());
        }
        let sites = grid.nx * grid.ny;
        if grid.empty.len() != sites
            || grid.values.len() != sites * grid.parameters.len()
            || grid.theta_deg.as_ref().is_some_and(|t| t.len() != sites)
        {
            return layout(format!("a grid of {} × {} sites whose arrays are not of that size", grid.nx, grid.ny));
        }
        let radius = 0.5 * focal_length_m / f_number;
        let p = grid.pitch_m;
        // the map: centred cells of the lattice's pitch covering the aperture, their centres on
        // the sites (to within a quarter pitch: the parity chosen by the lattice's offset)
        let place = |origin: f64| {
            let s = origin / p;
            let mut n = ((2.0 * radius / p).ceil() as usize).max(2);
            let half_site = (s - s.floor() - 0.5).abs() < 0.25;
            if n.is_multiple_of(2) != half_site {
                n += 1;
            }
            let d = s + 0.5 * (n as f64 - 1.0);
            let shift = d.round();
            (n, shift as i64, (d - shift) * p)
        };
        let (nx, dx, ox) = place(grid.origin_m.0);
        let (ny, dy, oy) = place(grid.origin_m.1);
        if nx.saturating_mul(ny) > MAP_MAX_CELLS {
            return layout(format!(
                "the aperture spans {nx} × {ny} sites of {} µm: more than the {MAP_MAX_CELLS} cells a map holds",
                p * 1e6
            ));
        }
        // atoms outside the library's range: counted, the worst named
        let ranges = library.ranges();
        let (mut out, mut clamped, mut worst) = (0u64, 0u64, None::<(f64, usize, usize, f64)>);
        for (site, &e) in grid.empty.iter().enumerate() {
            if e {
                continue;
            }
            let mut beyond = 0.0f64;
            for (q, &(lo, hi)) in ranges.iter().enumerate() {
                let v = grid.values[index[q] * sites + site];
                let excess = if v.is_nan() { f64::INFINITY } else { (lo - v).max(v - hi).max(0.0) };
                if excess > beyond {
                    beyond = excess;
                    if worst.is_none_or(|w| excess > w.0) && excess > range_tolerance {
                        worst = Some((excess, q, site, v));
                    }
                }
            }
            if beyond > range_tolerance {
                out += 1;
            } else if beyond > 0.0 {
                clamped += 1;
            }
        }
        if let Some((_, q, site, v)) = worst {
            let (i, j) = (site % grid.nx, site / grid.nx);
            let (lo, hi) = ranges[q];
            return layout(format!(
                "{out} atoms outside the library's range: the worst has {} = {v} against the library's [{lo}, {hi}] at site ({i}, {j}), x = {:.3} µm, y = {:.3} µm",
                library_columns[q],
                (grid.origin_m.0 + i as f64 * p) * 1e6,
                (grid.origin_m.1 + j as f64 * p) * 1e6,
            ));
        }
        // each map cell's atom: the distinct parameter sets
        let mut unique: Vec<Vec<f64>> = Vec::new();
        let mut seen: HashMap<Vec<u64>, u32> = HashMap::new();
        let mut cells = vec![EMPTY; nx * ny];
        let mut geometric = grid.theta_deg.as_ref().map(|_| vec![0.0; nx * ny]);
        let sign = handedness.map_or(0.0, Handedness::sign);
        let (mut atoms_in, mut empty_in, mut first_empty) = (0u64, 0u64, None);
        for jm in 0..ny {
            for im in 0..nx {
                let cell = jm * nx + im;
                let (x, y) = ((im as f64 - 0.5 * (nx as f64 - 1.0)) * p, (jm as f64 - 0.5 * (ny as f64 - 1.0)) * p);
                let inside = x * x + y * y <= radius * radius;
                let (i, j) = (im as i64 - dx, jm as i64 - dy);
                let site = (i >= 0 && j >= 0 && (i as usize) < grid.nx && (j as usize) < grid.ny)
                    .then(|| j as usize * grid.nx + i as usize)
                    .filter(|&s| !grid.empty[s]);
                let Some(site) = site else {
                    if inside {
                        empty_in += 1;
                        first_empty.get_or_insert((x, y));
                    }
                    continue;
                };
                if inside {
                    atoms_in += 1;
                }
                let params: Vec<f64> = (0..ranges.len())
                    .map(|q| grid.values[index[q] * sites + site].clamp(ranges[q].0, ranges[q].1))
                    .collect();
                let key: Vec<u64> = params.iter().map(|v| v.to_bits()).collect();
                let next = unique.len() as u32;
                let u = *seen.entry(key).or_insert_with(|| {
                    unique.push(params);
                    next
                });
                cells[cell] = u;
                if let (Some(g), Some(t)) = (geometric.as_mut(), grid.theta_deg.as_ref()) {
                    g[cell] = sign * 2.0 * t[site].to_radians();
                }
            }
        }
        let empty_cell = match (empty_cell, first_empty) {
            (Some(t), _) => {
                check("empty cell amplitude", t.norm(), t.norm() <= 1.0 + 1e-12, "|t| ≤ 1")?;
                t
            }
            (None, Some((x, y))) => {
                return layout(format!(
                    "{empty_in} lattice sites inside the aperture have no atom (the first at x = {:.3} µm, y = {:.3} µm): give the empty cell's transmission",
                    x * 1e6,
                    y * 1e6
                ));
            }
            (None, None) => Complex64::new(0.0, 0.0),
        };
        if atoms_in == 0 {
            return layout("no atom inside the aperture".into());
        }
        let st = &grid.stats;
        let ranges_text: Vec<String> = library_columns
            .iter()
            .enumerate()
            .filter_map(|(q, c)| {
                let &(a, b) = st.parameter_range.get(index[q])?;
                let r = optics::round_for_display;
                Some(format!("{c} {}–{} (library {}–{})", r(a), r(b), r(ranges[q].0), r(ranges[q].1)))
            })
            .collect();
        let layout_text = format!(
            "layout: {} atoms, {}, largest off-lattice distance {} nm, {} doubly occupied sites",
            st.atoms,
            ranges_text.join(", "),
            optics::round_for_display(st.max_off_lattice_m * 1e9),
            st.doubly_occupied_sites
        );
        Ok(LibraryMapLens {
            f_number,
            focal_length: focal_length_m,
            design_wavelength: design_wavelength_m,
            library,
            pitch: p,
            shape: (nx, ny),
            cells,
            unique,
            geometric,
            empty_cell,
            offset: (ox, oy),
            atoms_in_aperture: atoms_in,
            empty_in_aperture: empty_in,
            clamped,
            source,
            layout: layout_text,
            scalars: Mutex::new(Vec::new()),
            maps: Mutex::new(Vec::new()),
        })
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "library"
    }

    /// The aperture radius `f0/(2F#)`, m.
    pub fn aperture_radius(&self) -> f64 {
        0.5 * self.focal_length / self.f_number
    }

    /// The library.
    pub fn library(&self) -> &Library {
        &self.library
    }

    /// Atoms whose centre is inside the aperture.
    pub fn atoms_in_aperture(&self) -> u64 {
        self.atoms_in_aperture
    }

    /// Sites inside the aperture without an atom (they transmit the empty cell).
    pub fn empty_in_aperture(&self) -> u64 {
        self.empty_in_aperture
    }

    /// Atoms outside the library's range by less than the drawing's resolution, taken at its end.
    pub fn clamped_atoms(&self) -> u64 {
        self.clamped
    }

    /// The lattice's offset (x, y) from the axis the lens is imaged with, m (at most a quarter
    /// pitch in each direction: the sites are placed on the map's cells).
    pub fn lattice_offset_m(&self) -> (f64, f64) {
        self.offset
    }

    /// The map's cells along x and y.
    pub fn shape(&self) -> (usize, usize) {
        self.shape
    }

    /// Each distinct atom's field at `wavelength_m`.
    fn fields(&self, wavelength_m: f64) -> Vec<Complex64> {
        self.unique.iter().map(|p| self.library.transmission(p, wavelength_m)).collect()
    }

    /// The field of map cell `c` from the atoms' fields `t`.
    fn cell_field(&self, t: &[Complex64], c: usize) -> Complex64 {
        match self.cells[c] {
            EMPTY => self.empty_cell,
            u => {
                let v = t[u as usize];
                match &self.geometric {
                    Some(g) => v * Complex64::from_polar(1.0, g[c]),
                    None => v,
                }
            }
        }
    }

    /// The centre of map cell `(i, j)`, m.
    fn centre(&self, i: usize, j: usize) -> (f64, f64) {
        let (nx, ny) = self.shape;
        ((i as f64 - 0.5 * (nx as f64 - 1.0)) * self.pitch, (j as f64 - 0.5 * (ny as f64 - 1.0)) * self.pitch)
    }

    /// `(τ1, T)` at `wavelength_m`: the design order's and all the light of the cells whose
    /// centre is in the aperture, as fractions of the light on it.
    pub fn efficiency_and_transmission(&self, wavelength_m: f64) -> (f64, f64) {
        let key = wavelength_m.to_bits();
        if let Ok(cache) = self.scalars.lock()
            && let Some(hit) = cache.iter().find(|c| c.0 == key)
        {
            return (hit.1, hit.2);
        }
        let t = self.fields(wavelength_m);
        // a fin's unconverted light, |t_co|²: zero-order light, in T and not in τ1
        let co: Vec<f64> = self.unique.iter().map(|p| self.library.co_amplitude(p, wavelength_m).powi(2)).collect();
        let (nx, ny) = self.shape;
        let r2 = self.aperture_radius().powi(2);
        let z2 = self.focal_length * self.focal_length;
        let u = self.pitch / wavelength_m;
        let (mut tau, mut all) = (0.0, 0.0);
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = self.centre(i, j);
                let q = x * x + y * y;
                if q > r2 {
                    continue;
                }
                let a2 = self.cell_field(&t, j * nx + i).norm_sqr();
                let r = (q + z2).sqrt();
                all += a2 + self.cells.get(j * nx + i).and_then(|&u| co.get(u as usize)).unwrap_or(&0.0);
                tau += a2 * (sinc(u * x / r) * sinc(u * y / r)).powi(2);
            }
        }
        let scale = self.pitch * self.pitch / (PI * r2);
        let out = (tau * scale, all * scale);
        if let Ok(mut cache) = self.scalars.lock() {
            if cache.len() >= 4096 {
                cache.clear();
            }
            cache.push((key, out.0, out.1));
        }
        out
    }

    /// The field at `wavelength_m` as a map: amplitude `|t_c|` and the residual
    /// `ψ_c = arg t_c + k0 S(X_c)` (wrapped to (−π, π]; `k0 = 2π/λ0`), held with the wavefront
    /// `W = (λ/2π) ψ + (1 − λ/λ0) S`, so that `k W ≡ arg t_c + k S` (mod 2π).
    fn map(&self, wavelength_m: f64) -> Option<Arc<PhaseMap>> {
        let key = wavelength_m.to_bits();
        if let Ok(cache) = self.maps.lock()
            && let Some(hit) = cache.iter().find(|c| c.0 == key)
        {
            return Some(hit.1.clone());
        }
        let t = self.fields(wavelength_m);
        let (nx, ny) = self.shape;
        let k0 = TAU / self.design_wavelength;
        let z = self.focal_length;
        let mut phase = Vec::with_capacity(nx * ny);
        let mut amplitude = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = self.centre(i, j);
                let q = x * x + y * y;
                let sphere = q / ((q + z * z).sqrt() + z);
                let f = self.cell_field(&t, j * nx + i);
                let v = f.arg() + k0 * sphere;
                phase.push(v - TAU * (v / TAU).round());
                amplitude.push(f.norm());
            }
        }
        let map = PhaseMap::new(
            nx,
            ny,
            self.pitch,
            phase,
            Some(amplitude),
            MapAperture::Circle,
            self.aperture_radius(),
            self.focal_length,
            self.design_wavelength,
            StoredPhase::Given,
        )
        .ok()
        .map(Arc::new)?;
        if let Ok(mut cache) = self.maps.lock() {
            let keep = (MAP_CACHE_BYTES / (16 * nx * ny).max(1)).max(1);
            if cache.len() >= keep {
                cache.remove(0);
            }
            cache.push((key, map.clone()));
        }
        Some(map)
    }
}

impl LensModel for LibraryMapLens {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        let (tau, _) = self.efficiency_and_transmission(wavelength_m);
        let Some(map) = self.map(wavelength_m) else { return Vec::new() };
        let oblique = if field.is_on_axis() {
            None
        } else {
            Oblique::new(self.aperture_radius(), self.focal_length, field.x_rad, field.y_rad).ok()
        };
        let pupil = MapPupil::new(map, wavelength_m / TAU, 1.0 - wavelength_m / self.design_wavelength, oblique);
        vec![Order::map(tau, Arc::new(pupil))]
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.efficiency_and_transmission(wavelength_m).1
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.library.wavelengths().to_vec()
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.design_wavelength)
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        let (nx, ny) = self.shape;
        let empty = if self.empty_in_aperture > 0 {
            format!(
                "; {} empty sites transmit |t| = {}, φ = {} rad",
                self.empty_in_aperture,
                r(self.empty_cell.norm()),
                r(self.empty_cell.arg())
            )
        } else {
            String::new()
        };
        format!(
            "2-D meta-atom library lens F/{} f0 = {} mm at λ0 = {} nm ({}; {} atoms in the aperture on {nx} × {ny} sites of {} µm{empty}; lattice {} × {} nm off the axis; {}; local periodic approximation, each cell's mean against the exact reference sphere)",
            r(self.f_number),
            r(self.focal_length * 1e3),
            r(self.design_wavelength * 1e9),
            self.source,
            self.atoms_in_aperture,
            r(self.pitch * 1e6),
            r(self.offset.0 * 1e9),
            r(self.offset.1 * 1e9),
            self.layout,
        )
    }
}
