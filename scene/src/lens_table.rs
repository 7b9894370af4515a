//! The `[lens]` table as read (`RawLens`), what a built lens reports beside it (`LensInfo`), and
//! the readers both the radial families ([`crate::lens`]) and the 2-D layouts
//! ([`crate::layout2d`]) take: the meta-atom library and the Zernike list. Below both, so that
//! `lens` → `layout2d` → `lens_table` runs one way.

use serde::Deserialize;

use crate::error::{Error, num, quoted};
use crate::origins::{NumberOrFile, Origins};

#[derive(Deserialize, Clone, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLens {
    pub model: Option<String>,
    /// Read from the table by [`crate::lens::apply_preset`] before deserializing; here to be a known key.
    #[serde(rename = "preset")]
    pub _preset: Option<toml::Value>,
    pub f_number: Option<f64>,
    pub aperture_diameter_mm: Option<f64>,
    pub focal_length_mm: Option<f64>,
    pub design_wavelength_nm: Option<f64>,
    pub design_band_nm: Option<[f64; 2]>,
    pub group_delay_range_fs: Option<f64>,
    pub delay_overflow: Option<String>,
    pub design_order: Option<u32>,
    pub channels_nm: Option<Vec<f64>>,
    pub layout: Option<String>,
    pub zones: Option<String>,
    pub zone_mask: Option<String>,
    pub area_fractions: Option<Vec<f64>>,
    pub other_channels: Option<String>,
    pub glass: Option<String>,
    pub refractive_index: Option<f64>,
    pub elements: Option<u32>,
    pub coating_reflectance: Option<f64>,
    pub efficiency: Option<NumberOrFile>,
    pub transmission: Option<NumberOrFile>,
    pub channel_efficiencies: Option<Vec<NumberOrFile>>,
    pub mtf: Option<OneOrMany>,
    pub mtf_includes_pixel_um: Option<f64>,
    pub mtf_field: Option<u32>,
    pub iris_decentre_x: Option<f64>,
    pub iris_decentre_y: Option<f64>,
    pub obscuration: Option<f64>,
    pub sector_deg: Option<[f64; 2]>,
    pub spherical_um: Option<f64>,
    pub coma_um: Option<f64>,
    pub astigmatism_um: Option<f64>,
    pub field_curvature_um: Option<f64>,
    pub binary2: Option<Vec<f64>>,
    pub norm_radius_mm: Option<f64>,
    pub diffraction_order: Option<f64>,
    pub phase_csv: Option<String>,
    pub phase_spline_rad: Option<Vec<f64>>,
    pub phase_map: Option<String>,
    pub amplitude_map: Option<String>,
    pub phase_map_pitch_um: Option<f64>,
    pub aperture: Option<String>,
    pub dispersion: Option<String>,
    pub zernike_noll_rms_um: Option<Vec<f64>>,
    pub library: Option<String>,
    pub atom_phase_error_rad: Option<f64>,
    pub atom_transmission_error: Option<f64>,
    pub atom_error_seed: Option<u64>,
    pub parameter_bias: Option<Vec<f64>>,
    pub library_interpolation: Option<String>,
    pub layout_grid: Option<String>,
    pub layout_gds: Option<String>,
    pub gds_cell: Option<String>,
    pub gds_layer: Option<i64>,
    pub gds_datatype: Option<i64>,
    pub lattice_pitch_um: Option<f64>,
    pub atom: Option<String>,
    pub handedness: Option<String>,
    pub empty_cell: Option<toml::Value>,
    pub psf: Option<String>,
    pub psf_pitch_um: Option<f64>,
    pub psf_wavelengths_nm: Option<Vec<f64>>,
    /// Read by [`apply_zemax`] before deserializing (it fills the phase lens's keys); here to be
    /// known keys.
    pub zemax: Option<String>,
    pub zemax_surface: Option<u32>,
    /// Every family's: read by [`crate::load`] into the scene (docs/physics.md, "Relative
    /// illumination").
    pub relative_illumination: Option<NumberOrFile>,
}

/// A path, or a list of paths (`lens.mtf`: one Zemax export per wavelength).
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(untagged)]
pub(crate) enum OneOrMany {
    /// One path.
    One(String),
    /// Several paths.
    Many(Vec<String>),
}

impl OneOrMany {
    /// The paths, in the order given.
    pub(crate) fn paths(&self) -> Vec<&str> {
        match self {
            OneOrMany::One(p) => vec![p.as_str()],
            OneOrMany::Many(list) => list.iter().map(String::as_str).collect(),
        }
    }
}

/// What a comparison reports of a lens besides its [`optics::LensModel`].
#[derive(Clone, Debug, Default)]
pub(crate) struct LensInfo {
    /// The family, as `Design::kind` names it.
    pub kind: &'static str,
    /// Its design wavelength (a dispersion-engineered lens: the band's centre), m.
    pub design_wavelength_m: Option<f64>,
    /// A multiplexed lens's channel wavelengths, m.
    pub channels_m: Vec<f64>,
    /// Facts of the design a reader needs (group delay, β, glass, efficiency per channel).
    pub notes: Vec<String>,
    /// A PSF stack's pitch, checked against the camera.
    pub psf: Option<crate::psf::PsfLimits>,
    /// The wavelengths a lens given as data covers (a PSF stack, an MTF table), checked against
    /// the detected spectrum.
    pub table_range: Option<crate::psf::TableRange>,
}

/// `lens.library` (columns: parameters, `wavelength_nm`, `amplitude` or `transmittance`,
/// `phase_rad`, and for fins an optional `co_amplitude`, their unconverted light), interpolated
/// in the parameters as `lens.library_interpolation` says ([`library_interpolation`]): the
/// library and its parameter columns' names.
pub(crate) fn read_library(l: &RawLens, o: &Origins) -> Result<(lenses::Library, Vec<String>), Error> {
    let expected =
        "a CSV of the meta-atom library: parameter columns, wavelength_nm, amplitude or transmittance, phase_rad";
    let file = o.require("lens.library", l.library.as_deref(), expected)?;
    let (headers, rows) = crate::tables::read_columns(&o.path(file), "meta-atom library")
        .map_err(|e| o.table_error("lens.library", file, e, expected))?;
    let ctx = format!("lens.library = {}", quoted(file));
    let col = |name: &str| headers.iter().position(|h| h == name);
    let reserved = ["wavelength_nm", "amplitude", "transmittance", "phase_rad", "co_amplitude"];
    let (Some(iw), Some(ip)) = (col("wavelength_nm"), col("phase_rad")) else {
        return Err(o.bad(
            "lens.library",
            quoted(file),
            &format!("{expected} (its header is `{}`)", headers.join(",")),
        ));
    };
    let amplitude = match (col("amplitude"), col("transmittance")) {
        (Some(i), None) => (i, false),
        (None, Some(i)) => (i, true),
        _ => {
            return Err(o.bad(
                "lens.library",
                quoted(file),
                &format!("one of the columns amplitude (|t|) or transmittance (|t|²), not both or neither (its header is `{}`)", headers.join(",")),
            ));
        }
    };
    let names: Vec<&String> = headers.iter().filter(|h| !reserved.contains(&h.as_str())).collect();
    if names.is_empty() {
        return Err(o.bad(
            "lens.library",
            quoted(file),
            "at least one parameter column (e.g. diameter_nm) beside wavelength_nm, amplitude and phase_rad",
        ));
    }
    let mut table = Vec::with_capacity(rows.len());
    for (_, values) in &rows {
        let params: Vec<f64> = names.iter().map(|n| values[col(n).unwrap_or(0)]).collect();
        let a = values[amplitude.0];
        let a = if amplitude.1 { if a >= 0.0 { a.sqrt() } else { f64::NAN } } else { a };
        table.push((params, values[iw] * 1e-9, a, values[ip]));
    }
    let library = lenses::Library::new(&table)
        .map_err(|e| o.domain("lens.library", &ctx, e))?
        .with_interpolation(library_interpolation(l, o)?);
    // a fin's unconverted light (zero-order light: in T, not in τ1)
    let library = match col("co_amplitude") {
        Some(ic) => {
            let co: Vec<f64> = rows.iter().map(|(_, values)| values[ic]).collect();
            library.with_co_amplitude(&table, &co).map_err(|e| o.domain("lens.library", &ctx, e))?
        }
        None => library,
    };
    Ok((library, names.iter().map(|n| n.to_string()).collect()))
}

/// `lens.library_interpolation`: `"linear"` (the default: multilinear in the parameters) or
/// `"cubic"` (a C¹ cubic in each parameter; docs/physics.md, "Meta-atom library").
pub(crate) fn library_interpolation(l: &RawLens, o: &Origins) -> Result<lenses::Interpolation, Error> {
    match l.library_interpolation.as_deref() {
        None | Some("linear") => Ok(lenses::Interpolation::Linear),
        Some("cubic") => Ok(lenses::Interpolation::Cubic),
        Some(other) => Err(o.bad(
            "lens.library_interpolation",
            quoted(other),
            "\"linear\" (|t| and the unwrapped phase multilinear in the parameters, the default) or \"cubic\" (a C¹ piecewise cubic in each parameter, error O(h⁴): needed for the gradient with respect to lens.parameter_bias)",
        )),
    }
}

/// `lens.zernike_noll_rms_um` as `(Noll index, metres RMS)`, the first entry Z1.
/// The atoms' random errors, `(σ_φ, σ_t)` (`lens.atom_phase_error_rad`,
/// `lens.atom_transmission_error`, 0 where not given), checked as both layouts take them;
/// `below_zero` says what becomes of an amplitude factor drawn below 0.
pub(crate) fn atom_error_sigmas(l: &RawLens, o: &Origins, below_zero: &str) -> Result<(f64, f64), Error> {
    let phase = l.atom_phase_error_rad.unwrap_or(0.0);
    let phase = o.number("lens.atom_phase_error_rad", phase, phase >= 0.0, "a standard deviation ≥ 0 rad")?;
    let amplitude = l.atom_transmission_error.unwrap_or(0.0);
    let expected = format!(
        "a relative standard deviation in [0, 0.5): the amplitude factor 1 + ε of an atom must stay positive but for rare atoms ({below_zero})"
    );
    let amplitude = o.number("lens.atom_transmission_error", amplitude, (0.0..0.5).contains(&amplitude), &expected)?;
    Ok((phase, amplitude))
}

pub(crate) fn zernike(l: &RawLens, o: &Origins) -> Result<Option<Vec<(usize, f64)>>, Error> {
    let Some(list) = &l.zernike_noll_rms_um else { return Ok(None) };
    let key = "lens.zernike_noll_rms_um";
    let max = optics::fft::MAX_NOLL_INDEX;
    if list.is_empty() || list.len() > max {
        return Err(o.bad(
            key,
            format!("{} terms", list.len()),
            &format!("1 to {max} coefficients, Z1 first (Noll order, µm RMS of path)"),
        ));
    }
    let mut out = Vec::new();
    for (i, &c) in list.iter().enumerate() {
        let item = format!("{key}[{i}]");
        o.number(&item, c, c.abs() <= 1e3, "a Zernike coefficient in µm RMS, |c| ≤ 1000 µm")?;
        if c != 0.0 {
            out.push((i + 1, c * 1e-6));
        }
    }
    Ok(Some(out))
}

pub(crate) fn zernike_note(terms: &[(usize, f64)]) -> String {
    let list: Vec<String> =
        terms.iter().map(|(j, c)| format!("Z{j} = {} µm", num(optics::round_for_display(c * 1e6)))).collect();
    if list.is_empty() {
        "Zernike terms (Noll, RMS): all zero".to_owned()
    } else {
        format!("Zernike terms (Noll, RMS): {}", list.join(", "))
    }
}
