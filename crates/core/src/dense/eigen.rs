//! Eigen-decomposition of a small symmetric matrix by cyclic Jacobi
//! rotations.
//!
//! Sweeps over every pair `(p, q)` in a fixed order, each rotation chosen
//! to zero `A[p][q]` (the smaller of the two angles), until no
//! off-diagonal entry is larger than `eps` times the geometric mean of its
//! two diagonal entries (or exactly zero). Accurate to a few ulp of the
//! largest eigenvalue, and to high relative accuracy for positive definite
//! matrices; `O(N^3)` per sweep, a handful of sweeps. Sequential and in a
//! fixed order: the same bits on every thread count.

use faer::{Mat, MatRef};

/// Sweeps before giving up (convergence is quadratic; 10 is typical).
const MAX_SWEEPS: usize = 60;

/// Eigenvalues in ascending order and the eigenvectors as columns, in the
/// same order; `None` when the matrix holds a value that is not finite, or
/// the sweeps do not converge. Reads the lower triangle of `a`.
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
    let mut v = vec![0.0f64; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    let mut converged = n < 2;
    for _ in 0..MAX_SWEEPS {
        if converged {
            break;
        }
        converged = true;
        for p in 0..n {
            for q in p + 1..n {
                let apq = m[q * n + p];
                if apq == 0.0 {
                    continue;
                }
                let (app, aqq) = (m[p * n + p], m[q * n + q]);
                if apq.abs() <= f64::EPSILON * (app.abs() * aqq.abs()).sqrt() {
                    m[q * n + p] = 0.0;
                    m[p * n + q] = 0.0;
                    continue;
                }
                converged = false;
                rotate(&mut m, &mut v, n, p, q);
            }
        }
    }
    if !converged {
        return None;
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| m[x * n + x].total_cmp(&m[y * n + y]).then(x.cmp(&y)));
    let values = order.iter().map(|&k| m[k * n + k]).collect();
    let vectors = Mat::from_fn(n, n, |i, c| v[order[c] * n + i]);
    Some((values, vectors))
}

/// One Jacobi rotation in the plane `(p, q)`: `A <- J^T A J`, `V <- V J`
/// with `J` the identity but `J[p][p] = J[q][q] = c`, `J[p][q] = s =
/// -J[q][p]`, and `A[p][q]` becomes zero.
fn rotate(m: &mut [f64], v: &mut [f64], n: usize, p: usize, q: usize) {
    let (app, aqq, apq) = (m[p * n + p], m[q * n + q], m[q * n + p]);
    let theta = (aqq - app) / (2.0 * apq);
    // t = tan(phi), the root of t^2 + 2 theta t - 1 = 0 of smaller size.
    let t = if theta.is_finite() {
        theta.signum() / (theta.abs() + theta.hypot(1.0))
    } else {
        // |theta| overflowed: the rotation is tiny, t ~ 1 / (2 theta).
        0.5 / theta
    };
    let c = 1.0 / t.hypot(1.0);
    let s = t * c;
    // Columns p and q (then mirrored into rows p and q).
    for k in 0..n {
        if k == p || k == q {
            continue;
        }
        let (akp, akq) = (m[p * n + k], m[q * n + k]);
        let (np, nq) = (c * akp - s * akq, s * akp + c * akq);
        m[p * n + k] = np;
        m[q * n + k] = nq;
        m[k * n + p] = np;
        m[k * n + q] = nq;
    }
    m[p * n + p] = app - t * apq;
    m[q * n + q] = aqq + t * apq;
    m[q * n + p] = 0.0;
    m[p * n + q] = 0.0;
    // p < q by the sweep's order: column p lies before column q.
    let (lo, hi) = v.split_at_mut(q * n);
    let (vp, vq) = (&mut lo[p * n..(p + 1) * n], &mut hi[..n]);
    for (a, b) in vp.iter_mut().zip(vq.iter_mut()) {
        let (x, y) = (*a, *b);
        *a = c * x - s * y;
        *b = s * x + c * y;
    }
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
