//! The `model = "psf"` lens: a PSF stack read from a `.npy` array or a multi-page float TIFF
//! (docs/physics.md, "Designs given as data"), and the checks that need the rest of the scene
//! (the camera's Nyquist frequency, the detected spectrum's extent).
//!
//! Both readers check a file's sizes before they allocate for its samples: a header that
//! promises more than [`lenses::PSF_MAX_ELEMENTS`] values, or a file whose length does not match
//! its header, is refused unread.

use std::io::Read as _;
use std::path::Path;

use lenses::{Curve, PSF_MAX_ELEMENTS, PSF_MIN_SIDE, PsfStack};
use radiometry::Spectrum;

use crate::error::{Error, num, quoted};
use crate::lens::{LensInfo, RawLens};
use crate::load::Origins;

/// The most pages a TIFF stack may have (one per wavelength).
const MAX_PAGES: usize = 10_000;

/// The longest `.npy` header read, bytes (numpy writes 128 or a few hundred).
const MAX_NPY_HEADER: usize = 1 << 16;

/// The largest fraction of the signal (the detected spectrum times the lens efficiency) that may
/// lie outside the stack's wavelengths, where the end slices' OTF would stand for it; above it
/// the scene is refused, above [`OUTSIDE_WARNED`] warned about.
pub(crate) const PSF_OUTSIDE_MAX: f64 = 1e-3;

/// Above this fraction of the signal outside the stack's wavelengths the scene warns.
const OUTSIDE_WARNED: f64 = 1e-6;

/// The fraction of a slice's light in the stack's border band above which the scene warns.
const BORDER_WARNED: f64 = 1e-3;

/// The largest |imaginary part| of a re-centred OTF above which the scene warns (the table holds
/// the real part).
const IMAGINARY_WARNED: f64 = 0.01;

/// A stack in memory: `depth` slices of `ny × nx`, C order `[slice][row][column]`.
#[derive(Debug)]
pub(crate) struct Stack {
    pub depth: usize,
    pub ny: usize,
    pub nx: usize,
    pub values: Vec<f64>,
}

/// What the scene checks once the camera and the spectrum are known.
#[derive(Clone, Debug)]
pub(crate) struct PsfLimits {
    pub pitch_m: f64,
    pub range_m: (f64, f64),
    pub efficiency: Spectrum,
}

/// What the file formats accept, for messages.
const ACCEPTED: &str = "a .npy float array [wavelength, y, x] (dtype <f4, <f8, >f4 or >f8, C or Fortran order, NPY format 1.0–3.0) or a multi-page TIFF of 32- or 64-bit float samples (one page per wavelength)";

/// An element type of a `.npy` array.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Dtype {
    size: usize,
    little: bool,
}

/// A parsed `.npy` header.
#[derive(Debug, PartialEq)]
struct NpyHeader {
    dtype: Dtype,
    fortran: bool,
    shape: [usize; 3],
    /// Where the data start, bytes from the file's start.
    offset: usize,
}

/// The fixed start of a `.npy` file: the header's length and where it starts.
fn npy_preamble(bytes: &[u8]) -> Result<(usize, usize), String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not a .npy file (it does not start with \\x93NUMPY)".into());
    }
    let (major, minor) = (bytes[6], bytes[7]);
    let (len, start) = match major {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize, 12),
        2 | 3 => return Err("a .npy file cut inside its preamble".into()),
        _ => return Err(format!("NPY format version {major}.{minor}: expected 1.0, 2.0 or 3.0")),
    };
    if len > MAX_NPY_HEADER {
        return Err(format!("a .npy header of {len} bytes: expected at most {MAX_NPY_HEADER}"));
    }
    Ok((len, start))
}

/// A value of the header's Python dict literal.
#[derive(Debug, PartialEq)]
enum PyValue {
    Str(String),
    Bool(bool),
    Tuple(Vec<u64>),
}

/// A minimal reader of the Python literal numpy writes: `{'descr': '<f8', 'fortran_order':
/// False, 'shape': (3, 4, 5), }` (strings in single or double quotes, True/False, tuples of
/// whole numbers with an optional `L` suffix, trailing commas).
struct Literal<'a> {
    s: &'a [u8],
    at: usize,
}

impl Literal<'_> {
    fn skip(&mut self) {
        while self.at < self.s.len() && self.s[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip();
        if self.s.get(self.at) == Some(&c) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn expect(&mut self, c: u8) -> Result<(), String> {
        if self.eat(c) { Ok(()) } else { Err(self.unexpected(&format!("`{}`", c as char))) }
    }

    fn unexpected(&self, what: &str) -> String {
        let rest = String::from_utf8_lossy(&self.s[self.at.min(self.s.len())..]);
        let rest: String = rest.chars().take(24).collect();
        format!("a malformed .npy header: expected {what} at byte {}, found `{rest}`", self.at)
    }

    fn string(&mut self) -> Result<String, String> {
        self.skip();
        let quote = match self.s.get(self.at) {
            Some(&q @ (b'\'' | b'"')) => q,
            _ => return Err(self.unexpected("a quoted string")),
        };
        let start = self.at + 1;
        let end = self.s[start..].iter().position(|&c| c == quote).ok_or_else(|| self.unexpected("a closing quote"))?;
        self.at = start + end + 1;
        Ok(String::from_utf8_lossy(&self.s[start..start + end]).into_owned())
    }

    fn value(&mut self) -> Result<PyValue, String> {
        self.skip();
        match self.s.get(self.at) {
            Some(b'\'' | b'"') => Ok(PyValue::Str(self.string()?)),
            Some(b'(') => {
                self.at += 1;
                let mut items = Vec::new();
                loop {
                    if self.eat(b')') {
                        return Ok(PyValue::Tuple(items));
                    }
                    self.skip();
                    let start = self.at;
                    while self.at < self.s.len() && self.s[self.at].is_ascii_digit() {
                        self.at += 1;
                    }
                    let digits = std::str::from_utf8(&self.s[start..self.at]).unwrap_or("");
                    let n: u64 = digits.parse().map_err(|_| {
                        self.at = start;
                        self.unexpected("a whole number ≥ 0 in the shape")
                    })?;
                    self.eat(b'L');
                    items.push(n);
                    if !self.eat(b',') {
                        self.expect(b')')?;
                        return Ok(PyValue::Tuple(items));
                    }
                }
            }
            _ if self.s[self.at..].starts_with(b"True") => {
                self.at += 4;
                Ok(PyValue::Bool(true))
            }
            _ if self.s[self.at..].starts_with(b"False") => {
                self.at += 5;
                Ok(PyValue::Bool(false))
            }
            _ => Err(self.unexpected("a string, True, False or a tuple")),
        }
    }

    fn dict(&mut self) -> Result<Vec<(String, PyValue)>, String> {
        self.expect(b'{')?;
        let mut entries = Vec::new();
        loop {
            if self.eat(b'}') {
                break;
            }
            let key = self.string()?;
            self.expect(b':')?;
            let value = self.value()?;
            entries.push((key, value));
            if !self.eat(b',') {
                self.expect(b'}')?;
                break;
            }
        }
        self.skip();
        if self.at != self.s.len() {
            return Err(self.unexpected("the end of the header after the dict"));
        }
        Ok(entries)
    }
}

/// Parses a `.npy` header from the file's first bytes (at least the preamble and the header);
/// checks the dtype, the shape (3 axes, or 2 for one slice; each side ≥
/// [`PSF_MIN_SIDE`] but the first) and the element count (≤ [`PSF_MAX_ELEMENTS`]).
fn npy_header(bytes: &[u8]) -> Result<NpyHeader, String> {
    let (len, start) = npy_preamble(bytes)?;
    let Some(text) = bytes.get(start..start + len) else {
        return Err(format!("a .npy header of {len} bytes, but the file ends after {} bytes", bytes.len()));
    };
    let entries = Literal { s: text, at: 0 }.dict()?;
    let mut descr = None;
    let mut fortran = None;
    let mut shape = None;
    for (key, value) in entries {
        match (key.as_str(), value) {
            ("descr", PyValue::Str(s)) => descr = Some(s),
            ("fortran_order", PyValue::Bool(b)) => fortran = Some(b),
            ("shape", PyValue::Tuple(t)) => shape = Some(t),
            (k, v) => {
                return Err(format!(
                    "the .npy header's `{k}`: {v:?}: expected the keys descr (a string), fortran_order (True or False) and shape (a tuple)"
                ));
            }
        }
    }
    let descr = descr.ok_or("a .npy header without `descr`")?;
    let dtype = match descr.as_str() {
        "<f4" => Dtype { size: 4, little: true },
        "<f8" => Dtype { size: 8, little: true },
        ">f4" => Dtype { size: 4, little: false },
        ">f8" => Dtype { size: 8, little: false },
        other => {
            return Err(format!(
                "dtype '{other}': expected float samples, '<f4', '<f8', '>f4' or '>f8' (save with astype('float32') or 'float64')"
            ));
        }
    };
    let fortran = fortran.ok_or("a .npy header without `fortran_order`")?;
    let shape = shape.ok_or("a .npy header without `shape`")?;
    let shape = match shape.as_slice() {
        &[d, y, x] => [d, y, x],
        &[y, x] => [1, y, x],
        other => {
            return Err(format!(
                "an array of shape {other:?}: expected 3 axes [wavelength, y, x] (or 2, [y, x], for one wavelength)"
            ));
        }
    };
    let count = shape.iter().try_fold(1u64, |a, &b| a.checked_mul(b));
    if shape[0] == 0 || shape[1] < PSF_MIN_SIDE as u64 || shape[2] < PSF_MIN_SIDE as u64 {
        return Err(format!(
            "an array of shape {shape:?}: expected at least one slice of at least {PSF_MIN_SIDE} × {PSF_MIN_SIDE} samples"
        ));
    }
    if count.is_none_or(|c| c > PSF_MAX_ELEMENTS as u64) {
        return Err(format!(
            "an array of shape {shape:?}: more than {PSF_MAX_ELEMENTS} values (2^26): expected a smaller stack (crop or bin it)"
        ));
    }
    let shape = shape.map(|v| v as usize);
    Ok(NpyHeader { dtype, fortran, shape, offset: start + len })
}

/// The samples of `data` (exactly `depth·ny·nx` values of `dtype`) in C order.
fn npy_values(header: &NpyHeader, data: &[u8]) -> Vec<f64> {
    let [d, ny, nx] = header.shape;
    let read = |i: usize| -> f64 {
        let b = &data[i * header.dtype.size..(i + 1) * header.dtype.size];
        match (header.dtype.size, header.dtype.little) {
            (4, true) => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            (4, false) => f64::from(f32::from_be_bytes([b[0], b[1], b[2], b[3]])),
            (_, true) => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
            (_, false) => f64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    };
    if header.fortran {
        // element (k, y, x) at k + d (y + ny x)
        (0..d * ny * nx)
            .map(|c| {
                let (k, y, x) = (c / (ny * nx), (c / nx) % ny, c % nx);
                read(k + d * (y + ny * x))
            })
            .collect()
    } else {
        (0..d * ny * nx).map(read).collect()
    }
}

/// A whole `.npy` file in memory, read as [`read_npy`] reads a file.
#[cfg(test)]
pub(crate) fn parse_npy(bytes: &[u8]) -> Result<Stack, String> {
    npy_from(std::io::Cursor::new(bytes), bytes.len() as u64)
}

/// Reads a `.npy` file.
fn read_npy(path: &Path) -> Result<Stack, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read it ({e})"))?;
    let length = file.metadata().map_err(|e| format!("cannot read it ({e})"))?.len();
    npy_from(std::io::BufReader::new(file), length)
}

/// Reads a `.npy` array of `length` bytes from `source`: its preamble and header first, the
/// length checked against them, and only then its samples.
fn npy_from(mut source: impl std::io::Read + std::io::Seek, length: u64) -> Result<Stack, String> {
    let io = |e: std::io::Error| format!("cannot read it ({e})");
    let mut head = vec![0u8; 12.min(length) as usize];
    source.read_exact(&mut head).map_err(io)?;
    let (len, at) = npy_preamble(&head)?;
    head.truncate(at);
    head.resize(at + len, 0);
    source.seek(std::io::SeekFrom::Start(at as u64)).map_err(io)?;
    source
        .read_exact(&mut head[at..])
        .map_err(|_| format!("a .npy header of {len} bytes, but the file ends after {length} bytes"))?;
    let header = npy_header(&head)?;
    let [depth, ny, nx] = header.shape;
    let data = (depth * ny * nx) * header.dtype.size;
    if length != (header.offset + data) as u64 {
        return Err(format!(
            "{} bytes of data after the header: expected {data} ({depth} × {ny} × {nx} values of {} bytes)",
            length.saturating_sub(header.offset as u64),
            header.dtype.size
        ));
    }
    let mut bytes = vec![0u8; data];
    source.read_exact(&mut bytes).map_err(io)?;
    Ok(Stack { depth, ny, nx, values: npy_values(&header, &bytes) })
}

/// Reads a multi-page float TIFF: every page's size and sample format checked first (one size,
/// 32- or 64-bit IEEE float, one sample per pixel), then the pages decoded.
fn read_tiff(path: &Path) -> Result<Stack, String> {
    use tiff::decoder::{Decoder, DecodingResult};
    use tiff::tags::Tag;
    let open = || -> Result<Decoder<std::io::BufReader<std::fs::File>>, String> {
        let file = std::fs::File::open(path).map_err(|e| format!("cannot read it ({e})"))?;
        Decoder::new(std::io::BufReader::new(file)).map_err(|e| format!("not a readable TIFF ({e})"))
    };
    let tiff = |e: tiff::TiffError| format!("not a readable TIFF ({e})");
    let mut decoder = open()?;
    let mut size = None;
    let mut pages = 0usize;
    loop {
        let (w, h) = decoder.dimensions().map_err(tiff)?;
        let color = decoder.colortype().map_err(tiff)?;
        let format: u16 = decoder.get_tag_unsigned(Tag::SampleFormat).unwrap_or(1);
        let float = matches!(color, tiff::ColorType::Gray(32 | 64)) && format == 3;
        if !float {
            return Err(format!(
                "page {pages} holds {color:?} samples of format {format}: expected one 32- or 64-bit float sample per pixel (SampleFormat 3)"
            ));
        }
        let (w, h) = (w as usize, h as usize);
        match size {
            None => size = Some((w, h)),
            Some((w0, h0)) if (w0, h0) != (w, h) => {
                return Err(format!(
                    "page {pages} is {w} × {h} pixels, page 0 {w0} × {h0}: expected pages of one size (one slice per wavelength)"
                ));
            }
            Some(_) => {}
        }
        pages += 1;
        let count = (pages as u64) * (w as u64) * (h as u64);
        if count > PSF_MAX_ELEMENTS as u64 || pages > MAX_PAGES {
            return Err(format!(
                "{pages} pages of {w} × {h} pixels or more: expected at most {PSF_MAX_ELEMENTS} values (2^26) and {MAX_PAGES} pages"
            ));
        }
        if !decoder.more_images() {
            break;
        }
        decoder.next_image().map_err(tiff)?;
    }
    let (nx, ny) = size.unwrap_or_default();
    if nx < PSF_MIN_SIDE || ny < PSF_MIN_SIDE {
        return Err(format!("pages of {nx} × {ny} pixels: expected at least {PSF_MIN_SIDE} × {PSF_MIN_SIDE}"));
    }
    let mut decoder = open()?;
    let mut values = Vec::with_capacity(pages * nx * ny);
    for page in 0..pages {
        if page > 0 {
            decoder.next_image().map_err(tiff)?;
        }
        let before = values.len();
        match decoder.read_image().map_err(tiff)? {
            DecodingResult::F32(v) => values.extend(v.into_iter().map(f64::from)),
            DecodingResult::F64(v) => values.extend(v),
            _ => return Err(format!("page {page}: samples that are not 32- or 64-bit floats")),
        }
        if values.len() - before != nx * ny {
            return Err(format!("page {page}: {} samples for {nx} × {ny} pixels", values.len() - before));
        }
    }
    Ok(Stack { depth: pages, ny, nx, values })
}

/// Reads a PSF stack, `.npy` or TIFF by its first bytes.
pub(crate) fn read_stack(path: &Path) -> Result<Stack, String> {
    let mut magic = [0u8; 6];
    let n = std::fs::File::open(path)
        .and_then(|mut f| {
            let mut got = 0;
            while got < magic.len() {
                match f.read(&mut magic[got..])? {
                    0 => break,
                    k => got += k,
                }
            }
            Ok(got)
        })
        .map_err(|e| format!("cannot read it ({e})"))?;
    match &magic[..n] {
        [0x93, b'N', b'U', b'M', b'P', b'Y'] => read_npy(path),
        [b'I', b'I', 42 | 43, 0, ..] | [b'M', b'M', 0, 42 | 43, ..] => read_tiff(path),
        _ => Err(format!(
            "neither a .npy file nor a TIFF (its first bytes are {:02x?}): expected {ACCEPTED}",
            &magic[..n]
        )),
    }
}

/// The `model = "psf"` lens of a `[lens]` table.
#[allow(clippy::too_many_arguments)]
pub(crate) fn psf_lens(
    l: &RawLens,
    o: &Origins,
    f_number: f64,
    f0_m: f64,
    transmission: &dyn Fn(&Origins, &Curve) -> Result<Curve, Error>,
    info: &mut LensInfo,
) -> Result<PsfStack, Error> {
    let key = "lens.psf";
    let file = o.require(key, l.psf.as_deref(), &format!("the path of a PSF stack: {ACCEPTED}"))?;
    let expected = "the stack's sample pitch at the detector, > 0 µm";
    let pitch = o.require("lens.psf_pitch_um", l.psf_pitch_um, expected)?;
    let pitch = o.number("lens.psf_pitch_um", pitch, pitch > 0.0 && pitch < 1e6, expected)?;
    let wkey = "lens.psf_wavelengths_nm";
    let expected = "the wavelength of each slice of the stack, nm, > 0 and strictly increasing";
    let wavelengths = o.require(wkey, l.psf_wavelengths_nm.as_ref(), expected)?;
    for (i, &w) in wavelengths.iter().enumerate() {
        let ok = w > 0.0 && (i == 0 || w > wavelengths[i - 1]);
        o.number(&format!("{wkey}[{i}]"), w, ok, expected)?;
        o.wavelength(&format!("{wkey}[{i}]"), w);
    }
    let e = o.require(
        "lens.efficiency",
        l.efficiency.as_ref(),
        "the imaging efficiency τ(λ), a fraction in [0, 1] or a CSV path: required with a PSF stack, which is normalized and carries no efficiency",
    )?;
    let efficiency = o.curve("lens.efficiency", e, "efficiency")?;
    let transmission = transmission(o, &efficiency)?;
    let path = o.path(file);
    let stack = read_stack(&path).map_err(|message| Error::Table {
        origin: o.of(key),
        key: o.key(key),
        file: crate::error::shorten(file),
        cause: Box::new(Error::Csv { file: path.display().to_string(), line: None, message }),
    })?;
    let shape = format!("{} × {} × {}", stack.depth, stack.ny, stack.nx);
    if stack.depth != wavelengths.len() {
        return Err(o.bad(
            wkey,
            format!("a list of {}", wavelengths.len()),
            &format!(
                "one wavelength per slice of lens.psf = {}: {} (its shape is {shape}, [wavelength, y, x])",
                quoted(file),
                stack.depth
            ),
        ));
    }
    let efficiency_spectrum = match &efficiency {
        Curve::Constant(v) => Spectrum::Constant(*v),
        Curve::Table(t) => Spectrum::Sampled(t.clone()),
    };
    let range = (wavelengths[0] * 1e-9, wavelengths[wavelengths.len() - 1] * 1e-9);
    let mut lens = PsfStack::new(
        f_number,
        f0_m,
        pitch * 1e-6,
        wavelengths.iter().map(|w| w * 1e-9).collect(),
        [stack.ny, stack.nx],
        &stack.values,
        efficiency,
        transmission,
    )
    .map_err(|e| o.domain(key, &format!("{key} = {}", quoted(file)), e))?;
    if l.design_wavelength_nm.is_some() {
        let v = l.design_wavelength_nm.unwrap_or_default();
        let v = o.number("lens.design_wavelength_nm", v, v > 0.0, "a wavelength > 0 nm")?;
        o.wavelength("lens.design_wavelength_nm", v);
        lens = lens.with_design_wavelength(v * 1e-9).map_err(|e| o.domain("lens", "[lens]", e))?;
        info.design_wavelength_m = Some(v * 1e-9);
    }
    let report = lens.report().clone();
    let (border, at) = report.border_fraction;
    if border > BORDER_WARNED {
        o.warn(
            key,
            quoted(file),
            format!(
                "{:.3} % of the light of the slice at {} nm lies within {} samples of the stack's border: the PSF may be cut off (a larger stack would hold it)",
                border * 100.0,
                num(optics::round_for_display(at * 1e9)),
                lenses::PSF_BORDER_SAMPLES
            ),
        );
    }
    let (im, at, nu) = report.imaginary;
    if im > IMAGINARY_WARNED {
        o.warn(
            key,
            quoted(file),
            format!(
                "the PSF at {} nm is asymmetric about its centroid: its OTF has an imaginary part of {im:.3} at {:.1} cycles/mm, which the table (the real part) leaves out",
                num(optics::round_for_display(at * 1e9)),
                nu * 1e-3
            ),
        );
    }
    let shifts = report.centroids_m.iter().map(|c| c[0].hypot(c[1])).fold(0.0, f64::max);
    info.notes.push(format!(
        "PSF stack {}: {shape} at {} µm, {}–{} nm; OTF to the stack's Nyquist {:.1} cycles/mm (transforms of {} points, zero padded ×{}), linear in λ between slices; centroid offsets up to {:.3} µm kept as lateral shifts",
        crate::error::shorten(file),
        num(pitch),
        num(wavelengths[0]),
        num(wavelengths[wavelengths.len() - 1]),
        lens.nyquist() * 1e-3,
        report.transform_length,
        lenses::PSF_PADDING,
        shifts * 1e6
    ));
    info.psf = Some(PsfLimits { pitch_m: pitch * 1e-6, range_m: range, efficiency: efficiency_spectrum });
    Ok(lens)
}

/// The checks of a PSF-stack lens that need the rest of the scene: the stack's Nyquist frequency
/// above the camera's, and the signal (detected spectrum × efficiency) inside the stack's
/// wavelengths but for at most [`PSF_OUTSIDE_MAX`] of it.
pub(crate) fn check_scene(scene: &metric::Scene, limits: &PsfLimits, o: &Origins) -> Result<(), Error> {
    let camera = scene.camera();
    let stack_nyquist = 0.5 / limits.pitch_m;
    if stack_nyquist <= camera.nyquist() {
        return Err(o.bad(
            "lens.psf_pitch_um",
            num(limits.pitch_m * 1e6),
            &format!(
                "a pitch under {} µm: the stack's Nyquist frequency 1/(2p) = {:.1} cycles/mm must exceed the camera's {:.1} cycles/mm (camera.pixel_pitch_um = {}), up to which the metric needs the MTF",
                num(camera.pixel_pitch() * 1e6),
                stack_nyquist * 1e-3,
                camera.nyquist() * 1e-3,
                num(camera.pixel_pitch() * 1e6)
            ),
        ));
    }
    let (lo, hi) = limits.range_m;
    let signal = Spectrum::product(vec![metric::detected_spectrum(scene), limits.efficiency.clone()]);
    let total = signal.integral();
    if total.is_nan() || total <= 0.0 {
        return Ok(()); // no light: the evaluation says so
    }
    let inside = match radiometry::TopHat::new(lo, hi, 1.0) {
        Ok(band) => Spectrum::product(vec![signal, Spectrum::TopHat(band)]).integral(),
        Err(_) => 0.0, // a one-slice stack covers one wavelength
    };
    let outside = if total.is_finite() { (1.0 - inside / total).max(0.0) } else { 1.0 };
    let nm = |l: f64| num(optics::round_for_display(l * 1e9));
    let range = format!("{}–{} nm", nm(lo), nm(hi));
    if outside > PSF_OUTSIDE_MAX {
        return Err(o.bad(
            "lens.psf_wavelengths_nm",
            format!("[{range}]"),
            &format!(
                "wavelengths covering the detected spectrum: {:.4} % of the signal (detected spectrum × lens.efficiency) lies outside the stack's {range}, at most {} % accepted (the end slices would stand for it); extend the stack or narrow the spectrum",
                outside * 100.0,
                PSF_OUTSIDE_MAX * 100.0
            ),
        ));
    }
    if outside > OUTSIDE_WARNED {
        o.warn(
            "lens.psf_wavelengths_nm",
            format!("[{range}]"),
            format!(
                "{:.2e} of the signal lies outside the stack's wavelengths: the end slices' OTF stands for it",
                outside
            ),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A `.npy` file of `values` with `descr`, `fortran` and `shape`, format 1.0 (or 2.0).
    pub(crate) fn npy(descr: &str, fortran: bool, shape: &[usize], data: &[u8], version: u8) -> Vec<u8> {
        let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
        let dims = if dims.len() == 1 { format!("{},", dims[0]) } else { dims.join(", ") };
        let mut dict = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': ({dims}), }}",
            if fortran { "True" } else { "False" }
        );
        let pre = if version == 1 { 10 } else { 12 };
        while (pre + dict.len() + 1) % 64 != 0 {
            dict.push(' ');
        }
        dict.push('\n');
        let mut out = b"\x93NUMPY".to_vec();
        out.push(version);
        out.push(0);
        if version == 1 {
            out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        } else {
            out.extend_from_slice(&(dict.len() as u32).to_le_bytes());
        }
        out.extend_from_slice(dict.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn ramp(n: usize) -> Vec<f64> {
        (0..n).map(|i| i as f64).collect()
    }

    /// Every dtype and both orders give the same C-order values; versions 1 and 2 (3 differs
    /// only in the header's encoding) read alike.
    #[test]
    fn npy_dtypes_and_orders() {
        let (d, y, x) = (2, 8, 9);
        let c = ramp(d * y * x);
        // Fortran order: element (k, i, j) at k + d (i + y j)
        let mut f = vec![0.0; c.len()];
        for k in 0..d {
            for i in 0..y {
                for j in 0..x {
                    f[k + d * (i + y * j)] = c[(k * y + i) * x + j];
                }
            }
        }
        for (descr, fortran, source) in
            [("<f8", false, &c), ("<f4", false, &c), (">f8", false, &c), (">f4", true, &f), ("<f8", true, &f)]
        {
            let data: Vec<u8> = source
                .iter()
                .flat_map(|&v| match descr {
                    "<f8" => v.to_le_bytes().to_vec(),
                    ">f8" => v.to_be_bytes().to_vec(),
                    "<f4" => (v as f32).to_le_bytes().to_vec(),
                    _ => (v as f32).to_be_bytes().to_vec(),
                })
                .collect();
            for version in [1, 2, 3] {
                let s = parse_npy(&npy(descr, fortran, &[d, y, x], &data, version)).unwrap();
                assert_eq!((s.depth, s.ny, s.nx), (d, y, x));
                assert_eq!(s.values, c, "{descr} fortran={fortran} v{version}");
            }
        }
        let two = parse_npy(&npy("<f8", false, &[y, x], &vec![0u8; y * x * 8], 1)).unwrap();
        assert_eq!(two.depth, 1);
    }

    /// Headers that cannot be a stack are refused with what is accepted, before any allocation
    /// for the data (a shape of 2^40 values in a 100-byte file).
    #[test]
    fn npy_refusals() {
        let err = |bytes: Vec<u8>| parse_npy(&bytes).unwrap_err();
        let e = err(npy("<i4", false, &[1, 8, 8], &[0; 256], 1));
        assert!(e.contains("dtype '<i4'") && e.contains("'<f8'"), "{e}");
        let e = err(npy("<f8", false, &[1 << 20, 1 << 10, 1 << 10], &[], 1));
        assert!(e.contains("more than 67108864 values"), "{e}");
        let e = err(npy("<f8", false, &[2, 8, 8], &[0; 100], 1));
        assert!(e.contains("100 bytes of data") && e.contains("expected 1024"), "{e}");
        let e = err(npy("<f8", false, &[8], &[0; 64], 1));
        assert!(e.contains("expected 3 axes"), "{e}");
        let e = err(npy("<f8", false, &[1, 4, 8], &[0; 256], 1));
        assert!(e.contains("at least 8 × 8"), "{e}");
        let mut v9 = npy("<f8", false, &[1, 8, 8], &[0; 512], 1);
        v9[6] = 9;
        assert!(err(v9).contains("version 9.0"));
        let mut bad = npy("<f8", false, &[1, 8, 8], &[0; 512], 1);
        bad[20] = b'#';
        assert!(err(bad).contains("malformed .npy header"));
        assert!(err(b"PK\x03\x04".to_vec()).contains("not a .npy file"));
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]
        /// Random bytes, and random headers (dtypes, orders, shapes up to 2^40 values, lengths
        /// that do not match) never panic: each is read or refused with a message; what is read
        /// has the shape its header gives.
        #[test]
        fn the_npy_reader_never_panics(
            raw in proptest::collection::vec(any::<u8>(), 0..300),
            descr in prop::sample::select(vec!["<f8", ">f4", "<i8", "|u1", "<f2", "f8", "<f8 "]),
            fortran in any::<bool>(),
            shape in proptest::collection::vec(0usize..(1 << 14), 0..5),
            extra in 0usize..20,
            version in 0u8..5,
            cut in 0usize..400,
        ) {
            match parse_npy(&raw) {
                Ok(s) => prop_assert_eq!(s.values.len(), s.depth * s.ny * s.nx),
                Err(e) => prop_assert!(!e.is_empty()),
            }
            let count: usize = shape.iter().product::<usize>().min(4096);
            let mut bytes = npy(descr, fortran, &shape, &vec![0u8; count * 4 + extra], version.max(1));
            bytes[6] = version;
            for candidate in [bytes.clone(), bytes[..cut.min(bytes.len())].to_vec()] {
                match parse_npy(&candidate) {
                    Ok(s) => {
                        prop_assert_eq!(s.values.len(), s.depth * s.ny * s.nx);
                        prop_assert!(s.values.len() <= candidate.len() / 4);
                    }
                    Err(e) => prop_assert!(!e.is_empty()),
                }
            }
        }
    }
}
