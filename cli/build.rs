//! Links the `asnr` binary as a position-dependent executable on Linux (glibc): its 15 000
//! relative relocations (every pointer of clap's tables, the embedded scenes and the formatting
//! machinery in `.data.rel.ro`) are then resolved by the linker instead of by the dynamic
//! loader at every start, and those pages are no longer copied on write. A process's start
//! falls by about 0.2 ms of CPU (ARCHITECTURE.md, "Build settings"). The library (the Python
//! package's extension module links it) and the other binaries are unchanged.

fn main() {
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let env = std::env::var("CARGO_CFG_TARGET_ENV").unwrap_or_default();
    if os == "linux" && env == "gnu" {
        println!("cargo:rustc-link-arg-bin=asnr=-no-pie");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
