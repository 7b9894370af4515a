//! Criterion benchmarks of the optics kernels: the exact defocused OTF on its two branches
//! (Gauss–Legendre below `|a| = 24`, Bessel series above), the pixel MTF, the polychromatic
//! engine on the paper scene (preparation and the mean up to Nyquist), the closed-form engine's
//! kernels (one polychromatic OTF value of [`GaussianDefocus`], the Weideman `erfcx` against
//! the `errorfunctions` crate it replaces), the FFT path's [`OtfPlan::otf`] for a decentred
//! iris at 64–512 pupil samples, and a composite pupil of three sector zones (the field of
//! [`SampledZones::set_field`] and [`OtfPlan::otf_of_field`]) at 256.
//!
//! `cargo bench -p asnr-optics --bench kernels` (about a minute; `-- <filter>` runs a subset, e.g.
//! `-- fft`). Timings are measured here and never asserted (STYLE.md).

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, SamplingMode, criterion_main};
use num_complex::Complex64;
use optics::fft::{Aberrations, Aperture, Otf, OtfPlan, SampledPupil, SampledZones, ZoneField};
use optics::{Field, GaussianDefocus, LensModel, Order, Polychromatic, Pupil, Wavefront, defocus_otf, pixel_mtf};
use radiometry::{Gaussian, Spectrum};

/// Paper scene (SI, Fig. 2): F/2.5, f0 = 3.36 mm, λ0 = 800 nm, 5.2 µm pixels.
const F_NUMBER: f64 = 2.5;
const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;
const PIXEL: f64 = 5.2e-6;

/// The paper's chromatic metalens, `f(λ) = f0 λ0/λ` with the detector at `f0`, τ1 = 0.15 (the
/// `lenses` crate cannot be used here: it depends on `optics`).
#[derive(Debug)]
struct Chromatic;

impl LensModel for Chromatic {
    fn f_number(&self) -> f64 {
        F_NUMBER
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        let w020 = (1.0 - lambda / LAMBDA0) * F0 / (8.0 * F_NUMBER * F_NUMBER);
        vec![Order::new(0.15, Pupil::Full, Wavefront::defocus(w020))]
    }
}

/// Detected spectrum of the paper scene: flat source × Gaussian filter (50 nm range) × QE × λ.
fn paper_spectrum() -> Spectrum {
    Spectrum::product(vec![
        Spectrum::Constant(0.025e9),
        Spectrum::Gaussian(Gaussian::from_range(LAMBDA0, 50e-9, 1.0).unwrap()),
        Spectrum::Constant(0.2),
        Spectrum::Linear { slope: 1.0 },
    ])
}

fn monochromatic(c: &mut Criterion) {
    let mut group = c.benchmark_group("defocus_otf");
    group.warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    // (s, w): |a| = 8π w s from 0 (closed form) through the quadrature branch to the Bessel series
    for (label, s, w) in [
        ("w=0", 0.3, 0.0),
        ("w=0.5 quadrature", 0.3, 0.5),
        ("w=3 quadrature", 0.3, 3.0),
        ("w=100 bessel", 0.3, 100.0),
        ("w=1e4 bessel", 0.3, 1e4),
    ] {
        group.bench_function(label, |b| b.iter(|| defocus_otf(black_box(s), black_box(w))));
    }
    group.finish();

    let mut group = c.benchmark_group("pixel_mtf");
    group.warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    group.bench_function("nyquist", |b| b.iter(|| pixel_mtf(black_box(PIXEL), black_box(0.5 / PIXEL))));
    group.finish();
}

fn polychromatic(c: &mut Criterion) {
    let lens = Chromatic;
    let spectrum = paper_spectrum();
    let nyquist = 0.5 / PIXEL;
    let mut group = c.benchmark_group("polychromatic paper scene");
    group.sample_size(20).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    group.bench_function("new", |b| {
        b.iter(|| Polychromatic::new(&lens, black_box(&spectrum), Field::ON_AXIS, nyquist, None).unwrap())
    });
    let poly = Polychromatic::new(&lens, &spectrum, Field::ON_AXIS, nyquist, None).unwrap();
    group.bench_function("otf at nyquist/2", |b| b.iter(|| poly.otf(black_box(0.5 * nyquist))));
    group.bench_function("mean_mtf", |b| b.iter(|| poly.mean_mtf().0));
    group.bench_function("new + mean_mtf", |b| {
        b.iter(|| Polychromatic::new(&lens, black_box(&spectrum), Field::ON_AXIS, nyquist, None).unwrap().mean_mtf().0)
    });
    group.finish();
}

fn closed_form(c: &mut Criterion) {
    // the paper scene's detected spectrum λ·G(λ) (50 nm range), τ1 = 0.15, W020 = (1 − λ/λ0) k
    let k = F0 / (8.0 * F_NUMBER * F_NUMBER);
    let sigma = 50e-9 / (2.0 * 2f64.sqrt());
    let new = || GaussianDefocus::new(LAMBDA0, sigma, &[0.0, 1.0], 0.15, k, -k / LAMBDA0, F_NUMBER);
    let closed = new();
    let nyquist = 0.5 / PIXEL;
    let mut group = c.benchmark_group("closed form paper scene");
    group.warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    group.bench_function("GaussianDefocus::new", |b| b.iter(|| black_box(new())));
    for (label, tolerance) in [("otf at nyquist/2, 1e-7", 1e-7), ("otf at nyquist/2, 1e-10", 1e-10)] {
        group.bench_function(label, |b| b.iter(|| closed.otf(black_box(0.5 * nyquist), tolerance).0));
    }
    group.finish();
    // an argument of the cut zone at the paper's Nyquist frequency
    let z = Complex64::new(1.3, -0.4);
    let mut group = c.benchmark_group("erfcx");
    group.warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    group.bench_function("Weideman series (optics::faddeeva)", |b| b.iter(|| optics::faddeeva::erfcx(black_box(z))));
    group.bench_function("errorfunctions crate, 1e-13", |b| {
        b.iter(|| errorfunctions::erfcx_with_relerror(black_box(z), 1e-13))
    });
    group.finish();
}

fn fft(c: &mut Criterion) {
    // the paper's iris decentred by 10 % of the radius (SI Fig. S3), ½ wave of defocus, read up
    // to the paper scene's Nyquist: s = ν_N λ F# = 0.19
    let iris = Aperture::circle().decentred(0.1, 0.0).unwrap();
    let aberrations = Aberrations::defocus(0.5 * LAMBDA0);
    let s_max = 0.2;
    let mut group = c.benchmark_group("fft OtfPlan::otf decentred iris");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    group.sampling_mode(SamplingMode::Flat);
    for n in [64, 128, 256, 512] {
        let pupil = SampledPupil::new(n, &iris, &aberrations).unwrap();
        let mut plan = OtfPlan::new(n, s_max).unwrap();
        let mut otf = Otf::new();
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                plan.otf(black_box(&pupil), LAMBDA0, &mut otf);
                otf.sample(1, 0)
            })
        });
    }
    group.finish();

    // a segmented lens at one wavelength: three 120° sectors, each with its own defocus; the
    // field per wavelength and its OTF, against the single aperture's otf at the same N
    let zones: Vec<std::sync::Arc<Aperture>> = (0..3)
        .map(|j| {
            let third = std::f64::consts::TAU / 3.0;
            std::sync::Arc::new(Aperture::sector(j as f64 * third, (j + 1) as f64 * third).unwrap())
        })
        .collect();
    let fields: Vec<ZoneField> = (0..3)
        .map(|j| ZoneField {
            amplitude: 0.9,
            aberrations: Aberrations::defocus((j as f64 - 1.0) * LAMBDA0),
            tilt_m: [0.0, 0.0],
        })
        .collect();
    let n = 256;
    let mut sampled = SampledZones::new(n, &zones).unwrap();
    let mut plan = OtfPlan::new(n, s_max).unwrap();
    let mut otf = Otf::new();
    let mut group = c.benchmark_group("fft composite of three sectors");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    group.sampling_mode(SamplingMode::Flat);
    group.bench_function("set_field + otf_of_field, N = 256", |b| {
        b.iter(|| {
            sampled.set_field(black_box(&fields), LAMBDA0).unwrap();
            plan.otf_of_field(sampled.field(), sampled.weight(), &mut otf);
            otf.sample(1, 0)
        })
    });
    group.finish();

    let mut group = c.benchmark_group("fft SampledPupil::new decentred iris");
    group.sample_size(10).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(2));
    group.sampling_mode(SamplingMode::Flat);
    for n in [64, 256] {
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, &n| {
            b.iter(|| SampledPupil::new(black_box(n), &iris, &aberrations).unwrap())
        });
    }
    group.finish();
}

/// The benchmark group (a private module: the macro's function has no docs of its own).
mod group {
    criterion::criterion_group!(benches, super::monochromatic, super::polychromatic, super::closed_form, super::fft);
}
criterion_main!(group::benches);
