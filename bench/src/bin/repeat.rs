//! [`metric::evaluate`] of one scene file, repeated: the loop a profiler or an instruction counter
//! runs on (the numbers of an optimization are measured on it), with the median time per call.
//!
//! ```text
//! cargo build --release -p asnr-bench --bin repeat
//! target/release/repeat examples/spectrometer.toml [TOLERANCE [RUNS [--gradient KEY,KEY…]]]
//! valgrind --tool=callgrind target/release/repeat examples/spectrometer.toml 1e-6 20
//! perf record target/release/repeat examples/spectrometer.toml 1e-6 1500
//! ```
//!
//! The tolerance (default 1e-6) is set as `--set options.tolerance=…` would set it; 200 runs by
//! default. Prints the median wall time of one call (not a benchmark: BENCHMARKS.md and the
//! criterion benches are), the mean MTF, and the work the engines report. The scene is loaded
//! once, outside the loop; an instruction count of the whole process includes that load
//! (subtract a run with fewer repeats).
//!
//! With `--gradient KEY,…` each call is [`metric::gradient`] with respect to those keys instead
//! (the engine's parameters of `exposure.time_ms`, `spectrum.center_nm`, `spectrum.range_nm`,
//! `source.temperature_k`, `lens.f_number`, `lens.focal_length_mm`, `field.x_deg`,
//! `field.y_deg`, `lens.zernike_noll_rms_um[i]`; the gradient is per unit of the engine's
//! parameter), and the value alone is
//! timed interleaved with it (one call of each in turn), so that the two medians and their
//! ratio are measured side by side.

use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: repeat SCENE.toml [TOLERANCE [RUNS]]");
        return ExitCode::FAILURE;
    };
    let tolerance = args.get(1).map_or("1e-6", String::as_str);
    let runs: usize = match args.get(2).map_or(Ok(200), |r| r.parse()) {
        Ok(runs) if runs > 0 => runs,
        _ => {
            eprintln!("RUNS: write a whole number of at least 1, not {:?}", args[2]);
            return ExitCode::FAILURE;
        }
    };
    let keys: Option<Vec<metric::Parameter>> = match (args.get(3).map(String::as_str), args.get(4)) {
        (None, _) => None,
        (Some("--gradient"), Some(list)) => {
            let mut out = Vec::new();
            for key in list.split(',') {
                out.push(match key.trim() {
                    "exposure.time_ms" => metric::Parameter::Exposure,
                    "spectrum.center_nm" => metric::Parameter::SpectrumCenter,
                    "spectrum.range_nm" => metric::Parameter::SpectrumRange,
                    "source.temperature_k" => metric::Parameter::Temperature,
                    "lens.f_number" => metric::Parameter::FNumber,
                    "lens.focal_length_mm" => metric::Parameter::FocalLength,
                    "field.x_deg" => metric::Parameter::FieldAngle(0),
                    "field.y_deg" => metric::Parameter::FieldAngle(1),
                    // `lens.zernike_noll_rms_um[i]`: 0-based, the Noll index i + 1
                    other if other.starts_with("lens.zernike_noll_rms_um[") && other.ends_with(']') => {
                        match other["lens.zernike_noll_rms_um[".len()..other.len() - 1].parse::<usize>() {
                            Ok(i) => metric::Parameter::ZernikeNoll(i + 1),
                            Err(_) => {
                                eprintln!("--gradient: {other:?}: write the index as a whole number");
                                return ExitCode::FAILURE;
                            }
                        }
                    }
                    other => {
                        eprintln!("--gradient: {other:?} is not one of the keys this loop maps");
                        return ExitCode::FAILURE;
                    }
                });
            }
            Some(out)
        }
        _ => {
            eprintln!("usage: repeat SCENE.toml [TOLERANCE [RUNS [--gradient KEY,KEY…]]]");
            return ExitCode::FAILURE;
        }
    };
    let scene = match scene::load(Some(std::path::Path::new(path)), &[format!("options.tolerance={tolerance}")]) {
        Ok(scene) => scene,
        Err(e) => {
            eprintln!("{path}: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Some(parameters) = keys {
        let (mut value, mut both) = (Vec::with_capacity(runs), Vec::with_capacity(runs));
        for _ in 0..runs {
            optics::forget_remembered();
            let started = Instant::now();
            let e = metric::evaluate(std::hint::black_box(&scene));
            value.push(started.elapsed().as_secs_f64());
            optics::forget_remembered();
            let started = Instant::now();
            let g = metric::gradient(std::hint::black_box(&scene), &parameters);
            both.push(started.elapsed().as_secs_f64());
            if let Err(e) =
                e.as_ref().map(|_| ()).map_err(ToString::to_string).and(g.map(|_| ()).map_err(|e| e.to_string()))
            {
                eprintln!("{path}: {e}");
                return ExitCode::FAILURE;
            }
        }
        value.sort_by(f64::total_cmp);
        both.sort_by(f64::total_cmp);
        let (v, b) = (value[runs / 2], both[runs / 2]);
        println!(
            "value {:.1} µs, value and gradient {:.1} µs: {:.2}× (medians of {runs} calls each, interleaved)",
            v * 1e6,
            b * 1e6,
            b / v
        );
        return ExitCode::SUCCESS;
    }
    let mut seconds = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs {
        // one evaluation each: nothing remembered of a measured spectrum from the call before
        optics::forget_remembered();
        let started = Instant::now();
        let evaluation = metric::evaluate(std::hint::black_box(&scene));
        seconds.push(started.elapsed().as_secs_f64());
        last = Some(evaluation);
    }
    match last {
        Some(Ok(e)) => {
            seconds.sort_by(f64::total_cmp);
            let n = &e.numerics;
            println!(
                "median {:.1} µs over {runs} calls; mean MTF {:.15}; {} OTF values, {} single-wavelength OTFs",
                seconds[runs / 2] * 1e6,
                e.mean_mtf,
                n.otf_evaluations,
                n.spectral_evaluations
            );
            ExitCode::SUCCESS
        }
        Some(Err(e)) => {
            eprintln!("{path}: {e}");
            ExitCode::FAILURE
        }
        None => ExitCode::FAILURE,
    }
}
