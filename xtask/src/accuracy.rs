//! `cargo xtask accuracy [--quick] [--designs] [--keys CASE[,CASE]] [--only NAME[,NAME]]`: the accuracy-versus-time report (`--designs`: the
//! rows of the designs given as data alone, into `target/BENCHMARKS-designs.md`; `--keys`: the gradient's cost rows
//! of the named cases of `gradients_keys` (a part of each name) alone, into `target/BENCHMARKS-keys.md`; `--only`: the named
//! stand-alone sections alone, each replacing its own section of `BENCHMARKS.md`). Builds and runs the example
//! `bench/src/bin/accuracy/` (`main.rs` and its modules, the `asnr-bench` crate) in release (xtask depends on no
//! project crate), which writes `BENCHMARKS.md` and `docs/benchmarks/accuracy.svg` at the
//! workspace root.
//!
//! Before that it builds the release `asnr` binary (the report times a whole `asnr sweep`) and
//! prepares the numpy baseline `xtask/baselines/numpy_table.py`: a virtual environment in
//! `target/baselines-venv` with the pinned `xtask/baselines/requirements.txt` (made once, remade
//! when the requirements change), else the system `python3` if it imports numpy; when neither
//! works the report says "numpy not available: row skipped". Into that environment it installs
//! the Python package (`pip install ./python`, release) for the map's `evaluate_many` row
//! (`python/bench/map.py`).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{Result, bail};

use crate::cmd;

/// The virtual environment of the baseline, relative to the workspace root.
const VENV: &str = "target/baselines-venv";
const REQUIREMENTS: &str = "xtask/baselines/requirements.txt";

/// Build and run the report from the workspace `root`.
pub(crate) fn run(root: &Path, args: &[String]) -> Result<()> {
    let mut rest = args.iter();
    while let Some(arg) = rest.next() {
        match arg.as_str() {
            "--quick" | "--designs" | "--sweep" => {}
            "--only" | "--keys" if rest.next().is_some() => {}
            bad => bail!(
                "unknown or incomplete argument `{bad}` (usage: cargo xtask accuracy [--quick] [--designs] [--sweep] [--keys CASE[,CASE]] [--only NAME[,NAME]])"
            ),
        }
    }
    cmd::run(&mut cmd::cargo(root, &["build", "--release", "--quiet", "--package", "asnr", "--bin", "asnr"]))?;
    let asnr = target_dir(root).join("release").join(format!("asnr{}", std::env::consts::EXE_SUFFIX));
    let mut command =
        cmd::cargo(root, &["run", "--release", "--quiet", "--package", "asnr-bench", "--bin", "accuracy", "--"]);
    command.args(args).arg("--asnr").arg(&asnr);
    match python(root) {
        Ok(python) => {
            // the Python package, a release build (`pip install ./python`) in the same environment:
            // the map's `evaluate_many` row, beside the command
            let mut install = Command::new(&python);
            install
                .args([
                    "-m",
                    "pip",
                    "install",
                    "--quiet",
                    "--disable-pip-version-check",
                    "--force-reinstall",
                    "--no-deps",
                ])
                .arg(root.join("python"))
                .current_dir(root);
            match cmd::status(&mut install) {
                Ok(true) => {
                    command.arg("--asnr-python").arg(&python);
                }
                _ => eprintln!("accuracy: the Python package did not install: its map row skipped"),
            }
            command.arg("--python").arg(python);
        }
        Err(why) => eprintln!("accuracy: numpy not available: row skipped ({why})"),
    }
    command.arg(root);
    cmd::run(&mut command)
}

/// Cargo's target folder: `CARGO_TARGET_DIR` if set, else `target/` at the root.
pub(crate) fn target_dir(root: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), |dir| root.join(PathBuf::from(dir)))
}

/// Whether `python` imports numpy.
fn has_numpy(python: &Path) -> bool {
    Command::new(python)
        .args(["-c", "import numpy"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// An interpreter with numpy for the baseline: the project's virtual environment (made here if
/// it is missing or its requirements changed), else the system `python3`.
fn python(root: &Path) -> Result<PathBuf, String> {
    match cmd::venv(root, VENV, REQUIREMENTS, "numpy") {
        Ok(bin) => Ok(bin),
        Err(_) if has_numpy(Path::new("python3")) => {
            eprintln!("accuracy: could not make {VENV}; using the system python3, which has numpy");
            Ok(PathBuf::from("python3"))
        }
        Err(e) => Err(format!("{e:#}; and python3 has no numpy")),
    }
}
