//! The closed form's tolerance ladder alone (the "closed form" rows of the main tables for the
//! paper scene and the hard scene), with the two targets it carries, so that it can be
//! regenerated without the whole report: `--only closed`.

use metric::{Evaluation, Options, evaluate};

use crate::{Case, FULL, QUICK, reference, scene, time};

/// The section's title.
pub(crate) const TITLE: &str = "The closed form's tolerance ladder, alone";

/// The section's markdown.
pub(crate) fn section(tools: &crate::sections::Tools) -> Option<String> {
    let grid = if tools.quick { QUICK } else { FULL };
    let load_before = crate::load_average();
    let cases = [
        Case { name: "paper: F/2.5, 50 nm", f_number: 2.5, range_m: 50e-9 },
        Case { name: "hard: F/1.4, 200 nm", f_number: 1.4, range_m: 200e-9 },
    ];
    let mut rows = String::new();
    // (case, tolerance) → µs, for the targets
    let mut measured = Vec::new();
    for case in &cases {
        let exact = reference(case);
        for &t in grid.tolerances {
            let options = Options { tolerance: t, ..Options::default() };
            let s = scene(case, false, options);
            let (micros, repeats, e): (f64, usize, Evaluation) =
                time(grid.budget, grid.min_repeats, || evaluate(&s).unwrap());
            let error = (e.mean_mtf - exact).abs() / exact;
            let n = &e.numerics;
            eprintln!("closed: {} tol {t:e}: {micros:.1} µs, error {error:.1e}", case.name);
            rows += &format!(
                "| {} | tol {t:e} | {:.12} | {error:.1e} | {micros:.1} µs | {repeats} | {} OTF values, {} E(c) |\n",
                case.name, e.mean_mtf, n.otf_evaluations, n.closed_form_evaluations
            );
            measured.push((case.f_number, t, micros, error));
        }
    }
    let load_after = crate::load_average();
    let mut md = format!("## {TITLE}\n\n");
    md += &format!(
        "`metric::evaluate` of the paper scene (F/2.5, 50 nm) and the hard scene (F/1.4, 200 nm) with the closed-form \
         engine, the same scenes, references and timing as the main tables (median of repeated single-threaded calls \
         in this release process; error against `optics::reference::mean_mtf` at 1e-12). Machine: {}. Load \
         average (1, 5, 15 min) before: {load_before}; after: {load_after}. Regenerate this section alone: `cargo \
         run --release -p asnr-bench --bin accuracy -- --only closed`.\n\n",
        crate::report::machine()
    );
    md += "| scene | setting | mean MTF | error | time | repeats | work |\n|---|---|---|---|---|---|---|\n";
    md += &rows;
    md += "\n| target | measured | status |\n|---|---|---|\n";
    let targets =
        [(2.5, 1e-7, "paper point, tol 1e-7: ≤ 20 µs", 20.0), (1.4, 1e-6, "F/1.4, 200 nm, tol 1e-6: ≤ 200 µs", 200.0)];
    for (f_number, t, label, bound) in targets {
        if let Some(&(_, _, micros, error)) = measured.iter().find(|m| m.0 == f_number && m.1 == t) {
            let status = if micros <= bound && error <= t {
                format!("met ({:.2}× the bound)", micros / bound)
            } else {
                format!("missed by {:.1}×", micros / bound)
            };
            md += &format!("| {label} | {micros:.1} µs (error {error:.1e}) | {status} |\n");
        }
    }
    Some(md)
}
