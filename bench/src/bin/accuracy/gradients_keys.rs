//! The gradient's cost beside one evaluation for the keys whose lanes do not all ride on the
//! value's radial or closed-form rules (a part of BENCHMARKS.md's "Gradients" section): the
//! F-number and focal length beside Seidel terms on axis (the overlap engine's defocus lane),
//! the Gaussian band's centre and range where the OTF depends on direction (the overlap engine,
//! the FFT path of a phase map, lateral colour off axis, a decentred iris), a top-hat band's
//! centre and range and a blackbody's temperature over a band (lanes on the per-frequency
//! product rule's own sums), the Seidel terms at zero (the closed form's lanes along ρ⁴ and
//! ρ² on its own rule, a pass beside the value's), and the obscuration above 0 (the annulus's
//! inner edge moving on the FFT path). In one process (`metric::evaluate` against `metric::gradient`, the scene
//! built inside each timing, alternately, medians: `gradients::side_by_side`) and, where the
//! work is short beside the process's start, whole process (`asnr evaluate` against `asnr
//! gradient`, alternately, medians).
//!
//! `cargo xtask accuracy --only gradients`

use std::path::{Path, PathBuf};
use std::process::Command;

use metric::Parameter;
use optics::SeidelTerm;

use crate::gradients::Row;
use crate::sections::Tools;

/// One case: its name, the scene's file, its `--set` overrides, the keys (as `--wrt` spells
/// them and as [`Parameter`]s), the in-process repeats' share (1 = all, else fewer for a slow
/// case) and whether a whole-process row is taken too.
struct Case {
    name: &'static str,
    scene: PathBuf,
    overrides: Vec<String>,
    keys: &'static [&'static str],
    parameters: Vec<Parameter>,
    slow: bool,
    whole_process: bool,
}

fn owned(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| (*s).to_owned()).collect()
}

const SPECTRAL: &[&str] = &["spectrum.center_nm", "spectrum.range_nm"];
const APERTURE: &[&str] = &["lens.f_number", "lens.focal_length_mm"];
const SEIDEL: &[&str] = &["lens.spherical_um", "lens.astigmatism_um", "lens.field_curvature_um"];

/// The paper's scene under a 3000 K blackbody (its flat radiance replaced; the test's scene of
/// report/src/gradient.rs), written to `dir`.
fn blackbody(root: &Path, dir: &Path) -> Option<PathBuf> {
    let paper = std::fs::read_to_string(root.join("examples/paper-theory.toml")).ok()?;
    let text = paper
        .replace("kind = \"flat\"", "kind = \"blackbody\"\ntemperature_k = 3000.0\nscale = 2e-3")
        .replace("radiance_w_m2_sr_nm = 0.025", "");
    if !text.contains("blackbody") || text.contains("radiance_w_m2_sr_nm") {
        return None;
    }
    let path = dir.join("asnr-bench-blackbody.toml");
    std::fs::write(&path, text).ok()?;
    Some(path)
}

/// The cubic phase map of examples/phase-map-cubic.toml, its formula written on 1 µm cells
/// (1344 × 1344, as the spectral test of report/src/gradient.rs), and the scene reading it,
/// both in `dir`; the scene's path.
fn cubic_map(root: &Path, dir: &Path) -> Option<PathBuf> {
    let bytes = scene::npy::hyperbolic_cubic_map(1344, 1e-6, 3.36e-3, 800e-9, 0.672e-3, 30.0);
    std::fs::write(dir.join("asnr-bench-cubic.npy"), &bytes).ok()?;
    let text = std::fs::read_to_string(root.join("examples/phase-map-cubic.toml"))
        .ok()?
        .replace("\"../target/phase-maps/cubic-f2.5.npy\"", "\"asnr-bench-cubic.npy\"")
        .replace("phase_map_pitch_um = 0.5", "phase_map_pitch_um = 1.0");
    if !text.contains("asnr-bench-cubic.npy") || !text.contains("pitch_um = 1.0") {
        return None;
    }
    let path = dir.join("asnr-bench-cubic.toml");
    std::fs::write(&path, text).ok()?;
    Some(path)
}

fn cases(root: &Path, dir: &Path) -> Vec<Case> {
    let paper = root.join("examples/paper-theory.toml");
    let spectral = vec![Parameter::SpectrumCenter, Parameter::SpectrumRange];
    let mut cases = vec![
        Case {
            name: "F#, f0 beside coma 0.3 µm on axis (overlap engine, defocus lane), 1e-6",
            scene: paper.clone(),
            overrides: owned(&["lens.coma_um=0.3", "options.tolerance=1e-6"]),
            keys: APERTURE,
            parameters: vec![Parameter::FNumber, Parameter::FocalLength],
            slow: false,
            whole_process: true,
        },
        Case {
            name: "F#, f0 beside coma 0.3 µm on axis, 10 nm band, 1e-6",
            scene: paper.clone(),
            overrides: owned(&["lens.coma_um=0.3", "spectrum.range_nm=10", "options.tolerance=1e-6"]),
            keys: APERTURE,
            parameters: vec![Parameter::FNumber, Parameter::FocalLength],
            slow: false,
            whole_process: true,
        },
        Case {
            name: "centre, range: coma 0.3 µm on axis (overlap engine)",
            scene: paper.clone(),
            overrides: owned(&["lens.coma_um=0.3"]),
            keys: SPECTRAL,
            parameters: spectral.clone(),
            slow: false,
            whole_process: true,
        },
        Case {
            name: "centre, range: lateral colour at 5° (exact 1-D engine, over azimuth)",
            scene: paper.clone(),
            overrides: owned(&["field.x_deg=5"]),
            keys: SPECTRAL,
            parameters: spectral.clone(),
            slow: false,
            whole_process: true,
        },
        Case {
            name: "centre, range: decentred iris (examples/decentred-iris.toml)",
            scene: root.join("examples/decentred-iris.toml"),
            overrides: vec![],
            keys: SPECTRAL,
            parameters: spectral.clone(),
            slow: false,
            whole_process: true,
        },
    ];
    if let Some(map) = cubic_map(root, dir) {
        cases.push(Case {
            name: "centre, range: cubic phase map, 10 nm (FFT path, 256 samples)",
            scene: map,
            overrides: owned(&["spectrum.range_nm=10", "options.pupil_samples=256"]),
            keys: SPECTRAL,
            parameters: spectral,
            slow: true,
            whole_process: false,
        });
    }
    cases.push(Case {
        name: "centre, range: 50 nm top-hat on axis (the edges on the value's rule)",
        scene: paper.clone(),
        overrides: owned(&["spectrum.shape=\"tophat\""]),
        keys: SPECTRAL,
        parameters: vec![Parameter::SpectrumCenter, Parameter::SpectrumRange],
        slow: false,
        whole_process: true,
    });
    if let Some(bb) = blackbody(root, dir) {
        cases.push(Case {
            name: "temperature: 3000 K blackbody over the 50 nm band",
            scene: bb,
            overrides: vec![],
            keys: &["source.temperature_k"],
            parameters: vec![Parameter::Temperature],
            slow: false,
            whole_process: true,
        });
    }
    cases.push(Case {
        name: "obscuration 0.3 (the annulus's inner edge on the FFT path)",
        scene: paper.clone(),
        overrides: owned(&["lens.obscuration=0.3"]),
        keys: &["lens.obscuration"],
        parameters: vec![Parameter::Obscuration],
        // about 2 s a value on the FFT path: three runs, no whole-process row
        slow: true,
        whole_process: false,
    });
    cases.push(Case {
        name: "Seidel terms at zero (the closed form's lanes)",
        scene: paper,
        overrides: vec![],
        keys: SEIDEL,
        parameters: vec![
            Parameter::Seidel(SeidelTerm::Spherical),
            Parameter::Seidel(SeidelTerm::Astigmatism),
            Parameter::Seidel(SeidelTerm::FieldCurvature),
        ],
        slow: false,
        whole_process: true,
    });
    cases
}

/// Wall times of a whole-process pair, s: the value's and the gradient's medians and fastest.
struct Wall {
    value: f64,
    both: f64,
    value_min: f64,
    both_min: f64,
}

/// `repeats` alternate runs of `asnr evaluate` and `asnr gradient` of `case`.
fn whole_process(asnr: &Path, root: &Path, case: &Case, repeats: usize) -> Option<Wall> {
    let sets: Vec<String> = case.overrides.iter().flat_map(|s| ["--set".to_owned(), s.clone()]).collect();
    let evaluate = || {
        let mut c = Command::new(asnr);
        c.arg("evaluate").arg(&case.scene).args(&sets);
        c
    };
    let gradient = || {
        let mut c = Command::new(asnr);
        c.arg("gradient").arg(&case.scene).args(&sets);
        for k in case.keys {
            c.args(["--wrt", k]);
        }
        c
    };
    let [value, value_min, both, both_min] =
        crate::process::value_and_gradient_alternately(&evaluate, &gradient, root, repeats)?;
    Some(Wall { value, both, value_min, both_min })
}

/// The tables and their text.
pub(crate) fn markdown(tools: &Tools) -> Option<String> {
    markdown_of(tools, &[])
}

/// [`markdown`] of the cases whose names contain one of `names` (all where it is empty):
/// `accuracy --keys NAME[,NAME]` writes them into `target/BENCHMARKS-keys.md`, the rows to put
/// in BENCHMARKS.md's tables in place of their old ones.
pub(crate) fn markdown_of(tools: &Tools, names: &[&str]) -> Option<String> {
    let repeats = if tools.quick { 7 } else { 15 };
    let dir = std::env::temp_dir().join(format!("asnr-bench-keys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).ok()?;
    let mut cases = cases(&tools.root, &dir);
    cases.retain(|c| names.is_empty() || names.iter().any(|n| c.name.contains(n)));
    let load = crate::load_average();
    let mut inside: Vec<(&Case, Row)> = Vec::new();
    let mut outside: Vec<(&Case, Wall)> = Vec::new();
    for case in &cases {
        let Ok(source) = scene::read(Some(&case.scene)) else {
            eprintln!("gradients: {} did not read", case.scene.display());
            continue;
        };
        let runs = if case.slow { 3 } else { repeats };
        match crate::gradients::side_by_side(&source, &case.overrides, &case.parameters, runs) {
            Some(r) => inside.push((case, r)),
            None => eprintln!("gradients: {} did not evaluate", case.name),
        }
        if case.whole_process
            && let Some(asnr) = tools.asnr.as_deref()
            && let Some(w) = whole_process(asnr, &tools.root, case, if tools.quick { 5 } else { 11 })
        {
            outside.push((case, w));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    if inside.is_empty() {
        return None;
    }
    let profile = if cfg!(debug_assertions) { "Dev profile" } else { "Release" };
    let mut md = format!(
        "\nThe keys whose lanes are not all the radial engine's or a closed form's: the F-number and focal length \
         beside Seidel terms on axis (the paper's lens, examples/paper-theory.toml, on the overlap engine: the \
         defocus lane `W020 ρ²` on the value's nodes, docs/physics.md \"Gradients: the F-number and the focal length \
         with Seidel terms\"), the Gaussian band's centre and range where the OTF depends on direction (\"Gradients: \
         the spectrum where the OTF depends on direction\"), a 50 nm top-hat's centre and range and a 3000 K \
         blackbody's temperature over the paper's band (lanes on the per-frequency product rule's own sums: \"Gradients: \
         a top-hat's edges\", \"Gradients: a line's wavelength and a blackbody's temperature\"), \
         and the Seidel terms at zero on the paper's lens (the closed form's lanes along ρ⁴ and ρ² on its own rule, \
         \"Gradients: Seidel terms at zero\"), and an obscuration of 0.3 (the annulus's inner edge moving on the FFT \
         path, \"Gradients: the edge's motion on the FFT path\"). In one process: {profile}, the scene built inside each timing, medians (and fastest) of \
         {repeats} alternate runs after one of each (3 for the phase map and the obscuration), load average {load} at the start.\n\n| \
         case | keys | ASNR | value, median (fastest) | value and gradient, median (fastest) | ratio of medians | \
         ratio of fastest |\n|---|---|---|---|---|---|---|\n"
    );
    for (case, r) in &inside {
        md.push_str(&format!(
            "| {} | {} | {:.4} {}\n",
            case.name,
            case.keys.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", "),
            r.asnr,
            crate::gradients::timing_cells([r.value, r.value_min, r.both, r.both_min], 2)
        ));
    }
    md.push_str(&format!(
        "\nTarget (at most 3× one evaluation, in one process): {}.\n",
        inside
            .iter()
            .map(|(c, r)| format!("{}: {}", c.name, crate::gradients::within_three(r.both, r.value)))
            .collect::<Vec<_>>()
            .join("; ")
    ));
    if !outside.is_empty() {
        md.push_str(&format!(
            "\nThe same, whole process: `asnr evaluate SCENE --set …` against `asnr gradient SCENE --set … --wrt KEY …` \
             (the release binary, wall clock, medians (and fastest) of {} alternate runs after one of each, load average \
             {} at the start).\n\n| case | value, median (fastest) | value and gradient, median (fastest) | ratio of \
             medians | ratio of fastest |\n|---|---|---|---|---|\n",
            if tools.quick { 5 } else { 11 },
            crate::load_average()
        ));
        for (case, w) in &outside {
            md.push_str(&format!(
                "| {} {}\n",
                case.name,
                crate::gradients::timing_cells([w.value, w.value_min, w.both, w.both_min], 1)
            ));
        }
        md.push_str(&format!(
            "\nTarget (at most 3× one evaluation, whole process): {}.\n",
            outside
                .iter()
                .map(|(c, w)| format!("{}: {}", c.name, crate::gradients::within_three(w.both, w.value)))
                .collect::<Vec<_>>()
                .join("; ")
        ));
    }
    Some(md)
}
