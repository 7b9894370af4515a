//! The PSF-stack lens through the conformance check every lens model passes.

use lenses::{Curve, PsfStack};
use optics::testkit::check_lens;

use crate::band;

/// Three slices of elliptical, shifted, slightly skewed Gaussians (lateral colour, a direction-
/// dependent OTF, a non-zero imaginary part) at 780, 800 and 820 nm, 1 µm samples, F/2.5:
/// MTF(0) = 1, bounds, finite everywhere, efficiency within the transmission, over a band
/// reaching past the stack (the end slices held).
#[test]
fn a_psf_stack_passes_the_conformance_check() {
    let n = 48;
    let c = (n / 2) as f64;
    let mut values = Vec::new();
    for (k, shift) in [-1.5, 0.0, 2.0].iter().enumerate() {
        let (sx, sy) = (2.0 + k as f64, 2.5);
        for i in 0..n * n {
            let (y, x) = ((i / n) as f64 - c, (i % n) as f64 - c - shift);
            let skew = 1.0 + 0.1 * (x / sx).tanh();
            values.push(skew * (-(x * x) / (2.0 * sx * sx) - y * y / (2.0 * sy * sy)).exp());
        }
    }
    let lens = PsfStack::new(
        2.5,
        3.36e-3,
        1e-6,
        vec![780e-9, 800e-9, 820e-9],
        [n, n],
        &values,
        Curve::Constant(0.3),
        Curve::Constant(0.6),
    )
    .unwrap();
    assert!(lens.table().is_direction_dependent());
    assert!(lens.report().imaginary.0 > 1e-3, "{:?}", lens.report().imaginary);
    check_lens(&lens, &band(800.0, 10.0)).unwrap();
    check_lens(&lens, &band(800.0, 100.0)).unwrap();
}
