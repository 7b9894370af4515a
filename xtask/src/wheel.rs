//! `cargo xtask wheel`: the Python package as one portable wheel, built and checked.
//!
//! - **Build**: `maturin build --release --strip --zig --compatibility manylinux2014` into
//!   `target/wheels/`, in its own target directory (`target/wheel/`, so the workspace's native
//!   build is left as it is), with `RUSTFLAGS="-C target-cpu=x86-64-v3"` on x86-64: the variable
//!   replaces `.cargo/config.toml`'s `target-cpu=native`, so the wheel runs on any x86-64 with
//!   AVX2 and FMA (Intel since 2013, AMD since 2015) and not only on the machine that built it.
//!   zig links against glibc 2.17 symbol versions (manylinux2014), whatever the build machine's
//!   glibc. One wheel serves every CPython ≥ 3.10 (abi3).
//! - **Checks**: `auditwheel show` must find the manylinux_2_17 tag; `abi3audit --strict` must
//!   find no symbol outside the 3.10 stable ABI; and the extension's disassembly (`objdump -d`)
//!   must hold no instruction beyond x86-64-v3: no zmm register, no mask register and no
//!   ymm16–31/xmm16–31 (all AVX-512 only).
//!
//! `cargo xtask python` (a step of CI) and `cargo xtask torch` build [`Kind::Test`]: the same
//! code for the same CPU level and the same abi3 and instruction checks, but compiled by the test
//! build (the `dev` profile, opt-level 2, in `target/` when the build's `RUSTFLAGS` are already
//! [`RUSTFLAGS`], as `.ci/run` sets them), so that CI compiles only the extension and pyo3 for
//! it, and linked by the system's linker: its glibc tag is the build machine's, which only
//! zig's sysroot can lower. The glibc baseline (manylinux_2_17) is therefore checked by
//! `cargo xtask wheel` alone (ARCHITECTURE.md, "CI", says what that trades).
//!
//! No runtime dispatch: a function compiled for AVX-512 can only be called through `unsafe`
//! (`#[target_feature]`), which the workspace forbids (`unsafe_code = "forbid"`); the native
//! build is one flag away (ARCHITECTURE.md, "Build settings", measures what v3 costs).
//!
//! The tools (maturin, auditwheel, abi3audit) come pinned from `python/requirements-wheel.txt`
//! into `target/wheel-tools-venv`; the users' wheel adds ziglang (`python/requirements-zig.txt`)
//! in `target/wheel-release-venv`, so the test wheel of CI does not download zig.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

use crate::cmd;

/// The CPU level the wheel is compiled for (x86-64 hosts).
pub(crate) const CPU: &str = "x86-64-v3";
/// The flags that compile for [`CPU`]; `.ci/run` exports them for the whole of CI on x86-64.
pub(crate) const RUSTFLAGS: &str = "-C target-cpu=x86-64-v3";
/// The tools' virtual environment, relative to the workspace root.
const TOOLS_VENV: &str = "target/wheel-tools-venv";
/// The tools, pinned.
const TOOLS: &str = "python/requirements-wheel.txt";
/// The users' wheel's tools: [`TOOLS`] and zig (maturin `--zig`), in a virtual environment of
/// their own.
const RELEASE_TOOLS_VENV: &str = "target/wheel-release-venv";
/// zig, pinned: the users' wheel alone links with it.
const ZIG: &str = "python/requirements-zig.txt";
/// Cargo's target directory for the users' wheel (other flags and profile than the workspace's).
const TARGET_DIR: &str = "target/wheel";
/// Cargo's target directory for the test wheel when the build's own flags are not [`RUSTFLAGS`]
/// (a developer's native build, left as it is).
const TEST_TARGET_DIR: &str = "target/wheel-test";
/// Where the wheel is written.
const OUT: &str = "target/wheels";
/// The glibc baseline: the manylinux tag maturin builds for and auditwheel must confirm.
const MANYLINUX: &str = "manylinux_2_17_x86_64";

/// Which wheel to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// The wheel for users (`cargo xtask wheel`): release profile, linked by zig against glibc
    /// 2.17 (manylinux2014), in its own target directory.
    Release,
    /// The wheel CI installs and tests (`cargo xtask python`, `cargo xtask torch`): the test
    /// build's `dev` profile and, when its flags are [`RUSTFLAGS`], its artifacts; the system's
    /// linker, so the glibc tag is the build machine's.
    Test,
}

/// `cargo xtask wheel`: build and check the wheel, print its path.
pub(crate) fn run(root: &Path) -> Result<()> {
    let wheel = build(root, Kind::Release)?;
    println!("{}", wheel.display());
    Ok(())
}

/// The target directory of the test wheel: the workspace's own when the environment's
/// `RUSTFLAGS` are [`RUSTFLAGS`] (CI: the test build's dependencies are reused, not compiled
/// again), else one of its own, so that a native build is not overwritten by another CPU level.
fn test_target_dir(root: &Path, rustflags: Option<&str>) -> PathBuf {
    if rustflags.is_some_and(|flags| flags.trim() == RUSTFLAGS) {
        crate::accuracy::target_dir(root)
    } else {
        root.join(TEST_TARGET_DIR)
    }
}

/// Builds the wheel of `kind`, checks it, and returns its path.
pub(crate) fn build(root: &Path, kind: Kind) -> Result<PathBuf> {
    let python = match kind {
        Kind::Release => cmd::venv_of(root, RELEASE_TOOLS_VENV, &[TOOLS, ZIG], "auditwheel, abi3audit, ziglang"),
        Kind::Test => cmd::venv(root, TOOLS_VENV, TOOLS, "auditwheel, abi3audit"),
    }
    .context("the wheel tools")?;
    let bin = python.parent().context("the venv's bin folder")?.to_path_buf();
    let out = root.join(OUT);
    if out.exists() {
        std::fs::remove_dir_all(&out).with_context(|| format!("removing the old {OUT}"))?;
    }
    let path = std::env::join_paths(
        std::iter::once(bin.clone()).chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())),
    )?;
    let mut maturin = Command::new(bin.join("maturin"));
    maturin.args(["build", "--locked", "--strip"]);
    let target_dir = match kind {
        Kind::Release => {
            maturin.args(["--profile", "release", "--zig", "--compatibility", "manylinux2014"]);
            root.join(TARGET_DIR)
        }
        Kind::Test => {
            maturin.args(["--profile", "dev"]);
            test_target_dir(root, std::env::var("RUSTFLAGS").ok().as_deref())
        }
    };
    maturin
        .arg("--out")
        .arg(&out)
        .current_dir(root.join("python"))
        .env("CARGO_TARGET_DIR", target_dir)
        .env("PATH", path);
    let x86_64 = cfg!(target_arch = "x86_64");
    if x86_64 {
        maturin.env("RUSTFLAGS", RUSTFLAGS);
    }
    let started = std::time::Instant::now();
    cmd::run(&mut maturin)?;
    eprintln!("wheel: built in {:.1} s", started.elapsed().as_secs_f64());
    let wheels: Vec<PathBuf> = std::fs::read_dir(&out)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "whl"))
        .collect();
    let [wheel] = wheels.as_slice() else { bail!("{OUT}: expected one wheel, found {}", wheels.len()) };

    let show = output(Command::new(bin.join("auditwheel")).arg("show").arg(wheel))?;
    if x86_64 && kind == Kind::Release {
        if !show.contains(&format!("\"{MANYLINUX}\"")) {
            bail!("auditwheel show {}: not consistent with {MANYLINUX}:\n{show}", wheel.display());
        }
        eprintln!("auditwheel: consistent with {MANYLINUX}");
    } else {
        eprintln!("auditwheel (the build machine's glibc; the baseline is `cargo xtask wheel`'s):\n{}", show.trim());
    }
    cmd::run(Command::new(bin.join("abi3audit")).args(["--strict", "--summary"]).arg(wheel))?;
    if x86_64 {
        check_instructions(&python, wheel)?;
    }
    Ok(wheel.clone())
}

/// The standard output of `command`, which must succeed.
fn output(command: &mut Command) -> Result<String> {
    eprintln!("$ {}", cmd::display(command));
    let done = command.output().with_context(|| format!("could not start `{}`", cmd::display(command)))?;
    if !done.status.success() {
        bail!("`{}` failed: {}", cmd::display(command), String::from_utf8_lossy(&done.stderr));
    }
    Ok(String::from_utf8_lossy(&done.stdout).into_owned())
}

/// Unpacks the wheel's extension and fails on any instruction beyond [`CPU`] in its disassembly.
fn check_instructions(python: &Path, wheel: &Path) -> Result<()> {
    let dir = wheel.with_extension("unpacked");
    if dir.exists() {
        std::fs::remove_dir_all(&dir)?;
    }
    cmd::run(Command::new(python).args(["-m", "zipfile", "-e"]).arg(wheel).arg(&dir))?;
    let module = std::fs::read_dir(dir.join("asnr"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "so"))
        .context("the wheel holds no asnr/*.so")?;
    let text = output(Command::new("objdump").args(["-d", "--no-show-raw-insn"]).arg(&module))?;
    let (instructions, beyond) = beyond_v3(&text);
    if instructions < 1000 {
        bail!("objdump -d {}: {instructions} instructions: not the extension's disassembly", module.display());
    }
    if !beyond.is_empty() {
        bail!(
            "{}: {} of {instructions} instructions are beyond {CPU} (AVX-512), e.g.\n{}",
            module.display(),
            beyond.len(),
            beyond.iter().take(5).cloned().collect::<Vec<_>>().join("\n")
        );
    }
    eprintln!("objdump: {instructions} instructions, none beyond {CPU} (no zmm, mask or xmm/ymm16–31 register)");
    Ok(())
}

/// The number of instruction lines in `objdump -d` output and those that use an AVX-512-only
/// register: zmm, the mask registers `%k0`–`%k7`, or xmm/ymm 16–31.
pub(crate) fn beyond_v3(disassembly: &str) -> (usize, Vec<String>) {
    let mut instructions = 0;
    let mut beyond = Vec::new();
    for line in disassembly.lines() {
        // an instruction line: "  4010a0:\tvaddpd %ymm1,%ymm2,%ymm3"
        let Some((address, rest)) = line.split_once(":\t") else { continue };
        if !address.trim().chars().all(|c| c.is_ascii_hexdigit()) || address.trim().is_empty() {
            continue;
        }
        instructions += 1;
        if avx512_register(rest) {
            beyond.push(line.trim().to_owned());
        }
    }
    (instructions, beyond)
}

/// Whether an instruction's text names a register only AVX-512 has.
fn avx512_register(instruction: &str) -> bool {
    if instruction.contains("%zmm") {
        return true;
    }
    let bytes = instruction.as_bytes();
    instruction.match_indices('%').any(|(i, _)| {
        let name = &instruction[i + 1..];
        if name.starts_with('k') && bytes.get(i + 2).is_some_and(|c| (b'0'..=b'7').contains(c)) {
            return true;
        }
        let digits: String = name
            .strip_prefix("xmm")
            .or_else(|| name.strip_prefix("ymm"))
            .map_or(String::new(), |d| d.chars().take_while(char::is_ascii_digit).collect());
        digits.parse::<u32>().is_ok_and(|n| (16..32).contains(&n))
    })
}

#[cfg(test)]
mod tests {
    use super::{RUSTFLAGS, TEST_TARGET_DIR, beyond_v3, test_target_dir};

    #[test]
    fn the_test_wheel_shares_the_target_directory_only_with_its_own_flags() {
        let root = std::path::Path::new("/w");
        let own = root.join(TEST_TARGET_DIR);
        assert_eq!(test_target_dir(root, None), own);
        assert_eq!(test_target_dir(root, Some("-C target-cpu=native")), own);
        assert_eq!(test_target_dir(root, Some(&format!(" {RUSTFLAGS} "))), crate::accuracy::target_dir(root));
    }

    #[test]
    fn avx512_registers_are_found_and_v3_code_passes() {
        let text = "\n0000000000001000 <f>:\n\
                    1000:\tvfmadd231pd %ymm1,%ymm2,%ymm3\n\
                    1005:\tvaddpd %zmm1,%zmm2,%zmm3\n\
                    100a:\tvmovapd %xmm17,%xmm1\n\
                    1010:\tkmovw %k1,%eax\n\
                    1014:\tvmovupd %ymm15,(%rax)\n\
                    1018:\tmov %rsp,%rbp\n";
        let (instructions, beyond) = beyond_v3(text);
        assert_eq!(instructions, 6);
        assert_eq!(beyond.len(), 3, "{beyond:?}");
        assert!(beyond[0].contains("zmm") && beyond[1].contains("xmm17") && beyond[2].contains("%k1"));
    }
}
