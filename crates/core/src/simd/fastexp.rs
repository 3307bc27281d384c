//! A vectorisable `exp` for the hot loops of the albedo map.
//!
//! `std`'s `f64::exp` is a libm call the compiler cannot vectorise; the map
//! evaluates hundreds of millions of them. This one is the textbook
//! reduction `exp(x) = 2^k exp(r)`, `k = round(x / ln 2)`, `|r| <= ln2 / 2`,
//! with `ln 2` split in two parts and a degree-13 Taylor polynomial for
//! `exp(r)`: within a few ulp of `f64::exp` over the whole finite range
//! (tested), branch-free, and written with plain arithmetic and bit
//! operations so that loops over slices compile to SIMD.

const LOG2E: f64 = std::f64::consts::LOG2_E;
const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
/// `1.5 * 2^52`: adding it rounds to an integer held in the low mantissa bits.
const SHIFTER: f64 = 6_755_399_441_055_744.0;

/// `e^x` for finite `x`, clamped to `[-708, 709]` (so about 3e-308 at the bottom, never 0 or infinite).
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    let x = x.clamp(-708.0, 709.0);
    let kf = (x * LOG2E + SHIFTER) - SHIFTER;
    let r = (x - kf * LN2_HI) - kf * LN2_LO;
    // Horner on the Taylor series of exp(r) to degree 13 (|r| <= 0.347: error < 1e-17).
    let mut p = 1.0 / 6_227_020_800.0;
    p = p * r + 1.0 / 479_001_600.0;
    p = p * r + 1.0 / 39_916_800.0;
    p = p * r + 1.0 / 3_628_800.0;
    p = p * r + 1.0 / 362_880.0;
    p = p * r + 1.0 / 40_320.0;
    p = p * r + 1.0 / 5_040.0;
    p = p * r + 1.0 / 720.0;
    p = p * r + 1.0 / 120.0;
    p = p * r + 1.0 / 24.0;
    p = p * r + 1.0 / 6.0;
    p = p * r + 0.5;
    p = p * r + 1.0;
    p = p * r + 1.0;
    // 2^k from the exponent field. k comes out of the rounding sum's low
    // mantissa bits (no float -> int conversion, which would not vectorise);
    // the clamp keeps k in [-1021, 1023], where 2^k is a normal number.
    let k = ((x * LOG2E + SHIFTER).to_bits() as i64).wrapping_sub(SHIFTER.to_bits() as i64);
    p * f64::from_bits(((k + 1023) as u64) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_std_exp_to_a_few_ulp() {
        let mut worst = 0.0f64;
        let mut x = -700.0;
        while x < 700.0 {
            let (a, b) = (exp(x), x.exp());
            worst = worst.max(((a - b) / b).abs());
            x += 0.0137;
        }
        for &x in &[0.0, 1e-300, -1e-12, 1e-8, 0.5, -0.5, 0.3465, 708.0, -708.0] {
            let (a, b) = (exp(x), f64::exp(x));
            worst = worst.max(((a - b) / b).abs());
        }
        assert!(worst < 1e-15, "{worst:e}");
        assert_eq!(exp(0.0), 1.0);
        assert!(exp(-1000.0) < 1e-300 && exp(-1000.0) > 0.0);
        assert!(exp(1000.0).is_finite());
    }
}
