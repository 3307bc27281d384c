//! [`BlendRule::Plausible`](crate::BlendRule::Plausible) at many points in
//! one pass over the store.
//!
//! The rule's steps need, for every point and `theta_h` bin, the blend's
//! cosine-weighted reflectance and its clamped part at each of [`STEPS`]
//! ([`Budget`]). Both the GP's blend and the convex one are linear in their
//! weights, so a block of store rows times the `2m` weight vectors of `m`
//! points is one matrix product: the store is read once however many points
//! ask (a swatch sheet's 64, a map's nodes), not once a point.
//!
//! The pass runs over the `theta_h` bins in parallel, one task a bin (its
//! rows of the three channels, in order), so every budget is summed in the
//! same order whatever the thread count, and holds one bin's budgets per
//! task, not one per thread.

use rayon::prelude::*;

use crate::data::store::Rows;
use crate::dense::product::matmul;
use crate::error::Result;
use crate::model::Model;
use crate::model::blend::plausibility::max_albedos_of;
use crate::model::blend::plausible_budget::convex_weights_at;
use crate::model::blend::plausible_budget::{Budget, CLAMP_BUDGET, STEPS, counted};
use crate::model::blend::reconstruct::{Bands, Blend};
use crate::simd::dot;
use crate::simd::fold::with_scratch;

/// Store rows a step of the pass multiplies at once.
const BLOCK: usize = 480;

/// Below this many weight vectors a block's values are formed vector by
/// vector ([`dot::rows`]); from it on, by one matrix product (whose register
/// tiles take 8 vectors at once).
const PRODUCT_COLUMNS: usize = 8;

/// A worker's buffers, kept between tasks (a fresh allocation a task would
/// map and unmap pages each time, and every unmap interrupts the other cores).
#[derive(Default)]
struct Scratch {
    /// A block of store rows in f64.
    z64: Vec<f64>,
    /// Its values under every weight vector.
    t64: Vec<f64>,
    /// One blend's values of the block.
    row_values: Vec<f64>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

/// The blends of [`BlendRule::Plausible`](crate::BlendRule::Plausible)
/// at `points` (each `q` finite coordinates), in order: one pass over
/// the store for the steps of all of them, then each point's albedo
/// floor (point queries at the bins of the directional rule).
pub(crate) fn plausible_blends<'m>(
    model: &'m Model,
    points: &[Vec<f64>],
) -> Result<Vec<Blend<'m>>> {
    let gps = points
        .iter()
        .map(|x| Blend::gp_at(model, x))
        .collect::<Result<Vec<_>>>()?;
    let convex = convex_weights_at(model, points);
    let steps = plausible_steps(model, &gps, &convex)?;
    Ok(floored(model, gps, convex, steps))
}

/// The steps of [`BlendRule::Plausible`](crate::BlendRule::Plausible)
/// from each GP blend towards its convex weights, one per `theta_h` bin
/// (`result[point][bin]`).
///
/// A bin whose GP blend the clamp leaves within budget takes step 0
/// whatever the other steps would give, so each bin is read twice at
/// most: once for the GP blends alone at step 0, and once more, for the
/// points over budget only, for every step. Both passes sum the same
/// rows in the same order; the row values come from a matrix product
/// or row by row depending on how many weight vectors a pass has, which
/// can differ in the last bit, so only a bin exactly at the budget
/// could be decided differently from a single full pass.
fn plausible_steps(model: &Model, gps: &[Blend<'_>], convex: &[Vec<f64>]) -> Result<Vec<Vec<f64>>> {
    let m = gps.len();
    if m == 0 {
        return Ok(Vec::new());
    }
    model.store().verify_cheap()?;
    let dims = model.dims();
    let gp_weights: Vec<&[f64]> = gps.iter().map(|b| b.gp_weights()).collect();
    let by_band: Vec<Vec<f64>> = (0..dims.theta_h)
        .into_par_iter()
        .map(|band| {
            with_scratch(&SCRATCH, |s| {
                band_steps(model, band, &gp_weights, convex, s)
            })
        })
        .collect();
    model.verify()?;
    Ok((0..m)
        .map(|j| by_band.iter().map(|s| s[j]).collect())
        .collect())
}

/// The plausible rule's step of each point in theta_h bin `band`: the
/// budget at step 0 for every point, then every step for the points over
/// budget ([`plausible_steps`]).
fn band_steps(
    model: &Model,
    band: usize,
    gp_weights: &[&[f64]],
    convex: &[Vec<f64>],
    s: &mut Scratch,
) -> Vec<f64> {
    let m = gp_weights.len();
    let mut steps = vec![0.0; m];
    // Step 0 only, every point.
    let at_zero = band_budget(model, band, gp_weights, None, s);
    let over: Vec<usize> = (0..m)
        .filter(|&j| !at_zero.within_at_zero(0, j, CLAMP_BUDGET))
        .collect();
    if over.is_empty() {
        return steps;
    }
    // Every step, the points over budget.
    let w: Vec<&[f64]> = over.iter().map(|&j| gp_weights[j]).collect();
    let v: Vec<&[f64]> = over.iter().map(|&j| convex[j].as_slice()).collect();
    let full = band_budget(model, band, &w, Some(&v), s);
    let full_steps = full.steps(CLAMP_BUDGET);
    for (k, &j) in over.iter().enumerate() {
        steps[j] = full_steps[k];
    }
    steps
}

/// The budget of `theta_h` bin `band` for blends with GP weights `w`
/// and, given `v` (their convex weights), at every step of [`STEPS`];
/// without `v`, at step 0 alone (the other steps' sums stay 0).
fn band_budget(
    model: &Model,
    band: usize,
    w: &[&[f64]],
    v: Option<&[&[f64]]>,
    s: &mut Scratch,
) -> Budget {
    let store = model.store();
    let (n, dims) = (store.n(), model.dims());
    let (bins, per) = (dims.bins(), dims.theta_d * dims.phi_d);
    let (cosines, mean) = (model.cosine_products(), store.mean());
    let m = w.len();
    let columns: Vec<&[f64]> = w.iter().chain(v.into_iter().flatten()).copied().collect();
    // `A` (p x n, column-major) for the product path, padded with zero
    // vectors to whole register tiles of 8 (the product's edge rows
    // take a slower path).
    let p = if columns.len() >= PRODUCT_COLUMNS {
        columns.len().next_multiple_of(8)
    } else {
        columns.len()
    };
    let a: Vec<f64> = if p >= PRODUCT_COLUMNS {
        let columns = &columns;
        (0..n)
            .flat_map(|t| (0..p).map(move |j| columns.get(j).map_or(0.0, |c| c[t])))
            .collect()
    } else {
        Vec::new()
    };
    let mut budget = Budget::new(m, 1);
    for c in 0..3 {
        let start = c * bins + band * per;
        for r0 in (start..start + per).step_by(BLOCK) {
            let range = r0..(r0 + BLOCK).min(start + per);
            let len = range.len();
            s.t64.resize(p * len, 0.0);
            if p < PRODUCT_COLUMNS {
                s.row_values.resize(len, 0.0);
                for (j, col) in columns.iter().enumerate() {
                    let out = &mut s.row_values[..len];
                    match store.z() {
                        Rows::F32(z) => dot::rows(col, &z[r0 * n..], &mean[r0..], out),
                        Rows::F64(z) => dot::rows(col, &z[r0 * n..], &mean[r0..], out),
                    }
                    for (k, value) in out.iter().enumerate() {
                        s.t64[k * p + j] = *value;
                    }
                }
            } else {
                s.z64.resize(n * len, 0.0);
                store.copy_rows(r0, &mut s.z64[..n * len]);
                matmul(&mut s.t64[..p * len], &a, &s.z64[..n * len], n);
                for (k, row) in range.clone().enumerate() {
                    s.t64[k * p..(k + 1) * p]
                        .iter_mut()
                        .for_each(|t| *t += mean[row]);
                }
            }
            for (k, row) in range.enumerate() {
                if let Some(form) = counted(store, model.transform(), row) {
                    let t = &s.t64[k * p..(k + 1) * p];
                    let cos = cosines[row % bins];
                    match v {
                        Some(_) => budget.add(0, &t[..m], &t[m..2 * m], form, cos),
                        None => budget.add_at_zero(0, &t[..m], form, cos),
                    }
                }
            }
        }
    }
    budget
}

/// Each GP blend of `gps` moved by its `steps` towards its `convex`
/// weights, with the albedo floor of
/// [`BlendRule::Plausible`](crate::BlendRule::Plausible): while a
/// blend's largest directional albedo is above 1 (or above its convex
/// blend's, should the materials themselves exceed 1), every bin's step
/// is raised to the next floor of [`STEPS`]. The points go through the
/// floors together, so that each round's albedos read the directional
/// rule's rows once for all of them ([`Model::max_albedos_of`]); each
/// point's decisions and bits are what it would get alone.
fn floored<'m>(
    model: &'m Model,
    gps: Vec<Blend<'m>>,
    convex: Vec<Vec<f64>>,
    steps: Vec<Vec<f64>>,
) -> Vec<Blend<'m>> {
    let per = model.dims().theta_d * model.dims().phi_d;
    let banded = |j: usize, steps: Vec<f64>| {
        let bands = Bands::new(gps[j].gp_weights(), convex[j].clone(), steps, per);
        gps[j].with_bands(bands)
    };
    let mut moved: Vec<Option<Blend<'m>>> = (0..gps.len())
        .map(|j| (!steps[j].iter().all(|&t| t == 0.0)).then(|| banded(j, steps[j].clone())))
        .collect();
    let albedos = |moved: &[Option<Blend<'m>>], which: &[usize]| {
        let blends: Vec<&Blend<'_>> = which
            .iter()
            .map(|&j| moved[j].as_ref().unwrap_or(&gps[j]))
            .collect();
        max_albedos_of(model, &blends)
            .into_iter()
            .map(|(a, _)| a)
            .collect::<Vec<f64>>()
    };
    let all: Vec<usize> = (0..gps.len()).collect();
    let mut albedo = albedos(&moved, &all);
    let over: Vec<usize> = all.into_iter().filter(|&j| albedo[j] > 1.0).collect();
    let convex_blends: Vec<Blend<'_>> = over
        .iter()
        .map(|&j| Blend::of_weights(model, &convex[j]))
        .collect();
    let mut ceiling = vec![1.0f64; gps.len()];
    let convex_refs: Vec<&Blend<'_>> = convex_blends.iter().collect();
    for (&j, (a, _)) in over.iter().zip(max_albedos_of(model, &convex_refs)) {
        ceiling[j] = a.max(1.0);
    }
    drop(convex_blends);
    let mut active = over;
    for &floor in &STEPS[1..] {
        active.retain(|&j| albedo[j] > ceiling[j]);
        if active.is_empty() {
            break;
        }
        for &j in &active {
            moved[j] = Some(banded(j, steps[j].iter().map(|&t| t.max(floor)).collect()));
        }
        for (&j, a) in active.iter().zip(albedos(&moved, &active)) {
            albedo[j] = a;
        }
    }
    gps.into_iter()
        .zip(moved)
        .map(|(gp, b)| b.unwrap_or(gp))
        .collect()
}
