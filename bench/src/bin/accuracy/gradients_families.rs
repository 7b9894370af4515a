//! The gradient's cost beside one evaluation for the paper's lens families other than the
//! chromatic and phase lenses (BENCHMARKS.md, "Gradients: the paper's other lens families"):
//! the dispersion-engineered achromat (reduced and true) and the spatially multiplexed achromat
//! (interleaved, on axis and off axis), each the design of `examples/designs.toml` in the
//! paper's scene (`examples/paper-theory.toml` with its `[lens]` replaced), differentiated with
//! respect to its lens keys through the report's chain rules (`report::gradient::gradient`: the
//! keys without an engine parameter of their own, such as `lens.group_delay_range_fs` or
//! `lens.channels_nm[j]`, chain onto the engines' lanes; docs/physics.md, "Gradients: the
//! dispersion-engineered lens", "Gradients: the multiplexed lens").
//!
//! `cargo xtask accuracy --only gradients-families`

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use crate::sections::Tools;

/// The section's heading (after `## `).
pub(crate) const TITLE: &str = "Gradients: the paper's other lens families";

/// One case: its name, the design's name in examples/designs.toml, its `--set` overrides and
/// the keys as `--wrt` spells them.
struct Case {
    name: &'static str,
    design: &'static str,
    overrides: &'static [&'static str],
    keys: &'static [&'static str],
}

const CASES: &[Case] = &[
    Case {
        name: "achromat F/2.5, 5 fs (reduced β)",
        design: "achromat F/2.5, 5 fs (reduced)",
        overrides: &[],
        keys: &[
            "lens.f_number",
            "lens.focal_length_mm",
            "lens.group_delay_range_fs",
            "lens.design_band_nm[0]",
            "lens.design_band_nm[1]",
            "lens.efficiency",
            "lens.transmission",
        ],
    },
    Case {
        name: "achromat D = 0.2 mm, 5 fs (true achromat)",
        design: "achromat D = 0.2 mm, 5 fs",
        overrides: &[],
        keys: &[
            "lens.aperture_diameter_mm",
            "lens.focal_length_mm",
            "lens.design_band_nm[0]",
            "lens.design_band_nm[1]",
        ],
    },
    Case {
        name: "interleaved 750/800/850, on axis",
        design: "interleaved 750/800/850 F/2.5",
        overrides: &[],
        keys: &["lens.f_number", "lens.focal_length_mm", "lens.channels_nm", "lens.efficiency"],
    },
    Case {
        name: "interleaved 750/800/850, 3° off axis",
        design: "interleaved 750/800/850 F/2.5",
        overrides: &["field.x_deg=3"],
        keys: &["lens.f_number", "lens.focal_length_mm", "field.x_deg"],
    },
];

/// The `[lens]` table of the design named `name` in examples/designs.toml (its `[designs.lens]`
/// block up to the next `[[designs]]`), written as `[lens]`.
fn design_lens(designs: &str, name: &str) -> Option<String> {
    let start = designs.find(&format!("name = \"{name}\""))?;
    let rest = &designs[start..];
    let lens = rest.find("[designs.lens]")?;
    let block = &rest[lens + "[designs.lens]".len()..];
    let end = block.find("[[designs]]").unwrap_or(block.len());
    Some(format!("[lens]{}", &block[..end]))
}

/// The paper's scene with its `[lens]` table replaced by the design's, written to `dir`.
fn scene_of(root: &Path, dir: &Path, case: &Case) -> Option<PathBuf> {
    let paper = std::fs::read_to_string(root.join("examples/paper-theory.toml")).ok()?;
    let designs = std::fs::read_to_string(root.join("examples/designs.toml")).ok()?;
    let lens = design_lens(&designs, case.design)?;
    let start = paper.find("\n[lens]")? + 1;
    let end = start + paper[start..].find("\n[source]")? + 1;
    let text = format!("{}{}\n{}", &paper[..start], lens.trim_end(), &paper[end..]);
    let stem: String = case.name.chars().filter(char::is_ascii_alphanumeric).collect();
    let path = dir.join(format!("asnr-bench-family-{stem}.toml"));
    std::fs::write(&path, text).ok()?;
    Some(path)
}

/// One row in one process: the value (`scene::build_from` and `metric::evaluate`) against the
/// value and its gradient (`report::gradient::gradient`), alternately, `repeats` runs after one
/// of each: the ASNR, the gradient's norm in `∂ln ASNR/∂ln key`, `[value, value_min, both,
/// both_min]` (s).
fn in_process(scene: &Path, case: &Case, repeats: usize) -> Option<(f64, f64, [f64; 4])> {
    let source = scene::read(Some(scene)).ok()?;
    let overrides: Vec<String> = case.overrides.iter().map(|s| (*s).to_owned()).collect();
    let keys: Vec<String> = case.keys.iter().map(|s| (*s).to_owned()).collect();
    let first = match report::gradient::gradient(&source, &overrides, &keys) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("gradients-families: {}: {e:#}", case.name);
            return None;
        }
    };
    let value = || {
        let built = scene::build_from(&source, &overrides).unwrap();
        std::hint::black_box(metric::evaluate(&built).unwrap());
    };
    let both = || {
        std::hint::black_box(report::gradient::gradient(&source, &overrides, &keys).unwrap());
    };
    let time = |f: &dyn Fn()| {
        let start = Instant::now();
        f();
        start.elapsed().as_secs_f64()
    };
    let (mut values, mut boths) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        values.push(time(&value));
        boths.push(time(&both));
    }
    let least = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let (value_min, both_min) = (least(&values), least(&boths));
    let norm = (0..first.keys.len()).map(|i| first.relative(i).powi(2)).sum::<f64>().sqrt();
    Some((first.asnr, norm, [crate::median(values), value_min, crate::median(boths), both_min]))
}

/// `repeats` alternate runs of `asnr evaluate` and `asnr gradient` of `case`'s scene.
fn whole_process(asnr: &Path, root: &Path, scene: &Path, case: &Case, repeats: usize) -> Option<[f64; 4]> {
    let sets: Vec<String> = case.overrides.iter().flat_map(|s| ["--set".to_owned(), (*s).to_owned()]).collect();
    let evaluate = || {
        let mut c = Command::new(asnr);
        c.arg("evaluate").arg(scene).args(&sets);
        c
    };
    let gradient = || {
        let mut c = Command::new(asnr);
        c.arg("gradient").arg(scene).args(&sets);
        for k in case.keys {
            c.args(["--wrt", k]);
        }
        c
    };
    crate::process::value_and_gradient_alternately(&evaluate, &gradient, root, repeats)
}

/// The section: the one-process and whole-process tables, or `None` where no case evaluates.
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let repeats = if tools.quick { 11 } else { 31 };
    let process_repeats = if tools.quick { 5 } else { 11 };
    let dir = std::env::temp_dir().join(format!("asnr-bench-families-{}", std::process::id()));
    std::fs::create_dir_all(&dir).ok()?;
    let load = crate::load_average();
    let profile = if cfg!(debug_assertions) { "Dev profile" } else { "Release" };
    let mut inside = Vec::new();
    let mut whole = Vec::new();
    for case in CASES {
        let Some(scene) = scene_of(&tools.root, &dir, case) else {
            eprintln!("gradients-families: {} not found in examples/designs.toml", case.design);
            continue;
        };
        if let Some(row) = in_process(&scene, case, repeats) {
            inside.push((case, row));
        }
        if let Some(asnr) = tools.asnr.as_deref()
            && let Some(t) = whole_process(asnr, &tools.root, &scene, case, process_repeats)
        {
            whole.push((case, t));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    if inside.is_empty() {
        return None;
    }
    let mut md = format!(
        "## {TITLE}\n\n`cargo xtask accuracy --only gradients-families` (bench/src/bin/accuracy/gradients_families.rs): \
         the designs of examples/designs.toml in the paper's scene (examples/paper-theory.toml with its `[lens]` \
         replaced; its 50 nm band and tolerance 1e-6), one evaluation against the evaluation and its gradient over \
         the lens keys listed (`lens.channels_nm` is its three wavelengths). The dispersion-engineered lens's keys \
         chain onto the defocus lane through the true-delay fraction β and onto the design wavelength's lane, a band \
         edge is a limit of the signal's integrals (docs/physics.md, \"Gradients: the dispersion-engineered lens\"); \
         the interleaved lens's keys chain onto each channel's lanes (\"Gradients: the multiplexed lens\"). In one \
         process (`metric::evaluate` against `report::gradient::gradient`, the scene built inside each timing), \
         {profile}, medians (and fastest) of {repeats} alternate runs after one of each, load average {load} at the \
         start; ‖∂ln ASNR/∂ln key‖ is the norm of the relative sensitivities.\n\n| case | keys | ASNR | ‖∂ln \
         ASNR/∂ln key‖ | value, median (fastest) | value and gradient, median (fastest) | ratio of medians | ratio \
         of fastest |\n|---|---|---|---|---|---|---|---|\n"
    );
    for (case, (asnr, norm, t)) in &inside {
        md.push_str(&format!(
            "| {} | {} | {asnr:.4} | {norm:.3e} {}\n",
            case.name,
            case.keys.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", "),
            crate::gradients::timing_cells(*t, 2)
        ));
    }
    if !whole.is_empty() {
        md.push_str(&format!(
            "\nWhole process: `asnr evaluate SCENE` against `asnr gradient SCENE --wrt KEY …` (the release binary, \
             wall clock, medians (and fastest) of {process_repeats} alternate runs after one of each).\n\n| case | \
             value, median (fastest) | value and gradient, median (fastest) | ratio of medians | ratio of fastest \
             |\n|---|---|---|---|---|\n"
        ));
        for (case, t) in &whole {
            md.push_str(&format!("| {} {}\n", case.name, crate::gradients::timing_cells(*t, 1)));
        }
    }
    let verdicts: Vec<String> = inside
        .iter()
        .map(|(case, (_, _, t))| format!("{}: {}", case.name, crate::gradients::within_three(t[2], t[0])))
        .collect();
    md.push_str(&format!(
        "\nTarget (issue: the gradient over K ≤ 16 keys at most 3× one evaluation; in one process): {}.\n",
        verdicts.join("; ")
    ));
    Some(md)
}
