//! `e^x` on four or eight lanes, and the same operations on one number: the closed form's real
//! exponentials (the cut's `e^{−x²/2}` and the completed square's `e^{Re K}`, `closed.rs`), which
//! glibc's `exp` took one lane at a time (10 % of the paper point's time).
//!
//! The reduction is Cody–Waite's (Muller, "Elementary Functions", 3rd ed., §11.2; fdlibm's
//! `e_exp.c` constants): `x = n ln 2 + r`, `n` the nearest integer to `x/ln 2`, `r = (x − n L1) −
//! n L2` with `L1` the leading 32 bits of ln 2 (so `n L1` is exact for `|n| < 2^20`) and `L2` the
//! rest, `|r| ≤ ln 2/2 + 1e-15`. Then `e^r = 1 + r (1 + r (1/2! + r (1/3! + … + r/13!)))`, the
//! Taylor polynomial to degree 13 (truncation `r^14/14! < 4e-18`, 0.02 ulp), by Horner with the
//! 1 added last, and `e^x = e^r 2^n`, the power of two from its bits (exact; on the lanes by
//! the bits of `n + 2⁵² + 1023`, the same power). The polynomial's steps `p r + c` are fused
//! multiply-adds where the target has them (`complex4::fused`: one rounding a step instead of
//! two, half the operations; a product then a sum elsewhere), the reduction plain products and
//! sums: each lane of [`exp_lanes`] is [`exp`] of it to the last bit on either kind of target,
//! so the four- and eight-lane kernel stays the scalar one lane by lane.
//!
//! Accuracy (test `exp_is_within_two_ulp_of_the_correctly_rounded_one`, against glibc's `exp`,
//! itself within 0.502 ulp of `e^x`, over [−708, 709] and densely over the kernel's own range
//! [−60, 5]): within `2⁻⁵² e^x` of glibc's (asserted within 1.4 × that), so within
//! [`RELATIVE_ERROR`] of `e^x`. Below `x = −708` the result is 0 (`e^x < 3.3e-308`:
//! an absolute error below that, where glibc returns subnormals), above 709 +∞ (`e^709 =
//! 8.2e307`), NaN for NaN.

#[cfg(test)]
use wide::f64x4;

use crate::complex4::{Lanes, fused};

/// Bound on the relative error of [`exp`] and [`exp_lanes`] on `[−708, 709]` (2 ulp of 1).
pub(crate) const RELATIVE_ERROR: f64 = 2.0 * f64::EPSILON;

/// `1/ln 2`.
const LOG2_E: f64 = std::f64::consts::LOG2_E;
/// ln 2 in two parts (fdlibm's `ln2HI`, `ln2LO`): the first's low 32 bits are zero.
/// (6.93147180369123816490e-1 and 1.90821492927058770002e-10, as fdlibm writes them with these bits)
const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
/// Adding and subtracting this rounds to the nearest integer (for magnitudes below 2^51).
const ROUND: f64 = 6_755_399_441_055_744.0;
/// Below this `e^x` is returned as 0, above [`HIGHEST`] as +∞.
const LOWEST: f64 = -708.0;
const HIGHEST: f64 = 709.0;

/// 1/k! for k = 2 … 13, highest first (Horner's order).
const INVERSE_FACTORIALS: [f64; 12] = [
    1.0 / 6_227_020_800.0,
    1.0 / 479_001_600.0,
    1.0 / 39_916_800.0,
    1.0 / 3_628_800.0,
    1.0 / 362_880.0,
    1.0 / 40_320.0,
    1.0 / 5_040.0,
    1.0 / 720.0,
    1.0 / 120.0,
    1.0 / 24.0,
    1.0 / 6.0,
    0.5,
];

/// `e^x` (module docs): within [`RELATIVE_ERROR`] on `[−708, 709]`, 0 below, +∞ above.
#[inline(always)]
pub(crate) fn exp(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    let clamped = x.clamp(LOWEST, HIGHEST);
    let n = (clamped * LOG2_E + ROUND) - ROUND;
    let r = (clamped - n * LN2_HI) - n * LN2_LO;
    let mut p = INVERSE_FACTORIALS[0];
    for &c in &INVERSE_FACTORIALS[1..] {
        p = fused(p, r, c);
    }
    let e_r = fused(r, fused(r, p, 1.0), 1.0);
    let value = e_r * two_to(n);
    if x < LOWEST {
        0.0
    } else if x > HIGHEST {
        f64::INFINITY
    } else {
        value
    }
}

/// [`exp`] on four lanes, by the same operations in the same order on each.
#[cfg(test)]
pub(crate) fn exp4(x: f64x4) -> f64x4 {
    exp_lanes(x)
}

/// [`exp`] on the lanes of `V` (four or eight), by the same operations in the same order on each.
#[inline(always)]
pub(crate) fn exp_lanes<V: Lanes>(x: V) -> V {
    let k = V::splat;
    let clamped = x.max(k(LOWEST)).min(k(HIGHEST));
    let n = (clamped * k(LOG2_E) + k(ROUND)) - k(ROUND);
    let r = (clamped - n * k(LN2_HI)) - n * k(LN2_LO);
    let mut p = k(INVERSE_FACTORIALS[0]);
    for &c in &INVERSE_FACTORIALS[1..] {
        p = p.fused(r, k(c));
    }
    let e_r = r.fused(r.fused(p, k(1.0)), k(1.0));
    let value = e_r * n.two_to();
    let value = x.simd_lt(k(LOWEST)).select(k(0.0), value);
    let value = x.simd_gt(k(HIGHEST)).select(k(f64::INFINITY), value);
    x.is_nan().select(x, value)
}

/// `2^n` for an integer `n` in [−1022, 1023], from its bits.
#[inline(always)]
fn two_to(n: f64) -> f64 {
    f64::from_bits(((n as i64 + 1023) as u64) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f64x8;

    /// The largest difference from `f64::exp` (glibc's, within 0.502 ulp of `e^x`) over the given
    /// points in units of `2⁻⁵² e^x`, and the lanes of [`exp4`] and of [`exp_lanes`] on eight
    /// the scalar one to the bit.
    fn worst_ulp(points: impl Iterator<Item = f64>) -> f64 {
        let mut worst: f64 = 0.0;
        let xs: Vec<f64> = points.collect();
        for chunk in xs.chunks_exact(4) {
            let lanes = exp4(f64x4::new([chunk[0], chunk[1], chunk[2], chunk[3]])).to_array();
            // eight lanes: these four and their negatives
            let eight: [f64; 8] = std::array::from_fn(|l| if l < 4 { chunk[l] } else { -chunk[l - 4] });
            for (&x, &v) in eight.iter().zip(&exp_lanes(f64x8::new(eight)).to_array()) {
                assert_eq!(v.to_bits(), exp(x).to_bits(), "eight lanes, lane of {x}");
            }
            for (&x, &v) in chunk.iter().zip(&lanes) {
                let scalar = exp(x);
                assert_eq!(v.to_bits(), scalar.to_bits(), "lane of {x}");
                let want = x.exp();
                // the ulp of the value, in normal numbers
                let ulp = f64::EPSILON * want.abs();
                worst = worst.max((scalar - want).abs() / ulp);
            }
        }
        worst
    }

    /// [`RELATIVE_ERROR`] holds over [−708, 709] (every 1e-4 of its width, offset so that the
    /// points are not round) and densely over the closed form's arguments, [−60, 5] (the cut's
    /// `−x²/2` to 10σ, the completed square's `Re K ≤ ln √(2|A|)`); the ends and the special
    /// values.
    #[test]
    fn exp_is_within_two_ulp_of_the_correctly_rounded_one() {
        assert_eq!((LN2_HI, LN2_LO), (6.931_471_803_691_238e-1, 1.908_214_929_270_587_7e-10));
        let whole = worst_ulp((0..1_000_000).map(|i| -708.0 + 1417.0 * (i as f64 + 0.29) / 1e6));
        let kernel = worst_ulp((0..2_000_000).map(|i| -60.0 + 65.0 * (i as f64 + 0.577) / 2e6));
        let small = worst_ulp((0..400_000).map(|i| (i as f64 - 200_000.0) * 1.7e-6));
        // within 1.4 × 2⁻⁵² of glibc's (measured 1.000), itself within 0.502 ulp ≤ 0.502 × 2⁻⁵² of
        // e^x: within 1.902 × 2⁻⁵² < RELATIVE_ERROR of e^x
        for (range, worst) in [("[-708, 709]", whole), ("[-60, 5]", kernel), ("|x| < 0.34", small)] {
            println!("{range}: largest difference {worst:.3} × 2⁻⁵² e^x");
            assert!(worst <= 1.4, "{range}: {worst} × 2⁻⁵² e^x");
        }
        // the lanes' power of two from the bits of n + 2⁵² + 1023, the scalar one's from n's
        for n in -1022..=1023 {
            let lanes = f64x8::splat(n as f64).two_to().to_array();
            assert!(lanes.iter().all(|v| v.to_bits() == two_to(n as f64).to_bits()), "2^{n}");
            assert_eq!(f64x4::splat(n as f64).two_to().to_array()[0], 2f64.powi(n), "2^{n}");
        }
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-709.0), 0.0);
        assert_eq!(exp(710.0), f64::INFINITY);
        assert!(exp(f64::NAN).is_nan());
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        let lanes = exp4(f64x4::new([f64::NAN, f64::NEG_INFINITY, 800.0, -1e300])).to_array();
        assert!(lanes[0].is_nan());
        assert_eq!(&lanes[1..], &[0.0, f64::INFINITY, 0.0]);
    }
}
