//! Spectral rules for the mean MTF of a Gaussian spectrum, each with the production
//! monochromatic OTF (`optics::defocus_otf`) at its nodes and one fixed frequency rule, so that a
//! row's error is its spectral rule's.
//!
//! docs/physics.md, "Polychromatic OTF": `OTF_poly(ν) = Σ Wᵢ OTF(ν λᵢ F#, w(λᵢ)) / Σ Wᵢ` with the
//! detected weights `W ∝ λ · G(λ)` (flat source behind a Gaussian filter, constant QE and τ1),
//! and the mean MTF `(1/ν_N) ∫_0^{ν_N} |OTF_poly| dν` (paper eq. 1 without SNR0).

use optics::{defocus_otf, quad};

use crate::{Case, LAMBDA0, PIXEL_PITCH};

/// A spectral node: wavelength (m) and weight (quadrature weight × detected density `λ G(λ)`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Node {
    lambda: f64,
    weight: f64,
}

/// The case's Gaussian filter `G(λ) = exp(−(λ − λ0)²/(2σ²))` (peak 1).
fn gaussian(case: &Case, lambda: f64) -> f64 {
    (-0.5 * ((lambda - LAMBDA0) / case.sigma()).powi(2)).exp()
}

/// The trapezoid rule with `n ≥ 2` nodes on `[λ0 − kσ, λ0 + kσ]`: spacing `h = 2kσ/(n − 1)`,
/// weights `h` (`h/2` at the ends) times `λ G(λ)`. The Gaussian beyond ±kσ is dropped, which
/// biases the MTF area by about 1e-3 at ±3σ and 1e-7 at ±5σ (docs/physics.md, "Spectral quadrature").
pub(crate) fn uniform(case: &Case, k: u32, n: usize) -> Vec<Node> {
    let half = f64::from(k) * case.sigma();
    let h = 2.0 * half / (n - 1) as f64;
    (0..n)
        .map(|j| {
            let lambda = LAMBDA0 - half + h * j as f64;
            let end = if j == 0 || j == n - 1 { 0.5 } else { 1.0 };
            Node { lambda, weight: end * h * lambda * gaussian(case, lambda) }
        })
        .collect()
}

/// Gauss–Hermite nodes `λᵢ = λ0 + √2 σ xᵢ` from the standard rule `(xᵢ, wᵢ)` for `e^{−x²}`
/// (`optics::quad::gauss_hermite`): `∫ λ G(λ) g(λ) dλ = √2 σ ∫ e^{−x²} λ(x) g(λ(x)) dx`, so the
/// weight is `√2 σ wᵢ λᵢ` and the λ factor, linear in x, is integrated exactly with the rest.
/// Nodes at λ ≤ 0, where the spectrum is zero (docs/physics.md, "Spectra": truncated there), are dropped; their
/// weights are below `e^{−(λ0/σ)²/2}` (1e-28 for the hard scene).
pub(crate) fn hermite(case: &Case, standard: &[(f64, f64)]) -> Vec<Node> {
    let scale = 2f64.sqrt() * case.sigma();
    standard
        .iter()
        .map(|&(x, w)| {
            let lambda = LAMBDA0 + scale * x;
            Node { lambda, weight: scale * w * lambda }
        })
        .filter(|n| n.lambda > 0.0)
        .collect()
}

/// The fixed frequency rule of the spectral-rule rows: `panels` equal panels of the 16-point
/// Gauss–Legendre rule (`optics::quad`) on `[0, ν_N]`, each panel where `OTF_poly` changes sign
/// split at the zero, so `|OTF_poly|` is smooth on every piece and the rule converges fast.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrequencyRule {
    pub(crate) panels: usize,
    /// Largest relative change of the finest spectral rules' means at the last doubling of
    /// `panels`: the frequency rule's own error is below it.
    pub(crate) change: f64,
}

impl FrequencyRule {
    /// Doubles the panel count from 4 until the mean MTF of every rule in `finest` changes by
    /// at most 1e-14 relative (or 4096 panels).
    pub(crate) fn converged(case: &Case, finest: &[Vec<Node>]) -> FrequencyRule {
        let means = |panels: usize| -> Vec<f64> {
            let rule = FrequencyRule { panels, change: f64::NAN };
            finest.iter().map(|nodes| rule.mean_mtf(case, nodes).0).collect()
        };
        let mut panels = 4;
        let mut previous = means(panels);
        loop {
            panels *= 2;
            let current = means(panels);
            let change = current.iter().zip(&previous).map(|(c, p)| ((c - p) / c).abs()).fold(0.0, f64::max);
            if change <= 1e-14 || panels >= 4096 {
                return FrequencyRule { panels, change };
            }
            previous = current;
        }
    }

    /// The mean MTF up to Nyquist with the OTF summed over `nodes`, and the number of
    /// `OTF_poly` evaluations it took.
    pub(crate) fn mean_mtf(&self, case: &Case, nodes: &[Node]) -> (f64, usize) {
        let total: f64 = nodes.iter().map(|n| n.weight).sum();
        // (normalized weight, λ F# so that s = ν λ F#, defocus in waves)
        let prepared: Vec<(f64, f64, f64)> =
            nodes.iter().map(|n| (n.weight / total, n.lambda * case.f_number, case.waves(n.lambda))).collect();
        let count = std::cell::Cell::new(0);
        let otf = |nu: f64| {
            count.set(count.get() + 1);
            prepared.iter().map(|&(q, lf, w)| q * defocus_otf(nu * lf, w)).sum::<f64>()
        };
        let nyquist = 0.5 / PIXEL_PITCH;
        let integral = modulus_integral(&otf, nyquist, self.panels);
        (integral / nyquist, count.get())
    }
}

/// `∫_0^b |f| dx` by `panels` equal panels of the 16-point Gauss–Legendre rule. Where `f`
/// changes sign between consecutive nodes (or between `0`, `b` and the nearest node), the zero
/// is located (Illinois method) and the panel holding it is integrated in pieces split there,
/// each with the same rule.
fn modulus_integral(f: &dyn Fn(f64) -> f64, b: f64, panels: usize) -> f64 {
    let rule = quad::rule();
    let h = b / panels as f64;
    let edge = |p: usize| if p == panels { b } else { h * p as f64 };
    let mut points = Vec::with_capacity(panels * quad::ORDER + 2);
    points.push((0.0, f(0.0)));
    for p in 0..panels {
        let mid = 0.5 * (edge(p) + edge(p + 1));
        for &(x, _) in rule {
            let nu = mid + 0.5 * h * x;
            points.push((nu, f(nu)));
        }
    }
    points.push((b, f(b)));
    let roots: Vec<f64> = points
        .windows(2)
        .filter(|pair| pair[0].1 != 0.0 && pair[1].1 != 0.0 && (pair[0].1 < 0.0) != (pair[1].1 < 0.0))
        .map(|pair| illinois(f, pair[0], pair[1]))
        .collect();
    let mut total = 0.0;
    for p in 0..panels {
        let (lo, hi) = (edge(p), edge(p + 1));
        let inside: Vec<f64> = roots.iter().copied().filter(|&r| r > lo && r < hi).collect();
        if inside.is_empty() {
            let values = &points[1 + quad::ORDER * p..1 + quad::ORDER * (p + 1)];
            total += 0.5 * (hi - lo) * rule.iter().zip(values).map(|(&(_, w), &(_, v))| w * v.abs()).sum::<f64>();
        } else {
            let mut cuts = vec![lo];
            cuts.extend(inside);
            cuts.push(hi);
            for piece in cuts.windows(2) {
                total += quad::composite(piece[0], piece[1], 1, |x| f(x).abs());
            }
        }
    }
    total
}

/// A zero of `f` between `(a, f(a))` and `(b, f(b))` of opposite signs: regula falsi with the
/// Illinois modification (the retained end's value halved when it is retained twice), to a few
/// ulps.
fn illinois(f: &dyn Fn(f64) -> f64, (mut a, mut fa): (f64, f64), (mut b, mut fb): (f64, f64)) -> f64 {
    let mut side = 0;
    let mut c = a;
    for _ in 0..200 {
        let next = (a * fb - b * fa) / (fb - fa);
        if (next - c).abs() <= 2.0 * f64::EPSILON * next.abs() {
            return next;
        }
        c = next;
        let fc = f(c);
        if fc == 0.0 {
            return c;
        }
        if (fc < 0.0) == (fb < 0.0) {
            (b, fb) = (c, fc);
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        } else {
            (a, fa) = (c, fc);
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        }
    }
    c
}
