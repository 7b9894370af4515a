//! A lens given by its point spread functions: a stack of PSFs at a few wavelengths, simulated
//! (a designer's FDTD or angular-spectrum run, `asnr psf`) or measured, sampled on a square grid
//! at the detector.
//!
//! The stack becomes one imaging order whose OTF is a table against wavelength and frequency
//! ([`optics::Pupil::Table`]), each wavelength's lateral offset kept as the order's image shift
//! (docs/physics.md, "Designs given as data", PSF stacks).

use std::sync::Arc;

use optics::{Field, LensModel, Order, OtfTable, Pupil, SampledLine, SampledPlane, Wavefront};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex64;

use crate::Error;
use crate::chromatic::{Curve, check, check_efficiency_below_transmission, check_fraction};

/// How far below zero a sample may be, as a fraction of its slice's peak, before the stack is
/// refused: simulated PSFs carry small negative ringing (an OTF cut at the grid's Nyquist
/// frequency rings at about 1e-3 of the peak; `asnr psf --stack` at 2 µm on the paper's lens)
/// and measured ones a background subtracted with its noise; a value below
/// `−PSF_NEGATIVE_FLOOR × peak` is not noise but a sign error or an offset. The negative samples
/// accepted are kept as they are (nothing is clipped): they enter the sum and the OTF, and
/// together they may hold at most [`PSF_NEGATIVE_MASS`] of the slice's sum.
pub const PSF_NEGATIVE_FLOOR: f64 = 1e-2;

/// The largest share of a slice's sum its negative samples may hold together (`Σ|v<0| ≤ 1 % Σv`):
/// beyond it the background was over-subtracted. It bounds the OTF's modulus by
/// `1 + 2 PSF_NEGATIVE_MASS`.
pub const PSF_NEGATIVE_MASS: f64 = 1e-2;

/// The width, in samples, of the stack's border band whose light [`PsfReport::border_fraction`]
/// reports: light there says the PSF was probably cut off by the stack's edge.
pub const PSF_BORDER_SAMPLES: usize = 3;

/// Zero padding of the transforms: each line spread function of `n` samples is transformed on
/// `PSF_PADDING × max(nx, ny)` points, so the table's frequency step is `1/(PSF_PADDING n p)`, a
/// quarter of the grid's own `1/(n p)` (the OTF between the grid's frequencies is the exact
/// transform of the samples, not an interpolation of the table).
pub const PSF_PADDING: usize = 4;

/// The largest element count of a stack (`depth × ny × nx`) the readers accept: 2²⁶, 512 MiB as
/// f64 (a 1024 × 1024 × 64 stack); a file's header giving more is refused before any allocation.
pub const PSF_MAX_ELEMENTS: usize = 1 << 26;

/// Below this difference between the tangential and the sagittal curves (everywhere), and
/// between the tangential curve and the 2-D transform along [`PSF_SYMMETRY_AZIMUTHS`] azimuths
/// (at every [`PSF_SYMMETRY_STRIDE`]th frequency), the stack is taken as round and both curves
/// are their mean: the rounding of a radially symmetric PSF (a float32 file's 6e-8) must not
/// make the metric treat it as direction dependent. Any other stack keeps each slice's 2-D
/// transform ([`optics::SampledPlane`]) and its ASNR takes the mean MTF over azimuth.
pub const PSF_SYMMETRY_TOLERANCE: f64 = 1e-6;

/// Azimuths on `[0, π)` (from the field direction, every `π/8`) along which a stack's 2-D
/// transform is compared with its tangential curve to take it as round
/// ([`PSF_SYMMETRY_TOLERANCE`]).
pub const PSF_SYMMETRY_AZIMUTHS: usize = 8;

/// Every how many of the table's frequencies the 2-D transform is compared with the tangential
/// curve along the [`PSF_SYMMETRY_AZIMUTHS`] azimuths: every second step `2/(n p)` of the
/// samples' own frequency grid (the table's step is a quarter of it). A sampled check: a PSF
/// that is round at these points and not between them would be taken as round.
pub const PSF_SYMMETRY_STRIDE: usize = 8;

/// Below this distance from the centre sample, in samples, a centroid is taken as the centre
/// (no lateral shift): a shift of 1e-6 samples turns the OTF's phase by under 1e-5 rad up to the
/// stack's Nyquist frequency, and a centred PSF's rounding must not send the scene to the
/// engines of shifted images.
pub const PSF_CENTRE_TOLERANCE: f64 = 1e-6;

/// The fewest samples along each side of a slice.
pub const PSF_MIN_SIDE: usize = 8;

/// What [`PsfStack::new`] found in a stack besides its OTF: what the scene reports or warns
/// about.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct PsfReport {
    /// Slices, rows (y) and columns (x).
    pub shape: [usize; 3],
    /// The transform length of each line spread function (after zero padding).
    pub transform_length: usize,
    /// The largest fraction of a slice's light within [`PSF_BORDER_SAMPLES`] of the stack's
    /// border, and the wavelength (m) of that slice.
    pub border_fraction: (f64, f64),
    /// The largest |imaginary part| of a re-centred OTF below the stack's Nyquist frequency
    /// (the PSF's asymmetry about its centroid beyond the shift; the table holds the real part),
    /// with its wavelength (m) and frequency (cycles/m).
    pub imaginary: (f64, f64, f64),
    /// The centroid of each slice from the stack's centre sample `(⌊nx/2⌋, ⌊ny/2⌋)`, `[x, y]`, m.
    pub centroids_m: Vec<[f64; 2]>,
    /// The aliasing estimate: half the largest modulus of a slice's transform at the stack's
    /// Nyquist frequency `1/(2p)`, along either axis, with the slice's wavelength (m). Sampling
    /// folds the OTF about `1/(2p)`: there the samples' transform holds the OTF twice
    /// (`Ô(1/(2p)) = O(1/(2p)) + O(−1/(2p))`), so half of it is the OTF's value at the stack's
    /// Nyquist frequency; if `|O|` does not rise beyond it, no alias `O(k/p ± ν)` folded onto a
    /// frequency below exceeds it, nor does the error of the mean MTF (docs/physics.md, "PSF
    /// stacks").
    pub aliasing: (f64, f64),
}

/// A lens whose single imaging order is given by its PSFs at a few wavelengths (module docs).
///
/// - The PSF of slice `k` is sampled at `x = (j − ⌊nx/2⌋) p`, `y = (i − ⌊ny/2⌋) p` (column `j`,
///   row `i`, pitch `p` at the detector; the centre sample as numpy's `fftshift` puts it and as
///   `asnr psf` writes it), `+x` the field direction (the tangential curve), `+y` across it.
/// - Each slice is divided by its sum (a PSF carries its shape, not its power: the efficiency
///   `τ(λ)` and transmission `T(λ)` are given beside it, fractions of the light incident on the
///   aperture, `τ ≤ T ≤ 1`).
/// - Its centroid `c` is the order's `image_shift_m` at that wavelength (lateral colour, linear
///   in λ between the slices, the end slices' beyond), and the OTF is taken about it:
///   `OTF(ν) = Σ p(x) e^{−2πi ν·(x − c)}`. Along the two axes that is the 1-D transform of the
///   line spread function (the projection-slice theorem: the 2-D transform on the line `ν_y = 0`
///   is the 1-D transform of `Σ_y p`; tested against the direct 2-D sum), zero padded to
///   [`PSF_PADDING`]` × max(nx, ny)` points, from 0 to the stack's Nyquist frequency `1/(2p)`;
///   the table keeps the line spread functions ([`OtfTable::with_samples`]) and reads their
///   exact transform at any other frequency (not the linear interpolation between the grid's).
/// - Along any other azimuth `φ` the OTF is the 2-D transform of the slice along `φ`
///   (`Re Σ p(x) e^{−2πi ν·(x − c)}`, `ν = ν(cos φ, sin φ)`), read from the slice's transform on
///   a 2×-padded grid by Gaussian gridding ([`optics::SampledPlane`], error bound about 5e-9,
///   [`OtfTable::plane_error_bound`]), unless the stack is round
///   ([`PSF_SYMMETRY_TOLERANCE`]); the metric then averages the mean MTF over azimuth, as for
///   any 2-D OTF (docs/physics.md, "Pupils without rotational symmetry").
/// - The aliasing estimate [`PsfReport::aliasing`] is half the transform at `1/(2p)`.
/// - The table holds the real part of the re-centred OTF (the even part of the PSF about its
///   centroid); the imaginary part (an asymmetric PSF: coma) is dropped and its largest value
///   reported ([`PsfReport::imaginary`]). Where the two curves differ by at most
///   [`PSF_SYMMETRY_TOLERANCE`] both are their mean, and a centroid within
///   [`PSF_CENTRE_TOLERANCE`] samples of the centre is the centre. Negative samples within [`PSF_NEGATIVE_FLOOR`] can lift
///   `|OTF|` above 1 by at most twice their share; such values are held at ±1.
/// - Between the slices the OTF is linear in λ ([`OtfTable`]); the stack is not extrapolated: the
///   end slices' OTF holds beyond them, and the scene refuses a spectrum with weight there.
/// - The Fraunhofer check: a stack is the PSF at the detector, its blur already in it; the order
///   carries no defocus, and the check takes the blur its OTF implies
///   ([`optics::fraunhofer::table_blur_radius`]), unknown (beyond any threshold) outside the
///   stack's wavelengths, as for a tabulated OTF.
#[derive(Clone, Debug)]
pub struct PsfStack {
    f_number: f64,
    focal_length: f64,
    pitch: f64,
    table: Arc<OtfTable>,
    efficiency: Curve,
    transmission: Curve,
    design_wavelength: Option<f64>,
    report: PsfReport,
}

/// A refusal naming the slice (from 0), its wavelength and what is accepted.
fn refuse(k: usize, wavelengths_m: &[f64], what: String) -> Error {
    Error::PsfStack(format!("slice {k} ({} nm): {what}", optics::round_for_display(wavelengths_m[k] * 1e9)))
}

impl PsfStack {
    /// A PSF-stack lens of working F-number `f_number` (≥ 0.5) and focal length `focal_length_m`
    /// (> 0) whose PSFs at `wavelengths_m` (≥ 1, finite, > 0, strictly increasing) are `values`:
    /// `wavelengths_m.len()` slices of `ny × nx` samples (each side ≥ [`PSF_MIN_SIDE`], at most
    /// [`PSF_MAX_ELEMENTS`] in all), in C order `[slice][row y][column x]`, at pitch `pitch_m`
    /// (> 0) on the detector; with `efficiency` and `transmission` fractions (`τ ≤ T`).
    ///
    /// Refused (naming the slice, its wavelength, the sample and the value): a value not finite, a
    /// value below `−`[`PSF_NEGATIVE_FLOOR`]` ×` the slice's peak, a slice whose sum is not > 0.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        pitch_m: f64,
        wavelengths_m: Vec<f64>,
        [ny, nx]: [usize; 2],
        values: &[f64],
        efficiency: Curve,
        transmission: Curve,
    ) -> Result<Self, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        check("psf_pitch", pitch_m, pitch_m > 0.0, "a finite sample pitch > 0 m")?;
        check_fraction("efficiency", &efficiency)?;
        check_fraction("transmission", &transmission)?;
        let depth = wavelengths_m.len();
        if depth == 0 {
            return Err(Error::PsfStack("no slice: expected at least one wavelength".into()));
        }
        for (k, &l) in wavelengths_m.iter().enumerate() {
            if !(l.is_finite() && l > 0.0) || (k > 0 && l <= wavelengths_m[k - 1]) {
                return Err(Error::PsfStack(format!(
                    "wavelength {k} = {l} m: expected finite wavelengths > 0, strictly increasing"
                )));
            }
        }
        if ny < PSF_MIN_SIDE || nx < PSF_MIN_SIDE {
            return Err(Error::PsfStack(format!(
                "slices of {ny} × {nx} samples: expected at least {PSF_MIN_SIDE} × {PSF_MIN_SIDE}"
            )));
        }
        // the slices' 2-D transforms (`SampledPlane`: a grid of about 32 max(nx, ny)² bytes a
        // slice, kept) against the FFT path's memory budget, before any is made
        let (kept, building) = SampledPlane::bytes(ny, nx);
        let planes_bytes = depth as f64 * kept + building;
        if planes_bytes > optics::FFT_MEMORY_BUDGET {
            let gib = |b: f64| b / f64::from(1u32 << 30);
            return Err(Error::PsfStack(format!(
                "{depth} slices of {ny} × {nx}: their 2-D transforms need {:.2} GiB ({:.1} MB a slice, {:.1} MB while one is built: a grid of 2 max(nx, ny) = {} points a side) against the memory budget of {:.0} GiB; crop the slices around the PSF (a square window) or give fewer wavelengths",
                gib(planes_bytes),
                kept / 1e6,
                building / 1e6,
                2 * nx.max(ny),
                gib(optics::FFT_MEMORY_BUDGET)
            )));
        }
        let elements = depth.checked_mul(ny).and_then(|v| v.checked_mul(nx));
        if elements.is_none_or(|e| e > PSF_MAX_ELEMENTS || e != values.len()) {
            return Err(Error::PsfStack(format!(
                "{} values for {depth} slices of {ny} × {nx}: expected their product, at most {PSF_MAX_ELEMENTS}",
                values.len()
            )));
        }
        check_efficiency_below_transmission(&|l| efficiency.value(l), &[&efficiency], &transmission, wavelengths_m[0])?;

        let n = PSF_PADDING * nx.max(ny);
        let fft = FftPlanner::<f64>::new().plan_fft_forward(n);
        let mut buffer = vec![Complex64::new(0.0, 0.0); n];
        let mut scratch = vec![Complex64::new(0.0, 0.0); fft.get_inplace_scratch_len()];
        let half = n / 2;
        let frequencies: Vec<f64> = (0..=half).map(|k| k as f64 / (n as f64 * pitch_m)).collect();
        let (mut tangential, mut sagittal) = (Vec::with_capacity(depth), Vec::with_capacity(depth));
        let mut report = PsfReport {
            shape: [depth, ny, nx],
            transform_length: n,
            border_fraction: (0.0, wavelengths_m[0]),
            imaginary: (0.0, wavelengths_m[0], 0.0),
            centroids_m: Vec::with_capacity(depth),
            aliasing: (0.0, wavelengths_m[0]),
        };
        let (mut lsf_x, mut lsf_y) = (vec![0.0; nx], vec![0.0; ny]);
        let (mut lines_x, mut lines_y) = (Vec::with_capacity(depth), Vec::with_capacity(depth));
        let (mut sums, mut centroids) = (Vec::with_capacity(depth), Vec::with_capacity(depth));
        for (k, slice) in values.chunks_exact(ny * nx).enumerate() {
            let mut peak = f64::NEG_INFINITY;
            for (index, &v) in slice.iter().enumerate() {
                if !v.is_finite() {
                    return Err(refuse(
                        k,
                        &wavelengths_m,
                        format!("row {}, column {} is {v}: expected finite values", index / nx, index % nx),
                    ));
                }
                peak = peak.max(v);
            }
            let floor = -PSF_NEGATIVE_FLOOR * peak.max(0.0);
            if let Some(index) = slice.iter().position(|&v| v < floor) {
                return Err(refuse(
                    k,
                    &wavelengths_m,
                    format!(
                        "row {}, column {} is {:e}: expected values ≥ 0, or above −{PSF_NEGATIVE_FLOOR} × the slice's peak {:e} (noise)",
                        index / nx,
                        index % nx,
                        slice[index],
                        peak
                    ),
                ));
            }
            // line spread functions (unnormalized), the sum, the border's light
            lsf_x.iter_mut().for_each(|v| *v = 0.0);
            let mut border = 0.0;
            for (i, row) in slice.chunks_exact(nx).enumerate() {
                let edge_row = i < PSF_BORDER_SAMPLES || i + PSF_BORDER_SAMPLES >= ny;
                let mut row_sum = 0.0;
                for (j, &v) in row.iter().enumerate() {
                    lsf_x[j] += v;
                    row_sum += v;
                    if edge_row || j < PSF_BORDER_SAMPLES || j + PSF_BORDER_SAMPLES >= nx {
                        border += v;
                    }
                }
                lsf_y[i] = row_sum;
            }
            let sum: f64 = lsf_y.iter().sum();
            if !(sum > 0.0 && sum.is_finite()) {
                return Err(refuse(
                    k,
                    &wavelengths_m,
                    format!("its samples sum to {sum:e}: expected a sum > 0 (a PSF with light in it)"),
                ));
            }
            let negative: f64 = slice.iter().filter(|&&v| v < 0.0).map(|v| -v).sum();
            if negative > PSF_NEGATIVE_MASS * sum {
                return Err(refuse(
                    k,
                    &wavelengths_m,
                    format!(
                        "its negative samples sum to −{:.3} % of its sum: expected at most {} % (noise, not an over-subtracted background)",
                        100.0 * negative / sum,
                        100.0 * PSF_NEGATIVE_MASS
                    ),
                ));
            }
            lsf_x.iter_mut().chain(lsf_y.iter_mut()).for_each(|v| *v /= sum);
            let border = border / sum;
            if border > report.border_fraction.0 {
                report.border_fraction = (border, wavelengths_m[k]);
            }
            let centroid = |lsf: &[f64]| -> f64 {
                let c = lsf.len() / 2;
                lsf.iter().enumerate().map(|(j, v)| (j as f64 - c as f64) * v).sum::<f64>()
            };
            let snap = |c: f64| if c.abs() < PSF_CENTRE_TOLERANCE { 0.0 } else { c };
            let (cx, cy) = (snap(centroid(&lsf_x)), snap(centroid(&lsf_y)));
            report.centroids_m.push([cx * pitch_m, cy * pitch_m]);
            let mut transform = |lsf: &[f64], c: f64| -> Vec<f64> {
                buffer.iter_mut().for_each(|b| *b = Complex64::new(0.0, 0.0));
                for (b, &v) in buffer.iter_mut().zip(lsf) {
                    b.re = v;
                }
                fft.process_with_scratch(&mut buffer, &mut scratch);
                // n is even (a multiple of PSF_PADDING): buffer[n/2] is the value at 1/(2p)
                let alias = 0.5 * buffer[half].norm();
                if alias > report.aliasing.0 {
                    report.aliasing = (alias, wavelengths_m[k]);
                }
                // sample j sits at (j − ⌊n/2⌋) p; about the centroid c p the phase is
                // e^{−2πi ν (x_j − c p)} = e^{−2πi jm/N} e^{+2πi m (⌊n/2⌋ + c)/N}, ν = m/(N p)
                let origin = (lsf.len() / 2) as f64 + c;
                (0..=half)
                    .map(|m| {
                        let turn = std::f64::consts::TAU * (m as f64 * origin / n as f64).fract();
                        let value = buffer[m] * Complex64::from_polar(1.0, turn);
                        if value.im.abs() > report.imaginary.0 {
                            report.imaginary = (value.im.abs(), wavelengths_m[k], frequencies[m]);
                        }
                        value.re.clamp(-1.0, 1.0)
                    })
                    .collect()
            };
            tangential.push(transform(&lsf_x, cx));
            sagittal.push(transform(&lsf_y, cy));
            lines_x.push(SampledLine { origin: (nx / 2) as f64 + cx, values: lsf_x.clone() });
            lines_y.push(SampledLine { origin: (ny / 2) as f64 + cy, values: lsf_y.clone() });
            sums.push(sum);
            centroids.push([cx, cy]);
        }
        // the 2-D transforms, slices in parallel: as many built at once as the memory budget
        // left after the kept grids allows (checked above for one)
        let workers = ((optics::FFT_MEMORY_BUDGET - depth as f64 * kept) / building).floor().max(1.0) as usize;
        let planes = SampledPlane::stack(values, [ny, nx], &sums, &centroids, workers);
        // round: the two cuts and the transform along the azimuths between them agree
        let round = |k: usize| -> bool {
            let t = &tangential[k];
            (0..=half).step_by(PSF_SYMMETRY_STRIDE).all(|m| {
                (1..PSF_SYMMETRY_AZIMUTHS).all(|a| {
                    let phi = std::f64::consts::PI * a as f64 / PSF_SYMMETRY_AZIMUTHS as f64;
                    let turns = frequencies[m] * pitch_m;
                    let v = planes[k].transform([turns * phi.cos(), turns * phi.sin()]).clamp(-1.0, 1.0);
                    (v - t[m]).abs() <= PSF_SYMMETRY_TOLERANCE
                })
            })
        };
        let symmetric = tangential
            .iter()
            .flatten()
            .zip(sagittal.iter().flatten())
            .all(|(t, s)| (t - s).abs() <= PSF_SYMMETRY_TOLERANCE)
            && (0..depth).all(round);
        let (tangential, sagittal, lines) = if symmetric {
            let mean: Vec<Vec<f64>> = tangential
                .iter()
                .zip(&sagittal)
                .map(|(t, s)| t.iter().zip(s).map(|(a, b)| 0.5 * (a + b)).collect())
                .collect();
            // the mean of the two transforms: one line where the two are the same samples
            let both: Vec<Vec<SampledLine>> =
                lines_x.into_iter().zip(lines_y).map(|(x, y)| if x == y { vec![x] } else { vec![x, y] }).collect();
            (mean, None, (both, None))
        } else {
            let lines_x: Vec<Vec<SampledLine>> = lines_x.into_iter().map(|l| vec![l]).collect();
            let lines_y: Vec<Vec<SampledLine>> = lines_y.into_iter().map(|l| vec![l]).collect();
            (tangential, Some(sagittal), (lines_x, Some(lines_y)))
        };
        let table = OtfTable::new(wavelengths_m, frequencies, tangential, sagittal)
            .and_then(|t| t.with_samples(pitch_m, lines.0, lines.1))
            .and_then(|t| if symmetric { Ok(t) } else { t.with_planes(planes) })
            .map_err(Error::Table)?;
        Ok(PsfStack {
            f_number,
            focal_length: focal_length_m,
            pitch: pitch_m,
            table: Arc::new(table),
            efficiency,
            transmission,
            design_wavelength: None,
            report,
        })
    }

    /// This lens with a design wavelength (finite, > 0 m): the reference of the Fraunhofer check
    /// (paper SI eq. S15). Without one the lens reports none.
    pub fn with_design_wavelength(self, wavelength_m: f64) -> Result<Self, Error> {
        check("design_wavelength", wavelength_m, wavelength_m > 0.0, "a finite wavelength > 0 m")?;
        Ok(PsfStack { design_wavelength: Some(wavelength_m), ..self })
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "psf"
    }

    /// The OTF table made from the stack.
    pub fn table(&self) -> &OtfTable {
        &self.table
    }

    /// The stack's sample pitch, m.
    pub fn pitch(&self) -> f64 {
        self.pitch
    }

    /// The stack's Nyquist frequency `1/(2p)`, cycles/m: the table's last frequency.
    pub fn nyquist(&self) -> f64 {
        self.table.max_frequency()
    }

    /// The stack's wavelengths, m.
    pub fn wavelengths(&self) -> &[f64] {
        self.table.wavelengths()
    }

    /// What the stack showed (border light, asymmetry, centroids).
    pub fn report(&self) -> &PsfReport {
        &self.report
    }

    /// The image shift at `wavelength_m`: the centroids linear in λ, the end ones beyond.
    fn shift(&self, wavelength_m: f64) -> [f64; 2] {
        let (w, c) = (self.table.wavelengths(), &self.report.centroids_m);
        if wavelength_m <= w[0] {
            return c[0];
        }
        if wavelength_m >= w[w.len() - 1] {
            return c[w.len() - 1];
        }
        let i = w.partition_point(|&x| x <= wavelength_m);
        let u = (wavelength_m - w[i - 1]) / (w[i] - w[i - 1]);
        [c[i - 1][0] + u * (c[i][0] - c[i - 1][0]), c[i - 1][1] + u * (c[i][1] - c[i - 1][1])]
    }
}

impl LensModel for PsfStack {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    /// The one order: the stack's table, read from the field direction, and its centroid's
    /// shift, in the stack's frame (`+x` the field direction), turned onto the detector's axes
    /// with it (`x cos φ − y sin φ`, `x sin φ + y cos φ`, `φ = atan2(θy, θx)`, 0 on axis), so that
    /// the shift turns with the table (`turns_with_field`).
    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        let [cx, cy] = self.shift(wavelength_m);
        // the field direction as the engines read the table from it
        let direction = field.y_rad.atan2(field.x_rad);
        let [x, y] = if direction == 0.0 {
            // along +x (and on axis): the frames are one, the shift as it is
            [cx, cy]
        } else {
            let (s, c) = direction.sin_cos();
            [cx * c - cy * s, cx * s + cy * c]
        };
        vec![Order::new(
            self.efficiency.value(wavelength_m),
            Pupil::Table(Arc::clone(&self.table)),
            Wavefront::default().shifted(x, y),
        )]
    }

    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.efficiency.value(wavelength_m)
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.transmission.value(wavelength_m)
    }

    fn design_wavelength(&self) -> Option<f64> {
        self.design_wavelength
    }

    /// The PSFs are data: λ0 (`lens.design_wavelength_nm`) names the wavelength they were
    /// designed at for the Fraunhofer report's reference and enters no order, efficiency or
    /// transmission, so every quantity's derivative with respect to it is 0 (docs/physics.md,
    /// "Gradients: the design wavelength").
    fn design_wavelength_inert(&self) -> bool {
        true
    }

    /// The PSFs of one field point, in its frame: the same at every field point.
    fn turns_with_field(&self) -> bool {
        true
    }

    /// The curves' samples and the stack's wavelengths (the OTF is linear in λ between them).
    /// An efficiency or transmission table factored out (`crate::chromatic::factor_one_curve`).
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        crate::chromatic::factor_one_curve(&self.efficiency, &self.transmission, 1.0, |efficiency, transmission| {
            std::sync::Arc::new(PsfStack { efficiency, transmission, ..self.clone() })
        })
    }

    fn breakpoints(&self) -> Vec<f64> {
        crate::chromatic::curve_breakpoints(
            &self.efficiency,
            &self.transmission,
            self.table.wavelengths().iter().copied(),
        )
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        let w = self.table.wavelengths();
        let [depth, ny, nx] = self.report.shape;
        format!(
            "PSF-stack lens F/{} f0 = {} mm, {depth} slice{} of {ny} × {nx} at {} µm from {} to {} nm",
            r(self.f_number),
            r(self.focal_length * 1e3),
            if depth == 1 { "" } else { "s" },
            r(self.pitch * 1e6),
            r(w[0] * 1e9),
            r(w[w.len() - 1] * 1e9),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use optics::testkit::simpson_mean;

    const PITCH: f64 = 1e-6;

    fn lens(wavelengths: Vec<f64>, [ny, nx]: [usize; 2], values: &[f64]) -> Result<PsfStack, Error> {
        PsfStack::new(2.5, 3.36e-3, PITCH, wavelengths, [ny, nx], values, Curve::Constant(0.15), Curve::Constant(0.5))
    }

    /// A stack whose 2-D transforms would pass the memory budget is refused with the numbers
    /// before anything is made: 16 × 2²² samples (a strip) needs a grid of 2²³ points a side, about
    /// 32 · (2²²)² bytes; a 384 × 384 × 45 stack (232 MB of grids) is within it.
    #[test]
    fn planes_past_the_memory_budget_are_refused_before_allocating() {
        let e = lens(vec![800e-9], [16, 1 << 22], &[]).unwrap_err().to_string();
        assert!(e.contains("memory budget of 4 GiB") && e.contains("1 slices of 16 × 4194304"), "{e}");
        let (kept, building) = SampledPlane::bytes(384, 384);
        // the grid: (384 + 23) columns of 768 + 23 complex values, and the half spectrum of
        // 385 columns of 768 it is built through, with its real rows' buffers
        assert_eq!((kept, building), (407.0 * 791.0 * 16.0, 386.0 * 768.0 * 16.0));
        assert!(45.0 * kept + building < optics::FFT_MEMORY_BUDGET);
    }

    /// A Gaussian PSF `exp(−r²/(2σ²))` centred at `(x0, y0)` samples from the centre sample.
    fn gaussian(n: usize, sigma: f64, x0: f64, y0: f64, sx: f64) -> Vec<f64> {
        let c = (n / 2) as f64;
        (0..n * n)
            .map(|i| {
                let (y, x) = ((i / n) as f64 - c - y0, (i % n) as f64 - c - x0);
                (-(x * x / (sx * sx) + y * y) / (2.0 * sigma * sigma)).exp()
            })
            .collect()
    }

    /// The OTF of a sampled Gaussian of σ samples is `exp(−2π² σ² ν²)` (σ in m, ν in cycles/m):
    /// the Fourier transform of the continuous Gaussian; the sampled one differs by its aliases,
    /// `exp(−2π² σ²/p² ·(1 − 2|νp|)…)` ≤ e^{−2π²σ²/p²·…}: below 1e-12 for σ ≥ 2 samples at ν
    /// up to a quarter of the sampling rate, which is where the test looks. Its centroid shift
    /// becomes the image shift, and the tangential curve is along x.
    #[test]
    fn a_gaussian_psf_has_the_closed_form_otf() {
        let n = 64;
        let (sigma, x0, y0) = (2.5, 3.25, -1.5);
        let values = gaussian(n, sigma, x0, y0, 1.0);
        let lens = lens(vec![800e-9], [n, n], &values).unwrap();
        let r = lens.report();
        assert!((r.centroids_m[0][0] - x0 * PITCH).abs() < 1e-12 * PITCH, "{:?}", r.centroids_m);
        assert!((r.centroids_m[0][1] - y0 * PITCH).abs() < 1e-12 * PITCH, "{:?}", r.centroids_m);
        assert!(r.imaginary.0 < 1e-12, "a symmetric PSF about its centroid: {:?}", r.imaginary);
        assert!(r.border_fraction.0 < 1e-12, "{:?}", r.border_fraction);
        let s = sigma * PITCH;
        // between the table's frequencies too: the exact transform of the samples, not a linear
        // interpolation (which would be off by up to (Δν²/8)(4π²σ²) ≈ 1.2e-3 here)
        for nu in [0.0, 2e4, 5.5e4, 1e5, 1.25e5, 1.2345e5] {
            let want = (-2.0 * std::f64::consts::PI.powi(2) * s * s * nu * nu).exp();
            let got = lens.table().value(800e-9, nu, 0.0);
            assert!((got - want).abs() < 1e-12, "ν = {nu}: {got} vs {want}");
        }
        // at the table's own frequencies the transform is the closed form to 1e-12
        for (m, &nu) in lens.table().frequencies().iter().enumerate().take(n) {
            let want = (-2.0 * std::f64::consts::PI.powi(2) * s * s * nu * nu).exp();
            assert!((lens.table().value(800e-9, nu, 0.0) - want).abs() < 1e-12, "m = {m}");
        }
        let order = &lens.orders(800e-9, Field::ON_AXIS)[0];
        assert_eq!(order.wavefront.image_shift_m, r.centroids_m[0]);
        assert_eq!(order.efficiency, 0.15);
    }

    /// `erf` by its Maclaurin series (|x| ≤ 2: 60 terms reach 1e-16).
    fn erf(x: f64) -> f64 {
        let (mut term, mut sum) = (x, x);
        for k in 1..60 {
            term *= -x * x / k as f64;
            sum += term / (2 * k + 1) as f64;
        }
        2.0 / std::f64::consts::PI.sqrt() * sum
    }

    /// The stack of the issue: sampled Gaussians of σ(λ) = 3 µm·λ/800 nm at 1 µm, 64 × 64, 21
    /// slices over 700–900 nm.
    fn issue_stack() -> (Vec<f64>, Vec<f64>, PsfStack) {
        let n = 64;
        let wavelengths: Vec<f64> = (0..21).map(|k| 700e-9 + 10e-9 * k as f64).collect();
        let sigma = |l: f64| 3e-6 * l / 800e-9;
        let values: Vec<f64> = wavelengths.iter().flat_map(|&l| gaussian(n, sigma(l) / PITCH, 0.0, 0.0, 1.0)).collect();
        let lens = lens(wavelengths.clone(), [n, n], &values).unwrap();
        (wavelengths, values, lens)
    }

    /// The table of a stack is the exact transform of its samples at any frequency, not only
    /// on the padded grid's: against the direct 2-D sum `Σ p(x, y) cos(2πν x)/Σ p` written
    /// here (the slow reference) at frequencies between the grid's, to 1e-12 — far inside the
    /// tolerance the report states (1e-6); the linear interpolation it replaces was off by
    /// −1.3e-4 on this stack. Between slices the value is the slices' values linear in λ.
    #[test]
    fn the_table_is_the_exact_transform_of_the_samples_at_any_frequency() {
        let (wavelengths, values, lens) = issue_stack();
        let n = 64;
        assert!(lens.table().is_sampled());
        let direct = |k: usize, nu: f64| -> f64 {
            let slice = &values[k * n * n..(k + 1) * n * n];
            let (mut sum, mut acc) = (0.0, 0.0);
            for (index, &v) in slice.iter().enumerate() {
                let x = ((index % n) as f64 - (n / 2) as f64) * PITCH;
                sum += v;
                acc += v * (std::f64::consts::TAU * nu * x).cos();
            }
            acc / sum
        };
        let step = 1.0 / (PSF_PADDING as f64 * n as f64 * PITCH);
        let mut worst_linear: f64 = 0.0;
        for k in [0, 7, 20] {
            for m in [3.5, 10.25, 40.5, 77.7, 127.5] {
                let nu = m * step;
                let want = direct(k, nu);
                let got = lens.table().value(wavelengths[k], nu, 0.3);
                assert!((got - want).abs() < 1e-12, "slice {k}, ν = {nu}: {got} vs {want}");
                // what the linear interpolation between the grid's frequencies gave
                let (a, b) = (direct(k, m.floor() * step), direct(k, m.ceil() * step));
                worst_linear = worst_linear.max((a + (m - m.floor()) * (b - a) - want).abs());
            }
        }
        assert!(worst_linear > 1e-5, "the grid's linear interpolation was off: {worst_linear}");
        let (l, nu) = (743e-9, 0.3e5);
        let u = (l - wavelengths[4]) / (wavelengths[5] - wavelengths[4]);
        let want = direct(4, nu) + u * (direct(5, nu) - direct(4, nu));
        assert!((lens.table().value(l, nu, 0.0) - want).abs() < 1e-12);
        assert!(lens.table().value(l, 0.5 / PITCH + 1.0, 0.0) == 0.0, "zero beyond the stack's Nyquist");
    }

    /// The same stack against the continuous Gaussian's OTF `exp(−2π²σ²ν²)` (σ ∝ λ): at any
    /// wavelength between slices the mean MTF to the paper camera's Nyquist frequency (5.2 µm
    /// pixels) is the closed form `√π erf(a)/(2a)`, `a = √2 π σ ν_N`, within 3e-5 — the samples'
    /// own departure from the continuous Gaussian (below 1e-12 here) and the OTF's linear
    /// interpolation in λ between slices 10 nm apart (bound `(h²/8) max|∂²OTF/∂λ²|` ≈ 3.1e-5
    /// at the worst frequency, less in the mean: printed).
    #[test]
    fn a_gaussian_stack_gives_the_closed_form_mean_mtf_between_slices() {
        let (_, _, lens) = issue_stack();
        let nyquist = 0.5 / 5.2e-6;
        let mut worst: f64 = 0.0;
        for l in [700e-9, 705e-9, 733.3e-9, 800e-9, 815e-9, 868e-9, 895e-9] {
            let sigma = 3e-6 * l / 800e-9;
            let a = std::f64::consts::SQRT_2 * std::f64::consts::PI * sigma * nyquist;
            let want = std::f64::consts::PI.sqrt() * erf(a) / (2.0 * a);
            // Simpson's rule on 2000 intervals (the integrand is smooth: error ~1e-14)
            let got = simpson_mean(nyquist, |nu| lens.table().value(l, nu, 0.0).abs());
            eprintln!("{:.1} nm: mean MTF {got:.9} vs {want:.9}: {:+.2e}", l * 1e9, got - want);
            assert!((got - want).abs() < 3e-5, "{} nm: {got} vs {want}", l * 1e9);
            worst = worst.max((got - want).abs());
        }
        assert!(worst > 1e-7, "between slices the λ interpolation shows: {worst}");
        // what the table linear in ν between the padded grid's frequencies gave at 800 nm (the
        // grid's values are the exact transform: rebuilt from them)
        let grid = lens.table().frequencies().to_vec();
        let row: Vec<f64> = grid.iter().map(|&nu| lens.table().value(800e-9, nu, 0.0)).collect();
        let linear = OtfTable::new(vec![800e-9], grid, vec![row], None).unwrap();
        let linear_mean = simpson_mean(nyquist, |nu| linear.value(800e-9, nu, 0.0).abs());
        let a = std::f64::consts::SQRT_2 * std::f64::consts::PI * 3e-6 * nyquist;
        let before = linear_mean - std::f64::consts::PI.sqrt() * erf(a) / (2.0 * a);
        eprintln!("800 nm, linear in ν between the grid's frequencies: {before:+.2e}");
        assert!(before < -5e-5, "the linear interpolation's error: {before}");
    }

    /// Undersampled stacks (the issue's: σ = 3 µm sampled at 5 µm, σ = 1 µm at 2 µm): the
    /// aliasing estimate is the continuous Gaussian's OTF at the stack's Nyquist frequency,
    /// `exp(−2π²σ²/(4p²))` (0.169 and 0.287 with the samples' sum, computed here), and it bounds the OTF's error
    /// below that frequency and the mean MTF's to the paper camera's Nyquist frequency (the
    /// errors printed: +3.4e-2 and +9.1e-3 absolute, the issue's +5.2 % and +0.96 %); a stack
    /// at 1 µm of σ = 3 µm has an estimate below 1e-15.
    #[test]
    fn undersampled_stacks_report_their_aliasing() {
        let camera_nyquist = 0.5 / 5.2e-6;
        for (sigma, pitch, want) in [(3e-6, 5e-6, 0.169), (1e-6, 2e-6, 0.287)] {
            let n = 32;
            let values = gaussian(n, sigma / pitch, 0.0, 0.0, 1.0);
            let lens = PsfStack::new(
                2.5,
                3.36e-3,
                pitch,
                vec![8e-7],
                [n, n],
                &values,
                Curve::Constant(0.15),
                Curve::Constant(0.5),
            )
            .unwrap();
            let nyquist = 0.5 / pitch;
            let otf = |nu: f64| (-2.0 * std::f64::consts::PI.powi(2) * sigma * sigma * nu * nu).exp();
            let (alias, at) = lens.report().aliasing;
            assert_eq!(at, 8e-7);
            // Ô(1/(2p)) = Σ_k O((2k + 1)/(2p)) over the samples' sum Ô(0) = Σ_k O(k/p): the
            // estimate is O(1/(2p)) (1 + O(3/(2p))/O(1/(2p)) + …)/(1 + 2 O(1/p) + …)
            let folded = 2.0 * (otf(nyquist) + otf(3.0 * nyquist) + otf(5.0 * nyquist));
            let sum = 1.0 + 2.0 * (otf(2.0 * nyquist) + otf(4.0 * nyquist));
            assert!((alias - 0.5 * folded / sum).abs() < 1e-9, "{alias} vs {}", 0.5 * folded / sum);
            assert!((alias - want).abs() < 1e-3, "{alias}");
            // the OTF's error below the stack's Nyquist frequency, and the mean MTF's to the camera's
            let mut worst: f64 = 0.0;
            let error = simpson_mean(camera_nyquist, |nu| {
                let e = lens.table().value(8e-7, nu, 0.0) - otf(nu);
                worst = worst.max(e.abs());
                e
            });
            eprintln!(
                "σ = {sigma:e} m at {pitch:e} m: estimate {alias:.4}, OTF error ≤ {worst:.4}, mean MTF error {error:+.3e}"
            );
            assert!(worst <= alias && error > 0.0 && error <= alias, "{worst} {error} {alias}");
        }
        let values = gaussian(64, 3.0, 0.0, 0.0, 1.0);
        let lens = lens(vec![8e-7], [64, 64], &values).unwrap();
        assert!(lens.report().aliasing.0 < 1e-15, "{:?}", lens.report().aliasing);
    }

    /// An elliptical Gaussian (σx = 1.6 σy) has a narrower tangential curve (along x) than its
    /// sagittal one, each its own closed form, at the table's frequencies.
    #[test]
    fn tangential_is_along_x_and_sagittal_along_y() {
        let n = 64;
        let values = gaussian(n, 2.0, 0.0, 0.0, 1.6);
        let lens = lens(vec![600e-9], [n, n], &values).unwrap();
        assert!(lens.table().is_direction_dependent());
        let nu = lens.table().frequencies()[20];
        let g = |s: f64| (-2.0 * std::f64::consts::PI.powi(2) * s * s * nu * nu).exp();
        let t = lens.table().value(600e-9, nu, 0.0);
        let s = lens.table().value(600e-9, nu, std::f64::consts::FRAC_PI_2);
        assert!((t - g(3.2 * PITCH)).abs() < 1e-12, "{t} vs {}", g(3.2 * PITCH));
        assert!((s - g(2.0 * PITCH)).abs() < 1e-12, "{s} vs {}", g(2.0 * PITCH));
    }

    /// The table equals the direct 2-D sum `Σ_{x,y} p(x, y) e^{−2πi ν·(x − c)}` (the slow
    /// reference: every sample of an asymmetric, shifted PSF) on the axes and along 30° and
    /// 135°, within the planes' stated bound (below 1e-8), and the imaginary part is reported.
    #[test]
    fn projection_slice_equals_the_direct_two_dimensional_sum() {
        let (ny, nx) = (12, 16);
        let mut values: Vec<f64> =
            (0..ny * nx).map(|i| ((i * 37 % 11) as f64 + 0.5) * ((i % nx) as f64 + 1.0)).collect();
        values[5 * nx + 9] += 300.0;
        let lens = lens(vec![700e-9], [ny, nx], &values).unwrap();
        let sum: f64 = values.iter().sum();
        let [cx, cy] = lens.report().centroids_m[0];
        let n = lens.report().transform_length as f64;
        assert!(lens.table().is_two_dimensional());
        let bound = lens.table().plane_error_bound();
        assert!(bound > 0.0 && bound < 1e-8, "{bound}");
        let mut largest_imaginary: f64 = 0.0;
        for m in 0..=(n as usize / 2) {
            let nu = m as f64 / (n * PITCH);
            let direct = |phi: f64| -> Complex64 {
                let mut acc = Complex64::new(0.0, 0.0);
                for i in 0..ny {
                    for j in 0..nx {
                        let x = (j as f64 - (nx / 2) as f64) * PITCH - cx;
                        let y = (i as f64 - (ny / 2) as f64) * PITCH - cy;
                        let d = x * phi.cos() + y * phi.sin();
                        acc += Complex64::from_polar(values[i * nx + j] / sum, -std::f64::consts::TAU * nu * d);
                    }
                }
                acc
            };
            let (t, s) = (direct(0.0), direct(std::f64::consts::FRAC_PI_2));
            largest_imaginary = largest_imaginary.max(t.im.abs()).max(s.im.abs());
            for phi in [0.0, std::f64::consts::FRAC_PI_2, 30f64.to_radians(), 135f64.to_radians()] {
                let (got, want) = (lens.table().value(700e-9, nu, phi), direct(phi).re);
                assert!((got - want).abs() < bound, "m = {m}, φ = {phi}: {got} vs {want}");
            }
        }
        assert!((lens.report().imaginary.0 - largest_imaginary).abs() < 1e-12);
        assert!(largest_imaginary > 0.01, "an asymmetric PSF: {largest_imaginary}");
    }

    /// Two slices: the centroids interpolate linearly in λ as the image shift; the border's
    /// light is reported with its wavelength.
    #[test]
    fn shifts_interpolate_and_border_light_is_reported() {
        let n = 32;
        let mut values = gaussian(n, 1.5, -2.0, 0.0, 1.0);
        let mut wide = gaussian(n, 6.0, 2.0, 0.0, 1.0);
        values.append(&mut wide);
        let lens = lens(vec![700e-9, 900e-9], [n, n], &values).unwrap();
        let mid = lens.orders(800e-9, Field::ON_AXIS)[0].wavefront.image_shift_m;
        let [a, b] = [lens.report().centroids_m[0][0], lens.report().centroids_m[1][0]];
        assert!((mid[0] - 0.5 * (a + b)).abs() < 1e-18, "{mid:?}");
        assert!(a < -1.9e-6 && b > 1.5e-6, "{a} {b}");
        let (fraction, at) = lens.report().border_fraction;
        assert_eq!(at, 900e-9);
        assert!(fraction > 0.05 && fraction < 0.5, "{fraction}");
        assert_eq!(lens.breakpoints(), vec![700e-9, 900e-9]);
    }

    /// The stack's frame (`+x` the field direction) turns with the field point, its centroids'
    /// shifts with its table: the mean MTF over azimuth and the tangential and sagittal means'
    /// average are the same at every field point (`turns_with_field`; docs/physics.md,
    /// "Gradients: the field point"), for a stack that is not round and whose centroid moves
    /// with λ along both axes (lateral colour). Before the shifts were turned, the field along
    /// +y put them across the table's frame.
    #[test]
    fn the_mean_mtf_does_not_depend_on_the_field_point() {
        let n = 32;
        let mut values = gaussian(n, 1.5, -2.0, 0.5, 1.6);
        values.append(&mut gaussian(n, 2.0, 1.5, -0.5, 1.3));
        let lens = lens(vec![780e-9, 820e-9], [n, n], &values).unwrap();
        assert!(lens.turns_with_field());
        let detected = radiometry::Spectrum::TopHat(radiometry::TopHat::new(780e-9, 820e-9, 1.0).unwrap());
        let nyquist = 0.5 / 5.2e-6;
        let means = |x_deg: f64, y_deg: f64| {
            let field = Field::new(x_deg.to_radians(), y_deg.to_radians());
            let poly = optics::Polychromatic::new(&lens, &detected, field, nyquist, None).unwrap();
            let direction = field.y_rad.atan2(field.x_rad);
            let over = poly.mean_mtf_over_azimuth(direction, None).mean;
            let t = poly.mean_mtf_along(direction).0;
            let s = poly.mean_mtf_along(direction + 0.5 * std::f64::consts::PI).0;
            [over, 0.5 * (t + s)]
        };
        let along_x = means(5.0, 0.0);
        assert!(along_x[0] > 0.1 && (along_x[0] - along_x[1]).abs() > 1e-6, "{along_x:?}");
        for (x, y) in [(0.0, 5.0), (3.0, 4.0), (-5.0, 0.0), (1.0, -2.0), (0.0, 0.0)] {
            let there = means(x, y);
            for q in 0..2 {
                assert!((there[q] - along_x[q]).abs() < 1e-12, "({x}°, {y}°): {there:?} vs {along_x:?}");
            }
        }
        // the shift turned with the field direction: (0, 5°)'s is (5°, 0)'s turned by π/2
        let [a, b] = lens.orders(800e-9, Field::new(5f64.to_radians(), 0.0))[0].wavefront.image_shift_m;
        let [c, d] = lens.orders(800e-9, Field::new(0.0, 5f64.to_radians()))[0].wavefront.image_shift_m;
        assert!((c + b).abs() < 1e-20 && (d - a).abs() < 1e-20, "{:?}", [a, b, c, d]);
    }

    /// Bad stacks are refused naming the slice, the sample, the value and what is accepted.
    #[test]
    fn bad_stacks_are_refused() {
        let n = 16;
        let good = gaussian(n, 2.0, 0.0, 0.0, 1.0);
        let err = |values: &[f64], w: Vec<f64>| lens(w, [n, n], values).unwrap_err().to_string();
        let mut nan = good.clone();
        nan[3 * n + 4] = f64::NAN;
        let e = err(&nan, vec![8e-7]);
        assert!(e.contains("slice 0 (800 nm)") && e.contains("row 3, column 4 is NaN"), "{e}");
        let mut negative = good.clone();
        negative[7] = -0.02;
        let e = err(&negative, vec![8e-7]);
        assert!(e.contains("row 0, column 7") && e.contains("-2e-2") && e.contains("0.01"), "{e}");
        let mut noise = good.clone();
        noise[7] = -0.009;
        assert!(lens(vec![8e-7], [n, n], &noise).is_ok(), "noise within the floor is accepted");
        // σ = 2 samples: Σ = 8π ≈ 25.1; 40 samples at −0.009 hold 1.4 % of it
        let offset: Vec<f64> = good.iter().enumerate().map(|(i, &v)| if i < 40 { -0.009 } else { v }).collect();
        let e = err(&offset, vec![8e-7]);
        assert!(e.contains("negative samples sum to −1.") && e.contains("at most 1 %"), "{e}");
        let e = err(&[good.clone(), vec![0.0; n * n]].concat(), vec![8e-7, 9e-7]);
        assert!(e.contains("slice 1 (900 nm)") && e.contains("sum to 0e0"), "{e}");
        let e = err(&[good.clone(), good.clone()].concat(), vec![9e-7, 8e-7]);
        assert!(e.contains("strictly increasing"), "{e}");
        let e = err(&good, vec![8e-7, 9e-7]);
        assert!(e.contains("256 values for 2 slices"), "{e}");
        let e = lens(vec![8e-7], [4, 4], &good[..16]).unwrap_err().to_string();
        assert!(e.contains("at least 8 × 8"), "{e}");
    }
}
