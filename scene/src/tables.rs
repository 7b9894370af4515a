//! Two-column CSV tables (`wavelength_nm, value`) for spectra and lens curves.

use std::path::Path;

use anyhow::{Context, Result, bail};
use radiometry::Sampled;

/// Reads a table of `wavelength_nm, value` rows; `#` starts a comment, and a first row that is
/// not numeric is taken as a header. Wavelengths must increase strictly; values must lie in
/// `[lo, hi]` (`what` names them in messages).
pub fn read_table(path: &Path, lo: f64, hi: f64, what: &str) -> Result<Sampled> {
    let shown = path.display();
    let (wavelengths, values) = read_pairs(path, &WAVELENGTH, lo, hi, what)?;
    let metres = wavelengths.iter().map(|wl| wl * 1e-9).collect();
    Sampled::new(metres, values).with_context(|| format!("{shown}: invalid table"))
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

/// Reads a table of `x, value` rows as typed (`axis` units): the rules of [`read_table`].
pub fn read_pairs(path: &Path, axis: &Axis, lo: f64, hi: f64, what: &str) -> Result<(Vec<f64>, Vec<f64>)> {
    let shown = path.display();
    let (name, unit) = (axis.name, axis.unit);
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read the CSV file {shown}"))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes());
    // the first column kept as typed (the caller converts units)
    let (mut xs, mut values): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    for (index, record) in reader.records().enumerate() {
        let record = record.with_context(|| format!("{shown}: malformed CSV"))?;
        let line = record.position().map_or(index as u64 + 1, |p| p.line());
        if record.iter().all(|f| f.is_empty()) {
            continue;
        }
        if record.len() != 2 {
            bail!("{shown}: line {line}: {} columns; expected two: {name}_{unit}, value", record.len());
        }
        let parse = |field: &str| field.parse::<f64>().ok().filter(|v| v.is_finite());
        match (parse(&record[0]), parse(&record[1])) {
            (Some(x), Some(v)) => {
                if x < 0.0 || (x == 0.0 && !axis.zero_allowed) {
                    let bound = if axis.zero_allowed { "≥ 0" } else { "> 0" };
                    bail!("{shown}: line {line}: {name} {x} {unit}; expected a {name} {bound} {unit}");
                }
                if let Some(&prev) = xs.last()
                    && x <= prev
                {
                    bail!(
                        "{shown}: line {line}: {name} {x} {unit} does not exceed the previous {prev} {unit}; {name}s must increase strictly"
                    );
                }
                if !(lo..=hi).contains(&v) {
                    bail!("{shown}: line {line}: {what} {v} is out of range; expected [{lo}, {hi}]");
                }
                xs.push(x);
                values.push(v);
            }
            _ if xs.is_empty() && index == 0 => {} // header row
            _ => bail!(
                "{shown}: line {line}: `{}` is not a pair of finite numbers; expected {name}_{unit}, value",
                record.iter().collect::<Vec<_>>().join(",")
            ),
        }
    }
    if xs.len() < 2 {
        bail!("{shown}: {} data rows; expected at least two rows of {name}_{unit}, value", xs.len());
    }
    Ok((xs, values))
}
