//! Fidelity: does a material's own marker give it back, and how well is each
//! material predicted from the others, in the errors a person sees.
//!
//! Two measures sit beside the older RMSE of `ln(1 + v)` (`v = f cos_i
//! cos_o`), which is linear where `v` is small and so blind to dark
//! materials: the **relative albedo error** per channel (albedo by the
//! dense rule over the bins every output is scored on), and the
//! **log-relative table error**, the RMSE over measured bins of
//! `ln((v' + e) / (v + e))`, `e =` [`LOG_REL_OFFSET`], in which black
//! fabric weighs as much as a chrome highlight.
//!
//! Each is taken for two predictions of every material `i`, both linear
//! combinations of the stored rows ([`super::loo`]), so one pass over the
//! store gives them all:
//!
//! - **own point**: the model's material at `x_i`, the GP's blend
//!   `k(x_i)^T K^-1 Z = (I - mu K^-1) Z` (no noise on `k`) lifted by the
//!   default rule ([`crate::BlendRule::Floor`]) onto its floor under the
//!   convex blend at `x_i`; and the GP's blend alone beside it;
//! - **leave-one-out**: the same rule with `i` left out of both blends
//!   (the GP's closed form `z_i - (K^-1 z)_i / (K^-1)_ii`, no refit).

use brdf_merl::MerlTable;
use brdf_merl::albedo::Quadrature;
use faer::{Mat, MatRef};

use crate::data::store::Store;
use crate::error::Result;
use crate::eval::loo::{Evaluation, Every, Mix, Mixing, evaluate_some};
use crate::eval::nonneg::{convex_predictor, convex_rows};
use crate::eval::predictors::{gp_predictor, needs_two};
use crate::gplvm::kernel::{Kernel, rows_of};
use crate::gplvm::likelihood::factor;
use crate::progress::Progress;

pub use crate::eval::loo::LOG_REL_OFFSET;
pub use crate::model::judged::{Fidelity, GIVES_BACK, Judged, MARKER_RADIUS, Spread, Summary};

/// The bins `fit` judges its own points on, and `report` its settings:
/// every 8th phi_d bin, within 0.03% of the dense albedo.
pub const JUDGED_BINS: Every = Every::EIGHTH;

/// The GP's blend at every material's own point: `I - mu K^-1`.
pub fn own_point_predictor(kernel: &Kernel, latent: MatRef<'_, f64>) -> Result<Mat<f64>> {
    let n = latent.nrows();
    let (_, a) = factor(kernel.matrix(latent).as_ref(), "the own-point blend")?;
    Ok(Mat::from_fn(n, n, |i, j| {
        f64::from(u8::from(i == j)) - kernel.noise * a[(i, j)]
    }))
}

/// The fidelity of the model with latent points `latent` and `kernel` over
/// `store`, in one pass over the bins `every` keeps; leave-one-out too when
/// `held_out` (it needs two materials or more).
pub fn fidelity(
    store: &Store,
    latent: MatRef<'_, f64>,
    kernel: &Kernel,
    held_out: bool,
    every: Every,
    progress: &dyn Progress,
) -> Result<Fidelity> {
    // Outputs: the matrix predictors, then the mixes; a convex blend only
    // feeds its mix. At the own points it is the material itself unless
    // two materials share a point: then it takes a product of its own.
    let convex = convex_rows(kernel, latent, false);
    let n = latent.nrows();
    let itself = (0..n).all(|i| (0..n).all(|j| convex[(i, j)] == f64::from(u8::from(i == j))));
    let mut predictors = vec![own_point_predictor(kernel, latent)?];
    let mut scored = vec![true];
    let own_floor = if itself {
        Mix {
            from: 0,
            towards: 0,
            how: Mixing::FloorOnSelf,
        }
    } else {
        predictors.push(convex);
        scored.push(false);
        Mix {
            from: 0,
            towards: 1,
            how: Mixing::Floor,
        }
    };
    let mut mixes = vec![own_floor];
    let gp_held_out = predictors.len();
    if held_out {
        needs_two(n)?;
        predictors.push(gp_predictor(kernel, latent, false)?);
        predictors.push(convex_predictor(kernel, latent)?);
        scored.extend([true, false]);
        mixes.push(Mix {
            from: gp_held_out,
            towards: gp_held_out + 1,
            how: Mixing::Floor,
        });
    }
    scored.extend(mixes.iter().map(|_| true));
    let ev = evaluate_some(store, &predictors, &mixes, Some(&scored), every, progress)?;
    let count = predictors.len();
    let judged = |m: usize| judge(&ev, m);
    Ok(Fidelity {
        own: judged(count),
        own_gp: judged(0),
        held_out: held_out.then(|| judged(count + 1)),
        held_out_gp: held_out.then(|| judged(gp_held_out)),
    })
}

/// Output `m` of an evaluation, material by material.
fn judge(ev: &Evaluation, m: usize) -> Vec<Judged> {
    let e = &ev.errors[m];
    (0..ev.albedo.len())
        .map(|i| Judged {
            albedo: ev.albedo[i],
            predicted: e.albedo[i],
            log_rel: e.log_rel_rmse(i, ev.scored_rows),
            log: e.log_rmse(i, ev.scored_rows),
        })
        .collect()
}

/// The material `truth` (a MERL table of the model's dims, such as a file
/// [`crate::Located::find`] placed at `x`) judged against the model's
/// material at `x` by the default rule: relative albedo per channel (the
/// dense rule over both full tables) and the table errors over the bins
/// measured in `truth` that are not grazing.
pub fn judge_at(model: &crate::Model, x: &[f64], truth: &MerlTable) -> Result<Judged> {
    let table = model.at(x, crate::BlendRule::Floor)?.table()?;
    Ok(judge_tables(model.albedo_rule(), truth, &table))
}

/// `got` judged against `truth` (tables of the same dims) with the albedo `rule`.
pub fn judge_tables(rule: &Quadrature, truth: &MerlTable, got: &MerlTable) -> Judged {
    let dims = truth.dims();
    let (mut log_rel, mut log, mut count) = (0.0, 0.0, 0usize);
    for bin in 0..dims.bins() {
        let (ci, co) = dims.angles_of(bin).cosines();
        let c = (ci * co).max(0.0);
        if c < 1e-6 {
            continue;
        }
        for ch in 0..3 {
            let Some(t) = truth.value(ch, bin) else {
                continue;
            };
            let g = got.value(ch, bin).unwrap_or(0.0);
            let (v, w) = (t.max(0.0) * c, g.max(0.0) * c);
            let q = ((w + LOG_REL_OFFSET) / (v + LOG_REL_OFFSET)).ln();
            let d = w.ln_1p() - v.ln_1p();
            log_rel += q * q;
            log += d * d;
            count += 1;
        }
    }
    let rms = |s: f64| (s / count.max(1) as f64).sqrt();
    Judged {
        albedo: rule.albedo(truth),
        predicted: rule.albedo(got),
        log_rel: rms(log_rel),
        log: rms(log),
    }
}

/// How far apart the materials land: the median and smallest distance from
/// each latent point to its nearest neighbour, and how many lie within
/// 0.01 of another.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spacing {
    /// Median nearest-neighbour distance.
    pub median: f64,
    /// Smallest nearest-neighbour distance.
    pub smallest: f64,
    /// Materials within 0.01 of another.
    pub close: usize,
}

/// The [`Spacing`] of latent points `latent` (`N x q`, N >= 2).
pub fn spacing(latent: MatRef<'_, f64>) -> Spacing {
    let pts = rows_of(latent);
    let mut nn: Vec<f64> = (0..pts.len())
        .map(|i| {
            (0..pts.len())
                .filter(|&j| j != i)
                .map(|j| {
                    let d2: f64 = pts[i]
                        .iter()
                        .zip(&pts[j])
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum();
                    d2.sqrt()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    nn.sort_by(f64::total_cmp);
    Spacing {
        median: nn.get(nn.len() / 2).copied().unwrap_or(f64::INFINITY),
        smallest: nn.first().copied().unwrap_or(f64::INFINITY),
        close: nn.iter().filter(|&&d| d < 0.01).count(),
    }
}

/// The share of a `k x k` grid over the map's default view where the
/// model's predictive variance is below 0.1: how much of its map the model
/// knows (a 2-D model).
pub fn known_share(model: &crate::Model, k: usize) -> Result<f64> {
    let (v, k) = (crate::View::default(), k.max(2));
    let t = |i: usize| i as f64 / (k - 1) as f64;
    let mut known = 0;
    for a in 0..k {
        for b in 0..k {
            let x = [v.x0 + (v.x1 - v.x0) * t(a), v.y0 + (v.y1 - v.y0) * t(b)];
            known += usize::from(model.at(&x, crate::BlendRule::Gp)?.confidence().variance < 0.1);
        }
    }
    Ok(known as f64 / (k * k) as f64)
}
