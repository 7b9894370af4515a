//! The radial engine's OTF derivatives beside its OTF (BENCHMARKS.md, "Gradients"): the
//! geometric-phase Binary 2 metalens of `examples/phase-binary2.toml` (the paper's aperture,
//! F/2.5, f0 = 3.36 mm, the hyperbolic profile's four terms) at 800 nm, on 200 frequencies up to
//! twice Nyquist (`s` to 0.38), at an OTF accuracy of 1e-11: the time of the OTFs alone
//! ([`RadialOrder::otf`]) and of the OTFs with their derivatives with respect to the first K
//! Binary 2 coefficients ([`RadialOrder::otf_and_derivatives`], K = 4 and 12; the terms past the
//! fourth at zero), the median of 11 runs each.
//!
//! `cargo run --release -p asnr-optics --example radial_gradient_cost`

use std::sync::Arc;
use std::time::Instant;

use optics::radial::{RadialOrder, RadialProfile, RadialPupil};

fn median_seconds(mut f: impl FnMut() -> f64) -> f64 {
    let mut sink = 0.0;
    let mut times: Vec<f64> = (0..11)
        .map(|_| {
            let start = Instant::now();
            sink += f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    assert!(sink.is_finite());
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() -> Result<(), optics::Error> {
    let (r, f, l0): (f64, f64, f64) = (0.672e-3, 3.36e-3, 800e-9);
    let k0 = std::f64::consts::TAU / l0;
    let phase = vec![
        0.0,
        -k0 * r.powi(2) / (2.0 * f),
        k0 * r.powi(4) / (8.0 * f.powi(3)),
        -k0 * r.powi(6) / (16.0 * f.powi(5)),
        k0 * 5.0 * r.powi(8) / (128.0 * f.powi(7)),
    ];
    let lambda = l0;
    let terms = vec![
        (lambda / std::f64::consts::TAU, Arc::new(RadialProfile::even_polynomial(phase)?)),
        (1.0, Arc::new(RadialProfile::reference_sphere(r, f)?)),
    ];
    let pupil = Arc::new(RadialPupil::new(None, terms, vec![])?);
    let order = RadialOrder::new(pupil.clone(), pupil.fitted_defocus_m(), lambda);
    let accuracy = 1e-11;
    let frequencies: Vec<f64> = (1..=200).map(|i| 0.38 * i as f64 / 200.0).collect();
    let value = median_seconds(|| frequencies.iter().map(|&s| order.otf(s, accuracy)).sum());
    println!("OTF alone: {:.3} ms for {} frequencies", 1e3 * value, frequencies.len());
    for k in [4, 12] {
        // ∂W/∂a_j = (λ/2π) q^j: the geometric-phase dispersion
        let directions: Vec<RadialProfile> = (1..=k)
            .map(|j| {
                let mut c = vec![0.0; j + 1];
                c[j] = lambda / std::f64::consts::TAU;
                RadialProfile::even_polynomial(c)
            })
            .collect::<Result<_, _>>()?;
        let mut d = vec![0.0; k];
        let both = median_seconds(|| {
            frequencies.iter().map(|&s| order.otf_and_derivatives(s, accuracy, &directions, &mut d) + d[0]).sum()
        });
        println!("OTF and K = {k:2} derivatives: {:.3} ms, {:.2}x the OTF alone", 1e3 * both, both / value);
    }
    Ok(())
}
