//! GDSII meta-atom layouts (`.gds`, `.gds.gz`) → a 2-D grid of atom parameters on a square
//! lattice, for the 2-D library lens (docs/physics.md, "GDSII layouts").
//!
//! A streaming reader of the records it needs (ARCHITECTURE.md says why not a crate): each
//! record's 4-byte header (length, type, data type) and body are read into one reused buffer
//! from any [`Read`] (a file, or a gzip stream decoded on the fly), so no record list and no
//! whole file is held. Each cell (structure) keeps only its atoms on the chosen layer and
//! datatype, already reduced to a centre and a size (a pillar's diameter, a fin's width, length
//! and angle), and its references (SREF, AREF); other elements are skipped. The top cell is then
//! expanded through its references, each transform (reflection about x, magnification, rotation,
//! translation; GDSII's order) applied to the reduced atoms, and the atoms matched to the
//! lattice sites. Every size is checked before anything is allocated from it: an AREF's
//! instances and the expanded atom count (with the nesting) against `max_atoms`, the grid's
//! sites against `max_sites`.
//!
//! Anything it cannot interpret is refused naming the record and its byte offset: a truncated
//! file, a record whose length runs past the end or is odd or below 4, a record out of place, an
//! open or self-intersecting polygon, a fin that is not a rectangle, a reference to a missing cell
//! or a cycle, absolute magnification or angle, a layer with no atoms.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// An error of a GDSII file: the byte offset of the record, when the problem has one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{message}", offset.map(|o| format!("byte {o}: ")).unwrap_or_default())]
pub struct GdsError {
    /// The byte offset of the record's header in the (decompressed) stream.
    pub offset: Option<u64>,
    /// What is wrong, naming the record, and what is accepted.
    pub message: String,
}

fn err<T>(offset: u64, message: String) -> Result<T, GdsError> {
    Err(GdsError { offset: Some(offset), message })
}

/// What each layout element on the atom layer is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AtomKind {
    /// A closed polygon (a pillar drawn as a regular polygon): its diameter from its area,
    /// corrected for the vertex count (vertices on the circle).
    Pillar,
    /// A rectangle: width (shorter side), length (longer side), angle θ of the longer side from
    /// +x in [0°, 180°).
    Fin,
}

/// How to read a layout.
#[derive(Clone, Debug)]
pub struct GdsOptions {
    /// The cell to expand (default: the single top cell).
    pub cell: Option<String>,
    /// The atoms' layer and datatype.
    pub layer: i16,
    /// The atoms' datatype.
    pub datatype: i16,
    /// The lattice pitch, m.
    pub pitch_m: f64,
    /// Pillars or fins.
    pub atom: AtomKind,
    /// The most atoms the expanded layout may hold (refused before expanding beyond it).
    pub max_atoms: u64,
    /// The most lattice sites the grid may hold (refused before allocating beyond it).
    pub max_sites: u64,
}

pub use lenses::{AtomGrid, LayoutStats};

/// `n`-gon with its vertices on a circle of diameter D has the area `(n/8) D² sin(2π/n)`: the
/// diameter of a polygon of area `A` and `n` vertices (docs/physics.md, "GDSII layouts").
pub fn polygon_diameter(area: f64, vertices: usize) -> f64 {
    let n = vertices as f64;
    (8.0 * area / (n * (std::f64::consts::TAU / n).sin())).sqrt()
}

// ---- records ----

const HEADER: u8 = 0x00;
const BGNLIB: u8 = 0x01;
const LIBNAME: u8 = 0x02;
const UNITS: u8 = 0x03;
const ENDLIB: u8 = 0x04;
const BGNSTR: u8 = 0x05;
const STRNAME: u8 = 0x06;
const ENDSTR: u8 = 0x07;
const BOUNDARY: u8 = 0x08;
const PATH: u8 = 0x09;
const SREF: u8 = 0x0A;
const AREF: u8 = 0x0B;
const TEXT: u8 = 0x0C;
const LAYER: u8 = 0x0D;
const DATATYPE: u8 = 0x0E;
const XY: u8 = 0x10;
const ENDEL: u8 = 0x11;
const SNAME: u8 = 0x12;
const COLROW: u8 = 0x13;
const NODE: u8 = 0x15;
const STRANS: u8 = 0x1A;
const MAG: u8 = 0x1B;
const ANGLE: u8 = 0x1C;
const BOX: u8 = 0x2D;

/// A record's name for messages.
fn name(kind: u8) -> String {
    let names = [
        "HEADER",
        "BGNLIB",
        "LIBNAME",
        "UNITS",
        "ENDLIB",
        "BGNSTR",
        "STRNAME",
        "ENDSTR",
        "BOUNDARY",
        "PATH",
        "SREF",
        "AREF",
        "TEXT",
        "LAYER",
        "DATATYPE",
        "WIDTH",
        "XY",
        "ENDEL",
        "SNAME",
        "COLROW",
        "TEXTNODE",
        "NODE",
        "TEXTTYPE",
        "PRESENTATION",
        "SPACING",
        "STRING",
        "STRANS",
        "MAG",
        "ANGLE",
        "UINTEGER",
        "USTRING",
        "REFLIBS",
        "FONTS",
        "PATHTYPE",
        "GENERATIONS",
        "ATTRTABLE",
        "STYPTABLE",
        "STRTYPE",
        "ELFLAGS",
        "ELKEY",
        "LINKTYPE",
        "LINKKEYS",
        "NODETYPE",
        "PROPATTR",
        "PROPVALUE",
        "BOX",
        "BOXTYPE",
        "PLEX",
    ];
    names.get(kind as usize).map_or_else(|| format!("record type {kind:#04x}"), |n| (*n).to_owned())
}

/// The records of a stream, one at a time into a reused buffer.
struct Records<R> {
    input: R,
    offset: u64,
    body: Vec<u8>,
    count: u64,
}

/// One record: its type, data type, and the offset of its header.
#[derive(Clone, Copy)]
struct Head {
    kind: u8,
    data: u8,
    offset: u64,
}

impl<R: Read> Records<R> {
    /// The next record (its body in `self.body`); `None` at the end of the stream.
    fn next(&mut self) -> Result<Option<Head>, GdsError> {
        let mut header = [0u8; 4];
        let mut got = 0;
        while got < 4 {
            match self.input.read(&mut header[got..]) {
                Ok(0) => break,
                Ok(n) => got += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return err(self.offset, format!("cannot read: {e}")),
            }
        }
        if got == 0 {
            return Ok(None);
        }
        let offset = self.offset;
        if got < 4 {
            return err(offset, format!("the file ends inside a record header ({got} of 4 bytes): truncated"));
        }
        let length = u16::from_be_bytes([header[0], header[1]]) as usize;
        let (kind, data) = (header[2], header[3]);
        if length == 0 && kind == 0 && data == 0 {
            // NUL padding after ENDLIB (tape blocks)
            return Ok(None);
        }
        if length < 4 || !length.is_multiple_of(2) {
            return err(
                offset,
                format!("{} declares {length} bytes: expected an even length ≥ 4 (header included)", name(kind)),
            );
        }
        self.body.clear();
        let body = length - 4;
        let read = (&mut self.input).take(body as u64).read_to_end(&mut self.body);
        match read {
            Ok(n) if n == body => {}
            Ok(n) => {
                return err(
                    offset,
                    format!(
                        "{} declares {length} bytes, but the file ends {} bytes after it: truncated",
                        name(kind),
                        n + 4
                    ),
                );
            }
            Err(e) => return err(offset, format!("cannot read {}: {e}", name(kind))),
        }
        self.offset += length as u64;
        self.count += 1;
        Ok(Some(Head { kind, data, offset }))
    }

    fn i16s(&self) -> impl Iterator<Item = i16> + '_ {
        self.body.chunks_exact(2).map(|c| i16::from_be_bytes([c[0], c[1]]))
    }

    fn i32s(&self) -> impl Iterator<Item = i32> + '_ {
        self.body.chunks_exact(4).map(|c| i32::from_be_bytes([c[0], c[1], c[2], c[3]]))
    }

    fn reals(&self) -> impl Iterator<Item = f64> + '_ {
        self.body.chunks_exact(8).map(|c| real8(c.try_into().unwrap_or([0; 8])))
    }

    fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).trim_end_matches('\0').to_owned()
    }

    /// The body as `n` values of `size` bytes of data type `data`, else the error naming it.
    fn expect(&self, h: Head, data: u8, size: usize, n: Option<usize>, what: &str) -> Result<(), GdsError> {
        let count_ok = n.is_none_or(|n| self.body.len() == n * size);
        if h.data != data || !count_ok || !self.body.len().is_multiple_of(size) || self.body.is_empty() {
            return err(
                h.offset,
                format!("{} of data type {} and {} body bytes: expected {what}", name(h.kind), h.data, self.body.len()),
            );
        }
        Ok(())
    }
}

/// A GDSII 8-byte real: sign, excess-64 base-16 exponent, 56-bit mantissa.
pub fn real8(b: [u8; 8]) -> f64 {
    let sign = if b[0] & 0x80 != 0 { -1.0 } else { 1.0 };
    let exponent = i32::from(b[0] & 0x7F) - 64;
    let mantissa = u64::from_be_bytes([0, b[1], b[2], b[3], b[4], b[5], b[6], b[7]]) as f64 / 2f64.powi(56);
    sign * mantissa * 16f64.powi(exponent)
}

/// `v` as a GDSII 8-byte real (for writers; exact for values a double's 53 bits hold).
pub fn to_real8(v: f64) -> [u8; 8] {
    if v == 0.0 || !v.is_finite() {
        return [0; 8];
    }
    let sign = if v < 0.0 { 0x80 } else { 0 };
    let mut m = v.abs();
    let mut e = 64i32;
    while m >= 1.0 {
        m /= 16.0;
        e += 1;
    }
    while m < 1.0 / 16.0 {
        m *= 16.0;
        e -= 1;
    }
    let mantissa = (m * 2f64.powi(56)).round() as u64;
    let bytes = mantissa.to_be_bytes();
    [sign | (e.clamp(0, 127) as u8), bytes[1], bytes[2], bytes[3], bytes[4], bytes[5], bytes[6], bytes[7]]
}

// ---- cells ----

/// An atom reduced to its centre and size (database units; a fin's angle in radians).
#[derive(Clone, Copy, Debug)]
struct Atom {
    x: f64,
    y: f64,
    /// Pillar: diameter; fin: width.
    a: f64,
    /// Fin: length.
    b: f64,
    /// Fin: the longer side's angle from +x, radians.
    theta: f64,
}

/// An SREF (one instance) or AREF (`cols × rows`).
#[derive(Clone, Debug)]
struct Reference {
    cell: String,
    offset: u64,
    reflect: bool,
    mag: f64,
    angle_deg: f64,
    origin: (f64, f64),
    cols: u32,
    rows: u32,
    col_step: (f64, f64),
    row_step: (f64, f64),
}

#[derive(Default)]
struct Cell {
    atoms: Vec<Atom>,
    refs: Vec<Reference>,
    /// A PATH or BOX on the atom layer (offset), refused if the cell is used.
    other_on_layer: Option<(u64, &'static str)>,
}

/// An affine map: `p' = M p + t`, and the size scale.
#[derive(Clone, Copy)]
struct Affine {
    m: [f64; 4],
    t: (f64, f64),
    scale: f64,
}

impl Affine {
    const IDENTITY: Affine = Affine { m: [1.0, 0.0, 0.0, 1.0], t: (0.0, 0.0), scale: 1.0 };

    fn apply(&self, x: f64, y: f64) -> (f64, f64) {
        (self.m[0] * x + self.m[1] * y + self.t.0, self.m[2] * x + self.m[3] * y + self.t.1)
    }

    /// `self ∘ (reflect about x, magnify, rotate, translate by t)`.
    fn then(&self, r: &Reference, t: (f64, f64)) -> Affine {
        let (s, c) = r.angle_deg.to_radians().sin_cos();
        let f = if r.reflect { -1.0 } else { 1.0 };
        // local: [c −s; s c] · mag · diag(1, f)
        let l = [c * r.mag, -s * r.mag * f, s * r.mag, c * r.mag * f];
        let m = [
            self.m[0] * l[0] + self.m[1] * l[2],
            self.m[0] * l[1] + self.m[1] * l[3],
            self.m[2] * l[0] + self.m[3] * l[2],
            self.m[2] * l[1] + self.m[3] * l[3],
        ];
        Affine { m, t: self.apply(t.0, t.1), scale: self.scale * r.mag }
    }
}

/// Parses the stream: each cell's reduced atoms and references, the database unit (m).
struct Library {
    cells: HashMap<String, Cell>,
    order: Vec<String>,
    unit_m: f64,
    records: u64,
    bytes: u64,
    max_deviation: f64,
}

fn parse<R: Read>(input: R, o: &GdsOptions) -> Result<Library, GdsError> {
    let mut r = Records { input, offset: 0, body: Vec::with_capacity(1 << 16), count: 0 };
    let first = r.next()?.ok_or(GdsError { offset: None, message: "an empty file: expected a GDSII stream".into() })?;
    if first.kind != HEADER {
        return err(0, format!("{}: expected HEADER, the first record of a GDSII stream", name(first.kind)));
    }
    let mut lib = Library {
        cells: HashMap::new(),
        order: Vec::new(),
        unit_m: f64::NAN,
        records: 0,
        bytes: 0,
        max_deviation: 0.0,
    };
    let mut current: Option<(String, Cell)> = None;
    let mut ended = false;
    let mut points: Vec<(f64, f64)> = Vec::new();
    while let Some(h) = r.next()? {
        if ended {
            return err(h.offset, format!("{} after ENDLIB: expected the end of the stream", name(h.kind)));
        }
        match h.kind {
            BGNLIB | LIBNAME => {}
            UNITS => {
                r.expect(h, 5, 8, Some(2), "two 8-byte reals (user and database units)")?;
                let v: Vec<f64> = r.reals().collect();
                if !(v[1] > 0.0 && v[1] < 1.0) {
                    return err(h.offset, format!("UNITS: database unit {} m: expected (0, 1) m", v[1]));
                }
                lib.unit_m = v[1];
            }
            BGNSTR => {
                if current.is_some() {
                    return err(h.offset, "BGNSTR inside a structure: expected ENDSTR first".into());
                }
                let s =
                    r.next()?.ok_or(GdsError { offset: Some(h.offset), message: "truncated after BGNSTR".into() })?;
                if s.kind != STRNAME {
                    return err(s.offset, format!("{} after BGNSTR: expected STRNAME", name(s.kind)));
                }
                let cell = r.text();
                if lib.cells.contains_key(&cell) {
                    return err(s.offset, format!("STRNAME {cell:?} defined twice"));
                }
                current = Some((cell, Cell::default()));
            }
            ENDSTR => {
                let Some((cell, c)) = current.take() else {
                    return err(h.offset, "ENDSTR outside a structure".into());
                };
                lib.order.push(cell.clone());
                lib.cells.insert(cell, c);
            }
            ENDLIB => ended = true,
            BOUNDARY | PATH | BOX | SREF | AREF | TEXT | NODE => {
                let Some((_, cell)) = current.as_mut() else {
                    return err(h.offset, format!("{} outside a structure", name(h.kind)));
                };
                element(&mut r, h, cell, o, &mut points, &mut lib.max_deviation)?;
            }
            HEADER => return err(h.offset, "a second HEADER".into()),
            _ => {} // records not needed (properties, reference libraries, fonts …)
        }
    }
    if !ended {
        return err(r.offset, "the stream ends without ENDLIB: truncated".into());
    }
    if current.is_some() {
        return err(r.offset, "ENDLIB inside a structure: expected ENDSTR first".into());
    }
    if !lib.unit_m.is_finite() {
        return Err(GdsError { offset: None, message: "no UNITS record".into() });
    }
    lib.records = r.count;
    lib.bytes = r.offset;
    Ok(lib)
}

/// One element up to its ENDEL: an atom if it is on the atom layer, a reference, or skipped.
fn element<R: Read>(
    r: &mut Records<R>,
    start: Head,
    cell: &mut Cell,
    o: &GdsOptions,
    points: &mut Vec<(f64, f64)>,
    max_deviation: &mut f64,
) -> Result<(), GdsError> {
    let (mut layer, mut datatype) = (None, None);
    let mut sname = None;
    let (mut strans, mut mag, mut angle) = (0u16, 1.0, 0.0);
    let mut colrow = None;
    points.clear();
    let mut xy_offset = start.offset;
    loop {
        let h = r.next()?.ok_or(GdsError {
            offset: Some(start.offset),
            message: format!("the file ends inside {}: truncated", name(start.kind)),
        })?;
        match h.kind {
            ENDEL => break,
            LAYER => {
                r.expect(h, 2, 2, Some(1), "one 2-byte integer")?;
                layer = r.i16s().next();
            }
            DATATYPE => {
                r.expect(h, 2, 2, Some(1), "one 2-byte integer")?;
                datatype = r.i16s().next();
            }
            SNAME => sname = Some(r.text()),
            STRANS => {
                r.expect(h, 1, 2, Some(1), "one 2-byte bit array")?;
                strans = u16::from_be_bytes([r.body[0], r.body[1]]);
                if strans & 0x0006 != 0 {
                    return err(h.offset, "STRANS with absolute magnification or angle: expected relative ones".into());
                }
            }
            MAG => {
                r.expect(h, 5, 8, Some(1), "one 8-byte real")?;
                mag = r.reals().next().unwrap_or(1.0);
                if !(mag > 0.0 && mag.is_finite() && mag < 1e6) {
                    return err(h.offset, format!("MAG {mag}: expected a magnification in (0, 1e6)"));
                }
            }
            ANGLE => {
                r.expect(h, 5, 8, Some(1), "one 8-byte real")?;
                angle = r.reals().next().unwrap_or(0.0);
                if !angle.is_finite() || angle.abs() > 1e6 {
                    return err(h.offset, format!("ANGLE {angle}: expected degrees"));
                }
            }
            COLROW => {
                r.expect(h, 2, 2, Some(2), "two 2-byte integers (columns, rows)")?;
                let v: Vec<i16> = r.i16s().collect();
                if v[0] < 1 || v[1] < 1 {
                    return err(h.offset, format!("COLROW {} × {}: expected ≥ 1 each", v[0], v[1]));
                }
                colrow = Some((v[0] as u32, v[1] as u32));
            }
            XY => {
                r.expect(h, 3, 8, None, "pairs of 4-byte integers")?;
                if points.len() + r.body.len() / 8 > 1 << 16 {
                    return err(h.offset, "XY of more than 65536 points: expected an atom or a reference".into());
                }
                xy_offset = h.offset;
                let v: Vec<i32> = r.i32s().collect();
                points.extend(v.chunks_exact(2).map(|p| (f64::from(p[0]), f64::from(p[1]))));
            }
            BOUNDARY | PATH | BOX | SREF | AREF | TEXT | NODE | BGNSTR | ENDSTR | ENDLIB => {
                return err(h.offset, format!("{} inside {}: expected ENDEL first", name(h.kind), name(start.kind)));
            }
            _ => {}
        }
    }
    let on_layer = layer == Some(o.layer) && datatype.unwrap_or(0) == o.datatype;
    match start.kind {
        BOUNDARY if on_layer => {
            let atom = reduce(points, xy_offset, o.atom, max_deviation)?;
            cell.atoms.push(atom);
        }
        PATH | BOX if on_layer => {
            cell.other_on_layer.get_or_insert((start.offset, if start.kind == PATH { "PATH" } else { "BOX" }));
        }
        SREF | AREF => {
            let what = name(start.kind);
            let Some(cell_name) = sname else { return err(start.offset, format!("{what} without SNAME")) };
            let (cols, rows) = if start.kind == AREF {
                colrow.ok_or(GdsError { offset: Some(start.offset), message: "AREF without COLROW".into() })?
            } else {
                (1, 1)
            };
            let need = if start.kind == AREF { 3 } else { 1 };
            if points.len() != need {
                return err(xy_offset, format!("{what} XY of {} points: expected {need}", points.len()));
            }
            let p = &points[..];
            let col_step = if start.kind == AREF {
                ((p[1].0 - p[0].0) / f64::from(cols), (p[1].1 - p[0].1) / f64::from(cols))
            } else {
                (0.0, 0.0)
            };
            let row_step = if start.kind == AREF {
                ((p[2].0 - p[0].0) / f64::from(rows), (p[2].1 - p[0].1) / f64::from(rows))
            } else {
                (0.0, 0.0)
            };
            cell.refs.push(Reference {
                cell: cell_name,
                offset: start.offset,
                reflect: strans & 0x8000 != 0,
                mag,
                angle_deg: angle,
                origin: p[0],
                cols,
                rows,
                col_step,
                row_step,
            });
        }
        _ => {}
    }
    Ok(())
}

/// Whether segments `a–b` and `c–d` cross or touch (exact in the integer coordinates).
fn segments_meet(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> bool {
    let orient = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        ((q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)).signum() as i32
    };
    let on = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        r.0 >= p.0.min(q.0) && r.0 <= p.0.max(q.0) && r.1 >= p.1.min(q.1) && r.1 <= p.1.max(q.1)
    };
    let (o1, o2, o3, o4) = (orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b));
    if o1 != o2 && o3 != o4 && o1 * o2 <= 0 && o3 * o4 <= 0 && (o1 != 0 || o2 != 0) {
        return true;
    }
    (o1 == 0 && on(a, b, c)) || (o2 == 0 && on(a, b, d)) || (o3 == 0 && on(c, d, a)) || (o4 == 0 && on(c, d, b))
}

/// A closed polygon (first vertex repeated last) reduced to an atom.
fn reduce(points: &[(f64, f64)], offset: u64, kind: AtomKind, max_deviation: &mut f64) -> Result<Atom, GdsError> {
    let n = points.len();
    if n < 4 || points[0] != points[n - 1] {
        return err(
            offset,
            format!(
                "BOUNDARY XY of {n} points, last ≠ first: an open polygon; expected a closed one (≥ 3 vertices, the first repeated last)"
            ),
        );
    }
    let v = &points[..n - 1];
    let m = v.len();
    // simple: no two non-adjacent edges meet, no repeated vertex
    for i in 0..m {
        for j in i + 1..m {
            let adjacent = j == i + 1 || (i == 0 && j == m - 1);
            let (a, b, c, d) = (v[i], v[(i + 1) % m], v[j], v[(j + 1) % m]);
            if v[i] == v[j] || (!adjacent && segments_meet(a, b, c, d)) {
                return err(
                    offset,
                    format!(
                        "BOUNDARY: a self-intersecting polygon (edges {i} and {j} of {m} meet): expected a simple one"
                    ),
                );
            }
        }
    }
    let (mut area2, mut cx, mut cy) = (0.0, 0.0, 0.0);
    // shoelace about the first vertex (no cancellation at large coordinates)
    let o = v[0];
    for i in 0..m {
        let (p, q) = ((v[i].0 - o.0, v[i].1 - o.1), (v[(i + 1) % m].0 - o.0, v[(i + 1) % m].1 - o.1));
        let c = p.0 * q.1 - q.0 * p.1;
        area2 += c;
        cx += (p.0 + q.0) * c;
        cy += (p.1 + q.1) * c;
    }
    if area2 == 0.0 {
        return err(offset, "BOUNDARY of zero area".into());
    }
    let (x, y) = (o.0 + cx / (3.0 * area2), o.1 + cy / (3.0 * area2));
    let area = area2.abs() / 2.0;
    match kind {
        AtomKind::Pillar => {
            let d = polygon_diameter(area, m);
            for p in v {
                let dev = ((p.0 - x).hypot(p.1 - y) / (d / 2.0) - 1.0).abs();
                *max_deviation = max_deviation.max(dev);
            }
            Ok(Atom { x, y, a: d, b: 0.0, theta: 0.0 })
        }
        AtomKind::Fin => {
            let sides: Vec<(f64, f64)> =
                (0..m).map(|i| (v[(i + 1) % m].0 - v[i].0, v[(i + 1) % m].1 - v[i].1)).collect();
            let right = m == 4
                && (0..4).all(|i| {
                    let (a, b) = (sides[i], sides[(i + 1) % 4]);
                    (a.0 * b.0 + a.1 * b.1).abs() <= 1e-3 * a.0.hypot(a.1) * b.0.hypot(b.1)
                });
            if !right {
                return err(
                    offset,
                    format!(
                        "BOUNDARY of {m} vertices: expected a fin, a rectangle (4 vertices, right angles to 0.06°)"
                    ),
                );
            }
            let (s0, s1) = (sides[0].0.hypot(sides[0].1), sides[1].0.hypot(sides[1].1));
            let (long, w, l) = if s0 >= s1 { (sides[0], s1, s0) } else { (sides[1], s0, s1) };
            Ok(Atom { x, y, a: w, b: l, theta: long.1.atan2(long.0) })
        }
    }
}

// ---- expansion ----

/// The expanded atom count of each cell (saturating; an instance of a cell without atoms counts
/// as one, so that the count bounds the expansion's work), refusing cycles and missing cells.
fn counts(lib: &Library) -> Result<HashMap<&str, u64>, GdsError> {
    let mut done: HashMap<&str, u64> = HashMap::new();
    // iterative depth-first with an explicit stack (no recursion depth from the file)
    for root in &lib.order {
        let mut stack: Vec<(&str, usize)> = vec![(root.as_str(), 0)];
        let mut on_path: Vec<&str> = vec![root.as_str()];
        while let Some((name, next)) = stack.pop() {
            if done.contains_key(name) {
                on_path.pop();
                continue;
            }
            let cell = &lib.cells[name];
            if let Some(r) = cell.refs.get(next) {
                stack.push((name, next + 1));
                let child = lib.cells.get_key_value(&r.cell).map(|(k, _)| k.as_str()).ok_or(GdsError {
                    offset: Some(r.offset),
                    message: format!("a reference to the cell {:?}, which the file does not define", r.cell),
                })?;
                if on_path.contains(&child) {
                    return err(r.offset, format!("a reference cycle: {:?} references {:?} again", name, child));
                }
                if !done.contains_key(child) {
                    stack.push((child, 0));
                    on_path.push(child);
                }
                continue;
            }
            let mut total = cell.atoms.len() as u64;
            for r in &cell.refs {
                let n = u64::from(r.cols) * u64::from(r.rows);
                // an empty cell's instance counts as one: the expansion visits it
                total = total.saturating_add(n.saturating_mul(done[r.cell.as_str()].max(1)));
            }
            done.insert(name, total);
            on_path.pop();
        }
    }
    Ok(done)
}

/// Calls `visit` with every atom of `cell` under `t` (database units; θ radians).
fn expand(lib: &Library, cell: &str, t: Affine, visit: &mut dyn FnMut(Atom)) {
    let c = &lib.cells[cell];
    for a in &c.atoms {
        let (x, y) = t.apply(a.x, a.y);
        let dir = (t.m[0] * a.theta.cos() + t.m[1] * a.theta.sin(), t.m[2] * a.theta.cos() + t.m[3] * a.theta.sin());
        visit(Atom { x, y, a: a.a * t.scale, b: a.b * t.scale, theta: dir.1.atan2(dir.0) });
    }
    for r in &c.refs {
        for row in 0..r.rows {
            for col in 0..r.cols {
                let p = (
                    r.origin.0 + f64::from(col) * r.col_step.0 + f64::from(row) * r.row_step.0,
                    r.origin.1 + f64::from(col) * r.col_step.1 + f64::from(row) * r.row_step.1,
                );
                expand(lib, &r.cell, t.then(r, p), visit);
            }
        }
    }
}

/// Reads the layout at `path` (`.gds`, or gzip-compressed: detected by its magic bytes).
pub fn read_layout(path: &Path, o: &GdsOptions) -> Result<AtomGrid, GdsError> {
    let file = std::fs::File::open(path)
        .map_err(|e| GdsError { offset: None, message: format!("cannot read {}: {e}", path.display()) })?;
    let mut input = std::io::BufReader::with_capacity(1 << 20, file);
    let gz = {
        use std::io::BufRead as _;
        let head = input.fill_buf().map_err(|e| GdsError { offset: None, message: format!("cannot read: {e}") })?;
        head.starts_with(&[0x1F, 0x8B])
    };
    if gz { layout(flate2::bufread::MultiGzDecoder::new(input), o) } else { layout(input, o) }
}

/// The layout of a GDSII stream.
pub fn layout<R: Read>(input: R, o: &GdsOptions) -> Result<AtomGrid, GdsError> {
    let general = |message: String| GdsError { offset: None, message };
    if !(o.pitch_m > 0.0 && o.pitch_m.is_finite()) {
        return Err(general(format!("lattice pitch {} m: expected > 0", o.pitch_m)));
    }
    let lib = parse(input, o)?;
    let counts = counts(&lib)?;
    let top = match &o.cell {
        Some(c) => {
            if !lib.cells.contains_key(c) {
                return Err(general(format!("gds_cell {c:?}: no such cell; the file's cells: {}", list(&lib.order))));
            }
            c.clone()
        }
        None => {
            let referenced: std::collections::HashSet<&str> =
                lib.cells.values().flat_map(|c| c.refs.iter().map(|r| r.cell.as_str())).collect();
            let tops: Vec<String> = lib.order.iter().filter(|c| !referenced.contains(c.as_str())).cloned().collect();
            match tops.as_slice() {
                [one] => one.clone(),
                [] => return Err(general("no cell (an empty library)".into())),
                _ => return Err(general(format!("several top cells ({}): give gds_cell", list(&tops)))),
            }
        }
    };
    let total = counts[top.as_str()];
    let atoms = count_atoms(&lib, &top, &counts);
    if total > o.max_atoms {
        return Err(general(format!(
            "cell {top:?} expands to {total} atoms and instances on layer {}/{} (references and arrays nested): more than the {} the lattice holds; refused before expanding",
            o.layer, o.datatype, o.max_atoms
        )));
    }
    if atoms == 0 {
        return Err(general(format!(
            "no atoms on layer {} datatype {} in cell {top:?}: expected BOUNDARY polygons there",
            o.layer, o.datatype
        )));
    }
    // a PATH or BOX on the atom layer in a cell that is used
    for (name, c) in &lib.cells {
        if let Some((offset, what)) = c.other_on_layer
            && counts.contains_key(name.as_str())
        {
            return err(
                offset,
                format!(
                    "{what} on the atom layer {}/{} in cell {name:?}: expected BOUNDARY polygons",
                    o.layer, o.datatype
                ),
            );
        }
    }
    let unit = lib.unit_m;
    let p = o.pitch_m / unit; // pitch in database units
    // pass 1: the lattice's offset (circular mean of each coordinate modulo the pitch)
    let (mut sx, mut cx, mut sy, mut cy) = (0.0, 0.0, 0.0, 0.0);
    let k = std::f64::consts::TAU / p;
    expand(&lib, &top, Affine::IDENTITY, &mut |a| {
        let (s, c) = (k * a.x).sin_cos();
        sx += s;
        cx += c;
        let (s, c) = (k * a.y).sin_cos();
        sy += s;
        cy += c;
    });
    let x0 = sx.atan2(cx) / k;
    let y0 = sy.atan2(cy) / k;
    // pass 2: the grid's extent
    let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
    expand(&lib, &top, Affine::IDENTITY, &mut |a| {
        let (i, j) = (((a.x - x0) / p).round() as i64, ((a.y - y0) / p).round() as i64);
        lo = (lo.0.min(i), lo.1.min(j));
        hi = (hi.0.max(i), hi.1.max(j));
    });
    let (nx, ny) = ((hi.0 - lo.0 + 1) as u64, (hi.1 - lo.1 + 1) as u64);
    if nx.saturating_mul(ny) > o.max_sites {
        return Err(general(format!(
            "the atoms span {nx} × {ny} lattice sites of {} µm: more than the {} allowed; refused before allocating",
            o.pitch_m * 1e6,
            o.max_sites
        )));
    }
    let (nx, ny) = (nx as usize, ny as usize);
    let fins = o.atom == AtomKind::Fin;
    let np = if fins { 2 } else { 1 };
    let mut values = vec![f64::NAN; np * nx * ny];
    let mut empty = vec![true; nx * ny];
    let mut theta = fins.then(|| vec![f64::NAN; nx * ny]);
    let mut stats = LayoutStats {
        records: lib.records,
        bytes: lib.bytes,
        cells: lib.cells.len(),
        parameter_range: vec![(f64::INFINITY, f64::NEG_INFINITY); np],
        max_vertex_deviation: lib.max_deviation,
        database_unit_m: unit,
        ..LayoutStats::default()
    };
    let mut extra_sites = std::collections::HashSet::new();
    let nm = unit * 1e9;
    expand(&lib, &top, Affine::IDENTITY, &mut |a| {
        stats.atoms += 1;
        let (fi, fj) = ((a.x - x0) / p, (a.y - y0) / p);
        let (i, j) = (fi.round(), fj.round());
        let off = (fi - i).hypot(fj - j) * p * unit;
        stats.max_off_lattice_m = stats.max_off_lattice_m.max(off);
        let idx = (j as i64 - lo.1) as usize * nx + (i as i64 - lo.0) as usize;
        let params = [a.a * nm, a.b * nm];
        for (q, v) in params.iter().take(np).enumerate() {
            let r = &mut stats.parameter_range[q];
            *r = (r.0.min(*v), r.1.max(*v));
        }
        if !empty[idx] {
            extra_sites.insert(idx);
            return;
        }
        empty[idx] = false;
        for (q, v) in params.iter().take(np).enumerate() {
            values[q * nx * ny + idx] = *v;
        }
        if let Some(t) = theta.as_mut() {
            t[idx] = a.theta.to_degrees().rem_euclid(180.0);
            if t[idx] >= 180.0 {
                t[idx] = 0.0;
            }
        }
    });
    stats.doubly_occupied_sites = extra_sites.len() as u64;
    stats.empty_sites = empty.iter().filter(|&&e| e).count() as u64;
    Ok(AtomGrid {
        pitch_m: o.pitch_m,
        origin_m: ((x0 + lo.0 as f64 * p) * unit, (y0 + lo.1 as f64 * p) * unit),
        nx,
        ny,
        parameters: if fins { vec!["width_nm".into(), "length_nm".into()] } else { vec!["diameter_nm".into()] },
        values,
        empty,
        theta_deg: theta,
        stats,
    })
}

/// Whether `cell` holds any atom once expanded (1) or none (0).
fn count_atoms(lib: &Library, cell: &str, counts: &HashMap<&str, u64>) -> u64 {
    let c = &lib.cells[cell];
    if !c.atoms.is_empty() {
        return 1;
    }
    let mut seen = std::collections::HashSet::new();
    let mut stack = vec![cell];
    while let Some(name) = stack.pop() {
        if !seen.insert(name) {
            continue;
        }
        let c = &lib.cells[name];
        if !c.atoms.is_empty() {
            return 1;
        }
        stack.extend(c.refs.iter().filter(|r| counts.contains_key(r.cell.as_str())).map(|r| r.cell.as_str()));
    }
    0
}

fn list(names: &[String]) -> String {
    let shown: Vec<String> = names.iter().take(10).map(|n| format!("{n:?}")).collect();
    if names.len() > 10 { format!("{} … ({} in all)", shown.join(", "), names.len()) } else { shown.join(", ") }
}

/// A minimal GDSII writer (tests, benchmarks, and users' test layouts): polygons, SREF, AREF.
pub struct Writer<W: std::io::Write> {
    out: W,
}

impl<W: std::io::Write> Writer<W> {
    fn record(&mut self, kind: u8, data: u8, body: &[u8]) -> std::io::Result<()> {
        let length = u16::try_from(body.len() + 4).map_err(|_| std::io::Error::other("record over 65535 bytes"))?;
        self.out.write_all(&length.to_be_bytes())?;
        self.out.write_all(&[kind, data])?;
        self.out.write_all(body)
    }

    /// HEADER, BGNLIB, LIBNAME, UNITS (user unit 1e-3 of the database unit `unit_m`).
    pub fn new(out: W, unit_m: f64) -> std::io::Result<Self> {
        let mut w = Writer { out };
        w.record(HEADER, 2, &600i16.to_be_bytes())?;
        w.record(BGNLIB, 2, &[0u8; 24])?;
        w.record(LIBNAME, 6, b"ASNRLIB\0")?;
        let mut units = to_real8(1e-3).to_vec();
        units.extend_from_slice(&to_real8(unit_m));
        w.record(UNITS, 5, &units)?;
        Ok(w)
    }

    /// BGNSTR, STRNAME.
    pub fn begin_cell(&mut self, name: &str) -> std::io::Result<()> {
        self.record(BGNSTR, 2, &[0u8; 24])?;
        let mut n = name.as_bytes().to_vec();
        if !n.len().is_multiple_of(2) {
            n.push(0);
        }
        self.record(STRNAME, 6, &n)
    }

    /// ENDSTR.
    pub fn end_cell(&mut self) -> std::io::Result<()> {
        self.record(ENDSTR, 0, &[])
    }

    /// A BOUNDARY on `layer`/`datatype` through `points` (closed by repeating the first).
    pub fn polygon(&mut self, layer: i16, datatype: i16, points: &[(i32, i32)]) -> std::io::Result<()> {
        self.record(BOUNDARY, 0, &[])?;
        self.record(LAYER, 2, &layer.to_be_bytes())?;
        self.record(DATATYPE, 2, &datatype.to_be_bytes())?;
        let mut xy = Vec::with_capacity(8 * (points.len() + 1));
        for &(x, y) in points.iter().chain(points.first()) {
            xy.extend_from_slice(&x.to_be_bytes());
            xy.extend_from_slice(&y.to_be_bytes());
        }
        self.record(XY, 3, &xy)?;
        self.record(ENDEL, 0, &[])
    }

    fn transform(&mut self, reflect: bool, mag: f64, angle_deg: f64) -> std::io::Result<()> {
        if reflect || mag != 1.0 || angle_deg != 0.0 {
            self.record(STRANS, 1, &(if reflect { 0x8000u16 } else { 0 }).to_be_bytes())?;
            if mag != 1.0 {
                self.record(MAG, 5, &to_real8(mag))?;
            }
            if angle_deg != 0.0 {
                self.record(ANGLE, 5, &to_real8(angle_deg))?;
            }
        }
        Ok(())
    }

    /// An SREF of `cell` at `at`, reflected about x first if `reflect`, magnified, rotated.
    pub fn sref(&mut self, cell: &str, at: (i32, i32), reflect: bool, mag: f64, angle_deg: f64) -> std::io::Result<()> {
        self.record(SREF, 0, &[])?;
        let mut n = cell.as_bytes().to_vec();
        if !n.len().is_multiple_of(2) {
            n.push(0);
        }
        self.record(SNAME, 6, &n)?;
        self.transform(reflect, mag, angle_deg)?;
        let mut xy = at.0.to_be_bytes().to_vec();
        xy.extend_from_slice(&at.1.to_be_bytes());
        self.record(XY, 3, &xy)?;
        self.record(ENDEL, 0, &[])
    }

    /// An AREF of `cell`: `cols × rows` instances from `origin`, steps `col_step` and `row_step`.
    #[allow(clippy::too_many_arguments)]
    pub fn aref(
        &mut self,
        cell: &str,
        cols: i16,
        rows: i16,
        origin: (i32, i32),
        col_step: (i32, i32),
        row_step: (i32, i32),
        angle_deg: f64,
    ) -> std::io::Result<()> {
        self.record(AREF, 0, &[])?;
        let mut n = cell.as_bytes().to_vec();
        if !n.len().is_multiple_of(2) {
            n.push(0);
        }
        self.record(SNAME, 6, &n)?;
        self.transform(false, 1.0, angle_deg)?;
        let mut cr = cols.to_be_bytes().to_vec();
        cr.extend_from_slice(&rows.to_be_bytes());
        self.record(COLROW, 2, &cr)?;
        let corner = |n: i16, step: (i32, i32)| -> std::io::Result<(i32, i32)> {
            let at = |o: i32, s: i32| {
                i32::try_from(i64::from(o) + i64::from(n) * i64::from(s))
                    .map_err(|_| std::io::Error::other("an AREF corner beyond 32-bit coordinates"))
            };
            Ok((at(origin.0, step.0)?, at(origin.1, step.1)?))
        };
        let (c, r) = (corner(cols, col_step)?, corner(rows, row_step)?);
        let mut xy = Vec::new();
        for p in [origin, c, r] {
            xy.extend_from_slice(&p.0.to_be_bytes());
            xy.extend_from_slice(&p.1.to_be_bytes());
        }
        self.record(XY, 3, &xy)?;
        self.record(ENDEL, 0, &[])
    }

    /// ENDLIB; the writer's output.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.record(ENDLIB, 0, &[])?;
        Ok(self.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1 pm database unit: vertex rounding far below the tolerances checked.
    const UNIT: f64 = 1e-12;

    /// A regular `n`-gon of diameter `d` (vertices on the circle) centred at `c`, first vertex at
    /// angle `phase` (database units).
    fn ngon(c: (f64, f64), d: f64, n: usize, phase: f64) -> Vec<(i32, i32)> {
        (0..n)
            .map(|k| {
                let a = phase + std::f64::consts::TAU * k as f64 / n as f64;
                ((c.0 + 0.5 * d * a.cos()).round() as i32, (c.1 + 0.5 * d * a.sin()).round() as i32)
            })
            .collect()
    }

    fn pillars(pitch_m: f64) -> GdsOptions {
        GdsOptions {
            cell: None,
            layer: 1,
            datatype: 0,
            pitch_m,
            atom: AtomKind::Pillar,
            max_atoms: 1 << 20,
            max_sites: 1 << 22,
        }
    }

    fn at(g: &AtomGrid, q: usize, i: usize, j: usize) -> f64 {
        g.values[q * g.nx * g.ny + j * g.nx + i]
    }

    /// 9-vertex pillars (as DFlat draws them) give their circle's diameter; the area-equivalent
    /// circle is 4.05 % small, the correction's size.
    #[test]
    fn nine_vertex_pillars_give_their_diameters() {
        let p = 400e3; // 400 nm in pm
        let mut w = Writer::new(Vec::new(), UNIT).unwrap();
        w.begin_cell("TOP").unwrap();
        let mut want = Vec::new();
        for j in 0..3 {
            for i in 0..4 {
                let d = 100e3 + 20e3 * (4 * j + i) as f64;
                want.push(d);
                w.polygon(1, 0, &ngon((i as f64 * p, j as f64 * p), d, 9, 0.3 * i as f64)).unwrap();
            }
        }
        w.polygon(2, 0, &ngon((0.0, 0.0), 5e3, 4, 0.0)).unwrap(); // another layer: skipped
        w.end_cell().unwrap();
        let bytes = w.finish().unwrap();
        let g = layout(&bytes[..], &pillars(400e-9)).unwrap();
        assert_eq!((g.nx, g.ny, g.stats.atoms, g.stats.empty_sites), (4, 3, 12, 0));
        for j in 0..3 {
            for i in 0..4 {
                let d = at(&g, 0, i, j);
                let want = want[4 * j + i] * 1e-3; // nm
                assert!((d - want).abs() < 1e-4 * want, "{d} vs {want}");
            }
        }
        assert!(g.stats.max_off_lattice_m < 1e-12, "{}", g.stats.max_off_lattice_m);
        assert!(g.stats.max_vertex_deviation < 1e-4, "{}", g.stats.max_vertex_deviation);
        // the area-equivalent circle of a 9-gon: √((9/2π) sin 40°) = 0.9595, 4.05 % small
        let area = 9.0 / 8.0 * (std::f64::consts::TAU / 9.0).sin();
        let equivalent = (4.0 * area / std::f64::consts::PI).sqrt();
        assert!((1.0 - equivalent - 0.0405).abs() < 5e-5, "{}", 1.0 - equivalent);
        assert!((polygon_diameter(area, 9) - 1.0).abs() < 1e-15);
    }

    /// SREF and AREF with rotation, reflection and magnification against the transforms written
    /// out by hand: positions, fin angles, sizes.
    #[test]
    fn references_and_arrays_with_rotation() {
        let p = 500e3; // 500 nm lattice, pm
        let fin = |c: (f64, f64), w: f64, l: f64, theta: f64| -> Vec<(i32, i32)> {
            let (s, co) = theta.sin_cos();
            [(-l / 2.0, -w / 2.0), (l / 2.0, -w / 2.0), (l / 2.0, w / 2.0), (-l / 2.0, w / 2.0)]
                .iter()
                .map(|&(x, y)| ((c.0 + co * x - s * y).round() as i32, (c.1 + s * x + co * y).round() as i32))
                .collect()
        };
        let mut w = Writer::new(Vec::new(), UNIT).unwrap();
        // FIN: a 80 × 250 nm fin at 20° at the cell's origin
        w.begin_cell("FIN").unwrap();
        w.polygon(1, 0, &fin((0.0, 0.0), 80e3, 250e3, 20f64.to_radians())).unwrap();
        w.end_cell().unwrap();
        w.begin_cell("TOP").unwrap();
        // a 3 × 2 array rotated by 30°: the steps (already in the parent's frame) along the lattice
        w.aref("FIN", 3, 2, (0, 0), (p as i32, 0), (0, p as i32), 30.0).unwrap();
        // one reflected about x, then rotated by 90°, at site (4, 0)
        w.sref("FIN", ((4.0 * p) as i32, 0), true, 1.0, 90.0).unwrap();
        // one magnified 1.2×, at site (4, 1)
        w.sref("FIN", ((4.0 * p) as i32, p as i32), false, 1.2, 0.0).unwrap();
        w.end_cell().unwrap();
        let bytes = w.finish().unwrap();
        let o = GdsOptions { atom: AtomKind::Fin, ..pillars(500e-9) };
        let g = layout(&bytes[..], &o).unwrap();
        assert_eq!((g.nx, g.ny, g.stats.atoms, g.stats.empty_sites), (5, 2, 8, 2)); // column 3 empty
        let theta = g.theta_deg.as_ref().unwrap();
        let th = |i: usize, j: usize| theta[j * g.nx + i];
        for j in 0..2 {
            for i in 0..3 {
                assert!((th(i, j) - 50.0).abs() < 1e-3, "({i}, {j}): {}", th(i, j)); // 20° + 30°
                assert!((at(&g, 0, i, j) - 80.0).abs() < 1e-3 && (at(&g, 1, i, j) - 250.0).abs() < 1e-3);
            }
        }
        // reflected: 20° → −20°, then + 90° = 70°
        assert!((th(4, 0) - 70.0).abs() < 1e-3, "{}", th(4, 0));
        assert!((th(4, 1) - 20.0).abs() < 1e-3 && (at(&g, 1, 4, 1) - 300.0).abs() < 1e-3, "{}", at(&g, 1, 4, 1));
        assert!((at(&g, 0, 4, 1) - 96.0).abs() < 1e-3);
        assert!(g.stats.max_off_lattice_m < 1e-11, "{}", g.stats.max_off_lattice_m);
        // the same file gzip-compressed, read from disk
        let dir = std::env::temp_dir().join(format!("asnr-gds-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("fins.gds.gz");
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        std::io::Write::write_all(&mut gz, &bytes).unwrap();
        std::fs::write(&path, gz.finish().unwrap()).unwrap();
        let h = read_layout(&path, &o).unwrap();
        assert_eq!((h.values.len(), h.stats), (g.values.len(), g.stats.clone()));
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Off-lattice, doubly occupied and empty sites are reported.
    #[test]
    fn lattice_statistics() {
        let p = 400e3;
        let mut w = Writer::new(Vec::new(), UNIT).unwrap();
        w.begin_cell("TOP").unwrap();
        for i in 0..5 {
            if i == 2 {
                continue; // an empty site
            }
            let shift = if i == 3 { 10e3 } else { 0.0 }; // 10 nm off its site
            w.polygon(1, 0, &ngon((i as f64 * p + shift, 0.0), 150e3, 9, 0.0)).unwrap();
        }
        w.polygon(1, 0, &ngon((4.0 * p, 0.0), 120e3, 9, 0.0)).unwrap(); // a second atom on site 4
        w.end_cell().unwrap();
        let g = layout(&w.finish().unwrap()[..], &pillars(400e-9)).unwrap();
        assert_eq!((g.nx, g.stats.atoms, g.stats.empty_sites, g.stats.doubly_occupied_sites), (5, 5, 1, 1));
        assert!(g.empty[2] && at(&g, 0, 2, 0).is_nan());
        // the lattice offset is the atoms' circular mean: the 10 nm shift of one of five atoms
        // moves it 2 nm, leaving 8 nm on that atom
        assert!((g.stats.max_off_lattice_m - 8e-9).abs() < 0.2e-9, "{}", g.stats.max_off_lattice_m);
        assert_eq!(g.stats.parameter_range.len(), 1);
        assert!(
            (g.stats.parameter_range[0].0 - 120.0).abs() < 0.1 && (g.stats.parameter_range[0].1 - 150.0).abs() < 0.1
        );
    }

    fn message(bytes: &[u8], o: &GdsOptions) -> String {
        layout(bytes, o).unwrap_err().to_string()
    }

    /// Bad layouts are refused naming the record and its byte offset, before allocating.
    #[test]
    fn bad_layouts_are_refused() {
        let o = pillars(400e-9);
        let one = |edit: &dyn Fn(&mut Writer<Vec<u8>>)| {
            let mut w = Writer::new(Vec::new(), UNIT).unwrap();
            w.begin_cell("TOP").unwrap();
            edit(&mut w);
            w.end_cell().unwrap();
            w.finish().unwrap()
        };
        let good = one(&|w| w.polygon(1, 0, &ngon((0.0, 0.0), 100e3, 9, 0.0)).unwrap());
        // an AREF of 32767 × 32767 instances: refused from the counts, nothing expanded
        let mut w = Writer::new(Vec::new(), UNIT).unwrap();
        w.begin_cell("A").unwrap();
        w.polygon(1, 0, &ngon((0.0, 0.0), 100e3, 9, 0.0)).unwrap();
        w.end_cell().unwrap();
        w.begin_cell("TOP").unwrap();
        w.aref("A", 32767, 32767, (0, 0), (1000, 0), (0, 1000), 0.0).unwrap();
        w.end_cell().unwrap();
        let e = message(&w.finish().unwrap(), &o);
        assert!(e.contains("1073676289 atoms and instances") && e.contains("refused before expanding"), "{e}");
        // an array of an empty cell: its instances bound the work too
        let mut w = Writer::new(Vec::new(), UNIT).unwrap();
        w.begin_cell("EMPTY").unwrap();
        w.end_cell().unwrap();
        w.begin_cell("TOP").unwrap();
        w.polygon(1, 0, &ngon((0.0, 0.0), 100e3, 9, 0.0)).unwrap();
        w.aref("EMPTY", 32767, 32767, (0, 0), (1000, 0), (0, 1000), 0.0).unwrap();
        w.end_cell().unwrap();
        let e = message(&w.finish().unwrap(), &o);
        assert!(e.contains("refused before expanding"), "{e}");
        // a bow-tie, an open polygon, another layer only
        let bow = one(&|w| w.polygon(1, 0, &[(0, 0), (1000, 1000), (1000, 0), (0, 1000)]).unwrap());
        assert!(message(&bow, &o).contains("self-intersecting"), "{}", message(&bow, &o));
        let mut open = good.clone();
        // the XY record's last point: move its y by one unit (the polygon no longer closes)
        let xy = open.windows(4).position(|h| h[2] == XY && h[3] == 3).unwrap();
        let len = u16::from_be_bytes([open[xy], open[xy + 1]]) as usize;
        open[xy + len - 1] ^= 1;
        let e = message(&open, &o);
        assert!(e.contains(&format!("byte {xy}: BOUNDARY XY")) && e.contains("open polygon"), "{e}");
        let e = message(&good, &GdsOptions { layer: 7, ..o.clone() });
        assert!(e.contains("no atoms on layer 7"), "{e}");
        // a record whose length runs past the end
        let mut long = good.clone();
        let end = long.len() - 4;
        long[end..end + 2].copy_from_slice(&100u16.to_be_bytes());
        let e = message(&long, &o);
        assert!(e.contains(&format!("byte {end}: ENDLIB declares 100 bytes")) && e.contains("truncated"), "{e}");
        // a cycle and a missing cell
        let mut w = Writer::new(Vec::new(), UNIT).unwrap();
        for (a, b) in [("A", "B"), ("B", "A")] {
            w.begin_cell(a).unwrap();
            w.sref(b, (0, 0), false, 1.0, 0.0).unwrap();
            w.end_cell().unwrap();
        }
        let e = message(&w.finish().unwrap(), &GdsOptions { cell: Some("A".into()), ..o.clone() });
        assert!(e.contains("cycle"), "{e}");
        let missing = one(&|w| w.sref("NONE", (0, 0), false, 1.0, 0.0).unwrap());
        assert!(message(&missing, &o).contains("\"NONE\""), "{}", message(&missing, &o));
        // a grid larger than allowed: two atoms far apart
        let far = one(&|w| {
            w.polygon(1, 0, &ngon((0.0, 0.0), 100e3, 9, 0.0)).unwrap();
            w.polygon(1, 0, &ngon((2e9, 2e9), 100e3, 9, 0.0)).unwrap();
        });
        assert!(message(&far, &o).contains("before allocating"), "{}", message(&far, &o));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// Arbitrary bytes never panic, and every truncation of a valid file is refused.
        #[test]
        fn arbitrary_bytes_and_truncations(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..600), cut in 0usize..10_000) {
            let o = pillars(400e-9);
            let _ = layout(&bytes[..], &o);
            let mut w = Writer::new(Vec::new(), UNIT).unwrap();
            w.begin_cell("TOP").unwrap();
            w.polygon(1, 0, &ngon((0.0, 0.0), 100e3, 9, 0.0)).unwrap();
            w.aref("TOP2", 2, 2, (0, 0), (400_000, 0), (0, 400_000), 0.0).unwrap();
            w.end_cell().unwrap();
            w.begin_cell("TOP2").unwrap();
            w.polygon(1, 0, &ngon((800_000.0, 0.0), 120e3, 9, 0.0)).unwrap();
            w.end_cell().unwrap();
            let good = w.finish().unwrap();
            proptest::prop_assert!(layout(&good[..], &o).is_ok());
            let cut = cut % good.len();
            proptest::prop_assert!(layout(&good[..cut], &o).is_err());
            // a byte changed somewhere: never a panic
            let mut bad = good.clone();
            bad[cut] ^= bytes.first().copied().unwrap_or(0x55) | 1;
            let _ = layout(&bad[..], &o);
        }
    }
}
