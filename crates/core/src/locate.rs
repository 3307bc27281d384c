//! Locating a new material in a fitted latent space.
//!
//! The latent point whose reconstruction is closest to a new material `t`
//! (transformed and centred as the store: `z = t - mean`) minimises
//! `|z - Z^T w(x)|^2 = |z|^2 - 2 w(x)^T b + w(x)^T Y w(x)` with `b = Z z`.
//! The new material enters only through `b` (its dot products with the `N`
//! inputs: one streaming pass) and `|z|^2`; every candidate `x` then costs
//! O(N^2). The search covers the whole latent plane, not only the fit's box
//! `[-1, 1]^q`: a material unlike every input may be matched best beyond
//! it. Far from every input the kernel vanishes and the reconstruction
//! decays to the mean material, so the error there flattens to `|z|^2` and
//! the optimum is finite: within a few length scales of the inputs. The
//! search: the training points, a fine grid over the box and a coarser one
//! over the inputs' bounding box widened by [`REACH`] length scales (in the
//! plane, `q = 2`), then Hooke-Jeeves refinement, unconstrained but for
//! that widened box.

use brdf_merl::MerlFile;

use crate::error::{CoreError, Result};
use crate::gplvm::kernel::rows_of;
use crate::gplvm::optim::BOX;
use crate::maps::albedo_map::View;
use crate::model::Model;
use crate::simd::fold::ordered_blocks;

/// How many length scales beyond the inputs the search reaches: there the
/// kernel is below `e^-(REACH^2 / 2)` (3e-4), so the reconstruction is the
/// mean material to that share, and moving further changes nothing.
pub const REACH: f64 = 4.0;

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

impl Located {
    /// Does the point lie in the map's default view ([`View::default`])?
    /// (Always `true` beyond two dimensions, where there is no map.)
    pub fn in_default_view(&self) -> bool {
        let v = View::default();
        match self.point[..] {
            [x, y] => (v.x0..=v.x1).contains(&x) && (v.y0..=v.y1).contains(&y),
            _ => true,
        }
    }
}

impl Located {
    /// Find the latent point of `model` whose reconstruction best matches `file`.
    pub fn find(model: &Model, file: &MerlFile) -> Result<Located> {
        let dims = model.dims();
        if file.dims() != dims {
            return Err(CoreError::BadQuery(format!(
                "{}: dims {}, the model's materials are {dims}",
                file.path().display(),
                file.dims()
            )));
        }
        let store = model.store();
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
                model.transform().forward_raw_rows(bins, r0, &raw, &mut t);
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
        let y = model.gram();
        let error = |x: &[f64]| -> f64 {
            let Ok(w) = model.weights_at(x) else {
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
        let q = model.q();
        let latent = model.latent();
        // The inputs' bounding box (the fit's box at least), widened by REACH length scales.
        let reach = REACH * model.file().kernel.length_scale;
        let bounds: Vec<(f64, f64)> = (0..q)
            .map(|c| {
                let (lo, hi) = (0..n).fold((BOX.0, BOX.1), |(lo, hi), i| {
                    (lo.min(latent[(i, c)]), hi.max(latent[(i, c)]))
                });
                (lo - reach, hi + reach)
            })
            .collect();
        let mut candidates = rows_of(latent.as_ref());
        if q == 2 {
            let grid = |g: usize, (x0, x1): (f64, f64), (y0, y1): (f64, f64)| {
                let f =
                    move |k: usize, lo: f64, hi: f64| lo + (hi - lo) * k as f64 / (g - 1) as f64;
                (0..g * g).map(move |k| vec![f(k / g, x0, x1), f(k % g, y0, y1)])
            };
            candidates.extend(grid(33, BOX, BOX));
            candidates.extend(grid(41, bounds[0], bounds[1]));
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
                    x[c] = (x[c] + sign * step).clamp(bounds[c].0, bounds[c].1);
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
        model.verify()?;
        Ok(Located {
            point,
            rmse: (best.0.max(0.0) / d).sqrt(),
            spread: (s / d).sqrt(),
            nearest,
        })
    }
}
