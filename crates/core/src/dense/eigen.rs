//! Eigen-decomposition of a symmetric matrix: faer's (Householder
//! reduction to tridiagonal form, then implicit QR steps below 128 rows and
//! divide and conquer from 128), sequential (`Par::Seq`) on a thread of its own,
//! so the result does not depend on the thread count. faer picks its SIMD
//! path (and fused multiply-adds) for the CPU at run time, so the last bits
//! may differ from one CPU to another.
//!
//! On top of faer's result this module checks the input and the output for
//! values that are not finite and fixes each eigenvector's sign.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{Mat, MatRef, Par};

/// Eigenvalues in ascending order and the eigenvectors as columns, in the
/// same order, each with its largest-magnitude entry positive (the last
/// such entry on a tie); `None` when the matrix holds a value that is not
/// finite, the iteration does not converge or its scratch cannot be
/// allocated. Reads the lower triangle of the leading square block of `a`.
pub fn symmetric_eigen(a: MatRef<'_, f64>) -> Option<(Vec<f64>, Mat<f64>)> {
    // faer's products keep a scratch buffer in each thread that runs one,
    // of twice the L3 cache the CPU reports (960 MB where 480 MiB is
    // reported), reserved and mostly untouched, for the thread's life. On
    // a thread of its own it is given back on return, so that neither a
    // host program's threads nor a thread pool's keep it.
    std::thread::scope(|scope| {
        match std::thread::Builder::new()
            .name("eigen".into())
            .spawn_scoped(scope, || decompose(a))
        {
            Ok(worker) => worker.join().ok().flatten(),
            Err(_) => decompose(a),
        }
    })
}

/// [`symmetric_eigen`] on the calling thread.
fn decompose(a: MatRef<'_, f64>) -> Option<(Vec<f64>, Mat<f64>)> {
    let n = a.nrows().min(a.ncols());
    let a = a.submatrix(0, 0, n, n);
    if !(0..n).all(|j| (j..n).all(|i| a[(i, j)].is_finite())) {
        return None;
    }
    if n == 0 {
        return Some((Vec::new(), Mat::zeros(0, 0)));
    }
    let (mut s, mut u) = (Diag::<f64>::zeros(n), Mat::<f64>::zeros(n, n));
    let scratch = evd::self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::Yes,
        Par::Seq,
        Default::default(),
    );
    let mut mem = MemBuffer::try_new(scratch).ok()?;
    evd::self_adjoint_evd(
        a,
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .ok()?;
    let values: Vec<f64> = s.column_vector().iter().copied().collect();
    let finite = values.iter().all(|v| v.is_finite())
        && (0..n).all(|j| u.col(j).iter().all(|v| v.is_finite()));
    if !finite {
        return None;
    }
    // faer returns them in nondecreasing order; sort (stably) in case.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| values[x].total_cmp(&values[y]));
    let values = order.iter().map(|&k| values[k]).collect();
    let vectors = Mat::from_fn(n, n, |i, c| u[(i, order[c])]);
    Some((values, canonical_signs(vectors)))
}

/// Each column negated if need be so its largest-magnitude entry (the last
/// one, on a tie) is positive.
fn canonical_signs(mut v: Mat<f64>) -> Mat<f64> {
    for c in 0..v.ncols() {
        let col = v.col(c);
        let pivot = (0..col.nrows())
            .max_by(|&a, &b| col[a].abs().total_cmp(&col[b].abs()))
            .unwrap_or(0);
        if col.nrows() > 0 && col[pivot] < 0.0 {
            v.col_mut(c).iter_mut().for_each(|x| *x = -*x);
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_merl::synth::SplitMix64;

    /// Cyclic Jacobi rotations on a full copy of `a` until the off-diagonal
    /// part is negligible: the eigenvalues ascending and the eigenvectors
    /// (columns), independent of faer's algorithm.
    fn jacobi(a: &Mat<f64>) -> (Vec<f64>, Mat<f64>) {
        let n = a.nrows();
        // On the matrix scaled to a largest entry of 1, so the sums of
        // squares below neither overflow nor underflow.
        let scale = a.norm_max();
        let scale = if scale > 0.0 { scale } else { 1.0 };
        let mut m = Mat::from_fn(n, n, |i, j| {
            (if i >= j { a[(i, j)] } else { a[(j, i)] }) / scale
        });
        let mut v = Mat::<f64>::identity(n, n);
        for _sweep in 0..100 {
            let off: f64 = (0..n)
                .flat_map(|j| (0..n).filter(move |&i| i != j).map(move |i| (i, j)))
                .map(|(i, j)| m[(i, j)] * m[(i, j)])
                .sum();
            let diag: f64 = (0..n).map(|i| m[(i, i)] * m[(i, i)]).sum();
            if off <= (f64::EPSILON * f64::EPSILON) * diag || off == 0.0 {
                break;
            }
            for p in 0..n {
                for q in p + 1..n {
                    let apq = m[(p, q)];
                    if apq == 0.0 {
                        continue;
                    }
                    let theta = (m[(q, q)] - m[(p, p)]) / (2.0 * apq);
                    let t = theta.signum() / (theta.abs() + theta.hypot(1.0));
                    let t = if theta == 0.0 { 1.0 } else { t };
                    let c = 1.0 / (t * t + 1.0).sqrt();
                    let s = t * c;
                    for k in 0..n {
                        let (mkp, mkq) = (m[(k, p)], m[(k, q)]);
                        m[(k, p)] = c * mkp - s * mkq;
                        m[(k, q)] = s * mkp + c * mkq;
                    }
                    for k in 0..n {
                        let (mpk, mqk) = (m[(p, k)], m[(q, k)]);
                        m[(p, k)] = c * mpk - s * mqk;
                        m[(q, k)] = s * mpk + c * mqk;
                    }
                    for k in 0..n {
                        let (vkp, vkq) = (v[(k, p)], v[(k, q)]);
                        v[(k, p)] = c * vkp - s * vkq;
                        v[(k, q)] = s * vkp + c * vkq;
                    }
                }
            }
        }
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&x, &y| m[(x, x)].total_cmp(&m[(y, y)]));
        let vals = order.iter().map(|&k| m[(k, k)] * scale).collect();
        (vals, Mat::from_fn(n, n, |i, c| v[(i, order[c])]))
    }

    /// `A V = V S`, `V^T V = I`, ascending order and canonical signs, to a
    /// tolerance of rounding of the largest eigenvalue; the eigenvalues
    /// against Jacobi's and, where an eigenvalue is well separated from the
    /// others, its eigenvector too.
    fn check(a: &Mat<f64>) -> (Vec<f64>, Mat<f64>) {
        let n = a.nrows();
        let (vals, vecs) = symmetric_eigen(a.as_ref()).unwrap();
        assert_eq!((vals.len(), vecs.nrows(), vecs.ncols()), (n, n, n));
        let scale = a.norm_max();
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
                assert!((vtv[(i, j)] - want).abs() <= tol, "n = {n}: V^T V");
            }
        }
        assert!(vals.windows(2).all(|w| w[0] <= w[1]));
        for c in 0..n {
            let col = vecs.col(c);
            let max = col.iter().map(|x| x.abs()).fold(0.0, f64::max);
            let last = (0..n).rev().find(|&i| col[i].abs() == max).unwrap();
            assert!(col[last] > 0.0, "n = {n}: sign of column {c}");
        }
        let (want, w) = jacobi(a);
        for (g, r) in vals.iter().zip(&want) {
            assert!((g - r).abs() <= tol * scale, "n = {n}: {g:e} vs {r:e}");
        }
        for c in 0..n {
            let gap = (0..n)
                .filter(|&k| k != c)
                .map(|k| (want[k] - want[c]).abs())
                .fold(f64::INFINITY, f64::min);
            if gap > 1e-6 * scale {
                let cos: f64 = (0..n).map(|i| vecs[(i, c)] * w[(i, c)]).sum();
                let err = 1.0 - cos.abs();
                assert!(err <= 1e3 * tol * scale / gap, "n = {n}: vector {c}");
            }
        }
        (vals, vecs)
    }

    fn random_gram(rng: &mut SplitMix64, n: usize, d: usize) -> Mat<f64> {
        let z = Mat::from_fn(n, d, |_, _| rng.range(-1.0, 1.0));
        &z * z.transpose()
    }

    #[test]
    fn decomposes_random_symmetric_and_gram_matrices() {
        let mut rng = SplitMix64::new(9);
        // Full-rank Gram matrices on both sides of faer's switch from QR
        // steps to divide and conquer (128).
        for (n, d) in [(1, 3), (2, 5), (30, 40), (100, 300), (127, 200), (160, 320)] {
            check(&random_gram(&mut rng, n, d));
        }
        // Indefinite.
        for n in [3, 50, 140] {
            let l = Mat::from_fn(n, n, |_, _| rng.range(-1.0, 1.0));
            check(&Mat::from_fn(n, n, |i, j| l[(i.max(j), i.min(j))]));
        }
    }

    #[test]
    fn stays_stable_on_hard_cases() {
        let mut rng = SplitMix64::new(11);
        // Rank-deficient Gram matrices (rank d < n): n - d eigenvalues at
        // zero to rounding.
        for (n, d) in [(5, 2), (64, 8), (150, 10)] {
            let y = random_gram(&mut rng, n, d);
            let (vals, _) = check(&y);
            let top = vals[n - 1];
            assert!(vals[..n - d].iter().all(|s| s.abs() <= 1e-12 * top));
            assert!(vals[n - d] > 1e-6 * top);
        }
        // Repeated eigenvalues: a multiple of the identity, zero, and a
        // matrix with eigenvalue 1 of multiplicity 3 and 4 of multiplicity 2
        // in a random basis.
        let (vals, _) = check(&Mat::from_fn(6, 6, |i, j| if i == j { 2.0 } else { 0.0 }));
        assert!(vals.iter().all(|&s| (s - 2.0).abs() <= 1e-15));
        check(&Mat::<f64>::zeros(4, 4));
        check(&Mat::<f64>::zeros(130, 130));
        let basis = symmetric_eigen(random_gram(&mut rng, 5, 9).as_ref())
            .unwrap()
            .1;
        let d = [1.0, 1.0, 1.0, 4.0, 4.0];
        let a = Mat::from_fn(5, 5, |i, j| {
            (0..5).map(|k| basis[(i, k)] * d[k] * basis[(j, k)]).sum()
        });
        let (vals, _) = check(&a);
        for (g, w) in vals.iter().zip(&d) {
            assert!((g - w).abs() <= 1e-14 * 4.0);
        }
        // Many equal eigenvalues in divide and conquer's range: a rank-one
        // update of the identity.
        let x: Vec<f64> = (0..200).map(|_| rng.range(-1.0, 1.0)).collect();
        check(&Mat::from_fn(200, 200, |i, j| {
            x[i] * x[j] + if i == j { 1.0 } else { 0.0 }
        }));
        check(&Mat::from_fn(
            5,
            5,
            |i, j| if i == j { -(i as f64) } else { 1.0 },
        ));
        // Tiny and huge scales, and both in one matrix.
        for scale in [1e-150, 1e-300, 1e150, 1e300] {
            let y = random_gram(&mut rng, 40, 60);
            let max = y.norm_max();
            check(&Mat::from_fn(40, 40, |i, j| y[(i, j)] / max * scale));
        }
        check(&Mat::from_fn(
            3,
            3,
            |i, j| if i == j { 1e300 } else { 1e-300 },
        ));
        check(&Mat::from_fn(3, 3, |i, j| {
            if i == j { [1e-300, 1.0, 1e300][i] } else { 0.0 }
        }));
    }

    #[test]
    fn the_same_bits_on_one_and_two_threads() {
        let mut rng = SplitMix64::new(5);
        let y = random_gram(&mut rng, 300, 400);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| symmetric_eigen(y.as_ref()).unwrap())
        };
        let (one, two) = (run(1), run(2));
        assert!(
            one.0
                .iter()
                .zip(&two.0)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
        assert!(
            (0..300).all(|j| (0..300).all(|i| one.1[(i, j)].to_bits() == two.1[(i, j)].to_bits()))
        );
    }

    #[test]
    fn refuses_values_that_are_not_finite() {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for n in [3, 200] {
                let a = Mat::from_fn(n, n, |i, j| if (i, j) == (2, 1) { bad } else { 1.0 });
                assert!(symmetric_eigen(a.as_ref()).is_none());
            }
        }
        // The upper triangle is not read.
        let a = Mat::from_fn(3, 3, |i, j| if (i, j) == (1, 2) { f64::NAN } else { 1.0 });
        assert!(symmetric_eigen(a.as_ref()).is_some());
        // Finite entries, an eigenvalue that overflows (4 f64::MAX).
        let a = Mat::from_fn(4, 4, |_, _| f64::MAX);
        assert!(symmetric_eigen(a.as_ref()).is_none());
        assert_eq!(
            symmetric_eigen(Mat::<f64>::zeros(0, 0).as_ref()).unwrap().0,
            Vec::<f64>::new()
        );
    }
}
