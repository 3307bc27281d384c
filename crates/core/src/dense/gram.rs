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
    syrk(block, len, acc, false);
}

/// [`syrk_lower_add`] of a lower-triangular `n x n` matrix's columns
/// (`len == n`, `z_i` zero above row `i`): the same sums, with the groups
/// of eight rows above each tile's first column left out (their products
/// are exact zeros, and each value keeps its lane, so the bits are those
/// of [`syrk_lower_add`]); about half the work.
pub fn syrk_lower_add_triangular(block: &[f64], len: usize, acc: &mut [f64]) {
    syrk(block, len, acc, true);
}

fn syrk(block: &[f64], len: usize, acc: &mut [f64], triangular: bool) {
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
            unsafe { tiles_avx512(block, len, acc, triangular) };
            return;
        }
        if crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX2 and FMA (checked just above).
            unsafe { tiles_avx2(block, len, acc, triangular) };
            return;
        }
    }
    tiles_portable(block, len, acc, triangular);
}

/// The lane sums of one output reduced in the fixed order, then the tail.
#[inline(always)]
fn finish(l: [f64; LANES], zi: &[f64], zj: &[f64], split: usize) -> f64 {
    let s = ((l[0] + l[4]) + (l[1] + l[5])) + ((l[2] + l[6]) + (l[3] + l[7]));
    tail(s, zi, zj, split)
}

/// The values past the last full group of lanes, in order.
#[inline(always)]
fn tail(mut s: f64, zi: &[f64], zj: &[f64], split: usize) -> f64 {
    for (a, b) in zi[split..].iter().zip(&zj[split..]) {
        s = a.mul_add(*b, s);
    }
    s
}

/// One output the portable way (edge tiles of the vector paths too).
#[inline(always)]
fn dot8(zi: &[f64], zj: &[f64], start: usize) -> f64 {
    let split = zi.len() / LANES * LANES;
    let start = (start / LANES * LANES).min(split);
    let mut l = [0.0f64; LANES];
    for (a, b) in zi[start..split]
        .chunks_exact(LANES)
        .zip(zj[start..split].chunks_exact(LANES))
    {
        for k in 0..LANES {
            l[k] = a[k].mul_add(b[k], l[k]);
        }
    }
    finish(l, zi, zj, split)
}

fn tiles_portable(block: &[f64], len: usize, acc: &mut [f64], triangular: bool) {
    let n = block.len() / len;
    for j in 0..n {
        let zj = &block[j * len..(j + 1) * len];
        for i in j..n {
            let start = if triangular { i } else { 0 };
            acc[j * n + i] += dot8(&block[i * len..(i + 1) * len], zj, start);
        }
    }
}

/// Walk the lower triangle in tiles of `TI x TJ` outputs. `tile(rows,
/// cols, sums)` computes the `TI x TJ` sums of the materials `rows` by
/// `cols`; at the matrix's edges the indices past `n - 1` repeat `n - 1`
/// (so every tile is a full one; each material's run lies inside `block`,
/// asserted before `tile` runs), and only the outputs inside the lower
/// triangle are added.
#[inline(always)]
pub(super) fn walk<T, const TI: usize, const TJ: usize>(
    block: &[T],
    len: usize,
    acc: &mut [f64],
    mut tile: impl FnMut([usize; TI], [usize; TJ], &mut [[f64; TJ]; TI]),
) {
    let n = block.len() / len;
    let mut sums = [[0.0f64; TJ]; TI];
    for i0 in (0..n).step_by(TI) {
        let rows = std::array::from_fn(|a| (i0 + a).min(n - 1));
        for j0 in (0..n.min(i0 + TI)).step_by(TJ) {
            let cols = std::array::from_fn(|b| (j0 + b).min(n - 1));
            // The tile kernels load these runs unchecked.
            assert!(
                rows.iter()
                    .chain(&cols)
                    .all(|&m| (m + 1) * len <= block.len())
            );
            tile(rows, cols, &mut sums);
            for (a, row) in sums.iter().enumerate() {
                for (b, s) in row.iter().enumerate() {
                    let (i, j) = (i0 + a, j0 + b);
                    if i < n && j <= i {
                        acc[j * n + i] += s;
                    }
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn tiles_avx512(block: &[f64], len: usize, acc: &mut [f64], triangular: bool) {
    use std::arch::x86_64::*;
    const TI: usize = 4;
    const TJ: usize = 4;
    let split = len / LANES * LANES;
    walk::<f64, TI, TJ>(block, len, acc, |rows, cols, sums| {
        let p = block.as_ptr();
        let mut l = [[_mm512_setzero_pd(); TJ]; TI];
        // Every row of the tile is at least rows[0]: below it, zeros.
        let start = if triangular {
            (rows[0] / LANES * LANES).min(split)
        } else {
            0
        };
        for r in (start..split).step_by(LANES) {
            // SAFETY: r + 8 <= len and the tile's runs lie inside `block`
            // (asserted by `walk`).
            unsafe {
                let x = rows.map(|i| _mm512_loadu_pd(p.add(i * len + r)));
                for (b, j) in cols.iter().enumerate() {
                    let y = _mm512_loadu_pd(p.add(j * len + r));
                    for (la, xa) in l.iter_mut().zip(&x) {
                        la[b] = _mm512_fmadd_pd(*xa, y, la[b]);
                    }
                }
            }
        }
        // The fixed reduction of four outputs at once: the halves' sums
        // [l0 + l4, l1 + l5, l2 + l6, l3 + l7] of each, then the horizontal
        // sums give [a0 + a1, b0 + b1, a2 + a3, b2 + b3] and the same for
        // c, d; the 128-bit halves regrouped and added finish each as
        // (s0 + s1) + (s2 + s3).
        for (a, row) in l.iter().enumerate() {
            let mut r = [0.0f64; TJ];
            // SAFETY: AVX-512F (and so AVX) by this function's contract;
            // `r` holds 4 f64.
            unsafe {
                let h = row.map(|v| {
                    _mm256_add_pd(_mm512_castpd512_pd256(v), _mm512_extractf64x4_pd::<1>(v))
                });
                let ab = _mm256_hadd_pd(h[0], h[1]);
                let cd = _mm256_hadd_pd(h[2], h[3]);
                let lo = _mm256_permute2f128_pd::<0x20>(ab, cd);
                let hi = _mm256_permute2f128_pd::<0x31>(ab, cd);
                _mm256_storeu_pd(r.as_mut_ptr(), _mm256_add_pd(lo, hi));
            }
            for (b, (sum, r)) in sums[a].iter_mut().zip(r).enumerate() {
                *sum = if split < len {
                    let (i, j) = (rows[a], cols[b]);
                    tail(
                        r,
                        &block[i * len..(i + 1) * len],
                        &block[j * len..(j + 1) * len],
                        split,
                    )
                } else {
                    r
                };
            }
        }
    });
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn tiles_avx2(block: &[f64], len: usize, acc: &mut [f64], triangular: bool) {
    use std::arch::x86_64::*;
    const TI: usize = 2;
    const TJ: usize = 3;
    let split = len / LANES * LANES;
    walk::<f64, TI, TJ>(block, len, acc, |rows, cols, sums| {
        let p = block.as_ptr();
        let mut lo = [[_mm256_setzero_pd(); TJ]; TI];
        let mut hi = [[_mm256_setzero_pd(); TJ]; TI];
        // Every row of the tile is at least rows[0]: below it, zeros.
        let start = if triangular {
            (rows[0] / LANES * LANES).min(split)
        } else {
            0
        };
        for r in (start..split).step_by(LANES) {
            // SAFETY: r + 8 <= len and the tile's runs lie inside `block`
            // (asserted by `walk`).
            unsafe {
                let xl = rows.map(|i| _mm256_loadu_pd(p.add(i * len + r)));
                let xh = rows.map(|i| _mm256_loadu_pd(p.add(i * len + r + 4)));
                for (b, j) in cols.iter().enumerate() {
                    let yl = _mm256_loadu_pd(p.add(j * len + r));
                    let yh = _mm256_loadu_pd(p.add(j * len + r + 4));
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
            tiles_portable(&block, len, &mut portable, false);
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
    fn triangular_variant_gives_the_full_bits() {
        let mut rng = SplitMix64::new(23);
        for n in [1, 3, 8, 13, 37, 100] {
            // Columns of a lower-triangular matrix, column-major.
            let m: Vec<f64> = (0..n * n)
                .map(|t| {
                    if t % n >= t / n {
                        rng.range(-1.0, 1.0)
                    } else {
                        0.0
                    }
                })
                .collect();
            let (mut full, mut tri, mut portable) =
                (vec![0.0; n * n], vec![0.0; n * n], vec![0.0; n * n]);
            syrk_lower_add(&m, n, &mut full);
            syrk_lower_add_triangular(&m, n, &mut tri);
            tiles_portable(&m, n, &mut portable, true);
            assert_eq!(full, tri, "n = {n}");
            assert_eq!(full, portable, "n = {n}");
        }
    }

    #[test]
    fn empty_block_adds_nothing() {
        let mut acc: Vec<f64> = Vec::new();
        syrk_lower_add(&[], 4, &mut acc);
        assert!(acc.is_empty());
    }
}
