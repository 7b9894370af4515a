//! The F-number and focal-length gradient's cost beside one evaluation, whole process (a part of
//! BENCHMARKS.md's "Gradients" section): `asnr evaluate` against `asnr gradient --wrt
//! lens.f_number --wrt lens.focal_length_mm` on the paper's lens (the closed form: the
//! derivative on its own rule in t, docs/physics.md "Gradients: the F-number and the focal
//! length on the value's rule"), on the N-BK7 singlet at 100 nm and on the harmonic lens of
//! `examples/harmonic.toml` (the per-frequency product rule: the defocus lane `w ∂H/∂w` of its
//! Bessel and asymptotic forms beside each value), at the tolerances 1e-6 and 1e-4. Medians of
//! alternate runs.

use std::path::Path;
use std::process::Command;

use crate::sections::Tools;

/// One row: the case, the tolerance, the value's and the gradient's wall times (medians and
/// fastest, s).
struct Row {
    case: &'static str,
    tolerance: f64,
    value: f64,
    both: f64,
    value_min: f64,
    both_min: f64,
}

/// The paper's scene as the singlet the tests write: the chromatic lens replaced by one N-BK7
/// element (its efficiency and transmission lines dropped, as the refractive family takes none),
/// at a 100 nm band; written to `dir`.
fn singlet(root: &Path, dir: &Path) -> Option<std::path::PathBuf> {
    let paper = std::fs::read_to_string(root.join("examples/paper-theory.toml")).ok()?;
    let kept: Vec<&str> =
        paper.lines().filter(|l| !(l.starts_with("efficiency") || l.starts_with("transmission"))).collect();
    let text = kept
        .join("\n")
        .replace("model = \"chromatic\"", "model = \"refractive\"\nglass = \"N-BK7\"\nelements = 1")
        .replace("range_nm = 50.0", "range_nm = 100.0");
    let path = dir.join("asnr-bench-singlet.toml");
    std::fs::write(&path, text).ok()?;
    Some(path)
}

/// `repeats` alternate runs of `asnr evaluate` and `asnr gradient` on `scene` at `tolerance`.
fn row(asnr: &Path, root: &Path, case: &'static str, scene: &Path, tolerance: f64, repeats: usize) -> Option<Row> {
    let tol = format!("{tolerance:e}");
    let evaluate = || {
        let mut c = Command::new(asnr);
        c.arg("evaluate").arg(scene).args(["--tolerance", &tol]);
        c
    };
    let gradient = || {
        let mut c = Command::new(asnr);
        c.arg("gradient").arg(scene).args([
            "--wrt",
            "lens.f_number",
            "--wrt",
            "lens.focal_length_mm",
            "--tolerance",
            &tol,
        ]);
        c
    };
    let [value, value_min, both, both_min] =
        crate::process::value_and_gradient_alternately(&evaluate, &gradient, root, repeats)?;
    Some(Row { case, tolerance, value, both, value_min, both_min })
}

/// The same pairs in one process (`metric::evaluate` against `metric::gradient` over both keys,
/// the scene built inside each timing; `gradients::side_by_side`): the work itself, without the
/// process's start; `(case, tolerance, row)`.
fn in_process(root: &Path, singlet: &Path, repeats: usize) -> Vec<(&'static str, f64, crate::gradients::Row)> {
    let keys = [metric::Parameter::FNumber, metric::Parameter::FocalLength];
    let mut rows = Vec::new();
    for tolerance in [1e-6, 1e-4] {
        let set = vec![format!("options.tolerance={tolerance:e}")];
        for (case, path) in [
            (PAPER, root.join("examples/paper-theory.toml")),
            (SINGLET, singlet.to_path_buf()),
            (HARMONIC, root.join("examples/harmonic.toml")),
        ] {
            let Ok(source) = scene::read(Some(&path)) else { continue };
            rows.extend(crate::gradients::side_by_side(&source, &set, &keys, repeats).map(|r| (case, tolerance, r)));
        }
    }
    rows
}

const PAPER: &str = "paper lens (closed form)";
const SINGLET: &str = "N-BK7 singlet, 100 nm (per-frequency rule)";
const HARMONIC: &str = "harmonic lens p = 5, 50 nm (per-frequency rule)";

/// The table and its text, or `None` without the `asnr` binary.
pub(crate) fn markdown(tools: &Tools) -> Option<String> {
    let asnr = tools.asnr.as_deref()?;
    let repeats = if tools.quick { 5 } else { 11 };
    let paper = tools.root.join("examples/paper-theory.toml");
    let harmonic = tools.root.join("examples/harmonic.toml");
    let singlet = singlet(&tools.root, &std::env::temp_dir())?;
    let mut rows = Vec::new();
    for tolerance in [1e-6, 1e-4] {
        rows.extend(row(asnr, &tools.root, PAPER, &paper, tolerance, repeats));
        rows.extend(row(asnr, &tools.root, SINGLET, &singlet, tolerance, repeats));
        rows.extend(row(asnr, &tools.root, HARMONIC, &harmonic, tolerance, repeats));
    }
    let inside = in_process(&tools.root, &singlet, if tools.quick { 11 } else { 31 });
    let _ = std::fs::remove_file(&singlet);
    if rows.is_empty() {
        return None;
    }
    let mut md = format!(
        "\nThe F-number and the focal length, whole process: `asnr evaluate SCENE --tolerance T` against `asnr \
         gradient SCENE --wrt lens.f_number --wrt lens.focal_length_mm --tolerance T` (the release binary, wall \
         clock, medians of {repeats} alternate runs after one of each, load average {} at the start). On the paper's \
         lens (examples/paper-theory.toml) the closed form carries ∂O/∂ln K on its own rule in t and the frequency \
         rule's accepted weights integrate it (docs/physics.md, \"Gradients: the F-number and the focal length on \
         the value's rule\"): the gradient is one more mean. The N-BK7 singlet (the same scene, the lens one N-BK7 \
         element, a 100 nm band) and the harmonic lens (examples/harmonic.toml, six orders) take the per-frequency \
         product rule, whose Bessel and asymptotic forms of the defocused OTF carry their derivative w ∂H/∂w beside \
         each value (the lane differentiated analytically on the same recurrence and terms), integrated with the \
         weights of the spectral level and the frequency panels the value accepts: there too the gradient is one \
         more mean and one OTF at Nyquist.\n\n",
        crate::load_average()
    );
    md.push_str(
        "| scene | tolerance | value, median (fastest) | value and ∂/∂F#, ∂/∂f0, median (fastest) | ratio of medians | \
         ratio of fastest |\n|---|---|---|---|---|---|\n",
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {:e} {}\n",
            r.case,
            r.tolerance,
            crate::gradients::timing_cells([r.value, r.value_min, r.both, r.both_min], 1)
        ));
    }
    if !inside.is_empty() {
        md.push_str(
            "\nThe same in one process (`metric::evaluate` against `metric::gradient` over both keys, the scene built \
             inside each timing, as the tables above): the work without the process's start.\n\n| scene | tolerance | \
             value, median (fastest) | value and ∂/∂F#, ∂/∂f0, median (fastest) | ratio of medians | ratio of fastest \
             |\n|---|---|---|---|---|---|\n",
        );
        for (case, tolerance, r) in &inside {
            md.push_str(&format!(
                "| {case} | {tolerance:e} {}\n",
                crate::gradients::timing_cells([r.value, r.value_min, r.both, r.both_min], 2)
            ));
        }
    }
    md.push_str(&format!(
        "\nTarget (issue: at most 3× one evaluation; whole process): {}.\n",
        rows.iter()
            .map(|r| format!("{} at {:e}: {}", r.case, r.tolerance, crate::gradients::within_three(r.both, r.value)))
            .collect::<Vec<_>>()
            .join("; ")
    ));
    Some(md)
}
