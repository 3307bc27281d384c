//! The plausibility figures of many latent points in one pass over the
//! store: what the report's grid and a sweep of random points ask for.
//!
//! [`Blend::plausibility`] reads the whole store for one point. For the
//! GP's blend and the soft floor the values of a block of store rows at
//! every point are one product with the points' weights (as the exact
//! albedos are, [`crate::query::exact`]), so `m` points cost one pass and a
//! product instead of `m` passes. The largest directional albedo reads only
//! the directional rule's bins, point by point.

use rayon::prelude::*;

use crate::dense::product::matmul;
use crate::error::Result;
use crate::model::Model;
use crate::query::exact::{PassWeights, floor_of};
use crate::query::floor::{floor_points, top_of};
use crate::query::plausibility::{BlendRule, ClampSums, Plausibility};
use crate::simd::fold::{GROUPS, ordered_blocks};

/// Rows of the store a step of the pass multiplies at once.
const BLOCK: usize = 256;

impl Model {
    /// [`Blend::plausibility`](crate::Blend::plausibility) of the material
    /// `rule` forms at each of `points`. The GP's blend and the soft floor
    /// take one pass over the store for all the points; the plausible
    /// rule's steps need passes of their own ([`Model::plausible_blends`]
    /// makes all the points' blends in one), then each point's figures. The
    /// sums run in a fixed order: the answer does not depend on the thread
    /// count, and equals the one-point figures to rounding.
    pub fn plausibilities(
        &self,
        points: &[[f64; 2]],
        rule: BlendRule,
    ) -> Result<Vec<Plausibility>> {
        if rule == BlendRule::Plausible {
            let points: Vec<Vec<f64>> = points.iter().map(|p| p.to_vec()).collect();
            return self
                .plausible_blends(&points)?
                .iter()
                .map(|b| b.plausibility())
                .collect();
        }
        let floor = floor_of(rule)?;
        self.store().verify_cheap()?;
        let m = points.len();
        if m == 0 {
            return Ok(Vec::new());
        }
        let PassWeights {
            gp: a,
            convex: av,
            reach,
        } = self.pass_weights(points, floor)?;
        let store = self.store();
        let (n, bins) = (store.n(), self.dims().bins());
        let (mean, unmeasured) = (store.mean(), store.unmeasured());
        let cosines = self.cosine_products();
        let transform = self.transform();
        let parts = ordered_blocks(
            store.rows(),
            BLOCK,
            GROUPS,
            || vec![ClampSums::default(); m],
            |acc, range| {
                let len = range.len();
                let mut z = vec![0.0f64; n * len];
                store.copy_rows(range.start, &mut z);
                let mut t = vec![0.0f64; m * len];
                matmul(&mut t, &a, &z, n);
                let mut v = Vec::new();
                if floor {
                    v.resize(m * len, 0.0);
                    matmul(&mut v, &av, &z, n);
                }
                for (k, row) in range.enumerate() {
                    if unmeasured[row] != 0 {
                        continue;
                    }
                    let (mu, bin) = (mean[row], row % bins);
                    let t = &mut t[k * m..(k + 1) * m];
                    if floor {
                        let top = top_of(&z[k * n..(k + 1) * n]);
                        floor_points(t, &v[k * m..(k + 1) * m], mu, top, &reach[row / bins]);
                    }
                    let (c, form) = (cosines[bin], transform.inverse_form(bin));
                    for (s, &t) in acc.iter_mut().zip(t.iter()) {
                        s.add(form.unclamped(mu + t), c);
                    }
                }
            },
        );
        let mut sums = vec![ClampSums::default(); m];
        for part in parts {
            sums.iter_mut().zip(&part).for_each(|(s, p)| s.merge(p));
        }
        // The points' largest albedos are independent: one a thread.
        let out = points
            .par_iter()
            .zip(sums)
            .map(|(x, s)| {
                let (max_albedo, max_albedo_incidence) = self.at_with(x, rule)?.largest_albedo();
                Ok(s.figures(max_albedo, max_albedo_incidence))
            })
            .collect::<Result<Vec<_>>>()?;
        self.verify()?;
        Ok(out)
    }
}
