//! What can go wrong reading frames and measuring them: each message names the file, the
//! value and what is accepted.

use std::path::PathBuf;

/// An error of the `imaging` crate.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or decoded.
    #[error("{}: {message}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why (the decoder's or the system's words).
        message: String,
    },
    /// A frame that is not single-channel grayscale.
    #[error("{}: a {color} image; expected a grayscale frame (8- or 16-bit, no alpha): convert it, or export the camera's raw grey levels", path.display())]
    NotGrayscale {
        /// The file.
        path: PathBuf,
        /// Its colour type, as the PNG header says.
        color: String,
    },
    /// Frames of different sizes in one stack.
    #[error("{}: {width} × {height} pixels, but {} is {first_width} × {first_height}; every frame of a stack must have the same size", path.display(), first.display())]
    SizeMismatch {
        /// The frame that differs.
        path: PathBuf,
        /// Its width and height.
        width: usize,
        /// Its height.
        height: usize,
        /// The stack's first frame.
        first: PathBuf,
        /// The first frame's width.
        first_width: usize,
        /// The first frame's height.
        first_height: usize,
    },
    /// Frames of different bit depths in one stack (or between a stack and its capped black).
    #[error("{}: {bits}-bit, but {} is {first_bits}-bit; every frame of a stack must have the same bit depth (the grey levels of 8- and 16-bit files are on different scales)", path.display(), first.display())]
    DepthMismatch {
        /// The frame that differs.
        path: PathBuf,
        /// Its bits per sample.
        bits: u8,
        /// The stack's first frame.
        first: PathBuf,
        /// The first frame's bits per sample.
        first_bits: u8,
    },
    /// A file whose header asks for more pixels than a frame may have.
    #[error("{}: {width} × {height} pixels ({pixels} in all) is more than the {limit} pixels a {what} may have", path.display(), pixels = *width as u64 * *height as u64)]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its width, from its header.
        width: u32,
        /// Its height, from its header.
        height: u32,
        /// The most pixels accepted.
        limit: u64,
        /// `frame`, `target image` or `stack`.
        what: &'static str,
    },
    /// Fewer frames than a temporal standard deviation needs.
    #[error(
        "{what}: {frames} frame(s); at least 2 are needed for a temporal standard deviation (the paper grabbed 30)"
    )]
    TooFewFrames {
        /// Which stack.
        what: &'static str,
        /// How many frames it has.
        frames: usize,
    },
    /// A directory with no frame in it, or no input at all.
    #[error("{}: no frames found (give frame files, directories holding .png frames, or a pattern such as frames/*.png)", path.display())]
    NoFrames {
        /// The directory (or the empty argument list, as "").
        path: PathBuf,
    },
    /// A region written wrongly or lying outside the frames.
    #[error("{name} region `{text}`: {message}")]
    Region {
        /// `white`, `black`, or `capped-black`.
        name: &'static str,
        /// What was given.
        text: String,
        /// What is wrong and what is accepted.
        message: String,
    },
    /// The statistics refused the levels (no signal, no signal noise, …).
    #[error(transparent)]
    Statistics(#[from] noise::Error),
    /// A rendering that cannot be made (target, grid or scene out of range).
    #[error("render: {message}")]
    Render {
        /// What is wrong and what is accepted.
        message: String,
    },
    /// The scene could not be evaluated.
    #[error(transparent)]
    Scene(#[from] metric::Error),
    /// Frames too small for a noise power spectrum.
    #[error("{}: {width} × {height} pixels; a noise power spectrum needs frames of at least {min} × {min}", path.display())]
    TooSmall {
        /// The first frame.
        path: PathBuf,
        /// Its width.
        width: usize,
        /// Its height.
        height: usize,
        /// The least side accepted.
        min: usize,
    },
    /// A measured NEQ or capacity that the data do not define.
    #[error("noise power spectrum: {message}")]
    Measurement {
        /// Why, with the values.
        message: String,
    },
    /// A characterization series that cannot be fitted.
    #[error("camera characterization: {message}")]
    Characterization {
        /// What is wrong and what is needed.
        message: String,
    },
    /// A slanted-edge analysis that cannot be made (no edge, a saturated edge, an angle outside
    /// ISO 12233's range, …).
    #[error("{}: {message}", path.display())]
    Edge {
        /// The first frame (or what is wrong, e.g. `response`).
        path: PathBuf,
        /// What is wrong and what is accepted.
        message: String,
    },
    /// Capped-black levels at or above the levels they are subtracted from.
    #[error(
        "the capped black level {capped:.6} is not below the {region} level {level:.6}: the capped-black frames cannot be the camera's dark output for these frames"
    )]
    CappedBlack {
        /// The capped black level.
        capped: f64,
        /// `white` or `black`.
        region: &'static str,
        /// That region's level.
        level: f64,
    },
}
