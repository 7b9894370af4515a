//! Helpers the end-to-end test files share: run the `asnr` binary, read its output, expect a
//! clean failure.
// each test file uses its own subset
#![allow(dead_code)]

use std::process::{Command, Output};

/// Runs the `asnr` binary built for these tests.
pub fn asnr(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asnr")).args(args).output().expect("the asnr binary runs")
}

/// Its standard error as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `asnr` expecting failure; returns stderr after checking the exit code, that it did not
/// panic, and that only warnings (about the values: unit slips) precede the error message.
pub fn fails(args: &[&str]) -> String {
    let out = asnr(args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "args {args:?}: expected exit 1, stderr: {err}");
    assert!(!err.contains("panicked"), "args {args:?} panicked: {err}");
    let error = err.find("error: ").unwrap_or_else(|| panic!("args {args:?}: no error message: {err}"));
    assert!(err[..error].lines().all(|l| l.starts_with("warning: ")), "args {args:?}: {err}");
    err
}

/// Runs `asnr` expecting success and one JSON object on stdout.
pub fn json(args: &[&str]) -> serde_json::Value {
    let out = asnr(args);
    assert!(out.status.success(), "args {args:?}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("one JSON object on stdout")
}

/// The ASNR of the paper scene with each of `set` given as `--set`, from `asnr evaluate --json`.
pub fn asnr_at(set: &[String]) -> f64 {
    let mut args = vec!["evaluate", "--json"];
    for s in set {
        args.extend(["--set", s.as_str()]);
    }
    json(&args)["asnr"].as_f64().unwrap()
}
