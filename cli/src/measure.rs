//! `asnr measure`: the SNR (paper eq. 2–4), and with capped-black frames the veiling glare and
//! modulation (SI eq. S10–S12), of a stack of camera frames.

use std::path::PathBuf;

use anyhow::Result;

// Arguments of `asnr measure`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct MeasureArgs {
    /// Frames of one stack (8- or 16-bit grayscale PNG or TIFF), directories holding them (their
    /// .png/.tif files in name order), or patterns such as 'frames/*.png'; at least 2 frames (the paper
    /// grabbed 30).
    #[arg(required = true, value_name = "FRAMES")]
    pub frames: Vec<PathBuf>,
    /// The white region, X,Y,W,H in pixels (corner column and row from the top-left, width, height).
    #[arg(long, value_name = "X,Y,W,H")]
    pub white: String,
    /// The black region, X,Y,W,H in pixels.
    #[arg(long, value_name = "X,Y,W,H")]
    pub black: String,
    /// Frames taken with the camera capped (no light): their mean over the black region is the
    /// capped black level, from which VG = black/white (levels above it) and M are computed.
    #[arg(long, num_args = 1.., value_name = "FRAMES")]
    pub capped_black: Vec<PathBuf>,
    /// σ_s = σ_w instead of √(σ_w² − σ_b²): glare and camera noise count (the SI's variant).
    #[arg(long)]
    pub include_glare: bool,
    /// Frames of a slanted edge taken with the same camera: their e-SFR's mean MTF to Nyquist
    /// times the SNR is the measured ASNR (eq. 1; `asnr sfr` for the edge alone).
    #[arg(long, num_args = 1.., value_name = "IMAGE", conflicts_with = "mtf_csv")]
    pub edge: Vec<PathBuf>,
    /// The edge's region of interest, X,Y,W,H in pixels (default: the whole frame); one edge.
    #[arg(long, value_name = "X,Y,W,H", requires = "edge")]
    pub edge_roi: Option<String>,
    /// A measured MTF instead of an edge: CSV with columns frequency_cyc_per_mm, mtf, from 0 to
    /// at least Nyquist (needs --pixel-pitch-um or --compare for Nyquist).
    #[arg(long, value_name = "FILE")]
    pub mtf_csv: Option<PathBuf>,
    /// Pixel pitch, µm (Nyquist of --mtf-csv; default: the --compare scene's).
    #[arg(long, value_name = "UM")]
    pub pixel_pitch_um: Option<f64>,
    /// A scene file: its simulated ASNR, SNR0 and mean MTF (with the pixel aperture, as a
    /// measured edge has it) beside the measured ones, and the ratios (the paper's Fig. 2b).
    #[arg(long, value_name = "SCENE")]
    pub compare: Option<PathBuf>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `asnr measure`.
pub fn run(args: &MeasureArgs) -> Result<()> {
    let white = imaging::Region::parse("white", &args.white)?;
    let black = imaging::Region::parse("black", &args.black)?;
    let frames = imaging::read_stack("frames", &args.frames)?;
    let capped = if args.capped_black.is_empty() {
        None
    } else {
        let paths = imaging::frames::frame_paths(&args.capped_black)?;
        let mut capped = Vec::new();
        for (i, path) in paths.iter().enumerate() {
            let frame = imaging::read_frame(path)?;
            // each frame of the stack's size and depth, as it is read: memory stays that of a stack
            imaging::frames::same_format(&frames[0], &frame)?;
            if (i + 1) as u64 * (frame.width * frame.height) as u64 > imaging::frames::MAX_STACK_SAMPLES {
                anyhow::bail!(
                    "--capped-black: {} frames of {} × {} pixels are more than the {} grey levels a stack may hold",
                    paths.len(),
                    frame.width,
                    frame.height,
                    imaging::frames::MAX_STACK_SAMPLES
                );
            }
            capped.push(frame);
        }
        Some(capped)
    };
    // the scene with the pixel aperture, as a measured edge has it
    let simulated = match &args.compare {
        None => None,
        Some(path) => {
            Some((path.display().to_string(), crate::load(Some(path), &["camera.pixel_mtf=true".to_owned()])?))
        }
    };
    let edge_frames = if args.edge.is_empty() { None } else { Some(crate::sfrcmd::read(&args.edge, &[])?.0) };
    let mtf = match (&edge_frames, &args.mtf_csv) {
        (Some(frames), _) => Some(report::measure::MtfFrom::Edge { frames, roi: args.edge_roi.as_deref() }),
        (None, Some(path)) => Some(report::measure::MtfFrom::Table(path)),
        (None, None) => None,
    };
    let inputs = report::measure::MeasureInputs {
        white,
        black,
        capped: capped.as_deref(),
        include_glare: args.include_glare,
        mtf,
        pixel_pitch_um: args.pixel_pitch_um,
        compare: simulated.as_ref().map(|(label, scene)| (label.as_str(), scene)),
    };
    let report = report::measure::measure(&frames, &inputs)?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report.json()?)?);
        return Ok(());
    }
    let (m, measured, comparison) = (&report.measurement, &report.measured, &report.comparison);
    let noise = if m.include_glare {
        "σ_s = σ_w: glare and camera noise included (SI)"
    } else {
        "σ_s = √(σ_w² − σ_b²) (eq. 3): the black region's noise subtracted"
    };
    outln!("frames            {:>12}   {} × {} pixels", m.frames, frames[0].width, frames[0].height);
    outln!("white region      {:>12}   pixels at {}", m.pixels.white, args.white);
    outln!("black region      {:>12}   pixels at {}", m.pixels.black, args.black);
    outln!("white level       {:>12.4}   DN (mean over frames and pixels)", m.white);
    outln!("black level       {:>12.4}   DN", m.black);
    outln!("signal            {:>12.4}   DN = white − black (eq. 2)", m.signal);
    outln!("σ_w               {:>12.4}   DN (√ of the per-pixel temporal sample variance, averaged)", m.sigma_white);
    outln!("σ_b               {:>12.4}   DN", m.sigma_black);
    outln!("σ_s               {:>12.4}   DN, {noise}", m.sigma_signal);
    outln!("SNR               {:>12.4}   signal/σ_s (eq. 4), ± {:.4} (standard error)", m.snr, m.snr_sigma);
    if let (Some(c), Some(vg), Some(mo)) = (m.capped_black, m.vg, m.modulation) {
        outln!(
            "capped black      {:>12.4}   DN (mean of {} capped frames over the black region)",
            c,
            capped.map_or(0, |f| f.len())
        );
        outln!("VG                {:>12.4}   (black − capped)/(white − capped) (SI eq. S10)", vg);
        outln!("M                 {:>12.4}   (1 − VG)/(1 + VG) (SI eq. S11–S12)", mo);
    }
    if let Some(measured) = &measured {
        let a = &measured.asnr;
        let angle = measured.edge_angle_deg.map(|d| format!(", edge {d:+.2}°")).unwrap_or_default();
        outln!(
            "mean MTF          {:>12.5}   ± {:.5}, 0 to Nyquist: {}{angle}",
            a.mean_mtf,
            a.mean_mtf_sigma,
            measured.mtf_source
        );
        outln!(
            "measured ASNR     {:>12.4}   ± {:.4} = SNR × mean MTF (eq. 1), errors propagated",
            a.asnr,
            a.asnr_sigma
        );
    }
    if let Some(c) = &comparison {
        outln!("simulated         {:>12}   {} (with the pixel aperture)", "", c.scene);
        outln!("  ASNR            {:>12.4}   measured/simulated {:.4}", c.asnr, c.asnr_ratio);
        outln!("  SNR0            {:>12.4}   measured/simulated {:.4}", c.snr0, c.snr_ratio);
        outln!("  mean MTF        {:>12.5}   measured/simulated {:.4}", c.mean_mtf, c.mean_mtf_ratio);
    }
    Ok(())
}
