//! `cargo xtask python`: the Python package (`python/`) built into a virtual environment and its
//! pytest suite run against the command line (part of `cargo xtask ci`).
//!
//! Makes `target/python-venv` with the pinned `python/requirements-test.txt` (maturin, numpy,
//! pandas, dask/distributed, matplotlib, pytest; once, remade when the requirements change),
//! builds the debug `asnr` binary the tests compare with, builds the extension into the
//! environment with `maturin develop` (the dev profile, so it reuses the workspace's debug
//! build), and runs `pytest python/tests` with `ASNR_BIN` pointing at that binary. A Python
//! user installs the same package with `pip install ./python` (a release build).

use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result};

use crate::cmd;

/// The virtual environment, relative to the workspace root.
const VENV: &str = "target/python-venv";
/// What it installs, pinned.
const REQUIREMENTS: &str = "python/requirements-test.txt";

/// Build the package into the environment and run its tests, from the workspace `root`.
pub(crate) fn run(root: &Path) -> Result<()> {
    let python =
        cmd::venv(root, VENV, REQUIREMENTS, "pytest, maturin, numpy").context("the Python test environment")?;
    cmd::run(&mut cmd::cargo(root, &["build", "--quiet", "--locked", "--package", "asnr", "--bin", "asnr"]))?;
    let bin = python.parent().context("the environment's bin folder")?;
    let mut develop = Command::new(bin.join(if cfg!(windows) { "maturin.exe" } else { "maturin" }));
    develop
        .args(["develop", "--quiet", "--locked", "--manifest-path"])
        .arg(root.join("python").join("Cargo.toml"))
        .env("VIRTUAL_ENV", root.join(VENV))
        .current_dir(root);
    cmd::run(&mut develop)?;
    let asnr = crate::accuracy::target_dir(root).join("debug").join(format!("asnr{}", std::env::consts::EXE_SUFFIX));
    let mut pytest = Command::new(&python);
    pytest.args(["-m", "pytest", "-q", "python/tests"]).env("ASNR_BIN", &asnr).current_dir(root);
    cmd::run(&mut pytest)
}
