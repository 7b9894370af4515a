//! `cargo xtask ci`: the full check, one step after another, stopping at the first failure.
//! `.ci/run` runs exactly this.

use std::path::Path;

use anyhow::{Result, bail};

use crate::{cmd, readme, tidy};

/// One check: a short name for the log and the function that performs it.
struct Step {
    name: &'static str,
    run: fn(&Path) -> Result<()>,
}

/// The steps, in order: cheap checks first so a formatting slip fails in seconds.
const STEPS: &[Step] = &[
    Step { name: "rustfmt and clippy installed", run: ensure_components },
    Step { name: "fmt", run: fmt },
    Step { name: "tidy", run: run_tidy },
    Step { name: "clippy", run: clippy },
    Step { name: "test", run: test },
    Step {
        name: "python (the x86-64-v3 abi3 wheel from the test build, checked, in a fresh venv without Rust: pytest, README blocks)",
        run: python,
    },
    Step { name: "emva (asnr characterize against the emva1288 camera model)", run: emva },
    Step { name: "readme (every README command as written)", run: run_readme },
    Step { name: "stress (reduced grid)", run: stress },
    Step { name: "doc", run: doc },
];

/// Run every step from the workspace `root`; print `ci: N passed, M failed` at the end.
pub(crate) fn run(root: &Path) -> Result<()> {
    let total = STEPS.len();
    let start = std::time::Instant::now();
    for (index, step) in STEPS.iter().enumerate() {
        eprintln!("\n==> ci [{}/{total}] {}", index + 1, step.name);
        let begun = std::time::Instant::now();
        if let Err(err) = (step.run)(root) {
            println!("\nci: {index} passed, 1 failed");
            return Err(err.context(format!("ci step `{}` failed", step.name)));
        }
        eprintln!("==> ci [{}/{total}] done in {:.0} s", index + 1, begun.elapsed().as_secs_f64());
    }
    eprintln!("==> ci: {:.0} s in all", start.elapsed().as_secs_f64());
    println!("\nci: {total} passed, 0 failed");
    Ok(())
}

/// Install rustfmt and clippy through rustup when `cargo fmt` or `cargo clippy` is missing.
fn ensure_components(root: &Path) -> Result<()> {
    let fmt = cmd::status(&mut cmd::cargo(root, &["fmt", "--version"]))?;
    let clippy = cmd::status(&mut cmd::cargo(root, &["clippy", "--version"]))?;
    if fmt && clippy {
        return Ok(());
    }
    let mut rustup = std::process::Command::new("rustup");
    rustup.args(["component", "add", "rustfmt", "clippy"]).current_dir(root);
    cmd::run(&mut rustup)?;
    for tool in ["fmt", "clippy"] {
        if !cmd::status(&mut cmd::cargo(root, &[tool, "--version"]))? {
            bail!("`cargo {tool}` is still unavailable after `rustup component add`");
        }
    }
    Ok(())
}

fn fmt(root: &Path) -> Result<()> {
    cmd::run(&mut cmd::cargo(root, &["fmt", "--all", "--check"]))
}

fn run_tidy(root: &Path) -> Result<()> {
    eprintln!("$ cargo xtask tidy   (in-process)");
    tidy::run(root)
}

fn run_readme(root: &Path) -> Result<()> {
    eprintln!("$ cargo xtask readme   (in-process)");
    readme::run(root)
}

fn clippy(root: &Path) -> Result<()> {
    cmd::run(&mut cmd::cargo(root, &["clippy", "--workspace", "--all-targets", "--locked", "--", "-D", "warnings"]))
}

fn python(root: &Path) -> Result<()> {
    eprintln!("$ cargo xtask python   (in-process)");
    crate::python::run(root)
}

fn emva(root: &Path) -> Result<()> {
    eprintln!("$ cargo xtask emva   (in-process)");
    crate::emva::run(root)
}

fn test(root: &Path) -> Result<()> {
    cmd::run(&mut cmd::cargo(root, &["test", "--workspace", "--locked"]))
}

/// The reduced stress grid (`cargo xtask stress --quick`), in the test profile that the test step
/// has just built (opt-level 2), so CI pays no release build for it; the sweep's binary is built
/// with the test build's features (`cmd::debug_binaries`), so no project crate is compiled again.
fn stress(root: &Path) -> Result<()> {
    let sweep = cmd::debug_binaries(root)?.join(format!("stress{}", std::env::consts::EXE_SUFFIX));
    let mut command = std::process::Command::new(sweep);
    command.arg("--quick").current_dir(root);
    cmd::run(&mut command)
}

fn doc(root: &Path) -> Result<()> {
    let mut command = cmd::cargo(root, &["doc", "--workspace", "--no-deps", "--locked"]);
    command.env("RUSTDOCFLAGS", "-D warnings");
    cmd::run(&mut command)
}
