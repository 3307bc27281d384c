//! Locating a new material in a fitted latent space.
//!
//! The latent point whose reconstruction is closest to a new material `t`
//! (transformed and centred as the store: `z = t - mean`) minimises
//! `|z - Z^T w(x)|^2 = |z|^2 - 2 w(x)^T b + w(x)^T Y w(x)` with `b = Z z`.
//! The new material enters only through `b` (its dot products with the `N`
//! inputs: one streaming pass) and `|z|^2`; every candidate `x` then costs
//! O(N^2). The search: a coarse grid over the box (or the training points
//! when `q > 2`), then Hooke-Jeeves refinement.

use brdf_merl::MerlFile;

use crate::error::{CoreError, Result};
use crate::gplvm::kernel::rows_of;
use crate::gplvm::optim::BOX;
use crate::model::Model;
use crate::simd::fold::ordered_blocks;

/// Where a material lands.
#[derive(Debug, Clone, PartialEq)]
pub struct Located {
    /// The latent point.
    pub point: Vec<f64>,
    /// Root-mean-square reconstruction error per value, in transformed space.
    pub rmse: f64,
    /// RMS of the material itself around the mean (for scale): `rmse / spread` < 1 is better than the mean.
    pub spread: f64,
    /// Input materials by latent distance from the point, nearest first: (index, distance).
    pub nearest: Vec<(usize, f64)>,
}

impl Model {
    /// Find the latent point whose reconstruction best matches `file`.
    pub fn locate(&self, file: &MerlFile) -> Result<Located> {
        let dims = self.dims();
        if file.dims() != dims {
            return Err(CoreError::BadQuery(format!(
                "{}: dims {}, the model's materials are {dims}",
                file.path().display(),
                file.dims()
            )));
        }
        let store = self.store();
        store.verify_cheap()?;
        let (n, bins, rows) = (store.n(), dims.bins(), store.rows());
        let mean = store.mean();
        // b = Z z and |z|^2, in fixed chunks folded in order.
        let chunk = 1 << 16;
        let parts = ordered_blocks(
            rows,
            chunk,
            usize::MAX,
            || (vec![0.0; n], 0.0),
            |(b, s), range| {
                let r0 = range.start;
                let mut raw = vec![0.0; range.len()];
                file.copy_raw(r0, &mut raw);
                let mut t = vec![0.0; range.len()];
                self.transform().forward_raw_rows(bins, r0, &raw, &mut t);
                let mut zrow = vec![0.0; n];
                for (j, tv) in t.iter().enumerate() {
                    let z = tv - mean[r0 + j];
                    *s += z * z;
                    store.copy_rows(r0 + j, &mut zrow);
                    for (bi, zi) in b.iter_mut().zip(&zrow) {
                        *bi += z * zi;
                    }
                }
            },
        );
        let mut b = vec![0.0; n];
        let mut s = 0.0;
        for (pb, ps) in parts {
            b.iter_mut().zip(pb).for_each(|(x, y)| *x += y);
            s += ps;
        }
        let y = self.gram();
        let error = |x: &[f64]| -> f64 {
            let Ok(w) = self.weights_at(x) else {
                return f64::INFINITY;
            };
            let wb: f64 = w.iter().zip(&b).map(|(a, c)| a * c).sum();
            let mut wyw = 0.0;
            for i in 0..n {
                let mut row = 0.0;
                for j in 0..n {
                    row += y[(i, j)] * w[j];
                }
                wyw += w[i] * row;
            }
            s - 2.0 * wb + wyw
        };
        let q = self.q();
        let latent = self.latent();
        let mut candidates = rows_of(latent.as_ref());
        if q == 2 {
            let g = 33;
            for a in 0..g {
                for c in 0..g {
                    let f = |k: usize| BOX.0 + (BOX.1 - BOX.0) * k as f64 / (g - 1) as f64;
                    candidates.push(vec![f(a), f(c)]);
                }
            }
        }
        let mut best = candidates
            .iter()
            .map(|x| (error(x), x.clone()))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("at least one candidate");
        // Hooke-Jeeves refinement (exploratory moves only; the function is cheap).
        let mut step = 0.05;
        while step > 1e-6 {
            let mut improved = false;
            for c in 0..q {
                for sign in [1.0, -1.0] {
                    let mut x = best.1.clone();
                    x[c] = (x[c] + sign * step).clamp(BOX.0, BOX.1);
                    let e = error(&x);
                    if e < best.0 {
                        best = (e, x);
                        improved = true;
                        break;
                    }
                }
            }
            if !improved {
                step *= 0.5;
            }
        }
        let d = rows as f64;
        let point = best.1;
        let mut nearest: Vec<(usize, f64)> = (0..n)
            .map(|i| {
                let d2: f64 = (0..q).map(|c| (latent[(i, c)] - point[c]).powi(2)).sum();
                (i, d2.sqrt())
            })
            .collect();
        nearest.sort_by(|a, b| a.1.total_cmp(&b.1));
        file.verify()?;
        self.verify()?;
        Ok(Located {
            point,
            rmse: (best.0.max(0.0) / d).sqrt(),
            spread: (s / d).sqrt(),
            nearest,
        })
    }
}
