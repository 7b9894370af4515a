//! Wavefront error over the pupil: Seidel terms and Noll-ordered Zernike polynomials.
//!
//! `x, y` are pupil coordinates normalized to the aperture radius and measured from the **lens
//! axis**; `ρ² = x² + y²`, `x = ρ cos φ` (φ counter-clockwise from `+x`). The field point lies on
//! the `+x` axis at normalized height `H ∈ [0, 1]`. The optical path difference, metres, is
//! (the Seidel expansion in field and pupil coordinates of Wyant & Creath, "Basic wavefront
//! aberration theory for optical metrology", Applied Optics and Optical Engineering XI (1992),
//! with the field along `x` instead of `y`):
//!
//! ```text
//! W = W020 ρ² + W040 ρ⁴ + W131 H ρ³ cos φ + W222 H² ρ² cos² φ + W220 H² ρ² + Σ_j c_j Z_j(ρ, φ)
//! ```
//!
//! Sign (docs/physics.md, "Sign of the wavefront", as in [`crate::Wavefront`]): `W` is the optical
//! path of the actual wavefront relative to the reference sphere centred on the detector point;
//! the pupil field is `A exp(+i 2π W/λ)` (time dependence `exp(−iωt)`). `W020 > 0` is a focus
//! `Δz` behind the detector (`W020 = Δz NA²/2 = Δz/(8 F#²)`), and every Seidel term carries the
//! same sign: `W040 > 0` focuses the marginal zone behind the paraxial focus, `W220 > 0` adds to
//! `W020` (the field point's focus behind the detector), `W222 > 0` puts the tangential focus
//! (the `x`–`z` section, which holds the field point) behind the sagittal one, and `W131 > 0`
//! sends the outer zones' rays toward `+x` (`∂W/∂x > 0`), the coma flare pointing away from the
//! axis.
//!
//! Zernike terms use **Noll's** ordering and normalization (R. J. Noll, "Zernike polynomials and
//! atmospheric turbulence", J. Opt. Soc. Am. 66, 207 (1976), eq. 3 and Table I): with
//! `(n, m)` from `j`,
//! `Z_j = √(n+1) R_n^0(ρ)` for `m = 0`, `Z_j = √(2(n+1)) R_n^m(ρ) cos(mφ)` for even `j` and
//! `… sin(mφ)` for odd `j` when `m ≠ 0`, with
//! `R_n^m(ρ) = Σ_{k=0}^{(n−m)/2} (−1)^k (n−k)! / [k! ((n+m)/2−k)! ((n−m)/2−k)!] ρ^{n−2k}`.
//! They are orthonormal on the unit disc (mean of `Z_j²` over the disc is 1), so a coefficient
//! is the RMS wavefront of its term, metres. `Z_2 = 2ρ cos φ` (x tilt), `Z_4 = √3 (2ρ² − 1)`
//! (defocus), `Z_11 = √5 (6ρ⁴ − 6ρ² + 1)` (spherical). Beyond `ρ = 1` (a decentred aperture sees
//! `ρ` up to `1 + |decentre|`) every term is its polynomial continued.

use crate::Error;

/// Highest Noll index accepted: radial order `n ≤ 30`. The explicit factorial sum of `R_n^m`
/// loses accuracy to cancellation beyond that (terms of order `2ⁿ`).
pub const MAX_NOLL_INDEX: usize = 496;

/// A wavefront error: Seidel coefficients (metres of OPD at the pupil edge `ρ = 1`), the field
/// height they apply at, and Noll Zernike coefficients (metres RMS). Plain data; validated when a
/// [`SampledPupil`](super::SampledPupil) is built from it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aberrations {
    /// Defocus `W020` (m): `W020 ρ²`.
    pub w020_m: f64,
    /// Spherical aberration `W040` (m): `W040 ρ⁴`.
    pub w040_m: f64,
    /// Coma `W131` (m): `W131 H ρ³ cos φ`.
    pub w131_m: f64,
    /// Astigmatism `W222` (m): `W222 H² ρ² cos² φ`.
    pub w222_m: f64,
    /// Field curvature `W220` (m): `W220 H² ρ²`.
    pub w220_m: f64,
    /// Normalized field height `H ∈ [0, 1]` along `+x`.
    pub field: f64,
    /// Zernike terms `(Noll index j ≥ 1, coefficient in metres RMS)`.
    pub zernike_noll_m: Vec<(usize, f64)>,
}

impl Aberrations {
    /// Defocus only: `W = W020 ρ²`.
    pub fn defocus(w020_m: f64) -> Aberrations {
        Aberrations { w020_m, ..Aberrations::default() }
    }

    /// Whether the wavefront is defocus only (no other Seidel term with a non-zero field, no
    /// Zernike term): with a centred circle, the case of the exact 1-D path.
    pub fn is_defocus_only(&self) -> bool {
        let field_terms = self.field != 0.0 && (self.w131_m != 0.0 || self.w222_m != 0.0 || self.w220_m != 0.0);
        self.w040_m == 0.0 && !field_terms && self.zernike_noll_m.iter().all(|&(_, c)| c == 0.0)
    }

    /// Checks every coefficient is finite, `H ∈ [0, 1]` and every Noll index in
    /// `1..=`[`MAX_NOLL_INDEX`].
    pub fn validate(&self) -> Result<(), Error> {
        let seidel = [
            ("W020", self.w020_m),
            ("W040", self.w040_m),
            ("W131", self.w131_m),
            ("W222", self.w222_m),
            ("W220", self.w220_m),
        ];
        for (name, v) in seidel {
            if !v.is_finite() {
                return Err(Error::InvalidParameter { name, value: v, expected: "finite (metres of OPD)" });
            }
        }
        if !(0.0..=1.0).contains(&self.field) {
            return Err(Error::InvalidParameter { name: "field height H", value: self.field, expected: "in [0, 1]" });
        }
        for &(j, c) in &self.zernike_noll_m {
            if !(1..=MAX_NOLL_INDEX).contains(&j) {
                return Err(Error::InvalidParameter {
                    name: "Noll index",
                    value: j as f64,
                    expected: "in 1..=496 (radial order ≤ 30)",
                });
            }
            if !c.is_finite() {
                return Err(Error::InvalidParameter {
                    name: "Zernike coefficient",
                    value: c,
                    expected: "finite (metres RMS)",
                });
            }
        }
        Ok(())
    }

    /// The OPD (m) at `(x, y)`, normalized coordinates from the lens axis. For validated
    /// aberrations (see [`validate`](Self::validate)); slow path, for checks and single points.
    pub fn opd_m(&self, x: f64, y: f64) -> f64 {
        Compiled::new(self).opd_m(x, y)
    }
}

/// `(n, m)` of Noll index `j ≥ 1`; `m > 0` for the cosine terms (even `j`), `m < 0` for the sine
/// terms (odd `j`), `m = 0` for the rotationally symmetric ones (Noll 1976, Table I).
pub fn noll_to_nm(j: usize) -> (usize, i64) {
    assert!(j >= 1, "Noll indices start at 1");
    let mut n = 0;
    while (n + 1) * (n + 2) / 2 < j {
        n += 1;
    }
    let k = j - n * (n + 1) / 2 - 1; // position within the radial order, 0-based
    let m = if n % 2 == 0 { 2 * k.div_ceil(2) } else { 2 * (k / 2) + 1 };
    let m = m as i64;
    if m == 0 {
        (n, 0)
    } else if j.is_multiple_of(2) {
        (n, m)
    } else {
        (n, -m)
    }
}

/// One Zernike term ready to evaluate: `c · norm · Re/Im[(x + iy)^|m|] · P(ρ²)` with
/// `R_n^m(ρ) = ρ^|m| P(ρ²)`, `P` in Horner form (highest power first).
#[derive(Clone, Debug)]
struct ZernikeTerm {
    m: i64,
    poly: Vec<f64>,
}

/// Validated aberrations in evaluation form.
#[derive(Clone, Debug)]
pub(crate) struct Compiled {
    w020: f64,
    w040: f64,
    w131h: f64,
    w222h2: f64,
    w220h2: f64,
    zernike: Vec<ZernikeTerm>,
}

impl Compiled {
    pub(crate) fn new(a: &Aberrations) -> Compiled {
        let zernike = a
            .zernike_noll_m
            .iter()
            .filter(|&&(_, c)| c != 0.0)
            .map(|&(j, c)| {
                let (n, m) = noll_to_nm(j);
                let ma = m.unsigned_abs() as usize;
                let norm = if m == 0 { ((n + 1) as f64).sqrt() } else { (2.0 * (n + 1) as f64).sqrt() };
                // R_n^m = Σ_k coef_k ρ^{n−2k} = ρ^|m| Σ_k coef_k (ρ²)^{(n−|m|)/2 − k}
                let half = (n - ma) / 2;
                let poly: Vec<f64> = (0..=half)
                    .map(|k| {
                        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                        sign * factorial(n - k)
                            / (factorial(k) * factorial((n + ma) / 2 - k) * factorial((n - ma) / 2 - k))
                            * norm
                            * c
                    })
                    .collect();
                ZernikeTerm { m, poly }
            })
            .collect();
        Compiled {
            w020: a.w020_m,
            w040: a.w040_m,
            w131h: a.w131_m * a.field,
            w222h2: a.w222_m * a.field * a.field,
            w220h2: a.w220_m * a.field * a.field,
            zernike,
        }
    }

    /// The one Zernike term of a compilation that holds nothing else (`m` and the coefficients
    /// of `R_n^m/ρ^|m|` in ρ², highest first, scaled as [`opd_m`](Self::opd_m) reads them), so
    /// that several such terms can share `ρ²` and the powers of `x + iy` at a point; `None`
    /// otherwise.
    pub(crate) fn single_zernike(&self) -> Option<(i64, &[f64])> {
        let seidel = [self.w020, self.w040, self.w131h, self.w222h2, self.w220h2];
        match self.zernike.as_slice() {
            [t] if seidel.iter().all(|w| *w == 0.0) => Some((t.m, &t.poly)),
            _ => None,
        }
    }

    /// Whether some Zernike term is a sine term (odd Noll index, `m ≠ 0`): odd in y.
    pub(crate) fn has_sine_terms(&self) -> bool {
        self.zernike.iter().any(|t| t.m < 0)
    }

    /// OPD (m) at `(x, y)` from the lens axis.
    pub(crate) fn opd_m(&self, x: f64, y: f64) -> f64 {
        let r2 = x * x + y * y;
        // ρ³ cos φ = ρ² x, ρ² cos² φ = x²
        let mut w = r2 * (self.w020 + self.w220h2 + self.w040 * r2 + self.w131h * x) + self.w222h2 * x * x;
        for t in &self.zernike {
            let mut p = 0.0;
            for &c in &t.poly {
                p = p * r2 + c;
            }
            let ma = t.m.unsigned_abs();
            // (x + iy)^|m| = ρ^|m| (cos mφ + i sin mφ)
            let (mut re, mut im) = (1.0, 0.0);
            for _ in 0..ma {
                (re, im) = (re * x - im * y, re * y + im * x);
            }
            w += p * if t.m >= 0 { re } else { im };
        }
        w
    }
}

fn factorial(k: usize) -> f64 {
    (1..=k).map(|i| i as f64).product()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noll_indices_follow_table_1() {
        let table = [(1, (0, 0)), (2, (1, 1)), (3, (1, -1)), (4, (2, 0)), (5, (2, -2)), (6, (2, 2))];
        for (j, nm) in table {
            assert_eq!(noll_to_nm(j), nm, "j = {j}");
        }
        let more = [(7, (3, -1)), (8, (3, 1)), (9, (3, -3)), (10, (3, 3)), (11, (4, 0)), (12, (4, 2)), (13, (4, -2))];
        for (j, nm) in more {
            assert_eq!(noll_to_nm(j), nm, "j = {j}");
        }
        assert_eq!(noll_to_nm(22), (6, 0));
        assert_eq!(noll_to_nm(496), (30, 30));
    }

    /// Closed forms of Noll's Table I at a point.
    #[test]
    fn zernike_terms_match_closed_forms() {
        let (x, y) = (0.3_f64, -0.5_f64);
        let r2 = x * x + y * y;
        let phi = y.atan2(x);
        let r = r2.sqrt();
        let cases: [(usize, f64); 6] = [
            (2, 2.0 * x),
            (3, 2.0 * y),
            (4, 3f64.sqrt() * (2.0 * r2 - 1.0)),
            (8, 8f64.sqrt() * (3.0 * r2 - 2.0) * x),
            (11, 5f64.sqrt() * (6.0 * r2 * r2 - 6.0 * r2 + 1.0)),
            (10, 8f64.sqrt() * r * r2 * (3.0 * phi).cos()),
        ];
        for (j, expected) in cases {
            let a = Aberrations { zernike_noll_m: vec![(j, 1.0)], ..Aberrations::default() };
            let got = a.opd_m(x, y);
            assert!((got - expected).abs() < 1e-14, "Z{j}: {got} vs {expected}");
        }
    }

    /// The Seidel terms as defined in the module docs (Wyant & Creath with the field along +x),
    /// and field curvature adding to defocus with the same sign: `W020 = −W220 H²` cancels it.
    #[test]
    fn seidel_terms_match_their_definitions() {
        let (x, y, h) = (0.3_f64, -0.5_f64, 0.7_f64);
        let r2 = x * x + y * y;
        let cos_phi = x / r2.sqrt();
        let one = |a: Aberrations| Aberrations { field: h, ..a }.opd_m(x, y);
        let cases = [
            (one(Aberrations { w020_m: 1.0, ..Default::default() }), r2),
            (one(Aberrations { w040_m: 1.0, ..Default::default() }), r2 * r2),
            (one(Aberrations { w131_m: 1.0, ..Default::default() }), h * r2.powf(1.5) * cos_phi),
            (one(Aberrations { w222_m: 1.0, ..Default::default() }), h * h * r2 * cos_phi * cos_phi),
            (one(Aberrations { w220_m: 1.0, ..Default::default() }), h * h * r2),
        ];
        for (i, (got, expected)) in cases.into_iter().enumerate() {
            assert!((got - expected).abs() < 1e-15, "term {i}: {got} vs {expected}");
        }
        let balanced = one(Aberrations { w020_m: -0.5e-6 * h * h, w220_m: 0.5e-6, ..Default::default() });
        assert!(balanced.abs() < 1e-22, "{balanced}");
    }

    /// Orthonormality on the unit disc by a polar Gauss–Legendre × trapezoid product rule.
    #[test]
    fn zernike_terms_are_orthonormal() {
        let js = [1usize, 2, 4, 7, 11, 12, 22, 37, 60];
        let nodes = crate::quad::rule();
        let n_phi = 96;
        let mut gram = vec![0.0; js.len() * js.len()];
        let comps: Vec<Compiled> = js
            .iter()
            .map(|&j| Compiled::new(&Aberrations { zernike_noll_m: vec![(j, 1.0)], ..Default::default() }))
            .collect();
        for panel in 0..4 {
            for &(t, wt) in nodes {
                let r = (panel as f64 + 0.5 + 0.5 * t) / 4.0;
                let wr = 0.5 * wt / 4.0 * r;
                for k in 0..n_phi {
                    let phi = std::f64::consts::TAU * k as f64 / n_phi as f64;
                    let (x, y) = (r * phi.cos(), r * phi.sin());
                    let vals: Vec<f64> = comps.iter().map(|c| c.opd_m(x, y)).collect();
                    for a in 0..js.len() {
                        for b in 0..js.len() {
                            gram[a * js.len() + b] += wr * std::f64::consts::TAU / n_phi as f64 * vals[a] * vals[b];
                        }
                    }
                }
            }
        }
        for a in 0..js.len() {
            for b in 0..js.len() {
                let expected = if a == b { std::f64::consts::PI } else { 0.0 };
                let g = gram[a * js.len() + b];
                assert!((g - expected).abs() < 1e-10, "⟨Z{}, Z{}⟩ = {g}", js[a], js[b]);
            }
        }
    }
}
