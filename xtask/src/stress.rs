//! `cargo xtask stress [--quick] [--timeout SECONDS] [--only TEXT] [--list]`: the numerical
//! stress sweep of the metric over the corners of the physical parameter space.
//!
//! xtask depends on no project crate (`tidy` enforces it), so the sweep itself is the example
//! `bench/src/bin/stress.rs`; this task builds it in release and runs it, passing the
//! arguments on. It prints a table (engine and time of every point), the failures, warnings,
//! fallbacks and slowest points, and `stress: N points, M failures`, and fails on any failure.
//! `--quick` is the CI-sized grid (well under a minute in release).

use std::path::Path;

use anyhow::{Result, bail};

use crate::cmd;

/// The arguments the sweep accepts; anything else is refused here, before the release build.
const FLAGS: &[&str] = &["--quick", "--list", "-h", "--help"];
const OPTIONS: &[&str] = &["--timeout", "--only"];

/// Build and run the sweep from the workspace `root` with `args`.
pub(crate) fn run(root: &Path, args: &[String]) -> Result<()> {
    check_args(args)?;
    let mut command =
        cmd::cargo(root, &["run", "--release", "--quiet", "--package", "asnr-bench", "--bin", "stress", "--"]);
    command.args(args);
    cmd::run(&mut command)
}

fn check_args(args: &[String]) -> Result<()> {
    let mut iter = args.iter();
    while let Some(arg) = iter.next() {
        if OPTIONS.contains(&arg.as_str()) {
            if iter.next().is_none() {
                bail!(
                    "`{arg}` needs a value (usage: cargo xtask stress [--quick] [--timeout SECONDS] [--only TEXT] [--list])"
                );
            }
        } else if !FLAGS.contains(&arg.as_str()) {
            bail!(
                "unknown argument `{arg}` (usage: cargo xtask stress [--quick] [--timeout SECONDS] [--only TEXT] [--list])"
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(words: &[&str]) -> Vec<String> {
        words.iter().map(|w| (*w).to_owned()).collect()
    }

    #[test]
    fn accepts_the_sweep_flags_and_refuses_others() {
        assert!(check_args(&args(&[])).is_ok());
        assert!(check_args(&args(&["--quick", "--timeout", "5", "--only", "F/0.5"])).is_ok());
        assert!(check_args(&args(&["--timeout"])).is_err());
        assert!(check_args(&args(&["--fast"])).is_err());
    }
}
