//! `cargo xtask tidy`: the architecture invariants, checked by reading each member's
//! `Cargo.toml` (with the `toml` crate) and crate root.
//!
//! The layout (the user's design card): every workspace member is a folder at the repository
//! root (`radiometry/ optics/ noise/ metric/ lenses/ scene/ cli/ bench/ xtask/`, and the crates added
//! beside them); there is no `crates/` folder. For every member of the root manifest:
//! Downstream example crates are the one exception to the layout: `examples/<name>/` (one level,
//! e.g. `examples/custom-lens`), each a user's crate built with the public API only.
//!
//! - the package name is the folder's, except those [`PACKAGE_NAMES`] lists: the libraries are
//!   `asnr-<folder>` with `[lib] name = "<folder>"`, `cli/` is `asnr` (so that
//!   `cargo install --path cli` installs and reports the `asnr` binary);
//! - `version.workspace = true` (one version, in the root manifest);
//! - the project crates in its normal dependencies (`[dependencies]`, `[build-dependencies]`
//!   and their `[target.*]` forms) are among those [`RULES`] allows; dev-dependencies may use
//!   any project crate (so `metric` tests may use `lenses`);
//! - every dependency is `name.workspace = true`, so versions and paths live only in the root
//!   `[workspace.dependencies]`;
//! - it has `[lints] workspace = true`;
//! - `src/lib.rs`, `src/main.rs` and the binaries of `src/bin/`, whichever exist, open with a
//!   `//!` crate doc comment;
//! - every dependency it declares is named by its sources ([`unused_dependencies`]).
//!
//! And for the whole build: no package in `cargo metadata` needs a newer Rust than the
//! workspace's `rust-version`.
//!
//! And for every tracked `*.md`, `*.rs` and `*.toml` file (`git ls-files`): it refers to no path
//! outside the repository ([`OUTSIDE_PATTERNS`]); the physics conventions the code cites are in
//! the repository's own `docs/physics.md`. In every tracked `*.rs` file no string literal holds
//! a run of spaces between two words ([`spaced_literals`]).

use std::fs;
use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, bail};
use toml::{Table, Value};

/// Which project crates a member may use in its normal dependencies.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Allowed {
    /// Only these project crates (possibly none).
    Only(&'static [&'static str]),
    /// Any project crate.
    Any,
}

/// Architecture invariant: the dependency direction between project crates. A crate missing
/// here is itself a violation, so a new crate has to state its place in the graph.
pub(crate) const RULES: &[(&str, Allowed)] = &[
    ("radiometry", Allowed::Only(&[])),
    ("optics", Allowed::Only(&["radiometry"])),
    ("noise", Allowed::Only(&["radiometry"])),
    ("lenses", Allowed::Only(&["optics", "radiometry"])),
    ("metric", Allowed::Only(&["optics", "noise", "radiometry"])),
    ("scene", Allowed::Only(&["metric", "lenses", "optics", "noise", "radiometry"])),
    ("imaging", Allowed::Only(&["metric", "noise", "optics", "radiometry"])),
    // report: also imaging, whose measurements (edge MTF, measured ASNR) it reports for both front ends
    ("report", Allowed::Only(&["imaging", "metric", "scene", "radiometry"])),
    ("cli", Allowed::Any),
    // the Python extension: libraries only, never the command line (clap, plotters, image, …);
    // workspace-hack (no code) so that the wheel built from the test build compiles nothing again
    (
        "python",
        Allowed::Only(&[
            "report",
            "imaging",
            "scene",
            "metric",
            "lenses",
            "optics",
            "noise",
            "radiometry",
            "workspace-hack",
        ]),
    ),
    ("xtask", Allowed::Only(&[])),
    // the benchmark harness (binaries, not published): the libraries it measures (report: the
    // gradient's chain rules of the lens keys), never the command line, which it runs as a
    // subprocess
    ("bench", Allowed::Only(&["report", "imaging", "scene", "metric", "lenses", "optics", "noise", "radiometry"])),
    // examples/custom-lens: a downstream crate implementing LensModel with the public API only
    ("custom-lens", Allowed::Any),
    // no code: the test build's dependency features for the packages built alone
    ("workspace-hack", Allowed::Only(&["optics"])),
];

/// Folders whose package name is not the folder name: `(folder, package)`. The libraries are
/// packages `asnr-<folder>` (names that can be published: `noise`, `optics`, … are taken on
/// crates.io) whose library keeps the folder's name (`[lib] name`), so the code says
/// `use optics::…`; the root `[workspace.dependencies]` finds them by `package = "asnr-…"`.
pub(crate) const PACKAGE_NAMES: &[(&str, &str)] = &[
    ("cli", "asnr"),
    ("python", "asnr-python"),
    ("bench", "asnr-bench"),
    ("radiometry", "asnr-radiometry"),
    ("optics", "asnr-optics"),
    ("noise", "asnr-noise"),
    ("metric", "asnr-metric"),
    ("lenses", "asnr-lenses"),
    ("scene", "asnr-scene"),
    ("imaging", "asnr-imaging"),
    ("report", "asnr-report"),
];

/// The package name the member in `folder` must have.
fn package_name(folder: &str) -> &str {
    PACKAGE_NAMES.iter().find(|(f, _)| *f == folder).map_or(folder, |(_, package)| package)
}

/// Check every member of the workspace at `root`; print each violation as
/// `tidy: <path>: <problem>` and fail if there is any.
pub(crate) fn run(root: &Path) -> Result<()> {
    let manifest_path = root.join("Cargo.toml");
    let text =
        fs::read_to_string(&manifest_path).with_context(|| format!("cannot read {}", manifest_path.display()))?;
    let mut violations = Vec::new();
    let folders = match workspace_members(&text) {
        Ok(members) => members,
        Err(problem) => bail!("tidy: Cargo.toml: {problem}"),
    };
    violations.extend(check_layout(&folders, root.join("crates").exists()));
    for folder in &folders {
        check_member(root, folder, &mut violations)?;
    }
    violations.extend(check_outside_references(root)?);
    violations.extend(check_rust_version(root, &text)?);
    violations.extend(check_versions(&text));
    violations.extend(crate::features::check(root)?);
    if let Ok(lock) = fs::read_to_string(root.join("Cargo.lock")) {
        violations.extend(check_held(&lock));
    }
    if let Ok(citation) = fs::read_to_string(root.join("CITATION.cff")) {
        violations.extend(check_citation_version(&text, &citation));
    }
    for violation in &violations {
        eprintln!("tidy: {violation}");
    }
    if !violations.is_empty() {
        bail!("tidy: {} violation(s) in {} crates", violations.len(), folders.len());
    }
    eprintln!("tidy: {} crates checked, no violations", folders.len());
    Ok(())
}

/// Crates held at a version in Cargo.lock, and why (ARCHITECTURE.md, "Why each dependency is
/// there"): `cargo update` would move them.
const HELD: &[(&str, &str, &str)] = &[(
    "crc32fast",
    "1.4.2",
    "1.5 adds a runtime-dispatched AVX-512 path the wheel's x86-64-v3 check refuses; restore with `cargo update -p crc32fast --precise 1.4.2`",
)];

/// Each [`HELD`] crate found in the Cargo.lock `lock` at another version.
pub(crate) fn check_held(lock: &str) -> Vec<String> {
    let mut problems = Vec::new();
    let mut name = None;
    for line in lock.lines() {
        if let Some(n) = line.strip_prefix("name = ") {
            name = Some(n.trim_matches('"').to_owned());
        } else if let Some(v) = line.strip_prefix("version = ") {
            let version = v.trim_matches('"');
            if let Some((crate_name, held, why)) = HELD.iter().find(|(c, _, _)| name.as_deref() == Some(*c))
                && version != *held
            {
                problems.push(format!("Cargo.lock: {crate_name} {version}, held at {held}: {why}"));
            }
        }
    }
    problems
}

/// The `[workspace] members` of the root manifest `text`, as written.
pub(crate) fn workspace_members(text: &str) -> std::result::Result<Vec<String>, String> {
    let manifest: Table = text.parse().map_err(|err| format!("cannot parse: {err}"))?;
    let members = manifest
        .get("workspace")
        .and_then(|w| w.get("members"))
        .and_then(Value::as_array)
        .ok_or("has no [workspace] members list")?;
    members.iter().map(|m| m.as_str().map(str::to_owned).ok_or_else(|| format!("member {m} is not a string"))).collect()
}

/// Layout problems: a member that is not a top-level folder (`crates/optics`, `a/b`), or a
/// leftover `crates/` folder (`crates_dir`).
pub(crate) fn check_layout(members: &[String], crates_dir: bool) -> Vec<String> {
    let mut problems = Vec::new();
    for member in members {
        // a downstream example (`examples/custom-lens`) is a crate of its own that uses the
        // project as a user would: one level under examples/, nothing deeper
        let example = member.strip_prefix("examples/").is_some_and(|rest| !rest.is_empty() && !rest.contains('/'));
        if (member.contains('/') && !example) || member.contains('*') {
            problems.push(format!(
                "Cargo.toml: member `{member}` is not a folder at the repository root \
                 (the layout is radiometry/ optics/ noise/ metric/ lenses/ scene/ cli/ xtask/ …)"
            ));
        }
    }
    if crates_dir {
        problems.push("crates/: the crates stand at the repository root, not under crates/".to_owned());
    }
    problems
}

/// Check one member folder (`optics`, `xtask`), pushing `<path>: <problem>` lines.
fn check_member(root: &Path, folder: &str, violations: &mut Vec<String>) -> Result<()> {
    let name = folder.rsplit('/').next().unwrap_or(folder);
    let manifest_path = format!("{folder}/Cargo.toml");
    match fs::read_to_string(root.join(&manifest_path)) {
        Ok(text) => {
            violations
                .extend(check_manifest(name, &text).into_iter().map(|problem| format!("{manifest_path}: {problem}")));
            if let Ok(manifest) = text.parse::<Table>() {
                let unused = unused_dependencies(&manifest, |dirs| rust_sources(&root.join(folder), dirs))?;
                violations.extend(unused.into_iter().map(|problem| format!("{manifest_path}: {problem}")));
            }
        }
        Err(err) => violations.push(format!("{manifest_path}: cannot read: {err}")),
    }

    let mut crate_roots = 0;
    for file in ["src/lib.rs", "src/main.rs"] {
        let path = format!("{folder}/{file}");
        let full = root.join(&path);
        if !full.exists() {
            continue;
        }
        crate_roots += 1;
        let source = fs::read_to_string(&full).with_context(|| format!("cannot read {}", full.display()))?;
        if !opens_with_crate_doc(&source) {
            violations.push(format!("{path}: does not open with a `//!` crate doc comment"));
        }
    }
    // binaries under src/bin/ (`NAME.rs` or `NAME/main.rs`, the benchmark harness's) are crate
    // roots too
    let bins = root.join(folder).join("src/bin");
    let mut binaries: Vec<String> = fs::read_dir(&bins)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|entry| {
            let name = entry.file_name().to_string_lossy().into_owned();
            if entry.path().is_dir() && entry.path().join("main.rs").exists() {
                Some(format!("{folder}/src/bin/{name}/main.rs"))
            } else {
                name.ends_with(".rs").then(|| format!("{folder}/src/bin/{name}"))
            }
        })
        .collect();
    binaries.sort();
    for path in binaries {
        crate_roots += 1;
        let full = root.join(&path);
        let source = fs::read_to_string(&full).with_context(|| format!("cannot read {}", full.display()))?;
        if !opens_with_crate_doc(&source) {
            violations.push(format!("{path}: does not open with a `//!` crate doc comment"));
        }
    }
    if crate_roots == 0 {
        violations.push(format!("{folder}: has neither src/lib.rs, src/main.rs nor src/bin/"));
    }
    Ok(())
}

/// The problems in the manifest `text` of the member in folder `folder`, one line each.
pub(crate) fn check_manifest(folder: &str, text: &str) -> Vec<String> {
    let manifest: Table = match text.parse() {
        Ok(manifest) => manifest,
        Err(err) => return vec![format!("cannot parse: {err}")],
    };
    let mut problems = Vec::new();

    let expected = package_name(folder);
    let found = manifest.get("package").and_then(|package| package.get("name")).and_then(Value::as_str);
    match found {
        Some(name) if name == expected => {}
        Some(name) if expected == folder => {
            problems.push(format!("package name `{name}` differs from its folder name `{folder}`"))
        }
        Some(name) => problems.push(format!("package name `{name}`: the package in `{folder}/` is `{expected}`")),
        None => problems.push("has no [package] name".to_owned()),
    }
    // the Python extension's library is named by its module, the harness has binaries only
    if expected == format!("asnr-{folder}") && !matches!(folder, "python" | "bench") {
        let lib = manifest.get("lib").and_then(|lib| lib.get("name")).and_then(Value::as_str);
        if lib != Some(folder) {
            problems.push(format!(
                "[lib] name is {}: the library of package `{expected}` keeps its folder's name, `name = \"{folder}\"`",
                lib.map_or("missing".to_owned(), |l| format!("`{l}`"))
            ));
        }
    }

    let version_from_workspace = manifest
        .get("package")
        .and_then(|package| package.get("version"))
        .and_then(|v| v.get("workspace"))
        .and_then(Value::as_bool)
        == Some(true);
    if !version_from_workspace {
        problems.push("missing `version.workspace = true` (one version, in the root manifest)".to_owned());
    }

    let lints_from_workspace =
        manifest.get("lints").and_then(|lints| lints.get("workspace")).and_then(Value::as_bool) == Some(true);
    if !lints_from_workspace {
        problems.push("missing `[lints] workspace = true`".to_owned());
    }

    let allowed = RULES.iter().find(|(name, _)| *name == folder).map(|(_, allowed)| *allowed);
    if allowed.is_none() {
        problems.push(format!("no dependency rule for `{folder}`: add it to RULES in xtask/src/tidy.rs"));
    }

    for table in dependency_tables(&manifest) {
        for (key, spec) in table.deps {
            // A renamed dependency (`alias = { package = "optics", .. }`) is still `optics`, and a
            // package named apart from its folder (`asnr`) is its folder's (`cli`).
            let name = spec.get("package").and_then(Value::as_str).unwrap_or(key.as_str());
            let name = PACKAGE_NAMES.iter().find(|(_, package)| *package == name).map_or(name, |(folder, _)| *folder);
            let is_project = RULES.iter().any(|(project, _)| *project == name);
            if is_project
                && table.normal
                && let Some(Allowed::Only(list)) = allowed
                && !list.contains(&name)
            {
                let list = if list.is_empty() { "none".to_owned() } else { list.join(", ") };
                let place =
                    if table.label == "[dependencies]" { String::new() } else { format!(" in {}", table.label) };
                problems.push(format!("depends on {name}{place} (allowed: {list})"));
            }
            let from_workspace = spec.get("workspace").and_then(Value::as_bool) == Some(true);
            if !from_workspace {
                problems.push(format!(
                    "{key} in {} must be `{key}.workspace = true` \
                     (versions and paths only in the root [workspace.dependencies])",
                    table.label
                ));
            }
        }
    }
    problems
}

/// Declared dependencies that no source of the crate names: a normal dependency must be named
/// (`dep::`, `use dep`, `extern crate dep`) in `src/` or `build.rs`, a dev-dependency anywhere in
/// `src/`, `tests/`, `benches/` or `examples/`. `sources(dirs)` gives the text of the crate's
/// `.rs` files under those folders. The `unused_crate_dependencies` lint would do this for one
/// target at a time, and flags every normal dependency in every test target that does not use it.
pub(crate) fn unused_dependencies(
    manifest: &Table,
    sources: impl Fn(&[&str]) -> Result<Vec<String>>,
) -> Result<Vec<String>> {
    let mut problems = Vec::new();
    for table in dependency_tables(manifest) {
        let dirs: &[&str] = if table.normal { &["src", "build.rs"] } else { &["src", "tests", "benches", "examples"] };
        let texts = sources(dirs)?;
        for key in table.deps.keys() {
            let ident = key.replace('-', "_");
            if !texts.iter().any(|text| names_crate(text, &ident)) {
                problems.push(format!(
                    "{key} in {} is named by no source ({}): remove it, or use it",
                    table.label,
                    dirs.join(", ")
                ));
            }
        }
    }
    Ok(problems)
}

/// Whether Rust source `text` names the crate `ident`: `ident::`, `use ident`, or
/// `extern crate ident`, with `ident` a whole word.
pub(crate) fn names_crate(text: &str, ident: &str) -> bool {
    let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
    text.match_indices(ident).any(|(at, _)| {
        let before = text[..at].chars().next_back();
        let after = &text[at + ident.len()..];
        if word(before) || word(after.chars().next()) {
            return false;
        }
        let head = text[..at].trim_end();
        after.trim_start().starts_with("::") || head.ends_with("use") || head.ends_with("extern crate")
    })
}

/// The text of every `.rs` file under `dirs` (folders, or single files) of the crate at `crate_dir`.
fn rust_sources(crate_dir: &Path, dirs: &[&str]) -> Result<Vec<String>> {
    let mut texts = Vec::new();
    let mut stack: Vec<std::path::PathBuf> = dirs.iter().map(|d| crate_dir.join(d)).collect();
    while let Some(path) = stack.pop() {
        if path.is_dir() {
            for entry in fs::read_dir(&path)? {
                stack.push(entry?.path());
            }
        } else if path.is_file() && path.extension().is_some_and(|e| e == "rs") {
            texts.push(fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?);
        }
    }
    Ok(texts)
}

/// The packages of the build (`cargo metadata`) whose `rust-version` is newer than the
/// workspace's `rust-version` (in the root manifest `text`): the workspace's would then be a
/// promise the build cannot keep. The workspace's own code is held to it by clippy's
/// `incompatible_msrv` lint (std items stabilized later), part of `clippy -D warnings`.
fn check_rust_version(root: &Path, text: &str) -> Result<Vec<String>> {
    let manifest: Table = text.parse().context("Cargo.toml")?;
    let Some(ours) = manifest
        .get("workspace")
        .and_then(|w| w.get("package"))
        .and_then(|p| p.get("rust-version"))
        .and_then(Value::as_str)
    else {
        return Ok(vec!["Cargo.toml: [workspace.package] has no rust-version".to_owned()]);
    };
    let output = Command::new("cargo")
        .args(["metadata", "--format-version", "1", "--locked"])
        .current_dir(root)
        .stderr(std::process::Stdio::inherit())
        .output()
        .context("could not run `cargo metadata`")?;
    if !output.status.success() {
        bail!("`cargo metadata --format-version 1 --locked` failed");
    }
    let metadata: serde_json::Value = serde_json::from_slice(&output.stdout).context("cargo metadata's JSON")?;
    let mut problems = Vec::new();
    for package in metadata["packages"].as_array().map_or(&[][..], Vec::as_slice) {
        if let Some(theirs) = package["rust_version"].as_str()
            && newer(theirs, ours)
        {
            problems.push(format!(
                "Cargo.toml: rust-version = \"{ours}\", but {} {} needs Rust {theirs}: raise ours or hold that dependency back",
                package["name"].as_str().unwrap_or("?"),
                package["version"].as_str().unwrap_or("?")
            ));
        }
    }
    Ok(problems)
}

/// One version in one place: every project crate in the root manifest `text`'s
/// `[workspace.dependencies]` carries the `version` of `[workspace.package]` (cargo needs one on a
/// path dependency to publish), and no member sets a version of its own (checked per member:
/// `version.workspace = true`).
pub(crate) fn check_versions(text: &str) -> Vec<String> {
    let Ok(manifest) = text.parse::<Table>() else { return Vec::new() };
    let workspace = manifest.get("workspace");
    let ours = workspace.and_then(|w| w.get("package")).and_then(|p| p.get("version")).and_then(Value::as_str);
    let Some(ours) = ours else { return vec!["Cargo.toml: [workspace.package] has no version".to_owned()] };
    let mut problems = Vec::new();
    if let Some(deps) = workspace.and_then(|w| w.get("dependencies")).and_then(Value::as_table) {
        for (key, spec) in deps {
            if spec.get("path").is_none() {
                continue;
            }
            let version = spec.get("version").and_then(Value::as_str);
            if version != Some(ours) {
                problems.push(format!(
                    "Cargo.toml: [workspace.dependencies] {key} has version {}: expected \"{ours}\", the workspace's",
                    version.map_or("none".to_owned(), |v| format!("\"{v}\""))
                ));
            }
        }
    }
    problems
}

/// `CITATION.cff`'s `version:` line must be the workspace's version (root manifest `text`).
pub(crate) fn check_citation_version(text: &str, citation: &str) -> Vec<String> {
    let ours = text
        .parse::<Table>()
        .ok()
        .and_then(|m| m.get("workspace")?.get("package")?.get("version")?.as_str().map(str::to_owned));
    let cited = citation.lines().find_map(|l| l.strip_prefix("version:")).map(|v| v.trim().trim_matches('"'));
    match (ours, cited) {
        (Some(ours), Some(cited)) if ours == cited => Vec::new(),
        (ours, cited) => vec![format!(
            "CITATION.cff: version {} is not the workspace's {}",
            cited.unwrap_or("(none)"),
            ours.as_deref().unwrap_or("(none)")
        )],
    }
}

/// Whether Rust version `a` (`1.89`, `1.89.0`) is newer than `b`.
pub(crate) fn newer(a: &str, b: &str) -> bool {
    let parts = |v: &str| -> Vec<u64> { v.split('.').map(|p| p.trim().parse().unwrap_or(0)).collect() };
    let (mut a, mut b) = (parts(a), parts(b));
    a.resize(3, 0);
    b.resize(3, 0);
    a > b
}

/// One dependency table of a manifest.
struct DepTable<'a> {
    /// How the table is written in the manifest, for messages.
    label: String,
    /// Whether it is a normal (or build) dependency table rather than dev-dependencies.
    normal: bool,
    deps: &'a Table,
}

/// All dependency tables: top-level and `[target.<cfg>.*]`.
fn dependency_tables(manifest: &Table) -> Vec<DepTable<'_>> {
    const KINDS: [(&str, bool); 3] =
        [("dependencies", true), ("build-dependencies", true), ("dev-dependencies", false)];
    let mut tables = Vec::new();
    for (kind, normal) in KINDS {
        if let Some(deps) = manifest.get(kind).and_then(Value::as_table) {
            tables.push(DepTable { label: format!("[{kind}]"), normal, deps });
        }
    }
    if let Some(targets) = manifest.get("target").and_then(Value::as_table) {
        for (cfg, target) in targets {
            for (kind, normal) in KINDS {
                if let Some(deps) = target.get(kind).and_then(Value::as_table) {
                    tables.push(DepTable { label: format!("[target.'{cfg}'.{kind}]"), normal, deps });
                }
            }
        }
    }
    tables
}

/// Text that points outside the repository: the sibling `shared` folder of the project's
/// workspace, its conventions page (the repository's copy is `docs/physics.md`) and the paper's
/// file (cite the paper by title and authors). Written with `concat!` so that this file does not
/// match itself.
pub(crate) const OUTSIDE_PATTERNS: &[&str] = &[
    concat!("../", "shared"),
    concat!("shared/", "PHYSICS", ".md"),
    concat!("shared/", "paper"),
    concat!("PHYSICS", ".md"),
];

/// The file types checked for [`OUTSIDE_PATTERNS`].
const CHECKED_EXTENSIONS: &[&str] = &["md", "rs", "toml"];

/// The `path:line: refers to … outside the repository` problems of one tracked file.
pub(crate) fn outside_references(path: &str, text: &str) -> Vec<String> {
    let mut problems = Vec::new();
    for (number, line) in text.lines().enumerate() {
        // The first pattern that matches names the problem: the most specific come first.
        if let Some(pattern) = OUTSIDE_PATTERNS.iter().find(|pattern| line.contains(**pattern)) {
            problems.push(format!(
                "{path}:{}: refers to `{pattern}`, outside the repository (cite docs/physics.md, \
                 or the paper by title and authors)",
                number + 1
            ));
        }
    }
    problems
}

/// Check every tracked `*.md`, `*.rs`, `*.toml` file of the repository at `root` (and the
/// string literals of the `*.rs` files, [`spaced_literals`]).
fn check_outside_references(root: &Path) -> Result<Vec<String>> {
    let output = Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root)
        .output()
        .context("could not run `git ls-files` (tidy needs git and a clone)")?;
    if !output.status.success() {
        bail!("`git ls-files` failed: {}", String::from_utf8_lossy(&output.stderr).trim());
    }
    let mut problems = Vec::new();
    for path in String::from_utf8_lossy(&output.stdout).split('\0').filter(|path| !path.is_empty()) {
        let checked = Path::new(path)
            .extension()
            .and_then(|extension| extension.to_str())
            .is_some_and(|extension| CHECKED_EXTENSIONS.contains(&extension));
        if !checked {
            continue;
        }
        // A tracked file deleted in the work tree is not there to refer to anything.
        let Ok(text) = fs::read_to_string(root.join(path)) else { continue };
        problems.extend(outside_references(path, &text));
        if path.ends_with(".rs") {
            problems.extend(spaced_literals(path, &text));
        }
    }
    Ok(problems)
}

/// The shortest run of spaces inside a string literal that [`spaced_literals`] reports.
const SPACED_RUN: usize = 8;

/// The widest text before a run of spaces on its line of a literal's text that is a table's
/// label or column heading (`"capped black        μ = …"`, `"best of the grid points
/// ASNR …"`, `"Spatial frequency      Tangential        Sagittal"`), not a sentence: the
/// joined lines of a broken literal put 60 or more characters before the run.
const LABEL_WIDTH: usize = 40;

/// The `path:line: a run of N spaces inside a string literal` problems of one Rust source:
/// a run of [`SPACED_RUN`] or more spaces on one line of a `"…"` literal's text (raw literals
/// aside), preceded by a letter, a comma or `)` and followed by a letter or `(`, that is between
/// two words of a sentence, after more than [`LABEL_WIDTH`] characters of its line. It is what
/// a literal broken over lines without its continuation backslashes becomes once the lines are
/// joined: the next line's indentation inside the text. A table's label or column heading has
/// fewer characters before its run, and a column of numbers (`"{x:>8}        {y}"`,
/// `"1.0        2.0"`) is not between two words.
pub(crate) fn spaced_literals(path: &str, source: &str) -> Vec<String> {
    let chars: Vec<char> = source.chars().collect();
    let mut problems = Vec::new();
    let mut line = 1;
    let mut i = 0;
    // Count the newlines of chars[from..to] into `line`.
    let advance = |line: &mut usize, from: usize, to: usize| {
        *line += chars[from..to.min(chars.len())].iter().filter(|&&c| c == '\n').count();
    };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            let end = chars[i..].iter().position(|&c| c == '\n').map_or(chars.len(), |n| i + n);
            i = end;
        } else if c == '/' && next == Some('*') {
            // block comments nest in Rust
            let (mut depth, mut j) = (1, i + 2);
            while j < chars.len() && depth > 0 {
                if chars[j] == '/' && chars.get(j + 1) == Some(&'*') {
                    depth += 1;
                    j += 2;
                } else if chars[j] == '*' && chars.get(j + 1) == Some(&'/') {
                    depth -= 1;
                    j += 2;
                } else {
                    j += 1;
                }
            }
            advance(&mut line, i, j);
            i = j;
        } else if c == 'r' && matches!(next, Some('"' | '#')) && starts_raw(&chars, i) {
            // a raw literal r"…" or r#"…"# (or br…): skipped, its text is verbatim by design
            let hashes = chars[i + 1..].iter().take_while(|&&c| c == '#').count();
            if chars.get(i + 1 + hashes) != Some(&'"') {
                i += 1;
                continue;
            }
            let mut j = i + 2 + hashes;
            while j < chars.len()
                && !(chars[j] == '"' && chars[j + 1..].iter().take(hashes).filter(|&&c| c == '#').count() == hashes)
            {
                j += 1;
            }
            let end = (j + 1 + hashes).min(chars.len());
            advance(&mut line, i, end);
            i = end;
        } else if c == '"' {
            // a "…" literal: walk its text line by line (of the text: `\n`, `\r` and a newline end
            // one, a `\` at a source line's end joins two), noting each run of spaces
            let (mut j, mut label) = (i + 1, 0usize);
            while j < chars.len() && chars[j] != '"' {
                match (chars[j], chars.get(j + 1)) {
                    ('\\', Some('\n')) => {
                        // the continuation skips the next line's indentation
                        line += 1;
                        j += 2;
                        while chars.get(j).is_some_and(|c| c.is_whitespace()) {
                            if chars[j] == '\n' {
                                line += 1;
                            }
                            j += 1;
                        }
                    }
                    ('\\', Some('n' | 'r')) => {
                        label = 0;
                        j += 2;
                    }
                    ('\\', _) => {
                        label += 1;
                        j += 2;
                    }
                    ('\n', _) => {
                        line += 1;
                        label = 0;
                        j += 1;
                    }
                    (' ', _) => {
                        let run = chars[j..].iter().take_while(|&&c| c == ' ').count();
                        let before = chars[j - 1];
                        let after = chars.get(j + run).copied().unwrap_or('"');
                        if run >= SPACED_RUN
                            && label > LABEL_WIDTH
                            && (before.is_alphabetic() || matches!(before, ',' | ')'))
                            && (after.is_alphabetic() || after == '(')
                        {
                            problems.push(format!(
                                "{path}:{line}: a run of {run} spaces between two words inside a string literal \
                                 (a literal broken over lines without `\\` at each line's end?)"
                            ));
                        }
                        // leading spaces are indentation, not part of a label
                        if label > 0 {
                            label += run;
                        }
                        j += run;
                    }
                    _ => {
                        label += 1;
                        j += 1;
                    }
                }
            }
            i = j + 1;
        } else if c == '\'' {
            // a char literal ('"', '\'', '\u{..}') or a lifetime ('a)
            if next == Some('\\') {
                let end = chars[i + 2..].iter().position(|&c| c == '\'').map_or(chars.len(), |n| i + 2 + n + 1);
                i = end;
            } else if chars.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
        } else {
            if c == '\n' {
                line += 1;
            }
            i += 1;
        }
    }
    problems
}

/// Whether the `r` at `chars[i]` opens a raw literal (`r"`, `r#"`, `br"`, `cr"`) rather than
/// ending an identifier (`bar"` is not Rust, but `for r in` is).
fn starts_raw(chars: &[char], i: usize) -> bool {
    let ident = |k: Option<usize>| k.is_some_and(|k| chars[k].is_alphanumeric() || chars[k] == '_');
    match i.checked_sub(1) {
        None => true,
        Some(k) if matches!(chars[k], 'b' | 'c') => !ident(k.checked_sub(1)),
        Some(k) => !ident(Some(k)),
    }
}

/// Whether the first non-blank line of `source` is a `//!` doc comment.
pub(crate) fn opens_with_crate_doc(source: &str) -> bool {
    source.lines().map(str::trim).find(|line| !line.is_empty()).is_some_and(|line| line.starts_with("//!"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const CLEAN_METRIC: &str = r#"
        [package]
        name = "asnr-metric"
        version.workspace = true

        [lib]
        name = "metric"

        [dependencies]
        optics.workspace = true
        noise = { workspace = true }
        radiometry.workspace = true
        serde = { workspace = true, features = ["derive"] }

        [dev-dependencies]
        lenses.workspace = true

        [lints]
        workspace = true
    "#;

    #[test]
    fn clean_manifest_has_no_problems() {
        assert_eq!(check_manifest("metric", CLEAN_METRIC), Vec::<String>::new());
    }

    #[test]
    fn violating_manifest_reports_every_problem() {
        let manifest = r#"
            [package]
            name = "metrics"

            [dependencies]
            optics.workspace = true
            lenses.workspace = true
            serde = "1"

            [target.'cfg(unix)'.dependencies]
            libm = { version = "0.2" }
        "#;
        assert_eq!(
            check_manifest("metric", manifest),
            vec![
                "package name `metrics`: the package in `metric/` is `asnr-metric`",
                "[lib] name is missing: the library of package `asnr-metric` keeps its folder's name, `name = \"metric\"`",
                "missing `version.workspace = true` (one version, in the root manifest)",
                "missing `[lints] workspace = true`",
                "depends on lenses (allowed: optics, noise, radiometry)",
                "serde in [dependencies] must be `serde.workspace = true` \
                 (versions and paths only in the root [workspace.dependencies])",
                "libm in [target.'cfg(unix)'.dependencies] must be `libm.workspace = true` \
                 (versions and paths only in the root [workspace.dependencies])",
            ]
        );
    }

    #[test]
    fn leaf_crate_allows_no_project_crate_and_renames_are_seen_through() {
        let manifest = r#"
            [package]
            name = "asnr-radiometry"
            version.workspace = true
            [lib]
            name = "radiometry"
            [build-dependencies]
            opt = { package = "asnr-optics", workspace = true }
            [lints]
            workspace = true
        "#;
        assert_eq!(
            check_manifest("radiometry", manifest),
            vec!["depends on optics in [build-dependencies] (allowed: none)"]
        );
    }

    #[test]
    fn cli_may_depend_on_anything_and_unknown_crates_need_a_rule() {
        let cli = "[package]\nname = \"asnr\"\nversion.workspace = true\n[dependencies]\nlenses.workspace = true\n\
                   metric.workspace = true\n[lints]\nworkspace = true\n";
        assert!(check_manifest("cli", cli).is_empty());
        let unknown = "[package]\nname = \"extra\"\nversion.workspace = true\n[lints]\nworkspace = true\n";
        assert_eq!(
            check_manifest("extra", unknown),
            vec!["no dependency rule for `extra`: add it to RULES in xtask/src/tidy.rs"]
        );
        assert_eq!(check_manifest("cli", "[package").len(), 1);
        let named_cli = "[package]\nname = \"cli\"\nversion.workspace = true\n[lints]\nworkspace = true\n";
        assert_eq!(check_manifest("cli", named_cli), vec!["package name `cli`: the package in `cli/` is `asnr`"]);
    }

    #[test]
    fn a_held_crate_at_another_version_is_named() {
        let held = "[[package]]\nname = \"crc32fast\"\nversion = \"1.4.2\"\n";
        assert!(check_held(held).is_empty());
        let moved = "[[package]]\nname = \"crc32fast\"\nversion = \"1.5.4\"\n";
        let problems = check_held(moved);
        assert_eq!(problems.len(), 1);
        assert!(problems[0].contains("crc32fast 1.5.4, held at 1.4.2"), "{problems:?}");
    }

    #[test]
    fn the_python_extension_may_not_depend_on_the_command_line() {
        let python = "[package]\nname = \"asnr-python\"\nversion.workspace = true\n[dependencies]\nreport.workspace = true\n\
                      asnr.workspace = true\n[lints]\nworkspace = true\n";
        assert_eq!(
            check_manifest("python", python),
            vec![
                "depends on cli (allowed: report, imaging, scene, metric, lenses, optics, noise, radiometry, workspace-hack)"
            ]
        );
    }

    #[test]
    fn a_dependency_no_source_names_is_found() {
        let manifest: Table = "[dependencies]\nserde.workspace = true\nrand_pcg.workspace = true\n\
                               [dev-dependencies]\napprox.workspace = true\n"
            .parse()
            .unwrap();
        let src = "use serde::Serialize;\nfn f() { let _ = rand_pcg_like::X; }\n".to_owned();
        let test = "use approx::assert_relative_eq;\n".to_owned();
        let problems = unused_dependencies(&manifest, |dirs| {
            Ok(if dirs.contains(&"tests") { vec![src.clone(), test.clone()] } else { vec![src.clone()] })
        })
        .unwrap();
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert!(problems[0].starts_with("rand_pcg in [dependencies] is named by no source"), "{problems:?}");
        assert!(names_crate("extern crate foo;", "foo") && names_crate("x = foo ::bar()", "foo"));
        assert!(!names_crate("let foo = 1; foo_bar::x();", "foo") && !names_crate("a.foo::<u8>()", "foo_x"));
    }

    #[test]
    fn project_crates_carry_the_workspace_version() {
        let root = "[workspace.package]\nversion = \"0.2.0\"\n[workspace.dependencies]\n\
                    optics = { package = \"asnr-optics\", path = \"optics\", version = \"0.2.0\" }\n\
                    noise = { package = \"asnr-noise\", path = \"noise\", version = \"0.1.0\" }\n\
                    metric = { package = \"asnr-metric\", path = \"metric\" }\nserde = \"1\"\n";
        assert_eq!(
            check_versions(root),
            vec![
                "Cargo.toml: [workspace.dependencies] metric has version none: expected \"0.2.0\", the workspace's",
                "Cargo.toml: [workspace.dependencies] noise has version \"0.1.0\": expected \"0.2.0\", the workspace's",
            ]
        );
    }

    #[test]
    fn the_citation_cites_the_workspace_version() {
        let root = "[workspace.package]\nversion = \"0.2.0\"\n";
        assert!(check_citation_version(root, "cff-version: 1.2.0\nversion: 0.2.0\n").is_empty());
        assert_eq!(
            check_citation_version(root, "cff-version: 1.2.0\nversion: \"0.1.0\"\n"),
            vec!["CITATION.cff: version 0.1.0 is not the workspace's 0.2.0"]
        );
    }

    #[test]
    fn rust_versions_compare_by_number() {
        assert!(newer("1.90", "1.89") && newer("1.89.1", "1.89") && newer("1.100", "1.99.9"));
        assert!(!newer("1.89.0", "1.89") && !newer("1.88", "1.89") && !newer("1.9", "1.89"));
    }

    #[test]
    fn members_stand_at_the_root() {
        let members = workspace_members("[workspace]\nmembers = [\"optics\", \"crates/metric\"]\n").unwrap();
        assert_eq!(members, ["optics", "crates/metric"]);
        let problems = check_layout(&members, true);
        assert_eq!(problems.len(), 2, "{problems:?}");
        assert!(problems[0].contains("`crates/metric` is not a folder at the repository root"));
        assert!(problems[1].starts_with("crates/"));
        assert!(check_layout(&["optics".to_owned(), "xtask".to_owned()], false).is_empty());
        // downstream examples one level under examples/, and no deeper
        assert!(check_layout(&["examples/custom-lens".to_owned()], false).is_empty());
        assert_eq!(check_layout(&["examples/a/b".to_owned(), "examples/".to_owned()], false).len(), 2);
        assert!(workspace_members("[package]\nname = \"x\"\n").is_err());
    }

    #[test]
    fn references_outside_the_repository_are_found() {
        let up = concat!("../", "shared");
        let conventions = concat!("PHYSICS", ".md");
        let text = format!(
            "//! Conventions: docs/physics.md, \"Optics\".\n\
             /// See `{up}/{conventions}`.\n\
             /// ({conventions}, \"The metric\")\n\
             /// the paper: {up}/paper/how-good-is-your-metalens.md\n\
             pub const PHYSICS_TEST_VECTORS: [f64; 0] = [];\n"
        );
        let problems = outside_references("optics/src/x.rs", &text);
        assert_eq!(problems.len(), 3, "{problems:?}");
        assert!(problems[0].starts_with(&format!("optics/src/x.rs:2: refers to `{up}`")), "{problems:?}");
        assert!(problems[1].starts_with(&format!("optics/src/x.rs:3: refers to `{conventions}`")), "{problems:?}");
        assert!(problems[2].starts_with("optics/src/x.rs:4:"), "{problems:?}");
        assert!(outside_references("README.md", "See docs/physics.md and ARCHITECTURE.md.\n").is_empty());
    }

    #[test]
    fn the_repository_refers_to_nothing_outside_it() {
        let problems = check_outside_references(&crate::project_root()).unwrap();
        assert!(problems.is_empty(), "{}", problems.join("\n"));
    }

    #[test]
    fn spaced_runs_inside_literals_are_found() {
        // the bug: a literal whose lines were joined, each next line's indentation kept
        let sentence = "off axis the oblique wave's aberrations move with the aperture radius too, which the";
        let joined = format!(
            "fn f() -> &'static str {{\n    \"{sentence}{}radial engine's lanes do not follow\"\n}}\n",
            " ".repeat(18)
        );
        let problems = spaced_literals("metric/src/x.rs", &joined);
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert!(problems[0].starts_with("metric/src/x.rs:2: a run of 18 spaces"), "{problems:?}");
        // after a comma or ')' and before '(' too, on the literal's third source line (the
        // continued line's text joins the first's)
        let broken = format!("let s = \"{}a,\\\n   b\n {sentence}),        (d\";\n", "x".repeat(LABEL_WIDTH));
        let problems = spaced_literals("x.rs", &broken);
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert!(problems[0].starts_with("x.rs:3: a run of 8 spaces"), "{problems:?}");
        // the first line's words count for the second after a continuation
        let continued = format!("let s = \"{}\\\n      more words        here\";\n", "y".repeat(LABEL_WIDTH));
        assert_eq!(spaced_literals("x.rs", &continued).len(), 1);
        // not found: continuation lines, seven spaces, labels and column headings (also after
        // `\n`), columns of numbers, comments, raw literals, char literals and lifetimes beside
        // a literal
        let clean = format!(
            "let a = \"{sentence}, \\\n{pad}second line\";\n\
             let b = \"{sentence}{seven}spaces\";\n\
             let c = \"{{x:>8}}{pad}{{y}}  |{pad}|  {sentence} 1.0{pad}2.0\";\n\
             let l = \"best of the grid points{pad}ASNR {{}}\\nSpatial frequency{pad}Tangential{pad}Sagittal\";\n\
             // a comment {sentence}{pad}with spaces\n\
             /* a block {sentence}{pad}comment /* nested */ still {sentence}{pad}comment */\n\
             let d = r#\"raw {sentence}{pad}text\"#;\n\
             let e = ('\"', '\\'', \"quote\");\n\
             fn g<'a>(x: &'a str) -> &'a str {{ \"fine\" }}\n",
            pad = " ".repeat(12),
            seven = " ".repeat(7),
        );
        assert!(spaced_literals("y.rs", &clean).is_empty(), "{:?}", spaced_literals("y.rs", &clean));
    }

    #[test]
    fn crate_doc_must_come_first() {
        assert!(opens_with_crate_doc("\n//! Radiometry.\npub fn f() {}\n"));
        assert!(!opens_with_crate_doc("pub mod x;\n//! late\n"));
        assert!(!opens_with_crate_doc("/// item doc\nfn main() {}\n"));
        assert!(!opens_with_crate_doc(""));
    }
}
