//! The numerical stress sweep (`cargo xtask stress [--quick]`): [`metric::evaluate`] over the
//! corners of the physical parameter space, every point checked and timed.
//!
//! ```text
//! cargo run --release -p asnr-bench --bin stress -- [--quick] [--timeout SECONDS] [--only TEXT] [--list]
//! ```
//!
//! The grid: F/0.5–F/50; Gaussian spectral ranges 1e-3–600 nm; pixels 0.3–50 µm; efficiencies
//! 1e-9–1; 1e-3–1e12 photoelectrons (through the radiance or the exposure); defocus up to 1e4
//! waves at the band edges (focal lengths up to 1 m: `w = (1 − λ/λ0) f0/(8 F#² λ)`); top-hat,
//! tabulated, blackbody and line (one-wavelength) spectra and a tabulated QE; decentred and annular apertures (the FFT
//! path); off-axis points with lateral colour; sensor noise with saturation; glare included.
//! `--quick` runs the subset marked quick (well under a minute in release, for CI); the full grid
//! keeps the extreme corners, however slow they are today.
//!
//! Each point runs in a child process of this binary (`--point INDEX`), so a point that takes
//! longer than `--timeout` (default 20 s quick, 300 s full) is killed and reported as a failure
//! with its time, instead of stalling the sweep.
//!
//! Checked at every point: the evaluation succeeds; ASNR, mean MTF, SNR0 and the photoelectron
//! count are finite; `0 ≤ mean MTF ≤ 1`; `0 ≤ SNR0`; `ASNR ≤ SNR0`. Listed but not failures:
//! warnings, and fallbacks (a Gaussian, on-axis, full-pupil scene that did not get the
//! closed-form engine, or numerics that mention a fallback). Printed: a table with the engine
//! and the time of every point, the flagged points with their numerics, the slowest points, and
//! `stress: N points, M failures`; the exit status is non-zero on any failure.

use std::io::Read;
use std::process::{Command, ExitCode, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

use lenses::{ChromaticMetalens, Curve};
use metric::{Camera, GlareMode, Options, Scene, evaluate};
use optics::Field;
use optics::fft::Aperture;
use radiometry::{Blackbody, Gaussian, Line, Sampled, Spectrum, TopHat};

/// The paper scene (docs/physics.md, "The metric"): F/2.5, f0 = 3.36 mm, λ0 = 800 nm, 50 nm
/// Gaussian, 5.2 µm pixels, τ1 = 0.15, T = 0.55, QE 0.2, 0.025 W/(m² sr nm), 1.23 ms: 559.4 e⁻.
const F0_MM: f64 = 3.36;
const LAMBDA0_NM: f64 = 800.0;
const RADIANCE: f64 = 0.025e9;
const EXPOSURE_S: f64 = 1.23e-3;
const PAPER_ELECTRONS: f64 = 559.385;
const PAPER_EFFICIENCY: f64 = 0.15;

/// The light reaching the lens (after the filter).
#[derive(Clone, Debug)]
enum Light {
    /// A flat source behind a Gaussian filter (centre, the paper's range 2√2σ), nm.
    Gaussian { centre: f64, range: f64 },
    /// A flat source behind a top-hat band, nm.
    TopHat { lo: f64, hi: f64 },
    /// A flat source behind a tabulated filter: a triangle `lo–peak–hi` with `samples` points, nm.
    Table { lo: f64, peak: f64, hi: f64, samples: usize },
    /// A blackbody (K) behind a top-hat band, nm.
    Blackbody { kelvin: f64, lo: f64, hi: f64 },
    /// A blackbody (K) behind a Gaussian filter, nm.
    BlackbodyGaussian { kelvin: f64, centre: f64, range: f64 },
    /// A flat source behind a line filter (one wavelength for the optics; the photons of a band
    /// of equivalent width `width`), nm.
    Line { centre: f64, width: f64 },
}

impl Light {
    /// The band the defocus is quoted at: `centre ± range` for a Gaussian (±2.8σ), the band
    /// limits otherwise, nm.
    fn band(&self) -> (f64, f64) {
        match *self {
            Light::Gaussian { centre, range } | Light::BlackbodyGaussian { centre, range, .. } => {
                ((centre - range).max(1.0), centre + range)
            }
            Light::TopHat { lo, hi } | Light::Table { lo, hi, .. } | Light::Blackbody { lo, hi, .. } => (lo, hi),
            Light::Line { centre, .. } => (centre, centre),
        }
    }

    fn describe(&self) -> String {
        match *self {
            Light::Gaussian { centre, range } => format!("gauss {range}nm@{centre}"),
            Light::TopHat { lo, hi } => format!("tophat {lo}-{hi}"),
            Light::Table { lo, hi, samples, .. } => format!("table {lo}-{hi} ({samples})"),
            Light::Blackbody { kelvin, lo, hi } => format!("bb {kelvin}K {lo}-{hi}"),
            Light::BlackbodyGaussian { kelvin, centre, range } => format!("bb {kelvin}K gauss {range}nm@{centre}"),
            Light::Line { centre, width } => format!("line {width}nm@{centre}"),
        }
    }
}

/// One point of the sweep.
#[derive(Clone, Debug)]
struct Point {
    f_number: f64,
    f0_mm: f64,
    light: Light,
    pixel_um: f64,
    pixel_mtf: bool,
    /// first-order efficiency τ1 (T = max(τ1, 0.55))
    efficiency: f64,
    /// multiplies the source radiance
    radiance_scale: f64,
    exposure_s: f64,
    /// the iris decentre (fractions of the radius) and central obscuration, if not the full pupil
    aperture: Option<(f64, f64, f64)>,
    pupil_samples: usize,
    field_deg: f64,
    /// tabulated QE (a silicon-like curve) instead of the constant 0.2
    qe_table: bool,
    /// sensor: (read noise e⁻, full well e⁻)
    sensor: Option<(f64, f64)>,
    glare_included: bool,
    /// part of the `--quick` grid
    quick: bool,
}

impl Point {
    /// The paper scene.
    fn paper() -> Point {
        Point {
            f_number: 2.5,
            f0_mm: F0_MM,
            light: Light::Gaussian { centre: LAMBDA0_NM, range: 50.0 },
            pixel_um: 5.2,
            pixel_mtf: false,
            efficiency: PAPER_EFFICIENCY,
            radiance_scale: 1.0,
            exposure_s: EXPOSURE_S,
            aperture: None,
            pupil_samples: 256,
            field_deg: 0.0,
            qe_table: false,
            sensor: None,
            glare_included: false,
            quick: false,
        }
    }

    /// Largest defocus at the band edges, waves: `|1/λ0 − 1/λ| f0/(8 F#²)`.
    fn max_waves(&self) -> f64 {
        let (lo, hi) = self.light.band();
        let k = self.f0_mm * 1e-3 / (8.0 * self.f_number * self.f_number);
        let w = |nm: f64| k * (1.0 / (LAMBDA0_NM * 1e-9) - 1.0 / (nm * 1e-9)).abs();
        w(lo).max(w(hi))
    }

    /// Whether the closed-form spectral engine should apply: a flat source behind a Gaussian,
    /// constant QE and efficiency, the full pupil, on axis.
    fn closed_form_expected(&self) -> bool {
        matches!(self.light, Light::Gaussian { .. })
            && self.aperture.is_none()
            && self.field_deg == 0.0
            && !self.qe_table
    }

    fn describe(&self) -> String {
        let mut s = format!("F/{} f0 {}mm {} px {}um", self.f_number, self.f0_mm, self.light.describe(), self.pixel_um);
        if self.pixel_mtf {
            s.push_str(" pxMTF");
        }
        if self.efficiency != PAPER_EFFICIENCY {
            s.push_str(&format!(" tau {:e}", self.efficiency));
        }
        if self.radiance_scale != 1.0 {
            s.push_str(&format!(" L x{:.3e}", self.radiance_scale));
        }
        if self.exposure_s != EXPOSURE_S {
            s.push_str(&format!(" t {:.3e}s", self.exposure_s));
        }
        if let Some((dx, dy, obs)) = self.aperture {
            s.push_str(&format!(" iris ({dx},{dy}) obs {obs} N {}", self.pupil_samples));
        }
        if self.field_deg != 0.0 {
            s.push_str(&format!(" field {}deg", self.field_deg));
        }
        if self.qe_table {
            s.push_str(" QE table");
        }
        if let Some((read, well)) = self.sensor {
            s.push_str(&format!(" read {read}e well {well}e"));
        }
        if self.glare_included {
            s.push_str(" glare");
        }
        s
    }

    fn scene(&self) -> Result<Scene, String> {
        let nm = |x: f64| x * 1e-9;
        let err = |e: &dyn std::fmt::Display| e.to_string();
        let flat = Spectrum::Constant(RADIANCE * self.radiance_scale);
        let radiance = match self.light {
            Light::Gaussian { centre, range } => {
                let g = Gaussian::from_range(nm(centre), nm(range), 1.0).map_err(|e| err(&e))?;
                Spectrum::product(vec![flat, Spectrum::Gaussian(g)])
            }
            Light::TopHat { lo, hi } => {
                let t = TopHat::new(nm(lo), nm(hi), 1.0).map_err(|e| err(&e))?;
                Spectrum::product(vec![flat, Spectrum::TopHat(t)])
            }
            Light::Table { lo, peak, hi, samples } => {
                let wavelengths: Vec<f64> =
                    (0..samples).map(|i| nm(lo + (hi - lo) * i as f64 / (samples - 1) as f64)).collect();
                let values = wavelengths
                    .iter()
                    .map(|&l| {
                        let l = l * 1e9;
                        if l <= peak { (l - lo) / (peak - lo) } else { (hi - l) / (hi - peak) }
                    })
                    .map(|v: f64| v.clamp(0.0, 1.0))
                    .collect();
                let table = Sampled::new(wavelengths, values).map_err(|e| err(&e))?;
                Spectrum::product(vec![flat, Spectrum::Sampled(table)])
            }
            Light::Blackbody { kelvin, lo, hi } => {
                let b = Blackbody::new(kelvin).map_err(|e| err(&e))?;
                let t = TopHat::new(nm(lo), nm(hi), 1.0).map_err(|e| err(&e))?;
                Spectrum::product(vec![
                    Spectrum::blackbody(b, self.radiance_scale).map_err(|e| err(&e))?,
                    Spectrum::TopHat(t),
                ])
            }
            Light::BlackbodyGaussian { kelvin, centre, range } => {
                let b = Blackbody::new(kelvin).map_err(|e| err(&e))?;
                let g = Gaussian::from_range(nm(centre), nm(range), 1.0).map_err(|e| err(&e))?;
                Spectrum::product(vec![
                    Spectrum::blackbody(b, self.radiance_scale).map_err(|e| err(&e))?,
                    Spectrum::Gaussian(g),
                ])
            }
            Light::Line { centre, width } => {
                let l = Line::new(nm(centre), nm(width), 1.0).map_err(|e| err(&e))?;
                Spectrum::product(vec![flat, Spectrum::Line(l)])
            }
        };
        let transmission = self.efficiency.max(0.55);
        let mut lens = ChromaticMetalens::new(
            self.f_number,
            self.f0_mm * 1e-3,
            nm(LAMBDA0_NM),
            Curve::Constant(self.efficiency),
            Curve::Constant(transmission),
        )
        .map_err(|e| err(&e))?;
        if let Some((dx, dy, obscuration)) = self.aperture {
            let aperture = Aperture::annulus(obscuration).and_then(|a| a.decentred(dx, dy)).map_err(|e| err(&e))?;
            lens = lens.with_aperture(aperture);
        }
        let qe = if self.qe_table {
            // silicon-like: rising from 350 nm, peak 0.6 at 600 nm, falling to 0 at 1100 nm
            let table = Sampled::new(
                vec![nm(350.0), nm(450.0), nm(600.0), nm(800.0), nm(950.0), nm(1100.0)],
                vec![0.0, 0.45, 0.6, 0.35, 0.15, 0.0],
            )
            .map_err(|e| err(&e))?;
            Spectrum::Sampled(table)
        } else {
            Spectrum::Constant(0.2)
        };
        let mut camera = Camera::new(self.pixel_um * 1e-6, qe, self.pixel_mtf).map_err(|e| err(&e))?;
        if let Some((read, well)) = self.sensor {
            camera = camera.with_sensor(noise::Sensor::without_adc(read, 0.0, well).map_err(|e| err(&e))?);
        }
        let options = Options {
            pupil_samples: Some(self.pupil_samples),
            glare: if self.glare_included { GlareMode::Included } else { GlareMode::FirstOrder },
            ..Options::default()
        };
        let scene = Scene::new(Arc::new(lens), radiance, camera, self.exposure_s, options).map_err(|e| err(&e))?;
        if self.field_deg == 0.0 {
            Ok(scene)
        } else {
            scene.at_field(Field::new(self.field_deg.to_radians(), 0.0)).map_err(|e| err(&e))
        }
    }
}

/// The full grid; `quick` marks the CI subset.
fn grid() -> Vec<Point> {
    let mut points = Vec::new();
    let paper = Point::paper();
    let gauss = |range: f64| Light::Gaussian { centre: LAMBDA0_NM, range };

    // 1. the core cube: F-number × Gaussian range × pixel pitch, the paper's lens otherwise
    for f_number in [0.5, 1.0, 2.5, 10.0, 50.0] {
        for range in [1e-3, 0.1, 10.0, 100.0, 600.0] {
            for pixel_um in [0.3, 5.2, 50.0] {
                // the quick corners; F/0.5 at 600 nm on 0.3 µm pixels takes minutes today (full grid only)
                let corner = [0.5, 2.5, 50.0].contains(&f_number) && [1e-3, 10.0, 600.0].contains(&range);
                let slow = f_number == 0.5 && range == 600.0;
                let quick = corner && if slow { pixel_um != 0.3 } else { pixel_um != 5.2 };
                points.push(Point { f_number, light: gauss(range), pixel_um, quick, ..paper.clone() });
            }
        }
    }
    // the paper scene itself, with and without the pixel MTF
    points.push(Point { quick: true, ..paper.clone() });
    points.push(Point { pixel_mtf: true, quick: true, ..paper.clone() });

    // 2. large defocus: long focal lengths and broad bands, ~10 to ~1e4 waves at the band edges
    for f0_mm in [33.6, 336.0, 1000.0] {
        for f_number in [1.0, 2.5, 10.0] {
            for range in [10.0, 100.0, 600.0] {
                let quick = [(1000.0, 10.0, 10.0), (336.0, 1.0, 100.0)].contains(&(f0_mm, f_number, range));
                let point = Point { f0_mm, f_number, light: gauss(range), quick, ..paper.clone() };
                // up to ~1e4 waves: the corners beyond are the same physics, only slower
                if point.max_waves() <= 1.2e4 {
                    points.push(point);
                }
            }
        }
    }

    // 3. efficiency × photoelectrons (1e-3 to 1e12), alternately through radiance and exposure
    for (i, efficiency) in [1e-9, 1e-4, 1.0].into_iter().enumerate() {
        for (j, electrons) in [1e-3, 1.0, 1e6, 1e12].into_iter().enumerate() {
            let factor = electrons / PAPER_ELECTRONS * PAPER_EFFICIENCY / efficiency;
            let (radiance_scale, exposure_s) =
                if (i + j) % 2 == 0 { (factor, EXPOSURE_S) } else { (1.0, EXPOSURE_S * factor) };
            let quick = (i == 0 || i == 2) && (j == 0 || j == 3);
            points.push(Point { efficiency, radiance_scale, exposure_s, quick, ..paper.clone() });
        }
    }

    // 4. other spectra: top-hat, tables, blackbody, a tabulated QE
    for f_number in [1.0, 2.5, 10.0] {
        for (lo, hi) in [(799.5, 800.5), (775.0, 825.0), (600.0, 1000.0)] {
            let quick = f_number == 2.5 && lo == 775.0;
            points.push(Point { f_number, light: Light::TopHat { lo, hi }, quick, ..paper.clone() });
        }
    }
    for f_number in [1.4, 2.5] {
        for (lo, peak, hi, samples) in [(750.0, 800.0, 850.0, 3), (700.0, 790.0, 900.0, 41)] {
            let quick = f_number == 2.5 && samples == 41;
            points.push(Point { f_number, light: Light::Table { lo, peak, hi, samples }, quick, ..paper.clone() });
        }
    }
    for kelvin in [3000.0, 6500.0] {
        let light = Light::Blackbody { kelvin, lo: 400.0, hi: 1000.0 };
        points.push(Point { light, radiance_scale: 1e-3, quick: kelvin == 3000.0, ..paper.clone() });
        let light = Light::BlackbodyGaussian { kelvin, centre: LAMBDA0_NM, range: 50.0 };
        points.push(Point { light, radiance_scale: 1e-3, ..paper.clone() });
    }
    points.push(Point { qe_table: true, quick: true, ..paper.clone() });
    points.push(Point { qe_table: true, light: Light::TopHat { lo: 400.0, hi: 1000.0 }, ..paper.clone() });
    // line spectra: in focus, defocused (by ~500 and ~5000 waves at f0 = 336 mm: one wavelength
    // keeps every zero of its OTF, ~1600 below Nyquist at 5000 waves), through the FFT path and
    // off axis, with a tabulated QE, and beyond the Fraunhofer limit
    for (f_number, f0_mm, centre, pixel_um) in [
        (0.5, F0_MM, 800.0, 0.3),
        (2.5, F0_MM, 850.0, 5.2),
        (50.0, F0_MM, 600.0, 50.0),
        (2.5, 336.0, 850.0, 5.2),
        (1.0, 336.0, 900.0, 5.2),
    ] {
        let light = Light::Line { centre, width: 10.0 };
        let quick = f_number == 2.5;
        points.push(Point { f_number, f0_mm, light, pixel_um, quick, ..paper.clone() });
    }
    let line = Light::Line { centre: 830.0, width: 1.0 };
    points.push(Point {
        light: line.clone(),
        aperture: Some((0.1, 0.0, 0.0)),
        pupil_samples: 64,
        quick: true,
        ..paper.clone()
    });
    points.push(Point { light: line.clone(), field_deg: 8.0, qe_table: true, quick: true, ..paper.clone() });
    points.push(Point { light: Light::Line { centre: 1150.0, width: 10.0 }, ..paper.clone() });

    // 5. the FFT path: decentred irises (SI Fig. S3), an annulus, coarse and fine pupil grids
    for (dx, range) in [(0.1, 10.0), (0.1, 50.0), (0.1, 200.0), (0.3, 50.0)] {
        let quick = range == 10.0;
        points.push(Point {
            aperture: Some((dx, 0.0, 0.0)),
            light: gauss(range),
            pupil_samples: 64,
            quick,
            ..paper.clone()
        });
    }
    points.push(Point { aperture: Some((0.1, 0.0, 0.0)), ..paper.clone() });
    points.push(Point { aperture: Some((0.0, 0.0, 0.3)), pupil_samples: 64, quick: true, ..paper.clone() });
    for (f_number, range, pixel_um) in [(0.5, 10.0, 5.2), (1.0, 100.0, 5.2), (50.0, 50.0, 5.2), (2.5, 50.0, 0.3)] {
        points.push(Point {
            f_number,
            light: gauss(range),
            pixel_um,
            aperture: Some((0.1, 0.05, 0.0)),
            pupil_samples: 64,
            ..paper.clone()
        });
    }
    points.push(Point {
        aperture: Some((0.1, 0.0, 0.0)),
        light: Light::TopHat { lo: 775.0, hi: 825.0 },
        pupil_samples: 64,
        ..paper.clone()
    });

    // 6. off axis: lateral colour, complex 1-D sum
    points.push(Point { field_deg: 8.0, quick: true, ..paper.clone() });
    points.push(Point { field_deg: 30.0, ..paper.clone() });
    points.push(Point { field_deg: 10.0, f_number: 1.0, light: gauss(200.0), ..paper.clone() });

    // 7. the camera: read noise, a full well that clips, the glare-inclusive SNR
    points.push(Point { sensor: Some((10.0, 1e5)), quick: true, ..paper.clone() });
    points.push(Point { sensor: Some((3.0, 100.0)), quick: true, ..paper.clone() });
    points.push(Point { glare_included: true, ..paper.clone() });
    points.push(Point { glare_included: true, efficiency: 1e-9, ..paper });
    points
}

/// What a child process reports for one point.
#[derive(Debug)]
enum Outcome {
    Ok {
        seconds: f64,
        asnr: f64,
        mean_mtf: f64,
        snr0: f64,
        electrons: f64,
        engine: String,
        numerics: String,
        warnings: Vec<String>,
    },
    Error {
        seconds: f64,
        message: String,
    },
    Crashed {
        seconds: f64,
        message: String,
    },
    Timeout {
        seconds: f64,
    },
}

impl Outcome {
    fn seconds(&self) -> f64 {
        match self {
            Outcome::Ok { seconds, .. }
            | Outcome::Error { seconds, .. }
            | Outcome::Crashed { seconds, .. }
            | Outcome::Timeout { seconds } => *seconds,
        }
    }
}

/// Child mode: evaluates one point and prints one tab-separated line.
fn run_point(point: &Point) {
    let start = Instant::now();
    let result = point.scene().and_then(|scene| evaluate(&scene).map_err(|e| e.to_string()));
    let seconds = start.elapsed().as_secs_f64();
    let clean = |s: &str| s.replace(['\t', '\n'], " ");
    match result {
        Ok(e) => println!(
            "ok\t{seconds:?}\t{:?}\t{:?}\t{:?}\t{:?}\t{}\t{}\t{}",
            e.asnr,
            e.mean_mtf,
            e.snr0,
            e.photoelectrons,
            clean(&e.numerics.engine),
            clean(&format!("{:?}", e.numerics)),
            e.warnings.iter().map(|w| clean(w)).collect::<Vec<_>>().join(" || ")
        ),
        Err(message) => println!("error\t{seconds:?}\t{}", clean(&message)),
    }
}

fn parse(stdout: &str, wall: f64) -> Option<Outcome> {
    let fields: Vec<&str> = stdout.trim_end_matches('\n').split('\t').collect();
    let num = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok());
    match fields.first().copied() {
        Some("ok") if fields.len() >= 8 => Some(Outcome::Ok {
            seconds: num(1)?,
            asnr: num(2)?,
            mean_mtf: num(3)?,
            snr0: num(4)?,
            electrons: num(5)?,
            engine: fields[6].to_owned(),
            numerics: fields[7].to_owned(),
            warnings: fields
                .get(8)
                .filter(|w| !w.is_empty())
                .map_or(Vec::new(), |w| w.split(" || ").map(str::to_owned).collect()),
        }),
        Some("error") => Some(Outcome::Error { seconds: num(1).unwrap_or(wall), message: fields[2..].join(" ") }),
        _ => None,
    }
}

/// Runs point `index` in a child process, killed after `timeout`.
fn spawn(index: usize, timeout: Duration) -> Outcome {
    let start = Instant::now();
    let exe = match std::env::current_exe() {
        Ok(exe) => exe,
        Err(e) => return Outcome::Crashed { seconds: 0.0, message: format!("no executable path: {e}") },
    };
    let child = Command::new(exe)
        .args(["--point", &index.to_string()])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(child) => child,
        Err(e) => return Outcome::Crashed { seconds: 0.0, message: format!("could not start: {e}") },
    };
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if start.elapsed() > timeout => {
                let _ = child.kill();
                let _ = child.wait();
                return Outcome::Timeout { seconds: start.elapsed().as_secs_f64() };
            }
            Ok(None) => std::thread::sleep(Duration::from_micros(500)),
            Err(e) => return Outcome::Crashed { seconds: start.elapsed().as_secs_f64(), message: e.to_string() },
        }
    };
    let wall = start.elapsed().as_secs_f64();
    let (mut stdout, mut stderr) = (String::new(), String::new());
    if let Some(mut out) = child.stdout.take() {
        let _ = out.read_to_string(&mut stdout);
    }
    if let Some(mut err) = child.stderr.take() {
        let _ = err.read_to_string(&mut stderr);
    }
    match parse(&stdout, wall) {
        Some(outcome) if status.success() => outcome,
        _ => {
            let last = stderr.lines().filter(|l| !l.trim().is_empty()).take(3).collect::<Vec<_>>().join(" / ");
            Outcome::Crashed { seconds: wall, message: format!("{status}: {last}") }
        }
    }
}

/// The checks of one outcome: failures (empty if it passed).
fn failures(outcome: &Outcome) -> Vec<String> {
    let mut out = Vec::new();
    match outcome {
        Outcome::Ok { asnr, mean_mtf, snr0, electrons, .. } => {
            for (name, v) in [("asnr", asnr), ("mean_mtf", mean_mtf), ("snr0", snr0), ("photoelectrons", electrons)] {
                if !v.is_finite() {
                    out.push(format!("{name} = {v} is not finite"));
                }
            }
            if !(0.0..=1.0).contains(mean_mtf) {
                out.push(format!("mean MTF {mean_mtf} outside [0, 1]"));
            }
            if snr0.is_nan() || *snr0 < 0.0 {
                out.push(format!("SNR0 {snr0} < 0"));
            }
            if asnr.is_nan() || *asnr > snr0 * (1.0 + 1e-12) {
                out.push(format!("ASNR {asnr} > SNR0 {snr0}"));
            }
        }
        Outcome::Error { message, .. } => out.push(format!("error: {message}")),
        Outcome::Crashed { message, .. } => out.push(format!("crashed: {message}")),
        Outcome::Timeout { seconds } => out.push(format!("timeout: killed after {seconds:.1} s")),
    }
    out
}

fn usage() -> &'static str {
    "usage: stress [--quick] [--timeout SECONDS] [--only TEXT] [--list]\n"
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let points = grid();
    let (mut quick, mut list, mut timeout, mut only) = (false, false, None, None);
    let mut iter = args.iter();
    while let Some(arg) = iter.next() {
        match arg.as_str() {
            "--point" => {
                let Some(point) = iter.next().and_then(|i| i.parse::<usize>().ok()).and_then(|i| points.get(i)) else {
                    eprint!("stress: --point needs an index below {}\n{}", points.len(), usage());
                    return ExitCode::FAILURE;
                };
                run_point(point);
                return ExitCode::SUCCESS;
            }
            "--quick" => quick = true,
            "--list" => list = true,
            "--timeout" => match iter.next().and_then(|s| s.parse::<f64>().ok()).filter(|s| *s > 0.0) {
                Some(s) => timeout = Some(Duration::from_secs_f64(s)),
                None => {
                    eprint!("stress: --timeout needs a number of seconds > 0\n{}", usage());
                    return ExitCode::FAILURE;
                }
            },
            "--only" => only = iter.next().cloned(),
            "-h" | "--help" => {
                print!("{}", usage());
                return ExitCode::SUCCESS;
            }
            other => {
                eprint!("stress: unknown argument `{other}`\n{}", usage());
                return ExitCode::FAILURE;
            }
        }
    }
    let timeout = timeout.unwrap_or(Duration::from_secs(if quick { 20 } else { 300 }));
    let selected: Vec<usize> = (0..points.len())
        .filter(|&i| !quick || points[i].quick)
        .filter(|&i| only.as_ref().is_none_or(|t| points[i].describe().contains(t.as_str())))
        .collect();
    if list {
        for &i in &selected {
            println!("{i:>4}  {:>9.3e} waves  {}", points[i].max_waves(), points[i].describe());
        }
        return ExitCode::SUCCESS;
    }
    println!(
        "stress: {} points ({} grid), timeout {} s per point",
        selected.len(),
        if quick { "quick" } else { "full" },
        timeout.as_secs_f64()
    );
    println!(
        "{:>4} {:>9} {:>10} {:>11} {:>11} {:>10} {:>10} {:<12} {:<6} point",
        "#", "waves", "time", "N e-", "SNR0", "mean MTF", "ASNR", "engine", "status"
    );
    let start = Instant::now();
    let mut results = Vec::new();
    for &i in &selected {
        let outcome = spawn(i, timeout);
        let failed = failures(&outcome);
        let point = &points[i];
        let status = match (&outcome, failed.is_empty()) {
            (_, false) => "FAIL",
            (Outcome::Ok { warnings, .. }, true) if !warnings.is_empty() => "warn",
            _ => "ok",
        };
        let numbers = match &outcome {
            Outcome::Ok { asnr, mean_mtf, snr0, electrons, engine, .. } => format!(
                "{electrons:>11.4e} {snr0:>11.4e} {mean_mtf:>10.6} {asnr:>10.4e} {:<12}",
                engine.split([' ', ',']).next().unwrap_or("")
            ),
            _ => format!("{:>11} {:>11} {:>10} {:>10} {:<12}", "-", "-", "-", "-", "-"),
        };
        println!(
            "{i:>4} {:>9.2e} {:>8.3}ms {numbers} {status:<6} {}",
            point.max_waves(),
            outcome.seconds() * 1e3,
            point.describe()
        );
        results.push((i, outcome, failed));
    }
    let total = start.elapsed().as_secs_f64();

    let failed: Vec<_> = results.iter().filter(|r| !r.2.is_empty()).collect();
    if !failed.is_empty() {
        println!("\nfailures:");
        for (i, outcome, why) in &failed {
            println!("  #{i} {} ({:.2} s): {}", points[*i].describe(), outcome.seconds(), why.join("; "));
        }
    }
    let mut any_warning = false;
    for (i, outcome, _) in &results {
        if let Outcome::Ok { warnings, .. } = outcome {
            for w in warnings {
                if !any_warning {
                    println!("\nwarnings:");
                    any_warning = true;
                }
                println!("  #{i} {}: {w}", points[*i].describe());
            }
        }
    }
    let mut any_fallback = false;
    for (i, outcome, _) in &results {
        if let Outcome::Ok { engine, numerics, .. } = outcome {
            let missed = points[*i].closed_form_expected() && !engine.starts_with("closed-form");
            if missed || numerics.to_lowercase().contains("fallback") || engine.to_lowercase().contains("fallback") {
                if !any_fallback {
                    println!(
                        "\nfallbacks (a Gaussian on-axis full-pupil scene off the closed form, or a fallback in the numerics):"
                    );
                    any_fallback = true;
                }
                println!("  #{i} {}: {numerics}", points[*i].describe());
            }
        }
    }
    let mut by_time: Vec<_> = results.iter().collect();
    by_time.sort_by(|a, b| b.1.seconds().total_cmp(&a.1.seconds()));
    println!("\nslowest points:");
    for (i, outcome, _) in by_time.iter().take(10) {
        let numerics = match outcome {
            Outcome::Ok { numerics, .. } => numerics.clone(),
            Outcome::Timeout { .. } => "timed out".to_owned(),
            other => format!("{other:?}"),
        };
        println!(
            "  #{i} {:>9.3} s  {:.2e} waves  {}  [{numerics}]",
            outcome.seconds(),
            points[*i].max_waves(),
            points[*i].describe()
        );
    }
    let timeouts = results.iter().filter(|r| matches!(r.1, Outcome::Timeout { .. })).count();
    println!("\nwall time {total:.1} s");
    println!("stress: {} points, {} failures ({timeouts} timeouts)", results.len(), failed.len());
    if failed.is_empty() { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
