//! ASNR reports, shared by the `asnr` command line and the Python package so that both print
//! and return the same numbers: the evaluation's table and JSON object ([`output`]), the MTF
//! curve's, the value of one scene key that maximizes the ASNR ([`optimize`]), and the
//! comparison of lens designs under one scene ([`compare`]), and the measurements of camera frames
//! (the slanted-edge MTF and the measured ASNR, [`measure`]).
//!
//! No terminal, plotting or argument-parsing code lives here (the command line draws the
//! progress bars and plots); long computations report their progress through [`Progress`].

pub mod compare;
pub mod gradient;
pub mod measure;
pub mod metrics;
pub mod objective;
pub mod optimize;
pub mod output;
pub mod quasi_newton;
pub mod tolerance;

/// Progress of a long computation: its number of steps once known, then the steps as they are
/// done (from any thread), then its end. `()` ignores it.
pub trait Progress: Sync {
    /// The computation has `total` steps.
    fn start(&self, total: u64) {
        let _ = total;
    }
    /// `steps` more steps are done.
    fn advance(&self, steps: u64) {
        let _ = steps;
    }
    /// The computation is over (or failed).
    fn finish(&self) {}
}

impl Progress for () {}

/// `v` with at most four decimals, trailing zeros dropped: "800", "12.5", "0.0001".
pub fn number(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".to_owned() } else { s.to_owned() }
}
