// Property tests of the optics invariants on physical ranges, with fixed seeds:
//
// - `0 ≤ MTF ≤ MTF(0) = 1`, monochromatic and polychromatic, on and off axis;
// - the MTF vanishes past the incoherent cutoff `1/(λ F#)` of the shortest wavelength (exact
//   path, polychromatic sum, FFT grid);
// - a polychromatic OTF tends to the monochromatic one as the spectral range shrinks (exact and
//   FFT paths);
// - conjugate symmetry `OTF(−ν) = OTF(ν)*` of the complex OTF (lateral colour on the exact path,
//   decentred apertures on the FFT path, the raw FFT grid);
// - Parseval between the sampled pupil and its PSF, and the OTF grid summing to the PSF's
//   central value (the Fourier pair at the origin).
//
// Case counts keep the whole file to a few seconds in the dev profile.

use std::f64::consts::PI;
use std::sync::Arc;

use num_complex::Complex64;
use optics::fft::{Aberrations, Aperture, Otf, OtfPlan, SampledPupil};
use optics::{Field, LensModel, Order, Polychromatic, Pupil, Wavefront, defocus_otf, monochromatic_mtf};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use radiometry::{Gaussian, Spectrum, TopHat};

/// Design wavelength and focal length of the paper's lens.
const LAMBDA0: f64 = 800e-9;
const F0: f64 = 3.36e-3;

/// A chromatic metalens (`f(λ) = f0 λ0/λ`, detector at `f0`), optionally through a sampled
/// aperture, with the lateral colour of a remote stop off axis (`lenses::ChromaticMetalens`,
/// which this crate cannot depend on).
#[derive(Debug)]
struct Chromatic {
    f_number: f64,
    aperture: Option<Arc<Aperture>>,
}

impl Chromatic {
    fn new(f_number: f64) -> Chromatic {
        Chromatic { f_number, aperture: None }
    }

    fn with_aperture(f_number: f64, aperture: Aperture) -> Chromatic {
        Chromatic { f_number, aperture: Some(Arc::new(aperture)) }
    }

    /// `W020(λ) = (1 − λ/λ0) f0/(8 F#²)`, m (docs/physics.md, "Sign of the wavefront": negative for
    /// λ > λ0, the focus in front of the detector).
    fn w020(&self, lambda: f64) -> f64 {
        (1.0 - lambda / LAMBDA0) * F0 / (8.0 * self.f_number * self.f_number)
    }
}

impl LensModel for Chromatic {
    fn f_number(&self) -> f64 {
        self.f_number
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, lambda: f64, field: Field) -> Vec<Order> {
        let k = LAMBDA0 / lambda - 1.0;
        let wavefront =
            Wavefront::defocus(self.w020(lambda)).shifted(F0 * field.x_rad.tan() * k, F0 * field.y_rad.tan() * k);
        let pupil = self.aperture.as_ref().map_or(Pupil::Full, |a| Pupil::Aperture(a.clone()));
        vec![Order::new(0.15, pupil, wavefront)]
    }
}

/// Detected density of a Gaussian band: `G(λ) · λ` (flat source, constant QE).
fn gaussian_band(centre_m: f64, range_m: f64) -> Spectrum {
    Spectrum::product(vec![
        Spectrum::Gaussian(Gaussian::from_range(centre_m, range_m, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ])
}

fn config(cases: u32, seed: u64) -> ProptestConfig {
    ProptestConfig { cases, rng_seed: RngSeed::Fixed(seed), failure_persistence: None, ..ProptestConfig::default() }
}

/// `10^x`: log-uniform ranges for quantities spanning decades.
fn exp10(x: f64) -> f64 {
    10f64.powf(x)
}

/// Slack for rounding in quantities bounded by 1.
const ROUNDING: f64 = 1e-12;

proptest! {
    #![proptest_config(config(256, 0x5eed_0001))]

    /// Monochromatic: `|OTF(s, w)| ≤ OTF(0, w) = 1` for any defocus up to 1000 waves, and
    /// exactly 0 from the cutoff `s = 1` on.
    #[test]
    fn monochromatic_otf_is_bounded_by_one_and_cut_off(s in 0.0f64..1.0, w in 0.0f64..1000.0, past in 1.0f64..10.0) {
        prop_assert_eq!(defocus_otf(0.0, w), 1.0);
        let v = defocus_otf(s, w);
        prop_assert!(v.is_finite() && v.abs() <= 1.0 + ROUNDING, "OTF({s}, {w}) = {v}");
        prop_assert_eq!(defocus_otf(past, w), 0.0);
    }
}

proptest! {
    #![proptest_config(config(24, 0x5eed_0002))]

    /// Polychromatic, on and off axis, with and without the pixel MTF: `MTF(0) = 1` and
    /// `0 ≤ MTF ≤ 1` along both detector axes, from F/1 to F/16, ranges 0.1–100 nm, centres
    /// 450–1000 nm, pixels 1–20 µm, fields up to 15°.
    #[test]
    fn polychromatic_mtf_is_bounded_by_its_value_at_zero(
        log_f in 0.0f64..1.2,
        log_range_nm in -1.0f64..2.0,
        centre_nm in 450.0f64..1000.0,
        pixel_um in 1.0f64..20.0,
        pixel_on in any::<bool>(),
        field_deg in 0.0f64..15.0,
    ) {
        let lens = Chromatic::new(exp10(log_f));
        let spectrum = gaussian_band(centre_nm * 1e-9, exp10(log_range_nm) * 1e-9);
        let nyquist = 0.5 / (pixel_um * 1e-6);
        let field = Field::new(field_deg.to_radians(), 0.0);
        let pixel = pixel_on.then_some(pixel_um * 1e-6);
        let poly = Polychromatic::new(&lens, &spectrum, field, nyquist, pixel).unwrap();
        prop_assert_eq!(poly.mtf(0.0), 1.0);
        prop_assert!((poly.mtf_along(0.0, 0.3) - 1.0).abs() <= ROUNDING);
        for i in 1..=12 {
            let nu = nyquist * i as f64 / 12.0;
            for m in [poly.mtf(nu), poly.mtf_along(nu, 0.0), poly.mtf_along(nu, 0.5 * PI)] {
                prop_assert!(m.is_finite() && (0.0..=1.0 + ROUNDING).contains(&m), "MTF({nu}) = {m}");
            }
        }
    }

    /// Past the cutoff `1/(λ_min F#)` of the shortest wavelength of a top-hat band the
    /// polychromatic MTF is exactly 0, and the engine's own cutoff is that one.
    #[test]
    fn polychromatic_mtf_vanishes_past_the_cutoff_of_the_shortest_wavelength(
        log_f in 0.0f64..1.5,
        lo_nm in 400.0f64..900.0,
        width_nm in 1.0f64..200.0,
        past in 1.0001f64..3.0,
    ) {
        let f_number = exp10(log_f);
        let lens = Chromatic::new(f_number);
        let (lo, hi) = (lo_nm * 1e-9, (lo_nm + width_nm) * 1e-9);
        let spectrum =
            Spectrum::product(vec![Spectrum::TopHat(TopHat::new(lo, hi, 1.0).unwrap()), Spectrum::Linear { slope: 1.0 }]);
        let cutoff = 1.0 / (lo * f_number);
        let poly = Polychromatic::new(&lens, &spectrum, Field::ON_AXIS, 4.0 * cutoff, None).unwrap();
        prop_assert!((poly.max_cutoff() / cutoff - 1.0).abs() < 1e-12, "{} vs {cutoff}", poly.max_cutoff());
        prop_assert_eq!(poly.mtf(past * cutoff), 0.0);
        prop_assert_eq!(poly.mtf_along(past * cutoff, 1.0), 0.0);
        // and not before it: the band's own cutoffs start at 1/(hi F#)
        prop_assert!(poly.mtf(0.5 / (hi * f_number)) > 0.0);
        let mono = monochromatic_mtf(&lens, lo, Field::ON_AXIS, &[past * cutoff, 0.5 * cutoff], 64).unwrap();
        prop_assert_eq!(mono[0], 0.0);
        prop_assert!(mono[1] > 0.0 && mono[1] <= 1.0 + ROUNDING);
    }

    /// As the spectral range goes to 0 the polychromatic OTF is the monochromatic one at the
    /// centre wavelength: `defocus_otf(ν λ F#, W020/λ)` and [`monochromatic_mtf`].
    #[test]
    fn narrow_band_is_the_monochromatic_otf(
        log_f in 0.0f64..1.2,
        centre_nm in 500.0f64..1000.0,
        frac in 0.0f64..0.98,
    ) {
        let f_number = exp10(log_f);
        let lens = Chromatic::new(f_number);
        let centre = centre_nm * 1e-9;
        let cutoff = 1.0 / (centre * f_number);
        let nu = frac * cutoff;
        let mono = defocus_otf(frac, lens.w020(centre) / centre);
        let mono_mtf = monochromatic_mtf(&lens, centre, Field::ON_AXIS, &[nu], 64).unwrap()[0];
        prop_assert!((mono_mtf - mono.abs()).abs() < 1e-12, "{mono_mtf} vs {mono}");
        // the error falls with the range: 1e-3 nm and 1e-5 nm (relative ranges 1e-6, 1e-8)
        let mut errors = Vec::new();
        for range in [1e-12, 1e-14] {
            let spectrum = gaussian_band(centre, range);
            let poly = Polychromatic::new(&lens, &spectrum, Field::ON_AXIS, cutoff, None).unwrap();
            errors.push((poly.otf(nu) - mono).abs());
            prop_assert!((poly.mtf(nu) - mono_mtf).abs() < 1e-6, "{} vs {mono_mtf}", poly.mtf(nu));
        }
        prop_assert!(errors[0] < 1e-6 && errors[1] < 1e-8, "{errors:?}");
    }
}

proptest! {
    #![proptest_config(config(12, 0x5eed_0003))]

    /// A narrow band through a decentred iris tends to [`monochromatic_mtf`] (both on the exact
    /// path, the iris reduced to the centred circle with a tilt), and on the FFT path to the
    /// single pupil grid, as the spectral range shrinks.
    #[test]
    fn narrow_band_through_a_decentred_iris_is_monochromatic(
        log_f in 0.2f64..1.0,
        centre_nm in 600.0f64..1000.0,
        dx in -0.3f64..0.3,
        dy in -0.3f64..0.3,
        frac in 0.01f64..1.0,
        azimuth in 0.0f64..6.3,
    ) {
        let f_number = exp10(log_f);
        let lens = Chromatic::with_aperture(f_number, Aperture::circle().decentred(dx, dy).unwrap());
        let centre = centre_nm * 1e-9;
        let max_frequency = 0.25 / (centre * f_number);
        let nu = frac * max_frequency;
        let spectrum = gaussian_band(centre, 1e-14);
        // (the iris on the FFT path: the engine would otherwise reduce it to the exact path)
        let settings = optics::Settings { pupil_samples: Some(64), exact_irises: false, ..optics::Settings::default() };
        let poly = Polychromatic::with_settings(&lens, &spectrum, Field::ON_AXIS, max_frequency, None, settings).unwrap();
        let on_fft = matches!(poly.engine(), optics::Engine::Fft { pupil_samples: 64, .. });
        prop_assert!(on_fft, "{:?}", poly.engine());
        // monochromatic_mtf reduces the iris to the exact path, as the engine does by default
        let mono = monochromatic_mtf(&lens, centre, Field::ON_AXIS, &[nu], 64).unwrap()[0];
        let exact = Polychromatic::new(&lens, &spectrum, Field::ON_AXIS, max_frequency, None).unwrap();
        prop_assert!(matches!(exact.engine(), optics::Engine::Exact1d), "{:?}", exact.engine());
        let along_x = exact.mtf_along(nu, 0.0);
        prop_assert!((along_x - mono).abs() < 1e-6, "{along_x} vs {mono}");
        // a single pupil grid by hand, read along any azimuth
        let pupil = SampledPupil::new(64, lens.aperture.as_deref().unwrap(), &Aberrations::defocus(lens.w020(centre)))
            .unwrap();
        let mut plan = OtfPlan::new(64, 0.25).unwrap();
        let mut otf = Otf::new();
        plan.otf(&pupil, centre, &mut otf);
        let direct = otf.at(nu * centre * f_number, azimuth).norm();
        prop_assert!((poly.mtf_along(nu, azimuth) - direct).abs() < 1e-6, "{} vs {direct}", poly.mtf_along(nu, azimuth));
    }

    /// Conjugate symmetry of the complex polychromatic OTF: `OTF(ν, θ + π) = OTF(ν, θ)* =
    /// OTF(−ν, θ)`, with lateral colour off axis (exact path) and through a decentred iris with
    /// lateral colour (FFT path).
    #[test]
    fn complex_polychromatic_otf_is_conjugate_symmetric(
        log_f in 0.2f64..1.0,
        log_range_nm in 0.0f64..2.0,
        field_x_deg in -10.0f64..10.0,
        field_y_deg in -10.0f64..10.0,
        dx in -0.3f64..0.3,
        frac in 0.0f64..1.0,
        azimuth in 0.0f64..6.3,
    ) {
        let f_number = exp10(log_f);
        let spectrum = gaussian_band(LAMBDA0, exp10(log_range_nm) * 1e-9);
        let field = Field::new(field_x_deg.to_radians(), field_y_deg.to_radians());
        let max_frequency = 0.2 / (LAMBDA0 * f_number);
        let nu = frac * max_frequency;
        let exact = Chromatic::new(f_number);
        let iris = Chromatic::with_aperture(f_number, Aperture::circle().decentred(dx, 0.1).unwrap());
        for (lens, samples) in [(&exact, 64), (&iris, 48)] {
            let poly = Polychromatic::with_pupil_samples(lens, &spectrum, field, max_frequency, None, samples).unwrap();
            let z = poly.otf_along(nu, azimuth);
            let opposite = poly.otf_along(nu, azimuth + PI);
            let negative = poly.otf_along(-nu, azimuth);
            prop_assert!(z.norm() <= 1.0 + ROUNDING, "{z}");
            prop_assert!((opposite - z.conj()).norm() < 1e-12, "{opposite} vs {}", z.conj());
            prop_assert!((negative - z.conj()).norm() < 1e-12, "{negative} vs {}", z.conj());
        }
    }
}

/// A random pupil: a decentred annulus with defocus, spherical aberration, coma and astigmatism
/// (coefficients in waves at `LAMBDA0`).
fn pupil(n: usize, dx: f64, dy: f64, obscuration: f64, waves: [f64; 4], field: f64) -> SampledPupil {
    let aperture = Aperture::annulus(obscuration).unwrap().decentred(dx, dy).unwrap();
    let aberrations = Aberrations {
        w020_m: waves[0] * LAMBDA0,
        w040_m: waves[1] * LAMBDA0,
        w131_m: waves[2] * LAMBDA0,
        w222_m: waves[3] * LAMBDA0,
        field,
        ..Aberrations::default()
    };
    SampledPupil::new(n, &aperture, &aberrations).unwrap()
}

proptest! {
    #![proptest_config(config(16, 0x5eed_0004))]

    /// The FFT grid of any pupil: `OTF(−k) = OTF(k)*` at every stored lag, `|OTF| ≤ OTF(0) = 1`,
    /// and past the full aperture's cutoff (lags `|k| ≥ N`, `s ≥ 1`) the OTF is 0.
    #[test]
    fn fft_grid_is_conjugate_symmetric_bounded_and_cut_off(
        n in 16usize..48,
        dx in -0.4f64..0.4,
        dy in -0.4f64..0.4,
        obscuration in 0.0f64..0.6,
        w020 in -3.0f64..3.0,
        w040 in -2.0f64..2.0,
        w131 in -2.0f64..2.0,
        w222 in -2.0f64..2.0,
        field in 0.0f64..1.0,
    ) {
        let pupil = pupil(n, dx, dy, obscuration, [w020, w040, w131, w222], field);
        let mut plan = OtfPlan::new(n, 1.0).unwrap();
        let mut otf = Otf::new();
        plan.otf(&pupil, LAMBDA0, &mut otf);
        let k = otf.max_lag() as i64;
        prop_assert!(k >= n as i64);
        prop_assert_eq!(otf.sample(0, 0), Complex64::new(1.0, 0.0));
        let mut asymmetry: f64 = 0.0;
        let mut beyond: f64 = 0.0;
        for ky in -k..=k {
            for kx in -k..=k {
                let z = otf.sample(kx, ky);
                asymmetry = asymmetry.max((otf.sample(-kx, -ky) - z.conj()).norm());
                prop_assert!(z.norm() <= 1.0 + 1e-9, "|OTF({kx}, {ky})| = {}", z.norm());
                if kx.abs() >= n as i64 || ky.abs() >= n as i64 {
                    beyond = beyond.max(z.norm());
                }
            }
        }
        prop_assert!(asymmetry < 1e-13, "{asymmetry:e}");
        prop_assert!(beyond < 1e-12, "{beyond:e}");
    }

    /// Parseval: `Σ PSF = M² Σ |P|²` with `|P|² = A²`; the PSF's chief-ray value is `|Σ P|²`
    /// (the DFT at 0); and the OTF is its Fourier pair: `Σ_k autocorrelation(k) = |Σ P|²`, i.e.
    /// `Σ A (Σ_k OTF(k) − 1) + Σ A² = PSF(0)` (the zero lag is stored as exactly 1 instead of
    /// `Σ A²/Σ A`).
    #[test]
    fn parseval_between_pupil_psf_and_otf(
        n in 16usize..64,
        dx in -0.4f64..0.4,
        dy in -0.4f64..0.4,
        obscuration in 0.0f64..0.6,
        w020 in -3.0f64..3.0,
        w040 in -2.0f64..2.0,
        w131 in -2.0f64..2.0,
        field in 0.0f64..1.0,
    ) {
        let pupil = pupil(n, dx, dy, obscuration, [w020, w040, w131, 0.0], field);
        let mut plan = OtfPlan::new(n, 1.0).unwrap();
        let m = plan.padded_len() as f64;
        let mut psf = Vec::new();
        plan.psf(&pupil, LAMBDA0, &mut psf);
        let energy: f64 = pupil.amplitude().iter().map(|a| a * a).sum();
        let psf_sum: f64 = psf.iter().sum();
        prop_assert!((psf_sum / (m * m * energy) - 1.0).abs() < 1e-12, "{psf_sum} vs {}", m * m * energy);
        let k = 2.0 * PI / LAMBDA0;
        let field_sum: Complex64 = pupil
            .amplitude()
            .iter()
            .zip(pupil.opd_m())
            .map(|(&a, &w)| Complex64::from_polar(a, k * w))
            .sum();
        prop_assert!((psf[0] / field_sum.norm_sqr() - 1.0).abs() < 1e-10, "{} vs {}", psf[0], field_sum.norm_sqr());

        let mut otf = Otf::new();
        plan.otf(&pupil, LAMBDA0, &mut otf);
        let lag = otf.max_lag() as i64;
        let mut total = Complex64::new(0.0, 0.0);
        for ky in -lag..=lag {
            for kx in -lag..=lag {
                total += otf.sample(kx, ky);
            }
        }
        let area: f64 = pupil.amplitude().iter().sum();
        let central = area * (total.re - 1.0) + energy;
        prop_assert!(total.im.abs() < 1e-9 * total.re.abs().max(1.0), "{total}");
        prop_assert!((central / psf[0] - 1.0).abs() < 1e-9, "{central} vs {}", psf[0]);
    }
}
