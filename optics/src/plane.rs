//! The 2-D transform of a sampled PSF at any frequency, fast: the samples' transform on a
//! 2×-padded grid once (one FFT), then Gaussian gridding back to the frequency asked — the
//! type-2 non-uniform FFT of Dutt & Rokhlin (SIAM J. Sci. Comput. 14, 1993) and Greengard & Lee
//! (SIAM Rev. 46, 2004), with its error bounded in closed form (docs/physics.md, "PSF stacks").
//!
//! The samples `d_l` (`l = (l_x, l_y)`, `l_x = j − ⌊n_x/2⌋`, `l_y = i − ⌊n_y/2⌋`, summing to 1)
//! have the transform `T(θ) = Σ_l d_l e^{−2πi θ·l}` (θ in cycles per sample, 1-periodic). With
//! the Gaussian `φ(x) = e^{−x²/(4τ)}` (x in cells of the padded grid of `N = 2 max(n_x, n_y)`
//! points per turn) and its transform `φ̂(f) = √(4πτ) e^{−4π²τ f²}`, the grid holds
//! `G_g = Σ_l d_l/(φ̂(l_x/N) φ̂(l_y/N)) e^{−2πi g·l/N}` (an FFT), and by Poisson's summation
//!
//! ```text
//! Σ_g G_g φ(Nθ_x − g_x) φ(Nθ_y − g_y) = Σ_l d_l e^{−2πi θ·l} Π_axes (1 + Σ_{r≠0} e^{−2πi θ r N} φ̂(l/N + r)/φ̂(l/N))
//! ```
//!
//! so the sum over all grid points is `T(θ)` up to the aliases `r ≠ 0`; the sum is taken over
//! the [`PLANE_WIDTH`]² nearest points. Both errors are bounded ([`SampledPlane::error_bound`]).

use std::f64::consts::PI;

use num_complex::Complex64;
use realfft::RealFftPlanner;
use rustfft::FftPlanner;

/// The Gaussian kernel's variance parameter τ, in grid cells² (`φ(x) = e^{−x²/(4τ)}`): the
/// worst alias ratio (at `|l/N| = 1/4`, the samples' highest index on the 2×-padded grid) is
/// `e^{−2π²τ}` = 2.7e-9.
pub const PLANE_TAU: f64 = 1.0;

/// Grid points per axis the kernel takes around each frequency: beyond `PLANE_WIDTH/2 = 11`
/// cells the kernel is below `e^{−121/4}` = 7e-14.
pub const PLANE_WIDTH: usize = 22;

/// One PSF's samples prepared for their 2-D transform at any frequency (module docs).
#[derive(Clone, PartialEq)]
pub struct SampledPlane {
    /// grid points per turn along each axis (`2 max(n_x, n_y)`)
    n: usize,
    /// the half-plane `θ_x ≥ 0` (the other half is the conjugate), column by column: columns
    /// `g_x` from `−PLANE_WIDTH/2` to `N/2 + PLANE_WIDTH/2`, each holding the [`COLUMN`](Self::column)
    /// rows `g_y` from `−N/2 − PLANE_WIDTH/2` to `N/2 + PLANE_WIDTH/2` (periodic in `g_y`,
    /// unrolled so that the kernel reads each column's points in one contiguous run)
    grid: Vec<Complex64>,
    /// the point the transform is taken about, in samples from the centre sample `[x, y]`
    centroid: [f64; 2],
    /// `Σ |d_l|` (1 for samples ≥ 0)
    absolute_sum: f64,
}

impl std::fmt::Debug for SampledPlane {
    /// The grid's size, not its values (a few million).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SampledPlane")
            .field("grid", &format_args!("{} × {}", self.grid.len() / self.column(), self.column()))
            .field("centroid", &self.centroid)
            .field("absolute_sum", &self.absolute_sum)
            .finish()
    }
}

/// `φ̂(f)` of the Gaussian kernel (module docs).
fn kernel_transform(f: f64) -> f64 {
    (4.0 * PI * PLANE_TAU).sqrt() * (-4.0 * PI * PI * PLANE_TAU * f * f).exp()
}

/// `e^{−k²/(4τ)}` for `k` from 0 to `PLANE_WIDTH − 1`, computed once.
fn kernel_steps() -> &'static [f64; PLANE_WIDTH] {
    static STEPS: std::sync::OnceLock<[f64; PLANE_WIDTH]> = std::sync::OnceLock::new();
    STEPS.get_or_init(|| std::array::from_fn(|k| (-((k * k) as f64) / (4.0 * PLANE_TAU)).exp()))
}

/// The kernel's weights `φ(u − g)` at the [`PLANE_WIDTH`] grid points `g` nearest `u` (from the
/// first, which is returned). With `d = u − first` the weights are
/// `e^{−(d−k)²/(4τ)} = e^{−d²/(4τ)} (e^{d/(2τ)})^k e^{−k²/(4τ)}` (Greengard & Lee's fast
/// Gaussian gridding): two exponentials a point, not one a weight; the powers' rounding is
/// below `PLANE_WIDTH ε` relative ([`SampledPlane::error_bound`]).
fn weights(u: f64) -> (i64, [f64; PLANE_WIDTH]) {
    let first = u.floor() as i64 - (PLANE_WIDTH / 2) as i64 + 1;
    let d = u - first as f64;
    let ratio = (d / (2.0 * PLANE_TAU)).exp();
    let mut power = (-d * d / (4.0 * PLANE_TAU)).exp();
    let steps = kernel_steps();
    let mut w = [0.0; PLANE_WIDTH];
    for (w, &step) in w.iter_mut().zip(steps) {
        *w = power * step;
        power *= ratio;
    }
    (first, w)
}

impl SampledPlane {
    /// Rows `g_y` each column holds: `N + PLANE_WIDTH + 1`.
    fn column(&self) -> usize {
        self.n + PLANE_WIDTH + 1
    }

    /// Bytes a plane of `ny × nx` samples holds, `(kept, while built)`: the half-plane grid it
    /// keeps, `(N/2 + PLANE_WIDTH + 1) × (N + PLANE_WIDTH + 1)` complex values with
    /// `N = 2 max(n_x, n_y)` (about `32 max(n_x, n_y)²` bytes), and the `(N/2 + 1) × N` half
    /// spectrum it is built through with its rows' real buffer (freed after). A stack's caller
    /// checks `slices × kept + while built` against its memory budget before any plane is made.
    pub fn bytes(ny: usize, nx: usize) -> (f64, f64) {
        let n = 2.0 * nx.max(ny) as f64;
        let value = std::mem::size_of::<Complex64>() as f64;
        let width = PLANE_WIDTH as f64;
        ((0.5 * n + width + 1.0) * (n + width + 1.0) * value, (0.5 * n + 2.0) * n * value)
    }

    /// The plane of `values` (C order `[row y][column x]`, `ny × nx`, summing to 1 within 1e-9)
    /// about `centroid` (samples from the centre sample `(⌊nx/2⌋, ⌊ny/2⌋)`, `[x, y]`).
    /// `planner` (the columns' complex transforms) is shared between the slices of a stack.
    pub fn new(values: &[f64], shape: [usize; 2], centroid: [f64; 2], planner: &mut FftPlanner<f64>) -> Self {
        Self::scaled(values, 1.0, shape, centroid, &mut RealFftPlanner::new(), planner)
    }

    /// The planes of a stack's slices (`values`: `[slice][row y][column x]`, each slice divided
    /// by its `sums[k]` so that it sums to 1; `centroids[k]` as in [`new`](Self::new)), built in
    /// parallel (rayon), one slice at a time per worker: at most `workers` (≥ 1; and at most
    /// rayon's threads) transforms are
    /// being built at once, each taking the `while built` bytes of [`bytes`](Self::bytes), so a
    /// caller bounds the memory by the number of workers it gives. The same planes as
    /// [`new`](Self::new) of each slice divided by its sum, in order.
    pub fn stack(
        values: &[f64],
        [ny, nx]: [usize; 2],
        sums: &[f64],
        centroids: &[[f64; 2]],
        workers: usize,
    ) -> Vec<Self> {
        use rayon::prelude::*;
        assert_eq!(values.len(), sums.len() * ny * nx, "SampledPlane::stack: {} values", values.len());
        assert_eq!(
            sums.len(),
            centroids.len(),
            "SampledPlane::stack: {} sums, {} centroids",
            sums.len(),
            centroids.len()
        );
        let depth = sums.len();
        if depth == 0 {
            return Vec::new();
        }
        let per_worker = depth.div_ceil(workers.clamp(1, rayon::current_num_threads()));
        let size = ny * nx;
        (0..depth.div_ceil(per_worker))
            .into_par_iter()
            .flat_map_iter(|w| {
                let (mut real, mut complex) = (RealFftPlanner::new(), FftPlanner::new());
                (w * per_worker..((w + 1) * per_worker).min(depth))
                    .map(|k| {
                        let slice = &values[k * size..(k + 1) * size];
                        Self::scaled(slice, sums[k], [ny, nx], centroids[k], &mut real, &mut complex)
                    })
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    /// [`new`](Self::new) of `values / sum`, each value divided as it is read. The rows are real:
    /// each goes to its half spectrum `g_x = 0 … N/2` by a real-to-complex transform (realfft),
    /// then those `N/2 + 1` columns are transformed along `y`; the other half-plane is never
    /// formed (the transform is Hermitian, `G(−g) = G(g)*`, and [`transform`](Self::transform)
    /// reads `θ_x ≥ 0`).
    fn scaled(
        values: &[f64],
        sum: f64,
        [ny, nx]: [usize; 2],
        centroid: [f64; 2],
        real: &mut RealFftPlanner<f64>,
        complex: &mut FftPlanner<f64>,
    ) -> Self {
        assert_eq!(values.len(), ny * nx, "SampledPlane: {} values for {ny} × {nx}", values.len());
        let n = 2 * nx.max(ny);
        let (rows_fft, columns_fft) = (real.plan_fft_forward(n), complex.plan_fft_forward(n));
        let wrap = |l: i64| l.rem_euclid(n as i64) as usize;
        // the kernel's deconvolution 1/φ̂(l/N) along each axis, once per index
        let correction = |count: usize| -> Vec<f64> {
            (0..count).map(|j| 1.0 / kernel_transform((j as i64 - (count / 2) as i64) as f64 / n as f64)).collect()
        };
        let (cx, cy) = (correction(nx), correction(ny));
        // the half spectrum, column-major: column g_x (0 … N/2) holds N rows g_y (wrapped)
        let half_width = n / 2 + 1;
        let mut spectrum = vec![Complex64::new(0.0, 0.0); half_width * n];
        let mut line = rows_fft.make_input_vec();
        let mut out = rows_fft.make_output_vec();
        let mut scratch = rows_fft.make_scratch_vec();
        for (i, row) in values.chunks_exact(nx).enumerate() {
            let ly = i as i64 - (ny / 2) as i64;
            line.iter_mut().for_each(|v| *v = 0.0);
            for (j, (&v, &c)) in row.iter().zip(&cx).enumerate() {
                line[wrap(j as i64 - (nx / 2) as i64)] = v / sum * cy[i] * c;
            }
            rows_fft.process_with_scratch(&mut line, &mut out, &mut scratch).expect("realfft: buffers of its own plan");
            let y = wrap(ly);
            for (x, &v) in out.iter().enumerate() {
                spectrum[x * n + y] = v;
            }
        }
        columns_fft.process(&mut spectrum);
        // the kept columns g_x = −PLANE_WIDTH/2 … N/2 + PLANE_WIDTH/2, rows unrolled from
        // g_y = −N/2 − PLANE_WIDTH/2; outside 0 … N/2 a column is its mirror's conjugate read
        // at −g_y (G(g_x, g_y) = G(g_x − N, g_y) = G(N − g_x, −g_y)*)
        let half = PLANE_WIDTH / 2;
        let height = n + PLANE_WIDTH + 1;
        let first_row = -((n / 2 + half) as i64);
        let mut grid = Vec::with_capacity((n / 2 + 2 * half + 1) * height);
        for gx in -(half as i64)..=(n / 2 + half) as i64 {
            let (source, mirrored) =
                if (0..=(n / 2) as i64).contains(&gx) { (gx as usize, false) } else { (wrap(-gx), true) };
            let column = &spectrum[source * n..(source + 1) * n];
            // row g_y of the column is column[wrap(±g_y)], stepped by one (wrapping) per row
            let mut at = if mirrored { wrap(-first_row) } else { wrap(first_row) };
            for _ in 0..height {
                if mirrored {
                    grid.push(column[at].conj());
                    at = if at == 0 { n - 1 } else { at - 1 };
                } else {
                    grid.push(column[at]);
                    at = if at + 1 == n { 0 } else { at + 1 };
                }
            }
        }
        SampledPlane { n, grid, centroid, absolute_sum: values.iter().map(|v| (v / sum).abs()).sum() }
    }

    /// `Re Σ_l d_l e^{−2πi θ·(l − c)}` at `theta = [θ_x, θ_y]` cycles per sample (each within
    /// ±1/2), `c` the centroid: the real part of the samples' transform about their centroid,
    /// to within [`error_bound`](Self::error_bound).
    pub fn transform(&self, theta: [f64; 2]) -> f64 {
        // Re F(−θ) = Re F(θ)* = Re F(θ): read the half-plane θ_x ≥ 0
        let [tx, ty] = if theta[0] < 0.0 { [-theta[0], -theta[1]] } else { theta };
        let (x0, wx) = weights(tx * self.n as f64);
        let (y0, wy) = weights(ty * self.n as f64);
        let half = (PLANE_WIDTH / 2) as i64;
        let height = self.column();
        // column g_x sits at (g_x + PLANE_WIDTH/2) × height, row g_y at g_y + N/2 + PLANE_WIDTH/2
        let row = (y0 + (self.n / 2) as i64 + half) as usize;
        let mut acc = Complex64::new(0.0, 0.0);
        for (k, &wx) in wx.iter().enumerate() {
            let start = (x0 + k as i64 + half) as usize * height + row;
            let run = &self.grid[start..start + PLANE_WIDTH];
            let (mut re, mut im) = (0.0, 0.0);
            for (g, &wy) in run.iter().zip(&wy) {
                re += g.re * wy;
                im += g.im * wy;
            }
            acc += Complex64::new(re, im) * wx;
        }
        // about the centroid: e^{+2πi θ·c}, its angle reduced to one turn
        let turn = 2.0 * PI * (tx * self.centroid[0] + ty * self.centroid[1]).fract();
        (acc * Complex64::from_polar(1.0, turn)).re
    }

    /// A bound on `|transform − exact|` (module docs): the aliases, `Σ|d| ((1 + a)² − 1)` with
    /// `a = max_{|f| ≤ 1/4} Σ_{r≠0} φ̂(f + r)/φ̂(f)`, plus the points left out,
    /// `2 max|G| S t` with `max|G| ≤ Σ|d| / φ̂(1/4)²`, `S = Σ_g φ(u − g) ≤ √(4πτ)(1 + 2 Σ_k e^{−4π²τk²})`
    /// and `t = 2 Σ_{m≥0} φ(PLANE_WIDTH/2 + m)`; plus the rounding of the transforms
    /// (`4 log₂N ε` relative), of the weights' powers (`PLANE_WIDTH ε`) and of the `PLANE_WIDTH²` terms.
    pub fn error_bound(&self) -> f64 {
        let alias = (0..=64)
            .map(|i| {
                let f = 0.25 * i as f64 / 64.0;
                (1..=4)
                    .flat_map(|r| [r as f64, -(r as f64)])
                    .map(|r| kernel_transform(f + r) / kernel_transform(f))
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
        let largest = self.absolute_sum / kernel_transform(0.25).powi(2);
        let poisson: f64 = (1..=4).map(|k| (-4.0 * PI * PI * PLANE_TAU * (k * k) as f64).exp()).sum();
        let sum = (4.0 * PI * PLANE_TAU).sqrt() * (1.0 + 2.0 * poisson);
        let tail: f64 =
            2.0 * (0..64).map(|m| (-((PLANE_WIDTH / 2 + m) as f64).powi(2) / (4.0 * PLANE_TAU)).exp()).sum::<f64>();
        let relative = 4.0 * (self.n as f64).log2() + 2.0 * PLANE_WIDTH as f64 + 2.0;
        let rounding = relative * f64::EPSILON * largest * sum * sum;
        self.absolute_sum * ((1.0 + alias).powi(2) - 1.0) + 2.0 * largest * sum * tail + rounding
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stack's planes, built in parallel from unnormalized slices, are each slice's plane
    /// built alone from its normalized samples, bit for bit and in order, whatever the workers.
    #[test]
    fn a_stack_is_its_slices_one_by_one() {
        let (depth, ny, nx) = (5, 9, 14);
        let values: Vec<f64> =
            (0..depth * ny * nx).map(|i| ((i * 29 % 13) as f64 + 0.25) * (1 + i / (ny * nx)) as f64).collect();
        let sums: Vec<f64> = values.chunks_exact(ny * nx).map(|s| s.iter().sum()).collect();
        let centroids: Vec<[f64; 2]> = (0..depth).map(|k| [0.1 * k as f64, -0.2 * k as f64]).collect();
        let alone: Vec<SampledPlane> = values
            .chunks_exact(ny * nx)
            .zip(&sums)
            .zip(&centroids)
            .map(|((slice, sum), &c)| {
                let normalized: Vec<f64> = slice.iter().map(|v| v / sum).collect();
                SampledPlane::new(&normalized, [ny, nx], c, &mut FftPlanner::new())
            })
            .collect();
        for workers in [1, 2, 3, 64] {
            assert!(SampledPlane::stack(&values, [ny, nx], &sums, &centroids, workers) == alone, "{workers} workers");
        }
        assert!(SampledPlane::stack(&[], [ny, nx], &[], &[], 2).is_empty());
    }

    /// The gridded transform against the direct sum `Σ d_l cos(2π θ·(l − c))` written here, at
    /// frequencies off the grid's, on an asymmetric, shifted, non-square set of samples with
    /// a negative one: within the stated bound, and the bound below 1e-8.
    #[test]
    fn the_gridded_transform_is_the_direct_sum_within_its_bound() {
        let (ny, nx) = (12, 17);
        let mut values: Vec<f64> =
            (0..ny * nx).map(|i| ((i * 37 % 11) as f64 + 0.5) * ((i % nx) as f64 + 1.0)).collect();
        values[5 * nx + 9] += 300.0;
        values[3] = -2.0;
        let sum: f64 = values.iter().sum();
        values.iter_mut().for_each(|v| *v /= sum);
        let centroid = [0.37, -1.25];
        let plane = SampledPlane::new(&values, [ny, nx], centroid, &mut FftPlanner::new());
        let bound = plane.error_bound();
        assert!(bound < 1e-8, "{bound}");
        let direct = |t: [f64; 2]| -> f64 {
            let mut acc = 0.0;
            for i in 0..ny {
                for j in 0..nx {
                    let lx = j as f64 - (nx / 2) as f64 - centroid[0];
                    let ly = i as f64 - (ny / 2) as f64 - centroid[1];
                    acc += values[i * nx + j] * (2.0 * PI * (t[0] * lx + t[1] * ly)).cos();
                }
            }
            acc
        };
        let mut worst: f64 = 0.0;
        for tx in [-0.5, -0.31, -0.0123, 0.0, 0.07, 0.25, 0.4999, 0.5] {
            for ty in [-0.5, -0.2, 0.0, 0.013, 0.333, 0.5] {
                let (got, want) = (plane.transform([tx, ty]), direct([tx, ty]));
                worst = worst.max((got - want).abs());
                assert!((got - want).abs() <= bound, "θ = ({tx}, {ty}): {got} vs {want}, bound {bound:e}");
            }
        }
        eprintln!("worst {worst:.2e}, bound {bound:.2e}");
        assert!((plane.transform([0.0, 0.0]) - 1.0).abs() <= bound);
    }
}
