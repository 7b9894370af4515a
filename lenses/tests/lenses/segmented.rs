//! The segmented multiplexed lens against independent formulas: one full-aperture channel is
//! the chromatic lens; concentric zones against a brute-force autocorrelation of the composite
//! pupil; photon counts Σ a_j η_j.

use std::sync::Arc;

use lenses::{Channel, ChromaticMetalens, Curve, Layout, OtherChannels, Segmented, ZoneMap};
use optics::testkit::check_lens;
use optics::{Field, LensModel};
use radiometry::Sampled;

use crate::{F_NUMBER, F0, LAMBDA0, S, band, mean_mtf};

fn channel(wavelength_m: f64, efficiency: Curve) -> Channel {
    Channel { wavelength_m, efficiency }
}

fn constant(waves: &[f64], eta: f64) -> Vec<Channel> {
    waves.iter().map(|&w| channel(w, Curve::Constant(eta))).collect()
}

/// One channel filling the aperture is the chromatic lens of its wavelength: the same order
/// efficiency and defocus, and (through the composite pupil on the FFT path) the same MTF.
#[test]
fn one_full_aperture_channel_is_the_chromatic_lens() {
    let c = ChromaticMetalens::new(F_NUMBER, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap();
    let nus: Vec<f64> = S.iter().map(|s| s / (LAMBDA0 * F_NUMBER)).collect();
    for layout in [Layout::Concentric, Layout::Sectors] {
        let seg =
            Segmented::new(F_NUMBER, F0, constant(&[LAMBDA0], 0.15), layout, None, Curve::Constant(0.55)).unwrap();
        for lambda in [790e-9, 800e-9, 812e-9] {
            let (a, b) = (&seg.orders(lambda, Field::ON_AXIS)[0], &c.orders(lambda, Field::ON_AXIS)[0]);
            assert!((a.efficiency - b.efficiency).abs() < 1e-15);
            assert_eq!(a.wavefront.defocus_m, b.wavefront.defocus_m);
            let x = optics::monochromatic_mtf(&seg, lambda, Field::ON_AXIS, &nus, 256).unwrap();
            let y = optics::monochromatic_mtf(&c, lambda, Field::ON_AXIS, &nus, 256).unwrap();
            for (u, v) in x.iter().zip(&y) {
                // the FFT path against the exact 1-D path: 1e-4 at 256 samples (optics' fft docs)
                assert!((u - v).abs() < 2e-4, "{lambda}: {u} vs {v}");
            }
        }
        let detected = band(800.0, 20.0);
        let (a, b) = (mean_mtf(&seg, &detected, 2.5e5), mean_mtf(&c, &detected, 2.5e5));
        eprintln!("one channel, 800 ± 20 nm: segmented {a:.6}, chromatic {b:.6}");
        assert!((a - b).abs() < 2e-4 * b, "{a} vs {b}");
    }
}

/// OTF along +x at `s` of a circular pupil whose field is `amp(ρ²) exp(i 2π w(ρ²) ρ²/λ)`
/// (rotationally symmetric zones), by a midpoint rule over the overlap of the two shifted
/// pupils `P(x − s, y) P*(x + s, y)` (shift 2s in radius units), normalized by `∫ |P|²`: written
/// here independently of the FFT path.
fn brute_force_otf(s: f64, wavelength: f64, zone: &dyn Fn(f64) -> (f64, f64)) -> f64 {
    let n = 1200;
    let h = 2.0 / n as f64;
    let field = |x: f64, y: f64| -> (f64, f64) {
        let r2 = x * x + y * y;
        if r2 > 1.0 {
            return (0.0, 0.0);
        }
        let (amp, w020) = zone(r2);
        (amp, std::f64::consts::TAU * w020 * r2 / wavelength)
    };
    let (mut sum, mut norm) = (0.0, 0.0);
    for i in 0..n {
        let x = -1.0 + (i as f64 + 0.5) * h;
        for k in 0..n {
            let y = -1.0 + (k as f64 + 0.5) * h;
            let (a0, _) = field(x, y);
            norm += a0 * a0;
            let (a1, p1) = field(x - s, y);
            let (a2, p2) = field(x + s, y);
            sum += a1 * a2 * (p1 - p2).cos();
        }
    }
    sum / norm
}

/// Two concentric zones (inner: the 800 nm channel, outer: the 850 nm channel, η 0.6 and 0.3,
/// unequal areas) at 820 nm: the composite pupil's OTF against the brute-force autocorrelation.
#[test]
fn concentric_zones_match_a_brute_force_autocorrelation() {
    let chans = vec![channel(800e-9, Curve::Constant(0.6)), channel(850e-9, Curve::Constant(0.3))];
    let seg =
        Segmented::new(F_NUMBER, F0, chans, Layout::Concentric, Some(vec![0.4, 0.6]), Curve::Constant(0.7)).unwrap();
    let lambda = 820e-9;
    let k = F0 / (8.0 * F_NUMBER * F_NUMBER);
    let (w1, w2) = ((1.0 - lambda / 800e-9) * k, (1.0 - lambda / 850e-9) * k);
    let zone = |r2: f64| if r2 <= 0.4 { (0.6f64.sqrt(), w1) } else { (0.3f64.sqrt(), w2) };
    let nus: Vec<f64> = S.iter().map(|s| s / (lambda * F_NUMBER)).collect();
    let got = optics::monochromatic_mtf(&seg, lambda, Field::ON_AXIS, &nus, 256).unwrap();
    for (i, s) in S.into_iter().enumerate() {
        // measured agreement ≤ 2e-4 (the FFT path at 256 samples and the 1200² midpoint rule)
        let want = brute_force_otf(s, lambda, &zone).abs();
        eprintln!("s {s}: engine {:.5}, brute force {want:.5}", got[i]);
        assert!((got[i] - want).abs() < 1e-3, "s {s}: {} vs {want}", got[i]);
    }
    assert!((seg.efficiency(lambda) - (0.4 * 0.6 + 0.6 * 0.3)).abs() < 1e-15);
}

/// The zones' efficiencies sum to Σ a_j η_j(λ), with tabulated η_j, for every layout.
#[test]
fn zone_efficiencies_sum_to_the_area_weighted_efficiencies() {
    let eta = |peak: f64, at: f64| {
        Curve::Table(Sampled::new(vec![at - 100e-9, at, at + 100e-9], vec![0.2 * peak, peak, 0.3 * peak]).unwrap())
    };
    let chans = || {
        vec![channel(650e-9, eta(0.7, 650e-9)), channel(550e-9, eta(0.8, 550e-9)), channel(450e-9, eta(0.6, 450e-9))]
    };
    let areas = [0.2, 0.5, 0.25];
    let map: Arc<ZoneMap> = Arc::new(|x: f64, y: f64| {
        if y > 0.0 {
            Some(0)
        } else if x > 0.0 {
            Some(1)
        } else {
            Some(2)
        }
    });
    let lenses = [
        Segmented::new(F_NUMBER, F0, chans(), Layout::Concentric, Some(areas.to_vec()), Curve::Constant(0.9)).unwrap(),
        Segmented::new(F_NUMBER, F0, chans(), Layout::Sectors, Some(areas.to_vec()), Curve::Constant(0.9)).unwrap(),
        Segmented::new(F_NUMBER, F0, chans(), Layout::Mask(map), None, Curve::Constant(0.9)).unwrap(),
    ];
    let want_areas: [&[f64]; 3] = [&areas, &areas, &[0.5, 0.25, 0.25]];
    for (lens, want) in lenses.iter().zip(want_areas) {
        for (a, b) in lens.area_fractions().iter().zip(want) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
        for lambda in [420e-9, 500e-9, 555e-9, 640e-9, 700e-9] {
            let by_hand: f64 =
                (0..3).map(|j| lens.area_fractions()[j] * lens.channels()[j].efficiency.value(lambda)).sum();
            let zones: f64 = (0..3).map(|j| lens.zone_efficiency(j, lambda)).sum();
            let order = &lens.orders(lambda, Field::ON_AXIS)[0];
            assert!((order.efficiency - by_hand).abs() < 1e-15, "{lambda}");
            assert!((zones - by_hand).abs() < 1e-15, "{lambda}");
            assert!((order.pupil.area_fraction() - by_hand).abs() < 1e-12, "{lambda}");
            assert!(order.efficiency <= lens.transmission(lambda));
        }
    }
}

/// Three sectors at 750, 800, 850 nm against the chromatic lens at 800 nm of the same
/// efficiency (F/5, so that 128 pupil samples resolve the defocus at the band edges): the
/// multiplexed lens does not raise the broadband mean MTF (each wavelength is focused by one
/// third of the aperture only; the rest adds its defocused image).
#[test]
fn segmented_lens_does_not_beat_the_chromatic_lens_over_a_broad_band() {
    let f_number = 5.0;
    let waves = [750e-9, 800e-9, 850e-9];
    let seg = Segmented::new(f_number, F0, constant(&waves, 0.5), Layout::Sectors, None, Curve::Constant(0.8)).unwrap();
    let c = ChromaticMetalens::new(f_number, F0, LAMBDA0, Curve::Constant(0.5), Curve::Constant(0.8)).unwrap();
    check_lens(&seg, &band(800.0, 4.0)).unwrap();
    let nyquist = 1e5;
    for range in [50.0, 100.0, 200.0] {
        let detected = band(800.0, range);
        let a = optics::Polychromatic::with_pupil_samples(&seg, &detected, Field::ON_AXIS, nyquist, None, 128)
            .unwrap()
            .mean_mtf()
            .0;
        let b = mean_mtf(&c, &detected, nyquist);
        eprintln!(
            "F/5, 800 nm, range {range} nm, 100 cycles/mm: mean MTF segmented {a:.4}, chromatic {b:.4}: {:.0} % below",
            100.0 * (1.0 - a / b)
        );
        assert!(a < b, "{range} nm: {a} vs {b}");
    }
    let bg = seg.clone().with_other_channels(OtherChannels::Background);
    check_lens(&bg, &band(800.0, 4.0)).unwrap();
}

/// With the other channels as background the lens jumps from one lit zone to the next at each
/// band edge (its breakpoints): the spectral panels stop there instead of refining towards the
/// jump (which took 3.5 million panels before the interval ends were read from inside), and at
/// one wavelength inside a band the lens is that channel's zone alone.
#[test]
fn background_channels_evaluate_in_few_panels() {
    let lens = Segmented::new(
        F_NUMBER,
        F0,
        constant(&[750e-9, 800e-9, 850e-9], 0.15),
        Layout::Sectors,
        None,
        Curve::Constant(0.55),
    )
    .unwrap()
    .with_other_channels(OtherChannels::Background);
    let detected = band(800.0, 50.0);
    let settings = optics::Settings { pupil_samples: Some(64), ..optics::Settings::default() };
    let poly = optics::Polychromatic::with_settings(&lens, &detected, Field::ON_AXIS, 96.15e3, None, settings).unwrap();
    let (mean, work) = poly.mean_mtf();
    assert!(work.spectral_panels < 64, "{work:?}");
    assert!(mean > 0.0 && mean < 1.0, "{mean}");
    // inside the 800 nm band only the middle zone is lit: a third of the aperture, η = 0.15
    let orders = lens.orders(790e-9, Field::ON_AXIS);
    let optics::Pupil::Zones(zones) = &orders[0].pupil else { panic!("{:?}", orders[0].pupil) };
    let lit: Vec<usize> = (0..zones.len()).filter(|&j| zones[j].amplitude > 0.0).collect();
    assert_eq!(lit, [1]);
    assert!((orders[0].efficiency - 0.05).abs() < 1e-15, "{}", orders[0].efficiency);
}
