//! The gradient's cost beside one evaluation (BENCHMARKS.md, "Gradients"): the Binary 2 lens of
//! `examples/phase-binary2.toml` with a full sensor, its value (scene built and evaluated) and
//! its gradient over K = 4 and K = 10 keys (every key the gradient supports that the scene has), at the scene's
//! tolerance, the median of 21 runs each.
//!
//! `cargo run -p asnr-report --example gradient_cost`

use std::time::Instant;

fn median_seconds(mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..21)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/phase-binary2.toml");
    let source = scene::read(Some(&path))?;
    let overrides: Vec<String> = [
        "camera.read_noise_e=3",
        "camera.dark_current_e_per_s=200",
        "camera.gain_dn_per_e=0.5",
        "camera.adc_bits=12",
        "options.glare=\"included\"",
    ]
    .map(str::to_owned)
    .to_vec();
    // every key the gradient supports that this scene has (source.scale is a blackbody's)
    let keys: Vec<String> = [
        "exposure.time_ms",
        "camera.pixel_pitch_um",
        "lens.efficiency",
        "camera.read_noise_e",
        "source.radiance_w_m2_sr_nm",
        "camera.quantum_efficiency",
        "spectrum.peak",
        "lens.transmission",
        "camera.dark_current_e_per_s",
        "camera.gain_dn_per_e",
    ]
    .map(str::to_owned)
    .to_vec();
    // one run of each first, so that no row pays for the per-thread caches the others reuse
    std::hint::black_box(report::gradient::gradient(&source, &overrides, &keys)?);
    let value = median_seconds(|| {
        let built = scene::build_from(&source, &overrides).unwrap();
        std::hint::black_box(metric::evaluate(&built).unwrap());
    });
    println!("{:<34} {:>10} {:>8}", "Binary 2 lens (phase-binary2.toml)", "time (ms)", "× value");
    println!("{:<34} {:>10.2} {:>8.2}", "value (scene built, evaluated)", value * 1e3, 1.0);
    for k in [4, keys.len()] {
        let t = median_seconds(|| {
            std::hint::black_box(report::gradient::gradient(&source, &overrides, &keys[..k]).unwrap());
        });
        println!("{:<34} {:>10.2} {:>8.2}", format!("value and gradient, K = {k}"), t * 1e3, t / value);
    }
    Ok(())
}
