//! Writing a [`Plot`]: SVG (drawn at twice its size), or PNG rendered larger, box-filtered down
//! and tagged with its resolution.

use super::*;

/// Draws the SVG or PNG of `plot` into `path` (by its extension); errors name `flag`.
pub(super) fn render<P: Plot>(flag: &str, path: &Path, figure: &Figure, plot: &P) -> Result<()> {
    let err = |e: &dyn std::fmt::Display| anyhow!("{flag} {}: {e}", path.display());
    // before any drawing: the folder the file goes in (the system's "No such file" named neither)
    if let Some(folder) = path.parent().filter(|f| !f.as_os_str().is_empty() && !f.is_dir()) {
        bail!("{flag} {}: the folder {} does not exist; create it first", path.display(), folder.display());
    }
    register_font();
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("svg") => std::fs::write(path, svg(figure, plot).map_err(|e| err(&e))?).map_err(|e| err(&e)),
        Some("png") => {
            let (size, rgb) = rasterize(figure, plot, supersampling(figure, plot)).map_err(|e| err(&e))?;
            write_png(path, size, &rgb, figure.dpi).map_err(|e| err(&e))
        }
        _ => bail!("{flag} {}: expected a file name ending in .svg or .png", path.display()),
    }
}

/// The SVG text of `plot`: drawn at [`SVG_FINE`] times the figure's size, shown at its size.
pub(super) fn svg<P: Plot>(figure: &Figure, plot: &P) -> Result<String, String> {
    let ctx = Ctx { k: figure.px_per_pt() * f64::from(SVG_FINE) };
    let entries = plot.entries();
    let width = figure.width * SVG_FINE;
    let layout = Layout::new(ctx, i32::try_from(width).unwrap_or(i32::MAX), plot.title(), &entries, plot.aspect());
    let shown = (figure.width, layout.height(ctx).unsigned_abs().div_ceil(SVG_FINE));
    let fine = (width, shown.1 * SVG_FINE);
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, fine).into_drawing_area();
        compose(&root, ctx, &layout, plot, &entries)?;
    }
    Ok(text.replacen(
        &format!("<svg width=\"{}\" height=\"{}\"", fine.0, fine.1),
        &format!("<svg width=\"{}\" height=\"{}\"", shown.0, shown.1),
        1,
    ))
}

/// How many times larger a PNG is drawn than written: 3, or 2 for very large figures.
pub(super) fn supersampling<P: Plot>(figure: &Figure, plot: &P) -> u32 {
    let ctx = Ctx { k: figure.px_per_pt() };
    let layout =
        Layout::new(ctx, i32::try_from(figure.width).unwrap_or(i32::MAX), plot.title(), &plot.entries(), plot.aspect());
    let pixels = u64::from(figure.width) * u64::from(layout.height(ctx).unsigned_abs());
    if pixels * 9 <= MAX_SUPERSAMPLED { 3 } else { 2 }
}

/// The RGB pixels of `plot` at the figure's size: drawn `s` times larger and box-filtered down.
pub(super) fn rasterize<P: Plot>(figure: &Figure, plot: &P, s: u32) -> Result<((u32, u32), Vec<u8>), String> {
    let ctx = Ctx { k: figure.px_per_pt() * f64::from(s) };
    let entries = plot.entries();
    let width = figure.width * s;
    let layout = Layout::new(ctx, i32::try_from(width).unwrap_or(i32::MAX), plot.title(), &entries, plot.aspect());
    let size = (figure.width, layout.height(ctx).unsigned_abs().div_ceil(s));
    let big_size = (width, size.1 * s);
    let mut big = vec![255u8; big_size.0 as usize * big_size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut big, big_size).into_drawing_area();
        compose(&root, ctx, &layout, plot, &entries)?;
    }
    Ok((size, downsample(&big, size, s)))
}

/// `big` (RGB, `s` times `(w, h)`) averaged over `s × s` blocks.
pub(super) fn downsample(big: &[u8], (w, h): (u32, u32), s: u32) -> Vec<u8> {
    let (w, h, s) = (w as usize, h as usize, s as usize);
    let n = (s * s) as u32;
    let mut out = vec![0u8; w * h * 3];
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0u32; 3];
            for dy in 0..s {
                let row = (y * s + dy) * w * s;
                for dx in 0..s {
                    let i = (row + x * s + dx) * 3;
                    for (c, total) in sum.iter_mut().enumerate() {
                        *total += u32::from(big[i + c]);
                    }
                }
            }
            for (c, total) in sum.iter().enumerate() {
                out[(y * w + x) * 3 + c] = ((total + n / 2) / n) as u8;
            }
        }
    }
    out
}

/// Writes RGB pixels as a PNG with its resolution, `dpi`, in a pHYs chunk (pixels per metre,
/// both axes), through the `png` encoder.
pub(super) fn write_png(path: &Path, (w, h): (u32, u32), rgb: &[u8], dpi: f64) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| fail(&e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let ppm = (dpi / 0.0254).round() as u32;
    encoder.set_pixel_dims(Some(png::PixelDimensions { xppu: ppm, yppu: ppm, unit: png::Unit::Meter }));
    let mut writer = encoder.write_header().map_err(|e| fail(&e))?;
    writer.write_image_data(rgb).map_err(|e| fail(&e))?;
    writer.finish().map_err(|e| fail(&e))
}
