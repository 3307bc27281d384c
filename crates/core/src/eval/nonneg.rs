//! The leave-one-out predictions of [`crate::BlendRule::Plausible`]: each
//! held-out material predicted as a reconstruction at its latent point
//! would be, from the others (see [`crate::model::blend::plausible_budget`]). The GP's
//! weights `w` move towards the kernel's convex weights `v` (a
//! kernel-weighted average of the materials, plausible by construction):
//! `w + t (v - w)`, with the smallest `t` of [`STEPS`] for which the
//! reflectance the clamp removes is at most a budget's share of the
//! reflectance: per `theta_h` bin, as the rule does ([`banded_steps`]), or
//! for the whole table at once, the rule's earlier form, kept for
//! comparison ([`plausible_predictors`]). Both blends are linear in the
//! weights before the inverse transform, so one pass over the store gives
//! the removed reflectance at every step: per row, the GP value `g`, the
//! convex value `c`, and the clamped part of `g + t (c - g)` for each `t`.

use faer::{Mat, MatRef};

use crate::data::store::Store;
use crate::dense::product::matmul;
use crate::error::{ParamError, Result};
use crate::gplvm::kernel::{Kernel, rows_of};
use crate::model::blend::pass_bins::Every;
use crate::model::blend::plausible_budget::{Budget, STEPS, convex_weights, counted};
use crate::progress::Progress;
use crate::simd::fold::{GROUPS, ordered_blocks_then};

/// Rows of the store per block of the pass.
const BLOCK: usize = 1024;

/// The most the passes' partial sums may hold at once, in bytes.
const PARTIALS_BUDGET: usize = 64 << 20;

/// The convex leave-one-out predictor of [`crate::BlendRule::Plausible`]:
/// row `i` holds the convex weights at `x_i` of the other materials
/// (`V_ii = 0`), with the kernel's length scale times
/// [`crate::loo::CONVEX_LENGTH_RATIO`].
pub fn convex_predictor(kernel: &Kernel, latent: MatRef<'_, f64>) -> Result<Mat<f64>> {
    super::predictors::needs_two(latent.nrows())?;
    Ok(convex_rows(kernel, latent, true))
}

/// Row `i`: the convex weights at `x_i`, of the other materials when
/// `leave_out` (leave-one-out), of all of them otherwise (a material's own
/// point: the material alone, unless another shares the point).
pub(super) fn convex_rows(kernel: &Kernel, latent: MatRef<'_, f64>, leave_out: bool) -> Mat<f64> {
    let pts = rows_of(latent);
    let n = pts.len();
    let rows: Vec<Vec<f64>> = (0..n)
        .map(|i| convex_weights(&pts, &pts[i], kernel.length_scale, leave_out.then_some(i)))
        .collect();
    Mat::from_fn(n, n, |i, j| rows[i][j])
}

/// The leave-one-out predictors of the plausible rule's earlier form, which
/// moved the whole table by one step (kept to compare with
/// [`banded_steps`]), one per clamp budget in `budgets`: row `i` is
/// `(1 - t_i) P_i + t_i V_i` with the smallest `t_i` for which the clamp
/// removes at most the budget's share of the whole prediction's
/// reflectance. One pass over the store for every budget. Returns each
/// predictor with its steps `t`.
pub fn plausible_predictors(
    store: &Store,
    gp: MatRef<'_, f64>,
    convex: MatRef<'_, f64>,
    budgets: &[f64],
    progress: &dyn Progress,
) -> Result<Vec<(Mat<f64>, Vec<f64>)>> {
    let budget = budget_pass(store, gp, convex, false, Every::BIN, progress)?;
    let n = store.n();
    Ok(budgets
        .iter()
        .map(|&b| {
            let steps = budget.steps(b);
            let p = Mat::from_fn(n, n, |i, j| {
                (1.0 - steps[i]) * gp[(i, j)] + steps[i] * convex[(i, j)]
            });
            (p, steps)
        })
        .collect())
}

/// The steps of the plausible rule, held out, one set per budget in
/// `budgets`: the GP's leave-one-out prediction of material `i` moves
/// towards the convex one by its own step in each `theta_h` bin, the
/// smallest of [`crate::loo::STEPS`] for which the clamp removes at most
/// the budget's share of that bin's cosine-weighted reflectance, and every
/// bin's step is raised to the albedo floor where the prediction's largest
/// directional albedo is above 1 (as [`crate::BlendRule::Plausible`] does). Steps are
/// laid out bin by bin (`steps[band * N + i]`), to be mixed by
/// [`crate::loo::Mix`]. The budgets are judged on the bins `every` keeps
/// (each kept bin weighted by its cosines, as every bin is with
/// [`Every::BIN`]); the albedo floor always reads the directional rule's
/// rows.
pub fn banded_steps(
    store: &Store,
    gp: MatRef<'_, f64>,
    convex: MatRef<'_, f64>,
    budgets: &[f64],
    every: Every,
    progress: &dyn Progress,
) -> Result<Vec<Vec<f64>>> {
    let budget = budget_pass(store, gp, convex, true, every, progress)?;
    let stacked = stack(gp, convex);
    budgets
        .iter()
        .map(|&b| {
            let mut steps = budget.steps(b);
            super::albedo_floor::raise(store, &stacked, &mut steps)?;
            Ok(steps)
        })
        .collect()
}

/// The GP predictor above the convex one: column-major `2N x N`.
fn stack(gp: MatRef<'_, f64>, convex: MatRef<'_, f64>) -> Vec<f64> {
    let n = gp.nrows();
    (0..n)
        .flat_map(|j| {
            (0..2 * n).map(move |r| {
                if r < n {
                    gp[(r, j)]
                } else {
                    convex[(r - n, j)]
                }
            })
        })
        .collect()
}

/// One pass over the store: the clamp budget of every step for the GP and
/// convex leave-one-out predictions of every material, over the whole table
/// or per `theta_h` bin, on the rows `every` keeps.
fn budget_pass(
    store: &Store,
    gp: MatRef<'_, f64>,
    convex: MatRef<'_, f64>,
    banded: bool,
    every: Every,
    progress: &dyn Progress,
) -> Result<Budget> {
    let n = store.n();
    for p in [gp, convex] {
        if p.nrows() != n || p.ncols() != n {
            return Err(ParamError::PredictorShape {
                rows: p.nrows(),
                cols: p.ncols(),
                n,
            }
            .into());
        }
    }
    let stacked = stack(gp, convex);
    let dims = store.dims();
    let bands = if banded { dims.theta_h } else { 1 };
    let band_of = |row: usize| {
        if banded {
            dims.unbin(row % dims.bins()).0
        } else {
            0
        }
    };
    let transform = store.transform().build(dims);
    let cos = crate::data::transform::cosine_products(dims);
    let mean = store.mean();
    // Each group's partial sums wait for the ordered fold: keep them within
    // 64 MB together (the group count depends on N and the dims only, so
    // the bits do not depend on the thread count).
    let partial_bytes = n * bands * 2 * STEPS.len() * std::mem::size_of::<f64>();
    let groups = (PARTIALS_BUDGET / partial_bytes.max(1)).clamp(1, GROUPS);
    let kept = every.rows(dims, store.rows());
    let passed = kept.as_ref().map_or(store.rows(), Vec::len);
    progress.start("plausible steps", passed as u64);
    let parts = ordered_blocks_then(
        passed,
        BLOCK,
        groups,
        || {
            (
                Budget::new(n, bands),
                vec![0.0f64; BLOCK * n],
                vec![0.0f64; BLOCK * 2 * n],
            )
        },
        |(budget, zbuf, out), range| {
            let (r0, len) = (range.start, range.len());
            let z = &mut zbuf[..len * n];
            let ids = kept.as_ref().map(|k| &k[range]);
            store.copy_listed(r0, ids, z);
            // Bin-major rows are the columns of an n x len matrix.
            matmul(&mut out[..len * 2 * n], &stacked, z, n);
            for k in 0..len {
                let row = ids.map_or(r0 + k, |ids| ids[k] as usize);
                let Some(form) = counted(store, transform.as_ref(), row) else {
                    continue;
                };
                let col = &mut out[k * 2 * n..(k + 1) * 2 * n];
                col.iter_mut().for_each(|v| *v += mean[row]);
                budget.add(
                    band_of(row),
                    &col[..n],
                    &col[n..],
                    form,
                    cos[row % dims.bins()],
                );
            }
            progress.advance(len as u64);
        },
        |(budget, _, _)| budget,
    );
    progress.finish();
    let mut budget = Budget::new(n, bands);
    for b in &parts {
        budget.merge(b);
    }
    Ok(budget)
}
