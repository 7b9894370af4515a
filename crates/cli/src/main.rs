//! `asnr`: how good is this metalens, really?
//!
//! Evaluates the ASNR (paper eq. 1) of a scene file, or of the paper's lens embedded in the
//! binary. Human-readable table by default, `--json` for scripts. The only crate that reads
//! files, arguments or the environment.

mod output;
mod scene;
mod tables;

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// How good is this metalens, really? The ASNR of a lens, light, camera and exposure.
#[derive(Parser)]
#[command(name = "asnr", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate the ASNR of a scene (default: the paper's lens, embedded).
    Evaluate {
        /// Scene file (TOML). Without it, the embedded paper scene (examples/paper-theory.toml).
        scene: Option<PathBuf>,
        /// Override a scene key by its dotted path, e.g. --set lens.f_number=2.8 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
    },
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Evaluate { scene, set, json } => {
            let label = scene.as_ref().map_or("embedded paper scene".to_owned(), |p| p.display().to_string());
            let loaded = scene::load(scene.as_deref(), &set)?;
            let result = metric::evaluate(&loaded).map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
            output::check_finite(&result)?;
            if json {
                println!("{}", output::json(&label, &loaded, &result)?);
            } else {
                print!("{}", output::table(&label, &loaded, &result));
                for w in &result.warnings {
                    eprintln!("warning: {w}");
                }
            }
            Ok(())
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
