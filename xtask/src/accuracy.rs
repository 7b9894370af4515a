//! `cargo xtask accuracy [--quick]`: the accuracy-versus-time report. Builds and runs the example
//! `metric/examples/accuracy/` (`main.rs` and its modules) in release (xtask depends on no
//! project crate), which writes `BENCHMARKS.md` and `docs/benchmarks/accuracy.svg` at the
//! workspace root.

use std::path::Path;

use anyhow::{Result, bail};

use crate::cmd;

/// Build and run the report from the workspace `root`.
pub(crate) fn run(root: &Path, args: &[String]) -> Result<()> {
    if let Some(bad) = args.iter().find(|a| a.as_str() != "--quick") {
        bail!("unknown argument `{bad}` (usage: cargo xtask accuracy [--quick])");
    }
    let mut command =
        cmd::cargo(root, &["run", "--release", "--quiet", "--package", "metric", "--example", "accuracy", "--"]);
    command.args(args).arg(root);
    cmd::run(&mut command)
}
