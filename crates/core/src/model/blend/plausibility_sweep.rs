//! The plausibility figures of many latent points in one pass over the
//! store: what the report's grid and a sweep of random points ask for.
//!
//! [`Blend::plausibility`] reads the whole store for one point. For the
//! GP's blend and the soft floor the values of a block of store rows at
//! every point are one product with the points' weights (as the exact
//! albedos are, [`crate::maps::exact_albedos`]), so `m` points cost one pass and a
//! product instead of `m` passes. The largest directional albedo reads only
//! the directional rule's bins, all the points from one read of each
//! ([`crate::Atlas::largest_albedos`]).

use brdf_merl::directional::{INCIDENCE_DEGREES, largest};
use rayon::prelude::*;

use crate::dense::product::matmul;
use crate::error::Result;
use crate::model::Model;
use crate::model::blend::pass_bins::Every;
use crate::model::blend::pass_weights::pass_weights;
use crate::model::blend::pass_weights::{PassWeights, floor_of};
use crate::model::blend::plausibility::max_albedos_of;
use crate::model::blend::plausibility::{BlendRule, ClampSums, Plausibility};
use crate::model::blend::plausible_steps::plausible_blends;
use crate::model::blend::reconstruct::Blend;
use crate::model::blend::soft_floor::{floor_points, top_of};
use crate::simd::fold::{GROUPS, ordered_blocks};

/// Rows of the store a step of the pass multiplies at once.
const BLOCK: usize = 256;

/// [`Blend::plausibility`](crate::Blend::plausibility) of the material
/// `rule` forms at each of `points`. The GP's blend and the soft floor
/// take one pass over the store for all the points; the plausible
/// rule's steps need passes of their own ([`crate::Atlas::plausible_blends`]
/// makes all the points' blends in one), then one more pass for all
/// the points' figures (in each `theta_h` bin a blend's weights are
/// fixed, so that pass is a product with them too). The
/// sums run in a fixed order: the answer does not depend on the thread
/// count, and equals the one-point figures to rounding. The clamp's
/// figures are summed over the bins `every` keeps ([`Every::BIN`] for
/// the one-point figures; a subsample such as [`Every::EIGHTH`] for a
/// cheaper estimate of the same shares); the plausible rule's steps
/// and the largest albedo are the model's whatever `every`.
pub(crate) fn plausibilities(
    model: &Model,
    points: &[[f64; 2]],
    rule: BlendRule,
    every: Every,
) -> Result<Vec<Plausibility>> {
    if rule == BlendRule::Plausible {
        let points: Vec<Vec<f64>> = points.iter().map(|p| p.to_vec()).collect();
        let blends = plausible_blends(model, &points)?;
        model.store().verify_cheap()?;
        let sums = banded_clamp_sums(model, &blends, every);
        let blends: Vec<&Blend<'_>> = blends.iter().collect();
        let out = sums
            .iter()
            .zip(max_albedos_of(model, &blends))
            .map(|(s, (max_albedo, incidence))| s.figures(max_albedo, incidence))
            .collect();
        model.verify()?;
        return Ok(out);
    }
    let floor = floor_of(rule)?;
    let (gp, floored) = clamp_pass(model, points, !floor, floor, every)?;
    let sums = if floor { floored } else { gp };
    figures_of(model, points, rule, &sums)
}

/// [`crate::Atlas::plausibilities`] of the GP's blend and of the soft floor at
/// each of `points`, from one pass over the store for both (the floor
/// is the GP's values lifted): the same figures as two calls.
pub(crate) fn plausibilities_gp_and_floor(
    model: &Model,
    points: &[[f64; 2]],
    every: Every,
) -> Result<(Vec<Plausibility>, Vec<Plausibility>)> {
    let (gp, floored) = clamp_pass(model, points, true, true, every)?;
    Ok((
        figures_of(model, points, BlendRule::Gp, &gp)?,
        figures_of(model, points, BlendRule::Floor, &floored)?,
    ))
}

/// The figures of `rule`'s material at `points` from their clamp sums,
/// with the largest albedos from one more read of the directional rule's
/// rows.
fn figures_of(
    model: &Model,
    points: &[[f64; 2]],
    rule: BlendRule,
    sums: &[ClampSums],
) -> Result<Vec<Plausibility>> {
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let albedos = largest_albedos(model, points, rule)?;
    let out = sums
        .iter()
        .zip(albedos)
        .map(|(s, (max_albedo, incidence))| s.figures(max_albedo, incidence))
        .collect();
    model.verify()?;
    Ok(out)
}

/// The clamp's sums at each of `points` of the GP's blend (if `gp`) and
/// of the soft floor (if `floor`; else empty), from one pass over the
/// rows of the store that `every` keeps.
fn clamp_pass(
    model: &Model,
    points: &[[f64; 2]],
    gp: bool,
    floor: bool,
    every: Every,
) -> Result<(Vec<ClampSums>, Vec<ClampSums>)> {
    model.store().verify_cheap()?;
    let m = points.len();
    if m == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    let PassWeights {
        gp: a,
        convex: av,
        reach,
    } = pass_weights(model, points, floor)?;
    let store = model.store();
    let (n, bins) = (store.n(), model.dims().bins());
    let (mean, unmeasured) = (store.mean(), store.unmeasured());
    let cosines = model.cosine_products();
    let transform = model.transform();
    let (gm, fm) = (if gp { m } else { 0 }, if floor { m } else { 0 });
    let kept = every.rows(model.dims(), store.rows());
    let passed = kept.as_ref().map_or(store.rows(), Vec::len);
    let parts = ordered_blocks(
        passed,
        BLOCK,
        GROUPS,
        || {
            (
                vec![ClampSums::default(); gm],
                vec![ClampSums::default(); fm],
            )
        },
        |(gacc, facc), range| {
            let len = range.len();
            let listed = kept.as_ref().map(|k| &k[range.clone()]);
            let mut z = vec![0.0f64; n * len];
            store.copy_listed(range.start, listed, &mut z);
            let mut t = vec![0.0f64; m * len];
            matmul(&mut t, &a, &z, n);
            let mut v = Vec::new();
            if floor {
                v.resize(m * len, 0.0);
                matmul(&mut v, &av, &z, n);
            }
            for k in 0..len {
                let row = listed.map_or(range.start + k, |l| l[k] as usize);
                if unmeasured[row] != 0 {
                    continue;
                }
                let (mu, bin) = (mean[row], row % bins);
                let (c, form) = (cosines[bin], transform.inverse_form(bin));
                let t = &mut t[k * m..(k + 1) * m];
                for (s, &t) in gacc.iter_mut().zip(t.iter()) {
                    s.add(form.unclamped(mu + t), c);
                }
                if floor {
                    let top = top_of(&z[k * n..(k + 1) * n]);
                    floor_points(t, &v[k * m..(k + 1) * m], mu, top, &reach[row / bins]);
                    for (s, &t) in facc.iter_mut().zip(t.iter()) {
                        s.add(form.unclamped(mu + t), c);
                    }
                }
            }
        },
    );
    let (mut gsums, mut fsums) = (
        vec![ClampSums::default(); gm],
        vec![ClampSums::default(); fm],
    );
    for (g, f) in parts {
        gsums.iter_mut().zip(&g).for_each(|(s, p)| s.merge(p));
        fsums.iter_mut().zip(&f).for_each(|(s, p)| s.merge(p));
    }
    Ok((gsums, fsums))
}

/// The clamp's sums of `blends`, none of them on the soft floor (the
/// GP's, or the plausible rule's weights per `theta_h` bin), from one
/// pass over the store: in the rows of one `theta_h` bin of one channel
/// every blend's weights are fixed, so a block of them is one product
/// with the blends' weights. One task a bin and channel, merged in
/// order: the sums do not depend on the thread count. Only the rows
/// `every` keeps are read.
fn banded_clamp_sums(model: &Model, blends: &[Blend<'_>], every: Every) -> Vec<ClampSums> {
    let m = blends.len();
    let store = model.store();
    let (n, dims) = (store.n(), model.dims());
    let (bins, per) = (dims.bins(), dims.theta_d * dims.phi_d);
    let (mean, unmeasured) = (store.mean(), store.unmeasured());
    let cosines = model.cosine_products();
    let transform = model.transform();
    let parts: Vec<Vec<ClampSums>> = (0..3 * dims.theta_h)
        .into_par_iter()
        .map(|task| {
            let (c, band) = (task / dims.theta_h, task % dims.theta_h);
            let start = c * bins + band * per;
            // The blends' weights in this bin, laid out as the pass's
            // (material t, blend j at t m + j).
            let a: Vec<f64> = (0..n)
                .flat_map(|t| blends.iter().map(move |b| b.weights_of_row(start, bins)[t]))
                .collect();
            let mut acc = vec![ClampSums::default(); m];
            let (mut z, mut t) = (Vec::new(), Vec::new());
            // The band's kept rows (none listed when all are kept).
            let kept: Option<Vec<u32>> =
                (!every.keeps_every_bin()).then(|| every.band_rows(dims, start));
            let count = kept.as_ref().map_or(per, Vec::len);
            for from in (0..count).step_by(BLOCK) {
                let len = BLOCK.min(count - from);
                let listed = kept.as_ref().map(|k| &k[from..from + len]);
                z.resize(n * len, 0.0);
                t.resize(m * len, 0.0);
                store.copy_listed(start + from, listed, &mut z);
                matmul(&mut t, &a, &z, n);
                for k in 0..len {
                    let row = listed.map_or(start + from + k, |l| l[k] as usize);
                    if unmeasured[row] != 0 {
                        continue;
                    }
                    let (mu, bin) = (mean[row], row % bins);
                    let (cos, form) = (cosines[bin], transform.inverse_form(bin));
                    for (s, &t) in acc.iter_mut().zip(&t[k * m..(k + 1) * m]) {
                        s.add(form.unclamped(mu + t), cos);
                    }
                }
            }
            acc
        })
        .collect();
    let mut sums = vec![ClampSums::default(); m];
    for part in parts {
        sums.iter_mut().zip(&part).for_each(|(s, p)| s.merge(p));
    }
    sums
}

/// [`Blend::largest_albedo`](crate::Blend::largest_albedo) of the
/// material `rule` forms at each of `points` (the GP's blend or the soft
/// floor; the plausible rule is refused, as by
/// [`crate::Atlas::exact_albedos`]): the largest directional albedo and
/// its incidence (degrees). Each store row the directional rule reads
/// is read once for all the points, and the sums run in a fixed order:
/// the answer does not depend on the thread count, and equals the
/// one-point figures to rounding.
pub(crate) fn largest_albedos(
    model: &Model,
    points: &[[f64; 2]],
    rule: BlendRule,
) -> Result<Vec<(f64, f64)>> {
    let floor = floor_of(rule)?;
    model.store().verify_cheap()?;
    let m = points.len();
    if m == 0 {
        return Ok(Vec::new());
    }
    let PassWeights {
        gp: a,
        convex: av,
        reach,
    } = pass_weights(model, points, floor)?;
    let store = model.store();
    let (n, bins) = (store.n(), model.dims().bins());
    let (mean, unmeasured) = (store.mean(), store.unmeasured());
    let transform = model.transform();
    let directional = model.directional_rule();
    let (rule_bins, weights) = (directional.bins(), directional.weights());
    let angles = INCIDENCE_DEGREES.len();
    let incidence: Vec<u8> = directional.incidences().map(|k| k as u8).collect();
    // Sums laid out [incidence][channel][point].
    let parts = ordered_blocks(
        rule_bins.len(),
        BLOCK / 4,
        GROUPS,
        || vec![0.0f64; angles * 3 * m],
        |acc, range| {
            let len = range.len();
            let mut z = vec![0.0f64; 3 * len * n];
            for (k, e) in range.clone().enumerate() {
                let bin = rule_bins[e] as usize;
                for c in 0..3 {
                    let at = (3 * k + c) * n;
                    store.copy_rows(c * bins + bin, &mut z[at..at + n]);
                }
            }
            let mut t = vec![0.0f64; 3 * len * m];
            matmul(&mut t, &a, &z, n);
            let mut v = Vec::new();
            if floor {
                v.resize(3 * len * m, 0.0);
                matmul(&mut v, &av, &z, n);
            }
            for (k, e) in range.enumerate() {
                let bin = rule_bins[e] as usize;
                // A bin with a channel never measured counts as 0, as
                // in the one-point rule.
                if (0..3).any(|c| unmeasured[c * bins + bin] != 0) {
                    continue;
                }
                let (w, form) = (weights[e], transform.inverse_form(bin));
                for c in 0..3 {
                    let (row, at) = (c * bins + bin, (3 * k + c) * m);
                    let mu = mean[row];
                    let t = &mut t[at..at + m];
                    if floor {
                        let top = top_of(&z[(3 * k + c) * n..(3 * k + c + 1) * n]);
                        floor_points(t, &v[at..at + m], mu, top, &reach[c]);
                    }
                    let sums = &mut acc[(incidence[e] as usize * 3 + c) * m..][..m];
                    for (s, &t) in sums.iter_mut().zip(t.iter()) {
                        *s += w * form.unclamped(mu + t).max(0.0);
                    }
                }
            }
        },
    );
    let mut sums = vec![0.0f64; angles * 3 * m];
    for part in parts {
        sums.iter_mut().zip(&part).for_each(|(s, p)| *s += p);
    }
    model.verify()?;
    Ok((0..m)
        .map(|j| {
            let albedos: Vec<[f64; 3]> = (0..angles)
                .map(|k| [0, 1, 2].map(|c| sums[(k * 3 + c) * m + j]))
                .collect();
            largest(&albedos)
        })
        .collect())
}
