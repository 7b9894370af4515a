//! `cargo xtask emva`: `asnr characterize` checked against an independent EMVA 1288 camera
//! simulator, the camera model of the `emva1288` Python package (part of `cargo xtask ci`).
//!
//! Makes `target/emva-venv` with the pinned `imaging/tests/emva/requirements.txt` (once; remade
//! when the requirements change), builds the debug `asnr` (with the test build's features,
//! `cmd::debug_binaries`), and runs
//! `imaging/tests/emva/emva_series.py target/emva --asnr …`: it writes a seeded series of 16-bit
//! PNG stacks from the package's camera model at known K, read noise and full well, runs
//! `asnr characterize --json --plot target/emva/transfer.svg` on it, and checks K, both slopes,
//! the read noise and the saturation point within the tolerances its docstring states.

use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result};

use crate::cmd;

/// The virtual environment, relative to the workspace root.
const VENV: &str = "target/emva-venv";
/// The pinned package and its dependencies.
const REQUIREMENTS: &str = "imaging/tests/emva/requirements.txt";
/// The generator and check.
const SCRIPT: &str = "imaging/tests/emva/emva_series.py";

/// Make the environment, the series and the check, from the workspace `root`.
pub(crate) fn run(root: &Path) -> Result<()> {
    let python = cmd::venv(root, VENV, REQUIREMENTS, "emva1288.camera").context("the emva1288 environment")?;
    let asnr = cmd::debug_binaries(root)?.join(format!("asnr{}", std::env::consts::EXE_SUFFIX));
    let out = crate::accuracy::target_dir(root).join("emva");
    let mut check = Command::new(python);
    check.arg(root.join(SCRIPT)).arg(&out).arg("--asnr").arg(&asnr).current_dir(root);
    cmd::run(&mut check)
}
