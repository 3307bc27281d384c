//! How far above the convex blend the default rule may reach at a point so
//! that its material reflects no more light than 1 (or than the brightest
//! material, where a material itself reflects more) at any incidence.
//!
//! The default rule ([`crate::BlendRule::Floor`]) caps every value of its
//! material, in transformed space, at `c + r (top - c)`: `c` the convex
//! blend's value, `top` the brightest material's, and `r` in `[0, 1]` this
//! module's reach (one per channel and point). Why that bounds the
//! directional albedo: the inverse transform `F` is convex and increasing
//! in every bin (`max(0, s t)` or `max(0, s (e^t - 1))`), so
//!
//! ```text
//! F(c + r (top - c)) <= (1 - r) F(c) + r F(top)
//! F(c) = F(sum_i v_i t_i) <= sum_i v_i F(t_i)      (v the convex weights)
//! ```
//!
//! and a directional albedo `A(theta) = sum_b w_b f_b` of the material is at
//! most `(1 - r) sum_i v_i A_i(theta) + r A_top(theta)`, where `A_i` is
//! material `i`'s and `A_top` that of the table of brightest values. Both
//! are fixed by the store; [`EnergyBound::reach`] takes the largest `r`
//! that keeps this at or under the bound `max(1, max_i A_i(theta))` at each
//! incidence of [`DirectionalRule`] (a hair under it: rounding never takes
//! a blend over). The reach is 1 wherever the table of brightest values
//! stays under the bound, and it shrinks only near the materials that are
//! bright at grazing incidence, where the envelope of several would be
//! brighter than any one. At a material's own point the convex blend is
//! that material alone, which is under the cap whatever the reach: the rule
//! still gives every material back.

use brdf_merl::directional::{DirectionalRule, INCIDENCE_DEGREES};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::Store;
use crate::data::transform::InverseForm;
use crate::simd::fastexp::exp;

/// Incidences times channels: the albedos the bound is kept at.
const KC: usize = INCIDENCE_DEGREES.len() * 3;

/// Entries of the directional rule a worker sums at once (fixed, so that
/// the sums do not depend on the thread count).
const CHUNK: usize = 2048;

/// The share of the bound a blend is kept under, so that rounding in the
/// blend's sums cannot take it over.
const MARGIN: f64 = 1e-9;

/// What [`EnergyBound::reach`] needs: the materials' directional albedos
/// and, where the brightest values' table goes over the bound, its albedo.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct EnergyBound {
    /// Material `i`'s directional albedo at incidence `k`, channel `c`:
    /// `albedo[i * KC + 3 k + c]`.
    albedo: Vec<f64>,
    /// The incidences and channels where a blend could go over the bound.
    binding: Vec<Binding>,
}

/// One incidence and channel at which the brightest values' table reflects
/// more than the bound.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
struct Binding {
    /// `3 k + c`.
    kc: usize,
    /// The brightest values' directional albedo there.
    top: f64,
    /// What no blend may exceed there (less the margin).
    bound: f64,
}

impl EnergyBound {
    /// The bound of the materials in `store`: one pass over the store rows
    /// the directional rule reads (3 of them per entry of the rule, about
    /// 4% of the store at full resolution), in parallel, summed in a fixed
    /// order.
    pub(crate) fn of(store: &Store) -> EnergyBound {
        let (dims, n) = (store.dims(), store.n());
        let rule = DirectionalRule::new(dims);
        let transform = store.transform().build(dims);
        let (mean, unmeasured) = (store.mean(), store.unmeasured());
        let entries: Vec<(usize, (u32, f64))> = rule
            .incidences()
            .zip(
                rule.bins()
                    .iter()
                    .copied()
                    .zip(rule.weights().iter().copied()),
            )
            .collect();
        // Each chunk's sums: the materials' albedos, then the brightest's.
        let parts: Vec<Vec<f64>> = entries
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut acc = vec![0.0f64; (n + 1) * KC];
                let mut z = vec![0.0f64; n];
                for &(k, (bin, w)) in chunk {
                    let bin = bin as usize;
                    for c in 0..3 {
                        let row = c * dims.bins() + bin;
                        if unmeasured[row] != 0 {
                            continue;
                        }
                        store.copy_rows(row, &mut z);
                        let (kc, m) = (3 * k + c, mean[row]);
                        let top = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                        // The inverse transform in its closed form, a
                        // vectorisable loop per row.
                        let (scale, exponential) = match transform.inverse_form(bin) {
                            InverseForm::Linear(s) => (s, false),
                            InverseForm::Exp(s) => (s, true),
                        };
                        let value = |t: f64| {
                            let u = if exponential { exp(t) - 1.0 } else { t };
                            (scale * u).max(0.0)
                        };
                        for (a, &zi) in acc.iter_mut().skip(kc).step_by(KC).zip(&z) {
                            *a += w * value(m + zi);
                        }
                        acc[n * KC + kc] += w * value(m + top);
                    }
                }
                acc
            })
            .collect();
        let mut sums = vec![0.0f64; (n + 1) * KC];
        for part in parts {
            sums.iter_mut().zip(part).for_each(|(s, p)| *s += p);
        }
        let albedo = sums[..n * KC].to_vec();
        let binding = (0..KC)
            .filter_map(|kc| {
                let brightest = (0..n).map(|i| albedo[i * KC + kc]).fold(0.0, f64::max);
                let bound = brightest.max(1.0) * (1.0 - MARGIN);
                let top = sums[n * KC + kc];
                (top > bound).then_some(Binding { kc, top, bound })
            })
            .collect();
        EnergyBound { albedo, binding }
    }

    /// Whether this bound can serve a store of `n` materials (a bound read
    /// from a model file is checked before it is used).
    pub(crate) fn fits(&self, n: usize) -> bool {
        self.albedo.len() == n * KC
            && self.albedo.iter().all(|a| a.is_finite() && *a >= 0.0)
            && self
                .binding
                .iter()
                .all(|b| b.kc < KC && b.top.is_finite() && b.bound.is_finite() && b.top > b.bound)
    }

    /// The reach per channel of a point with convex weights `convex` (one
    /// per material, non-negative, summing to 1): the largest `r` in
    /// `[0, 1]` for which `(1 - r) sum_i v_i A_i + r A_top` stays under the
    /// bound at every incidence.
    pub(crate) fn reach(&self, convex: &[f64]) -> [f64; 3] {
        let mut reach = [1.0f64; 3];
        for b in &self.binding {
            let a: f64 = convex
                .iter()
                .enumerate()
                .map(|(i, v)| v * self.albedo[i * KC + b.kc])
                .sum();
            let r = if b.top > a {
                ((b.bound - a) / (b.top - a)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            let c = b.kc % 3;
            reach[c] = reach[c].min(r);
        }
        reach
    }
}
