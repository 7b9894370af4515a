//! The MTF from images of slanted edges: the e-SFR of ISO 12233 (the algorithm of its reference
//! implementation, sfrmat; docs/physics.md, "Slanted-edge MTF").
//!
//! A stack of frames (one or more) is dark-subtracted, linearized and averaged; the edges in the
//! region of interest are found from the gradient; for each edge:
//!
//! 1. per row (per column for a near-horizontal edge) the edge's position is the centroid of the
//!    derivative `(I[x+1] − I[x−1])/2`, first over the row, then under a Hamming window centred
//!    on the fitted edge; a straight (or 2nd-order) edge `x_e(y)` is fitted to them by least
//!    squares, twice;
//! 2. every pixel within a fixed reach of the edge is placed at its distance along the edge's
//!    normal, `n = (x − x_e(y)) cos θ`, and the distances are binned a quarter pixel wide (4×
//!    oversampled ESF); the rows used span a whole number of pixel phases (`rows · tan θ` whole);
//! 3. the LSF is the ESF's central difference, windowed by a Hamming window centred on its
//!    centroid; its Fourier transform at `f` (cycles per pixel along the normal) divided by its
//!    value at 0 is the MTF, divided by the transfer functions of the two filters the procedure
//!    applied: the central difference, `sin(2π f b)/(2π f b)`, and the bin's box, `sinc(f b)`,
//!    with `b` the bin width.
//!
//! The mean MTF to Nyquist is `2 ∫₀^½ MTF(f) df` (Simpson's rule on 50 intervals, each value the
//! transform itself, not an interpolation); MTF50 is located by bisection on the transform.
//!
//! Standard errors: with two or more frames, from the frames' spread (each frame's MTF through the
//! same fit, bins and window, projected on the mean's phase: `sd/√N`); with one frame, from the
//! scatter of the ESF samples in their bins about the binned ESF (linearly interpolated),
//! propagated linearly through the derivative, window, transform and normalization.

use std::path::PathBuf;

use num_complex::Complex64;
use serde::Serialize;

use crate::{Error, Frame, Region};

/// Bins per pixel along the edge's normal (ISO 12233: 4× oversampling).
pub const OVERSAMPLING: usize = 4;

/// The edge angles accepted, degrees off the nearest pixel axis: ISO 12233 asks for a slanted
/// edge (a few degrees; below 1° the rows do not sample the pixel phases, at 45° the two axes
/// are alike).
pub const ANGLE_RANGE_DEG: (f64, f64) = (1.0, 35.0);

/// The fraction of samples at the largest code of an integer frame above which the edge counts
/// as saturated (clipping flattens the ESF and raises the MTF).
pub const CLIPPED_LIMIT: f64 = 1e-3;

/// The distance along the normal analysed on each side of the edge, pixels, unless asked
/// otherwise: the LSF window's half-width. Wider windows keep more of a long LSF tail (a halo)
/// and let in more noise (the noise variance of the MTF grows with the window's length).
pub const DEFAULT_REACH_PX: f64 = 16.0;

/// Frequency step of the reported curve, cycles per pixel (50 steps to Nyquist).
pub const FREQUENCY_STEP: f64 = 0.01;

/// How the camera's grey levels (after the dark frame's subtraction) relate to exposure.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum Response {
    /// Proportional (a raw sensor).
    #[default]
    Linear,
    /// `DN − dark ∝ exposure^G` (G the log-log slope of the signal transfer, `asnr characterize`'s
    /// STF slope; 1/2.2 for a γ-2.2 encoding): exposure `∝ sign(v)|v|^(1/G)`.
    Gamma(f64),
    /// A measured transfer curve: grey levels above dark (increasing) and the exposures giving
    /// them (increasing, any unit), interpolated linearly through (0, 0); beyond the last point
    /// the last segment is extended.
    Table {
        /// Grey levels above dark, DN.
        dn: Vec<f64>,
        /// Exposure at each, any unit proportional to photons.
        exposure: Vec<f64>,
    },
}

impl Response {
    /// Checks the response's parameters.
    ///
    /// # Errors
    /// [`Error::Edge`] for a gamma that is not finite and > 0 or a table that does not increase.
    pub fn check(&self) -> Result<(), Error> {
        let bad = |message: String| Error::Edge { path: PathBuf::from("response"), message };
        match self {
            Response::Linear => Ok(()),
            Response::Gamma(g) if g.is_finite() && *g > 0.0 && *g <= 10.0 => Ok(()),
            Response::Gamma(g) => Err(bad(format!("gamma {g}: expected a finite exponent in (0, 10]"))),
            Response::Table { dn, exposure } => {
                if dn.len() != exposure.len() || dn.is_empty() {
                    return Err(bad(format!(
                        "a transfer curve of {} levels and {} exposures: expected as many of each, at least one",
                        dn.len(),
                        exposure.len()
                    )));
                }
                let mut last = (0.0, 0.0);
                for (&d, &e) in dn.iter().zip(exposure) {
                    if !(d.is_finite() && e.is_finite() && d > last.0 && e > last.1) {
                        return Err(bad(format!(
                            "transfer curve point ({d} DN above dark, exposure {e}) after ({}, {}): the levels above dark and the exposures must both increase from (0, 0)",
                            last.0, last.1
                        )));
                    }
                    last = (d, e);
                }
                Ok(())
            }
        }
    }

    /// The exposure of a grey level `v` above dark.
    pub fn linearize(&self, v: f64) -> f64 {
        match self {
            Response::Linear => v,
            Response::Gamma(g) => v.signum() * v.abs().powf(1.0 / g),
            Response::Table { dn, exposure } => {
                // segment i joins point i − 1 (point −1 = the origin) to point i
                let point = |i: usize| if i == 0 { (0.0, 0.0) } else { (dn[i - 1], exposure[i - 1]) };
                let n = dn.len();
                let i = dn.partition_point(|&d| d < v).min(n - 1);
                let (d0, e0) = point(i);
                let (d1, e1) = (dn[i], exposure[i]);
                e0 + (v - d0) * (e1 - e0) / (d1 - d0)
            }
        }
    }
}

/// What [`sfr`] is asked to do.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Region of interest (default: the whole frame).
    pub roi: Option<Region>,
    /// The camera's response.
    pub response: Response,
    /// Pixel pitch, m: adds cycles/mm to the report.
    pub pixel_pitch_m: Option<f64>,
    /// The fitted edge's polynomial degree, 1 (straight, default for 0) or 2.
    pub degree: usize,
    /// Distance along the normal analysed on each side of the edge, pixels (default
    /// [`DEFAULT_REACH_PX`]; less where the ROI's side or another edge is nearer).
    pub reach_px: Option<f64>,
}

/// Which pixel axis an edge runs along.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Orientation {
    /// Near vertical: the MTF is along the rows (x).
    Vertical,
    /// Near horizontal: the MTF is along the columns (y).
    Horizontal,
}

/// Where the standard errors come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Uncertainty {
    /// The spread of the frames' MTFs (two or more frames).
    Frames,
    /// The ESF samples' scatter in their bins (one frame).
    EsfBins,
}

/// One edge's e-SFR.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EdgeSfr {
    /// Which axis the edge runs along.
    pub orientation: Orientation,
    /// Angle off that axis, degrees (signed: positive when the edge's position grows along it).
    pub edge_angle_deg: f64,
    /// Where the fitted edge crosses the middle of the rows used, frame pixels (column, row).
    pub centre_px: [f64; 2],
    /// Rows (columns for a horizontal edge) used: a whole number of pixel phases.
    pub lines: usize,
    /// ESF samples used.
    pub samples: usize,
    /// Distance along the normal covered on each side of the edge, pixels.
    pub reach_px: f64,
    /// Mean linearized level on the dark and the bright side.
    pub levels: [f64; 2],
    /// Frequencies along the edge's normal, cycles per pixel, 0 to 1 in steps of 0.01.
    pub frequency_cyc_per_px: Vec<f64>,
    /// The same in cycles/mm, with a pixel pitch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_cyc_per_mm: Option<Vec<f64>>,
    /// The MTF at each frequency.
    pub mtf: Vec<f64>,
    /// Its standard error.
    pub mtf_sigma: Vec<f64>,
    /// Mean MTF from 0 to Nyquist (0.5 cycles/pixel): the ASNR's MTF factor (paper eq. 1).
    pub mean_mtf: f64,
    /// Its standard error.
    pub mean_mtf_sigma: f64,
    /// The first frequency where the MTF falls to 0.5, cycles per pixel (none if it stays above
    /// to 1 cycle/pixel).
    pub mtf50_cyc_per_px: Option<f64>,
    /// The same in cycles/mm, with a pixel pitch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mtf50_cyc_per_mm: Option<f64>,
    /// The MTF at Nyquist.
    pub mtf_nyquist: f64,
    /// Its standard error.
    pub mtf_nyquist_sigma: f64,
    /// Where the standard errors come from.
    pub uncertainty: Uncertainty,
}

/// What [`sfr`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Sfr {
    /// Frames averaged.
    pub frames: usize,
    /// Region of interest.
    pub roi: Region,
    /// Fraction of the samples at the largest code (integer frames).
    pub clipped_fraction: f64,
    /// Each edge, in the order of their position (left to right, then top to bottom).
    pub edges: Vec<EdgeSfr>,
}

impl Sfr {
    /// The one edge, when one is required (the measured ASNR's MTF).
    ///
    /// # Errors
    /// [`Error::Edge`] when the ROI held several edges, naming where each is.
    pub fn single(&self) -> Result<&EdgeSfr, Error> {
        match &self.edges[..] {
            [one] => Ok(one),
            edges => Err(Error::Edge {
                path: PathBuf::from(format!(
                    "ROI {},{},{},{}",
                    self.roi.x, self.roi.y, self.roi.width, self.roi.height
                )),
                message: format!(
                    "{} edges (at {}); one is required: give a ROI around one of them",
                    edges.len(),
                    edges
                        .iter()
                        .map(|e| format!("column {:.0}, row {:.0}", e.centre_px[0], e.centre_px[1]))
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
            }),
        }
    }
}

/// The e-SFR of every edge in `frames` (one or more, of one size and bit depth), after
/// subtracting `dark` (frames averaged per pixel) and linearizing by `options.response`.
///
/// # Errors
/// [`Error::TooFewFrames`] for no frames, [`Error::SizeMismatch`] / [`Error::DepthMismatch`]
/// between frames or with the dark frames, [`Error::Region`] for a ROI outside the frames or
/// smaller than 16 × 16, [`Error::Edge`] for a saturated edge, no edge, an edge at an angle
/// outside [`ANGLE_RANGE_DEG`] or one that does not cover the pixel phases.
pub fn sfr(frames: &[Frame], dark: &[Frame], options: &Options) -> Result<Sfr, Error> {
    let Some(first) = frames.first() else { return Err(Error::TooFewFrames { what: "edge frames", frames: 0 }) };
    for f in frames[1..].iter().chain(dark) {
        crate::frames::same_format(first, f)?;
    }
    options.response.check()?;
    let roi = options.roi.unwrap_or(Region { x: 0, y: 0, width: first.width, height: first.height });
    roi.check("ROI", first.width, first.height)?;
    if roi.width < 16 || roi.height < 16 {
        return Err(Error::Region {
            name: "ROI",
            text: format!("{},{},{},{}", roi.x, roi.y, roi.width, roi.height),
            message: "smaller than 16 × 16 pixels: an edge needs rows to fit and pixels on both sides".to_owned(),
        });
    }
    let edge_error = |message: String| Error::Edge { path: first.path.clone(), message };
    // saturation: samples at the largest code of an integer frame
    let clipped_fraction = if first.bit_depth <= 16 {
        let top = f64::from((1_u32 << first.bit_depth) - 1);
        let clipped = frames.iter().map(|f| roi_values(f, roi).filter(|&v| v >= top).count()).sum::<usize>();
        clipped as f64 / (frames.len() * roi.width * roi.height) as f64
    } else {
        0.0
    };
    if clipped_fraction > CLIPPED_LIMIT {
        return Err(edge_error(format!(
            "{:.2} % of the ROI's samples are at the largest code ({}), more than the {} % accepted: the edge is saturated (clipping flattens the bright side and inflates the MTF); lower the exposure",
            100.0 * clipped_fraction,
            (1_u32 << first.bit_depth) - 1,
            100.0 * CLIPPED_LIMIT
        )));
    }
    // dark level per pixel
    let dark_level: Vec<f64> = if dark.is_empty() {
        vec![0.0; roi.width * roi.height]
    } else {
        let mut sum = vec![0.0; roi.width * roi.height];
        for d in dark {
            for (s, v) in sum.iter_mut().zip(roi_values(d, roi)) {
                *s += v;
            }
        }
        sum.into_iter().map(|s| s / dark.len() as f64).collect()
    };
    let images: Vec<Vec<f64>> = frames
        .iter()
        .map(|f| roi_values(f, roi).zip(&dark_level).map(|(v, d)| options.response.linearize(v - d)).collect())
        .collect();
    let mut mean = vec![0.0; roi.width * roi.height];
    for image in &images {
        for (m, v) in mean.iter_mut().zip(image) {
            *m += v / images.len() as f64;
        }
    }
    let found = find_edges(&mean, roi.width, roi.height);
    if found.is_empty() {
        return Err(edge_error(format!(
            "ROI {},{},{},{}: no edge found (no line of strong gradient at least a quarter of the ROI long); give a ROI around one slanted edge",
            roi.x, roi.y, roi.width, roi.height
        )));
    }
    if let Some(problem) = separation_problem(&found, roi, options.reach_px.unwrap_or(DEFAULT_REACH_PX)) {
        return Err(edge_error(format!("ROI {},{},{},{}: {problem}", roi.x, roi.y, roi.width, roi.height)));
    }
    let mut edges = Vec::with_capacity(found.len());
    for (i, candidate) in found.iter().enumerate() {
        let others: Vec<&Candidate> = found.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, c)| c).collect();
        let edge = analyse(&images, &mean, roi, candidate, &others, options).map_err(|message| {
            edge_error(format!("ROI {},{},{},{}: {message}", roi.x, roi.y, roi.width, roi.height))
        })?;
        edges.push(edge);
    }
    Ok(Sfr { frames: frames.len(), roi, clipped_fraction, edges })
}

/// The grey levels of `frame` inside `roi`, row by row.
fn roi_values(frame: &Frame, roi: Region) -> impl Iterator<Item = f64> + '_ {
    (roi.y..roi.y + roi.height).flat_map(move |y| (roi.x..roi.x + roi.width).map(move |x| frame.at(x, y)))
}

/// An edge found in the ROI: the pixels of strong gradient along it.
#[derive(Clone, Debug)]
struct Candidate {
    orientation: Orientation,
    /// Per line (row for a vertical edge, column for a horizontal one, in the oriented image):
    /// the first and last across-position of the component's pixels, if any.
    span: Vec<Option<(usize, usize)>>,
    /// A rough straight line `across = a + b·along` through the component's pixels.
    line: (f64, f64),
    /// Lines where the component is not one edge's narrow band: wider than the median line by
    /// more than [`MIN_SEPARATION_PX`] (another edge runs across it) or split by a gap of two
    /// pixels or more (two edges side by side), with the first such line's (column, row).
    unseparated: (usize, [usize; 2]),
}

/// The least distance along their normals between two edges analysed in one ROI, pixels: each
/// keeps the half of the gap on its side, and an ESF needs at least 4 pixels on each side.
pub const MIN_SEPARATION_PX: f64 = 8.0;

/// Lines of a component that are not one edge's band before it counts as two edges that touch
/// or cross (one line can be noise; a crossing edge's band is two or more lines wide).
const UNSEPARATED_LINES: usize = 2;

/// The edges of `image` (`width × height`): 8-connected components of the pixels whose
/// smoothed gradient exceeds both a quarter of the largest and four times the median (the
/// noise's level), at least a quarter of the ROI (and 16 pixels) long.
fn find_edges(image: &[f64], width: usize, height: usize) -> Vec<Candidate> {
    let at = |x: usize, y: usize| image[y * width + x];
    let mut gx = vec![0.0; width * height];
    let mut gy = vec![0.0; width * height];
    for y in 1..height - 1 {
        for x in 1..width - 1 {
            gx[y * width + x] = (at(x + 1, y) - at(x - 1, y)) / 2.0;
            gy[y * width + x] = (at(x, y + 1) - at(x, y - 1)) / 2.0;
        }
    }
    // the magnitude of the 3 × 3 mean gradient
    let mut magnitude = vec![0.0; width * height];
    for y in 2..height - 2 {
        for x in 2..width - 2 {
            let (mut sx, mut sy) = (0.0, 0.0);
            for dy in 0..3 {
                for dx in 0..3 {
                    sx += gx[(y + dy - 1) * width + x + dx - 1];
                    sy += gy[(y + dy - 1) * width + x + dx - 1];
                }
            }
            magnitude[y * width + x] = (sx * sx + sy * sy).sqrt() / 9.0;
        }
    }
    let largest = magnitude.iter().copied().fold(0.0, f64::max);
    if largest.is_nan() || largest <= 0.0 {
        return Vec::new();
    }
    let mut sorted: Vec<f64> = magnitude.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let threshold = (0.25 * largest).max(4.0 * median);
    let strong: Vec<bool> = magnitude.iter().map(|&m| m > threshold).collect();
    let mut label = vec![usize::MAX; width * height];
    let mut out = Vec::new();
    for start in 0..width * height {
        if !strong[start] || label[start] != usize::MAX {
            continue;
        }
        let id = start;
        let mut stack = vec![start];
        label[start] = id;
        let mut pixels = Vec::new();
        while let Some(p) = stack.pop() {
            pixels.push(p);
            let (x, y) = ((p % width) as isize, (p / width) as isize);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= width as isize || ny >= height as isize {
                        continue;
                    }
                    let q = ny as usize * width + nx as usize;
                    if strong[q] && label[q] == usize::MAX {
                        label[q] = id;
                        stack.push(q);
                    }
                }
            }
        }
        let (mut x0, mut x1, mut y0, mut y1) = (usize::MAX, 0, usize::MAX, 0);
        let (mut sgx, mut sgy) = (0.0_f64, 0.0_f64);
        for &p in &pixels {
            let (x, y) = (p % width, p / width);
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            sgx += gx[p].abs();
            sgy += gy[p].abs();
        }
        // the gradient across a near-vertical edge is mostly along x
        let orientation = if sgx >= sgy { Orientation::Vertical } else { Orientation::Horizontal };
        let (along_len, roi_len, lines) = match orientation {
            Orientation::Vertical => (y1 - y0 + 1, height, height),
            Orientation::Horizontal => (x1 - x0 + 1, width, width),
        };
        if along_len < 16.max(roi_len / 4) {
            continue;
        }
        let mut span: Vec<Option<(usize, usize)>> = vec![None; lines];
        for &p in &pixels {
            let (along, across) = match orientation {
                Orientation::Vertical => (p / width, p % width),
                Orientation::Horizontal => (p % width, p / width),
            };
            span[along] = Some(match span[along] {
                None => (across, across),
                Some((a, b)) => (a.min(across), b.max(across)),
            });
        }
        let points: Vec<(f64, f64)> =
            span.iter().enumerate().filter_map(|(i, s)| s.map(|(a, b)| (i as f64, (a + b) as f64 / 2.0))).collect();
        let Some(coefficients) = fit_polynomial(&points, 1) else { continue };
        let across_gradient = match orientation {
            Orientation::Vertical => &gx,
            Orientation::Horizontal => &gy,
        };
        let unseparated = unseparated_lines(&pixels, &span, width, orientation, across_gradient);
        out.push(Candidate { orientation, span, line: (coefficients[0], coefficients[1]), unseparated });
    }
    out.sort_by(|a, b| {
        let key = |c: &Candidate| (c.orientation == Orientation::Horizontal, c.line.0);
        key(a).partial_cmp(&key(b)).unwrap_or(std::cmp::Ordering::Equal)
    });
    out
}

/// How many lines of a component (its `pixels`, `span` per line) are not one edge's narrow band,
/// and where the first of them is (column, row of its middle): wider than the median line by
/// more than [`MIN_SEPARATION_PX`], with fewer pixels than its span less one (a gap of two or
/// more pixels between two bands), or holding both signs of the gradient across the edge
/// (`across`), each at least half the line's largest (two edges of opposite contrast merged,
/// as the two sides of a narrow bar; one edge's band has one sign).
fn unseparated_lines(
    pixels: &[usize],
    span: &[Option<(usize, usize)>],
    width: usize,
    orientation: Orientation,
    across: &[f64],
) -> (usize, [usize; 2]) {
    let mut count = vec![0_usize; span.len()];
    let mut largest = vec![0.0_f64; span.len()];
    let along_of = |p: usize| match orientation {
        Orientation::Vertical => p / width,
        Orientation::Horizontal => p % width,
    };
    for &p in pixels {
        count[along_of(p)] += 1;
        largest[along_of(p)] = largest[along_of(p)].max(across[p].abs());
    }
    // [positive, negative] lobes at least half the line's largest
    let mut signs = vec![[false; 2]; span.len()];
    for &p in pixels {
        let l = along_of(p);
        if across[p].abs() >= 0.5 * largest[l] && largest[l] > 0.0 {
            signs[l][usize::from(across[p] < 0.0)] = true;
        }
    }
    let mut widths: Vec<usize> = span.iter().flatten().map(|(a, b)| b - a + 1).collect();
    widths.sort_unstable();
    let median = widths.get(widths.len() / 2).copied().unwrap_or(0) as f64;
    let mut found = 0;
    let mut first = [0, 0];
    for (along, s) in span.iter().enumerate() {
        let Some((a, b)) = *s else { continue };
        let w = b - a + 1;
        if w as f64 > median + MIN_SEPARATION_PX || count[along] + 1 < w || signs[along] == [true, true] {
            if found == 0 {
                let across = (a + b) / 2;
                first = match orientation {
                    Orientation::Vertical => [across, along],
                    Orientation::Horizontal => [along, across],
                };
            }
            found += 1;
        }
    }
    (found, first)
}

/// Why the edges `found` in `roi` cannot each be analysed apart, if they cannot: a component
/// that holds two edges touching or crossing, two edges along one axis that cross inside the
/// ROI or come closer than [`MIN_SEPARATION_PX`] along their normal, or two edges along
/// different axes whose bands, each widened by the `reach` its ESF takes, meet (one would run
/// through the other's ESF).
fn separation_problem(found: &[Candidate], roi: Region, reach: f64) -> Option<String> {
    let at = |c: &Candidate| -> [f64; 2] {
        let lines: Vec<usize> = c.span.iter().enumerate().filter_map(|(l, s)| s.map(|_| l)).collect();
        let mid = (lines[0] + lines[lines.len() - 1]) as f64 / 2.0;
        let across = c.line.0 + c.line.1 * mid;
        let (x, y) = match c.orientation {
            Orientation::Vertical => (across, mid),
            Orientation::Horizontal => (mid, across),
        };
        [x + roi.x as f64, y + roi.y as f64]
    };
    let name = |c: &Candidate| {
        let [x, y] = at(c);
        let axis = match c.orientation {
            Orientation::Vertical => "near-vertical",
            Orientation::Horizontal => "near-horizontal",
        };
        format!("a {axis} edge at column {x:.0}, row {y:.0}")
    };
    let fix = "give a ROI (--roi X,Y,W,H) around one edge, away from the other";
    for c in found {
        if c.unseparated.0 >= UNSEPARATED_LINES {
            let [x, y] = c.unseparated.1;
            return Some(format!(
                "two edges touch or cross near column {}, row {}: {} lines of strong gradient from there on are not one edge's band (wider than the others by more than {MIN_SEPARATION_PX} pixels, two bands side by side, or both contrasts in one band), so neither edge's ESF can be taken apart from the other's; {fix}",
                x + roi.x,
                y + roi.y,
                c.unseparated.0
            ));
        }
    }
    for (i, a) in found.iter().enumerate() {
        for b in &found[i + 1..] {
            let lines = |c: &Candidate| {
                let l: Vec<usize> = c.span.iter().enumerate().filter_map(|(l, s)| s.map(|_| l)).collect();
                (l[0], l[l.len() - 1])
            };
            let ((a0, a1), (b0, b1)) = (lines(a), lines(b));
            if a.orientation == b.orientation {
                // their separation along the normal over the lines both cover
                let (lo, hi) = (a0.max(b0), a1.min(b1));
                if lo > hi {
                    continue;
                }
                let gap = |l: usize| {
                    let t = l as f64;
                    let slope = (a.line.1 + b.line.1) / 2.0;
                    (b.line.0 + b.line.1 * t - a.line.0 - a.line.1 * t) / (1.0 + slope * slope).sqrt()
                };
                let (g0, g1) = (gap(lo), gap(hi));
                if g0.signum() != g1.signum() {
                    return Some(format!("{} and {} cross inside the ROI; {fix}", name(a), name(b)));
                }
                let least = g0.abs().min(g1.abs());
                if least < MIN_SEPARATION_PX {
                    return Some(format!(
                        "{} and {} are {least:.1} pixels apart along their normal, less than the {MIN_SEPARATION_PX} pixels two ESFs need (4 on each side of each edge); {fix}",
                        name(a),
                        name(b)
                    ));
                }
            } else {
                // different axes: the bands' boxes, each widened by the ESF's reach, must not meet
                let bbox = |c: &Candidate, l0: usize, l1: usize| -> [f64; 4] {
                    let across = c.span.iter().flatten();
                    let lo = across.clone().map(|s| s.0).min().unwrap_or(0) as f64 - reach;
                    let hi = across.map(|s| s.1).max().unwrap_or(0) as f64 + reach;
                    match c.orientation {
                        Orientation::Vertical => [lo, hi, l0 as f64, l1 as f64],
                        Orientation::Horizontal => [l0 as f64, l1 as f64, lo, hi],
                    }
                };
                let (p, q) = (bbox(a, a0, a1), bbox(b, b0, b1));
                if p[0] <= q[1] && q[0] <= p[1] && p[2] <= q[3] && q[2] <= p[3] {
                    return Some(format!("{} and {} meet: one runs through the other's ESF; {fix}", name(a), name(b)));
                }
            }
        }
    }
    None
}

/// Least-squares polynomial `c₀ + c₁ t + c₂ t² …` of `degree` through `(t, value)` points
/// (`None` when there are too few or they do not determine it).
fn fit_polynomial(points: &[(f64, f64)], degree: usize) -> Option<Vec<f64>> {
    if points.len() <= degree {
        return None;
    }
    // centred and scaled abscissae keep the normal equations well conditioned
    let mid = points.iter().map(|p| p.0).sum::<f64>() / points.len() as f64;
    let scale = points.iter().map(|p| (p.0 - mid).abs()).fold(0.0, f64::max).max(1.0);
    let a = nalgebra::DMatrix::from_fn(points.len(), degree + 1, |i, j| ((points[i].0 - mid) / scale).powi(j as i32));
    let b = nalgebra::DVector::from_iterator(points.len(), points.iter().map(|p| p.1));
    let solution = a.svd(true, true).solve(&b, 1e-12).ok()?;
    // back to powers of t: Σ s_j ((t − mid)/scale)^j
    let mut out = vec![0.0; degree + 1];
    for (j, s) in solution.iter().enumerate() {
        // binomial expansion of (t − mid)^j / scale^j
        let mut binomial = 1.0;
        for (k, o) in out.iter_mut().enumerate().take(j + 1) {
            *o += s * binomial * (-mid).powi((j - k) as i32) / scale.powi(j as i32);
            binomial *= (j - k) as f64 / (k + 1) as f64;
        }
    }
    out.iter().all(|c| c.is_finite()).then_some(out)
}

/// The polynomial's value at `t`.
fn polynomial(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * t + k)
}

/// Its slope at `t`.
fn polynomial_slope(c: &[f64], t: f64) -> f64 {
    c.iter().enumerate().skip(1).rev().fold(0.0, |acc, (j, &k)| acc * t + j as f64 * k)
}

/// Hamming window of half-width `half` at offset `d` from its centre (0 beyond).
fn hamming(d: f64, half: f64) -> f64 {
    if d.abs() >= half { 0.0 } else { 0.54 + 0.46 * (std::f64::consts::PI * d / half).cos() }
}

/// The LSF's window: flat over the middle half of `±half`, a Hamming taper over the outer
/// halves (0.08 at the ends). A Hamming window over the whole `±half` droops by
/// `0.23 (π d/half)²` near the middle, which narrows a wide LSF and raises its MTF (+0.5 % on
/// the mean MTF of a σ = 1.2 px Gaussian in ±32 px, measured by the tests' exact edges).
fn tapered(d: f64, half: f64) -> f64 {
    let flat = half / 2.0;
    if d.abs() <= flat { 1.0 } else { hamming(d.abs() - flat, half - flat) }
}

/// The MTF divided by the transfer functions of the ESF's bin (box of width `b`) and the
/// central difference over two bins: `sinc(f b) · sin(2π f b)/(2π f b)`.
pub fn filter_transfer(frequency_cyc_per_px: f64, bin_px: f64) -> f64 {
    let sinc = |x: f64| if x.abs() < 1e-8 { 1.0 - x * x / 6.0 } else { x.sin() / x };
    let x = std::f64::consts::PI * frequency_cyc_per_px * bin_px;
    sinc(x) * sinc(2.0 * x)
}

/// Analyses one edge; the message says what went wrong.
fn analyse(
    images: &[Vec<f64>],
    mean: &[f64],
    roi: Region,
    edge: &Candidate,
    others: &[&Candidate],
    options: &Options,
) -> Result<EdgeSfr, String> {
    let (w, h) = (roi.width, roi.height);
    // the oriented image: lines along the edge, positions across it
    let (lines_n, across_n) = match edge.orientation {
        Orientation::Vertical => (h, w),
        Orientation::Horizontal => (w, h),
    };
    let orient = |image: &[f64]| -> Vec<f64> {
        match edge.orientation {
            Orientation::Vertical => image.to_vec(),
            Orientation::Horizontal => {
                let mut t = vec![0.0; w * h];
                for y in 0..h {
                    for x in 0..w {
                        t[x * h + y] = image[y * w + x];
                    }
                }
                t
            }
        }
    };
    let image = orient(mean);
    let at = |line: usize, pos: usize| image[line * across_n + pos];
    // lines the edge crosses, two trimmed at each end (its corners)
    let lines: Vec<usize> = (0..lines_n).filter(|&l| edge.span[l].is_some()).collect();
    let (first_line, last_line) = (lines[0] + 2, lines[lines.len() - 1].saturating_sub(2));
    if last_line < first_line + 16 {
        return Err("the edge crosses fewer than 16 rows".to_owned());
    }
    // the other edges' rough lines bound each line's search
    let other_lines: Vec<(f64, f64)> =
        others.iter().filter(|o| o.orientation == edge.orientation).map(|o| o.line).collect();
    let bounds = |line: usize, centre: f64| -> (usize, usize) {
        let (mut lo, mut hi) = (1.0_f64, (across_n - 2) as f64);
        for (a, b) in &other_lines {
            let x = a + b * line as f64;
            if x < centre {
                lo = lo.max((x + centre) / 2.0);
            } else {
                hi = hi.min((x + centre) / 2.0);
            }
        }
        (lo.ceil().max(1.0) as usize, (hi.floor() as usize).min(across_n - 2))
    };
    let derivative = |line: usize, pos: usize| (at(line, pos + 1) - at(line, pos - 1)) / 2.0;
    // the derivative's sign: dark to bright along +x is positive
    let sign = {
        let s: f64 = (first_line..=last_line)
            .map(|l| {
                let c = edge.line.0 + edge.line.1 * l as f64;
                let (lo, hi) = bounds(l, c);
                (lo..=hi).map(|p| derivative(l, p)).sum::<f64>()
            })
            .sum();
        if s >= 0.0 { 1.0 } else { -1.0 }
    };
    let degree = options.degree.clamp(1, 2);
    // centroids: first under a window of the rough line, then twice under one of the fit
    let mut fit = vec![edge.line.0, edge.line.1];
    let mut half_window = (across_n as f64 / 4.0).max(8.0);
    for pass in 0..3 {
        let mut points = Vec::new();
        for l in first_line..=last_line {
            let centre = polynomial(&fit, l as f64);
            let (lo, hi) = bounds(l, centre);
            let (mut s0, mut s1) = (0.0, 0.0);
            for p in lo..=hi {
                let weight = hamming(p as f64 - centre, half_window);
                let d = sign * derivative(l, p) * weight;
                s0 += d;
                s1 += d * p as f64;
            }
            if s0 > 0.0 {
                points.push((l as f64, s1 / s0));
            }
        }
        fit = fit_polynomial(&points, if pass == 0 { 1 } else { degree })
            .ok_or_else(|| "the edge's positions cannot be fitted (too few rows with an edge)".to_owned())?;
        half_window = (across_n as f64 / 8.0).clamp(8.0, 32.0);
    }
    let mid_line = (first_line + last_line) as f64 / 2.0;
    let slope = polynomial_slope(&fit, mid_line);
    let angle = slope.atan().to_degrees();
    let (axis, other_axis) = match edge.orientation {
        Orientation::Vertical => ("vertical", "horizontal"),
        Orientation::Horizontal => ("horizontal", "vertical"),
    };
    if !(ANGLE_RANGE_DEG.0..=ANGLE_RANGE_DEG.1).contains(&angle.abs()) {
        return Err(format!(
            "the edge is {:.2}° off {axis}; ISO 12233 slanted-edge analysis needs {}° to {}° off the vertical or horizontal (a few degrees is best): {}",
            angle.abs(),
            ANGLE_RANGE_DEG.0,
            ANGLE_RANGE_DEG.1,
            if angle.abs() < ANGLE_RANGE_DEG.0 {
                "the rows would not sample the pixel's phases — tilt the edge"
            } else {
                "near 45° the edge's normal is as much along one pixel axis as the other — turn it toward the vertical or the horizontal"
            }
        ));
    }
    let _ = other_axis;
    // the lines used: a whole number of pixel phases, |tan θ| × lines a whole number
    let all = last_line - first_line + 1;
    let phases = (all as f64 * slope.abs()).floor();
    if phases < 1.0 {
        return Err(format!(
            "the edge moves {:.2} pixels over its {all} rows at {angle:.2}°: less than a pixel, so the rows do not sample the pixel's phases; use a longer edge or a larger angle",
            all as f64 * slope.abs()
        ));
    }
    let used = ((phases / slope.abs()).round() as usize).clamp(1, all);
    let first_line = first_line + (all - used) / 2;
    let last_line = first_line + used - 1;
    // reach along the normal: as far as every used line allows, 4 to 32 pixels
    let cos_at = |l: f64| 1.0 / (1.0 + polynomial_slope(&fit, l).powi(2)).sqrt();
    let mut reach = f64::INFINITY;
    for l in first_line..=last_line {
        let centre = polynomial(&fit, l as f64);
        let (lo, hi) = bounds(l, centre);
        reach = reach.min((centre - lo as f64).min(hi as f64 - centre) * cos_at(l as f64));
    }
    // quarter-pixel bins of the offset along the line (x − x_e), as sfrmat: each bin then
    // holds the pixel phases evenly; along the normal they are cos θ / 4 wide
    let cos_mid = cos_at(mid_line);
    let bin = cos_mid / OVERSAMPLING as f64;
    let reach = (reach.min(options.reach_px.unwrap_or(DEFAULT_REACH_PX)) / bin).floor() * bin;
    if reach.is_nan() || reach < 4.0 {
        return Err(format!(
            "the edge comes within {reach:.1} pixels of the ROI's side or of another edge: at least 4 pixels of each side are needed (ISO 12233 suggests more); widen the ROI"
        ));
    }
    let bins = (2.0 * reach / bin).round() as usize;
    let oriented: Vec<Vec<f64>> =
        if images.len() > 1 { images.iter().map(|i| orient(i)).collect() } else { Vec::new() };
    let mut count = vec![0_usize; bins];
    let mut sum = vec![0.0; bins];
    let mut frame_sums = vec![vec![0.0; bins]; oriented.len()];
    let mut samples: Vec<(f64, f64)> = Vec::new();
    for l in first_line..=last_line {
        let centre = polynomial(&fit, l as f64);
        let c = cos_mid;
        let lo = (centre - reach / c - 1.0).floor().max(0.0) as usize;
        let hi = ((centre + reach / c + 1.0).ceil() as usize).min(across_n - 1);
        for p in lo..=hi {
            let n = (p as f64 - centre) * c;
            let k = ((n + reach) / bin + 1e-9).floor();
            if k < 0.0 || k >= bins as f64 {
                continue;
            }
            let k = k as usize;
            let v = at(l, p);
            count[k] += 1;
            sum[k] += v;
            for (s, o) in frame_sums.iter_mut().zip(&oriented) {
                s[k] += o[l * across_n + p];
            }
            samples.push((n, v));
        }
    }
    if let Some(empty) = count.iter().position(|&c| c == 0) {
        return Err(format!(
            "the ESF's bin at {:.2} pixels from the edge is empty: the edge at {angle:.2}° does not spread the rows over the pixel's phases (a tangent near a simple fraction such as 1/2 or 1/3); change the angle a little",
            (empty as f64 + 0.5) * bin - reach
        ));
    }
    let centres: Vec<f64> = (0..bins).map(|k| (k as f64 + 0.5) * bin - reach).collect();
    let esf: Vec<f64> = sum.iter().zip(&count).map(|(s, &c)| s / c as f64).collect();
    let side = (bins / 8).max(1);
    let levels = {
        let m = |r: &[f64]| r.iter().sum::<f64>() / r.len() as f64;
        let (a, b) = (m(&esf[..side]), m(&esf[bins - side..]));
        if sign > 0.0 { [a, b] } else { [b, a] }
    };
    // the LSF on bins 1 … bins − 2, its window centred on its centroid
    let lsf_of = |e: &[f64]| -> Vec<f64> { (1..bins - 1).map(|k| (e[k + 1] - e[k - 1]) / 2.0).collect() };
    let positions = &centres[1..bins - 1];
    let lsf = lsf_of(&esf);
    let total: f64 = lsf.iter().sum();
    if total.is_nan() || total == 0.0 {
        return Err("no step across the edge".to_owned());
    }
    let centroid = lsf.iter().zip(positions).map(|(v, n)| v * n).sum::<f64>() / total;
    let centroid = if centroid.is_finite() { centroid.clamp(-reach / 2.0, reach / 2.0) } else { 0.0 };
    let half = reach - centroid.abs();
    let window: Vec<f64> = positions.iter().map(|n| tapered(n - centroid, half)).collect();
    let transform = |l: &[f64], f: f64| -> Complex64 {
        l.iter()
            .zip(&window)
            .zip(positions)
            .map(|((v, wk), n)| Complex64::from_polar(v * wk, -2.0 * std::f64::consts::PI * f * n))
            .sum()
    };
    let zero = transform(&lsf, 0.0);
    let mtf_at = |f: f64| (transform(&lsf, f).norm() / zero.norm()) / filter_transfer(f, bin);
    let frequencies: Vec<f64> = (0..=100).map(|j| j as f64 * FREQUENCY_STEP).collect();
    let nyquist_index = 50;
    let mtf: Vec<f64> = frequencies.iter().map(|&f| mtf_at(f)).collect();
    let simpson = |values: &[f64]| -> f64 {
        // 2 ∫₀^½ over 50 intervals of 0.01
        let s: f64 = (0..=nyquist_index)
            .map(|j| {
                let weight = if j == 0 || j == nyquist_index {
                    1.0
                } else if j % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                weight * values[j]
            })
            .sum();
        2.0 * s * FREQUENCY_STEP / 3.0
    };
    let mean_mtf = simpson(&mtf);
    // MTF50 by bisection between the grid points bracketing the first fall below 0.5
    let mtf50 = mtf.windows(2).position(|p| p[0] >= 0.5 && p[1] < 0.5).map(|j| {
        let (mut lo, mut hi) = (frequencies[j], frequencies[j + 1]);
        for _ in 0..40 {
            let m = (lo + hi) / 2.0;
            if mtf_at(m) >= 0.5 { lo = m } else { hi = m }
        }
        (lo + hi) / 2.0
    });
    // standard errors
    let (mtf_sigma, mean_mtf_sigma, uncertainty) = if oriented.len() > 1 {
        let phase: Vec<Complex64> = frequencies.iter().map(|&f| transform(&lsf, f)).map(|o| o / o.norm()).collect();
        let per_frame: Vec<Vec<f64>> = frame_sums
            .iter()
            .map(|s| {
                let e: Vec<f64> = s.iter().zip(&count).map(|(s, &c)| s / c as f64).collect();
                let l = lsf_of(&e);
                let z = transform(&l, 0.0);
                frequencies
                    .iter()
                    .zip(&phase)
                    .map(|(&f, u)| (u.conj() * transform(&l, f)).re / z.re.abs() / filter_transfer(f, bin))
                    .collect()
            })
            .collect();
        let n = per_frame.len() as f64;
        let sd = |values: &[f64]| {
            let m = values.iter().sum::<f64>() / n;
            (values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / n.sqrt()
        };
        let sigma: Vec<f64> =
            (0..frequencies.len()).map(|j| sd(&per_frame.iter().map(|m| m[j]).collect::<Vec<_>>())).collect();
        let means: Vec<f64> = per_frame.iter().map(|m| simpson(m)).collect();
        (sigma, sd(&means), Uncertainty::Frames)
    } else {
        // each bin's variance from its samples' scatter about the interpolated ESF
        let interpolate = |n: f64| {
            let t = ((n + reach) / bin - 0.5).clamp(0.0, (bins - 1) as f64);
            let k = (t.floor() as usize).min(bins - 2);
            let u = t - k as f64;
            esf[k] * (1.0 - u) + esf[k + 1] * u
        };
        let mut squares = vec![0.0; bins];
        for &(n, v) in &samples {
            let k = (((n + reach) / bin).floor() as usize).min(bins - 1);
            squares[k] += (v - interpolate(n)).powi(2);
        }
        // pooled over ±2 bins (single bins hold few samples), per sample; over the bin's count
        let variance: Vec<f64> = (0..bins)
            .map(|k| {
                let range = k.saturating_sub(2)..(k + 3).min(bins);
                let (s, c): (f64, usize) =
                    range.map(|j| (squares[j], count[j])).fold((0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
                let per_sample = if c > 1 { s / (c - 1) as f64 } else { 0.0 };
                per_sample / count[k] as f64
            })
            .collect();
        // M(f) = |O(f)|/|O(0)|/T(f); ∂O(f)/∂E_k from L_j = (E_{j+1} − E_{j−1})/2 on bins 1 … bins − 2
        let basis = |j: usize, f: f64| -> Complex64 {
            Complex64::from_polar(window[j], -2.0 * std::f64::consts::PI * f * positions[j])
        };
        let d_transform = |k: usize, f: f64| -> Complex64 {
            // E_k is in L at bin k − 1 (index k − 2, + ½) and at bin k + 1 (index k, − ½)
            let mut d = Complex64::new(0.0, 0.0);
            if (2..bins).contains(&k) && k - 2 < positions.len() {
                d += 0.5 * basis(k - 2, f);
            }
            if k < positions.len() {
                d -= 0.5 * basis(k, f);
            }
            d
        };
        let o: Vec<Complex64> = frequencies.iter().map(|&f| transform(&lsf, f)).collect();
        let gradient = |k: usize| -> Vec<f64> {
            let d0 = d_transform(k, 0.0);
            let dz = (zero.conj() * d0).re / zero.norm();
            frequencies
                .iter()
                .zip(&o)
                .map(|(&f, of)| {
                    let d = d_transform(k, f);
                    let dn = (of.conj() * d).re / of.norm().max(f64::MIN_POSITIVE);
                    (dn * zero.norm() - of.norm() * dz) / zero.norm().powi(2) / filter_transfer(f, bin)
                })
                .collect()
        };
        let mut var = vec![0.0; frequencies.len()];
        let mut var_mean = 0.0;
        for (k, v) in variance.iter().enumerate() {
            let g = gradient(k);
            for (s, gj) in var.iter_mut().zip(&g) {
                *s += v * gj * gj;
            }
            var_mean += v * simpson(&g).powi(2);
        }
        (var.into_iter().map(f64::sqrt).collect(), var_mean.sqrt(), Uncertainty::EsfBins)
    };
    let to_mm = |f: f64| options.pixel_pitch_m.map(|p| f / (p * 1e3));
    let (cx, cy) = {
        let across = polynomial(&fit, mid_line);
        match edge.orientation {
            Orientation::Vertical => (roi.x as f64 + across, roi.y as f64 + mid_line),
            Orientation::Horizontal => (roi.x as f64 + mid_line, roi.y as f64 + across),
        }
    };
    if mtf.iter().chain(&mtf_sigma).any(|v| !v.is_finite()) {
        return Err("the MTF is not finite (no step across the edge)".to_owned());
    }
    Ok(EdgeSfr {
        orientation: edge.orientation,
        edge_angle_deg: angle,
        centre_px: [cx, cy],
        lines: used,
        samples: samples.len(),
        reach_px: reach,
        levels,
        frequency_cyc_per_mm: options.pixel_pitch_m.map(|_| frequencies.iter().filter_map(|&f| to_mm(f)).collect()),
        frequency_cyc_per_px: frequencies,
        mtf_nyquist: mtf[nyquist_index],
        mtf_nyquist_sigma: mtf_sigma[nyquist_index],
        mtf,
        mtf_sigma,
        mean_mtf,
        mean_mtf_sigma,
        mtf50_cyc_per_mm: mtf50.and_then(to_mm),
        mtf50_cyc_per_px: mtf50,
        uncertainty,
    })
}
