//! The `model = "library"` lens laid out in 2-D (docs/physics.md, "2-D library layouts"):
//! `lens.layout_grid` (a `.npy` `[y, x]` of the library's one parameter, `NaN` where a site has no
//! atom) or `lens.layout_gds` (a GDSII layout read by [`crate::gds`]) on the lattice of
//! `lens.lattice_pitch_um`, with `lens.empty_cell` for the sites without an atom and
//! `lens.handedness` for fins → [`lenses::LibraryMapLens`].

use std::sync::Arc;

use num_complex::Complex64;

use crate::Error;
use crate::error::{num, quoted};
use crate::gds::{AtomKind, GdsOptions};
use crate::lens_table::{LensInfo, RawLens};
use crate::origins::Origins;

/// The most atoms and lattice sites a layout may hold (the paper's aperture on a 400 nm
/// lattice is 1.1e7 sites; a map holds at most 2^26 cells).
const MAX_SITES: u64 = 1 << 26;

/// The 2-D library lens of `l` (`layout_grid` or `layout_gds`), its statistics in `info`.
pub(crate) fn library_map_lens(
    l: &RawLens,
    o: &Origins,
    f_number: f64,
    f0_m: f64,
    l0: f64,
    info: &mut LensInfo,
) -> Result<lenses::LibraryMapLens, Error> {
    let two_d = if l.layout_gds.is_some() { "lens.layout_gds" } else { "lens.layout_grid" };
    if l.layout.is_some() {
        return Err(o.conflict(
            "lens.layout",
            format!("lens.layout (a radial layout) is not taken with {two_d}: give one of them"),
        ));
    }
    if let Some(seed) = l.atom_error_seed {
        return Err(o.bad(
            "lens.atom_error_seed",
            seed,
            &format!(
                "no seed with {two_d}: the 2-D layout takes the atoms' random errors in expectation over the draws (the mean over seeds; docs/physics.md, \"Fabrication errors of a 2-D layout\"), so there is nothing to draw"
            ),
        ));
    }
    if l.layout_gds.is_some() && l.layout_grid.is_some() {
        return Err(o.conflict("lens.layout_grid", "give one of lens.layout_grid and lens.layout_gds".into()));
    }
    if l.layout_grid.is_some() {
        for (key, given) in [
            ("gds_cell", l.gds_cell.is_some()),
            ("gds_layer", l.gds_layer.is_some()),
            ("gds_datatype", l.gds_datatype.is_some()),
            ("atom", l.atom.is_some()),
            ("handedness", l.handedness.is_some()),
        ] {
            if given {
                return Err(o.conflict(
                    &format!("lens.{key}"),
                    format!("lens.{key} is for lens.layout_gds; a layout_grid holds one parameter of pillars"),
                ));
            }
        }
    }
    let (library, names) = crate::lens_table::read_library(l, o)?;
    let pitch = o.require("lens.lattice_pitch_um", l.lattice_pitch_um, "the lattice pitch, µm (> 0)")?;
    let pitch = o.number("lens.lattice_pitch_um", pitch, pitch > 0.0, "the lattice pitch, µm (> 0)")? * 1e-6;
    let (grid, key, file, tolerance) = if let Some(file) = &l.layout_gds {
        let atom = match l.atom.as_deref().unwrap_or("pillar") {
            "pillar" => AtomKind::Pillar,
            "fin" => AtomKind::Fin,
            other => {
                return Err(o.bad(
                    "lens.atom",
                    quoted(other),
                    "\"pillar\" (diameter_nm) or \"fin\" (width_nm, length_nm, angle)",
                ));
            }
        };
        let layer = gds_number(o, "lens.gds_layer", l.gds_layer, true)?;
        let datatype = gds_number(o, "lens.gds_datatype", l.gds_datatype.or(Some(0)), false)?;
        let options = GdsOptions {
            cell: l.gds_cell.clone(),
            layer,
            datatype,
            pitch_m: pitch,
            atom,
            max_atoms: MAX_SITES,
            max_sites: MAX_SITES,
        };
        let grid = crate::gds::read_layout(&o.path(file), &options)
            .map_err(|e| o.bad("lens.layout_gds", quoted(file), &format!("a GDSII layout the lens can read: {e}")))?;
        // a polygon's vertices on the database grid move its diameter by up to √2 units
        let tolerance = 2.0 * grid.stats.database_unit_m * 1e9;
        (grid, "lens.layout_gds", file.clone(), tolerance)
    } else {
        let file = o.require("lens.layout_grid", l.layout_grid.as_deref(), "a .npy [y, x] of the atoms' parameter")?;
        if names.len() != 1 {
            return Err(o.bad(
                "lens.layout_grid",
                quoted(file),
                &format!("a library of one parameter column for a [y, x] grid; this library has {}", names.join(", ")),
            ));
        }
        let stack = crate::psf::map_of(o, "lens.layout_grid", file)
            .map_err(|m| o.bad("lens.layout_grid", quoted(file), &format!("a .npy float array [y, x]: {m}")))?;
        let (nx, ny) = (stack.nx, stack.ny);
        if (nx as u64).saturating_mul(ny as u64) > MAX_SITES {
            return Err(o.bad("lens.layout_grid", quoted(file), &format!("at most {MAX_SITES} sites")));
        }
        let empty: Vec<bool> = stack.values.iter().map(|v| v.is_nan()).collect();
        if let Some(i) = stack.values.iter().position(|v| v.is_infinite()) {
            return Err(o.bad(
                "lens.layout_grid",
                quoted(file),
                &format!(
                    "finite parameters (NaN for a site without an atom): site ({}, {}) is infinite",
                    i % nx,
                    i / nx
                ),
            ));
        }
        let atoms = empty.iter().filter(|e| !**e).count() as u64;
        let range = stack
            .values
            .iter()
            .filter(|v| !v.is_nan())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        let grid = lenses::AtomGrid {
            pitch_m: pitch,
            origin_m: (-0.5 * (nx as f64 - 1.0) * pitch, -0.5 * (ny as f64 - 1.0) * pitch),
            nx,
            ny,
            parameters: names.clone(),
            values: stack.values,
            empty,
            theta_deg: None,
            stats: lenses::LayoutStats {
                atoms,
                parameter_range: vec![range],
                empty_sites: nx as u64 * ny as u64 - atoms,
                ..lenses::LayoutStats::default()
            },
        };
        (grid, "lens.layout_grid", file.to_owned(), 0.0)
    };
    let empty_cell = empty_cell(l, o)?;
    let handedness = match l.handedness.as_deref() {
        None => None,
        Some("lcp") => Some(lenses::Handedness::Lcp),
        Some("rcp") => Some(lenses::Handedness::Rcp),
        Some(other) => {
            return Err(o.bad(
                "lens.handedness",
                quoted(other),
                "\"lcp\" or \"rcp\" (the light's circular polarization)",
            ));
        }
    };
    let source = format!(
        "library {}, layout {}",
        crate::error::shorten(l.library.as_deref().unwrap_or_default()),
        crate::error::shorten(&file)
    );
    let ctx = format!("{key} = {}", quoted(&file));
    let lens = lenses::LibraryMapLens::new(
        f_number,
        f0_m,
        l0,
        Arc::new(library),
        &names,
        &grid,
        empty_cell,
        handedness,
        tolerance,
        source,
    )
    .map_err(|e| match &e {
        lenses::Error::Layout(m) if m.contains("have no atom") => Error::Missing {
            origin: o.of("lens.empty_cell"),
            key: o.key("lens.empty_cell"),
            expected: format!(
                "what a site without an atom transmits ({ctx}: {m}): \"substrate\" (|t| = 1, φ = 0), [amplitude, phase_rad] or {{ amplitude = …, phase_rad = … }}"
            ),
        },
        _ => o.domain(key, &ctx, e),
    })?;
    let s = &grid.stats;
    let ranges: Vec<String> = grid
        .parameters
        .iter()
        .zip(&s.parameter_range)
        .zip(lens.library().ranges())
        .map(|((n, r), lib)| format!("{n} {}–{} (library {}–{})", num(r.0), num(r.1), num(lib.0), num(lib.1)))
        .collect();
    info.notes.push(format!(
        "layout: {} atoms on {} × {} sites of {} µm ({} in the aperture, {} empty there); {}; largest off-lattice distance {} nm, {} doubly occupied sites",
        s.atoms,
        grid.nx,
        grid.ny,
        num(pitch * 1e6),
        lens.atoms_in_aperture(),
        lens.empty_in_aperture(),
        ranges.join(", "),
        num((s.max_off_lattice_m * 1e9 * 100.0).round() / 100.0),
        s.doubly_occupied_sites,
    ));
    if lens.clamped_atoms() > 0 {
        info.notes.push(format!(
            "{} atoms outside the library's range by less than the drawing's resolution ({} nm) taken at its end",
            lens.clamped_atoms(),
            num(tolerance)
        ));
    }
    // the stated lattice error against the radial design (docs/physics.md, "2-D library layouts")
    let radius = 0.5 * f0_m / f_number;
    let g = std::f64::consts::FRAC_1_SQRT_2 * radius / (radius * radius + f0_m * f0_m).sqrt();
    let s_min = lenses::sinc(pitch * g / l0).powi(2);
    info.notes.push(format!(
        "lattice error against the radial design of the same layout: mean MTF and τ1 within 2 (1 − S_min) = {:.2e} at λ0 (S_min the cells' design-order amplitude at the aperture's edge)",
        2.0 * (1.0 - s_min)
    ));
    let lens = fabrication(l, o, lens, &names, info)?;
    let (tau, t) = lens.efficiency_and_transmission(l0);
    info.notes.push(format!(
        "at λ0: τ1 = {tau:.4}, T = {t:.4} (each cell's mean against the reference sphere is the design order; the rest of T is background)"
    ));
    info.design_wavelength_m = Some(l0);
    Ok(lens)
}

/// The 2-D layout as fabricated (docs/physics.md, "Fabrication errors of a 2-D layout"):
/// `lens.parameter_bias` (one per parameter column, added to every atom's parameters before the
/// library is read), the atoms' random phase and amplitude errors (`lens.atom_phase_error_rad`,
/// `lens.atom_transmission_error`, in expectation) and `lens.zernike_noll_rms_um` on the design
/// order's wavefront.
fn fabrication(
    l: &RawLens,
    o: &Origins,
    lens: lenses::LibraryMapLens,
    names: &[String],
    info: &mut LensInfo,
) -> Result<lenses::LibraryMapLens, Error> {
    let (phase, amplitude) = crate::lens_table::atom_error_sigmas(l, o, "those below 0 are taken as 0")?;
    let list = |b: &[f64]| format!("[{}]", b.iter().map(|&v| num(v)).collect::<Vec<_>>().join(", "));
    let dims = lens.library().dimensions();
    let bias = match &l.parameter_bias {
        None => vec![0.0; dims],
        Some(b) if b.len() != dims => {
            return Err(o.bad(
                "lens.parameter_bias",
                list(b),
                &format!(
                    "one bias per library parameter column, {dims} ({}), in that column's units",
                    names.join(", ")
                ),
            ));
        }
        Some(b) if b.iter().any(|v| !v.is_finite()) => {
            return Err(o.bad("lens.parameter_bias", list(b), "finite numbers"));
        }
        Some(b) => b.clone(),
    };
    let errors = lenses::AtomErrors { phase_sigma_rad: phase, transmission_sigma: amplitude, seed: 0 };
    let mut lens = lens.with_fabrication(&bias, errors).map_err(|e| match e {
        lenses::Error::Layout(m) => {
            o.bad("lens.parameter_bias", list(&bias), &format!("a bias that keeps every atom inside the library: {m}"))
        }
        e => o.domain("lens.parameter_bias", "[lens]", e),
    })?;
    if phase > 0.0 || amplitude > 0.0 || bias.iter().any(|&b| b != 0.0) {
        info.notes.push(format!(
            "fabrication errors: parameter bias {}, per-atom phase σ = {} rad and relative amplitude σ = {} in expectation over the draws (the expected field is the design order; the rest of the atoms' power is stray light, in T)",
            list(&bias),
            num(phase),
            num(amplitude),
        ));
    }
    if let Some(terms) = crate::lens_table::zernike(l, o)? {
        info.notes.push(crate::lens_table::zernike_note(&terms));
        lens = lens.with_zernike(terms).map_err(|e| o.domain("lens.zernike_noll_rms_um", "[lens]", e))?;
    }
    Ok(lens)
}

/// `lens.gds_layer` / `lens.gds_datatype`: a GDSII layer or datatype (0–32767).
fn gds_number(o: &Origins, key: &str, value: Option<i64>, required: bool) -> Result<i16, Error> {
    let expected = "an integer 0–32767 (the atoms' GDSII layer or datatype)";
    let v = if required { o.require(key, value, expected)? } else { value.unwrap_or(0) };
    i16::try_from(v).ok().filter(|v| *v >= 0).ok_or_else(|| o.bad(key, v, expected))
}

/// `lens.empty_cell`: `"substrate"` (|t| = 1, φ = 0), `[amplitude, phase_rad]` or
/// `{ amplitude = …, phase_rad = … }`.
fn empty_cell(l: &RawLens, o: &Origins) -> Result<Option<Complex64>, Error> {
    let expected = "\"substrate\" (|t| = 1, φ = 0), [amplitude, phase_rad] or { amplitude = …, phase_rad = … } with 0 ≤ amplitude ≤ 1";
    let Some(v) = &l.empty_cell else { return Ok(None) };
    let pair = match v {
        toml::Value::String(s) if s == "substrate" => Some((1.0, 0.0)),
        toml::Value::Array(a) if a.len() == 2 => match (
            a[0].as_float().or(a[0].as_integer().map(|i| i as f64)),
            a[1].as_float().or(a[1].as_integer().map(|i| i as f64)),
        ) {
            (Some(a), Some(p)) => Some((a, p)),
            _ => None,
        },
        toml::Value::Table(t) if t.len() == 2 => {
            let get = |k: &str| t.get(k).and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)));
            get("amplitude").zip(get("phase_rad"))
        }
        _ => None,
    };
    match pair {
        Some((a, p)) if a.is_finite() && p.is_finite() && (0.0..=1.0).contains(&a) => {
            Ok(Some(Complex64::from_polar(a, p)))
        }
        _ => Err(o.bad("lens.empty_cell", v, expected)),
    }
}
