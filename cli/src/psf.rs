//! `asnr psf` and `asnr otf`: the scene's 2-D polychromatic PSF and OTF at its field point and
//! pupil, as PNG images and numbers (CSV matrices and a JSON description of the grid).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use num_complex::Complex64;
use serde::Serialize;

/// Arguments of `asnr psf` and `asnr otf`.
#[derive(clap::Args)]
pub struct GridArgs {
    /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
    pub scene: Option<PathBuf>,
    /// Override a scene key by its dotted path (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Folder for the PNG, the CSV matrices and the JSON description (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
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
    let label = args.scene.as_ref().map_or("embedded paper scene".to_owned(), |p| p.display().to_string());
    let scene = crate::load(args.scene.as_deref(), &args.set)?;
    let detected = metric::detected_spectrum(&scene);
    let cutoff = optics::highest_cutoff(scene.lens(), &detected).map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
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
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("--out {}: cannot create the folder", args.out.display()))?;
    let centre = n / 2;
    // the full spectrum from the half one (the PSF is real: OTF(−ν) = OTF(ν)*), DC at the centre
    let full = |kx: usize, ky: usize| -> Complex64 {
        if kx <= n / 2 { transfer.at(kx, ky) } else { transfer.at(n - kx, (n - ky) % n).conj() }
    };
    let shifted = |i: usize| (i + centre) % n;
    let mut files = Vec::new();
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
            files.push(write_csv(&args.out.join("psf.csv"), n, &grid)?);
            files.push(write_image(&args.out.join("psf.png"), n, &grid, args.log)?);
            layout = "psf.csv: row r, column c is the PSF at y = (r − n/2)·spacing, x = (c − n/2)·spacing (rows along the detector's y), a fraction of the energy per sample";
        }
        Kind::Otf => {
            let value = |i: usize| full(shifted(i % n), shifted(i / n));
            let re: Vec<f64> = (0..n * n).map(|i| value(i).re).collect();
            let im: Vec<f64> = (0..n * n).map(|i| value(i).im).collect();
            let mtf: Vec<f64> = (0..n * n).map(|i| value(i).norm()).collect();
            (sum, peak) = (None, None);
            files.push(write_csv(&args.out.join("otf-real.csv"), n, &re)?);
            files.push(write_csv(&args.out.join("otf-imag.csv"), n, &im)?);
            files.push(write_csv(&args.out.join("mtf.csv"), n, &mtf)?);
            files.push(write_image(&args.out.join("mtf.png"), n, &mtf, args.log)?);
            layout = "row r, column c is the OTF at ν_y = (r − n/2)·step, ν_x = (c − n/2)·step (step = frequency_step_cyc_per_mm); mtf = |OTF|";
        }
    }
    let field = scene.field();
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
    let path = args.out.join(if kind == Kind::Psf { "psf.json" } else { "otf.json" });
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

/// A matrix as CSV, one row per line.
fn write_csv(path: &Path, n: usize, values: &[f64]) -> Result<String> {
    let mut out = String::with_capacity(n * n * 12);
    for row in values.chunks_exact(n) {
        let line: Vec<String> = row.iter().map(|v| format!("{v:e}")).collect();
        let _ = writeln!(out, "{}", line.join(","));
    }
    std::fs::write(path, out).with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(path.display().to_string())
}

/// A matrix as a 16-bit grayscale PNG, scaled to its largest value (or 4 decades of log).
fn write_image(path: &Path, n: usize, values: &[f64], log: bool) -> Result<String> {
    let top = values.iter().copied().fold(0.0, f64::max);
    let levels: Vec<u16> = values
        .iter()
        .map(|&v| {
            let r = if top > 0.0 { (v / top).max(0.0) } else { 0.0 };
            let r = if log { (1.0 + r.max(1e-4).log10() / 4.0).max(0.0) } else { r };
            (r * 65535.0).round() as u16
        })
        .collect();
    imaging::write_png(path, n, n, &levels, 16)?;
    Ok(path.display().to_string())
}
