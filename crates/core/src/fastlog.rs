//! A vectorisable `log1p` for the store pass of the log transform.
//!
//! `std`'s `f64::ln_1p` is a libm call the compiler cannot vectorise; a fit
//! of 100 MERL materials takes 437 million of them. This one is the
//! textbook method (as in fdlibm): `u = 1 + x` rounded, a correction
//! `c = (1 + x - u) / u` for that rounding, `u = 2^k m` with
//! `m` in `[sqrt(1/2), sqrt(2))`, and `log m = 2 atanh(s)`, `s = (m - 1)/(m + 1)`,
//! by its odd series to degree 23 (`|s| <= 0.172`: truncation below 1e-17).
//! Within a few ulp of `f64::ln_1p` for `x >= 0` (tested), branch-free.

const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
/// Bits of `sqrt(1/2)`: mantissas are reduced into `[sqrt(1/2), sqrt(2))`.
const SQRT_HALF_BITS: u64 = 0x3FE6_A09E_667F_3BCD;
const ONE_BITS: u64 = 0x3FF0_0000_0000_0000;
const MANTISSA: u64 = 0x000F_FFFF_FFFF_FFFF;
/// `2^52`: `f64::from_bits(TWO52_BITS | k) - 2^52 = k` for `k < 2^52`, without
/// an integer -> float conversion (which AVX2 cannot vectorise).
const TWO52_BITS: u64 = 0x4330_0000_0000_0000;
const TWO52: f64 = 4_503_599_627_370_496.0;

/// `ln(1 + x)` for finite `x >= 0` (the log transform's domain: a
/// reflectance times a cosine product). Exactly 0 at 0.
#[inline(always)]
pub fn log1p(x: f64) -> f64 {
    let u = 1.0 + x;
    // The rounding error of u, relative to u: exact differences by Sterbenz.
    let c = if u < 2.0 {
        x - (u - 1.0)
    } else {
        1.0 - (u - x)
    } / u;
    // u = 2^k m: shift the exponent so that m lands in [sqrt(1/2), sqrt(2)).
    let ix = u.to_bits().wrapping_add(ONE_BITS - SQRT_HALF_BITS);
    let kf = f64::from_bits(TWO52_BITS | (ix >> 52)) - (TWO52 + 1023.0);
    let m = f64::from_bits((ix & MANTISSA) + SQRT_HALF_BITS);
    let f = m - 1.0;
    let s = f / (2.0 + f);
    let z = s * s;
    // atanh(s)/s = sum z^j / (2j + 1), j = 0..11, by Horner.
    let mut p = 1.0 / 23.0;
    p = p * z + 1.0 / 21.0;
    p = p * z + 1.0 / 19.0;
    p = p * z + 1.0 / 17.0;
    p = p * z + 1.0 / 15.0;
    p = p * z + 1.0 / 13.0;
    p = p * z + 1.0 / 11.0;
    p = p * z + 1.0 / 9.0;
    p = p * z + 1.0 / 7.0;
    p = p * z + 1.0 / 5.0;
    p = p * z + 1.0 / 3.0;
    // log m = 2 s p(z) = f - 2 s (f/2 - ... ): write it as f - s (f - z' ...) to
    // keep the leading term exact: 2 s = f - s f, so log m = f - s (f - 2 z p').
    let r = s * (f - 2.0 * z * p);
    kf * LN2_HI + (f - (r - (kf * LN2_LO + c)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        (a - b).abs() / (b.abs() * f64::EPSILON)
    }

    #[test]
    fn matches_std_ln_1p_to_a_few_ulp() {
        let mut worst = 0.0f64;
        let mut x = 1e-300;
        while x < 1e300 {
            for t in [1.0, 1.37, 2.9, 7.1] {
                let v = x * t;
                worst = worst.max(ulps(log1p(v), v.ln_1p()));
            }
            x *= 1.013;
        }
        for k in 0..200_000 {
            let v = k as f64 * 1e-4;
            worst = worst.max(ulps(log1p(v), v.ln_1p()));
        }
        for v in [
            f64::MIN_POSITIVE,
            1e-17,
            1.1e-16,
            0.4142135,
            0.4142136,
            1.0,
            2.0,
            1e4,
        ] {
            worst = worst.max(ulps(log1p(v), v.ln_1p()));
        }
        assert!(worst <= 4.0, "{worst} ulp");
        assert_eq!(log1p(0.0), 0.0);
    }
}
