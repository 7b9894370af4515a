//! The pupil field's sine and cosine: the hand-written branch-free [`optics::fft::sin_cos`]
//! (Cody–Waite reduction, Taylor polynomials; the compiler vectorizes a row of it) against the
//! `wide` crate's `f64x4::sin_cos` (Agner Fog's vector class library, four lanes explicitly) and
//! the standard library's `f64::sin_cos` (the platform's libm), on rows of 4096 phases as
//! `fft::cis::fill` meets them: up to 1e3 rad (a pupil's defocus phase at the FFT path's
//! budget) and up to 1e5 rad (the budget's edge).
//!
//! `cargo bench -p asnr-optics --bench sincos` prints first, for each range, the largest error
//! of each against `f64::sin_cos` (absolute, over the row), then criterion's times per row;
//! ns/element is the median over 4096. Timings are measured here and never asserted (STYLE.md).

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_main};
use rand::{RngExt, SeedableRng};
use wide::f64x4;

/// Phases per row: a 64 × 64 pupil.
const ROW: usize = 4096;

/// A row of phases uniform in ±`range` rad (PCG-64 MCG, seeded).
fn phases(range: f64) -> Vec<f64> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    (0..ROW).map(|_| rng.random_range(-range..range)).collect()
}

/// The hand-written sine and cosine over `phi`, summed into `out` (sin, cos).
fn hand(phi: &[f64], out: &mut [(f64, f64)]) {
    for (o, &p) in out.iter_mut().zip(phi) {
        *o = optics::fft::sin_cos(p);
    }
}

/// `wide`'s four-lane sine and cosine over `phi` (a multiple of 4 long).
fn vector(phi: &[f64], out: &mut [(f64, f64)]) {
    for (o, p) in out.chunks_exact_mut(4).zip(phi.chunks_exact(4)) {
        let (s, c) = f64x4::new([p[0], p[1], p[2], p[3]]).sin_cos();
        let (s, c) = (s.to_array(), c.to_array());
        for k in 0..4 {
            o[k] = (s[k], c[k]);
        }
    }
}

/// The standard library's.
fn library(phi: &[f64], out: &mut [(f64, f64)]) {
    for (o, &p) in out.iter_mut().zip(phi) {
        *o = p.sin_cos();
    }
}

/// The largest absolute error of `f` against `f64::sin_cos` over 64 rows of `range`.
fn worst(f: fn(&[f64], &mut [(f64, f64)]), range: f64) -> f64 {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    let mut out = vec![(0.0, 0.0); ROW];
    let mut worst: f64 = 0.0;
    for _ in 0..64 {
        let phi: Vec<f64> = (0..ROW).map(|_| rng.random_range(-range..range)).collect();
        f(&phi, &mut out);
        for (&p, &(s, c)) in phi.iter().zip(&out) {
            let (s0, c0) = p.sin_cos();
            worst = worst.max((s - s0).abs()).max((c - c0).abs());
        }
    }
    worst
}

type Kernel = (&'static str, fn(&[f64], &mut [(f64, f64)]));
const KERNELS: [Kernel; 3] = [("hand-written", hand), ("wide f64x4", vector), ("std f64::sin_cos", library)];

fn sin_cos(c: &mut Criterion) {
    for range in [1e3, 1e5] {
        for (name, f) in KERNELS {
            eprintln!("sincos accuracy: {name}, |phi| < {range:e} rad: max abs error {:.1e}", worst(f, range));
        }
    }
    let mut group = c.benchmark_group("sincos");
    group.warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    group.throughput(Throughput::Elements(ROW as u64));
    for range in [1e3, 1e5] {
        let phi = phases(range);
        let mut out = vec![(0.0, 0.0); ROW];
        for (name, f) in KERNELS {
            group.bench_with_input(BenchmarkId::new(name, format!("{range:e} rad")), &phi, |b, phi| {
                b.iter(|| {
                    f(black_box(phi), &mut out);
                    black_box(out[ROW - 1])
                })
            });
        }
    }
    group.finish();
}

/// The benchmark group (a private module: the macro's function has no docs of its own).
mod group {
    criterion::criterion_group!(benches, super::sin_cos);
}
criterion_main!(group::benches);
