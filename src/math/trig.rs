//! `atan2` and `acos` for the closed-form inverse kinematics (issue 38: every-branch
//! UR IK ≤ 0.5 µs): the closed forms take ~20 of them per call, and the C library's
//! (glibc 2.36: ~18 ns each, a call with branches the processor cannot overlap)
//! were a third of the time. These are straight-line code, inlined, within about one
//! unit in the last place of the correctly rounded value (checked against the C
//! library's over the whole plane in the tests), with the same signed zeros, the same
//! ±π on the negative x axis and the same NaN; infinities go to the C library.
//!
//! # Method
//! `atan2(y, x)` is `atan(n / d)` with `n = min(|x|, |y|)`, `d = max(|x|, |y|)`
//! (`t = n / d ∈ [0, 1]`), then `π/2 − ·` when `|y| > |x|`, `π − ·` when `x < 0`, and
//! the sign of `y`. `atan(t) = atan(c) + atan(u)`, `u = (n − c·d) / (d + c·n)`, with
//! `c` the nearest of `0`, `tan(π/8)`, `1` (so `|u| ≤ tan(π/16)`), and
//! `atan(u) = u + u·z·P(z)`, `z = u²`, with `P` the degree-7 Chebyshev fit of
//! `(atan √z − √z) / z^{3/2}` on `[0, tan²(π/16)]` (error 8e-18, computed with mpmath
//! at 60 digits; times `z ≤ 0.04` it is far below one unit in the last place).
//! The quadrant and octant fold into one offset: the result is
//! `±(hi + s·atan(u) + lo)` with `(hi, lo)` the double-double value of
//! `H + s·atan(c)` (`H` 0, π/2 or π, `s = ±1`, `atan(c)` of the double `c` itself),
//! one table row of twelve chosen by the signs and the reduction point, loaded
//! while the division runs; the sum is rounded once (issue 38: 26 → 20 ns latency on
//! a chain of dependent calls, the same largest difference to the C library).
//!
//! Beside them, the closed forms' other small steps: [`hyp`] without `hypot`'s range
//! guard, the branch-free angle [`wrap`], and the planar and Rodrigues rotations by a
//! known sine and cosine.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, FRAC_PI_8, PI, TAU};

/// `tan(π/8)` as a double.
const C1: f64 = 0.414_213_562_373_095_03;
/// Where `c` switches: `tan(π/16)` and `tan(3π/16)`.
const T1: f64 = 0.198_912_367_379_658;
const T2: f64 = 0.668_178_637_919_298_9;

/// `P(z)`, ascending powers.
const P: [f64; 8] = [
    -0.333_333_333_333_333_3,
    0.199_999_999_999_972_87,
    -0.142_857_142_842_727_08,
    0.111_111_108_188_559_31,
    -0.090_908_799_406_567_5,
    0.076_907_240_168_532_6,
    -0.066_187_234_217_151_32,
    0.051_156_755_232_583_236,
];

/// `hi + s·a + lo` for the eight quadrant and octant cases and the three reduction
/// points: `atan2 = ±(hi + s·atan(u) + lo)` with `(hi, lo)` the double-double value
/// of `H + s·atan(c)` (`H` 0, π/2 or π), indexed by `6·[x < 0] + 3·[|y| > |x|] + k`,
/// `c` the `k`-th reduction point.
const OFFSETS: [(f64, f64, f64); 12] = [
    (0.0, 0.0, 1.0),
    (FRAC_PI_8, 3.060_132_146_563_891e-18, 1.0),
    (FRAC_PI_4, 3.061_616_997_868_383e-17, 1.0),
    (FRAC_PI_2, 6.123_233_995_736_766e-17, -1.0),
    (1.178_097_245_096_172_4, 5.817_220_781_080_377e-17, -1.0),
    (FRAC_PI_4, 3.061_616_997_868_383e-17, -1.0),
    (PI, 1.224_646_799_147_353_2e-16, -1.0),
    (2.748_893_571_891_069, 1.194_045_477_681_714_4e-16, -1.0),
    (2.356_194_490_192_345, 9.184_850_993_605_148e-17, -1.0),
    (FRAC_PI_2, 6.123_233_995_736_766e-17, 1.0),
    (1.963_495_408_493_620_7, 6.429_247_210_393_156e-17, 1.0),
    (2.356_194_490_192_345, 9.184_850_993_605_148e-17, 1.0),
];

/// `atan2(y, x)` (rad, in [−π, π]) as [`f64::atan2`], within about one unit in the
/// last place. Branch-free for finite arguments (the choices are table indices), so
/// that random directions cost no mispredicted jumps; the offset's load is off the
/// path to the result, which is `atan(u)` and three additions.
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    if !(ax < f64::INFINITY && ay < f64::INFINITY) {
        // Infinite or NaN.
        return y.atan2(x);
    }
    let swapped = ay > ax;
    let (n, d) = if swapped { (ax, ay) } else { (ay, ax) };
    if d == 0.0 {
        // Both zero: ±0 or ±π by the signs.
        return if x.is_sign_negative() {
            PI.copysign(y)
        } else {
            0.0f64.copysign(y)
        };
    }
    atan2_reduced(y, x, n, d, swapped)
}

/// [`atan2`] of `N` pairs, lane by lane the same bits: straight-line code that the
/// compiler can run in vector registers; lanes that are infinite, NaN or both zero
/// (rare) are redone by [`atan2`].
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(crate) fn atan2_lanes<const N: usize>(y: &[f64; N], x: &[f64; N]) -> [f64; N] {
    let mut r = [0.0; N];
    let mut special = false;
    for i in 0..N {
        r[i] = atan2_finite(y[i], x[i]);
        let (ax, ay) = (x[i].abs(), y[i].abs());
        // Finite (NaN compares false) and not both zero.
        let ok = (ax < f64::INFINITY) & (ay < f64::INFINITY) & ((ax > 0.0) | (ay > 0.0));
        special |= !ok;
    }
    if special {
        for i in 0..N {
            r[i] = atan2(y[i], x[i]);
        }
    }
    r
}

/// [`atan2`] of finite `y`, `x`, not both zero.
#[inline(always)]
fn atan2_finite(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let swapped = ay > ax;
    let (n, d) = if swapped { (ax, ay) } else { (ay, ax) };
    atan2_reduced(y, x, n, d, swapped)
}

/// [`atan2`] from `n = min(|x|, |y|)`, `d = max(|x|, |y|) > 0` and whether `|y| > |x|`.
#[inline(always)]
fn atan2_reduced(y: f64, x: f64, n: f64, d: f64, swapped: bool) -> f64 {
    // atan(n / d) = atan(c) + atan(u).
    let (i1, i2) = (n > T1 * d, n > T2 * d);
    // The reduction point by a table load: with a chain of selects here the UR solve
    // was 4 % slower than with the old form, with the load 16 % faster.
    let c = [0.0, C1, 1.0][i1 as usize + i2 as usize];
    let u = (n - c * d) / (d + c * n);
    let z = u * u;
    let z2 = z * z;
    let z4 = z2 * z2;
    let p = (P[0] + P[1] * z)
        + z2 * (P[2] + P[3] * z)
        + z4 * ((P[4] + P[5] * z) + z2 * (P[6] + P[7] * z));
    let k = 6 * (x.to_bits() >> 63) as usize + 3 * swapped as usize + i1 as usize + i2 as usize;
    let (hi, lo, s) = OFFSETS[k];
    let su = s * u;
    let a = hi + (su + (su * z * p + lo));
    a.copysign(y)
}

/// `acos(k)` (rad, in [0, π]) for `k` in [−1, 1], as `atan2(√((1 − k)(1 + k)), k)`;
/// NaN outside.
#[inline]
pub fn acos(k: f64) -> f64 {
    atan2(((1.0 - k) * (1.0 + k)).sqrt(), k)
}

/// `√(a² + b²)` without `f64::hypot`'s guard against overflow and underflow (a
/// library call of ~18 ns, a sixth of a UR solve): the closed forms' lengths are mm
/// and unit-vector components, whose squares stay far inside the range.
#[inline]
pub(crate) fn hyp(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

/// Angle of the planar vector (x, z), increasing with right-hand rotation about +y.
#[inline]
pub(crate) fn ang(v: [f64; 2]) -> f64 {
    v[0].atan2(v[1])
}

/// Rotation of the planar vector (x, z) about +y by the angle with sine `s`, cosine `c`.
#[inline]
pub(crate) fn rot2(v: [f64; 2], s: f64, c: f64) -> [f64; 2] {
    [v[0] * c + v[1] * s, -v[0] * s + v[1] * c]
}

/// Rodrigues rotation of `v` about unit `k` by the angle with sine `s`, cosine `c`,
/// on arrays (`v·c + (k × v)·s + k·((k·v)(1 − c))`, summed left to right).
#[inline(always)]
pub(crate) fn rot_vec(k: [f64; 3], s: f64, c: f64, v: [f64; 3]) -> [f64; 3] {
    let kxv = [
        k[1] * v[2] - k[2] * v[1],
        k[2] * v[0] - k[0] * v[2],
        k[0] * v[1] - k[1] * v[0],
    ];
    let f = (k[0] * v[0] + k[1] * v[1] + k[2] * v[2]) * (1.0 - c);
    [
        v[0] * c + kxv[0] * s + k[0] * f,
        v[1] * c + kxv[1] * s + k[1] * f,
        v[2] * c + kxv[2] * s + k[2] * f,
    ]
}

/// Wraps an angle into (−π, π].
#[inline]
pub(crate) fn wrap(a: f64) -> f64 {
    // Inputs here are sums of a few angles in (−π, π]: within ±2.5π one turn either
    // way, as selects (no data-dependent jump: the closed forms wrap ~40 values a
    // call); beyond, subtracting turns, and a floating-point remainder for anything
    // larger. Both give the same bits.
    if a.abs() < 2.5 * PI {
        let r = if a > PI { a - TAU } else { a };
        return if r <= -PI { r + TAU } else { r };
    }
    let mut r = if a.abs() > 4.0 * TAU { a % TAU } else { a };
    while r > PI {
        r -= TAU;
    }
    while r <= -PI {
        r += TAU;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rng;

    /// Units in the last place between `a` and the C library's `b`.
    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        let ulp = f64::EPSILON * b.abs().max(f64::MIN_POSITIVE);
        ((a - b) / ulp).abs()
    }

    /// Over random directions of every magnitude, near the axes, the diagonals and
    /// the switching points, within 2 units in the last place of the C library's
    /// (which is within 1 of the true value), and the quadrant never wrong.
    #[test]
    fn atan2_matches_the_c_library() {
        let mut rng = Rng::new(38);
        let mut worst: f64 = 0.0;
        let mut check = |y: f64, x: f64| {
            let (a, b) = (atan2(y, x), y.atan2(x));
            let e = ulps(a, b);
            assert!(
                e <= 2.0,
                "atan2({y:e}, {x:e}) = {a:e}, the C library {b:e} ({e} ulp)"
            );
            worst = worst.max(e);
        };
        for _ in 0..400_000 {
            let ang = rng.range(-PI, PI);
            let r = 10f64.powf(rng.range(-12.0, 12.0));
            check(r * ang.sin(), r * ang.cos());
        }
        for t in [T1, T2, 1.0, 0.0] {
            for k in -2000..=2000 {
                let n = t * (1.0 + k as f64 * 1e-6);
                for (sy, sx) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    check(sy * n, sx * 1.0);
                    check(sy * 1.0, sx * n);
                }
            }
        }
        // Tiny angles: the result is y/x to the last digit.
        for e in [-300, -200, -30, -16, -8] {
            let y = 10f64.powi(e);
            check(y, 3.0);
            check(-y, 3.0);
            check(y, -3.0);
            check(3.0, y);
        }
        assert!(worst <= 2.0);
        println!("largest difference to the C library: {worst} ulp");
    }

    /// Each offset row is `H + s·atan(c)` as a double-double: recomputed here from
    /// π/2, π, π/4 and atan(tan(π/8) as a double), each as `hi + lo`, by exact sums.
    #[test]
    fn offsets_are_the_double_double_sums() {
        use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, FRAC_PI_8};
        let two_sum = |a: f64, b: f64| {
            let s = a + b;
            let bb = s - a;
            (s, (a - (s - bb)) + (b - bb))
        };
        let pio2 = (FRAC_PI_2, 6.123_233_995_736_766e-17);
        let pi = (PI, 1.224_646_799_147_353_2e-16);
        let atan_c = [
            (0.0, 0.0),
            (FRAC_PI_8, 3.060_132_146_563_891e-18),
            (FRAC_PI_4, 3.061_616_997_868_383e-17),
        ];
        // Neither, |y| > |x|, x < 0, both: a, π/2 − a, π − a, π/2 + a.
        let cases = [((0.0, 0.0), 1.0), (pio2, -1.0), (pi, -1.0), (pio2, 1.0)];
        for (q, ((h_hi, h_lo), s)) in cases.iter().enumerate() {
            for (k, (c_hi, c_lo)) in atan_c.iter().enumerate() {
                let (sum, err) = two_sum(*h_hi, s * c_hi);
                let (hi, lo) = two_sum(sum, err + (h_lo + s * c_lo));
                assert_eq!(OFFSETS[3 * q + k], (hi, lo, *s), "row {}", 3 * q + k);
            }
        }
    }

    /// Signed zeros, ±π, NaN and infinities as the C library.
    #[test]
    fn atan2_special_values_as_the_c_library() {
        let vals = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            -f64::MAX,
        ];
        for &y in &vals {
            for &x in &vals {
                let (a, b) = (atan2(y, x), y.atan2(x));
                assert!(
                    (a.is_nan() && b.is_nan())
                        || (a.to_bits() == b.to_bits())
                        || ulps(a, b) <= 2.0 && a.is_sign_negative() == b.is_sign_negative(),
                    "atan2({y}, {x}) = {a}, the C library {b}"
                );
            }
        }
    }

    /// `acos` within 2 units in the last place of the C library's over [−1, 1] and
    /// next to ±1 (where `acos` is steep), exactly 0 and π at the ends.
    #[test]
    fn acos_matches_the_c_library() {
        let mut rng = Rng::new(39);
        for _ in 0..200_000 {
            let k = rng.range(-1.0, 1.0);
            let (a, b) = (acos(k), k.acos());
            assert!(
                ulps(a, b) <= 2.0,
                "acos({k:e}) = {a:e}, the C library {b:e}"
            );
        }
        for e in 1..=52 {
            for k in [1.0 - 2f64.powi(-e), -1.0 + 2f64.powi(-e)] {
                let (a, b) = (acos(k), k.acos());
                assert!(
                    ulps(a, b) <= 2.0,
                    "acos({k:e}) = {a:e}, the C library {b:e}"
                );
            }
        }
        assert_eq!(acos(1.0), 0.0);
        assert_eq!(acos(-1.0), PI);
        assert!(acos(1.5).is_nan() && acos(f64::NAN).is_nan());
    }
}
