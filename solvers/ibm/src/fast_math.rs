//! `e^x` and `ln(1 − α)` without branches or calls, for the loops over a
//! body's faces: libm's functions are calls, which keep a loop on scalars,
//! and these run on vector instructions. Each is a range reduction by the
//! bits of the number and a polynomial summed by Estrin's scheme.

/// `a b + c`, in one rounding where the target fuses it (an FMA
/// instruction; every 64-bit ARM has one): a chain of them is half as long
/// as multiplications and additions apart. Without FMA, `mul_add` would be
/// a call, so the two operations are kept.
#[inline(always)]
pub(crate) fn fused(a: f64, b: f64, c: f64) -> f64 {
    #[cfg(any(target_feature = "fma", target_arch = "aarch64"))]
    {
        a.mul_add(b, c)
    }
    #[cfg(not(any(target_feature = "fma", target_arch = "aarch64")))]
    {
        a * b + c
    }
}

/// ln 2 in two parts: the first has zeros in its last bits, so that
/// `k ln2_hi` is exact for the integers `k` of a range reduction.
const LN2_HI: f64 = 6.931_471_803_691_238e-1;
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;

/// `e^x` to a few units in the last place for `|x| ≤ 700` (clamped
/// beyond): `x = k ln 2 + r` with `|r| ≤ ln 2 / 2`, `e^r` by its Taylor
/// series to `r^13` (remainder below 1e-17), times `2^k` made from its
/// bits.
///
/// The series is summed by Estrin's scheme, pairs of terms joined by
/// `r²`, `r⁴` and `r⁸`, rather than by Horner's: the same operations
/// nearly, but a chain of four fused steps instead of thirteen. The
/// fractions' loop waits on that chain, not on the arithmetic units.
#[inline(always)]
pub(crate) fn exp(x: f64) -> f64 {
    // 1.5 × 2^52: adding it rounds to an integer, held in the low bits.
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    const C: [f64; 14] = INVERSE_FACTORIALS;
    let x = x.clamp(-700.0, 700.0);
    let shifted = x * std::f64::consts::LOG2_E + SHIFT;
    let k = shifted - SHIFT;
    let r = fused(-k, LN2_LO, fused(-k, LN2_HI, x));
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let pair = |n: usize| fused(C[n + 1], r, C[n]);
    let low = fused(fused(pair(6), r2, pair(4)), r4, fused(pair(2), r2, pair(0)));
    let high = fused(fused(pair(12), r2, pair(10)), r2, pair(8));
    let p = fused(high, r8, low);
    // 2^k: k + 1023 in the exponent's bits (k is in the low bits of
    // `shifted`, two's complement).
    let scale = f64::from_bits(shifted.to_bits().wrapping_add(1023) << 52);
    p * scale
}

/// `1/n!` for n = 0 to 13.
const INVERSE_FACTORIALS: [f64; 14] = [
    1.0,
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5_040.0,
    1.0 / 40_320.0,
    1.0 / 362_880.0,
    1.0 / 3_628_800.0,
    1.0 / 39_916_800.0,
    1.0 / 479_001_600.0,
    1.0 / 6_227_020_800.0,
];

/// `ln(1 − α)` for `0 ≤ α ≤ 1` to a few units in the last place; at
/// `α = 1`, `ln 2^−1022` instead of `−∞`.
///
/// `1 − α = m 2^k` with `√½ ≤ m < √2` (from the bits, shifted so that the
/// exponent field rounds at `√½`), and `ln m = 2 atanh s` with
/// `s = (m − 1)/(m + 1)`, `|s| ≤ 0.1716`, by its series to `s^21`
/// (`s²` ≤ 0.0295: remainder below 1e-18 of it). Where `k = 0`,
/// `m − 1 = −α` is taken as `−α`, without the rounding of `1 − α`.
#[inline(always)]
pub(crate) fn ln_one_minus(alpha: f64) -> f64 {
    const SQRT_HALF_BITS: u64 = 0x3fe6_a09e_667f_3bcd;
    // 1/(2j + 1), j = 0 to 10.
    const C: [f64; 11] = [
        1.0,
        1.0 / 3.0,
        1.0 / 5.0,
        1.0 / 7.0,
        1.0 / 9.0,
        1.0 / 11.0,
        1.0 / 13.0,
        1.0 / 15.0,
        1.0 / 17.0,
        1.0 / 19.0,
        1.0 / 21.0,
    ];
    // 2^52 as a float: or-ed into its low bits, an integer below 2^52
    // reads as 2^52 plus itself.
    const TWO_52_BITS: u64 = 0x4330_0000_0000_0000;
    const BIAS: u64 = 1023 << 52;
    let y = (1.0 - alpha).max(f64::MIN_POSITIVE);
    let bits = y.to_bits();
    // k + 1023 ≥ 1 in the exponent field: logical shifts and integer to
    // float by bits, which vector units without 64-bit arithmetic shifts
    // or conversions (AVX2) have.
    let biased = bits.wrapping_sub(SQRT_HALF_BITS).wrapping_add(BIAS) >> 52;
    let m = f64::from_bits(bits.wrapping_sub(biased << 52).wrapping_add(BIAS));
    let k = f64::from_bits(biased | TWO_52_BITS) - (4_503_599_627_370_496.0 + 1023.0);
    let f = if k == 0.0 { -alpha } else { m - 1.0 };
    let s = f / (2.0 + f);
    let z = s * s;
    let z2 = z * z;
    let z4 = z2 * z2;
    let z8 = z4 * z4;
    let pair = |n: usize| fused(C[n + 1], z, C[n]);
    let low = fused(fused(pair(6), z2, pair(4)), z4, fused(pair(2), z2, pair(0)));
    let high = fused(C[10], z2, pair(8));
    let series = fused(high, z8, low);
    fused(k, LN2_HI, fused(k, LN2_LO, 2.0 * s * series))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exponential without branches agrees with libm's to a few ulp.
    #[test]
    fn exponential_to_round_off() {
        let mut worst: f64 = 0.0;
        for n in 0..=200_000 {
            let x = -120.0 + 140.0 * n as f64 / 200_000.0;
            let (ours, libm) = (exp(x), x.exp());
            worst = worst.max(((ours - libm) / libm).abs());
        }
        assert!(worst < 4.0 * f64::EPSILON, "{worst:e}");
    }

    /// `ln(1 − α)` agrees with libm's `ln_1p(−α)` to a few ulp over the
    /// fractions of a layer, from far below the tail's 4.5e-5 to a face
    /// all but inside.
    #[test]
    fn log_of_one_minus_to_round_off() {
        let (mut relative, mut absolute): (f64, f64) = (0.0, 0.0);
        let mut check = |alpha: f64| {
            let (ours, libm) = (ln_one_minus(alpha), (-alpha).ln_1p());
            absolute = absolute.max((ours - libm).abs());
            relative = relative.max(((ours - libm) / libm).abs());
        };
        for n in 1..=200_000 {
            check(n as f64 / 200_001.0);
        }
        for n in 0..=300 {
            check(10f64.powf(-(n as f64) / 10.0));
            check(1.0 - 10f64.powf(-(n as f64) / 20.0));
        }
        assert!(
            relative < 4.0 * f64::EPSILON,
            "{relative:e} ({absolute:e} absolute)"
        );
        assert_eq!(ln_one_minus(0.0), 0.0);
        let inside = ln_one_minus(1.0);
        assert!((inside + 1022.0 * std::f64::consts::LN_2).abs() < 1e-12);
    }
}
