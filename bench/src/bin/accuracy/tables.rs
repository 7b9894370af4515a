//! The long tables the accuracy report and the criterion benches share (the benches include this
//! file by path).

use lenses::Curve;
use radiometry::Sampled;

/// A 5000-row table (0.08 nm from 600 to 1000 nm) of `mean` with a ripple of 7 nm × `stretch`
/// and one of 0.77 nm.
pub(crate) fn rows(mean: f64, stretch: f64) -> Curve {
    let wavelengths: Vec<f64> = (0..5000).map(|k| 600e-9 + 0.08e-9 * k as f64).collect();
    let values = wavelengths
        .iter()
        .map(|&l| mean * (1.0 + (l / (7e-9 * stretch)).sin() / 6.0 + (l / 0.77e-9).cos() / 24.0))
        .collect();
    Curve::Table(Sampled::new(wavelengths, values).unwrap())
}
