//! Scene files → validated ASNR scenes: the one library crate that reads files.
//!
//! A scene is a TOML file with the tables `[lens]`, `[source]`, `[spectrum]`, `[camera]`,
//! `[exposure]`, `[options]` and `[field]` or `[[fields]]` (the README lists every key); values
//! may name two-column CSV tables (`wavelength_nm, value`) beside the file. [`load`] reads one,
//! applies `--set`-style overrides (`"lens.f_number=2.8"`) and returns a [`metric::Scene`], or an
//! error that names the file (or the override), the dotted key, the value and what is accepted.
//!
//! ```
//! // the embedded paper scene (examples/paper-theory.toml) at F/2.8
//! let scene = scene::load(None, &["lens.f_number=2.8".to_owned()]).unwrap();
//! let result = metric::evaluate(&scene).unwrap();
//! assert!(result.asnr > 5.0 && result.asnr < 15.0);
//! ```
//!
//! Units: scene keys carry their unit in their name (`focal_length_mm`, `range_nm`,
//! `pixel_pitch_um`, `time_ms`); the domain types are in SI.

mod load;
mod tables;

pub use load::{PAPER_SCENE, Source, build_from, load, read};
pub use tables::{Axis, FREQUENCY, WAVELENGTH, read_pairs, read_table};

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
