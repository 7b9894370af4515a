//! Workspace automation, run as `cargo xtask <task>` (the cargo-xtask convention, as in
//! rust-analyzer): every check and chore of the project lives here, in Rust, instead of in
//! shell scripts. `.cargo/config.toml` aliases `cargo xtask` to this binary.
//!
//! Tasks:
//! - `accuracy [--quick] [--designs] [--keys CASE[,CASE]] [--only NAME[,NAME]]`: the accuracy-versus-time report
//!   (`BENCHMARKS.md`; `--designs`: the designs given as data alone, into `target/BENCHMARKS-designs.md`; `--keys`: the
//!   named gradient cost cases alone, into `target/BENCHMARKS-keys.md`).
//! - `ci`: the full check that `.ci/run` and the README point to.
//! - `data [--check | --maps]`: the generated data files of `examples/data/` (`data.rs`); `--maps`
//!   the examples' 2-D phase maps under `target/phase-maps/`.
//! - `emva`: `asnr characterize` against the `emva1288` package's camera model (`emva.rs`).
//! - `python`: the wheel installed into a fresh virtual environment, its pytest suite and the
//!   README's Python blocks (`python.rs`).
//! - `torch`: the PyTorch bridge `asnr.torch` tested in a pinned `target/torch-venv` (`torch.rs`;
//!   not in `ci`: torch's download takes minutes).
//! - `wheel`: the Python package as one portable wheel, built and checked (`wheel.rs`).
//! - `figures`: the paper's Fig. 2a, 2b and SI Fig. S9, regenerated into `docs/figures/`.
//! - `readme`: every command of the README's ```` ```sh ```` blocks, run as written (`readme.rs`).
//! - `tidy`: the architecture invariants (layout, dependency direction, workspace dependencies
//!   and lints, crate docs, no file pointing outside the repository).
//! - `stress [--quick]`: the numerical stress sweep of the metric (`stress.rs`).
//!
//! Each task is a module with a `run(root)` entry point; add new tasks to [`TASKS`] and `main`.

mod accuracy;
mod ci;
mod cmd;
mod data;
mod emva;
mod features;
mod figures;
mod python;
mod readme;
mod stress;
mod tidy;
mod torch;
mod wheel;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Every task with its one-line description, in the order `cargo xtask help` lists them.
const TASKS: &[(&str, &str)] = &[
    (
        "accuracy",
        "accuracy against time of every method: BENCHMARKS.md and its plot (--quick: fewer settings; --designs: the designs given as data alone; --keys: named gradient cost cases alone)",
    ),
    (
        "ci",
        "full check: fmt, tidy, clippy -D warnings, tests, the Python package's tests, the emva1288 cross-check, README commands, reduced stress grid, docs -D warnings",
    ),
    (
        "data",
        "(re)write the generated data files of examples/data/ (the spectrometer table; --check: compare only; --maps: the 2-D phase maps of the examples under target/phase-maps/)",
    ),
    (
        "emva",
        "asnr characterize checked on a series from the emva1288 package's camera model (a pinned venv in target/)",
    ),
    (
        "python",
        "the wheel installed with its extras into a fresh target/python-venv (pinned), no Rust on PATH: its pytest suite against the CLI and the README's Python blocks",
    ),
    (
        "torch",
        "the PyTorch bridge (asnr.torch) tested against the CLI, the wheel in a pinned target/torch-venv (reused; not in ci: torch's download takes minutes)",
    ),
    ("figures", "the paper's Fig. 2a, 2b and S9 (SVG + CSV) into docs/figures/, from a release build"),
    ("readme", "run every command of the README's ```sh blocks as written; none may change git status"),
    (
        "wheel",
        "the Python package as one portable abi3 wheel (x86-64-v3, manylinux2014) in target/wheels/, checked by auditwheel, abi3audit and its disassembly",
    ),
    (
        "tidy",
        "architecture invariants: layout, dependency direction, workspace deps and lints, crate docs, no paths outside the repository",
    ),
    ("stress", "numerical stress sweep of the metric, checked and timed (--quick: the CI-sized grid)"),
];

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let task = args.first().map(String::as_str);
    if let Some(extra) = args.get(1).filter(|_| !matches!(task, Some("stress" | "accuracy" | "data"))) {
        eprintln!("xtask: error: unexpected argument `{extra}` (this task takes no arguments)");
        return ExitCode::FAILURE;
    }
    let root = project_root();
    let result = match task {
        None | Some("help" | "-h" | "--help") => {
            print!("{}", help());
            Ok(())
        }
        Some("accuracy") => accuracy::run(&root, &args[1..]),
        Some("ci") => ci::run(&root),
        Some("data") => data::run(&root, &args[1..]),
        Some("emva") => emva::run(&root),
        Some("figures") => figures::run(&root),
        Some("python") => python::run(&root),
        Some("readme") => readme::run(&root),
        Some("tidy") => tidy::run(&root),
        Some("torch") => torch::run(&root),
        Some("wheel") => wheel::run(&root),
        Some("stress") => stress::run(&root, &args[1..]),
        Some(other) => {
            eprint!("{}", help());
            Err(anyhow::anyhow!("unknown task `{other}`"))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("xtask: error: {err:#}");
            ExitCode::FAILURE
        }
    }
}

/// The usage text: one line per task.
fn help() -> String {
    let mut text = String::from("usage: cargo xtask <task>\n\ntasks:\n");
    for (name, description) in TASKS {
        text.push_str(&format!("  {name:<8} {description}\n"));
    }
    text.push_str("  help     print this list\n");
    text
}

/// The workspace root: the parent of this crate's folder.
fn project_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives one level below the workspace root")
        .to_path_buf()
}
