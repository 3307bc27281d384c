//! A general matrix product `C = A B` (all column-major) for the
//! leave-one-out pass and the log-transform map.
//!
//! Each output is `sum_k A[r][k] B[k][c]` accumulated in `k` order with
//! fused multiply-adds, starting from zero. The AVX-512 path computes tiles
//! of 16 rows x 4 columns in registers, the AVX2 path (and AVX-512's last
//! rows) tiles of 8 rows x 4 columns (two loads of `A` and four broadcasts
//! of `B` per eight or sixteen fused multiply-adds), and the last rows
//! (fewer than 8, all of them for a few latent points) blocks of 8 columns
//! from a transposed copy of `B`; the edges and the portable path
//! (`f64::mul_add`) do the same operations per output, so the bits do not
//! depend on the CPU.

/// Columns of `c` per parallel task (a multiple of the tile's 4, so a
/// column is a tile's or an edge's whatever the split).
const COLUMNS: usize = 32;

/// Products of at least this many multiply-adds are split between threads.
const PARALLEL_MACS: usize = 1 << 21;

/// `c = a b` with `a` `m x k`, `b` `k x p` and `c` `m x p`, column-major
/// slices; `m = a.len() / k` and `p = b.len() / k`.
///
/// Large products are split by blocks of columns between threads; every
/// output is the same chain of operations either way, so the bits do not
/// depend on the thread count.
///
/// # Panics
/// When the lengths do not fit those shapes (a caller bug, never input).
pub fn matmul(c: &mut [f64], a: &[f64], b: &[f64], k: usize) {
    if k == 0 {
        c.iter_mut().for_each(|v| *v = 0.0);
        return;
    }
    assert!(a.len().is_multiple_of(k) && b.len().is_multiple_of(k));
    let (m, p) = (a.len() / k, b.len() / k);
    assert_eq!(c.len(), m * p);
    if m * k * p >= PARALLEL_MACS && p >= 2 * COLUMNS && m > 0 {
        use rayon::prelude::*;
        c.par_chunks_mut(COLUMNS * m)
            .zip(b.par_chunks(COLUMNS * k))
            .for_each(|(c, b)| columns(c, a, b, k));
    } else {
        columns(c, a, b, k);
    }
}

/// [`matmul`] on one thread (`k > 0`, shapes checked).
fn columns(c: &mut [f64], a: &[f64], b: &[f64], k: usize) {
    let (m, p) = (a.len() / k, b.len() / k);
    #[cfg(target_arch = "x86_64")]
    if crate::simd::has_avx2_fma() {
        let (m8, p4) = (m / 8 * 8, p / 4 * 4);
        // Rows in tiles of 16 where the CPU has AVX-512, the rest (and all
        // of them elsewhere) in tiles of 8.
        let m16 = if crate::simd::has_avx512f() {
            // SAFETY: the CPU has AVX-512F (checked just above).
            unsafe { tiles_avx512(c, a, b, (m, k, p)) };
            m / 16 * 16
        } else {
            0
        };
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        unsafe { tiles_avx2(c, a, b, (m, k, p), m16) };
        // The last rows (fewer than 8: all of them for a few points) in
        // blocks of 8 columns. SAFETY: as above.
        let p8 = if m8 < m {
            unsafe { narrow_avx2(c, a, b, (m, k, p), m8) }
        } else {
            p4
        };
        // The edges with the FMA instruction (`mul_add` is a libm call in a
        // build without it). SAFETY: as above.
        unsafe { edges_fma(c, a, b, (m, k, p), (m8, p8.min(p4), p4)) };
        return;
    }
    // Without the vector paths no tile covers anything: every output is an edge.
    edges(c, a, b, (m, k, p), (0, 0, 0));
}

/// The outputs no tile covers, one at a time: the last rows (from `m8`)
/// of columns `from..p4`, then every row of the last columns (from `p4`).
#[inline(always)]
fn edges(
    c: &mut [f64],
    a: &[f64],
    b: &[f64],
    (m, k, p): (usize, usize, usize),
    (m8, from, p4): (usize, usize, usize),
) {
    for col in from..p4 {
        for r in m8..m {
            c[col * m + r] = one(a, b, (m, k), r, col);
        }
    }
    for col in p4..p {
        for r in 0..m {
            c[col * m + r] = one(a, b, (m, k), r, col);
        }
    }
}

/// [`edges`] compiled with FMA: the same chains, the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn edges_fma(
    c: &mut [f64],
    a: &[f64],
    b: &[f64],
    shape: (usize, usize, usize),
    split: (usize, usize, usize),
) {
    edges(c, a, b, shape, split);
}

/// Rows `m8..m` (fewer than 8) of the first `p / 8 * 8` columns, in
/// blocks of 8 columns and groups of up to 4 rows; gives back the columns
/// covered. Each block of `B` is transposed once into a `k x 8` buffer, so
/// an output's chain (fused multiply-adds in `k` order from zero) is the
/// same as everywhere else while 8 of them advance per instruction pair.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn narrow_avx2(
    c: &mut [f64],
    a: &[f64],
    b: &[f64],
    (m, k, p): (usize, usize, usize),
    m8: usize,
) -> usize {
    let p8 = p / 8 * 8;
    assert!(a.len() == m * k && b.len() == k * p && c.len() == m * p && m8 <= m);
    let mut bt = vec![0.0f64; 8 * k];
    for c0 in (0..p8).step_by(8) {
        for j in 0..8 {
            for (t, &v) in b[(c0 + j) * k..(c0 + j + 1) * k].iter().enumerate() {
                bt[8 * t + j] = v;
            }
        }
        let mut r = m8;
        while r < m {
            let rows = (m - r).min(4);
            match rows {
                4 => narrow_group::<4>(c, a, &bt, (m, k), r, c0),
                3 => narrow_group::<3>(c, a, &bt, (m, k), r, c0),
                2 => narrow_group::<2>(c, a, &bt, (m, k), r, c0),
                _ => narrow_group::<1>(c, a, &bt, (m, k), r, c0),
            }
            r += rows;
        }
    }
    p8
}

/// `R` rows from `r0` of the 8 columns from `c0`, from the transposed
/// block `bt` (`k x 8`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn narrow_group<const R: usize>(
    c: &mut [f64],
    a: &[f64],
    bt: &[f64],
    (m, k): (usize, usize),
    r0: usize,
    c0: usize,
) {
    use std::arch::x86_64::*;
    assert!(r0 + R <= m && a.len() == m * k && bt.len() == 8 * k && c.len() >= (c0 + 8) * m);
    let (ap, bp) = (a.as_ptr(), bt.as_ptr());
    let mut lo = [_mm256_setzero_pd(); R];
    let mut hi = [_mm256_setzero_pd(); R];
    for t in 0..k {
        // SAFETY: t < k and r0 + R <= m, so 8 t + 8 <= bt.len() and
        // t m + r0 + i < a.len(), asserted above.
        unsafe {
            let y0 = _mm256_loadu_pd(bp.add(8 * t));
            let y1 = _mm256_loadu_pd(bp.add(8 * t + 4));
            for i in 0..R {
                let x = _mm256_broadcast_sd(&*ap.add(t * m + r0 + i));
                lo[i] = _mm256_fmadd_pd(x, y0, lo[i]);
                hi[i] = _mm256_fmadd_pd(x, y1, hi[i]);
            }
        }
    }
    let mut out = [0.0f64; 8];
    for i in 0..R {
        // SAFETY: `out` holds 8 values.
        unsafe {
            _mm256_storeu_pd(out.as_mut_ptr(), lo[i]);
            _mm256_storeu_pd(out.as_mut_ptr().add(4), hi[i]);
        }
        for (j, &v) in out.iter().enumerate() {
            c[(c0 + j) * m + r0 + i] = v;
        }
    }
}

/// One output the portable way.
#[inline(always)]
fn one(a: &[f64], b: &[f64], (m, k): (usize, usize), r: usize, col: usize) -> f64 {
    let mut s = 0.0f64;
    for (t, bt) in b[col * k..(col + 1) * k].iter().enumerate() {
        s = a[t * m + r].mul_add(*bt, s);
    }
    s
}

/// Tiles of 16 rows x 4 columns: two loads of `A` and four broadcasts of
/// `B` per sixteen fused multiply-adds (twice the AVX2 tile's work for the
/// same instructions), each output the same chain as everywhere else. Each
/// panel of 16 rows of `A` is copied once into a contiguous buffer (`k x
/// 16`) and kept hot while every block of columns of `B` passes it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn tiles_avx512(c: &mut [f64], a: &[f64], b: &[f64], (m, k, p): (usize, usize, usize)) {
    use std::arch::x86_64::*;
    let (m16, p4) = (m / 16 * 16, p / 4 * 4);
    assert!(a.len() == m * k && b.len() == k * p && c.len() == m * p);
    let mut panel = vec![0.0f64; 16 * k];
    let (pp, bp, cp) = (panel.as_mut_ptr(), b.as_ptr(), c.as_mut_ptr());
    for r0 in (0..m16).step_by(16) {
        for t in 0..k {
            panel[16 * t..16 * t + 16].copy_from_slice(&a[t * m + r0..t * m + r0 + 16]);
        }
        for c0 in (0..p4).step_by(4) {
            // SAFETY (all loads and stores): the panel holds 16 k values,
            // r0 + 16 <= m, c0 + 4 <= p and t < k, so every index lies
            // inside the panel, `b` (k x p) and `c` (m x p), asserted above.
            unsafe {
                let mut lo = [_mm512_setzero_pd(); 4];
                let mut hi = [_mm512_setzero_pd(); 4];
                for t in 0..k {
                    let x0 = _mm512_loadu_pd(pp.add(16 * t));
                    let x1 = _mm512_loadu_pd(pp.add(16 * t + 8));
                    for j in 0..4 {
                        let y = _mm512_set1_pd(*bp.add((c0 + j) * k + t));
                        lo[j] = _mm512_fmadd_pd(x0, y, lo[j]);
                        hi[j] = _mm512_fmadd_pd(x1, y, hi[j]);
                    }
                }
                for j in 0..4 {
                    _mm512_storeu_pd(cp.add((c0 + j) * m + r0), lo[j]);
                    _mm512_storeu_pd(cp.add((c0 + j) * m + r0 + 8), hi[j]);
                }
            }
        }
    }
}

/// Tiles of 8 rows x 4 columns, rows `from..` (a multiple of 8) only.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn tiles_avx2(c: &mut [f64], a: &[f64], b: &[f64], (m, k, p): (usize, usize, usize), from: usize) {
    use std::arch::x86_64::*;
    let (m8, p4) = (m / 8 * 8, p / 4 * 4);
    assert!(a.len() == m * k && b.len() == k * p && c.len() == m * p && from.is_multiple_of(8));
    let (ap, bp, cp) = (a.as_ptr(), b.as_ptr(), c.as_mut_ptr());
    for c0 in (0..p4).step_by(4) {
        for r0 in (from..m8).step_by(8) {
            // SAFETY (all loads and stores): r0 + 8 <= m, c0 + 4 <= p and
            // t < k, so every index lies inside `a` (m x k), `b` (k x p)
            // and `c` (m x p), asserted above.
            unsafe {
                let mut lo = [_mm256_setzero_pd(); 4];
                let mut hi = [_mm256_setzero_pd(); 4];
                for t in 0..k {
                    let x0 = _mm256_loadu_pd(ap.add(t * m + r0));
                    let x1 = _mm256_loadu_pd(ap.add(t * m + r0 + 4));
                    for j in 0..4 {
                        let y = _mm256_broadcast_sd(&*bp.add((c0 + j) * k + t));
                        lo[j] = _mm256_fmadd_pd(x0, y, lo[j]);
                        hi[j] = _mm256_fmadd_pd(x1, y, hi[j]);
                    }
                }
                for j in 0..4 {
                    _mm256_storeu_pd(cp.add((c0 + j) * m + r0), lo[j]);
                    _mm256_storeu_pd(cp.add((c0 + j) * m + r0 + 4), hi[j]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_merl::synth::SplitMix64;

    #[test]
    fn matches_a_plain_product_and_the_portable_bits() {
        let mut rng = SplitMix64::new(17);
        for (m, k, p) in [
            (1, 1, 1),
            (8, 3, 4),
            // Fewer than 8 rows: blocks of 8 columns, groups of 4, 3, 2, 1
            // rows, and the columns after the last block.
            (1, 16, 19),
            (2, 5, 8),
            (3, 16, 35),
            (4, 16, 64),
            (7, 9, 17),
            (15, 16, 27),
            (13, 7, 9),
            (300, 100, 37),
            // Split between threads: several blocks of columns and an edge.
            (64, 300, 203),
            (5, 0, 3),
            (0, 4, 2),
        ] {
            let a: Vec<f64> = (0..m * k).map(|_| rng.range(-1.0, 1.0)).collect();
            let b: Vec<f64> = (0..k * p).map(|_| rng.range(-1.0, 1.0)).collect();
            let mut got = vec![f64::NAN; m * p];
            matmul(&mut got, &a, &b, k);
            for col in 0..p {
                for r in 0..m {
                    // Plain sum in the same order, without fusing: each
                    // product's rounding at most eps * |a b| per step.
                    let (mut s, mut bound) = (0.0, 0.0);
                    for t in 0..k {
                        s += a[t * m + r] * b[col * k + t];
                        bound += (a[t * m + r] * b[col * k + t]).abs();
                    }
                    let g = got[col * m + r];
                    assert!((g - s).abs() <= 2.0 * k as f64 * f64::EPSILON * bound);
                    // The portable path's bits.
                    if k > 0 {
                        assert_eq!(g, one(&a, &b, (m, k), r, col));
                    } else {
                        assert_eq!(g, 0.0);
                    }
                }
            }
        }
    }
}
