//! Two costs the README and the changelog quote, each with the tolerance asked and the error
//! achieved against a converged reference (BENCHMARKS.md, "`asnr otf` and a phase lens off
//! axis: time against achieved error"):
//! - `asnr otf --set field.x_deg=8` (the README's command, the embedded paper scene): the 2-D
//!   OTF grid evaluated directly at its own frequencies (`imaging::render::transfer`, which takes that
//!   path where the grid has fewer frequencies inside the cutoff than the interpolation table
//!   has samples) against the same grid read from the table (`imaging::render::transfer_interpolated`,
//!   cubic in radius and linear in azimuth); the reference the direct path at a hundredth of the
//!   scene's tolerance, the error the largest `|OTF − reference|` over the grid (the OTF is 1 at
//!   zero frequency);
//! - `asnr evaluate examples/phase-binary2.toml --set field.x_deg=3` (a radial pupil off axis,
//!   on the FFT path whose pupil profiles are sampled once per grid and reused at every
//!   wavelength node, optics/src/poly/grid.rs): `metric::evaluate`'s time, its ASNR and its
//!   relative error against the same scene at a hundredth of its tolerance.
//!
//! `cargo xtask accuracy --only otf-paths`

use std::time::Instant;

use crate::sections::Tools;

/// The section's heading (after `## `).
pub(crate) const TITLE: &str = "`asnr otf` and a phase lens off axis: time against achieved error";

/// The README's `asnr otf` grid: 256 samples a side (the command's default).
const SIZE: usize = 256;

/// Seconds of one call of `f`.
fn time<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let out = f();
    (out, start.elapsed().as_secs_f64())
}

/// Median and fastest of `times`.
fn spread(times: &[f64]) -> (f64, f64) {
    (crate::median(times.to_vec()), times.iter().copied().fold(f64::INFINITY, f64::min))
}

/// The tolerance the scene's engine holds the value to (`numerics.tolerance` of its evaluation:
/// the frequency rule's on the 1-D engines, on the FFT path the looser of it and the FFT path's
/// own).
fn tolerance_of(scene: &metric::Scene) -> Result<f64, String> {
    Ok(metric::evaluate(scene).map_err(|e| e.to_string())?.numerics.tolerance)
}

/// The `asnr otf` row: `(tolerance, [direct median, fastest], [table median, fastest], direct
/// error, table error, direct evaluations, table evaluations)`.
type OtfRow = (f64, (f64, f64), (f64, f64), f64, f64, usize, usize);

fn otf_row(repeats: usize) -> Result<OtfRow, String> {
    let source = scene::read(None).map_err(|e| e.to_string())?;
    let overrides = vec!["field.x_deg=8".to_owned()];
    let built = scene::build_from(&source, &overrides).map_err(|e| e.to_string())?;
    let detected = metric::detected_spectrum(&built);
    let cutoff = optics::highest_cutoff(built.lens(), &detected).map_err(|e| e.to_string())?;
    // the command's default spacing: the grid's Nyquist frequency at the cutoff
    let spacing = 0.5 / cutoff;
    let tolerance = tolerance_of(&built)?;
    let direct = || imaging::render::transfer(&built, SIZE, SIZE, spacing).map_err(|e| e.to_string());
    let table = || imaging::render::transfer_interpolated(&built, SIZE, SIZE, spacing).map_err(|e| e.to_string());
    let (first_direct, first_table) = (direct()?, table()?);
    let (mut direct_times, mut table_times) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        direct_times.push(time(direct).1);
        table_times.push(time(table).1);
    }
    // the reference: the direct path at a hundredth of the tolerance
    let tighter = [overrides.clone(), vec![format!("options.tolerance={:e}", 0.01 * tolerance)]].concat();
    let fine = scene::build_from(&source, &tighter).map_err(|e| e.to_string())?;
    let reference = imaging::render::transfer(&fine, SIZE, SIZE, spacing).map_err(|e| e.to_string())?;
    let error = |t: &imaging::render::Transfer| {
        t.values.iter().zip(&reference.values).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max)
    };
    Ok((
        tolerance,
        spread(&direct_times),
        spread(&table_times),
        error(&first_direct),
        error(&first_table),
        first_direct.evaluations,
        first_table.evaluations,
    ))
}

/// The phase lens off axis: `(tolerance, ASNR, relative error, [median, fastest])`.
fn phase_row(tools: &Tools, repeats: usize) -> Result<(f64, f64, f64, (f64, f64)), String> {
    let path = tools.root.join("examples/phase-binary2.toml");
    let source = scene::read(Some(&path)).map_err(|e| e.to_string())?;
    let overrides = vec!["field.x_deg=3".to_owned()];
    let built = scene::build_from(&source, &overrides).map_err(|e| e.to_string())?;
    let tolerance = tolerance_of(&built)?;
    let value = || metric::evaluate(&built).map_err(|e| e.to_string());
    let first = value()?;
    let times: Vec<f64> = (0..repeats).map(|_| time(value).1).collect();
    let tighter = [overrides, vec![format!("options.tolerance={:e}", 0.01 * tolerance)]].concat();
    let fine = scene::build_from(&source, &tighter).map_err(|e| e.to_string())?;
    let reference = metric::evaluate(&fine).map_err(|e| e.to_string())?;
    Ok((tolerance, first.asnr, (first.asnr - reference.asnr).abs() / reference.asnr.abs(), spread(&times)))
}

/// A time in ms or s, 3 significant figures.
fn seconds(t: f64) -> String {
    if t < 1.0 { format!("{:.1} ms", t * 1e3) } else { format!("{t:.2} s") }
}

/// The section, or `None` where neither row runs.
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let repeats = if tools.quick { 1 } else { 5 };
    let load = crate::load_average();
    let profile = if cfg!(debug_assertions) { "Dev profile" } else { "Release" };
    let otf = otf_row(repeats).map_err(|e| eprintln!("otf-paths: asnr otf: {e}")).ok();
    let phase = phase_row(tools, repeats).map_err(|e| eprintln!("otf-paths: phase lens: {e}")).ok();
    if otf.is_none() && phase.is_none() {
        return None;
    }
    let mut md = format!(
        "## {TITLE}\n\n`cargo xtask accuracy --only otf-paths` (bench/src/bin/accuracy/otf_paths.rs), in one \
         process, {profile}, medians (and fastest) of {repeats} runs after one, load average {load} at the start; \
         the tolerance is the one the scene's engine works to (`numerics.tolerance` of its evaluation: on the FFT \
         path the looser of `options.tolerance` and `options.fft_tolerance`), the reference the same computation \
         with `options.tolerance` at a hundredth of it.\n"
    );
    if let Some((tolerance, direct, table, e_direct, e_table, n_direct, n_table)) = otf {
        md.push_str(&format!(
            "\n`asnr otf --set field.x_deg=8` (the embedded paper scene, its {SIZE} × {SIZE} grid at the default \
             spacing): the OTF at the grid's own frequencies (`imaging::transfer`, the path it takes where that is \
             fewer evaluations than the table's samples) against the same grid read from the interpolation table \
             (`imaging::transfer_interpolated`); error the largest |OTF − reference| over the grid.\n\n| path | \
             tolerance | polychromatic OTF evaluations | time, median (fastest) | max error |\n|---|---|---|---|---|\n\
             | grid's own frequencies | {tolerance:.0e} | {n_direct} | {} ({}) | {e_direct:.1e} |\n| interpolation \
             table | {tolerance:.0e} | {n_table} | {} ({}) | {e_table:.1e} |\n\nRatio of medians (table / direct): \
             {:.2}×.\n",
            seconds(direct.0),
            seconds(direct.1),
            seconds(table.0),
            seconds(table.1),
            table.0 / direct.0,
        ));
    }
    if let Some((tolerance, asnr, error, t)) = phase {
        md.push_str(&format!(
            "\nA radial pupil off axis on the FFT path, its profiles sampled once per grid and reused at every \
             wavelength node (`asnr evaluate examples/phase-binary2.toml --set field.x_deg=3` as \
             `metric::evaluate`):\n\n| scene | tolerance | ASNR | relative error | evaluate, median (fastest) |\n\
             |---|---|---|---|---|\n| phase-binary2, 3° off axis | {tolerance:.0e} | {asnr:.6} | {error:.1e} | {} \
             ({}) |\n",
            seconds(t.0),
            seconds(t.1),
        ));
    }
    Some(md)
}
