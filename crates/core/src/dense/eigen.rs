//! Eigen-decomposition of a small symmetric matrix: Householder reduction
//! to tridiagonal form, then implicit QR steps with Wilkinson shifts.
//!
//! The reduction applies `H_k = I - beta v v^T` from both sides for each
//! column, keeping the matrix full (column-major, so every inner loop is a
//! contiguous dot product or AXPY), and forms `Q = H_0 H_1 ...` from the
//! last reflection back. Each QR step chases a bulge down the unreduced
//! block with plane rotations, applied to the columns of the eigenvector
//! matrix; an off-diagonal entry below `eps (|d_i| + |d_i+1|)` is set to
//! zero (deflation). About `9 N^3` flops; sequential, in a fixed order, no
//! fused multiply-adds: the same bits on every CPU and thread count.

use faer::{Mat, MatRef};

use crate::simd::dot::{axpy, dot};

/// QR steps allowed per eigenvalue on average before giving up (two or
/// three are typical).
const MAX_STEPS_PER_VALUE: usize = 30;

/// Eigenvalues in ascending order and the eigenvectors as columns, in the
/// same order; `None` when the matrix holds a value that is not finite, or
/// the iteration does not converge. Reads the lower triangle of `a`.
pub fn symmetric_eigen(a: MatRef<'_, f64>) -> Option<(Vec<f64>, Mat<f64>)> {
    let n = a.nrows().min(a.ncols());
    // Column-major, full (mirrored from the lower triangle).
    let mut m = vec![0.0f64; n * n];
    for j in 0..n {
        for i in j..n {
            let v = a[(i, j)];
            if !v.is_finite() {
                return None;
            }
            m[j * n + i] = v;
            m[i * n + j] = v;
        }
    }
    let (mut d, mut e, mut z) = tridiagonalise(&mut m, n);
    if !d.iter().chain(&e).all(|v| v.is_finite()) {
        return None;
    }
    implicit_qr(&mut d, &mut e, &mut z, n)?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| d[x].total_cmp(&d[y]).then(x.cmp(&y)));
    let values = order.iter().map(|&k| d[k]).collect();
    let vectors = Mat::from_fn(n, n, |i, c| z[order[c] * n + i]);
    Some((values, vectors))
}

/// Reduce the full symmetric `m` (column-major, destroyed) to tridiagonal
/// form: its diagonal, its off-diagonal (`e[i]` couples `i` and `i + 1`)
/// and `Q` (column-major) with `m = Q T Q^T`.
fn tridiagonalise(m: &mut [f64], n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut e = vec![0.0f64; n.saturating_sub(1)];
    // (v, beta) of each reflection, v over rows k + 1..n.
    let mut reflections: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n);
    let (mut p, mut w) = (vec![0.0f64; n], vec![0.0f64; n]);
    for k in 0..n.saturating_sub(2) {
        let len = n - k - 1;
        let x = &m[k * n + k + 1..(k + 1) * n];
        let sigma = dot(x, x).sqrt();
        if sigma == 0.0 {
            reflections.push((Vec::new(), 0.0));
            continue;
        }
        let alpha = if x[0] > 0.0 { -sigma } else { sigma };
        let mut v = x.to_vec();
        v[0] -= alpha;
        let beta = 2.0 / dot(&v, &v);
        e[k] = alpha;
        // p = beta A22 v, A22 = m[k+1.., k+1..] (full, symmetric).
        let (p, w) = (&mut p[..len], &mut w[..len]);
        p.iter_mut().for_each(|x| *x = 0.0);
        for (j, vj) in v.iter().enumerate() {
            let col = (k + 1 + j) * n + k + 1;
            axpy(*vj, &m[col..col + len], p);
        }
        p.iter_mut().for_each(|x| *x *= beta);
        // w = p - (beta / 2) (p . v) v, then A22 -= v w^T + w v^T.
        let half = 0.5 * beta * dot(p, &v);
        for ((wi, pi), vi) in w.iter_mut().zip(p.iter()).zip(&v) {
            *wi = pi - half * vi;
        }
        for j in 0..len {
            let col = (k + 1 + j) * n + k + 1;
            let col = &mut m[col..col + len];
            axpy(-w[j], &v, col);
            axpy(-v[j], w, col);
        }
        reflections.push((v, beta));
    }
    if n >= 2 {
        e[n - 2] = m[(n - 2) * n + n - 1];
    }
    let d = (0..n).map(|i| m[i * n + i]).collect();
    // Q = H_0 (H_1 (... I)): each H_k touches rows and columns k + 1.. only.
    let mut q = vec![0.0f64; n * n];
    for i in 0..n {
        q[i * n + i] = 1.0;
    }
    for (k, (v, beta)) in reflections.iter().enumerate().rev() {
        if v.is_empty() {
            continue;
        }
        for j in k + 1..n {
            let col = &mut q[j * n + k + 1..(j + 1) * n];
            let s = beta * dot(v, col);
            axpy(-s, v, col);
        }
    }
    (d, e, q)
}

/// Diagonalise the tridiagonal `(d, e)`, applying every rotation to the
/// columns of `z` (column-major `n x n`); `None` if it does not converge.
fn implicit_qr(d: &mut [f64], e: &mut [f64], z: &mut [f64], n: usize) -> Option<()> {
    let mut steps = 0usize;
    let mut hi = n.saturating_sub(1);
    while hi > 0 {
        // Deflate: zero the negligible couplings, find the unreduced block
        // [lo, hi] ending lowest.
        for i in 0..hi {
            if e[i].abs() <= f64::EPSILON * (d[i].abs() + d[i + 1].abs()) {
                e[i] = 0.0;
            }
        }
        while hi > 0 && e[hi - 1] == 0.0 {
            hi -= 1;
        }
        if hi == 0 {
            break;
        }
        let mut lo = hi - 1;
        while lo > 0 && e[lo - 1] != 0.0 {
            lo -= 1;
        }
        steps += 1;
        if steps > MAX_STEPS_PER_VALUE * n {
            return None;
        }
        // Wilkinson shift: the eigenvalue of the trailing 2 x 2 nearer d[hi].
        let (a, b, c) = (d[hi - 1], e[hi - 1], d[hi]);
        let t = 0.5 * (a - c);
        let r = t.hypot(b);
        let mu = c - b * b / (t + if t < 0.0 { -r } else { r });
        let mut bulge = 0.0;
        for k in lo..hi {
            let (x, y) = if k == lo {
                (d[lo] - mu, e[lo])
            } else {
                (e[k - 1], bulge)
            };
            let r = x.hypot(y);
            let (cs, sn) = if r == 0.0 { (1.0, 0.0) } else { (x / r, y / r) };
            if k > lo {
                e[k - 1] = r;
            }
            // T <- G^T T G on rows and columns k, k + 1.
            let (a, b, c) = (d[k], e[k], d[k + 1]);
            let (cc, ss, cs2) = (cs * cs, sn * sn, cs * sn);
            d[k] = cc * a + 2.0 * cs2 * b + ss * c;
            d[k + 1] = ss * a - 2.0 * cs2 * b + cc * c;
            e[k] = cs2 * (c - a) + (cc - ss) * b;
            if k + 1 < hi {
                let f = e[k + 1];
                bulge = sn * f;
                e[k + 1] = cs * f;
            }
            let (left, right) = z.split_at_mut((k + 1) * n);
            let (zk, zk1) = (&mut left[k * n..], &mut right[..n]);
            for (p, q) in zk.iter_mut().zip(zk1.iter_mut()) {
                let (u, v) = (*p, *q);
                *p = cs * u + sn * v;
                *q = cs * v - sn * u;
            }
        }
        if !(d[lo..=hi].iter().chain(&e[lo..hi]).all(|v| v.is_finite())) {
            return None;
        }
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_merl::synth::SplitMix64;
    use faer::Side;

    fn check(a: &Mat<f64>) {
        let n = a.nrows();
        let (vals, vecs) = symmetric_eigen(a.as_ref()).unwrap();
        let scale = a.norm_max().max(1e-300);
        // A V = V S and V^T V = I, to rounding of the largest eigenvalue.
        let tol = f64::EPSILON * 64.0 * n as f64;
        let av = a * &vecs;
        for c in 0..n {
            for i in 0..n {
                let e = (av[(i, c)] - vecs[(i, c)] * vals[c]).abs();
                assert!(e <= tol * scale, "n = {n}: residual {e:e}");
            }
        }
        let vtv = vecs.transpose() * &vecs;
        for i in 0..n {
            for j in 0..n {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((vtv[(i, j)] - want).abs() <= tol);
            }
        }
        assert!(vals.windows(2).all(|w| w[0] <= w[1]));
        // Against faer's eigenvalues.
        let reference = a.self_adjoint_eigenvalues(Side::Lower).unwrap();
        for (g, w) in vals.iter().zip(&reference) {
            assert!((g - w).abs() <= tol * scale, "{g} vs {w}");
        }
    }

    #[test]
    fn decomposes_random_gram_and_degenerate_matrices() {
        let mut rng = SplitMix64::new(9);
        for (n, d) in [(1, 3), (2, 5), (5, 2), (30, 40), (100, 300), (64, 8)] {
            // A Gram matrix Z Z^T (rank min(n, d): degenerate when d < n).
            let z = Mat::from_fn(n, d, |_, _| rng.range(-1.0, 1.0));
            check(&(&z * z.transpose()));
        }
        // Repeated eigenvalues, zeros and negatives.
        check(&Mat::from_fn(6, 6, |i, j| if i == j { 2.0 } else { 0.0 }));
        check(&Mat::<f64>::zeros(4, 4));
        check(&Mat::from_fn(
            5,
            5,
            |i, j| if i == j { -(i as f64) } else { 1.0 },
        ));
        check(&Mat::from_fn(
            3,
            3,
            |i, j| if i == j { 1e300 } else { 1e-300 },
        ));
    }

    #[test]
    fn refuses_values_that_are_not_finite() {
        let a = Mat::from_fn(3, 3, |i, j| if (i, j) == (2, 1) { f64::NAN } else { 1.0 });
        assert!(symmetric_eigen(a.as_ref()).is_none());
    }
}
