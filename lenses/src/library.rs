//! A metalens given as a meta-atom library and the layout that places its atoms, in the local
//! periodic approximation (docs/physics.md, "Designs given as data").

use std::sync::Arc;

use num_complex::Complex64;
use optics::radial::{RadialProfile, RadialPupil};
use optics::{Field, LensModel, Order, Wavefront};
use rand::SeedableRng;
use rand_distr::{Distribution as _, StandardNormal};
use rand_pcg::Pcg64;

use crate::Error;
use crate::chromatic::check;

/// Degree in `q = ρ²` of the even polynomial fitted to the layout's design phase.
const DESIGN_FIT_DEGREE: usize = 10;

/// A meta-atom library: the complex transmission `t(p, λ)` of one atom (in its periodic cell) on
/// a full grid of parameters (one or more, each sorted) and wavelengths. Between grid points the
/// amplitude `|t|` and the unwrapped phase are interpolated multilinearly (in every parameter and
/// in λ), apart: the field follows the arc from one row to the next, not the chord (the chord's
/// `|t|` dips by `1 − cos(Δφ/2)` midway, which cost a lossless library of 64 levels over 2π
/// `Δφ²/6 ≈ 1.6e-3` of its first-order efficiency). The phases of a cell's corners are unwrapped
/// against its first corner's (each within ±π of it), so that a phase wrapping from π to −π
/// between two atoms interpolates through the short way. What remains is linear
/// interpolation's error, `h²/8` times the second derivative of `|t|` or `φ` along the
/// parameter (or λ) with `h` the library's step there: it falls as the square of the library's
/// density (docs/physics.md, "Meta-atom library").
///
/// With [`Interpolation::Cubic`] ([`with_interpolation`](Library::with_interpolation)) the
/// amplitude and unwrapped phase are instead a C¹ piecewise cubic in every parameter (λ stays
/// linear): error `O(h⁴)`, and a derivative in the parameters that is continuous across the rows.
#[derive(Clone, Debug)]
pub struct Library {
    axes: Vec<Vec<f64>>,
    wavelengths: Vec<f64>,
    /// `|t|` and `arg t` (as given, rad) at every grid point, the wavelength fastest, then the
    /// last parameter, …
    amplitude: Vec<f64>,
    phase: Vec<f64>,
    /// a fin's unconverted (co-polarized) amplitude at every grid point, where given
    /// ([`with_co_amplitude`](Library::with_co_amplitude))
    co_amplitude: Option<Vec<f64>>,
    /// how the values are interpolated in the parameters
    interpolation: Interpolation,
    /// per parameter axis and row, the slope stencil of [`Interpolation::Cubic`]: its first row
    /// and the weights of the rows from there (the derivative at the row of the polynomial
    /// through its up to 5 nearest rows)
    slopes: Vec<Vec<(usize, Vec<f64>)>>,
}

/// How a [`Library`] interpolates `|t|` and the unwrapped phase between its rows in each
/// parameter (in λ both are linear).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interpolation {
    /// Multilinear (the default): error `h²/8 max|f''|` with `h` the rows' step; the derivative
    /// in a parameter jumps at every row.
    #[default]
    Linear,
    /// Piecewise cubic Hermite in each parameter (tensor product), the slope at each row that of
    /// the polynomial through the 5 nearest rows (fewer on an axis of fewer rows): C¹ in every
    /// parameter, error `h⁴/384 max|f⁗|` plus the slopes' `O(h⁴)` (docs/physics.md, "Meta-atom
    /// library"). `|t|` is clamped to `[0, 1]` where the cubic would leave it (near rows of
    /// `|t|` at 0 or 1 with curvature; a kink there, and only there).
    Cubic,
}

impl Interpolation {
    /// The scene's spelling, `"linear"` or `"cubic"`.
    pub fn name(self) -> &'static str {
        match self {
            Interpolation::Linear => "linear",
            Interpolation::Cubic => "cubic",
        }
    }
}

/// The weights of the slope at every row of `axis`: the derivative at the row of the Lagrange
/// polynomial through the `min(5, n)` rows nearest it (centred where the axis allows):
/// `ℓ_k'(x_i) = Π_{m≠k,i}(x_i − x_m) / Π_{m≠k}(x_k − x_m)` for `k ≠ i` and
/// `ℓ_i'(x_i) = Σ_{m≠i} 1/(x_i − x_m)`.
fn slope_stencils(axis: &[f64]) -> Vec<(usize, Vec<f64>)> {
    let n = axis.len();
    let width = n.min(5);
    (0..n)
        .map(|i| {
            let start = i.saturating_sub(2).min(n - width);
            let xs = &axis[start..start + width];
            let xi = axis[i];
            let weights = (0..width)
                .map(|k| {
                    if start + k == i {
                        (0..width).filter(|&m| m != k).map(|m| 1.0 / (xi - xs[m])).sum()
                    } else {
                        let num: f64 = (0..width).filter(|&m| m != k && start + m != i).map(|m| xi - xs[m]).product();
                        let den: f64 = (0..width).filter(|&m| m != k).map(|m| xs[k] - xs[m]).product();
                        num / den
                    }
                })
                .collect();
            (start, weights)
        })
        .collect()
}

/// The cell `i` (`axis[i] ≤ x ≤ axis[i + 1]`) and the fraction along it, clamped to the axis's
/// ends; `(0, 0)` on a one-point axis.
fn cell_of(axis: &[f64], x: f64) -> (usize, f64) {
    if axis.len() == 1 {
        return (0, 0.0);
    }
    let i = axis.partition_point(|&a| a <= x).clamp(1, axis.len() - 1) - 1;
    (i, ((x - axis[i]) / (axis[i + 1] - axis[i])).clamp(0.0, 1.0))
}

/// `b − a` brought within ±π (the short way round).
fn wrapped_step(a: f64, b: f64) -> f64 {
    let step = b - a;
    step - std::f64::consts::TAU * (step / std::f64::consts::TAU).round()
}

impl Library {
    /// A library from rows `(parameters, wavelength_m, amplitude, phase_rad)`: the rows must
    /// hold every combination of the distinct parameter values and wavelengths exactly once
    /// (a full grid, in any order), each amplitude in `[0, 1]`.
    pub fn new(rows: &[(Vec<f64>, f64, f64, f64)]) -> Result<Library, Error> {
        let Some(first) = rows.first() else {
            return Err(Error::OutOfRange { name: "library rows", value: 0.0, expected: "at least one row" });
        };
        let dims = first.0.len();
        if dims == 0 {
            return Err(Error::OutOfRange {
                name: "library parameters",
                value: 0.0,
                expected: "at least one parameter column",
            });
        }
        let distinct = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        };
        let mut axes = Vec::new();
        for d in 0..dims {
            axes.push(distinct(rows.iter().map(|r| r.0.get(d).copied().unwrap_or(f64::NAN)).collect()));
        }
        let wavelengths = distinct(rows.iter().map(|r| r.1).collect());
        let size: usize = axes.iter().map(Vec::len).product::<usize>() * wavelengths.len();
        if size != rows.len() {
            return Err(Error::OutOfRange {
                name: "library rows",
                value: rows.len() as f64,
                expected: "a full grid: one row for every combination of the parameters' and wavelengths' distinct values",
            });
        }
        let mut amplitude = vec![f64::NAN; size];
        let mut phase = vec![f64::NAN; size];
        for (p, lambda, row_amplitude, row_phase) in rows {
            for v in p.iter().chain([lambda, row_amplitude, row_phase]) {
                check("library value", *v, true, "finite")?;
            }
            check(
                "library amplitude",
                *row_amplitude,
                (0.0..=1.0).contains(row_amplitude),
                "an amplitude |t| in [0, 1]",
            )?;
            let index = grid_index(&axes, &wavelengths, p, *lambda);
            if !amplitude[index].is_nan() {
                return Err(Error::OutOfRange {
                    name: "library row repeated at wavelength (m)",
                    value: *lambda,
                    expected: "one row per parameter combination and wavelength",
                });
            }
            amplitude[index] = *row_amplitude;
            phase[index] = *row_phase;
        }
        let slopes = axes.iter().map(|a| slope_stencils(a)).collect();
        Ok(Library {
            axes,
            wavelengths,
            amplitude,
            phase,
            co_amplitude: None,
            interpolation: Interpolation::Linear,
            slopes,
        })
    }

    /// This library with the unconverted amplitude `|t_co|` of a fin (the light that keeps the
    /// incident circular polarization, without the geometric phase: zero-order light;
    /// docs/physics.md, "2-D library layouts"), one value per row of `rows` (the rows this
    /// library was made from), each in `[0, 1]` with `|t|² + |t_co|² ≤ 1` (1e-9 allowed for
    /// rounding).
    pub fn with_co_amplitude(self, rows: &[(Vec<f64>, f64, f64, f64)], co: &[f64]) -> Result<Library, Error> {
        if co.len() != rows.len() {
            return Err(Error::OutOfRange {
                name: "library co_amplitude values",
                value: co.len() as f64,
                expected: "one per library row",
            });
        }
        let mut values = vec![0.0; self.amplitude.len()];
        for ((p, lambda, a, _), &c) in rows.iter().zip(co) {
            check("library co_amplitude", c, (0.0..=1.0).contains(&c), "an unconverted amplitude |t_co| in [0, 1]")?;
            check(
                "library co_amplitude",
                c,
                a * a + c * c <= 1.0 + 1e-9,
                "|t|² + |t_co|² ≤ 1 (a fin transmits at most the light on it)",
            )?;
            values[grid_index(&self.axes, &self.wavelengths, p, *lambda)] = c;
        }
        Ok(Library { co_amplitude: Some(values), ..self })
    }

    /// This library interpolated in the parameters by `interpolation`.
    pub fn with_interpolation(self, interpolation: Interpolation) -> Library {
        Library { interpolation, ..self }
    }

    /// How the library interpolates in the parameters.
    pub fn interpolation(&self) -> Interpolation {
        self.interpolation
    }

    /// Whether the library gives a fin's unconverted amplitude.
    pub fn has_co_amplitude(&self) -> bool {
        self.co_amplitude.is_some()
    }

    /// `|t_co(p, λ)|`, interpolated in the parameters and λ as `|t|` is (0 where the library
    /// gives none).
    pub fn co_amplitude(&self, params: &[f64], wavelength_m: f64) -> f64 {
        let Some(co) = &self.co_amplitude else { return 0.0 };
        if self.interpolation == Interpolation::Cubic {
            return self.cubic(params, wavelength_m, &|index| (co[index], 0.0)).0.clamp(0.0, 1.0);
        }
        self.corners(params, wavelength_m).iter().map(|&(index, weight)| weight * co[index]).sum()
    }

    /// The grid points around `(params, λ)` and their multilinear weights, the cell's first
    /// corner (every axis at its lower end) first; corners off a one-point axis weigh 0.
    fn corners(&self, params: &[f64], wavelength_m: f64) -> Vec<(usize, f64)> {
        // the cell and the fractions along every axis (the wavelength last)
        let mut cells: Vec<(usize, f64)> = Vec::with_capacity(self.axes.len() + 1);
        for (axis, &p) in self.axes.iter().zip(params).chain(std::iter::once((&self.wavelengths, &wavelength_m))) {
            if axis.len() == 1 {
                cells.push((0, 0.0));
                continue;
            }
            let i = axis.partition_point(|&a| a <= p).clamp(1, axis.len() - 1) - 1;
            let f = ((p - axis[i]) / (axis[i + 1] - axis[i])).clamp(0.0, 1.0);
            cells.push((i, f));
        }
        let lens: Vec<usize> = self.axes.iter().map(Vec::len).chain([self.wavelengths.len()]).collect();
        (0..(1usize << cells.len()))
            .map(|corner| {
                let mut index = 0;
                let mut weight = 1.0;
                for (d, &(i, f)) in cells.iter().enumerate() {
                    let up = (corner >> d) & 1 == 1 && lens[d] > 1;
                    if (corner >> d) & 1 == 1 && lens[d] == 1 {
                        weight = 0.0;
                    }
                    index = index * lens[d] + i + usize::from(up);
                    weight *= if up { f } else { 1.0 - f };
                }
                (index, weight)
            })
            .collect()
    }

    /// The parameter ranges `(min, max)`, one per parameter.
    pub fn ranges(&self) -> Vec<(f64, f64)> {
        self.axes.iter().map(|a| (a[0], a[a.len() - 1])).collect()
    }

    /// The wavelength range (m).
    pub fn wavelength_range(&self) -> (f64, f64) {
        (self.wavelengths[0], self.wavelengths[self.wavelengths.len() - 1])
    }

    /// The library's wavelengths (m), sorted.
    pub fn wavelengths(&self) -> &[f64] {
        &self.wavelengths
    }

    /// The number of parameters.
    pub fn dimensions(&self) -> usize {
        self.axes.len()
    }

    /// `t(p, λ)`: `|t|` and the phase multilinear in the parameters and λ (clamped to the grid's
    /// ends), the corners' phases unwrapped against the cell's first corner (type docs); with
    /// [`Interpolation::Cubic`], cubic in the parameters ([`Interpolation`]).
    pub fn transmission(&self, params: &[f64], wavelength_m: f64) -> Complex64 {
        if self.interpolation == Interpolation::Cubic {
            let (amplitude, phase) =
                self.cubic(params, wavelength_m, &|index| (self.amplitude[index], self.phase[index]));
            return Complex64::from_polar(amplitude.clamp(0.0, 1.0), phase);
        }
        let (mut amplitude, mut phase) = (0.0, 0.0);
        let mut reference = None;
        for (index, weight) in self.corners(params, wavelength_m) {
            // corner 0 (every axis at its cell's lower end) exists and comes first
            let base = *reference.get_or_insert(self.phase[index]);
            if weight != 0.0 {
                let step = self.phase[index] - base;
                let unwrapped = step - std::f64::consts::TAU * (step / std::f64::consts::TAU).round();
                amplitude += weight * self.amplitude[index];
                phase += weight * unwrapped;
            }
        }
        Complex64::from_polar(amplitude, reference.unwrap_or(0.0) + phase)
    }
}

impl Library {
    /// The cubic interpolant ([`Interpolation::Cubic`]) of the grid values `values(index) =
    /// (amplitude, phase)` at `(params, λ)`, unclamped.
    fn cubic(&self, params: &[f64], wavelength_m: f64, values: &dyn Fn(usize) -> (f64, f64)) -> (f64, f64) {
        let (li, lf) = cell_of(&self.wavelengths, wavelength_m);
        self.cubic_axis(0, 0, params, (li, lf), values)
    }

    /// The interpolant along parameter axes `d…` (tensor product, the first axis outermost) of
    /// the values whose earlier axes' indices make `base`; λ linear in the cell `lambda`. Along
    /// each axis the stencil's values are unwrapped in phase one after the next (each step within
    /// ±π), then interpolated by the cubic Hermite of the rows' slopes.
    fn cubic_axis(
        &self,
        d: usize,
        base: usize,
        params: &[f64],
        lambda: (usize, f64),
        values: &dyn Fn(usize) -> (f64, f64),
    ) -> (f64, f64) {
        if d == self.axes.len() {
            let n = self.wavelengths.len();
            let (a0, p0) = values(base * n + lambda.0);
            if n == 1 || lambda.1 == 0.0 {
                return (a0, p0);
            }
            let (a1, p1) = values(base * n + lambda.0 + 1);
            let f = lambda.1;
            return ((1.0 - f) * a0 + f * a1, p0 + f * wrapped_step(p0, p1));
        }
        let axis = &self.axes[d];
        let n = axis.len();
        if n == 1 {
            return self.cubic_axis(d + 1, base * n, params, lambda, values);
        }
        let (i, t) = cell_of(axis, params.get(d).copied().unwrap_or(f64::NAN));
        let (s0, w0) = &self.slopes[d][i];
        let (s1, w1) = &self.slopes[d][i + 1];
        let lo = (*s0).min(*s1);
        let hi = (s0 + w0.len()).max(s1 + w1.len());
        let mut local: Vec<(f64, f64)> = Vec::with_capacity(hi - lo);
        for j in lo..hi {
            let (a, p) = self.cubic_axis(d + 1, base * n + j, params, lambda, values);
            let p = match local.last() {
                Some(&(_, last)) => last + wrapped_step(last, p),
                None => p,
            };
            local.push((a, p));
        }
        let slope = |start: usize, weights: &[f64]| {
            weights.iter().enumerate().fold((0.0, 0.0), |(sa, sp), (k, w)| {
                let (a, p) = local[start + k - lo];
                (sa + w * a, sp + w * p)
            })
        };
        let (m0, m1) = (slope(*s0, w0), slope(*s1, w1));
        let (y0, y1) = (local[i - lo], local[i + 1 - lo]);
        let h = axis[i + 1] - axis[i];
        // the cubic Hermite basis on [0, 1]
        let (t2, t3) = (t * t, t * t * t);
        let (h00, h10, h01, h11) = (2.0 * t3 - 3.0 * t2 + 1.0, t3 - 2.0 * t2 + t, -2.0 * t3 + 3.0 * t2, t3 - t2);
        let hermite = |y0: f64, m0: f64, y1: f64, m1: f64| h00 * y0 + h10 * h * m0 + h01 * y1 + h11 * h * m1;
        (hermite(y0.0, m0.0, y1.0, m1.0), hermite(y0.1, m0.1, y1.1, m1.1))
    }
}

/// A value and its derivative with respect to one parameter: `(|t|, arg t, ∂|t|, ∂ arg t)`.
type Dual = [f64; 4];

impl Library {
    /// `t(p, λ)` and its derivative `∂t/∂p_wrt` (per unit of the parameter `wrt`, 0-based) with
    /// [`Interpolation::Cubic`]: forward mode on [`transmission`](Self::transmission)'s own
    /// rule. Along each axis the Hermite interpolant is linear in the rows' values and slopes
    /// (the slope stencils are linear in the rows), so the derivative along an axis other than
    /// `wrt` is the same interpolant of the inner derivatives; along `wrt` it adds the basis'
    /// derivative `(h₀₀′ y₀ + h₁₀′ h m₀ + h₀₁′ y₁ + h₁₁′ h m₁)/h` (`t` moves by `1/h` per unit of
    /// the parameter, 0 where the parameter is clamped to the axis's ends). The phase steps
    /// unwrapped by whole turns are constants, and where `|t|` is clamped to `[0, 1]` its
    /// derivative is 0 (the clamp's one-sided value). Then `∂t = (∂|t| + i |t| ∂ arg t) e^{i arg t}`.
    /// The value is [`transmission`](Self::transmission)'s, bit for bit. `None` with
    /// [`Interpolation::Linear`] (a kink at every row: no derivative there) or `wrt` out of range.
    pub fn transmission_and_derivative(
        &self,
        params: &[f64],
        wavelength_m: f64,
        wrt: usize,
    ) -> Option<(Complex64, Complex64)> {
        if self.interpolation != Interpolation::Cubic || wrt >= self.axes.len() {
            return None;
        }
        let (li, lf) = cell_of(&self.wavelengths, wavelength_m);
        let values = |index: usize| (self.amplitude[index], self.phase[index]);
        let [a, p, da, dp] = self.cubic_axis_dual(0, 0, params, (li, lf), wrt, &values);
        let (a, da) = if (0.0..=1.0).contains(&a) { (a, da) } else { (a.clamp(0.0, 1.0), 0.0) };
        let t = Complex64::from_polar(a, p);
        Some((t, Complex64::new(da, a * dp) * Complex64::from_polar(1.0, p)))
    }

    /// A fin's unconverted amplitude `|t_co(p, λ)|` ([`co_amplitude`](Self::co_amplitude)) and
    /// its derivative `∂|t_co|/∂p_wrt` with [`Interpolation::Cubic`]: forward mode on the same
    /// interpolant as [`transmission_and_derivative`](Self::transmission_and_derivative)'s `|t|`
    /// (0 where the value is clamped to `[0, 1]`). The value is
    /// [`co_amplitude`](Self::co_amplitude)'s, bit for bit. `(0, 0)` where the library gives no
    /// unconverted amplitude; `None` with [`Interpolation::Linear`] or `wrt` out of range.
    pub fn co_amplitude_and_derivative(&self, params: &[f64], wavelength_m: f64, wrt: usize) -> Option<(f64, f64)> {
        if self.interpolation != Interpolation::Cubic || wrt >= self.axes.len() {
            return None;
        }
        let Some(co) = &self.co_amplitude else { return Some((0.0, 0.0)) };
        let (li, lf) = cell_of(&self.wavelengths, wavelength_m);
        let values = |index: usize| (co[index], 0.0);
        let [a, _, da, _] = self.cubic_axis_dual(0, 0, params, (li, lf), wrt, &values);
        Some(if (0.0..=1.0).contains(&a) { (a, da) } else { (a.clamp(0.0, 1.0), 0.0) })
    }

    /// [`cubic_axis`](Self::cubic_axis) of the grid values `values(index) = (amplitude, phase)`
    /// with the derivative along parameter `wrt` carried beside each value ([`transmission_and_derivative`](Self::transmission_and_derivative)).
    fn cubic_axis_dual(
        &self,
        d: usize,
        base: usize,
        params: &[f64],
        lambda: (usize, f64),
        wrt: usize,
        values: &dyn Fn(usize) -> (f64, f64),
    ) -> Dual {
        if d == self.axes.len() {
            let n = self.wavelengths.len();
            let index = base * n + lambda.0;
            let (a0, p0) = values(index);
            if n == 1 || lambda.1 == 0.0 {
                return [a0, p0, 0.0, 0.0];
            }
            let (a1, p1) = values(index + 1);
            let f = lambda.1;
            return [(1.0 - f) * a0 + f * a1, p0 + f * wrapped_step(p0, p1), 0.0, 0.0];
        }
        let axis = &self.axes[d];
        let n = axis.len();
        if n == 1 {
            return self.cubic_axis_dual(d + 1, base * n, params, lambda, wrt, values);
        }
        let x = params.get(d).copied().unwrap_or(f64::NAN);
        let (i, t) = cell_of(axis, x);
        let (s0, w0) = &self.slopes[d][i];
        let (s1, w1) = &self.slopes[d][i + 1];
        let lo = (*s0).min(*s1);
        let hi = (s0 + w0.len()).max(s1 + w1.len());
        let mut local: Vec<Dual> = Vec::with_capacity(hi - lo);
        for j in lo..hi {
            let [a, p, da, dp] = self.cubic_axis_dual(d + 1, base * n + j, params, lambda, wrt, values);
            let p = match local.last() {
                Some(&[_, last, _, _]) => last + wrapped_step(last, p),
                None => p,
            };
            local.push([a, p, da, dp]);
        }
        let slope = |start: usize, weights: &[f64]| {
            weights.iter().enumerate().fold([0.0; 4], |mut s, (k, w)| {
                let v = local[start + k - lo];
                for (s, v) in s.iter_mut().zip(v) {
                    *s += w * v;
                }
                s
            })
        };
        let (m0, m1) = (slope(*s0, w0), slope(*s1, w1));
        let (y0, y1) = (local[i - lo], local[i + 1 - lo]);
        let h = axis[i + 1] - axis[i];
        let (t2, t3) = (t * t, t * t * t);
        let (h00, h10, h01, h11) = (2.0 * t3 - 3.0 * t2 + 1.0, t3 - 2.0 * t2 + t, -2.0 * t3 + 3.0 * t2, t3 - t2);
        let hermite = |c: usize| h00 * y0[c] + h10 * h * m0[c] + h01 * y1[c] + h11 * h * m1[c];
        let mut out = [hermite(0), hermite(1), hermite(2), hermite(3)];
        // the parameter inside the axis (not clamped to its ends): t moves by 1/h per unit
        let raw = (x - axis[i]) / h;
        if d == wrt && (0.0..=1.0).contains(&raw) {
            let (g00, g10, g01, g11) =
                (6.0 * t2 - 6.0 * t, 3.0 * t2 - 4.0 * t + 1.0, -6.0 * t2 + 6.0 * t, 3.0 * t2 - 2.0 * t);
            for (c, o) in [(0, 2), (1, 3)] {
                out[o] += (g00 * y0[c] + g10 * h * m0[c] + g01 * y1[c] + g11 * h * m1[c]) / h;
            }
        }
        out
    }
}

/// The place of the grid point `(p, λ)` in a library's values (the wavelength fastest, then the
/// last parameter, …); `p` and `λ` must be values of the axes.
fn grid_index(axes: &[Vec<f64>], wavelengths: &[f64], p: &[f64], lambda: f64) -> usize {
    let mut index = 0;
    for (d, axis) in axes.iter().enumerate() {
        index = index * axis.len() + axis.partition_point(|&a| a < p[d]);
    }
    index * wavelengths.len() + wavelengths.partition_point(|&l| l < lambda)
}

/// A metalens of meta-atoms from a [`Library`] placed in rings of equal pitch (a layout), in the
/// local periodic approximation (docs/physics.md, "Designs given as data"):
///
/// - atom `i` fills the ring `[r_i − Λ/2, r_i + Λ/2]` (Λ the pitch) with its library field
///   `t(p_i, λ)`, held over its cell;
/// - the design phase `ψ(r)` is the atoms' phase at λ0, unwrapped along the radius and fitted by
///   an even polynomial in `ρ²` (degree `DESIGN_FIT_DEGREE`); its `2π` steps are the zones;
/// - at each wavelength and in each zone the field, as a function of `ψ` over one period, has the
///   Fourier coefficients `c_m = (1/2π) ∫ f(ψ) e^{−imψ} dψ` (each atom's constant field over its
///   interval of `ψ`); order 1 carries `|c_1|²` of the zone's light with the phase `ψ + arg c_1`
///   (the imaging order: its coherent part, a least-squares polynomial in `ρ²` through the zones'
///   `c_1`, gives a radial pupil of amplitude `|c_1(ρ)|` and wavefront
///   `W = (λ/2π)(ψ + arg c_1) + sag` against the exact reference sphere); the zone-to-zone
///   scatter about it (the atoms' discreteness) and every other order (order m focuses at `f/m`)
///   are background;
/// - `τ1(λ) = ∫|c_1|² dA/(πR²)` of the coherent part, `T(λ) = Σ_atoms |t_i|² × area` (fractions
///   of the light on the aperture; Parseval: `Σ_m |c_m|²` is the zone's mean `|t|²`).
///
/// A staircase of N equal phase levels per zone gives `c_1 = sinc(1/N)` (tested).
#[derive(Debug)]
pub struct LibraryLens {
    f_number: f64,
    focal_length: f64,
    design_wavelength: f64,
    library: Arc<Library>,
    /// ring centres, m
    radii: Vec<f64>,
    pitch: f64,
    params: Vec<Vec<f64>>,
    /// the design phase as an even polynomial in q = ρ² (radians)
    design: Arc<RadialProfile>,
    design_coefficients: Vec<f64>,
    sphere: Arc<RadialProfile>,
    source: String,
    /// the distinct parameter sets, each atom's index into them and its area fraction
    unique: Vec<Vec<f64>>,
    atoms: Vec<(usize, f64)>,
    /// each atom's fabrication error factor `(1 + ε_i) e^{iδ_i}` (aligned with `atoms`), when
    /// [`LibraryLens::with_fabrication`] gave errors
    factors: Option<Vec<Complex64>>,
    /// each atom's phase draw `δ_i` (aligned with `atoms`; its factor's phase is `σ_φ δ_i`),
    /// drawn whatever σ_φ (the phase error's derivative at σ_φ = 0 needs them); empty before
    /// [`LibraryLens::with_fabrication`]
    phase_draws: Vec<f64>,
    /// how many atoms' amplitude factor `1 + ε_i` was drawn below 0 and taken as 0
    clamped: usize,
    /// each atom's layout row
    rows: Vec<usize>,
    /// the atoms' cells split at the zones, and the zones' (q at their middle, area fraction)
    cells: Vec<Cell>,
    zones: Vec<(f64, f64)>,
    /// the first order at the wavelengths asked so far: (λ bits, τ1, T, pupil)
    cache: std::sync::Mutex<Vec<Cached>>,
}

/// A wavelength's first order: (λ bits, τ1, T, pupil).
type Cached = (u64, f64, f64, Option<Arc<RadialPupil>>);

impl Clone for LibraryLens {
    fn clone(&self) -> LibraryLens {
        LibraryLens {
            f_number: self.f_number,
            focal_length: self.focal_length,
            design_wavelength: self.design_wavelength,
            library: self.library.clone(),
            radii: self.radii.clone(),
            pitch: self.pitch,
            params: self.params.clone(),
            design: self.design.clone(),
            design_coefficients: self.design_coefficients.clone(),
            sphere: self.sphere.clone(),
            source: self.source.clone(),
            unique: self.unique.clone(),
            atoms: self.atoms.clone(),
            factors: self.factors.clone(),
            phase_draws: self.phase_draws.clone(),
            clamped: self.clamped,
            rows: self.rows.clone(),
            cells: self.cells.clone(),
            zones: self.zones.clone(),
            cache: std::sync::Mutex::new(Vec::new()),
        }
    }
}

impl LibraryLens {
    /// A library lens of working F-number `f_number` with the detector at `focal_length_m`,
    /// designed at `design_wavelength_m`, from `library` and the layout's ring centres
    /// `radii_m` (equal pitch, from the axis outwards, covering the aperture `f0/(2F#)`) with
    /// each atom's parameters `params` (inside the library's ranges).
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        design_wavelength_m: f64,
        library: Arc<Library>,
        radii_m: Vec<f64>,
        params: Vec<Vec<f64>>,
        source: String,
    ) -> Result<LibraryLens, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        check("design_wavelength", design_wavelength_m, design_wavelength_m > 0.0, "a finite wavelength > 0 m")?;
        if library.has_co_amplitude() {
            return Err(Error::Layout(
                "the library's co_amplitude column is a fin's unconverted light (a 2-D layout of fins): a radial layout's atoms have no angle".into(),
            ));
        }
        let radius = 0.5 * focal_length_m / f_number;
        if radii_m.len() < 4 || radii_m.len() != params.len() {
            return Err(Error::OutOfRange {
                name: "layout atoms",
                value: radii_m.len() as f64,
                expected: "at least 4 rings, each with its parameters",
            });
        }
        let pitch = radii_m[1] - radii_m[0];
        check("layout pitch (m)", pitch, pitch > 0.0, "> 0: ring centres increasing")?;
        for (i, w) in radii_m.windows(2).enumerate() {
            let step = w[1] - w[0];
            if (step - pitch).abs() > 1e-6 * pitch {
                return Err(Error::OutOfRange {
                    name: "layout ring spacing (m)",
                    value: step,
                    expected: if i == 0 { "equal pitch" } else { "equal to the first spacing (an equal pitch)" },
                });
            }
        }
        check(
            "layout first ring centre (m)",
            radii_m[0],
            (radii_m[0] - 0.5 * pitch).abs() <= 1e-6 * pitch || radii_m[0].abs() <= 1e-6 * pitch,
            "half a pitch (cells from the axis) or 0",
        )?;
        let outer = radii_m[radii_m.len() - 1] + 0.5 * pitch;
        check("layout outer edge (m)", outer, outer >= radius * (1.0 - 1e-9), "at least the aperture radius f0/(2F#)")?;
        let ranges = library.ranges();
        for p in &params {
            if p.len() != ranges.len() {
                return Err(Error::OutOfRange {
                    name: "layout parameters per atom",
                    value: p.len() as f64,
                    expected: "as many as the library's parameter columns",
                });
            }
            for (&v, &(lo, hi)) in p.iter().zip(&ranges) {
                check("layout parameter", v, v >= lo && v <= hi, "inside the library's range of that parameter")?;
            }
        }
        let (lo, hi) = library.wavelength_range();
        check(
            "design_wavelength",
            design_wavelength_m,
            design_wavelength_m >= lo && design_wavelength_m <= hi,
            "inside the library's wavelengths",
        )?;
        // the design phase: the atoms' phase at λ0, unwrapped, fitted in q over the aperture
        let mut unwrapped: Vec<f64> = Vec::with_capacity(radii_m.len());
        for p in &params {
            let phase = library.transmission(p, design_wavelength_m).arg();
            let value = match unwrapped.last() {
                None => phase,
                Some(&last) => {
                    let turns = ((last - phase) / std::f64::consts::TAU).round();
                    let value = phase + turns * std::f64::consts::TAU;
                    // a step near π cannot be unwrapped: which way the phase went is unknown
                    check(
                        "layout phase step between neighbouring atoms at λ0 (rad)",
                        (value - last).abs(),
                        (value - last).abs() <= 0.9 * std::f64::consts::PI,
                        "at most 0.9π: the design phase is the atoms' phase unwrapped along the radius, which needs at least three atoms a zone and more than two phase levels",
                    )?;
                    value
                }
            };
            unwrapped.push(value);
        }
        let inside: Vec<(f64, f64)> = radii_m
            .iter()
            .zip(&unwrapped)
            .filter(|(r, _)| **r <= radius)
            .map(|(r, phi)| ((r / radius).powi(2), *phi))
            .collect();
        // a flat plate (every atom's phase alike): ψ has no zones, so no first order to image
        if let Some(&(_, first)) = inside.first()
            && inside.iter().all(|&(_, phi)| phi == first)
        {
            return Err(Error::Layout(format!(
                "every atom inside the aperture has the same phase at λ0 ({first:.6} rad): the layout is a flat plate, which focuses nothing (its design phase has no zones, so no imaging order: all its light is zero order); a lens's atoms follow a focusing phase profile"
            )));
        }
        let design_coefficients = fit_even(&inside, DESIGN_FIT_DEGREE);
        let design = Arc::new(RadialProfile::even_polynomial(design_coefficients.clone()).map_err(Error::Pupil)?);
        let sphere = Arc::new(RadialProfile::reference_sphere(radius, focal_length_m).map_err(Error::Pupil)?);
        // the cells, split where ψ crosses a whole turn from the axis (the zones), λ-independent
        let area = std::f64::consts::PI * radius * radius;
        let psi = |r: f64| design.value((r / radius).powi(2));
        let psi0 = psi(0.0);
        // a nearly flat plate (all atoms alike but a few): the fitted ψ never turns a whole 2π
        // across the aperture, so there is no zone edge and no imaging order to speak of, only
        // the zero order's plane wave, defocused against the detector by the whole sag of the
        // focal length's sphere (about R²/(2 f0 λ0) waves: 84 at F/2.5, f0 = 3.36 mm, 800 nm).
        // Refused as the flat plate is: its evaluation took minutes (each of its OTFs integrates
        // that defocus and the fit's wiggles) for a result beyond the Fraunhofer model anyway
        let span = inside.iter().map(|&(q, _)| (design.value(q) - psi0).abs()).fold(0.0, f64::max);
        if span < std::f64::consts::TAU {
            let fresnel = radius * radius / (2.0 * focal_length_m * design_wavelength_m);
            let unlike = inside.iter().filter(|&&(_, phi)| phi != inside[0].1).count();
            return Err(Error::Layout(format!(
                "the atoms' phase at λ0, unwrapped and fitted, changes by {span:.3e} rad across the aperture, less than one zone (2π; {unlike} of the {} atoms inside it differ in phase from the one on the axis): a nearly flat plate has no zone, so no imaging order (its light is the zero order's plane wave); a lens of f0 = {:.4} mm at λ0 = {:.1} nm has about {fresnel:.1} zones across this aperture",
                inside.len(),
                focal_length_m * 1e3,
                design_wavelength_m * 1e9
            )));
        }
        let turns = |r: f64| ((psi(r) - psi0).abs() / std::f64::consts::TAU).floor();
        let mut unique: Vec<Vec<f64>> = Vec::new();
        let mut atoms = Vec::new();
        let mut cells = Vec::new();
        let mut zone_edges: Vec<(f64, f64)> = Vec::new();
        let mut rows = Vec::new();
        for (row, (r, p)) in radii_m.iter().zip(&params).enumerate() {
            let (a, b) = ((r - 0.5 * pitch).max(0.0), (r + 0.5 * pitch).min(radius));
            if b <= a {
                continue;
            }
            let u = match unique.iter().position(|x| x == p) {
                Some(u) => u,
                None => {
                    unique.push(p.clone());
                    unique.len() - 1
                }
            };
            atoms.push((u, std::f64::consts::PI * (b * b - a * a) / area));
            rows.push(row);
            let atom = atoms.len() - 1;
            let mut start = a;
            while start < b {
                let k = turns(start);
                let mut end = b;
                if turns(b) > k {
                    let (mut lo, mut hi) = (start, b);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if turns(mid) > k { hi = mid } else { lo = mid }
                    }
                    end = hi;
                }
                let (pa, pb) = (psi(start), psi(end));
                let zone = k as usize;
                if zone_edges.len() <= zone {
                    zone_edges.resize(zone + 1, (f64::NAN, f64::NAN));
                }
                let edges = &mut zone_edges[zone];
                if edges.0.is_nan() {
                    edges.0 = start;
                }
                edges.1 = end;
                let kernel = (Complex64::from_polar(1.0, -pb) - Complex64::from_polar(1.0, -pa)) * Complex64::i();
                cells.push(Cell { atom, zone, kernel, span: pb - pa });
                if end <= start {
                    break;
                }
                start = end;
            }
        }
        let zones = zone_edges
            .iter()
            .map(|&(r_in, r_out)| {
                if r_in.is_nan() {
                    (0.0, 0.0)
                } else {
                    let q = 0.5 * (r_in * r_in + r_out * r_out) / (radius * radius);
                    (q, std::f64::consts::PI * (r_out * r_out - r_in * r_in) / area)
                }
            })
            .collect();
        Ok(LibraryLens {
            f_number,
            focal_length: focal_length_m,
            design_wavelength: design_wavelength_m,
            library,
            radii: radii_m,
            pitch,
            params,
            design,
            design_coefficients,
            sphere,
            source,
            unique,
            atoms,
            factors: None,
            phase_draws: Vec::new(),
            clamped: 0,
            rows,
            cells,
            zones,
            cache: std::sync::Mutex::new(Vec::new()),
        })
    }

    /// The lens as fabricated (docs/physics.md, "Fabrication errors of a library lens"): every
    /// atom's parameters shifted by `bias` (one per parameter, in the library's units; an atom
    /// pushed outside the library's range is refused) and, per atom `i` of the layout (a layout
    /// row, in order), an independent fabrication error of its complex transmission,
    /// `t_i(λ) → t_i(λ) (1 + ε_i) e^{iδ_i}` with `δ_i ~ N(0, σ_φ²)` (radians, the same at every
    /// wavelength: an error of the pillar's phase) and `ε_i ~ N(0, σ_t²)` (relative amplitude),
    /// drawn from `Pcg64::seed_from_u64(errors.seed)`, per row `δ` then `ε` (both drawn for every
    /// row, so a row's phase error does not depend on σ_t). `1 + ε_i < 0` is taken as 0 (an atom
    /// that transmits nothing; [`LibraryLens::clamped_atoms`] counts them: σ_t < 0.5 is required,
    /// so that is below 2.3 % of the atoms), and `|t_i|` is capped at 1 (a passive atom). The
    /// design phase ψ and the zones stay the nominal layout's (the design intent). With no bias
    /// and σ = 0 the lens is the nominal one, bit for bit.
    pub fn with_fabrication(mut self, bias: &[f64], errors: AtomErrors) -> Result<LibraryLens, Error> {
        errors.check(bias, &self.library)?;
        let ranges = self.library.ranges();
        if bias.iter().any(|&b| b != 0.0) {
            for p in &mut self.params {
                for (v, b) in p.iter_mut().zip(bias) {
                    *v += b;
                }
            }
            for (d, &(lo, hi)) in ranges.iter().enumerate() {
                if let Some(p) = self.params.iter().find(|p| p[d] < lo || p[d] > hi) {
                    return Err(Error::OutOfRange {
                        name: "layout parameter with parameter_bias",
                        value: p[d],
                        expected: "inside the library's range of that parameter",
                    });
                }
            }
            for p in &mut self.unique {
                for (v, b) in p.iter_mut().zip(bias) {
                    *v += b;
                }
            }
        }
        // the draws, whatever the σ (the same sequence: δ then ε per layout row)
        let mut rng = Pcg64::seed_from_u64(errors.seed);
        let mut per_row = Vec::with_capacity(self.radii.len());
        let mut deltas = Vec::with_capacity(self.radii.len());
        let mut clamped = 0;
        for _ in 0..self.radii.len() {
            let delta: f64 = StandardNormal.sample(&mut rng);
            let epsilon: f64 = StandardNormal.sample(&mut rng);
            let amplitude = 1.0 + errors.transmission_sigma * epsilon;
            if amplitude < 0.0 {
                clamped += 1;
            }
            per_row.push(Complex64::from_polar(amplitude.max(0.0), errors.phase_sigma_rad * delta));
            deltas.push(delta);
        }
        self.phase_draws = self.rows.iter().map(|&r| deltas[r]).collect();
        if errors.phase_sigma_rad > 0.0 || errors.transmission_sigma > 0.0 {
            self.factors = Some(self.rows.iter().map(|&r| per_row[r]).collect());
            self.clamped = clamped;
        }
        self.cache = std::sync::Mutex::new(Vec::new());
        Ok(self)
    }

    /// How many atoms' amplitude factor `1 + ε` was drawn below 0 and taken as 0.
    pub fn clamped_atoms(&self) -> usize {
        self.clamped
    }

    /// The meta-atom library.
    pub fn library(&self) -> &Library {
        &self.library
    }

    /// Every layout atom's parameters (a layout row each, as fabricated).
    pub fn layout_parameters(&self) -> &[Vec<f64>] {
        &self.params
    }

    /// The number of atoms of the layout (its rows).
    pub fn layout_atoms(&self) -> usize {
        self.radii.len()
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "library"
    }

    /// The aperture radius, m.
    pub fn aperture_radius(&self) -> f64 {
        0.5 * self.focal_length / self.f_number
    }

    /// The design phase (radians) at normalized radius `rho`.
    pub fn design_phase(&self, rho: f64) -> f64 {
        self.design.value(rho * rho)
    }

    /// `(T, zones' (q_centre, area fraction, c_1))` at `wavelength_m` (the cells precomputed).
    fn decompose(&self, wavelength_m: f64) -> (f64, Vec<(f64, f64, Complex64)>) {
        let t: Vec<Complex64> = self.unique.iter().map(|p| self.library.transmission(p, wavelength_m)).collect();
        // each atom's field: its library field, times its fabrication error (|t| ≤ 1) if any
        let t: Vec<Complex64> = match &self.factors {
            None => self.atoms.iter().map(|&(u, _)| t[u]).collect(),
            Some(f) => self.atoms.iter().zip(f).map(|(&(u, _), &f)| fabricated(t[u], None, f).0).collect(),
        };
        let transmission: f64 = self.atoms.iter().zip(&t).map(|(&(_, area), t)| t.norm_sqr() * area).sum();
        let mut sums = vec![(Complex64::new(0.0, 0.0), 0.0); self.zones.len()];
        for cell in &self.cells {
            // ∫ t e^{−iψ} dψ over [ψa, ψb] = i t (e^{−iψb} − e^{−iψa})
            let z = &mut sums[cell.zone];
            z.0 += t[cell.atom] * cell.kernel;
            z.1 += cell.span;
        }
        let zones = self
            .zones
            .iter()
            .zip(&sums)
            .filter(|(_, s)| s.1 != 0.0)
            .map(|(&(q, area), s)| (q, area, s.0 / s.1))
            .collect();
        (transmission, zones)
    }

    /// The imaging order's pupil at `wavelength_m` and its efficiency τ1: the coherent part of
    /// the zones' `c_1(q)`, a least-squares polynomial of degree [`COHERENT_FIT_DEGREE`] in `q`
    /// weighted by the zones' areas (its amplitude `|c_1|` and phase `ψ + arg c_1` as polynomials
    /// of degree [`PUPIL_KNOTS`] in `q`); `τ1 = ∫|c_1|² dq`. The zone-to-zone scatter about the
    /// fit (the atoms' discreteness) is light spread far from the image: background, within T.
    fn first_order(&self, wavelength_m: f64) -> (f64, f64, Option<Arc<RadialPupil>>) {
        let key = wavelength_m.to_bits();
        if let Ok(cache) = self.cache.lock()
            && let Some(hit) = cache.iter().find(|c| c.0 == key)
        {
            return (hit.1, hit.2, hit.3.clone());
        }
        let (transmission, zones) = self.decompose(wavelength_m);
        let result = if zones.is_empty() {
            (0.0, transmission, None)
        } else {
            let qw: Vec<(f64, f64)> = zones.iter().map(|&(q, a, _)| (q, a)).collect();
            let c_re: Vec<f64> = zones.iter().map(|z| z.2.re).collect();
            let c_im: Vec<f64> = zones.iter().map(|z| z.2.im).collect();
            let mut fits = fit_columns(&qw, &[&c_re, &c_im], COHERENT_FIT_DEGREE).into_iter();
            let (re, im) = (fits.next().unwrap_or_default(), fits.next().unwrap_or_default());
            let eval = |c: &[f64], q: f64| c.iter().rev().fold(0.0, |acc, &ci| acc * q + ci);
            // |c_1| and arg c_1 (unwrapped) at Chebyshev points in q, as polynomials in q
            let qs: Vec<f64> = (0..=PUPIL_KNOTS)
                .map(|j| 0.5 * (1.0 - (std::f64::consts::PI * j as f64 / PUPIL_KNOTS as f64).cos()))
                .collect();
            let mut amp = Vec::with_capacity(qs.len());
            let mut arg: Vec<(f64, f64, f64)> = Vec::with_capacity(qs.len());
            for &q in &qs {
                let c = Complex64::new(eval(&re, q), eval(&im, q));
                amp.push((q, c.norm(), 1.0));
                let a = c.arg();
                let a = match arg.last() {
                    Some(&(_, last, _)) => a + ((last - a) / std::f64::consts::TAU).round() * std::f64::consts::TAU,
                    None => a,
                };
                arg.push((q, a, 1.0));
            }
            let per_radian = wavelength_m / std::f64::consts::TAU;
            let qw: Vec<(f64, f64)> = qs.iter().map(|&q| (q, 1.0)).collect();
            let amp: Vec<f64> = amp.iter().map(|a| a.1).collect();
            let arg: Vec<f64> = arg.iter().map(|a| a.1).collect();
            let mut fits = fit_columns(&qw, &[&amp, &arg], PUPIL_KNOTS).into_iter();
            let (amp, arg) = (fits.next().unwrap_or_default(), fits.next().unwrap_or_default());
            match (RadialProfile::even_polynomial(amp), RadialProfile::even_polynomial(arg)) {
                (Ok(amplitude), Ok(residual)) => {
                    let tau = amplitude.mean_square().min(transmission);
                    let terms = vec![
                        (per_radian, self.design.clone()),
                        (1.0, self.sphere.clone()),
                        (per_radian, Arc::new(residual)),
                    ];
                    let pupil = RadialPupil::new(Some(Arc::new(amplitude)), terms, vec![]).ok().map(Arc::new);
                    (if pupil.is_some() { tau } else { 0.0 }, transmission, pupil)
                }
                _ => (0.0, transmission, None),
            }
        };
        if let Ok(mut cache) = self.cache.lock() {
            if cache.len() >= CACHE_WAVELENGTHS {
                cache.clear();
            }
            cache.push((key, result.0, result.1, result.2.clone()));
        }
        result
    }
}

/// The derivative of a library lens's imaging order at one wavelength with respect to one
/// entry of its parameter bias ([`LibraryLens::first_order_derivative`]).
#[derive(Clone, Debug)]
pub struct FirstOrderDerivative {
    /// `τ1`, as the lens's imaging order gives it ([`LensModel::orders`]).
    pub efficiency: f64,
    /// `T` ([`LensModel::transmission`]).
    pub transmission: f64,
    /// `∂τ1/∂b`.
    pub efficiency_derivative: f64,
    /// `∂T/∂b`.
    pub transmission_derivative: f64,
    /// `∂A/∂b`: the change of the pupil's field amplitude, an even polynomial in `q = ρ²`.
    pub amplitude: RadialProfile,
    /// `∂W/∂b`: the change of the pupil's whole wavefront (m), an even polynomial in `q`.
    pub wavefront_m: RadialProfile,
}

impl LibraryLens {
    /// The imaging order's derivative at `wavelength_m` with respect to the bias of parameter
    /// `wrt` (per unit of that parameter: every atom's `p_wrt → p_wrt + b`), by forward mode on
    /// the order's own rule (docs/physics.md, "Gradients: a library's parameter bias"): each
    /// distinct atom's `∂t/∂p` ([`Library::transmission_and_derivative`]), times its error
    /// factor; `∂T = Σ 2 Re(t̄ ∂t) × area`; each zone's `∂c_1` by the same sum over its cells;
    /// the least-squares fits (linear in their data) applied to the derivatives' data; at the
    /// Chebyshev points `∂|c| = Re(c̄ ∂c)/|c|` and `∂ arg c = Im(c̄ ∂c)/|c|²`, fitted as the
    /// value's are; `∂τ1 = 2∫A ∂A dq` on the rule of [`RadialProfile::mean_square`] (or `∂T`
    /// where `τ1` is capped at `T`). The design phase and the zones are the nominal layout's and
    /// do not move with the bias. `None` with linear interpolation in the parameters, `wrt` out
    /// of range, or where the wavelength has no imaging order (no zone, or no pupil).
    pub fn first_order_derivative(&self, wavelength_m: f64, wrt: usize) -> Option<FirstOrderDerivative> {
        self.first_order(wavelength_m).2.as_ref()?;
        let mut t = Vec::with_capacity(self.unique.len());
        for p in &self.unique {
            t.push(self.library.transmission_and_derivative(p, wavelength_m, wrt)?);
        }
        // each atom's field and its derivative, with its fabrication error (|t| ≤ 1), as the
        // value forms it (`fabricated`)
        let t: Vec<(Complex64, Complex64)> = match &self.factors {
            None => self.atoms.iter().map(|&(u, _)| t[u]).collect(),
            Some(f) => self
                .atoms
                .iter()
                .zip(f)
                .map(|(&(u, _), &f)| {
                    let (v, dv) = fabricated(t[u].0, Some(t[u].1), f);
                    (v, dv.unwrap_or_default())
                })
                .collect(),
        };
        self.first_order_derivative_of(wavelength_m, &t)
    }

    /// The imaging order's derivative at `wavelength_m` with respect to σ_φ, the σ of the
    /// atoms' phase errors (radians), every atom's draw `δ_i` held (the seed fixed;
    /// docs/physics.md, "Gradients: a library's atoms' phase errors"): each atom's field
    /// `v_i = t_i A_i e^{iσ_φ δ_i}` moves by `∂v_i = iδ_i v_i` — also where `|v|` is capped at 1,
    /// the cap `v/|v|` keeping the phase (`Re(v̄ ∂v) = 0`: σ_φ moves no atom across it) — and
    /// then the zones, fits and `τ1` as [`first_order_derivative`](Self::first_order_derivative).
    /// `None` before [`with_fabrication`](Self::with_fabrication) or where the wavelength has no
    /// imaging order.
    pub fn phase_error_derivative(&self, wavelength_m: f64) -> Option<FirstOrderDerivative> {
        if self.phase_draws.len() != self.atoms.len() {
            return None;
        }
        let t: Vec<Complex64> = self.unique.iter().map(|p| self.library.transmission(p, wavelength_m)).collect();
        let one = Complex64::new(1.0, 0.0);
        let t: Vec<(Complex64, Complex64)> = self
            .atoms
            .iter()
            .enumerate()
            .map(|(i, &(u, _))| {
                let f = self.factors.as_ref().map_or(one, |f| f[i]);
                let (v, dv) = fabricated(t[u], Some(Complex64::new(0.0, self.phase_draws[i]) * t[u]), f);
                (v, dv.unwrap_or_default())
            })
            .collect();
        self.first_order_derivative_of(wavelength_m, &t)
    }

    /// The imaging order's derivative at `wavelength_m` from each atom's field and its
    /// derivative `t` (aligned with `atoms`, fabricated), by the order's own rule (the steps of
    /// [`first_order_derivative`](Self::first_order_derivative) after the atoms').
    fn first_order_derivative_of(
        &self,
        wavelength_m: f64,
        t: &[(Complex64, Complex64)],
    ) -> Option<FirstOrderDerivative> {
        let (tau, transmission, pupil) = self.first_order(wavelength_m);
        pupil.as_ref()?;
        let d_transmission: f64 =
            self.atoms.iter().zip(t).map(|(&(_, area), (v, dv))| 2.0 * (v.conj() * dv).re * area).sum();
        let zero = Complex64::new(0.0, 0.0);
        let mut sums = vec![(zero, zero, 0.0); self.zones.len()];
        for cell in &self.cells {
            let z = &mut sums[cell.zone];
            z.0 += t[cell.atom].0 * cell.kernel;
            z.1 += t[cell.atom].1 * cell.kernel;
            z.2 += cell.span;
        }
        let zones: Vec<(f64, f64, Complex64, Complex64)> = self
            .zones
            .iter()
            .zip(&sums)
            .filter(|(_, s)| s.2 != 0.0)
            .map(|(&(q, area), s)| (q, area, s.0 / s.2, s.1 / s.2))
            .collect();
        let qw: Vec<(f64, f64)> = zones.iter().map(|&(q, a, _, _)| (q, a)).collect();
        let c_re: Vec<f64> = zones.iter().map(|z| z.2.re).collect();
        let c_im: Vec<f64> = zones.iter().map(|z| z.2.im).collect();
        let d_re: Vec<f64> = zones.iter().map(|z| z.3.re).collect();
        let d_im: Vec<f64> = zones.iter().map(|z| z.3.im).collect();
        let mut fits = fit_columns(&qw, &[&c_re, &c_im, &d_re, &d_im], COHERENT_FIT_DEGREE).into_iter();
        let mut next = || fits.next().unwrap_or_default();
        let (re, im, d_re, d_im) = (next(), next(), next(), next());
        let eval = |c: &[f64], q: f64| c.iter().rev().fold(0.0, |acc, &ci| acc * q + ci);
        let qs: Vec<f64> = (0..=PUPIL_KNOTS)
            .map(|j| 0.5 * (1.0 - (std::f64::consts::PI * j as f64 / PUPIL_KNOTS as f64).cos()))
            .collect();
        let (mut d_amp, mut d_arg) = (Vec::with_capacity(qs.len()), Vec::with_capacity(qs.len()));
        for &q in &qs {
            let c = Complex64::new(eval(&re, q), eval(&im, q));
            let dc = Complex64::new(eval(&d_re, q), eval(&d_im, q));
            let (n, cross) = (c.norm(), c.conj() * dc);
            if n == 0.0 {
                // |c_1| = 0 at a point: its phase is undefined, the fit not differentiable there
                return None;
            }
            d_amp.push(cross.re / n);
            d_arg.push(cross.im / (n * n));
        }
        let qw: Vec<(f64, f64)> = qs.iter().map(|&q| (q, 1.0)).collect();
        let mut fits = fit_columns(&qw, &[&d_amp, &d_arg], PUPIL_KNOTS).into_iter();
        let (d_amp, d_arg) = (fits.next().unwrap_or_default(), fits.next().unwrap_or_default());
        let per_radian = wavelength_m / std::f64::consts::TAU;
        let amplitude = RadialProfile::even_polynomial(d_amp).ok()?;
        let wavefront_m = RadialProfile::even_polynomial(d_arg.iter().map(|c| c * per_radian).collect()).ok()?;
        // τ1 = min(∫A² dq, T): the mean square on its own rule (8 Gauss panels, exact for these
        // polynomials), or T where it caps τ1
        let d_tau = match pupil.as_deref().and_then(|p| p.amplitude_profile()) {
            Some(a) if a.mean_square() <= transmission => {
                let mut sum = 0.0;
                optics::quad::for_each_node(0.0, 1.0, 8, |q, w| sum += w * 2.0 * a.value(q) * amplitude.value(q));
                sum
            }
            _ => d_transmission,
        };
        Some(FirstOrderDerivative {
            efficiency: tau,
            transmission,
            efficiency_derivative: d_tau,
            transmission_derivative: d_transmission,
            amplitude,
            wavefront_m,
        })
    }
}

/// An atom's field `t` times its fabrication error factor `f`, capped at `|t| ≤ 1` (a passive
/// atom: `v = t f` taken as `v/|v|` where `|v| > 1`), and with `dt` its derivative by the same
/// steps (`∂v = ∂t f`, and where capped `∂v/|v| − v Re(v̄ ∂v)/|v|³`, one-sided at `|v| = 1`):
/// the one per-atom rule of the value ([`LibraryLens::decompose`], `dt = None`, where the
/// derivative's steps are not taken) and of its forward mode
/// ([`LibraryLens::first_order_derivative`]).
#[inline(always)]
fn fabricated(t: Complex64, dt: Option<Complex64>, f: Complex64) -> (Complex64, Option<Complex64>) {
    let v = t * f;
    let n = v.norm();
    if n > 1.0 {
        (v / n, dt.map(|dt| dt * f).map(|dv| dv / n - v * (v.conj() * dv).re / (n * n * n)))
    } else {
        (v, dt.map(|dt| dt * f))
    }
}

/// Degree in `q` of the coherent first-order field fitted over the zones.
const COHERENT_FIT_DEGREE: usize = 8;

/// Degree in `q` of the imaging order's amplitude and phase polynomials (interpolating `|c_1|`
/// and `arg c_1` of the coherent fit at as many Chebyshev points plus one).
const PUPIL_KNOTS: usize = 12;

/// Wavelengths whose first order a lens keeps (an evaluation asks the same ones many times).
const CACHE_WAVELENGTHS: usize = 4096;

/// The fabrication errors of a library lens's atoms ([`LibraryLens::with_fabrication`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AtomErrors {
    /// σ of each atom's phase error, radians.
    pub phase_sigma_rad: f64,
    /// σ of each atom's relative amplitude error.
    pub transmission_sigma: f64,
    /// The seed of the draws.
    pub seed: u64,
}

impl AtomErrors {
    /// Checks the errors and a parameter bias for `library` as both layouts take them: σ_φ ≥ 0,
    /// σ_t in [0, 0.5) (the amplitude factor 1 + ε must stay positive but for rare atoms), one
    /// finite bias per parameter column.
    pub(crate) fn check(&self, bias: &[f64], library: &Library) -> Result<(), Error> {
        check(
            "atom_phase_error_rad",
            self.phase_sigma_rad,
            self.phase_sigma_rad >= 0.0,
            "a finite standard deviation ≥ 0 rad",
        )?;
        check(
            "atom_transmission_error",
            self.transmission_sigma,
            (0.0..0.5).contains(&self.transmission_sigma),
            "a finite relative standard deviation in [0, 0.5) (the amplitude factor 1 + ε must stay positive but for rare atoms)",
        )?;
        if bias.len() != library.ranges().len() {
            return Err(Error::OutOfRange {
                name: "parameter_bias entries",
                value: bias.len() as f64,
                expected: "one per library parameter column",
            });
        }
        bias.iter().try_for_each(|b| check("parameter_bias", *b, true, "finite"))
    }
}

/// One atom's cell (or the part of it in one zone): its atom (index into the lens's atoms), its
/// zone, and `i (e^{−iψb} − e^{−iψa})` and `ψb − ψa` over it.
#[derive(Clone, Debug)]
struct Cell {
    atom: usize,
    zone: usize,
    kernel: Complex64,
    span: f64,
}

/// Weighted least-squares polynomials `Σ c_i q^i` of `degree` (lowered to the points available)
/// through `points` `(q, weight)` and each column of `values` (`values[r][i]` at `points[i]`):
/// the normal equations, whose matrix `Σ w q^{i+j}` is the same for every column and is built
/// from the `2 degree + 1` moments `Σ w q^k` (one pass over the points, not `(degree + 1)²`
/// products a point). A column of one value gives that constant.
fn fit_columns(points: &[(f64, f64)], values: &[&[f64]], degree: usize) -> Vec<Vec<f64>> {
    let degree = degree.min(points.len().saturating_sub(1));
    let n = degree + 1;
    let mut moments = vec![0.0; 2 * n - 1];
    let mut rhs = vec![vec![0.0; n]; values.len()];
    for (idx, &(q, w)) in points.iter().enumerate() {
        let mut p = w;
        for (k, m) in moments.iter_mut().enumerate() {
            *m += p;
            if k < n {
                for (r, column) in rhs.iter_mut().zip(values) {
                    r[k] += p * column[idx];
                }
            }
            p *= q;
        }
    }
    rhs.into_iter()
        .zip(values)
        .map(|(b, column)| {
            // a column of one value is that constant: exactly what the fit should give, but the
            // monomial normal equations (ill-conditioned at degree 8–12) would give it as
            // coefficients of up to 0.3 that cancel to its value (a flat plate's layout, all
            // atoms alike: its wiggles of rounding size made the radial engine's phase series
            // long, each OTF 7× dearer)
            if let Some(&first) = column.first()
                && column.iter().all(|&v| v == first)
            {
                return vec![first];
            }
            let a = (0..n)
                .map(|i| {
                    let mut row: Vec<f64> = moments[i..i + n].to_vec();
                    row.push(b[i]);
                    row
                })
                .collect();
            solve(a)
        })
        .collect()
}

/// Least-squares coefficients `c_0 … c_degree` of `Σ c_i q^i` through the points `(q, value)`
/// (the degree lowered to the points available).
fn fit_even(points: &[(f64, f64)], degree: usize) -> Vec<f64> {
    let qw: Vec<(f64, f64)> = points.iter().map(|&(q, _)| (q, 1.0)).collect();
    let v: Vec<f64> = points.iter().map(|&(_, v)| v).collect();
    fit_columns(&qw, &[&v], degree).remove(0)
}

/// The solution of the normal equations `a` (rows `[A | b]`), by Gauss–Jordan elimination with
/// partial pivoting (a singular column gives 0).
fn solve(mut a: Vec<Vec<f64>>) -> Vec<f64> {
    let n = a.len();
    for col in 0..n {
        let pivot = (col..n).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs())).unwrap_or(col);
        a.swap(col, pivot);
        let p = a[col][col];
        if p == 0.0 {
            continue;
        }
        let pivot_row = a[col].clone();
        for (r, row) in a.iter_mut().enumerate() {
            if r != col {
                let factor = row[col] / p;
                for (x, &y) in row.iter_mut().zip(&pivot_row).skip(col) {
                    *x -= factor * y;
                }
            }
        }
    }
    (0..n).map(|i| if a[i][i] != 0.0 { a[i][n] / a[i][i] } else { 0.0 }).collect()
}

impl LensModel for LibraryLens {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        let (tau, _, pupil) = self.first_order(wavelength_m);
        let Some(mut pupil) = pupil else { return Vec::new() };
        if !field.is_on_axis()
            && let Ok(o) =
                optics::radial::Oblique::new(self.aperture_radius(), self.focal_length, field.x_rad, field.y_rad)
        {
            pupil = Arc::new((*pupil).clone().with_oblique(o));
        }
        vec![Order::radial(tau, pupil, Wavefront::default())]
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.first_order(wavelength_m).1
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.library.wavelengths.clone()
    }

    fn design_wavelength(&self) -> Option<f64> {
        Some(self.design_wavelength)
    }

    fn order_derivatives(&self, wavelength_m: f64, parameter: usize) -> Option<optics::OrderDerivatives> {
        let d = if parameter == optics::ATOM_PHASE_ERROR {
            self.phase_error_derivative(wavelength_m)?
        } else {
            self.first_order_derivative(wavelength_m, parameter)?
        };
        Some(optics::OrderDerivatives {
            efficiencies: vec![d.efficiency_derivative],
            transmission: d.transmission_derivative,
            fields: vec![(d.amplitude, d.wavefront_m)],
            tables: Vec::new(),
        })
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        format!(
            "meta-atom library lens F/{} f0 = {} mm at λ0 = {} nm ({}; {} atoms at {} µm pitch, local periodic approximation), against the exact reference sphere",
            r(self.f_number),
            r(self.focal_length * 1e3),
            r(self.design_wavelength * 1e9),
            self.source,
            self.radii.len(),
            r(self.pitch * 1e6),
        )
    }
}

impl LibraryLens {
    /// The design phase's coefficients in `q = ρ²` (radians), as fitted.
    pub fn design_coefficients(&self) -> &[f64] {
        &self.design_coefficients
    }
}
