//! The dispersion-engineered lens's keys (`lens.model = "dispersion-engineered"`) as chains on
//! the engines' parameters (docs/physics.md, "Gradients: the dispersion-engineered lens").
//!
//! Its one order is the full pupil with `W020(λ) = (1 − β)(1 − λ/λ0) f0/(8F#²)` inside the
//! design band `[λ_min, λ_max]` (λ0 its centre) and efficiency 0 outside, with
//! `β = min(1, ΔT_lib/ΔT_req)`, `ΔT_req = f0(√(1 + u) − 1)/c`, `u = 1/(4F#²)` (docs/physics.md,
//! "Lens families"). At fixed β the F-number and the focal length move it as the chromatic
//! lens's defocus `∝ f0/F#²` ([`Parameter::FNumber`], [`Parameter::FocalLength`], whose lane
//! `D_K` is `∂M̄` along `δW020 = W020`); β adds its own share, also along `W020`:
//! `∂ln β/∂ln F# = 1 + 1/√(1 + u)`, `∂ln β/∂ln f0 = −1`, `∂ln β/∂ln ΔT_lib = 1` where `β < 1`, all 0
//! where `β = 1` (then `W020 = 0` near the design). The band's edges move λ0
//! ([`Parameter::DesignWavelength`]) and the efficiency's window ([`Parameter::BandEdge`]).

use anyhow::{Result, anyhow};
use metric::Parameter;

use super::{Chain, lookup};

/// The family this module's chains are for.
const MODEL: &str = "dispersion-engineered";

/// Speed of light in vacuum, m/s (as `lenses::dispersion`'s).
const C: f64 = 299_792_458.0;

/// The design's numbers from the resolved scene.
struct Design {
    f_number: f64,
    focal_length_m: f64,
    library_s: f64,
}

/// A number of the resolved scene (a float, or an integer written without a point).
fn number(table: &toml::Table, name: &str) -> Option<f64> {
    let v = lookup(table, name)?;
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

impl Design {
    fn of(table: &toml::Table) -> Result<Design> {
        let missing = |name: &str| anyhow!("the resolved scene has no {name}");
        let f0_mm = number(table, "lens.focal_length_mm").ok_or_else(|| missing("lens.focal_length_mm"))?;
        let f_number = match number(table, "lens.f_number") {
            Some(f) => f,
            None => f0_mm / number(table, "lens.aperture_diameter_mm").ok_or_else(|| missing("lens.f_number"))?,
        };
        let library_fs =
            number(table, "lens.group_delay_range_fs").ok_or_else(|| missing("lens.group_delay_range_fs"))?;
        Ok(Design { f_number, focal_length_m: f0_mm * 1e-3, library_s: library_fs * 1e-15 })
    }

    /// `ΔT_req = R²/(c(√(R² + f0²) + f0))`, `R = f0/(2F#)` (as `lenses::required_group_delay`).
    fn required_s(&self) -> f64 {
        let (f, r) = (self.focal_length_m, 0.5 * self.focal_length_m / self.f_number);
        r * r / (C * (r.hypot(f) + f))
    }

    /// `(β, ∂ln β/∂ln F#)`; β < 1 only where the library is short of the aperture's need.
    fn beta(&self) -> (f64, f64) {
        let required = self.required_s();
        if required <= self.library_s {
            return (1.0, 0.0);
        }
        let u = 0.25 / (self.f_number * self.f_number);
        (self.library_s / required, 1.0 + 1.0 / (1.0 + u).sqrt())
    }
}

/// `Σ c ∂/∂p` scaled by `s`, the terms of `parts` together.
fn combined(parts: &[(&Chain, f64)]) -> Chain {
    parts.iter().flat_map(|(chain, s)| chain.iter().map(move |(p, c)| (*p, c * s))).collect()
}

/// The chain of a dispersion-engineered lens's key (`lens.f_number`, `lens.focal_length_mm`,
/// `lens.aperture_diameter_mm`, `lens.group_delay_range_fs`, `lens.design_band_nm[i]`), or why
/// it is refused (the kink of β at `ΔT_req = ΔT_lib`, a spectrum whose own edge or line is at a
/// band edge); `None` for another key or family.
pub(super) fn chain(key: &str, value: f64, lens_model: &str, table: &toml::Table) -> Option<Result<Chain>> {
    if lens_model != MODEL {
        return None;
    }
    let edge = match key {
        "lens.design_band_nm[0]" => Some(0),
        "lens.design_band_nm[1]" => Some(1),
        "lens.f_number" | "lens.focal_length_mm" | "lens.aperture_diameter_mm" | "lens.group_delay_range_fs" => None,
        _ => return None,
    };
    Some(match edge {
        Some(i) => band_edge(key, i, table),
        None => aperture(key, value, table),
    })
}

/// The F-number, focal length, aperture diameter and library range: chains on
/// [`Parameter::FNumber`] and [`Parameter::FocalLength`] (module docs).
fn aperture(key: &str, value: f64, table: &toml::Table) -> Result<Chain> {
    let design = Design::of(table).map_err(|e| anyhow!("--wrt {key}: {e}"))?;
    let (required, library) = (design.required_s(), design.library_s);
    if (required - library).abs() <= 1e-12 * library {
        let d_max = lenses_max_diameter(design.focal_length_m, library);
        return Err(anyhow!(
            "--wrt {key}: not differentiable here: the aperture needs exactly the library's group delay \
             (ΔT_req = ΔT_lib = {:.4} fs, D = D_max = {:.3} µm), where the true-delay fraction \
             β = min(1, ΔT_lib/ΔT_req) has a kink: on one side a true achromat (β = 1, no defocus), on the other \
             partly chromatic (W020 = (1 − β)(1 − λ/λ0) f0/(8F#²)), so the ASNR's one-sided derivatives differ; \
             move the design off D = D_max",
            library * 1e15,
            d_max * 1e6
        ));
    }
    let (beta, d_ln_beta) = design.beta();
    // per ln F# (f0 held), per ln f0 (F# held), per ln ΔT_lib
    let (d_f_number, d_focal, d_library): (Chain, Chain, Chain) = if beta < 1.0 {
        let g = beta / (1.0 - beta);
        (
            vec![(Parameter::FNumber, 1.0), (Parameter::FocalLength, -g * d_ln_beta)],
            vec![(Parameter::FocalLength, 1.0 / (1.0 - beta))],
            vec![(Parameter::FocalLength, -g)],
        )
    } else {
        // a true achromat: W020 = 0 near the design, so only the frequency scale and NA move
        (vec![(Parameter::FNumber, 1.0)], Vec::new(), Vec::new())
    };
    let diameter_given = lookup(table, "lens.aperture_diameter_mm").is_some();
    Ok(match key {
        "lens.f_number" => combined(&[(&d_f_number, 1.0 / value)]),
        // ∂/∂D = −(1/D) ∂/∂ln F#
        "lens.aperture_diameter_mm" => combined(&[(&d_f_number, -1.0 / value)]),
        // D held: ∂/∂ln f0 = ∂/∂ln f0|F# + ∂/∂ln F#
        "lens.focal_length_mm" if diameter_given => combined(&[(&d_focal, 1.0 / value), (&d_f_number, 1.0 / value)]),
        "lens.focal_length_mm" => combined(&[(&d_focal, 1.0 / value)]),
        _ => combined(&[(&d_library, 1.0 / value)]),
    })
}

/// `D_max = 2√(2 f0 c ΔT_lib + (c ΔT_lib)²)` (as `lenses::max_diameter`), for the kink's message.
fn lenses_max_diameter(focal_length_m: f64, delay_s: f64) -> f64 {
    let l = C * delay_s;
    2.0 * (2.0 * focal_length_m * l + l * l).sqrt()
}

/// A band edge (nm): half the centre's move, `∂/∂λ_i = (1/(2λ0)) ∂/∂ln λ0`, plus the edge's own
/// Leibniz term (per m); the centre's term left out where β = 1 (`W020 = 0` near the design: it
/// is 0). Refused where the spectrum has a kink of its own there (a line at the
/// edge, a top-hat's edge on it): the value's one-sided derivatives differ.
fn band_edge(key: &str, edge: usize, table: &toml::Table) -> Result<Chain> {
    let band = lookup(table, "lens.design_band_nm").and_then(toml::Value::as_array);
    let ends: Vec<f64> = band
        .map(|b| b.iter().filter_map(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64))).collect())
        .unwrap_or_default();
    let [lo, hi] = ends[..] else {
        return Err(anyhow!("--wrt {key}: the resolved scene's lens.design_band_nm is not two wavelengths"));
    };
    let x = if edge == 0 { lo } else { hi };
    let shape = lookup(table, "spectrum.shape").and_then(toml::Value::as_str).unwrap_or("");
    let center = number(table, "spectrum.center_nm");
    let spectrum_edges: Vec<f64> = match (shape, center, number(table, "spectrum.range_nm")) {
        ("line", Some(c), _) => vec![c],
        ("tophat", Some(c), Some(r)) => vec![c - 0.5 * r, c + 0.5 * r],
        _ => Vec::new(),
    };
    if spectrum_edges.iter().any(|&s| (s - x).abs() <= 1e-12 * x) {
        return Err(anyhow!(
            "--wrt {key}: not differentiable here: the band's edge {x} nm is where the spectrum ({shape}) has its own \
             edge or line, so the detected light at the edge jumps as the edge crosses it (the one-sided derivatives \
             differ); move the band's edge or the spectrum off it"
        ));
    }
    // a true achromat (β = 1): W020 = 0 whatever λ0, so λ0's lane is 0 and not taken
    let design = Design::of(table).map_err(|e| anyhow!("--wrt {key}: {e}"))?;
    if design.beta().0 == 1.0 {
        return Ok(vec![(Parameter::BandEdge(edge), 1e-9)]);
    }
    let centre_nm = 0.5 * (lo + hi);
    Ok(vec![(Parameter::DesignWavelength, 0.5 / centre_nm), (Parameter::BandEdge(edge), 1e-9)])
}

#[cfg(test)]
mod tests {
    use scene::Source;

    use super::super::gradient;
    use super::super::tests::{assert_weighted, check_with_references, owned, richardson, with_noise_spectrum};

    /// The lens's `[lens]` with the other sections of `examples/paper-theory.toml` (a 8 nm
    /// Gaussian band at 800 nm: cheap, σ = 2.83 nm), at the tolerance 1e-6, a read noise of 2 e⁻.
    fn scene_with(lens: &str, extra: &str) -> Source {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/paper-theory.toml");
        let text = std::fs::read_to_string(path).unwrap();
        let (head, rest) = text.split_once("[lens]").unwrap();
        let (_, tail) = rest.split_once("[source]").unwrap();
        let text = format!("{head}[lens]\nmodel = \"dispersion-engineered\"\n{lens}\n\n[source]{tail}\n{extra}\n")
            .replace("range_nm = 50.0", "range_nm = 8.0")
            .replace("quantum_efficiency = 0.2", "quantum_efficiency = 0.2\nread_noise_e = 2.0")
            .replace("form = \"mean\"", "form = \"mean\"\ntolerance = 1e-6");
        Source::from_text(text, "dispersion-engineered scene written in the test", std::env::temp_dir())
    }

    /// `examples/designs.toml`'s "achromat F/2.5, 5 fs (reduced)": β = 5/221.96, mostly chromatic.
    const REDUCED: &str = "f_number = 2.5\nfocal_length_mm = 3.36\ndesign_band_nm = [750.0, 850.0]\n\
                           group_delay_range_fs = 5.0\ndelay_overflow = \"reduced\"\nefficiency = 0.15\n\
                           transmission = 0.55";
    /// `examples/designs.toml`'s "achromat D = 0.2 mm, 5 fs": below D_max = 200.8 µm, β = 1.
    const BELOW_D_MAX: &str = "aperture_diameter_mm = 0.2\nfocal_length_mm = 3.36\ndesign_band_nm = [750.0, 850.0]\n\
                               group_delay_range_fs = 5.0\nefficiency = 0.15\ntransmission = 0.55";

    /// Each key's gradient (ASNR, mean MTF, SNR0, N), as ∂/∂ln key, against Richardson central
    /// differences of evaluations converged at 1e-10 with the steps `2h` and `h`, `h = step(key,
    /// value)`, within 10× the scene's tolerance 1e-6 of the gradient's norm (a quantity whose
    /// gradient is 0 everywhere against its own size). The errors/norm printed.
    fn check(source: &Source, overrides: &[&str], keys: &[&str], step: &dyn Fn(&str, f64) -> f64) {
        let overrides = owned(overrides);
        check_with_references(source, &overrides, keys, &|k, v| richardson(source, &overrides, k, v, step(k, v)));
    }

    /// A relative step of 1e-3 of the value for the design's keys (their scale is the key's
    /// own), 0.1 nm for the band's edges (the band's scale is the spectrum's σ = 2.83 nm), 0.05°
    /// for the field angle.
    fn step(key: &str, value: f64) -> f64 {
        match key {
            k if k.starts_with("lens.design_band_nm") => 0.1,
            "field.x_deg" => 0.05,
            _ => 1e-3 * value.abs(),
        }
    }

    /// The reduced design (β = 0.0225, W020 ≈ 0.98 × the chromatic lens's): its F-number, focal
    /// length and library range through β and the defocus lane, both band edges (λ0's defocus
    /// lane, and the efficiency's window: the long edge at 1.4σ above the spectrum's centre),
    /// efficiency, transmission and the field angle (3°: the relative illumination cos⁴θ alone), with
    /// the stray light in the integral form and the pixel MTF; and the same aperture given by its
    /// diameter.
    #[test]
    fn the_reduced_achromat_matches_central_differences() {
        let source = scene_with(REDUCED, "[field]\nx_deg = 3.0");
        let keys = [
            "lens.f_number",
            "lens.focal_length_mm",
            "lens.group_delay_range_fs",
            "lens.design_band_nm[0]",
            "lens.design_band_nm[1]",
            "lens.efficiency",
            "lens.transmission",
            "field.x_deg",
        ];
        let glare = ["options.glare=\"included\"", "options.form=\"integral\"", "camera.pixel_mtf=true"];
        let cut = ["lens.design_band_nm=[750.0, 804.0]", "lens.relative_illumination=\"cos4\""];
        check(&source, &[&glare[..], &cut[..]].concat(), &keys, &step);
        // the same aperture given by its diameter (F# = f0/D = 2.5): the diameter, and the focal
        // length with D held (β moves with both)
        let by_diameter = scene_with(&REDUCED.replace("f_number = 2.5", "aperture_diameter_mm = 1.344"), "");
        check(&by_diameter, &[], &["lens.aperture_diameter_mm", "lens.focal_length_mm"], &step);
    }

    /// The reduced design on axis, where the value's engine is the per-frequency product rule:
    /// both edges' lanes (795 and 803.5 nm, 1.8σ below and 1.2σ above the spectrum's centre) ride
    /// on that engine's own pass with the band's window on the spectrum (the edges' OTFs from its
    /// sums at the spectral panels' ends), with the stray light included, against the same
    /// references.
    #[test]
    fn the_reduced_achromat_band_edges_on_the_value_rule_match_central_differences() {
        let source = scene_with(REDUCED, "");
        let keys = ["lens.design_band_nm[0]", "lens.design_band_nm[1]"];
        let overrides = ["options.glare=\"included\"", "lens.design_band_nm=[795.0, 803.5]"];
        check(&source, &overrides, &keys, &step);
    }

    /// The reduced design with Zernike terms (Z4 0.02 µm, Z8 0.01 µm: the overlap engine,
    /// docs/physics.md "Gradients: the F-number and the focal length with Seidel terms"): the
    /// F-number and the library range through β and the overlap engine's defocus lane.
    #[test]
    fn the_reduced_achromat_with_zernike_terms_matches_central_differences() {
        let zernike = format!("{REDUCED}\nzernike_noll_rms_um = [0, 0, 0, 0.02, 0, 0, 0, 0.01]");
        let source = scene_with(&zernike, "");
        check(&source, &[], &["lens.f_number", "lens.group_delay_range_fs"], &step);
    }

    /// The reduced design with Zernike terms (Z4 0.02 µm, Z8 0.01 µm: the overlap engine, the
    /// OTF depending on direction): both band edges (795 and 803.5 nm), λ0's lane on the overlap
    /// engine's nodes (docs/physics.md "Gradients: the design wavelength with Seidel and Zernike
    /// terms") and each edge's on the value's rule over directions, the edge's OTF from the band's
    /// slivers there on the overlap engine (`metric`'s `EdgeOtf`).
    #[test]
    fn the_reduced_achromat_band_edges_with_zernike_terms_match_central_differences() {
        let zernike = format!("{REDUCED}\nzernike_noll_rms_um = [0, 0, 0, 0.02, 0, 0, 0, 0.01]");
        let source = scene_with(&zernike, "");
        let keys = ["lens.design_band_nm[0]", "lens.design_band_nm[1]"];
        check(&source, &["lens.design_band_nm=[795.0, 803.5]"], &keys, &step);
    }

    /// The reduced design on axis, where the value's engine is the per-frequency product rule:
    /// the F-number's and focal length's defocus lane and the pixel MTF's term ride on the band
    /// edges' pass (beside the edges' and λ0's lanes, that engine's own mean and end term), the
    /// library range and an edge with them, with the pixel MTF, against the same references.
    #[test]
    fn the_reduced_achromat_aperture_on_the_edge_pass_matches_central_differences() {
        let source = scene_with(REDUCED, "");
        let keys = ["lens.f_number", "lens.focal_length_mm", "lens.group_delay_range_fs", "lens.design_band_nm[1]"];
        let overrides = ["camera.pixel_mtf=true", "lens.design_band_nm=[750.0, 804.0]"];
        check(&source, &overrides, &keys, &step);
    }

    /// The true achromat below D_max (β = 1, W020 = 0): the diameter and the focal length (D
    /// held: F# = f0/D moves), the library's range (0: β stays 1), both band edges (the short
    /// one 1.1σ below the spectrum's centre; λ0's lane 0); and with the pixel MTF the diameter and
    /// the focal length, where at F/16.8 the cutoff 1/(λF#) falls inside [0, ν_N] and the value
    /// takes the reference panels rule: the defocus lane on the reference rule, the pixel's term of
    /// the integration by parts on the value's engine.
    #[test]
    fn the_true_achromat_below_d_max_matches_central_differences() {
        let source = scene_with(BELOW_D_MAX, "");
        let keys = [
            "lens.aperture_diameter_mm",
            "lens.focal_length_mm",
            "lens.group_delay_range_fs",
            "lens.design_band_nm[0]",
            "lens.design_band_nm[1]",
            "lens.efficiency",
        ];
        let overrides = ["lens.design_band_nm=[797.0, 850.0]"];
        check(&source, &overrides, &keys, &step);
        let pixel = ["camera.pixel_mtf=true"];
        check(&source, &pixel, &["lens.aperture_diameter_mm", "lens.focal_length_mm"], &step);
        let g = gradient(
            &source,
            &["lens.design_band_nm=[797.0, 850.0]".to_owned()],
            &["lens.group_delay_range_fs".to_owned()],
        )
        .unwrap();
        assert_eq!((g.d_asnr[0], g.d_mean_mtf[0], g.d_photoelectrons[0]), (0.0, 0.0, 0.0));
    }

    /// At D = D_max (ΔT_req = ΔT_lib) β = min(1, ΔT_lib/ΔT_req) has a kink: the design's keys are
    /// refused naming it; a band edge on a top-hat's edge likewise; the band's edges stay.
    #[test]
    fn the_kink_at_d_max_is_refused_naming_the_key() {
        let d_max_mm = super::lenses_max_diameter(3.36e-3, 5e-15) * 1e3;
        let lens = BELOW_D_MAX.replace("aperture_diameter_mm = 0.2", &format!("aperture_diameter_mm = {d_max_mm:e}"))
            + "\ndelay_overflow = \"reduced\"";
        let source = scene_with(&lens, "");
        for key in ["lens.aperture_diameter_mm", "lens.focal_length_mm", "lens.group_delay_range_fs"] {
            let e = gradient(&source, &[], &[key.to_owned()]).unwrap_err().to_string();
            assert!(e.starts_with(&format!("--wrt {key}: not differentiable here")), "{e}");
            assert!(e.contains("kink") && e.contains("D = D_max = 200.751 µm"), "{e}");
        }
        assert!(gradient(&source, &[], &["lens.design_band_nm[1]".to_owned()]).is_ok());
        let top_hat = ["spectrum.shape=\"tophat\"".to_owned(), "lens.design_band_nm=[796.0, 850.0]".to_owned()];
        let e = gradient(&source, &top_hat, &["lens.design_band_nm[0]".to_owned()]).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.design_band_nm[0]: not differentiable here") && e.contains("796 nm"), "{e}");
    }

    /// A line's wavelength on the achromats (docs/physics.md, "Gradients: the dispersion-engineered
    /// lens", a line's wavelength): inside the band the one order's `W020(c)` moves by
    /// `(1 − β)`-scaled chromatic defocus (the line engine's defocus lane, the frequency scale by
    /// parts). The reduced design at 803 nm with the exposure, at 3° with the pixel MTF, and
    /// under a noise spectrum; the true achromat (W020 = 0: the frequency scale alone) at 803 nm;
    /// against Richardson central differences (steps 4e-3 and 2e-3 nm) of evaluations converged
    /// at 1e-10; a line on the band's edge refused, naming it.
    #[test]
    fn a_line_on_the_achromats_matches_central_differences() {
        let line = ["spectrum.shape=\"line\"", "spectrum.center_nm=803", "spectrum.range_nm=1"];
        let step = |k: &str, v: f64| if k == "spectrum.center_nm" { 2e-3 } else { 1e-3 * v.abs() };
        let center = ["spectrum.center_nm"];
        check(&scene_with(REDUCED, ""), &line, &["spectrum.center_nm", "exposure.time_ms"], &step);
        let off_axis = scene_with(REDUCED, "[field]\nx_deg = 3.0");
        check(&off_axis, &[&line[..], &["camera.pixel_mtf=true"]].concat(), &center, &step);
        let shaped = with_noise_spectrum(&scene_with(REDUCED, ""), "line-achromat");
        assert_weighted(&gradient(&shaped, &owned(&line), &owned(&center)).unwrap());
        check(&shaped, &line, &center, &step);
        check(&scene_with(BELOW_D_MAX, ""), &line, &center, &step);
        let edge = ["spectrum.shape=\"line\"", "spectrum.center_nm=850", "spectrum.range_nm=1"];
        let e = gradient(&scene_with(REDUCED, ""), &owned(&edge), &owned(&center)).unwrap_err().to_string();
        assert!(e.contains("--wrt spectrum.center_nm") && e.contains("edge of the design band"), "{e}");
    }
}
