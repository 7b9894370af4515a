//! The sampled pupil, the reusable FFT plan and the complex OTF grid with its readers.

use std::f64::consts::{PI, TAU};
use std::fmt;
use std::sync::Arc;

use num_complex::Complex64;
use rustfft::{Fft, FftPlanner};

use super::aperture::Aperture;
use super::wavefront::{Aberrations, Compiled};
use crate::{Error, quad};

/// Smallest pupil grid accepted.
pub const MIN_SAMPLES: usize = 8;
/// Largest pupil grid accepted (a 16384² complex grid is 4 GiB).
pub const MAX_SAMPLES: usize = 8192;

/// Points per axis of the tensor-product Lagrange interpolation of the OTF grid (bicubic).
pub const INTERPOLATION_POINTS: usize = 4;

/// Extra lags stored beyond `s_max N` so that the interpolation stencil stays on the grid.
pub(super) const STENCIL_MARGIN: usize = INTERPOLATION_POINTS / 2;

/// A pupil sampled on an `N × N` grid across the aperture diameter: the transmission (area
/// fraction) of each pixel and the wavefront (OPD, metres) at its centre.
///
/// Pixel `(i, j)` (row `j`, column `i`, row-major) covers `x ∈ [−1 + i h, −1 + (i+1) h]`,
/// `y ∈ [−1 + j h, −1 + (j+1) h]`, `h = 2/N`, in units of the aperture radius from the aperture
/// centre; its OPD is evaluated at the centre, offset by the aperture's decentre so that `ρ` is
/// measured from the lens axis.
#[derive(Clone, Debug)]
pub struct SampledPupil {
    n: usize,
    aperture: Aperture,
    aberrations: Aberrations,
    amplitude: Vec<f64>,
    opd_m: Vec<f64>,
    area: f64,
}

impl SampledPupil {
    /// Samples `aperture` on an `n × n` grid (`n` in `8..=8192`) and evaluates `aberrations` on it.
    pub fn new(n: usize, aperture: &Aperture, aberrations: &Aberrations) -> Result<SampledPupil, Error> {
        check_samples(n)?;
        aberrations.validate()?;
        let h = 2.0 / n as f64;
        let mut amplitude = vec![0.0; n * n];
        for j in 0..n {
            let y0 = -1.0 + j as f64 * h;
            for i in 0..n {
                let x0 = -1.0 + i as f64 * h;
                amplitude[j * n + i] = (aperture.area_in(x0, x0 + h, y0, y0 + h) / (h * h)).clamp(0.0, 1.0);
            }
        }
        let area = amplitude.iter().sum::<f64>() * h * h;
        let mut pupil = SampledPupil {
            n,
            aperture: aperture.clone(),
            aberrations: Aberrations::default(),
            amplitude,
            opd_m: vec![0.0; n * n],
            area,
        };
        pupil.fill_opd(aberrations);
        Ok(pupil)
    }

    /// Replaces the wavefront, keeping the sampled geometry (cheap: one polynomial per pixel).
    pub fn set_aberrations(&mut self, aberrations: &Aberrations) -> Result<(), Error> {
        aberrations.validate()?;
        self.fill_opd(aberrations);
        Ok(())
    }

    fn fill_opd(&mut self, aberrations: &Aberrations) {
        let n = self.n;
        let h = 2.0 / n as f64;
        let (dx, dy) = self.aperture.decentre();
        let compiled = Compiled::new(aberrations);
        for j in 0..n {
            let y = -1.0 + (j as f64 + 0.5) * h + dy;
            for i in 0..n {
                let k = j * n + i;
                self.opd_m[k] =
                    if self.amplitude[k] > 0.0 { compiled.opd_m(-1.0 + (i as f64 + 0.5) * h + dx, y) } else { 0.0 };
            }
        }
        self.aberrations = aberrations.clone();
    }

    /// Samples across the aperture diameter.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The aperture sampled.
    pub fn aperture(&self) -> &Aperture {
        &self.aperture
    }

    /// The wavefront sampled.
    pub fn aberrations(&self) -> &Aberrations {
        &self.aberrations
    }

    /// Pixel transmissions (area fractions in `[0, 1]`), row-major `N × N`.
    pub fn amplitude(&self) -> &[f64] {
        &self.amplitude
    }

    /// OPD at pixel centres (m), row-major `N × N`; 0 where the pixel is opaque.
    pub fn opd_m(&self) -> &[f64] {
        &self.opd_m
    }

    /// Transmitting area `h² Σ A` in units of `R²` (`π` for the full circle, exact for the disc
    /// shapes): the zero-frequency normalization of the OTF.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The largest OPD difference between neighbouring transmitting samples, along x or y (m):
    /// the wavefront's steepest step per sample. Below half a wavelength the sampling resolves
    /// the pupil phase (its Nyquist limit); above, the field aliases and the grid is not yet in
    /// the range where the mean MTF converges at its measured order.
    pub fn max_opd_step_m(&self) -> f64 {
        let n = self.n;
        let (a, w) = (&self.amplitude, &self.opd_m);
        let mut step: f64 = 0.0;
        for j in 0..n {
            for i in 0..n {
                let k = j * n + i;
                if a[k] <= 0.0 {
                    continue;
                }
                if i + 1 < n && a[k + 1] > 0.0 {
                    step = step.max((w[k + 1] - w[k]).abs());
                }
                if j + 1 < n && a[k + n] > 0.0 {
                    step = step.max((w[k + n] - w[k]).abs());
                }
            }
        }
        step
    }

    /// Whether the exact 1-D path applies: a centred full circle with defocus only.
    pub fn is_centred_defocus(&self) -> bool {
        self.aperture.is_centred_circle() && self.aberrations.is_defocus_only()
    }
}

pub(super) fn check_samples(n: usize) -> Result<(), Error> {
    if !(MIN_SAMPLES..=MAX_SAMPLES).contains(&n) {
        return Err(Error::InvalidParameter {
            name: "pupil samples N",
            value: n as f64,
            expected: "an integer in 8..=8192",
        });
    }
    Ok(())
}

/// Smallest length `≥ len` of the form `2^a · r`, `r ∈ {1, 3, 5, 15}`.
///
/// rustfft's radix-4/8 butterflies make powers of two the fastest lengths; one factor 3 or 5 costs
/// little, more of them a lot: measured per 2-D point, 640 = 2⁷·5 takes 5.0 ns against 11.0 ns
/// for 625 = 5⁴, and 1280 takes 5.7 ns against 12.8 ns for 1250 = 2·5⁴.
pub fn fast_fft_len(len: usize) -> usize {
    let mut m = len.max(1);
    loop {
        let odd = m >> m.trailing_zeros();
        if matches!(odd, 1 | 3 | 5 | 15) {
            return m;
        }
        m += 1;
    }
}

/// FFT plans and work buffers for the OTF of an `N × N` pupil up to `s_max`, reused across
/// evaluations (create once per grid size; clone per thread).
///
/// The padded grid is `M × M` with `M` the [`fast_fft_len`] `≥ N + K`,
/// `K = ⌈s_max N⌉ + 2` the largest lag stored (the interpolation stencil needs two beyond
/// `s_max N`): `Q = M/N ≈ 1 + s_max`, not 2–4 (module docs).
pub struct OtfPlan {
    n: usize,
    m: usize,
    half: usize,
    s_max: f64,
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    rows: Vec<Complex64>,
    work: Vec<Complex64>,
    lags: Vec<Complex64>,
    scratch: Vec<Complex64>,
    /// the pupil spectrum kept while a derivative's spectrum is in `work`
    /// ([`otf_and_edge_derivative`](Self::otf_and_edge_derivative)); empty until first used
    kept: Vec<Complex64>,
}

impl Clone for OtfPlan {
    fn clone(&self) -> OtfPlan {
        OtfPlan {
            forward: Arc::clone(&self.forward),
            inverse: Arc::clone(&self.inverse),
            rows: self.rows.clone(),
            work: self.work.clone(),
            lags: self.lags.clone(),
            scratch: self.scratch.clone(),
            kept: self.kept.clone(),
            ..*self
        }
    }
}

impl fmt::Debug for OtfPlan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("OtfPlan")
            .field("n", &self.n)
            .field("padded", &self.m)
            .field("max_lag", &self.half)
            .field("s_max", &self.s_max)
            .finish_non_exhaustive()
    }
}

impl OtfPlan {
    /// A plan for `n × n` pupils (`n` in `8..=8192`) and frequencies up to `s_max ∈ (0, 1]`
    /// (normalized to the full-aperture cutoff `2 NA/λ`), in every direction.
    pub fn new(n: usize, s_max: f64) -> Result<OtfPlan, Error> {
        check_samples(n)?;
        if !(s_max > 0.0 && s_max <= 1.0) {
            return Err(Error::InvalidParameter { name: "s_max", value: s_max, expected: "in (0, 1]" });
        }
        let half = (s_max * n as f64).ceil() as usize + STENCIL_MARGIN;
        let m = fast_fft_len(n + half);
        let mut planner = FftPlanner::new();
        let forward = planner.plan_fft_forward(m);
        let inverse = planner.plan_fft_inverse(m);
        let scratch_len = forward.get_inplace_scratch_len().max(inverse.get_inplace_scratch_len());
        let zero = Complex64::new(0.0, 0.0);
        Ok(OtfPlan {
            n,
            m,
            half,
            s_max,
            forward,
            inverse,
            rows: vec![zero; n * m],
            work: vec![zero; m * m],
            lags: vec![zero; (half + 1) * m],
            scratch: vec![zero; scratch_len],
            kept: Vec::new(),
        })
    }

    /// Pupil samples `N` this plan is for.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Padded FFT length `M` (`Q = M/N`).
    pub fn padded_len(&self) -> usize {
        self.m
    }

    /// Largest lag `K` (each axis) of the grids this plan writes: `(2K + 1)²` values each.
    pub fn max_lag(&self) -> usize {
        self.half
    }

    /// Highest normalized frequency readable from the OTFs this plan computes.
    pub fn s_max(&self) -> f64 {
        self.s_max
    }

    /// `F = DFT₂(P)` of the zero-padded pupil field `P = A exp(i 2π W/λ)`, left transposed in
    /// `work` (`work[qx M + qy]`).
    fn pupil_spectrum(&mut self, pupil: &SampledPupil, wavelength_m: f64) {
        assert_eq!(pupil.n(), self.n, "pupil sampled with N = {} for a plan with N = {}", pupil.n(), self.n);
        assert!(wavelength_m > 0.0 && wavelength_m.is_finite(), "wavelength {wavelength_m} m");
        let n = self.n;
        let k = TAU / wavelength_m;
        self.spectrum_of(|j, row| {
            let amplitude = &pupil.amplitude[j * n..(j + 1) * n];
            let opd = &pupil.opd_m[j * n..(j + 1) * n];
            super::cis::fill(row, amplitude, k, opd);
        });
    }

    /// `F = DFT₂(P)` of the zero-padded pupil field whose row `j` (`N` values) `fill(j, row)`
    /// writes, left transposed in `work` (`work[qx M + qy]`).
    fn spectrum_of(&mut self, fill: impl Fn(usize, &mut [Complex64])) {
        self.spectrum_of_rows(0..self.n, fill);
    }

    /// [`spectrum_of`](Self::spectrum_of) of a field that is zero outside the rows `rows`
    /// (`fill` is called for those only): the other rows' transforms along x are zero, exactly,
    /// and are not computed; the spectrum is the same bit for bit as with every row filled.
    fn spectrum_of_rows(&mut self, rows: std::ops::Range<usize>, fill: impl Fn(usize, &mut [Complex64])) {
        let (n, m) = (self.n, self.m);
        let zero = Complex64::new(0.0, 0.0);
        let rows = rows.start.min(n)..rows.end.min(n).max(rows.start.min(n));
        let (r_lo, r_hi) = (rows.start, rows.end);
        for j in rows.clone() {
            let row = &mut self.rows[j * m..(j + 1) * m];
            row[n..].fill(zero);
            fill(j, &mut row[..n]);
        }
        // along x: the N non-zero rows only (of them, those in `rows`)
        if r_hi > r_lo {
            self.forward.process_with_scratch(&mut self.rows[r_lo * m..r_hi * m], &mut self.scratch);
        }
        // transpose into work (the rows outside `rows`, and N..M of the padded grid, are zero)
        const B: usize = 32;
        for c0 in (0..m).step_by(B) {
            for r0 in (r_lo..r_hi).step_by(B) {
                for c in c0..(c0 + B).min(m) {
                    for r in r0..(r0 + B).min(r_hi) {
                        self.work[c * m + r] = self.rows[r * m + c];
                    }
                }
            }
        }
        for c in 0..m {
            self.work[c * m..c * m + r_lo].fill(zero);
            self.work[c * m + r_hi..(c + 1) * m].fill(zero);
        }
        // along y
        self.forward.process_with_scratch(&mut self.work, &mut self.scratch);
    }

    /// The complex OTF of `pupil` at `wavelength_m`, written into `out` (its buffer reused).
    ///
    /// `OTF(k) = Σ_m P(m) P*(m + k) / (M² · Σ A)` for lags `|kx|, |ky| ≤ K`, computed as the
    /// inverse DFT of `|DFT(P)|²` (conjugated) and normalized by the exact aperture area; the zero
    /// lag is set to exactly 1 (module docs). Cost: `N + M + ⌈M/2⌉ + K + 1` FFTs of length `M`.
    ///
    /// # Panics
    /// If `pupil.n()` differs from the plan's `N` or the wavelength is not positive and finite.
    pub fn otf(&mut self, pupil: &SampledPupil, wavelength_m: f64, out: &mut Otf) {
        self.pupil_spectrum(pupil, wavelength_m);
        self.autocorrelation(pupil.amplitude.iter().sum::<f64>(), out);
    }

    /// The complex OTF of a pupil given as its complex field, `N × N` row-major (`field[j N + i]`,
    /// pixel `(i, j)` as in [`SampledPupil`]): a composite pupil of coherent zones
    /// ([`SampledZones`](super::SampledZones)) or any other field. `weight` is the normalization
    /// `Σ_k Σ_j A_jk a_j²` in pixel units (pixel area fractions `A_jk` of zone `j` times its
    /// power transmission `a_j²`): for one zone of amplitude 1 it is the `Σ A` of
    /// [`otf`](Self::otf), and both give the same grid for the same pupil. The zero lag is set to
    /// exactly 1; a field of zero weight gives the OTF 1 at zero and 0 elsewhere.
    ///
    /// # Panics
    /// If `field.len()` is not `N²`.
    pub fn otf_of_field(&mut self, field: &[Complex64], weight: f64, out: &mut Otf) {
        let n = self.n;
        assert_eq!(field.len(), n * n, "a field of {} values for a plan with N = {n}", field.len());
        self.spectrum_of(|j, row| row.copy_from_slice(&field[j * n..(j + 1) * n]));
        self.autocorrelation(weight, out);
    }

    /// The OTF of the field `field` ([`otf_of_field`](Self::otf_of_field)) and, into
    /// `derivatives`, its derivative along each wavefront direction of `directions` (the OPD per
    /// unit of a key at each pixel, m, `N²` row-major as `field`), at the wavenumber `k = 2π/λ`
    /// (docs/physics.md, "Gradients: 2-D pupils"): the field moves as `∂P = i k D P`, so the
    /// unnormalized PSF `|F|²` (`F = DFT₂(P)`) moves as `2 Re(F* DFT₂(∂P))`, and the OTF, its
    /// inverse DFT over the same `M² · weight` (the weight `Σ A a²` does not depend on the
    /// phase), as that inverse; the zero lag's derivative is exactly 0 (the value is exactly 1).
    /// One more forward and inverse transform per direction; the grids are those
    /// [`otf_of_field`](Self::otf_of_field) writes, so they are read with the same interpolation.
    ///
    /// # Panics
    /// If `field.len()` or a direction's length is not `N²`, or `derivatives` is shorter than
    /// `directions`.
    pub fn otf_and_derivatives_of_field(
        &mut self,
        field: &[Complex64],
        weight: f64,
        k: f64,
        directions: &[&[f64]],
        out: &mut Otf,
        derivatives: &mut [Otf],
    ) {
        let n = self.n;
        assert_eq!(field.len(), n * n, "a field of {} values for a plan with N = {n}", field.len());
        assert!(
            derivatives.len() >= directions.len(),
            "{} grids for {} directions",
            derivatives.len(),
            directions.len()
        );
        self.spectrum_of(|j, row| row.copy_from_slice(&field[j * n..(j + 1) * n]));
        let spectrum = self.work.clone();
        self.autocorrelation(weight, out);
        for (d, grid) in directions.iter().zip(derivatives.iter_mut()) {
            assert_eq!(d.len(), n * n, "a direction of {} values for a plan with N = {n}", d.len());
            // ∂P = i k D P
            self.spectrum_of(|j, row| {
                for (i, r) in row.iter_mut().enumerate() {
                    let idx = j * n + i;
                    *r = field[idx] * Complex64::new(0.0, k * d[idx]);
                }
            });
            self.autocorrelation_of(weight, grid, Some(&spectrum));
            grid.grid[self.half * (2 * self.half + 1) + self.half] = Complex64::new(0.0, 0.0);
        }
    }

    /// The OTF of the field `field` ([`otf_of_field`](Self::otf_of_field)) and, into
    /// `derivatives`, its derivative where a key moves the field itself and its weight: each of
    /// `moves` is `(∂P, ∂weight)`, the field's derivative (`N²` row-major as `field`) and the
    /// weight's (the edge's motion on the FFT path: docs/physics.md, "Gradients: the edge's
    /// motion on the FFT path"). The unnormalized PSF moves as `2 Re(F* DFT₂(∂P))`, so its
    /// inverse DFT is `P ⋆ ∂P + ∂P ⋆ P`; over the same `M² · weight` it is the derivative at
    /// fixed weight, and the weight's motion adds `−OTF · ∂weight/weight`. The zero lag's
    /// derivative is exactly 0 (the value is exactly 1). One more forward and inverse transform
    /// per move; the grids are those [`otf_of_field`](Self::otf_of_field) writes.
    ///
    /// # Panics
    /// If `field.len()` or a move's length is not `N²`, or `derivatives` is shorter than `moves`.
    pub fn otf_and_field_derivatives(
        &mut self,
        field: &[Complex64],
        weight: f64,
        moves: &[(&[Complex64], f64)],
        out: &mut Otf,
        derivatives: &mut [Otf],
    ) {
        let n = self.n;
        assert_eq!(field.len(), n * n, "a field of {} values for a plan with N = {n}", field.len());
        assert!(derivatives.len() >= moves.len(), "{} grids for {} moves", derivatives.len(), moves.len());
        self.spectrum_of(|j, row| row.copy_from_slice(&field[j * n..(j + 1) * n]));
        let spectrum = self.work.clone();
        self.autocorrelation(weight, out);
        let zero = self.half * (2 * self.half + 1) + self.half;
        for (&(d_field, d_weight), grid) in moves.iter().zip(derivatives.iter_mut()) {
            assert_eq!(
                d_field.len(),
                n * n,
                "a field's derivative of {} values for a plan with N = {n}",
                d_field.len()
            );
            self.spectrum_of(|j, row| row.copy_from_slice(&d_field[j * n..(j + 1) * n]));
            self.autocorrelation_of(weight, grid, Some(&spectrum));
            let rate = if weight > 0.0 { d_weight / weight } else { 0.0 };
            for (g, o) in grid.grid.iter_mut().zip(&out.grid) {
                *g -= o * rate;
            }
            grid.grid[zero] = Complex64::new(0.0, 0.0);
        }
    }

    /// The OTF of `pupil` at `wavelength_m` ([`otf`](Self::otf), the same grid bit for bit) and,
    /// into `derivative`, its derivative where the pupil's inner edge moves (the obscuration ε:
    /// docs/physics.md, "Gradients: the edge's motion on the FFT path"): `d_field` is the field's
    /// derivative `∂P` on the rows `rows` (`rows.len() · N` values, row-major from row
    /// `rows.start`; zero on the other rows) and `d_weight` the
    /// normalization's `∂(Σ A)`. As [`otf_and_field_derivatives`](Self::otf_and_field_derivatives),
    /// `∂OTF = IDFT₂(2 Re(F* DFT₂ ∂P))/(M² Σ A) − OTF · ∂(Σ A)/Σ A`, the zero lag's 0, with `F`
    /// the value's own pupil spectrum kept between the two transforms: one more forward
    /// transform (along x only the rows of `rows`) and one more inverse transform than the value.
    ///
    /// # Panics
    /// As [`otf`](Self::otf), or if `rows` is not within `0..N` or `d_field.len()` is not
    /// `rows.len() · N`.
    #[allow(clippy::too_many_arguments)]
    pub fn otf_and_edge_derivative(
        &mut self,
        pupil: &SampledPupil,
        wavelength_m: f64,
        d_field: &[Complex64],
        rows: std::ops::Range<usize>,
        d_weight: f64,
        out: &mut Otf,
        derivative: &mut Otf,
    ) {
        let n = self.n;
        assert!(rows.start <= rows.end && rows.end <= n, "rows {rows:?} for a plan with N = {n}");
        assert_eq!(
            d_field.len(),
            rows.len() * n,
            "a field's derivative of {} values for {} rows of N = {n}",
            d_field.len(),
            rows.len()
        );
        self.pupil_spectrum(pupil, wavelength_m);
        let weight = pupil.amplitude.iter().sum::<f64>();
        let mut kept = std::mem::take(&mut self.kept);
        kept.clone_from(&self.work);
        self.autocorrelation(weight, out);
        let first = rows.start;
        self.spectrum_of_rows(rows, |j, row| row.copy_from_slice(&d_field[(j - first) * n..(j - first + 1) * n]));
        self.autocorrelation_of(weight, derivative, Some(&kept));
        self.kept = kept;
        let rate = if weight > 0.0 { d_weight / weight } else { 0.0 };
        for (g, o) in derivative.grid.iter_mut().zip(&out.grid) {
            *g -= o * rate;
        }
        derivative.grid[self.half * (2 * self.half + 1) + self.half] = Complex64::new(0.0, 0.0);
    }

    /// The OTF grid from the pupil spectrum in `work`: `conj IDFT₂(|F|²) / (M² weight)` at the
    /// stored lags, the zero lag set to 1.
    ///
    /// `|F|²` is real, so its inverse `R` is Hermitian, `R(−k) = R(k)*`: only the lags
    /// `ky ∈ [0, K]` are transformed, the others are conjugates. Along `qy` two real rows
    /// `a, b` (`qx = 2j, 2j + 1`) go through one complex FFT as `z = a + i b`, and are separated
    /// with `A(ky) = (Z(ky) + Z(−ky)*)/2`, `B(ky) = (Z(ky) − Z(−ky)*)/(2i)`: `⌈M/2⌉ + K + 1`
    /// inverse FFTs instead of `M + 2K + 1`.
    fn autocorrelation(&mut self, weight: f64, out: &mut Otf) {
        self.autocorrelation_of(weight, out, None);
        out.grid[self.half * (2 * self.half + 1) + self.half] = Complex64::new(1.0, 0.0);
    }

    /// [`autocorrelation`](Self::autocorrelation) of the real spectrum `|F|²` (`value = None`),
    /// or, with `value = Some(F)`, of `2 Re(F* G)` with `G` the spectrum in `work` (the PSF's
    /// derivative along a direction whose field's spectrum is `G`); the zero lag as computed.
    fn autocorrelation_of(&mut self, weight: f64, out: &mut Otf, value: Option<&[Complex64]>) {
        let (m, half) = (self.m, self.half);
        // pack the real rows |F|² of qx = 2j, 2j + 1 into row j, in place (row j ≤ 2j is read
        // before it is written)
        let packed = m.div_ceil(2);
        for j in 0..packed {
            let (a, b) = (2 * j * m, (2 * j + 1) * m);
            for qy in 0..m {
                let power = |i: usize| match value {
                    None => self.work[i].norm_sqr(),
                    Some(f) => 2.0 * (f[i].conj() * self.work[i]).re,
                };
                let re = power(a + qy);
                let im = if 2 * j + 1 < m { power(b + qy) } else { 0.0 };
                self.work[j * m + qy] = Complex64::new(re, im);
            }
        }
        // inverse along qy → ky, then separate the pairs into the rows ky ∈ [0, K] of `lags`
        self.inverse.process_with_scratch(&mut self.work[..packed * m], &mut self.scratch);
        let (half_re, minus_half_i) = (Complex64::new(0.5, 0.0), Complex64::new(0.0, -0.5));
        for j in 0..packed {
            let z = &self.work[j * m..(j + 1) * m];
            for ky in 0..=half {
                let (zk, zm) = (z[ky % m], z[(m - ky % m) % m].conj());
                self.lags[ky * m + 2 * j] = (zk + zm) * half_re;
                if 2 * j + 1 < m {
                    self.lags[ky * m + 2 * j + 1] = (zk - zm) * minus_half_i;
                }
            }
        }
        // inverse along qx → kx
        self.inverse.process_with_scratch(&mut self.lags[..(half + 1) * m], &mut self.scratch);
        let scale = if weight > 0.0 { 1.0 / ((m * m) as f64 * weight) } else { 0.0 };
        let side = 2 * half + 1;
        out.n = self.n;
        out.half = half;
        out.s_max = self.s_max;
        out.grid.clear();
        out.grid.resize(side * side, Complex64::new(0.0, 0.0));
        let h = half as i64;
        for ky in 0..=h {
            let row = &self.lags[ky as usize * m..(ky as usize + 1) * m];
            for kx in -h..=h {
                // R(k) = Σ P(m + k) P*(m); the OTF is its conjugate (module docs)
                let v = row[kx.rem_euclid(m as i64) as usize].conj() * scale;
                out.grid[((ky + h) * side as i64 + kx + h) as usize] = v;
                // OTF(−k) = OTF(k)*
                out.grid[((h - ky) * side as i64 + h - kx) as usize] = v.conj();
            }
        }
    }

    /// The PSF `|DFT₂(P)|²` of the padded pupil, `M × M` row-major (`out[qy M + qx]`), in DFT
    /// order (index 0 is the chief ray; indices past `M/2` are negative positions). Sample pitch
    /// `λ F# N/M` in the image, with `F#` the working F-number of the full aperture of diameter `2R`.
    /// Unnormalized: `Σ PSF = M² Σ |P|²` (Parseval).
    ///
    /// # Panics
    /// As [`otf`](Self::otf).
    pub fn psf(&mut self, pupil: &SampledPupil, wavelength_m: f64, out: &mut Vec<f64>) {
        self.pupil_spectrum(pupil, wavelength_m);
        let m = self.m;
        out.clear();
        out.resize(m * m, 0.0);
        for qx in 0..m {
            for qy in 0..m {
                out[qy * m + qx] = self.work[qx * m + qy].norm_sqr();
            }
        }
    }
}

/// A complex OTF sampled at lags `kx, ky ∈ [−K, K]`, i.e. at `s = (kx, ky)/N`, with readers that
/// interpolate between samples.
///
/// Interpolation: tensor-product 4-point Lagrange (bicubic) in `(kx, ky)`, exact at the samples,
/// continuous, error `O(h⁴ ∂⁴OTF)` with `h = 1/N` where the OTF is smooth (module docs for the
/// measured size); the OTF of any aperture has a cone `1 − c|s|` at `s = 0`, where the error is
/// `O(h)` within two samples of the origin.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Otf {
    n: usize,
    half: usize,
    s_max: f64,
    grid: Vec<Complex64>,
}

impl Otf {
    /// An empty OTF, to be filled by [`OtfPlan::otf`].
    pub fn new() -> Otf {
        Otf::default()
    }

    /// Samples a given function `f(sx, sy)` on the grid of an `n`-sample pupil up to `s_max`:
    /// lets the readers be tested against a known OTF, and the exact path be read like the FFT one.
    ///
    /// # Panics
    /// If `n` is 0 or `s_max` is not in `(0, 1]`.
    pub fn tabulate(n: usize, s_max: f64, f: impl Fn(f64, f64) -> Complex64) -> Otf {
        assert!(n > 0 && s_max > 0.0 && s_max <= 1.0, "tabulate: n = {n}, s_max = {s_max}");
        let half = (s_max * n as f64).ceil() as usize + STENCIL_MARGIN;
        let mut grid = Vec::with_capacity((2 * half + 1) * (2 * half + 1));
        let h = 1.0 / n as f64;
        for ky in -(half as i64)..=half as i64 {
            for kx in -(half as i64)..=half as i64 {
                grid.push(f(kx as f64 * h, ky as f64 * h));
            }
        }
        Otf { n, half, s_max, grid }
    }

    /// Adds `rate` times `other` (a grid of the same plan) at every lag: a derivative grid
    /// gaining the OTF times a rate (an order's efficiency moving with a key, docs/physics.md,
    /// "Gradients: a library's parameter bias").
    ///
    /// # Panics
    /// If the two grids' sizes differ.
    pub(crate) fn add_scaled(&mut self, other: &Otf, rate: f64) {
        assert_eq!(self.grid.len(), other.grid.len(), "grids of {} and {} lags", self.grid.len(), other.grid.len());
        for (g, o) in self.grid.iter_mut().zip(&other.grid) {
            *g += o * rate;
        }
    }

    /// Pupil samples `N`: lag `k` is `s = k/N`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Largest stored lag `K` (each axis).
    pub fn max_lag(&self) -> usize {
        self.half
    }

    /// Highest normalized frequency the readers accept, in any direction.
    pub fn s_max(&self) -> f64 {
        self.s_max
    }

    /// The sample at lag `(kx, ky)`, `|kx|, |ky| ≤ K`: `OTF(kx/N, ky/N)`.
    ///
    /// # Panics
    /// If a lag is beyond `K`.
    pub fn sample(&self, kx: i64, ky: i64) -> Complex64 {
        let h = self.half as i64;
        assert!(kx.abs() <= h && ky.abs() <= h, "lag ({kx}, {ky}) beyond the stored ±{h}");
        self.grid[((ky + h) * (2 * h + 1) + kx + h) as usize]
    }

    /// The OTF at `(sx, sy)` (normalized frequency components), interpolated.
    ///
    /// # Panics
    /// If `|sx|` or `|sy|` exceeds `s_max` by more than `1e-9`.
    pub fn at_xy(&self, sx: f64, sy: f64) -> Complex64 {
        let lim = self.s_max + 1e-9;
        assert!(sx.abs() <= lim && sy.abs() <= lim, "({sx}, {sy}) beyond s_max = {}", self.s_max);
        let n = self.n as f64;
        let (u, v) = (sx * n, sy * n);
        let (i0, j0) = (u.floor(), v.floor());
        let (wx, wy) = (lagrange_weights(u - i0), lagrange_weights(v - j0));
        self.stencil(i0 as i64, &wx, j0 as i64, &wy)
    }

    /// `Σ grid · wx · wy` over the interpolation stencils whose cells start at `(i, j)` (grid
    /// indices from the centre): the reading [`at_xy`](Self::at_xy) takes, and with the
    /// derivative's weights in one direction, [`at_xy_and_slope`](Self::at_xy_and_slope)'s.
    fn stencil(&self, i: i64, wx: &[f64; INTERPOLATION_POINTS], j: i64, wy: &[f64; INTERPOLATION_POINTS]) -> Complex64 {
        let lo = 1 - (INTERPOLATION_POINTS as i64) / 2;
        let side = 2 * self.half + 1;
        let h = self.half as i64;
        let mut sum = Complex64::new(0.0, 0.0);
        for (b, &wyb) in wy.iter().enumerate() {
            if wyb == 0.0 {
                continue;
            }
            let row = ((j + lo + b as i64 + h) as usize) * side;
            let mut acc = Complex64::new(0.0, 0.0);
            for (a, &wxa) in wx.iter().enumerate() {
                acc += self.grid[row + (i + lo + a as i64 + h) as usize] * wxa;
            }
            sum += acc * wyb;
        }
        sum
    }

    /// The interpolated OTF at `(sx, sy)` as [`at_xy`](Self::at_xy), and its derivative along
    /// `(dx, dy)` (`d/dε` of the value at `(sx + ε dx, sy + ε dy)`): the same Lagrange stencil
    /// with the derivative's weights in each direction. The interpolant kinks at the cell
    /// edges; on an edge (a reading along an axis, `sy = 0`, lies on one all the way) the slope
    /// across it is the mean of the two cells' (the symmetric derivative, which central
    /// differences of the reading give).
    ///
    /// # Panics
    /// As [`at_xy`](Self::at_xy).
    pub fn at_xy_and_slope(&self, sx: f64, sy: f64, dx: f64, dy: f64) -> (Complex64, Complex64) {
        let lim = self.s_max + 1e-9;
        assert!(sx.abs() <= lim && sy.abs() <= lim, "({sx}, {sy}) beyond s_max = {}", self.s_max);
        let n = self.n as f64;
        let (u, v) = (sx * n, sy * n);
        let (i0, j0) = (u.floor() as i64, v.floor() as i64);
        let (tx, ty) = (u - i0 as f64, v - j0 as f64);
        let stencil = |i, wx: &_, j, wy: &_| self.stencil(i, wx, j, wy);
        let (wx, wy) = (lagrange_weights(tx), lagrange_weights(ty));
        let value = stencil(i0, &wx, j0, &wy);
        // the cell edge a coordinate lies on, to rounding (a reading along an axis turned by
        // π/2 has cos = 6e-17, not 0)
        let edge = |u: f64| {
            let e = u.round();
            ((u - e).abs() <= EDGE_SNAP).then_some(e as i64)
        };
        let mut slope = Complex64::new(0.0, 0.0);
        if dx != 0.0 {
            let across = match edge(u) {
                Some(e) => {
                    0.5 * (stencil(e, &lagrange_slopes(0.0), j0, &wy) + stencil(e - 1, &lagrange_slopes(1.0), j0, &wy))
                }
                None => stencil(i0, &lagrange_slopes(tx), j0, &wy),
            };
            slope += across * (dx * n);
        }
        if dy != 0.0 {
            let across = match edge(v) {
                Some(e) => {
                    0.5 * (stencil(i0, &wx, e, &lagrange_slopes(0.0)) + stencil(i0, &wx, e - 1, &lagrange_slopes(1.0)))
                }
                None => stencil(i0, &wx, j0, &lagrange_slopes(ty)),
            };
            slope += across * (dy * n);
        }
        (value, slope)
    }

    /// The OTF at normalized frequency `s ≥ 0` along `azimuth_rad` (counter-clockwise from `+x`).
    ///
    /// # Panics
    /// If `s` exceeds the OTF's [`s_max`](Self::s_max).
    pub fn at(&self, s: f64, azimuth_rad: f64) -> Complex64 {
        let (sin, cos) = azimuth_rad.sin_cos();
        self.at_xy(s * cos, s * sin)
    }

    /// The slice along `azimuth_rad` at the frequencies `s`.
    pub fn slice(&self, azimuth_rad: f64, s: &[f64]) -> Vec<Complex64> {
        s.iter().map(|&si| self.at(si, azimuth_rad)).collect()
    }

    /// The mean MTF `(1/s_max) ∫_0^{s_max} |OTF(s, azimuth)| ds` along a slice.
    ///
    /// The interpolant is a polynomial between the points where the slice crosses grid lines; each
    /// such piece is integrated with the 16-point Gauss–Legendre rule of [`crate::quad`].
    ///
    /// # Panics
    /// If `s_max` exceeds the OTF's [`s_max`](Self::s_max) (as [`at_xy`](Self::at_xy)).
    pub fn mean_mtf(&self, azimuth_rad: f64, s_max: f64) -> f64 {
        if s_max <= 0.0 {
            return 1.0;
        }
        let (sin, cos) = azimuth_rad.sin_cos();
        let n = self.n as f64;
        let mut cuts = vec![0.0, s_max];
        for c in [cos.abs(), sin.abs()] {
            if c > 1e-12 {
                let last = (s_max * n * c).floor() as usize;
                cuts.extend((1..=last).map(|k| k as f64 / (n * c)).filter(|&s| s < s_max));
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-14);
        let rule = quad::rule();
        let mut total = 0.0;
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            let mut sum = 0.0;
            for &(x, wt) in rule {
                let s = mid + half * x;
                sum += wt * self.at_xy(s * cos, s * sin).norm();
            }
            total += half * sum;
        }
        total / s_max
    }

    /// Azimuthal average of the MTF at `s`: `(1/π) ∫_0^π |OTF(s, φ)| dφ` (`|OTF|` is π-periodic
    /// since `OTF(−s) = OTF(s)*`), by the trapezoid rule on `max(64, 4 π s N)` azimuths.
    ///
    /// # Panics
    /// If `s` exceeds the OTF's [`s_max`](Self::s_max).
    pub fn azimuthal_mean_mtf(&self, s: f64) -> f64 {
        self.azimuthal_mean(s, |z| z.norm())
    }

    /// Azimuthal average of the complex OTF at `s` over the full circle, which is real:
    /// `(1/π) ∫_0^π Re OTF(s, φ) dφ` (same rule as [`azimuthal_mean_mtf`](Self::azimuthal_mean_mtf)).
    pub fn azimuthal_mean_otf(&self, s: f64) -> f64 {
        self.azimuthal_mean(s, |z| z.re)
    }

    fn azimuthal_mean(&self, s: f64, f: impl Fn(Complex64) -> f64) -> f64 {
        let count = ((4.0 * PI * s * self.n as f64).ceil() as usize).max(64);
        let sum: f64 = (0..count).map(|k| f(self.at(s, PI * k as f64 / count as f64))).sum();
        sum / count as f64
    }
}

/// Lagrange weights of the nodes `1 − P/2, …, P/2` at `t ∈ [0, 1)`.
fn lagrange_weights(t: f64) -> [f64; INTERPOLATION_POINTS] {
    let lo = 1.0 - (INTERPOLATION_POINTS / 2) as f64;
    let mut w = [0.0; INTERPOLATION_POINTS];
    for (j, wj) in w.iter_mut().enumerate() {
        let xj = lo + j as f64;
        let mut p = 1.0;
        for l in 0..INTERPOLATION_POINTS {
            if l != j {
                let xl = lo + l as f64;
                p *= (t - xl) / (xj - xl);
            }
        }
        *wj = p;
    }
    w
}

/// How near a cell edge (in cells) [`Otf::at_xy_and_slope`] takes a point to lie on it.
const EDGE_SNAP: f64 = 1e-9;

/// The derivatives in `t` of [`lagrange_weights`] (each weight's product rule).
fn lagrange_slopes(t: f64) -> [f64; INTERPOLATION_POINTS] {
    let lo = 1.0 - (INTERPOLATION_POINTS / 2) as f64;
    let mut w = [0.0; INTERPOLATION_POINTS];
    for (j, wj) in w.iter_mut().enumerate() {
        let xj = lo + j as f64;
        for m in 0..INTERPOLATION_POINTS {
            if m == j {
                continue;
            }
            let mut p = 1.0 / (xj - (lo + m as f64));
            for l in 0..INTERPOLATION_POINTS {
                if l != j && l != m {
                    let xl = lo + l as f64;
                    p *= (t - xl) / (xj - xl);
                }
            }
            *wj += p;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The interpolant's slope against central differences of [`OtfPlan`]'s `at_xy` inside a
    /// cell (step 1e-7 of a cell: the interpolant is a bicubic there, truncation ~1e-14), on
    /// the grid of an aberrated field, in a few directions.
    #[test]
    fn interpolant_slope_matches_differences() {
        let n = 16;
        let h = 2.0 / n as f64;
        let mut field = vec![Complex64::new(0.0, 0.0); n * n];
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
                if x * x + y * y <= 1.0 {
                    field[j * n + i] = Complex64::from_polar(1.0, 2.0 * (x * x * x + 0.5 * x * y + y * y));
                }
            }
        }
        let weight: f64 = field.iter().map(|z| z.norm_sqr()).sum();
        let mut plan = OtfPlan::new(n, 1.0).unwrap();
        let mut otf = Otf::new();
        plan.otf_of_field(&field, weight, &mut otf);
        for (sx, sy, dx, dy) in [(0.13, 0.21, 1.0, 0.0), (0.4, -0.27, 0.0, 1.0), (-0.33, 0.52, -0.6, 0.8)] {
            let (value, slope) = otf.at_xy_and_slope(sx, sy, dx, dy);
            assert_eq!(value, otf.at_xy(sx, sy));
            let e = 1e-7 / n as f64;
            let d = (otf.at_xy(sx + e * dx, sy + e * dy) - otf.at_xy(sx - e * dx, sy - e * dy)) / (2.0 * e);
            assert!((slope - d).norm() <= 1e-6 * slope.norm().max(1e-3), "({sx}, {sy}): {slope} vs {d}");
        }
    }

    /// The OTF grids' derivative where the field's amplitudes and weight move (an annulus's
    /// inner edge: each pixel's area fraction `A(ε)` exact, `∂A/∂ε` its arc length) against
    /// central differences of the grids of the annulus sampled at ε ± 1e-6 (truncation ~1e-12;
    /// the amplitudes are piecewise smooth in ε, and no pixel's corner lies within the step of
    /// the circle): 32 samples, ε = 0.3, a defocus and coma-like phase, the normalization Σ A.
    #[test]
    fn otf_field_derivatives_match_differences_of_the_grids() {
        let n = 32;
        let h = 2.0 / n as f64;
        let phase = |x: f64, y: f64| {
            let r2 = x * x + y * y;
            2.0 * r2 * x + 1.5 * r2
        };
        let sampled = |eps: f64| {
            let ap = super::super::Aperture::annulus(eps).unwrap();
            let (mut field, mut rate, mut weight, mut d_weight) =
                (vec![Complex64::new(0.0, 0.0); n * n], vec![Complex64::new(0.0, 0.0); n * n], 0.0, 0.0);
            for j in 0..n {
                for i in 0..n {
                    let (x0, y0) = (-1.0 + i as f64 * h, -1.0 + j as f64 * h);
                    let a = ap.area_in(x0, x0 + h, y0, y0 + h) / (h * h);
                    let da = ap.obscuration_rate_in(x0, x0 + h, y0, y0 + h).unwrap() / (h * h);
                    let unit = Complex64::from_polar(1.0, phase(x0 + 0.5 * h, y0 + 0.5 * h));
                    field[j * n + i] = unit * a;
                    rate[j * n + i] = unit * da;
                    weight += a;
                    d_weight += da;
                }
            }
            (field, rate, weight, d_weight)
        };
        let (field, rate, weight, d_weight) = sampled(0.3);
        let mut plan = OtfPlan::new(n, 0.9).unwrap();
        let (mut otf, mut d) = (Otf::new(), vec![Otf::new()]);
        plan.otf_and_field_derivatives(&field, weight, &[(&rate, d_weight)], &mut otf, &mut d);
        let grid = |eps: f64| {
            let (f, _, w, _) = sampled(eps);
            let mut out = Otf::new();
            plan.clone().otf_of_field(&f, w, &mut out);
            out
        };
        let (up, down, plain) = (grid(0.3 + 1e-6), grid(0.3 - 1e-6), grid(0.3));
        let half = otf.max_lag() as i64;
        let mut largest: f64 = 0.0;
        for ky in -half..=half {
            for kx in -half..=half {
                assert_eq!(otf.sample(kx, ky), plain.sample(kx, ky));
                let differences = (up.sample(kx, ky) - down.sample(kx, ky)) / 2e-6;
                largest = largest.max(differences.norm());
                assert!((d[0].sample(kx, ky) - differences).norm() <= 1e-7, "({kx}, {ky})");
            }
        }
        assert!(largest > 0.1, "{largest}");
        assert_eq!(d[0].sample(0, 0), Complex64::new(0.0, 0.0));
    }

    /// The grid's derivative in the obscuration from the value's own pupil spectrum
    /// ([`OtfPlan::otf_and_edge_derivative`]) against central differences of the grids of the
    /// sampled annulus at ε ± 1e-6 ([`OtfPlan::otf`] of [`SampledPupil::new`], the value's own
    /// path; truncation ~1e-12): 32 samples, ε = 0.3 and a sector of a ring at ε = 0.45, with
    /// defocus and coma. The field's derivative is written here on every pixel (each pixel's arc
    /// rate from [`Aperture::obscuration_rate_in`], the whole grid), and given again on the rows
    /// the circle crosses only: the same grids bit for bit. The value's grid is `otf`'s bit for
    /// bit.
    #[test]
    fn edge_derivative_matches_differences_of_the_value_grids() {
        let n = 32;
        let h = 2.0 / n as f64;
        let lambda = 1e-6;
        let aberrations = Aberrations { w020_m: 0.4e-6, w131_m: 0.3e-6, field: 1.0, ..Aberrations::default() };
        let shapes: [(f64, Option<(f64, f64)>); 2] = [(0.3, None), (0.45, Some((0.3, 2.6)))];
        for (eps, sector) in shapes {
            let aperture = |e: f64| Aperture::disc(e, sector).unwrap();
            let pupil = SampledPupil::new(n, &aperture(eps), &aberrations).unwrap();
            let k = TAU / lambda;
            let (mut moved, mut d_weight) = (vec![Complex64::new(0.0, 0.0); n * n], 0.0);
            for j in 0..n {
                for i in 0..n {
                    let (x0, y0) = (-1.0 + i as f64 * h, -1.0 + j as f64 * h);
                    let rate = aperture(eps).obscuration_rate_in(x0, x0 + h, y0, y0 + h).unwrap() / (h * h);
                    d_weight += rate;
                    moved[j * n + i] = Complex64::from_polar(rate, k * pupil.opd_m()[j * n + i]);
                }
            }
            let mut plan = OtfPlan::new(n, 0.9).unwrap();
            let (mut otf, mut d) = (Otf::new(), Otf::new());
            plan.otf_and_edge_derivative(&pupil, lambda, &moved, 0..n, d_weight, &mut otf, &mut d);
            // the rows the circle crosses
            let rows = (0..n).filter(|&j| moved[j * n..(j + 1) * n].iter().any(|z| z.norm() > 0.0));
            let (lo, hi) = (rows.clone().min().unwrap(), rows.max().unwrap() + 1);
            assert!(lo > 0 && hi < n, "rows {lo}..{hi}");
            let (mut otf_rows, mut d_rows) = (Otf::new(), Otf::new());
            plan.otf_and_edge_derivative(
                &pupil,
                lambda,
                &moved[lo * n..hi * n],
                lo..hi,
                d_weight,
                &mut otf_rows,
                &mut d_rows,
            );
            assert_eq!(d_rows, d);
            assert_eq!(otf_rows, otf);
            let grid = |e: f64| {
                let mut out = Otf::new();
                plan.clone().otf(&SampledPupil::new(n, &aperture(e), &aberrations).unwrap(), lambda, &mut out);
                out
            };
            let (up, down, plain) = (grid(eps + 1e-6), grid(eps - 1e-6), grid(eps));
            assert_eq!(otf, plain);
            let half = otf.max_lag() as i64;
            let mut largest: f64 = 0.0;
            for ky in -half..=half {
                for kx in -half..=half {
                    let differences = (up.sample(kx, ky) - down.sample(kx, ky)) / 2e-6;
                    largest = largest.max(differences.norm());
                    assert!((d.sample(kx, ky) - differences).norm() <= 1e-7, "ε {eps}, ({kx}, {ky})");
                }
            }
            assert!(largest > 0.05, "{largest}");
            assert_eq!(d.sample(0, 0), Complex64::new(0.0, 0.0));
        }
    }

    /// The OTF grids' derivatives by forward mode through the FFT against central differences of
    /// the grids of the field with its phase stepped along the direction: a coma-like wavefront
    /// with defocus and astigmatism on a 32-sample circle, the direction astigmatism, step 1e-4
    /// rad (truncation ~1e-9).
    #[test]
    fn otf_derivatives_match_differences_of_the_grids() {
        let n = 32;
        let h = 2.0 / n as f64;
        let (mut field, mut direction, mut weight) = (vec![Complex64::new(0.0, 0.0); n * n], vec![0.0; n * n], 0.0);
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
                let r2 = x * x + y * y;
                if r2 <= 1.0 {
                    field[j * n + i] = Complex64::from_polar(1.0, 2.0 * r2 * x + 1.5 * r2 + 0.7 * x * y);
                    direction[j * n + i] = x * x - y * y;
                    weight += 1.0;
                }
            }
        }
        let (k, step) = (1.0, 1e-4);
        let mut plan = OtfPlan::new(n, 0.9).unwrap();
        let (mut otf, mut d) = (Otf::new(), vec![Otf::new()]);
        plan.otf_and_derivatives_of_field(&field, weight, k, &[&direction], &mut otf, &mut d);
        let moved = |sign: f64| {
            let f: Vec<Complex64> = field
                .iter()
                .zip(&direction)
                .map(|(p, &dw)| p * Complex64::from_polar(1.0, sign * step * k * dw))
                .collect();
            let mut out = Otf::new();
            plan.clone().otf_of_field(&f, weight, &mut out);
            out
        };
        let (up, down) = (moved(1.0), moved(-1.0));
        let mut plain = Otf::new();
        plan.otf_of_field(&field, weight, &mut plain);
        let half = otf.max_lag() as i64;
        let mut largest: f64 = 0.0;
        for ky in -half..=half {
            for kx in -half..=half {
                assert_eq!(otf.sample(kx, ky), plain.sample(kx, ky));
                let differences = (up.sample(kx, ky) - down.sample(kx, ky)) / (2.0 * step);
                largest = largest.max(differences.norm());
                assert!((d[0].sample(kx, ky) - differences).norm() <= 1e-7, "({kx}, {ky})");
            }
        }
        assert!(largest > 0.1, "{largest}");
        assert_eq!(d[0].sample(0, 0), Complex64::new(0.0, 0.0));
    }

    #[test]
    fn fast_lengths_are_smooth_and_minimal() {
        assert_eq!(fast_fft_len(617), 640);
        assert_eq!(fast_fft_len(1231), 1280);
        assert_eq!(fast_fft_len(412), 480);
        assert_eq!(fast_fft_len(77), 80);
        assert_eq!(fast_fft_len(64), 64);
    }

    #[test]
    fn lagrange_weights_reproduce_cubics() {
        for t in [0.0, 0.25, 0.5, 0.9] {
            let w = lagrange_weights(t);
            for p in 0..INTERPOLATION_POINTS as i32 {
                let lo = 1 - (INTERPOLATION_POINTS as i32) / 2;
                let got: f64 = w.iter().enumerate().map(|(j, wj)| wj * ((lo + j as i32) as f64).powi(p)).sum();
                assert!((got - t.powi(p)).abs() < 1e-13, "t = {t}, degree {p}");
            }
        }
    }

    /// The Hermitian shortcut of the inverse transform against the direct sum
    /// `Σ_m P(m) P*(m + k) / Σ A` at every stored lag, for an odd and an even padded length.
    #[test]
    fn grid_is_the_direct_autocorrelation() {
        for (n, s_max, odd) in [(10, 0.2, true), (12, 0.2, false), (9, 1.0, false)] {
            let mut plan = OtfPlan::new(n, s_max).unwrap();
            assert_eq!(plan.padded_len() % 2 == 1, odd, "M = {}", plan.padded_len());
            // an arbitrary field with a few zeros
            let field: Vec<Complex64> = (0..n * n)
                .map(|p| {
                    if p % 7 == 3 {
                        Complex64::new(0.0, 0.0)
                    } else {
                        Complex64::from_polar(0.3 + (p % 5) as f64 * 0.15, 0.37 * (p * p) as f64)
                    }
                })
                .collect();
            let weight: f64 = field.iter().map(|z| z.norm_sqr()).sum();
            let mut otf = Otf::new();
            plan.otf_of_field(&field, weight, &mut otf);
            let k = otf.max_lag() as i64;
            let at = |i: i64, j: i64| {
                if (0..n as i64).contains(&i) && (0..n as i64).contains(&j) {
                    field[(j * n as i64 + i) as usize]
                } else {
                    Complex64::new(0.0, 0.0)
                }
            };
            let mut worst: f64 = 0.0;
            for ky in -k..=k {
                for kx in -k..=k {
                    if kx == 0 && ky == 0 {
                        continue;
                    }
                    let mut direct = Complex64::new(0.0, 0.0);
                    for j in 0..n as i64 {
                        for i in 0..n as i64 {
                            direct += at(i, j) * at(i + kx, j + ky).conj();
                        }
                    }
                    worst = worst.max((otf.sample(kx, ky) - direct / weight).norm());
                }
            }
            assert!(worst < 1e-14, "N = {n}: {worst:e}");
        }
    }

    #[test]
    fn plan_is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<OtfPlan>();
        check::<Otf>();
        check::<SampledPupil>();
    }
}
