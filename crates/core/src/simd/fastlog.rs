//! A fast, vectorisable `log1p` for the store pass of the log transform.
//!
//! `std`'s `f64::ln_1p` is a libm call the compiler cannot vectorise; a fit
//! of 100 MERL materials takes 437 million of them. The method is the
//! table-driven one of modern vector libms, without a division:
//!
//! - `u = 1 + x` (rounded) only picks the reduction: `u = 2^k z` with `z` in
//!   `[OFF, 2 OFF)`, `OFF ~ 0.707`, and the top 7 bits of the mantissa field
//!   of `u - OFF` pick one of 128 subintervals, with a table row of
//!   `invc ~ 1/centre` and `logc = -ln(invc)`. The row of the subinterval
//!   starting at `z = 1` is exactly `[1, 0]`, so small `x` never meets a table
//!   logarithm. Each `invc` is nudged (by under `2^-24`) so that its logarithm
//!   is within `2^-12` ulp of the stored double: `logc` is as good as exact.
//! - `r = (1 + x) 2^-k invc - 1` is `fma(x 2^-k, invc, fma(2^-k, invc, -1))`,
//!   from `x` itself, so the rounding of `1 + x` never enters: for tiny `x`
//!   (`u = 1`, the small-x trap) `r = x` exactly. `|r| <= 2^-7`.
//! - `ln(1 + x) = k ln2 + logc + log1p(r)`, `log1p(r) = r + r^2 P(r)` with a
//!   degree-5 minimax `P` (relative error below `2^-60` on the `r` range),
//!   by Estrin's scheme; no division anywhere.
//!
//! Within 2 ulp of `f64::ln_1p` for finite `x >= 0` (tested, including every
//! table and reduction boundary), exactly 0 at 0, branch-free. [`log1p`] is
//! plain arithmetic and `f64::mul_add` (a correctly rounded FMA everywhere:
//! without FMA hardware in the build it is a libm call, so the portable
//! path is slow there), and [`log1p_avx2`] and [`log1p_avx512`] perform the
//! same operations in the same order on 4 and 8 lanes, so all give the same
//! bits.
//!
//! The tables and coefficients come from `crates/core/tools/fastlog_tables.py`
//! (mpmath, 256-bit); the tests check them against `f64::ln` independently.

const LN2: f64 = std::f64::consts::LN_2;
/// Bits of `OFF = 0.70703125`: reduced mantissas lie in `[OFF, 2 OFF)`. Its
/// mantissa field has no bits below the index, so `z = 1` starts an interval.
const OFF: u64 = 0x3FE6_A000_0000_0000;
const TABLE_BITS: u32 = 7;
const N: usize = 1 << TABLE_BITS;
const EXP_MASK: u64 = 0xFFF0_0000_0000_0000;
/// Rows `[invc, logc]` (interleaved so that one 128-bit load fetches a row).
static TABLE: [[f64; 2]; N] = {
    let mut t = [[0.0; 2]; N];
    let mut k = 0;
    while k < N {
        t[k] = [INVC[k], LOGC[k]];
        k += 1;
    }
    t
};
/// `2^52`: `f64::from_bits(TWO52_BITS | k) - 2^52 = k` for `k < 2^52`, without
/// an integer -> float conversion (which AVX2 lacks for 64-bit lanes).
const TWO52_BITS: u64 = 0x4330_0000_0000_0000;
const TWO52: f64 = 4_503_599_627_370_496.0;
/// Bits of `2^511`: `2^511 / 2^k` stays normal for every `k` in `0..=1024`.
const TWO511_BITS: u64 = 0x5FE0_0000_0000_0000;
const TWO_M511: f64 = f64::from_bits(0x2000_0000_0000_0000);

/// `log1p(r) = r + r^2 (A0 + A1 r + ... + A5 r^5)` on `r` in `[-0.00387, 0.0079]`.
const A0: f64 = f64::from_bits(0xBFDF_FFFF_FFFF_FFFA);
const A1: f64 = f64::from_bits(0x3FD5_5555_5555_4760);
const A2: f64 = f64::from_bits(0xBFD0_0000_0018_7952);
const A3: f64 = f64::from_bits(0x3FC9_9999_E86A_889C);
const A4: f64 = f64::from_bits(0xBFC5_553E_83C6_F9D6);
const A5: f64 = f64::from_bits(0x3FC2_11CE_B54A_273A);

/// `ln(1 + x)` for finite `x >= 0` (the log transform's domain: a
/// reflectance times a cosine product). Exactly 0 at 0.
#[inline(always)]
pub fn log1p(x: f64) -> f64 {
    let u = 1.0 + x;
    let tmp = u.to_bits().wrapping_sub(OFF);
    let top = tmp & EXP_MASK; // k << 52 (u >= 1, so k >= 0)
    let [invc, logc] = TABLE[(tmp >> (52 - TABLE_BITS)) as usize & (N - 1)];
    let kf = f64::from_bits(TWO52_BITS | (tmp >> 52)) - TWO52;
    // 2^-k, in two power-of-two steps that never leave the normal range.
    let s = f64::from_bits(TWO511_BITS - top) * TWO_M511;
    // (1 + x) 2^-k invc - 1 without rounding 1 + x: for x below 2^-53 it is x.
    let r = (x * s).mul_add(invc, s.mul_add(invc, -1.0));
    let hi = kf.mul_add(LN2, logc + r);
    let r2 = r * r;
    let p = A3.mul_add(r, A2).mul_add(r2, A1.mul_add(r, A0));
    let p = A5.mul_add(r, A4).mul_add(r2 * r2, p);
    p.mul_add(r2, hi)
}

/// [`log1p`] of 4 lanes: the same operations in the same order, so the same bits.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
pub unsafe fn log1p_avx2(x: std::arch::x86_64::__m256d) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 and FMA by the caller's contract; every gather index is
    // masked into 0..N, the tables' length.
    unsafe {
        let u = _mm256_add_pd(_mm256_set1_pd(1.0), x);
        let tmp = _mm256_sub_epi64(_mm256_castpd_si256(u), _mm256_set1_epi64x(OFF as i64));
        let top = _mm256_and_si256(tmp, _mm256_set1_epi64x(EXP_MASK as i64));
        // The table rows of the 4 lanes, as pairs (two 128-bit loads
        // and an unpack beat two gathers on Zen 3).
        let i = _mm256_srli_epi64::<{ 52 - TABLE_BITS as i32 }>(tmp);
        let i = _mm256_and_si256(i, _mm256_set1_epi64x(N as i64 - 1));
        let (lo, hi) = (_mm256_castsi256_si128(i), _mm256_extracti128_si256::<1>(i));
        let row = |k: i64| TABLE.as_ptr().add(k as usize).cast::<f64>();
        let ab = |a: i64, b: i64| {
            _mm256_insertf128_pd::<1>(
                _mm256_castpd128_pd256(_mm_loadu_pd(row(a))),
                _mm_loadu_pd(row(b)),
            )
        };
        let a = ab(_mm_cvtsi128_si64(lo), _mm_cvtsi128_si64(hi));
        let b = ab(_mm_extract_epi64::<1>(lo), _mm_extract_epi64::<1>(hi));
        let (invc, logc) = (_mm256_unpacklo_pd(a, b), _mm256_unpackhi_pd(a, b));
        let kf = _mm256_or_si256(
            _mm256_srli_epi64::<52>(tmp),
            _mm256_set1_epi64x(TWO52_BITS as i64),
        );
        let kf = _mm256_sub_pd(_mm256_castsi256_pd(kf), _mm256_set1_pd(TWO52));
        let s = _mm256_sub_epi64(_mm256_set1_epi64x(TWO511_BITS as i64), top);
        let s = _mm256_mul_pd(_mm256_castsi256_pd(s), _mm256_set1_pd(TWO_M511));
        let r = _mm256_fmadd_pd(s, invc, _mm256_set1_pd(-1.0));
        let r = _mm256_fmadd_pd(_mm256_mul_pd(x, s), invc, r);
        let hi = _mm256_fmadd_pd(kf, _mm256_set1_pd(LN2), _mm256_add_pd(logc, r));
        let r2 = _mm256_mul_pd(r, r);
        let p01 = _mm256_fmadd_pd(_mm256_set1_pd(A1), r, _mm256_set1_pd(A0));
        let p23 = _mm256_fmadd_pd(_mm256_set1_pd(A3), r, _mm256_set1_pd(A2));
        let p45 = _mm256_fmadd_pd(_mm256_set1_pd(A5), r, _mm256_set1_pd(A4));
        let p = _mm256_fmadd_pd(p23, r2, p01);
        let p = _mm256_fmadd_pd(p45, _mm256_mul_pd(r2, r2), p);
        _mm256_fmadd_pd(p, r2, hi)
    }
}

/// [`log1p`] of 8 lanes: the same operations in the same order, so the
/// same bits; the table rows come by two gathers.
///
/// # Safety
/// The CPU must have AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
pub unsafe fn log1p_avx512(x: std::arch::x86_64::__m512d) -> std::arch::x86_64::__m512d {
    use std::arch::x86_64::*;
    // SAFETY: AVX-512F by the caller's contract; every gather index is
    // masked into 0..N rows of two doubles, the table's extent.
    unsafe {
        let u = _mm512_add_pd(_mm512_set1_pd(1.0), x);
        let tmp = _mm512_sub_epi64(_mm512_castpd_si512(u), _mm512_set1_epi64(OFF as i64));
        let top = _mm512_and_si512(tmp, _mm512_set1_epi64(EXP_MASK as i64));
        let i = _mm512_srli_epi64::<{ 52 - TABLE_BITS }>(tmp);
        let i = _mm512_and_si512(i, _mm512_set1_epi64(N as i64 - 1));
        // Row k's invc is double 2k of the table, its logc double 2k + 1.
        let i2 = _mm512_add_epi64(i, i);
        let base = TABLE.as_ptr().cast::<f64>();
        let invc = _mm512_i64gather_pd::<8>(i2, base);
        let logc = _mm512_i64gather_pd::<8>(_mm512_add_epi64(i2, _mm512_set1_epi64(1)), base);
        let kf = _mm512_or_si512(
            _mm512_srli_epi64::<52>(tmp),
            _mm512_set1_epi64(TWO52_BITS as i64),
        );
        let kf = _mm512_sub_pd(_mm512_castsi512_pd(kf), _mm512_set1_pd(TWO52));
        let s = _mm512_sub_epi64(_mm512_set1_epi64(TWO511_BITS as i64), top);
        let s = _mm512_mul_pd(_mm512_castsi512_pd(s), _mm512_set1_pd(TWO_M511));
        let r = _mm512_fmadd_pd(s, invc, _mm512_set1_pd(-1.0));
        let r = _mm512_fmadd_pd(_mm512_mul_pd(x, s), invc, r);
        let hi = _mm512_fmadd_pd(kf, _mm512_set1_pd(LN2), _mm512_add_pd(logc, r));
        let r2 = _mm512_mul_pd(r, r);
        let p01 = _mm512_fmadd_pd(_mm512_set1_pd(A1), r, _mm512_set1_pd(A0));
        let p23 = _mm512_fmadd_pd(_mm512_set1_pd(A3), r, _mm512_set1_pd(A2));
        let p45 = _mm512_fmadd_pd(_mm512_set1_pd(A5), r, _mm512_set1_pd(A4));
        let p = _mm512_fmadd_pd(p23, r2, p01);
        let p = _mm512_fmadd_pd(p45, _mm512_mul_pd(r2, r2), p);
        _mm512_fmadd_pd(p, r2, hi)
    }
}

/// `invc` of each subinterval: close to 1 / its centre.
const INVC: [f64; 128] = [
    f64::from_bits(0x3FF6_9147_2E28_E751),
    f64::from_bits(0x3FF6_719F_379B_00B4),
    f64::from_bits(0x3FF6_524F_82A7_6954),
    f64::from_bits(0x3FF6_3356_BB16_E4F1),
    f64::from_bits(0x3FF6_14B3_6A9E_B4C9),
    f64::from_bits(0x3FF5_F664_462B_ECC8),
    f64::from_bits(0x3FF5_D867_C275_6B2E),
    f64::from_bits(0x3FF5_BABC_BD32_EDAA),
    f64::from_bits(0x3FF5_9D61_E16B_65FF),
    f64::from_bits(0x3FF5_8056_0DF5_3FD5),
    f64::from_bits(0x3FF5_6397_BE46_D9E7),
    f64::from_bits(0x3FF5_4725_E4DE_169C),
    f64::from_bits(0x3FF5_2AFF_513D_84F6),
    f64::from_bits(0x3FF5_0F22_DFE8_4EF9),
    f64::from_bits(0x3FF4_F38F_645C_F8CC),
    f64::from_bits(0x3FF4_D843_B8C4_B8FF),
    f64::from_bits(0x3FF4_BD3E_DD11_7FAD),
    f64::from_bits(0x3FF4_A27F_B131_A703),
    f64::from_bits(0x3FF4_8805_2C82_E321),
    f64::from_bits(0x3FF4_6DCE_2E9F_99DB),
    f64::from_bits(0x3FF4_53D9_F550_ACC9),
    f64::from_bits(0x3FF4_3A27_2F30_ABEE),
    f64::from_bits(0x3FF4_20B5_31DF_4ADA),
    f64::from_bits(0x3FF4_0782_CF05_A21D),
    f64::from_bits(0x3FF3_EE8F_4470_1DE6),
    f64::from_bits(0x3FF3_D5D9_906A_9D71),
    f64::from_bits(0x3FF3_BD60_E15A_ADF5),
    f64::from_bits(0x3FF3_A524_3E84_9AB4),
    f64::from_bits(0x3FF3_8D22_D803_AA77),
    f64::from_bits(0x3FF3_755B_CC74_C027),
    f64::from_bits(0x3FF3_5DCE_5EDB_152F),
    f64::from_bits(0x3FF3_4679_A839_D36D),
    f64::from_bits(0x3FF3_2F5C_FD1A_FA9B),
    f64::from_bits(0x3FF3_1877_5D2D_F2DF),
    f64::from_bits(0x3FF3_01C8_36C1_A227),
    f64::from_bits(0x3FF2_EB4E_A17C_BF8E),
    f64::from_bits(0x3FF2_D50A_1158_DD47),
    f64::from_bits(0x3FF2_BEF9_9061_3EAF),
    f64::from_bits(0x3FF2_A91C_98CC_19A9),
    f64::from_bits(0x3FF2_9372_5ACE_A858),
    f64::from_bits(0x3FF2_7DFA_3F50_5337),
    f64::from_bits(0x3FF2_68B3_7C9F_ED97),
    f64::from_bits(0x3FF2_539D_7707_71F8),
    f64::from_bits(0x3FF2_3EB7_9A65_7CDD),
    f64::from_bits(0x3FF2_2A01_24CC_588D),
    f64::from_bits(0x3FF2_1579_8592_5DCF),
    f64::from_bits(0x3FF2_0120_1228_8288),
    f64::from_bits(0x3FF1_ECF4_3D67_A1E4),
    f64::from_bits(0x3FF1_D8F5_6A05_93CD),
    f64::from_bits(0x3FF1_C522_FAAD_4215),
    f64::from_bits(0x3FF1_B17C_6755_B3B3),
    f64::from_bits(0x3FF1_9E01_185D_9766),
    f64::from_bits(0x3FF1_8AB0_91CF_C29B),
    f64::from_bits(0x3FF1_778A_0F81_5D57),
    f64::from_bits(0x3FF1_648D_5499_461D),
    f64::from_bits(0x3FF1_51B9_A5AD_BBCE),
    f64::from_bits(0x3FF1_3F0E_8A8F_5C29),
    f64::from_bits(0x3FF1_2C8B_8BE9_7589),
    f64::from_bits(0x3FF1_1A30_1A3D_FEEE),
    f64::from_bits(0x3FF1_07FB_BAA3_ECD7),
    f64::from_bits(0x3FF0_F5ED_FD88_371F),
    f64::from_bits(0x3FF0_E406_5465_5826),
    f64::from_bits(0x3FF0_D244_5971_04BB),
    f64::from_bits(0x3FF0_C0A7_7E96_C5E4),
    f64::from_bits(0x3FF0_AF2F_7877_EB25),
    f64::from_bits(0x3FF0_9DDB_AA31_D993),
    f64::from_bits(0x3FF0_8CAB_B7B4_7E31),
    f64::from_bits(0x3FF0_7B9F_2500_83DD),
    f64::from_bits(0x3FF0_6AB5_A3DF_2A95),
    f64::from_bits(0x3FF0_59EE_A4E0_D491),
    f64::from_bits(0x3FF0_4949_DB49_CC16),
    f64::from_bits(0x3FF0_38C6_B57D_363E),
    f64::from_bits(0x3FF0_2864_FCEB_4C3F),
    f64::from_bits(0x3FF0_1824_3530_C92E),
    f64::from_bits(0x3FF0_0804_03E8_F47A),
    f64::from_bits(0x3FF0_0000_0000_0000),
    f64::from_bits(0x3FEF_A11C_AEC9_A317),
    f64::from_bits(0x3FEF_6310_B079_9FE1),
    f64::from_bits(0x3FEF_25F6_3FB9_EA96),
    f64::from_bits(0x3FEE_E9C7_ED97_AAFD),
    f64::from_bits(0x3FEE_AE80_7C03_D5D0),
    f64::from_bits(0x3FEE_741A_ABA6_8AF2),
    f64::from_bits(0x3FEE_3A91_8434_E67F),
    f64::from_bits(0x3FEE_01E0_1CF5_AF5B),
    f64::from_bits(0x3FED_CA01_DF5F_E236),
    f64::from_bits(0x3FED_92F2_2261_F6C2),
    f64::from_bits(0x3FED_5CAC_8B6B_5AD7),
    f64::from_bits(0x3FED_272C_98BD_7EA2),
    f64::from_bits(0x3FEC_F26E_6188_97F9),
    f64::from_bits(0x3FEC_BE6D_89A4_6103),
    f64::from_bits(0x3FEC_8B26_55F8_DD36),
    f64::from_bits(0x3FEC_5894_D1EA_BD90),
    f64::from_bits(0x3FEC_26B5_2F94_AC6D),
    f64::from_bits(0x3FEB_F583_F151_4187),
    f64::from_bits(0x3FEB_C4FD_753D_9D12),
    f64::from_bits(0x3FEB_951E_3424_33B8),
    f64::from_bits(0x3FEB_65E2_EAFD_6E73),
    f64::from_bits(0x3FEB_3748_4C38_2205),
    f64::from_bits(0x3FEB_094B_3C7E_BB90),
    f64::from_bits(0x3FEA_DBE8_7DBC_DA3B),
    f64::from_bits(0x3FEA_AF1D_39F7_A947),
    f64::from_bits(0x3FEA_82E6_6435_05CD),
    f64::from_bits(0x3FEA_5741_0523_653F),
    f64::from_bits(0x3FEA_2C2A_8CC1_05BA),
    f64::from_bits(0x3FEA_01A0_1B97_F980),
    f64::from_bits(0x3FE9_D79F_0608_1362),
    f64::from_bits(0x3FE9_AE24_E9E3_1C16),
    f64::from_bits(0x3FE9_852F_0B9D_1BEA),
    f64::from_bits(0x3FE9_5CBB_132E_C2F9),
    f64::from_bits(0x3FE9_34C6_714C_67FA),
    f64::from_bits(0x3FE9_0D4F_0ACE_ADCC),
    f64::from_bits(0x3FE8_E652_860F_8FF4),
    f64::from_bits(0x3FE8_BFCE_720F_77E1),
    f64::from_bits(0x3FE8_99C0_F16D_EF16),
    f64::from_bits(0x3FE8_7427_C054_0F49),
    f64::from_bits(0x3FE8_4F00_B5E0_184F),
    f64::from_bits(0x3FE8_2A4A_057E_1CB2),
    f64::from_bits(0x3FE8_0601_8431_8C63),
    f64::from_bits(0x3FE7_E225_569B_3DF3),
    f64::from_bits(0x3FE7_BEB3_93BD_37A7),
    f64::from_bits(0x3FE7_9BAA_60B8_7023),
    f64::from_bits(0x3FE7_7908_1709_892B),
    f64::from_bits(0x3FE7_56CA_C267_9124),
    f64::from_bits(0x3FE7_34F0_BFE7_57C0),
    f64::from_bits(0x3FE7_1378_6986_D9C8),
    f64::from_bits(0x3FE6_F260_13DC_254A),
    f64::from_bits(0x3FE6_D1A6_3150_9453),
    f64::from_bits(0x3FE6_B148_FF9B_4D4C),
];
/// `-ln(invc)`, rounded to nearest.
const LOGC: [f64; 128] = [
    f64::from_bits(0xBFD6_02D0_67D8_91E2),
    f64::from_bits(0xBFD5_A8CA_E04E_DFA2),
    f64::from_bits(0xBFD5_4F43_1417_E1A7),
    f64::from_bits(0xBFD4_F637_F312_980E),
    f64::from_bits(0xBFD4_9DA7_FAC4_C41D),
    f64::from_bits(0xBFD4_4592_14CF_9F32),
    f64::from_bits(0xBFD3_EDF4_5F75_683F),
    f64::from_bits(0xBFD3_96CE_1ADB_BF4D),
    f64::from_bits(0xBFD3_401D_E422_CB91),
    f64::from_bits(0xBFD2_E9E2_E26D_227B),
    f64::from_bits(0xBFD2_941B_0670_6B7C),
    f64::from_bits(0xBFD2_3EC5_9382_BA4A),
    f64::from_bits(0xBFD1_E9E1_5728_99F2),
    f64::from_bits(0xBFD1_956D_3813_C2FB),
    f64::from_bits(0xBFD1_4167_F3CA_7782),
    f64::from_bits(0xBFD0_EDD0_4E03_807D),
    f64::from_bits(0xBFD0_9AA5_711A_C6D4),
    f64::from_bits(0xBFD0_47E6_1872_83B6),
    f64::from_bits(0xBFCF_EB22_756A_07BE),
    f64::from_bits(0xBFCF_474A_EF6D_F224),
    f64::from_bits(0xBFCE_A445_13BC_AAC1),
    f64::from_bits(0xBFCE_020C_BCC3_5AB3),
    f64::from_bits(0xBFCD_60A1_C8B8_3502),
    f64::from_bits(0xBFCC_C000_BCDB_3C53),
    f64::from_bits(0xBFCC_2028_B697_F9B5),
    f64::from_bits(0xBFCB_8117_28A8_23CF),
    f64::from_bits(0xBFCA_E2CA_A4AF_2BCA),
    f64::from_bits(0xBFCA_4540_AA3E_AAFC),
    f64::from_bits(0xBFC9_A877_AC23_AA38),
    f64::from_bits(0xBFC9_0C6D_96EC_BCD5),
    f64::from_bits(0xBFC8_7121_3240_E997),
    f64::from_bits(0xBFC7_D690_1DCF_5ACC),
    f64::from_bits(0xBFC7_3CB9_6FFF_D124),
    f64::from_bits(0xBFC6_A399_F753_D37F),
    f64::from_bits(0xBFC6_0B31_5170_945B),
    f64::from_bits(0xBFC5_737C_C591_8CDA),
    f64::from_bits(0xBFC4_DC7B_F763_C197),
    f64::from_bits(0xBFC4_462B_ABA1_B3DE),
    f64::from_bits(0xBFC3_B08B_8F6F_F2A6),
    f64::from_bits(0xBFC3_1B99_46F2_4F83),
    f64::from_bits(0xBFC2_8753_EA51_AB9D),
    f64::from_bits(0xBFC1_F3B9_247A_5D3F),
    f64::from_bits(0xBFC1_60C7_CDA3_27A6),
    f64::from_bits(0xBFC0_CE7E_E4FC_C289),
    f64::from_bits(0xBFC0_3CDC_19A1_EC0E),
    f64::from_bits(0xBFBF_57BC_C870_05CA),
    f64::from_bits(0xBFBE_3707_F060_4879),
    f64::from_bits(0xBFBD_1797_9511_9364),
    f64::from_bits(0xBFBB_F968_9F5F_CA12),
    f64::from_bits(0xBFBA_DC77_D9AA_EA8A),
    f64::from_bits(0xBFB9_C0C3_246D_254E),
    f64::from_bits(0xBFB8_A647_64A1_DC2A),
    f64::from_bits(0xBFB7_8D02_F62D_8285),
    f64::from_bits(0xBFB6_74EF_FC76_5A56),
    f64::from_bits(0xBFB5_5E10_3A3E_0379),
    f64::from_bits(0xBFB4_485E_1CCB_DFA9),
    f64::from_bits(0xBFB3_33D7_D0D8_3F49),
    f64::from_bits(0xBFB2_207B_7A08_549E),
    f64::from_bits(0xBFB1_0E45_BC9A_E82B),
    f64::from_bits(0xBFAF_FA68_AC8B_92F6),
    f64::from_bits(0xBFAD_DA8B_31E7_EE3F),
    f64::from_bits(0xBFAB_BCEB_DAA8_F41F),
    f64::from_bits(0xBFA9_A188_17D3_DE6E),
    f64::from_bits(0xBFA7_8858_6715_7789),
    f64::from_bits(0xBFA5_715D_0CE3_CECA),
    f64::from_bits(0xBFA3_5C8C_66C1_3061),
    f64::from_bits(0xBFA1_49E4_6760_5A88),
    f64::from_bits(0xBF9E_72BE_02D3_CE29),
    f64::from_bits(0xBF9A_55F7_1645_C3E5),
    f64::from_bits(0xBF96_3D62_8DE9_0BA9),
    f64::from_bits(0xBF92_28FE_DBAA_2C51),
    f64::from_bits(0xBF8C_3172_85C7_5F0A),
    f64::from_bits(0xBF84_192A_32E8_3320),
    f64::from_bits(0xBF78_1210_F558_6B85),
    f64::from_bits(0xBF60_0405_23D5_87EA),
    f64::from_bits(0x0000_0000_0000_0000),
    f64::from_bits(0x3F87_DC46_2A01_0A7D),
    f64::from_bits(0x3F93_CEA3_C5C6_A570),
    f64::from_bits(0x3F9B_9FC0_B8AF_919F),
    f64::from_bits(0x3FA1_B0DA_3A03_D9A0),
    f64::from_bits(0x3FA5_8A5B_9A48_E4D6),
    f64::from_bits(0x3FA9_5C82_A8E8_E3F1),
    f64::from_bits(0x3FAD_276A_DB9B_0B69),
    f64::from_bits(0x3FB0_7598_3E88_E471),
    f64::from_bits(0x3FB2_53F6_176A_1418),
    f64::from_bits(0x3FB4_2EDC_C506_46F1),
    f64::from_bits(0x3FB6_0658_49A7_50D3),
    f64::from_bits(0x3FB7_DA76_D03B_12E1),
    f64::from_bits(0x3FB9_AB42_1790_33AF),
    f64::from_bits(0x3FBB_78C8_99D0_EDB6),
    f64::from_bits(0x3FBD_4314_035C_B365),
    f64::from_bits(0x3FBF_0A30_B841_62AA),
    f64::from_bits(0x3FC0_6715_3E72_5976),
    f64::from_bits(0x3FC1_4785_779F_42AF),
    f64::from_bits(0x3FC2_266E_D0A2_5AE1),
    f64::from_bits(0x3FC3_03D6_EEEC_7FD8),
    f64::from_bits(0x3FC3_DFC2_8F14_C62D),
    f64::from_bits(0x3FC4_BA36_ED22_55E6),
    f64::from_bits(0x3FC5_9338_A730_2092),
    f64::from_bits(0x3FC6_6ACD_4B3A_AD50),
    f64::from_bits(0x3FC7_40F8_C330_37AE),
    f64::from_bits(0x3FC8_15C0_4573_580A),
    f64::from_bits(0x3FC8_E928_E990_6D43),
    f64::from_bits(0x3FC9_BB36_161D_FB84),
    f64::from_bits(0x3FCA_8BEC_F4B8_2F17),
    f64::from_bits(0x3FCB_5B51_F4AF_B5C0),
    f64::from_bits(0x3FCC_2968_57C4_18C3),
    f64::from_bits(0x3FCC_F635_57C9_C5DB),
    f64::from_bits(0x3FCD_C1BC_7BDB_EC82),
    f64::from_bits(0x3FCE_8C02_9B52_5A73),
    f64::from_bits(0x3FCF_550A_7B13_7B3E),
    f64::from_bits(0x3FD0_0E6C_2919_5022),
    f64::from_bits(0x3FD0_71B8_84D9_5918),
    f64::from_bits(0x3FD0_D46B_6382_B74D),
    f64::from_bits(0x3FD1_3686_F937_A8B0),
    f64::from_bits(0x3FD1_980D_4EFC_2378),
    f64::from_bits(0x3FD1_F8FF_93BC_A2F4),
    f64::from_bits(0x3FD2_5960_06B3_763B),
    f64::from_bits(0x3FD2_B930_2CA4_9D25),
    f64::from_bits(0x3FD3_1871_C520_4185),
    f64::from_bits(0x3FD3_7726_808B_D863),
    f64::from_bits(0x3FD3_D54F_96F1_F712),
    f64::from_bits(0x3FD4_32EF_28EC_E813),
    f64::from_bits(0x3FD4_9006_8F04_09D3),
    f64::from_bits(0x3FD4_EC97_3DB4_026A),
    f64::from_bits(0x3FD5_48A2_CC49_D263),
    f64::from_bits(0x3FD5_A42A_92A4_CFE8),
    f64::from_bits(0x3FD5_FF30_8FC3_93DB),
];

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        (a - b).abs() / (b.abs() * f64::EPSILON)
    }

    /// The worst error of [`log1p`] against `f64::ln_1p` over `xs`, and (on
    /// machines with AVX2 + FMA, and AVX-512) that [`log1p_avx2`] and
    /// [`log1p_avx512`] give the same bits.
    fn worst(xs: &[f64]) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::has_avx2_fma() {
            use std::arch::x86_64::*;
            for v in xs.chunks_exact(4) {
                let mut out = [0.0; 4];
                // SAFETY: AVX2 and FMA checked above; 4 values in, 4 out.
                unsafe {
                    let y = log1p_avx2(_mm256_loadu_pd(v.as_ptr()));
                    _mm256_storeu_pd(out.as_mut_ptr(), y);
                }
                for (a, &x) in out.iter().zip(v) {
                    assert_eq!(a.to_bits(), log1p(x).to_bits(), "{x:e}");
                }
            }
        }
        #[cfg(target_arch = "x86_64")]
        if crate::simd::has_avx512f() {
            use std::arch::x86_64::*;
            for v in xs.chunks_exact(8) {
                let mut out = [0.0; 8];
                // SAFETY: AVX-512F checked above; 8 values in, 8 out.
                unsafe {
                    let y = log1p_avx512(_mm512_loadu_pd(v.as_ptr()));
                    _mm512_storeu_pd(out.as_mut_ptr(), y);
                }
                for (a, &x) in out.iter().zip(v) {
                    assert_eq!(a.to_bits(), log1p(x).to_bits(), "{x:e}");
                }
            }
        }
        xs.iter()
            .map(|&x| ulps(log1p(x), x.ln_1p()))
            .fold(0.0, f64::max)
    }

    /// `x` and its `n` neighbours (in ulp) either side, those `>= 0`.
    fn around(x: f64, n: u64, out: &mut Vec<f64>) {
        let b = x.to_bits();
        out.extend(
            (b.saturating_sub(n)..=b + n)
                .map(f64::from_bits)
                .filter(|v| v.is_finite() && *v >= 0.0),
        );
    }

    #[test]
    fn matches_std_ln_1p_to_a_few_ulp() {
        let mut xs = Vec::new();
        let mut x = 1e-300;
        while x < 1e300 {
            xs.extend([1.0, 1.37, 2.9, 7.1].map(|t| x * t));
            x *= 1.013;
        }
        xs.extend((0..200_000).map(|k| k as f64 * 1e-4));
        xs.extend([
            f64::MIN_POSITIVE,
            1e-17,
            1.1e-16,
            0.4142135,
            0.4142136,
            1.0,
            2.0,
            1e4,
            f64::MAX,
            f64::MAX / 3.0,
        ]);
        let w = worst(&xs);
        assert!(w <= 2.0, "{w} ulp");
        assert_eq!(log1p(0.0).to_bits(), 0);
        assert_eq!(log1p(-0.0), 0.0);
    }

    /// Every table interval edge (where `1 + x = 2^k z` moves to the next
    /// row), the reduction's interval edges `2^k OFF`, powers of two for `x`
    /// and for `1 + x`, with their neighbours, and the range just below
    /// `2^-53` where `1 + x` rounds to 1.
    #[test]
    fn accurate_at_table_and_reduction_boundaries() {
        let mut xs = Vec::new();
        for k in (0..64).chain([100, 500, 1000, 1022, 1023]) {
            let p = f64::from_bits((1023 + k as u64) << 52);
            for i in 0..=N as u64 {
                let z = f64::from_bits(OFF + (i << (52 - TABLE_BITS)));
                around(z * p - 1.0, 3, &mut xs);
                around(z * p, 3, &mut xs);
            }
        }
        for e in -1074..1024 {
            let p = 2f64.powi(e);
            around(p, 2, &mut xs);
            around(p - 1.0, 2, &mut xs);
            around(p * 1.5 - 1.0, 2, &mut xs);
        }
        for k in 0..4096u64 {
            xs.push(f64::from_bits(
                0x3C90_0000_0000_0000 - k * 0x0000_0100_0000_0000,
            ));
        }
        while xs.len() % 4 != 0 {
            xs.push(0.0);
        }
        let w = worst(&xs);
        assert!(w <= 2.0, "{w} ulp");
    }

    /// The table against an independent reference: `logc` is `-ln(invc)` to
    /// within the rounding of `f64::ln`, the row of `z = 1` is exactly
    /// `[1, 0]`, and every row's interval maps into the range the polynomial
    /// was fitted on.
    #[test]
    fn table_rows_are_consistent() {
        for (i, &[invc, logc]) in TABLE.iter().enumerate() {
            let lo = f64::from_bits(OFF + ((i as u64) << (52 - TABLE_BITS)));
            let hi = f64::from_bits(OFF + ((i as u64 + 1) << (52 - TABLE_BITS)));
            assert!(ulps(logc, -invc.ln()) <= 1.0, "row {i}");
            if lo == 1.0 {
                assert_eq!([invc, logc], [1.0, 0.0]);
            }
            for z in [lo, hi] {
                let r = z.mul_add(invc, -1.0);
                assert!((-0.00387..=0.0079).contains(&r), "row {i}: r = {r}");
            }
        }
    }
}
