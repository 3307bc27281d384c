//! The leave-one-out predictors of [`super::loo`]: `N x N` matrices `P`
//! that predict each material from the stored ones (`z_hat_i = sum_j P_ij
//! z_j`), for the GPLVM held out and for PCA held out and in sample. The
//! mathematics is in [`super::loo`]'s documentation.

use faer::{Mat, MatRef};

use crate::dense::symmetric_eigen;

use crate::error::{CoreError, ParamError, Result};
use crate::gplvm::kernel::Kernel;
use crate::gplvm::likelihood::factor;

/// Leave-one-out needs at least two materials (one held out, one to predict it).
pub(super) fn needs_two(n: usize) -> Result<()> {
    if n < 2 {
        return Err(ParamError::TooFewMaterials {
            method: "leave-one-out",
            needs: 2,
            got: n,
        }
        .into());
    }
    Ok(())
}

/// The GP leave-one-out predictor of latent points `latent` (`N x q`).
pub fn gp_predictor(
    kernel: &Kernel,
    latent: MatRef<'_, f64>,
    refit_mean: bool,
) -> Result<Mat<f64>> {
    let n = latent.nrows();
    needs_two(n)?;
    let (_, a) = factor(kernel.matrix(latent).as_ref(), "leave-one-out")?;
    let g: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| a[(i, j)]).sum::<f64>() / a[(i, i)])
        .collect();
    Ok(Mat::from_fn(n, n, |i, j| {
        let delta = if i == j { 1.0 } else { 0.0 };
        let mut p = delta - a[(i, j)] / a[(i, i)];
        if refit_mean && i == j {
            p -= g[i] / (n - 1) as f64;
        }
        p
    }))
}

/// Eigenvalues (descending) and eigenvectors (same order, as columns) of a
/// symmetric matrix.
pub(super) fn eigen_desc(y: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = y.nrows();
    let (s, u) = symmetric_eigen(y).ok_or(CoreError::Eigen("the Gram matrix"))?;
    let vals = (0..n).rev().map(|k| s[k]).collect();
    let vecs = Mat::from_fn(n, n, |i, k| u[(i, n - 1 - k)]);
    Ok((vals, vecs))
}

/// Components kept: the first `q` whose eigenvalue is meaningfully positive.
fn kept(vals: &[f64], q: usize) -> usize {
    let top = vals.first().copied().unwrap_or(0.0).max(0.0);
    vals.iter()
        .take(q)
        .take_while(|&&s| s > 1e-12 * top && s > 0.0)
        .count()
}

/// The PCA leave-one-out predictor with `q` components, from the Gram
/// matrix `y` of the centred data.
pub fn pca_predictor(y: MatRef<'_, f64>, q: usize) -> Result<Mat<f64>> {
    let n = y.nrows();
    if n < 3 {
        return Err(ParamError::TooFewMaterials {
            method: "PCA leave-one-out",
            needs: 3,
            got: n,
        }
        .into());
    }
    let m = (n - 1) as f64;
    let mut p = Mat::<f64>::zeros(n, n);
    for i in 0..n {
        let others: Vec<usize> = (0..n).filter(|&j| j != i).collect();
        // Re-centred by the others' mean: z'_j = z_j + z_i / (N - 1).
        let yp = Mat::from_fn(n - 1, n - 1, |a, b| {
            let (j, k) = (others[a], others[b]);
            y[(j, k)] + (y[(j, i)] + y[(k, i)]) / m + y[(i, i)] / (m * m)
        });
        // The held-out material re-centred: z'_i = z_i N / (N - 1).
        let b: Vec<f64> = others
            .iter()
            .map(|&j| (y[(j, i)] + y[(i, i)] / m) * n as f64 / m)
            .collect();
        let (vals, u) = eigen_desc(yp.as_ref())?;
        let mut w = vec![0.0; n - 1];
        for k in 0..kept(&vals, q) {
            let proj: f64 = (0..n - 1).map(|a| u[(a, k)] * b[a]).sum::<f64>() / vals[k];
            w.iter_mut()
                .enumerate()
                .for_each(|(a, wa)| *wa += u[(a, k)] * proj);
        }
        // mean_-i + sum_j w_j z'_j = mean + sum_j w_j z_j + (sum w - 1) z_i / (N - 1).
        for (a, &j) in others.iter().enumerate() {
            p[(i, j)] = w[a];
        }
        p[(i, i)] = (w.iter().sum::<f64>() - 1.0) / m;
    }
    Ok(p)
}

/// The in-sample PCA projector `U_q U_q^T` with `q` components.
pub fn pca_in_sample_predictor(y: MatRef<'_, f64>, q: usize) -> Result<Mat<f64>> {
    let n = y.nrows();
    let (vals, u) = eigen_desc(y)?;
    let k = kept(&vals, q);
    Ok(Mat::from_fn(n, n, |i, j| {
        (0..k).map(|c| u[(i, c)] * u[(j, c)]).sum()
    }))
}

/// Sum of the eigenvalues of `y` beyond the first `q`: the in-sample
/// squared residual of PCA with `q` components (transformed space, all rows).
pub fn discarded(y: MatRef<'_, f64>, q: usize) -> Result<f64> {
    let (vals, _) = eigen_desc(y)?;
    Ok(vals.iter().skip(q).map(|v| v.max(0.0)).sum())
}
