//! Zemax OpticStudio sequential files (`.zmx`) whose optical power is one Binary 2 surface on a
//! plane substrate: `[lens] zemax = "design.zmx"` fills the phase lens's keys from the file
//! (docs/physics.md, "Zemax OpticStudio files").
//!
//! The file is text, UTF-16 LE with a byte-order mark as OpticStudio writes it, or UTF-8/ASCII
//! ([`lenses::decode_text`]); one command a line, the commands after `SURF n` (indented) belong to
//! surface `n`. What is read:
//!
//! | command | meaning | scene key |
//! | --- | --- | --- |
//! | `MODE SEQ` | sequential mode (anything else refused) | |
//! | `UNIT MM` (`CM`, `IN`, `METER`) | the lens units of every length | |
//! | `ENPD d` | entrance pupil diameter (else `2 ×` the stop's semi-diameter `DIAM`) | `aperture_diameter_mm` |
//! | `WAVM n λ w`, `WAVL λ…`, `PWAV n` | the primary wavelength, µm | `design_wavelength_nm` |
//! | `TYPE BINARY_2`, `XDAT 1` = N, `XDAT 2` | the phase surface, its term count and normalization radius | `norm_radius_mm` |
//! | `XDAT 3 … 2+N` | the coefficients `A_i` on `ρ^{2i}`, radians | `binary2` |
//! | `PARM 0` | the diffraction order `M` (`PARM 1 … 8`: the substrate's even-asphere terms, 0) | `diffraction_order` |
//! | `DISZ` | thicknesses: their sum from the phase surface to the image | `focal_length_mm` |
//! | `STOP`, `DIAM` | the stop surface and its semi-diameter | |
//!
//! Anything that would make the file's system other than that lens is refused naming the line,
//! the surface number and its `TYPE`: a second powered surface, a curved or aspheric substrate,
//! a mirror, glass between the phase surface and the image, an object at a finite distance, a
//! stop after the lens, no stop, several configurations, unknown units.

use std::path::Path;

use crate::error::{Error, num};

/// What a `.zmx` file gives the phase lens, in the scene's units (mm, nm).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ZemaxLens {
    /// The Binary 2 surface's number in the file.
    pub surface: usize,
    /// `A_1 … A_N`, radians.
    pub coefficients: Vec<f64>,
    /// The normalization radius, mm.
    pub norm_radius_mm: f64,
    /// The diffraction order `M` (0 in the file is taken as 1, with a warning).
    pub diffraction_order: f64,
    /// The aperture (entrance pupil) diameter, mm.
    pub aperture_diameter_mm: f64,
    /// The primary wavelength, nm.
    pub design_wavelength_nm: f64,
    /// The distance from the phase surface to the image surface, mm.
    pub focal_length_mm: f64,
    /// How the values were found (the aperture's source, the units), for `asnr scene`.
    pub notes: Vec<String>,
    /// What the reader assumed and the user should check (a diffraction order of 0).
    pub warnings: Vec<String>,
}

/// One `SURF` block.
#[derive(Clone, Debug, Default)]
struct Surface {
    number: usize,
    /// The line of `SURF n`.
    line: usize,
    kind: String,
    /// The lines of `TYPE` and `CURV` (the `SURF` line where absent).
    kind_line: usize,
    curvature_line: usize,
    curvature: f64,
    conic: f64,
    /// `(line, text)` of `GLAS`, when given.
    glass: Option<(usize, String)>,
    /// `DISZ`: `None` for `INFINITY`.
    thickness: Option<f64>,
    semi_diameter: Option<f64>,
    stop: bool,
    /// `PARM i v`: `(i, v, line)`.
    parameters: Vec<(usize, f64, usize)>,
    /// `XDAT i v`: `(i, v, line)`.
    extra: Vec<(usize, f64, usize)>,
}

impl Surface {
    fn parameter(&self, i: usize) -> Option<(f64, usize)> {
        self.parameters.iter().rev().find(|p| p.0 == i).map(|p| (p.1, p.2))
    }

    fn extra(&self, i: usize) -> Option<(f64, usize)> {
        self.extra.iter().rev().find(|p| p.0 == i).map(|p| (p.1, p.2))
    }

    /// `surface N (TYPE)`, as messages name it.
    fn name(&self) -> String {
        format!("surface {} (TYPE {})", self.number, self.kind)
    }

    /// Whether the medium after the surface is glass (a `GLAS` other than blank or air).
    fn glass_after(&self) -> Option<&(usize, String)> {
        self.glass.as_ref().filter(|(_, g)| {
            let name = g.split_whitespace().next().unwrap_or("");
            !name.is_empty() && !name.eq_ignore_ascii_case("AIR")
        })
    }

    /// Whether any Binary 2 coefficient is non-zero.
    fn has_phase(&self) -> bool {
        self.extra.iter().any(|&(i, v, _)| i >= 3 && v != 0.0)
    }
}

/// The error of `file` at `line`.
fn bad(file: &str, line: Option<usize>, message: String) -> Error {
    Error::Zemax { file: file.to_owned(), line, message }
}

/// Reads `path` (`file` as messages name it) and the lens it holds; `surface` chooses the Binary
/// 2 surface where several are in the file.
pub(crate) fn read(path: &Path, file: &str, surface: Option<u32>) -> Result<ZemaxLens, Error> {
    let bytes = crate::tables::read_bytes(path, "Zemax file")?;
    let text = lenses::decode_text(&bytes).map_err(|e| bad(file, None, e.to_string()))?;
    parse(&text, file, surface)
}

/// A number of the file (`INFINITY` where `infinity` allows it).
fn number(file: &str, line: usize, command: &str, token: Option<&str>) -> Result<f64, Error> {
    let Some(token) = token else {
        return Err(bad(file, Some(line), format!("{command} without its value: expected a number")));
    };
    match token.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => {
            Err(bad(file, Some(line), format!("{command} {}: expected a finite number", crate::error::shorten(token))))
        }
    }
}

fn index(file: &str, line: usize, command: &str, token: Option<&str>) -> Result<usize, Error> {
    token.and_then(|t| t.parse::<usize>().ok()).filter(|&i| i <= 10_000).ok_or_else(|| {
        bad(file, Some(line), format!("{command} {}: expected an index 0 to 10000", token.unwrap_or("(nothing)")))
    })
}

/// The lens of the `.zmx` text `text` (`file` names it in messages).
pub(crate) fn parse(text: &str, file: &str, chosen: Option<u32>) -> Result<ZemaxLens, Error> {
    let mut surfaces: Vec<Surface> = Vec::new();
    let mut mode: Option<(usize, String)> = None;
    let mut unit: Option<(usize, String)> = None;
    let mut enpd: Option<(usize, f64)> = None;
    let mut aperture_kind: Option<(usize, String)> = None;
    let mut wavm: Vec<(usize, f64)> = Vec::new();
    let mut wavl: Vec<f64> = Vec::new();
    let mut pwav: Option<(usize, usize)> = None;
    let mut configurations: Option<(usize, usize)> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut tokens = raw.split_whitespace();
        let Some(command) = tokens.next() else { continue };
        let surface = surfaces.last_mut();
        match command {
            "MODE" => mode = Some((line, tokens.next().unwrap_or("").to_owned())),
            "UNIT" => unit = Some((line, tokens.next().unwrap_or("").to_owned())),
            "ENPD" => enpd = Some((line, number(file, line, command, tokens.next())?)),
            "FNUM" | "OBNA" | "FLOA" | "OBSC" | "PUPD" | "ISNA" => {
                aperture_kind = Some((line, command.to_owned()));
            }
            "WAVM" => {
                let n = index(file, line, command, tokens.next())?;
                let l = number(file, line, command, tokens.next())?;
                if n == 0 || n > 1000 {
                    return Err(bad(file, Some(line), format!("WAVM {n}: expected a wavelength number 1 to 1000")));
                }
                if wavm.len() < n {
                    wavm.resize(n, (0, f64::NAN));
                }
                wavm[n - 1] = (line, l);
            }
            "WAVL" => {
                wavl = tokens.map(|t| number(file, line, command, Some(t))).collect::<Result<_, _>>()?;
            }
            "PWAV" => pwav = Some((line, index(file, line, command, tokens.next())?)),
            "MNUM" => configurations = Some((line, index(file, line, command, tokens.next())?)),
            "SURF" => {
                let number = index(file, line, command, tokens.next())?;
                if number != surfaces.len() {
                    return Err(bad(
                        file,
                        Some(line),
                        format!(
                            "SURF {number}: expected surface {} (surfaces numbered from 0 in order)",
                            surfaces.len()
                        ),
                    ));
                }
                surfaces.push(Surface {
                    number,
                    line,
                    kind: "STANDARD".to_owned(),
                    kind_line: line,
                    curvature_line: line,
                    ..Surface::default()
                });
            }
            _ => {
                let Some(s) = surface else { continue };
                match command {
                    "TYPE" => {
                        s.kind = tokens.next().unwrap_or("").to_owned();
                        s.kind_line = line;
                    }
                    "CURV" => {
                        s.curvature = number(file, line, command, tokens.next())?;
                        s.curvature_line = line;
                    }
                    "CONI" => s.conic = number(file, line, command, tokens.next())?,
                    "GLAS" => s.glass = Some((line, tokens.collect::<Vec<_>>().join(" "))),
                    "DISZ" => {
                        s.thickness = match tokens.next() {
                            Some("INFINITY") => None,
                            t => Some(number(file, line, command, t)?),
                        }
                    }
                    "DIAM" => s.semi_diameter = Some(number(file, line, command, tokens.next())?),
                    "STOP" => s.stop = true,
                    "PARM" => {
                        let i = index(file, line, command, tokens.next())?;
                        let v = number(file, line, command, tokens.next())?;
                        s.parameters.push((i, v, line));
                    }
                    "XDAT" => {
                        let i = index(file, line, command, tokens.next())?;
                        let v = number(file, line, command, tokens.next())?;
                        s.extra.push((i, v, line));
                    }
                    _ => {}
                }
            }
        }
    }
    // the system
    match &mode {
        Some((_, m)) if m == "SEQ" => {}
        Some((line, m)) => {
            return Err(bad(
                file,
                Some(*line),
                format!("MODE {}: expected MODE SEQ (a sequential system)", crate::error::shorten(m)),
            ));
        }
        None if surfaces.is_empty() => {
            return Err(bad(file, None, "no MODE and no SURF: expected a Zemax OpticStudio .zmx lens file".to_owned()));
        }
        None => {}
    }
    if let Some((line, n)) = configurations
        && n > 1
    {
        return Err(bad(
            file,
            Some(line),
            format!("MNUM {n}: {n} configurations; expected one (save the configuration to evaluate as its own file)"),
        ));
    }
    let (unit_line, unit) =
        unit.ok_or_else(|| bad(file, None, "no UNIT line: expected UNIT MM, CM, IN or METER".to_owned()))?;
    let mm = match unit.as_str() {
        "MM" => 1.0,
        "CM" => 10.0,
        "IN" | "INCH" => 25.4,
        "METER" | "M" => 1000.0,
        other => {
            return Err(bad(
                file,
                Some(unit_line),
                format!("UNIT {}: expected lens units MM, CM, IN or METER", crate::error::shorten(other)),
            ));
        }
    };
    if surfaces.len() < 3 {
        return Err(bad(
            file,
            None,
            format!("{} surfaces: expected the object, the Binary 2 surface and the image at least", surfaces.len()),
        ));
    }
    let image = surfaces.len() - 1;
    // the object at infinity
    if let Some(t) = surfaces[0].thickness {
        return Err(bad(
            file,
            Some(surfaces[0].line),
            format!(
                "surface 0 (the object) at DISZ = {} {unit}: expected INFINITY (the scene's lens images an object at infinity)",
                num(t)
            ),
        ));
    }
    // every surface but the object: plane, no mirror; which carry a phase
    let mut binary: Vec<usize> = Vec::new();
    for s in &surfaces[1..] {
        if let Some((line, g)) = &s.glass
            && g.split_whitespace().next().is_some_and(|n| n.eq_ignore_ascii_case("MIRROR"))
        {
            return Err(bad(file, Some(*line), format!("{}: a mirror; expected a transmitting system", s.name())));
        }
        match s.kind.as_str() {
            "BINARY_2" => binary.push(s.number),
            "STANDARD" => {}
            _ => {
                return Err(bad(
                    file,
                    Some(s.kind_line),
                    format!(
                        "{}: expected TYPE STANDARD (plane) surfaces and one BINARY_2 surface on a plane substrate",
                        s.name()
                    ),
                ));
            }
        }
        if s.curvature != 0.0 {
            let what = if s.number == image { "a curved image surface" } else { "a curved surface (optical power)" };
            return Err(bad(
                file,
                Some(s.curvature_line),
                format!(
                    "{}: CURV = {} (radius {} {unit}), {what}; expected plane surfaces: the lens's power is its Binary 2 phase on a plane (or plane-parallel) substrate",
                    s.name(),
                    num(s.curvature),
                    num(1.0 / s.curvature)
                ),
            ));
        }
    }
    // the Binary 2 surface
    let powered: Vec<usize> = binary.iter().copied().filter(|&k| surfaces[k].has_phase()).collect();
    let k = match chosen {
        Some(c) => {
            let c = c as usize;
            if !binary.contains(&c) {
                let list: Vec<String> = binary.iter().map(ToString::to_string).collect();
                return Err(bad(
                    file,
                    None,
                    format!(
                        "lens.zemax_surface = {c}: not a BINARY_2 surface; the file's BINARY_2 surfaces: {}",
                        if list.is_empty() { "none".to_owned() } else { list.join(", ") }
                    ),
                ));
            }
            c
        }
        None => match (binary.as_slice(), powered.as_slice()) {
            ([], _) => {
                return Err(bad(
                    file,
                    None,
                    "no BINARY_2 surface: expected one (the lens's phase, Zemax Binary 2)".to_owned(),
                ));
            }
            ([only], _) | (_, [only]) => *only,
            (_, []) => {
                let list: Vec<String> = binary.iter().map(ToString::to_string).collect();
                return Err(bad(
                    file,
                    None,
                    format!(
                        "BINARY_2 surfaces {} all without a phase term: give lens.zemax_surface, the surface to read",
                        list.join(", ")
                    ),
                ));
            }
            _ => powered[0],
        },
    };
    if let Some(&other) = powered.iter().find(|&&p| p != k) {
        let s = &surfaces[other];
        return Err(bad(
            file,
            Some(s.line),
            format!(
                "{}: a second powered surface (a Binary 2 phase beside surface {k}'s); expected one phase surface",
                s.name()
            ),
        ));
    }
    let s = &surfaces[k];
    // its substrate: plane (CURV checked above), no even-asphere sag terms
    for &(i, v, line) in &s.parameters {
        if (1..=8).contains(&i) && v != 0.0 {
            return Err(bad(
                file,
                Some(line),
                format!(
                    "{}: PARM {i} = {}, the substrate's even-asphere term on r^{}: expected a plane substrate (PARM 1 to 8 zero; the diffraction order is PARM 0)",
                    s.name(),
                    num(v),
                    2 * i
                ),
            ));
        }
    }
    let (order, order_line) = s.parameter(0).unwrap_or((f64::NAN, s.line));
    let mut warnings = Vec::new();
    let order = if order.is_nan() || order == 0.0 {
        warnings.push(format!(
            "{file}: line {order_line}: {}: diffraction order {} (PARM 0); taken as M = 1, the coefficients as written (some exporters write 0; in OpticStudio M = 0 traces no diffracted power)",
            s.name(),
            if order.is_nan() { "not given".to_owned() } else { "0".to_owned() }
        ));
        1.0
    } else {
        order
    };
    let terms = match s.extra(1) {
        Some((n, line)) => {
            if n.fract() != 0.0 || !(1.0..=1000.0).contains(&n) {
                return Err(bad(
                    file,
                    Some(line),
                    format!("{}: XDAT 1 = {} terms: expected a whole number 1 to 1000", s.name(), num(n)),
                ));
            }
            n as usize
        }
        None => {
            return Err(bad(
                file,
                Some(s.line),
                format!("{}: no XDAT 1 (the number of terms): expected the Binary 2 extra data", s.name()),
            ));
        }
    };
    let norm = match s.extra(2) {
        Some((r, _)) if r > 0.0 => r,
        Some((r, line)) => {
            return Err(bad(
                file,
                Some(line),
                format!("{}: XDAT 2 = {}: expected a normalization radius > 0", s.name(), num(r)),
            ));
        }
        None => {
            return Err(bad(file, Some(s.line), format!("{}: no XDAT 2 (the normalization radius)", s.name())));
        }
    };
    let coefficients: Vec<f64> = (0..terms).map(|i| s.extra(3 + i).map_or(0.0, |(v, _)| v)).collect();
    let mut notes = Vec::new();
    if let Some(&(i, v, line)) = s.extra.iter().find(|&&(i, v, _)| i > 2 + terms && v != 0.0) {
        notes.push(format!(
            "line {line}: XDAT {i} = {} beyond the {terms} terms XDAT 1 counts: not used, as in OpticStudio",
            num(v)
        ));
    }
    // from the phase surface to the image: air, plane
    let mut distance = 0.0;
    for t in &surfaces[k..image] {
        if let Some((line, g)) = t.glass_after() {
            return Err(bad(
                file,
                Some(*line),
                format!(
                    "{}: GLAS {} after the phase surface: expected air between the Binary 2 surface and the image (the detector distance is the focal length in air; put the phase on the substrate's image side)",
                    t.name(),
                    crate::error::shorten(g)
                ),
            ));
        }
        let Some(d) = t.thickness else {
            return Err(bad(file, Some(t.line), format!("{}: DISZ INFINITY before the image", t.name())));
        };
        distance += d;
    }
    if distance <= 0.0 {
        return Err(bad(
            file,
            Some(s.line),
            format!("{}: the image {} {unit} after it: expected a distance > 0", s.name(), num(distance)),
        ));
    }
    // the stop: at the lens or before it
    let Some(stop) = surfaces.iter().find(|t| t.stop) else {
        return Err(bad(
            file,
            None,
            "sequential mode without a STOP surface: expected one (the aperture stop)".to_owned(),
        ));
    };
    if stop.number > k {
        return Err(bad(
            file,
            Some(stop.line),
            format!(
                "{}: the stop after the phase surface {k}: expected the stop at the lens or before it (the scene's aperture is the lens's)",
                stop.name()
            ),
        ));
    }
    let aperture = match (enpd, stop.semi_diameter) {
        (Some((line, d)), _) => {
            if d <= 0.0 {
                return Err(bad(file, Some(line), format!("ENPD {}: expected a diameter > 0", num(d))));
            }
            notes.push(format!("aperture: ENPD = {} {unit}", num(d)));
            d
        }
        (None, Some(r)) if r > 0.0 => {
            let kind = aperture_kind
                .as_ref()
                .map(|(_, c)| format!(" (the file's aperture is given by {c})"))
                .unwrap_or_default();
            notes.push(format!(
                "aperture: 2 × the stop surface {}'s semi-diameter DIAM = {} {unit}{kind}",
                stop.number,
                num(r)
            ));
            2.0 * r
        }
        _ => {
            return Err(bad(
                file,
                Some(stop.line),
                format!(
                    "{}: the stop without a semi-diameter DIAM > 0, and no ENPD: expected one of them",
                    stop.name()
                ),
            ));
        }
    };
    // the primary wavelength, µm
    let (pwav_line, p) = pwav.ok_or_else(|| bad(file, None, "no PWAV (the primary wavelength's number)".to_owned()))?;
    let micrometres = if !wavm.is_empty() {
        match wavm.get(p.wrapping_sub(1)) {
            Some(&(_, l)) if l.is_finite() => l,
            _ => {
                return Err(bad(file, Some(pwav_line), format!("PWAV {p}: no WAVM {p} line in the file")));
            }
        }
    } else {
        match wavl.get(p.wrapping_sub(1)) {
            Some(&l) => l,
            None => return Err(bad(file, Some(pwav_line), format!("PWAV {p}: no wavelength {p} in the file"))),
        }
    };
    if micrometres <= 0.0 {
        return Err(bad(
            file,
            Some(pwav_line),
            format!("the primary wavelength {} µm: expected > 0", num(micrometres)),
        ));
    }
    if mm != 1.0 {
        notes.push(format!("lengths in {unit}, × {} to mm", num(mm)));
    }
    Ok(ZemaxLens {
        surface: k,
        coefficients,
        norm_radius_mm: norm * mm,
        diffraction_order: order,
        aperture_diameter_mm: aperture * mm,
        design_wavelength_nm: micrometres * 1e3,
        focal_length_mm: distance * mm,
        notes,
        warnings,
    })
}

/// What a `.zmx` file gave a lens table (`lens::apply_zemax`), for `asnr scene` and the lens's notes.
#[derive(Clone, Debug)]
pub(crate) struct ZemaxSource {
    /// The path as given in the scene.
    pub file: String,
    /// The Binary 2 surface read.
    pub surface: usize,
    /// The keys the file supplied.
    pub keys: Vec<String>,
    /// How the values were found.
    pub notes: Vec<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    const EXAMPLE: &str = include_str!("../../examples/phase-binary2.toml");

    /// The Binary 2 coefficients of examples/phase-binary2.toml, read from it.
    fn example_coefficients() -> Vec<f64> {
        let table: toml::Table = toml::from_str(EXAMPLE).unwrap();
        let lens = table["lens"].as_table().unwrap();
        lens["binary2"].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect()
    }

    /// A .zmx as OpticStudio writes it: the object at infinity, a fused-silica substrate, the
    /// Binary 2 metasurface (the stop) `f0` before the image; `edit` changes its text.
    fn zmx(coefficients: &[f64], edit: &dyn Fn(String) -> String) -> String {
        let xdat: String = coefficients
            .iter()
            .enumerate()
            .map(|(i, a)| format!("  XDAT {} {a:e} 0 0 1.0E+0 0.0E+0 0 \"\"\n", i + 3))
            .collect();
        let text = format!(
            "VERS 190513 80 123 L123\nMODE SEQ\nNAME test\nUNIT MM X W X CM MR CPMM\nENPD 1.344\n\
             WAVM 1 0.55 1\nWAVM 2 0.8 1\nWAVM 3 0.9 1\nPWAV 2\n\
             SURF 0\n  TYPE STANDARD\n  CURV 0.0 0 0 0 0 \"\"\n  DISZ INFINITY\n\
             SURF 1\n  TYPE STANDARD\n  CURV 0.0 0 0 0 0 \"\"\n  DISZ 0.5\n  GLAS F_SILICA 0 0 1.458 67.8\n  DIAM 0.672 1 0 0 1 \"\"\n\
             SURF 2\n  STOP\n  TYPE BINARY_2\n  CURV 0.0 0 0 0 0 \"\"\n  DISZ 3.36\n  DIAM 0.672 1 0 0 1 \"\"\n\
             PARM 0 1\n  PARM 1 0\n  PARM 2 0\n  XDAT 1 {} 0 0\n  XDAT 2 0.672 0 0\n{xdat}\
             SURF 3\n  TYPE STANDARD\n  CURV 0.0 0 0 0 0 \"\"\n  DISZ 0\nMNUM 1 1\n",
            coefficients.len()
        );
        edit(text)
    }

    /// UTF-16 LE with a byte-order mark, CRLF line ends: as OpticStudio saves a file.
    fn utf16(text: &str) -> Vec<u8> {
        let mut out = vec![0xFF, 0xFE];
        for u in text.replace('\n', "\r\n").encode_utf16() {
            out.extend_from_slice(&u.to_le_bytes());
        }
        out
    }

    fn build(text: String) -> Result<metric::Scene, Error> {
        crate::build_from(&crate::Source::from_text(text, "test.toml", std::env::temp_dir()), &[])
    }

    /// The lens section of the example replaced by `lens`.
    fn with_lens(lens: &str) -> String {
        let (a, b) = (EXAMPLE.find("[lens]").unwrap(), EXAMPLE.find("[source]").unwrap());
        format!("{}{lens}\n\n{}", &EXAMPLE[..a], &EXAMPLE[b..])
    }

    /// A UTF-16 `.zmx` written here with the example's coefficients gives the example scene's
    /// numbers: bit for bit against the same lens with `aperture_diameter_mm` (the keys the file
    /// fills), to 1e-12 against the example's `f_number = 2.5` (F# = 3.36/1.344 in floating point).
    #[test]
    fn a_utf16_zmx_equals_the_toml_scene() {
        let dir = std::env::temp_dir().join(format!("asnr-zmx-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("lens.zmx");
        std::fs::write(&path, utf16(&zmx(&example_coefficients(), &|t| t))).unwrap();
        let from_file = build(with_lens(&format!(
            "[lens]\nzemax = \"{}\"\ndispersion = \"geometric-phase\"\nefficiency = 0.15\ntransmission = 0.55",
            path.display()
        )))
        .unwrap();
        let by_diameter = build(EXAMPLE.replace("f_number = 2.5", "aperture_diameter_mm = 1.344")).unwrap();
        let example = build(EXAMPLE.to_owned()).unwrap();
        let a = metric::evaluate(&from_file).unwrap();
        let b = metric::evaluate(&by_diameter).unwrap();
        let c = metric::evaluate(&example).unwrap();
        assert_eq!((a.asnr, a.mean_mtf), (b.asnr, b.mean_mtf));
        for (x, y) in [(a.asnr, c.asnr), (a.mean_mtf, c.mean_mtf), (a.asnr_mean, c.asnr_mean)] {
            assert!((x - y).abs() <= 1e-12 * y.abs(), "{x} vs {y}");
        }
        assert_eq!(from_file.lens().describe(), by_diameter.lens().describe());
        // the committed example file reads as the same lens
        let committed = read(Path::new("../examples/phase-binary2.zmx"), "phase-binary2.zmx", None).unwrap();
        let written = parse(&zmx(&example_coefficients(), &|t| t), "w", None).unwrap();
        assert_eq!((committed.coefficients, committed.focal_length_mm), (written.coefficients.clone(), 3.36));
        assert_eq!(written.design_wavelength_nm, 800.0);
        // the committed example scene, which names the committed file, gives the same numbers
        let scene = crate::load(Some(Path::new("../examples/phase-binary2-zmx.toml")), &[]).unwrap();
        let d = metric::evaluate(&scene).unwrap();
        assert_eq!((d.asnr, d.mean_mtf), (b.asnr, b.mean_mtf));
        std::fs::remove_dir_all(&dir).ok();
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// Any text, and the example file with any line dropped or cut short, is read or refused
        /// naming the file: never a panic.
        #[test]
        fn any_text_is_read_or_refused(text in "[ -~\n]{0,400}", drop in 0usize..64, cut in 0usize..40) {
            if let Err(e) = parse(&text, "t.zmx", None) {
                proptest::prop_assert!(e.to_string().starts_with("t.zmx: "));
            }
            let good = zmx(&example_coefficients(), &|t| t);
            let lines: Vec<&str> = good.lines().collect();
            let edited: Vec<String> = lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != drop % lines.len())
                .map(|(i, l)| if i % 7 == cut % 7 { l.chars().take(cut).collect() } else { (*l).to_owned() })
                .collect();
            if let Err(e) = parse(&edited.join("\n"), "t.zmx", None) {
                proptest::prop_assert!(e.to_string().starts_with("t.zmx: "));
            }
        }
    }

    /// What the file gives and where a scene key clashes with it.
    #[test]
    fn keys_from_the_file_and_their_clashes() {
        let dir = std::env::temp_dir().join(format!("asnr-zmx-keys-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("l.zmx"), zmx(&example_coefficients(), &|t| t)).unwrap();
        let scene = |extra: &str| {
            with_lens(&format!(
                "[lens]\nzemax = \"l.zmx\"\ndispersion = \"geometric-phase\"\nefficiency = 0.15\n{extra}"
            ))
        };
        let src = |text: String| crate::Source::from_text(text, "s.toml", dir.clone());
        let e = crate::build_from(&src(scene("focal_length_mm = 3.0")), &[]).unwrap_err().to_string();
        assert!(e.contains("lens.focal_length_mm") && e.contains("lens.zemax"), "{e}");
        let e = crate::build_from(&src(scene("f_number = 2.0")), &[]).unwrap_err().to_string();
        assert!(e.contains("lens.f_number"), "{e}");
        let e = crate::build_from(&src(scene("model = \"chromatic\"")), &[]).unwrap_err().to_string();
        assert!(e.contains("lens.model"), "{e}");
        // a --set overrides the file's value
        let moved = crate::build_from(&src(scene("")), &["lens.focal_length_mm=3.5".to_owned()]).unwrap();
        assert_eq!(moved.lens().focal_length(), 3.5e-3);
        let shown = crate::resolved_toml(&src(scene("")), &[]).unwrap().toml;
        assert!(
            shown.contains("# from the Zemax file \"l.zmx\", surface 2") && shown.contains("binary2 = ["),
            "{shown}"
        );
        let e = crate::build_from(&src(scene("zemax_surface = 1")), &[]).unwrap_err().to_string();
        assert!(e.contains("zemax_surface = 1") && e.contains("BINARY_2 surfaces: 2"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Each file the scene cannot take is refused naming the file, the line and the surface.
    #[test]
    fn bad_files_are_refused_naming_line_and_surface() {
        let coefficients = example_coefficients();
        let second = |t: String| {
            t.replace(
                "SURF 3\n  TYPE STANDARD\n  CURV 0.0 0 0 0 0 \"\"\n  DISZ 0\n",
                "SURF 3\n  TYPE BINARY_2\n  DISZ 1\n  XDAT 1 1 0 0\n  XDAT 2 1 0 0\n  XDAT 3 -10 0 0\nSURF 4\n  TYPE STANDARD\n  DISZ 0\n",
            )
        };
        type Edit = Box<dyn Fn(String) -> String>;
        let cases: Vec<(&str, Edit, &str)> = vec![
            (
                "second powered surface",
                Box::new(second),
                "line 35: surface 3 (TYPE BINARY_2): a second powered surface",
            ),
            ("no stop", Box::new(|t: String| t.replace("  STOP\n", "")), "without a STOP surface"),
            (
                "curved substrate",
                Box::new(|t: String| t.replacen("TYPE BINARY_2\n  CURV 0.0", "TYPE BINARY_2\n  CURV 0.01", 1)),
                "line 23: surface 2 (TYPE BINARY_2): CURV = 0.01",
            ),
            (
                "aspheric substrate",
                Box::new(|t: String| t.replace("PARM 2 0", "PARM 2 1e-3")),
                "line 28: surface 2 (TYPE BINARY_2): PARM 2 = 0.001",
            ),
            ("unknown units", Box::new(|t: String| t.replace("UNIT MM", "UNIT FURLONG")), "line 4: UNIT FURLONG"),
            ("non-sequential", Box::new(|t: String| t.replace("MODE SEQ", "MODE NSC")), "line 2: MODE NSC"),
            (
                "finite object",
                Box::new(|t: String| t.replace("DISZ INFINITY", "DISZ 100")),
                "line 10: surface 0 (the object) at DISZ = 100",
            ),
            (
                "a lens of glass",
                Box::new(|t: String| t.replacen("TYPE STANDARD\n  CURV 0.0", "TYPE STANDARD\n  CURV 0.05", 2)),
                "line 16: surface 1 (TYPE STANDARD): CURV = 0.05",
            ),
            (
                "glass after the phase",
                Box::new(|t: String| t.replace("  DISZ 3.36\n", "  DISZ 3.36\n  GLAS N-BK7\n")),
                "line 25: surface 2 (TYPE BINARY_2): GLAS N-BK7 after the phase surface",
            ),
            (
                "a coordinate break",
                Box::new(|t: String| t.replace("SURF 1\n  TYPE STANDARD", "SURF 1\n  TYPE COORDBRK")),
                "line 15: surface 1 (TYPE COORDBRK)",
            ),
            (
                "stop after",
                Box::new(|t: String| t.replace("  STOP\n", "").replace("SURF 3\n", "SURF 3\n  STOP\n")),
                "the stop after",
            ),
            ("no wavelength", Box::new(|t: String| t.replace("PWAV 2", "PWAV 7")), "line 9: PWAV 7"),
            ("configurations", Box::new(|t: String| t.replace("MNUM 1 1", "MNUM 3 1")), "MNUM 3"),
            ("no terms", Box::new(|t: String| t.replace("  XDAT 1 4 0 0\n", "")), "no XDAT 1"),
        ];
        let mut wrong = Vec::new();
        for (what, edit, want) in cases {
            let text = zmx(&coefficients, &*edit);
            let e = parse(&text, "design.zmx", None).unwrap_err().to_string();
            if !(e.starts_with("design.zmx: ") && e.contains(want)) {
                wrong.push(format!("{what}: {e}"));
            }
            // the same through the UTF-16 decoder
            let decoded = lenses::decode_text(&utf16(&text)).unwrap();
            assert_eq!(parse(&decoded, "design.zmx", None).unwrap_err().to_string(), e, "{what}");
        }
        assert!(wrong.is_empty(), "{wrong:#?}");
    }

    /// A diffraction order of 0 is taken as 1 with a warning; units scale every length; the
    /// aperture without ENPD is twice the stop's semi-diameter; XDAT past the term count is unused.
    #[test]
    fn order_units_and_aperture() {
        let c = example_coefficients();
        let zero = parse(&zmx(&c, &|t| t.replace("PARM 0 1", "PARM 0 0")), "z", None).unwrap();
        assert_eq!(zero.diffraction_order, 1.0);
        assert!(zero.warnings[0].contains("diffraction order 0 (PARM 0)"), "{:?}", zero.warnings);
        let minus = parse(&zmx(&c, &|t| t.replace("PARM 0 1", "PARM 0 -1")), "z", None).unwrap();
        assert_eq!((minus.diffraction_order, minus.warnings.len()), (-1.0, 0));
        let cm = parse(&zmx(&c, &|t| t.replace("UNIT MM", "UNIT CM")), "z", None).unwrap();
        for (v, want) in [(cm.focal_length_mm, 33.6), (cm.aperture_diameter_mm, 13.44), (cm.norm_radius_mm, 6.72)] {
            assert!((v - want).abs() < 1e-12 * want, "{v} vs {want}");
        }
        let stop = parse(&zmx(&c, &|t| t.replace("ENPD 1.344\n", "FNUM 2.5 0\n")), "z", None).unwrap();
        assert_eq!(stop.aperture_diameter_mm, 1.344);
        assert!(stop.notes.iter().any(|n| n.contains("semi-diameter") && n.contains("FNUM")), "{:?}", stop.notes);
        let fewer = parse(&zmx(&c, &|t| t.replace("XDAT 1 4", "XDAT 1 2")), "z", None).unwrap();
        assert_eq!(fewer.coefficients, c[..2]);
        assert!(fewer.notes.iter().any(|n| n.contains("XDAT 5")), "{:?}", fewer.notes);
        let wavl = parse(
            &zmx(&c, &|t| t.replace("WAVM 1 0.55 1\nWAVM 2 0.8 1\nWAVM 3 0.9 1\n", "WAVL 0.55 0.8 0.9\n")),
            "z",
            None,
        )
        .unwrap();
        assert_eq!(wavl.design_wavelength_nm, 800.0);
    }
}
