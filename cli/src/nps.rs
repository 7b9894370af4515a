//! `asnr nps`: the noise power spectrum of flat frames (temporal and spatial, EMVA 1288), and
//! with an MTF the measured NEQ and information capacity.

use std::fmt::Write;
use std::path::PathBuf;

use anyhow::Result;
use serde::Serialize;

// Arguments of `asnr nps`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct NpsArgs {
    /// Flat-field frames of one stack (8- or 16-bit grayscale PNG or TIFF), directories holding
    /// them, or patterns; at least 2.
    #[arg(required = true, value_name = "FLATS")]
    pub flats: Vec<PathBuf>,
    /// Dark frames (same size and depth): their mean frame is subtracted from every flat.
    #[arg(long, num_args = 1.., value_name = "FRAMES")]
    pub dark: Vec<PathBuf>,
    /// An MTF as CSV (`frequency_cyc_per_mm, mtf`) for the measured NEQ and capacity; needs
    /// --pixel-pitch-um.
    #[arg(long, value_name = "FILE.csv", requires = "pixel_pitch_um")]
    pub mtf_csv: Option<PathBuf>,
    /// The camera's pixel pitch, µm (cycles/pixel → cycles/mm).
    #[arg(long, value_name = "UM")]
    pub pixel_pitch_um: Option<f64>,
    /// The object's contrast for the capacity (default 1).
    #[arg(long, default_value_t = 1.0, value_name = "C")]
    pub contrast: f64,
    /// The NEQ and capacity from the temporal NPS alone (a frame averaged over many exposures)
    /// instead of temporal + spatial (one frame's noise).
    #[arg(long)]
    pub temporal_only: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    nps: &'a imaging::Nps,
    pixel_pitch_um: Option<f64>,
    measured: Option<&'a imaging::MeasuredMetrics>,
}

/// Runs `asnr nps`.
pub fn run(args: &NpsArgs) -> Result<()> {
    let flats = imaging::read_stack("flat frames", &args.flats)?;
    let darks = if args.dark.is_empty() { Vec::new() } else { imaging::read_stack("--dark", &args.dark)? };
    if let Some(p) = args.pixel_pitch_um
        && !(p.is_finite() && p > 0.0 && p < 1e4)
    {
        anyhow::bail!("--pixel-pitch-um {p}: expected a finite pitch > 0 µm and < 10 mm");
    }
    let n = imaging::nps(&flats, &darks)?;
    let measured = match (&args.mtf_csv, args.pixel_pitch_um) {
        (Some(path), Some(pitch_um)) => {
            let (f, m) = scene::read_pairs(path, &scene::FREQUENCY, 0.0, 10.0, "MTF")?;
            let nyquist_cyc_per_mm = 0.5 / (pitch_um * 1e-3);
            let last = f.last().copied().unwrap_or(0.0);
            if last < nyquist_cyc_per_mm {
                anyhow::bail!(
                    "{}: the MTF ends at {last} cycles/mm, below the Nyquist frequency {nyquist_cyc_per_mm:.2} cycles/mm of the {pitch_um} µm pixels; the NEQ and capacity need it to Nyquist",
                    path.display()
                );
            }
            let per_px: Vec<f64> = f.iter().map(|v| v * pitch_um * 1e-3).collect();
            Some(imaging::measured_metrics(&n, &per_px, &m, args.contrast, args.temporal_only)?)
        }
        _ => None,
    };
    if args.json {
        let report = Report { nps: &n, pixel_pitch_um: args.pixel_pitch_um, measured: measured.as_ref() };
        outln!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    let mut s = String::new();
    let _ = writeln!(s, "flat frames      {} of {} × {} pixels", n.frames, n.width, n.height);
    let _ =
        writeln!(s, "mean level       {:.3} DN{}", n.mean_dn, if darks.is_empty() { "" } else { " above the dark" });
    let _ = writeln!(
        s,
        "temporal noise   σ_t² = {:.4} DN² (σ_t {:.4} DN)",
        n.temporal_variance_dn2,
        n.temporal_variance_dn2.max(0.0).sqrt()
    );
    let _ = writeln!(
        s,
        "spatial noise    σ_s² = {:.4} DN² (fixed pattern; unbiased, NPS_t/L taken off)",
        n.spatial_variance_dn2
    );
    let _ = writeln!(s);
    let mm = args.pixel_pitch_um.map(|p| 1.0 / (p * 1e-3));
    let _ = writeln!(
        s,
        "{:>10} {:>11} {:>14} {:>14} {:>8}",
        "cyc/px",
        if mm.is_some() { "cyc/mm" } else { "" },
        "NPS_t DN²px²",
        "NPS_s DN²px²",
        "samples"
    );
    for i in 0..n.frequency_cyc_per_px.len() {
        let f = n.frequency_cyc_per_px[i];
        let in_mm = mm.map_or(String::new(), |k| format!("{:.2}", f * k));
        let _ = writeln!(s, "{f:>10.4} {in_mm:>11} {:>14.4} {:>14.4} {:>8}", n.temporal[i], n.spatial[i], n.counts[i]);
    }
    if let Some(m) = &measured {
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "measured NEQ     mean to Nyquist {:.4e} quanta per pixel (S²MTF²/NPS, {} noise; S/σ = {:.3})",
            m.mean_neq, m.noise, m.snr0
        );
        let _ = writeln!(
            s,
            "capacity         {:.4} bits/pixel ± {:.1e} (flat object, contrast {}; MTF and NPS taken as radially symmetric)",
            m.capacity_bits_per_pixel,
            m.capacity_error_bits,
            report::number(m.contrast)
        );
    }
    out!("{s}");
    Ok(())
}
