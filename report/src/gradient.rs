//! `asnr gradient`: the exact gradient of the ASNR, mean MTF, SNR0 and photoelectrons with respect
//! to scene keys (docs/physics.md, "Gradients").
//!
//! The keys are read, checked and spelled here (`lens.binary2[3]`: 0-based, no leading zeros;
//! `lens.binary2` means every entry); the derivatives come from the engines
//! ([`metric::gradient`]), each key mapped to the scene quantity it sets. A key the value does
//! not depend on smoothly, or whose derivative the engines do not compute yet, is refused naming
//! it: never a finite difference in its place.

use anyhow::{Context, Result, anyhow, bail};
use serde::Serialize;
use serde::ser::{SerializeMap, SerializeStruct, Serializer};

use metric::Parameter;
use scene::Source;

mod achromat;
mod multiplexed;

/// The gradient at one scene: its keys in their canonical spelling, their values, the value of
/// the ASNR, mean MTF, SNR0 and photoelectrons there, and the derivative of each with respect to
/// each key, in the key's own units (per ms for `exposure.time_ms`, per µm for
/// `camera.pixel_pitch_um`, …).
///
/// Serialized as `asnr gradient --json` prints it: `asnr`, `mean_mtf`, `snr0`,
/// `photoelectrons`, then `gradient`, `mean_mtf_gradient`, `snr0_gradient` and
/// `photoelectrons_gradient`, each an object `{KEY: derivative}` in the order of `keys`.
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// The keys, canonical spelling.
    pub keys: Vec<String>,
    /// Their values in the scene.
    pub values: Vec<f64>,
    /// The ASNR (in the scene's form).
    pub asnr: f64,
    /// The mean MTF.
    pub mean_mtf: f64,
    /// The zero-frequency SNR.
    pub snr0: f64,
    /// Signal photoelectrons per pixel.
    pub photoelectrons: f64,
    /// `∂ASNR/∂key`.
    pub d_asnr: Vec<f64>,
    /// `∂ mean MTF/∂key`.
    pub d_mean_mtf: Vec<f64>,
    /// `∂SNR0/∂key`.
    pub d_snr0: Vec<f64>,
    /// `∂N/∂key`.
    pub d_photoelectrons: Vec<f64>,
}

impl Gradient {
    /// The gradient of `evaluation`'s ASNR, mean MTF, SNR0 and photoelectrons with respect to the
    /// `expanded` keys (each with its value), from the four columns of derivatives in that order.
    fn of(expanded: &[(String, f64)], evaluation: &metric::Evaluation, columns: [Vec<f64>; 4]) -> Gradient {
        let [d_asnr, d_mean_mtf, d_snr0, d_photoelectrons] = columns;
        Gradient {
            keys: expanded.iter().map(|(k, _)| k.clone()).collect(),
            values: expanded.iter().map(|(_, v)| *v).collect(),
            asnr: evaluation.asnr,
            mean_mtf: evaluation.mean_mtf,
            snr0: evaluation.snr0,
            photoelectrons: evaluation.photoelectrons,
            d_asnr,
            d_mean_mtf,
            d_snr0,
            d_photoelectrons,
        }
    }

    /// The relative sensitivity `∂ln ASNR/∂ln key = (∂ASNR/∂key)·key/ASNR` of key `i`.
    pub fn relative(&self, i: usize) -> f64 {
        self.d_asnr[i] * self.values[i] / self.asnr
    }
}

/// `{KEY: value}` in the order of the keys.
struct ByKey<'a>(&'a [String], &'a [f64]);

impl Serialize for ByKey<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (k, v) in self.0.iter().zip(self.1) {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

impl Serialize for Gradient {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut s = serializer.serialize_struct("Gradient", 8)?;
        s.serialize_field("asnr", &self.asnr)?;
        s.serialize_field("mean_mtf", &self.mean_mtf)?;
        s.serialize_field("snr0", &self.snr0)?;
        s.serialize_field("photoelectrons", &self.photoelectrons)?;
        s.serialize_field("gradient", &ByKey(&self.keys, &self.d_asnr))?;
        s.serialize_field("mean_mtf_gradient", &ByKey(&self.keys, &self.d_mean_mtf))?;
        s.serialize_field("snr0_gradient", &ByKey(&self.keys, &self.d_snr0))?;
        s.serialize_field("photoelectrons_gradient", &ByKey(&self.keys, &self.d_photoelectrons))?;
        s.end()
    }
}

/// The keys whose derivative the engines compute, the scene quantity each sets, and whether the
/// quantity's derivative is taken per relative change (`∂/∂ln`, so `∂/∂key = (∂/∂ln)/key`).
const SUPPORTED: [(&str, Parameter); 10] = [
    ("exposure.time_ms", Parameter::Exposure),
    ("source.radiance_w_m2_sr_nm", Parameter::SignalScale),
    ("source.scale", Parameter::SignalScale),
    ("camera.quantum_efficiency", Parameter::SignalScale),
    ("spectrum.peak", Parameter::SignalScale),
    ("lens.efficiency", Parameter::Efficiency),
    ("lens.transmission", Parameter::Transmission),
    ("camera.read_noise_e", Parameter::ReadNoise),
    ("camera.dark_current_e_per_s", Parameter::DarkCurrent),
    ("camera.gain_dn_per_e", Parameter::Gain),
];

/// A blackbody source's temperature (Planck's ∂B/∂T): under a line and over a band (docs/physics.md,
/// "Gradients: a line's wavelength and a blackbody's temperature").
const TEMPERATURE: &str = "source.temperature_k";

/// The pixel pitch, kept apart: its derivative also moves the Nyquist frequency.
const PIXEL_PITCH: &str = "camera.pixel_pitch_um";

/// The lens families whose `efficiency` and `transmission` are one factor on the imaging orders
/// and on the transmitted light at every wavelength, so that they leave the OTF as it is: one
/// order (chromatic, phase, a PSF stack's one tabulated order), or the harmonic lens's orders
/// `τ_m = τ_base sinc²(α − m)`, every one proportional to `efficiency = τ_base` (no relative
/// weight between orders moves), or the dispersion-engineered lens's one order, τ inside its
/// design band and 0 outside (a factor on the signal alone; docs/physics.md, "Gradients: the
/// dispersion-engineered lens").
const SCALAR_EFFICIENCY_MODELS: [&str; 5] = ["chromatic", "phase", "harmonic", "psf", "dispersion-engineered"];

/// Keys the value does not depend on smoothly: integers, switches, seeds and limits.
const NOT_SMOOTH: [(&str, &str); 8] = [
    ("design_order", "an integer (the design's diffraction order)"),
    ("diffraction_order", "an integer (the diffraction order)"),
    ("adc_bits", "an integer (the ADC's resolution)"),
    ("pupil_samples", "an integer (the FFT path's sampling)"),
    ("seed", "a random seed"),
    ("elements", "an integer (a number of elements)"),
    ("full_well_e", "a limit: the value does not depend on it until the pixel saturates, where it has a kink"),
    ("black_level_dn", "a limit on the ADC's range: the value has a kink where the pixel saturates"),
];

/// Whether a parameter's derivative is per relative change.
fn logarithmic(p: Parameter) -> bool {
    !matches!(
        p,
        Parameter::ReadNoise
            | Parameter::DarkCurrent
            | Parameter::Gain
            | Parameter::Binary2(_)
            | Parameter::PhaseSpline(_)
            | Parameter::Zernike(_)
            | Parameter::ZernikeNoll(_)
            | Parameter::Seidel(_)
            | Parameter::SpectrumCenter
            | Parameter::SpectrumRange
            | Parameter::Temperature
            | Parameter::FieldAngle(_)
            | Parameter::FieldPointAngle { .. }
            | Parameter::LibraryBias(_)
            | Parameter::IrisDecentre(_)
            | Parameter::Obscuration
    )
}

/// The key's unit per the engine's unit: the spectral keys are in nm, their derivatives per m.
fn unit(p: Parameter) -> f64 {
    match p {
        Parameter::SpectrumCenter | Parameter::SpectrumRange => 1e-9,
        // the field keys are in degrees, the engine's angles in radians
        Parameter::FieldAngle(_) | Parameter::FieldPointAngle { .. } => std::f64::consts::PI / 180.0,
        _ => 1.0,
    }
}

/// The chromatic lens's Seidel terms, per µm: their gradient on the overlap engine
/// (docs/physics.md, "Gradients: Seidel terms on the overlap engine").
const SEIDEL: [(&str, metric::SeidelTerm); 4] = [
    ("lens.spherical_um", metric::SeidelTerm::Spherical),
    ("lens.coma_um", metric::SeidelTerm::Coma),
    ("lens.astigmatism_um", metric::SeidelTerm::Astigmatism),
    ("lens.field_curvature_um", metric::SeidelTerm::FieldCurvature),
];

/// A circular iris's decentre along x and y, a fraction of the aperture's radius: its lane on the
/// exact 1-D engine (docs/physics.md, "Gradients: the iris").
const IRIS_DECENTRE: [&str; 2] = ["lens.iris_decentre_x", "lens.iris_decentre_y"];

/// The spectral keys: the Gaussian or top-hat spectrum's centre and range, a line's wavelength
/// and equivalent width.
const SPECTRAL: [(&str, Parameter); 2] =
    [("spectrum.center_nm", Parameter::SpectrumCenter), ("spectrum.range_nm", Parameter::SpectrumRange)];

/// The F-number and the focal length: the families whose every order is the full circular
/// pupil with a defocus `W020 ∝ f0/F#²` alone (docs/physics.md, "Gradients").
const APERTURE: [(&str, Parameter); 2] =
    [("lens.f_number", Parameter::FNumber), ("lens.focal_length_mm", Parameter::FocalLength)];

/// The families [`APERTURE`]'s keys are differentiated for: the defocus families, and the phase
/// lens on the radial engine's lanes (its profile and reference sphere moving with the aperture
/// radius, docs/physics.md "Gradients"), and the dispersion-engineered lens (its true-delay
/// fraction moving with them: `achromat`'s chains, which take its keys first).
const APERTURE_MODELS: [&str; 5] = ["chromatic", "refractive", "harmonic", "phase", "dispersion-engineered"];

/// The design wavelength λ0 (docs/physics.md, "Gradients: the design wavelength").
const DESIGN_WAVELENGTH: &str = "lens.design_wavelength_nm";

/// The families [`DESIGN_WAVELENGTH`] is differentiated for: every order the full circular
/// pupil with a defocus alone, moving with λ0 as the lens says
/// (`optics::LensModel::design_wavelength_rates`); and the phase lens, whose gradient is 0 where
/// nothing it images with depends on λ0 (a geometric phase:
/// `optics::LensModel::design_wavelength_inert`), refused naming why otherwise; and a lens
/// given as data (a PSF stack, MTF tables), whose λ0 is the Fraunhofer report's reference alone
/// (its gradient 0).
const DESIGN_WAVELENGTH_MODELS: [&str; 6] = ["chromatic", "refractive", "harmonic", "phase", "psf", "tabulated"];

/// The scene quantity `lens.design_wavelength_nm` sets (`∂/∂ln λ0`), or why its gradient is
/// refused for this family; `None` for another key.
fn design_wavelength_parameter(key: &str, lens_model: &str) -> Option<Result<Parameter>> {
    if key != DESIGN_WAVELENGTH {
        return None;
    }
    if DESIGN_WAVELENGTH_MODELS.contains(&lens_model) {
        return Some(Ok(Parameter::DesignWavelength));
    }
    let why = match lens_model {
        "library" => {
            "it selects each atom from the library (the atom whose phase is nearest the design phase at λ0), a \
             piecewise choice: the value jumps wherever λ0 moves an atom's choice to the next row"
        }
        _ => "its orders are not followed through the design wavelength for this family yet",
    };
    Some(Err(anyhow!(
        "--wrt {key}: not differentiable here yet for lens.model = \"{lens_model}\" ({why}); supported for \
         lens.model = {} (on axis, every order the full circle with a defocus alone)",
        DESIGN_WAVELENGTH_MODELS.map(|m| format!("\"{m}\"")).join(", ")
    )))
}

/// The scene quantity `lens.f_number` or `lens.focal_length_mm` sets, or why its gradient is
/// refused for this family; `None` for another key (the focal length with
/// `lens.aperture_diameter_mm` given, F# = f0/D, is [`chain_rule`]'s). A phase lens with
/// `options.pupil_mapping = "exact"` (whose map moves with the aperture) or a phase table with an
/// amplitude column (an amplitude in r_mm moves with it) is refused naming why.
fn aperture_parameter(key: &str, lens_model: &str, table: &toml::Table) -> Option<Result<Parameter>> {
    let (_, p) = APERTURE.iter().find(|(k, _)| *k == key)?;
    if lens_model == "phase"
        && let Some(mapping) = lookup(table, "options.pupil_mapping").and_then(toml::Value::as_str)
        && mapping == "exact"
    {
        return Some(Err(anyhow!(
            "--wrt {key}: not differentiable here yet with options.pupil_mapping = \"exact\" (the map from the \
             pupil to the image's frequencies, sin θ = r/√(r² + f0²), moves with the aperture too, which the \
             radial engine's lanes do not follow); supported with options.pupil_mapping = \"paraxial\""
        )));
    }
    if !APERTURE_MODELS.contains(&lens_model) {
        let why = match lens_model {
            "library" => {
                "its aperture radius R = f0/(2F#) cuts the layout's rings: the design phase is fitted to the rings \
                 whose centre lies inside R and the outermost atom's cell ends at R, so the value jumps wherever R \
                 crosses a ring centre (every pitch of R) and has no derivative there"
            }
            _ => "its defocus is not followed through the F-number and focal length for this family yet",
        };
        return Some(Err(anyhow!(
            "--wrt {key}: not differentiable here yet for lens.model = \"{lens_model}\" ({why}); supported for \
             lens.model = {}",
            APERTURE_MODELS.map(|m| format!("\"{m}\"")).join(", ")
        )));
    }
    Some(Ok(*p))
}

/// A key's derivative as a combination of the engines' parameters: `∂/∂key = Σ c ∂/∂p` over
/// its `(p, c)`, each `∂/∂p` in the engine's units (per relative change for a [`logarithmic`]
/// parameter, per engine unit otherwise). Most keys set one parameter ([`direct`]); a chain
/// rule on lanes the engines compute gives the others (docs/physics.md, "Gradients: chain
/// rules"); an empty chain is a key the value does not depend on (derivative 0).
type Chain = Vec<(Parameter, f64)>;

/// The chain of a key that sets the parameter `p` itself, at the key's `value`.
fn direct(p: Parameter, value: f64) -> Chain {
    vec![(p, if logarithmic(p) { 1.0 / value } else { unit(p) })]
}

/// A radiance meter's readings (SI eq. S2, S6): the target's radiance is
/// `L_λ = E_norm(λ) corr P/(π d²/4) (2f/D)²/(π T_lenses)`, each reading a factor constant in λ
/// with the exponent given here: `∂ln L/∂ln key` (a [`Parameter::SignalScale`] times it).
const METER: [(&str, f64); 5] = [
    ("source.power_nw", 1.0),
    ("source.fiber_core_diameter_um", -2.0),
    ("source.relay_transmission", -1.0),
    ("source.relay_iris_mm", -2.0),
    ("source.relay_focal_length_mm", 2.0),
];

/// The chain of a key whose derivative is a chain rule on the engines' parameters, or why it
/// is refused; `None` for a key that sets one parameter itself (or another refusal's).
fn chain_rule(key: &str, value: f64, lens_model: &str, table: &toml::Table) -> Option<Result<Chain>> {
    if let Some((_, exponent)) = METER.iter().find(|(k, _)| *k == key) {
        return Some(Ok(vec![(Parameter::SignalScale, exponent / value)]));
    }
    if key == "source.calibration_wavelength_nm" {
        return Some(calibration_wavelength(key, value, table));
    }
    if key == "lens.norm_radius_mm" {
        return Some(norm_radius(key, value, lens_model, table));
    }
    if lens_model == "psf"
        && let Some(chain) = psf_stack(key, value, table)
    {
        return Some(chain);
    }
    let diameter_given = lookup(table, "lens.aperture_diameter_mm").is_some();
    if key == "lens.aperture_diameter_mm" || (key == "lens.focal_length_mm" && diameter_given) {
        // F# = f0/D: the F-number's lanes, with its checks for this family
        let checked = aperture_parameter("lens.f_number", lens_model, table)?;
        return Some(match checked {
            Err(e) => Err(anyhow!("{}", e.to_string().replacen("lens.f_number", key, 1))),
            // ∂/∂D = −(1/D) ∂/∂ln F#
            Ok(_) if key == "lens.aperture_diameter_mm" => Ok(vec![(Parameter::FNumber, -1.0 / value)]),
            // D held: ∂/∂ln f0 = ∂/∂ln f0|F# + ∂/∂ln F#
            Ok(_) => Ok(vec![(Parameter::FocalLength, 1.0 / value), (Parameter::FNumber, 1.0 / value)]),
        });
    }
    // the atoms' phase errors of a radial layout, every draw held, or of a 2-D layout, in
    // expectation over the draws: forward mode through the lens's pupil, as a parameter bias is
    // (docs/physics.md, "Gradients: a library's atoms' phase errors")
    if key == "lens.atom_phase_error_rad" && lens_model == "library" {
        return Some(Ok(vec![(Parameter::LibraryBias(metric::ATOM_PHASE_ERROR), 1.0)]));
    }
    // the atoms' amplitude errors of a 2-D layout, in expectation over the draws: smooth in σ_t
    // (docs/physics.md, "Gradients: a library's atoms' phase errors")
    let two_d = ["lens.layout_grid", "lens.layout_gds"].iter().any(|k| lookup(table, k).is_some());
    if key == "lens.atom_transmission_error" && lens_model == "library" && two_d {
        return Some(Ok(vec![(Parameter::LibraryBias(metric::ATOM_TRANSMISSION_ERROR), 1.0)]));
    }
    let why = match key {
        "lens.atom_phase_error_rad" => {
            "the value is smooth in it for a fixed seed (every atom's factor e^{iσδ_i} with its draw δ_i held), and \
             its derivative is computed for lens.model = \"library\" (a radial layout, lens.layout, or a 2-D layout, \
             lens.layout_grid or lens.layout_gds, on the FFT path): `asnr tolerance` gives the ASNR's sensitivity to \
             it for the other families"
        }
        "lens.atom_transmission_error" => {
            "every atom's amplitude factor 1 + σε_i is taken as 0 where it falls below 0 and its |t| capped at 1 (a \
             passive atom): the value has a kink wherever σ moves an atom across either limit (a 2-D layout, \
             lens.layout_grid or lens.layout_gds, takes the errors in expectation over the draws and its derivative \
             is computed)"
        }
        "lens.phase_map_pitch_um" if lens_model == "phase" => {
            // the cells' edges and values move (docs/physics.md, "Gradients: a phase map's pitch
            // and aperture"); N does not
            return Some(Ok(vec![(Parameter::MapPitch, 1.0 / value)]));
        }
        "lens.obscuration" if value == 0.0 => {
            // the edge of its domain [0, 1): one-sided, and 0 (docs/physics.md, "Gradients: the iris")
            return Some(Ok(Vec::new()));
        }
        "lens.obscuration" => {
            // 0 < ε < 1: the inner edge's motion on the FFT path (the mean MTF), and the area
            // fraction 1 − ε² on τ1 and T (the photon counts, ∂/∂ln τ1 + ∂/∂ln T):
            // docs/physics.md, "Gradients: the edge's motion on the FFT path"
            let rate = -2.0 * value / (1.0 - value * value);
            return Some(Ok(vec![
                (Parameter::Obscuration, 1.0),
                (Parameter::Efficiency, rate),
                (Parameter::Transmission, rate),
            ]));
        }
        _ => return None,
    };
    Some(Err(anyhow!("--wrt {key}: not differentiable here yet: {why}")))
}

/// `source.calibration_wavelength_nm` (SI eq. S3): the broadband correction
/// `corr = R(λ_cal) ∫ E_norm/R dλ` is the only place λ_cal enters, a factor constant in λ on
/// the radiance, so `∂ln L/∂λ_cal = R′(λ_cal)/R(λ_cal)`. The responsivity table is linear
/// between its rows: the slope of the row interval holding λ_cal; on a row the slopes of the
/// two sides differ (a kink) and the key is refused.
fn calibration_wavelength(key: &str, value: f64, table: &toml::Table) -> Result<Chain> {
    let file = lookup(table, "source.responsivity_csv")
        .and_then(toml::Value::as_str)
        .ok_or_else(|| anyhow!("--wrt {key}: the scene has no source.responsivity_csv"))?;
    let r = scene::read_table(std::path::Path::new(file), 0.0, f64::INFINITY, "responsivity")
        .with_context(|| format!("--wrt {key}: reading source.responsivity_csv"))?;
    let (w, v) = (r.wavelengths(), r.values());
    let l = value * 1e-9;
    // the table's wavelengths are its nm times 1e-9, as λ_cal is: a row is an exact match
    if let Some(k) = w.iter().position(|&x| x == l) {
        let slope = |a: usize, b: usize| (v[b] - v[a]) / ((w[b] - w[a]) * 1e9);
        let sides = match (k.checked_sub(1), (k + 1 < w.len()).then_some(k + 1)) {
            (Some(a), Some(b)) => format!("R′ is {:.4e} below and {:.4e} above, per nm", slope(a, k), slope(k, b)),
            _ => "the table ends there".to_owned(),
        };
        bail!(
            "--wrt {key}: not differentiable at {value} nm: a row of the responsivity table, which is linear between \
             its rows, so R(λ_cal) — a factor on the radiance (SI eq. S3) — has a kink there ({sides}); between two \
             rows ∂ln L/∂λ_cal = R′/R"
        );
    }
    let k = w.partition_point(|&x| x < l);
    if k == 0 || k == w.len() {
        bail!("--wrt {key}: {value} nm is outside the responsivity table");
    }
    let slope = (v[k] - v[k - 1]) / (w[k] - w[k - 1]);
    // per nm
    Ok(vec![(Parameter::SignalScale, slope / r.value(l) * 1e-9)])
}

/// `lens.norm_radius_mm` of a phase lens with Binary 2 terms, `φ = M Σ A_i (r/R_n)^{2i}`: R_n
/// enters only through the terms (a spline is in ρ = r/R, the Zernike terms are normalized to
/// the aperture, and a phase table, in r_mm, takes no R_n), so
/// `∂/∂ln R_n = Σ_i −2i A_i ∂/∂A_i` on the Binary 2 lanes.
fn norm_radius(key: &str, value: f64, lens_model: &str, table: &toml::Table) -> Result<Chain> {
    let terms = lookup(table, "lens.binary2").and_then(toml::Value::as_array);
    let Some(terms) = terms.filter(|_| lens_model == "phase") else {
        bail!(
            "--wrt {key}: not differentiable here: R_n normalizes lens.binary2 of lens.model = \"phase\", which this scene has not"
        );
    };
    let mut chain = Vec::new();
    for (i, a) in terms.iter().enumerate() {
        let a = match a {
            toml::Value::Float(a) => *a,
            toml::Value::Integer(a) => *a as f64,
            other => bail!("--wrt {key}: lens.binary2[{i}] = {other} is not a number"),
        };
        if a != 0.0 {
            chain.push((Parameter::Binary2(i), -2.0 * (i + 1) as f64 * a / value));
        }
    }
    Ok(chain)
}

/// A PSF stack's keys (docs/physics.md, "Gradients: chain rules"), `None` for another key. The
/// stack's OTF is a table in absolute frequency: the F-number and focal length move only the
/// photon count, `N ∝ NA² = 1/(4F#²)` (SI eq. S7), F# = f0/D where the diameter is given (a
/// [`Parameter::SignalScale`] times −2 per ln F#); the pitch scales the OTF's frequencies
/// ([`Parameter::PsfPitch`]); a slice's wavelength is a breakpoint of the OTF's interpolation
/// in λ.
fn psf_stack(key: &str, value: f64, table: &toml::Table) -> Option<Result<Chain>> {
    let diameter_given = lookup(table, "lens.aperture_diameter_mm").is_some();
    let scale = |exponent: f64| Some(Ok(vec![(Parameter::SignalScale, exponent / value)]));
    match key {
        "lens.f_number" => scale(-2.0),
        "lens.aperture_diameter_mm" => scale(2.0),
        "lens.focal_length_mm" if diameter_given => scale(-2.0),
        // the OTF is the stack's and the F-number is given: nothing moves
        "lens.focal_length_mm" => Some(Ok(Vec::new())),
        "lens.psf_pitch_um" => Some(Ok(vec![(Parameter::PsfPitch, 1.0 / value)])),
        _ if entry_of(key, "lens.psf_wavelengths_nm").is_some() => Some(Err(anyhow!(
            "--wrt {key}: not differentiable here yet: a slice's wavelength is a breakpoint of the OTF's \
             interpolation (linear in λ between the slices, the end slices' OTF standing beyond the stack): moving \
             it moves the kink of every OTF value's λ-dependence there and the interpolation's weights on the two \
             intervals beside it, and the spectral rules cut their panels at it; that derivative is not computed \
             (it is never replaced by a finite difference)"
        ))),
        _ => None,
    }
}

/// A key as written, parsed: its dotted name and its index, if any.
struct KeyPath {
    name: String,
    index: Option<usize>,
}

impl KeyPath {
    fn parse(key: &str) -> Result<KeyPath> {
        let key = key.trim();
        let (name, index) = match key.split_once('[') {
            Some((name, rest)) => {
                let index = rest
                    .strip_suffix(']')
                    .and_then(|i| i.trim().parse::<usize>().ok())
                    .with_context(|| format!("--wrt {key}: `{rest}` is not a list index (e.g. lens.binary2[1])"))?;
                (name.trim(), Some(index))
            }
            None => (key, None),
        };
        if name.is_empty() || name.split('.').any(|p| p.trim().is_empty()) {
            bail!("--wrt {key}: not a scene key (e.g. exposure.time_ms, lens.binary2[1])");
        }
        Ok(KeyPath { name: name.split('.').map(str::trim).collect::<Vec<_>>().join("."), index })
    }

    fn canonical(&self) -> String {
        match self.index {
            Some(i) => format!("{}[{i}]", self.name),
            None => self.name.clone(),
        }
    }
}

/// The resolved scene's value at a dotted name, if it has one.
fn lookup<'a>(table: &'a toml::Table, name: &str) -> Option<&'a toml::Value> {
    let mut parts = name.split('.');
    let mut cursor = table.get(parts.next()?)?;
    for part in parts {
        cursor = cursor.get(part)?;
    }
    Some(cursor)
}

/// The keys of `keys` in their canonical spelling with their values in the scene: a list key
/// without an index expanded to every entry; refused, naming the key, when the scene has no such
/// key, its value is not a number, or a key comes twice.
fn expand(source: &Source, table: &toml::Table, keys: &[String]) -> Result<Vec<(String, f64)>> {
    let mut out: Vec<(String, f64, String)> = Vec::new();
    for key in keys {
        if let Some(point) = field_point(key)? {
            let (index, axis) = point;
            let name = ["x_deg", "y_deg"][axis];
            let canonical = format!("fields[{index}].{name}");
            let list = lookup(table, "fields").and_then(toml::Value::as_array).ok_or_else(|| {
                anyhow!(
                    "--wrt {key}: {} has no [[fields]] list (a single point's keys are field.x_deg and field.y_deg)",
                    source.label()
                )
            })?;
            let entry = list.get(index).ok_or_else(|| {
                anyhow!("--wrt {key}: {} has {} points in [[fields]] (0-based)", source.label(), list.len())
            })?;
            let number = match entry.get(name) {
                Some(toml::Value::Float(v)) => *v,
                Some(toml::Value::Integer(v)) => *v as f64,
                Some(other) => bail!("--wrt {key}: {canonical} = {other} is not a number"),
                None => bail!(
                    "--wrt {key}: {} gives no {canonical} (it is 0 there: --set {canonical}=0 makes it a key)",
                    source.label()
                ),
            };
            if let Some((_, _, first)) = out.iter().find(|(k, _, _)| *k == canonical) {
                bail!("--wrt {key}: {canonical} is given twice (as `{first}` and `{}`)", key.trim());
            }
            out.push((canonical, number, key.trim().to_owned()));
            continue;
        }
        let path = KeyPath::parse(key)?;
        refuse_by_name(&path.canonical())?;
        let value = lookup(table, &path.name)
            .ok_or_else(|| anyhow!("--wrt {key}: {} has no such key (`asnr scene` lists its keys)", source.label()))?;
        let entries: Vec<(String, &toml::Value)> = match (path.index, value) {
            (Some(i), toml::Value::Array(list)) => vec![(
                path.canonical(),
                list.get(i).ok_or_else(|| {
                    anyhow!("--wrt {key}: {} has {} entries in {} (0-based)", source.label(), list.len(), path.name)
                })?,
            )],
            (Some(_), _) => bail!("--wrt {key}: {} is not a list", path.name),
            (None, toml::Value::Array(list)) => {
                list.iter().enumerate().map(|(i, v)| (format!("{}[{i}]", path.name), v)).collect()
            }
            (None, v) => vec![(path.canonical(), v)],
        };
        for (canonical, v) in entries {
            let number = match v {
                toml::Value::Float(v) => *v,
                toml::Value::Integer(v) => *v as f64,
                other => bail!("--wrt {key}: {canonical} = {other} is not a number; only numeric keys have a gradient"),
            };
            if let Some((_, _, first)) = out.iter().find(|(k, _, _)| *k == canonical) {
                bail!("--wrt {key}: {canonical} is given twice (as `{first}` and `{}`)", key.trim());
            }
            out.push((canonical, number, key.trim().to_owned()));
        }
    }
    Ok(out.into_iter().map(|(k, v, _)| (k, v)).collect())
}

/// A point of the scene's `[[fields]]` list's angle, `fields[i].x_deg` or `fields[i].y_deg`
/// (spaces and leading zeros allowed, spelled canonically after): `(i, axis)`; `None` for a key
/// that is not of the list; refused for another of its keys (`fields[i].weight`).
fn field_point(key: &str) -> Result<Option<(usize, usize)>> {
    let Some(rest) = key.trim().strip_prefix("fields") else { return Ok(None) };
    let Some(rest) = rest.trim_start().strip_prefix('[') else { return Ok(None) };
    let (index, name) = rest
        .split_once(']')
        .and_then(|(i, name)| Some((i.trim().parse::<usize>().ok()?, name.trim().strip_prefix('.')?.trim())))
        .with_context(|| format!("--wrt {key}: not a key of a [[fields]] point (e.g. fields[1].x_deg)"))?;
    match name {
        "x_deg" => Ok(Some((index, 0))),
        "y_deg" => Ok(Some((index, 1))),
        "weight" => bail!(
            "--wrt {key}: not differentiated: a point's weight is a choice of the average, not of the design (the \
             field-of-view mean moves with it as (value at the point − mean)/Σ weights)"
        ),
        _ => bail!("--wrt {key}: a [[fields]] point has the keys x_deg, y_deg and weight"),
    }
}

/// Refuses a key whose name says the value is not smooth in it (an integer, a seed, a limit, a
/// numerical option), whether or not the scene gives it.
fn refuse_by_name(key: &str) -> Result<()> {
    let last = key.rsplit('.').next().unwrap_or(key);
    let last = last.split('[').next().unwrap_or(last);
    if let Some((_, what)) = NOT_SMOOTH.iter().find(|(k, _)| last == *k || last.ends_with(&format!("_{k}"))) {
        bail!("--wrt {key}: not differentiable: it is {what}");
    }
    if key.starts_with("options.") {
        bail!("--wrt {key}: not differentiable: a numerical option of the evaluation, not a property of the design");
    }
    Ok(())
}

/// How many wavefront directions of each kind the scene's lens has, in the order of its lanes
/// (`optics::LensModel::binary2_directions` of a phase lens: Binary 2 coefficients, spline
/// knots, then the `m = 0` Zernike terms).
#[derive(Clone, Copy, Debug, Default)]
struct Lanes {
    binary2: usize,
    spline: usize,
}

impl Lanes {
    fn of(table: &toml::Table) -> Lanes {
        let len = |name: &str| lookup(table, name).and_then(toml::Value::as_array).map_or(0, Vec::len);
        Lanes { binary2: len("lens.binary2"), spline: len("lens.phase_spline_rad") }
    }
}

/// The index of `key` in the list `name` (`lens.binary2[3]` → 3), if it is an entry of it.
fn entry_of(key: &str, name: &str) -> Option<Result<usize>> {
    let index = key.strip_prefix(name)?.strip_prefix('[')?.strip_suffix(']')?;
    Some(index.parse::<usize>().with_context(|| format!("--wrt {key}: `{index}` is not a list index")))
}

/// The gradient with respect to `lens.parameter_bias[i]`, or why it is refused; `None` for
/// another key. With `lens.library_interpolation = "cubic"` the value is C¹ in the bias and the
/// engines follow it (docs/physics.md, "Gradients: a library's parameter bias"). With
/// `"linear"` (the default) the rows are joined by straight lines: every atom's field has a
/// kink wherever the bias moves its parameter across a row, so the value is only piecewise
/// smooth in the bias, and the gradient is refused.
fn library_bias(key: &str, table: &toml::Table) -> Option<Result<Parameter>> {
    let index = match entry_of(key, "lens.parameter_bias")? {
        Ok(i) => i,
        Err(e) => return Some(Err(e)),
    };
    let interpolation = lookup(table, "lens.library_interpolation").and_then(toml::Value::as_str).unwrap_or("linear");
    let model = lookup(table, "lens.model").and_then(toml::Value::as_str).unwrap_or("");
    Some(if interpolation == "cubic" && model == "library" {
        Ok(Parameter::LibraryBias(index))
    } else if interpolation == "cubic" {
        Err(anyhow!(
            "--wrt {key}: not differentiable here yet for lens.model = \"{model}\": the parameter bias's gradient is \
             computed for lens.model = \"library\" with a radial layout, on axis and off axis (its pupil on the FFT \
             path there, the atoms' fields a complex lane of its forward mode), and with a 2-D layout on the FFT \
             path (the atoms' table's derivative sampled as the site map's field)"
        ))
    } else {
        Err(anyhow!(
            "--wrt {key}: not differentiable with lens.library_interpolation = \"{interpolation}\": the library's rows \
             are joined by straight lines, so each atom's field has a kink wherever the bias moves its parameter \
             across a row; lens.library_interpolation = \"cubic\" (a C¹ cubic between the rows) makes the value \
             smooth in the bias, and its gradient is computed there"
        ))
    })
}

/// The field keys of a single field point (`[field]`), per degree.
const FIELD: [(&str, usize); 2] = [("field.x_deg", 0), ("field.y_deg", 1)];

/// The families whose field angles' gradient is computed (docs/physics.md, "Gradients: the
/// field point"). The chromatic, refractive and harmonic lenses' orders change with the field
/// point only through their image shifts (`optics::LensModel::image_shift_field_rates`), so
/// that the gradient is the shift lane plus the relative illumination: the chromatic lens's
/// lateral colour `f0 tan θ (λ0/λ − 1)` (its Seidel terms are the scene's at the field point,
/// not scaled with it), the harmonic lens's per order `f0 tan θ (pλ0/(mλ) − 1)`, and the
/// refractive lens, its stop at the lens, whose orders do not move with the field. The phase and
/// library lenses' orders off axis are radial pupils seen by an oblique wave, on the FFT path:
/// the wave's path `α·X + |X − P| − |P|` moves with the angle, one more lane of the FFT path's
/// forward mode (`optics::WavefrontDirection::FieldAngle`).
/// A PSF stack's PSFs are one field point's in its frame (`+x` the field direction), the
/// same at every field point: its mean MTF does not depend on the field angles, which move the
/// relative illumination alone (`optics::LensModel::turns_with_field`), as the
/// dispersion-engineered lens's one order, the same at every field point (no lateral colour).
const FIELD_MODELS: [&str; 7] =
    ["chromatic", "refractive", "harmonic", "phase", "library", "psf", "dispersion-engineered"];

/// The scene quantity `field.x_deg` or `field.y_deg` sets, or why its gradient is refused for
/// this family; `None` for another key ([`FIELD_MODELS`]).
fn field_parameter(key: &str, lens_model: &str) -> Option<Result<Parameter>> {
    let (_, axis) = FIELD.iter().find(|(k, _)| *k == key)?;
    if FIELD_MODELS.contains(&lens_model) {
        return Some(Ok(Parameter::FieldAngle(*axis)));
    }
    Some(Err(anyhow!(
        "--wrt {key}: not differentiable here yet for lens.model = \"{lens_model}\" (its off-axis orders are not \
         followed through the field angle yet; it is never replaced by a finite difference); supported for \
         lens.model = {}",
        FIELD_MODELS.map(|m| format!("\"{m}\"")).join(", ")
    )))
}

/// The scene quantity a canonical key sets, or why its gradient is refused.
fn parameter(key: &str, lens_model: &str, spectrum_shape: &str, lanes: Lanes) -> Result<Parameter> {
    refuse_by_name(key)?;
    if let Some((_, p)) = SPECTRAL.iter().find(|(k, _)| *k == key) {
        if !["gaussian", "tophat", "line"].contains(&spectrum_shape) {
            bail!(
                "--wrt {key}: not differentiable here yet for spectrum.shape = \"{spectrum_shape}\"; supported for \
                 spectrum.shape = \"gaussian\", \"tophat\" and \"line\""
            );
        }
        return Ok(*p);
    }
    if key == TEMPERATURE {
        return Ok(Parameter::Temperature);
    }
    if key == PIXEL_PITCH {
        return Ok(Parameter::PixelPitch);
    }
    if let Some(p) = design_wavelength_parameter(key, lens_model) {
        return p;
    }
    if let Some(p) = field_parameter(key, lens_model) {
        return p;
    }
    if let Some((point, axis)) = field_point(key)? {
        // a point of the field-of-view list: that point's field angle, times its weight's share
        let canonical = FIELD[axis].0;
        return match field_parameter(canonical, lens_model) {
            Some(Ok(_)) => Ok(Parameter::FieldPointAngle { point, axis }),
            Some(Err(e)) => Err(anyhow!("{}", e.to_string().replacen(canonical, key, 1))),
            None => unreachable!("a field key"),
        };
    }
    if key.starts_with("field.") {
        bail!(
            "--wrt {key}: not differentiable here yet: the field point moves the lateral colour's image shifts \
             f0 tan θ (λ0/λ − 1), an oblique wave's Seidel terms and the relative illumination, whose chain rule \
             is not computed yet (it is never replaced by a finite difference)"
        );
    }
    if let Some(axis) = IRIS_DECENTRE.iter().position(|k| *k == key) {
        return Ok(Parameter::IrisDecentre(axis));
    }
    if let Some((_, term)) = SEIDEL.iter().find(|(k, _)| *k == key) {
        if lens_model != "chromatic" {
            bail!(
                "--wrt {key}: not differentiable here for lens.model = \"{lens_model}\"; the Seidel terms are keys of \
                 lens.model = \"chromatic\""
            );
        }
        return Ok(Parameter::Seidel(*term));
    }
    let wavefront = [("lens.binary2", 0), ("lens.phase_spline_rad", 1), ("lens.zernike_noll_rms_um", 2)];
    for (name, kind) in wavefront {
        let Some(index) = entry_of(key, name) else { continue };
        let i = index?;
        if kind == 2 && lens_model != "phase" {
            // any family's Zernike terms: on the FFT path (docs/physics.md, "Gradients: 2-D pupils")
            return Ok(Parameter::ZernikeNoll(i + 1));
        }
        if lens_model != "phase" {
            bail!(
                "--wrt {key}: not differentiable here yet for lens.model = \"{lens_model}\"; supported for lens.model = \"phase\""
            );
        }
        return Ok(match kind {
            0 => Parameter::Binary2(i),
            1 => Parameter::PhaseSpline(lanes.binary2 + i),
            _ => match metric::zernike_m0_place(i + 1) {
                Ok(place) => Parameter::Zernike(lanes.binary2 + lanes.spline + place),
                // m ≠ 0: the OTF depends on direction, the FFT path's gradient
                Err(_) => Parameter::ZernikeNoll(i + 1),
            },
        });
    }
    if let Some((_, p)) = SUPPORTED.iter().find(|(k, _)| *k == key) {
        if matches!(p, Parameter::Efficiency | Parameter::Transmission)
            && !SCALAR_EFFICIENCY_MODELS.contains(&lens_model)
        {
            bail!(
                "--wrt {key}: not differentiable here yet for lens.model = \"{lens_model}\" (its {} weighs orders \
                 against each other); supported for lens.model = {}",
                key.trim_start_matches("lens."),
                SCALAR_EFFICIENCY_MODELS.map(|m| format!("\"{m}\"")).join(" or ")
            );
        }
        return Ok(*p);
    }
    bail!(
        "--wrt {key}: not differentiable here yet: the gradient is computed for {}, {PIXEL_PITCH} (with camera.pixel_mtf true or false), \
         spectrum.center_nm and spectrum.range_nm (a Gaussian or top-hat band, the OTF rotationally symmetric or not, or a line, on a PSF stack or a tabulated OTF between its slices and on the dispersion-engineered lens inside its band, and on axis on its FFT grids: an annulus, Seidel or Zernike terms), source.temperature_k (a blackbody source, under a line or over a band, on the overlap engine too), \
         the radiance meter's source.power_nw, source.fiber_core_diameter_um, source.relay_transmission, source.relay_iris_mm, source.relay_focal_length_mm and source.calibration_wavelength_nm (between the responsivity table's rows), \
         lens.design_wavelength_nm (lens.model = \"chromatic\", \"refractive\" or \"harmonic\", on axis and off axis over a band or under a line without Seidel terms, through a decentred circular iris on the exact 1-D engine, with Seidel or Zernike terms on the overlap engine, under a line on its FFT grids (an annulus, Seidel or Zernike terms), with camera.pixel_mtf true or false; lens.model = \"phase\" with a geometric phase, \"psf\" and \"tabulated\", where it is 0), \
         lens.f_number, lens.focal_length_mm and lens.aperture_diameter_mm \
         (lens.model = \"chromatic\", \"refractive\", \"harmonic\", \"phase\" or \"psf\"; with Seidel or Zernike terms on the overlap engine, on axis and off; the phase lens on axis (on the FFT path with Zernike terms of m ≠ 0) and off axis at a single [field] point or over a [[fields]] list, a phase map on axis; on axis and off over a band on the FFT grids of an annulus, Seidel terms through an iris or Zernike terms, with lens.design_wavelength_nm, and under a line on its FFT grids), lens.psf_pitch_um (lens.model = \"psf\"), lens.norm_radius_mm (lens.model = \"phase\" with lens.binary2), lens.binary2[i] and lens.phase_spline_rad[i] (lens.model = \"phase\"), lens.zernike_noll_rms_um[i] (every family that takes it), lens.iris_decentre_x and lens.iris_decentre_y (lens.model = \"chromatic\", a circular iris on the exact 1-D engine, or with Seidel terms, an annulus or a sector on the FFT path), lens.obscuration (lens.model = \"chromatic\": at 0, the edge of its domain, one-sided, 0; above 0 its inner edge's motion on the FFT path, a band's grids or a line's, asked with no wavefront key but Seidel terms), lens.phase_map_pitch_um (a phase map on axis: its cells' edges and values on the FFT path), lens.atom_phase_error_rad (lens.model = \"library\", a radial or 2-D layout), lens.atom_transmission_error (lens.model = \"library\", a 2-D layout), the dispersion-engineered lens's lens.f_number, lens.focal_length_mm, lens.aperture_diameter_mm, lens.group_delay_range_fs and lens.design_band_nm[i] (away from D = D_max; with Zernike terms too), lens.efficiency, lens.transmission and field angles, the multiplexed lens's lens.efficiency and lens.transmission (both layouts), lens.f_number, lens.focal_length_mm and field angles (both layouts), lens.channels_nm[j] and lens.channel_efficiencies[j] (interleaved, on axis and off, on axis on one pass with lens.f_number and lens.focal_length_mm, and on axis with Zernike terms on the overlap engine; segmented, on the FFT path, λ_j with other_channels = \"signal\"), the segmented layout's lens.area_fractions[j] (its zones' edges on the FFT path; where the fractions sum to 1 the last absorbs the change), and lens.spherical_um, lens.coma_um, lens.astigmatism_um and lens.field_curvature_um (lens.model = \"chromatic\", on the overlap engine, at zero, and through an iris, under a line or beside Zernike terms on the FFT path), and field.x_deg and field.y_deg of a single [field] point or fields[i].x_deg and fields[i].y_deg of a [[fields]] list (lens.model = \"chromatic\", \"refractive\", \"harmonic\", \"phase\", \"library\" or \"psf\"; with Zernike terms too; under a line off axis on the harmonic lens's orders and the interleaved lens's channels, with lens.f_number and lens.focal_length_mm); with camera.noise_spectrum, the camera, exposure and radiometric keys, camera.pixel_pitch_um (with camera.pixel_mtf true or false), lens.f_number and lens.focal_length_mm (on axis, every order the full circle with a defocus alone or with Seidel terms, or a phase lens on the radial engine or the FFT path; through a decentred circular iris and off axis on the exact 1-D engine; on the FFT grids of a sampled pupil, on axis and off), lens.iris_decentre_x and lens.iris_decentre_y, spectrum.center_nm and spectrum.range_nm (a Gaussian or top-hat band, or a line on one order with a defocus alone, through a circular iris too, or a tabulated order (a PSF stack), the harmonic and interleaved lenses' orders on axis and off, or a phase lens), source.temperature_k, lens.parameter_bias[i], lens.design_wavelength_nm, lens.psf_pitch_um, the Seidel terms (at zero too), and the wavefront and field keys on the radial engine, the exact 1-D engine, the overlap engine and the FFT path (a band's grids or a line's); this key's derivative is not computed by the engines (it is never replaced by a finite difference)",
        SUPPORTED.map(|(k, _)| k).join(", ")
    )
}

/// The gradient of the ASNR, mean MTF, SNR0 and photoelectrons of the scene of `source` with
/// `overrides`, with respect to `keys` (`--wrt`: dotted, `lens.binary2[3]` for a list entry,
/// `lens.binary2` for all of them). Refused, naming the key: an unknown key or one the scene
/// lacks, a key given twice (`[1]` and `[01]` are one key), a key that is not a number, a key
/// the value does not depend on smoothly, a key whose derivative the engines do not compute yet.
pub fn gradient(source: &Source, overrides: &[String], keys: &[String]) -> Result<Gradient> {
    Ok(gradient_and_evaluation(source, overrides, keys)?.0)
}

/// [`gradient`] and the evaluation it was taken at.
pub(crate) fn gradient_and_evaluation(
    source: &Source,
    overrides: &[String],
    keys: &[String],
) -> Result<(Gradient, metric::Evaluation)> {
    if keys.is_empty() {
        bail!("no key to differentiate with respect to: give one or more --wrt KEY");
    }
    if let Some(found) = multiplexed::with_channels(source, overrides, keys)? {
        return Ok(found);
    }
    if let Some(found) = multiplexed::with_zone_channels(source, overrides, keys)? {
        return Ok(found);
    }
    let (table, built) = crate::objective::resolved_and_built(source, overrides)?;
    let expanded = expand(source, &table, keys)?;
    let lens_model = lookup(&table, "lens.model").and_then(toml::Value::as_str).unwrap_or("").to_owned();
    let shape = lookup(&table, "spectrum.shape").and_then(toml::Value::as_str).unwrap_or("").to_owned();
    let lanes = Lanes::of(&table);
    let chains: Vec<Chain> = expanded
        .iter()
        .map(|(k, v)| {
            achromat::chain(k, *v, &lens_model, &table)
                .or_else(|| multiplexed::chain(k, *v, &lens_model, &table))
                .or_else(|| chain_rule(k, *v, &lens_model, &table))
                .unwrap_or_else(|| {
                    aperture_parameter(k, &lens_model, &table)
                        .or_else(|| library_bias(k, &table))
                        .unwrap_or_else(|| parameter(k, &lens_model, &shape, lanes))
                        .map(|p| direct(p, *v))
                })
        })
        .collect::<Result<_>>()?;
    // the engines' parameters, each once, in the order the keys first ask them
    let mut parameters: Vec<Parameter> = Vec::new();
    for (p, _) in chains.iter().flatten() {
        if !parameters.contains(p) {
            parameters.push(*p);
        }
    }
    if parameters.is_empty() {
        // every key's derivative is 0 (a key the value does not depend on): the evaluation alone
        parameters.push(Parameter::SignalScale);
    }
    let g = metric::gradient(&built, &parameters).map_err(|e| engine_refusal(source, &expanded, &chains, e))?;
    // ∂/∂key = Σ c ∂/∂p over the key's chain
    let per_key = |d: &[f64]| -> Vec<f64> {
        chains
            .iter()
            .map(|chain| {
                chain.iter().map(|(p, c)| c * d[parameters.iter().position(|q| q == p).expect("listed")]).sum::<f64>()
                    + 0.0
            })
            .collect()
    };
    let columns = [per_key(&g.asnr), per_key(&g.mean_mtf), per_key(&g.snr0), per_key(&g.photoelectrons)];
    Ok((Gradient::of(&expanded, &g.evaluation, columns), g.evaluation))
}

/// The engines' error, naming the keys as `--wrt` spells them: a refusal
/// ([`metric::Error::NotDifferentiable`]) names the quantity the engines differentiate against
/// (`the decentre of the lens's iris`), so the keys whose chain moves a quantity of that name
/// are put before it (`--wrt lens.iris_decentre_x: …`); another error keeps the scene's label.
fn engine_refusal(source: &Source, expanded: &[(String, f64)], chains: &[Chain], e: metric::Error) -> anyhow::Error {
    let metric::Error::NotDifferentiable { parameter, .. } = &e else {
        return anyhow!("{}: {e}", source.label());
    };
    let keys: Vec<&str> = expanded
        .iter()
        .zip(chains)
        .filter(|(_, chain)| chain.iter().any(|(p, _)| p.describe() == *parameter))
        .map(|((k, _), _)| k.as_str())
        .collect();
    match keys.is_empty() {
        true => anyhow!("{}: {e}", source.label()),
        false => anyhow!("--wrt {}: {}: {e}", keys.join(", "), source.label()),
    }
}

/// The gradient as a table: each key, its value, `∂ASNR/∂key` and `∂ln ASNR/∂ln key`, each
/// column as wide as its widest entry (a value prints in full: `0.30000000000000004`).
pub fn table(g: &Gradient) -> String {
    let width = g.keys.iter().map(|k| k.chars().count()).max().unwrap_or(3).max(3);
    let values: Vec<String> = g.values.iter().map(f64::to_string).collect();
    let value_width = values.iter().map(|v| v.chars().count()).max().unwrap_or(0).max("value".len());
    let mut out = format!(
        "ASNR {:.6}  (mean MTF {:.6}, SNR0 {:.6}, N {:.6e} e⁻)\n\n{:<width$}  {:>value_width$}  {:>14}  {:>16}\n",
        g.asnr, g.mean_mtf, g.snr0, g.photoelectrons, "key", "value", "∂ASNR/∂key", "∂ln ASNR/∂ln key"
    );
    for (i, k) in g.keys.iter().enumerate() {
        out.push_str(&format!(
            "{k:<width$}  {:>value_width$}  {:>14.6e}  {:>16.6}\n",
            values[i],
            g.d_asnr[i],
            g.relative(i)
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene::sweep::assignment;

    /// The tolerance of the converged evaluations the references difference (docs/physics.md,
    /// "Gradients": ≤ 1e-10).
    const REFERENCE_TOLERANCE: f64 = 1e-10;

    fn example(name: &str) -> Source {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples").join(name);
        scene::read(Some(&path)).unwrap()
    }

    pub(super) fn owned(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| (*s).to_owned()).collect()
    }

    /// `base`'s overrides followed by `more`'s, owned.
    fn joined(base: &[&str], more: &[&str]) -> Vec<String> {
        owned(&[base, more].concat())
    }

    /// A line at 803 nm, its equivalent width 1 nm.
    const LINE_803: [&str; 3] = ["spectrum.shape=\"line\"", "spectrum.center_nm=803", "spectrum.range_nm=1"];
    /// The pixel MTF and a read noise.
    const PIXEL_AND_READ_NOISE: [&str; 2] = ["camera.pixel_mtf=true", "camera.read_noise_e=2"];
    /// The integral form with the stray light, and a read noise.
    const INTEGRAL_WITH_GLARE: [&str; 3] =
        ["options.form=\"integral\"", "options.glare=\"included\"", "camera.read_noise_e=2"];

    /// (ASNR, mean MTF, SNR0, N) of a converged evaluation with `key = value`.
    fn converged(source: &Source, overrides: &[String], key: &str, value: f64) -> [f64; 4] {
        converged_at(source, overrides, key, value, REFERENCE_TOLERANCE)
    }

    /// [`converged`] at the tolerance `tolerance`.
    fn converged_at(source: &Source, overrides: &[String], key: &str, value: f64, tolerance: f64) -> [f64; 4] {
        // the key's own override replaced by the stepped value
        let mut set: Vec<String> =
            overrides.iter().filter(|o| o.split_once('=').is_none_or(|(k, _)| k.trim() != key)).cloned().collect();
        set.push(format!("options.tolerance={tolerance:e}"));
        set.push(assignment(key, value));
        let evaluate = || {
            let e = metric::evaluate(&scene::build_from(source, &set).unwrap()).unwrap();
            [e.asnr, e.mean_mtf, e.snr0, e.photoelectrons]
        };
        // an evaluation several checks take (the same scene, overrides and tolerance: one
        // gradient checked at two tolerances against the same references, or a case two tests
        // share) is made once in the test binary; a scene that reads files a test writes (a
        // layout, a table) is evaluated each time
        type Memo = std::sync::Mutex<std::collections::HashMap<String, std::sync::Arc<std::sync::OnceLock<[f64; 4]>>>>;
        static MEMO: std::sync::OnceLock<Memo> = std::sync::OnceLock::new();
        let reads_files =
            |t: &str| [".csv", ".npy", ".npz", ".gds", ".json", ".txt", ".tsv", ".dat"].iter().any(|x| t.contains(x));
        // (the examples' own data files are the repository's)
        let example = source.label().contains("/examples/");
        if set.iter().any(|o| reads_files(o)) || (!example && reads_files(source.text())) {
            return evaluate();
        }
        let memo_key = format!("{}\n{}\n{}", source.label(), source.text(), set.join("\n"));
        let cell = MEMO.get_or_init(Memo::default).lock().unwrap().entry(memo_key).or_default().clone();
        *cell.get_or_init(evaluate)
    }

    /// [`central`] at the steps `2h` and `h`, Richardson-extrapolated: `(4 D(h) − D(2h))/3`, whose
    /// error falls as `h⁴`.
    pub(super) fn richardson(source: &Source, overrides: &[String], key: &str, value: f64, h: f64) -> [f64; 4] {
        let (coarse, fine) =
            (central(source, overrides, key, value, 2.0 * h), central(source, overrides, key, value, h));
        std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0)
    }

    /// The reference written here: central differences of converged evaluations with step `h`.
    fn central(source: &Source, overrides: &[String], key: &str, value: f64, h: f64) -> [f64; 4] {
        central_at(source, overrides, key, value, h, REFERENCE_TOLERANCE)
    }

    /// [`central`] of evaluations at the tolerance `tolerance`.
    fn central_at(source: &Source, overrides: &[String], key: &str, value: f64, h: f64, tolerance: f64) -> [f64; 4] {
        let up = converged_at(source, overrides, key, value + h, tolerance);
        let down = converged_at(source, overrides, key, value - h, tolerance);
        std::array::from_fn(|i| (up[i] - down[i]) / (2.0 * h))
    }

    /// The step of the rule of docs/physics.md, h = (3 tol/|f‴|)^{1/3}, for a key on which the
    /// value varies on the scale of the key itself: |f‴| ~ 1 in relative units, so
    /// h = (3e-10)^{1/3} |v| ≈ 6.7e-4 |v| (truncation and rounding both ~1e-7 relative).
    fn relative_step(_key: &str, value: f64) -> f64 {
        (3.0 * REFERENCE_TOLERANCE).cbrt() * value.abs()
    }

    /// Every key's gradient (ASNR, mean MTF, SNR0, N) against the central differences, as
    /// relative sensitivities ∂/∂ln key (dimensionless), within 10× the tolerance the gradient
    /// was asked at (the scene's 1e-6) relative to the gradient's norm.
    fn check_against_differences(source: &Source, overrides: &[String], keys: &[&str]) {
        check_with_steps(source, overrides, keys, &relative_step);
    }

    /// [`check_against_differences`] with the step `step(key, value)`.
    fn check_with_steps(source: &Source, overrides: &[String], keys: &[&str], step: &dyn Fn(&str, f64) -> f64) {
        check_with_references(source, overrides, keys, &|k, v| central(source, overrides, k, v, step(k, v)));
    }

    /// [`check_against_differences`] against `reference(key, value)`: (ASNR, mean MTF, SNR0, N)'s
    /// derivatives with respect to the key.
    pub(super) fn check_with_references(
        source: &Source,
        overrides: &[String],
        keys: &[&str],
        reference: &dyn Fn(&str, f64) -> [f64; 4],
    ) {
        let tolerance = 1e-6;
        let g = gradient(source, overrides, &owned(keys)).unwrap();
        assert_eq!(g.keys, owned(keys));
        let references: Vec<[f64; 4]> = g.keys.iter().zip(&g.values).map(|(k, v)| reference(k, *v)).collect();
        let ours = [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons];
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            let relative =
                |d: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..g.keys.len()).map(|i| d(i) * g.values[i]).collect() };
            let mine = relative(&|i| ours[q][i]);
            let theirs = relative(&|i| references[i][q]);
            // a gradient that is zero (the mean MTF of keys that change N only) against the
            // quantity's own size: its differences are rounding
            let quantity = [g.asnr, g.mean_mtf, g.snr0, g.photoelectrons][q];
            let norm = match mine.iter().map(|x| x * x).sum::<f64>().sqrt() {
                0.0 => quantity,
                norm => norm,
            };
            for (i, k) in g.keys.iter().enumerate() {
                let error = (mine[i] - theirs[i]).abs();
                println!(
                    "{name} {k}: gradient {:.9e}, differences {:.9e}, error/norm {:.1e}",
                    mine[i],
                    theirs[i],
                    error / norm
                );
                assert!(error <= 10.0 * tolerance * norm, "{name} {k}: {} vs {} (norm {norm})", mine[i], theirs[i]);
            }
        }
    }

    /// The Binary 2 lens on the radial engine with a full sensor (read noise, dark current, an
    /// ADC) and the glare-inclusive SNR: every radiometric, exposure and camera key.
    #[test]
    fn camera_and_radiometric_keys_match_central_differences() {
        let source = example("phase-binary2.toml");
        let overrides = owned(&[
            "camera.read_noise_e=3",
            "camera.dark_current_e_per_s=20000",
            "camera.gain_dn_per_e=0.5",
            "camera.adc_bits=12",
            "options.glare=\"included\"",
            "spectrum.peak=0.8",
        ]);
        check_against_differences(
            &source,
            &overrides,
            &[
                "exposure.time_ms",
                "source.radiance_w_m2_sr_nm",
                "camera.quantum_efficiency",
                "spectrum.peak",
                "lens.efficiency",
                "lens.transmission",
                "camera.read_noise_e",
                "camera.dark_current_e_per_s",
                "camera.gain_dn_per_e",
                "camera.pixel_pitch_um",
            ],
        );
    }

    /// The paper's chromatic lens on the closed form: the pixel pitch moves N and the Nyquist
    /// frequency (Leibniz' rule on the mean MTF), in the mean and in the integral form.
    #[test]
    fn pixel_pitch_matches_central_differences_in_both_forms() {
        let source = scene::read(None).unwrap();
        let keys = ["camera.pixel_pitch_um", "exposure.time_ms", "lens.efficiency"];
        check_against_differences(&source, &[], &keys);
        check_against_differences(&source, &owned(&["options.form=\"integral\"", "camera.read_noise_e=2"]), &keys);
    }

    /// The pixel pitch with the pixel MTF (docs/physics.md, "Gradients: the pixel pitch with the
    /// pixel MTF": in x = ν/ν_N the sinc stays, the lens's OTF at x ν_N moves; by parts
    /// ∂M̄/∂ln p = M̄ − P(ν_N)|O(ν_N)| + P_ν) against central differences of evaluations
    /// converged at 1e-10, in the mean and the integral form, on each engine whose frequency
    /// rule records |O|: the paper's lens on the closed form, the Binary 2 lens on the radial
    /// engine, the decentred iris on the exact 1-D engine (tangential and sagittal), the paper's
    /// lens with coma on the overlap engine (over azimuth), and off axis with its lateral colour.
    #[test]
    fn pixel_pitch_with_the_pixel_mtf_matches_central_differences() {
        let keys = ["camera.pixel_pitch_um", "exposure.time_ms"];
        let paper = scene::read(None).unwrap();
        let integral = ["camera.pixel_mtf=true", "options.form=\"integral\"", "camera.read_noise_e=2"];
        for (source, overrides) in [
            (&paper, owned(&PIXEL_AND_READ_NOISE)),
            (&paper, owned(&integral)),
            (&example("phase-binary2.toml"), owned(&PIXEL_AND_READ_NOISE)),
            (&example("decentred-iris.toml"), owned(&integral)),
            (&paper, joined(&PIXEL_AND_READ_NOISE, &["lens.coma_um=0.3"])),
            (&paper, joined(&PIXEL_AND_READ_NOISE, &["field.x_deg=3"])),
        ] {
            println!("{overrides:?}");
            check_against_differences(source, &overrides, &keys);
        }
    }

    /// The paper's scene with its flat source replaced by a 3000 K blackbody (scale 2e-3).
    fn paper_blackbody() -> Source {
        let paper = scene::read(None).unwrap();
        let text = paper
            .text()
            .replace("kind = \"flat\"", "kind = \"blackbody\"\ntemperature_k = 3000.0\nscale = 2e-3")
            .replace("radiance_w_m2_sr_nm = 0.025", "");
        assert!(text.contains("blackbody") && !text.contains("radiance_w_m2_sr_nm"), "{text}");
        Source::from_text(text, "blackbody", ".")
    }

    /// A blackbody's scale (a factor constant in λ) on the paper's lens, and the temperature
    /// under a line (Planck's ∂ln B/∂T on the photon count; the line's wavelength through
    /// ∂ln B/∂λ too), against central differences.
    #[test]
    fn a_blackbody_scale_matches_central_differences() {
        let source = paper_blackbody();
        check_against_differences(&source, &owned(&["camera.read_noise_e=2"]), &["source.scale", "exposure.time_ms"]);
        let line = owned(&LINE_803);
        check_line(&source, &line, &["source.temperature_k", "source.scale"]);
    }

    /// A blackbody's temperature over a band (docs/physics.md, "Gradients: a line's wavelength
    /// and a blackbody's temperature": Planck's ∂ln B/∂T moves N and the OTF's spectral weights,
    /// the OTF of ρ ∂ln B/∂T on its own engine) against central differences of evaluations
    /// converged at 1e-10, Richardson-extrapolated from the relative steps 2h and h,
    /// h = (3e-10)^{1/3} T (`(4 D(h) − D(2h))/3`: the plain difference's truncation, 5e-7 of
    /// ∂N/∂T and 3e-6 of ∂M̄/∂T on the paper's lens, would hide the gradient's own error), within
    /// 10× the scene's 1e-6 of each quantity's gradient norm over the keys (the mean MTF's: the
    /// temperature's alone, as the exposure leaves it). The paper's chromatic lens behind a Gaussian band of 50 nm
    /// and of 200 nm (with the pixel MTF, read noise and the integral form there), and
    /// examples/tabulated.toml (a 2800 K lamp behind its 52 nm filter table, the lens's
    /// efficiency and the QE tables) as it is and behind a 200 nm top-hat.
    #[test]
    fn a_blackbody_temperature_over_a_band_matches_central_differences() {
        let keys = ["source.temperature_k", "exposure.time_ms"];
        let paper = paper_blackbody();
        let tabulated = example("tabulated.toml");
        // its filter table replaced by a 200 nm top-hat inside the lens's and the QE's tables
        let text = tabulated.text().replace(
            "shape = \"table\"\ncsv = \"data/filter-825-52.csv\"",
            "shape = \"tophat\"\ncenter_nm = 825.0\nrange_nm = 200.0",
        );
        assert!(text.contains("tophat") && !text.contains("filter-825-52"), "{text}");
        let wide = Source::from_text(text, "tabulated, 200 nm", tabulated.dir());
        for (source, overrides) in [
            (&paper, owned(&[])),
            (
                &paper,
                owned(&[
                    "spectrum.range_nm=200",
                    "camera.pixel_mtf=true",
                    "camera.read_noise_e=2",
                    "options.form=\"integral\"",
                ]),
            ),
            (&tabulated, owned(&[])),
            (&wide, owned(&[])),
        ] {
            check_with_references(source, &overrides, &keys, &|k, v| {
                let h = relative_step(k, v);
                richardson(source, &overrides, k, v, h)
            });
        }
    }

    /// A blackbody's temperature over a band where the OTF depends on direction (docs/physics.md,
    /// "Gradients: a line's wavelength and a blackbody's temperature": along each direction
    /// `∂O/∂T = ⟨g⟩(O_g − O)`, `∂|O| = Re(O* ∂O)/|O|`, on the value's rule over directions), off
    /// axis: the chromatic lens's lateral colour at 5° on a 10 nm band, a lens given as tangential
    /// and sagittal MTF tables (written here, coarse: few kinks for the references' rules) on a
    /// 10 nm band and a PSF stack (examples/psf-stack.toml) on a 4 nm band at 3°, the last two
    /// under a noise spectrum (the weighted mean's lane in ∂ASNR; Planck's ∂ln B/∂T moves N far
    /// more than the OTF, so it is a small share there, the white ∂M̄ checked on its own norm);
    /// against central differences of evaluations converged at 1e-10, Richardson-extrapolated
    /// from the relative steps 2h and h, within 10× the scene's 1e-6 of each quantity's gradient
    /// norm.
    #[test]
    fn a_blackbody_temperature_off_axis_matches_central_differences() {
        let keys = ["source.temperature_k", "exposure.time_ms"];
        let blackbody = |source: &Source, label: &str| {
            let text = source
                .text()
                .replace("kind = \"flat\"", "kind = \"blackbody\"\ntemperature_k = 3000.0\nscale = 2e-3")
                .replace("radiance_w_m2_sr_nm = 0.025", "");
            assert!(text.contains("blackbody") && !text.contains("radiance_w_m2_sr_nm"), "{text}");
            Source::from_text(text, label, source.dir())
        };
        // tangential and sagittal MTF tables, each falling with ν on a scale that grows with λ
        // (every 20 nm from 740 to 860 nm, every 24 cycles/mm to 120: few kinks for the
        // references' rules to resolve)
        let dir = std::env::temp_dir().join(format!("asnr-temperature-ts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut csv = String::from("wavelength_nm,frequency_cyc_per_mm,mtf,sagittal\n");
        for l in (740..=860).step_by(20) {
            for f in (0..=120).step_by(24) {
                let (l, f) = (f64::from(l), f64::from(f));
                let t = (-f / (40.0 + 0.5 * (l - 740.0))).exp();
                let s = (-f / (90.0 - 0.4 * (l - 740.0))).exp();
                csv.push_str(&format!("{l},{f},{t},{s}\n"));
            }
        }
        std::fs::write(dir.join("mtf-ts.csv"), csv).unwrap();
        std::fs::write(dir.join("nps.csv"), "frequency_cyc_per_mm,relative\n0,1\n30,1.4\n70,2.2\n130,3\n").unwrap();
        let mtf_table = Source::from_text(
            "[lens]\nmodel = \"tabulated\"\nmtf = \"mtf-ts.csv\"\nf_number = 2.5\n\
             focal_length_mm = 3.36\ndesign_wavelength_nm = 800.0\nefficiency = 0.15\ntransmission = 0.55\n\
             [source]\nkind = \"flat\"\nradiance_w_m2_sr_nm = 0.025\n[spectrum]\nshape = \"gaussian\"\n\
             center_nm = 800.0\nrange_nm = 50.0\n[camera]\npixel_pitch_um = 5.2\nquantum_efficiency = 0.2\n\
             noise_spectrum = \"nps.csv\"\n[exposure]\ntime_ms = 1.23\n",
            "MTF tables",
            &dir,
        );
        let shaped = blackbody(&with_noise_spectrum_beside(&example("psf-stack.toml"), "temperature-stack"), "shaped");
        for (source, overrides, keys) in [
            (paper_blackbody(), &["spectrum.range_nm=10", "field.x_deg=5"][..], &keys[..]),
            (blackbody(&mtf_table, "MTF tables"), &["spectrum.range_nm=10", "field.x_deg=3"], &keys),
            // the white mean MTF's lane and the weighted mean's (in the ASNR's) together
            (shaped, &["spectrum.range_nm=4", "field.x_deg=3"], &keys[..1]),
        ] {
            let overrides = owned(overrides);
            let started = std::time::Instant::now();
            check_with_references(&source, &overrides, keys, &|k, v| {
                let h = relative_step(k, v);
                let (coarse, fine) =
                    (central(&source, &overrides, k, v, 2.0 * h), central(&source, &overrides, k, v, h));
                std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0)
            });
            println!("{}: {:?}", source.label(), started.elapsed());
        }
    }

    /// A blackbody's temperature over a band where the pupil is sampled on the FFT path
    /// (docs/physics.md, "Gradients: a line's wavelength and a blackbody's temperature": the
    /// engines of ρ and ρ ∂ln B/∂T at the value's sampling, `∂O/∂T = ⟨g⟩(O_g − O)` along each
    /// direction): the Binary 2 phase lens at 5° off axis (the oblique wave's coma and
    /// astigmatism), on axis with a Z6 and the pixel MTF, and off axis under a noise spectrum (the
    /// weighted mean's lane in ∂ASNR), each on a 10 nm band at a fixed sampling
    /// (`options.pupil_samples = 64`: the grids are the same at every temperature, which moves
    /// the spectral weights alone), against Richardson-extrapolated central differences (relative
    /// steps 2h and h, h = (3e-10)^{1/3} T) of evaluations at 1e-9, within 10× the scene's 1e-6
    /// of each quantity's gradient (N within 1e-9).
    #[test]
    fn a_blackbody_temperature_on_the_fft_path_matches_central_differences() {
        let phase = example("phase-binary2.toml");
        let text = phase
            .text()
            .replace("kind = \"flat\"", "kind = \"blackbody\"\ntemperature_k = 3000.0\nscale = 2e-3")
            .replace("radiance_w_m2_sr_nm = 0.025", "");
        assert!(text.contains("blackbody") && !text.contains("radiance_w_m2_sr_nm"), "{text}");
        let blackbody = Source::from_text(text, "the Binary 2 lens lit by a blackbody", phase.dir());
        let noisy = with_noise_spectrum_beside(&blackbody, "temperature-fft");
        let step = |_: &str| (3.0 * REFERENCE_TOLERANCE).cbrt() * 3000.0;
        for (source, overrides) in [
            (&blackbody, &["field.x_deg=5"][..]),
            (&blackbody, &["lens.zernike_noll_rms_um=[0, 0, 0, 0, 0, 0.03]", "camera.pixel_mtf=true"]),
            (&noisy, &["field.x_deg=5"]),
        ] {
            let mut set = vec!["spectrum.range_nm=10", "options.pupil_samples=64"];
            set.extend(overrides);
            let e = metric::evaluate(&scene::build_from(source, &owned(&set)).unwrap()).unwrap();
            assert!(e.numerics.engine.starts_with("fft"), "{}", e.numerics.engine);
            let started = std::time::Instant::now();
            check_directional_spectrum(
                source,
                &set,
                &["source.temperature_k"],
                (Some(1e-6), 1e-6),
                &["options.tolerance=1e-9"],
                &step,
            );
            println!("{overrides:?}: {:?}", started.elapsed());
        }
    }

    /// The Gaussian spectrum's centre and range: they move N and the OTF's spectral weights
    /// (the engine's OTFs of ρλ and ρλ², docs/physics.md "Gradients"). The value varies on the
    /// scale of σ = range/(2√2), not of the key's value, so the step is (3e-10)^{1/3} σ
    /// (h/σ ≈ 6.7e-4: truncation and rounding both ~1e-7 relative). On the paper's chromatic
    /// lens (the closed form) in both forms and with the pixel MTF, and on the Binary 2 lens
    /// (the radial engine), within 10× the tolerance (1e-6) of the gradient's norm.
    #[test]
    fn spectral_keys_match_central_differences() {
        let keys = ["spectrum.center_nm", "spectrum.range_nm", "exposure.time_ms"];
        let sigma = |range_nm: f64| range_nm / (2.0 * std::f64::consts::SQRT_2);
        for (source, overrides, range) in [
            (scene::read(None).unwrap(), owned(&[]), 50.0),
            (
                scene::read(None).unwrap(),
                owned(&["options.form=\"integral\"", "camera.pixel_mtf=true", "spectrum.range_nm=100"]),
                100.0,
            ),
            (example("phase-binary2.toml"), owned(&["camera.read_noise_e=2"]), 50.0),
        ] {
            let step = move |k: &str, v: f64| {
                if k.starts_with("spectrum.") {
                    (3.0 * REFERENCE_TOLERANCE).cbrt() * sigma(range)
                } else {
                    relative_step(k, v)
                }
            };
            check_with_steps(&source, &overrides, &keys, &step);
        }
    }

    /// The band's spectral keys with the stray light (`options.glare = "included"`: the noise
    /// budget's background `B = N_T − N`, the transmitted light's derivative its own average over
    /// `ρ T`, docs/physics.md "Gradients: the transmitted light over a band") against central
    /// differences of evaluations converged at 1e-10, within 10× the scene's 1e-6 of each
    /// quantity's gradient norm: the paper's chromatic lens (constant τ1 and T) behind its
    /// Gaussian band with a read noise and in the integral form, behind a 120 nm top-hat;
    /// examples/paper-simulated.toml (τ1 and T tables, folded into the spectrum); the Binary 2
    /// lens on the radial engine. The step as [`spectral_keys_match_central_differences`]'.
    #[test]
    fn spectral_keys_with_the_stray_light_match_central_differences() {
        let keys = ["spectrum.center_nm", "spectrum.range_nm", "exposure.time_ms"];
        let glare = "options.glare=\"included\"";
        for (source, overrides, scale) in [
            (scene::read(None).unwrap(), owned(&INTEGRAL_WITH_GLARE), 50.0 / (2.0 * std::f64::consts::SQRT_2)),
            (
                scene::read(None).unwrap(),
                owned(&[glare, "spectrum.shape=\"tophat\"", "spectrum.range_nm=120", "camera.read_noise_e=2"]),
                120.0,
            ),
            (example("paper-simulated.toml"), owned(&[glare]), 50.0 / (2.0 * std::f64::consts::SQRT_2)),
            (example("phase-binary2.toml"), owned(&[glare]), 50.0 / (2.0 * std::f64::consts::SQRT_2)),
        ] {
            let step = move |k: &str, v: f64| {
                if k.starts_with("spectrum.") {
                    (3.0 * REFERENCE_TOLERANCE).cbrt() * scale
                } else {
                    relative_step(k, v)
                }
            };
            // the stray light is there: N_T > N
            let g = gradient(&source, &overrides, &owned(&keys)).unwrap();
            assert!(g.snr0 < g.photoelectrons.sqrt() * 0.99, "{} vs √N {}", g.snr0, g.photoelectrons.sqrt());
            check_with_steps(&source, &overrides, &keys, &step);
        }
    }

    /// A blackbody's temperature over a band with the stray light (`options.glare =
    /// "included"`): N_T's own average of ∂ln B/∂T over `ρ T`; the paper's lens behind its 50 nm
    /// band and examples/tabulated.toml (a lamp behind its filter table, τ1, T and QE tables),
    /// against the Richardson-extrapolated central differences of
    /// [`a_blackbody_temperature_over_a_band_matches_central_differences`].
    #[test]
    fn a_blackbody_temperature_over_a_band_with_the_stray_light_matches_central_differences() {
        let keys = ["source.temperature_k", "exposure.time_ms"];
        let glare = owned(&["options.glare=\"included\"", "camera.read_noise_e=2"]);
        for source in [paper_blackbody(), example("tabulated.toml")] {
            let g = gradient(&source, &glare, &owned(&keys)).unwrap();
            assert!(g.snr0 < g.photoelectrons.sqrt() * 0.99, "{} vs √N {}", g.snr0, g.photoelectrons.sqrt());
            check_with_references(&source, &glare, &keys, &|k, v| {
                let h = relative_step(k, v);
                richardson(&source, &glare, k, v, h)
            });
        }
    }

    /// A line's wavelength and equivalent width, with the keys `others` (docs/physics.md,
    /// "Gradients: a line's wavelength"), against central differences of evaluations converged
    /// at 1e-10: the width (N ∝ r) and the other keys with the relative step, the wavelength
    /// Richardson-extrapolated from the steps 2h and h, h = [`LINE_STEP_NM`]
    /// (`(4 D(h) − D(2h))/3`, truncation O(h⁴)), within 10× the scene's 1e-6 of the gradient's
    /// norm.
    fn check_line(source: &Source, overrides: &[String], others: &[&str]) {
        let mut keys = vec!["spectrum.center_nm", "spectrum.range_nm"];
        keys.extend_from_slice(others);
        check_with_references(source, overrides, &keys, &|k, v| {
            if k != "spectrum.center_nm" {
                return central(source, overrides, k, v, relative_step(k, v));
            }
            let (coarse, fine) =
                (central(source, overrides, k, v, 2.0 * LINE_STEP_NM), central(source, overrides, k, v, LINE_STEP_NM));
            std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0)
        });
    }

    /// The step of a line's wavelength, nm. The paper's aperture defocuses by
    /// `f0/(8F#²λ0) ≈ 84` waves per unit of `λ/λ0`, about 0.1 wave per nm, so the OTF at the
    /// line turns on a scale of a few nm (not of the wavelength's 803): with that scale L ≈ 2 nm,
    /// h = (3e-10)^{1/3} L ≈ 1.3e-3 nm balances truncation and the evaluations' 1e-10, and the
    /// extrapolation leaves rounding alone (~1e-10 · 2L/h ≈ 3e-7 of the derivative).
    const LINE_STEP_NM: f64 = 2e-3;

    /// The line at 803 nm on the paper's chromatic lens (a defocus W020(λ) affine in λ: the line
    /// engine's defocus lane) alone, with the pixel MTF and read noise, and in the integral form
    /// with the stray light; a QE table and a Gaussian filter under the line (their slopes in
    /// the photon count); and a refractive lens without dispersion (the frequency scaling alone).
    #[test]
    fn a_line_on_the_chromatic_lens_matches_central_differences() {
        let paper = scene::read(None).unwrap();
        check_line(&paper, &owned(&LINE_803), &["exposure.time_ms"]);
        check_line(&paper, &joined(&LINE_803, &PIXEL_AND_READ_NOISE), &["exposure.time_ms"]);
        check_line(&paper, &joined(&LINE_803, &INTEGRAL_WITH_GLARE), &["exposure.time_ms"]);
        // at the design wavelength (W020 = 0: the frequency scaling alone)
        check_line(&paper, &owned(&["spectrum.shape=\"line\"", "spectrum.center_nm=800", "spectrum.range_nm=2"]), &[]);
    }

    /// A line off axis on the chromatic lens (docs/physics.md, "Gradients: a line's wavelength off
    /// axis"): its one order at one wavelength, the lateral colour a phase of the whole OTF, so
    /// |O| and its derivative in c are the order's on axis (the value's tangential and sagittal
    /// means both that). At 803 nm at (5°, 3°) with the pixel MTF and read noise, at 8° in the
    /// integral form with the stray light, and at the design wavelength at 5° (the shift 0 there,
    /// its rate in c not: examples/monochromatic.toml).
    #[test]
    fn a_line_off_axis_on_the_chromatic_lens_matches_central_differences() {
        let paper = scene::read(None).unwrap();
        check_line(
            &paper,
            &joined(&LINE_803, &["field.x_deg=5", "field.y_deg=3", "camera.pixel_mtf=true", "camera.read_noise_e=2"]),
            &["exposure.time_ms"],
        );
        check_line(&paper, &joined(&LINE_803, &["field.x_deg=8", INTEGRAL_WITH_GLARE[0], INTEGRAL_WITH_GLARE[1]]), &[]);
        check_line(&example("monochromatic.toml"), &owned(&["field.x_deg=5"]), &["field.x_deg"]);
    }

    /// A line through the decentred iris (docs/physics.md, "Gradients: a line's wavelength
    /// through an iris": the line engine's defocus lane over azimuth, the iris's tilt
    /// `W020 (2d/NA)` moving with `W020(c)`): examples/decentred-iris.toml at 803 nm on axis with
    /// the exposure, at (3°, 1°) with the pixel MTF and read noise (the lateral colour beside the
    /// tilt), and on axis under a noise spectrum (the weight moving the gradient:
    /// [`assert_weighted`]), each against Richardson central differences of evaluations
    /// converged at 1e-10.
    #[test]
    fn a_line_through_a_decentred_iris_matches_central_differences() {
        let iris = example("decentred-iris.toml");
        check_line(&iris, &owned(&LINE_803), &["exposure.time_ms"]);
        check_line(
            &iris,
            &joined(&LINE_803, &["field.x_deg=3", "field.y_deg=1", PIXEL_AND_READ_NOISE[0], PIXEL_AND_READ_NOISE[1]]),
            &[],
        );
        let shaped = with_noise_spectrum(&iris, "line-iris");
        let line = owned(&LINE_803);
        let center = ["spectrum.center_nm"];
        assert_weighted(&gradient(&shaped, &line, &owned(&center)).unwrap());
        check_with_references(&shaped, &line, &center, &|k, v| richardson(&shaped, &line, k, v, LINE_STEP_NM));
    }

    /// A line on the interleaved multiplexed lens (docs/physics.md, "Gradients: a line's
    /// wavelength": on axis each channel's order `W020_j = (1 − λ/λ_j) f0/(8F#²)` moving by its
    /// own `−f0/(8F#² λ_j)`, the line engine's order lane; off axis "several orders under a line
    /// off axis"): the three channels of examples/designs.toml (750/800/850 nm) in the paper's
    /// scene at 803 nm with the exposure, with the pixel MTF and read noise, at 3°, and under a
    /// noise spectrum on axis (the weight moving the gradient: [`assert_weighted`]).
    #[test]
    fn a_line_on_the_interleaved_lens_matches_central_differences() {
        let paper = scene::read(None).unwrap();
        let rest = paper.text().split_once("[source]").unwrap().1;
        let interleaved = Source::from_text(
            format!(
                "title = \"interleaved\"\n[lens]\nmodel = \"multiplexed\"\nlayout = \"interleaved\"\nf_number = 2.5\n\
                 focal_length_mm = 3.36\nchannels_nm = [750.0, 800.0, 850.0]\nefficiency = 0.15\ntransmission = 0.55\n\n\
                 [source]{rest}"
            ),
            "multiplexed lens written in the test",
            ".",
        );
        check_line(&interleaved, &owned(&LINE_803), &["exposure.time_ms"]);
        check_line(&interleaved, &joined(&LINE_803, &PIXEL_AND_READ_NOISE), &[]);
        // off axis at 3°: each channel turned by its own lateral colour f0 tan θ (λ_j/λ − 1),
        // the orders functions of λ/λ_j alone (the line engine's lanes over azimuth)
        check_line(&interleaved, &joined(&LINE_803, &["field.x_deg=3"]), &[]);
        let shaped = with_noise_spectrum(&interleaved, "line-interleaved");
        let line = owned(&LINE_803);
        let center = ["spectrum.center_nm"];
        assert_weighted(&gradient(&shaped, &line, &owned(&center)).unwrap());
        check_with_references(&shaped, &line, &center, &|k, v| richardson(&shaped, &line, k, v, LINE_STEP_NM));
    }

    /// The Binary 2 lens (the radial engine's wavelength lanes: the sphere's phase 2πS/λ turns,
    /// the radian profile of a geometric phase stays) under a line at 803 nm, with read noise,
    /// with its Binary 2 coefficients and the F-number asked beside (the lanes stacked), and as
    /// a refractive profile of N-BK7 (the glass's n′(λ) on the profile).
    #[test]
    fn a_line_on_the_binary2_lens_matches_central_differences() {
        let binary2 = example("phase-binary2.toml");
        check_line(&binary2, &owned(&LINE_803), &["exposure.time_ms"]);
        check_line(&binary2, &joined(&LINE_803, &["camera.read_noise_e=2"]), &["lens.binary2[1]"]);
        check_line(&binary2, &joined(&LINE_803, &["lens.dispersion=\"refractive\"", "lens.glass=\"N-BK7\""]), &[]);
        // the F-number's lanes and the wavelength's on one pass: each as when asked alone
        let both = gradient(&binary2, &owned(&LINE_803), &owned(&["lens.f_number", "spectrum.center_nm"])).unwrap();
        let alone = gradient(&binary2, &owned(&LINE_803), &owned(&["spectrum.center_nm"])).unwrap();
        assert!((both.d_asnr[1] - alone.d_asnr[0]).abs() <= 1e-12 * alone.d_asnr[0].abs(), "{both:?} {alone:?}");
    }

    /// The refractive singlet of N-BK7 (uncoated: its Fresnel losses move N with n(λ) too; the
    /// defocus W020 ∝ n0 − n(λ) through n′) under a line at 650 nm, and with the pixel MTF and
    /// read noise.
    #[test]
    fn a_line_on_the_refractive_lens_matches_central_differences() {
        let singlet = refractive_singlet();
        let line = ["spectrum.shape=\"line\"", "spectrum.center_nm=650", "spectrum.range_nm=1"];
        check_line(&singlet, &owned(&line), &["exposure.time_ms"]);
        check_line(&singlet, &joined(&line, &PIXEL_AND_READ_NOISE), &[]);
    }

    /// The harmonic lens of design order 5 (six orders whose efficiencies τ_base sinc²(pλ0/λ − m)
    /// move against each other and whose defocus moves each by its own m: the line engine's
    /// order lane) under a line at 803 nm, alone and with the pixel MTF and read noise, in the
    /// integral form with the stray light, and with the F-number asked beside.
    #[test]
    fn a_line_on_the_harmonic_lens_matches_central_differences() {
        let harmonic = example("harmonic.toml");
        check_line(&harmonic, &owned(&LINE_803), &["exposure.time_ms"]);
        check_line(&harmonic, &joined(&LINE_803, &PIXEL_AND_READ_NOISE), &["lens.f_number"]);
        check_line(&harmonic, &joined(&LINE_803, &INTEGRAL_WITH_GLARE), &[]);
    }

    /// Several orders under a line off axis (docs/physics.md, "Gradients: several orders under a
    /// line off axis"): the harmonic lens's six orders at 803 nm, each turned by its own lateral
    /// colour `f0 tan θ (pλ0/(mλ) − 1)`, the line's wavelength and the design wavelength (the
    /// line engine's lanes over azimuth) with the exposure, against central differences of
    /// evaluations converged at 1e-10, Richardson-extrapolated from the steps 2h and h,
    /// h = [`LINE_STEP_NM`], within 10× the scene's 1e-6 of the gradient's norm: at 3° along x,
    /// and at (3°, 2°) with the pixel MTF and read noise; and the design wavelength at 3° under a
    /// noise spectrum (the weight moving the gradient: [`assert_weighted`]).
    #[test]
    fn a_line_off_axis_on_the_harmonic_lens_matches_central_differences() {
        let harmonic = example("harmonic.toml");
        let keys = ["spectrum.center_nm", "lens.design_wavelength_nm", "exposure.time_ms"];
        let fields = [
            joined(&LINE_803, &["field.x_deg=3"]),
            joined(&LINE_803, &["field.x_deg=3", "field.y_deg=2", PIXEL_AND_READ_NOISE[0], PIXEL_AND_READ_NOISE[1]]),
        ];
        for overrides in &fields {
            check_with_references(&harmonic, overrides, &keys, &|k, v| {
                let h = if k == keys[2] { relative_step(k, v) } else { LINE_STEP_NM };
                richardson(&harmonic, overrides, k, v, h)
            });
        }
        // the design wavelength under a noise spectrum: the same lanes, each frequency's weight
        // divided by n(ν)
        let shaped = with_noise_spectrum(&harmonic, "line-orders");
        let design = ["lens.design_wavelength_nm"];
        assert_weighted(&gradient(&shaped, &fields[0], &owned(&design)).unwrap());
        check_with_references(&shaped, &fields[0], &design, &|k, v| {
            richardson(&shaped, &fields[0], k, v, LINE_STEP_NM)
        });
    }

    /// The field angles, the F-number and the focal length under a line off axis on several
    /// orders each turned by its own lateral colour (docs/physics.md, "Gradients: the field point
    /// under a line"): the interleaved lens's three channels (750/800/850 nm, examples/designs.toml)
    /// under a 10 nm line at 800 nm at (3°, 2°) with the pixel MTF, and the harmonic lens's orders
    /// at 803 nm at (3°, 2°), whose field gradient is 4.5e-7 of the mean MTF per degree (its other
    /// orders' weights small near the design wavelength); the gradient at 1e-3 against Richardson
    /// central differences (steps 0.04° and 0.02°; 0.004 and 0.002 for F# and f0 in mm) of
    /// evaluations converged to 1e-10, within 10× 1e-3 of the norm (F# and f0 on the interleaved
    /// lens).
    #[test]
    fn field_angles_and_aperture_under_a_line_on_several_orders_match_central_differences() {
        let paper = scene::read(None).unwrap();
        let rest = paper.text().split_once("[source]").unwrap().1;
        let interleaved = Source::from_text(
            format!(
                "title = \"interleaved\"\n[lens]\nmodel = \"multiplexed\"\nlayout = \"interleaved\"\nf_number = 2.5\n\
                 focal_length_mm = 3.36\nchannels_nm = [750.0, 800.0, 850.0]\nefficiency = 0.15\ntransmission = 0.55\n\n\
                 [source]{rest}"
            ),
            "multiplexed lens written in the test",
            ".",
        );
        let interleaved_at = [
            "spectrum.shape=\"line\"",
            "spectrum.center_nm=800",
            "spectrum.range_nm=10",
            "field.x_deg=3",
            "field.y_deg=2",
            "camera.pixel_mtf=true",
        ];
        let harmonic = example("harmonic.toml");
        let harmonic_at = [LINE_803[0], LINE_803[1], LINE_803[2], "field.x_deg=3", "field.y_deg=2"];
        for (source, overrides) in [(&interleaved, &interleaved_at[..]), (&harmonic, &harmonic_at[..])] {
            let g = check_field_of(source, overrides, &["field.x_deg", "field.y_deg"], 0.02, 1e-3);
            assert!(g.d_mean_mtf.iter().all(|d| *d < 0.0), "{g:?}");
        }
        // F# and f0 on the same lanes, on the interleaved lens (the harmonic lens's take the same
        // formula; checked by hand, docs/physics.md)
        check_field_of(&interleaved, &interleaved_at, &["lens.f_number", "lens.focal_length_mm"], 0.002, 1e-3);
    }

    /// The families and scenes whose line's wavelength is not followed are refused naming why:
    /// a diffractive phase profile, the chromatic lens through an iris with an efficiency table,
    /// a line on a table's sample.
    #[test]
    fn a_line_wavelength_refusals_name_why() {
        let keys = owned(&["spectrum.center_nm"]);
        let line = owned(&LINE_803);
        let mut diffractive = line.clone();
        diffractive.extend(owned(&["lens.dispersion=\"diffractive\"", "lens.design_order=2"]));
        let e = gradient(&example("phase-binary2.toml"), &diffractive, &keys).unwrap_err().to_string();
        assert!(e.contains("diffractive") && e.contains("sinc"), "{e}");
        // the chromatic lens through an iris with an efficiency table (its slope has kinks at
        // the rows: the lens gives no rates in λ)
        let mut iris_table = line.clone();
        iris_table.push("lens.efficiency=\"data/metalens-efficiency.csv\"".to_owned());
        let e = gradient(&example("decentred-iris.toml"), &iris_table, &keys).unwrap_err().to_string();
        assert!(e.contains("not differentiable"), "{e}");
        // the width alone is followed everywhere: N ∝ r
        let g = gradient(&example("harmonic.toml"), &line, &owned(&["spectrum.range_nm"])).unwrap();
        assert!((g.d_photoelectrons[0] - g.photoelectrons / g.values[0]).abs() <= 1e-14 * g.d_photoelectrons[0]);
        assert_eq!(g.d_mean_mtf[0], 0.0);
    }

    /// A top-hat's centre and range (docs/physics.md, "Gradients: a top-hat's edges": Leibniz's
    /// rule, the single-wavelength OTFs at the two edges against the normalization's own terms)
    /// against central differences of evaluations converged at 1e-10, within 10× the scene's
    /// 1e-6 of the gradient's norm: the paper's lens at 50 and 120 nm (with the pixel MTF and
    /// read noise at 120 nm: the OTF changes sign below Nyquist there) and the Binary 2 lens. The step
    /// (3 · 1e-10)^{1/3} × the range (the value varies on the scale of the band, as for the
    /// Gaussian's σ).
    #[test]
    fn top_hat_edges_match_central_differences() {
        let keys = ["spectrum.center_nm", "spectrum.range_nm", "exposure.time_ms"];
        for (source, overrides, range) in [
            (scene::read(None).unwrap(), owned(&["spectrum.shape=\"tophat\""]), 50.0),
            (
                scene::read(None).unwrap(),
                owned(&[
                    "spectrum.shape=\"tophat\"",
                    "spectrum.range_nm=120",
                    "camera.pixel_mtf=true",
                    "camera.read_noise_e=2",
                ]),
                120.0,
            ),
            (example("phase-binary2.toml"), owned(&["spectrum.shape=\"tophat\""]), 50.0),
        ] {
            let step = move |k: &str, v: f64| {
                if k.starts_with("spectrum.") {
                    (3.0 * REFERENCE_TOLERANCE).cbrt() * range
                } else {
                    relative_step(k, v)
                }
            };
            check_with_steps(&source, &overrides, &keys, &step);
        }
    }

    /// The spectral keys `keys` of `source` with `overrides` where the OTF depends on direction
    /// (docs/physics.md, "Gradients: the spectrum where the OTF depends on direction"), asked at
    /// the tolerance `tolerance` (set as `options.tolerance` where given; else the scene's, 1e-6,
    /// and 1e-4 on the FFT path and the overlap engine), against central differences of
    /// evaluations with `reference` (overrides such as `options.tolerance=1e-10`: the tightest
    /// the engine reaches), Richardson-extrapolated from the steps 2h and h
    /// (`(4 D(h) − D(2h))/3`, truncation O(h⁴)), `h = step(key)`: the ASNR's and the mean MTF's
    /// relative sensitivities ∂/∂ln key within 10× `tolerance` of their norms, N's within 1e-9.
    /// Returns the gradient.
    fn check_directional_spectrum(
        source: &Source,
        overrides: &[&str],
        keys: &[&str],
        tolerance: (Option<f64>, f64),
        reference: &[&str],
        step: &dyn Fn(&str) -> f64,
    ) -> Gradient {
        let (asked, allowed) = tolerance;
        let mut set = owned(overrides);
        if let Some(t) = asked {
            set.push(format!("options.tolerance={t:e}"));
        }
        let g = gradient(source, &set, &owned(keys)).unwrap();
        let with_reference = joined(overrides, reference);
        let evaluated = |k: &str, v: f64| {
            let mut s: Vec<String> = with_reference
                .iter()
                .filter(|o| o.split_once('=').is_none_or(|(key, _)| key.trim() != k))
                .cloned()
                .collect();
            s.push(assignment(k, v));
            let e = metric::evaluate(&scene::build_from(source, &s).unwrap()).unwrap();
            [e.asnr, e.mean_mtf, e.photoelectrons]
        };
        let differences = |k: &str, v: f64, h: f64| -> [f64; 3] {
            let (up, down) = (evaluated(k, v + h), evaluated(k, v - h));
            std::array::from_fn(|q| (up[q] - down[q]) / (2.0 * h))
        };
        let theirs: Vec<[f64; 3]> = g
            .keys
            .iter()
            .zip(&g.values)
            .map(|(k, &v)| {
                let h = step(k);
                let (fine, coarse) = (differences(k, v, h), differences(k, v, 2.0 * h));
                std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0)
            })
            .collect();
        for (q, (name, ours)) in
            [("ASNR", &g.d_asnr), ("mean MTF", &g.d_mean_mtf), ("N", &g.d_photoelectrons)].into_iter().enumerate()
        {
            let mine: Vec<f64> = ours.iter().zip(&g.values).map(|(d, v)| d * v).collect();
            let norm = mine.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(norm > 0.0, "{name}: a zero gradient {g:?}");
            let bound = if q == 2 { 1e-9 } else { 10.0 * allowed };
            for (i, k) in g.keys.iter().enumerate() {
                let reference = theirs[i][q] * g.values[i];
                let error = (mine[i] - reference).abs() / norm;
                println!("{name} {k}: gradient {:.9e}, differences {reference:.9e}, error/norm {error:.1e}", mine[i]);
                assert!(error <= bound, "{name} {k}: {} vs {reference} (norm {norm})", mine[i]);
            }
        }
        g
    }

    /// The step for the spectral keys of a band of range `range_nm`: (3 · 1e-10)^{1/3} times its
    /// scale (σ = range/(2√2) for a Gaussian, the range for a top-hat), as for the symmetric OTF.
    fn spectral_step(range_nm: f64, gaussian: bool) -> impl Fn(&str) -> f64 {
        let scale = if gaussian { range_nm / (2.0 * std::f64::consts::SQRT_2) } else { range_nm };
        move |_: &str| (3.0 * REFERENCE_TOLERANCE).cbrt() * scale
    }

    /// Lateral colour (the paper's lens at 5° off axis, the exact 1-D engine's complex sum: the
    /// tangential and sagittal means) for a Gaussian band with and without the pixel MTF and for
    /// a top-hat, and the decentred iris (the exact engine's complex sum of its reduced circle),
    /// at the scene's 1e-6 against differences converged at 1e-10.
    #[test]
    fn spectral_keys_with_lateral_colour_and_a_decentred_iris_match_central_differences() {
        let paper = scene::read(None).unwrap();
        let keys = ["spectrum.center_nm", "spectrum.range_nm"];
        let converged = ["options.tolerance=1e-10"];
        for (overrides, gaussian) in [
            (&["field.x_deg=5"][..], true),
            (&["field.x_deg=3", "field.y_deg=4", "camera.pixel_mtf=true", "options.form=\"integral\""][..], true),
            (&["field.x_deg=5", "spectrum.shape=\"tophat\""][..], false),
        ] {
            check_directional_spectrum(
                &paper,
                overrides,
                &keys,
                (None, 1e-6),
                &converged,
                &spectral_step(50.0, gaussian),
            );
            let e = metric::evaluate(&scene::build_from(&paper, &owned(overrides)).unwrap()).unwrap();
            assert!(e.numerics.engine.contains("lateral colour"), "{}", e.numerics.engine);
        }
        check_directional_spectrum(
            &example("decentred-iris.toml"),
            &[],
            &keys,
            (None, 1e-6),
            &converged,
            &spectral_step(50.0, true),
        );
    }

    /// A broad band (200 nm, σ = 70.7 nm: the lanes' weights `(λ − c)/σ²` and `(λ − c)²/σ³`
    /// reach ±7σ = ±495 nm, where the band's product-integration nodes must resolve them) with
    /// lateral colour at 5° (the exact 1-D engine's tangential and sagittal means) and through
    /// the decentred iris, at the scene's 1e-6 against differences converged at 1e-10, within 10×
    /// the tolerance of the gradient's norm (docs/physics.md, "Gradients: the spectrum where the
    /// OTF depends on direction").
    #[test]
    fn spectral_keys_of_a_broad_band_with_lateral_colour_and_an_iris_match_central_differences() {
        let keys = ["spectrum.center_nm", "spectrum.range_nm"];
        let converged = ["options.tolerance=1e-10"];
        for (source, overrides) in [
            (scene::read(None).unwrap(), &["field.x_deg=5", "spectrum.range_nm=200"][..]),
            (example("decentred-iris.toml"), &["spectrum.range_nm=200"][..]),
        ] {
            let e = metric::evaluate(&scene::build_from(&source, &owned(overrides)).unwrap()).unwrap();
            assert!(e.numerics.engine.starts_with("exact-1d"), "{}", e.numerics.engine);
            check_directional_spectrum(
                &source,
                overrides,
                &keys,
                (None, 1e-6),
                &converged,
                &spectral_step(200.0, true),
            );
        }
    }

    /// The overlap engine (a Seidel coma of 0.3 µm on the paper's lens: the mean over azimuth of
    /// the overlap quadrature's complex OTF; a 4 nm band so that the references at 1e-10 take
    /// seconds), asked at 1e-6; and a PSF stack (examples/psf-stack.toml: each slice's OTF with
    /// its centroid's shift, linear in λ between the slices), asked at the scene's 1e-6 with the
    /// band centred at 802.5 nm, between slices: a Gaussian of 20 nm (its value is smooth in c
    /// and σ, the convolution of the stack's continuous piecewise-linear OTF with a smooth band),
    /// and a top-hat of 20 nm, its edges at 792.5 and 812.5 nm, between slices (its value is C¹
    /// in the edges: its derivative is the OTF at the edge, whose slope jumps where an edge
    /// crosses a slice, so a difference straddling a slice would see that kink).
    #[test]
    fn spectral_keys_on_the_overlap_engine_and_a_psf_stack_match_central_differences() {
        let keys = ["spectrum.center_nm", "spectrum.range_nm"];
        let converged = ["options.tolerance=1e-10"];
        let paper = scene::read(None).unwrap();
        let coma = ["lens.coma_um=0.3", "spectrum.range_nm=4"];
        let e = metric::evaluate(&scene::build_from(&paper, &owned(&coma)).unwrap()).unwrap();
        assert!(e.numerics.engine.starts_with("overlap"), "{}", e.numerics.engine);
        check_directional_spectrum(&paper, &coma, &keys, (Some(1e-6), 1e-6), &converged, &spectral_step(4.0, true));
        let stack = example("psf-stack.toml");
        for (overrides, range, gaussian) in [
            (&["spectrum.center_nm=802.5", "spectrum.range_nm=20"][..], 20.0, true),
            (&["spectrum.center_nm=802.5", "spectrum.range_nm=20", "spectrum.shape=\"tophat\""][..], 20.0, false),
        ] {
            check_directional_spectrum(
                &stack,
                overrides,
                &keys,
                (None, 1e-6),
                &converged,
                &spectral_step(range, gaussian),
            );
        }
    }

    /// The FFT path: the cubic-phase map of examples/phase-map-cubic.toml (its formula, written
    /// here on 1 µm cells, 1344 × 1344; a 10 nm band) with the pupil sampling fixed
    /// (`options.pupil_samples = 256`), so that the gradient and the differences are of one
    /// discrete rule (the grids, their interpolation, the azimuths), smooth in c; asked at
    /// 1e-6, the references at 1e-9 (the spectral nodes' tolerance there; each node's grid is
    /// exact to rounding at its sampling).
    #[test]
    fn spectral_keys_on_the_fft_path_of_a_phase_map_match_central_differences() {
        let bytes = scene::npy::hyperbolic_cubic_map(1344, 1e-6, 3.36e-3, 800e-9, 0.672e-3, 30.0);
        let dir = std::env::temp_dir().join(format!("asnr-spectral-map-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("cubic.npy"), &bytes).unwrap();
        let text = example("phase-map-cubic.toml")
            .text()
            .replace("\"../target/phase-maps/cubic-f2.5.npy\"", "\"cubic.npy\"")
            .replace("phase_map_pitch_um = 0.5", "phase_map_pitch_um = 1.0");
        assert!(text.contains("\"cubic.npy\"") && text.contains("pitch_um = 1.0"), "{text}");
        let source = Source::from_text(text, "the cubic phase map on 1 µm cells", &dir);
        let fixed = ["spectrum.range_nm=10", "options.pupil_samples=256"];
        let e = metric::evaluate(&scene::build_from(&source, &owned(&fixed)).unwrap()).unwrap();
        assert!(e.numerics.engine.starts_with("fft"), "{}", e.numerics.engine);
        check_directional_spectrum(
            &source,
            &fixed,
            &["spectrum.center_nm", "spectrum.range_nm"],
            (Some(1e-6), 1e-6),
            &["options.tolerance=1e-9"],
            &spectral_step(10.0, true),
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A small phase map in a scene of its own, written into `dir` (docs/physics.md, "Gradients: a
    /// phase map's pitch and aperture"): 16 × 16 cells of 0.5 µm holding the hyperbola of
    /// f0 = 18 µm at λ0 = 800 nm plus the smooth term `0.8 ((x/R)² + (y/R)³)` (radians, R = 3.6 µm,
    /// the aperture's radius at F/2.5: the circle inside the map's 4 µm half width), wrapped to
    /// [0, 2π) (a geometric phase), on a 4 nm band and pixels of 1.2 µm (Nyquist 417 cycles/mm,
    /// the cutoff 1/(λF#) 500).
    fn small_phase_map(dir: &std::path::Path) -> Source {
        let (n, pitch, f0, lambda0, radius) = (16usize, 0.5e-6, 18e-6, 800e-9, 3.6e-6);
        let k0 = std::f64::consts::TAU / lambda0;
        let centre = |k: usize| (k as f64 - 0.5 * (n as f64 - 1.0)) * pitch;
        let mut values = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (centre(i), centre(j));
                let phase =
                    -k0 * ((x * x + y * y + f0 * f0).sqrt() - f0) + 0.8 * ((x / radius).powi(2) + (y / radius).powi(3));
                values.push(phase.rem_euclid(std::f64::consts::TAU));
            }
        }
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join("small.npy"), scene::npy::npy_f64(&[n, n], &values).unwrap()).unwrap();
        let text = "title = \"a 16 × 16 phase map\"\n\
            [lens]\nmodel = \"phase\"\nf_number = 2.5\nfocal_length_mm = 0.018\ndesign_wavelength_nm = 800.0\n\
            phase_map = \"small.npy\"\nphase_map_pitch_um = 0.5\ndispersion = \"geometric-phase\"\n\
            efficiency = 0.15\ntransmission = 0.55\n\
            [source]\nkind = \"flat\"\nradiance_w_m2_sr_nm = 0.025\n\
            [spectrum]\nshape = \"gaussian\"\ncenter_nm = 800.0\nrange_nm = 4.0\npeak = 1.0\n\
            [camera]\npixel_pitch_um = 1.2\npixel_mtf = false\nquantum_efficiency = 0.2\n\
            [exposure]\ntime_ms = 1.23\n\
            [options]\nform = \"mean\"\n";
        Source::from_text(text.to_owned(), "a small phase map written in the test", dir)
    }

    /// A phase map's pitch, F-number and focal length (docs/physics.md, "Gradients: a phase map's
    /// pitch and aperture": its cells' edges and values on the FFT path, the frequency scale, N ∝
    /// 1/F#²) on [`small_phase_map`], at 512 pupil samples and the tolerance 1e-3, against central
    /// differences (relative step 0.01) of evaluations at the same sampling: within 10× the
    /// tolerance of each quantity's gradient norm. At a fixed sampling the value is a step
    /// function of p and R (each sample reads the cell holding its centre), within about 1e-4 of
    /// the converged value here, so the step is wide enough that its steps fall below the check's
    /// bound (measured: 2.2e-3 of the norm at most at 512 samples, 2.0e-3 at 1024).
    #[test]
    fn phase_map_pitch_and_aperture_match_central_differences() {
        let dir = std::env::temp_dir().join(format!("asnr-map-pitch-{}", std::process::id()));
        let source = small_phase_map(&dir);
        let set = owned(&["options.pupil_samples=512", "options.tolerance=1e-3"]);
        let keys = ["lens.phase_map_pitch_um", "lens.f_number", "lens.focal_length_mm"];
        let g = gradient(&source, &set, &owned(&keys)).unwrap();
        let references: Vec<[f64; 4]> = g
            .keys
            .iter()
            .zip(&g.values)
            .map(|(k, &v)| {
                let at = |x: f64| {
                    let mut all = set.clone();
                    all.push(assignment(k, x));
                    let e = metric::evaluate(&scene::build_from(&source, &all).unwrap()).unwrap();
                    [e.asnr, e.mean_mtf, e.snr0, e.photoelectrons]
                };
                let h = 0.01 * v;
                let (up, down) = (at(v + h), at(v - h));
                std::array::from_fn(|q| (up[q] - down[q]) / (2.0 * h))
            })
            .collect();
        within_of_the_norm(&g, &references, 1e-2, "a 16 × 16 phase map");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// `lens.f_number` and `lens.focal_length_mm` (docs/physics.md, "Gradients": the normalized
    /// frequency s = νλF# by parts, one OTF at Nyquist; the defocus W020 ∝ f0/F#² through
    /// ∂H/∂w; N ∝ 1/F#²) against central differences of evaluations converged at 1e-10, within
    /// 10× the scene's 1e-6 of the gradient's norm, with the step [`APERTURE_STEP`] (relative).
    fn check_aperture(source: &Source, overrides: &[String]) {
        let keys = ["lens.f_number", "lens.focal_length_mm", "exposure.time_ms"];
        check_with_steps(source, overrides, &keys, &|k, v| {
            if k.starts_with("lens.") { APERTURE_STEP * v.abs() } else { relative_step(k, v) }
        });
    }

    /// The relative step for the F-number and the focal length: the defocus at a band's edge is
    /// several waves (N_z Δλ/λ0 ≈ 5 for the paper's lens at 50 nm), so the value turns on a
    /// relative scale of K = f0/(8F#²) of a few per cent, not of 1: |f‴| of order (1/0.05)³ ≈ 1e4
    /// in relative units (an estimate from that scale) and h = (3e-10/1e4)^{1/3} ≈ 3e-5.
    const APERTURE_STEP: f64 = 3e-5;

    /// The paper's chromatic lens (the closed form) in both forms, with read noise and the stray
    /// light (N_T ∝ 1/F#² too), and under a line.
    #[test]
    fn f_number_and_focal_length_match_central_differences() {
        let paper = scene::read(None).unwrap();
        check_aperture(&paper, &[]);
        check_aperture(
            &paper,
            &owned(&["options.form=\"integral\"", "camera.read_noise_e=2", "options.glare=\"included\""]),
        );
        check_aperture(&paper, &owned(&LINE_803));
        // the pixel MTF inside the integral: its term ∫ν P′|O| dν of the integration by parts,
        // on the closed form and on a line (the value's own rules)
        check_aperture(&paper, &owned(&["camera.pixel_mtf=true"]));
        check_aperture(
            &paper,
            &owned(&[
                "camera.pixel_mtf=true",
                "spectrum.shape=\"line\"",
                "spectrum.center_nm=803",
                "spectrum.range_nm=1",
            ]),
        );
    }

    /// The F-number and focal length with the pixel MTF where the value takes the reference
    /// panels rule (a wavelength's cutoff inside the frequency band, or the rule forced by
    /// `options.spectral_rule`): the defocus lane on the reference rule with the pixel MTF in its
    /// weights, and the pixel's own term of the integration by parts `P_ν = (1/ν_N) ∫ ν P′|O| dν`
    /// on the value's engine (docs/physics.md, "Gradients: the F-number and the focal length").
    /// The paper's lens on a 4 nm band with the panels rule forced, against central differences
    /// of evaluations converged at 1e-10 ([`check_aperture`]); the dispersion-engineered lens at
    /// F/16.8, whose value takes that rule by itself, in `achromat`'s tests.
    #[test]
    fn f_number_with_the_pixel_mtf_on_the_reference_panels_rule_matches_central_differences() {
        let paper = scene::read(None).unwrap();
        let panels = owned(&["camera.pixel_mtf=true", "options.spectral_rule=\"panels\"", "spectrum.range_nm=4"]);
        check_aperture(&paper, &panels);
    }

    /// Off axis without Seidel terms (docs/physics.md, "Gradients: the F-number and the focal
    /// length off axis"): the exact 1-D engine's tangential and sagittal means, each node's OTF
    /// `D(νλF#, W020/λ) exp(−2πi ν u·Δ)` with the lateral colour `Δ ∝ f0`, not F# — by parts in
    /// νF#, the defocus lane and the image shifts' lane. The paper's lens at 5° along x, at
    /// (5°, 3°) with cos⁴θ, read noise, the pixel MTF (its term of the integration by parts) and
    /// the integral form with the stray light; the harmonic lens (each order its own shift and
    /// defocus) at 5°; the decentred iris at (3°, 2°) (its tilt `4 F# W020 d` a function of νF#,
    /// moving with the defocus lane; the lateral colour with the shifts' lane). Each against
    /// central differences of evaluations converged at 1e-10, within 10× the scene's 1e-6 of the
    /// gradient's norm ([`check_aperture`]).
    #[test]
    fn f_number_and_focal_length_off_axis_match_central_differences() {
        let paper = scene::read(None).unwrap();
        check_aperture(&paper, &owned(&["field.x_deg=5"]));
        check_aperture(
            &paper,
            &owned(&[
                "field.x_deg=5",
                "field.y_deg=3",
                "lens.relative_illumination=\"cos4\"",
                "camera.read_noise_e=2",
                "camera.pixel_mtf=true",
            ]),
        );
        check_aperture(&paper, &joined(&INTEGRAL_WITH_GLARE, &["field.x_deg=8"]));
        // the harmonic lens at 1°: its orders' images already 20× the differences' error apart
        // (∂ASNR/∂F# moves by 1e-2 of itself from the axis), at a ninth of the cost at 5°, whose
        // 1e-10 references need 256 azimuths
        check_aperture(&example("harmonic.toml"), &owned(&["field.x_deg=1"]));
        check_aperture(&example("decentred-iris.toml"), &owned(&["field.x_deg=3", "field.y_deg=2"]));
        // the refractive lens off axis: its stop at the lens, no image displaced, the OTF the one
        // on axis (`Polychromatic::field_independent`): the value's defocus lane, the pixel MTF's
        // term with it
        let refractive = refractive_singlet();
        check_aperture(&refractive, &owned(&["spectrum.range_nm=100", "field.x_deg=5", "camera.pixel_mtf=true"]));
    }

    /// The paper's scene with its lens made an N-BK7 singlet (written here).
    fn refractive_singlet() -> Source {
        let paper = scene::read(None).unwrap();
        let singlet: Vec<&str> =
            paper.text().lines().filter(|l| !(l.starts_with("efficiency") || l.starts_with("transmission"))).collect();
        Source::from_text(
            singlet
                .join("\n")
                .replace("model = \"chromatic\"", "model = \"refractive\"\nglass = \"N-BK7\"\nelements = 1"),
            "refractive singlet written in the test",
            ".",
        )
    }

    /// The refractive singlet at a 100 nm band and the harmonic lens (several orders, each its own
    /// defocus ∝ f0/F#²) on the per-frequency product rule's defocus lane (docs/physics.md,
    /// "Gradients: the F-number and the focal length on the value's rule"), as
    /// [`f_number_and_focal_length_match_central_differences`], and with the pixel MTF (its term
    /// ∫ν P′|O| dν of the integration by parts on the same accepted nodes).
    #[test]
    fn f_number_and_focal_length_of_the_refractive_and_harmonic_lenses_match_central_differences() {
        let refractive = refractive_singlet();
        check_aperture(&refractive, &owned(&["spectrum.range_nm=100"]));
        check_aperture(&refractive, &owned(&["spectrum.range_nm=100", "camera.pixel_mtf=true"]));
        let harmonic = example("harmonic.toml");
        check_aperture(&harmonic, &[]);
        check_aperture(&harmonic, &owned(&["camera.pixel_mtf=true"]));
    }

    /// The design wavelength λ0 (docs/physics.md, "Gradients: the design wavelength": each
    /// order's defocus along its own ∂W020/∂ln λ0, the harmonic lens's efficiencies with it, on
    /// the value's own rules) with the exposure, against central differences of evaluations
    /// converged at 1e-10, Richardson-extrapolated from the steps 2h and h, h = [`LINE_STEP_NM`]
    /// (the paper's aperture defocuses by about 0.1 wave per nm of λ0, as per nm of a line's
    /// wavelength), within 10× the scene's 1e-6 of each quantity's gradient norm: the paper's
    /// chromatic lens (the closed form), with the pixel MTF, in the integral form with the stray
    /// light and a read noise, under a line; the refractive singlet (N-BK7, n0 = n(λ0)) at a
    /// 100 nm band; the harmonic lens's orders (their defocus and sinc² efficiencies; the
    /// per-frequency product rule) with and without the pixel MTF, and under a line.
    #[test]
    fn design_wavelength_matches_central_differences() {
        let keys = ["lens.design_wavelength_nm", "exposure.time_ms"];
        let check = |source: &Source, overrides: &[String]| {
            check_with_references(source, overrides, &keys, &|k, v| {
                let h = if k == keys[0] { LINE_STEP_NM } else { relative_step(k, v) };
                richardson(source, overrides, k, v, h)
            });
        };
        let paper = scene::read(None).unwrap();
        check(&paper, &[]);
        check(&paper, &owned(&INTEGRAL_WITH_GLARE));
        check(&paper, &owned(&LINE_803));
        check(&paper, &owned(&["camera.pixel_mtf=true"]));
        check(&refractive_singlet(), &owned(&["spectrum.range_nm=100"]));
        let harmonic = example("harmonic.toml");
        check(&harmonic, &[]);
        check(&harmonic, &owned(&["camera.pixel_mtf=true"]));
        check(&harmonic, &owned(&LINE_803));
    }

    /// What the design wavelength's gradient refuses, naming the key and why: a library lens
    /// (its atoms chosen at λ0, piecewise), a phase lens of diffractive dispersion (its orders'
    /// efficiencies move with λ0: not followed yet), and the harmonic lens with the pixel MTF on
    /// the reference panels rule (no lane there). The gradient evaluates the scene
    /// before it refuses, so the refused scenes are cheap ones on the same refusals: the
    /// diffractive lens under a line (over its 50 nm band the evaluation takes a minute; the
    /// refusal is the family's, whatever the band) and the harmonic lens on a 4 nm band (the
    /// panels rule forced by the option).
    #[test]
    fn design_wavelength_refusals_name_why() {
        let key = owned(&["lens.design_wavelength_nm"]);
        let e = gradient(&example("library.toml"), &[], &key).unwrap_err().to_string();
        assert!(
            e.contains("--wrt lens.design_wavelength_nm: not differentiable here yet") && e.contains("piecewise"),
            "{e}"
        );
        let diffractive = joined(&["lens.dispersion=\"diffractive\"", "lens.design_order=2"], &LINE_803);
        let e = gradient(&example("phase-binary2.toml"), &diffractive, &key).unwrap_err().to_string();
        assert!(e.contains("design wavelength") && e.contains("diffractive one its orders' efficiencies"), "{e}");
        let panels = owned(&["camera.pixel_mtf=true", "options.spectral_rule=\"panels\"", "spectrum.range_nm=4"]);
        let e = gradient(&example("harmonic.toml"), &panels, &key).unwrap_err().to_string();
        assert!(e.contains("design wavelength") && e.contains("camera.pixel_mtf") && e.contains("panels"), "{e}");
    }

    /// The design wavelength off axis (docs/physics.md, "Gradients: the design wavelength off
    /// axis": on the exact 1-D engine, the lane of each order's defocus and efficiency beside the
    /// image shifts' scale, the lateral colour `f0 tan θ (λ0/λ − 1)` moving as `Δ + f0 tan θ`)
    /// and under a noise spectrum (each frequency's weight divided by n(ν): off axis on the same
    /// lanes, on axis on the reference rule), against central differences of evaluations
    /// converged at 1e-10, Richardson-extrapolated from the steps 2h and h, h = [`LINE_STEP_NM`],
    /// within 10× the scene's 1e-6 of the gradient's norm: the paper's chromatic lens at 5° along
    /// x, at (0°, 3°) with the pixel MTF, and under the noise spectrum on axis and at 5° (where
    /// the weight moves the gradient: [`assert_weighted`]); the harmonic lens's orders (each its
    /// own shift, defocus and efficiency) at 1° over a 20 nm band.
    #[test]
    fn design_wavelength_off_axis_and_under_a_noise_spectrum_match_central_differences() {
        let keys = ["lens.design_wavelength_nm"];
        let check = |source: &Source, overrides: &[String]| {
            check_with_references(source, overrides, &keys, &|k, v| richardson(source, overrides, k, v, LINE_STEP_NM));
        };
        let paper = scene::read(None).unwrap();
        check(&paper, &owned(&["field.x_deg=5"]));
        check(&paper, &owned(&["field.y_deg=3", "camera.pixel_mtf=true"]));
        let shaped = with_noise_spectrum(&paper, "design-wavelength");
        for overrides in [vec![], owned(&["field.x_deg=5"])] {
            assert_weighted(&gradient(&shaped, &overrides, &owned(&keys)).unwrap());
            check(&shaped, &overrides);
        }
        check(&example("harmonic.toml"), &owned(&["field.x_deg=1", "spectrum.range_nm=20"]));
    }

    /// A phase lens with a geometric phase (examples/phase-binary2.toml): its Binary 2 profile is
    /// given in radians and each order's path is λ/2π per radian, so nothing it images with
    /// depends on λ0: the value at λ0 ± 1 nm is the value at λ0 to the last bit, and the gradient
    /// is 0 (said so, not refused), beside the exposure's own.
    #[test]
    fn a_geometric_phase_does_not_move_with_the_design_wavelength() {
        let source = example("phase-binary2.toml");
        let asnr = |set: &[&str]| metric::evaluate(&scene::build_from(&source, &owned(set)).unwrap()).unwrap().asnr;
        let at = asnr(&[]);
        for moved in ["lens.design_wavelength_nm=799", "lens.design_wavelength_nm=801"] {
            assert_eq!(asnr(&[moved]).to_bits(), at.to_bits(), "{moved}");
        }
        let g = gradient(&source, &[], &owned(&["lens.design_wavelength_nm", "exposure.time_ms"])).unwrap();
        assert_eq!([g.d_asnr[0], g.d_mean_mtf[0], g.d_photoelectrons[0]], [0.0; 3], "{g:?}");
        assert!(g.d_asnr[1] > 0.0, "the exposure's own derivative beside it: {g:?}");
    }

    /// A PSF stack's design wavelength names the Fraunhofer report's reference alone: the value
    /// at λ0 ± 1 nm is the value at λ0 to the last bit (a 5 nm band: a few slices), and the
    /// gradient is 0 (said so, not refused).
    #[test]
    fn a_psf_stack_does_not_move_with_the_design_wavelength() {
        let source = example("psf-stack.toml");
        let asnr = |set: &[&str]| {
            let set: Vec<&str> = set.iter().copied().chain(["spectrum.range_nm=5"]).collect();
            metric::evaluate(&scene::build_from(&source, &owned(&set)).unwrap()).unwrap().asnr
        };
        let at = asnr(&[]);
        for moved in ["lens.design_wavelength_nm=799", "lens.design_wavelength_nm=801"] {
            assert_eq!(asnr(&[moved]).to_bits(), at.to_bits(), "{moved}");
        }
        let g = gradient(&source, &owned(&["spectrum.range_nm=5"]), &owned(&["lens.design_wavelength_nm"])).unwrap();
        assert_eq!([g.d_asnr[0], g.d_mean_mtf[0], g.d_photoelectrons[0]], [0.0; 3], "{g:?}");
    }

    /// The hyperbolic phase −(2π/λ0)(√(r² + f0²) − f0) of the example's aperture (F/2.5,
    /// f0 = 3.36 mm, λ0 = 800 nm) at `knots` equally spaced radii from the axis to the edge, as
    /// `lens.phase_spline_rad` (radians, in ρ = r/R).
    fn hyperbolic_knots(knots: usize) -> String {
        let (f0, radius, k0) = (3.36e-3_f64, 0.672e-3_f64, std::f64::consts::TAU / 800e-9);
        let values: Vec<String> = (0..knots)
            .map(|i| {
                let r = radius * i as f64 / (knots - 1) as f64;
                format!("{:.12}", -k0 * ((r * r + f0 * f0).sqrt() - f0))
            })
            .collect();
        format!("phase_spline_rad = [{}]", values.join(", "))
    }

    /// The phase lens's F-number and focal length (docs/physics.md, "Gradients": s = νλF# by
    /// parts, and the radial engine's lanes along R ∂φ0/∂R of a profile given in r, the
    /// reference sphere's R ∂S/∂R and S itself) against central differences of evaluations
    /// converged at 1e-10, within 10× the scene's 1e-6 of the gradient's norm, step
    /// [`APERTURE_STEP`]: the Binary 2 lens with its own R_norm (its profile moves with R),
    /// and under a line (the line's own rule). The integral form and the stray light take the
    /// same lines of `point_gradient` as the chromatic lens's (tested above).
    #[test]
    fn phase_lens_f_number_and_focal_length_match_central_differences() {
        let binary2 = example("phase-binary2.toml");
        check_aperture(&binary2, &[]);
        check_aperture(&binary2, &owned(&LINE_803));
    }

    /// With the pixel MTF (docs/physics.md, "Gradients: the pixel pitch with the pixel MTF"):
    /// the phase lens's F-number and focal length (by parts the sinc's term −P_ν joins
    /// P(ν_N)|O(ν_N)| − M̄, the radial engine's lanes carry P in their weights), the
    /// decentred iris's through the reduction (P_ν recorded along each azimuth beside its
    /// defocus lane), and the Binary 2 lens's wavefront keys (Binary 2 coefficients, the
    /// normalization radius, added spline knots, Noll 4 and 11: the lanes' weights carry P),
    /// against central differences of evaluations converged at 1e-10, within 10× the scene's
    /// 1e-6 of the gradient's norm, in the mean and the integral form.
    #[test]
    fn aperture_and_wavefront_keys_with_the_pixel_mtf_match_central_differences() {
        let binary2 = example("phase-binary2.toml");
        check_aperture(&binary2, &owned(&PIXEL_AND_READ_NOISE));
        check_aperture(&binary2, &owned(&["camera.pixel_mtf=true", "options.form=\"integral\""]));
        let iris = example("decentred-iris.toml");
        check_aperture(&iris, &owned(&PIXEL_AND_READ_NOISE));
        check_aperture(&iris, &owned(&["camera.pixel_mtf=true", "options.form=\"integral\""]));
        let keys = owned(&[
            "lens.binary2[0]",
            "lens.binary2[1]",
            "lens.binary2[2]",
            "lens.binary2[3]",
            "lens.norm_radius_mm",
            "lens.zernike_noll_rms_um[3]",
            "lens.zernike_noll_rms_um[10]",
        ]);
        let set = joined(&PIXEL_AND_READ_NOISE, &["lens.zernike_noll_rms_um=[0,0,0,0.01,0,0,0,0,0,0,-0.005]"]);
        // the example's normalization radius 0.672 mm
        let step = |k: &str| match k {
            "lens.norm_radius_mm" => NORM_RADIUS_STEP * 0.672,
            k if k.starts_with("lens.zernike") => PHASE_STEP / 27.0,
            k => phase_or_knot_step(k),
        };
        check_wavefront(&binary2, &set, &keys, &step);
        // added spline knots in a case of their own (the tensor rule across the knots: each 1e-10
        // reference takes seconds, where the keys above take milliseconds), beside a Binary 2
        // coefficient, under a line: the pixel's sinc sits in the frequency rule's weights
        // whatever the spectrum, and a line makes each reference twenty times cheaper than the
        // example's 50 nm band
        let keys = owned(&["lens.binary2[1]", "lens.phase_spline_rad[2]", "lens.phase_spline_rad[5]"]);
        let spline = ["lens.phase_spline_rad=[0, 0.3, -0.2, 0.1, 0.4, -0.3, 0.2]"];
        let set = owned(&[&PIXEL_AND_READ_NOISE[..], &LINE_803[..], &spline[..]].concat());
        check_wavefront(&binary2, &set, &keys, &step);
    }

    /// The example's coefficients normalized to the aperture (R_norm not given: the profile is
    /// in ρ and does not move, the sphere does), and a diffractive lens's several orders (each
    /// its own path per radian on the moving profile), as
    /// [`phase_lens_f_number_and_focal_length_match_central_differences`].
    #[test]
    fn phase_lens_in_rho_and_diffractive_f_number_and_focal_length_match_central_differences() {
        let in_rho = phase_scene_with(
            "binary2 = [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]",
        );
        check_aperture(&in_rho, &[]);
        // the diffractive lens's 1e-10 references take 35 s each at F/2.5 (its strongly defocused
        // other orders; 51 s on a 10 nm band), 5 s at F/5, where the same profile over half the
        // aperture still sends its light into several orders, each with its own path per radian:
        // the two aperture keys alone, the exposure checked with the others above
        let diffractive = owned(&["lens.dispersion=\"diffractive\"", "lens.design_order=2", "lens.f_number=5"]);
        let keys = ["lens.f_number", "lens.focal_length_mm"];
        check_with_steps(&example("phase-binary2.toml"), &diffractive, &keys, &|_, v| APERTURE_STEP * v.abs());
    }

    /// [`check_aperture`] with the lens keys' differences Richardson-extrapolated from the steps
    /// 2h and h, h = [`NARROW_APERTURE_STEP`] of the key (`(4 D(h) − D(2h))/3`, truncation
    /// O(h⁴)).
    fn check_aperture_extrapolated(source: &Source, overrides: &[String]) {
        let keys = ["lens.f_number", "lens.focal_length_mm", "exposure.time_ms"];
        check_with_references(source, overrides, &keys, &|k, v| {
            if !k.starts_with("lens.") {
                return central(source, overrides, k, v, relative_step(k, v));
            }
            let h = NARROW_APERTURE_STEP * v.abs();
            richardson(source, overrides, k, v, h)
        });
    }

    /// The relative step of [`check_aperture_extrapolated`]. On a narrow band a profile given in ρ
    /// is nearly in focus at every wavelength, and the F-number moves the reference sphere alone,
    /// by R ∂S/∂R ≈ R²/(2f0) ≈ 84 waves per unit of ln R on the example's aperture: the value
    /// turns on a relative scale of the F-number of about 5e-3, not the few per cent of a 50 nm
    /// band. On a 10 nm band the plain differences of ∂ASNR/∂ln F# (Binary 2 in ρ) at the steps
    /// 3e-5, 1e-4, 3e-4 gave −12.107607, −12.104237, −12.074644 against the gradient's
    /// −12.107940 at 1e-6 (−12.107940 at 1e-7 and 1e-8): an h² truncation of 2.7e-5 of the
    /// norm at [`APERTURE_STEP`], which the extrapolation removes.
    const NARROW_APERTURE_STEP: f64 = 5e-5;

    /// The phase lens's F-number and focal length on a 10 nm band (the profile given in ρ: Binary
    /// 2 without R_norm), where the value turns fast in the F-number (see
    /// [`NARROW_APERTURE_STEP`]), against Richardson-extrapolated central differences
    /// ([`check_aperture_extrapolated`]) within 10× the scene's 1e-6 of the gradient's norm
    /// (measured 1.4e-8).
    #[test]
    fn phase_lens_f_number_at_a_narrow_band_matches_extrapolated_differences() {
        let narrow = owned(&["spectrum.range_nm=10"]);
        let in_rho = phase_scene_with(
            "binary2 = [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]",
        );
        check_aperture_extrapolated(&in_rho, &narrow);
    }

    /// The 17-knot spline of the hyperbolic profile on the same 10 nm band, as
    /// [`phase_lens_f_number_at_a_narrow_band_matches_extrapolated_differences`], on the radial
    /// engine's rule split at the knots (`options.table_rule = "split"`, docs/physics.md, "The
    /// radial engine"): within 10× the scene's 1e-6 of the norm (measured 3.7e-6); on the tensor
    /// rule ∂M̄/∂ln F# is 1.3e-5 of the norm off at the tolerances 1e-6 and 1e-7 alike. Ignored by
    /// default (its references are evaluations at 1e-10 on the split rule: minutes in a debug
    /// build): `cargo test -p asnr-report --lib spline_f_number -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn spline_f_number_at_a_narrow_band_matches_extrapolated_differences() {
        let set = owned(&["spectrum.range_nm=10", "options.table_rule=\"split\""]);
        check_aperture_extrapolated(&phase_scene_with(&hyperbolic_knots(17)), &set);
    }

    /// The 17-knot spline lens's mean MTF on a 10 nm band: on the rule split at the knots
    /// (`options.table_rule = "split"`) at the tolerance 1e-7 within it (relative) of the split
    /// rule at [`REFERENCE_TOLERANCE`] (whose OTFs `cargo test -p asnr-optics --lib split_rule`
    /// checks against an adaptive reference); on the tensor rule (the default) at the same
    /// tolerance not (measured 1.3e-6 off: the tensor rule's error, which the tolerance does not
    /// move), so the test fails without the split rule.
    #[test]
    fn spline_lens_mean_mtf_meets_the_tolerance_on_the_split_rule() {
        let source = phase_scene_with(&hyperbolic_knots(17));
        let at = |rule: &str, tolerance: f64| {
            let set = owned(&[
                "spectrum.range_nm=10",
                &format!("options.table_rule=\"{rule}\""),
                &format!("options.tolerance={tolerance:e}"),
            ]);
            metric::evaluate(&scene::build_from(&source, &set).unwrap()).unwrap().mean_mtf
        };
        let reference = at("split", REFERENCE_TOLERANCE);
        let tolerance = 1e-7;
        let (split, tensor) = (at("split", tolerance), at("tensor", tolerance));
        eprintln!("mean MTF at {tolerance:e}: split {split:.12}, tensor {tensor:.12}, against {reference:.12}");
        assert!((split - reference).abs() <= tolerance * reference, "split: {split} vs {reference}");
        assert!((tensor - reference).abs() > tolerance * reference, "tensor: {tensor} vs {reference}");
    }

    /// `options.table_rule = "tensor"` (and the default) is the radial engine's rule before the
    /// option, bit for bit: the 17-knot spline lens on a 10 nm band at the default tolerance has
    /// the mean MTF 0.8097046873588404 that main's release build of 2026-12-06 (3340cd0) gave
    /// (`asnr evaluate SCENE --set spectrum.range_nm=10 --json`, SCENE this test's). Its note
    /// (the tensor rule's error above the tolerance) is in the evaluation's warnings at 1e-6,
    /// not at 1e-5, not with "split", and not for the analytic Binary 2 lens.
    #[test]
    fn spline_lens_tensor_rule_is_the_rule_before_and_notes_its_error() {
        let source = phase_scene_with(&hyperbolic_knots(17));
        let run = |source: &Source, set: &[&str]| {
            let mut set = owned(set);
            set.push("spectrum.range_nm=10".to_owned());
            metric::evaluate(&scene::build_from(source, &set).unwrap()).unwrap()
        };
        let noted = |e: &metric::Evaluation| e.warnings.iter().any(|w| w.contains("tensor rule"));
        let default = run(&source, &[]);
        let tensor = run(&source, &["options.table_rule=\"tensor\""]);
        assert_eq!(default.mean_mtf.to_bits(), 0.8097046873588404_f64.to_bits(), "{}", default.mean_mtf);
        assert_eq!(tensor.mean_mtf.to_bits(), default.mean_mtf.to_bits());
        assert!(noted(&default) && noted(&tensor), "{:?}", default.warnings);
        let note = default.warnings.iter().find(|w| w.contains("tensor rule")).unwrap();
        assert!(
            note.contains("lens.phase_spline_rad")
                && note.contains("about 2e-6 relative, not to the tolerance 1e-6")
                && note.contains("options.table_rule = \"split\""),
            "{note}"
        );
        assert!(!noted(&run(&source, &["options.tolerance=1e-5"])));
        assert!(!noted(&run(&source, &["options.table_rule=\"split\""])));
        assert!(!noted(&run(&example("phase-binary2.toml"), &[])));
    }

    /// A freeform spline alone (17 knots of the hyperbolic profile, in ρ: it does not move with
    /// R, the sphere does) and a phase table in r_mm (`examples/phase-table.toml` stopped to
    /// F/2.6, so that R moves inside the table: its profile moves along ρ φ′(ρ), the spline's
    /// own derivative), against central differences as above.
    #[test]
    fn spline_and_table_lenses_f_number_and_focal_length_match_central_differences() {
        check_aperture(&phase_scene_with(&hyperbolic_knots(17)), &[]);
        check_aperture(&example("phase-table.toml"), &owned(&["lens.f_number=2.6"]));
    }

    /// What the phase lens's F-number and focal-length gradient refuses, naming why: the exact
    /// pupil mapping, a phase table's amplitude column; the library
    /// lens (its value jumps where R crosses a ring centre).
    #[test]
    fn phase_and_library_aperture_refusals_name_why() {
        let binary2 = example("phase-binary2.toml");
        let keys = owned(&["lens.f_number"]);
        let e = gradient(&binary2, &owned(&["options.pupil_mapping=\"exact\""]), &keys).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.f_number") && e.contains("options.pupil_mapping = \"exact\""), "{e}");
        let e = gradient(&example("library.toml"), &[], &owned(&["lens.focal_length_mm"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.focal_length_mm") && e.contains("ring centre"), "{e}");
        // a table with an amplitude column in r_mm: the amplitude moves with R
        let dir = std::env::temp_dir().join(format!("asnr-amplitude-table-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut csv = String::from("r_mm,phase_rad,amplitude\n");
        for i in 0..=400 {
            let r = 0.7e-3 * f64::from(i) / 400.0;
            let phase = -std::f64::consts::TAU / 800e-9 * ((r * r + 3.36e-3_f64.powi(2)).sqrt() - 3.36e-3);
            csv.push_str(&format!("{},{phase},{}\n", r * 1e3, 1.0 - 0.2 * (r / 0.7e-3).powi(2)));
        }
        std::fs::write(dir.join("table.csv"), csv).unwrap();
        let text = example("phase-table.toml").text().replace("data/phase-hyperbolic-f2.5.csv", "table.csv");
        let table = Source::from_text(text, "amplitude table written in the test", &dir);
        let e = gradient(&table, &[], &keys).unwrap_err().to_string();
        assert!(e.contains("F-number") && e.contains("amplitude"), "{e}");
    }

    /// ∂SNR0 analytic: with shot noise alone SNR0 = √N and N ∝ t, so ∂SNR0/∂t = SNR0/(2t) and
    /// ∂ASNR/∂t = ASNR/(2t) (docs/physics.md, "Gradients"); with read noise σ_r,
    /// ∂SNR0/∂N = (N + 2σ_r²)/(2(N + σ_r²)^{3/2}).
    #[test]
    fn snr0_gradient_is_the_closed_form() {
        let source = example("phase-binary2.toml");
        let g = gradient(&source, &[], &owned(&["exposure.time_ms"])).unwrap();
        let t = g.values[0];
        assert!((g.d_snr0[0] - g.snr0 / (2.0 * t)).abs() <= 1e-14 * g.d_snr0[0], "{g:?}");
        assert!((g.d_asnr[0] - g.asnr / (2.0 * t)).abs() <= 1e-14 * g.d_asnr[0], "{g:?}");
        assert!((g.d_photoelectrons[0] - g.photoelectrons / t).abs() <= 1e-14 * g.d_photoelectrons[0]);
        assert_eq!(g.d_mean_mtf[0], 0.0);
        assert!((g.relative(0) - 0.5).abs() < 1e-14);
        let g = gradient(&source, &owned(&["camera.read_noise_e=4"]), &owned(&["exposure.time_ms"])).unwrap();
        let (n, r2) = (g.photoelectrons, 16.0);
        let closed = (n + 2.0 * r2) / (2.0 * (n + r2).powf(1.5)) * n / g.values[0];
        assert!((g.d_snr0[0] - closed).abs() <= 1e-13 * closed, "{} vs {closed}", g.d_snr0[0]);
    }

    /// The Binary 2 keys `keys` with `overrides` against central differences (see
    /// [`binary2_coefficients_match_central_differences`]); returns the gradient and the
    /// references.
    fn check_binary2(source: &Source, overrides: &[String], keys: &[String]) -> (Gradient, Vec<[f64; 4]>) {
        check_wavefront(source, overrides, keys, &|_| PHASE_STEP)
    }

    /// The step for a key in radians of phase (a Binary 2 coefficient, a spline knot): rounding
    /// 1e-10 · ASNR ≈ 1e-9 against truncation h²|f‴|/6 with |f‴| ≈ 8e-4 per rad³ (measured for
    /// A1, see [`binary2_coefficients_match_central_differences`]): h = (3e-9/8e-4)^{1/3}.
    const PHASE_STEP: f64 = 0.01554;

    /// The step for a spline knot: the value turns faster in a knot than in A1 (its cardinal
    /// function is local, ∂ASNR/∂φ_i is 20× ∂ASNR/∂A1); with [`PHASE_STEP`] the differences of
    /// knot 2 of [`phase_spline_knots_match_central_differences`] missed the gradient by 1.4e-5 of
    /// the norm, a truncation h²|f‴|/6 with |f‴| ≈ 0.25 per rad³, so h = (3e-9/0.25)^{1/3}.
    const KNOT_STEP: f64 = 2.3e-3;

    /// [`PHASE_STEP`] for the Binary 2 keys, [`KNOT_STEP`] for the spline's knots.
    fn phase_or_knot_step(key: &str) -> f64 {
        if key.starts_with("lens.phase_spline_rad") { KNOT_STEP } else { PHASE_STEP }
    }

    /// [`check_binary2`] with the step `step(key)` (in the key's units).
    fn check_wavefront(
        source: &Source,
        overrides: &[String],
        keys: &[String],
        step: &dyn Fn(&str) -> f64,
    ) -> (Gradient, Vec<[f64; 4]>) {
        let tolerance = 1e-6;
        let g = gradient(source, overrides, keys).unwrap();
        let references: Vec<[f64; 4]> = g
            .keys
            .iter()
            .zip(&g.values)
            .map(|(k, &v)| {
                let h = step(k);
                let up = converged(source, overrides, k, v + h);
                let down = converged(source, overrides, k, v - h);
                std::array::from_fn(|i| (up[i] - down[i]) / (2.0 * h))
            })
            .collect();
        for (q, (name, mine)) in [("ASNR", &g.d_asnr), ("mean MTF", &g.d_mean_mtf)].into_iter().enumerate() {
            let norm = mine.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(norm > 0.0, "{name}: a zero gradient");
            for (i, k) in g.keys.iter().enumerate() {
                let theirs = references[i][q];
                let error = (mine[i] - theirs).abs();
                println!(
                    "{name} {k}: gradient {:.9e}, differences {theirs:.9e}, error/norm {:.1e}",
                    mine[i],
                    error / norm
                );
                assert!(error <= 10.0 * tolerance * norm, "{name} {k}: {} vs {theirs} (norm {norm})", mine[i]);
            }
        }
        (g, references)
    }

    /// Every Binary 2 coefficient of the geometric-phase lens (the OTF's derivative inside the
    /// radial engine, on the value's own rules: `optics::Polychromatic::mean_mtf_and_binary2_gradient`), the example's four and two more
    /// terms, against central differences of evaluations converged at 1e-10: ∂/∂A_j (per radian
    /// of phase at the edge, as R = R_norm and M = 1 here) within 10× the scene's tolerance
    /// (1e-6) of the gradient's norm; SNR0 and N do not move with the phase. The step balances
    /// rounding (1e-10 · ASNR ≈ 1e-9) against truncation h²|f‴|/6 with |f‴| ≈ 8e-4 per rad³
    /// (measured: ∂ASNR/∂A1 by differences is 0.0224078 at h = 0.35 rad, the (3e-10)^{1/3}·|A1|
    /// step, and 0.0224235 at h = 0.03), so h = (3e-9/8e-4)^{1/3} ≈ 0.016 rad.
    /// (Measured: error/norm ≤ 2.2e-6, mostly the differences' truncation.)
    #[test]
    fn binary2_coefficients_match_central_differences() {
        let source = example("phase-binary2.toml");
        let overrides = owned(&[
            "lens.binary2=[-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425, -6.9e-5, 2e-6]",
        ]);
        let keys: Vec<String> = (0..6).map(|i| format!("lens.binary2[{i}]")).collect();
        let (g, references) = check_binary2(&source, &overrides, &owned(&["lens.binary2"]));
        assert_eq!(g.keys, keys);
        for (i, reference) in references.iter().enumerate() {
            assert_eq!(g.d_snr0[i], 0.0);
            assert_eq!(g.d_photoelectrons[i], 0.0);
            // the reference's SNR0 does not move either
            assert!(reference[2].abs() <= 1e-9 * g.snr0, "{}", reference[2]);
        }
        // an index past the list's end
        let e = gradient(&example("phase-binary2.toml"), &[], &owned(&["lens.binary2[4]"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.binary2[4]") && e.contains("has 4 entries"), "{e}");
    }

    /// A profile through zeros of the OTF inside the band (a 5 nm band, defocused by A1 = −480
    /// rad: the polychromatic OTF changes sign below Nyquist, where |O| has a kink): the rule
    /// splits its frequency panels there and stays within 10× the tolerance of the norm.
    #[test]
    fn binary2_gradient_through_otf_zeros() {
        let source = example("phase-binary2.toml");
        let overrides = owned(&["spectrum.range_nm=5", "lens.binary2[0]=-480"]);
        // the OTF does change sign below Nyquist here
        let built = scene::build_from(&source, &overrides).unwrap();
        let nyquist = built.camera().nyquist() * 1e-3;
        let axis: Vec<f64> = (1..=400).map(|i| nyquist * f64::from(i) / 400.0).collect();
        let mtf = metric::mtf_at(&built, &axis, &[]).unwrap().mtf;
        let dips = mtf.windows(3).filter(|w| w[1] < w[0] && w[1] < w[2] && w[1] < 1e-3).count();
        assert!(dips >= 1, "no zero of the OTF below Nyquist: {mtf:?}");
        check_binary2(&source, &overrides, &owned(&["lens.binary2[0]", "lens.binary2[1]"]));
    }

    /// K = 32: the example's four coefficients and 28 small ones (±2e-3/j rad, as the cost rows
    /// of BENCHMARKS.md), every lane computed in the one pass; eight of them (the first five,
    /// then j = 8, 16 and the last, ρ^64) against central differences of evaluations converged at
    /// 1e-10 (the step of [`binary2_coefficients_match_central_differences`]), within 10× the
    /// scene's tolerance of the gradient's norm over them. Eight, not 32, to keep the test within
    /// seconds: the lanes share one rule, so a wrong lane would show in any of them.
    #[test]
    fn binary2_gradient_over_32_coefficients() {
        let source = example("phase-binary2.toml");
        let coefficients: Vec<String> =
            [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]
                .into_iter()
                .chain((4..32usize).map(|j| if j.is_multiple_of(2) { 2e-3 } else { -2e-3 } / j as f64))
                .map(|c| format!("{c:e}"))
                .collect();
        let overrides = vec![format!("lens.binary2=[{}]", coefficients.join(", "))];
        let keys: Vec<String> = [0, 1, 2, 3, 4, 8, 16, 31].iter().map(|i| format!("lens.binary2[{i}]")).collect();
        let (g, _) = check_binary2(&source, &overrides, &keys);
        assert_eq!(g.keys, keys);
        // all 32 at once: the same derivatives as the eight asked alone (the same pass)
        let all = gradient(&source, &overrides, &owned(&["lens.binary2"])).unwrap();
        assert_eq!(all.keys.len(), 32);
        for (k, d) in g.keys.iter().zip(&g.d_asnr) {
            let i = all.keys.iter().position(|a| a == k).unwrap();
            assert!((all.d_asnr[i] - d).abs() <= 1e-12 * d.abs().max(1e-6), "{k}: {} vs {d}", all.d_asnr[i]);
        }
    }

    /// The example's text with its Binary 2 lines replaced by `lines` (a scene whose phase is a
    /// spline alone, or other Binary 2 coefficients).
    fn phase_scene_with(lines: &str) -> Source {
        let text = example("phase-binary2.toml").text().to_owned();
        let kept: Vec<&str> = text
            .lines()
            .filter(|l| !["binary2", "norm_radius_mm", "diffraction_order"].iter().any(|k| l.starts_with(k)))
            .collect();
        let text = kept.join("\n").replace("model = \"phase\"", &format!("model = \"phase\"\n{lines}"));
        Source::from_text(text, "phase-lens scene written in the test", std::env::temp_dir())
    }

    /// Each knot of a freeform spline added on the Binary 2 profile (six knots, ±0.5 rad)
    /// against central differences of evaluations converged at 1e-10 (step [`KNOT_STEP`]): within 10× the scene's tolerance of
    /// the gradient's norm. The profile is linear in the knots, so each knot's direction is the
    /// spline's cardinal basis function, computed in the same engine pass as the Binary 2 ones.
    /// On a 4 nm band (the same radial engine's lanes; each 1e-10 reference 1.5 s against 4.7 s
    /// over the example's 50 nm).
    #[test]
    fn phase_spline_knots_match_central_differences() {
        let source = example("phase-binary2.toml");
        let overrides = owned(&["lens.phase_spline_rad=[0.0, 0.4, -0.3, 0.5, -0.2, 0.3]", "spectrum.range_nm=4"]);
        let keys: Vec<String> =
            (0..6).map(|i| format!("lens.phase_spline_rad[{i}]")).chain(["lens.binary2[0]".to_owned()]).collect();
        let (g, references) = check_wavefront(
            &source,
            &overrides,
            &owned(&["lens.phase_spline_rad", "lens.binary2[0]"]),
            &phase_or_knot_step,
        );
        assert_eq!(g.keys, keys);
        for (i, reference) in references.iter().enumerate() {
            assert_eq!(g.d_snr0[i], 0.0);
            assert!(reference[2].abs() <= 1e-9 * g.snr0, "{}", reference[2]);
        }
        // a constant phase moves nothing: the knots' derivatives sum to (about) zero, since the
        // cardinal functions sum to 1 (the spline of a constant is that constant)
        let sum: f64 = g.d_mean_mtf[..6].iter().sum();
        let norm = g.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(sum.abs() <= 1e-5 * norm, "Σ ∂M̄/∂φ_i = {sum:e} (norm {norm:e})");
    }

    /// A spline added on the Binary 2 lens defocused to A1 = −480 rad (47.8 rad of ρ² from the
    /// example's −527.8, 7.6 waves) under a line at 800 nm: the OTF changes sign below Nyquist
    /// (9 sign changes on 60 frequencies; the |OTF| kink); the middle knot of five (±0.3 rad)
    /// against central differences within 10× the tolerance of the gradient's norm. One knot: a
    /// table phase has no polynomial proxy, so each converged evaluation at 1e-10 takes the
    /// radial engine's per-node path (the other knots share its lanes and its rule). Under a line
    /// that is one wavelength, so the two references take seconds (under a 5 nm band they took
    /// over 25 minutes). Step [`KNOT_STEP`]: measured error/norm 3.2e-6, and 2.8e-6 at half the
    /// step, so it is the gradient's own error at the scene's 1e-6, not the differences'
    /// truncation. The rule through the kink under a band is the one
    /// [`binary2_gradient_through_otf_zeros`] checks.
    #[test]
    fn phase_spline_gradient_through_otf_zeros() {
        let source = example("phase-binary2.toml");
        let overrides = owned(&[
            "spectrum.shape=\"line\"",
            "spectrum.center_nm=800",
            "spectrum.range_nm=1",
            "lens.binary2[0]=-480",
            "lens.phase_spline_rad=[0.0, 0.3, -0.2, 0.3, -0.1]",
        ]);
        let built = scene::build_from(&source, &overrides).unwrap();
        let nyquist = built.camera().nyquist() * 1e-3;
        let axis: Vec<f64> = (1..=60).map(|i| nyquist * f64::from(i) / 60.0).collect();
        let otf = metric::mtf_at(&built, &axis, &[]).unwrap().otf;
        let zeros = otf.windows(2).filter(|w| w[0] * w[1] < 0.0).count();
        assert!(zeros >= 1, "no zero of the OTF below Nyquist: {otf:?}");
        let keys = owned(&["lens.phase_spline_rad[2]"]);
        check_wavefront(&source, &overrides, &keys, &phase_or_knot_step);
    }

    /// The `m = 0` Zernike terms (Noll 1, 4, 11: `zernike_noll_rms_um[0]`, `[3]`, `[10]`) on the
    /// Binary 2 lens against central differences of evaluations converged at 1e-10, within 10× the
    /// tolerance of the norm. One µm RMS of Z4 is 2√3 µm of W020, ~27 rad of phase at 800 nm
    /// where an A1 of 1 rad is 1 rad: the step is [`PHASE_STEP`]/27 µm. Piston moves nothing
    /// (its derivative is 0); a term with m ≠ 0 is refused naming it.
    #[test]
    fn zernike_m0_terms_match_central_differences() {
        let source = example("phase-binary2.toml");
        let overrides = owned(&["lens.zernike_noll_rms_um=[0, 0, 0, 0.02, 0, 0, 0, 0, 0, 0, -0.01]"]);
        let keys =
            owned(&["lens.zernike_noll_rms_um[0]", "lens.zernike_noll_rms_um[3]", "lens.zernike_noll_rms_um[10]"]);
        let (g, _) = check_wavefront(&source, &overrides, &keys, &|_| PHASE_STEP / 27.0);
        assert_eq!(g.d_mean_mtf[0], 0.0, "piston: {g:?}");
        assert!(g.d_mean_mtf[1] != 0.0 && g.d_mean_mtf[2] != 0.0, "{g:?}");
        // a term with m ≠ 0 at zero on this radially symmetric pupil: 0 by symmetry (tilt moves
        // nothing at all)
        let tilt = gradient(&source, &overrides, &owned(&["lens.zernike_noll_rms_um[1]"])).unwrap();
        assert_eq!(tilt.d_mean_mtf[0], 0.0);
        // with a spline too: the Zernike lanes come after the knots'
        let overrides =
            owned(&["lens.zernike_noll_rms_um=[0, 0, 0, 0.02]", "lens.phase_spline_rad=[0.0, 0.4, -0.3, 0.5]"]);
        let both = gradient(&source, &overrides, &owned(&["lens.zernike_noll_rms_um[3]", "lens.phase_spline_rad[2]"]))
            .unwrap();
        let alone = gradient(&source, &overrides, &owned(&["lens.zernike_noll_rms_um[3]"])).unwrap();
        assert_eq!(both.d_asnr[0], alone.d_asnr[0]);
        assert!(both.d_asnr[0] != both.d_asnr[1]);
    }

    /// Composite Simpson's rule of `f` on `[a, b]` with `n` (even) intervals.
    fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        let inner: f64 = (1..n).map(|i| f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 }).sum();
        (f(a) + f(b) + inner) * h / 3.0
    }

    /// ∂ mean MTF/∂(Z4) against the closed form of the defocused OTF, written here: a line at
    /// λ0 = 800 nm through the hyperbolic profile (eight Binary 2 terms, its Taylor series in r²
    /// to ~1e-16 m at this aperture), so the wavefront is the Zernike term alone,
    /// `W = c √3 (2ρ² − 1)`: a defocus `W020 = 2√3 c`. The defocused pupil's autocorrelation at
    /// `s = ν λ F#` (Hopkins 1955; the overlap of the pupils shifted by ±s, the phase `4 a s x`
    /// with `a = k W020`) reduces to one integral,
    /// `OTF(s) = (4/π) ∫_0^{acos s} sin(4as(cos θ − s))/(4as) cos θ dθ` (y = sin θ), and its
    /// derivative in `a` is the integral of the integrand's; both by Simpson's rule here, the
    /// mean over `[0, ν_N]` by Simpson's rule too (no zero of the OTF below Nyquist at c = 0.1 µm).
    /// The mean MTF within 1e-7 and its derivative within 10× the scene's 1e-6 of itself.
    #[test]
    fn defocus_gradient_matches_the_defocused_otf() {
        // −(2π/λ0)(√(r² + f0²) − f0) as Binary 2 terms: A_i = −(2π/λ0) C(½, i) R^{2i}/f0^{2i−1}
        let (f0, radius, lambda) = (3.36e-3_f64, 0.672e-3_f64, 800e-9_f64);
        let mut binom = 1.0;
        let a: Vec<String> = (1..=8)
            .map(|i| {
                let fi = f64::from(i);
                binom *= (1.5 - fi) / fi;
                format!("{:e}", -std::f64::consts::TAU / lambda * binom * radius.powi(2 * i) / f0.powi(2 * i - 1))
            })
            .collect();
        let source = phase_scene_with(&format!("binary2 = [{}]", a.join(", ")));
        let c_um = 0.1;
        let overrides = owned(&[
            "spectrum.shape=\"line\"",
            "spectrum.range_nm=1",
            &format!("lens.zernike_noll_rms_um=[0, 0, 0, {c_um}]"),
        ]);
        let g = gradient(&source, &overrides, &owned(&["lens.zernike_noll_rms_um[3]"])).unwrap();
        // the closed form
        let k = std::f64::consts::TAU / lambda;
        let per_um = 2.0 * 3f64.sqrt() * 1e-6; // W020 per µm RMS of Z4
        let a = k * per_um * c_um;
        let otf = |s: f64| {
            let inner = |t: f64| {
                let b = 4.0 * s * (t.cos() - s);
                (a * b).sin() / (4.0 * a * s) * t.cos()
            };
            4.0 / std::f64::consts::PI * simpson(&inner, 0.0, s.acos(), 400)
        };
        let d_otf = |s: f64| {
            let inner = |t: f64| {
                let b = 4.0 * s * (t.cos() - s);
                (b * (a * b).cos() / (4.0 * a * s) - (a * b).sin() / (4.0 * a * a * s)) * t.cos()
            };
            4.0 / std::f64::consts::PI * simpson(&inner, 0.0, s.acos(), 400)
        };
        // s at Nyquist: ν_N λ F# with ν_N = 1/(2p)
        let s_nyquist = lambda * 2.5 / (2.0 * 5.2e-6);
        let tiny = 1e-9; // the integrand's 1/s at s = 0: its limit is the value just off it
        let mean = simpson(&|s| otf(s.max(tiny)).abs(), 0.0, s_nyquist, 200) / s_nyquist;
        let d_mean =
            simpson(&|s| otf(s.max(tiny)).signum() * d_otf(s.max(tiny)), 0.0, s_nyquist, 200) / s_nyquist * k * per_um;
        println!(
            "mean MTF {:.9} (closed form {mean:.9}); ∂/∂c {:.9e} (closed form {d_mean:.9e})",
            g.mean_mtf, g.d_mean_mtf[0]
        );
        assert!((g.mean_mtf - mean).abs() <= 1e-7, "{} vs {mean}", g.mean_mtf);
        assert!((g.d_mean_mtf[0] - d_mean).abs() <= 1e-5 * d_mean.abs(), "{} vs {d_mean}", g.d_mean_mtf[0]);
    }

    /// The Binary 2 gradient under a line spectrum (the line's own rule: one wavelength, each
    /// order's radial OTF and its derivatives) against central differences of evaluations
    /// converged at 1e-10, within 10× the tolerance of the norm; a diffractive lens's several
    /// orders too.
    #[test]
    fn binary2_gradient_under_a_line() {
        let source = example("phase-binary2.toml");
        let line = owned(&["spectrum.shape=\"line\"", "spectrum.center_nm=780", "spectrum.range_nm=1"]);
        check_binary2(&source, &line, &owned(&["lens.binary2[0]", "lens.binary2[1]", "lens.binary2[2]"]));
        let mut diffractive = line.clone();
        diffractive.extend(owned(&["lens.dispersion=\"diffractive\"", "lens.design_order=2"]));
        check_binary2(&source, &diffractive, &owned(&["lens.binary2[0]", "lens.binary2[1]"]));
    }

    /// `lens.parameter_bias[i]` with linear rows is refused naming the interpolation (a kink at
    /// every row; the option that makes the value smooth named).
    #[test]
    fn a_library_bias_with_linear_rows_is_refused_naming_the_interpolation() {
        let source = example("library.toml");
        let keys = owned(&["lens.parameter_bias[0]"]);
        let e = gradient(&source, &owned(&["lens.parameter_bias=[0]"]), &keys).unwrap_err().to_string();
        assert!(
            e.contains("--wrt lens.parameter_bias[0]: not differentiable with lens.library_interpolation = \"linear\"")
                && e.contains("lens.library_interpolation = \"cubic\""),
            "{e}"
        );
        // an index past the library's parameters
        let cubic = owned(&["lens.parameter_bias=[0]", "lens.library_interpolation=\"cubic\""]);
        let e = gradient(&source, &cubic, &owned(&["lens.parameter_bias[1]"])).unwrap_err().to_string();
        assert!(e.contains("lens.parameter_bias[1]"), "{e}");
    }

    /// `lens.parameter_bias[0]` of examples/library.toml with cubic rows, at a bias of 0.3 nm
    /// (the library's rows are 5 nm apart; no atom at a clamp), against central differences of
    /// evaluations converged at 1e-10: Richardson of steps 0.1 and 0.05 nm (the two steps'
    /// differences agree to well below the bound, so the step's error is not what is measured),
    /// within 10× the requested tolerance (1e-6) relative to the gradient's norm, for the ASNR,
    /// the mean MTF, SNR0 and N; plain, and with the glare included and the pixel MTF. The mean
    /// MTF barely moves with the bias (about 3e-6 per nm): its differences carry the converged
    /// evaluations' own error, up to 1e-10 of M̄ over the step (2e-9 per nm at 0.05 nm), which
    /// is added to its bound. Measured (`cargo test -p asnr-report --lib library_bias --
    /// --nocapture`): the ASNR within 4.3e-7 of its norm (6.6e-7 with the glare and the pixel
    /// MTF), the mean MTF within 6.1e-11 per nm; the lanes on the value's own rules.
    #[test]
    fn library_bias_matches_central_differences() {
        let source = example("library.toml");
        let key = "lens.parameter_bias[0]";
        for extra in [&[][..], &["options.glare=\"included\"", "camera.pixel_mtf=true"][..]] {
            let mut overrides = owned(&["lens.library_interpolation=\"cubic\"", "lens.parameter_bias=[0.3]"]);
            overrides.extend(owned(extra));
            let g = gradient(&source, &overrides, &owned(&[key])).unwrap();
            let (coarse, fine) =
                (central(&source, &overrides, key, 0.3, 0.1), central(&source, &overrides, key, 0.3, 0.05));
            let ours = [g.d_asnr[0], g.d_mean_mtf[0], g.d_snr0[0], g.d_photoelectrons[0]];
            for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
                let richardson = (4.0 * fine[q] - coarse[q]) / 3.0;
                let quantity = [g.asnr, g.mean_mtf, g.snr0, g.photoelectrons][q];
                // the differences' own error: the evaluations' tolerance over the smaller step
                let noise = REFERENCE_TOLERANCE * quantity / 0.05;
                let norm = ours[q].abs();
                let error = (ours[q] - richardson).abs();
                println!(
                    "{extra:?} {name}: gradient {:.9e}, Richardson {richardson:.9e} (steps {:.9e}, {:.9e}), error/norm {:.1e}",
                    ours[q],
                    coarse[q],
                    fine[q],
                    error / norm
                );
                assert!(error <= 1e-5 * norm + noise, "{extra:?} {name}: {} vs {richardson}", ours[q]);
                // the step's own error (the two steps' spread) is below the bound
                assert!(
                    (fine[q] - coarse[q]).abs() <= 1e-5 * norm + 2.0 * noise,
                    "{extra:?} {name}: {coarse:?} vs {fine:?}"
                );
            }
        }
    }

    /// `lens.atom_phase_error_rad` of examples/library.toml (docs/physics.md, "Gradients: a
    /// library's atoms' phase errors"): every atom's draw δ_i held (the seed fixed), its field
    /// moves by `iδ_i v_i`, through the lens's pupil as a parameter bias does; at σ = 0.1 rad and
    /// at 0 (where the draws are still the seed's; the key is ≥ 0, so one-sided there), with
    /// the glare and a relative amplitude error σ_t = 0.05 too, against Richardson-extrapolated
    /// central differences of evaluations converged at 1e-10 (steps 0.02 and 0.01 rad; at 0 the
    /// one-sided rule of order h³, h = 0.01 rad), within 10× the requested tolerance (1e-6)
    /// of each derivative plus the differences' own error (the evaluations' 1e-10 over the
    /// step), for the ASNR, the mean MTF, SNR0 and N.
    #[test]
    fn library_phase_error_matches_central_differences() {
        let source = example("library.toml");
        let key = "lens.atom_phase_error_rad";
        for (sigma, extra) in [
            (0.1, &[][..]),
            (0.0, &[][..]),
            (0.1, &["options.glare=\"included\"", "lens.atom_transmission_error=0.05"][..]),
        ] {
            let mut overrides = owned(&[&format!("{key}={sigma}")]);
            overrides.extend(owned(extra));
            let g = gradient(&source, &overrides, &owned(&[key])).unwrap();
            // σ ≥ 0: at 0 the one-sided differences of order h³,
            // D(h) = (−11 f(0) + 18 f(h) − 9 f(2h) + 2 f(3h))/(6h), Richardson-extrapolated
            // from h = 0.01 and 0.005 rad ((8 D(h/2) − D(h))/7)
            let (coarse, fine) = if sigma > 0.0 {
                (central(&source, &overrides, key, sigma, 0.02), central(&source, &overrides, key, sigma, 0.01))
            } else {
                let f: Vec<[f64; 4]> = (0..7).map(|j| converged(&source, &overrides, key, 0.005 * j as f64)).collect();
                let one_sided = |s: usize, h: f64| -> [f64; 4] {
                    std::array::from_fn(|q| {
                        (-11.0 * f[0][q] + 18.0 * f[s][q] - 9.0 * f[2 * s][q] + 2.0 * f[3 * s][q]) / (6.0 * h)
                    })
                };
                let (d_h, d_half) = (one_sided(2, 0.01), one_sided(1, 0.005));
                // as (4 fine − coarse)/3 below reads it: fine = (7 R + coarse)/4
                let r: [f64; 4] = std::array::from_fn(|q| (8.0 * d_half[q] - d_h[q]) / 7.0);
                (d_h, std::array::from_fn(|q| (3.0 * r[q] + d_h[q]) / 4.0))
            };
            let ours = [g.d_asnr[0], g.d_mean_mtf[0], g.d_snr0[0], g.d_photoelectrons[0]];
            assert!(ours[0] != 0.0, "{g:?}");
            for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
                let richardson = (4.0 * fine[q] - coarse[q]) / 3.0;
                let quantity = [g.asnr, g.mean_mtf, g.snr0, g.photoelectrons][q];
                // the differences' own error: the evaluations' tolerance times the sum of the
                // rule's weights (1/h for the central Richardson; (8·80/6 + 40/6)/7 ≈ 16.2
                // over h for the one-sided one)
                let noise = REFERENCE_TOLERANCE * quantity / 0.01 * if sigma > 0.0 { 1.0 } else { 16.2 };
                let error = (ours[q] - richardson).abs();
                println!(
                    "σ = {sigma} {extra:?} {name}: gradient {:.9e}, Richardson {richardson:.9e} (steps {:.9e}, {:.9e}), \
                     error/|gradient| {:.1e}",
                    ours[q],
                    coarse[q],
                    fine[q],
                    error / ours[q].abs()
                );
                assert!(
                    error <= 1e-5 * ours[q].abs() + noise,
                    "σ = {sigma} {extra:?} {name}: {} vs {richardson}",
                    ours[q]
                );
            }
        }
    }

    /// One key's gradient `g` (ASNR, mean MTF, SNR0, N; none zero) against the Richardson
    /// extrapolation `(4 fine − coarse)/3` of central differences at the steps `2h` and `h` of
    /// evaluations at the tolerance `reference`: within `bound` of each derivative plus the
    /// differences' own error, `reference` times the quantity over `h`; printed after `label`.
    fn one_key_within(
        g: &Gradient,
        (coarse, fine): ([f64; 4], [f64; 4]),
        h: f64,
        reference: f64,
        bound: f64,
        label: &str,
    ) {
        let ours = [g.d_asnr[0], g.d_mean_mtf[0], g.d_snr0[0], g.d_photoelectrons[0]];
        assert!(ours.iter().all(|d| *d != 0.0), "{g:?}");
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            let richardson = (4.0 * fine[q] - coarse[q]) / 3.0;
            let quantity = [g.asnr, g.mean_mtf, g.snr0, g.photoelectrons][q];
            let noise = reference * quantity / h;
            let error = (ours[q] - richardson).abs();
            println!(
                "{label} {name}: gradient {:.9e}, Richardson {richardson:.9e} (steps {:.9e}, {:.9e}), \
                 error/|gradient| {:.1e}",
                ours[q],
                coarse[q],
                fine[q],
                error / ours[q].abs()
            );
            assert!(error <= bound * ours[q].abs() + noise, "{label} {name}: {} vs {richardson}", ours[q]);
        }
    }

    /// The library lens off axis (its radial pupil seen by the oblique wave, on the FFT path:
    /// docs/physics.md, "Gradients: a library's parameter bias"): `lens.parameter_bias[0]` with
    /// cubic rows at 0.3 nm and `lens.atom_phase_error_rad` at 0.1 rad, each atom's field moving
    /// the sampled pupil by the complex lane `A(∂a + ik a ∂W)e^{ikW}` and the order's efficiency;
    /// examples/library.toml at 3° (the bias also at (3°, 2°) with the glare included and the
    /// pixel MTF; the phase errors under a noise spectrum, the weighted mean's lane in ∂ASNR) on
    /// a 4 nm band at a fixed sampling (`options.pupil_samples = 64`, so that the grids' pixels
    /// are the same at both points), against Richardson-extrapolated central differences of
    /// evaluations at 1e-9 (steps 0.1 and 0.05 nm, 0.02 and 0.01 rad): the gradient asked at
    /// 1e-9 within 1e-5 of each derivative plus the differences' own error (the evaluations'
    /// 1e-9 over the smaller step), for the ASNR, the mean MTF, SNR0 and N; asked at the scene's
    /// 1e-6, the ASNR's within 10× that of itself (its mean MTF's carries the value's own error
    /// at 1e-6, about 1e-6 of M̄ over the key's scale: 3.2e-5 of ∂M̄/∂σ for the phase errors).
    /// Measured: at 1e-9 the ASNR within 1.6e-6 of its derivative (the bias) and 4.6e-8 (the
    /// phase errors), the mean MTF's ∂M̄/∂σ within 1.5e-7, N within 6.8e-7; at 1e-6 the ASNR
    /// within 2.3e-6 and 4.8e-6.
    #[test]
    fn fft_library_bias_and_phase_error_off_axis_match_central_differences() {
        let library = example("library.toml");
        let noisy = with_noise_spectrum_beside(&library, "library-fft");
        let reference = 1e-9;
        for (source, key, value, h, extra) in [
            (&library, "lens.parameter_bias[0]", 0.3, 0.05, &["field.x_deg=3"][..]),
            (
                &library,
                "lens.parameter_bias[0]",
                0.3,
                0.05,
                &["field.x_deg=3", "field.y_deg=2", "options.glare=\"included\"", "camera.pixel_mtf=true"][..],
            ),
            // under a noise spectrum: the weighted mean's lane in ∂ASNR, the white one's in ∂M̄
            (&noisy, "lens.atom_phase_error_rad", 0.1, 0.01, &["field.x_deg=3"][..]),
        ] {
            let mut overrides = owned(&[
                "lens.library_interpolation=\"cubic\"",
                "lens.parameter_bias=[0.3]",
                "lens.atom_phase_error_rad=0.1",
                "spectrum.range_nm=4",
                "options.pupil_samples=64",
            ]);
            overrides.extend(owned(extra));
            let started = std::time::Instant::now();
            let e = metric::evaluate(&scene::build_from(source, &overrides).unwrap()).unwrap();
            assert!(e.numerics.engine.starts_with("fft"), "{}", e.numerics.engine);
            // at the scene's 1e-6, the ASNR's derivative within 10× that of itself (the mean
            // MTF's carries the value's own error at 1e-6, about 1e-6 M̄ over the key's scale)
            let at_scene = gradient(source, &overrides, &owned(&[key])).unwrap();
            // at the references' tolerance, every quantity's: the derivative of the same rule
            let mut asked = overrides.clone();
            asked.push(format!("options.tolerance={reference:e}"));
            let g = gradient(source, &asked, &owned(&[key])).unwrap();
            let (coarse, fine) = (
                central_at(source, &overrides, key, value, 2.0 * h, reference),
                central_at(source, &overrides, key, value, h, reference),
            );
            one_key_within(&g, (coarse, fine), h, reference, 1e-5, &format!("{key} {extra:?}"));
            let richardson = (4.0 * fine[0] - coarse[0]) / 3.0;
            let error = (at_scene.d_asnr[0] - richardson).abs() / at_scene.d_asnr[0].abs();
            println!(
                "{key} {extra:?} ASNR at 1e-6: gradient {:.9e}, error/|gradient| {error:.1e}; mean MTF {:.9e}",
                at_scene.d_asnr[0], at_scene.d_mean_mtf[0]
            );
            assert!(error <= 1e-5, "{key} {extra:?}: {} vs {richardson}", at_scene.d_asnr[0]);
            println!("{key} {extra:?}: {:?}", started.elapsed());
        }
    }

    /// The sections after `[lens]` of the small 2-D layouts' scenes: a 4 nm top-hat at 800 nm, the
    /// paper's camera without the pixel MTF, 64 pupil samples (the FFT path's discrete rule).
    const LAYOUT_SCENE_REST: &str = r#"[source]
kind = "flat"
radiance_w_m2_sr_nm = 0.025

[spectrum]
shape = "tophat"
center_nm = 800.0
range_nm = 4.0

[camera]
pixel_pitch_um = 5.2
pixel_mtf = false
quantum_efficiency = 0.2

[exposure]
time_ms = 1.23

[options]
pupil_samples = 64
"#;

    /// A small 2-D layout (a `.npy` grid of examples/data/library-tio2-like.csv's pillars, F/2.5,
    /// f0 = 125 µm, R = 25 µm on a 400 nm lattice, 129 × 129 sites: each site the diameter whose
    /// field at 800 nm is nearest the hyperbolic phase at its centre, among those 10 nm inside the
    /// library's range, and every 11th site empty, the substrate), its scene written in a fresh
    /// directory (cli/tests/design.rs builds the same grid without the empty sites).
    fn small_layout_grid(name: &str) -> Source {
        let library = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/data/library-tio2-like.csv");
        let text = std::fs::read_to_string(&library).unwrap();
        let mut rows = Vec::new();
        for line in text.lines().filter(|l| !l.starts_with('#') && !l.starts_with("diameter")) {
            let v: Vec<f64> = line.split(',').map(|s| s.trim().parse().unwrap()).collect();
            if v[1] == 800.0 {
                rows.push((v[0], v[2] * v[3].cos(), v[2] * v[3].sin()));
            }
        }
        let (pitch, f0, half) = (400.0f64, 125e3f64, 64usize);
        let n = 2 * half + 1;
        let mut grid = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                let (x, y) = ((i as f64 - half as f64) * pitch, (j as f64 - half as f64) * pitch);
                let target = -std::f64::consts::TAU / 800.0 * ((x * x + y * y + f0 * f0).sqrt() - f0);
                let (tx, ty) = (target.cos(), target.sin());
                let d = |r: &(f64, f64, f64)| (r.1 - tx).powi(2) + (r.2 - ty).powi(2);
                let inner = rows.iter().filter(|r| (110.0..=290.0).contains(&r.0));
                // every 11th site (a diagonal pattern) empty: the substrate, which no key moves
                let empty = (7 * i + 3 * j) % 11 == 0;
                grid.push(if empty { f64::NAN } else { inner.min_by(|a, b| d(a).total_cmp(&d(b))).unwrap().0 });
            }
        }
        let dir = std::env::temp_dir().join(format!("asnr-layout-gradient-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("lens.npy"), scene::npy::npy_f64(&[n, n], &grid).unwrap()).unwrap();
        let text = format!(
            r#"[lens]
model = "library"
f_number = 2.5
focal_length_mm = 0.125
design_wavelength_nm = 800.0
library = {library:?}
library_interpolation = "cubic"
layout_grid = "lens.npy"
lattice_pitch_um = 0.4
empty_cell = "substrate"
parameter_bias = [0.0]

{rest}"#,
            library = library.display().to_string(),
            rest = LAYOUT_SCENE_REST
        );
        Source::from_text(text, "a small 2-D layout", dir)
    }

    /// A 2-D layout (`lens.layout_grid`: a site map on the FFT path, on and off axis;
    /// docs/physics.md, "Gradients: a library's parameter bias", "… atoms' phase errors"):
    /// `lens.parameter_bias[0]` with cubic rows (each atom's `∂t`, the site map's field sampled
    /// with the table replaced by it, on the block path at `options.pupil_samples = 64`, samples
    /// wider than a site, and on the point path at 128, narrower) and `lens.atom_phase_error_rad`
    /// at 0.1 rad (each atom's table entry times `−σ`, the stray power `2σ|t|²E[a]²e^{−σ²}`; the
    /// empty sites do not move, so the mean MTF does), against
    /// Richardson-extrapolated central differences of evaluations at 1e-10 at the same fixed
    /// sampling (steps 0.5 and 0.25 nm, 0.02 and 0.01 rad), every quantity (ASNR, mean MTF, SNR0,
    /// N) within 10× the gradient's requested tolerance (1e-9) of its own size plus the
    /// differences' own error (the evaluations' 1e-10 over the smaller step); the bias also with
    /// transmission errors (σ_t = 0.1 at 1° with the glare included: each entry's factor `E[a]`
    /// moving with `|t|` through its cap `1/|t|`), and `lens.atom_transmission_error` itself at
    /// σ_t = 0.1 (the clipped moments' derivative in σ_t; steps 0.004 and 0.002); with linear rows
    /// refused, naming the key.
    #[test]
    fn layout_grid_bias_and_phase_error_match_central_differences() {
        let reference = 1e-10;
        let asked = 1e-9;
        for (key, value, h, extra) in [
            ("lens.parameter_bias[0]", 0.0, 0.25, &[][..]),
            ("lens.parameter_bias[0]", 0.0, 0.25, &["options.pupil_samples=128", "field.x_deg=2"][..]),
            ("lens.atom_phase_error_rad", 0.1, 0.01, &["field.y_deg=2", "options.glare=\"included\""][..]),
            // transmission errors: each atom's error factor E[a] moves with |t| through its cap
            (
                "lens.parameter_bias[0]",
                0.0,
                0.25,
                &["lens.atom_transmission_error=0.1", "options.glare=\"included\"", "field.x_deg=1"][..],
            ),
            // σ_t itself: the clipped moments E[a], E[a²] smooth in it, but curved on the scale of
            // σ_t (the differences' h⁴ term is 1.3e-6 of the derivative at steps 0.02 and 0.01)
            (
                "lens.atom_transmission_error",
                0.1,
                0.002,
                &["lens.atom_transmission_error=0.1", "options.glare=\"included\""][..],
            ),
        ] {
            let started = std::time::Instant::now();
            let source = small_layout_grid("grid");
            let mut overrides = owned(&["lens.atom_phase_error_rad=0.1"]);
            overrides.extend(owned(extra));
            let e = metric::evaluate(&scene::build_from(&source, &overrides).unwrap()).unwrap();
            assert!(e.numerics.engine.starts_with("fft"), "{}", e.numerics.engine);
            let mut at = overrides.clone();
            at.push(format!("options.tolerance={asked:e}"));
            let g = gradient(&source, &at, &owned(&[key])).unwrap();
            let (coarse, fine) = (
                central_at(&source, &overrides, key, value, 2.0 * h, reference),
                central_at(&source, &overrides, key, value, h, reference),
            );
            one_key_within(&g, (coarse, fine), h, reference, 10.0 * asked, &format!("{key} {extra:?}"));
            println!("{key} {extra:?}: {:?}", started.elapsed());
        }
        // linear rows: a kink at every row, refused naming the key
        let source = small_layout_grid("refused");
        let err =
            gradient(&source, &owned(&["lens.library_interpolation=\"linear\""]), &owned(&["lens.parameter_bias[0]"]))
                .unwrap_err()
                .to_string();
        assert!(err.contains("--wrt lens.parameter_bias[0]") && err.contains("cubic"), "{err}");
    }

    /// A small 2-D layout of fins (a GDSII of rectangles, F/2.5, f0 = 31.25 µm, R = 6.25 µm on a
    /// 400 nm lattice, 33 × 33 sites, every 11th empty: the substrate), each fin's angle half the
    /// hyperbolic phase at its site (lit LCP: `+2θ`), its width one of 62.5, 67.5, …, 87.5 nm by
    /// site, in a fin library written here (`width_nm` 50–100 nm in rows of 5 nm, `length_nm`
    /// 200 and 300 nm, 700–900 nm): `|t| = 0.7 − 0.25 sin(w/20 nm)` (0.70–0.94 in the layout, so
    /// that transmission errors of σ_t = 0.1 reach the cap `1/|t|`), `φ = 0.3 + w/200 nm`, and
    /// the fins' unconverted light `|t_co| = 0.3 + 0.1 cos(w/25 nm)`; the widths midway between
    /// rows, so that a step of 1 nm crosses none of the cubic's rows.
    fn small_fin_layout(name: &str) -> Source {
        let dir = std::env::temp_dir().join(format!("asnr-fin-gradient-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut csv = String::from("width_nm,length_nm,wavelength_nm,amplitude,phase_rad,co_amplitude\n");
        for i in 0..=10 {
            let w = 50.0 + 5.0 * i as f64;
            for l in [200.0, 300.0] {
                for lambda in [700.0, 800.0, 900.0] {
                    let (a, phi, co) = (0.7 - 0.25 * (w / 20.0).sin(), 0.3 + w / 200.0, 0.3 + 0.1 * (w / 25.0).cos());
                    csv.push_str(&format!("{w},{l},{lambda},{a},{phi},{co}\n"));
                }
            }
        }
        std::fs::write(dir.join("fins.csv"), csv).unwrap();
        // coordinates in picometres (the database unit), so that a fin's corners are right
        // angles to the reader's 0.06°
        let file = std::io::BufWriter::new(std::fs::File::create(dir.join("lens.gds")).unwrap());
        let mut w = scene::gds::Writer::new(file, 1e-12).unwrap();
        w.begin_cell("LENS").unwrap();
        let (pitch, f0, half) = (400e3f64, 31.25e6f64, 16i64);
        for j in -half..=half {
            for i in -half..=half {
                if (7 * (i + half) + 3 * (j + half)) % 11 == 0 {
                    continue;
                }
                let (x, y) = (i as f64 * pitch, j as f64 * pitch);
                let target = -std::f64::consts::TAU / 800e3 * ((x * x + y * y + f0 * f0).sqrt() - f0);
                let theta = 0.5 * target;
                let width = 62.5e3 + 5e3 * ((5 * i + 2 * j).rem_euclid(6)) as f64;
                let (half_l, half_w) = (125e3, 0.5 * width);
                let (c, s) = (theta.cos(), theta.sin());
                let corner = |a: f64, b: f64| ((x + a * c - b * s).round() as i32, (y + a * s + b * c).round() as i32);
                let points = [
                    corner(-half_l, -half_w),
                    corner(half_l, -half_w),
                    corner(half_l, half_w),
                    corner(-half_l, half_w),
                ];
                w.polygon(1, 0, &points).unwrap();
            }
        }
        w.end_cell().unwrap();
        w.finish().unwrap();
        let text = r#"[lens]
model = "library"
f_number = 2.5
focal_length_mm = 0.03125
design_wavelength_nm = 800.0
library = "fins.csv"
library_interpolation = "cubic"
layout_gds = "lens.gds"
gds_layer = 1
atom = "fin"
handedness = "lcp"
lattice_pitch_um = 0.4
empty_cell = "substrate"
parameter_bias = [0.0, 0.0]

"#;
        let text = format!("{text}{LAYOUT_SCENE_REST}glare = \"included\"\n");
        Source::from_text(text, "a small 2-D layout of fins", dir)
    }

    /// A 2-D layout of fins whose library gives their unconverted light (`co_amplitude`: zero-
    /// order light, in T and not in τ1), with transmission errors (docs/physics.md, "Gradients:
    /// a library's parameter bias"): `lens.parameter_bias[0]` (the width), each atom's table
    /// entry `t E[a](|t|) e^{−σ_φ²/2}` moving through its cap, `∂T` adding `2|t_co| ∂|t_co|` per
    /// atom and the stray power's derivative, with the glare included, against
    /// Richardson-extrapolated central differences (steps 0.5 and 0.25 nm) of evaluations at 1e-10
    /// at the same fixed sampling (`options.pupil_samples = 64`): every quantity (ASNR, mean MTF,
    /// SNR0, N) within 10× the gradient's requested tolerance (1e-9) of its own size plus the
    /// differences' own error (the evaluations' 1e-10 over the smaller step).
    #[test]
    fn fin_layout_bias_with_unconverted_light_and_transmission_errors_matches_central_differences() {
        let (reference, asked, key, h) = (1e-10, 1e-9, "lens.parameter_bias[0]", 0.25);
        let started = std::time::Instant::now();
        let source = small_fin_layout("co");
        let overrides = owned(&["lens.atom_transmission_error=0.1", "lens.atom_phase_error_rad=0.1"]);
        let e = metric::evaluate(&scene::build_from(&source, &overrides).unwrap()).unwrap();
        assert!(e.numerics.engine.starts_with("fft"), "{}", e.numerics.engine);
        let mut at = overrides.clone();
        at.push(format!("options.tolerance={asked:e}"));
        let g = gradient(&source, &at, &owned(&[key])).unwrap();
        let (coarse, fine) = (
            central_at(&source, &overrides, key, 0.0, 2.0 * h, reference),
            central_at(&source, &overrides, key, 0.0, h, reference),
        );
        one_key_within(&g, (coarse, fine), h, reference, 10.0 * asked, &format!("fins {key}"));
        println!("fins {key}: {:?}", started.elapsed());
    }

    /// Bad keys are refused naming the key.
    #[test]
    fn bad_keys_are_refused_naming_the_key() {
        let source = example("phase-binary2.toml");
        let refused = |keys: &[&str]| gradient(&source, &[], &owned(keys)).unwrap_err().to_string();
        let e = refused(&["lens.colour"]);
        assert!(e.contains("--wrt lens.colour") && e.contains("has no such key"), "{e}");
        let e = refused(&["camera.gain_dn_per_e"]);
        assert!(e.contains("--wrt camera.gain_dn_per_e") && e.contains("has no such key"), "{e}");
        let e = refused(&["exposure.time_ms", "exposure.time_ms"]);
        assert!(e.contains("exposure.time_ms is given twice"), "{e}");
        let e = refused(&["lens.binary2[1]", "lens.binary2[01]"]);
        assert!(e.contains("lens.binary2[1] is given twice (as `lens.binary2[1]` and `lens.binary2[01]`)"), "{e}");
        let e = refused(&["lens.binary2", "lens.binary2[3]"]);
        assert!(e.contains("lens.binary2[3] is given twice"), "{e}");
        let e = refused(&["lens.binary2[7]"]);
        assert!(e.contains("--wrt lens.binary2[7]") && e.contains("has 4 entries"), "{e}");
        let e = refused(&["lens.diffraction_order"]);
        assert!(e.contains("--wrt lens.diffraction_order: not differentiable: it is an integer"), "{e}");
        let e = refused(&["options.tolerance"]);
        assert!(e.contains("--wrt options.tolerance: not differentiable"), "{e}");
        let e = refused(&["lens.model"]);
        assert!(e.contains("lens.model = \"phase\" is not a number"), "{e}");
        let e = gradient(&example("library.toml"), &[], &owned(&["lens.f_number"])).unwrap_err().to_string();
        assert!(
            e.contains("--wrt lens.f_number: not differentiable here yet for lens.model = \"library\"")
                && e.contains("aperture radius"),
            "{e}"
        );
        let e = refused(&[]);
        assert!(e.contains("--wrt"), "{e}");
        // saturation is a kink
        let e = gradient(&source, &owned(&["camera.full_well_e=100"]), &owned(&["exposure.time_ms"]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not differentiable") && e.contains("saturates"), "{e}");
    }

    /// The JSON has the fields `asnr gradient --json` promises, keys in their canonical spelling.
    #[test]
    fn json_has_the_promised_fields() {
        let source = scene::read(None).unwrap();
        let g = gradient(&source, &[], &owned(&[" exposure . time_ms ", "camera.pixel_pitch_um"])).unwrap();
        let json = serde_json::to_value(&g).unwrap();
        for field in ["asnr", "mean_mtf", "snr0", "photoelectrons"] {
            assert!(json[field].is_f64(), "{field}: {json}");
        }
        for field in ["gradient", "mean_mtf_gradient", "snr0_gradient", "photoelectrons_gradient"] {
            let object = json[field].as_object().unwrap();
            let mut keys: Vec<&String> = object.keys().collect();
            keys.sort();
            assert_eq!(keys, ["camera.pixel_pitch_um", "exposure.time_ms"], "{json}");
        }
        assert_eq!(json["gradient"]["exposure.time_ms"].as_f64().unwrap(), g.d_asnr[0]);
        let text = table(&g);
        assert!(text.contains("exposure.time_ms") && text.contains("∂ln ASNR/∂ln key"), "{text}");
    }

    /// (ASNR, mean MTF) of an evaluation with `key = value` and `overrides` (no tolerance added).
    fn evaluated(source: &Source, overrides: &[String], key: &str, value: f64) -> [f64; 2] {
        let mut set: Vec<String> =
            overrides.iter().filter(|o| o.split_once('=').is_none_or(|(k, _)| k.trim() != key)).cloned().collect();
        set.push(assignment(key, value));
        let e = metric::evaluate(&scene::build_from(source, &set).unwrap()).unwrap();
        [e.asnr, e.mean_mtf]
    }

    /// Each key's gradient on the FFT path against central differences of the same discrete rule
    /// (the sampling fixed by `options.pupil_samples`, so that the grids, the interpolation, the
    /// fixed frequency rule and the azimuths are the value's at both points): forward mode
    /// through the FFT is the derivative of that rule, so the two agree to the differences' own
    /// error (step `h`, values exact to rounding: measured ≤ 2e-9 of the norm at h = 1e-5 µm).
    fn check_discrete_rule(source: &Source, overrides: &[String], keys: &[String], h: f64) -> Gradient {
        let g = gradient(source, overrides, keys).unwrap();
        let norm = g.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(norm > 0.0, "a zero gradient: {g:?}");
        for (i, k) in g.keys.iter().enumerate() {
            let up = evaluated(source, overrides, k, g.values[i] + h);
            let down = evaluated(source, overrides, k, g.values[i] - h);
            let theirs = (up[1] - down[1]) / (2.0 * h);
            let error = (g.d_mean_mtf[i] - theirs).abs() / norm;
            println!("{k}: gradient {:.9e}, differences {theirs:.9e}, error/norm {error:.1e}", g.d_mean_mtf[i]);
            assert!(error <= 1e-6, "{k}: {} vs {theirs} (norm {norm})", g.d_mean_mtf[i]);
            // ASNR = SNR0 · M̄, SNR0 does not move with the wavefront
            assert_eq!(g.d_snr0[i], 0.0);
            assert!((g.d_asnr[i] - g.snr0 * g.d_mean_mtf[i]).abs() <= 1e-12 * g.snr0 * norm);
        }
        g
    }

    /// Seidel terms beside Zernike terms on the FFT path (the order a radial pupil carrying the
    /// Zernike terms, its Seidel terms sampled with them: docs/physics.md, "Gradients: 2-D
    /// pupils"), the four Seidel keys and a Zernike key in one pass, over a band on axis and at
    /// 3° along y, and under a line, against the discrete rule's central differences (step
    /// 1e-5 µm).
    #[test]
    fn fft_seidel_beside_zernike_terms_is_the_derivative_of_the_discrete_rule() {
        let source = scene::read(None).unwrap();
        let keys = owned(&[
            "lens.spherical_um",
            "lens.coma_um",
            "lens.astigmatism_um",
            "lens.field_curvature_um",
            "lens.zernike_noll_rms_um[5]",
        ]);
        let terms = [
            "options.pupil_samples=64",
            "lens.spherical_um=0.05",
            "lens.coma_um=0.1",
            "lens.astigmatism_um=-0.05",
            "lens.field_curvature_um=0.03",
            "lens.zernike_noll_rms_um=[0, 0, 0, 0.02, 0.03, 0.01]",
        ];
        for more in [&["spectrum.range_nm=4"][..], &["spectrum.range_nm=4", "field.y_deg=3"], &LINE_803] {
            check_discrete_rule(&source, &joined(&terms, more), &keys, 1e-5);
        }
    }

    /// Zernike terms with m ≠ 0 (and the m = 0 defocus of the same 2-D pupil) on the paper's
    /// chromatic lens, which takes them through the FFT path (docs/physics.md, "Gradients: 2-D
    /// pupils"): Noll 1–7 against the discrete rule's central differences. Piston and tilt
    /// move nothing (|O| does not change under a constant or a shift).
    #[test]
    fn fft_zernike_gradient_is_the_derivative_of_the_discrete_rule() {
        let source = scene::read(None).unwrap();
        let overrides = owned(&[
            "spectrum.range_nm=4",
            "options.pupil_samples=64",
            "lens.zernike_noll_rms_um=[0, 0, 0, 0.05, 0.1, 0.0, 0.05]",
        ]);
        let g = check_discrete_rule(&source, &overrides, &owned(&["lens.zernike_noll_rms_um"]), 1e-5);
        let norm = g.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
        for i in [0, 1, 2] {
            assert!(g.d_mean_mtf[i].abs() <= 1e-4 * norm, "Noll {}: {g:?}", i + 1);
        }
        // with the pixel MTF (inside the same fixed rule)
        let mut pixel = overrides.clone();
        pixel.push("camera.pixel_mtf=true".to_owned());
        check_discrete_rule(&source, &pixel, &owned(&["lens.zernike_noll_rms_um[4]"]), 1e-5);
        // the pixel pitch without and with the pixel MTF (its sinc's term P_ν on the same fixed
        // rule; docs/physics.md, "Gradients: the pixel pitch with the pixel MTF"). The pitch
        // moves the fixed rule's end ν_N, so its nodes: the discrete rule's derivative differs
        // from Leibniz' rule by the rate of the rule's own error (below the FFT path's 3e-6):
        // measured, in ∂/∂ln p against the ASNR's and the mean MTF's values, 2.3e-6 without the
        // pixel MTF and 2.4e-6 with it (the same 3e-7 per µm of ∂M̄/∂p both ways); within 1e-5. The step 1e-5 µm moves no panel (their number
        // ⌈2ν_N/cell⌉ is the same at p ± h).
        for set in [&overrides, &pixel] {
            let g = gradient(&source, set, &owned(&["camera.pixel_pitch_um"])).unwrap();
            let (p, h) = (g.values[0], 1e-5);
            let up = evaluated(&source, set, "camera.pixel_pitch_um", p + h);
            let down = evaluated(&source, set, "camera.pixel_pitch_um", p - h);
            for (q, (mine, value)) in [(g.d_asnr[0], g.asnr), (g.d_mean_mtf[0], g.mean_mtf)].into_iter().enumerate() {
                let theirs = (up[q] - down[q]) / (2.0 * h);
                let error = (mine - theirs).abs() * p / value;
                println!("pixel pitch {set:?} {q}: gradient {mine:.9e}, differences {theirs:.9e}, error {error:.1e}");
                assert!(error <= 1e-5, "{q}: {mine} vs {theirs}");
            }
        }
    }

    /// The phase lens off axis (the oblique wave's coma and astigmatism put it on the FFT path):
    /// Binary 2 coefficients and a Zernike term with m ≠ 0, against the discrete rule's central
    /// differences (steps 1e-3 rad and 1e-5 µm in one pass: the check takes the larger).
    #[test]
    fn fft_binary2_off_axis_is_the_derivative_of_the_discrete_rule() {
        let source = example("phase-binary2.toml");
        let overrides = owned(&[
            "field.x_deg=5",
            "spectrum.range_nm=10",
            "options.pupil_samples=64",
            "lens.zernike_noll_rms_um=[0, 0, 0, 0, 0, 0.03]",
        ]);
        check_discrete_rule(&source, &overrides, &owned(&["lens.binary2[0]", "lens.binary2[1]"]), 1e-3);
        check_discrete_rule(&source, &overrides, &owned(&["lens.zernike_noll_rms_um[5]"]), 1e-5);
    }

    /// The phase lens's field angles off axis (the oblique wave's path moving with the angle:
    /// docs/physics.md, "Gradients: the field point") against the discrete rule's central
    /// differences (step 1e-3°), at 5° along x (∂/∂θy = 0 there: the pupil is symmetric about
    /// x) and at (5°, 3°).
    #[test]
    fn fft_field_angle_is_the_derivative_of_the_discrete_rule() {
        let source = example("phase-binary2.toml");
        for at in [["field.x_deg=5", "field.y_deg=0"], ["field.x_deg=5", "field.y_deg=3"]] {
            let mut overrides = owned(&["spectrum.range_nm=10", "options.pupil_samples=64"]);
            overrides.extend(owned(&at));
            check_discrete_rule(&source, &overrides, &owned(&["field.x_deg", "field.y_deg"]), 1e-3);
        }
    }

    /// The phase lens's F-number and focal length off axis (docs/physics.md, "Gradients: the
    /// F-number and the focal length of a phase lens off axis"): on the FFT path the aperture
    /// radius R = f0/(2F#) moves the profile given in r, the reference sphere and the oblique
    /// wave's path, f0 the sphere and the path as a whole, and F# the normalized frequency
    /// s = νλF# (by parts). Against central differences of the same discrete rule (the sampling
    /// fixed by `options.pupil_samples`), Richardson-extrapolated from relative steps 4e-6 and
    /// 2e-6 (the sphere's R ∂S/∂R ≈ 84 waves per unit ln R turns the value on a relative scale
    /// of about 5e-3), for ASNR, mean MTF, SNR0 and N, at 5° along x and at (5°, 3°) with the
    /// pixel MTF (its term of the integration by parts). By parts is the continuous rule's
    /// identity: the fixed composite rule's nodes move with s, so the discrete rule's
    /// derivative differs from it by the rate of the rule's own error; within 1e-5 of the
    /// norm, as the pixel pitch's on this path.
    #[test]
    fn fft_phase_lens_f_number_and_focal_length_off_axis() {
        let source = example("phase-binary2.toml");
        let keys = ["lens.f_number", "lens.focal_length_mm", "exposure.time_ms"];
        for at in [&["field.x_deg=5"][..], &["field.x_deg=5", "field.y_deg=3", "camera.pixel_mtf=true"][..]] {
            let mut overrides = owned(&["spectrum.range_nm=10", "options.pupil_samples=64"]);
            overrides.extend(owned(at));
            matches_the_fixed_rule(&source, &overrides, &keys, &format!("{at:?}"));
        }
    }

    /// The phase lens's F-number and focal length on axis with a Zernike term of m ≠ 0 (the
    /// pupil without rotational symmetry puts it on the FFT path: docs/physics.md, "Gradients:
    /// the F-number and the focal length of a phase lens off axis", whose lanes `P`, `T`, `S`
    /// are taken on axis without the oblique wave's two), with and without the pixel MTF, and
    /// over a `[[fields]]` list whose point on axis is on the FFT path too: against Richardson
    /// central differences of the same fixed rule, within 1e-5 of the norm.
    #[test]
    fn fft_phase_lens_f_number_and_focal_length_with_zernike_terms_on_axis() {
        let source = example("phase-binary2.toml");
        let keys = ["lens.f_number", "lens.focal_length_mm", "exposure.time_ms"];
        let zernike = "lens.zernike_noll_rms_um=[0, 0, 0, 0, 0, 0.03, 0, 0.02]";
        for at in [&[zernike][..], &[zernike, "camera.pixel_mtf=true"][..]] {
            let mut overrides = owned(&["spectrum.range_nm=10", "options.pupil_samples=64"]);
            overrides.extend(owned(at));
            matches_the_fixed_rule(&source, &overrides, &keys, &format!("{at:?}"));
        }
        let overrides = owned(&["spectrum.range_nm=10", "options.pupil_samples=64", zernike]);
        let list = with_fields(&source, &[(0.0, 1.0), (3.0, 2.0)]);
        matches_the_fixed_rule(&list, &overrides, &keys[..2], "0° and 3° with a Zernike term");
    }

    /// The phase lens's F-number and focal length on the FFT path under a noise spectrum (the
    /// lanes `P`, `T`, `S` and, off axis, the oblique wave's two on the value's noise-weighted
    /// pass, beside the weighted by-parts term: docs/physics.md, "Gradients: the F-number and
    /// the focal length of a phase lens off axis"), at 5° and on axis with a Zernike term of
    /// m ≠ 0, against Richardson central differences of the same fixed rule within 1e-5 of the
    /// norm, the weight making a difference ([`assert_weighted`]).
    #[test]
    fn fft_phase_lens_f_number_and_focal_length_under_a_noise_spectrum() {
        let source = with_noise_spectrum(&example("phase-binary2.toml"), "phase-lens-fft");
        let keys = ["lens.f_number", "lens.focal_length_mm"];
        for at in [&["field.x_deg=5"][..], &["lens.zernike_noll_rms_um=[0, 0, 0, 0, 0, 0.03]"][..]] {
            let mut overrides = owned(&["spectrum.range_nm=10", "options.pupil_samples=64"]);
            overrides.extend(owned(at));
            matches_the_fixed_rule(&source, &overrides, &keys, &format!("{at:?} under a noise spectrum"));
            assert_weighted(&gradient(&source, &overrides, &owned(&keys)).unwrap());
        }
    }

    /// `source`'s gradient over `keys` under `overrides` against Richardson central differences
    /// (relative steps 4e-6 and 2e-6) of evaluations on the same fixed pupil sampling, for ∂ASNR,
    /// ∂M̄, ∂SNR0 and ∂N, within 1e-5 of each quantity's gradient norm (the FFT path's aperture
    /// lanes: the fixed rule's nodes move with the frequency scale, so the discrete rule's
    /// derivative differs from the lanes' by the rate of the rule's own error).
    fn matches_the_fixed_rule(source: &Source, overrides: &[String], keys: &[&str], label: &str) {
        let g = gradient(source, overrides, &owned(keys)).unwrap();
        let references = fixed_rule_references(source, overrides, &g);
        within_of_the_norm(&g, &references, 1e-5, label);
    }

    /// Richardson central differences (relative steps 4e-6 and 2e-6) of (ASNR, M̄, SNR0, N) of
    /// evaluations under `overrides` (the same fixed pupil sampling as the gradient's), for each
    /// of `g`'s keys at its value.
    pub(super) fn fixed_rule_references(source: &Source, overrides: &[String], g: &Gradient) -> Vec<[f64; 4]> {
        let rule = |k: &str, v: f64, h: f64| -> [f64; 4] {
            let at = |x: f64| {
                let mut set = overrides.to_vec();
                set.push(assignment(k, x));
                let e = metric::evaluate(&scene::build_from(source, &set).unwrap()).unwrap();
                [e.asnr, e.mean_mtf, e.snr0, e.photoelectrons]
            };
            let (up, down) = (at(v + h), at(v - h));
            std::array::from_fn(|q| (up[q] - down[q]) / (2.0 * h))
        };
        g.keys
            .iter()
            .zip(&g.values)
            .map(|(k, &v)| {
                let h = 2e-6 * v.abs();
                let (coarse, fine) = (rule(k, v, 2.0 * h), rule(k, v, h));
                std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0)
            })
            .collect()
    }

    /// Each of (ASNR, mean MTF, SNR0, N)'s derivatives in `g`, as ∂/∂ln key, against
    /// `references[key]`, within `bound` times that quantity's gradient norm (not zero); the
    /// errors/norm printed after `label`.
    fn within_of_the_norm(g: &Gradient, references: &[[f64; 4]], bound: f64, label: &str) {
        let ours = [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons];
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            let mine: Vec<f64> = (0..g.keys.len()).map(|i| ours[q][i] * g.values[i]).collect();
            let theirs: Vec<f64> = (0..g.keys.len()).map(|i| references[i][q] * g.values[i]).collect();
            let norm = mine.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(norm > 0.0, "{name}: {g:?}");
            for (i, k) in g.keys.iter().enumerate() {
                let error = (mine[i] - theirs[i]).abs() / norm;
                println!(
                    "{label} {name} {k}: gradient {:.9e}, differences {:.9e}, error/norm {error:.1e}",
                    mine[i], theirs[i]
                );
                assert!(error <= bound, "{label} {name} {k}: {} vs {}", mine[i], theirs[i]);
            }
        }
    }

    /// A `[[fields]]` list written here, appended to `source`'s text: `(x_deg, weight)` per point.
    fn with_fields(source: &Source, points: &[(f64, f64)]) -> Source {
        let mut text = source.text().to_owned();
        for (x, w) in points {
            text.push_str(&format!("\n[[fields]]\nx_deg = {x}\nweight = {w}\n"));
        }
        Source::from_text(text, "fields written in the test", source.dir())
    }

    /// The phase lens's F-number and focal length over a `[[fields]]` list with points off axis
    /// (docs/physics.md, "Gradients: the F-number and the focal length of a phase lens off axis":
    /// each point off axis on its own FFT pass with the oblique wave's lanes, a point on axis on
    /// the radial engine's; the field-of-view mean is the weighted mean of the points' values, so
    /// its gradient is the weighted mean of theirs). On a 10 nm band with
    /// `options.pupil_samples = 64`: at 3° and 5° (weights 1, 2) against Richardson central
    /// differences of the list's discrete rule (relative steps 4e-6 and 2e-6, as the single
    /// point's [`fft_phase_lens_f_number_and_focal_length_off_axis`]) for ∂ASNR, ∂M̄, ∂SNR0 and
    /// ∂N within 1e-5 of the norm; and at 0° and 3° (weights 1, 2) against each point's own
    /// `[field]` gradient times its weight over the weights' sum, to rounding.
    #[test]
    fn fov_phase_lens_f_number_and_focal_length_off_axis() {
        let source = example("phase-binary2.toml");
        let keys = ["lens.f_number", "lens.focal_length_mm"];
        let overrides = owned(&["spectrum.range_nm=10", "options.pupil_samples=64"]);
        matches_the_fixed_rule(&with_fields(&source, &[(3.0, 1.0), (5.0, 2.0)]), &overrides, &keys, "3° and 5°");
        // on axis and at 3°: the list's gradient the weighted mean of the points' own
        let overrides = owned(&["spectrum.range_nm=4"]);
        let list = gradient(&with_fields(&source, &[(0.0, 1.0), (3.0, 2.0)]), &overrides, &owned(&keys)).unwrap();
        let point = |x: &str| {
            let at = format!("field.x_deg={x}");
            gradient(&source, &joined(&["spectrum.range_nm=4"], &[at.as_str()]), &owned(&keys)).unwrap()
        };
        let (on_axis, off_axis) = (point("0"), point("3"));
        for (i, k) in keys.iter().enumerate() {
            for (ours, a, b) in [
                (list.d_asnr[i], on_axis.d_asnr[i], off_axis.d_asnr[i]),
                (list.d_mean_mtf[i], on_axis.d_mean_mtf[i], off_axis.d_mean_mtf[i]),
            ] {
                let mean = (a + 2.0 * b) / 3.0;
                assert!((ours - mean).abs() <= 1e-12 * a.abs().max(b.abs()), "{k}: {ours} vs {mean}");
            }
        }
    }

    /// The Seidel terms through the decentred iris of `examples/decentred-iris.toml` (the iris
    /// puts the Seidel pupil on the FFT path: docs/physics.md, "Gradients: Seidel terms through
    /// an iris"), on axis and at 3° along y, against the discrete rule's central differences
    /// (step 1e-5 µm).
    #[test]
    fn fft_seidel_through_an_iris_is_the_derivative_of_the_discrete_rule() {
        let iris = example("decentred-iris.toml");
        let keys = owned(&["lens.spherical_um", "lens.coma_um", "lens.astigmatism_um", "lens.field_curvature_um"]);
        for at in ["field.y_deg=0", "field.y_deg=3"] {
            let overrides = owned(&[
                "spectrum.range_nm=4",
                "options.pupil_samples=64",
                "lens.spherical_um=0.05",
                "lens.coma_um=0.1",
                "lens.astigmatism_um=-0.05",
                "lens.field_curvature_um=0.03",
                at,
            ]);
            check_discrete_rule(&iris, &overrides, &keys, 1e-5);
        }
    }

    /// The decentre of the iris of `examples/decentred-iris.toml` with Seidel terms, and of an
    /// annulus (docs/physics.md, "Gradients: the iris": the grid stays on the iris, whose
    /// decentre moves each pixel's OPD by the wavefront's slope there, its edges with it), on
    /// the FFT path: on axis with the four Seidel terms, at 3° along y with coma, and through
    /// the annulus of obscuration 0.3 with spherical aberration, against the discrete rule's
    /// central differences (step 1e-5 of the radius).
    #[test]
    fn fft_iris_decentre_with_seidel_terms_or_an_annulus_is_the_derivative_of_the_discrete_rule() {
        let iris = example("decentred-iris.toml");
        let keys = owned(&["lens.iris_decentre_x", "lens.iris_decentre_y"]);
        let base = ["spectrum.range_nm=4", "options.pupil_samples=64", "lens.iris_decentre_y=-0.1"];
        for more in [
            &[
                "lens.spherical_um=0.05",
                "lens.coma_um=0.1",
                "lens.astigmatism_um=-0.05",
                "lens.field_curvature_um=0.03",
            ][..],
            &["lens.coma_um=0.1", "field.y_deg=3"],
            &["lens.obscuration=0.3", "lens.spherical_um=0.05"],
            &["lens.obscuration=0.3"],
        ] {
            check_discrete_rule(&iris, &joined(&base, more), &keys, 1e-5);
        }
    }

    /// The Seidel terms of the paper's lens (a full circle) under a line at 803 nm, whose pupil
    /// is on the line's FFT grids (docs/physics.md, "Gradients: 2-D pupils under a line"): on
    /// axis and at 3° along x, against the discrete rule's central differences (step 1e-5 µm).
    #[test]
    fn fft_seidel_under_a_line_is_the_derivative_of_the_discrete_rule() {
        let paper = scene::read(None).unwrap();
        let keys = owned(&["lens.spherical_um", "lens.coma_um", "lens.astigmatism_um", "lens.field_curvature_um"]);
        let terms =
            ["lens.spherical_um=0.1", "lens.coma_um=0.05", "lens.astigmatism_um=0.05", "lens.field_curvature_um=0.05"];
        for at in ["field.x_deg=0", "field.x_deg=3"] {
            let overrides = joined(
                &joined(&LINE_803, &terms).iter().map(String::as_str).collect::<Vec<_>>(),
                &["options.pupil_samples=64", at],
            );
            check_discrete_rule(&paper, &overrides, &keys, 1e-5);
        }
    }

    /// `keys`' gradient at the tolerance `tolerance` against central differences of evaluations
    /// converged at 1e-10, Richardson-extrapolated from the steps `2h` and `h`
    /// ([`richardson`]), each quantity (ASNR, mean MTF, SNR0, N) within 10× the tolerance of its
    /// gradient's norm.
    fn check_at_tolerance(source: &Source, overrides: &[&str], keys: &[&str], tolerance: f64, h: f64) {
        let base = owned(overrides);
        let mut set = base.clone();
        set.push(format!("options.tolerance={tolerance:e}"));
        let g = gradient(source, &set, &owned(keys)).unwrap();
        let ours = [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons];
        let references: Vec<[f64; 4]> =
            g.keys.iter().zip(&g.values).map(|(k, v)| richardson(source, &base, k, *v, h)).collect();
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            let quantity = [g.asnr, g.mean_mtf, g.snr0, g.photoelectrons][q];
            let norm = match ours[q].iter().map(|x| x * x).sum::<f64>().sqrt() {
                0.0 => quantity,
                norm => norm,
            };
            for (i, k) in g.keys.iter().enumerate() {
                let error = (ours[q][i] - references[i][q]).abs() / norm;
                println!(
                    "{name} {k}: gradient {:.9e}, differences {:.9e}, error/norm {error:.1e}",
                    ours[q][i], references[i][q]
                );
                assert!(error <= 10.0 * tolerance, "{name} {k}: {} vs {} (norm {norm})", ours[q][i], references[i][q]);
            }
        }
    }

    /// The field angles off axis with Zernike terms on the overlap engine (docs/physics.md,
    /// "Gradients: the field point": the terms are fixed on the pupil, each order's image shift
    /// moves as the lens's without them): the paper's lens with Z4 = 0.02 µm and Z8 = 0.01 µm on
    /// a 4 nm band at (3°, 2°), the gradient at 1e-3 against central differences of evaluations
    /// converged at 1e-10 (steps 0.02° and 0.01°, Richardson), within 10× 1e-3 of the norm.
    #[test]
    fn field_angles_with_zernike_terms_match_central_differences() {
        let keys = ["field.x_deg", "field.y_deg"];
        let overrides = [
            "spectrum.range_nm=4",
            "lens.zernike_noll_rms_um=[0, 0, 0, 0.02, 0, 0, 0, 0.01]",
            "field.x_deg=3",
            "field.y_deg=2",
        ];
        check_at_tolerance(&scene::read(None).unwrap(), &overrides, &keys, 1e-3, 1e-2);
    }

    /// A blackbody's temperature over a band on the overlap engine (docs/physics.md, "Gradients:
    /// a line's wavelength and a blackbody's temperature": the engines of ρ and ρ ∂ln B/∂T read
    /// along the value's directions): the paper's lens lit by a 3000 K blackbody with Z4 and Z8
    /// on a 10 nm band, on axis and at 3° along x, the gradient at 1e-3 against central
    /// differences of evaluations converged at 1e-10 (relative steps, Richardson), within 10×
    /// 1e-3 of each quantity's norm.
    #[test]
    fn a_blackbody_temperature_on_the_overlap_engine_matches_central_differences() {
        let source = paper_blackbody();
        let keys = ["source.temperature_k"];
        let zernike = "lens.zernike_noll_rms_um=[0, 0, 0, 0.02, 0, 0, 0, 0.01]";
        for at in ["field.x_deg=0", "field.x_deg=3"] {
            check_at_tolerance(&source, &["spectrum.range_nm=10", zernike, at], &keys, 1e-3, relative_step("", 3000.0));
        }
    }

    /// The meta-atom library lens of `examples/library.toml` off axis: its imaging order is a
    /// radial pupil seen by the same oblique wave, so the same lanes; against the discrete
    /// rule's central differences at (5°, 3°) on a 4 nm band.
    #[test]
    fn fft_library_field_angle_is_the_derivative_of_the_discrete_rule() {
        let library = example("library.toml");
        let overrides = owned(&["spectrum.range_nm=4", "options.pupil_samples=64", "field.x_deg=5", "field.y_deg=3"]);
        check_discrete_rule(&library, &overrides, &owned(&["field.x_deg", "field.y_deg"]), 2e-4);
    }

    /// The gradient at the sampling the tolerance chooses (Richardson of N/2 and N) at
    /// `tolerance`, against central differences of evaluations at the tighter `reference`
    /// tolerance (a 4 nm band, so that they take seconds), within 10× `tolerance` of the
    /// gradient's norm. The mean MTF turns fast in these terms (|f‴| ≈ 200 per µm³ for Z7 here:
    /// the differences at h = 0.023, 0.01, 0.003 µm gave −1.1608, −1.1757, −1.1789 against a
    /// gradient of −1.1792), so the differences at h = 6 and 3 nm RMS are extrapolated
    /// (Richardson, `(4 D(h/2) − D(h))/3`, truncation O(h⁴)); the evaluations' own error is
    /// smooth in the key at a fixed sampling, and cancels in the differences but for the part
    /// that varies over the step. The chromatic lens's Zernike terms now take the overlap engine
    /// (docs/physics.md, "Zernike terms on the overlap engine"), so this checks its gradient at
    /// a loose tolerance: measured 3.3e-5 and 1.0e-4 of the norm at 1e-3.
    fn check_converged(tolerance: f64, reference: f64) {
        let source = scene::read(None).unwrap();
        let base = owned(&["spectrum.range_nm=4", "lens.zernike_noll_rms_um=[0, 0, 0, 0.05, 0.1, 0, 0.05]"]);
        let keys = owned(&["lens.zernike_noll_rms_um[4]", "lens.zernike_noll_rms_um[6]"]);
        let mut set = base.clone();
        set.push(format!("options.tolerance={tolerance:e}"));
        let g = gradient(&source, &set, &keys).unwrap();
        let mut at_reference = base.clone();
        at_reference.push(format!("options.tolerance={reference:e}"));
        let norm = g.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
        for (i, k) in g.keys.iter().enumerate() {
            let d = |h: f64| {
                let up = evaluated(&source, &at_reference, k, g.values[i] + h);
                let down = evaluated(&source, &at_reference, k, g.values[i] - h);
                (up[1] - down[1]) / (2.0 * h)
            };
            let (coarse, fine) = (d(0.006), d(0.003));
            let theirs = (4.0 * fine - coarse) / 3.0;
            let error = (g.d_mean_mtf[i] - theirs).abs() / norm;
            println!(
                "tolerance {tolerance:e} {k}: gradient {:.7e}, differences at {reference:e} {theirs:.7e} \
                 (h = 6, 3 nm: {coarse:.7e}, {fine:.7e}), error/norm {error:.1e}",
                g.d_mean_mtf[i]
            );
            assert!(error <= 10.0 * tolerance, "{k}: {} vs {theirs} (norm {norm})", g.d_mean_mtf[i]);
        }
    }

    /// [`check_converged`] at the tolerance 1e-3, the references at 1e-4.
    #[test]
    fn fft_zernike_gradient_matches_converged_differences() {
        check_converged(1e-3, 1e-4);
    }

    /// [`check_converged`] at the default FFT tolerance 1e-4, the references at 1e-5: ignored
    /// by default (the four reference evaluations at 1e-5 take about half a minute each in a
    /// debug build); `cargo test -p asnr-report --lib fft_zernike_gradient_at_1e_4 -- --ignored`.
    #[test]
    #[ignore = "slow: reference evaluations at 1e-5 on the FFT path"]
    fn fft_zernike_gradient_at_1e_4_matches_converged_differences() {
        check_converged(1e-4, 1e-5);
    }

    /// The same physical perturbation, turned: Noll 6 (ρ² cos 2φ) at c is Noll 5 (ρ² sin 2φ) at
    /// c turned by 45°, so ∂ mean MTF/∂Z5 at Z5 = c equals ∂/∂Z6 at Z6 = c where the mean is
    /// taken over azimuth, to the FFT path's error (the grids are not turned with the pupil).
    /// On the paper scene at 0.2 µm, the default band, tolerance 1e-3: within 10× of it (on the
    /// FFT path 9e-5 relative; on the overlap engine, which now takes these terms and has no
    /// grid to turn, the two agree to 10 digits).
    #[test]
    fn fft_zernike_gradient_is_the_same_for_the_lens_turned() {
        let source = scene::read(None).unwrap();
        let at = |list: &str, key: &str| {
            let set = owned(&[&format!("lens.zernike_noll_rms_um={list}"), "options.tolerance=1e-3"]);
            gradient(&source, &set, &owned(&[key])).unwrap()
        };
        let z5 = at("[0, 0, 0, 0, 0.2]", "lens.zernike_noll_rms_um[4]");
        let z6 = at("[0, 0, 0, 0, 0, 0.2]", "lens.zernike_noll_rms_um[5]");
        println!("∂M̄/∂Z5 {:.9e}, ∂M̄/∂Z6 turned {:.9e}", z5.d_mean_mtf[0], z6.d_mean_mtf[0]);
        assert!(z5.d_mean_mtf[0] < 0.0);
        assert!((z5.d_mean_mtf[0] - z6.d_mean_mtf[0]).abs() <= 1e-2 * z5.d_mean_mtf[0].abs(), "{z5:?} {z6:?}");
    }

    /// The Seidel keys' gradient on the overlap engine at the tolerance `tolerance` against
    /// central differences of evaluations converged to 1e-10, Richardson-extrapolated from the
    /// steps 2h and h (`(4 D(h) − D(2h))/3`, truncation O(h⁴); the mean MTF turns fast in coma,
    /// so a plain central difference would need a step whose rounding, 1e-10/h, is the larger
    /// error), within 10× `tolerance` of the gradient's norm: ASNR, mean MTF, SNR0 (whose
    /// derivative is 0: the Seidel terms move the OTF only) and N.
    fn check_seidel(overrides: &[&str], keys: &[&str], tolerance: f64, h: f64) -> Gradient {
        check_seidel_on(&scene::read(None).unwrap(), overrides, keys, tolerance, h)
    }

    /// [`check_seidel`] on the scene `source`.
    fn check_seidel_on(source: &Source, overrides: &[&str], keys: &[&str], tolerance: f64, h: f64) -> Gradient {
        let source = source.clone();
        let mut set = owned(overrides);
        set.push(format!("options.tolerance={tolerance:e}"));
        let g = gradient(&source, &set, &owned(keys)).unwrap();
        let base = owned(overrides);
        let norm = g.d_asnr.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(norm > 0.0, "a zero gradient: {g:?}");
        let norm_mtf = g.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
        for (i, k) in g.keys.iter().enumerate() {
            let coarse = central(&source, &base, k, g.values[i], 2.0 * h);
            let fine = central(&source, &base, k, g.values[i], h);
            let theirs: [f64; 4] = std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0);
            let error = (g.d_asnr[i] - theirs[0]).abs() / norm;
            let error_mtf = (g.d_mean_mtf[i] - theirs[1]).abs() / norm_mtf;
            println!(
                "tolerance {tolerance:e} {k}: ∂ASNR {:.9e}, differences {:.9e}, error/norm {error:.1e}; ∂M̄ {:.9e}, \
                 differences {:.9e}, error/norm {error_mtf:.1e}",
                g.d_asnr[i], theirs[0], g.d_mean_mtf[i], theirs[1]
            );
            assert!(error <= 10.0 * tolerance, "{k}: ∂ASNR {} vs {} (norm {norm})", g.d_asnr[i], theirs[0]);
            assert!(error_mtf <= 10.0 * tolerance, "{k}: ∂M̄ {} vs {} (norm {norm_mtf})", g.d_mean_mtf[i], theirs[1]);
            assert_eq!(g.d_snr0[i], 0.0);
            assert_eq!(g.d_photoelectrons[i], 0.0);
            assert!(theirs[2].abs() <= 1e-9 * g.snr0 && theirs[3].abs() <= 1e-9 * g.photoelectrons, "{theirs:?}");
        }
        g
    }

    /// The four Seidel keys on the paper's chromatic lens on axis (a 4 nm band, so that the
    /// sixteen references at 1e-10 take seconds), each term present (the Filon rule of
    /// spherical aberration), at the tolerance 1e-6: measured at most 4.2e-8 of the norm (on a
    /// 20 nm band, 2.5e-8 to 3.3e-7); off axis at most 1.4e-8.
    #[test]
    fn seidel_gradient_matches_central_differences() {
        check_seidel(
            &[
                "spectrum.range_nm=4",
                "lens.spherical_um=0.15",
                "lens.coma_um=0.3",
                "lens.astigmatism_um=0.2",
                "lens.field_curvature_um=0.1",
            ],
            &["lens.spherical_um", "lens.coma_um", "lens.astigmatism_um", "lens.field_curvature_um"],
            1e-6,
            1e-3,
        );
    }

    /// Off axis, the lateral colour's phases on each wavelength: the field along x (a pupil
    /// symmetric about x, whose mirrored azimuths are read as conjugates) and along y (each
    /// azimuth computed), without spherical aberration (the closed form of the quadratic phase
    /// for the value, the Filon rule for the derivatives), with the pixel MTF in the weights.
    #[test]
    fn seidel_gradient_off_axis_matches_central_differences() {
        for field in ["field.x_deg=2", "field.y_deg=2"] {
            check_seidel(
                &[
                    "spectrum.range_nm=4",
                    field,
                    "lens.coma_um=0.3",
                    "lens.astigmatism_um=-0.2",
                    "camera.pixel_mtf=true",
                ],
                &["lens.spherical_um", "lens.coma_um", "lens.astigmatism_um"],
                1e-6,
                1e-3,
            );
        }
    }

    /// The same pupil on the FFT path: coma `W131 ρ³ cos θ = W131 (Z8/(3√8) + Z2/3)` and
    /// astigmatism `W222 ρ² cos² θ = W222 (Z4/(4√3) + Z6/(2√6))` + piston (Noll 1976:
    /// `Z2 = 2ρ cos θ`, `Z4 = √3 (2ρ² − 1)`, `Z6 = √6 ρ² cos 2θ`, `Z8 = √8 (3ρ³ − 2ρ) cos θ`), so
    /// the overlap engine's `∂M̄/∂W131` is the FFT path's `∂M̄/∂c8/(3√8) + ∂M̄/∂c2/3` on the
    /// chromatic lens carrying those Zernike terms instead, and `∂M̄/∂W222` its
    /// `∂M̄/∂c4/(4√3) + ∂M̄/∂c6/(2√6)`: within 10× the FFT path's tolerance 1e-3 of the
    /// norm, as its values. The Zernike lens is held on the FFT path by `options.pupil_samples =
    /// 256` (otherwise the overlap engine takes Zernike terms too).
    #[test]
    fn seidel_gradient_matches_the_fft_path_on_the_same_pupil() {
        let source = scene::read(None).unwrap();
        let (coma, astigmatism) = (0.3, 0.2);
        let overlap = gradient(
            &source,
            &owned(&[
                "spectrum.range_nm=4",
                &format!("lens.coma_um={coma}"),
                &format!("lens.astigmatism_um={astigmatism}"),
            ]),
            &owned(&["lens.coma_um", "lens.astigmatism_um"]),
        )
        .unwrap();
        let (s3, s6, s8) = (3.0_f64.sqrt(), 6.0_f64.sqrt(), 8.0_f64.sqrt());
        let zernike = format!(
            "lens.zernike_noll_rms_um=[0, {}, 0, {}, 0, {}, 0, {}]",
            coma / 3.0,
            astigmatism / (4.0 * s3),
            astigmatism / (2.0 * s6),
            coma / (3.0 * s8)
        );
        let fft = gradient(
            &source,
            &owned(&["spectrum.range_nm=4", &zernike, "options.tolerance=1e-3", "options.pupil_samples=256"]),
            &owned(&[
                "lens.zernike_noll_rms_um[1]",
                "lens.zernike_noll_rms_um[3]",
                "lens.zernike_noll_rms_um[5]",
                "lens.zernike_noll_rms_um[7]",
            ]),
        )
        .unwrap();
        let d = &fft.d_mean_mtf;
        let theirs = [d[3] / (3.0 * s8) + d[0] / 3.0, d[1] / (4.0 * s3) + d[2] / (2.0 * s6)];
        let norm = overlap.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
        println!(
            "mean MTF {:.7} (overlap) vs {:.7} (FFT); ∂M̄/∂W131 {:.7e} vs {:.7e}, ∂M̄/∂W222 {:.7e} vs {:.7e}",
            overlap.mean_mtf, fft.mean_mtf, overlap.d_mean_mtf[0], theirs[0], overlap.d_mean_mtf[1], theirs[1]
        );
        assert!((overlap.mean_mtf - fft.mean_mtf).abs() <= 1e-2 * overlap.mean_mtf);
        for (mine, theirs) in overlap.d_mean_mtf.iter().zip(theirs) {
            assert!((mine - theirs).abs() <= 1e-2 * norm, "{mine} vs {theirs} (norm {norm})");
        }
    }

    /// Zernike terms of the paper's chromatic lens on the overlap engine (docs/physics.md,
    /// "Zernike terms on the overlap engine"): forward mode with `∂W/∂c_j = 10⁻⁶ Z_j`, against
    /// central differences of evaluations converged to 1e-10 ([`check_seidel`]'s reference and
    /// bounds), at the tolerance 1e-6: Z5, Z7 and Z8 on axis; Z11 + Z5 with Z6 beside them off
    /// axis along y (lateral colour, the lens's own coma and astigmatism, every azimuth
    /// computed, Z5 and Z7 odd in y), with the Seidel keys asked in the same pass.
    #[test]
    fn zernike_overlap_gradient_matches_central_differences() {
        let on_axis = check_seidel(
            &["spectrum.range_nm=4", "lens.zernike_noll_rms_um=[0, 0, 0, 0, 0.05, 0, 0.04, -0.03]"],
            &["lens.zernike_noll_rms_um[4]", "lens.zernike_noll_rms_um[6]", "lens.zernike_noll_rms_um[7]"],
            1e-6,
            1e-3,
        );
        assert!(on_axis.d_mean_mtf.iter().all(|d| *d != 0.0), "{on_axis:?}");
        check_seidel(
            &[
                "spectrum.range_nm=4",
                "field.y_deg=2",
                "lens.coma_um=0.1",
                "lens.zernike_noll_rms_um=[0, 0, 0, 0, 0.05, 0.03, 0, 0, 0, 0, 0.02]",
            ],
            &[
                "lens.zernike_noll_rms_um[4]",
                "lens.zernike_noll_rms_um[5]",
                "lens.zernike_noll_rms_um[10]",
                "lens.coma_um",
            ],
            1e-6,
            1e-3,
        );
    }

    /// The Seidel keys at zero on the paper's lens (docs/physics.md, "Gradients: Seidel terms at
    /// zero"): the value on its closed form, spherical aberration's and field curvature's lanes
    /// on the overlap engine with the terms at zero, astigmatism half field curvature's, coma 0;
    /// against central differences of evaluations converged to 1e-10 ([`check_seidel`]: at ±h
    /// the scene is on the overlap engine) within 10× the tolerance 1e-6 of the norm, on a 10 nm
    /// band (quick) and on the paper's 50 nm with the pixel MTF, step 1 nm (Richardson from 2
    /// and 1 nm: the mean MTF is even in none of these terms, the chromatic defocus breaking the
    /// symmetry, and turns on the scale of a tenth of a µm).
    #[test]
    fn seidel_gradient_at_zero_matches_central_differences() {
        let keys = ["lens.spherical_um", "lens.astigmatism_um", "lens.field_curvature_um"];
        let narrow = check_seidel(&["spectrum.range_nm=10"], &keys, 1e-6, 1e-3);
        // W222 x² = W222 ρ²/2 + W222 ρ² cos 2φ/2: half field curvature's exactly
        assert_eq!(narrow.d_mean_mtf[1], 0.5 * narrow.d_mean_mtf[2]);
        assert!(narrow.d_mean_mtf.iter().all(|d| *d != 0.0), "{narrow:?}");
        check_seidel(&["camera.pixel_mtf=true"], &keys, 1e-6, 1e-3);
        // coma at zero: 0 by symmetry, asked beside the others
        let paper = scene::read(None).unwrap();
        let g = gradient(&paper, &owned(&["spectrum.range_nm=10"]), &owned(&["lens.coma_um", "lens.spherical_um"]))
            .unwrap();
        assert_eq!(g.d_mean_mtf[0], 0.0);
        assert!(g.d_mean_mtf[1] != 0.0);
    }

    /// The Seidel keys at zero under a line (docs/physics.md, "Gradients: Seidel terms at
    /// zero"): the line's value on the exact 1-D engine, the lanes of spherical aberration and
    /// field curvature on the overlap engine at the line's one wavelength, astigmatism half field
    /// curvature's. At ±h the line's value is on the FFT path (about 3e-5 off), so the reference
    /// written here is the line's narrow-band limit: a Gaussian band of 1e-3 nm at the same
    /// centre, whose mean MTF is the line's to 3e-10 (the error falls as the range², the scene's
    /// own note) and which is on the overlap engine at ±h, Richardson-extrapolated central
    /// differences of evaluations converged to 1e-10 (steps 2e-3 and 1e-3 µm), within 10× the tolerance 1e-6 of the norm. At 810 nm (a tenth of a wave of defocus
    /// per nm at 800 nm: 1 wave here), where the derivatives are not zero.
    #[test]
    fn seidel_gradient_at_zero_under_a_line_matches_a_narrow_band() {
        let source = scene::read(None).unwrap();
        let line = owned(&["spectrum.shape=line", "spectrum.center_nm=810", "spectrum.range_nm=1"]);
        let band = owned(&["spectrum.shape=gaussian", "spectrum.center_nm=810", "spectrum.range_nm=1e-3"]);
        let keys = ["lens.spherical_um", "lens.field_curvature_um", "lens.astigmatism_um"];
        let tolerance = 1e-6;
        let mut set = line.clone();
        set.push(format!("options.tolerance={tolerance:e}"));
        let g = gradient(&source, &set, &owned(&keys)).unwrap();
        // W222 x² = W222 ρ²/2 + W222 ρ² cos 2φ/2: half field curvature's exactly
        assert_eq!(g.d_mean_mtf[2], 0.5 * g.d_mean_mtf[1]);
        let norm = g.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(norm > 0.1, "{g:?}");
        let h = 1e-3;
        for (i, k) in keys.iter().enumerate().take(2) {
            let coarse = central(&source, &band, k, 0.0, 2.0 * h);
            let fine = central(&source, &band, k, 0.0, h);
            let theirs = (4.0 * fine[1] - coarse[1]) / 3.0;
            let error = (g.d_mean_mtf[i] - theirs).abs() / norm;
            println!(
                "{k}: ∂M̄ {:.9e}, the narrow band's differences {theirs:.9e}, error/norm {error:.1e}",
                g.d_mean_mtf[i]
            );
            assert!(error <= 10.0 * tolerance, "{k}: ∂M̄ {} vs {theirs} (norm {norm})", g.d_mean_mtf[i]);
            // the Seidel terms move the OTF only: ∂ASNR = SNR0 ∂M̄ (form = "mean")
            assert_eq!(g.d_snr0[i], 0.0);
            assert_eq!(g.d_photoelectrons[i], 0.0);
            assert!((g.d_asnr[i] - g.snr0 * g.d_mean_mtf[i]).abs() <= 1e-12 * g.d_asnr[i].abs(), "{g:?}");
        }
    }

    /// The Seidel keys off axis with every term zero (docs/physics.md, "Gradients: Seidel terms
    /// at zero"): the value the mean over azimuth on the exact 1-D engine, the lanes on the
    /// overlap engine with the terms at zero (its mean over azimuth, the same quantity), against
    /// central differences of evaluations converged to 1e-10 ([`check_seidel`]: at ±h the scene is
    /// on the overlap engine) within 10× the tolerance 1e-6 of the norm: a field point off both
    /// axes (each azimuth computed), a 4 nm band, coma not zero there (the lateral colour breaks
    /// the symmetry that makes it 0 on axis).
    #[test]
    fn seidel_gradient_off_axis_at_zero_matches_central_differences() {
        let keys = ["lens.spherical_um", "lens.coma_um", "lens.astigmatism_um", "lens.field_curvature_um"];
        let g = check_seidel(&["spectrum.range_nm=4", "field.x_deg=2", "field.y_deg=1"], &keys, 1e-6, 1e-3);
        assert!(g.d_mean_mtf[1] != 0.0, "{g:?}");
    }

    /// `lens.f_number` and `lens.focal_length_mm` of the chromatic lens with Seidel terms on
    /// axis (the overlap engine; docs/physics.md, "Gradients: the F-number and the focal length
    /// with Seidel terms": s = νλF# by parts over every azimuth, the defocus lane W020 ρ² on the
    /// overlap quadrature's nodes, N ∝ 1/F#²) against Richardson-extrapolated central
    /// differences of evaluations converged to 1e-10 ([`check_aperture_extrapolated`]) within
    /// 10× the tolerance 1e-6 of the norm: coma 0.3 µm, spherical aberration 0.2 µm (with the
    /// pixel MTF: its term of the integration by parts), on a 10 nm band; and off axis (docs/physics.md,
    /// "Gradients: the F-number and the focal length off axis": the lateral colour ∝ f0, not
    /// F#, its image shifts' lane beside the defocus lane on the same nodes) with coma at
    /// (5°, 3°), and with spherical aberration, astigmatism and the pixel MTF at 5°.
    #[test]
    fn f_number_and_focal_length_with_seidel_terms_match_central_differences() {
        let paper = scene::read(None).unwrap();
        let keys = owned(&["lens.f_number", "lens.focal_length_mm"]);
        for more in [
            &["lens.coma_um=0.3"][..],
            &["lens.spherical_um=0.2", "camera.pixel_mtf=true"],
            &["lens.coma_um=0.3", "field.x_deg=5", "field.y_deg=3"],
            &["lens.spherical_um=0.2", "lens.astigmatism_um=0.1", "field.x_deg=5", "camera.pixel_mtf=true"],
        ] {
            let base = joined(&["spectrum.range_nm=10"], more);
            // the overlap engine at the tolerance 1e-6 (not options.fft_tolerance's 1e-4)
            let mut set = base.clone();
            set.push("options.tolerance=1e-6".to_owned());
            let g = gradient(&paper, &set, &keys).unwrap();
            let relative = |d: &[f64]| -> Vec<f64> { d.iter().zip(&g.values).map(|(d, v)| d * v).collect() };
            let (asnr, mtf) = (relative(&g.d_asnr), relative(&g.d_mean_mtf));
            let norm = |d: &[f64]| d.iter().map(|x| x * x).sum::<f64>().sqrt();
            for (i, k) in g.keys.iter().enumerate() {
                let h = NARROW_APERTURE_STEP * g.values[i];
                let (coarse, fine) =
                    (central(&paper, &base, k, g.values[i], 2.0 * h), central(&paper, &base, k, g.values[i], h));
                let theirs: [f64; 4] = std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0 * g.values[i]);
                let (error, error_mtf) =
                    ((asnr[i] - theirs[0]).abs() / norm(&asnr), (mtf[i] - theirs[1]).abs() / norm(&mtf));
                println!(
                    "{more:?} {k}: ∂ASNR/∂ln {:.9e}, differences {:.9e}, error/norm {error:.1e}; ∂M̄/∂ln {:.9e}, \
                     differences {:.9e}, error/norm {error_mtf:.1e}",
                    asnr[i], theirs[0], mtf[i], theirs[1]
                );
                assert!(
                    error <= 1e-5 && error_mtf <= 1e-5,
                    "{k}: {} vs {}, {} vs {}",
                    asnr[i],
                    theirs[0],
                    mtf[i],
                    theirs[1]
                );
            }
            // N ∝ 1/F#² (SI eq. S7): −2N per ln F# (to the rounding of ∂N/∂F# times F#), and
            // nothing from f0
            let per_ln = g.d_photoelectrons[0] * g.values[0];
            assert!((per_ln + 2.0 * g.photoelectrons).abs() <= 4.0 * f64::EPSILON * g.photoelectrons, "{per_ln}");
            assert_eq!(g.d_photoelectrons[1], 0.0);
        }
    }

    /// Zernike terms with `m ≠ 0` on the paper's chromatic lens (Z4 0.02 µm, Z8 0.01 µm: the
    /// overlap engine) at a 10 nm band.
    const ZERNIKE_ON_OVERLAP: [&str; 2] =
        ["spectrum.range_nm=10", "lens.zernike_noll_rms_um=[0, 0, 0, 0.02, 0, 0, 0, 0.01]"];

    /// `keys` of `source` with `more` at the tolerance 1e-6 (the overlap engine's, not
    /// options.fft_tolerance's 1e-4) against central differences of evaluations converged at
    /// 1e-10 (without the gradient's tolerance), Richardson-extrapolated from the steps 2h and h:
    /// h = [`NARROW_APERTURE_STEP`] of the value for the F-number and the focal length,
    /// [`LINE_STEP_NM`] for the design wavelength; within 10× the tolerance of the gradient's norm.
    fn check_on_overlap(source: &Source, more: &[String], keys: &[&str]) {
        let mut set = more.to_vec();
        set.push("options.tolerance=1e-6".to_owned());
        let step =
            |k: &str, v: f64| if k == "lens.design_wavelength_nm" { LINE_STEP_NM } else { NARROW_APERTURE_STEP * v };
        check_with_references(source, &set, keys, &|k, v| richardson(source, more, k, v, step(k, v)));
    }

    /// The F-number and the focal length with Zernike terms on the overlap engine (docs/physics.md,
    /// "Gradients: the F-number and the focal length with Seidel terms": the same lanes with a
    /// Zernike pupil), on axis with the pixel MTF (its term of the parts), and at 3° along x (the
    /// mean over azimuth with the image shifts' lane) under a noise spectrum (each weight divided
    /// by n(ν)), against [`check_on_overlap`]'s references.
    #[test]
    fn f_number_and_focal_length_with_zernike_terms_match_central_differences() {
        let keys = ["lens.f_number", "lens.focal_length_mm"];
        let paper = scene::read(None).unwrap();
        check_on_overlap(&paper, &joined(&ZERNIKE_ON_OVERLAP, &["camera.pixel_mtf=true"]), &keys);
        let shaped = with_noise_spectrum(&paper, "zernike-aperture");
        check_on_overlap(&shaped, &joined(&ZERNIKE_ON_OVERLAP, &["field.x_deg=3"]), &keys);
    }

    /// The design wavelength with Zernike and Seidel terms on the overlap engine (docs/physics.md,
    /// "Gradients: the design wavelength with Seidel and Zernike terms": the lane of each node's
    /// `∂W020/∂ln λ0` and efficiency's rate on the quadrature's nodes), on axis with Zernike terms
    /// and the pixel MTF, at 3° along x under a noise spectrum, and with coma 0.3 µm, against
    /// [`check_on_overlap`]'s references.
    #[test]
    fn design_wavelength_with_zernike_and_seidel_terms_matches_central_differences() {
        let keys = ["lens.design_wavelength_nm"];
        let paper = scene::read(None).unwrap();
        check_on_overlap(&paper, &joined(&ZERNIKE_ON_OVERLAP, &["camera.pixel_mtf=true"]), &keys);
        let shaped = with_noise_spectrum(&paper, "zernike-design");
        check_on_overlap(&shaped, &joined(&ZERNIKE_ON_OVERLAP, &["field.x_deg=3"]), &keys);
        check_on_overlap(&paper, &owned(&["spectrum.range_nm=10", "lens.coma_um=0.3"]), &keys);
    }

    /// Refusals name the key and the reason: a Seidel key of another family; every Seidel term
    /// zero where the overlap engine does not take the scene (an iris). Under a line the keys
    /// at zero are computed (`seidel_gradient_at_zero_under_a_line_matches_a_narrow_band`),
    /// coma 0 by symmetry.
    #[test]
    fn seidel_gradient_refusals_name_the_key() {
        let paper = scene::read(None).unwrap();
        let e = gradient(&example("phase-binary2.toml"), &owned(&["lens.coma_um=0.1"]), &owned(&["lens.coma_um"]));
        let e = e.unwrap_err().to_string();
        assert!(e.contains("lens.coma_um"), "{e}");
        let line = owned(&LINE_803);
        let g = gradient(&paper, &line, &owned(&["lens.astigmatism_um", "lens.coma_um"])).unwrap();
        assert!(g.d_mean_mtf[0] != 0.0, "{g:?}");
        assert_eq!(g.d_mean_mtf[1], 0.0);
        let e = gradient(&example("decentred-iris.toml"), &[], &owned(&["lens.spherical_um"])).unwrap_err().to_string();
        assert!(e.contains("lens.spherical_um"), "{e}");
    }

    /// What the FFT path's gradient does not do stays refused by name, with the reason; and a
    /// term with m ≠ 0 at zero on a radially symmetric pupil has derivative 0 by symmetry.
    #[test]
    fn fft_gradient_refusals_name_the_key() {
        let paper = scene::read(None).unwrap();
        // m = 0 on a family other than the phase lens, where the OTF stays rotationally
        // symmetric (the radial engine, whose lanes are the phase lens's)
        let e = gradient(
            &paper,
            &owned(&["lens.zernike_noll_rms_um=[0, 0, 0, 0.05]"]),
            &owned(&["lens.zernike_noll_rms_um[3]"]),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("Zernike coefficient") && e.contains("Noll 4") && e.contains("radial engine"), "{e}");
        // Noll 5 at zero on the symmetric pupil: 0, as Noll 5 at ±c are one pupil turned by 90°
        let g = gradient(
            &paper,
            &owned(&["lens.zernike_noll_rms_um=[0, 0, 0, 0, 0]"]),
            &owned(&["lens.zernike_noll_rms_um[4]"]),
        )
        .unwrap();
        assert_eq!(g.d_mean_mtf[0], 0.0);
    }

    /// The field keys' gradient against central differences of evaluations converged to 1e-10,
    /// Richardson-extrapolated from the steps 2h and h (`(4 D(h) − D(2h))/3`), within 10× the
    /// scene's tolerance 1e-6 of the gradient's norm for each of ASNR, mean MTF, SNR0 and N.
    fn check_field(overrides: &[&str], keys: &[&str], h: f64) -> Gradient {
        check_field_at(overrides, keys, h, 1e-6)
    }

    /// [`check_field`] with the gradient at the tolerance `tolerance`.
    fn check_field_at(overrides: &[&str], keys: &[&str], h: f64, tolerance: f64) -> Gradient {
        check_field_of(&scene::read(None).unwrap(), overrides, keys, h, tolerance)
    }

    /// [`check_field_at`] on the scene `source`.
    fn check_field_of(source: &Source, overrides: &[&str], keys: &[&str], h: f64, tolerance: f64) -> Gradient {
        check_field_against(source, overrides, keys, h, tolerance, REFERENCE_TOLERANCE)
    }

    /// [`check_field_of`] with the references' evaluations at the tolerance `reference` (the
    /// FFT path, which reaches about 1e-5 here, not 1e-10).
    fn check_field_against(
        source: &Source,
        overrides: &[&str],
        keys: &[&str],
        h: f64,
        tolerance: f64,
        reference: f64,
    ) -> Gradient {
        let source = source.clone();
        let mut set = owned(overrides);
        set.push(format!("options.tolerance={tolerance:e}"));
        let g = gradient(&source, &set, &owned(keys)).unwrap();
        let ours = [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons];
        let references: Vec<[f64; 4]> = g
            .keys
            .iter()
            .zip(&g.values)
            .map(|(k, v)| {
                let coarse = central_at(&source, &owned(overrides), k, *v, 2.0 * h, reference);
                let fine = central_at(&source, &owned(overrides), k, *v, h, reference);
                std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0)
            })
            .collect();
        let mut failures = Vec::new();
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            let norm = ours[q].iter().map(|x| x * x).sum::<f64>().sqrt();
            // a gradient that is zero against the quantity's own size (per degree)
            let norm = if norm == 0.0 { [g.asnr, g.mean_mtf, g.snr0, g.photoelectrons][q] } else { norm };
            for (i, k) in g.keys.iter().enumerate() {
                let error = (ours[q][i] - references[i][q]).abs() / norm;
                println!(
                    "{name} {k}: gradient {:.9e}, differences {:.9e}, error/norm {error:.1e}",
                    ours[q][i], references[i][q]
                );
                if error > 10.0 * tolerance {
                    failures.push(format!("{name} {k}: {} vs {} (norm {norm})", ours[q][i], references[i][q]));
                }
            }
        }
        assert!(failures.is_empty(), "{failures:#?}");
        g
    }

    /// The paper's lens on a 4 nm band at (5°, 3°) with spherical aberration, coma and
    /// astigmatism (the overlap engine), the cos⁴ relative illumination, read noise and the pixel
    /// MTF: the scene of the field gradient's checks off axis with Seidel terms.
    const OFF_AXIS_WITH_SEIDEL_TERMS: [&str; 9] = [
        "spectrum.range_nm=4",
        "field.x_deg=5",
        "field.y_deg=3",
        "lens.spherical_um=0.15",
        "lens.coma_um=0.3",
        "lens.astigmatism_um=-0.2",
        "lens.relative_illumination=\"cos4\"",
        "camera.read_noise_e=2",
        "camera.pixel_mtf=true",
    ];

    /// Off axis at (5°, 3°) with Seidel terms (the overlap engine; the images shifted along the
    /// field direction, so every azimuth computed), the cos⁴ relative illumination, read noise
    /// and the pixel MTF: the shift lane (the lateral colour `f0 tan θ (λ0/λ − 1)`) and the
    /// radiometric factor together. A 4 nm band keeps the references at 1e-10 to seconds; the
    /// step 0.02° (the mean MTF turns on a scale of degrees).
    #[test]
    fn field_gradient_matches_central_differences() {
        let g = check_field_at(&OFF_AXIS_WITH_SEIDEL_TERMS, &["field.x_deg", "field.y_deg"], 0.02, 1e-8);
        // both the shift lane and the illumination move the value
        assert!(g.d_mean_mtf.iter().all(|d| *d != 0.0) && g.d_photoelectrons.iter().all(|d| *d < 0.0), "{g:?}");
    }

    /// The two cases the value's rules alone missed at the scene's tolerance 1e-6 (3.1e-5 of
    /// the norm at (5°, 3°), 1.3e-3 on axis with coma, whose gradient is small: docs/physics.md,
    /// "Gradients: the field point"), now with the lanes in the rules' acceptance: (5°, 3°) with
    /// three Seidel terms, cos⁴θ, read noise and the pixel MTF, and on axis with coma and
    /// astigmatism, each at 1e-6 against the Richardson central differences at 1e-10.
    #[test]
    fn field_gradient_at_the_scene_tolerance() {
        check_field_at(&OFF_AXIS_WITH_SEIDEL_TERMS, &["field.x_deg", "field.y_deg"], 0.02, 1e-6);
        let g = check_field_at(
            &["spectrum.range_nm=4", "lens.coma_um=0.3", "lens.astigmatism_um=0.2"],
            &["field.x_deg", "field.y_deg"],
            0.02,
            1e-6,
        );
        assert!(g.d_mean_mtf[0] != 0.0, "{g:?}");
    }

    /// The field along x (the images shifted along x: the mirrored azimuths read as conjugates,
    /// the y angle's lane as the conjugates' negatives) with a wider band (20 nm: larger
    /// shifts), and the y angle at 0 there: the pupil with coma along x is symmetric about x,
    /// so M̄ is even in θy and its derivative is 0, which the lane must give from the mirrored
    /// reading.
    #[test]
    fn field_gradient_along_x_matches_central_differences() {
        let g = check_field(
            &["spectrum.range_nm=20", "field.x_deg=5", "lens.coma_um=0.3", "lens.astigmatism_um=0.2"],
            &["field.x_deg", "field.y_deg"],
            0.02,
        );
        assert!(g.d_mean_mtf[0] < 0.0, "{g:?}");
        assert!(g.d_mean_mtf[1].abs() <= 1e-9 * g.d_mean_mtf[0].abs(), "{g:?}");
    }

    /// On axis the lateral colour vanishes: with coma (the overlap engine, not symmetric in θx)
    /// the lane gives a non-zero derivative, checked against the differences; without Seidel
    /// terms the pupil is rotationally symmetric, M̄ and cos⁴θ are even in each angle, and the
    /// derivative is 0 (the differences' within 10× the tolerance of the values).
    #[test]
    fn field_gradient_on_axis() {
        let g = check_field_at(
            &["spectrum.range_nm=4", "lens.coma_um=0.3", "lens.astigmatism_um=0.2"],
            &["field.x_deg", "field.y_deg"],
            0.02,
            1e-9,
        );
        assert!(g.d_mean_mtf[0] != 0.0, "{g:?}");
        let g = check_field(
            &["lens.relative_illumination=\"cos4\"", "camera.read_noise_e=2"],
            &["field.x_deg", "field.y_deg"],
            0.02,
        );
        assert!(g.d_asnr.iter().chain(&g.d_photoelectrons).all(|d| *d == 0.0), "{g:?}");
    }

    /// Off axis without Seidel terms: the exact 1-D engine's tangential and sagittal means, the
    /// shift lane on its spectral nodes, and the azimuth lane for the tangential and sagittal
    /// azimuths turning with atan2(θy, θx) (off the axes not exactly the images' direction). The
    /// paper's lens at its 50 nm band at (5°, 3°) with cos⁴θ, read noise and the pixel MTF
    /// (measured 4.1e-7 of the norm; without the azimuth lane 5e-6 at any tolerance), and at 8°
    /// along x, where ∂/∂θy is 0 (the pupil is rotationally symmetric: M̄ is even in θy), both
    /// at the scene's 1e-6.
    #[test]
    fn field_gradient_without_seidel_terms_matches_central_differences() {
        let g = check_field(&["field.x_deg=8"], &["field.x_deg", "field.y_deg"], 0.02);
        assert!(g.d_mean_mtf[0] < 0.0 && g.d_mean_mtf[1].abs() <= 1e-9 * g.d_mean_mtf[0].abs(), "{g:?}");
        let g = check_field_at(
            &[
                "field.x_deg=5",
                "field.y_deg=3",
                "lens.relative_illumination=\"cos4\"",
                "camera.read_noise_e=2",
                "camera.pixel_mtf=true",
            ],
            &["field.x_deg", "field.y_deg"],
            0.02,
            1e-6,
        );
        assert!(g.d_mean_mtf.iter().all(|d| *d < 0.0), "{g:?}");
    }

    /// The harmonic lens of `examples/harmonic.toml` (design order 5: each wavelength's orders
    /// m with their own lateral colour f0 tan θ (pλ0/(mλ) − 1), rate f0 sec²θ (pλ0/(mλ) − 1))
    /// off axis at (1°, 0.6°) with cos⁴θ and read noise on the exact 1-D engine, and along x at
    /// 1° (∂/∂θy = 0 there: the images along x, the pupils rotationally symmetric), against
    /// Richardson-extrapolated differences at 1e-10, within 10× the scene's 1e-6 of the norm.
    /// Small angles keep the references cheap (at 5° each 1e-10 evaluation takes 256 azimuths
    /// and ten times as long); the orders' images are apart there already, the code path the same.
    /// At (1°, 0.6°) a 10 nm band (3 spectral panels where the set of orders changes, against 8
    /// over the example's 50 nm) makes each 1e-10 evaluation eight times cheaper on the same
    /// lane: ∂M̄/∂θx is −2.10e-3 per degree there against −2.21e-3 over 50 nm, the other orders'
    /// images (m ≠ p, lateral colour f0 tan θ (p/m − 1) at λ0) as far apart (measured 1.7e-8 of
    /// the norm, 6.5e-6 on the value's rules alone). Along x on the
    /// same band (∂M̄/∂θx −2.106e-3 per degree): the value's rules alone left it 1.6e-5 of the
    /// norm off, the field lanes' second pass (spectral and frequency rules at q ε) 2.9e-7
    /// (docs/physics.md, "Gradients: the field point").
    #[test]
    fn harmonic_field_gradient_matches_central_differences() {
        let harmonic = example("harmonic.toml");
        let g = check_field_of(
            &harmonic,
            &[
                "spectrum.range_nm=10",
                "field.x_deg=1",
                "field.y_deg=0.6",
                "lens.relative_illumination=\"cos4\"",
                "camera.read_noise_e=2",
            ],
            &["field.x_deg", "field.y_deg"],
            0.02,
            1e-6,
        );
        assert!(g.d_mean_mtf.iter().all(|d| *d != 0.0) && g.d_photoelectrons.iter().all(|d| *d < 0.0), "{g:?}");
        let along_x = ["spectrum.range_nm=10", "field.x_deg=1"];
        let g = check_field_of(&harmonic, &along_x, &["field.x_deg", "field.y_deg"], 0.02, 1e-6);
        assert!(g.d_mean_mtf[0] != 0.0 && g.d_mean_mtf[1].abs() <= 1e-9 * g.d_mean_mtf[0].abs(), "{g:?}");
    }

    /// The refractive lens (the N-BK7 singlet at a 100 nm band, and a glass without dispersion
    /// on the closed form): its stop is at the lens, so no image moves with the field and the
    /// mean MTF's derivative is exactly 0 (the differences' too: the value does not read the
    /// angle), while cos⁴θ moves N, SNR0 and the ASNR; against the differences as above.
    #[test]
    fn refractive_field_gradient_is_the_illumination_alone() {
        let singlet = refractive_singlet();
        let overrides = [
            "spectrum.range_nm=100",
            "field.x_deg=5",
            "field.y_deg=3",
            "lens.relative_illumination=\"cos4\"",
            "camera.read_noise_e=2",
        ];
        let g = check_field_of(&singlet, &overrides, &["field.x_deg", "field.y_deg"], 0.02, 1e-6);
        assert!(g.d_mean_mtf.iter().all(|d| *d == 0.0) && g.d_asnr.iter().all(|d| *d < 0.0), "{g:?}");
        let plain = Source::from_text(
            singlet.text().replace("glass = \"N-BK7\"", "refractive_index = 1.5"),
            "refractive lens without dispersion written in the test",
            ".",
        );
        let g = check_field_of(&plain, &overrides, &["field.x_deg", "field.y_deg"], 0.02, 1e-6);
        assert!(g.d_mean_mtf.iter().all(|d| *d == 0.0) && g.d_asnr.iter().all(|d| *d < 0.0), "{g:?}");
    }

    /// The Binary 2 lens of `examples/phase-binary2.toml` off axis (the FFT path: the oblique
    /// wave's lane and the azimuths' turn, docs/physics.md "Gradients: the field point") with
    /// cos⁴θ and read noise, at the tolerance 1e-4, against Richardson central differences
    /// (steps 0.5° and 0.25°: the oblique aberrations turn on a scale of degrees) of
    /// evaluations at 1e-5, the FFT path's tightest practical tolerance here (it reaches about
    /// 1e-5 at its 1354 samples), within 10× the gradient's 1e-4 of the norm for ASNR, mean MTF,
    /// SNR0 and N. A 1 nm band keeps the references to seconds each; at 5° along x (∂/∂θy = 0
    /// there: the pupil is symmetric about x) and at (5°, 3°). The band's spectral rule is the
    /// same there as at 4 nm (one interpolated panel, 6 nodes against 10, the pupil's 1604
    /// samples against 1600 at the references' 1e-5: `asnr evaluate --json`'s `spectral_nodes`
    /// and `engine`), so each node's oblique wave and lateral colour still ride the lanes, at
    /// some 40 % less time per reference evaluation.
    #[test]
    fn phase_lens_field_gradient_matches_converged_differences() {
        let binary2 = example("phase-binary2.toml");
        for at in [["field.x_deg=5", "field.y_deg=0"], ["field.x_deg=5", "field.y_deg=3"]] {
            let mut overrides =
                vec!["spectrum.range_nm=1", "lens.relative_illumination=\"cos4\"", "camera.read_noise_e=2"];
            overrides.extend(at);
            let g = check_field_against(&binary2, &overrides, &["field.x_deg", "field.y_deg"], 0.25, 1e-4, 1e-5);
            assert!(g.d_mean_mtf[0] < 0.0 && g.d_photoelectrons.iter().all(|d| *d <= 0.0), "{g:?}");
        }
    }

    /// The library lens of `examples/library.toml` at (5°, 3°) on a 1 nm band with cos⁴θ, as
    /// [`phase_lens_field_gradient_matches_converged_differences`] (its spectral rule at 1 nm:
    /// two interpolated panels, 12 nodes, 1604 pupil samples at the references' 1e-5; the test
    /// takes about a quarter less time than at 4 nm).
    #[test]
    fn library_lens_field_gradient_matches_converged_differences() {
        let library = example("library.toml");
        let overrides = [
            "spectrum.range_nm=1",
            "field.x_deg=5",
            "field.y_deg=3",
            "lens.relative_illumination=\"cos4\"",
            "camera.read_noise_e=2",
        ];
        let g = check_field_against(&library, &overrides, &["field.x_deg", "field.y_deg"], 0.25, 1e-4, 1e-5);
        assert!(g.d_mean_mtf.iter().all(|d| *d < 0.0), "{g:?}");
    }

    /// The Binary 2 lens of `examples/phase-binary2.toml` on its own 50 nm band at 5°, the
    /// gradient at 1e-5 (the tightest tolerance the FFT path reaches there) against Richardson
    /// central differences of evaluations at the same 1e-5, within 10× of it; ignored by
    /// default (eight reference evaluations of about 20 s each in a release build):
    /// `cargo test -p asnr-report --lib phase_lens_field_gradient_on_its_band -- --ignored`.
    #[test]
    #[ignore = "slow: reference evaluations at 1e-5 on the FFT path over a 50 nm band"]
    fn phase_lens_field_gradient_on_its_band() {
        let binary2 = example("phase-binary2.toml");
        let overrides = ["field.x_deg=5", "lens.relative_illumination=\"cos4\""];
        check_field_against(&binary2, &overrides, &["field.x_deg"], 0.25, 1e-5, 1e-5);
    }

    /// Refused, naming the key and why: another family (off axis with Zernike terms held on the
    /// FFT path is computed: `aperture_design_wavelength_and_field_off_axis_on_the_fft_grids_…`).
    #[test]
    fn field_gradient_refusals_name_the_key() {
        // another family (a tabulated MTF: its tables are not followed through the field)
        let e = field_parameter("field.y_deg", "tabulated").unwrap().unwrap_err().to_string();
        assert!(e.contains("--wrt field.y_deg") && e.contains("supported for lens.model"), "{e}");
        // a point of a field-of-view list: past its end, its weight, a key it does not have,
        // and a single point's keys there
        let fov = field_of_view();
        for (key, says) in [
            ("fields[2].x_deg", "has 2 points"),
            ("fields[1].weight", "not differentiated"),
            ("fields[0].z_deg", "has the keys x_deg, y_deg and weight"),
            ("field.x_deg", "has no such key"),
        ] {
            let e = gradient(&fov, &[], &owned(&[key])).unwrap_err().to_string();
            assert!(e.contains(&format!("--wrt {key}")) && e.contains(says), "{key}: {e}");
        }
        let e = gradient(&fov, &[], &owned(&["fields[1].x_deg", "fields[01].x_deg"])).unwrap_err().to_string();
        assert!(e.contains("given twice"), "{e}");
    }

    /// The paper's scene over a field-of-view list written here: on axis (weight 1) and at
    /// 5° along x (weight 2).
    fn field_of_view() -> Source {
        let paper = scene::read(None).unwrap();
        let text = format!("{}\n[[fields]]\nx_deg = 0\n[[fields]]\nx_deg = 5\nweight = 2\n", paper.text());
        Source::from_text(text, "field-of-view scene written in the test", ".")
    }

    /// The points of a `[[fields]]` list (the field-of-view mean, a weighted mean of the points'
    /// evaluations with fixed weights): `fields[i].x_deg` against Richardson central differences
    /// of the list's evaluations converged to 1e-10 (steps 0.04° and 0.02°, `--set
    /// fields[1].x_deg=…`), within 10× the scene's 1e-6 of the norm; and each point's share
    /// against the single point's gradient (`[field]` at that point) times its weight over the
    /// weights' sum, 2/3 here, to rounding. The point on axis has derivative 0 (the pupil is
    /// rotationally symmetric there).
    #[test]
    fn field_of_view_points_match_central_differences() {
        let fov = field_of_view();
        let keys = ["fields[1].x_deg", "fields[0].x_deg"];
        let g =
            check_field_of(&fov, &["camera.read_noise_e=2", "lens.relative_illumination=\"cos4\""], &keys, 0.02, 1e-6);
        assert_eq!(g.keys, owned(&keys));
        assert!(g.d_asnr[0] < 0.0 && g.d_asnr[1] == 0.0, "{g:?}");
        let paper = scene::read(None).unwrap();
        let single = gradient(
            &paper,
            &owned(&["camera.read_noise_e=2", "lens.relative_illumination=\"cos4\"", "field.x_deg=5"]),
            &owned(&["field.x_deg"]),
        )
        .unwrap();
        for (ours, point) in [(g.d_asnr[0], single.d_asnr[0]), (g.d_mean_mtf[0], single.d_mean_mtf[0])] {
            assert!((ours - 2.0 / 3.0 * point).abs() <= 1e-12 * point.abs(), "{ours} vs 2/3 of {point}");
        }
    }

    /// The relative step for `lens.norm_radius_mm`: R_n moves the edge's phase by
    /// `Σ 2i A_i δ ln R_n ≈ 1055 rad` per unit of ln R_n on the example (A1 = −527.8), so the
    /// [`PHASE_STEP`] of A1 (0.0155 rad) is `δ ln R_n ≈ 1.5e-5`.
    const NORM_RADIUS_STEP: f64 = 1.5e-5;

    /// `lens.norm_radius_mm` of the Binary 2 lens (docs/physics.md, "Gradients: chain rules":
    /// `∂/∂ln R_n = Σ −2i A_i ∂/∂A_i` on the Binary 2 lanes), the example's four terms alone and
    /// with a freeform spline added (in ρ: it does not move with R_n), against
    /// central differences of evaluations converged at 1e-10, within 10× the scene's 1e-6 of
    /// the gradient's norm.
    #[test]
    fn norm_radius_matches_central_differences() {
        let source = example("phase-binary2.toml");
        let step =
            |k: &str, v: f64| if k == "lens.norm_radius_mm" { NORM_RADIUS_STEP * v } else { relative_step(k, v) };
        check_with_steps(&source, &[], &["lens.norm_radius_mm", "exposure.time_ms"], &step);
        let with_spline = owned(&["lens.phase_spline_rad=[0.0, 0.3, -0.2, 0.1]"]);
        check_with_steps(&source, &with_spline, &["lens.norm_radius_mm", "exposure.time_ms"], &step);
        // a phase lens whose profile takes no R_n (a spline alone) has no such key; a
        // chromatic lens neither
        let e = gradient(&scene::read(None).unwrap(), &[], &owned(&["lens.norm_radius_mm"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.norm_radius_mm"), "{e}");
    }

    /// `lens.aperture_diameter_mm` and `lens.focal_length_mm` with the diameter given
    /// (F# = f0/D: `∂/∂D = −(1/D) ∂/∂ln F#`, `∂/∂ln f0|D = ∂/∂ln f0|F# + ∂/∂ln F#`), on the
    /// Binary 2 lens read from its .zmx (its profile moves with R, the lanes of the radial
    /// engine) and on the paper's chromatic lens given by its diameter (the closed form), in
    /// both forms with the stray light, against central differences with [`APERTURE_STEP`].
    #[test]
    fn aperture_diameter_and_focal_length_at_a_given_diameter_match_central_differences() {
        let keys = ["lens.aperture_diameter_mm", "lens.focal_length_mm", "exposure.time_ms"];
        let step = |k: &str, v: f64| if k.starts_with("lens.") { APERTURE_STEP * v.abs() } else { relative_step(k, v) };
        let zmx = example("phase-binary2-zmx.toml");
        check_with_steps(&zmx, &[], &keys, &step);
        let paper = scene::read(None).unwrap();
        assert!(paper.text().contains("f_number = 2.5"));
        let by_diameter = Source::from_text(
            paper.text().replace("f_number = 2.5", "aperture_diameter_mm = 1.344"),
            "the paper's lens by its diameter, written in the test",
            ".",
        );
        check_with_steps(&by_diameter, &[], &keys, &step);
        check_with_steps(&by_diameter, &owned(&INTEGRAL_WITH_GLARE), &keys, &step);
        // the library lens's ring crossings refuse the diameter as the F-number
        let e = gradient(
            &Source::from_text(
                example("library.toml").text().replace("f_number = 2.5", "aperture_diameter_mm = 1.344"),
                "library lens by its diameter",
                std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples"),
            ),
            &[],
            &owned(&["lens.aperture_diameter_mm"]),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("--wrt lens.aperture_diameter_mm") && e.contains("ring centre"), "{e}");
    }

    /// The radiance meter's readings (SI eq. S2–S6: factors P, d⁻², T⁻¹, D⁻², f² on the radiance)
    /// and its calibration wavelength between two rows of the responsivity table (R′/R of the
    /// row interval), with read noise, the stray light and the integral form, against central
    /// differences; at a row (the example's 800 nm) the calibration wavelength is refused.
    #[test]
    fn radiance_meter_keys_match_central_differences() {
        let source = example("radiance-meter.toml");
        let keys = [
            "source.power_nw",
            "source.fiber_core_diameter_um",
            "source.relay_transmission",
            "source.relay_iris_mm",
            "source.relay_focal_length_mm",
            "source.calibration_wavelength_nm",
            "exposure.time_ms",
        ];
        // 820 nm: between the rows 800 and 850, the step 0.55 nm stays inside them
        check_against_differences(&source, &owned(&["source.calibration_wavelength_nm=820"]), &keys);
        check_against_differences(
            &source,
            &joined(&INTEGRAL_WITH_GLARE, &["source.calibration_wavelength_nm=820", "source.relay_transmission=0.9"]),
            &keys,
        );
        let e = gradient(&source, &[], &owned(&["source.calibration_wavelength_nm"])).unwrap_err().to_string();
        assert!(
            e.contains("--wrt source.calibration_wavelength_nm") && e.contains("a row of the responsivity table"),
            "{e}"
        );
    }

    /// The PSF stack's keys (docs/physics.md, "Gradients: chain rules"): the F-number through
    /// N ∝ 1/F#² alone (its OTF is a table in absolute frequency), the focal length not at all,
    /// the efficiency and transmission as the one order's constant factors, and the pitch
    /// scaling the OTF's frequencies (`∂M̄/∂ln p = MTF(ν_N) − M̄`, the stack's 2-D OTF averaged
    /// over azimuth; with the pixel MTF, by parts `P(ν_N)|O(ν_N)| − M̄ − P_ν`), in both forms with
    /// the stray light, against central differences of converged evaluations; a slice's
    /// wavelength is refused. The differences on a 5 nm band: the same slices' OTFs blended
    /// between their wavelengths on the same rule (6 spectral panels, 36 nodes, against 26 and
    /// 156 over the example's 50 nm: `asnr evaluate --json`), each 1e-10 reference some five
    /// times cheaper.
    #[test]
    fn psf_stack_keys_match_central_differences() {
        let source = example("psf-stack.toml");
        let keys = [
            "lens.f_number",
            "lens.focal_length_mm",
            "lens.efficiency",
            "lens.transmission",
            "lens.psf_pitch_um",
            "exposure.time_ms",
        ];
        let narrow = "spectrum.range_nm=5";
        check_against_differences(&source, &owned(&[narrow]), &keys);
        check_against_differences(&source, &joined(&INTEGRAL_WITH_GLARE, &[narrow]), &keys);
        let g = gradient(&source, &[], &owned(&["lens.focal_length_mm"])).unwrap();
        assert_eq!((g.d_asnr[0], g.d_photoelectrons[0]), (0.0, 0.0));
        let e = gradient(&source, &[], &owned(&["lens.psf_wavelengths_nm[3]"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.psf_wavelengths_nm[3]") && e.contains("breakpoint"), "{e}");
        // with the pixel MTF: its sinc's term P_ν of the integration by parts (on the stack's
        // 2-D OTF, over azimuth on the value's adaptive rule)
        check_against_differences(
            &source,
            &joined(&PIXEL_AND_READ_NOISE, &[narrow]),
            &["lens.psf_pitch_um", "camera.pixel_pitch_um"],
        );
    }

    /// A PSF stack's pitch under a noise spectrum (docs/physics.md, "Gradients: chain rules", a
    /// PSF stack): the weighted mean's change of scale, by parts `P(ν_N)|O(ν_N)|/n(ν_N) − G −
    /// (1/ν_N) ∫ P|O|(νP′/P − νn′/n)/n dν` over the stack's directions, with and without the pixel
    /// MTF, against central differences of evaluations converged at 1e-10, within 10× the scene's
    /// 1e-6 of the gradient's norm, where the weight moves the gradient ([`assert_weighted`]); at
    /// a 5 nm band (a few slices: the 1e-10 references take seconds, not the minutes of the 50 nm
    /// band's).
    #[test]
    fn psf_pitch_under_a_noise_spectrum_matches_central_differences() {
        let stack = with_noise_spectrum_beside(&example("psf-stack.toml"), "psf-pitch");
        let key = ["lens.psf_pitch_um"];
        for overrides in [owned(&["spectrum.range_nm=5"]), owned(&["spectrum.range_nm=5", "camera.pixel_mtf=true"])] {
            assert_weighted(&gradient(&stack, &overrides, &owned(&key)).unwrap());
            check_against_differences(&stack, &overrides, &key);
        }
    }

    /// A PSF stack's field angles (docs/physics.md, "Gradients: the field point"): its PSFs are
    /// one field point's in that point's frame, the same at every field point, so the mean MTF
    /// does not move (its differences are rounding) and N moves by the relative illumination
    /// alone (cos⁴θ here), against central differences of converged evaluations at (3°, 4°),
    /// in both forms with the stray light; on axis the derivative is 0.
    #[test]
    fn psf_stack_field_angles_match_central_differences() {
        let source = example("psf-stack.toml");
        let set = owned(&["lens.relative_illumination=\"cos4\"", "field.x_deg=3", "field.y_deg=4"]);
        let keys = ["field.x_deg", "field.y_deg"];
        check_with_steps(&source, &set, &keys, &|_, _| 1e-2);
        let integral: Vec<String> = set.iter().cloned().chain(owned(&INTEGRAL_WITH_GLARE)).collect();
        check_with_steps(&source, &integral, &keys, &|_, _| 1e-2);
        let g = gradient(&source, &set, &owned(&keys)).unwrap();
        assert_eq!(g.d_mean_mtf, vec![0.0, 0.0]);
        assert!(g.d_photoelectrons.iter().all(|d| *d < 0.0), "{g:?}");
        let on_axis = owned(&["lens.relative_illumination=\"cos4\""]);
        let g = gradient(&source, &on_axis, &owned(&keys)).unwrap();
        assert_eq!(g.d_asnr, vec![0.0, 0.0]);
    }

    /// A line on a PSF stack (docs/physics.md, "Gradients: a line's wavelength and a blackbody's
    /// temperature", on a table): between the slices at 800 and 805 nm the OTF is their linear
    /// interpolation in λ, whose slope on the slices' own OTFs (over azimuth, the stack's 2-D
    /// OTF) moves |O|; at 802 nm with the pixel MTF and read noise, and under a noise spectrum
    /// (the weight moving the gradient: [`assert_weighted`]), against Richardson central
    /// differences of evaluations converged at 1e-10, within 10× the scene's 1e-6 of the
    /// gradient's norm; at a slice's wavelength (800 nm) the kink is refused.
    #[test]
    fn a_line_on_a_psf_stack_matches_central_differences() {
        let stack = example("psf-stack.toml");
        let line = ["spectrum.shape=\"line\"", "spectrum.center_nm=802", "spectrum.range_nm=1"];
        let center = ["spectrum.center_nm"];
        let pixel = joined(&line, &PIXEL_AND_READ_NOISE);
        check_with_references(&stack, &pixel, &center, &|k, v| richardson(&stack, &pixel, k, v, LINE_STEP_NM));
        let shaped = with_noise_spectrum_beside(&stack, "line-stack");
        assert_weighted(&gradient(&shaped, &owned(&line), &owned(&center)).unwrap());
        check_with_references(&shaped, &owned(&line), &center, &|k, v| {
            richardson(&shaped, &owned(&line), k, v, LINE_STEP_NM)
        });
        let at_slice = owned(&["spectrum.shape=\"line\"", "spectrum.center_nm=800", "spectrum.range_nm=1"]);
        let e = gradient(&stack, &at_slice, &owned(&center)).unwrap_err().to_string();
        assert!(e.contains("--wrt spectrum.center_nm") && e.contains("breakpoint") && e.contains("kink"), "{e}");
    }

    /// The harmonic lens's `efficiency` (τ_base, a factor on every order's τ_m) and
    /// `transmission`, with the stray light, against central differences.
    #[test]
    fn harmonic_efficiency_and_transmission_match_central_differences() {
        let source = example("harmonic.toml");
        let keys = ["lens.efficiency", "lens.transmission", "exposure.time_ms"];
        check_against_differences(&source, &owned(&["options.glare=\"included\"", "camera.read_noise_e=2"]), &keys);
    }

    /// The keys still refused name the key and why: the library's amplitude errors (the
    /// obscuration under a line is computed on the line's grids:
    /// [`wavefront_keys_under_a_line_on_its_grids_are_the_derivative_of_the_discrete_rule`]).
    #[test]
    fn moving_edges_and_random_draws_are_refused_naming_why() {
        let library = example("library.toml");
        let e = gradient(&library, &[], &owned(&["lens.atom_transmission_error"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.atom_transmission_error") && e.contains("kink"), "{e}");
    }

    /// Under a line whose orders are on FFT grids (an annulus, Seidel or Zernike terms:
    /// docs/physics.md, "Gradients: 2-D pupils under a line") the obscuration, the Seidel terms
    /// and the Zernike terms are the FFT path's forward mode on the line's own grids: on the
    /// paper's lens under a line at 803 nm (64 pupil samples), an annulus ε = 0.3 with spherical
    /// aberration 0.05 µm and coma 0.1 µm at 3° off axis, with Z4, Z2 (at zero) and Z8 on axis
    /// under the noise spectrum, and the Binary 2 phase lens at 3° (its field angle and
    /// `lens.binary2[1]`), each key's mean MTF and ASNR derivatives against central
    /// differences of the same discrete rule (step 1e-5) within 1e-6 of the norm, the value
    /// beside the gradient the evaluation's bit for bit, and the photon count ∝ 1 − ε².
    #[test]
    fn wavefront_keys_under_a_line_on_its_grids_are_the_derivative_of_the_discrete_rule() {
        let paper = scene::read(None).unwrap();
        let line = ["options.pupil_samples=64", LINE_803[0], LINE_803[1], LINE_803[2]];
        let noisy = with_noise_spectrum(&paper, "line-grids");
        let binary2 = example("phase-binary2.toml");
        for (source, more, keys) in [
            (
                &paper,
                &["lens.obscuration=0.3", "field.y_deg=3", "lens.spherical_um=0.05", "lens.coma_um=0.1"][..],
                &["lens.obscuration", "lens.spherical_um", "lens.coma_um"][..],
            ),
            (
                &noisy,
                &["lens.zernike_noll_rms_um=[0, 0, 0, 0.02, 0, 0, 0, 0.01]"],
                &["lens.zernike_noll_rms_um[3]", "lens.zernike_noll_rms_um[1]", "lens.zernike_noll_rms_um[7]"],
            ),
            // a phase lens seen off axis: its pupil on the line's grids, the oblique wave's lane
            (&binary2, &["field.x_deg=3"], &["field.x_deg", "lens.binary2[1]"]),
        ] {
            let overrides = joined(&line, more);
            let g = gradient(source, &overrides, &owned(keys)).unwrap();
            let plain = metric::evaluate(&scene::build_from(source, &overrides).unwrap()).unwrap();
            assert_eq!((g.mean_mtf, g.asnr), (plain.mean_mtf, plain.asnr));
            let h = 1e-5;
            let differences: Vec<[f64; 2]> = (0..keys.len())
                .map(|i| {
                    let up = evaluated(source, &overrides, keys[i], g.values[i] + h);
                    let down = evaluated(source, &overrides, keys[i], g.values[i] - h);
                    [(up[0] - down[0]) / (2.0 * h), (up[1] - down[1]) / (2.0 * h)]
                })
                .collect();
            for (q, ours) in [(0, &g.d_asnr), (1, &g.d_mean_mtf)] {
                let norm = ours.iter().map(|x| x * x).sum::<f64>().sqrt();
                for (i, k) in keys.iter().enumerate() {
                    let error = (ours[i] - differences[i][q]).abs() / norm;
                    println!(
                        "{k} ({}): gradient {:.9e}, differences {:.9e}, error/norm {error:.1e}",
                        ["ASNR", "mean MTF"][q],
                        ours[i],
                        differences[i][q]
                    );
                    assert!(error <= 1e-6, "{k}: {} vs {} (norm {norm})", ours[i], differences[i][q]);
                }
            }
            if let Some(place) = keys.iter().position(|k| *k == "lens.obscuration") {
                let n = g.photoelectrons;
                assert!((g.d_photoelectrons[place] + 2.0 * 0.3 * n / (1.0 - 0.09)).abs() <= 1e-12 * n);
            }
        }
    }

    /// The F-number, the focal length, the design wavelength and the line's wavelength under a
    /// line whose orders are on its FFT grids (docs/physics.md, "Gradients: the F-number, the
    /// focal length and the wavelengths under a line on the grids": `D_s − 2 D_K`, `D_K`,
    /// `D_λ0 − r M̄`, and the line's `D_s + D_c − r M̄ − D_W`): the paper's lens through an annulus
    /// (ε = 0.3, and ε = 0.45 decentred by 0.15), with Seidel terms on the full circle and through
    /// the decentred iris of `examples/decentred-iris.toml`, with Z4 and Z8 (also at 800 nm, where
    /// the chromatic defocus is 0), and the harmonic lens's seven orders with Z4 and Z8, under a
    /// line (64 pupil samples), against central differences of the same discrete rule (relative
    /// step 1e-5, 2.5e-6 for the wavelengths): each key's `∂/∂ln key` of the ASNR and the mean
    /// MTF within 1e-6 of the norm, the value beside the gradient the evaluation's bit for bit.
    #[test]
    fn aperture_and_wavelengths_under_a_line_on_its_grids_are_the_derivative_of_the_discrete_rule() {
        let paper = scene::read(None).unwrap();
        let iris = example("decentred-iris.toml");
        let harmonic = example("harmonic.toml");
        let seidel = ["lens.spherical_um=0.05", "lens.coma_um=0.1", "lens.astigmatism_um=-0.05"];
        let zernike = "lens.zernike_noll_rms_um=[0, 0, 0, 0.02, 0, 0, 0, 0.01]";
        let at_800 = "spectrum.center_nm=800";
        let cases: [(&Source, Vec<&str>); 7] = [
            (&paper, vec![LINE_803[1], "lens.obscuration=0.3"]),
            (&paper, vec![LINE_803[1], "lens.obscuration=0.45", "lens.iris_decentre_x=0.15"]),
            (&paper, [&[LINE_803[1]], &seidel[..]].concat()),
            (&iris, [&[LINE_803[1]], &seidel[..], &["camera.pixel_mtf=true"]].concat()),
            (&paper, vec![LINE_803[1], zernike]),
            (&paper, vec![at_800, zernike]),
            (&harmonic, vec![LINE_803[1], zernike]),
        ];
        let keys = ["lens.f_number", "lens.focal_length_mm", "lens.design_wavelength_nm", "spectrum.center_nm"];
        for (source, extra) in cases {
            let overrides = joined(&["options.pupil_samples=64", LINE_803[0], LINE_803[2]], &extra);
            let g = gradient(source, &overrides, &owned(&keys)).unwrap();
            let plain = metric::evaluate(&scene::build_from(source, &overrides).unwrap()).unwrap();
            assert_eq!((g.mean_mtf, g.asnr), (plain.mean_mtf, plain.asnr));
            let differences: Vec<[f64; 2]> = keys
                .iter()
                .zip(&g.values)
                .map(|(k, &v)| {
                    let h = if k.ends_with("_nm") { 2.5e-6 } else { 1e-5 } * v;
                    let (up, down) = (evaluated(source, &overrides, k, v + h), evaluated(source, &overrides, k, v - h));
                    [(up[0] - down[0]) / (2.0 * h) * v, (up[1] - down[1]) / (2.0 * h) * v]
                })
                .collect();
            for (q, ours) in [(0, &g.d_asnr), (1, &g.d_mean_mtf)] {
                let ours: Vec<f64> = ours.iter().zip(&g.values).map(|(d, v)| d * v).collect();
                let norm = ours.iter().map(|x| x * x).sum::<f64>().sqrt();
                assert!(norm > 0.0, "{g:?}");
                for (i, k) in keys.iter().enumerate() {
                    let error = (ours[i] - differences[i][q]).abs() / norm;
                    println!(
                        "{extra:?} {k} ({}): gradient {:.9e}, differences {:.9e}, error/norm {error:.1e}",
                        ["ASNR", "mean MTF"][q],
                        ours[i],
                        differences[i][q]
                    );
                    assert!(error <= 1e-6, "{extra:?} {k}: {} vs {} (norm {norm})", ours[i], differences[i][q]);
                }
            }
        }
    }

    /// The obscuration ε of the paper's lens (an annulus on the FFT path; docs/physics.md,
    /// "Gradients: the edge's motion on the FFT path") against central differences of the same
    /// discrete rule (the sampling fixed by `options.pupil_samples = 64`, a 4 nm band, step
    /// 1e-5): the mean MTF's derivative is that rule's within 1e-6 of the norm (each pixel's
    /// area fraction is C¹ in ε: its derivative, the arc length inside the pixel, is continuous
    /// where the circle crosses a corner or touches a side), and N ∝ 1 − ε² (the area fraction on
    /// τ1 and T) gives ∂N = −2ε N/(1 − ε²) within 1e-9; centred at ε = 0.3, and through an
    /// annulus decentred by 0.15 of the radius (the OTF then depends on direction, the
    /// decentred defocus a tilt in the grid) at ε = 0.45. The value beside the gradient is the
    /// evaluation's bit for bit (the lane computed in the value's own pass).
    #[test]
    fn obscuration_gradient_is_the_derivative_of_the_discrete_rule() {
        let paper = scene::read(None).unwrap();
        for (eps, decentre) in [(0.3, 0.0), (0.45, 0.15)] {
            let overrides = vec![
                "spectrum.range_nm=4".to_owned(),
                "options.pupil_samples=64".to_owned(),
                assignment("lens.obscuration", eps),
                assignment("lens.iris_decentre_x", decentre),
            ];
            let g = gradient(&paper, &overrides, &owned(&["lens.obscuration"])).unwrap();
            // the lane rides on the value's pass: the value is the evaluation's bit for bit
            let plain = metric::evaluate(&scene::build_from(&paper, &overrides).unwrap()).unwrap();
            assert_eq!((g.mean_mtf, g.asnr), (plain.mean_mtf, plain.asnr));
            let h = 1e-5;
            let at = |v: f64| {
                let mut set: Vec<String> =
                    overrides.iter().filter(|o| !o.starts_with("lens.obscuration=")).cloned().collect();
                set.push(assignment("lens.obscuration", v));
                metric::evaluate(&scene::build_from(&paper, &set).unwrap()).unwrap()
            };
            let (up, down) = (at(eps + h), at(eps - h));
            let d_mtf = (up.mean_mtf - down.mean_mtf) / (2.0 * h);
            let d_asnr = (up.asnr - down.asnr) / (2.0 * h);
            let d_n = (up.photoelectrons - down.photoelectrons) / (2.0 * h);
            let error = (g.d_mean_mtf[0] - d_mtf).abs() / g.d_mean_mtf[0].abs();
            println!(
                "ε {eps}, decentre {decentre}: ∂M̄ {:.9e}, differences {d_mtf:.9e}, error/norm {error:.1e}; ∂ASNR {:.9e}, \
                 differences {d_asnr:.9e}",
                g.d_mean_mtf[0], g.d_asnr[0]
            );
            assert!(g.d_mean_mtf[0] < 0.0 && error <= 1e-6, "{g:?}");
            assert!((g.d_asnr[0] - d_asnr).abs() <= 1e-6 * g.d_asnr[0].abs(), "{g:?}");
            let n = g.photoelectrons;
            assert!((g.d_photoelectrons[0] - d_n).abs() <= 1e-9 * n, "{} vs {d_n}", g.d_photoelectrons[0]);
            assert!((g.d_photoelectrons[0] + 2.0 * eps * n / (1.0 - eps * eps)).abs() <= 1e-12 * n);
        }
    }

    /// The obscuration asked beside Seidel terms through the annulus (docs/physics.md,
    /// "Gradients: the edge's motion on the FFT path"): every lane a move of the sampled field on
    /// the FFT path, a term's `i k D P` and the inner edge's `∂A exp(i k W)` with `∂Σ A`, on the
    /// paper's lens at ε = 0.3 with spherical aberration 0.05 µm and field curvature 0.03 µm, on
    /// axis and at 3° with coma 0.1 µm, against central differences of the same discrete rule
    /// (64 pupil samples, a 4 nm band, step 1e-5) within 1e-6 of the norm, and the photon count
    /// ∝ 1 − ε² as the obscuration alone gives it.
    #[test]
    fn obscuration_beside_seidel_terms_is_the_derivative_of_the_discrete_rule() {
        let paper = scene::read(None).unwrap();
        let alone = |overrides: &[String]| gradient(&paper, overrides, &owned(&["lens.obscuration"])).unwrap();
        for (at, keys) in [
            ("field.y_deg=0", &["lens.obscuration", "lens.spherical_um", "lens.field_curvature_um"][..]),
            ("field.y_deg=3", &["lens.spherical_um", "lens.obscuration", "lens.coma_um"]),
        ] {
            let overrides = owned(&[
                "spectrum.range_nm=4",
                "options.pupil_samples=64",
                "lens.obscuration=0.3",
                "lens.spherical_um=0.05",
                "lens.coma_um=0.1",
                "lens.field_curvature_um=0.03",
                at,
            ]);
            let g = gradient(&paper, &overrides, &owned(keys)).unwrap();
            let norm = g.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
            let h = 1e-5;
            for (i, k) in g.keys.iter().enumerate() {
                let up = evaluated(&paper, &overrides, k, g.values[i] + h);
                let down = evaluated(&paper, &overrides, k, g.values[i] - h);
                let theirs = (up[1] - down[1]) / (2.0 * h);
                let error = (g.d_mean_mtf[i] - theirs).abs() / norm;
                println!(
                    "{at} {k}: gradient {:.9e}, differences {theirs:.9e}, error/norm {error:.1e}",
                    g.d_mean_mtf[i]
                );
                assert!(error <= 1e-6, "{k}: {} vs {theirs} (norm {norm})", g.d_mean_mtf[i]);
            }
            // the obscuration's own lane and photon counts as asked alone
            let place = g.keys.iter().position(|k| k == "lens.obscuration").unwrap();
            let one = alone(&overrides);
            assert!((g.d_mean_mtf[place] - one.d_mean_mtf[0]).abs() <= 1e-9 * norm, "{g:?} {one:?}");
            assert_eq!(g.d_photoelectrons[place], one.d_photoelectrons[0]);
        }
    }

    /// The obscuration's gradient at the tolerance 1e-3 (the sampling and Richardson
    /// extrapolation the tolerance chooses) against central differences of evaluations at 1e-5,
    /// the FFT path's tightest practical tolerance here, Richardson-extrapolated from the steps
    /// 0.01 and 0.005 (`(4 D(h) − D(2h))/3`, truncation O(h⁴); the mean MTF is smooth in ε on
    /// that scale: D(0.01) and D(0.02) differ by 1.6e-4 of it), on the paper's lens at ε = 0.3
    /// and a 4 nm band: the mean MTF's and the ASNR's within 10× the tolerance of their norms
    /// (measured 5.1e-3 and 2.5e-3; at the tolerance 1e-4, 1.2e-3 and 5.7e-4: the edge's
    /// sampling error in the derivative is about ten times the value's, docs/physics.md).
    #[test]
    fn obscuration_gradient_matches_converged_differences() {
        let paper = scene::read(None).unwrap();
        let base = owned(&["spectrum.range_nm=4", "lens.obscuration=0.3"]);
        let tolerance = 1e-3;
        let mut set = base.clone();
        set.push(format!("options.tolerance={tolerance:e}"));
        let g = gradient(&paper, &set, &owned(&["lens.obscuration"])).unwrap();
        let reference = joined(&["spectrum.range_nm=4", "options.tolerance=1e-5"], &[]);
        let d = |h: f64| {
            let (up, down) = (
                evaluated(&paper, &reference, "lens.obscuration", 0.3 + h),
                evaluated(&paper, &reference, "lens.obscuration", 0.3 - h),
            );
            [(up[0] - down[0]) / (2.0 * h), (up[1] - down[1]) / (2.0 * h)]
        };
        let (fine, coarse) = (d(0.005), d(0.01));
        for (q, (name, ours)) in [("ASNR", g.d_asnr[0]), ("mean MTF", g.d_mean_mtf[0])].into_iter().enumerate() {
            let theirs = (4.0 * fine[q] - coarse[q]) / 3.0;
            let error = (ours - theirs).abs() / ours.abs();
            println!("{name}: gradient {ours:.7e}, differences at 1e-5 {theirs:.7e}, error/norm {error:.1e}");
            assert!(error <= 10.0 * tolerance, "{name}: {ours} vs {theirs}");
        }
    }

    /// `lens.f_number`, `lens.focal_length_mm` and `lens.design_wavelength_nm` where the value's
    /// OTF is on the FFT grids of a sampled pupil (docs/physics.md, "Gradients: the F-number and
    /// the focal length on the FFT grids": the frequency scale's lane and the chromatic defocus's
    /// `D_K`, λ0's `D_λ0 − r M̄`): the paper's lens through an annulus (ε = 0.3, centred and
    /// decentred by 0.15), the decentred iris of `examples/decentred-iris.toml` with Seidel terms
    /// (and the pixel MTF), and the paper's lens with Zernike terms on the FFT path (its radial
    /// pupil), against central differences of the same discrete rule (64 pupil samples, a 4 nm
    /// band, relative step 1e-5, 2.5e-6 for λ0): the mean MTF's within 1e-6 of the norm; N ∝ 1/F#²
    /// as on every engine.
    #[test]
    fn aperture_and_design_wavelength_on_the_fft_grids_are_the_derivative_of_the_discrete_rule() {
        let paper = scene::read(None).unwrap();
        let iris = example("decentred-iris.toml");
        let seidel = ["lens.spherical_um=0.05", "lens.coma_um=0.1", "lens.astigmatism_um=-0.05"];
        let zernike = "lens.zernike_noll_rms_um=[0, 0, 0, 0.05, 0.1, 0.0, 0.05]";
        let cases: [(&Source, Vec<&str>); 5] = [
            (&paper, vec!["lens.obscuration=0.3"]),
            (&paper, vec!["lens.obscuration=0.45", "lens.iris_decentre_x=0.15"]),
            (&iris, seidel.to_vec()),
            (&iris, [&seidel[..], &["camera.pixel_mtf=true"]].concat()),
            (&paper, vec![zernike]),
        ];
        for (source, extra) in cases {
            let overrides = joined(&["spectrum.range_nm=4", "options.pupil_samples=64"], &extra);
            // (λ0 with Zernike terms is not computed yet: the lens gives no design-wavelength rates)
            let keys = match extra == [zernike] {
                true => owned(&["lens.f_number", "lens.focal_length_mm"]),
                false => owned(&["lens.f_number", "lens.focal_length_mm", "lens.design_wavelength_nm"]),
            };
            let g = mean_mtf_of_the_discrete_rule(source, &overrides, &keys, &format!("{extra:?}"));
            // N ∝ 1/F#², f0 and λ0 leave it (a constant efficiency)
            let n = g.photoelectrons;
            assert!((g.d_photoelectrons[0] * g.values[0] + 2.0 * n).abs() <= 1e-12 * n, "{g:?}");
        }
    }

    /// `source`'s gradient over `keys` under `overrides`, its mean MTF's derivatives against
    /// central differences of the same discrete rule (relative step 1e-5; 2.5e-6 for λ0, which
    /// turns the band's defocus fast, its truncation 4e-8 of the norm) within 1e-6 of the norm;
    /// the errors printed after `label`.
    fn mean_mtf_of_the_discrete_rule(source: &Source, overrides: &[String], keys: &[String], label: &str) -> Gradient {
        let g = gradient(source, overrides, keys).unwrap();
        let norm = g.d_mean_mtf.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(norm > 0.0, "{g:?}");
        for (i, k) in g.keys.iter().enumerate() {
            let h = if k == "lens.design_wavelength_nm" { 2.5e-6 } else { 1e-5 } * g.values[i];
            let up = evaluated(source, overrides, k, g.values[i] + h);
            let down = evaluated(source, overrides, k, g.values[i] - h);
            let theirs = (up[1] - down[1]) / (2.0 * h);
            let error = (g.d_mean_mtf[i] - theirs).abs() / norm;
            println!("{label} {k}: gradient {:.9e}, differences {theirs:.9e}, error/norm {error:.1e}", g.d_mean_mtf[i]);
            assert!(error <= 1e-6, "{label} {k}: {} vs {theirs} (norm {norm})", g.d_mean_mtf[i]);
        }
        g
    }

    /// Off axis on the FFT grids (docs/physics.md, "Gradients: the F-number and the focal length
    /// on the FFT grids off axis"): the lateral colour turns each node's reading by
    /// `exp(−2πi ν u·Δ)`, `Δ = f0 tan θ (λ0/λ − 1)`, its lane `−2πi ν u·δΔ` times the node's
    /// turned value beside the defocus's and λ0's: the paper's lens through an annulus (ε = 0.3)
    /// at 3°, the paper's lens with a Zernike term on the FFT path (its radial pupil) at 2°, and
    /// the decentred iris of `examples/decentred-iris.toml` with Seidel terms and the pixel MTF
    /// at (2°, 1.5°), against central differences of the same discrete rule (64 pupil
    /// samples, a 4 nm band, relative step 1e-5, 2.5e-6 for λ0): the mean MTF's within 1e-6 of
    /// the norm.
    #[test]
    fn aperture_design_wavelength_and_field_off_axis_on_the_fft_grids_are_the_derivative_of_the_discrete_rule() {
        let paper = scene::read(None).unwrap();
        let iris = example("decentred-iris.toml");
        let seidel = ["lens.spherical_um=0.05", "lens.coma_um=0.1", "lens.astigmatism_um=-0.05"];
        let aperture = ["lens.f_number", "lens.focal_length_mm", "lens.design_wavelength_nm"];
        let cases: [(&Source, Vec<&str>, Vec<&str>); 3] = [
            (&paper, vec!["lens.obscuration=0.3", "field.x_deg=3"], [&aperture[..], &["field.x_deg"]].concat()),
            // (Zernike terms on the FFT path: λ0 is not computed there, the lens gives no rates)
            (
                &paper,
                vec!["lens.zernike_noll_rms_um=[0, 0, 0, 0, 0.1]", "field.x_deg=2"],
                vec!["lens.f_number", "lens.focal_length_mm", "field.x_deg"],
            ),
            (
                &iris,
                [&seidel[..], &["camera.pixel_mtf=true", "field.x_deg=2", "field.y_deg=1.5"]].concat(),
                [&aperture[..], &["field.x_deg", "field.y_deg"]].concat(),
            ),
        ];
        for (source, extra, keys) in cases {
            // (λ0 off the band's centre: at 800 nm the value's adaptive rules there move it by
            // ~5e-7 between 800 ± 0.002 nm, more than its derivative does; at 801 nm its central
            // differences agree from 0.002 to 0.02 nm to 4e-6)
            let overrides =
                joined(&["spectrum.range_nm=4", "options.pupil_samples=64", "lens.design_wavelength_nm=801"], &extra);
            mean_mtf_of_the_discrete_rule(source, &overrides, &owned(&keys), &format!("{extra:?}"));
        }
        // under a noise spectrum the F-number's frequency scale is the continuous rule's by parts
        // (`ν ∂_ν` turns each node's lateral-colour phase too: minus the weighted D̃_Δ), so
        // against the discrete rule's differences within its error, the FFT path's 1e-4: the
        // ASNR's within 10× that of the norm (without D̃_Δ the F-number's is 6 % off)
        let noisy = with_noise_spectrum(&iris, "grids-off-axis");
        let overrides = owned(&[
            "spectrum.range_nm=4",
            "options.pupil_samples=64",
            "lens.design_wavelength_nm=801",
            "lens.obscuration=0.3",
            "field.x_deg=3",
        ]);
        let keys = owned(&["lens.f_number", "lens.focal_length_mm"]);
        let g = gradient(&noisy, &overrides, &keys).unwrap();
        assert_weighted(&g);
        let norm = g.d_asnr.iter().map(|x| x * x).sum::<f64>().sqrt();
        for (i, k) in keys.iter().enumerate() {
            let h = 1e-4 * g.values[i];
            let up = evaluated(&noisy, &overrides, k, g.values[i] + h);
            let down = evaluated(&noisy, &overrides, k, g.values[i] - h);
            let theirs = (up[0] - down[0]) / (2.0 * h);
            let error = (g.d_asnr[i] - theirs).abs() / norm;
            println!("noise {k}: gradient {:.9e}, differences {theirs:.9e}, error/norm {error:.1e}", g.d_asnr[i]);
            assert!(error <= 1e-3, "noise {k}: {} vs {theirs} (norm {norm})", g.d_asnr[i]);
        }
    }

    /// The F-number and the focal length through the paper's annulus (ε = 0.3, a 4 nm band) at
    /// the tolerance 1e-3 (the sampling and Richardson extrapolation the tolerance chooses)
    /// against central differences of evaluations at 1e-4 (0.24 s each; at 1e-5 the FFT path
    /// takes 2.6 s), Richardson-extrapolated from the relative steps 0.02 and 0.01
    /// (`(4 D(h) − D(2h))/3`, truncation O(h⁴); the steps wide enough that the evaluations'
    /// error, ~1e-4 of M̄, moves the differences by less than 2e-3 of the norm): the ASNR's and
    /// the mean MTF's within 10× the tolerance of their gradients' norms (measured on the command
    /// line 2.5e-4 and 1.6e-3).
    #[test]
    fn aperture_on_the_fft_grids_matches_converged_differences() {
        let paper = scene::read(None).unwrap();
        let base = owned(&["spectrum.range_nm=4", "lens.obscuration=0.3"]);
        let tolerance = 1e-3;
        let mut set = base.clone();
        set.push(format!("options.tolerance={tolerance:e}"));
        let keys = owned(&["lens.f_number", "lens.focal_length_mm"]);
        let g = gradient(&paper, &set, &keys).unwrap();
        let reference = owned(&["spectrum.range_nm=4", "lens.obscuration=0.3", "options.tolerance=1e-4"]);
        let mut theirs = [[0.0; 2]; 2];
        for (i, k) in keys.iter().enumerate() {
            let v = g.values[i];
            let d = |h: f64| {
                let (up, down) = (evaluated(&paper, &reference, k, v + h), evaluated(&paper, &reference, k, v - h));
                [(up[0] - down[0]) / (2.0 * h), (up[1] - down[1]) / (2.0 * h)]
            };
            let (fine, coarse) = (d(0.01 * v), d(0.02 * v));
            theirs[i] = std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0);
        }
        for (q, (name, ours)) in [("ASNR", &g.d_asnr), ("mean MTF", &g.d_mean_mtf)].into_iter().enumerate() {
            let norm = ours.iter().map(|x| x * x).sum::<f64>().sqrt();
            for (i, k) in keys.iter().enumerate() {
                let error = (ours[i] - theirs[i][q]).abs() / norm;
                println!(
                    "{name} {k}: gradient {:.7e}, differences at 1e-4 {:.7e}, error/norm {error:.1e}",
                    ours[i], theirs[i][q]
                );
                assert!(error <= 10.0 * tolerance, "{name} {k}: {} vs {}", ours[i], theirs[i][q]);
            }
        }
    }

    /// Each key's gradient (ASNR, mean MTF, SNR0, N) against central differences of evaluations
    /// converged at 1e-10 with the step `(3e-10/|f‴|)^{1/3}` for a value turning on the key's
    /// `scale`, as sensitivities per `scale` (`∂/∂key × scale`: the keys may be 0), within 10× the
    /// scene's 1e-6 relative to the gradient's norm (or the quantity's size where it is 0).
    fn check_at_scales(source: &Source, overrides: &[&str], keys: &[(&str, f64, f64)]) {
        let tolerance = 1e-6;
        let overrides = owned(overrides);
        let names: Vec<&str> = keys.iter().map(|k| k.0).collect();
        let g = gradient(source, &overrides, &owned(&names)).unwrap();
        let references: Vec<[f64; 4]> =
            keys.iter().zip(&g.values).map(|((k, _, h), v)| central(source, &overrides, k, *v, *h)).collect();
        let ours = [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons];
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            let mine: Vec<f64> = keys.iter().enumerate().map(|(i, k)| ours[q][i] * k.1).collect();
            let theirs: Vec<f64> = keys.iter().enumerate().map(|(i, k)| references[i][q] * k.1).collect();
            let quantity = [g.asnr, g.mean_mtf, g.snr0, g.photoelectrons][q];
            let norm = match mine.iter().map(|x| x * x).sum::<f64>().sqrt() {
                0.0 => quantity,
                norm => norm,
            };
            for (i, (k, _, _)) in keys.iter().enumerate() {
                let error = (mine[i] - theirs[i]).abs();
                println!(
                    "{name} {k}: gradient {:.9e}, differences {:.9e}, error/norm {:.1e}",
                    mine[i],
                    theirs[i],
                    error / norm
                );
                assert!(error <= 10.0 * tolerance * norm, "{name} {k}: {} vs {} (norm {norm})", mine[i], theirs[i]);
            }
        }
    }

    /// The steps of [`check_at_scales`] for the iris's decentre (the value turns on ~0.05 of the
    /// radius, as the F-number's few per cent: the tilt 2 W020 d is several waves at a 50 nm
    /// band's edge, [`APERTURE_STEP`]) and the field angles (per degree: the lateral colour
    /// f0 tan θ (λ0/λ − 1) turns the value over about a degree).
    const DECENTRE: f64 = APERTURE_STEP;
    const DEGREE: f64 = 1e-3;

    /// The decentred iris (examples/decentred-iris.toml, 0.15 of the radius along x, on axis):
    /// its decentre's lane on the exact 1-D engine (x, and y at 0: 0 by the mirror y → −y, which
    /// the differences must find), the F-number and the focal length through the reduction
    /// (F#/r, the tilt's shift Δ = 4 F# W020 d), the field angles at 0 (the lateral colour seen
    /// through the iris; x and y), and off axis at (3°, 2°) every one of them but the aperture.
    #[test]
    fn a_decentred_iris_keys_match_central_differences() {
        let iris = example("decentred-iris.toml");
        check_at_scales(
            &iris,
            &[],
            &[
                ("lens.iris_decentre_x", 1.0, DECENTRE),
                ("lens.iris_decentre_y", 1.0, DECENTRE),
                ("field.x_deg", 1.0, DEGREE),
                ("field.y_deg", 1.0, DEGREE),
                ("exposure.time_ms", 1.23, relative_step("", 1.23)),
            ],
        );
        check_aperture(&iris, &[]);
        check_aperture(&iris, &owned(&["options.form=\"integral\"", "lens.iris_decentre_y=-0.1"]));
        check_at_scales(
            &iris,
            &["field.x_deg=3", "field.y_deg=2"],
            &[
                ("lens.iris_decentre_x", 1.0, DECENTRE),
                ("lens.iris_decentre_y", 1.0, DECENTRE),
                ("field.x_deg", 1.0, DEGREE),
                ("field.y_deg", 1.0, DEGREE),
            ],
        );
        let e = metric::evaluate(&scene::build_from(&iris, &[]).unwrap()).unwrap();
        assert!(e.numerics.engine.contains("exact-1d"), "{}", e.numerics.engine);
    }

    /// The decentre at 0: on axis (the paper's lens) the OTF is rotationally symmetric and the
    /// derivative is 0 by the mirror d → −d; off axis at 3° along x the lateral colour breaks the
    /// mirror x → −x, and the iris's tilt 2 W020 d moves each wavelength's image against its
    /// lateral colour (both ∝ λ0/λ − 1): ∂/∂d_x is not 0, ∂/∂d_y is (the mirror y → −y). Each
    /// against central differences across 0 (evaluations with the iris moved either way).
    #[test]
    fn the_decentre_at_zero_matches_central_differences() {
        let paper = scene::read(None).unwrap();
        let keys = [("lens.iris_decentre_x", 1.0, DECENTRE), ("lens.iris_decentre_y", 1.0, DECENTRE)];
        let on_axis = gradient(&paper, &[], &owned(&["lens.iris_decentre_x", "lens.iris_decentre_y"])).unwrap();
        assert_eq!(on_axis.d_asnr, vec![0.0, 0.0]);
        check_at_scales(&paper, &["field.x_deg=3"], &keys);
        let off_axis = gradient(&paper, &owned(&["field.x_deg=3"]), &owned(&["lens.iris_decentre_x"])).unwrap();
        assert!(off_axis.d_asnr[0].abs() > 0.1, "{:?}", off_axis.d_asnr);
        // on axis the differences across 0 find 0 too (to rounding of the ASNR)
        for k in ["lens.iris_decentre_x", "lens.iris_decentre_y"] {
            let d = central(&paper, &[], k, 0.0, DECENTRE);
            assert!(d[0].abs() <= 1e-9 * on_axis.asnr / DECENTRE, "{k}: {d:?}");
        }
    }

    /// The obscuration at 0, the edge of its domain [0, 1): the removed disc's area πε² and every
    /// OTF change are O(ε²), so the one-sided derivative is 0, reported for all four quantities.
    /// The reference: one-sided differences (f(h) − f(0))/h on the FFT path (the annulus) at
    /// h = 0.02, 0.04, 0.08 against the exact value at 0; they vanish linearly in h (the
    /// quotient doubles with h, which a non-zero slope would not let it), and their extrapolation
    /// to h = 0 (removing the h and h² terms of f(h) − f(0) = a₂h² + a₃h³) is below 5 % of the
    /// quotient at 0.02 (the FFT path's 3e-6 over h = 0.02 is 1.5e-4 of the ASNR). N exactly
    /// ∝ 1 − ε².
    #[test]
    fn the_obscuration_at_zero_is_zero_one_sided() {
        let paper = scene::read(None).unwrap();
        let g = gradient(&paper, &[], &owned(&["lens.obscuration"])).unwrap();
        assert_eq!([g.d_asnr[0], g.d_mean_mtf[0], g.d_snr0[0], g.d_photoelectrons[0]], [0.0; 4]);
        // the scene's own tolerances (the FFT path at its default, the exact value at 0)
        let at = |e: f64| {
            let v =
                metric::evaluate(&scene::build_from(&paper, &[assignment("lens.obscuration", e)]).unwrap()).unwrap();
            [v.asnr, v.mean_mtf, v.snr0, v.photoelectrons]
        };
        let zero = at(0.0);
        let quotient = |h: f64| {
            let v = at(h);
            [(v[0] - zero[0]) / h, (v[3] - zero[3]) / h]
        };
        let (d1, d2, d4) = (quotient(0.02), quotient(0.04), quotient(0.08));
        let ratio = d2[0] / d1[0];
        assert!((1.6..=2.4).contains(&ratio), "{d1:?} {d2:?}");
        let r1 = 2.0 * d1[0] - d2[0];
        let r2 = 2.0 * d2[0] - d4[0];
        let slope = (4.0 * r1 - r2) / 3.0;
        println!("quotients {d1:?} {d2:?} {d4:?}, slope at 0 {slope:e}");
        assert!(slope.abs() <= 0.05 * d1[0].abs(), "{slope} against {}", d1[0]);
        // N = N0 (1 − ε²): its quotient −N0 h
        assert!((d1[1] + zero[3] * 0.02).abs() <= 1e-9 * zero[3], "{d1:?}");
    }

    /// The table's columns stay aligned whatever a value's length (a float printed in full).
    #[test]
    fn the_table_is_aligned_for_long_values() {
        let g = Gradient {
            keys: owned(&["lens.binary2[3]", "exposure.time_ms"]),
            values: vec![0.002638937829015425, 1.23],
            asnr: 10.0,
            mean_mtf: 0.4,
            snr0: 25.0,
            photoelectrons: 625.0,
            d_asnr: vec![1.5e-2, 4.0],
            d_mean_mtf: vec![0.0; 2],
            d_snr0: vec![0.0; 2],
            d_photoelectrons: vec![0.0; 2],
        };
        let text = table(&g);
        let lines: Vec<&str> = text.lines().skip(2).collect();
        assert_eq!(lines.len(), 3, "{text}");
        let widths: Vec<usize> = lines.iter().map(|l| l.chars().count()).collect();
        assert!(widths.iter().all(|&w| w == widths[0]), "{text}");
        // each value ends where the header's "value" ends
        let end = |l: &str, what: &str| l.find(what).map(|i| l[..i].chars().count() + what.chars().count());
        assert_eq!(end(lines[0], "value"), end(lines[1], "0.002638937829015425"), "{text}");
        assert_eq!(end(lines[0], "value"), end(lines[2], "1.23"), "{text}");
    }

    /// `source` with `camera.noise_spectrum` a table n(ν) written in a directory of its own
    /// (`name`): rows at 0, 30, 70 and 130 cycles/mm rising from 1 to 3, so that the weight
    /// 1/n(ν) falls by 3× over the band and has kinks inside it, none at the Nyquist frequency
    /// of a 5.2 µm pixel (96.15 cycles/mm).
    pub(super) fn with_noise_spectrum(source: &Source, name: &str) -> Source {
        let dir = std::env::temp_dir().join(format!("asnr-noise-gradient-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("nps.csv"), "frequency_cyc_per_mm,relative\n0,1\n30,1.4\n70,2.2\n130,3\n").unwrap();
        let text = source.text().replace("[camera]", "[camera]\nnoise_spectrum = \"nps.csv\"");
        assert!(text.contains("noise_spectrum"), "{text}");
        Source::from_text(text, "a scene with a noise spectrum", dir)
    }

    /// The weight matters: under the noise spectrum ∂ASNR is not SNR0 · ∂M̄ (what the white
    /// mean's lanes would give) by more than the test's tolerance, for each key of `g` that
    /// moves the OTF alone; so the checks against differences below can tell the two apart.
    pub(super) fn assert_weighted(g: &Gradient) {
        let norm = g.d_asnr.iter().map(|x| x * x).sum::<f64>().sqrt();
        let apart = g.d_asnr.iter().zip(&g.d_mean_mtf).map(|(a, m)| (a - g.snr0 * m).abs()).fold(0.0, f64::max);
        println!("largest |∂ASNR − SNR0 ∂M̄| {apart:.3e} of the norm {norm:.3e}");
        assert!(apart > 1e-3 * norm, "{g:?}");
    }

    /// The Binary 2 lens on the radial engine under a noise spectrum (docs/physics.md,
    /// "Gradients under a noise spectrum"): its Binary 2 coefficients and an m = 0 Zernike term
    /// (the radial engine's lanes on the value's noise-weighted pass, each divided by n(ν))
    /// against central differences of evaluations converged at 1e-10, within 10× the scene's
    /// tolerance (1e-6) of the gradient's norm; and the pixel pitch (Leibniz with
    /// MTF(ν_N)/n(ν_N) at the limit) with the camera keys, in the mean and the integral form.
    /// A spline's knots ride the same lanes (their own test below).
    #[test]
    fn wavefront_and_pitch_keys_under_a_noise_spectrum_match_central_differences() {
        let source = with_noise_spectrum(&example("phase-binary2.toml"), "binary2");
        let overrides = owned(&["lens.zernike_noll_rms_um=[0, 0, 0, 0.02]"]);
        let keys = owned(&["lens.binary2[0]", "lens.binary2[1]", "lens.binary2[2]"]);
        let (g, _) = check_wavefront(&source, &overrides, &keys, &phase_or_knot_step);
        assert_weighted(&g);
        let (g, _) =
            check_wavefront(&source, &overrides, &owned(&["lens.zernike_noll_rms_um[3]"]), &|_| PHASE_STEP / 27.0);
        assert_weighted(&g);
        let keys = ["camera.pixel_pitch_um", "exposure.time_ms", "lens.efficiency"];
        check_against_differences(&source, &[], &keys);
        check_against_differences(&source, &owned(&["options.form=\"integral\"", "camera.read_noise_e=2"]), &keys);
        // the paper's lens on the closed form: the pitch alone moves its OTF's weight
        let paper = with_noise_spectrum(&scene::read(None).unwrap(), "paper-pitch");
        check_against_differences(&paper, &[], &keys);
    }

    /// The spline's knots under a noise spectrum (docs/physics.md, "Gradients under a noise
    /// spectrum": the radial engine's lanes on the value's noise-weighted pass, each divided by
    /// n(ν), its frequency rule cut at the table's rows) against central differences of
    /// evaluations converged at 1e-10, within 10× the scene's tolerance (1e-6) of the gradient's
    /// norm, and apart from the white lanes (measured 1.5e-7–3.2e-7 of the norm on the 10 nm
    /// band, 6.9e-8–1.8e-6 over 50 nm; knot 3, 8.3e-9, left out: each reference at 1e-10 took
    /// some 4 s over 50 nm). On a 10 nm band: the same
    /// per-frequency product rule and noise-weighted pass as over the example's 50 nm, each
    /// 1e-10 reference some six times cheaper (as in
    /// [`frequency_scale_keys_under_a_noise_spectrum_match_central_differences`]).
    #[test]
    fn spline_knots_under_a_noise_spectrum_match_central_differences() {
        let source = with_noise_spectrum(&example("phase-binary2.toml"), "spline");
        let knots = owned(&["lens.phase_spline_rad=[0.0, 0.4, -0.3, 0.5]", "spectrum.range_nm=10"]);
        let keys = owned(&["lens.phase_spline_rad[1]", "lens.phase_spline_rad[2]"]);
        let (g, _) = check_wavefront(&source, &knots, &keys, &phase_or_knot_step);
        assert_weighted(&g);
    }

    /// The Seidel keys on the overlap engine under a noise spectrum (its lanes on the value's
    /// noise-weighted pass over azimuth, each divided by n(ν)), on axis and off axis with the
    /// pixel MTF, against [`check_seidel`]'s Richardson-extrapolated central differences within
    /// 10× the tolerance 1e-6 of the norm. A 1e-10 evaluation under a noise spectrum takes two
    /// passes of the overlap engine (11 s on axis with all four terms, 30 s off axis with three,
    /// 6 s with coma alone, release): on axis the keys of spherical aberration (m = 0, the Filon
    /// rule) and astigmatism (m = 2) with every term present, coma off axis, and the field
    /// angles beside coma alone (the spherical term's rule is the white tests' and the one above).
    #[test]
    fn seidel_keys_under_a_noise_spectrum_match_central_differences() {
        let source = with_noise_spectrum(&scene::read(None).unwrap(), "seidel");
        let keys = ["lens.spherical_um", "lens.astigmatism_um"];
        let g = check_seidel_on(
            &source,
            &[
                "spectrum.range_nm=4",
                "lens.spherical_um=0.15",
                "lens.coma_um=0.3",
                "lens.astigmatism_um=0.2",
                "lens.field_curvature_um=0.1",
            ],
            &keys,
            1e-6,
            1e-3,
        );
        assert_weighted(&g);
        let g = check_seidel_on(
            &source,
            &[
                "spectrum.range_nm=4",
                "field.y_deg=2",
                "lens.coma_um=0.3",
                "lens.astigmatism_um=-0.2",
                "camera.pixel_mtf=true",
            ],
            &["lens.coma_um"],
            1e-6,
            1e-3,
        );
        assert_weighted(&g);
        // the field angles' lanes on the overlap engine (the lateral colour's shifts and the
        // relative illumination), held to the tolerance as without the noise spectrum
        let coma_off_axis = [
            "spectrum.range_nm=4",
            "field.x_deg=5",
            "field.y_deg=3",
            "lens.coma_um=0.3",
            "lens.relative_illumination=\"cos4\"",
            "camera.read_noise_e=2",
            "camera.pixel_mtf=true",
        ];
        check_field_of(&source, &coma_off_axis, &["field.x_deg", "field.y_deg"], 0.02, 1e-6);
    }

    /// Zernike terms with m ≠ 0 on the FFT path under a noise spectrum (each frequency's weight
    /// of the value's fixed rule divided by n(ν), the Richardson extrapolation of the two levels
    /// as the value's), against central differences of the same discrete rule (the sampling
    /// fixed by `options.pupil_samples`): the ASNR's gradient within 1e-6 of its norm.
    #[test]
    fn fft_zernike_keys_under_a_noise_spectrum_are_the_derivative_of_the_discrete_rule() {
        let source = with_noise_spectrum(&scene::read(None).unwrap(), "fft");
        let overrides = owned(&[
            "spectrum.range_nm=4",
            "options.pupil_samples=64",
            "lens.zernike_noll_rms_um=[0, 0, 0, 0.05, 0.1, 0.0, 0.05]",
        ]);
        let keys =
            owned(&["lens.zernike_noll_rms_um[3]", "lens.zernike_noll_rms_um[4]", "lens.zernike_noll_rms_um[6]"]);
        let g = gradient(&source, &overrides, &keys).unwrap();
        assert_weighted(&g);
        let norm = g.d_asnr.iter().map(|x| x * x).sum::<f64>().sqrt();
        let h = 1e-5;
        for (i, k) in g.keys.iter().enumerate() {
            let up = evaluated(&source, &overrides, k, g.values[i] + h);
            let down = evaluated(&source, &overrides, k, g.values[i] - h);
            let theirs = (up[0] - down[0]) / (2.0 * h);
            let error = (g.d_asnr[i] - theirs).abs() / norm;
            println!("{k}: ∂ASNR {:.9e}, differences {theirs:.9e}, error/norm {error:.1e}", g.d_asnr[i]);
            assert!(error <= 1e-6, "{k}: {} vs {theirs} (norm {norm})", g.d_asnr[i]);
            assert_eq!(g.d_snr0[i], 0.0);
        }
        // the obscuration's edge lane (from the value's own grids) under the noise weight
        let overrides = owned(&["spectrum.range_nm=4", "options.pupil_samples=64", "lens.obscuration=0.3"]);
        let g = gradient(&source, &overrides, &owned(&["lens.obscuration"])).unwrap();
        let up = evaluated(&source, &overrides, "lens.obscuration", 0.3 + h);
        let down = evaluated(&source, &overrides, "lens.obscuration", 0.3 - h);
        let theirs = (up[0] - down[0]) / (2.0 * h);
        println!("lens.obscuration: ∂ASNR {:.9e}, differences {theirs:.9e}", g.d_asnr[0]);
        assert!((g.d_asnr[0] - theirs).abs() <= 1e-6 * theirs.abs(), "{g:?}");
        assert!((g.d_asnr[0] - g.snr0 * g.d_mean_mtf[0] - g.d_snr0[0] * g.asnr / g.snr0).abs() > 1e-3 * theirs.abs());
    }

    /// [`assert_weighted`] for keys that move N too: ∂ASNR differs from ∂SNR0 · G + SNR0 · ∂M̄
    /// (G = ASNR/SNR0 the weighted mean, ∂M̄ the white lane) by more than 1e-4 of its norm, 10× the
    /// checks' bound (a key that moves N as well as the OTF, such as the temperature, keeps its
    /// gradient's norm mostly in ∂SNR0).
    fn assert_weighted_beside_n(g: &Gradient) {
        let norm = g.d_asnr.iter().map(|x| x * x).sum::<f64>().sqrt();
        let weighted = g.asnr / g.snr0;
        let apart = (0..g.d_asnr.len())
            .map(|i| (g.d_asnr[i] - g.d_snr0[i] * weighted - g.snr0 * g.d_mean_mtf[i]).abs())
            .fold(0.0, f64::max);
        println!("largest |∂ASNR − ∂SNR0 G − SNR0 ∂M̄| {apart:.3e} of the norm {norm:.3e}");
        assert!(apart > 1e-4 * norm, "{g:?}");
    }

    /// [`with_noise_spectrum`] keeping `source`'s own directory (its data files), the table
    /// written in a directory of its own and named by its absolute path.
    fn with_noise_spectrum_beside(source: &Source, name: &str) -> Source {
        let dir = std::env::temp_dir().join(format!("asnr-noise-gradient-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let table = dir.join("nps.csv");
        std::fs::write(&table, "frequency_cyc_per_mm,relative\n0,1\n30,1.4\n70,2.2\n130,3\n").unwrap();
        let text =
            source.text().replace("[camera]", &format!("[camera]\nnoise_spectrum = {:?}", table.display().to_string()));
        assert!(text.contains("noise_spectrum"), "{text}");
        Source::from_text(text, "a scene with a noise spectrum", source.dir())
    }

    /// The keys that scale the OTF's frequency or the pixel's sinc under a noise spectrum
    /// (docs/physics.md, "Gradients under a noise spectrum": by parts, the end term
    /// P(ν_N)|O(ν_N)|/n(ν_N) and the interior term of n′, n fixed in cycles/mm) against central
    /// differences of evaluations converged at 1e-10, within 10× the scene's tolerance (1e-6) of
    /// the gradient's norm: the F-number and focal length of the phase lens (its aperture lanes on
    /// the value's noise-weighted pass) and of the paper's chromatic lens (the defocus lane on the
    /// reference rule, weighted; with the pixel MTF in the integral form), with [`check_aperture`]'s
    /// step, and the pixel pitch with the pixel MTF in both forms, the phase lens on a 10 nm band
    /// there (the same per-frequency product rule, each 1e-10 reference six times cheaper than
    /// over the example's 50 nm).
    #[test]
    fn frequency_scale_keys_under_a_noise_spectrum_match_central_differences() {
        let binary2 = with_noise_spectrum(&example("phase-binary2.toml"), "scale-binary2");
        let keys = owned(&["lens.f_number", "lens.focal_length_mm"]);
        assert_weighted_beside_n(&gradient(&binary2, &[], &keys).unwrap());
        check_aperture(&binary2, &[]);
        let paper = with_noise_spectrum(&scene::read(None).unwrap(), "scale-paper");
        assert_weighted_beside_n(&gradient(&paper, &[], &keys).unwrap());
        check_aperture(&paper, &[]);
        check_aperture(&paper, &joined(&INTEGRAL_WITH_GLARE, &["camera.pixel_mtf=true"]));
        let pitch = ["camera.pixel_pitch_um", "exposure.time_ms"];
        let narrow = joined(&PIXEL_AND_READ_NOISE, &["spectrum.range_nm=10"]);
        check_against_differences(&binary2, &narrow, &pitch);
        let integral = [&PIXEL_AND_READ_NOISE[..], &["spectrum.range_nm=10", "options.form=\"integral\""]].concat();
        check_against_differences(&binary2, &owned(&integral), &pitch);
    }

    /// The spectral keys under a noise spectrum (their lanes with each frequency's weight divided
    /// by n(ν)): a Gaussian band's centre and range and a blackbody's temperature over it on the
    /// paper's lens, against Richardson-extrapolated central differences of evaluations converged
    /// at 1e-10 (relative steps 2h and h), and a line's wavelength (the frequency scale's term
    /// and the defocus lane, weighted) as [`check_line`] checks it, within 10× the tolerance 1e-6
    /// of the norm.
    #[test]
    fn spectral_keys_under_a_noise_spectrum_match_central_differences() {
        let paper = with_noise_spectrum(&scene::read(None).unwrap(), "spectral-paper");
        let blackbody = with_noise_spectrum(&paper_blackbody(), "spectral-blackbody");
        for (source, keys) in [
            (&paper, &["spectrum.center_nm", "spectrum.range_nm", "exposure.time_ms"][..]),
            (&blackbody, &["source.temperature_k", "exposure.time_ms"][..]),
        ] {
            assert_weighted_beside_n(&gradient(source, &[], &owned(&keys[..1])).unwrap());
            check_with_references(source, &[], keys, &|k, v| {
                let h = relative_step(k, v);
                richardson(source, &[], k, v, h)
            });
        }
        let line = owned(&LINE_803);
        assert_weighted_beside_n(&gradient(&paper, &line, &owned(&["spectrum.center_nm"])).unwrap());
        check_line(&paper, &line, &["exposure.time_ms"]);
        check_line(&paper, &joined(&LINE_803, &PIXEL_AND_READ_NOISE), &["exposure.time_ms"]);
    }

    /// A library lens's parameter bias under a noise spectrum (its lane on the reference rule
    /// with each frequency's weight divided by n(ν)), as `library_bias_matches_central_differences`
    /// checks it: Richardson of steps 0.1 and 0.05 nm of evaluations converged at 1e-10, the ASNR
    /// within 10× the tolerance 1e-6 of its gradient (N's, mostly) and the weighted mean
    /// G = ASNR/SNR0's own derivative (∂ASNR − ∂SNR0 G)/SNR0 within the same bound over SNR0
    /// (the white ∂M̄ is 1e-6 per nm away from it), beside the differences' own error. On a
    /// 10 nm band: the same lane on the same reference rule, weighted, in 6 spectral panels of
    /// 102 nodes against the example's 22 of 374 over 50 nm (`asnr evaluate --json` at 1e-10),
    /// each 1e-10 reference some six times cheaper.
    #[test]
    fn library_bias_under_a_noise_spectrum_matches_central_differences() {
        let source = with_noise_spectrum_beside(&example("library.toml"), "bias");
        let key = "lens.parameter_bias[0]";
        let overrides =
            owned(&["lens.library_interpolation=\"cubic\"", "lens.parameter_bias=[0.3]", "spectrum.range_nm=10"]);
        let g = gradient(&source, &overrides, &owned(&[key])).unwrap();
        let weighted = |v: f64| {
            let [asnr, _, snr0, _] = converged(&source, &overrides, key, v);
            [asnr, asnr / snr0]
        };
        let difference = |h: f64| -> [f64; 2] {
            let (up, down) = (weighted(0.3 + h), weighted(0.3 - h));
            std::array::from_fn(|q| (up[q] - down[q]) / (2.0 * h))
        };
        let (coarse, fine) = (difference(0.1), difference(0.05));
        let richardson: [f64; 2] = std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0);
        let weighted_mean = g.asnr / g.snr0;
        let ours = [g.d_asnr[0], (g.d_asnr[0] - g.d_snr0[0] * weighted_mean) / g.snr0];
        // the ASNR's bound carried to G = ASNR/SNR0 (its gradient's norm over SNR0)
        let bounds = [1e-5 * g.d_asnr[0].abs(), 1e-5 * g.d_asnr[0].abs() / g.snr0];
        for (q, name) in ["ASNR", "G"].iter().enumerate() {
            let noise = REFERENCE_TOLERANCE * [g.asnr, weighted_mean][q] / 0.05;
            let error = (ours[q] - richardson[q]).abs();
            println!(
                "{name}: gradient {:.9e}, Richardson {:.9e}, error {error:.1e} (bound {:.1e})",
                ours[q],
                richardson[q],
                bounds[q] + noise
            );
            assert!(error <= bounds[q] + noise, "{name}: {} vs {}", ours[q], richardson[q]);
        }
    }

    /// The decentred iris's keys under a noise spectrum (docs/physics.md, "Gradients under a
    /// noise spectrum", "Gradients: the iris"): the decentre's lanes on the exact 1-D engine's
    /// noise-weighted pass over azimuth, and the F-number's and the focal length's defocus lane
    /// there beside the frequency scale's term by parts (its `n′` term), each frequency's weight
    /// divided by n(ν), against central differences of evaluations converged at 1e-10 within 10×
    /// the scene's 1e-6 of the gradient's norm; a 10 nm band keeps the references cheap.
    #[test]
    fn iris_keys_under_a_noise_spectrum_match_central_differences() {
        let iris = with_noise_spectrum(&example("decentred-iris.toml"), "iris");
        let narrow = ["spectrum.range_nm=10", "lens.iris_decentre_y=-0.1"];
        let decentres = [("lens.iris_decentre_x", 1.0, DECENTRE), ("lens.iris_decentre_y", 1.0, DECENTRE)];
        check_at_scales(&iris, &narrow, &decentres);
        assert_weighted(&gradient(&iris, &owned(&narrow), &owned(&decentres.map(|k| k.0))).unwrap());
        check_aperture(&iris, &owned(&narrow));
        assert_weighted_beside_n(
            &gradient(&iris, &owned(&narrow), &owned(&["lens.f_number", "lens.focal_length_mm"])).unwrap(),
        );
    }

    /// Off axis under a noise spectrum, the paper's lens at 3° (its lateral colour on the exact
    /// 1-D engine): the field angle's and the decentre's lanes on the weighted pass over azimuth,
    /// and the F-number's and focal length's defocus and image shifts' lanes, each weight divided
    /// by n(ν), against central differences of evaluations converged at 1e-10 within 10× the
    /// scene's 1e-6 of the gradient's norm; a 10 nm band.
    #[test]
    fn lateral_colour_keys_under_a_noise_spectrum_match_central_differences() {
        let paper = with_noise_spectrum(&scene::read(None).unwrap(), "lateral-colour");
        let off_axis = ["spectrum.range_nm=10", "field.x_deg=3"];
        check_at_scales(&paper, &off_axis, &[("field.x_deg", 1.0, DEGREE), ("lens.iris_decentre_x", 1.0, DECENTRE)]);
        check_aperture(&paper, &owned(&off_axis));
    }

    /// The design wavelength through the decentred iris (docs/physics.md, "Gradients: the design
    /// wavelength through an iris": on the exact 1-D engine each node's defocus W020 r² and the
    /// iris's tilt W020 (2d/NA) move with W020, beside the image shifts' scale off axis), white
    /// and under a noise spectrum (each frequency's weight divided by n(ν)), on axis and off axis
    /// at 3°, against central differences of evaluations converged at 1e-10,
    /// Richardson-extrapolated from the steps 2h and h, h = [`LINE_STEP_NM`], within 10× the
    /// scene's 1e-6 of the gradient's norm; a 10 nm band keeps the references cheap.
    #[test]
    fn design_wavelength_through_an_iris_matches_central_differences() {
        let keys = ["lens.design_wavelength_nm"];
        let check = |source: &Source, overrides: &[String]| {
            check_with_references(source, overrides, &keys, &|k, v| richardson(source, overrides, k, v, LINE_STEP_NM));
        };
        let iris = example("decentred-iris.toml");
        let narrow = owned(&["spectrum.range_nm=10"]);
        check(&iris, &narrow);
        check(&iris, &joined(&["spectrum.range_nm=10"], &["field.x_deg=3"]));
        let shaped = with_noise_spectrum(&iris, "design-iris");
        assert_weighted(&gradient(&shaped, &narrow, &owned(&keys)).unwrap());
        check(&shaped, &narrow);
    }

    /// The Seidel keys at zero under a noise spectrum (docs/physics.md, "Gradients under a noise
    /// spectrum", "Gradients: Seidel terms at zero"): the overlap engine run again with the terms
    /// at zero, its lanes on the value's noise-weighted rules (each ∂|O| divided by n(ν), the
    /// frequency rule cut at the table's rows): on axis spherical aberration's and field
    /// curvature's along one azimuth, astigmatism half field curvature's (exactly); off axis at
    /// (2°, 1°) the term's lane over azimuth (coma, not 0 there). Against [`check_seidel_on`]'s
    /// Richardson-extrapolated central differences of evaluations converged at 1e-10 within 10×
    /// the tolerance 1e-6 of the norm, on 10 nm and 4 nm bands.
    #[test]
    fn seidel_keys_at_zero_under_a_noise_spectrum_match_central_differences() {
        let source = with_noise_spectrum(&scene::read(None).unwrap(), "seidel-zero");
        let keys = ["lens.spherical_um", "lens.field_curvature_um"];
        let g = check_seidel_on(&source, &["spectrum.range_nm=10"], &keys, 1e-6, 1e-3);
        assert_weighted(&g);
        // W222 x² = W222 ρ²/2 + W222 ρ² cos 2φ/2: half field curvature's, weighted as it is
        let all = ["lens.astigmatism_um", "lens.field_curvature_um"];
        let both = gradient(&source, &owned(&["spectrum.range_nm=10"]), &owned(&all)).unwrap();
        assert_eq!(both.d_asnr[0], 0.5 * both.d_asnr[1]);
        let off_axis = ["spectrum.range_nm=4", "field.x_deg=2", "field.y_deg=1"];
        let g = check_seidel_on(&source, &off_axis, &["lens.coma_um"], 1e-6, 1e-3);
        assert_weighted(&g);
    }

    /// The F-number and focal length of the chromatic lens with Seidel terms on axis under a
    /// noise spectrum (docs/physics.md, "Gradients under a noise spectrum": the frequency scale's
    /// term by parts and the defocus lane D̃_K on the value's noise-weighted rules over azimuth on
    /// the overlap engine, each ∂|O| divided by n(ν); the white ∂M̄ on the overlap pass as without
    /// it): coma 0.3 µm, spherical aberration 0.2 µm with the pixel MTF, and coma 0.3 µm at 3°
    /// (the defocus and image shifts' lanes over azimuth), on a 4 nm band,
    /// against Richardson central differences of evaluations converged at 1e-10 (steps 1e-4 and
    /// 5e-5 relative, [`NARROW_APERTURE_STEP`]) within 10× the tolerance 1e-6 of the norm; the
    /// weight moves ∂ASNR apart from the white lanes' ([`assert_weighted_beside_n`]).
    #[test]
    fn f_number_with_seidel_terms_under_a_noise_spectrum_matches_central_differences() {
        let paper = with_noise_spectrum(&scene::read(None).unwrap(), "seidel-aperture");
        let keys = ["lens.f_number", "lens.focal_length_mm"];
        let cases = [
            &["lens.coma_um=0.3"][..],
            &["lens.spherical_um=0.2", "camera.pixel_mtf=true"],
            // off axis: the defocus and image shifts' lanes over azimuth, weighted
            &["lens.coma_um=0.3", "field.x_deg=3"],
        ];
        for more in cases {
            let base = joined(&["spectrum.range_nm=4"], more);
            // the overlap engine at the tolerance 1e-6 (not options.fft_tolerance's 1e-4)
            let mut set = base.clone();
            set.push("options.tolerance=1e-6".to_owned());
            let g = gradient(&paper, &set, &owned(&keys)).unwrap();
            assert_weighted_beside_n(&g);
            let references: Vec<[f64; 4]> = g
                .keys
                .iter()
                .zip(&g.values)
                .map(|(k, &v)| richardson(&paper, &base, k, v, NARROW_APERTURE_STEP * v.abs()))
                .collect();
            within_of_the_norm(&g, &references, 1e-5, &format!("{more:?}"));
        }
    }

    /// A top-hat's centre and range under a noise spectrum (docs/physics.md, "Gradients under a
    /// noise spectrum", "Gradients: a top-hat's edges": the edges' single-wavelength OTFs with each
    /// frequency's weight divided by n(ν), against the weighted mean on the same rule): the
    /// paper's lens on axis and at 5° (the lateral colour: over directions), on a 10 nm band,
    /// against central differences of evaluations converged at 1e-10 with the step
    /// (3 · 1e-10)^{1/3} × the range, within 10× the scene's 1e-6 of the gradient's norm.
    #[test]
    fn top_hat_edges_under_a_noise_spectrum_match_central_differences() {
        let paper = with_noise_spectrum(&scene::read(None).unwrap(), "top-hat");
        let keys = ["spectrum.center_nm", "spectrum.range_nm"];
        let step = |_: &str, _: f64| (3.0 * REFERENCE_TOLERANCE).cbrt() * 10.0;
        for more in [&[][..], &["field.x_deg=5"]] {
            let overrides = joined(&["spectrum.shape=\"tophat\"", "spectrum.range_nm=10"], more);
            assert_weighted_beside_n(&gradient(&paper, &overrides, &owned(&keys)).unwrap());
            check_with_steps(&paper, &overrides, &keys, &step);
        }
    }

    /// A line's wavelength on the harmonic lens's several orders under a noise spectrum
    /// (docs/physics.md, "Gradients under a noise spectrum": the order lane, each order moving by
    /// its own defocus and efficiency rates, with each frequency's weight divided by n(ν), beside
    /// the frequency scale's term by parts) at 803 nm, against [`check_line`]'s
    /// Richardson-extrapolated central differences of evaluations converged at 1e-10, within 10×
    /// the scene's 1e-6 of the gradient's norm.
    #[test]
    fn a_line_on_several_orders_under_a_noise_spectrum_matches_central_differences() {
        let harmonic = with_noise_spectrum_beside(&example("harmonic.toml"), "harmonic-line");
        let line = owned(&LINE_803);
        assert_weighted_beside_n(&gradient(&harmonic, &line, &owned(&["spectrum.center_nm"])).unwrap());
        check_line(&harmonic, &line, &[]);
    }

    /// A line's wavelength on the harmonic lens's several orders off axis under a noise spectrum
    /// (docs/physics.md, "Gradients: several orders under a line off axis", "Gradients under a
    /// noise spectrum"): the line engine's lanes over azimuth with each frequency's weight
    /// divided by n(ν), beside the frequency scale's term by parts with 1/n's slope, at 803 nm
    /// and 3°, with the read noise; against Richardson-extrapolated central differences of
    /// evaluations converged at 1e-10 (steps 2h and h, h = [`LINE_STEP_NM`]) within 10× the
    /// scene's 1e-6 of the gradient's norm.
    #[test]
    fn a_line_on_several_orders_off_axis_under_a_noise_spectrum_matches_central_differences() {
        let harmonic = with_noise_spectrum(&example("harmonic.toml"), "line-orders-off-axis");
        let overrides = joined(&LINE_803, &["field.x_deg=3", "camera.read_noise_e=2"]);
        let keys = ["spectrum.center_nm", "exposure.time_ms"];
        assert_weighted(&gradient(&harmonic, &overrides, &owned(&keys[..1])).unwrap());
        check_with_references(&harmonic, &overrides, &keys, &|k, v| {
            let h = if k == keys[1] { relative_step(k, v) } else { LINE_STEP_NM };
            richardson(&harmonic, &overrides, k, v, h)
        });
    }

    /// The design wavelength under a line off axis (docs/physics.md, "Gradients: the design
    /// wavelength off axis"): the chromatic lens's one order at the line's wavelength carries
    /// its lateral colour as a phase of the whole OTF, so the derivative is the on-axis one;
    /// white and under a noise spectrum at 803 nm and 3°, against central differences of
    /// evaluations converged at 1e-10, Richardson-extrapolated from the steps 2h and h,
    /// h = [`LINE_STEP_NM`], within 10× the scene's 1e-6 of the gradient's norm.
    #[test]
    fn design_wavelength_under_a_line_off_axis_matches_central_differences() {
        let keys = ["lens.design_wavelength_nm"];
        let paper = scene::read(None).unwrap();
        let shaped = with_noise_spectrum(&paper, "design-line");
        let overrides = joined(&LINE_803, &["field.x_deg=3", "camera.read_noise_e=2"]);
        for source in [&paper, &shaped] {
            check_with_references(source, &overrides, &keys, &|k, v| {
                richardson(source, &overrides, k, v, LINE_STEP_NM)
            });
        }
    }
}
