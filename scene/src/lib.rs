//! Scene files → validated ASNR scenes: the one library crate that reads files.
//!
//! A scene is a TOML file with the tables `[lens]`, `[source]`, `[spectrum]`, `[camera]`,
//! `[exposure]`, `[options]` and `[field]` or `[[fields]]`; the README's "Scene files" table lists
//! every key, and [`resolved_toml`] (`asnr scene`) prints a scene with every default filled in.
//! Values may name two-column CSV tables (`wavelength_nm, value`, see [`read_pairs`]) beside the
//! file. [`load`] reads one, applies `--set`-style overrides (`"lens.f_number=2.8"`) and returns
//! a [`metric::Scene`], or an [`Error`] that names the file (or the override), the dotted key,
//! the value and what is accepted:
//! `<file or "file (--set k=v)">: <dotted.key> = <value>: expected <accepted>`.
//!
//! ```
//! // the embedded paper scene (examples/paper-theory.toml) at F/2.8
//! let scene = scene::load(None, &["lens.f_number=2.8".to_owned()]).unwrap();
//! let result = metric::evaluate(&scene).unwrap();
//! assert!(result.asnr > 5.0 && result.asnr < 15.0);
//!
//! // a unit slip is valid but warned about: 0.0052 µm is 5.2 µm typed in mm
//! let loaded = scene::load_with_warnings(None, &["camera.pixel_pitch_um=0.0052".to_owned()]).unwrap();
//! assert!(loaded.warnings[0].to_string().contains("looks like mm (5.2 µm?)"));
//!
//! // a bad value names the override, the key, the value and what is accepted
//! let err = scene::load(None, &["spectrum.center_nm=800nm".to_owned()]).unwrap_err();
//! assert_eq!(
//!     err.to_string(),
//!     "embedded paper scene (--set spectrum.center_nm=800nm): spectrum.center_nm = \"800nm\": \
//!      expected a number in nm (write 800, not \"800nm\")"
//! );
//! ```
//!
//! `[source] kind` is `flat`, `blackbody`, `table` (a CSV of spectral radiance) or
//! `radiance_meter`: the readings of the paper's radiance meter (spectrometer spectrum, power
//! meter, fiber, responsivity, relay) turned into the target's radiance by SI eq. S1–S6
//! ([`radiometry::radiance_meter`]), whose steps [`Loaded::radiance_meter`] keeps.
//!
//! `[lens] model` chooses the family (docs/physics.md, "Lens families"): `chromatic`,
//! `refractive`, `dispersion-engineered`, `harmonic`, `multiplexed` (layout `segmented` or
//! `interleaved`) or `tabulated`, each with its keys; a key of another family is refused naming
//! the model, and `preset` fills in a named lens's keys ([`PRESETS`]). A comparison file has
//! `[[designs]]` (each a `name` and a `lens` table) instead of `[lens]`: [`load_comparison`]
//! builds every design in the shared scene ([`Comparison`], [`Design`]), and `--set` reaches one
//! design by index (`designs[1].lens.f_number=4`).
//!
//! Plausibility warnings ([`load_with_warnings`], [`Warning`]) flag values that are valid but
//! almost surely typed in another unit: a pixel pitch outside [`PIXEL_PITCH_PLAUSIBLE_UM`]
//! (0.1–100 µm), a focal length outside [`FOCAL_LENGTH_PLAUSIBLE_MM`] (0.01–10⁴ mm), a
//! wavelength (`design_wavelength_nm`, `center_nm`, or all of a table's) outside
//! [`WAVELENGTH_PLAUSIBLE_NM`] (100–20000 nm), an exposure outside [`EXPOSURE_PLAUSIBLE_MS`]
//! (10⁻⁶–10⁷ ms).
//!
//! Units: scene keys carry their unit in their name (`focal_length_mm`, `range_nm`,
//! `pixel_pitch_um`, `time_ms`); the domain types are in SI. Nothing given is dropped: unknown
//! keys, keys that do not apply, CSV rows that are not numbers and `--set` values with a
//! trailing TOML comment are errors.

mod compare;
mod error;
pub mod gds;
mod layout2d;
mod lens;
mod lens_table;
mod load;
pub mod npy;
mod origins;
mod psf;
mod resolved;
pub mod sweep;
mod tables;
mod zemax;

pub use compare::{
    Comparison, DESIGNS_SCENE, Design, build_comparison, is_comparison, load_comparison, read_comparison,
};
pub use error::{Error, SHOWN, Warning};
pub use lens::PRESETS;
pub use load::{
    Loaded, MAX_EXTENDED_LIST, PAPER_SCENE, PupilMapping, Source, build_from, build_with_warnings, canonical_key,
    check_overrides, load, load_with_warnings, read,
};
pub use origins::{
    ARRAY_KEYS, EXPOSURE_PLAUSIBLE_MS, FOCAL_LENGTH_PLAUSIBLE_MM, PIXEL_PITCH_PLAUSIBLE_UM, WAVELENGTH_PLAUSIBLE_NM,
};
pub use resolved::{Resolved, resolved_and_built, resolved_toml};
pub use tables::{Axis, CsvLines, FREQUENCY, MAX_FILE_BYTES, WAVELENGTH, read_pairs, read_table};

#[cfg(test)]
mod tests {
    #[test]
    fn the_title_reaches_the_scene() {
        let paper = crate::load(None, &[]).unwrap();
        assert_eq!(paper.title(), Some("Paper theory model: chromatic metalens F/2.5, 800 nm, 50 nm range"));
        let retitled = crate::load(None, &["title=\"Mine\"".to_owned()]).unwrap();
        assert_eq!(retitled.title(), Some("Mine"));
    }
}
