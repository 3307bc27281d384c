//! The weights of one pass over the store at many latent points: the GP's
//! `K^-1 k(x)` of every point side by side, and under the soft floor the
//! convex weights and reaches beside them. The exact albedos
//! (`crate::maps::exact_albedos`) and the plausibility at many points
//! ([`super::plausibility_sweep`]) read the store once with them.

use faer::Mat;

use crate::error::{CoreError, Result};
use crate::model::Model;
use crate::model::blend::plausibility::BlendRule;
use crate::model::blend::plausible_budget::convex_weights_at;

/// The weights of a pass over the store at `points` ([`PassWeights`]).
pub(crate) fn pass_weights(model: &Model, points: &[[f64; 2]], floor: bool) -> Result<PassWeights> {
    for p in points {
        model.check_point(p)?;
    }
    let (latent, kernel) = (model.latent(), model.file().kernel);
    let (n, m) = (latent.nrows(), points.len());
    let kx = Mat::from_fn(n, m, |i, j| {
        kernel.eval(&[latent[(i, 0)], latent[(i, 1)]], &points[j])
    });
    let w = model.llt_solve(&kx);
    let a: Vec<f64> = (0..n)
        .flat_map(|t| (0..m).map(move |j| (t, j)))
        .map(|(t, j)| w[(t, j)])
        .collect();
    let mut out = PassWeights {
        gp: a,
        convex: Vec::new(),
        reach: Default::default(),
    };
    if floor {
        let v = convex_weights_at(model, points);
        out.convex = (0..n)
            .flat_map(|t| (0..m).map(move |j| (t, j)))
            .map(|(t, j)| v[j][t])
            .collect();
        let bound = model.store().energy_bound();
        let reach: Vec<[f64; 3]> = v.iter().map(|v| bound.reach(v)).collect();
        out.reach = [0, 1, 2].map(|c| reach.iter().map(|r| r[c]).collect());
    }
    Ok(out)
}

/// The weights of a pass over the store at `m` points.
pub(crate) struct PassWeights {
    /// The GP's `K^-1 k(x)` of every point laid out `n x m` row-major
    /// (material `t`, point `j` at `t m + j`), so that a block of store rows
    /// `Z_block` (`len x n`) gives the points' values as one product.
    pub(crate) gp: Vec<f64>,
    /// Under the floor, the convex weights laid out alike (else empty).
    pub(crate) convex: Vec<f64>,
    /// Under the floor, each channel's reach at every point
    /// ([`crate::model::blend::soft_floor::reach_cap`]; else empty).
    pub(crate) reach: [Vec<f64>; 3],
}

/// Whether the map and the exact pass put every value of `rule`'s material on
/// its soft floor; the plausible rule's steps are not a function of the
/// point's weights, so no map draws them.
pub(crate) fn floor_of(rule: BlendRule) -> Result<bool> {
    match rule {
        BlendRule::Gp => Ok(false),
        BlendRule::Floor => Ok(true),
        BlendRule::Plausible => Err(CoreError::BadQuery(
            "the plausible rule's albedo has no map (its steps need a pass over the store per \
             point): use the gp or floor rule"
                .into(),
        )),
    }
}
