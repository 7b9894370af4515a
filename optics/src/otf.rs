//! Monochromatic transfer functions of a circular pupil: the exact defocused OTF, the
//! aberration-free MTF and the pixel-aperture MTF.
//!
//! Conventions (docs/physics.md, "The OTF"): `s = ν/ν_c(λ)` is the frequency
//! normalized to the incoherent cutoff `ν_c = 1/(λ F#)`; `w = W020/λ` is the defocus in waves at
//! the pupil edge. The OTF is normalized to 1 at `s = 0`, is real for a centred circular pupil
//! with defocus only, may be negative, and is zero for `s ≥ 1`.

use std::f64::consts::{FRAC_2_PI, PI};

use crate::quad::{self, fused};

/// Aberration-free MTF of a circular pupil: `MTF_0(s) = (2/π)[acos s − s √(1 − s²)]`.
///
/// Returns 1 for `s ≤ 0` and 0 for `s ≥ 1` (docs/physics.md: limit `a → 0` of the defocused OTF).
pub fn mtf_diffraction_limited(s: f64) -> f64 {
    if s <= 0.0 {
        1.0
    } else if s >= 1.0 {
        0.0
    } else {
        FRAC_2_PI * (s.acos() - s * (1.0 - s * s).sqrt())
    }
}

/// Mean of [`mtf_diffraction_limited`] over `[0, s_max]` in closed form.
///
/// `∫ acos s ds = s acos s − √(1 − s²)` and `∫ s √(1 − s²) ds = −(1 − s²)^{3/2}/3`, so
/// `∫_0^x MTF_0 ds = (2/π)[x acos x − √(1 − x²) + 1 − (1 − (1 − x²)^{3/2})/3]`, which is
/// `4/(3π)` at `x = 1` (docs/physics.md, "Test vectors and identities"). Past the cutoff the MTF is zero.
pub fn mtf_diffraction_limited_mean(s_max: f64) -> f64 {
    if s_max <= 0.0 {
        return 1.0;
    }
    let x = s_max.min(1.0);
    let r = (1.0 - x * x).sqrt();
    let area = FRAC_2_PI * (x * x.acos() - r + 1.0 - (1.0 - r * r * r) / 3.0);
    area / s_max
}

/// Number of Gauss–Legendre panels [`defocus_otf`] uses at `(s, w)`.
///
/// With `y = cos t` in the pupil-overlap integral the phase is `φ(t) = a (cos t − s)`,
/// `a = 8π w s`, on `t ∈ [0, acos s]`; its rate is at most `|a| sin(acos s)`. The panel count keeps
/// the phase turned through by any panel under [`quad::MAX_PANEL_PHASE`], so it grows linearly
/// with defocus and the error stays at rounding level for any `w`.
pub fn defocus_otf_panels(s: f64, w: f64) -> usize {
    if !(s > 0.0 && s < 1.0) {
        return 0;
    }
    let a = 8.0 * PI * w * s;
    let theta = s.acos();
    let turn = a.abs() * theta.sin() * theta;
    (turn / quad::MAX_PANEL_PHASE).ceil().max(1.0) as usize
}

/// Exact OTF of a centred circular pupil with defocus `w` waves (`W020/λ`) at normalized
/// frequency `s`.
///
/// docs/physics.md gives `OTF(s, w) = 4/(π a) ∫_0^{acos s} sin[a(cos t − s)] cos t dt` with `a = 8π w s`.
/// We integrate the same overlap integral before the integration by parts,
/// `OTF(s, w) = (4/π) ∫_0^{acos s} sin²t · cos[a(cos t − s)] dt`,
/// which has no `1/a` (so no special case at `a = 0`) and a smooth, bounded integrand: composite
/// Gauss–Legendre converges to rounding error with [`defocus_otf_panels`] panels.
/// The result is even in `w`, 1 at `s ≤ 0` and 0 at `s ≥ 1`.
pub fn defocus_otf(s: f64, w: f64) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let a = 8.0 * PI * w * s;
    // Largest phase reached: |a| (1 − s). Below 1e-8 the cosine is 1 to 5e-17.
    if a.abs() * (1.0 - s) < 1e-8 {
        return mtf_diffraction_limited(s);
    }
    if a.abs() >= BESSEL_SERIES_MIN_A {
        return defocus_otf_bessel(s, a);
    }
    defocus_otf_quadrature(s, w)
}

/// `|a|` from which [`defocus_otf`] sums the Bessel series instead of integrating: there the
/// series costs a few multiply-adds per term where the quadrature costs a sine and a cosine
/// per node, and the two agree to rounding error (tested).
pub const BESSEL_SERIES_MIN_A: f64 = 24.0;

/// [`defocus_otf`] by composite Gauss–Legendre quadrature of
/// `(4/π) ∫_0^{acos s} sin²t cos[a(cos t − s)] dt` with [`defocus_otf_panels`] panels, for any `a`.
pub fn defocus_otf_quadrature(s: f64, w: f64) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let a = 8.0 * PI * w * s;
    let theta = s.acos();
    let panels = defocus_otf_panels(s, w);
    // sines and cosines by the branch-free polynomial of `fft::cis` (a few ulp; libm's cost
    // most of this loop)
    let integral = quad::composite(0.0, theta, panels, |t| {
        let (sin_t, cos_t) = crate::fft::cis::sin_cos(t);
        sin_t * sin_t * crate::fft::cis::sin_cos(a * (cos_t - s)).1
    });
    (4.0 / PI) * integral
}

/// `w ∂OTF/∂w` of [`defocus_otf`] at `(s, w)`: the OTF's derivative with respect to the defocus,
/// per relative change of it (docs/physics.md, "Gradients": the F-number and the focal length
/// scale every wavelength's defocus `W020 ∝ f0/F#²`). Differentiating the integrand of the
/// t-form `(4/π) ∫_0^{acos s} sin²t cos[a(cos t − s)] dt` (`a = 8π w s`) under the integral,
/// `a ∂/∂a`: `−(4/π) ∫_0^{acos s} sin²t · a(cos t − s) · sin[a(cos t − s)] dt`, by composite
/// Gauss–Legendre with twice [`defocus_otf_panels`] panels (the integrand turns through the same
/// phase as the value's, times a factor linear in cos t). 0 at `s ≤ 0`, `s ≥ 1` and `w = 0`.
pub fn defocus_otf_log_derivative(s: f64, w: f64) -> f64 {
    if !(s > 0.0 && s < 1.0) || w == 0.0 {
        return 0.0;
    }
    let a = 8.0 * PI * w * s;
    let theta = s.acos();
    let panels = 2 * defocus_otf_panels(s, w);
    // sines and cosines by the branch-free polynomial of `fft::cis`, as the value's quadrature
    let integral = quad::composite(0.0, theta, panels, |t| {
        let (sin_t, cos_t) = crate::fft::cis::sin_cos(t);
        let phase = a * (cos_t - s);
        sin_t * sin_t * phase * crate::fft::cis::sin_cos(phase).0
    });
    -(4.0 / PI) * integral
}

/// [`defocus_otf`] by the Jacobi–Anger expansion `e^{i a cos t} = J0(a) + 2 Σ_{n≥1} iⁿ Jn(a) cos nt`
/// (the route of Hopkins' Bessel series), integrated term by term:
///
/// ```text
/// OTF = (4/π) [ cos(a s) (J0 C0 + 2 Σ_{n even} (−1)^{n/2} Jn Cn) + sin(a s) 2 Σ_{n odd} (−1)^{(n−1)/2} Jn Cn ]
/// Cn  = ∫_0^θ sin²t cos nt dt = ½ S(n) − ¼ [S(n+2) + S(n−2)],  S(m) = sin(mθ)/m, S(0) = θ,  θ = acos s
/// ```
///
/// `Jn(a)` for all `n` by Miller's backward recurrence normalized with `J0 + 2 Σ J2k = 1`,
/// started where `Jn(a) < 1e-17`; `sin(mθ)` by the Chebyshev recurrence. For `|a| ≥ 1`.
pub fn defocus_otf_bessel(s: f64, a: f64) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    bessel_lanes([s], [a], 0.0)[0]
}

/// `|a| (1 − s)` from which [`defocus_otf_many_within`] tries [`defocus_otf_asymptotic`] before
/// the Bessel series, which runs `|a| + 12 |a|^{1/3}` orders. The expansion's terms fall to
/// about `e^{−|a|(1 − s)}`: from 18 (1.5e-8) it answers the looser accuracies a product rule asks
/// of its light panels, and beyond 30 (1e-13) nearly all; where it cannot reach the accuracy it
/// says so within a few terms. The spectrometer scene at 1e-6: 30 → 18 saves 7 % of the
/// instructions of an evaluation (`valgrind --tool=callgrind`), the mean unchanged to 1e-13.
pub const ASYMPTOTIC_MIN_PHASE: f64 = 18.0;

/// Most terms [`defocus_otf_asymptotic`] sums in each of its two series.
const ASYMPTOTIC_TERMS: usize = 48;

/// `b_k/b_{k−1}` of the square-root edge's series times `a`: `(k − 3/2)(k + 1/2)/(2k)` (from
/// `c_k/c_{k−1} = −(3/2 − k)/(2k)` and `Γ(k + 3/2)/Γ(k + 1/2) = k + 1/2`), a table where the
/// loop divided twice a term.
const EDGE_RATIOS: [f64; ASYMPTOTIC_TERMS + 1] = {
    let mut table = [0.0; ASYMPTOTIC_TERMS + 1];
    let mut k = 1;
    while k <= ASYMPTOTIC_TERMS {
        let kf = k as f64;
        table[k] = (kf - 1.5) * (kf + 0.5) / (2.0 * kf);
        k += 1;
    }
    table
};

/// [`defocus_otf`] at large defocus from its asymptotic expansion, or `None` where the expansion
/// does not reach `target` (absolute).
///
/// With `u = cos t`, `OTF = (4/π) Re[e^{−ias} I]`, `I = ∫_s^1 √(1 − u²) e^{iau} du` (`a > 0`:
/// the OTF is even in `a`). The phase `au` has no stationary point, so `I` is the sum of its
/// two endpoints' expansions (Erdélyi, *Asymptotic Expansions*, §2.8–2.9):
///
/// ```text
/// u = s (regular):  −e^{ias} Σ_k (−1)^k f^{(k)}(s)/(ia)^{k+1},   f = √(1 − u²)
/// u = 1 (√ edge):   e^{ia} Σ_k √2 c_k Γ(k + 3/2) (ia)^{−(k+3/2)},  √(v(2 − v)) = √2 Σ_k c_k v^{k+1/2}
/// ```
///
/// (`v = 1 − u`, `c_k = C(1/2, k)(−1/2)^k`; Watson's lemma). Their real parts:
/// `Σ_{k odd} f^{(k)}(s) (−1)^{(k+1)/2} / a^{k+1}` (the derivatives from the three-term
/// recurrence of `2 g f' = g' f`, `g = 1 − u²`) and `Σ_k √2 c_k Γ(k + 3/2) a^{−(k+3/2)} cos(a(1 − s) − (2k + 3)π/4)`.
/// Both are asymptotic: their terms fall while `k` is below about `a(1 − s)`, to about
/// `e^{−a(1−s)}`. Each is summed until a term is below `target` (the first omitted term bounds
/// the remainder while they fall); a term that grows first gives `None`. Tested against the
/// Bessel series for `a(1 − s)` from 18 to 3e3 over `0 < s < 1`.
pub fn defocus_otf_asymptotic(s: f64, a: f64, target: f64) -> Option<f64> {
    asymptotic_with::<false>(s, a, target).map(|(value, _)| value)
}

/// [`defocus_otf_asymptotic`] and, beside it, `w ∂OTF/∂w = a ∂OTF/∂a` from the same two
/// expansions differentiated term by term (docs/physics.md, "Gradients: the F-number and the
/// focal length on the value's rule"): the expansion of `a d/da [e^{−ias} I]`, the integral of
/// `ia (u − s) √(1 − u²) e^{ia(u − s)}`, is the derivative of `I`'s expansion term by term (the
/// endpoint expansions of `∫ (u − s) f e^{iau}` are those of `f`'s with `(u − s)` expanded at
/// each end). The regular end's term `T_k ∝ a^{−(k+1)}` gives `−(k + 1) T_k`; the edge's
/// `b_k cos(φ_k)`, `b_k ∝ a^{−(k+3/2)}`, `φ_k = a(1 − s) − (2k + 3)π/4`, gives
/// `−(k + 3/2) b_k cos φ_k − a(1 − s) b_k sin φ_k`. Each series runs until its value's term is
/// below `target` and its derivative's below `target · max(1, a(1 − s))` (the derivative is about
/// `a(1 − s)` times the value's size: the same accuracy relative to it); `None` where a term
/// grows first, as the value.
pub fn defocus_otf_asymptotic_and_log_derivative(s: f64, a: f64, target: f64) -> Option<(f64, f64)> {
    asymptotic_with::<true>(s, a, target)
}

/// [`defocus_otf_asymptotic`], with its log-derivative where `LANE` (else 0).
#[inline(always)]
fn asymptotic_with<const LANE: bool>(s: f64, a: f64, target: f64) -> Option<(f64, f64)> {
    let x = a.abs();
    let phase = x * (1.0 - s);
    if !(s > 0.0 && s < 1.0 && phase.is_finite() && phase < 1e6 && target > 0.0) {
        return None;
    }
    // u = s: the odd orders of the regular endpoint's series, D_k = f^{(k)}(s)/a^{k+1}. From
    // 2 g f' = g' f (g = 1 − u², so g'' = −2) the derivatives follow a three-term recurrence,
    // f^{(n+1)} g = s (2n − 1) f^{(n)} + n (n − 2) f^{(n−1)}: one step per term
    let g0 = 1.0 - s * s;
    let (inv_x, inv) = (1.0 / x, 1.0 / (g0 * x));
    let (mut below, mut d) = (0.0, g0.sqrt() * inv_x);
    // D_{n+1} = α_n D_n + β_n D_{n−1}: the coefficients off the chain through D, so that a step
    // is one multiply-add on it (two multiplies and an add before)
    let (alpha, beta) = (s * inv, inv_x * inv);
    let step = |n: usize, below: f64, d: f64| {
        let nf = n as f64;
        fused(alpha * (2.0 * nf - 1.0), d, beta * (nf * (nf - 2.0)) * below)
    };
    let mut lower = 0.0;
    let mut previous = f64::INFINITY;
    let mut settled = false;
    // two steps a turn: n = 2j gives the odd order k = 2j + 1 (a term, of sign (−1)^{j+1}),
    // n = 2j + 1 the even one after it
    let mut sign = -1.0;
    // the derivative's target: its size is about a(1 − s) times the value's
    let lane_target = target * phase.max(1.0);
    let mut lane_lower = 0.0;
    for j in 0..ASYMPTOTIC_TERMS / 2 {
        (below, d) = (d, step(2 * j, below, d));
        let term = d * sign;
        lower += term;
        // a d/da of T_k ∝ a^{−(k+1)}, k = 2j + 1
        let lane_term = -((2 * j + 2) as f64) * term;
        if LANE {
            lane_lower += lane_term;
        }
        if term.abs() < target && (!LANE || lane_term.abs() < lane_target) {
            settled = true;
            break;
        }
        if term.abs() > previous {
            return None;
        }
        previous = term.abs();
        sign = -sign;
        (below, d) = (d, step(2 * j + 1, below, d));
    }
    if !settled {
        return None;
    }
    // u = 1: Watson's lemma at the square-root edge
    let (sin_p, cos_p) = crate::fft::cis::sin_cos(phase - 0.75 * PI);
    let turns = [cos_p, sin_p, -cos_p, -sin_p];
    // sin(φ − (2k + 3)π/4) likewise: sin, −cos, −sin, cos
    let sine_turns = [sin_p, -cos_p, -sin_p, cos_p];
    let mut b = std::f64::consts::SQRT_2 * 0.5 * PI.sqrt() / (x * x.sqrt());
    let (mut upper, mut lane_upper) = (0.0, 0.0);
    let mut previous = f64::INFINITY;
    for (k, &ratio) in EDGE_RATIOS.iter().enumerate() {
        if k > 0 {
            b *= ratio * inv_x;
        }
        // cos(φ − (2k + 3)π/4) = cos, sin, −cos, −sin of φ − 3π/4 as k goes round mod 4
        upper += b * turns[k & 3];
        if LANE {
            // a d/da of b_k cos φ_k: −(k + 3/2) b_k cos φ_k − a(1 − s) b_k sin φ_k
            lane_upper -= b * fused(k as f64 + 1.5, turns[k & 3], phase * sine_turns[k & 3]);
        }
        if b.abs() < target && (!LANE || b.abs() * (k as f64 + 1.5 + phase) < lane_target) {
            return Some(((4.0 / PI) * (lower + upper), (4.0 / PI) * (lane_lower + lane_upper)));
        }
        if b.abs() > previous {
            return None;
        }
        previous = b.abs();
    }
    None
}

/// [`defocus_otf`] at many `(s, w)` at once, into `out` (same length): those on the Bessel
/// series eight at a time, interleaved ([`defocus_otf_bessel`] is a chain of dependent
/// multiply-adds, and independent chains fill the pipeline and the vector registers), the rest
/// one by one. Equal to [`defocus_otf`] within 1e-12 (the series against the quadrature;
/// tested).
///
/// The series takes every point where the defocus matters (`|a|(1 − s) ≥ 1e-8`; a single call
/// takes it from [`BESSEL_SERIES_MIN_A`]). Four interleaved series cost less than the quadrature
/// from `|a| = 1` (spectrometer scene at 1e-6: 3.1 ms against 4.2 ms from 24), and below it the
/// series is a dozen orders where the quadrature still takes its panel of Gauss–Legendre points
/// and their cosines (-2 % instructions). The two agree to 1e-12 for `|a| ≥ 1`, and to 1e-15
/// from `|a| = 1e-8` to 1 (tested: the backward recurrence grows by `2n/|a|` a step there, from
/// 1e-300 over about 20 orders, far from overflow).
///
/// # Panics
/// If `points` and `out` differ in length.
pub fn defocus_otf_many(points: &[(f64, f64)], out: &mut [f64]) {
    defocus_otf_many_within(points, out, 0.0);
}

/// [`defocus_otf_many`] to an absolute error of `accuracy` per value (at most; 1e-17 or below
/// is [`defocus_otf_many`] itself): the Bessel series starts Miller's recurrence where the
/// orders it leaves out are below it, so a product rule that needs its values to 1e-10 need not
/// pay for 1e-17 (the spectrometer scene at tolerance 1e-6: 6 % of its time). Tested against
/// [`defocus_otf`] at every accuracy it takes.
///
/// # Panics
/// If `points` and `out` differ in length.
pub fn defocus_otf_many_within(points: &[(f64, f64)], out: &mut [f64], accuracy: f64) {
    assert_eq!(points.len(), out.len(), "one output per point");
    let mut lanes = [0usize; BATCH];
    let mut count = 0;
    fn run<const L: usize>(points: &[(f64, f64)], lanes: &[usize], out: &mut [f64], accuracy: f64) {
        // a short batch repeats its last point in the spare lanes
        let at = |k: usize| points[lanes[k.min(lanes.len() - 1)]];
        let s: [f64; L] = std::array::from_fn(|k| at(k).0);
        let a: [f64; L] = std::array::from_fn(|k| 8.0 * PI * at(k).1 * at(k).0);
        let values = bessel_lanes(s, a, accuracy);
        for (k, &i) in lanes.iter().enumerate() {
            out[i] = values[k];
        }
    }
    // the last, short batch in as few lanes as it fills (two lanes cost about 60 % of four:
    // the level increments of a product rule are often 2, 4 or 8 points, some on the expansion)
    let batch = |lanes: &[usize; BATCH], count: usize, out: &mut [f64]| match count {
        1 => run::<1>(points, &lanes[..1], out, accuracy),
        2 => run::<2>(points, &lanes[..2], out, accuracy),
        3 | 4 => run::<4>(points, &lanes[..count], out, accuracy),
        _ => run::<BATCH>(points, &lanes[..count], out, accuracy),
    };
    for (i, &(s, w)) in points.iter().enumerate() {
        let a = 8.0 * PI * w * s;
        let series = s > 0.0 && s < 1.0 && a.abs() * (1.0 - s) >= 1e-8;
        if !series {
            out[i] = defocus_otf(s, w);
            continue;
        }
        if a.abs() * (1.0 - s) >= ASYMPTOTIC_MIN_PHASE
            && let Some(value) = defocus_otf_asymptotic(s, a, 0.5 * accuracy.max(1e-16))
        {
            out[i] = value;
            continue;
        }
        lanes[count] = i;
        count += 1;
        if count == BATCH {
            batch(&lanes, count, out);
            count = 0;
        }
    }
    if count > 0 {
        batch(&lanes, count, out);
    }
}

/// [`defocus_otf_many_within`] and, beside each value, its defocus lane `w ∂OTF/∂w` into `lane`
/// (docs/physics.md, "Gradients: the F-number and the focal length on the value's rule"): on the
/// same forms the value takes, each differentiated analytically —
/// - the asymptotic expansion, term by term ([`defocus_otf_asymptotic_and_log_derivative`]),
///   where it answers the value's accuracy and the lane's (its target times `max(1, a(1 − s))`);
/// - the Bessel series, on the same recurrence, eight points at a time (the lane of
///   `bessel_lanes_with`);
/// - below `|a|(1 − s) = 1e-8`, where the value is the diffraction-limited MTF, 0: the lane is
///   `−(4/π) ∫ sin²t · φ sin φ dt` with `|φ| ≤ |a|(1 − s)`, below `2 (|a|(1 − s))² < 2e-16` there.
///
/// The values are those of [`defocus_otf_many_within`] bit for bit (the same forms, starts and
/// batches; the Bessel lanes' value is the value-alone recurrence's, the lane's chain beside it;
/// where the expansion answers the value but not the lane's target, the lane is the series' at
/// that point), so a frequency rule that reads them makes the value's decisions.
///
/// # Panics
/// If `points`, `out` and `lane` differ in length.
pub fn defocus_otf_many_and_log_derivative_within(
    points: &[(f64, f64)],
    out: &mut [f64],
    lane: &mut [f64],
    accuracy: f64,
) {
    assert_eq!(points.len(), out.len(), "one output per point");
    assert_eq!(points.len(), lane.len(), "one lane per point");
    let mut lanes = [0usize; BATCH];
    let mut count = 0;
    fn run<const L: usize>(points: &[(f64, f64)], lanes: &[usize], out: &mut [f64], lane: &mut [f64], accuracy: f64) {
        let at = |k: usize| points[lanes[k.min(lanes.len() - 1)]];
        let s: [f64; L] = std::array::from_fn(|k| at(k).0);
        let a: [f64; L] = std::array::from_fn(|k| 8.0 * PI * at(k).1 * at(k).0);
        let (values, derivatives) = bessel_lanes_with::<L, true>(s, a, accuracy);
        for (k, &i) in lanes.iter().enumerate() {
            out[i] = values[k];
            lane[i] = derivatives[k];
        }
    }
    let batch = |lanes: &[usize; BATCH], count: usize, out: &mut [f64], lane: &mut [f64]| match count {
        1 => run::<1>(points, &lanes[..1], out, lane, accuracy),
        2 => run::<2>(points, &lanes[..2], out, lane, accuracy),
        3 | 4 => run::<4>(points, &lanes[..count], out, lane, accuracy),
        _ => run::<BATCH>(points, &lanes[..count], out, lane, accuracy),
    };
    for (i, &(s, w)) in points.iter().enumerate() {
        let a = 8.0 * PI * w * s;
        let series = s > 0.0 && s < 1.0 && a.abs() * (1.0 - s) >= 1e-8;
        if !series {
            out[i] = defocus_otf(s, w);
            lane[i] = 0.0;
            continue;
        }
        // the value exactly as `defocus_otf_many_within` takes it (the expansion where it
        // reaches the accuracy); the lane from the expansion where it reaches the lane's target
        // too, else from the series at this one point (its value left aside)
        let target = 0.5 * accuracy.max(1e-16);
        if a.abs() * (1.0 - s) >= ASYMPTOTIC_MIN_PHASE
            && let Some(value) = defocus_otf_asymptotic(s, a, target)
        {
            out[i] = value;
            lane[i] = match defocus_otf_asymptotic_and_log_derivative(s, a, target) {
                Some((_, derivative)) => derivative,
                None => bessel_lanes_with::<1, true>([s], [a], accuracy).1[0],
            };
            continue;
        }
        lanes[count] = i;
        count += 1;
        if count == BATCH {
            batch(&lanes, count, out, lane);
            count = 0;
        }
    }
    if count > 0 {
        batch(&lanes, count, out, lane);
    }
}

/// [`defocus_otf`] and its defocus lane `w ∂OTF/∂w` at one point, to rounding: the forms of
/// [`defocus_otf_many_and_log_derivative_within`] (the t-form quadrature's
/// [`defocus_otf_log_derivative`] is the independent reference the tests hold it against).
pub fn defocus_otf_and_log_derivative(s: f64, w: f64) -> (f64, f64) {
    let (mut value, mut lane) = ([0.0], [0.0]);
    defocus_otf_many_and_log_derivative_within(&[(s, w)], &mut value, &mut lane, 0.0);
    (value[0], lane[0])
}

/// Lanes of [`defocus_otf_many`]'s batches: eight. Built for a CPU with AVX-512 (the project's
/// `target-cpu=native`, `.cargo/config.toml`), eight lanes are one register and the spectrometer
/// scene at 1e-6 takes 10 % less time than with four; on a baseline x86-64 build (two lanes a
/// register) eight and four cost the same.
const BATCH: usize = 8;

/// [`defocus_otf_bessel`] of `L` points `(s, a)`, `0 < s < 1`, `|a| ≥ 1`, in interleaved lanes
/// (independent chains of dependent multiply-adds fill the pipeline where one leaves it mostly
/// idle): one recurrence from the largest lane's start (a higher start only makes Miller's
/// recurrence more exact), everything in registers.
///
/// The sum is taken in the form that needs the fewest live values per order. Over all integer
/// orders (`J_{−n} = (−1)ⁿ J_n`, `C_{−n} = C_n`) the two brackets are `Σ_n iⁿ J_n C_n`, and with
/// `C_n = ½ S(n) − ¼ [S(n+2) + S(n−2)]` re-indexed on `S`:
///
/// ```text
/// Σ_n iⁿ J_n C_n = Σ_m i^m S(m) K_m,   K_m = ½ J_m + ¼ (J_{m−2} + J_{m+2}) = [(m−1) J_{m−1} + (m+1) J_{m+1}] / (2a)
/// ```
///
/// (the three-term recurrence twice), whose `±m` terms are equal: `even = θ J_1 + Σ_{m even ≥ 2}
/// ±sin(mθ)[(1 − 1/m) J_{m−1} + (1 + 1/m) J_{m+1}]`, `odd` the same over odd `m`, each over `a`.
/// Going down in `m`, `J_{m+1}`, `J_m` and the new `J_{m−1}` are at hand, and `sin(mθ)` comes from
/// the Chebyshev recurrence run downward from `sin(Mθ)`, `sin((M+1)θ)` (one sine and cosine per
/// lane), reseeded every 64 orders (its rounding grows with its length) and at `m = 3` by the
/// multiple-angle formulas. The lanes are rescaled
/// every four steps (the backward growth per step, `2n/|a|`, is below 3e5 for any `|a| ≥ 1`
/// within the defocus budget, so four steps stay within the 1e58 of headroom above the 1e250
/// threshold; below `|a| = 1` the series is about 20 orders long from 1e-300, and its growth,
/// at most `(40/|a|)^20` = 1e193 at `|a|` = 1e-8, stays below 1e-100). The per-order constants
/// come from [`order_coefficients`], four orders a block. The multiply-adds of a step are fused
/// ([`quad::fused`]) where the build has the instruction: the loop is bound by the
/// floating-point ports, and a fused pair is one operation (the spectrometer scene at 1e-6:
/// 8 % less time).
#[inline(always)]
fn bessel_lanes<const L: usize>(s: [f64; L], a: [f64; L], accuracy: f64) -> [f64; L] {
    bessel_lanes_with::<L, false>(s, a, accuracy).0
}

/// [`bessel_lanes`] and, where `LANE`, `w ∂OTF/∂w = a ∂OTF/∂a` of each lane on the same
/// recurrence (else 0): with `F = Σ_n iⁿ J_n C_n` and `OTF = (4/π) Re[e^{−ias} F]`,
/// `a d/da [e^{−ias} F] = e^{−ias} (a F′ − ias F)`, and `a F′ = Σ_m i^m S(m) a K_m[J′]` with `K_m`
/// linear in the `J`'s, so `K_m[J′] = dK_m/da`; by `J′_n = (n/a) J_n − J_{n+1} = J_{n−1} − (n/a) J_n`,
///
/// ```text
/// a K_m[J′] = J_m + [(m − 1)(m − 2) J_{m−1} − (m + 1)(m + 2) J_{m+1}] / (2a),   a K_0[J′] = −J_2
/// ```
///
/// (Watson, *A Treatise on the Theory of Bessel Functions*, §2.12): the orders at hand at each
/// step of the downward recurrence, one more multiply-add chain a step. With the value's sums
/// `E + iO = a F` and the lane's `G_E + i G_O = a F′` (the same signs `i^m`), the lane is
/// `(4/π) [cos(as)(G_E + s O) + sin(as)(G_O − s E)]` over Miller's normalization. The orders left
/// out are those of the value (its start): the lane's terms are the value's times factors of
/// about `m/a`, near 1 where the series ends.
#[inline(always)]
fn bessel_lanes_with<const L: usize, const LANE: bool>(
    s: [f64; L],
    a: [f64; L],
    accuracy: f64,
) -> ([f64; L], [f64; L]) {
    let x = a.map(f64::abs);
    // the start grows with |a|: the largest lane's
    let start = series_start(x.iter().copied().fold(0.0, f64::max), accuracy);
    // start ≡ 3 (mod 4): the recurrence runs in blocks of four whose signs are fixed
    let start = start | 3;
    // (m, 1 − 1/m, 1 + 1/m) for m = 0 … start, read four at a time from the top
    let table = order_coefficients(start + 1);
    let (blocks, _) = table[..=start].as_chunks::<4>();
    // (2/m, (m − 1)(m − 2)/(2m), (m + 1)(m + 2)/(2m)) for the lane, likewise
    let lane_table = if LANE { lane_coefficients(start + 1) } else { std::borrow::Cow::Borrowed(&[][..]) };
    let (lane_blocks, _) = lane_table.as_chunks::<4>();
    let theta = s.map(f64::acos);
    let two_cos = s.map(|s| 2.0 * s);
    let sin_theta = s.map(|s| (1.0 - s * s).max(0.0).sqrt());
    let two_over_x = x.map(|x| 2.0 / x);
    let theta_hi = theta.map(|t| f64::from(t as f32));
    let seed = |m: usize| sines_at(m, s, theta, theta_hi, sin_theta);
    let (mut sin_here, mut sin_above) = seed(start);
    let mut j_above = [0.0_f64; L];
    let mut j = [1e-300_f64; L];
    let (mut even, mut odd, mut norm) = ([0.0_f64; L], [0.0_f64; L], [0.0_f64; L]);
    let (mut lane_even, mut lane_odd) = ([0.0_f64; L], [0.0_f64; L]);
    // one step at order m ≥ 1: J_{m−1}, the term ±sin(mθ)[(1 − 1/m) J_{m−1} + (1 + 1/m) J_{m+1}]
    // into its sum (J_m into the norm for even m), then everything one order down
    macro_rules! step {
        ($order:expr, $lane_order:expr, $sum:ident, $lane_sum:ident, $sign:expr, $norm:expr) => {{
            let [mf, below, above]: [f64; 3] = $order;
            let sign: f64 = $sign;
            let (below_weight, above_weight) = (sign * below, sign * above);
            let [two_over_m, below_lane, above_lane]: [f64; 3] = $lane_order;
            let (two_over_m, below_lane, above_lane) = (sign * two_over_m, sign * below_lane, sign * above_lane);
            for l in 0..L {
                let below = fused(mf * two_over_x[l], j[l], -j_above[l]);
                if LANE {
                    // ±sin(mθ) · 2 a K_m[J′]/m (the ±m terms alike)
                    let inner = two_over_x[l] * fused(below_lane, below, -above_lane * j_above[l]);
                    $lane_sum[l] = fused(sin_here[l], fused(two_over_m, j[l], inner), $lane_sum[l]);
                }
                $sum[l] = fused(sin_here[l], fused(below_weight, below, above_weight * j_above[l]), $sum[l]);
                if $norm {
                    norm[l] += j[l];
                }
                j_above[l] = j[l];
                j[l] = below;
                let sin_below = fused(two_cos[l], sin_here[l], -sin_above[l]);
                sin_above[l] = sin_here[l];
                sin_here[l] = sin_below;
            }
        }};
    }
    // block k holds m = 4k … 4k + 3. m ≡ 3: odd −, m ≡ 2: even − and norm, m ≡ 1: odd +,
    // m ≡ 0: even + and norm (none at m = 0)
    for (k, block) in blocks.iter().enumerate().rev() {
        let lane = if LANE { lane_blocks[k] } else { [[0.0; 3]; 4] };
        step!(block[3], lane[3], odd, lane_odd, -1.0, false);
        step!(block[2], lane[2], even, lane_even, -1.0, true);
        step!(block[1], lane[1], odd, lane_odd, 1.0, false);
        if k == 0 {
            break;
        }
        step!(block[0], lane[0], even, lane_even, 1.0, true);
        for l in 0..L {
            if j[l].abs() > 1e250 {
                j_above[l] *= 1e-250;
                j[l] *= 1e-250;
                even[l] *= 1e-250;
                odd[l] *= 1e-250;
                norm[l] *= 1e-250;
                if LANE {
                    lane_even[l] *= 1e-250;
                    lane_odd[l] *= 1e-250;
                }
            }
        }
        // the next block's top order: reseeded 64 orders below the last seed, and at m = 3,
        // where the terms of a short series are largest, by the multiple-angle formulas
        // sin 3θ = sin θ (4s² − 1), sin 4θ = 4 s sin θ (2s² − 1) (no sine to compute: a
        // sines_at there, as at 3 mod 64 before, cost a tenth of a short series)
        let m = 4 * k - 1;
        if m == 3 {
            for l in 0..L {
                let s2 = s[l] * s[l];
                sin_here[l] = sin_theta[l] * (4.0 * s2 - 1.0);
                sin_above[l] = 4.0 * s[l] * sin_theta[l] * (2.0 * s2 - 1.0);
            }
        } else if (start - m).is_multiple_of(64) {
            (sin_here, sin_above) = seed(m);
        }
    }
    // now j = J_0, j_above = J_1
    let mut out = [0.0; L];
    let mut lane = [0.0; L];
    for l in 0..L {
        let even = theta[l] * j_above[l] + even[l];
        let norm = j[l] + 2.0 * norm[l];
        // odd terms change sign with a (Jn(−x) = (−1)ⁿ Jn(x)); sin(a s) does too: the product is even
        let (sin_as, cos_as) = crate::fft::cis::sin_cos(x[l] * s[l]);
        out[l] = (4.0 / PI) * (cos_as * even + sin_as * odd[l]) / (x[l] * norm);
        if LANE {
            // m = 0: θ a K_0[J′] = −θ J_2, J_2 = (2/a) J_1 − J_0
            let lane_even = lane_even[l] - theta[l] * fused(two_over_x[l], j_above[l], -j[l]);
            let (real, imaginary) = (fused(s[l], odd[l], lane_even), fused(-s[l], even, lane_odd[l]));
            lane[l] = (4.0 / PI) * (cos_as * real + sin_as * imaginary) / norm;
        }
    }
    (out, lane)
}

/// `sin(mθ)` and `sin((m+1)θ)` in each lane, with `mθ` to the last bit: `θ = θ_hi + θ_lo` with
/// `θ_hi` on 24 bits, so that `m θ_hi` is exact (`m < 2^29`) and `b = m θ_lo` is small
/// (`|θ_lo| ≤ 1e-7`: `|b| ≤ 0.05` up to `m = 5e5`, past any start within the defocus budget), its
/// sine and cosine by Taylor's series to `b⁷`, `b⁸` (below 1e-17 there); no branch, so the
/// lanes vectorize.
#[inline(always)]
fn sines_at<const L: usize>(
    m: usize,
    s: [f64; L],
    theta: [f64; L],
    theta_hi: [f64; L],
    sin_theta: [f64; L],
) -> ([f64; L], [f64; L]) {
    let mut here = [0.0; L];
    let mut above = [0.0; L];
    let mf = m as f64;
    for l in 0..L {
        let (sin_a, cos_a) = crate::fft::cis::sin_cos(mf * theta_hi[l]);
        let b = mf * (theta[l] - theta_hi[l]);
        let b2 = b * b;
        let sin_b = b * (1.0 - b2 / 6.0 * (1.0 - b2 / 20.0 * (1.0 - b2 / 42.0)));
        let cos_b = 1.0 - b2 / 2.0 * (1.0 - b2 / 12.0 * (1.0 - b2 / 30.0 * (1.0 - b2 / 56.0)));
        let (sin_m, cos_m) = (sin_a * cos_b + cos_a * sin_b, cos_a * cos_b - sin_a * sin_b);
        here[l] = sin_m;
        above[l] = sin_m * s[l] + cos_m * sin_theta[l];
    }
    (here, above)
}

/// Where Miller's backward recurrence for `Jn(x)` starts: [`SERIES_MARGIN`] orders above the
/// first `n > x` with `(x/2)ⁿ/n! < ε`, a bound on `|Jn(x)|` for every `n` (so the terms left
/// out are below it), read from a table by `⌈x⌉` up to `x = 256`, or 16 orders above the
/// Debye estimate `x + 12 x^{1/3} + 24` where that is lower (the bound is loose for large `x`).
/// `ε` is the largest of [`SERIES_CUTS`] within `accuracy` (the OTF's error: the orders left
/// out add at most about `J_n` each, as the series' terms are `J_n` times factors below 1, and
/// Miller's normalization is off by about `J_n²`), 1e-17 when none is. The 1e-17 table starts
/// at half the Debye start at `|a| = 2`, 30 % lower at 30 and 10 % lower at 100 (the
/// spectrometer scene's nodes are mostly between); 1e-10 another 10–15 % lower: the
/// recurrence's cost is its length.
fn series_start(x: f64, accuracy: f64) -> usize {
    const SIZE: usize = 257;
    static TABLES: std::sync::OnceLock<[[u16; SIZE]; SERIES_CUTS.len()]> = std::sync::OnceLock::new();
    let debye = |x: f64| (x + 12.0 * x.cbrt() + 24.0) as usize + 16;
    if x.is_nan() || x > (SIZE - 1) as f64 {
        return debye(x);
    }
    let tables = TABLES.get_or_init(|| {
        // ln n for the orders the table reaches (about 400), once
        let ln: Vec<f64> = (0..1024).map(|n| (n as f64).ln()).collect();
        SERIES_CUTS.map(|cut: f64| {
            std::array::from_fn(|k| {
                // ln((x/2)ⁿ/n!) summed term by term, from n = 1
                let ln_half = (0.5 * k as f64).ln();
                let (mut n, mut log_term) = (0usize, 0.0_f64);
                while n < ln.len() - 1 && ((n as f64) <= k as f64 || log_term > cut.ln()) {
                    n += 1;
                    log_term += ln_half - ln[n];
                }
                (n + SERIES_MARGIN).min(debye(k as f64)) as u16
            })
        })
    });
    // the loosest cut within the accuracy (the cuts fall), else the full series
    let table = SERIES_CUTS.iter().position(|&cut| cut <= accuracy).unwrap_or(SERIES_CUTS.len() - 1);
    tables[table][x.max(0.0).ceil() as usize] as usize
}

/// The bounds on the orders left out that [`series_start`] has tables for, loosest first:
/// 1e-17 is the full series (its terms below the rounding of the sum).
const SERIES_CUTS: [f64; 4] = [1e-8, 1e-11, 1e-14, 1e-17];

/// Orders above the last significant one at which [`series_start`] starts Miller's recurrence.
const SERIES_MARGIN: usize = 8;

/// `(m, 1 − 1/m, 1 + 1/m)` for `m = 0 …` at least `up_to − 1` (`m = 0` unused): from a table up
/// to 4096, built for the call beyond. The series reads its per-order constants from it, four
/// orders a block, where it converted and looked up `m` at every step.
fn order_coefficients(up_to: usize) -> std::borrow::Cow<'static, [[f64; 3]]> {
    static TABLE: std::sync::OnceLock<Vec<[f64; 3]>> = std::sync::OnceLock::new();
    const SIZE: usize = 4096;
    let build = |size: usize| -> Vec<[f64; 3]> {
        (0..size)
            .map(|m| {
                let r = if m == 0 { 0.0 } else { 1.0 / m as f64 };
                [m as f64, 1.0 - r, 1.0 + r]
            })
            .collect()
    };
    if up_to <= SIZE {
        std::borrow::Cow::Borrowed(TABLE.get_or_init(|| build(SIZE)).as_slice())
    } else {
        std::borrow::Cow::Owned(build(up_to))
    }
}

/// `(2/m, (m − 1)(m − 2)/(2m), (m + 1)(m + 2)/(2m))` for `m = 0 …` at least `up_to − 1` (`m = 0`
/// unused): the per-order constants of the lane of [`bessel_lanes_with`], as
/// [`order_coefficients`] for the value.
fn lane_coefficients(up_to: usize) -> std::borrow::Cow<'static, [[f64; 3]]> {
    static TABLE: std::sync::OnceLock<Vec<[f64; 3]>> = std::sync::OnceLock::new();
    const SIZE: usize = 4096;
    let build = |size: usize| -> Vec<[f64; 3]> {
        (0..size)
            .map(|m| {
                if m == 0 {
                    return [0.0; 3];
                }
                let mf = m as f64;
                [2.0 / mf, (mf - 1.0) * (mf - 2.0) / (2.0 * mf), (mf + 1.0) * (mf + 2.0) / (2.0 * mf)]
            })
            .collect()
    };
    if up_to <= SIZE {
        std::borrow::Cow::Borrowed(TABLE.get_or_init(|| build(SIZE)).as_slice())
    } else {
        std::borrow::Cow::Owned(build(up_to))
    }
}

/// Pixel-aperture MTF `|sinc(p ν)| = |sin(π p ν)/(π p ν)|` of a square pixel of pitch `p` with
/// 100 % fill factor, along a pixel axis (`p` in m, `ν` in cycles/m).
pub fn pixel_mtf(pixel_pitch_m: f64, frequency: f64) -> f64 {
    let x = PI * pixel_pitch_m * frequency;
    if x.abs() < 1e-8 { 1.0 - x * x / 6.0 } else { (x.sin() / x).abs() }
}

/// Incoherent cutoff frequency `ν_c = 1/(λ F#)` in cycles/m.
pub fn cutoff_frequency(wavelength_m: f64, f_number: f64) -> f64 {
    1.0 / (wavelength_m * f_number)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn physics_test_vectors_hold_to_1e5() {
        for (s, w, expected) in crate::reference::PHYSICS_TEST_VECTORS {
            let got = defocus_otf(s, w);
            assert!((got - expected).abs() < 1e-5, "OTF({s}, {w}) = {got}, expected {expected}");
        }
    }

    /// `w ∂OTF/∂w` against the five-point central difference of [`defocus_otf`] in w (written
    /// here), step 1e-3 waves: truncation h⁴|∂⁵OTF/∂w⁵|/30 ≤ 1e-12 · (8πs)⁵/30 ≈ 6e-11 at
    /// s = 0.7, rounding ~1e-15/h; both forms of the value (quadrature and Bessel series, a from
    /// 0.6 to 53). Within 1e-9.
    #[test]
    fn log_derivative_matches_differences_of_the_otf() {
        let h = 1e-3;
        for &s in &[0.1, 0.3, 0.55, 0.7] {
            for &w in &[0.25, -1.0, 3.0] {
                let f = |x: f64| defocus_otf(s, x);
                let d = (f(w - 2.0 * h) - 8.0 * f(w - h) + 8.0 * f(w + h) - f(w + 2.0 * h)) / (12.0 * h);
                let got = defocus_otf_log_derivative(s, w);
                assert!((got - w * d).abs() <= 1e-9, "s {s} w {w}: {got} vs {}", w * d);
            }
        }
        assert_eq!(defocus_otf_log_derivative(0.3, 0.0), 0.0);
        assert_eq!(defocus_otf_log_derivative(1.0, 2.0), 0.0);
    }

    #[test]
    fn zero_defocus_is_the_diffraction_limited_mtf() {
        for i in 1..100 {
            let s = i as f64 / 100.0;
            // a tiny but non-zero defocus takes the quadrature branch
            let q = defocus_otf(s, 1e-6);
            assert!((q - mtf_diffraction_limited(s)).abs() < 1e-11, "s = {s}");
        }
    }

    #[test]
    fn even_in_defocus_and_bounded() {
        for &w in &[0.1, 0.7, 3.0, 40.0] {
            for i in 0..=50 {
                let s = i as f64 / 50.0;
                let p = defocus_otf(s, w);
                assert_eq!(p, defocus_otf(s, -w));
                assert!(p.abs() <= 1.0 + 1e-15 && p.is_finite());
            }
        }
    }

    #[test]
    fn panel_count_grows_with_defocus() {
        assert_eq!(defocus_otf_panels(0.3, 0.0), 1);
        let small = defocus_otf_panels(0.3, 1.0);
        let large = defocus_otf_panels(0.3, 1000.0);
        assert!(large > 100 * small, "{small} → {large}");
    }

    #[test]
    fn diffraction_limited_mean_closed_form() {
        // ∫_0^1 MTF_0 ds = 4/(3π) (docs/physics.md, "Test vectors and identities")
        assert!((mtf_diffraction_limited_mean(1.0) - 4.0 / (3.0 * PI)).abs() < 1e-15);
        // against quadrature of MTF_0 on [0, 0.37] (smooth there)
        let x = 0.37;
        let q = quad::composite(0.0, x, 4, mtf_diffraction_limited) / x;
        assert!((mtf_diffraction_limited_mean(x) - q).abs() < 1e-14);
        // past the cutoff the area stays 4/(3π)
        assert!((mtf_diffraction_limited_mean(2.0) - 2.0 / (3.0 * PI)).abs() < 1e-15);
    }

    #[test]
    fn bessel_series_matches_quadrature() {
        // two independent evaluations of the same integral, over the regime where both apply
        let mut worst: f64 = 0.0;
        for &w in &[0.05, 0.5, 2.0, 7.3, 31.0, 150.0, 1200.0] {
            for i in 1..60 {
                let s = i as f64 / 60.0;
                let a = 8.0 * PI * w * s;
                if a < 1.0 {
                    continue;
                }
                let d = (defocus_otf_bessel(s, a) - defocus_otf_quadrature(s, w)).abs();
                worst = worst.max(d);
            }
        }
        assert!(worst < 1e-12, "largest difference {worst:e}");
    }

    /// The series from its tabulated start (`series_start`: the bound `(|a|/2)ⁿ/n!` up to
    /// `|a| = 256`, the Debye start beyond) against the quadrature, densely over the table, across
    /// its end and where its entries switch to the Debye start, one lane and eight at once.
    #[test]
    fn bessel_series_from_its_start_matches_quadrature() {
        let mut points = Vec::new();
        for k in 0..=700 {
            let a = 1.0 + 0.41 * k as f64;
            for s in [0.03, 0.31, 0.77, 0.98] {
                let w = a / (8.0 * PI * s);
                let want = defocus_otf_quadrature(s, w);
                let got = defocus_otf_bessel(s, a);
                assert!((got - want).abs() < 1e-12, "a {a}, s {s}: {got} vs {want}");
                points.push((s, w, want));
            }
        }
        let mut out = vec![0.0; points.len()];
        defocus_otf_many(&points.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>(), &mut out);
        for (p, got) in points.iter().zip(out) {
            assert!((got - p.2).abs() < 1e-12, "many, s {}, w {}: {got} vs {}", p.0, p.1, p.2);
        }
    }

    /// The batched evaluation (eight interleaved lanes from the largest lane's start) against
    /// one call each: points of very different defocus side by side (a lane with |a| = 1 next
    /// to one with |a| = 3e4 starts its recurrence far above its own start), points on the
    /// quadrature and outside (0, 1), in an order that leaves a remainder of three.
    #[test]
    fn many_at_once_is_each_alone() {
        let mut points = Vec::new();
        for &w in &[0.0, 0.01, -0.2, 0.9, 3.0, -12.0, 80.0, 1200.0] {
            for i in 0..=24 {
                points.push((i as f64 / 20.0 - 0.1, w));
            }
        }
        points.extend([(0.5, 1.0 / (8.0 * PI * 0.5)), (0.5, 3e4 / (8.0 * PI * 0.5)), (0.2, 40.0)]);
        let mut out = vec![f64::NAN; points.len()];
        defocus_otf_many(&points, &mut out);
        for (&(s, w), &got) in points.iter().zip(&out) {
            let want = defocus_otf(s, w);
            assert!((got - want).abs() <= 1e-12, "({s}, {w}): {got} vs {want}");
        }
        // every length of the last batch (one to seven lanes filled, and full)
        for n in 1..=17 {
            let few: Vec<(f64, f64)> = (0..n).map(|k| (0.1 + 0.08 * k as f64, 2.0 + 3.0 * k as f64)).collect();
            let mut out = vec![f64::NAN; n];
            defocus_otf_many(&few, &mut out);
            for (&(s, w), &got) in few.iter().zip(&out) {
                assert!((got - defocus_otf(s, w)).abs() <= 1e-12, "{n} points, ({s}, {w}): {got}");
            }
        }
    }

    /// Each of the series' shorter starts keeps its accuracy: the points of
    /// `many_at_once_is_each_alone` and the spectrometer scene's range (|a| up to 150 at s ≈
    /// 0.2) at accuracies from 1e-6 to 1e-16, against the full series.
    #[test]
    fn shorter_series_keep_their_accuracy() {
        let mut points = Vec::new();
        for &w in &[0.01, -0.2, 0.9, 3.0, -12.0, 28.0, 80.0, 1200.0] {
            for i in 1..40 {
                points.push((i as f64 / 40.0, w));
            }
        }
        let mut exact = vec![0.0; points.len()];
        defocus_otf_many(&points, &mut exact);
        for &accuracy in &[1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 1e-16] {
            let mut out = vec![f64::NAN; points.len()];
            defocus_otf_many_within(&points, &mut out, accuracy);
            for ((&(s, w), &got), &want) in points.iter().zip(&out).zip(&exact) {
                assert!((got - want).abs() <= accuracy.max(1e-15), "({s}, {w}) at {accuracy:e}: {got} vs {want}");
            }
        }
    }

    /// The asymptotic expansion against the Bessel series wherever it answers: s over (0, 1),
    /// a(1 − s) from [`ASYMPTOTIC_MIN_PHASE`] to 3e3, both signs of a, targets 1e-6 to 1e-14; it
    /// must answer (not fall back) on most of that range at 1e-12, and from 18 at 1e-8 (a scan
    /// of 400 s × 60 phases from 18 to 30 found the error at most 0.70 of the target).
    #[test]
    fn asymptotic_expansion_matches_the_series() {
        let (mut answered, mut asked, mut answered_near, mut asked_near) = (0, 0, 0, 0);
        for i in 1..40 {
            let s = i as f64 / 40.0;
            for &phase in &[ASYMPTOTIC_MIN_PHASE, 22.0, 26.0, 30.0, 45.0, 80.0, 150.0, 400.0, 3000.0] {
                for &sign in &[1.0, -1.0] {
                    let a = sign * phase / (1.0 - s);
                    let exact = defocus_otf_bessel(s, a);
                    for &target in &[1e-6, 1e-8, 1e-10, 1e-12, 1e-14] {
                        let fast = defocus_otf_asymptotic(s, a, target);
                        if let Some(fast) = fast {
                            assert!(
                                (fast - exact).abs() <= target + 1e-14,
                                "s {s}, a {a}, target {target:e}: {fast} vs {exact}"
                            );
                        }
                        if target == 1e-12 && phase >= 30.0 {
                            asked += 1;
                            answered += usize::from(fast.is_some());
                        }
                        if target == 1e-8 && phase <= 22.0 {
                            asked_near += 1;
                            answered_near += usize::from(fast.is_some());
                        }
                    }
                }
            }
        }
        assert!(answered * 10 >= asked * 8, "answered {answered} of {asked}");
        assert!(answered_near * 10 >= asked_near * 8, "from 18 at 1e-8: answered {answered_near} of {asked_near}");
    }

    /// Five-point central difference of `f` in `a`, times `a` (written here): the reference for
    /// each form's lane `a ∂OTF/∂a`.
    fn log_difference(f: &dyn Fn(f64) -> f64, a: f64, h: f64) -> f64 {
        a * (f(a - 2.0 * h) - 8.0 * f(a - h) + 8.0 * f(a + h) - f(a + 2.0 * h)) / (12.0 * h)
    }

    /// The Bessel series' lane (`bessel_lanes_with`) against five-point differences of the
    /// series itself in `a`, step `h = 1e-3 max(1, |a|/100)` (`1e-3 |a|` below `|a| = 1`): truncation `h⁴ |∂⁵_a OTF|/30 ≤
    /// h⁴/30` (each `a`-derivative brings a factor `|cos t − s| ≤ 1`), rounding about
    /// `1e-16 |a|/h`; within `1e-9 max(1, |a|)`. Over `0 < s < 1` and `|a|(1 − s)` from `1e-8`
    /// (where the series starts: the value's switch to the diffraction-limited MTF) through 1,
    /// 24 (the single value's switch from the quadrature) and 18 to 30 (the expansion's switch)
    /// up to 3000, both signs; and against the t-form quadrature of the lane
    /// ([`defocus_otf_log_derivative`], an independent form) within `1e-11 max(1, |a|)`.
    #[test]
    fn bessel_lane_matches_differences_of_the_series() {
        for i in 1..20 {
            let s = i as f64 / 20.0;
            for &phase in
                &[1.01e-8, 1e-6, 1e-3, 0.5, 0.999, 1.0, 1.001, 5.0, 17.99, 18.0, 18.01, 23.9, 24.1, 30.0, 200.0, 3000.0]
            {
                for &sign in &[1.0, -1.0] {
                    let a = sign * phase / (1.0 - s);
                    let (value, lane) = bessel_lanes_with::<1, true>([s], [a], 0.0);
                    assert_eq!(value[0], bessel_lanes([s], [a], 0.0)[0], "the value is the series' own");
                    let h = if a.abs() < 1.0 { 1e-3 * a.abs() } else { 1e-3 * (a.abs() / 100.0).max(1.0) };
                    let series = |a: f64| bessel_lanes([s], [a], 0.0)[0];
                    let reference = log_difference(&series, a, h);
                    let scale = a.abs().max(1.0);
                    assert!(
                        (lane[0] - reference).abs() <= 1e-9 * scale,
                        "s {s}, a {a}: lane {} vs differences {reference}",
                        lane[0]
                    );
                    let quadrature = defocus_otf_log_derivative(s, a / (8.0 * PI * s));
                    assert!(
                        (lane[0] - quadrature).abs() <= 1e-11 * scale,
                        "s {s}, a {a}: lane {} vs t-form {quadrature}",
                        lane[0]
                    );
                }
            }
        }
    }

    /// The expansion's lane against five-point differences of the expansion itself in `a`
    /// (at the target 1e-15, step `h = 0.01/(1 − s)`, a hundredth of a radian of the phase
    /// `a(1 − s)`: truncation about `a(1 − s) h⁴(1 − s)⁴/30`, rounding `1e-15 |a|/h`, both below
    /// `1e-9 a(1 − s)` relative to the OTF's size), within `1e-9 a(1 − s)`, and against
    /// the Bessel series' lane within `target · max(1, a(1 − s))` plus rounding, wherever it
    /// answers: `a(1 − s)` from 18 (its switch) to 3000, both signs, targets 1e-6 to 1e-14.
    #[test]
    fn asymptotic_lane_matches_differences_and_the_series() {
        let mut answered = 0;
        for i in 1..40 {
            let s = i as f64 / 40.0;
            for &phase in &[ASYMPTOTIC_MIN_PHASE, 18.5, 22.0, 26.0, 30.0, 45.0, 80.0, 150.0, 400.0, 3000.0] {
                for &sign in &[1.0, -1.0] {
                    let a = sign * phase / (1.0 - s);
                    let (value, series_lane) = bessel_lanes_with::<1, true>([s], [a], 0.0);
                    for &target in &[1e-6, 1e-8, 1e-10, 1e-12, 1e-14] {
                        let Some((fast, lane)) = defocus_otf_asymptotic_and_log_derivative(s, a, target) else {
                            continue;
                        };
                        answered += 1;
                        assert!((fast - value[0]).abs() <= target + 1e-14, "s {s}, a {a}: {fast} vs {}", value[0]);
                        assert!(
                            (lane - series_lane[0]).abs() <= target * phase.max(1.0) + 1e-12 * phase,
                            "s {s}, a {a}, target {target:e}: lane {lane} vs the series' {}",
                            series_lane[0]
                        );
                        if target == 1e-14 {
                            let h = 1e-2 / (1.0 - s);
                            let expansion = |a: f64| defocus_otf_asymptotic(s, a, 1e-15).unwrap_or(f64::NAN);
                            let reference = log_difference(&expansion, a, h);
                            if reference.is_finite() {
                                assert!(
                                    (lane - reference).abs() <= 1e-9 * phase,
                                    "s {s}, a {a}: lane {lane} vs differences {reference}"
                                );
                            }
                        }
                    }
                }
            }
        }
        assert!(answered > 1000, "answered {answered}");
    }

    /// Many points at once (values and lanes) against the single forms: the values equal to
    /// [`defocus_otf_many_within`] bit for bit, the lanes to the t-form quadrature
    /// within `accuracy · max(1, |a|(1 − s))` plus rounding, over `|a|(1 − s)` below `1e-8`
    /// (the lane 0), through the series and the expansion.
    #[test]
    fn many_lanes_are_each_alone() {
        let mut points = Vec::new();
        for i in 1..30 {
            let s = i as f64 / 30.0;
            for &phase in &[1e-10, 1e-7, 0.3, 3.0, 17.0, 19.0, 60.0, 700.0] {
                points.push((s, phase / (1.0 - s) / (8.0 * PI * s)));
            }
        }
        points.push((0.0, 1.0));
        points.push((1.0, 1.0));
        for &accuracy in &[0.0, 1e-12, 1e-9, 1e-6] {
            let mut values = vec![0.0; points.len()];
            let mut lanes = vec![0.0; points.len()];
            let mut plain = vec![0.0; points.len()];
            defocus_otf_many_and_log_derivative_within(&points, &mut values, &mut lanes, accuracy);
            defocus_otf_many_within(&points, &mut plain, accuracy);
            for (k, &(s, w)) in points.iter().enumerate() {
                let phase = (8.0 * PI * w * s).abs() * (1.0 - s);
                let loose = accuracy.max(1e-14);
                // the value's own forms: bit for bit
                assert_eq!(values[k].to_bits(), plain[k].to_bits(), "s {s}, w {w}: {} vs {}", values[k], plain[k]);
                let reference = defocus_otf_log_derivative(s, w);
                assert!(
                    (lanes[k] - reference).abs() <= loose * phase.max(1.0) * 2.0 + 1e-11 * phase.max(1.0),
                    "s {s}, w {w}, accuracy {accuracy:e}: {} vs {reference}",
                    lanes[k]
                );
            }
        }
        assert_eq!(defocus_otf_and_log_derivative(0.4, 0.0), (mtf_diffraction_limited(0.4), 0.0));
    }

    /// Below `|a| = 1`, where [`defocus_otf_many`] takes the series too: within 1e-15 of the
    /// quadrature from `|a|(1 − s) = 1e-8` up, over `0 < s < 1`.
    #[test]
    fn bessel_series_holds_at_small_defocus() {
        for i in 1..100 {
            let s = i as f64 / 100.0;
            for e in 0..=56 {
                let a = 10f64.powf(-8.0 + e as f64 / 7.0);
                if a * (1.0 - s) < 1e-8 {
                    continue;
                }
                let w = a / (8.0 * PI * s);
                let (quadrature, series) = (defocus_otf_quadrature(s, w), bessel_lanes([s], [a], 0.0)[0]);
                assert!((quadrature - series).abs() <= 1e-15, "s {s}, a {a:e}: {quadrature} vs {series}");
            }
        }
    }

    /// A batch starts at its largest lane's start: the start never falls as |a| grows.
    #[test]
    fn series_start_grows_with_a() {
        for &accuracy in &[1e-6, 1e-9, 1e-12, 1e-15, 0.0] {
            let mut last = 0;
            for i in 0..=4000 {
                let start = series_start(i as f64 * 0.1, accuracy);
                assert!(start >= last, "accuracy {accuracy:e}, |a| {}: {start} after {last}", i as f64 * 0.1);
                last = start;
            }
        }
    }

    #[test]
    fn bessel_series_is_even_in_a() {
        assert!((defocus_otf_bessel(0.3, 40.0) - defocus_otf_bessel(0.3, -40.0)).abs() < 1e-15);
    }

    #[test]
    fn pixel_mtf_values() {
        // p ν = 1/2 (Nyquist): sinc = sin(π/2)/(π/2) = 2/π
        assert!((pixel_mtf(5.2e-6, 1.0 / (2.0 * 5.2e-6)) - 2.0 / PI).abs() < 1e-15);
        assert_eq!(pixel_mtf(5.2e-6, 0.0), 1.0);
    }
}
