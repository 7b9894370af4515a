//! `cargo xtask data [--check]`: the generated data files of `examples/data/`, (re)written from
//! the code below so that anyone can reproduce them byte for byte (`--check`: fail if a file
//! differs from what the code makes, without writing).
//!
//! `examples/data/spectrometer-825-52.csv` is a synthetic spectrometer export (not a
//! measurement): a band-pass filter of 52 nm FWHM centred at 825 nm, sampled every 0.25 nm over
//! 600–1000 nm (1601 rows, `wavelength_nm,transmission`, transmission with 5 decimals):
//!
//! ```text
//! T(λ) = 0.002 + 0.898 · exp(−ln 2 · (2 |λ − 825 nm| / 52 nm)^8) + n(λ)
//! ```
//!
//! an 8th-power super-Gaussian (peak 0.9, half of the band above the floor at 825 ± 26 nm,
//! 10–90 % edges 9.7 nm wide) on a 0.2 % floor, plus measurement noise `n`: the sum of two
//! uniform deviates in ±0.0005 (triangular on ±0.001, standard deviation 0.00041, so that every
//! value stays ≥ 0.001) drawn in wavelength order from PCG-64 MCG (`rand_pcg`) seeded with [`SEED`]. It is
//! the issue's spectrometer case ("a spectrometer table at 0.25 nm over 600–1000 nm"), read by
//! `examples/spectrometer.toml` and the accuracy report.
//!
//! `examples/data/phase-hyperbolic-f2.5.csv` is the radial phase table of a hyperbolic metalens
//! (the paper's aperture: F/2.5, f0 = 3.36 mm, R = 0.672 mm, λ0 = 800 nm), as a designer's script
//! would export it: 801 rows `r_mm,phase_rad` from 0 to R, the unwrapped
//! `φ0(r) = −(2π/λ0)(√(r² + f0²) − f0)` with 9 decimals (read by `examples/phase-table.toml`).
//!
//! `examples/data/library-tio2-like.csv` is an ILLUSTRATIVE meta-atom library, not a simulation:
//! TiO2-like pillars 800 nm high, diameters 100–300 nm every 5 nm, 700–900 nm every 10 nm, whose
//! transmission follows a simple effective-index model (`pillar` below: the phase
//! `2π H (n_eff − 1)/λ` with `n_eff = 1 + 0.9 (n(λ) − 1)(d/300 nm)^1.5`, `n(λ) = 2.3 + 0.08/λ²`
//! (λ in µm), and the amplitude `0.95 − 0.15 (d/300 nm)^4`). `examples/data/layout-paper-lens.csv`
//! places it on the paper's lens: 1680 rings of 400 nm pitch, each the diameter whose field at
//! 800 nm is nearest to the hyperbolic phase (read by `examples/library.toml`).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, bail};

/// The spectrometer table, relative to the workspace root.
pub(crate) const SPECTROMETER: &str = "examples/data/spectrometer-825-52.csv";

/// First wavelength, step and row count of the table (nm): 600, 600.25, …, 1000.
const START_NM: f64 = 600.0;
const STEP_NM: f64 = 0.25;
const ROWS: usize = 1601;

/// The band: centre, FWHM (nm), peak and floor transmission, super-Gaussian order (the exponent
/// is twice it).
const CENTRE_NM: f64 = 825.0;
const FWHM_NM: f64 = 52.0;
const PEAK: f64 = 0.9;
const FLOOR: f64 = 0.002;
const ORDER: i32 = 4;

/// Half-width of each of the two uniform noise deviates.
const NOISE_HALF_WIDTH: f64 = 0.0005;

/// Seed of the noise generator.
pub(crate) const SEED: u64 = 825_052;

/// The project's one generator family: PCG-64 MCG (O'Neill 2014, `rand_pcg::Pcg64Mcg`), seeded
/// by `rand`'s `seed_from_u64`. Its 64-bit outputs are fixed by the algorithm (rand_pcg's
/// reproducibility promise); the uniform deviates are made from them here (the top 53 bits), so
/// the table does not depend on how a `rand` version turns bits into floats.
struct Uniform(rand_pcg::Pcg64Mcg);

impl Uniform {
    /// Uniform in [0, 1): the top 53 bits of the next output.
    fn next(&mut self) -> f64 {
        (rand::Rng::next_u64(&mut self.0) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The noiseless filter curve at `lambda_nm`.
fn band(lambda_nm: f64) -> f64 {
    let u = 2.0 * (lambda_nm - CENTRE_NM).abs() / FWHM_NM;
    FLOOR + (PEAK - FLOOR) * (-std::f64::consts::LN_2 * u.powi(2 * ORDER)).exp()
}

/// The text of the spectrometer table (header comment, column names, 1601 rows).
pub(crate) fn spectrometer_table() -> String {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "# Synthetic spectrometer export (NOT a measurement), written by `cargo xtask data` (xtask/src/data.rs).\n\
         # A band-pass filter of 52 nm FWHM at 825 nm, sampled every 0.25 nm over 600-1000 nm (1601 rows):\n\
         # T = 0.002 + 0.898 exp(-ln2 (2|lambda - 825 nm|/52 nm)^8) + noise, an 8th-power super-Gaussian\n\
         # (peak 0.9, 10-90 % edges 9.7 nm wide) on a 0.2 % floor; the noise is the sum of two uniform\n\
         # deviates in +-0.0005 from PCG-64 MCG seeded with {SEED}, drawn in wavelength order.\n\
         wavelength_nm,transmission"
    );
    let mut rng = Uniform(rand::SeedableRng::seed_from_u64(SEED));
    for i in 0..ROWS {
        let lambda = START_NM + STEP_NM * i as f64;
        let noise = NOISE_HALF_WIDTH * (2.0 * rng.next() - 1.0) + NOISE_HALF_WIDTH * (2.0 * rng.next() - 1.0);
        let _ = writeln!(text, "{lambda:.2},{:.5}", band(lambda) + noise);
    }
    text
}

/// The illustrative meta-atom library and its layout, relative to the workspace root.
pub(crate) const LIBRARY: &str = "examples/data/library-tio2-like.csv";
pub(crate) const LAYOUT: &str = "examples/data/layout-paper-lens.csv";

/// The illustrative library's pillar: height (nm), lattice period (nm), diameters (nm).
const PILLAR_HEIGHT_NM: f64 = 800.0;
const DIAMETERS_NM: (f64, f64, f64) = (100.0, 300.0, 5.0);

/// The illustrative pillar's transmission at `d_nm`, `lambda_nm` (module docs): an effective
/// index between air and a TiO2-like Cauchy index, `n_eff = 1 + 0.9 (n(λ) − 1)(d/300)^1.5`, the
/// phase `2π H (n_eff − 1)/λ` wrapped to (−π, π], the amplitude `0.95 − 0.15 (d/300)^4`.
fn pillar(d_nm: f64, lambda_nm: f64) -> (f64, f64) {
    let n = 2.3 + 0.08 / (lambda_nm * 1e-3).powi(2);
    let fill = (d_nm / DIAMETERS_NM.1).powf(1.5);
    let n_eff = 1.0 + 0.9 * (n - 1.0) * fill;
    let phase = std::f64::consts::TAU * PILLAR_HEIGHT_NM * (n_eff - 1.0) / lambda_nm;
    let wrapped = phase - std::f64::consts::TAU * (phase / std::f64::consts::TAU).round();
    (0.95 - 0.15 * (d_nm / DIAMETERS_NM.1).powi(4), wrapped)
}

fn diameters() -> Vec<f64> {
    let (lo, hi, step) = DIAMETERS_NM;
    let count = ((hi - lo) / step).round() as usize;
    (0..=count).map(|i| lo + step * i as f64).collect()
}

/// The illustrative library table (module docs).
pub(crate) fn library_table() -> String {
    let mut text = String::from(
        "# ILLUSTRATIVE TiO2-pillar-like meta-atom library, not a simulation (cargo xtask data):\n\
         # effective-index model of an 800 nm pillar, see xtask/src/data.rs\n\
         diameter_nm,wavelength_nm,amplitude,phase_rad\n",
    );
    for d in diameters() {
        for k in 0..=20 {
            let lambda = 700.0 + 10.0 * k as f64;
            let (a, phase) = pillar(d, lambda);
            let _ = writeln!(text, "{d:.1},{lambda:.1},{a:.6},{phase:.6}");
        }
    }
    text
}

/// The layout of the paper's lens in the illustrative library: rings of 400 nm pitch from the
/// axis to R = 0.672 mm, each the diameter whose field at 800 nm is nearest the hyperbolic phase.
pub(crate) fn layout_table() -> String {
    let (f0_nm, radius_nm, pitch_nm) = (3.36e6_f64, 0.672e6_f64, 400.0);
    let rows = (radius_nm / pitch_nm).round() as usize;
    let fields: Vec<(f64, f64, f64)> = diameters()
        .into_iter()
        .map(|d| {
            let (a, phase) = pillar(d, 800.0);
            (d, a * phase.cos(), a * phase.sin())
        })
        .collect();
    let mut text = String::from(
        "# layout of the paper's lens (F/2.5, f0 = 3.36 mm, 800 nm) in the ILLUSTRATIVE library (cargo xtask data)\nr_mm,diameter_nm\n",
    );
    for i in 0..rows {
        let r = (i as f64 + 0.5) * pitch_nm;
        let target = -std::f64::consts::TAU / 800.0 * ((r * r + f0_nm * f0_nm).sqrt() - f0_nm);
        let (tx, ty) = (target.cos(), target.sin());
        let best = fields
            .iter()
            .min_by(|a, b| {
                ((a.1 - tx).powi(2) + (a.2 - ty).powi(2)).total_cmp(&((b.1 - tx).powi(2) + (b.2 - ty).powi(2)))
            })
            .map_or(0.0, |f| f.0);
        let _ = writeln!(text, "{:.7},{best:.1}", r * 1e-6);
    }
    text
}

/// The hyperbolic phase table, relative to the workspace root.
pub(crate) const PHASE_TABLE: &str = "examples/data/phase-hyperbolic-f2.5.csv";

/// The hyperbolic metalens's radial phase table (module docs).
pub(crate) fn phase_table() -> String {
    let (f0_mm, radius_mm, lambda_mm, rows) = (3.36_f64, 0.672_f64, 800e-6_f64, 800);
    let mut text = String::from(
        "# hyperbolic metalens F/2.5, f0 = 3.36 mm, lambda0 = 800 nm (cargo xtask data)\nr_mm,phase_rad\n",
    );
    for i in 0..=rows {
        let r = radius_mm * i as f64 / rows as f64;
        let phase = -std::f64::consts::TAU / lambda_mm * ((r * r + f0_mm * f0_mm).sqrt() - f0_mm);
        let _ = writeln!(text, "{r:.6},{phase:.9}");
    }
    text
}

/// The 2-D phase maps of the examples (`cargo xtask data --maps`), written under `target/` (each
/// is 29 MB, too large to commit): the paper's aperture (F/2.5, f0 = 3.36 mm, λ0 = 800 nm) on
/// 0.5 µm cells, 2688 × 2688 (1.344 mm), the phase wrapped to [0, 2π) (geometric phase) as
/// float32 `[y, x]`, row j at y = (j − 1343.5) p.
pub(crate) const MAPS: [(&str, f64); 2] =
    [("target/phase-maps/hyperbolic-f2.5.npy", 0.0), ("target/phase-maps/cubic-f2.5.npy", 30.0)];

/// The cells of a map side and their pitch, m.
const MAP_CELLS: usize = 2688;
const MAP_PITCH: f64 = 0.5e-6;

/// A `.npy` float32 map of the hyperbolic phase `−(2π/λ0)(√(r² + f0²) − f0)` plus the cubic term
/// `alpha ((x/R)³ + (y/R)³)` (radians; R = 0.672 mm), wrapped to [0, 2π): the formula of
/// `scene::npy::hyperbolic_cubic_map`, which the tests and benchmarks call; written out here because
/// the task runner depends on no workspace crate (it builds in seconds, before them).
pub(crate) fn phase_map(alpha: f64) -> Vec<u8> {
    let (f0, lambda0, radius) = (3.36e-3, 800e-9, 0.672e-3);
    let k0 = 2.0 * std::f64::consts::PI / lambda0;
    let n = MAP_CELLS;
    let mut header = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({n}, {n}), }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.reserve(n * n * 4);
    let centre = |k: usize| (k as f64 - 0.5 * (n as f64 - 1.0)) * MAP_PITCH;
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (centre(i), centre(j));
            let phase =
                -k0 * ((x * x + y * y + f0 * f0).sqrt() - f0) + alpha * ((x / radius).powi(3) + (y / radius).powi(3));
            bytes.extend_from_slice(&(phase.rem_euclid(std::f64::consts::TAU) as f32).to_le_bytes());
        }
    }
    bytes
}

/// Write (or with `--check`, compare) every generated file under the workspace `root`; with
/// `--maps`, the examples' 2-D phase maps under `target/phase-maps/` instead.
pub(crate) fn run(root: &Path, args: &[String]) -> Result<()> {
    let check = match args {
        [] => false,
        [flag] if flag == "--check" => true,
        [flag] if flag == "--maps" => {
            std::fs::create_dir_all(root.join("target/phase-maps")).context("cannot create target/phase-maps")?;
            for (name, alpha) in MAPS {
                let path = root.join(name);
                std::fs::write(&path, phase_map(alpha)).with_context(|| format!("cannot write {}", path.display()))?;
                eprintln!("data: wrote {name} ({MAP_CELLS} × {MAP_CELLS} cells of 0.5 µm, cubic term {alpha} rad)");
            }
            return Ok(());
        }
        [bad, ..] => bail!("unknown argument `{bad}` (usage: cargo xtask data [--check | --maps])"),
    };
    let files = [
        (SPECTROMETER, spectrometer_table()),
        (PHASE_TABLE, phase_table()),
        (LIBRARY, library_table()),
        (LAYOUT, layout_table()),
    ];
    for (name, text) in files {
        let path = root.join(name);
        if check {
            let current = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
            if current != text {
                bail!("{name} differs from what `cargo xtask data` writes: run it and commit the file");
            }
            eprintln!("data: {name} is up to date");
        } else {
            std::fs::write(&path, &text).with_context(|| format!("cannot write {}", path.display()))?;
            eprintln!("data: wrote {name} ({} rows)", text.lines().filter(|l| !l.starts_with('#')).count() - 1);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(text: &str) -> Vec<(f64, f64)> {
        text.lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with("wavelength"))
            .map(|l| {
                let (a, b) = l.split_once(',').unwrap();
                (a.parse().unwrap(), b.parse().unwrap())
            })
            .collect()
    }

    #[test]
    fn the_table_has_the_issue_shape() {
        let rows = rows(&spectrometer_table());
        assert_eq!(rows.len(), 1601);
        assert_eq!((rows[0].0, rows[1600].0), (600.0, 1000.0));
        assert!(rows.windows(2).all(|w| (w[1].0 - w[0].0 - 0.25).abs() < 1e-12));
        // floor and noise: every value within ±0.001 of the noiseless curve, none below 0.001
        for &(l, t) in &rows {
            assert!((t - band(l)).abs() <= 0.001 + 5e-6, "{l}: {t}");
            assert!(t >= 0.001 - 5e-6, "{l}: {t}");
        }
        // the band: peak ~0.9 at 825 nm, half of it above the floor at 825 ± 26 nm
        let at = |nm: f64| band(nm);
        assert!((at(825.0) - 0.9).abs() < 1e-12);
        assert!((at(799.0) - (FLOOR + 0.5 * (PEAK - FLOOR))).abs() < 1e-12);
        assert!((at(851.0) - (FLOOR + 0.5 * (PEAK - FLOOR))).abs() < 1e-12);
        assert!((at(700.0) - FLOOR).abs() < 1e-12);
    }

    #[test]
    fn the_noise_is_seeded_and_centred() {
        assert_eq!(spectrometer_table(), spectrometer_table());
        let rows = rows(&spectrometer_table());
        let noise: Vec<f64> = rows.iter().map(|&(l, t)| t - band(l)).collect();
        let mean = noise.iter().sum::<f64>() / noise.len() as f64;
        let sd = (noise.iter().map(|n| (n - mean).powi(2)).sum::<f64>() / noise.len() as f64).sqrt();
        assert!(mean.abs() < 5e-5, "{mean}");
        // triangular on ±0.001: standard deviation 0.001/√6 = 0.00041 (and rounding to 5 decimals)
        assert!((sd - 0.001 / 6f64.sqrt()).abs() < 3e-5, "{sd}");
    }

    /// The committed file is what the generator writes (`cargo xtask data` after a change).
    #[test]
    fn the_committed_table_is_current() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
        let committed = std::fs::read_to_string(root.join(SPECTROMETER)).unwrap();
        assert!(committed == spectrometer_table(), "run `cargo xtask data` and commit {SPECTROMETER}");
        let committed = std::fs::read_to_string(root.join(PHASE_TABLE)).unwrap();
        assert!(committed == phase_table(), "run `cargo xtask data` and commit {PHASE_TABLE}");
        for (name, text) in [(LIBRARY, library_table()), (LAYOUT, layout_table())] {
            let committed = std::fs::read_to_string(root.join(name)).unwrap();
            assert!(committed == text, "run `cargo xtask data` and commit {name}");
        }
    }

    /// The phase table is the hyperbola: at the rim −(2π/λ0)(√(R² + f0²) − f0) = −527.79 rad.
    #[test]
    fn the_phase_table_reaches_the_rim() {
        let text = phase_table();
        let last = text.lines().last().unwrap();
        let (r, phase) = last.split_once(',').unwrap();
        assert_eq!(r, "0.672000");
        let want = -std::f64::consts::TAU / 800e-6 * ((0.672f64 * 0.672 + 3.36 * 3.36).sqrt() - 3.36);
        assert!((phase.parse::<f64>().unwrap() - want).abs() < 1e-8, "{phase} vs {want}");
    }
}
