//! Four complex numbers in two `wide::f64x4` registers, for the closed form's kernel evaluated at
//! four nodes of the rule in the pupil angle at once (`closed.rs`, `faddeeva.rs`). Every
//! operation is the one `num_complex` performs on one number, in the same order (no fused
//! multiply-adds), so each lane is the scalar result to the last bit.

use num_complex::Complex64;
use wide::f64x4;

/// Four complex numbers, lane by lane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Complex4 {
    pub re: f64x4,
    pub im: f64x4,
}

impl Complex4 {
    pub const ZERO: Complex4 = Complex4 { re: f64x4::ZERO, im: f64x4::ZERO };
    pub const ONE: Complex4 = Complex4 { re: f64x4::ONE, im: f64x4::ZERO };

    /// `z` on every lane.
    #[inline(always)]
    pub fn splat(z: Complex64) -> Complex4 {
        Complex4 { re: f64x4::splat(z.re), im: f64x4::splat(z.im) }
    }

    /// `Complex64::new(x, 0.0)` on each lane.
    #[inline(always)]
    pub fn real(x: f64x4) -> Complex4 {
        Complex4 { re: x, im: f64x4::ZERO }
    }

    /// `Complex64::new(0.0, y)` on each lane.
    #[inline(always)]
    pub fn imaginary(y: f64x4) -> Complex4 {
        Complex4 { re: f64x4::ZERO, im: y }
    }

    /// `self * other` (`num_complex`: `(ac − bd) + i(ad + bc)`).
    #[inline(always)]
    pub fn mul(self, other: Complex4) -> Complex4 {
        Complex4 { re: self.re * other.re - self.im * other.im, im: self.re * other.im + self.im * other.re }
    }

    #[inline(always)]
    pub fn add(self, other: Complex4) -> Complex4 {
        Complex4 { re: self.re + other.re, im: self.im + other.im }
    }

    #[inline(always)]
    pub fn sub(self, other: Complex4) -> Complex4 {
        Complex4 { re: self.re - other.re, im: self.im - other.im }
    }

    #[inline(always)]
    pub fn neg(self) -> Complex4 {
        Complex4 { re: -self.re, im: -self.im }
    }

    /// `self * x`, `x` real (`num_complex`'s `Complex * T`, and `T * Complex`).
    #[inline(always)]
    pub fn scale(self, x: f64x4) -> Complex4 {
        Complex4 { re: self.re * x, im: self.im * x }
    }

    /// `self + x`, `x` real.
    #[inline(always)]
    pub fn add_real(self, x: f64x4) -> Complex4 {
        Complex4 { re: self.re + x, im: self.im }
    }

    /// `x − self`, `x` real (`num_complex`'s `T − Complex`: `(x − re) + i(0 − im)`).
    #[inline(always)]
    pub fn real_minus(x: f64x4, z: Complex4) -> Complex4 {
        Complex4 { re: x - z.re, im: f64x4::ZERO - z.im }
    }

    /// `1/self` (`num_complex`: `re/|z|² − i im/|z|²`).
    #[inline(always)]
    pub fn inv(self) -> Complex4 {
        let norm_sqr = self.norm_sqr();
        Complex4 { re: self.re / norm_sqr, im: -self.im / norm_sqr }
    }

    /// `|z|²` (`re² + im²`).
    #[inline(always)]
    pub fn norm_sqr(self) -> f64x4 {
        self.re * self.re + self.im * self.im
    }

    /// `mask ? a : b`, lane by lane.
    #[inline(always)]
    pub fn select(mask: f64x4, a: Complex4, b: Complex4) -> Complex4 {
        Complex4 { re: mask.select(a.re, b.re), im: mask.select(a.im, b.im) }
    }

    /// Lane `l` as a `Complex64`.
    #[cfg(test)]
    pub fn lane(self, l: usize) -> Complex64 {
        Complex64::new(self.re.to_array()[l], self.im.to_array()[l])
    }
}
