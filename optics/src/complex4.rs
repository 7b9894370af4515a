//! Complex numbers on four or eight lanes (`wide::f64x4`, `wide::f64x8`), for the closed form's
//! kernel evaluated at four or eight nodes of the rule in the pupil angle at once (`closed.rs`,
//! `faddeeva.rs`). Every operation is the one `num_complex` performs on one number, in the same
//! order (no fused multiply-adds, but for the Faddeeva function's products and Horner steps
//! ([`Complexes::mul_add_real`], [`Complexes::mul_fused`], [`Complexes::mul_add`]), which its
//! scalar twin in `faddeeva.rs` fuses alike), so each lane
//! is the scalar result to the last bit, whatever the width: eight lanes advance two independent groups of four through the same latency-bound
//! chains (the Faddeeva series' Horner sums, the sine, cosine and exponential polynomials)
//! together, their dependent adds overlapping.

use std::ops::{Add, BitOr, Div, Mul, Neg, Sub};

use num_complex::Complex64;
use wide::{f64x4, f64x8};

/// The lane-by-lane operations the kernel uses, on [`f64x4`] and [`f64x8`] alike: each is the
/// `f64` operation on every lane (IEEE-754 sums, products and quotients, comparisons as masks).
pub(crate) trait Lanes:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + BitOr<Output = Self>
{
    const ZERO: Self;
    const ONE: Self;
    fn splat(x: f64) -> Self;
    /// Lane `l` is `f(l)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    /// The lanes, into `out[..Self::N]`.
    fn write(self, out: &mut [f64]);
    fn simd_lt(self, other: Self) -> Self;
    fn simd_gt(self, other: Self) -> Self;
    fn simd_ge(self, other: Self) -> Self;
    fn simd_eq(self, other: Self) -> Self;
    /// `self ? a : b`, lane by lane (`self` a mask).
    fn select(self, a: Self, b: Self) -> Self;
    fn any(self) -> bool;
    fn all(self) -> bool;
    fn max(self, other: Self) -> Self;
    fn min(self, other: Self) -> Self;
    fn floor(self) -> Self;
    fn is_nan(self) -> Self;
    /// `2^n` on each lane whose `n` is an integer in `[−1022, 1023]`, from its bits: `n + 2⁵² +
    /// 1023` holds `n + 1023` in its low 52 bits (exact: an integer below 2⁵³), which shifted
    /// left by 52 are the exponent field of `2^n` (`expo::exp`'s `two_to` on every lane).
    fn two_to(self) -> Self;
    /// `self × a + b` on each lane, rounded once where the target has fused multiply-adds
    /// (`target_feature = "fma"`), else as the product then the sum: on each lane the scalar
    /// [`fused`].
    fn fused(self, a: Self, b: Self) -> Self;
}

/// `a × b + c`, rounded once where the target has fused multiply-adds (`target_feature =
/// "fma"`: the project's builds for the machine they run on, `-C target-cpu=native`), else as
/// `a * b + c` (two roundings; `f64::mul_add` would then be a slow software call): the scalar
/// lane of [`Lanes::fused`], whose lanes it is to the last bit on either kind of target.
#[inline(always)]
pub(crate) fn fused(a: f64, b: f64, c: f64) -> f64 {
    if cfg!(target_feature = "fma") { a.mul_add(b, c) } else { a * b + c }
}

/// `a × b` in fused multiply-adds ([`Complexes::mul_fused`] on one number): `re = fused(re_a,
/// re_b, −(im_a im_b))`, `im = fused(re_a, im_b, im_a re_b)`. Each part is rounded twice, not
/// three times as in `num_complex`'s product, so it is within an ulp or so of that product.
#[inline(always)]
pub(crate) fn mul_fused(a: Complex64, b: Complex64) -> Complex64 {
    Complex64::new(fused(a.re, b.re, -(a.im * b.im)), fused(a.re, b.im, a.im * b.re))
}

/// `a × b + c` in fused multiply-adds ([`Complexes::mul_add`] on one number): `re = fused(re_a,
/// re_b, fused(−im_a, im_b, re_c))`, `im = fused(re_a, im_b, fused(im_a, re_b, im_c))`.
#[inline(always)]
pub(crate) fn mul_add_fused(a: Complex64, b: Complex64, c: Complex64) -> Complex64 {
    Complex64::new(fused(a.re, b.re, fused(-a.im, b.im, c.re)), fused(a.re, b.im, fused(a.im, b.re, c.im)))
}

macro_rules! lanes {
    ($v:ident, $n:literal) => {
        impl Lanes for $v {
            const ZERO: $v = $v::ZERO;
            const ONE: $v = $v::ONE;
            #[inline(always)]
            fn splat(x: f64) -> $v {
                $v::splat(x)
            }
            #[inline(always)]
            fn from_fn(f: impl FnMut(usize) -> f64) -> $v {
                $v::new(std::array::from_fn(f))
            }
            #[inline(always)]
            fn write(self, out: &mut [f64]) {
                out[..$n].copy_from_slice(&self.to_array());
            }
            #[inline(always)]
            fn simd_lt(self, other: $v) -> $v {
                $v::simd_lt(self, other)
            }
            #[inline(always)]
            fn simd_gt(self, other: $v) -> $v {
                $v::simd_gt(self, other)
            }
            #[inline(always)]
            fn simd_ge(self, other: $v) -> $v {
                $v::simd_ge(self, other)
            }
            #[inline(always)]
            fn simd_eq(self, other: $v) -> $v {
                $v::simd_eq(self, other)
            }
            #[inline(always)]
            fn select(self, a: $v, b: $v) -> $v {
                $v::select(self, a, b)
            }
            #[inline(always)]
            fn any(self) -> bool {
                $v::any(self)
            }
            #[inline(always)]
            fn all(self) -> bool {
                $v::all(self)
            }
            #[inline(always)]
            fn max(self, other: $v) -> $v {
                $v::max(self, other)
            }
            #[inline(always)]
            fn min(self, other: $v) -> $v {
                $v::min(self, other)
            }
            #[inline(always)]
            fn floor(self) -> $v {
                $v::floor(self)
            }
            #[inline(always)]
            fn is_nan(self) -> $v {
                $v::is_nan(self)
            }
            #[inline(always)]
            fn two_to(self) -> $v {
                $v::from_bits((self + $v::splat(4_503_599_627_370_496.0 + 1023.0)).to_bits() << 52_u32)
            }
            #[inline(always)]
            fn fused(self, a: $v, b: $v) -> $v {
                if cfg!(target_feature = "fma") { $v::mul_add(self, a, b) } else { self * a + b }
            }
        }
    };
}
lanes!(f64x4, 4);
lanes!(f64x8, 8);

/// Four complex numbers, lane by lane.
pub(crate) type Complex4 = Complexes<f64x4>;

/// Complex numbers on the lanes of `V`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Complexes<V> {
    pub re: V,
    pub im: V,
}

impl<V: Lanes> Complexes<V> {
    pub const ZERO: Complexes<V> = Complexes { re: V::ZERO, im: V::ZERO };
    pub const ONE: Complexes<V> = Complexes { re: V::ONE, im: V::ZERO };

    /// `z` on every lane.
    #[inline(always)]
    pub fn splat(z: Complex64) -> Complexes<V> {
        Complexes { re: V::splat(z.re), im: V::splat(z.im) }
    }

    /// `Complex64::new(x, 0.0)` on each lane.
    #[inline(always)]
    pub fn real(x: V) -> Complexes<V> {
        Complexes { re: x, im: V::ZERO }
    }

    /// `Complex64::new(0.0, y)` on each lane.
    #[inline(always)]
    pub fn imaginary(y: V) -> Complexes<V> {
        Complexes { re: V::ZERO, im: y }
    }

    /// `self * other` (`num_complex`: `(ac − bd) + i(ad + bc)`).
    #[inline(always)]
    pub fn mul(self, other: Complexes<V>) -> Complexes<V> {
        Complexes { re: self.re * other.re - self.im * other.im, im: self.re * other.im + self.im * other.re }
    }

    #[inline(always)]
    pub fn add(self, other: Complexes<V>) -> Complexes<V> {
        Complexes { re: self.re + other.re, im: self.im + other.im }
    }

    #[inline(always)]
    pub fn sub(self, other: Complexes<V>) -> Complexes<V> {
        Complexes { re: self.re - other.re, im: self.im - other.im }
    }

    #[inline(always)]
    pub fn neg(self) -> Complexes<V> {
        Complexes { re: -self.re, im: -self.im }
    }

    /// `self * x`, `x` real (`num_complex`'s `Complex * T`, and `T * Complex`).
    #[inline(always)]
    pub fn scale(self, x: V) -> Complexes<V> {
        Complexes { re: self.re * x, im: self.im * x }
    }

    /// `self × y + b`, `b` real: the Faddeeva series' Horner step in fused multiply-adds (`re =
    /// fused(re_s, re_y, fused(−im_s, im_y, b))`, `im = fused(re_s, im_y, im_s im_y)`), four
    /// operations where the product and the sum take seven; on each lane the scalar
    /// [`crate::faddeeva`] step (`horner_step`).
    #[inline(always)]
    pub fn mul_add_real(self, y: Complexes<V>, b: V) -> Complexes<V> {
        Complexes { re: self.re.fused(y.re, (-self.im).fused(y.im, b)), im: self.re.fused(y.im, self.im * y.re) }
    }
    /// `self × other` in fused multiply-adds: `re = fused(re_s, re_o, −(im_s im_o))`, `im =
    /// fused(re_s, im_o, im_s re_o)`, four operations where [`mul`](Self::mul) takes six; on each
    /// lane the scalar [`mul_fused`].
    #[inline(always)]
    pub fn mul_fused(self, other: Complexes<V>) -> Complexes<V> {
        Complexes {
            re: self.re.fused(other.re, -(self.im * other.im)),
            im: self.re.fused(other.im, self.im * other.re),
        }
    }

    /// `self × other + c` in fused multiply-adds: `re = fused(re_s, re_o, fused(−im_s, im_o,
    /// re_c))`, `im = fused(re_s, im_o, fused(im_s, re_o, im_c))`, four operations where the
    /// product and the sum take eight; on each lane the scalar [`mul_add_fused`].
    #[inline(always)]
    pub fn mul_add(self, other: Complexes<V>, c: Complexes<V>) -> Complexes<V> {
        Complexes {
            re: self.re.fused(other.re, (-self.im).fused(other.im, c.re)),
            im: self.re.fused(other.im, self.im.fused(other.re, c.im)),
        }
    }

    /// `x − self`, `x` real (`num_complex`'s `T − Complex`: `(x − re) + i(0 − im)`).
    #[inline(always)]
    pub fn real_minus(x: V, z: Complexes<V>) -> Complexes<V> {
        Complexes { re: x - z.re, im: V::ZERO - z.im }
    }

    /// `1/self` (`num_complex`: `re/|z|² − i im/|z|²`).
    #[inline(always)]
    pub fn inv(self) -> Complexes<V> {
        let norm_sqr = self.norm_sqr();
        Complexes { re: self.re / norm_sqr, im: -self.im / norm_sqr }
    }

    /// `|z|²` (`re² + im²`).
    #[inline(always)]
    pub fn norm_sqr(self) -> V {
        self.re * self.re + self.im * self.im
    }

    /// `mask ? a : b`, lane by lane.
    #[inline(always)]
    pub fn select(mask: V, a: Complexes<V>, b: Complexes<V>) -> Complexes<V> {
        Complexes { re: mask.select(a.re, b.re), im: mask.select(a.im, b.im) }
    }

    /// Lane `l` as a `Complex64`.
    #[cfg(test)]
    pub fn lane(self, l: usize) -> Complex64 {
        let (mut re, mut im) = ([0.0; 8], [0.0; 8]);
        self.re.write(&mut re);
        self.im.write(&mut im);
        Complex64::new(re[l], im[l])
    }
}
