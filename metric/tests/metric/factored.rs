//! Efficiency and transmission tables folded into the detected spectrum's exact moments
//! (`optics::FactoredEfficiency`, `optics::Polychromatic::with_parts`) against the node-based
//! path, in which every table row cuts a spectral panel: the same lens behind a wrapper that
//! forwards everything but the factoring.

use std::sync::Arc;

use lenses::{
    Channel, ChromaticMetalens, Curve, DelayOverflow, DispersionEngineered, Harmonic, Interleaved, Layout,
    OtherChannels, Segmented,
};
use metric::{Camera, Evaluation, Options, Scene, evaluate};
use optics::{Field, LensModel};
use radiometry::{Gaussian, Sampled, Spectrum};

use super::{F0, LAMBDA0};

/// A lens that keeps its tables in its orders: every method forwarded but
/// `factored_efficiency` (the default, `None`), so the optics take the node-based path, a
/// spectral panel cut at every table row.
#[derive(Debug)]
struct Unfactored(Arc<dyn LensModel>);

impl LensModel for Unfactored {
    fn f_number(&self) -> f64 {
        self.0.f_number()
    }
    fn focal_length(&self) -> f64 {
        self.0.focal_length()
    }
    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<optics::Order> {
        self.0.orders(wavelength_m, field)
    }
    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.0.efficiency(wavelength_m)
    }
    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.0.transmission(wavelength_m)
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.0.breakpoints()
    }
    fn design_wavelength(&self) -> Option<f64> {
        self.0.design_wavelength()
    }
}

/// `n` rows of `f` evenly over `[lo, hi]`.
fn table(n: usize, lo: f64, hi: f64, f: &dyn Fn(f64) -> f64) -> Sampled {
    let wavelengths: Vec<f64> = (0..n).map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64).collect();
    let values = wavelengths.iter().map(|&l| f(l)).collect();
    Sampled::new(wavelengths, values).unwrap()
}

/// An efficiency table of `n` rows over 690–910 nm around `mean`: a ripple of `period` and a saw
/// of one row's spacing (a kink at every row).
fn rippled(n: usize, mean: f64, period: f64) -> Curve {
    let step = 220e-9 / (n - 1) as f64;
    Curve::Table(table(n, 690e-9, 910e-9, &|l: f64| {
        mean * (1.0 + 0.12 * (l / period).sin() + 0.03 * ((l / step).round() % 2.0))
    }))
}

/// The paper's source and camera with a 41-row QE table, a Gaussian filter of `range_m` at
/// 800 nm, `lens` at `field`, evaluated at `tolerance` (a composite pupil at 96 samples across
/// it, so that both runs sample the same pupils).
fn evaluation(lens: Arc<dyn LensModel>, range_m: f64, field: Field, tolerance: f64) -> Evaluation {
    let qe = table(41, 680e-9, 920e-9, &|l: f64| 0.25 - 0.3 * (l - 800e-9) / 200e-9);
    let filter = Gaussian::from_range(LAMBDA0, range_m, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(5.2e-6, Spectrum::Sampled(qe), false).unwrap();
    let options = Options { tolerance, pupil_samples: Some(96), fft_tolerance: None, ..Options::default() };
    let scene = Scene::new(lens, radiance, camera, 1.23e-3, options).unwrap();
    let scene = scene.at_field(field).unwrap();
    evaluate(&scene).unwrap()
}

/// The folded and the node-based evaluation of `lens` agree within `within` (relative) on the
/// ASNR, the mean MTF, the photoelectrons, the transmitted photoelectrons and the glare; the
/// folded one's spectral nodes are returned beside the node-based one's.
fn agree(
    name: &str,
    lens: Arc<dyn LensModel>,
    range_m: f64,
    field: Field,
    tolerance: f64,
    within: f64,
) -> (usize, usize) {
    let parts = lens.factored_efficiency().map_or(0, |f| f.parts.len());
    assert!(parts > 0, "{name}: no factoring");
    let folded = evaluation(lens.clone(), range_m, field, tolerance);
    let nodes = evaluation(Arc::new(Unfactored(lens)), range_m, field, tolerance);
    // the fold is what ran, and the report says so
    assert_eq!((folded.numerics.factored_parts, nodes.numerics.factored_parts), (parts, 0), "{name}");
    let pairs = [
        ("asnr", folded.asnr, nodes.asnr),
        ("mean_mtf", folded.mean_mtf, nodes.mean_mtf),
        ("photoelectrons", folded.photoelectrons, nodes.photoelectrons),
        ("transmitted_photoelectrons", folded.transmitted_photoelectrons, nodes.transmitted_photoelectrons),
        ("glare.efficiency", folded.glare.efficiency, nodes.glare.efficiency),
        ("glare.transmission", folded.glare.transmission, nodes.glare.transmission),
        ("glare.vg", folded.glare.vg, nodes.glare.vg),
    ];
    for (quantity, f, n) in pairs {
        assert!((f - n).abs() <= within * n.abs(), "{name} {quantity}: folded {f} vs node-based {n}");
    }
    // (the numbers of the closing notes: `cargo test -p asnr-metric --test metric factored -- --nocapture`)
    eprintln!(
        "{name}: ASNR folded {} vs node-based {} ({:.1e} relative); spectral nodes {} vs {}",
        folded.asnr,
        nodes.asnr,
        (folded.asnr - nodes.asnr) / nodes.asnr,
        folded.numerics.spectral_nodes,
        nodes.numerics.spectral_nodes
    );
    (folded.numerics.spectral_nodes, nodes.numerics.spectral_nodes)
}

/// A chromatic lens's τ1 table (61 rows, a kink at every row) and T table (29 rows) folded: the
/// node-based path's numbers within 1e-6 at the default tolerance (1e-6), with fewer spectral
/// nodes (the rows no longer cut the rule's panels).
#[test]
fn an_efficiency_table_folded_into_the_moments_matches_the_node_based_path() {
    let efficiency = Curve::Table(table(61, 730e-9, 870e-9, &|l: f64| {
        0.14 + 0.02 * (l / 9e-9).sin() + 0.004 * ((l / 2.3e-9).round() % 2.0)
    }));
    let transmission = Curve::Table(table(29, 720e-9, 880e-9, &|l: f64| 0.5 + 0.05 * ((l - 800e-9) / 80e-9)));
    let lens = ChromaticMetalens::new(2.5, F0, LAMBDA0, efficiency, transmission).unwrap();
    let (folded, nodes) = agree("chromatic", Arc::new(lens), 50e-9, Field::ON_AXIS, 1e-6, 1e-6);
    assert!(folded < nodes, "{folded} vs {nodes}");
}

/// Every order's table folded: a three-channel interleaved lens whose channels carry different
/// 111-row efficiency tables (one part per channel) and a T table, on axis (the per-frequency
/// engine) and at 5° (lateral colour: the exact nodes summed as complex OTFs), each within 1e-9
/// of the node-based path at tolerance 1e-10.
#[test]
fn every_channel_table_of_an_interleaved_lens_is_folded() {
    let channels = [(760e-9, 0.7, 7e-9), (800e-9, 0.8, 11e-9), (840e-9, 0.75, 5e-9)]
        .iter()
        .map(|&(wavelength_m, mean, period)| Channel { wavelength_m, efficiency: rippled(111, mean, period) })
        .collect();
    let transmission = Curve::Table(table(23, 690e-9, 910e-9, &|l: f64| 0.9 - 0.1 * ((l - 800e-9) / 110e-9).powi(2)));
    let lens: Arc<dyn LensModel> = Arc::new(Interleaved::new(2.5, F0, channels, transmission).unwrap());
    assert_eq!(lens.factored_efficiency().map(|f| f.parts.len()), Some(3));
    let (folded, nodes) = agree("interleaved", lens.clone(), 100e-9, Field::ON_AXIS, 1e-10, 1e-9);
    assert!(folded < nodes, "{folded} vs {nodes}");
    let field = Field::new(5f64.to_radians(), 0.0);
    agree("interleaved at 5°", lens, 100e-9, field, 1e-10, 1e-9);
}

/// A harmonic lens (p = 5, several orders a wavelength) whose transmission is a 61-row table:
/// the table leaves the spectral panels (one part, the orders' sinc² efficiencies smooth), the
/// transmitted photoelectrons exact from the spectra; within 1e-9 at tolerance 1e-10.
#[test]
fn a_harmonic_lens_transmission_table_is_folded() {
    let transmission = Curve::Table(table(61, 690e-9, 910e-9, &|l: f64| 0.6 + 0.02 * (l / 3e-9).sin()));
    let lens: Arc<dyn LensModel> = Arc::new(Harmonic::new(2.5, F0, LAMBDA0, 5, 0.4, transmission).unwrap());
    let (folded, nodes) = agree("harmonic", lens, 20e-9, Field::ON_AXIS, 1e-10, 1e-9);
    assert!(folded < nodes, "{folded} vs {nodes}");
}

/// A dispersion-engineered achromat with a 111-row efficiency table (the generic one-curve
/// factoring): within 1e-9 at tolerance 1e-10.
#[test]
fn a_dispersion_engineered_efficiency_table_is_folded() {
    let lens = DispersionEngineered::new(
        2.5,
        F0,
        (700e-9, 900e-9),
        1e-12,
        rippled(111, 0.3, 9e-9),
        Curve::Constant(0.6),
        DelayOverflow::Reduced,
    )
    .unwrap();
    agree("dispersion-engineered", Arc::new(lens), 100e-9, Field::ON_AXIS, 1e-10, 1e-9);
}

/// Segmented lenses (a composite pupil of zones, the FFT path): with every channel on one
/// 111-row table (one part: the table scales each zone's field by its square root), and with
/// other channels as background and a table per channel (one part per zone, only that zone lit
/// in its band). Both runs sample the same pupils (96 samples across); within 1e-6 at the
/// tolerance 1e-6.
#[test]
fn segmented_lens_tables_are_folded_where_they_factor() {
    let waves = [790e-9, 800e-9, 810e-9];
    let common = rippled(111, 0.6, 9e-9);
    let channels = waves.iter().map(|&wavelength_m| Channel { wavelength_m, efficiency: common.clone() }).collect();
    let lens = Segmented::new(2.5, F0, channels, Layout::Concentric, None, Curve::Constant(0.9)).unwrap();
    assert_eq!(lens.factored_efficiency().map(|f| f.parts.len()), Some(1));
    agree("segmented, one table", Arc::new(lens), 20e-9, Field::ON_AXIS, 1e-6, 1e-6);

    let channels = waves
        .iter()
        .zip([(0.6, 7e-9), (0.7, 11e-9), (0.65, 5e-9)])
        .map(|(&wavelength_m, (mean, period))| Channel { wavelength_m, efficiency: rippled(111, mean, period) })
        .collect::<Vec<_>>();
    let signal = Segmented::new(2.5, F0, channels, Layout::Concentric, None, Curve::Constant(0.9)).unwrap();
    // all signal: the coherent sum mixes the tables as √(η_j η_k), which does not factor
    assert!(signal.factored_efficiency().is_none());
    let background = signal.with_other_channels(OtherChannels::Background);
    assert_eq!(background.factored_efficiency().map(|f| f.parts.len()), Some(3));
    agree("segmented, background, a table per zone", Arc::new(background), 20e-9, Field::ON_AXIS, 1e-6, 1e-6);
}

/// The node-based path of a harmonic lens whose transmission table has rows 0.1 nm apart: the
/// search for where its window of orders changes, run in every row's interval, stops at
/// adjacent doubles (to 1e-13 of a 0.1 nm interval is below the spacing of doubles near 800 nm,
/// and the bisection looped for ever where an order enters, at 800 nm here); the evaluation
/// ends, with a result or the work budget's refusal.
#[test]
fn narrow_table_rows_do_not_hang_the_search_for_order_changes() {
    let transmission = Curve::Table(table(2001, 700e-9, 900e-9, &|l: f64| 0.6 + 0.02 * (l / 3e-9).sin()));
    let lens: Arc<dyn LensModel> = Arc::new(Harmonic::new(2.5, F0, LAMBDA0, 5, 0.4, transmission).unwrap());
    let qe = Spectrum::Constant(0.2);
    let filter = Gaussian::from_range(LAMBDA0, 20e-9, 1.0).unwrap();
    let radiance = Spectrum::product(vec![Spectrum::Constant(0.025e9), Spectrum::Gaussian(filter)]);
    let camera = Camera::new(5.2e-6, qe, false).unwrap();
    let scene = Scene::new(Arc::new(Unfactored(lens)), radiance, camera, 1.23e-3, Options::default()).unwrap();
    match evaluate(&scene) {
        Ok(e) => assert!(e.mean_mtf > 0.0 && e.mean_mtf < 1.0, "{}", e.mean_mtf),
        Err(e) => assert!(e.to_string().contains("beyond the 5 s budget"), "{e}"),
    }
}
