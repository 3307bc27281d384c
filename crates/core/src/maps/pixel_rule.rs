//! The map's per-pixel rule: a quadrature rule of a few hundred bins,
//! with what its pixels need precomputed (the rows' `K^-1 Z^T`, means and
//! brightest values), kept by the atlas one a sample count.

use std::sync::Arc;

use brdf_merl::Quadrature;
use faer::Mat;

use crate::data::store::Rows;
use crate::maps::Atlas;
use crate::maps::exact_albedos::RuleRows;

/// The map's per-pixel rule at one sample count, ready for pixels: the
/// store rows the rule reads, where each channel's rows end, their means,
/// and `C = K^-1 Z_q^T` (column-major `r x n`), so that the values at a
/// point `x` are `mean + C k(x)`.
pub(crate) struct PixelRule {
    pub(crate) samples: usize,
    /// Bins the rule reads.
    pub(crate) bins: usize,
    pub(crate) rows: RuleRows,
    pub(crate) ends: Vec<usize>,
    pub(crate) c: Vec<f64>,
    /// `Z_q^T` (column-major `r x n`): the values of a convex blend `v` are
    /// `mean + Z_q^T v`.
    pub(crate) cv: Vec<f64>,
    pub(crate) mean: Vec<f64>,
    /// The largest centred value of each rule row (the soft floor's cap,
    /// [`crate::model::blend::soft_floor::floor_capped`]).
    pub(crate) top: Vec<f64>,
}

/// Per-pixel rules a model keeps, one a sample count: a viewer asking for
/// previews and full maps again and again pays for each rule once.
const PIXEL_RULE_CACHE: usize = 4;

impl Atlas {
    /// The per-pixel rule with `samples` samples, from the model's cache or
    /// built (the shaped quadrature rule, its store rows and `C`) and kept.
    pub(crate) fn pixel_rule(&self, samples: usize) -> Arc<PixelRule> {
        let cache = &self.pixel_rules;
        let same = |r: &PixelRule| r.samples == samples;
        if let Some(r) = cache.find(same) {
            return r;
        }
        let n = self.model.latent().nrows();
        let store = self.model.store();
        let quadrature =
            Quadrature::with_samples_shaped(self.model.albedo_rule(), samples, self.shape());
        // The rows the rule reads (measured ones only), grouped by channel,
        // with the quadrature weight folded into the inverse's scale.
        let rows = self.rows_of(&quadrature);
        let r = rows.rows.len();
        let ends: Vec<usize> = (0..3)
            .map(|c| rows.channel.iter().filter(|&&x| x as usize <= c).count())
            .collect();
        let zq = Mat::from_fn(n, r, |i, j| match store.z() {
            Rows::F32(z) => z[rows.rows[j] * n + i] as f64,
            Rows::F64(z) => z[rows.rows[j] * n + i],
        });
        // C^T = K^-1 Z_q^T, so that the values at x are mean + C k(x);
        // C column-major (r x n) for the product.
        let ct = self.model.llt_solve(&zq);
        let c: Vec<f64> = (0..n)
            .flat_map(|i| (0..r).map(move |j| (i, j)))
            .map(|(i, j)| ct[(i, j)])
            .collect();
        let cv: Vec<f64> = (0..n)
            .flat_map(|i| (0..r).map(move |j| (i, j)))
            .map(|(i, j)| zq[(i, j)])
            .collect();
        let mean: Vec<f64> = rows.rows.iter().map(|&row| store.mean()[row]).collect();
        let top: Vec<f64> = (0..r)
            .map(|j| (0..n).map(|i| zq[(i, j)]).fold(f64::NEG_INFINITY, f64::max))
            .collect();
        let rule = Arc::new(PixelRule {
            samples,
            bins: quadrature.len(),
            rows,
            ends,
            c,
            cv,
            mean,
            top,
        });
        cache.keep(rule.clone(), PIXEL_RULE_CACHE, same, |_| false);
        rule
    }
}
