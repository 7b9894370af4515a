//! `cargo xtask torch`: the PyTorch bridge (`asnr.torch`) tested against the command line.
//!
//! Not a step of `cargo xtask ci`: torch's Linux wheel from the package index brings CUDA's
//! libraries, 5.4 GB that took 11 min 41 s to download and install into a fresh environment
//! (ARCHITECTURE.md, "Why each dependency is there"), against 15 s for jax's CPU package, which
//! `cargo xtask python` installs and tests in CI. This task runs what CI leaves out:
//!
//! 1. The wheel, built and checked by `cargo xtask wheel` (`wheel.rs`), and the debug `asnr`.
//! 2. A virtual environment of its own, `target/torch-venv`, with torch, numpy and pytest pinned
//!    by `python/requirements-torch.txt`: made once and reused while the pins are the same (a
//!    stamp inside it, `cmd::venv`), so the download is paid once per machine; the wheel is
//!    installed into it anew each run (`--force-reinstall --no-deps`).
//! 3. The torch tests of `python/tests/test_gradient.py` with `ASNR_REQUIRE=torch`, so that a
//!    missing torch fails instead of skipping, against the debug binary (`ASNR_BIN`).

use std::path::Path;
use std::process::Command;

use anyhow::Result;

use crate::cmd;

/// The virtual environment, relative to the workspace root (kept between runs).
const VENV: &str = "target/torch-venv";
/// torch, numpy and pytest, pinned.
const REQUIREMENTS: &str = "python/requirements-torch.txt";

/// Build the wheel, install it beside torch, run the torch bridge's tests.
pub(crate) fn run(root: &Path) -> Result<()> {
    let wheel = crate::wheel::build(root, crate::wheel::Kind::Test)?;
    cmd::run(&mut cmd::cargo(root, &["build", "--quiet", "--locked", "--package", "asnr", "--bin", "asnr"]))?;
    let started = std::time::Instant::now();
    let python = cmd::venv(root, VENV, REQUIREMENTS, "torch, numpy, pytest")?;
    eprintln!("torch: {VENV} ready in {:.1} s", started.elapsed().as_secs_f64());
    let mut install = Command::new(&python);
    install
        .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--force-reinstall", "--no-deps"])
        .arg(&wheel);
    cmd::run(&mut install)?;
    let asnr = crate::accuracy::target_dir(root).join("debug").join(format!("asnr{}", std::env::consts::EXE_SUFFIX));
    let mut pytest = Command::new(&python);
    pytest
        .args(["-m", "pytest", "-q", "python/tests/test_gradient.py", "-k", "torch"])
        .env("ASNR_BIN", &asnr)
        .env("ASNR_REQUIRE", "torch")
        .current_dir(root);
    let started = std::time::Instant::now();
    cmd::run(&mut pytest)?;
    eprintln!("torch: the tests ran in {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}
