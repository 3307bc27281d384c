//! The one inner product of reconstruction: `w . z` for a row of the store.
//!
//! Every reconstruction path (a point query, a batch, a whole table, the
//! map) reduces to `mean + w . z_row` with `w` the N blend weights in f64
//! and `z_row` one contiguous row of the bin-major store, f32 or f64. The
//! sum runs in eight fixed lanes (element `k` goes to lane `k % 8`), then a
//! fixed pairwise reduction, then the tail in order; no fused multiply-add.
//! So the result is the same bits whether the loop compiles to SSE2 or to
//! AVX2 (chosen at run time, [`rows`]), and a point query equals the same
//! bin of a full table.

/// Store element types: f32 and f64, widened to f64 for the sum.
pub trait Element: Copy + Into<f64> + Send + Sync {
    /// Four consecutive elements widened to f64.
    ///
    /// # Safety
    /// The CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    unsafe fn load4(v: &[Self; 4]) -> std::arch::x86_64::__m256d;
}

impl Element for f32 {
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn load4(v: &[f32; 4]) -> std::arch::x86_64::__m256d {
        use std::arch::x86_64::*;
        // SAFETY: `v` is 4 readable f32; AVX2 by the caller's contract.
        unsafe { _mm256_cvtps_pd(_mm_loadu_ps(v.as_ptr())) }
    }
}

impl Element for f64 {
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn load4(v: &[f64; 4]) -> std::arch::x86_64::__m256d {
        use std::arch::x86_64::*;
        // SAFETY: `v` is 4 readable f64; AVX2 by the caller's contract.
        unsafe { _mm256_loadu_pd(v.as_ptr()) }
    }
}

const LANES: usize = 8;

/// `w . z[..w.len()]` in f64 (portable build; see the module notes).
#[inline(always)]
fn dot_body<T: Element>(w: &[f64], z: &[T]) -> f64 {
    let z = &z[..w.len()];
    let split = w.len() / LANES * LANES;
    let (wc, wr) = w.split_at(split);
    let (zc, zr) = z.split_at(split);
    let mut acc = [0.0f64; LANES];
    for (a, b) in wc.chunks_exact(LANES).zip(zc.chunks_exact(LANES)) {
        for k in 0..LANES {
            acc[k] += a[k] * b[k].into();
        }
    }
    let mut s = ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]));
    for (a, b) in wr.iter().zip(zr) {
        s += a * (*b).into();
    }
    s
}

#[inline(always)]
fn rows_body<T: Element>(w: &[f64], z: &[T], mean: &[f64], out: &mut [f64]) {
    let n = w.len();
    for ((o, m), row) in out.iter_mut().zip(mean).zip(z.chunks_exact(n)) {
        *o = m + dot_body(w, row);
    }
}

/// [`dot_body`] in AVX2 registers: lanes 0-3 in one, 4-7 in the other;
/// the same operations in the same order, so the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn dot_avx2<T: Element>(w: &[f64], z: &[T]) -> f64 {
    use std::arch::x86_64::*;
    let z = &z[..w.len()];
    let split = w.len() / LANES * LANES;
    let (wc, wr) = w.split_at(split);
    let (zc, zr) = z.split_at(split);
    let (mut lo, mut hi) = (_mm256_setzero_pd(), _mm256_setzero_pd());
    for (a, b) in wc.chunks_exact(LANES).zip(zc.chunks_exact(LANES)) {
        let (a0, a1) = a.split_at(4);
        let (b0, b1) = b.split_at(4);
        // SAFETY: each half is exactly 4 elements; AVX2 by the caller.
        unsafe {
            let a0 = _mm256_loadu_pd(a0.as_ptr());
            let a1 = _mm256_loadu_pd(a1.as_ptr());
            let b0 = T::load4(b0.try_into().unwrap_unchecked());
            let b1 = T::load4(b1.try_into().unwrap_unchecked());
            lo = _mm256_add_pd(lo, _mm256_mul_pd(a0, b0));
            hi = _mm256_add_pd(hi, _mm256_mul_pd(a1, b1));
        }
    }
    // [a0 + a4, a1 + a5, a2 + a6, a3 + a7], then (s0 + s1) + (s2 + s3).
    let mut pair = [0.0f64; 4];
    // SAFETY: `pair` holds 4 f64.
    unsafe { _mm256_storeu_pd(pair.as_mut_ptr(), _mm256_add_pd(lo, hi)) };
    let mut s = (pair[0] + pair[1]) + (pair[2] + pair[3]);
    for (a, b) in wr.iter().zip(zr) {
        s += a * (*b).into();
    }
    s
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn rows_avx2<T: Element>(w: &[f64], z: &[T], mean: &[f64], out: &mut [f64]) {
    let n = w.len();
    for ((o, m), row) in out.iter_mut().zip(mean).zip(z.chunks_exact(n)) {
        // SAFETY: AVX2 by the caller's contract.
        *o = m + unsafe { dot_avx2(w, row) };
    }
}

/// [`dot_avx2`] of two weight vectors against one row, which is loaded
/// once: each sum in the same operations and order as its own call.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn dot2_avx2<T: Element>(w: &[f64], v: &[f64], z: &[T]) -> (f64, f64) {
    use std::arch::x86_64::*;
    let n = w.len();
    let (z, v) = (&z[..n], &v[..n]);
    let split = n / LANES * LANES;
    let (mut wlo, mut whi) = (_mm256_setzero_pd(), _mm256_setzero_pd());
    let (mut vlo, mut vhi) = (_mm256_setzero_pd(), _mm256_setzero_pd());
    for k in (0..split).step_by(LANES) {
        // SAFETY: k + 8 <= split <= n, the length of all three; AVX2 by
        // the caller.
        unsafe {
            let b0 = T::load4(z[k..k + 4].try_into().unwrap_unchecked());
            let b1 = T::load4(z[k + 4..k + 8].try_into().unwrap_unchecked());
            let a0 = _mm256_loadu_pd(w[k..].as_ptr());
            let a1 = _mm256_loadu_pd(w[k + 4..].as_ptr());
            let c0 = _mm256_loadu_pd(v[k..].as_ptr());
            let c1 = _mm256_loadu_pd(v[k + 4..].as_ptr());
            wlo = _mm256_add_pd(wlo, _mm256_mul_pd(a0, b0));
            whi = _mm256_add_pd(whi, _mm256_mul_pd(a1, b1));
            vlo = _mm256_add_pd(vlo, _mm256_mul_pd(c0, b0));
            vhi = _mm256_add_pd(vhi, _mm256_mul_pd(c1, b1));
        }
    }
    let reduce = |lo: __m256d, hi: __m256d| {
        let mut pair = [0.0f64; 4];
        // SAFETY: `pair` holds 4 f64; AVX2 by the caller.
        unsafe { _mm256_storeu_pd(pair.as_mut_ptr(), _mm256_add_pd(lo, hi)) };
        (pair[0] + pair[1]) + (pair[2] + pair[3])
    };
    let (mut sw, mut sv) = (reduce(wlo, whi), reduce(vlo, vhi));
    for k in split..n {
        let b: f64 = z[k].into();
        sw += w[k] * b;
        sv += v[k] * b;
    }
    (sw, sv)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn rows2_avx2<T: Element>(
    w: &[f64],
    v: &[f64],
    z: &[T],
    mean: &[f64],
    out_w: &mut [f64],
    out_v: &mut [f64],
) {
    let n = w.len();
    for (((ow, ov), m), row) in out_w.iter_mut().zip(out_v).zip(mean).zip(z.chunks_exact(n)) {
        // SAFETY: AVX2 by the caller's contract.
        let (sw, sv) = unsafe { dot2_avx2(w, v, row) };
        (*ow, *ov) = (m + sw, m + sv);
    }
}

/// [`rows`] of two weight vectors over the same rows, reading each row
/// once: `out_w[j] = mean[j] + w . z_j` and `out_v[j] = mean[j] + v . z_j`,
/// the same bits as two calls of [`rows`]. `v` is as long as `w`.
pub fn rows2<T: Element>(
    w: &[f64],
    v: &[f64],
    z: &[T],
    mean: &[f64],
    out_w: &mut [f64],
    out_v: &mut [f64],
) {
    let (n, len) = (w.len(), out_w.len().min(out_v.len()));
    let (z, mean, v) = (&z[..len * n], &mean[..len], &v[..n]);
    let (out_w, out_v) = (&mut out_w[..len], &mut out_v[..len]);
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { rows2_avx2(w, v, z, mean, out_w, out_v) };
    }
    for (((ow, ov), m), row) in out_w.iter_mut().zip(out_v).zip(mean).zip(z.chunks_exact(n)) {
        (*ow, *ov) = (m + dot_body(w, row), m + dot_body(v, row));
    }
}

/// `w . z[..w.len()]`, f64 accumulation.
#[inline]
pub fn dot<T: Element>(w: &[f64], z: &[T]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { dot_avx2(w, z) };
    }
    dot_body(w, z)
}

/// `out[j] = mean[j] + w . z[j n .. (j + 1) n]` for `j < out.len()`, with
/// `n = w.len()`; the same bits as [`dot`] row by row.
pub fn rows<T: Element>(w: &[f64], z: &[T], mean: &[f64], out: &mut [f64]) {
    let (n, len) = (w.len(), out.len());
    let (z, mean) = (&z[..len * n], &mean[..len]);
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { rows_avx2(w, z, mean, out) };
    }
    rows_body(w, z, mean, out)
}

#[inline(always)]
fn axpy_body<T: Element>(a: f64, z: &[T], acc: &mut [f64]) {
    for (o, v) in acc.iter_mut().zip(z) {
        *o += a * (*v).into();
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn axpy_avx2<T: Element>(a: f64, z: &[T], acc: &mut [f64]) {
    axpy_body(a, z, acc)
}

/// `acc[i] += a * z[i]` for `i < acc.len()` (element by element, so the
/// same bits on every path).
#[inline]
pub fn axpy<T: Element>(a: f64, z: &[T], acc: &mut [f64]) {
    let z = &z[..acc.len()];
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { axpy_avx2(a, z, acc) };
    }
    axpy_body(a, z, acc)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_weights_in_one_pass_give_the_bits_of_two_passes() {
        for n in [1usize, 7, 8, 9, 100, 257] {
            let w: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 3.0).collect();
            let v: Vec<f64> = (0..n).map(|i| ((i * 13 % 7) as f64 - 2.5) / 7.0).collect();
            let rows_n = 5;
            let z32: Vec<f32> = (0..rows_n * n).map(|i| (i as f32 * 0.37).sin()).collect();
            let z64: Vec<f64> = z32.iter().map(|&x| f64::from(x) * 1.1).collect();
            let mean: Vec<f64> = (0..rows_n).map(|i| i as f64 * 0.25 - 0.5).collect();
            let (mut a, mut b) = (vec![0.0; rows_n], vec![0.0; rows_n]);
            let (mut ow, mut ov) = (vec![0.0; rows_n], vec![0.0; rows_n]);
            rows(&w, &z32, &mean, &mut a);
            rows(&v, &z32, &mean, &mut b);
            rows2(&w, &v, &z32, &mean, &mut ow, &mut ov);
            assert_eq!(a, ow, "f32, n {n}");
            assert_eq!(b, ov, "f32, n {n}");
            rows(&w, &z64, &mean, &mut a);
            rows(&v, &z64, &mean, &mut b);
            rows2(&w, &v, &z64, &mean, &mut ow, &mut ov);
            assert_eq!(a, ow, "f64, n {n}");
            assert_eq!(b, ov, "f64, n {n}");
            // The portable loop too.
            for (j, row) in z64.chunks_exact(n).enumerate() {
                assert_eq!(ow[j], mean[j] + dot_body(&w, row));
                assert_eq!(ov[j], mean[j] + dot_body(&v, row));
            }
        }
    }

    #[test]
    fn dot_matches_a_plain_sum_and_rows_match_dot() {
        for n in [1usize, 7, 8, 9, 100, 257] {
            let w: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 3.0).collect();
            let z: Vec<f32> = (0..3 * n).map(|i| (i as f32 * 0.37).sin()).collect();
            let plain: f64 = w.iter().zip(&z).map(|(a, b)| a * *b as f64).sum();
            let fast = dot(&w, &z);
            assert!(
                (fast - plain).abs() <= 1e-14 * n as f64,
                "n {n}: {fast} vs {plain}"
            );
            assert_eq!(fast.to_bits(), dot_body(&w, &z).to_bits());

            let mut acc = vec![1.0; n];
            axpy(0.25, &z, &mut acc);
            for (i, a) in acc.iter().enumerate() {
                assert_eq!(*a, 1.0 + 0.25 * z[i] as f64);
            }

            let mean = [0.5, -1.0, 2.0];
            let mut out = [0.0; 3];
            rows(&w, &z, &mean, &mut out);
            for (j, o) in out.iter().enumerate() {
                assert_eq!(o.to_bits(), (mean[j] + dot(&w, &z[j * n..])).to_bits());
            }
        }
    }
}
