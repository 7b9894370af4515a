//! Two-column CSV tables (`wavelength_nm, value`) for spectra and lens curves.

use std::path::Path;

use anyhow::{Context, Result, bail};
use radiometry::Sampled;

/// Reads a table of `wavelength_nm, value` rows; `#` starts a comment, and a first row that is
/// not numeric is taken as a header. Wavelengths must increase strictly; values must lie in
/// `[lo, hi]` (`what` names them in messages).
pub fn read_table(path: &Path, lo: f64, hi: f64, what: &str) -> Result<Sampled> {
    let shown = path.display();
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read the CSV file {shown}"))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes());
    // wavelengths kept in nm as typed, for messages; converted to m at the end
    let (mut wavelengths, mut values): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    for (index, record) in reader.records().enumerate() {
        let record = record.with_context(|| format!("{shown}: malformed CSV"))?;
        let line = record.position().map_or(index as u64 + 1, |p| p.line());
        if record.iter().all(|f| f.is_empty()) {
            continue;
        }
        if record.len() != 2 {
            bail!("{shown}: line {line}: {} columns; expected two: wavelength_nm, value", record.len());
        }
        let parse = |field: &str| field.parse::<f64>().ok().filter(|v| v.is_finite());
        match (parse(&record[0]), parse(&record[1])) {
            (Some(wl), Some(v)) => {
                if wl <= 0.0 {
                    bail!("{shown}: line {line}: wavelength {wl} nm; expected a wavelength > 0 nm");
                }
                if let Some(&prev) = wavelengths.last()
                    && wl <= prev
                {
                    bail!(
                        "{shown}: line {line}: wavelength {wl} nm does not exceed the previous {prev} nm; wavelengths must increase strictly"
                    );
                }
                if !(lo..=hi).contains(&v) {
                    bail!("{shown}: line {line}: {what} {v} is out of range; expected [{lo}, {hi}]");
                }
                wavelengths.push(wl);
                values.push(v);
            }
            _ if wavelengths.is_empty() && index == 0 => {} // header row
            _ => bail!(
                "{shown}: line {line}: `{}` is not a pair of finite numbers; expected wavelength_nm, value",
                record.iter().collect::<Vec<_>>().join(",")
            ),
        }
    }
    if wavelengths.len() < 2 {
        bail!("{shown}: {} data rows; expected at least two rows of wavelength_nm, value", wavelengths.len());
    }
    let metres = wavelengths.iter().map(|wl| wl * 1e-9).collect();
    Sampled::new(metres, values).with_context(|| format!("{shown}: invalid table"))
}
