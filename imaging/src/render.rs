//! The forward model of the paper's Fig. 4 and its restoration: a test object → the scene's
//! photoelectrons per pixel → the 2-D polychromatic OTF → veiling glare → sensor noise, and the
//! Wiener filter back.
//!
//! 1. **Object.** A [`Target`] of relative radiance `o ∈ [0, 1]` on a grid `S` times finer than
//!    the pixels (`S` odd).
//! 2. **Light.** A white area of the object gives `N` first-order photoelectrons per pixel (paper
//!    SI eq. S7–S8: [`metric::Evaluation::photoelectrons`]).
//! 3. **Optics.** The image is `N · (o ⊛ PSF)`: on the fine grid, the object's spectrum times the
//!    scene's polychromatic OTF ([`transfer`]: the signed, complex sum over wavelengths with the
//!    photoelectron weights, each wavelength at its own `s = ν λ F#`, at the scene's field and
//!    pupil; docs/physics.md, "Polychromatic OTF"). The product of spectra is a circular
//!    convolution: the object is padded to twice its size by repeating its edge cells, so no
//!    light wraps from one edge onto the opposite one (for PSFs up to half the image wide).
//! 4. **Pixels.** Each pixel reads the fine cell at its centre, or, when the camera applies the
//!    pixel MTF (`camera.pixel_mtf`), the mean of its `S × S` cells (pixel integration, whose
//!    transfer is the pixel MTF sampled on the fine grid).
//! 5. **Veiling glare.** The light the lens sends into other orders, `N_T − N` per pixel for a
//!    white object (eq. S8 with τ1 → T), is spread far beyond the image: a uniform veil of
//!    `(N_T − N) · ō` over the frame, `ō` the object's mean. For `ō = 1/2` the modulation of a
//!    large pattern is `N/(N + 2(N_T − N)ō) = τ1/T`, Buralli and Morris's `M0` (eq. S13).
//! 6. **Sensor** (EMVA 1288 linear model, [`noise::Sensor`]): Poisson photoelectrons of the
//!    expected charge plus the dark charge (dark current × exposure), clipped at the full well,
//!    Gaussian read noise, and with an ADC `DN = round(K e)` clipped to `[0, 2^bits − 1]`.
//!    Seeded (PCG-64 MCG): a seed gives the same frames on every machine.
//! 7. **Restoration.** Wiener: `G = H*/(|H|² + NSR)` with `H` the transfer from the object to the
//!    pixels (the OTF at the pixels' frequencies, times the pixel MTF when it is applied) and
//!    `NSR = σ²/N²`: the frame's white noise (its variance at the frame's mean level: shot noise of
//!    signal, veil and dark, read noise, quantization) over the power of a full white-to-black
//!    modulation. Then `G H = SNR(ν)²/(1 + SNR(ν)²)` with `SNR(ν) = MTF(ν) N/σ`, the SNR whose
//!    average over frequency is the ASNR (eq. 1): the restored contrast follows the ASNR.
//!    Optionally the black level is subtracted and the white raised back by a gain, as the paper
//!    discusses (the SNR is unchanged).

use std::f64::consts::{PI, SQRT_2};
use std::sync::Arc;

use num_complex::Complex64;
use optics::Polychromatic;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal, Poisson};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use serde::Serialize;

use crate::Error;
use crate::target::{Orientation, Target, bar_fundamental, bar_modulation};

/// Real 2-D FFTs of one size (`nx` columns, `ny` rows, row-major): rows by `realfft` (real ↔ the
/// half spectrum `nx/2 + 1` wide), columns by `rustfft`.
pub struct Fft2 {
    nx: usize,
    ny: usize,
    r2c: Arc<dyn realfft::RealToComplex<f64>>,
    c2r: Arc<dyn realfft::ComplexToReal<f64>>,
    col_forward: Arc<dyn rustfft::Fft<f64>>,
    col_inverse: Arc<dyn rustfft::Fft<f64>>,
}

impl Fft2 {
    /// Plans the transforms of an `nx × ny` image (`nx` even).
    pub fn new(nx: usize, ny: usize) -> Fft2 {
        let mut real = realfft::RealFftPlanner::<f64>::new();
        let mut complex = rustfft::FftPlanner::<f64>::new();
        Fft2 {
            nx,
            ny,
            r2c: real.plan_fft_forward(nx),
            c2r: real.plan_fft_inverse(nx),
            col_forward: complex.plan_fft_forward(ny),
            col_inverse: complex.plan_fft_inverse(ny),
        }
    }

    /// Columns of the half spectrum, `nx/2 + 1`.
    pub fn half_width(&self) -> usize {
        self.nx / 2 + 1
    }

    /// The half spectrum `F[ky · (nx/2 + 1) + kx]` of a real image (unnormalized DFT,
    /// `exp(−2πi k·n/N)`).
    pub fn forward(&self, image: &[f64]) -> Vec<Complex64> {
        let hw = self.half_width();
        let mut spectrum = vec![Complex64::new(0.0, 0.0); hw * self.ny];
        let mut row = vec![0.0; self.nx];
        for (y, out) in spectrum.chunks_exact_mut(hw).enumerate() {
            row.copy_from_slice(&image[y * self.nx..(y + 1) * self.nx]);
            // lengths match by construction
            let _ = self.r2c.process(&mut row, out);
        }
        self.columns(&mut spectrum, &self.col_forward);
        spectrum
    }

    /// The real image of a half spectrum, normalized (`inverse(forward(x)) = x`).
    pub fn inverse(&self, mut spectrum: Vec<Complex64>) -> Vec<f64> {
        let hw = self.half_width();
        self.columns(&mut spectrum, &self.col_inverse);
        let scale = 1.0 / (self.nx * self.ny) as f64;
        let mut image = vec![0.0; self.nx * self.ny];
        for (row, out) in spectrum.chunks_exact_mut(hw).zip(image.chunks_exact_mut(self.nx)) {
            // the DC and Nyquist bins of a real row are real: drop their rounding residue
            row[0].im = 0.0;
            if self.nx.is_multiple_of(2) {
                row[hw - 1].im = 0.0;
            }
            let _ = self.c2r.process(row, out);
            for v in out.iter_mut() {
                *v *= scale;
            }
        }
        image
    }

    fn columns(&self, spectrum: &mut [Complex64], fft: &Arc<dyn rustfft::Fft<f64>>) {
        let hw = self.half_width();
        let mut column = vec![Complex64::new(0.0, 0.0); self.ny];
        for x in 0..hw {
            for (y, c) in column.iter_mut().enumerate() {
                *c = spectrum[y * hw + x];
            }
            fft.process(&mut column);
            for (y, c) in column.iter().enumerate() {
                spectrum[y * hw + x] = *c;
            }
        }
    }
}

/// Azimuths over `[0, π)` at which a direction-dependent OTF is sampled (1.4° apart); between
/// them it is interpolated linearly, and `OTF(ν, φ + π) = OTF(ν, φ)*` gives the other half.
pub const AZIMUTHS: usize = 128;

/// Radial samples per frequency step of the grid: the OTF is read by cubic interpolation from
/// samples eight times finer than the grid's own frequency spacing.
pub const RADIAL_PER_STEP: f64 = 8.0;

/// A scene's polychromatic OTF sampled on the half spectrum of an `nx × ny` grid of spacing
/// `spacing_m` (the DFT frequencies `kx/(nx d)`, `ky/(ny d)`; `ky` above `ny/2` negative). The
/// grid's x is the detector's x; its rows run along the detector's y.
#[derive(Clone, Debug)]
pub struct Transfer {
    /// Columns of the grid.
    pub nx: usize,
    /// Rows of the grid.
    pub ny: usize,
    /// Sample spacing of the grid, m.
    pub spacing_m: f64,
    /// `OTF[ky · (nx/2 + 1) + kx]`, 1 at zero frequency.
    pub values: Vec<Complex64>,
    /// Whether the OTF depends on the direction (off axis with lateral colour, decentred pupils).
    pub direction_dependent: bool,
    /// Evaluations of the polychromatic OTF it took.
    pub evaluations: usize,
}

impl Transfer {
    /// The value at the grid's frequency `(kx, ky)` (`kx ≤ nx/2`).
    pub fn at(&self, kx: usize, ky: usize) -> Complex64 {
        self.values[ky * (self.nx / 2 + 1) + kx]
    }
}

/// Signed index of DFT bin `k` of `n`.
fn signed(k: usize, n: usize) -> f64 {
    if k <= n / 2 { k as f64 } else { k as f64 - n as f64 }
}

/// Samples the polychromatic OTF of `scene` (at its field point; the first one of a
/// field-of-view average) on the half spectrum of an `nx × ny` grid of spacing `spacing_m`.
///
/// The OTF is evaluated on radii `k · h`, `h` an eighth of the grid's frequency step, up to the
/// grid's corner or the incoherent cutoff of the shortest wavelength (zero beyond), along one
/// azimuth where it does not depend on the direction and along [`AZIMUTHS`] otherwise, and read
/// at each grid frequency by cubic (Catmull–Rom) interpolation in radius and linear
/// interpolation in azimuth. Where the grid has no more frequencies inside the cutoff than that
/// table has samples (a small grid off axis, as `asnr otf` and `asnr psf` write), the OTF is
/// evaluated at each grid frequency instead: exact there, with no interpolation, and cheaper.
/// In parallel (each worker its own `Polychromatic`).
///
/// # Errors
/// [`Error::Scene`] when the scene's optics cannot be evaluated.
pub fn transfer(scene: &metric::Scene, nx: usize, ny: usize, spacing_m: f64) -> Result<Transfer, Error> {
    transfer_sampled(scene, nx, ny, spacing_m, nx.max(ny), true)
}

/// [`transfer`] always read from the table (cubic in radius, linear in azimuth), even where the
/// grid's own frequencies would be fewer: the interpolated path of large grids, on any grid, for
/// measuring its error against the direct evaluation.
///
/// # Errors
/// [`Error::Scene`] when the scene's optics cannot be evaluated.
pub fn transfer_interpolated(scene: &metric::Scene, nx: usize, ny: usize, spacing_m: f64) -> Result<Transfer, Error> {
    transfer_sampled(scene, nx, ny, spacing_m, nx.max(ny), false)
}

/// [`transfer`] with the radial samples an eighth of the frequency step of a grid of `sampled`
/// cells a side (a padded grid keeps the sampling of the image it pads: the OTF is no less
/// smooth for the padding); `direct`: whether a grid with fewer frequencies than the table has
/// samples is evaluated at its own frequencies instead.
fn transfer_sampled(
    scene: &metric::Scene,
    nx: usize,
    ny: usize,
    spacing_m: f64,
    sampled: usize,
    direct: bool,
) -> Result<Transfer, Error> {
    let lens = scene.lens();
    let detected = metric::detected_spectrum(scene);
    let field = scene.field();
    let settings = scene.options().settings();
    let optics_error = |e: optics::Error| Error::Scene(metric::Error::Optics(e));
    let cutoff = optics::highest_cutoff(lens, &detected).map_err(optics_error)?;
    let corner = 0.5 / spacing_m * SQRT_2;
    let reach = corner.min(cutoff);
    let step = 1.0 / (RADIAL_PER_STEP * sampled as f64 * spacing_m);
    let radii = (reach / step).ceil() as usize + 3;
    let probe = Polychromatic::with_settings(lens, &detected, field, reach, None, settings).map_err(optics_error)?;
    let dependent = probe.direction_dependent();
    drop(probe);
    let azimuths = if dependent { AZIMUTHS } else { 1 };
    let hw = nx / 2 + 1;
    // the grid's frequency (ν_x, ν_y) of the half spectrum's sample `index`
    let frequency = |index: usize| -> (f64, f64) {
        let (kx, ky) = (index % hw, index / hw);
        (kx as f64 / (nx as f64 * spacing_m), signed(ky, ny) / (ny as f64 * spacing_m))
    };
    let inside = (0..ny * hw)
        .filter(|&index| {
            let (nu_x, nu_y) = frequency(index);
            let nu = nu_x.hypot(nu_y);
            nu > 0.0 && nu < cutoff
        })
        .count();
    if direct && inside <= (radii + 1) * azimuths {
        // fewer grid frequencies than table samples (a small grid off axis: `asnr otf`, `asnr
        // psf`): each grid frequency evaluated where it is, exact, with no interpolation
        let indices: Vec<usize> = (0..ny * hw).collect();
        let chunk = indices.len().div_ceil(4 * rayon::current_num_threads().max(1)).max(64);
        let values: Vec<Vec<Complex64>> = indices
            .par_chunks(chunk)
            .map(|indices| -> Result<Vec<Complex64>, Error> {
                let poly = Polychromatic::with_settings(lens, &detected, field, reach, None, settings)
                    .map_err(optics_error)?;
                Ok(indices
                    .iter()
                    .map(|&index| {
                        let (nu_x, nu_y) = frequency(index);
                        let nu = nu_x.hypot(nu_y);
                        if nu >= cutoff { Complex64::new(0.0, 0.0) } else { poly.otf_along(nu, nu_y.atan2(nu_x)) }
                    })
                    .collect())
            })
            .collect::<Result<_, _>>()?;
        let values = values.into_iter().flatten().collect();
        return Ok(Transfer { nx, ny, spacing_m, values, direction_dependent: dependent, evaluations: inside });
    }
    // table[k · azimuths + m] = OTF(k h, m π/azimuths), k = 0 … radii
    let chunk = (radii + 1).div_ceil(4 * rayon::current_num_threads().max(1)).max(16);
    let table: Vec<Vec<Complex64>> = (0..=radii)
        .collect::<Vec<_>>()
        .par_chunks(chunk)
        .map(|ks| -> Result<Vec<Complex64>, Error> {
            let poly =
                Polychromatic::with_settings(lens, &detected, field, reach, None, settings).map_err(optics_error)?;
            let mut out = Vec::with_capacity(ks.len() * azimuths);
            for &k in ks {
                let nu = k as f64 * step;
                for m in 0..azimuths {
                    let phi = m as f64 * PI / azimuths as f64;
                    out.push(if nu < cutoff { poly.otf_along(nu, phi) } else { Complex64::new(0.0, 0.0) });
                }
            }
            Ok(out)
        })
        .collect::<Result<_, _>>()?;
    let table: Vec<Complex64> = table.into_iter().flatten().collect();
    // sample (k, m); k = −1 continues the radial profile linearly (the OTF has a cone at ν = 0,
    // |ν|-like through the origin, but each radial profile is smooth from r = 0 on)
    let sample = |k: isize, m: usize| -> Complex64 {
        if k < 0 { table[m] * 2.0 - table[azimuths + m] } else { table[k as usize * azimuths + m] }
    };
    let along = |nu: f64, m: usize| -> Complex64 {
        let t = nu / step;
        let i = t.floor() as isize;
        let f = t - i as f64;
        // Catmull–Rom weights
        let w = [
            0.5 * (-f + 2.0 * f * f - f * f * f),
            0.5 * (2.0 - 5.0 * f * f + 3.0 * f * f * f),
            0.5 * (f + 4.0 * f * f - 3.0 * f * f * f),
            0.5 * (-f * f + f * f * f),
        ];
        (0..4).map(|j| sample(i - 1 + j as isize, m) * w[j as usize]).sum()
    };
    let values: Vec<Complex64> = (0..ny * hw)
        .into_par_iter()
        .map(|index| {
            let (nu_x, nu_y) = frequency(index);
            let nu = nu_x.hypot(nu_y);
            if nu == 0.0 {
                return Complex64::new(1.0, 0.0);
            }
            if nu >= cutoff {
                return Complex64::new(0.0, 0.0);
            }
            if azimuths == 1 {
                return along(nu, 0);
            }
            // φ in (−π/2, π/2]; the lower half is the conjugate of the opposite direction
            let mut phi = nu_y.atan2(nu_x);
            let flip = phi < 0.0;
            if flip {
                phi += PI;
            }
            let t = phi / PI * azimuths as f64;
            let m = (t.floor() as usize).min(azimuths - 1);
            let f = t - m as f64;
            let a = along(nu, m);
            let b = if m + 1 == azimuths { along(nu, 0).conj() } else { along(nu, m + 1) };
            let v = a * (1.0 - f) + b * f;
            if flip { v.conj() } else { v }
        })
        .collect();
    Ok(Transfer { nx, ny, spacing_m, values, direction_dependent: dependent, evaluations: (radii + 1) * azimuths })
}

/// How a rendering is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Seed of the noise (frame `i` uses `seed + i`).
    pub seed: u64,
    /// Raw frames to draw (at least 1; the first is restored).
    pub frames: usize,
    /// Whether the light of the other orders veils the image (step 5).
    pub glare: bool,
    /// Whether the restored image has the black level subtracted and the white raised back.
    pub subtract_black: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { seed: 1, frames: 1, glare: true, subtract_black: false }
    }
}

/// The measured modulation of one bar set in the noise-free, raw and restored images.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BarContrast {
    /// USAF group.
    pub group: i32,
    /// USAF element.
    pub element: u8,
    /// Line pairs per mm at the detector.
    pub frequency_cyc_per_mm: f64,
    /// Which way the bars run.
    pub orientation: Orientation,
    /// Whether the frequency lies above the detector's Nyquist frequency (aliased).
    pub above_nyquist: bool,
    /// In the noise-free image.
    pub expected: f64,
    /// In the first raw frame.
    pub raw: f64,
    /// In the restored image.
    pub restored: f64,
    /// Contrast-to-noise ratio over the raw frames: the mean of the bars' fundamental amplitude
    /// ([`bar_fundamental`]) over the frames, over its temporal standard deviation (at least 2
    /// frames): the SNR at the bars' frequency, eq. 2–4 applied to a bar set.
    pub cnr_raw: Option<f64>,
    /// Contrast-to-noise ratio over the restored frames, likewise.
    pub cnr_restored: Option<f64>,
}

/// A rendered scene.
#[derive(Clone, Debug)]
pub struct Rendering {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Noise-free charge per pixel, e⁻ (signal, veil and dark).
    pub expected_e: Vec<f64>,
    /// Raw frames: DN with an ADC, e⁻ without.
    pub frames: Vec<Vec<f64>>,
    /// The first frame restored, e⁻ (black-subtracted and raised back if asked).
    pub restored_e: Vec<f64>,
    /// First-order photoelectrons of a white area, `N` (eq. S7–S8).
    pub signal_e: f64,
    /// The uniform veil of the other orders' light, e⁻ per pixel.
    pub veil_e: f64,
    /// Dark charge per pixel, e⁻.
    pub dark_e: f64,
    /// Expected charge of a large white area, e⁻.
    pub white_e: f64,
    /// Expected charge of a large black area, e⁻.
    pub black_e: f64,
    /// The noise-to-signal power ratio of the Wiener filter, `σ²/N²`.
    pub nsr: f64,
    /// The frame's noise standard deviation at its mean level, e⁻.
    pub noise_e: f64,
    /// DN per e⁻ of the raw frames (the ADC's gain), or `None` when they are in e⁻.
    pub dn_per_e: Option<f64>,
    /// Per bar set, its modulation.
    pub bars: Vec<BarContrast>,
    /// The OTF's evaluations.
    pub otf_evaluations: usize,
    /// Whether the OTF depends on the direction.
    pub direction_dependent: bool,
}

impl Rendering {
    /// Mean restored modulation over the bar sets below Nyquist (0 without bars).
    pub fn mean_restored_contrast(&self) -> f64 {
        mean(self.bars.iter().filter(|b| !b.above_nyquist).map(|b| b.restored))
    }

    /// Mean raw modulation over the bar sets below Nyquist (0 without bars).
    pub fn mean_raw_contrast(&self) -> f64 {
        mean(self.bars.iter().filter(|b| !b.above_nyquist).map(|b| b.raw))
    }

    /// The restored contrast-to-noise ratio averaged over frequency as the ASNR averages the
    /// SNR (eq. 1): the two orientations of each element averaged, then the trapezoid rule over
    /// the elements' frequencies below Nyquist divided by their span (`None` with fewer than two
    /// elements or two frames).
    pub fn frequency_mean_cnr_restored(&self) -> Option<f64> {
        frequency_mean(&self.bars, |b| b.cnr_restored)
    }

    /// [`frequency_mean_cnr_restored`](Self::frequency_mean_cnr_restored) of the raw frame.
    pub fn frequency_mean_cnr_raw(&self) -> Option<f64> {
        frequency_mean(&self.bars, |b| b.cnr_raw)
    }
}

fn frequency_mean(bars: &[BarContrast], value: impl Fn(&BarContrast) -> Option<f64>) -> Option<f64> {
    // (frequency, mean over orientations), in frequency order
    let mut points: Vec<(f64, f64, usize)> = Vec::new();
    for b in bars.iter().filter(|b| !b.above_nyquist) {
        let v = value(b)?;
        match points.iter_mut().find(|p| p.0 == b.frequency_cyc_per_mm) {
            Some(p) => {
                p.1 += v;
                p.2 += 1;
            }
            None => points.push((b.frequency_cyc_per_mm, v, 1)),
        }
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    if points.len() < 2 {
        return None;
    }
    let area: f64 =
        points.windows(2).map(|w| 0.5 * (w[0].1 / w[0].2 as f64 + w[1].1 / w[1].2 as f64) * (w[1].0 - w[0].0)).sum();
    Some(area / (points[points.len() - 1].0 - points[0].0))
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0_usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// Renders `target` through `scene` (whose evaluation is `evaluation`): the noise-free image, the
/// raw frames and the restored first frame (module docs, steps 1–7).
///
/// # Errors
/// [`Error::Scene`] when the optics cannot be evaluated, [`Error::Render`] for no frames or a
/// scene without signal.
pub fn render(
    scene: &metric::Scene,
    evaluation: &metric::Evaluation,
    target: &Target,
    settings: &Settings,
) -> Result<Rendering, Error> {
    if settings.frames == 0 {
        return Err(Error::Render { message: "0 frames: expected at least 1".to_owned() });
    }
    let signal_e = evaluation.photoelectrons;
    if !(signal_e.is_finite() && signal_e > 0.0) {
        return Err(Error::Render { message: format!("{signal_e} photoelectrons per pixel: nothing to image") });
    }
    let camera = scene.camera();
    let pitch = camera.pixel_pitch();
    let s = target.oversample;
    let (fw, fh) = (target.fine_width(), target.fine_height());
    let (w, h) = (target.width, target.height);
    // 3. the image on the fine grid, relative to a white area: the object padded to twice its
    // size by repeating its edge cells, so that the convolution (a product of spectra, periodic)
    // does not wrap light from one edge onto the opposite one (PSFs up to half the image wide)
    let (pw, ph) = (2 * fw, 2 * fh);
    let (ox, oy) = (fw / 2, fh / 2);
    let otf = transfer_sampled(scene, pw, ph, pitch / s as f64, fw.max(fh), true)?;
    let padded: Vec<f64> = (0..pw * ph)
        .map(|i| {
            let (x, y) = ((i % pw).saturating_sub(ox).min(fw - 1), (i / pw).saturating_sub(oy).min(fh - 1));
            target.fine[y * fw + x]
        })
        .collect();
    let fine_fft = Fft2::new(pw, ph);
    let mut spectrum = fine_fft.forward(&padded);
    for (v, t) in spectrum.iter_mut().zip(&otf.values) {
        *v *= t;
    }
    let blurred_padded = fine_fft.inverse(spectrum);
    let blurred: Vec<f64> = (0..fw * fh).map(|i| blurred_padded[(i / fw + oy) * pw + i % fw + ox]).collect();
    // 4. pixels: the centre cell, or the mean of the pixel's cells
    let integrate = camera.pixel_mtf();
    let c = s / 2;
    let relative: Vec<f64> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if integrate {
                let mut sum = 0.0;
                for r in 0..s {
                    let row = &blurred[(y * s + r) * fw + x * s..(y * s + r) * fw + x * s + s];
                    sum += row.iter().sum::<f64>();
                }
                sum / (s * s) as f64
            } else {
                blurred[(y * s + c) * fw + x * s + c]
            }
        })
        .collect();
    // 5. light: signal, the veil of the other orders, dark charge
    let object_mean = target.mean();
    let veil_e =
        if settings.glare { (evaluation.transmitted_photoelectrons - signal_e).max(0.0) * object_mean } else { 0.0 };
    let sensor = camera.sensor();
    let dark_e = sensor.dark_current_e_per_s() * scene.exposure();
    let expected_e: Vec<f64> = relative.iter().map(|r| signal_e * r.max(0.0) + veil_e + dark_e).collect();
    // 6. frames
    let frames = (0..settings.frames)
        .map(|i| expose(&expected_e, sensor, settings.seed.wrapping_add(i as u64)))
        .collect::<Result<Vec<_>, _>>()?;
    let dn_per_e = sensor.gain_dn_per_e();
    let offset = sensor.black_level_dn();
    let to_electrons =
        |frame: &[f64]| -> Vec<f64> { frame.iter().map(|v| dn_per_e.map_or(*v, |k| (v - offset) / k)).collect() };
    // 7. Wiener restoration on the pixel grid, G = H*/(|H|² + NSR)
    let mean_level = expected_e.iter().sum::<f64>() / expected_e.len() as f64;
    let variance = mean_level + sensor.read_noise_e().powi(2) + sensor.quantization_variance_e2();
    let nsr = variance / (signal_e * signal_e);
    let pixel_fft = Fft2::new(w, h);
    let hw = w / 2 + 1;
    let filter: Vec<Complex64> = (0..h * hw)
        .map(|index| {
            let (kx, ky) = (index % hw, index / hw);
            // the pixel grid's bin k is the padded fine grid's bin 2k (its frequency k/(w p))
            let fine_ky = if ky <= h / 2 { 2 * ky } else { ph - 2 * (h - ky) };
            let mut t = otf.at(2 * kx, fine_ky);
            if integrate {
                t *= box_factor(kx, w, s) * box_factor(if ky <= h / 2 { ky } else { h - ky }, h, s);
            }
            t.conj() / (t.norm_sqr() + nsr)
        })
        .collect();
    let white_e = signal_e + veil_e + dark_e;
    let black_e = veil_e + dark_e;
    let restore = |raw_e: &[f64]| -> Vec<f64> {
        let mut spectrum = pixel_fft.forward(raw_e);
        for (v, g) in spectrum.iter_mut().zip(&filter) {
            *v *= g;
        }
        let mut restored = pixel_fft.inverse(spectrum);
        if settings.subtract_black {
            let gain = white_e / (white_e - black_e);
            for v in &mut restored {
                *v = (*v - black_e) * gain;
            }
        }
        restored
    };
    // every frame restored: the bars' fundamental amplitude over the frames gives their temporal
    // contrast-to-noise ratio, raw and restored (eq. 2–4 applied to a bar set)
    let mut raw_e = Vec::new();
    let mut restored_e = Vec::new();
    let mut differences: Vec<Vec<[f64; 2]>> = vec![Vec::with_capacity(frames.len()); target.bars.len()];
    for (i, frame) in frames.iter().enumerate() {
        let raw = to_electrons(frame);
        let restored = restore(&raw);
        for (set, d) in target.bars.iter().zip(&mut differences) {
            d.push([bar_fundamental(&raw, w, set), bar_fundamental(&restored, w, set)]);
        }
        if i == 0 {
            raw_e = raw;
            restored_e = restored;
        }
    }
    let cnr = |d: &[[f64; 2]], k: usize| -> Option<f64> {
        let n = d.len();
        (n >= 2).then(|| {
            let m = d.iter().map(|v| v[k]).sum::<f64>() / n as f64;
            let var = d.iter().map(|v| (v[k] - m).powi(2)).sum::<f64>() / (n - 1) as f64;
            m.abs() / var.sqrt()
        })
    };
    let bars = target
        .bars
        .iter()
        .zip(&differences)
        .map(|(set, d)| BarContrast {
            group: set.group,
            element: set.element,
            frequency_cyc_per_mm: set.frequency_cyc_per_mm,
            orientation: set.orientation,
            above_nyquist: !set.resolvable_by_pixels(),
            expected: bar_modulation(&expected_e, w, set),
            raw: bar_modulation(&raw_e, w, set),
            restored: bar_modulation(&restored_e, w, set),
            cnr_raw: cnr(d, 0),
            cnr_restored: cnr(d, 1),
        })
        .collect();
    Ok(Rendering {
        width: w,
        height: h,
        expected_e,
        frames,
        restored_e,
        signal_e,
        veil_e,
        dark_e,
        white_e,
        black_e,
        nsr,
        noise_e: variance.sqrt(),
        dn_per_e,
        bars,
        otf_evaluations: otf.evaluations,
        direction_dependent: otf.direction_dependent,
    })
}

/// Transfer of the mean over `s` fine cells centred on a pixel, at the pixel grid's DFT bin `k`
/// of `n` (`k ≤ n/2`): `(1/s) Σ_m cos(2π k m/(s n))`, `m = −(s−1)/2 … (s−1)/2` (the pixel MTF
/// `sinc(p ν)` as the fine grid samples it).
fn box_factor(k: usize, n: usize, s: usize) -> f64 {
    let half = (s / 2) as isize;
    (-half..=half).map(|m| (2.0 * PI * k as f64 * m as f64 / (s * n) as f64).cos()).sum::<f64>() / s as f64
}

/// One raw frame of the expected charge `expected_e` (step 6): DN with an ADC, e⁻ without.
///
/// # Errors
/// [`Error::Render`] for a charge the Poisson sampler cannot take (not finite).
pub fn expose(expected_e: &[f64], sensor: &noise::Sensor, seed: u64) -> Result<Vec<f64>, Error> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let read = Normal::new(0.0, sensor.read_noise_e())
        .map_err(|e| Error::Render { message: format!("read noise {}: {e}", sensor.read_noise_e()) })?;
    let full_well = sensor.full_well_e();
    let adc = sensor.gain_dn_per_e().zip(sensor.adc_bits());
    let offset = sensor.black_level_dn();
    expected_e
        .iter()
        .map(|&mean| {
            let shot = if mean > 0.0 {
                Poisson::new(mean)
                    .map_err(|e| Error::Render { message: format!("expected charge {mean} e⁻: {e}") })?
                    .sample(&mut rng)
            } else {
                0.0
            };
            let charge = shot.min(full_well) + read.sample(&mut rng);
            Ok(match adc {
                Some((k, bits)) => (k * charge + offset).round().clamp(0.0, ((1_u64 << bits) - 1) as f64),
                None => charge,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fft2_round_trips_and_matches_the_direct_dft() {
        let (nx, ny) = (6, 5);
        let image: Vec<f64> = (0..nx * ny).map(|i| ((i * 7919) % 13) as f64 - 4.0).collect();
        let fft = Fft2::new(nx, ny);
        let spectrum = fft.forward(&image);
        // the direct DFT at every bin of the half spectrum
        for ky in 0..ny {
            for kx in 0..=nx / 2 {
                let mut sum = Complex64::new(0.0, 0.0);
                for y in 0..ny {
                    for x in 0..nx {
                        let phase = -2.0 * PI * (kx as f64 * x as f64 / nx as f64 + ky as f64 * y as f64 / ny as f64);
                        sum += Complex64::from_polar(image[y * nx + x], phase);
                    }
                }
                assert!((spectrum[ky * (nx / 2 + 1) + kx] - sum).norm() < 1e-12, "({kx}, {ky})");
            }
        }
        let back = fft.inverse(spectrum);
        for (a, b) in image.iter().zip(&back) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn box_factor_is_the_sampled_pixel_mtf() {
        // k = 0: 1; a fine grid of 3 cells per pixel at the pixel Nyquist (k = n/2):
        // (1 + 2 cos(π/3))/3 = 2/3, against sinc(1/2) = 0.6366 of the continuous pixel
        assert!((box_factor(0, 64, 3) - 1.0).abs() < 1e-15);
        assert!((box_factor(32, 64, 3) - 2.0 / 3.0).abs() < 1e-15);
        assert!((box_factor(32, 64, 1) - 1.0).abs() < 1e-15);
    }

    /// The sensor model: Poisson mean and variance, read noise added, ADC gain and clipping.
    #[test]
    fn exposure_has_the_sensor_statistics() {
        let n = 200_000;
        let expected = vec![400.0; n];
        let shot = expose(&expected, &noise::Sensor::ideal(), 7).unwrap();
        let (m, v) = moments(&shot);
        // standard errors: √(400/n) = 0.045 for the mean, 400 √(2/n) = 1.3 for the variance
        assert!((m - 400.0).abs() < 0.2, "{m}");
        assert!((v - 400.0).abs() < 6.0, "{v}");
        let sensor = noise::Sensor::new(5.0, 0.0, f64::INFINITY, 0.5, 12).unwrap();
        let dn = expose(&expected, &sensor, 7).unwrap();
        let (m, v) = moments(&dn);
        // DN: K(400) = 200, K²(400 + 25) + 1/12 = 106.33
        assert!((m - 200.0).abs() < 0.1, "{m}");
        assert!((v - 106.33).abs() < 2.0, "{v}");
        let clipped = expose(&[1e4], &noise::Sensor::new(0.0, 0.0, 3000.0, 1.0, 10).unwrap(), 1).unwrap();
        assert_eq!(clipped, vec![1023.0]);
        // a black level shifts the output, not its variance; without it a dark frame is clipped
        // at 0 DN and its variance reads low
        let offset = sensor.with_black_level(100.0).unwrap();
        let (m, v) = moments(&expose(&expected, &offset, 7).unwrap());
        assert!((m - 300.0).abs() < 0.1 && (v - 106.33).abs() < 2.0, "{m} {v}");
        let dark = vec![0.0; n];
        let (_, unclipped) = moments(&expose(&dark, &offset, 9).unwrap());
        let (_, clipped) = moments(&expose(&dark, &sensor, 9).unwrap());
        // K² σ_r² + 1/12 = 6.33 DN²; clipped at 0, about a third of that
        assert!((unclipped - 6.333).abs() < 0.15 && clipped < 3.0, "{unclipped} {clipped}");
        // a seed gives the same frame
        assert_eq!(expose(&expected[..100], &sensor, 3).unwrap(), expose(&expected[..100], &sensor, 3).unwrap());
    }

    fn moments(x: &[f64]) -> (f64, f64) {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let v = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64;
        (m, v)
    }
}
