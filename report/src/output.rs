//! Reports: the human-readable table and the JSON object.

use std::fmt::Write;

use anyhow::Result;
use metric::{Evaluation, MetricForm, MtfCurve, Scene};
use serde::Serialize;

#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    /// The scene's `title` (null without one).
    title: Option<&'a str>,
    lens: String,
    #[serde(flatten)]
    result: &'a Evaluation,
}

/// One JSON object: the scene label, its title, the lens and every field of the evaluation.
pub fn json(label: &str, scene: &Scene, r: &Evaluation) -> Result<String> {
    Ok(serde_json::to_string_pretty(&Report {
        scene: label,
        title: scene.title(),
        lens: scene.lens().describe(),
        result: r,
    })?)
}

/// The header lines of every report: the scene (file or embedded), its title if it has one,
/// and the lens.
fn header(s: &mut String, label: &str, scene: &Scene) {
    let _ = writeln!(s, "scene      {label}");
    if let Some(title) = scene.title() {
        let _ = writeln!(s, "title      {title}");
    }
    let _ = writeln!(s, "lens       {}", scene.lens().describe());
}

/// The formula and the words of the SNR0 line: which noise terms went into it (paper SI eq. S9
/// or S14 when only shot noise is left, EMVA 1288 otherwise).
fn snr0_line(r: &Evaluation) -> (String, String) {
    let n = &r.noise;
    let stray = r.transmitted_photoelectrons - r.photoelectrons;
    let glare = r.glare_mode == metric::GlareMode::Included;
    if n.shot_noise_limited {
        return if glare {
            ("SNR0 = N/√N_T".to_owned(), format!("shot noise with the glare of {stray:.1} stray e⁻ (SI eq. S14)"))
        } else {
            ("SNR0 = √N".to_owned(), "shot-noise limited (SI eq. S9)".to_owned())
        };
    }
    let mut formula = vec![if glare { "N_T" } else { "N" }];
    let mut words = vec![if glare {
        format!("shot (with the glare of {stray:.1} stray e⁻, SI eq. S14)")
    } else {
        "shot".to_owned()
    }];
    if n.read_variance_e2 > 0.0 {
        formula.push("σ_r²");
        words.push(format!("read {:.1} e⁻", n.read_noise_e));
    }
    if n.dark_variance_e2 > 0.0 {
        formula.push("D·t");
        words.push(format!("dark {} e⁻", significant(n.dark_e)));
    }
    if n.quantization_variance_e2 > 0.0 {
        formula.push("σ_q²");
        words.push("quantization".to_owned());
    }
    (format!("SNR0 = N/√({})", formula.join(" + ")), format!("{} (EMVA 1288)", words.join(" + ")))
}

/// Each noise term's variance and its share of the total, for the report when shot noise is not
/// the only one.
fn noise_budget(r: &Evaluation) -> String {
    let n = &r.noise;
    let total = n.total_variance_e2;
    [
        ("shot", n.shot_variance_e2),
        ("read", n.read_variance_e2),
        ("dark", n.dark_variance_e2),
        ("quantization", n.quantization_variance_e2),
    ]
    .iter()
    .filter(|(_, v)| *v > 0.0)
    .map(|(name, v)| format!("{name} {} ({} %)", significant(*v), significant(100.0 * v / total)))
    .collect::<Vec<_>>()
    .join(", ")
}

/// `v` with four significant digits, in plain notation from 0.001 to 1e6.
fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if !(1e-3..1e6).contains(&v.abs()) {
        return format!("{v:.3e}");
    }
    let decimals = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

/// The short table printed by default.
pub fn table(label: &str, scene: &Scene, r: &Evaluation) -> String {
    let mut s = String::new();
    let form = match r.form {
        MetricForm::Mean => "SNR0 × mean MTF",
        MetricForm::Integral => "SNR0 × ∫MTF dν, cycles/mm",
    };
    header(&mut s, label, scene);
    let _ = writeln!(s);
    let _ = writeln!(s, "  ASNR                        {:>12.4}   {form}", r.asnr);
    let (formula, words) = snr0_line(r);
    let _ = writeln!(s, "  {formula:<28}{:>12.4}   {words}", r.snr0);
    if !r.noise.shot_noise_limited {
        let _ = writeln!(
            s,
            "    noise budget, e⁻²         {:>12}   {}",
            significant(r.noise.total_variance_e2),
            noise_budget(r)
        );
    }
    let _ = writeln!(s, "  photoelectrons N            {:>12.1}   per pixel (SI eq. S7–S8)", r.photoelectrons);
    let ri = &r.relative_illumination;
    let _ = writeln!(
        s,
        "  relative illumination       {:>12.4}   {}{}",
        ri.factor,
        ri.description,
        if r.field_points.is_empty() { "" } else { " (weighted mean over the field points)" }
    );
    let _ = writeln!(
        s,
        "  mean MTF                    {:>12.6}   over 0–{:.2} cycles/mm (Nyquist){}",
        r.mean_mtf,
        r.nyquist_cyc_per_mm,
        if scene.camera().pixel_mtf() { ", with pixel MTF" } else { "" }
    );
    if r.mean_mtf_tangential != r.mean_mtf_sagittal {
        let (names, at) = if !r.field_points.is_empty() {
            ("tangential / sagittal", "weighted mean over the field points".to_owned())
        } else if r.field_deg == [0.0, 0.0] {
            ("along x / along y", "on axis".to_owned())
        } else {
            ("tangential / sagittal", format!("at field ({}°, {}°)", r.field_deg[0], r.field_deg[1]))
        };
        let _ = writeln!(
            s,
            "    {names:<24}{:>12.6}   / {:.6} {at}: the OTF depends on direction{}",
            r.mean_mtf_tangential,
            r.mean_mtf_sagittal,
            if names.starts_with("tangential") { " (tangential: along the field, sagittal: across it)" } else { "" }
        );
    }
    for p in &r.field_points {
        let split = if p.mean_mtf_tangential == p.mean_mtf_sagittal {
            String::new()
        } else {
            format!(" (tangential {:.6} / sagittal {:.6})", p.mean_mtf_tangential, p.mean_mtf_sagittal)
        };
        let ri = if r.relative_illumination.model == "none" {
            String::new()
        } else {
            format!(", relative illumination {:.4}", p.relative_illumination)
        };
        let _ = writeln!(
            s,
            "    field ({:>5.2}°, {:>5.2}°) × {:<6} mean MTF {:.6}{split}, ASNR {:.4}{ri}",
            p.field_deg[0], p.field_deg[1], p.weight, p.mean_mtf, p.asnr
        );
    }
    let _ = writeln!(s, "  ∫ MTF dν                    {:>12.4}   cycles/mm", r.mtf_integral_cyc_per_mm);
    let _ = writeln!(
        s,
        "  ASNR, integral form         {:>12.2}   cycles/mm (eq. 1 as printed)",
        r.asnr_integral_cyc_per_mm
    );
    let _ = writeln!(
        s,
        "  mean wavelength             {:>12.2}   nm (cutoff there {:.1} cycles/mm)",
        r.mean_wavelength_nm, r.cutoff_cyc_per_mm
    );
    let _ = writeln!(s);
    let f = &r.fraunhofer;
    let shift = match (f.max_shift_nm, f.table_nm) {
        // a lens given as data: the blur its tables imply, known over their wavelengths only
        (Some(v), Some([lo, hi])) => format!(
            "±{v:.1} nm of {:.1} nm (as its table's OTF implies; known over {}–{} nm)",
            f.reference_nm.unwrap_or_default(),
            crate::number(lo),
            crate::number(hi)
        ),
        (None, Some([lo, hi])) => {
            format!("the table's {}–{} nm (the blur its OTF implies)", crate::number(lo), crate::number(hi))
        }
        (Some(v), None) => format!("±{v:.1} nm"),
        (None, None) => "no limit".to_owned(),
    };
    let _ = writeln!(
        s,
        "  Fraunhofer (SI eq. S15)     {:>12}   blur ≤ {} mm up to {shift}; {:.3} % of the signal beyond",
        if f.valid { "valid" } else { "NOT valid" },
        f.threshold_mm,
        100.0 * f.fraction_outside
    );
    let g = &r.glare;
    let _ = writeln!(
        s,
        "  glare M0 = τ1/T (eq. S13)   {:>12.4}   τ1 = {:.4}, T = {:.4}, VG = {:.1} % (eq. S12)",
        g.m0,
        g.efficiency,
        g.transmission,
        100.0 * g.vg
    );
    s
}

/// The MTF curve as CSV: one row per frequency. Where the OTF depends on direction, the
/// tangential and sagittal columns; over a field-of-view average, `mtf` (and they) are the
/// weighted means and `fields[i].mtf` (with `fields[i].mtf_tangential`, `fields[i].mtf_sagittal`
/// where they differ) are the curves of the scene's field point `fields[i]`.
pub fn mtf_csv(c: &MtfCurve) -> String {
    let mut header: Vec<String> =
        ["frequency_cyc_per_mm", "otf", "mtf", "diffraction_limited"].map(str::to_owned).into();
    let mut columns: Vec<&Vec<f64>> = vec![&c.frequency_cyc_per_mm, &c.otf, &c.mtf, &c.diffraction_limited];
    if let (Some(t), Some(g)) = (&c.mtf_tangential, &c.mtf_sagittal) {
        header.extend(["mtf_tangential".to_owned(), "mtf_sagittal".to_owned()]);
        columns.extend([t, g]);
    }
    for (i, p) in c.field_points.iter().enumerate() {
        header.push(format!("fields[{i}].mtf"));
        columns.push(&p.mtf);
        if let (Some(t), Some(g)) = (&p.mtf_tangential, &p.mtf_sagittal) {
            header.extend([format!("fields[{i}].mtf_tangential"), format!("fields[{i}].mtf_sagittal")]);
            columns.extend([t, g]);
        }
    }
    header.extend(c.wavelengths_nm.iter().map(|wl| format!("mtf_{wl}nm")));
    columns.extend(&c.monochromatic);
    let mut s = scene::sweep::csv_line(&header);
    for i in 0..c.frequency_cyc_per_mm.len() {
        s.push_str(&scene::sweep::csv_line(columns.iter().map(|curve| curve[i].to_string())));
    }
    s
}

#[derive(Serialize)]
struct MtfReport<'a> {
    scene: &'a str,
    /// The scene's `title` (null without one).
    title: Option<&'a str>,
    lens: String,
    /// What `mtf` is: on axis, the tangential–sagittal average, or the weighted mean over the
    /// field points (the text table's `MTF:` line).
    mtf_is: String,
    #[serde(flatten)]
    curve: &'a MtfCurve,
}

/// The MTF curve as one JSON object: the scene label, its title, the lens and the curve's fields.
pub fn mtf_json(label: &str, scene: &Scene, c: &MtfCurve) -> Result<String> {
    Ok(serde_json::to_string_pretty(&MtfReport {
        scene: label,
        title: scene.title(),
        lens: scene.lens().describe(),
        mtf_is: mtf_meaning(c).trim_start_matches("MTF: ").to_owned(),
        curve: c,
    })?)
}

/// What the `MTF` column of the table (and `mtf` of the CSV and JSON) is.
fn mtf_meaning(c: &MtfCurve) -> String {
    // a curve with tangential and sagittal directions is always the mean over azimuth
    // (`MtfCurve::mtf_over_azimuth`: every OTF that depends on direction)
    if !c.field_points.is_empty() {
        let points: Vec<String> = c
            .field_points
            .iter()
            .enumerate()
            .map(|(i, p)| format!("fields[{i}] ({}°, {}°) × {}", p.field_deg[0], p.field_deg[1], p.weight))
            .collect();
        format!(
            "MTF: weighted mean over {} field points{}: {}",
            c.field_points.len(),
            if c.mtf_over_azimuth { " of the means over azimuth" } else { "" },
            points.join(", ")
        )
    } else if c.mtf_over_azimuth {
        // the 2-D OTF's source: a PSF stack's planes or a sampled pupil
        let source = if c.otf_from_psf_stack {
            "a PSF stack"
        } else if c.otf_from_pupil {
            "a sampled 2-D pupil"
        } else {
            "images shifted apart by wavelength, or tangential and sagittal tables"
        };
        if c.field_deg == [0.0, 0.0] {
            format!("MTF: mean over azimuth (on axis; {source}: the OTF depends on direction)")
        } else {
            format!(
                "MTF: mean over azimuth at field ({}°, {}°) ({source}: the OTF depends on direction)",
                c.field_deg[0], c.field_deg[1]
            )
        }
    } else if c.field_deg == [0.0, 0.0] {
        "MTF: on axis".to_owned()
    } else {
        format!("MTF: at field ({}°, {}°), the same in every direction", c.field_deg[0], c.field_deg[1])
    }
}

/// At most this many field points get their own columns in the table.
const TABLE_FIELD_POINTS: usize = 4;

/// The MTF curve as a short table (at most 21 rows; `--csv` gives every point).
pub fn mtf_table(label: &str, scene: &Scene, c: &MtfCurve) -> String {
    let mut s = String::new();
    header(&mut s, label, scene);
    let _ = writeln!(
        s,
        "MTF{}; diffraction limit at the mean wavelength {:.1} nm; Nyquist {:.2} cycles/mm",
        if c.pixel_mtf { " × pixel MTF" } else { "" },
        c.mean_wavelength_nm,
        c.nyquist_cyc_per_mm
    );
    let _ = writeln!(s, "{}", mtf_meaning(c));
    let on_axis = c.field_points.is_empty() && c.field_deg == [0.0, 0.0];
    let mut columns: Vec<(String, &Vec<f64>)> = Vec::new();
    if let (Some(t), Some(g)) = (&c.mtf_tangential, &c.mtf_sagittal) {
        let (a, b) = if on_axis { ("along x", "along y") } else { ("tangential", "sagittal") };
        columns.extend([(a.to_owned(), t), (b.to_owned(), g)]);
    }
    if c.field_points.len() <= TABLE_FIELD_POINTS {
        for (i, p) in c.field_points.iter().enumerate() {
            match (&p.mtf_tangential, &p.mtf_sagittal) {
                (Some(t), Some(g)) => columns.extend([(format!("[{i}] tang."), t), (format!("[{i}] sag."), g)]),
                _ => columns.push((format!("[{i}] MTF"), &p.mtf)),
            }
        }
    } else {
        let _ = writeln!(s, "(each field point's curves: --csv or --json)");
    }
    let _ = writeln!(s);
    let _ = write!(s, "  {:>12}  {:>10}  {:>10}", "cycles/mm", "MTF", "diffr. lim.");
    for (name, _) in &columns {
        let _ = write!(s, "  {name:>10}");
    }
    for wl in &c.wavelengths_nm {
        let _ = write!(s, "  {:>10}", format!("{wl} nm"));
    }
    s.push('\n');
    let n = c.frequency_cyc_per_mm.len();
    let step = n.div_ceil(21).max(1);
    let rows = (0..n).step_by(step).chain(std::iter::once(n - 1)).collect::<std::collections::BTreeSet<_>>();
    for i in rows {
        let _ =
            write!(s, "  {:>12.3}  {:>10.6}  {:>10.6}", c.frequency_cyc_per_mm[i], c.mtf[i], c.diffraction_limited[i]);
        for (_, curve) in &columns {
            let _ = write!(s, "  {:>10.6}", curve[i]);
        }
        for mono in &c.monochromatic {
            let _ = write!(s, "  {:>10.6}", mono[i]);
        }
        s.push('\n');
    }
    s
}

/// The evaluation plan behind `r` (`asnr evaluate --explain`): which engine and why, the
/// quadratures and their work, and the error budget.
pub fn explain(scene: &Scene, r: &Evaluation, meter: Option<&radiometry::RadianceMeterSteps>) -> String {
    let n = &r.numerics;
    let mut s = String::from("\nHow this was computed (--explain)\n");
    if let Some(m) = meter {
        s.push_str(&radiance_meter(m));
    }
    let _ = writeln!(s, "  engine       {}", n.engine);
    let spectral = if n.engine.starts_with("monochromatic") {
        format!(
            "no spectral quadrature: a line spectrum is one wavelength, {:.4} nm; {} node{} (one per imaging \
             order), each order's exact OTF there; its photons are those of its equivalent band (peak × width)",
            r.mean_wavelength_nm,
            n.spectral_nodes,
            if n.spectral_nodes == 1 { "" } else { "s" }
        )
    } else if n.engine.starts_with("closed-form") {
        format!(
            "exact: the spectrum is a Gaussian × polynomial and the lens's defocus is affine in λ, so the \
             integral over λ is a complex Gaussian integral (Faddeeva erfcx, Weideman's series); {} evaluations \
             of it inside nested Clenshaw–Curtis rules over the pupil-overlap angle (pieces where the spectrum \
             is cut, split at its centre, and over the envelope peak, each split where the integral's phase \
             turns fast; where that envelope is below the tolerance the angle is skipped)",
            n.closed_form_evaluations
        )
    } else {
        let rule = if n.spectral_interpolated && n.spectral_evaluations > 0 {
            format!(
                "product integration per frequency: {} panels of nested Chebyshev–Lobatto levels (3, 5, 9, … 129 \
                 points), each OTF value climbing them until its share of the tolerance is met: {} \
                 single-wavelength OTFs in all; weights the exact moments of the detected spectrum, so its \
                 table samples cost nothing; panels follow the lens's defocus phase; {} nodes (17 per panel) for \
                 the averages over the spectrum",
                n.spectral_panels, n.spectral_evaluations, n.spectral_nodes
            )
        } else if n.spectral_interpolated {
            format!(
                "product integration: {} panels, {} nodes (Chebyshev–Lobatto points: each panel's count \
                 doubled until the OTF at Nyquist settles to its share of the tolerance, then cut to the fewest \
                 that stay within it; weights the exact \
                 moments of the detected spectrum, so its table samples cost nothing; panels follow the lens's \
                 defocus phase and where its set of orders changes)",
                n.spectral_panels, n.spectral_nodes
            )
        } else {
            format!(
                "{} panels, {} nodes of 16-point Gauss–Legendre (Gaussians kept to ±7σ: 2.6e-12 of the area left \
                 out; panels cut at every table sample and sized so the defocus phase turns ≤ 12 rad per panel; \
                 exact to rounding)",
                n.spectral_panels, n.spectral_nodes
            )
        };
        let rule = match n.factored_parts {
            0 => rule,
            1 => format!(
                "{rule}; the lens's table folded into those moments (the spectrum × the table: no table row cuts a panel)"
            ),
            k => format!(
                "{rule}; the lens's tables folded into those moments in {k} parts (each part's orders with the moments \
                 of the spectrum × its table: no table row cuts a panel)"
            ),
        };
        if n.engine.starts_with("fft") { format!("{rule}; one FFT OTF grid per node") } else { rule }
    };
    let _ = writeln!(s, "  spectrum     {spectral}");
    let _ = writeln!(
        s,
        "  frequencies  0 … {:.4} cycles/mm (Nyquist; the mean stops there), {}: {} panels, {} OTF evaluations, {} \
         sign changes located",
        r.nyquist_cyc_per_mm,
        if n.engine.starts_with("fft") {
            "a fixed composite Gauss–Legendre rule at half the finest grid cell"
        } else if n.engine.starts_with("closed-form") {
            "nested Clenshaw–Curtis on panels from the band's averaging of defocus (one in ln ν past 8 ν_s), \
             adaptive Gauss–Kronrod 7/15 where it does not settle"
        } else if n.spectral_interpolated {
            "nested Clenshaw–Curtis, adaptive Gauss–Kronrod 7/15 where it does not settle"
        } else {
            "adaptive Gauss–Kronrod 7/15"
        },
        n.frequency_panels,
        n.otf_evaluations,
        n.sign_changes
    );
    let budget = if n.engine.starts_with("fft") && n.engine.contains("convergence of") {
        "a quarter to the spectral rule, half to the pupil sampling (a composite pupil: the mean at N, its error the \
         grid convergence index of N/4, N/2 and N), the frequency rule converged below both"
    } else if n.engine.starts_with("fft") && n.engine.contains("chosen") {
        "a quarter to the spectral rule, half to the pupil sampling (Richardson on N/2 and N, its order checked at N/4, or only its direction where N/4 aliases the pupil phase), the frequency \
         rule converged below both"
    } else if n.spectral_interpolated && n.spectral_evaluations > 0 {
        "the frequency rule to three quarters of tolerance × mean, each OTF value's spectral sum to half of that \
         (nested estimates in both)"
    } else if n.spectral_interpolated {
        "a quarter to the spectral rule (nested estimate at Nyquist), the rest to the frequency rule"
    } else if n.engine.starts_with("closed-form") {
        "the frequency rule to tolerance × mean, each closed-form OTF value to half of that (nested estimates \
         in both); the spectral integral exact"
    } else {
        "the frequency rule to tolerance × mean (QUADPACK's error estimate); the spectral integrals exact to \
         rounding"
    };
    let _ = writeln!(s, "  tolerance    {:e} relative on the mean MTF: {budget}", n.tolerance);
    let glare = if (r.glare.transmission - r.glare.efficiency).abs() <= 1e-15 * r.glare.transmission.max(1e-300) {
        "no stray light (T = τ1): nothing to add".to_owned()
    } else {
        match r.glare_mode {
            metric::GlareMode::FirstOrder => format!(
                "first order only (the paper's main analysis): the stray {:.4} of the transmitted light adds no noise",
                1.0 - r.glare.m0
            ),
            metric::GlareMode::Included => format!(
                "included (SI eq. S14): shot noise of all {:.4} e⁻ transmitted, signal from the {:.4} e⁻ imaged",
                r.transmitted_photoelectrons, r.photoelectrons
            ),
        }
    };
    let _ = writeln!(s, "  glare        {glare}");
    let spectrum = if n.noise_spectrum {
        "non-white noise spectrum: ASNR = SNR0 · mean(MTF/n) (the SNR inside the integral, eq. 1 text)"
    } else {
        "white noise: ASNR = SNR0 · mean MTF (eq. 1)"
    };
    let (formula, words) = snr0_line(r);
    let noise = format!("{spectrum}; {formula}: {words}");
    let _ = writeln!(s, "  noise        {noise}");
    let fields = scene.fields().len();
    if fields > 0 {
        let _ = writeln!(s, "  field        weighted average of {fields} field points, each evaluated as above");
    }
    s
}

/// The steps of a radiance-meter source (SI eq. S1–S6) with their values, in the units of the
/// paper's SI (nm, nW, µm, mm; spectral quantities per nm).
fn radiance_meter(m: &radiometry::RadianceMeterSteps) -> String {
    let (lo, hi) = m.normalized.range();
    let peak = |t: &radiometry::Sampled| {
        let i = (0..t.values().len()).max_by(|&a, &b| t.values()[a].total_cmp(&t.values()[b])).unwrap_or(0);
        (t.values()[i], t.wavelengths()[i] * 1e9)
    };
    let (e_peak, at) = peak(&m.spectral_irradiance);
    let (l_peak, _) = peak(&m.radiance);
    let power_nw = m.fiber_irradiance_w_m2 * m.fiber_area_m2 * 1e9;
    let core_um = (4.0 * m.fiber_area_m2 / std::f64::consts::PI).sqrt() * 1e6;
    let mut s = String::from("  source       radiance meter → the target's spectral radiance (SI eq. S1–S6):\n");
    let mut line = |eq: &str, text: String| {
        let _ = writeln!(s, "    {eq:<4}{text}");
    };
    line(
        "S1",
        format!(
            "∫E_rel dλ = {} (the CSV's unit × nm) over {}–{} nm; E_norm = E_rel/∫E_rel dλ, peak {} /nm at {} nm",
            significant(m.relative_integral * 1e9),
            significant(lo * 1e9),
            significant(hi * 1e9),
            significant(m.normalized.values().iter().copied().fold(0.0, f64::max) * 1e-9),
            significant(peak(&m.normalized).1)
        ),
    );
    line(
        "S2",
        format!(
            "E = P/A_fiber = {} nW / {} m² (π d²/4, d = {} µm) = {} W/m²",
            significant(power_nw),
            significant(m.fiber_area_m2),
            significant(core_um),
            significant(m.fiber_irradiance_w_m2)
        ),
    );
    line(
        "S3",
        format!(
            "corr = ∫E_norm R(λ_cal)/R(λ) dλ = {} (R(λ_cal) = {})",
            significant(m.correction),
            significant(m.calibration_responsivity)
        ),
    );
    line("S4", format!("E_accurate = corr · E = {} W/m²", significant(m.corrected_irradiance_w_m2)));
    line(
        "S5",
        format!("E_λ = E_norm · E_accurate: peak {} W/(m² nm) at {} nm", significant(e_peak * 1e-9), significant(at)),
    );
    line(
        "S6",
        format!(
            "L_λ = E_λ/(π T_lenses) · (2f/D)² = E_λ × {} /sr: peak {} W/(m² sr nm) at {} nm, ∫L_λ dλ = {} W/(m² sr)",
            significant(m.relay_factor_per_sr),
            significant(l_peak * 1e-9),
            significant(at),
            significant(m.radiance.integral())
        ),
    );
    s
}

#[cfg(test)]
mod tests {
    use super::significant;

    #[test]
    fn significant_keeps_four_digits_and_never_breaks_on_zero() {
        assert_eq!(significant(559.43), "559.4");
        assert_eq!(significant(9.0), "9.000");
        assert_eq!(significant(2051.3), "2051");
        assert_eq!(significant(0.000_12), "1.200e-4");
        assert_eq!(significant(0.0), "0");
    }
}
