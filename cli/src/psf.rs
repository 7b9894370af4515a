//! `asnr psf` and `asnr otf`: the scene's 2-D polychromatic PSF and OTF at its field point and
//! pupil, as PNG images and numbers (CSV matrices and a JSON description of the grid).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use num_complex::Complex64;
use serde::Serialize;

// Arguments of `asnr psf` and `asnr otf`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct GridArgs {
    /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
    pub scene: Option<PathBuf>,
    /// Override a scene key by its dotted path (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Folder for the PNG, the CSV matrices and the JSON description (created if missing).
    #[arg(long, value_name = "DIR", required_unless_present = "stack")]
    pub out: Option<PathBuf>,
    /// Samples along each side of the grid (even, 16–2048).
    #[arg(long, default_value_t = 256, value_name = "N")]
    pub size: usize,
    /// PSF sample spacing, µm (default: 1/(2 ν_c) of the shortest wavelength's cutoff ν_c, so
    /// that the grid holds the whole OTF and the PSF is not aliased).
    #[arg(long, value_name = "UM")]
    pub spacing_um: Option<f64>,
    /// Draw the PNG on a logarithmic scale (4 decades below the peak), to see the PSF's tails.
    #[arg(long)]
    pub log: bool,
    /// `asnr psf` only: write the scene lens's monochromatic PSFs at `--wavelengths-nm` as a PSF
    /// stack, a .npy float array [wavelength, y, x] (the input of `[lens] model = "psf"`),
    /// instead of the polychromatic PSF; its description and the `[lens]` keys that read it
    /// back are printed.
    #[arg(long, value_name = "FILE.npy", requires = "wavelengths_nm", conflicts_with = "log")]
    pub stack: Option<PathBuf>,
    /// The stack's wavelengths, nm: a list `700,750,800` or a range `start:stop:step`.
    #[arg(long, value_name = "LIST", requires = "stack")]
    pub wavelengths_nm: Option<String>,
    /// The stack's sample type: `f4` (32-bit float, half the file) or `f8`.
    #[arg(long, value_name = "TYPE", default_value = "f4", requires = "stack")]
    pub dtype: String,
    /// Relative error allowed in the OTF (sets options.tolerance; default 1e-6, and 1e-4 on the FFT path).
    #[arg(long, value_name = "REL")]
    pub tolerance: Option<f64>,
}

/// The JSON description written beside the matrices.
#[derive(Serialize)]
struct Description {
    scene: String,
    quantity: &'static str,
    size: usize,
    /// PSF sample spacing, µm (the OTF's frequency step is 1/(size · spacing)).
    spacing_um: f64,
    /// OTF frequency step, cycles/mm.
    frequency_step_cyc_per_mm: f64,
    /// The grid's Nyquist frequency 1/(2 spacing), cycles/mm, and the cutoff of the shortest
    /// wavelength: the OTF beyond the grid's Nyquist is left out.
    grid_nyquist_cyc_per_mm: f64,
    cutoff_cyc_per_mm: f64,
    /// Row and column of the centre (x = y = 0, or ν = 0): index size/2.
    centre_index: usize,
    /// How to read the CSV matrices.
    layout: &'static str,
    field_deg: [f64; 2],
    direction_dependent: bool,
    /// PSF: the sum of the samples (1: a fraction of the energy per sample) and the peak.
    sum: Option<f64>,
    peak: Option<f64>,
    files: Vec<String>,
}

/// What `run` exports.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// The point spread function.
    Psf,
    /// The optical transfer function.
    Otf,
}

/// Runs `asnr psf` or `asnr otf`.
pub fn run(args: &GridArgs, kind: Kind) -> Result<()> {
    let n = args.size;
    if !(16..=2048).contains(&n) || n % 2 == 1 {
        anyhow::bail!("--size {n}: expected an even number of samples from 16 to 2048");
    }
    if let Some(stack) = &args.stack {
        if kind == Kind::Otf {
            anyhow::bail!("--stack: only with asnr psf (a stack of PSFs)");
        }
        return write_stack(args, stack);
    }
    let Some(out_dir) = &args.out else { anyhow::bail!("--out: expected the folder to write to") };
    let label = args.scene.as_ref().map_or("embedded paper scene".to_owned(), |p| p.display().to_string());
    let scene = crate::load(args.scene.as_deref(), &crate::with_tolerance(args.set.clone(), args.tolerance))?;
    let detected = metric::detected_spectrum(&scene);
    let cutoff = optics::highest_cutoff(scene.lens(), &detected).map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
    if !cutoff.is_finite() {
        // the grid is sized from the shortest wavelength's cutoff 1/(λ F#), which has no end
        anyhow::bail!(
            "{label}: the detected spectrum reaches λ = 0 nm (spectrum.range_nm, spectrum.center_nm or the tables), where the cutoff 1/(λ F#) is infinite and no grid holds the OTF: keep the band above 0 nm"
        );
    }
    let spacing = match args.spacing_um {
        Some(s) if s.is_finite() && s > 0.0 && s < 1e4 => s * 1e-6,
        Some(s) => anyhow::bail!("--spacing-um {s}: expected a sample spacing > 0 and below 10000 µm"),
        None => 0.5 / cutoff,
    };
    // off axis or through a composite pupil this takes tens of seconds: a spinner on a terminal
    let spinner = crate::sweep::spinner(format!("the {n} × {n} OTF grid of {label}"))?;
    let transfer = imaging::transfer(&scene, n, n, spacing);
    spinner.finish_and_clear();
    let transfer = transfer.map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("--out {}: cannot create the folder", out_dir.display()))?;
    let centre = n / 2;
    // the full spectrum from the half one (the PSF is real: OTF(−ν) = OTF(ν)*), DC at the centre
    let full = |kx: usize, ky: usize| -> Complex64 {
        if kx <= n / 2 { transfer.at(kx, ky) } else { transfer.at(n - kx, (n - ky) % n).conj() }
    };
    let shifted = |i: usize| (i + centre) % n;
    let mut files = Vec::new();
    // the images' titles: the scene's (or its lens), and the field point off axis
    let name = scene.title().map_or_else(|| scene.lens().describe(), str::to_owned);
    let field = scene.field();
    let off_axis = format!(", {}", crate::plot::field_label(&scene));
    let (sum, peak);
    let layout;
    match kind {
        Kind::Psf => {
            let fft = imaging::render::Fft2::new(n, n);
            let psf = fft.inverse(transfer.values.clone());
            // centred: sample (row, col) is y = (row − n/2) d, x = (col − n/2) d
            let grid: Vec<f64> = (0..n * n).map(|i| psf[shifted(i / n) * n + shifted(i % n)]).collect();
            sum = Some(grid.iter().sum::<f64>());
            peak = Some(grid.iter().copied().fold(f64::MIN, f64::max));
            files.push(write_csv(&out_dir.join("psf.csv"), n, &grid)?);
            let title = format!("Polychromatic PSF: {name}{off_axis}");
            let picture = Picture {
                title: &title,
                axes: ["x (µm)", "y (µm)"],
                value: ["PSF (fraction of the energy per sample)", "log₁₀ of the PSF over its peak"],
                step: spacing * 1e6,
            };
            files.push(write_image(&out_dir.join("psf.png"), n, &grid, args.log, &picture)?);
            layout = "psf.csv: row r, column c is the PSF at y = (r − n/2)·spacing, x = (c − n/2)·spacing (rows along the detector's y), a fraction of the energy per sample";
        }
        Kind::Otf => {
            let value = |i: usize| full(shifted(i % n), shifted(i / n));
            let re: Vec<f64> = (0..n * n).map(|i| value(i).re).collect();
            let im: Vec<f64> = (0..n * n).map(|i| value(i).im).collect();
            let mtf: Vec<f64> = (0..n * n).map(|i| value(i).norm()).collect();
            (sum, peak) = (None, None);
            files.push(write_csv(&out_dir.join("otf-real.csv"), n, &re)?);
            files.push(write_csv(&out_dir.join("otf-imag.csv"), n, &im)?);
            files.push(write_csv(&out_dir.join("mtf.csv"), n, &mtf)?);
            let title = format!("Polychromatic MTF: {name}{off_axis}");
            let picture = Picture {
                title: &title,
                axes: ["frequency along x (cycles/mm)", "frequency along y (cycles/mm)"],
                value: ["MTF", "log₁₀ MTF"],
                step: 1e-3 / (n as f64 * spacing),
            };
            files.push(write_image(&out_dir.join("mtf.png"), n, &mtf, args.log, &picture)?);
            layout = "row r, column c is the OTF at ν_y = (r − n/2)·step, ν_x = (c − n/2)·step (step = frequency_step_cyc_per_mm); mtf = |OTF|";
        }
    }
    let description = Description {
        scene: label,
        quantity: if kind == Kind::Psf { "psf" } else { "otf" },
        size: n,
        spacing_um: spacing * 1e6,
        frequency_step_cyc_per_mm: 1e-3 / (n as f64 * spacing),
        grid_nyquist_cyc_per_mm: 0.5e-3 / spacing,
        cutoff_cyc_per_mm: cutoff * 1e-3,
        centre_index: centre,
        layout,
        field_deg: [field.x_rad.to_degrees(), field.y_rad.to_degrees()],
        direction_dependent: transfer.direction_dependent,
        sum,
        peak,
        files,
    };
    let json = serde_json::to_string_pretty(&description)?;
    let path = out_dir.join(if kind == Kind::Psf { "psf.json" } else { "otf.json" });
    std::fs::write(&path, &json).with_context(|| format!("{}: cannot write", path.display()))?;
    outln!("{json}");
    if 0.5 / spacing < cutoff {
        eprintln!(
            "warning: the grid's Nyquist frequency {:.1} cycles/mm is below the cutoff {:.1} cycles/mm: the OTF beyond it is left out (lower --spacing-um)",
            0.5e-3 / spacing,
            cutoff * 1e-3
        );
    }
    Ok(())
}

/// The wavelengths of `--wavelengths-nm`, nm: `a,b,c` or `start:stop:step` (stop included when
/// it falls on the step, to 1e-9 of it).
fn parse_wavelengths(text: &str) -> Result<Vec<f64>> {
    let bad = || {
        anyhow::anyhow!(
            "--wavelengths-nm {text}: expected wavelengths in nm, > 0 and increasing, as a list `700,750,800` or a range `start:stop:step` (at most 4096)"
        )
    };
    let number = |t: &str| t.trim().parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0);
    let list: Vec<f64> = match text.split(':').collect::<Vec<_>>().as_slice() {
        [a, b, step] => {
            let (a, b, step) = (number(a).ok_or_else(bad)?, number(b).ok_or_else(bad)?, number(step).ok_or_else(bad)?);
            let count = ((b - a) / step + 1e-9).floor();
            if !(0.0..4096.0).contains(&count) {
                return Err(bad());
            }
            (0..=count as usize).map(|i| a + step * i as f64).collect()
        }
        [one] => one.split(',').map(|t| number(t).ok_or_else(bad)).collect::<Result<_>>()?,
        _ => return Err(bad()),
    };
    if list.is_empty() || list.len() > 4096 || list.windows(2).any(|w| w[1] <= w[0]) {
        return Err(bad());
    }
    Ok(list)
}

/// The description `asnr psf --stack` prints.
#[derive(Serialize)]
struct StackDescription {
    scene: String,
    quantity: &'static str,
    file: String,
    /// [wavelength, y, x]
    shape: [usize; 3],
    dtype: String,
    spacing_um: f64,
    wavelengths_nm: Vec<f64>,
    /// Row and column of the centre sample (x = y = 0): index size/2.
    centre_index: usize,
    layout: &'static str,
    field_deg: [f64; 2],
    /// The `[lens]` keys that read the stack back (efficiency and transmission to be given).
    lens_keys: String,
}

/// `asnr psf --stack`: the lens's PSF at each wavelength, each the inverse FFT of the scene's
/// OTF at that one wavelength (a line spectrum, the camera's QE set to 1: the PSF does not
/// depend on them), unit sum, as a .npy array [wavelength, y, x].
fn write_stack(args: &GridArgs, path: &Path) -> Result<()> {
    let n = args.size;
    let wavelengths = parse_wavelengths(args.wavelengths_nm.as_deref().unwrap_or_default())?;
    let size = match args.dtype.as_str() {
        "f4" => 4,
        "f8" => 8,
        other => anyhow::bail!("--dtype {other}: expected f4 (32-bit float) or f8 (64-bit float)"),
    };
    if wavelengths.len() * n * n > lenses::PSF_MAX_ELEMENTS {
        anyhow::bail!(
            "--wavelengths-nm and --size {n}: {} values, more than a PSF stack holds ({})",
            wavelengths.len() * n * n,
            lenses::PSF_MAX_ELEMENTS
        );
    }
    let label = args.scene.as_ref().map_or("embedded paper scene".to_owned(), |p| p.display().to_string());
    let scene = crate::load(args.scene.as_deref(), &crate::with_tolerance(args.set.clone(), args.tolerance))?;
    let lens = scene.lens();
    let spacing = match args.spacing_um {
        Some(s) if s.is_finite() && s > 0.0 && s < 1e4 => s * 1e-6,
        Some(s) => anyhow::bail!("--spacing-um {s}: expected a sample spacing > 0 and below 10000 µm"),
        // the shortest wavelength's cutoff 1/(λ F#) at the grid's Nyquist frequency
        None => 0.5 * wavelengths[0] * 1e-9 * lens.f_number(),
    };
    let camera = metric::Camera::new(scene.camera().pixel_pitch(), radiometry::Spectrum::Constant(1.0), false)?;
    let centre = n / 2;
    let shifted = |i: usize| (i + centre) % n;
    let fft = imaging::render::Fft2::new(n, n);
    let mut data = Vec::with_capacity(wavelengths.len() * n * n * size);
    for &nm in &wavelengths {
        let line = radiometry::Spectrum::Line(radiometry::Line::new(nm * 1e-9, 1e-9, 1.0)?);
        let mono =
            metric::Scene::new(scene.lens_arc(), line, camera.clone(), scene.exposure(), scene.options().clone())
                .and_then(|s| s.at_field(scene.field()))
                .with_context(|| format!("{label}: at {nm} nm"))?;
        let transfer =
            imaging::transfer(&mono, n, n, spacing).map_err(|e| anyhow::anyhow!("{label}: at {nm} nm: {e}"))?;
        let psf = fft.inverse(transfer.values);
        for i in 0..n * n {
            let v = psf[shifted(i / n) * n + shifted(i % n)];
            if size == 4 {
                data.extend_from_slice(&(v as f32).to_le_bytes());
            } else {
                data.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    let kind = if size == 4 { scene::npy::NpyType::F32 } else { scene::npy::NpyType::F64 };
    let descr = kind.descr();
    let mut bytes = scene::npy::npy_header(kind, &[wavelengths.len(), n, n]);
    bytes.extend_from_slice(&data);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("--stack {}: cannot create its folder", path.display()))?;
    }
    std::fs::write(path, &bytes).with_context(|| format!("--stack {}: cannot write", path.display()))?;
    let list: Vec<String> = wavelengths.iter().map(|w| format!("{w}")).collect();
    let field = scene.field();
    let description = StackDescription {
        scene: label,
        quantity: "psf-stack",
        file: path.display().to_string(),
        shape: [wavelengths.len(), n, n],
        dtype: descr.to_owned(),
        spacing_um: optics::round_for_display(spacing * 1e6),
        wavelengths_nm: wavelengths.clone(),
        centre_index: centre,
        layout: "slice k, row r, column c is the PSF at wavelength k, y = (r − n/2)·spacing, x = (c − n/2)·spacing (rows along the detector's y), a fraction of the energy per sample",
        field_deg: [field.x_rad.to_degrees(), field.y_rad.to_degrees()],
        lens_keys: format!(
            "model = \"psf\"\npsf = {}\npsf_pitch_um = {}\npsf_wavelengths_nm = [{}]\nf_number = {}\nfocal_length_mm = {}\n",
            toml_string(&path.display().to_string()),
            optics::round_for_display(spacing * 1e6),
            list.join(", "),
            optics::round_for_display(lens.f_number()),
            optics::round_for_display(lens.focal_length() * 1e3)
        ),
    };
    outln!("{}", serde_json::to_string_pretty(&description)?);
    Ok(())
}

/// `s` as a TOML basic string.
fn toml_string(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// A matrix as CSV, one row per line.
fn write_csv(path: &Path, n: usize, values: &[f64]) -> Result<String> {
    let mut out = String::with_capacity(n * n * 12);
    for row in values.chunks_exact(n) {
        out.push_str(&scene::sweep::csv_line(row.iter().map(|v| format!("{v:e}"))));
    }
    std::fs::write(path, out).with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(path.display().to_string())
}

/// What [`write_image`] draws: the quantity, its axes' sample step and unit.
struct Picture<'a> {
    title: &'a str,
    /// Axis descriptions of x and y.
    axes: [&'a str; 2],
    /// The colour bar's description: linear, and on the log scale.
    value: [&'a str; 2],
    /// Sample step along both axes, in the axes' unit.
    step: f64,
}

/// A centred `n × n` matrix (row r at y = (r − n/2)·step, column c at x = (c − n/2)·step) as
/// an image with labelled axes and a colour bar: its values, or with `log` log10 of the values
/// over their largest, 4 decades deep.
fn write_image(path: &Path, n: usize, values: &[f64], log: bool, picture: &Picture) -> Result<String> {
    let top = values.iter().copied().fold(0.0, f64::max);
    let shown = |v: f64| if log { (v / top).max(1e-4).log10() } else { v };
    let axis: Vec<f64> = (0..n).map(|i| (i as f64 - (n / 2) as f64) * picture.step).collect();
    // the heatmap's layout: column-major, z[i·n + j] at (x_i, y_j)
    let z = (0..n * n).map(|k| shown(values[(k % n) * n + k / n])).collect();
    let grid = crate::plot::Grid { xs: axis.clone(), ys: axis, z, shaded: Vec::new() };
    let labels = crate::plot::Labels {
        title: picture.title,
        x: picture.axes[0],
        y: picture.axes[1],
        z: picture.value[usize::from(log)],
        ..crate::plot::Labels::default()
    };
    crate::plot::image_plot("--out", path, &crate::plot::Figure::default(), &labels, &grid)?;
    Ok(path.display().to_string())
}
