//! The crate's error and warning types, and how user input is echoed in messages.

use std::fmt;

/// A scene that cannot be read or built.
///
/// `Display` is the whole message for the user, cause included (so `source()` is empty and a
/// chain printer does not repeat it): it names the file (or `file (--set k=v)`), the dotted key,
/// the value and what is accepted, `<origin>: <key> = <value>: expected <accepted>`. Every value
/// or line echoed from the input is shortened to about [`SHOWN`] characters.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file (the scene or a CSV table) that cannot be read.
    #[error("cannot read the {what} {path}: {cause}")]
    Read {
        /// "scene file" or "CSV file".
        what: &'static str,
        /// The path as given (a table's path resolved against the scene file's folder).
        path: String,
        /// Why.
        cause: std::io::Error,
    },
    /// A file longer than [`MAX_FILE_BYTES`](crate::MAX_FILE_BYTES), refused unread.
    #[error("{path}: more than {} MiB: expected a {what} (a scene is a few kB, a table at most a few MB)", limit >> 20)]
    TooLarge {
        /// "scene file" or "CSV file".
        what: &'static str,
        /// The path.
        path: String,
        /// The limit, bytes.
        limit: u64,
    },
    /// A file that is not UTF-8 text (binary data, another encoding).
    #[error(
        "{path}: not a text file (a NUL or non-UTF-8 byte at byte {offset} of {len}): expected a {what} in UTF-8 text"
    )]
    NotText {
        /// "scene file" or "CSV file".
        what: &'static str,
        /// The path.
        path: String,
        /// Byte offset of the first offending byte.
        offset: usize,
        /// The file's length in bytes.
        len: usize,
    },
    /// A scene file without any content.
    #[error("{origin}: the scene file is empty: expected TOML tables [lens], [source], [camera], [exposure]")]
    Empty {
        /// The scene file.
        origin: String,
    },
    /// A scene file that is not valid TOML.
    #[error("{origin}: malformed TOML at line {line}, column {column}: {message}: {excerpt}")]
    Toml {
        /// The scene file.
        origin: String,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column (characters) of the error.
        column: usize,
        /// The parser's message.
        message: String,
        /// The offending line, shortened around the column.
        excerpt: String,
    },
    /// A `--set` that is not `key=value` with a dotted key.
    #[error("--set {arg}: {problem}")]
    Override {
        /// The override as given (shortened).
        arg: String,
        /// What is wrong and what is accepted.
        problem: String,
    },
    /// A value outside what the key accepts.
    #[error("{origin}: {key} = {value}: expected {expected}")]
    Value {
        /// The file, or `file (--set k=v)`.
        origin: String,
        /// The dotted key.
        key: String,
        /// The value as given (shortened; strings quoted).
        value: String,
        /// What is accepted, with units.
        expected: String,
    },
    /// A key the scene needs and does not give.
    #[error("{origin}: {key} is missing: expected {expected}")]
    Missing {
        /// The file, or `file (--set k=v)`.
        origin: String,
        /// The dotted key.
        key: String,
        /// What is accepted, with units.
        expected: String,
    },
    /// A key given where it has no meaning (e.g. `source.temperature_k` with a flat source).
    #[error("{origin}: {key} does not apply to {context}")]
    NotApplicable {
        /// The file, or `file (--set k=v)`.
        origin: String,
        /// The dotted key.
        key: String,
        /// The key that rules it out, e.g. `source.kind = "flat"`.
        context: String,
    },
    /// Keys that cannot be given together, or one that needs another.
    #[error("{origin}: {message}")]
    Conflict {
        /// The file, or `file (--set k=v)`.
        origin: String,
        /// What conflicts and what to do.
        message: String,
    },
    /// A key the scene format does not know, a value of the wrong type, a missing table.
    #[error("{origin}: {key}: {message}")]
    Schema {
        /// The file, or `file (--set k=v)`.
        origin: String,
        /// The dotted key (`fields[1].x_deg` for list entries).
        key: String,
        /// What is wrong and what is accepted.
        message: String,
    },
    /// A bad row or shape of a CSV table.
    #[error("{file}: {}{message}", line.map(|l| format!("line {l}: ")).unwrap_or_default())]
    Csv {
        /// The table's path.
        file: String,
        /// 1-based line, when the problem has one.
        line: Option<u64>,
        /// What is wrong and what is accepted.
        message: String,
    },
    /// A Zemax OpticStudio `.zmx` file that does not hold a lens the scene can take.
    #[error("{file}: {}{message}", line.map(|l| format!("line {l}: ")).unwrap_or_default())]
    Zemax {
        /// The file's path.
        file: String,
        /// 1-based line, when the problem has one.
        line: Option<usize>,
        /// What is wrong (the surface number and TYPE) and what is accepted.
        message: String,
    },
    /// A CSV table named by a key that cannot be used.
    #[error("{origin}: {key} = \"{file}\": {cause}")]
    Table {
        /// The scene file, or `file (--set k=v)`.
        origin: String,
        /// The dotted key that names the table.
        key: String,
        /// The table's path as given in the scene.
        file: String,
        /// Why ([`Error::Read`], [`Error::NotText`], [`Error::Csv`], …).
        cause: Box<Error>,
    },
    /// A library constructor refused values that each passed the scene's own checks (e.g. an
    /// efficiency above the transmission at some wavelength).
    #[error("{origin}: {}{cause}", context.as_ref().map(|c| format!("{c}: ")).unwrap_or_default())]
    Domain {
        /// The file, or `file (--set k=v)`.
        origin: String,
        /// The keys or table involved, e.g. `[lens]`.
        context: Option<String>,
        /// The constructor's error.
        cause: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A scene that could not be built although every value was valid on its own, and that
    /// has values which look like a unit slip: the likely cause is named with the error (a
    /// quantum-efficiency table typed in µm detects no light at all).
    #[error("{error}; note, values that look like a unit slip: {}", warnings.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))]
    WithWarnings {
        /// The error.
        error: Box<Error>,
        /// The plausibility warnings of the scene.
        warnings: Vec<Warning>,
    },
}

/// A value that is valid but almost surely a unit slip (e.g. a pixel pitch of 0.0052 µm typed
/// in mm). Displayed as `<origin>: <key> = <value>: <hint>`; front ends print it as a warning.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Warning {
    /// The file, or `file (--set k=v)`.
    pub origin: String,
    /// The dotted key.
    pub key: String,
    /// The value as given (a number, or a CSV table's path in quotes).
    pub value: String,
    /// Why it looks wrong and the likely unit, e.g. `looks like mm (5.2 µm?)`.
    pub hint: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {} = {}: {}", self.origin, self.key, self.value, self.hint)
    }
}

/// At most this many characters of any value or line from the input appear in a message.
pub const SHOWN: usize = 80;

/// `text` as echoed in a message: at most [`SHOWN`] characters, then `… (N bytes)`; control
/// characters escaped so that a message stays on its line.
pub(crate) fn shorten(text: &str) -> String {
    let mut out = String::new();
    for (count, c) in text.chars().enumerate() {
        if count == SHOWN {
            out.push_str(&format!("… ({} bytes)", text.len()));
            return out;
        }
        if c.is_control() {
            out.extend(c.escape_debug());
        } else {
            out.push(c);
        }
    }
    out
}

/// A string value as echoed in a message: shortened and in double quotes.
pub(crate) fn quoted(text: &str) -> String {
    format!("\"{}\"", shorten(text))
}

/// A number as echoed in a message: as typed for ordinary magnitudes (`2.5`, `-2`, `NaN`,
/// `inf`), in exponent form outside 1e-5 ≤ |v| < 1e16 (never 300 digits for 1e300).
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if !v.is_finite() || a == 0.0 || (1e-5..1e16).contains(&a) { format!("{v}") } else { format!("{v:e}") }
}

/// A message from a parser with every `…` or "…" quoted span shortened, and the whole capped.
pub(crate) fn shorten_quoted(message: &str) -> String {
    let suggested = did_you_mean(message);
    let mut out = String::new();
    let mut rest = suggested.as_deref().unwrap_or(message);
    while let Some(start) = rest.find(['`', '"']) {
        let quote = rest[start..].chars().next().unwrap_or('`');
        let after = &rest[start + 1..];
        let Some(len) = after.find(quote) else { break };
        out.push_str(&rest[..=start]);
        out.push_str(&shorten(&after[..len]));
        out.push(quote);
        rest = &after[len + 1..];
    }
    out.push_str(rest);
    if out.chars().count() > 12 * SHOWN {
        let head: String = out.chars().take(12 * SHOWN).collect();
        return format!("{head}… ({} bytes)", out.len());
    }
    out
}

/// serde's "unknown field `X`, expected one of `a`, `b`, …" (or "expected `a` or `b`") with the
/// accepted name nearest to X (edit distance at most a third of its length, at least 2): "unknown
/// field `X`: did you mean `a`?" instead of the whole list; `None` when nothing is near.
fn did_you_mean(message: &str) -> Option<String> {
    let start = message.find("unknown field `")?;
    let rest = &message[start + "unknown field `".len()..];
    let end = rest.find('`')?;
    let field = &rest[..end];
    let list = rest[end + 1..].strip_prefix(", expected ")?;
    let names: Vec<&str> = list.split('`').skip(1).step_by(2).collect();
    let (best, distance) = names.iter().map(|n| (*n, edit_distance(field, n))).min_by_key(|(_, d)| *d)?;
    if distance > (field.chars().count() / 3).max(2) {
        return None;
    }
    let list_end = list.rfind('`').map_or(list.len(), |i| i + 1);
    let after = &list[list_end..];
    Some(format!("{}unknown field `{field}`: did you mean `{best}`?{after}", &message[..start]))
}

/// Levenshtein distance over characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut previous = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let here = (previous + usize::from(ca != *cb)).min(row[j] + 1).min(row[j + 1] + 1);
            previous = row[j + 1];
            row[j + 1] = here;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A key typo names the nearest key instead of listing all 34 of `[lens]`; a field far from
    /// every name keeps the list.
    #[test]
    fn a_typo_gets_the_nearest_key() {
        let m = "unknown field `f_numbr`, expected one of `model`, `preset`, `f_number`, `focal_length_mm`";
        assert_eq!(shorten_quoted(m), "unknown field `f_numbr`: did you mean `f_number`?");
        let m = "lens.x: unknown field `zzzzzzzz`, expected `model` or `preset`";
        assert_eq!(shorten_quoted(m), m);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }

    #[test]
    fn long_input_is_shortened_with_its_length() {
        let long = "x".repeat(30_000_000);
        let s = shorten(&long);
        assert!(s.len() < 120 && s.ends_with("… (30000000 bytes)"), "{s}");
        assert_eq!(shorten("800nm"), "800nm");
        assert_eq!(shorten("a\nb"), "a\\nb");
        let m = shorten_quoted(&format!("unknown field `{long}`, expected `x`"));
        assert!(m.len() < 200 && m.ends_with("bytes)`, expected `x`"), "{m}");
    }

    #[test]
    fn numbers_print_as_typed_or_in_exponent_form() {
        assert_eq!(num(-2.0), "-2");
        assert_eq!(num(0.0052), "0.0052");
        assert_eq!(num(f64::NAN), "NaN");
        assert_eq!(num(1e300), "1e300");
        assert_eq!(num(-1e-300), "-1e-300");
    }
}
