//! Slow, obviously correct reference for the defocus OTF, the polychromatic OTF and the mean MTF.
//!
//! Everything here is written for checking, not for speed, and is deliberately independent of the
//! fast path: it uses its own adaptive Gauss–Kronrod (G10–K21, QUADPACK constants), the
//! `y` form of the OTF integral exactly as printed in `PHYSICS.md` ("Optics: the OTF"), and plain
//! nested adaptive quadrature over wavelength and spatial frequency.
//!
//! Units: SI throughout (metres, cycles per metre). Waves for defocus.
//!
//! * [`otf_defocus`]: `OTF(s, w) = 4/(π a) ∫_0^{√(1−s²)} sin[a(√(1−y²) − s)] dy`, `a = 8π w s`,
//!   evaluated as `(4/π) ∫ u sinc(a u) dy` with `u = √(1−y²) − s`, which is exact at `a = 0`
//!   (`MTF_0(s)`) with no cancellation.
//! * [`polychromatic_otf`]: `∫ ρ(λ) OTF(ν λ F#, w(λ)) dλ / ∫ ρ(λ) dλ` for a chromatic lens
//!   `f(λ) = f0 λ0/λ`, `w(λ) = (λ/λ0 − 1) f0 / (8 F#² λ)` (signed sum, PHYSICS.md).
//! * [`mean_mtf`]: `(1/ν_N) ∫_0^{ν_N} P(ν) |OTF_poly(ν)| dν` (paper eq. 1 without SNR0), with the
//!   integration range split at the sign changes of `OTF_poly`.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// Gauss–Kronrod G10–K21 (QUADPACK dqk21 constants, Piessens et al. 1983, 33 digits)
// ---------------------------------------------------------------------------------------------

/// Abscissae of the 21-point Kronrod rule on [-1, 1], positive half, descending.
/// `XGK[1], XGK[3], …, XGK[9]` are the 10-point Gauss abscissae.
const XGK: [f64; 11] = [
    0.995_657_163_025_808_080_735_527_280_689_003,
    0.973_906_528_517_171_720_077_964_012_084_452,
    0.930_157_491_355_708_226_001_207_180_059_508,
    0.865_063_366_688_984_510_732_096_688_423_493,
    0.780_817_726_586_416_897_063_717_578_345_042,
    0.679_409_568_299_024_406_234_327_365_114_874,
    0.562_757_134_668_604_683_339_000_099_272_694,
    0.433_395_394_129_247_190_799_265_943_165_784,
    0.294_392_862_701_460_198_131_126_603_103_866,
    0.148_874_338_981_631_210_884_826_001_129_720,
    0.0,
];

/// Weights of the 21-point Kronrod rule, matching `XGK`.
const WGK: [f64; 11] = [
    0.011_694_638_867_371_874_278_064_396_062_192,
    0.032_558_162_307_964_727_478_818_972_459_390,
    0.054_755_896_574_351_996_031_381_300_244_580,
    0.075_039_674_810_919_952_767_043_140_916_190,
    0.093_125_454_583_697_605_535_065_465_083_366,
    0.109_387_158_802_297_641_899_210_590_325_805,
    0.123_491_976_262_065_851_077_958_109_831_074,
    0.134_709_217_311_473_325_928_054_001_771_707,
    0.142_775_938_577_060_080_797_094_273_138_717,
    0.147_739_104_901_338_491_374_841_515_972_068,
    0.149_445_554_002_916_905_664_936_468_389_821,
];

/// Weights of the 10-point Gauss rule at `XGK[1], XGK[3], …, XGK[9]`.
const WG: [f64; 5] = [
    0.066_671_344_308_688_137_593_568_809_893_332,
    0.149_451_349_150_580_593_145_776_339_657_697,
    0.219_086_362_515_982_043_995_534_934_228_163,
    0.269_266_719_309_996_355_091_226_921_569_469,
    0.295_524_224_714_752_870_173_892_994_651_338,
];

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
    /// Whether the requested tolerance was met before the depth or panel limits stopped the work.
    pub converged: bool,
}

/// The 21 nodes of the G10–K21 rule mapped to `[a, b]`, ascending.
fn gk21_nodes(a: f64, b: f64) -> [f64; 21] {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let mut x = [0.0; 21];
    for j in 0..10 {
        x[j] = c - h * XGK[j];
        x[20 - j] = c + h * XGK[j];
    }
    x[10] = c;
    x
}

/// Kronrod value and QUADPACK error estimate of one panel from the 21 function values at
/// [`gk21_nodes`] (ascending order), and whether the estimate is the rounding floor
/// `50 ε ∫|f|` (bisecting such a panel cannot reduce it).
fn gk21_from_values(a: f64, b: f64, fx: &[f64; 21]) -> (f64, f64, bool) {
    let h = 0.5 * (b - a);
    let mut resk = WGK[10] * fx[10];
    let mut resabs = WGK[10] * fx[10].abs();
    let mut resg = 0.0;
    for j in 0..10 {
        let pair = fx[j] + fx[20 - j];
        resk += WGK[j] * pair;
        resabs += WGK[j] * (fx[j].abs() + fx[20 - j].abs());
        if j % 2 == 1 {
            resg += WG[j / 2] * pair;
        }
    }
    let mean = 0.5 * resk;
    let mut resasc = WGK[10] * (fx[10] - mean).abs();
    for j in 0..10 {
        resasc += WGK[j] * ((fx[j] - mean).abs() + (fx[20 - j] - mean).abs());
    }
    let (resk, resabs, resasc) = (resk * h, resabs * h.abs(), resasc * h.abs());
    let mut err = ((resk - resg * h).abs()).abs();
    if resasc != 0.0 && err != 0.0 {
        err = resasc * (200.0 * err / resasc).powf(1.5).min(1.0);
    }
    let mut floor = err == 0.0;
    if resabs > f64::MIN_POSITIVE / (50.0 * f64::EPSILON) {
        let round = 50.0 * f64::EPSILON * resabs;
        if round >= err {
            err = round;
            floor = true;
        }
    }
    (resk, err, floor)
}

/// One G10–K21 panel: `(integral estimate, QUADPACK error estimate)` of `f` over `[a, b]`.
pub fn gauss_kronrod_21<F: FnMut(f64) -> f64>(f: &mut F, a: f64, b: f64) -> (f64, f64) {
    let x = gk21_nodes(a, b);
    let fx = x.map(&mut *f);
    let (value, error, _) = gk21_from_values(a, b, &fx);
    (value, error)
}

/// A panel of the globally adaptive scheme, ordered by its error estimate.
#[derive(Debug, Clone, Copy)]
struct Panel {
    a: f64,
    b: f64,
    value: f64,
    error: f64,
    depth: u32,
    /// The error estimate is the rounding floor (or exactly zero): never bisect.
    floor: bool,
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
    !p.floor && p.depth < MAX_DEPTH && m > p.a && m < p.b
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
        let (mut v, mut e) = (0.0, 0.0);
        for p in heap.iter().chain(frozen.iter()) {
            v += p.value;
            e += p.error;
        }
        (v, e)
    };
    let (mut value, mut error) = sums(&heap, &frozen);
    let mut converged = true;
    loop {
        if error <= abs_tol.max(rel_tol * value.abs()) {
            // Re-sum exactly to remove drift of the running sums before accepting.
            (value, error) = sums(&heap, &frozen);
            if error <= abs_tol.max(rel_tol * value.abs()) {
                break;
            }
        }
        let Some(worst) = heap.pop() else {
            converged = false;
            break;
        };
        if heap.len() + frozen.len() > MAX_PANELS {
            heap.push(worst);
            converged = false;
            break;
        }
        let m = 0.5 * (worst.a + worst.b);
        let mut children = eval(worst.a, m, worst.depth + 1);
        children.extend(eval(m, worst.b, worst.depth + 1));
        value -= worst.value;
        error -= worst.error;
        for c in children {
            value += c.value;
            error += c.error;
            if splittable(&c) {
                heap.push(c);
            } else {
                frozen.push(c);
            }
        }
    }
    let (value, error) = sums(&heap, &frozen);
    Quadrature {
        value,
        error,
        evaluations: evaluations(),
        converged,
    }
}

/// Adaptive G10–K21 quadrature of `f` over `[points[0], points[last]]`, integrating piecewise
/// between the given breakpoints (any order, duplicates allowed; the integral runs from the
/// smallest to the largest). Stops when the summed QUADPACK error estimate is at most
/// `max(abs_tol, rel_tol |value|)`, or when no panel can be bisected further ([`MAX_DEPTH`]).
pub fn integrate<F: FnMut(f64) -> f64>(
    f: F,
    points: &[f64],
    abs_tol: f64,
    rel_tol: f64,
) -> Quadrature {
    let pts = sorted_points(points);
    let count = std::cell::Cell::new(0usize);
    let f = std::cell::RefCell::new(f);
    let eval = |a: f64, b: f64, depth: u32| {
        let x = gk21_nodes(a, b);
        let mut g = f.borrow_mut();
        let fx = x.map(|t| (*g)(t));
        count.set(count.get() + 21);
        let (value, error, floor) = gk21_from_values(a, b, &fx);
        vec![Panel {
            a,
            b,
            value,
            error,
            depth,
            floor,
        }]
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

/// Root of `f` in `(x0, x1)` given `f(x0) = f0`, `f(x1) = f1` of opposite signs, by the Illinois
/// (modified regula falsi) method, which keeps the root bracketed. Stops at bracket width `xtol`.
fn illinois<F: FnMut(f64) -> f64>(
    f: &mut F,
    mut x0: f64,
    mut f0: f64,
    mut x1: f64,
    mut f1: f64,
    xtol: f64,
) -> f64 {
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
/// Every panel's 21 nodes are checked for a sign change of `f`; where one is found the root is
/// located (Illinois) and the panel replaced by the two panels on either side of it, so that
/// `|f|` is smooth on every panel that is accepted. Sign changes that fall between nodes are
/// still handled correctly (the kink makes the error estimate large and the panel is bisected).
pub fn integrate_modulus<F: FnMut(f64) -> f64, P: Fn(f64) -> f64>(
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
            let x = gk21_nodes(a, b);
            let mut g = f.borrow_mut();
            let fx = x.map(|t| (*g)(t));
            count.set(count.get() + 21);
            let change = (0..20).find(|&i| (fx[i] > 0.0 && fx[i + 1] < 0.0) || (fx[i] < 0.0 && fx[i + 1] > 0.0));
            match change {
                Some(i) if depth < MAX_DEPTH => {
                    let mut counted = |t: f64| {
                        count.set(count.get() + 1);
                        (*g)(t)
                    };
                    let r = illinois(&mut counted, x[i], fx[i], x[i + 1], fx[i + 1], xtol);
                    if r > a && r < b {
                        todo.push((a, r, depth + 1));
                        todo.push((r, b, depth + 1));
                        continue;
                    }
                    let gx: [f64; 21] = std::array::from_fn(|k| weight(x[k]) * fx[k].abs());
                    let (value, error, floor) = gk21_from_values(a, b, &gx);
                    out.push(Panel {
                        a,
                        b,
                        value,
                        error,
                        depth,
                        floor,
                    });
                }
                _ => {
                    let gx: [f64; 21] = std::array::from_fn(|k| weight(x[k]) * fx[k].abs());
                    let (value, error, floor) = gk21_from_values(a, b, &gx);
                    out.push(Panel {
                        a,
                        b,
                        value,
                        error,
                        depth,
                        floor,
                    });
                }
            }
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

/// Initial panels per oscillation period (in `y` for the OTF, in `λ` for the spectral integral).
const PANELS_PER_PERIOD: f64 = 1.0;

/// `sin(x)/x`, equal to 1 at `x = 0`. (`sin` has full relative accuracy, so no series is needed.)
fn sinc(x: f64) -> f64 {
    if x == 0.0 { 1.0 } else { x.sin() / x }
}

/// Exact OTF of a circular pupil with defocus `w` (waves at the pupil edge) at normalized
/// frequency `s = ν/ν_c`, from PHYSICS.md as printed:
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
    // (i) equal steps of the phase a(c − s), at most one period per panel;
    // (ii) c = 2s, 4s, 8s, … grading towards the branch point of √(1−y²) at y = 1 (c = 0),
    //      which lies just beyond y_max when s is small.
    let periods = a.abs() * (1.0 - s) / (2.0 * PI);
    let n = (periods * PANELS_PER_PERIOD).ceil().max(1.0) as usize;
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
    let q = integrate(integrand, &ys, abs_tol * PI / 4.0, 0.0);
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
    /// Defocus at the pupil edge in waves, `w(λ) = (λ/λ0 − 1) f0 / (8 F#²) / λ`.
    pub fn defocus_waves(&self, lambda: f64) -> f64 {
        (lambda / self.design_wavelength_m - 1.0) * self.focal_length_m
            / (8.0 * self.f_number * self.f_number)
            / lambda
    }

    /// Nyquist frequency `ν_N = 1/(2p)` (cycles/m).
    pub fn nyquist(&self) -> f64 {
        0.5 / self.pixel_pitch_m
    }

    /// `∫ ρ(λ) dλ` over the range, to full precision.
    fn norm(&self) -> f64 {
        let pts = self.lambda_points(self.lambda_min, self.lambda_max);
        let n = 64;
        let mut fine = Vec::new();
        for w in pts.windows(2) {
            fine.extend((0..n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        }
        fine.push(self.lambda_max);
        integrate(|l| (self.density)(l), &fine, 0.0, 1e-14).value
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
        let hi = if nu > 0.0 {
            self.lambda_max.min(1.0 / (nu * fnum))
        } else {
            self.lambda_max
        };
        if hi <= lo || norm == 0.0 {
            return 0.0;
        }
        // Panels of at most one period of the OTF's oscillation in λ: a = 8π w s is linear in λ
        // with slope da/dλ = π ν f0/(F# λ0); at least 8 panels per piece.
        let slope = PI * nu * self.focal_length_m / (fnum * self.design_wavelength_m);
        let mut pts = Vec::new();
        for w in self.lambda_points(lo, hi).windows(2) {
            let periods = slope * (w[1] - w[0]) / (2.0 * PI);
            let n = ((periods * PANELS_PER_PERIOD).ceil() as usize).max(8);
            pts.extend((0..n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        }
        pts.push(hi);
        // Error budget (normalized): quadrature 0.5 tol, OTF 0.2 tol, density cut 0.05 tol.
        // The cut is rigorous: |OTF| ≤ 1, so dropping ρ ≤ θ changes the integral by ≤ θ (hi − lo).
        let theta = 0.05 * tol * norm / (hi - lo);
        let otf_tol = 0.2 * tol;
        let integrand = |l: f64| {
            let r = (self.density)(l);
            if r.abs() <= theta {
                0.0
            } else {
                r * otf_defocus_tol(nu * l * fnum, self.defocus_waves(l), otf_tol)
            }
        };
        integrate(integrand, &pts, 0.5 * tol * norm, 0.0).value / norm
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
            |nu| self.poly_otf_abs(nu, inner_tol, norm),
            weight,
            &pts,
            0.1 * inner_tol * nu_n,
            rel_tol,
        )
    }
}

/// Polychromatic OTF `∫ ρ(λ) OTF(ν λ F#, w(λ)) dλ / ∫ ρ(λ) dλ` at frequency `nu` (cycles/m):
/// the signed, photoelectron-weighted sum of the monochromatic OTFs (PHYSICS.md
/// "Polychromatic OTF"). Error target `rel_tol · max(|OTF_poly|, 1e-3)`.
pub fn polychromatic_otf(scene: &ReferenceScene<'_>, nu: f64, rel_tol: f64) -> f64 {
    let norm = scene.norm();
    let rough = scene.poly_otf_abs(nu, 1e-6, norm);
    let tol = rel_tol * rough.abs().max(1e-3);
    scene.poly_otf_abs(nu, tol, norm)
}

/// Mean MTF up to Nyquist, `(1/ν_N) ∫_0^{ν_N} P(ν) |OTF_poly(ν)| dν` with
/// `P(ν) = |sin(π p ν)/(π p ν)|` if `pixel_mtf`, else 1 (paper eq. 1 divided by SNR0 ν_N).
/// Relative error target `rel_tol`.
pub fn mean_mtf(scene: &ReferenceScene<'_>, rel_tol: f64) -> f64 {
    mean_mtf_quadrature(scene, rel_tol).value
}

/// [`mean_mtf`] with the outer quadrature's error estimate and evaluation count (of OTF_poly),
/// both already divided by `ν_N` where applicable.
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
            return Quadrature {
                value: m,
                error: q.error / nu_n,
                ..q
            };
        }
        scale = 0.5 * m;
    }
}
