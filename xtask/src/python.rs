//! `cargo xtask python`: the Python package (`python/`) built into a virtual environment and its
//! pytest suite run against the command line (part of `cargo xtask ci`).
//!
//! Makes `target/python-venv` with the pinned `python/requirements-test.txt` (maturin, numpy,
//! pandas, dask/distributed, matplotlib, pytest; once, remade when the requirements change),
//! builds the debug `asnr` binary the tests compare with, installs the package into the
//! environment with the README's command, `pip install ./python` (maturin's PEP 517 build, here
//! in the dev profile so that it reuses the workspace's debug build; a user's install is a
//! release build), and runs `pytest python/tests` with `ASNR_BIN` pointing at that binary.

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
    let python = cmd::venv(root, VENV, REQUIREMENTS, "pytest, numpy").context("the Python test environment")?;
    cmd::run(&mut cmd::cargo(root, &["build", "--quiet", "--locked", "--package", "asnr", "--bin", "asnr"]))?;
    // the README's install command, `pip install ./python`, in the environment; in the dev
    // profile (maturin's PEP 517 builds are release by default), which reuses the workspace's
    // debug build; reinstalled whatever is there, without touching the pinned dependencies
    let mut install = Command::new(&python);
    install
        .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--force-reinstall", "--no-deps"])
        .arg(root.join("python"))
        .env("MATURIN_PEP517_ARGS", "--profile dev --locked")
        .current_dir(root);
    cmd::run(&mut install)?;
    let asnr = crate::accuracy::target_dir(root).join("debug").join(format!("asnr{}", std::env::consts::EXE_SUFFIX));
    let mut pytest = Command::new(&python);
    pytest.args(["-m", "pytest", "-q", "python/tests"]).env("ASNR_BIN", &asnr).current_dir(root);
    cmd::run(&mut pytest)
}
