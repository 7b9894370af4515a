//! The `Spectrum` enum: products of tabulated and analytic factors, with exact or quadrature
//! integrals.

use crate::Error;
use crate::analytic::{Blackbody, Gaussian, Line, TopHat};
use crate::quadrature;
use crate::sampled::Sampled;

use std::sync::Arc;

/// Half-width, in σ, of the window a Gaussian factor restricts a numerical integral to. The
/// neglected area is erfc(12/√2) ≈ 1.8e-33 of the Gaussian's.
pub const GAUSSIAN_WINDOW_SIGMAS: f64 = 12.0;

/// Truncated fractions at or below this are not reported by [`Spectrum::truncations`].
pub const NEGLIGIBLE_TRUNCATION: f64 = 1e-15;

/// A spectral function of wavelength (m), as a product of factors.
///
/// Every variant is exactly 0 at λ ≤ 0. Units are the caller's: typically one factor carries
/// W/(m² m) or W/(m² sr m) and the others are dimensionless (filter, efficiency, QE).
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// A constant for λ > 0 (0 at λ ≤ 0). Support (0, +∞).
    Constant(f64),
    /// `slope · λ` for λ > 0 (0 at λ ≤ 0); the λ factor of paper SI eq. S8. Support (0, +∞).
    Linear {
        /// Slope, value unit per m.
        slope: f64,
    },
    /// A table, piecewise linear and zero outside.
    Sampled(Sampled),
    /// A Gaussian truncated at λ ≤ 0.
    Gaussian(Gaussian),
    /// A top-hat band.
    TopHat(TopHat),
    /// A spectral line: one wavelength for integrals and the optics, with the weight of its
    /// equivalent band ([`Line`]). A product holding a line is that line, weighted by the other
    /// factors at its centre (see [`as_line`](Spectrum::as_line)).
    Line(Line),
    /// `scale ·` Planck spectral radiance B_λ(T) in W/(m² sr m). Support (0, +∞).
    Blackbody {
        /// The blackbody.
        source: Blackbody,
        /// Multiplier applied to the spectral radiance.
        scale: f64,
    },
    /// Planck's `∂ln B_λ/∂T` of `source` at λ > 0 (0 at λ ≤ 0), per K: `g(λ) = (x/T) eˣ/(eˣ − 1)`,
    /// `x = hc/(λkT)` ([`Blackbody::log_derivatives`]). Not a radiance: a weight that turns
    /// `ρ` into `∂ρ/∂T` where `ρ` holds the blackbody, so that the spectral rules integrate
    /// `∫ ρ g τ OTF dλ`, the temperature's move of the polychromatic OTF (docs/physics.md,
    /// "Gradients: a line's wavelength and a blackbody's temperature"). Smooth and positive on
    /// (0, +∞) (no breakpoints; it varies on the scale of λ, as the blackbody does), decreasing
    /// in λ from `hc/(kT²λ)` (Wien) to `1/T` (Rayleigh–Jeans). Support (0, +∞).
    PlanckTemperatureRate {
        /// The blackbody whose temperature moves.
        source: Blackbody,
    },
    /// The product of the factors (an empty product is 1 for λ > 0).
    Product(Vec<Spectrum>),
}

/// A Gaussian factor of a spectrum that loses a non-negligible part of its area outside the
/// spectrum's support (at λ ≤ 0, or outside a table or band it is multiplied with).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truncation {
    /// Center of the Gaussian, m.
    pub center_m: f64,
    /// σ of the Gaussian, m.
    pub sigma_m: f64,
    /// Fraction of the untruncated Gaussian's area outside `support_m`.
    pub fraction: f64,
    /// The spectrum's support, m, that the Gaussian is cut to.
    pub support_m: (f64, f64),
}

/// Most polynomial degree of one piece of a [`PiecewisePolynomial`] (a table × λ × a quadratic
/// QE, say); a product of higher degree is not offered as one.
pub const MAX_PIECE_DEGREE: usize = 4;

/// A spectrum that is a polynomial between breakpoints (see [`Spectrum::piecewise_polynomial`]):
/// piece `i` covers `[edges[i], edges[i + 1]]` and is `Σ_m pieces[i][m] (λ − edges[i])^m`; it is
/// zero outside `[edges[0], edges[last]]`.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewisePolynomial {
    /// Breakpoints, m, increasing.
    pub edges: Vec<f64>,
    /// Coefficients of each piece in powers of `λ − edges[i]` (SI), lowest first; those above
    /// [`degree`](Self::degree) are 0.
    pub pieces: Vec<[f64; MAX_PIECE_DEGREE + 1]>,
    /// The highest degree of any piece.
    pub degree: usize,
}

impl PiecewisePolynomial {
    /// `∫ p dλ` over the edges: `Σ_i Σ_m c_im h_i^{m+1}/(m + 1)`, `h_i` piece `i`'s width.
    pub fn integral(&self) -> f64 {
        self.pieces
            .iter()
            .zip(self.edges.windows(2))
            .map(|(c, e)| {
                let h = e[1] - e[0];
                c[..=self.degree].iter().enumerate().rev().fold(0.0, |acc, (m, &c)| acc * h + c / (m + 1) as f64) * h
            })
            .sum()
    }

    /// The value at `wavelength_m` (0 outside the edges).
    pub fn value(&self, wavelength_m: f64) -> f64 {
        let (first, last) = (self.edges[0], self.edges[self.edges.len() - 1]);
        if !(wavelength_m >= first && wavelength_m <= last) {
            return 0.0;
        }
        let i = self.edges.partition_point(|&e| e <= wavelength_m).clamp(1, self.pieces.len()) - 1;
        let t = wavelength_m - self.edges[i];
        self.pieces[i].iter().rev().fold(0.0, |acc, c| acc * t + c)
    }
}

/// Table rows (over all its tables) from which a spectrum's piecewise polynomial is remembered
/// ([`Spectrum::piecewise_polynomial`]); below, building it costs about what finding it would.
pub const MEMO_MIN_SAMPLES: usize = 64;

/// How many spectra's piecewise polynomials are remembered: the last ones built (a sweep's
/// detected spectrum, with and without an efficiency table folded in, and its transmission
/// product), each a few hundred kB at most for a 5000-row table.
pub const MEMO_ENTRIES: usize = 8;

/// The remembered piecewise polynomials with their integrals, the last built first.
type Memo = Vec<(Spectrum, Option<(Arc<PiecewisePolynomial>, f64)>)>;
thread_local! {
    /// Per thread: a sweep's worker threads each keep theirs (no lock; the same numbers in each,
    /// the polynomial being a function of the spectrum's bits).
    static PIECEWISE_MEMO: std::cell::RefCell<Memo> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Forgets the piecewise polynomials this thread remembers ([`Spectrum::piecewise_polynomial`]),
/// so that the next evaluation builds its own: for a time per evaluation measured by repeating
/// one scene (the accuracy report), which would otherwise find them made after the first.
pub fn forget_remembered() {
    PIECEWISE_MEMO.with_borrow_mut(Vec::clear);
}

/// A spectrum of the form `P(λ) · exp(−(λ − center)²/(2σ²))` for λ > 0, `P` a polynomial
/// (see [`Spectrum::gaussian_polynomial`]).
#[derive(Clone, Debug, PartialEq)]
pub struct GaussianPolynomial {
    /// Centre of the Gaussian, m.
    pub center_m: f64,
    /// Its standard deviation, m.
    pub sigma_m: f64,
    /// Coefficients of `P` in powers of λ (SI, λ in m), lowest first; they carry the peak value.
    pub coefficients: Vec<f64>,
}

impl GaussianPolynomial {
    /// The value at `wavelength_m` (0 at λ ≤ 0).
    pub fn value(&self, wavelength_m: f64) -> f64 {
        if wavelength_m <= 0.0 {
            return 0.0;
        }
        let d = (wavelength_m - self.center_m) / self.sigma_m;
        let p = self.coefficients.iter().rev().fold(0.0, |acc, c| acc * wavelength_m + c);
        p * (-0.5 * d * d).exp()
    }
}

/// One quadrature node: `Σ weight · g(wavelength_m)` approximates `∫ spectrum(λ) g(λ) dλ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadratureNode {
    /// Node wavelength, m.
    pub wavelength_m: f64,
    /// Spectrum value × quadrature weight (spectrum unit × m).
    pub weight: f64,
}

impl From<Sampled> for Spectrum {
    fn from(s: Sampled) -> Self {
        Spectrum::Sampled(s)
    }
}

impl From<Gaussian> for Spectrum {
    fn from(g: Gaussian) -> Self {
        Spectrum::Gaussian(g)
    }
}

impl From<TopHat> for Spectrum {
    fn from(t: TopHat) -> Self {
        Spectrum::TopHat(t)
    }
}

impl From<Line> for Spectrum {
    fn from(l: Line) -> Self {
        Spectrum::Line(l)
    }
}

impl From<Blackbody> for Spectrum {
    fn from(source: Blackbody) -> Self {
        Spectrum::Blackbody { source, scale: 1.0 }
    }
}

impl Spectrum {
    /// A validated [`Spectrum::Constant`]: `value` finite and ≥ 0.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `constant`.
    pub fn constant(value: f64) -> Result<Spectrum, Error> {
        crate::error::non_negative("constant", value, "")?;
        Ok(Spectrum::Constant(value))
    }

    /// A validated [`Spectrum::Linear`]: `slope` finite and ≥ 0 (per m).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `slope`.
    pub fn linear(slope: f64) -> Result<Spectrum, Error> {
        crate::error::non_negative("slope", slope, "per m")?;
        Ok(Spectrum::Linear { slope })
    }

    /// A validated [`Spectrum::Blackbody`]: `scale` finite and ≥ 0.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `scale`.
    pub fn blackbody(source: Blackbody, scale: f64) -> Result<Spectrum, Error> {
        crate::error::non_negative("scale", scale, "")?;
        Ok(Spectrum::Blackbody { source, scale })
    }

    /// The product of `factors`, with nested products flattened into one level.
    pub fn product(factors: Vec<Spectrum>) -> Spectrum {
        let mut flat = Vec::with_capacity(factors.len());
        for f in factors {
            flatten_into(f, &mut flat);
        }
        Spectrum::Product(flat)
    }

    /// Value at `wavelength_m` (the product of the factors' values); 0 at λ ≤ 0, NaN for NaN.
    /// A [`Line`] factor has the value of its equivalent band here; integrals treat it as one
    /// wavelength.
    pub fn value(&self, wavelength_m: f64) -> f64 {
        let l = wavelength_m;
        if l.is_nan() {
            return f64::NAN;
        }
        match self {
            Spectrum::Constant(c) => positive_only(l, *c),
            Spectrum::Linear { slope } => positive_only(l, slope * l),
            Spectrum::Sampled(s) => s.value(l),
            Spectrum::Gaussian(g) => g.value(l),
            Spectrum::TopHat(t) => t.value(l),
            Spectrum::Line(line) => line.value(l),
            Spectrum::Blackbody { source, scale } => scale * source.spectral_radiance(l),
            Spectrum::PlanckTemperatureRate { source } => {
                if l > 0.0 {
                    source.log_derivatives(l).1
                } else {
                    0.0
                }
            }
            Spectrum::Product(fs) => {
                if l <= 0.0 {
                    return 0.0;
                }
                fs.iter().map(|f| f.value(l)).product()
            }
        }
    }

    /// Interval (m) outside which the spectrum is exactly 0: the factors' supports intersected.
    /// Gaussian, Constant, Linear and Blackbody: (0, +∞); table: (first, last); top-hat:
    /// (lo, hi); line: its equivalent band (lo, hi). The lower bound is never < 0; an empty intersection is reported as a zero-width
    /// interval (x, x).
    pub fn support(&self) -> (f64, f64) {
        match self {
            Spectrum::Constant(_)
            | Spectrum::Linear { .. }
            | Spectrum::Gaussian(_)
            | Spectrum::Blackbody { .. }
            | Spectrum::PlanckTemperatureRate { .. } => (0.0, f64::INFINITY),
            Spectrum::Sampled(s) => s.range(),
            Spectrum::TopHat(t) => (t.lo(), t.hi()),
            Spectrum::Line(line) => (line.lo(), line.hi()),
            Spectrum::Product(fs) => {
                let (lo, hi) = fs
                    .iter()
                    .map(Spectrum::support)
                    .fold((0.0, f64::INFINITY), |(lo, hi), (a, b)| (f64::max(lo, a), f64::min(hi, b)));
                if lo > hi { (lo, lo) } else { (lo, hi) }
            }
        }
    }

    /// Sorted, deduplicated wavelengths (m) inside the (closed) support where the spectrum may
    /// not be smooth: table samples, top-hat edges, and a line's centre and band edges. Used to
    /// split quadrature panels.
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut out = Vec::new();
        self.collect_breakpoints(&mut out);
        let (lo, hi) = self.support();
        out.retain(|&x| x >= lo && x <= hi);
        // one table's wavelengths come strictly increasing: nothing to sort or merge
        if !out.is_sorted_by(|a, b| a < b) {
            out.sort_by(f64::total_cmp);
            out.dedup();
        }
        out
    }

    fn collect_breakpoints(&self, out: &mut Vec<f64>) {
        match self {
            Spectrum::Sampled(s) => out.extend_from_slice(s.wavelengths()),
            Spectrum::TopHat(t) => out.extend([t.lo(), t.hi()]),
            Spectrum::Line(line) => out.extend([line.lo(), line.center(), line.hi()]),
            Spectrum::Product(fs) => fs.iter().for_each(|f| f.collect_breakpoints(out)),
            _ => {}
        }
    }

    /// The Gaussian factors, in order (a quadrature can place nodes from their center and σ).
    pub fn gaussians(&self) -> Vec<&Gaussian> {
        let mut out = Vec::new();
        self.visit(&mut |f| {
            if let Spectrum::Gaussian(g) = f {
                out.push(g);
            }
        });
        out
    }

    fn blackbodies(&self) -> Vec<&Blackbody> {
        let mut out = Vec::new();
        self.visit(&mut |f| {
            if let Spectrum::Blackbody { source, .. } = f {
                out.push(source);
            }
        });
        out
    }

    /// The spectrum as `P(λ) · exp(−(λ − center)²/(2σ²))` for λ > 0 (0 at λ ≤ 0), with `P` a
    /// polynomial, when it is a product of exactly one Gaussian (several Gaussian factors are
    /// combined into one) with constants and linear factors; `None` otherwise (in particular for
    /// a [`Line`], which is one wavelength). Closed-form spectral integration applies to such
    /// spectra (`optics`, the Gaussian closed form).
    pub fn gaussian_polynomial(&self) -> Option<GaussianPolynomial> {
        let mut coefficients = vec![1.0];
        let mut gaussian: Option<(f64, f64, f64)> = None; // (center, σ, peak)
        let mut ok = true;
        self.visit(&mut |f| match f {
            Spectrum::Constant(c) => coefficients.iter_mut().for_each(|x| *x *= c),
            Spectrum::Linear { slope } => {
                coefficients.insert(0, 0.0);
                coefficients.iter_mut().for_each(|x| *x *= slope);
            }
            Spectrum::Gaussian(g) => {
                let (m2, s2, p2) = (g.center(), g.sigma(), g.peak());
                gaussian = Some(match gaussian {
                    None => (m2, s2, p2),
                    // exp(−(λ−m1)²/2s1²) exp(−(λ−m2)²/2s2²) = exp(−(m1−m2)²/2(s1²+s2²)) exp(−(λ−m)²/2s²)
                    Some((m1, s1, p1)) => {
                        let (v1, v2) = (s1 * s1, s2 * s2);
                        let m = (m1 * v2 + m2 * v1) / (v1 + v2);
                        let s = (v1 * v2 / (v1 + v2)).sqrt();
                        let p = p1 * p2 * (-(m1 - m2).powi(2) / (2.0 * (v1 + v2))).exp();
                        (m, s, p)
                    }
                });
            }
            _ => ok = false,
        });
        let (center_m, sigma_m, peak) = gaussian?;
        coefficients.iter_mut().for_each(|x| *x *= peak);
        (ok && sigma_m > 0.0 && sigma_m.is_finite() && coefficients.iter().all(|c| c.is_finite()))
            .then_some(GaussianPolynomial { center_m, sigma_m, coefficients })
    }

    /// The spectrum as a [`PiecewisePolynomial`], exactly, when it is a product of tables,
    /// top-hats, constants and linear factors with a finite support and pieces of degree at most
    /// [`MAX_PIECE_DEGREE`] (a filter table × λ × constant QE and radiance: quadratic pieces
    /// between the table's samples); `None` otherwise (Gaussians, blackbodies, lines, or no
    /// bounded factor). Moments of such a spectrum are sums of polynomial integrals, exact
    /// whatever the number of samples.
    ///
    /// Remembered, with its integral: a spectrum with a table of [`MEMO_MIN_SAMPLES`] rows or more (a measured
    /// filter, radiance or QE) keeps its polynomial in a small memo of the last [`MEMO_ENTRIES`]
    /// such spectra (one per thread), found again for a spectrum whose every number has the same
    /// bits ([`same_bits`](Self::same_bits)): the points of a sweep that leaves the spectrum alone
    /// (an F-number sweep of a measured-spectrum scene) build it once, not two times a point,
    /// and get the very same polynomial (the same `Arc`) each time, which the optics' moment
    /// rules are remembered by.
    pub fn piecewise_polynomial(&self) -> Option<Arc<PiecewisePolynomial>> {
        self.remembered_piecewise().map(|(p, _)| p)
    }

    /// [`piecewise_polynomial`](Self::piecewise_polynomial) with its
    /// [`integral`](PiecewisePolynomial::integral), both remembered.
    fn remembered_piecewise(&self) -> Option<(Arc<PiecewisePolynomial>, f64)> {
        let mut rows = 0;
        self.visit(&mut |f| {
            if let Spectrum::Sampled(t) = f {
                rows += t.wavelengths().len();
            }
        });
        let build = || {
            self.build_piecewise_polynomial().map(|p| {
                let integral = p.integral();
                (Arc::new(p), integral)
            })
        };
        if rows < MEMO_MIN_SAMPLES {
            return build();
        }
        PIECEWISE_MEMO.with_borrow_mut(|memo| {
            if let Some((_, found)) = memo.iter().find(|(s, _)| s.same_bits(self)) {
                return found.clone();
            }
            let built = build();
            memo.insert(0, (self.clone(), built.clone()));
            memo.truncate(MEMO_ENTRIES);
            built
        })
    }

    /// Whether `self` and `other` are the same product of the same factors with numbers of the
    /// same bits (so that every computation from them gives the same bits: `0.0` and `-0.0`
    /// differ here, unlike `==`, and a NaN equals its own bits).
    pub fn same_bits(&self, other: &Spectrum) -> bool {
        let same =
            |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        match (self, other) {
            (Spectrum::Constant(a), Spectrum::Constant(b)) => a.to_bits() == b.to_bits(),
            (Spectrum::Linear { slope: a }, Spectrum::Linear { slope: b }) => a.to_bits() == b.to_bits(),
            (Spectrum::Sampled(a), Spectrum::Sampled(b)) => {
                same(a.wavelengths(), b.wavelengths()) && same(a.values(), b.values())
            }
            (Spectrum::Gaussian(a), Spectrum::Gaussian(b)) => a.bits() == b.bits(),
            (Spectrum::TopHat(a), Spectrum::TopHat(b)) => a.bits() == b.bits(),
            (Spectrum::Line(a), Spectrum::Line(b)) => a.bits() == b.bits(),
            (Spectrum::Blackbody { source: a, scale: x }, Spectrum::Blackbody { source: b, scale: y }) => {
                a.bits() == b.bits() && x.to_bits() == y.to_bits()
            }
            (Spectrum::PlanckTemperatureRate { source: a }, Spectrum::PlanckTemperatureRate { source: b }) => {
                a.bits() == b.bits()
            }
            (Spectrum::Product(a), Spectrum::Product(b)) => {
                a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.same_bits(y))
            }
            _ => false,
        }
    }

    /// [`piecewise_polynomial`](Self::piecewise_polynomial), built.
    fn build_piecewise_polynomial(&self) -> Option<PiecewisePolynomial> {
        let mut factors = Vec::new();
        self.visit(&mut |f| factors.push(f));
        let (lo, hi) = self.support();
        if !(lo < hi && hi.is_finite() && lo >= 0.0) {
            return None;
        }
        let mut degree = 0;
        for f in &factors {
            degree += match f {
                Spectrum::Constant(_) | Spectrum::TopHat(_) => 0,
                Spectrum::Linear { .. } | Spectrum::Sampled(_) => 1,
                _ => return None,
            };
        }
        if degree > MAX_PIECE_DEGREE {
            return None;
        }
        // the breakpoints come sorted, deduplicated and within the support: the support's ends
        // go at the ends
        let mut edges = self.breakpoints();
        if edges.first() != Some(&lo) {
            edges.insert(0, lo);
        }
        if edges.last() != Some(&hi) {
            edges.push(hi);
        }
        let mut unit = [0.0; MAX_PIECE_DEGREE + 1];
        unit[0] = 1.0;
        let mut pieces = vec![unit; edges.len() - 1];
        // factor by factor over all pieces (one dispatch a factor, not a piece); `top` is the
        // degree so far, raised by one by each linear factor, within the bound counted above
        let mut top = 0;
        for f in &factors {
            // × (c0 + c1 t), t = λ − x0, from the top down in place
            let times = |piece: &mut [f64; MAX_PIECE_DEGREE + 1], c0: f64, c1: f64, top: usize| {
                piece[top + 1] = piece[top] * c1;
                for m in (1..=top).rev() {
                    piece[m] = piece[m] * c0 + piece[m - 1] * c1;
                }
                piece[0] *= c0;
            };
            match f {
                Spectrum::Constant(c) => pieces.iter_mut().for_each(|p| p[..=top].iter_mut().for_each(|v| *v *= c)),
                Spectrum::TopHat(t) => {
                    for (i, piece) in pieces.iter_mut().enumerate() {
                        let c = t.value(0.5 * (edges[i] + edges[i + 1]));
                        piece[..=top].iter_mut().for_each(|v| *v *= c);
                    }
                }
                Spectrum::Linear { slope } => {
                    for (i, piece) in pieces.iter_mut().enumerate() {
                        times(piece, slope * edges[i], *slope, top);
                    }
                    top += 1;
                }
                Spectrum::Sampled(table) => {
                    // the table's segment under each piece: the pieces run in increasing λ
                    let (w, v) = (table.wavelengths(), table.values());
                    let mut k = 1;
                    for (i, piece) in pieces.iter_mut().enumerate() {
                        let (x0, x1) = (edges[i], edges[i + 1]);
                        let mid = 0.5 * (x0 + x1);
                        while k < w.len() - 1 && w[k] < mid {
                            k += 1;
                        }
                        let slope = (v[k] - v[k - 1]) / (w[k] - w[k - 1]);
                        times(piece, v[k - 1] + slope * (x0 - w[k - 1]), slope, top);
                    }
                    top += 1;
                }
                _ => return None,
            }
        }
        pieces.iter().all(|p| p.iter().all(|c| c.is_finite())).then_some(PiecewisePolynomial { edges, pieces, degree })
    }

    /// The spectrum as one weighted wavelength, when a factor is a [`Line`]: the line at its
    /// centre with weight `peak · width · Π f(center)` over the other factors `f`, so that
    /// `∫ spectrum · g dλ = weight · g(center)` for any `g` (the whole band at one wavelength).
    /// With several lines the narrowest (the first among equals) is the wavelength, and the
    /// others act as filters: their equivalent bands' values at its centre. `None` without a line.
    pub fn as_line(&self) -> Option<QuadratureNode> {
        let mut factors = Vec::new();
        self.visit(&mut |f| factors.push(f));
        let (index, line) = factors
            .iter()
            .enumerate()
            .filter_map(|(i, f)| if let Spectrum::Line(l) = f { Some((i, *l)) } else { None })
            .reduce(|best, next| if next.1.width() < best.1.width() { next } else { best })?;
        let c = line.center();
        let others: f64 = factors.iter().enumerate().filter(|&(i, _)| i != index).map(|(_, f)| f.value(c)).product();
        Some(QuadratureNode { wavelength_m: c, weight: line.integral() * others })
    }

    /// The [`Line`] factor [`as_line`](Spectrum::as_line) takes as the wavelength (the narrowest,
    /// the first among equals), if any.
    pub fn line(&self) -> Option<Line> {
        let mut found: Option<Line> = None;
        self.visit(&mut |f| {
            if let Spectrum::Line(l) = f
                && found.is_none_or(|best| l.width() < best.width())
            {
                found = Some(*l);
            }
        });
        found
    }

    /// How the weight `w` of [`as_line`](Spectrum::as_line) moves with the line's centre `c`:
    /// `∂ln w/∂c = Σ_f ∂ln f/∂λ` at `c` over the other factors `f` (per m): 0 for a constant, a
    /// top-hat or another line's equivalent band (strictly inside them), `1/c` for the photon
    /// factor `λ`, `−(c − c_g)/σ²` for a Gaussian, a table's segment's slope over its value,
    /// and Planck's `∂ln B/∂λ` ([`Blackbody::log_derivatives`]). The line's own weight
    /// `peak · width` does not move with its centre. `Err` naming why where `w` is not
    /// differentiable there: a table's sample or a band's edge at `c` (a kink or a jump), a
    /// factor that is 0 at `c`, or no line.
    pub fn line_weight_log_derivative(&self) -> Result<f64, String> {
        let line = self.line().ok_or_else(|| "the spectrum has no line".to_owned())?;
        let c = line.center();
        let mut factors = Vec::new();
        self.visit(&mut |f| factors.push(f));
        let mut skipped = false;
        let mut sum = 0.0;
        let inside = |lo: f64, hi: f64, what: &str| {
            if c > lo && c < hi {
                Ok(0.0)
            } else {
                Err(format!(
                    "the line at {:.6} nm lies on or outside the edge of {what} [{:.6}, {:.6}] nm, where the weight jumps",
                    c * 1e9,
                    lo * 1e9,
                    hi * 1e9
                ))
            }
        };
        for f in factors {
            sum += match f {
                Spectrum::Line(l) if !skipped && *l == line => {
                    skipped = true;
                    0.0
                }
                Spectrum::Line(l) => inside(l.lo(), l.hi(), "another line's equivalent band")?,
                Spectrum::TopHat(t) => inside(t.lo(), t.hi(), "a top-hat band")?,
                Spectrum::Constant(v) if *v != 0.0 => 0.0,
                Spectrum::Linear { slope } if *slope != 0.0 => 1.0 / c,
                Spectrum::Gaussian(g) => -(c - g.center()) / (g.sigma() * g.sigma()),
                Spectrum::Blackbody { source, scale } if *scale != 0.0 => source.log_derivatives(c).0,
                Spectrum::PlanckTemperatureRate { source } => source.temperature_rate_log_slope(c),
                Spectrum::Sampled(table) => {
                    let (w, v) = (table.wavelengths(), table.values());
                    let k = w.partition_point(|&x| x < c);
                    if k == 0 || k >= w.len() || w[k] == c {
                        return Err(format!(
                            "the line at {:.6} nm lies on a sample of a table or outside it (a table is linear \
                             between its samples, with a kink at each)",
                            c * 1e9
                        ));
                    }
                    let value = f.value(c);
                    if value == 0.0 {
                        return Err(format!("a table is 0 at the line's {:.6} nm", c * 1e9));
                    }
                    (v[k] - v[k - 1]) / (w[k] - w[k - 1]) / value
                }
                _ => return Err(format!("a factor of the spectrum is 0 at the line's {:.6} nm", c * 1e9)),
            };
        }
        Ok(sum)
    }

    /// Calls `f` on every non-product factor.
    fn visit<'a>(&'a self, f: &mut impl FnMut(&'a Spectrum)) {
        match self {
            Spectrum::Product(fs) => fs.iter().for_each(|x| x.visit(f)),
            other => f(other),
        }
    }

    /// Each Gaussian factor that loses more than 1e-15 of its (untruncated) area outside the
    /// spectrum's support: below λ = 0 (½·erfc(center/(σ√2)) for a lone Gaussian) or outside a
    /// table or band it is multiplied with (docs/physics.md, "Spectra": truncated there, and the fact reported).
    /// A spectrum with a [`Line`] truncates nothing: its Gaussian factors are only evaluated at
    /// the line.
    pub fn truncations(&self) -> Vec<Truncation> {
        if self.as_line().is_some() {
            return Vec::new();
        }
        let (lo, hi) = self.support();
        self.gaussians()
            .into_iter()
            .filter_map(|g| {
                let fraction = g.fraction_outside(lo, hi);
                (fraction > NEGLIGIBLE_TRUNCATION).then_some(Truncation {
                    center_m: g.center(),
                    sigma_m: g.sigma(),
                    fraction,
                    support_m: (lo, hi),
                })
            })
            .collect()
    }

    /// ∫ spectrum dλ over λ > 0 (spectrum unit × m).
    ///
    /// With a [`Line`] factor: the weight of [`as_line`](Self::as_line), `peak · width` times the
    /// other factors at the centre (exact).
    ///
    /// Exact (closed form): a single `Sampled` (trapezoid), `Gaussian` (erfc, with truncation),
    /// `TopHat`, `Blackbody` (σT⁴/π), each optionally times `Constant`s. Products of only
    /// `Constant` and `Linear` factors integrate to +∞ (0 if a factor is 0).
    ///
    /// Otherwise: composite 16-node Gauss–Legendre on panels split at the
    /// [`breakpoints`](Self::breakpoints), which is exact (to rounding) for products of tables,
    /// top-hats, constants and up to 30 linear factors (piecewise polynomials of degree ≤ 31).
    /// Gaussian factors restrict the range to center ± 12σ with 1σ panels (relative error
    /// ~1e-15, up to ~1e-12 for σ below 1e-4 of the center, from rounding the node
    /// positions); Blackbody factors add panels at ratios √2 around the Wien peak and map the
    /// infinite upper tail to a finite interval by u = 1/λ (relative error ~1e-15 on
    /// ∫B dλ and ∫λB dλ).
    pub fn integral(&self) -> f64 {
        if let Some(line) = self.as_line() {
            return line.weight;
        }
        let factors: Vec<&Spectrum> = {
            let mut v = Vec::new();
            self.visit(&mut |f| v.push(f));
            v
        };
        let mut constant = 1.0;
        let mut rest: Vec<&Spectrum> = Vec::new();
        for f in &factors {
            match f {
                Spectrum::Constant(c) => constant *= c,
                other => rest.push(other),
            }
        }
        let exact = match rest.as_slice() {
            [] => Some(f64::INFINITY),
            [Spectrum::Sampled(s)] => Some(s.integral()),
            [Spectrum::Gaussian(g)] => Some(g.integral()),
            [Spectrum::TopHat(t)] => Some(t.integral()),
            [Spectrum::Blackbody { source, scale }] => Some(scale * source.integral()),
            _ => None,
        };
        // a product of tables, top-hats and λ: exact sums of polynomial integrals over its
        // pieces, a pass over its breakpoints (the quadrature below evaluates every factor at
        // several nodes of every piece: half of a measured-spectrum sweep point's time)
        if exact.is_none()
            && let Some((_, integral)) = self.remembered_piecewise()
        {
            return integral;
        }
        // a Gaussian filter times tables (a measured transmission or QE): the tables' exact
        // polynomial pieces against the Gaussian, a few points a piece
        if exact.is_none()
            && let Some(integral) = self.gaussian_piecewise_integral()
        {
            return integral;
        }
        match exact {
            Some(v) if v.is_infinite() && constant == 0.0 => 0.0,
            Some(v) => constant * v,
            None if rest.iter().all(|f| matches!(f, Spectrum::Linear { .. })) => {
                // Constants × λ^n over (0, ∞): diverges unless a factor is 0.
                let k: f64 = rest
                    .iter()
                    .map(|f| match f {
                        Spectrum::Linear { slope } => *slope,
                        _ => 1.0,
                    })
                    .product::<f64>()
                    * constant;
                if k == 0.0 { 0.0 } else { k * f64::INFINITY }
            }
            None => self.quadrature_nodes().iter().map(|n| n.weight).sum(),
        }
    }

    /// `∫ p(λ) G(λ) dλ` where the spectrum is Gaussian factors `G` (combined into one) times a
    /// product `p` of tables, top-hats, constants and linear factors with a
    /// [`piecewise_polynomial`](Self::piecewise_polynomial); `None` otherwise. Over the window
    /// the quadrature keeps (± [`GAUSSIAN_WINDOW_SIGMAS`] σ), each piece is integrated by
    /// Gauss–Legendre on `n` points, exact for `p` (degree `d`) times the Gaussian's Taylor
    /// polynomial of degree `2n − 1 − d` about the piece's centre: the rest is at most
    /// `(w/2σ)^{2n−d}` of the piece's integral (`w` its width; the Hermite factor
    /// `He_k(0)/k!` < 1 left out), and `n` (2 to 8) is the fewest points that bring it below
    /// 1e-17; a piece wider than σ/4 is cut into equal parts no wider. A 5000-row table at
    /// 0.08 nm under a 21 nm σ takes 3 points a row (the 16-point panels of the general
    /// quadrature, each point a lookup of every factor, took 45 % of an evaluation of a harmonic
    /// lens with a 5000-row transmission table).
    fn gaussian_piecewise_integral(&self) -> Option<f64> {
        let mut gaussians = Vec::new();
        let mut rest = Vec::new();
        let mut bounded = false;
        let mut other = false;
        self.visit(&mut |f| match f {
            Spectrum::Gaussian(_) => gaussians.push(f.clone()),
            Spectrum::Sampled(_) | Spectrum::TopHat(_) => {
                bounded = true;
                rest.push(f.clone());
            }
            Spectrum::Constant(_) | Spectrum::Linear { .. } => rest.push(f.clone()),
            _ => other = true,
        });
        if other || !bounded || gaussians.is_empty() {
            return None;
        }
        let g = Spectrum::Product(gaussians).gaussian_polynomial()?;
        let (center, sigma, peak) = (g.center_m, g.sigma_m, g.coefficients[0]);
        let (p, _) = Spectrum::Product(rest).remembered_piecewise()?;
        let (lo, hi) = (center - GAUSSIAN_WINDOW_SIGMAS * sigma, center + GAUSSIAN_WINDOW_SIGMAS * sigma);
        let d = p.degree as i32;
        let mut sum = 0.0;
        for (piece, edge) in p.pieces.iter().zip(p.edges.windows(2)) {
            let (a, b) = (edge[0].max(lo).max(0.0), edge[1].min(hi));
            if a >= b {
                continue;
            }
            let parts = ((b - a) / (0.25 * sigma)).ceil().max(1.0);
            let w = (b - a) / parts;
            let ratio = w / (2.0 * sigma);
            let points = (2..=8).find(|&n| ratio.powi(2 * n - d) <= 1e-17).unwrap_or(8) as usize;
            let rule = quadrature::gauss_legendre(points);
            for k in 0..parts as usize {
                let (pa, pb) = (a + w * k as f64, if k + 1 == parts as usize { b } else { a + w * (k + 1) as f64 });
                let (half, mid) = (0.5 * (pb - pa), 0.5 * (pa + pb));
                for &(x, weight) in rule {
                    let l = mid + half * x;
                    let t = l - edge[0];
                    let value = piece[..=p.degree].iter().rev().fold(0.0, |acc, c| acc * t + c);
                    let z = (l - center) / sigma;
                    sum += half * weight * value * (-0.5 * z * z).exp();
                }
            }
        }
        Some(peak * sum)
    }

    /// Quadrature nodes for weighting by this spectrum: `Σ weight · g(λ)` ≈ `∫ spectrum · g dλ`,
    /// with the panels described in [`integral`](Self::integral) (nodes of zero weight
    /// dropped). `Σ weight` is the numerical integral. Empty when the spectrum has unbounded
    /// support without a decaying (Gaussian or Blackbody) factor. With a [`Line`] factor: one
    /// node, [`as_line`](Self::as_line) (exact for every `g`), or none if its weight is 0.
    pub fn quadrature_nodes(&self) -> Vec<QuadratureNode> {
        self.quadrature_nodes_cut_at(&[])
    }

    /// [`quadrature_nodes`](Self::quadrature_nodes) with the panels also cut at `cuts` (m) where
    /// they fall inside the rule's interval: the kinks of a function `g` the nodes will weigh
    /// (a lens's transmission between the rows of its tables), so that every panel meets `g`
    /// smooth. With no cuts the same nodes, bit for bit.
    pub fn quadrature_nodes_cut_at(&self, extra: &[f64]) -> Vec<QuadratureNode> {
        let mut nodes = Vec::new();
        if let Some(line) = self.as_line() {
            push(&mut nodes, line.wavelength_m, line.weight);
            return nodes;
        }
        let (mut lo, mut hi) = self.support();
        let gaussians = self.gaussians();
        for g in &gaussians {
            lo = lo.max(g.center() - GAUSSIAN_WINDOW_SIGMAS * g.sigma());
            hi = hi.min(g.center() + GAUSSIAN_WINDOW_SIGMAS * g.sigma());
        }
        if lo.is_nan() || hi.is_nan() || lo >= hi {
            return nodes;
        }
        let blackbodies = self.blackbodies();
        if hi.is_infinite() && blackbodies.is_empty() {
            return nodes;
        }
        let mut cuts = self.breakpoints();
        cuts.extend(extra.iter().copied().filter(|x| x.is_finite()));
        cuts.push(lo);
        for g in &gaussians {
            let k = GAUSSIAN_WINDOW_SIGMAS as i32;
            cuts.extend((-k..=k).map(|i| g.center() + f64::from(i) * g.sigma()));
        }
        for b in &blackbodies {
            let p = b.peak_wavelength();
            // p/32 (where B ~ e^-159 of its peak) to 64 p, ratios √2.
            cuts.extend((-10..=12).map(|i| p * 2f64.powf(f64::from(i) / 2.0)));
        }
        // The tail starts at the last cut; it needs a finite, positive start.
        let tail_start = cuts.iter().copied().fold(lo, f64::max);
        if hi.is_finite() {
            cuts.push(hi);
        }
        let top = if hi.is_finite() { hi } else { tail_start };
        cuts.retain(|&x| x >= lo && x <= top);
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        for w in cuts.windows(2) {
            quadrature::for_each_node(w[0], w[1], |x, wt| push(&mut nodes, x, wt * self.value(x)));
        }
        if hi.is_infinite() && tail_start > 0.0 {
            // ∫_L^∞ f(λ) dλ = ∫_0^{1/L} f(1/u)/u² du, split into four panels.
            let umax = 1.0 / tail_start;
            for j in 0..4 {
                let (a, b) = (umax * f64::from(j) / 4.0, umax * f64::from(j + 1) / 4.0);
                quadrature::for_each_node(a, b, |u, wt| {
                    let l = 1.0 / u;
                    push(&mut nodes, l, wt * self.value(l) / (u * u));
                });
            }
        }
        nodes
    }
}

fn push(nodes: &mut Vec<QuadratureNode>, wavelength_m: f64, weight: f64) {
    if weight != 0.0 {
        nodes.push(QuadratureNode { wavelength_m, weight });
    }
}

fn positive_only(l: f64, v: f64) -> f64 {
    if l > 0.0 { v } else { 0.0 }
}

fn flatten_into(s: Spectrum, out: &mut Vec<Spectrum>) {
    match s {
        Spectrum::Product(fs) => fs.into_iter().for_each(|f| flatten_into(f, out)),
        other => out.push(other),
    }
}

#[cfg(test)]
mod tests {

    /// The piecewise polynomial of a filter table × a second, coarser table × λ × a top-hat ×
    /// a constant is the product itself, at the samples, between them and across every
    /// breakpoint; spectra with a smooth non-polynomial factor have none.
    #[test]
    fn piecewise_polynomial_reproduces_the_product() {
        let fine = Sampled::new(
            (0..=40).map(|i| 600e-9 + 10e-9 * f64::from(i)).collect(),
            (0..=40).map(|i| 0.5 + 0.4 * (0.7 * f64::from(i)).sin()).collect(),
        )
        .unwrap();
        let coarse = Sampled::new(vec![550e-9, 700e-9, 850e-9, 1100e-9], vec![0.2, 1.0, 0.6, 0.9]).unwrap();
        let s = Spectrum::product(vec![
            Spectrum::Sampled(fine),
            Spectrum::Sampled(coarse),
            Spectrum::Linear { slope: 2.0 },
            Spectrum::TopHat(TopHat::new(640e-9, 930e-9, 1.5).unwrap()),
            Spectrum::Constant(3.0),
        ]);
        let p = s.piecewise_polynomial().expect("a product of tables, λ, a top-hat and a constant");
        assert_eq!((p.edges[0], *p.edges.last().unwrap()), (640e-9, 930e-9));
        for k in 0..=3000 {
            let l = 620e-9 + 330e-9 * f64::from(k) / 3000.0;
            let (got, want) = (p.value(l), s.value(l));
            assert!((got - want).abs() <= 1e-12 * want.abs().max(1e-9), "{l}: {got} vs {want}");
        }
        let g = Gaussian::new(800e-9, 20e-9, 1.0).unwrap();
        assert!(
            Spectrum::product(vec![Spectrum::Gaussian(g), Spectrum::TopHat(TopHat::new(7e-7, 9e-7, 1.0).unwrap())])
                .piecewise_polynomial()
                .is_none()
        );
        assert!(Spectrum::Linear { slope: 1.0 }.piecewise_polynomial().is_none(), "an unbounded support");
        // its integral, exact over the pieces, against the quadrature nodes (Gauss–Legendre
        // panels between the breakpoints, exact for these quadratic and cubic pieces)
        let quadrature: f64 = s.quadrature_nodes().iter().map(|n| n.weight).sum();
        assert!((s.integral() - quadrature).abs() <= 1e-13 * quadrature, "{} vs {quadrature}", s.integral());
        assert_eq!(s.integral(), p.integral());
    }

    #[test]
    fn gaussian_polynomial_reproduces_the_product() {
        // radiance × Gaussian filter × Gaussian QE × λ: one Gaussian times a linear polynomial
        let g1 = Gaussian::new(800e-9, 20e-9, 2.0).unwrap();
        let g2 = Gaussian::new(780e-9, 40e-9, 0.5).unwrap();
        let s = Spectrum::product(vec![
            Spectrum::Constant(3.0),
            Spectrum::Gaussian(g1),
            Spectrum::Linear { slope: 1.0 },
            Spectrum::Gaussian(g2),
        ]);
        let gp = s.gaussian_polynomial().unwrap();
        assert_eq!(gp.coefficients.len(), 2);
        for l in [700e-9, 790e-9, 805e-9, 900e-9] {
            let (a, b) = (s.value(l), gp.value(l));
            assert!((a - b).abs() <= 1e-13 * a.abs(), "{l}: {a} vs {b}");
        }
        assert_eq!(gp.value(-1e-9), 0.0);
        // tables, top-hats and blackbodies have no such form
        let t =
            Spectrum::product(vec![Spectrum::Gaussian(g1), Spectrum::TopHat(TopHat::new(7e-7, 9e-7, 1.0).unwrap())]);
        assert!(t.gaussian_polynomial().is_none());
        assert!(Spectrum::Constant(1.0).gaussian_polynomial().is_none());
    }
    use super::*;

    /// `∂ln w/∂c` of a line's weight ([`Spectrum::line_weight_log_derivative`]) against central
    /// differences of [`Spectrum::as_line`]'s weight with the line moved (relative step 1e-6 of
    /// the centre, truncation and rounding both ~1e-10 of the derivative's scale 1/σ): a line
    /// through a blackbody, a table, a Gaussian, a constant and the photon factor λ; refused on
    /// a table's sample and at a band's edge.
    #[test]
    fn a_line_weight_moves_with_its_centre_as_its_factors_slopes() {
        let table = Spectrum::Sampled(Sampled::new(vec![700e-9, 800e-9, 900e-9], vec![0.2, 0.9, 0.4]).unwrap());
        let with = |c: f64| {
            Spectrum::product(vec![
                Spectrum::Blackbody { source: Blackbody::new(3000.0).unwrap(), scale: 2e-3 },
                table.clone(),
                Spectrum::Gaussian(Gaussian::new(780e-9, 20e-9, 0.9).unwrap()),
                Spectrum::Line(Line::new(c, 1e-9, 0.8).unwrap()),
                Spectrum::Constant(0.2),
                Spectrum::Linear { slope: 1.0 },
            ])
        };
        for c in [803e-9, 750e-9, 871e-9] {
            let h = 1e-6 * c;
            let weight = |c: f64| with(c).as_line().unwrap().weight.ln();
            let differences = (weight(c + h) - weight(c - h)) / (2.0 * h);
            let exact = with(c).line_weight_log_derivative().unwrap();
            assert!((exact - differences).abs() <= 1e-7 / 20e-9, "{c}: {exact} vs {differences}");
        }
        let e = with(800e-9).line_weight_log_derivative().unwrap_err();
        assert!(e.contains("sample"), "{e}");
        let band = Spectrum::product(vec![
            Spectrum::TopHat(TopHat::new(780e-9, 803e-9, 1.0).unwrap()),
            Spectrum::Line(Line::new(803e-9, 1e-9, 1.0).unwrap()),
        ]);
        assert!(band.line_weight_log_derivative().unwrap_err().contains("edge"));
    }

    /// Planck's temperature rate `g = ∂ln B/∂T` ([`Spectrum::PlanckTemperatureRate`]) against
    /// central differences in T of the logarithm of Planck's law written here,
    /// `B = 2hc²/λ⁵/(exp(hc/(λkT)) − 1)` (SI 2019 constants), relative step 1e-5 (truncation
    /// ~(h/T)² = 1e-10 of g, ln B varying on the scale of T; rounding ~1e-11), from 300 nm to
    /// 20 µm at 300, 3000 and 30 000 K (x = hc/(λkT) from 0.024 to 160), within 1e-8 relative;
    /// its slope in λ (the line weight's arm) against central differences of ln g in λ; and
    /// `∫ B g dλ = ∂(σT⁴/π)/∂T = 4σT³/π` through the spectrum's quadrature, within 1e-12.
    #[test]
    fn planck_temperature_rate_is_the_derivative_of_plancks_law() {
        let (h, c, k): (f64, f64, f64) = (6.626_070_15e-34, 299_792_458.0, 1.380_649e-23);
        let ln_planck = |l: f64, t: f64| (2.0 * h * c * c).ln() - 5.0 * l.ln() - (h * c / (l * k * t)).exp_m1().ln();
        for t in [300.0, 3000.0, 30000.0] {
            let rate = Spectrum::PlanckTemperatureRate { source: Blackbody::new(t).unwrap() };
            for l in [300e-9, 550e-9, 825e-9, 1.6e-6, 5e-6, 20e-6] {
                let step = 1e-5 * t;
                let differences = (ln_planck(l, t + step) - ln_planck(l, t - step)) / (2.0 * step);
                let g = rate.value(l);
                assert!(g > 0.0 && ((g - differences) / differences).abs() <= 1e-8, "{t} K {l}: {g} vs {differences}");
                let dl = 1e-6 * l;
                let slope = (rate.value(l + dl).ln() - rate.value(l - dl).ln()) / (2.0 * dl);
                let line = Spectrum::product(vec![rate.clone(), Spectrum::Line(Line::new(l, 1e-12, 1.0).unwrap())]);
                let exact = line.line_weight_log_derivative().unwrap();
                assert!((exact - slope).abs() <= 1e-7 / l, "{t} K {l}: slope {exact} vs {slope}");
            }
            assert_eq!(rate.value(0.0), 0.0);
            let source = Blackbody::new(t).unwrap();
            let weighted = Spectrum::product(vec![Spectrum::from(source), rate]).integral();
            let exact = 4.0 * crate::constants::STEFAN_BOLTZMANN * t.powi(3) / std::f64::consts::PI;
            assert!(((weighted - exact) / exact).abs() <= 1e-12, "{t} K: ∫B g = {weighted} vs {exact}");
        }
    }

    /// A Gaussian times tables ([`Spectrum::gaussian_piecewise_integral`]) against the 16-point
    /// panels of the general quadrature (the slow, obviously correct reference, cut at every row
    /// and every σ): a 5000-row table at 0.08 nm × λ (3 points a row), a 3-row table (pieces of
    /// 5σ, cut into parts), a top-hat, two Gaussians, a table reaching past the window; within
    /// 1e-13.
    #[test]
    fn a_gaussian_times_tables_integrates_as_the_general_quadrature() {
        let g = |center_nm: f64, range_nm: f64| {
            Spectrum::Gaussian(Gaussian::from_range(center_nm * 1e-9, range_nm * 1e-9, 1.7).unwrap())
        };
        let long: Vec<f64> = (0..5000).map(|k| 600e-9 + 0.08e-9 * k as f64).collect();
        let ripple = long.iter().map(|&l| 0.5 + 0.1 * (l / 7e-9).sin() + 0.02 * (l / 0.77e-9).cos()).collect();
        let long = Spectrum::Sampled(Sampled::new(long, ripple).unwrap());
        let short = Spectrum::Sampled(Sampled::new(vec![700e-9, 800e-9, 900e-9], vec![0.2, 0.9, 0.4]).unwrap());
        let hat = Spectrum::TopHat(TopHat::new(780e-9, 830e-9, 0.8).unwrap());
        let cases = [
            Spectrum::product(vec![g(800.0, 50.0), long.clone(), Spectrum::Linear { slope: 2.0 }]),
            Spectrum::product(vec![g(800.0, 50.0), short.clone(), Spectrum::Constant(3.0)]),
            Spectrum::product(vec![g(810.0, 30.0), hat]),
            Spectrum::product(vec![g(800.0, 50.0), g(790.0, 80.0), long.clone(), short]),
            Spectrum::product(vec![g(620.0, 100.0), long]),
        ];
        for (k, s) in cases.iter().enumerate() {
            let fast = s.gaussian_piecewise_integral().unwrap();
            let slow: f64 = s.quadrature_nodes().iter().map(|n| n.weight).sum();
            assert!(
                (fast - slow).abs() <= 1e-13 * slow.abs(),
                "case {k}: {fast} vs {slow} ({:e})",
                (fast - slow) / slow
            );
            assert_eq!(s.integral(), fast, "case {k}");
        }
        // not this form: a Gaussian without a bounded factor, a lone Gaussian
        assert!(
            Spectrum::product(vec![g(800.0, 50.0), Spectrum::Constant(2.0)]).gaussian_piecewise_integral().is_none()
        );
        assert!(g(800.0, 50.0).gaussian_piecewise_integral().is_none());
    }

    fn table(w_nm: &[f64], v: &[f64]) -> Sampled {
        Sampled::new(w_nm.iter().map(|w| w / 1e9).collect(), v.to_vec()).unwrap()
    }

    /// A spectrum built twice from the same numbers finds its piecewise polynomial remembered
    /// (the same `Arc`), whose integral is the one built afresh; `same_bits` tells `0.0` from
    /// `-0.0` (which `==` does not) and a table's rows from a coarser one's, and below
    /// [`MEMO_MIN_SAMPLES`] rows nothing is remembered.
    #[test]
    fn piecewise_polynomials_are_remembered_by_their_bits() {
        let spectrum = |rows: u32, last: f64| {
            let w: Vec<f64> = (0..rows).map(|i| 600e-9 + 0.25e-9 * f64::from(i)).collect();
            let mut v: Vec<f64> = (0..rows).map(|i| 0.5 + 0.3 * (0.1 * f64::from(i)).sin()).collect();
            v[rows as usize - 1] = last;
            Spectrum::product(vec![
                Spectrum::Sampled(Sampled::new(w, v).unwrap()),
                Spectrum::Linear { slope: 1.0 },
                Spectrum::Constant(0.2),
            ])
        };
        let (a, b) = (spectrum(1601, 0.0), spectrum(1601, 0.0));
        let (pa, pb) = (a.piecewise_polynomial().unwrap(), b.piecewise_polynomial().unwrap());
        assert!(Arc::ptr_eq(&pa, &pb), "the same bits: remembered");
        let fresh = a.build_piecewise_polynomial().unwrap();
        assert_eq!(*pa, fresh);
        assert_eq!(b.integral().to_bits(), fresh.integral().to_bits());
        let negative = spectrum(1601, -0.0);
        assert!(a == negative && !a.same_bits(&negative), "0 and −0: equal, not the same bits");
        assert!(!Arc::ptr_eq(&pa, &negative.piecewise_polynomial().unwrap()));
        assert!(!a.same_bits(&spectrum(1600, 0.0)));
        let small = spectrum(MEMO_MIN_SAMPLES as u32 - 1, 0.0);
        assert!(!Arc::ptr_eq(&small.piecewise_polynomial().unwrap(), &small.piecewise_polynomial().unwrap()));
        let g = Gaussian::new(800e-9, 20e-9, 1.0).unwrap();
        assert!(Spectrum::Gaussian(g).same_bits(&Spectrum::Gaussian(g)));
        assert!(!Spectrum::Gaussian(g).same_bits(&Spectrum::Gaussian(Gaussian::new(800e-9, 21e-9, 1.0).unwrap())));
    }

    #[test]
    fn product_flattens() {
        let a = Spectrum::Constant(2.0);
        let p =
            Spectrum::product(vec![a.clone(), Spectrum::Product(vec![a.clone(), Spectrum::Product(vec![a.clone()])])]);
        assert_eq!(p, Spectrum::Product(vec![a.clone(), a.clone(), a]));
        assert_eq!(p.value(1e-6), 8.0);
        assert_eq!(p.value(0.0), 0.0);
        assert_eq!(Spectrum::Product(vec![]).value(1e-6), 1.0);
    }

    #[test]
    fn support_and_breakpoints() {
        let s = Spectrum::product(vec![
            table(&[400.0, 600.0, 900.0], &[1.0, 1.0, 1.0]).into(),
            TopHat::new(500e-9, 1000e-9, 1.0).unwrap().into(),
            Gaussian::new(800e-9, 10e-9, 1.0).unwrap().into(),
        ]);
        let (lo, hi) = s.support();
        assert_eq!((lo, hi), (500e-9, 900e-9));
        assert_eq!(s.breakpoints(), vec![500e-9, 600e-9, 900e-9]);
        assert_eq!(s.gaussians().len(), 1);
        assert_eq!(Spectrum::Constant(1.0).support(), (0.0, f64::INFINITY));
        let disjoint = Spectrum::product(vec![
            TopHat::new(1e-7, 2e-7, 1.0).unwrap().into(),
            TopHat::new(3e-7, 4e-7, 1.0).unwrap().into(),
        ]);
        assert_eq!(disjoint.support(), (3e-7, 3e-7));
        assert_eq!(disjoint.integral(), 0.0);
    }

    #[test]
    fn single_factor_integrals_are_closed_form() {
        let g = Gaussian::new(800e-9, 10e-9, 3.0).unwrap();
        assert_eq!(Spectrum::Gaussian(g).integral(), g.integral());
        assert_eq!(Spectrum::product(vec![Spectrum::Constant(2.0), g.into()]).integral(), 2.0 * g.integral());
        assert_eq!(Spectrum::Constant(2.0).integral(), f64::INFINITY);
        assert_eq!(Spectrum::Constant(0.0).integral(), 0.0);
        assert!(Spectrum::Linear { slope: 1.0 }.quadrature_nodes().is_empty());
    }

    #[test]
    fn numerical_gaussian_matches_closed_form() {
        // Gaussian × Linear(0)+... : force the numerical path with a factor of Linear-free
        // TopHat covering everything, and compare with the erfc form.
        let g = Gaussian::new(800e-9, 10e-9, 3.0).unwrap();
        let s = Spectrum::product(vec![g.into(), TopHat::new(0.0, 1e-5, 1.0).unwrap().into()]);
        assert!((s.integral() / g.integral() - 1.0).abs() < 1e-13);
    }

    #[test]
    fn a_line_is_one_wavelength_with_the_weight_of_its_band() {
        let line = Line::new(800e-9, 10e-9, 0.5).unwrap();
        let s = Spectrum::product(vec![
            Spectrum::Constant(3.0),
            line.into(),
            Spectrum::Linear { slope: 2.0 },
            table(&[700.0, 900.0], &[0.2, 0.6]).into(),
        ]);
        // 3 × (0.5 × 10 nm) × 2 × 800 nm × 0.4 (the table at 800 nm)
        let weight = 3.0 * 5e-9 * 2.0 * 800e-9 * 0.4;
        let node = s.as_line().unwrap();
        assert_eq!(node.wavelength_m, 800e-9);
        assert!((node.weight - weight).abs() < 1e-15 * weight, "{} vs {weight}", node.weight);
        assert_eq!(s.integral(), node.weight);
        assert_eq!(s.quadrature_nodes(), vec![node]);
        // the function is the equivalent band 795–805 nm
        assert_eq!(s.support(), (line.lo(), line.hi()));
        assert!((line.lo() - 795e-9).abs() < 1e-20 && (line.hi() - 805e-9).abs() < 1e-20);
        assert_eq!(s.breakpoints(), vec![line.lo(), 800e-9, line.hi()]);
        assert!((s.value(801e-9) - 3.0 * 0.5 * 2.0 * 801e-9 * 0.402).abs() < 1e-20);
        assert_eq!(s.value(806e-9), 0.0);
        // no closed form, nothing truncated, even by a Gaussian factor far narrower than the band
        assert!(s.gaussian_polynomial().is_none());
        let g = Spectrum::product(vec![line.into(), Gaussian::new(790e-9, 1e-9, 2.0).unwrap().into()]);
        assert!(g.truncations().is_empty());
        // 5e-9 × 2 exp(−50)
        let expected = 5e-9 * 2.0 * (-50f64).exp();
        assert!((g.integral() - expected).abs() < 1e-12 * expected, "{} vs {expected}", g.integral());
        // a line outside a table has no weight and no node
        let dark = Spectrum::product(vec![line.into(), table(&[810.0, 900.0], &[1.0, 1.0]).into()]);
        assert_eq!(dark.integral(), 0.0);
        assert!(dark.quadrature_nodes().is_empty());
        assert!(Spectrum::Constant(1.0).as_line().is_none());
    }

    #[test]
    fn of_two_lines_the_narrower_is_the_wavelength() {
        // a 1 nm laser line at 805 nm through a 20 nm band at 800 nm of peak 0.8: the band
        // transmits 0.8 of the line's 1 nm × 2
        let laser = Line::new(805e-9, 1e-9, 2.0).unwrap();
        let filter = Line::new(800e-9, 20e-9, 0.8).unwrap();
        for s in
            [Spectrum::product(vec![filter.into(), laser.into()]), Spectrum::product(vec![laser.into(), filter.into()])]
        {
            let node = s.as_line().unwrap();
            assert_eq!(node.wavelength_m, 805e-9);
            assert!((node.weight - 1.6e-9).abs() < 1e-24, "{}", node.weight);
        }
    }

    #[test]
    fn a_line_counts_the_photons_of_a_top_hat_of_its_width() {
        // flat source × filter × λ: ∫ λ over [c − w/2, c + w/2] = c w exactly, for any w
        for (c, w) in [(800e-9, 50e-9), (550e-9, 1e-9), (1e-6, 1.5e-6)] {
            let with = |filter: Spectrum| {
                Spectrum::product(vec![Spectrum::Constant(7.0), filter, Spectrum::Linear { slope: 1.0 }]).integral()
            };
            let line = with(Line::new(c, w, 0.9).unwrap().into());
            let band = with(TopHat::new(c - 0.5 * w, c + 0.5 * w, 0.9).unwrap().into());
            // (the top-hat's Gauss–Legendre nodes carry rounding of their positions, ~1e-13)
            assert!((line - band).abs() < 1e-12 * band, "{line} vs {band}");
        }
    }

    #[test]
    fn truncation_reported_only_when_non_negligible() {
        let wide = Spectrum::Gaussian(Gaussian::new(10e-9, 20e-9, 1.0).unwrap());
        let t = wide.truncations();
        assert_eq!(t.len(), 1);
        assert!((t[0].fraction - 0.308_537_538_725_986_9).abs() < 1e-15);
        let narrow = Spectrum::Gaussian(Gaussian::new(800e-9, 10e-9, 1.0).unwrap());
        assert!(narrow.truncations().is_empty());
        // Cut by a table covering only center ± 1σ: 2 × Φ(−1) = 0.31731050786291415 lost.
        let cut = Spectrum::product(vec![narrow.clone(), table(&[790.0, 810.0], &[1.0, 1.0]).into()]);
        let t = cut.truncations();
        assert_eq!(t.len(), 1);
        assert!((t[0].fraction - 0.317_310_507_862_914_15).abs() < 1e-12);
        assert_eq!(t[0].support_m, (790e-9, 810e-9));
    }
}
