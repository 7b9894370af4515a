//! The map per point, against numpy: the 40 × 100 F-number × band map of the paper scene
//! (`asnr sweep`, [`crate::map::ARGS`]) as a whole release process, its CPU time per point beside
//! the numpy script `xtask/baselines/numpy_map.py` computing the same grid (whole process too),
//! each point's mean MTF against the sweep at `--tolerance 1e-12`; and the paper point
//! (F/2.5, 50 nm) at tolerance 1e-7, one `metric::evaluate` call timed in process.
//! A stand-alone section ([`crate::sections`]): `cargo xtask accuracy --only map` regenerates it.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// The section's heading.
pub(crate) const TITLE: &str = "The map per point, against numpy";

/// The numpy script's run: whole-process wall and CPU seconds, its own timing of the map (after
/// numpy's import), and its mean MTF per point in the sweep's order.
struct Numpy {
    wall_s: f64,
    cpu_s: f64,
    inner_s: f64,
    values: Vec<f64>,
    version: String,
}

fn run_numpy(python: &Path, root: &Path) -> Option<Numpy> {
    let script = root.join("xtask").join("baselines").join("numpy_map.py");
    eprintln!("map (numpy): {} {}", python.display(), script.display());
    let cpu = crate::children_cpu_s().unwrap_or(0.0);
    let started = Instant::now();
    let output = Command::new(python).arg(&script).output().ok()?;
    let wall_s = started.elapsed().as_secs_f64();
    let cpu_s = crate::children_cpu_s().unwrap_or(0.0) - cpu;
    if !output.status.success() {
        eprintln!("  failed: {}", String::from_utf8_lossy(&output.stderr));
        return None;
    }
    let text = String::from_utf8_lossy(&output.stdout);
    let (head, values) = text.split_once("values:\n")?;
    let key = |name: &str| head.lines().find_map(|l| l.strip_prefix(&format!("{name}=")).map(str::to_owned));
    let values: Option<Vec<f64>> = values.lines().map(|l| l.rsplit(',').next()?.trim().parse().ok()).collect();
    let numpy =
        Numpy { wall_s, cpu_s, inner_s: key("seconds")?.parse().ok()?, values: values?, version: key("numpy")? };
    eprintln!("  {wall_s:.2} s wall, {cpu_s:.2} s CPU ({:.2} s after the import)", numpy.inner_s);
    Some(numpy)
}

/// The paper point at tolerance 1e-7: the median time of `metric::evaluate` on the built scene
/// (s), its mean MTF, its E(c) evaluations and OTF values, and the same scene's mean MTF at 1e-12.
fn paper_point(root: &Path, repeats: usize) -> Option<(f64, f64, usize, usize, f64)> {
    let source = scene::read(Some(&root.join("examples/paper-theory.toml"))).ok()?;
    let at = |tolerance: &str| scene::build_from(&source, &[format!("options.tolerance={tolerance}")]).ok();
    let (scene, reference) = (at("1e-7")?, at("1e-12")?);
    let first = metric::evaluate(&scene).ok()?;
    let reference = metric::evaluate(&reference).ok()?.mean_mtf;
    let times: Vec<f64> = (0..repeats)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(metric::evaluate(&scene).unwrap());
            start.elapsed().as_secs_f64()
        })
        .collect();
    let n = &first.numerics;
    Some((crate::median(times), first.mean_mtf, n.closed_form_evaluations, n.otf_evaluations, reference))
}

/// The section's markdown (None without the release `asnr`).
pub(crate) fn section(tools: &crate::sections::Tools) -> Option<String> {
    let Some(asnr) = tools.asnr.as_deref() else {
        eprintln!("map: needs the release `asnr` binary (--asnr BIN; `cargo xtask accuracy` passes it)");
        return None;
    };
    let runs = if tools.quick { 1 } else { 3 };
    let load_before = crate::load_average();
    eprintln!("map: {} {}", asnr.display(), crate::map::ARGS.join(" "));
    let (mut walls, mut cpus, mut points) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..runs {
        let (wall, cpu, p) = crate::map::run(asnr, &[]);
        eprintln!("  {wall:.2} s wall, {cpu:.2} s CPU");
        walls.push(wall);
        cpus.push(cpu);
        points = p;
    }
    let (_, _, reference) = crate::map::run(asnr, &["--tolerance", "1e-12"]);
    let relative = |a: f64, b: f64| if b == 0.0 { a.abs() } else { (a - b).abs() / b.abs() };
    let ours_error = points.iter().zip(&reference).map(|(p, r)| relative(p.0, r.0)).fold(0.0, f64::max);
    let n = points.len() as f64;
    let (wall, cpu) = (crate::median(walls), crate::median(cpus));
    let numpy = tools.python.as_deref().and_then(|py| run_numpy(py, &tools.root));
    let paper = paper_point(&tools.root, if tools.quick { 51 } else { 501 });
    let load_after = crate::load_average();

    let profile = if cfg!(debug_assertions) { "dev profile" } else { "release" };
    let mut md = format!("## {TITLE}\n\n");
    md += &format!(
        "`asnr {}` (the paper scene, examples/paper-theory.toml; {} points; release binary, 2 worker threads) timed from \
         outside as a whole process: wall clock and CPU time (user + system, `/proc/self/stat` of the waiting process), \
         median of {runs} run(s); per point: the CPU time over the points. Beside it the numpy script \
         `xtask/baselines/numpy_map.py` (the same grid and scene, and the same closed form of the spectral integral as \
         the sweep: E(c) by the complex error function, Weideman's 36-term series vectorized; then fixed composite \
         Gauss–Legendre rules in the pupil angle, over the cut and the uncut zone, and in ν, their node counts set per \
         point and frequency from the phases they must resolve; every (point, frequency) of the whole grid that takes \
         the same rules evaluated as one array; numpy's BLAS on one thread), one run, whole process too (the \
         interpreter's start and numpy's import included). \
         Agreement: each point's mean MTF against the same sweep at `--tolerance 1e-12` (largest relative difference). \
         The paper point: `metric::evaluate` of examples/paper-theory.toml at `options.tolerance = 1e-7`, in this \
         {profile} process, median of repeats (one thread), its mean MTF against the same scene at 1e-12. Load average \
         (1, 5, 15 min) before: {load_before}; after: {load_after}. Regenerate this section alone: \
         `cargo xtask accuracy --only map`.\n\n",
        crate::map::ARGS.join(" "),
        points.len()
    );
    md += "| map | wall | CPU | CPU per point | largest mean-MTF difference from the 1e-12 sweep |\n|---|---|---|---|---|\n";
    md += &format!(
        "| `asnr sweep`, tolerance 1e-6 (default) | {wall:.2} s | {cpu:.2} s | {:.0} µs | {ours_error:.1e} |\n",
        1e6 * cpu / n
    );
    match &numpy {
        Some(np) if np.values.len() == reference.len() => {
            let error = np.values.iter().zip(&reference).map(|(v, r)| relative(*v, r.0)).fold(0.0, f64::max);
            md += &format!(
                "| numpy {} (`numpy_map.py`; the map alone after the import: {:.2} s) | {:.2} s | {:.2} s | {:.0} µs | {error:.1e} |\n",
                np.version,
                np.inner_s,
                np.wall_s,
                np.cpu_s,
                1e6 * np.cpu_s / n
            );
            if cpu > 0.0 {
                md += &format!(
                    "\nCPU per point, numpy over ours (same run): {:.1}× (wall: {:.1}×).\n",
                    np.cpu_s / cpu,
                    np.wall_s / wall
                );
            }
        }
        Some(np) => {
            md += &format!("| numpy: {} values for {} points: not compared | — | — | — | — |\n", np.values.len(), n);
        }
        None => md += "| numpy: not run (no `--python` with numpy, or the script failed) | — | — | — | — |\n",
    }
    if let Some((seconds, mean, evaluations, otf_values, exact)) = paper {
        md += &format!(
            "\nThe paper point at tolerance 1e-7: {:.1} µs a `metric::evaluate` call, mean MTF {mean:.12} ({:.1e} from \
             {exact:.12} at 1e-12), {otf_values} OTF values, {evaluations} E(c).\n",
            1e6 * seconds,
            relative(mean, exact)
        );
        if evaluations > 0 && otf_values > 0 {
            let per = seconds / evaluations as f64;
            md += &format!(
                "\nWhat 40 µs and 20 µs a point would take: the closed form's time is its count of E(c) times their cost \
                 (here {:.0} ns each, the call's time over its count, everything else in the call included). At that \
                 cost 40 µs is about {:.0} E(c) and 20 µs about {:.0}, against {evaluations} here ({:.0} per OTF value). \
                 The nested Clenshaw–Curtis rule in the pupil angle accepts a piece at 9 points where its own even \
                 Chebyshev coefficients bound the error within the piece's share of the tolerance, else at 17 (33 on \
                 a few): 8 or 16 E(c) a piece with the ends shared, 3–4 pieces an OTF value. So 20 µs needs both fewer \
                 values and fewer points: about 9 OTF values of 2 pieces at 9 points each, or the call {:.1}× cheaper per E(c), \
                 or a surrogate for the OTF in (ν, F#, σ) with a stated bound. The set-up around the kernel (the \
                 128 spectral nodes and the detected spectrum read at them, the frequency rule's defocus statistics, \
                 the signal integrals) is about 5 µs of the call since it stopped reading the spectrum twice and \
                 sorting what comes sorted, so the rest is the kernel and the rule in t. The Faddeeva series already \
                 takes the fewest terms the tolerance allows (20–24 of 36 at 1e-6 and 1e-7), the real exponentials \
                 are the project's four-lane `exp` (within 2 × 2⁻⁵² relative) and a piece's unshared ends ride in its first \
                 call; what is left of an E(c) is the series' rational evaluation, the moments' completed square, sin t, cos t \
                 and the cut, with no one part whose removal gives 2× (ARCHITECTURE.md, \"Where the time goes\"). \
                 Eight lanes (AVX-512) would halve the per-group overhead, not the arithmetic. The paper scene's \
                 polynomial is of degree one (two moments), so fewer moments save nothing there.\n",
                1e9 * per,
                40e-6 / per,
                20e-6 / per,
                evaluations as f64 / otf_values as f64,
                seconds / 20e-6
            );
        }
    }
    md += &reuse_estimate();
    Some(md)
}

/// What reusing one F-number's work across the map's bands would take, from the scene's numbers:
/// the polychromatic OTF is linear in the spectral weight, `∫ w(λ) OTF(ν, λ) dλ / ∫ w`, so one
/// table of the monochromatic OTF in λ per frequency and F-number serves every band (the
/// Gaussian bands are not nested windows of one integrand, but each weight integrates against the
/// same interpolant); the mean MTF's |·| comes after the λ integral, so it is the OTF, not the
/// frequency-averaged MTF, that is reused. The table must resolve the OTF's oscillation in λ,
/// `d a/dλ = π ν f0/(F# λ0)` (the defocus phase `a = 8π W020 ν F#` of the chromatic lens,
/// `W020 = (1 − λ/λ0) f0/(8 F#²)`), over the widest band's ±6σ.
fn reuse_estimate() -> String {
    let (f0, lambda0, pitch) = (3.36e-3, 800e-9, 5.2e-6);
    let nyquist = 1.0 / (2.0 * pitch);
    let sigma = 300e-9 / (2.0 * 2f64.sqrt());
    let span = 12.0 * sigma;
    let per_nm = |f_number: f64| std::f64::consts::PI * nyquist * f0 / (f_number * lambda0) * 1e-9;
    // a Chebyshev interpolant resolves e^{iωx} on [−1, 1] (a phase 2ω) from degree ω on
    let nodes = |f_number: f64| per_nm(f_number) * span * 1e9 / 2.0;
    let short = lambda0 - 6.0 * sigma;
    let waves = (1.0 - short / lambda0) * f0 / (8.0 * 1.4 * 1.4) / short;
    format!(
        "\nReuse across the bands of one F-number (not built): the polychromatic OTF is linear in the spectral weight, \
         so one table of the monochromatic OTF in λ per frequency serves every band of an F-number. At Nyquist the \
         defocus phase turns {:.2} rad/nm at F/1.4 ({:.2} at F/5); over the 300 nm band's ±6σ ({:.0} nm) the table \
         needs about {:.0} Chebyshev nodes in λ at F/1.4 ({:.0} at F/5), each node a monochromatic OTF, at each of \
         the ~25 frequencies of a point: about {:.0} monochromatic OTFs (each an integral over the pupil angle, of up \
         to {:.0} waves of defocus at the band's short end) for the F/1.4 row, to replace 100 closed-form means. It pays where the defocus is small \
         (the slow F-numbers), so a planner would choose per F-number, with the interpolant's Chebyshev tail as its \
         error bound.\n",
        per_nm(1.4),
        per_nm(5.0),
        span * 1e9,
        nodes(1.4),
        nodes(5.0),
        25.0 * nodes(1.4),
        waves,
    )
}
