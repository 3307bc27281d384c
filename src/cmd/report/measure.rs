//! The report's measurements: stores, fits and leave-one-out errors per
//! transform, the Hooke-Jeeves step sweep, f32 vs f64 stores, and the
//! albedo map's accuracy and time. Work that depends only on (transform,
//! precision) is done once: each store and its Gram matrix is built once
//! and every fit and the leave-one-out pass of that transform reuse it.

use std::path::Path;
use std::time::{Duration, Instant};

use brdf_atlas_core::loo::{self, Evaluation};
use brdf_atlas_core::{
    Atlas, Dataset, Fit, GplvmParams, GramData, Model, ModelFile, NoProgress, OptimizerKind,
    Precision, Store, StoreRef, TransformKind, build_scratch_store,
};
use faer::Mat;

use super::plan::Plan;
use super::results::{FitRow, LooRow, PrecisionRow, Results, StoreRow};
use super::steps::Steps;
use super::timed;
use crate::cmd::fit::DEFAULT_MIN_STEP;
use crate::error::Error;
use crate::progress::Bars;

/// One transform's f32 store, its Gram data, and its q = 2 Hooke-Jeeves fit
/// when the plan made one.
struct Transformed {
    store: Store,
    gram: GramData,
    y: Mat<f64>,
    kept: Option<Fit>,
    /// The q = 2 fit with the kernel learned (log transform only).
    learned: Option<Fit>,
}

/// A store built for the report, its Gram data and centred Gram matrix
/// `y`, and how long building it took.
pub struct Built {
    pub store: Store,
    pub gram: GramData,
    pub y: Mat<f64>,
    pub time: Duration,
}

/// Run every measurement of `plan` on `data`, building stores and model
/// files in `work`, and add the results to `r`. `log`: the f32 log store
/// if an earlier section built it (it is not built again).
pub fn measure(
    data: &Dataset,
    plan: &Plan,
    work: &Path,
    log: Option<Built>,
    steps: &mut Steps,
    r: &mut Results,
) -> Result<(), Error> {
    let log = per_transform(data, TransformKind::Log, log, plan, work, steps, r)?;
    let raw = per_transform(data, TransformKind::Raw, None, plan, work, steps, r)?;

    // Store precision: the log store again in f64, the same latent points.
    steps.section("Store precision: the f64 store, f32 vs f64 reconstructions");
    steps.say("log transform: f64 store, f32 vs f64 reconstructions")?;
    let (store64, _, y64) = build(data, TransformKind::Log, Precision::F64, work, r)?;
    r.gram_rel_diff = (&log.y - &y64).norm_max() / log.y.norm_max();
    let models = match (&log.kept, &raw.kept) {
        (Some(lf), Some(rf)) => {
            let log_model =
                in_memory_model(work, "log-f32", data, lf, &log.store, &log.y, &log.gram)?;
            let log64 = in_memory_model(work, "log-f64", data, lf, &store64, &log.y, &log.gram)?;
            let raw_model =
                in_memory_model(work, "raw-f32", data, rf, &raw.store, &raw.y, &raw.gram)?;
            compare_precision(&log_model, &log64, plan, r)?;
            Some((Atlas::new(log_model), Atlas::new(raw_model)))
        }
        _ => None,
    };
    drop(store64);

    if let Some((log_model, raw_model)) = &models {
        steps.section("Albedo map: sample count vs error vs time");
        steps.say("albedo map: sample count vs error vs time")?;
        super::maps::samples(log_model, plan, r)?;
        steps.section("Albedo map: exact-albedo rules vs error vs time");
        steps.say("albedo map: exact-albedo rules against the dense rule")?;
        super::maps::rules(log_model, plan, r)?;
        steps.section("Albedo map: the default method and the prepared map");
        steps.say(
            "albedo map: the albedo field and the prepared lattice against the per-pixel rule",
        )?;
        super::maps::methods(log_model, plan, r)?;
        steps.section("Albedo map: size vs time");
        steps.say("albedo map: size vs time")?;
        super::maps::sizes(log_model, raw_model, plan, r)?;
        steps.section("Plausibility grid");
        steps.say(&format!(
            "plausibility at {0} x {0} points of the map, each model, every blend rule",
            plan.plausibility_grid
        ))?;
        super::plausible::measure(log_model, TransformKind::Log, "fixed", plan, r)?;
        if let Some(lf) = &log.learned {
            let learned =
                in_memory_model(work, "log-learned", data, lf, &log.store, &log.y, &log.gram)?;
            super::plausible::measure(
                &Atlas::new(learned),
                TransformKind::Log,
                "learned",
                plan,
                r,
            )?;
        }
        super::plausible::measure(raw_model, TransformKind::Raw, "fixed", plan, r)?;
    }
    Ok(())
}

/// One transform: its store, the fits for q = 1..Q (and q = 2 by the other
/// optimiser), the leave-one-out pass of those fits and of PCA, and for
/// the log transform Hooke-Jeeves' minimum step sweep.
fn per_transform(
    data: &Dataset,
    transform: TransformKind,
    built: Option<Built>,
    plan: &Plan,
    work: &Path,
    steps: &mut Steps,
    r: &mut Results,
) -> Result<Transformed, Error> {
    let name = transform.name();
    steps.section(format!(
        "Leave-one-out and fits, {name} transform: store, fits, leave-one-out pass"
    ));
    let (store, gram, y) = match built {
        Some(b) => {
            steps.say(&format!(
                "{name} transform: store and Gram matrix (built by the fidelity section)"
            ))?;
            r.stores.push(StoreRow {
                transform,
                precision: Precision::F32,
                time: b.time,
                bytes: b.store.len_bytes(),
            });
            (b.store, b.gram, b.y)
        }
        None => {
            steps.say(&format!("{name} transform: store and Gram matrix"))?;
            build(data, transform, Precision::F32, work, r)?
        }
    };
    steps.say(&format!("{name} transform: fits for q = 1..{}", plan.q_max))?;
    let mut runs: Vec<(&'static str, usize, OptimizerKind)> = (1..=plan.q_max)
        .map(|q| ("gplvm", q, plan.optimizer))
        .collect();
    if plan.q_max >= 2 {
        runs.push(("gplvm-other", 2, plan.other_optimizer()));
    }
    let mut predictors = Vec::new();
    let mut labels = Vec::new();
    let mut kept = None;
    for (method, q, optimizer) in runs {
        let (fit, row) = fit(&gram, transform, q, optimizer, DEFAULT_MIN_STEP)?;
        predictors.push(loo::gp_predictor(
            &fit.kernel,
            fit.outcome.latent.as_ref(),
            true,
        )?);
        labels.push((method, q));
        r.fits.push(row);
        if q == 2 && optimizer == OptimizerKind::default() {
            kept = Some((fit, predictors.len() - 1));
            r.kept_label = method;
        }
    }
    // The kernel learned with the points (log transform, the default).
    let mut learned = None;
    if transform == TransformKind::Log && plan.q_max >= 2 {
        steps.say("log transform: the kernel learned with the points (q = 2)")?;
        let fit = GplvmParams::new(2)
            .optimizer(OptimizerKind::Lbfgs)
            .learn_kernel(true)
            .check()?
            .fit(&gram, &NoProgress)?;
        predictors.push(loo::gp_predictor(
            &fit.kernel,
            fit.outcome.latent.as_ref(),
            true,
        )?);
        labels.push(("gplvm-learned", 2));
        learned = Some((fit, predictors.len() - 1));
    }
    // The plausible rule's held-out predictions mix a fit's GP predictor
    // with the convex one, theta_h bin by theta_h bin.
    let mut mixes = Vec::new();
    let mut mix_labels = Vec::new();
    let candidates = [
        (&kept, "gplvm-plausible", "convex"),
        (&learned, "gplvm-learned-plausible", "convex-learned"),
    ];
    for ((fit, at), label, convex_label) in candidates
        .into_iter()
        .filter_map(|(f, l, c)| f.as_ref().map(|f| (f, l, c)))
    {
        steps.say(&format!(
            "{name} transform: the plausible rule's steps, held out ({label})"
        ))?;
        let (latent, kernel) = (fit.outcome.latent.as_ref(), &fit.kernel);
        let convex = loo::convex_predictor(kernel, latent)?;
        let bars = Bars::new("plausible steps");
        let mut banded = loo::banded_steps(
            &store,
            predictors[*at].as_ref(),
            convex.as_ref(),
            &[loo::CLAMP_BUDGET],
            plan.every(),
            &bars,
        )?;
        predictors.push(convex);
        labels.push((convex_label, 2));
        mixes.push(loo::Mix {
            from: *at,
            towards: predictors.len() - 1,
            how: loo::Mixing::Steps(banded.remove(0)),
        });
        mix_labels.push((label, 2));
        // The soft floor under the same convex blend (fixed kernel only).
        if label == "gplvm-plausible" {
            mixes.push(loo::Mix {
                from: *at,
                towards: predictors.len() - 1,
                how: loo::Mixing::Floor,
            });
            mix_labels.push(("gplvm-floor", 2));
        }
    }
    // The fixed kernel's GP weights constrained instead of adapted: the
    // nearest convex weights (nothing clamped, at a cost in accuracy).
    if let Some((_, at)) = &kept {
        let projected = loo::projected_predictor(predictors[*at].as_ref())?;
        predictors.push(projected);
        labels.push(("gplvm-projected", 2));
    }
    for q in 1..=plan.q_max {
        predictors.push(loo::pca_predictor(y.as_ref(), q)?);
        labels.push(("pca", q));
    }
    labels.extend(mix_labels);
    for (fit, kernel) in [(&kept, "fixed"), (&learned, "learned")] {
        if let Some((fit, _)) = fit {
            r.spread.push((
                transform,
                kernel,
                super::plausible::median_nearest(fit.outcome.latent.as_ref()),
            ));
        }
    }
    steps.say(&format!(
        "{name} transform: leave-one-out pass ({} predictors over {} values)",
        predictors.len() + mixes.len(),
        store.rows()
    ))?;
    let bars = Bars::new("leave-one-out");
    let t = Instant::now();
    let ev = loo::evaluate_some(&store, &predictors, &mixes, None, plan.every(), &bars)?;
    r.loo_times.push((transform, predictors.len(), t.elapsed()));
    drop(bars);
    record_loo(r, transform, &labels, &ev, y.as_ref())?;
    if transform == TransformKind::Log {
        steps.section("Fitting: Hooke-Jeeves' minimum step sweep");
        steps.say("log transform: Hooke-Jeeves minimum step sweep (q = 2)")?;
        if plan.q_max >= 2 {
            for &m in &plan.min_steps {
                r.sweep
                    .push(fit(&gram, transform, 2, OptimizerKind::HookeJeeves, m)?.1);
            }
        }
    }
    Ok(Transformed {
        store,
        gram,
        y,
        kept: kept.map(|(fit, _)| fit),
        learned: learned.map(|(fit, _)| fit),
    })
}

/// Build one store (timed, and recorded in `r`) and its normalised Gram data.
fn build(
    data: &Dataset,
    transform: TransformKind,
    precision: Precision,
    work: &Path,
    r: &mut Results,
) -> Result<(Store, GramData, Mat<f64>), Error> {
    let b = build_timed(data, transform, precision, work)?;
    r.stores.push(StoreRow {
        transform,
        precision,
        time: b.time,
        bytes: b.store.len_bytes(),
    });
    Ok((b.store, b.gram, b.y))
}

/// Build one scratch store (named in `work`, held in memory and never
/// written to disk, [`build_scratch_store`]) and its normalised Gram data,
/// timed (the store; the Gram data is the normalisation of what the pass
/// summed).
pub fn build_timed(
    data: &Dataset,
    transform: TransformKind,
    precision: Precision,
    work: &Path,
) -> Result<Built, Error> {
    let path = work.join(format!("{}-{}.store", transform.name(), precision.name()));
    let bars = Bars::new("store");
    let t = Instant::now();
    let (store, y) = build_scratch_store(data, transform, precision, &path, &bars)?;
    let time = t.elapsed();
    let gram = GramData::new(y.clone(), store.rows())?;
    Ok(Built {
        store,
        gram,
        y,
        time,
    })
}

/// One fit from the shared Gram data, timed (the optimiser only).
fn fit(
    gram: &GramData,
    transform: TransformKind,
    q: usize,
    optimizer: OptimizerKind,
    min_step: f64,
) -> Result<(Fit, FitRow), Error> {
    let params = GplvmParams::new(q)
        .optimizer(optimizer)
        .min_step(min_step)
        .initial_step(0.25f64.max(min_step))
        .check()?;
    let t = Instant::now();
    let fit = params.fit(gram, &NoProgress)?;
    let time = t.elapsed();
    let row = FitRow {
        transform,
        q,
        optimizer,
        min_step,
        time,
        initial_cost: fit.outcome.initial_cost,
        cost: fit.outcome.cost,
        evaluations: fit.outcome.evaluations,
    };
    Ok((fit, row))
}

/// The errors of one leave-one-out pass, a row per predictor (`labels`).
fn record_loo(
    r: &mut Results,
    transform: TransformKind,
    labels: &[(&'static str, usize)],
    ev: &Evaluation,
    y: faer::MatRef<'_, f64>,
) -> Result<(), Error> {
    let n = r.names.len();
    r.scored_rows = ev.scored_rows;
    for (&(method, q), e) in labels.iter().zip(&ev.errors) {
        let in_sample = if method == "pca" {
            Some((loo::discarded(y, q)? / (n * ev.rows) as f64).sqrt())
        } else {
            None
        };
        r.loo.push(LooRow {
            transform,
            method,
            q,
            raw: e.raw_total(ev.scored_rows),
            log: e.log_total(ev.scored_rows),
            transformed: (e.transformed.iter().sum::<f64>() / (n * ev.rows) as f64).sqrt(),
            materials: (0..n)
                .map(|i| (e.raw_rmse(i, ev.scored_rows), e.log_rmse(i, ev.scored_rows)))
                .collect(),
            in_sample,
        });
    }
    Ok(())
}

/// The model of `fit` on `store`, in memory (named `work/NAME.atlas` in
/// messages; nothing is written).
pub fn in_memory_model(
    work: &Path,
    name: &str,
    data: &Dataset,
    fit: &Fit,
    store: &Store,
    y: &Mat<f64>,
    gram: &GramData,
) -> Result<Model, Error> {
    let store_name = store
        .path()
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let store_ref = StoreRef::of(store, store_name);
    let file = ModelFile::new(data.names.clone(), fit, store, y.as_ref(), gram, store_ref);
    let store = store.try_clone()?;
    Ok(Model::new(work.join(format!("{name}.atlas")), file, store)?)
}

/// Latent points for the precision comparison: materials and midpoints.
fn probe_points(model: &Model, count: usize) -> Vec<Vec<f64>> {
    let x = model.latent();
    let n = x.nrows();
    (0..count)
        .map(|k| {
            let (a, b) = ((2 * k) % n, (2 * k + 1) % n);
            (0..x.ncols())
                .map(|c| {
                    if k % 2 == 0 {
                        x[(a, c)]
                    } else {
                        0.5 * (x[(a, c)] + x[(b, c)])
                    }
                })
                .collect()
        })
        .collect()
}

/// Full reconstructions from the f32 and the f64 store at the same points.
fn compare_precision(m32: &Model, m64: &Model, plan: &Plan, r: &mut Results) -> Result<(), Error> {
    for x in probe_points(m32, plan.points) {
        let (a, time32) = timed(plan.repeat, || {
            Ok(m32.at(&x, brdf_atlas_core::BlendRule::Gp)?.table()?)
        })?;
        let (b, time64) = timed(plan.repeat, || {
            Ok(m64.at(&x, brdf_atlas_core::BlendRule::Gp)?.table()?)
        })?;
        let dims = a.dims();
        let (mut max_abs, mut peak, mut sum2, mut count) = (0.0f64, 0.0f64, 0.0f64, 0usize);
        for c in 0..3 {
            for bin in 0..dims.bins() {
                if let (Some(u), Some(v)) = (a.value(c, bin), b.value(c, bin)) {
                    let d = (u - v).abs();
                    max_abs = max_abs.max(d);
                    peak = peak.max(v.abs());
                    sum2 += d * d;
                    count += 1;
                }
            }
        }
        r.precision.push(PrecisionRow {
            point: x,
            max_abs,
            max_rel: max_abs / peak.max(f64::MIN_POSITIVE),
            rms: (sum2 / count.max(1) as f64).sqrt(),
            time32,
            time64,
        });
    }
    Ok(())
}
