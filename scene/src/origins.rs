//! Where a scene's values came from ([`Origins`]: the file or the `--set` that gave each key)
//! and the checks every module that reads a scene shares: the messages that name the origin, the
//! key, the value and what is accepted, the plausibility warnings, and the CSV tables a scene's
//! values name (cached per source). The lowest layer of the scene reader: `psf` and `lens` build
//! on it, `load` on those, `resolved` on `load` (ARCHITECTURE.md, "scene").

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use lenses::Curve;
use serde::Deserialize;
use serde::de::{self, Visitor};

use crate::error::{Error, Warning, num, quoted, shorten};
use crate::tables::{WAVELENGTH, read_pairs, sampled};

/// A scene value that is a number or the path of a two-column CSV table.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum NumberOrFile {
    Number(f64),
    File(String),
}

impl<'de> Deserialize<'de> for NumberOrFile {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = NumberOrFile;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or the path of a CSV file (wavelength_nm, value)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<NumberOrFile, E> {
                Ok(NumberOrFile::Number(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<NumberOrFile, E> {
                Ok(NumberOrFile::Number(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<NumberOrFile, E> {
                Ok(NumberOrFile::Number(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<NumberOrFile, E> {
                Ok(NumberOrFile::File(v.to_owned()))
            }
        }
        d.deserialize_any(V)
    }
}

/// Where a scene came from, and which keys `--set` overrode: every message names its origin.
/// Plausibility warnings collect here while the scene is built.
pub(crate) struct Origins {
    pub file: String,
    pub(crate) dir: PathBuf,
    pub overrides: BTreeMap<String, String>,
    pub(crate) warnings: RefCell<Vec<Warning>>,
    /// How the lens table is named in messages: `lens`, or `designs[1].lens` in a comparison file.
    pub lens: String,
    /// The preset the lens table named, and the keys it supplied (not given in the table).
    pub preset: Option<(String, Vec<String>)>,
    /// The Zemax file the lens table named, and what it supplied.
    pub zemax: Option<crate::zemax::ZemaxSource>,
    /// The steps of a radiance-meter source (SI eq. S1–S6), kept for reports.
    pub(crate) meter: RefCell<Option<radiometry::RadianceMeterSteps>>,
    /// The pupil mapping a phase or library lens on axis was imaged with (`options.pupil_mapping`),
    /// `None` for a lens the option does not apply to.
    pub(crate) mapping: std::cell::Cell<Option<crate::load::PupilMapping>>,
    /// The tables its source's scenes have read.
    pub(crate) tables: TableCache,
    /// The 2-D arrays its source was given in memory in place of `.npy` files.
    pub(crate) arrays: Arrays,
}

/// The scene keys a 2-D array may be given for in memory ([`crate::Source::with_array`]) in
/// place of a `.npy` file: the phase map, its amplitude map and the library lens's layout grid.
pub const ARRAY_KEYS: [&str; 3] = ["lens.phase_map", "lens.amplitude_map", "lens.layout_grid"];

/// One array given in memory: the text that stands for it as the key's value, its shape as given
/// and its values in C order (`[y, x]`: `values[y·nx + x]`), shared by every scene built from the
/// source.
#[derive(Clone, Debug)]
pub(crate) struct InMemory {
    pub label: String,
    pub shape: Vec<u64>,
    pub values: std::sync::Arc<Vec<f64>>,
}

/// The arrays a [`crate::Source`] was given in memory, by scene key (one of [`ARRAY_KEYS`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct Arrays(pub(crate) std::sync::Arc<BTreeMap<String, InMemory>>);

impl Arrays {
    /// The array given for `key` if the key's value is still its label (a later override that
    /// names a file takes the file).
    pub(crate) fn get(&self, key: &str, value: &str) -> Option<&InMemory> {
        self.0.get(key).filter(|a| a.label == value)
    }
}

/// The CSV tables the scenes of one [`Source`] have read, each kept while its file's size and
/// modification time are unchanged: a sweep's points read and parse each table once (a 1601-row
/// spectrometer table was read again at every point).
#[derive(Clone, Debug, Default)]
pub(crate) struct TableCache(std::sync::Arc<std::sync::Mutex<std::collections::HashMap<TableKey, CachedTable>>>);

/// A table's file, its largest accepted value (as bits) and what it holds.
type TableKey = (PathBuf, u64, String);

#[derive(Clone, Debug)]
struct CachedTable {
    /// The file's modification time and length when it was read.
    stamp: (Option<std::time::SystemTime>, u64),
    table: radiometry::Sampled,
    lo_nm: f64,
    hi_nm: f64,
}

impl TableCache {
    /// The stamp of `path` now (None when it cannot be read: then nothing is cached).
    fn stamp(path: &Path) -> Option<(Option<std::time::SystemTime>, u64)> {
        std::fs::metadata(path).ok().map(|m| (m.modified().ok(), m.len()))
    }

    fn get(&self, key: &TableKey, stamp: (Option<std::time::SystemTime>, u64)) -> Option<CachedTable> {
        let map = self.0.lock().ok()?;
        map.get(key).filter(|c| c.stamp == stamp && stamp.0.is_some()).cloned()
    }

    fn put(&self, key: TableKey, value: CachedTable) {
        if let Ok(mut map) = self.0.lock() {
            map.insert(key, value);
        }
    }
}

impl Origins {
    /// The origins of a scene read from `file` (in `dir`) with the `--set` keys `overrides`, its
    /// lens table named `lens` in messages, sharing its source's tables and in-memory arrays:
    /// no warnings, preset, Zemax file, meter steps or pupil mapping yet.
    pub(crate) fn new(
        file: String,
        dir: PathBuf,
        overrides: BTreeMap<String, String>,
        lens: String,
        tables: TableCache,
        arrays: Arrays,
    ) -> Origins {
        Origins {
            file,
            dir,
            overrides,
            warnings: RefCell::new(Vec::new()),
            lens,
            preset: None,
            zemax: None,
            meter: RefCell::new(None),
            mapping: std::cell::Cell::new(None),
            tables,
            arrays,
        }
    }

    /// The origins of one design of a comparison file: the same file and overrides, the lens
    /// table named `lens` (e.g. `designs[1].lens`), no warnings yet.
    pub(crate) fn for_lens(&self, lens: String) -> Origins {
        Origins::new(
            self.file.clone(),
            self.dir.clone(),
            self.overrides.clone(),
            lens,
            self.tables.clone(),
            self.arrays.clone(),
        )
    }

    /// The plausibility warnings collected so far (taken out).
    pub(crate) fn take_warnings(&self) -> Vec<Warning> {
        self.warnings.take()
    }

    /// `key` as messages name it: a `lens.…` key of a comparison's design is `designs[i].lens.…`.
    pub(crate) fn key(&self, key: &str) -> String {
        match key.strip_prefix("lens") {
            Some(rest) if self.lens != "lens" && (rest.is_empty() || rest.starts_with(['.', '['])) => {
                format!("{}{rest}", self.lens)
            }
            _ => key.to_owned(),
        }
    }

    /// A context such as `[lens]` or `lens.model = "x"` with the lens table named as in [`Origins::key`].
    fn context(&self, context: &str) -> String {
        if self.lens == "lens" {
            return context.to_owned();
        }
        context.replace("[lens]", &format!("[{}]", self.lens)).replace("lens.", &format!("{}.", self.lens))
    }

    /// The origin of `key`: the `--set` that gave it, else the one that gave the nearest table
    /// above it, else those that gave keys below it (all of them), else the file.
    pub(crate) fn of(&self, key: &str) -> String {
        let key = &self.key(key);
        let below = |a: &str, b: &str| a.starts_with(&format!("{b}.")) || a.starts_with(&format!("{b}["));
        let exact = self.overrides.iter().find(|(k, _)| *k == key).map(|(_, arg)| vec![arg]);
        let above = || {
            self.overrides.iter().filter(|(k, _)| below(key, k)).max_by_key(|(k, _)| k.len()).map(|(_, arg)| vec![arg])
        };
        let inside = self.overrides.iter().filter(|(k, _)| below(k, key)).map(|(_, arg)| arg).collect::<Vec<_>>();
        match exact.or_else(above).unwrap_or(inside) {
            args if args.is_empty() => self.file.clone(),
            args => {
                let sets: Vec<String> = args.iter().map(|a| format!("--set {}", shorten(a))).collect();
                format!("{} ({})", self.file, sets.join(", "))
            }
        }
    }

    pub(crate) fn bad(&self, key: &str, value: impl fmt::Display, expected: &str) -> Error {
        Error::Value {
            origin: self.of(key),
            key: self.key(key),
            value: value.to_string(),
            expected: expected.to_owned(),
        }
    }

    pub(crate) fn number(&self, key: &str, value: f64, ok: bool, expected: &str) -> Result<f64, Error> {
        if value.is_finite() && ok { Ok(value) } else { Err(self.bad(key, num(value), expected)) }
    }

    pub(crate) fn require<T>(&self, key: &str, value: Option<T>, expected: &str) -> Result<T, Error> {
        value.ok_or_else(|| Error::Missing { origin: self.of(key), key: self.key(key), expected: expected.to_owned() })
    }

    pub(crate) fn forbid<T>(&self, key: &str, value: &Option<T>, context: &str) -> Result<(), Error> {
        if value.is_some() {
            return Err(Error::NotApplicable {
                origin: self.of(key),
                key: self.key(key),
                context: self.context(context),
            });
        }
        Ok(())
    }

    pub(crate) fn conflict(&self, key: &str, message: String) -> Error {
        Error::Conflict { origin: self.of(key), message: self.context(&message) }
    }

    /// A library constructor's refusal, named by the keys or table involved.
    pub(crate) fn domain(
        &self,
        key: &str,
        context: &str,
        cause: impl std::error::Error + Send + Sync + 'static,
    ) -> Error {
        let context = (!context.is_empty()).then(|| self.context(context));
        Error::Domain { origin: self.of(key), context, cause: Box::new(cause) }
    }

    pub(crate) fn warn(&self, key: &str, value: String, hint: String) {
        self.warnings.borrow_mut().push(Warning { origin: self.of(key), key: self.key(key), value, hint });
    }

    /// A CSV path as given in the scene, resolved against the scene file's folder.
    pub(crate) fn path(&self, file: &str) -> PathBuf {
        let p = Path::new(file);
        if p.is_absolute() { p.to_path_buf() } else { self.dir.join(p) }
    }

    /// `e` from reading the table `file` of `key`, in the key's context; a string that is a
    /// number with a unit or a quoted number (`"15%"`, `"0.15"`) and no such file is named as such.
    pub(crate) fn table_error(&self, key: &str, file: &str, e: Error, expected: &str) -> Error {
        if let Error::Read { cause, .. } = &e
            && cause.kind() == std::io::ErrorKind::NotFound
            && let Some(n) = number_prefix(file)
        {
            let rest = file.trim()[n.len()..].trim();
            let write = match (rest, n.parse::<f64>()) {
                ("%", Ok(v)) => format!("write {}, not {}", num(v / 100.0), quoted(file)),
                _ => format!("write {n}, not {}", quoted(file)),
            };
            return self.bad(
                key,
                quoted(file),
                &format!("{expected} ({write}), or the path of a CSV file (none is there)"),
            );
        }
        Error::Table { origin: self.of(key), key: self.key(key), file: shorten(file), cause: Box::new(e) }
    }

    /// The CSV table `file` given for `key`, values in `[0, hi]`.
    pub(crate) fn table(
        &self,
        key: &str,
        file: &str,
        hi: f64,
        what: &str,
        expected: &str,
    ) -> Result<radiometry::Sampled, Error> {
        let path = self.path(file);
        let cache_key = (path.clone(), hi.to_bits(), what.to_owned());
        let stamp = TableCache::stamp(&path);
        let (table, lo_nm, hi_nm) = match stamp.and_then(|s| self.tables.get(&cache_key, s)) {
            Some(c) => (c.table, c.lo_nm, c.hi_nm),
            None => {
                let read = read_pairs(&path, &WAVELENGTH, 0.0, hi, what).and_then(|(nm, values)| {
                    let (lo_nm, hi_nm) = (nm[0], nm[nm.len() - 1]);
                    sampled(&path, &nm, values).map(|t| (t, lo_nm, hi_nm))
                });
                let (table, lo_nm, hi_nm) = read.map_err(|e| self.table_error(key, file, e, expected))?;
                if let Some(stamp) = stamp {
                    self.tables.put(cache_key, CachedTable { stamp, table: table.clone(), lo_nm, hi_nm });
                }
                (table, lo_nm, hi_nm)
            }
        };
        if hi_nm < WAVELENGTH_PLAUSIBLE_NM.0 || lo_nm > WAVELENGTH_PLAUSIBLE_NM.1 {
            let (unit, factor) = wavelength_slip(hi_nm);
            self.warn(
                key,
                quoted(file),
                format!(
                    "its wavelengths {}–{} nm are all outside {}–{} nm: looks like {unit} ({}–{} nm?)",
                    num(lo_nm),
                    num(hi_nm),
                    WAVELENGTH_PLAUSIBLE_NM.0,
                    WAVELENGTH_PLAUSIBLE_NM.1,
                    rounded(lo_nm * factor),
                    rounded(hi_nm * factor)
                ),
            );
        }
        Ok(table)
    }

    /// A fraction in `[0, 1]`, constant or tabulated.
    pub(crate) fn curve(&self, key: &str, value: &NumberOrFile, what: &str) -> Result<Curve, Error> {
        let expected = "a fraction in [0, 1] or a CSV path";
        Ok(match value {
            NumberOrFile::Number(v) => Curve::Constant(self.number(key, *v, (0.0..=1.0).contains(v), expected)?),
            NumberOrFile::File(f) => Curve::Table(self.table(key, f, 1.0, what, "a fraction in [0, 1]")?),
        })
    }

    /// Warns about a wavelength in nm outside [`WAVELENGTH_PLAUSIBLE_NM`].
    pub(crate) fn wavelength(&self, key: &str, nm: f64) {
        let (lo, hi) = WAVELENGTH_PLAUSIBLE_NM;
        if nm < lo || nm > hi {
            let (unit, factor) = wavelength_slip(nm);
            let side = if nm < lo { format!("below {lo} nm") } else { format!("above {hi} nm") };
            self.warn(key, num(nm), format!("{side}: looks like {unit} ({} nm?)", rounded(nm * factor)));
        }
    }
}

/// Plausible wavelengths, nm: from the far ultraviolet to the thermal infrared. A scene value
/// outside is valid but almost surely in µm or m (below) or pm/Å (above), and warned about.
pub const WAVELENGTH_PLAUSIBLE_NM: (f64, f64) = (100.0, 20000.0);
/// Plausible pixel pitches, µm (below: mm typed as µm; above: nm typed as µm).
pub const PIXEL_PITCH_PLAUSIBLE_UM: (f64, f64) = (0.1, 100.0);
/// Plausible focal lengths, mm (below: m typed as mm; above: µm typed as mm).
pub const FOCAL_LENGTH_PLAUSIBLE_MM: (f64, f64) = (0.01, 1e4);
/// Plausible exposure times, ms: 1 ns to 2.8 h (below: s typed as ms; above: µs typed as ms).
pub const EXPOSURE_PLAUSIBLE_MS: (f64, f64) = (1e-6, 1e7);

/// The unit a wavelength outside the plausible range was probably typed in, and the factor to nm.
fn wavelength_slip(nm: f64) -> (&'static str, f64) {
    if nm > WAVELENGTH_PLAUSIBLE_NM.1 {
        ("pm", 1e-3)
    } else if nm < 1e-3 {
        ("m", 1e9)
    } else {
        ("µm", 1e3)
    }
}

/// `v` to 6 significant digits, as a number is typed (`5.2`, not `5.199999999999999`).
pub(crate) fn rounded(v: f64) -> String {
    num(format!("{v:.5e}").parse::<f64>().unwrap_or(v))
}

/// The number a string starts with, as typed (`"800nm"` → `800`), if any.
pub(crate) fn number_prefix(s: &str) -> Option<&str> {
    let s = s.trim();
    let mut end = 0;
    for (i, c) in s.char_indices().take(40) {
        if !(c.is_ascii_digit() || "+-.eE".contains(c)) {
            break;
        }
        end = i + c.len_utf8();
    }
    (0..=end).rev().map(|e| &s[..e]).find(|p| p.contains(|c: char| c.is_ascii_digit()) && p.parse::<f64>().is_ok())
}

/// The unit a scene key carries in its name (`center_nm` → ` in nm`), for messages.
pub(crate) fn unit_of(key: &str) -> &'static str {
    let key = key.trim_end_matches(|c: char| c.is_ascii_digit() || c == '[' || c == ']');
    let suffixes = [
        ("_w_m2_sr_nm", " in W/(m² sr nm)"),
        ("_e_per_s", " in e⁻/s"),
        ("_dn_per_e", " in DN/e⁻"),
        ("_nw", " in nW"),
        ("_nm", " in nm"),
        ("_um", " in µm"),
        ("_mm", " in mm"),
        ("_ms", " in ms"),
        ("_deg", " in degrees"),
        ("_k", " in K"),
        ("_e", " in e⁻"),
        ("_bits", " of bits"),
    ];
    suffixes.iter().find(|(s, _)| key.ends_with(s)).map_or("", |(_, u)| u)
}
