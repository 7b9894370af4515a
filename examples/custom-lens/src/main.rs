//! `cargo run -p custom-lens`: the hybrid achromat of this crate beside the paper's chromatic
//! metalens, and beside a chromatic twin with the hybrid's efficiency (same D, f and τ at λ0),
//! on the paper's scene at several spectral ranges.

use std::process::ExitCode;
use std::sync::Arc;

use custom_lens::{BK7_CAUCHY, HybridAchromat, paper_scene};

// no code: its dependency features let this build share the test build's (workspace-hack/Cargo.toml)
use lenses::{ChromaticMetalens, Curve};
use optics::LensModel;
use workspace_hack as _;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let hybrid = HybridAchromat::new(2.5, 3.36e-3, 800e-9, BK7_CAUCHY)?;
    let tau = hybrid.efficiency(800e-9);
    let t = hybrid.transmission(800e-9);
    let lenses: [(&str, Arc<dyn LensModel>); 3] = [
        ("hybrid achromat", Arc::new(hybrid)),
        (
            "chromatic (paper)",
            Arc::new(ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(0.15), Curve::Constant(0.55))?),
        ),
        (
            "chromatic twin",
            Arc::new(ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(tau), Curve::Constant(t))?),
        ),
    ];
    println!("ASNR on the paper's scene (F/2.5, f0 = 3.36 mm, 800 nm Gaussian band, 5.2 µm pixels, 1.23 ms)");
    println!(
        "chromatic (paper): τ1 = 0.15, T = 0.55; chromatic twin: the hybrid's τ = {tau:.3} and T = {t:.3} at 800 nm"
    );
    print!("{:>10}", "range nm");
    for (name, _) in &lenses {
        print!("  {name:>20}");
    }
    println!();
    for range_nm in [10.0, 50.0, 100.0, 200.0] {
        print!("{range_nm:>10}");
        for (_, lens) in &lenses {
            let result = metric::evaluate(&paper_scene(lens.clone(), range_nm * 1e-9)?)?;
            print!("  {:>20.3}", result.asnr);
        }
        println!();
    }
    Ok(())
}
