//! Dual PCA: the starting latent points from the eigen-decomposition of the
//! `N x N` Gram matrix `Y = Z Z^T`, never the `d x d` covariance.
//!
//! With `Y = U S U^T`, the principal coordinates of the materials are the
//! columns `U_k sqrt(s_k)` of the largest eigenvalues. They are scaled by one
//! common factor (keeping the shape) so the largest coordinate has
//! magnitude 1, inside the box `[-1, 1]^q`. The eigenvectors come with fixed
//! signs (largest-magnitude entry positive, see
//! [`symmetric_eigen`](crate::dense::symmetric_eigen)), so the start is
//! deterministic.

use faer::{Mat, MatRef};

use crate::dense::symmetric_eigen;

use crate::error::{CoreError, ParamError, Result};

/// The `N x q` PCA start, and the eigenvalues of `Y` in descending order.
pub fn dual_pca(y: MatRef<'_, f64>, q: usize) -> Result<(Mat<f64>, Vec<f64>)> {
    let n = y.nrows();
    if q == 0 || q >= n.max(1) {
        return Err(ParamError::LatentDimForData { q, n }.into());
    }
    let (s, u) = symmetric_eigen(y).ok_or(CoreError::Eigen("the Gram matrix"))?;
    let eigenvalues: Vec<f64> = (0..n).rev().map(|k| s[k]).collect();
    let mut x = Mat::<f64>::zeros(n, q);
    for c in 0..q {
        let k = n - 1 - c;
        let root = s[k].max(0.0).sqrt();
        for i in 0..n {
            x[(i, c)] = u[(i, k)] * root;
        }
    }
    let max = x.as_ref().norm_max();
    if max > 0.0 && max.is_finite() {
        x = &x * faer::Scale(1.0 / max);
    }
    Ok((x, eigenvalues))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_planar_embedding_up_to_rotation() {
        // Points on a line in d = 3: one non-zero eigenvalue, coordinates proportional to t.
        let t = [-2.0, -1.0, 0.5, 2.5];
        let mean = t.iter().sum::<f64>() / 4.0;
        let z = Mat::<f64>::from_fn(4, 3, |i, j| (t[i] - mean) * [1.0, 2.0, -1.0][j]);
        let (x, ev) = dual_pca((&z * z.transpose()).as_ref(), 1).unwrap();
        assert!(ev[1].abs() < 1e-9 * ev[0]);
        let ratio = x[(0, 0)] / (t[0] - mean);
        for i in 0..4 {
            assert!((x[(i, 0)] - ratio * (t[i] - mean)).abs() < 1e-12);
        }
        assert!((x.as_ref().norm_max() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn q_must_be_below_n() {
        let y = Mat::<f64>::identity(2, 2);
        assert!(
            dual_pca(y.as_ref(), 2)
                .unwrap_err()
                .to_string()
                .contains("q = 2")
        );
        assert!(dual_pca(Mat::<f64>::identity(1, 1).as_ref(), 1).is_err());
        assert!(dual_pca(y.as_ref(), 1).is_ok());
        // All-identical materials: Y = 0, all points at the origin, still finite.
        let (x, _) = dual_pca(Mat::<f64>::zeros(3, 3).as_ref(), 2).unwrap();
        assert_eq!(x.as_ref().norm_max(), 0.0);
    }
}
