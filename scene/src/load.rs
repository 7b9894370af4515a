//! Scene files: TOML → raw serde structs → validated [`metric::Scene`].
//!
//! Architecture invariant: this is the only place that reads scene files; every value is checked
//! here with a message naming the file (or the `--set` that gave it), the dotted key, the value
//! and what is accepted, before any library type is built.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, anyhow, bail};
use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, MetricForm, Options, Scene};
use radiometry::{Blackbody, Gaussian, Line, Spectrum, TopHat};
use serde::Deserialize;
use serde::de::{self, Visitor};

use crate::tables::{FREQUENCY, read_pairs, read_table};

/// The paper's theory scene, embedded in the binary (`examples/paper-theory.toml`).
pub const PAPER_SCENE: &str = include_str!("../../examples/paper-theory.toml");

/// A scene value that is a number or the path of a two-column CSV table.
#[derive(Clone, Debug, PartialEq)]
enum NumberOrFile {
    Number(f64),
    File(String),
}

impl<'de> Deserialize<'de> for NumberOrFile {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = NumberOrFile;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or the path of a CSV file (wavelength_nm, value)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<NumberOrFile, E> {
                Ok(NumberOrFile::Number(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<NumberOrFile, E> {
                Ok(NumberOrFile::Number(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<NumberOrFile, E> {
                Ok(NumberOrFile::Number(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<NumberOrFile, E> {
                Ok(NumberOrFile::File(v.to_owned()))
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    #[serde(default)]
    title: Option<String>,
    lens: RawLens,
    source: RawSource,
    #[serde(default)]
    spectrum: Option<RawSpectrum>,
    camera: RawCamera,
    exposure: RawExposure,
    #[serde(default)]
    options: Option<RawOptions>,
    #[serde(default)]
    field: Option<RawField>,
    #[serde(default)]
    fields: Option<Vec<RawFieldPoint>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFieldPoint {
    x_deg: Option<f64>,
    y_deg: Option<f64>,
    weight: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawField {
    x_deg: Option<f64>,
    y_deg: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLens {
    model: Option<String>,
    f_number: f64,
    focal_length_mm: f64,
    design_wavelength_nm: f64,
    efficiency: NumberOrFile,
    transmission: Option<NumberOrFile>,
    iris_decentre_x: Option<f64>,
    iris_decentre_y: Option<f64>,
    obscuration: Option<f64>,
    sector_deg: Option<[f64; 2]>,
    spherical_um: Option<f64>,
    coma_um: Option<f64>,
    astigmatism_um: Option<f64>,
    field_curvature_um: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSource {
    kind: String,
    radiance_w_m2_sr_nm: Option<f64>,
    temperature_k: Option<f64>,
    scale: Option<f64>,
    csv: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpectrum {
    shape: String,
    center_nm: Option<f64>,
    range_nm: Option<f64>,
    peak: Option<f64>,
    csv: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    pixel_pitch_um: f64,
    #[serde(default)]
    pixel_mtf: bool,
    quantum_efficiency: NumberOrFile,
    read_noise_e: Option<f64>,
    dark_current_e_per_s: Option<f64>,
    full_well_e: Option<f64>,
    gain_dn_per_e: Option<f64>,
    adc_bits: Option<u32>,
    noise_spectrum: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExposure {
    time_ms: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOptions {
    form: Option<String>,
    fraunhofer_threshold_mm: Option<f64>,
    fraunhofer_max_fraction: Option<f64>,
    pupil_samples: Option<u32>,
    glare: Option<String>,
    tolerance: Option<f64>,
}

/// Where a scene came from, and which keys `--set` overrode: every message names its origin.
struct Origins {
    file: String,
    dir: PathBuf,
    overrides: BTreeMap<String, String>,
}

impl Origins {
    /// The origin of `key`: the `--set` that gave it (or a table above it), else the file.
    fn of(&self, key: &str) -> String {
        for (k, arg) in &self.overrides {
            if key == k || key.starts_with(&format!("{k}.")) || k.starts_with(&format!("{key}.")) {
                return format!("{} (--set {arg})", self.file);
            }
        }
        self.file.clone()
    }

    fn bad(&self, key: &str, value: impl fmt::Display, expected: &str) -> anyhow::Error {
        anyhow!("{}: {key} = {value}: expected {expected}", self.of(key))
    }

    fn number(&self, key: &str, value: f64, ok: bool, expected: &str) -> Result<f64> {
        if value.is_finite() && ok { Ok(value) } else { Err(self.bad(key, value, expected)) }
    }

    fn require<T>(&self, key: &str, value: Option<T>, expected: &str) -> Result<T> {
        value.ok_or_else(|| anyhow!("{}: {key} is missing: expected {expected}", self.of(key)))
    }

    fn forbid<T>(&self, key: &str, value: &Option<T>, context: &str) -> Result<()> {
        if value.is_some() {
            bail!("{}: {key} does not apply to {context}", self.of(key));
        }
        Ok(())
    }

    fn path(&self, file: &str) -> PathBuf {
        let p = Path::new(file);
        if p.is_absolute() { p.to_path_buf() } else { self.dir.join(p) }
    }

    /// The CSV table `file` given for `key`, values in `[0, hi]`.
    fn table(&self, key: &str, file: &str, hi: f64, what: &str) -> Result<radiometry::Sampled> {
        read_table(&self.path(file), 0.0, hi, what).with_context(|| format!("{}: {key} = \"{file}\"", self.of(key)))
    }

    /// A fraction in `[0, 1]`, constant or tabulated.
    fn curve(&self, key: &str, value: &NumberOrFile, what: &str) -> Result<Curve> {
        Ok(match value {
            NumberOrFile::Number(v) => {
                Curve::Constant(self.number(key, *v, (0.0..=1.0).contains(v), "a fraction in [0, 1] or a CSV path")?)
            }
            NumberOrFile::File(f) => Curve::Table(self.table(key, f, 1.0, what)?),
        })
    }
}

/// A scene file's text, read once and built into scenes with different overrides (sweeps):
/// its TOML is parsed once, on first use, and each scene starts from a copy of that table.
#[derive(Clone, Debug)]
pub struct Source {
    text: String,
    label: String,
    dir: PathBuf,
    parsed: std::sync::OnceLock<std::result::Result<toml::Table, String>>,
}

impl Source {
    /// How messages name this scene.
    pub fn label(&self) -> &str {
        &self.label
    }
}

/// Reads a scene file (None = the embedded paper scene).
pub fn read(file: Option<&Path>) -> Result<Source> {
    let (text, label, dir) = match file {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read the scene file {}", path.display()))?;
            let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
            (text, path.display().to_string(), dir)
        }
        None => (PAPER_SCENE.to_owned(), "embedded paper scene".to_owned(), PathBuf::from(".")),
    };
    Ok(Source { text, label, dir, parsed: std::sync::OnceLock::new() })
}

/// Reads and validates a scene: `file` (None = the embedded paper scene) with `--set` overrides.
pub fn load(file: Option<&Path>, overrides: &[String]) -> Result<Scene> {
    build_from(&read(file)?, overrides)
}

/// Builds and validates the scene of `source` with `--set` overrides.
pub fn build_from(source: &Source, overrides: &[String]) -> Result<Scene> {
    let (text, label, dir) = (&source.text, source.label.clone(), source.dir.clone());
    if text.trim().is_empty() {
        bail!("{label}: the scene file is empty: expected TOML tables [lens], [source], [camera], [exposure]");
    }
    let parsed = source.parsed.get_or_init(|| toml::from_str(text).map_err(|e| e.to_string().trim_end().to_owned()));
    let mut table = parsed.clone().map_err(|e| anyhow!("{label}: malformed TOML: {e}"))?;
    let mut origins = Origins { file: label, dir, overrides: BTreeMap::new() };
    for arg in overrides {
        let (key, value) = apply_override(&mut table, arg)?;
        origins.overrides.insert(key, value);
    }
    let raw: RawScene = serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
        let key = e.path().to_string();
        // toml appends "in `key`" to its messages; the key is already named in front
        let inner = e.inner().to_string();
        let inner = inner.split("\nin `").next().unwrap_or_default().trim_end().to_owned();
        anyhow!("{}: {key}: {inner}", origins.of(&key))
    })?;
    let scene = build(&raw, &origins)?;
    Ok(match &raw.title {
        Some(title) => scene.with_title(title.clone()),
        None => scene,
    })
}

/// Applies one `--set key=value` to the TOML table. The value is read as TOML (number, boolean,
/// quoted string), or as a bare string if it is not valid TOML (`--set spectrum.shape=tophat`).
fn apply_override(table: &mut toml::Table, arg: &str) -> Result<(String, String)> {
    let Some((key, value)) = arg.split_once('=') else {
        bail!("--set {arg}: expected key=value with a dotted key, e.g. --set lens.f_number=2.5");
    };
    let key = key.trim();
    let parts: Vec<&str> = key.split('.').collect();
    if key.is_empty() || parts.iter().any(|p| p.is_empty()) {
        bail!("--set {arg}: `{key}` is not a dotted key, e.g. lens.f_number");
    }
    let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.trim().to_owned()));
    let mut cursor = table;
    for (i, part) in parts.iter().enumerate() {
        if i + 1 == parts.len() {
            cursor.insert((*part).to_owned(), parsed.clone());
        } else {
            let entry = cursor.entry((*part).to_owned()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
            cursor = entry
                .as_table_mut()
                .ok_or_else(|| anyhow!("--set {arg}: `{}` is a value, not a table", parts[..=i].join(".")))?;
        }
    }
    Ok((key.to_owned(), arg.to_owned()))
}

fn build(raw: &RawScene, o: &Origins) -> Result<Scene> {
    // [lens]
    let l = &raw.lens;
    match l.model.as_deref().unwrap_or("chromatic") {
        "chromatic" => {}
        other => {
            return Err(o.bad(
                "lens.model",
                format!("\"{other}\""),
                "\"chromatic\" (a chromatic metalens or diffractive lens)",
            ));
        }
    }
    let f_number = o.number("lens.f_number", l.f_number, l.f_number >= 0.5, "a number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
    let f0 = o.number("lens.focal_length_mm", l.focal_length_mm, l.focal_length_mm > 0.0, "a length > 0 mm")?;
    let l0 = o.number(
        "lens.design_wavelength_nm",
        l.design_wavelength_nm,
        l.design_wavelength_nm > 0.0,
        "a wavelength > 0 nm",
    )?;
    let efficiency = o.curve("lens.efficiency", &l.efficiency, "efficiency")?;
    let transmission = match &l.transmission {
        Some(t) => o.curve("lens.transmission", t, "transmission")?,
        None => efficiency.clone(),
    };
    let mut lens = ChromaticMetalens::new(f_number, f0 * 1e-3, l0 * 1e-9, efficiency, transmission)
        .map_err(|e| anyhow!("{}: [lens]: {e}", o.of("lens")))?;
    if let Some(aperture) = aperture(l, o)? {
        lens = lens.with_aperture(aperture);
    }
    let seidel = |key: &str, v: Option<f64>| -> Result<f64> {
        let v = v.unwrap_or(0.0);
        Ok(o.number(key, v, v.abs() <= 1e3, "a wavefront coefficient in µm, |W| ≤ 1000 µm")? * 1e-6)
    };
    let terms = [
        seidel("lens.spherical_um", l.spherical_um)?,
        seidel("lens.coma_um", l.coma_um)?,
        seidel("lens.astigmatism_um", l.astigmatism_um)?,
        seidel("lens.field_curvature_um", l.field_curvature_um)?,
    ];
    if terms.iter().any(|&t| t != 0.0) {
        lens = lens.with_seidel(terms[0], terms[1], terms[2], terms[3]);
    }

    // [source] × [spectrum]
    let radiance = source(&raw.source, o)?;
    let filter = match &raw.spectrum {
        Some(s) => filter(s, o)?,
        None => None,
    };
    let radiance = match filter {
        Some(f) => Spectrum::product(vec![radiance, f]),
        None => radiance,
    };

    // [camera]
    let c = &raw.camera;
    let pitch = o.number("camera.pixel_pitch_um", c.pixel_pitch_um, c.pixel_pitch_um > 0.0, "a length > 0 µm")?;
    let qe = match o.curve("camera.quantum_efficiency", &c.quantum_efficiency, "quantum efficiency")? {
        Curve::Constant(v) => Spectrum::Constant(v),
        Curve::Table(t) => Spectrum::Sampled(t),
    };
    let mut camera =
        Camera::new(pitch * 1e-6, qe, c.pixel_mtf).map_err(|e| anyhow!("{}: [camera]: {e}", o.of("camera")))?;
    if let Some(sensor) = sensor(c, o)? {
        camera = camera.with_sensor(sensor);
    }
    if let Some(file) = &c.noise_spectrum {
        let key = "camera.noise_spectrum";
        let (cyc_per_mm, relative) = read_pairs(&o.path(file), &FREQUENCY, 0.0, f64::MAX, "relative noise amplitude")
            .with_context(|| format!("{}: {key} = \"{file}\"", o.of(key)))?;
        let shape = optics::NoiseShape::new(cyc_per_mm.iter().map(|f| f * 1e3).collect(), relative)
            .map_err(|e| anyhow!("{}: {key} = \"{file}\": {e}", o.of(key)))?;
        camera = camera.with_noise_spectrum(shape);
    }

    // [exposure], [options]
    let t = o.number("exposure.time_ms", raw.exposure.time_ms, raw.exposure.time_ms > 0.0, "a time > 0 ms")?;
    let mut options = Options::default();
    if let Some(opt) = &raw.options {
        if let Some(form) = &opt.form {
            options.form = match form.as_str() {
                "mean" => MetricForm::Mean,
                "integral" => MetricForm::Integral,
                other => return Err(o.bad("options.form", format!("\"{other}\""), "\"mean\" or \"integral\"")),
            };
        }
        if let Some(v) = opt.fraunhofer_threshold_mm {
            options.fraunhofer_threshold =
                o.number("options.fraunhofer_threshold_mm", v, v > 0.0, "a length > 0 mm")? * 1e-3;
        }
        if let Some(g) = &opt.glare {
            options.glare = match g.as_str() {
                "first_order" => metric::GlareMode::FirstOrder,
                "included" => metric::GlareMode::Included,
                other => {
                    return Err(o.bad("options.glare", format!("\"{other}\""), "\"first_order\" or \"included\""));
                }
            };
        }
        if let Some(v) = opt.pupil_samples {
            options.pupil_samples = o.number(
                "options.pupil_samples",
                f64::from(v),
                (16..=4096).contains(&v),
                "a whole number of pupil samples from 16 to 4096",
            )? as usize;
        }
        if let Some(v) = opt.tolerance {
            options.tolerance = o.number(
                "options.tolerance",
                v,
                (1e-14..=0.1).contains(&v),
                "a relative error of the mean MTF from 1e-14 to 0.1 (default 1e-6)",
            )?;
        }
        if let Some(v) = opt.fraunhofer_max_fraction {
            options.fraunhofer_max_fraction =
                o.number("options.fraunhofer_max_fraction", v, (0.0..=1.0).contains(&v), "a fraction in [0, 1]")?;
        }
    }
    let scene =
        Scene::new(Arc::new(lens), radiance, camera, t * 1e-3, options).map_err(|e| anyhow!("{}: {e}", o.file))?;
    let angle = |key: &str, v: Option<f64>| -> Result<f64> {
        let v = v.unwrap_or(0.0);
        Ok(o.number(key, v, v.abs() < 90.0, "an angle in degrees, within ±90")?.to_radians())
    };
    match (&raw.field, &raw.fields) {
        (Some(_), Some(_)) => bail!("{}: [field] and [[fields]] both given: use one point or a weighted list", o.file),
        (Some(f), None) => {
            let field = optics::Field::new(angle("field.x_deg", f.x_deg)?, angle("field.y_deg", f.y_deg)?);
            scene.at_field(field).map_err(|e| anyhow!("{}: {e}", o.of("field")))
        }
        (None, Some(list)) => {
            if list.is_empty() {
                bail!("{}: [[fields]] is empty: expected at least one field point", o.of("fields"));
            }
            let mut points = Vec::new();
            for (i, f) in list.iter().enumerate() {
                let x = angle(&format!("fields[{i}].x_deg"), f.x_deg)?;
                let y = angle(&format!("fields[{i}].y_deg"), f.y_deg)?;
                let w = f.weight.unwrap_or(1.0);
                let w = o.number(&format!("fields[{i}].weight"), w, w >= 0.0, "a relative weight ≥ 0")?;
                points.push((optics::Field::new(x, y), w));
            }
            scene.over_fields(points).map_err(|e| anyhow!("{}: [[fields]]: {e}", o.of("fields")))
        }
        (None, None) => Ok(scene),
    }
}

/// The sensor noise model, when the scene gives any of its keys (otherwise shot-noise limited).
fn sensor(c: &RawCamera, o: &Origins) -> Result<Option<noise::Sensor>> {
    if c.read_noise_e.is_none()
        && c.dark_current_e_per_s.is_none()
        && c.full_well_e.is_none()
        && c.gain_dn_per_e.is_none()
        && c.adc_bits.is_none()
    {
        return Ok(None);
    }
    let read = c.read_noise_e.unwrap_or(0.0);
    let read = o.number("camera.read_noise_e", read, read >= 0.0, "a read noise ≥ 0 e⁻ rms")?;
    let dark = c.dark_current_e_per_s.unwrap_or(0.0);
    let dark = o.number("camera.dark_current_e_per_s", dark, dark >= 0.0, "a dark current ≥ 0 e⁻/s")?;
    let well = match c.full_well_e {
        Some(w) => o.number("camera.full_well_e", w, w > 0.0, "a full-well capacity > 0 e⁻")?,
        None => f64::INFINITY,
    };
    let sensor = match (c.gain_dn_per_e, c.adc_bits) {
        (Some(k), Some(bits)) => {
            let k = o.number("camera.gain_dn_per_e", k, k > 0.0, "a conversion gain > 0 DN/e⁻")?;
            if !(1..=32).contains(&bits) {
                return Err(o.bad("camera.adc_bits", bits, "a whole number of bits from 1 to 32"));
            }
            noise::Sensor::new(read, dark, well, k, bits)
        }
        (None, None) => noise::Sensor::without_adc(read, dark, well),
        (Some(_), None) => bail!("{}: camera.gain_dn_per_e needs camera.adc_bits too", o.of("camera.adc_bits")),
        (None, Some(_)) => bail!("{}: camera.adc_bits needs camera.gain_dn_per_e too", o.of("camera.gain_dn_per_e")),
    };
    sensor.map(Some).map_err(|e| anyhow!("{}: [camera]: {e}", o.of("camera")))
}

/// The iris, when the scene makes it other than the centred full circle.
fn aperture(l: &RawLens, o: &Origins) -> Result<Option<optics::fft::Aperture>> {
    let fraction = |key: &str, v: Option<f64>, lo: f64, hi: f64, expected: &str| -> Result<Option<f64>> {
        v.map(|v| o.number(key, v, v >= lo && v < hi, expected)).transpose()
    };
    let dx =
        fraction("lens.iris_decentre_x", l.iris_decentre_x, -1.0, 1.0, "a fraction of the aperture radius in (−1, 1)")?;
    let dy =
        fraction("lens.iris_decentre_y", l.iris_decentre_y, -1.0, 1.0, "a fraction of the aperture radius in (−1, 1)")?;
    let obscuration = fraction("lens.obscuration", l.obscuration, 0.0, 1.0, "a ratio of radii in [0, 1)")?;
    let sector = match l.sector_deg {
        Some([a, b]) => {
            let key = "lens.sector_deg";
            if !(a.is_finite() && b.is_finite() && b > a && b - a <= 360.0) {
                return Err(o.bad(
                    key,
                    format!("[{a}, {b}]"),
                    "[start, end] in degrees with start < end ≤ start + 360",
                ));
            }
            Some((a.to_radians(), b.to_radians()))
        }
        None => None,
    };
    if dx.is_none() && dy.is_none() && obscuration.is_none() && sector.is_none() {
        return Ok(None);
    }
    let shape = optics::fft::Aperture::disc(obscuration.unwrap_or(0.0), sector)
        .map_err(|e| anyhow!("{}: lens.obscuration / lens.sector_deg: {e}", o.of("lens")))?;
    let shape = shape
        .decentred(dx.unwrap_or(0.0), dy.unwrap_or(0.0))
        .map_err(|e| anyhow!("{}: lens.iris_decentre_x / _y: {e}", o.of("lens")))?;
    Ok(Some(shape))
}

fn source(s: &RawSource, o: &Origins) -> Result<Spectrum> {
    let kind = s.kind.as_str();
    let ctx = format!("source.kind = \"{kind}\"");
    match kind {
        "flat" => {
            o.forbid("source.temperature_k", &s.temperature_k, &ctx)?;
            o.forbid("source.scale", &s.scale, &ctx)?;
            o.forbid("source.csv", &s.csv, &ctx)?;
            let key = "source.radiance_w_m2_sr_nm";
            let l = o.require(key, s.radiance_w_m2_sr_nm, "a spectral radiance > 0 W/(m² sr nm)")?;
            // W/(m² sr nm) → W/(m² sr m)
            Ok(Spectrum::Constant(o.number(key, l, l > 0.0, "a spectral radiance > 0 W/(m² sr nm)")? * 1e9))
        }
        "blackbody" => {
            o.forbid("source.radiance_w_m2_sr_nm", &s.radiance_w_m2_sr_nm, &ctx)?;
            o.forbid("source.csv", &s.csv, &ctx)?;
            let key = "source.temperature_k";
            let t = o.require(key, s.temperature_k, "a temperature > 0 K")?;
            let t = o.number(key, t, t > 0.0, "a temperature > 0 K")?;
            let scale = s.scale.unwrap_or(1.0);
            let scale = o.number("source.scale", scale, scale > 0.0, "a factor > 0 on the Planck radiance")?;
            let source = Blackbody::new(t).map_err(|e| anyhow!("{}: {key}: {e}", o.of(key)))?;
            Ok(Spectrum::Blackbody { source, scale })
        }
        "table" => {
            o.forbid("source.radiance_w_m2_sr_nm", &s.radiance_w_m2_sr_nm, &ctx)?;
            o.forbid("source.temperature_k", &s.temperature_k, &ctx)?;
            o.forbid("source.scale", &s.scale, &ctx)?;
            let key = "source.csv";
            let f = o.require(key, s.csv.as_ref(), "the path of a CSV file: wavelength_nm, W/(m² sr nm)")?;
            let table = o.table(key, f, f64::INFINITY, "spectral radiance")?;
            Ok(Spectrum::Sampled(table.scaled(1e9)))
        }
        other => Err(o.bad("source.kind", format!("\"{other}\""), "\"flat\", \"blackbody\" or \"table\"")),
    }
}

fn filter(s: &RawSpectrum, o: &Origins) -> Result<Option<Spectrum>> {
    let shape = s.shape.as_str();
    let ctx = format!("spectrum.shape = \"{shape}\"");
    let band = |o: &Origins| -> Result<(f64, f64, f64)> {
        o.forbid("spectrum.csv", &s.csv, &ctx)?;
        let c = o.require("spectrum.center_nm", s.center_nm, "a wavelength > 0 nm")?;
        let c = o.number("spectrum.center_nm", c, c > 0.0, "a wavelength > 0 nm")?;
        let r = o.require("spectrum.range_nm", s.range_nm, "a width > 0 nm")?;
        let r = o.number("spectrum.range_nm", r, r > 0.0, "a width > 0 nm")?;
        let p = s.peak.unwrap_or(1.0);
        let p = o.number("spectrum.peak", p, p > 0.0 && p <= 1.0, "a transmission in (0, 1]")?;
        Ok((c * 1e-9, r * 1e-9, p))
    };
    Ok(match shape {
        "gaussian" => {
            let (c, r, p) = band(o)?;
            Some(Spectrum::Gaussian(
                Gaussian::from_range(c, r, p).map_err(|e| anyhow!("{}: [spectrum]: {e}", o.of("spectrum")))?,
            ))
        }
        "tophat" => {
            let (c, r, p) = band(o)?;
            if c - 0.5 * r <= 0.0 {
                return Err(o.bad(
                    "spectrum.range_nm",
                    r * 1e9,
                    "a full width under twice spectrum.center_nm (the band must stay at λ > 0)",
                ));
            }
            Some(Spectrum::TopHat(
                TopHat::new(c - 0.5 * r, c + 0.5 * r, p)
                    .map_err(|e| anyhow!("{}: [spectrum]: {e}", o.of("spectrum")))?,
            ))
        }
        "line" => {
            // one wavelength for the optics; range_nm is the equivalent width that sets the
            // photon count (∫T dλ = peak × range, as for the other shapes)
            o.forbid("spectrum.csv", &s.csv, &ctx)?;
            let c = o.require("spectrum.center_nm", s.center_nm, "the line's wavelength > 0 nm")?;
            let c = o.number("spectrum.center_nm", c, c > 0.0, "the line's wavelength > 0 nm")?;
            let width = "the equivalent width > 0 nm of the band (∫T dλ / T_peak; it sets the photon count)";
            let r = o.require("spectrum.range_nm", s.range_nm, width)?;
            let r = o.number("spectrum.range_nm", r, r > 0.0, width)?;
            if r >= 2.0 * c {
                return Err(o.bad(
                    "spectrum.range_nm",
                    r,
                    "an equivalent width under twice spectrum.center_nm (the band must stay at λ > 0)",
                ));
            }
            let p = s.peak.unwrap_or(1.0);
            let p = o.number("spectrum.peak", p, p > 0.0 && p <= 1.0, "a transmission in (0, 1]")?;
            Some(Spectrum::Line(
                Line::new(c * 1e-9, r * 1e-9, p).map_err(|e| anyhow!("{}: [spectrum]: {e}", o.of("spectrum")))?,
            ))
        }
        "table" => {
            for (k, v) in
                [("spectrum.center_nm", s.center_nm), ("spectrum.range_nm", s.range_nm), ("spectrum.peak", s.peak)]
            {
                o.forbid(k, &v, &ctx)?;
            }
            let f = o.require("spectrum.csv", s.csv.as_ref(), "the path of a CSV file: wavelength_nm, transmission")?;
            Some(Spectrum::Sampled(o.table("spectrum.csv", f, 1.0, "transmission")?))
        }
        "none" => {
            for (k, v) in
                [("spectrum.center_nm", s.center_nm), ("spectrum.range_nm", s.range_nm), ("spectrum.peak", s.peak)]
            {
                o.forbid(k, &v, &ctx)?;
            }
            o.forbid("spectrum.csv", &s.csv, &ctx)?;
            None
        }
        other => {
            return Err(o.bad(
                "spectrum.shape",
                format!("\"{other}\""),
                "\"gaussian\", \"tophat\", \"line\" (one wavelength), \"table\" or \"none\"",
            ));
        }
    })
}
