//! The two rules of a radial table's knots side by side (BENCHMARKS.md, "A phase table: the
//! tensor and the split rule"): `[options] table_rule = "tensor"` (the default; Gauss–Legendre
//! panels sized for an analytic integrand, good to about `optics::radial::TENSOR_TABLE_ERROR` =
//! 2e-6 whatever the tolerance) against `"split"` (every panel between the knots' crossings,
//! within the tolerance asked; a pupil whose tables have more than
//! `optics::radial::SPLIT_MAX_KNOTS` = 64 knots keeps the tensor rule). Two lenses of the
//! paper's aperture, both the hyperbolic profile of `examples/phase-table.toml`: the example
//! itself (801 samples: more than 64 knots, so `"split"` is the tensor rule) and the same lens
//! with the profile as a 17-knot spline (`lens.phase_spline_rad`, `phase_csv` left out), where
//! the split rule applies. Each: the mean MTF under each rule at the tolerances 1e-4 and 1e-6,
//! its error against the split rule at 1e-9 (the converged reference), and the time of
//! `metric::evaluate` (the scene built once, outside the timing; the two rules alternately,
//! medians). docs/physics.md, "The radial engine".
//!
//! `cargo xtask accuracy --only table-rule`

use std::time::Instant;

use crate::sections::Tools;

/// The section's heading.
pub(crate) const TITLE: &str = "A phase table: the tensor and the split rule";

/// The hyperbolic phase of `examples/phase-table.toml` (R = 0.672 mm, f0 = 3.36 mm, λ0 =
/// 800 nm) at `knots` equally spaced radii from the axis to the rim, rad:
/// `−(2π/λ0)(√(r² + f0²) − f0)` (the example's table, `cargo xtask data`, samples the same).
fn hyperbolic_knots(knots: usize) -> Vec<f64> {
    let (radius, f0, l0) = (0.672e-3_f64, 3.36e-3_f64, 800e-9_f64);
    let k0 = std::f64::consts::TAU / l0;
    (0..knots)
        .map(|i| {
            let r = radius * i as f64 / (knots - 1) as f64;
            -k0 * ((r * r + f0 * f0).sqrt() - f0)
        })
        .collect()
}

/// The lens's scene (`knots`: the 17-knot spline in place of the example's table) with
/// `table_rule` at `tolerance`.
fn scene(tools: &Tools, knots: Option<usize>, rule: &str, tolerance: f64) -> Option<metric::Scene> {
    let path = tools.root.join("examples/phase-table.toml");
    let mut overrides = vec![format!("options.table_rule=\"{rule}\""), format!("options.tolerance={tolerance:e}")];
    let built = scene::read(Some(&path)).and_then(|source| match knots {
        None => scene::build_from(&source, &overrides),
        Some(n) => {
            let values: Vec<String> = hyperbolic_knots(n).iter().map(|v| format!("{v:e}")).collect();
            overrides.push(format!("lens.phase_spline_rad=[{}]", values.join(", ")));
            scene::build_from(&source.without_lens_keys(&["phase_csv"]), &overrides)
        }
    });
    match built {
        Ok(s) => Some(s),
        Err(e) => {
            eprintln!("table-rule: {}: {e}", path.display());
            None
        }
    }
}

/// One run of `metric::evaluate` of `scene`: (seconds, mean MTF).
fn timed(scene: &metric::Scene) -> Option<(f64, f64)> {
    optics::forget_remembered();
    let start = Instant::now();
    let e = metric::evaluate(std::hint::black_box(scene)).ok()?;
    Some((start.elapsed().as_secs_f64(), e.mean_mtf))
}

/// One row: lens, tolerance; per rule (tensor, split) the mean MTF, the median and fastest time;
/// the reference.
struct Row {
    lens: &'static str,
    tolerance: f64,
    mtf: [f64; 2],
    median: [f64; 2],
    fastest: [f64; 2],
    reference: f64,
}

/// The rows of one lens: its reference, then each tolerance's two rules side by side.
fn rows(tools: &Tools, lens: &'static str, knots: Option<usize>, repeats: usize) -> Option<Vec<Row>> {
    let reference = metric::evaluate(&scene(tools, knots, "split", REFERENCE_TOLERANCE)?).ok()?.mean_mtf;
    let mut rows = Vec::new();
    for tolerance in [1e-4, 1e-6] {
        let scenes = [scene(tools, knots, "tensor", tolerance)?, scene(tools, knots, "split", tolerance)?];
        // one untimed run of each first (the per-thread caches), then alternately
        let mut mtf = [0.0; 2];
        for (m, s) in mtf.iter_mut().zip(&scenes) {
            *m = timed(s)?.1;
        }
        let mut times = [Vec::new(), Vec::new()];
        for _ in 0..repeats {
            for ((t, s), m) in times.iter_mut().zip(&scenes).zip(&mtf) {
                let (seconds, value) = timed(s)?;
                // the same value at every run
                assert_eq!(value.to_bits(), m.to_bits(), "table-rule: a run's mean MTF moved");
                t.push(seconds);
            }
        }
        let fastest = [0, 1].map(|i| times[i].iter().copied().fold(f64::INFINITY, f64::min));
        let [tensor, split] = times;
        let median = [crate::median(tensor), crate::median(split)];
        rows.push(Row { lens, tolerance, mtf, median, fastest, reference });
    }
    Some(rows)
}

/// The converged reference's tolerance (the split rule).
const REFERENCE_TOLERANCE: f64 = 1e-9;

/// The section's markdown.
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let repeats = if tools.quick { 3 } else { 7 };
    let load = || {
        std::fs::read_to_string("/proc/loadavg")
            .ok()
            .map_or_else(|| "unknown".to_owned(), |s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
    };
    let load_before = load();
    let mut all = Vec::new();
    for (lens, knots) in [("17-knot spline", Some(17)), ("the example's 801-sample table", None)] {
        match rows(tools, lens, knots, repeats) {
            Some(r) => all.extend(r),
            None => eprintln!("table-rule: the {lens} did not evaluate"),
        }
    }
    if all.is_empty() {
        return None;
    }
    let profile = if cfg!(debug_assertions) { "Dev profile" } else { "Release" };
    let mut md = format!("## {TITLE}\n\n");
    md.push_str(&format!(
        "`cargo xtask accuracy --only table-rule` (bench/src/bin/accuracy/table_rule.rs): the paper's aperture with \
         the hyperbolic profile of `examples/phase-table.toml` (its 50 nm band), as a 17-knot spline \
         (`lens.phase_spline_rad`, the profile at 17 equally spaced radii, `phase_csv` left out) and as the \
         example's own 801-sample table, under `[options] table_rule = \"tensor\"` (the default: Gauss–Legendre \
         panels sized for an analytic integrand, which converge only algebraically across a knot, so such a lens is \
         good to about `TENSOR_TABLE_ERROR` = 2e-6 relative whatever the tolerance) and `\"split\"` (every panel \
         between the knots' crossings; docs/physics.md, \"The radial engine\"). A pupil whose tables have more \
         than 64 knots (`SPLIT_MAX_KNOTS`) keeps the tensor rule under `\"split\"`: the example's table takes the \
         same rule either way, and its reference (that rule at {REFERENCE_TOLERANCE:e}) keeps the tensor rule's own \
         error of up to about 2e-6. The error is each mean MTF's against the same lens under the split rule at \
         {REFERENCE_TOLERANCE:e}. `metric::evaluate` of the scene built once, {profile}, one untimed run of each \
         rule, then {repeats} of each alternately, medians (the fastest in brackets); load average (1, 5, 15 min) \
         before: {load_before}, after: {}.\n\n",
        load()
    ));
    md.push_str(
        "| lens | tolerance | reference (split, 1e-9) | mean MTF, tensor | error, tensor | mean MTF, split | error, \
         split | tensor: time, median (fastest) | split: time, median (fastest) | split / tensor: medians \
         (fastest) |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in &all {
        let error = |m: f64| (m - r.reference) / r.reference;
        md.push_str(&format!(
            "| {} | {:e} | {:.10} | {:.10} | {:+.1e} | {:.10} | {:+.1e} | {:.1} ms ({:.1} ms) | {:.1} ms ({:.1} ms) | \
             {:.1}× ({:.1}×) |\n",
            r.lens,
            r.tolerance,
            r.reference,
            r.mtf[0],
            error(r.mtf[0]),
            r.mtf[1],
            error(r.mtf[1]),
            1e3 * r.median[0],
            1e3 * r.fastest[0],
            1e3 * r.median[1],
            1e3 * r.fastest[1],
            r.median[1] / r.median[0],
            r.fastest[1] / r.fastest[0]
        ));
    }
    Some(md)
}
