//! The meta-atom library lens against references written here: an N-level staircase's
//! first-order efficiency `sinc²(1/N)` (scalar theory), and a library of λ-independent phase and
//! `|t|² = τ` against the geometric-phase lens of the same profile.

use std::sync::Arc;

use lenses::{Curve, Dispersion, Library, LibraryLens, PhaseLens, binary2_profile, hyperbolic_binary2, sinc};
use optics::{Field, LensModel, Polychromatic, Settings};
use radiometry::{Gaussian, Spectrum};

const F0: f64 = 3.36e-3;
const L0: f64 = 800e-9;

/// A library of `levels` atoms (parameter 0 … levels − 1) of phase `2π p/levels` and amplitude
/// `amplitude`, the same at 700, 800 and 900 nm.
fn levels_library(levels: usize, amplitude: f64) -> Library {
    let mut rows = Vec::new();
    for p in 0..levels {
        for lambda in [700e-9, 800e-9, 900e-9] {
            let phase = std::f64::consts::TAU * p as f64 / levels as f64;
            let wrapped = if phase > std::f64::consts::PI { phase - std::f64::consts::TAU } else { phase };
            rows.push((vec![p as f64], lambda, amplitude, wrapped));
        }
    }
    Library::new(&rows).unwrap()
}

/// The hyperbolic layout at `pitch_m`: each ring picks the level nearest to the design phase.
fn hyperbolic_layout(f_number: f64, pitch_m: f64, levels: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let radius = 0.5 * F0 / f_number;
    let count = (radius / pitch_m).ceil() as usize;
    let mut radii = Vec::new();
    let mut params = Vec::new();
    for i in 0..count {
        let r = (i as f64 + 0.5) * pitch_m;
        let phase = -std::f64::consts::TAU / L0 * ((r * r + F0 * F0).sqrt() - F0);
        let level =
            (phase.rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU * levels as f64).round() as usize % levels;
        radii.push(r);
        params.push(vec![level as f64]);
    }
    (radii, params)
}

/// N levels per zone send `sinc²(1/N)` of the light into the first order (zones of 80 to 100s of
/// atoms at F/10, so that the atoms' grid barely moves the level edges): to 2e-3, for N = 3, 4,
/// 8; the transmission is `|t|²` of every atom. Two levels (a binary lens) are refused: its
/// phase steps of π cannot be unwrapped into a design phase.
#[test]
fn staircase_sends_sinc_squared_into_the_first_order() {
    let f_number = 10.0;
    let binary = Arc::new(levels_library(2, 0.9));
    let (radii, params) = hyperbolic_layout(f_number, 0.1e-6, 2);
    let e = LibraryLens::new(f_number, F0, L0, binary, radii, params, "test".into()).unwrap_err();
    assert!(e.to_string().contains("unwrapped"), "{e}");
    for levels in [3usize, 4, 8] {
        let library = Arc::new(levels_library(levels, 0.9));
        let (radii, params) = hyperbolic_layout(f_number, 0.1e-6, levels);
        let lens = LibraryLens::new(f_number, F0, L0, library, radii, params, "test".into()).unwrap();
        let orders = lens.orders(L0, Field::ON_AXIS);
        let tau = orders[0].efficiency;
        let want = 0.81 * sinc(1.0 / levels as f64).powi(2);
        assert!((tau - want).abs() < 2e-3, "N = {levels}: τ1 = {tau} vs 0.81 sinc² = {want}");
        let t = lens.transmission(L0);
        assert!((t - 0.81).abs() < 1e-9, "N = {levels}: T = {t}");
    }
}

/// A library of 64 levels (`sinc²(1/64)` = 0.9992), λ-independent phase, `|t|² = 0.5`: its mean
/// MTF is the geometric-phase lens's of the same (hyperbolic) profile over a 50 nm band to 1e-4
/// (the residual staircase), and τ1 = 0.5 sinc²(1/64) to 1e-3.
#[test]
fn fine_library_is_the_geometric_phase_lens() {
    let f_number = 10.0;
    let levels = 64;
    let library = Arc::new(levels_library(levels, 0.5f64.sqrt()));
    let (radii, params) = hyperbolic_layout(f_number, 0.05e-6, levels);
    let lens = LibraryLens::new(f_number, F0, L0, library, radii, params, "test".into()).unwrap();
    let tau = lens.orders(L0, Field::ON_AXIS)[0].efficiency;
    assert!((tau - 0.5 * sinc(1.0 / 64.0).powi(2)).abs() < 1e-3, "τ1 = {tau}");
    let radius = 0.5 * F0 / f_number;
    let profile = Arc::new(binary2_profile(&hyperbolic_binary2(F0, L0, radius, 6), 1.0, radius, radius).unwrap());
    let phase = PhaseLens::new(
        f_number,
        F0,
        L0,
        profile,
        None,
        Dispersion::GeometricPhase,
        Curve::Constant(0.5),
        Curve::Constant(0.5),
        "binary2".into(),
    )
    .unwrap();
    let spectrum = Spectrum::product(vec![
        Spectrum::Gaussian(Gaussian::from_range(L0, 50e-9, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ]);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let settings = Settings { tolerance: 1e-7, ..Settings::default() };
    let mean = |lens: &dyn LensModel| {
        Polychromatic::with_settings(lens, &spectrum, Field::ON_AXIS, nyquist, None, settings).unwrap().mean_mtf().0
    };
    let (a, b) = (mean(&lens), mean(&phase));
    assert!((a - b).abs() < 1e-4 * b, "library {a} vs geometric phase {b}");
}

/// Bad libraries and layouts are refused: a grid with a hole, an amplitude above 1, a layout of
/// unequal pitch, a parameter outside the library, a layout short of the aperture.
#[test]
fn library_and_layout_errors() {
    let rows = vec![(vec![0.0], 800e-9, 1.0, 0.0), (vec![1.0], 800e-9, 1.0, 1.0), (vec![1.0], 900e-9, 1.0, 1.0)];
    assert!(Library::new(&rows).unwrap_err().to_string().contains("full grid"));
    let rows = vec![(vec![0.0], 800e-9, 1.5, 0.0)];
    assert!(Library::new(&rows).unwrap_err().to_string().contains("[0, 1]"));
    let library = Arc::new(levels_library(4, 1.0));
    let (radii, params) = hyperbolic_layout(10.0, 0.1e-6, 4);
    let mut uneven = radii.clone();
    uneven[3] += 0.01e-6;
    let e = LibraryLens::new(10.0, F0, L0, library.clone(), uneven, params.clone(), "t".into()).unwrap_err();
    assert!(e.to_string().contains("equal"), "{e}");
    let mut outside = params.clone();
    outside[5] = vec![7.0];
    let e = LibraryLens::new(10.0, F0, L0, library.clone(), radii.clone(), outside, "t".into()).unwrap_err();
    assert!(e.to_string().contains("library's range"), "{e}");
    let n = radii.len() / 2;
    let e = LibraryLens::new(10.0, F0, L0, library, radii[..n].to_vec(), params[..n].to_vec(), "t".into()).unwrap_err();
    assert!(e.to_string().contains("aperture radius"), "{e}");
}
