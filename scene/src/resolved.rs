//! The scene as read, written back as TOML with every default filled in (`asnr scene`).
//!
//! Numbers are written as they were read (shortest round-trip form, in the scene's units), so
//! the text loads again to the same scene; CSV paths are written resolved (absolute), so it
//! loads from any folder. Defaults come from the library ([`metric::Options::default`],
//! [`noise::Sensor::ideal`]), not from numbers typed here.

use std::fmt::Write as _;

use metric::{GlareMode, MetricForm, Options};

use crate::error::{Error, Warning, shorten};
use crate::lens::Model;
use crate::lens_table::RawLens;
use crate::load::{RawScene, Source, build_checked, prepare};
use crate::origins::{NumberOrFile, Origins};

/// A scene as read ([`resolved_toml`]) and its plausibility warnings.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// TOML with every default filled in and every CSV path resolved (absolute).
    pub toml: String,
    /// Values that are valid but almost surely a unit slip, as [`crate::Loaded::warnings`].
    pub warnings: Vec<Warning>,
}

/// The scene of `source` with `overrides` as TOML with every default filled in and every CSV
/// path resolved (absolute): what was read. It is validated (built) once, and loads again to the
/// same scene.
pub fn resolved_toml(source: &Source, overrides: &[String]) -> Result<Resolved, Error> {
    Ok(resolved_and_built(source, overrides)?.0)
}

/// [`resolved_toml`] and the scene it validated, built once: the scene is
/// [`crate::build_from`]'s of the same `source` and `overrides`.
pub fn resolved_and_built(source: &Source, overrides: &[String]) -> Result<(Resolved, metric::Scene), Error> {
    let (raw, origins) = prepare(source, overrides)?;
    let loaded = build_checked(&raw, &origins)?;
    Ok((Resolved { toml: write(&raw, &origins)?, warnings: loaded.warnings }, loaded.scene))
}

struct Out {
    text: String,
}

impl Out {
    fn line(&mut self, line: &str) {
        self.text.push_str(line);
        self.text.push('\n');
    }

    fn table(&mut self, name: &str) {
        let _ = write!(self.text, "\n[{name}]\n");
    }

    fn value(&mut self, key: &str, value: &str) {
        let _ = writeln!(self.text, "{key} = {value}");
    }

    fn number(&mut self, key: &str, v: f64) {
        self.value(key, &float(v));
    }

    fn string(&mut self, key: &str, s: &str) {
        self.value(key, &toml::Value::String(s.to_owned()).to_string());
    }
}

/// A TOML float that parses back to the same `f64` (`0.25`, `5.0`, `1e-6`, `inf`).
fn float(v: f64) -> String {
    if v.is_infinite() {
        return if v > 0.0 { "inf".to_owned() } else { "-inf".to_owned() };
    }
    format!("{v:?}")
}

/// The shortest decimal `d` with `d × to_si == si` (a default held in SI, written in the
/// scene's unit, e.g. 0.25e-3 m as 0.25 mm).
fn in_unit(si: f64, to_si: f64) -> f64 {
    for digits in 0..17 {
        if let Ok(d) = format!("{:.digits$e}", si / to_si).parse::<f64>()
            && d * to_si == si
        {
            return d;
        }
    }
    si / to_si
}

/// A CSV path as the loader resolves it, made absolute so the text loads from any folder.
fn path(o: &Origins, key: &str, file: &str) -> Result<String, Error> {
    // an array given in memory keeps the text that stands for it
    if o.arrays.get(key, file).is_some() {
        return Ok(file.to_owned());
    }
    let resolved = o.path(file);
    let resolved = std::path::absolute(&resolved).unwrap_or(resolved);
    resolved.to_str().map(str::to_owned).ok_or_else(|| Error::Value {
        origin: o.file.clone(),
        key: key.to_owned(),
        value: format!("\"{}\"", shorten(&resolved.to_string_lossy())),
        expected: "a path that is valid UTF-8 (to be written as TOML)".to_owned(),
    })
}

fn curve(out: &mut Out, o: &Origins, key: &str, value: &NumberOrFile) -> Result<(), Error> {
    match value {
        NumberOrFile::Number(v) => out.number(key, *v),
        NumberOrFile::File(f) => out.string(key, &path(o, &o.key(&format!("lens.{key}")), f)?),
    }
    Ok(())
}

fn list(values: &[f64]) -> String {
    format!("[{}]", values.iter().map(|v| float(*v)).collect::<Vec<_>>().join(", "))
}

/// The `[lens]` table of an already validated lens: the keys of its family, defaults filled in.
fn lens(out: &mut Out, o: &Origins, l: &RawLens) -> Result<(), Error> {
    out.table(&o.lens);
    let model = crate::lens::model(l, o)?;
    if let Some((name, keys)) = &o.preset {
        out.line(&format!(
            "# preset {}: {} from the preset, the other keys as given (they override it)",
            toml::Value::String(name.clone()),
            if keys.is_empty() { "nothing".to_owned() } else { keys.join(", ") }
        ));
    }
    if let Some(z) = &o.zemax {
        out.line(&format!(
            "# from the Zemax file {}, surface {} (BINARY_2): {}{}",
            toml::Value::String(z.file.clone()),
            z.surface,
            if z.keys.is_empty() { "nothing (every key overridden)".to_owned() } else { z.keys.join(", ") },
            z.notes.iter().map(|n| format!("; {n}")).collect::<String>()
        ));
    }
    out.string("model", model.name());
    match (l.f_number, l.aperture_diameter_mm) {
        (_, Some(d)) => out.number("aperture_diameter_mm", d),
        (f, None) => out.number("f_number", f.unwrap_or_default()),
    }
    out.number("focal_length_mm", l.focal_length_mm.unwrap_or_default());
    let efficiency = |out: &mut Out| -> Result<(), Error> {
        match &l.efficiency {
            Some(e) => curve(out, o, "efficiency", e),
            None => Ok(()),
        }
    };
    let transmission = |out: &mut Out| -> Result<(), Error> {
        match (&l.transmission, &l.efficiency) {
            (Some(t), _) => curve(out, o, "transmission", t),
            (None, Some(e)) => {
                out.line("# transmission not given: the efficiency (no stray light)");
                curve(out, o, "transmission", e)
            }
            (None, None) => Ok(()),
        }
    };
    match model {
        Model::Chromatic => {
            out.number("design_wavelength_nm", l.design_wavelength_nm.unwrap_or_default());
            efficiency(out)?;
            transmission(out)?;
            out.number("iris_decentre_x", l.iris_decentre_x.unwrap_or(0.0));
            out.number("iris_decentre_y", l.iris_decentre_y.unwrap_or(0.0));
            out.number("obscuration", l.obscuration.unwrap_or(0.0));
            match l.sector_deg {
                Some([a, b]) => out.value("sector_deg", &list(&[a, b])),
                None => out.line("# sector_deg not given: the full circle"),
            }
            for (key, v) in [
                ("spherical_um", l.spherical_um),
                ("coma_um", l.coma_um),
                ("astigmatism_um", l.astigmatism_um),
                ("field_curvature_um", l.field_curvature_um),
            ] {
                out.number(key, v.unwrap_or(0.0));
            }
        }
        Model::Refractive => {
            out.number("design_wavelength_nm", l.design_wavelength_nm.unwrap_or_default());
            match (&l.glass, l.refractive_index) {
                (_, Some(n)) => out.number("refractive_index", n),
                (Some(g), None) => out.string("glass", g),
                (None, None) => {
                    out.line("# glass not given: N-BK7");
                    out.string("glass", "N-BK7");
                }
            }
            out.value("elements", &l.elements.unwrap_or(1).to_string());
            match l.coating_reflectance {
                Some(r) => out.number("coating_reflectance", r),
                None => out.line("# coating_reflectance not given: uncoated (Fresnel reflectance of the glass)"),
            }
        }
        Model::Dispersion => {
            let [lo, hi] = l.design_band_nm.unwrap_or_default();
            out.value("design_band_nm", &list(&[lo, hi]));
            out.number("group_delay_range_fs", l.group_delay_range_fs.unwrap_or_default());
            out.string("delay_overflow", l.delay_overflow.as_deref().unwrap_or("reject"));
            efficiency(out)?;
            transmission(out)?;
        }
        Model::Harmonic => {
            out.number("design_wavelength_nm", l.design_wavelength_nm.unwrap_or_default());
            out.value("design_order", &l.design_order.unwrap_or(1).to_string());
            efficiency(out)?;
            transmission(out)?;
        }
        Model::Multiplexed => {
            out.string("layout", l.layout.as_deref().unwrap_or("interleaved"));
            out.value("channels_nm", &list(l.channels_nm.as_deref().unwrap_or_default()));
            efficiency(out)?;
            if let Some(list) = &l.channel_efficiencies {
                let mut items = Vec::new();
                for (j, e) in list.iter().enumerate() {
                    items.push(match e {
                        NumberOrFile::Number(v) => float(*v),
                        NumberOrFile::File(f) => {
                            toml::Value::String(path(o, &format!("lens.channel_efficiencies[{j}]"), f)?).to_string()
                        }
                    });
                }
                out.value("channel_efficiencies", &format!("[{}]", items.join(", ")));
            }
            if let Some(t) = &l.transmission {
                curve(out, o, "transmission", t)?;
            }
            out.string("other_channels", l.other_channels.as_deref().unwrap_or("signal"));
            if l.layout.as_deref() == Some("segmented") {
                out.string("zones", l.zones.as_deref().unwrap_or("concentric"));
                if let Some(file) = &l.zone_mask {
                    out.string("zone_mask", &path(o, "lens.zone_mask", file)?);
                }
                match &l.area_fractions {
                    Some(a) => out.value("area_fractions", &list(a)),
                    None => out.line("# area_fractions not given: 1/N each"),
                }
            }
        }
        Model::Tabulated => {
            let key = o.key("lens.mtf");
            match &l.mtf {
                Some(crate::lens_table::OneOrMany::Many(files)) => {
                    let resolved: Vec<String> = files
                        .iter()
                        .map(|f| path(o, &key, f).map(|p| toml::Value::String(p).to_string()))
                        .collect::<Result<_, _>>()?;
                    out.value("mtf", &format!("[{}]", resolved.join(", ")));
                }
                one => out.string("mtf", &path(o, &key, one.as_ref().map_or("", |m| m.paths()[0]))?),
            }
            if let Some(i) = l.mtf_field {
                out.value("mtf_field", &i.to_string());
            }
            match l.mtf_includes_pixel_um {
                Some(p) => out.number("mtf_includes_pixel_um", p),
                None => out.line("# mtf_includes_pixel_um not given: the table holds the lens MTF alone"),
            }
            match l.design_wavelength_nm {
                Some(w) => out.number("design_wavelength_nm", w),
                None => out.line("# design_wavelength_nm not given: none (the Fraunhofer check has no reference)"),
            }
            efficiency(out)?;
            transmission(out)?;
        }
        Model::Library => {
            out.number("design_wavelength_nm", l.design_wavelength_nm.unwrap_or_default());
            if let Some(file) = &l.library {
                out.string("library", &path(o, "lens.library", file)?);
            }
            if let Some(file) = &l.layout {
                out.string("layout", &path(o, "lens.layout", file)?);
            }
            if let Some(file) = &l.layout_grid {
                out.string("layout_grid", &path(o, "lens.layout_grid", file)?);
            }
            if let Some(file) = &l.layout_gds {
                out.string("layout_gds", &path(o, "lens.layout_gds", file)?);
                match &l.gds_cell {
                    Some(c) => out.string("gds_cell", c),
                    None => out.line("# gds_cell not given: the single top cell"),
                }
                out.value("gds_layer", &l.gds_layer.unwrap_or_default().to_string());
                out.value("gds_datatype", &l.gds_datatype.unwrap_or_default().to_string());
                out.string("atom", l.atom.as_deref().unwrap_or("pillar"));
                if let Some(h) = &l.handedness {
                    out.string("handedness", h);
                }
            }
            if l.layout_grid.is_some() || l.layout_gds.is_some() {
                out.number("lattice_pitch_um", l.lattice_pitch_um.unwrap_or_default());
                match &l.empty_cell {
                    Some(v) => out.value("empty_cell", &v.to_string()),
                    None => out.line("# empty_cell not given: every site in the aperture must hold an atom"),
                }
            }
            out.number("atom_phase_error_rad", l.atom_phase_error_rad.unwrap_or(0.0));
            out.number("atom_transmission_error", l.atom_transmission_error.unwrap_or(0.0));
            if l.layout_grid.is_some() || l.layout_gds.is_some() {
                out.line("# no atom_error_seed: a 2-D layout takes the atoms' errors in expectation");
            } else {
                out.value("atom_error_seed", &l.atom_error_seed.unwrap_or(0).to_string());
            }
            if let Some(b) = &l.parameter_bias {
                out.value("parameter_bias", &list(b));
            }
            match &l.library_interpolation {
                Some(i) => out.string("library_interpolation", i),
                None => {
                    out.line("# library_interpolation not given: linear in the parameters");
                    out.string("library_interpolation", "linear");
                }
            }
        }
        Model::Phase => {
            out.number("design_wavelength_nm", l.design_wavelength_nm.unwrap_or_default());
            if let Some(a) = &l.binary2 {
                out.value("binary2", &list(a));
                match l.norm_radius_mm {
                    Some(r) => out.number("norm_radius_mm", r),
                    None => {
                        let radius = 0.5 * l.focal_length_mm.unwrap_or_default()
                            / l.f_number.unwrap_or_else(|| {
                                l.focal_length_mm.unwrap_or_default() / l.aperture_diameter_mm.unwrap_or(1.0)
                            });
                        out.line("# norm_radius_mm not given: the aperture radius");
                        out.number("norm_radius_mm", radius);
                    }
                }
                out.number("diffraction_order", l.diffraction_order.unwrap_or(1.0));
            }
            if let Some(file) = &l.phase_csv {
                out.string("phase_csv", &path(o, "lens.phase_csv", file)?);
            }
            if let Some(knots) = &l.phase_spline_rad {
                out.value("phase_spline_rad", &list(knots));
            }
            if let Some(file) = &l.phase_map {
                out.string("phase_map", &path(o, "lens.phase_map", file)?);
                out.number("phase_map_pitch_um", l.phase_map_pitch_um.unwrap_or_default());
                if let Some(file) = &l.amplitude_map {
                    out.string("amplitude_map", &path(o, "lens.amplitude_map", file)?);
                }
                out.string("aperture", l.aperture.as_deref().unwrap_or("circle"));
            }
            let dispersion = l.dispersion.as_deref().unwrap_or_default();
            out.string("dispersion", dispersion);
            if dispersion == "diffractive" {
                out.value("design_order", &l.design_order.unwrap_or(1).to_string());
            }
            if let Some(g) = &l.glass {
                out.string("glass", g);
            }
            efficiency(out)?;
            transmission(out)?;
        }
        Model::Psf => {
            if let Some(file) = &l.psf {
                out.string("psf", &path(o, &o.key("lens.psf"), file)?);
            }
            out.number("psf_pitch_um", l.psf_pitch_um.unwrap_or_default());
            out.value("psf_wavelengths_nm", &list(l.psf_wavelengths_nm.as_deref().unwrap_or_default()));
            match l.design_wavelength_nm {
                Some(w) => out.number("design_wavelength_nm", w),
                None => out.line("# design_wavelength_nm not given: none (the Fraunhofer check has no reference)"),
            }
            efficiency(out)?;
            transmission(out)?;
        }
    }
    if let Some(z) = &l.zernike_noll_rms_um {
        out.value("zernike_noll_rms_um", &list(z));
    }
    match &l.relative_illumination {
        // the default, given or not, in the same words (a resolved scene is a fixed point)
        None => default_illumination(out),
        Some(NumberOrFile::File(word)) if word == "none" => default_illumination(out),
        Some(NumberOrFile::Number(v)) => out.number("relative_illumination", *v),
        Some(NumberOrFile::File(word)) if word == "cos4" => out.string("relative_illumination", word),
        Some(NumberOrFile::File(file)) => {
            out.string("relative_illumination", &path(o, &o.key("lens.relative_illumination"), file)?)
        }
    }
    Ok(())
}

/// `relative_illumination = "none"`, the default, and what it means.
fn default_illumination(out: &mut Out) {
    out.line(
        "# relative_illumination \"none\" (the default): every field point as bright as the axis, as in the paper",
    );
    out.string("relative_illumination", "none");
}

/// The resolved TOML of an already validated scene.
pub(crate) fn write(raw: &RawScene, o: &Origins) -> Result<String, Error> {
    let mut out = Out { text: String::new() };
    out.line("# The scene as read (asnr scene): every default filled in, CSV paths resolved.");
    out.line(&format!("# From: {}", shorten(&o.file)));
    for arg in o.overrides.values() {
        out.line(&format!("#   --set {}", shorten(arg)));
    }
    if let Some(title) = &raw.title {
        out.string("title", title);
    }

    lens(&mut out, o, &raw.lens)?;

    let s = &raw.source;
    out.table("source");
    out.string("kind", &s.kind);
    match s.kind.as_str() {
        "flat" => out.number("radiance_w_m2_sr_nm", s.radiance_w_m2_sr_nm.unwrap_or_default()),
        "blackbody" => {
            out.number("temperature_k", s.temperature_k.unwrap_or_default());
            out.number("scale", s.scale.unwrap_or(1.0));
        }
        "radiance_meter" => {
            out.line("# the target's spectral radiance from a radiance meter's readings (SI eq. S1–S6)");
            let file = s.relative_spectrum_csv.as_deref().unwrap_or_default();
            out.string("relative_spectrum_csv", &path(o, "source.relative_spectrum_csv", file)?);
            out.number("power_nw", s.power_nw.unwrap_or_default());
            out.number("fiber_core_diameter_um", s.fiber_core_diameter_um.unwrap_or_default());
            let file = s.responsivity_csv.as_deref().unwrap_or_default();
            out.string("responsivity_csv", &path(o, "source.responsivity_csv", file)?);
            out.number("calibration_wavelength_nm", s.calibration_wavelength_nm.unwrap_or_default());
            out.number("relay_transmission", s.relay_transmission.unwrap_or_default());
            out.number("relay_iris_mm", s.relay_iris_mm.unwrap_or_default());
            out.number("relay_focal_length_mm", s.relay_focal_length_mm.unwrap_or_default());
        }
        _ => out.string("csv", &path(o, "source.csv", s.csv.as_deref().unwrap_or_default())?),
    }

    out.table("spectrum");
    match &raw.spectrum {
        None => {
            out.line("# [spectrum] not given: no filter");
            out.string("shape", "none");
        }
        Some(sp) => {
            out.string("shape", &sp.shape);
            match sp.shape.as_str() {
                "table" => out.string("csv", &path(o, "spectrum.csv", sp.csv.as_deref().unwrap_or_default())?),
                "none" => {}
                _ => {
                    out.number("center_nm", sp.center_nm.unwrap_or_default());
                    out.number("range_nm", sp.range_nm.unwrap_or_default());
                    out.number("peak", sp.peak.unwrap_or(1.0));
                }
            }
        }
    }

    let c = &raw.camera;
    let ideal = noise::Sensor::ideal();
    out.table("camera");
    out.number("pixel_pitch_um", c.pixel_pitch_um);
    out.value("pixel_mtf", &c.pixel_mtf.to_string());
    match &c.quantum_efficiency {
        NumberOrFile::Number(v) => out.number("quantum_efficiency", *v),
        NumberOrFile::File(f) => out.string("quantum_efficiency", &path(o, "camera.quantum_efficiency", f)?),
    }
    out.number("read_noise_e", c.read_noise_e.unwrap_or(ideal.read_noise_e()));
    out.number("dark_current_e_per_s", c.dark_current_e_per_s.unwrap_or(ideal.dark_current_e_per_s()));
    out.number("full_well_e", c.full_well_e.unwrap_or(ideal.full_well_e()));
    match (c.gain_dn_per_e, c.adc_bits) {
        (Some(k), Some(bits)) => {
            out.number("gain_dn_per_e", k);
            out.value("adc_bits", &bits.to_string());
            out.number("black_level_dn", c.black_level_dn.unwrap_or(0.0));
        }
        _ => out.line("# gain_dn_per_e, adc_bits not given: no ADC quantization"),
    }
    match &c.noise_spectrum {
        Some(f) => out.string("noise_spectrum", &path(o, "camera.noise_spectrum", f)?),
        None => out.line("# noise_spectrum not given: white noise"),
    }

    out.table("exposure");
    out.number("time_ms", raw.exposure.time_ms);

    let defaults = Options::default();
    let opt = raw.options.as_ref();
    out.table("options");
    let form = match defaults.form {
        MetricForm::Mean => "mean",
        MetricForm::Integral => "integral",
    };
    out.string("form", opt.and_then(|p| p.form.as_deref()).unwrap_or(form));
    out.number(
        "fraunhofer_threshold_mm",
        opt.and_then(|p| p.fraunhofer_threshold_mm).unwrap_or_else(|| in_unit(defaults.fraunhofer_threshold, 1e-3)),
    );
    out.number(
        "fraunhofer_max_fraction",
        opt.and_then(|p| p.fraunhofer_max_fraction).unwrap_or(defaults.fraunhofer_max_fraction),
    );
    match opt.and_then(|p| p.pupil_samples).map(|v| v as usize).or(defaults.pupil_samples) {
        Some(v) => out.value("pupil_samples", &v.to_string()),
        None => out.line("# pupil_samples: not set, so the FFT path chooses its sampling from the tolerance"),
    }
    let glare = match defaults.glare {
        GlareMode::FirstOrder => "first_order",
        GlareMode::Included => "included",
    };
    out.string("glare", opt.and_then(|p| p.glare.as_deref()).unwrap_or(glare));
    // written only where the scene set it: a set tolerance is asked of every engine, the FFT
    // path's too, while the default is 1e-4 there
    match opt.and_then(|p| p.tolerance) {
        Some(t) => out.number("tolerance", t),
        None => out.line(&format!(
            "# tolerance: not set, so {:e} (and {:e} on the FFT path)",
            defaults.tolerance,
            defaults.fft_tolerance.unwrap_or(defaults.tolerance)
        )),
    }
    let rule = match defaults.spectral_rule {
        optics::SpectralRule::Interpolated => "interpolated",
        optics::SpectralRule::Panels => "panels",
    };
    out.string("spectral_rule", opt.and_then(|p| p.spectral_rule.as_deref()).unwrap_or(rule));
    out.string("pupil_mapping", opt.and_then(|p| p.pupil_mapping.as_deref()).unwrap_or("paraxial"));
    out.string("table_rule", opt.and_then(|p| p.table_rule.as_deref()).unwrap_or(defaults.table_rule.name()));

    match (&raw.field, &raw.fields) {
        (_, Some(list)) => {
            for f in list {
                out.text.push_str("\n[[fields]]\n");
                out.number("x_deg", f.x_deg.unwrap_or(0.0));
                out.number("y_deg", f.y_deg.unwrap_or(0.0));
                out.number("weight", f.weight.unwrap_or(1.0));
            }
        }
        (f, None) => {
            out.table("field");
            out.number("x_deg", f.as_ref().and_then(|f| f.x_deg).unwrap_or(0.0));
            out.number("y_deg", f.as_ref().and_then(|f| f.y_deg).unwrap_or(0.0));
        }
    }
    Ok(out.text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_in_the_scene_unit_round_trip() {
        let d = Options::default();
        let mm = in_unit(d.fraunhofer_threshold, 1e-3);
        assert_eq!(mm, 0.25);
        assert_eq!(mm * 1e-3, d.fraunhofer_threshold);
        for v in [0.25, 5.2, 1e-6, 3.36, 1e300, 0.1 + 0.2] {
            assert_eq!(float(v).parse::<f64>().unwrap(), v);
        }
        assert_eq!(float(f64::INFINITY), "inf");
    }
}
