//! End-to-end tests of `asnr evaluate --metrics` and `asnr nps`: the JSON fields, the values
//! that follow from each other, and bad input refused with the value and what is accepted.

use std::path::PathBuf;

mod common;

use common::{asnr, fails, json, stderr};

/// The paper scene's metrics: NEQ(0) = SNR0², the perfect-lens capacity ½ log₂(1 + SNR0² c²)
/// (Shannon), the capacity below it, per second = per frame × rate, the ideal-lens ratio =
/// ASNR / its ASNR; the table prints the lines; bad options exit 1 naming the value.
#[test]
fn evaluate_metrics_json_and_table() {
    let v = json(&[
        "evaluate",
        "--metrics",
        "--contrast",
        "0.5",
        "--frame-rate-hz",
        "30",
        "--task",
        "disk:20:0.05",
        "--json",
    ]);
    let snr0 = v["snr0"].as_f64().unwrap();
    let neq0 = v["neq_zero"].as_f64().unwrap();
    assert!((neq0 - snr0 * snr0).abs() < 1e-9 * neq0);
    let c = v["capacity_bits_per_pixel"].as_f64().unwrap();
    let perfect = v["capacity_perfect_lens_bits_per_pixel"].as_f64().unwrap();
    assert!((perfect - 0.5 * (1.0 + snr0 * snr0 * 0.25).log2()).abs() < 1e-12 * perfect);
    assert!(c > 0.0 && c < perfect);
    let per_second = v["capacity_bits_per_pixel_per_second"].as_f64().unwrap();
    assert!((per_second - 30.0 * c).abs() < 1e-12 * per_second);
    let ratio = v["ideal_lens"]["ratio"].as_f64().unwrap();
    let asnr_value = v["asnr"].as_f64().unwrap();
    assert!((ratio - asnr_value / v["ideal_lens"]["asnr"].as_f64().unwrap()).abs() < 1e-12);
    assert!(v["detectability"]["d_prime"].as_f64().unwrap() > 0.0);
    assert_eq!(v["neq"]["neq"].as_array().unwrap().len(), 101);
    let out = asnr(&["evaluate", "--metrics"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    for line in ["mean NEQ to Nyquist", "capacity", "ideal lens ASNR", "ASNR / ideal lens"] {
        assert!(table.contains(line), "{table}");
    }
    let err = fails(&["evaluate", "--metrics", "--object", "power-law:2.5"]);
    assert!(err.contains("2.5") && err.contains("0 ≤ β < 2"), "{err}");
    let err = fails(&["evaluate", "--metrics", "--task", "ring:3:1"]);
    assert!(err.contains("disk:DIAMETER_UM:CONTRAST"), "{err}");
    let err = fails(&["evaluate", "--metrics", "--frame-rate-hz", "0"]);
    assert!(err.contains("frame rate (Hz) = 0"), "{err}");
}

/// Writes a 16-bit PNG of `levels`.
fn png(path: &PathBuf, w: usize, h: usize, levels: &[f64]) {
    let bytes: Vec<u8> = levels.iter().flat_map(|l| (l.round() as u16).to_be_bytes()).collect();
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    encoder.write_header().unwrap().write_image_data(&bytes).unwrap();
}

/// `asnr nps` on eight flat frames of uniform noise 80 DN wide (variance 80²/12 = 533.3 DN², the
/// rounding to integers adds 1/12) with a fixed pattern of ±10 DN in a checkerboard (variance 100): the
/// temporal and spatial variances within 10 %, the measured capacity with an MTF CSV of 1;
/// frames of another size exit 1 naming both files.
#[test]
fn nps_of_flat_frames() {
    let dir = std::env::temp_dir().join(format!("asnr-cli-test-{}-nps", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = (32usize, 32usize);
    let mut paths = Vec::new();
    for k in 0..8 {
        let mut rng: rand_pcg::Pcg64Mcg = rand::SeedableRng::seed_from_u64(100 + k);
        let levels: Vec<f64> = (0..w * h)
            .map(|i| {
                let pattern = if (i % w + i / w) % 2 == 0 { 10.0 } else { -10.0 };
                let u = rand::RngExt::random::<f64>(&mut rng) - 0.5;
                1000.0 + pattern + 80.0 * u
            })
            .collect();
        let path = dir.join(format!("flat{k}.png"));
        png(&path, w, h, &levels);
        paths.push(path);
    }
    let csv = dir.join("mtf.csv");
    std::fs::write(&csv, "frequency_cyc_per_mm,mtf\n0,1\n200,1\n").unwrap();
    let mut args: Vec<String> = vec!["nps".into()];
    args.extend(paths.iter().map(|p| p.display().to_string()));
    args.extend([
        "--mtf-csv".into(),
        csv.display().to_string(),
        "--pixel-pitch-um".into(),
        "5".into(),
        "--json".into(),
    ]);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let v = json(&refs);
    let temporal = v["temporal_variance_dn2"].as_f64().unwrap();
    let spatial = v["spatial_variance_dn2"].as_f64().unwrap();
    let expected_t = 80.0 * 80.0 / 12.0 + 1.0 / 12.0;
    eprintln!("temporal {temporal:.2} (expected {expected_t:.2}), spatial {spatial:.2} (expected 100)");
    assert!((temporal - expected_t).abs() < 0.1 * expected_t);
    assert!((spatial - 100.0).abs() < 10.0);
    assert!(v["measured"]["capacity_bits_per_pixel"].as_f64().unwrap() > 0.0);
    // a frame of another size
    let odd = dir.join("odd.png");
    png(&odd, 16, 16, &vec![1000.0; 256]);
    let err = fails(&["nps", paths[0].to_str().unwrap(), odd.to_str().unwrap()]);
    assert!(err.contains("odd.png") && err.contains("same size"), "{err}");
    // an MTF that stops below Nyquist (100 cycles/mm at 5 µm)
    std::fs::write(&csv, "frequency_cyc_per_mm,mtf\n0,1\n50,0.5\n").unwrap();
    let err = fails(&[
        "nps",
        paths[0].to_str().unwrap(),
        paths[1].to_str().unwrap(),
        "--mtf-csv",
        csv.to_str().unwrap(),
        "--pixel-pitch-um",
        "5",
    ]);
    assert!(err.contains("mtf.csv") && err.contains("below the Nyquist frequency 100.00"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
