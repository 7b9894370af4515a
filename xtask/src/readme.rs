//! `cargo xtask readme`: every command of the README runs as written.
//!
//! The commands are the lines of the README's ```` ```sh ```` fenced blocks, one command per line
//! (a line ending in `\` continues on the next), with `#` comments stripped. Other fenced blocks
//! (sample output, where `$ ` marks what was typed) hold no commands. Each command runs from the
//! repository root with `sh -c`, must exit 0, and must leave `git status --porcelain` as it was:
//! a README command writes nothing in the repository outside `target/` (which is ignored).
//!
//! A few commands are not run; [`SKIP`] lists each with its reason, and a skip entry that
//! matches no README command is itself an error, so the list cannot go stale.

use std::fs;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};

/// README commands that are not run: `(command prefix, reason)`. Kept minimal.
pub(crate) const SKIP: &[(&str, &str)] = &[
    ("cargo xtask ci", "the CI itself, which runs this step"),
    (
        "pip install ./python",
        "installs into the user's Python environment (a release build, minutes); `cargo xtask python`, a step of `cargo xtask ci`, installs the same package as the portable wheel into a fresh target/python-venv",
    ),
    ("cargo install --path cli", "a release build (minutes) that installs into ~/.cargo/bin, outside the repository"),
    (
        "cargo xtask figures",
        "a release build and four sweeps (minutes), and it rewrites the tracked docs/figures/ by design",
    ),
    (
        "cargo xtask accuracy",
        "a release build and the full accuracy report (minutes), and it rewrites the tracked BENCHMARKS.md",
    ),
    ("cargo xtask stress", "a release build (minutes); `cargo xtask ci` runs its reduced grid in its own step"),
    (
        "cargo doc --workspace --no-deps --open",
        "opens a browser; the `doc` step of `cargo xtask ci` builds the same pages with -D warnings",
    ),
];

/// Extract the commands of the README's ```` ```sh ```` blocks, in order.
pub(crate) fn commands(markdown: &str) -> Vec<String> {
    let mut commands = Vec::new();
    let mut fence: Option<bool> = None; // Some(is_sh) inside a fenced block
    let mut pending = String::new();
    for line in markdown.lines() {
        let trimmed = line.trim();
        if let Some(info) = trimmed.strip_prefix("```") {
            fence = match fence {
                None => Some(info.trim() == "sh"),
                Some(_) => None,
            };
            pending.clear();
            continue;
        }
        if fence != Some(true) {
            continue;
        }
        let code = strip_comment(line).trim_end();
        let (code, continued) = match code.strip_suffix('\\') {
            Some(head) => (head, true),
            None => (code, false),
        };
        if !pending.is_empty() && !code.trim().is_empty() {
            pending.push(' ');
        }
        pending.push_str(code.trim());
        if !continued && !pending.is_empty() {
            commands.push(std::mem::take(&mut pending));
        }
    }
    commands
}

/// `line` without its shell comment: from the first `#` that starts a word outside quotes.
fn strip_comment(line: &str) -> &str {
    let mut quote = None;
    let mut previous = ' ';
    for (index, c) in line.char_indices() {
        match (quote, c) {
            (None, '\'' | '"') => quote = Some(c),
            (Some(q), _) if c == q => quote = None,
            (None, '#') if previous.is_whitespace() => return &line[..index],
            _ => {}
        }
        previous = c;
    }
    line
}

/// The reason `command` is skipped, if a [`SKIP`] entry matches it (the entry, then nothing or
/// a space).
pub(crate) fn skip_reason(command: &str) -> Option<&'static str> {
    SKIP.iter()
        .find(|(prefix, _)| command.strip_prefix(prefix).is_some_and(|rest| rest.is_empty() || rest.starts_with(' ')))
        .map(|(_, reason)| *reason)
}

/// The [`SKIP`] entries that match none of `commands`.
pub(crate) fn stale_skips(commands: &[String]) -> Vec<&'static str> {
    SKIP.iter()
        .map(|(prefix, _)| *prefix)
        .filter(|prefix| !commands.iter().any(|command| skip_reason(command).is_some() && command.starts_with(prefix)))
        .collect()
}

/// `git status --porcelain` of the repository at `root` (ignored files such as `target/` are not
/// listed).
fn git_status(root: &Path) -> Result<String> {
    let output = Command::new("git")
        .args(["status", "--porcelain", "--untracked-files=all"])
        .current_dir(root)
        .output()
        .context("could not run `git status` (the README check needs git and a clone)")?;
    if !output.status.success() {
        bail!("`git status --porcelain` failed: {}", String::from_utf8_lossy(&output.stderr).trim());
    }
    Ok(String::from_utf8_lossy(&output.stdout).into_owned())
}

/// The last `lines` lines of `text`.
fn tail(text: &str, lines: usize) -> String {
    let all: Vec<&str> = text.lines().collect();
    all[all.len().saturating_sub(lines)..].join("\n")
}

/// Run every README command from `root`; fail on the first that exits non-zero or changes the
/// repository's `git status`.
pub(crate) fn run(root: &Path) -> Result<()> {
    let path = root.join("README.md");
    let text = fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
    let commands = commands(&text);
    if commands.is_empty() {
        bail!("README.md: no commands found in ```sh blocks");
    }
    let stale = stale_skips(&commands);
    if !stale.is_empty() {
        bail!("xtask/src/readme.rs: SKIP entries match no README command: {}", stale.join(", "));
    }
    run_all(root, &commands)
}

/// Run `commands` (all but the skipped ones) from `root`, each with `sh -c`; fail on the first
/// that exits non-zero or changes `git status`.
fn run_all(root: &Path, commands: &[String]) -> Result<()> {
    let before = git_status(root)?;
    let (mut ran, mut skipped) = (0, 0);
    for command in commands {
        if let Some(reason) = skip_reason(command) {
            eprintln!("readme: skip `{command}`: {reason}");
            skipped += 1;
            continue;
        }
        eprintln!("$ {command}");
        let start = Instant::now();
        let output = Command::new("sh")
            .args(["-c", command])
            .current_dir(root)
            .output()
            .with_context(|| format!("could not start `sh -c {command}`"))?;
        if !output.status.success() {
            bail!(
                "README command `{command}` failed ({}):\n{}\n{}",
                output.status,
                tail(&String::from_utf8_lossy(&output.stdout), 20),
                tail(&String::from_utf8_lossy(&output.stderr), 20)
            );
        }
        eprintln!("   ok ({:.1} s)", start.elapsed().as_secs_f64());
        let after = git_status(root)?;
        if after != before {
            bail!(
                "README command `{command}` changed the repository (write under target/ or /tmp instead):\n\
                 git status --porcelain before:\n{before}after:\n{after}"
            );
        }
        ran += 1;
    }
    eprintln!("readme: {ran} commands ran, {skipped} skipped, repository unchanged");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const README: &str = "# Title\n\
        \n\
        ```sh\n\
        cargo asnr evaluate        # the main job\n\
        \n\
        cargo xtask ci             # the tests\n\
        ```\n\
        \n\
        Sample output:\n\
        \n\
        ```\n\
        $ cargo asnr evaluate\n\
        ASNR 10.38\n\
        ```\n\
        \n\
        ```toml\n\
        [lens]\n\
        ```\n\
        \n\
        ```sh\n\
        # a comment line\n\
        cargo asnr mtf --plot 'a #b.svg' --set \"x=#1\" # trailing\n\
        cargo asnr sweep --over a=1:2 \\\n\
            --csv\n\
        echo a#b\n\
        ```\n";

    #[test]
    fn commands_come_from_sh_blocks_only_without_comments() {
        assert_eq!(
            commands(README),
            vec![
                "cargo asnr evaluate",
                "cargo xtask ci",
                "cargo asnr mtf --plot 'a #b.svg' --set \"x=#1\"",
                "cargo asnr sweep --over a=1:2 --csv",
                "echo a#b",
            ]
        );
    }

    #[test]
    fn sample_output_and_other_languages_hold_no_commands() {
        let text = "```\n$ cargo asnr evaluate\n```\n```console\n$ ls\n```\n```toml\nx = 1\n```\n";
        assert!(commands(text).is_empty());
        // An unterminated block still yields its commands, and text after a block is prose.
        assert_eq!(commands("```sh\nls\n```\nls -l\n```sh\npwd\n"), vec!["ls", "pwd"]);
    }

    #[test]
    fn skips_match_whole_words_and_stale_entries_are_found() {
        assert!(skip_reason("cargo xtask ci").is_some());
        assert!(skip_reason("cargo xtask figures").is_some());
        assert!(skip_reason("cargo xtask cix").is_none());
        assert!(skip_reason("cargo asnr evaluate").is_none());
        let all: Vec<String> = SKIP.iter().map(|(prefix, _)| (*prefix).to_owned()).collect();
        assert!(stale_skips(&all).is_empty());
        let listed =
            ["cargo xtask ci", "cargo install --path cli", "cargo xtask accuracy", "cargo xtask stress --quick"];
        let listed: Vec<String> = listed.iter().map(|c| (*c).to_owned()).collect();
        assert_eq!(
            stale_skips(&listed),
            vec!["pip install ./python", "cargo xtask figures", "cargo doc --workspace --no-deps --open"]
        );
    }

    /// A scratch git repository holding `readme` as README.md (committed), for [`run_all`].
    fn scratch_repository(name: &str, readme: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("xtask-readme-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        fs::write(dir.join("README.md"), readme).unwrap();
        fs::write(dir.join(".gitignore"), "/target\n").unwrap();
        for args in
            [&["init", "-q"][..], &["add", "-A"], &["-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "r"]]
        {
            assert!(Command::new("git").args(args).current_dir(&dir).status().unwrap().success());
        }
        dir
    }

    #[test]
    fn run_checks_exit_status_and_that_the_repository_is_unchanged() {
        let ok = scratch_repository("ok", "```sh\nmkdir -p target && echo x > target/out.txt\ntrue # fine\n```\n");
        run_all(&ok, &commands(&fs::read_to_string(ok.join("README.md")).unwrap())).unwrap();
        let failing = scratch_repository("fail", "```sh\ntrue\nexit 3\n```\n");
        let err = format!(
            "{:#}",
            run_all(&failing, &commands(&fs::read_to_string(failing.join("README.md")).unwrap())).unwrap_err()
        );
        assert!(err.contains("README command `exit 3` failed"), "{err}");
        let writing = scratch_repository("write", "```sh\necho x > plot.svg\n```\n");
        let err = format!(
            "{:#}",
            run_all(&writing, &commands(&fs::read_to_string(writing.join("README.md")).unwrap())).unwrap_err()
        );
        assert!(err.contains("`echo x > plot.svg` changed the repository") && err.contains("?? plot.svg"), "{err}");
        let editing = scratch_repository("edit", "```sh\necho more >> README.md\n```\n");
        let err = format!(
            "{:#}",
            run_all(&editing, &commands(&fs::read_to_string(editing.join("README.md")).unwrap())).unwrap_err()
        );
        assert!(err.contains(" M README.md"), "{err}");
        for dir in [ok, failing, writing, editing] {
            let _ = fs::remove_dir_all(dir);
        }
    }

    #[test]
    fn the_readme_has_commands_and_none_is_a_bare_binary_or_a_placeholder() {
        let text = fs::read_to_string(crate::project_root().join("README.md")).unwrap();
        let commands = commands(&text);
        assert!(commands.iter().any(|c| c == "cargo asnr evaluate"), "{commands:?}");
        assert!(commands.iter().any(|c| c == "cargo xtask ci"), "{commands:?}");
        for command in &commands {
            assert!(!command.starts_with("asnr "), "bare `asnr`: {command}");
            assert!(!command.contains('…'), "placeholder `…`: {command}");
        }
        assert!(stale_skips(&commands).is_empty());
    }
}
