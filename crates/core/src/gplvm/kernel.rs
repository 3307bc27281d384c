//! The RBF kernel `c(x, x') = exp(-|x - x'|^2 / (2 l^2)) + mu delta(x, x')`.

use crate::error::ParamError;
use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

/// Kernel hyperparameters: length scale `l` and noise `mu` (defaults 1 and 1e-4, the paper's).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Kernel {
    /// Length scale `l` of the RBF.
    pub length_scale: f64,
    /// Noise `mu`, added on the diagonal only.
    pub noise: f64,
}

impl Default for Kernel {
    fn default() -> Self {
        Kernel {
            length_scale: 1.0,
            noise: 1e-4,
        }
    }
}

/// Smallest and largest length scale a kernel may have.
pub const LENGTH_SCALE_RANGE: (f64, f64) = (1e-6, 1e6);
/// Smallest and largest noise a kernel may have.
pub const NOISE_RANGE: (f64, f64) = (1e-15, 1e6);
/// Where a length scale learned by maximum likelihood is kept. The latent
/// points lie in `[-1, 1]^q`: below 0.05 the materials would be
/// uncorrelated bumps 1/40 of the box wide; above 20 every pair is closer
/// than a tenth of `l` and `K` is all but singular.
pub const LEARNED_LENGTH_SCALE_RANGE: (f64, f64) = (0.05, 20.0);
/// Where a noise learned by maximum likelihood is kept (relative to the
/// data's mean variance, which the fit normalises to 1): at most 10, where
/// the model explains nothing, and at least 1e-8, which keeps the condition
/// number of `K` below about 1e8 even when two materials coincide.
pub const LEARNED_NOISE_RANGE: (f64, f64) = (1e-8, 10.0);

impl Kernel {
    /// Check the hyperparameters lie in [`LENGTH_SCALE_RANGE`] and
    /// [`NOISE_RANGE`] (beyond them `K` is all ones or the identity to
    /// working precision, or its entries are NaN); the error says which.
    pub fn check(&self) -> Result<(), ParamError> {
        let (min, max) = LENGTH_SCALE_RANGE;
        if !(min..=max).contains(&self.length_scale) {
            return Err(ParamError::LengthScale {
                value: self.length_scale,
                min,
                max,
            });
        }
        let (min, max) = NOISE_RANGE;
        if !(min..=max).contains(&self.noise) {
            return Err(ParamError::Noise {
                value: self.noise,
                min,
                max,
            });
        }
        Ok(())
    }

    /// `exp(-|a - b|^2 / (2 l^2))`, without the noise term.
    #[inline]
    pub fn eval(&self, a: &[f64], b: &[f64]) -> f64 {
        let r2: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
        (-r2 / (2.0 * self.length_scale * self.length_scale)).exp()
    }

    /// The `N x N` matrix `K` of latent points `x` (`N x q`), noise on the diagonal.
    pub fn matrix(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        let n = x.nrows();
        let pts = rows_of(x);
        // Each pair once: `eval` is symmetric bit for bit (it sums squared
        // differences, and `a - b` is `-(b - a)` exactly).
        let mut k = Mat::<f64>::zeros(n, n);
        for j in 0..n {
            k[(j, j)] = 1.0 + self.noise;
            for i in 0..j {
                let v = self.eval(&pts[i], &pts[j]);
                k[(i, j)] = v;
                k[(j, i)] = v;
            }
        }
        k
    }

    /// `k(p)_i = exp(-|p - x_i|^2 / (2 l^2))`: no noise term, so a training
    /// point does not reproduce itself exactly.
    pub fn vector(&self, x: MatRef<'_, f64>, p: &[f64]) -> Vec<f64> {
        rows_of(x).iter().map(|xi| self.eval(xi, p)).collect()
    }
}

/// The rows of a small matrix as vectors.
pub(crate) fn rows_of(x: MatRef<'_, f64>) -> Vec<Vec<f64>> {
    (0..x.nrows())
        .map(|i| (0..x.ncols()).map(|j| x[(i, j)]).collect())
        .collect()
}
