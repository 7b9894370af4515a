//! The design wavelength's gradient cost beside one evaluation (BENCHMARKS.md, "Gradients: the
//! design wavelength"): `lens.design_wavelength_nm` on the paper's lens (the closed form: the
//! lane along `δW020 = (λ/λ0) f0/(8F#²)` on its own rule in t) and on the harmonic lens of
//! `examples/harmonic.toml` (the per-frequency product rule: each order's `∂H/∂w δw_o` and its
//! efficiency's `δτ_o H_o` beside each value), in one process and whole process, at the
//! tolerances 1e-6 and 1e-4 (docs/physics.md, "Gradients: the design wavelength").

use std::path::Path;
use std::process::Command;

use crate::sections::Tools;

/// The section's heading (after `## `).
pub(crate) const TITLE: &str = "Gradients: the design wavelength";

const KEY: &str = "lens.design_wavelength_nm";

/// The scenes: `(case, example)`.
const CASES: [(&str, &str); 2] = [
    ("paper lens (closed form)", "paper-theory.toml"),
    ("harmonic lens p = 5, 50 nm (per-frequency rule)", "harmonic.toml"),
];

/// `repeats` alternate runs of `asnr evaluate` and `asnr gradient --wrt lens.design_wavelength_nm`
/// on `scene` at `tolerance`, after one of each: `[value, value_min, both, both_min]` (s).
fn whole_process(asnr: &Path, root: &Path, scene: &Path, tolerance: f64, repeats: usize) -> Option<[f64; 4]> {
    let tol = format!("{tolerance:e}");
    let evaluate = || {
        let mut c = Command::new(asnr);
        c.arg("evaluate").arg(scene).args(["--tolerance", &tol]);
        c
    };
    let gradient = || {
        let mut c = Command::new(asnr);
        c.arg("gradient").arg(scene).args(["--wrt", KEY, "--tolerance", &tol]);
        c
    };
    let [value, value_min, both, both_min] =
        crate::process::value_and_gradient_alternately(&evaluate, &gradient, root, repeats)?;
    Some([value, value_min, both, both_min])
}

/// The section: the one-process and whole-process tables, or `None` where no scene evaluates.
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let repeats = if tools.quick { 11 } else { 31 };
    let process_repeats = if tools.quick { 5 } else { 11 };
    let load = crate::load_average();
    let profile = if cfg!(debug_assertions) { "Dev profile" } else { "Release" };
    let mut inside = Vec::new();
    for tolerance in [1e-6, 1e-4] {
        let set = vec![format!("options.tolerance={tolerance:e}")];
        for (case, file) in CASES {
            let Ok(source) = scene::read(Some(&tools.root.join("examples").join(file))) else { continue };
            let row = crate::gradients::side_by_side(&source, &set, &[metric::Parameter::DesignWavelength], repeats);
            inside.extend(row.map(|r| (case, tolerance, r)));
        }
    }
    if inside.is_empty() {
        eprintln!("gradients-design: neither example differentiated");
        return None;
    }
    let mut md = format!(
        "## {TITLE}\n\n`cargo xtask accuracy --only gradients-design` (bench/src/bin/accuracy/gradients_design.rs): \
         one evaluation against the evaluation and its gradient with respect to `lens.design_wavelength_nm`, on the \
         paper's lens (examples/paper-theory.toml: the closed form carries the lane along ∂W020/∂ln λ0 = (λ/λ0) \
         f0/(8F#²) on its own rule in t) and the harmonic lens (examples/harmonic.toml, six orders: the per-frequency \
         product rule carries Σ_o [τ_o ∂H/∂w δw_o + δτ_o H_o] beside each value, on the spectral level the value \
         accepts), the frequency rule's accepted weights integrating the lane (docs/physics.md, \"Gradients: the \
         design wavelength\"): one more mean. In one process (`metric::evaluate` against `metric::gradient`, the scene \
         built inside each timing), {profile}, medians (and fastest) of {repeats} alternate runs after one of each, \
         load average {load} at the start.\n\n| scene | tolerance | ASNR | \\|∂ASNR/∂ln λ0\\| | value, median \
         (fastest) | value and gradient, median (fastest) | ratio of medians | ratio of fastest \
         |\n|---|---|---|---|---|---|---|---|\n"
    );
    for (case, tolerance, r) in &inside {
        md.push_str(&format!(
            "| {case} | {tolerance:e} | {:.4} | {:.3e} {}\n",
            r.asnr,
            r.norm,
            crate::gradients::timing_cells([r.value, r.value_min, r.both, r.both_min], 2)
        ));
    }
    let mut whole = Vec::new();
    if let Some(asnr) = tools.asnr.as_deref() {
        for tolerance in [1e-6, 1e-4] {
            for (case, file) in CASES {
                let scene = tools.root.join("examples").join(file);
                whole.extend(
                    whole_process(asnr, &tools.root, &scene, tolerance, process_repeats).map(|t| (case, tolerance, t)),
                );
            }
        }
    }
    if !whole.is_empty() {
        md.push_str(&format!(
            "\nWhole process: `asnr evaluate SCENE --tolerance T` against `asnr gradient SCENE --wrt {KEY} --tolerance \
             T` (the release binary, wall clock, medians of {process_repeats} alternate runs after one of each).\n\n| \
             scene | tolerance | value, median (fastest) | value and ∂/∂λ0, median (fastest) | ratio of medians | \
             ratio of fastest |\n|---|---|---|---|---|---|\n"
        ));
        for (case, tolerance, t) in &whole {
            md.push_str(&format!("| {case} | {tolerance:e} {}\n", crate::gradients::timing_cells(*t, 1)));
        }
    }
    let verdicts: Vec<String> = inside
        .iter()
        .map(|(case, t, r)| format!("{case} at {t:e}: {}", crate::gradients::within_three(r.both, r.value)))
        .collect();
    md.push_str(&format!("\nTarget (issue: at most 3× one evaluation; in one process): {}.\n", verdicts.join("; ")));
    Some(md)
}
