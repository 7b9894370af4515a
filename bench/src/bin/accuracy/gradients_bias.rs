//! The cost of a library lens's parameter-bias gradient beside one evaluation (BENCHMARKS.md,
//! "Gradients: a library's parameter bias"): `examples/library.toml` with
//! `lens.library_interpolation = "cubic"` and `lens.parameter_bias = [0.3]`, the scene built and
//! evaluated (`metric::evaluate`) against the scene built, evaluated and differentiated with
//! respect to `lens.parameter_bias[0]` (`metric::gradient`: the lens's forward-mode order
//! derivatives and the radial engine's amplitude and phase lane beside each of the value's own
//! OTF values, on the value's per-frequency product rule and frequency rule, in the
//! evaluation's own pass; docs/physics.md, "Gradients: a library's parameter bias").
//! Medians of repeats in one process, release.
//!
//! `cargo xtask accuracy --only gradients-bias`

use metric::Parameter;

use crate::sections::Tools;

/// The section's markdown, or `None` where the example cannot be read.
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let repeats = if tools.quick { 3 } else { 7 };
    let load = crate::load_average();
    let source = scene::read(Some(&tools.root.join("examples/library.toml"))).ok()?;
    let mut md = format!(
        "## Gradients: a library's parameter bias\n\n\
         `examples/library.toml` with `lens.library_interpolation = \"cubic\"` and `lens.parameter_bias = [0.3]` \
         (nm): one evaluation against the evaluation and its gradient with respect to `lens.parameter_bias[0]`, \
         the scene built inside each timing, medians (and fastest) of {repeats} alternate runs in one process after \
         one of each, release, load average {load} at the start. The gradient's lanes ride on the value's own \
         rules in the evaluation's pass: each OTF value with its amplitude and phase lane, integrated with the \
         weights of the spectral level and the frequency panels the value accepts (docs/physics.md, \"Gradients: \
         a library's parameter bias\"): the target is at most 3× one evaluation.\n\n\
         | tolerance | ASNR | \\|∂ASNR/∂b\\| (per nm) | value, median (fastest) | value and gradient, median (fastest) | \
         ratio of medians | ratio of fastest |\n|---|---|---|---|---|---|---|\n"
    );
    let mut ratios = Vec::new();
    for tolerance in [1e-6, 1e-4] {
        let overrides = vec![
            "lens.library_interpolation=\"cubic\"".to_owned(),
            "lens.parameter_bias=[0.3]".to_owned(),
            format!("options.tolerance={tolerance:e}"),
        ];
        let row = crate::gradients::side_by_side(&source, &overrides, &[Parameter::LibraryBias(0)], repeats)?;
        ratios.push(row.both / row.value);
        md.push_str(&format!(
            "| {tolerance:e} | {:.4} | {:.4e} | {:.1} ms ({:.1} ms) | {:.1} ms ({:.1} ms) | {:.2}× | {:.2}× |\n",
            row.asnr,
            row.norm,
            1e3 * row.value,
            1e3 * row.value_min,
            1e3 * row.both,
            1e3 * row.both_min,
            row.both / row.value,
            row.both_min / row.value_min
        ));
    }
    let met = ratios.iter().all(|&r| r <= 3.0);
    md.push_str(&format!(
        "\nTarget (at most 3× one evaluation): {}.\n",
        if met { "met" } else { "not met: the lanes cost more than twice the value's OTFs" }
    ));
    Some(md)
}
