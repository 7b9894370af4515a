//! Comparison files: several lens designs under one scene (`asnr compare`).
//!
//! A comparison file is a scene file without `[lens]` and with `[[designs]]`, each a `name` and
//! a `lens` table (`[designs.lens]` or inline) with the keys of a `[lens]` table. Every design
//! shares the file's `[source]`, `[spectrum]`, `[camera]`, `[exposure]`, `[options]` and
//! `[field]`: the same scene, sensor and exposure, and (unless `allow_different_focal_lengths =
//! true`) the same focal length, so that the designs differ in the lens alone (docs/physics.md,
//! "Lens families": a fair comparison keeps the focal length, sensor, scene and exposure).
//!
//! ```
//! // the embedded comparison (examples/designs.toml), one design made slower
//! let set = ["designs[1].lens.f_number=4".to_owned()];
//! let comparison = scene::load_comparison(None, &set).unwrap();
//! assert_eq!(comparison.designs[0].kind, "chromatic");
//! assert_eq!(comparison.designs[1].scene.lens().f_number(), 4.0);
//! // the paper's lens has N_z = f0/(8F#²λ0) = 84 Fresnel zones: its twin band is λ0/(2N_z) = 4.76 nm
//! assert!((comparison.designs[0].fresnel_zones - 84.0).abs() < 1e-9);
//! ```

use std::path::Path;
use std::sync::Arc;

use lenses::{ChromaticMetalens, Curve};
use metric::Scene;

use crate::error::{Error, Warning, num, quoted};
use crate::load::{Source, build_parts, merged, raw_scene};
use crate::origins::Origins;

/// The built-in comparison of the lens families at the paper's focal length, sensor, scene and
/// exposure (`examples/designs.toml`), embedded as the paper scene is.
pub const DESIGNS_SCENE: &str = include_str!("../../examples/designs.toml");

/// How messages name the embedded comparison.
const EMBEDDED: &str = "embedded design comparison";

/// One design of a comparison.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Design {
    /// Its `name`.
    pub name: String,
    /// Its family: `chromatic`, `refractive`, `dispersion-engineered`, `harmonic`,
    /// `multiplexed-interleaved`, `multiplexed-segmented` or `tabulated`.
    pub kind: &'static str,
    /// The file's scene with this design's lens.
    pub scene: Scene,
    /// The chromatic twin: a chromatic lens of the same F-number and focal length, designed for
    /// the scene's centre wavelength λc, with this lens's efficiency τ(λc) and transmission
    /// T(λc) there, in the same scene.
    pub twin: Scene,
    /// The Fresnel zones of the aperture, `N_z = R²/(2 f0 λ0) = f0/(8F#²λ0)`, λ0 the design
    /// wavelength (the band's centre for an achromat, the channels' centre for a multiplexed lens).
    pub fresnel_zones: f64,
    /// The band a chromatic lens of this aperture keeps sharp, `λ0/(2N_z)`, nm.
    pub twin_band_nm: f64,
    /// The design wavelength λ0 used for `fresnel_zones`, nm.
    pub design_wavelength_nm: f64,
    /// A multiplexed lens's channel wavelengths, nm (empty otherwise).
    pub channels_nm: Vec<f64>,
    /// Facts of the design (group delay and β, glass and transmission, channels).
    pub notes: Vec<String>,
}

/// The designs of a comparison file, built.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Comparison {
    /// The file's `title`.
    pub title: Option<String>,
    /// How messages name the file.
    pub label: String,
    /// The designs, in file order.
    pub designs: Vec<Design>,
    /// Values that look like a unit slip (each once).
    pub warnings: Vec<Warning>,
    /// The shared spectrum's `center_nm` and `range_nm`, when it has them (a band-pass shape).
    pub band_nm: Option<(f64, f64)>,
}

/// Reads a comparison file (None = the embedded comparison, [`DESIGNS_SCENE`]).
pub fn read_comparison(file: Option<&Path>) -> Result<Source, Error> {
    match file {
        Some(_) => crate::read(file),
        // its CSV tables are those of the source tree's examples/ folder
        None => Ok(Source::from_text(DESIGNS_SCENE, EMBEDDED, concat!(env!("CARGO_MANIFEST_DIR"), "/../examples"))),
    }
}

/// Reads and builds a comparison file (None = the embedded one) with `--set` overrides: shared
/// keys (`spectrum.range_nm=20`) apply to every design, `designs[1].lens.f_number=4` to one.
pub fn load_comparison(file: Option<&Path>, overrides: &[String]) -> Result<Comparison, Error> {
    crate::check_overrides(file, overrides)?;
    build_comparison(&read_comparison(file)?, overrides)
}

/// Whether `source` is a comparison file (it has `designs`); false when it cannot be parsed.
pub fn is_comparison(source: &Source) -> bool {
    merged(source, &[]).is_ok_and(|(table, _)| table.contains_key("designs"))
}

/// Builds the comparison of `source` with `overrides` (every design validated; errors name
/// the design's key, e.g. `designs[1].lens.f_number`).
pub fn build_comparison(source: &Source, overrides: &[String]) -> Result<Comparison, Error> {
    let (mut table, origins) = merged(source, overrides)?;
    if table.contains_key("lens") {
        return Err(origins.conflict(
            "lens",
            "a comparison file gives each design's lens in [[designs]] ([designs.lens]); a [lens] table would apply to no design: remove it (to change one design, set designs[N].lens.KEY)".to_owned(),
        ));
    }
    let key = "allow_different_focal_lengths";
    let allow = match table.remove(key) {
        None => false,
        Some(toml::Value::Boolean(b)) => b,
        Some(v) => return Err(origins.bad(key, &v, "true or false")),
    };
    let expected = "[[designs]] tables, each with a name and a lens table ([designs.lens])";
    let designs = match table.remove("designs") {
        Some(toml::Value::Array(list)) if !list.is_empty() => list,
        Some(toml::Value::Array(_)) => {
            return Err(origins.bad("designs", "[]", &format!("at least one of {expected}")));
        }
        Some(v) => return Err(origins.bad("designs", &v, expected)),
        None => return Err(origins.require::<()>("designs", None, expected).unwrap_err()),
    };
    let mut built: Vec<Design> = Vec::new();
    let mut warnings: Vec<Warning> = Vec::new();
    for (i, entry) in designs.into_iter().enumerate() {
        let at = format!("designs[{i}]");
        let toml::Value::Table(mut entry) = entry else {
            return Err(origins.bad(&at, &entry, "a table with a name and a lens table"));
        };
        let name = match entry.remove("name") {
            Some(toml::Value::String(s)) if !s.trim().is_empty() => s,
            Some(v) => return Err(origins.bad(&format!("{at}.name"), &v, "the design's name, a non-empty string")),
            None => return Err(origins.require::<()>(&format!("{at}.name"), None, "the design's name").unwrap_err()),
        };
        if built.iter().any(|d| d.name == name) {
            return Err(origins.bad(&format!("{at}.name"), quoted(&name), "a name no other design has"));
        }
        let lens = match entry.remove("lens") {
            Some(toml::Value::Table(t)) => t,
            Some(v) => return Err(origins.bad(&format!("{at}.lens"), &v, "a lens table ([designs.lens] or inline)")),
            None => {
                return Err(origins
                    .require::<()>(&format!("{at}.lens"), None, "a lens table ([designs.lens] or inline)")
                    .unwrap_err());
            }
        };
        if let Some(k) = entry.keys().next() {
            return Err(Error::Schema {
                origin: origins.of(&format!("{at}.{k}")),
                key: format!("{at}.{}", crate::error::shorten(k)),
                message: "unknown key: a design has `name` and `lens` (the other tables are shared)".to_owned(),
            });
        }
        let with_lens = |lens: toml::Table| {
            let mut scene_table = table.clone();
            scene_table.insert("lens".to_owned(), toml::Value::Table(lens));
            scene_table
        };
        let mut o = origins.for_lens(format!("{at}.lens"));
        let raw = raw_scene(with_lens(lens.clone()), &mut o, &|| Some(with_lens(lens.clone())))?;
        let built_parts = build_parts(&raw, &o);
        for w in o.take_warnings() {
            if !warnings.contains(&w) {
                warnings.push(w);
            }
        }
        let (scene, info) = match built_parts {
            Ok(parts) => parts,
            Err(error) if warnings.is_empty() => return Err(error),
            Err(error) => return Err(Error::WithWarnings { error: Box::new(error), warnings }),
        };
        let centre_m = raw
            .spectrum
            .as_ref()
            .and_then(|s| s.center_nm)
            .map(|c| c * 1e-9)
            .or(info.design_wavelength_m)
            .unwrap_or(scene.lens().design_wavelength().unwrap_or(550e-9));
        let lambda0 = info.design_wavelength_m.unwrap_or(centre_m);
        let twin = twin(&scene, centre_m, &o)?;
        let (f_number, f0) = (scene.lens().f_number(), scene.lens().focal_length());
        let fresnel_zones = f0 / (8.0 * f_number * f_number * lambda0);
        built.push(Design {
            name,
            kind: info.kind,
            twin,
            fresnel_zones,
            twin_band_nm: lambda0 / (2.0 * fresnel_zones) * 1e9,
            design_wavelength_nm: lambda0 * 1e9,
            channels_nm: info.channels_m.iter().map(|c| c * 1e9).collect(),
            notes: info.notes,
            scene,
        });
    }
    if !allow {
        let first = &built[0];
        let f0 = first.scene.lens().focal_length();
        if let Some((i, d)) =
            built.iter().enumerate().find(|(_, d)| (d.scene.lens().focal_length() - f0).abs() > 1e-12 * f0)
        {
            return Err(origins.conflict(
                &format!("designs[{i}].lens.focal_length_mm"),
                format!(
                    "designs[{i}] ({}) has focal length {} mm, designs[0] ({}) {} mm: a fair comparison keeps the focal length (and so the image scale); give the designs one focal length, or allow_different_focal_lengths = true",
                    quoted(&d.name),
                    num(d.scene.lens().focal_length() * 1e3),
                    quoted(&first.name),
                    num(f0 * 1e3)
                ),
            ));
        }
    }
    let title = table.get("title").and_then(|t| t.as_str()).map(str::to_owned);
    let spectrum = table.get("spectrum").and_then(toml::Value::as_table);
    let number = |key: &str| {
        spectrum.and_then(|s| s.get(key)).and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
    };
    let band_nm = number("center_nm").zip(number("range_nm"));
    Ok(Comparison { title, label: source.label().to_owned(), designs: built, warnings, band_nm })
}

/// The chromatic twin of `scene`'s lens: the same F-number and focal length, designed for
/// `centre_m`, with the lens's efficiency and transmission there, in the same scene.
fn twin(scene: &Scene, centre_m: f64, o: &Origins) -> Result<Scene, Error> {
    let context = "the chromatic twin of [lens]";
    let lens = scene.lens();
    let (tau, t) = (lens.efficiency(centre_m), lens.transmission(centre_m));
    let chromatic = ChromaticMetalens::new(
        lens.f_number(),
        lens.focal_length(),
        centre_m,
        Curve::Constant(tau.min(t)),
        Curve::Constant(t),
    )
    .map_err(|e| o.domain("lens", context, e))?;
    let twin = Scene::new(
        Arc::new(chromatic),
        scene.radiance().clone(),
        scene.camera().clone(),
        scene.exposure(),
        scene.options().clone(),
    )
    .map_err(|e| o.domain("lens", context, e))?;
    let twin = if scene.fields().is_empty() {
        twin.at_field(scene.field())
    } else {
        twin.over_fields(scene.fields().to_vec())
    };
    let twin = twin
        .map_err(|e| o.domain("lens", context, e))?
        .with_relative_illumination(scene.relative_illumination().clone());
    Ok(match scene.title() {
        Some(title) => twin.with_title(title),
        None => twin,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each design of the example, written as a scene file by `asnr scene`, loads again to the
    /// same ASNR, bit for bit; a design's key set by index reaches that design alone.
    #[test]
    fn designs_resolve_to_the_same_asnr_and_indexed_keys_reach_one_design() {
        let source = read_comparison(None).unwrap();
        let comparison = build_comparison(&source, &["spectrum.range_nm=10".to_owned()]).unwrap();
        assert_eq!(comparison.band_nm, Some((800.0, 10.0)));
        let (table, _) = merged(&source, &[]).unwrap();
        let designs = table["designs"].as_array().unwrap();
        for (i, design) in comparison.designs.iter().enumerate() {
            let mut scene = table.clone();
            scene.remove("designs");
            scene.insert("lens".to_owned(), designs[i]["lens"].clone());
            let text = toml::to_string(&scene).unwrap();
            let single = Source::from_text(text, "design", concat!(env!("CARGO_MANIFEST_DIR"), "/../examples"));
            let set = ["spectrum.range_nm=10".to_owned()];
            let resolved = crate::resolved_toml(&single, &set).unwrap().toml;
            let again = Source::from_text(resolved.clone(), "resolved", ".");
            let a = metric::evaluate(&design.scene).unwrap().asnr;
            let b = metric::evaluate(&crate::build_from(&again, &[]).unwrap()).unwrap().asnr;
            assert_eq!(a, b, "{}:\n{resolved}", design.name);
        }
        let slower = build_comparison(&source, &["designs[1].lens.f_number=4".to_owned()]).unwrap();
        assert_eq!(slower.designs[1].scene.lens().f_number(), 4.0);
        assert_eq!(slower.designs[0].scene.lens().f_number(), 2.5);
        let e = build_comparison(&source, &["designs[1].lens.f_number=0.1".to_owned()]).unwrap_err().to_string();
        assert!(
            e.starts_with(
                "embedded design comparison (--set designs[1].lens.f_number=0.1): designs[1].lens.f_number = 0.1: expected a number ≥ 0.5"
            ),
            "{e}"
        );
    }

    /// The chromatic twin of the paper's lens is the paper's lens; the small achromat's N_z and
    /// twin band follow f0/(8F#²λ0).
    #[test]
    fn twins_and_fresnel_zones() {
        let comparison = load_comparison(None, &[]).unwrap();
        let paper = &comparison.designs[0];
        assert_eq!(metric::evaluate(&paper.twin).unwrap().asnr, metric::evaluate(&paper.scene).unwrap().asnr);
        assert!((paper.twin_band_nm - 800.0 / 168.0).abs() < 1e-9);
        let small = comparison.designs.iter().find(|d| d.name.starts_with("achromat D")).unwrap();
        let f_number = 3.36 / 0.2;
        assert!((small.fresnel_zones - 3.36e-3 / (8.0 * f_number * f_number * 800e-9)).abs() < 1e-9);
        assert!(small.notes[0].starts_with("true achromat: ΔT_req = 4.96 fs ≤ ΔT_lib = 5 fs"), "{:?}", small.notes);
    }
}
