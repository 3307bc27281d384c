//! The kernels of the incremental cost on small dense symmetric matrices
//! stored column-major: matrix-vector products, quadratic forms and the
//! symmetric rank-two update.
//!
//! A product `A x` is computed as `N` inner products of the columns of `A`
//! with `x` (for symmetric `A`, column `r` is row `r`), each in four fixed
//! lanes of fused multiply-adds with a fixed reduction and the tail in
//! order. The AVX2+FMA path (chosen at run time) holds one register of
//! lanes per column and takes eight columns at a time, so each element of
//! `x` is loaded once for eight columns and the short sums (N is about 100)
//! keep enough independent additions in flight; it performs the same
//! operations in the same order as the portable path (`f64::mul_add`), so
//! both give the same bits. (On x86 without FMA the portable `mul_add` is a
//! library call, much slower; the fused products are more accurate, so the
//! search's incremental cost drifts less and refactorises less often.) A quadratic form `x^T A x` reads only the
//! block lower triangle, about half the arithmetic. The rank-two update is
//! element by element without fusing, the same bits on every path, and exactly
//! symmetric: `a_rc` and `a_cr` get the same products.

/// `out[r] = A[.., r] . x` for the `n x n` column-major `A` (`n = x.len()`).
pub fn symv(a: &[f64], x: &[f64], out: &mut [f64]) {
    let n = x.len();
    let (a, out) = (&a[..n * n], &mut out[..n]);
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        return unsafe { symv_avx2(a, x, out) };
    }
    symv_body(a, x, out)
}

/// The quadratic form `x^T A x` of the symmetric `n x n` column-major `A`
/// (`n = x.len()`) from its block lower triangle, about half the arithmetic
/// of `x . (A x)`; `scratch` (`n` values) is overwritten.
///
/// The columns go in groups of eight, `G = [c0, g)`: for `c` in `G`,
/// `d_c = x[G] . A[G, c]` (the diagonal block) and `b_c = x[g..] . A[g.., c]`
/// (below it), each in the lanes of [`symv`]; the form is `x . s` with
/// `s_c = d_c + 2 b_c`.
pub fn quadform(a: &[f64], x: &[f64], scratch: &mut [f64]) -> f64 {
    let n = x.len();
    let (a, s) = (&a[..n * n], &mut scratch[..n]);
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        return unsafe { quadform_avx2(a, x, s) };
    }
    quadform_body(a, x, s)
}

const GROUP: usize = 8;

fn quadform_body(a: &[f64], x: &[f64], s: &mut [f64]) -> f64 {
    let n = x.len();
    for (c, sc) in s.iter_mut().enumerate() {
        let c0 = c / GROUP * GROUP;
        let g = (c0 + GROUP).min(n);
        let d = dot4(&x[c0..g], &a[c * n + c0..c * n + g]);
        let b = dot4(&x[g..], &a[c * n + g..(c + 1) * n]);
        *sc = d + 2.0 * b;
    }
    dot4(x, s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn quadform_avx2(a: &[f64], x: &[f64], s: &mut [f64]) -> f64 {
    let n = x.len();
    let full = n / GROUP * GROUP;
    for c0 in (0..full).step_by(GROUP) {
        let g = c0 + GROUP;
        let (mut d, mut b) = ([[0.0]; GROUP], [[0.0]; GROUP]);
        dots_avx2(a, (n, c0, c0), [&x[c0..g]], &mut d);
        dots_avx2(a, (n, c0, g), [&x[g..]], &mut b);
        for ((sc, d), b) in s[c0..g].iter_mut().zip(d).zip(b) {
            *sc = d[0] + 2.0 * b[0];
        }
    }
    for (c, sc) in s.iter_mut().enumerate().skip(full) {
        let mut d = [[0.0]];
        dots_avx2(a, (n, c, full), [&x[full..]], &mut d);
        *sc = d[0][0] + 2.0 * 0.0;
    }
    let mut r = [[0.0]];
    dots_avx2(s, (n, 0, 0), [x], &mut r);
    r[0][0]
}

/// [`symv`] of two vectors in one pass over `A`, the same bits as two
/// calls: where `A` does not fit in the core's cache (N above about 350 on
/// a 2 MB L2), reading it is the product's cost.
///
/// Sequential: a product takes 10 to 100 us, and handing half of one to
/// another thread (rayon's `join`) made a 400-material search spend a
/// third of its time waking threads, more under load.
pub fn symv2(a: &[f64], x: [&[f64]; 2], out: [&mut [f64]; 2]) {
    let n = x[0].len();
    assert_eq!(x[1].len(), n);
    let a = &a[..n * n];
    let [o0, o1] = out;
    let (o0, o1) = (&mut o0[..n], &mut o1[..n]);
    symv2_all(a, x, [o0, o1]);
}

/// [`quadform`] of two vectors in one pass over `A`, the same bits as two
/// calls; `scratch` (`n` values each) is overwritten.
pub fn quadform2(a: &[f64], x: [&[f64]; 2], scratch: [&mut [f64]; 2]) -> [f64; 2] {
    let n = x[0].len();
    assert_eq!(x[1].len(), n);
    let a = &a[..n * n];
    let [s0, s1] = scratch;
    let (s0, s1) = (&mut s0[..n], &mut s1[..n]);
    quadform2_all(a, x, [s0, s1]);
    [dot_fused(x[0], s0), dot_fused(x[1], s1)]
}

/// [`dot4`] through the AVX2+FMA kernel where the CPU has it (outside a
/// function compiled for FMA, `mul_add` is a library call).
fn dot_fused(x: &[f64], y: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2_fma() {
        let mut r = [[0.0]];
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        unsafe { dots_avx2(y, (y.len(), 0, 0), [x], &mut r) };
        return r[0][0];
    }
    dot4(x, y)
}

/// Columns a pass of the two-vector kernels takes: four columns of two
/// vectors keep eight accumulators, three loads and no spills in AVX2's
/// sixteen registers.
const PAIR_COLUMNS: usize = 4;

/// `out[v][c] = A[.., c] . x[v]`.
fn symv2_all(a: &[f64], x: [&[f64]; 2], out: [&mut [f64]; 2]) {
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        return unsafe { symv2_all_avx2(a, x, out) };
    }
    let n = x[0].len();
    for (v, out) in out.into_iter().enumerate() {
        for (k, o) in out.iter_mut().enumerate() {
            *o = dot4(x[v], &a[k * n..]);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn symv2_all_avx2(a: &[f64], x: [&[f64]; 2], out: [&mut [f64]; 2]) {
    const C: usize = PAIR_COLUMNS;
    let n = x[0].len();
    let [o0, o1] = out;
    let count = o0.len();
    let full = count / C * C;
    for k0 in (0..full).step_by(C) {
        let mut r = [[0.0; 2]; C];
        dots_avx2(a, (n, k0, 0), x, &mut r);
        for (k, r) in r.into_iter().enumerate() {
            (o0[k0 + k], o1[k0 + k]) = (r[0], r[1]);
        }
    }
    for k in full..count {
        let mut r = [[0.0; 2]];
        dots_avx2(a, (n, k, 0), x, &mut r);
        (o0[k], o1[k]) = (r[0][0], r[0][1]);
    }
}

/// [`quadform`]'s `s_c` for every column, of both vectors.
fn quadform2_all(a: &[f64], x: [&[f64]; 2], s: [&mut [f64]; 2]) {
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        return unsafe { quadform2_all_avx2(a, x, s) };
    }
    let n = x[0].len();
    for (v, s) in s.into_iter().enumerate() {
        for (c, sc) in s.iter_mut().enumerate() {
            let g0 = c / GROUP * GROUP;
            let g = (g0 + GROUP).min(n);
            let d = dot4(&x[v][g0..g], &a[c * n + g0..c * n + g]);
            let b = dot4(&x[v][g..], &a[c * n + g..(c + 1) * n]);
            *sc = d + 2.0 * b;
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn quadform2_all_avx2(a: &[f64], x: [&[f64]; 2], s: [&mut [f64]; 2]) {
    const C: usize = PAIR_COLUMNS;
    let n = x[0].len();
    let [s0, s1] = s;
    // Whole groups of eight columns, as [`quadform`] takes them.
    let full = n / GROUP * GROUP;
    for g0 in (0..full).step_by(GROUP) {
        let g = g0 + GROUP;
        // The group's columns four at a time, against the same rows as
        // [`quadform`]'s eight.
        for h in (g0..g).step_by(C) {
            let (mut d, mut b) = ([[0.0; 2]; C], [[0.0; 2]; C]);
            dots_avx2(a, (n, h, g0), [&x[0][g0..g], &x[1][g0..g]], &mut d);
            dots_avx2(a, (n, h, g), [&x[0][g..], &x[1][g..]], &mut b);
            for (k, (d, b)) in d.into_iter().zip(b).enumerate() {
                s0[h + k] = d[0] + 2.0 * b[0];
                s1[h + k] = d[1] + 2.0 * b[1];
            }
        }
    }
    for c in full..n {
        let mut d = [[0.0; 2]];
        dots_avx2(a, (n, c, full), [&x[0][full..], &x[1][full..]], &mut d);
        s0[c] = d[0][0] + 2.0 * 0.0;
        s1[c] = d[0][1] + 2.0 * 0.0;
    }
}

/// `A += s2 s2^T - s1 s1^T` for the `n x n` column-major `A`
/// (`n = s1.len()`): `a_rc = (a_rc + s2_r s2_c) - s1_r s1_c`, so a
/// symmetric `A` stays exactly symmetric.
pub fn rank2_update(a: &mut [f64], s1: &[f64], s2: &[f64]) {
    let n = s1.len();
    let (a, s2) = (&mut a[..n * n], &s2[..n]);
    #[cfg(target_arch = "x86_64")]
    if super::has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { rank2_update_avx2(a, s1, s2) };
    }
    rank2_update_body(a, s1, s2)
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

/// `x . col[..x.len()]` in four fixed lanes of fused multiply-adds
/// (element `k` goes to lane `k % 4`), reduced as `(l0 + l1) + (l2 + l3)`,
/// then the tail in order.
#[inline(always)]
fn dot4(x: &[f64], col: &[f64]) -> f64 {
    let col = &col[..x.len()];
    let split = x.len() / 4 * 4;
    let mut acc = [0.0f64; 4];
    for (a, b) in x[..split].chunks_exact(4).zip(col[..split].chunks_exact(4)) {
        for k in 0..4 {
            acc[k] = a[k].mul_add(b[k], acc[k]);
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (a, b) in x[split..].iter().zip(&col[split..]) {
        s = a.mul_add(*b, s);
    }
    s
}

/// [`dot4`] of `C` consecutive column segments of `a` with `V` vectors of
/// `n = xs[v].len()` values, in AVX2 registers with FMA: segment `c` is
/// `a[(c0 + c) stride + r0..][..n]` and `out[c][v]` its product with
/// `xs[v]`, the same operations in the same order as [`dot4`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn dots_avx2<const C: usize, const V: usize>(
    a: &[f64],
    (stride, c0, r0): (usize, usize, usize),
    xs: [&[f64]; V],
    out: &mut [[f64; V]; C],
) {
    use std::arch::x86_64::*;
    let n = xs[0].len();
    for x in xs {
        assert_eq!(x.len(), n);
    }
    assert!(r0 + n <= stride && (c0 + C) * stride <= a.len());
    let a = &a[c0 * stride + r0..];
    let split = n / 4 * 4;
    let mut acc = [[_mm256_setzero_pd(); V]; C];
    for k in (0..split).step_by(4) {
        // SAFETY: k + 4 <= n, each vector holds n values and each segment
        // c * stride + [0, n) lies inside `a` (asserted above).
        unsafe {
            let mut xv = [_mm256_setzero_pd(); V];
            for v in 0..V {
                xv[v] = _mm256_loadu_pd(xs[v].as_ptr().add(k));
            }
            for (c, acc) in acc.iter_mut().enumerate() {
                let av = _mm256_loadu_pd(a.as_ptr().add(c * stride + k));
                for (acc, x) in acc.iter_mut().zip(&xv) {
                    *acc = _mm256_fmadd_pd(*x, av, *acc);
                }
            }
        }
    }
    // (l0 + l1) + (l2 + l3) of four columns at once: the horizontal sums
    // give [a0 + a1, b0 + b1, a2 + a3, b2 + b3] and the same for c, d.
    let mut sums = [[0.0f64; V]; C];
    for v in 0..V {
        let mut c = 0;
        while c + 4 <= C {
            let mut r = [0.0f64; 4];
            // SAFETY: AVX2 by this function's contract; `r` holds 4 f64.
            unsafe {
                let ab = _mm256_hadd_pd(acc[c][v], acc[c + 1][v]);
                let cd = _mm256_hadd_pd(acc[c + 2][v], acc[c + 3][v]);
                let lo = _mm256_permute2f128_pd::<0x20>(ab, cd);
                let hi = _mm256_permute2f128_pd::<0x31>(ab, cd);
                _mm256_storeu_pd(r.as_mut_ptr(), _mm256_add_pd(lo, hi));
            }
            for (k, r) in r.into_iter().enumerate() {
                sums[c + k][v] = r;
            }
            c += 4;
        }
        for (acc, sum) in acc[c..].iter().zip(&mut sums[c..]) {
            let mut l = [0.0f64; 4];
            // SAFETY: `l` holds 4 f64.
            unsafe { _mm256_storeu_pd(l.as_mut_ptr(), acc[v]) };
            sum[v] = (l[0] + l[1]) + (l[2] + l[3]);
        }
    }
    for (c, (out, sums)) in out.iter_mut().zip(sums).enumerate() {
        for (v, (o, mut s)) in out.iter_mut().zip(sums).enumerate() {
            for (x, a) in xs[v][split..]
                .iter()
                .zip(&a[c * stride + split..c * stride + n])
            {
                s = x.mul_add(*a, s);
            }
            *o = s;
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn symv_avx2(a: &[f64], x: &[f64], out: &mut [f64]) {
    const C: usize = 8;
    let n = x.len();
    let full = n / C * C;
    for c0 in (0..full).step_by(C) {
        let mut r = [[0.0]; C];
        dots_avx2(a, (n, c0, 0), [x], &mut r);
        for (o, r) in out[c0..c0 + C].iter_mut().zip(r) {
            *o = r[0];
        }
    }
    for (c, o) in out.iter_mut().enumerate().skip(full) {
        let mut r = [[0.0]];
        dots_avx2(a, (n, c, 0), [x], &mut r);
        *o = r[0][0];
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
        for n in [1usize, 3, 4, 5, 8, 9, 12, 13, 64, 100, 101, 403] {
            let a = symmetric(n, &mut rng);
            let x: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
            let y: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
            let (mut o1, mut o2, mut p1, mut p2) =
                (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            symv(&a, &x, &mut o1);
            symv_body(&a, &x, &mut p1);
            assert_eq!(o1, p1, "n {n}");
            symv(&a, &y, &mut o2);
            symv_body(&a, &y, &mut p2);
            assert_eq!(o2, p2, "n {n}");
            for r in 0..n {
                let plain: f64 = (0..n).map(|c| a[c * n + r] * x[c]).sum();
                assert!((p1[r] - plain).abs() <= 1e-14 * n as f64, "n {n} row {r}");
            }

            let mut s = vec![0.0; n];
            let q = quadform(&a, &x, &mut s);
            assert_eq!(
                q.to_bits(),
                quadform_body(&a, &x, &mut s).to_bits(),
                "n {n}"
            );
            let plain: f64 = (0..n)
                .flat_map(|r| (0..n).map(move |c| (r, c)))
                .map(|(r, c)| x[r] * a[c * n + r] * x[c])
                .sum();
            assert!(
                (q - plain).abs() <= 1e-14 * (n * n) as f64,
                "n {n}: {q} vs {plain}"
            );

            let (mut q0, mut q1) = (vec![0.0; n], vec![0.0; n]);
            symv2(&a, [&x, &y], [&mut q0, &mut q1]);
            assert_eq!((&q0, &q1), (&p1, &p2), "n {n}");
            let (mut t0, mut t1) = (vec![0.0; n], vec![0.0; n]);
            let pair = quadform2(&a, [&x, &y], [&mut t0, &mut t1]);
            let one = [quadform(&a, &x, &mut s), quadform(&a, &y, &mut s)];
            assert_eq!(pair.map(f64::to_bits), one.map(f64::to_bits), "n {n}");

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
