//! The tabulated lens against the chromatic lens whose exact OTF it tabulates, directly, through
//! a generated Zemax FFT MTF listing (UTF-16 LE with BOM, Latin-1) and with a pixel MTF inside.

use std::fmt::Write;
use std::sync::Arc;

use lenses::{ChromaticMetalens, Curve, FieldChoice, Tabulated, parse_zemax_fft_mtf, zemax_otf_table};
use metric::{Camera, Options, Scene, evaluate};
use optics::OtfTable;
use optics::testkit::check_lens;
use radiometry::{Gaussian, Spectrum};

use crate::{F_NUMBER, F0, LAMBDA0, band, mean_mtf};

/// The paper's chromatic lens's exact OTF at `wavelength` and `nu` (cycles/m):
/// `defocus_otf(ν λ F#, W020(λ)/λ)`, zero beyond the cutoff.
fn exact_otf(wavelength: f64, nu: f64) -> f64 {
    let s = nu * wavelength * F_NUMBER;
    if s >= 1.0 {
        return 0.0;
    }
    let w020 = (1.0 - wavelength / LAMBDA0) * F0 / (8.0 * F_NUMBER * F_NUMBER);
    optics::defocus_otf(s, w020 / wavelength)
}

fn chromatic() -> ChromaticMetalens {
    ChromaticMetalens::new(F_NUMBER, F0, LAMBDA0, Curve::Constant(0.15), Curve::Constant(0.55)).unwrap()
}

/// Wavelengths `lo..=hi` nm in steps of `step` nm (m), frequencies 0 to 520 cycles/mm (above
/// the cutoff of 770 nm at F/2.5) in steps of `dnu` cycles/mm (cycles/m).
fn grid(lo: f64, hi: f64, step: f64, dnu: f64) -> (Vec<f64>, Vec<f64>) {
    let n = ((hi - lo) / step).round() as usize;
    let waves = (0..=n).map(|i| (lo + step * i as f64) * 1e-9).collect();
    let m = (520.0 / dnu).round() as usize;
    let freqs = (0..=m).map(|k| dnu * k as f64 * 1e3).collect();
    (waves, freqs)
}

fn table_of(waves: &[f64], freqs: &[f64], factor: &dyn Fn(f64) -> f64) -> OtfTable {
    let rows: Vec<Vec<f64>> =
        waves.iter().map(|&l| freqs.iter().map(|&nu| exact_otf(l, nu) * factor(nu)).collect()).collect();
    OtfTable::new(waves.to_vec(), freqs.to_vec(), rows, None).unwrap()
}

fn tabulated(table: OtfTable, pixel: Option<f64>) -> Tabulated {
    Tabulated::new(F_NUMBER, F0, table, Curve::Constant(0.15), Curve::Constant(0.55), pixel)
        .unwrap()
        .with_design_wavelength(LAMBDA0)
        .unwrap()
}

/// The mean MTF of a table by direct quadrature, independent of the engine: the detected
/// spectrum times the table summed over λ (Gauss–Legendre on 1 nm panels between the table's
/// rows, over ±25 nm ≈ ±7σ of a 10 nm band), its modulus averaged over `[0, nu_max]`
/// (Gauss–Legendre on 2 cycles/mm panels, the table's columns).
fn direct_mean_mtf(table: &OtfTable, detected: &Spectrum, nu_max: f64) -> f64 {
    let (lo, hi) = (775e-9, 825e-9);
    let norm = optics::quad::composite(lo, hi, 50, |l| detected.value(l));
    let otf = |nu: f64| optics::quad::composite(lo, hi, 50, |l| detected.value(l) * table.value(l, nu, 0.0)) / norm;
    let panels = (nu_max / 2e3).round() as usize;
    optics::quad::composite(0.0, nu_max, panels, |nu| otf(nu).abs()) / nu_max
}

/// A table of the chromatic lens's signed OTF at 1 nm × 2 cycles/mm: the engine's mean MTF over
/// 800 ± 10 nm up to 250 cycles/mm equals the direct quadrature of the table (1e-6), and both
/// are the chromatic lens's to the error of linear interpolation in λ (the OTF turns fast in
/// λ here, one wave of defocus per 10 nm: measured 2.2e-3 at 1 nm rows, 4.5e-3 at 2 nm).
#[test]
fn table_of_the_exact_otf_reproduces_the_chromatic_mean_mtf() {
    let (waves, freqs) = grid(770.0, 830.0, 1.0, 2.0);
    let table = table_of(&waves, &freqs, &|_| 1.0);
    let detected = band(800.0, 10.0);
    let direct = direct_mean_mtf(&table, &detected, 2.5e5);
    let lens = tabulated(table, None);
    let (got, want) = (mean_mtf(&lens, &detected, 2.5e5), mean_mtf(&chromatic(), &detected, 2.5e5));
    eprintln!("tabulated {got:.6} (direct {direct:.6}) vs chromatic {want:.6} ({:.1e})", (got - want).abs() / want);
    assert!((got - direct).abs() < 1e-6 * direct, "engine {got} vs direct {direct}");
    assert!((got - want).abs() < 3e-3 * want, "{got} vs {want}");
}

/// The Zemax FFT MTF listing of one wavelength, as OpticStudio writes it (module docs of
/// `lenses::parse_zemax_fft_mtf`): an on-axis field and a 5° field (the same curve here).
fn zemax_listing(wavelength: f64, freqs: &[f64]) -> String {
    let mut t = String::new();
    t.push_str("Listing of FFT MTF Data\r\n\r\nFile : C:\\Lenses\\chromatic metalens.zmx\r\n");
    t.push_str("Title: paper chromatic lens F/2.5\r\nDate : 12/1/2026\r\n\r\n");
    let _ = write!(t, "Data for {:.4} µm.\r\nSpatial Frequency units are cycles per mm.\r\n", wavelength * 1e6);
    for field in ["0.0000 (deg)", "5.0000 (deg)"] {
        let _ = write!(t, "\r\nField: {field}\r\n  Spatial frequency      Tangential        Sagittal\r\n");
        for &nu in freqs {
            let v = exact_otf(wavelength, nu).abs();
            let _ = write!(t, "{:>16.6}{:>16.6}{:>16.6}\r\n", nu * 1e-3, v, v);
        }
    }
    t
}

/// Listings at 770 to 830 nm (every 2 nm, 0.xxxx µm as Zemax prints) encoded as UTF-16 LE with
/// BOM and as Latin-1 parse back to the printed values and give the chromatic lens's mean MTF
/// over 800 ± 10 nm (where the OTF is positive below 250 cycles/mm, so the MTF table is the OTF).
#[test]
fn zemax_listings_round_trip_and_reproduce_the_mean_mtf() {
    let (waves, freqs) = grid(770.0, 830.0, 2.0, 2.0);
    let texts: Vec<String> = waves.iter().map(|&l| zemax_listing(l, &freqs)).collect();
    let utf16: Vec<Vec<u8>> = texts
        .iter()
        .map(|t| [0xFF, 0xFE].into_iter().chain(t.encode_utf16().flat_map(u16::to_le_bytes)).collect())
        .collect();
    let latin1: Vec<Vec<u8>> =
        texts.iter().map(|t| t.chars().map(|c| u8::try_from(c as u32).unwrap()).collect()).collect();
    let parse = |all: &[Vec<u8>]| all.iter().map(|b| parse_zemax_fft_mtf(b).unwrap()).collect::<Vec<_>>();
    let (a, b) = (parse(&utf16), parse(&latin1));
    assert_eq!(a, b);
    assert_eq!(a[5].wavelengths_m.len(), 1);
    assert!((a[5].wavelengths_m[0] - 780e-9).abs() < 1e-18);
    assert_eq!(a[5].fields.len(), 2);
    let table = zemax_otf_table(&a, FieldChoice::OnAxis).unwrap();
    for (i, &l) in waves.iter().enumerate().step_by(7) {
        for &nu in freqs.iter().step_by(13) {
            let printed = exact_otf(l, nu).abs();
            assert!((table.value(l, nu, 0.0) - printed).abs() <= 5e-7, "{i}: {l} {nu}");
        }
    }
    let lens = tabulated(table, None);
    let detected = band(800.0, 10.0);
    let (got, want) = (mean_mtf(&lens, &detected, 2.5e5), mean_mtf(&chromatic(), &detected, 2.5e5));
    eprintln!("from Zemax listings {got:.6} vs chromatic {want:.6} ({:.1e})", (got - want).abs() / want);
    // 2 nm rows of the modulus: 4.5e-3 measured (the interpolation in λ, docs above)
    assert!((got - want).abs() < 6e-3 * want, "{got} vs {want}");
}

fn scene(lens: Arc<dyn optics::LensModel>, pixel_mtf: bool) -> Scene {
    let filter = Gaussian::from_range(LAMBDA0, 10e-9, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(2e-6, Spectrum::Constant(0.2), pixel_mtf).unwrap();
    Scene::new(lens, radiance, camera, 1.23e-3, Options::default()).unwrap()
}

/// A measured MTF containing the 2 µm pixel's sinc: divided out (up to the pixel's Nyquist
/// frequency, 250 cycles/mm) it gives the chromatic lens's evaluation with the camera's pixel
/// MTF (800 ± 5 nm); kept, the metric would count the pixel MTF twice (measured: 0.5045
/// divided, 0.5056 chromatic, 0.4669 twice).
#[test]
fn a_contained_pixel_mtf_is_not_counted_twice() {
    let p = 2e-6;
    let (waves, freqs) = grid(770.0, 830.0, 1.0, 2.0);
    let measured = table_of(&waves, &freqs, &|nu| optics::pixel_mtf(p, nu));
    let divided = tabulated(measured.clone(), Some(p));
    assert_eq!(divided.pixel_mtf_division(), Some((p, 2.5e5)));
    assert_eq!(divided.table().max_frequency(), 2.5e5);
    let want = evaluate(&scene(Arc::new(chromatic()), true)).unwrap();
    let got = evaluate(&scene(Arc::new(divided), true)).unwrap();
    let twice = evaluate(&scene(Arc::new(tabulated(measured, None)), true)).unwrap();
    eprintln!(
        "pixel MTF divided out {:.6}, chromatic {:.6}, counted twice {:.6}",
        got.mean_mtf, want.mean_mtf, twice.mean_mtf
    );
    // the interpolation of 1 nm rows in λ, as above
    assert!((got.mean_mtf - want.mean_mtf).abs() < 3e-3 * want.mean_mtf, "{} vs {}", got.mean_mtf, want.mean_mtf);
    assert!((got.photoelectrons - want.photoelectrons).abs() < 1e-9 * want.photoelectrons);
    assert!(twice.mean_mtf < 0.97 * want.mean_mtf);
}

/// The conformance checks on a coarse table (5 nm × 10 cycles/mm).
#[test]
fn tabulated_lens_conforms() {
    let (waves, freqs) = grid(770.0, 830.0, 5.0, 10.0);
    let lens = tabulated(table_of(&waves, &freqs, &|_| 1.0), None);
    check_lens(&lens, &band(800.0, 10.0)).unwrap();
}
