//! Evaluation of a scene: photoelectrons, SNR0, mean MTF, ASNR and the validity report.

use std::f64::consts::PI;
use std::sync::Arc;

use optics::{LensModel, Polychromatic};
use radiometry::Spectrum;
use radiometry::constants::{PLANCK, SPEED_OF_LIGHT};
use serde::Serialize;

use crate::{Error, GlareMode, MetricForm, Scene};

/// Fraunhofer validity of the result (paper SI eq. S15).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fraunhofer {
    /// Whether the detected spectrum stays inside the valid range: the fraction of the signal
    /// blurred beyond the threshold is at most the scene's allowance.
    pub valid: bool,
    /// Blur-radius threshold, mm.
    pub threshold_mm: f64,
    /// The largest wavelength shift from `reference_nm` whose blur radius stays under the
    /// threshold (eq. S15 solved for Δλ), nm; `None` if there is no reference or no shift reaches
    /// the threshold.
    pub max_shift_nm: Option<f64>,
    /// The wavelength `max_shift_nm` is measured from, nm: the design wavelength, or for a lens
    /// given as data (an OTF table, a PSF stack) without one, the mean detected wavelength
    /// (absent from the JSON when there is none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_nm: Option<f64>,
    /// For a lens given as data: the wavelengths its OTF tables cover, nm. Its blur is the one
    /// the table's OTF implies (docs/physics.md, "Fraunhofer validity"), and the light outside
    /// these wavelengths, whose blur no one gave, counts as beyond the threshold (absent from the
    /// JSON for a lens given by its formula).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table_nm: Option<[f64; 2]>,
    /// Fraction of the detected signal at wavelengths blurred beyond the threshold.
    pub fraction_outside: f64,
    /// The allowance for `fraction_outside`.
    pub max_fraction: f64,
}

/// Veiling glare estimate from spurious orders (paper SI eq. S12–S13).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Glare {
    /// Imaging efficiency τ1 averaged over the detected spectrum.
    pub efficiency: f64,
    /// Total transmission T averaged over the detected spectrum.
    pub transmission: f64,
    /// Zero-frequency modulation `M0 = τ1/T` (eq. S13).
    pub m0: f64,
    /// Veiling glare `VG = (1 − M0)/(1 + M0)` (eq. S12).
    pub vg: f64,
}

/// One field point of a field-of-view average.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FieldPoint {
    /// Field angles `(x, y)`, degrees.
    pub field_deg: [f64; 2],
    /// Relative weight.
    pub weight: f64,
    /// The relative illumination there, the factor on its signal.
    pub relative_illumination: f64,
    /// Mean MTF there.
    pub mean_mtf: f64,
    /// Tangential mean MTF there (along the field direction).
    pub mean_mtf_tangential: f64,
    /// Sagittal mean MTF there (across the field direction).
    pub mean_mtf_sagittal: f64,
    /// ASNR there.
    pub asnr: f64,
}

/// The variances (e⁻²) behind the zero-frequency SNR:
/// `SNR0 = N/√(N + N_bg + D·t + σ_r² + σ_q²/K²)` (EMVA 1288 Release 4.0 Linear, §2.3, with the
/// stray light's shot noise N_bg of paper SI eq. S14); `√N` (SI eq. S9) when only shot noise is
/// left.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseReport {
    /// The noise terms with a non-zero variance, in the order `"shot"`, `"read"`, `"dark"`,
    /// `"quantization"` (shot noise is always there when there is signal).
    pub terms: Vec<&'static str>,
    /// Whether shot noise is the only term (`SNR0 = √N`, SI eq. S9, or `N/√N_T`, eq. S14).
    pub shot_noise_limited: bool,
    /// Read noise σ_r, e⁻ rms.
    pub read_noise_e: f64,
    /// Dark charge D·t collected in the exposure, e⁻.
    pub dark_e: f64,
    /// Shot noise of the signal and of the stray light.
    pub shot_variance_e2: f64,
    /// Shot noise of the dark current.
    pub dark_variance_e2: f64,
    /// Read noise σ_r².
    pub read_variance_e2: f64,
    /// Quantization, (1/12 DN²)/K².
    pub quantization_variance_e2: f64,
    /// Their sum.
    pub total_variance_e2: f64,
    /// Whether signal + stray light + dark charge exceeded the full well (the signal was clipped).
    pub saturated: bool,
}

/// How the numbers were computed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Numerics {
    /// The OTF engine: `"exact-1d"` (centred circular pupil with defocus, docs/physics.md, "Exact defocused OTF"),
    /// `"fft: N pupil samples, padded to M"` for other pupils and wavefronts, `"closed-form …"`
    /// for the closed-form spectral integral, or `"monochromatic (line spectrum): …"` followed by
    /// one of the first two for a line spectrum (one wavelength, no spectral quadrature).
    pub engine: String,
    /// The relative tolerance of the mean MTF the engine worked to: `options.tolerance`, or
    /// on the FFT path `options.fft_tolerance` where that is larger (1e-4 by default).
    pub tolerance: f64,
    /// Evaluations of the closed-form spectral integral (closed-form engine only).
    pub closed_form_evaluations: usize,
    /// Single-wavelength OTFs summed by per-frequency product integration (exact 1-D engine).
    pub spectral_evaluations: usize,
    /// Whether a non-white noise spectrum put the SNR inside the integral.
    pub noise_spectrum: bool,
    /// Spectral quadrature panels and nodes.
    pub spectral_panels: usize,
    /// Spectral nodes (over all imaging orders).
    pub spectral_nodes: usize,
    /// Frequency panels, after splitting at sign changes of the polychromatic OTF.
    pub frequency_panels: usize,
    /// Evaluations of the polychromatic OTF.
    pub otf_evaluations: usize,
    /// Sign changes of the polychromatic OTF below Nyquist (each one a zero of the MTF).
    pub sign_changes: usize,
    /// Whether the spectral nodes are product-integration nodes (the OTF interpolated in λ,
    /// weights the moments of the detected spectrum) rather than Gauss–Legendre panels.
    pub spectral_interpolated: bool,
    /// Parts of the lens whose tables product integration folded into the detected spectrum's
    /// moments (`LensModel::factored_efficiency`, `optics::Polychromatic::with_parts`): 0 where
    /// the lens has no table to fold or the rule does not factor (the reference panels, a line,
    /// the closed form).
    pub factored_parts: usize,
}

/// The ASNR of a scene and the numbers behind it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evaluation {
    /// The ASNR in the scene's chosen form (see `form`).
    pub asnr: f64,
    /// Which form `asnr` is: `mean` (dimensionless) or `integral` (cycles/mm).
    pub form: MetricForm,
    /// `SNR0 × mean MTF` (paper eq. 1, normalized by ν_N); with a non-white noise spectrum
    /// `n(ν)`, `SNR0 × mean(MTF/n)` (the SNR inside the integral).
    pub asnr_mean: f64,
    /// `SNR0 × ∫_0^{ν_N} MTF dν`, cycles/mm (paper eq. 1 as printed).
    pub asnr_integral_cyc_per_mm: f64,
    /// Mean of the polychromatic MTF over `[0, ν_N]`. Where the OTF depends on direction (lateral
    /// colour off axis, a decentred iris, a 2-D pupil), averaged over azimuth as well.
    pub mean_mtf: f64,
    /// Tangential mean MTF, as Zemax and Code V name it: for frequencies along the field
    /// direction (in the meridional plane, the direction lateral colour smears; on axis, along
    /// the detector's x axis).
    pub mean_mtf_tangential: f64,
    /// Sagittal mean MTF: for frequencies across the field direction (on axis, along y).
    pub mean_mtf_sagittal: f64,
    /// Field angles `(x, y)`, degrees (the first point of a field-of-view average).
    pub field_deg: [f64; 2],
    /// The points of a field-of-view average, whose weighted means the fields above are (empty
    /// for a single field).
    pub field_points: Vec<FieldPoint>,
    /// `∫_0^{ν_N} MTF dν`, cycles/mm.
    pub mtf_integral_cyc_per_mm: f64,
    /// Zero-frequency SNR `N/√(total noise variance)` (EMVA 1288; the terms in `noise`): with
    /// an ideal sensor `√N` (paper SI eq. S9) with `glare = "first_order"`, `N/√N_T` (eq. S14)
    /// with `glare = "included"`.
    pub snr0: f64,
    /// Which noise `snr0` counts.
    pub glare_mode: GlareMode,
    /// Signal photoelectrons per pixel `N` (paper SI eq. S7–S8), times the relative
    /// illumination at the field point.
    pub photoelectrons: f64,
    /// The relative illumination used: which, and its factor at the field point.
    pub relative_illumination: crate::IlluminationReport,
    /// Photoelectrons per pixel from all transmitted light, imaged or stray, `N_T` (eq. S8 with
    /// τ1 → T): the shot noise of the glare-inclusive SNR.
    pub transmitted_photoelectrons: f64,
    /// The noise budget behind `snr0` (EMVA 1288 form).
    pub noise: NoiseReport,
    /// Nyquist frequency `1/(2p)`, cycles/mm.
    pub nyquist_cyc_per_mm: f64,
    /// Photoelectron-weighted mean wavelength, nm.
    pub mean_wavelength_nm: f64,
    /// Incoherent cutoff `1/(λ F#)` at the mean wavelength, cycles/mm.
    pub cutoff_cyc_per_mm: f64,
    /// Fraunhofer validity (eq. S15).
    pub fraunhofer: Fraunhofer,
    /// Veiling glare estimate (eq. S12–S13).
    pub glare: Glare,
    /// Warnings about the result's assumptions (truncated spectra, validity).
    pub warnings: Vec<String>,
    /// How it was computed.
    pub numerics: Numerics,
}

/// The note of a lens with a table's knots (`lens.phase_csv`, `lens.phase_spline_rad`, a table's
/// amplitude) on the radial engine's tensor rule at a tolerance tighter than that rule's error
/// there, [`optics::radial::TENSOR_TABLE_ERROR`] (docs/physics.md, "The radial engine"): the
/// mean MTF is then good to about that, not to the tolerance. `None` with
/// `options.table_rule = "split"` (up to [`optics::radial::SPLIT_MAX_KNOTS`] knots), at looser
/// tolerances, on the FFT and overlap engines, and for analytic profiles.
fn table_rule_note(scene: &Scene, engine: optics::Engine, mean_wavelength: f64) -> Option<String> {
    use optics::radial::{SPLIT_MAX_KNOTS, TENSOR_TABLE_ERROR, TableRule};
    let options = scene.options();
    if options.tolerance >= TENSOR_TABLE_ERROR
        || !matches!(engine, optics::Engine::Exact1d | optics::Engine::Monochromatic { .. })
    {
        return None;
    }
    let knots = scene
        .lens()
        .orders(mean_wavelength, scene.field())
        .iter()
        .filter_map(|o| match &o.pupil {
            optics::Pupil::Radial(p) => Some(p.table_knots().len()),
            _ => None,
        })
        .max()
        .filter(|&k| k > 0)?;
    if options.table_rule == TableRule::Split && knots <= SPLIT_MAX_KNOTS {
        return None;
    }
    let why = if knots <= SPLIT_MAX_KNOTS {
        "options.table_rule = \"split\" meets the tolerance at about 11× the time".to_owned()
    } else {
        format!(
            "the split rule takes tables of at most {SPLIT_MAX_KNOTS} knots inside the pupil and this one has {knots}, so the tensor rule is used whatever options.table_rule says (the error above is a 17-knot spline's; a denser table's jumps are smaller, its error not measured)"
        )
    };
    Some(format!(
        "lens.phase_csv, lens.phase_spline_rad or a table's amplitude: the radial engine's tensor rule integrates a cubic spline's profile to about {TENSOR_TABLE_ERROR:e} relative, not to the tolerance {:e} asked (its third derivative jumps at the knots); {why} (docs/physics.md, \"The radial engine\")",
        options.tolerance
    ))
}

/// Evaluates the ASNR of `scene` (paper eq. 1) at its field point (or the weighted average over
/// its field points).
///
/// - Detected spectrum before the lens: `ρ(λ) = L(λ) η(λ) λ` (radiance × QE × λ, eq. S8).
/// - Photoelectrons `N = A t π NA² /(h c) ∫ ρ(λ) τ1(λ) dλ` (eq. S7 into S8), `A = p²`,
///   `NA = 1/(2 F#)`; `SNR0 = √N` (S9) for a shot-noise limited sensor, otherwise the EMVA 1288
///   SNR of [`noise::budget`] (see [`NoiseReport`]).
/// - Mean MTF: [`optics::Polychromatic::mean_mtf`] up to `ν_N = 1/(2p)`.
pub fn evaluate(scene: &Scene) -> Result<Evaluation, Error> {
    if scene.fields().is_empty() {
        return evaluate_field(scene);
    }
    // field-of-view average: each point evaluated with its own off-axis OTF, then the
    // weighted mean of the ASNRs (and of the numbers behind them)
    let mut points = Vec::new();
    for &(field, weight) in scene.fields() {
        points.push((evaluate_field(&scene.single_field(field))?, weight));
    }
    // relative weights, divided by the largest first (exact for it, no underflow for subnormal
    // ones), then the weighted mean (paper SI, end of the veiling-glare section)
    let largest = points.iter().map(|p| p.1).fold(0.0, f64::max);
    let relative: Vec<f64> = points.iter().map(|p| p.1 / largest).collect();
    let total: f64 = relative.iter().sum();
    let mean =
        |f: &dyn Fn(&Evaluation) -> f64| points.iter().zip(&relative).map(|((e, _), w)| w * f(e)).sum::<f64>() / total;
    let mut combined = points[0].0.clone();
    combined.asnr = mean(&|e| e.asnr);
    combined.asnr_mean = mean(&|e| e.asnr_mean);
    combined.asnr_integral_cyc_per_mm = mean(&|e| e.asnr_integral_cyc_per_mm);
    combined.mean_mtf = mean(&|e| e.mean_mtf);
    combined.mean_mtf_tangential = mean(&|e| e.mean_mtf_tangential);
    combined.mean_mtf_sagittal = mean(&|e| e.mean_mtf_sagittal);
    combined.mtf_integral_cyc_per_mm = mean(&|e| e.mtf_integral_cyc_per_mm);
    combined.snr0 = mean(&|e| e.snr0);
    // the relative illumination makes the signal differ from point to point
    combined.photoelectrons = mean(&|e| e.photoelectrons);
    combined.transmitted_photoelectrons = mean(&|e| e.transmitted_photoelectrons);
    combined.relative_illumination.factor = mean(&|e| e.relative_illumination.factor);
    combined.fraunhofer.valid = points.iter().all(|(e, _)| e.fraunhofer.valid);
    combined.warnings = points.iter().flat_map(|(e, _)| e.warnings.clone()).collect();
    combined.warnings.dedup();
    combined.field_points = points
        .iter()
        .map(|(e, w)| FieldPoint {
            field_deg: e.field_deg,
            weight: *w,
            relative_illumination: e.relative_illumination.factor,
            mean_mtf: e.mean_mtf,
            mean_mtf_tangential: e.mean_mtf_tangential,
            mean_mtf_sagittal: e.mean_mtf_sagittal,
            asnr: e.asnr,
        })
        .collect();
    check_finite(&combined)?;
    Ok(combined)
}

/// The evaluation at the scene's single field point.
pub(crate) fn evaluate_field(scene: &Scene) -> Result<Evaluation, Error> {
    evaluate_field_with(scene, false).map(|(e, _)| e)
}

/// [`evaluate_field`] and, with `binary2`, the mean MTF's derivative with respect to each Binary 2
/// coefficient of the lens, computed in the same pass as the mean
/// ([`Polychromatic::mean_mtf_and_binary2_gradient`]); `None` where that does not apply (off
/// axis, a direction-dependent OTF, an engine other than the per-frequency exact one).
pub(crate) fn evaluate_field_with(scene: &Scene, binary2: bool) -> Result<(Evaluation, Option<Vec<f64>>), Error> {
    evaluate_field_differentiated(scene, binary2, &[], &[]).map(|(e, d, _, _)| (e, d))
}

/// What a library lens's parameter bias moves, on the value's own rules
/// ([`evaluate_field_differentiated`] with `bias`): one entry per parameter asked.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BiasLanes {
    /// `∂M̄/∂b`: the OTF's lane beside each value, the frequency rule's accepted weights
    /// ([`Polychromatic::mean_mtf_and_field_gradient`]).
    pub mean_mtf: Vec<f64>,
    /// `∂ln N/∂b = Σ w Σ_o ∂τ_o / Σ w Σ_o τ_o` on the nodes that make N.
    pub ln_photoelectrons: Vec<f64>,
    /// `∂ln N_T/∂b = Σ w ∂T / Σ w T` on the nodes that make N_T.
    pub ln_transmitted: Vec<f64>,
}

/// The wavefront derivatives of the mean MTF on the FFT path
/// ([`evaluate_field_differentiated`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum GridGradient {
    /// None asked.
    NotAsked,
    /// `∂M̄` along each direction asked, on the value's own FFT rules
    /// ([`optics::Polychromatic::mean_mtf_over_azimuth_and_gradient`]).
    Computed(Vec<f64>),
    /// The OTF is rotationally symmetric here (one order set of radial pupils on axis, on the
    /// radial or exact engines; or off axis where the field does not move it,
    /// [`optics::Polychromatic::field_independent`]): not computed on the grids.
    Symmetric,
    /// The OTF depends on direction but the engine gives no derivative (an order not a radial
    /// pupil on the grids, a line spectrum's grids, a noise spectrum).
    Unavailable,
}

impl GridGradient {
    /// The next lane's `∂M̄` for a key whose lane, where the grids computed lanes, is the one at
    /// `*place` (then `*place` moves past it): `Some(0)` where the OTF is rotationally symmetric
    /// (a key whose mean MTF is even about the symmetric point), `None` where the engine gives
    /// no lane (the caller refuses the key, saying why).
    pub(crate) fn next_lane(&self, place: &mut usize) -> Option<f64> {
        match self {
            GridGradient::Computed(all) => {
                let d = all[*place];
                *place += 1;
                Some(d)
            }
            GridGradient::Symmetric => Some(0.0),
            GridGradient::NotAsked | GridGradient::Unavailable => None,
        }
    }
}

/// What [`evaluate_field_differentiated`] returns: the evaluation, the mean MTF's Binary 2
/// derivatives, its derivatives on the FFT path, and a library lens's bias lanes.
pub(crate) type Differentiated = (Evaluation, Option<Vec<f64>>, GridGradient, Option<BiasLanes>);
/// The field lanes' derivatives of the engine rebuilt with the given settings, along the given
/// directions ([`refine_field_lanes`]).
type Recompute<'a> = dyn Fn(optics::Settings, &[optics::WavefrontDirection]) -> Option<Vec<f64>> + 'a;

/// The tightest tolerance [`refine_field_lanes`] runs a pass at (the rules' rounding floor).
const MIN_LANE_TOLERANCE: f64 = 1e-13;

/// The field angles' lanes of an overlap-engine or exact 1-D engine gradient held to the
/// tolerance relative to their own size (docs/physics.md, "Gradients: the field point"). Each lane is the nodes'
/// values times `−2πi ν u·∂Δ/∂θ`, at most `L` = [`optics::Polychromatic::field_lane_bound`]
/// times the value, so an error ε·M̄ of the value's spectral rule moves it by up to `L ε M̄`;
/// where that exceeds `ε |∂M̄/∂θ|` (a small gradient: on axis, or a narrow band) the spectral
/// rule is run again at the tolerance `q ε` (ε the engine's tolerance), `q = |∂M̄/∂θ|/(L M̄)` (at least 1e-4, the gradient
/// `gradient` from the value's own rules), by `again` (the engine rebuilt with that
/// `spectral_tolerance`), and the field lanes are taken from it; the value and the other lanes
/// stay the value's rules'. On the overlap engine the other rules (frequency, azimuths, each
/// node's t and x rules) already hold the lanes: tightening them changed the lanes by less than
/// 1e-9 of the norm in the cases of `report`'s `field_gradient` tests. On the exact 1-D engine
/// (`L` its nodes' largest rate, the harmonic lens's far orders included) the frequency rule
/// too, which also accepts on the value alone, runs at `q ε` (`frequency_tolerance`): on the
/// harmonic lens at 1° on a 10 nm band the spectral rule alone left 3.9e-6 of the norm, both
/// 2.9e-7 (docs/physics.md, "Gradients: the field point"); the azimuths stay the value's rule.
/// The tolerance is at least [`MIN_LANE_TOLERANCE`].
fn refine_field_lanes(
    poly: &Polychromatic,
    settings: optics::Settings,
    grid: &[optics::WavefrontDirection],
    gradient: &mut [f64],
    mean: f64,
    again: &Recompute,
) {
    let field = |d: &optics::WavefrontDirection| matches!(d, optics::WavefrontDirection::FieldAngle(_));
    let Some(bound) = poly.field_lane_bound() else { return };
    if !(grid.iter().any(field) && bound > 0.0 && mean > 0.0) {
        return;
    }
    let norm = grid.iter().zip(gradient.iter()).filter(|(d, _)| field(d)).map(|(_, g)| g * g).sum::<f64>().sqrt();
    let q = (norm / (bound * mean)).max(1e-4);
    if q >= 1.0 {
        return;
    }
    let tight = (q * poly.tolerance()).max(MIN_LANE_TOLERANCE);
    let tighter = if matches!(poly.engine(), optics::Engine::Exact1d | optics::Engine::Monochromatic { fft: None }) {
        // its frequency panels accept on the value alone too
        optics::Settings { spectral_tolerance: Some(tight), frequency_tolerance: Some(tight), ..settings }
    } else {
        optics::Settings { spectral_tolerance: Some(tight), ..settings }
    };
    let lanes: Vec<optics::WavefrontDirection> = grid.iter().copied().filter(field).collect();
    if let Some(refined) = again(tighter, &lanes) {
        let mut refined = refined.into_iter();
        for (g, d) in gradient.iter_mut().zip(grid) {
            if field(d)
                && let Some(r) = refined.next()
            {
                *g = r;
            }
        }
    }
}

/// [`evaluate_field_with`] and, for each of `grid` (wavefront directions), the mean MTF's
/// derivative on the FFT path, in the same evaluation (the value's grids, rules and
/// extrapolation; docs/physics.md, "Gradients: 2-D pupils"); and for each of `bias` (a library
/// lens's parameters, `LensModel::order_derivatives`), what its bias moves on the value's own
/// rules ([`BiasLanes`]; `None` where the engine does not give it: the caller's reference rule
/// then). The evaluation is the same, bit for bit, with or without `bias`.
pub(crate) fn evaluate_field_differentiated(
    scene: &Scene,
    binary2: bool,
    grid: &[optics::WavefrontDirection],
    bias: &[usize],
) -> Result<Differentiated, Error> {
    evaluate_field_with_lanes(scene, binary2, grid, bias, None).map(|(d, _)| d)
}

/// The defocus lane a gradient asks of the value's own pass ([`evaluate_field_with_lanes`]):
/// `∂O/∂ln K` (`rates` `None`: the F-number, the focal length, a one-order line's wavelength) or
/// the order lane of a line whose orders move each by its rates `[α_o, γ_o]`
/// ([`optics::Polychromatic::mean_mtf_and_order_lane`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DefocusLane {
    pub rates: Option<Vec<[f64; 2]>>,
}

/// What the value's pass gave for a [`DefocusLane`]: the mean with its lane
/// ([`optics::DefocusDerivative`], its mean the evaluation's bit for bit) and `P(ν_N)|O(ν_N)|`,
/// the pixel MTF times the OTF at Nyquist (the integration by parts' end term).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DefocusFound {
    pub found: optics::DefocusDerivative,
    pub edge: f64,
    /// whether the lane is the order lane (rates given), not `∂O/∂ln K`
    pub order_lane: bool,
}

/// [`evaluate_field_differentiated`] and, with `defocus`, its lane on the value's own pass
/// where the value's engine reads each OTF value from the value's own forms with the lane
/// beside it (the line engine on orders that are full centred circles with a defocus alone:
/// [`optics::Polychromatic::mean_mtf_and_order_lane`]); the evaluation is the same, bit for bit,
/// with or without it. `None` where the engine does not give it so (the caller's own pass then).
pub(crate) fn evaluate_field_with_lanes(
    scene: &Scene,
    binary2: bool,
    grid: &[optics::WavefrontDirection],
    bias: &[usize],
    defocus: Option<&DefocusLane>,
) -> Result<(Differentiated, Option<DefocusFound>), Error> {
    let mut grid_gradient = if grid.is_empty() { GridGradient::NotAsked } else { GridGradient::Unavailable };
    let lens = scene.lens();
    let camera = scene.camera();
    let detected = detected_spectrum(scene);
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let field = scene.field();
    let options = scene.options();
    // the obscuration's lane rides on the value's own FFT pass, from each grid's pupil spectrum
    // (docs/physics.md, "Gradients: the edge's motion on the FFT path"; the value unchanged)
    let settings =
        optics::Settings { edge_lane: grid.contains(&optics::WavefrontDirection::Obscuration), ..options.settings() };
    defocus_up_front(scene, &detected, nyquist)?;
    let folded = Folded::of(lens, &detected);
    let parts = folded.parts();
    let poly = Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings).map_err(|e| match e {
        // a detected integral beyond f64::MAX is too much light, not none
        optics::Error::NoSignal { total } if total == f64::INFINITY => overflow(
            "the detected spectral integral ∫ L η λ τ1 dλ",
            format!("the radiance (source.radiance_w_m2_sr_nm, source.scale or the source table) is too large: it exceeds {:e}", f64::MAX),
        ),
        // terms that overflow to ∞ − ∞: too much light or too wide a band, not none
        optics::Error::NoSignal { total } if total.is_nan() => overflow(
            "the detected spectral integral ∫ L η λ τ1 dλ",
            "its terms overflow (NaN): the spectrum (spectrum.range_nm, spectrum.center_nm or the tables) reaches too far, or the radiance is too large".to_owned(),
        ),
        optics::Error::NoSignal { total: 0.0 } => Error::NoLight {
            reason: "the lens transmits nothing into its imaging order where light is detected (lens.efficiency \
                     is zero there)"
                .to_owned(),
        },
        e => Error::Optics(e),
    })?;
    let mean_wavelength = poly.spectral_average(|lambda, _| lambda);
    if !(mean_wavelength.is_finite() && mean_wavelength > 0.0) {
        return Err(overflow(
            "the mean detected wavelength",
            format!(
                "the detected spectrum's moment ∫ L η λ² τ1 dλ is too large to represent (mean wavelength \
                 {mean_wavelength}): the spectrum (spectrum.range_nm, spectrum.center_nm or the tables) reaches \
                 wavelengths too long"
            ),
        ));
    }
    // the MTF integration resolves a bounded number of defocus waves (far beyond the Fraunhofer
    // validity of paper SI eq. S15)
    let waves = poly.max_defocus() / mean_wavelength;
    if waves.is_nan() || waves > MAX_DEFOCUS_WAVES {
        return Err(Error::Defocus {
            waves,
            w020_m: poly.max_defocus(),
            wavelength_nm: mean_wavelength * 1e9,
            limit: MAX_DEFOCUS_WAVES,
        });
    }
    // the work of the MTF integration grows as the square of the defocus phase at the frequency
    // limit, a = 8π F# ν W020 (docs/physics.md, "Exact defocused OTF"): past the budget a scene
    // would take minutes; it stops at once with the numbers instead
    let phase = 8.0 * std::f64::consts::PI * lens.f_number() * nyquist * poly.max_defocus();
    if phase.is_nan() || phase > MAX_DEFOCUS_PHASE {
        return Err(Error::DefocusPhase { phase, w020_m: poly.max_defocus(), limit: MAX_DEFOCUS_PHASE });
    }
    // on the spectral rules the work is about nodes × phase (each node's OTF at each frequency,
    // the frequencies and each OTF's cost both growing with the phase)
    if poly.engine() != optics::Engine::ClosedForm {
        let work = poly.spectral_nodes() as f64 * phase.max(1.0);
        if work > MAX_SPECTRAL_WORK {
            return Err(Error::SpectralWork {
                nodes: poly.spectral_nodes(),
                phase,
                seconds: work * SECONDS_PER_SPECTRAL_WORK,
            });
        }
    }

    let na = lens.numerical_aperture();
    let pitch = camera.pixel_pitch();
    // the relative illumination at this field point: a factor on the camera-plane irradiance
    // of eq. S7, so on the signal and on every photon's shot noise (docs/physics.md, "Relative
    // illumination")
    let illumination = scene.relative_illumination().at(field)?;
    // eq. S7–S8, N = RI p² t π NA² /(h c) ∫ ρ τ1 dλ, in the same order of operations as the
    // plain product but with the binary exponent kept aside, so that no partial product
    // overflows
    let photoelectrons = Scaled::of(pitch)
        .times(pitch)
        .times(scene.exposure())
        .times(PI)
        .times(na)
        .times(na)
        .over(PLANCK * SPEED_OF_LIGHT)
        .times(poly.total_weight())
        .value()
        * illumination;
    if !photoelectrons.is_finite() {
        return Err(overflow(
            "the photoelectrons per pixel N (paper SI eq. S7–S8)",
            format!(
                "pixel pitch {pitch:e} m (camera.pixel_pitch_um), exposure {:e} s (exposure.time_ms), NA {na:e} \
                 (lens.f_number) and the detected radiance make N exceed {:e} e⁻, more than any full well holds",
                scene.exposure(),
                f64::MAX
            ),
        ));
    }
    let integrals = folded.integrals(lens, &detected, &poly);
    // eq. S8 with τ1 → T: every photoelectron the lens transmits, imaged or stray
    let transmitted = Scaled::of(photoelectrons).over(poly.total_weight()).times(integrals.transmission).value();
    if !transmitted.is_finite() {
        return Err(overflow(
            "the transmitted photoelectrons N_T (paper SI eq. S8 with τ1 → T)",
            format!("N = {photoelectrons:e} e⁻ times T/τ1 exceeds {:e} e⁻", f64::MAX),
        ));
    }
    // stray light of the other orders adds shot noise but no signal (eq. S14: τ1 → T for the noise)
    let background = match scene.options().glare {
        GlareMode::FirstOrder => 0.0,
        GlareMode::Included => (transmitted - photoelectrons).max(0.0),
    };
    let budget = noise::budget(camera.sensor(), photoelectrons, background, scene.exposure())?;
    let snr0 = budget.snr;
    // where the OTF depends on direction, a mean along the field direction (tangential) and one
    // across it (sagittal) are reported, and the ASNR takes the mean averaged over azimuth
    // (docs/physics.md, "Pupils without rotational symmetry": the same lens turned gives the same
    // ASNR) for every such OTF: a sampled pupil's 2-D OTF, and the 1-D engines' image shifts
    // (lateral colour, a decentred iris) and T and S tables; otherwise one mean
    let along_field = field.y_rad.atan2(field.x_rad);
    let mut azimuth_warning = None;
    let mut binary2_gradient = None;
    let mut bias_gradient = None;
    let mut defocus_found = None;
    let mut directional = |noise: Option<&optics::NoiseShape>| {
        let mean_along = |azimuth: f64| match noise {
            None => poly.mean_mtf_along(azimuth),
            Some(shape) => poly.mean_mtf_over_noise(shape, azimuth),
        };
        if poly.has_pupil_grid() || poly.direction_dependent() {
            let mut a = None;
            if noise.is_none() && !grid.is_empty() {
                // a band's FFT grids, the overlap and exact 1-D engines; or a line's grids
                // (docs/physics.md, "Gradients: 2-D pupils under a line")
                let found = match poly.mean_mtf_over_azimuth_and_gradient(along_field, grid) {
                    Ok(None) => match poly.line_mean_mtf_over_azimuth_and_gradient(along_field, grid, None) {
                        // a line's several orders off axis, each turned by its own lateral colour
                        Ok(None) => Ok(poly
                            .line_field_lanes_over_azimuth(along_field, grid, None)
                            .map(|g| (poly.mean_mtf_over_azimuth(along_field, None), g))),
                        other => other,
                    },
                    other => other,
                };
                match found {
                    Ok(Some((mean, mut gradient))) => {
                        refine_field_lanes(&poly, settings, grid, &mut gradient, mean.mean, &|tighter, lanes| {
                            let refined =
                                Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, tighter)
                                    .ok()?;
                            match refined.mean_mtf_over_azimuth_and_gradient(along_field, lanes) {
                                Ok(Some(r)) => Some(r.1),
                                _ => refined.line_field_lanes_over_azimuth(along_field, lanes, None),
                            }
                        });
                        grid_gradient = GridGradient::Computed(gradient);
                        a = Some(mean);
                    }
                    Ok(None) => {}
                    Err(e) => return Err(Error::Optics(e)),
                }
            }
            let a = match a {
                Some(a) => a,
                None => poly.mean_mtf_over_azimuth(along_field, noise),
            };
            if a.change > optics::AZIMUTH_SHARE * poly.tolerance() * a.mean.abs() {
                azimuth_warning = Some(format!(
                    "the mean MTF over azimuth is not converged at {} azimuths: its last doubling changed it by {:.2e} (relative), more than the {:.1e} allowed",
                    a.azimuths,
                    a.change / a.mean.abs().max(f64::MIN_POSITIVE),
                    optics::AZIMUTH_SHARE * poly.tolerance()
                ));
            }
            Ok((a.mean, a.tangential, a.sagittal, a.work))
        } else {
            // on axis a rotationally symmetric OTF; off axis one the field does not move (every
            // order's image-shift rate zero: a refractive lens, its stop at the lens)
            if !grid.is_empty() && (field.is_on_axis() || poly.field_independent()) {
                grid_gradient = GridGradient::Symmetric;
            }
            if noise.is_none()
                && binary2
                && let Some((m, gradient, work)) = poly.mean_mtf_and_binary2_gradient()
            {
                binary2_gradient = Some(gradient);
                return Ok((m, m, m, work));
            }
            // a library lens's bias: its lanes beside the value's own OTFs, the mean unchanged
            if noise.is_none()
                && !bias.is_empty()
                && let Some((m, gradient, work)) = poly.mean_mtf_and_field_gradient(bias)
            {
                bias_gradient = Some(gradient);
                return Ok((m, m, m, work));
            }
            // a line's defocus or order lane beside the value's own OTFs (the line engine reads
            // them from the value's forms: the mean unchanged bit for bit)
            if noise.is_none()
                && let Some(lane) = defocus
                && matches!(poly.engine(), optics::Engine::Monochromatic { fft: None })
                && let Some(found) = match &lane.rates {
                    None => poly.mean_mtf_and_defocus_derivative(),
                    Some(rates) => poly.mean_mtf_and_order_lane(rates),
                }
            {
                defocus_found = Some(found);
                return Ok((found.mean, found.mean, found.mean, found.work));
            }
            let (m, work) = mean_along(0.0);
            Ok((m, m, m, work))
        }
    };
    let (mean_mtf, mean_mtf_tangential, mean_mtf_sagittal, work) = directional(None)?;
    // a non-white noise spectrum puts the SNR inside the integral (eq. 1 text): the mean of
    // MTF(ν)/n(ν), over azimuth or tangential and sagittal averaged as for the MTF
    let (weighted_mean, work) = match camera.noise_spectrum() {
        None => (mean_mtf, work),
        Some(shape) => {
            let (m, _, _, w) = directional(Some(shape))?;
            (m, add_work(work, w))
        }
    };
    if let Some(reason) = poly.over_budget() {
        return Err(Error::WorkBudget { reason });
    }
    let integral = mean_mtf * nyquist * 1e-3;
    let asnr_mean = snr0 * weighted_mean;
    let asnr_integral = snr0 * weighted_mean * nyquist * 1e-3;

    let fraunhofer = fraunhofer(scene, &poly, mean_wavelength);
    let glare = glare(&integrals);

    let mut warnings = Vec::new();
    for (what, spectrum) in [("radiance", scene.radiance()), ("quantum efficiency", camera.quantum_efficiency())] {
        for t in spectrum.truncations() {
            warnings.push(truncation_warning(what, &t));
        }
    }
    if budget.saturated {
        warnings.push(format!(
            "the pixel saturates: {:.0} e⁻ of signal, stray light and dark charge exceed the {:.0} e⁻ the sensor holds; the signal was clipped to {:.0} e⁻ and SNR0 uses it",
            budget.unclipped_signal_e + budget.background_e + budget.dark_e,
            budget.saturation_e,
            budget.signal_e
        ));
    }
    warnings.extend(azimuth_warning);
    warnings.extend(table_rule_note(scene, poly.engine(), mean_wavelength));
    if !fraunhofer.valid {
        warnings.push(format!(
            "{:.2} % of the signal is blurred beyond the Fraunhofer threshold of {} mm (paper SI eq. S15): the MTF model is not valid there",
            100.0 * fraunhofer.fraction_outside,
            fraunhofer.threshold_mm
        ));
    }
    let evaluation = Evaluation {
        asnr: match scene.options().form {
            MetricForm::Mean => asnr_mean,
            MetricForm::Integral => asnr_integral,
        },
        form: scene.options().form,
        asnr_mean,
        asnr_integral_cyc_per_mm: asnr_integral,
        mean_mtf,
        mean_mtf_tangential,
        mean_mtf_sagittal,
        field_deg: [field.x_rad.to_degrees(), field.y_rad.to_degrees()],
        field_points: Vec::new(),
        mtf_integral_cyc_per_mm: integral,
        snr0,
        glare_mode: scene.options().glare,
        photoelectrons,
        relative_illumination: crate::IlluminationReport {
            model: scene.relative_illumination().name(),
            description: scene.relative_illumination().describe(),
            factor: illumination,
        },
        transmitted_photoelectrons: transmitted,
        noise: NoiseReport {
            terms: [
                ("shot", budget.shot_variance_e2),
                ("read", budget.read_variance_e2),
                ("dark", budget.dark_variance_e2),
                ("quantization", budget.quantization_variance_e2),
            ]
            .into_iter()
            .filter_map(|(name, v)| (v > 0.0).then_some(name))
            .collect(),
            shot_noise_limited: budget.read_variance_e2 == 0.0
                && budget.dark_variance_e2 == 0.0
                && budget.quantization_variance_e2 == 0.0,
            read_noise_e: camera.sensor().read_noise_e(),
            dark_e: budget.dark_e,
            shot_variance_e2: budget.shot_variance_e2,
            dark_variance_e2: budget.dark_variance_e2,
            read_variance_e2: budget.read_variance_e2,
            quantization_variance_e2: budget.quantization_variance_e2,
            total_variance_e2: budget.total_variance_e2,
            saturated: budget.saturated,
        },
        nyquist_cyc_per_mm: nyquist * 1e-3,
        mean_wavelength_nm: mean_wavelength * 1e9,
        cutoff_cyc_per_mm: optics::cutoff_frequency(mean_wavelength, lens.f_number()) * 1e-3,
        fraunhofer,
        glare,
        warnings,
        numerics: Numerics {
            engine: match poly.engine() {
                optics::Engine::Fft { pupil_samples, padded, coarse, extrapolated } => match coarse {
                    Some(c) if extrapolated => format!(
                        "fft: {pupil_samples} pupil samples, padded to {padded} (chosen from the tolerance; \
                             Richardson with {c})"
                    ),
                    Some(c) => format!(
                        "fft: {pupil_samples} pupil samples, padded to {padded} (chosen from the tolerance; \
                             its error from the convergence of {}, {c} and {pupil_samples})",
                        c / 2
                    ),
                    None => format!("fft: {pupil_samples} pupil samples, padded to {padded}"),
                },
                optics::Engine::Monochromatic { fft: Some((pupil_samples, padded)) } => {
                    format!("monochromatic (line spectrum): fft: {pupil_samples} pupil samples, padded to {padded}")
                }
                optics::Engine::Monochromatic { fft: None } if poly.has_lateral_shifts() => {
                    "monochromatic (line spectrum): exact-1d, complex sum with lateral colour".to_owned()
                }
                optics::Engine::Monochromatic { fft: None } => "monochromatic (line spectrum): exact-1d".to_owned(),
                optics::Engine::Exact1d if poly.has_lateral_shifts() => {
                    "exact-1d, complex sum with lateral colour".to_owned()
                }
                optics::Engine::Exact1d => "exact-1d".to_owned(),
                optics::Engine::Overlap { skipped } => format!(
                    "overlap quadrature: the full pupil's polynomial wavefront (Seidel and Zernike terms) integrated over the two pupils' \
                     overlap at each frequency and azimuth (defocus exact across the lag, nested \
                     Clenshaw–Curtis along it); {skipped} lightest spectral nodes left out"
                ),
                optics::Engine::ClosedForm => {
                    "closed-form spectral integral (Gaussian spectrum, affine defocus)".to_owned()
                }
            },
            tolerance: poly.tolerance(),
            closed_form_evaluations: work.closed_form_evaluations,
            spectral_evaluations: work.spectral_evaluations,
            noise_spectrum: camera.noise_spectrum().is_some(),
            spectral_panels: work.spectral_panels,
            spectral_nodes: work.spectral_nodes,
            frequency_panels: work.frequency_panels,
            otf_evaluations: work.otf_evaluations,
            sign_changes: work.sign_changes,
            spectral_interpolated: work.spectral_interpolated,
            factored_parts: if work.spectral_interpolated { parts.len() } else { 0 },
        },
    };
    check_finite(&evaluation)?;
    // the bias's signal terms on the nodes that make N and N_T (`Folded::integrals`: the nodes
    // integrate ρ itself where the lens does not factor)
    let bias_lanes = match bias_gradient {
        Some(mean_mtf) if folded.factored.is_none() => bias_signal(lens, &poly, bias, integrals.transmission)
            .map(|(ln_photoelectrons, ln_transmitted)| BiasLanes { mean_mtf, ln_photoelectrons, ln_transmitted }),
        _ => None,
    };
    // the integration by parts' end term, after the mean so that its decisions are the value's
    let defocus_found = defocus_found.map(|found| DefocusFound {
        found,
        edge: nyquist_edge(&poly, nyquist, pixel),
        order_lane: defocus.is_some_and(|d| d.rates.is_some()),
    });
    Ok(((evaluation, binary2_gradient, grid_gradient, bias_lanes), defocus_found))
}

/// The lanes of the noise-weighted mean `G = (1/ν_N) ∫ P |O| / n dν` (with a non-white noise
/// spectrum `camera.noise_spectrum`, the mean the ASNR takes; paper eq. 1 text), on the value's
/// own rules (docs/physics.md, "Gradients under a noise spectrum"): the same engine, built from
/// the scene as [`evaluate_field_with_lanes`] builds it, and the value's noise-weighted pass with
/// each OTF's lanes divided by `n(ν)` as the value is. What the lanes of the white mean are in
/// [`Differentiated`], these are for `G`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct NoiseLanes {
    /// `G` itself, as the evaluation computes it (the weighted mean over azimuth where the OTF is
    /// 2-D, the mean along one direction where it is rotationally symmetric).
    pub mean: f64,
    /// `∂G/∂A_j` along each of the lens's wavefront directions on the radial engine
    /// ([`optics::Polychromatic::mean_mtf_over_noise_and_binary2_gradient`]), where asked and given.
    pub binary2: Option<Vec<f64>>,
    /// `∂G` along each of `grid` on the 2-D engines
    /// ([`optics::Polychromatic::mean_mtf_over_azimuth_over_noise_and_gradient`]), or
    /// [`GridGradient::Symmetric`] where the OTF is rotationally symmetric, as the white lanes'.
    pub grid: GridGradient,
}

/// [`NoiseLanes`] of the scene's single field point, along the lens's wavefront directions
/// (`binary2`) and `grid`. Where the OTF depends on direction on the exact 1-D engine (its
/// tangential and sagittal means), the grid's lanes are [`GridGradient::Unavailable`].
pub(crate) fn noise_weighted_lanes(
    scene: &Scene,
    binary2: bool,
    grid: &[optics::WavefrontDirection],
) -> Result<NoiseLanes, Error> {
    let camera = scene.camera();
    let Some(shape) = camera.noise_spectrum() else {
        return Err(Error::NotDifferentiable {
            parameter: "the noise-weighted mean MTF",
            reason: "the scene has a white noise spectrum (camera.noise_spectrum not given)".to_owned(),
        });
    };
    let lens = scene.lens();
    let detected = detected_spectrum(scene);
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let field = scene.field();
    // the value's own settings (`evaluate_field_with_lanes`)
    let settings = optics::Settings {
        edge_lane: grid.contains(&optics::WavefrontDirection::Obscuration),
        ..scene.options().settings()
    };
    let folded = Folded::of(lens, &detected);
    let parts = folded.parts();
    let poly = Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings)?;
    let along_field = field.y_rad.atan2(field.x_rad);
    let mut lanes = NoiseLanes {
        mean: f64::NAN,
        binary2: None,
        grid: if grid.is_empty() { GridGradient::NotAsked } else { GridGradient::Unavailable },
    };
    if poly.has_pupil_grid() || poly.direction_dependent() {
        // the grid's lanes, or the exact 1-D engine's (a circular iris's decentre, the field
        // angles' lateral colour), on the value's noise-weighted pass over azimuth, as the white
        // pass takes them
        let found = if grid.is_empty() {
            None
        } else {
            match poly.mean_mtf_over_azimuth_over_noise_and_gradient(along_field, grid, shape)? {
                None => match poly.line_mean_mtf_over_azimuth_and_gradient(along_field, grid, Some(shape))? {
                    // a line's several orders off axis, each turned by its own lateral colour
                    None => poly
                        .line_field_lanes_over_azimuth(along_field, grid, Some(shape))
                        .map(|g| (poly.mean_mtf_over_azimuth(along_field, Some(shape)), g)),
                    found => found,
                },
                found => found,
            }
        };
        match found {
            Some((mean, mut gradient)) => {
                refine_field_lanes(&poly, settings, grid, &mut gradient, mean.mean, &|tighter, lanes| {
                    let refined =
                        Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, tighter).ok()?;
                    match refined.mean_mtf_over_azimuth_over_noise_and_gradient(along_field, lanes, shape) {
                        Ok(Some(r)) => Some(r.1),
                        _ => refined.line_field_lanes_over_azimuth(along_field, lanes, Some(shape)),
                    }
                });
                lanes.grid = GridGradient::Computed(gradient);
                lanes.mean = mean.mean;
            }
            None if poly.has_pupil_grid() => lanes.mean = poly.mean_mtf_over_azimuth(along_field, Some(shape)).mean,
            None => {
                let (t, _) = poly.mean_mtf_over_noise(shape, along_field);
                let (s, _) = poly.mean_mtf_over_noise(shape, along_field + 0.5 * PI);
                lanes.mean = 0.5 * (t + s);
            }
        }
    } else {
        if !grid.is_empty() && (field.is_on_axis() || poly.field_independent()) {
            lanes.grid = GridGradient::Symmetric;
        }
        match binary2.then(|| poly.mean_mtf_over_noise_and_binary2_gradient(shape)).flatten() {
            Some((m, gradient, _)) => {
                lanes.mean = m;
                lanes.binary2 = Some(gradient);
            }
            None => lanes.mean = poly.mean_mtf_over_noise(shape, 0.0).0,
        }
    }
    Ok(lanes)
}

/// `P(ν_N)|O(ν_N)|`, the end term of the defocus and order lanes' integration by parts
/// ([`DefocusFound::edge`]): the pixel MTF (`pixel`, its pitch, where the camera applies it)
/// times the engine's OTF at Nyquist (a full centred pupil on axis: real and the same along
/// every direction).
pub(crate) fn nyquist_edge(poly: &Polychromatic, nyquist: f64, pixel: Option<f64>) -> f64 {
    poly.otf(nyquist).abs() * pixel.map_or(1.0, |pitch| optics::pixel_mtf(pitch, nyquist))
}

/// `(∂ln N/∂b, ∂ln N_T/∂b)` along each of `bias` on the nodes that make N and N_T (the nodes
/// integrate ρ itself: `Σ w ∂τ / Σ w τ` with `Σ w τ` the engine's total weight, and
/// `Σ w ∂T / Σ w T` with `transmission = Σ w T`, as [`Folded::integrals`] forms them); `None`
/// where the lens gives no order derivatives at a node.
fn bias_signal(
    lens: &dyn LensModel,
    poly: &Polychromatic<'_>,
    bias: &[usize],
    transmission: f64,
) -> Option<(Vec<f64>, Vec<f64>)> {
    // each node's derivatives once, in the order the nodes are read
    let mut at: Vec<Option<Vec<optics::OrderDerivatives>>> = Vec::new();
    poly.detected_integral(|lambda| {
        at.push(bias.iter().map(|&p| lens.order_derivatives(lambda, p)).collect());
        0.0
    })?;
    let at: Vec<Vec<optics::OrderDerivatives>> = at.into_iter().collect::<Option<_>>()?;
    let mut ln_n = Vec::with_capacity(bias.len());
    let mut ln_t = Vec::with_capacity(bias.len());
    for j in 0..bias.len() {
        let mut node = at.iter();
        let d_tau = poly.detected_integral(|_| node.next().map_or(f64::NAN, |d| d[j].efficiencies.iter().sum()))?;
        let mut node = at.iter();
        let d_t = poly.detected_integral(|_| node.next().map_or(f64::NAN, |d| d[j].transmission))?;
        ln_n.push(d_tau / poly.total_weight());
        ln_t.push(d_t / transmission);
    }
    Some((ln_n, ln_t))
}

/// The largest defocus, in waves at the mean wavelength, that [`evaluate`] integrates: far beyond
/// any lens the Fraunhofer model holds for (paper SI eq. S15: tens of waves at the 0.25 mm blur
/// threshold) and the stress grid's 1e4 waves at the band edges, well short of the point where
/// the phases lose their precision and the frequency integration stops converging.
pub const MAX_DEFOCUS_WAVES: f64 = 1e5;

/// The largest `spectral nodes × defocus phase at the frequency limit (rad)` that [`evaluate`]
/// integrates on the spectral rules: about 5 s on one core ([`SECONDS_PER_SPECTRAL_WORK`]).
pub const MAX_SPECTRAL_WORK: f64 = 3e6;

/// Seconds per unit of `nodes × phase` on the spectral rules, measured on the spectrometer table
/// (`examples/spectrometer.toml` at F/0.8, f0 = 6, 10 and 20 mm: 760 × 570, 1320 × 950 and
/// 2840 × 1900 took 0.59, 1.87 and 8.95 s; release, one core).
pub const SECONDS_PER_SPECTRAL_WORK: f64 = 1.7e-6;

/// The largest defocus phase at the frequency limit, `8π F# ν_N |W020|` in radians, that
/// [`evaluate`] integrates: the work grows as its square (measured on the closed form: 3.7e4 rad,
/// the paper lens designed for 10 nm, 60 s before the closed form's own budget stopped it at a
/// few seconds; 1.0e5 rad, F/0.5 with f0 = 50 mm over a 1000 nm range, 89 s). The broadest scene
/// of the paper's study, F/1.4 over 300 nm, reaches 670 rad; the stress grid's F/1 f0 = 336 mm,
/// 3.3e4 rad.
pub const MAX_DEFOCUS_PHASE: f64 = 1e5;

/// Refuses, before any spectral rule is built, a scene whose defocus phase at `max_frequency`,
/// `8π F# ν |W020|`, exceeds [`MAX_DEFOCUS_PHASE`] at every one of a few wavelengths where light
/// is detected: every spectral node then exceeds it, so the check after the rule (on
/// [`Polychromatic::max_defocus`]) would refuse it too, but only after the rule's panels,
/// which follow that phase, were built (`lens.binary2 = [1e8]` asked for 10 GB and minutes).
/// The wavelengths: a line's, each Gaussian factor's centre, and five across a bounded support
/// where the detected spectrum is not zero.
fn defocus_up_front(scene: &Scene, detected: &Spectrum, max_frequency: f64) -> Result<(), Error> {
    let lens = scene.lens();
    let mut lambdas = Vec::new();
    if let Some(line) = detected.as_line() {
        lambdas.push(line.wavelength_m);
    } else {
        lambdas.extend(detected.gaussians().iter().map(|g| g.center()));
        let (lo, hi) = detected.support();
        if hi.is_finite() {
            lambdas.extend((0..5).map(|i| lo + (hi - lo) * (i as f64 + 0.5) / 5.0));
        }
    }
    let per_w020 = 8.0 * std::f64::consts::PI * lens.f_number() * max_frequency;
    let mut least: Option<(f64, f64, f64)> = None;
    for &lambda in lambdas.iter().filter(|&&l| l > 0.0 && detected.value(l) > 0.0) {
        let orders = lens.orders(lambda, scene.field());
        let w020 = orders
            .iter()
            .filter(|o| o.efficiency > 0.0)
            .map(|o| o.wavefront.defocus_m.abs())
            .fold(0.0, |m: f64, w| if w.is_nan() { f64::NAN } else { m.max(w) });
        // the smallest over the wavelengths (NaN counts as beyond: it is refused later too)
        let phase = match per_w020 * w020 {
            p if p.is_nan() => f64::INFINITY,
            p => p,
        };
        if least.is_none_or(|(p, _, _)| phase < p) {
            least = Some((phase, w020, lambda));
        }
    }
    match least {
        // the same order of checks as after the rule: the waves first
        Some((_, w020_m, lambda)) if w020_m / lambda > MAX_DEFOCUS_WAVES => Err(Error::Defocus {
            waves: w020_m / lambda,
            w020_m,
            wavelength_nm: lambda * 1e9,
            limit: MAX_DEFOCUS_WAVES,
        }),
        Some((phase, w020_m, _)) if phase > MAX_DEFOCUS_PHASE => {
            Err(Error::DefocusPhase { phase, w020_m, limit: MAX_DEFOCUS_PHASE })
        }
        _ => Ok(()),
    }
}

fn overflow(quantity: &'static str, detail: String) -> Error {
    Error::Overflow { quantity, detail }
}

/// Every number of an evaluation is finite: a number that is not (an overflow the checks above
/// did not foresee) is an error naming it, never a NaN or an infinity in a report.
fn check_finite(e: &Evaluation) -> Result<(), Error> {
    let numbers = [
        ("asnr", e.asnr),
        ("asnr_mean", e.asnr_mean),
        ("asnr_integral_cyc_per_mm", e.asnr_integral_cyc_per_mm),
        ("mean_mtf", e.mean_mtf),
        ("mean_mtf_tangential", e.mean_mtf_tangential),
        ("mean_mtf_sagittal", e.mean_mtf_sagittal),
        ("mtf_integral_cyc_per_mm", e.mtf_integral_cyc_per_mm),
        ("snr0", e.snr0),
        ("photoelectrons", e.photoelectrons),
        ("transmitted_photoelectrons", e.transmitted_photoelectrons),
        ("noise.total_variance_e2", e.noise.total_variance_e2),
        ("nyquist_cyc_per_mm", e.nyquist_cyc_per_mm),
        ("mean_wavelength_nm", e.mean_wavelength_nm),
        ("cutoff_cyc_per_mm", e.cutoff_cyc_per_mm),
        ("fraunhofer.fraction_outside", e.fraunhofer.fraction_outside),
        ("fraunhofer.max_shift_nm", e.fraunhofer.max_shift_nm.unwrap_or(0.0)),
        ("glare.efficiency", e.glare.efficiency),
        ("glare.transmission", e.glare.transmission),
        ("glare.m0", e.glare.m0),
        ("glare.vg", e.glare.vg),
    ];
    match numbers.iter().find(|(_, v)| !v.is_finite()) {
        Some(&(name, value)) => Err(overflow(
            "a result",
            format!("{name} = {value} is not a finite number for this scene; its inputs are too large or too small"),
        )),
        None => Ok(()),
    }
}

/// A positive number as a mantissa in [0.5, 1) and a binary exponent: products and quotients
/// round exactly as the plain ones do, without overflowing or underflowing on the way.
#[derive(Clone, Copy)]
struct Scaled {
    mantissa: f64,
    exponent: i32,
}

impl Scaled {
    fn of(x: f64) -> Scaled {
        let (mantissa, exponent) = frexp(x);
        Scaled { mantissa, exponent }
    }

    fn times(self, x: f64) -> Scaled {
        let (m, e) = frexp(x);
        let (mantissa, exponent) = frexp(self.mantissa * m);
        Scaled { mantissa, exponent: self.exponent + e + exponent }
    }

    fn over(self, x: f64) -> Scaled {
        let (m, e) = frexp(x);
        let (mantissa, exponent) = frexp(self.mantissa / m);
        Scaled { mantissa, exponent: self.exponent - e + exponent }
    }

    /// The number, `inf` beyond `f64::MAX`, rounded to a subnormal or 0 below `f64::MIN_POSITIVE`.
    fn value(self) -> f64 {
        let (mut m, mut e) = (self.mantissa, self.exponent);
        while e > 1000 {
            m *= 2f64.powi(1000);
            e -= 1000;
            if m.is_infinite() {
                return m;
            }
        }
        while e < -1000 {
            m *= 2f64.powi(-1000);
            e += 1000;
        }
        m * 2f64.powi(e)
    }
}

/// `x = m 2^e` with `|m|` in [0.5, 1) for finite non-zero `x` (`(x, 0)` for 0, NaN, ±inf).
fn frexp(x: f64) -> (f64, i32) {
    if x == 0.0 || !x.is_finite() {
        return (x, 0);
    }
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    if biased == 0 {
        // subnormal: scale into the normal range first
        let (m, e) = frexp(x * 2f64.powi(64));
        return (m, e - 64);
    }
    (f64::from_bits((bits & !(0x7ff << 52)) | (1022 << 52)), biased - 1022)
}

/// The warning for a Gaussian factor of the `what` spectrum cut by the spectrum's support
/// ([`radiometry::Truncation`]): at λ ≤ 0 for a lone Gaussian, otherwise at the ends of the
/// table or band it is multiplied with, with the fraction lost on each side (docs/physics.md:
/// spectra are truncated there and the fact reported).
fn truncation_warning(what: &str, t: &radiometry::Truncation) -> String {
    let (lo, hi) = t.support_m;
    let nm = |m: f64| m * 1e9;
    let mut sides = Vec::new();
    let below = gaussian_tail_below(t.center_m, t.sigma_m, lo);
    if below > 0.0 {
        sides.push(if lo > 0.0 {
            format!("{below:.3e} below {:.1} nm", nm(lo))
        } else {
            format!("{below:.3e} at λ ≤ 0")
        });
    }
    if hi.is_finite() {
        let above = gaussian_tail_below(-t.center_m, t.sigma_m, -hi);
        if above > 0.0 {
            sides.push(format!("{above:.3e} above {:.1} nm", nm(hi)));
        }
    }
    let (cut_by, sides) = if lo <= 0.0 && hi.is_infinite() {
        ("reaches λ ≤ 0".to_owned(), String::new())
    } else {
        let range = format!("{:.1}–{:.1} nm", nm(lo), nm(hi));
        (
            format!("is cut to the {range} the {what} covers (a table or band it is multiplied with)"),
            format!(" ({})", sides.join(", ")),
        )
    };
    format!(
        "the {what}'s Gaussian factor (centre {:.1} nm, σ {:.1} nm) {cut_by}: {:.3e} of its area was cut off{sides}",
        nm(t.center_m),
        nm(t.sigma_m),
        t.fraction
    )
}

/// The fraction of a Gaussian's area (centre `center`, σ `sigma`, any sign) below `x`:
/// `½·erfc((center − x)/(σ√2))`, through [`radiometry::Gaussian::truncated_fraction`] (its
/// area at λ ≤ 0) of the Gaussian shifted by `−x`.
fn gaussian_tail_below(center: f64, sigma: f64, x: f64) -> f64 {
    let tail = |c: f64| radiometry::Gaussian::new(c, sigma, 1.0).map_or(0.5, |g| g.truncated_fraction());
    let d = center - x;
    if d >= 0.0 { tail(d) } else { 1.0 - tail(-d) }
}

/// The work of two passes over the same spectral quadrature.
fn add_work(a: optics::Work, b: optics::Work) -> optics::Work {
    optics::Work {
        frequency_panels: a.frequency_panels + b.frequency_panels,
        otf_evaluations: a.otf_evaluations + b.otf_evaluations,
        sign_changes: a.sign_changes + b.sign_changes,
        closed_form_evaluations: a.closed_form_evaluations + b.closed_form_evaluations,
        spectral_evaluations: a.spectral_evaluations + b.spectral_evaluations,
        ..a
    }
}

/// Detected spectral density before the lens: radiance × QE × λ (paper SI eq. S8 integrand
/// without τ1 and the constant factors).
pub fn detected_spectrum(scene: &Scene) -> Spectrum {
    detected_spectrum_of(scene.radiance(), scene.camera())
}

/// [`detected_spectrum`] of a radiance seen by a camera.
pub(crate) fn detected_spectrum_of(radiance: &Spectrum, camera: &crate::Camera) -> Spectrum {
    Spectrum::product(vec![radiance.clone(), camera.quantum_efficiency().clone(), Spectrum::Linear { slope: 1.0 }])
}

/// The polychromatic MTF of a scene sampled on a frequency grid, with references.
///
/// Over a field-of-view average (`[[fields]]`), every curve is the weighted mean of the field
/// points' curves, each of which is in `field_points`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MtfCurve {
    /// Frequencies, cycles/mm, from 0 to the requested maximum.
    pub frequency_cyc_per_mm: Vec<f64>,
    /// Signed polychromatic OTF of the rotationally symmetric system (image displacements
    /// ignored), before the pixel MTF.
    pub otf: Vec<f64>,
    /// Polychromatic MTF `|OTF|`, times the pixel MTF if the camera applies it; where the OTF
    /// depends on direction (off axis with lateral colour, a decentred pupil, a sampled pupil),
    /// the mean over azimuth at each frequency, as `Evaluation::mean_mtf` is ([`Self::mtf_over_azimuth`]).
    pub mtf: Vec<f64>,
    /// Aberration-free MTF of the same aperture at the mean wavelength (times the pixel MTF if
    /// applied): the diffraction limit for reference.
    pub diffraction_limited: Vec<f64>,
    /// Wavelengths of the monochromatic curves, nm.
    pub wavelengths_nm: Vec<f64>,
    /// Monochromatic MTFs, one row per wavelength (times the pixel MTF if applied).
    pub monochromatic: Vec<Vec<f64>>,
    /// Where the OTF depends on direction: the tangential MTF (Zemax and Code V's name), for
    /// frequencies along the field direction, the one lateral colour degrades (on axis, along x).
    pub mtf_tangential: Option<Vec<f64>>,
    /// Where the OTF depends on direction: the sagittal MTF, for frequencies across the field
    /// direction (on axis, along y).
    pub mtf_sagittal: Option<Vec<f64>>,
    /// Whether `mtf` (and each field point's) is the mean over azimuth of an OTF that depends
    /// on direction (a sampled pupil's 2-D OTF: a phase map, non-radial Zernike terms; the 1-D
    /// engines' image shifts: lateral colour, a decentred iris; docs/physics.md, "Pupils
    /// without rotational symmetry"), as `Evaluation::mean_mtf` is; the directional curves are
    /// then two of the azimuths it averages.
    pub mtf_over_azimuth: bool,
    /// Whether that OTF is a PSF stack's (each wavelength's whole PSF, `model = "psf"`): it
    /// names the curve's source in the reports.
    #[serde(skip)]
    pub otf_from_psf_stack: bool,
    /// Whether that OTF is a sampled pupil's 2-D OTF (the FFT path or the overlap quadrature)
    /// rather than the 1-D engines' with image shifts or tangential and sagittal tables: it
    /// names the curve's source in the reports.
    #[serde(skip)]
    pub otf_from_pupil: bool,
    /// Field angles `(x, y)`, degrees, of a single field point (the first point of a
    /// field-of-view average).
    pub field_deg: [f64; 2],
    /// The points of a field-of-view average, each with its own curves, whose weighted means the
    /// curves above are (empty for a single field).
    pub field_points: Vec<FieldCurve>,
    /// Nyquist frequency, cycles/mm.
    pub nyquist_cyc_per_mm: f64,
    /// Photoelectron-weighted mean wavelength, nm.
    pub mean_wavelength_nm: f64,
    /// Whether the pixel MTF is included.
    pub pixel_mtf: bool,
}

/// The MTF at one field point of a field-of-view average, on the frequencies of its [`MtfCurve`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FieldCurve {
    /// Field angles `(x, y)`, degrees.
    pub field_deg: [f64; 2],
    /// Relative weight.
    pub weight: f64,
    /// The MTF there (the mean over azimuth where the OTF depends on direction).
    pub mtf: Vec<f64>,
    /// The tangential MTF there, where the OTF depends on direction.
    pub mtf_tangential: Option<Vec<f64>>,
    /// The sagittal MTF there, where the OTF depends on direction.
    pub mtf_sagittal: Option<Vec<f64>>,
}

/// How far an [`MtfCurve`] extends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrequencyRange {
    /// From 0 to the camera's Nyquist frequency `1/(2p)`.
    Nyquist,
    /// From 0 to the incoherent cutoff of the shortest wavelength in the spectrum, beyond which the
    /// MTF is zero.
    Cutoff,
}

/// Samples the polychromatic MTF of `scene` at `points` equally spaced frequencies over `range`,
/// with the diffraction-limited curve at the mean wavelength and the monochromatic MTFs at
/// `wavelengths_m`. Over a field-of-view average, the curves of every field point and their
/// weighted means.
pub fn mtf_curve(
    scene: &Scene,
    range: FrequencyRange,
    points: usize,
    wavelengths_m: &[f64],
) -> Result<MtfCurve, Error> {
    curves_over_fields(scene, Sampling::Grid(range, points), wavelengths_m)
}

/// [`mtf_curve`] at the frequencies `frequencies_cyc_per_mm` (each finite and ≥ 0, in any order)
/// instead of a grid: the same curves, computed the same way (the Python package's `asnr.mtf`).
pub fn mtf_at(scene: &Scene, frequencies_cyc_per_mm: &[f64], wavelengths_m: &[f64]) -> Result<MtfCurve, Error> {
    if let Some(&bad) = frequencies_cyc_per_mm.iter().find(|f| !(f.is_finite() && **f >= 0.0)) {
        return Err(Error::OutOfRange {
            name: "frequency (cycles/mm)",
            value: bad,
            expected: "finite frequencies ≥ 0",
        });
    }
    curves_over_fields(scene, Sampling::Given(frequencies_cyc_per_mm), wavelengths_m)
}

/// Where an [`MtfCurve`] is sampled.
#[derive(Clone, Copy, Debug)]
enum Sampling<'a> {
    /// `points` equally spaced frequencies over a range.
    Grid(FrequencyRange, usize),
    /// These frequencies, cycles/mm.
    Given(&'a [f64]),
}

/// The curves of [`mtf_curve`] sampled as `sampling` says, averaged over the scene's fields.
fn curves_over_fields(scene: &Scene, sampling: Sampling<'_>, wavelengths_m: &[f64]) -> Result<MtfCurve, Error> {
    if scene.fields().is_empty() {
        return mtf_curve_at_field(scene, sampling, wavelengths_m);
    }
    let mut curves = Vec::new();
    for &(field, weight) in scene.fields() {
        curves.push((mtf_curve_at_field(&scene.single_field(field), sampling, wavelengths_m)?, weight));
    }
    let total: f64 = curves.iter().map(|c| c.1).sum();
    let mean = |f: &dyn Fn(&MtfCurve) -> &Vec<f64>| -> Vec<f64> {
        let mut out = vec![0.0; curves[0].0.frequency_cyc_per_mm.len()];
        for (c, w) in &curves {
            for (o, v) in out.iter_mut().zip(f(c)) {
                *o += w * v / total;
            }
        }
        out
    };
    let split = curves.iter().any(|(c, _)| c.mtf_tangential.is_some());
    let mut combined = curves[0].0.clone();
    combined.otf = mean(&|c| &c.otf);
    combined.mtf = mean(&|c| &c.mtf);
    combined.monochromatic = (0..wavelengths_m.len()).map(|i| mean(&|c| &c.monochromatic[i])).collect();
    // a field point whose OTF does not depend on direction has tangential = sagittal = mtf
    combined.mtf_tangential = split.then(|| mean(&|c| c.mtf_tangential.as_ref().unwrap_or(&c.mtf)));
    combined.mtf_sagittal = split.then(|| mean(&|c| c.mtf_sagittal.as_ref().unwrap_or(&c.mtf)));
    combined.mtf_over_azimuth = curves.iter().any(|(c, _)| c.mtf_over_azimuth);
    combined.otf_from_psf_stack = curves.iter().any(|(c, _)| c.otf_from_psf_stack);
    combined.otf_from_pupil = curves.iter().any(|(c, _)| c.otf_from_pupil);
    combined.field_points = curves
        .into_iter()
        .map(|(c, weight)| FieldCurve {
            field_deg: c.field_deg,
            weight,
            mtf: c.mtf,
            mtf_tangential: c.mtf_tangential,
            mtf_sagittal: c.mtf_sagittal,
        })
        .collect();
    Ok(combined)
}

/// The curves at the scene's single field point.
fn mtf_curve_at_field(scene: &Scene, sampling: Sampling<'_>, wavelengths_m: &[f64]) -> Result<MtfCurve, Error> {
    let lens = scene.lens();
    let camera = scene.camera();
    let detected = detected_spectrum(scene);
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let max_frequency = match sampling {
        Sampling::Grid(FrequencyRange::Nyquist, _) => camera.nyquist(),
        Sampling::Grid(FrequencyRange::Cutoff, _) => match optics::highest_cutoff(lens, &detected)? {
            c if c.is_finite() => c,
            // a band that reaches λ = 0: the cutoff 1/(λ F#) has no end
            _ => {
                return Err(overflow(
                    "the incoherent cutoff 1/(λ F#) of the shortest detected wavelength",
                    "the detected spectrum reaches λ = 0 nm (spectrum.range_nm, spectrum.center_nm or the tables): stop the axis at Nyquist, or keep the band above 0 nm".to_owned(),
                ));
            }
        },
        // the engines are prepared up to the highest frequency asked (at least Nyquist)
        Sampling::Given(given) => given.iter().fold(camera.nyquist(), |m, f| m.max(f * 1e3)),
    };
    let field = scene.field();
    let options = scene.options();
    let settings = options.settings();
    // the budget of `evaluate`, at Nyquist: an axis to the cutoff costs more, but is not refused
    // where the mean MTF is computed
    defocus_up_front(scene, &detected, camera.nyquist())?;
    let folded = Folded::of(lens, &detected);
    let parts = folded.parts();
    let poly = Polychromatic::with_parts(lens, &detected, &parts, field, max_frequency, pixel, settings)?;
    let mean_wavelength = poly.spectral_average(|lambda, _| lambda);
    let frequencies: Vec<f64> = match sampling {
        Sampling::Grid(_, points) => {
            let points = points.max(2);
            (0..points).map(|k| max_frequency * k as f64 / (points - 1) as f64).collect()
        }
        Sampling::Given(given) => given.iter().map(|f| f * 1e3).collect(),
    };
    let pixel_factor = |nu: f64| pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu));
    let otf: Vec<f64> = frequencies.iter().map(|&nu| poly.otf(nu)).collect();
    let mtf = frequencies.iter().zip(&otf).map(|(&nu, o)| o.abs() * pixel_factor(nu)).collect();
    let diffraction_limited = frequencies
        .iter()
        .map(|&nu| optics::mtf_diffraction_limited(nu * mean_wavelength * lens.f_number()) * pixel_factor(nu))
        .collect();
    let along_field = field.y_rad.atan2(field.x_rad);
    let along = |azimuth: f64| -> Vec<f64> { frequencies.iter().map(|&nu| poly.mtf_along(nu, azimuth)).collect() };
    let (mtf_tangential, mtf_sagittal) = if poly.direction_dependent() {
        (Some(along(along_field)), Some(along(along_field + 0.5 * PI)))
    } else {
        (None, None)
    };
    // where the OTF depends on direction the headline curve is, as `mean_mtf` is, the average
    // over azimuth
    let mtf_over_azimuth = poly.has_pupil_grid() || poly.direction_dependent();
    let mtf = if mtf_over_azimuth {
        frequencies.iter().map(|&nu| poly.mtf_over_azimuth(nu, along_field)).collect()
    } else {
        mtf
    };
    let monochromatic = wavelengths_m
        .iter()
        .map(|&l| {
            let mtf = optics::monochromatic_mtf(
                lens,
                l,
                field,
                &frequencies,
                options.pupil_samples.unwrap_or(optics::DEFAULT_PUPIL_SAMPLES),
            )?;
            Ok(mtf.iter().zip(&frequencies).map(|(m, &nu)| m * pixel_factor(nu)).collect())
        })
        .collect::<Result<Vec<Vec<f64>>, Error>>()?;
    Ok(MtfCurve {
        frequency_cyc_per_mm: frequencies.iter().map(|nu| nu * 1e-3).collect(),
        otf,
        mtf,
        diffraction_limited,
        wavelengths_nm: wavelengths_m.iter().map(|l| optics::round_for_display(l * 1e9)).collect(),
        monochromatic,
        mtf_tangential,
        mtf_sagittal,
        mtf_over_azimuth,
        otf_from_psf_stack: poly.has_psf_planes(),
        otf_from_pupil: poly.has_pupil_grid(),
        field_deg: [field.x_rad.to_degrees(), field.y_rad.to_degrees()],
        field_points: Vec::new(),
        nyquist_cyc_per_mm: camera.nyquist() * 1e-3,
        mean_wavelength_nm: mean_wavelength * 1e9,
        pixel_mtf: pixel.is_some(),
    })
}

/// The Fraunhofer check (paper SI eq. S15) of `scene` whose detected mean wavelength is
/// `mean_wavelength` (m): the fraction of the signal blurred beyond the threshold, and the largest
/// shift from the reference wavelength that stays within it. A lens given as data (tabulated
/// orders) blurs as its tables imply and is not known outside them
/// ([`optics::fraunhofer::table_blur_radius`]).
fn fraunhofer(scene: &Scene, poly: &Polychromatic<'_>, mean_wavelength: f64) -> Fraunhofer {
    let options = scene.options();
    let threshold = options.fraunhofer_threshold;
    let table = optics::fraunhofer::table_range(scene.lens(), mean_wavelength, scene.field());
    let reference = scene.lens().design_wavelength().or(table.map(|_| mean_wavelength));
    let max_shift = reference.and_then(|l0| optics::fraunhofer::max_wavelength_shift(scene.lens(), l0, threshold));
    // a fraction ≥ 0: the rounding of 1 − inside/total (a one-slice PSF stack under a line gave
    // −1e-16, printed "-0.000 %"); + 0.0 turns −0 into 0
    let fraction_outside = poly.fraction_blurred_beyond(threshold).max(0.0) + 0.0;
    Fraunhofer {
        valid: fraction_outside <= options.fraunhofer_max_fraction,
        threshold_mm: threshold * 1e3,
        max_shift_nm: max_shift.map(|s| s * 1e9),
        reference_nm: reference.map(|l| l * 1e9),
        table_nm: table.map(|(lo, hi)| [lo * 1e9, hi * 1e9]),
        fraction_outside,
        max_fraction: options.fraunhofer_max_fraction,
    }
}

/// The lens and the detected spectrum as the optics integrate them: where the lens has
/// efficiency or transmission tables ([`optics::FactoredEfficiency`]), each part's table folded
/// into the detected spectrum, handed to the optics as that part's spectrum beside its relative
/// orders ([`optics::Part`]), so that the rows cost what a spectrum table's do (exact moments,
/// no spectral panel cut at each row); otherwise no parts.
pub(crate) struct Folded {
    factored: Option<Factored>,
}

struct Factored {
    /// the lens's total transmission as a spectrum factor
    transmission: Spectrum,
    /// each part's relative lens and `ρ t_p`
    parts: Vec<(Arc<dyn LensModel>, Spectrum)>,
}

/// `∫ ρ dλ`, `∫ ρ τ1 dλ` and `∫ ρ T dλ` over the detected spectrum ρ (before the lens; paper SI
/// eq. S8, S13), in its units.
struct SignalIntegrals {
    detected: f64,
    efficiency: f64,
    transmission: f64,
}

impl Folded {
    pub(crate) fn of(lens: &dyn LensModel, detected: &Spectrum) -> Folded {
        Folded {
            factored: lens.factored_efficiency().map(|f| Factored {
                transmission: f.transmission,
                parts: f
                    .parts
                    .into_iter()
                    .map(|p| (p.relative, Spectrum::product(vec![detected.clone(), p.table])))
                    .collect(),
            }),
        }
    }

    /// The parts to hand to the optics (none without tables).
    pub(crate) fn parts(&self) -> Vec<optics::Part<'_>> {
        self.factored.as_ref().map_or_else(Vec::new, |f| {
            f.parts.iter().map(|(lens, detected)| optics::Part { lens: &**lens, detected }).collect()
        })
    }

    /// The signal integrals: by the optics' spectral nodes (weights `ρ`), or, with the tables
    /// folded, `∫ ρ τ1 = Σ_p ∫ ρ t_p r_p`, the nodes' total weight, and `∫ ρ`, `∫ ρ T` exactly
    /// from the spectra (radiometry's `Spectrum::integral`).
    fn integrals(&self, lens: &dyn LensModel, detected: &Spectrum, poly: &Polychromatic<'_>) -> SignalIntegrals {
        match &self.factored {
            None => {
                // (without parts the nodes integrate ρ itself: `detected_integrals` is `Some`;
                // the three in one pass over the nodes, each the sum `detected_integral` takes)
                let [detected, efficiency, transmission] = poly
                    .detected_integrals(|l| [1.0, lens.efficiency(l), lens.transmission(l)])
                    .unwrap_or([f64::NAN; 3]);
                SignalIntegrals { detected, efficiency, transmission }
            }
            Some(f) => SignalIntegrals {
                detected: detected.integral(),
                efficiency: poly.total_weight(),
                transmission: Spectrum::product(vec![detected.clone(), f.transmission.clone()]).integral(),
            },
        }
    }
}

fn glare(integrals: &SignalIntegrals) -> Glare {
    let detected = integrals.detected;
    let efficiency = integrals.efficiency / detected;
    let transmission = integrals.transmission / detected;
    let m0 = noise::buralli_morris_modulation(efficiency, transmission);
    Glare { efficiency, transmission, m0, vg: noise::glare_from_modulation(m0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Gaussian cut by a table names the table's range and each side's loss; a lone Gaussian
    /// reaching λ ≤ 0 says so (½·erfc(2/√2) = Φ(−2) = 0.02275 for a centre 2σ from 0).
    #[test]
    fn truncation_warning_says_what_cut_the_gaussian() {
        let cut =
            radiometry::Truncation { center_m: 540e-9, sigma_m: 50e-9, fraction: 0.2, support_m: (490e-9, 640e-9) };
        let w = truncation_warning("radiance", &cut);
        // 1σ below (Φ(−1) = 0.15866), 2σ above (Φ(−2) = 0.02275)
        assert!(w.contains("cut to the 490.0–640.0 nm the radiance covers"), "{w}");
        assert!(w.contains("(1.587e-1 below 490.0 nm, 2.275e-2 above 640.0 nm)") && !w.contains("λ ≤ 0"), "{w}");
        let zero = radiometry::Truncation {
            center_m: 40e-9,
            sigma_m: 20e-9,
            fraction: 0.02275,
            support_m: (0.0, f64::INFINITY),
        };
        let w = truncation_warning("quantum efficiency", &zero);
        assert!(w.contains("the quantum efficiency's Gaussian factor") && w.contains("reaches λ ≤ 0: 2.275e-2"), "{w}");
        assert!((gaussian_tail_below(1.0, 1.0, 1.0) - 0.5).abs() < 1e-15);
        assert!((gaussian_tail_below(0.0, 1.0, 1.0) - 0.841_344_746_068_542_9).abs() < 1e-12);
    }
}
