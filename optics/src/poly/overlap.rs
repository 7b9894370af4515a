//! The overlap engine: the OTF of a full circular pupil with a polynomial wavefront (defocus,
//! the Seidel terms and Zernike terms) as a quadrature over the two pupils' overlap, at exactly the frequencies and
//! azimuths the metric's rules ask for (docs/physics.md, "Analytic 2-D pupils by quadrature over
//! the overlap").
//!
//! In units of the pupil radius, at normalized frequency `s = ν λ F#` along the azimuth φ (unit
//! vector `e`, `e⊥` across it), the OTF is the normalized autocorrelation
//!
//! ```text
//! O(s, φ) = (1/π) ∬_{|p₊| ≤ 1, |p₋| ≤ 1} exp(i k [W(p₋) − W(p₊)]) dx dy,   p± = (x ± s) e + y e⊥
//! ```
//!
//! (the sign that gives a tilt `W = NA Δ·ρ` the image-shift phase `exp(−2πi ν·Δ)`; the rules
//! below integrate `exp(i k [W(p₊) − W(p₋)])` and take the conjugate).
//!
//! The overlap is `|y| ≤ sin T`, `|x| ≤ X(y) = √(1 − y²) − s`, `T = acos s`. With `y = sin t`
//! (dy = cos t dt) and `x = X u`, `X = cos t − s` is analytic in t and the square-root edge is
//! gone (the t-form of the 1-D defocused OTF, docs/physics.md "Exact defocused OTF"). Defocus
//! (and field curvature) give the difference `4 s (W020 + W220) x`, linear in x: its factor
//! `e^{i a X u}`, `a = 8π s (W020 + W220)/λ`, is integrated exactly against the Legendre
//! interpolant of the rest `h(u) = exp(i k ΔW_rest)` at `n` Gauss–Legendre points
//! (`∫_{−1}^{1} P_m(u) e^{ibu} du = 2 i^m j_m(b)`, spherical Bessel functions; a Filon-type
//! rule), so the defocus of the chromatic lens costs no points in x. The t integral is nested
//! Clenshaw–Curtis, its error bounded by the tail of its own Chebyshev coefficients.

use std::cell::Cell;
use std::f64::consts::PI;
use std::sync::OnceLock;

use num_complex::Complex64;

use super::spectral::{Nodes, Scene};
use super::{Engine, FrequencyRule, OtfEngine, WavefrontDirection};
use crate::fft::{Aberrations, Compiled, noll_to_nm, sin_cos};
use crate::lens::Pupil;
use crate::radial::RadialPupil;
use std::sync::Arc;

/// The Gauss–Legendre levels of the x rule (points), coarsest first.
const X_LEVELS: [usize; 8] = [6, 8, 12, 16, 24, 32, 48, 64];

/// The nested Clenshaw–Curtis levels of the t rule (points).
const T_LEVELS: [usize; 6] = [5, 9, 17, 33, 65, 129];

/// The largest defocus phase `k|W020|` (radians) the overlap engine takes: the t rule's last
/// level resolves it (a point per radian and five more); beyond it the FFT path takes the scene.
const MAX_DEFOCUS_PHASE: f64 = (T_LEVELS[T_LEVELS.len() - 1] - 5) as f64;

/// Share of the value tolerance the x rule may spend (the t rule takes the rest).
const X_SHARE: f64 = 0.25;

/// The most a skipped node's weight may add up to, relative to the total weight and the
/// tolerance: the OTF of a node is at most 1 in modulus, so skipping them moves the normalized
/// OTF by at most this times the tolerance.
const SKIP_SHARE: f64 = 1e-3;

/// One spectral node's order: its wavelength, weight and wavefront (m at the pupil edge, the
/// field along +x at `H = 1`), with the x rule's level chosen for it.
#[derive(Clone)]
struct Term {
    lambda: f64,
    weight: f64,
    shift: [f64; 2],
    /// `[∂Δx/∂θx, ∂Δy/∂θy]` (m per radian), where the lens gives it
    /// (`LensModel::image_shift_field_rates`): the field angles' lanes
    shift_rate: Option<[f64; 2]>,
    /// W020 + W220 (m): the part whose difference is linear in x
    defocus: f64,
    /// the order's own defocus W020 (m; without the field curvature and a Zernike pupil's
    /// terms): the scale of the [`WavefrontDirection::Defocus`] lane at this node
    lens_defocus: f64,
    /// `[∂W020/∂ln λ0 (m), (∂τ/∂ln λ0)/τ]` of the order at this node, where the lens gives its
    /// design-wavelength rates (`LensModel::design_wavelength_rates`): the scale of the
    /// [`WavefrontDirection::DesignWavelength`] lane's `ρ²` and of its efficiency term
    design: Option<[f64; 2]>,
    spherical: f64,
    coma: f64,
    astigmatism: f64,
    /// the Zernike terms beyond what `defocus` and `spherical` carry (every term with `m ≠ 0`,
    /// and `m = 0` terms of radial order `n ≥ 6`), m, with the highest radial order among them
    zernike: Option<(Arc<Compiled>, usize)>,
    /// the Noll indices and coefficients (m) `zernike` holds
    zernike_rest: Vec<(usize, f64)>,
    /// the node's highest normalized frequency (at the frequency limit), where its x rule is
    /// probed
    s_top: f64,
    /// bounds on the rest of the wavefront `W_rest` (all but the defocus part) over the unit
    /// disc, m: the largest `|∇W_rest|` and the largest second derivative along a direction
    /// ([`Term::rest_bounds`]), read by [`Term::otf_bound`]
    slope: f64,
    curvature: f64,
}

impl Term {
    /// `k [W_rest(p₊) − W_rest(p₋)]`, the wavefront difference without the defocus part, with
    /// `W_rest = W040 r⁴ + W131 r² x + W222 x² + Σ c_j Z_j` (radians; the Zernike terms
    /// `defocus` and `spherical` do not carry).
    #[inline]
    fn rest_phase(&self, k: f64, xa: f64, ya: f64, xb: f64, yb: f64) -> f64 {
        let w = |x: f64, y: f64| {
            let r2 = x * x + y * y;
            r2 * (self.spherical * r2 + self.coma * x) + self.astigmatism * x * x
        };
        let mut d = w(xa, ya) - w(xb, yb);
        if let Some((z, _)) = &self.zernike {
            d += z.opd_m(xa, ya) - z.opd_m(xb, yb);
        }
        k * d
    }

    /// Bounds on `W_rest = W040 r⁴ + W131 r² x + W222 x² + Σ c_j Z_j` over the unit disc: the
    /// largest `|∇W_rest|` and the largest `|∂²W_rest/∂e²|` along any unit vector `e` (m). Per
    /// term: `|∇r⁴| = 4r³ ≤ 4` and its Hessian `4r² I + 8 p pᵀ` at most 12; `∇(r² x) = (3x² + y²,
    /// 2xy)`, at most `3r² ≤ 3`, its Hessian `[[6x, 2y], [2y, 2x]]` with eigenvalues `4x ± 2r`,
    /// at most 6; `x²`: 2 and 2. A Zernike term is a polynomial of degree `n` bounded by its
    /// normalization `N = √(2(n + 1))` (`√(n + 1)` for `m = 0`) on the disc (`|R_n^m| ≤ 1`), so by
    /// Kellogg's inequality (O. D. Kellogg, Math. Z. 27 (1928) 55: a polynomial of degree `n`
    /// bounded by 1 on the unit ball has `|∇P| ≤ n²` there) `|∇Z| ≤ n² N`, and `∂_e Z`, of degree
    /// `n − 1` and bounded by `n² N`, has `|∂²_e Z| ≤ (n − 1)² n² N`.
    fn rest_bounds(&self) -> (f64, f64) {
        let (w040, w131, w222) = (self.spherical.abs(), self.coma.abs(), self.astigmatism.abs());
        let mut slope = 4.0 * w040 + 3.0 * w131 + 2.0 * w222;
        let mut curvature = 12.0 * w040 + 6.0 * w131 + 2.0 * w222;
        for &(j, c) in &self.zernike_rest {
            let (n, m) = noll_to_nm(j);
            let norm = if m == 0 { ((n + 1) as f64).sqrt() } else { (2.0 * (n + 1) as f64).sqrt() };
            let (n2, below) = ((n * n) as f64, (n.saturating_sub(1) * n.saturating_sub(1)) as f64);
            slope += c.abs() * n2 * norm;
            curvature += c.abs() * below * n2 * norm;
        }
        (slope, curvature)
    }

    /// An a-priori bound on the modulus of this node's OTF at normalized frequency `s` (any
    /// azimuth; docs/physics.md, "Analytic 2-D pupils by quadrature over the overlap", "A-priori
    /// bounds"): the least of 1, the diffraction-limited OTF `(2/π)(T − s sin T)` (the overlap's
    /// area over π: `|∫ e^{iψ}| ≤ ∫ 1`), and the bound from one integration by parts in x. With
    /// the defocus phase `a x` (`a = 4 s k (W020 + W220)`) and `h = e^{i k ΔW_rest}`,
    /// `|∫_{−X}^{X} e^{iax} h dx| ≤ (2 + ∫ |∂h/∂x| dx)/|a| ≤ (2 + 2X g)/|a|`, where `∂_x ΔW_rest =
    /// e·(∇W_rest(p₊) − ∇W_rest(p₋))` is at most `2 × slope` and, the segment from `p₋` to `p₊`
    /// (length 2s) lying in the disc, at most `2s × curvature`: `g = k min(2 slope, 2s
    /// curvature)`. Then `|O| ≤ (1/π) ∫_{−T}^{T} cos t (2 + 2X g)/|a| dt = (4 sin T + 2g(T − s sin
    /// T))/(π |a|)` (`∫ cos t dt = 2 sin T`, `∫ cos t (cos t − s) dt = T − s sin T`).
    fn otf_bound(&self, s: f64) -> f64 {
        if s >= 1.0 {
            return 0.0;
        }
        let k = 2.0 * PI / self.lambda;
        let big_t = s.acos();
        let sin_t = (1.0 - s * s).sqrt();
        let area = big_t - s * sin_t;
        let mut bound = (2.0 / PI * area).min(1.0);
        let a = (4.0 * s * k * self.defocus).abs();
        if a > 0.0 {
            let g = k * (2.0 * self.slope).min(2.0 * s * self.curvature);
            bound = bound.min((4.0 * sin_t + 2.0 * g * area) / (PI * a));
        }
        bound
    }

    fn has_rest(&self) -> bool {
        self.spherical != 0.0 || self.coma != 0.0 || self.astigmatism != 0.0 || self.zernike.is_some()
    }

    /// Whether `W(p₊) − W(p₋)` is at most quadratic in x (the wavefront at most cubic: no
    /// spherical aberration, Zernike terms of radial order ≤ 3), so that the value's x integral
    /// is in closed form ([`quadratic_phase_integral`]).
    fn quadratic(&self) -> bool {
        self.spherical == 0.0 && self.zernike.as_ref().is_none_or(|(_, n)| *n <= 3)
    }

    /// Whether the wavefront is even in y (no Zernike sine term): with every image shift along
    /// x the pupil is then symmetric about x.
    fn even_in_y(&self) -> bool {
        self.zernike.as_ref().is_none_or(|(z, _)| !z.has_sine_terms())
    }
}

/// A Gauss–Legendre level of the x rule with its Legendre projection: `a[m][j] = (2m + 1)/2 ·
/// w_j P_m(u_j)`, so that `c_m = Σ_j a[m][j] h(u_j)` are the interpolant's Legendre coefficients.
struct XRule {
    nodes: Vec<f64>,
    projection: Vec<Vec<f64>>,
}

fn x_rule(level: usize) -> &'static XRule {
    static RULES: OnceLock<Vec<XRule>> = OnceLock::new();
    let rules = RULES.get_or_init(|| {
        X_LEVELS
            .iter()
            .map(|&n| {
                let gl = crate::quad::gauss_legendre(n);
                let nodes: Vec<f64> = gl.iter().map(|p| p.0).collect();
                let mut projection = vec![vec![0.0; n]; n];
                for (j, &(u, w)) in gl.iter().enumerate() {
                    // P_m(u) by the three-term recurrence
                    let (mut p0, mut p1) = (1.0, u);
                    for (m, row) in projection.iter_mut().enumerate() {
                        let p = if m == 0 { p0 } else { p1 };
                        row[j] = 0.5 * (2 * m + 1) as f64 * w * p;
                        if m >= 1 {
                            let next = ((2 * m + 1) as f64 * u * p1 - m as f64 * p0) / (m + 1) as f64;
                            (p0, p1) = (p1, next);
                        }
                    }
                }
                XRule { nodes, projection }
            })
            .collect()
    });
    &rules[level]
}

/// The spherical Bessel functions `j_m(b)`, `m = 0 … out.len() − 1`, by Miller's downward
/// recurrence `j_{m−1} = (2m + 1)/b j_m − j_{m+1}` from well above both `m` and `|b|`,
/// normalized by `Σ (2m + 1) j_m² = 1` (Abramowitz & Stegun 10.1.50) and signed by the larger of
/// `j_0 = sin b/b` and `j_1`.
fn spherical_bessel(b: f64, out: &mut [f64]) {
    let n = out.len();
    let x = b.abs();
    if x < 1e-8 {
        out.iter_mut().enumerate().for_each(|(m, o)| *o = if m == 0 { 1.0 } else { 0.0 });
        return;
    }
    let start = n.max(x as usize) + 24 + (x.sqrt() as usize);
    let (mut above, mut here) = (0.0_f64, 1e-30_f64);
    let mut norm = 0.0;
    for m in (0..=start).rev() {
        // here = j_m (unnormalized), above = j_{m+1}
        norm += (2 * m + 1) as f64 * here * here;
        if m < n {
            out[m] = here;
        }
        if m == 0 {
            break;
        }
        let below = (2 * m + 1) as f64 / x * here - above;
        (above, here) = (here, below);
        if here.abs() > 1e150 {
            // rescale what is held so far (the stored orders and the running sum)
            let f = 1e-150;
            here *= f;
            above *= f;
            norm *= f * f;
            out.iter_mut().skip(m.saturating_sub(1)).for_each(|o| *o *= f);
        }
    }
    let mut scale = 1.0 / norm.sqrt();
    let (j0, j1) = (x.sin() / x, (x.sin() / x - x.cos()) / x);
    let sign = if j0.abs() >= j1.abs() { j0 * out[0] } else { j1 * out.get(1).copied().unwrap_or(j1) };
    if sign < 0.0 {
        scale = -scale;
    }
    for (m, o) in out.iter_mut().enumerate() {
        *o *= scale;
        if b < 0.0 && m % 2 == 1 {
            *o = -*o;
        }
    }
}

/// Puts the Zernike terms of `pupil` (the full circle with Zernike terms alone,
/// [`RadialPupil::is_zernike_only`]) on `term`'s wavefront (docs/physics.md, "Zernike terms on
/// the overlap engine"). The order's `defocus_m` holds the pupil's best-fit defocus
/// ([`Order::radial`](crate::Order::radial)), which the pupil's OPD takes off again; of the
/// `m = 0` terms, `Z4 = √3 (2ρ² − 1)` adds `2√3 c` to the defocus and `Z11 = √5 (6ρ⁴ − 6ρ² + 1)`
/// adds `6√5 c` to the spherical aberration and `−6√5 c` to the defocus (Noll 1976, Table I;
/// a piston drops out of `W(p₊) − W(p₋)`), so that the defocus rule takes what is linear in the
/// lag; every other term stays a polynomial in the pupil coordinates ([`Compiled`], the FFT
/// path's own evaluation of Noll's polynomials).
fn add_zernike(term: &mut Term, pupil: &RadialPupil) {
    term.defocus -= pupil.fitted_defocus_m();
    term.lens_defocus -= pupil.fitted_defocus_m();
    let mut rest = Vec::new();
    let mut degree = 0;
    for &(j, c) in pupil.zernike_noll_m() {
        if c == 0.0 {
            continue;
        }
        match noll_to_nm(j) {
            (0, 0) => {}
            (2, 0) => term.defocus += 2.0 * 3f64.sqrt() * c,
            (4, 0) => {
                let a = 6.0 * 5f64.sqrt() * c;
                term.spherical += a;
                term.defocus -= a;
            }
            (n, _) => {
                rest.push((j, c));
                degree = degree.max(n);
            }
        }
    }
    if !rest.is_empty() {
        let compiled = Compiled::new(&Aberrations { zernike_noll_m: rest.clone(), ..Aberrations::default() });
        term.zernike = Some((Arc::new(compiled), degree));
        term.zernike_rest = rest;
    }
}

/// Clenshaw–Curtis weights at `points` (one of [`T_LEVELS`]) on [−1, 1].
fn cc_weights(points: usize) -> &'static [f64] {
    super::frequency::clenshaw_curtis(points)
}

/// The overlap engine over the spectral nodes of a scene whose every order is the full circle
/// with a polynomial wavefront.
#[derive(Debug)]
pub(super) struct Overlap<'a> {
    scene: Scene<'a>,
    nodes: Nodes,
    terms: Vec<Term>,
    /// the absolute error allowed in one OTF value (the frequency rule sets it)
    value_tolerance: Cell<f64>,
    /// the largest t-rule error estimate accepted beyond its share (at the last level)
    worst: Cell<f64>,
    /// per node, the x rule's probed tail at each level computed so far ([`x_tail`])
    tails: std::cell::RefCell<Vec<Vec<f64>>>,
    /// whether every image shift is along x (the Seidel pupil is symmetric about x): then
    /// `O(ν, π − φ) = O(ν, φ)*` and a mirrored azimuth's values are reused
    mirror: bool,
    /// values by (frequency, value tolerance, azimuth mod π in nrad)
    mirrored: std::cell::RefCell<std::collections::HashMap<(u64, u64, i64), Complex64>>,
    /// values and Seidel derivatives by the same keys ([`OtfEngine::otf_along_and_gradient`])
    differentiated: std::cell::RefCell<std::collections::HashMap<(u64, u64, i64), Differentiated>>,
    /// the wavefront lanes of the directions last asked ([`Lane::of`]: each Zernike lane's
    /// polynomial compiled once, not at every OTF value), with the field angles' axes
    lanes: std::cell::RefCell<Option<LaneSet>>,
    /// per term, its spectral sample's wavelength (bits) and part and its order's place at that
    /// wavelength: where the defocus lane's rule meets the value's nodes ([`DefocusRule`])
    keys: Vec<(u64, usize, usize)>,
    /// the defocus lane's own spectral rule, built when the lane is first asked
    defocus_rule: std::cell::OnceCell<Option<DefocusRule>>,
}

/// The [`WavefrontDirection::Defocus`] lane's own spectral rule (docs/physics.md, "Gradients:
/// the F-number and the focal length with Seidel terms"): each panel's `2n − 1` nested
/// Chebyshev–Lobatto points over the value's `n` ([`spectral::doubled`](super::spectral::doubled)).
/// The lane reads the value's terms at the even points (their OTF and lane are computed for the
/// value anyway) with this rule's weights, and computes the odd points' terms for the lane alone;
/// the value's own sums are not touched.
#[derive(Debug)]
struct DefocusRule {
    /// per value term, this rule's weight (efficiency included) at its wavelength
    weights: Vec<f64>,
    /// the odd points' terms (and any even point's the value left out as light), weighted by
    /// this rule
    extra: Vec<Term>,
    /// the x rule's probed tails of `extra` ([`x_tail`])
    tails: std::cell::RefCell<Vec<Vec<f64>>>,
    /// Σ weights × efficiencies over every point and order of the rule
    total: f64,
}

/// The directions of a gradient, their wavefront lanes and field angles' axes in their order.
type LaneSet = (Vec<WavefrontDirection>, Arc<Vec<Lane>>, Vec<usize>);

/// An OTF value with its Seidel derivatives ([`OtfEngine::otf_along_and_gradient`]).
type Differentiated = (Complex64, Vec<Complex64>);

impl std::fmt::Debug for Term {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Term {{ λ = {} m, weight {} }}", self.lambda, self.weight)
    }
}

impl<'a> Overlap<'a> {
    /// The engine for `scene` and its `nodes`, or `None` where some order is not the full circle
    /// with Seidel and Zernike terms (an aperture, a map, a radial profile or amplitude, an
    /// oblique radial pupil, a table): the FFT path takes it.
    pub fn new(scene: Scene<'a>, nodes: Nodes, tolerance: f64) -> Option<Overlap<'a>> {
        let mut terms = Vec::new();
        let mut keys = Vec::new();
        for &(lambda, weight, part) in &nodes.samples {
            if weight == 0.0 {
                continue;
            }
            for (o, term) in sample_terms(&scene, lambda, weight, part)?.into_iter().enumerate() {
                if let Some(term) = term {
                    terms.push(term);
                    keys.push((lambda.to_bits(), part, o));
                }
            }
        }
        let total = nodes.total_weight;
        if terms.is_empty() || total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        // skip the lightest nodes while their weights add up to at most SKIP_SHARE of the
        // tolerance (their OTFs are at most 1)
        let mut order: Vec<usize> = (0..terms.len()).collect();
        order.sort_by(|&a, &b| terms[a].weight.abs().total_cmp(&terms[b].weight.abs()));
        let mut skipped = 0.0;
        let mut keep = vec![true; terms.len()];
        for i in order {
            if skipped + terms[i].weight.abs() > SKIP_SHARE * tolerance * total {
                break;
            }
            skipped += terms[i].weight.abs();
            keep[i] = false;
        }
        let keys: Vec<(u64, usize, usize)> = keys.into_iter().zip(&keep).filter(|(_, k)| **k).map(|(t, _)| t).collect();
        let mut kept: Vec<Term> = terms.into_iter().zip(keep).filter(|(_, k)| *k).map(|(t, _)| t).collect();
        // a defocus the t rule cannot resolve (its phase 4s(1 − s) k|W020| peaks at k|W020|, at
        // s = 1/2; each level needs a point per radian and five more): the FFT path takes the scene — a harmonic lens's far orders with
        // Zernike terms (docs/physics.md, "Zernike terms on the overlap engine")
        if kept.iter().any(|t| 2.0 * PI / t.lambda * t.defocus.abs() > MAX_DEFOCUS_PHASE) {
            return None;
        }
        let mut engine = Overlap {
            scene,
            nodes,
            terms: Vec::new(),
            value_tolerance: Cell::new(0.05 * tolerance),
            worst: Cell::new(0.0),
            tails: std::cell::RefCell::new(Vec::new()),
            mirror: false,
            mirrored: std::cell::RefCell::new(std::collections::HashMap::new()),
            differentiated: std::cell::RefCell::new(std::collections::HashMap::new()),
            lanes: std::cell::RefCell::new(None),
            keys,
            defocus_rule: std::cell::OnceCell::new(),
        };
        let top = engine.scene.max_frequency.min(engine.max_cutoff());
        for term in &mut kept {
            term.s_top = (top * engine.scene.f_number * term.lambda).min(0.999);
        }
        engine.tails = std::cell::RefCell::new(vec![Vec::new(); kept.len()]);
        engine.mirror = kept.iter().all(|t| t.shift[1] == 0.0 && t.even_in_y());
        engine.terms = kept;
        Some(engine)
    }

    /// The polychromatic OTF at `frequency` along `azimuth`, each node to its share of the
    /// value tolerance.
    fn compute(&self, frequency: f64, azimuth: f64) -> Complex64 {
        let (sn, c) = azimuth.sin_cos();
        let nuf = frequency.abs() * self.scene.f_number;
        // O(−ν) = O(ν)*: the azimuth turned by π
        let (cr, sr) = if frequency < 0.0 { (-c, -sn) } else { (c, sn) };
        let total = self.nodes.total_weight;
        // each node's share of the value tolerance ε: ε W/(n |w|), at most 2 (|O| ≤ 1), so that
        // Σ |w| ε_node / W ≤ ε; light nodes (the spectrum's tails) are computed more loosely
        let share = self.value_tolerance.get() * total / self.terms.len() as f64;
        let k = -2.0 * PI * frequency;
        let mut sum = Complex64::new(0.0, 0.0);
        let mut excess = 0.0;
        for (index, term) in self.terms.iter().enumerate() {
            let s = nuf * term.lambda;
            if s >= 1.0 {
                continue;
            }
            let eps = share / term.weight.abs();
            if eps >= term.otf_bound(s) {
                // |O| ≤ its bound (at most 1): leaving the node out moves the sum by at most its
                // share
                continue;
            }
            let Some(x_level) = self.x_level(index, X_SHARE * eps) else {
                excess += term.weight.abs() * 2.0 / total;
                continue;
            };
            let (v, error) = term_otf(term, x_level, s, cr, sr, (1.0 - X_SHARE) * eps);
            // the project's sign (docs/physics.md, "Sign of the wavefront"): a tilt
            // W = NA Δ·ρ multiplies the OTF by exp(−2πi ν·Δ), as an image shift does, so the OTF
            // is ∫ P(p₋) P*(p₊), the conjugate of the integral above
            let mut v = v.conj();
            if error > (1.0 - X_SHARE) * eps {
                // |O| ≤ 1: never off by more than 1 + |v|
                excess += term.weight.abs() * error.min(1.0 + v.norm()) / total;
            }
            let [dx, dy] = term.shift;
            if dx != 0.0 || dy != 0.0 {
                let (ps, pc) = (k * (dx * c + dy * sn)).sin_cos();
                v *= Complex64::new(pc, ps);
            }
            sum += v * term.weight;
        }
        if excess > self.value_tolerance.get() {
            self.worst.set(self.worst.get().max(excess));
        }
        sum / total
    }

    /// The first x level of node `index` whose probed Legendre tail ([`x_tail`]) is within
    /// `target`, probing levels as they are first needed; `None` past the last.
    fn x_level(&self, index: usize, target: f64) -> Option<usize> {
        x_level_of(&self.tails, &self.terms[index], index, target)
    }

    /// The defocus lane's own spectral rule ([`DefocusRule`]), built on first use; `None` where
    /// the value's nodes are not product integration's or a panel's doubled rule would pass the
    /// finest level (the lane then takes the value's nodes and weights).
    fn defocus_rule(&self) -> Option<&DefocusRule> {
        self.defocus_rule
            .get_or_init(|| {
                let samples = super::spectral::doubled(&self.scene, &self.nodes)?;
                let top = self.scene.max_frequency.min(self.max_cutoff());
                let at: std::collections::HashMap<(u64, usize, usize), usize> =
                    self.keys.iter().enumerate().map(|(i, k)| (*k, i)).collect();
                let mut weights = vec![0.0; self.terms.len()];
                let (mut extra, mut total) = (Vec::new(), 0.0);
                for &(lambda, weight, part) in &samples {
                    if weight == 0.0 {
                        continue;
                    }
                    for (o, term) in sample_terms(&self.scene, lambda, weight, part)?.into_iter().enumerate() {
                        let Some(mut term) = term else { continue };
                        total += term.weight;
                        match at.get(&(lambda.to_bits(), part, o)) {
                            Some(&i) => weights[i] = term.weight,
                            None => {
                                term.s_top = (top * self.scene.f_number * term.lambda).min(0.999);
                                extra.push(term);
                            }
                        }
                    }
                }
                let tails = std::cell::RefCell::new(vec![Vec::new(); extra.len()]);
                (total > 0.0 && total.is_finite()).then_some(DefocusRule { weights, extra, tails, total })
            })
            .as_ref()
    }
}

/// The terms of one spectral sample `(lambda, weight, part)`: one per order of the part's lens at
/// `lambda`, in their order, `None` for an order of zero efficiency; `None` where some order is
/// not the full circle with Seidel and Zernike terms.
fn sample_terms(scene: &Scene<'_>, lambda: f64, weight: f64, part: usize) -> Option<Vec<Option<Term>>> {
    let lens = &scene.part(part).lens;
    let rates = lens.image_shift_field_rates(lambda, scene.field);
    let design = lens.design_wavelength_rates(lambda, scene.field);
    let mut out = Vec::new();
    for (o, order) in lens.orders(lambda, scene.field).into_iter().enumerate() {
        if order.efficiency == 0.0 {
            out.push(None);
            continue;
        }
        let w = order.wavefront;
        let mut term = Term {
            lambda,
            weight: weight * order.efficiency,
            shift: w.image_shift_m,
            shift_rate: rates.as_ref().and_then(|r| r.get(o)).copied(),
            defocus: w.defocus_m + w.field_curvature_m,
            lens_defocus: w.defocus_m,
            design: design.as_ref().and_then(|r| r.get(o)).map(|&[d_w, d_tau]| [d_w, d_tau / order.efficiency]),
            spherical: w.spherical_m,
            coma: w.coma_m,
            astigmatism: w.astigmatism_m,
            zernike: None,
            zernike_rest: Vec::new(),
            s_top: 0.0,
            slope: 0.0,
            curvature: 0.0,
        };
        match &order.pupil {
            Pupil::Full => {}
            Pupil::Radial(p) if p.is_zernike_only() => add_zernike(&mut term, p),
            _ => return None,
        }
        (term.slope, term.curvature) = term.rest_bounds();
        out.push(Some(term));
    }
    Some(out)
}

/// [`Overlap::x_level`] on the probed tails `tails` of a list of terms, `term` the one at `index`.
fn x_level_of(tails: &std::cell::RefCell<Vec<Vec<f64>>>, term: &Term, index: usize, target: f64) -> Option<usize> {
    let mut tails = tails.borrow_mut();
    let known = &mut tails[index];
    if let Some(level) = known.iter().position(|&t| t <= target) {
        return Some(level);
    }
    while known.len() < X_LEVELS.len() {
        let tail = x_tail(term, known.len());
        known.push(tail);
        if tail <= target {
            return Some(known.len() - 1);
        }
    }
    None
}

/// The OTF of `term` at normalized frequency `s` along the unit vector `(c, sn)`, to the
/// absolute error `eps`: the nested t rule until its Chebyshev tail is within `eps`; with the
/// error estimate of the level returned (beyond `eps` only at the last level).
fn term_otf(term: &Term, x_level: usize, s: f64, c: f64, sn: f64, eps: f64) -> (Complex64, f64) {
    if s >= 1.0 {
        return (Complex64::new(0.0, 0.0), 0.0);
    }
    let k = 2.0 * PI / term.lambda;
    let a = 4.0 * s * k * term.defocus;
    let big_t = s.acos();
    let rule = x_rule(x_level);
    let n = rule.nodes.len();
    let rest = term.has_rest();
    // without spherical aberration (and Zernike terms of radial order ≥ 4) the difference
    // W(p₊) − W(p₋) is quadratic in x
    let quadratic = term.quadratic();
    // the integrand at τ ∈ [−1, 1] (t = T τ): cos t · X · ∫ e^{i a X u} h(u) du
    let integrand = |tau: f64| -> Complex64 {
        let t = big_t * tau;
        let (y, ct) = sin_cos(t);
        let x_half = ct - s;
        if x_half <= 0.0 {
            return Complex64::new(0.0, 0.0);
        }
        if quadratic {
            // the whole phase is quadratic in x: a x + g(x) = α x² + β x + γ from its values
            // at −X, 0, X, and the x integral in closed form
            let f = |x: f64| {
                let (xp, xm) = (x + s, x - s);
                a * x + term.rest_phase(k, xp * c - y * sn, xp * sn + y * c, xm * c - y * sn, xm * sn + y * c)
            };
            let (lo, mid, hi) = (f(-x_half), f(0.0), f(x_half));
            let alpha = (hi + lo - 2.0 * mid) / (2.0 * x_half * x_half);
            let beta = (hi - lo) / (2.0 * x_half);
            let (si, co) = sin_cos(mid);
            return Complex64::new(co, si) * quadratic_phase_integral(alpha, beta, x_half) * ct;
        }
        let b = a * x_half;
        let mut bessel = [0.0; 64];
        let bessel = &mut bessel[..n];
        spherical_bessel(b, bessel);
        // K_j = Σ_m a[m][j] 2 i^m j_m(b)
        let mut kernel = [Complex64::new(0.0, 0.0); 64];
        let kernel = &mut kernel[..n];
        for (m, row) in rule.projection.iter().enumerate() {
            let v = 2.0 * bessel[m];
            match m % 4 {
                0 => row.iter().zip(kernel.iter_mut()).for_each(|(p, kk)| kk.re += p * v),
                1 => row.iter().zip(kernel.iter_mut()).for_each(|(p, kk)| kk.im += p * v),
                2 => row.iter().zip(kernel.iter_mut()).for_each(|(p, kk)| kk.re -= p * v),
                _ => row.iter().zip(kernel.iter_mut()).for_each(|(p, kk)| kk.im -= p * v),
            }
        }
        let mut sum = Complex64::new(0.0, 0.0);
        for (j, &u) in rule.nodes.iter().enumerate() {
            let h = if rest {
                let x = x_half * u;
                // p± = (x ± s) e + y e⊥ in the pupil's own axes
                let (xp, xm) = (x + s, x - s);
                let phase = term.rest_phase(k, xp * c - y * sn, xp * sn + y * c, xm * c - y * sn, xm * sn + y * c);
                let (si, co) = sin_cos(phase);
                Complex64::new(co, si)
            } else {
                Complex64::new(1.0, 0.0)
            };
            sum += kernel[j] * h;
        }
        sum * (ct * x_half)
    };
    // nested Clenshaw–Curtis in τ: start where the level resolves the defocus phase
    // a (1 − s) on each side at half a point a radian
    let phase = a.abs() * (1.0 - s);
    let mut level = T_LEVELS.iter().position(|&p| p as f64 >= phase + 5.0).unwrap_or(T_LEVELS.len() - 1);
    let mut values: Vec<Complex64> = Vec::new();
    loop {
        let points = T_LEVELS[level];
        let m = points - 1;
        if values.len() == points {
            // nothing new
        } else if !values.is_empty() && (values.len() - 1) * 2 == m {
            let mut next = Vec::with_capacity(points);
            for i in 0..points {
                next.push(if i % 2 == 0 { values[i / 2] } else { integrand((PI * i as f64 / m as f64).cos()) });
            }
            values = next;
        } else {
            values = (0..points).map(|i| integrand((PI * i as f64 / m as f64).cos())).collect();
        }
        let weights = cc_weights(points);
        let sum: Complex64 = values.iter().zip(weights).map(|(v, w)| v * *w).sum();
        let scale = big_t / PI;
        let error = scale * t_error(&values);
        if error <= eps || level + 1 == T_LEVELS.len() {
            return (sum * scale, error);
        }
        level += 1;
    }
}

/// `∫_{−X}^{X} exp(i(α x² + β x)) dx` in closed form (Abramowitz & Stegun 7.1.1–7.1.2, 7.4.32):
/// with `ζ = √(−iα)` (`Re ζ > 0`), `x₀ = β/(2α)` and `u = x₀ ± X`, it is
/// `√π/(2ζ) e^{−iαx₀²} [erf(ζ u₊) − erf(ζ u₋)]`; each `erf(ζu) = σ(1 − e^{−ζ²u²} erfcx(σζu))`,
/// `σ = sign u` (so that `erfcx` is read where `Re ≥ 0`, `faddeeva::erfcx`), and the phases
/// combine to `e^{i(αX² ± βX)}` before they are formed: no large phase `β²/(4α)` is rounded. The
/// constant parts survive only where the stationary point `−x₀` lies inside `[−X, X]`. Where
/// `|α| X² <` [`MOMENTS_MIN_PHASE`], the Taylor series of [`small_alpha_moments`] (within
/// `3e-15 X`), continuous in α: the quadratic term was once left out below `|α| X² = 1e-9`, a
/// jump of up to `1e-9 X` in the t rule's integrand wherever the term crossed it (a coma of
/// 1e-4 µm on the paper's lens: the t rule's tail never fell, and the evaluation was refused with
/// an error estimate of 1.3).
fn quadratic_phase_integral(alpha: f64, beta: f64, x: f64) -> Complex64 {
    if alpha.abs() * x * x < MOMENTS_MIN_PHASE {
        return small_alpha_integral(alpha, beta, x);
    }
    let zeta = Complex64::new(0.0, -alpha).sqrt();
    let x0 = beta / (2.0 * alpha);
    let (u1, u2) = (x0 + x, x0 - x);
    let (s1, s2) = (if u1 >= 0.0 { 1.0 } else { -1.0 }, if u2 >= 0.0 { 1.0 } else { -1.0 });
    let cis = |phase: f64| {
        let (si, co) = sin_cos(phase);
        Complex64::new(co, si)
    };
    let aa = alpha * x * x;
    let mut sum = cis(aa - beta * x) * crate::faddeeva::erfcx(zeta * (s2 * u2)) * s2
        - cis(aa + beta * x) * crate::faddeeva::erfcx(zeta * (s1 * u1)) * s1;
    if s1 != s2 {
        sum += cis(-alpha * x0 * x0) * (s1 - s2);
    }
    sum * (PI.sqrt() / (2.0 * zeta))
}

/// The error bound of a Clenshaw–Curtis level from the tail of its Chebyshev coefficients
/// (`quad::chebyshev_tail_parts`, real and imaginary parts): `Σ_i size rⁱ (|μ_{n−1+i}| +
/// |μ_{n−1−i}|)` with the constant weight's moments `μ_j = 2/(1 − j²)` (even j).
fn t_error(values: &[Complex64]) -> f64 {
    let n = values.len();
    let re: Vec<f64> = values.iter().map(|v| v.re).collect();
    let im: Vec<f64> = values.iter().map(|v| v.im).collect();
    let moment = |j: usize| if j.is_multiple_of(2) { 2.0 / ((j * j) as f64 - 1.0).abs() } else { 0.0 };
    let mut total = 0.0;
    let largest = values.iter().map(|v| v.norm()).fold(0.0, f64::max);
    for part in [re, im] {
        match crate::quad::chebyshev_tail_parts(&part) {
            // at rounding: nothing left to resolve (a part that is zero but for rounding has
            // no falling tail to read)
            Some((size, _)) if size <= 1e-13 * largest => {}
            Some((size, rate)) if rate < crate::quad::TAIL_MAX_RATE => {
                let mut r = 1.0;
                for i in 1..n {
                    r *= rate;
                    total += size * r * (moment(n - 1 + i) + moment(n - 1 - i));
                }
            }
            _ => return f64::INFINITY,
        }
    }
    total
}

/// The x rule's error at `level` for `term`: its probed Legendre tail, the last two of the
/// coefficients of `h(u) = exp(i k ΔW_rest)` times 4 (for the tail beyond them), the largest
/// along 8 azimuths and at 5 heights across the overlap at the node's highest frequency (the
/// phase differences grow with s); 0 without terms beyond defocus.
fn x_tail(term: &Term, level: usize) -> f64 {
    if !term.has_rest() {
        return 0.0;
    }
    let s = term.s_top;
    let k = 2.0 * PI / term.lambda;
    let big_t = s.acos();
    let rule = x_rule(level);
    let n = rule.nodes.len();
    let mut worst = 0.0_f64;
    for q in 0..8 {
        let (sn, c) = (PI * q as f64 / 8.0).sin_cos();
        for tau in [-0.9, -0.5, 0.0, 0.5, 0.9] {
            let (y, ct) = (big_t * tau).sin_cos();
            let x_half = ct - s;
            let h: Vec<Complex64> = rule
                .nodes
                .iter()
                .map(|&u| {
                    let x = x_half * u;
                    let (xp, xm) = (x + s, x - s);
                    let phase = term.rest_phase(k, xp * c - y * sn, xp * sn + y * c, xm * c - y * sn, xm * sn + y * c);
                    Complex64::from_polar(1.0, phase)
                })
                .collect();
            let coefficient =
                |m: usize| rule.projection[m].iter().zip(&h).map(|(p, v)| v * *p).sum::<Complex64>().norm();
            worst = worst.max(4.0 * (coefficient(n - 1) + coefficient(n - 2)));
        }
    }
    worst
}

/// A Seidel term of the chromatic lens's wavefront, as a direction of the overlap engine's
/// gradient ([`WavefrontDirection::Seidel`]): per µm at the pupil's edge (the key's unit,
/// `lens.spherical_um` …), the field along +x, with the sign of
/// [`Wavefront`](crate::Wavefront).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeidelTerm {
    /// Spherical aberration `W040 ρ⁴` (`lens.spherical_um`).
    Spherical,
    /// Coma `W131 ρ³ cos φ = W131 r² x` (`lens.coma_um`).
    Coma,
    /// Astigmatism `W222 ρ² cos² φ = W222 x²` (`lens.astigmatism_um`).
    Astigmatism,
    /// Field curvature `W220 ρ²` (`lens.field_curvature_um`): it adds to every order's defocus.
    FieldCurvature,
}

impl SeidelTerm {
    /// The scene key that sets the term (`lens.coma_um` …).
    pub fn key(self) -> &'static str {
        match self {
            SeidelTerm::Spherical => "lens.spherical_um",
            SeidelTerm::Coma => "lens.coma_um",
            SeidelTerm::Astigmatism => "lens.astigmatism_um",
            SeidelTerm::FieldCurvature => "lens.field_curvature_um",
        }
    }

    /// The wavefront this term adds per µm at the pupil point `(x, y)` (units of the pupil
    /// radius, the field along +x), m.
    #[inline]
    fn opd(self, x: f64, y: f64) -> f64 {
        let r2 = x * x + y * y;
        1e-6 * match self {
            SeidelTerm::Spherical => r2 * r2,
            SeidelTerm::Coma => r2 * x,
            SeidelTerm::Astigmatism => x * x,
            SeidelTerm::FieldCurvature => r2,
        }
    }
}

/// The smallest `|α| X²` at which the derivatives take [`quadratic_moments`] (below it the
/// recurrence divides by a small `α`: [`small_alpha_moments`], the Taylor series in `α`, takes
/// them). The recurrence's rounding is about `1e-16 (1 + |β| X)/(|α| X²)` relative in `I1` and
/// that squared over `1e-16` in `I2` (it divides by `2α` twice): at most `1e-12 (1 + |β| X)`
/// here. The Filon rule took the small `α` before the Taylor series did, at a threshold of
/// 1e-4 (where `I2` was only good to about 1e-8): it took the t rule's nodes near its ends
/// (where `X = cos t − s` is small) and with them most of the Zernike gradient's time (each of
/// its x nodes' lanes, `lanes_opd`).
const MOMENTS_MIN_PHASE: f64 = 1e-2;

/// `[I0, I1, I2]`, `I_m = ∫_{−X}^{X} x^m exp(i(α x² + β x)) dx`: `I0` by
/// [`quadratic_phase_integral`], and since `d/dx e^{iφ} = i (2αx + β) e^{iφ}`, integration by
/// parts gives `2α I1 + β I0 = −i [e^{iφ}]` and `2α I2 + β I1 = −i [x e^{iφ}] + i I0` (the
/// brackets between −X and X).
fn quadratic_moments(alpha: f64, beta: f64, x: f64) -> [Complex64; 3] {
    let i0 = quadratic_phase_integral(alpha, beta, x);
    let cis = |phase: f64| {
        let (si, co) = sin_cos(phase);
        Complex64::new(co, si)
    };
    let aa = alpha * x * x;
    let (up, down) = (cis(aa + beta * x), cis(aa - beta * x));
    let i = Complex64::new(0.0, 1.0);
    let i1 = (-i * (up - down) - beta * i0) / (2.0 * alpha);
    let i2 = (-i * x * (up + down) + i * i0 - beta * i1) / (2.0 * alpha);
    [i0, i1, i2]
}

/// The Taylor terms of `e^{iαx²}` that [`small_alpha_moments`] keeps: `(iαx²)^j/j!`, `j <
/// SMALL_ALPHA_TERMS`.
const SMALL_ALPHA_TERMS: usize = 6;

/// The monomials `u^p` whose Fourier integrals [`monomial_fourier_every`] gives: `p ≤ 2 + 2 (J − 1)`.
const MONOMIALS: usize = 2 * SMALL_ALPHA_TERMS + 1;

/// The Legendre coefficients of the monomials: `u^p = Σ_l c[p][l] P_l(u)`, from `u^0 = P_0` by
/// `u P_l = ((l + 1) P_{l+1} + l P_{l−1})/(2l + 1)` (Abramowitz & Stegun 22.7.10).
fn monomial_legendre() -> &'static [[f64; MONOMIALS]; MONOMIALS] {
    static C: OnceLock<[[f64; MONOMIALS]; MONOMIALS]> = OnceLock::new();
    C.get_or_init(|| {
        let mut c = [[0.0; MONOMIALS]; MONOMIALS];
        c[0][0] = 1.0;
        for p in 0..MONOMIALS - 1 {
            for l in 0..=p {
                let v = c[p][l];
                let d = (2 * l + 1) as f64;
                c[p + 1][l + 1] += v * (l + 1) as f64 / d;
                if l > 0 {
                    c[p + 1][l - 1] += v * l as f64 / d;
                }
            }
        }
        c
    })
}

/// [`quadratic_moments`] where the quadratic phase is small (`|α| X² <` [`MOMENTS_MIN_PHASE`],
/// where the recurrence would divide by a small `α`): `e^{iαx²} = Σ_j (iαx²)^j/j!`, so `I_m =
/// X^{m+1} Σ_j (iαX²)^j/j! L_{m+2j}(βX)` ([`monomial_fourier_every`]), the terms `j <`
/// [`SMALL_ALPHA_TERMS`]; the first left out is at most `2 X^{m+1} (|α| X²)^J/J!`, below
/// `3e-15 X^{m+1}` here.
///
/// The terms `j < J` with `J` the fewest (at most [`SMALL_ALPHA_TERMS`]) whose first term left
/// out, `2 X^{m+1} (|α|X²)^J/J!`, is below `2e-16 X^{m+1}` (as [`small_alpha_integral`]), and
/// the monomials `p ≤ 2J` those terms read: where the quadratic phase is far below
/// [`MOMENTS_MIN_PHASE`] (the t rule's nodes near its ends) three or five monomials of the
/// thirteen.
fn small_alpha_moments(alpha: f64, beta: f64, x: f64) -> [Complex64; 3] {
    let a = alpha.abs() * x * x;
    let (mut terms, mut left_out) = (1, a);
    while terms < SMALL_ALPHA_TERMS && left_out > 1e-16 {
        terms += 1;
        left_out *= a / terms as f64;
    }
    let mut l = [Complex64::new(0.0, 0.0); MONOMIALS];
    monomial_fourier_every(beta * x, 2 * terms + 1, 1, 2 * terms + 1, &mut l);
    let step = Complex64::new(0.0, alpha * x * x);
    let mut out = [Complex64::new(0.0, 0.0); 3];
    let mut power = x;
    for (m, o) in out.iter_mut().enumerate() {
        let mut term = Complex64::new(power, 0.0);
        for j in 0..terms {
            *o += term * l[m + 2 * j];
            term *= step / (j + 1) as f64;
        }
        power *= x;
    }
    out
}

/// `I0` of [`small_alpha_moments`] alone, for the value (`quadratic_phase_integral`): the terms
/// `j < J` of `X Σ_j (iαX²)^j/j! L_{2j}(βX)` with `J` the fewest (at most
/// [`SMALL_ALPHA_TERMS`]) whose first term left out, `2X (|α|X²)^J/J!`, is below `2e-16 X`, and
/// only the even `L_p` those terms read: where the quadratic phase is far below
/// [`MOMENTS_MIN_PHASE`] (most of the t rule's nodes near its ends on a lens with Seidel terms)
/// two or three terms instead of six.
fn small_alpha_integral(alpha: f64, beta: f64, x: f64) -> Complex64 {
    let a = alpha.abs() * x * x;
    let (mut terms, mut left_out) = (1, a);
    while terms < SMALL_ALPHA_TERMS && left_out > 1e-16 {
        terms += 1;
        left_out *= a / terms as f64;
    }
    let mut l = [Complex64::new(0.0, 0.0); MONOMIALS];
    // the Bessel functions to the order `small_alpha_moments` forms, so that its `I0` is this
    // bit for bit (the gradient's pass takes the value from it)
    monomial_fourier_every(beta * x, 2 * terms - 1, 2, 2 * terms + 1, &mut l);
    let step = Complex64::new(0.0, alpha * x * x);
    let mut term = Complex64::new(x, 0.0);
    let mut sum = Complex64::new(0.0, 0.0);
    for j in 0..terms {
        sum += term * l[2 * j];
        term *= step / (j + 1) as f64;
    }
    sum
}

/// The terms of [`monomial_fourier_every`]'s power series for `|b| < 1`: `k < 24`, the last below
/// `1/24! < 2e-24`.
const SERIES_TERMS: usize = 24;

/// `2/n` for `n < MONOMIALS + SERIES_TERMS` (entry 0 unused), as the series divides.
const TWO_OVER: [f64; MONOMIALS + SERIES_TERMS] = {
    let mut t = [0.0; MONOMIALS + SERIES_TERMS];
    let mut n = 1;
    while n < t.len() {
        t[n] = 2.0 / n as f64;
        n += 1;
    }
    t
};

/// `L_p(b) = ∫_{−1}^{1} u^p e^{ibu} du` for `p < count` (at most `MONOMIALS`) in steps of `step`
/// from 0 into `out` (the others left as they are): for `|b| < 1` by the power series
/// `Σ_k (ib)^k/k! · 2/(p + k + 1)` (`p + k` even; 24 terms, the last below `1/24! < 2e-24`),
/// else from the Legendre expansion of `u^p` ([`monomial_legendre`]) and `∫_{−1}^{1} P_l(u)
/// e^{ibu} du = 2 i^l j_l(b)` (the Filon rule's identity, [`spherical_bessel`] formed for `l <
/// top`, `top` at least `count` and at most `MONOMIALS`: two calls with the same `b` and `top`
/// give the same `L_p` bit for bit whatever their counts).
///
/// The power series: `(ib)^k/k! = i^k r_k` with `r_k = Π_{j<k} b/(j + 1)` (the product in that
/// order), formed once for every `p`; `L_p` is real for even `p` (the even `k`, `i^k =
/// (−1)^{k/2}`) and imaginary for odd `p` (the odd `k`, `i^k = i (−1)^{(k−1)/2}`), each a sum of
/// `r_k · 2/(p + k + 1)` in increasing `k`: the same products and sums, in the same order, as the
/// series summed term by term in complex arithmetic for each `p` (bit for bit,
/// `monomial_fourier_matches_the_series_term_by_term`), at a twelfth of the multiplications.
fn monomial_fourier_every(b: f64, count: usize, step: usize, top: usize, out: &mut [Complex64; MONOMIALS]) {
    let count = count.min(MONOMIALS);
    let top = top.clamp(count, MONOMIALS);
    if b.abs() < 1.0 {
        let mut r = [0.0; SERIES_TERMS];
        let mut v = 1.0;
        for (k, rk) in r.iter_mut().enumerate() {
            *rk = v;
            v *= b / (k + 1) as f64;
        }
        for p in (0..count).step_by(step) {
            let mut sum = 0.0;
            for k in (p % 2..SERIES_TERMS).step_by(2) {
                let term = if (k / 2) % 2 == 0 { r[k] } else { -r[k] };
                sum += term * TWO_OVER[p + k + 1];
            }
            out[p] = if p % 2 == 0 { Complex64::new(sum, 0.0) } else { Complex64::new(0.0, sum) };
        }
        return;
    }
    let mut j = [0.0; MONOMIALS];
    spherical_bessel(b, &mut j[..top]);
    let c = monomial_legendre();
    for p in (0..count).step_by(step) {
        let (mut re, mut im) = (0.0, 0.0);
        for (l, &jl) in j.iter().enumerate().take(p + 1) {
            let v = 2.0 * c[p][l] * jl;
            match l % 4 {
                0 => re += v,
                1 => im += v,
                2 => re -= v,
                _ => im -= v,
            }
        }
        out[p] = Complex64::new(re, im);
    }
}

/// A direction of the overlap engine's gradient: a Seidel term ([`SeidelTerm`]), the Zernike
/// term of a Noll index per µm RMS (`∂W = 10⁻⁶ Z_j(x, y)`, [`WavefrontDirection::Zernike`]), or
/// each order's own defocus per relative change ([`WavefrontDirection::Defocus`]: `ρ²` here,
/// each node's derivative scaled by its `W020`), or the design wavelength
/// ([`WavefrontDirection::DesignWavelength`]: `ρ²` scaled by each node's `∂W020/∂ln λ0`, plus
/// its efficiency's rate times its value).
#[derive(Clone, Debug)]
enum Lane {
    Seidel(SeidelTerm),
    Defocus,
    Design,
    /// Noll's polynomial per µm and its radial order
    Zernike(Compiled, usize),
}

impl Lane {
    /// The lane of `direction`, `None` for a direction the overlap engine does not carry (a
    /// radial profile's lane) or a Noll index out of range.
    fn of(direction: &WavefrontDirection) -> Option<Lane> {
        match *direction {
            WavefrontDirection::Seidel(t) => Some(Lane::Seidel(t)),
            WavefrontDirection::Defocus => Some(Lane::Defocus),
            WavefrontDirection::DesignWavelength => Some(Lane::Design),
            WavefrontDirection::Zernike(j) if (1..=crate::fft::MAX_NOLL_INDEX).contains(&j) => {
                let compiled =
                    Compiled::new(&Aberrations { zernike_noll_m: vec![(j, 1e-6)], ..Aberrations::default() });
                Some(Lane::Zernike(compiled, noll_to_nm(j).0))
            }
            _ => None,
        }
    }

    /// The wavefront this lane adds per µm at the pupil point `(x, y)`, m (the defocus lane:
    /// `ρ²`, per metre of `W020`).
    #[inline]
    fn opd(&self, x: f64, y: f64) -> f64 {
        match self {
            Lane::Seidel(t) => t.opd(x, y),
            Lane::Defocus | Lane::Design => x * x + y * y,
            Lane::Zernike(z, _) => z.opd_m(x, y),
        }
    }
}

/// Every lane's wavefront per µm at the pupil point `(x, y)` into `out` (m), each bit for bit
/// as [`Lane::opd`] gives it: the Zernike lanes share `ρ²` and the powers `(x + iy)^|m|`
/// (`Compiled::opd_m` forms them by the same products from 1, and adds the term to a zero
/// wavefront: `0 + p Re/Im`), each then its own Horner sum in ρ².
fn lanes_opd(lanes: &[Lane], x: f64, y: f64, out: &mut [f64]) {
    let r2 = x * x + y * y;
    let mut powers = [(1.0_f64, 0.0_f64); 32];
    let mut formed = 0usize;
    for (o, lane) in out.iter_mut().zip(lanes) {
        *o = match lane {
            Lane::Zernike(z, _) => match z.single_zernike() {
                Some((m, poly)) if (m.unsigned_abs() as usize) < powers.len() => {
                    let ma = m.unsigned_abs() as usize;
                    while formed < ma {
                        let (re, im) = powers[formed];
                        powers[formed + 1] = (re * x - im * y, re * y + im * x);
                        formed += 1;
                    }
                    let mut p = 0.0;
                    for &c in poly {
                        p = p * r2 + c;
                    }
                    let (re, im) = powers[ma];
                    0.0 + p * if m >= 0 { re } else { im }
                }
                _ => lane.opd(x, y),
            },
            Lane::Seidel(_) | Lane::Defocus | Lane::Design => lane.opd(x, y),
        };
    }
}

/// The points [`lanes_opd_at`] takes at once: the moments rule's six (`p₊` and `p₋` at `x = −X,
/// 0, X`), padded.
const LANE_POINTS: usize = 8;

/// `(Re, Im)` of a power `(x + iy)^m` at [`LANE_POINTS`] points.
type LanePowers = ([f64; LANE_POINTS], [f64; LANE_POINTS]);

/// [`lanes_opd`] at [`LANE_POINTS`] points at once, lane `l`'s values into `out[l]`, each bit for
/// bit as [`lanes_opd`] gives it at that point (the same operations in the same order, point by
/// point): the powers `(x + iy)^|m|` formed once for every lane, each lane's loops over the
/// points, which the compiler can take several points a register. `powers` is scratch (kept by
/// the caller so that nothing is allocated per call).
fn lanes_opd_at(
    lanes: &[Lane],
    x: &[f64; LANE_POINTS],
    y: &[f64; LANE_POINTS],
    powers: &mut Vec<LanePowers>,
    out: &mut [[f64; LANE_POINTS]],
) {
    let mut r2 = [0.0; LANE_POINTS];
    for ((r, &xi), &yi) in r2.iter_mut().zip(x).zip(y) {
        *r = xi * xi + yi * yi;
    }
    // (re, im) of (x + iy)^m at every point, m = 0 … powers.len() − 1
    powers.clear();
    powers.push(([1.0; LANE_POINTS], [0.0; LANE_POINTS]));
    for (o, lane) in out.iter_mut().zip(lanes) {
        match lane {
            Lane::Zernike(z, _) => match z.single_zernike() {
                Some((m, poly)) if (m.unsigned_abs() as usize) < 32 => {
                    let ma = m.unsigned_abs() as usize;
                    while powers.len() <= ma {
                        let (re, im) = powers[powers.len() - 1];
                        let mut next = ([0.0; LANE_POINTS], [0.0; LANE_POINTS]);
                        for i in 0..LANE_POINTS {
                            next.0[i] = re[i] * x[i] - im[i] * y[i];
                            next.1[i] = re[i] * y[i] + im[i] * x[i];
                        }
                        powers.push(next);
                    }
                    let mut p = [0.0; LANE_POINTS];
                    for &c in poly {
                        for (pi, &ri) in p.iter_mut().zip(&r2) {
                            *pi = *pi * ri + c;
                        }
                    }
                    let part = if m >= 0 { &powers[ma].0 } else { &powers[ma].1 };
                    for ((oi, &pi), &qi) in o.iter_mut().zip(&p).zip(part) {
                        *oi = 0.0 + pi * qi;
                    }
                }
                _ => (0..LANE_POINTS).for_each(|i| o[i] = lane.opd(x[i], y[i])),
            },
            Lane::Seidel(_) | Lane::Defocus | Lane::Design => {
                (0..LANE_POINTS).for_each(|i| o[i] = lane.opd(x[i], y[i]))
            }
        }
    }
}

impl Lane {
    /// The lane's degree in the pupil coordinates.
    fn degree(&self) -> usize {
        match self {
            Lane::Seidel(SeidelTerm::Spherical) => 4,
            Lane::Seidel(SeidelTerm::Coma) => 3,
            Lane::Seidel(_) | Lane::Defocus | Lane::Design => 2,
            Lane::Zernike(_, n) => *n,
        }
    }

    /// Whether the lane is even in y (every Seidel term, a Zernike cosine or `m = 0` term).
    fn even_in_y(&self) -> bool {
        match self {
            Lane::Seidel(_) | Lane::Defocus | Lane::Design => true,
            Lane::Zernike(z, _) => !z.has_sine_terms(),
        }
    }
}

/// The Filon kernel of an x level at `b = a X`: `K_j = Σ_m a[m][j] 2 i^m j_m(b)`, so that
/// `∫_{−1}^{1} e^{ibu} g(u) du ≈ Σ_j K_j g(u_j)` for `g` interpolated at the level's nodes.
fn filon_kernel(rule: &XRule, b: f64, kernel: &mut [Complex64]) {
    let n = kernel.len();
    let mut bessel = [0.0; 64];
    let bessel = &mut bessel[..n];
    spherical_bessel(b, bessel);
    kernel.iter_mut().for_each(|k| *k = Complex64::new(0.0, 0.0));
    for (m, row) in rule.projection.iter().enumerate() {
        let v = 2.0 * bessel[m];
        match m % 4 {
            0 => row.iter().zip(kernel.iter_mut()).for_each(|(p, kk)| kk.re += p * v),
            1 => row.iter().zip(kernel.iter_mut()).for_each(|(p, kk)| kk.im += p * v),
            2 => row.iter().zip(kernel.iter_mut()).for_each(|(p, kk)| kk.re -= p * v),
            _ => row.iter().zip(kernel.iter_mut()).for_each(|(p, kk)| kk.im -= p * v),
        }
    }
}

/// [`term_otf`] and, into `out`, the derivative of the same integral with respect to each of
/// `terms` (docs/physics.md, "Gradients: Seidel terms on the overlap engine"): a term moves the
/// wavefront by `c D(p)`, so the integrand `exp(i k [W(p₊) − W(p₋)])` by the factor
/// `i k [D(p₊) − D(p₋)]`, a polynomial in x of degree at most 3. Forward mode on the value's
/// nodes: at each of the t rule's nodes the x integral of the factor times the integrand is
/// the value's Filon rule (the defocus phase `e^{i a X u}` exactly, the rest interpolated at the
/// value's x level's Gauss–Legendre points, where the value's closed form for a quadratic phase
/// has no points of its own), and the t rule is the level the value accepts, with its weights.
/// The value is [`term_otf`]'s, computed the same way.
#[allow(clippy::too_many_arguments)]
fn term_otf_and_derivatives(
    term: &Term,
    x_level: usize,
    s: f64,
    c: f64,
    sn: f64,
    eps: f64,
    terms: &[Lane],
    out: &mut [Complex64],
) -> (Complex64, f64) {
    out.iter_mut().for_each(|o| *o = Complex64::new(0.0, 0.0));
    if s >= 1.0 {
        return (Complex64::new(0.0, 0.0), 0.0);
    }
    let lanes = terms.len();
    let k = 2.0 * PI / term.lambda;
    let a = 4.0 * s * k * term.defocus;
    let big_t = s.acos();
    let rule = x_rule(x_level);
    let n = rule.nodes.len();
    let rest = term.has_rest();
    let quadratic = term.quadratic();
    // the phase quadratic in x and every lane's factor at most quadratic: the x integrals in
    // closed form (where the quadratic term is large enough for the moments' recurrence)
    let moments = quadratic && terms.iter().all(|d| d.degree() <= 3);
    // the lanes' wavefronts at two points and their differences at three
    let mut scratch = vec![0.0; 5 * lanes];
    // the lanes' wavefronts at the moments rule's six points
    let mut at_points = vec![[0.0; LANE_POINTS]; if moments { lanes } else { 0 }];
    let mut powers: Vec<LanePowers> = Vec::with_capacity(if moments { 4 } else { 0 });
    // the value and the derivatives at τ ∈ [−1, 1], into `row` (1 + lanes values)
    let mut integrand = |tau: f64, row: &mut [Complex64]| {
        row.iter_mut().for_each(|r| *r = Complex64::new(0.0, 0.0));
        let t = big_t * tau;
        let (y, ct) = sin_cos(t);
        let x_half = ct - s;
        if x_half <= 0.0 {
            return;
        }
        // p± = (x ± s) e + y e⊥ in the pupil's own axes
        let points = |x: f64| {
            let (xp, xm) = (x + s, x - s);
            (xp * c - y * sn, xp * sn + y * c, xm * c - y * sn, xm * sn + y * c)
        };
        // the phase a x + rest, quadratic in x where `quadratic`: its α, β and value at x = 0
        // from its values at −X, 0 and X
        let quadratic_fit = || {
            let f = |x: f64| {
                let (xa, ya, xb, yb) = points(x);
                a * x + term.rest_phase(k, xa, ya, xb, yb)
            };
            let (lo, mid, hi) = (f(-x_half), f(0.0), f(x_half));
            ((hi + lo - 2.0 * mid) / (2.0 * x_half * x_half), (hi - lo) / (2.0 * x_half), mid)
        };
        if moments {
            // the value's closed form, and each lane's factor g(x) = k [D(p₊) − D(p₋)] (at most
            // quadratic in x) against the same phase by the moments of `quadratic_moments`, or
            // where the quadratic term is small (|α| X² below MOMENTS_MIN_PHASE) by its Taylor
            // series on the moments of e^{iβx} (`small_alpha_moments`)
            let (alpha, beta, mid) = quadratic_fit();
            let (si, co) = sin_cos(mid);
            let front = Complex64::new(co, si) * ct;
            // with the value's closed form `quadratic_phase_integral`: the first of
            // `quadratic_moments`, or of `small_alpha_moments` (its `small_alpha_integral` bit
            // for bit, on the same Bessel functions)
            let [i0, i1, i2] = if alpha.abs() * x_half * x_half >= MOMENTS_MIN_PHASE {
                quadratic_moments(alpha, beta, x_half)
            } else {
                small_alpha_moments(alpha, beta, x_half)
            };
            let closed = i0;
            // the value as `term_otf` forms it, bit for bit
            row[0] = Complex64::new(co, si) * closed * ct;
            // each lane's k [D(p₊) − D(p₋)] at −X, 0 and X: the six points at once
            let (mut px, mut py) = ([0.0; LANE_POINTS], [0.0; LANE_POINTS]);
            for (i, x) in [-x_half, 0.0, x_half].into_iter().enumerate() {
                let (xa, ya, xb, yb) = points(x);
                (px[2 * i], py[2 * i], px[2 * i + 1], py[2 * i + 1]) = (xa, ya, xb, yb);
            }
            lanes_opd_at(terms, &px, &py, &mut powers, &mut at_points);
            for (r, d) in row[1..].iter_mut().zip(at_points.iter()) {
                let (g_lo, g_mid, g_hi) = (k * (d[0] - d[1]), k * (d[2] - d[3]), k * (d[4] - d[5]));
                let g2 = (g_hi + g_lo - 2.0 * g_mid) / (2.0 * x_half * x_half);
                let g1 = (g_hi - g_lo) / (2.0 * x_half);
                // i ∫ g e^{iφ}
                *r = front * (i0 * g_mid + i1 * g1 + i2 * g2) * Complex64::new(0.0, 1.0);
            }
            return;
        }
        let mut kernel = [Complex64::new(0.0, 0.0); 64];
        let kernel = &mut kernel[..n];
        filon_kernel(rule, a * x_half, kernel);
        let scale = ct * x_half;
        let mut value = Complex64::new(0.0, 0.0);
        for (j, &u) in rule.nodes.iter().enumerate() {
            let (xa, ya, xb, yb) = points(x_half * u);
            let h = if rest {
                let (si, co) = sin_cos(term.rest_phase(k, xa, ya, xb, yb));
                Complex64::new(co, si)
            } else {
                Complex64::new(1.0, 0.0)
            };
            let kh = kernel[j] * h;
            value += kh;
            let (plus, rest) = scratch.split_at_mut(lanes);
            let minus = &mut rest[..lanes];
            lanes_opd(terms, xa, ya, plus);
            lanes_opd(terms, xb, yb, minus);
            for ((r, p), m) in row[1..].iter_mut().zip(plus.iter()).zip(minus.iter()) {
                // i k [D(p₊) − D(p₋)]
                let factor = k * (p - m);
                *r += Complex64::new(-kh.im * factor, kh.re * factor);
            }
        }
        row[1..].iter_mut().for_each(|r| *r *= scale);
        row[0] = if quadratic {
            // the value's closed form, as `term_otf` takes it
            let (alpha, beta, mid) = quadratic_fit();
            let (si, co) = sin_cos(mid);
            Complex64::new(co, si) * quadratic_phase_integral(alpha, beta, x_half) * ct
        } else {
            value * scale
        };
    };
    let phase = a.abs() * (1.0 - s);
    let mut level = T_LEVELS.iter().position(|&p| p as f64 >= phase + 5.0).unwrap_or(T_LEVELS.len() - 1);
    let width = 1 + lanes;
    // the rows at the current level's points (point i at τ = cos(πi/m))
    let mut rows: Vec<Complex64> = Vec::new();
    loop {
        let points = T_LEVELS[level];
        let m = points - 1;
        let held = rows.len() / width;
        if held == points {
            // nothing new
        } else if held > 0 && (held - 1) * 2 == m {
            let mut next = vec![Complex64::new(0.0, 0.0); points * width];
            for (i, row) in next.chunks_mut(width).enumerate() {
                if i % 2 == 0 {
                    row.copy_from_slice(&rows[(i / 2) * width..(i / 2 + 1) * width]);
                } else {
                    integrand((PI * i as f64 / m as f64).cos(), row);
                }
            }
            rows = next;
        } else {
            rows = vec![Complex64::new(0.0, 0.0); points * width];
            for (i, row) in rows.chunks_mut(width).enumerate() {
                integrand((PI * i as f64 / m as f64).cos(), row);
            }
        }
        let weights = cc_weights(points);
        let values: Vec<Complex64> = rows.chunks(width).map(|r| r[0]).collect();
        let scale = big_t / PI;
        let error = scale * t_error(&values);
        if error <= eps || level + 1 == T_LEVELS.len() {
            let mut sum = Complex64::new(0.0, 0.0);
            for (row, w) in rows.chunks(width).zip(weights) {
                sum += row[0] * *w;
                for (o, r) in out.iter_mut().zip(&row[1..]) {
                    *o += r * *w;
                }
            }
            out.iter_mut().for_each(|o| *o *= scale);
            return (sum * scale, error);
        }
        level += 1;
    }
}

impl Overlap<'_> {
    /// [`compute`](Self::compute) and, into `out`, the polychromatic OTF's derivative with
    /// respect to each of `terms`, every node on the value's rules ([`term_otf_and_derivatives`]);
    /// the lateral-colour phases and the spectral weights do not depend on the Seidel terms.
    /// Into `out_field`, the derivative with respect to each field angle of `axes` (0: x, 1: y;
    /// [`WavefrontDirection::FieldAngle`]): each node's turned value `v e^{ik Δ·u}` (k = −2πν,
    /// `u` the azimuth's unit vector) times `i k u_a ∂Δ_a/∂θ_a`, on the same nodes (every term
    /// has its `shift_rate` where `axes` holds a field angle: [`OtfEngine::otf_along_and_gradient`]).
    /// An axis `1 + k` (2, 3) is the spectral moment `k` ([`WavefrontDirection::SpectralMoment`]):
    /// each node's turned value times `u = λ − λ̄` or `u² − ⟨u²⟩`, on the same nodes; the axis 4
    /// the image shifts' scale ([`WavefrontDirection::ImageShift`]): the turned value times
    /// `i k u·Δ`. Without wavefront lanes (`terms` empty) each node's value is [`term_otf`]'s, as
    /// [`compute`](Self::compute) takes it.
    #[allow(clippy::too_many_arguments)]
    fn compute_with_derivatives(
        &self,
        frequency: f64,
        azimuth: f64,
        terms: &[Lane],
        out: &mut [Complex64],
        axes: &[usize],
        out_field: &mut [Complex64],
    ) -> Complex64 {
        out.iter_mut().for_each(|o| *o = Complex64::new(0.0, 0.0));
        out_field.iter_mut().for_each(|o| *o = Complex64::new(0.0, 0.0));
        let (sn, c) = azimuth.sin_cos();
        let nuf = frequency.abs() * self.scene.f_number;
        let (cr, sr) = if frequency < 0.0 { (-c, -sn) } else { (c, sn) };
        let total = self.nodes.total_weight;
        let share = self.value_tolerance.get() * total / self.terms.len() as f64;
        let k = -2.0 * PI * frequency;
        let mut sum = Complex64::new(0.0, 0.0);
        let mut excess = 0.0;
        let mut node = vec![Complex64::new(0.0, 0.0); terms.len()];
        let (mean, variance) =
            if axes.iter().any(|&a| a == 2 || a == 3) { self.nodes.wavelength_moments() } else { (0.0, 0.0) };
        // the defocus lane on its own spectral rule, where it is asked and the rule exists
        let defocus = terms.iter().position(|l| matches!(l, Lane::Defocus));
        let rule = defocus.and_then(|_| self.defocus_rule());
        for (index, term) in self.terms.iter().enumerate() {
            let s = nuf * term.lambda;
            if s >= 1.0 {
                continue;
            }
            let eps = share / term.weight.abs();
            if eps >= term.otf_bound(s) {
                continue;
            }
            let Some(x_level) = self.x_level(index, X_SHARE * eps) else {
                excess += term.weight.abs() * 2.0 / total;
                continue;
            };
            let (v, error) = if terms.is_empty() {
                term_otf(term, x_level, s, cr, sr, (1.0 - X_SHARE) * eps)
            } else {
                term_otf_and_derivatives(term, x_level, s, cr, sr, (1.0 - X_SHARE) * eps, terms, &mut node)
            };
            // the conjugate, as in `compute` (the project's sign)
            let mut v = v.conj();
            let mut turn = Complex64::new(1.0, 0.0);
            if error > (1.0 - X_SHARE) * eps {
                excess += term.weight.abs() * error.min(1.0 + v.norm()) / total;
            }
            let [dx, dy] = term.shift;
            if dx != 0.0 || dy != 0.0 {
                let (ps, pc) = (k * (dx * c + dy * sn)).sin_cos();
                turn = Complex64::new(pc, ps);
                v *= turn;
            }
            sum += v * term.weight;
            for ((o, d), lane) in out.iter_mut().zip(&node).zip(terms) {
                // the defocus lane's ρ² per metre, times this node's own W020: ∂/∂ln K, with
                // the weight of its own rule where it has one
                let weight = match (lane, rule) {
                    (Lane::Defocus, Some(rule)) => rule.weights[index] * term.lens_defocus,
                    (Lane::Defocus, None) => term.weight * term.lens_defocus,
                    // the design wavelength: ρ² per metre times ∂W020/∂ln λ0, and the turned
                    // value times the efficiency's rate (the caller has every node's rates)
                    (Lane::Design, _) => {
                        let [d_w, d_tau] = term.design.unwrap_or([0.0; 2]);
                        *o += v * (term.weight * d_tau);
                        term.weight * d_w
                    }
                    _ => term.weight,
                };
                *o += d.conj() * turn * weight;
            }
            let u = term.lambda - mean;
            for (o, &axis) in out_field.iter_mut().zip(axes) {
                match (axis, term.shift_rate) {
                    // ∂(v e^{ik Δ·u})/∂θ_a = i k u_a (∂Δ_a/∂θ_a) v e^{ik Δ·u}
                    (0, Some([rx, _])) => *o += Complex64::new(0.0, k * rx * c) * v * term.weight,
                    (1, Some([_, ry])) => *o += Complex64::new(0.0, k * ry * sn) * v * term.weight,
                    // the spectral moments: the node's weight times u or u² − ⟨u²⟩
                    (2, _) => *o += v * (term.weight * u),
                    (3, _) => *o += v * (term.weight * (u * u - variance)),
                    // the image shifts scaled by 1 + ε: i k u·Δ times the turned value
                    (4, _) => *o += Complex64::new(0.0, k * (dx * c + dy * sn)) * v * term.weight,
                    _ => {}
                }
            }
        }
        if excess > self.value_tolerance.get() {
            self.worst.set(self.worst.get().max(excess));
        }
        if let (Some(d), Some(rule)) = (defocus, rule) {
            // the rule's odd points, for the lane alone, each node to the value's share
            let one = [Lane::Defocus];
            let mut derivative = [Complex64::new(0.0, 0.0)];
            for (index, term) in rule.extra.iter().enumerate() {
                let s = nuf * term.lambda;
                if s >= 1.0 {
                    continue;
                }
                let eps = share / term.weight.abs();
                if eps >= term.otf_bound(s) {
                    continue;
                }
                let Some(x_level) = x_level_of(&rule.tails, term, index, X_SHARE * eps) else { continue };
                term_otf_and_derivatives(term, x_level, s, cr, sr, (1.0 - X_SHARE) * eps, &one, &mut derivative);
                let [dx, dy] = term.shift;
                let turn = if dx != 0.0 || dy != 0.0 {
                    let (ps, pc) = (k * (dx * c + dy * sn)).sin_cos();
                    Complex64::new(pc, ps)
                } else {
                    Complex64::new(1.0, 0.0)
                };
                out[d] += derivative[0].conj() * turn * (term.weight * term.lens_defocus);
            }
        }
        out_field.iter_mut().for_each(|o| *o /= total);
        for (i, o) in out.iter_mut().enumerate() {
            *o /= match rule {
                Some(rule) if Some(i) == defocus => rule.total,
                _ => total,
            };
        }
        sum / total
    }
}

impl OtfEngine for Overlap<'_> {
    fn engine(&self) -> Engine {
        Engine::Overlap { skipped: self.nodes.nodes.len().saturating_sub(self.terms.len()) }
    }

    fn nodes(&self) -> &Nodes {
        &self.nodes
    }

    fn f_number(&self) -> f64 {
        self.scene.f_number
    }

    fn field_lane_bound(&self) -> Option<f64> {
        let top = self.scene.max_frequency.min(self.max_cutoff());
        let mut largest = 0.0_f64;
        for term in &self.terms {
            let [rx, ry] = term.shift_rate?;
            largest = largest.max(rx.abs()).max(ry.abs());
        }
        Some(2.0 * PI * top * largest)
    }

    fn otf(&self, frequency: f64) -> f64 {
        self.otf_along(frequency, 0.0).re
    }

    fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64 {
        if !self.mirror {
            return self.compute(frequency, azimuth);
        }
        // a pupil symmetric about x with images shifted along x: O(ν, π − φ) = O(ν, φ)*
        let key = |phi: f64| (phi.rem_euclid(PI) * 1e9).round() as i64 % (PI * 1e9).round() as i64;
        let tolerance = self.value_tolerance.get().to_bits();
        let cache = self.mirrored.borrow();
        if let Some(v) = cache.get(&(frequency.to_bits(), tolerance, key(PI - azimuth))) {
            return v.conj();
        }
        if let Some(v) = cache.get(&(frequency.to_bits(), tolerance, key(azimuth))) {
            return *v;
        }
        drop(cache);
        let v = self.compute(frequency, azimuth);
        let mut cache = self.mirrored.borrow_mut();
        if cache.len() > 1 << 16 {
            cache.clear();
        }
        cache.insert((frequency.to_bits(), tolerance, key(azimuth)), v);
        v
    }

    fn direction_dependent(&self) -> bool {
        true
    }

    /// Seidel and Zernike directions, the field angles (where every node has its image
    /// shift's rates) and the spectral moments (each node's value re-weighted); a pupil symmetric about x with images shifted along x reads a mirrored
    /// azimuth's value and derivatives as the conjugates where every wavefront direction is even
    /// in y (the Seidel terms, Zernike cosine and `m = 0` terms: the derivative keeps the
    /// symmetry; so does the x field angle's, `u_x` changing sign with the conjugate's phase),
    /// the y field angle's as the conjugates' negatives (`u_y` keeps its sign), the spectral
    /// moments' as the conjugates (real factors on the values), as
    /// [`otf_along`](Self::otf_along) does.
    fn otf_along_and_gradient(
        &self,
        frequency: f64,
        azimuth: f64,
        directions: &[WavefrontDirection],
        gradient: &mut [Complex64],
    ) -> Option<Complex64> {
        let cached =
            self.lanes.borrow().as_ref().filter(|(d, _, _)| d == directions).map(|(_, l, a)| (l.clone(), a.clone()));
        let (terms, axes) = match cached {
            Some(set) => set,
            None => {
                let mut terms: Vec<Lane> = Vec::new();
                let mut axes = Vec::new();
                for d in directions {
                    match d {
                        WavefrontDirection::FieldAngle(a) if *a < 2 => axes.push(*a),
                        WavefrontDirection::SpectralMoment(k) if (1..=2).contains(k) => axes.push(1 + *k),
                        WavefrontDirection::ImageShift => axes.push(4),
                        _ => terms.push(Lane::of(d)?),
                    }
                }
                let terms = Arc::new(terms);
                *self.lanes.borrow_mut() = Some((directions.to_vec(), terms.clone(), axes.clone()));
                // the mirrored values cached were of other directions
                self.differentiated.borrow_mut().clear();
                (terms, axes)
            }
        };
        if axes.iter().any(|&a| a < 2) && self.terms.iter().any(|t| t.shift_rate.is_none()) {
            return None;
        }
        if terms.iter().any(|l| matches!(l, Lane::Design)) && self.terms.iter().any(|t| t.design.is_none()) {
            return None;
        }
        // each direction's place in `gradient`: the wavefront lanes, then the field angles' and
        // the spectral moments', in the order asked
        let scatter = |lanes: &[Complex64], field: &[Complex64], gradient: &mut [Complex64]| {
            let (mut i, mut j) = (0, 0);
            for (g, d) in gradient.iter_mut().zip(directions) {
                if matches!(
                    d,
                    WavefrontDirection::FieldAngle(_)
                        | WavefrontDirection::SpectralMoment(_)
                        | WavefrontDirection::ImageShift
                ) {
                    *g = field[j];
                    j += 1;
                } else {
                    *g = lanes[i];
                    i += 1;
                }
            }
        };
        let mut seidel = vec![Complex64::new(0.0, 0.0); terms.len()];
        let mut field = vec![Complex64::new(0.0, 0.0); axes.len()];
        // a lane odd in y breaks the mirror symmetry of the derivative
        if !self.mirror || !terms.iter().all(Lane::even_in_y) {
            let v = self.compute_with_derivatives(frequency, azimuth, &terms, &mut seidel, &axes, &mut field);
            scatter(&seidel, &field, gradient);
            return Some(v);
        }
        let key = |phi: f64| (phi.rem_euclid(PI) * 1e9).round() as i64 % (PI * 1e9).round() as i64;
        let tolerance = self.value_tolerance.get().to_bits();
        let cache = self.differentiated.borrow();
        if let Some((v, d)) = cache.get(&(frequency.to_bits(), tolerance, key(PI - azimuth)))
            && d.len() == gradient.len()
        {
            for ((g, d), direction) in gradient.iter_mut().zip(d).zip(directions) {
                *g = match direction {
                    WavefrontDirection::FieldAngle(1) => -d.conj(),
                    _ => d.conj(),
                };
            }
            return Some(v.conj());
        }
        drop(cache);
        let v = self.compute_with_derivatives(frequency, azimuth, &terms, &mut seidel, &axes, &mut field);
        scatter(&seidel, &field, gradient);
        let mut cache = self.differentiated.borrow_mut();
        if cache.len() > 1 << 16 {
            cache.clear();
        }
        cache.insert((frequency.to_bits(), tolerance, key(azimuth)), (v, gradient.to_vec()));
        Some(v)
    }

    fn frequency_rule(&self) -> FrequencyRule {
        FrequencyRule::Adaptive { min_panels: 1.0 }
    }

    fn set_value_tolerance(&self, absolute: f64) {
        self.value_tolerance.set(absolute.max(1e-15));
    }

    fn value_noise(&self) -> f64 {
        self.value_tolerance.get()
    }

    fn defocus_lane_nodes(&self) -> Option<usize> {
        self.defocus_rule().map(|r| r.weights.iter().filter(|w| **w != 0.0).count() + r.extra.len())
    }

    fn over_budget(&self) -> Option<String> {
        let worst = self.worst.get();
        (worst > 0.0).then(|| {
            format!(
                "the overlap quadrature's t rule reached {} points with an OTF error estimate of {worst:.1e}",
                T_LEVELS[T_LEVELS.len() - 1]
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form of `∫ e^{i(αx² + βx)}` against a 400-point Gauss–Legendre sum, across the
    /// stationary point, beside it, far from it and for tiny α.
    #[test]
    fn quadratic_phase_integral_matches_a_quadrature() {
        let rule = crate::quad::gauss_legendre(400);
        for &(alpha, beta, x) in &[
            (3.0, 1.0, 0.9),
            (-3.0, 1.0, 0.9),
            (0.7, 12.0, 0.5),
            (-20.0, 45.0, 1.0),
            (1e-4, 30.0, 0.8),
            (1e-7, -2.0, 1.0),
            (5.0, 0.0, 0.3),
            (1e-12, 0.0, 1.0),
            // on both sides of 1e-9, where the quadratic term was once left out (a jump of
            // 2.4e-11 here), and past |βX| = 80
            (0.8e-9, 60.0, 1.0),
            (1.2e-9, 60.0, 1.0),
            (5e-3, 300.0, 1.0),
        ] {
            let reference: Complex64 =
                rule.iter().map(|&(u, w)| Complex64::from_polar(w * x, alpha * x * x * u * u + beta * x * u)).sum();
            let closed = quadratic_phase_integral(alpha, beta, x);
            assert!((closed - reference).norm() < 1e-12, "α {alpha}, β {beta}, X {x}: {closed} vs {reference}");
        }
    }

    /// The moments `I_m = ∫_{−X}^{X} x^m e^{i(αx² + βx)} dx` (m = 0, 1, 2) where the quadratic
    /// phase is small ([`small_alpha_moments`]: the Taylor series on `∫ u^p e^{ibu}`, by its
    /// power series for |βX| < 1 and by spherical Bessel functions above) against a 400-point
    /// Gauss–Legendre sum of the integrand itself, across |βX| from 0 to 80 and |α| X² up to
    /// [`MOMENTS_MIN_PHASE`]; and at the threshold, against [`quadratic_moments`].
    #[test]
    fn small_alpha_moments_match_a_quadrature() {
        let rule = crate::quad::gauss_legendre(400);
        for &x in &[1.0, 0.3, 1e-3] {
            for &ax2 in &[0.0, 1e-12, -3e-8, 5e-6, -1e-4, 3e-3, -1e-2, 1e-2] {
                for &bx in &[0.0, 1e-9, -0.4, 0.999, 1.0, -2.5, 7.0, 31.0, -80.0] {
                    let (alpha, beta) = (ax2 / (x * x), bx / x);
                    let moments = small_alpha_moments(alpha, beta, x);
                    // the value's own series is the moments' I0 bit for bit (the gradient's pass
                    // takes the value from the moments), on either side of |β X| = 1
                    let i0 = small_alpha_integral(alpha, beta, x);
                    assert!(
                        i0.re.to_bits() == moments[0].re.to_bits() && i0.im.to_bits() == moments[0].im.to_bits(),
                        "α X² {ax2}, β X {bx}, X {x}: {i0} vs {}",
                        moments[0]
                    );
                    for (m, got) in moments.iter().enumerate() {
                        let reference: Complex64 = rule
                            .iter()
                            .map(|&(u, w)| {
                                let xu = x * u;
                                Complex64::from_polar(w * x * xu.powi(m as i32), alpha * xu * xu + beta * xu)
                            })
                            .sum();
                        let scale = x.powi(m as i32 + 1);
                        assert!(
                            (got - reference).norm() <= 1e-14 * scale,
                            "α X² {ax2}, β X {bx}, X {x}, m {m}: {got} vs {reference}"
                        );
                    }
                    if ax2.abs() == MOMENTS_MIN_PHASE {
                        let recurrence = quadratic_moments(alpha, beta, x);
                        for m in 0..3 {
                            let scale = x.powi(m as i32 + 1) * (1.0 + bx.abs());
                            let d = (moments[m] - recurrence[m]).norm();
                            assert!(d <= 1e-11 * scale, "α X² {ax2}, β X {bx}, X {x}, m {m}: {d:e}");
                        }
                    }
                }
            }
        }
    }

    /// [`monomial_fourier_every`]'s power series (`|b| < 1`) against the series summed term by
    /// term in complex arithmetic for each power (the form it replaced), bit for bit in the part
    /// that is not zero, and the other part zero; every power, and the even ones up to a count.
    #[test]
    fn monomial_fourier_matches_the_series_term_by_term() {
        let by_terms = |b: f64, p: usize| {
            let (mut term, mut sum) = (Complex64::new(1.0, 0.0), Complex64::new(0.0, 0.0));
            for k in 0..24 {
                if (p + k).is_multiple_of(2) {
                    sum += term * (2.0 / (p + k + 1) as f64);
                }
                term *= Complex64::new(0.0, b / (k + 1) as f64);
            }
            sum
        };
        let mut b = -0.999_999;
        while b < 1.0 {
            for (count, step) in [(MONOMIALS, 1), (1, 2), (3, 2), (7, 2), (11, 2)] {
                let mut out = [Complex64::new(f64::NAN, f64::NAN); MONOMIALS];
                monomial_fourier_every(b, count, step, count, &mut out);
                for (p, got) in out.iter().enumerate() {
                    if p >= count || p % step != 0 {
                        assert!(got.re.is_nan() && got.im.is_nan(), "b {b}, p {p}: {got} written");
                        continue;
                    }
                    let want = by_terms(b, p);
                    let (part, other, want_part, want_other) = if p % 2 == 0 {
                        (got.re, got.im, want.re, want.im)
                    } else {
                        (got.im, got.re, want.im, want.re)
                    };
                    assert_eq!(part.to_bits(), want_part.to_bits(), "b {b}, p {p}: {got} vs {want}");
                    assert!(other == 0.0 && want_other == 0.0, "b {b}, p {p}: {got} vs {want}");
                }
            }
            b += 0.012_345_7;
        }
        for b in [0.0, -0.0, 1e-300, -1e-12, 0.5, -0.75] {
            let mut out = [Complex64::new(0.0, 0.0); MONOMIALS];
            monomial_fourier_every(b, MONOMIALS, 1, MONOMIALS, &mut out);
            for (p, got) in out.iter().enumerate() {
                let want = by_terms(b, p);
                assert!(got.re == want.re && got.im == want.im, "b {b}, p {p}: {got} vs {want}");
            }
        }
    }

    /// [`lanes_opd_at`] against [`lanes_opd`] at each of its points, bit for bit, for Zernike
    /// lanes of radial orders 1–6 (cosine, sine and `m = 0` terms, in an order that forms the
    /// powers out of turn), the Seidel terms and the defocus lane.
    #[test]
    fn lanes_at_points_match_lanes_one_point_at_a_time() {
        let mut lanes: Vec<Lane> = [9, 2, 22, 5, 8, 4, 16, 7, 11, 3, 6, 13]
            .iter()
            .map(|&j| Lane::of(&WavefrontDirection::Zernike(j)).unwrap())
            .collect();
        for t in [SeidelTerm::Spherical, SeidelTerm::Coma, SeidelTerm::Astigmatism, SeidelTerm::FieldCurvature] {
            lanes.push(Lane::Seidel(t));
        }
        lanes.push(Lane::Defocus);
        let (mut x, mut y) = ([0.0; LANE_POINTS], [0.0; LANE_POINTS]);
        for i in 0..LANE_POINTS {
            let (sn, c) = (0.9 * i as f64 + 0.3).sin_cos();
            (x[i], y[i]) = (0.93 * c * (1.0 - 0.1 * i as f64), 0.93 * sn * (1.0 - 0.07 * i as f64));
        }
        let mut out = vec![[0.0; LANE_POINTS]; lanes.len()];
        let mut powers = Vec::new();
        lanes_opd_at(&lanes, &x, &y, &mut powers, &mut out);
        let mut one = vec![0.0; lanes.len()];
        for i in 0..LANE_POINTS {
            lanes_opd(&lanes, x[i], y[i], &mut one);
            for (l, &v) in one.iter().enumerate() {
                assert_eq!(out[l][i].to_bits(), v.to_bits(), "lane {l}, point {i}: {} vs {v}", out[l][i]);
            }
        }
    }

    /// `j_m(b)` against the closed forms `j_0 = sin b/b`, `j_1 = sin b/b² − cos b/b`,
    /// `j_2 = (3/b² − 1) sin b/b − 3 cos b/b²`, and the small-argument series for high orders.
    #[test]
    fn spherical_bessel_matches_closed_forms() {
        for &b in &[0.3, 1.0, 3.1, 7.5, 20.0, -4.0, 60.0, 150.0] {
            let mut out = [0.0; 40];
            spherical_bessel(b, &mut out);
            let (s, c) = b.sin_cos();
            let j0 = s / b;
            let j1 = s / (b * b) - c / b;
            let j2 = (3.0 / (b * b) - 1.0) * s / b - 3.0 * c / (b * b);
            for (m, exact) in [j0, j1, j2].iter().enumerate() {
                assert!((out[m] - exact).abs() < 1e-12, "b = {b}, m = {m}: {} vs {exact}", out[m]);
            }
        }
        // j_30(1) = 1/(61!!) (1 − 1/(2·63) + …)
        let mut out = [0.0; 31];
        spherical_bessel(1.0, &mut out);
        let double_factorial: f64 = (1..=30).map(|i| (2 * i + 1) as f64).product();
        let series = (1.0 - 1.0 / 126.0 + 1.0 / (8.0 * 63.0 * 65.0)) / double_factorial;
        assert!((out[30] / series - 1.0).abs() < 1e-6, "{} vs {series}", out[30]);
    }

    /// A node of the chromatic lens's kind at 800 nm with `defocus` (m) and the rest given.
    fn node(defocus: f64, spherical: f64, coma: f64, astigmatism: f64, zernike: &[(usize, f64)]) -> Term {
        let mut term = Term {
            lambda: 800e-9,
            weight: 1.0,
            shift: [0.0, 0.0],
            shift_rate: None,
            defocus,
            lens_defocus: defocus,
            design: None,
            spherical,
            coma,
            astigmatism,
            zernike: None,
            zernike_rest: Vec::new(),
            s_top: 0.9,
            slope: 0.0,
            curvature: 0.0,
        };
        if !zernike.is_empty() {
            let degree = zernike.iter().map(|&(j, _)| noll_to_nm(j).0).max().unwrap_or(0);
            let compiled = Compiled::new(&Aberrations { zernike_noll_m: zernike.to_vec(), ..Aberrations::default() });
            term.zernike = Some((Arc::new(compiled), degree));
            term.zernike_rest = zernike.to_vec();
        }
        (term.slope, term.curvature) = term.rest_bounds();
        term
    }

    /// The a-priori bound that leaves a node out ([`Term::otf_bound`]): its two constants hold
    /// against the wavefront's gradient and second derivative by finite differences on a
    /// 61 × 61 grid over the disc (the slope bound within 2× of the largest found, so that the
    /// bound is not vacuous), and the node's OTF by the rules of [`term_otf`] (to 1e-10) is
    /// within it at 12 frequencies and 6 azimuths, for coma, astigmatism, spherical aberration
    /// and Zernike terms of radial order 2–6 under 0.5–6 waves of defocus; where the defocus
    /// dominates the bound falls below 0.3 (conclusive for a node whose share of the tolerance
    /// is larger).
    #[test]
    fn otf_bound_holds_for_the_nodes_otf() {
        let cases: [(&str, Term); 5] = [
            ("coma 0.5 µm", node(0.0, 0.0, 0.5e-6, 0.0, &[])),
            ("astigmatism 0.2 µm", node(0.0, 0.0, 0.0, 0.2e-6, &[])),
            ("spherical 0.2 µm, coma −0.3 µm", node(0.0, 0.2e-6, -0.3e-6, 0.0, &[])),
            ("Noll 5–8, 0.05 µm", node(0.0, 0.0, 0.0, 0.0, &[(5, 0.05e-6), (6, 0.05e-6), (7, 0.05e-6), (8, 0.05e-6)])),
            ("Noll 9, 14, 22", node(0.0, 0.0, 0.0, 0.0, &[(9, 0.03e-6), (14, -0.02e-6), (22, 0.02e-6)])),
        ];
        let mut conclusive = 0;
        for (name, base) in &cases {
            // the constants against finite differences (h = 1e-4) inside the disc
            let w = |x: f64, y: f64| {
                let r2 = x * x + y * y;
                let mut v = base.spherical * r2 * r2 + base.coma * r2 * x + base.astigmatism * x * x;
                if let Some((z, _)) = &base.zernike {
                    v += z.opd_m(x, y);
                }
                v
            };
            let (h, mut slope, mut curvature) = (1e-4, 0.0_f64, 0.0_f64);
            for i in 0..61 {
                for j in 0..61 {
                    let (x, y) = (-0.999 + 1.998 * i as f64 / 60.0, -0.999 + 1.998 * j as f64 / 60.0);
                    if x * x + y * y > (1.0 - 2.0 * h) * (1.0 - 2.0 * h) {
                        continue;
                    }
                    let (gx, gy) = ((w(x + h, y) - w(x - h, y)) / (2.0 * h), (w(x, y + h) - w(x, y - h)) / (2.0 * h));
                    slope = slope.max(gx.hypot(gy));
                    for q in 0..8 {
                        let (sn, c) = (PI * q as f64 / 8.0).sin_cos();
                        let second = (w(x + h * c, y + h * sn) - 2.0 * w(x, y) + w(x - h * c, y - h * sn)) / (h * h);
                        curvature = curvature.max(second.abs());
                    }
                }
            }
            assert!(slope <= base.slope * (1.0 + 1e-6), "{name}: |∇W| {slope:e} > {:e}", base.slope);
            assert!(curvature <= base.curvature * (1.0 + 1e-3), "{name}: {curvature:e} > {:e}", base.curvature);
            if base.zernike.is_none() {
                assert!(base.slope <= 2.0 * slope, "{name}: slope bound {:e} vs {slope:e}", base.slope);
            }
            for defocus in [0.4e-6, 1.2e-6, 4.8e-6] {
                let mut term = base.clone();
                term.defocus = defocus;
                for q in 1..=12 {
                    let s = 0.07 * q as f64;
                    let bound = term.otf_bound(s);
                    for a in 0..6 {
                        let (sn, c) = (PI * a as f64 / 6.0).sin_cos();
                        let (v, error) = term_otf(&term, X_LEVELS.len() - 1, s, c, sn, 1e-10);
                        assert!(error <= 1e-8, "{name}, s {s}: the rule's error {error:e}");
                        assert!(
                            v.norm() <= bound + 1e-8,
                            "{name}, W020 {defocus:e}, s {s}, azimuth {a}: |O| {} > bound {bound}",
                            v.norm()
                        );
                    }
                    if bound < 0.3 {
                        conclusive += 1;
                    }
                }
            }
        }
        assert!(conclusive >= 40, "the bound was below 0.3 at {conclusive} of 180 points");
    }
}
