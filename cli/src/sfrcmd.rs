//! `asnr sfr`: the MTF of slanted edges in camera frames (ISO 12233 e-SFR, `imaging::sfr`).

use std::path::{Path, PathBuf};

use anyhow::Result;

// Arguments of `asnr sfr`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct SfrArgs {
    /// Frames of the edge (8- or 16-bit grayscale PNG or TIFF, or 32-bit float TIFF), directories
    /// holding them, or patterns such as 'edge/*.png': one or more, averaged (two or more give
    /// the standard errors from their spread).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// Region of interest, X,Y,W,H in pixels (default: the whole frame).
    #[arg(long, value_name = "X,Y,W,H")]
    pub roi: Option<String>,
    /// Dark frames (the camera capped, same exposure), averaged per pixel and subtracted first.
    #[arg(long, num_args = 1.., value_name = "FILE")]
    pub dark: Vec<PathBuf>,
    /// The camera's response: DN − dark ∝ exposure^G (G the STF slope of `asnr characterize`;
    /// 1 is linear, 0.4545 a γ-2.2 encoding). Default: linear.
    #[arg(long, value_name = "G", conflicts_with = "transfer")]
    pub gamma: Option<f64>,
    /// The camera's measured transfer curve: the JSON of `asnr characterize --json` (its levels'
    /// mean above the dark level against their illumination), interpolated linearly.
    #[arg(long, value_name = "FILE")]
    pub transfer: Option<PathBuf>,
    /// Pixel pitch, µm: adds cycles/mm.
    #[arg(long, value_name = "UM")]
    pub pixel_pitch_um: Option<f64>,
    /// Fit the edge with a parabola instead of a straight line (a lens's distortion bends it).
    #[arg(long)]
    pub curved: bool,
    /// Distance along the normal analysed on each side of the edge, pixels (the LSF window;
    /// default 16, less where the ROI ends).
    #[arg(long, value_name = "PX")]
    pub reach: Option<f64>,
    /// Print one JSON object instead of the table.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Print the curve as CSV (edge, frequency_cyc_per_px, [frequency_cyc_per_mm,] mtf, mtf_sigma).
    #[arg(long)]
    pub csv: bool,
    /// Also draw the MTF curves into FILE (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

/// Reads the edge frames and the dark frames (one or more each, of one size and bit depth).
pub fn read(images: &[PathBuf], dark: &[PathBuf]) -> Result<(Vec<imaging::Frame>, Vec<imaging::Frame>)> {
    let frames = imaging::frames::read_frames("edge frames", images, 1)?;
    let dark = if dark.is_empty() { Vec::new() } else { imaging::frames::read_frames("dark frames", dark, 1)? };
    Ok((frames, dark))
}

/// Runs `asnr sfr`.
pub fn run(args: &SfrArgs) -> Result<()> {
    let options = report::measure::sfr_options(
        args.roi.as_deref(),
        args.gamma,
        args.transfer.as_deref(),
        args.pixel_pitch_um,
        args.curved,
        args.reach,
    )?;
    let (frames, dark) = read(&args.images, &args.dark)?;
    let result = imaging::sfr(&frames, &dark, &options)?;
    if let Some(path) = &args.plot {
        plot(path, &result, options.pixel_pitch_m)?;
    }
    if args.json {
        // one edge: its fields at the top level too
        outln!("{}", serde_json::to_string_pretty(&report::measure::sfr_json(&result)?)?);
        return Ok(());
    }
    let mm = options.pixel_pitch_m.is_some();
    if args.csv {
        let mut header = vec!["edge", "frequency_cyc_per_px"];
        if mm {
            header.push("frequency_cyc_per_mm");
        }
        header.extend(["mtf", "mtf_sigma"]);
        outln!("{}", header.join(","));
        for (i, e) in result.edges.iter().enumerate() {
            for j in 0..e.mtf.len() {
                let per_mm = e.frequency_cyc_per_mm.as_ref().map(|f| format!("{},", f[j])).unwrap_or_default();
                outln!("{},{},{per_mm}{},{}", i + 1, e.frequency_cyc_per_px[j], e.mtf[j], e.mtf_sigma[j]);
            }
        }
        return Ok(());
    }
    outln!(
        "frames            {:>12}   {} × {} pixels, ROI {},{},{},{}",
        result.frames,
        frames[0].width,
        frames[0].height,
        result.roi.x,
        result.roi.y,
        result.roi.width,
        result.roi.height
    );
    outln!("clipped           {:>11.3} %   of the ROI's samples at the largest code", 100.0 * result.clipped_fraction);
    let uncertainty = |e: &imaging::EdgeSfr| match e.uncertainty {
        imaging::sfr::Uncertainty::Frames => "standard errors from the frames' spread",
        imaging::sfr::Uncertainty::EsfBins => "standard errors from the ESF bins' scatter (one frame)",
    };
    for (i, e) in result.edges.iter().enumerate() {
        outln!("");
        outln!(
            "edge {}            {:>12}   {:+.3}° off the pixel axis, through column {:.1}, row {:.1}; {} lines, reach ±{:.1} px",
            i + 1,
            format!("{:?}", e.orientation).to_lowercase(),
            e.edge_angle_deg,
            e.centre_px[0],
            e.centre_px[1],
            e.lines,
            e.reach_px
        );
        outln!("dark, bright      {:>12.4}   {:.4} (linearized levels)", e.levels[0], e.levels[1]);
        outln!(
            "mean MTF          {:>12.5}   ± {:.5}, 0 to Nyquist (the ASNR's factor, eq. 1); {}",
            e.mean_mtf,
            e.mean_mtf_sigma,
            uncertainty(e)
        );
        outln!("MTF at Nyquist    {:>12.5}   ± {:.5}", e.mtf_nyquist, e.mtf_nyquist_sigma);
        match (e.mtf50_cyc_per_px, e.mtf50_cyc_per_mm) {
            (Some(px), Some(per_mm)) => outln!("MTF50             {px:>12.5}   cycles/pixel = {per_mm:.2} cycles/mm"),
            (Some(px), None) => outln!("MTF50             {px:>12.5}   cycles/pixel"),
            (None, _) => outln!("MTF50                     —   the MTF stays above 0.5 to 1 cycle/pixel"),
        }
        outln!(
            "{:>12}  {}{:>10}  {:>10}",
            "cycles/px",
            if mm { format!("{:>12}  ", "cycles/mm") } else { String::new() },
            "MTF",
            "± σ"
        );
        for j in (0..e.mtf.len()).step_by(5) {
            let per_mm = e.frequency_cyc_per_mm.as_ref().map(|f| format!("{:>12.2}  ", f[j])).unwrap_or_default();
            outln!("{:>12.2}  {per_mm}{:>10.5}  {:>10.5}", e.frequency_cyc_per_px[j], e.mtf[j], e.mtf_sigma[j]);
        }
    }
    Ok(())
}

/// The MTF curves with their ±σ bands, Nyquist marked.
fn plot(path: &Path, result: &imaging::Sfr, pitch_m: Option<f64>) -> Result<()> {
    let scale = pitch_m.map_or(1.0, |p| 1.0 / (p * 1e3));
    let mut series = Vec::new();
    for (i, e) in result.edges.iter().enumerate() {
        let points = |k: f64| -> Vec<(f64, f64)> {
            e.frequency_cyc_per_px
                .iter()
                .zip(&e.mtf)
                .zip(&e.mtf_sigma)
                .map(|((f, m), s)| (f * scale, m + k * s))
                .collect()
        };
        let name = if result.edges.len() > 1 { format!("edge {} ", i + 1) } else { String::new() };
        series.push(crate::plot::Series {
            label: format!("{name}MTF ({:+.2}°, mean to Nyquist {:.4})", e.edge_angle_deg, e.mean_mtf),
            points: points(0.0),
            shaded: Vec::new(),
            best: None,
        });
        for (k, sign) in [(1.0, "+"), (-1.0, "−")] {
            series.push(crate::plot::Series {
                label: format!("{name}MTF {sign} σ"),
                points: points(k),
                shaded: Vec::new(),
                best: None,
            });
        }
    }
    let x = if pitch_m.is_some() {
        "spatial frequency along the edge normal (cycles/mm)"
    } else {
        "spatial frequency along the edge normal (cycles/pixel)"
    };
    let labels = crate::plot::Labels { title: "slanted-edge MTF (ISO 12233 e-SFR)", x, y: "MTF", ..Default::default() };
    let marks = [crate::plot::Mark { x: 0.5 * scale, label: Some("Nyquist".to_owned()) }];
    crate::plot::lines_plot("--plot", path, &crate::plot::Figure::default(), &labels, &series, &marks, false)
}
