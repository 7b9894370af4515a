//! Pupil geometry: the transmitting region of the exit pupil and its anti-aliased sampling.
//!
//! Coordinates are normalized to the aperture radius `R = D/2` and measured from the aperture
//! centre: the aperture is inside the square `[-1, 1]²` the pupil grid spans. Angles are
//! counter-clockwise from `+x`, in radians.
//!
//! # Edge pixels carry their area fraction
//! A pixel's transmission is the fraction of its area inside the aperture. For every shape built
//! from discs and wedges (circle, decentred circle, annulus, sector, ring zone, and their combinations) the
//! fraction is **exact** (to rounding): the pixel square is clipped by the wedge's half-planes
//! (Sutherland–Hodgman; a wedge wider than π is split in two), and the area of the clipped convex
//! polygon inside a disc is the sum over its edges of the signed area of the triangle (centre,
//! edge) inside the disc — straight pieces as triangles, pieces outside as circular sectors
//! (the standard polygon–circle intersection decomposition). An annulus is the outer disc's area
//! minus the inner disc's. Pixels wholly inside or outside (tested by the distances of the
//! square's nearest point and farthest corner from the centre) skip the geometry.
//!
//! Why exact area rather than a hard edge: a binary (hard-edged) pupil, as prysm and most FFT tools
//! use, misplaces the edge by up to half a pixel, and the mean MTF converges only like `1/N`. With
//! exact area fractions the sampled pupil is the true pupil convolved with the pixel box and then
//! sampled; its area is exact and the mean-MTF error falls like `N⁻² log N` (measured: see the
//! table in the [`fft`](super) module docs).
//!
//! An arbitrary [`Aperture::mask`] closure only answers inside/outside at a point, so its pixels
//! are probed at a 3 × 3 pattern (corners, edge midpoints, centre): if all nine agree the pixel is
//! taken as wholly in or out, otherwise its fraction is the mean over a 16 × 16 grid of sub-pixel
//! centres (an error of at most `1/16` of a pixel's area per edge pixel, a few `1e-3` on average
//! along a straight edge). Features that slip between the nine probes (thinner than half a pixel)
//! are missed: such features are below the grid's resolution anyway.

use std::f64::consts::{PI, TAU};
use std::fmt;
use std::sync::Arc;

use crate::Error;

/// The inside/outside test of a masked aperture: `(x, y)` in the pupil grid's normalized
/// coordinates (`[-1, 1]²`, centre of the grid at the origin).
pub type MaskFn = dyn Fn(f64, f64) -> bool + Send + Sync;

/// Side of the sub-pixel grid a masked aperture's edge pixels are supersampled with.
pub const MASK_SUPERSAMPLING: usize = 16;

/// The transmitting region of an exit pupil, in coordinates normalized to the aperture radius.
///
/// Built with [`circle`](Aperture::circle), [`annulus`](Aperture::annulus),
/// [`sector`](Aperture::sector), [`disc`](Aperture::disc) (annular sector),
/// [`ring`](Aperture::ring) (an annular sector inside the full aperture: a zone) or
/// [`mask`](Aperture::mask), optionally [`decentred`](Aperture::decentred) from the lens axis.
/// Constructors validate their parameters.
#[derive(Clone)]
pub struct Aperture {
    shape: Shape,
    decentre: (f64, f64),
}

#[derive(Clone)]
enum Shape {
    /// `obscuration ≤ r ≤ outer` (`outer ≤ 1`), optionally only angles in `[start, end]`.
    Disc {
        obscuration: f64,
        outer: f64,
        sector: Option<(f64, f64)>,
    },
    Mask(Arc<MaskFn>),
}

impl fmt::Debug for Aperture {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut d = f.debug_struct("Aperture");
        match &self.shape {
            Shape::Disc { obscuration, outer, sector } => {
                d.field("obscuration", obscuration).field("outer", outer).field("sector", sector)
            }
            Shape::Mask(_) => d.field("mask", &"<closure>"),
        };
        d.field("decentre", &self.decentre).finish()
    }
}

impl Aperture {
    /// The full circle of radius 1 (the lens' clear aperture), centred on the lens axis.
    pub fn circle() -> Aperture {
        Aperture { shape: Shape::Disc { obscuration: 0.0, outer: 1.0, sector: None }, decentre: (0.0, 0.0) }
    }

    /// An annulus `obscuration ≤ r ≤ 1`: a circle with a central obscuration of radius ratio
    /// `obscuration` in `[0, 1)`.
    pub fn annulus(obscuration: f64) -> Result<Aperture, Error> {
        Aperture::disc(obscuration, None)
    }

    /// A sector of the circle: angles in `[start_rad, end_rad]` (counter-clockwise from `+x`),
    /// `0 < end − start ≤ 2π`. One segment of a segmented multiplexed lens.
    pub fn sector(start_rad: f64, end_rad: f64) -> Result<Aperture, Error> {
        Aperture::disc(0.0, Some((start_rad, end_rad)))
    }

    /// The general disc shape: an annulus `obscuration ≤ r ≤ 1` (`obscuration` in `[0, 1)`),
    /// restricted to the angular range `sector = (start, end)` if given (`0 < end − start ≤ 2π`).
    pub fn disc(obscuration: f64, sector: Option<(f64, f64)>) -> Result<Aperture, Error> {
        if !(0.0..1.0).contains(&obscuration) {
            return Err(Error::InvalidParameter { name: "obscuration", value: obscuration, expected: "in [0, 1)" });
        }
        Aperture::ring(obscuration, 1.0, sector)
    }

    /// A ring `inner ≤ r ≤ outer` of the full aperture (`0 ≤ inner < outer ≤ 1`, in units of the
    /// full aperture's radius, centred on the lens axis), restricted to the angles
    /// `sector = (start, end)` if given (`0 < end − start ≤ 2π`): one zone of a segmented lens.
    /// The pupil grid still spans the full aperture (`s = 1` is its cutoff), and edge pixels carry
    /// their exact area, on both circles and both sector edges (module docs). Concentric zones
    /// of area fractions `a_j` are the rings `r_{j−1} … r_j` with `r_j = √(Σ_{i≤j} a_i)`.
    pub fn ring(inner: f64, outer: f64, sector: Option<(f64, f64)>) -> Result<Aperture, Error> {
        if !(outer > 0.0 && outer <= 1.0) {
            return Err(Error::InvalidParameter {
                name: "ring outer radius",
                value: outer,
                expected: "in (0, 1] (fraction of the full aperture's radius)",
            });
        }
        if !(inner >= 0.0 && inner < outer) {
            return Err(Error::InvalidParameter {
                name: "ring inner radius",
                value: inner,
                expected: "in [0, outer) (fraction of the full aperture's radius)",
            });
        }
        if let Some((a, b)) = sector {
            if !a.is_finite() {
                return Err(Error::InvalidParameter { name: "sector start", value: a, expected: "finite (radians)" });
            }
            let width = b - a;
            if !(width > 0.0 && width <= TAU) {
                return Err(Error::InvalidParameter {
                    name: "sector width",
                    value: width,
                    expected: "end − start in (0, 2π] radians",
                });
            }
        }
        // A full turn is no restriction.
        let sector = sector.filter(|(a, b)| b - a < TAU);
        Ok(Aperture { shape: Shape::Disc { obscuration: inner, outer, sector }, decentre: (0.0, 0.0) })
    }

    /// An arbitrary aperture: `inside(x, y)` says whether the point `(x, y)` of the grid square
    /// `[-1, 1]²` (normalized to the radius, origin at the grid centre) transmits. Edge pixels are
    /// supersampled (module docs). The cutoff `s = 1` of the frequency axis stays that of a
    /// full aperture of diameter 2.
    pub fn mask(inside: impl Fn(f64, f64) -> bool + Send + Sync + 'static) -> Aperture {
        Aperture { shape: Shape::Mask(Arc::new(inside)), decentre: (0.0, 0.0) }
    }

    /// The same aperture with its centre displaced from the lens axis by `(dx, dy)` in units of
    /// its radius (the decentred iris of the paper's Fig. S3). The pupil grid stays centred on the
    /// aperture; the wavefront is evaluated at `ρ` measured from the lens axis, so a decentred
    /// aperture sees the lens' wavefront off its own centre (defocus becomes defocus + tilt,
    /// spherical aberration becomes coma, astigmatism, …).
    pub fn decentred(self, dx: f64, dy: f64) -> Result<Aperture, Error> {
        for (name, v) in [("decentre x", dx), ("decentre y", dy)] {
            if !v.is_finite() {
                return Err(Error::InvalidParameter { name, value: v, expected: "finite (fraction of the radius)" });
            }
        }
        Ok(Aperture { decentre: (dx, dy), ..self })
    }

    /// The aperture centre's offset from the lens axis, in units of the aperture radius.
    pub fn decentre(&self) -> (f64, f64) {
        self.decentre
    }

    /// Whether this is the full circle centred on the lens axis: the case the exact 1-D path
    /// ([`crate::defocus_otf`]) covers when the wavefront is defocus only.
    pub fn is_centred_circle(&self) -> bool {
        matches!(self.shape, Shape::Disc { obscuration, outer, sector: None } if obscuration == 0.0 && outer == 1.0)
            && self.decentre == (0.0, 0.0)
    }

    /// The aperture as one circle, when it is exactly one: `Some((centre, radius))`, the centre
    /// `[dx, dy]` from the lens axis and the radius, both in units of the full aperture's radius
    /// `R` (a [`circle`](Aperture::circle) or a [`ring`](Aperture::ring) without obscuration or
    /// sector, centred or [`decentred`](Aperture::decentred): the scene's iris is
    /// `Aperture::disc(0, None).decentred(dx, dy)`, the circle of radius 1 centred at
    /// `(dx, dy)`). `None` for an annulus, a sector or a mask.
    ///
    /// With a defocus-only wavefront such a pupil is a centred circle in disguise:
    /// [`reduce_decentred_circle`] gives its exact 1-D description.
    pub fn as_circle(&self) -> Option<([f64; 2], f64)> {
        match self.shape {
            Shape::Disc { obscuration: 0.0, outer, sector: None } => Some(([self.decentre.0, self.decentre.1], outer)),
            _ => None,
        }
    }

    /// Exact area of the aperture in units of `R²` (`π` for the full circle), or `None` for a mask.
    pub fn exact_area(&self) -> Option<f64> {
        match self.shape {
            Shape::Disc { obscuration, outer, sector } => {
                let angle = sector.map_or(TAU, |(a, b)| b - a);
                Some(0.5 * angle * (outer * outer - obscuration * obscuration))
            }
            Shape::Mask(_) => None,
        }
    }

    /// The aperture's area as a fraction of the full circle's `π`: exact for the disc shapes,
    /// measured on a 512 × 512 grid (edge pixels supersampled) for a mask.
    pub fn area_fraction(&self) -> f64 {
        if let Some(a) = self.exact_area() {
            return a / PI;
        }
        let n = 512;
        let h = 2.0 / n as f64;
        let mut total = 0.0;
        for j in 0..n {
            let y0 = -1.0 + j as f64 * h;
            for i in 0..n {
                let x0 = -1.0 + i as f64 * h;
                total += self.area_in(x0, x0 + h, y0, y0 + h);
            }
        }
        total / PI
    }

    /// The inner radius ε of a disc shape (an annulus, ring or sector's; 0 for the full disc), in
    /// units of the full aperture's radius; `None` for a mask.
    pub fn obscuration(&self) -> Option<f64> {
        match &self.shape {
            Shape::Disc { obscuration, .. } => Some(*obscuration),
            Shape::Mask(_) => None,
        }
    }

    /// The rate at which the area of the rectangle `[x0, x1] × [y0, y1]` (grid coordinates, as
    /// [`area_in`](Self::area_in)) that transmits moves with the obscuration ε (the inner
    /// radius of a disc shape, in units of the full aperture's radius): minus the length of the
    /// inner circle `r = ε` (inside the sector, if any) that lies in the rectangle, since
    /// `∂/∂ε ∫∫_{r ≥ ε} dA = −∮_{r = ε} ds` (docs/physics.md, "Gradients: the edge's motion on
    /// the FFT path"). Exact to rounding: the circle's crossings of the rectangle's sides and the
    /// sector's edges cut it into arcs, each wholly in or out. `None` for a mask (its edges are
    /// not a parameter).
    pub fn obscuration_rate_in(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> Option<f64> {
        match &self.shape {
            Shape::Disc { obscuration, sector, .. } => {
                Some(-arc_length_in(&Rect { x0, x1, y0, y1 }, *obscuration, *sector))
            }
            Shape::Mask(_) => None,
        }
    }

    /// The rates at which the area of the rectangle `[x0, x1] × [y0, y1]` (grid coordinates, as
    /// [`area_in`](Self::area_in)) that transmits moves with each edge of a disc shape, in the
    /// order (inner radius ε, outer radius, wedge's start angle a, wedge's end angle b): `−` the
    /// length of the circle `r = ε` in the rectangle (inside the wedge, if any), `+` that of the
    /// circle `r = outer`, and for a wedge `∓ ∫ r dr` along its straight edge at angle a (b)
    /// between ε and the outer radius inside the rectangle, since a radial edge turning by `dθ`
    /// sweeps `r dr dθ` (docs/physics.md, "Gradients: the multiplexed lens"). The angles' rates
    /// are 0 without a wedge. Exact to rounding (the arcs as
    /// [`obscuration_rate_in`](Self::obscuration_rate_in), the segments by clipping). `None` for
    /// a mask.
    pub fn edge_rates_in(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> Option<[f64; 4]> {
        let Shape::Disc { obscuration, outer, sector } = &self.shape else { return None };
        let rect = Rect { x0, x1, y0, y1 };
        let (near, far) = rect.distance_range();
        if near > *outer || far < *obscuration {
            return Some([0.0; 4]);
        }
        let inner = -arc_length_in(&rect, *obscuration, *sector);
        let rim = arc_length_in(&rect, *outer, *sector);
        let (start, end) = match sector {
            Some((a, b)) => {
                (-radial_moment_in(&rect, *a, *obscuration, *outer), radial_moment_in(&rect, *b, *obscuration, *outer))
            }
            None => (0.0, 0.0),
        };
        Some([inner, rim, start, end])
    }

    /// Area of the rectangle `[x0, x1] × [y0, y1]` (grid coordinates) that transmits.
    pub fn area_in(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        let rect = Rect { x0, x1, y0, y1 };
        match &self.shape {
            Shape::Disc { obscuration, outer, sector } => disc_area_in(&rect, *obscuration, *outer, *sector),
            Shape::Mask(inside) => mask_area_in(&rect, inside.as_ref()),
        }
    }
}

/// A circular pupil with defocus, decentred from the lens axis, described as the centred circle
/// the exact 1-D path computes ([`reduce_decentred_circle`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReducedCircle {
    /// Radius `r` of the pupil, in units of the full aperture's radius `R`: the pupil is a lens
    /// of F-number `F#/r`, its frequencies `s' = s/r` (`s` normalized to the full aperture's
    /// cutoff `2 NA/λ`, the FFT path's convention).
    pub radius: f64,
    /// Defocus at the pupil's own edge, m: `W020 r²`.
    pub defocus_m: f64,
    /// Image displacement on the detector, m, that the decentre's tilt produces:
    /// `Δ = 2 W020 d/NA = 4 F# W020 d`.
    pub image_shift_m: [f64; 2],
}

/// The exact description of a circular pupil of radius `radius` centred at `centre` (both in
/// units of the full aperture's radius `R`, the centre from the lens axis; what
/// [`Aperture::as_circle`] returns) on a lens with defocus only, `W = W020 ρ²` with `ρ` from
/// the lens axis (docs/physics.md, "Sign of the wavefront"), and image-side numerical aperture
/// `numerical_aperture = 1/(2 F#)` of the full aperture.
///
/// # Derivation
/// Write a pupil point as `x = d + u` (`d` the centre, `|u| ≤ r`, units of `R`):
///
/// ```text
/// W = W020 |d + u|² = W020 |u|² + 2 W020 d·u + W020 |d|²
///   = (W020 r²) |v|² + 2 W020 d·u + piston,         v = u/r, |v| ≤ 1
/// ```
///
/// - **Defocus** `W020 r²` at the pupil's own edge `|v| = 1`: the pupil is the centred circle of
///   radius `rR`, a lens of F-number `F#/r` whose cutoff is `r ν_c`, so its OTF is
///   [`crate::defocus_otf`]`(s/r, W020 r²/λ)` at the full aperture's normalized frequency `s`
///   (docs/physics.md, "Exact defocused OTF"; zero for `s ≥ r`).
/// - **Tilt** `t·u`, `t = 2 W020 d` (m of OPD per unit `R`, the convention of
///   [`ZoneField::tilt_m`](super::ZoneField::tilt_m)). A wavefront slope `∂W/∂x > 0` moves the
///   PSF toward `+x` (module docs of [`fft`](super), "Conventions"); the stationary phase of the
///   Fraunhofer integral puts the PSF of `W = t·u` at `Δ = t z/R = t/NA` (module docs of
///   [`SampledZones`](super::SampledZones)), so
///
///   ```text
///   Δ = 2 W020 d / NA = 4 F# W020 d        (m, on the detector)
///   ```
///
///   the convention of [`crate::Wavefront::image_shift_m`]: the OTF is multiplied by
///   `exp(−2πi ν·Δ)` (docs/physics.md, "Polychromatic OTF"). In the FFT path's normalized
///   frequency (`ν = s/(λ F#)`) that phase is `−8π w d·s` with `w = W020/λ`: `W020 > 0` (focus
///   behind the detector, rays not yet crossed) and an iris moved toward `+x` put the blur
///   toward `+x`, as the ray picture says.
/// - The **piston** `W020 |d|²` does not change the OTF.
///
/// Hence, exactly (the FFT path reproduces it to its sampling error; tests/optics/fft.rs):
///
/// ```text
/// OTF_decentred(ν) = defocus_otf(s/r, W020 r²/λ) · exp(−2πi ν·Δ),   s = ν λ F#
/// ```
///
/// # Errors
/// [`Error::InvalidParameter`] for a radius outside `(0, 1]`, a non-finite centre or defocus,
/// or a numerical aperture outside `(0, 1)`.
///
/// # Example
/// ```
/// use optics::fft::{Aperture, reduce_decentred_circle};
/// // the scene's iris decentred by 15 % of the radius along x, at F/2.5, 1 µm of defocus
/// let iris = Aperture::circle().decentred(0.15, 0.0)?;
/// let (centre, radius) = iris.as_circle().unwrap();
/// let reduced = reduce_decentred_circle(centre, radius, 1e-6, 0.2)?;
/// assert_eq!((reduced.radius, reduced.defocus_m), (1.0, 1e-6));
/// assert!((reduced.image_shift_m[0] - 1.5e-6).abs() < 1e-20); // 2 × 1 µm × 0.15 / 0.2
/// # Ok::<(), optics::Error>(())
/// ```
pub fn reduce_decentred_circle(
    centre: [f64; 2],
    radius: f64,
    w020_m: f64,
    numerical_aperture: f64,
) -> Result<ReducedCircle, Error> {
    if !(radius > 0.0 && radius <= 1.0) {
        return Err(Error::InvalidParameter {
            name: "circle radius",
            value: radius,
            expected: "in (0, 1] (fraction of the full aperture's radius)",
        });
    }
    if let Some(&c) = centre.iter().find(|c| !c.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "circle centre",
            value: c,
            expected: "finite (fraction of the radius)",
        });
    }
    if !w020_m.is_finite() {
        return Err(Error::InvalidParameter { name: "W020", value: w020_m, expected: "finite (metres of OPD)" });
    }
    if !(numerical_aperture > 0.0 && numerical_aperture < 1.0) {
        return Err(Error::InvalidParameter {
            name: "numerical aperture",
            value: numerical_aperture,
            expected: "in (0, 1)",
        });
    }
    let k = 2.0 * w020_m / numerical_aperture;
    Ok(ReducedCircle { radius, defocus_m: w020_m * radius * radius, image_shift_m: [k * centre[0], k * centre[1]] })
}

#[derive(Clone, Copy)]
struct Rect {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Rect {
    fn area(&self) -> f64 {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }

    /// Distances from the origin to the nearest point and the farthest corner.
    fn distance_range(&self) -> (f64, f64) {
        let nx = 0.0_f64.clamp(self.x0, self.x1);
        let ny = 0.0_f64.clamp(self.y0, self.y1);
        let fx = self.x0.abs().max(self.x1.abs());
        let fy = self.y0.abs().max(self.y1.abs());
        (nx.hypot(ny), fx.hypot(fy))
    }
}

/// A convex polygon of at most 8 vertices, counter-clockwise (a square clipped by two lines
/// has at most 6).
#[derive(Clone, Copy)]
struct Polygon {
    v: [(f64, f64); 8],
    len: usize,
}

impl Polygon {
    fn from_rect(r: &Rect) -> Polygon {
        let mut v = [(0.0, 0.0); 8];
        v[..4].copy_from_slice(&[(r.x0, r.y0), (r.x1, r.y0), (r.x1, r.y1), (r.x0, r.y1)]);
        Polygon { v, len: 4 }
    }

    fn vertices(&self) -> &[(f64, f64)] {
        &self.v[..self.len]
    }

    /// Keeps the part where `n · p ≥ 0` (Sutherland–Hodgman against one line through the origin).
    fn clip(&self, n: (f64, f64)) -> Polygon {
        let mut out = Polygon { v: [(0.0, 0.0); 8], len: 0 };
        let side = |p: (f64, f64)| n.0 * p.0 + n.1 * p.1;
        let vs = self.vertices();
        for i in 0..vs.len() {
            let p = vs[i];
            let q = vs[(i + 1) % vs.len()];
            let (fp, fq) = (side(p), side(q));
            if fp >= 0.0 {
                out.push(p);
            }
            if (fp >= 0.0) != (fq >= 0.0) {
                let t = fp / (fp - fq);
                out.push((p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1)));
            }
        }
        out
    }

    fn push(&mut self, p: (f64, f64)) {
        self.v[self.len] = p;
        self.len += 1;
    }

    /// Shoelace area.
    fn area(&self) -> f64 {
        let vs = self.vertices();
        let mut a = 0.0;
        for i in 0..vs.len() {
            let (p, q) = (vs[i], vs[(i + 1) % vs.len()]);
            a += p.0 * q.1 - p.1 * q.0;
        }
        0.5 * a
    }

    /// Area inside the disc of radius `r` about the origin: Σ over edges of the signed area of
    /// the triangle (origin, p, q) inside the disc.
    fn area_in_disc(&self, r: f64) -> f64 {
        let vs = self.vertices();
        (0..vs.len()).map(|i| triangle_in_disc(vs[i], vs[(i + 1) % vs.len()], r)).sum()
    }
}

/// Signed area of triangle (origin, a, b) ∩ disc(origin, r): the segment is cut at its crossings
/// with the circle; pieces inside count as triangles `½ p × q`, pieces outside as circular sectors
/// `½ r² ∠(p, q)`.
fn triangle_in_disc(a: (f64, f64), b: (f64, f64), r: f64) -> f64 {
    let d = (b.0 - a.0, b.1 - a.1);
    let dd = d.0 * d.0 + d.1 * d.1;
    if dd == 0.0 {
        return 0.0;
    }
    let ad = a.0 * d.0 + a.1 * d.1;
    let c = a.0 * a.0 + a.1 * a.1 - r * r;
    let disc = ad * ad - dd * c;
    let mut pts = [a; 4];
    let mut n = 1;
    if disc > 0.0 {
        let sq = disc.sqrt();
        for t in [(-ad - sq) / dd, (-ad + sq) / dd] {
            if t > 0.0 && t < 1.0 {
                pts[n] = (a.0 + t * d.0, a.1 + t * d.1);
                n += 1;
            }
        }
    }
    pts[n] = b;
    n += 1;
    let mut area = 0.0;
    for w in pts[..n].windows(2) {
        let (p, q) = (w[0], w[1]);
        let cross = p.0 * q.1 - p.1 * q.0;
        let mid = (0.5 * (p.0 + q.0), 0.5 * (p.1 + q.1));
        // Strictly inside: a segment tangent to the circle at its midpoint is outside. A chord
        // misjudged within 1e-12 r² of tangency changes the area by under (2e-6 r)³.
        if mid.0 * mid.0 + mid.1 * mid.1 < r * r * (1.0 - 1e-12) {
            area += 0.5 * cross;
        } else {
            let dot = p.0 * q.0 + p.1 * q.1;
            area += 0.5 * r * r * cross.atan2(dot);
        }
    }
    area
}

/// Exact area of `rect ∩ {obscuration ≤ r ≤ outer} ∩ wedge`.
fn disc_area_in(rect: &Rect, obscuration: f64, outer: f64, sector: Option<(f64, f64)>) -> f64 {
    let (near, far) = rect.distance_range();
    if near >= outer || far <= obscuration {
        return 0.0;
    }
    let full_square = Polygon::from_rect(rect);
    let ring = |poly: &Polygon, full: f64| -> f64 {
        let within_outer = if far <= outer { full } else { poly.area_in_disc(outer) };
        let inner = if obscuration == 0.0 || near >= obscuration {
            0.0
        } else if far <= obscuration {
            full
        } else {
            poly.area_in_disc(obscuration)
        };
        (within_outer - inner).max(0.0)
    };
    match sector {
        None => ring(&full_square, rect.area()),
        Some((a, b)) => {
            // Split into wedges no wider than π, each the intersection of two half-planes.
            let pieces = if b - a > PI { [(a, 0.5 * (a + b)), (0.5 * (a + b), b)] } else { [(a, b), (b, b)] };
            let mut total = 0.0;
            for (lo, hi) in pieces {
                if hi <= lo {
                    continue;
                }
                let (sa, ca) = lo.sin_cos();
                let (sb, cb) = hi.sin_cos();
                // cross(u_lo, p) ≥ 0 and cross(p, u_hi) ≥ 0
                let poly = full_square.clip((-sa, ca)).clip((sb, -cb));
                if poly.len < 3 {
                    continue;
                }
                total += ring(&poly, poly.area());
            }
            total
        }
    }
}

/// Length of the circle `r = radius` (centred on the origin) inside `rect` and, if given, inside
/// the wedge of angles `[a, b]` (counter-clockwise from `+x`, `0 < b − a < 2π`): the angles where
/// the circle crosses the rectangle's four sides and the wedge's two edges cut `[0, 2π)` into
/// arcs, each wholly inside or outside; the arcs whose midpoint is inside add `radius` times
/// their angle.
fn arc_length_in(rect: &Rect, radius: f64, sector: Option<(f64, f64)>) -> f64 {
    if radius <= 0.0 {
        return 0.0;
    }
    let (near, far) = rect.distance_range();
    if near > radius || far < radius {
        return 0.0;
    }
    let mut cuts = [0.0; 12];
    cuts[1] = TAU;
    let mut count = 2;
    let mut cut = |t: f64| {
        cuts[count] = t.rem_euclid(TAU);
        count += 1;
    };
    for x in [rect.x0, rect.x1] {
        if x.abs() < radius {
            let t = (x / radius).acos();
            cut(t);
            cut(-t);
        }
    }
    for y in [rect.y0, rect.y1] {
        if y.abs() < radius {
            let t = (y / radius).asin();
            cut(t);
            cut(PI - t);
        }
    }
    if let Some((a, b)) = sector {
        cut(a);
        cut(b);
    }
    let cuts = &mut cuts[..count];
    cuts.sort_by(f64::total_cmp);
    let in_sector = |t: f64| sector.is_none_or(|(a, b)| (t - a).rem_euclid(TAU) <= b - a);
    let mut length = 0.0;
    for w in cuts.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        if hi <= lo {
            continue;
        }
        let mid = 0.5 * (lo + hi);
        let (s, c) = mid.sin_cos();
        let (x, y) = (radius * c, radius * s);
        if x >= rect.x0 && x <= rect.x1 && y >= rect.y0 && y <= rect.y1 && in_sector(mid) {
            length += radius * (hi - lo);
        }
    }
    length
}

/// `∫ r dr` over the part of the ray at angle `theta` from the origin with `r` in
/// `[from, to]` that lies inside `rect` (each coordinate's slab clips the ray's `r`).
fn radial_moment_in(rect: &Rect, theta: f64, from: f64, to: f64) -> f64 {
    let (s, c) = theta.sin_cos();
    let (mut lo, mut hi) = (from, to);
    for (u, a, b) in [(c, rect.x0, rect.x1), (s, rect.y0, rect.y1)] {
        if u == 0.0 {
            if a > 0.0 || b < 0.0 {
                return 0.0;
            }
        } else {
            let (p, q) = (a / u, b / u);
            lo = lo.max(p.min(q));
            hi = hi.min(p.max(q));
        }
    }
    if hi > lo { 0.5 * (hi * hi - lo * lo) } else { 0.0 }
}

/// Area of `rect` where `inside` holds: nine probes, then a 16 × 16 supersampling if they disagree.
fn mask_area_in(rect: &Rect, inside: &MaskFn) -> f64 {
    let (w, h) = (rect.x1 - rect.x0, rect.y1 - rect.y0);
    let first = inside(rect.x0, rect.y0);
    let uniform =
        (0..3).all(|j| (0..3).all(|i| inside(rect.x0 + 0.5 * w * i as f64, rect.y0 + 0.5 * h * j as f64) == first));
    if uniform {
        return if first { rect.area() } else { 0.0 };
    }
    let s = MASK_SUPERSAMPLING;
    let mut count = 0usize;
    for j in 0..s {
        let y = rect.y0 + h * (j as f64 + 0.5) / s as f64;
        for i in 0..s {
            if inside(rect.x0 + w * (i as f64 + 0.5) / s as f64, y) {
                count += 1;
            }
        }
    }
    rect.area() * count as f64 / (s * s) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The obscuration's rate per pixel against central differences of the pixel's exact area
    /// (step 1e-6, truncation ~1e-12 of a pixel's area per unit ε; the radii are chosen off the
    /// grid lines, where the circle would be tangent to a pixel's side and the area not smooth
    /// in ε), for an annulus, an annular sector and a decentred annulus, and their
    /// sum against `∂(exact area)/∂ε = −ε × (the sector's angle)`.
    #[test]
    fn obscuration_rates_are_the_areas_derivatives() {
        let shapes = [
            (0.3, None, (0.0, 0.0)),
            (0.45, Some((-0.4, 1.9)), (0.0, 0.0)),
            (0.47, Some((1.0, 1.0 + TAU / 3.0)), (0.0, 0.0)),
            (0.3, None, (0.15, 0.0)),
        ];
        for (eps, sector, (dx, dy)) in shapes {
            let build = |e: f64| Aperture::disc(e, sector).unwrap().decentred(dx, dy).unwrap();
            let (ap, up, down) = (build(eps), build(eps + 1e-6), build(eps - 1e-6));
            for n in [7usize, 16, 33] {
                let h = 2.0 / n as f64;
                let mut total = 0.0;
                for j in 0..n {
                    for i in 0..n {
                        let (x0, y0) = (-1.0 + i as f64 * h, -1.0 + j as f64 * h);
                        let rate = ap.obscuration_rate_in(x0, x0 + h, y0, y0 + h).unwrap();
                        let d = (up.area_in(x0, x0 + h, y0, y0 + h) - down.area_in(x0, x0 + h, y0, y0 + h)) / 2e-6;
                        assert!((rate - d).abs() <= 1e-7, "ε {eps}, n {n}, ({i}, {j}): {rate} vs {d}");
                        total += rate;
                    }
                }
                let angle = sector.map_or(TAU, |(a, b)| b - a);
                assert!((total + eps * angle).abs() <= 1e-12, "ε {eps}, n {n}: {total} vs {}", -eps * angle);
            }
        }
        assert_eq!(Aperture::mask(|_, _| true).obscuration_rate_in(0.0, 0.1, 0.0, 0.1), None);
        assert_eq!(Aperture::circle().obscuration_rate_in(-0.1, 0.1, -0.1, 0.1), Some(0.0));
    }

    /// The exact pixel fractions sum to the exact area, for every disc shape, at coarse grids.
    #[test]
    fn pixel_areas_sum_to_the_exact_area() {
        let shapes = [
            Aperture::circle(),
            Aperture::annulus(0.37).unwrap(),
            Aperture::sector(0.3, 2.2).unwrap(),
            Aperture::sector(-1.0, 3.5).unwrap(),
            Aperture::disc(0.5, Some((1.0, 1.0 + TAU / 3.0))).unwrap(),
            Aperture::ring(0.0, 0.61, None).unwrap(),
            Aperture::ring(0.3, 0.8, None).unwrap(),
            Aperture::ring(0.45, 0.9, Some((-0.4, 1.9))).unwrap(),
            Aperture::ring(0.2, 0.7, Some((0.5, 0.5 + 4.0))).unwrap(),
        ];
        for ap in &shapes {
            for n in [7usize, 16, 33] {
                let h = 2.0 / n as f64;
                let mut total = 0.0;
                for j in 0..n {
                    for i in 0..n {
                        let (x0, y0) = (-1.0 + i as f64 * h, -1.0 + j as f64 * h);
                        total += ap.area_in(x0, x0 + h, y0, y0 + h);
                    }
                }
                let exact = ap.exact_area().unwrap();
                assert!((total - exact).abs() < 1e-13, "{ap:?} n = {n}: {total} vs {exact}");
            }
        }
    }

    /// Zones tiling the circle (three concentric rings of equal area, `r_j = √(j/3)`, and three
    /// sectors of the outer ring) share their boundary pixels: every pixel's areas add up to the
    /// circle's, to rounding.
    #[test]
    fn ring_zones_tile_the_circle_pixel_by_pixel() {
        let r = [0.0, (1.0f64 / 3.0).sqrt(), (2.0f64 / 3.0).sqrt(), 1.0];
        let third = TAU / 3.0;
        let zones = [
            Aperture::ring(r[0], r[1], None).unwrap(),
            Aperture::ring(r[1], r[2], None).unwrap(),
            Aperture::ring(r[2], r[3], Some((0.1, 0.1 + third))).unwrap(),
            Aperture::ring(r[2], r[3], Some((0.1 + third, 0.1 + 2.0 * third))).unwrap(),
            Aperture::ring(r[2], r[3], Some((0.1 + 2.0 * third, 0.1 + TAU))).unwrap(),
        ];
        for z in &zones[..2] {
            assert!((z.area_fraction() - 1.0 / 3.0).abs() < 1e-15, "{z:?}");
        }
        let circle = Aperture::circle();
        let n = 29;
        let h = 2.0 / n as f64;
        for j in 0..n {
            for i in 0..n {
                let (x0, y0) = (-1.0 + i as f64 * h, -1.0 + j as f64 * h);
                let sum: f64 = zones.iter().map(|z| z.area_in(x0, x0 + h, y0, y0 + h)).sum();
                let whole = circle.area_in(x0, x0 + h, y0, y0 + h);
                assert!((sum - whole).abs() < 1e-15, "pixel ({i}, {j}): {sum} vs {whole}");
            }
        }
    }

    #[test]
    fn ring_radii_are_validated() {
        for (inner, outer) in
            [(0.5, 0.5), (0.6, 0.5), (-0.1, 0.5), (0.0, 1.01), (0.0, 0.0), (f64::NAN, 0.5), (0.1, f64::NAN)]
        {
            assert!(Aperture::ring(inner, outer, None).is_err(), "({inner}, {outer})");
        }
        assert!(Aperture::ring(0.0, 1.0, None).unwrap().is_centred_circle());
        assert!(!Aperture::ring(0.0, 0.9, None).unwrap().is_centred_circle());
        assert!(Aperture::ring(0.2, 0.9, Some((1.0, 0.5))).is_err());
    }

    /// A pixel straddling the circle and a sector edge: the area against a fine midpoint rule.
    #[test]
    fn edge_pixel_area_matches_brute_force() {
        let ap = Aperture::sector(0.2, 0.75).unwrap();
        let r = Rect { x0: 0.55, x1: 0.8, y0: 0.45, y1: 0.7 };
        let exact = disc_area_in(&r, 0.0, 1.0, Some((0.2, 0.75)));
        let m = 2000;
        let mut count = 0usize;
        for j in 0..m {
            for i in 0..m {
                let x = r.x0 + (r.x1 - r.x0) * (i as f64 + 0.5) / m as f64;
                let y = r.y0 + (r.y1 - r.y0) * (j as f64 + 0.5) / m as f64;
                let phi = y.atan2(x);
                if x * x + y * y <= 1.0 && (0.2..=0.75).contains(&phi) {
                    count += 1;
                }
            }
        }
        let brute = r.area() * count as f64 / (m * m) as f64;
        assert!((exact - brute).abs() < 1e-5 * r.area(), "{exact} vs {brute}");
        assert!((ap.area_in(r.x0, r.x1, r.y0, r.y1) - exact).abs() < 1e-15);
    }

    /// Each edge's rate of a ring wedge's area in pixels that its circles and straight edges
    /// cross ([`Aperture::edge_rates_in`]) against central differences of the exact area
    /// ([`Aperture::area_in`], the slow, obviously correct reference) with that edge moved.
    #[test]
    fn edge_rates_match_differences_of_the_area() {
        let (inner, outer, a, b) = (0.3, 0.8, 0.4, 2.3);
        let ring = |d: [f64; 4]| Aperture::ring(inner + d[0], outer + d[1], Some((a + d[2], b + d[3]))).unwrap();
        let here = ring([0.0; 4]);
        let h = 1e-6;
        let n = 16;
        let w = 2.0 / n as f64;
        let mut crossed = [0usize; 4];
        for j in 0..n {
            for i in 0..n {
                let (x0, y0) = (-1.0 + i as f64 * w, -1.0 + j as f64 * w);
                let rates = here.edge_rates_in(x0, x0 + w, y0, y0 + w).unwrap();
                for (e, rate) in rates.iter().enumerate() {
                    let moved = |t: f64| {
                        let mut d = [0.0; 4];
                        d[e] = t;
                        ring(d).area_in(x0, x0 + w, y0, y0 + w)
                    };
                    let reference = (moved(h) - moved(-h)) / (2.0 * h);
                    assert!((rate - reference).abs() < 1e-7, "pixel ({i}, {j}) edge {e}: {rate} vs {reference}");
                    crossed[e] += usize::from(*rate != 0.0);
                }
            }
        }
        assert!(crossed.iter().all(|&c| c > 3), "{crossed:?}");
        // a mask has no edge parameters; a pixel far from every edge has no rate
        assert!(Aperture::mask(|_, _| true).edge_rates_in(0.0, 0.1, 0.0, 0.1).is_none());
        assert_eq!(here.edge_rates_in(0.9, 1.0, 0.9, 1.0), Some([0.0; 4]));
    }
}
