//! More than one number from the same evaluation: the noise-equivalent quanta NEQ(ν), the
//! Shannon information capacity per pixel (Fellgett–Linfoot), an ideal observer's detectability
//! d′ of a disk, and the ASNR of an ideal lens of the same aperture (docs/physics.md, "Metrics
//! beyond the ASNR").
//!
//! Frequencies inside are in cycles per pixel, `ν' = ν p`: the Nyquist square is
//! `|ν'x|, |ν'y| ≤ ½`, of area 1.
//!
//! - `NEQ(ν) = SNR0² MTF(ν)² / n(ν)²`, quanta per pixel (`/p²` per unit area), with SNR0 the
//!   evaluation's (every term of its noise budget) and `n` the camera's noise spectrum (1 when
//!   white).
//! - `C = ½ ∫∫_square log₂(1 + NEQ(ν) W(ν)) d²ν'`, bits per pixel (Fellgett & Linfoot 1955;
//!   Shannon 1948), `W` the object's power spectrum relative to its mean level squared: `c²`
//!   (flat) or `c² |ν|^−β / ⟨|ν|^−β⟩_square` (power law of the same variance).
//! - `d′² = c_t² SNR0² ∫∫_square (π R'² · 2J1(2πR'ν')/(2πR'ν'))² MTF² / n² d²ν'`, `R' = R/p`:
//!   the prewhitening matched filter of a disk of radius `R` and contrast `c_t` on the mean level
//!   (Barrett & Myers 2004, §13.2); a perfect lens gives `d′ = c_t SNR0 √(πR'²)`.
//!
//! The MTF in two dimensions: the optics' polychromatic OTF read along `|ν|` (radially symmetric
//! systems) or along each direction (`Polychromatic::otf_along`, where it depends on direction),
//! times the separable pixel MTF `|sinc(p νx) sinc(p νy)|` where the camera applies one.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::sync::Arc;

use optics::{Field, LensModel, Order, Polychromatic, Pupil, Wavefront};
use serde::Serialize;

use crate::evaluate::{Folded, detected_spectrum};
use crate::{Error, Evaluation, Scene};

/// The object's power spectrum `W(ν)` relative to its mean level squared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ObjectSpectrum {
    /// `W = c²` at every frequency: a white/black target of modulation `c`.
    Flat,
    /// `W ∝ |ν|^−β`, scaled so that its mean over the Nyquist square is `c²` (the same variance
    /// as the flat object); `0 ≤ β < 2` (the variance diverges at `ν = 0` from β = 2 on).
    PowerLaw {
        /// The exponent β of the power spectrum.
        beta: f64,
    },
}

/// A detection task: a disk on the uniform background of the scene's bright level.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DiskTask {
    /// The disk's diameter in the image plane, m.
    pub diameter_m: f64,
    /// Its contrast: the disk's signal minus the background's, over the background's (> 0).
    pub contrast: f64,
}

/// What [`metrics`] computes besides the fixed metrics.
#[derive(Clone, Debug, PartialEq)]
pub struct MetricsOptions {
    /// The object's power spectrum for the capacity.
    pub object: ObjectSpectrum,
    /// The object's contrast `c` (the modulation of a white/black target: 1).
    pub contrast: f64,
    /// A frame rate, Hz, for the capacity per second.
    pub frame_rate_hz: Option<f64>,
    /// A detection task for d′.
    pub task: Option<DiskTask>,
    /// Points of the NEQ curve from 0 to Nyquist (≥ 2).
    pub points: usize,
}

impl Default for MetricsOptions {
    fn default() -> Self {
        MetricsOptions { object: ObjectSpectrum::Flat, contrast: 1.0, frame_rate_hz: None, task: None, points: 101 }
    }
}

impl MetricsOptions {
    /// Checks every value against its physical range.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |name, value, expected| Err(Error::OutOfRange { name, value, expected });
        if !(self.contrast.is_finite() && self.contrast > 0.0) {
            return bad("contrast", self.contrast, "a finite contrast > 0 (1: a white/black target)");
        }
        if let ObjectSpectrum::PowerLaw { beta } = self.object
            && !(beta.is_finite() && (0.0..2.0).contains(&beta))
        {
            return bad(
                "power-law exponent β",
                beta,
                "0 ≤ β < 2 (the object's variance over the Nyquist square diverges from β = 2 on)",
            );
        }
        if let Some(rate) = self.frame_rate_hz
            && !(rate.is_finite() && rate > 0.0)
        {
            return bad("frame rate (Hz)", rate, "a finite rate > 0 Hz");
        }
        if let Some(task) = self.task {
            if !(task.diameter_m.is_finite() && task.diameter_m > 0.0 && task.diameter_m < 1.0) {
                return bad("disk diameter (µm)", task.diameter_m * 1e6, "a finite diameter > 0 µm and < 1 m");
            }
            if !(task.contrast.is_finite() && task.contrast > 0.0) {
                return bad("disk contrast", task.contrast, "a finite contrast > 0");
            }
        }
        if self.points < 2 || self.points > 100_000 {
            return bad("NEQ curve points", self.points as f64, "2 to 100000");
        }
        Ok(())
    }
}

/// The NEQ along one frequency axis, 0 to Nyquist.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NeqCurve {
    /// Frequencies, cycles/mm.
    pub frequency_cyc_per_mm: Vec<f64>,
    /// `NEQ(ν) = SNR0² MTF(ν)² / n(ν)²`, equivalent quanta per pixel (where the OTF depends on
    /// direction, the mean of the tangential and sagittal NEQs).
    pub neq: Vec<f64>,
}

/// The ideal observer's detectability of a disk.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Detectability {
    /// The task.
    pub task: DiskTask,
    /// `d′`, dimensionless.
    pub d_prime: f64,
    /// `d′` through a perfect lens (MTF = 1 over the Nyquist square) with the same noise.
    pub d_prime_perfect_lens: f64,
    /// The fraction of the disk's energy `∫∫|ΔS|²` inside the Nyquist square: what the sampled
    /// image can hold of it (the rest, aliased, is left out of `d′`).
    pub energy_in_band: f64,
}

/// The ASNR of a diffraction-limited lens of the same F-number and focal length with efficiency
/// 1 (τ1 = T = 1), in the same scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IdealLens {
    /// Its ASNR, in the scene's form.
    pub asnr: f64,
    /// Its mean MTF to Nyquist.
    pub mean_mtf: f64,
    /// Its SNR0.
    pub snr0: f64,
    /// The scene's ASNR over the ideal lens's: "how good is your metalens" as a fraction of what
    /// its aperture allows.
    pub ratio: f64,
}

/// The metrics of a scene beyond the ASNR (see the module docs for the definitions).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Metrics {
    /// The NEQ curve.
    pub neq: NeqCurve,
    /// `(1/ν_N) ∫_0^{ν_N} NEQ dν`, quanta per pixel.
    pub mean_neq: f64,
    /// `NEQ(0) = SNR0²`, quanta per pixel.
    pub neq_zero: f64,
    /// The object spectrum: `"flat"` or `"power-law"`.
    pub object: &'static str,
    /// Its exponent β (0 for flat).
    pub object_beta: f64,
    /// The object's contrast c.
    pub contrast: f64,
    /// Shannon information capacity, bits per pixel.
    pub capacity_bits_per_pixel: f64,
    /// Estimated error of the capacity's quadrature, bits per pixel (the difference between the
    /// last two levels of the refinement).
    pub capacity_error_bits: f64,
    /// The capacity with a perfect lens (MTF = 1) and the same noise: `½ log₂(1 + SNR0² c²)` for a
    /// flat object.
    pub capacity_perfect_lens_bits_per_pixel: f64,
    /// The frame rate, Hz, if given.
    pub frame_rate_hz: Option<f64>,
    /// `capacity_bits_per_pixel × frame rate`, bits per pixel per second.
    pub capacity_bits_per_pixel_per_second: Option<f64>,
    /// The detectability of the task, if one was given.
    pub detectability: Option<Detectability>,
    /// The ideal lens of the same aperture.
    pub ideal_lens: IdealLens,
    /// How the two-dimensional MTF was formed.
    pub mtf_2d: String,
}

/// The per-field numbers before the field average.
struct FieldMetrics {
    neq: Vec<f64>,
    mean_neq: f64,
    neq_zero: f64,
    capacity: f64,
    capacity_error: f64,
    capacity_perfect: f64,
    d2: Option<(f64, f64, f64)>,
    mtf_2d: String,
}

/// The metrics of `scene`, whose evaluation is `evaluation` ([`crate::evaluate`] of the same
/// scene), for the object, task and frame rate of `options`. Over a field-of-view average,
/// each field point's metrics are weighted as the ASNR's are (and its ideal lens evaluated the
/// same way).
pub fn metrics(scene: &Scene, evaluation: &Evaluation, options: &MetricsOptions) -> Result<Metrics, Error> {
    options.validate()?;
    let fields: Vec<(FieldMetrics, f64)> = if scene.fields().is_empty() {
        vec![(at_field(scene, evaluation.snr0, options)?, 1.0)]
    } else {
        let mut out = Vec::new();
        for &(field, weight) in scene.fields() {
            let single = scene.single_field(field);
            let e = crate::evaluate(&single)?;
            out.push((at_field(&single, e.snr0, options)?, weight));
        }
        out
    };
    let largest = fields.iter().map(|f| f.1).fold(0.0, f64::max);
    let total: f64 = fields.iter().map(|f| f.1 / largest).sum();
    let mean = |f: &dyn Fn(&FieldMetrics) -> f64| fields.iter().map(|(m, w)| w / largest * f(m)).sum::<f64>() / total;
    let nyquist = scene.camera().nyquist();
    let points = options.points;
    let frequency_cyc_per_mm = (0..points).map(|k| nyquist * 1e-3 * k as f64 / (points - 1) as f64).collect();
    let neq = (0..points).map(|k| mean(&|m| m.neq[k])).collect();
    let capacity = mean(&|m| m.capacity);
    let detectability = options.task.map(|task| Detectability {
        task,
        d_prime: mean(&|m| m.d2.map_or(0.0, |d| d.0.sqrt())),
        d_prime_perfect_lens: mean(&|m| m.d2.map_or(0.0, |d| d.1.sqrt())),
        energy_in_band: mean(&|m| m.d2.map_or(0.0, |d| d.2)),
    });
    let ideal = ideal_lens(scene, evaluation)?;
    let (object, beta) = match options.object {
        ObjectSpectrum::Flat => ("flat", 0.0),
        ObjectSpectrum::PowerLaw { beta } => ("power-law", beta),
    };
    let result = Metrics {
        neq: NeqCurve { frequency_cyc_per_mm, neq },
        mean_neq: mean(&|m| m.mean_neq),
        neq_zero: mean(&|m| m.neq_zero),
        object,
        object_beta: beta,
        contrast: options.contrast,
        capacity_bits_per_pixel: capacity,
        capacity_error_bits: mean(&|m| m.capacity_error),
        capacity_perfect_lens_bits_per_pixel: mean(&|m| m.capacity_perfect),
        frame_rate_hz: options.frame_rate_hz,
        capacity_bits_per_pixel_per_second: options.frame_rate_hz.map(|r| capacity * r),
        detectability,
        ideal_lens: ideal,
        mtf_2d: fields[0].0.mtf_2d.clone(),
    };
    let numbers = [
        ("mean_neq", result.mean_neq),
        ("capacity_bits_per_pixel", result.capacity_bits_per_pixel),
        ("capacity_perfect_lens_bits_per_pixel", result.capacity_perfect_lens_bits_per_pixel),
        ("ideal_lens.asnr", result.ideal_lens.asnr),
        ("ideal_lens.ratio", result.ideal_lens.ratio),
        ("detectability.d_prime", result.detectability.as_ref().map_or(0.0, |d| d.d_prime)),
    ];
    if let Some(&(name, value)) = numbers.iter().find(|(_, v)| !v.is_finite()) {
        return Err(Error::Overflow {
            quantity: "a metric",
            detail: format!("{name} = {value} is not a finite number for this scene"),
        });
    }
    Ok(result)
}

/// A diffraction-limited lens with efficiency 1: one order, the full pupil, no aberration.
#[derive(Debug)]
struct IdealAperture {
    f_number: f64,
    focal_length: f64,
}

impl LensModel for IdealAperture {
    fn f_number(&self) -> f64 {
        self.f_number
    }
    fn focal_length(&self) -> f64 {
        self.focal_length
    }
    fn orders(&self, _: f64, _: Field) -> Vec<Order> {
        vec![Order::new(1.0, Pupil::Full, Wavefront::default())]
    }
    fn describe(&self) -> String {
        format!("ideal lens F/{} (diffraction-limited, efficiency 1)", self.f_number)
    }
}

/// The same scene through [`IdealAperture`] of the lens's F-number and focal length.
fn ideal_lens(scene: &Scene, evaluation: &Evaluation) -> Result<IdealLens, Error> {
    let lens = scene.lens();
    let ideal = Arc::new(IdealAperture { f_number: lens.f_number(), focal_length: lens.focal_length() });
    let e = crate::evaluate(&scene.clone().with_lens(ideal))?;
    Ok(IdealLens { asnr: e.asnr, mean_mtf: e.mean_mtf, snr0: e.snr0, ratio: evaluation.asnr / e.asnr })
}

/// The metrics at the scene's single field point, with its zero-frequency SNR `snr0`.
fn at_field(scene: &Scene, snr0: f64, options: &MetricsOptions) -> Result<FieldMetrics, Error> {
    let lens = scene.lens();
    let camera = scene.camera();
    let pitch = camera.pixel_pitch();
    let detected = detected_spectrum(scene);
    let folded = Folded::of(lens, &detected);
    let parts = folded.parts();
    let field = scene.field();
    // the OTF up to the corner of the Nyquist square, √2 ν_N; the pixel MTF applied here, in 2-D
    let corner = std::f64::consts::SQRT_2 * camera.nyquist();
    let settings = scene.options().settings();
    let poly = Polychromatic::with_parts(lens, &detected, &parts, field, corner, None, settings)?;
    let directional = poly.direction_dependent();
    let cutoff = optics::highest_cutoff(lens, &detected)? * pitch;
    let noise = camera.noise_spectrum();
    let pixel = camera.pixel_mtf();
    let snr2 = snr0 * snr0;
    let along_field = field.y_rad.atan2(field.x_rad);
    // NEQ(ν') in cycles/pixel along an azimuth (the optics' OTF along it, the pixel MTF in 2-D)
    let n2 = |nu: f64| noise.map_or(1.0, |n| n.value(nu / pitch).powi(2));
    let pixel_2d = |nu: f64, theta: f64| {
        if pixel { optics::pixel_mtf(1.0, nu * theta.cos()) * optics::pixel_mtf(1.0, nu * theta.sin()) } else { 1.0 }
    };
    let optical = |nu: f64, theta: f64| {
        if directional { poly.otf_along(nu / pitch, theta).norm() } else { poly.otf(nu / pitch).abs() }
    };
    // the 1-D curve: along the field direction and across it (on axis: x and y), averaged where
    // the OTF depends on direction (the two directions a 1-D NEQ is read along; the mean MTF
    // and the MTF curve average over every azimuth instead)
    let neq_1d = |nu: f64| {
        let at = |theta: f64| {
            let m = optical(nu, theta) * pixel_2d(nu, theta);
            snr2 * m * m / n2(nu)
        };
        if directional { 0.5 * (at(along_field) + at(along_field + FRAC_PI_2)) } else { at(0.0) }
    };
    let points = options.points;
    let neq: Vec<f64> = (0..points).map(|k| neq_1d(0.5 * k as f64 / (points - 1) as f64)).collect();
    let tolerance = scene.options().tolerance.max(1e-10);
    let mean_neq = 2.0 * integrate_1d(0.0, 0.5, cutoff, tolerance, &neq_1d);

    let symmetry = match (directional, pixel) {
        (true, _) => Symmetry::HalfPlane,
        (false, true) => Symmetry::Octant,
        (false, false) => Symmetry::Radial,
    };
    let square = square_metrics(
        &|nu, theta| optical(nu, theta) * pixel_2d(nu, theta),
        noise.is_some().then_some(&n2 as &dyn Fn(f64) -> f64),
        snr0,
        pitch,
        options,
        Quadrature { symmetry, cutoff, tolerance },
    );
    let mtf_2d = match (directional, pixel) {
        (false, false) => "radial: the polychromatic OTF along |ν| (radially symmetric)",
        (false, true) => "radial OTF along |ν| times the pixel MTF |sinc(p νx) sinc(p νy)|",
        (true, false) => "the polychromatic OTF along each direction (it depends on direction)",
        (true, true) => "the polychromatic OTF along each direction times the pixel MTF |sinc(p νx) sinc(p νy)|",
    };
    Ok(FieldMetrics {
        neq,
        mean_neq,
        neq_zero: snr2 / n2(0.0),
        capacity: square.capacity_bits_per_pixel,
        capacity_error: square.capacity_error_bits,
        capacity_perfect: square.capacity_perfect_lens_bits_per_pixel,
        d2: square.detectability.map(|(d, dp, e)| (d * d, dp * dp, e)),
        mtf_2d: mtf_2d.to_owned(),
    })
}

/// How a two-dimensional integrand over the Nyquist square depends on direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symmetry {
    /// A function of `|ν|` alone.
    Radial,
    /// The square's own symmetry (a radial function times the separable pixel MTF): one
    /// octant, times 8.
    Octant,
    /// Only `f(ν) = f(−ν)` (an OTF that depends on direction): a half-plane's four octants, times 2.
    HalfPlane,
}

/// How [`square_metrics`] integrates over the Nyquist square.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadrature {
    /// How the integrand depends on direction.
    pub symmetry: Symmetry,
    /// Where the radial panels break (the incoherent cutoff), cycles/pixel; beyond the square's
    /// corner (e.g. infinity): nowhere.
    pub cutoff: f64,
    /// The relative tolerance the panels are doubled to.
    pub tolerance: f64,
}

/// The integrals over the Nyquist square behind [`Metrics`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SquareMetrics {
    /// `C = ½ ∫∫ log₂(1 + NEQ W) d²ν'`, bits per pixel.
    pub capacity_bits_per_pixel: f64,
    /// Its estimated quadrature error (the last two refinement levels' difference).
    pub capacity_error_bits: f64,
    /// The same with MTF = 1.
    pub capacity_perfect_lens_bits_per_pixel: f64,
    /// For a task: `(d′, d′ with MTF = 1, the disk's energy fraction inside the square)`.
    pub detectability: Option<(f64, f64, f64)>,
}

/// The capacity and detectability of [`MetricsOptions`] for an MTF `mtf(ν', θ)` (ν' in cycles per
/// pixel, θ the direction from the x axis, pixel MTF included), a relative noise power spectrum
/// `nps(ν')` (`n²`; `None`: white) and the zero-frequency SNR `snr0`, on pixels of pitch
/// `pixel_pitch_m` (the task's disk is given in m), integrated over the
/// Nyquist square `|ν'x|, |ν'y| ≤ ½` as `quadrature` says (its symmetry, the radial panels'
/// break at the cutoff, the relative tolerance the panels are doubled to; at a work limit, the
/// estimated error says how far it got).
pub fn square_metrics(
    mtf: &dyn Fn(f64, f64) -> f64,
    nps: Option<&dyn Fn(f64) -> f64>,
    snr0: f64,
    pixel_pitch_m: f64,
    options: &MetricsOptions,
    quadrature: Quadrature,
) -> SquareMetrics {
    let Quadrature { symmetry, cutoff, tolerance } = quadrature;
    let snr2 = snr0 * snr0;
    // W(ν') relative to the mean level squared
    let c2 = options.contrast * options.contrast;
    let scale = match options.object {
        ObjectSpectrum::Flat => c2,
        ObjectSpectrum::PowerLaw { beta } => c2 / power_law_mean(beta),
    };
    let weight = |nu: f64| match options.object {
        ObjectSpectrum::Flat => c2,
        ObjectSpectrum::PowerLaw { beta } => scale * nu.powf(-beta),
    };
    let disk = options.task.map(|t| (0.5 * t.diameter_m, t.contrast));
    let pitch = pixel_pitch_m;
    // the integrands for an MTF value m at ν': capacity, capacity with MTF = 1, d′² and d′²
    // with MTF = 1, the disk's energy fraction
    let integrands = |nu: f64, m: f64| -> [f64; 5] {
        let n2 = nps.map_or(1.0, |f| f(nu));
        let w = weight(nu);
        let capacity = 0.5 * (snr2 * m * m * w / n2).ln_1p() / std::f64::consts::LN_2;
        let capacity_perfect = 0.5 * (snr2 * w / n2).ln_1p() / std::f64::consts::LN_2;
        let (d2, d2_perfect, energy) = match disk {
            Some((radius_m, c)) => {
                // the disk's radius in pixels
                let r = radius_m / pitch;
                let s = PI * r * r * jinc(2.0 * PI * r * nu);
                let s2 = s * s;
                (c * c * snr2 * s2 * m * m / n2, c * c * snr2 * s2 / n2, s2 / (PI * r * r))
            }
            None => (0.0, 0.0, 0.0),
        };
        [capacity, capacity_perfect, d2, d2_perfect, energy]
    };
    let (values, error) = integrate_square(
        cutoff,
        tolerance,
        symmetry == Symmetry::HalfPlane,
        symmetry != Symmetry::Radial,
        &|nu, theta| integrands(nu, mtf(nu, theta)),
    );
    let capacity_perfect = match options.object {
        // exact: W and the noise are constant over the square
        ObjectSpectrum::Flat if nps.is_none() => 0.5 * (snr2 * c2).ln_1p() / std::f64::consts::LN_2,
        _ => values[1],
    };
    SquareMetrics {
        capacity_bits_per_pixel: values[0],
        capacity_error_bits: error[0],
        capacity_perfect_lens_bits_per_pixel: capacity_perfect,
        detectability: disk.map(|_| (values[2].sqrt(), values[3].sqrt(), values[4])),
    }
}

/// `2 J1(x)/x`, 1 at 0 (the Fourier transform of a disk over its area).
pub fn jinc(x: f64) -> f64 {
    if x.abs() < 1e-6 { 1.0 - x * x / 8.0 } else { 2.0 * libm::j1(x) / x }
}

/// The mean of `|ν'|^−β` over the Nyquist square `|ν'x|, |ν'y| ≤ ½` (area 1): by its eight
/// octants in polar coordinates, `8 ∫_0^{π/4} ∫_0^{a/cos θ} r^{1−β} dr dθ` with `a = ½`,
/// `= (8 a^{2−β}/(2−β)) ∫_0^{π/4} cos^{β−2}θ dθ`, the last integral (smooth) by 32-point
/// Gauss–Legendre, exact to rounding.
pub fn power_law_mean(beta: f64) -> f64 {
    let a: f64 = 0.5;
    let angular: f64 = optics::quad::gauss_legendre(32)
        .iter()
        .map(|&(x, w)| {
            let theta = FRAC_PI_4 * 0.5 * (x + 1.0);
            FRAC_PI_4 * 0.5 * w * theta.cos().powf(beta - 2.0)
        })
        .sum();
    8.0 * a.powf(2.0 - beta) / (2.0 - beta) * angular
}

/// Gauss–Legendre points per panel of the metrics' quadratures.
const POINTS: usize = 8;

/// The nodes and weights of `panels` equal panels of the [`POINTS`]-point rule on each piece of
/// `[lo, hi]` split at `breaks` (those strictly inside).
fn composite(lo: f64, hi: f64, breaks: &[f64], panels: usize) -> Vec<(f64, f64)> {
    let rule = optics::quad::gauss_legendre(POINTS);
    let mut edges = vec![lo];
    edges.extend(breaks.iter().copied().filter(|&b| b > lo && b < hi));
    edges.push(hi);
    let mut out = Vec::new();
    for piece in edges.windows(2) {
        let h = (piece[1] - piece[0]) / panels as f64;
        for p in 0..panels {
            let mid = piece[0] + h * (p as f64 + 0.5);
            out.extend(rule.iter().map(|&(x, w)| (mid + 0.5 * h * x, 0.5 * h * w)));
        }
    }
    out
}

/// `∫_lo^hi f`, the panels doubled until two levels agree to `tolerance` (relative), split at
/// `cutoff` where it falls inside.
fn integrate_1d(lo: f64, hi: f64, cutoff: f64, tolerance: f64, f: &dyn Fn(f64) -> f64) -> f64 {
    let sum = |panels| composite(lo, hi, &[cutoff], panels).iter().map(|&(x, w)| w * f(x)).sum::<f64>();
    let mut previous = sum(1);
    let mut panels = 2;
    loop {
        let current = sum(panels);
        if (current - previous).abs() <= tolerance * current.abs() || panels >= 256 {
            return current;
        }
        previous = current;
        panels *= 2;
    }
}

/// The largest number of MTF evaluations over the square a refinement level may take where the
/// OTF depends on direction (each one an OTF along a direction).
const MAX_DIRECTIONAL_EVALUATIONS: usize = 200_000;

/// `∫∫` over the Nyquist square `|ν'x|, |ν'y| ≤ ½` of the five integrands `f(|ν'|, θ)` (θ the
/// direction from the x axis), each even in ν (`f(ν) = f(−ν)`), and the estimated error of each.
///
/// The square is cut into octants, each the triangle `0 ≤ θ' ≤ π/4`, `0 ≤ r ≤ a/cos θ'` in the
/// base octant's polar coordinates (`a = ½`). Inside the inscribed circle, `r = a u²` (which
/// smooths the `r log r` of a power-law object at 0) with `u` and `θ'` on composite
/// Gauss–Legendre panels; between the circle and the square, `r = a/cos φ`, `φ ∈ [0, π/4]`, and
/// `θ' ∈ [φ, π/4]`, the corner's arc exactly (the angular measure of a circle inside a square,
/// `8 r (π/4 − arccos(a/r))`, needs no singular rule that way). The radial panels break at the
/// incoherent cutoff `cutoff` (cycles/pixel). A function of `r` alone (`angular = false`) takes
/// one node per ring, weighted by the exact arc. Where `f` depends on direction without
/// octant symmetry (`directional`), the four octants of a half-plane are summed and doubled.
/// The panels double until every integral agrees with the previous level to `tolerance`
/// (relative to the largest of it and 1e-12), or at the work limit.
fn integrate_square(
    cutoff: f64,
    tolerance: f64,
    directional: bool,
    angular: bool,
    f: &dyn Fn(f64, f64) -> [f64; 5],
) -> ([f64; 5], [f64; 5]) {
    let a = 0.5;
    let angular = angular || directional;
    let level = |panels: usize| -> [f64; 5] {
        // rings: (r, weight of the radial rule with the polar Jacobian, lowest θ')
        let mut rings = Vec::new();
        let u_break = (cutoff / a).sqrt();
        for (u, w) in composite(0.0, 1.0, &[u_break], panels) {
            let r = a * u * u;
            rings.push((r, w * 2.0 * a * u * r, 0.0));
        }
        let phi_break = if cutoff > a { (a / cutoff).min(1.0).acos() } else { 0.0 };
        for (phi, w) in composite(0.0, FRAC_PI_4, &[phi_break], panels) {
            let r = a / phi.cos();
            rings.push((r, w * a * phi.sin() / (phi.cos() * phi.cos()) * r, phi));
        }
        let mut total = [0.0; 5];
        for (r, wr, theta0) in rings {
            let mut add = |v: [f64; 5], w: f64| {
                for (t, x) in total.iter_mut().zip(v) {
                    *t += w * x;
                }
            };
            if !angular {
                // the exact arc of the octant at radius r, times the 8 octants
                add(f(r, 0.0), 8.0 * wr * (FRAC_PI_4 - theta0));
                continue;
            }
            for (t, wt) in composite(theta0, FRAC_PI_4, &[], panels) {
                if directional {
                    for theta in [t, FRAC_PI_2 - t, FRAC_PI_2 + t, PI - t] {
                        add(f(r, theta), 2.0 * wr * wt);
                    }
                } else {
                    add(f(r, t), 8.0 * wr * wt);
                }
            }
        }
        total
    };
    let evaluations = |panels: usize| {
        let rings = 4 * POINTS * panels;
        if angular { rings * POINTS * panels * if directional { 4 } else { 1 } } else { rings }
    };
    let max_panels = if directional { 64 } else { 128 };
    let mut previous = level(1);
    let mut panels = 2;
    loop {
        let current = level(panels);
        let error: Vec<f64> = current.iter().zip(&previous).map(|(c, p)| (c - p).abs()).collect();
        let converged = current.iter().zip(&error).all(|(c, e)| *e <= tolerance * c.abs().max(1e-12));
        let next = 2 * panels;
        if converged || next > max_panels || (directional && evaluations(next) > MAX_DIRECTIONAL_EVALUATIONS) {
            let mut e = [0.0; 5];
            e.copy_from_slice(&error);
            return (current, e);
        }
        previous = current;
        panels = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quadrature over the square against closed forms: the area (1), `∫∫ |ν'|²` (1/6),
    /// and a Gaussian `e^{−|ν|²/s²}` against the product of two error functions
    /// (`(s√π erf(a/s))²`), with and without the angular nodes.
    #[test]
    fn square_quadrature_closed_forms() {
        let s: f64 = 0.3;
        let gaussian_exact = (s * PI.sqrt() * libm::erf(0.5 / s)).powi(2);
        for (directional, angular) in [(false, false), (false, true), (true, true)] {
            let (v, _) = integrate_square(0.3, 1e-12, directional, angular, &|r, _| {
                [1.0, r * r, (-r * r / (s * s)).exp(), 0.0, 0.0]
            });
            assert!((v[0] - 1.0).abs() < 1e-13, "area {}", v[0]);
            assert!((v[1] - 1.0 / 6.0).abs() < 1e-13, "second moment {}", v[1]);
            assert!((v[2] - gaussian_exact).abs() < 1e-12, "{} vs {gaussian_exact}", v[2]);
        }
    }

    /// `power_law_mean` against a brute-force midpoint sum over the square (2000² cells, the
    /// singular cell at 0 aside: the rest converges to about 1e-4 relative for β = 1).
    #[test]
    fn power_law_mean_brute_force() {
        assert!((power_law_mean(0.0) - 1.0).abs() < 1e-14);
        let beta = 1.0;
        let n = 2000;
        let h = 1.0 / n as f64;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let x = -0.5 + h * (i as f64 + 0.5);
                let y = -0.5 + h * (j as f64 + 0.5);
                sum += h * h * (x * x + y * y).sqrt().powf(-beta);
            }
        }
        let exact = power_law_mean(beta);
        assert!((sum - exact).abs() < 1e-3 * exact, "{sum} vs {exact}");
    }

    /// `jinc` against its series `1 − x²/8 + x⁴/192` near 0 and the first zero of J1 (3.8317).
    #[test]
    fn jinc_values() {
        for x in [1e-3_f64, 1e-2, 0.1] {
            let series = 1.0 - x * x / 8.0 + x.powi(4) / 192.0;
            assert!((jinc(x) - series).abs() < 1e-9, "{x}");
        }
        assert!(jinc(3.831_705_970_207_512).abs() < 1e-12);
        assert_eq!(jinc(0.0), 1.0);
    }
}
