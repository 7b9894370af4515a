//! The `[lens]` table: one builder per lens family (docs/physics.md, "Lens families").
//!
//! `model` chooses the family; every key of the table is checked against it, so a key of
//! another family is refused naming the model (`lens.design_order does not apply to
//! lens.model = "chromatic"`). A `preset` fills in the keys the table does not give.

use std::sync::Arc;

use lenses::{
    Channel, ChromaticMetalens, Curve, DelayOverflow, DispersionEngineered, Glass, Harmonic, Interleaved, PsfStack,
    Refractive, Sellmeier, Surfaces, max_diameter, required_group_delay,
};
use optics::LensModel;
use radiometry::Spectrum;

use crate::error::{Error, num, quoted};
use crate::lens_table::{LensInfo, RawLens, read_library, zernike, zernike_note};
use crate::origins::{NumberOrFile, Origins};
use crate::psf::{
    ACCEPTED, ALIASING_MAX, ALIASING_WARNED, BORDER_WARNED, IMAGINARY_WARNED, PsfLimits, TableRange, read_stack,
};
use crate::zemax::ZemaxSource;

/// The models a scene file accepts, as messages list them.
pub(crate) const MODELS: &str = "\"chromatic\", \"refractive\", \"dispersion-engineered\", \"harmonic\", \"multiplexed\" (layout \"interleaved\" or \"segmented\"), \"tabulated\" (an MTF table), \"phase\" (your design's phase profile), \"library\" (a meta-atom library and its layout) or \"psf\" (a PSF stack)";

/// The lens presets, by the names of `lenses::preset_names`: a name and the `[lens]` keys it
/// stands for (keys given beside `preset` override them). Each is the lens of `lenses::preset`
/// of that name (the publications and the values chosen are documented there); a test checks
/// that both build the same lens.
pub const PRESETS: [(&str, &str); 6] = [
    (
        "paper-chromatic",
        "model = \"chromatic\"\nf_number = 2.5\nfocal_length_mm = 3.36\ndesign_wavelength_nm = 800.0\n\
         efficiency = 0.15\ntransmission = 0.55\n",
    ),
    (
        "chen2019",
        "model = \"dispersion-engineered\"\naperture_diameter_mm = 0.0264\nfocal_length_mm = 0.0646665292094759\n\
         design_band_nm = [460.0, 700.0]\ngroup_delay_range_fs = 4.5\nefficiency = 0.2\ntransmission = 0.9\n",
    ),
    (
        "wang2018",
        "model = \"dispersion-engineered\"\naperture_diameter_mm = 0.05\nfocal_length_mm = 0.235\n\
         design_band_nm = [400.0, 660.0]\ngroup_delay_range_fs = 4.5\nefficiency = 0.4\ntransmission = 0.9\n",
    ),
    (
        "ndao2020",
        "model = \"dispersion-engineered\"\naperture_diameter_mm = 0.01\nfocal_length_mm = 0.041365578819969516\n\
         design_band_nm = [640.0, 1200.0]\ngroup_delay_range_fs = 0.97\ndelay_overflow = \"reject\"\n\
         efficiency = 0.5599999999999999\ntransmission = 0.8\n",
    ),
    (
        "ndao2020-reduced",
        "model = \"dispersion-engineered\"\naperture_diameter_mm = 0.01\nfocal_length_mm = 0.041365578819969516\n\
         design_band_nm = [640.0, 1200.0]\ngroup_delay_range_fs = 0.97\ndelay_overflow = \"reduced\"\n\
         efficiency = 0.5599999999999999\ntransmission = 0.8\n",
    ),
    (
        "n-bk7-singlet",
        "model = \"refractive\"\nf_number = 2.5\nfocal_length_mm = 3.36\ndesign_wavelength_nm = 800.0\n\
         glass = \"N-BK7\"\nelements = 1\n",
    ),
];

/// The glasses `lens.glass` names.
const GLASSES: &str = "\"N-BK7\" (Schott, Sellmeier 300–2500 nm)";

/// A lens family of the scene format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Model {
    Chromatic,
    Refractive,
    Dispersion,
    Harmonic,
    Multiplexed,
    Tabulated,
    Phase,
    Library,
    Psf,
}

impl Model {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Model::Chromatic => "chromatic",
            Model::Refractive => "refractive",
            Model::Dispersion => "dispersion-engineered",
            Model::Harmonic => "harmonic",
            Model::Multiplexed => "multiplexed",
            Model::Tabulated => "tabulated",
            Model::Phase => "phase",
            Model::Library => "library",
            Model::Psf => "psf",
        }
    }

    /// Whether the family has the key (the keys every family has are not listed).
    fn has(self, key: &str) -> bool {
        let keys: &[&str] = match self {
            Model::Chromatic => &[
                "design_wavelength_nm",
                "efficiency",
                "transmission",
                "iris_decentre_x",
                "iris_decentre_y",
                "obscuration",
                "sector_deg",
                "spherical_um",
                "coma_um",
                "astigmatism_um",
                "field_curvature_um",
                "zernike_noll_rms_um",
            ],
            Model::Refractive => &[
                "design_wavelength_nm",
                "glass",
                "refractive_index",
                "elements",
                "coating_reflectance",
                "zernike_noll_rms_um",
            ],
            Model::Dispersion => &[
                "design_band_nm",
                "group_delay_range_fs",
                "delay_overflow",
                "efficiency",
                "transmission",
                "zernike_noll_rms_um",
            ],
            Model::Harmonic => {
                &["design_wavelength_nm", "design_order", "efficiency", "transmission", "zernike_noll_rms_um"]
            }
            Model::Library => &[
                "design_wavelength_nm",
                "library",
                "layout",
                "atom_phase_error_rad",
                "atom_transmission_error",
                "atom_error_seed",
                "parameter_bias",
                "library_interpolation",
                "zernike_noll_rms_um",
                "layout_grid",
                "layout_gds",
                "gds_cell",
                "gds_layer",
                "gds_datatype",
                "lattice_pitch_um",
                "atom",
                "handedness",
                "empty_cell",
            ],
            Model::Phase => &[
                "design_wavelength_nm",
                "efficiency",
                "transmission",
                "binary2",
                "norm_radius_mm",
                "diffraction_order",
                "phase_csv",
                "phase_spline_rad",
                "phase_map",
                "amplitude_map",
                "phase_map_pitch_um",
                "aperture",
                "dispersion",
                "design_order",
                "glass",
                "zernike_noll_rms_um",
                "zemax",
                "zemax_surface",
            ],
            Model::Multiplexed => &[
                "channels_nm",
                "layout",
                "zones",
                "zone_mask",
                "area_fractions",
                "other_channels",
                "efficiency",
                "channel_efficiencies",
                "transmission",
                "zernike_noll_rms_um",
            ],
            Model::Tabulated => {
                &["mtf", "mtf_includes_pixel_um", "mtf_field", "design_wavelength_nm", "efficiency", "transmission"]
            }
            Model::Psf => {
                &["psf", "psf_pitch_um", "psf_wavelengths_nm", "design_wavelength_nm", "efficiency", "transmission"]
            }
        };
        keys.contains(&key)
    }
}

impl RawLens {
    /// Every family-specific key and whether the table gives it.
    fn given(&self) -> [(&'static str, bool); 62] {
        [
            ("layout_grid", self.layout_grid.is_some()),
            ("layout_gds", self.layout_gds.is_some()),
            ("gds_cell", self.gds_cell.is_some()),
            ("gds_layer", self.gds_layer.is_some()),
            ("gds_datatype", self.gds_datatype.is_some()),
            ("lattice_pitch_um", self.lattice_pitch_um.is_some()),
            ("atom", self.atom.is_some()),
            ("handedness", self.handedness.is_some()),
            ("empty_cell", self.empty_cell.is_some()),
            ("zemax", self.zemax.is_some()),
            ("zemax_surface", self.zemax_surface.is_some()),
            ("phase_map", self.phase_map.is_some()),
            ("amplitude_map", self.amplitude_map.is_some()),
            ("phase_map_pitch_um", self.phase_map_pitch_um.is_some()),
            ("aperture", self.aperture.is_some()),
            ("library", self.library.is_some()),
            ("atom_phase_error_rad", self.atom_phase_error_rad.is_some()),
            ("atom_transmission_error", self.atom_transmission_error.is_some()),
            ("atom_error_seed", self.atom_error_seed.is_some()),
            ("parameter_bias", self.parameter_bias.is_some()),
            ("library_interpolation", self.library_interpolation.is_some()),
            ("psf", self.psf.is_some()),
            ("psf_pitch_um", self.psf_pitch_um.is_some()),
            ("psf_wavelengths_nm", self.psf_wavelengths_nm.is_some()),
            ("binary2", self.binary2.is_some()),
            ("norm_radius_mm", self.norm_radius_mm.is_some()),
            ("diffraction_order", self.diffraction_order.is_some()),
            ("phase_csv", self.phase_csv.is_some()),
            ("phase_spline_rad", self.phase_spline_rad.is_some()),
            ("dispersion", self.dispersion.is_some()),
            ("zernike_noll_rms_um", self.zernike_noll_rms_um.is_some()),
            ("design_wavelength_nm", self.design_wavelength_nm.is_some()),
            ("design_band_nm", self.design_band_nm.is_some()),
            ("group_delay_range_fs", self.group_delay_range_fs.is_some()),
            ("delay_overflow", self.delay_overflow.is_some()),
            ("design_order", self.design_order.is_some()),
            ("channels_nm", self.channels_nm.is_some()),
            ("layout", self.layout.is_some()),
            ("zones", self.zones.is_some()),
            ("zone_mask", self.zone_mask.is_some()),
            ("area_fractions", self.area_fractions.is_some()),
            ("other_channels", self.other_channels.is_some()),
            ("glass", self.glass.is_some()),
            ("refractive_index", self.refractive_index.is_some()),
            ("elements", self.elements.is_some()),
            ("coating_reflectance", self.coating_reflectance.is_some()),
            ("efficiency", self.efficiency.is_some()),
            ("transmission", self.transmission.is_some()),
            ("channel_efficiencies", self.channel_efficiencies.is_some()),
            ("mtf", self.mtf.is_some()),
            ("mtf_includes_pixel_um", self.mtf_includes_pixel_um.is_some()),
            ("mtf_field", self.mtf_field.is_some()),
            ("iris_decentre_x", self.iris_decentre_x.is_some()),
            ("iris_decentre_y", self.iris_decentre_y.is_some()),
            ("obscuration", self.obscuration.is_some()),
            ("sector_deg", self.sector_deg.is_some()),
            ("spherical_um", self.spherical_um.is_some()),
            ("coma_um", self.coma_um.is_some()),
            ("astigmatism_um", self.astigmatism_um.is_some()),
            ("field_curvature_um", self.field_curvature_um.is_some()),
            ("f_number", self.f_number.is_some()),
            ("aperture_diameter_mm", self.aperture_diameter_mm.is_some()),
        ]
    }
}

/// The model a lens table names (default chromatic), or the error listing the accepted ones.
pub(crate) fn model(l: &RawLens, o: &Origins) -> Result<Model, Error> {
    Ok(match l.model.as_deref().unwrap_or("chromatic") {
        "chromatic" => Model::Chromatic,
        "refractive" => Model::Refractive,
        "dispersion-engineered" => Model::Dispersion,
        "harmonic" => Model::Harmonic,
        "multiplexed" => Model::Multiplexed,
        "tabulated" => Model::Tabulated,
        "phase" => Model::Phase,
        "library" => Model::Library,
        "psf" => Model::Psf,
        other => return Err(o.bad("lens.model", quoted(other), MODELS)),
    })
}

/// Fills the keys a `preset` stands for into the lens table `lens` (keys given stay); returns
/// the preset's name and the keys it supplied.
pub(crate) fn apply_preset(lens: &mut toml::Table, o: &Origins) -> Result<Option<(String, Vec<String>)>, Error> {
    let Some(value) = lens.get("preset").cloned() else { return Ok(None) };
    let names: Vec<String> = PRESETS.iter().map(|(n, _)| quoted(n)).collect();
    let expected = format!("the name of a preset: {}", names.join(", "));
    let Some(name) = value.as_str() else { return Err(o.bad("lens.preset", &value, &expected)) };
    let Some((_, text)) = PRESETS.iter().find(|(n, _)| *n == name) else {
        return Err(o.bad("lens.preset", quoted(name), &expected));
    };
    let preset: toml::Table = toml::from_str(text).unwrap_or_default();
    if let (Some(given), Some(own)) = (lens.get("model").and_then(|m| m.as_str()), preset.get("model"))
        && Some(given) != own.as_str()
    {
        return Err(o.conflict(
            "lens.model",
            format!(
                "lens.preset = {} is a {} lens, but lens.model = {}: give the model of the preset, or no preset",
                quoted(name),
                own,
                quoted(given)
            ),
        ));
    }
    let mut supplied = Vec::new();
    for (k, v) in preset {
        // a preset's aperture yields to the other aperture key given in the table
        let other = match k.as_str() {
            "f_number" => "aperture_diameter_mm",
            "aperture_diameter_mm" => "f_number",
            _ => "",
        };
        if !lens.contains_key(&k) && !lens.contains_key(other) {
            supplied.push(k.clone());
            lens.insert(k, v);
        }
    }
    Ok(Some((name.to_owned(), supplied)))
}

/// Fills the phase lens's keys from the Zemax file `lens.zemax` names (docs/physics.md, "Zemax
/// OpticStudio files"): `binary2`, `norm_radius_mm`, `diffraction_order`,
/// `aperture_diameter_mm`, `focal_length_mm`, `design_wavelength_nm`, and `model = "phase"`.
/// A key the scene file also gives is refused (one source for each number); a `--set` of it
/// overrides the file's value (a sweep over the focal length).
pub(crate) fn apply_zemax(lens: &mut toml::Table, o: &Origins) -> Result<Option<ZemaxSource>, Error> {
    let Some(value) = lens.get("zemax").cloned() else {
        if lens.contains_key("zemax_surface") {
            return Err(o.conflict(
                "lens.zemax_surface",
                "lens.zemax_surface without lens.zemax: it chooses the Binary 2 surface of the .zmx file lens.zemax names".to_owned(),
            ));
        }
        return Ok(None);
    };
    let expected = "the path of a Zemax OpticStudio .zmx file (sequential, one Binary 2 surface on a plane substrate)";
    let Some(file) = value.as_str() else { return Err(o.bad("lens.zemax", &value, expected)) };
    match lens.get("model") {
        None => {
            lens.insert("model".to_owned(), toml::Value::String("phase".to_owned()));
        }
        Some(m) if m.as_str() == Some("phase") => {}
        Some(m) => {
            return Err(o.conflict(
                "lens.model",
                format!("lens.zemax gives a phase lens, but lens.model = {m}: give model = \"phase\" or none"),
            ));
        }
    }
    let surface = match lens.get("zemax_surface") {
        None => None,
        Some(v) => match v.as_integer().and_then(|i| u32::try_from(i).ok()).filter(|&i| i >= 1) {
            Some(i) => Some(i),
            None => return Err(o.bad("lens.zemax_surface", v, "the number of a BINARY_2 surface of the file (≥ 1)")),
        },
    };
    let path = o.path(file);
    let z = crate::zemax::read(&path, &path.display().to_string(), surface)
        .map_err(|e| o.table_error("lens.zemax", file, e, expected))?;
    for w in &z.warnings {
        o.warn("lens.zemax", quoted(file), w.clone());
    }
    let supplied: [(&str, toml::Value); 6] = [
        ("binary2", toml::Value::Array(z.coefficients.iter().map(|&a| toml::Value::Float(a)).collect())),
        ("norm_radius_mm", toml::Value::Float(z.norm_radius_mm)),
        ("diffraction_order", toml::Value::Float(z.diffraction_order)),
        ("aperture_diameter_mm", toml::Value::Float(z.aperture_diameter_mm)),
        ("focal_length_mm", toml::Value::Float(z.focal_length_mm)),
        ("design_wavelength_nm", toml::Value::Float(z.design_wavelength_nm)),
    ];
    let mut keys = Vec::new();
    for (key, v) in supplied {
        let dotted = format!("lens.{key}");
        let set = |k: &str| o.overrides.contains_key(&o.key(&format!("lens.{k}")));
        let given = lens
            .contains_key(key)
            .then_some(key)
            .or_else(|| (key == "aperture_diameter_mm" && lens.contains_key("f_number")).then_some("f_number"));
        match given {
            Some(k) if set(k) => continue,
            Some(k) => {
                return Err(o.conflict(
                    &format!("lens.{k}"),
                    format!(
                        "lens.{k} given with lens.zemax, whose file gives {dotted}: give the number once (remove lens.{k}; --set lens.{k}=… overrides the file's)"
                    ),
                ));
            }
            None => {
                lens.insert(key.to_owned(), v);
                keys.push(key.to_owned());
            }
        }
    }
    Ok(Some(ZemaxSource { file: file.to_owned(), surface: z.surface, keys, notes: z.notes }))
}

/// A lens built from its table.
pub(crate) struct BuiltLens {
    pub lens: Arc<dyn LensModel>,
    pub info: LensInfo,
}

/// Builds the lens of a `[lens]` table (every key validated against its family).
pub(crate) fn build(l: &RawLens, o: &Origins) -> Result<BuiltLens, Error> {
    let model = model(l, o)?;
    let context = format!("lens.model = {}", quoted(model.name()));
    for (key, given) in l.given() {
        if given && !matches!(key, "f_number" | "aperture_diameter_mm") && !model.has(key) {
            return Err(Error::NotApplicable {
                origin: o.of(&format!("lens.{key}")),
                key: o.key(&format!("lens.{key}")),
                context: o.key(&context),
            });
        }
    }
    let f0 = o.require("lens.focal_length_mm", l.focal_length_mm, "a length > 0 mm")?;
    let f0 = o.number("lens.focal_length_mm", f0, f0 > 0.0, "a length > 0 mm")?;
    let (lo, hi) = crate::origins::FOCAL_LENGTH_PLAUSIBLE_MM;
    if f0 < lo {
        o.warn("lens.focal_length_mm", num(f0), format!("below {lo} mm: looks like m ({} mm?)", rounded(f0 * 1e3)));
    } else if f0 > hi {
        o.warn("lens.focal_length_mm", num(f0), format!("above {hi} mm: looks like µm ({} mm?)", rounded(f0 * 1e-3)));
    }
    let f_number = f_number(l, o, f0)?;
    let f0_m = f0 * 1e-3;
    let efficiency = |o: &Origins| -> Result<Curve, Error> {
        let e = o.require("lens.efficiency", l.efficiency.as_ref(), "a fraction in [0, 1] or a CSV path")?;
        o.curve("lens.efficiency", e, "efficiency")
    };
    let transmission = |o: &Origins, efficiency: &Curve| -> Result<Curve, Error> {
        match &l.transmission {
            Some(t) => o.curve("lens.transmission", t, "transmission"),
            None => Ok(efficiency.clone()),
        }
    };
    let design_wavelength = |o: &Origins| -> Result<f64, Error> {
        let key = "lens.design_wavelength_nm";
        let v = o.require(key, l.design_wavelength_nm, "a wavelength > 0 nm")?;
        let v = o.number(key, v, v > 0.0, "a wavelength > 0 nm")?;
        o.wavelength(key, v);
        Ok(v * 1e-9)
    };
    let mut info = LensInfo { kind: model.name(), ..LensInfo::default() };
    let lens: Arc<dyn LensModel> = match model {
        Model::Chromatic => {
            let l0 = design_wavelength(o)?;
            let efficiency = efficiency(o)?;
            let transmission = transmission(o, &efficiency)?;
            let mut lens = ChromaticMetalens::new(f_number, f0_m, l0, efficiency, transmission)
                .map_err(|e| o.domain("lens", "[lens]", e))?;
            if let Some(aperture) = aperture(l, o)? {
                lens = lens.with_aperture(aperture);
            }
            let seidel = |key: &str, v: Option<f64>| -> Result<f64, Error> {
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
            info.design_wavelength_m = Some(l0);
            Arc::new(lens)
        }
        Model::Refractive => {
            let l0 = design_wavelength(o)?;
            let glass = match (&l.glass, l.refractive_index) {
                (Some(_), Some(_)) => {
                    return Err(o.conflict(
                        "lens.refractive_index",
                        "lens.glass and lens.refractive_index both given: give one (a named glass, or a constant index without dispersion)".to_owned(),
                    ));
                }
                (None, Some(n)) => {
                    Glass::Constant(o.number("lens.refractive_index", n, n >= 1.0, "a refractive index ≥ 1")?)
                }
                (glass, None) => match glass.as_deref().unwrap_or("N-BK7") {
                    "N-BK7" => {
                        let (lo, hi) = Sellmeier::N_BK7.range();
                        if !(l0 >= lo && l0 <= hi) {
                            return Err(o.bad(
                                "lens.design_wavelength_nm",
                                num(l0 * 1e9),
                                "a wavelength in 300–2500 nm (where the N-BK7 Sellmeier formula holds)",
                            ));
                        }
                        Glass::Sellmeier(Sellmeier::N_BK7)
                    }
                    other => return Err(o.bad("lens.glass", quoted(other), GLASSES)),
                },
            };
            let elements = l.elements.unwrap_or(1);
            if !(1..=100).contains(&elements) {
                return Err(o.bad("lens.elements", elements, "a whole number of thin elements from 1 to 100"));
            }
            let surfaces = match l.coating_reflectance {
                Some(r) => Surfaces::Coated(o.number(
                    "lens.coating_reflectance",
                    r,
                    (0.0..1.0).contains(&r),
                    "a reflectance per surface in [0, 1)",
                )?),
                None => Surfaces::Uncoated,
            };
            let lens = Refractive::new(f_number, f0_m, l0, glass, elements, surfaces)
                .map_err(|e| o.domain("lens", "[lens]", e))?;
            let n0 = lens.index(l0).unwrap_or(1.0);
            info.notes.push(format!(
                "n(λ0) = {:.4}, τ = T = {:.4} at λ0 ({} element{}, {})",
                n0,
                lens.transmission(l0),
                elements,
                if elements == 1 { "" } else { "s" },
                match surfaces {
                    Surfaces::Uncoated => "uncoated".to_owned(),
                    Surfaces::Coated(r) => format!("coated, R = {} per surface", num(r)),
                }
            ));
            info.design_wavelength_m = Some(l0);
            Arc::new(lens)
        }
        Model::Dispersion => {
            let key = "lens.design_band_nm";
            let [lo, hi] = o.require(key, l.design_band_nm, "[λ_min, λ_max] in nm, 0 < λ_min < λ_max")?;
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
                return Err(o.bad(
                    key,
                    format!("[{}, {}]", num(lo), num(hi)),
                    "[λ_min, λ_max] in nm, 0 < λ_min < λ_max",
                ));
            }
            o.wavelength(key, lo);
            let key = "lens.group_delay_range_fs";
            let expected = "the meta-atom library's group-delay range > 0 fs";
            let delay = o.require(key, l.group_delay_range_fs, expected)?;
            let delay = o.number(key, delay, delay > 0.0, expected)?;
            let overflow = match l.delay_overflow.as_deref().unwrap_or("reject") {
                "reject" => DelayOverflow::Reject,
                "reduced" => DelayOverflow::Reduced,
                other => {
                    return Err(o.bad(
                        "lens.delay_overflow",
                        quoted(other),
                        "\"reject\" (refuse an aperture the library cannot make achromatic) or \"reduced\" (accept it partly chromatic)",
                    ));
                }
            };
            let efficiency = efficiency(o)?;
            let transmission = transmission(o, &efficiency)?;
            let required = required_group_delay(f0_m, f0_m / f_number);
            if overflow == DelayOverflow::Reject && required > delay * 1e-15 {
                let d_max = max_diameter(f0_m, delay * 1e-15);
                return Err(o.bad(
                    "lens.group_delay_range_fs",
                    num(delay),
                    &format!(
                        "at least ΔT_req = {:.2} fs, the group delay the aperture D = {} mm (F/{}) needs at f0 = {} mm; \
                         this library (ΔT_lib = {} fs) allows at most D_max = {:.1} µm (F/{:.2}): \
                         give a smaller aperture, a library of larger range, or lens.delay_overflow = \"reduced\"",
                        required * 1e15,
                        rounded(f0 / f_number),
                        rounded(f_number),
                        num(f0),
                        num(delay),
                        d_max * 1e6,
                        f0_m / d_max
                    ),
                ));
            }
            let lens = DispersionEngineered::new(
                f_number,
                f0_m,
                (lo * 1e-9, hi * 1e-9),
                delay * 1e-15,
                efficiency,
                transmission,
                overflow,
            )
            .map_err(|e| o.domain("lens", "[lens]", e))?;
            let beta = lens.true_delay_fraction();
            info.notes.push(if beta < 1.0 {
                format!(
                    "reduced achromatism: ΔT_req = {:.2} fs > ΔT_lib = {} fs, β = ΔT_lib/ΔT_req = {:.4} (D_max = {:.1} µm)",
                    required * 1e15,
                    num(delay),
                    beta,
                    max_diameter(f0_m, delay * 1e-15) * 1e6
                )
            } else {
                format!("true achromat: ΔT_req = {:.2} fs ≤ ΔT_lib = {} fs, β = 1", required * 1e15, num(delay))
            });
            info.design_wavelength_m = Some(0.5 * (lo + hi) * 1e-9);
            Arc::new(lens)
        }
        Model::Harmonic => {
            let l0 = design_wavelength(o)?;
            let key = "lens.design_order";
            let p = o.require(key, l.design_order, "a whole number from 1 to 1000 (the phase wraps at 2πp)")?;
            if !(1..=1000).contains(&p) {
                return Err(o.bad(key, p, "a whole number from 1 to 1000 (the phase wraps at 2πp)"));
            }
            let key = "lens.efficiency";
            let expected =
                "a fraction in [0, 1]: the peak efficiency τ_base of the design order (a harmonic lens takes no table)";
            let base = match o.require(key, l.efficiency.as_ref(), expected)? {
                NumberOrFile::Number(v) => o.number(key, *v, (0.0..=1.0).contains(v), expected)?,
                NumberOrFile::File(f) => return Err(o.bad(key, quoted(f), expected)),
            };
            let transmission = transmission(o, &Curve::Constant(base))?;
            let lens =
                Harmonic::new(f_number, f0_m, l0, p, base, transmission).map_err(|e| o.domain("lens", "[lens]", e))?;
            info.notes.push(format!("design order p = {p}: orders m with |m − p λ0/λ| ≤ 3"));
            info.design_wavelength_m = Some(l0);
            Arc::new(lens)
        }
        Model::Multiplexed => {
            let key = "lens.layout";
            let layouts = "\"segmented\" (zones side by side) or \"interleaved\" (meta-atoms interleaved)";
            let segmented = match o.require(key, l.layout.as_deref(), layouts)? {
                "interleaved" => false,
                "segmented" => true,
                other => return Err(o.bad(key, quoted(other), layouts)),
            };
            let other_channels = match l.other_channels.as_deref().unwrap_or("signal") {
                "signal" => lenses::OtherChannels::Signal,
                "background" if segmented => lenses::OtherChannels::Background,
                other => {
                    let expected = if segmented {
                        "\"signal\" (every zone's light is signal, with its defocus) or \"background\" (a zone's light is signal only in its channel's band)"
                    } else {
                        "\"signal\" (an interleaved lens's other channels form a defocused image over the full aperture: signal with its defocus in the OTF, docs/physics.md)"
                    };
                    return Err(o.bad("lens.other_channels", quoted(other), expected));
                }
            };
            let layout = if segmented {
                let zones = "\"concentric\" (rings, the first channel innermost), \"sectors\" (wedges) or \"mask\" (a zone map in lens.zone_mask)";
                // the mask is read once the channels are known (its zone numbers refer to them)
                let layout = match l.zones.as_deref().unwrap_or("concentric") {
                    "concentric" => Some(lenses::Layout::Concentric),
                    "sectors" => Some(lenses::Layout::Sectors),
                    "mask" => None,
                    other => return Err(o.bad("lens.zones", quoted(other), zones)),
                };
                if layout.is_some() {
                    o.forbid("lens.zone_mask", &l.zone_mask, "lens.zones other than \"mask\"")?;
                }
                Some(layout)
            } else {
                let ctx = "lens.layout = \"interleaved\"";
                o.forbid("lens.zones", &l.zones, ctx)?;
                o.forbid("lens.zone_mask", &l.zone_mask, ctx)?;
                o.forbid("lens.area_fractions", &l.area_fractions, ctx)?;
                None
            };
            let key = "lens.channels_nm";
            let expected = "1 to 16 channel wavelengths in nm, each > 0, increasing";
            let channels = o.require(key, l.channels_nm.as_ref(), expected)?;
            if channels.is_empty() || channels.len() > 16 {
                return Err(o.bad(key, format!("a list of {}", channels.len()), expected));
            }
            let mut prev = 0.0;
            for (j, &c) in channels.iter().enumerate() {
                // a segmented lens's channels are in its zones' order; an interleaved lens's increase
                let ok = if segmented { c > 0.0 && !channels[..j].contains(&c) } else { c > prev };
                let expected = if segmented {
                    "1 to 16 distinct channel wavelengths in nm, each > 0, in the zones' order"
                } else {
                    expected
                };
                o.number(&format!("{key}[{j}]"), c, ok, expected)?;
                o.wavelength(&format!("{key}[{j}]"), c);
                prev = c;
            }
            let etas: Vec<Curve> = match (&l.efficiency, &l.channel_efficiencies) {
                (Some(_), Some(_)) => {
                    return Err(o.conflict(
                        "lens.channel_efficiencies",
                        "lens.efficiency and lens.channel_efficiencies both given: give one (the same η for every channel, or one per channel)".to_owned(),
                    ));
                }
                (Some(e), None) => {
                    let eta = o.curve("lens.efficiency", e, "efficiency")?;
                    vec![eta; channels.len()]
                }
                (None, Some(list)) => {
                    if list.len() != channels.len() {
                        return Err(o.bad(
                            "lens.channel_efficiencies",
                            format!("a list of {}", list.len()),
                            &format!("one efficiency per channel: {} (as lens.channels_nm)", channels.len()),
                        ));
                    }
                    list.iter()
                        .enumerate()
                        .map(|(j, e)| o.curve(&format!("lens.channel_efficiencies[{j}]"), e, "efficiency"))
                        .collect::<Result<_, _>>()?
                }
                (None, None) => {
                    return Err(o.require::<()>(
                        "lens.efficiency",
                        None,
                        "each channel's efficiency η as if it filled the aperture: a fraction in [0, 1] or a CSV path (or lens.channel_efficiencies, one per channel)",
                    ).unwrap_err());
                }
            };
            let key = "lens.transmission";
            let expected = "the total transmission T into all channels and orders: a fraction in [0, 1] or a CSV path";
            let t = o.require(key, l.transmission.as_ref(), expected)?;
            let transmission = o.curve(key, t, "transmission")?;
            let n = channels.len();
            let list: Vec<Channel> =
                channels.iter().zip(etas).map(|(c, e)| Channel { wavelength_m: c * 1e-9, efficiency: e }).collect();
            info.channels_m = channels.iter().map(|c| c * 1e-9).collect();
            let (lo, hi) = channels.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), &c| (a.min(c), b.max(c)));
            info.design_wavelength_m = Some(0.5 * (lo + hi) * 1e-9);
            if let Some(layout) = layout {
                let layout = match layout {
                    Some(layout) => layout,
                    None => {
                        let key = "lens.zone_mask";
                        let expected = "the path of a zone-mask file: a square grid of zone numbers 1 to N (the channels of lens.channels_nm) or 0 for opaque over the aperture's bounding square, first row at the top";
                        let file = o.require(key, l.zone_mask.as_deref(), expected)?;
                        let grid = crate::tables::read_zone_grid(&o.path(file), n)
                            .map_err(|e| o.table_error(key, file, e, expected))?;
                        if grid.zones() < n {
                            return Err(o.bad(
                                key,
                                quoted(file),
                                &format!(
                                    "a zone for every channel: the grid's largest zone number is {} for {n} channels",
                                    grid.zones()
                                ),
                            ));
                        }
                        o.forbid(
                            "lens.area_fractions",
                            &l.area_fractions,
                            "lens.zones = \"mask\" (the areas are measured from the map)",
                        )?;
                        lenses::Layout::Mask(Arc::new(move |x, y| grid.at(x, y)))
                    }
                };
                let areas = match &l.area_fractions {
                    None => None,
                    Some(a) => {
                        let key = "lens.area_fractions";
                        let expected = "one area fraction per channel, each > 0, summing to at most 1";
                        if a.len() != n {
                            return Err(o.bad(key, format!("a list of {}", a.len()), expected));
                        }
                        for (j, &v) in a.iter().enumerate() {
                            o.number(&format!("{key}[{j}]"), v, v > 0.0 && v <= 1.0, expected)?;
                        }
                        let sum: f64 = a.iter().sum();
                        if sum > 1.0 + 1e-12 {
                            return Err(o.bad(key, format!("a list summing to {}", num(sum)), expected));
                        }
                        Some(a.clone())
                    }
                };
                let lens = lenses::Segmented::new(f_number, f0_m, list, layout, areas, transmission)
                    .map_err(|e| o.domain("lens", "[lens]", e))?
                    .with_other_channels(other_channels);
                info.kind = "multiplexed-segmented";
                let fractions: Vec<String> = lens.area_fractions().iter().map(|a| format!("{a:.4}")).collect();
                info.notes.push(format!(
                    "{n} {} zones, area fractions {}, τ_j = a_j η_j; other channels' light: {}",
                    l.zones.as_deref().unwrap_or("concentric"),
                    fractions.join(", "),
                    l.other_channels.as_deref().unwrap_or("signal")
                ));
                Arc::new(lens)
            } else {
                let lens =
                    Interleaved::new(f_number, f0_m, list, transmission).map_err(|e| o.domain("lens", "[lens]", e))?;
                info.kind = "multiplexed-interleaved";
                info.notes.push(format!("{n} interleaved channels, each τ_j = η_j/N² = η_j/{}", n * n));
                Arc::new(lens)
            }
        }
        Model::Tabulated => {
            let key = "lens.mtf";
            let expected = "the path of an MTF table: a CSV (wavelength_nm, frequency_cyc_per_mm, mtf[, sagittal]), a Zemax FFT MTF text export, or a list of Zemax exports (one per wavelength)";
            let files = o.require(key, l.mtf.as_ref(), expected)?.paths();
            if files.is_empty() || files.len() > 1000 {
                return Err(o.bad(key, format!("a list of {}", files.len()), expected));
            }
            let mut listings = Vec::new();
            let mut csv_table = None;
            for (i, &file) in files.iter().enumerate() {
                let item = if files.len() > 1 { format!("{key}[{i}]") } else { key.to_owned() };
                let path = o.path(file);
                let bytes = crate::tables::read_bytes(&path, "MTF table").map_err(|e| Error::Table {
                    origin: o.of(key),
                    key: o.key(&item),
                    file: crate::error::shorten(file),
                    cause: Box::new(e),
                })?;
                let ctx = format!("{item} = {}", quoted(file));
                if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv")) {
                    if files.len() > 1 {
                        return Err(o.bad(&item, quoted(file), "a Zemax export: a list holds one Zemax FFT MTF export per wavelength (a CSV table holds every wavelength itself: give it alone)"));
                    }
                    let text = lenses::decode_text(&bytes).map_err(|e| o.domain(&item, &ctx, e))?;
                    let rows = crate::tables::mtf_rows(&text).map_err(|e| o.domain(&item, &ctx, e))?;
                    csv_table = Some(lenses::mtf_table_from_rows(&rows).map_err(|e| o.domain(&item, &ctx, e))?);
                } else {
                    listings.push(lenses::parse_zemax_fft_mtf(&bytes).map_err(|e| o.domain(&item, &ctx, e))?);
                }
            }
            let ctx = format!("{key} = {}", files.iter().map(|f| quoted(f)).collect::<Vec<_>>().join(", "));
            // the Zemax field block: the on-axis one, or the one lens.mtf_field names (from 0)
            let field = match l.mtf_field {
                Some(i) if csv_table.is_some() => {
                    return Err(o.bad(
                        "lens.mtf_field",
                        i,
                        "no field index with a CSV table (it holds one curve per wavelength): only with Zemax exports",
                    ));
                }
                Some(i) => lenses::FieldChoice::Index(i as usize),
                None => lenses::FieldChoice::OnAxis,
            };
            let table = match csv_table {
                Some(table) => table,
                None => lenses::zemax_otf_table(&listings, field).map_err(|e| o.domain(key, &ctx, e))?,
            };
            let file = files.join(", ");
            let efficiency = efficiency(o)?;
            let transmission = transmission(o, &efficiency)?;
            let lens_efficiency = efficiency.clone();
            let pixel = match l.mtf_includes_pixel_um {
                Some(p) => Some(
                    o.number(
                        "lens.mtf_includes_pixel_um",
                        p,
                        p > 0.0,
                        "the pitch > 0 µm of the pixel whose MTF the table contains (divided out)",
                    )? * 1e-6,
                ),
                None => None,
            };
            let mut lens = lenses::Tabulated::new(f_number, f0_m, table, efficiency, transmission, pixel)
                .map_err(|e| o.domain("lens", "[lens]", e))?;
            if l.design_wavelength_nm.is_some() {
                let l0 = design_wavelength(o)?;
                lens = lens.with_design_wavelength(l0).map_err(|e| o.domain("lens", "[lens]", e))?;
                info.design_wavelength_m = Some(l0);
            }
            info.notes.push(format!("OTF table from {}", crate::error::shorten(&file)));
            let rows = lens.table().wavelengths();
            info.table_range = Some(crate::psf::TableRange {
                key,
                value: Some(files.iter().map(|f| quoted(&crate::error::shorten(f))).collect::<Vec<_>>().join(", ")),
                what: "table",
                ends: "end rows",
                range_m: (rows[0], rows[rows.len() - 1]),
                efficiency: match lens_efficiency {
                    Curve::Constant(v) => radiometry::Spectrum::Constant(v),
                    Curve::Table(t) => radiometry::Spectrum::Sampled(t),
                },
            });
            Arc::new(lens)
        }
        Model::Library if l.layout_grid.is_some() || l.layout_gds.is_some() => {
            let l0 = design_wavelength(o)?;
            Arc::new(crate::layout2d::library_map_lens(l, o, f_number, f0_m, l0, &mut info)?)
        }
        Model::Library => {
            let l0 = design_wavelength(o)?;
            let (lens, names) = library_lens(l, o, f_number, f0_m, l0)?;
            let lens = library_fabrication(l, o, lens, &names, &mut info)?;
            // the first order's pupil (a polynomial amplitude and phase in q, three terms) under
            // the radial engine's work budget: the atoms' phase errors or a layout that does not
            // follow the design phase leave a first order whose phase and amplitude turn fast
            let sigma = l.atom_phase_error_rad.unwrap_or(0.0);
            let (key, value) = if sigma > 0.0 {
                ("lens.atom_phase_error_rad", num(sigma))
            } else {
                ("lens.layout", quoted(l.layout.as_deref().unwrap_or_default()))
            };
            radial_work_within(&lens, l0, 3, o, key, &value, MAX_LIBRARY_WORK)?;
            info.design_wavelength_m = Some(l0);
            info.notes.push(format!(
                "at λ0: τ1 = {:.4}, T = {:.4} (first order from the zones' Fourier coefficients; the other orders are background)",
                lens.efficiency(l0),
                lens.transmission(l0)
            ));
            Arc::new(lens)
        }
        Model::Phase => {
            if let Some(z) = &o.zemax {
                info.notes.push(format!(
                    "from the Zemax file {}, surface {} (BINARY_2): {}{}",
                    crate::error::shorten(&z.file),
                    z.surface,
                    z.keys.join(", "),
                    z.notes.iter().map(|n| format!("; {n}")).collect::<String>()
                ));
            }
            let l0 = design_wavelength(o)?;
            info.design_wavelength_m = Some(l0);
            if l.phase_map.is_some() {
                Arc::new(phase_map_lens(l, o, f_number, f0_m, l0, efficiency(o)?, &transmission, &mut info)?)
            } else {
                Arc::new(phase_lens(l, o, f_number, f0_m, l0, efficiency(o)?, &transmission, &mut info)?)
            }
        }
        Model::Psf => Arc::new(psf_lens(l, o, f_number, f0_m, &transmission, &mut info)?),
    };
    // a phase lens and a 2-D layout take the terms themselves
    let two_d_layout = model == Model::Library && (l.layout_grid.is_some() || l.layout_gds.is_some());
    let lens = match zernike(l, o)? {
        Some(terms) if model != Model::Phase && !two_d_layout => {
            let probe = info.design_wavelength_m.or(info.channels_m.first().copied()).unwrap_or(550e-9);
            info.notes.push(zernike_note(&terms));
            let (count, given) = (terms.len(), zernike_note(&terms));
            let lens: Arc<dyn LensModel> = Arc::new(
                lenses::WithZernike::new(lens, terms, probe)
                    .map_err(|e| o.domain("lens.zernike_noll_rms_um", "[lens]", e))?,
            );
            radial_work(lens.as_ref(), probe, count, o, "lens.zernike_noll_rms_um", &given)?;
            lens
        }
        _ => lens,
    };
    Ok(BuiltLens { lens, info })
}

/// The `model = "library"` lens: `lens.library` ([`read_library`]) and `lens.layout` (`r_mm`
/// and the same parameter columns).
fn library_lens(
    l: &RawLens,
    o: &Origins,
    f_number: f64,
    f0_m: f64,
    l0: f64,
) -> Result<(lenses::LibraryLens, Vec<String>), Error> {
    let (library, names) = read_library(l, o)?;
    let names: Vec<&String> = names.iter().collect();
    let expected = "a CSV of the layout: r_mm at each ring's centre (equal pitch) and the library's parameter columns";
    let file = o.require("lens.layout", l.layout.as_deref(), expected)?;
    let (lheaders, lrows) = crate::tables::read_columns(&o.path(file), "layout")
        .map_err(|e| o.table_error("lens.layout", file, e, expected))?;
    let lctx = format!("lens.layout = {}", quoted(file));
    let Some(ir) = lheaders.iter().position(|h| h == "r_mm") else {
        return Err(o.bad(
            "lens.layout",
            quoted(file),
            &format!("{expected} (its header is `{}`)", lheaders.join(",")),
        ));
    };
    let mut indices = Vec::new();
    for n in &names {
        match lheaders.iter().position(|h| h == *n) {
            Some(i) => indices.push(i),
            None => {
                return Err(o.bad(
                    "lens.layout",
                    quoted(file),
                    &format!("the library's parameter column `{n}` (its header is `{}`)", lheaders.join(",")),
                ));
            }
        }
    }
    let ranges = library.ranges();
    let mut radii = Vec::with_capacity(lrows.len());
    let mut params = Vec::with_capacity(lrows.len());
    for (line, values) in &lrows {
        let p: Vec<f64> = indices.iter().map(|&i| values[i]).collect();
        for ((v, (lo, hi)), n) in p.iter().zip(&ranges).zip(&names) {
            if v < lo || v > hi {
                return Err(o.bad(
                    "lens.layout",
                    quoted(file),
                    &format!(
                        "every atom's {n} inside the library's range [{}, {}]: line {} has {}",
                        num(*lo),
                        num(*hi),
                        line.map_or("?".to_owned(), |l| l.to_string()),
                        num(*v)
                    ),
                ));
            }
        }
        radii.push(values[ir] * 1e-3);
        params.push(p);
    }
    let (lo, hi) = library.wavelength_range();
    if !(l0 >= lo && l0 <= hi) {
        return Err(o.bad(
            "lens.design_wavelength_nm",
            num(l0 * 1e9),
            &format!("a wavelength inside the library's, {}–{} nm", num(lo * 1e9), num(hi * 1e9)),
        ));
    }
    let source = format!(
        "library {} ({} parameter{}: {}), layout {}",
        crate::error::shorten(l.library.as_deref().unwrap_or_default()),
        names.len(),
        if names.len() == 1 { "" } else { "s" },
        names.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", "),
        crate::error::shorten(file)
    );
    let names = names.iter().map(|n| n.to_string()).collect();
    lenses::LibraryLens::new(f_number, f0_m, l0, Arc::new(library), radii, params, source)
        .map(|lens| (lens, names))
        .map_err(|e| o.domain("lens.layout", &lctx, e))
}

/// The library lens as fabricated: `lens.parameter_bias` (one per parameter column, added to
/// every layout atom's parameters) and the atoms' independent phase and amplitude errors
/// (`lens.atom_phase_error_rad`, `lens.atom_transmission_error`, drawn from
/// `lens.atom_error_seed`; docs/physics.md, "Fabrication errors of a library lens").
fn library_fabrication(
    l: &RawLens,
    o: &Origins,
    lens: lenses::LibraryLens,
    names: &[String],
    info: &mut LensInfo,
) -> Result<lenses::LibraryLens, Error> {
    let (phase, amplitude) =
        crate::lens_table::atom_error_sigmas(l, o, "those drawn below 0 are taken as 0 and counted in the notes")?;
    let seed = l.atom_error_seed.unwrap_or(0);
    let ranges = lens.library().ranges();
    let list = |b: &[f64]| format!("[{}]", b.iter().map(|&v| num(v)).collect::<Vec<_>>().join(", "));
    let bias = match &l.parameter_bias {
        None => vec![0.0; ranges.len()],
        Some(b) => {
            if b.len() != ranges.len() {
                return Err(o.bad(
                    "lens.parameter_bias",
                    list(b),
                    &format!(
                        "one bias per library parameter column, {} ({}), in that column's units",
                        ranges.len(),
                        names.join(", ")
                    ),
                ));
            }
            for (d, (&v, &(lo, hi))) in b.iter().zip(&ranges).enumerate() {
                if !v.is_finite() {
                    return Err(o.bad("lens.parameter_bias", list(b), "finite numbers"));
                }
                let values: Vec<f64> = lens.layout_parameters().iter().map(|p| p[d] + v).collect();
                let out = values.iter().filter(|&&x| x < lo || x > hi).count();
                if out > 0 {
                    let (min, max) =
                        values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, c), &x| (a.min(x), c.max(x)));
                    return Err(o.bad(
                        "lens.parameter_bias",
                        list(b),
                        &format!(
                            "a bias that keeps every atom inside the library: with {} = {} added, {out} of {} atoms leave the library's range [{}, {}] of {} (the biased layout spans [{}, {}])",
                            names[d],
                            num(v),
                            values.len(),
                            num(lo),
                            num(hi),
                            names[d],
                            num(min),
                            num(max)
                        ),
                    ));
                }
            }
            b.clone()
        }
    };
    let errors = lenses::AtomErrors { phase_sigma_rad: phase, transmission_sigma: amplitude, seed };
    let lens = lens.with_fabrication(&bias, errors).map_err(|e| o.domain("lens.parameter_bias", "[lens]", e))?;
    if phase > 0.0 || amplitude > 0.0 || bias.iter().any(|&b| b != 0.0) {
        info.notes.push(format!(
            "fabrication errors: parameter bias [{}], per-atom phase σ = {} rad and relative amplitude σ = {} over {} atoms (seed {seed}){}",
            bias.iter().map(|&b| num(b)).collect::<Vec<_>>().join(", "),
            num(phase),
            num(amplitude),
            lens.layout_atoms(),
            match lens.clamped_atoms() {
                0 => String::new(),
                n => format!("; {n} atoms' amplitude factor 1 + ε drawn below 0, taken as 0"),
            }
        ));
    }
    Ok(lens)
}

/// The `model = "phase"` lens: its profile (`binary2` or `phase_csv`), dispersion, efficiency.
#[allow(clippy::too_many_arguments)]
fn phase_lens(
    l: &RawLens,
    o: &Origins,
    f_number: f64,
    f0_m: f64,
    l0: f64,
    efficiency: Curve,
    transmission: &dyn Fn(&Origins, &Curve) -> Result<Curve, Error>,
    info: &mut LensInfo,
) -> Result<lenses::PhaseLens, Error> {
    let radius = 0.5 * f0_m / f_number;
    let spline = match &l.phase_spline_rad {
        Some(knots) => {
            for (i, &v) in knots.iter().enumerate() {
                o.number(&format!("lens.phase_spline_rad[{i}]"), v, v.is_finite(), "a finite phase in radians")?;
            }
            if !(lenses::SPLINE_MIN_KNOTS..=lenses::SPLINE_MAX_KNOTS).contains(&knots.len()) {
                return Err(o.bad(
                    "lens.phase_spline_rad",
                    format!("{} knots", knots.len()),
                    "3 to 1024 knots: the phase (radians at λ0) at equally spaced radii from the axis to the aperture's edge",
                ));
            }
            let profile = lenses::spline_profile(knots).map_err(|e| o.domain("lens.phase_spline_rad", "[lens]", e))?;
            Some((Arc::new(profile), format!("a spline of {} knots", knots.len())))
        }
        None => None,
    };
    // the phase per unit of each Binary 2 coefficient (the gradient's directions)
    let mut binary2_terms: Vec<f64> = Vec::new();
    let (phase, amplitude, source) = match (&l.binary2, &l.phase_csv, &spline) {
        (None, None, Some((profile, what))) => {
            for key in ["norm_radius_mm", "diffraction_order"] {
                if l.given().iter().any(|(k, g)| *k == key && *g) {
                    return Err(o.bad(
                        &format!("lens.{key}"),
                        "given",
                        "only with lens.binary2 (lens.phase_spline_rad is in radians at ρ = r/R)",
                    ));
                }
            }
            (profile.clone(), None, what.clone())
        }
        (Some(_), Some(_), _) => {
            return Err(o.conflict(
                "lens.phase_csv",
                "lens.binary2 and lens.phase_csv both given: give one profile (Zemax Binary 2 coefficients, or a radial table)".to_owned(),
            ));
        }
        (None, None, None) => {
            return Err(o.bad(
                "lens.binary2",
                "nothing",
                "the phase at λ0: binary2 = [A1, A2, …] (radians, Zemax Binary 2 with norm_radius_mm), phase_csv = \"file.csv\" (columns r_mm, phase_rad, optional amplitude), or phase_spline_rad = [φ0, …, φN] (radians at N + 1 equally spaced radii, axis to edge)",
            ));
        }
        (Some(coefficients), None, _) => {
            o.forbid("lens.phase_csv", &l.phase_csv, "lens.binary2")?;
            for (i, &a) in coefficients.iter().enumerate() {
                o.number(&format!("lens.binary2[{i}]"), a, a.is_finite(), "a finite coefficient in radians")?;
            }
            if coefficients.is_empty() {
                return Err(o.bad("lens.binary2", "[]", "at least one coefficient A1 (radians)"));
            }
            let norm = match l.norm_radius_mm {
                Some(r) => o.number("lens.norm_radius_mm", r, r > 0.0, "a length > 0 mm")? * 1e-3,
                None => {
                    info.notes.push(format!("norm_radius_mm not given: the aperture radius {} mm", num(radius * 1e3)));
                    radius
                }
            };
            let m = l.diffraction_order.unwrap_or(1.0);
            let m = o.number(
                "lens.diffraction_order",
                m,
                m != 0.0 && m.abs() <= 1e3,
                "Zemax's diffraction order M, non-zero (default 1)",
            )?;
            // each term M A_i (r/R_norm)^{2i} at the aperture's edge must be a number: a tiny
            // R_norm (1e-300 mm) overflows it to ∞, which the profile then refused naming no key
            let scale = (radius / norm).powi(2);
            let mut power = 1.0_f64;
            for (i, &a) in coefficients.iter().enumerate() {
                power *= scale;
                if !(m * a * power).is_finite() {
                    let given = l.norm_radius_mm.is_some();
                    let (key, value) = if given && !power.is_finite() {
                        ("lens.norm_radius_mm".to_owned(), num(norm * 1e3))
                    } else {
                        (format!("lens.binary2[{i}]"), num(a))
                    };
                    return Err(o.bad(
                        &key,
                        value,
                        &format!(
                            "a profile whose term M·A{} (r/R_norm)^{} stays finite at the aperture's edge, r = {} mm (R_norm = {} mm, M = {}): it is beyond the largest number, about 1.8e308",
                            i + 1,
                            2 * (i + 1),
                            num(radius * 1e3),
                            num(norm * 1e3),
                            num(m)
                        ),
                    ));
                }
            }
            let mut power = 1.0_f64;
            binary2_terms = (0..coefficients.len())
                .map(|_| {
                    power *= scale;
                    m * power
                })
                .collect();
            let profile = lenses::binary2_profile(coefficients, m, norm, radius)
                .map_err(|e| o.domain("lens.binary2", "[lens]", e))?;
            (
                Arc::new(profile),
                None,
                format!(
                    "Zemax Binary 2, {} terms, R_norm = {} mm, M = {}",
                    coefficients.len(),
                    num(norm * 1e3),
                    num(m)
                ),
            )
        }
        (None, Some(file), _) => {
            for key in ["norm_radius_mm", "diffraction_order"] {
                if l.given().iter().any(|(k, g)| *k == key && *g) {
                    return Err(o.bad(
                        &format!("lens.{key}"),
                        "given",
                        "only with lens.binary2 (a phase table is in r_mm)",
                    ));
                }
            }
            let path = o.path(file);
            let table = crate::tables::read_phase_table(&path, radius * 1e3)
                .map_err(|e| o.table_error("lens.phase_csv", file, e, "a CSV of r_mm, phase_rad[, amplitude]"))?;
            let rho: Vec<f64> = table.r_mm.iter().map(|r| r * 1e-3 / radius).collect();
            let phase = optics::radial::RadialProfile::table(rho.clone(), table.phase_rad)
                .map_err(|e| o.domain("lens.phase_csv", "[lens]", lenses::Error::Pupil(e)))?;
            let amplitude = match table.amplitude {
                Some(a) => Some(Arc::new(
                    optics::radial::RadialProfile::table(rho, a)
                        .map_err(|e| o.domain("lens.phase_csv", "[lens]", lenses::Error::Pupil(e)))?,
                )),
                None => None,
            };
            (Arc::new(phase), amplitude, format!("phase table {}", crate::error::shorten(file)))
        }
    };
    let dispersion = dispersion(l, o, info)?;
    let transmission = transmission(o, &efficiency)?;
    let alone = l.binary2.is_none() && l.phase_csv.is_none();
    // the phase's change with the aperture radius R = f0/(2F#), the focal length held (the
    // gradient's F-number and focal length, docs/physics.md "Gradients"): a profile given in r
    // (Binary 2 with its own R_norm, a table in r_mm) moves along R ∂φ0/∂R, one given in ρ (a
    // spline, Binary 2 normalized to the aperture) does not; a table's amplitude in r_mm would
    // move the pupil's amplitude, which the derivative lanes do not follow: not recorded
    let moves = (l.binary2.is_some() && l.norm_radius_mm.is_some()) || l.phase_csv.is_some();
    let motion = match (moves, &amplitude) {
        (false, _) => optics::radial::RadialProfile::even_polynomial(vec![0.0]).map_err(|e| e.to_string()),
        (true, None) => {
            phase.radius_log_derivative().ok_or_else(|| "the phase profile has no such derivative".to_owned())
        }
        (true, Some(_)) => Err(
            "the phase table's amplitude column is in r_mm, so the pupil's amplitude moves with the aperture radius \
             R = f0/(2F#), which the radial engine's lanes (changes of the wavefront) do not follow"
                .to_owned(),
        ),
    };
    let mut lens =
        lenses::PhaseLens::new(f_number, f0_m, l0, phase, amplitude, dispersion, efficiency, transmission, source)
            .map_err(|e| o.domain("lens", "[lens]", e))?
            .with_binary2_terms(binary2_terms)
            .with_spline_knots(l.phase_spline_rad.as_ref().map_or(0, Vec::len))
            .with_zernike_directions(l.zernike_noll_rms_um.as_ref().map_or(0, Vec::len));
    lens = lens.with_aperture_motion(motion);
    let spline_what = spline.as_ref().map(|(_, what)| what.clone());
    if let Some((profile, what)) = spline
        && !alone
    {
        lens = lens.with_added_phase(profile, &what);
    }
    // the profile alone, then with the Zernike terms: each refusal names what made it
    let mut count = l.binary2.as_ref().map_or(0, Vec::len)
        + if l.phase_csv.is_some() { RADIAL_TABLE_TERMS } else { 0 }
        + if spline_what.is_some() { RADIAL_TABLE_TERMS } else { 0 };
    match (&l.binary2, &l.phase_csv, &spline_what) {
        (Some(b), _, _) => radial_work(&lens, l0, count, o, "lens.binary2", &format!("[{} coefficients]", b.len()))?,
        (None, Some(file), _) => radial_work(&lens, l0, count, o, "lens.phase_csv", &quoted(file))?,
        (None, None, Some(what)) => radial_work(&lens, l0, count, o, "lens.phase_spline_rad", what)?,
        (None, None, None) => {}
    }
    if let Some(terms) = zernike(l, o)? {
        info.notes.push(zernike_note(&terms));
        count += terms.len();
        let given = zernike_note(&terms);
        lens = lens.with_zernike(terms).map_err(|e| o.domain("lens.zernike_noll_rms_um", "[lens]", e))?;
        radial_work(&lens, l0, count, o, "lens.zernike_noll_rms_um", &given)?;
    }
    Ok(lens)
}

/// `lens.dispersion` (with `design_order`, `glass`) of a phase lens.
fn dispersion(l: &RawLens, o: &Origins, info: &mut LensInfo) -> Result<lenses::Dispersion, Error> {
    let dispersions = "\"geometric-phase\" (radian phase fixed: one order, f ∝ 1/λ), \"diffractive\" (a kinoform wrapped at 2πp: orders m, τ_m = τ sinc²(pλ0/λ − m)) or \"refractive\" (optical path fixed)";
    let dispersion = match o.require("lens.dispersion", l.dispersion.as_deref(), dispersions)? {
        "geometric-phase" => {
            o.forbid("lens.design_order", &l.design_order, "lens.dispersion = \"geometric-phase\"")?;
            o.forbid("lens.glass", &l.glass, "lens.dispersion = \"geometric-phase\"")?;
            lenses::Dispersion::GeometricPhase
        }
        "diffractive" => {
            o.forbid("lens.glass", &l.glass, "lens.dispersion = \"diffractive\"")?;
            let p = l.design_order.unwrap_or(1);
            if !(1..=1000).contains(&p) {
                return Err(o.bad("lens.design_order", p, "a whole number from 1 to 1000 (the phase wraps at 2πp)"));
            }
            if l.design_order.is_none() {
                info.notes.push("design_order not given: p = 1 (the ordinary diffractive lens)".to_owned());
            }
            lenses::Dispersion::Diffractive { design_order: p }
        }
        "refractive" => {
            o.forbid("lens.design_order", &l.design_order, "lens.dispersion = \"refractive\"")?;
            let glass = match l.glass.as_deref() {
                None => None,
                Some("N-BK7") => Some(Sellmeier::N_BK7),
                Some(other) => return Err(o.bad("lens.glass", quoted(other), GLASSES)),
            };
            lenses::Dispersion::Refractive { glass }
        }
        other => return Err(o.bad("lens.dispersion", quoted(other), dispersions)),
    };
    Ok(dispersion)
}

#[allow(clippy::too_many_arguments)]
/// The `model = "phase"` lens given by a 2-D map (`phase_map`, docs/physics.md "Phase maps"):
/// the `.npy` maps read (sizes checked against the file before the samples), the map's coverage
/// of the aperture, its values and its cells' phase steps checked with the numbers.
fn phase_map_lens(
    l: &RawLens,
    o: &Origins,
    f_number: f64,
    f0_m: f64,
    l0: f64,
    efficiency: Curve,
    transmission: &dyn Fn(&Origins, &Curve) -> Result<Curve, Error>,
    info: &mut LensInfo,
) -> Result<lenses::PhaseMapLens, Error> {
    for (key, given) in [
        ("binary2", l.binary2.is_some()),
        ("phase_csv", l.phase_csv.is_some()),
        ("phase_spline_rad", l.phase_spline_rad.is_some()),
        ("norm_radius_mm", l.norm_radius_mm.is_some()),
        ("diffraction_order", l.diffraction_order.is_some()),
        ("zernike_noll_rms_um", l.zernike_noll_rms_um.is_some()),
    ] {
        if given {
            return Err(o.bad(
                &format!("lens.{key}"),
                "given",
                "not with lens.phase_map (the map is the whole phase: add any other term to it)",
            ));
        }
    }
    let file = l.phase_map.as_deref().unwrap_or_default();
    let pitch = o.require(
        "lens.phase_map_pitch_um",
        l.phase_map_pitch_um,
        "the map's cell pitch in µm (each sample is held over its cell)",
    )?;
    let pitch = o.number("lens.phase_map_pitch_um", pitch, pitch > 0.0, "a pitch > 0 µm")? * 1e-6;
    let aperture = match l.aperture.as_deref().unwrap_or("circle") {
        "circle" => optics::map::MapAperture::Circle,
        "square" => optics::map::MapAperture::Square,
        other => {
            return Err(o.bad(
                "lens.aperture",
                quoted(other),
                "\"circle\" (default: diameter f0/F#) or \"square\" (side f0/F#, 4/π of the circle's light)",
            ));
        }
    };
    let read = |key: &str, file: &str| {
        let path = o.path(file);
        crate::psf::map_of(o, key, file).map_err(|message| Error::Table {
            origin: o.of(key),
            key: o.key(key),
            file: crate::error::shorten(file),
            cause: Box::new(Error::Csv { file: path.display().to_string(), line: None, message }),
        })
    };
    let phase = read("lens.phase_map", file)?;
    let amplitude = match &l.amplitude_map {
        Some(a) => {
            let map = read("lens.amplitude_map", a)?;
            if (map.ny, map.nx) != (phase.ny, phase.nx) {
                return Err(o.bad(
                    "lens.amplitude_map",
                    format!("an array of {} × {} [y, x]", map.ny, map.nx),
                    &format!("the phase map's shape, {} × {}", phase.ny, phase.nx),
                ));
            }
            Some(map.values)
        }
        None => None,
    };
    let radius = 0.5 * f0_m / f_number;
    let r = optics::round_for_display;
    let (nx, ny) = (phase.nx, phase.ny);
    let half = 0.5 * (nx.min(ny)) as f64 * pitch;
    if half < radius * (1.0 - 1e-12) {
        return Err(o.bad(
            "lens.phase_map",
            format!("{ny} × {nx} cells of {} µm ({} × {} mm)", r(pitch * 1e6), r(ny as f64 * pitch * 1e3), r(nx as f64 * pitch * 1e3)),
            &format!(
                "a map covering the aperture ({} mm across: f0/F#), centred on the axis: at least {} cells a side at this pitch",
                r(2.0 * radius * 1e3),
                (2.0 * radius / pitch * (1.0 - 1e-12)).ceil()
            ),
        ));
    }
    let dispersion = dispersion(l, o, info)?;
    let stored = lenses::PhaseMapLens::stored_phase(&dispersion);
    // the values inside the aperture first: a NaN is named with its cell
    let centre = |i: usize, j: usize| {
        [(i as f64 - 0.5 * (nx as f64 - 1.0)) * pitch * 1e3, (j as f64 - 0.5 * (ny as f64 - 1.0)) * pitch * 1e3]
    };
    let inside = |i: usize, j: usize| {
        let [x, y] = centre(i, j);
        let near = |c: f64| (c.abs() - 0.5 * pitch * 1e3).max(0.0) / (radius * 1e3);
        aperture.contains(near(x), near(y))
    };
    for (key, values) in [("lens.phase_map", Some(&phase.values)), ("lens.amplitude_map", amplitude.as_ref())] {
        let Some(values) = values else { continue };
        for j in 0..ny {
            for i in 0..nx {
                let v = values[j * nx + i];
                let ok = v.is_finite() && (key == "lens.phase_map" || v >= 0.0);
                if !ok && inside(i, j) {
                    let [x, y] = centre(i, j);
                    return Err(o.bad(
                        key,
                        format!("{} at [y, x] = [{j}, {i}] (x = {} mm, y = {} mm)", num(v), r(x), r(y)),
                        if key == "lens.phase_map" {
                            "finite radians inside the aperture"
                        } else {
                            "finite and ≥ 0 inside the aperture"
                        },
                    ));
                }
            }
        }
    }
    let map = optics::map::PhaseMap::new(nx, ny, pitch, phase.values, amplitude, aperture, radius, f0_m, l0, stored)
        .map_err(|e| o.domain("lens.phase_map", "[lens]", lenses::Error::Pupil(e)))?;
    // the cell must resolve the focusing phase: the reference sphere's step per cell ≤ π
    let (step, cell) = map.largest_sphere_step();
    if step > std::f64::consts::PI {
        return Err(o.bad(
            "lens.phase_map_pitch_um",
            num(pitch * 1e6),
            &format!(
                "cells that resolve the lens's phase gradient: at x = {} mm, y = {} mm ([y, x] = [{}, {}]) the focusing phase turns by {} rad a cell, more than π (a pitch ≤ {} µm there)",
                r(cell.centre_m[0] * 1e3),
                r(cell.centre_m[1] * 1e3),
                cell.index[1],
                cell.index[0],
                r(step),
                r(pitch * 1e6 * std::f64::consts::PI / step)
            ),
        ));
    }
    // refractive and diffractive lenses scale φ0 with λ: the map must be unwrapped
    if stored == optics::map::StoredPhase::Given
        && let Some(cell) = map.first_jump()
    {
        return Err(o.bad(
            "lens.phase_map",
            format!(
                "a step of {} rad between neighbouring cells at x = {} mm, y = {} mm ([y, x] = [{}, {}])",
                r(cell.value),
                r(cell.centre_m[0] * 1e3),
                r(cell.centre_m[1] * 1e3),
                cell.index[1],
                cell.index[0]
            ),
            &format!(
                "the unwrapped phase φ0 for dispersion = \"{}\" (neighbours within π: a wrapped map is allowed with \"geometric-phase\" only), on cells fine enough for its gradient",
                dispersion.name()
            ),
        ));
    }
    let transmission = transmission(o, &efficiency)?;
    let source = format!("phase map {}", crate::error::shorten(file));
    lenses::PhaseMapLens::new(f_number, f0_m, l0, Arc::new(map), dispersion, efficiency, transmission, source)
        .map_err(|e| o.domain("lens", "[lens]", e))
}

/// The cost of a term of a radial table's phase, in units of a polynomial term (a spline piece).
const RADIAL_TABLE_TERMS: usize = 4;

/// The largest work the radial engine is given, in units of `(1 + Φ/16)² max(1, terms/16)`
/// ([`radial_work`]). Release timings on the F/2.5 phase lens of examples/phase-binary2.toml
/// over its 50 nm band: Z11 = 1 µm (`--set 'lens.zernike_noll_rms_um=[0,0,0,0,0,0,0,0,0,0,1]'`,
/// Φ = 210 rad, 199 units) 3.5 s and 5 µm (4440 units) more than 60 s; a Binary 2 profile of
/// A1, A2 and 200 terms of 1e-3 rad (Φ = 20 rad, 64 units) 2.4 s and of 400 terms (900 units)
/// 40 s. 600 units: about 10 s at most.
pub(crate) const MAX_RADIAL_WORK: f64 = 600.0;

/// The [`radial_work`] budget of a meta-atom library lens's first order, whose unit costs about
/// ten times a phase profile's (its pupil is refitted at every wavelength of the spectral rule,
/// and its amplitude turns too). Release timings on examples/library.toml over its 50 nm band,
/// CPU time of `asnr evaluate` (which evaluates a second time for the pupil-mapping check):
/// `lens.atom_phase_error_rad` 0 (1.1 units) 0.25 s, 1 (25 units) 5.7 s, 1.5 (237 units) 49 s;
/// 2 is 2450 units and 3 is 1.06e4. 60 units stand for about 10 s.
pub(crate) const MAX_LIBRARY_WORK: f64 = 60.0;

/// Refuses, before any rule is built, a lens whose radial pupil would cost the radial engine
/// more than [`MAX_RADIAL_WORK`]: its autocorrelation integral takes Gauss–Legendre panels of 16
/// points turning by at most 16 rad each along both of its variables (`optics::radial`, module
/// docs), so each OTF value costs about `(1 + Φ/16)²` panels, where `Φ = (2π/λ) osc W'` is the
/// phase by which the OPD's slope in `q = ρ²` can turn the integrand (`osc` its largest less its
/// smallest value on `[0, 1]`; the best-fit defocus, linear in `q`, does not change it); each
/// node evaluates the phase's Chebyshev series (at most 64 terms), or beyond it the profile's
/// own terms: `max(1, terms/16)`. `W'` is taken by differences at 1024 points at `probe_m`, on
/// axis. `key` and `value` name what sets the profile.
fn radial_work(
    lens: &dyn LensModel,
    probe_m: f64,
    terms: usize,
    o: &Origins,
    key: &str,
    value: &str,
) -> Result<(), Error> {
    radial_work_within(lens, probe_m, terms, o, key, value, MAX_RADIAL_WORK)
}

/// [`radial_work`] against `limit` units.
fn radial_work_within(
    lens: &dyn LensModel,
    probe_m: f64,
    terms: usize,
    o: &Origins,
    key: &str,
    value: &str,
    limit: f64,
) -> Result<(), Error> {
    for order in lens.orders(probe_m, optics::Field::ON_AXIS) {
        let optics::Pupil::Radial(pupil) = &order.pupil else { continue };
        const N: usize = 1024;
        let w: Vec<f64> = (0..=N).map(|i| pupil.opd_beyond_defocus_m(i as f64 / N as f64)).collect();
        let slopes = w.windows(2).map(|p| (p[1] - p[0]) * N as f64);
        let (lo, hi) = slopes.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)));
        let phase = std::f64::consts::TAU / probe_m * (hi - lo);
        // an amplitude's relative slope turns the integrand too: the engine counts
        // 4 max|A'(q)|/rms(A) radians for it (`optics::radial`, `amplitude_turns`)
        let a: Vec<f64> = (0..=N).map(|i| pupil.amplitude(i as f64 / N as f64)).collect();
        let a_slope = a.windows(2).map(|p| ((p[1] - p[0]) * N as f64).abs()).fold(0.0, f64::max);
        let a_rms = (a.iter().map(|v| v * v).sum::<f64>() / a.len() as f64).sqrt();
        let turns = if a_slope == 0.0 { 0.0 } else { 4.0 * a_slope / a_rms.max(f64::MIN_POSITIVE) };
        let phase = phase + turns;
        let work = (1.0 + phase / 16.0).powi(2) * (terms as f64 / 16.0).max(1.0);
        if work.is_nan() || work > limit {
            return Err(o.bad(
                key,
                value,
                &format!(
                    "a profile the radial engine integrates in seconds: the slope of its path beyond the best-fit defocus{} turns the phase by {} rad at {} nm across the pupil, with {terms} terms, about {} units of work (1 + phase/16)² max(1, terms/16), beyond the {limit} allowed (about 10 s; the work grows as the square of that phase, and with the terms beyond 16); reduce {key}",
                    if turns > 1.0 { format!(" and its amplitude's relative slope ({turns:.3e} rad)") } else { String::new() },
                    if phase.is_finite() { format!("{phase:.3e}") } else { "more than 1.8e308".to_owned() },
                    num(optics::round_for_display(probe_m * 1e9)),
                    if work.is_finite() { format!("{work:.2e}") } else { "more than 1.8e308".to_owned() },
                ),
            ));
        }
    }
    Ok(())
}

/// The `model = "psf"` lens of a `[lens]` table.
pub(crate) fn psf_lens(
    l: &RawLens,
    o: &Origins,
    f_number: f64,
    f0_m: f64,
    transmission: &dyn Fn(&Origins, &Curve) -> Result<Curve, Error>,
    info: &mut LensInfo,
) -> Result<PsfStack, Error> {
    let key = "lens.psf";
    let file = o.require(key, l.psf.as_deref(), &format!("the path of a PSF stack: {ACCEPTED}"))?;
    // from 1 nm: a finer pitch is far below any wavelength the stack samples, and 1e-304 µm
    // made the OTF table's frequencies 1/(n p) infinite
    let expected = "the stack's sample pitch at the detector, from 0.001 µm (1 nm) to below 1e6 µm";
    let pitch = o.require("lens.psf_pitch_um", l.psf_pitch_um, expected)?;
    let pitch = o.number("lens.psf_pitch_um", pitch, (1e-3..1e6).contains(&pitch), expected)?;
    let wkey = "lens.psf_wavelengths_nm";
    let expected = "the wavelength of each slice of the stack, nm, > 0 and strictly increasing";
    let wavelengths = o.require(wkey, l.psf_wavelengths_nm.as_ref(), expected)?;
    for (i, &w) in wavelengths.iter().enumerate() {
        let ok = w > 0.0 && (i == 0 || w > wavelengths[i - 1]);
        o.number(&format!("{wkey}[{i}]"), w, ok, expected)?;
        o.wavelength(&format!("{wkey}[{i}]"), w);
    }
    let e = o.require(
        "lens.efficiency",
        l.efficiency.as_ref(),
        "the imaging efficiency τ(λ), a fraction in [0, 1] or a CSV path: required with a PSF stack, which is normalized and carries no efficiency",
    )?;
    let efficiency = o.curve("lens.efficiency", e, "efficiency")?;
    let transmission = transmission(o, &efficiency)?;
    let path = o.path(file);
    let stack = read_stack(&path).map_err(|message| Error::Table {
        origin: o.of(key),
        key: o.key(key),
        file: crate::error::shorten(file),
        cause: Box::new(Error::Csv { file: path.display().to_string(), line: None, message }),
    })?;
    let shape = format!("{} × {} × {}", stack.depth, stack.ny, stack.nx);
    if stack.depth != wavelengths.len() {
        return Err(o.bad(
            wkey,
            format!("a list of {}", wavelengths.len()),
            &format!(
                "one wavelength per slice of lens.psf = {}: {} (its shape is {shape}, [wavelength, y, x])",
                quoted(file),
                stack.depth
            ),
        ));
    }
    let efficiency_spectrum = match &efficiency {
        Curve::Constant(v) => Spectrum::Constant(*v),
        Curve::Table(t) => Spectrum::Sampled(t.clone()),
    };
    let range = (wavelengths[0] * 1e-9, wavelengths[wavelengths.len() - 1] * 1e-9);
    let mut lens = PsfStack::new(
        f_number,
        f0_m,
        pitch * 1e-6,
        wavelengths.iter().map(|w| w * 1e-9).collect(),
        [stack.ny, stack.nx],
        &stack.values,
        efficiency,
        transmission,
    )
    .map_err(|e| o.domain(key, &format!("{key} = {}", quoted(file)), e))?;
    if l.design_wavelength_nm.is_some() {
        let v = l.design_wavelength_nm.unwrap_or_default();
        let v = o.number("lens.design_wavelength_nm", v, v > 0.0, "a wavelength > 0 nm")?;
        o.wavelength("lens.design_wavelength_nm", v);
        lens = lens.with_design_wavelength(v * 1e-9).map_err(|e| o.domain("lens", "[lens]", e))?;
        info.design_wavelength_m = Some(v * 1e-9);
    }
    let report = lens.report().clone();
    let (alias, at) = report.aliasing;
    let aliasing = |alias: f64| {
        format!(
            "the stack's spectrum at its Nyquist frequency 1/(2p) = {:.1} cycles/mm is {:.3e} (slice at {} nm): the PSF is undersampled, and the aliases folded about that frequency may add up to {:.3e} to the MTF below it and to the mean MTF (half the spectrum there, the OTF at 1/(2p), if the MTF does not rise beyond it)",
            lens.nyquist() * 1e-3,
            2.0 * alias,
            num(optics::round_for_display(at * 1e9)),
            alias
        )
    };
    if alias > ALIASING_MAX {
        return Err(o.bad(
            "lens.psf_pitch_um",
            num(pitch),
            &format!(
                "a pitch that samples the PSF ({}; at most {ALIASING_MAX} accepted, warned above {ALIASING_WARNED:e}): sample it finer, e.g. at λ F#/2 (`asnr psf --stack` does)",
                aliasing(alias)
            ),
        ));
    }
    let mut notices = Vec::new();
    if alias > ALIASING_WARNED {
        notices.push((quoted(file), aliasing(alias)));
    }
    let (border, at) = report.border_fraction;
    if border > BORDER_WARNED {
        notices.push((
            quoted(file),
            format!(
                "{:.3} % of the light of the slice at {} nm lies within {} samples of the stack's border: the PSF may be cut off (a larger stack would hold it)",
                border * 100.0,
                num(optics::round_for_display(at * 1e9)),
                lenses::PSF_BORDER_SAMPLES
            ),
        ));
    }
    let (im, at, nu) = report.imaginary;
    if im > IMAGINARY_WARNED {
        notices.push((
            quoted(file),
            format!(
                "the PSF at {} nm is asymmetric about its centroid: its OTF has an imaginary part of {im:.3} at {:.1} cycles/mm, which the table (the real part) leaves out",
                num(optics::round_for_display(at * 1e9)),
                nu * 1e-3
            ),
        ));
    }
    let shifts = report.centroids_m.iter().map(|c| c[0].hypot(c[1])).fold(0.0, f64::max);
    info.notes.push(format!(
        "PSF stack {}: {shape} at {} µm, {}–{} nm; OTF to the stack's Nyquist {:.1} cycles/mm, the samples' exact transform at every frequency (tabulated on {} points, zero padded ×{}), linear in λ between slices; aliasing estimate {:.1e}; centroid offsets up to {:.3} µm kept as lateral shifts",
        crate::error::shorten(file),
        num(pitch),
        num(wavelengths[0]),
        num(wavelengths[wavelengths.len() - 1]),
        lens.nyquist() * 1e-3,
        report.transform_length,
        lenses::PSF_PADDING,
        report.aliasing.0,
        shifts * 1e6
    ));
    info.psf = Some(PsfLimits { pitch_m: pitch * 1e-6, notices });
    info.table_range = Some(TableRange {
        key: "lens.psf_wavelengths_nm",
        value: None,
        what: "stack",
        ends: "end slices",
        range_m: range,
        efficiency: efficiency_spectrum,
    });
    Ok(lens)
}

/// The working F-number from `lens.f_number` or `lens.aperture_diameter_mm` (exactly one).
fn f_number(l: &RawLens, o: &Origins, f0_mm: f64) -> Result<f64, Error> {
    let expected = "a number ≥ 0.5 (NA = 1/(2F#) ≤ 1)";
    match (l.f_number, l.aperture_diameter_mm) {
        (Some(_), Some(_)) => Err(o.conflict(
            "lens.aperture_diameter_mm",
            "lens.f_number and lens.aperture_diameter_mm both given: give one (F# = f0/D)".to_owned(),
        )),
        (None, None) => Err(o
            .require::<()>("lens.f_number", None, &format!("{expected}, or lens.aperture_diameter_mm (F# = f0/D)"))
            .unwrap_err()),
        (Some(f), None) => o.number("lens.f_number", f, f >= 0.5, expected),
        (None, Some(d)) => {
            let key = "lens.aperture_diameter_mm";
            let ok = d > 0.0 && f0_mm / d >= 0.5;
            let expected = format!("a diameter > 0 mm and ≤ 2 f0 = {} mm (F# = f0/D ≥ 0.5)", num(2.0 * f0_mm));
            o.number(key, d, ok, &expected)?;
            Ok(f0_mm / d)
        }
    }
}

/// `v` to 6 significant digits.
fn rounded(v: f64) -> String {
    num(format!("{v:.5e}").parse::<f64>().unwrap_or(v))
}

/// The iris, when the scene makes it other than the centred full circle (a decentre of 0 and an
/// obscuration of 0 are the default pupil, computed exactly as without the keys).
fn aperture(l: &RawLens, o: &Origins) -> Result<Option<optics::fft::Aperture>, Error> {
    let decentre = "a fraction of the aperture radius in (−1, 1)";
    let open = |key: &str, v: Option<f64>| v.map(|v| o.number(key, v, v > -1.0 && v < 1.0, decentre)).transpose();
    let dx = open("lens.iris_decentre_x", l.iris_decentre_x)?.unwrap_or(0.0);
    let dy = open("lens.iris_decentre_y", l.iris_decentre_y)?.unwrap_or(0.0);
    let obscuration = match l.obscuration {
        Some(v) => o.number("lens.obscuration", v, (0.0..1.0).contains(&v), "a ratio of radii in [0, 1)")?,
        None => 0.0,
    };
    let sector = match l.sector_deg {
        Some([a, b]) => {
            let key = "lens.sector_deg";
            if !(a.is_finite() && b.is_finite() && b > a && b - a <= 360.0) {
                return Err(o.bad(
                    key,
                    format!("[{}, {}]", num(a), num(b)),
                    "[start, end] in degrees with start < end ≤ start + 360",
                ));
            }
            Some((a.to_radians(), b.to_radians()))
        }
        None => None,
    };
    if dx == 0.0 && dy == 0.0 && obscuration == 0.0 && sector.is_none() {
        return Ok(None);
    }
    let shape = optics::fft::Aperture::disc(obscuration, sector)
        .map_err(|e| o.domain("lens", "lens.obscuration / lens.sector_deg", e))?;
    let shape = shape.decentred(dx, dy).map_err(|e| o.domain("lens", "lens.iris_decentre_x / _y", e))?;
    Ok(Some(shape))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every preset's keys build the lens `lenses::preset` builds of that name (ndao2020: τ = 0.7 × 0.8,
    /// written as the f64 it is) (same description
    /// and transfer at three wavelengths), or are refused as it is.
    #[test]
    fn presets_are_the_lenses_presets() {
        assert_eq!(PRESETS.iter().map(|(n, _)| *n).collect::<Vec<_>>(), lenses::preset_names());
        for (name, _) in PRESETS {
            let text = crate::PAPER_SCENE.replace(
                &crate::PAPER_SCENE
                    [crate::PAPER_SCENE.find("[lens]").unwrap()..crate::PAPER_SCENE.find("[source]").unwrap()],
                &format!("[lens]\npreset = \"{name}\"\n\n"),
            );
            let source = crate::Source::from_text(text, "p", ".");
            match (crate::build_from(&source, &[]), lenses::preset(name)) {
                (Ok(scene), Ok(lens)) => {
                    assert_eq!(scene.lens().describe(), lens.describe(), "{name}");
                    for l in [500e-9, 700e-9, 900e-9] {
                        assert_eq!(scene.lens().efficiency(l), lens.efficiency(l), "{name}");
                        assert_eq!(scene.lens().transmission(l), lens.transmission(l), "{name}");
                    }
                }
                (Err(e), Err(_)) => assert!(e.to_string().contains("ΔT_req"), "{name}: {e}"),
                (a, b) => panic!("{name}: {:?} against {:?}", a.err().map(|e| e.to_string()), b.err()),
            }
        }
    }

    fn phase_scene(lens_keys: &str) -> String {
        crate::PAPER_SCENE.replace(
            &crate::PAPER_SCENE[crate::PAPER_SCENE.find("[lens]").unwrap()..crate::PAPER_SCENE.find("[source]").unwrap()],
            &format!("[lens]\nmodel = \"phase\"\nf_number = 2.5\nfocal_length_mm = 3.36\ndesign_wavelength_nm = 800.0\nefficiency = 0.15\ntransmission = 0.55\n{lens_keys}\n\n"),
        )
    }

    fn build_text(text: String, overrides: &[&str]) -> Result<metric::Scene, crate::Error> {
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        crate::build_from(&crate::Source::from_text(text, "test.toml", std::env::temp_dir()), &overrides)
    }

    /// A freeform spline profile (`lens.phase_spline_rad`) alone is the lens of its knots; on a
    /// Binary 2 profile it adds to it (the knots of zero change nothing); a knot is a `--set`
    /// key; too few knots, a knot not finite, Binary 2's own keys without Binary 2, and a knot
    /// past the list's end are refused naming the key.
    #[test]
    fn phase_spline_keys_and_errors() {
        let hyperbolic = "binary2 = [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]";
        let geometric = "dispersion = \"geometric-phase\"";
        let mean = |text: String, set: &[&str]| metric::evaluate(&build_text(text, set).unwrap()).unwrap().mean_mtf;
        let plain = mean(phase_scene(&format!("{hyperbolic}\n{geometric}")), &[]);
        let zero = phase_scene(&format!("{hyperbolic}\nphase_spline_rad = [0.0, 0.0, 0.0, 0.0, 0.0]\n{geometric}"));
        assert_eq!(mean(zero.clone(), &[]), plain);
        let scene = build_text(zero.clone(), &[]).unwrap();
        assert!(scene.lens().describe().contains("+ a spline of 5 knots"), "{}", scene.lens().describe());
        let bent = mean(zero.clone(), &["lens.phase_spline_rad[2]=3"]);
        assert!(bent < 0.95 * plain, "3 rad at mid-radius is an aberration: {plain} -> {bent}");
        // the hyperbola sampled at 33 knots is the Binary 2 lens to 1e-4 of the mean MTF
        let (f0, radius, k) = (3.36e-3, 0.672e-3, std::f64::consts::TAU / 800e-9);
        let knots: Vec<String> = (0..33)
            .map(|i| {
                let r = radius * i as f64 / 32.0;
                format!("{}", -k * ((r * r + f0 * f0).sqrt() - f0))
            })
            .collect();
        let alone = mean(phase_scene(&format!("phase_spline_rad = [{}]\n{geometric}", knots.join(", "))), &[]);
        assert!((alone - plain).abs() < 1e-4, "{alone} vs {plain}");
        let err = |text: String, set: &[&str]| build_text(text, set).unwrap_err().to_string();
        let e = err(phase_scene(&format!("phase_spline_rad = [0.0, 1.0]\n{geometric}")), &[]);
        assert!(e.contains("lens.phase_spline_rad") && e.contains("2 knots") && e.contains("3 to 1024"), "{e}");
        let e = err(zero.clone(), &["lens.phase_spline_rad[1]=nan"]);
        assert!(e.contains("lens.phase_spline_rad[1]"), "{e}");
        let e = err(phase_scene(&format!("phase_spline_rad = [0.0, 1.0, 0.0]\nnorm_radius_mm = 1\n{geometric}")), &[]);
        assert!(e.contains("lens.norm_radius_mm") && e.contains("only with lens.binary2"), "{e}");
        let e = err(zero, &["lens.phase_spline_rad[5]=1"]);
        assert!(e.contains("another knot moves every one"), "{e}");
    }

    /// `--set` of a numeric list's entry past its end extends the list with zeros (a Binary 2
    /// profile gains a term: A5 = 0 is the same lens, A5 ≠ 0 another); an index spelled with a
    /// leading zero is the same key (given twice it is refused); a list of tables does not grow.
    #[test]
    fn set_past_a_lists_end_extends_it_with_zeros() {
        let hyperbolic = "binary2 = [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]";
        let text = phase_scene(&format!("{hyperbolic}\ndispersion = \"geometric-phase\""));
        let mean = |set: &[&str]| metric::evaluate(&build_text(text.clone(), set).unwrap()).unwrap().mean_mtf;
        let plain = mean(&[]);
        assert_eq!(mean(&["lens.binary2[5]=0"]), plain);
        let source = crate::Source::from_text(text.clone(), "test.toml", std::env::temp_dir());
        let resolved = crate::resolved_toml(&source, &["lens.binary2[5]=0.5".to_owned()]).unwrap().toml;
        assert!(
            resolved.contains("0.002638937829015425, 0, 0.5]") || resolved.contains("0.002638937829015425, 0.0, 0.5]"),
            "{resolved}"
        );
        assert!(mean(&["lens.binary2[5]=0.5"]) != plain);
        assert_eq!(mean(&["lens.binary2[01]=0"]), mean(&["lens.binary2[1]=0"]));
        let e = build_text(text.clone(), &["lens.binary2[1]=0", "lens.binary2[01]=1"]).unwrap_err().to_string();
        assert!(e.contains("lens.binary2[1] is given twice"), "{e}");
        let e = build_text(text.clone(), &["lens.binary2[5000]=1"]).unwrap_err().to_string();
        assert!(e.contains("up to 1024 entries"), "{e}");
        assert_eq!(crate::canonical_key("lens.binary2[03]").as_deref(), Some("lens.binary2[3]"));
        assert_eq!(crate::canonical_key(" designs[ 1 ].lens.f_number").as_deref(), Some("designs[1].lens.f_number"));
        assert_eq!(crate::canonical_key("lens.binary2[x]"), None);
        let fields = format!("{text}\n[[fields]]\nx_deg = 0\n");
        let e = build_text(fields, &["fields[3].x_deg=1"]).unwrap_err().to_string();
        assert!(e.contains("has 1 entries"), "{e}");
    }

    /// The hyperbolic Binary 2 metalens loads, `--set lens.binary2[1]` reaches one coefficient,
    /// and the phase lens's mistakes are named: no dispersion, no profile, two profiles, a key of
    /// another dispersion, Zernike terms on a family with an iris.
    #[test]
    fn phase_lens_keys_and_errors() {
        let hyperbolic = "binary2 = [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425]";
        let ok = phase_scene(&format!("{hyperbolic}\ndispersion = \"geometric-phase\""));
        let scene = build_text(ok.clone(), &[]).unwrap();
        assert!(scene.lens().describe().contains("Binary 2"), "{}", scene.lens().describe());
        let changed = build_text(ok.clone(), &["lens.binary2[1]=0"]).unwrap();
        let a = metric::evaluate(&scene).unwrap().mean_mtf;
        let b = metric::evaluate(&changed).unwrap().mean_mtf;
        assert!(b < 0.95 * a, "removing A2 adds spherical aberration: {a} -> {b}");
        let err = |text: String| build_text(text, &[]).unwrap_err().to_string();
        let e = err(phase_scene(hyperbolic));
        assert!(e.contains("lens.dispersion") && e.contains("geometric-phase"), "{e}");
        let e = err(phase_scene("dispersion = \"geometric-phase\""));
        assert!(e.contains("lens.binary2") && e.contains("phase_csv"), "{e}");
        let e = err(phase_scene(&format!("{hyperbolic}\nphase_csv = \"x.csv\"\ndispersion = \"refractive\"")));
        assert!(e.contains("both given"), "{e}");
        let e = err(phase_scene(&format!("{hyperbolic}\ndispersion = \"geometric-phase\"\ndesign_order = 2")));
        assert!(e.contains("lens.design_order"), "{e}");
        let iris = crate::PAPER_SCENE.replace(
            "transmission = 0.55",
            "transmission = 0.55\nobscuration = 0.3\nzernike_noll_rms_um = [0, 0, 0, 0.1]",
        );
        let e = err(iris);
        assert!(e.contains("zernike"), "{e}");
    }

    /// A `.npy` float64 map `[y, x]` of `values(x_mm, y_mm)` on `n × n` cells of `pitch_um`,
    /// written to the temporary folder as `name`.
    fn write_map(name: &str, n: usize, pitch_um: f64, values: impl Fn(f64, f64) -> f64) -> String {
        let c = |k: usize| (k as f64 - 0.5 * (n as f64 - 1.0)) * pitch_um * 1e-3;
        let grid: Vec<f64> = (0..n * n).map(|k| values(c(k % n), c(k / n))).collect();
        let bytes = crate::npy::npy_f64(&[n, n], &grid).unwrap();
        let path = std::env::temp_dir().join(format!("asnr-map-{}-{name}", std::process::id()));
        std::fs::write(&path, bytes).unwrap();
        path.display().to_string()
    }

    /// A map given in memory (`Source::with_array`) is the map of the `.npy` file holding the same
    /// values: the same lens to the last digit, the same refusal naming the key (the array's text
    /// in place of the file's name), and a later override naming a file reads the file.
    #[test]
    fn a_map_given_in_memory_is_its_npy_file() {
        let small = |keys: &str| phase_scene(keys).replace("focal_length_mm = 3.36", "focal_length_mm = 0.125");
        let k0 = 2.0 * std::f64::consts::PI / 800e-6; // per mm
        let n = 50;
        let c = |k: usize| (k as f64 - 0.5 * (n as f64 - 1.0)) * 1e-3;
        let phase =
            |x: f64, y: f64| -k0 * ((x * x + y * y + 0.125f64.powi(2)).sqrt() - 0.125) + 2.0 * x * x * x / 1.25e-4;
        let values: Vec<f64> = (0..n * n).map(|i| phase(c(i % n), c(i / n))).collect();
        let file = write_map("memory.npy", n, 1.0, phase);
        let text = small("phase_map = \"given\"\nphase_map_pitch_um = 1.0\ndispersion = \"geometric-phase\"");
        let source = crate::Source::from_text(text.clone(), "test.toml", std::env::temp_dir());
        let source = source.with_array("lens.phase_map", "<array>", vec![n as u64, n as u64], values.clone()).unwrap();
        let label = ["lens.phase_map=\"<array>\"".to_owned()];
        let given = metric::evaluate(&crate::build_from(&source, &label).unwrap()).unwrap();
        let from_file = build_text(text, &[&format!("lens.phase_map=\"{file}\"")]).unwrap();
        let from_file = metric::evaluate(&from_file).unwrap();
        assert_eq!(given.mean_mtf.to_bits(), from_file.mean_mtf.to_bits());
        assert_eq!(given.asnr.to_bits(), from_file.asnr.to_bits());
        // a value naming a file (here the scene's own) reads the file, whatever arrays are given
        let named =
            small(&format!("phase_map = \"{file}\"\nphase_map_pitch_um = 1.0\ndispersion = \"geometric-phase\""));
        let named = crate::Source::from_text(named, "test.toml", std::env::temp_dir())
            .with_array("lens.phase_map", "<array>", vec![n as u64, n as u64], vec![0.0; n * n])
            .unwrap();
        assert_eq!(
            metric::evaluate(&crate::build_from(&named, &[]).unwrap()).unwrap().asnr.to_bits(),
            given.asnr.to_bits()
        );
        // the same checks: a NaN in the aperture, a shape of one axis, a key that takes no array
        let mut bad = values.clone();
        bad[(n / 2) * n + n / 2] = f64::NAN;
        let bad = crate::Source::from_text(
            small("phase_map = \"x\"\nphase_map_pitch_um = 1.0\ndispersion = \"geometric-phase\""),
            "t",
            ".",
        )
        .with_array("lens.phase_map", "<array>", vec![n as u64, n as u64], bad)
        .unwrap();
        let e = crate::build_from(&bad, &label).unwrap_err().to_string();
        assert!(e.contains("lens.phase_map") && e.contains("[y, x] = [25, 25]"), "{e}");
        let flat =
            source.clone().with_array("lens.phase_map", "<array>", vec![(n * n) as u64], values.clone()).unwrap();
        let e = crate::build_from(&flat, &label).unwrap_err().to_string();
        assert!(e.contains("lens.phase_map") && e.contains("<array>") && e.contains("expected 2 axes [y, x]"), "{e}");
        let e = source.clone().with_array("lens.binary2", "<array>", vec![2, 2], vec![0.0; 4]).unwrap_err();
        assert!(
            e.contains("lens.binary2") && e.contains("lens.phase_map, lens.amplitude_map, lens.layout_grid"),
            "{e}"
        );
        let e = source.with_array("lens.phase_map", "<array>", vec![3, 3], vec![0.0; 4]).unwrap_err();
        assert!(e.contains("4 values for the shape [3, 3]"), "{e}");
        std::fs::remove_file(file).ok();
    }

    /// A small lens (f0 = 0.125 mm, F/2.5, R = 25 µm) given as a map: the hyperbolic design loads
    /// (wrapped too, with a geometric phase), and the map's mistakes are refused with the key and
    /// the numbers: a NaN inside the aperture, a map that does not cover it, cells too coarse
    /// for the focusing phase, a wrapped map for a refractive lens, an amplitude map of another
    /// shape, a header promising more data than the file holds.
    #[test]
    fn phase_maps_are_checked() {
        let small = |keys: &str| phase_scene(keys).replace("focal_length_mm = 3.36", "focal_length_mm = 0.125");
        let k0 = 2.0 * std::f64::consts::PI / 800e-6; // per mm
        let hyperbolic = move |x: f64, y: f64| -k0 * ((x * x + y * y + 0.125f64.powi(2)).sqrt() - 0.125);
        let wrap = |v: f64| v - 2.0 * std::f64::consts::PI * (v / (2.0 * std::f64::consts::PI)).floor();
        let good = write_map("good.npy", 50, 1.0, hyperbolic);
        let keys = |file: &str, extra: &str| format!("phase_map = \"{file}\"\nphase_map_pitch_um = 1.0\n{extra}");
        let scene = build_text(small(&keys(&good, "dispersion = \"geometric-phase\"")), &[]).unwrap();
        assert!(scene.lens().describe().contains("50 × 50 cells"), "{}", scene.lens().describe());
        let wrapped = write_map("wrapped.npy", 50, 1.0, move |x, y| wrap(hyperbolic(x, y)));
        let a = metric::evaluate(&scene).unwrap().mean_mtf;
        let w = build_text(small(&keys(&wrapped, "dispersion = \"geometric-phase\"")), &[]).unwrap();
        let b = metric::evaluate(&w).unwrap().mean_mtf;
        assert!((a - b).abs() < 1e-9, "wrapped {b} vs unwrapped {a}");
        let err = |text: String| build_text(text, &[]).unwrap_err().to_string();
        let e = err(small(&keys(&wrapped, "dispersion = \"refractive\"")));
        assert!(
            e.contains("lens.phase_map") && e.contains("between neighbouring cells") && e.contains("unwrapped"),
            "{e}"
        );
        let nan = write_map("nan.npy", 50, 1.0, |x, y| if x.abs() < 1e-3 && y.abs() < 1e-3 { f64::NAN } else { 0.0 });
        let e = err(small(&keys(&nan, "dispersion = \"geometric-phase\"")));
        assert!(e.contains("NaN") && e.contains("[y, x] = [24, 24]"), "{e}");
        let short = write_map("short.npy", 40, 1.0, hyperbolic);
        let e = err(small(&keys(&short, "dispersion = \"geometric-phase\"")));
        assert!(
            e.contains("40 × 40 cells") && e.contains("covering the aperture") && e.contains("at least 50 cells"),
            "{e}"
        );
        let coarse = write_map("coarse.npy", 13, 4.0, hyperbolic);
        let e = err(small(&format!(
            "phase_map = \"{coarse}\"\nphase_map_pitch_um = 4.0\ndispersion = \"geometric-phase\""
        )));
        assert!(e.contains("lens.phase_map_pitch_um") && e.contains("more than π") && e.contains("a pitch ≤"), "{e}");
        let other = write_map("other.npy", 52, 1.0, |_, _| 1.0);
        let e = err(small(&keys(&good, &format!("amplitude_map = \"{other}\"\ndispersion = \"geometric-phase\""))));
        assert!(e.contains("lens.amplitude_map") && e.contains("52 × 52"), "{e}");
        // a header of 1000 × 1000 over the data of 50 × 50: refused before reading the samples
        let bytes = std::fs::read(&good).unwrap();
        let text = String::from_utf8_lossy(&bytes[10..]).replace("(50, 50)", "(1000, 1000)");
        let mut lying = bytes[..10].to_vec();
        lying.extend_from_slice(&text.as_bytes()[..bytes.len() - 10 - (50 * 50 * 8)]);
        lying.extend_from_slice(&bytes[bytes.len() - 50 * 50 * 8..]);
        let path = std::env::temp_dir().join(format!("asnr-map-{}-lying.npy", std::process::id()));
        std::fs::write(&path, lying).unwrap();
        let e = err(small(&keys(&path.display().to_string(), "dispersion = \"geometric-phase\"")));
        assert!(e.contains("bytes of data after the header") && e.contains("1000 × 1000"), "{e}");
        let e = err(small(&keys(&good, "dispersion = \"geometric-phase\"\naperture = \"hexagon\"")));
        assert!(e.contains("lens.aperture") && e.contains("square"), "{e}");
    }

    /// A phase table that is wrapped, too short, or not from the axis is refused naming the
    /// file and the numbers.
    #[test]
    fn phase_tables_are_checked() {
        let dir = std::env::temp_dir().join(format!("asnr-phase-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cases = [
            ("short.csv", "r_mm,phase_rad\n0,0\n0.1,-1\n0.2,-2\n0.5,-3\n", "aperture radius 0.672"),
            ("wrapped.csv", "r_mm,phase_rad\n0,0\n0.3,-1\n0.5,-5\n0.7,-6\n", "more than π"),
            ("offaxis.csv", "r_mm,phase_rad\n0.1,0\n0.3,-1\n0.5,-2\n0.7,-3\n", "expected 0"),
            ("noheader.csv", "0,0\n0.3,-1\n0.5,-2\n0.7,-3\n", "not a header"),
        ];
        for (name, text, want) in cases {
            std::fs::write(dir.join(name), text).unwrap();
            let scene =
                phase_scene(&format!("phase_csv = \"{}\"\ndispersion = \"geometric-phase\"", dir.join(name).display()));
            let e = build_text(scene, &[]).unwrap_err().to_string();
            assert!(e.contains(want) && e.contains(name), "{name}: {e}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Zernike terms on the chromatic family: Z11 lowers the mean MTF; all-zero terms change nothing.
    #[test]
    fn zernike_terms_on_a_family() {
        let plain = build_text(crate::PAPER_SCENE.to_owned(), &[]).unwrap();
        let zero = build_text(crate::PAPER_SCENE.to_owned(), &["lens.zernike_noll_rms_um=[0, 0, 0, 0]"]).unwrap();
        let z11 = build_text(crate::PAPER_SCENE.to_owned(), &["lens.zernike_noll_rms_um=[0,0,0,0,0,0,0,0,0,0,0.05]"])
            .unwrap();
        let (a, b, c) =
            (metric::evaluate(&plain).unwrap(), metric::evaluate(&zero).unwrap(), metric::evaluate(&z11).unwrap());
        assert!((a.mean_mtf - b.mean_mtf).abs() < 1e-6 * a.mean_mtf, "{} vs {}", a.mean_mtf, b.mean_mtf);
        assert!(c.mean_mtf < a.mean_mtf, "{} vs {}", c.mean_mtf, a.mean_mtf);
    }
}
