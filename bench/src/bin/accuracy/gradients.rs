//! The gradient's cost beside one evaluation (BENCHMARKS.md, "Gradients: the value and its
//! gradient side by side"): the Binary 2 metalens of `examples/phase-binary2.toml` with K = 4,
//! 12 and 32 Binary 2 coefficients, the scene built and evaluated (`metric::evaluate`) against
//! the scene built, evaluated and differentiated with respect to every coefficient
//! (`metric::gradient`: the derivatives ride on the value's own rules, one pass), and the radial
//! engine's OTF beside its OTF with K derivatives at one wavelength
//! (`RadialOrder::otf_and_derivatives`). Medians of repeats in one process, release.
//!
//! `cargo xtask accuracy --only gradients`

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use metric::Parameter;
use optics::radial::{RadialOrder, RadialProfile, RadialPupil};

use crate::sections::Tools;

/// The example's four coefficients (the hyperbolic profile at R_norm = R, radians).
const HYPERBOLIC: [f64; 4] = [-527.7875658030853, 5.277875658030851, -0.105557513160617, 0.002638937829015425];

/// The coefficients past the fourth: small, alternating (radians at the normalization radius),
/// so that every term moves the wavefront a little and none dominates.
fn extra(j: usize) -> f64 {
    let sign = if j.is_multiple_of(2) { 1.0 } else { -1.0 };
    sign * 2e-3 / (j as f64)
}

/// The `--set` of the example's lens with `k` coefficients.
fn coefficients(k: usize) -> String {
    let list: Vec<String> = (0..k).map(|j| format!("{:e}", if j < 4 { HYPERBOLIC[j] } else { extra(j) })).collect();
    format!("lens.binary2=[{}]", list.join(", "))
}

/// The median of `repeats` timings of `f`, seconds.
fn median_seconds(repeats: usize, mut f: impl FnMut()) -> f64 {
    let times: Vec<f64> = (0..repeats).map(|_| seconds(&mut f)).collect();
    crate::median(times)
}

/// One run of `f`, seconds.
fn seconds(f: &mut impl FnMut()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64()
}

/// One row: K, the value's time, the value and gradient's time (s).
pub(crate) struct Row {
    pub(crate) k: usize,
    pub(crate) value: f64,
    pub(crate) both: f64,
    /// the fastest runs: on a loaded machine, the nearest to the work itself
    pub(crate) value_min: f64,
    pub(crate) both_min: f64,
    pub(crate) asnr: f64,
    pub(crate) norm: f64,
}

impl Row {
    /// The row's cells after its first: ASNR, gradient norm, the two times (median and fastest,
    /// ms to `digits` decimals) and their ratios, each cell opened by `|`, the row closed.
    fn cells(&self, digits: usize) -> String {
        format!(
            "| {:.4} | {:.3e} {}",
            self.asnr,
            self.norm,
            timing_cells([self.value, self.value_min, self.both, self.both_min], digits)
        )
    }
}

/// The cells of a value's time against the value and gradient's: `| value ms (fastest ms) |
/// both ms (fastest ms) | ratio of medians× | ratio of fastest× |` from `[value, value_min,
/// both, both_min]` (s), the times in ms to `digits` decimals, the row closed.
pub(crate) fn timing_cells([value, value_min, both, both_min]: [f64; 4], digits: usize) -> String {
    format!(
        "| {:.digits$} ms ({:.digits$} ms) | {:.digits$} ms ({:.digits$} ms) | {:.2}× | {:.2}× |",
        1e3 * value,
        1e3 * value_min,
        1e3 * both,
        1e3 * both_min,
        both / value,
        both_min / value_min
    )
}

/// The target for the value and gradient against the value alone: at most 3×.
pub(crate) fn within_three(both: f64, value: f64) -> &'static str {
    if both <= 3.0 * value { "met" } else { "not met" }
}

fn measure(root: &Path, k: usize, repeats: usize) -> Option<Row> {
    let source = scene::read(Some(&root.join("examples/phase-binary2.toml"))).ok()?;
    let overrides = vec![coefficients(k)];
    let parameters: Vec<Parameter> = (0..k).map(Parameter::Binary2).collect();
    side_by_side(&source, &overrides, &parameters, repeats)
}

/// The 2-D row: the paper's lens (`examples/paper-theory.toml`, its Gaussian 50 nm band) with
/// 0.05 µm RMS of each of Zernike Noll 5–8 (astigmatism and coma), at the tolerance
/// `tolerance`; the value against the value and its gradient over the four terms. With
/// `overlap` the overlap engine takes it (forward mode on its nodes, docs/physics.md "Zernike
/// terms on the overlap engine"); without, the FFT path (`options.overlap` off, as for a map or
/// a layout, which keep it: forward mode through the FFT, "Gradients: 2-D pupils").
fn measure_2d(root: &Path, tolerance: f64, overlap: bool, repeats: usize) -> Option<Row> {
    let source = scene::read(Some(&root.join("examples/paper-theory.toml"))).ok()?;
    let overrides = vec![
        "lens.zernike_noll_rms_um=[0, 0, 0, 0, 0.05, 0.05, 0.05, 0.05]".to_owned(),
        format!("options.tolerance={tolerance:e}"),
    ];
    let parameters: Vec<Parameter> = (5..=8).map(Parameter::ZernikeNoll).collect();
    let engine = move |built: metric::Scene| {
        let options = metric::Options { overlap, ..built.options().clone() };
        built.with_options(options).unwrap()
    };
    side_by_side_with(&source, &overrides, &parameters, repeats, &engine)
}

/// The aperture row: the Binary 2 metalens of `examples/phase-binary2.toml` (its four
/// coefficients, R_norm given) differentiated with respect to `lens.f_number` and
/// `lens.focal_length_mm` (the radial engine's three aperture lanes beside its four Binary 2
/// lanes, and one OTF at Nyquist: docs/physics.md, "Gradients").
fn measure_aperture(root: &Path, repeats: usize) -> Option<Row> {
    let source = scene::read(Some(&root.join("examples/phase-binary2.toml"))).ok()?;
    side_by_side(&source, &[], &[Parameter::FNumber, Parameter::FocalLength], repeats)
}

/// The line rows: `example` under a line at 803 nm (1 nm equivalent width) differentiated with
/// respect to `spectrum.center_nm` (docs/physics.md, "Gradients: a line's wavelength and a
/// blackbody's temperature"): on the paper's chromatic lens and the harmonic lens the line
/// engine's defocus or order lane beside each OTF value in the value's own pass, on the Binary 2
/// lens the radial engine's wavelength lanes. The row's norm is |∂ASNR/∂c| per nm.
fn measure_line(root: &Path, example: &str, repeats: usize) -> Option<Row> {
    let source = scene::read(Some(&root.join("examples").join(example))).ok()?;
    let overrides: Vec<String> = ["spectrum.shape=\"line\"", "spectrum.center_nm=803", "spectrum.range_nm=1"]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    let row = side_by_side(&source, &overrides, &[Parameter::SpectrumCenter], repeats)?;
    Some(Row { norm: 1e-9 * row.norm, ..row })
}

/// The radial engine at 800 nm: the OTF alone and with K derivatives on 200 frequencies to
/// s = 0.38 (twice Nyquist), accuracy 1e-11; (K, OTF time, OTF and derivatives time) in s.
fn radial(repeats: usize) -> Option<(f64, Vec<(usize, f64)>)> {
    let (r, f, l0): (f64, f64, f64) = (0.672e-3, 3.36e-3, 800e-9);
    let k0 = std::f64::consts::TAU / l0;
    let phase = vec![
        0.0,
        -k0 * r.powi(2) / (2.0 * f),
        k0 * r.powi(4) / (8.0 * f.powi(3)),
        -k0 * r.powi(6) / (16.0 * f.powi(5)),
        k0 * 5.0 * r.powi(8) / (128.0 * f.powi(7)),
    ];
    let terms = vec![
        (l0 / std::f64::consts::TAU, Arc::new(RadialProfile::even_polynomial(phase).ok()?)),
        (1.0, Arc::new(RadialProfile::reference_sphere(r, f).ok()?)),
    ];
    let pupil = Arc::new(RadialPupil::new(None, terms, vec![]).ok()?);
    let order = RadialOrder::new(pupil.clone(), pupil.fitted_defocus_m(), l0);
    let accuracy = 1e-11;
    let frequencies: Vec<f64> = (1..=200).map(|i| 0.38 * i as f64 / 200.0).collect();
    let mut sink = 0.0;
    let value = median_seconds(repeats, || sink += frequencies.iter().map(|&s| order.otf(s, accuracy)).sum::<f64>());
    let mut rows = Vec::new();
    for k in [4, 12, 32] {
        // ∂W/∂a_j = (λ/2π) q^j: the geometric-phase dispersion
        let directions: Vec<RadialProfile> = (1..=k)
            .map(|j| {
                let mut c = vec![0.0; j + 1];
                c[j] = l0 / std::f64::consts::TAU;
                RadialProfile::even_polynomial(c)
            })
            .collect::<Result<_, _>>()
            .ok()?;
        let mut d = vec![0.0; k];
        let both = median_seconds(repeats, || {
            sink += frequencies
                .iter()
                .map(|&s| order.otf_and_derivatives(s, accuracy, &directions, &mut d) + d[0])
                .sum::<f64>()
        });
        rows.push((k, both));
    }
    assert!(sink.is_finite());
    Some((value, rows))
}

/// The section's markdown.
pub(crate) fn section(tools: &Tools) -> Option<String> {
    let repeats = if tools.quick { 11 } else { 31 };
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map_or_else(|| "unknown".to_owned(), |s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "));

    let rows: Vec<Row> = [4, 12, 32].iter().filter_map(|&k| measure(&tools.root, k, repeats)).collect();
    if rows.is_empty() {
        eprintln!("gradients: examples/phase-binary2.toml did not evaluate");
        return None;
    }
    let profile = if cfg!(debug_assertions) { "Dev profile" } else { "Release" };
    let mut md = String::from("## Gradients: the value and its gradient side by side\n\n");
    md.push_str(&format!(
        "`cargo xtask accuracy --only gradients` (bench/src/bin/accuracy/gradients.rs): the Binary 2 metalens of \
         examples/phase-binary2.toml at its tolerance (1e-6) with K Binary 2 coefficients (the example's four, then \
         small alternating ones, ±2e-3/j rad), on axis. The value is the scene built and evaluated \
         (`metric::evaluate`); the gradient is the scene built, evaluated and differentiated with respect to all K \
         coefficients (`metric::gradient`), where the radial engine returns each OTF with its K derivatives on the \
         spectral level the value accepts and the frequency rule's accepted panels integrate them with the value's \
         weights, in the same pass (docs/physics.md, \"Gradients\"). {profile}, medians of {repeats} runs in one \
         process, the value and the gradient run alternately, load average {load} at the start.\n\n"
    ));
    md.push_str(
        "| K | ASNR | ‖∂ASNR/∂A‖ | value, median (fastest) | value and gradient, median (fastest) | ratio of \
         medians | ratio of fastest |\n|---|---|---|---|---|---|---|\n",
    );
    for r in &rows {
        md.push_str(&format!("| {} {}\n", r.k, r.cells(2)));
    }
    let status = |r: &Row| match (r.both <= 3.0 * r.value, r.both_min <= 3.0 * r.value_min) {
        (true, true) => "met",
        (false, false) => "not met",
        (true, false) => "met by the medians, not by the fastest runs",
        (false, true) => "met by the fastest runs, not by the medians",
    };
    md.push_str(&format!(
        "\nTarget (issue: the gradient over K ≤ 16 keys at most 3× one evaluation; here K = 4, 12 and 32): {}.\n",
        rows.iter().map(|r| format!("K = {}: {}", r.k, status(r))).collect::<Vec<_>>().join("; ")
    ));
    if let Some(r) = measure_aperture(&tools.root, repeats) {
        md.push_str(&format!(
            "\nThe phase lens's F-number and focal length (K = 2: `lens.f_number`, `lens.focal_length_mm` of the same \
             lens with its four coefficients): three more lanes of the radial engine (the profile's motion with the \
             aperture radius, the reference sphere's two directions, read eight lanes at a time beside the Binary 2 \
             moments) and one OTF at Nyquist. The same timing as above.\n\n| keys | ASNR | ‖∂ASNR/∂ln key‖ | value, \
             median (fastest) | value and gradient, median (fastest) | ratio of medians | ratio of fastest \
             |\n|---|---|---|---|---|---|---|\n| F#, f0 {}\n\nTarget (at most 3× one evaluation): {}.\n",
            r.cells(2),
            status(&r)
        ));
    }
    let rows_2d: Vec<(&str, f64, Row)> = [(true, 1e-3), (true, 1e-4), (true, 1e-6), (false, 1e-3), (false, 1e-4)]
        .iter()
        .filter_map(|&(overlap, t)| {
            let runs = if overlap || t >= 1e-3 { repeats } else { 5 };
            let engine = if overlap { "overlap" } else { "FFT" };
            measure_2d(&tools.root, t, overlap, runs).map(|r| (engine, t, r))
        })
        .collect();
    if !rows_2d.is_empty() {
        md.push_str(
            "\nA 2-D pupil: the paper's lens (examples/paper-theory.toml, its 50 nm band) with 0.05 µm RMS of each of \
             Zernike Noll 5–8 (astigmatism and coma), the gradient over the four terms. On the overlap engine (the \
             default for Zernike terms on the full circle) by forward mode on the value's nodes (docs/physics.md, \
             \"Zernike terms on the overlap engine\"); on the FFT path (`options.overlap` off, the path a map or a \
             layout keeps) by forward mode through the FFT (\"Gradients: 2-D pupils\"): the value's grids are built \
             again at the two levels the value extrapolates (N/2 and N), each with one more forward and inverse \
             transform per term, and read at the value's frequencies and azimuths. The same timing as above (5 runs \
             for the FFT path at 1e-4).\n\n",
        );
        md.push_str(
            "| engine | tolerance | ASNR | ‖∂ASNR/∂c‖ (per µm) | value, median (fastest) | value and gradient, median \
             (fastest) | ratio of medians | ratio of fastest |\n|---|---|---|---|---|---|---|---|\n",
        );
        for (engine, t, r) in &rows_2d {
            md.push_str(&format!("| {engine} | {t:e} {}\n", r.cells(1)));
        }
        let overlap: Vec<String> = rows_2d
            .iter()
            .filter(|(e, _, _)| *e == "overlap")
            .map(|(_, t, r)| format!("{t:e}: {}", status(r)))
            .collect();
        md.push_str(&format!(
            "\nTarget (the Zernike gradient on the overlap engine at most 3× one evaluation): {}.\n",
            overlap.join("; ")
        ));
    }
    let lines: Vec<(&str, Row)> = [
        ("paper lens (chromatic)", "paper-theory.toml"),
        ("Binary 2", "phase-binary2.toml"),
        ("harmonic, p = 5", "harmonic.toml"),
    ]
    .iter()
    .filter_map(|&(name, file)| measure_line(&tools.root, file, repeats).map(|r| (name, r)))
    .collect();
    if !lines.is_empty() {
        md.push_str(
            "\nA line's wavelength: each example under a line at 803 nm (`--set spectrum.shape=\"line\" --set \
             spectrum.center_nm=803 --set spectrum.range_nm=1`), the gradient with respect to `spectrum.center_nm` \
             (docs/physics.md, \"Gradients: a line's wavelength and a blackbody's temperature\"). The paper's lens \
             (one order) and the harmonic lens (six orders) take the line engine's lane beside each OTF value in the \
             value's own pass (`w ∂H/∂w` times ∂ln w/∂c; per order ∂ln w_o/∂c and ∂τ_o/∂c), the frequency scaling \
             by parts (one OTF at Nyquist); the Binary 2 lens the radial engine's wavelength lanes. The same timing \
             as above.\n\n| lens | ASNR | \\|∂ASNR/∂c\\| (per nm) | value, median (fastest) | value and gradient, median \
             (fastest) | ratio of medians | ratio of fastest |\n|---|---|---|---|---|---|---|\n",
        );
        for (name, r) in &lines {
            md.push_str(&format!("| {name} {}\n", r.cells(3)));
        }
        md.push_str(&format!(
            "\nTarget (at most 3× one evaluation): {}.\n",
            lines.iter().map(|(name, r)| format!("{name}: {}", status(r))).collect::<Vec<_>>().join("; ")
        ));
    }
    md.extend(crate::gradients_aperture::markdown(tools));
    md.extend(crate::gradients_keys::markdown(tools));
    if let Some((value, radial)) = radial(repeats) {
        md.push_str(
            "\nThe radial engine alone, one wavelength: the Binary 2 metalens at 800 nm, 200 frequencies up to s = \
             0.38 (twice Nyquist), OTF accuracy 1e-11; `RadialOrder::otf` against `RadialOrder::otf_and_derivatives` \
             with the first K coefficients' directions (the same t-panel and v rule serves both).\n\n",
        );
        md.push_str("| | time | vs OTF alone |\n|---|---|---|\n");
        md.push_str(&format!("| OTF | {:.3} ms | 1× |\n", 1e3 * value));
        for (k, both) in radial {
            md.push_str(&format!("| + {k} derivatives | {:.3} ms | {:.2}× |\n", 1e3 * both, both / value));
        }
    }
    Some(md)
}

/// The value and the value with its gradient over `parameters`, each `repeats` times, of
/// `source` with `overrides` (the scene built inside each timing). One run of each first, so
/// that neither pays for the per-thread caches the other reuses; then alternately, so that a
/// change of the machine's load falls on both. The row's `k` is the number of parameters.
pub(crate) fn side_by_side(
    source: &scene::Source,
    overrides: &[String],
    parameters: &[Parameter],
    repeats: usize,
) -> Option<Row> {
    side_by_side_with(source, overrides, parameters, repeats, &|built| built)
}

/// [`side_by_side`] with `adjust` applied to each scene built (an option the scene file does
/// not spell, such as the engine), inside each timing.
fn side_by_side_with(
    source: &scene::Source,
    overrides: &[String],
    parameters: &[Parameter],
    repeats: usize,
    adjust: &dyn Fn(metric::Scene) -> metric::Scene,
) -> Option<Row> {
    let built = adjust(scene::build_from(source, overrides).ok()?);
    let first = metric::gradient(&built, parameters).ok()?;
    let (mut values, mut boths) = (Vec::with_capacity(repeats), Vec::with_capacity(repeats));
    for _ in 0..repeats {
        values.push(seconds(&mut || {
            let built = adjust(scene::build_from(source, overrides).unwrap());
            std::hint::black_box(metric::evaluate(&built).unwrap());
        }));
        boths.push(seconds(&mut || {
            let built = adjust(scene::build_from(source, overrides).unwrap());
            std::hint::black_box(metric::gradient(&built, parameters).unwrap());
        }));
    }
    let least = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let (value_min, both_min) = (least(&values), least(&boths));
    let (value, both) = (crate::median(values), crate::median(boths));
    let norm = first.asnr.iter().map(|g| g * g).sum::<f64>().sqrt();
    Some(Row { k: parameters.len(), value, both, value_min, both_min, asnr: first.evaluation.asnr, norm })
}
