//! The packages the README builds alone resolve every dependency's features as the test build
//! does (a tidy check), so that after `cargo test --workspace` their commands compile nothing
//! again: `cargo asnr …`, `cargo run -p custom-lens`, `cargo test -p custom-lens` and
//! `cargo run -p asnr-scene --example …`.
//!
//! Cargo resolves features over the packages a command selects: the test build's set includes
//! what the dev-dependencies and the Python package turn on, a single package's does not, and
//! where they differ every crate above the difference is compiled twice (minutes in CI). The
//! `workspace-hack` package asks for the difference; this check says what is missing from it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use anyhow::{Context, Result, bail};

/// The builds of single packages that the README runs: `(what the README runs, cargo tree
/// arguments that resolve the same graph)`.
const ALONE: &[(&str, &[&str])] = &[
    ("cargo asnr", &["-p", "asnr", "-e", "normal,build"]),
    ("cargo run -p custom-lens", &["-p", "custom-lens", "-e", "normal,build"]),
    ("cargo test -p custom-lens", &["-p", "custom-lens", "-e", "normal,build,dev"]),
    ("cargo run -p asnr-scene --example", &["-p", "asnr-scene", "-e", "normal,build,dev"]),
    ("maturin build (python/)", &["-p", "asnr-python", "-e", "normal,build"]),
];

/// A resolved graph: each package's name and the features on it.
type Resolved = BTreeMap<String, BTreeSet<String>>;

/// Parse `cargo tree -e features --prefix none`: lines `name vX.Y.Z …` (a package) and
/// `name feature "f"` (a feature on it).
pub(crate) fn parse_tree(text: &str) -> Resolved {
    let mut resolved = Resolved::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let (Some(name), Some(second)) = (words.next(), words.next()) else { continue };
        let features = resolved.entry(name.to_owned()).or_default();
        if second == "feature"
            && let Some(feature) = words.next()
        {
            features.insert(feature.trim_matches('"').to_owned());
        }
    }
    resolved
}

/// The features the workspace's test build puts on a package of `alone` that `alone` lacks:
/// `package "feature"`, one a line; the root package's own features are the command line's.
pub(crate) fn missing(workspace: &Resolved, alone: &Resolved, root: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (package, features) in alone {
        if package == root {
            continue;
        }
        if let Some(wanted) = workspace.get(package) {
            out.extend(wanted.difference(features).map(|f| format!("{package} \"{f}\"")));
        }
    }
    out
}

fn tree(root: &Path, args: &[&str]) -> Result<Resolved> {
    let mut command = crate::cmd::cargo(root, &["tree", "--locked", "--prefix", "none"]);
    command.args(args);
    // `-e features` beside the edge kinds of `args`
    let output = command.output().context("could not run `cargo tree`")?;
    if !output.status.success() {
        bail!("`{}` failed: {}", crate::cmd::display(&command), String::from_utf8_lossy(&output.stderr));
    }
    Ok(parse_tree(&String::from_utf8_lossy(&output.stdout)))
}

/// With edge kinds `-e KINDS`, add `features` to them.
fn with_features(args: &[&str]) -> Vec<String> {
    let mut out: Vec<String> = args.iter().map(|a| (*a).to_owned()).collect();
    if let Some(i) = out.iter().position(|a| a == "-e") {
        out[i + 1].push_str(",features");
    }
    out
}

/// The violations: for each package built alone, the features it resolves apart from the test
/// build, and what to add to workspace-hack/Cargo.toml.
pub(crate) fn check(root: &Path) -> Result<Vec<String>> {
    let args = with_features(&["--workspace", "-e", "normal,build,dev"]);
    let workspace = tree(root, &args.iter().map(String::as_str).collect::<Vec<_>>())?;
    let mut violations = Vec::new();
    for (what, alone) in ALONE {
        let args = with_features(alone);
        let resolved = tree(root, &args.iter().map(String::as_str).collect::<Vec<_>>())?;
        let missing = missing(&workspace, &resolved, alone[1]);
        if !missing.is_empty() {
            violations.push(format!(
                "`{what}` resolves dependency features apart from `cargo test --workspace`, so it compiles the crates \
                 above them again: add to workspace-hack/Cargo.toml {}",
                missing.join(", ")
            ));
        }
    }
    Ok(violations)
}

#[cfg(test)]
mod tests {
    use super::*;

    const WORKSPACE: &str = "asnr v0.1.0 (/w/cli)\nserde v1.0.0\nserde feature \"alloc\"\nserde feature \"std\"\n\
                             rand v0.10.0\nrand feature \"sys_rng\"\nasnr feature \"default\"\n";

    #[test]
    fn a_feature_the_test_build_adds_is_missing_until_asked_for() {
        let workspace = parse_tree(WORKSPACE);
        let alone = parse_tree("asnr v0.1.0 (/w/cli)\nserde v1.0.0\nserde feature \"std\"\n");
        // rand is not in the graph alone: nothing to share; asnr's own features are the command's
        assert_eq!(missing(&workspace, &alone, "asnr"), vec!["serde \"alloc\"".to_owned()]);
        let alone = parse_tree("asnr v0.1.0\nserde v1.0.0\nserde feature \"std\"\nserde feature \"alloc\"\n");
        assert!(missing(&workspace, &alone, "asnr").is_empty());
    }
}
