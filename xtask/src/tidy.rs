//! `cargo xtask tidy`: the architecture invariants, checked by reading each member's
//! `Cargo.toml` (with the `toml` crate) and crate root.
//!
//! For every folder under `crates/`, and for `xtask/`:
//! - the package name equals the folder name;
//! - the project crates in its normal dependencies (`[dependencies]`, `[build-dependencies]`
//!   and their `[target.*]` forms) are among those [`RULES`] allows; dev-dependencies may use
//!   any project crate (so `metric` tests may use `lenses`);
//! - every dependency is `name.workspace = true`, so versions and paths live only in the root
//!   `[workspace.dependencies]`;
//! - it has `[lints] workspace = true`;
//! - `src/lib.rs` and `src/main.rs`, whichever exist, open with a `//!` crate doc comment.

use std::fs;
use std::path::Path;

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
    ("cli", Allowed::Any),
    ("xtask", Allowed::Only(&[])),
];

/// Check every member under the workspace `root`; print each violation as
/// `tidy: <path>: <problem>` and fail if there is any.
pub(crate) fn run(root: &Path) -> Result<()> {
    let crates_dir = root.join("crates");
    let mut folders = Vec::new();
    for entry in fs::read_dir(&crates_dir).with_context(|| format!("cannot list {}", crates_dir.display()))? {
        let entry = entry?;
        if entry.file_type()?.is_dir() {
            folders.push(format!("crates/{}", entry.file_name().to_string_lossy()));
        }
    }
    folders.sort();
    folders.push("xtask".to_owned());

    let mut violations = Vec::new();
    for folder in &folders {
        check_member(root, folder, &mut violations)?;
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

/// Check one member folder (`crates/optics`, `xtask`), pushing `<path>: <problem>` lines.
fn check_member(root: &Path, folder: &str, violations: &mut Vec<String>) -> Result<()> {
    let name = folder.rsplit('/').next().unwrap_or(folder);
    let manifest_path = format!("{folder}/Cargo.toml");
    match fs::read_to_string(root.join(&manifest_path)) {
        Ok(text) => violations
            .extend(check_manifest(name, &text).into_iter().map(|problem| format!("{manifest_path}: {problem}"))),
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
    if crate_roots == 0 {
        violations.push(format!("{folder}: has neither src/lib.rs nor src/main.rs"));
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

    let package_name = manifest.get("package").and_then(|package| package.get("name")).and_then(Value::as_str);
    match package_name {
        Some(name) if name == folder => {}
        Some(name) => problems.push(format!("package name `{name}` differs from its folder name `{folder}`")),
        None => problems.push("has no [package] name".to_owned()),
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
            // A renamed dependency (`alias = { package = "optics", .. }`) is still `optics`.
            let name = spec.get("package").and_then(Value::as_str).unwrap_or(key.as_str());
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

/// Whether the first non-blank line of `source` is a `//!` doc comment.
pub(crate) fn opens_with_crate_doc(source: &str) -> bool {
    source.lines().map(str::trim).find(|line| !line.is_empty()).is_some_and(|line| line.starts_with("//!"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const CLEAN_METRIC: &str = r#"
        [package]
        name = "metric"
        version.workspace = true

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
                "package name `metrics` differs from its folder name `metric`",
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
            name = "radiometry"
            [build-dependencies]
            opt = { package = "optics", workspace = true }
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
        let cli = "[package]\nname = \"cli\"\n[dependencies]\nlenses.workspace = true\n\
                   metric.workspace = true\n[lints]\nworkspace = true\n";
        assert!(check_manifest("cli", cli).is_empty());
        let unknown = "[package]\nname = \"extra\"\n[lints]\nworkspace = true\n";
        assert_eq!(
            check_manifest("extra", unknown),
            vec!["no dependency rule for `extra`: add it to RULES in xtask/src/tidy.rs"]
        );
        assert_eq!(check_manifest("cli", "[package").len(), 1);
    }

    #[test]
    fn crate_doc_must_come_first() {
        assert!(opens_with_crate_doc("\n//! Radiometry.\npub fn f() {}\n"));
        assert!(!opens_with_crate_doc("pub mod x;\n//! late\n"));
        assert!(!opens_with_crate_doc("/// item doc\nfn main() {}\n"));
        assert!(!opens_with_crate_doc(""));
    }
}
