//! The e-SFR against edges of known MTF: the exact image of a Gaussian-blurred step integrated over
//! square pixels, whose MTF along the edge's normal is `exp(−2π²σ²f²) · sinc(f cos θ) · sinc(f sin θ)`
//! (the Gaussian's transfer times the square pixel's 2-D aperture along the normal's direction).

use std::f64::consts::PI;
use std::path::PathBuf;

use imaging::sfr::{Options, Response, Uncertainty};
use imaging::{Error, Frame, Region, sfr};
use rand::SeedableRng;
use rand_distr::Distribution;

/// Φ, the standard normal distribution function.
fn phi(t: f64) -> f64 {
    0.5 * libm::erfc(-t / 2f64.sqrt())
}

/// The second antiderivative of Φ: `H(t) = ((t² + 1)/2) Φ(t) + (t/2) φ(t)` (H'' = Φ).
fn h2(t: f64) -> f64 {
    let density = (-t * t / 2.0).exp() / (2.0 * PI).sqrt();
    (t * t + 1.0) / 2.0 * phi(t) + t / 2.0 * density
}

/// The exact mean of `Φ(n/σ)` over pixel (column `i`, row `j`: the square `[i − ½, i + ½] × [j − ½,
/// j + ½]`), `n = (x − x0) cos θ − (y − y0) sin θ` the distance from the edge through `(x0, y0)`
/// at `θ` off vertical: `∫∫ Φ((a x + c y − k)/σ) dx dy = σ²/(a c) Σ± H(corner)`.
fn pixel_fraction(i: usize, j: usize, x0: f64, y0: f64, theta: f64, sigma: f64) -> f64 {
    let (a, c) = (theta.cos(), -theta.sin());
    let k = a * x0 + c * y0;
    let u = |x: f64, y: f64| (a * x + c * y - k) / sigma;
    let (x_lo, x_hi, y_lo, y_hi) = (i as f64 - 0.5, i as f64 + 0.5, j as f64 - 0.5, j as f64 + 0.5);
    sigma * sigma / (a * c) * (h2(u(x_hi, y_hi)) - h2(u(x_lo, y_hi)) - h2(u(x_hi, y_lo)) + h2(u(x_lo, y_lo)))
}

/// A `size × size` frame of a dark-to-bright edge at `theta_deg` off vertical through the
/// centre, blurred by a Gaussian of `sigma` pixels, levels `dark` and `bright`.
fn edge_image(size: usize, theta_deg: f64, sigma: f64, dark: f64, bright: f64) -> Vec<f64> {
    let c = (size as f64 - 1.0) / 2.0 + 0.3;
    let theta = theta_deg.to_radians();
    (0..size * size).map(|p| dark + (bright - dark) * pixel_fraction(p % size, p / size, c, c, theta, sigma)).collect()
}

/// The true MTF along the normal at `f` cycles/pixel.
fn truth(f: f64, theta_deg: f64, sigma: f64) -> f64 {
    let sinc = |x: f64| if x == 0.0 { 1.0 } else { (PI * x).sin() / (PI * x) };
    let t = theta_deg.to_radians();
    (-2.0 * PI * PI * sigma * sigma * f * f).exp() * (sinc(f * t.cos()) * sinc(f * t.sin())).abs()
}

/// Its mean to Nyquist, by the trapezoidal rule on 20 000 intervals (error below 1e-9).
fn truth_mean(theta_deg: f64, sigma: f64) -> f64 {
    let n = 20_000;
    let h = 0.5 / n as f64;
    let s: f64 =
        (0..=n).map(|i| truth(i as f64 * h, theta_deg, sigma) * if i == 0 || i == n { 0.5 } else { 1.0 }).sum();
    s * h / 0.5
}

fn frame(data: Vec<f64>, size: usize, bit_depth: u8, name: &str) -> Frame {
    Frame { path: PathBuf::from(name), width: size, height: size, bit_depth, data }
}

/// A frame of Poisson counts about `image`.
fn poisson(image: &[f64], seed: u64) -> Vec<f64> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    image.iter().map(|&m| rand_distr::Poisson::new(m).unwrap().sample(&mut rng)).collect()
}

const SIZE: usize = 160;

#[test]
fn noiseless_edges_recover_the_mean_mtf_within_0_2_percent() {
    for &sigma in &[0.5, 0.8, 1.2] {
        for &angle in &[2.0, 3.5, 5.0, 7.0, 10.0, -6.0] {
            let image = edge_image(SIZE, angle, sigma, 0.2, 1.0);
            let result = sfr(&[frame(image, SIZE, 32, "edge.tif")], &[], &Options::default()).unwrap();
            assert_eq!(result.edges.len(), 1);
            let e = &result.edges[0];
            let expected = truth_mean(angle, sigma);
            let error = e.mean_mtf / expected - 1.0;
            println!(
                "σ {sigma} px, {angle:>5}°: angle {:.4}°, mean MTF {:.6} vs {expected:.6} ({:+.4} %), MTF(Nyquist) {:.5} vs {:.5}",
                e.edge_angle_deg,
                e.mean_mtf,
                100.0 * error,
                e.mtf_nyquist,
                truth(0.5, angle, sigma)
            );
            assert!((e.edge_angle_deg - angle).abs() < 0.02, "angle {} for {angle}", e.edge_angle_deg);
            assert!(error.abs() < 2e-3, "σ {sigma}, {angle}°: mean MTF {} vs {expected}", e.mean_mtf);
            for (f, m) in e.frequency_cyc_per_px.iter().zip(&e.mtf).take(51) {
                assert!((m - truth(*f, angle, sigma)).abs() < 5e-3, "σ {sigma}, {angle}°, f {f}: {m}");
            }
            assert_eq!(e.uncertainty, Uncertainty::EsfBins);
        }
    }
}

#[test]
fn horizontal_edges_and_cycles_per_mm() {
    // the transpose of a vertical edge: same MTF, frequencies in cycles/mm from the pitch
    let image = edge_image(SIZE, 4.0, 0.7, 0.25, 1.0);
    let transposed: Vec<f64> = (0..SIZE * SIZE).map(|p| image[(p % SIZE) * SIZE + p / SIZE]).collect();
    let options = Options { pixel_pitch_m: Some(2e-6), ..Options::default() };
    let e = &sfr(&[frame(transposed, SIZE, 32, "h.tif")], &[], &options).unwrap().edges[0];
    assert_eq!(e.orientation, imaging::sfr::Orientation::Horizontal);
    assert!((e.mean_mtf / truth_mean(4.0, 0.7) - 1.0).abs() < 2e-3);
    let mm = e.frequency_cyc_per_mm.as_ref().unwrap();
    assert!((mm[50] - 250.0).abs() < 1e-9, "Nyquist of a 2 µm pixel is 250 cycles/mm, not {}", mm[50]);
    let (px, mm50) = (e.mtf50_cyc_per_px.unwrap(), e.mtf50_cyc_per_mm.unwrap());
    assert!((mm50 - px * 500.0).abs() < 1e-9);
    // MTF50 against the truth located by bisection here
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let m = (lo + hi) / 2.0;
        if truth(m, 4.0, 0.7) >= 0.5 { lo = m } else { hi = m }
    }
    assert!((px - lo).abs() < 2e-3, "MTF50 {px} vs {lo}");
}

/// Edge SNR = (bright − dark)/√bright = 50 with a 4:1 contrast: bright 4444.4 e⁻, dark 1111.1.
fn noisy_levels() -> (f64, f64) {
    let bright = (50.0 / 0.75_f64).powi(2);
    (bright / 4.0, bright)
}

#[test]
fn poisson_edges_at_snr_50_within_1_percent_and_their_standard_errors_cover() {
    let (dark, bright) = noisy_levels();
    let sigma = 0.7;
    let mut z = Vec::new();
    for (seed, &angle) in [2.0, 3.0, 5.0, 7.5, 10.0].iter().cycle().take(20).enumerate() {
        let clean = edge_image(SIZE, angle, sigma, dark, bright);
        let image = poisson(&clean, seed as u64);
        let e = &sfr(&[frame(image, SIZE, 16, "noisy.png")], &[], &Options::default()).unwrap().edges[0];
        let expected = truth_mean(angle, sigma);
        let error = e.mean_mtf / expected - 1.0;
        z.push((e.mean_mtf - expected) / e.mean_mtf_sigma);
        println!(
            "seed {seed}, {angle}°: mean MTF {:.5} ± {:.5} vs {expected:.5} ({:+.3} %)",
            e.mean_mtf,
            e.mean_mtf_sigma,
            100.0 * error
        );
        assert!(error.abs() < 0.01, "{angle}°, seed {seed}: {:.3} %", 100.0 * error);
    }
    // the standard error describes the scatter: z-scores' rms near 1, 90 % within ±2
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    let inside = z.iter().filter(|v| v.abs() < 2.0).count();
    println!("z rms {rms:.3}, {inside}/{} within ±2", z.len());
    assert!((0.5..1.6).contains(&rms), "z rms {rms}");
    assert!(inside >= 17, "{inside} of 20 within 2 standard errors");
}

#[test]
fn a_stack_averages_and_its_spread_gives_the_standard_error() {
    let (dark, bright) = noisy_levels();
    let (sigma, angle) = (0.7, 5.0);
    let clean = edge_image(SIZE, angle, sigma, dark, bright);
    let expected = truth_mean(angle, sigma);
    let (mut z, mut stated, mut single) = (Vec::new(), 0.0, 0.0);
    for stack in 0..10_u64 {
        let frames: Vec<Frame> =
            (0..4).map(|i| frame(poisson(&clean, 100 + 4 * stack + i), SIZE, 16, "stack.png")).collect();
        let e = &sfr(&frames, &[], &Options::default()).unwrap().edges[0];
        assert_eq!(e.uncertainty, Uncertainty::Frames);
        z.push((e.mean_mtf - expected) / e.mean_mtf_sigma);
        stated += e.mean_mtf_sigma / 10.0;
        single += sfr(&frames[..1], &[], &Options::default()).unwrap().edges[0].mean_mtf_sigma / 10.0;
        assert!((e.mean_mtf / expected - 1.0).abs() < 0.01);
    }
    println!("4 frames: ± {stated:.5} (mean over 10 stacks); 1 frame: ± {single:.5}; z {z:.2?}");
    // four frames average the noise: the standard error halves (each stack's estimate, from
    // 4 frames, scatters like a t-distribution of 3 degrees of freedom: the mean of 10 is compared)
    assert!((0.35..0.75).contains(&(stated / single)), "{stated} vs {single}");
    let inside = z.iter().filter(|v| v.abs() < 3.0).count();
    assert!(inside >= 9, "{inside} of 10 stacks within 3 standard errors");
}

#[test]
fn dark_frames_and_gamma_are_undone() {
    let (angle, sigma) = (6.0, 0.8);
    let linear = edge_image(SIZE, angle, sigma, 0.2, 1.0);
    // a camera with a black offset of 500 DN and DN − dark = 40000 · exposure^0.45
    let g = 0.45;
    let encoded: Vec<f64> = linear.iter().map(|v| 500.0 + 40000.0 * v.powf(g)).collect();
    let dark = frame(vec![500.0; SIZE * SIZE], SIZE, 32, "dark.tif");
    let options = Options { response: Response::Gamma(g), ..Options::default() };
    let e =
        &sfr(&[frame(encoded.clone(), SIZE, 32, "gamma.tif")], std::slice::from_ref(&dark), &options).unwrap().edges[0];
    assert!((e.mean_mtf / truth_mean(angle, sigma) - 1.0).abs() < 2e-3, "{}", e.mean_mtf);
    // the same camera as a transfer table (exposures 0.05 … 1.2), interpolated linearly
    let exposure: Vec<f64> = (1..=240).map(|i| i as f64 * 0.005).collect();
    let dn: Vec<f64> = exposure.iter().map(|x| 40000.0 * x.powf(g)).collect();
    let options = Options { response: Response::Table { dn, exposure }, ..Options::default() };
    let t = &sfr(&[frame(encoded.clone(), SIZE, 32, "table.tif")], &[dark], &options).unwrap().edges[0];
    assert!((t.mean_mtf / truth_mean(angle, sigma) - 1.0).abs() < 3e-3, "{}", t.mean_mtf);
    // not linearized, the mean MTF is visibly wrong
    let raw = &sfr(&[frame(encoded, SIZE, 32, "raw.tif")], &[], &Options::default()).unwrap().edges[0];
    assert!((raw.mean_mtf / truth_mean(angle, sigma) - 1.0).abs() > 0.01);
}

#[test]
fn two_edges_are_reported_apart() {
    // a bright bar 60 pixels wide at 5°: a rising and a falling edge
    let (angle, sigma): (f64, f64) = (5.0, 0.8);
    let theta = angle.to_radians();
    let c = SIZE as f64 / 2.0;
    let image: Vec<f64> = (0..SIZE * SIZE)
        .map(|p| {
            let (i, j) = (p % SIZE, p / SIZE);
            0.2 + 0.8
                * (pixel_fraction(i, j, c - 30.0, c, theta, sigma) - pixel_fraction(i, j, c + 30.0, c, theta, sigma))
        })
        .collect();
    let result = sfr(&[frame(image, SIZE, 32, "bar.tif")], &[], &Options::default()).unwrap();
    assert_eq!(result.edges.len(), 2);
    assert!(result.edges[0].centre_px[0] < result.edges[1].centre_px[0]);
    for e in &result.edges {
        assert!((e.edge_angle_deg - angle).abs() < 0.05);
        // each edge's reach stops halfway to the other: a shorter LSF window, so 0.5 %
        assert!((e.mean_mtf / truth_mean(angle, sigma) - 1.0).abs() < 5e-3, "{}", e.mean_mtf);
    }
    assert!(result.single().is_err_and(|e| e.to_string().contains("2 edges")));
}

fn message(result: Result<imaging::Sfr, Error>) -> String {
    match result {
        Ok(r) => panic!("accepted: {} edges", r.edges.len()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_input_is_refused_with_the_reason() {
    let o = Options::default();
    // no edge: a flat noisy frame
    let flat = poisson(&vec![1000.0; SIZE * SIZE], 3);
    let m = message(sfr(&[frame(flat, SIZE, 16, "flat.png")], &[], &o));
    assert!(m.contains("flat.png") && m.contains("no edge"), "{m}");
    // 0° and 45°
    for (angle, word) in [(0.001, "0.00°"), (0.4, "0.40°"), (45.0, "45.00°"), (40.0, "40.00°")] {
        let m = message(sfr(&[frame(edge_image(SIZE, angle, 0.8, 0.2, 1.0), SIZE, 32, "a.tif")], &[], &o));
        assert!(m.contains(word) && m.contains("ISO 12233"), "{angle}°: {m}");
    }
    // saturated: the bright side at 65535
    let clipped: Vec<f64> = edge_image(SIZE, 5.0, 0.8, 10000.0, 80000.0).iter().map(|v| v.min(65535.0)).collect();
    let m = message(sfr(&[frame(clipped, SIZE, 16, "sat.png")], &[], &o));
    assert!(m.contains("saturated") && m.contains("sat.png") && m.contains('%'), "{m}");
    // sizes and bit depths
    let a = frame(edge_image(SIZE, 5.0, 0.8, 100.0, 1000.0), SIZE, 16, "a.png");
    let mut b = a.clone();
    b.path = PathBuf::from("b.png");
    b.bit_depth = 8;
    assert!(matches!(sfr(&[a.clone(), b], &[], &o), Err(Error::DepthMismatch { .. })));
    let small = Frame { path: PathBuf::from("c.png"), width: 10, height: 10, bit_depth: 16, data: vec![0.0; 100] };
    assert!(matches!(sfr(&[a.clone(), small.clone()], &[], &o), Err(Error::SizeMismatch { .. })));
    assert!(matches!(sfr(std::slice::from_ref(&a), &[small], &o), Err(Error::SizeMismatch { .. })));
    // a ROI outside
    let roi = Options { roi: Some(Region { x: 100, y: 0, width: 100, height: 50 }), ..Options::default() };
    let m = message(sfr(std::slice::from_ref(&a), &[], &roi));
    assert!(m.contains("ROI") && m.contains("outside"), "{m}");
    // a bad gamma
    let g = Options { response: Response::Gamma(-1.0), ..Options::default() };
    assert!(message(sfr(&[a], &[], &g)).contains("gamma -1"));
}

#[test]
fn a_png_header_of_a_million_squared_pixels_is_refused_before_decoding() {
    let dir = std::env::temp_dir().join(format!("asnr-sfr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.png");
    // signature, IHDR length 13, "IHDR", width and height 10⁶, 16-bit grey, then nothing
    let mut bytes = b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR".to_vec();
    bytes.extend(1_000_000_u32.to_be_bytes());
    bytes.extend(1_000_000_u32.to_be_bytes());
    bytes.extend([16, 0, 0, 0, 0, 0, 0, 0, 0]);
    std::fs::write(&path, bytes).unwrap();
    let e = imaging::frames::read_frames("edge frames", std::slice::from_ref(&path), 1).unwrap_err();
    assert!(matches!(e, Error::TooLarge { width: 1_000_000, height: 1_000_000, .. }), "{e}");
    assert!(e.to_string().contains("huge.png"));
    std::fs::remove_dir_all(dir).unwrap();
}

/// A slanted edge rendered through the paper's scene with the pixel aperture
/// (`camera.pixel_mtf = true`, the pixels integrated): the e-SFR of the noise-free image against
/// the scene's own MTF (metric::mtf_at, the optics times `sinc(p ν)`) times `sinc(f sin θ)`, the
/// part of the square pixel's 2-D aperture along the edge normal that the scene's 1-D pixel MTF
/// leaves out. The fine grid's cells and the sum over a pixel's cells together make the pixel's
/// `sinc(f)` exactly (docs/physics.md), so the rendering's sampling adds no error of its own.
/// What remains is the LSF window cutting the defocused lens's long PSF tails: measured +0.44 %
/// on the mean MTF at the default ±16 px, +0.21 % at ±48 px, +0.17 % at ±96 px (used here,
/// 224 × 224 pixels); 0.3 % allowed, and 0.002 at each frequency to Nyquist (measured 0.001).
#[test]
fn a_rendered_edge_recovers_the_scenes_mtf() {
    let scene = scene::load(None, &["camera.pixel_mtf=true".to_owned(), "spectrum.range_nm=50".to_owned()]).unwrap();
    let evaluation = metric::evaluate(&scene).unwrap();
    let angle: f64 = 5.0;
    let target = imaging::target::slanted_edge(224, angle, 0.6, 5).unwrap();
    let settings = imaging::render::Settings { seed: 1, frames: 1, glare: false, subtract_black: false };
    let r = imaging::render(&scene, &evaluation, &target, &settings).unwrap();
    let image = Frame { path: "rendered".into(), width: r.width, height: r.height, bit_depth: 32, data: r.expected_e };
    let e = &sfr(&[image], &[], &Options { reach_px: Some(96.0), ..Options::default() }).unwrap().edges[0];
    assert!((e.edge_angle_deg - angle).abs() < 0.01, "{}", e.edge_angle_deg);
    let pitch_mm = scene.camera().pixel_pitch() * 1e3;
    let per_mm: Vec<f64> = e.frequency_cyc_per_px.iter().map(|f| f / pitch_mm).collect();
    let curve = metric::mtf_at(&scene, &per_mm, &[]).unwrap();
    let sinc = |x: f64| if x == 0.0 { 1.0 } else { (PI * x).sin() / (PI * x) };
    let s = angle.to_radians().sin();
    let expected: Vec<f64> =
        curve.mtf.iter().zip(&e.frequency_cyc_per_px).map(|(m, f)| m * sinc(f * s).abs()).collect();
    let worst = e.mtf.iter().zip(&expected).take(51).map(|(m, x)| (m - x).abs()).fold(0.0, f64::max);
    let mean_expected = {
        let s: f64 = (0..=50)
            .map(|j| {
                expected[j]
                    * if j == 0 || j == 50 {
                        1.0
                    } else if j % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    }
            })
            .sum();
        2.0 * s * 0.01 / 3.0
    };
    println!(
        "rendered edge: mean MTF {:.5} vs the scene's {:.5} (evaluate: {:.5}); largest difference to Nyquist {worst:.5}",
        e.mean_mtf, mean_expected, evaluation.mean_mtf
    );
    assert!((e.mean_mtf / mean_expected - 1.0).abs() < 3e-3);
    assert!(worst < 2e-3);
}

/// The measured ASNR (SNR of the white and black regions × the edge's mean MTF) of rendered
/// frames, Poisson noise and the scene's sensor, recovers the scene's ASNR (pixel aperture on,
/// no glare) within its stated standard error: 100 seeds of 4 frames of a 96 × 96 edge of
/// contrast 1; the fraction within 1.96 σ is near 95 % (measured: printed).
#[test]
fn the_measured_asnr_of_rendered_frames_covers_the_scenes() {
    let scene = scene::load(None, &["camera.pixel_mtf=true".to_owned(), "spectrum.range_nm=50".to_owned()]).unwrap();
    let evaluation = metric::evaluate(&scene).unwrap();
    let target = imaging::target::slanted_edge(96, 5.0, 1.0, 3).unwrap();
    let settings = imaging::render::Settings { seed: 1, frames: 1, glare: false, subtract_black: false };
    let r = imaging::render(&scene, &evaluation, &target, &settings).unwrap();
    let (white, black) = (target.white.unwrap(), target.black.unwrap());
    let sensor = scene.camera().sensor();
    let mut z = Vec::new();
    for seed in 0..100_u64 {
        let frames: Vec<Frame> = (0..4)
            .map(|i| Frame {
                path: format!("seed-{seed}-{i}").into(),
                width: r.width,
                height: r.height,
                bit_depth: 16,
                data: imaging::render::expose(&r.expected_e, sensor, 1000 * seed + i).unwrap(),
            })
            .collect();
        let m = imaging::measure(&frames, white, black, None, false).unwrap();
        let result = sfr(&frames, &[], &Options::default()).unwrap();
        let e = result.single().unwrap();
        let a = imaging::MeasuredAsnr::new(m.snr, m.snr_sigma, e.mean_mtf, e.mean_mtf_sigma);
        z.push((a.asnr - evaluation.asnr) / a.asnr_sigma);
    }
    let inside = z.iter().filter(|v| v.abs() < 1.96).count();
    let mean = z.iter().sum::<f64>() / z.len() as f64;
    println!("scene ASNR {:.4}; {inside}/100 measured within 1.96 σ; mean z {mean:+.3}", evaluation.asnr);
    assert!((88..=100).contains(&inside), "{inside} of 100 within 1.96 standard errors");
    assert!(mean.abs() < 0.5, "mean z {mean}: a bias");
}
