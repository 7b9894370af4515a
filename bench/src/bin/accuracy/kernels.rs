//! The OTF kernels table: each way of computing the monochromatic OTF of a defocused circular
//! pupil, against `optics::reference::otf_defocus` (printed y-form, adaptive Gauss–Kronrod,
//! 1e-13 absolute), at 12 frequencies `s = (k − ½)/12` for each defocus in [`DEFOCUS_WAVES`].

use std::f64::consts::PI;
use std::time::Duration;

use optics::reference::{otf_defocus, otf_geometric, otf_hopkins, otf_hopkins_terms};
use optics::{BESSEL_SERIES_MIN_A, defocus_otf, defocus_otf_panels, defocus_otf_quadrature, quad};

/// Defocus values (waves at the pupil edge), small to large.
pub(crate) const DEFOCUS_WAVES: [f64; 5] = [0.25, 1.0, 5.0, 30.0, 300.0];

/// Normalized frequencies of every defocus: `s = (k − ½)/12`, k = 1 … 12.
fn frequencies() -> Vec<f64> {
    (1..=12).map(|k| (f64::from(k) - 0.5) / 12.0).collect()
}

/// A way of computing the OTF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Kernel {
    /// `optics::defocus_otf`: Gauss–Legendre panels from `defocus_otf_panels` below
    /// `|a| = BESSEL_SERIES_MIN_A`, the Jacobi–Anger series above.
    Production,
    /// `optics::defocus_otf_quadrature`: the production panels at every `a`.
    ProductionQuadrature,
    /// One n-point Gauss–Legendre rule on the t-form (docs/physics.md, "Exact defocused OTF").
    GaussLegendre(usize),
    /// Hopkins' series cut after K terms (`None`: its own term count, converged).
    Hopkins(Option<usize>),
    /// The geometric approximation 2 J1(a)/a.
    Geometric,
}

impl Kernel {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Kernel::Production => "optics::defocus_otf",
            Kernel::ProductionQuadrature => "defocus_otf_quadrature",
            Kernel::GaussLegendre(_) => "Gauss–Legendre, fixed nodes",
            Kernel::Hopkins(_) => "Hopkins series",
            Kernel::Geometric => "geometric 2J1(a)/a",
        }
    }

    pub(crate) fn setting(self) -> String {
        match self {
            Kernel::Production | Kernel::ProductionQuadrature => "panels grow with a".into(),
            Kernel::GaussLegendre(n) => format!("n = {n}"),
            Kernel::Hopkins(Some(k)) => format!("K = {k}"),
            Kernel::Hopkins(None) => "all terms".into(),
            Kernel::Geometric => "—".into(),
        }
    }
}

/// Error and time of a kernel at one defocus, over the 12 frequencies.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cell {
    /// Largest absolute error.
    pub(crate) abs: f64,
    /// Largest error relative to the envelope `min(1, 4/(π|a|))` of the OTF at each point.
    pub(crate) rel: f64,
    /// Median time per OTF value, ns.
    pub(crate) nanos: f64,
}

/// One kernel: a [`Cell`] per defocus in [`DEFOCUS_WAVES`], and what it computed.
pub(crate) struct KernelRow {
    pub(crate) kernel: Kernel,
    pub(crate) cells: Vec<Cell>,
    pub(crate) work: String,
}

impl KernelRow {
    pub(crate) fn max_abs(&self) -> f64 {
        self.cells.iter().map(|c| c.abs).fold(0.0, f64::max)
    }

    pub(crate) fn max_rel(&self) -> f64 {
        self.cells.iter().map(|c| c.rel).fold(0.0, f64::max)
    }

    /// Mean time per OTF value over all points, ns.
    pub(crate) fn nanos(&self) -> f64 {
        self.cells.iter().map(|c| c.nanos).sum::<f64>() / self.cells.len() as f64
    }
}

/// The t-form (docs/physics.md) `OTF = 4/(π a) ∫_0^{acos s} sin[a(cos t − s)] cos t dt`, `a = 8π w s`, by
/// one Gauss–Legendre rule (`rule` on [−1, 1]) over the whole interval.
fn t_form(s: f64, w: f64, rule: &[(f64, f64)]) -> f64 {
    let a = 8.0 * PI * w * s;
    let half = 0.5 * s.acos();
    let sum: f64 = rule
        .iter()
        .map(|&(x, weight)| {
            let cos_t = (half * (1.0 + x)).cos();
            weight * (a * (cos_t - s)).sin() * cos_t
        })
        .sum();
    4.0 / (PI * a) * half * sum
}

fn evaluator(kernel: Kernel) -> Box<dyn Fn(f64, f64) -> f64> {
    match kernel {
        Kernel::Production => Box::new(defocus_otf),
        Kernel::ProductionQuadrature => Box::new(defocus_otf_quadrature),
        Kernel::GaussLegendre(n) => {
            let rule = quad::gauss_legendre(n);
            Box::new(move |s, w| t_form(s, w, &rule))
        }
        Kernel::Hopkins(Some(k)) => Box::new(move |s, w| otf_hopkins_terms(s, w, k)),
        Kernel::Hopkins(None) => Box::new(otf_hopkins),
        Kernel::Geometric => Box::new(otf_geometric),
    }
}

/// The Gauss–Legendre node counts of the production kernel at each defocus: `16 ×
/// defocus_otf_panels` where `|a| < BESSEL_SERIES_MIN_A`, the series at the other points.
fn production_work(kernel: Kernel, s: &[f64]) -> String {
    let per_w: Vec<String> = DEFOCUS_WAVES
        .iter()
        .map(|&w| {
            let nodes: Vec<usize> = s
                .iter()
                .filter(|&&s| kernel == Kernel::ProductionQuadrature || 8.0 * PI * w * s < BESSEL_SERIES_MIN_A)
                .map(|&s| quad::ORDER * defocus_otf_panels(s, w))
                .collect();
            let series = s.len() - nodes.len();
            let range = match (nodes.iter().min(), nodes.iter().max()) {
                (Some(lo), Some(hi)) if lo == hi => format!("{lo}"),
                (Some(lo), Some(hi)) => format!("{lo}–{hi}"),
                _ => return "series".to_owned(),
            };
            if series == 0 { range } else { format!("{range} (series at {series} of {})", s.len()) }
        })
        .collect();
    format!("nodes per w: {}", per_w.join(" · "))
}

/// Measures every kernel; `quick` runs fewer settings with a smaller time budget.
pub(crate) fn measure(quick: bool) -> Vec<KernelRow> {
    let s = frequencies();
    let reference: Vec<Vec<f64>> =
        DEFOCUS_WAVES.iter().map(|&w| s.iter().map(|&s| otf_defocus(s, w)).collect()).collect();
    let (nodes, terms): (&[usize], &[usize]) =
        if quick { (&[8, 32, 128], &[5, 20]) } else { (&[8, 16, 32, 64, 128], &[5, 10, 20, 40]) };
    let mut kernels = vec![Kernel::Production, Kernel::ProductionQuadrature];
    kernels.extend(nodes.iter().map(|&n| Kernel::GaussLegendre(n)));
    kernels.extend(terms.iter().map(|&k| Kernel::Hopkins(Some(k))));
    // the full series with libm's Jn takes 0.6 s a value at w = 300: not in a smoke run
    if !quick {
        kernels.push(Kernel::Hopkins(None));
    }
    kernels.push(Kernel::Geometric);
    let (budget, min_repeats) = if quick { (Duration::from_millis(2), 0) } else { (Duration::from_millis(50), 3) };
    eprintln!("OTF kernels (max |error| and time per value at w = {DEFOCUS_WAVES:?}):");
    kernels
        .into_iter()
        .map(|kernel| {
            let f = evaluator(kernel);
            let cells: Vec<Cell> = DEFOCUS_WAVES
                .iter()
                .zip(&reference)
                .map(|(&w, exact)| {
                    let (micros, _, _) = crate::time(budget, min_repeats, || {
                        s.iter().map(|&s| f(std::hint::black_box(s), std::hint::black_box(w))).sum::<f64>()
                    });
                    let (mut abs, mut rel) = (0.0f64, 0.0f64);
                    for (&s, e) in s.iter().zip(exact) {
                        let v = f(s, w);
                        let envelope = (4.0 / (PI * 8.0 * PI * w * s)).min(1.0);
                        abs = abs.max((v - e).abs());
                        rel = rel.max((v - e).abs() / envelope);
                    }
                    Cell { abs, rel, nanos: micros * 1e3 / s.len() as f64 }
                })
                .collect();
            let work = match kernel {
                Kernel::Production | Kernel::ProductionQuadrature => production_work(kernel, &s),
                Kernel::GaussLegendre(n) => format!("{n} sines and cosines"),
                Kernel::Hopkins(Some(k)) => format!("Bessel orders ≤ {}", 2 * k),
                Kernel::Hopkins(None) => "K = a + 12a^{1/3} + 31 terms".into(),
                Kernel::Geometric => "one J1".into(),
            };
            let row = KernelRow { kernel, cells, work };
            let summary: Vec<String> = row.cells.iter().map(|c| format!("{:.1e}/{:.0}ns", c.abs, c.nanos)).collect();
            eprintln!("  {:<28} {:<18} {}", kernel.name(), kernel.setting(), summary.join("  "));
            row
        })
        .collect()
}
