//! The overlap quadrature (`Engine::Overlap`, docs/physics.md "Analytic 2-D pupils by quadrature
//! over the overlap") against a brute-force 2-D sum over the two pupils' overlap written here,
//! and against the FFT path on the same lens.

use std::f64::consts::PI;

use num_complex::Complex64;
use optics::{Engine, Field, LensModel, Order, Pupil, Settings, Wavefront};
use radiometry::{Gaussian, Spectrum};

const F_NUMBER: f64 = 2.5;
const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;

/// The chromatic metalens (`W020 = (1 − λ/λ0) f0/(8 F#²)`) with Seidel terms (m) at the field
/// point, and a lateral colour `Δx = shift (λ0/λ − 1)` along x.
#[derive(Debug)]
struct SeidelLens {
    spherical: f64,
    coma: f64,
    astigmatism: f64,
    shift: f64,
}

impl SeidelLens {
    fn wavefront(&self, lambda: f64) -> Wavefront {
        let mut w = Wavefront::defocus((1.0 - lambda / LAMBDA0) * F0 / (8.0 * F_NUMBER * F_NUMBER));
        w.spherical_m = self.spherical;
        w.coma_m = self.coma;
        w.astigmatism_m = self.astigmatism;
        w.shifted(self.shift * (LAMBDA0 / lambda - 1.0), 0.0)
    }
}

impl LensModel for SeidelLens {
    fn f_number(&self) -> f64 {
        F_NUMBER
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        vec![Order::new(0.15, Pupil::Full, self.wavefront(lambda))]
    }
}

/// `W(x, y)` on the unit pupil (the field along +x, `H = 1`; `fft::Aberrations` definitions).
fn opd(w: &Wavefront, x: f64, y: f64) -> f64 {
    let r2 = x * x + y * y;
    w.defocus_m * r2 + w.spherical_m * r2 * r2 + w.coma_m * r2 * x + w.astigmatism_m * x * x
}

/// The monochromatic OTF by brute force: `(1/π) ∬ exp(i k [W(p₋) − W(p₊)])` over the overlap of
/// the pupils centred at `∓s e` (the project's sign: a tilt `W = NA Δ·ρ` gives the image-shift
/// phase `exp(−2πi ν·Δ)`), a plain product Gauss–Legendre rule in the pupil's lag frame
/// (`points` in y over the overlap's height, `points` in x over its width at each y), no
/// substitution, no analytic part.
fn brute_force(w: &Wavefront, lambda: f64, s: f64, phi: f64, rule: &[(f64, f64)]) -> Complex64 {
    let k = 2.0 * PI / lambda;
    let (sn, c) = phi.sin_cos();
    let height = (1.0 - s * s).sqrt();
    let mut sum = Complex64::new(0.0, 0.0);
    for &(v, wy) in rule {
        let y = height * v;
        let half = (1.0 - y * y).sqrt() - s;
        for &(u, wx) in rule {
            let x = half * u;
            let (xp, xm) = (x + s, x - s);
            let phase = k * (opd(w, xm * c - y * sn, xm * sn + y * c) - opd(w, xp * c - y * sn, xp * sn + y * c));
            sum += Complex64::from_polar(wy * wx * half * height, phase);
        }
    }
    sum / PI
}

/// The polychromatic OTF by brute force: 40 Gauss–Hermite wavelengths of the Gaussian spectrum,
/// each [`brute_force`], with its lateral-colour phase `exp(−2πi ν·Δ)`.
fn brute_force_poly(lens: &SeidelLens, sigma: f64, nu: f64, phi: f64, rule: &[(f64, f64)]) -> Complex64 {
    let hermite = optics::quad::gauss_hermite(40);
    let mut sum = Complex64::new(0.0, 0.0);
    let mut total = 0.0;
    for &(x, weight) in &hermite {
        let lambda = LAMBDA0 + 2f64.sqrt() * sigma * x;
        let w = lens.wavefront(lambda);
        let s = nu * lambda * F_NUMBER;
        let otf = if s < 1.0 { brute_force(&w, lambda, s, phi, rule) } else { Complex64::new(0.0, 0.0) };
        let tilt = -2.0 * PI * nu * (w.image_shift_m[0] * phi.cos() + w.image_shift_m[1] * phi.sin());
        sum += otf * Complex64::from_polar(weight, tilt);
        total += weight;
    }
    sum / total
}

fn band(range: f64) -> Spectrum {
    Spectrum::Gaussian(Gaussian::from_range(LAMBDA0, range, 1.0).unwrap())
}

/// The engine's complex OTF along azimuths and at frequencies up to Nyquist (5.2 µm pixels) for
/// coma, astigmatism and spherical aberration with lateral colour, against [`brute_force_poly`]
/// (300 × 300 points; the plain rule converges slowly at the overlap's square-root edge): within
/// 1e-6 (measured: 2.7e-9 at worst).
#[test]
fn overlap_matches_a_brute_force_sum_over_the_overlap() {
    let rule = optics::quad::gauss_legendre(300);
    let range = 10e-9;
    let sigma = range / (2.0 * 2f64.sqrt());
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let lenses = [
        SeidelLens { spherical: 0.0, coma: 0.5e-6, astigmatism: 0.0, shift: 0.0 },
        SeidelLens { spherical: 0.2e-6, coma: -0.3e-6, astigmatism: 0.25e-6, shift: 20e-6 },
    ];
    let settings = Settings { tolerance: 1e-8, fft_tolerance: None, ..Settings::default() };
    let mut worst = 0.0_f64;
    for lens in &lenses {
        let detected = band(range);
        let poly =
            optics::Polychromatic::with_settings(lens, &detected, Field::ON_AXIS, nyquist, None, settings).unwrap();
        assert!(matches!(poly.engine(), Engine::Overlap { .. }), "{:?}", poly.engine());
        for &nu in &[0.2 * nyquist, 0.6 * nyquist, nyquist] {
            for &phi in &[0.0, 0.5, PI / 2.0, 2.3] {
                let engine = poly.otf_along(nu, phi);
                let reference = brute_force_poly(lens, sigma, nu, phi, &rule);
                let error = (engine - reference).norm();
                worst = worst.max(error);
                assert!(error < 1e-6, "ν = {nu}, φ = {phi}: {engine} vs {reference}");
            }
        }
    }
    eprintln!("overlap against the brute-force sum: worst {worst:.1e}");
}

/// The mean MTF over azimuth by the overlap quadrature and by the FFT path (its sampling chosen
/// for 1e-4, Richardson-extrapolated) on 0.5 µm of coma with a 20 nm band, on axis and with the
/// lateral colour of a 5° field along the coma's axis (where the OTF's sign shows: the coma's
/// phase and the image shift's add): within the FFT path's tolerance.
#[test]
fn overlap_matches_the_fft_path() {
    for shift in [0.0, F0 * 5f64.to_radians().tan()] {
        overlap_matches_the_fft_path_with(SeidelLens { spherical: 0.0, coma: 0.5e-6, astigmatism: 0.0, shift });
    }
}

fn overlap_matches_the_fft_path_with(lens: SeidelLens) {
    let detected = band(20e-9);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let mean = |overlap: bool| {
        let settings = Settings { tolerance: 1e-4, fft_tolerance: Some(1e-4), overlap, ..Settings::default() };
        let poly =
            optics::Polychromatic::with_settings(&lens, &detected, Field::ON_AXIS, nyquist, None, settings).unwrap();
        assert_eq!(matches!(poly.engine(), Engine::Overlap { .. }), overlap, "{:?}", poly.engine());
        poly.mean_mtf_over_azimuth(0.0, None).mean
    };
    let (quadrature, fft) = (mean(true), mean(false));
    let rel = (quadrature - fft).abs() / fft;
    eprintln!("overlap {quadrature:.8}, fft {fft:.8}: {rel:.1e}");
    assert!(rel < 1e-4, "overlap {quadrature} vs fft {fft}");
}

/// The chromatic metalens of [`SeidelLens`] carrying Zernike terms `(Noll index, metres RMS)` on
/// every order (as `lens.zernike_noll_rms_um` puts them: a radial pupil with the terms alone,
/// `Order::radial`), with coma and a lateral colour along x for a field point off axis.
#[derive(Debug)]
struct ZernikeLens {
    seidel: SeidelLens,
    zernike: Vec<(usize, f64)>,
    pupil: std::sync::Arc<optics::radial::RadialPupil>,
}

impl ZernikeLens {
    fn new(seidel: SeidelLens, zernike: Vec<(usize, f64)>) -> ZernikeLens {
        let pupil = std::sync::Arc::new(optics::radial::RadialPupil::new(None, vec![], zernike.clone()).unwrap());
        ZernikeLens { seidel, zernike, pupil }
    }
}

impl LensModel for ZernikeLens {
    fn f_number(&self) -> f64 {
        F_NUMBER
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        vec![Order::radial(0.15, self.pupil.clone(), self.seidel.wavefront(lambda))]
    }
}

/// `Σ c_j Z_j(x, y)` from Noll's Table I written out (Noll 1976; `Z5 = √6 ρ² sin 2θ`,
/// `Z6 = √6 ρ² cos 2θ`, `Z7 = √8 (3ρ³ − 2ρ) sin θ`, `Z8 = √8 (3ρ³ − 2ρ) cos θ`,
/// `Z11 = √5 (6ρ⁴ − 6ρ² + 1)`, `Z22 = √7 (20ρ⁶ − 30ρ⁴ + 12ρ² − 1)`), independent of the
/// engine's own evaluation.
fn zernike_opd(terms: &[(usize, f64)], x: f64, y: f64) -> f64 {
    let r2 = x * x + y * y;
    terms
        .iter()
        .map(|&(j, c)| {
            c * match j {
                5 => 6f64.sqrt() * 2.0 * x * y,
                6 => 6f64.sqrt() * (x * x - y * y),
                7 => 8f64.sqrt() * (3.0 * r2 - 2.0) * y,
                8 => 8f64.sqrt() * (3.0 * r2 - 2.0) * x,
                11 => 5f64.sqrt() * (6.0 * r2 * r2 - 6.0 * r2 + 1.0),
                22 => 7f64.sqrt() * (20.0 * r2 * r2 * r2 - 30.0 * r2 * r2 + 12.0 * r2 - 1.0),
                _ => panic!("Noll {j} is not written out here"),
            }
        })
        .sum()
}

/// [`brute_force_poly`] for a [`ZernikeLens`]: the Seidel wavefront plus [`zernike_opd`].
fn brute_force_zernike(lens: &ZernikeLens, sigma: f64, nu: f64, phi: f64, rule: &[(f64, f64)]) -> Complex64 {
    let hermite = optics::quad::gauss_hermite(40);
    let (sn, c) = phi.sin_cos();
    let mut sum = Complex64::new(0.0, 0.0);
    let mut total = 0.0;
    for &(h, weight) in &hermite {
        let lambda = LAMBDA0 + 2f64.sqrt() * sigma * h;
        let w = lens.seidel.wavefront(lambda);
        let s = nu * lambda * F_NUMBER;
        total += weight;
        if s >= 1.0 {
            continue;
        }
        let k = 2.0 * PI / lambda;
        let opd_all = |x: f64, y: f64| opd(&w, x, y) + zernike_opd(&lens.zernike, x, y);
        let height = (1.0 - s * s).sqrt();
        let mut otf = Complex64::new(0.0, 0.0);
        for &(v, wy) in rule {
            let y = height * v;
            let half = (1.0 - y * y).sqrt() - s;
            for &(u, wx) in rule {
                let x = half * u;
                let (xp, xm) = (x + s, x - s);
                let phase = k * (opd_all(xm * c - y * sn, xm * sn + y * c) - opd_all(xp * c - y * sn, xp * sn + y * c));
                otf += Complex64::from_polar(wy * wx * half * height, phase);
            }
        }
        let tilt = -2.0 * PI * nu * (w.image_shift_m[0] * c + w.image_shift_m[1] * sn);
        sum += otf / PI * Complex64::from_polar(weight, tilt);
    }
    sum / total
}

/// The lenses the Zernike tests take: Z5, Z7 (coma along y), Z8 (coma along x), and Z11 with Z5
/// and Z22 beside the coma and lateral colour of a field point off axis.
fn zernike_lenses() -> Vec<ZernikeLens> {
    let none = || SeidelLens { spherical: 0.0, coma: 0.0, astigmatism: 0.0, shift: 0.0 };
    vec![
        ZernikeLens::new(none(), vec![(5, 0.08e-6)]),
        ZernikeLens::new(none(), vec![(7, 0.06e-6)]),
        ZernikeLens::new(none(), vec![(8, -0.06e-6)]),
        ZernikeLens::new(
            SeidelLens { spherical: 0.0, coma: 0.2e-6, astigmatism: 0.0, shift: F0 * 3f64.to_radians().tan() },
            vec![(5, 0.05e-6), (11, 0.04e-6), (22, 0.01e-6)],
        ),
    ]
}

/// Zernike terms with `m ≠ 0` (and `m = 0` beside them) on the overlap engine (docs/physics.md,
/// "Zernike terms on the overlap engine"): the complex OTF along azimuths up to Nyquist against
/// [`brute_force_zernike`] (200 × 200 points), within 1e-6.
#[test]
fn zernike_overlap_matches_a_brute_force_sum_over_the_overlap() {
    let rule = optics::quad::gauss_legendre(200);
    let range = 10e-9;
    let sigma = range / (2.0 * 2f64.sqrt());
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let settings = Settings { tolerance: 1e-8, fft_tolerance: None, ..Settings::default() };
    let mut worst = 0.0_f64;
    for lens in &zernike_lenses() {
        let detected = band(range);
        let poly =
            optics::Polychromatic::with_settings(lens, &detected, Field::ON_AXIS, nyquist, None, settings).unwrap();
        assert!(matches!(poly.engine(), Engine::Overlap { .. }), "{:?}", poly.engine());
        for &nu in &[0.3 * nyquist, nyquist] {
            for &phi in &[0.0, 0.7, 2.3] {
                let engine = poly.otf_along(nu, phi);
                let reference = brute_force_zernike(lens, sigma, nu, phi, &rule);
                let error = (engine - reference).norm();
                worst = worst.max(error);
                assert!(error < 1e-6, "{:?}, ν = {nu}, φ = {phi}: {engine} vs {reference}", lens.zernike);
            }
        }
    }
    eprintln!("Zernike overlap against the brute-force sum: worst {worst:.1e}");
}

/// The mean MTF over azimuth of the Zernike lenses by the overlap engine and by the FFT path (its
/// sampling chosen for 1e-4, Richardson-extrapolated), 20 nm band: within the FFT path's 1e-4.
#[test]
fn zernike_overlap_matches_the_fft_path() {
    let detected = band(20e-9);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    for lens in &zernike_lenses() {
        let mean = |overlap: bool| {
            let settings = Settings { tolerance: 1e-4, fft_tolerance: Some(1e-4), overlap, ..Settings::default() };
            let poly =
                optics::Polychromatic::with_settings(lens, &detected, Field::ON_AXIS, nyquist, None, settings).unwrap();
            assert_eq!(matches!(poly.engine(), Engine::Overlap { .. }), overlap, "{:?}", poly.engine());
            poly.mean_mtf_over_azimuth(0.0, None).mean
        };
        let (quadrature, fft) = (mean(true), mean(false));
        let rel = (quadrature - fft).abs() / fft;
        eprintln!("{:?}: overlap {quadrature:.8}, fft {fft:.8}: {rel:.1e}", lens.zernike);
        assert!(rel < 1e-4, "{:?}: overlap {quadrature} vs fft {fft}", lens.zernike);
    }
}

/// [`SeidelLens`] with its chromatic defocus scaled by `scale` (the `K = f0/(8F#²)` of the
/// F-number's defocus lane), the Seidel terms as they are.
#[derive(Debug)]
struct ScaledDefocus {
    lens: SeidelLens,
    scale: f64,
}

impl LensModel for ScaledDefocus {
    fn f_number(&self) -> f64 {
        F_NUMBER
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        let mut w = self.lens.wavefront(lambda);
        w.defocus_m *= self.scale;
        vec![Order::new(0.15, Pupil::Full, w)]
    }
}

/// `Settings::overlap_always`: a defocus alone (every Seidel term zero) on the overlap engine
/// gives the mean MTF of the exact 1-D path (the per-frequency product rule) within the
/// tolerance 1e-8 (docs/physics.md, "Gradients: Seidel terms at zero"), and without the setting
/// the scene stays on its own engine.
#[test]
fn overlap_always_takes_a_defocus_alone_to_the_same_mean() {
    let lens = SeidelLens { spherical: 0.0, coma: 0.0, astigmatism: 0.0, shift: 0.0 };
    let detected = band(20e-9);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let mean = |overlap_always: bool| {
        let settings = Settings { tolerance: 1e-8, fft_tolerance: None, overlap_always, ..Settings::default() };
        let poly =
            optics::Polychromatic::with_settings(&lens, &detected, Field::ON_AXIS, nyquist, None, settings).unwrap();
        assert_eq!(matches!(poly.engine(), Engine::Overlap { .. }), overlap_always, "{:?}", poly.engine());
        poly.mean_mtf_along(0.0).0
    };
    let (overlap, exact) = (mean(true), mean(false));
    let rel = (overlap - exact).abs() / exact;
    eprintln!("a defocus alone: overlap {overlap:.12}, exact 1-D {exact:.12}: {rel:.1e}");
    assert!(rel < 3e-8, "overlap {overlap} vs exact {exact}");
}

/// The defocus lane `D_K = ∂M̄/∂ln K` on the overlap engine
/// (`Polychromatic::mean_mtf_over_azimuth_and_defocus_lane`, forward mode along `W020 ρ²` on
/// each node) against central differences in `K` of the mean over azimuth converged to 1e-10
/// (the chromatic defocus scaled by `1 ± h`, h = 1e-4: the band's edge is under a wave of
/// defocus here, so the truncation h² |f‴|/6 is far below the tolerance; measured 1.5e-8 of
/// the mean, and P_ν 7e-10), with coma and spherical aberration and with the pixel MTF (its `P_ν` against the
/// same term written here on a Gauss–Legendre rule over the MTF averaged over azimuth): within
/// 10× the tolerance 1e-7 of the mean.
#[test]
fn overlap_defocus_lane_matches_central_differences() {
    let detected = band(10e-9);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let pitch = 5.2e-6;
    let seidel = || SeidelLens { spherical: 0.2e-6, coma: 0.3e-6, astigmatism: 0.0, shift: 0.0 };
    let poly_at = |scale: f64, tolerance: f64| {
        let lens = ScaledDefocus { lens: seidel(), scale };
        let settings = Settings { tolerance, fft_tolerance: None, ..Settings::default() };
        let lens: &'static ScaledDefocus = Box::leak(Box::new(lens));
        let detected: &'static Spectrum = Box::leak(Box::new(detected.clone()));
        optics::Polychromatic::with_settings(lens, detected, Field::ON_AXIS, nyquist, Some(pitch), settings).unwrap()
    };
    let poly = poly_at(1.0, 1e-7);
    let found = poly.mean_mtf_over_azimuth_and_defocus_lane(0.0).unwrap();
    let h = 1e-4;
    let mean = |scale: f64| poly_at(scale, 1e-10).mean_mtf_over_azimuth(0.0, None).mean;
    let theirs = (mean(1.0 + h) - mean(1.0 - h)) / (2.0 * h);
    eprintln!("D_K {:.10e} vs differences {theirs:.10e}; mean {:.10}", found.defocus, found.mean);
    assert!((found.defocus - theirs).abs() <= 1e-6 * found.mean, "{found:?} vs {theirs}");
    // P_ν = (1/ν_N) ∫ ν P′(ν) M(ν) dν, M the MTF over azimuth without the pixel (M P is the
    // engine's), P = sin x/x, x = πpν
    let reference = poly_at(1.0, 1e-10);
    let pixel = |nu: f64| {
        let x = PI * pitch * nu;
        if x == 0.0 { 1.0 } else { x.sin() / x }
    };
    let slope = |nu: f64| {
        let x = PI * pitch * nu;
        if x == 0.0 { 0.0 } else { (x * x.cos() - x.sin()) / x }
    };
    let rule = optics::quad::gauss_legendre(64);
    let mut p_nu = 0.0;
    for &(u, w) in &rule {
        let nu = 0.5 * nyquist * (1.0 + u);
        p_nu += 0.5 * w * slope(nu) * reference.mtf_over_azimuth(nu, 0.0) / pixel(nu);
    }
    eprintln!("P_ν {:.10e} vs {p_nu:.10e}", found.pixel_slope);
    assert!((found.pixel_slope - p_nu).abs() <= 1e-6 * found.mean, "{} vs {p_nu}", found.pixel_slope);
}

/// A coma of 1e-4 µm and 1e-6 µm on the paper's lens (50 nm band) on the overlap engine: the t
/// rule's integrand is continuous in the quadratic phase α (docs/physics.md, "Analytic 2-D pupils
/// by quadrature over the overlap"), so the evaluation stays within its budget (it was refused
/// with an error estimate of 1.3–1.8 where α X² crossed 1e-9 across the rule's nodes) and its mean
/// over azimuth is the defocus alone's on the exact 1-D path: the coma's phase k W131 is at most
/// 7.9e-4 rad, which moves the mean by its square's order, 6e-7 of it at 1e-4 µm.
#[test]
fn overlap_takes_a_tiny_coma() {
    let detected = band(50e-9);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let settings = Settings { tolerance: 1e-8, fft_tolerance: None, ..Settings::default() };
    let plain = SeidelLens { spherical: 0.0, coma: 0.0, astigmatism: 0.0, shift: 0.0 };
    let exact = optics::Polychromatic::with_settings(&plain, &detected, Field::ON_AXIS, nyquist, None, settings)
        .unwrap()
        .mean_mtf_along(0.0)
        .0;
    for (coma, within) in [(1e-10, 2e-6), (1e-12, 1e-8)] {
        let lens = SeidelLens { spherical: 0.0, coma, astigmatism: 0.0, shift: 0.0 };
        let poly =
            optics::Polychromatic::with_settings(&lens, &detected, Field::ON_AXIS, nyquist, None, settings).unwrap();
        assert!(matches!(poly.engine(), Engine::Overlap { .. }), "{:?}", poly.engine());
        let mean = poly.mean_mtf_over_azimuth(0.0, None).mean;
        assert_eq!(poly.over_budget(), None, "coma {coma} m");
        let rel = (mean - exact).abs() / exact;
        eprintln!("coma {coma} m: {mean:.12} against the defocus alone's {exact:.12}: {rel:.1e}");
        assert!(rel < within, "coma {coma} m: {mean} vs {exact} ({rel:.1e})");
    }
}

/// The spectral moments' lanes (`WavefrontDirection::SpectralMoment`: each node's value times
/// `u = λ − λ̄` and `u² − ⟨u²⟩`) give a Gaussian band's derivatives `∂M̄/∂c = L₁/σ²` and
/// `∂M̄/∂σ = (L₂ + 2 (λ̄ − c) L₁)/σ³` (docs/physics.md, "Gradients: the spectrum where the OTF
/// depends on direction"), against central differences in `c` and `σ` of the means converged to
/// 1e-10 (Richardson from the steps 0.04 σ and 0.02 σ, truncation O(h⁴)) on a 10 nm band: on the
/// overlap engine (coma and spherical aberration with lateral colour, the mean over azimuth) and
/// on the exact 1-D engine (lateral colour alone, the tangential and sagittal means), within 10×
/// the tolerance 1e-7 of the mean per unit of σ.
#[test]
fn spectral_moment_lanes_match_central_differences() {
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let range = 10e-9;
    let sigma = range / (2.0 * 2f64.sqrt());
    let lanes = [optics::WavefrontDirection::SpectralMoment(1), optics::WavefrontDirection::SpectralMoment(2)];
    for (lens, overlap) in [
        (SeidelLens { spherical: 0.1e-6, coma: 0.3e-6, astigmatism: 0.0, shift: 40e-6 }, true),
        (SeidelLens { spherical: 0.0, coma: 0.0, astigmatism: 0.0, shift: 40e-6 }, false),
    ] {
        let lens: &'static SeidelLens = Box::leak(Box::new(lens));
        let poly_at = |center: f64, sigma: f64, tolerance: f64| {
            let g = Gaussian::new(center, sigma, 1.0).unwrap();
            let detected: &'static Spectrum = Box::leak(Box::new(Spectrum::Gaussian(g)));
            let settings = Settings { tolerance, fft_tolerance: None, ..Settings::default() };
            optics::Polychromatic::with_settings(lens, detected, Field::ON_AXIS, nyquist, None, settings).unwrap()
        };
        let mean = |center: f64, sigma: f64| {
            let poly = poly_at(center, sigma, 1e-10);
            if overlap {
                poly.mean_mtf_over_azimuth(0.0, None).mean
            } else {
                0.5 * (poly.mean_mtf_along(0.0).0 + poly.mean_mtf_along(0.5 * PI).0)
            }
        };
        let poly = poly_at(LAMBDA0, sigma, 1e-7);
        assert_eq!(matches!(poly.engine(), Engine::Overlap { .. }), overlap, "{:?}", poly.engine());
        assert!(poly.direction_dependent());
        let (m, l) = if overlap {
            let (a, l) = poly.mean_mtf_over_azimuth_and_overlap_gradient(0.0, &lanes).unwrap();
            (a.mean, l)
        } else {
            let (t, _, lt) = poly.mean_mtf_along_and_gradient(0.0, &lanes).unwrap();
            let (s, _, ls) = poly.mean_mtf_along_and_gradient(0.5 * PI, &lanes).unwrap();
            (0.5 * (t + s), vec![0.5 * (lt[0] + ls[0]), 0.5 * (lt[1] + ls[1])])
        };
        let (mean_lambda, _) = poly.node_wavelength_moments();
        let d_c = l[0] / (sigma * sigma);
        let d_s = (l[1] + 2.0 * (mean_lambda - LAMBDA0) * l[0]) / sigma.powi(3);
        // Richardson from the steps 2h and h: truncation O(h⁴)
        let h = 0.02 * sigma;
        let central = |f: &dyn Fn(f64) -> f64| {
            let d = |h: f64| (f(h) - f(-h)) / (2.0 * h);
            (4.0 * d(h) - d(2.0 * h)) / 3.0
        };
        let ref_c = central(&|e| mean(LAMBDA0 + e, sigma));
        let ref_s = central(&|e| mean(LAMBDA0, sigma + e));
        eprintln!(
            "overlap {overlap}: M̄ {m:.10}, σ∂/∂c {:.6e} vs {:.6e}, σ∂/∂σ {:.6e} vs {:.6e}",
            sigma * d_c,
            sigma * ref_c,
            sigma * d_s,
            sigma * ref_s
        );
        assert!((d_c - ref_c).abs() * sigma <= 1e-6 * m, "∂/∂c {d_c} vs {ref_c}");
        assert!((d_s - ref_s).abs() * sigma <= 1e-6 * m, "∂/∂σ {d_s} vs {ref_s}");
    }
}
