//! The side-by-side panel of `asnr render`, laid out like the paper's Fig. 3 and 4: one column
//! per spectral range, the raw image above the restored one, each tile lettered.

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use plotters::style::FontTransform;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// One column of the panel: its heading and its two 8-bit images.
pub struct Column {
    /// What the column shows (range, ASNR).
    pub heading: String,
    /// The raw frame, 8-bit grey levels.
    pub raw: Vec<u8>,
    /// The restored image, 8-bit grey levels.
    pub restored: Vec<u8>,
}

/// Tiles are scaled up by a whole factor until they are at least this wide.
const MIN_TILE: usize = 320;
const GAP: usize = 12;
const SIDE: usize = 30;
/// Title and heading sizes (pixels of plotters' font size) and their line heights.
const TITLE_SIZE: f64 = 18.0;
const TITLE_LINE: usize = 24;
const HEADING_SIZE: f64 = 15.0;
const HEADING_LINE: usize = 20;
/// Room above and below the title's and the headings' lines.
const PAD: usize = 8;

/// Writes the panel of `columns` (images `width × height`) as an 8-bit grayscale PNG.
pub fn write(path: &Path, title: &str, width: usize, height: usize, columns: &[Column]) -> Result<()> {
    crate::plot::register_font();
    let k = MIN_TILE.div_ceil(width).max(1);
    let (tw, th) = (width * k, height * k);
    let n = columns.len();
    let w = SIDE + n * tw + (n + 1) * GAP;
    // the title over the whole width and each heading over its column, wrapped so none is clipped
    let title_lines = wrap(title, TITLE_SIZE, w - 2 * GAP);
    let headings: Vec<Vec<String>> = columns.iter().map(|c| wrap(&c.heading, HEADING_SIZE, tw)).collect();
    let title_h = title_lines.len() * TITLE_LINE + 2 * PAD;
    let heading_h = headings.iter().map(Vec::len).max().unwrap_or(0) * HEADING_LINE + PAD;
    let top = title_h + heading_h;
    let h = top + 2 * th + 3 * GAP;
    let mut rgb = vec![255_u8; w * h * 3];
    let origin = |col: usize, row: usize| (SIDE + GAP + col * (tw + GAP), top + GAP + row * (th + GAP));
    for (c, column) in columns.iter().enumerate() {
        for (row, image) in [&column.raw, &column.restored].into_iter().enumerate() {
            let (x0, y0) = origin(c, row);
            for y in 0..th {
                for x in 0..tw {
                    let v = image[(y / k) * width + x / k];
                    let at = ((y0 + y) * w + x0 + x) * 3;
                    rgb[at..at + 3].fill(v);
                }
            }
        }
    }
    let fail = |e: &dyn std::fmt::Display| anyhow!("{}: cannot draw the panel ({e})", path.display());
    {
        let (pw, ph) = (u32::try_from(w).map_err(|e| fail(&e))?, u32::try_from(h).map_err(|e| fail(&e))?);
        let root = BitMapBackend::with_buffer(&mut rgb, (pw, ph)).into_drawing_area();
        let text = |size: f64| ("sans-serif", size).into_font().color(&BLACK);
        let centre = Pos::new(HPos::Center, VPos::Center);
        for (i, line) in title_lines.into_iter().enumerate() {
            let at = (to_i32(w / 2), to_i32(PAD + i * TITLE_LINE + TITLE_LINE / 2));
            root.draw(&Text::new(line, at, text(TITLE_SIZE).pos(centre))).map_err(|e| fail(&e))?;
        }
        for (c, lines) in headings.into_iter().enumerate() {
            let (x0, _) = origin(c, 0);
            for (i, line) in lines.into_iter().enumerate() {
                let at = (to_i32(x0 + tw / 2), to_i32(title_h + i * HEADING_LINE + HEADING_LINE / 2));
                root.draw(&Text::new(line, at, text(HEADING_SIZE).pos(centre))).map_err(|e| fail(&e))?;
            }
            for row in 0..2 {
                let (x, y) = origin(c, row);
                let letter = format!("({})", char::from(b'a' + (row * n + c) as u8));
                let corner = (to_i32(x + 4), to_i32(y + 4));
                root.draw(&Rectangle::new([corner, (corner.0 + 30, corner.1 + 20)], WHITE.filled()))
                    .map_err(|e| fail(&e))?;
                let style = text(14.0).pos(Pos::new(HPos::Left, VPos::Top));
                root.draw(&Text::new(letter, (corner.0 + 3, corner.1 + 2), style)).map_err(|e| fail(&e))?;
            }
        }
        for (row, label) in ["raw", "Wiener restored"].into_iter().enumerate() {
            let (_, y) = origin(0, row);
            let style = text(15.0).transform(FontTransform::Rotate270).pos(centre);
            root.draw(&Text::new(label, (to_i32(SIDE / 2 + 2), to_i32(y + th / 2)), style)).map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    // everything on it is grey: an 8-bit grayscale PNG is a third of the RGB one (noise does not
    // compress)
    let grey: Vec<u16> = rgb.chunks_exact(3).map(|p| u16::from(p[0])).collect();
    imaging::write_png(path, w, h, &grey, 8)?;
    Ok(())
}

/// `text` broken into lines at spaces so each is at most `width` pixels wide in the embedded font
/// at `size` (a single word wider than that is a line of its own).
fn wrap(text: &str, size: f64, width: usize) -> Vec<String> {
    let font = ("sans-serif", size).into_font();
    crate::plot::wrap_words(text, |t| font.box_size(t).is_ok_and(|(w, _)| w as usize <= width))
}

fn to_i32(v: usize) -> i32 {
    i32::try_from(v).unwrap_or(i32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn titles_wrap_to_the_width_and_keep_every_word() {
        crate::plot::register_font();
        let title = "USAF-1951 target: raw (top) and Wiener-restored (bottom), with veiling glare";
        let width = 320;
        let lines = wrap(title, TITLE_SIZE, width);
        assert!(lines.len() >= 2, "{lines:?}");
        let font = ("sans-serif", TITLE_SIZE).into_font();
        for line in &lines {
            let (w, _) = font.box_size(line).unwrap();
            assert!(w as usize <= width, "{line:?} is {w} px wide");
        }
        assert_eq!(lines.join(" "), title);
        // a word wider than the width is a line of its own, not dropped
        assert_eq!(wrap("a Wiener-restored b", TITLE_SIZE, 10), ["a", "Wiener-restored", "b"]);
    }
}
