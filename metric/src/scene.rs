//! The scene: lens, light, camera, exposure, options — validated domain types.

use std::sync::Arc;

use optics::{Field, LensModel};
use radiometry::Spectrum;
use serde::Serialize;

use crate::Error;

fn check(name: &'static str, value: f64, ok: bool, expected: &'static str) -> Result<(), Error> {
    if value.is_finite() && ok { Ok(()) } else { Err(Error::OutOfRange { name, value, expected }) }
}

/// The camera: pixel pitch, spectral quantum efficiency, and whether the pixel-aperture MTF
/// multiplies the lens MTF.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pixel_pitch: f64,
    quantum_efficiency: Spectrum,
    pixel_mtf: bool,
    sensor: noise::Sensor,
    noise_spectrum: Option<optics::NoiseShape>,
}

impl Camera {
    /// A camera with square pixels of `pixel_pitch_m` (active area `p²`, 100 % fill factor),
    /// quantum efficiency η(λ) (values in `[0, 1]`), and the pixel-aperture MTF
    /// `|sinc(p ν)|` applied if `pixel_mtf` (docs/physics.md, "Pixel MTF": off by default, the paper uses the lens
    /// MTF only).
    pub fn new(pixel_pitch_m: f64, quantum_efficiency: Spectrum, pixel_mtf: bool) -> Result<Self, Error> {
        check("pixel_pitch", pixel_pitch_m, pixel_pitch_m > 0.0, "a finite length > 0 m")?;
        // the Nyquist frequency 1/(2p) must be finite too (p ≥ 2.8e-309 m)
        check(
            "pixel_pitch",
            pixel_pitch_m,
            (0.5 / pixel_pitch_m).is_finite(),
            "a length whose Nyquist frequency 1/(2p) is finite (≥ 2.8e-309 m)",
        )?;
        Ok(Camera {
            pixel_pitch: pixel_pitch_m,
            quantum_efficiency,
            pixel_mtf,
            sensor: noise::Sensor::ideal(),
            noise_spectrum: None,
        })
    }

    /// This camera with a sensor noise model (default: [`noise::Sensor::ideal`], shot-noise
    /// limited as the paper assumes).
    pub fn with_sensor(self, sensor: noise::Sensor) -> Self {
        Camera { sensor, ..self }
    }

    /// This camera with a non-white noise spectrum `n(ν)` (relative to the white level of
    /// SNR0): the SNR then moves inside the frequency integral of eq. 1, `ASNR = SNR0 · mean(MTF/n)`.
    pub fn with_noise_spectrum(self, noise_spectrum: optics::NoiseShape) -> Self {
        Camera { noise_spectrum: Some(noise_spectrum), ..self }
    }

    /// The non-white noise spectrum, if any (default: white).
    pub fn noise_spectrum(&self) -> Option<&optics::NoiseShape> {
        self.noise_spectrum.as_ref()
    }

    /// The sensor noise model.
    pub fn sensor(&self) -> &noise::Sensor {
        &self.sensor
    }

    /// Pixel pitch p, m.
    pub fn pixel_pitch(&self) -> f64 {
        self.pixel_pitch
    }

    /// Nyquist frequency `1/(2p)`, cycles/m.
    pub fn nyquist(&self) -> f64 {
        0.5 / self.pixel_pitch
    }

    /// Quantum efficiency η(λ).
    pub fn quantum_efficiency(&self) -> &Spectrum {
        &self.quantum_efficiency
    }

    /// Whether the pixel-aperture MTF is applied.
    pub fn pixel_mtf(&self) -> bool {
        self.pixel_mtf
    }
}

/// Which form of paper eq. 1 the `asnr` field reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MetricForm {
    /// `SNR0 × mean MTF over [0, ν_N]`: dimensionless, the SNR averaged over frequency (default).
    #[default]
    Mean,
    /// `SNR0 × ∫_0^{ν_N} MTF dν` in cycles/mm: eq. 1 as printed.
    Integral,
}

/// Which noise the zero-frequency SNR counts (paper SI, "ASNR metric that includes VG effect").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GlareMode {
    /// The paper's main analysis: signal and shot noise from the imaging order only (eq. S8–S9).
    #[default]
    FirstOrder,
    /// Noise from all transmitted light, signal from the imaging order: `SNR = S/√S_N` (eq. S14,
    /// τ1 → T in eq. S7 for `S_N`), used with the normalized MTF.
    Included,
}

/// Evaluation options.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Which form the `asnr` field reports.
    pub form: MetricForm,
    /// Geometric blur radius up to which the Fraunhofer MTF is valid, m (paper SI eq. S15: 0.25 mm).
    pub fraunhofer_threshold: f64,
    /// Largest fraction of the detected signal allowed at wavelengths blurred beyond the
    /// threshold for the result to count as valid.
    pub fraunhofer_max_fraction: f64,
    /// Pupil samples across the diameter when the FFT path is needed (16 to 4096); `None`: chosen
    /// from the tolerance.
    pub pupil_samples: Option<usize>,
    /// Whether the SNR counts the stray light of the other orders (veiling glare).
    pub glare: GlareMode,
    /// Relative error allowed in the mean MTF (the frequency integral and, on the closed-form
    /// engine, the integral that remains); spectral quadratures are exact to rounding anyway.
    pub tolerance: f64,
    /// Whether the closed-form spectral engine may be used where it applies (off: always the
    /// spectral quadrature, for cross-checks).
    pub closed_form: bool,
    /// The spectral rule where no closed form applies: product integration (default) or the
    /// per-interval panels kept as the reference.
    pub spectral_rule: optics::SpectralRule,
    /// The radial engine's rule for a pupil with a table's knots (`options.table_rule`): the
    /// tensor rule (default, good to about [`optics::radial::TENSOR_TABLE_ERROR`] relative) or
    /// the rule split at the knots (within the tolerance, at about 11× the time).
    pub table_rule: optics::radial::TableRule,
    /// Relative tolerance of the mean MTF on the FFT path: `None` follows `tolerance` (a scene
    /// that sets its tolerance asks it of every engine); the default is
    /// [`optics::DEFAULT_FFT_TOLERANCE`].
    pub fft_tolerance: Option<f64>,
    /// Whether a circular iris on a defocus-only lens goes to the exact path (default; off: the
    /// FFT path, for cross-checks): [`optics::Settings::exact_irises`].
    pub exact_irises: bool,
    /// Whether a full circular pupil with Seidel terms beyond defocus is computed by the
    /// quadrature over the pupils' overlap (default; off: the FFT path, for cross-checks):
    /// [`optics::Settings::overlap`].
    pub overlap: bool,
}

impl Options {
    /// The optics engine's settings these options ask for.
    pub fn settings(&self) -> optics::Settings {
        optics::Settings {
            pupil_samples: self.pupil_samples,
            tolerance: self.tolerance,
            closed_form: self.closed_form,
            spectral_rule: self.spectral_rule,
            fft_tolerance: self.fft_tolerance,
            exact_irises: self.exact_irises,
            overlap: self.overlap,
            spectral_tolerance: None,
            frequency_tolerance: None,
            overlap_always: false,
            edge_lane: false,
            table_rule: self.table_rule,
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            form: MetricForm::Mean,
            fraunhofer_threshold: 0.25e-3,
            fraunhofer_max_fraction: 0.01,
            pupil_samples: None,
            glare: GlareMode::FirstOrder,
            tolerance: optics::DEFAULT_TOLERANCE,
            closed_form: true,
            spectral_rule: optics::SpectralRule::Interpolated,
            table_rule: optics::radial::TableRule::Tensor,
            fft_tolerance: Some(optics::DEFAULT_FFT_TOLERANCE),
            exact_irises: true,
            overlap: true,
        }
    }
}

/// Everything the ASNR depends on.
#[derive(Clone, Debug)]
pub struct Scene {
    lens: Arc<dyn LensModel>,
    radiance: Spectrum,
    camera: Camera,
    exposure: f64,
    options: Options,
    field: Field,
    /// further weighted field points for a field-of-view average (empty: `field` alone)
    fields: Vec<(Field, f64)>,
    /// the scene's title (scene files: `title`), for reports and plots
    title: Option<String>,
    /// the fall of the irradiance with the field angle (default: none, as in the paper)
    relative_illumination: crate::RelativeIllumination,
}

impl Scene {
    /// A scene: `lens`; `radiance`, the spectral radiance of the bright target as it reaches the
    /// lens, after any filter (W/(m² sr m)); `camera`; exposure time `exposure_s`; `options`.
    pub fn new(
        lens: Arc<dyn LensModel>,
        radiance: Spectrum,
        camera: Camera,
        exposure_s: f64,
        options: Options,
    ) -> Result<Self, Error> {
        check("exposure", exposure_s, exposure_s > 0.0, "a finite time > 0 s")?;
        check_options(&options)?;
        check_light(&radiance, &camera)?;
        Ok(Scene {
            lens,
            radiance,
            camera,
            exposure: exposure_s,
            options,
            field: Field::ON_AXIS,
            fields: Vec::new(),
            title: None,
            relative_illumination: crate::RelativeIllumination::None,
        })
    }

    /// This scene with other `options` (validated as in [`new`](Self::new)).
    pub fn with_options(self, options: Options) -> Result<Self, Error> {
        check_options(&options)?;
        Ok(Scene { options, ..self })
    }

    /// This scene with another lens (the rest unchanged): e.g. a lens model written elsewhere
    /// (the Python package's `LensModel`) in a scene read from a file.
    pub fn with_lens(self, lens: Arc<dyn LensModel>) -> Self {
        Scene { lens, ..self }
    }

    /// This scene seen at the field point `field` (default: on axis).
    pub fn at_field(self, field: Field) -> Result<Self, Error> {
        for (name, v) in [("field angle x", field.x_rad), ("field angle y", field.y_rad)] {
            check(name, v, v.abs() < std::f64::consts::FRAC_PI_2, "a finite angle within ±90°")?;
        }
        Ok(Scene { field, ..self })
    }

    /// The field point.
    pub fn field(&self) -> Field {
        self.field
    }

    /// This scene with a relative illumination (docs/physics.md, "Relative illumination"): the
    /// signal of each field point times its factor (default: none, as in the paper). A table
    /// must reach every field point's angle when the scene is evaluated.
    pub fn with_relative_illumination(self, relative_illumination: crate::RelativeIllumination) -> Self {
        Scene { relative_illumination, ..self }
    }

    /// The relative illumination.
    pub fn relative_illumination(&self) -> &crate::RelativeIllumination {
        &self.relative_illumination
    }

    /// This scene averaged over weighted field points (paper SI, end of the veiling-glare
    /// section: the ASNR "as an average (or a weighted average …) over the ASNR at several
    /// locations in the FOV"). Weights are relative, ≥ 0, not all zero.
    pub fn over_fields(self, fields: Vec<(Field, f64)>) -> Result<Self, Error> {
        let mut first = None;
        for &(field, weight) in &fields {
            check("field weight", weight, weight >= 0.0, "a finite weight ≥ 0")?;
            first.get_or_insert(field);
            self.clone().at_field(field)?;
        }
        // relative weights: normalized by the largest in the average, so that subnormal weights
        // (5e-324) weigh as much as their ratios say instead of underflowing
        let largest = fields.iter().map(|f| f.1).fold(0.0, f64::max);
        check("largest field weight", largest, largest > 0.0, "at least one field with a weight > 0")?;
        let field = first.unwrap_or(Field::ON_AXIS);
        Ok(Scene { field, fields, ..self })
    }

    /// This scene at one of its (already validated) field points, without the average.
    pub(crate) fn single_field(&self, field: Field) -> Scene {
        Scene { field, fields: Vec::new(), ..self.clone() }
    }

    /// The weighted field points of a field-of-view average (empty for a single field).
    pub fn fields(&self) -> &[(Field, f64)] {
        &self.fields
    }

    /// The same scene with a title (reports and plot titles show it). An empty or blank title
    /// is no title.
    pub fn with_title(mut self, title: impl Into<String>) -> Self {
        let title = title.into();
        self.title = if title.trim().is_empty() { None } else { Some(title) };
        self
    }

    /// The scene's title, if it has one.
    pub fn title(&self) -> Option<&str> {
        self.title.as_deref()
    }

    /// The lens.
    pub fn lens(&self) -> &dyn LensModel {
        &*self.lens
    }

    /// The lens, shared.
    pub fn lens_arc(&self) -> Arc<dyn LensModel> {
        self.lens.clone()
    }

    /// Spectral radiance reaching the lens, W/(m² sr m).
    pub fn radiance(&self) -> &Spectrum {
        &self.radiance
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Exposure time, s.
    pub fn exposure(&self) -> f64 {
        self.exposure
    }

    /// The options.
    pub fn options(&self) -> &Options {
        &self.options
    }
}

/// The range `(lo, hi)` (m) outside which `spectrum` is zero, for each bounded factor of it
/// (tables, top-hats, lines), with the factor's name; unbounded factors are not listed.
fn bounded_factors(spectrum: &Spectrum, name: &'static str, out: &mut Vec<(&'static str, f64, f64)>) {
    match spectrum {
        Spectrum::Product(factors) => factors.iter().for_each(|f| bounded_factors(f, name, out)),
        other => {
            let (lo, hi) = other.support();
            if hi.is_finite() {
                out.push((name, lo, hi));
            }
        }
    }
}

/// Refuses a scene that detects no light before any optics is computed: bounded factors of the
/// radiance and of the quantum efficiency that do not overlap (paper SI eq. S8:
/// the detected spectrum is `L(λ) η(λ) λ`, zero outside the overlap), or a detected spectrum
/// that is zero everywhere (a zero quantum efficiency, radiance or filter peak).
fn check_light(radiance: &Spectrum, camera: &Camera) -> Result<(), Error> {
    let mut factors = Vec::new();
    bounded_factors(radiance, "the radiance reaching the lens (source × spectrum filter)", &mut factors);
    bounded_factors(camera.quantum_efficiency(), "the quantum efficiency (camera.quantum_efficiency)", &mut factors);
    let nm = |(name, lo, hi): (&str, f64, f64)| {
        format!("{name} covers {}–{} nm", optics::round_for_display(lo * 1e9), optics::round_for_display(hi * 1e9))
    };
    for (i, &a) in factors.iter().enumerate() {
        for &b in &factors[i + 1..] {
            if a.1.max(b.1) >= a.2.min(b.2) {
                return Err(Error::NoLight { reason: format!("{}, {}: they do not overlap", nm(a), nm(b)) });
            }
        }
    }
    let detected = crate::evaluate::detected_spectrum_of(radiance, camera);
    // a Gaussian × polynomial (the sweeps' usual spectrum) is zero everywhere only where its
    // polynomial is (a numerical integral would cost 5 % of a sweep point); else the integral
    let (none, overflows) = match detected.gaussian_polynomial() {
        Some(gp) => (gp.coefficients.iter().all(|&c| c == 0.0), gp.coefficients.iter().any(|c| !c.is_finite())),
        None => {
            let integral = detected.integral();
            // a radiance beyond f64::MAX is ∞, and ∞ × 0 (a table's zero outside its range) NaN:
            // too much light, not none
            (integral == 0.0, !integral.is_finite())
        }
    };
    if overflows {
        return Err(Error::Overflow {
            quantity: "the detected spectrum L η λ",
            detail: format!(
                "the radiance (source.radiance_w_m2_sr_nm, source.scale or the source table, times the spectrum \
                 filter) times the quantum efficiency exceeds the largest number, about {:e}: expected a radiance \
                 that a double can hold",
                f64::MAX
            ),
        });
    }
    if none {
        return Err(Error::NoLight {
            reason: "the radiance (source.radiance_w_m2_sr_nm or the source table, times the spectrum filter) \
                     times the quantum efficiency (camera.quantum_efficiency) is zero at every wavelength"
                .to_owned(),
        });
    }
    Ok(())
}

/// The checks of [`Options`] shared by [`Scene::new`] and [`Scene::with_options`].
fn check_options(options: &Options) -> Result<(), Error> {
    check(
        "fraunhofer_threshold",
        options.fraunhofer_threshold,
        options.fraunhofer_threshold > 0.0,
        "a finite length > 0 m",
    )?;
    check(
        "fraunhofer_max_fraction",
        options.fraunhofer_max_fraction,
        (0.0..=1.0).contains(&options.fraunhofer_max_fraction),
        "a fraction in [0, 1]",
    )?;
    if let Some(n) = options.pupil_samples {
        let n = n as f64;
        check("pupil_samples", n, (16.0..=4096.0).contains(&n), "a whole number from 16 to 4096")?;
    }
    let t = options.tolerance;
    check("tolerance", t, (1e-14..=0.1).contains(&t), "a relative error from 1e-14 to 0.1")?;
    Ok(())
}
