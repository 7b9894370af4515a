//! NEQ, capacity and detectability against closed forms and brute-force 2-D references written
//! here: tensor Gauss–Legendre sums over the whole Nyquist square in Cartesian coordinates, which
//! share nothing with the library's octant and polar rule.

use std::f64::consts::{LN_2, PI};

use metric::{DiskTask, MetricsOptions, ObjectSpectrum, Quadrature, Symmetry, jinc, square_metrics};

use super::*;

/// `∫∫_{|x|,|y| ≤ ½} f(x, y)`: `panels²` cells of a 10 × 10 Gauss–Legendre rule (nodes from
/// `optics::quad::gauss_legendre`, an independent library rule).
fn brute_force(panels: usize, f: &dyn Fn(f64, f64) -> f64) -> f64 {
    let rule = optics::quad::gauss_legendre(10);
    let h = 1.0 / panels as f64;
    let nodes: Vec<(f64, f64)> = (0..panels)
        .flat_map(|p| {
            let mid = -0.5 + h * (p as f64 + 0.5);
            rule.iter().map(move |&(x, w)| (mid + 0.5 * h * x, 0.5 * h * w))
        })
        .collect();
    let mut total = 0.0;
    for &(x, wx) in &nodes {
        for &(y, wy) in &nodes {
            total += wx * wy * f(x, y);
        }
    }
    total
}

fn gaussian(s: f64) -> impl Fn(f64, f64) -> f64 {
    move |nu: f64, _| (-0.5 * nu * nu / (s * s)).exp()
}

/// A Gaussian MTF with white noise: the capacity against the brute-force 2-D sum of
/// `½ log₂(1 + SNR0² c² MTF²)` (converged to 1e-12 at 40² cells), within 1e-9 relative; the
/// same with the pixel MTF `|sinc νx sinc νy|` (octant symmetry) and with a direction-dependent
/// MTF (elliptical Gaussian, half-plane symmetry).
#[test]
fn capacity_of_a_gaussian_mtf_matches_brute_force() {
    let (snr0, c) = (150.0, 0.8);
    let options = MetricsOptions { contrast: c, ..MetricsOptions::default() };
    let log_term = |m: f64| 0.5 * (1.0 + snr0 * snr0 * c * c * m * m).log2();
    let sinc = |x: f64| if x == 0.0 { 1.0 } else { ((PI * x).sin() / (PI * x)).abs() };
    let s = 0.2;
    // radial
    let fast = square_metrics(
        &gaussian(s),
        None,
        snr0,
        5e-6,
        &options,
        Quadrature { symmetry: Symmetry::Radial, cutoff: f64::INFINITY, tolerance: 1e-12 },
    );
    let slow = brute_force(40, &|x, y| log_term((-0.5 * (x * x + y * y) / (s * s)).exp()));
    eprintln!("radial: capacity {:.12} bits, reference {slow:.12}", fast.capacity_bits_per_pixel);
    assert!((fast.capacity_bits_per_pixel - slow).abs() < 1e-9 * slow);
    assert!(fast.capacity_error_bits < 1e-9 * slow);
    // the pixel MTF in 2-D
    let with_pixel = |nu: f64, theta: f64| gaussian(s)(nu, theta) * sinc(nu * theta.cos()) * sinc(nu * theta.sin());
    let fast = square_metrics(
        &with_pixel,
        None,
        snr0,
        5e-6,
        &options,
        Quadrature { symmetry: Symmetry::Octant, cutoff: f64::INFINITY, tolerance: 1e-12 },
    );
    let slow = brute_force(40, &|x, y| log_term((-0.5 * (x * x + y * y) / (s * s)).exp() * sinc(x) * sinc(y)));
    eprintln!("octant: capacity {:.12} bits, reference {slow:.12}", fast.capacity_bits_per_pixel);
    assert!((fast.capacity_bits_per_pixel - slow).abs() < 1e-9 * slow);
    // an elliptical MTF (σ 0.2 along x, 0.1 along y, rotated by 0.3 rad)
    let rot = 0.3_f64;
    let ellipse = |x: f64, y: f64| {
        let (u, v) = (x * rot.cos() + y * rot.sin(), -x * rot.sin() + y * rot.cos());
        (-0.5 * (u * u / 0.04 + v * v / 0.01)).exp()
    };
    let polar = |nu: f64, theta: f64| ellipse(nu * theta.cos(), nu * theta.sin());
    let fast = square_metrics(
        &polar,
        None,
        snr0,
        5e-6,
        &options,
        Quadrature { symmetry: Symmetry::HalfPlane, cutoff: f64::INFINITY, tolerance: 1e-10 },
    );
    let slow = brute_force(40, &|x, y| log_term(ellipse(x, y)));
    eprintln!("half-plane: capacity {:.12} bits, reference {slow:.12}", fast.capacity_bits_per_pixel);
    assert!((fast.capacity_bits_per_pixel - slow).abs() < 1e-8 * slow);
}

/// A perfect lens (MTF = 1) with white noise: `C = ½ log₂(1 + SNR0² c²)` (Shannon), from the
/// quadrature as well as from the closed form the library takes for it; a power-law object of
/// the same variance has less capacity (Jensen: log is concave), and against the brute-force
/// sum (the singularity at 0 limits that to about 1e-5).
#[test]
fn perfect_lens_capacity_is_shannons() {
    let (snr0, c): (f64, f64) = (40.0, 1.0);
    let exact = 0.5 * (1.0 + snr0 * snr0 * c * c).ln() / LN_2;
    let flat = MetricsOptions::default();
    let one = |_: f64, _: f64| 1.0;
    let white = |_: f64| 1.0;
    let m = square_metrics(
        &one,
        Some(&white),
        snr0,
        5e-6,
        &flat,
        Quadrature { symmetry: Symmetry::Radial, cutoff: f64::INFINITY, tolerance: 1e-12 },
    );
    assert!((m.capacity_bits_per_pixel - exact).abs() < 1e-12 * exact, "{} vs {exact}", m.capacity_bits_per_pixel);
    assert!((m.capacity_perfect_lens_bits_per_pixel - exact).abs() < 1e-12 * exact);
    let beta = 1.0;
    let power = MetricsOptions { object: ObjectSpectrum::PowerLaw { beta }, ..MetricsOptions::default() };
    let p = square_metrics(
        &one,
        None,
        snr0,
        5e-6,
        &power,
        Quadrature { symmetry: Symmetry::Radial, cutoff: f64::INFINITY, tolerance: 1e-10 },
    );
    let scale = metric::power_law_mean(beta);
    let slow = brute_force(200, &|x, y| 0.5 * (1.0 + snr0 * snr0 * (x * x + y * y).sqrt().powf(-beta) / scale).log2());
    eprintln!("power law β = 1: {:.10} bits, brute force {slow:.10}, flat {exact:.10}", p.capacity_bits_per_pixel);
    assert!(p.capacity_bits_per_pixel < exact);
    assert!((p.capacity_bits_per_pixel - slow).abs() < 1e-5 * slow);
}

/// The disk's d′ with a Gaussian MTF against the brute-force 2-D sum of
/// `c² SNR0² (πR'² jinc(2πR'ν))² MTF²` (R' the radius in pixels); through a perfect lens, d′ → `c SNR0
/// √(πR'²)` times the square root of the disk's energy inside the square (Parseval; the
/// energy fraction against its own brute-force sum).
#[test]
fn disk_detectability_matches_brute_force() {
    let pitch = 5e-6;
    let (snr0, contrast) = (80.0, 0.05);
    for diameter_um in [3.0, 20.0, 60.0] {
        let task = DiskTask { diameter_m: diameter_um * 1e-6, contrast };
        let options = MetricsOptions { task: Some(task), ..MetricsOptions::default() };
        let s = 0.25;
        let fast = square_metrics(
            &gaussian(s),
            None,
            snr0,
            pitch,
            &options,
            Quadrature { symmetry: Symmetry::Radial, cutoff: f64::INFINITY, tolerance: 1e-10 },
        );
        let (d, d_perfect, energy) = fast.detectability.unwrap();
        let r = 0.5 * diameter_um * 1e-6 / pitch;
        let spectrum = |x: f64, y: f64| {
            let nu = (x * x + y * y).sqrt();
            let arg = 2.0 * PI * r * nu;
            let j = if arg == 0.0 { 1.0 } else { 2.0 * libm::j1(arg) / arg };
            PI * r * r * j
        };
        let slow = brute_force(60, &|x, y| {
            let m = (-0.5 * (x * x + y * y) / (s * s)).exp();
            (contrast * snr0 * spectrum(x, y) * m).powi(2)
        })
        .sqrt();
        let slow_energy = brute_force(60, &|x, y| spectrum(x, y).powi(2)) / (PI * r * r);
        eprintln!(
            "disk {diameter_um} µm: d′ {d:.10}, reference {slow:.10}; energy in band {energy:.8} ({slow_energy:.8})"
        );
        assert!((d - slow).abs() < 1e-8 * slow);
        assert!((energy - slow_energy).abs() < 1e-8);
        let matched = contrast * snr0 * (PI * r * r).sqrt() * energy.sqrt();
        assert!((d_perfect - matched).abs() < 1e-8 * matched, "{d_perfect} vs {matched}");
        assert!(d < d_perfect);
    }
    assert_eq!(jinc(0.0), 1.0);
}

/// `∫_{−½}^{½} e^{−κx²} dx = √(π/κ) erf(√κ/2)` (κ > 0).
fn gauss_line(kappa: f64) -> f64 {
    (PI / kappa).sqrt() * libm::erf(0.5 * kappa.sqrt())
}

/// `∫_{−½}^{½} e^{+κx²} dx = Σ_n (κ/4)ⁿ/((2n+1) n!)` (term by term; every term positive, so
/// summed to rounding).
fn gauss_line_growing(kappa: f64) -> f64 {
    let (mut term, mut sum) = (1.0, 0.0);
    for n in 0..2000 {
        let add = term / (2 * n + 1) as f64;
        sum += add;
        if add < 1e-18 * sum {
            break;
        }
        term *= 0.25 * kappa / (n + 1) as f64;
    }
    sum
}

/// The capacity `½ ∫∫_square log₂(1 + a e^{−bν²}) d²ν` in closed form (white noise, flat
/// object, `a = SNR0² c²`, a Gaussian MTF `e^{−bν²/2}` so that `MTF² = e^{−bν²}`), over the
/// Nyquist square `|νx|, |νy| ≤ ½` of area 1 (cycles per pixel), by the series of `ln(1 + x)`,
/// each term separable over the square:
/// - `a < 1` (so `x = a e^{−bν²} < 1` everywhere): `ln(1 + x) = Σ_k (−1)^{k+1} x^k/k`, and
///   `∫∫ e^{−kbν²} = (√(π/(kb)) erf(√(kb)/2))²`;
/// - `x ≥ 1` over the whole square (`a e^{−b/2} ≥ 1`, at the corner): `ln(1 + x) = ln x + ln(1 + 1/x)`,
///   `∫∫ ln x = ln a − b/6` (`∫∫ ν² = 1/6`) and `∫∫ x^{−k} = a^{−k} (∫_{−½}^{½} e^{+kbt²} dt)²`.
///
/// The series alternate with terms falling as `q^k/k`, `q = a` or `1/(a e^{−b/2})`: summed until
/// a term is below 1e-18.
fn capacity_closed_form(a: f64, b: f64) -> f64 {
    let mut sum = 0.0;
    if a < 1.0 {
        for k in 1..10_000 {
            let kb = k as f64 * b;
            let term = a.powi(k) / k as f64 * gauss_line(kb).powi(2);
            sum += if k % 2 == 1 { term } else { -term };
            if term < 1e-18 {
                break;
            }
        }
    } else {
        assert!(a * (-0.5 * b).exp() >= 1.0, "x ≥ 1 over the square");
        sum = a.ln() - b / 6.0;
        for k in 1..10_000 {
            let kb = k as f64 * b;
            let term = a.powi(-k) / k as f64 * gauss_line_growing(kb).powi(2);
            sum += if k % 2 == 1 { term } else { -term };
            if term < 1e-18 {
                break;
            }
        }
    }
    0.5 * sum / LN_2
}

/// The modified Bessel functions `e^{−z} I0(z)` and `e^{−z} I1(z)` by their power series
/// (`I_n(z) = Σ_m (z/2)^{2m+n}/(m! (m+n)!)`, every term positive), for the moderate `z` used here.
fn scaled_i0_i1(z: f64) -> (f64, f64) {
    let (mut t0, mut t1) = (1.0, 0.5 * z);
    let (mut i0, mut i1) = (0.0, 0.0);
    for m in 0..500 {
        i0 += t0;
        i1 += t1;
        if t0 < 1e-18 * i0 && t1 < 1e-18 * i1 {
            break;
        }
        let q = 0.25 * z * z;
        t0 *= q / ((m + 1) * (m + 1)) as f64;
        t1 *= q / ((m + 1) * (m + 2)) as f64;
    }
    ((-z).exp() * i0, (-z).exp() * i1)
}

/// Capacity against its closed form for a Gaussian MTF with white noise (the series in
/// `capacity_closed_form`): `a = SNR0² c² < 1` (SNR0 0.9, c 1; SNR0 1.2, c 0.5) through the erf
/// series, and `a ≥ 1` with `x = a e^{−bν²} ≥ 1` over the whole square (SNR0 20, b = 8: 7.3 at
/// the corner) through `ln x + ln(1 + 1/x)`; within 1e-11 relative. A Gaussian whose `x` crosses
/// 1 inside the square has no separable series (the crossing is a circle, the square's sides
/// are not): the brute-force test above covers that case. The quadrature's panels are doubled to
/// 1e-12; measured within 4e-16 (`cargo test -p asnr-metric --test metric closed_form -- --nocapture`),
/// asserted within 1e-11.
#[test]
fn capacity_of_a_gaussian_mtf_matches_its_closed_form() {
    for (snr0, contrast, b) in [(0.9_f64, 1.0_f64, 3.0_f64), (1.2, 0.5, 10.0), (20.0, 1.0, 8.0), (20.0, 0.8, 2.0)] {
        let options = MetricsOptions { contrast, ..MetricsOptions::default() };
        let mtf = |nu: f64, _: f64| (-0.5 * b * nu * nu).exp();
        let fast = square_metrics(
            &mtf,
            None,
            snr0,
            5e-6,
            &options,
            Quadrature { symmetry: Symmetry::Radial, cutoff: f64::INFINITY, tolerance: 1e-12 },
        );
        let exact = capacity_closed_form(snr0 * snr0 * contrast * contrast, b);
        let error = (fast.capacity_bits_per_pixel - exact).abs() / exact;
        eprintln!(
            "SNR0 {snr0}, c {contrast}, b {b}: capacity {:.14} bits, closed form {exact:.14}, relative error {error:.1e}",
            fast.capacity_bits_per_pixel
        );
        assert!(error < 1e-11, "{} vs {exact}", fast.capacity_bits_per_pixel);
    }
}

/// d′ of a disk (radius R' pixels, contrast c_t) with a Gaussian MTF `e^{−bν²/2}` and white
/// noise, against the closed form over the whole plane:
/// `d′² = c_t² SNR0² ∫∫ (πR'² 2J1(2πR'ν)/(2πR'ν))² e^{−bν²} d²ν = c_t² SNR0² 2πR'² ∫_0^∞ J1(αν)² e^{−bν²} dν/ν`
/// with `α = 2πR'`, and `∫_0^∞ J1(αν)² e^{−pν²} dν/ν = ½ [1 − e^{−z}(I0(z) + I1(z))]`,
/// `z = α²/(2p)` (its derivative in p is `−∫ J1² e^{−pν²} ν dν = −e^{−z} I1(z)/(2p)`, the
/// Weber–Schafheitlin/Hankel integral, Gradshteyn & Ryzhik 6.633.2; it is ½ at p → 0, the
/// Parseval value ∫ J1²/ν = ½, and 0 at p → ∞). The library integrates the Nyquist square
/// only: the MTF is narrow enough (b = 160, 200: MTF² = e^{−40}, e^{−50} at ν = ½) that what
/// lies beyond the square's inscribed circle, at most `e^{−b/4}` of the integrand's peak times
/// the plane's remaining weight, is below 1e-15 relative. Measured within 4e-15; asserted within
/// 1e-11 (the quadrature's panels doubled to 1e-12).
#[test]
fn disk_detectability_matches_its_closed_form() {
    let pitch = 2e-6;
    let snr0 = 30.0;
    for (diameter_um, contrast, b) in [(4.0_f64, 0.1_f64, 160.0_f64), (12.0, 0.02, 200.0), (1.0, 0.5, 160.0)] {
        let task = DiskTask { diameter_m: diameter_um * 1e-6, contrast };
        let options = MetricsOptions { task: Some(task), ..MetricsOptions::default() };
        let mtf = |nu: f64, _: f64| (-0.5 * b * nu * nu).exp();
        let fast = square_metrics(
            &mtf,
            None,
            snr0,
            pitch,
            &options,
            Quadrature { symmetry: Symmetry::Radial, cutoff: f64::INFINITY, tolerance: 1e-12 },
        );
        let (d, _, _) = fast.detectability.unwrap();
        let r = 0.5 * diameter_um * 1e-6 / pitch;
        let alpha = 2.0 * PI * r;
        let z = alpha * alpha / (2.0 * b);
        let (i0, i1) = scaled_i0_i1(z);
        let exact = (contrast * contrast * snr0 * snr0 * 2.0 * PI * r * r * 0.5 * (1.0 - (i0 + i1))).sqrt();
        let error = (d - exact).abs() / exact;
        eprintln!(
            "disk {diameter_um} µm, b {b} (z = {z:.3}): d′ {d:.14}, closed form {exact:.14}, relative error {error:.1e}"
        );
        assert!(error < 1e-11, "{d} vs {exact}");
    }
}

/// An aberration-free lens with efficiency 1.
#[derive(Debug)]
struct Ideal;

impl optics::LensModel for Ideal {
    fn f_number(&self) -> f64 {
        2.5
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, _: f64, _: optics::Field) -> Vec<optics::Order> {
        vec![optics::Order::new(1.0, optics::Pupil::Full, optics::Wavefront::default())]
    }
}

/// On a scene: the NEQ curve is `SNR0² MTF²` of the MTF curve (the same 1-D pixel MTF), its
/// zero `SNR0²`; the paper's lens has less capacity than its ideal lens of the same aperture,
/// whose ASNR ratio is below 1 and the product of the SNR0 and mean-MTF ratios; an ideal lens
/// scene is its own ideal lens (ratio 1).
#[test]
fn scene_metrics_are_consistent() {
    let scene = paper_with(paper_lens());
    let evaluation = evaluate(&scene).unwrap();
    let options = MetricsOptions { points: 11, ..MetricsOptions::default() };
    let m = metric::metrics(&scene, &evaluation, &options).unwrap();
    let curve = metric::mtf_curve(&scene, metric::FrequencyRange::Nyquist, 11, &[]).unwrap();
    let snr2 = evaluation.snr0 * evaluation.snr0;
    for (neq, mtf) in m.neq.neq.iter().zip(&curve.mtf) {
        assert!((neq - snr2 * mtf * mtf).abs() < 1e-9 * snr2, "{neq} vs {}", snr2 * mtf * mtf);
    }
    assert!((m.neq_zero - snr2).abs() < 1e-9 * snr2);
    assert!(m.capacity_bits_per_pixel < m.capacity_perfect_lens_bits_per_pixel);
    let ideal = &m.ideal_lens;
    assert!(ideal.ratio < 1.0 && ideal.ratio > 0.0);
    let product = evaluation.snr0 / ideal.snr0 * evaluation.mean_mtf / ideal.mean_mtf;
    assert!((ideal.ratio - product).abs() < 1e-9, "{} vs {product}", ideal.ratio);
    eprintln!(
        "paper scene: capacity {:.4} bits/pixel (perfect lens {:.4}), mean NEQ {:.1}, ideal-lens ASNR {:.2}, ratio {:.4}",
        m.capacity_bits_per_pixel, m.capacity_perfect_lens_bits_per_pixel, m.mean_neq, ideal.asnr, ideal.ratio
    );
    let ideal_scene = scene.with_lens(Arc::new(Ideal));
    let e = evaluate(&ideal_scene).unwrap();
    let m = metric::metrics(&ideal_scene, &e, &options).unwrap();
    assert!((m.ideal_lens.ratio - 1.0).abs() < 1e-12, "{}", m.ideal_lens.ratio);
}

/// Out-of-range options are refused with the value: β = 2, a zero contrast, a negative frame rate.
#[test]
fn metrics_options_out_of_range() {
    for options in [
        MetricsOptions { object: ObjectSpectrum::PowerLaw { beta: 2.0 }, ..MetricsOptions::default() },
        MetricsOptions { contrast: 0.0, ..MetricsOptions::default() },
        MetricsOptions { frame_rate_hz: Some(-1.0), ..MetricsOptions::default() },
        MetricsOptions { task: Some(DiskTask { diameter_m: f64::NAN, contrast: 0.1 }), ..MetricsOptions::default() },
    ] {
        let e = options.validate().unwrap_err().to_string();
        assert!(e.contains("out of range"), "{e}");
    }
}
