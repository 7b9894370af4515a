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
    /// A cubic spline through `(ρ_i, value_i)`, zero slope at `ρ = 0`.
    Table(Spline),
}

/// A function of the normalized pupil radius `ρ ∈ [0, 1]`: a wavefront term (metres, or radians
/// of phase scaled by the caller) or a field amplitude. Immutable; build once, share in an `Arc`.
#[derive(Clone, Debug, PartialEq)]
pub struct RadialProfile {
    kind: Kind,
    /// least-squares slope in `q` over `[0, 1]` (the best-fit defocus per unit of the profile)
    fit: f64,
    /// `max |f'(q)|`, `max |f''(q)|` on `[0, 1]`, sampled
    bounds: (f64, f64),
    /// `∫_0^1 f(q)² dq` (the power of an amplitude profile)
    mean_square: f64,
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

    fn finish(kind: Kind) -> RadialProfile {
        let mut p = RadialProfile { kind, fit: 0.0, bounds: (0.0, 0.0), mean_square: 0.0 };
        // least-squares slope 12 ∫(q − ½) f dq and the mean square, by 8 panels of 16 points
        let (mut slope, mut square) = (0.0, 0.0);
        crate::quad::for_each_node(0.0, 1.0, 8, |q, w| {
            let f = p.value(q);
            slope += w * 12.0 * (q - 0.5) * f;
            square += w * f * f;
        });
        p.fit = slope;
        p.mean_square = square;
        p.bounds = derivative_bounds(|q| p.value(q));
        p
    }

    /// The value at `q = ρ²` (`q ∈ [0, 1]`; the table's last piece continues beyond).
    #[inline]
    pub fn value(&self, q: f64) -> f64 {
        match &self.kind {
            Kind::Even(c) => c.iter().rev().fold(0.0, |acc, &ci| acc * q + ci),
            // written without the cancellation of √(z² + R²q) − z at small q
            Kind::Sphere { r2, z } => r2 * q / ((z * z + r2 * q).sqrt() + z),
            Kind::Table(s) => s.value(q.max(0.0).sqrt()),
        }
    }

    /// The least-squares slope of the profile in `q = ρ²` over the pupil (uniform in area):
    /// its best-fit defocus per unit.
    pub fn fitted_slope(&self) -> f64 {
        self.fit
    }

    /// `∫_0^1 f(q)² dq`: the power of an amplitude profile over the pupil, relative to a
    /// uniform amplitude of 1.
    pub fn mean_square(&self) -> f64 {
        self.mean_square
    }

    /// Whether the profile is a table (knots limit the smoothness the rule may assume).
    fn knots(&self) -> usize {
        match &self.kind {
            Kind::Table(s) => s.x.len(),
            _ => 0,
        }
    }
}

/// `(max |f'|, max |f''|)` of `f` on `[0, 1]` from differences at [`BOUND_SAMPLES`] + 1 points,
/// with a margin of 25 % for what falls between them.
fn derivative_bounds(f: impl Fn(f64) -> f64) -> (f64, f64) {
    let h = 1.0 / BOUND_SAMPLES as f64;
    let values: Vec<f64> = (0..=BOUND_SAMPLES).map(|i| f(i as f64 * h)).collect();
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
        Ok(Spline { x, y, m })
    }

    fn value(&self, t: f64) -> f64 {
        let n = self.x.len();
        let i = self.x.partition_point(|&xi| xi <= t).clamp(1, n - 1) - 1;
        let h = self.x[i + 1] - self.x[i];
        let (a, b) = ((self.x[i + 1] - t) / h, (t - self.x[i]) / h);
        a * self.y[i]
            + b * self.y[i + 1]
            + ((a * a * a - a) * self.m[i] + (b * b * b - b) * self.m[i + 1]) * h * h / 6.0
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
        let mut pupil = RadialPupil { oblique: None, amplitude, terms, zernike_noll_m, zernike_even, fit: 0.0 };
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

    /// The off-axis part of the OPD (m) at normalized pupil coordinates `(x, y)` (0 on axis).
    pub fn oblique_opd_m(&self, x: f64, y: f64) -> f64 {
        self.oblique.map_or(0.0, |o| o.opd_m(x, y))
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

    /// `∫|P|² dA / π`: the pupil's power relative to a uniform amplitude of 1.
    pub fn power(&self) -> f64 {
        self.amplitude.as_ref().map_or(1.0, |a| a.mean_square())
    }

    /// This pupil with `zernike_noll_m` added to its Zernike terms.
    pub fn with_zernike(&self, zernike_noll_m: &[(usize, f64)]) -> Result<RadialPupil, Error> {
        let mut all = self.zernike_noll_m.clone();
        all.extend_from_slice(zernike_noll_m);
        RadialPupil::new(self.amplitude.clone(), self.terms.clone(), all)
    }
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
    /// extra phase-equivalent (radians) for an amplitude table's knots
    amplitude_turns: f64,
    /// the phase beyond the defocus, `k (W(q) − W020 q)` (radians), as a Chebyshev series in
    /// `x = 2q − 1`, where one of at most [`PROXY_MAX_DEGREE`] holds it to
    /// [`PROXY_PHASE_ERROR`] (evaluated by Clenshaw's recurrence instead of the profile's own
    /// terms: a table's spline search, a sphere's root)
    proxy: Option<Vec<f64>>,
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

/// `out[i] = Σ c_k T_k(2q_i − 1)` for every lane, by Clenshaw's recurrence run over eight lanes
/// at once (coefficient by coefficient): the same operations as [`clenshaw`] on each lane, in
/// loops the compiler vectorizes.
fn clenshaw_lanes(c: &[f64], q: &[f64], out: &mut [f64]) {
    // blocks of eight lanes whose recurrences stay in registers through the coefficients
    const L: usize = 8;
    let block = |q: &[f64], out: &mut [f64]| {
        let mut x2 = [0.0; L];
        for l in 0..L {
            x2[l] = 2.0 * (2.0 * q[l] - 1.0);
        }
        let (mut b1, mut b2) = ([0.0; L], [0.0; L]);
        for &ck in c[1..].iter().rev() {
            for l in 0..L {
                (b1[l], b2[l]) = (crate::quad::fused(x2[l], b1[l], ck - b2[l]), b1[l]);
            }
        }
        for l in 0..L {
            out[l] = c[0] + 0.5 * x2[l] * b1[l] - b2[l];
        }
    };
    let n = q.len() / L * L;
    for (q, out) in q[..n].chunks_exact(L).zip(out[..n].chunks_exact_mut(L)) {
        block(q, out);
    }
    for (o, &q) in out[n..].iter_mut().zip(&q[n..]) {
        *o = clenshaw(c, q);
    }
}

/// `Σ_i w_i cos(a_i − b_i)` in eight partial sums (the cosine of each lane vectorizes; one chain
/// of dependent adds would be bound by its latency).
fn cosine_sum(w: &[f64], a: &[f64], b: &[f64]) -> f64 {
    const L: usize = 8;
    let mut acc = [0.0; L];
    let n = w.len() / L * L;
    for ((w, a), b) in w[..n].chunks_exact(L).zip(a[..n].chunks_exact(L)).zip(b[..n].chunks_exact(L)) {
        for l in 0..L {
            acc[l] += w[l] * crate::fft::cis::sin_cos(a[l] - b[l]).1;
        }
    }
    let mut total: f64 = acc.iter().sum();
    for i in n..w.len() {
        total += w[i] * crate::fft::cis::sin_cos(a[i] - b[i]).1;
    }
    total
}

/// Fills the lanes `row..row + v_nodes.len()` of one t node: `q₁` at `q[l]`, `q₂` at
/// `q[lanes + l]`, the weight `scale × w_v` at `weight[l]`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn fill_row(
    s: f64,
    sin_t: f64,
    cos_t: f64,
    v_nodes: &[(f64, f64)],
    scale: f64,
    q: &mut [f64],
    weight: &mut [f64],
    row: usize,
    lanes: usize,
) {
    let sin2 = sin_t * sin_t;
    let delta = 4.0 * s * (cos_t - s);
    for (j, &(v, wv)) in v_nodes.iter().enumerate() {
        let q1 = cos_t * cos_t + v * v * sin2;
        q[row + j] = q1;
        // q₂ = (cos t − 2s)² + v² sin²t ≥ 0; the clamp holds it there through rounding
        q[lanes + row + j] = (q1 - delta).max(0.0);
        weight[row + j] = scale * wv;
    }
}

/// The proxy of `phase` ([`RadialOrder`]): the first degree of 8, 16, 32, 64 whose last four
/// coefficients sum below a tenth of the error allowed and whose values at the midpoints of the
/// next finer grid agree within it; `None` otherwise. The error allowed is
/// [`PROXY_PHASE_ERROR`], or the rounding of the phase's own size (1e-15 of its largest
/// coefficient), or `rounding`, the rounding of the exact evaluation's terms (radians): the
/// proxy is then as accurate as the evaluation it replaces.
fn phase_proxy(phase: &dyn Fn(f64) -> f64, rounding: f64) -> Option<Vec<f64>> {
    let mut n = 8;
    while n <= PROXY_MAX_DEGREE {
        let c = chebyshev_fit(phase, n);
        let size = c.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let allowed = PROXY_PHASE_ERROR.max(1e-15 * size).max(rounding);
        let tail: f64 = c[n - 3..].iter().map(|v| v.abs()).sum();
        if tail <= 0.1 * allowed {
            let checked = (0..2 * n).all(|j| {
                let x = (std::f64::consts::PI * (j as f64 + 0.5) / (2 * n) as f64).cos();
                let q = 0.5 * (x + 1.0);
                (clenshaw(&c, q) - phase(q)).abs() <= allowed
            });
            if checked {
                return Some(c);
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
        let residual: Vec<f64> = (0..=BOUND_SAMPLES).map(|i| pupil.opd_beyond_defocus_m(i as f64 * h)).collect();
        let residual_slopes: Vec<f64> = residual.windows(2).map(|w| (w[1] - w[0]) / h).collect();
        let slopes: Vec<f64> = residual_slopes.iter().map(|d| w020_m + d).collect();
        let slope = 1.25 * slopes.iter().map(|v| v.abs()).fold(0.0, f64::max);
        // windows of 2^j samples by doubling: max and min over [i, i + 2m) from those of m, in
        // place (entry i reads entry i + m before it is overwritten)
        let (mut hi, mut lo) = (slopes.clone(), slopes.clone());
        // two neighbouring slopes differ by the second difference: a window of one sample holds
        // the change across it
        let across = slopes.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, f64::max);
        let mut oscillation = Vec::new();
        let mut width = 1;
        loop {
            let osc = hi.iter().zip(&lo).map(|(h, l)| h - l).fold(0.0, f64::max);
            oscillation.push(1.25 * (osc + across));
            if width >= BOUND_SAMPLES {
                break;
            }
            let n = hi.len() - width;
            for i in 0..n {
                hi[i] = hi[i].max(hi[i + width]);
                lo[i] = lo[i].min(lo[i + width]);
            }
            hi.truncate(n);
            lo.truncate(n);
            width *= 2;
        }
        let amplitude_turns = pupil.amplitude.as_ref().map_or(0.0, |a| {
            // an amplitude table: about one radian of "turn" a knot interval, beside its own slope
            let (d1, _) = a.bounds;
            let scale = a.mean_square().sqrt().max(f64::MIN_POSITIVE);
            0.25 * a.knots() as f64 + 4.0 * d1 / scale
        });
        let k = std::f64::consts::TAU / wavelength_m;
        // the exact evaluation's rounding: a few units in the last place of its largest term
        // (its size, not its exact maximum: 17 samples)
        let magnitude = (0..=16)
            .map(|i| i as f64 / 16.0)
            .map(|q| (w020_m * q).abs() + pupil.opd_magnitude_m(q))
            .fold(0.0, f64::max);
        let rounding = 4.0 * f64::EPSILON * k * magnitude;
        let proxy = phase_proxy(&|q| k * pupil.opd_beyond_defocus_m(q), rounding);
        RadialOrder { pupil, w020_m, wavelength_m, slope, oscillation, amplitude_turns, proxy }
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

    /// The real OTF at `s = ν λ F#` (normalized frequency, `0 ≤ s`; 0 from `s ≥ 1`), within
    /// about `accuracy` (absolute) of the autocorrelation integral (module docs).
    pub fn otf(&self, s: f64, accuracy: f64) -> f64 {
        if s >= 1.0 {
            return 0.0;
        }
        if s <= 0.0 {
            return 1.0;
        }
        let k = std::f64::consts::TAU / self.wavelength_m;
        let (g1, osc) = (self.slope, self.oscillation_over(4.0 * s * (1.0 - s)));
        let t_end = s.acos();
        // phase the integrand can turn through along t and along v (module docs' bounds), plus
        // the sin²t factor's (frequency 2) and an amplitude table's
        let phase_t = k * (4.0 * s * (1.0 - s) * g1 + osc * t_end) + 2.0 * t_end + self.amplitude_turns;
        let phase_v = k * osc + self.amplitude_turns;
        let theta = panel_phase(accuracy);
        let t_panels = (phase_t / theta).ceil().max(1.0) as usize;
        let v_rule = small_rule(phase_v, accuracy);
        let v_panels = if v_rule.is_some() { 1 } else { (phase_v / theta).ceil().max(1.0) as usize };
        let rule16 = crate::quad::rule();
        // the v nodes on [0, 1] with their weights: one short rule, or 16-point panels
        let v_nodes: Vec<(f64, f64)> = match v_rule {
            Some(r) => r.iter().map(|&(xv, wv)| (0.5 + 0.5 * xv, 0.5 * wv)).collect(),
            None => {
                let hv = 0.5 / v_panels as f64;
                (0..v_panels)
                    .flat_map(|pv| {
                        let vc = (2 * pv + 1) as f64 * hv;
                        rule16.iter().map(move |&(xv, wv)| (vc + hv * xv, hv * wv))
                    })
                    .collect()
            }
        };
        let total = self.direct(s, t_end, t_panels, &v_nodes);
        4.0 * total / (std::f64::consts::PI * self.pupil.power())
    }

    /// The phase `k W(q)` at every lane of `q` into `phase`; the field amplitudes multiply `weight`
    /// (`q₁` in the first half of `q`, `q₂` in the second, `weight` as long as a half).
    fn lanes(&self, q: &[f64], phase: &mut [f64], weight: &mut [f64]) {
        let k = std::f64::consts::TAU / self.wavelength_m;
        let a = k * self.w020_m;
        let pupil = &*self.pupil;
        match self.proxy.as_deref() {
            Some(c) => {
                clenshaw_lanes(c, q, phase);
                for (p, &qi) in phase.iter_mut().zip(q) {
                    *p += a * qi;
                }
            }
            None => {
                for (p, &qi) in phase.iter_mut().zip(q) {
                    *p = a * qi + k * pupil.opd_beyond_defocus_m(qi);
                }
            }
        }
        if pupil.amplitude.is_some() {
            let half = weight.len();
            for (i, w) in weight.iter_mut().enumerate() {
                *w *= pupil.amplitude(q[i]) * pupil.amplitude(q[half + i]);
            }
        }
    }

    /// The tensor rule, every node's whole phase: `t_panels` 16-point panels on `[0, acos s]`
    /// times `v_nodes`, one t panel at a time, its `(t, v)` nodes as lanes (the phase and the
    /// cosine run as loops over lanes the compiler vectorizes).
    fn direct(&self, s: f64, t_end: f64, t_panels: usize, v_nodes: &[(f64, f64)]) -> f64 {
        let rule16 = crate::quad::rule();
        let lanes = rule16.len() * v_nodes.len();
        let mut q = vec![0.0; 2 * lanes];
        let mut weight = vec![0.0; lanes];
        let mut phase = vec![0.0; 2 * lanes];
        let mut total = 0.0;
        let ht = 0.5 * t_end / t_panels as f64;
        for pt in 0..t_panels {
            let tc = (2 * pt + 1) as f64 * ht;
            for (i, &(xt, wt)) in rule16.iter().enumerate() {
                let t = tc + ht * xt;
                let (sin_t, cos_t) = crate::fft::cis::sin_cos(t);
                let sin2 = sin_t * sin_t;
                fill_row(s, sin_t, cos_t, v_nodes, ht * wt * sin2, &mut q, &mut weight, i * v_nodes.len(), lanes);
            }
            self.lanes(&q, &mut phase, &mut weight);
            total += cosine_sum(&weight, &phase[..lanes], &phase[lanes..]);
        }
        total
    }
}

/// The phase (radians) a 16-point Gauss–Legendre panel may turn through for an error of about
/// `accuracy`: `(θ/2)^32/32! = accuracy`, between 6 and 16 rad.
fn panel_phase(accuracy: f64) -> f64 {
    // 32! = 2.63e35
    let acc = accuracy.clamp(1e-300, 1.0);
    (2.0 * (acc * 2.631_308_369_336_935e35).powf(1.0 / 32.0)).clamp(6.0, 16.0)
}

/// A shorter Gauss–Legendre rule (4 or 8 points on `[−1, 1]`) that integrates a factor turning
/// through `phase` radians to `accuracy`, if one does: `(θ/2)^{2n}/(2n)! ≤ accuracy`.
fn small_rule(phase: f64, accuracy: f64) -> Option<&'static [(f64, f64)]> {
    type Rule = Vec<(f64, f64)>;
    static RULES: OnceLock<(Rule, Rule)> = OnceLock::new();
    let (four, eight) = RULES.get_or_init(|| (crate::quad::gauss_legendre(4), crate::quad::gauss_legendre(8)));
    let half = 0.5 * phase.max(1e-3);
    // (2n)! for n = 4, 8: 40320, 2.09e13
    if half.powi(8) / 40_320.0 <= accuracy * 1e-2 {
        Some(four)
    } else if half.powi(16) / 2.092_278_988_8e13 <= accuracy * 1e-2 {
        Some(eight)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// The lane-wise Clenshaw recurrence is the scalar one lane by lane (the same operations:
    /// equal to the bit), also for lane counts that are not a multiple of the block, and the
    /// lane-wise cosine sum is the plain sum within rounding.
    #[test]
    fn lanes_match_the_scalar_recurrence() {
        let c: Vec<f64> = (0..18).map(|k| (k as f64 + 1.0).recip() * if k % 2 == 0 { 3.0 } else { -2.0 }).collect();
        for n in [1, 7, 8, 13, 64, 67] {
            let q: Vec<f64> = (0..n).map(|i| ((i as f64 + 0.5) / n as f64).powi(2)).collect();
            let mut out = vec![0.0; n];
            clenshaw_lanes(&c, &q, &mut out);
            for (o, &q) in out.iter().zip(&q) {
                assert_eq!(o.to_bits(), clenshaw(&c, q).to_bits(), "q = {q}");
            }
            let w: Vec<f64> = q.iter().map(|q| 1.0 - q).collect();
            let a: Vec<f64> = q.iter().map(|q| 40.0 * q).collect();
            let b: Vec<f64> = q.iter().map(|q| 3.0 * q * q).collect();
            let plain: f64 = (0..n).map(|i| w[i] * (a[i] - b[i]).cos()).sum();
            assert!((cosine_sum(&w, &a, &b) - plain).abs() < 1e-13 * n as f64, "n = {n}");
        }
    }
}
