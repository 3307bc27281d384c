//! `brdf-atlas report`: what accuracy costs in time, measured on a directory
//! of MERL files and written up as `report.md` with CSV tables and PNG plots.
//!
//! The measurements come from the core library (stores, fits, the
//! leave-one-out pass of [`brdf_atlas_core::loo`], maps, reconstruction);
//! this module decides what to run, times it and writes the results. Work
//! that depends only on (transform, precision) is done once: each store and
//! its Gram matrix is built once and every fit and the leave-one-out pass of
//! that transform reuse it. Everything is written into a staging directory
//! beside REPORT_DIR, which takes REPORT_DIR's place only when the whole
//! report is done: a failed run leaves no partial report, and an earlier
//! report stays until the new one is complete.

mod plot;

use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant, SystemTime};

use brdf_atlas_core::ModelFile;
use brdf_atlas_core::loo::{self, Evaluation};
use brdf_atlas_core::measure::{map_error, reference_albedo};
use brdf_atlas_core::{AlbedoMethod, DEFAULT_SAMPLES, View};
use brdf_atlas_core::{Dataset, build_store};
use brdf_atlas_core::{
    Fit, GplvmParams, GramData, Model, OptimizerKind, Precision, Store, TransformKind,
};
use brdf_merl::Quadrature;
use faer::Mat;

use crate::error::Error;
use crate::fit::{secs, size};
use crate::progress::Bars;

/// What to measure, on which data, and where the report goes.
#[derive(Debug, Clone)]
pub struct Options {
    /// Directory of MERL `.binary` files.
    pub dir: PathBuf,
    /// Report directory to write (replaced as a whole when done).
    pub out: PathBuf,
    /// Largest latent dimension of the leave-one-out sweep.
    pub q_max: usize,
    /// Fewer settings everywhere (fewer sample counts, sizes, steps).
    pub quick: bool,
    /// Optimiser of the fits for q = 1..q_max (the other one fits q = 2 too).
    pub optimizer: OptimizerKind,
}

/// Default `--q-max`.
pub const DEFAULT_Q_MAX: usize = 8;
/// `--q-max` under `--quick` when not given.
pub const QUICK_Q_MAX: usize = 3;

/// The settings each part of the report sweeps.
struct Plan {
    q_max: usize,
    min_steps: Vec<f64>,
    samples: Vec<usize>,
    sizes: Vec<usize>,
    /// Reference pixels per side of the map-accuracy grid.
    grid: usize,
    /// Size of the map timed for each sample count.
    timed_size: usize,
    /// Latent points reconstructed for the precision comparison.
    points: usize,
    /// Time short runs three times and keep the median.
    repeat: bool,
}

impl Plan {
    fn new(options: &Options, n: usize) -> Plan {
        let q_max = options.q_max.min(n.saturating_sub(1)).max(1);
        if options.quick {
            Plan {
                q_max,
                min_steps: vec![1e-1, 1e-2, 1e-3],
                samples: vec![16, 64, 256],
                sizes: vec![64, 128, 256],
                grid: 2,
                timed_size: 128,
                points: 2,
                repeat: false,
            }
        } else {
            Plan {
                q_max,
                min_steps: vec![1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4],
                samples: vec![16, 64, 256, 1024, 4096],
                sizes: vec![128, 256, 512, 1024],
                grid: 4,
                timed_size: 256,
                points: 4,
                repeat: true,
            }
        }
    }
}

/// One fit of the latent points.
struct FitRow {
    transform: TransformKind,
    q: usize,
    optimizer: OptimizerKind,
    min_step: f64,
    time: Duration,
    initial_cost: f64,
    cost: f64,
    evaluations: u64,
}

/// Leave-one-out errors of one method.
struct LooRow {
    transform: TransformKind,
    method: &'static str,
    q: usize,
    raw: f64,
    log: f64,
    transformed: f64,
    /// Per material: (reflectance RMSE, log RMSE).
    materials: Vec<(f64, f64)>,
    /// In-sample PCA RMSE in transformed space, from the discarded eigenvalues.
    in_sample: Option<f64>,
}

/// Building one store.
struct StoreRow {
    transform: TransformKind,
    precision: Precision,
    time: Duration,
    bytes: u64,
}

/// The f32 and f64 reconstruction of one latent point.
struct PrecisionRow {
    point: Vec<f64>,
    max_abs: f64,
    max_rel: f64,
    rms: f64,
    time32: Duration,
    time64: Duration,
}

/// One sample count of the log map.
struct SampleRow {
    samples: usize,
    bins: usize,
    max_err: f64,
    mean_err: f64,
    time: Duration,
}

/// One map size.
struct SizeRow {
    method: String,
    size: usize,
    time: Duration,
}

/// Everything measured.
#[derive(Default)]
struct Results {
    names: Vec<String>,
    dims: String,
    d: usize,
    scan: Duration,
    stores: Vec<StoreRow>,
    fits: Vec<FitRow>,
    loo: Vec<LooRow>,
    loo_times: Vec<(TransformKind, usize, Duration)>,
    scored_rows: usize,
    sweep: Vec<FitRow>,
    precision: Vec<PrecisionRow>,
    gram_rel_diff: f64,
    samples: Vec<SampleRow>,
    reference_time: Duration,
    reference_pixels: usize,
    sizes: Vec<SizeRow>,
}

/// What the demo and `run` print at the end.
pub struct Summary {
    /// The report file.
    pub report: PathBuf,
    /// Wall time of the whole run.
    pub total: Duration,
    /// Materials.
    pub materials: usize,
}

/// Run `report` and say where it went.
pub fn run(options: &Options) -> Result<ExitCode, Error> {
    let mut out = std::io::stdout().lock();
    let summary = write(options, &mut out)?;
    writeln!(
        out,
        "wrote {} ({} materials) in {}",
        summary.report.display(),
        summary.materials,
        secs(summary.total)
    )?;
    Ok(ExitCode::SUCCESS)
}

/// A directory that is removed when dropped unless committed.
struct Staging {
    dir: PathBuf,
    out: PathBuf,
    committed: bool,
}

impl Staging {
    fn new(out: &Path) -> Result<Staging, Error> {
        let name = out
            .file_name()
            .ok_or_else(|| Error::Input(format!("{}: not a directory name", out.display())))?
            .to_string_lossy()
            .into_owned();
        if out.exists() && !is_report(out) {
            return Err(Error::Input(format!(
                "{}: exists and is not a brdf-atlas report (no report.md); choose a new directory",
                out.display()
            )));
        }
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let dir = parent.join(format!(".{name}.tmp-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("work")).map_err(|source| Error::CreateDir {
            path: dir.clone(),
            source,
        })?;
        Ok(Staging {
            dir,
            out: out.to_path_buf(),
            committed: false,
        })
    }

    fn work(&self) -> PathBuf {
        self.dir.join("work")
    }

    /// Drop the work files and move the report into place (replacing an older report).
    fn commit(mut self) -> Result<(), Error> {
        let io = |path: &Path, e: std::io::Error| {
            Error::Input(format!("{}: cannot finish the report: {e}", path.display()))
        };
        std::fs::remove_dir_all(self.work()).map_err(|e| io(&self.work(), e))?;
        let old = self.dir.with_extension("old");
        if self.out.exists() {
            std::fs::rename(&self.out, &old).map_err(|e| io(&self.out, e))?;
        }
        std::fs::rename(&self.dir, &self.out).map_err(|e| io(&self.out, e))?;
        self.committed = true;
        if old.exists() {
            std::fs::remove_dir_all(&old).map_err(|e| io(&old, e))?;
        }
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            // Best effort: the error that got us here is what matters.
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

fn is_report(dir: &Path) -> bool {
    dir.is_dir()
        && (dir.join("report.md").is_file()
            || std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_none()))
}

/// Median wall time of `f`: once, or three times when one run is short and `repeat`.
fn timed<T>(repeat: bool, mut f: impl FnMut() -> Result<T, Error>) -> Result<(T, Duration), Error> {
    let t = Instant::now();
    let v = f()?;
    let first = t.elapsed();
    if !repeat || first > Duration::from_millis(700) {
        return Ok((v, first));
    }
    let mut times = vec![first];
    for _ in 0..2 {
        let t = Instant::now();
        f()?;
        times.push(t.elapsed());
    }
    times.sort();
    Ok((v, times[1]))
}

/// Measure everything and write the report; progress lines go to `say`.
pub fn write(options: &Options, say: &mut dyn Write) -> Result<Summary, Error> {
    let start = Instant::now();
    let load_start = load_average();
    let staging = Staging::new(&options.out)?;
    let bars = Bars::new(format!("opening {}", options.dir.display()));
    let t = Instant::now();
    let data = Dataset::open_dir(&options.dir)?;
    let n = data.len();
    if n < 3 {
        return Err(Error::Input(format!(
            "{}: a report needs at least 3 materials, found {n}",
            options.dir.display()
        )));
    }
    let mut r = Results {
        names: data.names.clone(),
        dims: data.dims().to_string(),
        d: data.dims().values(),
        scan: t.elapsed(),
        ..Default::default()
    };
    let plan = Plan::new(options, n);
    drop(bars);
    let work = staging.work();
    let step = |say: &mut dyn Write, text: &str| -> Result<(), Error> {
        writeln!(say, "[{:7.1} s] {text}", start.elapsed().as_secs_f64())?;
        Ok(())
    };

    // Stores, fits and leave-one-out, per transform.
    let mut q2 = Vec::new();
    for transform in [TransformKind::Log, TransformKind::Raw] {
        step(
            say,
            &format!("{} transform: store and Gram matrix", transform.name()),
        )?;
        let (store, gram, y) = build(&data, transform, Precision::F32, &work, &mut r)?;
        step(
            say,
            &format!(
                "{} transform: fits for q = 1..{}",
                transform.name(),
                plan.q_max
            ),
        )?;
        let mut predictors = Vec::new();
        let mut labels = Vec::new();
        let mut kept = None;
        for q in 1..=plan.q_max {
            let (fit, row) = fit(&gram, transform, q, options.optimizer, 1e-3)?;
            predictors.push(loo::gp_predictor(
                &fit.kernel,
                fit.outcome.latent.as_ref(),
                true,
            )?);
            labels.push(("gplvm", q));
            r.fits.push(row);
            if q == 2 && options.optimizer == OptimizerKind::HookeJeeves {
                kept = Some(fit);
            }
        }
        if plan.q_max >= 2 {
            let other = other_optimizer(options.optimizer);
            let (fit, row) = fit(&gram, transform, 2, other, 1e-3)?;
            predictors.push(loo::gp_predictor(
                &fit.kernel,
                fit.outcome.latent.as_ref(),
                true,
            )?);
            labels.push(("gplvm-other", 2));
            r.fits.push(row);
            if other == OptimizerKind::HookeJeeves {
                kept = Some(fit);
            }
        }
        for q in 1..=plan.q_max {
            predictors.push(loo::pca_predictor(y.as_ref(), q)?);
            labels.push(("pca", q));
        }
        step(
            say,
            &format!(
                "{} transform: leave-one-out pass ({} predictors over {} values)",
                transform.name(),
                predictors.len(),
                store.rows()
            ),
        )?;
        let bars = Bars::new("leave-one-out");
        let t = Instant::now();
        let ev = loo::evaluate(&store, &predictors, &bars)?;
        r.loo_times.push((transform, predictors.len(), t.elapsed()));
        drop(bars);
        record_loo(&mut r, transform, &labels, &ev, y.as_ref())?;
        if transform == TransformKind::Log {
            step(
                say,
                "log transform: Hooke-Jeeves minimum step sweep (q = 2)",
            )?;
            for &m in &plan.min_steps {
                if plan.q_max >= 2 {
                    r.sweep
                        .push(fit(&gram, transform, 2, OptimizerKind::HookeJeeves, m)?.1);
                }
            }
        }
        q2.push((store, gram, y, kept));
    }

    // Store precision: the log store again in f64, the same latent points.
    step(say, "log transform: f64 store, f32 vs f64 reconstructions")?;
    let (store64, _, y64) = build(&data, TransformKind::Log, Precision::F64, &work, &mut r)?;
    let [
        (log32, log_gram, log_y, log_fit),
        (raw32, raw_gram, raw_y, raw_fit),
    ] = <[_; 2]>::try_from(q2).map_err(|_| Error::Input("internal: two transforms".into()))?;
    r.gram_rel_diff = (&log_y - &y64).norm_max() / log_y.norm_max();
    let models = match (log_fit, raw_fit) {
        (Some(lf), Some(rf)) => {
            let log_model = model_file(&work, "log-f32", &data, &lf, &log32, &log_y, &log_gram)?;
            let log64 = model_file(&work, "log-f64", &data, &lf, &store64, &log_y, &log_gram)?;
            let raw_model = model_file(&work, "raw-f32", &data, &rf, &raw32, &raw_y, &raw_gram)?;
            compare_precision(&log_model, &log64, &plan, &mut r)?;
            drop(log64);
            Some((log_model, raw_model))
        }
        _ => None,
    };
    drop(store64);

    // Maps.
    if let Some((log_model, raw_model)) = &models {
        step(say, "albedo map: sample count vs error vs time")?;
        map_samples(log_model, &plan, &mut r)?;
        step(say, "albedo map: size vs time")?;
        for &s in &plan.sizes {
            let view = View::default();
            let (_, t) = timed(plan.repeat, || {
                Ok(log_model.albedo_map(
                    s,
                    s,
                    view,
                    Some(DEFAULT_SAMPLES),
                    &brdf_atlas_core::NoProgress,
                )?)
            })?;
            r.sizes.push(SizeRow {
                method: format!("log, {DEFAULT_SAMPLES} samples"),
                size: s,
                time: t,
            });
            let (_, t) = timed(plan.repeat, || {
                Ok(raw_model.albedo_map(s, s, view, None, &brdf_atlas_core::NoProgress)?)
            })?;
            r.sizes.push(SizeRow {
                method: "raw, linear".into(),
                size: s,
                time: t,
            });
        }
    }
    drop(models);
    drop((log32, raw32));

    step(say, "writing tables and plots")?;
    let dir = staging.dir.clone();
    write_csvs(&dir, &r)?;
    plot::all(&dir, &r)?;
    let total = start.elapsed();
    let md = markdown(options, &plan, &r, total, load_start, load_average());
    std::fs::write(dir.join("report.md"), md).map_err(|e| {
        Error::Input(format!(
            "{}: cannot write: {e}",
            dir.join("report.md").display()
        ))
    })?;
    staging.commit()?;
    Ok(Summary {
        report: options.out.join("report.md"),
        total,
        materials: n,
    })
}

/// The optimiser that is not `kind`.
fn other_optimizer(kind: OptimizerKind) -> OptimizerKind {
    match kind {
        OptimizerKind::HookeJeeves => OptimizerKind::Lbfgs,
        OptimizerKind::Lbfgs => OptimizerKind::HookeJeeves,
    }
}

/// Build one store (timed) and its normalised Gram data.
fn build(
    data: &Dataset,
    transform: TransformKind,
    precision: Precision,
    work: &Path,
    r: &mut Results,
) -> Result<(Store, GramData, Mat<f64>), Error> {
    let path = work.join(format!("{}-{}.store", transform.name(), precision.name()));
    let bars = Bars::new("store");
    let t = Instant::now();
    let (store, y) = build_store(data, transform, precision, &path, &bars)?;
    r.stores.push(StoreRow {
        transform,
        precision,
        time: t.elapsed(),
        bytes: store.len_bytes(),
    });
    let gram = GramData::new(y.clone(), store.rows())?;
    Ok((store, gram, y))
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
    let fit = params.fit(gram, &brdf_atlas_core::NoProgress)?;
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

/// Write a model file for `fit` on `store` into `work` and open it.
#[allow(clippy::too_many_arguments)]
fn model_file(
    work: &Path,
    name: &str,
    data: &Dataset,
    fit: &Fit,
    store: &Store,
    y: &Mat<f64>,
    gram: &GramData,
) -> Result<Model, Error> {
    let path = work.join(format!("{name}.atlas"));
    let store_name = store
        .path()
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let rows = (0..y.nrows())
        .map(|i| (0..y.ncols()).map(|j| y[(i, j)]).collect())
        .collect();
    let file = ModelFile::new(data.names.clone(), fit, store, rows, gram, store_name);
    Model::write_file(&path, &file)?;
    Ok(Model::open(&path)?)
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

fn compare_precision(m32: &Model, m64: &Model, plan: &Plan, r: &mut Results) -> Result<(), Error> {
    for x in probe_points(m32, plan.points) {
        let (a, time32) = timed(plan.repeat, || Ok(m32.at(&x)?.table()))?;
        let (b, time64) = timed(plan.repeat, || Ok(m64.at(&x)?.table()))?;
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

fn map_samples(model: &Model, plan: &Plan, r: &mut Results) -> Result<(), Error> {
    let view = View::default();
    let w = 4 * plan.grid;
    let pixels: Vec<(usize, usize)> = (0..plan.grid)
        .flat_map(|a| (0..plan.grid).map(move |b| (2 + 4 * a, 2 + 4 * b)))
        .collect();
    let dense = Quadrature::dense(model.dims(), 1);
    let t = Instant::now();
    let reference = pixels
        .iter()
        .map(|&(px, py)| {
            reference_albedo(
                model,
                &view.pixel_to_latent(px as f64, py as f64, w, w),
                &dense,
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    r.reference_time = t.elapsed();
    r.reference_pixels = pixels.len();
    let bars = Bars::new("map sample counts");
    for &s in &plan.samples {
        let small = model.albedo_map(w, w, view, Some(s), &brdf_atlas_core::NoProgress)?;
        let (max_err, mean_err) = map_error(&small, &pixels, &reference);
        let size = plan.timed_size;
        let (map, time) = timed(plan.repeat, || {
            Ok(model.albedo_map(size, size, view, Some(s), &bars)?)
        })?;
        let bins = match map.method {
            AlbedoMethod::Quadrature { bins, .. } => bins,
            AlbedoMethod::Linear => 0,
        };
        r.samples.push(SampleRow {
            samples: s,
            bins,
            max_err,
            mean_err,
            time,
        });
    }
    Ok(())
}

/// `/proc/loadavg`'s first three numbers, if readable.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".into())
}

/// The CPU model from `/proc/cpuinfo`, if readable.
fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// Today's date (UTC) as `YYYY-MM-DD`, from the system clock.
fn today() -> String {
    let days = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400) as i64;
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + (month <= 2) as i64;
    format!("{year:04}-{month:02}-{day:02}")
}

fn write_file(dir: &Path, name: &str, text: &str) -> Result<(), Error> {
    let path = dir.join(name);
    std::fs::write(&path, text)
        .map_err(|e| Error::Input(format!("{}: cannot write: {e}", path.display())))
}

fn write_csvs(dir: &Path, r: &Results) -> Result<(), Error> {
    let mut s = String::from(
        "transform,method,q,rmse_reflectance,rmse_cos_log,rmse_transformed,pca_in_sample_rmse_transformed\n",
    );
    for l in &r.loo {
        let _ = writeln!(
            s,
            "{},{},{},{:e},{:e},{:e},{}",
            l.transform.name(),
            l.method,
            l.q,
            l.raw,
            l.log,
            l.transformed,
            l.in_sample.map_or(String::new(), |v| format!("{v:e}"))
        );
    }
    write_file(dir, "loo.csv", &s)?;
    let mut s = String::from("transform,method,q,material,rmse_reflectance,rmse_cos_log\n");
    for l in &r.loo {
        for (name, (raw, log)) in r.names.iter().zip(&l.materials) {
            let _ = writeln!(
                s,
                "{},{},{},{name},{raw:e},{log:e}",
                l.transform.name(),
                l.method,
                l.q
            );
        }
    }
    write_file(dir, "loo-materials.csv", &s)?;
    let mut s =
        String::from("transform,q,optimizer,min_step,seconds,initial_cost,cost,evaluations\n");
    for f in r.fits.iter().chain(&r.sweep) {
        let _ = writeln!(
            s,
            "{},{},{},{},{:.4},{:e},{:e},{}",
            f.transform.name(),
            f.q,
            f.optimizer.name(),
            f.min_step,
            f.time.as_secs_f64(),
            f.initial_cost,
            f.cost,
            f.evaluations
        );
    }
    write_file(dir, "fits.csv", &s)?;
    let mut s = String::from("samples,bins,max_rel_error,mean_rel_error,seconds\n");
    for m in &r.samples {
        let _ = writeln!(
            s,
            "{},{},{:e},{:e},{:.4}",
            m.samples,
            m.bins,
            m.max_err,
            m.mean_err,
            m.time.as_secs_f64()
        );
    }
    write_file(dir, "map-samples.csv", &s)?;
    let mut s = String::from("method,size,seconds\n");
    for m in &r.sizes {
        let _ = writeln!(s, "{},{},{:.4}", m.method, m.size, m.time.as_secs_f64());
    }
    write_file(dir, "map-size.csv", &s)?;
    let mut s = String::from("transform,precision,build_seconds,bytes\n");
    for st in &r.stores {
        let _ = writeln!(
            s,
            "{},{},{:.3},{}",
            st.transform.name(),
            st.precision.name(),
            st.time.as_secs_f64(),
            st.bytes
        );
    }
    write_file(dir, "stores.csv", &s)?;
    let mut s =
        String::from("point,max_abs_diff,max_diff_over_peak,rms_diff,seconds_f32,seconds_f64\n");
    for p in &r.precision {
        let _ = writeln!(
            s,
            "\"{}\",{:e},{:e},{:e},{:.4},{:.4}",
            point(&p.point),
            p.max_abs,
            p.max_rel,
            p.rms,
            p.time32.as_secs_f64(),
            p.time64.as_secs_f64()
        );
    }
    write_file(dir, "precision.csv", &s)
}

fn point(x: &[f64]) -> String {
    x.iter()
        .map(|v| format!("{v:.3}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn pct(v: f64) -> String {
    if v >= 0.1 {
        format!("{:.0}%", 100.0 * v)
    } else if v >= 0.001 {
        format!("{:.2}%", 100.0 * v)
    } else {
        format!("{:.1e}%", 100.0 * v)
    }
}

fn g4(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

impl Results {
    fn loo_row(&self, t: TransformKind, method: &str, q: usize) -> Option<&LooRow> {
        self.loo
            .iter()
            .find(|l| l.transform == t && l.method == method && l.q == q)
    }
}

fn markdown(
    options: &Options,
    plan: &Plan,
    r: &Results,
    total: Duration,
    load_start: String,
    load_end: String,
) -> String {
    let n = r.names.len();
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "# brdf-atlas report: what accuracy costs\n");
    let _ = writeln!(
        w,
        "Data: {n} materials ({}, d = {} values each) from `{}`. Measured on {} by \
         brdf-atlas {}{}, in {} in all.\n",
        r.dims,
        r.d,
        options.dir.display(),
        today(),
        env!("CARGO_PKG_VERSION"),
        if options.quick { " with `--quick`" } else { "" },
        secs(total)
    );
    let _ = writeln!(
        w,
        "Machine: {} ({} hardware threads available), {} rayon threads; load average \
         {load_start} at the start, {load_end} at the end. The machine may be shared: times \
         are wall times of single runs{}, \
         upper bounds rather than best cases. Files were read through the page cache.\n",
        cpu_model(),
        std::thread::available_parallelism().map_or(0, |p| p.get()),
        rayon::current_num_threads(),
        if plan.repeat {
            " (the median of three when a run takes under 0.7 s)"
        } else {
            ""
        }
    );
    let _ = writeln!(
        w,
        "Opening and validating the {n} files took {}. Files here: `loo.csv`, `loo-materials.csv`, `fits.csv`, `stores.csv`, \
         `precision.csv`, `map-samples.csv`, `map-size.csv`, and the plots below.\n",
        secs(r.scan)
    );

    // Leave-one-out.
    let _ = writeln!(w, "## Leave-one-out reconstruction error\n");
    let _ = writeln!(
        w,
        "![Leave-one-out error vs latent dimension](loo.png)\n\n\
         Each material is predicted from the other {} and compared with itself. \
         **GPLVM**: the model's prediction at the held-out material's latent point, \
         `z_i - (K^-1 Z)_i / (K^-1)_ii` in closed form, with the mean material also \
         re-estimated without it (closed form too); the latent points and \
         hyperparameters are those fitted on all {n} materials (no refit), so the \
         held-out material still shaped where it sits. Fits by {} (minimum step \
         1e-3 for Hooke-Jeeves, the default optimiser of `fit`), and at q = 2 by {} \
         too. **PCA held out**: the \
         material projected on the top q principal directions of the other {} \
         materials, centred by their own mean (a proper leave-one-out, one \
         eigen-decomposition of their Gram matrix per material). **PCA in sample** \
         (transformed space only): the residual when every material is projected on \
         the directions of all {n}, itself included, from the discarded eigenvalues \
         of `Z Z^T`; it is not a held-out error, and is the best any q-component linear model can do on these materials (the GPLVM is not linear and can beat it).\n",
        n - 1,
        options.optimizer.name(),
        other_optimizer(options.optimizer).name(),
        n - 1
    );
    let _ = writeln!(
        w,
        "Metrics, over all materials and the {} of {} table values that some input \
         measured and that are not grazing (`cos_i cos_o >= 1e-6`): **reflectance \
         RMSE** in 1/sr (the prediction inverted from the model's transform per value \
         and clamped to >= 0, as `reconstruct` writes it; highlights dominate it) and \
         **cosine-weighted log RMSE**, the RMSE of `log(1 + f cos_i cos_o)` \
         (Sztrajman et al. 2021). The reference values are the materials as stored \
         (f32, unmeasured samples read as 0). The transformed-space RMSE is over all \
         values.\n",
        r.scored_rows, r.d
    );
    let _ = writeln!(
        w,
        "| q | transform | GPLVM refl. | GPLVM log | PCA held out refl. | PCA held out log | GPLVM transformed | PCA held out transformed | PCA in sample transformed |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|");
    for q in 1..=plan.q_max {
        for t in [TransformKind::Log, TransformKind::Raw] {
            if let (Some(g), Some(p)) = (r.loo_row(t, "gplvm", q), r.loo_row(t, "pca", q)) {
                let _ = writeln!(
                    w,
                    "| {q} | {} | {} | {} | {} | {} | {} | {} | {} |",
                    t.name(),
                    g4(g.raw),
                    g4(g.log),
                    g4(p.raw),
                    g4(p.log),
                    g4(g.transformed),
                    g4(p.transformed),
                    p.in_sample.map_or("-".into(), g4)
                );
            }
        }
    }
    for t in [TransformKind::Log, TransformKind::Raw] {
        if let Some(l) = r.loo_row(t, "gplvm-other", 2) {
            let _ = writeln!(
                w,
                "\nGPLVM q = 2 fitted by {} instead ({} transform): reflectance RMSE {}, log RMSE {}.",
                other_optimizer(options.optimizer).name(),
                t.name(),
                g4(l.raw),
                g4(l.log)
            );
        }
    }
    let _ = writeln!(w, "\n![Reflectance RMSE](loo-reflectance.png)\n");
    for (t, count, time) in &r.loo_times {
        let _ = writeln!(
            w,
            "The {} transform's leave-one-out pass: {count} predictors in {} (one streaming \
             pass over the store, all predictors at once).",
            t.name(),
            secs(*time)
        );
    }
    // Worst materials at the default settings.
    if let Some(l) = r.loo_row(TransformKind::Log, "gplvm", 2.min(plan.q_max)) {
        let _ = writeln!(
            w,
            "\n### Worst materials (GPLVM, log transform, q = {})\n",
            l.q
        );
        let _ = writeln!(
            w,
            "| by log RMSE | log RMSE | by reflectance RMSE | refl. RMSE |"
        );
        let _ = writeln!(w, "|---|---|---|---|");
        let mut by_log: Vec<usize> = (0..n).collect();
        by_log.sort_by(|&a, &b| l.materials[b].1.total_cmp(&l.materials[a].1));
        let mut by_raw: Vec<usize> = (0..n).collect();
        by_raw.sort_by(|&a, &b| l.materials[b].0.total_cmp(&l.materials[a].0));
        for k in 0..5.min(n) {
            let _ = writeln!(
                w,
                "| {} | {} | {} | {} |",
                r.names[by_log[k]],
                g4(l.materials[by_log[k]].1),
                r.names[by_raw[k]],
                g4(l.materials[by_raw[k]].0)
            );
        }
        let _ = writeln!(w, "\nEvery material and method: `loo-materials.csv`.");
    }

    // Fits.
    let _ = writeln!(w, "\n## Fitting: Hooke-Jeeves vs L-BFGS\n");
    let _ = writeln!(
        w,
        "Times are the optimiser alone (PCA start included), from the Gram matrix \
         each transform's store pass built once; the cost is the negative log \
         likelihood of the normalised data (lower is better).\n"
    );
    let _ = writeln!(
        w,
        "| transform | q | optimiser | time | start cost | final cost | evaluations |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|");
    for f in &r.fits {
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {} | {} |",
            f.transform.name(),
            f.q,
            f.optimizer.name(),
            secs(f.time),
            g4(f.initial_cost),
            g4(f.cost),
            f.evaluations
        );
    }
    if !r.sweep.is_empty() {
        let _ = writeln!(
            w,
            "\n![Cost reached vs time](optimizers.png)\n\nHooke-Jeeves' minimum step \
             (log transform, q = 2; the default is 1e-3):\n"
        );
        let _ = writeln!(w, "| min step | time | final cost | evaluations |");
        let _ = writeln!(w, "|---|---|---|---|");
        for f in &r.sweep {
            let _ = writeln!(
                w,
                "| {:e} | {} | {} | {} |",
                f.min_step,
                secs(f.time),
                g4(f.cost),
                f.evaluations
            );
        }
    }

    // Maps.
    if !r.samples.is_empty() {
        let _ = writeln!(w, "\n## Albedo map (log transform, q = 2)\n");
        let _ = writeln!(
            w,
            "![Map error and time vs quadrature samples](map-samples.png)\n\n\
             Error: at {} pixels of a small map, the per-pixel quadrature albedo against \
             the dense rule (every bin, 8 sub-cells) applied to the full reconstruction \
             at the same latent point ({} for the references), relative to the \
             reference's largest channel. Time: one {}x{} map.\n",
            r.reference_pixels,
            secs(r.reference_time),
            plan.timed_size,
            plan.timed_size
        );
        let _ = writeln!(w, "| samples | bins read | max error | mean error | time |");
        let _ = writeln!(w, "|---|---|---|---|---|");
        for m in &r.samples {
            let _ = writeln!(
                w,
                "| {}{} | {} | {} | {} | {} |",
                m.samples,
                if m.samples == DEFAULT_SAMPLES {
                    " (default)"
                } else {
                    ""
                },
                m.bins,
                pct(m.max_err),
                pct(m.mean_err),
                secs(m.time)
            );
        }
        let _ = writeln!(w, "\n![Map time vs size](map-size.png)\n");
        let _ = writeln!(w, "| size | method | time |");
        let _ = writeln!(w, "|---|---|---|");
        for m in &r.sizes {
            let _ = writeln!(w, "| {0}x{0} | {1} | {2} |", m.size, m.method, secs(m.time));
        }
    }

    // Precision.
    let _ = writeln!(w, "\n## Store precision: f32 vs f64\n");
    let _ = writeln!(
        w,
        "| transform | precision | store build (pass + Gram) | size |"
    );
    let _ = writeln!(w, "|---|---|---|---|");
    for st in &r.stores {
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} |",
            st.transform.name(),
            st.precision.name(),
            secs(st.time),
            size(st.bytes)
        );
    }
    let _ = writeln!(
        w,
        "\nThe store is memory-mapped: its size is the memory a reconstruction or map \
         touches. Gram matrix from the f32 store vs the f64 store: largest difference \
         {} of its largest entry.\n",
        g4(r.gram_rel_diff)
    );
    if !r.precision.is_empty() {
        let _ = writeln!(
            w,
            "Full reconstructions (log transform, q = 2) at the same latent points and \
             weights from the f32 and the f64 store, in reflectance (1/sr):\n"
        );
        let _ = writeln!(
            w,
            "| latent point | max difference | max / peak value | RMS difference | time f32 | time f64 |"
        );
        let _ = writeln!(w, "|---|---|---|---|---|---|");
        for p in &r.precision {
            let _ = writeln!(
                w,
                "| ({}) | {} | {} | {} | {} | {} |",
                point(&p.point),
                g4(p.max_abs),
                g4(p.max_rel),
                g4(p.rms),
                secs(p.time32),
                secs(p.time64)
            );
        }
    }
    s
}
