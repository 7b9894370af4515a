//! Slow, obviously correct reference for the defocus OTF, the polychromatic OTF and the mean MTF.
//!
//! Everything here is written for checking, not for speed, and is deliberately independent of the
//! fast path: it uses its own adaptive Gauss–Kronrod (G10–K21 and G30–K61, QUADPACK constants), the
//! `y` form of the OTF integral exactly as printed in docs/physics.md ("Exact defocused OTF"), and plain
//! nested adaptive quadrature over wavelength and spatial frequency.
//!
//! Units: SI throughout (metres, cycles per metre). Waves for defocus.
//!
//! * [`otf_defocus`]: `OTF(s, w) = 4/(π a) ∫_0^{√(1−s²)} sin[a(√(1−y²) − s)] dy`, `a = 8π w s`,
//!   evaluated as `(4/π) ∫ u sinc(a u) dy` with `u = √(1−y²) − s`, which is exact at `a = 0`
//!   (`MTF_0(s)`) with no cancellation.
//! * [`polychromatic_otf`]: `∫ ρ(λ) OTF(ν λ F#, w(λ)) dλ / ∫ ρ(λ) dλ` for a chromatic lens
//!   `f(λ) = f0 λ0/λ`, `w(λ) = (1 − λ/λ0) f0 / (8 F#² λ)` (signed sum; the sign of
//!   docs/physics.md, "Sign of the wavefront": `w > 0` is a focus behind the detector, so `w < 0` for
//!   `λ > λ0`; the defocus OTF is even in `w`).
//! * [`mean_mtf`]: `(1/ν_N) ∫_0^{ν_N} P(ν) |OTF_poly(ν)| dν` (paper eq. 1 without SNR0), with the
//!   integration range split at the sign changes of `OTF_poly`.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::f64::consts::PI;

use crate::quad::MAX_POINTS;
pub use crate::quad::{GK21, GK61, GaussKronrod};

/// Maximum number of bisections of an initial interval in [`integrate`].
pub const MAX_DEPTH: u32 = 60;

/// Maximum number of live panels in one adaptive integration (a safety stop).
const MAX_PANELS: usize = 500_000;

/// Result of an adaptive quadrature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quadrature {
    /// The integral estimate (sum of the Kronrod results of all final panels).
    pub value: f64,
    /// Estimated absolute error (sum of the QUADPACK error estimates of all final panels).
    pub error: f64,
    /// Number of integrand evaluations.
    pub evaluations: usize,
    /// Whether the summed error estimate meets the requested tolerance.
    pub converged: bool,
}

/// A panel of the globally adaptive scheme, ordered by its error estimate.
#[derive(Debug, Clone, Copy)]
struct Panel {
    a: f64,
    b: f64,
    value: f64,
    error: f64,
    depth: u32,
    /// Rounding floor `50 ε ∫|f|` of the panel; a panel whose error estimate is no larger (or
    /// zero) is never bisected, since bisection cannot reduce it.
    round: f64,
}

impl PartialEq for Panel {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Panel {}
impl PartialOrd for Panel {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Panel {
    fn cmp(&self, other: &Self) -> Ordering {
        self.error.total_cmp(&other.error)
    }
}

/// Whether `[a, b]` can still be bisected in floating point.
fn splittable(p: &Panel) -> bool {
    let m = 0.5 * (p.a + p.b);
    p.error > p.round && p.depth < MAX_DEPTH && m > p.a && m < p.b
}

/// Globally adaptive bisection over a list of panels (QUADPACK QAG strategy): repeatedly bisect the
/// panel with the largest error estimate until `Σ error ≤ max(abs_tol, rel_tol |Σ value|)`.
/// `eval(a, b, depth)` returns the panels that replace `[a, b]` (normally one).
fn adapt<E: FnMut(f64, f64, u32) -> Vec<Panel>>(
    initial: Vec<Panel>,
    mut eval: E,
    abs_tol: f64,
    rel_tol: f64,
    evaluations: &dyn Fn() -> usize,
) -> Quadrature {
    let mut heap: BinaryHeap<Panel> = BinaryHeap::new();
    let mut frozen: Vec<Panel> = Vec::new();
    for p in initial {
        if splittable(&p) {
            heap.push(p);
        } else {
            frozen.push(p);
        }
    }
    let sums = |heap: &BinaryHeap<Panel>, frozen: &[Panel]| {
        let (mut v, mut e, mut r) = (0.0, 0.0, 0.0);
        for p in heap.iter().chain(frozen.iter()) {
            v += p.value;
            e += p.error;
            r += p.round;
        }
        (v, e, r)
    };
    // Done when the target is met, or when the error is within twice the summed rounding floors
    // (a target below rounding cannot be met; bisecting further would only chase noise).
    let done = |v: f64, e: f64, r: f64| e <= abs_tol.max(rel_tol * v.abs()).max(2.0 * r);
    let (mut value, mut error, mut round) = sums(&heap, &frozen);
    loop {
        if done(value, error, round) {
            // Re-sum exactly to remove drift of the running sums before accepting.
            (value, error, round) = sums(&heap, &frozen);
            if done(value, error, round) {
                break;
            }
        }
        let Some(worst) = heap.pop() else {
            break;
        };
        if heap.len() + frozen.len() > MAX_PANELS {
            heap.push(worst);
            break;
        }
        let m = 0.5 * (worst.a + worst.b);
        let mut children = eval(worst.a, m, worst.depth + 1);
        children.extend(eval(m, worst.b, worst.depth + 1));
        value -= worst.value;
        error -= worst.error;
        round -= worst.round;
        for c in children {
            value += c.value;
            error += c.error;
            round += c.round;
            if splittable(&c) {
                heap.push(c);
            } else {
                frozen.push(c);
            }
        }
    }
    let (value, error, _) = sums(&heap, &frozen);
    Quadrature { value, error, evaluations: evaluations(), converged: error <= abs_tol.max(rel_tol * value.abs()) }
}

/// Adaptive Gauss–Kronrod quadrature of `f` from the smallest to the largest of `points`,
/// integrating piecewise between all of them (any order, duplicates allowed).
///
/// Globally adaptive bisection (QUADPACK QAG): the panel with the largest error estimate is
/// bisected until the summed QUADPACK error estimate is at most `max(abs_tol, rel_tol |value|)`.
/// Panels at [`MAX_DEPTH`] bisections, too narrow to split, or whose estimate is already the
/// rounding floor `50 ε ∫|f|` are not split, and the work stops when the summed estimate is within
/// twice the summed rounding floors; `converged` says whether the target itself was met.
pub fn integrate<F: FnMut(f64) -> f64>(
    rule: GaussKronrod,
    f: F,
    points: &[f64],
    abs_tol: f64,
    rel_tol: f64,
) -> Quadrature {
    let pts = sorted_points(points);
    let count = std::cell::Cell::new(0usize);
    let f = std::cell::RefCell::new(f);
    let eval = |a: f64, b: f64, depth: u32| {
        let n = rule.points();
        let x = rule.nodes(a, b);
        let mut fx = [0.0; MAX_POINTS];
        let mut g = f.borrow_mut();
        for k in 0..n {
            fx[k] = (*g)(x[k]);
        }
        count.set(count.get() + n);
        let (value, error, round) = rule.estimate(a, b, &fx[..n]);
        vec![Panel { a, b, value, error, depth, round }]
    };
    let mut initial = Vec::new();
    for w in pts.windows(2) {
        initial.extend(eval(w[0], w[1], 0));
    }
    adapt(initial, eval, abs_tol, rel_tol, &|| count.get())
}

/// Smallest absolute tolerance (normalized OTF units) requested from the spectral integral: the
/// OTF itself is only accurate to about 1e-14 (rounding), and asking the spectral quadrature to
/// resolve noise of that size would make it bisect without end.
const MIN_POLY_TOL: f64 = 2e-13;

/// Finite breakpoints, sorted ascending, without duplicates.
fn sorted_points(points: &[f64]) -> Vec<f64> {
    let mut pts: Vec<f64> = points.iter().copied().filter(|x| x.is_finite()).collect();
    pts.sort_by(f64::total_cmp);
    pts.dedup();
    pts
}

/// First pair of indices `i < j` with `fx[i]`, `fx[j]` of opposite signs and only zeros between.
fn sign_change(fx: &[f64]) -> Option<(usize, usize)> {
    let mut last: Option<usize> = None;
    for (j, &v) in fx.iter().enumerate() {
        if v != 0.0 {
            if let Some(i) = last
                && (fx[i] > 0.0) != (v > 0.0)
            {
                return Some((i, j));
            }
            last = Some(j);
        }
    }
    None
}

/// Root of `f` in `(x0, x1)` given `f(x0) = f0`, `f(x1) = f1` of opposite signs, by the Illinois
/// (modified regula falsi) method, which keeps the root bracketed. Stops at bracket width `xtol`.
fn illinois<F: FnMut(f64) -> f64>(f: &mut F, mut x0: f64, mut f0: f64, mut x1: f64, mut f1: f64, xtol: f64) -> f64 {
    let mut side = 0;
    for _ in 0..200 {
        if (x1 - x0).abs() <= xtol {
            break;
        }
        let mut x = (x0 * f1 - x1 * f0) / (f1 - f0);
        if !(x > x0.min(x1) && x < x0.max(x1)) {
            x = 0.5 * (x0 + x1);
        }
        let fx = f(x);
        if fx == 0.0 {
            return x;
        }
        if (fx > 0.0) == (f1 > 0.0) {
            x1 = x;
            f1 = fx;
            if side == -1 {
                f0 *= 0.5;
            }
            side = -1;
        } else {
            x0 = x;
            f0 = fx;
            if side == 1 {
                f1 *= 0.5;
            }
            side = 1;
        }
    }
    if f0.abs() < f1.abs() { x0 } else { x1 }
}

/// Adaptive quadrature of `weight(x) |f(x)|`, split at the sign changes of `f`.
///
/// The nodes of every panel are checked for a sign change of `f`; where one is found the root is
/// located (Illinois, to `1e-13` of the whole range) and the panel replaced by the two panels on
/// either side of it, so that `|f|` is smooth on the panels that are kept. Sign changes that fall
/// between nodes are still handled correctly, only more slowly: the kink makes the error estimate
/// large and the panel is bisected until its nodes see the change. Otherwise as [`integrate`].
pub fn integrate_modulus<F: FnMut(f64) -> f64, P: Fn(f64) -> f64>(
    rule: GaussKronrod,
    f: F,
    weight: P,
    points: &[f64],
    abs_tol: f64,
    rel_tol: f64,
) -> Quadrature {
    let pts = sorted_points(points);
    let span = pts.last().copied().unwrap_or(0.0) - pts.first().copied().unwrap_or(0.0);
    let xtol = 1e-13 * span.abs();
    let count = std::cell::Cell::new(0usize);
    let f = std::cell::RefCell::new(f);
    let eval = |a: f64, b: f64, depth: u32| {
        let mut out = Vec::new();
        let mut todo = vec![(a, b, depth)];
        while let Some((a, b, depth)) = todo.pop() {
            let n = rule.points();
            let x = rule.nodes(a, b);
            let mut fx = [0.0; MAX_POINTS];
            let mut g = f.borrow_mut();
            for k in 0..n {
                fx[k] = (*g)(x[k]);
            }
            count.set(count.get() + n);
            if depth < MAX_DEPTH
                && let Some((i, j)) = sign_change(&fx[..n])
            {
                let mut counted = |t: f64| {
                    count.set(count.get() + 1);
                    (*g)(t)
                };
                let r = illinois(&mut counted, x[i], fx[i], x[j], fx[j], xtol);
                if r > a && r < b {
                    todo.push((a, r, depth + 1));
                    todo.push((r, b, depth + 1));
                    continue;
                }
            }
            let gx: [f64; MAX_POINTS] = std::array::from_fn(|k| weight(x[k]) * fx[k].abs());
            let (value, error, round) = rule.estimate(a, b, &gx[..n]);
            out.push(Panel { a, b, value, error, depth, round });
        }
        out
    };
    let mut initial = Vec::new();
    for w in pts.windows(2) {
        initial.extend(eval(w[0], w[1], 0));
    }
    adapt(initial, eval, abs_tol, rel_tol, &|| count.get())
}

// ---------------------------------------------------------------------------------------------
// Monochromatic OTF of a defocused circular pupil
// ---------------------------------------------------------------------------------------------

/// Absolute accuracy target of [`otf_defocus`].
pub const OTF_ABS_TOL: f64 = 1e-13;

/// Initial panels per period of `sin(a u)` in the OTF integral when it has fewer than 8 periods
/// (G10–K21 panels of 1.3 periods).
const Y_PANELS_PER_PERIOD_21: f64 = 0.75;

/// Initial panels per period of `sin(a u)` in the OTF integral when it has 8 periods or more
/// (G30–K61 panels of 10 periods).
const Y_PANELS_PER_PERIOD_61: f64 = 0.1;

/// Initial panels per period (`Δa = 2π`) of the OTF's oscillation in λ (G10–K21 panels of 2
/// periods). These only set the starting mesh: adaptivity refines wherever it is too coarse.
const LAMBDA_PANELS_PER_PERIOD: f64 = 0.5;

/// `sin(x)/x`, equal to 1 at `x = 0`. (`sin` has full relative accuracy, so no series is needed.)
fn sinc(x: f64) -> f64 {
    if x == 0.0 { 1.0 } else { x.sin() / x }
}

/// docs/physics.md test vectors `(s, w, OTF)` for the defocused OTF, printed there to 5 decimals
/// (tolerance 1e-5): every OTF implementation is checked against them.
pub const PHYSICS_TEST_VECTORS: [(f64, f64, f64); 7] = [
    (0.1, 0.0, 0.87289),
    (0.1, 0.5, 0.74209),
    (0.1, 1.0, 0.42665),
    (0.2, 1.0, -0.01441),
    (0.5, 0.25, 0.28747),
    (0.05, 2.0, 0.41297),
    (0.1, 2.0, -0.08396),
];

/// Exact OTF of a circular pupil with defocus `w` (waves at the pupil edge) at normalized
/// frequency `s = ν/ν_c`, from docs/physics.md as printed:
/// `OTF(s, w) = 4/(π a) ∫_0^{√(1−s²)} sin[a(√(1−y²) − s)] dy`, `a = 8π w s`,
/// computed as `(4/π) ∫ u sinc(a u) dy`, `u = √(1−y²) − s`, so that `a → 0` gives
/// `MTF_0(s) = (2/π)[acos s − s√(1−s²)]` without cancellation. Real, may be negative; even in `s`
/// and `w`; 1 at `s = 0`; 0 for `|s| ≥ 1`. Absolute accuracy about [`OTF_ABS_TOL`].
pub fn otf_defocus(s: f64, w: f64) -> f64 {
    otf_defocus_tol(s, w, OTF_ABS_TOL)
}

/// [`otf_defocus`] with a given absolute accuracy target.
fn otf_defocus_tol(s: f64, w: f64, abs_tol: f64) -> f64 {
    if s.is_nan() || w.is_nan() {
        return f64::NAN;
    }
    let s = s.abs();
    if s >= 1.0 {
        return 0.0;
    }
    if s == 0.0 {
        return 1.0;
    }
    let a = 8.0 * PI * w * s;
    let ymax = ((1.0 - s) * (1.0 + s)).sqrt();
    // Breakpoints, chosen in c = √(1−y²) ∈ [s, 1] and mapped to y = √(1−c²):
    // (i) equal steps of the phase a(c − s) (a few periods per panel at most, see the constants);
    // (ii) c = 2s, 4s, 8s, … grading towards the branch point of √(1−y²) at y = 1 (c = 0),
    //      which lies just beyond y_max when s is small.
    let periods = a.abs() * (1.0 - s) / (2.0 * PI);
    // Long oscillatory integrals: G30–K61 on panels of several periods; short ones: G10–K21.
    let (rule, per) = if periods >= 8.0 { (GK61, Y_PANELS_PER_PERIOD_61) } else { (GK21, Y_PANELS_PER_PERIOD_21) };
    let n = (periods * per).ceil().max(1.0) as usize;
    let mut cs: Vec<f64> = (1..n).map(|k| s + (1.0 - s) * k as f64 / n as f64).collect();
    let mut c = 2.0 * s;
    while c < 1.0 {
        cs.push(c);
        c *= 2.0;
    }
    let mut ys: Vec<f64> = cs.iter().map(|&c| ((1.0 - c) * (1.0 + c)).sqrt()).collect();
    ys.retain(|&y| y > 0.0 && y < ymax);
    ys.push(0.0);
    ys.push(ymax);
    let integrand = |y: f64| {
        let u = ((1.0 - y) * (1.0 + y)).sqrt() - s;
        if u <= 0.0 { 0.0 } else { u * sinc(a * u) }
    };
    let q = integrate(rule, integrand, &ys, abs_tol * PI / 4.0, 0.0);
    4.0 / PI * q.value
}

// ---------------------------------------------------------------------------------------------
// Polychromatic OTF and mean MTF of a chromatic (diffractive) lens
// ---------------------------------------------------------------------------------------------

/// A chromatic lens `f(λ) = f0 λ0/λ` with a detector at `f0`, a spectrum and a pixel pitch.
pub struct ReferenceScene<'a> {
    /// Photoelectron spectral density (arbitrary scale) at wavelength λ (m); zero outside
    /// `[lambda_min, lambda_max]`.
    pub density: &'a dyn Fn(f64) -> f64,
    /// Lower end of the wavelength integration range (m), `> 0`.
    pub lambda_min: f64,
    /// Upper end of the wavelength integration range (m), finite.
    pub lambda_max: f64,
    /// Wavelengths (m) inside the range where the density has kinks or jumps.
    pub breakpoints: &'a [f64],
    /// F-number `F# = f0/D`.
    pub f_number: f64,
    /// Design focal length `f0` (m); the detector stays at `f0`.
    pub focal_length_m: f64,
    /// Design wavelength `λ0` (m).
    pub design_wavelength_m: f64,
    /// Pixel pitch `p` (m); Nyquist `ν_N = 1/(2p)`.
    pub pixel_pitch_m: f64,
    /// Multiply the MTF by the pixel aperture MTF `|sinc(p ν)|` (100 % fill factor).
    pub pixel_mtf: bool,
}

impl ReferenceScene<'_> {
    /// Defocus at the pupil edge in waves, `w(λ) = W020(λ)/λ = (1 − λ/λ0) f0 / (8 F#²) / λ`
    /// (docs/physics.md, "Sign of the wavefront": negative for `λ > λ0`, where `f(λ) < f0` focuses in
    /// front of the detector).
    pub fn defocus_waves(&self, lambda: f64) -> f64 {
        (1.0 - lambda / self.design_wavelength_m) * self.focal_length_m / (8.0 * self.f_number * self.f_number) / lambda
    }

    /// Nyquist frequency `ν_N = 1/(2p)` (cycles/m).
    pub fn nyquist(&self) -> f64 {
        0.5 / self.pixel_pitch_m
    }

    /// `∫ ρ(λ) dλ` over the range (64 panels per piece between breakpoints, relative 1e-14).
    fn norm(&self) -> f64 {
        let pts = self.lambda_points(self.lambda_min, self.lambda_max);
        let n = 64;
        let mut fine = Vec::new();
        for w in pts.windows(2) {
            fine.extend((0..n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        }
        fine.push(self.lambda_max);
        integrate(GK21, |l| (self.density)(l), &fine, 0.0, 1e-14).value
    }

    /// Breakpoints of the density inside `[lo, hi]`, with the ends.
    fn lambda_points(&self, lo: f64, hi: f64) -> Vec<f64> {
        let mut pts: Vec<f64> = self
            .breakpoints
            .iter()
            .copied()
            .chain(std::iter::once(self.design_wavelength_m))
            .filter(|&l| l > lo && l < hi)
            .collect();
        pts.push(lo);
        pts.push(hi);
        sorted_points(&pts)
    }

    /// `∫ ρ(λ) OTF(ν λ F#, w(λ)) dλ / norm` with absolute error about `tol`.
    fn poly_otf_abs(&self, nu: f64, tol: f64, norm: f64) -> f64 {
        let tol = tol.max(MIN_POLY_TOL);
        let nu = nu.abs();
        let fnum = self.f_number;
        let lo = self.lambda_min;
        // Past λ = 1/(ν F#) the frequency is beyond the cutoff and the OTF is zero.
        let hi = if nu > 0.0 { self.lambda_max.min(1.0 / (nu * fnum)) } else { self.lambda_max };
        if hi <= lo || norm == 0.0 {
            return 0.0;
        }
        // Initial panels of two periods of the OTF's oscillation in λ: a = 8π w s is linear in λ
        // with slope da/dλ = π ν f0/(F# λ0); at least 8 panels per piece.
        let slope = PI * nu * self.focal_length_m / (fnum * self.design_wavelength_m);
        let mut pts = Vec::new();
        for w in self.lambda_points(lo, hi).windows(2) {
            let periods = slope * (w[1] - w[0]) / (2.0 * PI);
            let n = ((periods * LAMBDA_PANELS_PER_PERIOD).ceil() as usize).max(8);
            pts.extend((0..n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        }
        pts.push(hi);
        // Error budget (normalized): quadrature 0.5 tol, OTF 0.2 tol, cut 0.05 tol. The cut is
        // rigorous: where ρ(λ) times a bound on |OTF| is ≤ θ, dropping the node changes the
        // integral by at most θ (hi − lo).
        let theta = 0.05 * tol * norm / (hi - lo);
        let otf_tol = 0.2 * tol;
        let integrand = |l: f64| {
            let r = (self.density)(l);
            let (s, w) = (nu * l * fnum, self.defocus_waves(l));
            // |OTF| ≤ min(1, 4/(π |a|)) from |sin| ≤ 1 in the printed formula (a = 8π w s).
            let bound = (4.0 / (PI * (8.0 * PI * w * s).abs())).min(1.0);
            if r.abs() * bound <= theta { 0.0 } else { r * otf_defocus_tol(s, w, otf_tol) }
        };
        let q = integrate(GK21, integrand, &pts, 0.5 * tol * norm, 0.0);
        q.value / norm
    }

    /// `∫_0^{ν_N} P(ν) |OTF_poly(ν)| dν` with OTF_poly accurate to `inner_tol` (absolute).
    fn modulus_integral(&self, rel_tol: f64, inner_tol: f64, norm: f64) -> Quadrature {
        let fnum = self.f_number;
        let nu_n = self.nyquist();
        let nu_hi = nu_n.min(1.0 / (self.lambda_min * fnum));
        // ν where the upper wavelength limit 1/(ν F#) crosses λ_max or a density breakpoint.
        let mut pts: Vec<f64> = self
            .breakpoints
            .iter()
            .chain(std::iter::once(&self.lambda_max))
            .map(|&l| 1.0 / (l * fnum))
            .filter(|&nu| nu > 0.0 && nu < nu_hi)
            .collect();
        pts.extend((0..=4).map(|k| nu_hi * k as f64 / 4.0));
        let p = self.pixel_pitch_m;
        let pixel = self.pixel_mtf;
        let weight = move |nu: f64| if pixel { sinc(PI * p * nu).abs() } else { 1.0 };
        integrate_modulus(
            GK21,
            |nu| self.poly_otf_abs(nu, inner_tol, norm),
            weight,
            &pts,
            0.1 * inner_tol * nu_n,
            rel_tol,
        )
    }
}

/// Polychromatic OTF `∫ ρ(λ) OTF(ν λ F#, w(λ)) dλ / ∫ ρ(λ) dλ` at frequency `nu` (cycles/m):
/// the signed, photoelectron-weighted sum of the monochromatic OTFs (docs/physics.md
/// "Polychromatic OTF"). Error target `rel_tol · max(|OTF_poly|, 1e-3)`.
pub fn polychromatic_otf(scene: &ReferenceScene<'_>, nu: f64, rel_tol: f64) -> f64 {
    let norm = scene.norm();
    let rough = scene.poly_otf_abs(nu, 1e-6, norm);
    let tol = rel_tol * rough.abs().max(1e-3);
    scene.poly_otf_abs(nu, tol, norm)
}

/// Mean MTF up to Nyquist, `(1/ν_N) ∫_0^{ν_N} P(ν) |OTF_poly(ν)| dν` with
/// `P(ν) = |sin(π p ν)/(π p ν)|` if `pixel_mtf`, else 1 (paper eq. 1 divided by SNR0 ν_N).
/// Relative error target `rel_tol`, down to about `2e-12 / mean` (the inner integrals are not
/// asked for better than 2e-13 absolute). Measured cost (opt-level 2): 0.06 s for the paper scene
/// (F/2.5, 50 nm Gaussian, 5.2 µm), 2.3 s for F/1.4, 200 nm, 2 µm; nearly independent of
/// `rel_tol` because the oscillations must be resolved anyway.
pub fn mean_mtf(scene: &ReferenceScene<'_>, rel_tol: f64) -> f64 {
    mean_mtf_quadrature(scene, rel_tol).value
}

/// [`mean_mtf`] with the frequency quadrature's error estimate (divided by `ν_N`; the inner
/// integrals are held to a tenth of the target separately), its number of OTF_poly evaluations,
/// and whether it converged.
pub fn mean_mtf_quadrature(scene: &ReferenceScene<'_>, rel_tol: f64) -> Quadrature {
    let norm = scene.norm();
    let nu_n = scene.nyquist();
    // The inner (OTF_poly) error feeds straight into the mean: keep it below a tenth of the
    // target, assuming first that the mean is at least 1e-3 and redoing the work if it is not.
    let mut scale = 1e-3;
    loop {
        let q = scene.modulus_integral(0.5 * rel_tol, 0.1 * rel_tol * scale, norm);
        let m = q.value / nu_n;
        if m >= scale || m <= 0.0 || scale < 1e-12 {
            return Quadrature { value: m, error: q.error / nu_n, ..q };
        }
        scale = 0.5 * m;
    }
}

/// Hopkins' Bessel series for the defocused OTF (H. H. Hopkins, "The frequency response of a
/// defocused optical system", Proc. R. Soc. A 231, 91–103, 1955), a third independent evaluation.
///
/// In Hopkins' reduced frequency `s_H = 2s` (so `s_H = 2` is the cutoff) and with
/// `a = 4π w s_H = 8π w s`, `β = acos(s_H/2)`:
///
/// ```text
/// OTF = (4/(π a)) cos(a s_H/2) [β J1(a) + Σ_{n≥1} (−1)^{n+1} sin(2nβ)/(2n) (J_{2n−1}(a) − J_{2n+1}(a))]
///     − (4/(π a)) sin(a s_H/2) [Σ_{n≥0} (−1)^n sin((2n+1)β)/(2n+1) (J_{2n}(a) − J_{2n+2}(a))]
/// ```
///
/// Bessel functions from `libm::jn` (not the fast path's recurrence); the sums stop where
/// `Jn(a)` is below 1e-17 (`n > a + 12 a^{1/3} + 30`). For `a → 0` the closed form MTF_0 is used.
pub fn otf_hopkins(s: f64, w: f64) -> f64 {
    let a = (8.0 * PI * w * s).abs();
    otf_hopkins_terms(s, w, (a + 12.0 * a.cbrt() + 30.0) as usize + 1)
}

/// [`otf_hopkins`] with each of its two brackets cut after `terms` terms: `β J1` and `n = 1 …
/// terms − 1` in the first, `n = 0 … terms − 1` in the second (Bessel orders up to `2 terms`).
/// The series converges once `2 terms` passes `|a| = 8π |w s|`, where `Jn(a)` starts to decay;
/// fewer terms give the truncation error the accuracy report measures.
pub fn otf_hopkins_terms(s: f64, w: f64, terms: usize) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let a = (8.0 * PI * w * s).abs();
    let beta = s.acos();
    if a < 1e-6 {
        return std::f64::consts::FRAC_2_PI * (beta - s * (1.0 - s * s).sqrt());
    }
    let j = |n: i32| libm::jn(n, a);
    let terms = i32::try_from(terms).unwrap_or(i32::MAX / 2 - 1);
    let mut first = beta * j(1);
    let mut second = 0.0;
    for n in 1..terms {
        let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
        let m = f64::from(2 * n);
        first += sign * (m * beta).sin() / m * (j(2 * n - 1) - j(2 * n + 1));
    }
    for n in 0..terms {
        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
        let m = f64::from(2 * n + 1);
        second += sign * (m * beta).sin() / m * (j(2 * n) - j(2 * n + 2));
    }
    let k = 4.0 / (PI * a);
    k * ((a * s).cos() * first - (a * s).sin() * second)
}

/// The geometric-optics limit of the defocused OTF (docs/physics.md, "Geometric limit"), an
/// approximation for comparisons, good at large defocus only: `OTF → 2 J1(x)/x` with
/// `x = π d ν`, blur-disk diameter `d = 2 |Δz| NA`. With `Δz = 8 F#² W020`, `NA = 1/(2 F#)` and
/// `ν = s/(λ F#)`, `x = 8π |w| s = |a|`. 1 at `s ≤ 0` and `a = 0`; 0 at `s ≥ 1` like the OTF
/// (the geometric formula itself knows no cutoff); `J1` from `libm`.
pub fn otf_geometric(s: f64, w: f64) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let x = (8.0 * PI * w * s).abs();
    if x < 1e-8 { 1.0 - x * x / 8.0 } else { 2.0 * libm::j1(x) / x }
}
