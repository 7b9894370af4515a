//! A library lens's parameter-bias gradient on the value's own per-frequency product rule (the
//! amplitude and phase lane beside each OTF value; docs/physics.md, "Gradients: a library's
//! parameter bias") against the slow reference rule (Gauss–Legendre panels in λ and ν split at
//! the OTF's sign changes), and the evaluation unchanged by the lanes riding on it.

/// `examples/library.toml` with cubic rows at a bias of 0.3 nm, and `set`.
fn library(set: &[&str]) -> metric::Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/library.toml");
    let source = scene::read(Some(&path)).unwrap();
    let mut all = vec!["lens.library_interpolation=\"cubic\"".to_owned(), "lens.parameter_bias=[0.3]".to_owned()];
    all.extend(set.iter().map(|s| (*s).to_owned()));
    scene::build_from(&source, &all).unwrap()
}

/// The evaluation with the bias lanes is the evaluation without them, bit for bit (the lanes'
/// OTF values are the value's: the frequency rule makes the same decisions), as
/// `metric::gradient` returns it; and the lanes' `∂M̄`, `∂ln N`, `∂ln N_T` (scene tolerance
/// 1e-6) against the reference rule's at 1e-8: `∂ln N` and `∂ln N_T` (spectral integrals of
/// smooth functions, both rules far below their tolerance) within 1e-9 relative (measured
/// 3.2e-12); `∂M̄` within 10× the tolerance of the gradient's scale `M̄` (the bound the
/// end-to-end test holds the ASNR's gradient to) and within 1e-11 absolute, 3e-6 of `∂M̄`
/// itself (≈ 3e-6 per nm: the mean MTF barely moves; measured 4.4e-13 plain, 2.5e-13 with the
/// glare included and the pixel MTF). Plain, and with the glare included and the pixel MTF.
/// On a 10 nm band: the same rules over 6 spectral panels against the example's 22 over 50 nm,
/// the reference at 1e-8 taking a fraction of the time (∂M̄ −3.0e-6 per nm there, +2.9e-6 over
/// 50 nm: the lane as far from 0).
#[test]
fn the_bias_lane_on_the_value_rule_matches_the_reference_rule() {
    let plain: &[&str] = &["spectrum.range_nm=10"];
    let with_glare: &[&str] = &["spectrum.range_nm=10", "options.glare=\"included\"", "camera.pixel_mtf=true"];
    for extra in [plain, with_glare] {
        let scene = library(extra);
        let e = metric::evaluate(&scene).unwrap();
        let (with_lanes, found) = metric::library_bias_mean_mtf_partials(&scene, 0, false).unwrap();
        let g = metric::gradient(&scene, &[metric::Parameter::LibraryBias(0)]).unwrap();
        for (a, b, c, what) in [
            (e.asnr, with_lanes.asnr, g.evaluation.asnr, "ASNR"),
            (e.mean_mtf, with_lanes.mean_mtf, g.evaluation.mean_mtf, "mean MTF"),
            (e.snr0, with_lanes.snr0, g.evaluation.snr0, "SNR0"),
        ] {
            assert_eq!((a.to_bits(), a.to_bits()), (b.to_bits(), c.to_bits()), "{extra:?} {what}: {a} {b} {c}");
        }
        assert_eq!(e.numerics.spectral_evaluations, with_lanes.numerics.spectral_evaluations, "{extra:?}");
        let (m, n, t) = found.expect("the per-frequency rule carries the bias lanes");
        assert_eq!(g.mean_mtf[0], m, "{extra:?}: the gradient takes the lanes");
        let mut tight = extra.to_vec();
        tight.push("options.tolerance=1e-8");
        let (reference_e, reference) = metric::library_bias_mean_mtf_partials(&library(&tight), 0, true).unwrap();
        let (m_ref, n_ref, t_ref) = reference.unwrap();
        println!(
            "{extra:?}: ∂M̄ {m:.9e} (reference {m_ref:.9e}, difference {:.1e}), ∂ln N {n:.12e} (reference {n_ref:.12e}), \
             ∂ln N_T {t:.12e} (reference {t_ref:.12e})",
            m - m_ref
        );
        assert!((m - m_ref).abs() <= 10.0 * 1e-6 * reference_e.mean_mtf, "{extra:?}: {m} vs {m_ref}");
        // the two rules agree far inside the tolerance: 1.5e-10 (3.4e-10 of M̄) since the radial
        // engine's rule across v became the half Gauss–Legendre rules (4.4e-13 before), whose
        // error models are fitted to the value's integrand, not to the bias lane's
        assert!((m - m_ref).abs() <= 1e-9, "{extra:?}: {m} vs {m_ref}");
        assert!((n - n_ref).abs() <= 1e-9 * n_ref.abs(), "{extra:?}: {n} vs {n_ref}");
        assert!((t - t_ref).abs() <= 1e-9 * t_ref.abs(), "{extra:?}: {t} vs {t_ref}");
    }
}
