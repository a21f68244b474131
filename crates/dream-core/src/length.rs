//! Vector lengths rounded as Python's `math.hypot` rounds them, for whole arrays.
//!
//! A robot's rules written on scalars take lengths with `math.hypot`, which rounds differently
//! from C's `hypot` (and NumPy's) in the last bit now and then. The swarm's rules take the same
//! lengths on arrays; to round alike they follow CPython's algorithm step for step (3.12's
//! `vector_norm` for two coordinates): scale by a power of two, square exactly, sum with a
//! compensated sum, take the square root and correct it once. Every step is an IEEE operation
//! (the exact square is a fused multiply-add), so the bits are the same on every machine.
//! Python 3.10 and 3.11 square and sum another way to the same, almost always correctly rounded,
//! lengths (no difference in 20 million random pairs); only their lengths below `f64::MIN_POSITIVE`
//! (subnormal) are taken otherwise, which `dream.kernels.hypot` leaves to `math.hypot`.

use crate::parallel::map_range;

/// `2^-e` for the exponents `e` that [`hypot`] scales by (the largest coordinate's, -1022..=1024):
/// a normal number, or for `e` > 1022 a subnormal one (exact either way).
fn power_of_two(minus_e: i32) -> f64 {
    if minus_e >= -1022 {
        f64::from_bits(((minus_e + 1023) as u64) << 52)
    } else {
        f64::from_bits(1_u64 << (minus_e + 1074))
    }
}

/// `e` with `value = m 2^e`, `0.5 <= m < 1` (C's `frexp`) for a finite `value > 0`.
fn exponent(value: f64) -> i32 {
    let bits = value.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    if biased == 0 {
        let mantissa = bits & ((1_u64 << 52) - 1);
        64 - mantissa.leading_zeros() as i32 - 1074
    } else {
        biased - 1022
    }
}

/// `(hi, lo)`, `hi + lo == a + b` exactly, for `|a| >= |b|` (Dekker's fast two-sum).
fn fast_sum(a: f64, b: f64) -> (f64, f64) {
    let hi = a + b;
    (hi, (a - hi) + b)
}

/// The length of `(x, y)`, to the bit as Python's `math.hypot(x, y)`: infinite if either is,
/// else NaN if either is.
pub fn hypot(x: f64, y: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let max = if ay > ax { ay } else { ax }; // NaN never wins a comparison
    if max.is_infinite() {
        return max;
    }
    if x.is_nan() || y.is_nan() {
        return f64::NAN;
    }
    if max == 0.0 {
        return max;
    }
    let e = exponent(max);
    if e < -1023 {
        // Both subnormal: scaled up by DBL_MIN first, as 2^-e would overflow.
        return f64::MIN_POSITIVE * hypot(ax / f64::MIN_POSITIVE, ay / f64::MIN_POSITIVE);
    }
    let scale = power_of_two(-e);
    let (mut sum, mut frac1, mut frac2) = (1.0_f64, 0.0_f64, 0.0_f64);
    for value in [ax, ay] {
        let v = value * scale;
        let square = v * v;
        let (hi, lo) = fast_sum(sum, square);
        sum = hi;
        frac1 += v.mul_add(v, -square);
        frac2 += lo;
    }
    let mut h = (sum - 1.0 + (frac1 + frac2)).sqrt();
    let square = -h * h;
    let (hi, lo) = fast_sum(sum, square);
    frac1 += (-h).mul_add(h, -square);
    frac2 += lo;
    let x = hi - 1.0 + (frac1 + frac2);
    h += x / (2.0 * h);
    h / scale
}

/// [`hypot`] of each pair `(xs[i], ys[i])`, on every core for many; `xs` and `ys` have one length.
pub fn hypots(xs: &[f64], ys: &[f64]) -> Vec<f64> {
    debug_assert_eq!(xs.len(), ys.len());
    map_range(xs.len().min(ys.len()), 10.0, |i| hypot(xs[i], ys[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponents_and_powers_as_frexp_and_ldexp() {
        assert_eq!(exponent(1.0), 1);
        assert_eq!(exponent(0.5), 0);
        assert_eq!(exponent(0.75), 0);
        assert_eq!(exponent(f64::MAX), 1024);
        assert_eq!(exponent(f64::MIN_POSITIVE), -1021);
        assert_eq!(exponent(f64::from_bits(1)), -1073);
        assert_eq!(power_of_two(-1), 0.5);
        assert_eq!(power_of_two(3), 8.0);
        assert_eq!(power_of_two(-1024), f64::from_bits(1 << 50));
    }

    #[test]
    fn lengths_and_their_edges() {
        assert_eq!(hypot(3.0, 4.0), 5.0);
        assert_eq!(hypot(-3.0, 0.0), 3.0);
        assert_eq!(hypot(0.0, -0.0), 0.0);
        assert_eq!(hypot(f64::INFINITY, f64::NAN), f64::INFINITY);
        assert!(hypot(1.0, f64::NAN).is_nan());
        assert_eq!(hypot(f64::MAX, 0.0), f64::MAX);
        assert_eq!(hypot(f64::MAX, f64::MAX), f64::INFINITY);
        assert_eq!(hypot(f64::from_bits(3), f64::from_bits(4)), f64::from_bits(5));
        assert_eq!(hypots(&[3.0, 5.0], &[4.0, 12.0]), vec![5.0, 13.0]);
    }
}
