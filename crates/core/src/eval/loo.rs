//! Leave-one-out (LOO) reconstruction error, in closed form, for the GPLVM
//! and for PCA, in one streaming pass over the store.
//!
//! Every method here predicts material `i` as a linear combination of the
//! stored rows: `z_hat_i = sum_j P_ij z_j` (centred values `z`, so the
//! prediction in transformed space is `mean + z_hat_i`). A method is an
//! `N x N` *predictor* matrix `P`; [`evaluate`] applies many predictors to
//! every row of the store at once (one matrix product per block of rows) and
//! folds the squared errors per material, never holding `Z` on the heap.
//!
//! **GPLVM, held out.** With `A = K^-1` (`K` with the noise on its diagonal,
//! latent points and hyperparameters as fitted on all `N` materials: no
//! refit), the GP prediction of material `i` from the others is
//! `z_i - (A z)_i / A_ii` (the classic LOO identity). The store is centred
//! by the mean of all `N` materials, which includes the held-out one; with
//! `refit_mean` the mean is re-estimated without `i` as well. That changes
//! every other row by `c = z_i / (N - 1)`, and the GP prediction of the
//! constant vector gives the correction in closed form too:
//! `z_hat_i = z_i - (A z)_i / A_ii - g_i z_i / (N - 1)`, `g_i = (A 1)_i / A_ii`.
//!
//! **PCA, held out.** For each `i`, the Gram matrix of the other `N - 1`
//! materials re-centred by their own mean is `Y'` (from `Y`, no data pass);
//! projecting the held-out material on their top `q` principal directions is
//! again a combination of the others' rows: `w = U_q S_q^-1 U_q^T b` with
//! `b_j = <z'_j, z'_i>`; one eigen-decomposition of an `(N-1) x (N-1)` matrix
//! per material.
//!
//! **PCA, in sample.** `P = U_q U_q^T` (eigenvectors of `Y`): the projection
//! of every material on the top `q` directions of all `N`, itself included.
//! Its total squared error in transformed space is the sum of the discarded
//! eigenvalues of `Y` ([`discarded`]); it is not a held-out error.

use brdf_merl::Dims;
use faer::Mat;

use crate::dense::product::matmul;

use super::score::{RowIds, RowScratch, Scoring, Sums, score_block};
use crate::data::store::Store;
use crate::data::transform::{InverseForm, TransformKind};
use crate::error::{ParamError, Result};
use crate::model::blend::soft_floor::{floor_points, floor_points_each, top_of};
use crate::progress::Progress;
use crate::simd::fold::{GROUPS, ordered_blocks_then};

/// Rows of the store per block of the LOO pass.
const BLOCK: usize = 1024;

pub use super::nonneg::{banded_steps, convex_predictor, plausible_predictors};
pub use super::predictors::{discarded, gp_predictor, pca_in_sample_predictor, pca_predictor};
pub use super::projected::{capped_simplex, projected_predictor};
pub use crate::model::blend::pass_bins::Every;
pub use crate::model::blend::plausible_budget::{CLAMP_BUDGET, CONVEX_LENGTH_RATIO, STEPS};

/// Squared errors of one predictor, per material.
#[derive(Debug, Clone, PartialEq)]
pub struct Errors {
    /// Sum over all rows of the squared error in transformed space.
    pub transformed: Vec<f64>,
    /// Sum over the scored rows of the squared error of the reflectance
    /// (1/sr), after the inverse transform and the clamp to `>= 0`.
    pub raw: Vec<f64>,
    /// Sum over the scored rows of the squared error of `log(1 + f cos_i cos_o)`.
    pub log: Vec<f64>,
    /// Sum over the scored rows of the squared log-relative error
    /// `ln((v' + e) / (v + e))`, `v = f cos_i cos_o`, `e =` [`LOG_REL_OFFSET`]:
    /// a dark material's error weighs as much as a highlight's.
    pub log_rel: Vec<f64>,
    /// The albedo of each prediction (dense rule over the measured rows,
    /// grazing ones included), per channel.
    pub albedo: Vec<[f64; 3]>,
}

pub use super::score::LOG_REL_OFFSET;

impl Errors {
    /// RMSE of material `i`'s reflectance over the scored rows.
    pub fn raw_rmse(&self, i: usize, scored: usize) -> f64 {
        (self.raw[i] / scored.max(1) as f64).sqrt()
    }

    /// RMSE of material `i`'s cosine-weighted log over the scored rows.
    pub fn log_rmse(&self, i: usize, scored: usize) -> f64 {
        (self.log[i] / scored.max(1) as f64).sqrt()
    }

    /// RMSE of material `i`'s log-relative error over the scored rows.
    pub fn log_rel_rmse(&self, i: usize, scored: usize) -> f64 {
        (self.log_rel[i] / scored.max(1) as f64).sqrt()
    }

    /// RMSE over all materials and scored rows (reflectance).
    pub fn raw_total(&self, scored: usize) -> f64 {
        (self.raw.iter().sum::<f64>() / (scored.max(1) * self.raw.len()) as f64).sqrt()
    }

    /// RMSE over all materials and scored rows (cosine-weighted log).
    pub fn log_total(&self, scored: usize) -> f64 {
        (self.log.iter().sum::<f64>() / (scored.max(1) * self.log.len()) as f64).sqrt()
    }
}

/// The result of [`evaluate`]: errors per predictor, and which rows scored.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// One entry per predictor, in the order given.
    pub errors: Vec<Errors>,
    /// Rows scored for reflectance and log errors: measured by some input
    /// material and not grazing (`cos_i cos_o >= 1e-6`, where the log
    /// transform recovers nothing).
    pub scored_rows: usize,
    /// All rows of the store.
    pub rows: usize,
    /// The albedo of each stored material over the same rows and rule as
    /// [`Errors::albedo`], per channel: what the predictions are judged against.
    pub albedo: Vec<[f64; 3]>,
}

/// `cos_i cos_o` of each bin and whether the log transform treats it as grazing.
fn cosines(dims: Dims) -> (Vec<f64>, Vec<bool>) {
    let log = TransformKind::Log.build(dims);
    let cos = crate::data::transform::cosine_products(dims);
    let grazing = (0..dims.bins())
        .map(|b| matches!(log.inverse_form(b), InverseForm::Exp(s) if s == 0.0))
        .collect();
    (cos, grazing)
}

/// Apply every predictor to every row of `store` and sum the squared errors
/// per material: one streaming pass, parallel over fixed groups of blocks
/// folded in order (same bits for any thread count).
pub fn evaluate(
    store: &Store,
    predictors: &[Mat<f64>],
    progress: &dyn Progress,
) -> Result<Evaluation> {
    evaluate_mixed(store, predictors, &[], progress)
}

/// A predictor mixed row by row from two of [`evaluate_mixed`]'s matrix
/// predictors, `P_from` and `P_towards`, as [`Mix::how`] says.
#[derive(Debug, Clone, PartialEq)]
pub struct Mix {
    /// Index of the predictor at `t = 0` (the GP's, for the rules).
    pub from: usize,
    /// Index of the predictor at `t = 1` (the convex blend's).
    pub towards: usize,
    /// How the two are mixed.
    pub how: Mixing,
}

/// How a [`Mix`] forms each prediction from its two predictors'.
#[derive(Debug, Clone, PartialEq)]
pub enum Mixing {
    /// Material `i` in `theta_h` bin `b` is predicted by
    /// `(1 - t) P_from + t P_towards`, `t = steps[b * N + i]` (see
    /// [`banded_steps`]): [`crate::BlendRule::Plausible`].
    Steps(Vec<f64>),
    /// Each value is [`crate::floor::soft_floor`] of the two predictors'
    /// values (with the mean added): [`crate::BlendRule::Floor`].
    Floor,
    /// [`Mixing::Floor`] onto the material itself (`towards` unused): the
    /// rule at a material's own point, where the convex blend is the
    /// material alone, without a product for it.
    FloorOnSelf,
}

/// [`evaluate`] with mixed predictors after the matrix ones: the errors
/// come in the order `predictors`, then `mixes`.
pub fn evaluate_mixed(
    store: &Store,
    predictors: &[Mat<f64>],
    mixes: &[Mix],
    progress: &dyn Progress,
) -> Result<Evaluation> {
    evaluate_some(store, predictors, mixes, None, Every::BIN, progress)
}

/// [`evaluate_mixed`] scoring only the outputs (matrix predictors, then
/// mixes) that `scored` marks, or all of them when it is `None` (a
/// predictor that only feeds a mix costs its product, not its scoring; the
/// errors of outputs not scored are zero), over the rows `every` keeps.
pub fn evaluate_some(
    store: &Store,
    predictors: &[Mat<f64>],
    mixes: &[Mix],
    scored: Option<&[bool]>,
    every: Every,
    progress: &dyn Progress,
) -> Result<Evaluation> {
    let n = store.n();
    let count = predictors.len();
    if let Some(p) = predictors.iter().find(|p| p.nrows() != n || p.ncols() != n) {
        return Err(ParamError::PredictorShape {
            rows: p.nrows(),
            cols: p.ncols(),
            n,
        }
        .into());
    }
    let theta_h = store.dims().theta_h;
    let steps_len = |m: &Mix| match &m.how {
        Mixing::Steps(steps) => steps.len(),
        Mixing::Floor | Mixing::FloorOnSelf => theta_h * n,
    };
    if let Some(m) = mixes
        .iter()
        .find(|m| m.from >= count || m.towards >= count || steps_len(m) != theta_h * n)
    {
        return Err(ParamError::PredictorShape {
            rows: steps_len(m),
            cols: m.from.max(m.towards),
            n,
        }
        .into());
    }
    let mn = count * n;
    // Predictions per row: the matrix predictors', then the mixed ones'.
    let mt = mn + mixes.len() * n;
    // All predictors stacked: row m * N + i predicts material i by method m.
    // Column-major mn x n.
    let stacked: Vec<f64> = (0..n)
        .flat_map(|j| (0..mn).map(move |r| (r, j)))
        .map(|(r, j)| predictors[r / n][(r % n, j)])
        .collect();
    let dims = store.dims();
    let bins = dims.bins();
    let rows = store.rows();
    // Each floor mix's reach per channel and material, from the convex
    // weights its material is predicted with (the material itself on its
    // own point).
    let reach: Vec<[Vec<f64>; 3]> = mixes
        .iter()
        .map(|mix| {
            let convex: Vec<Vec<f64>> = match mix.how {
                Mixing::Steps(_) => return Default::default(),
                Mixing::FloorOnSelf => (0..n)
                    .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
                    .collect(),
                Mixing::Floor => {
                    let p = &predictors[mix.towards];
                    (0..n)
                        .map(|i| (0..n).map(|j| p[(i, j)]).collect())
                        .collect()
                }
            };
            let bound = store.energy_bound();
            let r: Vec<[f64; 3]> = convex.iter().map(|v| bound.reach(v)).collect();
            [0, 1, 2].map(|c| r.iter().map(|r| r[c]).collect())
        })
        .collect();
    let kept = every.rows(dims, rows);
    let passed = kept.as_ref().map_or(rows, Vec::len);
    let (cos, grazing) = cosines(dims);
    let log_space = store.transform() == TransformKind::Log;
    let transform = store.transform().build(dims);
    let outputs = count + mixes.len();
    let scored_outputs: Vec<bool> = match scored {
        Some(s) if s.len() == outputs => s.to_vec(),
        Some(s) => {
            return Err(ParamError::PredictorShape {
                rows: s.len(),
                cols: outputs,
                n,
            }
            .into());
        }
        None => vec![true; outputs],
    };
    let weight = every.weights(dims);
    let scoring = Scoring {
        n,
        bins,
        mean: store.mean(),
        unmeasured: store.unmeasured(),
        grazing: &grazing,
        cos: &cos,
        weight: &weight,
        scored: &scored_outputs,
        transform: transform.as_ref(),
        log_space,
    };
    progress.start("loo", passed as u64);
    struct Group {
        sums: Sums,
        scored: usize,
        zbuf: Vec<f64>,
        out: Vec<f64>,
        mixed: Vec<f64>,
        tops: Vec<f64>,
        row: RowScratch,
    }
    // Each group's buffers (`out` is `BLOCK x` predictors `x N` values)
    // are freed as it ends; only its sums wait for the ordered fold.
    let partials = ordered_blocks_then(
        passed,
        BLOCK,
        GROUPS,
        || Group {
            sums: Sums::zeros(mt, n),
            scored: 0,
            zbuf: vec![0.0f64; BLOCK * n],
            out: vec![0.0f64; BLOCK * mn],
            mixed: vec![0.0f64; if mixes.is_empty() { 0 } else { BLOCK * mt }],
            tops: vec![0.0f64; n],
            row: RowScratch {
                truth: vec![0.0; n],
                reflectance: vec![0.0; n],
                log: vec![0.0; n],
                rel: vec![0.0; n],
                predicted: vec![0.0; n],
                predicted_log: vec![0.0; n],
            },
        },
        |g, range| {
            let len = range.len();
            let listed = kept.as_ref().map(|k| &k[range.clone()]);
            let ids = listed.map_or(RowIds::From(range.start), RowIds::List);
            let z = &mut g.zbuf[..len * n];
            store.copy_listed(range.start, listed, z);
            // Bin-major rows are the columns of an n x len matrix.
            matmul(&mut g.out[..len * mn], &stacked, z, n);
            let tops = &mut g.tops;
            let out = if mixes.is_empty() {
                &g.out[..len * mn]
            } else {
                for k in 0..len {
                    let band = dims.unbin(ids.get(k) % bins).0;
                    let (src, dst) = (
                        &g.out[k * mn..(k + 1) * mn],
                        &mut g.mixed[k * mt..(k + 1) * mt],
                    );
                    dst[..mn].copy_from_slice(src);
                    let mean = scoring.mean[ids.get(k)];
                    for (m, mix) in mixes.iter().enumerate() {
                        let (from, towards) = (
                            &src[mix.from * n..(mix.from + 1) * n],
                            match mix.how {
                                Mixing::FloorOnSelf => &z[k * n..(k + 1) * n],
                                _ => &src[mix.towards * n..(mix.towards + 1) * n],
                            },
                        );
                        let out = &mut dst[mn + m * n..mn + (m + 1) * n];
                        match &mix.how {
                            Mixing::Steps(steps) => {
                                let steps = &steps[band * n..(band + 1) * n];
                                for (((o, &a), &b), &t) in
                                    out.iter_mut().zip(from).zip(towards).zip(steps)
                                {
                                    *o = a + t * (b - a);
                                }
                            }
                            Mixing::Floor | Mixing::FloorOnSelf => {
                                // Compiled for FMA where the CPU has it:
                                // `soft_floor`'s exp and log1p are fused
                                // multiply-adds, a library call elsewhere.
                                out.copy_from_slice(from);
                                let zr = &z[k * n..(k + 1) * n];
                                let reach = &reach[m][ids.get(k) / bins];
                                if matches!(mix.how, Mixing::FloorOnSelf) {
                                    floor_points(out, towards, mean, top_of(zr), reach);
                                } else {
                                    // Held out: each material's cap is the
                                    // brightest of the others'.
                                    others_top(zr, tops);
                                    floor_points_each(out, towards, mean, tops, reach);
                                }
                            }
                        }
                    }
                }
                &g.mixed[..len * mt]
            };
            g.scored += score_block(&scoring, ids, z, out, &mut g.sums, &mut g.row);
            progress.advance(len as u64);
        },
        |g| (g.sums, g.scored),
    );
    progress.finish();
    let mut total = Sums::zeros(mt, n);
    let mut scored = 0;
    for (sums, group_scored) in partials {
        total.add(&sums);
        scored += group_scored;
    }
    let slice = |v: &[f64], m: usize| v[m * n..(m + 1) * n].to_vec();
    let albedo_of = |a: &[Vec<f64>; 3], k: usize| [a[0][k], a[1][k], a[2][k]];
    let errors = (0..outputs)
        .map(|m| Errors {
            transformed: slice(&total.transformed, m),
            raw: slice(&total.raw, m),
            log: slice(&total.log, m),
            log_rel: slice(&total.log_rel, m),
            albedo: (m * n..(m + 1) * n)
                .map(|k| albedo_of(&total.albedo, k))
                .collect(),
        })
        .collect();
    store.verify()?;
    Ok(Evaluation {
        errors,
        scored_rows: scored,
        rows,
        albedo: (0..n).map(|i| albedo_of(&total.truth, i)).collect(),
    })
}

/// For each material, the largest of the other materials' values `z`.
fn others_top(z: &[f64], tops: &mut [f64]) {
    let (mut first, mut second, mut at) = (f64::NEG_INFINITY, f64::NEG_INFINITY, usize::MAX);
    for (i, &v) in z.iter().enumerate() {
        if v > first {
            (second, first, at) = (first, v, i);
        } else if v > second {
            second = v;
        }
    }
    for (i, t) in tops.iter_mut().enumerate() {
        *t = if i == at { second } else { first };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{Dataset, Precision, build_store};
    use crate::eval::predictors::eigen_desc;
    use crate::gplvm::kernel::Kernel;
    use crate::progress::NoProgress;
    use brdf_merl::synth::{SplitMix64, database};
    use faer::MatRef;
    use faer::Side;
    use faer::linalg::solvers::Solve;

    /// A store of `n` synthetic materials and its centred data as a dense `N x d` matrix.
    fn small_store(
        dir: &std::path::Path,
        n: usize,
        dims: Dims,
        transform: TransformKind,
    ) -> (Store, Mat<f64>) {
        for m in database(n, 4) {
            m.brdf
                .table(dims)
                .write(dir.join(format!("{}.binary", m.name)))
                .unwrap();
        }
        let data = Dataset::open_dir(dir).unwrap();
        let out = dir.join(format!("{}.store", transform.name()));
        let (store, _) = build_store(&data, transform, Precision::F64, &out, &NoProgress).unwrap();
        let d = store.rows();
        let mut row = vec![0.0; n];
        let mut z = Mat::<f64>::zeros(n, d);
        for j in 0..d {
            store.copy_rows(j, &mut row);
            (0..n).for_each(|i| z[(i, j)] = row[i]);
        }
        (store, z)
    }

    fn without(z: MatRef<'_, f64>, i: usize) -> Mat<f64> {
        let others: Vec<usize> = (0..z.nrows()).filter(|&j| j != i).collect();
        Mat::from_fn(others.len(), z.ncols(), |a, c| z[(others[a], c)])
    }

    /// Subtract the column means; return them.
    fn recentre(z: &mut Mat<f64>) -> Vec<f64> {
        let n = z.nrows() as f64;
        (0..z.ncols())
            .map(|c| {
                let m = (0..z.nrows()).map(|r| z[(r, c)]).sum::<f64>() / n;
                (0..z.nrows()).for_each(|r| z[(r, c)] -= m);
                m
            })
            .collect()
    }

    #[test]
    fn gp_closed_form_equals_brute_force_refits_of_the_weights() {
        let tmp = tempfile::tempdir().unwrap();
        let n = 7;
        let (_, z) = small_store(
            tmp.path(),
            n,
            Dims::new(4, 4, 8).unwrap(),
            TransformKind::Log,
        );
        let mut rng = SplitMix64::new(3);
        let latent = Mat::<f64>::from_fn(n, 2, |_, _| rng.range(-1.0, 1.0));
        let scale = z.as_ref().norm_max();
        for noise in [1e-4, 1e-2] {
            let kernel = Kernel {
                length_scale: 0.8,
                noise,
            };
            let k = kernel.matrix(latent.as_ref());
            for refit_mean in [false, true] {
                let pz = gp_predictor(&kernel, latent.as_ref(), refit_mean).unwrap() * &z;
                for i in 0..n {
                    // Drop row and column i, solve densely with the rest, predict z_i.
                    let others: Vec<usize> = (0..n).filter(|&j| j != i).collect();
                    let kk = Mat::from_fn(n - 1, n - 1, |a, b| k[(others[a], others[b])]);
                    let ki = Mat::from_fn(n - 1, 1, |a, _| k[(i, others[a])]);
                    let mut zo = without(z.as_ref(), i);
                    let mean = if refit_mean {
                        recentre(&mut zo)
                    } else {
                        vec![0.0; z.ncols()]
                    };
                    let w = kk.llt(Side::Lower).unwrap().solve(&ki);
                    let pred = w.transpose() * &zo;
                    for c in 0..z.ncols() {
                        let want = mean[c] + pred[(0, c)];
                        assert!(
                            (pz[(i, c)] - want).abs() <= 1e-9 * scale,
                            "mu {noise} refit {refit_mean} material {i} value {c}: {} vs {want}",
                            pz[(i, c)]
                        );
                    }
                }
            }
        }
    }

    /// Top-`q` principal directions (`d x q`) of centred rows, from the
    /// `d x d` covariance: the primal problem, independent of the Gram trick.
    fn primal_directions(z: &Mat<f64>, q: usize) -> Mat<f64> {
        let (_, v) = eigen_desc((z.transpose() * z).as_ref()).unwrap();
        Mat::from_fn(z.ncols(), q, |r, c| v[(r, c)])
    }

    #[test]
    fn pca_predictors_equal_dense_primal_pca() {
        let tmp = tempfile::tempdir().unwrap();
        let n = 8;
        let (_, z) = small_store(
            tmp.path(),
            n,
            Dims::new(4, 4, 8).unwrap(),
            TransformKind::Raw,
        );
        let y = &z * z.transpose();
        let scale = z.as_ref().norm_max();
        for q in [1, 3] {
            // In sample: projection on the top q directions of all materials.
            let v = primal_directions(&z, q);
            let want = &z * &v * v.transpose();
            let got = pca_in_sample_predictor(y.as_ref(), q).unwrap() * &z;
            assert!((&got - &want).norm_max() <= 1e-9 * scale);
            let resid = (&z - &got).squared_norm_l2();
            let disc = discarded(y.as_ref(), q).unwrap();
            assert!(
                (resid - disc).abs() <= 1e-9 * y.as_ref().norm_max(),
                "{resid} vs {disc}"
            );
            // Held out: recentre the others, their directions, project.
            let got = pca_predictor(y.as_ref(), q).unwrap() * &z;
            for i in 0..n {
                let mut zo = without(z.as_ref(), i);
                let mean = recentre(&mut zo);
                let v = primal_directions(&zo, q);
                let zi = Mat::from_fn(1, z.ncols(), |_, c| z[(i, c)] - mean[c]);
                let proj = &zi * &v * v.transpose();
                for c in 0..z.ncols() {
                    let want = mean[c] + proj[(0, c)];
                    assert!(
                        (got[(i, c)] - want).abs() <= 1e-8 * scale,
                        "q {q} material {i} value {c}: {} vs {want}",
                        got[(i, c)]
                    );
                }
            }
        }
    }

    #[test]
    fn streamed_errors_equal_dense_ones_for_any_thread_count() {
        let tmp = tempfile::tempdir().unwrap();
        let n = 6;
        let dims = Dims::new(8, 8, 16).unwrap();
        for transform in [TransformKind::Raw, TransformKind::Log] {
            let sub = tmp.path().join(transform.name());
            std::fs::create_dir(&sub).unwrap();
            let (store, z) = small_store(&sub, n, dims, transform);
            let y = &z * z.transpose();
            let mut rng = SplitMix64::new(9);
            let latent = Mat::<f64>::from_fn(n, 2, |_, _| rng.range(-1.0, 1.0));
            let preds = vec![
                gp_predictor(&Kernel::default(), latent.as_ref(), true).unwrap(),
                pca_predictor(y.as_ref(), 2).unwrap(),
            ];
            let run = |threads| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| evaluate(&store, &preds, &NoProgress).unwrap())
            };
            let ev = run(2);
            assert_eq!(ev, run(1));
            // Dense reference with the library's own transform and std's log.
            let t = transform.build(dims);
            let log = TransformKind::Log.build(dims);
            let (cos, grazing) = cosines(dims);
            let mean = store.mean();
            let mut scored = 0;
            for (m, p) in preds.iter().enumerate() {
                let zh = p * &z;
                let (mut et, mut ef, mut el) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                for row in 0..store.rows() {
                    let bin = row % dims.bins();
                    let ok = store.unmeasured()[row] == 0 && !grazing[bin];
                    scored += (m == 0 && ok) as usize;
                    for i in 0..n {
                        let (tt, tp) = (mean[row] + z[(i, row)], mean[row] + zh[(i, row)]);
                        et[i] += (tp - tt).powi(2);
                        if ok {
                            let (ft, fp) = (t.inverse(bin, tt), t.inverse(bin, tp));
                            ef[i] += (fp - ft).powi(2);
                            let l = |f: f64| (f * cos[bin]).ln_1p();
                            el[i] += (l(fp) - l(ft)).powi(2);
                            assert!((log.forward(bin, Some(fp)) - l(fp)).abs() < 1e-12);
                        }
                    }
                }
                let e = &ev.errors[m];
                for i in 0..n {
                    for (got, want, what) in [
                        (e.transformed[i], et[i], "transformed"),
                        (e.raw[i], ef[i], "raw"),
                        (e.log[i], el[i], "log"),
                    ] {
                        assert!(
                            (got - want).abs() <= 1e-9 * want.abs().max(1e-12),
                            "{transform:?} predictor {m} material {i} {what}: {got} vs {want}"
                        );
                    }
                }
            }
            assert_eq!(ev.scored_rows, scored);
            assert!(scored > 0 && scored < ev.rows);
        }
    }
}
