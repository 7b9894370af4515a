//! `asnr plot`: replot sweep CSVs (`asnr sweep --csv`) as overlaid lines, or one of them as a
//! heatmap, without evaluating anything. `cargo xtask figures` draws the paper's Fig. 2a, 2b and
//! SI Fig. S9 with it from the CSVs it keeps in `docs/figures/`.
//!
//! Every line of a CSV is a point; columns are found by their header names (`lens.f_number`,
//! `spectrum.range_nm`, `asnr`, …). Lines starting with `#` are comments. `--shade-invalid`
//! reads the `fraunhofer_valid` column (SI eq. S15) and shades where it is `false`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::plot::{self, Figure, Grid, Labels, Mark, Series};

/// The column `--shade-invalid` reads: whether the Fraunhofer approximation holds (SI eq. S15).
const VALID_COLUMN: &str = "fraunhofer_valid";

/// Legend entry of the shaded points or cells.
const SHADE_LABEL: &str = "Fraunhofer approximation not valid (SI eq. S15)";

// Arguments of `asnr plot`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args, Debug)]
pub struct PlotArgs {
    /// Sweep CSV files (as written by `asnr sweep --csv`), each with an optional legend label:
    /// theory.csv=theory. Several files overlay their lines; a heatmap takes one.
    #[arg(required = true, value_name = "CSV[=LABEL]")]
    inputs: Vec<String>,
    /// The column on the x axis, e.g. spectrum.range_nm.
    #[arg(long, value_name = "COLUMN")]
    x: String,
    /// The column on the y axis: the value of each line (e.g. asnr), or with --z the heatmap's
    /// second key.
    #[arg(long, value_name = "COLUMN")]
    y: String,
    /// Draw a heatmap of this column over --x and --y (a complete grid from one CSV) with the
    /// ridge of its maximum: for each x, the y where it is largest.
    #[arg(long, value_name = "COLUMN")]
    z: Option<String>,
    /// Split each CSV into one line per distinct value of this column, e.g. lens.f_number.
    #[arg(long, value_name = "COLUMN", conflicts_with = "z")]
    group: Option<String>,
    /// Legend label of each group; `{}` stands for its value, e.g. "F/{}" (default: the column's
    /// name and unit, e.g. "pixel pitch = {} µm").
    #[arg(long, value_name = "TEMPLATE", requires = "group")]
    group_label: Option<String>,
    /// The plot to write, .svg or .png.
    #[arg(short, long, value_name = "FILE.svg|png")]
    output: PathBuf,
    /// Caption above the chart (default: "Y vs X" with the columns' names; "" for none).
    #[arg(long)]
    title: Option<String>,
    /// Description of the x axis (default: the column's name and unit, e.g. "spectral range (nm)"
    /// for spectrum.range_nm).
    #[arg(long, value_name = "TEXT")]
    x_label: Option<String>,
    /// Description of the y axis (default: the column's name and unit).
    #[arg(long, value_name = "TEXT")]
    y_label: Option<String>,
    /// Description of the heatmap's colour bar (default: the --z column's name and unit).
    #[arg(long, value_name = "TEXT", requires = "z")]
    z_label: Option<String>,
    /// Width of the plot, pixels (default 900); the height follows.
    #[arg(long, value_name = "PX")]
    width: Option<u32>,
    /// Resolution, dots per inch: text is 8–10 pt and lines are sized in points at it, and PNGs
    /// record it (default: the width over 6 inches, 150 dpi at 900 px). E.g. --width 1050 --dpi
    /// 300 for a 3.5-inch column.
    #[arg(long, value_name = "N")]
    dpi: Option<f64>,
    /// Shade where the fraunhofer_valid column is false (SI eq. S15); lines are dashed there.
    #[arg(long)]
    shade_invalid: bool,
    /// A vertical line at X with an optional legend label, e.g. --mark-x "2.5=F/2.5" (repeatable;
    /// marks with the same label share one legend entry).
    #[arg(long, value_name = "X[=LABEL]")]
    mark_x: Vec<String>,
    /// A dot at the maximum of each line, its x and y in the legend.
    #[arg(long, conflicts_with = "z")]
    mark_best: bool,
}

/// Runs `asnr plot`: reads the CSVs, checks every value, and writes the plot.
pub fn run(args: &PlotArgs) -> Result<()> {
    let figure = Figure::new(args.width, args.dpi)?;
    let marks = args.mark_x.iter().map(|m| parse_mark(m)).collect::<Result<Vec<_>>>()?;
    let inputs = args.inputs.iter().map(|i| parse_input(i)).collect::<Vec<_>>();
    // axis labels: the given text, or the column's name and unit; names (no units) in titles
    let label = |given: &Option<String>, column: &str| given.clone().unwrap_or_else(|| plot::axis_label(column));
    let name = |given: &Option<String>, column: &str| given.clone().unwrap_or_else(|| plot::quantity(column).0);
    let (x_label, y_label) = (label(&args.x_label, &args.x), label(&args.y_label, &args.y));
    let (x_name, y_name) = (name(&args.x_label, &args.x), name(&args.y_label, &args.y));
    if let Some(z) = &args.z {
        let [(path, _)] = inputs.as_slice() else {
            bail!("--z {z}: a heatmap is drawn from one CSV; got {} files", inputs.len());
        };
        let table = Table::read(path)?;
        let grid = grid(&table, &args.x, &args.y, z, args.shade_invalid)?;
        let (z_label, z_name) = (label(&args.z_label, z), name(&args.z_label, z));
        let title = args.title.clone().unwrap_or_else(|| format!("{z_name} vs {x_name} and {y_name}"));
        let ridge = format!("max {z_name} for each {x_name}");
        let labels = Labels {
            title: &title,
            x: &x_label,
            y: &y_label,
            z: &z_label,
            ridge: &ridge,
            shade: SHADE_LABEL,
            x_unit: "",
            log_y: false,
            log_x: false,
        };
        return plot::heatmap_plot("--output", &args.output, &figure, &labels, &grid, &marks);
    }
    let mut series = Vec::new();
    for (path, label) in &inputs {
        let table = Table::read(path)?;
        series.extend(lines(&table, label.as_deref(), args)?);
    }
    let title = args.title.clone().unwrap_or_else(|| format!("{y_name} vs {x_name}"));
    let x_unit = plot::quantity(&args.x).1.unwrap_or_default();
    let labels = Labels { title: &title, x: &x_label, y: &y_label, shade: SHADE_LABEL, x_unit, ..Labels::default() };
    plot::lines_plot("--output", &args.output, &figure, &labels, &series, &marks, args.mark_best)
}

/// `CSV[=LABEL]`: an existing file named with `=` is taken whole; otherwise the text after the
/// first `=` is the label.
fn parse_input(arg: &str) -> (PathBuf, Option<String>) {
    match arg.split_once('=') {
        Some((path, label)) if !Path::new(arg).is_file() => (PathBuf::from(path), Some(label.to_owned())),
        _ => (PathBuf::from(arg), None),
    }
}

/// `X[=LABEL]` of `--mark-x`.
fn parse_mark(arg: &str) -> Result<Mark> {
    let (x, label) = match arg.split_once('=') {
        Some((x, label)) => (x, Some(label.trim().to_owned()).filter(|l| !l.is_empty())),
        None => (arg, None),
    };
    let x = x
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .with_context(|| format!("--mark-x {arg}: `{}` is not a finite number; expected X or X=LABEL", x.trim()))?;
    Ok(Mark { x, label })
}

/// The file name without its extension, the default legend label.
fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned())
}

/// The largest magnitude of a plotted value: an axis pads its range by a few percent and places
/// ticks over it, which overflows near the largest double (about 1.8e308).
const AXIS_LIMIT: f64 = 1e307;

/// One CSV file: its header and its data rows, each with its line number.
struct Table {
    path: PathBuf,
    headers: Vec<String>,
    rows: Vec<(u64, Vec<String>)>,
}

impl Table {
    /// Reads `path`: a header line, then rows of the same length; `#` lines are comments.
    fn read(path: &Path) -> Result<Self> {
        let name = path.display();
        let text = std::fs::read_to_string(path).with_context(|| format!("{name}: cannot read the CSV file"))?;
        let mut reader =
            csv::ReaderBuilder::new().comment(Some(b'#')).trim(csv::Trim::All).from_reader(text.as_bytes());
        let headers: Vec<String> = reader
            .headers()
            .with_context(|| format!("{name}: cannot read the header line"))?
            .iter()
            .map(str::to_owned)
            .collect();
        // a column named twice: which one a flag means is not known (one was silently used)
        if let Some((i, twice)) = headers.iter().enumerate().find(|(i, h)| headers[..*i].contains(h)) {
            let first = headers.iter().position(|h| h == twice).unwrap_or(0);
            bail!(
                "{name}: the header names column `{twice}` twice (fields {} and {}); expected each column named once",
                first + 1,
                i + 1
            );
        }
        let mut rows = Vec::new();
        let mut lines = scene::CsvLines::new(&text, Some(b'#'));
        for record in reader.records() {
            let record = record.map_err(|e| {
                let line = lines.of(e.position()).map_or(String::new(), |l| format!(" line {l}"));
                anyhow::anyhow!("{name}{line}: {e}; expected {} comma-separated fields as in the header", headers.len())
            })?;
            let line = lines.of(record.position()).unwrap_or(0);
            rows.push((line, record.iter().map(str::to_owned).collect()));
        }
        if rows.is_empty() {
            bail!("{name}: no data rows; expected a header line and at least one row (as `asnr sweep --csv` writes)");
        }
        Ok(Self { path: path.to_owned(), headers, rows })
    }

    /// The index of column `name`, requested by `flag`.
    fn column(&self, name: &str, flag: &str) -> Result<usize> {
        self.headers.iter().position(|h| h == name).with_context(|| {
            format!(
                "{}: no column `{name}` ({flag}); the columns are: {}",
                self.path.display(),
                self.headers.join(", ")
            )
        })
    }

    /// Column `name` as finite numbers whose magnitude an axis can span: at most
    /// [`AXIS_LIMIT`] (an axis's margin beyond values near the largest double overflows).
    fn numbers(&self, name: &str, flag: &str) -> Result<Vec<f64>> {
        let values = self.finite(name, flag)?;
        if flag != "--group"
            && let Some((k, v)) = values.iter().enumerate().find(|(_, v)| v.abs() > AXIS_LIMIT)
        {
            bail!(
                "{} line {}, column `{name}` ({flag}): {v:e} is beyond what an axis can span with its margin; expected values of magnitude at most {AXIS_LIMIT:e} (the largest number is about 1.8e308)",
                self.path.display(),
                self.rows[k].0
            );
        }
        Ok(values)
    }

    /// Column `name` as finite numbers.
    fn finite(&self, name: &str, flag: &str) -> Result<Vec<f64>> {
        let c = self.column(name, flag)?;
        self.rows
            .iter()
            .map(|(line, row)| {
                row[c].parse::<f64>().ok().filter(|v| v.is_finite()).with_context(|| {
                    format!(
                        "{} line {line}, column `{name}`: `{}` is not a finite number; expected a number",
                        self.path.display(),
                        row[c]
                    )
                })
            })
            .collect()
    }

    /// Column `name` as `true` / `false`.
    fn flags(&self, name: &str, flag: &str) -> Result<Vec<bool>> {
        let c = self.column(name, flag)?;
        self.rows
            .iter()
            .map(|(line, row)| match row[c].as_str() {
                "true" => Ok(true),
                "false" => Ok(false),
                other => {
                    bail!("{} line {line}, column `{name}`: `{other}`; expected true or false", self.path.display())
                }
            })
            .collect()
    }

    /// The shading flags for `--shade-invalid` (true where the Fraunhofer model is not valid), or
    /// none.
    fn invalid(&self, shade: bool) -> Result<Vec<bool>> {
        if !shade {
            return Ok(vec![false; self.rows.len()]);
        }
        Ok(self.flags(VALID_COLUMN, "--shade-invalid")?.into_iter().map(|valid| !valid).collect())
    }
}

/// The lines of one CSV: one, or one per distinct value of `--group`, each sorted by x. A repeated
/// x within a line is an error (a two-key sweep needs `--group`). Legend: the file's `label` (its
/// name by default); with groups, the group label, after the file's label when one was given or
/// several files are drawn.
fn lines(table: &Table, label: Option<&str>, args: &PlotArgs) -> Result<Vec<Series>> {
    let xs = table.numbers(&args.x, "--x")?;
    let ys = table.numbers(&args.y, "--y")?;
    let invalid = table.invalid(args.shade_invalid)?;
    // group key: (value, its text for the legend) for each row
    let groups: Vec<(f64, String)> = match &args.group {
        Some(column) => {
            let values = table.numbers(column, "--group")?;
            values.into_iter().map(|v| (v, plot::number(v))).collect()
        }
        None => vec![(0.0, String::new()); xs.len()],
    };
    let mut distinct: Vec<(f64, String)> = Vec::new();
    for g in &groups {
        if !distinct.iter().any(|d| d.0 == g.0) {
            distinct.push(g.clone());
        }
    }
    distinct.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut series = Vec::new();
    for (value, text) in &distinct {
        let mut rows: Vec<usize> = (0..xs.len()).filter(|&k| groups[k].0 == *value).collect();
        rows.sort_by(|&a, &b| xs[a].total_cmp(&xs[b]));
        if let Some(w) = rows.windows(2).find(|w| xs[w[0]] == xs[w[1]]) {
            let (a, b) = (table.rows[w[0]].0, table.rows[w[1]].0);
            bail!(
                "{}: column `{}` (--x) has the value {} twice in one line (lines {a} and {b}); expected each x \
                 once per line, or --group COLUMN to draw one line per value of another column",
                table.path.display(),
                args.x,
                xs[w[0]],
            );
        }
        let file = label.map_or_else(|| stem(&table.path), str::to_owned);
        let name = match &args.group {
            None => file,
            Some(column) => {
                let template = args.group_label.clone().unwrap_or_else(|| match plot::quantity(column) {
                    (name, Some(unit)) => format!("{name} = {{}} {unit}"),
                    (name, None) => format!("{name} = {{}}"),
                });
                let group = template.replace("{}", text);
                if label.is_some() || args.inputs.len() > 1 { format!("{file}, {group}") } else { group }
            }
        };
        series.push(Series {
            label: name,
            points: rows.iter().map(|&k| (xs[k], ys[k])).collect(),
            shaded: rows.iter().map(|&k| invalid[k]).collect(),
            best: None,
        });
    }
    Ok(series)
}

/// The complete grid `z(x, y)` of one CSV for a heatmap: every pair of distinct x and y values
/// exactly once.
fn grid(table: &Table, x: &str, y: &str, z: &str, shade: bool) -> Result<Grid> {
    let (xv, yv, zv) = (table.numbers(x, "--x")?, table.numbers(y, "--y")?, table.numbers(z, "--z")?);
    let invalid = table.invalid(shade)?;
    let distinct = |values: &[f64]| {
        let mut d = values.to_vec();
        d.sort_by(f64::total_cmp);
        d.dedup();
        d
    };
    let (xs, ys) = (distinct(&xv), distinct(&yv));
    let ny = ys.len();
    let mut cells: Vec<Option<usize>> = vec![None; xs.len() * ny];
    for k in 0..xv.len() {
        // both values come from the sorted, deduplicated axes, so the searches succeed
        let (Ok(i), Ok(j)) =
            (xs.binary_search_by(|v| v.total_cmp(&xv[k])), ys.binary_search_by(|v| v.total_cmp(&yv[k])))
        else {
            continue;
        };
        if let Some(first) = cells[i * ny + j] {
            bail!(
                "{}: {x} = {}, {y} = {} appears twice (lines {} and {}); a heatmap needs each pair once",
                table.path.display(),
                xv[k],
                yv[k],
                table.rows[first].0,
                table.rows[k].0
            );
        }
        cells[i * ny + j] = Some(k);
    }
    if let Some(missing) = cells.iter().position(Option::is_none) {
        bail!(
            "{}: the grid of {x} × {y} is incomplete: no row for {x} = {}, {y} = {}; a heatmap needs every \
             pair of the {} × {} distinct values (as `asnr sweep --over {x}=… --over {y}=… --csv` writes)",
            table.path.display(),
            xs[missing / ny],
            ys[missing % ny],
            xs.len(),
            ny
        );
    }
    let rows: Vec<usize> = cells.into_iter().flatten().collect();
    Ok(Grid { z: rows.iter().map(|&k| zv[k]).collect(), shaded: rows.iter().map(|&k| invalid[k]).collect(), xs, ys })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marks_and_inputs_parse() {
        assert_eq!(parse_mark("2.5=F/2.5").unwrap(), Mark { x: 2.5, label: Some("F/2.5".to_owned()) });
        assert_eq!(parse_mark("40").unwrap(), Mark { x: 40.0, label: None });
        let err = parse_mark("abc=x").unwrap_err().to_string();
        assert!(err.contains("--mark-x abc=x: `abc` is not a finite number"), "{err}");
        assert_eq!(parse_input("a.csv=theory"), (PathBuf::from("a.csv"), Some("theory".to_owned())));
        assert_eq!(parse_input("a.csv"), (PathBuf::from("a.csv"), None));
    }
}
