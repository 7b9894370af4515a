//! The FFT engine: sampled pupils (apertures, composite pupils of zones, wavefronts beyond
//! defocus) by FFT, one complex OTF grid per spectral node and order (docs/physics.md, "General
//! pupils"); tabulated orders are read directly beside the grids.

use std::f64::consts::PI;
use std::sync::Arc;

use num_complex::Complex64;

use super::{AzimuthalMean, Polychromatic};
use crate::Error;
use crate::fft::{Aperture, Otf, OtfPlan, SampledPupil, SampledZones, ZoneField};
use crate::lens::{Field, LensModel, Order, Pupil};
use crate::radial::TableRule;
use crate::table::OtfTable;

use super::frequency::{FIRST_AZIMUTHS, MAX_AZIMUTHS};
use super::spectral::{Node, Nodes, Scene, needs_grid};
use super::{AZIMUTH_SHARE, Engine, FFT_MEMORY_BUDGET, FrequencyRule, OtfEngine};

pub(super) struct FftNode {
    lambda: f64,
    weight: f64,
    shift: [f64; 2],
    kind: FftKind,
    /// the grid's derivative in the obscuration ε, computed with the grid in the value's pass
    /// where the scene asks for it ([`Settings::edge_lane`](super::Settings::edge_lane)) and the
    /// order's pupil is an aperture of disc shape ([`FftLayer::kind_and_edge_lane`])
    lane: Option<Otf>,
}

/// How an order's OTF is read on the FFT layer.
pub(super) enum FftKind {
    /// A complex OTF grid: a sampled pupil or a composite of zones (shared with other engines
    /// of the same lens through [`SharedGrids`]).
    Grid(Arc<Otf>),
    /// A tabulated OTF ([`Pupil::Table`]), read at ν directly.
    Table(Arc<OtfTable>),
}

/// The FFT layer: one complex OTF grid per spectral node and order.
pub(super) struct FftPath {
    nodes: Vec<FftNode>,
    pub pupil_samples: usize,
    pub padded: usize,
}

impl std::fmt::Debug for FftPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "FftPath {{ {} nodes, N = {}, M = {} }}", self.nodes.len(), self.pupil_samples, self.padded)
    }
}

impl FftPath {
    /// One complex OTF grid per spectral sample and order of `nodes`, from one reused plan (a
    /// tabulated order is read directly); sampled pupils and zones are cached while their
    /// apertures (the same `Arc`s) stay the same. The grids are counted against
    /// [`FFT_MEMORY_BUDGET`] before any is made.
    pub fn build(scene: &Scene<'_>, nodes: &Nodes, pupil_samples: usize) -> Result<FftPath, Error> {
        let lambda_max = nodes.samples.iter().map(|s| s.0).fold(0.0, f64::max);
        let s_max = (scene.max_frequency * lambda_max * scene.f_number).min(1.0);
        let mut layer = FftLayer::new(pupil_samples, s_max, scene.lens.numerical_aperture())?;
        // memory budget: one (2K + 1)² complex grid per spectral node and order on the grid path,
        // counted before any is made (a 300 nm band at 1024 samples would hold 12 GB)
        let side = 2 * layer.plan.max_lag() + 1;
        let grid_bytes = (side * side * std::mem::size_of::<Complex64>()) as f64;
        let mut grids = nodes.nodes.iter().filter(|n| n.table.is_none()).count();
        if scene.edge_lane {
            // each grid may carry its obscuration lane beside it
            grids *= 2;
        }
        if grids as f64 * grid_bytes > FFT_MEMORY_BUDGET {
            return Err(Error::WorkBudget {
                grids,
                grid_mb: grid_bytes / 1e6,
                total_gib: grids as f64 * grid_bytes / f64::from(1u32 << 30),
                budget_gib: FFT_MEMORY_BUDGET / f64::from(1u32 << 30),
                pupil_samples,
            });
        }
        let mut out = Vec::new();
        for &(lambda, weight, part) in &nodes.samples {
            if weight == 0.0 {
                continue;
            }
            for (o, order) in scene.part(part).lens.orders(lambda, scene.field).into_iter().enumerate() {
                if order.efficiency == 0.0 {
                    // no light in this order here (a factored part's zone outside its band): no grid
                    continue;
                }
                let (kind, lane) = if scene.edge_lane {
                    layer.kind_and_edge_lane(&order, lambda)?
                } else if let Some(shared) = scene.shared {
                    let key = GridKey::of(&scene.part(part), pupil_samples, s_max, lambda, o);
                    (shared.kind(key, || layer.kind(&order, lambda))?, None)
                } else {
                    (layer.kind(&order, lambda)?, None)
                };
                out.push(FftNode {
                    lambda,
                    weight: weight * order.efficiency,
                    shift: order.wavefront.image_shift_m,
                    kind,
                    lane,
                });
            }
        }
        Ok(FftPath { nodes: out, pupil_samples, padded: layer.plan.padded_len() })
    }

    /// Whether the pupils of `nodes` sampled at `pupil_samples` alias their phase: `Some(true)`
    /// where some single aperture's wavefront turns by more than [`PHASE_NYQUIST_WAVES`] between
    /// neighbouring samples, `None` where a pupil is a composite of zones (whose ring edges
    /// converge irregularly whatever the phase does). Samples the pupils only: no grid.
    fn aliases_phase(scene: &Scene<'_>, nodes: &Nodes, pupil_samples: usize) -> Result<Option<bool>, Error> {
        // (the layer's plan is not used: the smallest one)
        let mut layer = FftLayer::new(pupil_samples, 1e-9, scene.lens.numerical_aperture())?;
        let mut aliased = false;
        for &(lambda, weight, part) in &nodes.samples {
            if weight == 0.0 {
                continue;
            }
            for order in scene.part(part).lens.orders(lambda, scene.field) {
                match &order.pupil {
                    Pupil::Table(_) => {}
                    Pupil::Zones(_) | Pupil::Map(_) => return Ok(None),
                    _ => {
                        let slot = layer.pupil(&order)?;
                        aliased |= layer.pupils[slot].1.max_opd_step_m() > PHASE_NYQUIST_WAVES * lambda;
                    }
                }
            }
        }
        Ok(Some(aliased))
    }

    /// `Σ weight × OTF` over the grids along `azimuth` (radians from x), each times
    /// `exp(−2πi ν u·Δ)` for its image shift; not normalized.
    pub fn sum_along(&self, scene: &Scene<'_>, frequency: f64, azimuth: f64) -> Complex64 {
        self.sum_along_reading(scene, frequency, azimuth, |otf, x, y| otf.at_xy(x, y))
    }

    /// [`sum_along`](Self::sum_along) of several paths of one lens and field at once (`paths`:
    /// each with its scene), each the same to the bit: a grid the paths share
    /// ([`SharedGrids`]) is read once at the point its wavelength asks for (the same point for
    /// every path: the point depends on the wavelength, `F#`, ν and the azimuth alone), and
    /// weighed by each path's own weight.
    pub fn sums_along(paths: &[(&FftPath, &Scene<'_>)], frequency: f64, azimuth: f64) -> Vec<Complex64> {
        // the grids read so far and their values, in the order read: the other paths' nodes
        // that coincide come in the same order
        let mut read: Vec<(*const Otf, Complex64)> = Vec::new();
        let mut sums = Vec::with_capacity(paths.len());
        for (path, scene) in paths {
            let mut cursor = 0;
            let mut fresh: Vec<(*const Otf, Complex64)> = Vec::new();
            let sum = path.sum_along_reading(scene, frequency, azimuth, |otf, x, y| {
                let grid = Arc::as_ptr(otf);
                if let Some(i) = read[cursor..].iter().position(|(g, _)| *g == grid) {
                    cursor += i + 1;
                    return read[cursor - 1].1;
                }
                let value = otf.at_xy(x, y);
                fresh.push((grid, value));
                value
            });
            if read.is_empty() {
                read = fresh;
            }
            sums.push(sum);
        }
        sums
    }

    /// [`sum_along`](Self::sum_along) with each grid read by `read(grid, sx, sy)` (its
    /// interpolant at `(sx, sy)`).
    #[inline]
    fn sum_along_reading(
        &self,
        scene: &Scene<'_>,
        frequency: f64,
        azimuth: f64,
        mut read: impl FnMut(&Arc<Otf>, f64, f64) -> Complex64,
    ) -> Complex64 {
        let (sin_a, cos_a) = azimuth.sin_cos();
        let k = -2.0 * PI * frequency;
        let nuf = frequency.abs() * scene.f_number;
        // OTF(−ν) = OTF(ν)*: read the grid at |ν| along the azimuth turned by π
        let azimuth = if frequency < 0.0 { azimuth + PI } else { azimuth };
        let from_field = azimuth - scene.field_direction();
        // the direction once: every grid is read along it (`Otf::at` would take it per grid)
        let (read_sin, read_cos) = azimuth.sin_cos();
        let mut sum = Complex64::new(0.0, 0.0);
        for n in &self.nodes {
            let s = nuf * n.lambda;
            if s >= 1.0 {
                continue;
            }
            let mut v = match &n.kind {
                FftKind::Grid(otf) if s <= otf.s_max() => read(otf, s * read_cos, s * read_sin) * n.weight,
                FftKind::Grid(_) => continue,
                FftKind::Table(t) => Complex64::new(t.value(n.lambda, frequency, from_field) * n.weight, 0.0),
            };
            let [dx, dy] = n.shift;
            if dx != 0.0 || dy != 0.0 {
                let (ps, pc) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
                v *= Complex64::new(pc, ps);
            }
            sum += v;
        }
        sum
    }

    /// [`sum_along`](Self::sum_along) at `frequency ≥ 0` and its derivative with respect to
    /// `azimuth` ([`sum_along_and_move`](Self::sum_along_and_move) turning): each grid's
    /// interpolant turned (`s (−sin φ, cos φ)·∇`, [`Otf::at_xy_and_slope`]), and each shift's
    /// phase `−2πi ν u⊥·Δ` (`u⊥ = (−sin φ, cos φ)`). A table is read from the field direction,
    /// so it turns with it: its derivative is 0 where the azimuth is the field direction's (the
    /// only use, [`FftPath::gradient_over_azimuth`]'s field lanes).
    fn sum_along_and_turn(&self, scene: &Scene<'_>, frequency: f64, azimuth: f64) -> (Complex64, Complex64) {
        self.sum_along_and_move(scene, frequency, azimuth, true)
    }

    /// [`sum_along`](Self::sum_along) at `frequency ≥ 0` and its derivative with respect to
    /// `ln F#` at fixed pupils: each grid's interpolant read at `s = νλF#` moves along
    /// `s (cos φ, sin φ)·∇` ([`Otf::at_xy_and_slope`]); the shifts' phases (in ν) and a
    /// table (read at ν) do not move.
    fn sum_along_and_scale(&self, scene: &Scene<'_>, frequency: f64, azimuth: f64) -> (Complex64, Complex64) {
        self.sum_along_and_move(scene, frequency, azimuth, false)
    }

    /// The sum along `azimuth` and its derivative as the readings turn with the azimuth
    /// (`turn`) or move along it with the frequency scale (else), as the two callers above say.
    fn sum_along_and_move(
        &self,
        scene: &Scene<'_>,
        frequency: f64,
        azimuth: f64,
        turn: bool,
    ) -> (Complex64, Complex64) {
        let (sin_a, cos_a) = azimuth.sin_cos();
        let k = -2.0 * PI * frequency;
        let nuf = frequency * scene.f_number;
        let from_field = azimuth - scene.field_direction();
        let (mut sum, mut moved) = (Complex64::new(0.0, 0.0), Complex64::new(0.0, 0.0));
        for n in &self.nodes {
            let s = nuf * n.lambda;
            if s >= 1.0 {
                continue;
            }
            let (mut v, mut d) = match &n.kind {
                FftKind::Grid(otf) if s <= otf.s_max() => {
                    let (dx, dy) = if turn { (-s * sin_a, s * cos_a) } else { (s * cos_a, s * sin_a) };
                    let (v, d) = otf.at_xy_and_slope(s * cos_a, s * sin_a, dx, dy);
                    (v * n.weight, d * n.weight)
                }
                FftKind::Grid(_) => continue,
                FftKind::Table(t) => {
                    (Complex64::new(t.value(n.lambda, frequency, from_field) * n.weight, 0.0), Complex64::new(0.0, 0.0))
                }
            };
            let [dx, dy] = n.shift;
            if dx != 0.0 || dy != 0.0 {
                let (ps, pc) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
                let phase = Complex64::new(pc, ps);
                d = if turn {
                    d * phase + v * phase * Complex64::new(0.0, k * (-dx * sin_a + dy * cos_a))
                } else {
                    d * phase
                };
                v *= phase;
            }
            sum += v;
            moved += d;
        }
        (sum, moved)
    }

    /// The derivative of this level's mean over `count` azimuths from `first` (the value's
    /// [`fixed_mean`] along each) with respect to `ln F#` at fixed pupils: the same frequencies
    /// in ν, azimuths, spectral weights, pixel MTF and normalization as the value, each grid's
    /// reading moving with `s = νλF#` ([`sum_along_and_scale`](Self::sum_along_and_scale)),
    /// `∂|O| = Re(O* ∂O)/|O|` (0 where `O = 0`): the discrete rule's exact derivative, where
    /// the by-parts identity `P(ν_N)|O(ν_N)| − M̄ − P_ν` is the continuous rule's
    /// (docs/physics.md, "Gradients: the multiplexed lens").
    pub(super) fn scale_over_azimuth(&self, scene: &Scene<'_>, nodes: &Nodes, first: f64, count: usize) -> f64 {
        let lo = self.nodes.iter().map(|n| n.lambda).fold(f64::INFINITY, f64::min);
        let top = scene.max_frequency.min(1.0 / (lo * scene.f_number));
        let (panels, _) = fixed_rule(top, self.finest_cell(scene.f_number));
        let rule = crate::quad::gauss_legendre(crate::quad::FIXED_ORDER);
        let h = top / panels as f64;
        let pixel = |nu: f64| scene.pixel_pitch.map_or(1.0, |p| crate::otf::pixel_mtf(p, nu));
        let mut total = 0.0;
        for j in 0..count {
            let azimuth = first + PI * j as f64 / count as f64;
            for p in 0..panels {
                let mid = h * (p as f64 + 0.5);
                for &(x, w) in &rule {
                    let nu = mid + 0.5 * h * x;
                    let (o, d) = self.sum_along_and_scale(scene, nu, azimuth);
                    let modulus = o.norm();
                    if modulus > 0.0 {
                        total += 0.5 * h * w * pixel(nu) * (o.conj() * d).re / modulus;
                    }
                }
            }
        }
        total / (nodes.total_weight * scene.max_frequency * count as f64)
    }

    /// The finest grid cell in ν (cycles/m): the interpolated grids kink at every cell edge.
    pub fn finest_cell(&self, f_number: f64) -> f64 {
        self.nodes
            .iter()
            .filter_map(|n| match &n.kind {
                FftKind::Grid(otf) => Some(1.0 / (otf.n() as f64 * n.lambda * f_number)),
                FftKind::Table(_) => None,
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// The FFT grids of engines of one lens and field under several spectra
/// ([`Polychromatic::with_shared_grids`](super::Polychromatic::with_shared_grids)): each grid
/// made once and read by every engine whose node asks for it. A grid depends on its order's
/// pupil at the node's wavelength (the lens, the field, the wavelength and the order's place
/// among the lens's orders there), the pupil sampling `N` and the frequency extent `s_max` of
/// the plan (its lags); not on the spectrum's weights. Those are the key, bit for bit, so a
/// grid found is the one the engine would make. Hold it for engines of one lens: the lens is
/// known by its address.
#[derive(Debug, Default)]
pub struct SharedGrids {
    grids: std::sync::Mutex<SharedMap>,
}

#[derive(Debug, Default)]
struct SharedMap {
    grids: std::collections::HashMap<GridKey, Arc<Otf>>,
    /// grids found here, and grids made
    found: usize,
    made: usize,
}

/// What a grid depends on ([`SharedGrids`]): the lens's address, the field's angles, `N`,
/// `s_max`, the wavelength (bits) and the order's place.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct GridKey {
    lens: usize,
    field: [u64; 2],
    pupil_samples: usize,
    s_max: u64,
    lambda: u64,
    order: usize,
}

impl GridKey {
    fn of(scene: &Scene<'_>, pupil_samples: usize, s_max: f64, lambda: f64, order: usize) -> GridKey {
        GridKey {
            lens: std::ptr::from_ref(scene.lens).cast::<()>() as usize,
            field: [scene.field.x_rad.to_bits(), scene.field.y_rad.to_bits()],
            pupil_samples,
            s_max: s_max.to_bits(),
            lambda: lambda.to_bits(),
            order,
        }
    }
}

impl SharedGrids {
    /// An empty set of grids.
    pub fn new() -> SharedGrids {
        SharedGrids::default()
    }

    /// How many grids the engines found here and how many they made.
    pub fn found_and_made(&self) -> (usize, usize) {
        let map = self.grids.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        (map.found, map.made)
    }

    /// Drops the grids held here: the engines built keep theirs, later ones make their own.
    pub fn forget(&self) {
        self.grids.lock().unwrap_or_else(std::sync::PoisonError::into_inner).grids.clear();
    }

    /// The grid of `key`, else `make`'s (kept where it is a grid).
    fn kind(&self, key: GridKey, make: impl FnOnce() -> Result<FftKind, Error>) -> Result<FftKind, Error> {
        let mut map = self.grids.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(grid) = map.grids.get(&key) {
            let grid = grid.clone();
            map.found += 1;
            return Ok(FftKind::Grid(grid));
        }
        let kind = make()?;
        if let FftKind::Grid(grid) = &kind {
            map.made += 1;
            map.grids.insert(key, grid.clone());
        }
        Ok(kind)
    }
}

/// Spectral nodes read through FFT grids: one sampling fixed by the settings, or the two
/// samplings `N/2` and `N` of a [`SamplingPlan`](crate::fft::SamplingPlan) chosen from the
/// tolerance, whose means are extrapolated (Richardson, `fft::sampling`).
#[derive(Debug)]
pub(super) struct Grids<'a> {
    pub scene: Scene<'a>,
    pub nodes: Nodes,
    pub fft: FftPath,
    /// the coarse sampling `N/2` and the plan, when the tolerance chose `N`
    pub coarse: Option<(FftPath, crate::fft::SamplingPlan)>,
    /// whether the OTF is read from the coarse sampling (while the frequency rule takes its mean)
    pub reading_coarse: std::cell::Cell<bool>,
    /// the means along the azimuths the sampling choice read at the accepted pair of levels
    read: Option<ReadMeans>,
}

/// The means along azimuths that the sampling choice read at its accepted levels: slot `j`, at
/// `first + π j / MAX_AZIMUTHS`, holds `(M_{N/2}, M_N)` by [`fixed_mean`] where it was read.
#[derive(Debug)]
struct ReadMeans {
    first: f64,
    means: Vec<Option<(f64, f64)>>,
}

/// Share of the tolerance the FFT sampling may spend (the spectral rule spends its own share,
/// the fixed frequency rule is converged far below either).
pub(super) const SAMPLING_SHARE: f64 = 0.5;

/// Seconds for one OTF grid at 256 pupil samples (`cargo bench -p asnr-optics --bench kernels -- "fft
/// OtfPlan"`: 2.1 ms; the time grows as N²).
const SECONDS_PER_GRID_256: f64 = 2.1e-3;

/// The Nyquist limit of a sampled pupil phase: half a wave between neighbouring samples. A
/// coarser grid aliases the wavefront, and the mean is not yet in the range where the levels
/// converge at their measured order: coma 0.5 µm on the paper scene (whose band's flanks carry 15
/// waves of defocus, 2 waves a sample at N = 32) moves its mean along x by 9.2e-5, 1.2e-4 and
/// 4.7e-5 from N = 32 to 64, 128 and 256, an observed order of −0.4 from the aliased N = 32 (0.3
/// over the nodes it resolves) and 1.4 above it, while the pair (64, 128) alone was within 7.6e-6.
const PHASE_NYQUIST_WAVES: f64 = 0.5;

/// The time the grids of one sampling level may take: past it the scene stops with the numbers
/// (three levels are held, N/4 with about a sixteenth of the grids of N, and a refinement builds
/// one more).
const GRID_TIME_BUDGET: f64 = 3.0;

impl<'a> Grids<'a> {
    /// The engine for `nodes`: at `pupil_samples` if given; else at the sampling the tolerance
    /// asks for (`fft::pupil_samples_for` with [`SAMPLING_SHARE`] of it), verified by the
    /// Richardson extrapolation of the means at `N/2` and `N` and refined (doubling `N`) until
    /// the estimate is within it, or [`Error::PupilSampling`] beyond reach. The mean judged is
    /// the one the ASNR takes: the mean MTF averaged over azimuth, by the rule of
    /// `Polychromatic::mean_mtf_over_azimuth` (the azimuths from the field direction, as many as
    /// the fine level needs for [`AZIMUTH_SHARE`] of the tolerance), the same azimuths at the
    /// three levels.
    pub fn new(scene: Scene<'a>, nodes: Nodes, pupil_samples: Option<usize>, tolerance: f64) -> Result<Self, Error> {
        // the sampling works to its share of the tolerance; a refusal speaks of the whole
        Self::sampled(scene, nodes, pupil_samples, tolerance).map_err(|e| match e {
            Error::PupilSampling { tolerance, needed, limit, reachable } => Error::PupilSampling {
                tolerance: tolerance / SAMPLING_SHARE,
                needed,
                limit,
                reachable: reachable / SAMPLING_SHARE,
            },
            other => other,
        })
    }

    fn sampled(scene: Scene<'a>, nodes: Nodes, pupil_samples: Option<usize>, tolerance: f64) -> Result<Self, Error> {
        if let Some(n) = pupil_samples {
            let fft = FftPath::build(&scene, &nodes, n)?;
            return Ok(Grids {
                scene,
                nodes,
                fft,
                coarse: None,
                reading_coarse: std::cell::Cell::new(false),
                read: None,
            });
        }
        let lambda_max = nodes.samples.iter().map(|s| s.0).fold(0.0, f64::max);
        let s_max = (scene.max_frequency * lambda_max * scene.f_number).clamp(1e-6, 1.0);
        let grids = nodes.nodes.iter().filter(|n| n.table.is_none()).count().max(1);
        let mut plan = crate::fft::pupil_samples_for(SAMPLING_SHARE * tolerance, s_max, grids)?;
        // the time budget caps N too: the grids of one level (grids × N² at 2.1 ms per grid of
        // 256 samples) within GRID_TIME_BUDGET
        let by_time = (256.0 * (GRID_TIME_BUDGET / (grids as f64 * SECONDS_PER_GRID_256)).sqrt()) as usize;
        plan.limit = plan.limit.min(by_time - by_time % 2);
        if plan.samples > plan.limit && crate::fft::reachable(plan.limit) <= plan.tolerance {
            // the padding's free samples went past the limit, the tolerance itself does not
            plan.samples = plan.limit;
        }
        if plan.samples > plan.limit {
            return Err(Error::PupilSampling {
                tolerance: plan.tolerance,
                needed: plan.samples,
                limit: plan.limit,
                reachable: crate::fft::reachable(plan.limit),
            });
        }
        // each level is judged by the quantity the ASNR takes: the mean MTF averaged over
        // azimuth by its own rule (`mean_mtf_over_azimuth`: nested trapezoids from the field
        // direction), on the same azimuths at every level so that the levels differ by their
        // sampling alone; the fine level chooses how many
        let first = scene.field_direction();
        let tolerance_over_azimuth = AZIMUTH_SHARE * tolerance;
        let level = |n: usize| FftPath::build(&scene, &nodes, n).map(Level::new);
        let aliased = |n: usize| FftPath::aliases_phase(&scene, &nodes, n).map(|a| a == Some(true));
        // a composite pupil: the mean at N, its error by the observed order (fft::sampling)
        if FftPath::aliases_phase(&scene, &nodes, plan.coarse() / 2)?.is_none() {
            plan.rule = crate::fft::ErrorRule::FinestLevel;
        }
        // three levels: N/4 checks that the pair (N/2, N) is in its asymptotic range (a
        // composite pupil's ring edges can make N/2 and N agree by chance: the concentric
        // segmented lens went 0.3104, 0.3087, 0.3110 at N = 32, 64, 128 and settles at 0.3119)
        let mut quarter = (level(plan.coarse() / 2)?, aliased(plan.coarse() / 2)?);
        let mut coarse = level(plan.coarse())?;
        let mut fine = level(plan.samples)?;
        loop {
            let count = fine.azimuths(&scene, &nodes, first, tolerance_over_azimuth);
            let full = fine.over_azimuth(&scene, &nodes, first, count);
            let half = coarse.over_azimuth(&scene, &nodes, first, count);
            let quarter_mean = quarter.0.over_azimuth(&scene, &nodes, first, count);
            let estimate = match plan.estimate(quarter_mean, half, full) {
                // the study's gain on the extrapolated value (`fft::extrapolation_gain`) was
                // measured along x; averaged over azimuth the grids are read between their lines
                // too, whose interpolation error falls faster: astigmatism 0.2 µm on the paper
                // scene moved 1.3e-3, 2.7e-4, 5.6e-5, 1.7e-5 from N = 32 to 512, an order of
                // 2.3 falling to 1.7, where p = 1.5 overshot by 1.8e-4 at (64, 128) with an
                // estimate of 4.7e-5. The correction itself bounds the extrapolated value's
                // error for any order ≥ 1 (the value moves by at most that much between p = 1
                // and p → ∞), and the order is checked below
                e if plan.rule == crate::fft::ErrorRule::Richardson => {
                    crate::fft::Extrapolated { error: e.correction, converged: e.correction <= plan.tolerance, ..e }
                }
                e => e,
            };
            // accepted where the estimate passes and the levels converge at least at first order
            // (or have settled far below the tolerance)
            let order = crate::fft::observed_order(quarter_mean, half, full);
            let settled = (full - half).abs() <= 0.1 * plan.tolerance * full.abs();
            // an N/4 level that aliases the pupil phase of single apertures (the flanks of a
            // broad band) is not in the asymptotic range, and its order says nothing: the pair's
            // own estimate decides, which the study found 0.9–1.3 times the true error for
            // single apertures from N = 128 on (fft::sampling), provided the three levels move
            // one way (a chance agreement turns back). Composite pupils keep the order check.
            let monotone = (half - quarter_mean) * (full - half) > 0.0;
            let aliased_quarter = quarter.1 && monotone && plan.samples >= crate::fft::MIN_CHOSEN_SAMPLES;
            if estimate.converged && (order >= 1.0 || settled || aliased_quarter) {
                break;
            }
            plan = match plan.refine(estimate.error) {
                Ok(next) => next,
                // doubling would pass the limit: the limit itself is tried before giving up
                Err(_) if plan.samples + 2 <= plan.limit => {
                    crate::fft::SamplingPlan { samples: plan.limit - plan.limit % 2, ..plan }
                }
                Err(e) => return Err(e),
            };
            // the old levels move down when N doubled (Richardson needs N/2), with the means
            // along the azimuths they have read
            let doubled = fine.path.pupil_samples == plan.coarse();
            if doubled {
                let old_coarse = std::mem::replace(&mut coarse, fine);
                quarter = (old_coarse, aliased(plan.coarse() / 2)?);
            } else {
                quarter = (level(plan.coarse() / 2)?, aliased(plan.coarse() / 2)?);
                coarse = level(plan.coarse())?;
            }
            fine = level(plan.samples)?;
        }
        let means = coarse.means.iter().zip(&fine.means).map(|(c, f)| c.zip(*f)).collect();
        Ok(Grids {
            scene,
            nodes,
            fft: fine.path,
            coarse: Some((coarse.path, plan)),
            reading_coarse: std::cell::Cell::new(false),
            read: Some(ReadMeans { first, means }),
        })
    }

    fn path(&self) -> &FftPath {
        match &self.coarse {
            Some((coarse, _)) if self.reading_coarse.get() => coarse,
            _ => &self.fft,
        }
    }
}

/// One sampling level of the choice in [`Grids::new`]: its grids and the means along the
/// azimuths read so far, slot `j` at `first + π j / MAX_AZIMUTHS` (the nested trapezoid rules
/// of `M` azimuths read every `MAX_AZIMUTHS / M`-th slot, so a refinement in `M`, or a level
/// moved down when `N` doubles, reuses what it has read).
struct Level {
    path: FftPath,
    means: Vec<Option<f64>>,
}

impl Level {
    fn new(path: FftPath) -> Level {
        Level { path, means: vec![None; MAX_AZIMUTHS] }
    }

    /// The trapezoid rule of `count` azimuths (a power of two from [`FIRST_AZIMUTHS`] to
    /// [`MAX_AZIMUTHS`]) on `[first, first + π)` of the mean MTF along each ([`fixed_mean`]).
    fn over_azimuth(&mut self, scene: &Scene<'_>, nodes: &Nodes, first: f64, count: usize) -> f64 {
        let step = MAX_AZIMUTHS / count;
        let mut sum = 0.0;
        for j in (0..MAX_AZIMUTHS).step_by(step) {
            sum += *self.means[j].get_or_insert_with(|| {
                let azimuth = first + PI * j as f64 / MAX_AZIMUTHS as f64;
                let path = &self.path;
                fixed_mean(scene, path, &|nu| (path.sum_along(scene, nu, azimuth) / nodes.total_weight).norm())
            });
        }
        sum / count as f64
    }

    /// The azimuths the rule over azimuth takes on this level
    /// (`Polychromatic::mean_mtf_over_azimuth`'s rule): doubled from [`FIRST_AZIMUTHS`] until
    /// two successive averages differ by at most `tolerance` relative to the mean, or
    /// [`MAX_AZIMUTHS`].
    fn azimuths(&mut self, scene: &Scene<'_>, nodes: &Nodes, first: f64, tolerance: f64) -> usize {
        let mut count = FIRST_AZIMUTHS;
        let mut average = self.over_azimuth(scene, nodes, first, count);
        while count < MAX_AZIMUTHS {
            count *= 2;
            let refined = self.over_azimuth(scene, nodes, first, count);
            let change = (refined - average).abs();
            average = refined;
            if change <= tolerance * average.abs() {
                break;
            }
        }
        count
    }
}

/// The mean over `[0, top]` (top the frequency limit, or the highest cutoff below it) of
/// `P(ν) value(ν)` on the FFT path: the interpolated grid is only continuous across its cells
/// (kinks at every grid line of every node), so a fixed composite rule at half the finest
/// cell ([`fixed_rule`]), not an adaptive one, integrates it to well below the FFT path's own
/// error. The integral is divided by `max_frequency` (the OTF is zero beyond `top`).
fn fixed_mean(scene: &Scene<'_>, path: &FftPath, value: &dyn Fn(f64) -> f64) -> f64 {
    let lo = path.nodes.iter().map(|n| n.lambda).fold(f64::INFINITY, f64::min);
    let top = scene.max_frequency.min(1.0 / (lo * scene.f_number));
    let (panels, _) = fixed_rule(top, path.finest_cell(scene.f_number));
    let pixel = |nu: f64| scene.pixel_pitch.map_or(1.0, |p| crate::otf::pixel_mtf(p, nu));
    crate::quad::composite_fixed(0.0, top, panels, |nu| value(nu).abs() * pixel(nu)) / scene.max_frequency
}

/// The panels of the fixed composite rule over `[0, top]` for grids whose finest cell in ν is
/// `cell`: half a cell each (at least 8, at most 65 536; the error this leaves is measured at
/// [`crate::quad::FIXED_ORDER`]), and the OTF evaluations.
pub(super) fn fixed_rule(top: f64, cell: f64) -> (usize, usize) {
    let panels = ((2.0 * top / cell).ceil() as usize).clamp(8, 1 << 16);
    (panels, panels * crate::quad::FIXED_ORDER)
}

impl OtfEngine for Grids<'_> {
    fn engine(&self) -> Engine {
        Engine::Fft {
            pupil_samples: self.fft.pupil_samples,
            padded: self.fft.padded,
            coarse: self.coarse.as_ref().map(|(c, _)| c.pupil_samples),
            extrapolated: self.richardson().is_some(),
        }
    }

    fn nodes(&self) -> &Nodes {
        &self.nodes
    }

    fn f_number(&self) -> f64 {
        self.scene.f_number
    }

    fn otf(&self, frequency: f64) -> f64 {
        // no rotational symmetry to rely on: the real part along +x
        self.otf_along(frequency, 0.0).re
    }

    fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64 {
        self.path().sum_along(&self.scene, frequency, azimuth) / self.nodes.total_weight
    }

    fn fft_reading(&self) -> Option<(&FftPath, &Scene<'_>, f64)> {
        Some((self.path(), &self.scene, self.nodes.total_weight))
    }

    fn direction_dependent(&self) -> bool {
        true
    }

    fn frequency_rule(&self) -> FrequencyRule {
        FrequencyRule::Fixed { cell: self.fft.finest_cell(self.scene.f_number) }
    }

    fn richardson(&self) -> Option<crate::fft::SamplingPlan> {
        self.coarse.as_ref().map(|(_, plan)| *plan).filter(|p| p.rule == crate::fft::ErrorRule::Richardson)
    }

    fn read_coarse(&self, on: bool) {
        self.reading_coarse.set(on && self.coarse.is_some());
    }

    fn wavefront_gradient_over_azimuth(
        &self,
        first: f64,
        count: usize,
        directions: &[WavefrontDirection],
    ) -> Result<Option<Vec<f64>>, Error> {
        self.gradient_over_azimuth(first, count, directions, None)
    }

    fn wavefront_gradient_over_azimuth_over_noise(
        &self,
        first: f64,
        count: usize,
        directions: &[WavefrontDirection],
        noise: &super::NoiseShape,
    ) -> Result<Option<Vec<f64>>, Error> {
        self.gradient_over_azimuth(first, count, directions, Some(noise))
    }

    fn scale_over_azimuth(&self, first: f64, count: usize) -> Option<f64> {
        let fine = self.fft.scale_over_azimuth(&self.scene, &self.nodes, first, count);
        let Some(plan) = self.richardson() else { return Some(fine) };
        let Some((coarse_path, _)) = &self.coarse else { return Some(fine) };
        let coarse = coarse_path.scale_over_azimuth(&self.scene, &self.nodes, first, count);
        Some(plan.extrapolate(coarse, fine).value)
    }

    fn means_along(&self, azimuth: f64) -> Option<(f64, f64)> {
        let ReadMeans { first, means } = self.read.as_ref()?;
        // the slot of `azimuth`, if it is one (the rule over azimuth reads `first + π k / M`)
        let slot = (azimuth - first) / PI * MAX_AZIMUTHS as f64;
        let j = slot.round();
        if (slot - j).abs() > 1e-9 || j < 0.0 || j >= MAX_AZIMUTHS as f64 {
            return None;
        }
        means[j as usize]
    }
}

/// Cache size of sampled pupils and zone sets on the FFT layer (a lens has a few apertures).
const SAMPLED_CACHE: usize = 8;

/// The FFT layer's state while its grids are computed: one plan, and the sampled pupils and
/// zone sets of the apertures seen so far (kept while the lens hands out the same `Arc`s).
struct FftLayer {
    n: usize,
    plan: OtfPlan,
    numerical_aperture: f64,
    circle: Arc<Aperture>,
    square: Arc<Aperture>,
    pupils: Vec<(Arc<Aperture>, SampledPupil)>,
    zones: Vec<SampledZones>,
    fields: Vec<ZoneField>,
    radial: RadialCache,
}

impl FftLayer {
    fn new(n: usize, s_max: f64, numerical_aperture: f64) -> Result<FftLayer, Error> {
        Ok(FftLayer {
            n,
            plan: OtfPlan::new(n, s_max)?,
            numerical_aperture,
            circle: Arc::new(Aperture::circle()),
            square: Arc::new(Aperture::mask(|x, y| x.abs() <= 1.0 && y.abs() <= 1.0)),
            pupils: Vec::new(),
            zones: Vec::new(),
            fields: Vec::new(),
            radial: RadialCache::default(),
        })
    }

    /// How `order`'s OTF at `lambda` is read: a grid of its sampled pupil, of its composite of
    /// zones, or its table.
    fn kind(&mut self, order: &Order, lambda: f64) -> Result<FftKind, Error> {
        let slot = match &order.pupil {
            Pupil::Table(t) => return Ok(FftKind::Table(t.clone())),
            Pupil::Zones(zones) => return self.zones_grid(zones, lambda).map(|g| FftKind::Grid(Arc::new(g))),
            _ => self.pupil(order)?,
        };
        let mut otf = Otf::new();
        match &order.pupil {
            Pupil::Map(map) => {
                let sampled = &self.pupils[slot].1;
                let (field, weight) = map.field(sampled.n(), sampled.amplitude(), lambda);
                self.plan.otf_of_field(&field, weight, &mut otf);
            }
            Pupil::Radial(radial) => {
                let (field, weight) = radial_field(&mut self.radial, &self.pupils[slot].1, radial, lambda);
                self.plan.otf_of_field(&field, weight, &mut otf);
            }
            _ => self.plan.otf(&self.pupils[slot].1, lambda, &mut otf),
        }
        Ok(FftKind::Grid(Arc::new(otf)))
    }

    /// [`kind`](Self::kind) and, where `order`'s pupil is an aperture of disc shape, the grid's
    /// derivative in the obscuration ε from the same pupil spectrum
    /// ([`OtfPlan::otf_and_edge_derivative`](crate::fft::OtfPlan::otf_and_edge_derivative),
    /// [`edge_motion`]): the grid is [`kind`](Self::kind)'s bit for bit.
    fn kind_and_edge_lane(&mut self, order: &Order, lambda: f64) -> Result<(FftKind, Option<Otf>), Error> {
        let Pupil::Aperture(aperture) = &order.pupil else { return Ok((self.kind(order, lambda)?, None)) };
        let slot = self.pupil(order)?;
        let sampled = &self.pupils[slot].1;
        let Some((moved, rows, d_weight)) = edge_motion(sampled, aperture, lambda) else {
            return Ok((self.kind(order, lambda)?, None));
        };
        let (mut otf, mut lane) = (Otf::new(), Otf::new());
        self.plan.otf_and_edge_derivative(sampled, lambda, &moved, rows, d_weight, &mut otf, &mut lane);
        Ok((FftKind::Grid(Arc::new(otf)), Some(lane)))
    }

    /// The cached sampled pupil of `order` (its aperture, or the full circle) with the order's
    /// wavefront: its slot in `pupils`.
    fn pupil(&mut self, order: &Order) -> Result<usize, Error> {
        let aperture = match &order.pupil {
            Pupil::Aperture(a) => a.clone(),
            Pupil::Map(m) if m.aperture() == crate::map::MapAperture::Square => self.square.clone(),
            _ => self.circle.clone(),
        };
        let mut aberrations = order.wavefront.aberrations();
        if let Pupil::Map(_) = &order.pupil {
            // the map's field holds its whole wavefront (`MapPupil::field`): the sampled pupil
            // gives the edge pixels' areas only
            aberrations = crate::fft::Aberrations::default();
        }
        if let Pupil::Radial(radial) = &order.pupil {
            // the symmetric part is added per pixel (`radial_field`); the rest is sampled here
            aberrations.zernike_noll_m = radial.asymmetric_zernike();
        }
        let slot = match self.pupils.iter().position(|(a, _)| Arc::ptr_eq(a, &aperture)) {
            Some(i) => {
                self.pupils[i].1.set_aberrations(&aberrations)?;
                i
            }
            None => {
                let p = SampledPupil::new(self.n, &aperture, &aberrations)?;
                if self.pupils.len() == SAMPLED_CACHE {
                    self.pupils.remove(0);
                }
                self.pupils.push((aperture, p));
                self.pupils.len() - 1
            }
        };
        Ok(slot)
    }

    /// The OTF of one composite pupil (docs/physics.md, "General pupils"; `fft::SampledZones`):
    /// the zones' fields add coherently, each with its amplitude, its wavefront and, for its own
    /// image shift Δ, the tilt `W += (Δx x + Δy y) NA` (x, y in units of the full aperture's
    /// radius), which multiplies its part of the OTF by `exp(−2πi ν·Δ)` as an order's shift does.
    fn zones_grid(&mut self, zones: &[crate::Zone], lambda: f64) -> Result<Otf, Error> {
        let slot = self.zones_grid_field(zones, lambda)?;
        let sampled = &self.zones[slot];
        let mut otf = Otf::new();
        self.plan.otf_of_field(sampled.field(), sampled.weight(), &mut otf);
        Ok(otf)
    }

    /// Samples `zones` (cached) and sets their composite field at `lambda`, each zone's fields in
    /// `self.fields`: the slot of the sampling in `self.zones`.
    fn zones_grid_field(&mut self, zones: &[crate::Zone], lambda: f64) -> Result<usize, Error> {
        let apertures = || zones.iter().map(|z| &z.aperture);
        let slot = match self.zones.iter().position(|s| s.is_sampling_of(apertures())) {
            Some(i) => i,
            None => {
                let list: Vec<Arc<Aperture>> = apertures().cloned().collect();
                if self.zones.len() == SAMPLED_CACHE {
                    self.zones.remove(0);
                }
                self.zones.push(SampledZones::new(self.n, &list)?);
                self.zones.len() - 1
            }
        };
        let na = self.numerical_aperture;
        self.fields.clear();
        self.fields.extend(zones.iter().map(|z| ZoneField {
            amplitude: z.amplitude,
            aberrations: z.wavefront.aberrations(),
            tilt_m: [z.wavefront.image_shift_m[0] * na, z.wavefront.image_shift_m[1] * na],
        }));
        self.zones[slot].set_field(&self.fields, lambda)?;
        Ok(slot)
    }
}

/// How one direction moves the zones of a composite pupil ([`FftLayer::zones_lanes`]).
enum ZoneLane<'r> {
    /// Every zone's own defocus by itself (per relative change).
    Defocus,
    /// Every zone's own tilt by itself (per relative change).
    ImageShift,
    /// Each zone at its own rates (per unit of a key).
    Rates(&'r [crate::ZoneRate]),
    /// A direction the zones do not carry.
    Missing,
}

impl FftLayer {
    /// The composite field of `zones` at `lambda` as [`zones_grid`](Self::zones_grid) builds
    /// it, its weight, and per direction its move `(∂P, ∂weight)` (docs/physics.md, "Gradients:
    /// the multiplexed lens"): [`WavefrontDirection::Defocus`] moves each zone's own defocus by
    /// itself, `∂W_j = W020_j (x² + y²)`, and [`WavefrontDirection::ImageShift`] each zone's own
    /// tilt (its image shift) by itself, `∂W_j = t_j·(x, y)`, both per relative change
    /// ([`SampledZones::field_derivative`]); [`ZoneLane::Rates`] each zone at the lens's own
    /// rates (`LensModel::zone_rates`: `∂a_j`, `∂W_j = ∂W020_j (x² + y²) + NA ∂Δ_j·(x, y)` and
    /// the edges' motion, [`SampledZones::rates_derivative`]). `None` for a lane missing or a
    /// zone whose wavefront is not a defocus alone.
    #[allow(clippy::type_complexity)]
    fn zones_lanes(
        &mut self,
        zones: &[crate::Zone],
        lambda: f64,
        lanes: &[ZoneLane<'_>],
    ) -> Result<Option<(Vec<Complex64>, f64, Vec<(Vec<Complex64>, f64)>)>, Error> {
        if !zones.iter().all(|z| z.wavefront.is_defocus_only()) {
            return Ok(None);
        }
        // the value's field on the value's sampling
        let slot = self.zones_grid_field(zones, lambda)?;
        let sampled = &self.zones[slot];
        let field = sampled.field().to_vec();
        let weight = sampled.weight();
        let fields = &self.fields;
        let still = vec![0.0; zones.len()];
        let na = self.numerical_aperture;
        let mut moves = Vec::with_capacity(lanes.len());
        for lane in lanes {
            let moved = match lane {
                ZoneLane::Defocus => sampled.field_derivative(fields, lambda, &still, &|j, x, y| {
                    fields[j].aberrations.w020_m * (x * x + y * y)
                }),
                ZoneLane::ImageShift => sampled.field_derivative(fields, lambda, &still, &|j, x, y| {
                    let [tx, ty] = fields[j].tilt_m;
                    tx * x + ty * y
                }),
                ZoneLane::Rates(rates) => sampled.rates_derivative(fields, lambda, rates, na),
                ZoneLane::Missing => None,
            };
            let Some(moved) = moved else { return Ok(None) };
            moves.push(moved);
        }
        Ok(Some((field, weight, moves)))
    }
}

/// The field of a radial pupil ([`Pupil::Radial`]) on the samples of `sampled` (the full circle
/// with the order's other aberrations): each transmitting pixel's area fraction times the
/// profile's amplitude at its centre, with the profile's OPD beyond the defocus added to the
/// sampled OPD; and its power `Σ f A²` (pixel units), the OTF's normalization. The profiles'
/// samples at the pixels do not depend on the wavelength (the phase `k W` does, through `k`
/// and the terms' coefficients): they are read from `cache` ([`RadialSamples`]), made once per
/// grid and profile, the same numbers in the same operations as evaluating them here.
fn radial_field(
    cache: &mut RadialCache,
    sampled: &crate::fft::SampledPupil,
    radial: &crate::radial::RadialPupil,
    lambda: f64,
) -> (Vec<Complex64>, f64) {
    let n = sampled.n();
    let k = 2.0 * PI / lambda;
    let (area, opd) = (sampled.amplitude(), sampled.opd_m());
    let at = cache.view(sampled, radial);
    let mut field = vec![Complex64::new(0.0, 0.0); n * n];
    let mut weight = 0.0;
    for (i, p) in at.pixels.iter().enumerate() {
        let a = at.amplitude.map_or(1.0, |v| v[i]);
        weight += area[p.idx] * a * a;
        let w = opd[p.idx] + radial.opd_beyond_defocus_from(p.q, |t| at.terms[t][i]) + at.oblique.map_or(0.0, |v| v[i]);
        field[p.idx] = Complex64::from_polar(area[p.idx] * a, k * w);
    }
    (field, weight)
}

/// A transmitting pixel of a radial pupil's grid ([`radial_field`]) inside its circle: its
/// index, centre `(x, y)`, `r² = x² + y²` and `q = min(r² k², 1)` (`k` the frequency scale).
struct RadialPixel {
    idx: usize,
    x: f64,
    y: f64,
    r2: f64,
    q: f64,
}

/// Profiles kept per set of pixels ([`RadialSamples`]): a lens's shared ones (its phase terms,
/// its reference sphere) and a wavelength's own (a library's amplitude and residual).
const RADIAL_PROFILES: usize = 16;

/// The samples of radial pupils' profiles at the pixels of one grid ([`radial_field`]): the
/// pixels (for one pupil grid size and frequency scale), each profile's values at their `q`
/// (keyed by the profile's `Arc`, which the cache holds so the key stays that profile's), and
/// an oblique incidence's OPD at their centres. None depends on the wavelength.
struct RadialSamples {
    n: usize,
    scale2: u64,
    pixels: Vec<RadialPixel>,
    /// most recently used last
    profiles: Vec<(Arc<crate::radial::RadialProfile>, Vec<f64>)>,
    oblique: Vec<(crate::radial::Oblique, Vec<f64>)>,
}

/// The [`RadialSamples`] of an FFT layer, one per frequency scale seen (a lens has one).
#[derive(Default)]
struct RadialCache {
    sets: Vec<RadialSamples>,
}

/// What [`radial_field`] reads of a [`RadialSamples`] for one pupil: the pixels, and at each the
/// amplitude (`None`: uniform), each OPD term's profile, and the oblique OPD (`None`: on axis).
struct RadialView<'c> {
    pixels: &'c [RadialPixel],
    amplitude: Option<&'c [f64]>,
    terms: Vec<&'c [f64]>,
    oblique: Option<&'c [f64]>,
}

impl RadialCache {
    /// The samples of `radial`'s profiles on the pixels of `sampled` (the layer's full circle:
    /// its transmitting pixels are those of its size), made where not cached.
    fn view<'c>(
        &'c mut self,
        sampled: &crate::fft::SampledPupil,
        radial: &crate::radial::RadialPupil,
    ) -> RadialView<'c> {
        let n = sampled.n();
        let scale2 = radial.frequency_scale().powi(2);
        let at = match self.sets.iter().position(|s| s.n == n && s.scale2 == scale2.to_bits()) {
            Some(i) => i,
            None => {
                let mut pixels = Vec::new();
                for (idx, x, y) in crate::fft::transmitting_pixels(n, sampled.amplitude()) {
                    // a pupil in direction cosines fills the circle of radius 1/k of the
                    // paraxial one (its rim pixel by pixel, not by area fraction)
                    let r2 = x * x + y * y;
                    let q = r2 * scale2;
                    if scale2 > 1.0 && q > 1.0 {
                        continue;
                    }
                    pixels.push(RadialPixel { idx, x, y, r2, q: q.min(1.0) });
                }
                if self.sets.len() == SAMPLED_CACHE {
                    self.sets.remove(0);
                }
                self.sets.push(RadialSamples {
                    n,
                    scale2: scale2.to_bits(),
                    pixels,
                    profiles: Vec::new(),
                    oblique: Vec::new(),
                });
                self.sets.len() - 1
            }
        };
        let set = &mut self.sets[at];
        let mut wanted: Vec<&Arc<crate::radial::RadialProfile>> = radial.terms().iter().map(|(_, p)| p).collect();
        if let Some(a) = radial.amplitude_profile() {
            wanted.push(a);
        }
        for p in &wanted {
            set.keep(p);
        }
        // the wanted profiles are the last ones now: drop the least recently used beyond the bound
        while set.profiles.len() > RADIAL_PROFILES.max(wanted.len()) {
            set.profiles.remove(0);
        }
        if let Some(o) = radial.oblique() {
            match set.oblique.iter().position(|(seen, _)| seen == o) {
                Some(i) => {
                    let entry = set.oblique.remove(i);
                    set.oblique.push(entry);
                }
                None => {
                    let values = set.pixels.iter().map(|p| o.opd_m(p.x, p.y)).collect();
                    if set.oblique.len() == SAMPLED_CACHE {
                        set.oblique.remove(0);
                    }
                    set.oblique.push((*o, values));
                }
            }
        }
        let set = &self.sets[at];
        let values = |p: &Arc<crate::radial::RadialProfile>| {
            set.profiles.iter().find(|(seen, _)| Arc::ptr_eq(seen, p)).map_or(&[][..], |(_, v)| v.as_slice())
        };
        RadialView {
            pixels: &set.pixels,
            amplitude: radial.amplitude_profile().map(values),
            terms: radial.terms().iter().map(|(_, p)| values(p)).collect(),
            oblique: radial
                .oblique()
                .and_then(|o| set.oblique.iter().find(|(seen, _)| seen == o))
                .map(|(_, v)| v.as_slice()),
        }
    }
}

impl RadialSamples {
    /// Makes `profile`'s values at the pixels where not cached, and marks them the most
    /// recently used.
    fn keep(&mut self, profile: &Arc<crate::radial::RadialProfile>) {
        let entry = match self.profiles.iter().position(|(seen, _)| Arc::ptr_eq(seen, profile)) {
            Some(i) => self.profiles.remove(i),
            None => (profile.clone(), self.pixels.iter().map(|p| profile.value(p.q)).collect()),
        };
        self.profiles.push(entry);
    }
}

/// Monochromatic MTF of `lens` at one wavelength along +x, at each of `frequencies` (cycles/m):
/// the modulus of the efficiency-weighted sum of its orders' OTFs (with their lateral-shift
/// phases), normalized to 1 at zero frequency (all zeros if no order transmits). Orders beyond
/// the exact path get one FFT grid each, with `pupil_samples` across the diameter (a composite
/// pupil of zones one grid of its coherent field); a tabulated order is read at ν, along +x
/// measured from the field direction.
pub fn monochromatic_mtf(
    lens: &dyn LensModel,
    wavelength_m: f64,
    field: Field,
    frequencies: &[f64],
    pupil_samples: usize,
) -> Result<Vec<f64>, Error> {
    let to_s = |nu: f64| nu.abs() * wavelength_m * lens.f_number();
    let s_max = frequencies.iter().map(|&nu| to_s(nu)).fold(0.0, f64::max).clamp(1e-6, 1.0);
    let mut sum = vec![Complex64::new(0.0, 0.0); frequencies.len()];
    let mut total = 0.0;
    let mut layer: Option<FftLayer> = None;
    // along +x: a tabulated order's direction relative to the field's
    let from_field = -field.y_rad.atan2(field.x_rad);
    for order in lens.orders(wavelength_m, field) {
        total += order.efficiency;
        let kind = if needs_grid(&order, true) {
            let layer = match &mut layer {
                Some(l) => l,
                slot => slot.insert(FftLayer::new(pupil_samples, s_max, lens.numerical_aperture())?),
            };
            Some(layer.kind(&order, wavelength_m)?)
        } else {
            None
        };
        let node = Node::of(&order, wavelength_m, order.efficiency, Some(lens.numerical_aperture()), TableRule::Tensor);
        for (acc, &nu) in sum.iter_mut().zip(frequencies) {
            let s = to_s(nu);
            if s >= 1.0 {
                continue;
            }
            // (a reduced iris's tilt is in its node's shift; a grid holds its pupil's own phase)
            let (otf, shift) = match &kind {
                Some(FftKind::Grid(g)) => (g.at(s.min(g.s_max()), 0.0), order.wavefront.image_shift_m[0]),
                _ => (Complex64::new(node.otf(s, nu, from_field), 0.0), node.shift[0]),
            };
            let phase = -2.0 * PI * nu * shift;
            *acc += otf * Complex64::from_polar(order.efficiency, phase);
        }
    }
    Ok(sum.iter().map(|z| if total > 0.0 { z.norm() / total } else { 0.0 }).collect())
}

/// A direction in which a scene key moves the wavefront of every order, for the gradient on
/// the FFT path ([`Polychromatic::mean_mtf_over_azimuth_and_gradient`](super::Polychromatic::mean_mtf_over_azimuth_and_gradient);
/// docs/physics.md, "Gradients: 2-D pupils").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WavefrontDirection {
    /// Lane `i` of the lens's wavefront directions (`LensModel::binary2_directions`: Binary 2
    /// coefficients, spline knots, `m = 0` Zernike terms of a phase lens), a radial profile in
    /// `q = ρ²` per order: the derivative per unit of that key.
    Lane(usize),
    /// The Zernike term of Noll index `j` (≥ 1) added to every order's wavefront
    /// (`lens.zernike_noll_rms_um[j − 1]`): `∂W = 10⁻⁶ Z_j(x, y)` per µm RMS (Noll 1976
    /// normalization, as the value samples it).
    Zernike(usize),
    /// A Seidel term of the chromatic lens's wavefront (`lens.spherical_um`, `lens.coma_um`,
    /// `lens.astigmatism_um`, `lens.field_curvature_um`), per µm at the pupil's edge: the
    /// overlap engine's gradient ([`SeidelTerm`](super::SeidelTerm); docs/physics.md,
    /// "Gradients: Seidel terms on the overlap engine"). The FFT path does not carry it.
    Seidel(super::SeidelTerm),
    /// The field angle along x (`0`) or y (`1`), per radian, for a lens whose orders change with
    /// the field only through their image shifts (`LensModel::image_shift_field_rates`: the
    /// lateral colour): each spectral node's OTF turns by `exp(−2πi ν·Δ)`, so it gains
    /// `−2πi ν_a (∂Δ_a/∂θ_a)` times itself (a tilt of the wavefront, `W = NA Δ·ρ`). The exact
    /// 1-D and overlap engines' gradient (docs/physics.md, "Gradients: the field point"). On
    /// the FFT path, the oblique wave's path of a radial pupil seen off axis (a phase or
    /// library lens: `RadialPupil::with_oblique`, its orders without image shifts) moves with
    /// the angle: `∂W = ∂(α·X + |X − P| − |P|)/∂θ_a` at each pixel, a lane as a Zernike term's.
    FieldAngle(usize),
    /// Each order's own defocus `W020(λ)` (not the field curvature), per relative change:
    /// `∂W = W020 ρ²` at each spectral node, the lane `∂O/∂ln K` of the F-number and focal
    /// length (`W020 ∝ f0/F#²`) on the overlap engine (docs/physics.md, "Gradients: the
    /// F-number and the focal length with Seidel terms"). The overlap engine carries it, and the
    /// exact engine for a decentred circular iris ([`IrisDecentre`](Self::IrisDecentre)), whose
    /// tilt `2 W020 d` scales with the defocus: there the node's image displacement
    /// `Δ = 2 W020 d/NA` moves with it too (docs/physics.md, "Gradients: the iris"). The FFT
    /// path carries it for orders through a sampled pupil (the full circle, an annulus, an iris,
    /// decentred, beside Seidel terms and the obscuration's edge; a radial pupil's own defocus
    /// beyond its best fit to its terms): `i k W020 ρ² P` at each pixel, `ρ²` at the pixel's
    /// centre as the value samples it (docs/physics.md, "Gradients: the F-number and the focal
    /// length on the FFT grids").
    Defocus,
    /// The decentre of a circular iris along x (`0`, `lens.iris_decentre_x`) or y (`1`), per unit
    /// of the decentre (a fraction of the aperture's radius), on an order whose only aberration
    /// is defocus: the iris is the centred circle with the tilt `2 W020 d` that moves the image by
    /// `Δ = 2 W020 d/NA` (`fft::reduce_decentred_circle`), so each node's OTF gains
    /// `−2πi ν_a (2 W020/NA)` times itself, as a field angle's lateral colour does. The exact
    /// 1-D engine's gradient (docs/physics.md, "Gradients: the iris").
    IrisDecentre(usize),
    /// The obscuration ε of an order's annular aperture (`lens.obscuration`, the inner radius
    /// in units of the full aperture's radius), per unit ε: not a wavefront but the pupil's
    /// inner edge, which moves each edge pixel's area fraction by minus the inner circle's arc
    /// length in it over the pixel's area ([`Aperture::obscuration_rate_in`]). The FFT path
    /// carries it for orders through such an aperture
    /// ([`OtfPlan::otf_and_field_derivatives`](crate::fft::OtfPlan::otf_and_field_derivatives):
    /// `∂P = ∂A · P/A` at each edge pixel and the normalization `Σ A` moving by `Σ ∂A`;
    /// docs/physics.md, "Gradients: the edge's motion on the FFT path").
    Obscuration,
    /// The spectral weight's moment `k` (1 or 2) about the nodes' mean wavelength
    /// `λ̄ = Σ w λ / Σ w` (node weights `w`, the orders' efficiencies included): each spectral
    /// node's value times `u = λ − λ̄` (`k = 1`, m) or `u² − ⟨u²⟩` (`k = 2`, m²,
    /// `⟨u²⟩ = Σ w u² / Σ w`), summed and normalized as the value. A Gaussian band's centre and
    /// width move the weights by these factors, `∂ln G/∂c = (λ − c)/σ²` and
    /// `∂ln G/∂σ = (λ − c)²/σ³`, so their lanes are the value's own nodes re-weighted
    /// (docs/physics.md, "Gradients: the spectrum where the OTF depends on direction"). The exact
    /// 1-D and overlap engines carry it ([`Polychromatic::node_wavelength_moments`](super::Polychromatic::node_wavelength_moments)
    /// gives `λ̄` and `⟨u²⟩`).
    SpectralMoment(usize),
    /// Each node's image displacement other than a decentred iris's tilt (the lateral colour:
    /// `Δ = f0 tan θ (λ0/λ − 1)` of the chromatic lens, each harmonic order's own), scaled by
    /// `1 + ε`, per relative change: each node's turned OTF gains `−2πi ν u·(Δ − Δ_iris)` times
    /// itself. The lateral colour is proportional to f0 and does not depend on F#, so this is
    /// the lane the F-number's and the focal length's gradient off axis need beside the defocus
    /// lane (docs/physics.md, "Gradients: the F-number and the focal length off axis"). The exact
    /// 1-D engine carries it.
    ImageShift,
    /// The oblique wave's path of a radial pupil seen off axis (`RadialPupil::with_oblique`: a
    /// phase lens on the FFT path) per unit relative change of the aperture radius `R`, the
    /// detector distance held (`0`: `R ∂OPD/∂R`), or of `R` and the detector distance together
    /// (`1`: the path itself, homogeneous of degree 1 in both;
    /// [`Oblique::opd_radius_rate_m`](crate::radial::Oblique::opd_radius_rate_m)). With the
    /// lanes of the lens's aperture directions (`LensModel::aperture_directions`) they give the
    /// F-number's and the focal length's gradient off axis (docs/physics.md, "Gradients: the
    /// F-number and the focal length of a phase lens off axis"). The FFT path carries it.
    ObliqueScale(usize),
    /// The lens's design wavelength λ0 (`lens.design_wavelength_nm`), per relative change, each
    /// order's defocus and efficiency at each node moving by `LensModel::design_wavelength_rates`
    /// (`s = νλF#` and the image shifts held): each node's turned OTF gains
    /// `(δτ/τ) v + τ q ∂H/∂w δw` turned by its phase (`v = q τ H`, `δw = δW020/λ`), the
    /// normalization's own rate not subtracted (the caller's, `Polychromatic::design_signal_rate`),
    /// and the lateral colour's share of λ0 is the [`ImageShift`](Self::ImageShift) lane's
    /// (docs/physics.md, "Gradients: the design wavelength off axis"). The exact 1-D engine
    /// carries it, for full circular pupils with a defocus alone; the FFT path on axis for the
    /// pupils it carries [`Defocus`](Self::Defocus) on, each node's `∂W020/∂ln λ0 ρ²` as that
    /// lane's and its efficiency's rate on its grid.
    DesignWavelength,
    /// A lens parameter `p` that moves each order's field, amplitude and phase, and its
    /// efficiency (`LensModel::order_derivatives(λ, p)`: a library lens's parameter bias, or its
    /// atoms' phase errors with `p` = [`ATOM_PHASE_ERROR`](crate::ATOM_PHASE_ERROR)), per unit
    /// of the parameter. On the FFT path, for a radial pupil (seen off axis): the sampled field
    /// `P = A a e^{ikW}` (area fraction `A`, amplitude `a(q)`) moves by the complex lane
    /// `∂P = A (∂a + i k a ∂W) e^{ikW}` at each pixel, `∂W` as the value samples `W` (the
    /// profile at `q` plus its best-fit defocus's rate times `x² + y² − q`), the normalization
    /// `Σ A a²` by `Σ 2 A a ∂a`, and the node's weight `w τ_o` by `w ∂τ_o`; the normalization of
    /// the polychromatic OTF `Σ w τ_o` by `Σ w ∂τ_o` (docs/physics.md, "Gradients: a library's
    /// parameter bias"). For a site map (a 2-D layout, on and off axis): the field moves by the
    /// same sampling of the atoms' table's derivative (`OrderDerivatives::tables`,
    /// [`MapPupil::field_derivative`](crate::map::MapPupil::field_derivative)). The FFT path
    /// carries it.
    OrderField(usize),
    /// A designer's phase map's pitch, aperture radius or detector distance, per relative change
    /// ([`MapScale`](crate::map::MapScale)), on axis: the cells' edges move across the pupil and
    /// the cells' values with their centres and reference sphere, a complex lane of the field
    /// and its power ([`MapPupil::scale_derivative`](crate::map::MapPupil::scale_derivative);
    /// docs/physics.md, "Gradients: a phase map's pitch and aperture"). The FFT path carries it.
    MapScale(crate::map::MapScale),
    /// A key that moves the zones of a composite pupil each at its own rate
    /// ([`ZoneKey`](crate::ZoneKey), `LensModel::zone_rates`: a channel's wavelength or own
    /// efficiency of a segmented multiplexed lens), per unit of the key. On the FFT path the
    /// composite field moves by `∂P_k = Σ_j A_jk (∂a_j + i k a_j ∂W_j(x_k)) e^{ik(W_j + t_j·x_k)}`
    /// with `∂W_j = ∂W020_j (x² + y²) + NA ∂Δ_j·(x, y)`, its normalization `Σ A a²` by
    /// `Σ 2 A a ∂a`, the node's weight `w τ_o` by `w ∂τ_o` and the polychromatic OTF's
    /// normalization `Σ w τ_o` by `Σ w ∂τ_o` (docs/physics.md, "Gradients: the multiplexed
    /// lens"). The field angles of such a lens are [`FieldAngle`](Self::FieldAngle), with the
    /// lens's rates of [`ZoneKey::FieldAngle`](crate::ZoneKey::FieldAngle). The FFT path
    /// carries it.
    Zone(crate::ZoneKey),
}

/// The most bytes the derivatives' accumulators (one complex value per frequency read, azimuth
/// and direction) may take.
const GRADIENT_MEMORY_BUDGET: f64 = 1.0 * (1u64 << 30) as f64;

impl FftPath {
    /// The derivative of the mean MTF averaged over `count` azimuths from `first`, as the value
    /// takes it on this level ([`fixed_mean`] along each azimuth `first + πk/count`, averaged),
    /// with respect to each of `directions` (docs/physics.md, "Gradients: 2-D pupils"): every
    /// grid's OTF and its derivatives from the same field
    /// ([`OtfPlan::otf_and_derivatives_of_field`](crate::fft::OtfPlan::otf_and_derivatives_of_field)),
    /// read at the value's frequencies and azimuths with the value's interpolation, weights and
    /// lateral-colour phases, and `∂|O| = Re(O* ∂O)/|O|` (0 where `O = 0`: the kink of `|O|`,
    /// a set of measure zero on the fixed rule). `None` where an order is not a radial pupil on
    /// the grid path (apertures, zones and maps do not carry these keys; a site map carries
    /// [`WavefrontDirection::OrderField`] alone), a lane is missing, or
    /// the accumulators would pass their memory budget.
    ///
    /// With a non-white noise spectrum `noise`, of the value's mean of `P |O| / n` instead: each
    /// frequency's weight divided by `n(ν)` as the value's is (docs/physics.md, "Gradients under
    /// a noise spectrum").
    fn gradient_over_azimuth(
        &self,
        scene: &Scene<'_>,
        nodes: &Nodes,
        first: f64,
        count: usize,
        directions: &[WavefrontDirection],
        noise: Option<&super::NoiseShape>,
    ) -> Result<Option<Vec<f64>>, Error> {
        let k_dirs = directions.len();
        if k_dirs == 0 {
            return Ok(Some(Vec::new()));
        }
        // the value's fixed rule ([`fixed_mean`]) and its azimuths
        let lo = self.nodes.iter().map(|n| n.lambda).fold(f64::INFINITY, f64::min);
        let top = scene.max_frequency.min(1.0 / (lo * scene.f_number));
        let (panels, _) = fixed_rule(top, self.finest_cell(scene.f_number));
        let rule = crate::quad::gauss_legendre(crate::quad::FIXED_ORDER);
        let h = top / panels as f64;
        let mut frequencies = Vec::with_capacity(panels * rule.len());
        for p in 0..panels {
            let mid = h * (p as f64 + 0.5);
            for &(x, w) in &rule {
                frequencies.push((mid + 0.5 * h * x, 0.5 * h * w));
            }
        }
        let azimuths: Vec<f64> = (0..count).map(|j| first + PI * j as f64 / count as f64).collect();
        let points = frequencies.len() * azimuths.len();
        if (points * k_dirs * std::mem::size_of::<Complex64>()) as f64 > GRADIENT_MEMORY_BUDGET {
            return Ok(None);
        }
        // the image shifts' lanes of orders through sampled pupils are each node's turned OTF
        // times `−2πi ν u·δΔ` (no FFT: `shift_lane_sums`); the others move the pupil's field
        let shifted = |d: &WavefrontDirection| {
            matches!(d, WavefrontDirection::ImageShift | WavefrontDirection::FieldAngle(0 | 1))
        };
        let by_shift = directions.iter().any(shifted) && self.shifts_on_sampled_pupils(scene, nodes);
        let (d_sum, d_total) = if by_shift {
            let rest: Vec<WavefrontDirection> = directions.iter().copied().filter(|d| !shifted(d)).collect();
            let moved: Vec<WavefrontDirection> = directions.iter().copied().filter(shifted).collect();
            let (d_rest, total_rest) = match rest.is_empty() {
                true => (Vec::new(), Vec::new()),
                false => match self.lane_sums(scene, nodes, &frequencies, &azimuths, &rest)? {
                    Some(found) => found,
                    None => return Ok(None),
                },
            };
            let Some(d_moved) = self.shift_lane_sums(scene, nodes, &frequencies, &azimuths, &moved) else {
                return Ok(None);
            };
            // the two sets of lanes back in the order asked
            let mut d_sum = Vec::with_capacity(points * k_dirs);
            let mut d_total = Vec::with_capacity(k_dirs);
            for point in 0..points {
                let (mut r, mut m) = (point * rest.len(), point * moved.len());
                for d in directions {
                    if shifted(d) {
                        d_sum.push(d_moved[m]);
                        m += 1;
                    } else {
                        d_sum.push(d_rest[r]);
                        r += 1;
                    }
                }
            }
            let mut r = 0;
            for d in directions {
                if shifted(d) {
                    d_total.push(0.0);
                } else {
                    d_total.push(total_rest[r]);
                    r += 1;
                }
            }
            (d_sum, d_total)
        } else {
            match self.lane_sums(scene, nodes, &frequencies, &azimuths, directions)? {
                Some(found) => found,
                None => return Ok(None),
            }
        };
        let pixel = |nu: f64| {
            let p = scene.pixel_pitch.map_or(1.0, |p| crate::otf::pixel_mtf(p, nu));
            noise.map_or(p, |n| p / n.value(nu))
        };
        // the field angles turn the azimuths' start, the field direction φ_f = atan2(θy, θx):
        // the rule's mean moves by ∂M̄/∂φ_f · ∂φ_f/∂θ_a (docs/physics.md, "Gradients: the field
        // point"; 0 on an exact mean over azimuth, the rule's own error otherwise)
        let field = scene.field;
        let turns = !field.is_on_axis() && directions.iter().any(|d| matches!(d, WavefrontDirection::FieldAngle(_)));
        let mut gradient = vec![0.0; k_dirs];
        let mut d_first = 0.0;
        // the level's mean `Σ w P |sum|` (the normalization's motion takes it)
        let mut mean = 0.0;
        for (a, &azimuth) in azimuths.iter().enumerate() {
            for (f, &(nu, w)) in frequencies.iter().enumerate() {
                let (o, turn) = if turns {
                    self.sum_along_and_turn(scene, nu, azimuth)
                } else {
                    (self.sum_along(scene, nu, azimuth), Complex64::new(0.0, 0.0))
                };
                let modulus = o.norm();
                if modulus == 0.0 {
                    continue;
                }
                let base = (a * frequencies.len() + f) * k_dirs;
                let scale = w * pixel(nu) / modulus;
                for (g, d) in gradient.iter_mut().zip(&d_sum[base..base + k_dirs]) {
                    *g += scale * (o.conj() * d).re;
                }
                d_first += scale * (o.conj() * turn).re;
                mean += w * pixel(nu) * modulus;
            }
        }
        if turns {
            let r2 = field.x_rad * field.x_rad + field.y_rad * field.y_rad;
            for (g, d) in gradient.iter_mut().zip(directions) {
                match d {
                    WavefrontDirection::FieldAngle(0) => *g += d_first * (-field.y_rad / r2),
                    WavefrontDirection::FieldAngle(1) => *g += d_first * (field.x_rad / r2),
                    _ => {}
                }
            }
        }
        // O = sum / total weight: Re(O* ∂O)/|O| = Re(sum* ∂sum)/(|sum| total)
        let norm = nodes.total_weight * scene.max_frequency * count as f64;
        gradient.iter_mut().for_each(|g| *g /= norm);
        // an order field's efficiencies move the normalization Σ w τ_o: ∂O gains −O Σ w ∂τ_o/Σ w τ_o,
        // so each mean's derivative −M̄ Σ w ∂τ_o/Σ w τ_o
        for (g, d) in gradient.iter_mut().zip(&d_total) {
            *g -= mean / norm * d / nodes.total_weight;
        }
        Ok(Some(gradient))
    }

    /// Each node's derivative grids along `directions` read at `frequencies` and `azimuths` as
    /// the value reads its grid (`k_dirs` complex sums per point, azimuth-major) and each
    /// direction's `Σ w ∂τ_o` (an order field's efficiencies: the normalization's motion), for
    /// [`gradient_over_azimuth`](Self::gradient_over_azimuth). `None` where a node does not
    /// carry a direction.
    #[allow(clippy::type_complexity)]
    fn lane_sums(
        &self,
        scene: &Scene<'_>,
        nodes: &Nodes,
        frequencies: &[(f64, f64)],
        azimuths: &[f64],
        directions: &[WavefrontDirection],
    ) -> Result<Option<(Vec<Complex64>, Vec<f64>)>, Error> {
        let k_dirs = directions.len();
        let points = frequencies.len() * azimuths.len();
        let mut d_sum = vec![Complex64::new(0.0, 0.0); points * k_dirs];
        // the grids again, node by node in `build`'s order, each with its derivatives
        let lambda_max = nodes.samples.iter().map(|s| s.0).fold(0.0, f64::max);
        let s_max = (scene.max_frequency * lambda_max * scene.f_number).min(1.0);
        // (built when a node's grid is built again: not where every node carries its lanes)
        let mut built: Option<FftLayer> = None;
        let n = self.pupil_samples;
        let mut zernike: Vec<(usize, Vec<f64>)> = Vec::new();
        let mut d_grids: Vec<Otf> = (0..k_dirs).map(|_| Otf::new()).collect();
        let mut otf = Otf::new();
        let mut stored = self.nodes.iter();
        // `Σ w ∂τ_o` of each `OrderField` direction (the normalization's motion)
        let mut d_total = vec![0.0; k_dirs];
        for &(lambda, weight, part) in &nodes.samples {
            if weight == 0.0 {
                continue;
            }
            let lens = scene.part(part).lens;
            // each order's `[∂W020/∂ln λ0, ∂τ/∂ln λ0]` at this wavelength where λ0 is asked
            let design = match directions.contains(&WavefrontDirection::DesignWavelength) {
                true => match lens.design_wavelength_rates(lambda, scene.field) {
                    Some(r) => Some(r),
                    None => return Ok(None),
                },
                false => None,
            };
            let lanes = if directions.iter().any(|d| matches!(d, WavefrontDirection::Lane(_))) {
                match lens.binary2_directions(lambda) {
                    Some(l) => Some(l),
                    None => return Ok(None),
                }
            } else {
                None
            };
            // each `OrderField` direction's order derivatives at this wavelength
            let mut order_fields: Vec<Option<crate::OrderDerivatives>> = Vec::with_capacity(k_dirs);
            for d in directions {
                order_fields.push(match *d {
                    WavefrontDirection::OrderField(p) => match lens.order_derivatives(lambda, p) {
                        Some(found) => Some(found),
                        None => return Ok(None),
                    },
                    _ => None,
                });
            }
            for (index, order) in lens.orders(lambda, scene.field).into_iter().enumerate() {
                if order.efficiency == 0.0 {
                    continue;
                }
                let Some(node) = stored.next() else { return Ok(None) };
                // the chromatic defocus through a sampled pupil (the full circle or an aperture:
                // an annulus, a decentred iris), beside Seidel terms and the obscuration's edge:
                // every lane a move of the field (`sampled_moves`; docs/physics.md, "Gradients: the
                // F-number and the focal length on the FFT grids")
                let defocus_lanes = |d: &WavefrontDirection| {
                    matches!(d, WavefrontDirection::Defocus | WavefrontDirection::DesignWavelength)
                };
                let rates = design.as_ref().and_then(|r| r.get(index)).copied();
                if design.is_some() && rates.is_none() {
                    return Ok(None);
                }
                if directions.iter().any(defocus_lanes)
                    && let (Pupil::Full | Pupil::Aperture(_), FftKind::Grid(_)) = (&order.pupil, &node.kind)
                {
                    let layer = match &mut built {
                        Some(l) => l,
                        slot => slot.insert(FftLayer::new(n, s_max, scene.lens.numerical_aperture())?),
                    };
                    let slot = layer.pupil(&order)?;
                    let aperture = match &order.pupil {
                        Pupil::Aperture(a) => a.clone(),
                        _ => layer.circle.clone(),
                    };
                    let Some((field, weight, moves)) =
                        sampled_moves(&layer.pupils[slot].1, &aperture, &order, directions, rates, lambda)?
                    else {
                        return Ok(None);
                    };
                    let refs: Vec<(&[Complex64], f64)> = moves.iter().map(|(m, w)| (m.as_slice(), *w)).collect();
                    layer.plan.otf_and_field_derivatives(&field, weight, &refs, &mut otf, &mut d_grids);
                    design_efficiency_rate(&mut d_grids, &otf, directions, rates, order.efficiency);
                    let grids: Vec<&Otf> = d_grids.iter().collect();
                    read_derivatives(&mut d_sum, &grids, node, scene.f_number, frequencies, azimuths, k_dirs);
                    continue;
                }
                // the Seidel terms through an iris, or on a full circle (a line's grids): their OPD
                // at the pixels as the value samples the pupil; an iris's decentre: the wavefront's
                // slope there (`decentre_opd`)
                let iris = matches!(order.pupil, Pupil::Aperture(_));
                if let (Pupil::Full | Pupil::Aperture(_), FftKind::Grid(_)) = (&order.pupil, &node.kind)
                    && directions.iter().all(|d| {
                        matches!(d, WavefrontDirection::Seidel(_))
                            || (iris && matches!(d, WavefrontDirection::IrisDecentre(0 | 1)))
                    })
                {
                    let layer = match &mut built {
                        Some(l) => l,
                        slot => slot.insert(FftLayer::new(n, s_max, scene.lens.numerical_aperture())?),
                    };
                    let slot = layer.pupil(&order)?;
                    let aperture = match &order.pupil {
                        Pupil::Aperture(a) => a.clone(),
                        _ => layer.circle.clone(),
                    };
                    let Some((field, weight, opd)) =
                        seidel_through_aperture(&layer.pupils[slot].1, &aperture, &order, directions, lambda)?
                    else {
                        return Ok(None);
                    };
                    let refs: Vec<&[f64]> = opd.iter().map(Vec::as_slice).collect();
                    layer.plan.otf_and_derivatives_of_field(
                        &field,
                        weight,
                        2.0 * PI / lambda,
                        &refs,
                        &mut otf,
                        &mut d_grids,
                    );
                    let grids: Vec<&Otf> = d_grids.iter().collect();
                    read_derivatives(&mut d_sum, &grids, node, scene.f_number, frequencies, azimuths, k_dirs);
                    continue;
                }
                // an order through an aperture of disc shape: the obscuration moves its inner
                // edge (the only key this path differentiates there)
                if let (Pupil::Aperture(aperture), FftKind::Grid(_)) = (&order.pupil, &node.kind) {
                    // the obscuration beside Seidel terms through the annulus: every lane a move of
                    // the field, a term's `i k D P` at a fixed weight and the inner edge's
                    // `∂A exp(i k W)` with `∂Σ A` (docs/physics.md, "Gradients: the edge's motion on
                    // the FFT path")
                    let seidel_or_edge = |d: &WavefrontDirection| {
                        matches!(d, WavefrontDirection::Seidel(_) | WavefrontDirection::Obscuration)
                    };
                    if directions.iter().all(seidel_or_edge)
                        && directions.iter().any(|d| matches!(d, WavefrontDirection::Seidel(_)))
                    {
                        let layer = match &mut built {
                            Some(l) => l,
                            slot => slot.insert(FftLayer::new(n, s_max, scene.lens.numerical_aperture())?),
                        };
                        let slot = layer.pupil(&order)?;
                        let Some(moves) =
                            edge_and_seidel_moves(&layer.pupils[slot].1, aperture, &order, directions, lambda)?
                        else {
                            return Ok(None);
                        };
                        let (field, weight, moves) = moves;
                        let refs: Vec<(&[Complex64], f64)> = moves.iter().map(|(m, w)| (m.as_slice(), *w)).collect();
                        layer.plan.otf_and_field_derivatives(&field, weight, &refs, &mut otf, &mut d_grids);
                        let grids: Vec<&Otf> = d_grids.iter().collect();
                        read_derivatives(&mut d_sum, &grids, node, scene.f_number, frequencies, azimuths, k_dirs);
                        continue;
                    }
                    if !directions.iter().all(|d| *d == WavefrontDirection::Obscuration) {
                        return Ok(None);
                    }
                    // the lane the value's pass computed beside the grid, from the same spectrum
                    if let Some(lane) = &node.lane {
                        let lanes = vec![lane; k_dirs];
                        read_derivatives(&mut d_sum, &lanes, node, scene.f_number, frequencies, azimuths, k_dirs);
                        continue;
                    }
                    let layer = match &mut built {
                        Some(l) => l,
                        slot => slot.insert(FftLayer::new(n, s_max, scene.lens.numerical_aperture())?),
                    };
                    let slot = layer.pupil(&order)?;
                    let Some((field, weight, moved)) = edge_field(&layer.pupils[slot].1, aperture, lambda) else {
                        return Ok(None);
                    };
                    let moves: Vec<(&[Complex64], f64)> =
                        directions.iter().map(|_| (moved.0.as_slice(), moved.1)).collect();
                    layer.plan.otf_and_field_derivatives(&field, weight, &moves, &mut otf, &mut d_grids);
                    let grids: Vec<&Otf> = d_grids.iter().collect();
                    read_derivatives(&mut d_sum, &grids, node, scene.f_number, frequencies, azimuths, k_dirs);
                    continue;
                }
                // a site map's order: its field is linear in the atoms' table, its move the same
                // sampling of the table's derivative (`MapPupil::field_derivative`)
                if let (Pupil::Map(map), FftKind::Grid(_)) = (&order.pupil, &node.kind) {
                    // (or a designer's map's scales: its cells' edges and values, `MapPupil::scale_derivative`)
                    let scales = directions.iter().all(|d| matches!(d, WavefrontDirection::MapScale(_)));
                    if !scales && !directions.iter().all(|d| matches!(d, WavefrontDirection::OrderField(_))) {
                        return Ok(None);
                    }
                    let layer = match &mut built {
                        Some(l) => l,
                        slot => slot.insert(FftLayer::new(n, s_max, scene.lens.numerical_aperture())?),
                    };
                    let slot = layer.pupil(&order)?;
                    let sampled = &layer.pupils[slot].1;
                    let (field, power) = map.field(sampled.n(), sampled.amplitude(), lambda);
                    let mut moves: Vec<(Vec<Complex64>, f64)> = Vec::with_capacity(k_dirs);
                    let mut rates = vec![0.0; k_dirs];
                    for (j, (derivatives, direction)) in order_fields.iter().zip(directions).enumerate() {
                        if let WavefrontDirection::MapScale(scale) = *direction {
                            let Some(moved) = map.scale_derivative(sampled.n(), sampled.amplitude(), lambda, scale)
                            else {
                                return Ok(None);
                            };
                            moves.push(moved);
                            continue;
                        }
                        let Some(d) = derivatives else { return Ok(None) };
                        let (Some(d_table), Some(&d_tau)) = (d.tables.get(index), d.efficiencies.get(index)) else {
                            return Ok(None);
                        };
                        let Some(moved) = map.field_derivative(sampled.n(), sampled.amplitude(), lambda, d_table)
                        else {
                            return Ok(None);
                        };
                        moves.push(moved);
                        rates[j] = d_tau / order.efficiency;
                    }
                    let refs: Vec<(&[Complex64], f64)> = moves.iter().map(|(m, w)| (m.as_slice(), *w)).collect();
                    layer.plan.otf_and_field_derivatives(&field, power, &refs, &mut otf, &mut d_grids);
                    for ((grid, &rate), total) in d_grids.iter_mut().zip(&rates).zip(d_total.iter_mut()) {
                        if rate != 0.0 {
                            grid.add_scaled(&otf, rate);
                            *total += node.weight * rate;
                        }
                    }
                    let grids: Vec<&Otf> = d_grids.iter().collect();
                    read_derivatives(&mut d_sum, &grids, node, scene.f_number, frequencies, azimuths, k_dirs);
                    continue;
                }
                // a composite pupil of zones (a segmented multiplexed lens): each zone's own
                // defocus and tilt move by themselves (`FftLayer::zones_lanes`)
                if let (Pupil::Zones(zones), FftKind::Grid(_)) = (&order.pupil, &node.kind) {
                    // (an order-level shift would move with the image-shift lane too)
                    if node.shift != [0.0, 0.0] {
                        return Ok(None);
                    }
                    let layer = match &mut built {
                        Some(l) => l,
                        slot => slot.insert(FftLayer::new(n, s_max, scene.lens.numerical_aperture())?),
                    };
                    // each direction's lane: every zone's own defocus or tilt, or the lens's rates per
                    // zone of a key that moves them one by one (`LensModel::zone_rates`)
                    let mut rated: Vec<Option<crate::ZoneRates>> = Vec::with_capacity(k_dirs);
                    for d in directions {
                        let key = match *d {
                            WavefrontDirection::FieldAngle(axis) if axis < 2 => crate::ZoneKey::FieldAngle(axis),
                            WavefrontDirection::Zone(key) => key,
                            _ => {
                                rated.push(None);
                                continue;
                            }
                        };
                        let Some(rates) = lens.zone_rates(lambda, scene.field, key).and_then(|r| r.get(index).cloned())
                        else {
                            return Ok(None);
                        };
                        if rates.zones.len() != zones.len() {
                            return Ok(None);
                        }
                        rated.push(Some(rates));
                    }
                    let lanes: Vec<ZoneLane<'_>> = directions
                        .iter()
                        .zip(&rated)
                        .map(|(d, r)| match (d, r) {
                            (_, Some(r)) => ZoneLane::Rates(&r.zones),
                            (WavefrontDirection::Defocus, None) => ZoneLane::Defocus,
                            (WavefrontDirection::ImageShift, None) => ZoneLane::ImageShift,
                            _ => ZoneLane::Missing,
                        })
                        .collect();
                    let Some((field, weight, moves)) = layer.zones_lanes(zones, lambda, &lanes)? else {
                        return Ok(None);
                    };
                    let refs: Vec<(&[Complex64], f64)> = moves.iter().map(|(m, w)| (m.as_slice(), *w)).collect();
                    layer.plan.otf_and_field_derivatives(&field, weight, &refs, &mut otf, &mut d_grids);
                    // the order's efficiency moves its node's weight w τ_o and the normalization
                    for ((grid, r), total) in d_grids.iter_mut().zip(&rated).zip(d_total.iter_mut()) {
                        if let Some(r) = r
                            && r.efficiency != 0.0
                        {
                            let rate = r.efficiency / order.efficiency;
                            grid.add_scaled(&otf, rate);
                            *total += node.weight * rate;
                        }
                    }
                    let grids: Vec<&Otf> = d_grids.iter().collect();
                    read_derivatives(&mut d_sum, &grids, node, scene.f_number, frequencies, azimuths, k_dirs);
                    continue;
                }
                let radial = match (&order.pupil, &node.kind) {
                    (Pupil::Radial(radial), FftKind::Grid(_)) => radial.clone(),
                    // a table is data: the wavefront keys do not move it
                    (_, FftKind::Table(_)) => continue,
                    _ => return Ok(None),
                };
                let layer = match &mut built {
                    Some(l) => l,
                    slot => slot.insert(FftLayer::new(n, s_max, scene.lens.numerical_aperture())?),
                };
                let slot = layer.pupil(&order)?;
                let (field, power) = radial_field(&mut layer.radial, &layer.pupils[slot].1, &radial, lambda);
                // each direction's OPD per unit key at the pixels the field transmits
                let mut opd: Vec<Vec<f64>> = Vec::with_capacity(k_dirs);
                for d in directions {
                    let values = match *d {
                        WavefrontDirection::Lane(i) => {
                            let Some(profile) = lanes.as_ref().and_then(|l| l.get(index)).and_then(|o| o.get(i)) else {
                                return Ok(None);
                            };
                            radial_direction(n, &radial, &field, profile)
                        }
                        WavefrontDirection::Zernike(j) => {
                            let (_, m) = crate::fft::noll_to_nm(j);
                            if m == 0 {
                                // in the radial profile at q (`opd_beyond_defocus_m`)
                                let profile = crate::radial::zernike_radial_profile(crate::fft::noll_to_nm(j).0, 1e-6);
                                radial_direction(n, &radial, &field, &profile)
                            } else {
                                // sampled on the pupil's (x, y) as the value samples it
                                let at = match zernike.iter().position(|(jj, _)| *jj == j) {
                                    Some(p) => p,
                                    None => {
                                        let unit = crate::fft::Aberrations {
                                            zernike_noll_m: vec![(j, 1e-6)],
                                            ..crate::fft::Aberrations::default()
                                        };
                                        let sampled = SampledPupil::new(n, &Aperture::circle(), &unit)?;
                                        zernike.push((j, sampled.opd_m().to_vec()));
                                        zernike.len() - 1
                                    }
                                };
                                zernike[at].1.clone()
                            }
                        }
                        // an oblique wave's path moves with the angle (an order without image
                        // shift: the pupil's wavefront is measured from the chief ray's image)
                        WavefrontDirection::FieldAngle(axis) if axis < 2 => {
                            let Some(oblique) = radial.oblique() else { return Ok(None) };
                            if node.shift != [0.0, 0.0] {
                                return Ok(None);
                            }
                            oblique_direction(n, &field, oblique, axis)
                        }
                        WavefrontDirection::ObliqueScale(which) if which < 2 => {
                            let Some(oblique) = radial.oblique() else { return Ok(None) };
                            if node.shift != [0.0, 0.0] {
                                return Ok(None);
                            }
                            at_transmitting_pixels(n, &field, |x, y| match which {
                                0 => oblique.opd_radius_rate_m(x, y),
                                _ => oblique.opd_m(x, y),
                            })
                        }
                        // its move is the field's own (below)
                        WavefrontDirection::OrderField(_) => Vec::new(),
                        // the order's own defocus beyond the pupil's best fit to its terms (the
                        // chromatic defocus of a lens with Zernike terms, `Order::radial`), sampled
                        // as the pupil samples the order's `W020 (x² + y²)`
                        WavefrontDirection::Defocus => {
                            let own = order.wavefront.defocus_m - radial.fitted_defocus_m();
                            at_transmitting_pixels(n, &field, |x, y| own * (x * x + y * y))
                        }
                        // the design wavelength moves that defocus by the lens's rate
                        WavefrontDirection::DesignWavelength => {
                            let Some([rate, _]) = rates else { return Ok(None) };
                            at_transmitting_pixels(n, &field, |x, y| rate * (x * x + y * y))
                        }
                        // the order's Seidel terms, sampled on the full circle with its Zernike
                        // terms (`FftLayer::pupil`): each term's polynomial as the value samples it
                        WavefrontDirection::Seidel(term) => {
                            seidel_unit_opd(n, &Aperture::circle(), term, order.wavefront.aberrations().field)?
                        }
                        WavefrontDirection::FieldAngle(_)
                        | WavefrontDirection::IrisDecentre(_)
                        | WavefrontDirection::Obscuration
                        | WavefrontDirection::SpectralMoment(_)
                        | WavefrontDirection::ImageShift
                        | WavefrontDirection::ObliqueScale(_)
                        | WavefrontDirection::MapScale(_)
                        | WavefrontDirection::Zone(_) => return Ok(None),
                    };
                    opd.push(values);
                }
                if order_fields.iter().any(Option::is_some) {
                    // the complex lanes: each wavefront direction's `i k D P`, each order field's
                    // own move, and the node's efficiency rate on its OTF
                    let k = 2.0 * PI / lambda;
                    let mut moves: Vec<(Vec<Complex64>, f64)> = Vec::with_capacity(k_dirs);
                    let mut rates = vec![0.0; k_dirs];
                    for (j, derivatives) in order_fields.iter().enumerate() {
                        match derivatives {
                            Some(d) => {
                                let (Some((d_amplitude, d_wavefront)), Some(&d_tau)) =
                                    (d.fields.get(index), d.efficiencies.get(index))
                                else {
                                    return Ok(None);
                                };
                                let sampled = &layer.pupils[slot].1;
                                moves.push(order_field_move(
                                    &mut layer.radial,
                                    sampled,
                                    &radial,
                                    d_amplitude,
                                    d_wavefront,
                                    lambda,
                                ));
                                rates[j] = d_tau / order.efficiency;
                            }
                            None => moves.push((
                                field.iter().zip(&opd[j]).map(|(p, &d)| p * Complex64::new(0.0, k * d)).collect(),
                                0.0,
                            )),
                        }
                    }
                    let refs: Vec<(&[Complex64], f64)> = moves.iter().map(|(m, w)| (m.as_slice(), *w)).collect();
                    layer.plan.otf_and_field_derivatives(&field, power, &refs, &mut otf, &mut d_grids);
                    for ((grid, &rate), total) in d_grids.iter_mut().zip(&rates).zip(d_total.iter_mut()) {
                        if rate != 0.0 {
                            grid.add_scaled(&otf, rate);
                            *total += node.weight * rate;
                        }
                    }
                } else {
                    let refs: Vec<&[f64]> = opd.iter().map(Vec::as_slice).collect();
                    layer.plan.otf_and_derivatives_of_field(
                        &field,
                        power,
                        2.0 * PI / lambda,
                        &refs,
                        &mut otf,
                        &mut d_grids,
                    );
                }
                design_efficiency_rate(&mut d_grids, &otf, directions, rates, order.efficiency);
                let grids: Vec<&Otf> = d_grids.iter().collect();
                read_derivatives(&mut d_sum, &grids, node, scene.f_number, frequencies, azimuths, k_dirs);
            }
        }
        if stored.next().is_some() {
            return Ok(None);
        }
        Ok(Some((d_sum, d_total)))
    }

    /// Whether every order of every node is a sampled pupil whose image shift is a phase of its
    /// grid's reading (the full circle, an aperture, a radial pupil without an oblique wave's
    /// path, on a grid): there the image shifts' lanes are [`shift_lane_sums`](Self::shift_lane_sums)'.
    fn shifts_on_sampled_pupils(&self, scene: &Scene<'_>, nodes: &Nodes) -> bool {
        let mut stored = self.nodes.iter();
        for &(lambda, weight, part) in &nodes.samples {
            if weight == 0.0 {
                continue;
            }
            for order in scene.part(part).lens.orders(lambda, scene.field) {
                if order.efficiency == 0.0 {
                    continue;
                }
                let Some(node) = stored.next() else { return false };
                let sampled = match &order.pupil {
                    Pupil::Full | Pupil::Aperture(_) => true,
                    Pupil::Radial(radial) => radial.oblique().is_none(),
                    _ => false,
                };
                if !sampled || !matches!(node.kind, FftKind::Grid(_)) {
                    return false;
                }
            }
        }
        stored.next().is_none()
    }

    /// The image shifts' lanes ([`WavefrontDirection::ImageShift`]: every node's shift `Δ` scaled
    /// by `1 + ε`; [`WavefrontDirection::FieldAngle`] `a`: its shift moving by its order's rate
    /// `∂Δ_a/∂θ_a`, `LensModel::image_shift_field_rates`) of orders through sampled pupils
    /// ([`shifts_on_sampled_pupils`](Self::shifts_on_sampled_pupils)): each node's turned reading
    /// `w O(s) exp(−2πi ν u·Δ)` gains `−2πi ν u·δΔ` times itself, the grid and its weight held
    /// (docs/physics.md, "Gradients: the F-number and the focal length on the FFT grids off
    /// axis"). Summed as [`lane_sums`](Self::lane_sums) does; no FFT. `None` where a lens gives
    /// no field rates for a field angle asked.
    fn shift_lane_sums(
        &self,
        scene: &Scene<'_>,
        nodes: &Nodes,
        frequencies: &[(f64, f64)],
        azimuths: &[f64],
        directions: &[WavefrontDirection],
    ) -> Option<Vec<Complex64>> {
        let k_dirs = directions.len();
        let mut d_sum = vec![Complex64::new(0.0, 0.0); frequencies.len() * azimuths.len() * k_dirs];
        let fields = directions.iter().any(|d| matches!(d, WavefrontDirection::FieldAngle(_)));
        let mut stored = self.nodes.iter();
        let mut rates: Vec<[f64; 2]> = vec![[0.0; 2]; k_dirs];
        for &(lambda, weight, part) in &nodes.samples {
            if weight == 0.0 {
                continue;
            }
            let lens = scene.part(part).lens;
            let field_rates = match fields {
                true => Some(lens.image_shift_field_rates(lambda, scene.field)?),
                false => None,
            };
            for (index, order) in lens.orders(lambda, scene.field).into_iter().enumerate() {
                if order.efficiency == 0.0 {
                    continue;
                }
                let node = stored.next()?;
                let FftKind::Grid(otf) = &node.kind else { return None };
                for (rate, d) in rates.iter_mut().zip(directions) {
                    *rate = match *d {
                        WavefrontDirection::ImageShift => node.shift,
                        WavefrontDirection::FieldAngle(a) => {
                            let r = field_rates.as_ref().and_then(|r| r.get(index))?;
                            if a == 0 { [r[0], 0.0] } else { [0.0, r[1]] }
                        }
                        _ => return None,
                    };
                }
                read_shift_lanes(&mut d_sum, otf, node, scene.f_number, frequencies, azimuths, &rates);
            }
        }
        stored.next().is_none().then_some(d_sum)
    }
}

/// Adds one node's image-shift lanes to `d_sum` (`rates.len()` values per point, azimuth-major):
/// its grid read as `sum_along` reads it (its weight, its lateral-colour phase, the same
/// interpolation) times `−2πi ν u·δΔ` for each direction's shift rate `δΔ` in `rates`.
fn read_shift_lanes(
    d_sum: &mut [Complex64],
    otf: &Otf,
    node: &FftNode,
    f_number: f64,
    frequencies: &[(f64, f64)],
    azimuths: &[f64],
    rates: &[[f64; 2]],
) {
    let k_dirs = rates.len();
    let nuf = f_number * node.lambda;
    for (a, &azimuth) in azimuths.iter().enumerate() {
        let (sin_a, cos_a) = azimuth.sin_cos();
        let [dx, dy] = node.shift;
        for (f, &(nu, _)) in frequencies.iter().enumerate() {
            let s = nu.abs() * nuf;
            if s >= 1.0 || s > otf.s_max() {
                continue;
            }
            let k = -2.0 * PI * nu;
            let (ps, pc) = (k * (dx * cos_a + dy * sin_a)).sin_cos();
            let turned = otf.at_xy(s * cos_a, s * sin_a) * node.weight * Complex64::new(pc, ps);
            let base = (a * frequencies.len() + f) * k_dirs;
            for (slot, [rx, ry]) in d_sum[base..base + k_dirs].iter_mut().zip(rates) {
                *slot += turned * Complex64::new(0.0, k * (rx * cos_a + ry * sin_a));
            }
        }
    }
}

/// Adds one node's derivative grids `d_grids`, read as `sum_along` reads the node's grid (its
/// weight, its lateral-colour phase, the same interpolation), to `d_sum` at each of `azimuths`
/// and `frequencies` (`k_dirs` values per point, azimuth-major).
fn read_derivatives(
    d_sum: &mut [Complex64],
    d_grids: &[&Otf],
    node: &FftNode,
    f_number: f64,
    frequencies: &[(f64, f64)],
    azimuths: &[f64],
    k_dirs: usize,
) {
    let nuf = f_number * node.lambda;
    let s_grid = d_grids[0].s_max();
    for (a, &azimuth) in azimuths.iter().enumerate() {
        let (sin_a, cos_a) = azimuth.sin_cos();
        let [dx, dy] = node.shift;
        for (f, &(nu, _)) in frequencies.iter().enumerate() {
            let s = nu.abs() * nuf;
            if s >= 1.0 || s > s_grid {
                continue;
            }
            let mut factor = Complex64::new(node.weight, 0.0);
            if dx != 0.0 || dy != 0.0 {
                let (ps, pc) = (-2.0 * PI * nu * (dx * cos_a + dy * sin_a)).sin_cos();
                factor *= Complex64::new(pc, ps);
            }
            let base = (a * frequencies.len() + f) * k_dirs;
            for (slot, grid) in d_sum[base..base + k_dirs].iter_mut().zip(d_grids) {
                *slot += grid.at_xy(s * cos_a, s * sin_a) * factor;
            }
        }
    }
}

/// The field of an order through `aperture` sampled as `sampled` (each pixel's area fraction
/// `A` times `exp(i k W)` at its centre, as [`OtfPlan::otf`](crate::fft::OtfPlan::otf) builds
/// it), its weight `Σ A`, and their derivatives in the obscuration ε: `∂A` at each pixel from
/// [`Aperture::obscuration_rate_in`] (minus the inner circle's arc length in the pixel over its
/// area), so `∂P = ∂A exp(i k W)` and `∂(Σ A) = Σ ∂A` (docs/physics.md, "Gradients: the edge's
/// motion on the FFT path"). An edge pixel has `A > 0` (the circle passes through it), so its
/// OPD is sampled. `None` for a mask.
#[allow(clippy::type_complexity)]
fn edge_field(
    sampled: &SampledPupil,
    aperture: &Aperture,
    lambda: f64,
) -> Option<(Vec<Complex64>, f64, (Vec<Complex64>, f64))> {
    let n = sampled.n();
    let h = 2.0 / n as f64;
    let k = 2.0 * PI / lambda;
    let (area, opd) = (sampled.amplitude(), sampled.opd_m());
    let mut field = vec![Complex64::new(0.0, 0.0); n * n];
    crate::fft::cis::fill(&mut field, area, k, opd);
    let mut moved = vec![Complex64::new(0.0, 0.0); n * n];
    let mut d_weight = 0.0;
    for j in 0..n {
        let y0 = -1.0 + j as f64 * h;
        for i in 0..n {
            let x0 = -1.0 + i as f64 * h;
            let rate = aperture.obscuration_rate_in(x0, x0 + h, y0, y0 + h)? / (h * h);
            if rate == 0.0 {
                continue;
            }
            let idx = j * n + i;
            d_weight += rate;
            moved[idx] = Complex64::from_polar(rate, k * opd[idx]);
        }
    }
    Some((field, area.iter().sum::<f64>(), (moved, d_weight)))
}

/// An order's field, its weight and each direction's OPD per unit key ([`seidel_through_aperture`]).
type SeidelField = (Vec<Complex64>, f64, Vec<Vec<f64>>);

/// The field of an order through `aperture` sampled as `sampled` (as [`edge_field`]'s: the
/// pixels' area fractions `A` times `exp(i k W)`), its weight `Σ A`, and the OPD per µm of each
/// Seidel term of `directions` at every pixel (`10⁻⁶ {ρ⁴, H ρ³ cos φ, H² ρ² cos² φ, H² ρ²}` at the
/// order's field height `H`, sampled through the same aperture as the value's,
/// [`SampledPupil::new`]): the Seidel terms through an iris on the FFT path (docs/physics.md,
/// "Gradients: Seidel terms through an iris"); an [`WavefrontDirection::IrisDecentre`]'s OPD
/// per unit decentre there ([`decentre_opd`]). `None` where a direction is neither.
fn seidel_through_aperture(
    sampled: &SampledPupil,
    aperture: &Aperture,
    order: &crate::lens::Order,
    directions: &[WavefrontDirection],
    lambda: f64,
) -> Result<Option<SeidelField>, Error> {
    let n = sampled.n();
    let (area, opd) = (sampled.amplitude(), sampled.opd_m());
    let mut field = vec![Complex64::new(0.0, 0.0); n * n];
    crate::fft::cis::fill(&mut field, area, 2.0 * PI / lambda, opd);
    let height = order.wavefront.aberrations().field;
    let mut out = Vec::with_capacity(directions.len());
    for d in directions {
        if let WavefrontDirection::IrisDecentre(axis @ (0 | 1)) = *d {
            let Some(rate) = decentre_opd(sampled, &order.wavefront.aberrations(), axis) else { return Ok(None) };
            out.push(rate);
            continue;
        }
        let WavefrontDirection::Seidel(term) = *d else { return Ok(None) };
        out.push(seidel_unit_opd(n, aperture, term, height)?);
    }
    Ok(Some((field, area.iter().sum(), out)))
}

/// The OPD (m) of one Seidel term at 1 µm at field height `height`, sampled on `n` pixels across
/// `aperture` as the value's pupil samples it: a Seidel key's direction per µm.
fn seidel_unit_opd(n: usize, aperture: &Aperture, term: super::SeidelTerm, height: f64) -> Result<Vec<f64>, Error> {
    let mut unit = crate::fft::Aberrations { field: height, ..crate::fft::Aberrations::default() };
    match term {
        super::SeidelTerm::Spherical => unit.w040_m = 1e-6,
        super::SeidelTerm::Coma => unit.w131_m = 1e-6,
        super::SeidelTerm::Astigmatism => unit.w222_m = 1e-6,
        super::SeidelTerm::FieldCurvature => unit.w220_m = 1e-6,
    }
    Ok(SampledPupil::new(n, aperture, &unit)?.opd_m().to_vec())
}

/// The OPD's rate (m per unit decentre, a fraction of the radius) along `axis` (0: x, 1: y) at
/// each pixel of `sampled` (0 outside the aperture), where the wavefront `aberrations` is the
/// Seidel polynomial (docs/physics.md, "Gradients: the iris"): the grid stays on the iris and
/// the wavefront is read at `ρ = p + d` from the lens axis (`SampledPupil`'s OPD), so the iris's
/// decentre `d` moves each pixel's OPD by `∂W/∂x_a (p + d)`: with `r² = x² + y²`,
/// `∂W/∂x = 2 W020 x + 4 W040 r² x + W131 H (r² + 2x²) + 2 W222 H² x + 2 W220 H² x` and
/// `∂W/∂y = 2 W020 y + 4 W040 r² y + 2 W131 H x y + 2 W220 H² y`; the iris's edges (an
/// annulus's, a sector's) move with it, fixed on the grid. `None` with a Zernike term.
fn decentre_opd(sampled: &SampledPupil, aberrations: &crate::fft::Aberrations, axis: usize) -> Option<Vec<f64>> {
    if aberrations.zernike_noll_m.iter().any(|&(_, c)| c != 0.0) {
        return None;
    }
    let a = aberrations;
    let h_field = a.field;
    let n = sampled.n();
    let h = 2.0 / n as f64;
    let (dx, dy) = sampled.aperture().decentre();
    let amplitude = sampled.amplitude();
    let mut out = vec![0.0; n * n];
    for j in 0..n {
        let y = -1.0 + (j as f64 + 0.5) * h + dy;
        for i in 0..n {
            let k = j * n + i;
            if amplitude[k] <= 0.0 {
                continue;
            }
            let x = -1.0 + (i as f64 + 0.5) * h + dx;
            let r2 = x * x + y * y;
            out[k] = if axis == 0 {
                2.0 * a.w020_m * x
                    + 4.0 * a.w040_m * r2 * x
                    + a.w131_m * h_field * (r2 + 2.0 * x * x)
                    + 2.0 * (a.w222_m + a.w220_m) * h_field * h_field * x
            } else {
                2.0 * a.w020_m * y
                    + 4.0 * a.w040_m * r2 * y
                    + 2.0 * a.w131_m * h_field * x * y
                    + 2.0 * a.w220_m * h_field * h_field * y
            };
        }
    }
    Some(out)
}

/// An order's field, its weight and each direction's move of it ([`edge_and_seidel_moves`]).
type FieldMoves = (Vec<Complex64>, f64, Vec<(Vec<Complex64>, f64)>);

/// An order's field through `aperture` sampled as `sampled` and its weight `Σ A`
/// ([`edge_field`]'s), with each of `directions` as a move of the field `(∂P, ∂Σ A)`: a Seidel
/// term's `i k D P` (`D` its OPD per µm, [`seidel_through_aperture`]'s; the weight fixed) and the
/// obscuration's inner edge `∂A exp(i k W)` with `∂Σ A` ([`edge_field`]'s). `None` where a
/// direction is neither, or the aperture has no obscuration's edge (a mask).
fn edge_and_seidel_moves(
    sampled: &SampledPupil,
    aperture: &Aperture,
    order: &crate::lens::Order,
    directions: &[WavefrontDirection],
    lambda: f64,
) -> Result<Option<FieldMoves>, Error> {
    let Some((field, weight, moved)) = edge_field(sampled, aperture, lambda) else { return Ok(None) };
    let seidel: Vec<WavefrontDirection> =
        directions.iter().copied().filter(|d| matches!(d, WavefrontDirection::Seidel(_))).collect();
    let Some((_, _, opd)) = seidel_through_aperture(sampled, aperture, order, &seidel, lambda)? else {
        return Ok(None);
    };
    let k = 2.0 * PI / lambda;
    let mut opd = opd.into_iter();
    let mut moves = Vec::with_capacity(directions.len());
    for d in directions {
        match d {
            WavefrontDirection::Obscuration => moves.push(moved.clone()),
            WavefrontDirection::Seidel(_) => {
                let Some(o) = opd.next() else { return Ok(None) };
                moves.push((field.iter().zip(&o).map(|(p, w)| Complex64::new(0.0, k * w) * p).collect(), 0.0));
            }
            _ => return Ok(None),
        }
    }
    Ok(Some((field, weight, moves)))
}

/// An order's field through `aperture` sampled as `sampled` and its weight `Σ A` (as
/// [`edge_field`]'s: what [`OtfPlan::otf`](crate::fft::OtfPlan::otf) transforms), with each of
/// `directions` as a move of the field `(∂P, ∂Σ A)`: the order's own defocus per relative change
/// ([`WavefrontDirection::Defocus`]: `i k W020 ρ² P`, `ρ²` at the pixel's centre in full-aperture
/// coordinates as the value samples it, so through a decentred iris the tilt `2 W020 d·ρ` moves
/// with it), a Seidel term's `i k D P` ([`seidel_through_aperture`]'s `D`), both at a fixed
/// weight, and the obscuration's inner edge ([`edge_field`]'s). `None` where a direction is none
/// of these, or the obscuration is asked of an aperture without its edge (docs/physics.md,
/// "Gradients: the F-number and the focal length on the FFT grids").
fn sampled_moves(
    sampled: &SampledPupil,
    aperture: &Aperture,
    order: &crate::lens::Order,
    directions: &[WavefrontDirection],
    design: Option<[f64; 2]>,
    lambda: f64,
) -> Result<Option<FieldMoves>, Error> {
    let k = 2.0 * PI / lambda;
    let n = sampled.n();
    let (area, opd) = (sampled.amplitude(), sampled.opd_m());
    let (field, weight, edge) = if directions.contains(&WavefrontDirection::Obscuration) {
        let Some((field, weight, moved)) = edge_field(sampled, aperture, lambda) else { return Ok(None) };
        (field, weight, Some(moved))
    } else {
        let mut field = vec![Complex64::new(0.0, 0.0); n * n];
        crate::fft::cis::fill(&mut field, area, k, opd);
        (field, area.iter().sum::<f64>(), None)
    };
    let seidel: Vec<WavefrontDirection> =
        directions.iter().copied().filter(|d| matches!(d, WavefrontDirection::Seidel(_))).collect();
    let mut seidel_opd = match seidel.is_empty() {
        true => Vec::new(),
        false => match seidel_through_aperture(sampled, aperture, order, &seidel, lambda)? {
            Some((_, _, opd)) => opd,
            None => return Ok(None),
        },
    }
    .into_iter();
    // `w ρ²` at the transmitting pixels' centres, decentred as `SampledPupil` samples it
    let (dx, dy) = sampled.aperture().decentre();
    let h = 2.0 / n as f64;
    let sampled_defocus = |w020: f64| -> Vec<f64> {
        let defocus = crate::fft::Compiled::new(&crate::fft::Aberrations::defocus(w020));
        let mut w = vec![0.0; n * n];
        for j in 0..n {
            let y = -1.0 + (j as f64 + 0.5) * h + dy;
            for i in 0..n {
                let idx = j * n + i;
                if area[idx] > 0.0 {
                    w[idx] = defocus.opd_m(-1.0 + (i as f64 + 0.5) * h + dx, y);
                }
            }
        }
        w
    };
    let turn =
        |d: &[f64]| -> Vec<Complex64> { field.iter().zip(d).map(|(p, w)| Complex64::new(0.0, k * w) * p).collect() };
    let mut moves = Vec::with_capacity(directions.len());
    for d in directions {
        match d {
            WavefrontDirection::Defocus => moves.push((turn(&sampled_defocus(order.wavefront.defocus_m)), 0.0)),
            WavefrontDirection::DesignWavelength => {
                let Some([rate, _]) = design else { return Ok(None) };
                moves.push((turn(&sampled_defocus(rate)), 0.0));
            }
            WavefrontDirection::Seidel(_) => {
                let Some(o) = seidel_opd.next() else { return Ok(None) };
                moves.push((turn(&o), 0.0));
            }
            WavefrontDirection::Obscuration => match &edge {
                Some(moved) => moves.push(moved.clone()),
                None => return Ok(None),
            },
            _ => return Ok(None),
        }
    }
    Ok(Some((field, weight, moves)))
}

/// The design wavelength's move of an order's efficiency on its node (`rates`, the lens's
/// `[∂W020/∂ln λ0, ∂τ/∂ln λ0]` for the order, [`WavefrontDirection::DesignWavelength`]): the
/// node's weight `w τ` moves by `w ∂τ`, so its grid's lane gains `(∂τ/τ) OTF`; the
/// normalization's own rate is the caller's (`Polychromatic::design_signal_rate`).
fn design_efficiency_rate(
    d_grids: &mut [Otf],
    otf: &Otf,
    directions: &[WavefrontDirection],
    rates: Option<[f64; 2]>,
    efficiency: f64,
) {
    let Some([_, d_tau]) = rates else { return };
    if d_tau == 0.0 || efficiency == 0.0 {
        return;
    }
    for (grid, d) in d_grids.iter_mut().zip(directions) {
        if *d == WavefrontDirection::DesignWavelength {
            grid.add_scaled(otf, d_tau / efficiency);
        }
    }
}

/// The derivative in the obscuration ε of the field of an order through `aperture` sampled as
/// `sampled` (as [`edge_field`]'s, which [`OtfPlan::otf`](crate::fft::OtfPlan::otf) transforms):
/// `∂P = ∂A exp(i k W)` at each pixel the inner circle crosses, `∂A` from
/// [`Aperture::obscuration_rate_in`], zero elsewhere, given on the rows that may hold a non-zero
/// value (`rows.len() · N` values from row `rows.start`); those rows; and `∂(Σ A)`. Only the pixels within one of the square `[−ε, ε]²` (grid coordinates, the
/// aperture's centre at the origin) are visited: a pixel farther from it does not meet the
/// circle `r = ε`, whose arc length in it is exactly 0. `None` for a mask.
fn edge_motion(
    sampled: &SampledPupil,
    aperture: &Aperture,
    lambda: f64,
) -> Option<(Vec<Complex64>, std::ops::Range<usize>, f64)> {
    let n = sampled.n();
    let h = 2.0 / n as f64;
    let k = 2.0 * PI / lambda;
    let opd = sampled.opd_m();
    let eps = aperture.obscuration()?.clamp(0.0, 1.0);
    // pixels [−1 + i h, −1 + (i + 1) h] meeting [−ε, ε], one pixel of margin each side
    let first = (((1.0 - eps) / h).floor() as usize).saturating_sub(1).min(n);
    let last = ((((1.0 + eps) / h).ceil() as usize) + 1).min(n);
    let mut moved = vec![Complex64::new(0.0, 0.0); (last - first) * n];
    let mut d_weight = 0.0;
    for j in first..last {
        let y0 = -1.0 + j as f64 * h;
        for i in first..last {
            let x0 = -1.0 + i as f64 * h;
            let rate = aperture.obscuration_rate_in(x0, x0 + h, y0, y0 + h)? / (h * h);
            if rate == 0.0 {
                continue;
            }
            d_weight += rate;
            moved[(j - first) * n + i] = Complex64::from_polar(rate, k * opd[j * n + i]);
        }
    }
    Some((moved, first..last, d_weight))
}

/// The OPD per unit of a radial direction `profile` at the pixels where `field` transmits (0
/// elsewhere), as the value's field moves with it: the pupil carries `profile(q)` less its
/// best-fit defocus `b q` ([`RadialPupil::opd_beyond_defocus_m`](crate::radial::RadialPupil::opd_beyond_defocus_m),
/// `q` as [`radial_field`] computes it: `(x² + y²)` times the pupil's frequency scale squared,
/// at most 1), and the order's sampled defocus carries `b (x² + y²)` (`Order::radial`), so the
/// pixel moves by `profile(q) + b (x² + y² − q)`: the two differ where `q` is clamped at the rim
/// (edge pixels whose centre lies outside the circle) or scaled.
fn radial_direction(
    n: usize,
    radial: &crate::radial::RadialPupil,
    field: &[Complex64],
    profile: &crate::radial::RadialProfile,
) -> Vec<f64> {
    let slope = profile.fitted_slope();
    let scale2 = radial.frequency_scale().powi(2);
    at_transmitting_pixels(n, field, |x, y| {
        let r2 = x * x + y * y;
        let q = (r2 * scale2).min(1.0);
        profile.value(q) + slope * (r2 - q)
    })
}

/// The move of a radial pupil's sampled field ([`radial_field`]) where its amplitude profile
/// moves by `d_amplitude` and its wavefront by `d_wavefront` (m) (docs/physics.md, "Gradients: a
/// library's parameter bias"; [`WavefrontDirection::OrderField`]): at each pixel the value
/// transmits, `∂P = A (∂a + i k a ∂W) e^{ikW}`, `∂W` as [`radial_direction`] samples a profile
/// (its best-fit defocus's rate on the order's sampled defocus), and the normalization's
/// `∂(Σ A a²) = Σ 2 A a ∂a`.
fn order_field_move(
    cache: &mut RadialCache,
    sampled: &crate::fft::SampledPupil,
    radial: &crate::radial::RadialPupil,
    d_amplitude: &crate::radial::RadialProfile,
    d_wavefront: &crate::radial::RadialProfile,
    lambda: f64,
) -> (Vec<Complex64>, f64) {
    let n = sampled.n();
    let k = 2.0 * PI / lambda;
    let (area, opd) = (sampled.amplitude(), sampled.opd_m());
    let slope = d_wavefront.fitted_slope();
    let at = cache.view(sampled, radial);
    let mut moved = vec![Complex64::new(0.0, 0.0); n * n];
    let mut d_weight = 0.0;
    for (i, p) in at.pixels.iter().enumerate() {
        let a = at.amplitude.map_or(1.0, |v| v[i]);
        let w = opd[p.idx] + radial.opd_beyond_defocus_from(p.q, |t| at.terms[t][i]) + at.oblique.map_or(0.0, |v| v[i]);
        let da = d_amplitude.value(p.q);
        let dw = d_wavefront.value(p.q) + slope * (p.r2 - p.q);
        d_weight += 2.0 * area[p.idx] * a * da;
        moved[p.idx] = Complex64::from_polar(area[p.idx], k * w) * Complex64::new(da, k * a * dw);
    }
    (moved, d_weight)
}

/// `value(x, y)` at the centres of the pixels where `field` transmits (0 elsewhere), the pupil
/// grid's n × n pixels spanning [−1, 1]² row by row.
fn at_transmitting_pixels(n: usize, field: &[Complex64], value: impl Fn(f64, f64) -> f64) -> Vec<f64> {
    let h = 2.0 / n as f64;
    let mut out = vec![0.0; n * n];
    for j in 0..n {
        let y = -1.0 + (j as f64 + 0.5) * h;
        for i in 0..n {
            let idx = j * n + i;
            if field[idx] == Complex64::new(0.0, 0.0) {
                continue;
            }
            out[idx] = value(-1.0 + (i as f64 + 0.5) * h, y);
        }
    }
    out
}

/// The OPD per radian of the field angle along x (`axis` 0) or y (1) at the pixels where
/// `field` transmits (0 elsewhere): the oblique wave's path ([`Oblique::opd_m`](crate::radial::Oblique::opd_m),
/// which [`radial_field`] adds at the pixel centres `(x, y)`) differentiated in the angle
/// ([`Oblique::opd_field_rate_m`](crate::radial::Oblique::opd_field_rate_m); docs/physics.md,
/// "Gradients: the field point").
fn oblique_direction(n: usize, field: &[Complex64], oblique: &crate::radial::Oblique, axis: usize) -> Vec<f64> {
    at_transmitting_pixels(n, field, |x, y| oblique.opd_field_rate_m(x, y, axis))
}

impl Grids<'_> {
    /// The derivative of the mean MTF averaged over `count` azimuths from `first` (the value's
    /// rule, [`Polychromatic::mean_mtf_over_azimuth`](super::Polychromatic::mean_mtf_over_azimuth))
    /// with respect to each of `directions`: each level's ([`FftPath::gradient_over_azimuth`]),
    /// extrapolated as the value is (Richardson, linear in the two levels' means: the
    /// derivative of the extrapolated value is the extrapolation of the derivatives).
    pub(super) fn gradient_over_azimuth(
        &self,
        first: f64,
        count: usize,
        directions: &[WavefrontDirection],
        noise: Option<&super::NoiseShape>,
    ) -> Result<Option<Vec<f64>>, Error> {
        let Some(fine) = self.fft.gradient_over_azimuth(&self.scene, &self.nodes, first, count, directions, noise)?
        else {
            return Ok(None);
        };
        let Some(plan) = self.richardson() else { return Ok(Some(fine)) };
        let Some((coarse_path, _)) = &self.coarse else { return Ok(Some(fine)) };
        let Some(coarse) =
            coarse_path.gradient_over_azimuth(&self.scene, &self.nodes, first, count, directions, noise)?
        else {
            return Ok(None);
        };
        Ok(Some(fine.iter().zip(&coarse).map(|(&f, &c)| plan.extrapolate(c, f).value).collect()))
    }
}

impl Polychromatic<'_> {
    /// The mean MTF averaged over azimuth ([`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth),
    /// white noise) and its derivative with respect to each of `directions` on the same rules
    /// (docs/physics.md, "Gradients: 2-D pupils"): the same azimuths, frequencies, grids,
    /// interpolation, spectral weights, pixel MTF and Richardson extrapolation as the value, each
    /// grid's derivative by forward mode through the FFT
    /// ([`OtfPlan::otf_and_derivatives_of_field`](crate::fft::OtfPlan::otf_and_derivatives_of_field)).
    /// `Ok(None)` where the engine is not the FFT engine of a band, or an order is not a radial
    /// pupil on the grids (the keys are defined on those).
    ///
    /// # Errors
    /// Building the grids again ([`Error`] of the FFT layer).
    pub fn mean_mtf_over_azimuth_and_gradient(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
    ) -> Result<Option<(AzimuthalMean, Vec<f64>)>, Error> {
        if matches!(self.engine(), Engine::Overlap { .. } | Engine::Exact1d) {
            return Ok(self.mean_mtf_over_azimuth_and_overlap_gradient(first, directions));
        }
        if !matches!(self.engine(), Engine::Fft { .. }) {
            return Ok(None);
        }
        let mean = self.mean_mtf_over_azimuth(first, None);
        Ok(self.engine.wavefront_gradient_over_azimuth(first, mean.azimuths, directions)?.map(|g| (mean, g)))
    }

    /// The derivative of [`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth) (white noise)
    /// with respect to `ln F#` at fixed pupils on the FFT engine: each grid read at `s = νλF#`
    /// moving with F#, the frequencies in ν, azimuths, weights, pixel MTF and Richardson
    /// extrapolation the value's (the discrete rule's exact frequency-scale term). `None` on
    /// another engine.
    pub fn mean_mtf_over_azimuth_scale_lane(&self, first: f64) -> Option<f64> {
        if !matches!(self.engine(), Engine::Fft { .. }) {
            return None;
        }
        let mean = self.mean_mtf_over_azimuth(first, None);
        self.engine.scale_over_azimuth(first, mean.azimuths)
    }

    /// [`mean_mtf_over_azimuth_and_gradient`](Self::mean_mtf_over_azimuth_and_gradient) under a
    /// non-white noise spectrum `n`: the mean over azimuth of `(1/ν_max) ∫ P |O| / n dν`
    /// ([`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth) with `noise`, bit for bit) and
    /// its derivative along each of `directions` on the same rules, each frequency's weight
    /// divided by `n(ν)` as the value's is (docs/physics.md, "Gradients under a noise
    /// spectrum"): the overlap engine's and the exact 1-D engine's lanes
    /// ([`mean_mtf_over_azimuth_over_noise_and_overlap_gradient`](Self::mean_mtf_over_azimuth_over_noise_and_overlap_gradient))
    /// or the FFT path's. `Ok(None)` where the white one gives none.
    ///
    /// # Errors
    /// Building the grids again ([`Error`] of the FFT layer).
    pub fn mean_mtf_over_azimuth_over_noise_and_gradient(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
        noise: &super::NoiseShape,
    ) -> Result<Option<(AzimuthalMean, Vec<f64>)>, Error> {
        if matches!(self.engine(), Engine::Overlap { .. } | Engine::Exact1d) {
            return Ok(self.mean_mtf_over_azimuth_over_noise_and_overlap_gradient(first, directions, noise));
        }
        if !matches!(self.engine(), Engine::Fft { .. }) {
            return Ok(None);
        }
        let mean = self.mean_mtf_over_azimuth(first, Some(noise));
        Ok(self
            .engine
            .wavefront_gradient_over_azimuth_over_noise(first, mean.azimuths, directions, noise)?
            .map(|g| (mean, g)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference of the cached [`radial_field`]: its profiles evaluated at every pixel.
    fn radial_field_direct(
        sampled: &crate::fft::SampledPupil,
        radial: &crate::radial::RadialPupil,
        lambda: f64,
    ) -> (Vec<Complex64>, f64) {
        let n = sampled.n();
        let k = 2.0 * PI / lambda;
        let (area, opd) = (sampled.amplitude(), sampled.opd_m());
        let scale2 = radial.frequency_scale().powi(2);
        let mut field = vec![Complex64::new(0.0, 0.0); n * n];
        let mut weight = 0.0;
        for (idx, x, y) in crate::fft::transmitting_pixels(n, area) {
            // a pupil in direction cosines fills the circle of radius 1/k of the paraxial one
            // (its rim pixel by pixel, not by area fraction)
            let q = (x * x + y * y) * scale2;
            if scale2 > 1.0 && q > 1.0 {
                continue;
            }
            let q = q.min(1.0);
            let a = radial.amplitude(q);
            weight += area[idx] * a * a;
            let w = opd[idx] + radial.opd_beyond_defocus_m(q) + radial.oblique_opd_m(x, y);
            field[idx] = Complex64::from_polar(area[idx] * a, k * w);
        }
        (field, weight)
    }

    /// The reference of the cached [`order_field_move`]: its profiles evaluated at every pixel.
    fn order_field_move_direct(
        sampled: &crate::fft::SampledPupil,
        radial: &crate::radial::RadialPupil,
        d_amplitude: &crate::radial::RadialProfile,
        d_wavefront: &crate::radial::RadialProfile,
        lambda: f64,
    ) -> (Vec<Complex64>, f64) {
        let n = sampled.n();
        let k = 2.0 * PI / lambda;
        let (area, opd) = (sampled.amplitude(), sampled.opd_m());
        let scale2 = radial.frequency_scale().powi(2);
        let slope = d_wavefront.fitted_slope();
        let mut moved = vec![Complex64::new(0.0, 0.0); n * n];
        let mut d_weight = 0.0;
        for (idx, x, y) in crate::fft::transmitting_pixels(n, area) {
            let r2 = x * x + y * y;
            let q = r2 * scale2;
            if scale2 > 1.0 && q > 1.0 {
                continue;
            }
            let q = q.min(1.0);
            let a = radial.amplitude(q);
            let w = opd[idx] + radial.opd_beyond_defocus_m(q) + radial.oblique_opd_m(x, y);
            let da = d_amplitude.value(q);
            let dw = d_wavefront.value(q) + slope * (r2 - q);
            d_weight += 2.0 * area[idx] * a * da;
            moved[idx] = Complex64::from_polar(area[idx], k * w) * Complex64::new(da, k * a * dw);
        }
        (moved, d_weight)
    }
    use crate::fft::Aberrations;

    /// The radial pupil's field and its move from the profiles' samples cached per grid
    /// ([`RadialCache`], reused across the wavelengths as the FFT path's layer reuses it) are
    /// the fields from the profiles evaluated at every pixel ([`radial_field_direct`],
    /// [`order_field_move_direct`]), bit for bit: a phase lens's pupil (a polynomial phase whose
    /// coefficient scales with λ, the reference sphere, a tabulated amplitude, an `m = 0`
    /// Zernike term) on axis and seen off axis, and the same pupil in direction cosines (its
    /// frequency scale drops the rim's pixels), at three wavelengths each, 48 samples.
    #[test]
    fn radial_field_from_cached_samples_is_the_direct_field() {
        use crate::radial::{DirectionCosines, Oblique, RadialProfile, RadialPupil};
        let n = 48;
        let phase = Arc::new(RadialProfile::even_polynomial(vec![0.0, -2.0e3, 35.0, -1.5]).unwrap());
        let sphere = Arc::new(RadialProfile::reference_sphere(0.5e-3, 2.0e-3).unwrap());
        let amplitude =
            Arc::new(RadialProfile::table(vec![0.0, 0.4, 0.7, 1.0, 1.2], vec![1.0, 0.97, 0.9, 0.8, 0.78]).unwrap());
        let d_amplitude = RadialProfile::even_polynomial(vec![0.01, -0.02]).unwrap();
        let d_wavefront = RadialProfile::table(vec![0.0, 0.5, 0.8, 1.0], vec![0.0, 2e-9, 5e-9, 9e-9]).unwrap();
        let pupil_at = |lambda: f64| {
            let terms = vec![(lambda / (2.0 * PI), phase.clone()), (1.0, sphere.clone())];
            RadialPupil::new(Some(amplitude.clone()), terms, vec![(11, 0.02e-6)]).unwrap()
        };
        let oblique = Oblique::new(0.5e-3, 2.0e-3, 0.05, -0.02).unwrap();
        let cosines = DirectionCosines::new(0.3).unwrap();
        let lambdas = [0.45e-6, 0.55e-6, 0.65e-6];
        let kinds: [&dyn Fn(f64) -> RadialPupil; 3] =
            [&|l| pupil_at(l), &|l| pupil_at(l).with_oblique(oblique), &|l| cosines.map(&pupil_at(l), 0.1e-6).unwrap()];
        let mut cache = RadialCache::default();
        let mut compared = 0;
        for _ in 0..2 {
            for kind in &kinds {
                for &lambda in &lambdas {
                    let radial = kind(lambda);
                    let defocus = Aberrations { w020_m: radial.fitted_defocus_m(), ..Aberrations::default() };
                    let sampled = SampledPupil::new(n, &Aperture::circle(), &defocus).unwrap();
                    let (field, weight) = radial_field(&mut cache, &sampled, &radial, lambda);
                    let (reference, reference_weight) = radial_field_direct(&sampled, &radial, lambda);
                    assert_eq!(weight.to_bits(), reference_weight.to_bits(), "{lambda}");
                    assert!(field.iter().any(|p| p.norm() > 0.0));
                    for (p, r) in field.iter().zip(&reference) {
                        assert_eq!((p.re.to_bits(), p.im.to_bits()), (r.re.to_bits(), r.im.to_bits()), "{lambda}");
                    }
                    let (moved, d_weight) =
                        order_field_move(&mut cache, &sampled, &radial, &d_amplitude, &d_wavefront, lambda);
                    let (reference, reference_weight) =
                        order_field_move_direct(&sampled, &radial, &d_amplitude, &d_wavefront, lambda);
                    assert_eq!(d_weight.to_bits(), reference_weight.to_bits(), "{lambda}");
                    assert!(moved.iter().any(|p| p.norm() > 0.0));
                    for (p, r) in moved.iter().zip(&reference) {
                        assert_eq!((p.re.to_bits(), p.im.to_bits()), (r.re.to_bits(), r.im.to_bits()), "{lambda}");
                    }
                    compared += 1;
                }
            }
        }
        assert_eq!(compared, 18);
        // one set of pixels per frequency scale, each profile sampled once however many wavelengths
        assert_eq!(cache.sets.len(), 2);
        assert!(cache.sets.iter().all(|s| s.profiles.len() <= RADIAL_PROFILES && s.oblique.len() <= 1));
    }

    /// Engines of one lens under `ρ`, `ρλ` and `ρλ²` (the spectral gradient's three) built with
    /// [`SharedGrids`] against each built alone: the same OTF along every direction read, bit for
    /// bit, with the grids of the nodes they have in common made once (an annulus with coma and a
    /// chromatic defocus: the FFT path at 32 samples, a 10 nm band at 800 nm).
    #[test]
    fn shared_grids_are_the_grids_each_engine_makes() {
        #[derive(Debug)]
        struct Annulus(Arc<Aperture>);
        impl LensModel for Annulus {
            fn f_number(&self) -> f64 {
                2.5
            }
            fn focal_length(&self) -> f64 {
                3.36e-3
            }
            fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
                let wavefront =
                    crate::Wavefront { coma_m: 0.3e-6, ..crate::Wavefront::defocus(2.0 * (lambda - 0.8e-6)) };
                vec![Order::new(0.5, Pupil::Aperture(self.0.clone()), wavefront)]
            }
        }
        let lens = Annulus(Arc::new(Aperture::annulus(0.3).unwrap()));
        let band = radiometry::Spectrum::Gaussian(radiometry::Gaussian::from_range(0.8e-6, 10e-9, 1.0).unwrap());
        let linear = radiometry::Spectrum::Linear { slope: 1.0 };
        let spectra = [
            band.clone(),
            radiometry::Spectrum::product(vec![band.clone(), linear.clone()]),
            radiometry::Spectrum::product(vec![band, linear.clone(), linear]),
        ];
        let settings = super::super::Settings {
            pupil_samples: Some(32),
            tolerance: 1e-4,
            spectral_tolerance: Some(1e-9),
            ..super::super::Settings::default()
        };
        let nyquist = 1.0 / (2.0 * 5.2e-6);
        let shared = SharedGrids::new();
        let build = |s| Polychromatic::with_settings(&lens, s, Field::ON_AXIS, nyquist, None, settings).unwrap();
        let alone: Vec<_> = spectra.iter().map(build).collect();
        let together: Vec<_> = spectra
            .iter()
            .map(|s| {
                Polychromatic::with_shared_grids(&lens, s, Field::ON_AXIS, nyquist, None, settings, &shared).unwrap()
            })
            .collect();
        let bits = |z: Complex64| (z.re.to_bits(), z.im.to_bits());
        for nu in [0.0, 0.1, 0.37, 0.8, 0.99].map(|f| f * nyquist) {
            for azimuth in [0.0, 0.7, 2.0] {
                // each engine read alone, and the three read together (each shared grid once)
                let at_once = Polychromatic::otf_along_together(&together, nu, azimuth);
                for ((a, b), c) in alone.iter().zip(&together).zip(at_once) {
                    assert!(matches!(b.engine(), Engine::Fft { pupil_samples: 32, .. }), "{:?}", b.engine());
                    let a = a.otf_along(nu, azimuth);
                    assert_eq!(bits(a), bits(b.otf_along(nu, azimuth)), "{nu} {azimuth}");
                    assert_eq!(bits(a), bits(c), "{nu} {azimuth}");
                }
            }
        }
        // every node's grid is made once: the second and third engines find theirs
        let (found, made) = shared.found_and_made();
        assert!(made > 0 && found >= made, "found {found}, made {made}");
        shared.forget();
        assert_eq!(shared.found_and_made(), (found, made));
    }

    /// [`edge_motion`] (the pixels near the inner circle only) against the field's derivative
    /// written on every pixel of the grid (each pixel's [`Aperture::obscuration_rate_in`]): the
    /// same values bit for bit on its rows, zero on the others, and the same `∂(Σ A)`; an
    /// annulus, a sector of a ring, a decentred annulus (its wavefront then measured from the
    /// lens axis), at 48 and 64 samples.
    #[test]
    fn edge_motion_is_the_whole_grids() {
        let lambda = 0.8e-6;
        let aberrations = Aberrations { w020_m: 0.5e-6, w222_m: 0.2e-6, field: 1.0, ..Aberrations::default() };
        let apertures = [
            Aperture::annulus(0.3).unwrap(),
            Aperture::ring(0.45, 0.9, Some((-0.4, 2.1))).unwrap(),
            Aperture::annulus(0.55).unwrap().decentred(0.15, -0.05).unwrap(),
        ];
        for n in [48, 64] {
            for aperture in &apertures {
                let sampled = SampledPupil::new(n, aperture, &aberrations).unwrap();
                let h = 2.0 / n as f64;
                let k = 2.0 * PI / lambda;
                let (mut whole, mut d_weight) = (vec![Complex64::new(0.0, 0.0); n * n], 0.0);
                for j in 0..n {
                    for i in 0..n {
                        let (x0, y0) = (-1.0 + i as f64 * h, -1.0 + j as f64 * h);
                        let rate = aperture.obscuration_rate_in(x0, x0 + h, y0, y0 + h).unwrap() / (h * h);
                        if rate != 0.0 {
                            d_weight += rate;
                            whole[j * n + i] = Complex64::from_polar(rate, k * sampled.opd_m()[j * n + i]);
                        }
                    }
                }
                let (moved, rows, dw) = edge_motion(&sampled, aperture, lambda).unwrap();
                assert_eq!(dw, d_weight);
                assert!(d_weight < 0.0, "{d_weight}");
                assert_eq!(moved.len(), rows.len() * n);
                for j in 0..n {
                    let row = &whole[j * n..(j + 1) * n];
                    if rows.contains(&j) {
                        assert_eq!(row, &moved[(j - rows.start) * n..(j - rows.start + 1) * n], "row {j}");
                    } else {
                        assert!(row.iter().all(|z| *z == Complex64::new(0.0, 0.0)), "row {j}");
                    }
                }
                assert!(rows.len() < n, "{rows:?}");
            }
        }
        assert!(
            edge_motion(
                &SampledPupil::new(16, &Aperture::circle(), &aberrations).unwrap(),
                &Aperture::mask(|_, _| true),
                lambda
            )
            .is_none()
        );
    }
}
