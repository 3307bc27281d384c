//! The Gram kernel of the store pass: `Y += Z_b^T Z_b` over one
//! material-major block, lower triangle only.
//!
//! Each output is an inner product of two materials' runs of `len` values
//! in eight fixed lanes of fused multiply-adds (value `r` goes to lane
//! `r % 8`), reduced as `((l0 + l4) + (l1 + l5)) + ((l2 + l6) + (l3 + l7))`,
//! then the tail in order, then added to the output. The AVX-512 path (one
//! register of eight lanes), the AVX2 path (two registers of four) and the
//! portable path (`f64::mul_add`) do the same operations in the same order,
//! so the Gram matrix has the same bits on every CPU. Tiles of outputs
//! share their loads: 4 x 4 outputs per step with AVX-512, 2 x 3 with AVX2.

const LANES: usize = 8;

/// `acc[j * n + i] += z_i . z_j` for `j <= i < n`, with `z_i =
/// block[i * len..(i + 1) * len]` and `n = block.len() / len`. `acc` is
/// `n x n`, column-major; its strict upper triangle is not touched.
///
/// # Panics
/// When `len == 0` with a non-empty block, or `acc` is not `n x n`
/// (caller bugs, never input).
pub fn syrk_lower_add(block: &[f64], len: usize, acc: &mut [f64]) {
    if block.is_empty() {
        return;
    }
    assert!(len > 0 && block.len() % len == 0);
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

/// The lane sums of one output reduced in the fixed order, then the tail.
#[inline(always)]
fn finish(l: [f64; LANES], zi: &[f64], zj: &[f64], split: usize) -> f64 {
    let mut s = ((l[0] + l[4]) + (l[1] + l[5])) + ((l[2] + l[6]) + (l[3] + l[7]));
    for (a, b) in zi[split..].iter().zip(&zj[split..]) {
        s = a.mul_add(*b, s);
    }
    s
}

/// One output the portable way (edge tiles of the vector paths too).
#[inline(always)]
fn dot8(zi: &[f64], zj: &[f64]) -> f64 {
    let split = zi.len() / LANES * LANES;
    let mut l = [0.0f64; LANES];
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

fn tiles_portable(block: &[f64], len: usize, acc: &mut [f64]) {
    let n = block.len() / len;
    for j in 0..n {
        let zj = &block[j * len..(j + 1) * len];
        for i in j..n {
            acc[j * n + i] += dot8(&block[i * len..(i + 1) * len], zj);
        }
    }
}

/// Walk the lower triangle in tiles of `TI x TJ` outputs: full tiles go to
/// `tile(i0, j0, out)`, which returns the `TI x TJ` sums; outputs outside
/// the matrix's lower triangle are dropped; edge rows and columns that do
/// not fill a tile go through [`dot8`].
#[inline(always)]
fn walk<const TI: usize, const TJ: usize>(
    block: &[f64],
    len: usize,
    acc: &mut [f64],
    mut tile: impl FnMut(usize, usize, &mut [[f64; TJ]; TI]),
) {
    let n = block.len() / len;
    let (ni, nj) = (n / TI * TI, n / TJ * TJ);
    let mut sums = [[0.0f64; TJ]; TI];
    for i0 in (0..ni).step_by(TI) {
        for j0 in (0..nj).step_by(TJ) {
            if j0 > i0 + TI - 1 {
                break;
            }
            tile(i0, j0, &mut sums);
            for (a, row) in sums.iter().enumerate() {
                for (b, s) in row.iter().enumerate() {
                    let (i, j) = (i0 + a, j0 + b);
                    if j <= i {
                        acc[j * n + i] += s;
                    }
                }
            }
        }
        // Columns past the last full tile of columns.
        for j in nj..n {
            for i in i0.max(j)..i0 + TI {
                acc[j * n + i] += dot8(
                    &block[i * len..(i + 1) * len],
                    &block[j * len..(j + 1) * len],
                );
            }
        }
    }
    // Rows past the last full tile of rows.
    for i in ni..n {
        for j in 0..=i {
            acc[j * n + i] += dot8(
                &block[i * len..(i + 1) * len],
                &block[j * len..(j + 1) * len],
            );
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn tiles_avx512(block: &[f64], len: usize, acc: &mut [f64]) {
    use std::arch::x86_64::*;
    const TI: usize = 4;
    const TJ: usize = 4;
    let split = len / LANES * LANES;
    walk::<TI, TJ>(block, len, acc, |i0, j0, sums| {
        assert!((i0 + TI) * len <= block.len() && (j0 + TJ) * len <= block.len());
        let p = block.as_ptr();
        let mut l = [[_mm512_setzero_pd(); TJ]; TI];
        for r in (0..split).step_by(LANES) {
            // SAFETY: r + 8 <= len and the tile's runs lie inside `block`
            // (asserted above).
            unsafe {
                let mut x = [_mm512_setzero_pd(); TI];
                for (a, x) in x.iter_mut().enumerate() {
                    *x = _mm512_loadu_pd(p.add((i0 + a) * len + r));
                }
                for b in 0..TJ {
                    let y = _mm512_loadu_pd(p.add((j0 + b) * len + r));
                    for a in 0..TI {
                        l[a][b] = _mm512_fmadd_pd(x[a], y, l[a][b]);
                    }
                }
            }
        }
        for a in 0..TI {
            for b in 0..TJ {
                let mut lanes = [0.0f64; LANES];
                // SAFETY: `lanes` holds 8 f64.
                unsafe { _mm512_storeu_pd(lanes.as_mut_ptr(), l[a][b]) };
                let (i, j) = (i0 + a, j0 + b);
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

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn tiles_avx2(block: &[f64], len: usize, acc: &mut [f64]) {
    use std::arch::x86_64::*;
    const TI: usize = 2;
    const TJ: usize = 3;
    let split = len / LANES * LANES;
    walk::<TI, TJ>(block, len, acc, |i0, j0, sums| {
        assert!((i0 + TI) * len <= block.len() && (j0 + TJ) * len <= block.len());
        let p = block.as_ptr();
        let mut lo = [[_mm256_setzero_pd(); TJ]; TI];
        let mut hi = [[_mm256_setzero_pd(); TJ]; TI];
        for r in (0..split).step_by(LANES) {
            // SAFETY: r + 8 <= len and the tile's runs lie inside `block`
            // (asserted above).
            unsafe {
                let mut xl = [_mm256_setzero_pd(); TI];
                let mut xh = [_mm256_setzero_pd(); TI];
                for a in 0..TI {
                    xl[a] = _mm256_loadu_pd(p.add((i0 + a) * len + r));
                    xh[a] = _mm256_loadu_pd(p.add((i0 + a) * len + r + 4));
                }
                for b in 0..TJ {
                    let yl = _mm256_loadu_pd(p.add((j0 + b) * len + r));
                    let yh = _mm256_loadu_pd(p.add((j0 + b) * len + r + 4));
                    for a in 0..TI {
                        lo[a][b] = _mm256_fmadd_pd(xl[a], yl, lo[a][b]);
                        hi[a][b] = _mm256_fmadd_pd(xh[a], yh, hi[a][b]);
                    }
                }
            }
        }
        for a in 0..TI {
            for b in 0..TJ {
                let mut lanes = [0.0f64; LANES];
                // SAFETY: `lanes` holds 8 f64, the two halves 4 each.
                unsafe {
                    _mm256_storeu_pd(lanes.as_mut_ptr(), lo[a][b]);
                    _mm256_storeu_pd(lanes.as_mut_ptr().add(4), hi[a][b]);
                }
                let (i, j) = (i0 + a, j0 + b);
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

    fn random(len: usize, n: usize, rng: &mut SplitMix64) -> Vec<f64> {
        (0..len * n).map(|_| rng.range(-1.0, 1.0) * 3.0).collect()
    }

    /// The plain triple loop, in order, without fused multiply-adds.
    fn naive(block: &[f64], len: usize) -> Vec<f64> {
        let n = block.len() / len;
        let mut y = vec![0.0; n * n];
        for j in 0..n {
            for i in j..n {
                let mut s = 0.0;
                for r in 0..len {
                    s += block[i * len + r] * block[j * len + r];
                }
                y[j * n + i] = s;
            }
        }
        y
    }

    #[test]
    fn matches_a_plain_triple_loop_and_the_portable_bits() {
        let mut rng = SplitMix64::new(11);
        // Odd sizes exercise the edge tiles and the tails.
        for (len, n) in [
            (1, 1),
            (7, 3),
            (8, 4),
            (37, 5),
            (512, 13),
            (300, 24),
            (1000, 9),
        ] {
            let block = random(len, n, &mut rng);
            let want = naive(&block, len);
            let mut got = vec![0.0; n * n];
            syrk_lower_add(&block, len, &mut got);
            let mut portable = vec![0.0; n * n];
            tiles_portable(&block, len, &mut portable);
            // Bit for bit whatever the path the CPU takes.
            assert_eq!(got, portable, "{len} x {n}");
            for j in 0..n {
                for i in 0..n {
                    let (g, w) = (got[j * n + i], want[j * n + i]);
                    if i < j {
                        assert_eq!(g, 0.0, "upper triangle untouched");
                        continue;
                    }
                    // Both sums of `len` products of magnitude at most 9:
                    // each within len * eps * sum |products| of the exact value.
                    let bound: f64 = (0..len)
                        .map(|r| (block[i * len + r] * block[j * len + r]).abs())
                        .sum::<f64>()
                        * 2.0
                        * len as f64
                        * f64::EPSILON;
                    assert!((g - w).abs() <= bound, "{len} x {n} ({i}, {j}): {g} vs {w}");
                }
            }
            // Accumulates: a second call doubles the sums exactly.
            syrk_lower_add(&block, len, &mut got);
            assert_eq!(got, portable.iter().map(|v| v * 2.0).collect::<Vec<_>>());
        }
    }

    #[test]
    fn empty_block_adds_nothing() {
        let mut acc: Vec<f64> = Vec::new();
        syrk_lower_add(&[], 4, &mut acc);
        assert!(acc.is_empty());
    }
}
