//! The library lens laid out in 2-D (`lens.layout_gds`, `lens.layout_grid`; docs/physics.md,
//! "2-D library layouts") against the radial library lens of the same layout.
//!
//! The layout follows `examples/library.toml`'s: the example's library
//! (`examples/data/library-tio2-like.csv`), rings of 400 nm, each the diameter whose field at
//! 800 nm is nearest the hyperbolic phase at the ring's centre (the rule of `cargo xtask data`),
//! on a small lens of the same F-number (F/2.5, f0 = 125 µm, R = 25 µm: the OTF depends on
//! `ν λ F#` only, and a 127 × 127 lattice keeps the test fast). The 2-D layout draws at each
//! lattice site the atom of the ring its centre falls in; the GDS is written here by the project's
//! writer (`scene::gds::Writer`: 9-vertex polygons as DFlat writes them, on a 1 nm grid).

use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};

use optics::Field;

const F0_NM: f64 = 125e3;
const RADIUS_NM: f64 = 25e3;
const PITCH_NM: f64 = 400.0;

fn library_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/data/library-tio2-like.csv")
}

/// The library's (diameter, field at 800 nm) rows.
fn library_at_800() -> Vec<(f64, f64, f64)> {
    let text = std::fs::read_to_string(library_path()).unwrap();
    let mut rows = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#') && !l.starts_with("diameter")) {
        let v: Vec<f64> = line.split(',').map(|s| s.trim().parse().unwrap()).collect();
        if v[1] == 800.0 {
            rows.push((v[0], v[2] * v[3].cos(), v[2] * v[3].sin()));
        }
    }
    rows
}

/// Ring `i`'s diameter: the library's field nearest the hyperbolic phase at `(i + ½) p`.
fn rings() -> Vec<f64> {
    let fields = library_at_800();
    let n = (RADIUS_NM / PITCH_NM).round() as usize + 1;
    (0..n)
        .map(|i| {
            let r = (i as f64 + 0.5) * PITCH_NM;
            let target = -TAU / 800.0 * ((r * r + F0_NM * F0_NM).sqrt() - F0_NM);
            let (tx, ty) = (target.cos(), target.sin());
            fields
                .iter()
                .min_by(|a, b| {
                    ((a.1 - tx).powi(2) + (a.2 - ty).powi(2)).total_cmp(&((b.1 - tx).powi(2) + (b.2 - ty).powi(2)))
                })
                .unwrap()
                .0
        })
        .collect()
}

/// Sites per side (odd: a site on the axis) and the diameter at site `(i, j)` (`None` outside the
/// drawn disc, one pitch beyond the aperture).
fn sites() -> (usize, impl Fn(usize, usize) -> Option<f64>) {
    let rings = rings();
    let half = (RADIUS_NM / PITCH_NM).ceil() as usize + 1;
    let n = 2 * half + 1;
    let at = move |i: usize, j: usize| {
        let (x, y) = ((i as f64 - half as f64) * PITCH_NM, (j as f64 - half as f64) * PITCH_NM);
        let r = x.hypot(y);
        (r <= RADIUS_NM + PITCH_NM).then(|| rings[((r / PITCH_NM) as usize).min(rings.len() - 1)])
    };
    (n, at)
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("asnr-layout2d-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The GDS of the layout: one cell, 9-vertex pillars on layer 1 (vertices on the circle, 1 nm).
fn write_gds(path: &Path, diameter: impl Fn(usize, usize) -> Option<f64>, n: usize) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = scene::gds::Writer::new(file, 1e-9).unwrap();
    w.begin_cell("LENS").unwrap();
    let half = (n / 2) as f64;
    for j in 0..n {
        for i in 0..n {
            let Some(d) = diameter(i, j) else { continue };
            let (cx, cy) = ((i as f64 - half) * PITCH_NM, (j as f64 - half) * PITCH_NM);
            let points: Vec<(i32, i32)> = (0..9)
                .map(|k| {
                    let a = TAU * k as f64 / 9.0;
                    ((cx + 0.5 * d * a.cos()).round() as i32, (cy + 0.5 * d * a.sin()).round() as i32)
                })
                .collect();
            w.polygon(1, 0, &points).unwrap();
        }
    }
    w.end_cell().unwrap();
    w.finish().unwrap();
}

/// A `.npy` float64 `[n, n]` of `value(i, j)` (NaN for no atom).
fn write_npy(path: &Path, n: usize, value: impl Fn(usize, usize) -> f64) {
    let grid: Vec<f64> = (0..n * n).map(|k| value(k % n, k / n)).collect();
    std::fs::write(path, scene::npy::npy_f64(&[n, n], &grid).unwrap()).unwrap();
}

/// A scene of the small lens with `lens_keys` (the library given).
fn scene_text(lens_keys: &str) -> String {
    format!(
        r#"
[lens]
model = "library"
f_number = 2.5
focal_length_mm = {f0}
design_wavelength_nm = 800.0
library = "{library}"
{lens_keys}

[source]
kind = "flat"
radiance_w_m2_sr_nm = 0.025

[spectrum]
shape = "gaussian"
center_nm = 800.0
range_nm = 50.0
peak = 1.0

[camera]
pixel_pitch_um = 5.2
pixel_mtf = false
quantum_efficiency = 0.2

[exposure]
time_ms = 1.23

[options]
pupil_samples = 256
"#,
        f0 = F0_NM * 1e-6,
        library = library_path().display()
    )
}

fn load(dir: &Path, lens_keys: &str) -> Result<metric::Scene, String> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene_text(lens_keys)).unwrap();
    scene::load(Some(&path), &[]).map_err(|e| e.to_string())
}

fn tau1(scene: &metric::Scene) -> f64 {
    scene.lens().orders(800e-9, Field::ON_AXIS).iter().map(|o| o.efficiency).sum()
}

/// The stated lattice error: twice `1 − S_min`, the cells' design-order amplitude
/// `sinc(g_x p/λ) sinc(g_y p/λ)` at the aperture's edge on the diagonal at the band's short end
/// (docs/physics.md, "2-D library layouts").
fn lattice_bound() -> f64 {
    let sinc = |u: f64| (PI * u).sin() / (PI * u);
    let c = RADIUS_NM / 2f64.sqrt();
    let g = c / (RADIUS_NM * RADIUS_NM + F0_NM * F0_NM).sqrt();
    let u = PITCH_NM / 775.0 * g;
    2.0 * (1.0 - sinc(u) * sinc(u))
}

/// The rings' diameters as the radial layout's CSV (`r_mm, diameter_nm`, ring i at (i + ½) p).
fn write_radial_layout(path: &std::path::Path, rings: &[f64]) {
    let mut csv = String::from("r_mm,diameter_nm\n");
    for (i, dia) in rings.iter().enumerate() {
        csv.push_str(&format!("{:.7},{dia:.1}\n", (i as f64 + 0.5) * PITCH_NM * 1e-6));
    }
    std::fs::write(path, csv).unwrap();
}

/// The radial layout drawn in 2-D, read from a GDS written here and from a `.npy` grid, gives the
/// radial library lens's τ1 and mean MTF within the stated lattice error.
#[test]
fn a_gds_and_a_grid_of_the_radial_layout_reproduce_the_radial_library_lens() {
    let d = dir("same");
    let rings = rings();
    write_radial_layout(&d.join("layout.csv"), &rings);
    let (n, at) = sites();
    write_gds(&d.join("lens.gds"), &at, n);
    write_npy(&d.join("lens.npy"), n, |i, j| at(i, j).unwrap_or(f64::NAN));
    let radial = load(&d, "layout = \"layout.csv\"").unwrap();
    let gds = load(&d, "layout_gds = \"lens.gds\"\ngds_layer = 1\nlattice_pitch_um = 0.4").unwrap();
    let grid = load(&d, "layout_grid = \"lens.npy\"\nlattice_pitch_um = 0.4").unwrap();
    let bound = lattice_bound();
    let e_radial = metric::evaluate(&radial).unwrap();
    let (t_radial, t_gds, t_grid) = (tau1(&radial), tau1(&gds), tau1(&grid));
    println!("stated lattice error 2(1 − S_min) = {bound:.4}");
    println!("radial: τ1 = {t_radial:.5}, mean MTF = {:.5}, ASNR = {:.4}", e_radial.mean_mtf, e_radial.asnr);
    for (name, s, t) in [("GDS", &gds, t_gds), ("grid", &grid, t_grid)] {
        let e = metric::evaluate(s).unwrap();
        let dm = e.mean_mtf - e_radial.mean_mtf;
        println!(
            "{name}: τ1 = {t:.5} ({:+.2e} relative), mean MTF = {:.5} ({dm:+.2e}), ASNR = {:.4} ({:+.2e} relative)",
            t / t_radial - 1.0,
            e.mean_mtf,
            e.asnr,
            e.asnr / e_radial.asnr - 1.0
        );
        assert!(dm.abs() <= bound, "{name}: mean MTF {} vs radial {}: beyond {bound}", e.mean_mtf, e_radial.mean_mtf);
        assert!((t / t_radial - 1.0).abs() <= bound, "{name}: τ1 {t} vs radial {t_radial}: beyond {bound}");
    }
    // the GDS's 9-vertex polygons on a 1 nm grid give the grid's diameters to within the drawing
    assert!((t_gds / t_grid - 1.0).abs() < 2e-3, "GDS τ1 {t_gds} vs grid {t_grid}");
    std::fs::remove_dir_all(&d).ok();
}

/// Atoms outside the library's range (100–300 nm) are refused with their count and the worst.
#[test]
fn atoms_outside_the_library_are_refused_with_count_and_worst() {
    let d = dir("range");
    let (n, at) = sites();
    let c = n / 2;
    write_npy(&d.join("lens.npy"), n, |i, j| match (i, j) {
        (i, j) if i == c && j == c => 350.0,
        (i, j) if i == c + 1 && j == c => 320.0,
        (i, j) if i == c + 2 && j == c => 80.0,
        _ => at(i, j).unwrap_or(f64::NAN),
    });
    let e = load(&d, "layout_grid = \"lens.npy\"\nlattice_pitch_um = 0.4").unwrap_err();
    assert!(e.contains("lens.layout_grid") && e.contains("3 atoms outside the library's range"), "{e}");
    assert!(e.contains("diameter_nm = 350") && e.contains("[100, 300]"), "{e}");
    std::fs::remove_dir_all(&d).ok();
}

/// A GDS layer without atoms is refused naming the layer; empty sites in the aperture need
/// `empty_cell`, and with it are bare substrate.
#[test]
fn a_layer_without_atoms_and_empty_sites_are_refused() {
    let d = dir("layer");
    let (n, at) = sites();
    write_gds(&d.join("lens.gds"), &at, n);
    let e = load(&d, "layout_gds = \"lens.gds\"\ngds_layer = 2\nlattice_pitch_um = 0.4").unwrap_err();
    assert!(e.contains("lens.layout_gds") && e.contains("no atoms on layer 2"), "{e}");
    // a hole of 3 × 3 sites at the centre
    let c = n / 2;
    let holed = |i: usize, j: usize| if i.abs_diff(c) <= 1 && j.abs_diff(c) <= 1 { None } else { at(i, j) };
    write_gds(&d.join("holed.gds"), holed, n);
    let keys = "layout_gds = \"holed.gds\"\ngds_layer = 1\nlattice_pitch_um = 0.4";
    let e = load(&d, keys).unwrap_err();
    assert!(e.contains("lens.empty_cell") && e.contains("9 lattice sites inside the aperture have no atom"), "{e}");
    let full = tau1(&load(&d, "layout_gds = \"lens.gds\"\ngds_layer = 1\nlattice_pitch_um = 0.4").unwrap());
    let substrate = tau1(&load(&d, &format!("{keys}\nempty_cell = \"substrate\"")).unwrap());
    let dark = tau1(&load(&d, &format!("{keys}\nempty_cell = [0.0, 0.0]")).unwrap());
    println!("τ1: full {full:.5}, hole of substrate {substrate:.5}, dark hole {dark:.5}");
    assert!(dark < full && substrate != dark, "{full} {substrate} {dark}");
    std::fs::remove_dir_all(&d).ok();
}

/// [`load`] with 128 pupil samples (0.39 µm, a lattice pitch: the 2-D pupil's cells resolved),
/// to keep the many evaluations of the fabrication test fast.
fn load_128(dir: &Path, lens_keys: &str) -> Result<metric::Scene, String> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene_text(lens_keys).replace("pupil_samples = 256", "pupil_samples = 128")).unwrap();
    scene::load(Some(&path), &[]).map_err(|e| e.to_string())
}

/// Mean MTF and τ1 of a scene (τ1 at 800 nm, on axis).
fn mtf_and_tau(scene: &metric::Scene) -> (f64, f64) {
    (metric::evaluate(scene).unwrap().mean_mtf, tau1(scene))
}

/// The fabrication-error keys on the 2-D layout give the radial lens's τ1 and mean MTF within the
/// stated lattice error, each error on its own: a parameter bias, the atoms' random phase and
/// amplitude errors (the 2-D lens takes their expectation; the radial lens draws one error a
/// ring, so it is averaged over 4 seeds; its few rings a zone add `(e^{σ²} − 1)/N` of
/// incoherent power, docs/physics.md); and a bias past the library's range and a seed refused.
/// The Zernike terms are [`fabrication_wavefront_errors_on_a_2d_layout_follow_the_radial_lens`]
/// (a test of their own, so the two share the test threads).
#[test]
fn fabrication_errors_on_a_2d_layout_follow_the_radial_lens() {
    let d = dir("fabrication");
    let (rings, bound, nominal) = fabrication_layout(&d);
    // a bias of 6 nm that keeps every ring inside the library's 100–300 nm
    let (lo, hi) = rings.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let bias = if hi + 6.0 <= 300.0 { 6.0 } else { -6.0 };
    assert!(lo + bias >= 100.0 && hi + bias <= 300.0, "rings {lo}–{hi}");
    let cases: [(&str, String, usize); 3] = [
        ("bias", format!("parameter_bias = [{bias}]"), 1),
        ("phase σ 0.3 rad", "atom_phase_error_rad = 0.3".into(), 4),
        ("amplitude σ 0.2", "atom_transmission_error = 0.2".into(), 4),
    ];
    for (name, keys, seeds) in cases {
        fabrication_error_follows_the_radial_lens(&d, bound, nominal, name, &keys, seeds);
    }
    // a bias past the library's range is refused naming the key and the atoms; a seed has no draws
    let e = load(&d, "layout_grid = \"lens.npy\"\nlattice_pitch_um = 0.4\nparameter_bias = [150]").unwrap_err();
    assert!(e.contains("lens.parameter_bias") && e.contains("outside the library's range"), "{e}");
    let e = load(&d, "layout_grid = \"lens.npy\"\nlattice_pitch_um = 0.4\natom_error_seed = 3").unwrap_err();
    assert!(e.contains("lens.atom_error_seed") && e.contains("expectation"), "{e}");
    std::fs::remove_dir_all(&d).ok();
}

/// Zernike terms on the 2-D layout (a symmetric Z11 and a coma Z7) give the radial lens's τ1
/// and mean MTF within the stated lattice error, as
/// [`fabrication_errors_on_a_2d_layout_follow_the_radial_lens`].
#[test]
fn fabrication_wavefront_errors_on_a_2d_layout_follow_the_radial_lens() {
    let d = dir("fabrication-wavefront");
    let (_, bound, nominal) = fabrication_layout(&d);
    let cases: [(&str, &str); 2] = [
        ("Z11 0.05 µm", "zernike_noll_rms_um = [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.05]"),
        ("Z7 0.05 µm", "zernike_noll_rms_um = [0, 0, 0, 0, 0, 0, 0.05]"),
    ];
    for (name, keys) in cases {
        fabrication_error_follows_the_radial_lens(&d, bound, nominal, name, keys, 1);
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The layout of the fabrication tests written in `d` (the radial layout's CSV, the 2-D grid's
/// `.npy`): the rings, the stated lattice error, and the nominal 2-D lens's (mean MTF, τ1).
fn fabrication_layout(d: &Path) -> (Vec<f64>, f64, (f64, f64)) {
    let rings = rings();
    write_radial_layout(&d.join("layout.csv"), &rings);
    let (n, at) = sites();
    write_npy(&d.join("lens.npy"), n, |i, j| at(i, j).unwrap_or(f64::NAN));
    let bound = lattice_bound();
    let nominal = mtf_and_tau(&load_128(d, "layout_grid = \"lens.npy\"\nlattice_pitch_um = 0.4").unwrap());
    println!("stated lattice error {bound:.4}; nominal 2-D: mean MTF {:.5}, τ1 {:.5}", nominal.0, nominal.1);
    (rings, bound, nominal)
}

/// One fabrication error `keys` (named `name`) on the 2-D layout against the radial lens averaged
/// over `seeds` draws: mean MTF and τ1 within `bound`, the lens moved from the `nominal` 2-D
/// lens's (mean MTF, τ1), and a phase error's τ1 scaled by e^{−σ²} exactly.
fn fabrication_error_follows_the_radial_lens(
    d: &Path,
    bound: f64,
    (m_nominal, t_nominal): (f64, f64),
    name: &str,
    keys: &str,
    seeds: usize,
) {
    let (mut m_radial, mut t_radial) = (0.0, 0.0);
    for seed in 0..seeds {
        let radial = load_128(d, &format!("layout = \"layout.csv\"\n{keys}\natom_error_seed = {seed}")).unwrap();
        let (m, t) = mtf_and_tau(&radial);
        m_radial += m / seeds as f64;
        t_radial += t / seeds as f64;
    }
    let grid = load_128(d, &format!("layout_grid = \"lens.npy\"\nlattice_pitch_um = 0.4\n{keys}")).unwrap();
    let (m, t) = mtf_and_tau(&grid);
    println!(
        "{name}: radial mean MTF {m_radial:.5}, τ1 {t_radial:.5}; 2-D mean MTF {m:.5} ({:+.2e}), τ1 {t:.5} ({:+.2e} relative)",
        m - m_radial,
        t / t_radial - 1.0
    );
    assert!((m - m_radial).abs() <= bound, "{name}: mean MTF {m} vs radial {m_radial}: beyond {bound}");
    assert!((t / t_radial - 1.0).abs() <= bound, "{name}: τ1 {t} vs radial {t_radial}: beyond {bound}");
    // each error moves the lens: the comparison is not of two nominal lenses
    assert!((m - m_nominal).abs() > 1e-4 || (t - t_nominal).abs() > 1e-4, "{name}: no change");
    if seeds > 1 && keys.contains("phase") {
        // in expectation every atom's field is scaled by e^{−σ²/2}: τ1 by e^{−σ²} exactly
        let ratio = t / t_nominal;
        assert!((ratio - (-0.09f64).exp()).abs() < 1e-9, "{name}: τ1 ratio {ratio} vs e^(−σ²)");
    }
}
