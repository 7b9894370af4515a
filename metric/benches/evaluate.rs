//! Criterion benchmarks of [`metric::evaluate`]: the whole ASNR of a scene, from the spectral
//! quadrature to the mean MTF, the photoelectron count and the reports.
//!
//! - the paper scene (SI, Fig. 2): F/2.5, f0 = 3.36 mm, λ0 = 800 nm, a 50 nm Gaussian range,
//!   5.2 µm pixels, τ1 = 0.15, T = 0.55, QE 0.2, 1.23 ms (closed-form engine at the default
//!   tolerance and at 1e-7, and the spectral quadrature);
//! - the same lens at F/1.4 with a 200 nm range (the costly corner of the paper's design space:
//!   up to ±7σ = ±495 nm around 800 nm, 44 waves of defocus at the widest kept wavelength);
//! - the paper scene through the decentred iris of SI Fig. S3 (the FFT path, 256 pupil samples);
//! - designs given as data, read from their example files: the Binary 2 metalens
//!   (`examples/phase-binary2.toml`, the radial engine at 1e-6) and the meta-atom library lens
//!   (`examples/library.toml`; its per-wavelength fits cached after the first evaluation);
//! - the paper scene with a 5000-row τ1 table (0.08 nm from 600 to 1000 nm), folded into the
//!   detected spectrum's exact moments (`optics::FactoredEfficiency`; before, its rows cut
//!   52 598 spectral nodes and the work budget refused it), and the same scene through an
//!   interleaved lens of three channels (775, 800, 825 nm), each channel's efficiency its own
//!   5000-row table (one part per channel, `optics::Polychromatic::with_parts`).
//!
//! `cargo bench -p asnr-metric --bench evaluate` (about a minute). Timings are measured here and never
//! asserted (STYLE.md).

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, SamplingMode, criterion_main};
use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, Options, Scene, evaluate};
use radiometry::{Gaussian, Spectrum};

const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;

/// The long tables shared with the accuracy report.
#[path = "../../bench/src/bin/accuracy/tables.rs"]
mod tables;
use tables::rows;

fn lens(f_number: f64) -> ChromaticMetalens {
    ChromaticMetalens::new(f_number, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap()
}

/// The paper theory scene with `lens`, a Gaussian filter of `range_m` at λ0 on a flat source.
fn scene(lens: ChromaticMetalens, range_m: f64) -> Scene {
    let filter = Gaussian::from_range(LAMBDA0, range_m, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(5.2e-6, Spectrum::Constant(0.2), false).unwrap();
    Scene::new(Arc::new(lens), radiance, camera, 1.23e-3, Options::default()).unwrap()
}

/// An example scene file of the repository, as `asnr evaluate` reads it.
fn example(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples").join(name);
    scene::load(Some(&path), &[]).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("evaluate");
    group.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(5));
    // slow points (up to seconds each): one run per sample is enough
    group.sampling_mode(SamplingMode::Flat);
    let cases = [
        ("paper F2.5 50nm", scene(lens(2.5), 50e-9)),
        ("paper F2.5 50nm tolerance 1e-7", {
            let options = Options { tolerance: 1e-7, ..Options::default() };
            scene(lens(2.5), 50e-9).with_options(options).unwrap()
        }),
        ("paper F2.5 50nm spectral quadrature", {
            let options = Options { closed_form: false, ..Options::default() };
            scene(lens(2.5), 50e-9).with_options(options).unwrap()
        }),
        ("F1.4 200nm", scene(lens(1.4), 200e-9)),
        ("paper F2.5 50nm decentred iris fft", {
            let iris = optics::fft::Aperture::circle().decentred(0.1, 0.0).unwrap();
            scene(lens(2.5).with_aperture(iris), 50e-9)
        }),
        ("Binary 2 metalens F2.5 50nm", example("phase-binary2.toml")),
        ("library lens F2.5 50nm", example("library.toml")),
        ("paper F2.5 50nm efficiency table 5000 rows", {
            let lens = ChromaticMetalens::new(2.5, F0, LAMBDA0, rows(0.12, 1.0), Curve::Constant(0.55)).unwrap();
            scene(lens, 50e-9)
        }),
        ("interleaved 3 channels 50nm, a 5000-row table each", {
            let channels = [(775e-9, 0.7, 0.8), (800e-9, 0.8, 1.0), (825e-9, 0.75, 1.3)]
                .iter()
                .map(|&(wavelength_m, mean, stretch)| lenses::Channel { wavelength_m, efficiency: rows(mean, stretch) })
                .collect();
            let interleaved = lenses::Interleaved::new(2.5, F0, channels, Curve::Constant(0.9)).unwrap();
            scene(lens(2.5), 50e-9).with_lens(Arc::new(interleaved))
        }),
    ];
    for (name, scene) in &cases {
        // one evaluation each, nothing remembered of a measured spectrum from the call before
        group.bench_function(*name, |b| {
            b.iter(|| {
                optics::forget_remembered();
                evaluate(black_box(scene)).unwrap().asnr
            })
        });
    }
    group.finish();
}

/// The benchmark group (a private module: the macro's function has no docs of its own).
mod group {
    criterion::criterion_group!(benches, super::bench);
}
criterion_main!(group::benches);
