//! Composite Gauss–Legendre quadrature with a fixed rule per panel, and single Gauss–Legendre
//! and Gauss–Hermite rules of any order (for the accuracy report's fixed-order comparisons).
//!
//! Every integral in the fast path is a sum of panels, each integrated with the same
//! [`ORDER`]-point Gauss–Legendre rule (nodes from `gauss-quad`, Bogaert's algorithm). The
//! panel count, not the rule order, grows with the oscillation of the integrand: that keeps
//! the error bound uniform (a panel whose integrand turns through at most [`MAX_PANEL_PHASE`]
//! radians is integrated to about 1e-16) and the nodes cacheable.

use std::num::NonZeroUsize;
use std::sync::OnceLock;

/// Points of the Gauss–Legendre rule used on every panel.
pub const ORDER: usize = 16;

/// Largest phase (radians) of an oscillatory factor `cos(phase)` across one panel.
///
/// A 16-point Gauss–Legendre rule integrates `exp(i k x)` on `[-1, 1]` with an error of about
/// `(e k / 32)^32`; a panel phase of 12 rad is `k = 6`, an error below 1e-18.
pub const MAX_PANEL_PHASE: f64 = 12.0;

/// The [`ORDER`]-point rule on `[-1, 1]`: `(node, weight)` pairs, nodes ascending.
pub fn rule() -> &'static [(f64, f64); ORDER] {
    static RULE: OnceLock<[(f64, f64); ORDER]> = OnceLock::new();
    RULE.get_or_init(|| {
        let mut out = [(0.0, 0.0); ORDER];
        out.copy_from_slice(&gauss_legendre(ORDER));
        out
    })
}

/// The `n`-point Gauss–Legendre rule on `[-1, 1]` (`n ≥ 1`; 0 is taken as 1): `(node, weight)`
/// pairs, nodes ascending, exact for polynomials of degree `2n − 1`. Nodes and weights from
/// `gauss-quad` (Bogaert's O(n) algorithm, accurate to rounding for any `n`).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let n = NonZeroUsize::new(n).unwrap_or(NonZeroUsize::MIN);
    let mut pairs = gauss_quad::legendre::GaussLegendre::new(n).as_node_weight_pairs().to_vec();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs
}

/// The `n`-point Gauss–Hermite rule for `∫_{−∞}^{∞} e^{−x²} f(x) dx ≈ Σ wᵢ f(xᵢ)` (`n ≥ 1`; 0 is
/// taken as 1): `(node, weight)` pairs, nodes ascending, exact for polynomials `f` of degree
/// `2n − 1`. A Gaussian spectrum of centre μ and standard deviation σ takes the nodes
/// `λᵢ = μ + √2 σ xᵢ`.
///
/// Golub–Welsch (the eigenvalues of the Jacobi matrix, from `gauss-quad`) gives the nodes to a
/// few ulps of the largest; each is then polished by Newton's method on the orthonormal Hermite
/// recurrence (Press et al., *Numerical Recipes*, 3rd ed., §4.6, `gauher`)
///
/// ```text
/// p₀ = π^{−1/4},  p₁ = √2 x p₀,  pⱼ = √(2/j) x pⱼ₋₁ − √((j−1)/j) pⱼ₋₂,  pₙ' = √(2n) pₙ₋₁,
/// ```
///
/// and the weight taken from the same recurrence, `wᵢ = 2/pₙ'(xᵢ)²`, which keeps its relative
/// accuracy even for the outermost nodes (weights down to 1e-300), where the eigenvector form of
/// Golub–Welsch only has absolute accuracy. The recurrence is run on `pⱼ e^{−x²/2}`, which stays
/// of order one, so nothing overflows for `n` up to several hundred.
pub fn gauss_hermite(n: usize) -> Vec<(f64, f64)> {
    let n = NonZeroUsize::new(n).unwrap_or(NonZeroUsize::MIN);
    let m = n.get();
    // (pₙ, pₙ₋₁) e^{−x²/2}
    let scaled = |x: f64| {
        let (mut prev, mut cur) = (0.0, std::f64::consts::PI.powf(-0.25) * (-0.5 * x * x).exp());
        for j in 1..=m {
            let j = j as f64;
            let next = (2.0 / j).sqrt() * x * cur - ((j - 1.0) / j).sqrt() * prev;
            prev = cur;
            cur = next;
        }
        (cur, prev)
    };
    let initial = gauss_quad::hermite::GaussHermite::new(n);
    let mut pairs: Vec<(f64, f64)> = initial
        .as_node_weight_pairs()
        .iter()
        .map(|&(x0, _)| {
            let mut x = x0;
            for _ in 0..8 {
                let (p, q) = scaled(x);
                let step = p / ((2.0 * m as f64).sqrt() * q);
                x -= step;
                if step.abs() <= 4.0 * f64::EPSILON * x.abs().max(1.0) {
                    break;
                }
            }
            // wᵢ = 2/pₙ'² = 2/(2n pₙ₋₁²) = e^{−x²}/(n (pₙ₋₁ e^{−x²/2})²)
            let q = scaled(x).1;
            (x, (-x * x).exp() / (m as f64 * q * q))
        })
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs
}

/// Points per panel of the fixed frequency rule on FFT grids ([`composite_fixed`]): its panels
/// are half of the finest grid cell, and the bicubic interpolant is smooth inside a cell. Four
/// points on half cells (8 OTF readings a cell) moved the mean over azimuth of 0.5 µm coma on
/// the paper scene (`cargo test -p asnr-metric --test metric fft_path_with_an_aliased`) by
/// 1.4e-8, 9e-9 and 9e-10 at N = 128, 256 and 512 against the former 8 points on quarter cells
/// (32 readings a cell), far below the FFT path's own error, for a quarter of the readings
/// (one full cell of 4 points: 6.6e-8 at N = 128; at quarter cells 4 points had moved coma by
/// 2e-9 and the concentric segmented lens by 6e-9 at N = 256).
pub const FIXED_ORDER: usize = 4;

/// Integrates `f` over `[a, b]` with `panels` equal panels of the [`FIXED_ORDER`]-point rule.
pub fn composite_fixed<F: FnMut(f64) -> f64>(a: f64, b: f64, panels: usize, mut f: F) -> f64 {
    static RULE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    let rule = RULE.get_or_init(|| gauss_legendre(FIXED_ORDER));
    let panels = panels.max(1);
    let h = (b - a) / panels as f64;
    let mut total = 0.0;
    for p in 0..panels {
        let mid = a + h * (p as f64 + 0.5);
        let sum: f64 = rule.iter().map(|&(x, w)| w * f(mid + 0.5 * h * x)).sum();
        total += 0.5 * h * sum;
    }
    total
}

/// Integrates `f` over `[a, b]` with `panels` equal panels of the [`ORDER`]-point rule.
pub fn composite<F: FnMut(f64) -> f64>(a: f64, b: f64, panels: usize, mut f: F) -> f64 {
    let panels = panels.max(1);
    let h = (b - a) / panels as f64;
    let rule = rule();
    let mut total = 0.0;
    for p in 0..panels {
        let lo = a + h * p as f64;
        let mid = lo + 0.5 * h;
        let mut sum = 0.0;
        for &(x, w) in rule {
            sum += w * f(mid + 0.5 * h * x);
        }
        total += 0.5 * h * sum;
    }
    total
}

/// Calls `visit(x, weight)` for every node of `panels` equal panels on `[a, b]`.
pub fn for_each_node<F: FnMut(f64, f64)>(a: f64, b: f64, panels: usize, mut visit: F) {
    let panels = panels.max(1);
    let h = (b - a) / panels as f64;
    for p in 0..panels {
        let mid = a + h * (p as f64 + 0.5);
        for &(x, w) in rule() {
            visit(mid + 0.5 * h * x, 0.5 * h * w);
        }
    }
}

/// `cos(πi/128)` for `i = 0 … 255`, a whole turn: `cos(πm/n)` for any `n` dividing 128 (the
/// nested Chebyshev–Lobatto levels to 129 points) is entry `m · 128/n`, for `m < 2n`, with no
/// cosine computed and no reflection.
pub fn turn_cosines() -> &'static [f64; 256] {
    static COSINES: std::sync::OnceLock<[f64; 256]> = std::sync::OnceLock::new();
    COSINES.get_or_init(|| std::array::from_fn(|i| (std::f64::consts::PI * i as f64 / 128.0).cos()))
}

/// `sum + Σ_t terms[t] cos(π i_t / n)` with `i_t = first + t · step` taken mod `2n` (`first,
/// step ≤ 2n`): the cosine sums of Chebyshev–Lobatto points, `cos(πjk/n)`, from
/// [`turn_cosines`] where `n` divides 128 (every nested level: entry `i · 128/n` mod 256, a mask
/// and no branch a term), computed otherwise. Four partial sums (one chain of dependent adds
/// is bound by their latency), added pairwise at the end.
pub fn add_stepped_cosines(sum: f64, terms: &[f64], first: usize, step: usize, n: usize) -> f64 {
    let mut sums = [sum, 0.0, 0.0, 0.0];
    if 128 % n == 0 {
        let table = turn_cosines();
        let stride = 128 / n;
        let (mut i, step) = ((first * stride) & 255, (step * stride) & 255);
        let mut chunks = terms.chunks_exact(4);
        for chunk in &mut chunks {
            for (slot, &t) in sums.iter_mut().zip(chunk) {
                *slot += t * table[i];
                i = (i + step) & 255;
            }
        }
        for &t in chunks.remainder() {
            sums[0] += t * table[i];
            i = (i + step) & 255;
        }
    } else {
        let period = 2 * n;
        let mut i = first % period;
        for (t, &term) in terms.iter().enumerate() {
            sums[t % 4] += term * (std::f64::consts::PI * i as f64 / n as f64).cos();
            i = (i + step) % period;
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3])
}

/// `a · b + c`: one fused multiply-add (one rounding) where the build targets a CPU that has
/// the instruction (`target-cpu=native` on x86-64 with FMA, `.cargo/config.toml`; every
/// aarch64), else a multiply and an add (two roundings; `f64::mul_add` would call the C
/// library's `fma` there, a function call a term). The inner loops of the exact OTF use it:
/// where they are bound by the floating-point ports, a fused pair is one operation, not two.
/// The two forms differ by at most one rounding of `a · b`: results agree between builds to
/// rounding, not to the bit.
#[inline(always)]
pub fn fused(a: f64, b: f64, c: f64) -> f64 {
    if cfg!(any(target_feature = "fma", target_arch = "aarch64")) { a.mul_add(b, c) } else { a * b + c }
}

/// `Σ a_k b_k` over the shorter of the two, in four partial sums added pairwise at the end (one
/// chain of dependent adds is bound by their latency: a product rule's 33-point sum took as long
/// as its products four times over).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut sums = [0.0; 4];
    let (chunks_a, chunks_b) = (a.chunks_exact(4), b.chunks_exact(4));
    let (rest_a, rest_b) = (chunks_a.remainder(), chunks_b.remainder());
    for (x, y) in chunks_a.zip(chunks_b) {
        for l in 0..4 {
            sums[l] += x[l] * y[l];
        }
    }
    for (slot, (x, y)) in sums.iter_mut().zip(rest_a.iter().zip(rest_b)) {
        *slot += x * y;
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3])
}

/// Coefficients at the end of a nested Clenshaw–Curtis level that [`chebyshev_tail`] reads as
/// its tail, and as many before them for its rate of decay.
pub const TAIL: usize = 4;

/// The fastest decay rate per degree [`chebyshev_tail`] (and the estimates built on
/// [`chebyshev_tail_parts`]) still read as a falling tail: above it the coefficients are not
/// falling, and no bound follows.
pub const TAIL_MAX_RATE: f64 = 0.8;

/// The size of the Chebyshev coefficients a level of `values` cannot hold, from those it holds
/// (Trefethen, *Approximation Theory and Approximation Practice*, ch. 8 and 19).
///
/// `values` are a function at the `n = 2^k + 1` Chebyshev–Lobatto points `x_k = cos(πk/(n − 1))`
/// (`k = 0` at `x = 1`; `n ≤ 129`). Their interpolant's coefficients `c_j` are the cosine
/// transform of the values; an integral of the interpolant against a weight with Chebyshev
/// moments `μ_j` is off by `Σ_{j ≥ n} c_j (μ_j − μ_{2(n−1)−j})` (each coefficient the points
/// cannot hold aliased onto a degree below `n − 1`). The last [`TAIL`] coefficients give the
/// size of the tail and, against the [`TAIL`] before them, its rate of decay `r` per degree;
/// the coefficients left out are then at most `size · r^i`, and with their aliases sum to at
/// most `2 · size · r/(1 − r)`, which is returned: times a bound on the moments near degree
/// `n`, a bound on the integral's error. Infinite below `2 TAIL + 1` points or where the
/// coefficients do not fall (`r ≥ 0.8`), zero where the last ones are. A geometric tail is an
/// assumption (the nested estimate makes it too): the level must resolve the integrand's
/// oscillation for it to be trusted.
pub fn chebyshev_tail(values: &[f64]) -> f64 {
    match chebyshev_tail_parts(values) {
        Some((size, rate)) if rate < TAIL_MAX_RATE => 2.0 * size * rate / (1.0 - rate),
        _ => f64::INFINITY,
    }
}

/// The size of the last [`TAIL`] Chebyshev coefficients of `values` and their rate of decay per
/// degree against the [`TAIL`] before them ([`chebyshev_tail`], which sums them), or `None`
/// where the level is too short or not a nested one (`2^k + 1` points). A size of 0 has rate 0.
pub fn chebyshev_tail_parts(values: &[f64]) -> Option<(f64, f64)> {
    let n = values.len();
    if !(2 * TAIL + 1..=129).contains(&n) || !(n - 1).is_power_of_two() {
        return None;
    }
    let m = n - 1;
    let coefficient = |j: usize| {
        // Σ'' v_k cos(πjk/m): the halved ends, then k = 1 … m − 1
        let ends = 0.5 * (values[0] + if j.is_multiple_of(2) { values[m] } else { -values[m] });
        let sum = add_stepped_cosines(ends, &values[1..m], j, j, m);
        (if j == m { 0.5 } else { 1.0 }) * 2.0 / m as f64 * sum.abs()
    };
    let size = (n - TAIL..n).map(coefficient).fold(0.0, f64::max);
    if size == 0.0 {
        return Some((0.0, 0.0));
    }
    let before = (n - 2 * TAIL..n - TAIL).map(coefficient).fold(0.0, f64::max);
    // the fourth root ([`TAIL`] = 4) by two square roots, not `powf`
    const _: () = assert!(TAIL == 4);
    let rate = (size / before).sqrt().sqrt();
    Some((size, if rate.is_nan() { f64::INFINITY } else { rate }))
}

/// A zero of `f` in `[x0, x1]`, where `f0 = f(x0)` and `f1 = f(x1)` have opposite signs: the
/// Illinois variant of regula falsi with a bisection safeguard, to `tol` in `x`. A non-finite
/// value ends the search at its abscissa (a lens whose order count changes inside a panel).
pub fn illinois(f: &mut dyn FnMut(f64) -> f64, mut x0: f64, mut f0: f64, mut x1: f64, mut f1: f64, tol: f64) -> f64 {
    let mut side = 0;
    for _ in 0..200 {
        if (x1 - x0).abs() <= tol {
            break;
        }
        let mut x = (x0 * f1 - x1 * f0) / (f1 - f0);
        if !(x > x0.min(x1) && x < x0.max(x1)) {
            x = 0.5 * (x0 + x1);
        }
        let fx = f(x);
        if fx == 0.0 || !fx.is_finite() {
            return x;
        }
        if fx * f1 < 0.0 {
            x0 = x1;
            f0 = f1;
            side = 0;
        } else {
            side += 1;
            if side >= 2 {
                f0 *= 0.5;
            }
        }
        x1 = x;
        f1 = fx;
    }
    0.5 * (x0 + x1)
}

// Gauss–Kronrod pairs (QUADPACK dqk15 / dqk21 / dqk61 constants, Piessens et al. 1983, computed by
// L. W. Fullerton with 80-digit arithmetic; checked by polynomial exactness in the reference's
// tests). The fast path and `reference` share the constants, not the algorithms.

/// A Gauss–Kronrod pair on [-1, 1] in QUADPACK layout: `xgk` are the non-negative Kronrod
/// abscissae in descending order ending with 0; `xgk[1], xgk[3], …` are the Gauss abscissae (the
/// Gauss rule has an even number of points, so 0 is a Kronrod-only node); `wgk` are the Kronrod
/// weights matching `xgk`; `wg[j]` is the Gauss weight of `xgk[2j + 1]`.
#[derive(Debug, Clone, Copy)]
pub struct GaussKronrod {
    xgk: &'static [f64],
    wgk: &'static [f64],
    wg: &'static [f64],
}

impl GaussKronrod {
    /// Number of points of the Kronrod rule.
    pub fn points(&self) -> usize {
        2 * self.xgk.len() - 1
    }

    /// Nodes of the Kronrod rule mapped to `[a, b]`, ascending; only the first
    /// [`points`](Self::points) entries are used.
    pub fn nodes(&self, a: f64, b: f64) -> [f64; MAX_POINTS] {
        let m = self.xgk.len() - 1;
        let c = 0.5 * (a + b);
        let h = 0.5 * (b - a);
        let mut x = [0.0; MAX_POINTS];
        for j in 0..m {
            x[j] = c - h * self.xgk[j];
            x[2 * m - j] = c + h * self.xgk[j];
        }
        x[m] = c;
        x
    }

    /// The Kronrod weights on `[-1, 1]` in the order of [`nodes`](Self::nodes) (times the
    /// half-width, the weights of the panel's Kronrod sum).
    pub fn kronrod_weights(&self) -> [f64; MAX_POINTS] {
        let m = self.xgk.len() - 1;
        let mut w = [0.0; MAX_POINTS];
        for j in 0..m {
            w[j] = self.wgk[j];
            w[2 * m - j] = self.wgk[j];
        }
        w[m] = self.wgk[m];
        w
    }

    /// The Kronrod and Gauss sums, `resabs` (`∫|f|`) and `resasc` (`∫|f − mean|`) of one panel of
    /// half-width `half` from the function values at [`nodes`](Self::nodes).
    pub fn sums(&self, half: f64, fx: &[f64]) -> Sums {
        let m = self.xgk.len() - 1;
        let mut resk = self.wgk[m] * fx[m];
        let mut resabs = self.wgk[m] * fx[m].abs();
        let mut resg = 0.0;
        for j in 0..m {
            let pair = fx[j] + fx[2 * m - j];
            resk += self.wgk[j] * pair;
            resabs += self.wgk[j] * (fx[j].abs() + fx[2 * m - j].abs());
            if j % 2 == 1 {
                resg += self.wg[j / 2] * pair;
            }
        }
        if 2 * self.wg.len() > m {
            // an odd Gauss rule (G7): the centre is a Gauss node too
            resg += self.wg[m / 2] * fx[m];
        }
        let mean = 0.5 * resk;
        let mut resasc = self.wgk[m] * (fx[m] - mean).abs();
        for j in 0..m {
            resasc += self.wgk[j] * ((fx[j] - mean).abs() + (fx[2 * m - j] - mean).abs());
        }
        let h = half.abs();
        Sums { kronrod: resk * half, gauss: resg * half, resabs: resabs * h, resasc: resasc * h }
    }

    /// Kronrod value, QUADPACK error estimate and rounding floor `50 ε ∫|f|` of one panel from
    /// the function values at [`nodes`](Self::nodes). The error estimate is never below the floor.
    pub fn estimate(&self, a: f64, b: f64, fx: &[f64]) -> (f64, f64, f64) {
        let s = self.sums(0.5 * (b - a), fx);
        let mut err = s.error();
        let mut round = 0.0;
        if s.resabs > f64::MIN_POSITIVE / (50.0 * f64::EPSILON) {
            round = 50.0 * f64::EPSILON * s.resabs;
            err = err.max(round);
        }
        (s.kronrod, err, round)
    }

    /// One panel: `(integral estimate, QUADPACK error estimate)` of `f` over `[a, b]`.
    pub fn panel<F: FnMut(f64) -> f64>(&self, mut f: F, a: f64, b: f64) -> (f64, f64) {
        let n = self.points();
        let x = self.nodes(a, b);
        let mut fx = [0.0; MAX_POINTS];
        for k in 0..n {
            fx[k] = f(x[k]);
        }
        let (value, error, _) = self.estimate(a, b, &fx[..n]);
        (value, error)
    }
}

/// Largest number of points of the rules below.
pub const MAX_POINTS: usize = 61;

/// The G7–K15 pair (QUADPACK `dqk15`).
#[allow(clippy::excessive_precision)]
pub const GK15: GaussKronrod = GaussKronrod {
    xgk: &[
        0.991_455_371_120_812_639_206_854_697_526_329,
        0.949_107_912_342_758_524_526_189_684_047_851,
        0.864_864_423_359_769_072_789_712_788_640_926,
        0.741_531_185_599_394_439_863_864_773_280_788,
        0.586_087_235_467_691_130_294_144_845_693_013,
        0.405_845_151_377_397_166_906_606_412_076_961,
        0.207_784_955_007_898_467_600_689_403_773_245,
        0.0,
    ],
    wgk: &[
        0.022_935_322_010_529_224_963_732_008_058_970,
        0.063_092_092_629_978_553_290_700_663_189_204,
        0.104_790_010_322_250_183_839_876_322_541_518,
        0.140_653_259_715_525_918_745_189_590_510_238,
        0.169_004_726_639_267_902_826_583_426_598_550,
        0.190_350_578_064_785_409_913_256_402_421_014,
        0.204_432_940_075_298_892_414_161_999_234_649,
        0.209_482_141_084_727_828_012_999_174_891_714,
    ],
    wg: &[
        0.129_484_966_168_869_693_270_611_432_679_082,
        0.279_705_391_489_276_667_901_467_771_423_780,
        0.381_830_050_505_118_944_950_369_775_488_975,
        0.417_959_183_673_469_387_755_102_040_816_327,
    ],
};

/// The G10–K21 pair (QUADPACK `dqk21`).
// The 33-digit QUADPACK values are kept as published (rounded to f64 by the compiler).
#[allow(clippy::excessive_precision)]
pub const GK21: GaussKronrod = GaussKronrod {
    xgk: &[
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
    ],
    wgk: &[
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
    ],
    wg: &[
        0.066_671_344_308_688_137_593_568_809_893_332,
        0.149_451_349_150_580_593_145_776_339_657_697,
        0.219_086_362_515_982_043_995_534_934_228_163,
        0.269_266_719_309_996_355_091_226_921_569_469,
        0.295_524_224_714_752_870_173_892_994_651_338,
    ],
};

/// The G30–K61 pair (QUADPACK `dqk61`).
// The 33-digit QUADPACK values are kept as published (rounded to f64 by the compiler).
#[allow(clippy::excessive_precision)]
pub const GK61: GaussKronrod = GaussKronrod {
    xgk: &[
        0.999_484_410_050_490_637_571_325_895_705_811,
        0.996_893_484_074_649_540_271_630_050_918_695,
        0.991_630_996_870_404_594_858_628_366_109_486,
        0.983_668_123_279_747_209_970_032_581_605_663,
        0.973_116_322_501_126_268_374_693_868_423_707,
        0.960_021_864_968_307_512_216_871_025_581_798,
        0.944_374_444_748_559_979_415_831_324_037_439,
        0.926_200_047_429_274_325_879_324_277_080_474,
        0.905_573_307_699_907_798_546_522_558_925_958,
        0.882_560_535_792_052_681_543_116_462_530_226,
        0.857_205_233_546_061_098_958_658_510_658_944,
        0.829_565_762_382_768_397_442_898_119_732_502,
        0.799_727_835_821_839_083_013_668_942_322_683,
        0.767_777_432_104_826_194_917_977_340_974_503,
        0.733_790_062_453_226_804_726_171_131_369_528,
        0.697_850_494_793_315_796_932_292_388_026_640,
        0.660_061_064_126_626_961_370_053_668_149_271,
        0.620_526_182_989_242_861_140_477_556_431_189,
        0.579_345_235_826_361_691_756_024_932_172_540,
        0.536_624_148_142_019_899_264_169_793_311_073,
        0.492_480_467_861_778_574_993_693_061_207_709,
        0.447_033_769_538_089_176_780_609_900_322_854,
        0.400_401_254_830_394_392_535_476_211_542_661,
        0.352_704_725_530_878_113_471_037_207_089_374,
        0.304_073_202_273_625_077_372_677_107_199_257,
        0.254_636_926_167_889_846_439_805_129_817_805,
        0.204_525_116_682_309_891_438_957_671_002_025,
        0.153_869_913_608_583_546_963_794_672_743_256,
        0.102_806_937_966_737_030_147_096_751_318_001,
        0.051_471_842_555_317_695_833_025_213_166_723,
        0.0,
    ],
    wgk: &[
        0.001_389_013_698_677_007_624_551_591_226_760,
        0.003_890_461_127_099_884_051_267_201_844_516,
        0.006_630_703_915_931_292_173_319_826_369_750,
        0.009_273_279_659_517_763_428_441_146_892_024,
        0.011_823_015_253_496_341_742_232_898_853_251,
        0.014_369_729_507_045_804_812_451_432_443_580,
        0.016_920_889_189_053_272_627_572_289_420_322,
        0.019_414_141_193_942_381_173_408_951_050_128,
        0.021_828_035_821_609_192_297_167_485_738_339,
        0.024_191_162_078_080_601_365_686_370_725_232,
        0.026_509_954_882_333_101_610_601_709_335_075,
        0.028_754_048_765_041_292_843_978_785_354_334,
        0.030_907_257_562_387_762_472_884_252_943_092,
        0.032_981_447_057_483_726_031_814_191_016_854,
        0.034_979_338_028_060_024_137_499_670_731_468,
        0.036_882_364_651_821_229_223_911_065_617_136,
        0.038_678_945_624_727_592_950_348_651_532_281,
        0.040_374_538_951_535_959_111_995_279_752_468,
        0.041_969_810_215_164_246_147_147_541_285_970,
        0.043_452_539_701_356_069_316_831_728_117_073,
        0.044_814_800_133_162_663_192_355_551_616_723,
        0.046_059_238_271_006_988_116_271_735_559_374,
        0.047_185_546_569_299_153_945_261_478_181_099,
        0.048_185_861_757_087_129_140_779_492_298_305,
        0.049_055_434_555_029_778_887_528_165_367_238,
        0.049_795_683_427_074_206_357_811_569_379_942,
        0.050_405_921_402_782_346_840_893_085_653_585,
        0.050_881_795_898_749_606_492_297_473_049_805,
        0.051_221_547_849_258_772_170_656_282_604_944,
        0.051_426_128_537_459_025_933_862_879_215_781,
        0.051_494_729_429_451_567_558_340_433_647_099,
    ],
    wg: &[
        0.007_968_192_496_166_605_615_465_883_474_674,
        0.018_466_468_311_090_959_142_302_131_912_047,
        0.028_784_707_883_323_369_349_719_179_611_292,
        0.038_799_192_569_627_049_596_801_936_446_348,
        0.048_402_672_830_594_052_902_938_140_422_808,
        0.057_493_156_217_619_066_481_721_689_402_056,
        0.065_974_229_882_180_495_128_128_515_115_962,
        0.073_755_974_737_705_206_268_243_850_022_191,
        0.080_755_895_229_420_215_354_694_938_460_530,
        0.086_899_787_201_082_979_802_387_530_715_126,
        0.092_122_522_237_786_128_717_632_707_087_619,
        0.096_368_737_174_644_259_639_468_626_351_810,
        0.099_593_420_586_795_267_062_780_282_103_569,
        0.101_762_389_748_405_504_596_428_952_168_554,
        0.102_852_652_893_558_840_341_285_636_705_415,
    ],
};

/// The sums of one Gauss–Kronrod panel ([`GaussKronrod::sums`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sums {
    /// The Kronrod sum: the panel's integral.
    pub kronrod: f64,
    /// The embedded Gauss sum.
    pub gauss: f64,
    /// QUADPACK's `resabs`: the Kronrod integral of `|f|`.
    pub resabs: f64,
    /// QUADPACK's `resasc`: the Kronrod integral of `|f − mean|`, the panel's variation.
    pub resasc: f64,
}

impl Sums {
    /// QUADPACK's error estimate `resasc · min(1, (200 |K − G| / resasc)^1.5)`: `|K − G|`
    /// overstates the Kronrod error on smooth panels, where it falls as a power of the ratio.
    pub fn error(&self) -> f64 {
        let error = (self.kronrod - self.gauss).abs();
        if self.resasc > 0.0 && error > 0.0 {
            self.resasc * (200.0 * error / self.resasc).powf(1.5).min(1.0)
        } else {
            error
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wherever the level resolves the oscillation (`n ≥ κ + 1`: the engines' 0.5 points per
    /// radian of the phase `2κ` across the interval) and [`chebyshev_tail`] gives a finite size,
    /// that size times the largest moment of the constant weight from degree n/2 up
    /// (`2/((n/2)² − 1)`) bounds the Clenshaw–Curtis rule's error, for oscillations `cos(κx + φ)`
    /// at every level; a function whose coefficients do not fall (a kink) is refused. Below the
    /// resolution aliasing can make the last coefficients small by chance (κ = 40 at 17 points:
    /// off by 0.7 against an estimate of 1e-3), which is why the engines do not ask it there.
    #[test]
    fn chebyshev_tail_bounds_the_clenshaw_curtis_error() {
        let mut trusted = 0;
        for &kappa in &[0.5, 2.0, 5.0, 10.0, 20.0, 40.0] {
            for &phase in &[0.0, 0.7, 1.9] {
                let f = |x: f64| (kappa * x + phase).cos();
                let exact = ((kappa + phase).sin() - (phase - kappa).sin()) / kappa;
                for &n in &[9usize, 17, 33, 65] {
                    if (n as f64) < kappa + 1.0 {
                        continue;
                    }
                    let m = n - 1;
                    let values: Vec<f64> =
                        (0..n).map(|k| f((std::f64::consts::PI * k as f64 / m as f64).cos())).collect();
                    let integral: f64 = values.iter().zip(crate::poly::clenshaw_curtis(n)).map(|(v, w)| v * w).sum();
                    let tail = chebyshev_tail(&values);
                    if tail.is_finite() {
                        trusted += 1;
                        let half = (m / 2) as f64;
                        let bound = tail * 2.0 / (half * half - 1.0);
                        let error = (integral - exact).abs();
                        assert!(error <= bound.max(1e-15), "κ {kappa}, φ {phase}, n {n}: error {error:e} > {bound:e}");
                    }
                }
            }
        }
        assert!(trusted > 20, "the estimate was trusted {trusted} times only");
        // |x| has coefficients falling as 1/j²: not geometric, refused
        let values: Vec<f64> = (0..33).map(|k| (std::f64::consts::PI * k as f64 / 32.0).cos().abs()).collect();
        assert_eq!(chebyshev_tail(&values), f64::INFINITY);
    }

    #[test]
    fn rule_weights_sum_to_two_and_are_symmetric() {
        let r = rule();
        let sum: f64 = r.iter().map(|p| p.1).sum();
        assert!((sum - 2.0).abs() < 1e-14, "sum of weights {sum}");
        for i in 0..ORDER {
            assert!((r[i].0 + r[ORDER - 1 - i].0).abs() < 1e-15);
            assert!((r[i].1 - r[ORDER - 1 - i].1).abs() < 1e-15);
        }
    }

    #[test]
    fn integrates_polynomials_of_degree_31_exactly() {
        // ∫_0^1 x^31 dx = 1/32
        let v = composite(0.0, 1.0, 1, |x| x.powi(31));
        assert!((v - 1.0 / 32.0).abs() < 1e-15, "{v}");
    }

    #[test]
    fn gauss_legendre_rules_are_exact_to_degree_2n_minus_1() {
        // ∫_{−1}^{1} x^{2k} dx = 2/(2k + 1); odd powers integrate to 0 by the symmetric nodes
        for n in [1, 2, 3, 8, 16, 37, 128] {
            let r = gauss_legendre(n);
            assert_eq!(r.len(), n);
            assert!(r.windows(2).all(|p| p[0].0 < p[1].0));
            for k in 0..n {
                let exact = 2.0 / (2 * k + 1) as f64;
                let got: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * k as i32)).sum();
                assert!((got / exact - 1.0).abs() < 1e-13, "n {n}, x^{}: {got} vs {exact}", 2 * k);
            }
            // one degree too many: x^{2n} is not integrated exactly (the error falls as 4^{−n},
            // so it is visible for small n only)
            if n <= 8 {
                let got: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * n as i32)).sum();
                assert!((got * (2 * n + 1) as f64 / 2.0 - 1.0).abs() > 1e-6, "n {n}");
            }
        }
        assert_eq!(&gauss_legendre(ORDER)[..], &rule()[..]);
        assert_eq!(gauss_legendre(0), gauss_legendre(1));
    }

    #[test]
    fn gauss_hermite_rules_integrate_even_moments_exactly() {
        // ∫ x^{2k} e^{−x²} dx = Γ(k + ½) = √π (2k − 1)!!/2^k, built up by Γ(k + 3/2) = (k + ½) Γ(k + ½)
        for n in [1, 2, 5, 16, 33, 64, 128] {
            let r = gauss_hermite(n);
            assert_eq!(r.len(), n);
            assert!(r.windows(2).all(|p| p[0].0 < p[1].0));
            let mut exact = std::f64::consts::PI.sqrt();
            for k in 0..n {
                let got: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * k as i32)).sum();
                assert!((got / exact - 1.0).abs() < 1e-12, "n {n}, x^{}: {got} vs {exact}", 2 * k);
                // odd moments vanish: nodes and weights symmetric
                let odd: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * k as i32 + 1)).sum();
                let scale: f64 = r.iter().map(|&(x, w)| (w * x.powi(2 * k as i32 + 1)).abs()).sum();
                assert!(odd.abs() <= 1e-13 * scale, "n {n}, x^{}: {odd}", 2 * k + 1);
                exact *= k as f64 + 0.5;
            }
            // x^{2n} is past the rule's degree: its moment comes out low by √π n!/2^n, a
            // relative √(πn)/2^n, visible for small n
            if n <= 5 {
                let got: f64 = r.iter().map(|&(x, w)| w * x.powi(2 * n as i32)).sum();
                assert!((got / exact - 1.0).abs() > 1e-2, "n {n}");
            }
        }
    }

    #[test]
    fn gauss_hermite_matches_a_closed_form_transform() {
        // ∫ e^{−x²} cos(k x) dx = √π e^{−k²/4}: an entire integrand, converged at 40 nodes
        for k in [0.5, 2.0, 6.0] {
            let got: f64 = gauss_hermite(40).iter().map(|&(x, w)| w * (k * x).cos()).sum();
            let exact = std::f64::consts::PI.sqrt() * (-k * k / 4.0).exp();
            assert!((got - exact).abs() < 1e-14, "k {k}: {got} vs {exact}");
        }
    }

    #[test]
    fn oscillatory_panel_budget_holds() {
        // ∫_0^L cos(x) dx = sin(L): one panel turning through MAX_PANEL_PHASE radians.
        let l = MAX_PANEL_PHASE;
        let v = composite(0.0, l, 1, f64::cos);
        assert!((v - l.sin()).abs() < 1e-14, "{v} vs {}", l.sin());
    }
}
