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
use std::f64::consts::PI;
use std::sync::{Arc, Mutex};

use num_complex::Complex64;
use optics::map::{MAP_MAX_CELLS, MapPupil, SiteMap};
use optics::radial::Oblique;
use optics::{Field, LensModel, Order};

use crate::atom_grid::AtomGrid;
use crate::chromatic::check;
use crate::{AtomErrors, Error, Library};

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

/// The most wavelengths whose atoms' tables a lens keeps.
const TABLE_CACHE: usize = 4096;

/// A wavelength's atoms' table: (λ bits, `t_u(λ)` with the empty cell last).
type CachedTable = (u64, Arc<[Complex64]>);

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
    /// each map cell's atom (index into `unique`, or `unique.len()`: the empty cell) and
    /// geometric phase `σ 2θ` (fins)
    sites: Arc<SiteMap>,
    unique: Vec<Vec<f64>>,
    empty_cell: Complex64,
    /// the lattice's residual offset from the axis, m (at most a quarter pitch a direction)
    offset: (f64, f64),
    atoms_in_aperture: u64,
    empty_in_aperture: u64,
    clamped: u64,
    source: String,
    /// the layout's statistics, for the description
    layout: String,
    /// the atoms' random fabrication errors `(σ_φ, σ_t)` ([`LibraryMapLens::with_fabrication`])
    errors: Option<(f64, f64)>,
    /// the parameter bias added to every atom (none: zeros)
    bias: Vec<f64>,
    /// Zernike terms `(Noll index, metres RMS)` added to the design order's wavefront
    zernike: Vec<(usize, f64)>,
    scalars: Mutex<Vec<(u64, f64, f64)>>,
    tables: Mutex<Vec<CachedTable>>,
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
            sites: self.sites.clone(),
            unique: self.unique.clone(),
            empty_cell: self.empty_cell,
            offset: self.offset,
            atoms_in_aperture: self.atoms_in_aperture,
            empty_in_aperture: self.empty_in_aperture,
            clamped: self.clamped,
            source: self.source.clone(),
            layout: self.layout.clone(),
            errors: self.errors,
            bias: self.bias.clone(),
            zernike: self.zernike.clone(),
            scalars: Mutex::new(Vec::new()),
            tables: Mutex::new(Vec::new()),
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
        // each map cell's atom: the distinct parameter sets (the empty cell is `u32::MAX` until
        // their count is known)
        const EMPTY: u32 = u32::MAX;
        let mut unique: Vec<Vec<f64>> = Vec::new();
        let mut seen: HashMap<Vec<u64>, u32> = HashMap::new();
        let mut cells = vec![EMPTY; nx * ny];
        let mut geometric = grid.theta_deg.as_ref().map(|_| vec![0.0; nx * ny]);
        let sign = handedness.map_or(0.0, Handedness::sign);
        let (mut atoms_in, mut empty_in, mut first_empty) = (0u64, 0u64, None);
        let (mut params, mut key, mut last) = (vec![0.0; ranges.len()], vec![0u64; ranges.len()], None::<u32>);
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
                for (q, range) in ranges.iter().enumerate() {
                    params[q] = grid.values[index[q] * sites + site].clamp(range.0, range.1);
                    key[q] = params[q].to_bits();
                }
                // neighbours mostly hold the same atom: the last one is checked before the table
                let u = match last {
                    Some(u) if unique[u as usize] == params => u,
                    _ => match seen.get(key.as_slice()) {
                        Some(&u) => u,
                        None => {
                            let next = unique.len() as u32;
                            seen.insert(key.clone(), next);
                            unique.push(params.clone());
                            next
                        }
                    },
                };
                last = Some(u);
                cells[cell] = u;
                if let (Some(g), Some(t)) = (geometric.as_mut(), grid.theta_deg.as_ref()) {
                    g[cell] = sign * 2.0 * t[site].to_radians();
                }
            }
        }
        let empty_index = unique.len() as u32;
        for c in &mut cells {
            if *c == EMPTY {
                *c = empty_index;
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
        let sites = SiteMap::new(
            nx,
            ny,
            p,
            cells,
            unique.len() + 1,
            geometric.as_deref(),
            radius,
            focal_length_m,
            design_wavelength_m,
        )
        .map_err(|e| Error::Layout(format!("the layout's site map: {e}")))?;
        Ok(LibraryMapLens {
            f_number,
            focal_length: focal_length_m,
            design_wavelength: design_wavelength_m,
            library,
            pitch: p,
            shape: (nx, ny),
            sites: Arc::new(sites),
            unique,
            empty_cell,
            offset: (ox, oy),
            atoms_in_aperture: atoms_in,
            empty_in_aperture: empty_in,
            clamped,
            source,
            layout: layout_text,
            errors: None,
            bias: Vec::new(),
            zernike: Vec::new(),
            scalars: Mutex::new(Vec::new()),
            tables: Mutex::new(Vec::new()),
        })
    }

    /// The lens as fabricated (docs/physics.md, "Fabrication errors of a 2-D layout"): every
    /// atom's parameters shifted by `bias` (one per parameter column, in the library's units,
    /// before the library is read; an atom pushed outside the library's range is refused with
    /// the count and the worst), and every atom's complex transmission given the radial lens's
    /// independent random error `t → t (1 + ε) e^{iδ}`, `δ ~ N(0, σ_φ²)`, `ε ~ N(0, σ_t²)`,
    /// `1 + ε` taken as 0 below 0 and `|t|` capped at 1 ([`crate::LibraryLens::with_fabrication`]),
    /// in expectation over the draws: the design order's field is the expected field, each atom's
    /// table entry times `E[a e^{iδ}]`, and the rest of the atoms' mean
    /// power `|t|² E[a²] − |E[t a e^{iδ}]|²`, uncorrelated from atom to atom, is light spread over
    /// the cell's diffraction angles: stray light, in T and not in τ1. `errors.seed` is not
    /// used (there are no draws). With no bias and σ = 0 the lens is the nominal one, bit for
    /// bit.
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for σ outside its range (as the radial lens's), a bias of the
    /// wrong length or not finite, or an atom pushed outside the library's range.
    pub fn with_fabrication(mut self, bias: &[f64], errors: AtomErrors) -> Result<LibraryMapLens, Error> {
        errors.check(bias, &self.library)?;
        let ranges = self.library.ranges();
        if bias.iter().any(|&b| b != 0.0) {
            let shifted: Vec<Vec<f64>> =
                self.unique.iter().map(|p| p.iter().zip(bias).map(|(v, b)| v + b).collect::<Vec<f64>>()).collect();
            // the atoms pushed out: their count over the aperture's cells and the worst
            let mut outside = vec![0.0; shifted.len() + 1];
            let mut worst: Option<(f64, usize, f64)> = None;
            for (u, p) in shifted.iter().enumerate() {
                for (d, (&v, &(lo, hi))) in p.iter().zip(&ranges).enumerate() {
                    let excess = (lo - v).max(v - hi);
                    if excess > 0.0 {
                        outside[u] = 1.0;
                        if worst.is_none_or(|w| excess > w.0) {
                            worst = Some((excess, d, v));
                        }
                    }
                }
            }
            if let Some((_, d, v)) = worst {
                let count = self.sites.count_weighted(&outside);
                return Err(Error::Layout(format!(
                    "parameter_bias {} pushes {count} atoms in the aperture outside the library's range: the worst has parameter {} = {v} against the library's [{}, {}]",
                    bias[d],
                    d + 1,
                    ranges[d].0,
                    ranges[d].1
                )));
            }
            self.unique = shifted;
            self.bias = bias.to_vec();
        }
        self.errors = (errors.phase_sigma_rad > 0.0 || errors.transmission_sigma > 0.0)
            .then_some((errors.phase_sigma_rad, errors.transmission_sigma));
        self.scalars = Mutex::new(Vec::new());
        self.tables = Mutex::new(Vec::new());
        Ok(self)
    }

    /// This lens with Zernike terms `(Noll index, metres RMS)` added to its design order's
    /// wavefront over the aperture's circle (`lens.zernike_noll_rms_um`; Noll 1976, as for the
    /// radial families), each cell taking the terms' path at its centre
    /// ([`optics::map::MapPupil::with_zernike`]).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] for a Noll index outside `1..=`[`optics::fft::MAX_NOLL_INDEX`] or a
    /// non-finite coefficient.
    pub fn with_zernike(mut self, zernike_noll_m: Vec<(usize, f64)>) -> Result<LibraryMapLens, Error> {
        let aberrations = optics::fft::Aberrations { zernike_noll_m, ..optics::fft::Aberrations::default() };
        aberrations.validate().map_err(|_| Error::OutOfRange {
            name: "zernike_noll_rms_um",
            value: f64::NAN,
            expected: "Noll indices 1 to the largest the FFT path takes, finite coefficients",
        })?;
        self.zernike = aberrations.zernike_noll_m;
        Ok(self)
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

    /// Each distinct atom's field at `wavelength_m`, the empty cell's last (the site map's
    /// table; computed once a wavelength).
    fn table(&self, wavelength_m: f64) -> Arc<[Complex64]> {
        let key = wavelength_m.to_bits();
        if let Ok(cache) = self.tables.lock()
            && let Some(hit) = cache.iter().find(|c| c.0 == key)
        {
            return hit.1.clone();
        }
        // the atoms' expected fields under their random errors (none: the fields)
        let table: Arc<[Complex64]> = self
            .unique
            .iter()
            .map(|p| {
                let t = self.library.transmission(p, wavelength_m);
                match self.errors {
                    None => t,
                    Some((phase, amplitude)) => t * expected_factor(t.norm(), phase, amplitude).0,
                }
            })
            .chain(std::iter::once(self.empty_cell))
            .collect();
        if let Ok(mut cache) = self.tables.lock() {
            if cache.len() >= TABLE_CACHE {
                cache.clear();
            }
            cache.push((key, table.clone()));
        }
        table
    }

    /// The atoms' table's derivative at `wavelength_m` with respect to the bias of parameter
    /// `wrt` (docs/physics.md, "Gradients: a library's parameter bias"), and each atom's stray
    /// power's: each distinct atom's entry `t M(|t|)`, `M = E[a e^{iδ}]` its expected error
    /// factor ([`expected_factor`]), moves by `∂t M + t M′ ∂|t|` with `∂t`
    /// ([`Library::transmission_and_derivative`]) and `∂|t| = Re(t̄ ∂t)/|t|`, `M′` the factor's
    /// derivative through the cap `a ≤ 1/|t|` ([`expected_factor_derivative`]; 0 without
    /// transmission errors); the incoherent power `|t|²(E[a²] − M²)` by
    /// `(2|t|(E[a²] − M²) + |t|²(E[a²]′ − 2M M′)) ∂|t|`, and a fin's unconverted power `|t_co|²`
    /// by `2|t_co| ∂|t_co|` ([`Library::co_amplitude_and_derivative`]); the empty cell does not
    /// move. `None` with linear interpolation or `wrt` out of range.
    fn bias_table_derivative(&self, wavelength_m: f64, wrt: usize) -> Option<(Vec<Complex64>, Vec<f64>)> {
        let (mut d_table, mut d_spread) = (Vec::with_capacity(self.unique.len() + 1), Vec::new());
        for p in &self.unique {
            let (t, dt) = self.library.transmission_and_derivative(p, wavelength_m, wrt)?;
            let (co, d_co) = self.library.co_amplitude_and_derivative(p, wavelength_m, wrt)?;
            let mut spread = 2.0 * co * d_co;
            match self.errors {
                None => d_table.push(dt),
                Some((phase, amplitude)) => {
                    let a = t.norm();
                    let (mean, square) = expected_factor(a, phase, amplitude);
                    let (d_mean, d_square) = expected_factor_derivative(a, phase, amplitude);
                    let d_a = if a > 0.0 { (t.conj() * dt).re / a } else { 0.0 };
                    d_table.push(dt * mean + t * (d_mean * d_a));
                    // the value's max(·, 0) only guards rounding: E[a²] ≥ E[a]² ≥ M²
                    if square - mean * mean > 0.0 {
                        spread += (2.0 * a * (square - mean * mean) + a * a * (d_square - 2.0 * mean * d_mean)) * d_a;
                    }
                }
            }
            d_spread.push(spread);
        }
        d_table.push(Complex64::new(0.0, 0.0));
        d_spread.push(0.0);
        Some((d_table, d_spread))
    }

    /// The atoms' table's derivative at `wavelength_m` with respect to σ_φ, the σ of the atoms'
    /// phase errors (docs/physics.md, "Gradients: a library's atoms' phase errors"): each entry
    /// is the atom's field times `E[a] e^{−σ_φ²/2}` ([`expected_factor`]), so it moves by `−σ_φ`
    /// times itself, and the incoherent power `|t|²(E[a²] − E[a]² e^{−σ_φ²})` by `2σ_φ |t|² E[a]²
    /// e^{−σ_φ²}`; the empty cell does not move. At σ_φ = 0 both are 0 (the factor is even in σ_φ).
    fn phase_error_table_derivative(&self, wavelength_m: f64) -> (Vec<Complex64>, Vec<f64>) {
        let Some((phase, amplitude)) = self.errors else {
            return (vec![Complex64::new(0.0, 0.0); self.unique.len() + 1], vec![0.0; self.unique.len() + 1]);
        };
        let table = self.table(wavelength_m);
        let mut d_table: Vec<Complex64> = table.iter().map(|t| -phase * t).collect();
        if let Some(last) = d_table.last_mut() {
            *last = Complex64::new(0.0, 0.0);
        }
        let mut d_spread: Vec<f64> = self
            .unique
            .iter()
            .map(|p| {
                let t = self.library.transmission(p, wavelength_m).norm();
                let mean = expected_factor(t, phase, amplitude).0;
                2.0 * phase * t * t * mean * mean
            })
            .collect();
        d_spread.push(0.0);
        (d_table, d_spread)
    }

    /// The atoms' table's derivative at `wavelength_m` with respect to σ_t, the σ of the atoms'
    /// relative amplitude errors (docs/physics.md, "Gradients: a library's atoms' phase
    /// errors"): each entry `t E[a] e^{−σ_φ²/2}` moves by `t ∂E[a]/∂σ_t e^{−σ_φ²/2}` and the
    /// incoherent power `|t|²(E[a²] − M²)` by `|t|²(∂E[a²] − 2M ∂M)`, the clipped moments'
    /// derivatives in σ_t ([`expected_factor_sigma_derivative`]); the empty cell does not move.
    fn transmission_error_table_derivative(&self, wavelength_m: f64) -> (Vec<Complex64>, Vec<f64>) {
        let (phase, amplitude) = self.errors.unwrap_or((0.0, 0.0));
        let (mut d_table, mut d_spread) = (Vec::with_capacity(self.unique.len() + 1), Vec::new());
        for p in &self.unique {
            let t = self.library.transmission(p, wavelength_m);
            let (mean, square) = expected_factor(t.norm(), phase, amplitude);
            let (d_mean, d_square) = expected_factor_sigma_derivative(t.norm(), phase, amplitude);
            d_table.push(t * d_mean);
            d_spread.push(if square - mean * mean > 0.0 {
                t.norm_sqr() * (d_square - 2.0 * mean * d_mean)
            } else {
                0.0
            });
        }
        d_table.push(Complex64::new(0.0, 0.0));
        d_spread.push(0.0);
        (d_table, d_spread)
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
        let (tau, mut all) = self.sites.powers(&self.table(wavelength_m), wavelength_m);
        // a fin's unconverted light, |t_co|²: zero-order light, in T and not in τ1 (the empty
        // cell, last in the table, has none)
        let co: Vec<f64> = self
            .unique
            .iter()
            .map(|p| self.library.co_amplitude(p, wavelength_m).powi(2))
            .chain(std::iter::once(0.0))
            .collect();
        all += self.sites.count_weighted(&co);
        // the atoms' random errors' incoherent power, |t|² E[a²] − |E[t a e^{iδ}]|²: in T, not in τ1
        if let Some((phase, amplitude)) = self.errors {
            let spread: Vec<f64> = self
                .unique
                .iter()
                .map(|p| {
                    let t = self.library.transmission(p, wavelength_m).norm();
                    let (mean, square) = expected_factor(t, phase, amplitude);
                    (t * t * (square - mean * mean)).max(0.0)
                })
                .chain(std::iter::once(0.0))
                .collect();
            all += self.sites.count_weighted(&spread);
        }
        let scale = self.pitch * self.pitch / (PI * self.aperture_radius().powi(2));
        let out = (tau * scale, all * scale);
        if let Ok(mut cache) = self.scalars.lock() {
            if cache.len() >= TABLE_CACHE {
                cache.clear();
            }
            cache.push((key, out.0, out.1));
        }
        out
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
        let oblique = if field.is_on_axis() {
            None
        } else {
            Oblique::new(self.aperture_radius(), self.focal_length, field.x_rad, field.y_rad).ok()
        };
        let pupil = MapPupil::sites(self.sites.clone(), self.table(wavelength_m), wavelength_m, oblique);
        // the terms were checked by `with_zernike`
        let pupil = if self.zernike.is_empty() { Ok(pupil) } else { pupil.with_zernike(&self.zernike) };
        match pupil {
            Ok(pupil) => vec![Order::map(tau, Arc::new(pupil))],
            Err(_) => Vec::new(),
        }
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

    fn order_derivatives(&self, wavelength_m: f64, parameter: usize) -> Option<optics::OrderDerivatives> {
        let (d_table, d_spread) = if parameter == optics::ATOM_PHASE_ERROR {
            self.phase_error_table_derivative(wavelength_m)
        } else if parameter == optics::ATOM_TRANSMISSION_ERROR {
            self.transmission_error_table_derivative(wavelength_m)
        } else {
            self.bias_table_derivative(wavelength_m, parameter)?
        };
        let table = self.table(wavelength_m);
        let (d_design, mut d_all) = self.sites.power_rates(&table, &d_table, wavelength_m);
        d_all += self.sites.count_weighted(&d_spread);
        let scale = self.pitch * self.pitch / (PI * self.aperture_radius().powi(2));
        Some(optics::OrderDerivatives {
            efficiencies: vec![d_design * scale],
            transmission: d_all * scale,
            fields: Vec::new(),
            tables: vec![d_table.into()],
        })
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
        let mut fabrication = String::new();
        if !self.bias.is_empty() {
            let b: Vec<String> = self.bias.iter().map(|&b| r(b).to_string()).collect();
            fabrication.push_str(&format!("; parameter bias {}", b.join(", ")));
        }
        if let Some((phase, amplitude)) = self.errors {
            fabrication.push_str(&format!(
                "; atom errors σ_φ = {} rad, σ_t = {} (expected field coherent, the rest stray light)",
                r(phase),
                r(amplitude)
            ));
        }
        if !self.zernike.is_empty() {
            let z: Vec<String> = self.zernike.iter().map(|(j, c)| format!("Z{j} = {} µm", r(c * 1e6))).collect();
            fabrication.push_str(&format!("; Zernike (Noll, RMS) {}", z.join(", ")));
        }
        format!(
            "2-D meta-atom library lens F/{} f0 = {} mm at λ0 = {} nm ({}; {} atoms in the aperture on {nx} × {ny} sites of {} µm{empty}; lattice {} × {} nm off the axis; {}{fabrication}; local periodic approximation, each cell's mean against the exact reference sphere)",
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

/// `(E[a e^{iδ}], E[a²])` of an atom of amplitude `|t|` under the random errors `δ ~ N(0, σ_φ²)`,
/// `ε ~ N(0, σ_t²)` with `a = min(max(1 + ε, 0), 1/|t|)` (the radial lens's draws: `1 + ε < 0`
/// taken as 0, `|t a|` capped at 1): `E[e^{iδ}] = e^{−σ_φ²/2}` (the normal's characteristic
/// function, real) and, with `Z` standard normal, `α = −1/σ_t`, `β = (1/|t| − 1)/σ_t`, the moments
/// of the normal clipped to `[0, 1/|t|]` (Johnson, Kotz & Balakrishnan, *Continuous Univariate
/// Distributions* 1, §10.1, the truncated normal's moments, plus the mass at the cap):
/// `E[a] = Φ(β) − Φ(α) + σ_t (φ(α) − φ(β)) + (1 − Φ(β))/|t|`,
/// `E[a²] = (1 + σ_t²)(Φ(β) − Φ(α)) + 2σ_t (φ(α) − φ(β)) + σ_t² (α φ(α) − β φ(β)) + (1 − Φ(β))/|t|²`.
fn expected_factor(t: f64, phase_sigma: f64, transmission_sigma: f64) -> (f64, f64) {
    let phase = (-0.5 * phase_sigma * phase_sigma).exp();
    let s = transmission_sigma;
    if s == 0.0 {
        // a ≤ 1/|t| is 1 for |t| ≤ 1
        return (phase, 1.0);
    }
    let pdf = |z: f64| if z.is_finite() { (-0.5 * z * z).exp() / (2.0 * PI).sqrt() } else { 0.0 };
    let cdf = |z: f64| 0.5 * libm::erfc(-z / std::f64::consts::SQRT_2);
    let alpha = -1.0 / s;
    let cap = if t > 0.0 { 1.0 / t } else { f64::INFINITY };
    let beta = (cap - 1.0) / s;
    let above = if cap.is_finite() { 1.0 - cdf(beta) } else { 0.0 };
    let (top, mass) = if cap.is_finite() { (cap, above) } else { (0.0, 0.0) };
    let inside = cdf(beta) - cdf(alpha);
    let edge = pdf(alpha) - pdf(beta);
    let moment = if beta.is_finite() { alpha * pdf(alpha) - beta * pdf(beta) } else { alpha * pdf(alpha) };
    let mean = inside + s * edge + top * mass;
    let square = (1.0 + s * s) * inside + 2.0 * s * edge + s * s * moment + top * top * mass;
    (phase * mean, square)
}

/// `(∂E[a e^{iδ}]/∂|t|, ∂E[a²]/∂|t|)` of [`expected_factor`]'s moments: `a = min(max(1 + ε, 0), c)`
/// with the cap `c = 1/|t|`, so `∂E[a]/∂c = P(1 + ε > c) = 1 − Φ(β)` and `∂E[a²]/∂c = 2c(1 − Φ(β))`
/// (the clipped normal's moments differentiated in their upper limit: the terms in β cancel,
/// Leibniz's rule on `E[min(X, c)] = ∫ min(x, c) dF`), `β = (c − 1)/σ_t`, and `∂c/∂|t| = −1/|t|²`;
/// the first times the phase errors' `e^{−σ_φ²/2}`. Both 0 without transmission errors (`a = 1`
/// for `|t| ≤ 1`) and at `|t| = 0` (no cap).
fn expected_factor_derivative(t: f64, phase_sigma: f64, transmission_sigma: f64) -> (f64, f64) {
    let s = transmission_sigma;
    if s == 0.0 || t <= 0.0 {
        return (0.0, 0.0);
    }
    let phase = (-0.5 * phase_sigma * phase_sigma).exp();
    let cap = 1.0 / t;
    let beta = (cap - 1.0) / s;
    let above = 0.5 * libm::erfc(beta / std::f64::consts::SQRT_2);
    let d_cap = -1.0 / (t * t);
    (phase * above * d_cap, 2.0 * cap * above * d_cap)
}

/// `(∂E[a e^{iδ}]/∂σ_t, ∂E[a²]/∂σ_t)` of [`expected_factor`]'s moments, `a = min(max(1 + σ_t Z,
/// 0), c)`: the clipping points move no mass (the integrand is continuous there), so
/// `∂E[a]/∂σ_t = E[Z; α < Z < β] = φ(α) − φ(β)` and `∂E[a²]/∂σ_t = 2E[(1 + σ_t Z) Z; α < Z < β]
/// = 2(φ(α) − φ(β)) + 2σ_t (Φ(β) − Φ(α) + α φ(α) − β φ(β))` (`α = −1/σ_t`, `β = (c − 1)/σ_t`,
/// `∫ z² φ = Φ − z φ`), the first times `e^{−σ_φ²/2}`. Both 0 at σ_t = 0 (the moments are even
/// in σ_t).
fn expected_factor_sigma_derivative(t: f64, phase_sigma: f64, transmission_sigma: f64) -> (f64, f64) {
    let s = transmission_sigma;
    if s == 0.0 {
        return (0.0, 0.0);
    }
    let phase = (-0.5 * phase_sigma * phase_sigma).exp();
    let pdf = |z: f64| if z.is_finite() { (-0.5 * z * z).exp() / (2.0 * PI).sqrt() } else { 0.0 };
    let cdf = |z: f64| 0.5 * libm::erfc(-z / std::f64::consts::SQRT_2);
    let alpha = -1.0 / s;
    let cap = if t > 0.0 { 1.0 / t } else { f64::INFINITY };
    let beta = (cap - 1.0) / s;
    let edge = pdf(alpha) - pdf(beta);
    let moment = if beta.is_finite() { alpha * pdf(alpha) - beta * pdf(beta) } else { alpha * pdf(alpha) };
    (phase * edge, 2.0 * edge + 2.0 * s * (cdf(beta) - cdf(alpha) + moment))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The clipped moments against a direct quadrature of the normal's density (the composite
    /// Simpson rule on [−12, 12] in z, 24 001 points, the clipping applied pointwise).
    #[test]
    fn expected_factor_matches_a_quadrature() {
        for &(t, sp, st) in
            &[(0.9f64, 0.0f64, 0.3f64), (0.99, 0.5, 0.1), (0.5, 0.2, 0.49), (1.0, 0.0, 0.2), (0.0, 0.3, 0.3)]
        {
            let n = 24_000;
            let h = 24.0 / n as f64;
            let cap = if t > 0.0 { 1.0 / t } else { f64::INFINITY };
            let (mut m1, mut m2) = (0.0, 0.0);
            for i in 0..=n {
                let z = -12.0 + i as f64 * h;
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                let density = (-0.5 * z * z).exp() / (2.0 * PI).sqrt();
                let a = (1.0 + st * z).max(0.0).min(cap);
                m1 += w * a * density;
                m2 += w * a * a * density;
            }
            let (m1, m2) = (m1 * h / 3.0 * (-0.5 * sp * sp).exp(), m2 * h / 3.0);
            let (e1, e2) = expected_factor(t, sp, st);
            // the kink at the clip points limits Simpson's rule to O(h²): 1e-7 at h = 1e-3
            assert!(
                (e1 - m1).abs() < 1e-7 && (e2 - m2).abs() < 1e-7,
                "|t| {t} σφ {sp} σt {st}: ({e1}, {e2}) vs ({m1}, {m2})"
            );
        }
    }

    /// The moments' derivative in `|t|` (through the cap `1/|t|`) against central differences of
    /// the moments (step 1e-4, Richardson-extrapolated from 2e-4: error O(h⁴) ≈ 1e-16 plus the
    /// rounding's 1e-12): within 1e-9.
    #[test]
    fn expected_factor_derivative_matches_central_differences() {
        for &(t, sp, st) in &[(0.9f64, 0.0f64, 0.3f64), (0.99, 0.5, 0.1), (0.5, 0.2, 0.49), (0.7, 0.1, 0.2)] {
            let central = |h: f64| {
                let (up, down) = (expected_factor(t + h, sp, st), expected_factor(t - h, sp, st));
                ((up.0 - down.0) / (2.0 * h), (up.1 - down.1) / (2.0 * h))
            };
            let (coarse, fine) = (central(2e-4), central(1e-4));
            let want = ((4.0 * fine.0 - coarse.0) / 3.0, (4.0 * fine.1 - coarse.1) / 3.0);
            let got = expected_factor_derivative(t, sp, st);
            assert!(got.0 != 0.0 && got.1 != 0.0, "{got:?}");
            assert!(
                (got.0 - want.0).abs() < 1e-9 && (got.1 - want.1).abs() < 1e-9,
                "|t| {t} σφ {sp} σt {st}: {got:?} vs {want:?}"
            );
        }
        assert_eq!(expected_factor_derivative(0.8, 0.3, 0.0), (0.0, 0.0));
    }

    /// The moments' derivative in σ_t against central differences of the moments in σ_t (steps
    /// 2e-4 and 1e-4, Richardson-extrapolated), also at `|t| = 0` (no cap): within 1e-9 (not at
    /// `|t| = 1/2`, where the clipping is symmetric about 1 and `∂E[a]/∂σ_t` is 0).
    #[test]
    fn expected_factor_sigma_derivative_matches_central_differences() {
        for &(t, sp, st) in
            &[(0.9f64, 0.0f64, 0.3f64), (0.99, 0.5, 0.1), (0.55, 0.2, 0.45), (0.0, 0.3, 0.3), (0.7, 0.1, 0.2)]
        {
            let central = |h: f64| {
                let (up, down) = (expected_factor(t, sp, st + h), expected_factor(t, sp, st - h));
                ((up.0 - down.0) / (2.0 * h), (up.1 - down.1) / (2.0 * h))
            };
            let (coarse, fine) = (central(2e-4), central(1e-4));
            let want = ((4.0 * fine.0 - coarse.0) / 3.0, (4.0 * fine.1 - coarse.1) / 3.0);
            let got = expected_factor_sigma_derivative(t, sp, st);
            assert!(got.0 != 0.0 && got.1 != 0.0, "{got:?}");
            assert!(
                (got.0 - want.0).abs() < 1e-9 && (got.1 - want.1).abs() < 1e-9,
                "|t| {t} σφ {sp} σt {st}: {got:?} vs {want:?}"
            );
        }
        assert_eq!(expected_factor_sigma_derivative(0.8, 0.3, 0.0), (0.0, 0.0));
    }
}
