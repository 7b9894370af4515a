//! `asnr`: how good is this metalens, really?
//!
//! Evaluates the ASNR (paper eq. 1) of a scene file, or of the paper's lens embedded in the
//! binary. Human-readable table by default, `--json` for scripts. The only program that reads
//! files, arguments or the environment; its subcommands live in the `asnr` library (`src/lib.rs`).

use std::process::ExitCode;

use clap::Parser;

// no code: its dependency features let this build share the test build's (workspace-hack/Cargo.toml)
use workspace_hack as _;

fn main() -> ExitCode {
    let cli = asnr::Cli::parse();
    match asnr::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // the reader of standard output went away (`asnr sweep --csv | head`): stop quietly
        Err(e) if asnr::is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
