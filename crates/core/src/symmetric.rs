//! The two O(N^2) kernels of the incremental cost, on small dense symmetric
//! matrices stored column-major: matrix-vector products and the symmetric
//! rank-two update.
//!
//! A product `A x` is computed as `N` inner products of the columns of `A`
//! with `x` (for symmetric `A`, column `r` is row `r`), each in four fixed
//! lanes with a fixed reduction and the tail in order, no fused
//! multiply-add. The AVX2 path (chosen at run time) holds one register of
//! lanes per column and takes eight columns at a time against one vector,
//! or four against two vectors, so each element of `x` is loaded once for
//! several columns and the short sums (N is about 100) keep enough
//! independent additions in flight; it performs the same operations in the
//! same order as the portable path, so both give the same bits. The rank-two update is
//! element by element, the same bits on every path too, and exactly
//! symmetric: `a_rc` and `a_cr` get the same products.

/// `out[r] = A[.., r] . x` for the `n x n` column-major `A` (`n = x.len()`).
pub fn symv(a: &[f64], x: &[f64], out: &mut [f64]) {
    let n = x.len();
    let (a, out) = (&a[..n * n], &mut out[..n]);
    #[cfg(target_arch = "x86_64")]
    if has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { symv_avx2(a, x, out) };
    }
    symv_body(a, x, out)
}

/// [`symv`] of two vectors at once: `out1 = A x1`, `out2 = A x2`, the same
/// bits as two calls.
pub fn symv2(a: &[f64], x1: &[f64], x2: &[f64], out1: &mut [f64], out2: &mut [f64]) {
    let n = x1.len();
    let (a, x2) = (&a[..n * n], &x2[..n]);
    let (out1, out2) = (&mut out1[..n], &mut out2[..n]);
    #[cfg(target_arch = "x86_64")]
    if has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { symv2_avx2(a, x1, x2, out1, out2) };
    }
    symv_body(a, x1, out1);
    symv_body(a, x2, out2);
}

/// `A += s2 s2^T - s1 s1^T` for the `n x n` column-major `A`
/// (`n = s1.len()`): `a_rc = (a_rc + s2_r s2_c) - s1_r s1_c`, so a
/// symmetric `A` stays exactly symmetric.
pub fn rank2_update(a: &mut [f64], s1: &[f64], s2: &[f64]) {
    let n = s1.len();
    let (a, s2) = (&mut a[..n * n], &s2[..n]);
    #[cfg(target_arch = "x86_64")]
    if has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { rank2_update_avx2(a, s1, s2) };
    }
    rank2_update_body(a, s1, s2)
}

#[cfg(target_arch = "x86_64")]
fn has_avx2() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

fn symv_body(a: &[f64], x: &[f64], out: &mut [f64]) {
    for (o, col) in out.iter_mut().zip(a.chunks_exact(x.len())) {
        *o = dot4(x, col);
    }
}

#[inline(always)]
fn rank2_update_body(a: &mut [f64], s1: &[f64], s2: &[f64]) {
    for ((col, &t1), &t2) in a.chunks_exact_mut(s1.len()).zip(s1).zip(s2) {
        for ((v, &r1), &r2) in col.iter_mut().zip(s1).zip(s2) {
            *v = (*v + r2 * t2) - r1 * t1;
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn rank2_update_avx2(a: &mut [f64], s1: &[f64], s2: &[f64]) {
    // Plain element-wise arithmetic: the compiler vectorises it four wide
    // and (Rust never contracts a * b + c) keeps the same roundings.
    rank2_update_body(a, s1, s2)
}

/// `x . col[..x.len()]` in four fixed lanes (element `k` goes to lane
/// `k % 4`), reduced as `(l0 + l1) + (l2 + l3)`, then the tail in order.
#[inline(always)]
fn dot4(x: &[f64], col: &[f64]) -> f64 {
    let col = &col[..x.len()];
    let split = x.len() / 4 * 4;
    let mut acc = [0.0f64; 4];
    for (a, b) in x[..split].chunks_exact(4).zip(col[..split].chunks_exact(4)) {
        for k in 0..4 {
            acc[k] += a[k] * b[k];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (a, b) in x[split..].iter().zip(&col[split..]) {
        s += a * b;
    }
    s
}

/// [`dot4`] of `C` consecutive columns of `a` (from column `c0`, each
/// `n = xs[v].len()` long) with `V` vectors, in AVX2 registers:
/// `out[c][v] = a[c0 + c] . xs[v]`, the same operations in the same order.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn dots_avx2<const C: usize, const V: usize>(
    a: &[f64],
    c0: usize,
    xs: [&[f64]; V],
    out: &mut [[f64; V]; C],
) {
    use std::arch::x86_64::*;
    let n = xs[0].len();
    for x in xs {
        assert_eq!(x.len(), n);
    }
    let a = &a[c0 * n..(c0 + C) * n];
    let split = n / 4 * 4;
    let mut acc = [[_mm256_setzero_pd(); V]; C];
    for k in (0..split).step_by(4) {
        // SAFETY: k + 4 <= n, each vector holds n values and `a` holds C columns of n.
        unsafe {
            let mut xv = [_mm256_setzero_pd(); V];
            for v in 0..V {
                xv[v] = _mm256_loadu_pd(xs[v].as_ptr().add(k));
            }
            for (c, acc) in acc.iter_mut().enumerate() {
                let av = _mm256_loadu_pd(a.as_ptr().add(c * n + k));
                for (acc, x) in acc.iter_mut().zip(&xv) {
                    *acc = _mm256_add_pd(*acc, _mm256_mul_pd(*x, av));
                }
            }
        }
    }
    for c in 0..C {
        for v in 0..V {
            let mut l = [0.0f64; 4];
            // SAFETY: `l` holds 4 f64.
            unsafe { _mm256_storeu_pd(l.as_mut_ptr(), acc[c][v]) };
            let mut s = (l[0] + l[1]) + (l[2] + l[3]);
            for (x, a) in xs[v][split..].iter().zip(&a[c * n + split..(c + 1) * n]) {
                s += x * a;
            }
            out[c][v] = s;
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn symv_avx2(a: &[f64], x: &[f64], out: &mut [f64]) {
    const C: usize = 8;
    let n = x.len();
    let full = n / C * C;
    for c0 in (0..full).step_by(C) {
        let mut r = [[0.0]; C];
        dots_avx2(a, c0, [x], &mut r);
        for (o, r) in out[c0..c0 + C].iter_mut().zip(r) {
            *o = r[0];
        }
    }
    for (c, o) in out.iter_mut().enumerate().skip(full) {
        let mut r = [[0.0]];
        dots_avx2(a, c, [x], &mut r);
        *o = r[0][0];
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn symv2_avx2(a: &[f64], x1: &[f64], x2: &[f64], out1: &mut [f64], out2: &mut [f64]) {
    const C: usize = 4;
    let n = x1.len();
    let full = n / C * C;
    for c0 in (0..full).step_by(C) {
        let mut r = [[0.0; 2]; C];
        dots_avx2(a, c0, [x1, x2], &mut r);
        for (j, r) in r.iter().enumerate() {
            (out1[c0 + j], out2[c0 + j]) = (r[0], r[1]);
        }
    }
    for c in full..n {
        let mut r = [[0.0; 2]];
        dots_avx2(a, c, [x1, x2], &mut r);
        (out1[c], out2[c]) = (r[0][0], r[0][1]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_merl::synth::SplitMix64;

    fn symmetric(n: usize, rng: &mut SplitMix64) -> Vec<f64> {
        let mut a = vec![0.0; n * n];
        for c in 0..n {
            for r in 0..=c {
                let v = rng.range(-2.0, 2.0);
                a[c * n + r] = v;
                a[r * n + c] = v;
            }
        }
        a
    }

    /// The dispatched kernels give the bits of the portable ones, and the
    /// products agree with a plain double loop.
    #[test]
    fn kernels_match_the_portable_path_and_a_plain_product() {
        let mut rng = SplitMix64::new(7);
        for n in [1usize, 3, 4, 5, 8, 9, 13, 64, 100, 101] {
            let a = symmetric(n, &mut rng);
            let x: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
            let y: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
            let (mut o1, mut o2, mut p1, mut p2) =
                (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            symv(&a, &x, &mut o1);
            symv_body(&a, &x, &mut p1);
            assert_eq!(o1, p1, "n {n}");
            symv2(&a, &x, &y, &mut o1, &mut o2);
            symv_body(&a, &y, &mut p2);
            assert_eq!((&o1, &o2), (&p1, &p2), "n {n}");
            for r in 0..n {
                let plain: f64 = (0..n).map(|c| a[c * n + r] * x[c]).sum();
                assert!((p1[r] - plain).abs() <= 1e-14 * n as f64, "n {n} row {r}");
            }

            let (mut u, mut w) = (a.clone(), a.clone());
            rank2_update(&mut u, &x, &y);
            rank2_update_body(&mut w, &x, &y);
            assert_eq!(u, w, "n {n}");
            for c in 0..n {
                for r in 0..n {
                    assert_eq!(u[c * n + r].to_bits(), u[r * n + c].to_bits());
                    let want = a[c * n + r] + y[r] * y[c] - x[r] * x[c];
                    assert!((u[c * n + r] - want).abs() <= 1e-14);
                }
            }
        }
    }
}
