//! Example scene files that no other test loads.

use std::path::Path;

use radiometry::Spectrum;

// no code: its dependency features let this build share the test build's (workspace-hack/Cargo.toml)
use workspace_hack as _;

/// `examples/spectrometer.toml` loads: the paper's lens behind the generated spectrometer table
/// (`cargo xtask data`), every one of its 1601 samples read (0.25 nm over 600–1000 nm). Not
/// evaluated here: the per-interval spectral rule takes seconds on 1600 intervals in a debug
/// build; the accuracy report (`cargo xtask accuracy`) evaluates it in release.
#[test]
fn the_spectrometer_scene_loads() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/spectrometer.toml");
    let scene = scene::load(Some(&path), &[]).unwrap();
    assert_eq!(scene.lens().f_number(), 2.5);
    assert_eq!(scene.lens().focal_length(), 3.36e-3);
    assert!((scene.camera().pixel_pitch() - 5.2e-6).abs() < 1e-18);
    let Spectrum::Product(factors) = scene.radiance() else { panic!("{:?}", scene.radiance()) };
    let tables: Vec<_> = factors
        .iter()
        .filter_map(|f| match f {
            Spectrum::Sampled(t) => Some(t),
            _ => None,
        })
        .collect();
    assert_eq!(tables.len(), 1, "{factors:?}");
    let (wavelengths, values) = (tables[0].wavelengths(), tables[0].values());
    assert_eq!(wavelengths.len(), 1601);
    assert!((wavelengths[0] - 600e-9).abs() < 1e-18 && (wavelengths[1600] - 1000e-9).abs() < 1e-18);
    // the band: peak ~0.9 near 825 nm, the 0.2 % floor with ±0.1 % noise far from it
    let peak = values.iter().copied().fold(0.0, f64::max);
    assert!((0.899..=0.902).contains(&peak), "{peak}");
    assert!(values[..200].iter().all(|&v| (0.001..=0.003).contains(&v)));
}
