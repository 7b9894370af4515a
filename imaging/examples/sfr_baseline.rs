//! The slanted-edge e-SFR beside its numpy baseline (`xtask/baselines/numpy_sfr.py`, the same
//! algorithm): the BENCHMARKS.md row. Run with
//! `cargo run -p asnr-imaging --example sfr_baseline --release [-- PYTHON]` (PYTHON: an
//! interpreter with numpy; default `target/baselines-venv/bin/python`, the environment
//! `cargo xtask accuracy` makes from xtask/baselines/requirements.txt).
//!
//! The edge: the exact image of a step blurred by a Gaussian of σ = 0.7 px and integrated over
//! square pixels, 5° off vertical, 160 × 160 pixels, levels 0.2 and 1 (imaging/tests/sfr.rs),
//! whose MTF along the normal is exp(−2π²σ²f²) · sinc(f cos θ) · sinc(f sin θ). Times: the median
//! of 21 calls after a warm-up, each side in its own process, one thread.

use std::f64::consts::PI;
use std::io::Write as _;
use std::path::PathBuf;
use std::time::Instant;

fn phi(t: f64) -> f64 {
    0.5 * libm::erfc(-t / 2f64.sqrt())
}

fn h2(t: f64) -> f64 {
    (t * t + 1.0) / 2.0 * phi(t) + t / 2.0 * (-t * t / 2.0).exp() / (2.0 * PI).sqrt()
}

fn main() {
    let (size, angle, sigma) = (160_usize, 5.0_f64, 0.7);
    let theta = angle.to_radians();
    let (a, c) = (theta.cos(), -theta.sin());
    let mid = (size as f64 - 1.0) / 2.0 + 0.3;
    let k = a * mid + c * mid;
    let image: Vec<f64> = (0..size * size)
        .map(|p| {
            let (i, j) = ((p % size) as f64, (p / size) as f64);
            let u = |x: f64, y: f64| (a * x + c * y - k) / sigma;
            let f = sigma * sigma / (a * c)
                * (h2(u(i + 0.5, j + 0.5)) - h2(u(i - 0.5, j + 0.5)) - h2(u(i + 0.5, j - 0.5))
                    + h2(u(i - 0.5, j - 0.5)));
            0.2 + 0.8 * f
        })
        .collect();
    let truth = {
        let sinc = |x: f64| if x == 0.0 { 1.0 } else { (PI * x).sin() / (PI * x) };
        let n = 20_000;
        let h = 0.5 / n as f64;
        (0..=n)
            .map(|i| {
                let f = i as f64 * h;
                let m = (-2.0 * PI * PI * sigma * sigma * f * f).exp() * (sinc(f * a) * sinc(f * c)).abs();
                m * if i == 0 || i == n { 0.5 } else { 1.0 }
            })
            .sum::<f64>()
            * h
            / 0.5
    };
    let frame = imaging::Frame { path: "edge".into(), width: size, height: size, bit_depth: 32, data: image.clone() };
    let options = imaging::sfr::Options::default();
    let run = || imaging::sfr(std::slice::from_ref(&frame), &[], &options).expect("the edge is analysed");
    let ours = run();
    let mut times: Vec<f64> = (0..21)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(run());
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    let ours_time = times[10];
    let e = &ours.edges[0];

    // the image as a .npy (version 1.0, little-endian f64, C order) for the numpy script
    let dir = std::env::temp_dir().join(format!("asnr-sfr-baseline-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let npy = dir.join("edge.npy");
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({size}, {size}), }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    bytes.extend(image.iter().flat_map(|v| v.to_le_bytes()));
    std::fs::File::create(&npy).and_then(|mut f| f.write_all(&bytes)).expect("the .npy is written");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let python = std::env::args().nth(1).map_or_else(|| root.join("target/baselines-venv/bin/python"), PathBuf::from);
    let output = std::process::Command::new(&python)
        .arg(root.join("xtask/baselines/numpy_sfr.py"))
        .arg(&npy)
        .output()
        .unwrap_or_else(|e| panic!("{}: {e} (give an interpreter with numpy as the argument)", python.display()));
    std::fs::remove_dir_all(&dir).ok();
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "numpy baseline failed: {}", String::from_utf8_lossy(&output.stderr));
    let field = |name: &str| -> f64 {
        let at = text.find(&format!("\"{name}\": ")).expect("the field") + name.len() + 4;
        text[at..].split([',', '}']).next().and_then(|v| v.trim().parse().ok()).expect("a number")
    };
    let version = std::process::Command::new(&python)
        .args(["-c", "import numpy; print(numpy.__version__)"])
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_default();
    println!("Slanted edge, 160 × 160, 5°, σ = 0.7 px, exact: mean MTF to Nyquist {truth:.6}");
    println!("| implementation | mean MTF | error | MTF(Nyquist) | angle | time |");
    println!("|---|---|---|---|---|---|");
    println!(
        "| `imaging::sfr` | {:.6} | {:+.4} % | {:.5} | {:.4}° | {:.2} ms |",
        e.mean_mtf,
        100.0 * (e.mean_mtf / truth - 1.0),
        e.mtf_nyquist,
        e.edge_angle_deg,
        1e3 * ours_time
    );
    println!(
        "| numpy {version} (`xtask/baselines/numpy_sfr.py`) | {:.6} | {:+.4} % | {:.5} | {:.4}° | {:.2} ms |",
        field("mean_mtf"),
        100.0 * (field("mean_mtf") / truth - 1.0),
        field("mtf_nyquist"),
        field("edge_angle_deg"),
        1e3 * field("seconds")
    );
    println!("agreement: mean MTF differs by {:.2e}", (e.mean_mtf - field("mean_mtf")).abs());
}
