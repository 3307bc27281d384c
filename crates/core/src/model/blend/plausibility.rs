//! Is the material at a latent point a physical one, and does the model know
//! anything there?
//!
//! - [`Plausibility`]: what the blend `mean + w . Z` does before the inverse
//!   transform clamps it to `>= 0`: the share of the cosine-weighted
//!   reflectance the clamp removes, the share of values it touches, and the
//!   largest directional albedo of the result (a physical BRDF reflects no
//!   more than it receives: at most 1).
//! - [`Confidence`]: the GP's predictive variance `1 - k(x)^T K^-1 k(x)`
//!   (the kernel has unit signal variance, so 0 at a material and 1 where
//!   the data say nothing), and the sum of the weights.
//! - [`BlendRule`]: the GP's weights as they are, or moved just far enough
//!   towards the kernel's convex weights `k / sum(k)` that no measured value
//!   goes negative.
//!
//! A full [`Plausibility`] reads the whole store once (as a table does); the
//! confidence costs nothing beyond the weights.

use brdf_merl::directional::{INCIDENCE_DEGREES, largest};
use rayon::prelude::*;
use serde::Serialize;

use brdf_merl::MerlTable;

use crate::error::Result;
use crate::model::Model;
use crate::model::blend::reconstruct::Blend;

/// Rows a worker handles at once (fixed, so sums do not depend on the thread
/// count; the table's, so [`Blend::table_and_plausibility`] sums alike).
const CHUNK: usize = crate::model::blend::reconstruct::TABLE_CHUNK;

/// Above this predictive variance (out of the prior's 1) a point is reported
/// as one where the model knows little: the data explain less than half of
/// what the material there could be.
pub const LOW_CONFIDENCE_VARIANCE: f64 = 0.5;

/// How a latent point's weights are formed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BlendRule {
    /// The GP's mean: `w = K^-1 k(x)`, the paper's reconstruction. Between
    /// dissimilar materials its weights take mixed signs and the blend can
    /// go negative; the inverse transform then clamps it.
    Gp,
    /// In each `theta_h` bin `b` of the table, `w' = w + t_b (v - w)`, `v`
    /// the convex weights of a narrower kernel
    /// ([`crate::loo::CONVEX_LENGTH_RATIO`]), with the smallest `t_b` of
    /// [`crate::loo::STEPS`] for which the clamp removes at most
    /// [`crate::loo::CLAMP_BUDGET`] of that bin's cosine-weighted
    /// reflectance: the GP's weights wherever they are plausible, and the
    /// least step along the segment to the convex blend (plausible by
    /// construction: a convex blend of non-negative values) only in the
    /// bins where they are not. Should the largest directional albedo of
    /// the result exceed 1, every bin's step is then raised to the smallest
    /// floor of the steps that brings it to 1 or below (the convex blend is
    /// a mean of the materials, so it reflects no more than they do). Costs
    /// one extra pass over the store per latent point.
    Plausible,
    /// The GP's blend, each value lifted onto a soft floor under the convex
    /// blend's (the convex weights `v` of [`BlendRule::Plausible`]): a row
    /// with GP value `g` and convex value `c` becomes
    /// `c h(g / c)`, `h` a smooth maximum of `g / c` and
    /// [`crate::model::blend::soft_floor::FLOOR_SHARE`] ([`crate::model::blend::soft_floor`]). No
    /// value is ever clamped, values well above the floor keep the GP's,
    /// and each value depends on the point's two weight vectors alone: no
    /// pass over the store, and the material varies smoothly over the map.
    /// The default: what `reconstruct`, `eval`, the map and every binding
    /// give unless asked for another rule.
    #[default]
    Floor,
}

impl BlendRule {
    /// The name used on the command line and in records.
    pub fn name(self) -> &'static str {
        match self {
            BlendRule::Gp => "gp",
            BlendRule::Plausible => "plausible",
            BlendRule::Floor => "floor",
        }
    }

    /// Parse a [`BlendRule::name`].
    pub fn parse(s: &str) -> Option<BlendRule> {
        [BlendRule::Gp, BlendRule::Plausible, BlendRule::Floor]
            .into_iter()
            .find(|r| r.name() == s)
    }
}

/// How physical the material of a blend is (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Plausibility {
    /// Share of the cosine-weighted reflectance the clamp removes:
    /// `sum max(-f, 0) c / sum |f| c` over measured bins and channels, with
    /// `f` before the clamp and `c = cos(theta_i) cos(theta_o)`.
    pub clamped_reflectance: f64,
    /// Share of measured values (bins x channels) below zero before the clamp.
    pub clamped_values: f64,
    /// Largest directional albedo of the clamped material, over channels and
    /// the incidence angles of [`brdf_merl::directional::INCIDENCE_DEGREES`].
    pub max_albedo: f64,
    /// The incidence (degrees from the normal) of `max_albedo`.
    pub max_albedo_incidence: f64,
}

impl Plausibility {
    /// Does the material meet the plausibility bar: nothing clamped beyond
    /// 1% of its reflectance and no directional albedo above 1?
    pub fn is_plausible(&self) -> bool {
        self.clamped_reflectance <= 0.01 && self.max_albedo <= 1.0
    }
}

/// What the model knows at a latent point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Confidence {
    /// The GP's predictive variance `1 - k^T K^-1 k`, in units of the prior:
    /// 0 at an input material, 1 far from all of them.
    pub variance: f64,
    /// The sum of the blend's weights (about 1 among the data, towards 0 far
    /// from it, where the blend falls back to the mean material).
    pub weight_sum: f64,
}

impl Confidence {
    /// The model knows little here ([`LOW_CONFIDENCE_VARIANCE`]).
    pub fn is_low(&self) -> bool {
        self.variance > LOW_CONFIDENCE_VARIANCE
    }
}

/// The largest directional albedo of each of `blends`, the bits of
/// [`Blend::largest_albedo`] (point queries at the bins of the
/// directional rule only): each
/// incidence's sums run over the rule's bins in the rule's order for
/// every blend, as [`brdf_merl::DirectionalRule::integrate`] sums them,
/// but a bin's rows are read once for all the blends (while they are in
/// cache) rather than once a blend. The incidence angles in parallel.
/// With each albedo, its incidence (degrees from the normal).
pub(crate) fn max_albedos_of(model: &Model, blends: &[&Blend<'_>]) -> Vec<(f64, f64)> {
    let rule = model.directional_rule();
    let m = blends.len();
    let by_incidence: Vec<Vec<[f64; 3]>> = (0..INCIDENCE_DEGREES.len())
        .into_par_iter()
        .map(|k| {
            let entries = rule.start_of(k)..rule.start_of(k + 1);
            let mut acc = vec![[0.0f64; 3]; m];
            for (&b, &w) in rule.bins()[entries.clone()]
                .iter()
                .zip(&rule.weights()[entries])
            {
                for (acc, blend) in acc.iter_mut().zip(blends) {
                    let v = blend.rgb_once(b as usize).unwrap_or([0.0; 3]);
                    for c in 0..3 {
                        acc[c] += w * v[c];
                    }
                }
            }
            acc
        })
        .collect();
    (0..m)
        .map(|j| {
            let albedos: Vec<[f64; 3]> = by_incidence.iter().map(|a| a[j]).collect();
            largest(&albedos)
        })
        .collect()
}

impl Blend<'_> {
    /// What the model knows at this point.
    pub fn confidence(&self) -> Confidence {
        let kw: f64 = self
            .kernel()
            .iter()
            .zip(self.gp_weights())
            .map(|(k, w)| k * w)
            .sum();
        Confidence {
            variance: (1.0 - kw).clamp(0.0, 1.0),
            weight_sum: self.weights().iter().sum(),
        }
    }

    /// How physical this material is: one pass over the store for the clamp
    /// figures, and point queries at the bins of the directional-albedo rule.
    /// [`CoreError::FileChanged`](crate::CoreError::FileChanged) if the
    /// store changed under the pass.
    pub fn plausibility(&self) -> Result<Plausibility> {
        let model = self.model();
        model.store().verify_cheap()?;
        let store = model.store();
        let (rows, bins) = (store.rows(), model.dims().bins());
        let unmeasured = store.unmeasured();
        let cosines = model.cosine_products();
        let parts: Vec<ClampSums> = (0..rows.div_ceil(CHUNK))
            .into_par_iter()
            .map_init(
                || vec![0.0; CHUNK],
                |t, k| {
                    let r0 = k * CHUNK;
                    let len = CHUNK.min(rows - r0);
                    self.transformed_rows(r0, &mut t[..len]);
                    self.clamp_sums(r0, &t[..len], unmeasured, bins, cosines)
                },
            )
            .collect();
        model.verify()?;
        Ok(self.figures(&parts))
    }

    /// [`Blend::table`] and [`Blend::plausibility`] from one pass over the
    /// store: the same table, and the same figures to the bit (the clamp's
    /// sums come in the same chunks, merged in the same order).
    pub fn table_and_plausibility(&self) -> Result<(MerlTable, Plausibility)> {
        let model = self.model();
        let (store, bins) = (model.store(), model.dims().bins());
        let (unmeasured, cosines) = (store.unmeasured(), model.cosine_products());
        let (table, parts) =
            self.table_with(|r0, t| self.clamp_sums(r0, t, unmeasured, bins, cosines))?;
        Ok((table, self.figures(&parts)))
    }

    /// The clamp's sums over transformed values `t` of rows `r0 ..`.
    fn clamp_sums(
        &self,
        r0: usize,
        t: &[f64],
        unmeasured: &[u8],
        bins: usize,
        cosines: &[f64],
    ) -> ClampSums {
        let transform = self.model().transform();
        let mut acc = ClampSums::default();
        for (row, &v) in (r0..r0 + t.len()).zip(t) {
            if unmeasured[row] == 0 {
                let bin = row % bins;
                acc.add(transform.inverse_form(bin).unclamped(v), cosines[bin]);
            }
        }
        acc
    }

    /// The figures from the chunks' sums, merged in order, and the largest
    /// directional albedo.
    fn figures(&self, parts: &[ClampSums]) -> Plausibility {
        let mut sums = ClampSums::default();
        parts.iter().for_each(|p| sums.merge(p));
        let (max_albedo, max_albedo_incidence) = self.largest_albedo();
        sums.figures(max_albedo, max_albedo_incidence)
    }

    /// The largest directional albedo of this material and its incidence
    /// (degrees from the normal): [`Blend::plausibility`]'s albedo figures
    /// without its pass over the store (point queries at the bins of the
    /// directional-albedo rule only).
    pub fn largest_albedo(&self) -> (f64, f64) {
        let rule = self.model().directional_rule();
        largest(&rule.integrate(|b| self.rgb_once(b).unwrap_or([0.0; 3])))
    }
}

/// The clamp's sums over the measured values of one material: what
/// [`Plausibility`]'s shares are formed from.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ClampSums {
    /// Cosine-weighted reflectance the clamp removes.
    removed: f64,
    /// Cosine-weighted reflectance before the clamp, in absolute value.
    total: f64,
    /// Values below zero.
    negative: f64,
    /// Values summed.
    values: f64,
}

impl ClampSums {
    /// Count value `f` (before the clamp) of a bin with cosine product `c`.
    #[inline]
    pub(crate) fn add(&mut self, f: f64, c: f64) {
        self.removed += (-f).max(0.0) * c;
        self.total += f.abs() * c;
        self.negative += f64::from(u8::from(f < 0.0));
        self.values += 1.0;
    }

    /// Add the sums of another part of the values.
    pub(crate) fn merge(&mut self, other: &ClampSums) {
        self.removed += other.removed;
        self.total += other.total;
        self.negative += other.negative;
        self.values += other.values;
    }

    /// The figures, with the largest directional albedo found elsewhere.
    pub(crate) fn figures(&self, max_albedo: f64, max_albedo_incidence: f64) -> Plausibility {
        let share = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
        Plausibility {
            clamped_reflectance: share(self.removed, self.total),
            clamped_values: share(self.negative, self.values),
            max_albedo,
            max_albedo_incidence,
        }
    }
}
