//! Stacks of grayscale frames: 8- and 16-bit PNG (1-, 2- and 4-bit grey is expanded to 8-bit) and
//! TIFF (`.tif`, `.tiff`; also 32-bit floating point), grey levels as read (DN), no scaling.

use std::path::{Path, PathBuf};

use crate::Error;

/// One grayscale frame: `width × height` grey levels, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// The file it was read from.
    pub path: PathBuf,
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Bits per sample of the file: 8 or 16 (unsigned integers), 32 (a floating-point TIFF).
    pub bit_depth: u8,
    /// Grey levels, `data[y · width + x]`.
    pub data: Vec<f64>,
}

impl Frame {
    /// The grey level at column `x`, row `y` (from the top).
    pub fn at(&self, x: usize, y: usize) -> f64 {
        self.data[y * self.width + x]
    }
}

/// Reads one grayscale frame: PNG, or TIFF by the extension `.tif`/`.tiff`.
///
/// # Errors
/// [`Error::Read`] when the file cannot be opened or decoded, [`Error::NotGrayscale`] for a
/// colour, palette or alpha image.
pub fn read_frame(path: &Path) -> Result<Frame, Error> {
    let tiff = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff"));
    if tiff {
        return read_tiff(path);
    }
    let read = |message: String| Error::Read { path: path.to_owned(), message };
    // the size from the header's bytes, before the decoder allocates anything for it
    let (w, h) = png_dimensions(path)?;
    check_pixels(path, w, h, MAX_FRAME_PIXELS, "frame")?;
    let file = std::fs::File::open(path).map_err(|e| read(e.to_string()))?;
    // the decoder's own limit, raised to a 16-bit frame of the largest size accepted
    let limits = png::Limits { bytes: 2 * MAX_FRAME_PIXELS as usize + (1 << 20) };
    let mut decoder = png::Decoder::new_with_limits(std::io::BufReader::new(file), limits);
    // low bit depths to 8 bits; palettes would become RGB and are refused below
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| read(format!("not a PNG frame ({e})")))?;
    let (color, depth) = reader.output_color_type();
    if color != png::ColorType::Grayscale {
        return Err(Error::NotGrayscale { path: path.to_owned(), color: format!("{color:?}").to_lowercase() });
    }
    // the size was checked against the limit above, so it fits in memory (None: it overflows)
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| read(format!("{w} × {h} pixels: the decoded frame would not fit in memory")))?;
    let mut buffer = vec![0; size];
    let info = reader.next_frame(&mut buffer).map_err(|e| read(format!("cannot decode ({e})")))?;
    let (width, height) = (info.width as usize, info.height as usize);
    let data: Vec<f64> = match depth {
        png::BitDepth::Sixteen => {
            buffer[..info.buffer_size()].chunks_exact(2).map(|b| f64::from(u16::from_be_bytes([b[0], b[1]]))).collect()
        }
        _ => buffer[..info.buffer_size()].iter().map(|&b| f64::from(b)).collect(),
    };
    if data.len() != width * height {
        return Err(read(format!("{} samples for {width} × {height} pixels", data.len())));
    }
    let bit_depth = if depth == png::BitDepth::Sixteen { 16 } else { 8 };
    Ok(Frame { path: path.to_owned(), width, height, bit_depth, data })
}

/// The width and height a PNG file's header gives, read from its first 24 bytes (the signature
/// and the IHDR chunk, which the PNG standard puts first) without decoding anything.
///
/// # Errors
/// [`Error::Read`] when the file cannot be opened or does not start with a PNG signature and
/// its IHDR chunk.
pub fn png_dimensions(path: &Path) -> Result<(u32, u32), Error> {
    use std::io::Read as _;
    let read = |message: String| Error::Read { path: path.to_owned(), message };
    let mut file = std::fs::File::open(path).map_err(|e| read(e.to_string()))?;
    let mut head = [0u8; 24];
    let mut got = 0;
    while got < head.len() {
        match file.read(&mut head[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) => return Err(read(e.to_string())),
        }
    }
    if got < head.len() || head[..8] != *b"\x89PNG\r\n\x1a\n" || head[12..16] != *b"IHDR" {
        return Err(read(format!(
            "not a PNG ({got} bytes of the 24 of a PNG signature and IHDR header were found, or they differ)"
        )));
    }
    let word = |i: usize| u32::from_be_bytes([head[i], head[i + 1], head[i + 2], head[i + 3]]);
    Ok((word(16), word(20)))
}

/// Writes a grayscale PNG of `width × height` grey levels (row-major from the top-left), 8-bit
/// when every level is below 256 and `bit_depth` is 8, else 16-bit.
///
/// # Errors
/// [`Error::Read`] (naming the file) when it cannot be written, or the levels do not fill
/// `width × height`.
pub fn write_png(path: &Path, width: usize, height: usize, levels: &[u16], bit_depth: u8) -> Result<(), Error> {
    let fail = |message: String| Error::Read { path: path.to_owned(), message };
    if levels.len() != width * height || (bit_depth == 8 && levels.iter().any(|&v| v > 255)) {
        return Err(fail(format!("{} levels for {width} × {height} pixels at {bit_depth} bits", levels.len())));
    }
    let file = std::fs::File::create(path).map_err(|e| fail(format!("cannot write ({e})")))?;
    let (w, h) = (u32::try_from(width), u32::try_from(height));
    let (Ok(w), Ok(h)) = (w, h) else { return Err(fail(format!("{width} × {height} pixels: too large for PNG"))) };
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Grayscale);
    let bytes: Vec<u8> = if bit_depth == 8 {
        encoder.set_depth(png::BitDepth::Eight);
        levels.iter().map(|&v| v as u8).collect()
    } else {
        encoder.set_depth(png::BitDepth::Sixteen);
        levels.iter().flat_map(|v| v.to_be_bytes()).collect()
    };
    let mut writer = encoder.write_header().map_err(|e| fail(format!("cannot write ({e})")))?;
    writer.write_image_data(&bytes).map_err(|e| fail(format!("cannot write ({e})")))?;
    writer.finish().map_err(|e| fail(format!("cannot write ({e})")))
}

/// Reads one grayscale TIFF (8- or 16-bit unsigned or 32-bit float, first image of the file).
fn read_tiff(path: &Path) -> Result<Frame, Error> {
    use tiff::decoder::{Decoder, DecodingResult};
    let read = |message: String| Error::Read { path: path.to_owned(), message };
    let file = std::fs::File::open(path).map_err(|e| read(e.to_string()))?;
    let mut decoder =
        Decoder::new(std::io::BufReader::new(file)).map_err(|e| read(format!("not a TIFF frame ({e})")))?;
    let color = decoder.colortype().map_err(|e| read(format!("cannot decode ({e})")))?;
    let bit_depth = match color {
        tiff::ColorType::Gray(8) => 8,
        tiff::ColorType::Gray(16) => 16,
        // 32-bit samples: read below only as IEEE floats (e.g. a linear float export)
        tiff::ColorType::Gray(32) => 32,
        other => return Err(Error::NotGrayscale { path: path.to_owned(), color: format!("{other:?}").to_lowercase() }),
    };
    let (width, height) = decoder.dimensions().map_err(|e| read(format!("cannot decode ({e})")))?;
    check_pixels(path, width, height, MAX_FRAME_PIXELS, "frame")?;
    let data: Vec<f64> = match decoder.read_image().map_err(|e| read(format!("cannot decode ({e})")))? {
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F32(v) if bit_depth == 32 => {
            if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
                return Err(read(format!("a sample of {bad}: expected finite floating-point grey levels")));
            }
            v.into_iter().map(f64::from).collect()
        }
        _ => {
            return Err(read(
                "samples that are not 8- or 16-bit unsigned or 32-bit floating-point grey levels".to_owned(),
            ));
        }
    };
    let (width, height) = (width as usize, height as usize);
    if data.len() != width * height {
        return Err(read(format!("{} samples for {width} × {height} pixels", data.len())));
    }
    Ok(Frame { path: path.to_owned(), width, height, bit_depth, data })
}

/// Whether `name` matches `pattern`: `*` any run of characters, `?` one character.
fn matches(pattern: &[char], name: &[char]) -> bool {
    match (pattern.first(), name.first()) {
        (None, None) => true,
        (Some('*'), _) => matches(&pattern[1..], name) || (!name.is_empty() && matches(pattern, &name[1..])),
        (Some('?'), Some(_)) => matches(&pattern[1..], &name[1..]),
        (Some(p), Some(n)) if p == n => matches(&pattern[1..], &name[1..]),
        _ => false,
    }
}

/// The frame files of `inputs`: files as given, directories as their `.png`/`.tif(f)` files in name
/// order, and a file name with `*` or `?` (a glob the shell did not expand, e.g. quoted) as the
/// files of its directory that match it, in name order.
///
/// # Errors
/// [`Error::Read`] for a directory that cannot be listed, [`Error::NoFrames`] for a directory
/// or pattern without frames or no inputs at all.
pub fn frame_paths(inputs: &[PathBuf]) -> Result<Vec<PathBuf>, Error> {
    if inputs.is_empty() {
        return Err(Error::NoFrames { path: PathBuf::new() });
    }
    let mut out = Vec::new();
    for input in inputs {
        let name = input.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if !input.exists() && (name.contains('*') || name.contains('?')) {
            let dir = match input.parent() {
                Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
                _ => PathBuf::from("."),
            };
            let pattern: Vec<char> = name.chars().collect();
            let listing =
                std::fs::read_dir(&dir).map_err(|e| Error::Read { path: dir.clone(), message: e.to_string() })?;
            let mut found: Vec<PathBuf> = listing
                .filter_map(|entry| entry.ok().map(|e| e.path()))
                .filter(|p| {
                    p.is_file()
                        && p.file_name()
                            .is_some_and(|n| matches(&pattern, &n.to_string_lossy().chars().collect::<Vec<_>>()))
                })
                .collect();
            if found.is_empty() {
                return Err(Error::NoFrames { path: input.clone() });
            }
            found.sort();
            out.extend(found);
        } else if input.is_dir() {
            let listing =
                std::fs::read_dir(input).map_err(|e| Error::Read { path: input.clone(), message: e.to_string() })?;
            let mut found: Vec<PathBuf> = listing
                .filter_map(|entry| entry.ok().map(|e| e.path()))
                .filter(|p| {
                    p.extension().is_some_and(|e| ["png", "tif", "tiff"].iter().any(|x| e.eq_ignore_ascii_case(x)))
                })
                .collect();
            if found.is_empty() {
                return Err(Error::NoFrames { path: input.clone() });
            }
            found.sort();
            out.extend(found);
        } else {
            out.push(input.clone());
        }
    }
    Ok(out)
}

/// Reads a stack: every frame of `inputs` ([`frame_paths`]), all of the first one's size and bit
/// depth, at least two (`what` names the stack in the messages), at most [`MAX_STACK_SAMPLES`]
/// grey levels in all.
///
/// # Errors
/// Those of [`frame_paths`] and [`read_frame`], [`Error::SizeMismatch`],
/// [`Error::DepthMismatch`], [`Error::TooLarge`] and [`Error::TooFewFrames`].
pub fn read_stack(what: &'static str, inputs: &[PathBuf]) -> Result<Vec<Frame>, Error> {
    read_frames(what, inputs, 2)
}

/// [`read_stack`] with at least `min_frames` frames (1 for an edge image, whose standard error
/// can come from the ESF's bins).
///
/// # Errors
/// Those of [`read_stack`].
pub fn read_frames(what: &'static str, inputs: &[PathBuf], min_frames: usize) -> Result<Vec<Frame>, Error> {
    let paths = frame_paths(inputs)?;
    let mut frames: Vec<Frame> = Vec::with_capacity(paths.len().min(1024));
    let mut samples = 0_u64;
    for path in &paths {
        let frame = read_frame(path)?;
        if let Some(first) = frames.first() {
            same_format(first, &frame)?;
        }
        samples += (frame.width * frame.height) as u64;
        if samples > MAX_STACK_SAMPLES {
            return Err(Error::TooLarge {
                path: frame.path,
                width: frame.width as u32,
                height: frame.height as u32,
                limit: MAX_STACK_SAMPLES,
                what: "stack (all its frames together)",
            });
        }
        frames.push(frame);
    }
    if frames.len() < min_frames.max(1) {
        return Err(Error::TooFewFrames { what, frames: frames.len() });
    }
    Ok(frames)
}

/// The grey levels a stack may hold in all, 2²⁸ (2 GiB of `f64`): e.g. 30 frames of 8.9
/// megapixels.
pub const MAX_STACK_SAMPLES: u64 = 1 << 28;

/// The pixels a frame may have, 2²⁶ (67 megapixels, 512 MiB of `f64`), checked from the file's
/// header before anything is decoded.
pub const MAX_FRAME_PIXELS: u64 = 1 << 26;

/// Checks that `frame` has `first`'s size and bit depth.
///
/// # Errors
/// [`Error::SizeMismatch`] or [`Error::DepthMismatch`], naming both files.
pub fn same_format(first: &Frame, frame: &Frame) -> Result<(), Error> {
    if (first.width, first.height) != (frame.width, frame.height) {
        return Err(Error::SizeMismatch {
            path: frame.path.clone(),
            width: frame.width,
            height: frame.height,
            first: first.path.clone(),
            first_width: first.width,
            first_height: first.height,
        });
    }
    if first.bit_depth != frame.bit_depth {
        return Err(Error::DepthMismatch {
            path: frame.path.clone(),
            bits: frame.bit_depth,
            first: first.path.clone(),
            first_bits: first.bit_depth,
        });
    }
    Ok(())
}

/// Refuses a header of more than `limit` pixels, before any decoding.
pub(crate) fn check_pixels(path: &Path, width: u32, height: u32, limit: u64, what: &'static str) -> Result<(), Error> {
    if u64::from(width) * u64::from(height) > limit {
        return Err(Error::TooLarge { path: path.to_owned(), width, height, limit, what });
    }
    Ok(())
}
