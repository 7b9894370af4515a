//! The metrics beyond the ASNR ([`metric::metrics`]): their options parsed from the command
//! line's and the Python package's words, their table lines and their JSON fields.

use std::fmt::Write;

use anyhow::{Result, bail};
use metric::{DiskTask, Evaluation, Metrics, MetricsOptions, ObjectSpectrum, Scene};
use serde::Serialize;

/// `flat` or `power-law:BETA` (0 ≤ β < 2).
pub fn parse_object(text: &str) -> Result<ObjectSpectrum> {
    let t = text.trim();
    if t == "flat" {
        return Ok(ObjectSpectrum::Flat);
    }
    if let Some(beta) = t.strip_prefix("power-law:") {
        let beta: f64 = match beta.trim().parse() {
            Ok(b) => b,
            Err(_) => bail!("--object {text}: β = {beta:?} is not a number; expected power-law:BETA with 0 ≤ β < 2"),
        };
        return Ok(ObjectSpectrum::PowerLaw { beta });
    }
    bail!("--object {text}: expected flat or power-law:BETA (the object's power spectrum ∝ |ν|^−β, 0 ≤ β < 2)")
}

/// `disk:DIAMETER_UM:CONTRAST`: a disk of that diameter in the image plane (µm) and contrast.
pub fn parse_task(text: &str) -> Result<DiskTask> {
    let parts: Vec<&str> = text.trim().split(':').collect();
    match parts.as_slice() {
        ["disk", d, c] => {
            let number = |what: &str, v: &str| -> Result<f64> {
                v.trim().parse().map_err(|_| {
                    anyhow::anyhow!(
                        "--task {text}: the {what} {v:?} is not a number; expected disk:DIAMETER_UM:CONTRAST"
                    )
                })
            };
            Ok(DiskTask { diameter_m: number("diameter", d)? * 1e-6, contrast: number("contrast", c)? })
        }
        _ => bail!("--task {text}: expected disk:DIAMETER_UM:CONTRAST, e.g. disk:20:0.05"),
    }
}

/// The options from the words of the command line (`None`: the defaults).
pub fn options(
    object: Option<&str>,
    contrast: Option<f64>,
    frame_rate_hz: Option<f64>,
    task: Option<&str>,
) -> Result<MetricsOptions> {
    let options = MetricsOptions {
        object: object.map(parse_object).transpose()?.unwrap_or(ObjectSpectrum::Flat),
        contrast: contrast.unwrap_or(1.0),
        frame_rate_hz,
        task: task.map(parse_task).transpose()?,
        ..MetricsOptions::default()
    };
    options.validate()?;
    Ok(options)
}

/// The metrics' lines of the evaluation table.
pub fn table(m: &Metrics, e: &Evaluation) -> String {
    let mut s = String::new();
    let _ = writeln!(s);
    let _ = writeln!(s, "metrics (docs/physics.md, \"Metrics beyond the ASNR\")");
    let _ = writeln!(
        s,
        "  NEQ(0) = SNR0²               {:>12.4e}   quanta per pixel (noise: {})",
        m.neq_zero,
        e.noise.terms.join(", ")
    );
    let _ =
        writeln!(s, "  mean NEQ to Nyquist          {:>12.4e}   quanta per pixel, (1/ν_N) ∫ SNR0² MTF² dν", m.mean_neq);
    let object = match m.object {
        "flat" => format!("flat object, contrast {}", crate::number(m.contrast)),
        _ => format!("power-law object |ν|^−{}, contrast {}", crate::number(m.object_beta), crate::number(m.contrast)),
    };
    let _ = writeln!(
        s,
        "  capacity                     {:>12.4}   bits/pixel ± {:.1e} ({object}; perfect lens {:.4})",
        m.capacity_bits_per_pixel, m.capacity_error_bits, m.capacity_perfect_lens_bits_per_pixel
    );
    if let (Some(rate), Some(per_second)) = (m.frame_rate_hz, m.capacity_bits_per_pixel_per_second) {
        let _ = writeln!(
            s,
            "  capacity per second          {:>12.4}   bits/pixel/s at {} Hz",
            per_second,
            crate::number(rate)
        );
    }
    if let Some(d) = &m.detectability {
        let _ = writeln!(
            s,
            "  detectability d′             {:>12.4}   disk {} µm, contrast {} (perfect lens {:.4}; {:.2} % of its energy below Nyquist)",
            d.d_prime,
            crate::number(d.task.diameter_m * 1e6),
            crate::number(d.task.contrast),
            d.d_prime_perfect_lens,
            100.0 * d.energy_in_band
        );
    }
    let i = &m.ideal_lens;
    let _ = writeln!(
        s,
        "  ideal lens ASNR              {:>12.4}   same F-number, diffraction-limited, efficiency 1 (SNR0 {:.2}, mean MTF {:.4})",
        i.asnr, i.snr0, i.mean_mtf
    );
    let _ = writeln!(s, "  ASNR / ideal lens            {:>12.4}", i.ratio);
    let _ = writeln!(s, "  2-D MTF                      {}", m.mtf_2d);
    s
}

#[derive(Serialize)]
struct WithMetrics<'a> {
    #[serde(flatten)]
    report: serde_json::Value,
    #[serde(flatten)]
    metrics: &'a Metrics,
}

/// The evaluation's JSON object ([`crate::output::json`]) with the metrics' fields beside its own.
pub fn json(label: &str, scene: &Scene, e: &Evaluation, m: &Metrics) -> Result<String> {
    let report: serde_json::Value = serde_json::from_str(&crate::output::json(label, scene, e)?)?;
    Ok(serde_json::to_string_pretty(&WithMetrics { report, metrics: m })?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The words accepted and the messages of those refused.
    #[test]
    fn parse_words() {
        assert_eq!(parse_object("flat").unwrap(), ObjectSpectrum::Flat);
        assert_eq!(parse_object("power-law:1.5").unwrap(), ObjectSpectrum::PowerLaw { beta: 1.5 });
        assert!(parse_object("pink").unwrap_err().to_string().contains("expected flat or power-law:BETA"));
        assert!(parse_object("power-law:x").unwrap_err().to_string().contains("is not a number"));
        let t = parse_task("disk:20:0.05").unwrap();
        assert!((t.diameter_m - 20e-6).abs() < 1e-18 && t.contrast == 0.05);
        assert!(parse_task("square:2:1").unwrap_err().to_string().contains("disk:DIAMETER_UM:CONTRAST"));
        assert!(parse_task("disk:a:1").unwrap_err().to_string().contains("the diameter \"a\""));
        let e = options(Some("power-law:2"), None, None, None).unwrap_err().to_string();
        assert!(e.contains("0 ≤ β < 2"), "{e}");
        let e = options(None, Some(-1.0), None, None).unwrap_err().to_string();
        assert!(e.contains("contrast = -1"), "{e}");
    }
}
