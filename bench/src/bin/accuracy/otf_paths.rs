//! Two costs the README and the changelog quote, each with the tolerance asked and the error
//! achieved against a converged reference (BENCHMARKS.md, "`asnr otf` and a phase lens off
//! axis: time against achieved error"):
//! - `asnr otf --set field.x_deg=8` (the README's command, the embedded paper scene): the 2-D
//!   OTF grid evaluated directly at its own frequencies (`imaging::render::transfer`, which takes that
//!   path where the grid has fewer frequencies inside the cutoff than the interpolation table
//!   has samples) against the same grid read from the table (`imaging::render::transfer_interpolated`,
//!   cubic in radius and linear in azimuth); the reference written here ([`reference_otf`]: the
//!   polychromatic OTF's integral over λ by composite Gauss–Legendre, split at the frequency's
//!   cutoff wavelength, converged by doubling its panels) on every fourth grid frequency along
//!   each axis, the error the largest `|OTF − reference|` there (the OTF is 1 at zero
//!   frequency). Not the direct path at a tighter tolerance: the grid reaches the shortest
//!   wavelength's cutoff, inside the band, so the engine takes the reference panels rule, whose
//!   nodes do not depend on `options.tolerance` (nor on `options.spectral_rule`): that
//!   reference was the path itself, bit for bit;
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
/// error, table error, direct evaluations, table evaluations, the reference's own change on its
/// last doubling, the frequencies it is read at)`.
type OtfRow = (f64, (f64, f64), (f64, f64), f64, f64, usize, usize, f64, usize);

/// Every how many grid frequencies along each axis the reference is read.
const REFERENCE_STRIDE: usize = 4;

/// Gaussian factors of the detected spectrum cut at ±this many σ (beyond, 2e-18 of the weight).
const REFERENCE_SIGMAS: f64 = 9.0;

/// The polychromatic OTF of `scene` at `(nu, phi)` (cycles/m, radians), written here from its
/// definition (docs/physics.md, "Polychromatic OTF"): `∫ρ Σ_o τ_o H(νλF#, W020_o/λ)
/// exp(−2πi ν u·Δ_o) dλ / ∫ρ Σ_o τ_o dλ`, `H` the exact defocused OTF of the full circle
/// ([`optics::defocus_otf`]), `Δ_o` each order's image shift (its lateral colour), `u` the
/// frequency's direction; both integrals by `panels` equal panels of 16-point Gauss–Legendre
/// over the detected spectrum's support (Gaussian factors cut at ±[`REFERENCE_SIGMAS`] σ), the
/// panel holding the cutoff wavelength `1/(νF#)` (where `H`'s kink is) split there. `None`
/// where an order is not the full circle with a defocus alone.
fn reference_otf(
    scene: &metric::Scene,
    detected: &radiometry::Spectrum,
    nu: f64,
    phi: f64,
    panels: usize,
) -> Option<[f64; 2]> {
    let lens = scene.lens();
    let field = scene.field();
    let f_number = lens.f_number();
    let (mut lo, mut hi) = detected.support();
    for g in detected.gaussians() {
        lo = lo.max(g.center() - REFERENCE_SIGMAS * g.sigma());
        hi = hi.min(g.center() + REFERENCE_SIGMAS * g.sigma());
    }
    let rule = optics::quad::gauss_legendre(16);
    let cut = if nu > 0.0 { 1.0 / (nu * f_number) } else { f64::INFINITY };
    let (sin_phi, cos_phi) = phi.sin_cos();
    let (mut sum, mut total) = ([0.0, 0.0], 0.0);
    let width = (hi - lo) / panels as f64;
    for p in 0..panels {
        let (a, b) = (lo + p as f64 * width, lo + (p + 1) as f64 * width);
        let pieces = if cut > a && cut < b { vec![(a, cut), (cut, b)] } else { vec![(a, b)] };
        for (a, b) in pieces {
            let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
            for &(x, w) in &rule {
                let lambda = mid + half * x;
                let rho = w * half * detected.value(lambda);
                for order in lens.orders(lambda, field) {
                    if !(matches!(order.pupil, optics::Pupil::Full) && order.wavefront.is_defocus_only()) {
                        return None;
                    }
                    let h = optics::defocus_otf(nu * lambda * f_number, order.wavefront.defocus_m / lambda);
                    let [dx, dy] = order.wavefront.image_shift_m;
                    let phase = -2.0 * std::f64::consts::PI * nu * (dx * cos_phi + dy * sin_phi);
                    let (sin, cos) = phase.sin_cos();
                    let v = rho * order.efficiency * h;
                    sum = [sum[0] + v * cos, sum[1] + v * sin];
                    total += rho * order.efficiency;
                }
            }
        }
    }
    Some([sum[0] / total, sum[1] / total])
}

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
    // the reference written here on every REFERENCE_STRIDE-th frequency of the half spectrum
    // the transfer holds (index kx + ky (nx/2 + 1)), its panels doubled until the last doubling
    // moves it by less than a thousandth of the tolerance
    let hw = SIZE / 2 + 1;
    let signed = |k: usize| if k < SIZE / 2 { k as f64 } else { k as f64 - SIZE as f64 };
    let picked: Vec<usize> = (0..SIZE * hw)
        .filter(|i| (i % hw).is_multiple_of(REFERENCE_STRIDE) && (i / hw).is_multiple_of(REFERENCE_STRIDE))
        .collect();
    let at = |panels: usize| -> Result<Vec<[f64; 2]>, String> {
        picked
            .iter()
            .map(|&i| {
                let (nu_x, nu_y) =
                    ((i % hw) as f64 / (SIZE as f64 * spacing), signed(i / hw) / (SIZE as f64 * spacing));
                let nu = nu_x.hypot(nu_y);
                match nu {
                    0.0 => Some([1.0, 0.0]),
                    _ if nu >= cutoff => Some([0.0, 0.0]),
                    _ => reference_otf(&built, &detected, nu, nu_y.atan2(nu_x), panels),
                }
                .ok_or_else(|| "the reference needs every order the full circle with a defocus alone".to_owned())
            })
            .collect()
    };
    let (mut panels, mut reference) = (8, at(8)?);
    let change = loop {
        panels *= 2;
        let finer = at(panels)?;
        let change = finer.iter().zip(&reference).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max);
        reference = finer;
        if change <= 1e-3 * tolerance || panels >= 1024 {
            break change;
        }
    };
    let error = |t: &imaging::render::Transfer| {
        picked
            .iter()
            .zip(&reference)
            .map(|(&i, b)| (t.values[i].re - b[0]).hypot(t.values[i].im - b[1]))
            .fold(0.0, f64::max)
    };
    Ok((
        tolerance,
        spread(&direct_times),
        spread(&table_times),
        error(&first_direct),
        error(&first_table),
        first_direct.evaluations,
        first_table.evaluations,
        change,
        picked.len(),
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
         path the looser of `options.tolerance` and `options.fft_tolerance`).\n"
    );
    if let Some((tolerance, direct, table, e_direct, e_table, n_direct, n_table, change, points)) = otf {
        md.push_str(&format!(
            "\n`asnr otf --set field.x_deg=8` (the embedded paper scene, its {SIZE} × {SIZE} grid at the default \
             spacing): the OTF at the grid's own frequencies (`imaging::transfer`, the path it takes where that is \
             fewer evaluations than the table's samples) against the same grid read from the interpolation table \
             (`imaging::transfer_interpolated`); error the largest |OTF − reference| over {points} frequencies \
             (every {REFERENCE_STRIDE}th along each axis of the half spectrum), the reference written in the task \
             (the OTF's integral over λ by composite 16-point Gauss–Legendre, split at each frequency's cutoff \
             wavelength, its panels doubled until the last doubling moved it by {change:.1e}). The grid reaches the \
             shortest wavelength's cutoff, inside the band, so the engine takes its reference panels rule, whose \
             nodes do not depend on `options.tolerance`: the same path at a hundredth of the tolerance is the path \
             itself, bit for bit, and cannot serve as its reference.\n\n| path | \
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
