//! Layouts as site maps (`optics::map::SiteMap`, `MapPupil::sites`) against references written
//! here cell by cell: the design order's powers, the pupil sampled finer than the cells against
//! the phase-map path (`PhaseMap`, `MapPupil::new`) built from the same cells, and the pupil
//! sampled coarser than the cells against the mean of each sample's cells' own design-order
//! fields (docs/physics.md, "Resampling a layout to the pupil grid").

use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use num_complex::Complex64;
use optics::map::{MapAperture, MapPupil, PhaseMap, SiteMap, StoredPhase};

const PITCH: f64 = 0.4e-6;
const CELLS: usize = 240;
const RADIUS: f64 = 48e-6;
const FOCAL: f64 = 240e-6; // F/2.5
const L0: f64 = 0.8e-6;
const LEVELS: usize = 8;

fn sinc(u: f64) -> f64 {
    if u == 0.0 { 1.0 } else { (PI * u).sin() / (PI * u) }
}

fn centre(i: usize) -> f64 {
    (i as f64 - 0.5 * (CELLS as f64 - 1.0)) * PITCH
}

fn sphere(x: f64, y: f64) -> f64 {
    (x * x + y * y + FOCAL * FOCAL).sqrt() - FOCAL
}

/// A focusing layout of 8 atoms (phase steps of 2π/8 with amplitudes 0.8–1) plus the empty
/// cell, each cell taking the atom nearest the hyperbolic phase `−k0 S`, and a small geometric
/// phase on every cell: `(atoms, geometric, table at λ)`.
fn layout(lambda: f64) -> (Vec<u32>, Vec<f64>, Vec<Complex64>) {
    let k0 = TAU / L0;
    let mut atoms = Vec::with_capacity(CELLS * CELLS);
    let mut geometric = Vec::with_capacity(CELLS * CELLS);
    for j in 0..CELLS {
        for i in 0..CELLS {
            let target = (-k0 * sphere(centre(i), centre(j))).rem_euclid(TAU);
            atoms.push(((target / TAU * LEVELS as f64).round() as usize % LEVELS) as u32);
            geometric.push(0.3 * ((i * 7 + j * 13) % 5) as f64 / 5.0);
        }
    }
    // the atoms' phase scales with 1/λ as a pillar's propagation phase does
    let table = (0..LEVELS)
        .map(|u| {
            Complex64::from_polar(0.8 + 0.2 * (u as f64 / LEVELS as f64), TAU * u as f64 / LEVELS as f64 * L0 / lambda)
        })
        .chain(std::iter::once(Complex64::new(1.0, 0.0)))
        .collect();
    (atoms, geometric, table)
}

fn site_map(atoms: Vec<u32>, geometric: &[f64]) -> Arc<SiteMap> {
    Arc::new(SiteMap::new(CELLS, CELLS, PITCH, atoms, LEVELS + 1, Some(geometric), RADIUS, FOCAL, L0).unwrap())
}

/// Samples whose square lies inside the circle: area 1, else 0.
fn full_samples(n: usize) -> Vec<f64> {
    let h = 2.0 / n as f64;
    let mut area = vec![0.0; n * n];
    for j in 0..n {
        for i in 0..n {
            let (x, y) = ((i as f64 + 0.5) * h - 1.0, (j as f64 + 0.5) * h - 1.0);
            let far = (x.abs() + 0.5 * h).hypot(y.abs() + 0.5 * h);
            if far <= 1.0 {
                area[j * n + i] = 1.0;
            }
        }
    }
    area
}

/// The cell's design order at λ (on axis): `t e^{i(k0 S + γ)} sinc sinc e^{ik(1 − λ/λ0) S}`.
fn cell_field(t: Complex64, gamma: f64, x: f64, y: f64, lambda: f64) -> (Complex64, f64) {
    let r = (x * x + y * y + FOCAL * FOCAL).sqrt();
    let u = PITCH / lambda;
    let share = sinc(u * x / r) * sinc(u * y / r);
    let k = TAU / lambda;
    let phase = TAU / L0 * sphere(x, y) + gamma + k * (1.0 - lambda / L0) * sphere(x, y);
    (t * Complex64::from_polar(share, phase), share)
}

#[test]
fn powers_equal_the_sum_over_the_cells() {
    let lambda = 0.76e-6;
    let (atoms, geometric, table) = layout(lambda);
    let map = site_map(atoms.clone(), &geometric);
    let (design, all) = map.powers(&table, lambda);
    let (mut want_design, mut want_all) = (0.0, 0.0);
    for j in 0..CELLS {
        for i in 0..CELLS {
            let (x, y) = (centre(i), centre(j));
            if x * x + y * y > RADIUS * RADIUS {
                continue;
            }
            let t = table[atoms[j * CELLS + i] as usize];
            let (_, share) = cell_field(t, 0.0, x, y, lambda);
            want_all += t.norm_sqr();
            want_design += t.norm_sqr() * share * share;
        }
    }
    // T exactly; τ1 with the share held over blocks of b = 16 cells at their centroid: the
    // share's curvature over the block, (π p b/(λ z))²/18 to leading order (docs/physics.md)
    assert!((all / want_all - 1.0).abs() < 1e-12, "T {all} against {want_all}");
    let e = (design / want_design - 1.0).abs();
    let bound = (PI * PITCH * 16.0 * PITCH / (lambda * FOCAL)).powi(2) / 18.0;
    println!("τ1 sum: block share against the cells' own: {e:.2e} (leading-order bound {bound:.2e})");
    assert!(e < 1.2 * bound, "τ1 sum {design} against {want_design}: {e:.1e}, bound {bound:.1e}");
}

#[test]
fn samples_finer_than_the_cells_equal_the_phase_map_path() {
    let lambda = 0.84e-6;
    let (atoms, geometric, table) = layout(lambda);
    let map = site_map(atoms.clone(), &geometric);
    // the same cells as a phase map: ψ = arg t + γ + k0 S (wrapped) and |t|
    let k0 = TAU / L0;
    let (mut phase, mut amplitude) = (Vec::new(), Vec::new());
    for j in 0..CELLS {
        for i in 0..CELLS {
            let c = j * CELLS + i;
            let t = table[atoms[c] as usize];
            let v = t.arg() + geometric[c] + k0 * sphere(centre(i), centre(j));
            phase.push(v - TAU * (v / TAU).round());
            amplitude.push(t.norm());
        }
    }
    let phase_map = PhaseMap::new(
        CELLS,
        CELLS,
        PITCH,
        phase,
        Some(amplitude),
        MapAperture::Circle,
        RADIUS,
        FOCAL,
        L0,
        StoredPhase::Given,
    )
    .unwrap();
    let n = 512; // 0.19 µm samples: finer than the 0.4 µm cells
    let area = full_samples(n);
    let (fast, fast_weight) = MapPupil::sites(map, table.into(), lambda, None).field(n, &area, lambda);
    let (slow, slow_weight) =
        MapPupil::new(Arc::new(phase_map), lambda / TAU, 1.0 - lambda / L0, None).field(n, &area, lambda);
    let worst = fast.iter().zip(&slow).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    println!("point samples: largest difference from the phase-map path {worst:.1e}");
    // the site map holds e^{i(k0 S + γ)} in f32: 1e-6
    assert!(worst < 1e-6, "largest difference {worst:.1e}");
    assert!((fast_weight / slow_weight - 1.0).abs() < 1e-12, "weights {fast_weight} against {slow_weight}");
}

#[test]
fn samples_coarser_than_the_cells_are_the_mean_of_their_cells() {
    for (lambda, n) in [(0.76e-6, 24), (0.84e-6, 17), (0.8e-6, 40)] {
        let (atoms, geometric, table) = layout(lambda);
        let map = site_map(atoms.clone(), &geometric);
        let area = full_samples(n);
        let pupil = MapPupil::sites(map, table.clone().into(), lambda, None);
        let (fast, weight) = pupil.field(n, &area, lambda);
        let h = 2.0 / n as f64;
        let w = h * RADIUS;
        // the remainder of the smooth phase k(1 − λ/λ0) S taken linear over a sample: its
        // curvature is at most k |1 − λ/λ0| / z, over at most w/√2 from the sample's centre
        let curvature = TAU / lambda * (1.0 - lambda / L0).abs() / FOCAL;
        let remainder = 0.5 * curvature * w * w / 2.0;
        let (mut worst, mut worst_over_bound, mut want_weight) = (0.0f64, 0.0f64, 0.0);
        for js in 0..n {
            for is in 0..n {
                if area[js * n + is] == 0.0 {
                    continue;
                }
                let (xs, ys) = (((is as f64 + 0.5) * h - 1.0) * RADIUS, ((js as f64 + 0.5) * h - 1.0) * RADIUS);
                let (_, share_s) = cell_field(Complex64::new(1.0, 0.0), 0.0, xs, ys, lambda);
                let (mut sum, mut power, mut count, mut share_dev) = (Complex64::new(0.0, 0.0), 0.0, 0.0, 0.0f64);
                for j in 0..CELLS {
                    for i in 0..CELLS {
                        let (x, y) = (centre(i), centre(j));
                        let inside = ((x / RADIUS + 1.0) / h).floor() as usize == is
                            && ((y / RADIUS + 1.0) / h).floor() as usize == js
                            && x * x + y * y <= RADIUS * RADIUS;
                        if !inside {
                            continue;
                        }
                        let c = j * CELLS + i;
                        let t = table[atoms[c] as usize];
                        let (f, share) = cell_field(t, geometric[c], x, y, lambda);
                        sum += f;
                        power += t.norm_sqr();
                        count += 1.0;
                        share_dev = share_dev.max((share - share_s).abs());
                    }
                }
                let want = sum / count;
                want_weight += share_s * share_s * power / count;
                let e = (fast[js * n + is] - want).norm();
                let bound = (power / count).sqrt() * (remainder + share_dev) + 1e-6;
                worst = worst.max(e);
                worst_over_bound = worst_over_bound.max(e / bound);
            }
        }
        println!(
            "λ = {} nm, {n}² samples of {:.1} µm: largest difference from the cells' mean {worst:.1e} ({:.2} of its bound)",
            lambda * 1e9,
            w * 1e6,
            worst_over_bound
        );
        assert!(worst_over_bound <= 1.0, "λ {lambda}, n {n}: {worst:.1e} is {worst_over_bound:.2} of its bound");
        assert!((weight / want_weight - 1.0).abs() < 1e-12, "weight {weight} against {want_weight}");
    }
}

/// A layout's field is linear in its atoms' table and its power quadratic: the field's
/// derivative where the table moves by `dt` (`MapPupil::field_derivative`, docs/physics.md,
/// "Gradients: a library's parameter bias") against the central difference of the fields of
/// `t ± s dt`, s = 1e-3 (exact for a linear map, and for the power's quadratic form, up to the
/// rounding of the sums over the samples), on
/// the point path (samples finer than the cells) and the block path (coarser), on axis and with
/// the oblique wave; and `SiteMap::power_rates` against the powers' central difference.
#[test]
fn field_derivative_is_the_difference_of_the_moved_tables() {
    let lambda = 0.81e-6;
    let (atoms, geometric, table) = layout(lambda);
    let map = site_map(atoms, &geometric);
    // a move of every atom but the empty cell
    let mut dt: Vec<Complex64> =
        (0..table.len()).map(|u| Complex64::new(0.3 - 0.05 * u as f64, 0.1 + 0.02 * u as f64)).collect();
    dt[LEVELS] = Complex64::new(0.0, 0.0);
    let s = 1e-3;
    let moved = |sign: f64| -> Vec<Complex64> { table.iter().zip(&dt).map(|(t, d)| t + sign * s * d).collect() };
    let (up, down) = (moved(1.0), moved(-1.0));
    let oblique = optics::radial::Oblique::new(RADIUS, FOCAL, 0.03, -0.02).unwrap();
    for (n, obl) in [(300, None), (300, Some(oblique)), (40, None), (40, Some(oblique))] {
        let area = full_samples(n);
        let pupil = |t: &[Complex64]| MapPupil::sites(map.clone(), t.to_vec().into(), lambda, obl);
        let (field, _) = pupil(&table).field(n, &area, lambda);
        let (d_field, d_power) = pupil(&table).field_derivative(n, &area, lambda, &dt).unwrap();
        let (f_up, p_up) = pupil(&up).field(n, &area, lambda);
        let (f_down, p_down) = pupil(&down).field(n, &area, lambda);
        let scale = field.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let worst = (0..n * n).map(|i| ((f_up[i] - f_down[i]) / (2.0 * s) - d_field[i]).norm()).fold(0.0, f64::max);
        let want = (p_up - p_down) / (2.0 * s);
        println!(
            "{n}² samples, oblique {}: field {worst:.1e} of {scale:.2}, power {d_power:.9e} vs {want:.9e}",
            obl.is_some()
        );
        assert!(worst < 1e-10 * scale, "n {n}: the field's derivative is {worst:.1e} off");
        // the powers are sums of n² terms: their rounding (1e-13 of P over 2s) is the difference's
        assert!((d_power - want).abs() < 1e-13 * p_up / s, "n {n}: power {d_power} vs {want}");
    }
    let (d_design, d_all) = map.power_rates(&table, &dt, lambda);
    let ((du, au), (dd, ad)) = (map.powers(&up, lambda), map.powers(&down, lambda));
    let (want_design, want_all) = ((du - dd) / (2.0 * s), (au - ad) / (2.0 * s));
    assert!((d_design - want_design).abs() < 1e-10 * want_design.abs(), "{d_design} vs {want_design}");
    assert!((d_all - want_all).abs() < 1e-10 * want_all.abs(), "{d_all} vs {want_all}");
}
