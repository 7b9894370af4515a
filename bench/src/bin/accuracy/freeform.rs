//! The README's freeform design example ("Designing with the ASNR"): the paper's aperture as the
//! Binary 2 metalens of `examples/phase-binary2.toml` at a 100 nm band, A1 fixed and the next 11
//! Binary 2 terms free, searched by `asnr optimize --method gradient`, beside the hyperbolic
//! profile and the 2-term COBYLA search the README already shows. Each run is the release binary
//! timed from outside (wall clock, one run), its evaluations and result from its JSON, and the
//! optimum evaluated again at the default tolerance 1e-6.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::sections::Tools;

/// The section's heading.
pub(crate) const TITLE: &str = "Freeform design: 11 Binary 2 terms by the gradient";

/// The bounds of the free terms `lens.binary2[1..=11]` (radians of phase at ρ = 1): A2 and A3 as
/// the README's 2-term search, ±5 rad for the higher terms.
pub(crate) fn free_terms() -> Vec<String> {
    (1..=11)
        .flat_map(|i| {
            let range = match i {
                1 => "-20:30",
                2 => "-10:10",
                _ => "-5:5",
            };
            ["--over".to_owned(), format!("lens.binary2[{i}]={range}")]
        })
        .collect()
}

/// One run of the release binary from the workspace root: its JSON and wall time.
fn run(asnr: &Path, root: &Path, args: &[String]) -> Option<(Value, f64)> {
    eprintln!("  freeform: asnr {}", args.join(" "));
    let (stdout, wall) = crate::process::timed(Command::new(asnr).args(args), root)?;
    eprintln!("  {wall:.2} s wall");
    Some((serde_json::from_str(&stdout).ok()?, wall))
}

fn strings(words: &[&str]) -> Vec<String> {
    words.iter().map(|w| (*w).to_owned()).collect()
}

/// The ASNR at a search's optimum (`best`, its keys and values) at the default tolerance.
fn at_optimum(asnr: &Path, root: &Path, best: &Value) -> Option<f64> {
    let mut args = strings(&["evaluate", "examples/phase-binary2.toml", "--set", "spectrum.range_nm=100", "--json"]);
    for (key, value) in best.as_object()? {
        args.push("--set".to_owned());
        args.push(format!("{key}={}", value.as_f64()?));
    }
    run(asnr, root, &args)?.0["asnr"].as_f64()
}

pub(crate) fn section(tools: &Tools) -> Option<String> {
    let Some(asnr) = tools.asnr.as_deref() else {
        eprintln!("  freeform: no release asnr binary (--asnr)");
        return None;
    };
    let root = &tools.root;
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".to_owned());
    let (hyperbolic, hyperbolic_s) = run(
        asnr,
        root,
        &strings(&["evaluate", "examples/phase-binary2.toml", "--set", "spectrum.range_nm=100", "--json"]),
    )?;
    let cobyla_args = strings(&[
        "optimize",
        "examples/phase-binary2.toml",
        "--set",
        "spectrum.range_nm=100",
        "--over",
        "lens.binary2[1]=-20:30",
        "--over",
        "lens.binary2[2]=-10:10",
        "--tolerance",
        "1e-4",
        "--xtol",
        "1e-3",
        "--json",
    ]);
    let (cobyla, cobyla_s) = run(asnr, root, &cobyla_args)?;
    let mut freeform_args =
        strings(&["optimize", "examples/phase-binary2.toml", "--set", "spectrum.range_nm=100", "--method", "gradient"]);
    freeform_args.extend(free_terms());
    freeform_args.extend(strings(&["--tolerance", "1e-4", "--xtol", "1e-3", "--json"]));
    let (freeform, freeform_s) = run(asnr, root, &freeform_args)?;
    let cobyla_asnr = at_optimum(asnr, root, &cobyla["best"])?;
    let freeform_asnr = at_optimum(asnr, root, &freeform["best"])?;
    let hyperbolic_asnr = hyperbolic["asnr"].as_f64()?;
    let number = |v: &Value, key: &str| v[key].as_f64().unwrap_or(f64::NAN);
    let count = |v: &Value, key: &str| v[key].as_u64().unwrap_or(0);
    let coefficients: Vec<String> =
        (1..=11).map(|i| format!("{:.3}", number(&freeform["best"], &format!("lens.binary2[{i}]")))).collect();
    let at_bound: Vec<String> = freeform["at_bound"]
        .as_object()
        .map(|m| m.iter().filter(|(_, v)| v.as_bool() == Some(true)).map(|(k, _)| format!("`{k}`")).collect())
        .unwrap_or_default();
    let mut out = format!(
        "## {TITLE}\n\n\
         The README's freeform example (\"Designing with the ASNR\"): the paper's aperture as the Binary 2 \
         metalens of `examples/phase-binary2.toml` at a 100 nm band, A1 fixed (it sets the focal length) and \
         `lens.binary2[1]` to `lens.binary2[11]` free (A2 in −20…30, A3 in −10…10, the others in −5…5 rad), \
         searched by projected L-BFGS on the exact gradient after the Halton start set, each point at \
         `--tolerance 1e-4`; beside it the hyperbolic profile and the README's 2-term COBYLA search. Release \
         binary, each run timed from outside (wall clock, one run, whole process), load average {load} (1, 5, \
         15 min) on a shared machine; each optimum's ASNR is `asnr evaluate` there at the default tolerance \
         1e-6. Generated by `cargo xtask accuracy --only freeform`.\n\n\
         | design | evaluations | wall | ASNR at the optimum | vs hyperbolic |\n|---|---|---|---|---|\n\
         | hyperbolic profile (`asnr evaluate`) | 1 | {hyperbolic_s:.2} s | {hyperbolic_asnr:.4} | — |\n\
         | A2, A3 by COBYLA (README) | {} ({} start points) | {cobyla_s:.2} s | {cobyla_asnr:.4} | {:+.2} % |\n\
         | A2…A12 by the gradient (11 keys) | {} ({} start points) | {freeform_s:.2} s | {freeform_asnr:.4} | {:+.2} % |\n\n",
        count(&cobyla, "evaluations"),
        count(&cobyla, "start_points"),
        100.0 * (cobyla_asnr / hyperbolic_asnr - 1.0),
        count(&freeform, "evaluations"),
        count(&freeform, "start_points"),
        100.0 * (freeform_asnr / hyperbolic_asnr - 1.0),
    );
    out.push_str(&format!(
        "The freeform optimum: A2…A12 = {} rad; stopped: {}; the projected gradient's largest component {:.2e}; at a bound: {}.\n\n\
         Command: `asnr {}`.\n\n",
        coefficients.join(", "),
        freeform["stopped"].as_str().unwrap_or("?"),
        number(&freeform, "projected_gradient"),
        if at_bound.is_empty() { "none".to_owned() } else { at_bound.join(", ") },
        freeform_args.join(" "),
    ));
    Some(out)
}
