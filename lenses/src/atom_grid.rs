//! A 2-D meta-atom layout on a square lattice ([`AtomGrid`]): the domain type a layout reader
//! (`scene::gds` for GDSII, `scene` for `.npy` grids) produces and the 2-D library lens
//! ([`crate::LibraryMapLens`]) consumes.

/// A layout on a square lattice: `values[p][y][x]` (row-major, parameter `p` of
/// [`AtomGrid::parameters`], nm), `NaN` and `empty[y][x]` where a site has no atom.
#[derive(Clone, Debug)]
pub struct AtomGrid {
    /// Lattice pitch, m.
    pub pitch_m: f64,
    /// Position (x, y) of site `[0][0]`, m.
    pub origin_m: (f64, f64),
    /// Sites along x.
    pub nx: usize,
    /// Sites along y.
    pub ny: usize,
    /// The parameter columns: `diameter_nm`, or `width_nm`, `length_nm`.
    pub parameters: Vec<String>,
    /// `[parameter, y, x]`, nm.
    pub values: Vec<f64>,
    /// `[y, x]`: no atom on the site.
    pub empty: Vec<bool>,
    /// `[y, x]`: a fin's angle θ in [0°, 180°) (fins only).
    pub theta_deg: Option<Vec<f64>>,
    /// The layout's statistics.
    pub stats: LayoutStats,
}

/// What a designer checks before fabrication.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayoutStats {
    /// Records read.
    pub records: u64,
    /// Bytes read (decompressed).
    pub bytes: u64,
    /// Cells in the library.
    pub cells: usize,
    /// Atoms after expansion.
    pub atoms: u64,
    /// Each parameter's (min, max), nm.
    pub parameter_range: Vec<(f64, f64)>,
    /// The largest distance of an atom's centre from its lattice site, m.
    pub max_off_lattice_m: f64,
    /// Sites with two or more atoms (the first one is kept).
    pub doubly_occupied_sites: u64,
    /// Sites inside the grid's bounding box without an atom.
    pub empty_sites: u64,
    /// The largest relative distance of a pillar's vertex from its circle (0 for a regular
    /// polygon): how far the vertex-count correction is from exact.
    pub max_vertex_deviation: f64,
    /// The drawing's resolution (a GDSII file's database unit), m; 0 for a grid of numbers.
    pub database_unit_m: f64,
}
