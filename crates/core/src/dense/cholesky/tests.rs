use super::*;
use brdf_merl::synth::SplitMix64;
use faer::Side;
use faer::linalg::solvers::{DenseSolveCore, Solve};

/// An RBF kernel matrix of random points, with noise: the kind the fit
/// factorises, condition number up to about `n / noise`.
fn kernel(n: usize, noise: f64, rng: &mut SplitMix64) -> Mat<f64> {
    let x: Vec<[f64; 2]> = (0..n)
        .map(|_| [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)])
        .collect();
    Mat::from_fn(n, n, |i, j| {
        let d2 = (x[i][0] - x[j][0]).powi(2) + (x[i][1] - x[j][1]).powi(2);
        (-d2 / 2.0).exp() + if i == j { noise } else { 0.0 }
    })
}

fn column_major(k: &Mat<f64>) -> Vec<f64> {
    let n = k.nrows();
    (0..n * n).map(|t| k[(t % n, t / n)]).collect()
}

/// The factor, solves, inverse and log-determinant against faer's, and
/// `L L^T` against `K`.
fn check_against_faer(n: usize, noise: f64, rng: &mut SplitMix64) {
    let k = kernel(n, noise, rng);
    let c = Cholesky::factor(k.as_ref()).unwrap();
    let reference = k.llt(Side::Lower).unwrap();
    let rl = reference.L();
    // The factor itself: within eps * 8n of L's scale.
    let tol = f64::EPSILON * 8.0 * n as f64;
    for i in 0..n {
        for j in 0..n {
            let want = if j <= i { rl[(i, j)] } else { 0.0 };
            assert!((c.l(i, j) - want).abs() <= tol * 1e3, "L[{i}][{j}] n = {n}");
        }
    }
    // L L^T reproduces K to rounding.
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..=j).map(|t| c.l(i, t) * c.l(j, t)).sum();
            assert!((s - k[(i, j)]).abs() <= tol * 2.0, "({i}, {j}) n = {n}");
        }
    }
    let want_ld: f64 = 2.0 * (0..n).map(|i| rl[(i, i)].ln()).sum::<f64>();
    assert!((c.log_det() - want_ld).abs() <= 1e-10 * want_ld.abs().max(1.0));
    // Solves and inverse: residuals relative to cond(K) ~ n / noise.
    let b = Mat::from_fn(n, 3, |_, _| rng.range(-1.0, 1.0));
    let x = c.solve(b.as_ref());
    let resid = (&k * &x - &b).norm_max();
    assert!(
        resid <= 1e-9 * (n as f64).max(1.0),
        "solve residual {resid:e}, n = {n}"
    );
    let xr = reference.solve(&b);
    assert!((&x - &xr).norm_max() <= 1e-8 * n as f64 * xr.norm_max().max(1.0));
    let inv = c.inverse();
    let want = reference.inverse();
    let err = (&inv - &want).norm_max() / want.norm_max();
    assert!(err <= 1e-9 * n as f64, "inverse {err:e}, n = {n}");
    for i in 0..n {
        for j in 0..n {
            assert_eq!(inv[(i, j)], inv[(j, i)]);
        }
    }
    // The same through the slice entry points, with a reused factor.
    let mut again = Cholesky::with_size(n);
    again.factor_into(&column_major(&k)).unwrap();
    let (mut out, mut scratch) = (vec![0.0; n * n], Vec::new());
    again.inverse_into(&mut out, &mut scratch);
    assert_eq!(out, column_major(&inv), "n = {n}");
}

#[test]
fn factor_solve_inverse_and_log_det_agree_with_faer() {
    let mut rng = SplitMix64::new(5);
    for (n, noise) in [(1, 1e-4), (2, 1e-4), (7, 1e-2), (33, 1e-4), (100, 1e-4)] {
        check_against_faer(n, noise, &mut rng);
    }
}

#[test]
fn blocked_sizes_agree_with_faer() {
    // Around the groups of 8 and the blocks of 64.
    let mut rng = SplitMix64::new(9);
    for n in [1, 31, 64, 65, 129, 400] {
        check_against_faer(n, 1e-4, &mut rng);
    }
}

/// The obvious triple loops in the documented order (row-major `n x n`):
/// `L`, or the first failing pivot.
fn chain_factor(k: &Mat<f64>) -> Result<Vec<f64>, usize> {
    let n = k.nrows();
    let mut l = vec![0.0f64; n * n];
    for j in 0..n {
        for i in j..n {
            let mut a = k[(i, j)];
            for t in 0..j {
                a = (-l[i * n + t]).mul_add(l[j * n + t], a);
            }
            if i == j {
                if !(a > 0.0 && a.is_finite()) {
                    return Err(j);
                }
                l[j * n + j] = a.sqrt();
            } else {
                l[i * n + j] = a * (1.0 / l[j * n + j]);
            }
        }
    }
    Ok(l)
}

/// `M = L^-1` by the same loops (row-major).
fn chain_inverse(l: &[f64], n: usize) -> Vec<f64> {
    let mut m = vec![0.0; n * n];
    for j in 0..n {
        m[j * n + j] = 1.0 / l[j * n + j];
        for i in j + 1..n {
            let mut a = 0.0f64;
            for t in j..i {
                a = (-l[i * n + t]).mul_add(m[t * n + j], a);
            }
            m[i * n + j] = a * (1.0 / l[i * n + i]);
        }
    }
    m
}

#[test]
fn every_path_gives_the_bits_of_the_plain_loops() {
    let mut rng = SplitMix64::new(13);
    for n in [1, 7, 8, 9, 63, 64, 65, 72, 129, 200] {
        let k = kernel(n, 1e-4, &mut rng);
        let want_l = chain_factor(&k).unwrap();
        let want_m = chain_inverse(&want_l, n);
        let kc = column_major(&k);
        let mut first: Option<Vec<f64>> = None;
        for path in Path::available() {
            let mut c = Cholesky::with_size(n);
            c.factor_on(&kc, path).unwrap();
            for i in 0..n {
                for j in 0..=i {
                    assert_eq!(
                        c.l(i, j).to_bits(),
                        want_l[i * n + j].to_bits(),
                        "L[{i}][{j}], n = {n}, {path:?}"
                    );
                }
            }
            let (mut out, mut scratch) = (vec![0.0; n * n], Vec::new());
            c.inverse_on(&mut out, &mut scratch, path);
            // The scratch starts with W = L^-T: M[i][j] at i ld + j.
            for j in 0..n {
                for i in 0..n {
                    let want = if i >= j { want_m[i * n + j] } else { 0.0 };
                    assert_eq!(
                        scratch[i * c.ld + j].to_bits(),
                        want.to_bits(),
                        "M[{i}][{j}], n = {n}, {path:?}"
                    );
                }
            }
            // K^-1 = M^T M by the same chains, from k = max(i, j).
            for j in 0..n {
                for i in j..n {
                    let mut s = 0.0f64;
                    for t in i..n {
                        s = want_m[t * n + i].mul_add(want_m[t * n + j], s);
                    }
                    assert_eq!(
                        out[j * n + i].to_bits(),
                        s.to_bits(),
                        "K^-1[{i}][{j}], n = {n}, {path:?}"
                    );
                }
            }
            match &first {
                None => first = Some(out),
                Some(f) => assert_eq!(*f, out, "K^-1, n = {n}, {path:?}"),
            }
        }
    }
}

#[test]
fn reports_the_first_non_positive_pivot() {
    // Positive definite up to index 2; row 3 repeats row 2.
    let rows = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 1.0],
        [0.0, 0.0, 1.0, 1.0],
    ];
    let k = Mat::from_fn(4, 4, |i, j| rows[i][j]);
    assert_eq!(
        Cholesky::factor(k.as_ref()).unwrap_err(),
        NotPositive { index: 3 }
    );
    let nan = Mat::from_fn(2, 2, |i, j| if i == j { f64::NAN } else { 0.0 });
    assert_eq!(
        Cholesky::factor(nan.as_ref()).unwrap_err(),
        NotPositive { index: 0 }
    );
    let negative = Mat::from_fn(3, 3, |i, j| if i == j { 1.0 - i as f64 } else { 0.0 });
    assert_eq!(
        Cholesky::factor(negative.as_ref()).unwrap_err(),
        NotPositive { index: 1 }
    );
}

#[test]
fn the_first_failing_pivot_survives_blocking() {
    let mut rng = SplitMix64::new(21);
    let n = 150;
    let good = kernel(n, 0.5, &mut rng);
    // Row and column 70 repeat 69 (so the leading 71 x 71 block is
    // singular), with the diagonal 1e-3 less, so pivot 70 is clearly
    // negative rather than a rounding error either side of zero, in a
    // matrix otherwise well conditioned. Negative at 70. A NaN below the
    // diagonal at (100, 3) poisons row 100 and so pivot 100.
    let singular = Mat::from_fn(n, n, |i, j| {
        let f = |t: usize| if t == 70 { 69 } else { t };
        good[(f(i), f(j))] - if i == 70 && j == 70 { 1e-3 } else { 0.0 }
    });
    let mut negative = good.clone();
    negative[(70, 70)] = -1.0;
    let mut nan = good.clone();
    nan[(100, 3)] = f64::NAN;
    for (k, want) in [(&singular, 70), (&negative, 70), (&nan, 100)] {
        assert_eq!(chain_factor(k).unwrap_err(), want);
        for path in Path::available() {
            let mut c = Cholesky::with_size(n);
            let got = c.factor_on(&column_major(k), path);
            assert_eq!(got, Err(NotPositive { index: want }), "{path:?}");
        }
        assert_eq!(
            Cholesky::factor(k.as_ref()).unwrap_err(),
            NotPositive { index: want }
        );
    }
    // A failed factorisation leaves the buffer ready for the next.
    let mut c = Cholesky::with_size(n);
    assert!(c.factor_into(&column_major(&negative)).is_err());
    c.factor_into(&column_major(&good)).unwrap();
    let fresh = Cholesky::factor(good.as_ref()).unwrap();
    for i in 0..n {
        for j in 0..=i {
            assert_eq!(c.l(i, j).to_bits(), fresh.l(i, j).to_bits());
        }
    }
}
