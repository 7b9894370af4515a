//! Test objects for the forward model: a procedural USAF-1951 resolution target, or a user's
//! grayscale PNG.
//!
//! The target is drawn in the detector plane (its bar frequencies are given at the detector, in
//! cycles/mm) on a grid `oversample` times finer than the pixels, each fine cell holding the
//! exact fraction of its area that the bars cover (axis-aligned rectangles), so that no edge is
//! aliased before the optics blur it.
//!
//! USAF-1951 (MIL-STD-150A): element `e` of group `g` has `2^(g + (e − 1)/6)` line pairs per mm;
//! each element is two sets of three bars, one with the bars vertical (its frequency along x) and
//! one with them horizontal (along y); a bar is `w = 1/(2f)` wide and `5w` long, the bars `w`
//! apart. The layout here is simpler than the printed target's spiral: one column per group,
//! coarsest on the left, its six elements from the top, and beside the groups a white and a black
//! square (the paper's white and black areas, where eq. 2–4 are measured).

use std::path::Path;

use serde::Serialize;

use crate::{Error, Region};

/// Bright bars on a dark ground, or dark bars on a bright ground.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Polarity {
    /// Dark (chrome) bars on a clear ground: the usual printed target.
    Positive,
    /// Clear bars on a dark ground: a back-lit chrome target with the bars etched out.
    Negative,
}

/// Which way a set of three bars runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Orientation {
    /// Bars along y: the pattern's frequency is along x (columns).
    Vertical,
    /// Bars along x: the pattern's frequency is along y (rows).
    Horizontal,
}

/// One set of three bars of the target.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BarSet {
    /// USAF group.
    pub group: i32,
    /// USAF element, 1 to 6.
    pub element: u8,
    /// Line pairs per mm at the detector.
    pub frequency_cyc_per_mm: f64,
    /// Which way the bars run.
    pub orientation: Orientation,
    /// Top-left corner of the set (the first bar's corner), in detector pixels (column, row).
    pub origin_px: [f64; 2],
    /// Bar width, detector pixels.
    pub bar_width_px: f64,
}

impl BarSet {
    /// The set's rectangles `(x0, y0, x1, y1)` in detector pixels.
    fn bars(&self) -> [[f64; 4]; 3] {
        let [x, y] = self.origin_px;
        let w = self.bar_width_px;
        core::array::from_fn(|k| {
            let along = 2.0 * w * k as f64;
            match self.orientation {
                Orientation::Vertical => [x + along, y, x + along + w, y + 5.0 * w],
                Orientation::Horizontal => [x, y + along, x + 5.0 * w, y + along + w],
            }
        })
    }

    /// The rows (or columns) along the bars' middle 60 % of their length, and where the set
    /// starts across the bars, in pixels.
    fn reading_frame(&self) -> (std::ops::Range<usize>, f64) {
        let w = self.bar_width_px;
        let [x, y] = self.origin_px;
        let (len0, across0) = match self.orientation {
            Orientation::Vertical => (y, x),
            Orientation::Horizontal => (x, y),
        };
        let first = (len0 + 1.0 * w).floor() as usize;
        (first..((len0 + 4.0 * w).ceil() as usize).max(first + 1), across0)
    }

    /// The (column, row) of the pixel `along` the bars and `across` them.
    fn pixel(&self, along: usize, across: usize) -> (usize, usize) {
        match self.orientation {
            Orientation::Vertical => (across, along),
            Orientation::Horizontal => (along, across),
        }
    }

    /// Whether the pattern's period (two bar widths) is at least two pixels: below it the
    /// frequency lies above the detector's Nyquist frequency and is aliased.
    pub fn resolvable_by_pixels(&self) -> bool {
        self.bar_width_px >= 1.0
    }
}

/// A test object on the detector's pixel grid, drawn `oversample` times finer.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// Detector pixels per row.
    pub width: usize,
    /// Detector rows.
    pub height: usize,
    /// Fine cells per pixel along each axis.
    pub oversample: usize,
    /// Relative radiance in [0, 1] on the fine grid, `(oversample · width) × (oversample · height)`,
    /// row-major from the top-left cell.
    pub fine: Vec<f64>,
    /// The bar sets (empty for a user image).
    pub bars: Vec<BarSet>,
    /// A region inside the white square (or the white ground), detector pixels.
    pub white: Option<Region>,
    /// A region inside the black square (or the black ground), detector pixels.
    pub black: Option<Region>,
    /// What it is, for reports.
    pub description: String,
}

impl Target {
    /// Mean relative radiance over the image (the veiling glare follows it).
    pub fn mean(&self) -> f64 {
        self.fine.iter().sum::<f64>() / self.fine.len() as f64
    }

    /// Width of the fine grid.
    pub fn fine_width(&self) -> usize {
        self.width * self.oversample
    }

    /// Height of the fine grid.
    pub fn fine_height(&self) -> usize {
        self.height * self.oversample
    }
}

/// Line pairs per mm of USAF-1951 group `group`, element `element` (1 to 6).
pub fn usaf_frequency(group: i32, element: u8) -> f64 {
    2f64.powf(f64::from(group) + f64::from(element - 1) / 6.0)
}

/// The USAF-1951 groups worth drawing for a camera of Nyquist frequency `nyquist_cyc_per_mm`:
/// from the group whose first element is at or below a sixteenth of Nyquist to the group holding
/// Nyquist.
pub fn usaf_groups_for(nyquist_cyc_per_mm: f64) -> (i32, i32) {
    let last = nyquist_cyc_per_mm.log2().floor() as i32;
    (last - 3, last)
}

/// Largest supported fine grid (cells along one side): an 8192² grid of f64 is 0.5 GiB.
pub const MAX_FINE_SIDE: usize = 8192;

/// A USAF-1951 target of groups `groups.0 ..= groups.1` drawn for pixels of `pitch_m`, with the
/// white and black squares beside the groups; `oversample` fine cells per pixel (odd, so that a
/// pixel's centre is a cell's centre).
///
/// # Errors
/// [`Error::Render`] for an empty or too fine group range, an even or zero oversampling, or a
/// target whose grid would exceed [`MAX_FINE_SIDE`].
pub fn usaf(pitch_m: f64, groups: (i32, i32), polarity: Polarity, oversample: usize) -> Result<Target, Error> {
    check_oversample(oversample)?;
    let (first, last) = groups;
    if !(first <= last && last - first <= 6) {
        return Err(Error::Render {
            message: format!("USAF groups {first} to {last}: expected a first group ≤ the last, at most 7 groups"),
        });
    }
    let pitch_mm = pitch_m * 1e3;
    // bar width in pixels of element 1 of the coarsest group
    let bar_px = |g: i32, e: u8| 1.0 / (2.0 * usaf_frequency(g, e) * pitch_mm);
    // a group is 12 bar widths of its first element wide: refused before any size is computed
    // from it (group −2000's bars are ∞ pixels wide, and a width of ∞ pixels saturates a usize)
    let coarsest = bar_px(first, 1);
    let side = 12.0 * coarsest * oversample as f64;
    if side.is_nan() || side > MAX_FINE_SIDE as f64 {
        return Err(Error::Render {
            message: format!(
                "USAF group {first}'s bars are {coarsest:.3e} pixels wide, a target beyond {MAX_FINE_SIDE} cells a side at {oversample} cells a pixel: draw a higher first group (finer bars), or lower the oversampling"
            ),
        });
    }
    let margin = (2.0 * coarsest).ceil().max(16.0);
    let mut bars = Vec::new();
    let mut x = margin;
    let mut height: f64 = 0.0;
    for g in first..=last {
        let w1 = bar_px(g, 1);
        let mut y = margin;
        for e in 1..=6_u8 {
            let w = bar_px(g, e);
            let frequency_cyc_per_mm = usaf_frequency(g, e);
            // origins on whole pixels: the measured contrast then sees each element alike
            let (ox, oy) = (x.round(), y.round());
            bars.push(BarSet {
                group: g,
                element: e,
                frequency_cyc_per_mm,
                orientation: Orientation::Vertical,
                origin_px: [ox, oy],
                bar_width_px: w,
            });
            bars.push(BarSet {
                group: g,
                element: e,
                frequency_cyc_per_mm,
                orientation: Orientation::Horizontal,
                origin_px: [(ox + 7.0 * w).round(), oy],
                bar_width_px: w,
            });
            y += 7.0 * w;
        }
        height = height.max(y);
        x += 12.0 * w1 + (2.0 * w1).max(4.0);
    }
    // the white and the black square, stacked, each as tall as a third of the groups' column
    let side = ((height - margin) / 3.0).floor().max(16.0);
    let (sx, white_y) = (x.round(), margin);
    let black_y = (margin + side + margin.min(side)).round();
    let width = (sx + side + margin).ceil() as usize;
    let height = (height.max(black_y + side) + margin).ceil() as usize;
    let (width, height) = (width + width % 2, height + height % 2);
    if width.max(height) * oversample > MAX_FINE_SIDE {
        return Err(Error::Render {
            message: format!(
                "USAF groups {first} to {last} make a {width} × {height} pixel target, a {} × {} fine grid at {oversample} cells a pixel, beyond {MAX_FINE_SIDE} cells a side: draw fewer groups, from a higher first group (finer bars), or lower the oversampling",
                width * oversample,
                height * oversample
            ),
        });
    }
    let (ground, ink) = match polarity {
        Polarity::Positive => (1.0, 0.0),
        Polarity::Negative => (0.0, 1.0),
    };
    let mut target = Target {
        width,
        height,
        oversample,
        fine: vec![ground; width * oversample * height * oversample],
        bars: bars.clone(),
        white: None,
        black: None,
        description: format!(
            "USAF-1951 {} target, groups {first} to {last} ({:.2}–{:.1} cycles/mm at the detector)",
            match polarity {
                Polarity::Positive => "positive (dark bars on a clear ground)",
                Polarity::Negative => "negative (clear bars on a dark ground)",
            },
            usaf_frequency(first, 1),
            usaf_frequency(last, 6)
        ),
    };
    for set in &bars {
        for rect in set.bars() {
            paint(&mut target, rect, ink);
        }
    }
    let square = |y: f64| [sx, y, sx + side, y + side];
    paint(&mut target, square(white_y), 1.0);
    paint(&mut target, square(black_y), 0.0);
    // measuring regions: the middle half of each square
    let inner = |y: f64| {
        let q = (side / 4.0).round() as usize;
        Region { x: sx as usize + q, y: y as usize + q, width: side as usize - 2 * q, height: side as usize - 2 * q }
    };
    target.white = Some(inner(white_y));
    target.black = Some(inner(black_y));
    Ok(target)
}

/// A user's grayscale PNG (8 or 16 bit) as the object, one file pixel per detector pixel, grey
/// levels scaled to [0, 1] by the largest code (255 or 65535).
///
/// # Errors
/// The errors of [`crate::read_frame`], and [`Error::Render`] for an even or zero oversampling
/// or an image too large.
pub fn from_png(path: &Path, oversample: usize) -> Result<Target, Error> {
    check_oversample(oversample)?;
    // the size from the header, before the image is decoded
    let (w, h) = crate::frames::png_dimensions(path)?;
    let (w, h) = (w as usize, h as usize);
    if w.max(h).saturating_mul(oversample) > MAX_FINE_SIDE {
        return Err(Error::Render {
            message: format!(
                "{}: {w} × {h} pixels need a {} × {} fine grid at {oversample} cells a pixel, beyond {MAX_FINE_SIDE} cells a side: lower the oversampling or use a smaller image",
                path.display(),
                w.saturating_mul(oversample),
                h.saturating_mul(oversample)
            ),
        });
    }
    let frame = crate::read_frame(path)?;
    let full = match frame.bit_depth {
        8 => 255.0,
        16 => 65535.0,
        bits => {
            return Err(Error::Read {
                path: path.to_owned(),
                message: format!("{bits}-bit floating-point samples: a target image must be 8- or 16-bit grey levels"),
            });
        }
    };
    let (width, height) = (frame.width, frame.height);
    check_side(width * oversample, height * oversample)?;
    let fw = width * oversample;
    let mut fine = vec![0.0; fw * height * oversample];
    for (i, v) in fine.iter_mut().enumerate() {
        let (fx, fy) = (i % fw, i / fw);
        *v = frame.at(fx / oversample, fy / oversample) / full;
    }
    Ok(Target {
        width,
        height,
        oversample,
        fine,
        bars: Vec::new(),
        white: None,
        black: None,
        description: format!("{} ({width} × {height} pixels)", path.display()),
    })
}

/// A slanted edge through the middle of a `size × size` pixel frame, `angle_deg` off vertical
/// (clockwise as rows go down: the edge's column grows with the row), dark on the left: the
/// bright side at relative radiance 1, the dark side at `(1 − c)/(1 + c)` for a Michelson
/// contrast `c` (ISO 12233 asks for about 0.6, a 4:1 edge). Each fine cell holds the exact
/// fraction of its area on the bright side (the second antiderivative of the step, the ramp
/// `max(t, 0)²/2`, at the cell's four corners). The white and black regions are on either side,
/// clear of the edge, for `asnr measure`.
///
/// # Errors
/// [`Error::Render`] for an angle outside 0.5° to 44.5°, a contrast outside (0, 1], a size
/// outside 32 to 4096 pixels or a grid beyond [`MAX_FINE_SIDE`].
pub fn slanted_edge(size: usize, angle_deg: f64, contrast: f64, oversample: usize) -> Result<Target, Error> {
    check_oversample(oversample)?;
    let bad = |message: String| Err(Error::Render { message });
    if !(angle_deg.is_finite() && (0.5..=44.5).contains(&angle_deg.abs())) {
        return bad(format!("slanted edge at {angle_deg}°: expected 0.5° to 44.5° off vertical (ISO 12233: about 5°)"));
    }
    if !(contrast.is_finite() && contrast > 0.0 && contrast <= 1.0) {
        return bad(format!(
            "slanted edge of contrast {contrast}: expected a Michelson contrast in (0, 1] (ISO 12233: about 0.6)"
        ));
    }
    if !(32..=4096).contains(&size) {
        return bad(format!("slanted edge of {size} pixels: expected a frame of 32 to 4096 pixels a side"));
    }
    check_side(size * oversample, size * oversample)?;
    let dark = (1.0 - contrast) / (1.0 + contrast);
    let theta = angle_deg.to_radians();
    let (a, c) = (theta.cos(), -theta.sin());
    let mid = size as f64 / 2.0;
    let k = a * mid + c * mid;
    let h = 1.0 / oversample as f64;
    let fine_side = size * oversample;
    let ramp = |t: f64| if t > 0.0 { t * t / 2.0 } else { 0.0 };
    let fine: Vec<f64> = (0..fine_side * fine_side)
        .map(|i| {
            let (x0, y0) = ((i % fine_side) as f64 * h, (i / fine_side) as f64 * h);
            let u = |x: f64, y: f64| a * x + c * y - k;
            let corners = [u(x0, y0), u(x0 + h, y0), u(x0, y0 + h), u(x0 + h, y0 + h)];
            let bright = if corners.iter().all(|&v| v >= 0.0) {
                1.0
            } else if corners.iter().all(|&v| v <= 0.0) {
                0.0
            } else {
                ((ramp(corners[3]) - ramp(corners[2]) - ramp(corners[1]) + ramp(corners[0])) / (a * c * h * h))
                    .clamp(0.0, 1.0)
            };
            dark + (1.0 - dark) * bright
        })
        .collect();
    let region = |x: usize| Region { x, y: 3 * size / 8, width: size / 8, height: size / 4 };
    Ok(Target {
        width: size,
        height: size,
        oversample,
        fine,
        bars: Vec::new(),
        white: Some(region(13 * size / 16)),
        black: Some(region(size / 16)),
        description: format!(
            "slanted edge, {angle_deg}° off vertical, Michelson contrast {contrast} (dark side {dark:.4} of the bright), {size} × {size} pixels"
        ),
    })
}

fn check_oversample(oversample: usize) -> Result<(), Error> {
    if oversample % 2 == 1 && oversample <= 9 {
        Ok(())
    } else {
        Err(Error::Render {
            message: format!(
                "oversampling {oversample}: expected an odd number of fine cells per pixel from 1 to 9 (a pixel's centre is then a cell's centre)"
            ),
        })
    }
}

fn check_side(fine_width: usize, fine_height: usize) -> Result<(), Error> {
    if fine_width.max(fine_height) > MAX_FINE_SIDE {
        return Err(Error::Render {
            message: format!(
                "the image needs a {fine_width} × {fine_height} fine grid, beyond {MAX_FINE_SIDE} cells a side: lower the oversampling or use a smaller image"
            ),
        });
    }
    Ok(())
}

/// Paints the rectangle `[x0, y0, x1, y1]` (detector pixels) with `level`, each fine cell
/// blended by the exact fraction of its area the rectangle covers.
fn paint(target: &mut Target, rect: [f64; 4], level: f64) {
    let s = target.oversample as f64;
    let fw = target.fine_width();
    let fh = target.fine_height();
    let [x0, y0, x1, y1] = rect.map(|v| v * s);
    let cover = |lo: f64, hi: f64, cell: usize| {
        let c = cell as f64;
        (hi.min(c + 1.0) - lo.max(c)).clamp(0.0, 1.0)
    };
    let cols = (x0.floor().max(0.0) as usize)..(x1.ceil() as usize).min(fw);
    let rows = (y0.floor().max(0.0) as usize)..(y1.ceil() as usize).min(fh);
    for r in rows {
        let fy = cover(y0, y1, r);
        for c in cols.clone() {
            let f = fy * cover(x0, x1, c);
            let v = &mut target.fine[r * fw + c];
            *v += f * (level - *v);
        }
    }
}

/// The measured modulation of one bar set in an image of detector pixels (`width` per row),
/// `M = |bars − gaps|/(bars + gaps)` of [`bar_levels`].
pub fn bar_modulation(image: &[f64], width: usize, set: &BarSet) -> f64 {
    let (bars, gaps) = bar_levels(image, width, set);
    let sum = bars + gaps;
    if sum > 0.0 { (bars - gaps).abs() / sum } else { 0.0 }
}

/// The amplitude of the bar set's fundamental in an image, in the image's units: the
/// least-squares fit `I = a + b cos(π (u − u0 − w/2)/w)` over the pixels whose centres lie across
/// the three bars (`u0 … u0 + 5w`, `u` across the bars) and along the middle 60 % of their
/// length; `b > 0` where the bars are brighter than the gaps. A narrow-band measure: its noise
/// comes from frequencies near the bars' own, where a linear restoration scales the noise as it
/// scales the signal.
pub fn bar_fundamental(image: &[f64], width: usize, set: &BarSet) -> f64 {
    let height = image.len() / width;
    let w = set.bar_width_px;
    let (along, across0) = set.reading_frame();
    let across = across0.floor() as usize..(across0 + 5.0 * w).ceil() as usize;
    let (mut n, mut sc, mut si, mut scc, mut sci) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for a in along {
        for c in across.clone() {
            let centre = c as f64 + 0.5;
            if centre < across0 || centre > across0 + 5.0 * w {
                continue;
            }
            let (col, row) = set.pixel(a, c);
            if col >= width || row >= height {
                continue;
            }
            let v = image[row * width + col];
            let k = (std::f64::consts::PI * (centre - across0 - 0.5 * w) / w).cos();
            n += 1.0;
            sc += k;
            si += v;
            scc += k * k;
            sci += k * v;
        }
    }
    let var = scc - sc * sc / n;
    if n < 2.0 || var <= 0.0 { 0.0 } else { (sci - sc * si / n) / var }
}

/// The mean levels of the bars and of the gaps between them: the image averaged along the bars
/// over the middle 60 % of their length, read across them at the three bar centres and the two
/// gap centres (linear interpolation between pixel centres).
pub fn bar_levels(image: &[f64], width: usize, set: &BarSet) -> (f64, f64) {
    let height = image.len() / width;
    let w = set.bar_width_px;
    let (rows, across0) = set.reading_frame();
    let value = |along: usize, across: usize| -> f64 {
        let (c, r) = set.pixel(along, across);
        image[r.min(height - 1) * width + c.min(width - 1)]
    };
    // the profile across the bars at a position `p` (pixels), averaged along them
    let profile = |p: f64| -> f64 {
        let t = p - 0.5;
        let i = t.floor().max(0.0);
        let frac = (t - i).clamp(0.0, 1.0);
        let i = i as usize;
        let mut sum = 0.0;
        for along in rows.clone() {
            sum += (1.0 - frac) * value(along, i) + frac * value(along, i + 1);
        }
        sum / rows.len() as f64
    };
    let bars = (0..3).map(|k| profile(across0 + w * (0.5 + 2.0 * k as f64))).sum::<f64>() / 3.0;
    let gaps = (0..2).map(|k| profile(across0 + w * (1.5 + 2.0 * k as f64))).sum::<f64>() / 2.0;
    (bars, gaps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn usaf_frequencies_follow_the_standard() {
        // MIL-STD-150A: group 0 element 1 is 1 lp/mm; group 2 element 3 is 5.04 lp/mm
        assert_eq!(usaf_frequency(0, 1), 1.0);
        assert!((usaf_frequency(2, 3) - 5.0397).abs() < 1e-4);
        assert!((usaf_frequency(6, 4) - 90.5097).abs() < 1e-4);
        // 5.2 µm pixels: Nyquist 96.15 cycles/mm lies in group 6
        assert_eq!(usaf_groups_for(96.15), (3, 6));
    }

    /// The painted area equals the bars' area exactly (coverage fractions, not point samples),
    /// and an unblurred target has the full modulation where the bars are wider than a pixel.
    #[test]
    fn bars_are_painted_by_their_exact_area() {
        let t = usaf(5.2e-6, (3, 6), Polarity::Negative, 3).unwrap();
        // the bars end at least 4 pixels before the squares, whose measuring regions start a
        // quarter of their side (≈ half the region's width) inside them
        let white = t.white.unwrap();
        let end = (white.x - white.width / 2 - 1) * t.oversample;
        let fw = t.fine_width();
        let ink: f64 = t.fine.iter().enumerate().filter(|(i, _)| i % fw < end).map(|(_, v)| v).sum::<f64>() / 9.0;
        let bars: f64 = t.bars.iter().map(|b| 15.0 * b.bar_width_px * b.bar_width_px).sum();
        assert!((ink - bars).abs() < 1e-9 * ink, "{ink} vs {bars}");
        // the object sampled at pixel centres (the middle fine cell) keeps its modulation
        let s = t.oversample;
        let centres: Vec<f64> = (0..t.height * t.width)
            .map(|i| t.fine[((i / t.width) * s + s / 2) * t.fine_width() + (i % t.width) * s + s / 2])
            .collect();
        for set in t.bars.iter().filter(|b| b.bar_width_px >= 3.0) {
            let m = bar_modulation(&centres, t.width, set);
            assert!(m > 0.9, "{set:?}: {m}");
        }
    }

    #[test]
    fn bad_oversampling_and_groups_are_refused() {
        assert!(usaf(5.2e-6, (3, 6), Polarity::Positive, 2).is_err());
        assert!(usaf(5.2e-6, (6, 3), Polarity::Positive, 3).is_err());
        assert!(usaf(5.2e-6, (-20, 6), Polarity::Positive, 3).is_err());
    }
}
