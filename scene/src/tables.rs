//! Two-column CSV tables (`wavelength_nm, value`) for spectra and lens curves.

use std::path::Path;

use radiometry::Sampled;

use crate::error::{Error, shorten};

/// Reads a table of `wavelength_nm, value` rows: the rules of [`read_pairs`], wavelengths
/// converted to m.
pub fn read_table(path: &Path, lo: f64, hi: f64, what: &str) -> Result<Sampled, Error> {
    let (wavelengths, values) = read_pairs(path, &WAVELENGTH, lo, hi, what)?;
    sampled(path, &wavelengths, values)
}

/// The table read from `path` as a [`Sampled`] spectrum, wavelengths from nm to m.
pub(crate) fn sampled(path: &Path, wavelengths_nm: &[f64], values: Vec<f64>) -> Result<Sampled, Error> {
    let metres = wavelengths_nm.iter().map(|wl| wl * 1e-9).collect();
    Sampled::new(metres, values).map_err(|e| Error::Csv {
        file: path.display().to_string(),
        line: None,
        message: format!("invalid table: {e}"),
    })
}

/// The first column of a two-column table: its name and unit in messages, and whether 0 is
/// allowed.
pub struct Axis {
    /// Name, e.g. "wavelength".
    pub name: &'static str,
    /// Unit as typed, e.g. "nm".
    pub unit: &'static str,
    /// Whether the first value may be 0 (frequencies) or must be > 0 (wavelengths).
    pub zero_allowed: bool,
}

/// Wavelengths in nm, > 0.
pub const WAVELENGTH: Axis = Axis { name: "wavelength", unit: "nm", zero_allowed: false };

/// Spatial frequencies in cycles/mm, ≥ 0.
pub const FREQUENCY: Axis = Axis { name: "frequency", unit: "cyc_per_mm", zero_allowed: true };

/// Reads a UTF-8 text file (`what` names it in messages: "scene file", "CSV file"); a leading
/// byte-order mark is dropped, a file with a NUL or non-UTF-8 byte is refused as not text.
/// Files longer than this are refused unread (a scene is a few kB, a spectral table at most a
/// few MB): `/dev/zero` or a disk image given by mistake must not fill the memory.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// The bytes of `path` (a table in an encoding its parser decodes, e.g. a UTF-16 Zemax export),
/// refused unread beyond [`MAX_FILE_BYTES`].
pub(crate) fn read_bytes(path: &Path, what: &'static str) -> Result<Vec<u8>, Error> {
    use std::io::Read as _;
    let io = |cause| Error::Read { what, path: path.display().to_string(), cause };
    let mut bytes = Vec::new();
    std::fs::File::open(path).and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes)).map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(Error::TooLarge { what, path: path.display().to_string(), limit: MAX_FILE_BYTES });
    }
    Ok(bytes)
}

pub(crate) fn read_text(path: &Path, what: &'static str) -> Result<String, Error> {
    read_text_limited(path, what, MAX_FILE_BYTES)
}

/// The reader of the project's CSV inputs (tables, points files): `#` comments and blank lines
/// skipped, fields trimmed, rows of any length (the caller names a wrong count with its line).
/// Line numbers (from 1) of CSV records in their text. The csv crate's `Position` of a record is
/// where the reader began looking for it, before the blank lines (and comment lines) it skipped:
/// a row after two blank lines was named as line 3 where it stood on line 5. So the line is
/// counted here from that byte offset (`csv::Position::byte`), past the lines the reader skips.
/// Records come in order, so the newlines are counted once, from the last record on.
#[derive(Clone, Debug)]
pub struct CsvLines<'a> {
    text: &'a [u8],
    comment: Option<u8>,
    byte: usize,
    line: u64,
}

impl<'a> CsvLines<'a> {
    /// The lines of `text`, the very text the reader reads, whose lines starting with `comment`
    /// the reader skips (`Some(b'#')` for the project's reader, which reads `#` lines as comments).
    pub fn new(text: &'a str, comment: Option<u8>) -> Self {
        CsvLines { text: text.as_bytes(), comment, byte: 0, line: 1 }
    }

    /// The line at which the record at `position` stands (`None` without a position).
    pub fn of(&mut self, position: Option<&csv::Position>) -> Option<u64> {
        let mut target = usize::try_from(position?.byte()).unwrap_or(usize::MAX).min(self.text.len());
        if target < self.byte {
            (self.byte, self.line) = (0, 1);
        }
        self.line += self.text[self.byte..target].iter().filter(|&&b| b == b'\n').count() as u64;
        // past the empty and comment lines the reader skipped to reach the record
        loop {
            let rest = &self.text[target..];
            let skipped = match rest.first() {
                Some(b'\n') => 1,
                Some(b'\r') if rest.get(1) == Some(&b'\n') => 2,
                Some(c) if Some(*c) == self.comment => match rest.iter().position(|&b| b == b'\n') {
                    Some(end) => end + 1,
                    None => break,
                },
                _ => break,
            };
            target += skipped;
            self.line += 1;
        }
        self.byte = target;
        Some(self.line)
    }
}

pub(crate) fn csv_reader(text: &str, has_headers: bool) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .has_headers(has_headers)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes())
}

/// [`read_text`] with another size limit (points files of a sweep may hold millions of rows).
pub(crate) fn read_text_limited(path: &Path, what: &'static str, limit: u64) -> Result<String, Error> {
    use std::io::Read as _;
    let shown = || path.display().to_string();
    let io = |cause| Error::Read { what, path: shown(), cause };
    let mut bytes = Vec::new();
    std::fs::File::open(path).and_then(|f| f.take(limit + 1).read_to_end(&mut bytes)).map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(Error::TooLarge { what, path: shown(), limit });
    }
    let len = bytes.len();
    let text = String::from_utf8(bytes).map_err(|e| Error::NotText {
        what,
        path: shown(),
        offset: e.utf8_error().valid_up_to(),
        len,
    })?;
    if let Some(offset) = text.find('\0') {
        return Err(Error::NotText { what, path: shown(), offset, len });
    }
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_owned(),
        None => text,
    })
}

/// Whether a CSV field reads as a number, or starts like one (`0.1S`, `800nm`): such a field
/// makes its row data, never a header.
fn numeric_looking(field: &str) -> bool {
    field.parse::<f64>().is_ok() || field.starts_with(|c: char| c.is_ascii_digit() || "+-.".contains(c))
}

/// The unit a header's first field names, when it is one of the length units a wavelength
/// column might be given in (`wavelength_um`, `lambda (µm)`, `wl[nm]`).
fn header_length_unit(field: &str) -> Option<&'static str> {
    let lower = field.to_lowercase();
    let tokens: Vec<&str> =
        lower.split(|c: char| !(c.is_alphanumeric() || c == 'µ' || c == 'å')).filter(|t| !t.is_empty()).collect();
    let last = tokens.last().copied()?;
    if tokens.len() < 2 && !lower.contains(['(', '[']) {
        return None; // a bare word such as "nm" or "um" alone is taken as the unit only in a compound
    }
    Some(match last {
        "nm" | "nanometer" | "nanometers" | "nanometre" | "nanometres" => "nm",
        "um" | "µm" | "micron" | "microns" | "micrometer" | "micrometers" | "micrometre" | "micrometres" => "µm",
        "mm" => "mm",
        "m" | "meter" | "meters" | "metre" | "metres" => "m",
        "pm" => "pm",
        "a" | "å" | "angstrom" | "angstroms" => "Å",
        _ => return None,
    })
}

/// Reads a table of `x, value` rows as typed (`axis` units). `#` starts a comment line; the
/// first row is a header only if none of its fields is or starts like a number
/// (`wavelength_nm,value`): `700,nan` or `700,0.1S` is data and an error. A wavelength header
/// that names another unit (`wavelength_um`) is refused rather than read as nm. The `x` must
/// increase strictly; values must be finite and lie in `[lo, hi]` (`what` names them).
pub fn read_pairs(path: &Path, axis: &Axis, lo: f64, hi: f64, what: &str) -> Result<(Vec<f64>, Vec<f64>), Error> {
    let file = path.display().to_string();
    let (name, unit) = (axis.name, axis.unit);
    let err = |line: Option<u64>, message: String| Error::Csv { file: file.clone(), line, message };
    let text = read_text(path, "CSV file")?;
    let mut reader = csv_reader(&text, false);
    let mut lines = CsvLines::new(&text, Some(b'#'));
    // the first column kept as typed (the caller converts units)
    let (mut xs, mut values): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut first = true;
    for (index, record) in reader.records().enumerate() {
        let record = record.map_err(|e| {
            let line = lines.of(e.position());
            err(line, format!("malformed CSV: {}", shorten(&e.to_string())))
        })?;
        let line = lines.of(record.position()).unwrap_or(index as u64 + 1);
        if record.iter().all(str::is_empty) {
            continue;
        }
        let row = || shorten(&record.iter().collect::<Vec<_>>().join(","));
        if record.len() == 1 {
            let field = &record[0];
            let separator =
                [(';', "';'"), ('\t', "tab"), (' ', "spaces")].into_iter().find(|(c, _)| field.contains(*c));
            if let Some((_, separator)) = separator {
                return Err(err(
                    Some(line),
                    format!("`{}` is separated by {separator}; expected comma-separated `{name}_{unit}, value`", row()),
                ));
            }
        }
        if record.iter().any(|f| f.contains(';')) {
            return Err(err(
                Some(line),
                format!(
                    "`{}` contains ';' (a semicolon-separated table, decimal commas?); expected comma-separated `{name}_{unit}, value` with decimal points",
                    row()
                ),
            ));
        }
        if record.len() != 2 {
            return Err(err(
                Some(line),
                format!("`{}`: {} columns; expected two: {name}_{unit}, value", row(), record.len()),
            ));
        }
        let is_header = first && !record.iter().any(numeric_looking);
        first = false;
        if is_header {
            if axis.unit == "nm"
                && let Some(other) = header_length_unit(&record[0])
                && other != "nm"
            {
                return Err(err(
                    Some(line),
                    format!(
                        "the header `{}` gives the {name} in {other}; expected the {name} in nm (convert the column, header `{name}_nm`)",
                        row()
                    ),
                ));
            }
            continue;
        }
        let parse = |field: &str| -> Result<f64, Error> {
            match field.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                Ok(_) => Err(err(
                    Some(line),
                    format!(
                        "`{}` is not a pair of finite numbers: `{}` is not finite; expected {name}_{unit}, value",
                        row(),
                        shorten(field)
                    ),
                )),
                Err(_) => Err(err(
                    Some(line),
                    format!(
                        "`{}` is not a pair of finite numbers: `{}` is not a number; expected {name}_{unit}, value",
                        row(),
                        shorten(field)
                    ),
                )),
            }
        };
        let (x, v) = (parse(&record[0])?, parse(&record[1])?);
        if x < 0.0 || (x == 0.0 && !axis.zero_allowed) {
            let bound = if axis.zero_allowed { "≥ 0" } else { "> 0" };
            return Err(err(Some(line), format!("{name} {x} {unit}; expected a {name} {bound} {unit}")));
        }
        if let Some(&prev) = xs.last()
            && x <= prev
        {
            return Err(err(
                Some(line),
                format!("{name} {x} {unit} does not exceed the previous {prev} {unit}; {name}s must increase strictly"),
            ));
        }
        if !(lo..=hi).contains(&v) {
            return Err(err(Some(line), format!("{what} {v} is out of range; expected [{lo}, {hi}]")));
        }
        xs.push(x);
        values.push(v);
    }
    if xs.len() < 2 {
        return Err(err(None, format!("{} data rows; expected at least two rows of {name}_{unit}, value", xs.len())));
    }
    Ok((xs, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each record's line, counted by hand: blank lines (LF and CRLF) and `#` comments before a
    /// record, which the csv crate's own `Position::line` leaves out; without a comment character
    /// a `#` line is a record.
    #[test]
    fn csv_lines_count_the_skipped_lines() {
        let text = "h,v\n1,2\n\n\r\n# a comment\n3,4\n#x,y\n5,6\n";
        let lines_of = |comment: Option<u8>| -> Vec<u64> {
            let mut reader = csv::ReaderBuilder::new()
                .has_headers(false)
                .comment(comment)
                .flexible(true)
                .from_reader(text.as_bytes());
            let mut lines = CsvLines::new(text, comment);
            reader.records().map(|r| lines.of(r.unwrap().position()).unwrap()).collect()
        };
        assert_eq!(lines_of(Some(b'#')), vec![1, 2, 6, 8]);
        assert_eq!(lines_of(None), vec![1, 2, 5, 6, 7, 8]);
        // the crate's own count, for the record: it names line 3 for the row on line 6
        let mut reader = csv_reader(text, false);
        let third = reader.records().nth(2).unwrap().unwrap();
        assert_eq!(third.position().map(csv::Position::line), Some(3));
    }

    /// A bad row after blank lines and a comment is named by the line it stands on.
    #[test]
    fn a_bad_row_after_blank_lines_names_its_own_line() {
        let e = table("blank-lines.csv", b"wavelength_nm,value\n700,0.1\n\n\n# measured\n800,abc\n").unwrap_err();
        assert!(e.to_string().contains("line 6: `800,abc`"), "{e}");
    }

    fn table(name: &str, text: &[u8]) -> Result<(Vec<f64>, Vec<f64>), Error> {
        let dir = std::env::temp_dir().join(format!("scene-tables-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        read_pairs(&path, &WAVELENGTH, 0.0, 1.0, "efficiency")
    }

    /// A first row that starts with a number is data: `nan` or `0.1S` there is an error naming
    /// the line and the value, not a header silently dropped (it was, before).
    #[test]
    fn a_numeric_first_row_is_data_not_a_header() {
        for (name, text, bad) in [
            ("nan.csv", "700,nan\n800,0.1\n900,0.1\n", "`nan` is not finite"),
            ("unit.csv", "700,0.1S\n800,0.1\n900,0.1\n", "`0.1S` is not a number"),
        ] {
            let e = table(name, text.as_bytes()).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("line 1: ") && e.contains(bad), "{e}");
        }
        let (xs, _) = table("header.csv", b"wavelength_nm,value\n700,0.1\n800,0.2\n").unwrap();
        assert_eq!(xs, vec![700.0, 800.0]);
        let (xs, _) = table("bom.csv", "\u{feff}700,0.1\n800,0.2\n".as_bytes()).unwrap();
        assert_eq!(xs, vec![700.0, 800.0], "a byte-order mark must not turn the first row into a header");
    }

    #[test]
    fn other_separators_are_named() {
        for (name, text, sep) in [
            ("semi.csv", "wavelength_nm;value\n700;0.1\n800;0.2\n", "separated by ';'"),
            ("tab.csv", "700\t0.1\n800\t0.2\n", "separated by tab"),
            ("decimal-comma.csv", "700;0,1\n800;0,2\n", "contains ';'"),
        ] {
            let e = table(name, text.as_bytes()).unwrap_err().to_string();
            assert!(e.contains(sep) && e.contains("expected comma-separated `wavelength_nm, value`"), "{e}");
            assert!(e.contains("line 1"), "{e}");
        }
    }

    #[test]
    fn a_header_in_another_unit_is_refused() {
        let e = table("um.csv", b"wavelength_um,value\n0.7,0.1\n0.8,0.2\n").unwrap_err().to_string();
        assert!(e.contains("gives the wavelength in µm; expected the wavelength in nm"), "{e}");
        assert!(table("nm.csv", b"lambda (nm),value\n700,0.1\n800,0.2\n").is_ok());
    }

    #[test]
    fn binary_and_long_rows_give_short_messages() {
        let e = table("bin.csv", b"700,0.1\n\xff\xfe\x00\x01").unwrap_err().to_string();
        assert!(e.contains("not a text file") && e.contains("byte 8"), "{e}");
        let long = format!("700,{}\n", "9".repeat(1_000_000) + "x");
        let e = table("long.csv", long.as_bytes()).unwrap_err().to_string();
        assert!(e.len() < 400 && e.contains("bytes)"), "{} bytes: {}", e.len(), &e[..e.len().min(400)]);
    }
}

/// A segmented lens's zone map read from a text file: a square grid of zone numbers over the
/// full aperture's bounding square `[−1, 1]²` (docs/physics.md, "Lens families": segmented).
///
/// Format: one grid row per line, the first line at the top (`y = +1`), columns from `x = −1` to
/// `+1`; cells separated by spaces, tabs or commas; `1` … `N` is the zone of channel `k` (in the
/// order of `channels_nm`), `0` or `.` is opaque; `#` starts a comment line, blank lines are
/// skipped. Every row has as many cells as there are rows (at least 2, at most 4096). Cells
/// outside the unit circle are outside the lens whatever they hold.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ZoneGrid {
    side: usize,
    /// row-major from the top, 0 opaque, k ≥ 1 channel k
    cells: Vec<u16>,
}

impl ZoneGrid {
    /// The zone (0-based channel index) at `(x, y)` in `[−1, 1]²`, `None` where opaque.
    pub(crate) fn at(&self, x: f64, y: f64) -> Option<usize> {
        let n = self.side as f64;
        let col = (((x + 1.0) * 0.5 * n).floor().max(0.0) as usize).min(self.side - 1);
        let row = (((1.0 - y) * 0.5 * n).floor().max(0.0) as usize).min(self.side - 1);
        match self.cells[row * self.side + col] {
            0 => None,
            k => Some(usize::from(k) - 1),
        }
    }

    /// The largest zone number in the grid.
    pub(crate) fn zones(&self) -> usize {
        usize::from(self.cells.iter().copied().max().unwrap_or(0))
    }
}

/// Reads a [`ZoneGrid`] from `path` (`channels` zones accepted).
pub(crate) fn read_zone_grid(path: &Path, channels: usize) -> Result<ZoneGrid, Error> {
    let file = path.display().to_string();
    let err = |line: usize, message: String| Error::Csv { file: file.clone(), line: Some(line as u64), message };
    let text = read_text(path, "zone-mask file")?;
    let mut rows: Vec<(usize, Vec<u16>)> = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let number = index + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut row = Vec::new();
        for cell in line.split(|c: char| c == ',' || c.is_whitespace()).filter(|c| !c.is_empty()) {
            let zone = match cell {
                "." => 0,
                _ => match cell.parse::<u16>() {
                    Ok(k) if usize::from(k) <= channels => k,
                    _ => {
                        return Err(err(
                            number,
                            format!(
                                "cell {}: expected a zone number 1 to {channels} (one per channel of lens.channels_nm) or 0 or . for opaque",
                                shorten(cell)
                            ),
                        ));
                    }
                },
            };
            row.push(zone);
        }
        if row.len() > 4096 {
            return Err(err(number, format!("{} cells: expected at most 4096 per row", row.len())));
        }
        rows.push((number, row));
    }
    let side = rows.len();
    if !(2..=4096).contains(&side) {
        return Err(Error::Csv {
            file,
            line: None,
            message: format!("{side} grid rows: expected a square grid of 2 to 4096 rows of zone numbers"),
        });
    }
    let mut cells = Vec::with_capacity(side * side);
    for (number, row) in rows {
        if row.len() != side {
            return Err(err(
                number,
                format!(
                    "{} cells: expected {side}, as many as the grid has rows (a square over the aperture)",
                    row.len()
                ),
            ));
        }
        cells.extend(row);
    }
    Ok(ZoneGrid { side, cells })
}

#[cfg(test)]
mod zone_grid_tests {
    use super::*;

    /// Rows from the top (+y), columns from the left (−x); 0 and `.` opaque; zones 1-based in
    /// the file, 0-based channels in the map; the square's edges belong to its edge cells.
    #[test]
    fn grid_cells_map_to_the_aperture_square() {
        let dir = std::env::temp_dir().join(format!("scene-zone-grid-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("grid.txt");
        std::fs::write(&path, "# top row first\n1, 2\n. 3\n").unwrap();
        let grid = read_zone_grid(&path, 3).unwrap();
        assert_eq!(grid.zones(), 3);
        assert_eq!(grid.at(-0.5, 0.5), Some(0));
        assert_eq!(grid.at(0.5, 0.5), Some(1));
        assert_eq!(grid.at(-0.5, -0.5), None);
        assert_eq!(grid.at(0.5, -0.5), Some(2));
        assert_eq!((grid.at(1.0, 1.0), grid.at(-1.0, -1.0)), (Some(1), None));
        std::fs::write(&path, "1 2\n3 x\n").unwrap();
        let e = read_zone_grid(&path, 3).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("cell x"), "{e}");
    }
}

/// A radial phase table (`lens.phase_csv`): radii in mm from the axis, the phase at λ0 in
/// radians, and optionally the field amplitude.
pub(crate) struct PhaseTable {
    pub r_mm: Vec<f64>,
    pub phase_rad: Vec<f64>,
    pub amplitude: Option<Vec<f64>>,
}

/// Reads `r_mm, phase_rad[, amplitude]` (a header naming the columns, in any order; `#`
/// comments): `r` from 0, strictly increasing, reaching at least `aperture_radius_mm`; the phase
/// finite and unwrapped (a step of more than π between neighbouring samples is refused: the
/// table is then either wrapped or too coarse for its local zone period `2π/|φ'|`, and the
/// message gives both); the amplitude finite, ≥ 0, not zero everywhere.
pub(crate) fn read_phase_table(path: &Path, aperture_radius_mm: f64) -> Result<PhaseTable, Error> {
    let file = path.display().to_string();
    let err = |line: Option<u64>, message: String| Error::Csv { file: file.clone(), line, message };
    let (headers, rows) = read_columns(path, "phase table")?;
    let find = |name: &str| headers.iter().position(|h| h == name);
    let (Some(ir), Some(ip)) = (find("r_mm"), find("phase_rad")) else {
        return Err(err(
            Some(1),
            format!(
                "the header `{}` lacks r_mm or phase_rad: expected the columns r_mm, phase_rad and optionally amplitude",
                headers.join(",")
            ),
        ));
    };
    let ia = find("amplitude");
    let (mut r, mut phase, mut amp) = (Vec::new(), Vec::new(), Vec::new());
    for (line, values) in &rows {
        let ri = values[ir];
        if ri < 0.0 || r.last().is_some_and(|&last| ri <= last) {
            return Err(err(*line, format!("r_mm = {ri}: expected ≥ 0 and strictly increasing")));
        }
        r.push(ri);
        phase.push(values[ip]);
        if let Some(ia) = ia {
            let a = values[ia];
            if a < 0.0 {
                return Err(err(*line, format!("amplitude = {a}: expected ≥ 0 (a field amplitude)")));
            }
            amp.push(a);
        }
    }
    if r.len() < 4 {
        return Err(err(None, format!("{} rows: expected at least 4, from r = 0 to the aperture radius", r.len())));
    }
    if r[0] != 0.0 {
        return Err(err(None, format!("the first r_mm is {}: expected 0 (the table starts on the axis)", r[0])));
    }
    let last = r[r.len() - 1];
    if last < aperture_radius_mm * (1.0 - 1e-9) {
        return Err(err(
            None,
            format!(
                "the last r_mm is {last}: expected at least the aperture radius {aperture_radius_mm} mm (the table must cover the aperture)"
            ),
        ));
    }
    for i in 1..r.len() {
        let step = (phase[i] - phase[i - 1]).abs();
        if step > std::f64::consts::PI && r[i - 1] < aperture_radius_mm {
            let period = std::f64::consts::TAU * (r[i] - r[i - 1]) / step;
            return Err(err(
                None,
                format!(
                    "the phase steps by {step:.3} rad between r = {} and {} mm: more than π, so the table is wrapped or too coarse \
                     (a step of {step:.3} rad means a local zone period of about {period:.3e} mm; sample at least 4 points a zone and give the unwrapped phase)",
                    r[i - 1],
                    r[i]
                ),
            ));
        }
    }
    let amplitude = if ia.is_some() {
        if amp.iter().all(|&a| a == 0.0) {
            return Err(err(
                None,
                "the amplitude is 0 everywhere: expected a field amplitude > 0 somewhere".to_owned(),
            ));
        }
        // the amplitude is shape only (docs/physics.md): scaled to a largest value of 1 before
        // use, so that a uniform 1e-200 is the column of 1 it stands for (it gave a mean MTF of
        // 0.878 where the table without it gives 0.441)
        let top = amp.iter().copied().fold(0.0, f64::max);
        Some(amp.iter().map(|a| a / top).collect())
    } else {
        None
    };
    Ok(PhaseTable { r_mm: r, phase_rad: phase, amplitude })
}

/// Columns of a CSV table by their header names (`#` comments, a header row), every field a
/// finite number: the header's names (lower-cased) and the rows in order, each with the line it
/// came from.
pub(crate) type Columns = (Vec<String>, Vec<(Option<u64>, Vec<f64>)>);

/// Reads a CSV of named numeric columns (module docs of [`Columns`]); `what` names the table in
/// messages ("meta-atom library").
pub(crate) fn read_columns(path: &Path, what: &str) -> Result<Columns, Error> {
    let file = path.display().to_string();
    let text = read_text(path, "CSV file")?;
    let err = |line: Option<u64>, message: String| Error::Csv { file: file.clone(), line, message };
    let mut reader = csv_reader(&text, true);
    let headers: Vec<String> = reader
        .headers()
        .map_err(|e| err(None, format!("cannot read the header of the {what}: {e}")))?
        .iter()
        .map(|h| h.trim().to_lowercase())
        .collect();
    if headers.iter().any(|h| numeric_looking(h)) {
        return Err(err(
            Some(1),
            format!("the first row `{}` is not a header: the {what} needs its column names", headers.join(",")),
        ));
    }
    let mut rows = Vec::new();
    let mut lines = CsvLines::new(&text, Some(b'#'));
    for record in reader.records() {
        let record = record.map_err(|e| err(lines.of(e.position()), format!("{e}")))?;
        let line = lines.of(record.position());
        if record.len() != headers.len() {
            return Err(err(
                line,
                format!("{} fields: expected {} (the header's columns)", record.len(), headers.len()),
            ));
        }
        let mut values = Vec::with_capacity(headers.len());
        for (name, raw) in headers.iter().zip(record.iter()) {
            let v = raw
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(line, format!("{name} = `{}`: expected a finite number", shorten(raw))))?;
            values.push(v);
        }
        rows.push((line, values));
    }
    if rows.is_empty() {
        return Err(err(None, format!("no rows: the {what} is empty")));
    }
    Ok((headers, rows))
}

/// The long MTF CSV of `lens.mtf` (`wavelength_nm, frequency_cyc_per_mm, mtf[, sagittal]`) read
/// by the project's CSV reader ([`csv_reader`]: `#` comments, blank lines, quoting, fields
/// trimmed): a first row that is not all numbers is the header; every other row is numbers, each
/// with its line (from 1), for [`lenses::mtf_table_from_rows`]. Errors name the line, the
/// column and the value.
pub(crate) fn mtf_rows(text: &str) -> Result<Vec<(usize, Vec<f64>)>, lenses::Error> {
    let text = text.trim_start_matches('\u{feff}');
    let mut reader = csv_reader(text, false);
    let mut lines = CsvLines::new(text, Some(b'#'));
    let mut rows = Vec::new();
    let mut first = true;
    for record in reader.records() {
        let record = record.map_err(|e| lenses::Error::Parse {
            line: lines.of(e.position()).map_or(0, |l| l as usize),
            expected: "a CSV row".into(),
            found: e.to_string(),
        })?;
        let line = lines.of(record.position()).map_or(0, |l| l as usize);
        let numbers: Vec<Option<f64>> =
            record.iter().map(|f| f.parse::<f64>().ok().filter(|v| v.is_finite())).collect();
        match numbers.iter().position(Option::is_none) {
            // the header: names, not numbers, before any data
            Some(_) if first && rows.is_empty() => {}
            Some(column) => {
                const NAMES: [&str; 4] = ["wavelength_nm", "frequency_cyc_per_mm", "mtf", "sagittal"];
                let name = NAMES.get(column).map_or(String::new(), |n| format!(" ({n})"));
                return Err(lenses::Error::Parse {
                    line,
                    expected: format!("a finite number in column {}{name}", column + 1),
                    found: format!("`{}`", crate::error::shorten(&record[column])),
                });
            }
            None => rows.push((line, numbers.into_iter().flatten().collect())),
        }
        first = false;
    }
    Ok(rows)
}

#[cfg(test)]
mod mtf_rows_tests {
    use super::*;

    /// The long MTF CSV by the shared reader: comments, a header, quoted and padded fields, rows
    /// with their lines; a bad field named by line, column and value.
    #[test]
    fn reads_rows_by_the_shared_rules() {
        let text = "\u{feff}# measured\nwavelength_nm, frequency_cyc_per_mm, mtf\n600, 0, 1\n\"600\", 100 , 0.4\n";
        let rows = mtf_rows(text).unwrap();
        assert_eq!(rows, [(3, vec![600.0, 0.0, 1.0]), (4, vec![600.0, 100.0, 0.4])]);
        let table = lenses::mtf_table_from_rows(&rows).unwrap();
        assert_eq!(table.frequencies(), &[0.0, 1e5]);
        let e = mtf_rows("600, 0, 1\n600, 100, x\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("column 3 (mtf)") && e.contains("`x`"), "{e}");
        // a header after data is a bad row, not a second header
        let e = mtf_rows("600, 0, 1\nwavelength_nm, frequency_cyc_per_mm, mtf\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("column 1 (wavelength_nm)"), "{e}");
    }
}
