//! Tabulated orders (`Pupil::Table`) against the lens they were tabulated from: a chromatic
//! lens's exact OTF (`defocus_otf`, docs/physics.md, "Chromatic lens") sampled at 41
//! wavelengths × 200 frequencies reproduces its mean MTF on the exact 1-D path, on the FFT layer
//! beside a sampled pupil and at one wavelength; tangential and sagittal curves are read along
//! and across the field direction.

use std::f64::consts::PI;
use std::sync::Arc;

use optics::fft::Aperture;
use optics::{Engine, Field, LensModel, Order, OtfTable, Polychromatic, Pupil, Wavefront, defocus_otf};
use radiometry::{Line, Spectrum, TopHat};

const F_NUMBER: f64 = 2.5;
const FOCAL_LENGTH: f64 = 3.36e-3;
const DESIGN: f64 = 800e-9;
const EFFICIENCY: f64 = 0.7;
/// The band the table covers, and the spectrum's.
const BAND: (f64, f64) = (780e-9, 820e-9);

fn w020(lambda: f64) -> f64 {
    (1.0 - lambda / DESIGN) * FOCAL_LENGTH / (8.0 * F_NUMBER * F_NUMBER)
}

/// The chromatic lens's OTF at 41 wavelengths (1 nm apart) × 200 frequencies up to the cutoff
/// of the shortest one.
fn chromatic_table() -> OtfTable {
    let wavelengths: Vec<f64> = (0..41).map(|i| BAND.0 + (BAND.1 - BAND.0) * i as f64 / 40.0).collect();
    let top = 1.0 / (BAND.0 * F_NUMBER);
    let frequencies: Vec<f64> = (0..200).map(|k| top * k as f64 / 199.0).collect();
    let rows = wavelengths
        .iter()
        .map(|&l| frequencies.iter().map(|&nu| defocus_otf(nu * l * F_NUMBER, w020(l) / l)).collect())
        .collect();
    OtfTable::new(wavelengths, frequencies, rows, None).unwrap()
}

/// The chromatic lens, its order either exact (`Pupil::Full` with its defocus) or tabulated;
/// optionally with a second order through a sampled annulus (which sends the lens to the FFT
/// layer).
#[derive(Debug)]
struct Chromatic {
    table: Option<Arc<OtfTable>>,
    annulus: Option<Arc<Aperture>>,
}

impl LensModel for Chromatic {
    fn f_number(&self) -> f64 {
        F_NUMBER
    }
    fn focal_length(&self) -> f64 {
        FOCAL_LENGTH
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        let wavefront = Wavefront::defocus(w020(lambda));
        let pupil = match &self.table {
            Some(t) => Pupil::Table(t.clone()),
            None => Pupil::Full,
        };
        let mut orders = vec![Order::new(EFFICIENCY, pupil, wavefront)];
        if let Some(a) = &self.annulus {
            orders.push(Order::new(0.1, Pupil::Aperture(a.clone()), Wavefront::defocus(0.5 * w020(lambda))));
        }
        orders
    }
}

fn band() -> Spectrum {
    Spectrum::product(vec![
        Spectrum::TopHat(TopHat::new(BAND.0, BAND.1, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ])
}

const NYQUIST: f64 = 0.5 / 5.2e-6;

/// On the exact path: the mean MTF over 780–820 nm (Nyquist of 5.2 µm pixels) of the tabulated
/// order against the exact one. The table is linear between its rows and columns; measured
/// difference 5.0e-5 of the mean (0.4989), the table's interpolation error (1 nm rows against
/// the OTF's ≈ 12 nm period in λ at Nyquist, docs/physics.md "Spectral quadrature"; 2.6e3
/// cycles/m columns), far above the engines' 1e-6 tolerance. Pointwise: 7.0e-4.
#[test]
fn a_table_of_the_chromatic_lens_reproduces_its_mean_mtf() {
    let spectrum = band();
    let exact = Chromatic { table: None, annulus: None };
    let tabulated = Chromatic { table: Some(Arc::new(chromatic_table())), annulus: None };
    let pe = Polychromatic::new(&exact, &spectrum, Field::ON_AXIS, NYQUIST, None).unwrap();
    let pt = Polychromatic::new(&tabulated, &spectrum, Field::ON_AXIS, NYQUIST, None).unwrap();
    assert_eq!(pt.engine(), Engine::Exact1d);
    assert!(!pt.direction_dependent());
    // ∫ λ dλ over the band × the efficiency, exactly; each engine's sum of weights within its
    // rounding (the tabulated order's panels rule: 41 panels of 16 nodes, 3.6e-14 measured)
    let exact_weight = 0.5 * (BAND.1 * BAND.1 - BAND.0 * BAND.0) * EFFICIENCY;
    assert!((pe.total_weight() - exact_weight).abs() < 1e-14 * exact_weight, "{}", pe.total_weight());
    assert!((pt.total_weight() - exact_weight).abs() < 1e-13 * exact_weight, "{}", pt.total_weight());
    let (me, _) = pe.mean_mtf();
    let (mt, work) = pt.mean_mtf();
    // the panels are cut at the 41 table rows
    assert!(work.spectral_panels >= 40, "{work:?}");
    let relative = (mt - me).abs() / me;
    assert!(relative < 1e-4, "table {mt} vs exact {me}: {relative:e}");
    let mut worst: f64 = 0.0;
    for k in 1..100 {
        let nu = NYQUIST * k as f64 / 100.0;
        worst = worst.max((pt.otf(nu) - pe.otf(nu)).abs());
    }
    assert!(worst < 2e-3, "pointwise {worst:e}");
    assert_eq!(pt.mtf(1.0 / (BAND.0 * F_NUMBER) * 1.01), 0.0);
}

/// At one wavelength (`monochromatic_mtf` and the line engine): on a table row only the
/// frequency interpolation is left (measured 2.6e-6 in focus at 800 nm, 3.6e-4 at 811 nm with
/// 1.1 waves of defocus), between rows the wavelength's too (measured 5.9e-3 halfway between
/// rows at 800.5 nm).
#[test]
fn a_table_at_one_wavelength_matches_the_exact_otf() {
    let tabulated = Chromatic { table: Some(Arc::new(chromatic_table())), annulus: None };
    let frequencies: Vec<f64> = (0..60).map(|k| NYQUIST * 3.0 * k as f64 / 59.0).collect();
    for (lambda, tolerance) in [(800e-9, 1e-5), (811e-9, 1e-3), (800.5e-9, 1e-2)] {
        let got = optics::monochromatic_mtf(&tabulated, lambda, Field::ON_AXIS, &frequencies, 64).unwrap();
        let spectrum = Spectrum::Line(Line::new(lambda, 1e-9, 1.0).unwrap());
        let line = Polychromatic::new(&tabulated, &spectrum, Field::ON_AXIS, 3.0 * NYQUIST, None).unwrap();
        assert_eq!(line.engine(), Engine::Monochromatic { fft: None });
        for (&nu, &m) in frequencies.iter().zip(&got) {
            let s = nu * lambda * F_NUMBER;
            let exact = defocus_otf(s, w020(lambda) / lambda).abs();
            assert!((m - exact).abs() < tolerance, "λ = {lambda:e}, ν = {nu:e}: {m} vs {exact}");
            assert!((line.mtf(nu) - m).abs() < 1e-14, "λ = {lambda:e}, ν = {nu:e}");
        }
    }
}

/// Beside an order that needs the FFT layer, the tabulated order is read at each node's ν: the
/// lens with the table against the same lens with the exact order, both on the FFT layer (the
/// annulus order's grids are the same), along two azimuths.
#[test]
fn a_table_beside_a_sampled_pupil_is_read_on_the_fft_layer() {
    let spectrum = band();
    let annulus = Arc::new(Aperture::annulus(0.4).unwrap());
    let exact = Chromatic { table: None, annulus: Some(annulus.clone()) };
    let tabulated = Chromatic { table: Some(Arc::new(chromatic_table())), annulus: Some(annulus) };
    let settings = optics::Settings { pupil_samples: Some(64), ..optics::Settings::default() };
    let pe = Polychromatic::with_settings(&exact, &spectrum, Field::ON_AXIS, NYQUIST, None, settings).unwrap();
    let pt = Polychromatic::with_settings(&tabulated, &spectrum, Field::ON_AXIS, NYQUIST, None, settings).unwrap();
    assert!(matches!(pt.engine(), Engine::Fft { .. }), "{:?}", pt.engine());
    for azimuth in [0.0, 1.0] {
        let (me, _) = pe.mean_mtf_along(azimuth);
        let (mt, _) = pt.mean_mtf_along(azimuth);
        // the tabulated order against the exact order's FFT grid: the table's error and the
        // FFT path's (4e-4 at N = 64, tests/optics/fft.rs); measured 1.6e-4 and 2.7e-4
        assert!((mt - me).abs() < 5e-4, "azimuth {azimuth}: table {mt} vs exact {me}");
    }
}

/// A table with different tangential and sagittal curves, off axis with the field along +y:
/// the tangential curve is read along the field direction (azimuth π/2 on the detector), the
/// sagittal one across it (docs/physics.md, "Off-axis MTFs: tangential and sagittal").
#[test]
fn tangential_and_sagittal_curves_follow_the_field_direction() {
    let wavelengths = vec![700e-9, 900e-9];
    let frequencies = vec![0.0, 1e5, 2e5];
    let t = vec![vec![1.0, 0.5, 0.2]; 2];
    let s = vec![vec![1.0, 0.8, 0.6]; 2];
    let table = Arc::new(OtfTable::new(wavelengths, frequencies, t, Some(s)).unwrap());
    let lens = Chromatic { table: Some(table), annulus: None };
    let spectrum = Spectrum::Line(Line::new(800e-9, 1e-9, 1.0).unwrap());
    let field = Field::new(0.0, 0.1);
    let poly = Polychromatic::new(&lens, &spectrum, field, 2e5, None).unwrap();
    assert!(poly.direction_dependent());
    assert!((poly.mtf_along(1e5, 0.5 * PI) - 0.5).abs() < 1e-14);
    assert!((poly.mtf_along(1e5, 0.0) - 0.8).abs() < 1e-14);
    assert!((poly.mtf_along(1e5, 0.25 * PI) - 0.65).abs() < 1e-14);
    // along +x (the sagittal direction here) for the mean and monochromatic_mtf
    let (mean, _) = poly.mean_mtf();
    let (sagittal, _) = poly.mean_mtf_along(0.0);
    assert_eq!(mean, sagittal);
    assert!((sagittal - 0.8).abs() < 1e-6, "{sagittal}");
    let mono = optics::monochromatic_mtf(&lens, 800e-9, field, &[1e5], 64).unwrap();
    assert!((mono[0] - 0.8).abs() < 1e-14, "{mono:?}");
    // on axis the field direction is +x: tangential along x
    let mono = optics::monochromatic_mtf(&lens, 800e-9, Field::ON_AXIS, &[1e5], 64).unwrap();
    assert!((mono[0] - 0.5).abs() < 1e-14, "{mono:?}");
}
