//! Radially symmetric pupils given as data, and their OTF by the autocorrelation integral.
//!
//! A designer's lens (a phase profile, a meta-atom library's order, Zernike terms of `m = 0`)
//! has a pupil field `P(ρ) = A(ρ) exp(i 2π W(ρ)/λ)` that depends on the normalized pupil radius
//! `ρ` alone (docs/physics.md, "Designs given as data"). Its OTF is radially symmetric and real,
//! the autocorrelation of `P` normalized by its power:
//!
//! ```text
//! OTF(s) = 2 Re ∫_{x>0} P(p + d/2) P*(p − d/2) dA / ∫|P|² dA,   d = 2s (pupil radii)
//! ```
//!
//! With `u = x + d/2 = cos t` and `y = v sin t` (`dA = sin²t dt dv`) the half overlap is the
//! rectangle `t ∈ [0, acos s]`, `v ∈ [0, 1]` (times 2 for `v < 0`), and the integrand is smooth
//! wherever `A` and `W` are: with `q = ρ²`, `q₁ = cos²t + v² sin²t` and
//! `q₂ = q₁ − 4s(cos t − s)`,
//!
//! ```text
//! OTF(s) = 4/N ∫_0^{acos s} sin²t ∫_0^1 A(q₁) A(q₂) cos(k[W(q₁) − W(q₂)]) dv dt,
//! N = ∫|P|² dA / 1 = π ∫_0^1 A(q)² dq,   k = 2π/λ.
//! ```
//!
//! For `A = 1` and `W = W020 q` the inner integral is `cos(a(cos t − s))` with `a = 8π w s`,
//! `w = W020/λ`: the 1-D integral of [`crate::defocus_otf`]. The rule is a tensor product of
//! Gauss–Legendre panels whose count follows the phase the integrand can turn through and the
//! accuracy asked (module [`crate::quad`]: a 16-point panel turning through `θ` radians errs by
//! about `(θ/2)^32/32!`). The phase bounds come from the wavefront sampled when the order is
//! prepared: along t `k (4s(1 − s) max|W′| + osc_δ(W′) acos s)`, across v `k osc_δ(W′)`, with
//! `osc_δ(W′)` the largest change of `W′(q)` over a window of the shift's width `δ = 4s(1 − s)`.
//!
//! Wavefront sign: as [`crate::Wavefront`] (docs/physics.md, "Sign of the wavefront"). A radial
//! pupil's OPD is `W020 q + (Σ c_k f_k(q) − q Σ c_k b_k)`: the order's defocus `W020` plus the
//! profile's terms with their best-fit defocus `b_k` removed ([`RadialPupil::fitted_defocus_m`],
//! the least-squares slope in `q` over the pupil), so that the order's `W020` is what sizes the
//! spectral panels and the Fraunhofer check; [`crate::Order::radial`] adds the fit to the order's
//! defocus.

use std::sync::{Arc, OnceLock};

use crate::Error;
use crate::fft::noll_to_nm;

/// Samples in `q = ρ²` of a profile's derivative bounds (the rule's phase estimates).
const BOUND_SAMPLES: usize = 256;

/// How a [`RadialProfile`] is given.
#[derive(Clone, Debug, PartialEq)]
enum Kind {
    /// `Σ_i c_i q^i`, `q = ρ²` (ascending powers).
    Even(Vec<f64>),
    /// `√(R² q + z²) − z`: the sag of the exact reference sphere of radius `z` over a pupil of
    /// radius `R` (metres when `R`, `z` are).
    Sphere { r2: f64, z: f64 },
    /// `R²q/√(R²q + z²)`: the sphere's change `R ∂S/∂R` with the aperture radius `R`, `z` held
    /// ([`RadialProfile::radius_log_derivative`] of a [`Kind::Sphere`]).
    SphereSlope { r2: f64, z: f64 },
    /// `ρ s'(ρ)` of a cubic spline `s` ([`RadialProfile::radius_log_derivative`] of a
    /// [`Kind::Table`]): its change `R ∂/∂R` where it is given in `r = Rρ`.
    TableSlope(Spline),
    /// A cubic spline through `(ρ_i, value_i)`, zero slope at `ρ = 0`.
    Table(Spline),
    /// A lens-plane profile read in direction cosines ([`DirectionCosines`]): at `q` (the
    /// squared direction cosine over its largest, `E = e_max²`) the profile `inner` (1 where
    /// none) at the lens-plane `q_r = q (1 − E)/(1 − qE)`, divided by `c² = 1 − qE` where
    /// `obliquity` (the flat lens's amplitude factor).
    Mapped { inner: Option<Arc<RadialProfile>>, e2: f64, obliquity: bool },
}

/// A function of the normalized pupil radius `ρ ∈ [0, 1]`: a wavefront term (metres, or radians
/// of phase scaled by the caller) or a field amplitude. Immutable; build once, share in an `Arc`.
#[derive(Clone, Debug, PartialEq)]
pub struct RadialProfile {
    kind: Kind,
    /// its fitted slope, derivative bounds and mean square, made when first asked: a profile
    /// that only serves as a derivative's direction (`RadialOrder::otf_and_derivatives`, K of
    /// them at every wavelength) never needs them
    summary: Lazy<Summary>,
    /// the values at the bound samples and the Chebyshev series, made when first asked
    /// ([`RadialProfile::sampled`]): a lens's profiles are shared by every wavelength's pupil
    sampled: Lazy<Sampled>,
}

/// Something derived from a profile's kind (its [`Summary`], its [`Sampled`] values), made once
/// when first asked; not part of the profile's value: two profiles are equal whether or not
/// either has made it.
#[derive(Clone, Debug)]
struct Lazy<T>(OnceLock<T>);

impl<T> Default for Lazy<T> {
    fn default() -> Self {
        Lazy(OnceLock::new())
    }
}

impl<T> PartialEq for Lazy<T> {
    fn eq(&self, _: &Lazy<T>) -> bool {
        true
    }
}

/// What the rule reads of a profile besides its values.
#[derive(Clone, Copy, Debug)]
struct Summary {
    /// least-squares slope in `q` over `[0, 1]` (the best-fit defocus per unit of the profile)
    fit: f64,
    /// `max |f'(q)|`, `max |f''(q)|` on `[0, 1]`, sampled
    bounds: (f64, f64),
    /// `∫_0^1 f(q)² dq` (the power of an amplitude profile)
    mean_square: f64,
}

/// A profile at the [`BOUND_SAMPLES`] + 1 points `q = i/BOUND_SAMPLES` and as a Chebyshev series
/// in `x = 2q − 1` with the largest error of the series on `[0, 1]` (`None` where one of degree
/// at most [`PROXY_MAX_DEGREE`] does not hold it to the rounding of its values: a table).
#[derive(Clone, Debug, PartialEq)]
struct Sampled {
    values: Vec<f64>,
    series: Option<(Vec<f64>, f64)>,
}

impl RadialProfile {
    /// `Σ_i c_i ρ^{2i}` (`coefficients[i]` multiplies `ρ^{2i}`): a Zemax Binary 2 surface's phase
    /// `M Σ A_i ρ^{2i}` with `coefficients = [0, M A_1, M A_2, …]`. Every coefficient finite.
    pub fn even_polynomial(coefficients: Vec<f64>) -> Result<RadialProfile, Error> {
        for &c in &coefficients {
            if !c.is_finite() {
                return Err(Error::InvalidParameter {
                    name: "radial polynomial coefficient",
                    value: c,
                    expected: "finite",
                });
            }
        }
        Ok(RadialProfile::finish(Kind::Even(coefficients)))
    }

    /// The sag `√(R² ρ² + z²) − z` of a sphere of radius `z` centred on the axis at `z` behind a
    /// pupil of radius `R` (both metres, finite, > 0): the path from the pupil point at `ρ` to
    /// the axial point at `z`, less `z`. The wavefront of a lens against the exact reference
    /// sphere centred on the detector at `z` adds it to `(λ/2π) φ(ρ)` (docs/physics.md).
    pub fn reference_sphere(aperture_radius_m: f64, distance_m: f64) -> Result<RadialProfile, Error> {
        for (name, v) in [("aperture radius", aperture_radius_m), ("detector distance", distance_m)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidParameter { name, value: v, expected: "finite and > 0 m" });
            }
        }
        Ok(RadialProfile::finish(Kind::Sphere { r2: aperture_radius_m * aperture_radius_m, z: distance_m }))
    }

    /// A table `values[i]` at normalized radii `rho[i]` (at least 4, finite, strictly
    /// increasing, the first `0`, the last `≥ 1`), read through a cubic spline with zero slope
    /// at the axis (a radially symmetric function is even in `ρ`) and zero curvature at its
    /// last sample.
    pub fn table(rho: Vec<f64>, values: Vec<f64>) -> Result<RadialProfile, Error> {
        Ok(RadialProfile::finish(Kind::Table(Spline::new(rho, values)?)))
    }

    /// The profile's change `R ∂/∂R` with the aperture radius `R` where it is given in the
    /// lens-plane radius `r = Rρ` and read at `ρ` (docs/physics.md, "Gradients": the F-number
    /// and focal length of a phase lens): `f(Rρ)` moves along `ρ ∂f/∂ρ = 2q ∂f/∂q`. An even
    /// polynomial `Σ c_i q^i` gives `Σ 2i c_i q^i`; the sphere `√(R²q + z²) − z` (its distance
    /// `z` held) gives `R²q/√(R²q + z²)`; a table's spline `s` gives `ρ s'(ρ)`, the derivative of
    /// the same cubic pieces. `None` for a profile read through a map ([`DirectionCosines`]),
    /// whose map moves with the aperture too.
    pub fn radius_log_derivative(&self) -> Option<RadialProfile> {
        let kind = match &self.kind {
            Kind::Even(c) => Kind::Even(c.iter().enumerate().map(|(i, c)| 2.0 * i as f64 * c).collect()),
            Kind::Sphere { r2, z } => Kind::SphereSlope { r2: *r2, z: *z },
            Kind::Table(s) => Kind::TableSlope(s.clone()),
            Kind::SphereSlope { .. } | Kind::TableSlope(_) | Kind::Mapped { .. } => return None,
        };
        Some(RadialProfile::finish(kind))
    }

    /// The profile times `factor` (finite), where that is a profile of the same kind: an even
    /// polynomial, a table or a table's slope (each linear in its values); `None` for a sphere
    /// or a mapped profile.
    pub fn scaled(&self, factor: f64) -> Option<RadialProfile> {
        let spline = |s: &Spline| Spline {
            x: s.x.clone(),
            y: s.y.iter().map(|y| factor * y).collect(),
            m: s.m.iter().map(|m| factor * m).collect(),
            per_radius: s.per_radius,
        };
        let kind = match &self.kind {
            Kind::Even(c) => Kind::Even(c.iter().map(|c| factor * c).collect()),
            Kind::Table(s) => Kind::Table(spline(s)),
            Kind::TableSlope(s) => Kind::TableSlope(spline(s)),
            _ => return None,
        };
        factor.is_finite().then(|| RadialProfile::finish(kind))
    }

    fn finish(kind: Kind) -> RadialProfile {
        RadialProfile { kind, summary: Lazy::default(), sampled: Lazy::default() }
    }

    /// The fitted slope, derivative bounds and mean square, computed once.
    fn summary(&self) -> &Summary {
        self.summary.0.get_or_init(|| {
            // least-squares slope 12 ∫(q − ½) f dq and the mean square, by 8 panels of 16 points
            let (mut slope, mut square) = (0.0, 0.0);
            crate::quad::for_each_node(0.0, 1.0, 8, |q, w| {
                let f = self.value(q);
                slope += w * 12.0 * (q - 0.5) * f;
                square += w * f * f;
            });
            Summary { fit: slope, mean_square: square, bounds: derivative_bounds(|q| self.value(q)) }
        })
    }

    /// The value at `q = ρ²` (`q ∈ [0, 1]`; the table's last piece continues beyond).
    #[inline]
    pub fn value(&self, q: f64) -> f64 {
        match &self.kind {
            Kind::Even(c) => c.iter().rev().fold(0.0, |acc, &ci| acc * q + ci),
            // written without the cancellation of √(z² + R²q) − z at small q
            Kind::Sphere { r2, z } => r2 * q / ((z * z + r2 * q).sqrt() + z),
            Kind::SphereSlope { r2, z } => r2 * q / (z * z + r2 * q).sqrt(),
            Kind::Table(s) => s.value(q.max(0.0).sqrt()),
            Kind::TableSlope(s) => {
                let rho = q.max(0.0).sqrt();
                rho * s.slope(rho)
            }
            Kind::Mapped { inner, e2, obliquity } => {
                let c2 = 1.0 - q * e2;
                let v = inner.as_ref().map_or(1.0, |p| p.value(q * (1.0 - e2) / c2));
                if *obliquity { v / c2 } else { v }
            }
        }
    }

    /// Whether [`value8`](Self::value8) reads the profile (every kind but a table, and a table
    /// read through the map).
    fn vectorizes(&self) -> bool {
        match &self.kind {
            Kind::Table(_) | Kind::TableSlope(_) => false,
            Kind::Mapped { inner, .. } => inner.as_ref().is_none_or(|p| p.vectorizes()),
            _ => true,
        }
    }

    /// [`value`](Self::value) at eight points at once (`wide::f64x8`), by the same operations
    /// in the same order on each lane, so each lane is the scalar value to the last bit; a
    /// table (see [`vectorizes`](Self::vectorizes)) lane by lane.
    #[inline]
    fn value8(&self, q: wide::f64x8) -> wide::f64x8 {
        use wide::f64x8;
        match &self.kind {
            Kind::Even(c) => c.iter().rev().fold(f64x8::ZERO, |acc, &ci| acc * q + f64x8::splat(ci)),
            Kind::Sphere { r2, z } => {
                let (r2, z) = (f64x8::splat(*r2), f64x8::splat(*z));
                r2 * q / ((z * z + r2 * q).sqrt() + z)
            }
            Kind::SphereSlope { r2, z } => {
                let (r2, z) = (f64x8::splat(*r2), f64x8::splat(*z));
                r2 * q / (z * z + r2 * q).sqrt()
            }
            Kind::Table(_) | Kind::TableSlope(_) => f64x8::new(q.to_array().map(|qi| self.value(qi))),
            Kind::Mapped { inner, e2, obliquity } => {
                let e2 = f64x8::splat(*e2);
                let c2 = f64x8::ONE - q * e2;
                let v = inner.as_ref().map_or(f64x8::ONE, |p| p.value8(q * (f64x8::ONE - e2) / c2));
                if *obliquity { v / c2 } else { v }
            }
        }
    }

    /// `value(q₁) value(q₂)` on eight lanes ([`value8`](Self::value8)); in direction cosines
    /// (`c² = 1 − qE`) with one division a lane, not four: `r = 1/(c₁² c₂²)`, the lens-plane
    /// `q_r = q (1 − E)/c²` of each point as `q (1 − E) c̄² r` with `c̄²` the other point's (a few
    /// units in the last place from the scalar reading).
    #[inline]
    fn product8(&self, q1: wide::f64x8, q2: wide::f64x8) -> wide::f64x8 {
        use wide::f64x8;
        match &self.kind {
            Kind::Mapped { inner, e2, obliquity: true } => {
                let e2 = f64x8::splat(*e2);
                let (c1, c2) = (f64x8::ONE - q1 * e2, f64x8::ONE - q2 * e2);
                let r = f64x8::ONE / (c1 * c2);
                match inner {
                    None => r,
                    Some(p) => {
                        let scale = (f64x8::ONE - e2) * r;
                        p.value8(q1 * c2 * scale) * p.value8(q2 * c1 * scale) * r
                    }
                }
            }
            _ => self.value8(q1) * self.value8(q2),
        }
    }

    /// The profile at the bound samples and as a Chebyshev series ([`Sampled`]), computed once.
    fn sampled(&self) -> &Sampled {
        self.sampled.0.get_or_init(|| {
            let h = 1.0 / BOUND_SAMPLES as f64;
            let values: Vec<f64> = (0..=BOUND_SAMPLES).map(|i| self.value(i as f64 * h)).collect();
            let size = values.iter().fold(0.0_f64, |acc, v| acc.max(v.abs()));
            // to the rounding of the values (a few units in the last place of the largest)
            let series = fit_series(&|q| self.value(q), 8.0 * f64::EPSILON * size);
            Sampled { values, series }
        })
    }

    /// The least-squares slope of the profile in `q = ρ²` over the pupil (uniform in area):
    /// its best-fit defocus per unit.
    pub fn fitted_slope(&self) -> f64 {
        self.summary().fit
    }

    /// `∫_0^1 f(q)² dq`: the power of an amplitude profile over the pupil, relative to a
    /// uniform amplitude of 1.
    pub fn mean_square(&self) -> f64 {
        self.summary().mean_square
    }

    /// Whether the profile is a table (knots limit the smoothness the rule may assume).
    fn knots(&self) -> usize {
        match &self.kind {
            Kind::Table(s) | Kind::TableSlope(s) => s.x.len(),
            Kind::Mapped { inner: Some(p), .. } => p.knots(),
            _ => 0,
        }
    }
}

impl RadialPupil {
    /// The knots `0 < ρ_i < 1` of the pupil's tables (its wavefront terms and amplitude), in
    /// this pupil's radius, ascending and distinct: where the integrand's third derivative jumps
    /// ([`TableRule`]); empty for analytic profiles.
    pub fn table_knots(&self) -> Vec<f64> {
        let mut knots: Vec<f64> = self
            .terms
            .iter()
            .filter(|(c, _)| *c != 0.0)
            .map(|(_, p)| p)
            .chain(self.amplitude.as_ref())
            .flat_map(|p| p.knot_radii())
            .filter(|&r| r > 0.0 && r < 1.0)
            .collect();
        knots.sort_by(f64::total_cmp);
        knots.dedup();
        knots
    }
}

impl RadialProfile {
    /// The radii `ρ` where the profile's third derivative may jump: a table's knots (read through
    /// the map of [`DirectionCosines`] at `q = q_r/(1 − E + q_r E)`); none for an analytic kind.
    fn knot_radii(&self) -> Vec<f64> {
        match &self.kind {
            Kind::Table(s) | Kind::TableSlope(s) => s.x.clone(),
            Kind::Mapped { inner: Some(p), e2, .. } => {
                p.knot_radii().into_iter().map(|r| (r * r / (1.0 - e2 + r * r * e2)).sqrt()).collect()
            }
            _ => Vec::new(),
        }
    }
}

/// `(max |f'|, max |f''|)` of `f` on `[0, 1]` from differences at [`BOUND_SAMPLES`] + 1 points,
/// with a margin of 25 % for what falls between them.
fn derivative_bounds(f: impl Fn(f64) -> f64) -> (f64, f64) {
    let h = 1.0 / BOUND_SAMPLES as f64;
    let values: Vec<f64> = (0..=BOUND_SAMPLES).map(|i| f(i as f64 * h)).collect();
    bounds_of_samples(&values)
}

/// [`derivative_bounds`] from the values at the [`BOUND_SAMPLES`] + 1 points `q = i/BOUND_SAMPLES`.
fn bounds_of_samples(values: &[f64]) -> (f64, f64) {
    let h = 1.0 / BOUND_SAMPLES as f64;
    let d1 = values.windows(2).map(|w| ((w[1] - w[0]) / h).abs()).fold(0.0, f64::max);
    let d2 = values.windows(3).map(|w| ((w[2] - 2.0 * w[1] + w[0]) / (h * h)).abs()).fold(0.0, f64::max);
    (1.25 * d1, 1.25 * d2)
}

/// A cubic spline with zero slope at its first knot (the axis) and zero curvature at its last.
#[derive(Clone, Debug, PartialEq)]
struct Spline {
    x: Vec<f64>,
    y: Vec<f64>,
    /// second derivatives at the knots
    m: Vec<f64>,
    /// `(n − 1)/x_{n−1}`: the piece a radius falls in, were the knots evenly spaced
    /// ([`piece`](Spline::piece)'s guess)
    per_radius: f64,
}

impl Spline {
    fn new(x: Vec<f64>, y: Vec<f64>) -> Result<Spline, Error> {
        if x.len() != y.len() {
            return Err(Error::InvalidParameter {
                name: "radial table length",
                value: y.len() as f64,
                expected: "one value per radius",
            });
        }
        if x.len() < 4 {
            return Err(Error::InvalidParameter {
                name: "radial table samples",
                value: x.len() as f64,
                expected: "at least 4 samples from the axis to the rim",
            });
        }
        if x[0] != 0.0 {
            return Err(Error::InvalidParameter {
                name: "radial table first radius",
                value: x[0],
                expected: "0 (the table starts on the axis)",
            });
        }
        for (i, (&xi, &yi)) in x.iter().zip(&y).enumerate() {
            if !xi.is_finite() || (i > 0 && xi <= x[i - 1]) {
                return Err(Error::InvalidParameter {
                    name: "radial table radius",
                    value: xi,
                    expected: "finite and strictly increasing",
                });
            }
            if !yi.is_finite() {
                return Err(Error::InvalidParameter { name: "radial table value", value: yi, expected: "finite" });
            }
        }
        let last = x[x.len() - 1];
        if last < 1.0 - 1e-9 {
            return Err(Error::InvalidParameter {
                name: "radial table last radius",
                value: last,
                expected: "≥ 1 (the table must reach the rim of the aperture)",
            });
        }
        // the tridiagonal system of the second derivatives: clamped (slope 0) at x0, natural at xn
        let n = x.len();
        let mut a = vec![0.0; n];
        let mut b = vec![0.0; n];
        let mut c = vec![0.0; n];
        let mut r = vec![0.0; n];
        let h0 = x[1] - x[0];
        b[0] = h0 / 3.0;
        c[0] = h0 / 6.0;
        r[0] = (y[1] - y[0]) / h0;
        for i in 1..n - 1 {
            let (hl, hr) = (x[i] - x[i - 1], x[i + 1] - x[i]);
            a[i] = hl / 6.0;
            b[i] = (hl + hr) / 3.0;
            c[i] = hr / 6.0;
            r[i] = (y[i + 1] - y[i]) / hr - (y[i] - y[i - 1]) / hl;
        }
        b[n - 1] = 1.0;
        // Thomas algorithm (diagonally dominant)
        for i in 1..n {
            let w = a[i] / b[i - 1];
            b[i] -= w * c[i - 1];
            r[i] -= w * r[i - 1];
        }
        let mut m = vec![0.0; n];
        m[n - 1] = r[n - 1] / b[n - 1];
        for i in (0..n - 1).rev() {
            m[i] = (r[i] - c[i] * m[i + 1]) / b[i];
        }
        let per_radius = (n - 1) as f64 / x[n - 1];
        Ok(Spline { x, y, m, per_radius })
    }

    /// The piece `i` that [`value`](Self::value) and [`slope`](Self::slope) read at `t`:
    /// `x_i ≤ t < x_{i+1}`, the first piece continued below the axis and the last beyond the
    /// rim (`partition_point` of the knots `≤ t`, clamped). Evenly spaced knots (a
    /// `phase_spline_rad`, most tables) put `t` in the piece `⌊t (n − 1)/x_{n−1}⌋`, which is
    /// checked against its ends and taken; otherwise the binary search, so the piece is the
    /// search's in every case.
    #[inline]
    fn piece(&self, t: f64) -> usize {
        let n = self.x.len();
        let last = n - 2;
        let guess = t * self.per_radius;
        // `guess < n − 1` fails for NaN as `partition_point`'s comparisons do
        if guess >= 0.0 && guess < (last + 1) as f64 {
            let i = (guess as usize).min(last);
            if self.x[i] <= t && (i == last || t < self.x[i + 1]) {
                return i;
            }
        }
        self.x.partition_point(|&xi| xi <= t).clamp(1, n - 1) - 1
    }

    fn value(&self, t: f64) -> f64 {
        let i = self.piece(t);
        let h = self.x[i + 1] - self.x[i];
        let (a, b) = ((self.x[i + 1] - t) / h, (t - self.x[i]) / h);
        a * self.y[i]
            + b * self.y[i + 1]
            + ((a * a * a - a) * self.m[i] + (b * b * b - b) * self.m[i + 1]) * h * h / 6.0
    }

    /// `s'(t)`: the derivative of the piece [`value`](Self::value) reads at `t`.
    fn slope(&self, t: f64) -> f64 {
        let i = self.piece(t);
        let h = self.x[i + 1] - self.x[i];
        let (a, b) = ((self.x[i + 1] - t) / h, (t - self.x[i]) / h);
        (self.y[i + 1] - self.y[i]) / h
            + ((1.0 - 3.0 * a * a) * self.m[i] + (3.0 * b * b - 1.0) * self.m[i + 1]) * h / 6.0
    }
}

/// A radially symmetric pupil given as data (module docs): the field amplitude `A(ρ)` and the
/// wavefront terms beyond the order's defocus, and Zernike terms (Noll order, metres RMS; a
/// term with `m ≠ 0` breaks the symmetry and sends the order to the FFT path).
///
/// The OPD at `q = ρ²` is `W020 q + Σ c_k (f_k(q) − b_k q) + Σ_j z_j (Z_j − b_j q)` with `W020`
/// the order's [`defocus_m`](crate::Wavefront::defocus_m) and `b` the best-fit slopes: the
/// profile's own defocus is carried by the order ([`fitted_defocus_m`](Self::fitted_defocus_m)).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RadialPupil {
    oblique: Option<Oblique>,
    /// `Some(k)` for a pupil in direction cosines ([`DirectionCosines`]): the paraxial
    /// normalized frequency `s = ν λ F#` is `s/k` of this pupil's, `k = √(1 + NA0²)`
    frequency_scale: Option<f64>,
    amplitude: Option<Arc<RadialProfile>>,
    terms: Vec<(f64, Arc<RadialProfile>)>,
    zernike_noll_m: Vec<(usize, f64)>,
    /// the `m = 0` Zernike terms as one even polynomial in `q`
    zernike_even: Vec<f64>,
    fit: f64,
}

impl RadialPupil {
    /// A pupil of field amplitude `amplitude` (`None`: uniform; the order's efficiency carries
    /// the power, the profile only its shape) and OPD `Σ coefficient × profile` (metres per unit
    /// of each profile), plus Zernike terms `(Noll index, metres RMS)`. Coefficients finite,
    /// Noll indices in `1..=`[`crate::fft::MAX_NOLL_INDEX`], the amplitude not zero everywhere.
    pub fn new(
        amplitude: Option<Arc<RadialProfile>>,
        terms: Vec<(f64, Arc<RadialProfile>)>,
        zernike_noll_m: Vec<(usize, f64)>,
    ) -> Result<RadialPupil, Error> {
        for &(c, _) in &terms {
            if !c.is_finite() {
                return Err(Error::InvalidParameter { name: "wavefront coefficient", value: c, expected: "finite" });
            }
        }
        let check = crate::fft::Aberrations { zernike_noll_m: zernike_noll_m.clone(), ..Default::default() };
        check.validate()?;
        if let Some(a) = &amplitude
            && a.mean_square().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        {
            return Err(Error::InvalidParameter {
                name: "pupil amplitude power",
                value: a.mean_square(),
                expected: "> 0 (some light through the pupil)",
            });
        }
        let mut zernike_even: Vec<f64> = Vec::new();
        for &(j, c) in &zernike_noll_m {
            let (n, m) = noll_to_nm(j);
            if m != 0 || c == 0.0 {
                continue;
            }
            let poly = zernike_radial_q(n);
            if zernike_even.len() < poly.len() {
                zernike_even.resize(poly.len(), 0.0);
            }
            for (acc, p) in zernike_even.iter_mut().zip(poly) {
                *acc += c * p;
            }
        }
        let mut pupil = RadialPupil {
            oblique: None,
            frequency_scale: None,
            amplitude,
            terms,
            zernike_noll_m,
            zernike_even,
            fit: 0.0,
        };
        let even_fit = if pupil.zernike_even.is_empty() {
            0.0
        } else {
            RadialProfile::even_polynomial(pupil.zernike_even.clone())?.fitted_slope()
        };
        pupil.fit = pupil.terms.iter().map(|(c, p)| c * p.fitted_slope()).sum::<f64>() + even_fit;
        Ok(pupil)
    }

    /// The best-fit defocus of this pupil's wavefront terms (m at the rim, the least-squares
    /// slope in `ρ²`), which the order carries in its `defocus_m` and the pupil leaves out.
    pub fn fitted_defocus_m(&self) -> f64 {
        self.fit
    }

    /// Whether the pupil is radially symmetric (every Zernike term has `m = 0`, no oblique
    /// incidence).
    pub fn is_symmetric(&self) -> bool {
        self.oblique.is_none() && self.zernike_noll_m.iter().all(|&(j, c)| c == 0.0 || noll_to_nm(j).1 == 0)
    }

    /// This pupil seen from a field point off axis ([`Oblique`]): its OPD gains the difference
    /// between the oblique wave's path to the chief ray's image point and the on-axis path to
    /// the axial point, which holds the field's coma, astigmatism and field curvature. The pupil
    /// is then not symmetric (the FFT path).
    pub fn with_oblique(mut self, oblique: Oblique) -> RadialPupil {
        self.oblique = Some(oblique);
        self
    }

    /// The factor `k` from the paraxial normalized frequency `s = ν λ F#` to this pupil's own
    /// (1 for a pupil on the lens plane; `√(1 + NA0²)` in direction cosines,
    /// [`DirectionCosines`]): the OTF at `s` is the autocorrelation at `k s`, zero from `s ≥ 1/k`.
    pub fn frequency_scale(&self) -> f64 {
        self.frequency_scale.unwrap_or(1.0)
    }

    /// The off-axis part of the OPD (m) at normalized pupil coordinates `(x, y)` (0 on axis).
    pub fn oblique_opd_m(&self, x: f64, y: f64) -> f64 {
        self.oblique.map_or(0.0, |o| o.opd_m(x, y))
    }

    /// The oblique incidence of a pupil seen off axis ([`with_oblique`](Self::with_oblique)),
    /// `None` on axis.
    pub fn oblique(&self) -> Option<&Oblique> {
        self.oblique.as_ref()
    }

    /// Whether the pupil's field is the uniform full circle with Zernike terms alone (no
    /// amplitude profile, no profile terms, no oblique incidence, on the lens plane): its
    /// wavefront is then a polynomial in the pupil coordinates, which the overlap engine takes.
    pub fn is_zernike_only(&self) -> bool {
        self.amplitude.is_none() && self.terms.is_empty() && self.oblique.is_none() && self.frequency_scale.is_none()
    }

    /// The Zernike terms `(Noll index, metres RMS)`.
    pub fn zernike_noll_m(&self) -> &[(usize, f64)] {
        &self.zernike_noll_m
    }

    /// The Zernike terms with `m ≠ 0` (those the radial engine cannot take).
    pub fn asymmetric_zernike(&self) -> Vec<(usize, f64)> {
        self.zernike_noll_m.iter().copied().filter(|&(j, c)| c != 0.0 && noll_to_nm(j).1 != 0).collect()
    }

    /// The OPD (m) at `q = ρ²` beyond the order's defocus: `Σ c_k (f_k(q) − b_k q)` plus the
    /// `m = 0` Zernike terms less their fit (the `m ≠ 0` terms are not included).
    #[inline]
    pub fn opd_beyond_defocus_m(&self, q: f64) -> f64 {
        let mut w = -self.fit * q;
        for (c, p) in &self.terms {
            w += c * p.value(q);
        }
        if !self.zernike_even.is_empty() {
            w += self.zernike_even.iter().rev().fold(0.0, |acc, &ci| acc * q + ci);
        }
        w
    }

    /// The OPD terms `(c_k, f_k)` of [`new`](Self::new) (metres per unit of each profile).
    pub(crate) fn terms(&self) -> &[(f64, Arc<RadialProfile>)] {
        &self.terms
    }

    /// [`opd_beyond_defocus_m`](Self::opd_beyond_defocus_m) at `q` with each term's profile
    /// value `f_k(q)` given by `value(k)` (samples of the profiles, which do not depend on the
    /// wavelength where the coefficients do): the same operations in the same order, so the
    /// same bits where `value(k)` is `f_k(q)`.
    #[inline]
    pub(crate) fn opd_beyond_defocus_from(&self, q: f64, value: impl Fn(usize) -> f64) -> f64 {
        let mut w = -self.fit * q;
        for (k, (c, _)) in self.terms.iter().enumerate() {
            w += c * value(k);
        }
        if !self.zernike_even.is_empty() {
            w += self.zernike_even.iter().rev().fold(0.0, |acc, &ci| acc * q + ci);
        }
        w
    }

    /// The OPD beyond the order's defocus ([`opd_beyond_defocus_m`](Self::opd_beyond_defocus_m))
    /// from its terms' cached samples and series ([`RadialProfile::sampled`]), a sum with the
    /// pupil's own coefficients, so that a wavelength's pupil costs no profile evaluation:
    /// `None` where a term has no series (a table).
    fn residual(&self) -> Option<Residual> {
        let h = 1.0 / BOUND_SAMPLES as f64;
        let q = |i: usize| i as f64 * h;
        let mut samples: Vec<f64> = (0..=BOUND_SAMPLES).map(|i| -self.fit * q(i)).collect();
        let mut magnitude: Vec<f64> = (0..=16).map(|j| (self.fit * q(16 * j)).abs()).collect();
        // −fit q = −fit (½ + ½ T₁(2q − 1))
        let mut series = vec![-0.5 * self.fit, -0.5 * self.fit];
        let mut error = 0.0;
        let add = |series: &mut Vec<f64>, c: f64, terms: &[f64]| {
            if series.len() < terms.len() {
                series.resize(terms.len(), 0.0);
            }
            for (acc, t) in series.iter_mut().zip(terms) {
                *acc += c * t;
            }
        };
        for (c, p) in &self.terms {
            let sampled = p.sampled();
            let (terms, e) = sampled.series.as_ref()?;
            for (s, v) in samples.iter_mut().zip(&sampled.values) {
                *s += c * v;
            }
            for (j, m) in magnitude.iter_mut().enumerate() {
                *m += (c * sampled.values[16 * j]).abs();
            }
            add(&mut series, *c, terms);
            error += c.abs() * e;
        }
        if !self.zernike_even.is_empty() {
            let z = |q: f64| self.zernike_even.iter().rev().fold(0.0, |acc, &ci| acc * q + ci);
            for (i, s) in samples.iter_mut().enumerate() {
                *s += z(q(i));
            }
            for (j, m) in magnitude.iter_mut().enumerate() {
                *m += z(q(16 * j)).abs();
            }
            // a polynomial of degree d is its interpolant on d + 1 points or more: exact
            let terms = chebyshev_fit(&z, (self.zernike_even.len() - 1).max(2));
            error += 4.0 * f64::EPSILON * terms.iter().map(|t| t.abs()).sum::<f64>();
            add(&mut series, 1.0, &terms);
        }
        Some(Residual { samples, series, error, magnitude })
    }

    /// `|fit q| + Σ |c p(q)| + |Zernike terms|` (m): the size of the terms
    /// [`opd_beyond_defocus_m`](Self::opd_beyond_defocus_m) adds, which sets its rounding (a
    /// geometric-phase lens's phase and reference sphere cancel to a few percent of either).
    pub fn opd_magnitude_m(&self, q: f64) -> f64 {
        let mut w = (self.fit * q).abs();
        for (c, p) in &self.terms {
            w += (c * p.value(q)).abs();
        }
        if !self.zernike_even.is_empty() {
            w += self.zernike_even.iter().rev().fold(0.0, |acc, &ci| acc * q + ci).abs();
        }
        w
    }

    /// The field amplitude at `q = ρ²` (1 where none is given).
    #[inline]
    pub fn amplitude(&self, q: f64) -> f64 {
        self.amplitude.as_ref().map_or(1.0, |a| a.value(q))
    }

    /// The field amplitude's profile in `q = ρ²`, where one is given (`None`: uniform).
    pub fn amplitude_profile(&self) -> Option<&Arc<RadialProfile>> {
        self.amplitude.as_ref()
    }

    /// `∫|P|² dA / π`: the pupil's power relative to a uniform amplitude of 1.
    pub fn power(&self) -> f64 {
        self.amplitude.as_ref().map_or(1.0, |a| a.mean_square())
    }

    /// This pupil with `zernike_noll_m` added to its Zernike terms.
    pub fn with_zernike(&self, zernike_noll_m: &[(usize, f64)]) -> Result<RadialPupil, Error> {
        if self.frequency_scale.is_some() {
            return Err(Error::InvalidParameter {
                name: "Zernike terms on a pupil in direction cosines",
                value: zernike_noll_m.len() as f64,
                expected: "Zernike terms added on the lens plane, before the pupil is mapped",
            });
        }
        let mut all = self.zernike_noll_m.clone();
        all.extend_from_slice(zernike_noll_m);
        RadialPupil::new(self.amplitude.clone(), self.terms.clone(), all)
    }
}

/// A pupil's OPD beyond its order's defocus, m ([`RadialPupil::residual`]): at the bound samples
/// `q = i/BOUND_SAMPLES`, as a Chebyshev series in `2q − 1` with its largest error, and the size
/// of its terms at `q = j/16` (their rounding).
struct Residual {
    samples: Vec<f64>,
    series: Vec<f64>,
    error: f64,
    magnitude: Vec<f64>,
}

/// A plane wave from a field point off axis through a thin lens whose aperture is its stop
/// (docs/physics.md, "Designs given as data"): the chief ray crosses the lens centre undeviated
/// and meets the detector at `h = z (tan θx, tan θy)`. With the wave's direction cosines `α` and
/// pupil coordinates `X = R (x, y)`, the OPD a lens phase adds to against the reference sphere
/// centred on `h` is `α·X + |X − P| − |P|` (`P = (h, z)`), which on axis is the sag
/// `√(|X|² + z²) − z`. [`opd_m`](Oblique::opd_m) is the difference from that on-axis sag: the
/// field aberrations (coma, astigmatism, field curvature) of a lens designed on axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oblique {
    radius_m: f64,
    distance_m: f64,
    alpha: [f64; 2],
    image: [f64; 2],
}

impl Oblique {
    /// Incidence at the field angles `(x_rad, y_rad)` (chief-ray angles, |θ| < 80°) on a lens of
    /// aperture radius `radius_m` with the detector at `distance_m`.
    pub fn new(radius_m: f64, distance_m: f64, x_rad: f64, y_rad: f64) -> Result<Oblique, Error> {
        for (name, v) in [("field angle x", x_rad), ("field angle y", y_rad)] {
            if !(v.is_finite() && v.abs() < 80f64.to_radians()) {
                return Err(Error::InvalidParameter { name, value: v, expected: "finite, |θ| < 80° (radians)" });
            }
        }
        for (name, v) in [("aperture radius", radius_m), ("detector distance", distance_m)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidParameter { name, value: v, expected: "finite and > 0 m" });
            }
        }
        let (tx, ty) = (x_rad.tan(), y_rad.tan());
        let norm = (1.0 + tx * tx + ty * ty).sqrt();
        Ok(Oblique { radius_m, distance_m, alpha: [tx / norm, ty / norm], image: [distance_m * tx, distance_m * ty] })
    }

    /// The OPD (m) at normalized pupil coordinates `(x, y)` beyond the on-axis sag.
    pub fn opd_m(&self, x: f64, y: f64) -> f64 {
        let (xm, ym, z) = (self.radius_m * x, self.radius_m * y, self.distance_m);
        let [hx, hy] = self.image;
        let to_image = ((xm - hx).powi(2) + (ym - hy).powi(2) + z * z).sqrt() - (hx * hx + hy * hy + z * z).sqrt();
        let r2 = xm * xm + ym * ym;
        let sag = r2 / ((r2 + z * z).sqrt() + z);
        self.alpha[0] * xm + self.alpha[1] * ym + to_image - sag
    }

    /// The derivative of [`opd_m`](Oblique::opd_m) at `(x, y)` with respect to the field angle
    /// along x (`axis` 0) or y (1), m per radian (docs/physics.md, "Gradients: the field point"):
    /// with `t = (tan θx, tan θy)`, `α = t/√(1 + |t|²)` and the image point `P = z t`,
    /// `∂α_a/∂t_a = (1 + t_b²)/n³`, `∂α_b/∂t_a = −t_a t_b/n³` (`n = √(1 + |t|²)`),
    /// `∂|X − P|/∂t_a = −z (X_a − P_a)/|X − P|`, `∂|P|/∂t_a = z P_a/|P|` (the distances with
    /// `z`), and `∂t_a/∂θ_a = 1 + t_a²`; the on-axis sag does not move.
    pub fn opd_field_rate_m(&self, x: f64, y: f64, axis: usize) -> f64 {
        let (xm, ym, z) = (self.radius_m * x, self.radius_m * y, self.distance_m);
        let [hx, hy] = self.image;
        let (t, along) = ([hx / z, hy / z], [xm, ym]);
        let (a, b) = if axis == 0 { (0, 1) } else { (1, 0) };
        let n2 = 1.0 + t[0] * t[0] + t[1] * t[1];
        let n3 = n2 * n2.sqrt();
        let d_alpha = (along[a] * (1.0 + t[b] * t[b]) - along[b] * t[a] * t[b]) / n3;
        let to_image = ((xm - hx).powi(2) + (ym - hy).powi(2) + z * z).sqrt();
        let to_axis_image = (hx * hx + hy * hy + z * z).sqrt();
        let image = self.image[a];
        let d_path = -z * (along[a] - image) / to_image - z * image / to_axis_image;
        (d_alpha + d_path) * (1.0 + t[a] * t[a])
    }

    /// The derivative of [`opd_m`](Oblique::opd_m) at `(x, y)` with respect to the logarithm of
    /// the aperture radius `R`, the detector distance `z` and the field angles held, m
    /// (docs/physics.md, "Gradients: the F-number and the focal length of a phase lens off
    /// axis"): the pupil point `X = R(x, y)` moves along itself, so with `r = |X|`
    /// `R ∂OPD/∂R = α·X + (X − P)·X/|X − P| − r²/√(r² + z²)` (the distances with `z`; the
    /// on-axis sag `√(r² + z²) − z`). The OPD is homogeneous of degree 1 in `(R, z)` (the image
    /// point `P = z t` scales with `z`), so its rate along `ln z` is `opd_m − R ∂OPD/∂R`.
    pub fn opd_radius_rate_m(&self, x: f64, y: f64) -> f64 {
        let (xm, ym, z) = (self.radius_m * x, self.radius_m * y, self.distance_m);
        let [hx, hy] = self.image;
        let to_image = ((xm - hx).powi(2) + (ym - hy).powi(2) + z * z).sqrt();
        let r2 = xm * xm + ym * ym;
        self.alpha[0] * xm + self.alpha[1] * ym + ((xm - hx) * xm + (ym - hy) * ym) / to_image
            - r2 / (r2 + z * z).sqrt()
    }
}

/// `scale · √(n+1) R_n^0(ρ)` as a profile in `q = ρ²` (Noll 1976; `n` even): the wavefront of an
/// `m = 0` Zernike term per unit of its RMS coefficient times `scale`, the direction of that
/// coefficient's derivative (`LensModel::binary2_directions`).
pub fn zernike_radial_profile(n: usize, scale: f64) -> RadialProfile {
    RadialProfile::finish(Kind::Even(zernike_radial_q(n).into_iter().map(|c| c * scale).collect()))
}

/// `√(n+1) R_n^0(ρ)` as ascending coefficients in `q = ρ²` (Noll 1976; `n` even).
fn zernike_radial_q(n: usize) -> Vec<f64> {
    let half = n / 2;
    let norm = ((n + 1) as f64).sqrt();
    let fact = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
    // R_n^0 = Σ_k (−1)^k (n−k)!/(k! ((n/2−k)!)²) ρ^{n−2k}: power q^{half − k}
    let mut out = vec![0.0; half + 1];
    for k in 0..=half {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        out[half - k] = sign * fact(n - k) / (fact(k) * fact(half - k) * fact(half - k)) * norm;
    }
    out
}

/// The flat lens's exact pupil mapping (docs/physics.md, "The flat lens's exact image"): a lens
/// whose field `U(r) e^{ikW(r)}` lives on its plane images, on axis through the Rayleigh–Sommerfeld
/// integral in the Fraunhofer approximation about the image point, the Fourier transform in the
/// direction cosines `e = r/√(r² + z²)` of `P̃(e) = U(r(e)) e^{ikW(r(e))}/c²`, `c² = 1 − e²` (the
/// Jacobian `z²/c⁴` times the obliquity `c` and the `c/z` of the distance). The OTF is the
/// normalized autocorrelation of `P̃` at the lag `λν`, so the pupil's radius is
/// `e_max = R/√(R² + z²)`, not the paraxial `NA0 = R/z`.
///
/// In the pupil's own normalized variable `q = e²/e_max²` the lens-plane `q_r = (r/R)²` is
/// `q (1 − E)/(1 − qE)` with `E = e_max²`, and the cutoff `2 e_max/λ` is `1/k` of the paraxial
/// one, `k = √(1 + NA0²)`. [`map`](DirectionCosines::map) rewrites a lens-plane
/// [`RadialPupil`] so: every profile read through the map, the amplitude divided by `c²`, the
/// frequency scaled by `k`; the radial engine then runs unchanged (the map is radial on axis).
/// The mapped profiles are kept by the profile they map (a lens's profiles are shared by every
/// wavelength's pupil), so that each is fitted once.
#[derive(Debug)]
pub struct DirectionCosines {
    e2: f64,
    scale: f64,
    obliquity: Arc<RadialProfile>,
    cache: std::sync::Mutex<Vec<(Arc<RadialProfile>, Arc<RadialProfile>)>>,
    /// the mapped monomials `q_r^i` (index 0), and `q_r^i/c²` (index 1), made when the map has
    /// prepared [`MAPPED_BEFORE_MONOMIALS`] polynomials the generic way
    bases: [OnceLock<MappedMonomials>; 2],
    /// polynomials mapped so far
    polynomials: std::sync::atomic::AtomicUsize,
}

/// Polynomials a map prepares point by point before it makes its [`MappedMonomials`] (which
/// cost about as much as 20 of them): a phase profile's few shared terms never need them, a
/// library's new ones at every wavelength do.
const MAPPED_BEFORE_MONOMIALS: usize = 24;

/// The mapped monomials `m_i(q) = q_r(q)^i` (divided by `c² = 1 − qE` for an amplitude),
/// `i ≤` [`MAPPED_MONOMIALS`], at every point the preparation of a profile reads
/// ([`RadialProfile::sampled`], its [`Summary`]) and as their Chebyshev interpolants at the
/// degrees [`fit_series`] tries: a mapped polynomial `Σ c_i q_r^i` is prepared as the sums
/// `Σ c_i m_i` (the interpolant is linear in the function), not by evaluating and fitting it
/// again. A library lens's imaging order has a new amplitude and residual polynomial at every
/// wavelength (lenses/src/library.rs).
#[derive(Debug)]
struct MappedMonomials {
    /// `m_i` at `q = k/`[`BOUND_SAMPLES`]
    samples: Vec<Vec<f64>>,
    /// the summary's nodes `(q, w)` (8 Gauss panels on `[0, 1]`) and `m_i` there
    nodes: Vec<(f64, f64)>,
    at_nodes: Vec<Vec<f64>>,
    /// `chebyshev_fit(m_i, n)` for `n = 8, 16, 32, 64` (index `log2 n − 3`)
    series: Vec<Vec<Vec<f64>>>,
}

/// The highest power of `q_r` a mapped polynomial may have to be prepared from
/// [`MappedMonomials`] (a library's amplitude and phase have 12; higher ones are fitted as
/// any other profile).
const MAPPED_MONOMIALS: usize = 16;

impl MappedMonomials {
    fn new(e2: f64, obliquity: bool) -> MappedMonomials {
        let monomial = |i: usize, q: f64| {
            let c2 = 1.0 - q * e2;
            let v = (q * (1.0 - e2) / c2).powi(i as i32);
            if obliquity { v / c2 } else { v }
        };
        let h = 1.0 / BOUND_SAMPLES as f64;
        let mut nodes = Vec::new();
        crate::quad::for_each_node(0.0, 1.0, 8, |q, w| nodes.push((q, w)));
        let degrees = (0..=MAPPED_MONOMIALS).map(|i| {
            let samples: Vec<f64> = (0..=BOUND_SAMPLES).map(|k| monomial(i, k as f64 * h)).collect();
            let at_nodes: Vec<f64> = nodes.iter().map(|&(q, _)| monomial(i, q)).collect();
            let mut series = Vec::new();
            let mut n = 8;
            while n <= PROXY_MAX_DEGREE {
                series.push(chebyshev_fit(&|q| monomial(i, q), n));
                n *= 2;
            }
            (samples, at_nodes, series)
        });
        let (mut samples, mut at_nodes, mut series) = (Vec::new(), Vec::new(), Vec::new());
        for (s, a, c) in degrees {
            samples.push(s);
            at_nodes.push(a);
            series.push(c);
        }
        MappedMonomials { samples, nodes, at_nodes, series }
    }

    /// `mapped` (the map of the polynomial `coefficients`) with its samples, series and summary
    /// made from the monomials' (equal to its own preparation up to rounding); `None` for a
    /// polynomial of degree above [`MAPPED_MONOMIALS`].
    fn prepare(&self, coefficients: &[f64], mapped: RadialProfile) -> Option<RadialProfile> {
        if coefficients.len() > MAPPED_MONOMIALS + 1 {
            return None;
        }
        let sum = |table: &[Vec<f64>], k: usize| -> f64 { coefficients.iter().zip(table).map(|(c, m)| c * m[k]).sum() };
        let values: Vec<f64> = (0..=BOUND_SAMPLES).map(|k| sum(&self.samples, k)).collect();
        let size = values.iter().fold(0.0_f64, |acc, v| acc.max(v.abs()));
        let fit = |n: usize| -> Vec<f64> {
            let level = n.trailing_zeros() as usize - 3;
            let series: Vec<&Vec<f64>> = self.series.iter().map(|s| &s[level]).collect();
            (0..=n).map(|j| coefficients.iter().zip(&series).map(|(c, s)| c * s[j]).sum()).collect()
        };
        let series = fit_series_with(&|q| mapped.value(q), 8.0 * f64::EPSILON * size, &fit);
        let (mut slope, mut square) = (0.0, 0.0);
        for (m, &(q, w)) in self.nodes.iter().enumerate() {
            let f = sum(&self.at_nodes, m);
            slope += w * 12.0 * (q - 0.5) * f;
            square += w * f * f;
        }
        let summary = Summary { fit: slope, mean_square: square, bounds: bounds_of_samples(&values) };
        let _ = mapped.summary.0.set(summary);
        let _ = mapped.sampled.0.set(Sampled { values, series });
        Some(mapped)
    }
}

/// Mapped profiles a [`DirectionCosines`] keeps (a lens has a few; a library's per-wavelength
/// amplitudes are new each time and pass through).
const MAPPED_CACHE: usize = 32;

impl DirectionCosines {
    /// The map of a lens of paraxial numerical aperture `na0 = R/z` (aperture radius over the
    /// distance to the detector; finite, > 0).
    pub fn new(na0: f64) -> Result<DirectionCosines, Error> {
        if !(na0.is_finite() && na0 > 0.0) {
            return Err(Error::InvalidParameter {
                name: "paraxial numerical aperture",
                value: na0,
                expected: "finite and > 0",
            });
        }
        let e2 = na0 * na0 / (1.0 + na0 * na0);
        let obliquity = Arc::new(RadialProfile::finish(Kind::Mapped { inner: None, e2, obliquity: true }));
        Ok(DirectionCosines {
            e2,
            scale: (1.0 + na0 * na0).sqrt(),
            obliquity,
            cache: Default::default(),
            bases: Default::default(),
            polynomials: Default::default(),
        })
    }

    /// `k = √(1 + NA0²)`: the exact pupil's cutoff is `1/k` of the paraxial one.
    pub fn frequency_scale(&self) -> f64 {
        self.scale
    }

    /// `e_max² = NA0²/(1 + NA0²)`, the squared sine of the rim ray's angle.
    pub fn rim_sine_squared(&self) -> f64 {
        self.e2
    }

    /// A lens-plane profile (a wavefront term) read through the map, at the same ray (not
    /// kept: a new profile is fitted when first sampled).
    pub fn profile(&self, profile: RadialProfile) -> RadialProfile {
        RadialProfile::finish(Kind::Mapped { inner: Some(Arc::new(profile)), e2: self.e2, obliquity: false })
    }

    fn mapped(&self, profile: &Arc<RadialProfile>, obliquity: bool) -> Arc<RadialProfile> {
        let make = || {
            let mapped = RadialProfile::finish(Kind::Mapped { inner: Some(profile.clone()), e2: self.e2, obliquity });
            // a polynomial: prepared from the mapped monomials
            let prepared = match &profile.kind {
                Kind::Even(c)
                    if c.len() <= MAPPED_MONOMIALS + 1
                        && self.polynomials.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
                            >= MAPPED_BEFORE_MONOMIALS =>
                {
                    self.bases[usize::from(obliquity)]
                        .get_or_init(|| MappedMonomials::new(self.e2, obliquity))
                        .prepare(c, mapped.clone())
                }
                _ => None,
            };
            Arc::new(prepared.unwrap_or(mapped))
        };
        let Ok(mut cache) = self.cache.lock() else { return make() };
        if let Some((_, m)) = cache.iter().find(|(p, m)| {
            Arc::ptr_eq(p, profile) && matches!(m.kind, Kind::Mapped { obliquity: o, .. } if o == obliquity)
        }) {
            return m.clone();
        }
        let m = make();
        if cache.len() >= MAPPED_CACHE {
            cache.remove(0);
        }
        cache.push((profile.clone(), m.clone()));
        m
    }

    /// `pupil` (on the lens plane, with an order's own defocus `w020_m` beyond the pupil's fit,
    /// m at the rim in `q_r`) in direction cosines: its terms, its `m = 0` Zernike terms and the
    /// defocus read through the map, its amplitude divided by `c²`. Refused for a pupil seen
    /// off axis or with Zernike terms of `m ≠ 0` (the map is radial on axis only).
    pub fn map(&self, pupil: &RadialPupil, w020_m: f64) -> Result<RadialPupil, Error> {
        if pupil.frequency_scale.is_some() {
            return Ok(pupil.clone());
        }
        if !pupil.is_symmetric() {
            return Err(Error::InvalidParameter {
                name: "pupil mapped to direction cosines",
                value: pupil.asymmetric_zernike().len() as f64,
                expected: "a radially symmetric pupil on axis (the exact map is radial on axis only)",
            });
        }
        let amplitude = Some(match &pupil.amplitude {
            Some(a) => self.mapped(a, true),
            None => self.obliquity.clone(),
        });
        let mut terms: Vec<(f64, Arc<RadialProfile>)> =
            pupil.terms.iter().map(|(c, p)| (*c, self.mapped(p, false))).collect();
        let mut even = pupil.zernike_even.clone();
        if w020_m != 0.0 {
            if even.len() < 2 {
                even.resize(2, 0.0);
            }
            even[1] += w020_m;
        }
        if even.iter().any(|&c| c != 0.0) {
            let poly = Arc::new(RadialProfile::even_polynomial(even)?);
            terms.push((1.0, self.mapped(&poly, false)));
        }
        let mut out = RadialPupil::new(amplitude, terms, vec![])?;
        out.frequency_scale = Some(self.scale);
        Ok(out)
    }
}

/// A radial pupil prepared for one order at one wavelength: its OPD's derivative bounds, which
/// size the quadrature.
#[derive(Clone, Debug)]
pub struct RadialOrder {
    pupil: Arc<RadialPupil>,
    w020_m: f64,
    wavelength_m: f64,
    /// `max |W'(q)|` of the whole OPD, m, and the oscillation of `W'` over windows of
    /// `2^j/`[`BOUND_SAMPLES`] in `q` (`j = 0, 1, …`: the largest `W'(a) − W'(b)` with
    /// `|a − b|` within the window), m: how much the phase difference of two pupil points a
    /// shift apart can change (module docs)
    slope: f64,
    oscillation: Vec<f64>,
    /// extra phase-equivalent (radians) for the amplitude: a table's knots, or the change of
    /// `ln A` across the rule for a smooth amplitude kept from zero
    amplitude_turns: f64,
    /// the part of it from the terms of `ln A` of degree 2 and up in `q` (what puts `v⁴` and
    /// beyond across v: the short rules' second model)
    amplitude_higher: f64,
    /// the phase beyond the defocus, `k (W(q) − W020 q)` (radians), as a Chebyshev series in
    /// `x = 2q − 1`, where one of at most [`PROXY_MAX_DEGREE`] holds it to
    /// [`PROXY_PHASE_ERROR`] (evaluated by Clenshaw's recurrence instead of the profile's own
    /// terms: a table's spline search, a sphere's root), cut per OTF to the accuracy asked
    proxy: Option<Proxy>,
    /// the knots `0 < ρ_i < 1` of the pupil's tables (its wavefront terms and amplitude), in
    /// this pupil's radius, ascending: where the integrand's third derivative jumps
    /// ([`split_nodes`](Self::split_nodes)); empty for analytic profiles
    knots: Vec<f64>,
    /// the range `(lo, hi)` of `W′` (m) on each interval between the knots (`knots.len() + 1`
    /// of them, from the axis to the rim), with a margin as [`slope`](Self::slope)'s: how fast
    /// a piece of the split rule turns ([`split_nodes`](Self::split_nodes))
    knot_slopes: Vec<(f64, f64)>,
    /// the rule of a pupil with a table's knots ([`TableRule`])
    table_rule: TableRule,
}

/// The radial engine's rule for a pupil with a table's knots (`phase_csv`, `phase_spline_rad`, a
/// table's amplitude; `[options] table_rule`, docs/physics.md, "The radial engine"). A pupil
/// without knots takes the tensor rule either way.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TableRule {
    /// The tensor rule sized for an analytic integrand (the default): a cubic spline's third
    /// derivative jumps at its knots, so the OTF is good to about [`TENSOR_TABLE_ERROR`]
    /// (relative) whatever the accuracy asked.
    #[default]
    Tensor,
    /// The rule split at the knots' crossings (`RadialOrder::split_nodes`): within the
    /// accuracy asked, at about 11× the tensor rule's time on a 17-knot spline; a pupil whose
    /// tables have more than [`SPLIT_MAX_KNOTS`] knots keeps the tensor rule.
    Split,
}

impl TableRule {
    /// The name in scene files (`options.table_rule`).
    pub fn name(self) -> &'static str {
        match self {
            TableRule::Tensor => "tensor",
            TableRule::Split => "split",
        }
    }
}

/// How far (relative) the tensor rule's OTF and mean MTF of a pupil with a table's knots may
/// be from the converged value whatever the accuracy asked ([`TableRule::Tensor`]): measured on
/// the 17-knot hyperbolic spline, whose mean MTF on the 50 nm band is 1.8e-6 off at the
/// tolerance 1e-6 and its OTF up to 3e-6 off at every accuracy from 1e-7 to 1e-10
/// (docs/physics.md, "Designs given as data", the spline paragraph).
pub const TENSOR_TABLE_ERROR: f64 = 2e-6;

/// A phase proxy's Chebyshev coefficients and, for each degree it may be cut to, the largest
/// phase error of the cut series: `tails[d] = Σ_{k ≥ d} |c_k|` plus the fit's own error (a
/// Chebyshev polynomial is at most 1 in size on `[−1, 1]`), so that [`RadialOrder::otf`] reads
/// only the terms its accuracy needs.
#[derive(Clone, Debug)]
struct Proxy {
    coefficients: Vec<f64>,
    tails: Vec<f64>,
}

impl Proxy {
    fn new(coefficients: Vec<f64>, fit_error: f64) -> Proxy {
        let mut tails = vec![fit_error; coefficients.len() + 1];
        for d in (0..coefficients.len()).rev() {
            tails[d] = tails[d + 1] + coefficients[d].abs();
        }
        Proxy { coefficients, tails }
    }

    /// The fewest leading coefficients (at least one) whose series is within `phase_error`
    /// radians of the phase everywhere on the pupil; all of them where none is.
    fn cut(&self, phase_error: f64) -> &[f64] {
        let n = self.coefficients.len();
        let d = (1..=n).find(|&d| self.tails[d] <= phase_error).unwrap_or(n);
        &self.coefficients[..d]
    }
}

/// A radial OTF's rule ([`RadialOrder::otf`]): its nodes and the proxy's cut.
type Rule<'a> = (Nodes, Option<&'a [f64]>);

/// The nodes of a radial OTF's rule, handed out a panel of lanes at a time
/// ([`RadialOrder::panel_nodes`]).
enum Nodes {
    /// The tensor rule: `t_panels` 16-point panels on `[0, t_end]` (`t_end = acos s`) times
    /// `v_nodes` across v (a pupil whose profiles are analytic).
    Tensor { t_end: f64, t_panels: usize, v_nodes: std::borrow::Cow<'static, [(f64, f64)]> },
    /// The rule split at a table's knots ([`RadialOrder::split_nodes`]): every lane's `q₁`, `q₂`
    /// and weight (t and v rule, `sin²t`), padded with lanes of weight zero to whole panels of
    /// [`SPLIT_LANES`].
    Split { q1: Vec<f64>, q2: Vec<f64>, weight: Vec<f64> },
}

/// The most knots a pupil's tables may have for the split rule (`Nodes::Split`; a freeform
/// spline has tens): its nodes grow with the knots (about 4 t breaks and 2 row crossings a
/// knot), so a dense table (`examples/phase-table.toml`, 803 rows) keeps the tensor rule.
pub const SPLIT_MAX_KNOTS: usize = 64;

/// Lanes of a panel of the split rule ([`Nodes::Split`]).
const SPLIT_LANES: usize = 256;

impl Nodes {
    /// The lanes of one panel.
    fn lanes(&self) -> usize {
        match self {
            Nodes::Tensor { v_nodes, .. } => crate::quad::rule().len() * v_nodes.len(),
            Nodes::Split { .. } => SPLIT_LANES,
        }
    }

    /// The panels.
    fn panels(&self) -> usize {
        match self {
            Nodes::Tensor { t_panels, .. } => *t_panels,
            Nodes::Split { weight, .. } => weight.len() / SPLIT_LANES,
        }
    }
}

/// Largest degree of a phase proxy ([`RadialOrder`]).
const PROXY_MAX_DEGREE: usize = 64;

/// Phase error (radians) a proxy may have anywhere on `[0, 1]`: an OTF moves by at most that.
const PROXY_PHASE_ERROR: f64 = 1e-13;

/// Chebyshev coefficients of `f` on `q ∈ [0, 1]` (`x = 2q − 1`) of degree `n`, from its values at
/// the `n + 1` Chebyshev–Lobatto points (the discrete cosine transform, written out).
fn chebyshev_fit(f: &dyn Fn(f64) -> f64, n: usize) -> Vec<f64> {
    let values: Vec<f64> = (0..=n)
        .map(|j| {
            let x = (std::f64::consts::PI * j as f64 / n as f64).cos();
            f(0.5 * (x + 1.0))
        })
        .collect();
    // cos(π jk/n) from a table of one turn, cos(π m/n) for m < 2n
    let table: Vec<f64> = (0..2 * n).map(|m| (std::f64::consts::PI * m as f64 / n as f64).cos()).collect();
    (0..=n)
        .map(|k| {
            let mut sum = 0.0;
            for (j, v) in values.iter().enumerate() {
                let w = if j == 0 || j == n { 0.5 } else { 1.0 };
                sum += w * v * table[(j * k) % (2 * n)];
            }
            let scale = if k == 0 || k == n { 1.0 } else { 2.0 };
            scale * sum / n as f64
        })
        .collect()
}

/// `Σ c_k T_k(2q − 1)` by Clenshaw's recurrence.
#[inline]
fn clenshaw(c: &[f64], q: f64) -> f64 {
    let x2 = 2.0 * (2.0 * q - 1.0);
    let (mut b1, mut b2) = (0.0, 0.0);
    for &ck in c[1..].iter().rev() {
        (b1, b2) = (crate::quad::fused(x2, b1, ck - b2), b1);
    }
    c[0] + 0.5 * x2 * b1 - b2
}

/// `Σ c_k T_k(2q − 1)` on eight lanes at once by Clenshaw's recurrence (`wide::f64x8`, one
/// AVX-512 register where the build has it): the same fused operations as [`clenshaw`] on each
/// lane. The engine runs it as [`clenshaw8_blocks`]; this one block alone is that function's
/// reference in the tests.
#[cfg(test)]
fn clenshaw8(c: &[f64], q: wide::f64x8) -> wide::f64x8 {
    use wide::f64x8;
    let x2 = f64x8::splat(2.0) * q.mul_add(f64x8::splat(2.0), f64x8::splat(-1.0));
    let (mut b1, mut b2) = (f64x8::ZERO, f64x8::ZERO);
    for &ck in c[1..].iter().rev() {
        (b1, b2) = (x2.mul_add(b1, f64x8::splat(ck) - b2), b1);
    }
    // as the scalar recurrence rounds it: the product, then the two sums
    f64x8::splat(c[0]) + f64x8::splat(0.5) * x2 * b1 - b2
}

/// `clenshaw8` (`Σ c_k T_k(2q − 1)` by Clenshaw's recurrence, each lane the fused operations of
/// [`clenshaw`]) on `N` blocks of eight lanes at once: one pass over the coefficients carries
/// the `N` recurrences side by side, so that their chains of dependent multiply-adds overlap
/// (one recurrence at a time waits on each step's latency). Each lane takes the operations of
/// `clenshaw8` in the same order, so each block is its value to the last bit (tested in
/// `lanes_match_the_scalar_recurrence`).
#[inline(always)]
fn clenshaw8_blocks<const N: usize>(c: &[f64], q: [wide::f64x8; N]) -> [wide::f64x8; N] {
    use wide::f64x8;
    let x2: [f64x8; N] =
        std::array::from_fn(|j| f64x8::splat(2.0) * q[j].mul_add(f64x8::splat(2.0), f64x8::splat(-1.0)));
    let (mut b1, mut b2) = ([f64x8::ZERO; N], [f64x8::ZERO; N]);
    for &ck in c[1..].iter().rev() {
        let ck = f64x8::splat(ck);
        for j in 0..N {
            (b1[j], b2[j]) = (x2[j].mul_add(b1[j], ck - b2[j]), b1[j]);
        }
    }
    std::array::from_fn(|j| f64x8::splat(c[0]) + f64x8::splat(0.5) * x2[j] * b1[j] - b2[j])
}

/// Eight values from `x[at..at + 8]`.
#[inline(always)]
fn load8(x: &[f64], at: usize) -> wide::f64x8 {
    let mut a = [0.0; 8];
    a.copy_from_slice(&x[at..at + 8]);
    wide::f64x8::new(a)
}

/// `Σ_i w_i cos(a_i − b_i)`: eight lanes at a time by `wide::f64x8::sin_cos` (Agner Fog's vector
/// sine and cosine, as the FFT path's pupil rows, `fft::cis`), the rest by the scalar
/// [`sin_cos`](crate::fft::cis::sin_cos).
fn cosine_sum(w: &[f64], a: &[f64], b: &[f64]) -> f64 {
    let n = w.len() / 8 * 8;
    let mut acc = wide::f64x8::ZERO;
    for i in (0..n).step_by(8) {
        let (_, cos) = (load8(a, i) - load8(b, i)).sin_cos();
        acc = load8(w, i).mul_add(cos, acc);
    }
    let mut total = acc.reduce_add();
    for i in n..w.len() {
        total += w[i] * crate::fft::cis::sin_cos(a[i] - b[i]).1;
    }
    total
}

/// `Σ_i w_i cos(a (q₁ − q₂) + p(q₁) − p(q₂))` with `p` the Chebyshev series `c` in `2q − 1`
/// ([`clenshaw8_blocks`]), `q₁ = q1[i]`, `q₂ = q2[i]`: the phase and its cosine fused eight lanes at a
/// time, nothing stored between them; the rest lane by lane.
fn proxy_cosine_sum(c: &[f64], a: f64, q1: &[f64], q2: &[f64], w: &[f64]) -> f64 {
    use wide::f64x8;
    let n = w.len() / 8 * 8;
    let a8 = f64x8::splat(a);
    // two blocks of eight a step: independent recurrences the core overlaps
    let (mut acc, mut acc2) = (f64x8::ZERO, f64x8::ZERO);
    let pairs = n / 16 * 16;
    for i in (0..pairs).step_by(16) {
        let (x, y, x2, y2) = (load8(q1, i), load8(q2, i), load8(q1, i + 8), load8(q2, i + 8));
        let [px, py, px2, py2] = clenshaw8_blocks(c, [x, y, x2, y2]);
        let phase = a8.mul_add(x - y, px - py);
        let phase2 = a8.mul_add(x2 - y2, px2 - py2);
        acc = load8(w, i).mul_add(phase.sin_cos().1, acc);
        acc2 = load8(w, i + 8).mul_add(phase2.sin_cos().1, acc2);
    }
    for i in (pairs..n).step_by(8) {
        let (x, y) = (load8(q1, i), load8(q2, i));
        let [px, py] = clenshaw8_blocks(c, [x, y]);
        let phase = a8.mul_add(x - y, px - py);
        acc = load8(w, i).mul_add(phase.sin_cos().1, acc);
    }
    let mut total = (acc + acc2).reduce_add();
    for i in n..w.len() {
        let phase = a * (q1[i] - q2[i]) + (clenshaw(c, q1[i]) - clenshaw(c, q2[i]));
        total += w[i] * crate::fft::cis::sin_cos(phase).1;
    }
    total
}

/// Fills the lanes of one t panel, v node by v node (`16 j + i` for the t node `i` and the v node
/// `j`: each v node's column of 16 t nodes runs as vector loops): `q₁` at `q[l]`, `q₂` at
/// `q[lanes + l]`, the weight `scale_i × w_v` at `weight[l]`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn fill_columns(
    s: f64,
    sin_t: &[f64; 16],
    cos_t: &[f64; 16],
    scale: &[f64; 16],
    v_nodes: &[(f64, f64)],
    q: &mut [f64],
    weight: &mut [f64],
    lanes: usize,
) {
    let (mut cos2, mut sin2, mut delta) = ([0.0; 16], [0.0; 16], [0.0; 16]);
    for i in 0..16 {
        cos2[i] = cos_t[i] * cos_t[i];
        sin2[i] = sin_t[i] * sin_t[i];
        delta[i] = 4.0 * s * (cos_t[i] - s);
    }
    for (j, &(v, wv)) in v_nodes.iter().enumerate() {
        let v2 = v * v;
        let (first, second, weights) = (&mut q[16 * j..16 * j + 16], 16 * j + lanes, &mut weight[16 * j..16 * j + 16]);
        let mut q2 = [0.0; 16];
        for i in 0..16 {
            let q1 = cos2[i] + v2 * sin2[i];
            first[i] = q1;
            // q₂ = (cos t − 2s)² + v² sin²t ≥ 0; the clamp holds it there through rounding
            let d = q1 - delta[i];
            q2[i] = if d > 0.0 { d } else { 0.0 };
            weights[i] = scale[i] * wv;
        }
        q[second..second + 16].copy_from_slice(&q2);
    }
}

/// The proxy of `phase` ([`RadialOrder`]): [`fit_series`] to [`PROXY_PHASE_ERROR`] or
/// `rounding`, the rounding of the exact evaluation's terms (radians), whichever is larger: the
/// proxy is then as accurate as the evaluation it replaces.
fn phase_proxy(phase: &dyn Fn(f64) -> f64, rounding: f64) -> Option<Proxy> {
    fit_series(phase, PROXY_PHASE_ERROR.max(rounding)).map(|(c, error)| Proxy::new(c, error))
}

/// The Chebyshev series of `f` on `q ∈ [0, 1]` and its error: the first degree of 8, 16, 32, 64
/// whose last four coefficients sum below a tenth of the error allowed and whose values at the
/// midpoints of the next finer grid agree with `f` within it; `None` otherwise. The error
/// allowed is `floor`, or the rounding of the series' own size (1e-15 of its largest
/// coefficient), whichever is larger.
fn fit_series(f: &dyn Fn(f64) -> f64, floor: f64) -> Option<(Vec<f64>, f64)> {
    fit_series_with(f, floor, &|n| chebyshev_fit(f, n))
}

/// [`fit_series`] with the degree-`n` fit given by `fit` (the same interpolant by another route:
/// [`DirectionCosines`]'s sums of mapped monomials), each checked against `f` as there.
fn fit_series_with(f: &dyn Fn(f64) -> f64, floor: f64, fit: &dyn Fn(usize) -> Vec<f64>) -> Option<(Vec<f64>, f64)> {
    let mut n = 8;
    while n <= PROXY_MAX_DEGREE {
        let c = fit(n);
        let size = c.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let allowed = floor.max(1e-15 * size);
        let tail: f64 = c[n - 3..].iter().map(|v| v.abs()).sum();
        if tail <= 0.1 * allowed {
            let checked = (0..2 * n).all(|j| {
                let x = (std::f64::consts::PI * (j as f64 + 0.5) / (2 * n) as f64).cos();
                let q = 0.5 * (x + 1.0);
                (clenshaw(&c, q) - f(q)).abs() <= allowed
            });
            if checked {
                return Some((c, allowed));
            }
        }
        n *= 2;
    }
    None
}

impl RadialOrder {
    /// `pupil` with the order's defocus `w020_m` (m at the rim) at `wavelength_m`.
    pub fn new(pupil: Arc<RadialPupil>, w020_m: f64, wavelength_m: f64) -> RadialOrder {
        let h = 1.0 / BOUND_SAMPLES as f64;
        // from the terms' cached samples and series where they have them
        let mut parts = pupil.residual();
        let residual: Vec<f64> = match &mut parts {
            Some(parts) => std::mem::take(&mut parts.samples),
            None => (0..=BOUND_SAMPLES).map(|i| pupil.opd_beyond_defocus_m(i as f64 * h)).collect(),
        };
        let residual_slopes: Vec<f64> = residual.windows(2).map(|w| (w[1] - w[0]) / h).collect();
        let slopes: Vec<f64> = residual_slopes.iter().map(|d| w020_m + d).collect();
        let slope = 1.25 * slopes.iter().map(|v| v.abs()).fold(0.0, f64::max);
        // windows of 2^j samples by doubling: max and min over [i, i + 2m) from those of m (the
        // slopes are finite: plain comparisons, which vectorize, not `f64::max`)
        let larger = |a: f64, b: f64| if a > b { a } else { b };
        let smaller = |a: f64, b: f64| if a < b { a } else { b };
        let (mut hi, mut lo) = (slopes.clone(), slopes.clone());
        let (mut next_hi, mut next_lo) = (vec![0.0; slopes.len()], vec![0.0; slopes.len()]);
        // two neighbouring slopes differ by the second difference: a window of one sample holds
        // the change across it
        let across = slopes.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, larger);
        // the largest `h − l`, eight running maxima (one chain of dependent maxima would not
        // vectorize)
        let widest = |hi: &[f64], lo: &[f64]| {
            let mut acc = [0.0_f64; 8];
            let n = hi.len().min(lo.len()) / 8 * 8;
            for (h, l) in hi[..n].chunks_exact(8).zip(lo[..n].chunks_exact(8)) {
                for k in 0..8 {
                    acc[k] = larger(acc[k], h[k] - l[k]);
                }
            }
            let rest = hi[n..].iter().zip(&lo[n..]).map(|(h, l)| h - l).fold(0.0, larger);
            acc.iter().copied().fold(rest, larger)
        };
        let mut oscillation = Vec::new();
        let mut width = 1;
        loop {
            let osc = widest(&hi, &lo);
            oscillation.push(1.25 * (osc + across));
            if width >= BOUND_SAMPLES {
                break;
            }
            // max and min over [i, i + 2·width) from those over width, into the other buffers
            let n = hi.len() - width;
            for ((o, a), b) in next_hi[..n].iter_mut().zip(&hi[..n]).zip(&hi[width..width + n]) {
                *o = larger(*a, *b);
            }
            for ((o, a), b) in next_lo[..n].iter_mut().zip(&lo[..n]).zip(&lo[width..width + n]) {
                *o = smaller(*a, *b);
            }
            std::mem::swap(&mut hi, &mut next_hi);
            std::mem::swap(&mut lo, &mut next_lo);
            hi.truncate(n);
            lo.truncate(n);
            width *= 2;
        }
        let (amplitude_turns, amplitude_higher) = pupil.amplitude.as_ref().map_or((0.0, 0.0), |a| {
            let (d1, d2) = a.summary().bounds;
            let scale = a.mean_square().sqrt().max(f64::MIN_POSITIVE);
            let low = a.sampled().values.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()));
            if a.knots() == 0 && low >= 0.1 * scale {
                // a smooth amplitude kept from zero (a polynomial, the obliquity 1/c² of a pupil
                // in direction cosines): the product A(q₁)A(q₂) is exp(ln A(q₁) + ln A(q₂)), a
                // real exponent the rules integrate as they do a phase of the same size. Across
                // v it changes by at most 2 max|(ln A)′| (q₁ and q₂ each move by at most 1), of
                // which the curvature of ln A (v⁴ and up) by at most max|(ln A)″|
                let slope = d1 / low;
                (2.0 * slope, d2 / low + slope * slope)
            } else {
                // a table, or an amplitude near zero: about one radian of "turn" a knot
                // interval, beside its own slope
                let turns = 0.25 * a.knots() as f64 + 4.0 * d1 / scale;
                (turns, turns)
            }
        });
        let k = std::f64::consts::TAU / wavelength_m;
        // the exact evaluation's rounding: a few units in the last place of its largest term
        // (its size, not its exact maximum: 17 samples)
        let magnitude = (0..=16)
            .map(|j| {
                let q = j as f64 / 16.0;
                (w020_m * q).abs() + parts.as_ref().map_or_else(|| pupil.opd_magnitude_m(q), |p| p.magnitude[j])
            })
            .fold(0.0, f64::max);
        let rounding = 4.0 * f64::EPSILON * k * magnitude;
        let proxy = match parts {
            // the terms' series summed: as accurate as they are, plus the sum's rounding
            Some(parts) => Some(Proxy::new(parts.series.iter().map(|c| k * c).collect(), k * parts.error + rounding)),
            None => phase_proxy(&|q| k * pupil.opd_beyond_defocus_m(q), rounding),
        };
        let knots = pupil.table_knots();
        // the slopes' range on each knot interval: every sample window that meets it
        let knot_slopes = (0..=knots.len())
            .map(|j| {
                let lower = if j == 0 { 0.0 } else { knots[j - 1] * knots[j - 1] };
                let upper = if j == knots.len() { 1.0 } else { knots[j] * knots[j] };
                let first = ((lower / h).floor() as usize).min(slopes.len() - 1);
                let last = ((upper / h).ceil() as usize).clamp(first + 1, slopes.len());
                let (lo, hi) = slopes[first..last]
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &v| (l.min(v), u.max(v)));
                let margin = 0.125 * (hi - lo) + across;
                (lo - margin, hi + margin)
            })
            .collect();
        RadialOrder {
            pupil,
            w020_m,
            wavelength_m,
            slope,
            oscillation,
            amplitude_turns,
            amplitude_higher,
            proxy,
            knots,
            knot_slopes,
            table_rule: TableRule::Tensor,
        }
    }

    /// This order with the rule `rule` for a pupil with a table's knots ([`TableRule`]; the
    /// default is [`TableRule::Tensor`]).
    pub fn with_table_rule(mut self, rule: TableRule) -> RadialOrder {
        self.table_rule = rule;
        self
    }

    /// The oscillation of `W'` (m) over windows of width `delta` in `q` (the next dyadic window).
    fn oscillation_over(&self, delta: f64) -> f64 {
        let samples = (delta * BOUND_SAMPLES as f64).max(1.0);
        let j = (samples.log2().ceil() as usize).min(self.oscillation.len() - 1);
        self.oscillation[j]
    }

    /// The pupil.
    pub fn pupil(&self) -> &Arc<RadialPupil> {
        &self.pupil
    }

    /// The real OTF at `s = ν λ F#` (normalized frequency, `0 ≤ s`; 0 from `s ≥ 1/k`, `k` the
    /// pupil's [`frequency_scale`](RadialPupil::frequency_scale)), within
    /// about `accuracy` (absolute) of the autocorrelation integral (module docs).
    pub fn otf(&self, s: f64, accuracy: f64) -> f64 {
        let (s, (nodes, proxy)) = match self.scaled_rule(s, accuracy) {
            Ok(inside) => inside,
            Err(end) => return end,
        };
        let total = self.direct(s, &nodes, proxy);
        4.0 * total / (std::f64::consts::PI * self.pupil.power())
    }

    /// The real OTF at `s` as [`otf`](Self::otf), and into `derivatives` its derivative with
    /// respect to each parameter `p_j` whose change of the whole OPD is `directions[j]` (m per
    /// unit of `p_j`, as a function of `q = ρ²`; the OPD's part the order carries as defocus
    /// included: a coefficient's best-fit defocus moves with it, so the whole wavefront's
    /// change is what the phase difference sees). On the same nodes and with the same phases as
    /// the value (docs/physics.md, "Gradients"):
    ///
    /// ```text
    /// ∂OTF/∂p_j = −4/N ∫ sin²t ∫ A(q₁) A(q₂) sin(k[W(q₁) − W(q₂)]) k [D_j(q₁) − D_j(q₂)] dv dt
    /// ```
    ///
    /// The integrand turns through the same phase as the value's, times a polynomial factor of
    /// the directions' low degree, so the value's rule holds it to about the same accuracy
    /// relative to `k max|D_j|`.
    pub fn otf_and_derivatives(
        &self,
        s: f64,
        accuracy: f64,
        directions: &[RadialProfile],
        derivatives: &mut [f64],
    ) -> f64 {
        derivatives.iter_mut().for_each(|d| *d = 0.0);
        let (s, (nodes, proxy)) = match self.scaled_rule(s, accuracy) {
            Ok(inside) => inside,
            Err(end) => return end,
        };
        let total = self.direct_derivatives(s, &nodes, proxy, directions, derivatives);
        let norm = 4.0 / (std::f64::consts::PI * self.pupil.power());
        derivatives.iter_mut().for_each(|d| *d *= norm);
        norm * total
    }

    /// `s` scaled to the pupil ([`frequency_scale`](RadialPupil::frequency_scale)) and the rule
    /// there, or the OTF at an end of its support: 0 from the cutoff on, 1 at `s ≤ 0` (the OTF
    /// normalized there). The one preamble of the OTF and of its derivative forms.
    #[inline]
    fn scaled_rule(&self, s: f64, accuracy: f64) -> Result<(f64, Rule<'_>), f64> {
        let s = s * self.pupil.frequency_scale();
        if s >= 1.0 {
            return Err(0.0);
        }
        if s <= 0.0 {
            return Err(1.0);
        }
        Ok((s, self.rule(s, accuracy)))
    }

    /// The rule [`otf`](Self::otf) uses at `s` for `accuracy`: `acos s`, the t panels, the v
    /// nodes and the proxy's cut.
    fn rule(&self, s: f64, accuracy: f64) -> Rule<'_> {
        let k = std::f64::consts::TAU / self.wavelength_m;
        let (g1, osc) = (self.slope, self.oscillation_over(4.0 * s * (1.0 - s)));
        let t_end = s.acos();
        // phase the integrand can turn through along t and along v (module docs' bounds), plus
        // the sin²t factor's (frequency 2) and an amplitude table's
        let phase_t = k * (4.0 * s * (1.0 - s) * g1 + osc * t_end) + 2.0 * t_end + self.amplitude_turns;
        let phase_v = k * osc + self.amplitude_turns;
        let theta = panel_phase(accuracy);
        let t_panels = (phase_t / theta).ceil().max(1.0) as usize;
        // the phase in the series' terms of degree j and up (radians), for the short rules
        let beyond = |j: usize| match &self.proxy {
            Some(p) => 2.0 * p.tails[j.min(p.coefficients.len())],
            None => f64::INFINITY,
        };
        // the part of the v phase from the terms of degree 3 and up (v⁴ and beyond), and an
        // amplitude table's turns
        let higher = (k * osc).min(beyond(3)) + self.amplitude_higher;
        let v_rule = small_rule(phase_v, higher, accuracy, &beyond);
        let v_panels = if v_rule.is_some() { 1 } else { (phase_v / theta).ceil().max(1.0) as usize };
        let rule16 = crate::quad::rule();
        // the v nodes on [0, 1] with their weights: one short rule, or 16-point panels
        let v_nodes: std::borrow::Cow<'static, [(f64, f64)]> = match v_rule {
            Some(r) => r.into(),
            None => {
                let hv = 0.5 / v_panels as f64;
                (0..v_panels)
                    .flat_map(|pv| {
                        let vc = (2 * pv + 1) as f64 * hv;
                        rule16.iter().map(move |&(xv, wv)| (vc + hv * xv, hv * wv))
                    })
                    .collect::<Vec<_>>()
                    .into()
            }
        };
        // the proxy cut to a phase error of a quarter of the accuracy: a phase error e moves
        // the OTF by at most 2e (|cos(φ + e) − cos φ| ≤ e at each of the two points, and
        // ∫A(q₁)A(q₂) ≤ ∫A² by Cauchy–Schwarz), half the accuracy; the quadrature has the rest
        let proxy = self.proxy.as_ref().map(|p| p.cut(0.25 * accuracy));
        if self.table_rule == TableRule::Split && !self.knots.is_empty() && self.knots.len() <= SPLIT_MAX_KNOTS {
            return (self.split_nodes(s, accuracy, t_end, phase_t), proxy);
        }
        (Nodes::Tensor { t_end, t_panels, v_nodes }, proxy)
    }

    /// The rule of a pupil with a table's knots (docs/physics.md, "The radial engine"): a cubic
    /// spline's third derivative jumps at each knot `ρ_i`, so the integrand is only piecewise
    /// analytic, and a Gauss–Legendre panel across a jump converges only algebraically. Here
    /// every panel lies between the jumps:
    ///
    /// - each row (one t node, `c = cos t`, `σ = sin t`) is split across v where either pupil's
    ///   radius crosses a knot, `q₁ = c² + v²σ² = ρ_i²` and `q₂ = (c − 2s)² + v²σ² = ρ_i²`;
    /// - t is split where such a crossing enters the rows: at `v = 0` (`c = ρ_i`, `c = 2s ± ρ_i`,
    ///   and `c = 2s`, the second pupil's axis, where a spline's first piece has its `ρ³`) and at
    ///   `v = 1` (`q₂ = 1 + 4s² − 4sc = ρ_i²`). A crossing entering at `v = 0` moves as
    ///   `√(t − t_i)`, which puts `(t − t_i)^{7/2}` into the row integral: a segment next to one
    ///   takes its nodes through `t = t_a + L w²` (its mirror at the other end, `w²(3 − 2w)` at
    ///   both), in which the row integral is analytic again.
    ///
    /// Each piece takes the fewest Gauss–Legendre points ([`for_each_piece_node`]) for the phase
    /// it turns through and how that turn bends: along t a share of the tensor rule's bound
    /// `phase_t` in proportion to the segment's length (twice that through a map), taken as
    /// wholly bent; across v the piece `[a, b]` turns through `k σ² (b² − a²) max|W′(q₁) − W′(q₂)|`
    /// (the phase's rate along v is `2vσ² k (W′(q₁) − W′(q₂))`), with `W′` bounded on the knot
    /// interval each pupil's radius stays in ([`knot_slopes`](Self::knot_slopes)), and bends by
    /// the ranges of `W′` on those intervals and by `v²` on `[a, b]` (`(b − a)/(b + a)` of its
    /// turn). Each piece is then within `accuracy` of its share of the rule's measure.
    fn split_nodes(&self, s: f64, accuracy: f64, t_end: f64, phase_t: f64) -> Nodes {
        // the pieces' errors add up over the rule's measure, ∫ sin²t dt dv ≤ π/4 (times 4/π)
        let allowed = accuracy;
        let k = std::f64::consts::TAU / self.wavelength_m;
        let squares: Vec<f64> = self.knots.iter().map(|r| r * r).collect();
        // the t breaks, each with whether a crossing enters at v = 0 there (a square root)
        let mut breaks: Vec<(f64, bool)> = Vec::with_capacity(4 * self.knots.len() + 1);
        let mut at = |c: f64, root: bool| {
            if c > s && c < 1.0 {
                breaks.push((c.acos(), root));
            }
        };
        at(2.0 * s, true);
        for &r in &self.knots {
            at(r, true);
            at(2.0 * s + r, true);
            at(2.0 * s - r, true);
            at((1.0 + 4.0 * s * s - r * r) / (4.0 * s), false);
        }
        breaks.sort_by(|a, b| a.0.total_cmp(&b.0));
        // segments' ends, breaks closer than 1e-12 t_end merged
        let close = 1e-12 * t_end;
        let mut ends: Vec<(f64, bool)> = vec![(0.0, false)];
        for (t, root) in breaks {
            match ends.last_mut() {
                Some(last) if t - last.0 <= close => last.1 |= root,
                _ => ends.push((t, root)),
            }
        }
        let segments = ends.len();
        match ends.last_mut() {
            Some(last) if t_end - last.0 <= close && segments > 1 => last.0 = t_end,
            _ => ends.push((t_end, false)),
        }
        let (mut q1, mut q2, mut weight) = (Vec::new(), Vec::new(), Vec::new());
        let mut v_ends: Vec<f64> = Vec::with_capacity(2 * self.knots.len() + 2);
        for w in ends.windows(2) {
            let ((ta, root_a), (tb, root_b)) = (w[0], w[1]);
            let length = tb - ta;
            // a map doubles the rate the integrand turns at, at most, and multiplies it by a
            // polynomial of degree 1 or 2 (at least two points)
            let mapped = root_a || root_b;
            let theta = phase_t * length / t_end * if mapped { 2.0 } else { 1.0 };
            for_each_piece_node(theta, theta, allowed, if mapped { 2 } else { 1 }, |x, wx| {
                // through the map that makes a square root at an end analytic
                let (t, dt) = match (root_a, root_b) {
                    (false, false) => (ta + length * x, length),
                    (true, false) => (ta + length * x * x, 2.0 * length * x),
                    (false, true) => (tb - length * (1.0 - x) * (1.0 - x), 2.0 * length * (1.0 - x)),
                    (true, true) => (ta + length * x * x * (3.0 - 2.0 * x), 6.0 * length * x * (1.0 - x)),
                };
                let (sin_t, cos_t) = t.sin_cos();
                let sigma2 = sin_t * sin_t;
                let row = wx * dt * sigma2;
                let (c1, c2) = (cos_t * cos_t, (cos_t - 2.0 * s) * (cos_t - 2.0 * s));
                v_ends.clear();
                v_ends.push(0.0);
                for &r in &self.knots {
                    for c in [c1, c2] {
                        let v2 = (r * r - c) / sigma2;
                        if v2 > 0.0 && v2 < 1.0 {
                            v_ends.push(v2.sqrt());
                        }
                    }
                }
                v_ends.push(1.0);
                v_ends.sort_by(f64::total_cmp);
                let delta = 4.0 * s * (cos_t - s);
                for p in v_ends.windows(2) {
                    let (va, vb) = (p[0], p[1]);
                    if vb <= va {
                        continue;
                    }
                    // the phase's change along the piece, `σ² k (W′(q₁) − W′(q₂))` times
                    // `b² − a²`, from the slopes' range over the knot interval of each pupil
                    let middle = 0.5 * (va + vb);
                    let first = c1 + middle * middle * sigma2;
                    let (j1, j2) =
                        (squares.partition_point(|&x| x <= first), squares.partition_point(|&x| x <= first - delta));
                    let ((lo1, hi1), (lo2, hi2)) = (self.knot_slopes[j1], self.knot_slopes[j2]);
                    let spread = (hi1 - lo2).max(hi2 - lo1).max(0.0);
                    let span = vb * vb - va * va;
                    let theta = (k * spread * sigma2 + self.amplitude_turns) * span;
                    // its bend: the change of the rate along the piece, from the slopes' own
                    // ranges and from v² on [a, b] ((b − a)/(b + a) of a straight turn)
                    let bend = (k * ((hi1 - lo1) + (hi2 - lo2)) * sigma2 + self.amplitude_turns) * span
                        + theta * (vb - va) / (vb + va);
                    for_each_piece_node(theta, bend, allowed, 1, |y, wy| {
                        let v = va + (vb - va) * y;
                        let first = c1 + v * v * sigma2;
                        let d = first - delta;
                        q1.push(first);
                        // q₂ ≥ 0; the clamp holds it there through rounding
                        q2.push(if d > 0.0 { d } else { 0.0 });
                        weight.push(row * wy * (vb - va));
                    });
                }
            });
        }
        let padded = weight.len().div_ceil(SPLIT_LANES) * SPLIT_LANES;
        q1.resize(padded, 0.0);
        q2.resize(padded, 0.0);
        weight.resize(padded, 0.0);
        Nodes::Split { q1, q2, weight }
    }

    /// `direct` with the derivatives along `directions` added into
    /// `derivatives` ([`otf_and_derivatives`](Self::otf_and_derivatives)): each lane's phase
    /// once, its sine and cosine once, then one multiply-add per lane and direction.
    #[allow(clippy::too_many_arguments)]
    fn direct_derivatives(
        &self,
        s: f64,
        nodes: &Nodes,
        proxy: Option<&[f64]>,
        directions: &[RadialProfile],
        derivatives: &mut [f64],
    ) -> f64 {
        let lanes = nodes.lanes();
        let k = std::f64::consts::TAU / self.wavelength_m;
        let a = k * self.w020_m;
        LANE_BUFFERS.with_borrow_mut(|[q, weight, _]| {
            q.resize(2 * lanes, 0.0);
            weight.resize(lanes, 0.0);
            // every direction an even polynomial or a profile read eight lanes at a time (a
            // sphere's slope): the polynomials' moments and the others' sums, eight lanes at a
            // time; a table direction sends every lane through the scalar sum
            let degree = directions
                .iter()
                .map(|d| match &d.kind {
                    Kind::Even(c) => Some(c.len()),
                    _ if d.vectorizes() => Some(1),
                    _ => None,
                })
                .try_fold(1, |n, d| d.map(|d| n.max(d)));
            let mut moments = degree.filter(|_| proxy.is_some()).map(|n| vec![wide::f64x8::ZERO; n]);
            // the directions read eight lanes at a time (not polynomials), with their sums
            let general: Vec<usize> = match moments {
                Some(_) => (0..directions.len()).filter(|&j| !matches!(directions[j].kind, Kind::Even(_))).collect(),
                None => Vec::new(),
            };
            let mut sums = vec![wide::f64x8::ZERO; general.len()];
            let mut total = 0.0;
            for pt in 0..nodes.panels() {
                self.panel_lanes(s, nodes, pt, q, weight);
                // even polynomials with the proxy: the phase as the value's lanes, and the moments
                // `Σ_l −w sin(Δφ) (q₁^m − q₂^m)` once for all the directions
                let start = match (proxy, moments.as_mut()) {
                    (Some(c), Some(moments)) => {
                        use wide::f64x8;
                        let n = lanes / 8 * 8;
                        let a8 = f64x8::splat(a);
                        let mut acc = f64x8::ZERO;
                        for i in (0..n).step_by(8) {
                            let (x, y) = (load8(q, i), load8(q, lanes + i));
                            let [px, py] = clenshaw8_blocks(c, [x, y]);
                            let (sin, cos) = a8.mul_add(x - y, px - py).sin_cos();
                            let w = load8(weight, i);
                            acc = w.mul_add(cos, acc);
                            let slope = -(w * sin);
                            let (mut p1, mut p2) = (x, y);
                            for m in moments.iter_mut().skip(1) {
                                *m = slope.mul_add(p1 - p2, *m);
                                p1 *= x;
                                p2 *= y;
                            }
                            for (sum, &j) in sums.iter_mut().zip(&general) {
                                *sum = slope.mul_add(directions[j].value8(x) - directions[j].value8(y), *sum);
                            }
                        }
                        total += acc.reduce_add();
                        n
                    }
                    _ => 0,
                };
                for (l, &w) in weight.iter().enumerate().skip(start) {
                    let (q1, q2) = (q[l], q[lanes + l]);
                    let beyond = match proxy {
                        Some(c) => clenshaw(c, q1) - clenshaw(c, q2),
                        None => k * (self.pupil.opd_beyond_defocus_m(q1) - self.pupil.opd_beyond_defocus_m(q2)),
                    };
                    let (sin, cos) = crate::fft::cis::sin_cos(a * (q1 - q2) + beyond);
                    total += w * cos;
                    let slope = -w * sin * k;
                    for (d, direction) in derivatives.iter_mut().zip(directions) {
                        *d += slope * (direction.value(q1) - direction.value(q2));
                    }
                }
            }
            if let Some(moments) = moments {
                let moments: Vec<f64> = moments.iter().map(|m| m.reduce_add()).collect();
                for (d, direction) in derivatives.iter_mut().zip(directions) {
                    if let Kind::Even(c) = &direction.kind {
                        *d += k * c.iter().zip(&moments).skip(1).map(|(c, m)| c * m).sum::<f64>();
                    }
                }
                for (sum, &j) in sums.iter().zip(&general) {
                    derivatives[j] += k * sum.reduce_add();
                }
            }
            total
        })
    }

    /// The lanes of t panel `pt` of the rule ([`rule`](Self::rule): `t_panels` 16-point panels
    /// on `[0, t_end]` times `v_nodes`), the one node builder of the value (`direct`)
    /// and of its derivatives ([`direct_derivatives`](Self::direct_derivatives)): each node's
    /// `q₁` and `q₂` into `q` (first and second half) and its weight (the t and v rule's, `sin²t`
    /// and the field amplitudes) into `weight`.
    #[allow(clippy::too_many_arguments)]
    fn panel_lanes(&self, s: f64, nodes: &Nodes, pt: usize, q: &mut [f64], weight: &mut [f64]) {
        self.panel_nodes(s, nodes, pt, q, weight);
        self.amplitudes(q, weight);
    }

    /// The real OTF at `s` as [`otf`](Self::otf) and its derivative with respect to a
    /// parameter that moves the pupil's field amplitude along `amplitude` (`∂A/∂b` as a
    /// function of `q = ρ²`) and its whole wavefront along `wavefront_m` (`∂W/∂b`, m): forward
    /// mode on the value's rule, its nodes and phases (docs/physics.md, "Gradients: a
    /// library's parameter bias"). With `I = ∫ sin²t ∫ A(q₁) A(q₂) cos(k[W(q₁) − W(q₂)]) dv dt`
    /// and `OTF = 4 I/(π P)`, `P = ∫A² dq`:
    ///
    /// ```text
    /// ∂I = ∫ sin²t ∫ { [∂A(q₁) A(q₂) + A(q₁) ∂A(q₂)] cos(kΔW) − A(q₁) A(q₂) sin(kΔW) k [∂W(q₁) − ∂W(q₂)] } dv dt
    /// ∂OTF = 4 ∂I/(π P) − OTF ∂P/P,   ∂P = 2 ∫ A ∂A dq
    /// ```
    ///
    /// (`∂P` on the rule of [`RadialProfile::mean_square`], exact for polynomials). Lane by
    /// lane, not eight at a time: a library lens's bias is one direction.
    pub fn otf_and_field_derivative(
        &self,
        s: f64,
        accuracy: f64,
        amplitude: &RadialProfile,
        wavefront_m: &RadialProfile,
    ) -> (f64, f64) {
        // the OTF is normalized to 1 at s = 0 whatever the pupil: no derivative there
        let (s, (nodes, proxy)) = match self.scaled_rule(s, accuracy) {
            Ok(inside) => inside,
            Err(end) => return (end, 0.0),
        };
        let lanes = nodes.lanes();
        let k = std::f64::consts::TAU / self.wavelength_m;
        let a = k * self.w020_m;
        let (mut q, mut weight) = (vec![0.0; 2 * lanes], vec![0.0; lanes]);
        let (mut total, mut derivative) = (0.0, 0.0);
        for pt in 0..nodes.panels() {
            // the value's nodes and weights without the amplitudes, which are differentiated here
            self.panel_nodes(s, &nodes, pt, &mut q, &mut weight);
            for (l, &w) in weight.iter().enumerate() {
                let (q1, q2) = (q[l], q[lanes + l]);
                let beyond = match proxy {
                    Some(c) => clenshaw(c, q1) - clenshaw(c, q2),
                    None => k * (self.pupil.opd_beyond_defocus_m(q1) - self.pupil.opd_beyond_defocus_m(q2)),
                };
                let (sin, cos) = crate::fft::cis::sin_cos(a * (q1 - q2) + beyond);
                let (a1, a2) = (self.pupil.amplitude(q1), self.pupil.amplitude(q2));
                total += w * a1 * a2 * cos;
                derivative += w
                    * ((amplitude.value(q1) * a2 + a1 * amplitude.value(q2)) * cos
                        - a1 * a2 * sin * k * (wavefront_m.value(q1) - wavefront_m.value(q2)));
            }
        }
        let power = self.pupil.power();
        let mut d_power = 0.0;
        crate::quad::for_each_node(0.0, 1.0, 8, |q, w| {
            d_power += w * 2.0 * self.pupil.amplitude(q) * amplitude.value(q);
        });
        let norm = 4.0 / (std::f64::consts::PI * power);
        let otf = norm * total;
        (otf, norm * derivative - otf * d_power / power)
    }

    /// The real OTF at `s` as [`otf`](Self::otf), bit for bit, and into `derivatives` its
    /// derivative along each of `fields` (`(∂A, ∂W)`: a parameter's change of the field
    /// amplitude and of the whole wavefront, m, as functions of `q = ρ²`), as
    /// [`otf_and_field_derivative`](Self::otf_and_field_derivative) gives one: forward mode on
    /// the value's nodes and phases (docs/physics.md, "Gradients: a library's parameter bias").
    /// The value's own sums run unchanged (the same lanes, weights, phase series and cosine
    /// sums as `direct`), each lane's sine taken from the same `sin_cos` as its
    /// cosine, so that a frequency rule reading these values makes the value's decisions: the
    /// lanes ride on the value's evaluation. Eight lanes at a time where the phase has its
    /// proxy; else the value by `direct`'s sum and the lanes beside it.
    pub fn otf_and_field_derivatives(
        &self,
        s: f64,
        accuracy: f64,
        fields: &[(&RadialProfile, &RadialProfile)],
        derivatives: &mut [f64],
    ) -> f64 {
        derivatives.iter_mut().for_each(|d| *d = 0.0);
        let (s, (nodes, proxy)) = match self.scaled_rule(s, accuracy) {
            Ok(inside) => inside,
            Err(end) => return end,
        };
        let lanes = nodes.lanes();
        let k = std::f64::consts::TAU / self.wavelength_m;
        let a = k * self.w020_m;
        let total = FIELD_BUFFERS.with_borrow_mut(|[q, bare, weight, phase]| {
            q.resize(2 * lanes, 0.0);
            bare.resize(lanes, 0.0);
            weight.resize(lanes, 0.0);
            if proxy.is_none() {
                phase.resize(2 * lanes, 0.0);
            }
            let mut total = 0.0;
            for pt in 0..nodes.panels() {
                // the value's lanes exactly (`panel_lanes`: the nodes, then the amplitudes), and
                // the rule's weights without the amplitudes, which the lanes differentiate
                self.panel_nodes(s, &nodes, pt, q, bare);
                weight.copy_from_slice(bare);
                self.amplitudes(q, weight);
                let (q1, q2) = q.split_at(lanes);
                total += match proxy {
                    Some(c) => self.proxy_cosine_sum_and_lanes(c, a, k, q1, q2, weight, bare, fields, derivatives),
                    None => {
                        for (p, &qi) in phase.iter_mut().zip(q.iter()) {
                            *p = a * qi + k * self.pupil.opd_beyond_defocus_m(qi);
                        }
                        let (p1, p2) = phase.split_at(lanes);
                        for l in 0..lanes {
                            let (sin, cos) = crate::fft::cis::sin_cos(p1[l] - p2[l]);
                            let (a1, a2) = (self.pupil.amplitude(q1[l]), self.pupil.amplitude(q2[l]));
                            for (d, (amplitude, wavefront)) in derivatives.iter_mut().zip(fields) {
                                *d += bare[l]
                                    * ((amplitude.value(q1[l]) * a2 + a1 * amplitude.value(q2[l])) * cos
                                        - a1 * a2 * sin * k * (wavefront.value(q1[l]) - wavefront.value(q2[l])));
                            }
                        }
                        cosine_sum(weight, p1, p2)
                    }
                };
            }
            total
        });
        let power = self.pupil.power();
        let norm = 4.0 / (std::f64::consts::PI * power);
        let otf = 4.0 * total / (std::f64::consts::PI * power);
        for (d, (amplitude, _)) in derivatives.iter_mut().zip(fields) {
            let mut d_power = 0.0;
            crate::quad::for_each_node(0.0, 1.0, 8, |q, w| {
                d_power += w * 2.0 * self.pupil.amplitude(q) * amplitude.value(q);
            });
            *d = norm * *d - otf * d_power / power;
        }
        otf
    }

    /// [`proxy_cosine_sum`] of the value's lanes, bit for bit (the same blocks of sixteen and
    /// eight, the same accumulators, the scalar tail), with each lane's derivative along `fields`
    /// added into `derivatives` from the same sine and cosine
    /// ([`otf_and_field_derivatives`](Self::otf_and_field_derivatives)): `bare` the lanes' rule
    /// weights without the amplitudes.
    #[allow(clippy::too_many_arguments)]
    fn proxy_cosine_sum_and_lanes(
        &self,
        c: &[f64],
        a: f64,
        k: f64,
        q1: &[f64],
        q2: &[f64],
        w: &[f64],
        bare: &[f64],
        fields: &[(&RadialProfile, &RadialProfile)],
        derivatives: &mut [f64],
    ) -> f64 {
        use wide::f64x8;
        let n = w.len() / 8 * 8;
        let a8 = f64x8::splat(a);
        let k8 = f64x8::splat(k);
        let mut sums = [f64x8::ZERO; 8];
        let mut more = vec![f64x8::ZERO; fields.len().saturating_sub(sums.len())];
        let amplitude = self.pupil.amplitude.as_deref();
        // one block of eight lanes' derivatives from their sine and cosine
        let mut lanes = |i: usize, x: f64x8, y: f64x8, sin: f64x8, cos: f64x8| {
            let (a1, a2) = amplitude.map_or((f64x8::ONE, f64x8::ONE), |p| (p.value8(x), p.value8(y)));
            let b = load8(bare, i);
            let (bc, bs) = (b * cos, b * sin * k8 * a1 * a2);
            for (j, (d_a, d_w)) in fields.iter().enumerate() {
                let term = bc * (d_a.value8(x) * a2 + a1 * d_a.value8(y)) - bs * (d_w.value8(x) - d_w.value8(y));
                let sum = if j < sums.len() { &mut sums[j] } else { &mut more[j - sums.len()] };
                *sum += term;
            }
        };
        let (mut acc, mut acc2) = (f64x8::ZERO, f64x8::ZERO);
        let pairs = n / 16 * 16;
        for i in (0..pairs).step_by(16) {
            let (x, y, x2, y2) = (load8(q1, i), load8(q2, i), load8(q1, i + 8), load8(q2, i + 8));
            let [px, py, px2, py2] = clenshaw8_blocks(c, [x, y, x2, y2]);
            let phase = a8.mul_add(x - y, px - py);
            let phase2 = a8.mul_add(x2 - y2, px2 - py2);
            let ((sin, cos), (sin2, cos2)) = (phase.sin_cos(), phase2.sin_cos());
            acc = load8(w, i).mul_add(cos, acc);
            acc2 = load8(w, i + 8).mul_add(cos2, acc2);
            lanes(i, x, y, sin, cos);
            lanes(i + 8, x2, y2, sin2, cos2);
        }
        for i in (pairs..n).step_by(8) {
            let (x, y) = (load8(q1, i), load8(q2, i));
            let [px, py] = clenshaw8_blocks(c, [x, y]);
            let phase = a8.mul_add(x - y, px - py);
            let (sin, cos) = phase.sin_cos();
            acc = load8(w, i).mul_add(cos, acc);
            lanes(i, x, y, sin, cos);
        }
        let mut total = (acc + acc2).reduce_add();
        for (j, d) in derivatives.iter_mut().enumerate() {
            *d += if j < sums.len() { sums[j] } else { more[j - sums.len()] }.reduce_add();
        }
        for i in n..w.len() {
            let phase = a * (q1[i] - q2[i]) + (clenshaw(c, q1[i]) - clenshaw(c, q2[i]));
            let (sin, cos) = crate::fft::cis::sin_cos(phase);
            total += w[i] * cos;
            let (a1, a2) = amplitude.map_or((1.0, 1.0), |p| (p.value(q1[i]), p.value(q2[i])));
            for (d, (d_a, d_w)) in derivatives.iter_mut().zip(fields) {
                *d += bare[i]
                    * ((d_a.value(q1[i]) * a2 + a1 * d_a.value(q2[i])) * cos
                        - a1 * a2 * sin * k * (d_w.value(q1[i]) - d_w.value(q2[i])));
            }
        }
        total
    }

    /// [`panel_lanes`](Self::panel_lanes) without the field amplitudes: the rule's weights
    /// (t and v rule, `sin²t`) alone.
    #[allow(clippy::too_many_arguments)]
    fn panel_nodes(&self, s: f64, nodes: &Nodes, pt: usize, q: &mut [f64], weight: &mut [f64]) {
        let (t_end, t_panels, v_nodes) = match nodes {
            Nodes::Tensor { t_end, t_panels, v_nodes } => (*t_end, *t_panels, v_nodes),
            Nodes::Split { q1, q2, weight: w } => {
                let range = pt * SPLIT_LANES..(pt + 1) * SPLIT_LANES;
                q[..SPLIT_LANES].copy_from_slice(&q1[range.clone()]);
                q[SPLIT_LANES..2 * SPLIT_LANES].copy_from_slice(&q2[range.clone()]);
                weight.copy_from_slice(&w[range]);
                return;
            }
        };
        let rule16 = crate::quad::rule();
        let lanes = weight.len();
        let ht = 0.5 * t_end / t_panels as f64;
        let tc = (2 * pt + 1) as f64 * ht;
        // the 16 nodes' t, and their sines and cosines eight at a time
        let (mut t, mut sin_t, mut cos_t) = ([0.0; 16], [0.0; 16], [0.0; 16]);
        for (ti, &(xt, _)) in t.iter_mut().zip(rule16) {
            *ti = tc + ht * xt;
        }
        for half in 0..2 {
            let (sin, cos) = load8(&t, 8 * half).sin_cos();
            sin_t[8 * half..8 * half + 8].copy_from_slice(&sin.to_array());
            cos_t[8 * half..8 * half + 8].copy_from_slice(&cos.to_array());
        }
        let mut scale = [0.0; 16];
        for ((c, &(_, wt)), &st) in scale.iter_mut().zip(rule16).zip(&sin_t) {
            *c = ht * wt * st * st;
        }
        fill_columns(s, &sin_t, &cos_t, &scale, v_nodes, q, weight, lanes);
    }

    /// The field amplitudes at every lane into `weight` (`q₁` in the first half of `q`, `q₂` in
    /// the second, `weight` as long as a half), where the pupil has an amplitude profile.
    ///
    ///
    /// A profile [`RadialProfile::product8`] reads (a polynomial, a sphere, the obliquity
    /// `1/c²` of a pupil in direction cosines and any of those read through that map) is read
    /// eight lanes at a time, to within a few units in the last place of the scalar
    /// [`RadialProfile::value`]; a table lane by lane.
    fn amplitudes(&self, q: &[f64], weight: &mut [f64]) {
        let Some(amplitude) = &self.pupil.amplitude else { return };
        let half = weight.len();
        let (q1, q2) = q.split_at(half);
        let n = if amplitude.vectorizes() { half / 8 * 8 } else { 0 };
        for i in (0..n).step_by(8) {
            let w = amplitude.product8(load8(q1, i), load8(q2, i)) * load8(weight, i);
            weight[i..i + 8].copy_from_slice(&w.to_array());
        }
        for i in n..half {
            weight[i] *= amplitude.value(q1[i]) * amplitude.value(q2[i]);
        }
    }

    /// The tensor rule, every node's whole phase: `t_panels` 16-point panels on `[0, acos s]`
    /// times `v_nodes`, one t panel at a time, its `(t, v)` nodes as lanes. The phase beyond the
    /// defocus is `proxy` (a cut of the order's, [`proxy_cosine_sum`]: phase and cosine fused
    /// eight lanes at a time), or without one the profile's own terms, then [`cosine_sum`].
    fn direct(&self, s: f64, nodes: &Nodes, proxy: Option<&[f64]>) -> f64 {
        let lanes = nodes.lanes();
        let k = std::f64::consts::TAU / self.wavelength_m;
        let a = k * self.w020_m;
        LANE_BUFFERS.with_borrow_mut(|[q, weight, phase]| {
            q.resize(2 * lanes, 0.0);
            weight.resize(lanes, 0.0);
            if proxy.is_none() {
                phase.resize(2 * lanes, 0.0);
            }
            let mut total = 0.0;
            for pt in 0..nodes.panels() {
                self.panel_lanes(s, nodes, pt, q, weight);
                total += match proxy {
                    Some(c) => proxy_cosine_sum(c, a, &q[..lanes], &q[lanes..], weight),
                    None => {
                        for (p, &qi) in phase.iter_mut().zip(q.iter()) {
                            *p = a * qi + k * self.pupil.opd_beyond_defocus_m(qi);
                        }
                        cosine_sum(weight, &phase[..lanes], &phase[lanes..])
                    }
                };
            }
            total
        })
    }
}

thread_local! {
    /// The buffers of [`RadialOrder::otf_and_field_derivatives`] (`q₁ | q₂`, the bare rule
    /// weights, the value's weights, phases), kept by the thread from one OTF to the next.
    static FIELD_BUFFERS: std::cell::RefCell<[Vec<f64>; 4]> =
        const { std::cell::RefCell::new([Vec::new(), Vec::new(), Vec::new(), Vec::new()]) };
}

thread_local! {
    /// The lanes' buffers (`q₁ | q₂`, weights, phases) of [`RadialOrder::direct`] and
    /// [`RadialOrder::direct_derivatives`], kept by the thread from one OTF to the next (no
    /// allocation per OTF).
    static LANE_BUFFERS: std::cell::RefCell<[Vec<f64>; 3]> =
        const { std::cell::RefCell::new([Vec::new(), Vec::new(), Vec::new()]) };
}

/// The nodes `x` and weights of a rule on `[0, 1]` for an integrand turning through `theta`
/// radians there, to about `allowed` of its size: the fewest Gauss–Legendre points `n`, at least
/// `least`, at most 16, whose error for `exp(iθx)` on `[0, 1]`, `(n!)⁴ θ^{2n}/((2n + 1)((2n)!)³)`
/// (the rule's remainder `(n!)⁴ f^{(2n)}/((2n + 1)((2n)!)³)` on a unit interval, Abramowitz and
/// Stegun 25.4.30, with `|f^{(2n)}| ≤ θ^{2n}`), is within `allowed`; else 16-point panels each
/// turning through at most [`panel_phase`]`(allowed)`.
fn for_each_piece_node(theta: f64, curved: f64, allowed: f64, least: usize, mut visit: impl FnMut(f64, f64)) {
    static RULES: OnceLock<Vec<Vec<(f64, f64)>>> = OnceLock::new();
    let rules = RULES.get_or_init(|| {
        (1..=16)
            .map(|n| crate::quad::gauss_legendre(n).into_iter().map(|(x, w)| (0.5 * (x + 1.0), 0.5 * w)).collect())
            .collect()
    });
    let square = theta * theta;
    // the remainders for n = 1, θ²/24 and θ/12, then by their ratios from n to n + 1
    let bend = curved;
    let (mut error, mut curved, mut n) = (square / 24.0, bend / 12.0, 1);
    while n < 16 && (error + curved > allowed || n < least) {
        let m = n as f64;
        let pair = (2.0 * m + 1.0) * (2.0 * m + 2.0);
        error *= (m + 1.0).powi(4) * square * (2.0 * m + 1.0) / ((2.0 * m + 3.0) * pair.powi(3));
        curved *= (m + 1.0).powi(3) * bend * (2.0 * m + 1.0) / ((2.0 * m + 3.0) * pair * pair);
        n += 1;
    }
    let error = error + curved;
    if error <= allowed {
        for &(x, w) in &rules[n - 1] {
            visit(x, w);
        }
        return;
    }
    let panels = (theta / panel_phase(allowed)).ceil().max(1.0) as usize;
    let h = 1.0 / panels as f64;
    for p in 0..panels {
        for &(x, w) in &rules[15] {
            visit((p as f64 + x) * h, w * h);
        }
    }
}

/// The phase (radians) a 16-point Gauss–Legendre panel may turn through for an error of about
/// `accuracy`: `(θ/2)^32/32! = accuracy`, between 6 and 16 rad.
fn panel_phase(accuracy: f64) -> f64 {
    thread_local! {
        /// The last accuracy asked and its phase: an evaluation asks one accuracy for each of
        /// its OTFs, and the power is then read, not computed again (the same value).
        static LAST: std::cell::Cell<Option<(f64, f64)>> = const { std::cell::Cell::new(None) };
    }
    if let Some((last, phase)) = LAST.get()
        && last.to_bits() == accuracy.to_bits()
    {
        return phase;
    }
    // 32! = 2.63e35
    let acc = accuracy.clamp(1e-300, 1.0);
    let phase = (2.0 * (acc * 2.631_308_369_336_935e35).powf(1.0 / 32.0)).clamp(6.0, 16.0);
    LAST.set(Some((accuracy, phase)));
    phase
}

/// A shorter Gauss–Legendre rule across v (4 or 8 nodes on `[0, 1]`) that integrates the v
/// factor to `accuracy`, if one does. `phase` bounds how far its phase turns across v; `higher`
/// how far the part of it from the terms of degree 3 and up in q (and an amplitude table) turns;
/// `beyond(j)` bounds the phase (radians) in the terms of degree j and up (infinite where the
/// pupil has no phase series).
///
/// Along v the phase is `k[W(q₁) − W(q₁ − δ)]` with `q₁ = cos²t + v² sin²t`, a function of v²,
/// not a band-limited one: a defocus and a spherical term make it `θ v²`, a term q³ adds `v⁴`,
/// and a term of degree j in q puts `v^{2(j−1)}` in. The whole integrand is even in v (the
/// overlap's two halves `v < 0` and `v > 0` are alike), so the rule of n nodes is the positive
/// half of the 2n-point rule on `[−1, 1]` with its weights (`∫_0^1 = ½ ∫_{−1}^1`): exact for
/// even polynomials of degree `4n − 2`, i.e. for the terms of degree `j ≤ 2n` in q, where the
/// n-point rule on `[0, 1]` it replaced held them to `j ≤ n` (`2(j − 1) ≤ 2n − 1`). The error
/// models, measured for `cos(φ₀ + θ p(v))` against 200 points (φ₀ from 0 to 2.3; `python3
/// xtask/baselines/short_rules.py`, rows `h4` and `h8`, prints the largest θ of each rule per
/// accuracy, where the models stop; each model at or above those points): `p = v²`, 4 nodes
/// `7e-10 θ⁸` (θ ≤ 2.55), 8 nodes `7e-23 θ^15.4` (θ ≤ 11.3); `p = v⁴`, 4 nodes `2e-6 θ^4.13`
/// (θ ≤ 0.885), 8 nodes `4e-14 θ^9.4` (θ ≤ 6.26); the terms beyond the rule's degree, 4 × their
/// phase. (The rules on `[0, 1]` before: `v²` 4 points `1.2e-6 θ⁴` (θ ≤ 0.87), 8 points
/// `4e-14 θ^9.4` (θ ≤ 6.1); `v⁴` `1.2e-5 θ²` (θ ≤ 0.19), `4e-9 θ⁵` (θ ≤ 2.7). The band-limited
/// estimate `(θ/2)^{2n}/(2n)!` those replaced promised far more than the rules hold: the 4-point
/// rule was 2e-11 off at an accuracy of 1e-12 on the Binary 2 metalens, and 1e-3 off for `v⁴` at
/// θ = 0.75 where it promised 1e-8.)
fn small_rule(phase: f64, higher: f64, accuracy: f64, beyond: &dyn Fn(usize) -> f64) -> Option<&'static [(f64, f64)]> {
    /// (points n, the v² model's factor, power and largest θ, the v⁴ model's, nodes and weights
    /// on [0, 1])
    type Model = (f64, f64, f64);
    type Rule = (usize, Model, Model, Vec<(f64, f64)>);
    static RULES: OnceLock<[Rule; 2]> = OnceLock::new();
    let rules = RULES.get_or_init(|| {
        [(4, (7e-10, 8.0, 2.55), (2e-6, 4.13, 0.885)), (8, (7e-23, 15.4, 11.3), (4e-14, 9.4, 6.26))].map(
            |(n, square, fourth)| {
                // the positive half of the 2n-point rule on [−1, 1], its weights as they are (the
                // integrand is even in v: ∫_0^1 = ½ ∫_{−1}^1)
                let on_unit = crate::quad::gauss_legendre(2 * n).into_iter().filter(|&(x, _)| x > 0.0).collect();
                (n, square, fourth, on_unit)
            },
        )
    });
    let allowed = 1e-2 * accuracy;
    let error = |(factor, power, largest): Model, theta: f64| {
        if theta <= largest { factor * theta.powf(power) } else { f64::INFINITY }
    };
    rules
        .iter()
        .find(|(n, square, fourth, _)| {
            error(*square, phase) + error(*fourth, higher) + 4.0 * beyond(2 * n + 1) <= allowed
        })
        .map(|(.., rule)| rule.as_slice())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The oblique wave's field rate against Richardson-extrapolated central differences of its
    /// OPD in each angle (steps 2h and h, h = 1e-4 rad: truncation O(h⁴) ~ 1e-16 of the path),
    /// at points across the pupil, on and off the axes (the paper's aperture, f0 = 1 mm at F/2),
    /// within 1e-9 of the rate's size there.
    #[test]
    fn oblique_field_rate_matches_differences() {
        let (radius, z) = (0.25e-3, 1e-3);
        for (tx, ty) in [(5f64, 0f64), (5.0, 3.0), (-2.0, 7.0), (0.0, 0.0)] {
            let (tx, ty) = (tx.to_radians(), ty.to_radians());
            let at = |x: f64, y: f64| Oblique::new(radius, z, x, y).unwrap();
            let o = at(tx, ty);
            for (x, y) in [(0.0, 0.0), (0.9, 0.1), (-0.3, 0.7), (0.5, -0.8)] {
                for axis in 0..2 {
                    let step = |h: f64| {
                        let (dx, dy) = if axis == 0 { (h, 0.0) } else { (0.0, h) };
                        (at(tx + dx, ty + dy).opd_m(x, y) - at(tx - dx, ty - dy).opd_m(x, y)) / (2.0 * h)
                    };
                    let h = 1e-4;
                    let reference = (4.0 * step(h) - step(2.0 * h)) / 3.0;
                    let rate = o.opd_field_rate_m(x, y, axis);
                    let scale = radius * (x * x + y * y).sqrt().max(1e-3);
                    assert!(
                        (rate - reference).abs() <= 1e-9 * scale,
                        "({tx}, {ty}) at ({x}, {y}) axis {axis}: {rate:e} vs {reference:e}"
                    );
                }
            }
        }
    }

    /// The spline reproduces a cubic even function's values between its knots when the function
    /// satisfies its end conditions closely, and passes through its knots exactly.
    #[test]
    fn spline_interpolates() {
        let x: Vec<f64> = (0..=40).map(|i| i as f64 / 40.0).collect();
        let f = |r: f64| (3.0 * r).cos();
        let y: Vec<f64> = x.iter().map(|&r| f(r)).collect();
        let s = Spline::new(x.clone(), y.clone()).unwrap();
        for (xi, yi) in x.iter().zip(&y) {
            assert!((s.value(*xi) - yi).abs() < 1e-15);
        }
        // inside (away from the natural end, whose zero curvature is not cos's)
        for i in 0..300 {
            let r = 0.8 * i as f64 / 300.0;
            assert!((s.value(r) - f(r)).abs() < 2e-6, "r = {r}: {} vs {}", s.value(r), f(r));
        }
    }

    /// [`Spline::piece`] is the binary search's piece (`partition_point` of the knots `≤ t`,
    /// clamped to the pieces) at every point tried: on evenly and unevenly spaced knots, at and
    /// beside each knot (one unit in the last place either way), between them, below the axis,
    /// beyond the rim, and at NaN.
    #[test]
    fn spline_pieces_are_the_searchs() {
        let even: Vec<f64> = (0..=16).map(|i| i as f64 / 16.0).collect();
        let uneven: Vec<f64> = (0..=20).map(|i| (i as f64 / 20.0).powf(1.7) * 1.02).collect();
        for x in [even, uneven] {
            let y: Vec<f64> = x.iter().map(|r| r * r).collect();
            let s = Spline::new(x.clone(), y).unwrap();
            let n = x.len();
            let search = |t: f64| x.partition_point(|&xi| xi <= t).clamp(1, n - 1) - 1;
            let mut points: Vec<f64> = vec![-0.5, -1e-300, 1.5, 1e300, f64::NAN];
            for &xi in &x {
                points.extend([xi, f64::from_bits(xi.to_bits() + 1), f64::from_bits(xi.to_bits().max(1) - 1)]);
            }
            points.extend((0..=1000).map(|i| 1.1 * i as f64 / 1000.0));
            for t in points {
                assert_eq!(s.piece(t), search(t), "t = {t:e}");
            }
        }
    }

    /// `radius_log_derivative` against central differences in `ln R` of the profile rebuilt at
    /// `R e^{±h}` (written here): the sphere `√(R²q + z²) − z` (z held), an even polynomial in
    /// `(r/R_n)²` read at `ρ = r/R`, and a table in `r` (its knots `r_i/R` move with R; the
    /// spline's end conditions are scale-free, so it is the same spline in r). Step h = 1e-4:
    /// truncation h²|f‴|/6 and rounding ε/h both below 1e-8 of the size.
    #[test]
    fn radius_log_derivatives_are_the_profiles_own() {
        let (radius, z, h) = (0.672e-3_f64, 3.36e-3_f64, 1e-4_f64);
        let r_knots: Vec<f64> = (0..=20).map(|i| 0.7e-3 * i as f64 / 20.0).collect();
        let phase = |r: f64| -2.0e9 * r * r + 1.0e15 * r.powi(4) + (r * 9e3).sin();
        let table = |big_r: f64| {
            let rho = r_knots.iter().map(|r| r / big_r).collect();
            RadialProfile::table(rho, r_knots.iter().map(|&r| phase(r)).collect()).unwrap()
        };
        let poly = |big_r: f64| {
            let s = (big_r / 0.6e-3).powi(2);
            RadialProfile::even_polynomial(vec![0.0, -5.0 * s, 0.3 * s * s, -0.01 * s.powi(3)]).unwrap()
        };
        let sphere = |big_r: f64| RadialProfile::reference_sphere(big_r, z).unwrap();
        let builders: [(&str, &dyn Fn(f64) -> RadialProfile); 3] =
            [("sphere", &sphere), ("polynomial", &poly), ("table", &table)];
        for (name, build) in builders {
            let slope = build(radius).radius_log_derivative().unwrap();
            let (up, down) = (build(radius * h.exp()), build(radius * (-h).exp()));
            let size = (0..=50).map(|i| build(radius).value(i as f64 / 50.0).abs()).fold(0.0, f64::max);
            for i in 0..=50 {
                let q = i as f64 / 50.0;
                let reference = (up.value(q) - down.value(q)) / (2.0 * h);
                let error = (slope.value(q) - reference).abs();
                assert!(error <= 1e-7 * size, "{name} at q = {q}: {} vs {reference}", slope.value(q));
            }
        }
        assert!(sphere(radius).radius_log_derivative().unwrap().radius_log_derivative().is_none());
        let scaled = table(radius).scaled(-2.5).unwrap();
        assert!((scaled.value(0.3) + 2.5 * table(radius).value(0.3)).abs() < 1e-12 * size_of(&table(radius)));
    }

    fn size_of(p: &RadialProfile) -> f64 {
        (0..=50).map(|i| p.value(i as f64 / 50.0).abs()).fold(0.0, f64::max)
    }

    /// A mapped polynomial prepared from the mapped monomials (`MappedMonomials`) reads as the
    /// same polynomial mapped and prepared point by point (the generic path: `value` at every
    /// sample, `fit_series` of its own values): samples, series, slope, mean square and
    /// derivative bounds, a library-like amplitude and phase of degree 12 at NA0 = 0.2 and 0.5,
    /// with and without the obliquity.
    #[test]
    fn mapped_polynomials_prepare_as_their_own_fits() {
        let amplitude: Vec<f64> = (0..=12).map(|i| [0.93, -0.04, 0.011, -0.002][i % 4] / (1.0 + i as f64)).collect();
        let phase: Vec<f64> = (0..=12).map(|i| [0.0, -3.1, 1.7, -0.6][i % 4] * 0.5_f64.powi(i as i32)).collect();
        let mut series_compared = 0;
        for na in [0.2, 0.5] {
            let map = DirectionCosines::new(na).unwrap();
            // past the polynomials a map prepares point by point
            for i in 0..MAPPED_BEFORE_MONOMIALS {
                let p = Arc::new(RadialProfile::even_polynomial(vec![1.0, i as f64]).unwrap());
                assert!(map.mapped(&p, false).sampled.0.get().is_none(), "prepared early");
            }
            for (c, obliquity) in [(&amplitude, true), (&phase, false), (&amplitude, false)] {
                let poly = Arc::new(RadialProfile::even_polynomial(c.clone()).unwrap());
                let fast = map.mapped(&poly, obliquity);
                let slow = RadialProfile::finish(Kind::Mapped { inner: Some(poly.clone()), e2: map.e2, obliquity });
                assert!(fast.sampled.0.get().is_some() && fast.summary.0.get().is_some(), "not prepared");
                assert!(slow.sampled.0.get().is_none(), "the reference is generic");
                let size = slow.sampled().values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                for (a, b) in fast.sampled().values.iter().zip(&slow.sampled().values) {
                    assert!((a - b).abs() <= 1e-14 * size, "NA {na}: sample {a} vs {b}");
                }
                // both fitted to the rounding of their values, or neither (a series of degree
                // 64 does not hold it)
                match (&fast.sampled().series, &slow.sampled().series) {
                    (None, None) => {}
                    (Some((cf, ef)), Some((cs, es))) => {
                        series_compared += 1;
                        assert_eq!(cf.len(), cs.len(), "NA {na}: the same degree");
                        assert!((ef - es).abs() <= 1e-14 * size, "NA {na}: error {ef} vs {es}");
                        for k in 0..=64 {
                            let q = k as f64 / 64.0;
                            let (a, b) = (clenshaw(cf, q), clenshaw(cs, q));
                            assert!((a - b).abs() <= 1e-14 * size, "NA {na}: series at {q}: {a} vs {b}");
                        }
                    }
                    (f, s) => panic!("NA {na}, obliquity {obliquity}: series {} vs {}", f.is_some(), s.is_some()),
                }
                let (f, s) = (fast.summary(), slow.summary());
                assert!((f.fit - s.fit).abs() <= 1e-14 * size, "NA {na}: slope {} vs {}", f.fit, s.fit);
                assert!((f.mean_square - s.mean_square).abs() <= 1e-14 * size * size, "NA {na}: mean square");
                assert!((f.bounds.0 - s.bounds.0).abs() <= 1e-10 * s.bounds.0.max(size), "NA {na}: bound 1");
                assert!((f.bounds.1 - s.bounds.1).abs() <= 1e-8 * s.bounds.1.max(size), "NA {na}: bound 2");
            }
        }
        assert!(series_compared >= 2, "{series_compared} series compared");
    }

    /// The eight-lane reading of a profile ([`RadialProfile::value8`], the amplitudes' fast
    /// path) is the scalar reading to the last bit, for every kind it takes (a polynomial, a
    /// sphere, the obliquity `1/c²` and a polynomial through the direction-cosine map) and for
    /// a table (lane by lane), at points over the whole pupil.
    #[test]
    fn eight_lanes_read_as_one() {
        let map = DirectionCosines::new(0.7).unwrap();
        let poly = RadialProfile::even_polynomial(vec![0.9, -0.31, 0.17, -0.05, 0.013]).unwrap();
        let x: Vec<f64> = (0..=12).map(|i| i as f64 / 12.0).collect();
        let table = RadialProfile::table(x.clone(), x.iter().map(|r| 1.0 - 0.4 * r * r).collect()).unwrap();
        let profiles = [
            poly.clone(),
            RadialProfile::reference_sphere(0.672e-3, 3.36e-3).unwrap(),
            (*map.obliquity).clone(),
            (*map.mapped(&Arc::new(poly), true)).clone(),
            map.profile(RadialProfile::reference_sphere(1e-3, 2e-3).unwrap()),
            table.clone(),
            (*map.mapped(&Arc::new(table), true)).clone(),
        ];
        for (k, p) in profiles.iter().enumerate() {
            for start in 0..40 {
                let q: [f64; 8] = std::array::from_fn(|i| ((start * 8 + i) as f64 / 319.0).min(1.0));
                let lanes = p.value8(wide::f64x8::new(q)).to_array();
                for (qi, got) in q.iter().zip(lanes) {
                    assert_eq!(got.to_bits(), p.value(*qi).to_bits(), "profile {k} at q = {qi}");
                }
            }
        }
        assert!(!profiles[5].vectorizes() && !profiles[6].vectorizes() && profiles[3].vectorizes());
        // the product of two points' values, one division a lane in direction cosines
        for (k, p) in profiles.iter().enumerate() {
            for start in 0..40 {
                let q1: [f64; 8] = std::array::from_fn(|i| ((start * 8 + i) as f64 / 319.0).min(1.0));
                let q2: [f64; 8] = std::array::from_fn(|i| 1.0 - q1[i] * q1[i]);
                let lanes = p.product8(wide::f64x8::new(q1), wide::f64x8::new(q2)).to_array();
                for i in 0..8 {
                    let want = p.value(q1[i]) * p.value(q2[i]);
                    let error = (lanes[i] - want).abs() / want.abs().max(f64::MIN_POSITIVE);
                    assert!(error < 8.0 * f64::EPSILON, "profile {k} at {}, {}: {}", q1[i], q2[i], error);
                }
            }
        }
    }

    /// The short rules across v are the positive halves of the 8- and 16-point rules on
    /// `[−1, 1]` (the integrand is even in v): exact for `v^{2m}` to `m = 2n − 1` with n nodes
    /// (the n-point rule on `[0, 1]` before reached `m = n − 1`), and wherever [`small_rule`]
    /// takes one for `cos(φ₀ + θ v²)` or `cos(φ₀ + θ v⁴)` (θ from 0.01 to 12, accuracies 1e-12
    /// to 1e-4, φ₀ from 0 to 2.3) it integrates that within the 1 % of the accuracy it is
    /// allowed, against 64 panels of 16 points written here.
    #[test]
    fn short_rules_across_v_are_half_rules_within_their_models() {
        let four = small_rule(0.1, 0.0, 1e-3, &|_| 0.0).expect("the 4-node rule");
        let eight = small_rule(3.0, 0.0, 1e-3, &|_| 0.0).expect("the 8-node rule");
        assert_eq!((four.len(), eight.len()), (4, 8));
        for rule in [four, eight] {
            let n = rule.len();
            for m in 0..2 * n {
                let got: f64 = rule.iter().map(|&(v, w)| w * v.powi(2 * m as i32)).sum();
                let want = 1.0 / (2 * m + 1) as f64;
                assert!((got - want).abs() < 1e-14, "{n} nodes, v^{}: {got} vs {want}", 2 * m);
            }
        }
        let reference = |f: &dyn Fn(f64) -> f64| {
            let mut sum = 0.0;
            crate::quad::for_each_node(0.0, 1.0, 64, |v, w| sum += w * f(v));
            sum
        };
        let mut taken = [0usize; 2];
        for power in [2, 4] {
            for i in 0..=60 {
                let theta = 0.01 * 1200f64.powf(i as f64 / 60.0);
                // the v⁴ shape's phase is all in the terms of degree 3 and up (`higher`)
                let higher = if power == 4 { theta } else { 0.0 };
                for accuracy in [1e-12, 1e-10, 1e-8, 1e-6, 1e-4] {
                    let Some(rule) = small_rule(theta, higher, accuracy, &|_| 0.0) else { continue };
                    taken[usize::from(rule.len() == 8)] += 1;
                    for j in 0..=5 {
                        let phi = 2.3 * j as f64 / 5.0;
                        let f = |v: f64| (phi + theta * v.powi(power)).cos();
                        let got: f64 = rule.iter().map(|&(v, w)| w * f(v)).sum();
                        let error = (got - reference(&f)).abs();
                        assert!(
                            error <= 1e-2 * accuracy + 1e-15,
                            "v^{power}, θ {theta}, accuracy {accuracy:e}, {} nodes: {error:e}",
                            rule.len()
                        );
                    }
                }
            }
        }
        assert!(taken.iter().all(|&n| n > 20), "{taken:?}");
    }

    /// Z11's polynomial in q is √5 (6q² − 6q + 1); Z22's √7 (20q³ − 30q² + 12q − 1).
    #[test]
    fn zernike_radial_polynomials() {
        let z11 = zernike_radial_q(4);
        let r5 = 5f64.sqrt();
        for (got, want) in z11.iter().zip([r5, -6.0 * r5, 6.0 * r5]) {
            assert!((got - want).abs() < 1e-14);
        }
        let z22 = zernike_radial_q(6);
        let r7 = 7f64.sqrt();
        for (got, want) in z22.iter().zip([-r7, 12.0 * r7, -30.0 * r7, 20.0 * r7]) {
            assert!((got - want).abs() < 1e-13);
        }
    }

    /// The sag of the reference sphere against its direct form, and its fitted slope against the
    /// least-squares slope computed here by a fine midpoint sum (200 000 points: its rounding is about 1e-11 relative).
    #[test]
    fn sphere_sag_and_fit() {
        let (r, z) = (0.672e-3, 3.36e-3);
        let p = RadialProfile::reference_sphere(r, z).unwrap();
        for i in 0..=10 {
            let q = i as f64 / 10.0;
            let direct = (r * r * q + z * z).sqrt() - z;
            assert!((p.value(q) - direct).abs() < 1e-18);
        }
        let n = 200_000;
        let slope: f64 = (0..n)
            .map(|i| {
                let q = (i as f64 + 0.5) / n as f64;
                12.0 * (q - 0.5) * p.value(q) / n as f64
            })
            .sum();
        assert!((p.fitted_slope() - slope).abs() < 1e-10 * slope.abs(), "{} vs {slope}", p.fitted_slope());
    }

    /// The paper's aperture as a geometric-phase metalens at `lambda` (m): the hyperbolic phase as
    /// four Binary 2 terms and the exact reference sphere, the order's defocus the pupil's fit.
    fn binary2_order(lambda: f64) -> RadialOrder {
        let (r, f, l0): (f64, f64, f64) = (0.672e-3, 3.36e-3, 800e-9);
        let k0 = std::f64::consts::TAU / l0;
        let a = [
            0.0,
            -k0 * r.powi(2) / (2.0 * f),
            k0 * r.powi(4) / (8.0 * f.powi(3)),
            -k0 * r.powi(6) / (16.0 * f.powi(5)),
            k0 * 5.0 * r.powi(8) / (128.0 * f.powi(7)),
        ];
        let phase = Arc::new(RadialProfile::even_polynomial(a.to_vec()).unwrap());
        let sphere = Arc::new(RadialProfile::reference_sphere(r, f).unwrap());
        let terms = vec![(lambda / std::f64::consts::TAU, phase), (1.0, sphere)];
        let pupil = Arc::new(RadialPupil::new(None, terms, vec![]).unwrap());
        let w020 = pupil.fitted_defocus_m();
        RadialOrder::new(pupil, w020, lambda)
    }

    /// The lane of an amplitude and a phase direction together
    /// ([`RadialOrder::otf_and_field_derivative`]) against central differences of the OTF of
    /// the pupil moved along both (Richardson of steps 1e-3 and 5e-4 of the parameter, each OTF
    /// to 1e-13): a Binary 2 metalens's wavefront (the paper's aperture at 780 nm) with an
    /// amplitude `1 − 0.3q + 0.1q²`, moved along `∂A = 0.1 + 0.2q` and `∂W = 40 nm (q − q²)`,
    /// at six frequencies to s = 0.9; within 1e-9 (the value is `otf`'s to 1e-13).
    #[test]
    fn amplitude_and_phase_lane_matches_differences() {
        let (r, f, l0, lambda): (f64, f64, f64, f64) = (0.672e-3, 3.36e-3, 800e-9, 780e-9);
        let k0 = std::f64::consts::TAU / l0;
        let a = vec![0.0, -k0 * r.powi(2) / (2.0 * f), k0 * r.powi(4) / (8.0 * f.powi(3))];
        let phase = Arc::new(RadialProfile::even_polynomial(a).unwrap());
        let sphere = Arc::new(RadialProfile::reference_sphere(r, f).unwrap());
        let d_amplitude = RadialProfile::even_polynomial(vec![0.1, 0.2]).unwrap();
        let d_wavefront = RadialProfile::even_polynomial(vec![0.0, 40e-9, -40e-9]).unwrap();
        let order = |b: f64| {
            let amplitude = RadialProfile::even_polynomial(vec![1.0 + 0.1 * b, -0.3 + 0.2 * b, 0.1]).unwrap();
            let moved = Arc::new(RadialProfile::even_polynomial(vec![0.0, 40e-9 * b, -40e-9 * b]).unwrap());
            let terms = vec![(lambda / std::f64::consts::TAU, phase.clone()), (1.0, sphere.clone()), (1.0, moved)];
            let pupil = Arc::new(RadialPupil::new(Some(Arc::new(amplitude)), terms, vec![]).unwrap());
            let w020 = pupil.fitted_defocus_m();
            RadialOrder::new(pupil, w020, lambda)
        };
        let at = order(0.0);
        for s in [0.05, 0.2, 0.4, 0.6, 0.75, 0.9] {
            let (value, derivative) = at.otf_and_field_derivative(s, 1e-13, &d_amplitude, &d_wavefront);
            assert!((value - at.otf(s, 1e-13)).abs() < 1e-13, "s {s}: {value} vs {}", at.otf(s, 1e-13));
            let central = |h: f64| (order(h).otf(s, 1e-13) - order(-h).otf(s, 1e-13)) / (2.0 * h);
            let richardson = (4.0 * central(5e-4) - central(1e-3)) / 3.0;
            println!("s {s}: derivative {derivative:.6e}, differences {richardson:.6e}");
            assert!((derivative - richardson).abs() < 1e-9, "s {s}: {derivative} vs {richardson}");
        }
    }

    /// The lanes that ride on the value ([`RadialOrder::otf_and_field_derivatives`]): the value
    /// is [`RadialOrder::otf`]'s bit for bit (the frequency rule reading it makes the value's
    /// decisions), and each lane is the lane-by-lane reference
    /// ([`RadialOrder::otf_and_field_derivative`], whose derivative is tested against
    /// differences above) to rounding, 1e-12: the test above's pupil with and without its
    /// amplitude, two directions at once, at three accuracies and six frequencies.
    #[test]
    fn field_lanes_ride_on_the_value_bit_for_bit() {
        let (r, f, l0, lambda): (f64, f64, f64, f64) = (0.672e-3, 3.36e-3, 800e-9, 780e-9);
        let k0 = std::f64::consts::TAU / l0;
        let a = vec![0.0, -k0 * r.powi(2) / (2.0 * f), k0 * r.powi(4) / (8.0 * f.powi(3))];
        let phase = Arc::new(RadialProfile::even_polynomial(a).unwrap());
        let sphere = Arc::new(RadialProfile::reference_sphere(r, f).unwrap());
        let directions = [
            (
                RadialProfile::even_polynomial(vec![0.1, 0.2]).unwrap(),
                RadialProfile::even_polynomial(vec![0.0, 40e-9, -40e-9]).unwrap(),
            ),
            (
                RadialProfile::even_polynomial(vec![-0.05, 0.0, 0.3]).unwrap(),
                RadialProfile::even_polynomial(vec![5e-9, 0.0, 0.0, 20e-9]).unwrap(),
            ),
        ];
        let fields: Vec<(&RadialProfile, &RadialProfile)> = directions.iter().map(|(a, w)| (a, w)).collect();
        for amplitude in [Some(vec![1.0, -0.3, 0.1]), None] {
            let amplitude = amplitude.map(|c| Arc::new(RadialProfile::even_polynomial(c).unwrap()));
            let terms = vec![(lambda / std::f64::consts::TAU, phase.clone()), (1.0, sphere.clone())];
            let pupil = Arc::new(RadialPupil::new(amplitude, terms, vec![]).unwrap());
            let w020 = pupil.fitted_defocus_m();
            let order = RadialOrder::new(pupil, w020, lambda);
            assert!(order.proxy.is_some());
            for accuracy in [1e-13, 1e-7, 1e-4] {
                for s in [0.0, 0.05, 0.2, 0.4, 0.75, 0.9, 1.0] {
                    let mut lanes = [0.0; 2];
                    let value = order.otf_and_field_derivatives(s, accuracy, &fields, &mut lanes);
                    assert_eq!(value.to_bits(), order.otf(s, accuracy).to_bits(), "s {s}, accuracy {accuracy}");
                    for (lane, (d_a, d_w)) in lanes.iter().zip(&directions) {
                        let (v, reference) = order.otf_and_field_derivative(s, accuracy, d_a, d_w);
                        assert!((v - value).abs() < 1e-12, "s {s}: {v} vs {value}");
                        assert!((lane - reference).abs() < 1e-12, "s {s}, accuracy {accuracy}: {lane} vs {reference}");
                    }
                }
            }
        }
    }

    /// The phase proxy a wavelength's pupil sums from its terms' cached series equals, within the
    /// two error bounds, the proxy fitted to the pupil's own phase (the slow path, evaluating
    /// the profiles), and both the phase itself; the OTF cut to a loose accuracy drops terms and
    /// stays within that accuracy of the full series' OTF.
    #[test]
    fn summed_and_cut_proxies_hold_their_bounds() {
        for lambda in [700e-9, 800e-9, 905e-9] {
            let order = binary2_order(lambda);
            let summed = order.proxy.as_ref().expect("polynomial and sphere terms have series");
            let k = std::f64::consts::TAU / lambda;
            let pupil = order.pupil.clone();
            let exact = |q: f64| k * pupil.opd_beyond_defocus_m(q);
            // to the rounding of the exact evaluation's terms, as `RadialOrder::new` fits it
            let size = (0..=16).map(|j| pupil.opd_magnitude_m(j as f64 / 16.0)).fold(0.0, f64::max);
            let fitted = phase_proxy(&exact, 4.0 * f64::EPSILON * k * size).expect("the phase has a series");
            let bound = summed.tails[summed.coefficients.len()] + fitted.tails[fitted.coefficients.len()];
            for i in 0..=200 {
                let q = i as f64 / 200.0;
                let (a, b) = (clenshaw(&summed.coefficients, q), clenshaw(&fitted.coefficients, q));
                assert!((a - b).abs() <= bound, "λ {lambda:e}, q {q}: {a} vs {b} (bound {bound:e})");
                assert!((a - exact(q)).abs() <= 2.0 * bound, "λ {lambda:e}, q {q}");
            }
            // cut to an OTF accuracy of 1e-4: fewer terms, the OTF within 1e-4 of the full one's
            let (loose, tight) = (summed.cut(0.25e-4).len(), summed.cut(0.25e-14).len());
            assert!(loose < tight, "λ {lambda:e}: {loose} vs {tight} terms");
            for s in [0.02, 0.1, 0.19, 0.5] {
                let (a, b) = (order.otf(s, 1e-4), order.otf(s, 1e-13));
                assert!((a - b).abs() <= 1e-4, "λ {lambda:e}, s {s}: {a} vs {b}");
            }
        }
    }

    /// The rule [`RadialOrder::otf`] picks for an accuracy holds it: against the same integral by
    /// two 16-point panels across v and three times the t panels (the full phase series), the
    /// Binary 2 metalens's OTF at 1e-12 over the band and the frequencies up to twice Nyquist.
    /// (A 3-point rule across v by the same phase estimate was 1e-11 off here.)
    #[test]
    fn the_chosen_rule_holds_a_tight_accuracy() {
        let rule16 = crate::quad::rule();
        let v_fine: Vec<(f64, f64)> = (0..2)
            .flat_map(|p| rule16.iter().map(move |&(x, w)| (0.25 * (2 * p + 1) as f64 + 0.25 * x, 0.25 * w)))
            .collect();
        for lambda in [700e-9, 760e-9, 800e-9, 850e-9, 905e-9] {
            let order = binary2_order(lambda);
            let full = order.proxy.as_ref().map(|p| p.coefficients.as_slice());
            for s in [0.01, 0.05, 0.1, 0.19, 0.38] {
                let t_end = f64::acos(s);
                let nodes = Nodes::Tensor { t_end, t_panels: 12, v_nodes: v_fine.clone().into() };
                let fine = 4.0 * order.direct(s, &nodes, full) / std::f64::consts::PI;
                let got = order.otf(s, 1e-12);
                assert!((got - fine).abs() <= 1e-12, "λ {lambda:e}, s {s}: {got} vs {fine}");
            }
        }
    }

    /// The OTF's derivatives with respect to the Binary 2 coefficients (radians of phase at
    /// `q^j`, the geometric-phase dispersion: `∂W/∂a_j = (λ/2π) q^j`), on the value's nodes,
    /// against central differences of converged OTFs (accuracy 1e-13) of pupils rebuilt with
    /// `a_j ± h` (their best-fit defocus, carried by the order, refitted), with
    /// `h = (3 · 1e-13 / |f‴|)^{1/3}` ≈ 1e-4 (docs/physics.md, "Gradients"; `f‴` of order one
    /// per radian³): truncation `h²/6` and rounding `1e-13/h` both below 2e-9.
    #[test]
    fn binary2_derivatives_match_central_differences() {
        let (r, f, l0): (f64, f64, f64) = (0.672e-3, 3.36e-3, 800e-9);
        let k0 = std::f64::consts::TAU / l0;
        let base = [
            0.0,
            -k0 * r.powi(2) / (2.0 * f),
            k0 * r.powi(4) / (8.0 * f.powi(3)),
            -k0 * r.powi(6) / (16.0 * f.powi(5)),
            k0 * 5.0 * r.powi(8) / (128.0 * f.powi(7)),
        ];
        let order_with = |lambda: f64, a: &[f64], sphere_coefficient: f64| {
            let phase = Arc::new(RadialProfile::even_polynomial(a.to_vec()).unwrap());
            let sphere = Arc::new(RadialProfile::reference_sphere(r, f).unwrap());
            let terms = vec![(lambda / std::f64::consts::TAU, phase), (sphere_coefficient, sphere)];
            let pupil = Arc::new(RadialPupil::new(None, terms, vec![]).unwrap());
            let w020 = pupil.fitted_defocus_m();
            RadialOrder::new(pupil, w020, lambda)
        };
        let order = |lambda: f64, a: &[f64]| order_with(lambda, a, 1.0);
        let h = 1e-4;
        for lambda in [760e-9, 800e-9, 850e-9] {
            // a small defocus of the design too, so that the sine part is not small
            let mut design = base.to_vec();
            design[1] += 3.0;
            let directions: Vec<RadialProfile> = (1..=4)
                .map(|j| {
                    let mut c = vec![0.0; j + 1];
                    c[j] = lambda / std::f64::consts::TAU;
                    RadialProfile::even_polynomial(c).unwrap()
                })
                .collect();
            let at = order(lambda, &design);
            for s in [0.02, 0.1, 0.19, 0.38, 0.7] {
                let mut got = [0.0; 4];
                let value = at.otf_and_derivatives(s, 1e-13, &directions, &mut got);
                assert!((value - at.otf(s, 1e-13)).abs() <= 1e-12, "λ {lambda:e}, s {s}");
                let norm = got.iter().map(|g| g * g).sum::<f64>().sqrt();
                for j in 1..=4 {
                    let (mut up, mut down) = (design.clone(), design.clone());
                    up[j] += h;
                    down[j] -= h;
                    let fd = (order(lambda, &up).otf(s, 1e-13) - order(lambda, &down).otf(s, 1e-13)) / (2.0 * h);
                    assert!(
                        (got[j - 1] - fd).abs() <= 1e-8 * norm.max(1e-3),
                        "λ {lambda:e}, s {s}, a{j}: {} vs {fd} (norm {norm:e})",
                        got[j - 1]
                    );
                }
                // a direction that is not an even polynomial (the sphere's sag, m per unit of
                // its term's coefficient, ~530 rad per unit: h = 2e-7) takes the lane-by-lane
                // path for all five: the same four derivatives, and the fifth against its own
                // central difference
                let mut with_sphere: Vec<RadialProfile> = directions.clone();
                with_sphere.push(RadialProfile::reference_sphere(r, f).unwrap());
                let mut lane = [0.0; 5];
                at.otf_and_derivatives(s, 1e-13, &with_sphere, &mut lane);
                for j in 0..4 {
                    assert!((lane[j] - got[j]).abs() <= 1e-12 * norm.max(1.0), "λ {lambda:e}, s {s}, a{}", j + 1);
                }
                let hs = 2e-7;
                let fd = (order_with(lambda, &design, 1.0 + hs).otf(s, 1e-13)
                    - order_with(lambda, &design, 1.0 - hs).otf(s, 1e-13))
                    / (2.0 * hs);
                assert!(
                    (lane[4] - fd).abs() <= 1e-8 * lane[4].abs().max(1.0),
                    "λ {lambda:e}, s {s}: {} vs {fd}",
                    lane[4]
                );
            }
        }
    }

    /// The eight-lane Clenshaw recurrence is the scalar one lane by lane (the same fused
    /// operations: equal to the bit), and the lane-wise sums are the plain sums within rounding,
    /// also for lane counts that are not a multiple of eight.
    #[test]
    fn lanes_match_the_scalar_recurrence() {
        let c: Vec<f64> = (0..18).map(|k| (k as f64 + 1.0).recip() * if k % 2 == 0 { 3.0 } else { -2.0 }).collect();
        for n in [1, 7, 8, 13, 64, 67] {
            let q: Vec<f64> = (0..n).map(|i| ((i as f64 + 0.5) / n as f64).powi(2)).collect();
            for block in q.chunks_exact(8) {
                let lanes = clenshaw8(&c, load8(block, 0)).to_array();
                for (o, &q) in lanes.iter().zip(block) {
                    assert_eq!(o.to_bits(), clenshaw(&c, q).to_bits(), "q = {q}");
                }
            }
            // the recurrences side by side: each block as alone, for every degree the proxies
            // are cut to
            for d in 1..=c.len() {
                let blocks: Vec<wide::f64x8> = q.chunks_exact(8).map(|b| load8(b, 0)).collect();
                let reversed: Vec<wide::f64x8> = blocks.iter().rev().copied().collect();
                for (four, two) in blocks.chunks_exact(4).zip(reversed.chunks_exact(2)) {
                    let together = clenshaw8_blocks(&c[..d], [four[0], four[1], four[2], four[3]]);
                    let pair = clenshaw8_blocks(&c[..d], [two[0], two[1]]);
                    for (got, &q) in together.iter().chain(&pair).zip(four.iter().chain(two)) {
                        let alone = clenshaw8(&c[..d], q).to_array();
                        for (g, a) in got.to_array().iter().zip(alone) {
                            assert_eq!(g.to_bits(), a.to_bits(), "degree {d}");
                        }
                    }
                }
            }
            let w: Vec<f64> = q.iter().map(|q| 1.0 - q).collect();
            let a: Vec<f64> = q.iter().map(|q| 40.0 * q).collect();
            let b: Vec<f64> = q.iter().map(|q| 3.0 * q * q).collect();
            let plain: f64 = (0..n).map(|i| w[i] * (a[i] - b[i]).cos()).sum();
            assert!((cosine_sum(&w, &a, &b) - plain).abs() < 1e-13 * n as f64, "n = {n}");
            // the fused phase: 37 (q₁ − q₂) + p(q₁) − p(q₂), q₂ = q₁²
            let q2: Vec<f64> = q.iter().map(|q| q * q).collect();
            let fused = proxy_cosine_sum(&c, 37.0, &q, &q2, &w);
            let plain: f64 =
                (0..n).map(|i| w[i] * (37.0 * (q[i] - q2[i]) + clenshaw(&c, q[i]) - clenshaw(&c, q2[i])).cos()).sum();
            assert!((fused - plain).abs() < 1e-13 * n as f64, "n = {n}: {fused} vs {plain}");
        }
    }
}

#[cfg(test)]
mod split_tests {
    use super::*;

    /// The order at `lambda` of a geometric-phase lens whose phase is the spline through `knots`
    /// equally spaced samples (axis to rim, as `lens.phase_spline_rad`) of the hyperbolic phase
    /// −(2π/λ0)(√(r² + f0²) − f0) of the paper's aperture (R = 0.672 mm, f0 = 3.36 mm, λ0 =
    /// 800 nm; about 530 rad at the rim), against the reference sphere, the order carrying the
    /// best-fit defocus (as `lenses::PhaseLens` builds it).
    fn spline_order(knots: usize, lambda: f64) -> RadialOrder {
        let (f0, radius, l0) = (3.36e-3_f64, 0.672e-3_f64, 800e-9_f64);
        let k0 = std::f64::consts::TAU / l0;
        let rho: Vec<f64> = (0..knots).map(|i| i as f64 / (knots - 1) as f64).collect();
        let values = rho.iter().map(|p| -k0 * (((radius * p).powi(2) + f0 * f0).sqrt() - f0)).collect();
        let spline = Arc::new(RadialProfile::table(rho, values).unwrap());
        let sphere = Arc::new(RadialProfile::reference_sphere(radius, f0).unwrap());
        let terms = vec![(lambda / std::f64::consts::TAU, spline), (1.0, sphere)];
        let pupil = RadialPupil::new(None, terms, vec![]).unwrap();
        let w020 = pupil.fitted_defocus_m();
        RadialOrder::new(Arc::new(pupil), w020, lambda)
    }

    /// `∫_a^b f` by bisection until the 8- and 16-point Gauss–Legendre rules of an interval agree
    /// within its share of `tol` (absolute): knots anywhere, found by the bisection alone.
    fn adaptive(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64, depth: usize) -> f64 {
        let rule = |n: usize| {
            let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
            crate::quad::gauss_legendre(n).iter().map(|&(x, w)| h * w * f(c + h * x)).sum::<f64>()
        };
        let (coarse, fine) = (rule(8), rule(16));
        if (fine - coarse).abs() <= tol || depth == 0 {
            return fine;
        }
        let m = 0.5 * (a + b);
        adaptive(f, a, m, 0.5 * tol, depth - 1) + adaptive(f, m, b, 0.5 * tol, depth - 1)
    }

    /// The OTF at `s` by the module's integral (module docs), each of its two integrals
    /// [`adaptive`] to `tol`: the whole OPD `W020 q + opd_beyond_defocus_m(q)` read lane by lane.
    fn reference(order: &RadialOrder, s: f64, tol: f64) -> f64 {
        let k = std::f64::consts::TAU / order.wavelength_m;
        let w = |q: f64| order.w020_m * q + order.pupil.opd_beyond_defocus_m(q);
        let row = |t: f64| {
            let (sin_t, cos_t) = t.sin_cos();
            let f = |v: f64| {
                let q1 = cos_t * cos_t + v * v * sin_t * sin_t;
                let q2 = (q1 - 4.0 * s * (cos_t - s)).max(0.0);
                order.pupil.amplitude(q1) * order.pupil.amplitude(q2) * (k * (w(q1) - w(q2))).cos()
            };
            sin_t * sin_t * adaptive(&f, 0.0, 1.0, tol, 40)
        };
        4.0 * adaptive(&row, 0.0, s.acos(), tol, 40) / (std::f64::consts::PI * order.pupil.power())
    }

    /// The rule split at the knots (`RadialOrder::split_nodes`) holds the accuracy asked on the
    /// 17-knot spline of the hyperbolic phase, in focus (λ0) and 25 nm off (a few waves of
    /// defocus), at low, middle and high frequencies, against [`reference`] to 1e-13. (The
    /// tensor rule it replaces for tables was 3e-7 to 7e-6 off here at every accuracy from 1e-6
    /// to 1e-10.) Analytic profiles keep the tensor rule: no knots.
    #[test]
    fn split_rule_holds_the_accuracy_on_a_spline() {
        // the tensor rule (the default) misses the accuracy 1e-8 somewhere: the split rule's reason
        let mut tensor_worst: f64 = 0.0;
        for lambda in [800e-9, 825e-9] {
            let tensor = spline_order(17, lambda);
            let order = spline_order(17, lambda).with_table_rule(TableRule::Split);
            assert_eq!(order.knots.len(), 15);
            for s in [0.05, 0.2, 0.45] {
                let reference = reference(&order, s, 1e-13);
                assert!(matches!(tensor.rule(s, 1e-8).0, Nodes::Tensor { .. }));
                tensor_worst = tensor_worst.max((tensor.otf(s, 1e-8) - reference).abs());
                for accuracy in [1e-6, 1e-8, 1e-10] {
                    assert!(matches!(order.rule(s, accuracy).0, Nodes::Split { .. }));
                    let got = order.otf(s, accuracy);
                    let lanes = match order.rule(s, accuracy).0 {
                        Nodes::Split { weight, .. } => weight.len(),
                        _ => 0,
                    };
                    eprintln!("λ {lambda:e} s {s} accuracy {accuracy:e}: lanes {lanes} error {:.1e}", got - reference);
                    assert!(
                        (got - reference).abs() <= accuracy,
                        "λ {lambda:e}, s {s}, accuracy {accuracy:e}: {got} vs {reference} ({:.1e})",
                        got - reference
                    );
                }
            }
        }
        eprintln!("the tensor rule at the accuracy 1e-8: largest error {tensor_worst:.1e}");
        assert!(tensor_worst > 1e-8, "the tensor rule within 1e-8 ({tensor_worst:.1e}): the test shows nothing");
        let pupil = RadialPupil::new(
            None,
            vec![(1e-7, Arc::new(RadialProfile::even_polynomial(vec![0.0, 1.0, 2.0]).unwrap()))],
            vec![],
        );
        let analytic = RadialOrder::new(Arc::new(pupil.unwrap()), 1e-7, 800e-9).with_table_rule(TableRule::Split);
        assert!(analytic.knots.is_empty() && matches!(analytic.rule(0.2, 1e-8).0, Nodes::Tensor { .. }));
    }
}
