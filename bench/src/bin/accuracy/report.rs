//! `BENCHMARKS.md`: the two tables, what each method is, and the targets.

use std::fmt::Write as _;

use crate::kernels::{DEFOCUS_WAVES, Kernel, KernelRow};
use crate::tolerance::{BINARY2, COMA, IRIS, LIBRARY, NUMPY_RADIAL, NUMPY_SCRIPT, SPECTROMETER, TABLE};
use crate::{Context, Family, Row, design, map, targets};

/// One line per mean-MTF method: what it is.
fn explain(family: Family) -> String {
    match family {
        Family::ClosedForm => "`metric::evaluate` with the closed-form engine (`optics::GaussianDefocus`): the \
             Gaussian × polynomial spectrum integrated over λ exactly (complex Gaussian integrals, Faddeeva's \
             erfcx), nested Clenshaw–Curtis pieces in the pupil angle t, and in ν panels from the band's \
             spectral averaging of defocus (one in ln ν past 8 ν_s), to the tolerance."
            .into(),
        Family::Quadrature => "`metric::evaluate` with the closed form off (engine `exact-1d`): product \
             integration per frequency over ±7σ (panels of ≤ 48 rad of defocus phase at Nyquist; each OTF value \
             climbs each panel's nested Chebyshev–Lobatto levels until its share of the tolerance is met, by the \
             nested estimate or the Chebyshev tail of the level's own values, the share equal between panels; \
             weights the Chebyshev moments of λ·G(λ)), `optics::defocus_otf_many_within` (the Bessel series, to \
             the accuracy the rule needs) at every point, nested Clenshaw–Curtis in ν."
            .into(),
        Family::Fft => "`metric::evaluate` on the same circular pupil given as an explicit aperture, sampled on \
             the general-pupil engine (`exact_irises` off: by default a circular iris goes to the exact path): N \
             pupil samples across the diameter → PSF → OTF by FFT at every spectral node; its error falls as \
             ~0.4 N^-1.6."
            .into(),
        Family::FftDecentred => "`metric::evaluate` through the paper's iris decentred by 10 % of the radius \
             (SI Fig. S3), sampled on the FFT path at fixed pupil samplings N (`exact_irises` off), against the \
             exact reference of the decentred iris (below)."
            .into(),
        Family::Table => "`metric::evaluate` with the Gaussian filter given as a `Spectrum::Sampled` table \
             (samples every h over ±7σ, piecewise linear between them; closed form off): product integration \
             per frequency as above, its moments exact sums over the table's samples (the piecewise-linear \
             model × λ), so the error is the table's interpolation of the Gaussian, ∝ h²."
            .into(),
        Family::Uniform(_) => "trapezoid rule: n equally spaced wavelengths over λ0 ± kσ with weights λ·G(λ) \
             (h/2 at the ends), `optics::defocus_otf` at each, the fixed frequency rule below; the Gaussian \
             beyond ±kσ is dropped (docs/physics.md: a bias of ~1e-3 of the MTF area at ±3σ, ~1e-7 at ±5σ)."
            .into(),
        Family::Hermite => "n wavelengths λ0 + √2σ xᵢ of the rule for e^{−x²} \
             (`optics::quad::gauss_hermite`) with weights wᵢ λᵢ (the λ factor of the detected weight is \
             integrated exactly), `optics::defocus_otf` at each, the fixed frequency rule below; no cut."
            .into(),
        Family::Default => "`metric::evaluate` of a scene file read as `asnr evaluate` reads it \
             (`scene::load` with `--set options.tolerance=…`), every other setting the default: the engines \
             choose their work (spectral rule, frequency rule, FFT sampling) from the tolerance. Scenes: \
             `examples/spectrometer.toml`, `examples/decentred-iris.toml`, and `examples/paper-theory.toml` \
             with `lens.coma_um=0.5` (FFT path); references below."
            .into(),
        Family::Numpy => format!(
            "`{NUMPY_SCRIPT}` (numpy, not part of the engines): product integration — the OTF interpolated in λ \
             by a Legendre polynomial through nλ Gauss–Legendre nodes, weights the exact moments of the \
             piecewise-linear λ·T(λ) — and fixed Gauss–Legendre rules of nt points in the pupil angle and nν in \
             frequency; the median of repeated calls inside Python after the table is read (BLAS held to one \
             thread), as our rows time `metric::evaluate` on a loaded scene."
        ),
    }
}

/// One line per OTF kernel: what it is.
fn explain_kernel(kernel: Kernel) -> &'static str {
    match kernel {
        Kernel::Production => {
            "production: `(4/π) ∫_0^{acos s} sin²t cos[a(cos t − s)] dt` by 16-point \
             Gauss–Legendre panels, `defocus_otf_panels` of them (≤ 12 rad of phase each), for |a| < 24; the \
             Jacobi–Anger Bessel series (Miller's recurrence) from |a| = 24 (`BESSEL_SERIES_MIN_A`) up."
        }
        Kernel::ProductionQuadrature => {
            "the production panels at every a (what the series replaces above \
             |a| = 24)."
        }
        Kernel::GaussLegendre(_) => {
            "one n-point Gauss–Legendre rule on the t-form of docs/physics.md \
             `4/(πa) ∫_0^{acos s} sin[a(cos t − s)] cos t dt`, whatever a: it fails once the integrand's \
             ~a/π oscillations outnumber the nodes."
        }
        Kernel::Hopkins(_) => {
            "Hopkins' 1955 Bessel series with libm's Jn, each of its two brackets cut after K \
             terms (Bessel orders ≤ 2K; `optics::reference::otf_hopkins_terms`): converged once 2K passes \
             a = 8πws; \"all terms\" is `optics::reference::otf_hopkins`."
        }
        Kernel::Geometric => {
            "the geometric-optics blur disk `2J1(x)/x`, x = πdν = 8πws = a (docs/physics.md, \
             \"Geometric limit\"; `optics::reference::otf_geometric`): a large-defocus approximation."
        }
    }
}

fn duration(micros: f64) -> String {
    if micros >= 1000.0 { format!("{:.2} ms", micros / 1000.0) } else { format!("{micros:.1} µs") }
}

fn nanos(ns: f64) -> String {
    if ns >= 1e6 {
        format!("{:.1} ms", ns / 1e6)
    } else if ns >= 1e4 {
        format!("{:.1} µs", ns / 1e3)
    } else {
        format!("{ns:.0} ns")
    }
}

/// The CPU's model, the cores available, the OS and architecture.
pub(crate) fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines().find(|l| l.starts_with("model name")).map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| "unknown CPU".to_owned());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} cores available, {} {}", std::env::consts::OS, std::env::consts::ARCH)
}

/// The whole file.
pub(crate) fn markdown(rows: &[Row], kernels: &[KernelRow], context: &Context) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Benchmarks: accuracy against time\n");
    let _ = writeln!(
        s,
        "Regenerate with `cargo xtask accuracy` (this file and `docs/benchmarks/accuracy.svg`){}.\n",
        if context.quick { " — this copy is from the reduced `--quick` grid" } else { "" }
    );
    let _ = writeln!(
        s,
        "Machine: {}; load average (1, 5, 15 min) {} at the start of the run and {} at its end: the machine \
         is shared, and a load above its core count slows every row. Times are medians of repeated \
         single-threaded calls in a release build for the CPU it runs on (`target-cpu=native` in \
         `.cargo/config.toml`, ARCHITECTURE.md \"Build settings\"; vector extensions in this build: {}).\n",
        machine(),
        context.load.0,
        context.load.1,
        vector_extensions()
    );
    let _ = writeln!(s, "![error against time](docs/benchmarks/accuracy.svg)\n");

    let _ = writeln!(s, "## Mean MTF of one ASNR point\n");
    let references: Vec<String> = context
        .references
        .iter()
        .map(|(name, value, seconds)| format!("{name}: {value:.15} in {seconds:.1} s"))
        .collect();
    let _ = writeln!(
        s,
        "Error: relative error of the mean MTF (hence of the ASNR); for the paper and hard scenes against \
         `optics::reference::mean_mtf` at 1e-12 (printed y-form OTF, adaptive Gauss–Kronrod in ν, λ and y; computed once per scene — {}). The \
         reference's own error is ~1e-12. The scenes: the paper's chromatic metalens (f0 = 3.36 mm, λ0 = 800 nm, \
         τ1 = 0.15) with a flat source behind a Gaussian filter centred at λ0, 5.2 µm pixels; detected weight \
         λ·G(λ).\n",
        references.join("; ")
    );
    let rules: Vec<String> = context
        .frequency_rules
        .iter()
        .map(|(name, rule)| {
            let change = if rule.change == 0.0 { "not at all".to_owned() } else { format!("by {:.0e}", rule.change) };
            format!("{name}: {} panels (the last doubling moved the means {change})", rule.panels)
        })
        .collect();
    let _ = writeln!(
        s,
        "Time per point: a whole `metric::evaluate` call (photoelectrons, glare, Fraunhofer check, mean MTF) for \
         the production rows; the mean MTF alone (nodes and frequency rule) for the uniform and Gauss–Hermite \
         rows. Their frequency rule is fixed and converged, so that their error is the spectral rule's: equal \
         panels of 16-point Gauss–Legendre on [0, ν_N], each panel where the polychromatic OTF changes sign split \
         at the zero (Illinois), panel count doubled until the finest rules' means move by ≤ 1e-14 — {}.\n",
        rules.join("; ")
    );
    if let Some((reference, tangential, sagittal, seconds, check)) = context.notes.iris {
        let _ = writeln!(
            s,
            "Decentred iris (SI Fig. S3; {IRIS} and the fixed-N rows' 0.1): exact reference, written for this \
             report (bench/src/bin/accuracy/iris.rs). On the defocus-only chromatic lens a full-size iris \
             decentred by d radii is exactly the centred circular pupil with the same defocus W020(λ) plus a tilt \
             2 d W020(λ), i.e. an image shift Δ(λ) = −4 d F# W020(λ) along the decentre: the OTF along it is the \
             exact defocus OTF times exp(−i d a), a = 8π w s, summed over λ as a complex number, and across it \
             the centred lens's. So the tangential mean is a nested adaptive Gauss–Kronrod integral (G10–K21, \
             relative 1e-12) of |∫ λ G(λ) OTF e^(−i d a) dλ| over ν, with the printed y-form OTF \
             (`optics::reference::otf_defocus`, 1e-13 absolute) at every node, and the sagittal mean is \
             `optics::reference::mean_mtf`; `metric::evaluate` reports their average. At d = 0.15: \
             {reference:.15} (tangential {tangential:.15}, sagittal {sagittal:.15}; {seconds:.1} s). Its own \
             accuracy: at d = 0 the same code gives `optics::reference::mean_mtf` to {check:.1e}, and its \
             quadratures are held to 1e-12.\n"
        );
    }
    if let Some((name, exact, richardson, order)) = context.decentred {
        let _ = writeln!(
            s,
            "Decentred iris 0.1 ({name}, fixed N): exact reference {exact:.12}; the Richardson extrapolation \
             M_fine + (M_fine − M_mid)/(2^p − 1) of the three finest pupil samplings (observed order \
             p = {order:.2}), the reference before, is {richardson:.12}, {:.1e} from it.\n",
            (richardson - exact).abs() / exact
        );
    }
    if let Some((reference, seconds, work)) = &context.notes.spectrometer {
        let _ = writeln!(
            s,
            "Spectrometer table ({SPECTROMETER}): `examples/spectrometer.toml`, the paper's lens (F/2.5, \
             f0 = 3.36 mm, λ0 = 800 nm) behind `{TABLE}` (synthetic: a 52 nm super-Gaussian band at 825 nm, 1601 \
             samples at 0.25 nm over 600–1000 nm, 0.2 % floor, seeded noise; `cargo xtask data` writes it), flat \
             source, constant QE, 5.2 µm pixels. Reference: the same scene through `optics::Polychromatic` with \
             `Settings {{ spectral_rule: SpectralRule::Panels, tolerance: 1e-12, .. }}` (the per-interval rule: \
             16-point Gauss–Legendre panels cut at every table sample, exact to rounding for the piecewise-linear \
             table; the frequency rule to 1e-12), computed once: {reference:.15} in {seconds:.1} s ({work}). \
             The report builds the detected spectrum (radiance × QE × λ) as `metric::evaluate` does and \
             calls the optics directly, so the reference's mean is the optics' alone.\n"
        );
    }
    if let Some((reference, seconds, work)) = &context.notes.binary2 {
        let _ = writeln!(
            s,
            "Designs given as data: {BINARY2} is `examples/phase-binary2.toml` (the paper's aperture as four Zemax \
             Binary 2 coefficients of the hyperbolic phase, a geometric-phase metalens against the exact reference \
             sphere, the radial engine); reference: the same scene through the per-interval rule at 1e-12, \
             {reference:.15} in {seconds:.1} s ({work}). The numpy baseline `{NUMPY_RADIAL}` computes the same mean \
             with fixed Gauss–Hermite nodes in λ and tensor Gauss–Legendre rules in ν and the pupil's t and v, all \
             vectorized ({}).\n",
            match &context.notes.numpy_radial {
                Ok(version) => format!("numpy {version}, run side by side in this run"),
                Err(why) => why.clone(),
            }
        );
    }
    if let Some((reference, seconds, work)) = &context.notes.library {
        let _ = writeln!(
            s,
            "{LIBRARY} is `examples/library.toml`: 1680 rings of an illustrative TiO2-like meta-atom library (an \
             effective-index model, `cargo xtask data`) on the paper's aperture; reference: its per-interval rule at \
             1e-12, {reference:.15} in {seconds:.1} s ({work}).\n"
        );
    }
    match &context.notes.numpy {
        Ok((python, version)) => {
            let _ = writeln!(
                s,
                "numpy baseline: `python3 {NUMPY_SCRIPT} {TABLE}` with numpy {version} ({}), side by side with \
                 our rows in this run; its error is against the same reference.\n",
                if python.contains("baselines-venv") {
                    "the virtual environment `cargo xtask accuracy` makes in target/baselines-venv from \
                     xtask/baselines/requirements.txt"
                } else {
                    "the system interpreter"
                }
            );
        }
        Err(why) => {
            let _ = writeln!(s, "{why}.\n");
        }
    }
    if let Some((reference, order, samplings)) = &context.notes.coma {
        let means: Vec<String> = samplings.iter().map(|(n, m)| format!("N = {n}: {m:.12}")).collect();
        let _ = writeln!(
            s,
            "Coma ({COMA}): `examples/paper-theory.toml` with `lens.coma_um=0.5` (the overlap quadrature). Reference: the \
             Richardson extrapolation M_fine + (M_fine − M_mid)/(2^p − 1) of fixed pupil samplings ({}; \
             `options.pupil_samples`), observed order p = {order:.2}: {reference:.12}. Its own error is about the \
             size of the last correction, {:.1e}.\n",
            means.join(", "),
            (reference - samplings[2].1).abs() / reference
        );
    }
    let mut families: Vec<Family> = Vec::new();
    for r in rows {
        let generic = match r.family {
            Family::Uniform(_) => Family::Uniform(0),
            f => f,
        };
        if !families.contains(&generic) {
            families.push(generic);
        }
    }
    for f in families {
        let name = match f {
            Family::Uniform(_) => "uniform ±kσ".to_owned(),
            f => f.name(),
        };
        let _ = writeln!(s, "- **{name}**: {}", explain(f));
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "| scene | method | setting | mean MTF | relative error | time per point | runs | work |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.12} | {:.1e} | {} | {} | {} |",
            r.case,
            r.family.name(),
            r.setting,
            r.mean_mtf,
            r.error,
            duration(r.micros),
            r.repeats,
            r.work
        );
    }
    if let Some(p) = &context.binary2_process {
        let _ = writeln!(s);
        s.push_str(&crate::process::markdown(p));
    }

    let _ = writeln!(s, "\n## OTF kernels\n");
    let _ = writeln!(
        s,
        "The monochromatic OTF of a centred circular pupil with defocus w waves, at the 12 frequencies \
         s = (k − ½)/12 for each w, against `optics::reference::otf_defocus` (the y-form printed in docs/physics.md, by \
         adaptive Gauss–Kronrod, accurate to ~1e-13 absolute: smaller errors are the reference's). Each w column: \
         the largest absolute error over the 12 points · the median time per OTF value. Relative error: to the \
         envelope min(1, 4/(π|a|)), a = 8πws, that bounds |OTF| (|sin| ≤ 1 in the printed formula). The OTF is 1 \
         at s = 0, so an absolute error is also relative to the OTF's scale, and bounds the error it puts into \
         the mean MTF.\n"
    );
    let mut seen: Vec<&'static str> = Vec::new();
    for row in kernels {
        if !seen.contains(&row.kernel.name()) {
            seen.push(row.kernel.name());
            let _ = writeln!(s, "- **{}**: {}", row.kernel.name(), explain_kernel(row.kernel));
        }
    }
    let _ = writeln!(s);
    let header: Vec<String> = DEFOCUS_WAVES.iter().map(|w| format!("w = {w}")).collect();
    let _ = writeln!(
        s,
        "| method | setting | {} | max abs. error | max rel. error | time per value | work |",
        header.join(" | ")
    );
    let _ = writeln!(s, "|---|---|{}---|---|---|---|", "---|".repeat(DEFOCUS_WAVES.len()));
    for row in kernels {
        let cells: Vec<String> = row.cells.iter().map(|c| format!("{:.1e} · {}", c.abs, nanos(c.nanos))).collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1e} | {:.1e} | {} | {} |",
            row.kernel.name(),
            row.kernel.setting(),
            cells.join(" | "),
            row.max_abs(),
            row.max_rel(),
            nanos(row.nanos()),
            row.work
        );
    }
    let _ = writeln!(s);
    match &context.map {
        Some(m) => map_section(&mut s, m),
        None => {
            let _ = writeln!(
                s,
                "## The map\n\nNot measured: the release `asnr` binary was not given (`cargo xtask accuracy` builds it \
                 and passes `--asnr`).\n"
            );
        }
    }
    if let Some(d) = &context.design {
        s.push_str(&design::markdown(d));
    }
    if let Some(b) = &context.sweep {
        s.push_str(&crate::sweep::markdown(b));
    }
    s.push_str(&targets::markdown(rows, context.map.as_ref(), context.binary2_process.as_ref()));
    s
}

fn map_section(s: &mut String, m: &map::Map) {
    let _ = writeln!(s, "## The map: a whole `asnr sweep`\n");
    let _ = writeln!(
        s,
        "`asnr {}` ({} points, release binary, 2 worker threads), timed from outside as a whole process: wall \
         clock and the CPU time (user + system) it used, medians of {} runs. Error: the largest relative \
         difference of a point's ASNR (and of its mean MTF) from the same sweep with `--tolerance 1e-12`.\n",
        map::ARGS.join(" "),
        m.points,
        m.runs
    );
    let _ = writeln!(s, "| sweep | wall | CPU | largest ASNR error | largest mean-MTF error | runs |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    let _ = writeln!(
        s,
        "| tolerance 1e-6 (default) | {:.2} s | {:.2} s | {:.1e} | {:.1e} | {} |",
        m.wall_s, m.cpu_s, m.asnr_error, m.mean_mtf_error, m.runs
    );
    let _ = writeln!(s, "| tolerance 1e-12 (the reference) | {:.2} s | — | — | — | 1 |", m.reference_wall_s);
    if let Some((py, cli)) = m.python {
        let _ = writeln!(
            s,
            "| Python: `asnr.evaluate_many` + `asnr.to_csv` on the same points, in one process, 2 threads (`python/bench/map.py`; the command beside it in the same run: {cli:.2} s, so {:.2}×) | {py:.2} s | — | 0 (the same CSV bytes) | 0 | {} |",
            py / cli,
            m.runs.max(3)
        );
    }
    let _ = writeln!(s);
}

/// The vector extensions this report was compiled with (the build's target features), or the
/// baseline's: the times depend on them (ARCHITECTURE.md, "Build settings").
fn vector_extensions() -> String {
    let features = [
        ("SSE2", cfg!(target_feature = "sse2")),
        ("AVX2", cfg!(target_feature = "avx2")),
        ("FMA", cfg!(target_feature = "fma")),
        ("AVX-512F", cfg!(target_feature = "avx512f")),
        ("NEON", cfg!(target_feature = "neon")),
    ];
    let on: Vec<&str> = features.iter().filter(|(_, on)| *on).map(|(name, _)| *name).collect();
    if on.is_empty() { "none beyond the baseline".to_owned() } else { on.join(", ") }
}
