//! `asnr merge`: the CSVs of `asnr sweep --shard I/N` joined into the single-process CSV.
//!
//! Each shard's rows carry the point's index in the whole sweep (first column, `index`), in the
//! order they finished. The merge checks that the files have the same header, that no index is
//! given twice and none is missing (0 … the largest, or 0 … `--expect` − 1), sorts the rows by
//! index and writes them without the index column. The fields are copied as read (the numbers
//! are not parsed and re-printed), and quoted as `asnr sweep --csv` quotes them, so the result is
//! the single-process CSV byte for byte.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};

use scene::sweep::{INDEX_COLUMN, csv_line};

// Arguments of `asnr merge`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct MergeArgs {
    /// The shards' CSV files (`asnr sweep --shard I/N --csv > shard-I.csv`), in any order.
    #[arg(required = true, value_name = "SHARD.csv")]
    pub files: Vec<PathBuf>,
    /// Write the merged CSV to this file instead of standard output.
    #[arg(long, short, value_name = "FILE.csv")]
    pub output: Option<PathBuf>,
    /// The number of points the whole sweep has: the merge then also refuses missing points at
    /// the end (without it, it checks that the indices run from 0 to the largest without a gap).
    #[arg(long, value_name = "N")]
    pub expect: Option<usize>,
}

/// Runs `asnr merge`.
pub fn run(args: &MergeArgs) -> Result<()> {
    let merged = merge(&args.files, args.expect)?;
    match &args.output {
        Some(path) => std::fs::write(path, merged).with_context(|| format!("cannot write {}", path.display()))?,
        None => {
            use std::io::Write as _;
            let mut out = std::io::stdout().lock();
            if let Err(e) = out.write_all(merged.as_bytes()).and_then(|()| out.flush()) {
                // `asnr merge … | head` closes the pipe: not an error of the merge
                if e.kind() != std::io::ErrorKind::BrokenPipe {
                    return Err(e.into());
                }
            }
        }
    }
    Ok(())
}

/// The merged CSV of the shard files `files`.
pub fn merge(files: &[PathBuf], expect: Option<usize>) -> Result<String> {
    let mut header: Option<(Vec<String>, String)> = None;
    // (index, the row's fields after the index, the file and line it came from)
    let mut rows: Vec<(usize, Vec<String>, usize, u64)> = Vec::new();
    for (f, path) in files.iter().enumerate() {
        let shown = path.display();
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read the shard {shown}"))?;
        let mut reader = csv::ReaderBuilder::new().has_headers(true).from_reader(text.as_bytes());
        let mut lines = scene::CsvLines::new(&text, None);
        let names: Vec<String> = reader
            .headers()
            .with_context(|| format!("{shown}: cannot read its header"))?
            .iter()
            .map(str::to_owned)
            .collect();
        if names.first().map(String::as_str) != Some(INDEX_COLUMN) {
            bail!(
                "{shown}: the header starts with `{}`: expected `{INDEX_COLUMN}`, the first column `asnr sweep --shard I/N` writes",
                names.first().map_or("", String::as_str)
            );
        }
        match &header {
            None => header = Some((names, shown.to_string())),
            Some((first, first_file)) if *first != names => bail!(
                "{shown}: its header `{}` differs from {first_file}'s `{}`: expected shards of one sweep",
                names.join(","),
                first.join(",")
            ),
            Some(_) => {}
        }
        for record in reader.records() {
            let record = record.with_context(|| format!("{shown}: a malformed row"))?;
            let line = lines.of(record.position()).unwrap_or(0);
            let index: usize = record[0].parse().ok().with_context(|| {
                format!("{shown}: line {line}: index `{}`: expected a whole number ≥ 0", &record[0])
            })?;
            rows.push((index, record.iter().skip(1).map(str::to_owned).collect(), f, line));
        }
    }
    let Some((names, _)) = header else { bail!("no shard files given") };
    rows.sort_by_key(|r| r.0);
    for pair in rows.windows(2) {
        if pair[0].0 == pair[1].0 {
            bail!(
                "index {} is in {} (line {}) and in {} (line {}): expected each point once (shards of one sweep, each file given once)",
                pair[0].0,
                files[pair[0].2].display(),
                pair[0].3,
                files[pair[1].2].display(),
                pair[1].3
            );
        }
    }
    let total = expect.unwrap_or_else(|| rows.last().map_or(0, |r| r.0 + 1));
    // counted from the sorted, distinct rows: time and memory follow the rows, never `total`
    let inside = rows.partition_point(|r| r.0 < total);
    let beyond = rows.len() - inside;
    let missing_count = total - inside;
    if missing_count > 0 || beyond > 0 {
        // the first 8 missing indices, from the gaps between the rows
        let mut first_missing = Vec::new();
        let mut next = 0;
        for r in rows[..inside].iter().chain(std::iter::once(&(total, Vec::new(), 0, 0))) {
            while next < r.0 && first_missing.len() < 8 {
                first_missing.push(next.to_string());
                next += 1;
            }
            if first_missing.len() == 8 {
                break;
            }
            next = r.0 + 1;
        }
        let beyond_text = format!(
            "{beyond} row(s) with an index ≥ {total} (the largest {}), beyond the {total} points{}",
            rows.last().map_or(0, |r| r.0),
            if expect.is_some() { " --expect gives" } else { "" }
        );
        // the files merged, as the message's subject
        let mut names: Vec<String> = files.iter().take(4).map(|f| f.display().to_string()).collect();
        if files.len() > 4 {
            names.push(format!("… ({} files)", files.len()));
        }
        let names = names.join(", ");
        if missing_count == 0 {
            bail!("{names}: {beyond_text}: expected the shards of one sweep of {total} points");
        }
        bail!(
            "{names}: {missing_count} of the {total} points missing (indices {}{}){}: expected every shard of the sweep, complete",
            first_missing.join(", "),
            if missing_count > first_missing.len() { ", …" } else { "" },
            if beyond > 0 { format!(", and {beyond_text}") } else { String::new() }
        );
    }
    let mut out = csv_line(names.iter().skip(1));
    for (_, fields, _, _) in &rows {
        out.push_str(&csv_line(fields));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shard(name: &str, text: &str) -> PathBuf {
        let path = std::env::temp_dir().join(format!("asnr-merge-{}-{name}.csv", std::process::id()));
        std::fs::write(&path, text).unwrap();
        path
    }

    /// A huge `--expect` or index is counted from the rows, not enumerated (the merge used to
    /// list 0 … N − 1: 1e14 indices), and the message does not contradict itself.
    #[test]
    fn huge_expect_and_index_are_counted_not_enumerated() {
        let file = shard("huge", "index,a\n0,x\n2,y\n100000000000,z\n");
        let e = merge(std::slice::from_ref(&file), Some(100_000_000_000_000)).unwrap_err().to_string();
        assert!(
            e.contains("99999999999997 of the 100000000000000 points missing (indices 1, 3, 4, 5, 6, 7, 8, 9, …)"),
            "{e}"
        );
        let e = merge(std::slice::from_ref(&file), None).unwrap_err().to_string();
        assert!(e.contains("99999999998 of the 100000000001 points missing (indices 1, 3, 4"), "{e}");
        // every point present but some beyond --expect: no "0 of … missing"
        let file = shard("beyond", "index,a\n0,x\n1,y\n2,z\n");
        let e = merge(std::slice::from_ref(&file), Some(2)).unwrap_err().to_string();
        assert!(!e.contains("missing") && e.contains("1 row(s) with an index ≥ 2 (the largest 2)"), "{e}");
        let e = merge(std::slice::from_ref(&file), Some(5)).unwrap_err().to_string();
        assert!(e.contains("2 of the 5 points missing (indices 3, 4)"), "{e}");
        assert_eq!(merge(std::slice::from_ref(&file), Some(3)).unwrap(), "a\nx\ny\nz\n");
    }
}
