//! `cargo xtask wheel`: the Python package as one portable wheel, built and checked.
//!
//! - **Build**: `maturin build --release --strip --zig --compatibility manylinux2014` into
//!   `target/wheels/`, in its own target directory (`target/wheel/`, so the workspace's native
//!   build is left as it is), with `RUSTFLAGS="-C target-cpu=x86-64-v3"` on x86-64: the variable
//!   replaces `.cargo/config.toml`'s `target-cpu=native`, so the wheel runs on any x86-64 with
//!   AVX2 and FMA (Intel since 2013, AMD since 2015) and not only on the machine that built it.
//!   zig links against glibc 2.17 symbol versions (manylinux2014), whatever the build machine's
//!   glibc. One wheel serves every CPython ≥ 3.10 (abi3).
//!   `cargo xtask python` and `cargo xtask torch` build the same wheel in the profile `wheel-ci`
//!   (`--profile wheel-ci`: opt-level 2, no line tables), which compiles in less time.
//! - **Checks**: `auditwheel show` must find the manylinux_2_17 tag; `abi3audit --strict` must
//!   find no symbol outside the 3.10 stable ABI; and the extension's disassembly (`objdump -d`)
//!   must hold no instruction beyond x86-64-v3: no zmm register, no mask register and no
//!   ymm16–31/xmm16–31 (all AVX-512 only).
//!
//! No runtime dispatch: a function compiled for AVX-512 can only be called through `unsafe`
//! (`#[target_feature]`), which the workspace forbids (`unsafe_code = "forbid"`); the native
//! build is one flag away (ARCHITECTURE.md, "Build settings", measures what v3 costs).
//!
//! The tools (maturin, ziglang, auditwheel, abi3audit) come pinned from
//! `python/requirements-wheel.txt` into `target/wheel-tools-venv`.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

use crate::cmd;

/// The CPU level the wheel is compiled for (x86-64 hosts).
pub(crate) const CPU: &str = "x86-64-v3";
/// The tools' virtual environment, relative to the workspace root.
const TOOLS_VENV: &str = "target/wheel-tools-venv";
/// The tools, pinned.
const TOOLS: &str = "python/requirements-wheel.txt";
/// Cargo's target directory for the wheel's build (other flags than the workspace's).
const TARGET_DIR: &str = "target/wheel";
/// Where the wheel is written.
const OUT: &str = "target/wheels";
/// The glibc baseline: the manylinux tag maturin builds for and auditwheel must confirm.
const MANYLINUX: &str = "manylinux_2_17_x86_64";

/// The Cargo profile of the wheel for users (`cargo xtask wheel`).
pub(crate) const RELEASE: &str = "release";
/// The Cargo profile of the wheel CI builds and tests (`cargo xtask python`; the workspace's
/// Cargo.toml says how it differs from release).
pub(crate) const CI: &str = "wheel-ci";

/// `cargo xtask wheel`: build and check the wheel, print its path.
pub(crate) fn run(root: &Path) -> Result<()> {
    let wheel = build(root, RELEASE)?;
    println!("{}", wheel.display());
    Ok(())
}

/// Builds the wheel in the Cargo profile `profile`, checks it, and returns its path.
pub(crate) fn build(root: &Path, profile: &str) -> Result<PathBuf> {
    let python = cmd::venv(root, TOOLS_VENV, TOOLS, "auditwheel, abi3audit, ziglang").context("the wheel tools")?;
    let bin = python.parent().context("the venv's bin folder")?.to_path_buf();
    let out = root.join(OUT);
    if out.exists() {
        std::fs::remove_dir_all(&out).with_context(|| format!("removing the old {OUT}"))?;
    }
    let path = std::env::join_paths(
        std::iter::once(bin.clone()).chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())),
    )?;
    let mut maturin = Command::new(bin.join("maturin"));
    maturin
        .args([
            "build",
            "--profile",
            profile,
            "--locked",
            "--strip",
            "--zig",
            "--compatibility",
            "manylinux2014",
            "--out",
        ])
        .arg(&out)
        .current_dir(root.join("python"))
        .env("CARGO_TARGET_DIR", root.join(TARGET_DIR))
        .env("PATH", path);
    let x86_64 = cfg!(target_arch = "x86_64");
    if x86_64 {
        maturin.env("RUSTFLAGS", format!("-C target-cpu={CPU}"));
    }
    cmd::run(&mut maturin)?;
    let wheels: Vec<PathBuf> = std::fs::read_dir(&out)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "whl"))
        .collect();
    let [wheel] = wheels.as_slice() else { bail!("{OUT}: expected one wheel, found {}", wheels.len()) };

    let show = output(Command::new(bin.join("auditwheel")).arg("show").arg(wheel))?;
    if x86_64 && !show.contains(&format!("\"{MANYLINUX}\"")) {
        bail!("auditwheel show {}: not consistent with {MANYLINUX}:\n{show}", wheel.display());
    }
    eprintln!("auditwheel: consistent with {MANYLINUX}");
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
    use super::beyond_v3;

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
