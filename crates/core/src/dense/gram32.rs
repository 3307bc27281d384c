//! The Gram kernel of an f32 store's pass: `Y += Z_b^T Z_b` over one
//! material-major block of f32 values, lower triangle only, with f32
//! products summed in f32 over a block and the block's sums added in f64.
//!
//! Each output is an inner product of two materials' runs of `len` values
//! in sixteen fixed f32 lanes of fused multiply-adds (value `r` goes to lane
//! `r % 16`, so a 512-row block puts 32 products in each lane). The lanes
//! are widened to f64 and reduced as `a_k = l_k + l_(k+8)`, then
//! `((a0 + a4) + (a1 + a5)) + ((a2 + a6) + (a3 + a7))`, then the values
//! past the last full group of sixteen are added in order (in f64, where the
//! product of two f32 is exact), and the result is added to the output. The
//! AVX-512 path (one register of sixteen lanes), the AVX2 path (two of
//! eight) and the portable path (`f32::mul_add`) do the same operations in
//! the same order, so the Gram matrix has the same bits on every CPU.
//!
//! Why f32 lanes are enough: an f32 store already rounds every value to
//! 2^-24 of itself, which moves each product by up to 2^-23 of its size,
//! and `Y` by that share of the sum of the products' sizes. A lane's 32
//! rounded additions move its sum by at most `32 * 2^-24` of the sum of its
//! products' sizes (about `sqrt(32) * 2^-24` typically): the same order,
//! while the sums across the 8 544 blocks of a 100-material table (and the
//! reduction of each block's lanes) stay in f64, as sums of millions of
//! values must. A store kept in f64 uses the f64 kernel
//! ([`super::gram::syrk_lower_add`]). Twice the lanes per instruction make
//! this kernel about twice as fast as the f64 one.

/// Lanes of one output's sum.
const LANES: usize = 16;

use super::gram::walk;

/// `acc[j * n + i] += z_i . z_j` for `j <= i < n`, with `z_i =
/// block[i * len..(i + 1) * len]` and `n = block.len() / len`, as the
/// module describes. `acc` is `n x n`, column-major; its strict upper
/// triangle is not touched.
///
/// # Panics
/// When `len == 0` with a non-empty block, or `acc` is not `n x n`
/// (caller bugs, never input).
pub fn syrk_lower_add_f32(block: &[f32], len: usize, acc: &mut [f64]) {
    if block.is_empty() {
        return;
    }
    assert!(len > 0 && block.len().is_multiple_of(len));
    let n = block.len() / len;
    assert_eq!(acc.len(), n * n);
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::has_avx512f() {
            // SAFETY: the CPU has AVX-512F (checked just above).
            unsafe { tiles_avx512(block, len, acc) };
            return;
        }
        if crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX2 and FMA (checked just above).
            unsafe { tiles_avx2(block, len, acc) };
            return;
        }
    }
    tiles_portable(block, len, acc);
}

/// The lanes of one output widened and reduced in the fixed order, then
/// the tail in order.
#[inline(always)]
fn finish(l: [f32; LANES], zi: &[f32], zj: &[f32], split: usize) -> f64 {
    let a: [f64; 8] = std::array::from_fn(|k| l[k] as f64 + l[k + 8] as f64);
    let s = ((a[0] + a[4]) + (a[1] + a[5])) + ((a[2] + a[6]) + (a[3] + a[7]));
    tail(s, zi, zj, split)
}

/// The values past the last full group of lanes, in order, in f64.
#[inline(always)]
fn tail(mut s: f64, zi: &[f32], zj: &[f32], split: usize) -> f64 {
    for (x, y) in zi[split..].iter().zip(&zj[split..]) {
        s = (*x as f64).mul_add(*y as f64, s);
    }
    s
}

/// One output the portable way.
#[inline(always)]
fn dot16(zi: &[f32], zj: &[f32]) -> f64 {
    let split = zi.len() / LANES * LANES;
    let mut l = [0.0f32; LANES];
    for (a, b) in zi[..split]
        .chunks_exact(LANES)
        .zip(zj[..split].chunks_exact(LANES))
    {
        for k in 0..LANES {
            l[k] = a[k].mul_add(b[k], l[k]);
        }
    }
    finish(l, zi, zj, split)
}

fn tiles_portable(block: &[f32], len: usize, acc: &mut [f64]) {
    let n = block.len() / len;
    for j in 0..n {
        let zj = &block[j * len..(j + 1) * len];
        for i in j..n {
            acc[j * n + i] += dot16(&block[i * len..(i + 1) * len], zj);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn tiles_avx512(block: &[f32], len: usize, acc: &mut [f64]) {
    use std::arch::x86_64::*;
    const TI: usize = 4;
    const TJ: usize = 4;
    let split = len / LANES * LANES;
    walk::<f32, TI, TJ>(block, len, acc, |rows, cols, sums| {
        let p = block.as_ptr();
        let mut l = [[_mm512_setzero_ps(); TJ]; TI];
        for r in (0..split).step_by(LANES) {
            // SAFETY: r + 16 <= len and the tile's runs lie inside `block`
            // (asserted by `walk`).
            unsafe {
                let x = rows.map(|i| _mm512_loadu_ps(p.add(i * len + r)));
                for (b, j) in cols.iter().enumerate() {
                    let y = _mm512_loadu_ps(p.add(j * len + r));
                    for (la, xa) in l.iter_mut().zip(&x) {
                        la[b] = _mm512_fmadd_ps(*xa, y, la[b]);
                    }
                }
            }
        }
        // The fixed reduction of four outputs at once: each one's lanes
        // widened, `a_k = l_k + l_(k+8)`, then as the f64 kernel reduces
        // its eight lanes (see `super::gram`).
        for (a, row) in l.iter().enumerate() {
            let mut r = [0.0f64; TJ];
            // SAFETY: AVX-512F (and so AVX) by this function's contract;
            // `r` holds 4 f64.
            unsafe {
                let h = row.map(|v| {
                    let lo = _mm512_cvtps_pd(_mm512_castps512_ps256(v));
                    let hi = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(
                        _mm512_castps_pd(v),
                    )));
                    let a8 = _mm512_add_pd(lo, hi);
                    _mm256_add_pd(_mm512_castpd512_pd256(a8), _mm512_extractf64x4_pd::<1>(a8))
                });
                let ab = _mm256_hadd_pd(h[0], h[1]);
                let cd = _mm256_hadd_pd(h[2], h[3]);
                let lo = _mm256_permute2f128_pd::<0x20>(ab, cd);
                let hi = _mm256_permute2f128_pd::<0x31>(ab, cd);
                _mm256_storeu_pd(r.as_mut_ptr(), _mm256_add_pd(lo, hi));
            }
            for (b, (sum, r)) in sums[a].iter_mut().zip(r).enumerate() {
                let (i, j) = (rows[a], cols[b]);
                *sum = tail(
                    r,
                    &block[i * len..(i + 1) * len],
                    &block[j * len..(j + 1) * len],
                    split,
                );
            }
        }
    });
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn tiles_avx2(block: &[f32], len: usize, acc: &mut [f64]) {
    use std::arch::x86_64::*;
    const TI: usize = 2;
    const TJ: usize = 2;
    let split = len / LANES * LANES;
    walk::<f32, TI, TJ>(block, len, acc, |rows, cols, sums| {
        let p = block.as_ptr();
        let mut lo = [[_mm256_setzero_ps(); TJ]; TI];
        let mut hi = [[_mm256_setzero_ps(); TJ]; TI];
        for r in (0..split).step_by(LANES) {
            // SAFETY: r + 16 <= len and the tile's runs lie inside `block`
            // (asserted by `walk`).
            unsafe {
                let xl = rows.map(|i| _mm256_loadu_ps(p.add(i * len + r)));
                let xh = rows.map(|i| _mm256_loadu_ps(p.add(i * len + r + 8)));
                for (b, j) in cols.iter().enumerate() {
                    let yl = _mm256_loadu_ps(p.add(j * len + r));
                    let yh = _mm256_loadu_ps(p.add(j * len + r + 8));
                    for a in 0..TI {
                        lo[a][b] = _mm256_fmadd_ps(xl[a], yl, lo[a][b]);
                        hi[a][b] = _mm256_fmadd_ps(xh[a], yh, hi[a][b]);
                    }
                }
            }
        }
        for a in 0..TI {
            for b in 0..TJ {
                let mut lanes = [0.0f32; LANES];
                // SAFETY: `lanes` holds 16 f32, the two halves 8 each.
                unsafe {
                    _mm256_storeu_ps(lanes.as_mut_ptr(), lo[a][b]);
                    _mm256_storeu_ps(lanes.as_mut_ptr().add(8), hi[a][b]);
                }
                let (i, j) = (rows[a], cols[b]);
                sums[a][b] = finish(
                    lanes,
                    &block[i * len..(i + 1) * len],
                    &block[j * len..(j + 1) * len],
                    split,
                );
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_merl::synth::SplitMix64;

    fn random(len: usize, n: usize, rng: &mut SplitMix64) -> Vec<f32> {
        (0..len * n)
            .map(|_| (rng.range(-1.0, 1.0) * 3.0) as f32)
            .collect()
    }

    /// The exact sums (f64 products of f32 values are exact; a plain f64
    /// sum of at most a few thousand is within 1e-12 of exact here).
    fn exact(block: &[f32], len: usize) -> Vec<(f64, f64)> {
        let n = block.len() / len;
        let mut y = vec![(0.0, 0.0); n * n];
        for j in 0..n {
            for i in j..n {
                let (mut s, mut size) = (0.0, 0.0);
                for r in 0..len {
                    let p = block[i * len + r] as f64 * block[j * len + r] as f64;
                    s += p;
                    size += p.abs();
                }
                y[j * n + i] = (s, size);
            }
        }
        y
    }

    #[test]
    fn within_the_f32_lane_bound_and_the_same_bits_on_every_path() {
        let mut rng = SplitMix64::new(17);
        // Odd sizes exercise the edge tiles and the tails.
        for (len, n) in [
            (1, 1),
            (15, 3),
            (16, 4),
            (37, 5),
            (512, 13),
            (512, 100),
            (1000, 9),
        ] {
            let block = random(len, n, &mut rng);
            let want = exact(&block, len);
            let mut got = vec![0.0; n * n];
            syrk_lower_add_f32(&block, len, &mut got);
            let mut portable = vec![0.0; n * n];
            tiles_portable(&block, len, &mut portable);
            assert_eq!(got, portable, "{len} x {n}");
            #[cfg(target_arch = "x86_64")]
            if crate::simd::has_avx2_fma() {
                let mut avx2 = vec![0.0; n * n];
                // SAFETY: the CPU has AVX2 and FMA (checked just above).
                unsafe { tiles_avx2(&block, len, &mut avx2) };
                assert_eq!(got, avx2, "{len} x {n}");
            }
            // Each lane adds at most len / 16 products in f32.
            let per_lane = (len / LANES).max(1) as f64;
            for j in 0..n {
                for i in 0..n {
                    let g = got[j * n + i];
                    if i < j {
                        assert_eq!(g, 0.0, "upper triangle untouched");
                        continue;
                    }
                    let (s, size) = want[j * n + i];
                    let bound = (per_lane + 1.0) * f32::EPSILON as f64 / 2.0 * size + 1e-12 * size;
                    assert!((g - s).abs() <= bound, "{len} x {n} ({i}, {j}): {g} vs {s}");
                }
            }
            // Accumulates: a second call doubles the sums exactly.
            syrk_lower_add_f32(&block, len, &mut got);
            assert_eq!(got, portable.iter().map(|v| v * 2.0).collect::<Vec<_>>());
        }
    }

    #[test]
    fn a_single_row_is_exact() {
        let block = [3.0e-3f32, -7.5, 1.25e4];
        let mut acc = vec![0.0; 9];
        syrk_lower_add_f32(&block, 1, &mut acc);
        assert_eq!(acc[0], 3.0e-3f32 as f64 * 3.0e-3f32 as f64);
        assert_eq!(acc[1], 3.0e-3f32 as f64 * -7.5);
        assert_eq!(acc[8], 1.25e4 * 1.25e4);
    }

    #[test]
    fn empty_block_adds_nothing() {
        let mut acc: Vec<f64> = Vec::new();
        syrk_lower_add_f32(&[], 4, &mut acc);
        assert!(acc.is_empty());
    }
}
