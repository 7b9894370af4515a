//! Sweeps: one scene evaluated at many values of its keys, the same way for every front end.
//!
//! `asnr sweep` (grids, `--points` files, `--shard I/N`), `asnr merge` and the Python package's
//! `evaluate_many` all build each point with [`evaluate_point`] (`asnr sweep` through [`Points`],
//! which reads the scene file once and builds the same scene) and write it with [`csv_row`], so a
//! point computed by any of them is the same `f64`s and, in CSV, the same bytes. A grid is the
//! cartesian product of its axes, the first key varying slowest ([`Grid`]); a point's *index* is
//! its position in that order (or its row in a points file), which shards and merges keep.
//!
//! ```
//! use scene::sweep::{Grid, axis, evaluate_point};
//! let source = scene::read(None).unwrap(); // the embedded paper scene
//! let grid = Grid::new(vec![axis(2.0, 4.0, 3), axis(10.0, 100.0, 2)]);
//! assert_eq!(grid.len(), 6);
//! assert_eq!(grid.values(3), vec![3.0, 100.0]); // the second F-number, the second range
//! let keys = ["lens.f_number".to_owned(), "spectrum.range_nm".to_owned()];
//! let point = evaluate_point(&source, &[], &keys, &grid.values(3)).unwrap();
//! assert!(point.asnr > 0.0 && point.mean_mtf < 1.0);
//! ```

use std::path::Path;
use std::sync::Arc;

use serde::Serialize;

use optics::LensModel;

use crate::{Error, Source};

/// `KEY=VALUE` for a generated value: the shortest decimal that parses back to the same `f64`,
/// as a TOML integer when it is a whole number TOML's 64-bit integers hold exactly (|v| < 2^53:
/// integer keys such as `options.pupil_samples` stay integers), else in exponent form, which TOML
/// reads as a float (`5e19`, not `50000000000000000000`, which overflows TOML's integers).
pub fn assignment(key: &str, value: f64) -> String {
    if value.fract() == 0.0 && value.abs() < 9_007_199_254_740_992.0 {
        format!("{key}={value}")
    } else if value.fract() != 0.0 && value.abs() >= 1e-5 && value.abs() < 1e16 {
        // plain decimals with a point are TOML floats too, and read better
        format!("{key}={value}")
    } else {
        format!("{key}={value:e}")
    }
}

/// `n` values from `lo` to `hi`, both included, equally spaced: `lo + (hi − lo) i/(n − 1)`, the
/// last exactly `hi` (`lo` alone for `n ≤ 1`). `asnr sweep --over KEY=LO:HI:N` and the Python
/// package's `asnr.axis` use it, so their grids are the same numbers.
pub fn axis(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let n = n.max(1);
    if n == 1 {
        return vec![lo];
    }
    (0..n).map(|i| if i + 1 == n { hi } else { lo + (hi - lo) * i as f64 / (n - 1) as f64 }).collect()
}

/// The cartesian product of axes, the first varying slowest.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    axes: Vec<Vec<f64>>,
}

impl Grid {
    /// The grid of `axes` (each non-empty).
    pub fn new(axes: Vec<Vec<f64>>) -> Grid {
        Grid { axes }
    }

    /// Its points: the product of the axes' lengths.
    pub fn len(&self) -> usize {
        self.axes.iter().map(Vec::len).product()
    }

    /// Whether it has no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Its axes.
    pub fn axes(&self) -> &[Vec<f64>] {
        &self.axes
    }

    /// The values of point `index` (`0 ≤ index < len`), one per axis.
    pub fn values(&self, index: usize) -> Vec<f64> {
        let mut flat = index;
        let mut values = vec![0.0; self.axes.len()];
        for (k, axis) in self.axes.iter().enumerate().rev() {
            values[k] = axis[flat % axis.len()];
            flat /= axis.len();
        }
        values
    }
}

/// The points of shard `shard` of `count` (1-based, `1 ≤ shard ≤ count`) among `total`: the
/// indices `shard − 1, shard − 1 + count, …` (strided, so every shard gets a share of each
/// region of the grid and the shards take about equal time).
pub fn shard_indices(shard: usize, count: usize, total: usize) -> impl Iterator<Item = usize> {
    (shard.saturating_sub(1)..total).step_by(count.max(1))
}

/// One evaluated point.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// The swept keys' values, in the keys' order.
    pub values: Vec<f64>,
    /// Mean MTF up to Nyquist.
    pub mean_mtf: f64,
    /// Zero-frequency SNR.
    pub snr0: f64,
    /// The ASNR (the scene's form).
    pub asnr: f64,
    /// Signal photoelectrons per pixel.
    pub photoelectrons: f64,
    /// Whether the Fraunhofer model is valid there (SI eq. S15).
    pub fraunhofer_valid: bool,
    /// The evaluation's warnings there (truncated spectra, saturation, validity).
    pub warnings: Vec<String>,
}

/// Why a point could not be evaluated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PointError {
    /// The scene with the point's values is not valid.
    #[error(transparent)]
    Scene(#[from] Error),
    /// The scene is valid but cannot be evaluated (no signal, a work budget exceeded, …).
    #[error("{label}: {cause}")]
    Evaluate {
        /// How the scene is named ([`Source::label`]).
        label: String,
        /// Why.
        cause: metric::Error,
    },
}

/// The scene of `source` with `overrides` and then `keys[i] = values[i]` ([`assignment`]),
/// evaluated (`metric::evaluate`).
pub fn evaluate_point(
    source: &Source,
    overrides: &[String],
    keys: &[String],
    values: &[f64],
) -> Result<Point, PointError> {
    evaluate_point_with_lens(source, overrides, keys, values, None)
}

/// [`evaluate_point`] with the scene's lens replaced by `lens` when given (the Python package's
/// lenses written in Python): the same scene, evaluation and point otherwise.
pub fn evaluate_point_with_lens(
    source: &Source,
    overrides: &[String],
    keys: &[String],
    values: &[f64],
    lens: Option<Arc<dyn LensModel>>,
) -> Result<Point, PointError> {
    let mut set = overrides.to_vec();
    set.extend(keys.iter().zip(values).map(|(k, v)| assignment(k, *v)));
    let scene = crate::build_from(source, &set)?;
    evaluate_scene(source, scene, values, lens)
}

/// The point of `scene` (its lens replaced by `lens` when given), evaluated.
fn evaluate_scene(
    source: &Source,
    mut scene: metric::Scene,
    values: &[f64],
    lens: Option<Arc<dyn LensModel>>,
) -> Result<Point, PointError> {
    if let Some(lens) = lens {
        scene = scene.with_lens(lens);
    }
    let r =
        metric::evaluate(&scene).map_err(|cause| PointError::Evaluate { label: source.label().to_owned(), cause })?;
    Ok(Point {
        values: values.to_vec(),
        mean_mtf: r.mean_mtf,
        snr0: r.snr0,
        asnr: r.asnr,
        photoelectrons: r.photoelectrons,
        fraunhofer_valid: r.fraunhofer.valid,
        warnings: r.warnings,
    })
}

/// Many points of one scene and its overrides over the same keys: [`evaluate_point`] at each,
/// the same `f64`s and errors, with the scene file read once. The first point builds its scene
/// the whole way and keeps the merged table and its deserialized form; the next ones set their
/// keys' values on the sections that hold them and deserialize those sections alone, then build
/// and validate the scene as [`crate::build_from`] does. Keys it cannot set that way (list
/// entries, a lens preset, …) and any point whose scene fails to build go the whole way, so
/// every message is the same. Shared by threads (`&self`).
pub struct Points<'a> {
    source: &'a Source,
    overrides: &'a [String],
    keys: &'a [String],
    prepared: std::sync::OnceLock<Option<crate::load::Prepared>>,
}

impl<'a> Points<'a> {
    /// The points of `source` with `overrides` and then `keys` set.
    pub fn new(source: &'a Source, overrides: &'a [String], keys: &'a [String]) -> Points<'a> {
        Points { source, overrides, keys, prepared: std::sync::OnceLock::new() }
    }

    /// [`evaluate_point`] at `values` (one per key).
    pub fn evaluate(&self, values: &[f64]) -> Result<Point, PointError> {
        self.evaluate_with_lens(values, None)
    }

    /// [`evaluate_point_with_lens`] at `values` (one per key).
    pub fn evaluate_with_lens(&self, values: &[f64], lens: Option<Arc<dyn LensModel>>) -> Result<Point, PointError> {
        let prepared = self.prepared.get_or_init(|| {
            let mut set = self.overrides.to_vec();
            set.extend(self.keys.iter().zip(values).map(|(k, v)| assignment(k, *v)));
            crate::load::Prepared::new(self.source, &set, self.keys)
        });
        match prepared.as_ref().and_then(|p| p.build(values)) {
            Some(loaded) => evaluate_scene(self.source, loaded.scene, values, lens),
            None => evaluate_point_with_lens(self.source, self.overrides, self.keys, values, lens),
        }
    }
}

/// The result columns of a sweep's CSV, after the keys' columns.
pub const RESULT_COLUMNS: [&str; 6] = ["mean_mtf", "snr0", "asnr", "photoelectrons", "fraunhofer_valid", "warnings"];

/// The column a sharded sweep writes first: the point's index in the whole sweep.
pub const INDEX_COLUMN: &str = "index";

/// One CSV line (with its `\n`) of `fields`, written by the `csv` crate: a field is quoted when
/// it holds a comma, a quote or a line break (RFC 4180), the one rule of every CSV the project
/// writes (sweeps, merges, the MTF curve, render's contrast table, the PSF matrices).
pub fn csv_line<I, S>(fields: I) -> String
where
    I: IntoIterator<Item = S>,
    S: AsRef<[u8]>,
{
    let mut writer = csv::WriterBuilder::new().terminator(csv::Terminator::Any(b'\n')).from_writer(Vec::new());
    // writing to memory cannot fail, and the fields are the caller's UTF-8 text
    let _ = writer.write_record(fields);
    let bytes = writer.into_inner().unwrap_or_default();
    String::from_utf8(bytes).unwrap_or_default()
}

/// The header line (with its `\n`): `index` first when `indexed`, one column per key (its dotted
/// name), then [`RESULT_COLUMNS`].
pub fn csv_header(keys: &[String], indexed: bool) -> String {
    let mut fields: Vec<&str> = Vec::with_capacity(keys.len() + RESULT_COLUMNS.len() + 1);
    if indexed {
        fields.push(INDEX_COLUMN);
    }
    fields.extend(keys.iter().map(String::as_str));
    fields.extend(RESULT_COLUMNS);
    csv_line(fields)
}

/// One point's line (with its `\n`): its index first when given, the keys' values, the results
/// (shortest round-trip decimals), the Fraunhofer validity and the warnings joined by ` | `.
pub fn csv_row(point: &Point, index: Option<usize>) -> String {
    use std::fmt::Write;
    // the numbers and the validity never hold a comma, a quote or a line break, which [`csv_line`]
    // quotes: where the warnings hold none either, the line is its fields joined by commas
    // (test `a_csv_row_is_the_csv_writers_line`), with no writer made for it
    let warnings = point.warnings.join(" | ");
    if !warnings.contains([',', '"', '\r', '\n']) {
        let mut line = String::with_capacity(24 * (point.values.len() + 5) + warnings.len());
        if let Some(i) = index {
            let _ = write!(line, "{i},");
        }
        for v in point.values.iter().chain(&[point.mean_mtf, point.snr0, point.asnr, point.photoelectrons]) {
            let _ = write!(line, "{v},");
        }
        let _ = writeln!(line, "{},{warnings}", point.fraunhofer_valid);
        return line;
    }
    let mut fields: Vec<String> = Vec::with_capacity(point.values.len() + RESULT_COLUMNS.len() + 1);
    fields.extend(index.map(|i| i.to_string()));
    fields.extend(point.values.iter().map(f64::to_string));
    fields.extend([point.mean_mtf, point.snr0, point.asnr, point.photoelectrons].map(|v| v.to_string()));
    fields.push(point.fraunhofer_valid.to_string());
    fields.push(warnings);
    csv_line(fields)
}

/// The most rows a points file may hold (as many as a sweep's grid).
pub const MAX_POINTS: usize = 10_000_000;

/// A points file: designs that are not a grid, one row each.
#[derive(Clone, Debug, PartialEq)]
pub struct PointsFile {
    /// The header: one dotted scene key per column.
    pub keys: Vec<String>,
    /// The rows' values, one per key.
    pub rows: Vec<Vec<f64>>,
}

/// Reads a points file: a CSV whose header names scene keys (`lens.f_number,spectrum.range_nm`)
/// and whose every row gives a finite number for each (blank lines and `#` comment lines
/// skipped). Errors name the file, the line, the column and the value.
pub fn read_points(path: &Path) -> Result<PointsFile, Error> {
    let file = path.display().to_string();
    let bad = |line: Option<u64>, message: String| Error::Csv { file: file.clone(), line, message };
    let text = crate::tables::read_text_limited(path, "points file", 1 << 30)?;
    let mut reader = crate::tables::csv_reader(&text, true);
    let header = reader.headers().map_err(|e| bad(Some(1), format!("cannot read the header: {e}")))?.clone();
    let keys: Vec<String> = header.iter().map(str::to_owned).collect();
    // a file without its header: its first row would be read as keys "2.5", …
    if let Some(number) = keys.iter().find(|k| k.trim().parse::<f64>().is_ok()) {
        return Err(bad(
            Some(1),
            format!(
                "header `{}`: `{number}` is a number, not a scene key: a points file starts with a header naming the keys of its columns, e.g. `lens.f_number,spectrum.range_nm`",
                header.iter().collect::<Vec<_>>().join(",")
            ),
        ));
    }
    if keys.is_empty() || keys.iter().any(String::is_empty) {
        return Err(bad(
            Some(1),
            format!(
                "header `{}`: expected dotted scene keys, one per column, e.g. `lens.f_number,spectrum.range_nm`",
                header.iter().collect::<Vec<_>>().join(",")
            ),
        ));
    }
    if let Some((i, k)) = keys.iter().enumerate().find(|(i, k)| keys[..*i].contains(k)) {
        return Err(bad(
            Some(1),
            format!(
                "column {} `{k}` repeats column {}: give each key once",
                i + 1,
                1 + keys.iter().position(|x| x == k).unwrap_or(0)
            ),
        ));
    }
    let mut rows = Vec::new();
    let mut lines = crate::tables::CsvLines::new(&text, Some(b'#'));
    for record in reader.records() {
        let record = record.map_err(|e| bad(lines.of(e.position()), format!("{e}")))?;
        let line = lines.of(record.position());
        if record.iter().all(str::is_empty) {
            continue;
        }
        if record.len() != keys.len() {
            return Err(bad(
                line,
                format!("{} fields: expected {}, one per key of the header", record.len(), keys.len()),
            ));
        }
        let mut values = Vec::with_capacity(keys.len());
        for (field, key) in record.iter().zip(&keys) {
            match field.parse::<f64>() {
                Ok(v) if v.is_finite() => values.push(v),
                _ => {
                    return Err(bad(
                        line,
                        format!("{key} = `{}`: expected a finite number", crate::error::shorten(field)),
                    ));
                }
            }
        }
        rows.push(values);
        if rows.len() > MAX_POINTS {
            return Err(bad(line, format!("more than {MAX_POINTS} points: split the file")));
        }
    }
    if rows.is_empty() {
        return Err(bad(None, "no points: expected a header of scene keys and at least one row of numbers".to_owned()));
    }
    Ok(PointsFile { keys, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assignments_parse_back_as_toml_bit_for_bit() {
        // 5e19 as "50000000000000000000" is a TOML integer beyond i64; whole numbers below 2^53
        // stay integers (integer keys), everything else round-trips through a TOML float
        assert_eq!(assignment("k", 5e19), "k=5e19");
        assert_eq!(assignment("k", 64.0), "k=64");
        for v in [5e19, 64.0, 0.1, 1.0 / 3.0, -2.5e-7, 1e-300, 5e-324, f64::MAX, -9.007_199_254_740_993e15, 123456.789]
        {
            let text = assignment("k", v);
            let literal = &text[2..];
            // a TOML integer (no point, no exponent) must fit in i64; anything else is a float
            if !literal.contains(['.', 'e']) {
                assert!(literal.parse::<i64>().is_ok(), "{text}");
            }
            assert_eq!(literal.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{text}");
        }
    }

    /// `Points` gives each point [`evaluate_point`]'s answer (the reference: the scene built
    /// from its TOML at each point): the same `f64`s and warnings, and the same refusal.
    #[test]
    fn points_answer_as_evaluate_point_does() {
        let source = crate::read(None).unwrap();
        let overrides = ["exposure.time_ms=2".to_owned()];
        let keys = ["lens.f_number".to_owned(), "spectrum.range_nm".to_owned()];
        let points = Points::new(&source, &overrides, &keys);
        // F/1.4 over 300 nm: blurred beyond the Fraunhofer threshold (a warning); F/0: refused
        for values in [[2.5, 50.0], [1.4, 300.0], [0.0, 50.0], [5.0, 2.0], [-1.0, 3.0]] {
            let (a, b) = (points.evaluate(&values), evaluate_point(&source, &overrides, &keys, &values));
            match (a, b) {
                (Ok(a), Ok(b)) => {
                    assert_eq!(csv_row(&a, None), csv_row(&b, None));
                    assert_eq!(a.asnr.to_bits(), b.asnr.to_bits());
                }
                (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                (a, b) => panic!("{values:?}: {a:?} against {b:?}"),
            }
        }
        assert!(points.prepared.get().is_some_and(Option::is_some), "the paper scene's keys are prepared");
    }

    #[test]
    fn a_grid_lists_its_points_first_axis_slowest() {
        let grid = Grid::new(vec![axis(1.0, 2.0, 2), axis(0.0, 1.0, 3)]);
        let all: Vec<Vec<f64>> = (0..grid.len()).map(|i| grid.values(i)).collect();
        assert_eq!(
            all,
            vec![vec![1.0, 0.0], vec![1.0, 0.5], vec![1.0, 1.0], vec![2.0, 0.0], vec![2.0, 0.5], vec![2.0, 1.0]]
        );
        assert_eq!(axis(1.4, 5.0, 40)[39], 5.0);
        assert_eq!(axis(3.0, 9.0, 1), vec![3.0]);
    }

    #[test]
    fn shards_partition_the_points() {
        for (count, total) in [(1, 7), (3, 7), (4, 4), (5, 3)] {
            let mut seen: Vec<usize> = (1..=count).flat_map(|s| shard_indices(s, count, total)).collect();
            seen.sort_unstable();
            assert_eq!(seen, (0..total).collect::<Vec<_>>(), "{count} shards of {total}");
        }
        assert_eq!(shard_indices(2, 3, 8).collect::<Vec<_>>(), vec![1, 4, 7]);
    }

    #[test]
    fn a_csv_row_quotes_only_the_warnings_that_need_it() {
        let point = Point {
            values: vec![2.5, 0.1],
            mean_mtf: 0.25,
            snr0: 10.0,
            asnr: 2.5,
            photoelectrons: 100.0,
            fraunhofer_valid: false,
            warnings: vec!["a, b".to_owned(), "c".to_owned()],
        };
        assert_eq!(csv_row(&point, None), "2.5,0.1,0.25,10,2.5,100,false,\"a, b | c\"\n");
        assert_eq!(csv_row(&point, Some(7)), "7,2.5,0.1,0.25,10,2.5,100,false,\"a, b | c\"\n");
        let keys = ["lens.f_number".to_owned()];
        assert_eq!(
            csv_header(&keys, true),
            "index,lens.f_number,mean_mtf,snr0,asnr,photoelectrons,fraunhofer_valid,warnings\n"
        );
    }

    /// A point's line is the one the `csv` crate writes of its fields (each number's shortest
    /// decimal, the validity, the warnings joined by ` | `), with and without an index, whatever
    /// the warnings hold.
    #[test]
    fn a_csv_row_is_the_csv_writers_line() {
        let written = |point: &Point, index: Option<usize>| {
            let mut fields: Vec<String> = index.iter().map(usize::to_string).collect();
            fields.extend(point.values.iter().map(f64::to_string));
            fields.extend([point.mean_mtf, point.snr0, point.asnr, point.photoelectrons].map(|v| v.to_string()));
            fields.push(point.fraunhofer_valid.to_string());
            fields.push(point.warnings.join(" | "));
            csv_line(fields)
        };
        let warnings: [&[&str]; 7] = [
            &[],
            &["1.11 % of the signal is blurred beyond the Fraunhofer threshold of 0.25 mm"],
            &["a", "b"],
            &["a, b"],
            &["say \"x\""],
            &["two\nlines", "cr\r"],
            &["", ""],
        ];
        for (k, w) in warnings.iter().enumerate() {
            let point = Point {
                values: vec![1.4, 5.01010101010101, -0.0, 1e-300, f64::INFINITY][..1 + k % 5].to_vec(),
                mean_mtf: 0.9189413370831366,
                snr0: f64::NAN,
                asnr: -2.5e-17,
                photoelectrons: 1e22,
                fraunhofer_valid: k % 2 == 0,
                warnings: w.iter().map(|s| (*s).to_owned()).collect(),
            };
            for index in [None, Some(0), Some(3999)] {
                assert_eq!(csv_row(&point, index), written(&point, index), "{w:?}");
            }
        }
    }

    #[test]
    fn a_points_file_is_read_and_its_errors_name_line_and_value() {
        let dir = std::env::temp_dir().join(format!("asnr-points-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.csv");
        std::fs::write(&good, "lens.f_number, spectrum.range_nm\n# a comment\n2.5,50\n\n4,1e2\n").unwrap();
        let read = read_points(&good).unwrap();
        assert_eq!(read.keys, vec!["lens.f_number", "spectrum.range_nm"]);
        assert_eq!(read.rows, vec![vec![2.5, 50.0], vec![4.0, 100.0]]);
        let bad = dir.join("bad.csv");
        std::fs::write(&bad, "lens.f_number\n2.5\nfast\n").unwrap();
        let e = read_points(&bad).unwrap_err().to_string();
        assert!(e.contains("bad.csv: line 3: lens.f_number = `fast`: expected a finite number"), "{e}");
        std::fs::write(&bad, "lens.f_number,lens.f_number\n2.5,3\n").unwrap();
        assert!(read_points(&bad).unwrap_err().to_string().contains("repeats column 1"));
        std::fs::write(&bad, "lens.f_number\n").unwrap();
        assert!(read_points(&bad).unwrap_err().to_string().contains("no points"));
        std::fs::write(&bad, "a,b\n1\n").unwrap();
        assert!(read_points(&bad).unwrap_err().to_string().contains("1 fields: expected 2"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
