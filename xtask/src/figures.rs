//! `cargo xtask figures`: regenerate the paper's figures into `docs/figures/`, each as an SVG
//! with the CSV it is drawn from beside it:
//!
//! - Fig. 2a: the theoretical ASNR (eq. 1) over F-number and spectral range (Gaussian spectrum,
//!   range = 2√2σ, wavelength-independent efficiencies), with the best range for each F-number
//!   and the F/2.5 slice of Fig. 2b marked;
//! - Fig. 2b: that slice at F/2.5 ("theory") and a "simulated" curve from tabulated lens efficiency
//!   and camera QE (`examples/paper-simulated.toml`; illustrative tables, not the paper's data);
//! - SI Fig. S9: the ASNR against spectral range extended to broad bands for several F-numbers,
//!   shaded where the Fraunhofer approximation fails (SI eq. S15);
//! - Fig. 4: the simulated USAF target at 100, 50 and 10 nm, raw and Wiener-restored
//!   (`asnr render`), as a PNG panel with its contrast table.
//!
//! The task builds the `asnr` binary in release mode and drives it as a subprocess (xtask depends
//! on no project crate): `asnr sweep … --csv` computes each CSV, `asnr plot` draws each SVG, so
//! every figure can be redrawn from its CSV by hand with the command echoed here.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{Context, Result, bail};

use crate::cmd;

/// Fig. 2a grid: F-numbers from F/1.4 to F/5 (37 points: steps of 0.1, F/2.5 included).
const FIG2A_F_NUMBERS: usize = 37;
/// Fig. 2a grid: spectral ranges from 2 to 200 nm (100 points: steps of 2 nm).
const FIG2A_RANGES: usize = 100;
/// Fig. 2b: spectral ranges from 2 to 200 nm (steps of 2 nm).
const FIG2B_RANGES: usize = 100;
/// SI Fig. S9: spectral ranges from 5 to 800 nm (steps of 5 nm), at F/1.5, 2.5, 3.5 and 4.5.
const FIGS9_RANGES: usize = 160;

/// Where the figures go, relative to the workspace root.
const OUT_DIR: &str = "docs/figures";

/// The nominal widths (FWHM, nm) of the paper's four band-pass filters (SI section 1b: Thorlabs
/// FB800-10 and FB800-40, Salvo 825 nm/52 nm and 830 nm/125 nm), where it measured.
const PAPER_FILTERS_NM: [f64; 4] = [10.0, 40.0, 52.0, 125.0];

/// The super-Gaussian order of a flat-topped band-pass filter (`exp(−ln 2 (2x/FWHM)^8)`, the
/// shape of `examples/data/spectrometer-825-52.csv`).
const FILTER_ORDER: i32 = 4;

/// The spectral range 2√2σ of a flat-topped filter of full width at half maximum `fwhm_nm`: the
/// paper defines the filters' range as 2√2σ of their measured spectra (Results, Fig. 2b: "the
/// spectral range of the band-pass filters was also defined as 2√2σ"), not as their FWHM. For
/// the order-4 super-Gaussian σ² = (FWHM/2)² Γ(3/8)/(Γ(1/8) (ln 2)^{1/4}), 2√2σ = 0.8305 FWHM
/// (a top-hat: 0.8165; a Gaussian: 1.2011); here by the trapezoid rule over ±3 FWHM.
fn filter_range_nm(fwhm_nm: f64) -> f64 {
    let n = 60_000;
    let (a, h) = (-3.0 * fwhm_nm, 6.0 * fwhm_nm / f64::from(n));
    let (mut s0, mut s2) = (0.0, 0.0);
    for i in 0..=n {
        let x = a + f64::from(i) * h;
        let f = (-std::f64::consts::LN_2 * (2.0 * x / fwhm_nm).powi(2 * FILTER_ORDER)).exp();
        let w = if i == 0 || i == n { 0.5 } else { 1.0 };
        s0 += w * f;
        s2 += w * f * x * x;
    }
    2.0 * std::f64::consts::SQRT_2 * (s2 / s0).sqrt()
}

/// One sweep: the CSV it writes (in [`OUT_DIR`]) and the `asnr sweep` arguments before `--csv`.
struct Sweep {
    csv: &'static str,
    args: Vec<String>,
}

/// The sweeps, in the order they run.
fn sweeps() -> Vec<Sweep> {
    let owned = |args: &[&str]| args.iter().map(|a| (*a).to_owned()).collect::<Vec<_>>();
    vec![
        Sweep {
            csv: "fig2a-asnr-fnumber-range.csv",
            args: owned(&[
                "--over",
                &format!("lens.f_number=1.4:5:{FIG2A_F_NUMBERS}"),
                "--over",
                &format!("spectrum.range_nm=2:200:{FIG2A_RANGES}"),
            ]),
        },
        Sweep {
            csv: "fig2b-theory.csv",
            args: owned(&["--set", "lens.f_number=2.5", "--over", &format!("spectrum.range_nm=2:200:{FIG2B_RANGES}")]),
        },
        Sweep {
            csv: "fig2b-simulated.csv",
            args: owned(&[
                "examples/paper-simulated.toml",
                "--over",
                &format!("spectrum.range_nm=2:200:{FIG2B_RANGES}"),
            ]),
        },
        Sweep {
            csv: "figS9-broad-bands.csv",
            args: owned(&[
                "--over",
                "lens.f_number=1.5:4.5:4",
                "--over",
                &format!("spectrum.range_nm=5:800:{FIGS9_RANGES}"),
            ]),
        },
    ]
}

/// The `asnr plot` arguments of each figure (paths relative to the workspace root).
fn plots() -> Vec<Vec<String>> {
    let dir = |file: &str| format!("{OUT_DIR}/{file}");
    let range = "spectral range 2√2σ (nm)";
    let ranges: Vec<String> = PAPER_FILTERS_NM.iter().map(|&w| format!("{:.1}", filter_range_nm(w))).collect();
    let filters =
        format!("the paper's filters (10, 40, 52, 125 nm FWHM) at their 2√2σ: {} nm (flat-topped)", ranges.join(", "));
    let mut fig2b = vec![
        format!("{}=theory: flat τ1 and QE", dir("fig2b-theory.csv")),
        format!("{}=simulated: tabulated τ1(λ), QE(λ) (illustrative)", dir("fig2b-simulated.csv")),
        "--x".into(),
        "spectrum.range_nm".into(),
        "--y".into(),
        "asnr".into(),
        "--x-label".into(),
        range.into(),
        "--y-label".into(),
        "ASNR".into(),
        "--title".into(),
        "Fig. 2b — ASNR at F/2.5 against spectral range (Gaussian at 800 nm)".into(),
        "--mark-best".into(),
    ];
    for width in PAPER_FILTERS_NM {
        fig2b.extend(["--mark-x".into(), format!("{:.1}={filters}", filter_range_nm(width))]);
    }
    fig2b.extend(["--output".into(), dir("fig2b-asnr-range-f2.5.svg")]);
    let fig2a = vec![
        dir("fig2a-asnr-fnumber-range.csv"),
        "--x".into(),
        "lens.f_number".into(),
        "--y".into(),
        "spectrum.range_nm".into(),
        "--z".into(),
        "asnr".into(),
        "--x-label".into(),
        "F-number".into(),
        "--y-label".into(),
        range.into(),
        "--z-label".into(),
        "ASNR".into(),
        "--title".into(),
        "Fig. 2a — theoretical ASNR against F-number and spectral range".into(),
        "--mark-x".into(),
        "2.5=F/2.5: Fig. 2b".into(),
        "--shade-invalid".into(),
        "--output".into(),
        dir("fig2a-asnr-fnumber-range.svg"),
    ];
    let figs9 = vec![
        dir("figS9-broad-bands.csv"),
        "--x".into(),
        "spectrum.range_nm".into(),
        "--y".into(),
        "asnr".into(),
        "--group".into(),
        "lens.f_number".into(),
        "--group-label".into(),
        "F/{}".into(),
        "--x-label".into(),
        range.into(),
        "--y-label".into(),
        "ASNR".into(),
        "--title".into(),
        "Fig. S9 — ASNR against spectral range, extended to broad bands".into(),
        "--shade-invalid".into(),
        "--output".into(),
        dir("figS9-broad-bands.svg"),
    ];
    vec![fig2a, fig2b, figs9]
}

/// Builds `asnr` in release mode, runs the sweeps into CSVs and draws the SVGs, all in
/// `docs/figures/` under the workspace `root`.
pub(crate) fn run(root: &Path) -> Result<()> {
    let start = Instant::now();
    cmd::run(&mut cmd::cargo(root, &["build", "--release", "--package", "asnr", "--bin", "asnr"]))?;
    let asnr = asnr_binary(root)?;
    let out = root.join(OUT_DIR);
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let computing = Instant::now();
    for sweep in sweeps() {
        let step = Instant::now();
        let mut command = Command::new(&asnr);
        command.arg("sweep").args(&sweep.args).arg("--csv").current_dir(root).stderr(Stdio::inherit());
        let shown = format!("asnr {}", cmd::display(&command).split_once(' ').map_or("", |(_, rest)| rest));
        eprintln!("$ {shown} > {OUT_DIR}/{}", sweep.csv);
        let output = command.output().with_context(|| format!("could not start `{}`", asnr.display()))?;
        if !output.status.success() {
            bail!("`{shown}` failed");
        }
        let mut text = String::new();
        let _ = writeln!(text, "# written by `cargo xtask figures`: {shown}");
        text.push_str(&String::from_utf8_lossy(&output.stdout));
        let path = out.join(sweep.csv);
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
        eprintln!("  {:.1} s", step.elapsed().as_secs_f64());
    }
    let sweeping = computing.elapsed().as_secs_f64();
    for args in plots() {
        let mut command = Command::new(&asnr);
        command.arg("plot").args(&args).current_dir(root);
        eprintln!("$ asnr {}", cmd::display(&command).split_once(' ').map_or("", |(_, rest)| rest));
        if !command.status().with_context(|| format!("could not start `{}`", asnr.display()))?.success() {
            bail!("`asnr plot` failed for {}", args.last().map_or("?", String::as_str));
        }
    }
    // Fig. 4: the simulated and restored USAF target at 100, 50 and 10 nm (its panel, contrast
    // table and description; the individual images stay in target/)
    let scratch = root.join("target").join("fig4-render");
    let mut command = Command::new(&asnr);
    command.args(["render", "--ranges", "100,50,10", "--frames", "12", "--out"]).arg(&scratch).current_dir(root);
    eprintln!("$ asnr {}", cmd::display(&command).split_once(' ').map_or("", |(_, rest)| rest));
    if !command.status().with_context(|| format!("could not start `{}`", asnr.display()))?.success() {
        bail!("`asnr render` failed for Fig. 4");
    }
    for (from, to) in [("panel.png", "fig4-render-panel.png"), ("contrast.csv", "fig4-render-contrast.csv")] {
        std::fs::copy(scratch.join(from), out.join(to))
            .with_context(|| format!("cannot copy {from} into {OUT_DIR}"))?;
    }
    println!("figures: written to {OUT_DIR}/ in {:.1} s ({sweeping:.1} s of sweeps)", start.elapsed().as_secs_f64());
    Ok(())
}

/// The release `asnr` binary: `target_directory` from `cargo metadata`, so `CARGO_TARGET_DIR`
/// and `build.target-dir` are respected.
fn asnr_binary(root: &Path) -> Result<PathBuf> {
    let mut command = cmd::cargo(root, &["metadata", "--format-version", "1", "--no-deps"]);
    let output = command.output().context("could not run `cargo metadata`")?;
    if !output.status.success() {
        bail!("`cargo metadata` failed: {}", String::from_utf8_lossy(&output.stderr));
    }
    let metadata: serde_json::Value =
        serde_json::from_slice(&output.stdout).context("`cargo metadata` printed no JSON")?;
    let target = metadata["target_directory"].as_str().context("`cargo metadata` has no target_directory")?;
    let binary = Path::new(target).join("release").join(format!("asnr{}", std::env::consts::EXE_SUFFIX));
    if !binary.is_file() {
        bail!("{}: not found after `cargo build --release -p asnr`", binary.display());
    }
    Ok(binary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_plot_reads_a_csv_some_sweep_writes_and_writes_an_svg() {
        let written: Vec<String> = sweeps().iter().map(|s| format!("{OUT_DIR}/{}", s.csv)).collect();
        for args in plots() {
            let inputs: Vec<&str> =
                args.iter().take_while(|a| !a.starts_with("--")).map(|a| a.split('=').next().unwrap_or(a)).collect();
            assert!(!inputs.is_empty(), "{args:?}");
            for input in inputs {
                assert!(written.iter().any(|w| w == input), "{input} is not written by a sweep");
            }
            let output = args.iter().skip_while(|a| *a != "--output").nth(1).expect("an --output");
            assert!(output.starts_with(OUT_DIR) && output.ends_with(".svg"), "{output}");
        }
    }

    /// 2√2σ of the order-4 super-Gaussian against its closed form,
    /// 0.5·2√2·√(Γ(3/8)/Γ(1/8))·(ln 2)^{−1/8} FWHM = 0.830452… FWHM (Γ(3/8) = 2.370436184416601,
    /// Γ(1/8) = 7.533941598797612).
    #[test]
    fn filter_range_is_the_closed_form() {
        let closed = std::f64::consts::SQRT_2
            * (2.370_436_184_416_601_f64 / 7.533_941_598_797_612).sqrt()
            * std::f64::consts::LN_2.powf(-0.125);
        for w in PAPER_FILTERS_NM {
            assert!((filter_range_nm(w) / w - closed).abs() < 1e-9, "{w}: {}", filter_range_nm(w) / w);
        }
    }
}
