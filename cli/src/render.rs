//! `asnr render`: simulated and restored images of a test target through a scene, one per
//! spectral range (the paper's Fig. 4), and `asnr psf` / `asnr otf`: the scene's 2-D PSF and OTF.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use imaging::render::{Rendering, Settings};
use imaging::target::{self, Polarity, Target};
use serde::Serialize;

// Arguments of `asnr render`.
// (a plain comment, not a doc comment: clap would make it the subcommand's about, over the
// variant's, when the arguments are built, which is deferred to the subcommand run)
#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
    pub scene: Option<PathBuf>,
    /// Override a scene key by its dotted path (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Folder for the images, the panel, contrast.csv and render.json (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Spectral ranges to render, nm (each sets spectrum.range_nm), in the panel's order, e.g.
    /// 100,50,10 as in the paper's Fig. 3 and 4. Without it, the scene as it is.
    #[arg(long, value_delimiter = ',', value_name = "NM")]
    pub ranges: Vec<f64>,
    /// Seed of the noise (frame i of a range uses seed + i; the same seed gives the same images).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub seed: u64,
    /// The object: `usaf` (dark bars on a clear ground), `usaf-negative` (clear bars on a dark
    /// ground), `slanted-edge` (for `asnr sfr`: see --angle, --contrast, --size), or a grayscale
    /// PNG (one file pixel per detector pixel, white = the scene's radiance).
    #[arg(long, default_value = "usaf", value_name = "usaf|usaf-negative|slanted-edge|FILE.png")]
    pub target: String,
    /// Slanted edge: degrees off vertical (ISO 12233: about 5°).
    #[arg(long, default_value_t = 5.0, value_name = "DEG")]
    pub angle: f64,
    /// Slanted edge: Michelson contrast, (bright − dark)/(bright + dark) (ISO 12233: about 0.6;
    /// 1 for a black dark side, which `asnr measure` can also read the SNR from).
    #[arg(long, default_value_t = 0.6, value_name = "C")]
    pub contrast: f64,
    /// Slanted edge: frame size, pixels a side.
    #[arg(long, default_value_t = 160, value_name = "PX")]
    pub size: usize,
    /// USAF groups to draw, FIRST:LAST (default: from Nyquist/16 to the group holding Nyquist).
    #[arg(long, value_name = "FIRST:LAST")]
    pub groups: Option<String>,
    /// Fine cells per pixel along each axis (odd, 1–9): the optics are applied on this finer
    /// grid before the pixels sample it.
    #[arg(long, default_value_t = 3, value_name = "S")]
    pub oversample: usize,
    /// Raw frames per range: with 2 or more, each range's frames are also written to
    /// frames-<range>/ as 16-bit PNGs for `asnr measure` (the paper grabbed 30).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub frames: usize,
    /// Leave out the veiling glare of the light in other orders (the paper's Fig. 4 did).
    #[arg(long)]
    pub no_glare: bool,
    /// Subtract the black level from the restored images and raise the white back by a gain.
    #[arg(long)]
    pub subtract_black: bool,
    /// Print render.json's object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// One range's results, as render.json has them.
#[derive(Serialize)]
struct RangeReport {
    label: String,
    range_nm: Option<f64>,
    asnr: f64,
    snr0: f64,
    mean_mtf: f64,
    photoelectrons: f64,
    veil_e: f64,
    dark_e: f64,
    white_e: f64,
    black_e: f64,
    noise_e: f64,
    nsr: f64,
    /// 16-bit PNG code per e⁻ of the raw and restored 16-bit images.
    png16_per_e: f64,
    /// DN per e⁻ of the camera's ADC, if it has one.
    dn_per_e: Option<f64>,
    mean_contrast_raw: f64,
    mean_contrast_restored: f64,
    /// Contrast-to-noise ratios averaged over frequency as the ASNR is (eq. 1).
    cnr_raw: Option<f64>,
    cnr_restored: Option<f64>,
    otf_evaluations: usize,
    direction_dependent: bool,
    files: Vec<String>,
    /// Per bar set: modulation (noise-free, raw, restored) and contrast-to-noise ratios.
    bars: Vec<imaging::render::BarContrast>,
}

/// render.json.
#[derive(Serialize)]
struct Report {
    scene: String,
    target: String,
    width: usize,
    height: usize,
    pixel_pitch_um: f64,
    oversample: usize,
    seed: u64,
    frames: usize,
    glare: bool,
    subtract_black: bool,
    /// Where eq. 2–4 can be measured: `asnr measure frames-…/ --white … --black …`.
    white_region: Option<imaging::Region>,
    black_region: Option<imaging::Region>,
    ranges: Vec<RangeReport>,
    panel: Option<String>,
    contrast_csv: Option<String>,
}

/// Runs `asnr render`.
pub fn run(args: &RenderArgs) -> Result<()> {
    if args.frames == 0 || args.frames > 1000 {
        anyhow::bail!("--frames {}: expected 1 to 1000 frames per range", args.frames);
    }
    if let Some(bad) = args.ranges.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
        anyhow::bail!("--ranges: {bad} nm: expected spectral ranges > 0 nm");
    }
    let label = args.scene.as_ref().map_or("embedded paper scene".to_owned(), |p| p.display().to_string());
    // the scenes, each validated before any image is made
    let ranges: Vec<Option<f64>> =
        if args.ranges.is_empty() { vec![None] } else { args.ranges.iter().copied().map(Some).collect() };
    let mut scenes = Vec::new();
    for range in &ranges {
        let mut set = args.set.clone();
        if let Some(r) = range {
            set.push(format!("spectrum.range_nm={r}"));
        }
        scenes.push(crate::load(args.scene.as_deref(), &set)?);
    }
    let pitch = scenes[0].camera().pixel_pitch();
    let nyquist_cyc_per_mm = scenes[0].camera().nyquist() * 1e-3;
    let object = make_target(args, pitch, nyquist_cyc_per_mm)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("--out {}: cannot create the folder", args.out.display()))?;
    let settings =
        Settings { seed: args.seed, frames: args.frames, glare: !args.no_glare, subtract_black: args.subtract_black };
    let progress = crate::sweep::progress_bar(ranges.len() as u64, "ranges")?;
    let mut reports = Vec::new();
    let mut columns = Vec::new();
    let mut csv = scene::sweep::csv_line([
        "range_nm",
        "group",
        "element",
        "frequency_cyc_per_mm",
        "orientation",
        "above_nyquist",
        "expected",
        "raw",
        "restored",
        "cnr_raw",
        "cnr_restored",
    ]);
    for (range, scene) in ranges.iter().zip(&scenes) {
        let evaluation = metric::evaluate(scene).map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
        let rendering = imaging::render(scene, &evaluation, &object, &settings)?;
        // an ADC without a black level clips the dark noise at 0 DN (EMVA 1288's offset is missing)
        if rendering.dn_per_e.is_some() {
            let frame = &rendering.frames[0];
            let zeros = frame.iter().filter(|&&v| v == 0.0).count() as f64 / frame.len() as f64;
            if zeros > 0.01 && scene.camera().sensor().black_level_dn() == 0.0 {
                eprintln!(
                    "warning: {:.1} % of the pixels read 0 DN: the ADC clips the dark noise there (no black level), so dark frames measure low noise; set camera.black_level_dn to a few σ of the dark noise in DN",
                    100.0 * zeros
                );
            }
        }
        let tag = range.map_or("scene".to_owned(), |r| format!("{}nm", crate::plot::number(r)));
        let (files, png16_per_e) = write_images(&args.out, &tag, &rendering)?;
        for b in &rendering.bars {
            let orientation = match b.orientation {
                target::Orientation::Vertical => "vertical",
                target::Orientation::Horizontal => "horizontal",
            };
            csv.push_str(&scene::sweep::csv_line([
                range.map_or(String::new(), |r| r.to_string()),
                b.group.to_string(),
                b.element.to_string(),
                b.frequency_cyc_per_mm.to_string(),
                orientation.to_owned(),
                b.above_nyquist.to_string(),
                b.expected.to_string(),
                b.raw.to_string(),
                b.restored.to_string(),
                b.cnr_raw.map_or(String::new(), |v| v.to_string()),
                b.cnr_restored.map_or(String::new(), |v| v.to_string()),
            ]));
        }
        let heading = match range {
            Some(r) => format!("{} nm", crate::plot::number(*r)),
            None => scene.title().unwrap_or("scene").to_owned(),
        };
        columns.push(crate::panel::Column {
            heading: format!("{heading}: ASNR {:.2}", evaluation.asnr),
            raw: display(&rendering.frames[0], rendering.dn_per_e.unwrap_or(1.0), &rendering),
            restored: display(&rendering.restored_e, 1.0, &rendering),
        });
        reports.push(RangeReport {
            label: tag,
            range_nm: *range,
            asnr: evaluation.asnr,
            snr0: evaluation.snr0,
            mean_mtf: evaluation.mean_mtf,
            photoelectrons: rendering.signal_e,
            veil_e: rendering.veil_e,
            dark_e: rendering.dark_e,
            white_e: rendering.white_e,
            black_e: rendering.black_e,
            noise_e: rendering.noise_e,
            nsr: rendering.nsr,
            png16_per_e,
            dn_per_e: rendering.dn_per_e,
            mean_contrast_raw: rendering.mean_raw_contrast(),
            mean_contrast_restored: rendering.mean_restored_contrast(),
            cnr_raw: rendering.frequency_mean_cnr_raw(),
            cnr_restored: rendering.frequency_mean_cnr_restored(),
            otf_evaluations: rendering.otf_evaluations,
            direction_dependent: rendering.direction_dependent,
            files,
            bars: rendering.bars.clone(),
        });
        progress.inc(1);
    }
    progress.finish_and_clear();
    let panel_path = args.out.join("panel.png");
    let title = format!(
        "{}: raw (top) and Wiener-restored (bottom){}",
        object_name(&object),
        if args.no_glare { ", no veiling glare" } else { ", with veiling glare" }
    );
    crate::panel::write(&panel_path, &title, object.width, object.height, &columns)?;
    let contrast_path = (!object.bars.is_empty()).then(|| args.out.join("contrast.csv"));
    if let Some(path) = &contrast_path {
        std::fs::write(path, &csv).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    let report = Report {
        scene: label.clone(),
        target: object.description.clone(),
        width: object.width,
        height: object.height,
        pixel_pitch_um: pitch * 1e6,
        oversample: object.oversample,
        seed: args.seed,
        frames: args.frames,
        glare: !args.no_glare,
        subtract_black: args.subtract_black,
        white_region: object.white,
        black_region: object.black,
        ranges: reports,
        panel: Some(panel_path.display().to_string()),
        contrast_csv: contrast_path.map(|p| p.display().to_string()),
    };
    let json = serde_json::to_string_pretty(&report)?;
    let json_path = args.out.join("render.json");
    std::fs::write(&json_path, &json).with_context(|| format!("{}: cannot write", json_path.display()))?;
    if args.json {
        outln!("{json}");
    } else {
        out!("{}", table(&report, &object));
    }
    Ok(())
}

fn object_name(object: &Target) -> String {
    if object.bars.is_empty() { "image".to_owned() } else { "USAF-1951 target".to_owned() }
}

/// The table `asnr render` prints.
fn table(report: &Report, object: &Target) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "scene      {}", report.scene);
    let _ = writeln!(out, "target     {}", report.target);
    let _ = writeln!(
        out,
        "image      {} × {} pixels of {} µm, optics on a grid {} times finer, seed {}, {}",
        report.width,
        report.height,
        crate::plot::number(report.pixel_pitch_um),
        report.oversample,
        report.seed,
        if report.glare { "veiling glare of the other orders included" } else { "no veiling glare" }
    );
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "  {:<10} {:>8} {:>8} {:>10} {:>9} {:>9} {:>12} {:>9} {:>8} {:>9}",
        "range", "ASNR", "SNR0", "N e⁻", "veil e⁻", "σ e⁻", "contrast raw", "restored", "CNR raw", "restored"
    );
    for r in &report.ranges {
        let _ = writeln!(
            out,
            "  {:<10} {:>8.3} {:>8.3} {:>10.1} {:>9.1} {:>9.2} {:>12.4} {:>9.4} {:>8} {:>9}",
            r.label,
            r.asnr,
            r.snr0,
            r.photoelectrons,
            r.veil_e,
            r.noise_e,
            r.mean_contrast_raw,
            r.mean_contrast_restored,
            r.cnr_raw.map_or("–".to_owned(), |v| format!("{v:.3}")),
            r.cnr_restored.map_or("–".to_owned(), |v| format!("{v:.3}"))
        );
    }
    if !object.bars.is_empty() {
        let _ = writeln!(
            out,
            "\n  contrast: the bar modulation |bars − gaps|/(bars + gaps), mean over the {} bar sets below Nyquist;\n  CNR: the mean of the bars' fundamental amplitude over the frames over its temporal σ (eq. 2–4 for a bar set), averaged over frequency as the ASNR is (per set: contrast.csv)",
            object.bars.iter().filter(|b| b.resolvable_by_pixels()).count()
        );
    }
    if let (Some(w), Some(b)) = (report.white_region, report.black_region) {
        let _ = writeln!(
            out,
            "  white and black areas: --white {},{},{},{} --black {},{},{},{} (for asnr measure on frames-*/)",
            w.x, w.y, w.width, w.height, b.x, b.y, b.width, b.height
        );
    }
    if let Some(panel) = &report.panel {
        let _ = writeln!(out, "  panel: {panel}");
    }
    out
}

/// The object of `--target`.
fn make_target(args: &RenderArgs, pitch: f64, nyquist_cyc_per_mm: f64) -> Result<Target> {
    if args.target == "slanted-edge" {
        if args.groups.is_some() {
            anyhow::bail!("--groups: only for --target usaf or usaf-negative, not a slanted edge");
        }
        return Ok(target::slanted_edge(args.size, args.angle, args.contrast, args.oversample)?);
    }
    let polarity = match args.target.as_str() {
        "usaf" => Some(Polarity::Positive),
        "usaf-negative" => Some(Polarity::Negative),
        _ => None,
    };
    let Some(polarity) = polarity else {
        if args.groups.is_some() {
            anyhow::bail!("--groups: only for --target usaf or usaf-negative, not an image file");
        }
        let path = Path::new(&args.target);
        if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            anyhow::bail!(
                "--target {}: expected usaf, usaf-negative, slanted-edge or a grayscale .png file",
                args.target
            );
        }
        return Ok(target::from_png(path, args.oversample)?);
    };
    let groups = match &args.groups {
        None => target::usaf_groups_for(nyquist_cyc_per_mm),
        Some(text) => {
            let parsed = text.split_once(':').and_then(|(a, b)| Some((a.trim().parse().ok()?, b.trim().parse().ok()?)));
            parsed.ok_or_else(|| {
                anyhow::anyhow!("--groups {text}: expected FIRST:LAST, two whole USAF group numbers such as 3:6")
            })?
        }
    };
    let given =
        args.groups.as_deref().map_or_else(|| format!("{}:{} (the default)", groups.0, groups.1), str::to_owned);
    // the coarsest bars of the first group must lie at or below Nyquist: above it the camera
    // resolves none of the bars, and their contrast and frequency (2^2000 cycles/mm is ∞) mean
    // nothing
    let coarsest = target::usaf_frequency(groups.0, 1);
    if groups.0 <= groups.1 && !(coarsest.is_finite() && coarsest <= nyquist_cyc_per_mm) {
        anyhow::bail!(
            "--groups {given}: group {}'s coarsest bars ({} cycles/mm) lie above the camera's Nyquist frequency {:.1} cycles/mm: the camera resolves none of them; expected a first group of at most {} (the group holding Nyquist)",
            groups.0,
            if coarsest.is_finite() {
                format!("{}", optics::round_for_display(coarsest))
            } else {
                format!("2^{}", groups.0)
            },
            nyquist_cyc_per_mm,
            target::usaf_groups_for(nyquist_cyc_per_mm).1
        );
    }
    target::usaf(pitch, groups, polarity, args.oversample).map_err(|e| match e {
        imaging::Error::Render { message } => anyhow::anyhow!("--groups {given}: {message}"),
        e => e.into(),
    })
}

/// 8-bit display levels of an image in units of `per_e` per e⁻: 0 e⁻ → 0, the white area's
/// expected level → 220 (headroom for noise and overshoot), clipped.
fn display(image: &[f64], per_e: f64, r: &Rendering) -> Vec<u8> {
    let scale = 220.0 / (r.white_e * per_e);
    image.iter().map(|v| (v * scale).round().clamp(0.0, 255.0) as u8).collect()
}

/// Writes the raw (first frame) and restored images of one range, 8-bit for viewing and 16-bit
/// for measuring, and the frames for `asnr measure`; returns the files and the 16-bit scale.
fn write_images(dir: &Path, tag: &str, r: &Rendering) -> Result<(Vec<String>, f64)> {
    let mut files = Vec::new();
    let mut put = |name: String, levels: &[u16], depth: u8| -> Result<()> {
        let path = dir.join(name);
        imaging::write_png(&path, r.width, r.height, levels, depth)?;
        files.push(path.display().to_string());
        Ok(())
    };
    // 16-bit codes: the ADC's DN as they are; without an ADC, e⁻ times the power of two that
    // keeps the white level + 8σ below 65535
    let top = r.white_e + 8.0 * r.noise_e;
    let png16_per_e = match r.dn_per_e {
        Some(k) => k,
        None => 2f64.powi((65535.0 / top).log2().floor().clamp(-20.0, 20.0) as i32),
    };
    let frame_scale = if r.dn_per_e.is_some() { 1.0 } else { png16_per_e };
    let to16 = |image: &[f64], scale: f64| -> Vec<u16> {
        image.iter().map(|v| (v * scale).round().clamp(0.0, 65535.0) as u16).collect()
    };
    let eight =
        |image: &[f64], per_e: f64| -> Vec<u16> { display(image, per_e, r).into_iter().map(u16::from).collect() };
    put(format!("raw-{tag}.png"), &eight(&r.frames[0], r.dn_per_e.unwrap_or(1.0)), 8)?;
    put(format!("raw-{tag}-16bit.png"), &to16(&r.frames[0], frame_scale), 16)?;
    put(format!("restored-{tag}.png"), &eight(&r.restored_e, 1.0), 8)?;
    put(format!("restored-{tag}-16bit.png"), &to16(&r.restored_e, png16_per_e), 16)?;
    if r.frames.len() > 1 {
        let folder = dir.join(format!("frames-{tag}"));
        std::fs::create_dir_all(&folder).with_context(|| format!("{}: cannot create", folder.display()))?;
        for (i, frame) in r.frames.iter().enumerate() {
            let path = folder.join(format!("frame-{i:03}.png"));
            imaging::write_png(&path, r.width, r.height, &to16(frame, frame_scale), 16)?;
        }
        files.push(format!("{}/ ({} frames)", folder.display(), r.frames.len()));
    }
    Ok((files, png16_per_e))
}
