//! The convergence study of the `optics::fft` module docs ("Choosing the pupil sampling"): how
//! the mean MTF and the OTF at a few frequencies converge with the pupil sampling `N`, for the
//! pupils the FFT path serves, and how well a Richardson extrapolation on `N/2` and `N`
//! estimates the error.
//!
//! `cargo run -p asnr-optics --example fft_sampling` (a few minutes; `-- mono` or
//! `-- poly` runs one part).

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;
use std::time::Instant;

use num_complex::Complex64;
use optics::fft::{
    Aberrations, Aperture, Otf, OtfPlan, SampledPupil, SampledZones, ZoneField, defocus_mean_mtf,
    reduce_decentred_circle,
};
use optics::{Field, LensModel, Order, Polychromatic, Pupil, Settings, Wavefront, defocus_otf};
use radiometry::{Gaussian, Spectrum};

/// Paper lens (SI, Fig. 2): F/2.5, f0 = 3.36 mm, λ0 = 800 nm, 5.2 µm pixels.
const F_NUMBER: f64 = 2.5;
const F0: f64 = 3.36e-3;
const LAMBDA0: f64 = 800e-9;
const PIXEL: f64 = 5.2e-6;
/// The paper scene's Nyquist frequency at λ0 in the normalized frequency: `ν_N λ0 F#` = 0.192.
const S_MAX: f64 = 0.2;
/// Frequencies at which the OTF itself is followed.
const PROBES: [f64; 3] = [0.05, 0.1, 0.19];

/// The Richardson orders whose estimates are tabulated.
const ORDERS: [f64; 2] = [1.5, 2.0];

/// A pupil of the study at one wavelength (`LAMBDA0`).
enum Case {
    Single(Aperture, Aberrations),
    Zones(Vec<Arc<Aperture>>, Vec<ZoneField>),
}

/// One case: what it is, the pupil, and the exact mean MTF and probe values when known.
struct Study {
    name: &'static str,
    case: Case,
    exact: Option<(f64, Vec<Complex64>)>,
}

/// Mean MTF over `[0, S_MAX]` along `+x` and the OTF at the probes, at `n` samples; and the time
/// of the OTF grid alone.
fn measure(case: &Case, n: usize) -> (f64, Vec<Complex64>, f64) {
    let mut plan = OtfPlan::new(n, S_MAX).unwrap();
    let mut otf = Otf::new();
    let seconds = match case {
        Case::Single(aperture, aberrations) => {
            let pupil = SampledPupil::new(n, aperture, aberrations).unwrap();
            let t = Instant::now();
            plan.otf(&pupil, LAMBDA0, &mut otf);
            t.elapsed().as_secs_f64()
        }
        Case::Zones(apertures, fields) => {
            let mut zones = SampledZones::new(n, apertures).unwrap();
            zones.set_field(fields, LAMBDA0).unwrap();
            let t = Instant::now();
            plan.otf_of_field(zones.field(), zones.weight(), &mut otf);
            t.elapsed().as_secs_f64()
        }
    };
    let probes = PROBES.iter().map(|&s| otf.at(s, 0.0)).collect();
    (otf.mean_mtf(0.0, S_MAX), probes, seconds)
}

fn defocus(w: f64) -> Aberrations {
    Aberrations::defocus(w * LAMBDA0)
}

/// The chromatic defocus of the paper lens at `lambda` (docs/physics.md, "Chromatic lens").
fn w020(lambda: f64) -> f64 {
    (1.0 - lambda / LAMBDA0) * F0 / (8.0 * F_NUMBER * F_NUMBER)
}

fn studies() -> Vec<Study> {
    let exact_circle =
        |w: f64| (defocus_mean_mtf(w, S_MAX), PROBES.iter().map(|&s| defocus_otf(s, w).into()).collect());
    // a decentred iris: its reduction (`reduce_decentred_circle`) on the exact path; along +x the
    // shift phase does not change |OTF|, and the probes carry it
    let exact_iris = |w: f64, d: f64| {
        let reduced = reduce_decentred_circle([d, 0.0], 1.0, w * LAMBDA0, 0.5 / F_NUMBER).unwrap();
        let probes = PROBES
            .iter()
            .map(|&s| {
                let nu = s / (LAMBDA0 * F_NUMBER);
                defocus_otf(s, w) * Complex64::from_polar(1.0, -2.0 * PI * nu * reduced.image_shift_m[0])
            })
            .collect();
        (defocus_mean_mtf(w, S_MAX), probes)
    };
    let coma = |lambda: f64| Aberrations {
        w020_m: w020(lambda) * LAMBDA0 / lambda,
        w131_m: 0.5e-6 * LAMBDA0 / lambda,
        field: 1.0,
        ..Aberrations::default()
    };
    let third = TAU / 3.0;
    let sectors: Vec<Arc<Aperture>> =
        (0..3).map(|j| Arc::new(Aperture::sector(j as f64 * third, (j + 1) as f64 * third).unwrap())).collect();
    let rings: Vec<Arc<Aperture>> = (0..3)
        .map(|j| Arc::new(Aperture::ring((j as f64 / 3.0).sqrt(), ((j + 1) as f64 / 3.0).sqrt(), None).unwrap()))
        .collect();
    let fields = |waves: [f64; 3]| -> Vec<ZoneField> {
        waves.iter().map(|&w| ZoneField { amplitude: 0.9, aberrations: defocus(w), tilt_m: [0.0, 0.0] }).collect()
    };
    vec![
        Study {
            name: "circle, w = 0.5",
            case: Case::Single(Aperture::circle(), defocus(0.5)),
            exact: Some(exact_circle(0.5)),
        },
        Study {
            name: "circle, w = 2",
            case: Case::Single(Aperture::circle(), defocus(2.0)),
            exact: Some(exact_circle(2.0)),
        },
        Study {
            name: "iris d = 0.10, w = 0.5",
            case: Case::Single(Aperture::circle().decentred(0.1, 0.0).unwrap(), defocus(0.5)),
            exact: Some(exact_iris(0.5, 0.1)),
        },
        Study {
            name: "iris d = 0.15, w = 2",
            case: Case::Single(Aperture::circle().decentred(0.15, 0.0).unwrap(), defocus(2.0)),
            exact: Some(exact_iris(2.0, 0.15)),
        },
        Study { name: "coma 0.5 µm, 800 nm", case: Case::Single(Aperture::circle(), coma(800e-9)), exact: None },
        Study { name: "coma 0.5 µm, 820 nm", case: Case::Single(Aperture::circle(), coma(820e-9)), exact: None },
        Study {
            name: "annulus 0.5, w = 1",
            case: Case::Single(Aperture::annulus(0.5).unwrap(), defocus(1.0)),
            exact: None,
        },
        Study {
            name: "half disc, w = 0",
            case: Case::Single(Aperture::sector(0.0, PI).unwrap(), defocus(0.0)),
            // along x the half disc's OTF is MTF_0(s) (tests/optics/fft.rs)
            exact: Some(exact_circle(0.0)),
        },
        Study {
            name: "sector 120°, w = 1",
            case: Case::Single(Aperture::sector(0.3, 0.3 + third).unwrap(), defocus(1.0)),
            exact: None,
        },
        Study { name: "3 sectors, w = −1, 0, 1", case: Case::Zones(sectors, fields([-1.0, 0.0, 1.0])), exact: None },
        Study { name: "3 rings, w = −1, 0, 1", case: Case::Zones(rings, fields([-1.0, 0.0, 1.0])), exact: None },
    ]
}

/// Observed order from three successive values at `N/4, N/2, N`.
fn observed_order(a: f64, b: f64, c: f64) -> f64 {
    ((b - a).abs() / (c - b).abs()).log2()
}

fn mono() {
    let sizes = [32usize, 64, 128, 256, 512, 1024, 2048];
    println!("## Monochromatic grids (λ = 800 nm, mean MTF over [0, {S_MAX}] along +x)\n");
    println!("Relative error of the mean MTF `e_N`; observed order `p_N = log2(|M_N/2 − M_N/4| / |M_N − M_N/2|)`;");
    println!("largest error of the OTF at s = 0.05, 0.1, 0.19 (`otf`); the Richardson estimate");
    println!("`|M_N − M_N/2|/(2^p − 1)` over the true error (`est/e`) and the error of the extrapolated");
    println!("value (`e_R`) for p = 1.5 and 2. Reference: exact where known, otherwise the Richardson");
    println!("extrapolation of N = 1024 and 2048 with the order observed at 2048 (marked ~).\n");
    println!(
        "| case | N | mean MTF | e_N | p_N | otf | est/e, p = 1.5 | e_R, p = 1.5 | est/e, p = 2 | e_R, p = 2 | grid time |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for study in studies() {
        let rows: Vec<(usize, f64, Vec<Complex64>, f64)> = sizes
            .iter()
            .map(|&n| {
                let (m, probes, t) = measure(&study.case, n);
                (n, m, probes, t)
            })
            .collect();
        let len = rows.len();
        let (reference, probes_ref, marker) = match &study.exact {
            Some((m, p)) => (*m, p.clone(), ""),
            None => {
                let p = observed_order(rows[len - 3].1, rows[len - 2].1, rows[len - 1].1);
                let m = rows[len - 1].1 + (rows[len - 1].1 - rows[len - 2].1) / (2f64.powf(p) - 1.0);
                (m, rows[len - 1].2.clone(), "~")
            }
        };
        for (i, (n, m, probes, t)) in rows.iter().enumerate() {
            let e = (m - reference) / reference;
            let p =
                if i >= 2 { format!("{:.2}", observed_order(rows[i - 2].1, rows[i - 1].1, *m)) } else { "—".into() };
            let otf = probes.iter().zip(&probes_ref).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            let mut richardson = String::new();
            for q in ORDERS {
                if i >= 1 {
                    let d = m - rows[i - 1].1;
                    let est = d.abs() / (2f64.powf(q) - 1.0) / reference;
                    let extrapolated = m + d / (2f64.powf(q) - 1.0);
                    let er = ((extrapolated - reference) / reference).abs();
                    richardson += &format!(" {:.2} | {er:.1e} |", est / e.abs());
                } else {
                    richardson += " — | — |";
                }
            }
            println!(
                "| {} | {n} | {m:.9} | {marker}{:.1e} | {p} | {otf:.1e} |{richardson} {:.2} ms |",
                study.name,
                e.abs(),
                1e3 * t
            );
        }
    }
}

/// The paper's chromatic metalens with optional coma and an optional aperture (the `lenses`
/// crate depends on this one).
#[derive(Debug)]
struct Paper {
    coma_m: f64,
    aperture: Option<Arc<Aperture>>,
    /// the decentred iris given by its reduction on the exact path
    reduced: bool,
}

impl LensModel for Paper {
    fn f_number(&self) -> f64 {
        F_NUMBER
    }
    fn focal_length(&self) -> f64 {
        F0
    }
    fn orders(&self, lambda: f64, _: Field) -> Vec<Order> {
        let w = w020(lambda);
        match &self.aperture {
            Some(a) if self.reduced => {
                let (c, r) = a.as_circle().unwrap();
                let red = reduce_decentred_circle(c, r, w, 0.5 / F_NUMBER).unwrap();
                let [dx, dy] = red.image_shift_m;
                vec![Order::new(0.15, Pupil::Full, Wavefront::defocus(red.defocus_m).shifted(dx, dy))]
            }
            Some(a) => vec![Order::new(0.15, Pupil::Aperture(a.clone()), Wavefront::defocus(w))],
            None => {
                let mut wavefront = Wavefront::defocus(w);
                wavefront.coma_m = self.coma_m;
                vec![Order::new(0.15, Pupil::Full, wavefront)]
            }
        }
    }
}

fn poly() {
    let spectrum = Spectrum::product(vec![
        Spectrum::Gaussian(Gaussian::from_range(LAMBDA0, 50e-9, 1.0).unwrap()),
        Spectrum::Linear { slope: 1.0 },
    ]);
    let nyquist = 0.5 / PIXEL;
    let mean = |lens: &Paper, n: Option<usize>, azimuth: f64| {
        let settings = Settings { pupil_samples: n, tolerance: 1e-10, ..Settings::default() };
        let t = Instant::now();
        let poly = Polychromatic::with_settings(lens, &spectrum, Field::ON_AXIS, nyquist, None, settings).unwrap();
        let m = poly.mean_mtf_along(azimuth).0;
        (m, t.elapsed().as_secs_f64())
    };
    println!("\n## Polychromatic paper scene (F/2.5, 50 nm, 5.2 µm pixels): whole mean MTF\n");
    println!("Mean of the tangential (+x) and sagittal (+y) mean MTFs. Reference: the exact path (the");
    println!("iris by its reduction) or, for coma, the Richardson extrapolation of 512 and 1024.\n");
    println!("| case | N | mean MTF | e_N | p_N | est/e, p = 1.5 | e_R, p = 1.5 | est/e, p = 2 | e_R, p = 2 | time |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let iris = |d: f64| Some(Arc::new(Aperture::circle().decentred(d, 0.0).unwrap()));
    let cases: Vec<(&str, Paper, Option<Paper>)> = vec![
        (
            "circle as an aperture",
            Paper { coma_m: 0.0, aperture: Some(Arc::new(Aperture::circle())), reduced: false },
            Some(Paper { coma_m: 0.0, aperture: None, reduced: false }),
        ),
        (
            "iris d = 0.10",
            Paper { coma_m: 0.0, aperture: iris(0.1), reduced: false },
            Some(Paper { coma_m: 0.0, aperture: iris(0.1), reduced: true }),
        ),
        (
            "iris d = 0.15",
            Paper { coma_m: 0.0, aperture: iris(0.15), reduced: false },
            Some(Paper { coma_m: 0.0, aperture: iris(0.15), reduced: true }),
        ),
        ("coma 0.5 µm", Paper { coma_m: 0.5e-6, aperture: None, reduced: false }, None),
    ];
    let sizes = [32usize, 64, 128, 256, 512, 1024];
    for (name, lens, exact) in cases {
        let both = |n: Option<usize>, l: &Paper| {
            let (a, t1) = mean(l, n, 0.0);
            let (b, t2) = mean(l, n, FRAC_PI_2);
            (0.5 * (a + b), t1 + t2)
        };
        let rows: Vec<(usize, f64, f64)> = sizes
            .iter()
            .map(|&n| {
                let (m, t) = both(Some(n), &lens);
                (n, m, t)
            })
            .collect();
        let len = rows.len();
        let (reference, marker) = match &exact {
            Some(l) => (both(None, l).0, ""),
            None => {
                let p = observed_order(rows[len - 3].1, rows[len - 2].1, rows[len - 1].1);
                (rows[len - 1].1 + (rows[len - 1].1 - rows[len - 2].1) / (2f64.powf(p) - 1.0), "~")
            }
        };
        for (i, &(n, m, t)) in rows.iter().enumerate() {
            let e = (m - reference) / reference;
            let p =
                if i >= 2 { format!("{:.2}", observed_order(rows[i - 2].1, rows[i - 1].1, m)) } else { "—".into() };
            let mut richardson = String::new();
            for q in ORDERS {
                if i >= 1 {
                    let d = m - rows[i - 1].1;
                    let est = d.abs() / (2f64.powf(q) - 1.0) / reference;
                    let er = ((m + d / (2f64.powf(q) - 1.0) - reference) / reference).abs();
                    richardson += &format!(" {:.2} | {er:.1e} |", est / e.abs());
                } else {
                    richardson += " — | — |";
                }
            }
            println!("| {name} | {n} | {m:.9} | {marker}{:.1e} | {p} |{richardson} {:.0} ms |", e.abs(), 1e3 * t / 2.0);
        }
    }
}

fn main() {
    let which = std::env::args().nth(1).unwrap_or_default();
    if which.is_empty() || which == "mono" {
        mono();
    }
    if which.is_empty() || which == "poly" {
        poly();
    }
}
