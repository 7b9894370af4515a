//! The phase-profile lens against references written here: the Binary 2 series of the hyperbola,
//! the diffraction limit, the paraxial families (chromatic, harmonic) where the exact sphere's
//! departure from the parabola is below the tolerance, and the ideal refractive lens.

use std::sync::Arc;

use lenses::{
    ChromaticMetalens, Curve, Dispersion, Glass, Harmonic, PhaseLens, Refractive, Surfaces, binary2_profile,
    hyperbolic_binary2,
};
use optics::radial::RadialProfile;
use optics::{Field, LensModel, Polychromatic, Pupil, Settings, mtf_diffraction_limited};
use radiometry::{Gaussian, Spectrum};

const F0: f64 = 3.36e-3;
const L0: f64 = 800e-9;

fn band(range_nm: f64) -> Spectrum {
    Spectrum::product(vec![
        Spectrum::Gaussian(Gaussian::from_range(L0, range_nm * 1e-9, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ])
}

/// The hyperbolic phase through 6 Binary 2 terms, normalized to the aperture radius.
fn hyperbolic(f_number: f64, dispersion: Dispersion) -> PhaseLens {
    let radius = 0.5 * F0 / f_number;
    let coefficients = hyperbolic_binary2(F0, L0, radius, 6);
    let profile = Arc::new(binary2_profile(&coefficients, 1.0, radius, radius).unwrap());
    PhaseLens::new(
        f_number,
        F0,
        L0,
        profile,
        None,
        dispersion,
        Curve::Constant(0.15),
        Curve::Constant(0.55),
        "binary2".into(),
    )
    .unwrap()
}

fn mean(lens: &dyn LensModel, spectrum: &Spectrum, nyquist: f64, tolerance: f64) -> f64 {
    let settings = Settings { tolerance, ..Settings::default() };
    Polychromatic::with_settings(lens, spectrum, Field::ON_AXIS, nyquist, None, settings).unwrap().mean_mtf().0
}

/// The coefficients of docs/physics.md: `A1 = −(2π/λ0) R²/(2f0)`, `A2 = +(2π/λ0) R⁴/(8f0³)`,
/// `A3 = −(2π/λ0) R⁶/(16 f0⁵)`, `A4 = +(2π/λ0) 5R⁸/(128 f0⁷)`, and four terms within 1e-11 m of
/// the hyperbola (as path, `λ0 φ/2π`) at the paper's aperture.
#[test]
fn binary2_series_of_the_hyperbola() {
    let r = 0.672e-3;
    let k = std::f64::consts::TAU / L0;
    let a = hyperbolic_binary2(F0, L0, r, 4);
    let want = [
        -k * r.powi(2) / (2.0 * F0),
        k * r.powi(4) / (8.0 * F0.powi(3)),
        -k * r.powi(6) / (16.0 * F0.powi(5)),
        k * 5.0 * r.powi(8) / (128.0 * F0.powi(7)),
    ];
    for (got, want) in a.iter().zip(want) {
        assert!((got - want).abs() < 1e-12 * want.abs(), "{got} vs {want}");
    }
    let profile = binary2_profile(&a, 1.0, r, r).unwrap();
    for i in 0..=20 {
        let rho = i as f64 / 20.0;
        let exact = -((rho * r).powi(2) + F0 * F0).sqrt() + F0;
        let path = profile.value(rho * rho) / k;
        assert!((path - exact).abs() < 1e-11, "ρ = {rho}: {path} vs {exact}");
    }
}

/// The hyperbolic geometric-phase lens is diffraction-limited at λ0 (its wavefront against the
/// exact sphere vanishes): the monochromatic MTF is the aberration-free one.
#[test]
fn hyperbolic_profile_is_diffraction_limited_at_the_design_wavelength() {
    let lens = hyperbolic(2.5, Dispersion::GeometricPhase);
    let cutoff = 1.0 / (L0 * 2.5);
    let freqs: Vec<f64> = (1..20).map(|i| i as f64 / 20.0 * cutoff).collect();
    let mtf = optics::monochromatic_mtf(&lens, L0, Field::ON_AXIS, &freqs, 64).unwrap();
    for (m, nu) in mtf.iter().zip(&freqs) {
        let want = mtf_diffraction_limited(nu / cutoff);
        assert!((m - want).abs() < 1e-9, "ν/ν_c = {}: {m} vs {want}", nu / cutoff);
    }
}

/// The quadratic profile `−π r²/(λ0 f0)` carries `−R⁴/(8 f0³)` = −0.67 µm (−0.84 waves) of
/// spherical aberration at the rim of the paper's aperture (the OPD at the rim less the axis's,
/// less the paraxial defocus there, which is zero at λ0).
#[test]
fn quadratic_profile_carries_spherical_aberration() {
    let (f_number, radius) = (2.5, 0.672e-3);
    let k = std::f64::consts::TAU / L0;
    let quadratic = Arc::new(RadialProfile::even_polynomial(vec![0.0, -k * radius * radius / (2.0 * F0)]).unwrap());
    let lens = PhaseLens::new(
        f_number,
        F0,
        L0,
        quadratic,
        None,
        Dispersion::GeometricPhase,
        Curve::Constant(0.15),
        Curve::Constant(0.55),
        "test".into(),
    )
    .unwrap();
    let order = &lens.orders(L0, Field::ON_AXIS)[0];
    let Pupil::Radial(pupil) = &order.pupil else { panic!("not a radial pupil") };
    let opd = |q: f64| order.wavefront.defocus_m * q + pupil.opd_beyond_defocus_m(q);
    // at λ0 the OPD is the sag less its parabola: √(R² + f0²) − f0 − R²/(2f0) at the rim,
    // −R⁴/(8 f0³) = −0.672 µm (−0.84 waves) to fourth order, −0.659 µm (−0.82 waves) exactly
    let rim = opd(1.0) - opd(0.0);
    let exact = (radius * radius + F0 * F0).sqrt() - F0 - radius * radius / (2.0 * F0);
    assert!((rim - exact).abs() < 1e-12, "{rim} vs {exact}");
    let fourth = -radius.powi(4) / (8.0 * F0.powi(3));
    assert!((rim - fourth).abs() < 0.025 * fourth.abs(), "{rim} vs {fourth}");
    assert!((rim / L0 + 0.824).abs() < 0.001, "{} waves", rim / L0);
}

/// At F/25 the exact sphere is the parabola to 2.5e-6 waves over a 50 nm band: the hyperbolic
/// geometric-phase lens is the chromatic lens, and the diffractive p = 1 lens the harmonic one,
/// to 1e-6 of the mean MTF.
#[test]
fn paraxial_limit_is_the_chromatic_and_harmonic_families() {
    let f_number = 25.0;
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let spectrum = band(50.0);
    let phase = mean(&hyperbolic(f_number, Dispersion::GeometricPhase), &spectrum, nyquist, 1e-8);
    let chromatic = ChromaticMetalens::new(f_number, F0, L0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
    let reference = mean(&chromatic, &spectrum, nyquist, 1e-8);
    assert!((phase - reference).abs() < 1e-6 * reference, "{phase} vs {reference}");
    let diffractive =
        mean(&hyperbolic(f_number, Dispersion::Diffractive { design_order: 1 }), &spectrum, nyquist, 1e-8);
    let harmonic = Harmonic::new(f_number, F0, L0, 1, 0.15, Curve::Constant(0.55)).unwrap();
    let reference = mean(&harmonic, &spectrum, nyquist, 1e-8);
    assert!((diffractive - reference).abs() < 1e-6 * reference, "{diffractive} vs {reference}");
}

/// The hyperbolic profile as a fixed optical path (refractive, no glass) is diffraction-limited
/// at every wavelength: over a 200 nm band its mean MTF is the ideal refractive lens's.
#[test]
fn refractive_hyperbolic_profile_is_diffraction_limited_over_a_band() {
    let nyquist = 1.0 / (2.0 * 2.0e-6);
    let spectrum = band(200.0);
    let lens = hyperbolic(2.5, Dispersion::Refractive { glass: None });
    let got = mean(&lens, &spectrum, nyquist, 1e-8);
    let ideal = Refractive::new(2.5, F0, L0, Glass::Constant(1.5), 1, Surfaces::Coated(0.0)).unwrap();
    let want = mean(&ideal, &spectrum, nyquist, 1e-8);
    assert!((got - want).abs() < 1e-7 * want, "{got} vs {want}");
}

/// The diffractive kinoform's orders: at λ0 the design order carries τ; between, the orders
/// share `τ sinc²(pλ0/λ − m)`.
#[test]
fn diffractive_orders_share_the_efficiency() {
    let lens = hyperbolic(2.5, Dispersion::Diffractive { design_order: 3 });
    let at_design = lens.orders(L0, Field::ON_AXIS);
    let total: f64 = at_design.iter().map(|o| o.efficiency).sum();
    assert!((total - 0.15).abs() < 1e-15, "{total}");
    let lambda = 850e-9;
    let alpha = 3.0 * L0 / lambda;
    let sum: f64 = lens.orders(lambda, Field::ON_AXIS).iter().map(|o| o.efficiency).sum();
    let want: f64 = (1..=6)
        .filter(|&m| (m as f64 - alpha).abs() <= 3.0)
        .map(|m| 0.15 * lenses::sinc(alpha - m as f64).powi(2))
        .sum();
    assert!((sum - want).abs() < 1e-15, "{sum} vs {want}");
}

/// Off axis the hyperbolic metalens has the field aberrations of its oblique wave: at 8° and
/// λ0 its monochromatic MTF (FFT path) falls below the diffraction limit, and at 0.01° it is the
/// on-axis one to the FFT path's accuracy.
#[test]
fn off_axis_hyperbolic_lens_has_field_aberrations() {
    let lens = hyperbolic(2.5, Dispersion::GeometricPhase);
    let cutoff = 1.0 / (L0 * 2.5);
    let freqs: Vec<f64> = (1..10).map(|i| i as f64 / 10.0 * cutoff).collect();
    let tilted = optics::monochromatic_mtf(&lens, L0, Field::new(8f64.to_radians(), 0.0), &freqs, 256).unwrap();
    let near = optics::monochromatic_mtf(&lens, L0, Field::new(0.01f64.to_radians(), 0.0), &freqs, 256).unwrap();
    let mut loss = 0.0;
    for ((t, n), nu) in tilted.iter().zip(&near).zip(&freqs) {
        let ideal = mtf_diffraction_limited(nu / cutoff);
        assert!((n - ideal).abs() < 2e-3, "0.01°, ν/ν_c = {}: {n} vs {ideal}", nu / cutoff);
        loss += ideal - t;
    }
    assert!(loss > 0.05, "the 8° MTF is not below the diffraction limit: total loss {loss}");
}

/// The conformance checks of optics::testkit hold (the diffractive lens at F/10, whose stray
/// orders' defocus, up to 3 × R²/(2f0) = 17 waves, keeps the radial engine's work small).
#[test]
fn phase_lens_conforms() {
    optics::testkit::check_lens(&hyperbolic(2.5, Dispersion::GeometricPhase), &band(20.0)).unwrap();
    optics::testkit::check_lens(&hyperbolic(10.0, Dispersion::Diffractive { design_order: 1 }), &band(20.0)).unwrap();
}

/// The clamped–natural cubic spline through `(0, y0), (½, y1), (1, y2)` solved as two cubics
/// `a + b t + c t² + d t³` (8 unknowns: the knots, zero slope at 0, C¹ and C² at ½, zero
/// curvature at 1) by Gaussian elimination with partial pivoting: the reference for three knots.
fn two_piece_spline(y: [f64; 3]) -> impl Fn(f64) -> f64 {
    let row = |t: f64, k: usize| -> [f64; 4] {
        match k {
            0 => [1.0, t, t * t, t * t * t],
            1 => [0.0, 1.0, 2.0 * t, 3.0 * t * t],
            _ => [0.0, 0.0, 2.0, 6.0 * t],
        }
    };
    let mut a = vec![[0.0; 9]; 8];
    let mut put = |r: usize, piece: usize, coefficients: [f64; 4], sign: f64, rhs: f64| {
        for (j, c) in coefficients.iter().enumerate() {
            a[r][4 * piece + j] += sign * c;
        }
        a[r][8] = rhs;
    };
    put(0, 0, row(0.0, 0), 1.0, y[0]);
    put(1, 0, row(0.5, 0), 1.0, y[1]);
    put(2, 1, row(0.5, 0), 1.0, y[1]);
    put(3, 1, row(1.0, 0), 1.0, y[2]);
    put(4, 0, row(0.0, 1), 1.0, 0.0);
    put(5, 0, row(0.5, 1), 1.0, 0.0);
    put(5, 1, row(0.5, 1), -1.0, 0.0);
    put(6, 0, row(0.5, 2), 1.0, 0.0);
    put(6, 1, row(0.5, 2), -1.0, 0.0);
    put(7, 1, row(1.0, 2), 1.0, 0.0);
    for col in 0..8 {
        let pivot = (col..8).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs())).unwrap();
        a.swap(col, pivot);
        let pivot_row = a[col];
        for (r, row) in a.iter_mut().enumerate() {
            if r != col {
                let w = row[col] / pivot_row[col];
                for (x, p) in row.iter_mut().zip(&pivot_row).skip(col) {
                    *x -= w * p;
                }
            }
        }
    }
    let x: Vec<f64> = (0..8).map(|i| a[i][8] / a[i][i]).collect();
    move |t: f64| {
        let c = if t <= 0.5 { &x[..4] } else { &x[4..] };
        c[0] + t * (c[1] + t * (c[2] + t * c[3]))
    }
}

/// Three knots: the profile is the two-piece clamped–natural spline (written above as its own
/// linear system), whose slope vanishes on the axis; four knots or more: the spline of a phase
/// table at the knots' radii (`RadialProfile::table`), through every knot.
#[test]
fn spline_profile_is_the_clamped_natural_spline() {
    let y = [1.3, -0.4, 2.1];
    let profile = lenses::spline_profile(&y).unwrap();
    let reference = two_piece_spline(y);
    for i in 0..=100 {
        let rho = i as f64 / 100.0;
        let (got, want) = (profile.value(rho * rho), reference(rho));
        assert!((got - want).abs() < 1e-13, "ρ = {rho}: {got} vs {want}");
    }
    // zero slope on the axis: the difference quotient (S(ρ) − S(0))/ρ falls in proportion to ρ
    // (S = y0 + S''(0) ρ²/2 + …), ten times smaller at ρ = 1e-4 than at 1e-3
    let quotient = |rho: f64| (profile.value(rho * rho) - profile.value(0.0)) / rho;
    let ratio = quotient(1e-3) / quotient(1e-4);
    assert!((ratio - 10.0).abs() < 0.05, "{ratio}");
    let knots = [0.0, -3.0, -11.0, -24.5, -40.0, -60.0];
    let many = lenses::spline_profile(&knots).unwrap();
    let table = RadialProfile::table((0..knots.len()).map(|i| i as f64 / 5.0).collect(), knots.to_vec()).unwrap();
    for i in 0..=50 {
        let q = (i as f64 / 50.0).powi(2);
        assert_eq!(many.value(q), table.value(q));
    }
    for (i, k) in knots.iter().enumerate() {
        let rho = i as f64 / 5.0;
        assert!((many.value(rho * rho) - k).abs() < 1e-12, "knot {i}");
    }
}

/// Knots sampled from the hyperbolic profile at the paper's aperture (F/2.5, f0 = 3.36 mm,
/// λ0 = 800 nm, about 530 rad at the edge) converge to it as the knots grow (9, 17, 33): the
/// largest phase error falls at least 3× per doubling (the natural end's error falls as h², the
/// interior's as h⁴), and the 100 nm band's mean MTF of the spline lens goes to the hyperbolic
/// lens's (`-- --nocapture` prints both errors).
#[test]
fn spline_of_the_hyperbola_converges_to_it() {
    let f_number = 2.5;
    let radius = 0.5 * F0 / f_number;
    let k = std::f64::consts::TAU / L0;
    let exact = |rho: f64| -k * (((rho * radius).powi(2) + F0 * F0).sqrt() - F0);
    let lens_of = |knots: usize| {
        let values: Vec<f64> = (0..knots).map(|i| exact(i as f64 / (knots - 1) as f64)).collect();
        let profile = Arc::new(lenses::spline_profile(&values).unwrap());
        PhaseLens::new(
            f_number,
            F0,
            L0,
            profile.clone(),
            None,
            Dispersion::GeometricPhase,
            Curve::Constant(0.15),
            Curve::Constant(0.55),
            "spline".into(),
        )
        .unwrap()
    };
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let spectrum = band(100.0);
    let reference = mean(&hyperbolic(f_number, Dispersion::GeometricPhase), &spectrum, nyquist, 1e-7);
    let mut last: Option<(f64, f64)> = None;
    for knots in [9, 17, 33] {
        let lens = lens_of(knots);
        let error =
            (0..=1000).map(|i| i as f64 / 1000.0).map(|r| (lens.phase_at(r) - exact(r)).abs()).fold(0.0, f64::max);
        let mtf_error = (mean(&lens, &spectrum, nyquist, 1e-7) - reference).abs();
        println!("{knots} knots: phase error {error:.3e} rad, mean MTF error {mtf_error:.3e}");
        if let Some((e, m)) = last {
            assert!(error < e / 3.0, "{knots} knots: phase error {error} after {e}");
            assert!(mtf_error < m, "{knots} knots: mean MTF error {mtf_error} after {m}");
        }
        last = Some((error, mtf_error));
    }
    let (error, mtf_error) = last.unwrap();
    assert!(error < 0.05 && mtf_error < 1e-4, "33 knots: phase error {error} rad, mean MTF error {mtf_error}");
}

/// A spline added to a Binary 2 profile adds to its phase; too few knots, too many, or one
/// not finite are refused naming the key.
#[test]
fn spline_added_to_binary2_and_bad_knots() {
    let base = hyperbolic(2.5, Dispersion::GeometricPhase);
    let spline = Arc::new(lenses::spline_profile(&[0.5, 0.2, -0.3, 0.1]).unwrap());
    let both = base.clone().with_added_phase(spline.clone(), "spline");
    for i in 0..=10 {
        let rho = i as f64 / 10.0;
        let want = base.phase_at(rho) + spline.value(rho * rho);
        assert!((both.phase_at(rho) - want).abs() < 1e-12 * want.abs().max(1.0), "ρ = {rho}");
    }
    assert!(both.describe().contains("+ spline"), "{}", both.describe());
    for (knots, says) in [
        (vec![1.0, 2.0], "phase_spline_rad knots = 2"),
        (vec![0.0; 1025], "phase_spline_rad knots = 1025"),
        (vec![0.0, f64::NAN, 1.0], "phase_spline_rad = NaN"),
        (vec![0.0, 1.0, f64::INFINITY, 1.0], "phase_spline_rad = inf"),
    ] {
        let e = lenses::spline_profile(&knots).unwrap_err().to_string();
        assert!(e.contains(says), "{e}");
    }
}

/// The gradient's directions of a phase lens with 4 Binary 2 terms, a spline of 5 knots and
/// Zernike terms up to Noll 11 (`LensModel::binary2_directions`): 4 + 5 + 3 lanes (Noll 1, 4
/// and 11 are the m = 0 terms). The spline is linear in its knots, so each knot's lane is the
/// change of the spline when that knot moves by 1 rad (the difference of two splines written
/// here), times the order's path per radian (λ/2π, geometric phase); the Zernike lanes are
/// `1e-6 √(n+1) R_n^0` (Noll 1976: `√3 (2ρ² − 1)`, `√5 (6ρ⁴ − 6ρ² + 1)`), metres per µm.
#[test]
fn directions_of_the_binary2_terms_spline_knots_and_m0_zernike_terms() {
    let knots = [0.5, 0.2, -0.3, 0.1, 0.4];
    let lens = hyperbolic(2.5, Dispersion::GeometricPhase)
        .with_binary2_terms(vec![1.0; 4])
        .with_spline_knots(knots.len())
        .with_zernike_directions(11);
    let lambda = 780e-9;
    let directions = lens.binary2_directions(lambda).unwrap();
    assert_eq!(directions.len(), 1);
    let lanes = &directions[0];
    assert_eq!(lanes.len(), 4 + 5 + 3);
    let per_radian = lambda / std::f64::consts::TAU;
    let base = lenses::spline_profile(&knots).unwrap();
    for i in 0..knots.len() {
        let mut moved = knots;
        moved[i] += 1.0;
        let moved = lenses::spline_profile(&moved).unwrap();
        for j in 0..=20 {
            let q = f64::from(j) / 20.0;
            let want = per_radian * (moved.value(q) - base.value(q));
            let got = lanes[4 + i].value(q);
            assert!((got - want).abs() <= 1e-12 * per_radian, "knot {i}, q = {q}: {got} vs {want}");
        }
    }
    for j in 0..=20 {
        let q = f64::from(j) / 20.0;
        let z = [1.0, 3f64.sqrt() * (2.0 * q - 1.0), 5f64.sqrt() * (6.0 * q * q - 6.0 * q + 1.0)];
        for (k, z) in z.iter().enumerate() {
            let got = lanes[9 + k].value(q);
            assert!((got - 1e-6 * z).abs() <= 1e-18, "Zernike lane {k}, q = {q}: {got} vs {}", 1e-6 * z);
        }
    }
    // no Binary 2 terms, no spline, no Zernike terms: no directions
    assert!(hyperbolic(2.5, Dispersion::GeometricPhase).binary2_directions(lambda).is_none());
}
