//! Running external commands: echo each one, then run it with inherited output, and turn a
//! failure into an error that names the command.

use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, bail};

/// A `cargo` command with `args`, run from the workspace `root`.
pub(crate) fn cargo(root: &Path, args: &[&str]) -> Command {
    let mut command = Command::new("cargo");
    command.args(args).current_dir(root);
    command
}

/// Builds the workspace's binaries in the debug profile with the feature set of
/// `cargo test --workspace` (dev-dependencies' features included: `--tests` selects them) and
/// returns the folder that holds them (`target/debug`).
///
/// After the test step of `cargo xtask ci` this compiles only the binaries that no test needed
/// (the stress sweep's) and reuses every library. Building the whole workspace's binaries, not
/// `--package asnr`, keeps that true without relying on workspace-hack (which makes `asnr`'s own
/// resolution agree, for the README's commands; ARCHITECTURE.md, "CI").
pub(crate) fn debug_binaries(root: &Path) -> Result<std::path::PathBuf> {
    run(&mut cargo(root, &["build", "--quiet", "--locked", "--workspace", "--bins", "--tests"]))?;
    Ok(crate::accuracy::target_dir(root).join("debug"))
}

/// Echo `command` to stderr, run it and fail unless it exits successfully.
pub(crate) fn run(command: &mut Command) -> Result<()> {
    if status(command)? { Ok(()) } else { bail!("`{}` failed", display(command)) }
}

/// Echo `command` to stderr, run it and report whether it exited successfully; an error only
/// when it could not be started at all.
pub(crate) fn status(command: &mut Command) -> Result<bool> {
    let shown = display(command);
    eprintln!("$ {shown}");
    let status =
        command.status().with_context(|| format!("could not start `{shown}` (is it installed and on PATH?)"))?;
    Ok(status.success())
}

/// `command` as a shell line: environment overrides, program, arguments.
pub(crate) fn display(command: &Command) -> String {
    let mut words = Vec::new();
    for (key, value) in command.get_envs() {
        if let Some(value) = value {
            words.push(format!("{}={}", key.to_string_lossy(), quote(&value.to_string_lossy())));
        }
    }
    words.push(quote(&command.get_program().to_string_lossy()));
    words.extend(command.get_args().map(|arg| quote(&arg.to_string_lossy())));
    words.join(" ")
}

/// Double-quote a word that contains whitespace or is empty.
fn quote(word: &str) -> String {
    if word.is_empty() || word.contains(char::is_whitespace) { format!("\"{word}\"") } else { word.to_owned() }
}

/// The python of the virtual environment `venv` (relative to `root`) with the pinned
/// `requirements` installed: made with `python3 -m venv` and `pip install -r` when it is missing
/// or was made from other requirements (a stamp file inside it keeps the requirements it was
/// made from), reused otherwise; `probe` is a module it must import.
pub(crate) fn venv(root: &Path, venv: &str, requirements: &str, probe: &str) -> Result<std::path::PathBuf> {
    venv_of(root, venv, &[requirements], probe)
}

/// [`venv`] with several pinned files installed together (`pip install -r A -r B`), the stamp
/// keeping all of them.
pub(crate) fn venv_of(root: &Path, venv: &str, requirements: &[&str], probe: &str) -> Result<std::path::PathBuf> {
    let dir = root.join(venv);
    let bin = if cfg!(windows) { dir.join("Scripts").join("python.exe") } else { dir.join("bin").join("python") };
    let mut pinned = String::new();
    for file in requirements {
        pinned += &std::fs::read_to_string(root.join(file)).map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
    }
    let imports = |python: &Path| {
        Command::new(python)
            .args(["-c", &format!("import {probe}")])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    };
    let stamp = dir.join("requirements.installed");
    if std::fs::read_to_string(&stamp).is_ok_and(|s| s == pinned) && imports(&bin) {
        return Ok(bin);
    }
    if !status(Command::new("python3").args(["-m", "venv", "--clear"]).arg(&dir))? {
        anyhow::bail!("python3 -m venv {venv} failed");
    }
    let mut pip = Command::new(&bin);
    pip.args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check"]);
    for file in requirements {
        pip.arg("-r").arg(root.join(file));
    }
    if !status(&mut pip)? || !imports(&bin) {
        anyhow::bail!("could not install {} into {venv} (or it does not import {probe})", requirements.join(" and "));
    }
    std::fs::write(&stamp, &pinned)?;
    Ok(bin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_shows_env_program_and_quoted_args() {
        let mut command = cargo(Path::new("."), &["doc", "--workspace"]);
        command.env("RUSTDOCFLAGS", "-D warnings");
        assert_eq!(display(&command), "RUSTDOCFLAGS=\"-D warnings\" cargo doc --workspace");
    }
}
