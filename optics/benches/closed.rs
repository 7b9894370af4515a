//! Criterion benchmarks of the closed-form engine ([`GaussianDefocus`]) at the two scenes of
//! BENCHMARKS.md: the paper point (F/2.5, f0 = 3.36 mm, λ0 = 800 nm, Gaussian of 50 nm range,
//! 5.2 µm pixels) and the hard point (F/1.4, 200 nm), each at several tolerances:
//!
//! - one polychromatic OTF value (`GaussianDefocus::otf`) at half Nyquist and at Nyquist, at an
//!   absolute tolerance;
//! - the OTF at 16 frequencies at once (`GaussianDefocus::otf_many`), the nodes of one
//!   16-point Gauss–Legendre rule on `[0, ν_N]`;
//! - the whole mean MTF up to Nyquist (`Polychromatic::mean_mtf` with the closed form, the
//!   frequency rule included) at a relative tolerance.
//!
//! `cargo bench -p optics --bench closed` (about a minute; `-- paper` or `-- hard` runs one
//! scene). Timings are measured here and never asserted.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_main};
use optics::{
    AffineDefocus, Engine, Field, GaussianDefocus, LensModel, Order, Polychromatic, Pupil, Settings, Wavefront,
};
use radiometry::{Gaussian, Spectrum};

/// Design focal length of the paper's lens, m.
const F0: f64 = 3.36e-3;
/// Design wavelength, m.
const LAMBDA0: f64 = 800e-9;
/// Pixel pitch, m: Nyquist 1/(2p) = 96.15 cycles/mm.
const PIXEL: f64 = 5.2e-6;

/// The chromatic metalens `f(λ) = f0 λ0/λ` at an F-number, τ1 = 0.15: W020 = (1 − λ/λ0) f0/(8F#²)
/// (docs/physics.md, "Chromatic lens").
#[derive(Debug)]
struct Chromatic(f64);

impl LensModel for Chromatic {
    fn f_number(&self) -> f64 {
        self.0
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        let w020 = (1.0 - lambda / LAMBDA0) * F0 / (8.0 * self.0 * self.0);
        vec![Order::new(0.15, Pupil::Full, Wavefront::defocus(w020))]
    }
    fn affine_defocus(&self, _: Field) -> Option<AffineDefocus> {
        // the promise that lets the closed-form engine take this lens
        let k = F0 / (8.0 * self.0 * self.0);
        Some(AffineDefocus { efficiency: 0.15, transmission: 0.15, w020_intercept_m: k, w020_slope: -k / LAMBDA0 })
    }
}

/// A scene: its name, F-number and spectral range (2√2 σ, docs/physics.md "Spectra"), m.
const SCENES: [(&str, f64, f64); 2] = [("paper F/2.5 50 nm", 2.5, 50e-9), ("hard F/1.4 200 nm", 1.4, 200e-9)];

fn closed(c: &mut Criterion) {
    let nyquist = 0.5 / PIXEL;
    for (name, f_number, range) in SCENES {
        // the detected spectrum λ·G(λ), τ1 = 0.15
        let k = F0 / (8.0 * f_number * f_number);
        let sigma = range / (2.0 * 2f64.sqrt());
        let engine = GaussianDefocus::new(LAMBDA0, sigma, &[0.0, 1.0], 0.15, k, -k / LAMBDA0, f_number);
        let mut group = c.benchmark_group(format!("closed {name}"));
        group.warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
        for tolerance in [1e-2, 1e-4, 1e-7, 1e-10] {
            for (label, nu) in [("otf ν_N/2", 0.5 * nyquist), ("otf ν_N", nyquist)] {
                group.bench_with_input(BenchmarkId::new(label, tolerance), &tolerance, |b, &t| {
                    b.iter(|| engine.otf(black_box(nu), t).0)
                });
            }
            let nodes: Vec<f64> =
                optics::quad::gauss_legendre(16).iter().map(|p| 0.5 * nyquist * (1.0 + p.0)).collect();
            let mut out = vec![0.0; nodes.len()];
            group.bench_with_input(BenchmarkId::new("otf_many 16 GL nodes", tolerance), &tolerance, |b, &t| {
                b.iter(|| {
                    engine.otf_many(black_box(&nodes), t, &mut out);
                    out[0]
                })
            });
        }
        let lens = Chromatic(f_number);
        let spectrum = Spectrum::product(vec![
            Spectrum::Gaussian(Gaussian::from_range(LAMBDA0, range, 1.0).unwrap()),
            Spectrum::Linear { slope: 1.0 },
        ]);
        for tolerance in [1e-2, 1e-4, 1e-7, 1e-10] {
            let settings = Settings { tolerance, ..Settings::default() };
            let poly = Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, nyquist, None, settings).unwrap();
            assert!(matches!(poly.engine(), Engine::ClosedForm), "{name}: not the closed-form engine");
            group.bench_with_input(BenchmarkId::new("mean_mtf", tolerance), &tolerance, |b, _| {
                b.iter(|| poly.mean_mtf().0)
            });
        }
        group.finish();
    }
}

/// The benchmark group (a private module: the macro's function has no docs of its own).
mod group {
    criterion::criterion_group!(benches, super::closed);
}
criterion_main!(group::benches);
