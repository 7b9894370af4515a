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

/// Arguments of `asnr characterize`.
#[derive(clap::Args)]
pub struct CharacterizeArgs {
    /// The series file (TOML: `region`, `[dark] frames`, `[[levels]] illumination, frames`).
    #[arg(value_name = "SERIES.toml")]
    pub series: PathBuf,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
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
        levels.push(
            imaging::level_of(&frames, region, illumination).with_context(|| format!("{}: {what}", file.display()))?,
        );
    }
    let c = imaging::characterize(dark, &levels).with_context(|| file.display().to_string())?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
        return Ok(());
    }
    let fit = |f: &imaging::Fit| format!("{:.4} ± {:.4} ({} levels)", f.slope, f.slope_sigma, f.points);
    println!(
        "capped black        μ = {:.3} DN, σ = {:.3} DN ({} frames, {} pixels)",
        c.dark.mean,
        c.dark.variance.sqrt(),
        c.dark.frames,
        c.dark.pixels
    );
    println!(
        "conversion gain K   {:.5} ± {:.5} DN/e⁻ (EMVA 1288: σ² − σ²_dark = K (μ − μ_dark))",
        c.conversion_gain, c.conversion_gain_sigma
    );
    println!("read noise          {:.3} e⁻ (σ_dark / K)", c.read_noise_e);
    println!(
        "saturation          level {} (the largest variance): μ = {:.1} DN, {:.0} e⁻ above the capped black",
        c.saturation, c.levels[c.saturation].mean, c.saturation_e
    );
    println!("STF slope           {} (log μ − μ_dark vs log illumination; 1 = linear)", fit(&c.stf));
    println!("STF slope, raw      {} (capped black not subtracted)", fit(&c.stf_raw));
    println!("PTC slope           {} (log √(σ² − σ²_dark) vs log μ − μ_dark; 0.5 = shot-noise limited)", fit(&c.ptc));
    println!("PTC slope, raw      {} (capped black not subtracted)", fit(&c.ptc_raw));
    Ok(())
}
