//! Cholesky factorisation `K = L L^T` of a symmetric positive definite
//! matrix, its log-determinant, solves and inverse.
//!
//! `K` is `N x N` with `N` the number of materials (100 to 1000),
//! factorised and inverted hundreds of times per fit, so both are blocked
//! (the `blocked` submodule): nearly all the arithmetic is register-tiled
//! products `C -= A B` over blocks of 64 columns, as in a general matrix
//! product. Sequential, and every entry of `L`, `L^-1` and `K^-1 = L^-T
//! L^-1` is one chain of fused multiply-adds in a fixed order, so the bits
//! do not depend on the CPU path (AVX-512, AVX2, portable), the block size
//! or the thread count.
//!
//! `L` is kept column-major with the leading dimension rounded up to a
//! multiple of 8, the padding zero, so the tiles need no edge cases.

mod blocked;

use faer::{Mat, MatRef};

use crate::simd::dot::{axpy, dot};
use blocked::{PAD, Path};

/// `L` of `K = L L^T`.
#[derive(Debug, Clone)]
pub struct Cholesky {
    n: usize,
    /// The leading dimension: `n` rounded up to a multiple of [`PAD`].
    ld: usize,
    /// `L[i][j]` (`j <= i < n`) at `l[j * ld + i]`; rows `n..ld` of the
    /// first `n` columns are zero; the strict upper triangle is scratch.
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
        let ld = n.next_multiple_of(PAD);
        Cholesky {
            n,
            ld,
            l: vec![0.0; ld * ld],
        }
    }

    /// Factorise `k` (square; its lower triangle is read).
    pub fn factor(k: MatRef<'_, f64>) -> Result<Cholesky, NotPositive> {
        let n = k.nrows().min(k.ncols());
        let mut c = Cholesky::with_size(n);
        c.load(|j, col| {
            for (i, v) in col.iter_mut().enumerate() {
                *v = k[(j + i, j)];
            }
        });
        c.run(Path::detect())?;
        Ok(c)
    }

    /// Factorise the `n x n` column-major `k` (its lower triangle is read)
    /// into this factor's buffer.
    ///
    /// # Panics
    /// When `k` is not `n x n` (a caller bug, never input).
    pub fn factor_into(&mut self, k: &[f64]) -> Result<(), NotPositive> {
        self.factor_on(k, Path::detect())
    }

    fn factor_on(&mut self, k: &[f64], path: Path) -> Result<(), NotPositive> {
        let n = self.n;
        assert_eq!(k.len(), n * n);
        self.load(|j, col| col.copy_from_slice(&k[j * n + j..(j + 1) * n]));
        self.run(path)
    }

    /// Column `j`'s rows `j..n` from `fill(j, rows)`, its padding zeroed.
    fn load(&mut self, mut fill: impl FnMut(usize, &mut [f64])) {
        let (n, ld) = (self.n, self.ld);
        for (j, col) in self.l.chunks_exact_mut(ld).take(n).enumerate() {
            fill(j, &mut col[j..n]);
            col[n..].iter_mut().for_each(|v| *v = 0.0);
        }
    }

    fn run(&mut self, path: Path) -> Result<(), NotPositive> {
        blocked::factor(path, &mut self.l, self.n).map_err(|index| NotPositive { index })
    }

    /// The size `n`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// `L[i][j]` (zero above the diagonal).
    pub fn l(&self, i: usize, j: usize) -> f64 {
        if j > i { 0.0 } else { self.l[j * self.ld + i] }
    }

    /// Column `j` of `L` from the diagonal down (`n - j` values).
    fn column(&self, j: usize) -> &[f64] {
        &self.l[j * self.ld + j..j * self.ld + self.n]
    }

    /// `log|K| = 2 sum log L_ii`.
    pub fn log_det(&self) -> f64 {
        2.0 * (0..self.n).map(|i| self.column(i)[0].ln()).sum::<f64>()
    }

    /// `b <- K^-1 b` for one right-hand side of `n` values.
    ///
    /// # Panics
    /// When `b` does not have `n` values (a caller bug).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.n;
        assert_eq!(b.len(), n);
        // L y = b by columns of L: y_j, then take its part out of the rows
        // below.
        for j in 0..n {
            let col = self.column(j);
            b[j] /= col[0];
            let yj = b[j];
            axpy(-yj, &col[1..], &mut b[j + 1..]);
        }
        // L^T x = y from the last row: x_k from the x below it, along
        // column k of L.
        for k in (0..n).rev() {
            let col = self.column(k);
            b[k] = (b[k] - dot(&col[1..], &b[k + 1..])) / col[0];
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
    /// column-major alike), with `scratch` for `L^-T` and the product
    /// (resized as needed).
    ///
    /// `W = L^-T` blocked like the factorisation, then `K^-1 = W W^T`, the
    /// lower triangle by the same register tiles, mirrored.
    ///
    /// # Panics
    /// When `out` is not `n x n` (a caller bug).
    pub fn inverse_into(&self, out: &mut [f64], scratch: &mut Vec<f64>) {
        self.inverse_on(out, scratch, Path::detect());
    }

    fn inverse_on(&self, out: &mut [f64], scratch: &mut Vec<f64>, path: Path) {
        let (n, ld) = (self.n, self.ld);
        assert_eq!(out.len(), n * n);
        scratch.resize(2 * ld * ld, 0.0);
        let (w, g) = scratch.split_at_mut(ld * ld);
        blocked::invert(path, &self.l, w, n);
        blocked::gram(path, w, g, n);
        for j in 0..n {
            for i in j..n {
                let v = -g[j * ld + i];
                out[j * n + i] = v;
                out[i * n + j] = v;
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
mod tests;
