//! A downstream crate loading a scene file with one call and printing its ASNR.
//!
//! ```text
//! cargo run -p asnr-scene --example evaluate_file                              # examples/paper-theory.toml
//! cargo run -p asnr-scene --example evaluate_file -- examples/tabulated.toml
//! ```
//!
//! Run from the repository root (the default path and the CSV tables the example scenes name
//! are relative to it).

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let path = std::env::args_os().nth(1).map_or_else(|| PathBuf::from("examples/paper-theory.toml"), PathBuf::from);
    let loaded = match scene::load_with_warnings(Some(&path), &[]) {
        Ok(loaded) => loaded,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    match metric::evaluate(&loaded.scene) {
        Ok(result) => {
            println!(
                "{}: ASNR = {:.4} (mean MTF {:.4}, SNR0 {:.2})",
                path.display(),
                result.asnr,
                result.mean_mtf,
                result.snr0
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {}: {e}", path.display());
            ExitCode::FAILURE
        }
    }
}
