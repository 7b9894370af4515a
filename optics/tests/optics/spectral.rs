//! The product-integration spectral rule (the default) against the per-interval panels rule (the
//! reference, exact to rounding) on hard scenes: a measured-like table with a kink at every
//! sample, broad bands with tens of waves of defocus, OTF sign changes, and lateral colour.

use optics::{Field, LensModel, Order, Polychromatic, Pupil, Settings, SpectralRule, Wavefront};
use radiometry::{Gaussian, Sampled, Spectrum, TopHat};

const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;

/// The chromatic metalens of docs/physics.md, `W020 = (1 − λ/λ0) f0/(8 F#²)`, with an optional
/// lateral colour: the image moves by `lateral × (λ − λ0)/λ0` along x.
#[derive(Debug)]
struct Chromatic {
    f_number: f64,
    lateral: f64,
}

impl LensModel for Chromatic {
    fn f_number(&self) -> f64 {
        self.f_number
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        let w020 = (1.0 - lambda / LAMBDA0) * F0 / (8.0 * self.f_number * self.f_number);
        let wavefront = Wavefront::defocus(w020).shifted(self.lateral * (lambda - LAMBDA0) / LAMBDA0, 0.0);
        vec![Order::new(0.15, Pupil::Full, wavefront)]
    }
    fn affine_defocus(&self, _: Field) -> Option<optics::AffineDefocus> {
        // W020 = f0/(8F#²) − λ f0/(8F#² λ0), promised only without lateral colour
        let k = F0 / (8.0 * self.f_number * self.f_number);
        (self.lateral == 0.0).then_some(optics::AffineDefocus {
            efficiency: 0.15,
            transmission: 1.0,
            w020_intercept_m: k,
            w020_slope: -k / LAMBDA0,
        })
    }
}

/// A spectrometer-like table over `lo`–`hi` nm at `step` nm: a steep band of 52 nm at 825 nm, a
/// 0.2 % floor and ±0.05 % of seeded noise, times λ (photon counts), piecewise linear.
fn table(lo: f64, hi: f64, step: f64) -> Spectrum {
    let mut rng: rand_pcg::Pcg64Mcg = rand::SeedableRng::seed_from_u64(0x2545_f491_4f6c_dd1d);
    let n = ((hi - lo) / step).round() as usize + 1;
    let (mut waves, mut values) = (Vec::new(), Vec::new());
    for i in 0..n {
        let nm = lo + step * i as f64;
        let noise = (rand::RngExt::random::<f64>(&mut rng) - 0.5) * 1e-3;
        let band = 0.9 / (1.0 + ((nm - 825.0) / 26.0).powi(10));
        waves.push(nm * 1e-9);
        values.push((band + 0.002 + noise).max(0.0));
    }
    Spectrum::product(vec![Spectrum::Sampled(Sampled::new(waves, values).unwrap()), Spectrum::Linear { slope: 1.0 }])
}

fn gaussian(centre_nm: f64, range_nm: f64) -> Spectrum {
    Spectrum::product(vec![
        Spectrum::Gaussian(Gaussian::from_range(centre_nm * 1e-9, range_nm * 1e-9, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ])
}

fn top_hat(lo_nm: f64, hi_nm: f64) -> Spectrum {
    Spectrum::product(vec![
        Spectrum::TopHat(TopHat::new(lo_nm * 1e-9, hi_nm * 1e-9, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ])
}

/// The mean MTF (along x where the OTF depends on direction) with the given rule and tolerance,
/// and the work it took.
fn mean(lens: &Chromatic, spectrum: &Spectrum, pixel: f64, rule: SpectralRule, tolerance: f64) -> (f64, optics::Work) {
    // the closed form off: the Gaussian scenes must take the spectral rules too
    let settings = Settings { tolerance, spectral_rule: rule, closed_form: false, ..Settings::default() };
    let nyquist = 1.0 / (2.0 * pixel);
    let poly = Polychromatic::with_settings(lens, spectrum, Field::ON_AXIS, nyquist, Some(pixel), settings).unwrap();
    poly.mean_mtf_along(0.0)
}

/// Every scene at tolerances 1e-3, 1e-5 and 1e-7: the product-integration mean within the
/// tolerance of the panels rule's at 1e-12 (itself exact to ~1e-12), on product-integration
/// nodes, with no more work at a looser tolerance (nodes, or single-wavelength OTFs where each
/// OTF value climbs its own levels).
#[test]
fn product_integration_meets_the_tolerance_on_hard_scenes() {
    let scenes: Vec<(&str, Chromatic, Spectrum, f64)> = vec![
        // 400 nm of table at 1 nm: a kink at every sample, ±20 waves at the ends
        ("table 600–1000 nm, F/2.5", Chromatic { f_number: 2.5, lateral: 0.0 }, table(600.0, 1000.0, 1.0), 5.2e-6),
        // ±7σ of a 300 nm range: tens of waves of defocus at F/1.4
        ("Gaussian 300 nm, F/1.4", Chromatic { f_number: 1.4, lateral: 0.0 }, gaussian(800.0, 300.0), 5.2e-6),
        // far from λ0 (2–5 waves everywhere): the OTF changes sign below Nyquist
        ("top-hat 600–660 nm, F/1.4", Chromatic { f_number: 1.4, lateral: 0.0 }, top_hat(600.0, 660.0), 2e-6),
        // lateral colour of 20 µm per λ0: the complex OTF turns with λ as well
        ("lateral colour, 700–900 nm", Chromatic { f_number: 2.5, lateral: 20e-6 }, top_hat(700.0, 900.0), 5.2e-6),
    ];
    for (name, lens, spectrum, pixel) in &scenes {
        let (want, _) = mean(lens, spectrum, *pixel, SpectralRule::Panels, 1e-12);
        let mut last_work = 0;
        for tolerance in [1e-7, 1e-5, 1e-3] {
            let (got, work) = mean(lens, spectrum, *pixel, SpectralRule::Interpolated, tolerance);
            let error = ((got - want) / want).abs();
            eprintln!("{name} at {tolerance:e}: {got} vs {want} ({error:.1e}), {work:?}");
            assert!(work.spectral_interpolated, "{name}: {work:?}");
            assert!(error <= tolerance, "{name} at {tolerance:e}: {got} vs {want} ({error:.1e})");
            // the work: the nodes, or where each OTF value chooses its own (per-frequency product
            // integration), the single-wavelength OTFs summed
            let spent = if work.spectral_evaluations > 0 { work.spectral_evaluations } else { work.spectral_nodes };
            assert!(last_work == 0 || spent <= last_work, "{name} at {tolerance:e}: {work:?}");
            last_work = spent;
        }
    }
}

/// Where a cutoff falls inside the band below the frequency limit (F/8 with 2 µm pixels: Nyquist
/// 250 cycles/mm, the cutoff of 600 nm at 208), the panels rule, which clips its panels at the
/// cutoff, is used whatever the setting, and the result is the reference's.
#[test]
fn a_cutoff_inside_the_band_takes_the_panels_rule() {
    let lens = Chromatic { f_number: 8.0, lateral: 0.0 };
    let spectrum = top_hat(500.0, 700.0);
    let (want, _) = mean(&lens, &spectrum, 2e-6, SpectralRule::Panels, 1e-6);
    let (got, work) = mean(&lens, &spectrum, 2e-6, SpectralRule::Interpolated, 1e-6);
    assert!(!work.spectral_interpolated, "{work:?}");
    assert_eq!(got, want);
}

/// The closed form on broad Gaussians whose ±6–10σ reach λ = 0 (300 nm at 800 nm: λ = 0 lies
/// 6.3σ below the centre; the truncation there is dropped where the tail's own share of the
/// tolerance allows) and with the nested frequency rule where all of ±7σ passes Nyquist:
/// within each tolerance of the panels rule at 1e-12.
#[test]
fn closed_form_meets_the_tolerance_on_broad_bands() {
    let scenes = [(1.4, 300.0, 5.2e-6), (2.5, 300.0, 5.2e-6), (5.0, 200.0, 5.2e-6), (2.5, 50.0, 2e-6)];
    for (f_number, range, pixel) in scenes {
        let lens = Chromatic { f_number, lateral: 0.0 };
        let spectrum = gaussian(800.0, range);
        let (want, _) = mean(&lens, &spectrum, pixel, SpectralRule::Panels, 1e-12);
        for tolerance in [1e-4, 1e-6, 1e-8] {
            let settings = Settings { tolerance, ..Settings::default() };
            let nyquist = 1.0 / (2.0 * pixel);
            let poly =
                Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, nyquist, Some(pixel), settings).unwrap();
            assert_eq!(poly.engine(), optics::Engine::ClosedForm, "F/{f_number}, {range} nm");
            let (got, _) = poly.mean_mtf_along(0.0);
            let error = ((got - want) / want).abs();
            assert!(error <= tolerance, "F/{f_number}, {range} nm at {tolerance:e}: {got} vs {want} ({error:.1e})");
        }
    }
}

/// The closed form at 1e-10 on F/1.4 over 200 nm without the pixel MTF (the accuracy report's
/// hard scene): its frequency rule once accepted the panel [0, 12] cycles/mm on a credited
/// acceleration of the nested moves (318, 30.4, 0.0139: 3.0e-8 predicted, 3.8e-6 next), 3.5e-10
/// off; within the tolerance of the panels rule at 1e-12 now.
#[test]
fn closed_form_meets_a_tight_tolerance_on_a_broad_band() {
    let lens = Chromatic { f_number: 1.4, lateral: 0.0 };
    let spectrum = gaussian(800.0, 200.0);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let at = |tolerance: f64, rule: SpectralRule, closed_form: bool| {
        let settings = Settings { tolerance, spectral_rule: rule, closed_form, ..Settings::default() };
        let poly = Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, nyquist, None, settings).unwrap();
        poly.mean_mtf().0
    };
    let want = at(1e-12, SpectralRule::Panels, false);
    let got = at(1e-10, SpectralRule::Interpolated, true);
    let error = ((got - want) / want).abs();
    assert!(error <= 1e-10, "{got} vs {want} ({error:.1e})");
}

/// F/1.4 over 200 nm at 1e-6 (the accuracy report's hard scene): its mean, 0.11, is below half the
/// first pass's guess (0.25), so the mean is computed twice, the second pass 2.2× tighter. A value
/// of the first pass whose own estimate meets the tighter tolerance is kept, not recomputed: 1428
/// E(c) over the two passes, where recomputing every value took 2253. The work is a count, the
/// same on every machine; the mean stays within the tolerance of the panels rule at 1e-12.
#[test]
fn closed_form_second_pass_keeps_the_values_that_meet_it() {
    let lens = Chromatic { f_number: 1.4, lateral: 0.0 };
    let spectrum = gaussian(800.0, 200.0);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let at = |tolerance: f64, rule: SpectralRule, closed_form: bool| {
        let settings = Settings { tolerance, spectral_rule: rule, closed_form, ..Settings::default() };
        let poly = Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, nyquist, None, settings).unwrap();
        poly.mean_mtf()
    };
    let (want, _) = at(1e-12, SpectralRule::Panels, false);
    let (got, work) = at(1e-6, SpectralRule::Interpolated, true);
    let error = ((got - want) / want).abs();
    assert!(error <= 1e-6, "{got} vs {want} ({error:.1e})");
    // two passes of 26 values each: the second asks every frequency again
    assert_eq!(work.otf_evaluations, 52, "{work:?}");
    assert!(
        work.closed_form_evaluations <= 1600,
        "{} E(c): the second pass recomputed kept values",
        work.closed_form_evaluations
    );
}

/// The paper's lens at F/1.86 over a 20 nm band (a point of the 40 × 100 map): the frequency
/// rule's nested estimate once took its ratio from the 3-point level (moves 1.4e-2, then 4.1e-6
/// from 5 to 9 points) and accepted the 9-point mean, 2.7e-7 off, at tolerances 1e-7 and 1e-8.
/// The reference here is not the frequency rule: composite Simpson over 600 intervals of the
/// closed form's MTF at 1e-12 on [0, Nyquist] (its error from the step, about 1e-12 here).
#[test]
fn closed_form_frequency_rule_does_not_trust_the_three_point_level() {
    let lens = Chromatic { f_number: 1.861_538_461_538_461_6, lateral: 0.0 };
    let spectrum = gaussian(800.0, 20.060_606_060_606_062);
    let nyquist = 1.0 / (2.0 * 5.2e-6);
    let settings = |tolerance: f64| Settings { tolerance, ..Settings::default() };
    let exact = Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, nyquist, None, settings(1e-12)).unwrap();
    let intervals = 600;
    let step = nyquist / intervals as f64;
    let simpson: f64 = (0..=intervals)
        .map(|k| {
            let weight = if k == 0 || k == intervals {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            weight * exact.mtf(step * k as f64)
        })
        .sum::<f64>()
        * step
        / 3.0
        / nyquist;
    for tolerance in [1e-6, 1e-7, 1e-8] {
        let poly =
            Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, nyquist, None, settings(tolerance)).unwrap();
        let (got, work) = poly.mean_mtf();
        let error = ((got - simpson) / simpson).abs();
        assert!(error <= tolerance, "at {tolerance:e}: {got} against Simpson's {simpson} ({error:.1e}; {work:?})");
    }
}

/// The spectral lanes on the per-frequency product rule
/// ([`Polychromatic::mean_mtf_and_spectral_lanes`]; docs/physics.md, "Gradients: a line's
/// wavelength and a blackbody's temperature", "Gradients: a top-hat's edges"): the mean is the
/// value's bit for bit, and the lanes match central differences written here of the mean on
/// the panels rule (the reference, exact to rounding) at 1e-12, Richardson-extrapolated from the
/// steps 2h and h (`(4 D(h) − D(2h))/3`):
/// - the rate lane with `r = (λ − c)/σ² − ⟨·⟩`, which is `∂ln ρ/∂c` of a Gaussian band of centre
///   `c` (peak held), against moving `c`;
/// - the edge lanes of a top-hat `[a, b]` against moving `a` and `b`, with the pixel MTF.
///
/// Each within 10× the tolerance asked (1e-7) of `M̄` per unit of the band's scale (σ, or the
/// range), the scale on which the mean varies.
#[test]
fn spectral_lanes_match_differences_of_the_panels_rule() {
    let lens = Chromatic { f_number: 2.5, lateral: 0.0 };
    let pixel = 5.2e-6;
    let nyquist = 1.0 / (2.0 * pixel);
    let tolerance = 1e-7;
    let settings = Settings { tolerance, closed_form: false, ..Settings::default() };
    let reference = |spectrum: &Spectrum| mean(&lens, spectrum, pixel, SpectralRule::Panels, 1e-12).0;
    let richardson = |f: &dyn Fn(f64) -> f64, h: f64| {
        let d = |h: f64| (f(h) - f(-h)) / (2.0 * h);
        (4.0 * d(h) - d(2.0 * h)) / 3.0
    };
    // a Gaussian band of 60 nm at 810 nm: the rate of its centre
    let (c, range) = (810e-9, 60e-9);
    let sigma = range / (2.0 * std::f64::consts::SQRT_2);
    let band = |c: f64| {
        Spectrum::product(vec![
            Spectrum::Gaussian(Gaussian::from_range(c, range, 1.0).unwrap()),
            Spectrum::Linear { slope: 1.0 },
        ])
    };
    let spectrum = band(c);
    let poly = Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, nyquist, Some(pixel), settings).unwrap();
    assert_eq!(poly.engine(), optics::Engine::Exact1d);
    let value = poly.mean_mtf().0;
    let rate = |l: f64| (l - c) / (sigma * sigma);
    let average = poly.spectral_average(|l, _| rate(l));
    let centred = move |l: f64| rate(l) - average;
    let (mean_with_lanes, lanes, _) = poly.mean_mtf_and_spectral_lanes(Some(&centred), false).unwrap();
    assert_eq!(mean_with_lanes.to_bits(), value.to_bits());
    let want = richardson(&|h| reference(&band(c + h)), 1e-3 * sigma);
    let error = (lanes[0] - want).abs() * sigma / value;
    eprintln!("centre: lane {:.9e}, differences {want:.9e}, error × σ/M̄ {error:.1e}", lanes[0]);
    assert!(error <= 10.0 * tolerance, "{} vs {want}", lanes[0]);
    // a top-hat of 770–830 nm: its edges
    let (a, b) = (770e-9, 830e-9);
    let hat = |a: f64, b: f64| {
        Spectrum::product(vec![Spectrum::TopHat(TopHat::new(a, b, 1.0).unwrap()), Spectrum::Linear { slope: 1.0 }])
    };
    let spectrum = hat(a, b);
    let poly = Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, nyquist, Some(pixel), settings).unwrap();
    assert_eq!(poly.spectral_ends(), Some((a, b)));
    let value = poly.mean_mtf().0;
    let (mean_with_lanes, lanes, _) = poly.mean_mtf_and_spectral_lanes(None, true).unwrap();
    assert_eq!(mean_with_lanes.to_bits(), value.to_bits());
    let h = 1e-3 * (b - a);
    let wants = [richardson(&|h| reference(&hat(a + h, b)), h), richardson(&|h| reference(&hat(a, b + h)), h)];
    for (edge, (lane, want)) in ["lower", "upper"].iter().zip(lanes.iter().zip(wants)) {
        let error = (lane - want).abs() * (b - a) / value;
        eprintln!("{edge} edge: lane {lane:.9e}, differences {want:.9e}, error × range/M̄ {error:.1e}");
        assert!(error <= 10.0 * tolerance, "{edge}: {lane} vs {want}");
    }
}
