//! The GPLVM cost `L(X) = d/2 log|K| + 1/2 tr(K^-1 Y)` and its gradient,
//! computed densely from a Cholesky factor.
//!
//! The data enter only through the Gram matrix `Y = Z Z^T` (the Gram trick):
//! every evaluation is O(N^3) on an `N x N` matrix, whatever `d` is.
//!
//! **Signal scale.** The kernel has unit signal variance, so the data are
//! normalised to unit mean variance per dimension before fitting:
//! `Y <- Y / s^2` with `s^2 = tr(Y) / (N d)`. Reconstruction
//! (`k(x)^T K^-1 Z`) is invariant to this scale, so only the fit sees it; the
//! noise `mu` is then relative to the data's variance.

use faer::{Mat, MatRef};

use crate::dense::Cholesky;
use crate::dense::product::matmul;

use crate::error::{CoreError, ParamError, Result};
use crate::gplvm::kernel::Kernel;

/// The data of a fit: the normalised Gram matrix and the dimension `d`.
#[derive(Debug, Clone)]
pub struct GramData {
    y: Mat<f64>,
    d: usize,
    scale2: f64,
}

impl GramData {
    /// Normalise a raw Gram matrix `Y = Z Z^T` of `d`-dimensional centred data.
    pub fn new(y: Mat<f64>, d: usize) -> Result<GramData> {
        let n = y.nrows();
        if n == 0 || y.ncols() != n || d == 0 {
            return Err(ParamError::GramShape {
                rows: y.nrows(),
                cols: y.ncols(),
                d,
            }
            .into());
        }
        if !y.as_ref().norm_max().is_finite() {
            return Err(ParamError::GramNotFinite.into());
        }
        let trace: f64 = (0..n).map(|i| y[(i, i)]).sum();
        let scale2 = if trace > 0.0 {
            trace / (n * d) as f64
        } else {
            1.0
        };
        Ok(GramData {
            y: &y * faer::Scale(1.0 / scale2),
            d,
            scale2,
        })
    }

    /// The normalised Gram matrix.
    pub fn y(&self) -> MatRef<'_, f64> {
        self.y.as_ref()
    }

    /// Number of materials `N`.
    pub fn n(&self) -> usize {
        self.y.nrows()
    }

    /// Dimension `d` of each material.
    pub fn d(&self) -> usize {
        self.d
    }

    /// The variance `s^2` the data were divided by.
    pub fn scale2(&self) -> f64 {
        self.scale2
    }
}

/// `(log|K|, K^-1)` from a Cholesky factorisation; a typed error if `K` is not SPD.
///
/// Sequential on purpose ([`Cholesky`]): `K` is small (`N x N`, N about
/// 100), where thread hand-offs cost more than the arithmetic, this runs
/// thousands of times in a fit, and a sequential factorisation gives the
/// same bits on any machine load and thread count.
pub fn factor(k: MatRef<'_, f64>, context: &str) -> Result<(f64, Mat<f64>)> {
    let not_spd = |pivot| CoreError::NotPositiveDefinite {
        context: context.to_string(),
        pivot,
    };
    let l = Cholesky::factor(k).map_err(|e| not_spd(Some(e.index)))?;
    let logdet = l.log_det();
    if !logdet.is_finite() {
        return Err(not_spd(None));
    }
    Ok((logdet, l.inverse()))
}

/// `tr(A B)` for symmetric `A`, `B`: the sum of their elementwise product.
pub fn trace_product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> f64 {
    let mut s = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            s += a[(i, j)] * b[(i, j)];
        }
    }
    s
}

/// `A B A` for `n x n` matrices, through the library's own product
/// ([`crate::dense::product::matmul`]; faer's would reserve a scratch of
/// twice the reported L3 cache in the calling thread).
fn sandwich(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let n = a.nrows();
    let columns = |m: MatRef<'_, f64>| -> Vec<f64> {
        let mut out = Vec::with_capacity(n * n);
        for j in 0..n {
            out.extend((0..n).map(|i| m[(i, j)]));
        }
        out
    };
    let (a, b) = (columns(a), columns(b));
    let (mut ab, mut aba) = (vec![0.0; n * n], vec![0.0; n * n]);
    matmul(&mut ab, &a, &b, n);
    matmul(&mut aba, &ab, &a, n);
    Mat::from_fn(n, n, |i, j| aba[j * n + i])
}

/// The cost at latent points `x` (`N x q`), from scratch.
pub fn cost(kernel: &Kernel, data: &GramData, x: MatRef<'_, f64>) -> Result<f64> {
    let k = kernel.matrix(x);
    let (logdet, inv) = factor(k.as_ref(), "dense cost")?;
    Ok(0.5 * data.d as f64 * logdet + 0.5 * trace_product(inv.as_ref(), data.y()))
}

/// The gradient of the cost with respect to the latent points and to the
/// logarithms of the kernel's hyperparameters.
#[derive(Debug, Clone)]
pub struct Gradient {
    /// `dL/dx`, `N x q`.
    pub latent: Mat<f64>,
    /// `dL/d(ln l)`.
    pub log_length_scale: f64,
    /// `dL/d(ln mu)`.
    pub log_noise: f64,
}

/// The cost and its gradient with respect to `x`, `ln l` and `ln mu`.
///
/// With `G = d K^-1 - K^-1 Y K^-1`, `dL = 1/2 tr(G dK)`, so
/// `dL/dx_i = -sum_j G_ij k_ij (x_i - x_j) / l^2`;
/// `dK_ij/d(ln l) = k_ij |x_i - x_j|^2 / l^2` off the diagonal (where `k_ij`
/// is the RBF, 1 on the diagonal whatever `l`) and `dK/d(ln mu) = mu I`, so
/// `dL/d(ln l) = 1/2 sum_ij G_ij k_ij |x_i - x_j|^2 / l^2` and
/// `dL/d(ln mu) = 1/2 mu tr(G)`.
pub fn cost_and_full_gradient(
    kernel: &Kernel,
    data: &GramData,
    x: MatRef<'_, f64>,
) -> Result<(f64, Gradient)> {
    let (n, q) = (x.nrows(), x.ncols());
    let k = kernel.matrix(x);
    let (logdet, inv) = factor(k.as_ref(), "dense gradient")?;
    let d = data.d as f64;
    let cost = 0.5 * d * logdet + 0.5 * trace_product(inv.as_ref(), data.y());
    let kyk = sandwich(inv.as_ref(), data.y());
    let l2 = kernel.length_scale * kernel.length_scale;
    let mut latent = Mat::<f64>::zeros(n, q);
    let (mut dlength, mut trace_g) = (0.0, 0.0);
    for i in 0..n {
        trace_g += d * inv[(i, i)] - kyk[(i, i)];
        for j in 0..n {
            if i == j {
                continue;
            }
            let g = d * inv[(i, j)] - kyk[(i, j)];
            let w = g * k[(i, j)] / l2;
            let mut r2 = 0.0;
            for c in 0..q {
                let dx = x[(i, c)] - x[(j, c)];
                latent[(i, c)] -= w * dx;
                r2 += dx * dx;
            }
            dlength += w * r2;
        }
    }
    Ok((
        cost,
        Gradient {
            latent,
            log_length_scale: 0.5 * dlength,
            log_noise: 0.5 * kernel.noise * trace_g,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Side;
    use faer::linalg::solvers::DenseSolveCore;

    pub(crate) fn random_problem(n: usize, d: usize, seed: u64) -> (GramData, Mat<f64>) {
        let mut rng = brdf_merl::synth::SplitMix64::new(seed);
        let z = Mat::<f64>::from_fn(n, d, |_, _| rng.range(-1.0, 1.0));
        let x = Mat::<f64>::from_fn(n, 2, |_, _| rng.range(-1.0, 1.0));
        (GramData::new(&z * z.transpose(), d).unwrap(), x)
    }

    #[test]
    fn cost_matches_brute_force() {
        let (data, x) = random_problem(6, 40, 3);
        let kernel = Kernel::default();
        let k = kernel.matrix(x.as_ref());
        // Brute force: determinant by LU-free eigenvalues, inverse by faer's general solver.
        let evals = k.self_adjoint_eigenvalues(Side::Lower).unwrap();
        let logdet: f64 = evals.iter().map(|e| e.ln()).sum();
        let inv = k.partial_piv_lu().inverse();
        let want = 0.5 * 40.0 * logdet + 0.5 * trace_product(inv.as_ref(), data.y());
        let got = cost(&kernel, &data, x.as_ref()).unwrap();
        assert!((got - want).abs() <= 1e-10 * want.abs(), "{got} vs {want}");
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let (data, x) = random_problem(8, 30, 11);
        let kernel = Kernel {
            length_scale: 0.7,
            noise: 1e-2,
        };
        let g = cost_and_full_gradient(&kernel, &data, x.as_ref())
            .unwrap()
            .1
            .latent;
        let h = 1e-6;
        for i in 0..8 {
            for c in 0..2 {
                let mut xp = x.clone();
                let mut xm = x.clone();
                xp[(i, c)] += h;
                xm[(i, c)] -= h;
                let fd = (cost(&kernel, &data, xp.as_ref()).unwrap()
                    - cost(&kernel, &data, xm.as_ref()).unwrap())
                    / (2.0 * h);
                assert!(
                    (fd - g[(i, c)]).abs() <= 1e-5 * fd.abs().max(1.0),
                    "({i},{c}): fd {fd} vs {}",
                    g[(i, c)]
                );
            }
        }
    }

    #[test]
    fn kernel_gradient_matches_finite_differences() {
        let (data, x) = random_problem(9, 30, 12);
        for kernel in [
            Kernel {
                length_scale: 0.7,
                noise: 1e-2,
            },
            Kernel {
                length_scale: 2.5,
                noise: 0.3,
            },
        ] {
            let (_, g) = cost_and_full_gradient(&kernel, &data, x.as_ref()).unwrap();
            let h = 1e-6;
            let at = |dl: f64, dm: f64| {
                let k = Kernel {
                    length_scale: kernel.length_scale * dl.exp(),
                    noise: kernel.noise * dm.exp(),
                };
                cost(&k, &data, x.as_ref()).unwrap()
            };
            let fd_l = (at(h, 0.0) - at(-h, 0.0)) / (2.0 * h);
            let fd_m = (at(0.0, h) - at(0.0, -h)) / (2.0 * h);
            for (name, fd, got) in [
                ("ln l", fd_l, g.log_length_scale),
                ("ln mu", fd_m, g.log_noise),
            ] {
                assert!(
                    (fd - got).abs() <= 1e-5 * fd.abs().max(1.0),
                    "{kernel:?} {name}: fd {fd} vs {got}"
                );
            }
        }
    }

    #[test]
    fn normalisation_gives_unit_mean_variance() {
        let (data, _) = random_problem(5, 50, 1);
        let tr: f64 = (0..5).map(|i| data.y()[(i, i)]).sum();
        assert!((tr / (5.0 * 50.0) - 1.0).abs() < 1e-12);
        let zero = GramData::new(Mat::zeros(3, 3), 10).unwrap();
        assert_eq!(zero.scale2(), 1.0);
    }
}
