//! The meta-atom library lens against references written here: an N-level staircase's
//! first-order efficiency `sinc²(1/N)` (scalar theory), and a library of λ-independent phase and
//! `|t|² = τ` against the geometric-phase lens of the same profile.

use std::sync::Arc;

use lenses::{
    AtomErrors, Curve, Dispersion, Interpolation, Library, LibraryLens, PhaseLens, binary2_profile, hyperbolic_binary2,
    sinc,
};
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

/// The fine library lens of [`fine_library_is_the_geometric_phase_lens`] (64 levels, F/10,
/// 50 nm pitch: 300+ atoms a zone at the rim), `|t|² = 0.5`.
fn fine_lens() -> LibraryLens {
    let library = Arc::new(levels_library(64, 0.5f64.sqrt()));
    let (radii, params) = hyperbolic_layout(10.0, 0.05e-6, 64);
    LibraryLens::new(10.0, F0, L0, library, radii, params, "test".into()).unwrap()
}

/// τ1 and T at three wavelengths and the mean MTF over a 50 nm band, as bits (to compare two
/// lenses bit for bit).
fn fingerprint(lens: &LibraryLens) -> Vec<u64> {
    let mut out = Vec::new();
    for lambda in [780e-9, 800e-9, 820e-9] {
        out.push(lens.orders(lambda, Field::ON_AXIS)[0].efficiency.to_bits());
        out.push(lens.transmission(lambda).to_bits());
    }
    let spectrum = Spectrum::Gaussian(Gaussian::from_range(L0, 50e-9, 1.0).unwrap());
    let settings = Settings { tolerance: 1e-4, ..Settings::default() };
    let poly = Polychromatic::with_settings(lens, &spectrum, Field::ON_AXIS, 1.0 / (2.0 * 5.2e-6), None, settings);
    out.push(poly.unwrap().mean_mtf().0.to_bits());
    out
}

fn errors(phase: f64, amplitude: f64, seed: u64) -> AtomErrors {
    AtomErrors { phase_sigma_rad: phase, transmission_sigma: amplitude, seed }
}

/// σ = 0 and a bias of 0 give the nominal lens bit for bit, whatever the seed.
#[test]
fn no_fabrication_error_is_the_nominal_lens_bit_for_bit() {
    let nominal = fingerprint(&fine_lens());
    let fabricated = fine_lens().with_fabrication(&[0.0], errors(0.0, 0.0, 12345)).unwrap();
    assert_eq!(fingerprint(&fabricated), nominal);
}

/// Independent per-atom phase errors δ ~ N(0, σ²): each zone's first-order coefficient is the
/// mean of its atoms' `t e^{iδ}`, whose expectation is `t e^{−σ²/2}` (the normal's
/// characteristic function), so τ1 → τ1(0) e^{−σ²} (a Strehl-like factor; the light lost goes
/// into the zone-to-zone scatter and the other orders) with many atoms a zone, and T is
/// unchanged (a phase error). This lens has ~5 zones of ~300 atoms: one draw's τ1 scatters by
/// ~2 sd(cos δ)/(e^{−σ²/2} √N) ≈ 1.3 % (σ = 0.6, over the zones) about the expectation, biased
/// up by (e^{σ²} − 1)/N ≈ 0.15 % (the incoherent part of a finite zone); the mean of 16 seeds
/// is then within 1 % (3 standard errors).
#[test]
fn phase_errors_reduce_tau1_by_exp_minus_sigma_squared() {
    let nominal = fine_lens();
    let (tau0, t0) = (nominal.orders(L0, Field::ON_AXIS)[0].efficiency, nominal.transmission(L0));
    for sigma in [0.3f64, 0.6] {
        let want = (-sigma * sigma).exp();
        let seeds = 16;
        let mut mean = 0.0;
        for seed in 0..seeds {
            let lens = fine_lens().with_fabrication(&[0.0], errors(sigma, 0.0, seed)).unwrap();
            mean += lens.orders(L0, Field::ON_AXIS)[0].efficiency / tau0 / seeds as f64;
            let t = lens.transmission(L0);
            assert!((t - t0).abs() < 1e-12, "σ = {sigma}: T = {t} vs {t0}");
        }
        assert!((mean - want).abs() < 1e-2 * want, "σ = {sigma}: mean τ1/τ1(0) = {mean} vs e^(−σ²) = {want}");
    }
    // an amplitude error ε ~ N(0, σ_t²) leaves the coherent c_1 (E[1 + ε] = 1: τ1 to 1 %), and
    // T = E|1 + ε|² |t|² = (1 + σ_t²) |t|² (to its standard error over 16 seeds, ~1e-3); at
    // σ_t = 0.1 the cap |t| ≤ 1 (here 1 + ε > √2, a 4σ draw) and 1 + ε < 0 (10σ) never act
    let (mut tau, mut t) = (0.0, 0.0);
    for seed in 0..16 {
        let lens = fine_lens().with_fabrication(&[0.0], errors(0.0, 0.1, seed)).unwrap();
        tau += lens.orders(L0, Field::ON_AXIS)[0].efficiency / tau0 / 16.0;
        t += lens.transmission(L0) / t0 / 16.0;
        assert_eq!(lens.clamped_atoms(), 0);
    }
    assert!((tau - 1.0).abs() < 1e-2, "σ_t = 0.1: mean τ1/τ1(0) = {tau}");
    assert!((t - 1.01).abs() < 3e-3, "σ_t = 0.1: mean T/T(0) = {t} vs 1 + σ_t² = 1.01");
}

/// The same seed gives the same lens bit for bit; another seed another lens.
#[test]
fn atom_errors_are_reproducible_from_their_seed() {
    let a = fingerprint(&fine_lens().with_fabrication(&[0.0], errors(0.4, 0.1, 7)).unwrap());
    let b = fingerprint(&fine_lens().with_fabrication(&[0.0], errors(0.4, 0.1, 7)).unwrap());
    let c = fingerprint(&fine_lens().with_fabrication(&[0.0], errors(0.4, 0.1, 8)).unwrap());
    assert_eq!(a, b);
    assert_ne!(a, c);
}

/// A parameter bias shifts every atom (here by a whole level: the phase ramp moves by 2π/64,
/// a constant piston, so τ1 is the nominal one to 1e-3); one that pushes an atom outside the
/// library, or of the wrong length, or σ_t ≥ 0.5, is refused.
#[test]
fn parameter_bias_and_bad_errors() {
    // the levels library ends at level 63: shift the layout's atoms off the top level first
    let library = Arc::new(levels_library(64, 0.5f64.sqrt()));
    let (radii, params) = hyperbolic_layout(10.0, 0.05e-6, 64);
    let params: Vec<Vec<f64>> = params.into_iter().map(|p| vec![p[0].min(62.0)]).collect();
    let lens = || LibraryLens::new(10.0, F0, L0, library.clone(), radii.clone(), params.clone(), "t".into()).unwrap();
    let tau0 = lens().orders(L0, Field::ON_AXIS)[0].efficiency;
    let shifted = lens().with_fabrication(&[1.0], errors(0.0, 0.0, 0)).unwrap();
    let tau = shifted.orders(L0, Field::ON_AXIS)[0].efficiency;
    assert!((tau - tau0).abs() < 1e-3, "bias of one level: τ1 = {tau} vs {tau0}");
    let e = lens().with_fabrication(&[2.0], errors(0.0, 0.0, 0)).unwrap_err();
    assert!(e.to_string().contains("library's range"), "{e}");
    let e = lens().with_fabrication(&[0.0, 0.0], errors(0.0, 0.0, 0)).unwrap_err();
    assert!(e.to_string().contains("one per library parameter"), "{e}");
    let e = lens().with_fabrication(&[0.0], errors(0.0, 0.5, 0)).unwrap_err();
    assert!(e.to_string().contains("[0, 0.5)"), "{e}");
    let e = lens().with_fabrication(&[0.0], errors(-0.1, 0.0, 0)).unwrap_err();
    assert!(e.to_string().contains("≥ 0"), "{e}");
}

/// A library of constant `|t|` (64 phase levels over 2π, |t| = 0.9) keeps `|t|` between its rows:
/// the field follows the arc, not the chord (whose `|t|` dips midway by `1 − cos(π/64)` =
/// 1.2e-3, a first-order efficiency loss of `Δφ²/6` ≈ 1.6e-3 averaged over a row's step). The
/// phase midway is the rows' mean, through the short way where it wraps from π to −π (levels 32
/// and 33: π and −π + 2π·33/64 − 2π … written out here), and in λ the same.
#[test]
fn a_constant_amplitude_library_keeps_its_amplitude_between_rows() {
    let levels = 64;
    let library = levels_library(levels, 0.9);
    let step = std::f64::consts::TAU / levels as f64;
    for k in 0..levels - 1 {
        for u in [0.25, 0.5, 0.9] {
            let p = k as f64 + u;
            let t = library.transmission(&[p], 750e-9);
            assert!((t.norm() - 0.9).abs() < 1e-14, "p = {p}: |t| = {}", t.norm());
            // the phase step · p, as a point on the circle
            let want = num_complex::Complex64::from_polar(0.9, step * p);
            assert!((t - want).norm() < 1e-13, "p = {p}: {t} vs {want}");
        }
    }
    // 32 → 33 crosses the wrap (π, then −π + π/32): midway the phase is π + π/64
    let t = library.transmission(&[32.5], 800e-9);
    assert!((t.arg().rem_euclid(std::f64::consts::TAU) - (std::f64::consts::PI + step / 2.0)).abs() < 1e-13, "{t}");
    // the chord the field used to follow, for scale
    let chord = 0.5 * (num_complex::Complex64::from_polar(0.9, 0.0) + num_complex::Complex64::from_polar(0.9, step));
    assert!(0.9 - chord.norm() > 1e-3, "{}", chord.norm());
}

/// A fin library over width 50–100 nm, length 200–300 nm and 700–900 nm: converted amplitude
/// `a`, phase 0 (a fin's phase is its angle's), and with `co` the unconverted amplitude
/// `co(w) = co · w/100 nm` (linear in the width: interpolated as `|t|` is).
fn fin_library(a: f64, co: Option<f64>) -> Library {
    let mut rows = Vec::new();
    let mut unconverted = Vec::new();
    for w in [50.0, 100.0] {
        for l in [200.0, 300.0] {
            for lambda in [700e-9, 800e-9, 900e-9] {
                rows.push((vec![w, l], lambda, a, 0.0));
                unconverted.push(co.unwrap_or(0.0) * w / 100.0);
            }
        }
    }
    let library = Library::new(&rows).unwrap();
    match co {
        Some(_) => library.with_co_amplitude(&rows, &unconverted).unwrap(),
        None => library,
    }
}

/// A 50 × 50 lattice of 400 nm holding fins of width 75 nm and length 250 nm (θ = 0), covering
/// the aperture of F/2.5 at f0 = 50 µm (R = 10 µm), through `library`.
fn fin_lens(library: Library, fins: bool) -> Result<lenses::LibraryMapLens, lenses::Error> {
    let (n, pitch) = (50, 400e-9);
    let grid = lenses::AtomGrid {
        pitch_m: pitch,
        origin_m: (-0.5 * (n as f64 - 1.0) * pitch, -0.5 * (n as f64 - 1.0) * pitch),
        nx: n,
        ny: n,
        parameters: vec!["width_nm".into(), "length_nm".into()],
        values: [vec![75.0; n * n], vec![250.0; n * n]].concat(),
        empty: vec![false; n * n],
        theta_deg: fins.then(|| vec![0.0; n * n]),
        stats: lenses::LayoutStats::default(),
    };
    lenses::LibraryMapLens::new(
        2.5,
        50e-6,
        L0,
        Arc::new(library),
        &["width_nm".into(), "length_nm".into()],
        &grid,
        None,
        fins.then_some(lenses::Handedness::Lcp),
        0.0,
        "fins".into(),
    )
}

/// A fin's unconverted light (`co_amplitude`) is zero-order light: it adds `|t_co|²` to the
/// transmission T of every cell in the aperture and nothing to τ1. Against the same lens
/// without the column: τ1 equal, and `T = T_0 (a² + co²)/a²` (every cell holds the same fin, so
/// `T_0/a²` is the aperture's fill), with `co` = 0.5 × 75/100 interpolated in the width. The
/// library refuses `|t|² + |t_co|² > 1`, and pillars (no angle) and radial layouts refuse the
/// column.
#[test]
fn a_fins_unconverted_light_counts_in_the_transmission_not_in_tau1() {
    let a = 0.8;
    let plain = fin_lens(fin_library(a, None), true).unwrap();
    let with = fin_lens(fin_library(a, Some(0.5)), true).unwrap();
    let co = 0.5 * 0.75;
    for lambda in [720e-9, 800e-9, 880e-9] {
        let (tau0, t0) = plain.efficiency_and_transmission(lambda);
        let (tau, t) = with.efficiency_and_transmission(lambda);
        assert_eq!(tau, tau0, "τ1 at {lambda}");
        let want = t0 * (a * a + co * co) / (a * a);
        assert!((t - want).abs() < 1e-12 * want, "T at {lambda}: {t} vs {want}");
        assert!(t > t0 && t <= 1.0, "{t} {t0}");
        assert!((with.transmission(lambda) - t).abs() < 1e-15);
    }
    let e = fin_lens(fin_library(a, Some(0.5)), false).unwrap_err().to_string();
    assert!(e.contains("co_amplitude") && e.contains("no angle"), "{e}");
    let rows = vec![(vec![1.0], 8e-7, 0.9, 0.0), (vec![2.0], 8e-7, 0.9, 0.0)];
    let e = Library::new(&rows).unwrap().with_co_amplitude(&rows, &[0.3, 0.5]).unwrap_err().to_string();
    assert!(e.contains("co_amplitude") && e.contains("≤ 1"), "{e}");
    let library = Library::new(&rows).unwrap().with_co_amplitude(&rows, &[0.3, 0.4]).unwrap();
    assert!((library.co_amplitude(&[1.25], 8e-7) - 0.325).abs() < 1e-15);
    let radii: Vec<f64> = (0..8).map(|i| (i as f64 + 0.5) * 1e-4).collect();
    let e = LibraryLens::new(2.5, F0, L0, Arc::new(library), radii, vec![vec![1.5]; 8], "radial".into())
        .unwrap_err()
        .to_string();
    assert!(e.contains("co_amplitude"), "{e}");
}

/// A cubic fin library over width 50–100 nm (11 rows), length 200–300 nm and 700–900 nm whose
/// converted field `|t| = 0.6 + 0.25 sin(w/20 nm)`, `φ = w/40 nm` and unconverted amplitude
/// `|t_co| = 0.3 + 0.1 cos(w/25 nm)` move with the width (`|t|² + |t_co|² ≤ 0.89`).
fn smooth_fin_library() -> Library {
    let mut rows = Vec::new();
    let mut unconverted = Vec::new();
    for i in 0..=10 {
        let w = 50.0 + 5.0 * i as f64;
        for l in [200.0, 300.0] {
            for lambda in [700e-9, 800e-9, 900e-9] {
                rows.push((vec![w, l], lambda, 0.6 + 0.25 * (w / 20.0).sin(), w / 40.0));
                unconverted.push(0.3 + 0.1 * (w / 25.0).cos());
            }
        }
    }
    Library::new(&rows)
        .unwrap()
        .with_co_amplitude(&rows, &unconverted)
        .unwrap()
        .with_interpolation(Interpolation::Cubic)
}

/// A 2-D fin layout's bias with transmission errors and the fins' unconverted light
/// (docs/physics.md, "Gradients: a library's parameter bias"): `order_derivatives`' `∂τ1` and
/// `∂T` of the width's bias against Richardson-extrapolated central differences (steps 0.002
/// and 0.001 nm) of the lens's own `(τ1, T)` with the bias applied by `with_fabrication`, on a
/// 50 × 50 lattice of fins whose width runs 56–94 nm across it and angle turns with the site,
/// at σ_t = 0.3 (the cap `a ≤ 1/|t|` reached by a fifth of the draws of the brightest atoms)
/// with σ_φ = 0.2, and without errors: within 1e-8 of each derivative. Measured 6e-10 (the
/// differences' own error: the cubic's third derivative jumps at each row, and the atoms
/// within a step of a row give an error O(h): 6e-9 at 0.01 nm, 3e-8 at 0.1 nm). Then σ_t
/// itself, the clipped moments' derivative in σ_t.
#[test]
fn fin_layout_bias_with_transmission_errors_and_unconverted_light() {
    let library = Arc::new(smooth_fin_library());
    let (n, pitch) = (50, 400e-9);
    let width: Vec<f64> = (0..n * n).map(|k| 56.0 + 38.0 * ((k % n + 3 * (k / n)) % 37) as f64 / 36.0).collect();
    let grid = lenses::AtomGrid {
        pitch_m: pitch,
        origin_m: (-0.5 * (n as f64 - 1.0) * pitch, -0.5 * (n as f64 - 1.0) * pitch),
        nx: n,
        ny: n,
        parameters: vec!["width_nm".into(), "length_nm".into()],
        values: [width, vec![250.0; n * n]].concat(),
        empty: vec![false; n * n],
        theta_deg: Some((0..n * n).map(|k| (7 * k % 180) as f64).collect()),
        stats: lenses::LayoutStats::default(),
    };
    let nominal = lenses::LibraryMapLens::new(
        2.5,
        50e-6,
        L0,
        library,
        &["width_nm".into(), "length_nm".into()],
        &grid,
        None,
        Some(lenses::Handedness::Lcp),
        0.0,
        "fins".into(),
    )
    .unwrap();
    for (phase, amplitude) in [(0.2, 0.3), (0.0, 0.0)] {
        let at = |b: f64| {
            let lens = nominal.clone().with_fabrication(&[b, 0.0], errors(phase, amplitude, 1)).unwrap();
            lens.efficiency_and_transmission(780e-9)
        };
        let lens = nominal.clone().with_fabrication(&[0.5, 0.0], errors(phase, amplitude, 1)).unwrap();
        let d = lens.order_derivatives(780e-9, 0).unwrap();
        let central = |h: f64| {
            let (up, down) = (at(0.5 + h), at(0.5 - h));
            ((up.0 - down.0) / (2.0 * h), (up.1 - down.1) / (2.0 * h))
        };
        let (coarse, fine) = (central(0.002), central(0.001));
        let richardson = ((4.0 * fine.0 - coarse.0) / 3.0, (4.0 * fine.1 - coarse.1) / 3.0);
        let ours = (d.efficiencies[0], d.transmission);
        println!(
            "σφ {phase} σt {amplitude}: ∂τ1 {:.9e} vs {:.9e}, ∂T {:.9e} vs {:.9e}",
            ours.0, richardson.0, ours.1, richardson.1
        );
        for (a, b) in [(ours.0, richardson.0), (ours.1, richardson.1)] {
            assert!(a != 0.0 && (a - b).abs() <= 1e-8 * a.abs(), "σφ {phase} σt {amplitude}: {a} vs {b}");
        }
    }
    // σ_t itself (optics::ATOM_TRANSMISSION_ERROR), at σ_t = 0.3 and σ_φ = 0.2, against
    // Richardson central differences in σ_t (steps 0.002 and 0.001): within 1e-8
    let at = |st: f64| {
        let lens = nominal.clone().with_fabrication(&[0.5, 0.0], errors(0.2, st, 1)).unwrap();
        lens.efficiency_and_transmission(780e-9)
    };
    let lens = nominal.clone().with_fabrication(&[0.5, 0.0], errors(0.2, 0.3, 1)).unwrap();
    let d = lens.order_derivatives(780e-9, optics::ATOM_TRANSMISSION_ERROR).unwrap();
    let central = |h: f64| {
        let (up, down) = (at(0.3 + h), at(0.3 - h));
        ((up.0 - down.0) / (2.0 * h), (up.1 - down.1) / (2.0 * h))
    };
    let (coarse, fine) = (central(0.002), central(0.001));
    let richardson = ((4.0 * fine.0 - coarse.0) / 3.0, (4.0 * fine.1 - coarse.1) / 3.0);
    println!(
        "σt: ∂τ1 {:.9e} vs {:.9e}, ∂T {:.9e} vs {:.9e}",
        d.efficiencies[0], richardson.0, d.transmission, richardson.1
    );
    for (a, b) in [(d.efficiencies[0], richardson.0), (d.transmission, richardson.1)] {
        assert!(a != 0.0 && (a - b).abs() <= 1e-8 * a.abs(), "σt: {a} vs {b}");
    }
}

/// A smooth two-parameter library to measure the interpolants against: `|t| = 0.5 + 0.3 sin(p)
/// cos(0.7 s)` and the phase `φ = 2.5 p + sin(1.3 p) + 0.4 s²` (wrapped into (−π, π] as a
/// library gives it), λ-independent, on `p ∈ [0, 3]` in `steps` rows and `s ∈ [0, 1]` in
/// `s_steps` rows, at 700 and 900 nm.
fn smooth_library(steps: usize, s_steps: usize, interpolation: Interpolation) -> Library {
    let mut rows = Vec::new();
    for i in 0..=steps {
        for j in 0..=s_steps {
            let p = 3.0 * i as f64 / steps as f64;
            let s = if s_steps == 0 { 0.0 } else { j as f64 / s_steps as f64 };
            let (a, phi) = smooth_field(p, s);
            let wrapped = phi - std::f64::consts::TAU * (phi / std::f64::consts::TAU).round();
            for lambda in [700e-9, 900e-9] {
                rows.push((vec![p, s], lambda, a, wrapped));
            }
        }
    }
    Library::new(&rows).unwrap().with_interpolation(interpolation)
}

/// The field [`smooth_library`] samples.
fn smooth_field(p: f64, s: f64) -> (f64, f64) {
    (0.5 + 0.3 * p.sin() * (0.7 * s).cos(), 2.5 * p + (1.3 * p).sin() + 0.4 * s * s)
}

/// The largest `|t − t_exact|` of a library over 997 × 7 points off its rows (ends included).
fn worst_error(library: &Library, two_d: bool) -> f64 {
    let mut worst: f64 = 0.0;
    for i in 0..=996 {
        let p = 3.0 * i as f64 / 996.0;
        for j in 0..7 {
            let s = if two_d { j as f64 / 6.0 } else { 0.0 };
            let (a, phi) = smooth_field(p, s);
            let t = library.transmission(&[p, s], 800e-9);
            worst = worst.max((t - num_complex::Complex64::from_polar(a, phi)).norm());
        }
    }
    worst
}

/// `library_interpolation = "cubic"` against a library sampled from a known smooth field: halving
/// the rows' step divides linear interpolation's error by about 4 (`h²/8 max|f''|`) and the
/// cubic's by about 16 (`O(h⁴)`, the ends included), in one parameter and in two (the tensor
/// product); at 12 rows over the range the cubic is already 20× closer. Measured (this test
/// prints them; `cargo test -p asnr-lenses --test lenses cubic -- --nocapture`): linear 4.0×
/// per halving; cubic 30×, 22×, 16× from 12 to 96 rows (faster than h⁴ while coarse, then h⁴).
#[test]
fn cubic_rows_converge_as_h4_and_linear_as_h2() {
    for two_d in [false, true] {
        let s_steps = |n: usize| if two_d { n / 3 } else { 0 };
        let errors = |interpolation| -> Vec<f64> {
            [12, 24, 48, 96]
                .iter()
                .map(|&n| worst_error(&smooth_library(n, s_steps(n), interpolation), two_d))
                .collect()
        };
        let (linear, cubic) = (errors(Interpolation::Linear), errors(Interpolation::Cubic));
        println!("2-D {two_d}: linear {linear:?}, cubic {cubic:?}");
        for k in 0..3 {
            let (rl, rc) = (linear[k] / linear[k + 1], cubic[k] / cubic[k + 1]);
            assert!((3.5..4.5).contains(&rl), "linear's error ratio at halving {k}: {rl} ({linear:?})");
            // at least h⁴ throughout, and h⁴ (not faster) once the rows resolve the field
            assert!(rc > 12.0 && rc < 40.0, "cubic's error ratio at halving {k}: {rc} ({cubic:?})");
            assert!(k < 2 || rc < 20.0, "cubic's error ratio at halving {k}: {rc} ({cubic:?})");
        }
        assert!(cubic[0] * 20.0 < linear[0], "{cubic:?} vs {linear:?}");
    }
}

/// The cubic interpolant is C¹ across a row: the one-sided slopes at a row (`Δ = 1e-6` of the
/// step) agree to the differences' own error, where linear's jump by the change of the field's
/// slope over a step; and exactly at the rows both give the library's values.
#[test]
fn cubic_rows_have_a_continuous_slope_and_pass_through_the_rows() {
    let cubic = smooth_library(12, 0, Interpolation::Cubic);
    let linear = smooth_library(12, 0, Interpolation::Linear);
    let h = 0.25;
    let delta = 1e-6 * h;
    for row in 1..12 {
        let p = row as f64 * h;
        let (a, phi) = smooth_field(p, 0.0);
        let exact = num_complex::Complex64::from_polar(a, phi);
        assert!((cubic.transmission(&[p, 0.0], 800e-9) - exact).norm() < 1e-14, "row {row}");
        let jump = |library: &Library| {
            let t = |x: f64| library.transmission(&[x, 0.0], 800e-9);
            let left = (t(p) - t(p - delta)) / delta;
            let right = (t(p + delta) - t(p)) / delta;
            (right - left).norm()
        };
        // the one-sided differences' own error: |t''| Δ ≈ 1e-6 · 0.25 · 7
        assert!(jump(&cubic) < 1e-5, "row {row}: cubic's slope jumps by {}", jump(&cubic));
        assert!(jump(&linear) > 1e-2, "row {row}: linear's slope jumps by {}", jump(&linear));
    }
}

/// The cubic `|t|` stays in `[0, 1]`: a library whose `|t|` steps from 1 to 0 and back (the
/// cubic would overshoot above 1 and below 0 beside the steps) is clamped there.
#[test]
fn cubic_amplitude_stays_between_0_and_1() {
    let mut rows = Vec::new();
    for p in 0..12 {
        let a = if (4..8).contains(&p) { 0.0 } else { 1.0 };
        for lambda in [700e-9, 900e-9] {
            rows.push((vec![p as f64], lambda, a, 0.0));
        }
    }
    let library = Library::new(&rows).unwrap().with_interpolation(Interpolation::Cubic);
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..=1100 {
        let a = library.transmission(&[i as f64 * 0.01], 800e-9).norm();
        range = (range.0.min(a), range.1.max(a));
    }
    assert!(range.0 >= 0.0 && range.1 <= 1.0, "{range:?}");
    assert_eq!(range, (0.0, 1.0));
}

/// `Library::transmission_and_derivative` (forward mode on the cubic's rule) against
/// differences of `transmission` in each parameter of a 2-D library, at 241 × 5 points: off the
/// rows, Richardson of central differences of steps 1e-4 and 5e-5 of the range, within 1e-8 of
/// the derivative's size; on a row (the second derivative jumps there: C¹, not C²) and at the
/// axis's ends, one-sided differences of step 1e-7 within 1e-5. The value is
/// `transmission`'s bit for bit. Linear rows have no derivative (`None`).
#[test]
fn cubic_derivative_is_the_interpolants_own() {
    let library = smooth_library(12, 4, Interpolation::Cubic);
    let mut worst: f64 = 0.0;
    for i in 0..=240 {
        let p = 3.0 * i as f64 / 240.0;
        for j in 0..5 {
            let s = 0.05 + 0.9 * j as f64 / 4.0;
            for (wrt, step, rows) in [(0, 3e-4, 0.25), (1, 1e-4, 0.25)] {
                let (t, dt) = library.transmission_and_derivative(&[p, s], 800e-9, wrt).unwrap();
                assert_eq!(t, library.transmission(&[p, s], 800e-9));
                let hi = if wrt == 0 { 3.0 } else { 1.0 };
                let x = [p, s][wrt];
                let at = |a: f64, b: f64| {
                    let mut y = [p, s];
                    y[wrt] = b.min(hi);
                    let up = library.transmission(&y, 800e-9);
                    y[wrt] = a.max(0.0);
                    (up - library.transmission(&y, 800e-9)) / (b.min(hi) - a.max(0.0))
                };
                let off_row = ((x / rows).round() * rows - x).abs() > 2.0 * step;
                if off_row {
                    let central = |h: f64| at(x - h, x + h);
                    let richardson = (4.0 * central(0.5 * step) - central(step)) / 3.0;
                    worst = worst.max((richardson - dt).norm() / dt.norm().max(1.0));
                } else {
                    // both sides inside the axis agree with the derivative (C¹); at an end, the one
                    for side in [at(x - 1e-7, x), at(x, x + 1e-7)] {
                        if side.is_finite() {
                            assert!(
                                (side - dt).norm() < 1e-5 * dt.norm().max(1.0),
                                "p {p} s {s} wrt {wrt}: {dt} vs {side}"
                            );
                        }
                    }
                }
            }
        }
    }
    println!("cubic derivative: worst relative difference {worst:.2e}");
    assert!(worst < 1e-8, "{worst:e}");
    let linear = smooth_library(12, 4, Interpolation::Linear);
    assert!(linear.transmission_and_derivative(&[1.3, 0.5], 800e-9, 0).is_none());
    assert!(library.transmission_and_derivative(&[1.3, 0.5], 800e-9, 2).is_none());
}

/// A 72-level library with cubic rows (parameter 0 … 71, phase `2π (p − 4)/64`, amplitude
/// `0.75 + 0.15 cos(6π p/64)`), whose hyperbolic layout at F/10 uses levels 4 … 67, so that a
/// bias of a few levels stays inside the library.
fn cubic_levels_lens() -> LibraryLens {
    let mut rows = Vec::new();
    for p in 0..72 {
        for lambda in [700e-9, 800e-9, 900e-9] {
            let phase = std::f64::consts::TAU * (p as f64 - 4.0) / 64.0;
            let wrapped = phase - std::f64::consts::TAU * (phase / std::f64::consts::TAU).round();
            let amplitude = 0.75 + 0.15 * (3.0 * std::f64::consts::TAU * p as f64 / 64.0).cos();
            rows.push((vec![p as f64], lambda, amplitude, wrapped));
        }
    }
    let library = Arc::new(Library::new(&rows).unwrap().with_interpolation(Interpolation::Cubic));
    let (radii, params) = hyperbolic_layout(10.0, 0.1e-6, 64);
    let params = params.into_iter().map(|p| vec![p[0] + 4.0]).collect();
    LibraryLens::new(10.0, F0, L0, library, radii, params, "test".into()).unwrap()
}

/// `LibraryLens::first_order_derivative` against central differences of the lens's own imaging
/// order (τ1, T, the pupil's amplitude and whole wavefront at 11 radii) in the parameter bias,
/// at a bias of 0.3 levels, 780 and 815 nm, without and with atom errors (σ_φ = 0.3 rad,
/// σ_t = 0.02: no atom reaches the cap |t| = 1, where the value has a kink): Richardson of steps
/// 0.04 and 0.02 levels (smaller steps meet the fits' rounding, about 1e-9 of A over the step).
/// Each group (τ1 and T; A; W) within 3e-5 of its largest derivative; measured (this test prints
/// them; `cargo test -p asnr-lenses --test lenses first_order_derivative -- --nocapture`):
/// at most 3.1e-6 (τ1 and T), 1.2e-5 (A), 1.4e-7 (W), about the differences' own spread.
#[test]
fn first_order_derivative_against_central_differences() {
    let nominal = cubic_levels_lens();
    let bias = 0.3;
    for with_errors in [false, true] {
        let e = if with_errors { errors(0.3, 0.02, 11) } else { AtomErrors::default() };
        let lens = |b: f64| nominal.clone().with_fabrication(&[b], e).unwrap();
        let at_bias = lens(bias);
        for lambda in [780e-9, 815e-9] {
            let d = at_bias.first_order_derivative(lambda, 0).unwrap();
            // the quantities compared: τ1, T, A(q) and W(q) at 11 radii
            let sample = |l: &LibraryLens| -> Vec<f64> {
                let orders = l.orders(lambda, Field::ON_AXIS);
                let optics::Pupil::Radial(pupil) = &orders[0].pupil else { panic!("a radial pupil") };
                let mut out = vec![orders[0].efficiency, l.transmission(lambda)];
                out.extend((0..=10).map(|i| pupil.amplitude(i as f64 / 10.0)));
                out.extend((0..=10).map(|i| {
                    let q = i as f64 / 10.0;
                    pupil.opd_beyond_defocus_m(q) + pupil.fitted_defocus_m() * q
                }));
                out
            };
            let value = sample(&at_bias);
            assert_eq!(value[0], d.efficiency);
            assert_eq!(value[1], d.transmission);
            let difference = |h: f64| -> Vec<f64> {
                let (up, down) = (sample(&lens(bias + h)), sample(&lens(bias - h)));
                up.iter().zip(&down).map(|(u, d)| (u - d) / (2.0 * h)).collect()
            };
            let (coarse, fine) = (difference(0.04), difference(0.02));
            let mut ours = vec![d.efficiency_derivative, d.transmission_derivative];
            ours.extend((0..=10).map(|i| d.amplitude.value(i as f64 / 10.0)));
            ours.extend((0..=10).map(|i| d.wavefront_m.value(i as f64 / 10.0)));
            let groups = [0..2, 2..13, 13..24];
            for group in groups {
                let size = ours[group.clone()].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                let worst =
                    group.clone().map(|k| ((4.0 * fine[k] - coarse[k]) / 3.0 - ours[k]).abs()).fold(0.0_f64, f64::max);
                println!("errors {with_errors} λ {lambda}: quantities {group:?}: {:.1e} of {size:.3e}", worst / size);
                assert!(worst < 3e-5 * size, "errors {with_errors} λ {lambda}: {group:?}: {ours:?} vs {fine:?}");
            }
            assert!(d.efficiency_derivative.abs() > 1e-4, "a derivative to test: {}", d.efficiency_derivative);
        }
    }
}
