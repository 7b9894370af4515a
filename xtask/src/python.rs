//! `cargo xtask python`: the Python package as a user gets it, tested (part of `cargo xtask ci`).
//!
//! 1. The wheel, built for x86-64-v3 and checked (abi3, the disassembly) as by `cargo xtask wheel`
//!    (`wheel.rs`), but from the test build: its `dev` profile and, under `.ci/run`'s `RUSTFLAGS`,
//!    its compiled dependencies, linked by the system's linker (`wheel::Kind::Test`; the glibc
//!    baseline is `cargo xtask wheel`'s check).
//! 2. A fresh virtual environment, `target/python-venv` (made anew each run), into which pip
//!    installs the wheel with its extras, `asnr-….whl[plot,dask,jax]`, pytest and gdstk (the
//!    GDS writer of `python/tests/test_gds.py`), every version pinned by the constraints file
//!    `python/requirements-test.txt` (jax's CPU package among them: the JAX bridge `asnr.jax` is
//!    tested here; the PyTorch bridge in `cargo xtask torch`).
//! 3. With no Rust toolchain on `PATH` (every folder holding `cargo` or `rustc` left out, checked
//!    from inside Python first): the pytest suite `python/tests` against the debug `asnr` binary
//!    (`ASNR_BIN`), with `ASNR_REQUIRE=jax,scipy,gdstk` so that a missing jax, scipy or gdstk
//!    fails the JAX bridge's and the GDS tests instead of skipping them; every ```` ```python ```` block of the README,
//!    each as a script of its own in `target/readme-python/`, as a user pastes it; and
//!    `examples/python/asnr_in_a_loss.py` (the ASNR in a loss, by scipy and by JAX).
//!
//! The developer's install, `pip install ./python` (maturin's PEP 517 build from the clone), is
//! the same build without the portable flags.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

use crate::cmd;

/// The virtual environment, relative to the workspace root.
const VENV: &str = "target/python-venv";
/// The pinned versions of the package's dependencies, extras and pytest (a constraints file).
const CONSTRAINTS: &str = "python/requirements-test.txt";
/// Where the README's Python blocks are written and run.
const SNIPPETS: &str = "target/readme-python";
/// The packages whose absence fails the tests that need them (`ASNR_REQUIRE`), rather than
/// skipping them: the JAX bridge's, with scipy for `scipy.optimize.minimize(jac=True)`, and
/// gdstk, which writes the GDS of `python/tests/test_gds.py`.
const REQUIRED: &str = "jax,scipy,gdstk";
/// What the tests need beyond the wheel and its extras (pinned by the constraints file).
const TEST_ONLY: [&str; 2] = ["pytest", "gdstk"];
/// The example where the ASNR is one term of a loss, run after the tests.
const LOSS_EXAMPLE: &str = "examples/python/asnr_in_a_loss.py";

/// Build the wheel, install it into a fresh environment, run the tests and the README's Python.
pub(crate) fn run(root: &Path) -> Result<()> {
    let wheel = crate::wheel::build(root, crate::wheel::Kind::Test)?;
    let asnr = cmd::debug_binaries(root)?.join(format!("asnr{}", std::env::consts::EXE_SUFFIX));
    let dir = root.join(VENV);
    if !cmd::status(Command::new("python3").args(["-m", "venv", "--clear"]).arg(&dir))? {
        bail!("python3 -m venv {VENV} failed");
    }
    let python = if cfg!(windows) { dir.join("Scripts").join("python.exe") } else { dir.join("bin").join("python") };
    // the user's command, `pip install asnr-….whl[plot,dask,jax]`, with pytest; versions pinned
    let mut install = Command::new(&python);
    install
        .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "-c"])
        .arg(root.join(CONSTRAINTS))
        .arg(format!("{}[plot,dask,jax]", wheel.display()))
        .args(TEST_ONLY);
    let started = std::time::Instant::now();
    cmd::run(&mut install)?;
    eprintln!("python: the wheel, its extras and pytest installed in {:.1} s", started.elapsed().as_secs_f64());

    let path = without_rust()?;
    let mut check = Command::new(&python);
    check
        .args([
            "-c",
            "import shutil, asnr; found = [t for t in ('cargo', 'rustc') if shutil.which(t)]; \
             assert not found, found; print('asnr from', asnr.__file__, '- no cargo, no rustc on PATH')",
        ])
        .env("PATH", &path)
        .current_dir(root.join("target"));
    cmd::run(&mut check)?;

    let mut pytest = Command::new(&python);
    pytest
        .args(["-m", "pytest", "-q", "python/tests"])
        .env("ASNR_BIN", &asnr)
        .env("ASNR_REQUIRE", REQUIRED)
        .env("PATH", &path)
        .current_dir(root);
    let started = std::time::Instant::now();
    cmd::run(&mut pytest)?;
    eprintln!("python: pytest ran in {:.1} s", started.elapsed().as_secs_f64());
    readme_snippets(root, &python, &path)?;
    let mut example = Command::new(&python);
    example.arg(root.join(LOSS_EXAMPLE)).env("PATH", &path).current_dir(root);
    let started = std::time::Instant::now();
    cmd::run(&mut example).with_context(|| LOSS_EXAMPLE.to_owned())?;
    eprintln!("python: {LOSS_EXAMPLE} ran in {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

/// `PATH` without the folders that hold `cargo` or `rustc`: the user of a wheel has no Rust
/// toolchain.
fn without_rust() -> Result<std::ffi::OsString> {
    let keep: Vec<PathBuf> = std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())
        .filter(|dir| !["cargo", "rustc"].iter().any(|tool| dir.join(tool).exists()))
        .collect();
    Ok(std::env::join_paths(keep)?)
}

/// Writes every ```` ```python ```` block of the README to a script of its own and runs it with
/// `python` from the scripts' folder, `PATH` as given; the first failure names the block's line.
fn readme_snippets(root: &Path, python: &Path, path: &std::ffi::OsStr) -> Result<()> {
    let readme = std::fs::read_to_string(root.join("README.md")).context("README.md")?;
    let blocks = python_blocks(&readme);
    if blocks.is_empty() {
        bail!("README.md: no ```python blocks");
    }
    let dir = root.join(SNIPPETS);
    if dir.exists() {
        std::fs::remove_dir_all(&dir)?;
    }
    std::fs::create_dir_all(&dir)?;
    for (line, code) in &blocks {
        let script = dir.join(format!("readme-line-{line}.py"));
        std::fs::write(&script, code)?;
        let mut run = Command::new(python);
        run.arg(&script).env("PATH", path).env("MPLBACKEND", "Agg").current_dir(&dir);
        cmd::run(&mut run).with_context(|| format!("README.md:{line}: the ```python block, as a script"))?;
    }
    eprintln!("readme: {} Python blocks ran as scripts", blocks.len());
    Ok(())
}

/// The README's ```` ```python ```` blocks: the line of each opening fence and its code.
pub(crate) fn python_blocks(markdown: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String)> = None;
    let mut inside_other = false;
    for (index, line) in markdown.lines().enumerate() {
        let trimmed = line.trim();
        if let Some(info) = trimmed.strip_prefix("```") {
            if let Some(block) = current.take() {
                blocks.push(block);
            } else if inside_other {
                inside_other = false;
            } else if info.trim() == "python" {
                current = Some((index + 1, String::new()));
            } else {
                inside_other = true;
            }
            continue;
        }
        if let Some((_, code)) = &mut current {
            code.push_str(line);
            code.push('\n');
        }
    }
    blocks
}

#[cfg(test)]
mod tests {
    use super::python_blocks;

    #[test]
    fn python_blocks_are_found_with_their_lines() {
        let text = "# t\n```sh\nls\n```\n```python\nimport asnr\nprint(1)\n```\n```text\n```python\n```\n";
        let blocks = python_blocks(text);
        assert_eq!(blocks, vec![(5, "import asnr\nprint(1)\n".to_owned())]);
    }
}
