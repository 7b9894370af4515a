//! The built-in lens families pass the `optics::testkit` conformance checks and agree with
//! independent formulas (one binary: the modules below hold the families added later).

mod exact;
mod library;
mod phase;
mod photons;
mod psf;
mod reference;
mod segmented;
mod tabulated;

use lenses::{ChromaticMetalens, Curve};
use optics::testkit::check_lens;
use radiometry::{Gaussian, Sampled, Spectrum};

fn band(centre_nm: f64, range_nm: f64) -> Spectrum {
    Spectrum::product(vec![
        Spectrum::Gaussian(Gaussian::from_range(centre_nm * 1e-9, range_nm * 1e-9, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ])
}

#[test]
fn chromatic_metalens_conforms() {
    for f_number in [1.4, 2.5, 5.0] {
        let lens =
            ChromaticMetalens::new(f_number, 3.36e-3, 800e-9, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
        for (c, r) in [(800.0, 1.0), (800.0, 50.0), (850.0, 20.0)] {
            check_lens(&lens, &band(c, r)).unwrap_or_else(|e| panic!("F/{f_number}, {c} nm ± {r} nm: {e}"));
        }
    }
}

#[test]
fn tabulated_efficiency_conforms() {
    let eff = Sampled::new(vec![700e-9, 800e-9, 900e-9], vec![0.05, 0.15, 0.08]).unwrap();
    let lens = ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Table(eff), Curve::Constant(0.55)).unwrap();
    check_lens(&lens, &band(800.0, 100.0)).unwrap();
}

#[test]
fn conformance_check_catches_a_broken_lens() {
    // a lens that claims an efficiency but reports a NaN defocus must fail the check
    #[derive(Debug)]
    struct Broken;
    impl optics::LensModel for Broken {
        fn f_number(&self) -> f64 {
            2.0
        }
        fn focal_length(&self) -> f64 {
            1e-2
        }
        fn orders(&self, _: f64, _: optics::Field) -> Vec<optics::Order> {
            vec![optics::Order::new(0.5, optics::Pupil::Full, optics::Wavefront::defocus(f64::NAN))]
        }
    }
    assert!(check_lens(&Broken, &band(800.0, 10.0)).is_err());
}

#[test]
fn conformance_check_catches_orders_into_that_replaces() {
    // orders_into must append to the caller's buffer what orders returns; one that clears it
    // first would drop the orders of the wavelengths before (the per-frequency rule reads a
    // level's points through one buffer)
    #[derive(Debug)]
    struct Replacing;
    impl optics::LensModel for Replacing {
        fn f_number(&self) -> f64 {
            2.0
        }
        fn focal_length(&self) -> f64 {
            1e-2
        }
        fn orders(&self, _: f64, _: optics::Field) -> Vec<optics::Order> {
            vec![optics::Order::new(0.5, optics::Pupil::Full, optics::Wavefront::defocus(1e-7))]
        }
        fn orders_into(&self, wavelength_m: f64, field: optics::Field, out: &mut Vec<optics::Order>) {
            *out = self.orders(wavelength_m, field);
        }
    }
    let error = check_lens(&Replacing, &band(800.0, 10.0)).unwrap_err();
    assert!(error.contains("orders_into"), "{error}");
}

// ---- wavefront sign (docs/physics.md, "Sign of the wavefront") ----

const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;
const F_NUMBER: f64 = 2.5;

fn paper_lens() -> ChromaticMetalens {
    ChromaticMetalens::new(F_NUMBER, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap()
}

/// The wavelength where the chromatic defocus is `w020_m`, from the convention alone:
/// `W020(λ) = (1 − λ/λ0) f0/(8 F#²)` ⇒ `λ = λ0 (1 − W020 8F#²/f0)`.
fn wavelength_with_defocus(w020_m: f64) -> f64 {
    LAMBDA0 * (1.0 - w020_m * 8.0 * F_NUMBER * F_NUMBER / F0)
}

/// OTF along `+x` at `s = ν/ν_c` of a circular pupil with the rotationally symmetric wavefront
/// `W = W020 ρ² + W040 ρ⁴` (m) at `wavelength`, by brute-force quadrature of the pupil
/// autocorrelation `OTF(s) = (1/π) ∫ P(u) P*(u + 2s x̂) d²u`, `P = exp(+i 2π W/λ)`, written here
/// independently of the FFT path. With `u = (x − s, y)` the overlap is `(|x| + s)² + y² ≤ 1` and
/// the phase difference `k [W(x − s, y) − W(x + s, y)] = −4 k s x [W020 + 2 W040 (x² + y² + s²)]`
/// is odd in `x`, so the OTF is real: `(4/π) ∫_0^{1−s} dx ∫_0^{√(1−(x+s)²)} cos(…) dy`, done in
/// `x + s = cos t`, `y = v sin t` (no square-root endpoint), Gauss–Legendre in `t` and `v`.
fn autocorrelation_otf(s: f64, w020_m: f64, w040_m: f64, wavelength: f64) -> f64 {
    let k = std::f64::consts::TAU / wavelength;
    let mut total = 0.0;
    optics::quad::for_each_node(0.0, s.acos(), 24, |t, wt| {
        let (sin_t, cos_t) = t.sin_cos();
        let x = cos_t - s;
        let inner = optics::quad::composite(0.0, 1.0, 24, |v| {
            let y = v * sin_t;
            let phase = -4.0 * k * s * x * (w020_m + 2.0 * w040_m * (x * x + y * y + s * s));
            phase.cos()
        });
        total += wt * sin_t * sin_t * inner;
    });
    4.0 / std::f64::consts::PI * total
}

/// Normalized frequencies of the checks, and the lens's MTF there (FFT path, 256 samples).
const S: [f64; 6] = [0.05, 0.1, 0.2, 0.3, 0.45, 0.6];

fn lens_mtf(lens: &ChromaticMetalens, wavelength: f64) -> Vec<f64> {
    let nus: Vec<f64> = S.iter().map(|s| s / (wavelength * F_NUMBER)).collect();
    optics::monochromatic_mtf(lens, wavelength, optics::Field::ON_AXIS, &nus, 256).unwrap()
}

/// The quadrature above is right: the diffraction-limited MTF and the exact defocus OTF.
#[test]
fn autocorrelation_quadrature_reproduces_the_exact_otf() {
    for s in S {
        let perfect = autocorrelation_otf(s, 0.0, 0.0, LAMBDA0);
        assert!((perfect - optics::mtf_diffraction_limited(s)).abs() < 1e-12, "s {s}: {perfect}");
        for w in [0.3, -0.7, 1.5] {
            let got = autocorrelation_otf(s, w * LAMBDA0, 0.0, LAMBDA0);
            let exact = optics::defocus_otf(s, w);
            assert!((got - exact).abs() < 1e-10, "s {s}, w {w}: {got} vs {exact}");
        }
    }
}

/// The sign test. With spherical aberration `W040 > 0`, the chromatic defocus balances it at
/// the wavelength where `W020(λ) = −W040` (above λ0: `f(λ) < f0` pulls the focus in front of the
/// detector, toward the marginal focus): there the lens's OTF is that of the balanced pupil
/// `W040 (ρ⁴ − ρ²)`; at the wavelength on the other side of λ0, `W020 = +W040`, it is that of
/// `W040 (ρ⁴ + ρ²)` and much worse. A lens whose defocus had the opposite sign swaps the two.
#[test]
fn chromatic_defocus_balances_spherical_aberration_above_the_design_wavelength() {
    let w040 = 0.5e-6;
    let lens = paper_lens().with_seidel(w040, 0.0, 0.0, 0.0);
    let balanced = wavelength_with_defocus(-w040);
    let doubled = wavelength_with_defocus(w040);
    // 805.95 nm and 794.05 nm for the paper's lens (f0/(8F#²) = 67.2 µm)
    assert!((balanced - 805.952e-9).abs() < 1e-12 && (doubled - 794.048e-9).abs() < 1e-12, "{balanced} {doubled}");

    let at_balanced = lens_mtf(&lens, balanced);
    let at_doubled = lens_mtf(&lens, doubled);
    let (mut sum_balanced, mut sum_doubled) = (0.0, 0.0);
    for (i, s) in S.into_iter().enumerate() {
        let good = autocorrelation_otf(s, -w040, w040, balanced);
        let bad = autocorrelation_otf(s, w040, w040, doubled);
        // the two pupils are far apart: the check discriminates the sign
        assert!(good.abs() - bad.abs() > 0.05, "s {s}: {good} vs {bad}");
        assert!((at_balanced[i] - good.abs()).abs() < 2e-3, "s {s}: lens {} vs balanced {good}", at_balanced[i]);
        assert!((at_doubled[i] - bad.abs()).abs() < 2e-3, "s {s}: lens {} vs unbalanced {bad}", at_doubled[i]);
        sum_balanced += at_balanced[i];
        sum_doubled += at_doubled[i];
    }
    assert!(sum_balanced > sum_doubled + 0.5, "{sum_balanced} vs {sum_doubled}");
}

/// Field curvature adds to the chromatic defocus with the same sign: at the wavelength where
/// `W020(λ) = −W220` the field point is in focus (the diffraction-limited MTF), at `W020 = +W220`
/// it sees twice the defocus, `2 W220/λ` waves.
#[test]
fn field_curvature_adds_to_the_chromatic_defocus() {
    let w220 = 0.5e-6;
    let lens = paper_lens().with_seidel(0.0, 0.0, 0.0, w220);
    let sharp = wavelength_with_defocus(-w220);
    let blurred = wavelength_with_defocus(w220);
    let at_sharp = lens_mtf(&lens, sharp);
    let at_blurred = lens_mtf(&lens, blurred);
    for (i, s) in S.into_iter().enumerate() {
        let perfect = optics::mtf_diffraction_limited(s);
        let twice = optics::defocus_otf(s, 2.0 * w220 / blurred).abs();
        assert!(perfect - twice > 0.05, "s {s}");
        assert!((at_sharp[i] - perfect).abs() < 2e-3, "s {s}: {} vs {perfect}", at_sharp[i]);
        assert!((at_blurred[i] - twice).abs() < 2e-3, "s {s}: {} vs {twice}", at_blurred[i]);
    }
}

// ---- the refractive reference (docs/physics.md, "Lens families") ----

/// The diffraction-limited polychromatic mean MTF over `[0, nu_max]` for the `detected`
/// spectrum, from the closed-form monochromatic mean alone: with a wavelength-independent
/// efficiency the mean of `Σ w(λ) MTF0(ν λ F#)/Σ w` over ν is `∫ ρ(λ) M(ν_max λ F#) dλ / ∫ ρ`,
/// `M` = [`optics::mtf_diffraction_limited_mean`]. Gauss–Legendre over ±10 σ of a Gaussian band.
fn diffraction_limited_mean(detected: &Spectrum, centre: f64, sigma: f64, nu_max: f64, f_number: f64) -> f64 {
    let (lo, hi) = (centre - 10.0 * sigma, centre + 10.0 * sigma);
    let num = optics::quad::composite(lo, hi, 64, |l| {
        detected.value(l) * optics::mtf_diffraction_limited_mean(nu_max * l * f_number)
    });
    num / optics::quad::composite(lo, hi, 64, |l| detected.value(l))
}

fn mean_mtf(lens: &dyn optics::LensModel, detected: &Spectrum, nu_max: f64) -> f64 {
    optics::Polychromatic::new(lens, detected, optics::Field::ON_AXIS, nu_max, None).unwrap().mean_mtf().0
}

#[test]
fn dispersion_free_refractive_lens_is_diffraction_limited_over_a_band() {
    use lenses::{Glass, Refractive, Surfaces};
    let lens = Refractive::new(F_NUMBER, F0, LAMBDA0, Glass::Constant(1.5168), 2, Surfaces::Uncoated).unwrap();
    check_lens(&lens, &band(800.0, 100.0)).unwrap();
    for (centre, range) in [(550.0, 100.0), (800.0, 200.0), (1000.0, 50.0)] {
        let detected = band(centre, range);
        let sigma = range * 1e-9 / (2.0 * std::f64::consts::SQRT_2);
        // Nyquist of a 2 µm pixel: 250 cycles/mm, half the cutoff at 800 nm
        let got = mean_mtf(&lens, &detected, 2.5e5);
        let want = diffraction_limited_mean(&detected, centre * 1e-9, sigma, 2.5e5, F_NUMBER);
        assert!((got - want).abs() < 1e-5 * want, "{centre} nm ± {range}: {got} vs {want}");
    }
}

/// N-BK7 focuses red behind the detector and blue in front: the lens's defocus against the hand
/// formula `W020 = f0/(8F#²) (n0 − n)/(n0 − 1)` with the catalogue's indices (n_e = 1.51872 at
/// 546.07 nm, n_C = 1.51432 at 656.27 nm, n_F = 1.52238 at 486.13 nm).
#[test]
fn n_bk7_lens_defocus_has_the_sign_of_normal_dispersion() {
    use lenses::{Glass, Refractive, Sellmeier, Surfaces};
    use optics::LensModel;
    let lens =
        Refractive::new(F_NUMBER, F0, 546.07e-9, Glass::Sellmeier(Sellmeier::N_BK7), 1, Surfaces::Uncoated).unwrap();
    let k = F0 / (8.0 * F_NUMBER * F_NUMBER);
    let n0 = 1.51872;
    for (lambda, n) in [(656.27e-9, 1.51432), (486.13e-9, 1.52238)] {
        let hand = k * (n0 - n) / (n0 - 1.0);
        let order = &lens.orders(lambda, optics::Field::ON_AXIS)[0];
        let w020 = order.wavefront.defocus_m;
        assert_eq!(w020 > 0.0, lambda > 546.07e-9, "{lambda}: {w020}");
        // catalogue indices to 5 decimals: the index difference to ~0.3 %
        assert!((w020 - hand).abs() < 5e-3 * hand.abs(), "{lambda}: {w020} vs {hand}");
    }
    // 656 nm: +0.570 µm, 486 nm: −0.471 µm at F/2.5, f0 = 3.36 mm
    assert!((lens.orders(656.27e-9, optics::Field::ON_AXIS)[0].wavefront.defocus_m - 0.570e-6).abs() < 3e-9);
    // the polychromatic MTF of a broad band is below the diffraction limit, and conforms
    check_lens(&lens, &band(550.0, 100.0)).unwrap();
    let detected = band(550.0, 200.0);
    let sigma = 200e-9 / (2.0 * std::f64::consts::SQRT_2);
    let perfect = diffraction_limited_mean(&detected, 550e-9, sigma, 2.5e5, F_NUMBER);
    assert!(mean_mtf(&lens, &detected, 2.5e5) < perfect);
}

// ---- the dispersion-engineered achromat ----

/// [`diffraction_limited_mean`] with the spectrum restricted to `[lo, hi]` (the wavelengths a
/// lens images), Gauss–Legendre on 64 panels.
fn diffraction_limited_mean_between(detected: &Spectrum, lo: f64, hi: f64, nu_max: f64, f_number: f64) -> f64 {
    let num = optics::quad::composite(lo, hi, 64, |l| {
        detected.value(l) * optics::mtf_diffraction_limited_mean(nu_max * l * f_number)
    });
    num / optics::quad::composite(lo, hi, 64, |l| detected.value(l))
}

#[test]
fn ideal_achromat_is_diffraction_limited_in_its_band() {
    use lenses::{DelayOverflow, DispersionEngineered};
    // F/2.5 at f0 = 3.36 mm needs 221.96 fs: a library of 250 fs suffices
    let lens = DispersionEngineered::new(
        F_NUMBER,
        F0,
        (400e-9, 1200e-9),
        250e-15,
        Curve::Constant(0.3),
        Curve::Constant(0.7),
        DelayOverflow::Reject,
    )
    .unwrap();
    for (centre, range) in [(600.0, 40.0), (800.0, 60.0), (1000.0, 40.0)] {
        let detected = band(centre, range);
        check_lens(&lens, &detected).unwrap();
        let sigma = range * 1e-9 / (2.0 * std::f64::consts::SQRT_2);
        let got = mean_mtf(&lens, &detected, 2.5e5);
        let want = diffraction_limited_mean(&detected, centre * 1e-9, sigma, 2.5e5, F_NUMBER);
        assert!((got - want).abs() < 1e-5 * want, "{centre} nm ± {range}: {got} vs {want}");
    }
    // a band straddling the upper edge: only the wavelengths inside are imaged
    let detected = band(1150.0, 200.0);
    let got = mean_mtf(&lens, &detected, 2.5e5);
    let want =
        diffraction_limited_mean_between(&detected, 1150e-9 - 7.0 * 200e-9 / 8f64.sqrt(), 1200e-9, 2.5e5, F_NUMBER);
    assert!((got - want).abs() < 1e-5 * want, "{got} vs {want}");
}

// ---- the harmonic diffractive lens ----

/// Near λ0 a harmonic lens of design order 1 images as the chromatic lens whose τ1 is its
/// first-order efficiency: the other orders carry ~δ²/k² each (δ = λ0/λ − 1), far below the
/// tolerance. At λ0 exactly only the first order carries light: the diffraction limit.
#[test]
fn harmonic_lens_of_order_one_images_as_the_chromatic_lens_near_the_design_wavelength() {
    use lenses::{Harmonic, sinc};
    let h = Harmonic::new(F_NUMBER, F0, LAMBDA0, 1, 0.4, Curve::Constant(0.6)).unwrap();
    let nus: Vec<f64> = S.iter().map(|s| s / (LAMBDA0 * F_NUMBER)).collect();
    let at_design = optics::monochromatic_mtf(&h, LAMBDA0, optics::Field::ON_AXIS, &nus, 256).unwrap();
    for (s, m) in S.iter().zip(&at_design) {
        assert!((m - optics::mtf_diffraction_limited(*s)).abs() < 1e-12, "s {s}: {m}");
    }
    for lambda in [799.2e-9, 800.5e-9, 801e-9] {
        let tau1 = 0.4 * sinc(LAMBDA0 / lambda - 1.0).powi(2);
        let c = ChromaticMetalens::new(F_NUMBER, F0, LAMBDA0, Curve::Constant(tau1), Curve::Constant(0.6)).unwrap();
        let a = optics::monochromatic_mtf(&h, lambda, optics::Field::ON_AXIS, &nus, 256).unwrap();
        let b = optics::monochromatic_mtf(&c, lambda, optics::Field::ON_AXIS, &nus, 256).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-5, "{lambda}: {x} vs {y}");
        }
    }
}

// ---- the interleaved multiplexed lens ----

/// One channel is the chromatic lens of its wavelength (τ = η/1²); with three channels at the
/// wavelength of one, the monochromatic OTF is the efficiency-weighted sum of that channel's
/// diffraction-limited OTF and the others' defocused ones.
#[test]
fn interleaved_channels_are_chromatic_lenses() {
    use lenses::{Channel, Interleaved};
    let nus: Vec<f64> = S.iter().map(|s| s / (LAMBDA0 * F_NUMBER)).collect();
    let one = vec![Channel { wavelength_m: LAMBDA0, efficiency: Curve::Constant(0.5) }];
    let single = Interleaved::new(F_NUMBER, F0, one, Curve::Constant(0.9)).unwrap();
    let c = ChromaticMetalens::new(F_NUMBER, F0, LAMBDA0, Curve::Constant(0.5), Curve::Constant(0.9)).unwrap();
    for lambda in [780e-9, 800e-9, 830e-9] {
        let a = optics::monochromatic_mtf(&single, lambda, optics::Field::ON_AXIS, &nus, 256).unwrap();
        let b = optics::monochromatic_mtf(&c, lambda, optics::Field::ON_AXIS, &nus, 256).unwrap();
        assert_eq!(a, b, "{lambda}");
    }
    let waves = [700e-9, LAMBDA0, 900e-9];
    let three: Vec<Channel> =
        waves.iter().map(|&w| Channel { wavelength_m: w, efficiency: Curve::Constant(0.6) }).collect();
    let lens = Interleaved::new(F_NUMBER, F0, three, Curve::Constant(0.9)).unwrap();
    check_lens(&lens, &band(800.0, 1.0)).unwrap();
    let got = optics::monochromatic_mtf(&lens, LAMBDA0, optics::Field::ON_AXIS, &nus, 256).unwrap();
    let k = F0 / (8.0 * F_NUMBER * F_NUMBER);
    for (i, s) in S.into_iter().enumerate() {
        let sum: f64 = waves.iter().map(|&w| optics::defocus_otf(s, (1.0 - LAMBDA0 / w) * k / LAMBDA0)).sum();
        let want = (sum / 3.0).abs();
        assert!((got[i] - want).abs() < 1e-12, "s {s}: {} vs {want}", got[i]);
        assert!(got[i] < optics::mtf_diffraction_limited(s));
    }
}

/// A table of `values` evenly over 650–950 nm.
fn rows(values: &[f64]) -> Curve {
    let n = values.len();
    let wavelengths = (0..n).map(|k| 650e-9 + 300e-9 * k as f64 / (n - 1) as f64).collect();
    Curve::Table(Sampled::new(wavelengths, values.to_vec()).unwrap())
}

/// Lenses whose tables are factored out (`LensModel::factored_efficiency`) pass the checks,
/// among them that the parts' orders times their tables are the lens's orders: a chromatic lens
/// with a T table only, an interleaved lens with a table per channel (three parts) and with its
/// outer channels on one table (two parts, its orders not in the lens's order), a harmonic lens
/// with a T table, a dispersion-engineered achromat with a τ table, and segmented lenses with
/// one table for every zone and with a table per zone, other channels as background (for
/// those, the factoring check alone: their polychromatic MTF on the FFT path costs seconds).
#[test]
fn factored_lenses_conform() {
    use lenses::{
        Channel, DelayOverflow, DispersionEngineered, Harmonic, Interleaved, Layout, OtherChannels, Segmented,
    };
    use optics::LensModel;
    let ripple =
        |mean: f64, k: f64| -> Vec<f64> { (0..31).map(|i| mean * (1.0 + 0.1 * (k * i as f64).sin())).collect() };
    let channels = |tables: &[Curve]| -> Vec<Channel> {
        [780e-9, 800e-9, 820e-9]
            .iter()
            .zip(tables)
            .map(|(&wavelength_m, efficiency)| Channel { wavelength_m, efficiency: efficiency.clone() })
            .collect()
    };
    let distinct = [rows(&ripple(0.6, 0.7)), rows(&ripple(0.7, 1.1)), rows(&ripple(0.65, 0.3))];
    let common = [rows(&ripple(0.6, 0.7)), rows(&ripple(0.6, 0.7)), rows(&ripple(0.6, 0.7))];
    // the outer channels on one table: one part for both, the inner channel's part between
    let shared = [rows(&ripple(0.6, 0.7)), rows(&ripple(0.7, 1.1)), rows(&ripple(0.6, 0.7))];
    let t = rows(&ripple(0.9, 0.5));
    let lenses: Vec<(&str, Box<dyn LensModel>)> = vec![
        (
            "chromatic, T table",
            Box::new(ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(0.15), t.clone()).unwrap()),
        ),
        ("interleaved", Box::new(Interleaved::new(2.5, 3.36e-3, channels(&distinct), t.clone()).unwrap())),
        (
            "interleaved, two channels on one table",
            Box::new(Interleaved::new(2.5, 3.36e-3, channels(&shared), t.clone()).unwrap()),
        ),
        ("harmonic", Box::new(Harmonic::new(2.5, 3.36e-3, 800e-9, 5, 0.4, rows(&ripple(0.6, 0.9))).unwrap())),
        (
            "dispersion-engineered",
            Box::new(
                DispersionEngineered::new(
                    2.5,
                    3.36e-3,
                    (760e-9, 840e-9),
                    1e-12,
                    rows(&ripple(0.3, 0.8)),
                    Curve::Constant(0.6),
                    DelayOverflow::Reduced,
                )
                .unwrap(),
            ),
        ),
        (
            "segmented, one table",
            Box::new(
                Segmented::new(5.0, 3.36e-3, channels(&common), Layout::Concentric, None, Curve::Constant(0.9))
                    .unwrap(),
            ),
        ),
        (
            "segmented, a table per zone, background",
            Box::new(
                Segmented::new(5.0, 3.36e-3, channels(&distinct), Layout::Sectors, None, Curve::Constant(0.9))
                    .unwrap()
                    .with_other_channels(OtherChannels::Background),
            ),
        ),
    ];
    let parts = |k: usize| lenses[k].1.factored_efficiency().map(|f| f.parts.len());
    assert_eq!((parts(1), parts(2)), (Some(3), Some(2)));
    for (name, lens) in &lenses {
        assert!(lens.factored_efficiency().is_some(), "{name}");
        if name.starts_with("segmented") {
            // (composite pupils on the FFT path: the polychromatic checks cost seconds here)
            optics::testkit::check_factoring(lens.as_ref(), &band(800.0, 30.0))
                .unwrap_or_else(|e| panic!("{name}: {e}"));
        } else {
            check_lens(lens.as_ref(), &band(800.0, 30.0)).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}

/// A lens whose factoring does not give its orders: a chromatic lens's, its table doubled.
#[derive(Debug)]
struct Misfactored(ChromaticMetalens);

impl optics::LensModel for Misfactored {
    fn f_number(&self) -> f64 {
        self.0.f_number()
    }
    fn focal_length(&self) -> f64 {
        self.0.focal_length()
    }
    fn orders(&self, wavelength_m: f64, field: optics::Field) -> Vec<optics::Order> {
        self.0.orders(wavelength_m, field)
    }
    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.0.transmission(wavelength_m)
    }
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        let mut f = self.0.factored_efficiency()?;
        f.parts[0].table = Spectrum::product(vec![Spectrum::Constant(2.0), f.parts[0].table.clone()]);
        Some(f)
    }
}

/// The factoring check fails a factoring whose parts do not give the lens's orders, naming the
/// wavelength and both efficiencies.
#[test]
fn a_wrong_factoring_is_caught() {
    let lens = ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, rows(&[0.1, 0.15, 0.12]), Curve::Constant(0.55)).unwrap();
    optics::testkit::check_factoring(&lens, &band(800.0, 30.0)).unwrap();
    let e = optics::testkit::check_factoring(&Misfactored(lens), &band(800.0, 30.0)).unwrap_err();
    assert!(e.contains("at λ = ") && e.contains("is not among the factored parts' orders"), "{e}");
}
