//! General-pupil OTF by FFT: a sampled pupil of any shape (decentred, annular, sector, masked)
//! with any wavefront (Seidel terms, Noll Zernike terms) → complex 2-D OTF, read along any
//! azimuth, azimuthally averaged, or as the mean MTF up to a frequency.
//!
//! The exact 1-D path ([`crate::defocus_otf`]) covers a centred circle with defocus only
//! ([`SampledPupil::is_centred_defocus`] says when); this path covers everything else and is
//! tested against it where both apply.
//!
//! A composite pupil of coherent zones (a segmented multiplexed lens, [`crate::Pupil::Zones`])
//! is sampled once per set of zone apertures ([`SampledZones`]: each zone's pixels with their
//! exact area fractions, e.g. [`Aperture::ring`] zones); per wavelength its complex field
//! `Σ_j A_jk a_j exp(i 2π W_j/λ)` goes through [`OtfPlan::otf_of_field`], normalized by the power
//! `Σ_k Σ_j A_jk a_j²` the zones pass, which is the single aperture's normalization below for one
//! zone of amplitude 1 (zones tiling the circle give the circle's grid to rounding; tested,
//! with a brute-force autocorrelation of two half discs, in tests/optics/zones.rs).
//!
//! # Conventions
//! - **Pupil**: coordinates normalized to the aperture radius `R = D/2`, from the aperture centre;
//!   an `N × N` grid spans the diameter, pixel `h = 2/N` ([`SampledPupil`]). The wavefront is
//!   evaluated at `ρ` from the **lens axis** (the aperture may be decentred), in metres of OPD
//!   ([`Aberrations`]). Field `P = A exp(+i 2π W/λ)`, `A` the pixel's transmitted area fraction
//!   ([`Aperture`]), `W` the OPD at its centre.
//! - **Frequency**: `s = ν/ν_c`, `ν_c = 2 NA/λ = 1/(λ F#)` of the full aperture of diameter `D`
//!   (`F# = z/D`, `z` the pupil–detector distance), the crate's convention. `s = 1` is the cutoff
//!   of the full aperture whatever the shape; a lag of `k` pupil samples is `s = k/N`.
//!   Azimuths are counter-clockwise from `+x`.
//! - **OTF**: with the Fraunhofer PSF `PSF(x) = |∫ P(ξ) e^{−i 2π ξ·x/(λ z)} d²ξ|²` (time factor
//!   `e^{−iωt}`) and `OTF(ν) = ∫ PSF(x) e^{−i 2π ν·x} d²x / ∫ PSF`,
//!
//!   ```text
//!   OTF(s) = ∫ P(u) P*(u + 2s) d²u / ∫ |P|² d²u        (u, s in units of R and ν_c)
//!   ```
//!
//!   the normalized autocorrelation of the generalized pupil (Goodman, *Introduction to Fourier
//!   Optics*, 3rd ed., §6.3.1 and §6.4.1). `OTF(0) = 1`, `OTF(−s) = OTF(s)*`, and a PSF
//!   displaced by `x0` multiplies the OTF by `e^{−i 2π ν·x0}`. With these signs a wavefront slope
//!   `∂W/∂x > 0` moves the PSF toward `+x`, as the ray picture says: an iris decentred by `dx`
//!   (fraction of `R`) on a lens with defocus `w = W020/λ > 0` (focus behind the detector, rays
//!   not yet crossed) puts the blur at `x0 = 4 w dx λF#`, OTF phase `−8π w dx s_x` (tested). The
//!   OTF therefore keeps the image displacement (lateral colour, decentre) that a polychromatic
//!   sum needs.
//!
//! # Algorithm
//! The discrete OTF at lag `k = (kx, ky)` is `Σ_m P(m) P*(m + k) / Σ_m A(m)`. By Wiener–Khinchin
//! the DFT of a cyclic autocorrelation is `|DFT(P)|²`, so [`OtfPlan::otf`] computes
//! `conj IDFT₂(|DFT₂(P_pad)|²) / (M² Σ A)` on an `M × M` zero-padded grid. A direct sum over the
//! `(2K+1)²` wanted lags would cost `N² (2K+1)²` products (`~0.16 N⁴` at `s_max = 0.2`) against
//! `O(M² log M)`.
//!
//! **Padding.** The linear autocorrelation of an `N`-sample support vanishes for `|k| ≥ N`; the
//! cyclic one of length `M` adds copies shifted by `M`, so lags `|k| ≤ M − N` are alias-free.
//! Only `|k| ≤ K = ⌈s_max N⌉ + 2` are stored (two beyond `s_max N` for the interpolation
//! stencil), so `M ≥ N + K`: `Q = M/N ≈ 1 + s_max` — 1.2 for the paper scene's Nyquist
//! (`s ≈ 0.19`), where tools that pad to `Q = 2–4` for the whole OTF pay 3–11× the memory and
//! time for frequencies the metric never reads. `M` is the next fast length ([`fast_fft_len`]).
//! Only the `N` non-zero rows are transformed along `x`, and only the `2K + 1` wanted `ky` rows
//! along `x` on the way back: `2N + 2M + 2K + 1` FFTs of length `M` per evaluation, with the
//! plans (`Arc<dyn Fft<f64>>`) and buffers held by the reusable [`OtfPlan`].
//!
//! **Normalization by the exact area, not by the zero lag.** An edge pixel transmits its area
//! fraction `A ∈ (0, 1)`, so the zero lag `Σ A²` falls short of the area `Σ A` by `O(h)` (0.5 %
//! at `N = 128`), while lags beyond a pixel average the edge out. Dividing by the zero lag — what
//! "normalize to 1 at zero" does literally — biases every frequency upward by `O(1/N)` (measured
//! +1.1e-3 in the mean MTF at `N = 512`); dividing by `Σ A h²`, which is the exact area for the
//! disc shapes, leaves the `O(N⁻² log N)` below. The zero lag is then set to exactly 1, its
//! continuum value.
//!
//! # Accuracy
//! 1. **Edge pixels** make the sampled pupil the aperture convolved with the pixel box, so the
//!    OTF comes out convolved with the tent `box ⋆ box` (variance `h²/6` per axis in `s`, with
//!    `h = 1/N`). Where the OTF is smooth that is `O(N⁻²)`; at its cone `1 − c|s|` at the origin
//!    (`c = 4/π` for a circle, `∮|n·ŝ| dl / area` in general) it is `−c/(12 N² |s|)`: `−0.1/N` at
//!    the first lag — the largest pointwise error of any slice, measured `0.09/N` — and
//!    `O(N⁻² ln(s_max N))` in the mean MTF. A hard-edged pupil (binary pixels, as in prysm) has
//!    errors of roughly `O(1/N)` that jump with `N`: for `N` in [128, 144) and [256, 288) its mean-MTF
//!    error (`w = 0`, `s_max = 0.2`) reaches 1.9e-4 and 7.7e-5, against 6.7e-5 and 2.3e-5 here.
//! 2. **Wavefront sampling**: `W` at pixel centres. Defocus `w` turns the phase by up to
//!    `8πw/N` rad per pixel at the edge and the OTF oscillates in `s` with period `≈ 1/(4w)`:
//!    keep `N ≳ 50 w` (under 0.5 rad and over 12 samples per period).
//! 3. **Interpolation** ([`Otf::at`]): tensor-product 4-point Lagrange (bicubic), exact at the
//!    samples. Against the exact OTF tabulated on the same grid ([`Otf::tabulate`]), the error
//!    for `s ≥ 0.05` is `O(N⁻⁴)` (`w = 0`: 2.7e-6 at `N = 128`, 1.8e-7 at `N = 256`; `w = 1`:
//!    6.3e-6 and 4.2e-7). Near the
//!    origin the stencil straddles the cone: up to `0.15/N` within three samples of it, then
//!    decaying like `N⁻⁴/|s|³`; `≈ 0.45/N²` in a mean MTF over `[0, 0.2]`.
//!
//! Convergence with pupil sampling: error of the mean MTF over `[0, 0.2]` (the paper scene's
//! Nyquist) along the `+x` slice against the exact 1-D path, for a centred circle with `w` waves
//! of defocus, and the time of one evaluation ([`OtfPlan::otf`] + [`Otf::mean_mtf`], best of 3,
//! dev profile: opt-level 2, dependencies 3; a 2-core development machine). Produced by
//! [`convergence_table`]`(w, 0.2, &[32, 64, 128, 256, 512, 1024])` for `w = 0, 1`; regenerate it
//! with `cargo run -p optics --example fft_convergence`:
//!
//! | N | M | error, w = 0 | error, w = 1 | time per evaluation |
//! |---|---|---|---|---|
//! | 32 | 48 | 3.2e-4 | 4.3e-4 | 0.04 ms |
//! | 64 | 80 | 1.9e-4 | 2.3e-4 | 0.13 ms |
//! | 128 | 160 | 6.7e-5 | 7.9e-5 | 0.5 ms |
//! | 256 | 320 | 2.3e-5 | 2.5e-5 | 2.5 ms |
//! | 512 | 640 | 7.0e-6 | 7.9e-6 | 12 ms |
//! | 1024 | 1280 | 2.1e-6 | 2.3e-6 | 50 ms |
//!
//! Once per aperture, not per wavelength: sampling the pupil (0.5, 1.7, 6.7 ms at `N` = 128, 256,
//! 512) and creating the plan (under 1 ms). The error falls by ≈ 3.1 per doubling of `N`
//! (`N⁻² log N`, item 1 above).
//!
//! The issue's target, 1e-4 on the mean MTF of the paper scene, is met from `N = 128`.
//!
//! # Example
//! ```
//! use optics::fft::{Aberrations, Aperture, Otf, OtfPlan, SampledPupil};
//! let wavelength = 0.8e-6;
//! // a circle with half a wave of defocus: the FFT path against the exact 1-D path
//! let pupil = SampledPupil::new(128, &Aperture::circle(), &Aberrations::defocus(0.5 * wavelength))?;
//! let mut plan = OtfPlan::new(128, 0.2)?; // once per grid size, reused for every wavelength
//! let mut otf = Otf::new(); // buffer reused across evaluations
//! plan.otf(&pupil, wavelength, &mut otf);
//! assert!((otf.at(0.1, 0.3).re - optics::defocus_otf(0.1, 0.5)).abs() < 1e-3);
//! assert!((otf.mean_mtf(0.0, 0.2) - optics::fft::defocus_mean_mtf(0.5, 0.2)).abs() < 1e-4);
//! // a decentred iris: complex, direction-dependent
//! let iris = Aperture::circle().decentred(0.3, 0.0)?;
//! let lens = Aberrations { w040_m: 0.5 * wavelength, ..Aberrations::default() };
//! plan.otf(&SampledPupil::new(128, &iris, &lens)?, wavelength, &mut otf);
//! assert!(otf.at(0.1, 0.0).im.abs() > 1e-3);
//! # Ok::<(), optics::Error>(())
//! ```

mod aperture;
mod convergence;
mod plan;
mod wavefront;
mod zones;

pub use aperture::{Aperture, MASK_SUPERSAMPLING, MaskFn, ReducedCircle, reduce_decentred_circle};
pub use convergence::{convergence_table, defocus_mean_mtf};
pub use plan::{INTERPOLATION_POINTS, MAX_SAMPLES, MIN_SAMPLES, Otf, OtfPlan, SampledPupil, fast_fft_len};
pub use wavefront::{Aberrations, MAX_NOLL_INDEX, noll_to_nm};
pub use zones::{SampledZones, ZoneField};
