//! Cholesky factorisation `K = L L^T` of a small symmetric positive
//! definite matrix, its log-determinant, solves and inverse.
//!
//! Unblocked and sequential: `K` is `N x N` with `N` the number of
//! materials, factorised a few hundred times per fit. `L` is kept by rows
//! (row `i` holds `L[i][0..=i]`, contiguous), so every inner loop is a
//! contiguous dot product ([`crate::simd::dot::dot`], eight fixed lanes) or
//! an AXPY ([`crate::simd::dot::axpy`], element by element): the same bits
//! on every CPU and thread count.

use faer::{Mat, MatRef};

use super::gram::syrk_lower_add_triangular;
use crate::simd::dot::{axpy, dot};

/// `L` of `K = L L^T`, by rows.
#[derive(Debug, Clone)]
pub struct Cholesky {
    n: usize,
    /// Row `i` at `l[i * n..i * n + i + 1]`; the rest is zero.
    l: Vec<f64>,
}

/// `K` is not numerically positive definite: the first pivot that is not
/// positive (or not finite).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NotPositive {
    /// Index of that pivot.
    pub index: usize,
}

impl Cholesky {
    /// A factor of size `n`, to be filled by [`Cholesky::factor_into`].
    pub fn with_size(n: usize) -> Cholesky {
        Cholesky {
            n,
            l: vec![0.0; n * n],
        }
    }

    /// Factorise `k` (square; its lower triangle is read).
    pub fn factor(k: MatRef<'_, f64>) -> Result<Cholesky, NotPositive> {
        let n = k.nrows().min(k.ncols());
        let mut c = Cholesky::with_size(n);
        c.factor_with(|i, j| k[(i, j)])?;
        Ok(c)
    }

    /// Factorise the `n x n` column-major `k` (its lower triangle is read)
    /// into this factor's buffer.
    ///
    /// # Panics
    /// When `k` is not `n x n` (a caller bug, never input).
    pub fn factor_into(&mut self, k: &[f64]) -> Result<(), NotPositive> {
        let n = self.n;
        assert_eq!(k.len(), n * n);
        self.factor_with(|i, j| k[j * n + i])
    }

    fn factor_with(&mut self, k: impl Fn(usize, usize) -> f64) -> Result<(), NotPositive> {
        let n = self.n;
        self.l.iter_mut().for_each(|v| *v = 0.0);
        for i in 0..n {
            let (done, row) = self.l.split_at_mut(i * n);
            let row = &mut row[..=i];
            for j in 0..i {
                let lj = &done[j * n..j * n + j + 1];
                let s = k(i, j) - dot(&row[..j], &lj[..j]);
                row[j] = s / lj[j];
            }
            let s = k(i, i) - dot(&row[..i], &row[..i]);
            // Not `s <= 0.0`: a NaN pivot fails too.
            if !(s > 0.0 && s.is_finite()) {
                return Err(NotPositive { index: i });
            }
            row[i] = s.sqrt();
        }
        Ok(())
    }

    /// The size `n`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// `L[i][j]` (zero above the diagonal).
    pub fn l(&self, i: usize, j: usize) -> f64 {
        if j > i { 0.0 } else { self.l[i * self.n + j] }
    }

    /// `log|K| = 2 sum log L_ii`.
    pub fn log_det(&self) -> f64 {
        2.0 * (0..self.n)
            .map(|i| self.l[i * self.n + i].ln())
            .sum::<f64>()
    }

    /// `b <- K^-1 b` for one right-hand side of `n` values.
    ///
    /// # Panics
    /// When `b` does not have `n` values (a caller bug).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.n;
        assert_eq!(b.len(), n);
        // L y = b, row by row.
        for i in 0..n {
            let row = &self.l[i * n..i * n + i + 1];
            b[i] = (b[i] - dot(&row[..i], &b[..i])) / row[i];
        }
        // L^T x = y, by rows of L from the last: x_k, then take its part
        // out of the rows above.
        for k in (0..n).rev() {
            let row = &self.l[k * n..k * n + k + 1];
            b[k] /= row[k];
            let xk = b[k];
            axpy(-xk, &row[..k], &mut b[..k]);
        }
    }

    /// `K^-1 B`, column by column.
    ///
    /// # Panics
    /// When `b` does not have `n` rows (a caller bug).
    pub fn solve(&self, b: MatRef<'_, f64>) -> Mat<f64> {
        assert_eq!(b.nrows(), self.n);
        let mut out = Mat::<f64>::zeros(self.n, b.ncols());
        let mut col = vec![0.0; self.n];
        for j in 0..b.ncols() {
            col.iter_mut().enumerate().for_each(|(i, v)| *v = b[(i, j)]);
            self.solve_in_place(&mut col);
            out.col_as_slice_mut(j).copy_from_slice(&col);
        }
        out
    }

    /// `K^-1` into `out` (`n x n`, exactly symmetric, so row- and
    /// column-major alike), with `scratch` for `L^-1` (resized as needed).
    ///
    /// `M = L^-1` column by column (forward substitution of `e_j`, dot
    /// products along rows of `L`), then `K^-1 = M^T M`, whose entries are
    /// the inner products of `M`'s columns: the Gram kernel
    /// ([`syrk_lower_add_triangular`]) on `M` stored column-major.
    ///
    /// # Panics
    /// When `out` is not `n x n` (a caller bug).
    pub fn inverse_into(&self, out: &mut [f64], scratch: &mut Vec<f64>) {
        let n = self.n;
        assert_eq!(out.len(), n * n);
        scratch.clear();
        scratch.resize(n * n, 0.0);
        for (j, col) in scratch.chunks_exact_mut(n).enumerate() {
            // Column j of M is zero above row j.
            col[j] = 1.0 / self.l[j * n + j];
            for i in j + 1..n {
                let row = &self.l[i * n..i * n + i + 1];
                col[i] = -dot(&row[j..i], &col[j..i]) / row[i];
            }
        }
        out.iter_mut().for_each(|v| *v = 0.0);
        if n > 0 {
            syrk_lower_add_triangular(scratch, n, out);
        }
        // Mirror the lower triangle (column-major) into the upper.
        for j in 0..n {
            for i in j + 1..n {
                out[i * n + j] = out[j * n + i];
            }
        }
    }

    /// `K^-1` as a matrix.
    pub fn inverse(&self) -> Mat<f64> {
        let mut out = vec![0.0; self.n * self.n];
        self.inverse_into(&mut out, &mut Vec::new());
        Mat::from_fn(self.n, self.n, |i, j| out[j * self.n + i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_merl::synth::SplitMix64;
    use faer::Side;
    use faer::linalg::solvers::{DenseSolveCore, Solve};

    /// An RBF kernel matrix of random points, with noise: the kind the fit
    /// factorises, condition number up to about 1e6.
    fn kernel(n: usize, noise: f64, rng: &mut SplitMix64) -> Mat<f64> {
        let x: Vec<[f64; 2]> = (0..n)
            .map(|_| [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)])
            .collect();
        Mat::from_fn(n, n, |i, j| {
            let d2 = (x[i][0] - x[j][0]).powi(2) + (x[i][1] - x[j][1]).powi(2);
            (-d2 / 2.0).exp() + if i == j { noise } else { 0.0 }
        })
    }

    #[test]
    fn factor_solve_inverse_and_log_det_agree_with_faer() {
        let mut rng = SplitMix64::new(5);
        for (n, noise) in [(1, 1e-4), (2, 1e-4), (7, 1e-2), (33, 1e-4), (100, 1e-4)] {
            let k = kernel(n, noise, &mut rng);
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
            // Solves and inverse: residuals relative to cond(K) ~ 1/noise.
            let b = Mat::from_fn(n, 3, |_, _| rng.range(-1.0, 1.0));
            let x = c.solve(b.as_ref());
            let resid = (&k * &x - &b).norm_max();
            assert!(resid <= 1e-9, "solve residual {resid:e}, n = {n}");
            let xr = reference.solve(&b);
            assert!((&x - &xr).norm_max() <= 1e-8 * xr.norm_max().max(1.0));
            let inv = c.inverse();
            let want = reference.inverse();
            let err = (&inv - &want).norm_max() / want.norm_max();
            assert!(err <= 1e-9, "inverse {err:e}, n = {n}");
            for i in 0..n {
                for j in 0..n {
                    assert_eq!(inv[(i, j)], inv[(j, i)]);
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
}
