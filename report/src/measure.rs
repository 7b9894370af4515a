//! Measurements of camera frames, shared by `asnr sfr` / `asnr measure` and the Python
//! package's `asnr.sfr` / `asnr.measure`, so that both return the same fields and numbers: the
//! slanted-edge analysis's options and JSON object ([`sfr_options`], [`sfr_json`]), and the
//! measured ASNR — the stack's SNR times the mean MTF of an edge or a table, beside a scene's
//! simulated values ([`measure`], [`MeasureReport::json`]).
//!
//! The frames are read (or, from Python, built from arrays) by the caller; the computation is
//! `imaging`'s.

use std::path::Path;

use anyhow::{Context, Result, bail};
use imaging::{Frame, MeasuredAsnr, Measurement, Region};
use serde::Serialize;

/// The response of a `--transfer` file: `asnr characterize --json`'s levels (their mean above
/// the dark level against their illumination), interpolated linearly.
///
/// # Errors
/// A file that cannot be read, is not JSON, or lacks `dark.mean` and the levels' `mean` and
/// `illumination`; a table that is not increasing.
pub fn read_transfer(path: &Path) -> Result<imaging::sfr::Response> {
    let text = std::fs::read_to_string(path).with_context(|| format!("--transfer {}: cannot read", path.display()))?;
    let value: serde_json::Value = serde_json::from_str(&text).with_context(|| {
        format!("--transfer {}: not JSON (expected `asnr characterize --json`'s output)", path.display())
    })?;
    let number = |v: &serde_json::Value, key: &str| v.get(key).and_then(serde_json::Value::as_f64);
    let dark = value.get("dark").and_then(|d| number(d, "mean"));
    let levels = value.get("levels").and_then(serde_json::Value::as_array);
    let (Some(dark), Some(levels)) = (dark, levels) else {
        bail!(
            "--transfer {}: no `dark.mean` and `levels` (expected `asnr characterize --json`'s output)",
            path.display()
        );
    };
    let mut points = Vec::new();
    for (i, level) in levels.iter().enumerate() {
        let (Some(mean), Some(illumination)) = (number(level, "mean"), number(level, "illumination")) else {
            bail!("--transfer {}: levels[{i}] has no `mean` and `illumination`", path.display());
        };
        points.push((mean - dark, illumination));
    }
    points.sort_by(|a, b| a.1.total_cmp(&b.1));
    let response = imaging::sfr::Response::Table {
        dn: points.iter().map(|p| p.0).collect(),
        exposure: points.iter().map(|p| p.1).collect(),
    };
    response.check().with_context(|| format!("--transfer {}", path.display()))?;
    Ok(response)
}

/// The e-SFR's options from the command line's words: `roi` as `X,Y,W,H`, the response (a
/// `gamma`, a `transfer` file, or linear), the pixel pitch in µm, a 2nd-order edge (`curved`),
/// the LSF's reach in pixels.
///
/// # Errors
/// A ROI that is not `X,Y,W,H`, a pitch outside (0, 1000) µm, a reach outside 4–1000 pixels,
/// those of [`read_transfer`].
pub fn sfr_options(
    roi: Option<&str>,
    gamma: Option<f64>,
    transfer: Option<&Path>,
    pixel_pitch_um: Option<f64>,
    curved: bool,
    reach: Option<f64>,
) -> Result<imaging::sfr::Options> {
    let roi = roi.map(|r| Region::parse("ROI", r)).transpose()?;
    let response = match (gamma, transfer) {
        (Some(_), Some(path)) => bail!("--gamma and --transfer {}: give one response, not both", path.display()),
        (Some(g), None) => imaging::sfr::Response::Gamma(g),
        (None, Some(path)) => read_transfer(path)?,
        (None, None) => imaging::sfr::Response::Linear,
    };
    if let Some(p) = pixel_pitch_um
        && !(p.is_finite() && p > 0.0 && p < 1000.0)
    {
        bail!("--pixel-pitch-um {p}: expected a pitch > 0 and < 1000 µm");
    }
    if let Some(r) = reach
        && !(r.is_finite() && (4.0..=1000.0).contains(&r))
    {
        bail!("--reach {r}: expected 4 to 1000 pixels");
    }
    Ok(imaging::sfr::Options {
        roi,
        response,
        pixel_pitch_m: pixel_pitch_um.map(|p| p * 1e-6),
        degree: if curved { 2 } else { 1 },
        reach_px: reach,
    })
}

/// `asnr sfr --json`'s object: the analysis with its `edges`, and, when the ROI holds one edge,
/// that edge's fields at the top level too (`mean_mtf`, `mtf50_cyc_per_px`, `mtf_nyquist`,
/// `edge_angle_deg`, `frequency_cyc_per_px`, `mtf`, …).
///
/// # Errors
/// None in practice (the values are plain numbers and strings).
pub fn sfr_json(result: &imaging::Sfr) -> Result<serde_json::Value> {
    let mut value = serde_json::to_value(result)?;
    if let ([edge], Some(object)) = (&result.edges[..], value.as_object_mut())
        && let serde_json::Value::Object(fields) = serde_json::to_value(edge)?
    {
        object.extend(fields);
    }
    Ok(value)
}

/// Where the measured mean MTF comes from.
pub enum MtfFrom<'a> {
    /// Frames of a slanted edge taken with the same camera, and the edge's ROI (`X,Y,W,H`;
    /// default the whole frame); one edge.
    Edge {
        /// The frames (one or more, one size).
        frames: &'a [Frame],
        /// The region holding the edge.
        roi: Option<&'a str>,
    },
    /// A CSV table with columns `frequency_cyc_per_mm, mtf`, from 0 to at least Nyquist.
    Table(&'a Path),
}

/// The simulated values set beside the measured ones (the paper's Fig. 2b).
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// The scene's name (its file).
    pub scene: String,
    /// Its simulated ASNR, with the pixel aperture.
    pub asnr: f64,
    /// Its SNR0.
    pub snr0: f64,
    /// Its mean MTF to Nyquist, with the pixel aperture.
    pub mean_mtf: f64,
    /// Measured ASNR over simulated.
    pub asnr_ratio: f64,
    /// Measured SNR over simulated SNR0.
    pub snr_ratio: f64,
    /// Measured mean MTF over simulated.
    pub mean_mtf_ratio: f64,
}

/// The measured ASNR, with where its MTF came from.
#[derive(Clone, Debug, Serialize)]
pub struct Measured {
    /// SNR × mean MTF with their standard errors.
    #[serde(flatten)]
    pub asnr: MeasuredAsnr,
    /// A sentence naming the edge frames or the table.
    pub mtf_source: String,
    /// The edge's angle off the pixel axis, degrees (an edge only).
    pub edge_angle_deg: Option<f64>,
}

/// What [`measure`] found: the stack's SNR (and glare), the measured ASNR when an MTF was
/// given, and the comparison with a scene when one was given.
#[derive(Clone, Debug)]
pub struct MeasureReport {
    /// The stack's statistics (eq. 2–4; SI eq. S10–S12 with capped-black frames).
    pub measurement: Measurement,
    /// The measured ASNR.
    pub measured: Option<Measured>,
    /// The simulated values beside the measured ones.
    pub comparison: Option<Comparison>,
}

impl MeasureReport {
    /// `asnr measure --json`'s object: the measurement's fields, then `measured_asnr` and
    /// `compare` when there are.
    ///
    /// # Errors
    /// None in practice (plain numbers and strings).
    pub fn json(&self) -> Result<serde_json::Value> {
        let mut value = serde_json::to_value(&self.measurement)?;
        if let Some(object) = value.as_object_mut() {
            if let Some(measured) = &self.measured {
                object.insert("measured_asnr".to_owned(), serde_json::to_value(measured)?);
            }
            if let Some(c) = &self.comparison {
                object.insert("compare".to_owned(), serde_json::to_value(c)?);
            }
        }
        Ok(value)
    }
}

/// The inputs of [`measure`] besides the stack.
pub struct MeasureInputs<'a> {
    /// The white region.
    pub white: Region,
    /// The black region.
    pub black: Region,
    /// Frames taken with the camera capped (same size as the stack), for VG and M.
    pub capped: Option<&'a [Frame]>,
    /// σ_s = σ_w (glare and camera noise counted, the SI's variant).
    pub include_glare: bool,
    /// The measured MTF, if any.
    pub mtf: Option<MtfFrom<'a>>,
    /// Pixel pitch, µm (Nyquist of a table; default the compared scene's).
    pub pixel_pitch_um: Option<f64>,
    /// A scene to set beside the measurement, and its name: evaluated as given, so the caller
    /// sets `camera.pixel_mtf = true` (a measured edge contains the pixel aperture).
    pub compare: Option<(&'a str, &'a metric::Scene)>,
}

/// `asnr measure`: the SNR of the stack `frames` (eq. 2–4), and with an MTF the measured ASNR
/// = SNR × mean MTF with its propagated standard error, beside a scene's simulated values.
///
/// # Errors
/// Those of `imaging::measure` and `imaging::sfr` (naming the file and the reason), a pitch
/// outside (0, 1000) µm, an edge ROI holding no edge or several, a table without Nyquist (no
/// pitch), a scene that cannot be evaluated, a comparison without a measured MTF.
pub fn measure(frames: &[Frame], inputs: &MeasureInputs<'_>) -> Result<MeasureReport> {
    let m = imaging::measure(frames, inputs.white, inputs.black, inputs.capped, inputs.include_glare)?;
    if let Some(p) = inputs.pixel_pitch_um
        && !(p.is_finite() && p > 0.0 && p < 1000.0)
    {
        bail!("--pixel-pitch-um {p}: expected a pitch > 0 and < 1000 µm");
    }
    let simulated = match inputs.compare {
        None => None,
        Some((label, scene)) => {
            let evaluation = metric::evaluate(scene).with_context(|| format!("--compare {label}"))?;
            Some((label, scene.camera().pixel_pitch(), evaluation))
        }
    };
    let pitch_m = inputs.pixel_pitch_um.map(|p| p * 1e-6).or(simulated.as_ref().map(|s| s.1));
    let measured = match &inputs.mtf {
        None => None,
        Some(from) => {
            let (mean, sigma, source, angle) = measured_mtf(from, pitch_m)?;
            Some(Measured {
                asnr: MeasuredAsnr::new(m.snr, m.snr_sigma, mean, sigma),
                mtf_source: source,
                edge_angle_deg: angle,
            })
        }
    };
    let comparison = match (&simulated, &measured) {
        (Some((scene, _, e)), Some(measured)) => Some(Comparison {
            scene: (*scene).to_owned(),
            asnr: e.asnr,
            snr0: e.snr0,
            mean_mtf: e.mean_mtf,
            asnr_ratio: measured.asnr.asnr / e.asnr,
            snr_ratio: m.snr / e.snr0,
            mean_mtf_ratio: measured.asnr.mean_mtf / e.mean_mtf,
        }),
        (Some(_), None) => bail!("--compare needs the measured MTF too: give --edge IMAGE… or --mtf-csv FILE"),
        _ => None,
    };
    Ok(MeasureReport { measurement: m, measured, comparison })
}

/// The mean MTF to Nyquist of an edge or a table: value, standard error, where it came from, the
/// edge's angle.
fn measured_mtf(from: &MtfFrom<'_>, pitch_m: Option<f64>) -> Result<(f64, f64, String, Option<f64>)> {
    match from {
        MtfFrom::Edge { frames, roi } => {
            let options = sfr_options(*roi, None, None, pitch_m.map(|p| p * 1e6), false, None)?;
            let result = imaging::sfr(frames, &[], &options)?;
            // one MTF is required: several edges are refused with the option that picks one
            let e = result.single().map_err(|e| match e {
                imaging::Error::Edge { path, message } => imaging::Error::Edge {
                    path,
                    message: format!("{message} (asnr measure --edge-roi X,Y,W,H; edge_roi=\"X,Y,W,H\" in Python)"),
                },
                other => other,
            })?;
            let first = frames.first().map_or_else(String::new, |f| f.path.display().to_string());
            Ok((
                e.mean_mtf,
                e.mean_mtf_sigma,
                format!("slanted edge, {} frame(s) from {first}", result.frames),
                Some(e.edge_angle_deg),
            ))
        }
        MtfFrom::Table(path) => {
            let Some(pitch) = pitch_m else {
                bail!(
                    "--mtf-csv {}: Nyquist needs the pixel pitch: give --pixel-pitch-um or --compare SCENE",
                    path.display()
                );
            };
            // `frequency_cyc_per_mm, mtf` rows, the frequencies increasing (the scene's table reader)
            let (f, m) = scene::read_pairs(path, &scene::FREQUENCY, 0.0, 1.0, "MTF")
                .with_context(|| format!("--mtf-csv {}", path.display()))?;
            let nyquist = 1.0 / (2.0 * pitch * 1e3);
            let mean = imaging::measure::mean_mtf_of_table(path, &f, &m, nyquist)?;
            Ok((mean, 0.0, format!("table {} (no standard error given)", path.display()), None))
        }
    }
}
