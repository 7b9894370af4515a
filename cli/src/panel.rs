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
const TITLE: usize = 40;
const HEADING: usize = 30;
const SIDE: usize = 30;

/// Writes the panel of `columns` (images `width × height`) as an 8-bit grayscale PNG.
pub fn write(path: &Path, title: &str, width: usize, height: usize, columns: &[Column]) -> Result<()> {
    crate::plot::register_font();
    let k = MIN_TILE.div_ceil(width).max(1);
    let (tw, th) = (width * k, height * k);
    let n = columns.len();
    let w = SIDE + n * tw + (n + 1) * GAP;
    let h = TITLE + HEADING + 2 * th + 3 * GAP;
    let mut rgb = vec![255_u8; w * h * 3];
    let origin = |col: usize, row: usize| (SIDE + GAP + col * (tw + GAP), TITLE + HEADING + GAP + row * (th + GAP));
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
        root.draw(&Text::new(title.to_owned(), (to_i32(w / 2), to_i32(TITLE / 2)), text(18.0).pos(centre)))
            .map_err(|e| fail(&e))?;
        for (c, column) in columns.iter().enumerate() {
            let (x0, _) = origin(c, 0);
            let at = (to_i32(x0 + tw / 2), to_i32(TITLE + HEADING / 2));
            root.draw(&Text::new(column.heading.clone(), at, text(15.0).pos(centre))).map_err(|e| fail(&e))?;
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

fn to_i32(v: usize) -> i32 {
    i32::try_from(v).unwrap_or(i32::MAX)
}
