//! The slanted-edge e-SFR (`asnr sfr`, `imaging::sfr`) beside its numpy baseline
//! (`xtask/baselines/numpy_sfr.py`, the same algorithm): the section "Slanted-edge MTF against
//! numpy" (`cargo xtask accuracy --only sfr`).
//!
//! The edge: the exact image of a step blurred by a Gaussian of σ = 0.7 px and integrated over
//! square pixels, 5° off vertical, 160 × 160 pixels, levels 0.2 and 1 (imaging/tests/sfr.rs),
//! whose MTF along the normal is exp(−2π²σ²f²) · sinc(f cos θ) · sinc(f sin θ). Times: the median
//! of 21 calls after a warm-up, each side in its own process, one thread. `imaging` is a
//! dev-dependency of `metric` (the examples may use any project crate), so the e-SFR runs in
//! process, as the numpy script's does in its own.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::io::Write as _;
use std::time::Instant;

use crate::sections::Tools;

fn phi(t: f64) -> f64 {
    0.5 * libm::erfc(-t / 2f64.sqrt())
}

fn h2(t: f64) -> f64 {
    (t * t + 1.0) / 2.0 * phi(t) + t / 2.0 * (-t * t / 2.0).exp() / (2.0 * PI).sqrt()
}

/// The section's markdown, or None (the reason printed) without a Python with numpy.
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let Some(python) = tools.python.as_deref() else {
        eprintln!("sfr: no Python with numpy (--python PY)");
        return None;
    };

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
    let bytes = scene::npy::npy_f64(&[size, size], &image).expect("the image fills its shape");
    std::fs::File::create(&npy).and_then(|mut f| f.write_all(&bytes)).expect("the .npy is written");
    let output = match std::process::Command::new(python)
        .arg(tools.root.join("xtask/baselines/numpy_sfr.py"))
        .arg(&npy)
        .output()
    {
        Ok(output) => output,
        Err(e) => {
            eprintln!("sfr: {}: {e}", python.display());
            return None;
        }
    };
    std::fs::remove_dir_all(&dir).ok();
    let text = String::from_utf8_lossy(&output.stdout);
    if !output.status.success() {
        eprintln!("sfr: the numpy baseline failed: {}", String::from_utf8_lossy(&output.stderr));
        return None;
    }
    let field = |name: &str| -> Option<f64> {
        let at = text.find(&format!("\"{name}\": "))? + name.len() + 4;
        text[at..].split([',', '}']).next().and_then(|v| v.trim().parse().ok())
    };
    let version = std::process::Command::new(python)
        .args(["-c", "import numpy; print(numpy.__version__)"])
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_default();
    let mut s = String::new();
    let _ = writeln!(s, "## {TITLE}\n");
    let _ = writeln!(
        s,
        "`cargo xtask accuracy --only sfr` (numpy from the virtual environment `cargo xtask accuracy` makes in\n\
         target/baselines-venv): the e-SFR of `asnr sfr` (`imaging::sfr`) beside\n\
         `xtask/baselines/numpy_sfr.py`, the same algorithm in numpy (edge centroids, quarter-pixel ESF\n\
         bins, windowed LSF, the bins' and the derivative's transfer divided out), on the exact image of a\n\
         Gaussian-blurred (σ = {sigma} px), pixel-integrated edge {angle}° off vertical, {size} × {size} pixels; exact\n\
         mean MTF to Nyquist {truth:.6}. Times: medians of 21 calls after a warm-up, one thread; ours\n\
         includes finding the edge in the frame and the standard errors propagated from the ESF bins,\n\
         which the numpy script leaves out.\n"
    );
    let _ = writeln!(s, "| implementation | mean MTF | error | MTF(Nyquist) | angle | time |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    let _ = writeln!(
        s,
        "| `imaging::sfr` | {:.6} | {:+.4} % | {:.5} | {:.4}° | {:.2} ms |",
        e.mean_mtf,
        100.0 * (e.mean_mtf / truth - 1.0),
        e.mtf_nyquist,
        e.edge_angle_deg,
        1e3 * ours_time
    );
    let _ = writeln!(
        s,
        "| numpy {version} (`xtask/baselines/numpy_sfr.py`) | {:.6} | {:+.4} % | {:.5} | {:.4}° | {:.2} ms |",
        field("mean_mtf")?,
        100.0 * (field("mean_mtf")? / truth - 1.0),
        field("mtf_nyquist")?,
        field("edge_angle_deg")?,
        1e3 * field("seconds")?
    );
    let _ = writeln!(s, "\nAgreement: the two mean MTFs differ by {:.1e}.", (e.mean_mtf - field("mean_mtf")?).abs());
    Some(s)
}

/// The section's heading.
pub(crate) const TITLE: &str = "Slanted-edge MTF against numpy";
