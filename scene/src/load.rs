//! Scene files: TOML → raw serde structs → validated [`metric::Scene`].
//!
//! Architecture invariant: this is the only place that reads scene files; every value is checked
//! here with a message naming the file (or the `--set` that gave it), the dotted key, the value
//! and what is accepted, before any library type is built.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use lenses::Curve;
use metric::{Camera, MetricForm, Options, Scene};
use radiometry::{Blackbody, Gaussian, Line, Spectrum, TopHat};
use serde::Deserialize;

use crate::error::{Error, Warning, num, quoted, shorten, shorten_quoted};
use crate::lens_table::RawLens;
use crate::origins::{
    EXPOSURE_PLAUSIBLE_MS, NumberOrFile, Origins, PIXEL_PITCH_PLAUSIBLE_UM, TableCache, number_prefix, rounded, unit_of,
};
use crate::tables::{FREQUENCY, read_pairs, read_text};

/// The paper's theory scene, embedded in the binary (`examples/paper-theory.toml`).
pub const PAPER_SCENE: &str = include_str!("../../examples/paper-theory.toml");

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    #[serde(default)]
    pub title: Option<String>,
    pub lens: RawLens,
    pub source: RawSource,
    #[serde(default)]
    pub spectrum: Option<RawSpectrum>,
    pub camera: RawCamera,
    pub exposure: RawExposure,
    #[serde(default)]
    pub options: Option<RawOptions>,
    #[serde(default)]
    pub field: Option<RawField>,
    #[serde(default)]
    pub fields: Option<Vec<RawFieldPoint>>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFieldPoint {
    pub x_deg: Option<f64>,
    pub y_deg: Option<f64>,
    pub weight: Option<f64>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawField {
    pub x_deg: Option<f64>,
    pub y_deg: Option<f64>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSource {
    pub kind: String,
    pub radiance_w_m2_sr_nm: Option<f64>,
    pub temperature_k: Option<f64>,
    pub scale: Option<f64>,
    pub csv: Option<String>,
    // kind = "radiance_meter" (SI eq. S1–S6)
    pub relative_spectrum_csv: Option<String>,
    pub power_nw: Option<f64>,
    pub fiber_core_diameter_um: Option<f64>,
    pub responsivity_csv: Option<String>,
    pub calibration_wavelength_nm: Option<f64>,
    pub relay_transmission: Option<f64>,
    pub relay_iris_mm: Option<f64>,
    pub relay_focal_length_mm: Option<f64>,
}

impl RawSource {
    /// Every key of `[source]` but `kind`, and whether it is given.
    fn given(&self) -> [(&'static str, bool); 12] {
        [
            ("radiance_w_m2_sr_nm", self.radiance_w_m2_sr_nm.is_some()),
            ("temperature_k", self.temperature_k.is_some()),
            ("scale", self.scale.is_some()),
            ("csv", self.csv.is_some()),
            ("relative_spectrum_csv", self.relative_spectrum_csv.is_some()),
            ("power_nw", self.power_nw.is_some()),
            ("fiber_core_diameter_um", self.fiber_core_diameter_um.is_some()),
            ("responsivity_csv", self.responsivity_csv.is_some()),
            ("calibration_wavelength_nm", self.calibration_wavelength_nm.is_some()),
            ("relay_transmission", self.relay_transmission.is_some()),
            ("relay_iris_mm", self.relay_iris_mm.is_some()),
            ("relay_focal_length_mm", self.relay_focal_length_mm.is_some()),
        ]
    }
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSpectrum {
    pub shape: String,
    pub center_nm: Option<f64>,
    pub range_nm: Option<f64>,
    pub peak: Option<f64>,
    pub csv: Option<String>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCamera {
    pub pixel_pitch_um: f64,
    #[serde(default)]
    pub pixel_mtf: bool,
    pub quantum_efficiency: NumberOrFile,
    pub read_noise_e: Option<f64>,
    pub dark_current_e_per_s: Option<f64>,
    pub full_well_e: Option<f64>,
    pub gain_dn_per_e: Option<f64>,
    pub adc_bits: Option<u32>,
    pub black_level_dn: Option<f64>,
    pub noise_spectrum: Option<String>,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawExposure {
    pub time_ms: f64,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawOptions {
    pub form: Option<String>,
    pub fraunhofer_threshold_mm: Option<f64>,
    pub fraunhofer_max_fraction: Option<f64>,
    pub pupil_samples: Option<u32>,
    pub glare: Option<String>,
    pub tolerance: Option<f64>,
    pub spectral_rule: Option<String>,
    pub pupil_mapping: Option<String>,
    pub table_rule: Option<String>,
}

/// The parsed TOML of a source, or how it failed (kept to build the error again).
#[derive(Clone, Debug)]
struct TomlFailure {
    line: usize,
    column: usize,
    message: String,
    excerpt: String,
}

impl TomlFailure {
    fn new(text: &str, e: &toml::de::Error) -> TomlFailure {
        let start = e.span().map_or(0, |s| s.start).min(text.len());
        let start = (0..=start).rev().find(|&i| text.is_char_boundary(i)).unwrap_or(0);
        let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
        let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
        let line = text[..start].matches('\n').count() + 1;
        let column = text[line_start..start].chars().count() + 1;
        let whole = &text[line_start..line_end];
        let excerpt = if whole.chars().count() <= crate::error::SHOWN {
            format!("`{}`", shorten(whole))
        } else {
            let skip = column.saturating_sub(crate::error::SHOWN / 2);
            let part: String = whole.chars().skip(skip).take(crate::error::SHOWN).collect();
            let lead = if skip > 0 { "…" } else { "" };
            let tail = if whole.chars().count() > skip + crate::error::SHOWN { "…" } else { "" };
            format!("`{lead}{}{tail}` (a line of {} bytes)", shorten(&part), whole.len())
        };
        let message = e.message().trim().replace('\n', "; ");
        TomlFailure { line, column, message: shorten_quoted(&message), excerpt }
    }

    fn error(&self, origin: &str) -> Error {
        Error::Toml {
            origin: origin.to_owned(),
            line: self.line,
            column: self.column,
            message: self.message.clone(),
            excerpt: self.excerpt.clone(),
        }
    }
}

/// A scene file's text, read once and built into scenes with different overrides (sweeps):
/// its TOML is parsed once, on first use, and each scene starts from a copy of that table.
#[derive(Clone, Debug)]
pub struct Source {
    text: String,
    label: String,
    dir: PathBuf,
    parsed: std::sync::OnceLock<Result<toml::Table, TomlFailure>>,
    tables: TableCache,
    arrays: crate::origins::Arrays,
}

impl Source {
    /// How messages name this scene.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The scene file's text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The folder its CSV paths resolve against.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// A scene given as text (`label` names it in messages; CSV paths resolve against `dir`).
    pub fn from_text(text: impl Into<String>, label: impl Into<String>, dir: impl Into<PathBuf>) -> Source {
        Source {
            text: text.into(),
            label: label.into(),
            dir: dir.into(),
            parsed: std::sync::OnceLock::new(),
            tables: TableCache::default(),
            arrays: crate::origins::Arrays::default(),
        }
    }

    /// This source with a 2-D array given in memory for `key` (one of
    /// [`ARRAY_KEYS`](crate::ARRAY_KEYS): `lens.phase_map`, `lens.amplitude_map`,
    /// `lens.layout_grid`) in place of a `.npy` file: a scene built from it whose `key` has the
    /// value `label` (an override `key="label"`) reads `values` (C order, `shape` as given) as it
    /// would read the file, with the same checks and messages; a value naming a file reads the
    /// file. The values are kept once, shared by every scene built from the source. An unknown
    /// key is refused here; the shape and values are checked when a scene is built, as a file's.
    pub fn with_array(
        mut self,
        key: &str,
        label: impl Into<String>,
        shape: Vec<u64>,
        values: Vec<f64>,
    ) -> Result<Source, String> {
        if !crate::ARRAY_KEYS.contains(&key) {
            return Err(format!(
                "{key}: not a key that takes an array (expected one of {})",
                crate::ARRAY_KEYS.join(", ")
            ));
        }
        let count = shape.iter().try_fold(1u64, |a, &b| a.checked_mul(b));
        if count != Some(values.len() as u64) {
            return Err(format!("{key}: {} values for the shape {shape:?}", values.len()));
        }
        let array = crate::origins::InMemory { label: label.into(), shape, values: std::sync::Arc::new(values) };
        std::sync::Arc::make_mut(&mut self.arrays.0).insert(key.to_owned(), array);
        Ok(self)
    }

    /// This source with the keys `keys` of its lens table left out (a design given anew in place
    /// of the one the file gives: `Scene.with_phase_map` and `with_layout` in Python). The other
    /// keys, the label, the folder and the arrays are kept; the text is the table written anew
    /// (its comments dropped). A text that is not TOML is returned as it is: building it names the
    /// error.
    pub fn without_lens_keys(&self, keys: &[&str]) -> Source {
        let Ok(mut table) = toml::from_str::<toml::Table>(&self.text) else { return self.clone() };
        let Some(toml::Value::Table(lens)) = table.get_mut("lens") else { return self.clone() };
        if !keys.iter().any(|k| lens.contains_key(*k)) {
            return self.clone();
        }
        for key in keys {
            lens.remove(*key);
        }
        Source { text: table.to_string(), parsed: std::sync::OnceLock::new(), ..self.clone() }
    }

    /// The arrays given in memory ([`Source::with_array`]): each key, its label, shape and values.
    pub fn arrays(&self) -> impl Iterator<Item = (&str, &str, &[u64], &[f64])> {
        self.arrays.0.iter().map(|(k, a)| (k.as_str(), a.label.as_str(), a.shape.as_slice(), a.values.as_slice()))
    }
}

/// A built scene and the plausibility warnings of its values (see [`load_with_warnings`]).
#[derive(Debug)]
#[non_exhaustive]
pub struct Loaded {
    /// The validated scene.
    pub scene: Scene,
    /// Values that are valid but almost surely a unit slip, in the order they were read.
    pub warnings: Vec<Warning>,
    /// With `[source] kind = "radiance_meter"`: every step from the meter's readings to the
    /// target's spectral radiance (SI eq. S1–S6), for reports (`asnr evaluate --explain`).
    pub radiance_meter: Option<radiometry::RadianceMeterSteps>,
    /// For a lens given by its phase profile or meta-atom library, imaged on axis: the pupil
    /// mapping used (`options.pupil_mapping`); `None` where the option does not apply.
    pub pupil_mapping: Option<PupilMapping>,
}

/// How a flat lens's pupil maps to the image's spatial frequencies (`options.pupil_mapping`,
/// docs/physics.md "The flat lens's exact image").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PupilMapping {
    /// The paraxial map `sin θ ≈ r/f0` (the paper's and Zemax's FFT-MTF convention; default).
    Paraxial,
    /// The flat lens's exact map `sin θ = r/√(r² + f0²)` with its obliquity and distance factors.
    Exact,
}

impl PupilMapping {
    /// The name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            PupilMapping::Paraxial => "paraxial",
            PupilMapping::Exact => "exact",
        }
    }

    /// The other mapping.
    pub fn other(self) -> PupilMapping {
        match self {
            PupilMapping::Paraxial => PupilMapping::Exact,
            PupilMapping::Exact => PupilMapping::Paraxial,
        }
    }
}

/// Reads a scene file (None = the embedded paper scene).
pub fn read(file: Option<&Path>) -> Result<Source, Error> {
    Ok(match file {
        Some(path) => {
            let text = read_text(path, "scene file")?;
            let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
            Source::from_text(text, path.display().to_string(), dir)
        }
        None => Source::from_text(PAPER_SCENE, "embedded paper scene", "."),
    })
}

/// Reads and validates a scene: `file` (None = the embedded paper scene) with `--set` overrides.
pub fn load(file: Option<&Path>, overrides: &[String]) -> Result<Scene, Error> {
    Ok(load_with_warnings(file, overrides)?.scene)
}

/// [`load`], with the plausibility warnings: a pixel pitch outside
/// [`PIXEL_PITCH_PLAUSIBLE_UM`], a focal length outside [`FOCAL_LENGTH_PLAUSIBLE_MM`](crate::FOCAL_LENGTH_PLAUSIBLE_MM), a
/// wavelength (`design_wavelength_nm`, `center_nm`, or a whole table's) outside
/// [`WAVELENGTH_PLAUSIBLE_NM`](crate::WAVELENGTH_PLAUSIBLE_NM), an exposure outside [`EXPOSURE_PLAUSIBLE_MS`]. Each names the
/// key, the value and the unit it was probably typed in.
pub fn load_with_warnings(file: Option<&Path>, overrides: &[String]) -> Result<Loaded, Error> {
    check_overrides(file, overrides)?;
    build_with_warnings(&read(file)?, overrides)
}

/// Builds and validates the scene of `source` with `--set` overrides.
pub fn build_from(source: &Source, overrides: &[String]) -> Result<Scene, Error> {
    Ok(build_with_warnings(source, overrides)?.scene)
}

/// [`build_from`], with the plausibility warnings of [`load_with_warnings`].
pub fn build_with_warnings(source: &Source, overrides: &[String]) -> Result<Loaded, Error> {
    let (raw, origins) = prepare(source, overrides)?;
    build_checked(&raw, &origins)
}

/// Builds the scene and takes its plausibility warnings: with the scene, or named beside the
/// error when it cannot be built (a unit slip is then the likely cause).
pub(crate) fn build_checked(raw: &RawScene, origins: &Origins) -> Result<Loaded, Error> {
    let built = build(raw, origins);
    let warnings = origins.warnings.take();
    match built {
        Ok(scene) => {
            Ok(Loaded { scene, warnings, radiance_meter: origins.meter.take(), pupil_mapping: origins.mapping.get() })
        }
        Err(error) if warnings.is_empty() => Err(error),
        Err(error) => Err(Error::WithWarnings { error: Box::new(error), warnings }),
    }
}

/// Checks the syntax of every override (`key=value`, a dotted key) before any file is read.
/// When one lacks `=` and `file` does not exist, `file` is probably that override's value split
/// off by an argument parser (`--set lens.f_number 2.8`), and the message says so.
pub fn check_overrides(file: Option<&Path>, overrides: &[String]) -> Result<(), Error> {
    let lacking: Vec<&String> = overrides.iter().filter(|a| !a.contains('=')).collect();
    if let (Some(path), [arg]) = (file, lacking.as_slice())
        && !path.exists()
        && path.extension().is_none_or(|e| e != "toml")
    {
        let value = path.display().to_string();
        return Err(Error::Override {
            arg: shorten(arg),
            problem: format!("expected KEY=VALUE (write --set {}={})", shorten(arg.trim()), shorten(&value)),
        });
    }
    apply_overrides(&mut toml::Table::new(), overrides, true).map(drop)
}

/// Applies every override in turn; a key given twice is refused (the first would be dropped).
/// Returns each key with the override that gave it.
/// With `check_only` (an empty table: the syntax alone), an indexed key (`designs[1].lens.x`) is
/// not looked up.
fn apply_overrides(
    table: &mut toml::Table,
    overrides: &[String],
    check_only: bool,
) -> Result<BTreeMap<String, String>, Error> {
    let mut given: BTreeMap<String, String> = BTreeMap::new();
    for arg in overrides {
        let (key, arg) = apply_override(table, arg, check_only)?;
        if let Some(first) = given.get(&key) {
            return Err(Error::Override {
                arg: shorten(&arg),
                problem: format!(
                    "{key} is given twice (also by --set {}); expected each key once (--tolerance and --over set their keys too)",
                    shorten(first)
                ),
            });
        }
        // a table given after a key inside it would replace (drop) that key
        let below = |a: &str| a.starts_with(&format!("{key}.")) || a.starts_with(&format!("{key}["));
        if let Some((inner, first)) = given.iter().find(|(k, _)| below(k)) {
            return Err(Error::Override {
                arg: shorten(&arg),
                problem: format!(
                    "it replaces the table {key}, dropping {inner} given before it by --set {}; give the table first, then the keys inside it",
                    shorten(first)
                ),
            });
        }
        given.insert(key, arg);
    }
    Ok(given)
}

/// The merged TOML table of `source` with `overrides`, and where each key came from.
pub(crate) fn merged(source: &Source, overrides: &[String]) -> Result<(toml::Table, Origins), Error> {
    let (text, label, dir) = (&source.text, source.label.clone(), source.dir.clone());
    apply_overrides(&mut toml::Table::new(), overrides, true)?;
    if text.trim().is_empty() {
        return Err(Error::Empty { origin: label });
    }
    let parsed = source.parsed.get_or_init(|| toml::from_str(text).map_err(|e| TomlFailure::new(text, &e)));
    let mut table = parsed.clone().map_err(|e| e.error(&label))?;
    let overrides = apply_overrides(&mut table, overrides, false)?;
    let origins = Origins::new(label, dir, overrides, "lens".to_owned(), source.tables.clone(), source.arrays.clone());
    Ok((table, origins))
}

/// The merged TOML table of `source` with `overrides`, deserialized, and where each key came from.
pub(crate) fn prepare(source: &Source, overrides: &[String]) -> Result<(RawScene, Origins), Error> {
    let (table, mut origins) = merged(source, overrides)?;
    if table.contains_key("designs") {
        return Err(origins.conflict(
            "designs",
            "the file compares designs ([[designs]]): read it with asnr compare (scene::load_comparison), or give one lens as [lens]".to_owned(),
        ));
    }
    let raw = raw_scene(table, &mut origins, &|| merged(source, overrides).ok().map(|(table, _)| table))?;
    Ok((raw, origins))
}

/// The sections whose keys [`Prepared`] sets on a prepared raw scene.
const PREPARED_SECTIONS: [&str; 7] = ["lens", "source", "spectrum", "camera", "exposure", "options", "field"];

/// A scene's source with its `--set` overrides, read once for many builds that change only the
/// values of some keys (a sweep's points): the merged table and the raw scene, deserialized at
/// one point. A point then re-applies each of its assignments to a copy of its section's table
/// (the same [`apply_override`] as [`merged`]), deserializes that section alone and builds the
/// scene from the raw scene with those sections replaced ([`build_checked`], the same
/// validation and warnings). A struct's fields deserialize independently of one another, so
/// the raw scene is the one [`prepare`] makes of the whole merged table with the point's
/// assignments; wherever a step fails, [`Prepared::build`] answers `None` and the caller builds
/// the point the whole way ([`build_with_warnings`]), whose error is then the one reported.
pub(crate) struct Prepared {
    /// The merged table at the point it was prepared at.
    table: toml::Table,
    /// Its raw scene.
    raw: RawScene,
    /// Each key with the override that gave it, at that point.
    overrides: BTreeMap<String, String>,
    label: String,
    dir: PathBuf,
    tables: TableCache,
    arrays: crate::origins::Arrays,
    /// The swept keys.
    keys: Vec<String>,
    /// The swept keys' sections, each once, with the indices (in `keys`) of the keys each holds.
    sections: Vec<(&'static str, Vec<usize>)>,
    /// Each section as a point deserialized it, by its index in `sections` and the bits of its
    /// keys' values, with the overrides its assignments gave: a section is a function of those
    /// values alone, so a point whose values were seen before (the map's 40 F-numbers each
    /// come back at every band) takes it from here. At most [`PREPARED_SECTIONS_KEPT`].
    seen: std::sync::Mutex<std::collections::HashMap<(usize, Vec<u64>), SectionAt>>,
}

/// How many deserialized sections a [`Prepared`] keeps (a few hundred bytes to a few kB each).
pub(crate) const PREPARED_SECTIONS_KEPT: usize = 4096;

/// One section of the raw scene, deserialized at some values of its swept keys, and the
/// overrides (`key`, `assignment`) those keys' assignments gave.
#[derive(Clone)]
pub(crate) struct SectionAt {
    raw: RawSection,
    overrides: Vec<(String, String)>,
}

/// A section of the raw scene.
#[derive(Clone)]
enum RawSection {
    Lens(Box<RawLens>),
    Source(RawSource),
    Spectrum(RawSpectrum),
    Camera(RawCamera),
    Exposure(RawExposure),
    Options(RawOptions),
    Field(RawField),
}

impl RawSection {
    /// `value` deserialized as the section `name`.
    fn of(name: &str, value: toml::Value) -> Option<RawSection> {
        Some(match name {
            "lens" => RawSection::Lens(Box::new(RawLens::deserialize(value).ok()?)),
            "source" => RawSection::Source(RawSource::deserialize(value).ok()?),
            "spectrum" => RawSection::Spectrum(RawSpectrum::deserialize(value).ok()?),
            "camera" => RawSection::Camera(RawCamera::deserialize(value).ok()?),
            "exposure" => RawSection::Exposure(RawExposure::deserialize(value).ok()?),
            "options" => RawSection::Options(RawOptions::deserialize(value).ok()?),
            "field" => RawSection::Field(RawField::deserialize(value).ok()?),
            _ => return None,
        })
    }

    /// Puts it in place in `raw`.
    fn set(self, raw: &mut RawScene) {
        match self {
            RawSection::Lens(lens) => raw.lens = *lens,
            RawSection::Source(source) => raw.source = source,
            RawSection::Spectrum(spectrum) => raw.spectrum = Some(spectrum),
            RawSection::Camera(camera) => raw.camera = camera,
            RawSection::Exposure(exposure) => raw.exposure = exposure,
            RawSection::Options(options) => raw.options = Some(options),
            RawSection::Field(field) => raw.field = Some(field),
        }
    }
}

impl Prepared {
    /// Prepares `source` with `overrides`, whose last `keys.len()` entries assign `keys` (one
    /// point's [`crate::sweep::assignment`]s). `None` where a point could not be built this way
    /// and be the same scene: a key that is not `SECTION.KEY` of one of [`PREPARED_SECTIONS`]
    /// (a list entry, a comparison's design, a table), a lens preset or Zemax file (which fill
    /// the lens table from what it holds), a warning while reading, or any error (the points
    /// are then built the whole way, which reports it).
    pub(crate) fn new(source: &Source, overrides: &[String], keys: &[String]) -> Option<Prepared> {
        let mut sections: Vec<(&'static str, Vec<usize>)> = Vec::new();
        for (i, key) in keys.iter().enumerate() {
            let (section, leaf) = key.trim().split_once('.')?;
            let section = PREPARED_SECTIONS.iter().find(|s| **s == section)?;
            if leaf.is_empty() || leaf.contains(['.', '[', ']']) || ["preset", "zemax", "zemax_surface"].contains(&leaf)
            {
                return None;
            }
            match sections.iter_mut().find(|(s, _)| s == section) {
                Some((_, held)) => held.push(i),
                None => sections.push((*section, vec![i])),
            }
        }
        let (table, mut origins) = merged(source, overrides).ok()?;
        if table.contains_key("designs") {
            return None;
        }
        // each swept key's section is a table holding the key
        for key in keys {
            let (section, leaf) = key.trim().split_once('.')?;
            table.get(section)?.as_table()?.get(leaf)?;
        }
        let kept = table.clone();
        let raw = raw_scene(table, &mut origins, &|| None).ok()?;
        if origins.preset.is_some() || origins.zemax.is_some() || !origins.warnings.borrow().is_empty() {
            return None;
        }
        Some(Prepared {
            table: kept,
            raw,
            overrides: origins.overrides,
            label: origins.file,
            dir: origins.dir,
            tables: origins.tables,
            arrays: origins.arrays,
            keys: keys.to_vec(),
            sections,
            seen: std::sync::Mutex::new(std::collections::HashMap::new()),
        })
    }

    /// Section `s` of `sections` with its keys set to their `values` (one per key of the
    /// sweep): each key's assignment applied to a copy of the section's table as
    /// [`merged`] applies it, then the section deserialized; `None` where a step fails.
    fn section_at(&self, s: usize, values: &[f64]) -> Option<SectionAt> {
        let (name, held) = &self.sections[s];
        let mut holder = toml::Table::new();
        holder.insert((*name).to_owned(), self.table.get(*name)?.clone());
        let mut overrides = Vec::with_capacity(held.len());
        for &k in held {
            let arg = crate::sweep::assignment(&self.keys[k], *values.get(k)?);
            let (key, arg) = apply_override(&mut holder, &arg, false).ok()?;
            // only the prepared sections' keys, given before (the checks of a key given twice
            // or inside a table given after it ran when the point was prepared)
            self.overrides.get(&key)?;
            overrides.push((key, arg));
        }
        if holder.len() != 1 {
            return None;
        }
        let value = holder.remove(*name)?;
        Some(SectionAt { raw: RawSection::of(name, value)?, overrides })
    }

    /// The scene with the swept keys at `values` (one per key, in the keys' order), built and
    /// checked as [`build_with_warnings`] builds it from the overrides and the keys'
    /// [`crate::sweep::assignment`]s; `None` where any step fails (build it that way for the
    /// error).
    pub(crate) fn build(&self, values: &[f64]) -> Option<Loaded> {
        if values.len() != self.keys.len() {
            return None;
        }
        let mut overrides = self.overrides.clone();
        let mut raw = self.raw.clone();
        for (s, (_, held)) in self.sections.iter().enumerate() {
            let id = (s, held.iter().map(|&k| values[k].to_bits()).collect::<Vec<u64>>());
            let known = self.seen.lock().ok().and_then(|seen| seen.get(&id).cloned());
            let section = match known {
                Some(section) => section,
                None => {
                    let section = self.section_at(s, values)?;
                    if let Ok(mut seen) = self.seen.lock()
                        && seen.len() < PREPARED_SECTIONS_KEPT
                    {
                        seen.insert(id, section.clone());
                    }
                    section
                }
            };
            overrides.extend(section.overrides);
            section.raw.set(&mut raw);
        }
        let origins = Origins::new(
            self.label.clone(),
            self.dir.clone(),
            overrides,
            "lens".to_owned(),
            self.tables.clone(),
            self.arrays.clone(),
        );
        build_checked(&raw, &origins).ok()
    }
}

/// A scene's merged table (its lens's preset filled in) as the raw scene. The table is moved
/// into the deserializer (a sweep builds one per point: a copy kept for the error message cost
/// 3 % of a map); where it fails, `rebuild` makes it again for the message (without the preset,
/// whose values are never the strings the message quotes).
pub(crate) fn raw_scene(
    mut table: toml::Table,
    origins: &mut Origins,
    rebuild: &dyn Fn() -> Option<toml::Table>,
) -> Result<RawScene, Error> {
    if let Some(toml::Value::Table(lens)) = table.get_mut("lens") {
        origins.preset = crate::lens::apply_preset(lens, origins)?;
        origins.zemax = crate::lens::apply_zemax(lens, origins)?;
    }
    serde_path_to_error::deserialize(toml::Value::Table(table))
        .map_err(|e| schema_error(&e, &rebuild().unwrap_or_default(), origins))
}

/// A serde error (unknown key, wrong type, missing key) as a message naming origin and key; a
/// string where a number belongs (`"800nm"`) says which number and unit to write.
fn schema_error(e: &serde_path_to_error::Error<toml::de::Error>, table: &toml::Table, o: &Origins) -> Error {
    let key = o.key(&e.path().to_string());
    // toml appends "in `key`" to its messages; the key is already named in front
    let inner = e.inner().to_string();
    let inner = inner.split("\nin `").next().unwrap_or_default().trim_end().to_owned();
    let origin = o.of(&key);
    let numeric = if inner.ends_with("expected f64") {
        Some("a number")
    } else if inner.ends_with("expected u32") {
        Some("a whole number")
    } else {
        None
    };
    if let (Some(kind), true) = (numeric, inner.starts_with("invalid type: string")) {
        let unit = unit_of(&key);
        if let Some(toml::Value::String(s)) = lookup(table, e.path())
            && let Some(n) = number_prefix(s)
        {
            let expected = format!("{kind}{unit} (write {n}, not {})", quoted(s));
            return Error::Value { origin, key: shorten(&key), value: quoted(s), expected };
        }
    }
    // `f_number = "fast"`, `pupil_samples = 256.5`, `center_nm = true`: which number, which unit
    let message = match numeric {
        Some(kind) => format!("{} ({kind}{})", shorten_quoted(&inner), unit_of(&key)),
        None => shorten_quoted(&inner),
    };
    Error::Schema { origin, key: shorten(&key), message }
}

/// The value at a serde path in the merged table.
fn lookup<'a>(table: &'a toml::Table, path: &serde_path_to_error::Path) -> Option<&'a toml::Value> {
    use serde_path_to_error::Segment;
    let mut segments = path.iter();
    let mut value = match segments.next()? {
        Segment::Map { key } => table.get(key)?,
        _ => return None,
    };
    for segment in segments {
        value = match segment {
            Segment::Map { key } => value.as_table()?.get(key)?,
            Segment::Seq { index } => value.as_array()?.get(*index)?,
            _ => return None,
        };
    }
    Some(value)
}

/// `text` as TOML reads it where it is a plain decimal number: `[+-]` digits (no leading zero
/// but `0` itself), then a fraction `.digits` and/or an exponent `e[+-]digits`; an integer
/// without either (within i64), a finite float with. `None` for anything else (underscores, `inf`,
/// hex, dates, strings …), which the TOML parser reads. A sweep's `--over` values are all
/// plain numbers ([`crate::sweep::assignment`]): each of its points skips a TOML parse per key.
fn plain_number(text: &str) -> Option<toml::Value> {
    let bytes = text.as_bytes();
    let digits = |from: usize| bytes[from..].iter().take_while(|b| b.is_ascii_digit()).count();
    let mut i = usize::from(matches!(bytes.first(), Some(b'+' | b'-')));
    let whole = digits(i);
    if whole == 0 || (whole > 1 && bytes[i] == b'0') {
        return None;
    }
    i += whole;
    let mut float = false;
    if bytes.get(i) == Some(&b'.') {
        let fraction = digits(i + 1);
        if fraction == 0 {
            return None;
        }
        i += 1 + fraction;
        float = true;
    }
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        i += 1 + usize::from(matches!(bytes.get(i + 1), Some(b'+' | b'-')));
        let exponent = digits(i);
        if exponent == 0 {
            return None;
        }
        i += exponent;
        float = true;
    }
    if i != bytes.len() {
        return None;
    }
    if float {
        // beyond f64 (1e400) TOML refuses the literal; so does this
        text.parse().ok().filter(|v: &f64| v.is_finite()).map(toml::Value::Float)
    } else {
        text.parse().ok().map(toml::Value::Integer)
    }
}

/// Applies one `--set key=value` to the TOML table. The value is read as TOML (number, boolean,
/// quoted string), or as a bare string if it is not valid TOML (`--set spectrum.shape=tophat`).
fn apply_override(table: &mut toml::Table, arg: &str, check_only: bool) -> Result<(String, String), Error> {
    let refuse = |problem: String| Error::Override { arg: shorten(arg), problem };
    let Some((key, value)) = arg.split_once('=') else {
        return Err(refuse(format!(
            "expected key=value with a dotted key (write --set {}=VALUE, e.g. --set lens.f_number=2.5)",
            shorten(arg.trim())
        )));
    };
    let key = key.trim();
    let parts: Vec<&str> = key.split('.').collect();
    if key.is_empty() || parts.iter().any(|p| p.is_empty()) {
        return Err(refuse(format!("`{}` is not a dotted key, e.g. lens.f_number", shorten(key))));
    }
    if value.contains(['\n', '\r']) {
        return Err(refuse("the value spans several lines; expected a value on one line".to_owned()));
    }
    let parsed = plain_number(value.trim()).unwrap_or_else(|| {
        toml::from_str::<toml::Table>(&format!("v = {value}"))
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| toml::Value::String(value.trim().to_owned()))
    });
    // `2.8 # x` or `2.8#x` is valid TOML with a comment: refuse rather than drop the rest
    if value.contains('#') && !parsed.to_string().contains('#') {
        return Err(refuse(format!(
            "`#` starts a TOML comment, so the value would be read as {parsed} and the rest dropped; expected the value alone (quote a string that holds `#`)"
        )));
    }
    let mut cursor = table;
    for (i, part) in parts.iter().enumerate() {
        let here = parts[..=i].join(".");
        let last = i + 1 == parts.len();
        let (name, index) = split_index(part).ok_or_else(|| {
            refuse(format!("`{}` is not a key or a list entry (write e.g. designs[1].lens.f_number=4)", shorten(part)))
        })?;
        let Some(index) = index else {
            if last {
                cursor.insert(name.to_owned(), parsed.clone());
                break;
            }
            let entry = cursor.entry(name.to_owned()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
            cursor =
                entry.as_table_mut().ok_or_else(|| refuse(format!("`{}` is a value, not a table", shorten(&here))))?;
            continue;
        };
        let Some(value) = cursor.get_mut(name) else {
            if check_only {
                break;
            }
            return Err(refuse(format!("`{}`: the scene has no list `{}` to index", shorten(&here), shorten(name))));
        };
        let Some(list) = value.as_array_mut() else {
            return Err(refuse(format!(
                "`{}` is not a list ([[{}]]), so `{}` names nothing",
                name,
                name,
                shorten(&here)
            )));
        };
        let len = list.len();
        let number = |v: &toml::Value| matches!(v, toml::Value::Float(_) | toml::Value::Integer(_));
        if index >= len && last && number(&parsed) && list.iter().all(number) && !list.is_empty() {
            // a numeric list grows with zeros up to the entry set (a Binary 2 profile gains terms)
            if name == "phase_spline_rad" {
                return Err(refuse(format!(
                    "`{}`: `{name}` has {len} knots ({name}[0] to {name}[{}]); the knots are equally spaced from the axis to the edge, so another knot moves every one: give the whole list (--set lens.{name}=[…])",
                    shorten(&here),
                    len - 1
                )));
            }
            if index >= MAX_EXTENDED_LIST {
                return Err(refuse(format!(
                    "`{}`: {index} is past the end of `{name}` ({len} entries); a list grows with zeros up to {MAX_EXTENDED_LIST} entries at most",
                    shorten(&here)
                )));
            }
            list.resize(index + 1, toml::Value::Float(0.0));
        }
        let Some(item) = list.get_mut(index) else {
            let range = if len == 0 { "none".to_owned() } else { format!("{name}[0] to {name}[{}]", len - 1) };
            return Err(refuse(format!("`{}`: `{name}` has {len} entries ({range})", shorten(&here))));
        };
        if last {
            *item = parsed.clone();
            break;
        }
        cursor = item.as_table_mut().ok_or_else(|| refuse(format!("`{}` is a value, not a table", shorten(&here))))?;
    }
    let canonical = canonical_key(key).unwrap_or_else(|| key.to_owned());
    Ok((canonical, arg.to_owned()))
}

/// The most entries a numeric list may grow to when `--set` (or `--over`) gives an entry past
/// its end: the list is extended with zeros up to that entry.
pub const MAX_EXTENDED_LIST: usize = 1024;

/// The canonical spelling of a dotted key: each list index a plain decimal, 0-based, without
/// leading zeros or spaces (`lens.binary2[03]` and `lens.binary2[ 3 ]` are `lens.binary2[3]`),
/// so that one entry is one key whichever way it is written; `None` where a segment is not
/// `name` or `name[index]`.
pub fn canonical_key(key: &str) -> Option<String> {
    let parts = key
        .trim()
        .split('.')
        .map(|part| {
            let (name, index) = split_index(part)?;
            Some(index.map_or_else(|| name.to_owned(), |i| format!("{name}[{i}]")))
        })
        .collect::<Option<Vec<String>>>()?;
    Some(parts.join("."))
}

/// `name` or `name[index]` of one segment of a dotted key; `None` for a malformed index.
fn split_index(part: &str) -> Option<(&str, Option<usize>)> {
    let Some((name, rest)) = part.split_once('[') else { return Some((part, None)) };
    let index = rest.strip_suffix(']')?.trim().parse().ok()?;
    (!name.is_empty()).then_some((name, Some(index)))
}

fn build(raw: &RawScene, o: &Origins) -> Result<Scene, Error> {
    Ok(build_parts(raw, o)?.0)
}

/// The scene and what the comparison needs to know of its lens.
pub(crate) fn build_parts(raw: &RawScene, o: &Origins) -> Result<(Scene, crate::lens_table::LensInfo), Error> {
    // [lens]
    let crate::lens::BuiltLens { lens, info } = crate::lens::build(&raw.lens, o)?;
    let lens = pupil_mapping(raw, lens, &info, o)?;

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
    let (lo, hi) = PIXEL_PITCH_PLAUSIBLE_UM;
    if pitch < lo {
        o.warn(
            "camera.pixel_pitch_um",
            num(pitch),
            format!("below {lo} µm: looks like mm ({} µm?)", rounded(pitch * 1e3)),
        );
    } else if pitch > hi {
        o.warn(
            "camera.pixel_pitch_um",
            num(pitch),
            format!("above {hi} µm: looks like nm ({} µm?)", rounded(pitch * 1e-3)),
        );
    }
    let qe = match o.curve("camera.quantum_efficiency", &c.quantum_efficiency, "quantum efficiency")? {
        Curve::Constant(v) => Spectrum::Constant(v),
        Curve::Table(t) => Spectrum::Sampled(t),
    };
    let mut camera = Camera::new(pitch * 1e-6, qe, c.pixel_mtf).map_err(|e| o.domain("camera", "[camera]", e))?;
    if let Some(sensor) = sensor(c, o)? {
        camera = camera.with_sensor(sensor);
    }
    if let Some(file) = &c.noise_spectrum {
        let key = "camera.noise_spectrum";
        let expected = "the path of a CSV file: frequency_cyc_per_mm, relative noise amplitude";
        let (cyc_per_mm, relative) = read_pairs(&o.path(file), &FREQUENCY, 0.0, f64::MAX, "relative noise amplitude")
            .map_err(|e| o.table_error(key, file, e, expected))?;
        let shape = optics::NoiseShape::new(cyc_per_mm.iter().map(|f| f * 1e3).collect(), relative)
            .map_err(|e| o.domain(key, &format!("{key} = {}", quoted(file)), e))?;
        camera = camera.with_noise_spectrum(shape);
    }

    // [exposure], [options]
    let t = o.number("exposure.time_ms", raw.exposure.time_ms, raw.exposure.time_ms > 0.0, "a time > 0 ms")?;
    let (lo, hi) = EXPOSURE_PLAUSIBLE_MS;
    if t < lo {
        o.warn("exposure.time_ms", num(t), format!("below {lo} ms (1 ns): looks like s ({} ms?)", rounded(t * 1e3)));
    } else if t > hi {
        o.warn("exposure.time_ms", num(t), format!("above {hi} ms (2.8 h): looks like µs ({} ms?)", rounded(t * 1e-3)));
    }
    let options = options(raw.options.as_ref(), o)?;
    let scene = Scene::new(lens, radiance, camera, t * 1e-3, options).map_err(|e| o.domain("", "", e))?;
    if let Some(limits) = &info.psf {
        crate::psf::check_scene(&scene, limits, o)?;
    }
    if let Some(range) = &info.table_range {
        crate::psf::check_table_range(&scene, range, o)?;
    }
    if let Some(limits) = &info.psf {
        crate::psf::warn_notices(limits, o);
    }
    // a lens given by its phase profile or a meta-atom library images an oblique wave
    // (`optics::radial::Oblique`) below 80° only: beyond, its orders fell back to the axis and
    // 85° returned the on-axis numbers
    let oblique = matches!(raw.lens.model.as_deref(), Some("phase" | "library"));
    let angle = |key: &str, v: Option<f64>| -> Result<f64, Error> {
        let v = v.unwrap_or(0.0);
        if oblique {
            let expected = "an angle in degrees within ±80 for a lens given by its phase profile or meta-atom library (its oblique incidence is modelled below 80°)";
            return Ok(o.number(key, v, v.abs() < MAX_OBLIQUE_DEG, expected)?.to_radians());
        }
        Ok(o.number(key, v, v.abs() < 90.0, "an angle in degrees, within ±90")?.to_radians())
    };
    let scene = match (&raw.field, &raw.fields) {
        (Some(_), Some(_)) => {
            return Err(
                o.conflict("field", "[field] and [[fields]] both given: use one point or a weighted list".to_owned())
            );
        }
        (Some(f), None) => {
            let field = optics::Field::new(angle("field.x_deg", f.x_deg)?, angle("field.y_deg", f.y_deg)?);
            scene.at_field(field).map_err(|e| o.domain("field", "[field]", e))?
        }
        (None, Some(list)) => {
            if list.is_empty() {
                return Err(o.conflict("fields", "[[fields]] is empty: expected at least one field point".to_owned()));
            }
            let mut points = Vec::new();
            for (i, f) in list.iter().enumerate() {
                let x = angle(&format!("fields[{i}].x_deg"), f.x_deg)?;
                let y = angle(&format!("fields[{i}].y_deg"), f.y_deg)?;
                let w = f.weight.unwrap_or(1.0);
                let w = o.number(&format!("fields[{i}].weight"), w, w >= 0.0, "a relative weight ≥ 0")?;
                points.push((optics::Field::new(x, y), w));
            }
            scene.over_fields(points).map_err(|e| o.domain("fields", "[[fields]]", e))?
        }
        (None, None) => scene,
    };
    let scene = match &raw.title {
        Some(title) => scene.with_title(title.clone()),
        None => scene,
    };
    let scene = relative_illumination(&raw.lens, scene, o)?;
    Ok((scene, info))
}

/// What `options.pupil_mapping` accepts.
const PUPIL_MAPPING: &str = "\"paraxial\" (the default: sin θ ≈ r/f0, the paper's and Zemax's FFT-MTF convention) or \"exact\" (the flat lens's sin θ = r/√(r² + f0²) with its obliquity, on axis, for a lens given by its radial phase profile or meta-atom library)";

/// `options.pupil_mapping` (docs/physics.md, "The flat lens's exact image"): the lens imaged
/// through the flat lens's exact map where asked ([`lenses::ExactPupilMap`]), and the mapping
/// recorded for the report where the option applies (a radial phase profile or a library on axis).
/// `"exact"` is refused, naming the key, for other families, 2-D phase maps and layouts, and
/// off-axis field points (the map is radial on axis only).
fn pupil_mapping(
    raw: &RawScene,
    lens: std::sync::Arc<dyn optics::LensModel>,
    info: &crate::lens_table::LensInfo,
    o: &Origins,
) -> Result<std::sync::Arc<dyn optics::LensModel>, Error> {
    let key = "options.pupil_mapping";
    let given = raw.options.as_ref().and_then(|p| p.pupil_mapping.as_deref());
    let mapping = match given {
        None | Some("paraxial") => PupilMapping::Paraxial,
        Some("exact") => PupilMapping::Exact,
        Some(other) => return Err(o.bad(key, quoted(other), PUPIL_MAPPING)),
    };
    // a library's 2-D layout (layout_grid, layout_gds) is a 2-D pupil, as a phase map is
    let radial = matches!(raw.lens.model.as_deref(), Some("phase" | "library"))
        && raw.lens.phase_map.is_none()
        && raw.lens.layout_grid.is_none()
        && raw.lens.layout_gds.is_none();
    let on_axis = |x: Option<f64>, y: Option<f64>| x.unwrap_or(0.0) == 0.0 && y.unwrap_or(0.0) == 0.0;
    let axial = match (&raw.field, &raw.fields) {
        (Some(f), _) => on_axis(f.x_deg, f.y_deg),
        (None, Some(list)) => list.iter().all(|f| on_axis(f.x_deg, f.y_deg)),
        (None, None) => true,
    };
    let probe = info.design_wavelength_m.unwrap_or(550e-9);
    if mapping == PupilMapping::Paraxial {
        if radial && axial {
            // the report's check evaluates the lens through the exact map: where that map does
            // not take the lens (Zernike terms off m = 0), no check, and a warning says so
            match lenses::exact_map_refusal(lens.as_ref(), probe) {
                None => o.mapping.set(Some(mapping)),
                Some(why) => o.warn(
                    key,
                    quoted("paraxial"),
                    format!(
                        "the paraxial map's error against the flat lens's exact image is not estimated for this lens: {why}"
                    ),
                ),
            }
        }
        return Ok(lens);
    }
    if !radial {
        return Err(o.bad(
            key,
            quoted("exact"),
            "\"paraxial\" for this lens: \"exact\" maps the pupil of a lens given by its radial phase profile (lens.binary2, lens.phase_csv, lens.phase_spline_rad) or a meta-atom library's radial layout; 2-D phase maps and the other families are imaged paraxially",
        ));
    }
    if !axial {
        return Err(o.bad(
            key,
            quoted("exact"),
            "\"paraxial\" off axis: the exact map is radial on axis only (set the field to 0°, or use the paraxial map)",
        ));
    }
    let mapped = lenses::ExactPupilMap::new(lens, probe).map_err(|e| o.domain(key, "[options]", e))?;
    o.mapping.set(Some(mapping));
    Ok(std::sync::Arc::new(mapped))
}

/// The largest field angle, degrees, of a lens whose orders carry the oblique wave
/// (`optics::radial::Oblique::new` refuses |θ| ≥ 80° on either axis).
const MAX_OBLIQUE_DEG: f64 = 80.0;

/// What `lens.relative_illumination` accepts.
const RELATIVE_ILLUMINATION: &str = "\"none\" (the default, as in the paper), \"cos4\" (cos⁴ of the field angle), a fraction in [0, 1] at every field point, or the path of a CSV table field_deg, relative illumination (angles from 0 to below 90°, increasing; values in [0, 1])";

/// The field angle of a relative-illumination table, degrees, ≥ 0.
const FIELD_ANGLE: crate::tables::Axis = crate::tables::Axis { name: "field_angle", unit: "deg", zero_allowed: true };

/// `scene` with the relative illumination `lens.relative_illumination` names (every family's
/// key; default none), a table checked to reach every field point.
fn relative_illumination(l: &crate::lens_table::RawLens, scene: Scene, o: &Origins) -> Result<Scene, Error> {
    use metric::RelativeIllumination;
    let key = "lens.relative_illumination";
    let ri = match &l.relative_illumination {
        None => return Ok(scene),
        Some(NumberOrFile::Number(v)) => {
            RelativeIllumination::Constant(o.number(key, *v, (0.0..=1.0).contains(v), RELATIVE_ILLUMINATION)?)
        }
        Some(NumberOrFile::File(name)) => match name.as_str() {
            "none" => RelativeIllumination::None,
            "cos4" => RelativeIllumination::Cos4,
            file => {
                // a word that is no file (a misspelt model) is named as such, not as a missing file
                let path = o.path(file);
                if !path.exists() && !file.contains(['.', '/', '\\']) {
                    return Err(o.bad(key, quoted(file), RELATIVE_ILLUMINATION));
                }
                let (degrees, values) = read_pairs(&path, &FIELD_ANGLE, 0.0, 1.0, "relative illumination")
                    .map_err(|e| o.table_error(key, file, e, RELATIVE_ILLUMINATION))?;
                let radians = degrees.iter().map(|d| d.to_radians()).collect();
                RelativeIllumination::table(shorten(file), radians, values)
                    .map_err(|e| o.domain(key, &format!("{key} = {}", quoted(file)), e))?
            }
        },
    };
    let points: Vec<(String, optics::Field)> = if scene.fields().is_empty() {
        vec![("field".to_owned(), scene.field())]
    } else {
        scene.fields().iter().enumerate().map(|(i, f)| (format!("fields[{i}]"), f.0)).collect()
    };
    for (name, field) in points {
        if ri.at(field).is_err() {
            return Err(o.bad(
                key,
                format!("{} ({})", quoted(&ri.name()), ri.describe()),
                &format!(
                    "a table reaching every field angle: {name} is at {}° from the axis (the table is not extrapolated)",
                    num(optics::round_for_display(RelativeIllumination::field_angle(field).to_degrees()))
                ),
            ));
        }
    }
    Ok(scene.with_relative_illumination(ri))
}

/// `[options]`: [`Options::default`] with the keys given.
fn options(opt: Option<&RawOptions>, o: &Origins) -> Result<Options, Error> {
    let mut options = Options::default();
    let Some(opt) = opt else { return Ok(options) };
    if let Some(form) = &opt.form {
        options.form = match form.as_str() {
            "mean" => MetricForm::Mean,
            "integral" => MetricForm::Integral,
            other => return Err(o.bad("options.form", quoted(other), "\"mean\" or \"integral\"")),
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
            other => return Err(o.bad("options.glare", quoted(other), "\"first_order\" or \"included\"")),
        };
    }
    if let Some(r) = &opt.spectral_rule {
        options.spectral_rule = match r.as_str() {
            "interpolated" => optics::SpectralRule::Interpolated,
            "panels" => optics::SpectralRule::Panels,
            other => {
                return Err(o.bad(
                    "options.spectral_rule",
                    quoted(other),
                    "\"interpolated\" (product integration, the default) or \"panels\" (the per-interval reference rule)",
                ));
            }
        };
    }
    if let Some(r) = &opt.table_rule {
        options.table_rule = match r.as_str() {
            "tensor" => optics::radial::TableRule::Tensor,
            "split" => optics::radial::TableRule::Split,
            other => {
                return Err(o.bad(
                    "options.table_rule",
                    quoted(other),
                    "\"tensor\" (the radial engine's tensor rule, the default) or \"split\" (the rule split at a table's knots)",
                ));
            }
        };
    }
    if let Some(v) = opt.pupil_samples {
        if !(16..=4096).contains(&v) {
            return Err(o.bad("options.pupil_samples", v, "a whole number of pupil samples from 16 to 4096"));
        }
        options.pupil_samples = Some(v as usize);
    }
    if let Some(v) = opt.tolerance {
        // a tolerance the scene asks for is asked of every engine, the FFT path's too
        options.fft_tolerance = None;
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
    Ok(options)
}

/// The sensor noise model, when the scene gives any of its keys (otherwise shot-noise limited).
fn sensor(c: &RawCamera, o: &Origins) -> Result<Option<noise::Sensor>, Error> {
    if c.read_noise_e.is_none()
        && c.dark_current_e_per_s.is_none()
        && c.full_well_e.is_none()
        && c.gain_dn_per_e.is_none()
        && c.adc_bits.is_none()
        && c.black_level_dn.is_none()
    {
        return Ok(None);
    }
    let read = c.read_noise_e.unwrap_or(0.0);
    let read = o.number("camera.read_noise_e", read, read >= 0.0, "a read noise ≥ 0 e⁻ rms")?;
    let dark = c.dark_current_e_per_s.unwrap_or(0.0);
    let dark = o.number("camera.dark_current_e_per_s", dark, dark >= 0.0, "a dark current ≥ 0 e⁻/s")?;
    let well = match c.full_well_e {
        // inf: no saturation, as without the key (what `asnr scene` prints for the default)
        Some(w) if w == f64::INFINITY => w,
        Some(w) => o.number("camera.full_well_e", w, w > 0.0, "a full-well capacity > 0 e⁻ (inf for no limit)")?,
        None => f64::INFINITY,
    };
    let sensor = match (c.gain_dn_per_e, c.adc_bits) {
        (Some(k), Some(bits)) => {
            let k = o.number("camera.gain_dn_per_e", k, k > 0.0, "a conversion gain > 0 DN/e⁻")?;
            if !(1..=32).contains(&bits) {
                return Err(o.bad("camera.adc_bits", bits, "a whole number of bits from 1 to 32"));
            }
            let sensor = noise::Sensor::new(read, dark, well, k, bits);
            match (sensor, c.black_level_dn) {
                (Ok(sensor), Some(b)) => {
                    let top = ((1_u64 << bits) - 1) as f64;
                    let b = o.number(
                        "camera.black_level_dn",
                        b,
                        (0.0..top).contains(&b),
                        &format!("a black level ≥ 0 DN and below the ADC's largest output {top} DN"),
                    )?;
                    sensor.with_black_level(b)
                }
                (sensor, _) => sensor,
            }
        }
        (None, None) if c.black_level_dn.is_some() => {
            return Err(o.conflict(
                "camera.black_level_dn",
                "a black level needs an ADC: camera.gain_dn_per_e and camera.adc_bits".to_owned(),
            ));
        }
        (None, None) => noise::Sensor::without_adc(read, dark, well),
        (Some(_), None) => {
            return Err(o.conflict("camera.adc_bits", "camera.gain_dn_per_e needs camera.adc_bits too".to_owned()));
        }
        (None, Some(_)) => {
            return Err(o.conflict("camera.gain_dn_per_e", "camera.adc_bits needs camera.gain_dn_per_e too".to_owned()));
        }
    };
    sensor.map(Some).map_err(|e| o.domain("camera", "[camera]", e))
}

/// The kinds of `[source]` and the keys each takes (besides `kind`).
const SOURCE_KINDS: [(&str, &[&str]); 4] = [
    ("flat", &["radiance_w_m2_sr_nm"]),
    ("blackbody", &["temperature_k", "scale"]),
    ("table", &["csv"]),
    (
        "radiance_meter",
        &[
            "relative_spectrum_csv",
            "power_nw",
            "fiber_core_diameter_um",
            "responsivity_csv",
            "calibration_wavelength_nm",
            "relay_transmission",
            "relay_iris_mm",
            "relay_focal_length_mm",
        ],
    ),
];

fn source(s: &RawSource, o: &Origins) -> Result<Spectrum, Error> {
    let kind = s.kind.as_str();
    let ctx = format!("source.kind = {}", quoted(kind));
    let Some((_, keys)) = SOURCE_KINDS.iter().find(|(k, _)| *k == kind) else {
        return Err(o.bad("source.kind", quoted(kind), "\"flat\", \"blackbody\", \"table\" or \"radiance_meter\""));
    };
    for (key, given) in s.given() {
        if given && !keys.contains(&key) {
            o.forbid(&format!("source.{key}"), &Some(()), &ctx)?;
        }
    }
    match kind {
        "flat" => {
            let key = "source.radiance_w_m2_sr_nm";
            let l = o.require(key, s.radiance_w_m2_sr_nm, "a spectral radiance > 0 W/(m² sr nm)")?;
            // W/(m² sr nm) → W/(m² sr m)
            Ok(Spectrum::Constant(o.number(key, l, l > 0.0, "a spectral radiance > 0 W/(m² sr nm)")? * 1e9))
        }
        "blackbody" => {
            let key = "source.temperature_k";
            let t = o.require(key, s.temperature_k, "a temperature > 0 K")?;
            let t = o.number(key, t, t > 0.0, "a temperature > 0 K")?;
            let scale = s.scale.unwrap_or(1.0);
            let scale = o.number("source.scale", scale, scale > 0.0, "a factor > 0 on the Planck radiance")?;
            let source = Blackbody::new(t).map_err(|e| o.domain(key, key, e))?;
            Ok(Spectrum::Blackbody { source, scale })
        }
        "table" => {
            let key = "source.csv";
            let f = o.require(key, s.csv.as_ref(), "the path of a CSV file: wavelength_nm, W/(m² sr nm)")?;
            let table = o.table(key, f, f64::INFINITY, "spectral radiance", "the path of a CSV file")?;
            Ok(Spectrum::Sampled(table.scaled(1e9)))
        }
        _ => radiance_meter(s, o),
    }
}

/// `[source] kind = "radiance_meter"`: the meter's readings → the target's spectral radiance by
/// SI eq. S1–S6 ([`radiometry::radiance_meter`]); the steps are kept for `--explain`.
fn radiance_meter(s: &RawSource, o: &Origins) -> Result<Spectrum, Error> {
    let positive = |key: &str, v: Option<f64>, expected: &str| -> Result<f64, Error> {
        let v = o.require(key, v, expected)?;
        o.number(key, v, v > 0.0, expected)
    };
    let key = "source.relative_spectrum_csv";
    let expected =
        "the path of a CSV file: wavelength_nm, relative spectral power (the spectrometer's export, any unit, ≥ 0)";
    let f = o.require(key, s.relative_spectrum_csv.as_ref(), expected)?;
    let relative = o.table(key, f, f64::INFINITY, "relative spectral power", "the path of a CSV file")?;
    let power = positive("source.power_nw", s.power_nw, "the power meter's reading > 0 nW")?;
    let core = positive("source.fiber_core_diameter_um", s.fiber_core_diameter_um, "a fiber core diameter > 0 µm")?;
    let key = "source.responsivity_csv";
    let expected = "the path of a CSV file: wavelength_nm, the power meter's responsivity (A/W or relative, ≥ 0)";
    let f = o.require(key, s.responsivity_csv.as_ref(), expected)?;
    let responsivity = o.table(key, f, f64::INFINITY, "responsivity", "the path of a CSV file")?;
    let key = "source.calibration_wavelength_nm";
    let cal = positive(key, s.calibration_wavelength_nm, "the meter's calibration wavelength > 0 nm")?;
    o.wavelength(key, cal);
    let (lo, hi) = responsivity.range();
    let r_cal = responsivity.value(cal * 1e-9);
    if !(cal * 1e-9 >= lo && cal * 1e-9 <= hi && r_cal > 0.0) {
        return Err(o.bad(
            key,
            num(cal),
            &format!(
                "a wavelength where the responsivity table ({}) is > 0: it covers {}–{} nm",
                shorten(&quoted(s.responsivity_csv.as_deref().unwrap_or_default())),
                rounded(lo * 1e9),
                rounded(hi * 1e9)
            ),
        ));
    }
    let t = s.relay_transmission;
    let t = o.require("source.relay_transmission", t, "the relay lenses' transmission in (0, 1]")?;
    let t =
        o.number("source.relay_transmission", t, t > 0.0 && t <= 1.0, "the relay lenses' transmission in (0, 1]")?;
    let iris = positive("source.relay_iris_mm", s.relay_iris_mm, "the relay iris diameter > 0 mm")?;
    let focal = positive("source.relay_focal_length_mm", s.relay_focal_length_mm, "the relay focal length > 0 mm")?;
    let meter = radiometry::RadianceMeter {
        relative_spectrum: relative,
        power_w: power * 1e-9,
        fiber_core_diameter_m: core * 1e-6,
        responsivity,
        calibration_wavelength_m: cal * 1e-9,
        relay_transmission: t,
        relay_iris_m: iris * 1e-3,
        relay_focal_length_m: focal * 1e-3,
    };
    let steps = radiometry::radiance_meter(&meter)
        .map_err(|e| o.domain("source", "[source] kind = \"radiance_meter\" (SI eq. S1–S6)", e))?;
    let radiance = Spectrum::Sampled(steps.radiance.clone());
    o.meter.replace(Some(steps));
    Ok(radiance)
}

fn filter(s: &RawSpectrum, o: &Origins) -> Result<Option<Spectrum>, Error> {
    let shape = s.shape.as_str();
    let ctx = format!("spectrum.shape = {}", quoted(shape));
    let band = |o: &Origins| -> Result<(f64, f64, f64), Error> {
        o.forbid("spectrum.csv", &s.csv, &ctx)?;
        let c = o.require("spectrum.center_nm", s.center_nm, "a wavelength > 0 nm")?;
        let c = o.number("spectrum.center_nm", c, c > 0.0, "a wavelength > 0 nm")?;
        o.wavelength("spectrum.center_nm", c);
        let r = o.require("spectrum.range_nm", s.range_nm, "a width > 0 nm")?;
        // in metres too: 1e-320 nm is 0 m
        let r = o.number("spectrum.range_nm", r, r * 1e-9 > 0.0, "a width > 0 nm (at least 1e-300 nm)")?;
        let p = s.peak.unwrap_or(1.0);
        let p = o.number("spectrum.peak", p, p > 0.0 && p <= 1.0, "a transmission in (0, 1]")?;
        Ok((c * 1e-9, r * 1e-9, p))
    };
    Ok(match shape {
        "gaussian" => {
            let (c, r, p) = band(o)?;
            // σ = range/(2√2) at least radiometry's 1e-10 of the centre (narrower is a line)
            let least = 2.0 * std::f64::consts::SQRT_2 * radiometry::MIN_RELATIVE_SIGMA * c;
            if r < least {
                return Err(o.bad(
                    "spectrum.range_nm",
                    num(s.range_nm.unwrap_or(r * 1e9)),
                    &format!(
                        "a width of at least {:e} nm (2√2 × 1e-10 of spectrum.center_nm: no wavelength grid resolves a narrower Gaussian; use spectrum.shape = \"line\")",
                        least * 1e9
                    ),
                ));
            }
            Some(Spectrum::Gaussian(Gaussian::from_range(c, r, p).map_err(|e| o.domain("spectrum", "[spectrum]", e))?))
        }
        "tophat" => {
            let (c, r, p) = band(o)?;
            if c - 0.5 * r <= 0.0 {
                return Err(o.bad(
                    "spectrum.range_nm",
                    num(s.range_nm.unwrap_or(r * 1e9)),
                    "a full width under twice spectrum.center_nm (the band must stay at λ > 0)",
                ));
            }
            Some(Spectrum::TopHat(
                TopHat::new(c - 0.5 * r, c + 0.5 * r, p).map_err(|e| o.domain("spectrum", "[spectrum]", e))?,
            ))
        }
        "line" => {
            // one wavelength for the optics; range_nm is the equivalent width that sets the
            // photon count (∫T dλ = peak × range, as for the other shapes)
            o.forbid("spectrum.csv", &s.csv, &ctx)?;
            let c = o.require("spectrum.center_nm", s.center_nm, "the line's wavelength > 0 nm")?;
            let c = o.number("spectrum.center_nm", c, c > 0.0, "the line's wavelength > 0 nm")?;
            o.wavelength("spectrum.center_nm", c);
            let width = "the equivalent width > 0 nm of the band (∫T dλ / T_peak; it sets the photon count)";
            let r = o.require("spectrum.range_nm", s.range_nm, width)?;
            let r = o.number("spectrum.range_nm", r, r > 0.0, width)?;
            if r >= 2.0 * c {
                return Err(o.bad(
                    "spectrum.range_nm",
                    num(r),
                    "an equivalent width under twice spectrum.center_nm (the band must stay at λ > 0)",
                ));
            }
            let p = s.peak.unwrap_or(1.0);
            let p = o.number("spectrum.peak", p, p > 0.0 && p <= 1.0, "a transmission in (0, 1]")?;
            Some(Spectrum::Line(Line::new(c * 1e-9, r * 1e-9, p).map_err(|e| o.domain("spectrum", "[spectrum]", e))?))
        }
        "table" => {
            for (k, v) in
                [("spectrum.center_nm", s.center_nm), ("spectrum.range_nm", s.range_nm), ("spectrum.peak", s.peak)]
            {
                o.forbid(k, &v, &ctx)?;
            }
            let f = o.require("spectrum.csv", s.csv.as_ref(), "the path of a CSV file: wavelength_nm, transmission")?;
            Some(Spectrum::Sampled(o.table("spectrum.csv", f, 1.0, "transmission", "the path of a CSV file")?))
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
                quoted(other),
                "\"gaussian\", \"tophat\", \"line\" (one wavelength), \"table\" or \"none\"",
            ));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resolved_toml;

    /// A prepared scene's point is the scene built the whole way (the reference: the merged TOML
    /// deserialized and built at each point, `build_with_warnings`): the same evaluation to the
    /// bit, the same plausibility warnings in the same order, and a refusal where that refuses.
    #[test]
    fn a_prepared_point_is_the_scene_built_the_whole_way() {
        let paper = read(None).unwrap();
        let set = |keys: &[&str], values: &[f64]| -> Vec<String> {
            keys.iter().zip(values).map(|(k, v)| crate::sweep::assignment(k, *v)).collect()
        };
        let cases: [(&[&str], &[&[f64]]); 3] = [
            // the map's keys; a band of 1e-3 nm and F/40
            (&["lens.f_number", "spectrum.range_nm"], &[&[2.5, 50.0], &[1.4, 300.0], &[40.0, 1e-3], &[5.0, 2.0]]),
            // sections the file does not hold ([field]) and the unit-slip warnings (5e-3 µm, 1e5 ms)
            (
                &["camera.pixel_pitch_um", "exposure.time_ms", "field.x_deg", "spectrum.center_nm"],
                &[&[5.2, 1.23, 0.0, 800.0], &[5e-3, 1e5, 3.0, 550.0], &[2.0, 10.0, 1.5, 2e4]],
            ),
            // an integer key of [options]
            (&["options.pupil_samples", "lens.focal_length_mm"], &[&[64.0, 3.36], &[128.0, 1.0]]),
        ];
        let fixed = ["source.radiance_w_m2_sr_nm=0.05".to_owned()];
        for (keys, points) in cases {
            let keys: Vec<String> = keys.iter().map(|k| (*k).to_owned()).collect();
            let mut first = fixed.to_vec();
            first.extend(set(&keys.iter().map(String::as_str).collect::<Vec<_>>(), points[0]));
            let prepared = Prepared::new(&paper, &first, &keys).expect("the paper scene's keys are prepared");
            // (twice over: the second time each section comes from those the first deserialized)
            for values in points.iter().chain(points) {
                let assignments = set(&keys.iter().map(String::as_str).collect::<Vec<_>>(), values);
                let mut all = fixed.to_vec();
                all.extend(assignments.iter().cloned());
                let whole = build_with_warnings(&paper, &all).unwrap();
                let fast = prepared.build(values).expect("a valid point is built prepared");
                assert_eq!(fast.warnings, whole.warnings, "{keys:?} = {values:?}");
                let (a, b) = match (metric::evaluate(&fast.scene), metric::evaluate(&whole.scene)) {
                    (Ok(a), Ok(b)) => (a, b),
                    // (a pixel of 5 nm: the defocus phase at its Nyquist frequency is refused)
                    (a, b) => {
                        assert_eq!(format!("{:?}", a.err()), format!("{:?}", b.err()));
                        continue;
                    }
                };
                assert_eq!(
                    [a.mean_mtf, a.snr0, a.asnr, a.photoelectrons].map(f64::to_bits),
                    [b.mean_mtf, b.snr0, b.asnr, b.photoelectrons].map(f64::to_bits),
                    "{keys:?} = {values:?}"
                );
                assert_eq!(a.warnings, b.warnings);
            }
            // a refused value: no prepared scene (the whole way then names the error)
            let mut bad = points[0].to_vec();
            bad[0] = -1.0;
            let assignments = set(&keys.iter().map(String::as_str).collect::<Vec<_>>(), &bad);
            assert!(prepared.build(&bad).is_none(), "{keys:?} = {bad:?}");
            assert!(prepared.build(&bad).is_none(), "{keys:?} = {bad:?}, again");
            assert!(prepared.build(&bad[1..]).is_none(), "too few values");
            let mut all = fixed.to_vec();
            all.extend(assignments);
            assert!(build_with_warnings(&paper, &all).is_err());
        }
        // keys it does not set: a list entry, a table, the top level, a preset's lens
        let none = |source: &Source, keys: &[&str], values: &[&str]| {
            let keys: Vec<String> = keys.iter().map(|k| (*k).to_owned()).collect();
            let set: Vec<String> = keys.iter().zip(values).map(|(k, v)| format!("{k}={v}")).collect();
            Prepared::new(source, &set, &keys).is_none()
        };
        assert!(none(&paper, &["lens.binary2[0]"], &["1"]));
        assert!(none(&paper, &["lens"], &["1"]));
        assert!(none(&paper, &["title"], &["1"]));
        assert!(none(&paper, &["designs.lens.f_number"], &["1"]));
        let preset =
            Source::from_text(PAPER_SCENE.replace("model = \"chromatic\"", "preset = \"paper-chromatic\""), "p", ".");
        assert!(build_from(&preset, &[]).is_ok());
        assert!(none(&preset, &["lens.f_number"], &["2"]));
        assert!(!none(&paper, &["lens.f_number"], &["2"]));
    }

    /// A sweep's scenes read each CSV table once: a second build of one source takes the table
    /// from its cache while the file's length and modification time are unchanged (here the
    /// file is rewritten with other values of the same length and its time set back: the cached
    /// values stay), and reads it again when they change.
    #[test]
    fn a_sources_tables_are_read_once_while_unchanged() {
        let dir = std::env::temp_dir().join(format!("scene-table-cache-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let qe = dir.join("qe.csv");
        std::fs::write(&qe, "wavelength_nm,qe\n700,0.20\n900,0.20\n").unwrap();
        let text = include_str!("../../examples/paper-theory.toml")
            .replace("quantum_efficiency = 0.2 ", "quantum_efficiency = \"qe.csv\" ");
        let source = Source::from_text(text, "cached.toml", &dir);
        let photoelectrons = |s: &Source| metric::evaluate(&build_from(s, &[]).unwrap()).unwrap().photoelectrons;
        let first = photoelectrons(&source);
        let time = std::fs::metadata(&qe).unwrap().modified().unwrap();
        std::fs::write(&qe, "wavelength_nm,qe\n700,0.40\n900,0.40\n").unwrap();
        std::fs::File::options().write(true).open(&qe).unwrap().set_modified(time).unwrap();
        assert_eq!(photoelectrons(&source), first, "the cached table");
        std::fs::write(&qe, "wavelength_nm,qe\n700,0.4\n900,0.4\n").unwrap();
        let again = photoelectrons(&source);
        assert!((again / first - 2.0).abs() < 1e-9, "{again} vs {first}: the file changed, read again");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Several overrides reach one key: the one that gave it is blamed, not the table above it;
    /// a table given after a key inside it (which it would drop) is refused.
    #[test]
    fn the_override_that_gave_a_key_is_blamed_and_none_is_dropped() {
        let table = "spectrum={shape=\"gaussian\",center_nm=800.0,range_nm=50.0,peak=1.0}".to_owned();
        let e = load(None, &[table.clone(), "spectrum.range_nm=-5".to_owned()]).unwrap_err().to_string();
        assert!(e.starts_with("embedded paper scene (--set spectrum.range_nm=-5): spectrum.range_nm = -5"), "{e}");
        let e = load(None, &["spectrum.range_nm=-5".to_owned(), table]).unwrap_err().to_string();
        assert!(e.contains("it replaces the table spectrum, dropping spectrum.range_nm given before it by --set spectrum.range_nm=-5"), "{e}");
    }

    /// The plain-number fast path reads what TOML reads, value and type, and leaves everything
    /// else to the TOML parser (which reads it as before, or not at all).
    #[test]
    fn plain_numbers_read_as_toml_reads_them() {
        let toml =
            |text: &str| toml::from_str::<toml::Table>(&format!("v = {text}")).ok().and_then(|mut t| t.remove("v"));
        for text in
            ["0", "7", "-3", "+12", "1.4", "-0.25", "1e-7", "2.5E+3", "6.02e23", "5e-324", "0.1", "9223372036854775807"]
        {
            assert_eq!(plain_number(text), toml(text), "{text}");
            assert!(plain_number(text).is_some(), "{text}");
        }
        // not plain: TOML's own reading (or refusal) stands
        for text in [
            "1e400",
            "01",
            "1.",
            ".5",
            "1e",
            "1_000",
            "inf",
            "nan",
            "0x1f",
            "1.2.3",
            "--1",
            "1e+",
            "",
            "-",
            "9223372036854775808",
            "2.8 # x",
        ] {
            assert_eq!(plain_number(text), None, "{text}");
        }
    }

    #[test]
    fn number_prefixes_and_units() {
        assert_eq!(number_prefix("800nm"), Some("800"));
        assert_eq!(number_prefix(" 5.2 um"), Some("5.2"));
        assert_eq!(number_prefix("1e-3s"), Some("1e-3"));
        assert_eq!(number_prefix("2.8e"), Some("2.8"));
        assert_eq!(number_prefix("fast"), None);
        assert_eq!(number_prefix("inf"), None);
        assert_eq!(number_prefix("e5"), None);
        assert_eq!(unit_of("spectrum.center_nm"), " in nm");
        assert_eq!(unit_of("source.radiance_w_m2_sr_nm"), " in W/(m² sr nm)");
        assert_eq!(unit_of("camera.dark_current_e_per_s"), " in e⁻/s");
        assert_eq!(unit_of("fields[0].x_deg"), " in degrees");
        assert_eq!(unit_of("lens.sector_deg[1]"), " in degrees");
        assert_eq!(unit_of("lens.f_number"), "");
    }

    /// The resolved TOML of every example scene builds to the same scene: same ASNR, bit for bit;
    /// and `resolved_and_built` gives that TOML with `build_from`'s scene (the same ASNR).
    #[test]
    fn resolved_examples_load_to_the_same_asnr() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
        for name in
            ["paper-theory.toml", "monochromatic.toml", "decentred-iris.toml", "harmonic.toml", "radiance-meter.toml"]
        {
            let source = read(Some(&root.join(name))).unwrap();
            let text = resolved_toml(&source, &[]).unwrap().toml;
            let again = Source::from_text(text.clone(), "resolved", std::env::temp_dir());
            let a = metric::evaluate(&build_from(&source, &[]).unwrap()).unwrap();
            let b = metric::evaluate(&build_from(&again, &[]).unwrap()).unwrap();
            assert_eq!(a.asnr, b.asnr, "{name}:\n{text}");
            // and it is a fixed point: resolving the resolved scene changes only the header
            let twice = resolved_toml(&again, &[]).unwrap().toml;
            let body = |t: &str| t.lines().filter(|l| !l.starts_with("# From")).collect::<Vec<_>>().join("\n");
            assert_eq!(body(&twice), body(&text), "{name}");
            let (resolved, built) = crate::resolved_and_built(&source, &[]).unwrap();
            assert_eq!(body(&resolved.toml), body(&text), "{name}");
            assert_eq!(metric::evaluate(&built).unwrap().asnr.to_bits(), a.asnr.to_bits(), "{name}");
        }
    }

    /// `options.table_rule` (docs/physics.md, "The radial engine"): "tensor" by default, "split"
    /// taken, reaching the engine's settings and the resolved scene; another value refused naming
    /// the key, the value and what is accepted.
    #[test]
    fn table_rule_is_read_and_refused_naming_the_key() {
        use optics::radial::TableRule;
        let source = Source::from_text(PAPER_SCENE, "p.toml", std::env::temp_dir());
        let rule = |set: &[&str]| {
            let set: Vec<String> = set.iter().map(|s| (*s).to_owned()).collect();
            build_from(&source, &set).map(|s| s.options().settings().table_rule)
        };
        assert_eq!(rule(&[]).unwrap(), TableRule::Tensor);
        assert_eq!(rule(&["options.table_rule=\"tensor\""]).unwrap(), TableRule::Tensor);
        assert_eq!(rule(&["options.table_rule=\"split\""]).unwrap(), TableRule::Split);
        let e = rule(&["options.table_rule=\"spline\""]).unwrap_err().to_string();
        assert!(
            e.contains("options.table_rule = \"spline\": expected \"tensor\"") && e.contains("or \"split\""),
            "{e}"
        );
        let text = |set: &[&str]| {
            let set: Vec<String> = set.iter().map(|s| (*s).to_owned()).collect();
            resolved_toml(&source, &set).unwrap().toml
        };
        assert!(text(&[]).contains("table_rule = \"tensor\""), "{}", text(&[]));
        assert!(text(&["options.table_rule=\"split\""]).contains("table_rule = \"split\""));
    }

    /// A scene with a radiance-meter source on the hand-worked tables of
    /// `radiometry/tests/radiometry.rs` (`radiance_meter_s1_to_s6_worked_by_hand`), in a folder
    /// of its own; `extra` replaces lines of `[source]`.
    fn meter_scene(name: &str, edits: &[(&str, &str)]) -> (String, PathBuf) {
        let dir = std::env::temp_dir().join(format!("scene-meter-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("rel.csv"), "wavelength_nm,counts\n800,2\n810,4\n820,2\n").unwrap();
        std::fs::write(dir.join("resp.csv"), "wavelength_nm,a_per_w\n800,0.5\n810,0.5\n820,1.0\n").unwrap();
        let mut source = "[source]\nkind = \"radiance_meter\"\nrelative_spectrum_csv = \"rel.csv\"\npower_nw = 10\n\
                          fiber_core_diameter_um = 400\nresponsivity_csv = \"resp.csv\"\ncalibration_wavelength_nm = 810\n\
                          relay_transmission = 0.8\nrelay_iris_mm = 10\nrelay_focal_length_mm = 50\n"
            .to_owned();
        for (from, to) in edits {
            assert!(source.contains(from), "{from}");
            source = source.replacen(from, to, 1);
        }
        let text = format!(
            "[lens]\nf_number = 2.5\nfocal_length_mm = 3.36\ndesign_wavelength_nm = 800.0\nefficiency = 0.15\n\
             transmission = 0.55\n\n{source}\n[camera]\npixel_pitch_um = 5.2\nquantum_efficiency = 0.2\n\n\
             [exposure]\ntime_ms = 1.23\n"
        );
        (text, dir)
    }

    /// `lens.relative_illumination` (every family's key, default none): cos⁴θ at 10° scales the
    /// signal by cos⁴10° = 0.940 609 and changes nothing on axis; a table (field_deg, RI)
    /// interpolates (0.875 at 15° between 0.95 at 10° and 0.8 at 20°) and must reach every field
    /// point; a value outside [0, 1], NaN or an unknown word is refused with the file, the key
    /// and the value; `asnr scene` writes it back and it loads to the same scene.
    #[test]
    fn relative_illumination_is_every_familys_key() {
        let dir = std::env::temp_dir().join(format!("scene-ri-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("ri.csv"), "field_deg,ri\n0,1\n10,0.95\n20,0.8\n").unwrap();
        let source = Source::from_text(PAPER_SCENE, "p.toml", &dir);
        let build = |set: &[&str]| build_from(&source, &set.iter().map(|s| s.to_string()).collect::<Vec<_>>());
        let signal = |set: &[&str]| metric::evaluate(&build(set).unwrap()).unwrap().photoelectrons;
        let axis = signal(&[]);
        assert_eq!(signal(&["lens.relative_illumination=\"cos4\""]), axis);
        let off = signal(&["field.x_deg=10"]);
        let cos4 = signal(&["field.x_deg=10", "lens.relative_illumination=\"cos4\""]);
        assert!((cos4 / off - 10f64.to_radians().cos().powi(4)).abs() < 1e-15, "{}", cos4 / off);
        let table = signal(&["field.x_deg=15", "lens.relative_illumination=\"ri.csv\""]);
        assert!((table / off - 0.875).abs() < 1e-12, "{}", table / off);
        assert!((signal(&["lens.relative_illumination=0.5"]) / axis - 0.5).abs() < 1e-15);
        // every family's key: the harmonic lens takes it too
        let harmonic =
            build(&["lens.model=\"harmonic\"", "lens.design_order=5", "lens.relative_illumination=\"cos4\""]).unwrap();
        assert_eq!(harmonic.relative_illumination(), &metric::RelativeIllumination::Cos4);
        for (value, shown) in [("-0.1", "-0.1"), ("1.5", "1.5"), ("nan", "NaN"), ("\"cos3\"", "\"cos3\"")] {
            let e = build(&[&format!("lens.relative_illumination={value}")]).unwrap_err().to_string();
            assert!(e.contains(&format!("p.toml (--set lens.relative_illumination={value}): lens.relative_illumination = {shown}: expected \"none\"")), "{e}");
        }
        let e = build(&["field.x_deg=25", "lens.relative_illumination=\"ri.csv\""]).unwrap_err().to_string();
        assert!(
            e.contains("lens.relative_illumination = \"ri.csv\"") && e.contains("field is at 25° from the axis"),
            "{e}"
        );
        std::fs::write(dir.join("bad.csv"), "field_deg,ri\n0,1\n10,1.2\n").unwrap();
        let e = build(&["lens.relative_illumination=\"bad.csv\""]).unwrap_err().to_string();
        assert!(
            e.contains("lens.relative_illumination = \"bad.csv\"") && e.contains("line 3: relative illumination 1.2"),
            "{e}"
        );
        let set = ["field.x_deg=15".to_owned(), "lens.relative_illumination=\"ri.csv\"".to_owned()];
        let resolved = resolved_toml(&source, &set).unwrap().toml;
        assert!(
            resolved.contains(&format!("relative_illumination = \"{}\"", dir.join("ri.csv").display())),
            "{resolved}"
        );
        let again = build_from(&Source::from_text(resolved, "r", std::env::temp_dir()), &[]).unwrap();
        assert_eq!(metric::evaluate(&again).unwrap().photoelectrons, table);
        let plain = resolved_toml(&source, &[]).unwrap().toml;
        assert!(plain.contains("relative_illumination = \"none\""), "{plain}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The radiance-meter source gives the target radiance of the hand-worked example: S1 ∫E_rel
    /// = 60 nm, S2 E = 1/(4π) W/m², S3 corr = 1/6 + ln 2, S4 E_acc = 0.0684218 W/m², S5 E_λ(810 nm)
    /// = 4/6e-8 m × E_acc = 4.561454e6 W/(m² m), S6 × 125/π: L(810 nm) = 1.814945e8 W/(m² sr m)
    /// (every step worked on paper in radiometry's test); through the scene's units (nW, µm,
    /// mm, nm) to 1e-14.
    #[test]
    fn a_radiance_meter_source_gives_the_hand_worked_radiance() {
        let (text, dir) = meter_scene("ok", &[]);
        let loaded = build_with_warnings(&Source::from_text(text.clone(), "m.toml", &dir), &[]).unwrap();
        let l = loaded.scene.radiance();
        let want = 1.814_944_931_522_343_8e8;
        assert!((l.value(810e-9) / want - 1.0).abs() < 1e-14, "{l:?}");
        assert!((l.value(805e-9) / (0.75 * want) - 1.0).abs() < 1e-14);
        assert_eq!(l.value(830e-9), 0.0);
        let steps = loaded.radiance_meter.unwrap();
        assert!((steps.relative_integral / 6e-8 - 1.0).abs() < 1e-14);
        assert!((steps.fiber_irradiance_w_m2 * 4.0 * std::f64::consts::PI - 1.0).abs() < 1e-14);
        assert!((steps.correction / (1.0 / 6.0 + 2f64.ln()) - 1.0).abs() < 1e-14);
        assert!((steps.corrected_irradiance_w_m2 / 0.068_421_811_962_487_5 - 1.0).abs() < 1e-14);
        assert!((steps.relay_factor_per_sr * std::f64::consts::PI / 125.0 - 1.0).abs() < 1e-14);
        // other sources carry no steps
        assert!(build_with_warnings(&Source::from_text(PAPER_SCENE, "p", "."), &[]).unwrap().radiance_meter.is_none());
        // `asnr scene` writes every key back, paths absolute, and it loads to the same radiance
        let resolved = resolved_toml(&Source::from_text(text, "m.toml", &dir), &[]).unwrap().toml;
        assert!(
            resolved.contains("power_nw = 10.0\n") && resolved.contains("relay_focal_length_mm = 50.0\n"),
            "{resolved}"
        );
        let again = build_from(&Source::from_text(resolved, "r", std::env::temp_dir()), &[]).unwrap();
        assert_eq!(again.radiance().value(810e-9), l.value(810e-9));
    }

    /// Every bad key or value of a radiance-meter source is named with the file, the key, the
    /// value and what is accepted; missing files name the key and the path.
    #[test]
    fn radiance_meter_errors_name_the_key() {
        let error = |name: &str, edits: &[(&str, &str)]| {
            let (text, dir) = meter_scene(name, edits);
            build_from(&Source::from_text(text, "m.toml", &dir), &[]).unwrap_err().to_string()
        };
        type Case<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a str);
        let cases: [Case; 11] = [
            (
                "power",
                &[("power_nw = 10", "power_nw = 0")],
                "m.toml: source.power_nw = 0: expected the power meter's reading > 0 nW",
            ),
            (
                "core",
                &[("fiber_core_diameter_um = 400", "fiber_core_diameter_um = -4")],
                "m.toml: source.fiber_core_diameter_um = -4: expected a fiber core diameter > 0 µm",
            ),
            (
                "t",
                &[("relay_transmission = 0.8", "relay_transmission = 1.2")],
                "m.toml: source.relay_transmission = 1.2: expected the relay lenses' transmission in (0, 1]",
            ),
            (
                "iris",
                &[("relay_iris_mm = 10", "relay_iris_mm = 0")],
                "m.toml: source.relay_iris_mm = 0: expected the relay iris diameter > 0 mm",
            ),
            (
                "focal",
                &[("relay_focal_length_mm = 50\n", "")],
                "m.toml: source.relay_focal_length_mm is missing: expected the relay focal length > 0 mm",
            ),
            (
                "cal",
                &[("calibration_wavelength_nm = 810", "calibration_wavelength_nm = 900")],
                "m.toml: source.calibration_wavelength_nm = 900: expected a wavelength where the responsivity table (\"resp.csv\") is > 0: it covers 800–820 nm",
            ),
            ("file", &[("\"rel.csv\"", "\"nope.csv\"")], "source.relative_spectrum_csv"),
            (
                "foreign",
                &[("power_nw = 10", "power_nw = 10\nscale = 2")],
                "m.toml: source.scale does not apply to source.kind = \"radiance_meter\"",
            ),
            (
                "kind",
                &[("\"radiance_meter\"", "\"radiance-meter\"")],
                "m.toml: source.kind = \"radiance-meter\": expected \"flat\", \"blackbody\", \"table\" or \"radiance_meter\"",
            ),
            ("unit", &[("power_nw = 10", "power_nw = \"10nW\"")], "source.power_nw"),
            ("unknown", &[("power_nw = 10", "power_nw = 10\npower_uw = 1")], "power_uw"),
        ];
        for (name, edits, want) in cases {
            let got = error(name, edits);
            assert!(got.contains(want), "{name}: {got}\n  wanted: {want}");
        }
        // the responsivity is zero inside the spectrum's band: the chain refuses it (S3)
        let (text, dir) = meter_scene("zero", &[]);
        std::fs::write(dir.join("resp.csv"), "800,0.5\n810,0.5\n815,0.0\n820,0.0\n").unwrap();
        let got = build_from(&Source::from_text(text, "m.toml", &dir), &[]).unwrap_err().to_string();
        assert!(
            got.contains("[source] kind = \"radiance_meter\"") && got.contains("responsivity must be > 0"),
            "{got}"
        );
        // a missing file says which file and which key
        let got = error("missing", &[("\"resp.csv\"", "\"gone.csv\"")]);
        assert!(got.contains("source.responsivity_csv") && got.contains("gone.csv"), "{got}");
        // a key of the radiance meter under another kind is refused naming the kind
        let text = PAPER_SCENE.replacen("radiance_w_m2_sr_nm = 0.025", "radiance_w_m2_sr_nm = 0.025\npower_nw = 3", 1);
        let got = build_from(&Source::from_text(text, "f.toml", "."), &[]).unwrap_err().to_string();
        assert_eq!(got, "f.toml: source.power_nw does not apply to source.kind = \"flat\"");
    }

    /// A table whose wavelengths all lie below 100 nm was typed in µm: valid, and warned about.
    #[test]
    fn a_table_in_micrometres_is_warned_about() {
        let dir = std::env::temp_dir().join(format!("scene-load-um-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("qe.csv"), "0.65,0.2\n1.0,0.1\n").unwrap();
        let text = PAPER_SCENE.replacen("quantum_efficiency = 0.2", "quantum_efficiency = \"qe.csv\"", 1);
        // such a table detects no light in the band: the error names the likely slip with it
        let error = build_with_warnings(&Source::from_text(text, "s.toml", &dir), &[]).unwrap_err();
        let Error::WithWarnings { error: cause, warnings } = &error else { panic!("{error}") };
        assert!(cause.to_string().contains("no detected signal"), "{cause}");
        let shown: Vec<String> = warnings.iter().map(ToString::to_string).collect();
        assert_eq!(
            shown,
            [
                "s.toml: camera.quantum_efficiency = \"qe.csv\": its wavelengths 0.65–1 nm are all outside 100–20000 nm: looks like µm (650–1000 nm?)"
            ]
        );
        assert!(
            error.to_string().contains("note, values that look like a unit slip: s.toml: camera.quantum_efficiency")
        );
        assert!(build_with_warnings(&Source::from_text(PAPER_SCENE, "p", "."), &[]).unwrap().warnings.is_empty());
    }

    #[test]
    fn whole_numbers_and_types_are_named() {
        let paper = Source::from_text(PAPER_SCENE, "p", ".");
        let e = build_from(&paper, &["options.pupil_samples=256.5".to_owned()]).unwrap_err().to_string();
        assert!(
            e.ends_with("options.pupil_samples: invalid type: floating point `256.5`, expected u32 (a whole number)"),
            "{e}"
        );
        let e = build_from(&paper, &["spectrum.center_nm=true".to_owned()]).unwrap_err().to_string();
        assert!(e.ends_with("expected f64 (a number in nm)"), "{e}");
    }

    #[test]
    fn toml_errors_quote_a_short_excerpt() {
        let text = format!("title = \"x\"\n[lens\n{}", "y".repeat(10_000));
        let e = build_from(&Source::from_text(text, "big.toml", "."), &[]).unwrap_err().to_string();
        assert!(e.starts_with("big.toml: malformed TOML at line 2, column "), "{e}");
        assert!(e.contains("`[lens`"), "{e}");
        assert!(e.len() < 300, "{e}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 512, ..Default::default() })]

        /// Any finite value of any numeric key, by --set, loads or is refused with a message
        /// naming the key: never a panic. (Magnitudes from 1e-300 to 1e300: robustness, not physics.)
        #[test]
        fn any_finite_value_loads_or_names_its_key(
            index in 0usize..NUMERIC_KEYS.len(),
            mantissa in -10.0f64..10.0,
            exponent in -300i32..300,
        ) {
            let key = NUMERIC_KEYS[index];
            let value = mantissa * 10f64.powi(exponent);
            let paper = Source::from_text(PAPER_SCENE, "p", ".");
            let set = format!("{key}={value:e}");
            match build_with_warnings(&paper, std::slice::from_ref(&set)) {
                Ok(loaded) => {
                    for w in &loaded.warnings {
                        proptest::prop_assert!(w.key == key, "{w}");
                    }
                }
                Err(e) => {
                    let m = e.to_string();
                    proptest::prop_assert!(m.contains(key) || m.contains("[lens]") || m.contains("[camera]") || m.contains("[spectrum]"), "{set}: {m}");
                }
            }
        }
    }

    const NUMERIC_KEYS: [&str; 24] = [
        "lens.f_number",
        "lens.focal_length_mm",
        "lens.design_wavelength_nm",
        "lens.efficiency",
        "lens.transmission",
        "lens.iris_decentre_x",
        "lens.obscuration",
        "lens.spherical_um",
        "lens.coma_um",
        "source.radiance_w_m2_sr_nm",
        "spectrum.center_nm",
        "spectrum.range_nm",
        "spectrum.peak",
        "camera.pixel_pitch_um",
        "camera.quantum_efficiency",
        "camera.read_noise_e",
        "camera.dark_current_e_per_s",
        "camera.full_well_e",
        "exposure.time_ms",
        "options.fraunhofer_threshold_mm",
        "options.fraunhofer_max_fraction",
        "options.tolerance",
        "field.x_deg",
        "field.y_deg",
    ];
}
