//! `asnr characterize SERIES.toml`: a camera's STF, PTC, conversion gain, read noise and
//! saturation from stacks at increasing illumination (paper SI Fig. S6–S8, EMVA 1288).
//!
//! The series file (TOML; paths relative to it):
//!
//! ```toml
//! region = "0,0,64,64"        # X,Y,W,H in pixels; default: the whole frame
//! [dark]                      # the capped camera
//! frames = ["dark/"]          # files, directories (their .png in name order) or patterns
//! [[levels]]
//! illumination = 1.0          # any unit proportional to photons per pixel (irradiance × time)
//! frames = ["level-01/*.png"]
//! ```

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::Deserialize;

// Arguments of `asnr characterize`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct CharacterizeArgs {
    /// The series file (TOML: `region`, `[dark] frames`, `[[levels]] illumination, frames`).
    #[arg(value_name = "SERIES.toml")]
    pub series: PathBuf,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Also draw the STF and PTC on log-log axes with their fitted lines, with and without the
    /// capped black subtracted (paper SI Fig. S7–S8), into FILE (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Plot width in pixels (default 900).
    #[arg(long, value_name = "PX")]
    pub width: Option<u32>,
    /// Plot resolution: sets the size of text and lines (a point is 1/72 inch), and PNGs record
    /// it (default: the width over 6 inches).
    #[arg(long)]
    pub dpi: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Series {
    region: Option<String>,
    dark: Stack,
    levels: Vec<Stack>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Stack {
    #[serde(default)]
    illumination: Option<f64>,
    frames: Vec<PathBuf>,
}

fn read_stack(base: &Path, file: &Path, what: &str, stack: &Stack) -> Result<Vec<imaging::Frame>> {
    let paths: Vec<PathBuf> = stack.frames.iter().map(|p| base.join(p)).collect();
    imaging::read_stack("stack", &paths).with_context(|| format!("{}: {what}", file.display()))
}

/// Runs `asnr characterize`.
pub fn run(args: &CharacterizeArgs) -> Result<()> {
    let file = &args.series;
    let text = std::fs::read_to_string(file).with_context(|| format!("cannot read {}", file.display()))?;
    let series: Series = toml::from_str(&text).with_context(|| format!("{}: not a series file", file.display()))?;
    let base = file.parent().unwrap_or(Path::new("."));
    if series.levels.is_empty() {
        bail!("{}: no [[levels]]; expected at least 3 illuminated stacks", file.display());
    }
    let dark_frames = read_stack(base, file, "[dark]", &series.dark)?;
    let region = match &series.region {
        Some(text) => {
            imaging::Region::parse("characterization", text).with_context(|| format!("{}: region", file.display()))?
        }
        None => imaging::Region { x: 0, y: 0, width: dark_frames[0].width, height: dark_frames[0].height },
    };
    let dark = imaging::level_of(&dark_frames, region, 0.0).with_context(|| format!("{}: [dark]", file.display()))?;
    let mut levels = Vec::with_capacity(series.levels.len());
    for (i, stack) in series.levels.iter().enumerate() {
        let what = format!("levels[{i}]");
        let Some(illumination) = stack.illumination else {
            bail!(
                "{}: {what}.illumination is missing; expected a positive number (photons per pixel, any unit)",
                file.display()
            );
        };
        let frames = read_stack(base, file, &what, stack)?;
        let (f, d) = (&frames[0], &dark_frames[0]);
        if (f.width, f.height) != (d.width, d.height) {
            bail!(
                "{}: {what}: {} is {} × {} pixels, but the [dark] frame {} is {} × {}; every stack of a series must have the same size",
                file.display(),
                f.path.display(),
                f.width,
                f.height,
                d.path.display(),
                d.width,
                d.height
            );
        }
        levels.push(
            imaging::level_of(&frames, region, illumination).with_context(|| format!("{}: {what}", file.display()))?,
        );
    }
    let c = imaging::characterize(dark, &levels).with_context(|| file.display().to_string())?;
    for warning in &c.warnings {
        eprintln!("warning: {}: {warning}", file.display());
    }
    if let Some(path) = &args.plot {
        let figure = crate::plot::Figure::new(args.width, args.dpi)?;
        plot(path, &figure, file, &c)?;
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&c)?);
        return Ok(());
    }
    let fit = |f: &imaging::Fit| format!("{:.4} ± {:.4} ({} levels)", f.slope, f.slope_sigma, f.points);
    outln!(
        "capped black        μ = {:.3} DN, σ = {:.3} DN ({} frames, {} pixels)",
        c.dark.mean,
        c.dark.variance.sqrt(),
        c.dark.frames,
        c.dark.pixels
    );
    outln!(
        "conversion gain K   {:.5} ± {:.5} DN/e⁻ (EMVA 1288: σ² − σ²_dark = K (μ − μ_dark))",
        c.conversion_gain,
        c.conversion_gain_sigma
    );
    outln!(
        "read noise          {:.3} ± {:.3} e⁻ (√(σ²_dark − 1/12 DN²) / K, EMVA 1288)",
        c.read_noise_e,
        c.read_noise_sigma_e
    );
    outln!(
        "saturation          level {} (the largest variance): μ = {:.1} DN, {:.0} e⁻ above the capped black",
        c.saturation,
        c.levels[c.saturation].mean,
        c.saturation_e
    );
    outln!("STF slope           {} (log μ − μ_dark vs log illumination; 1 = linear)", fit(&c.stf));
    outln!("STF slope, raw      {} (capped black not subtracted)", fit(&c.stf_raw));
    outln!("PTC slope           {} (log √(σ² − σ²_dark) vs log μ − μ_dark; 0.5 = shot-noise limited)", fit(&c.ptc));
    outln!("PTC slope, raw      {} (capped black not subtracted)", fit(&c.ptc_raw));
    Ok(())
}

/// The STF and PTC of `c` on log-log axes (paper SI Fig. S7, S8): measured levels and fitted
/// lines, raw (red) and with the capped black subtracted (blue); hollow points were not fitted.
fn plot(path: &Path, figure: &crate::plot::Figure, file: &Path, c: &imaging::Characterization) -> Result<()> {
    use crate::plot::{FitPanel, FitSet};
    let slope = |what: &str, f: &imaging::Fit| format!("{what}: slope {:.4} ± {:.4}", f.slope, f.slope_sigma);
    let (dark_mean, dark_var) = (c.dark.mean, c.dark.variance);
    let set = |label: String, f: &imaging::Fit, colour: usize, point: &dyn Fn(&imaging::Level) -> (f64, f64)| FitSet {
        label,
        points: c.levels.iter().map(point).collect(),
        fitted: c.fitted.clone(),
        line: Some((f.slope, f.intercept)),
        colour,
    };
    let stf = FitPanel {
        caption: "(a) signal transfer (STF)",
        x: "illumination (series file units)",
        y: "mean signal (DN)",
        sets: vec![
            set(slope("STF, raw μ", &c.stf_raw), &c.stf_raw, 1, &|l: &imaging::Level| (l.illumination, l.mean)),
            set(slope("STF, μ − μ_dark (capped black subtracted)", &c.stf), &c.stf, 0, &|l: &imaging::Level| {
                (l.illumination, l.mean - dark_mean)
            }),
        ],
    };
    let ptc = FitPanel {
        caption: "(b) photon transfer (PTC)",
        x: "mean signal (DN)",
        y: "temporal noise σ (DN)",
        sets: vec![
            set(slope("PTC, raw σ vs μ", &c.ptc_raw), &c.ptc_raw, 1, &|l: &imaging::Level| {
                (l.mean, l.variance.sqrt())
            }),
            set(
                slope("PTC, √(σ² − σ²_dark) vs μ − μ_dark (subtracted)", &c.ptc),
                &c.ptc,
                0,
                &|l: &imaging::Level| (l.mean - dark_mean, (l.variance - dark_var).max(0.0).sqrt()),
            ),
        ],
    };
    let name = file.file_name().map_or_else(|| file.display().to_string(), |n| n.to_string_lossy().into_owned());
    let title = format!(
        "Camera transfer curves ({name}): K = {:.4} DN/e⁻, read noise {:.2} e⁻",
        c.conversion_gain, c.read_noise_e
    );
    crate::plot::fit_panels_plot("--plot", path, figure, &title, &[stf, ptc])
}
