//! `brdf_atlas.fit`: the command-line tool's `fit`, with a progress callback.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use brdf_atlas_core::limits::MAX_Q;
use brdf_atlas_core::{
    Atlas, Dataset, FitOptions, GplvmParams, Model, OptimizerKind, Precision, Progress,
    TransformKind, default_kernel, fit_dir, store_path_for,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Failure, Result};

/// Least time between two calls of the progress callback within one phase.
const CALLBACK_INTERVAL: Duration = Duration::from_millis(100);

/// A [`Progress`] that calls a Python callable `callback(label, done,
/// total)`: once when a phase starts, at most every [`CALLBACK_INTERVAL`]
/// while it runs, once when it ends. The first exception the callable raises
/// is kept (and later calls skipped) for the caller to raise.
struct Callback {
    callable: Py<PyAny>,
    state: Mutex<Phase>,
    done: AtomicU64,
    error: Mutex<Option<PyErr>>,
}

struct Phase {
    label: String,
    total: u64,
    last: Instant,
}

impl Callback {
    fn call(&self, label: &str, done: u64, total: u64) {
        let mut error = self.error.lock().unwrap_or_else(|e| e.into_inner());
        if error.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = self.callable.call1(py, (label, done, total)) {
                *error = Some(e);
            }
        });
    }
}

impl Progress for Callback {
    fn start(&self, label: &str, total: u64) {
        {
            let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
            *s = Phase {
                label: label.to_string(),
                total,
                last: Instant::now(),
            };
        }
        self.done.store(0, Ordering::Relaxed);
        self.call(label, 0, total);
    }

    fn advance(&self, delta: u64) {
        let done = self.done.fetch_add(delta, Ordering::Relaxed) + delta;
        let due = {
            let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
            if s.last.elapsed() >= CALLBACK_INTERVAL {
                s.last = Instant::now();
                Some((s.label.clone(), s.total))
            } else {
                None
            }
        };
        if let Some((label, total)) = due {
            self.call(&label, done.min(total), total);
        }
    }

    fn finish(&self) {
        let (label, total) = {
            let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
            (s.label.clone(), s.total)
        };
        self.call(&label, total, total);
    }
}

/// `.binary` files in `dir`, as the library counts them; `None` when the
/// directory cannot be listed (the library then says why).
fn count_binaries(dir: &Path) -> Option<usize> {
    let entries = std::fs::read_dir(dir).ok()?;
    Some(
        entries
            .filter_map(std::result::Result::ok)
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "binary") && !p.is_dir())
            .count(),
    )
}

fn choice<T>(value: &str, option: &str, parse: fn(&str) -> Option<T>, names: &str) -> Result<T> {
    parse(value).ok_or_else(|| Failure::input(format!("{option} {value:?}: expected {names}")))
}

/// Fit a latent space to the MERL `.binary` files of `merl_dir` (sorted by
/// name) and write the model file `out` and its store `out.store`, as
/// `brdf-atlas fit MERL_DIR -o OUT` does, with the same options and
/// defaults and the same messages on failure. Both files are written
/// atomically: a failed fit leaves earlier files as they were.
///
/// `progress(label, done, total)`, if given, is called as each phase starts,
/// every 0.1 s or so while it runs and when it ends; an exception it raises
/// is raised again once the fit has finished (the fit is not interrupted).
///
/// A re-fit into the same `out` of the same files, unchanged since, with
/// the same `transform` and `store_precision` uses the existing store again
/// (no store pass): `store_reused` says so.
///
/// With `map_field` (the default, as the command-line tool) a 2-D model's
/// map fields of the default view and of [-3, 3]^2 are built after the fit
/// and saved beside the model (`fields`: its `.fields` file), so that the
/// first maps of those regions, in any program, only evaluate them.
///
/// Returns a dict: `model`, `store` (paths), `store_reused`, `names`,
/// `ignored` (entries left out, with why), `cost`, `initial_cost`,
/// `iterations`, `evaluations`, `fields` (the saved fields' path, or None),
/// and `seconds` (per phase: scan, store, optimise, save, map_field).
#[pyfunction]
#[pyo3(signature = (merl_dir, out, *, q = 2, transform = "rel-log", optimizer = "lbfgs",
                    store_precision = "f32", length_scale = None, noise = 3e-5, min_step = 1e-3,
                    map_field = true, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn fit<'py>(
    py: Python<'py>,
    merl_dir: PathBuf,
    out: PathBuf,
    q: usize,
    transform: &str,
    optimizer: &str,
    store_precision: &str,
    length_scale: Option<f64>,
    noise: f64,
    min_step: f64,
    map_field: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let transform = choice(
        transform,
        "transform",
        TransformKind::parse,
        "\"rel-log\", \"log\" or \"raw\"",
    )?;
    let optimizer = choice(
        optimizer,
        "optimizer",
        OptimizerKind::parse,
        "\"hooke-jeeves\" or \"lbfgs\"",
    )?;
    let precision = choice(
        store_precision,
        "store_precision",
        Precision::parse,
        "\"f32\" or \"f64\"",
    )?;
    // The default length scale depends on how many materials there are
    // (`default_kernel`): the directory's listing says.
    let length_scale = length_scale
        .unwrap_or_else(|| default_kernel(count_binaries(&merl_dir).unwrap_or(0)).length_scale);
    let params = GplvmParams::new(q)
        .length_scale(length_scale)
        .noise(noise)
        .optimizer(optimizer)
        .min_step(min_step)
        .check()
        .map_err(Failure::from)?;
    let callback = progress.map(|callable| Callback {
        callable,
        state: Mutex::new(Phase {
            label: String::new(),
            total: 0,
            last: Instant::now(),
        }),
        done: AtomicU64::new(0),
        error: Mutex::new(None),
    });
    let report = py.detach(|| {
        let n = count_binaries(&merl_dir).unwrap_or(0);
        if n > 0 && q >= n {
            Dataset::open_dir(&merl_dir)?;
            return Err(Failure::input(format!(
                "{}: q = {q} needs more materials than latent dimensions (1 to {MAX_Q}), found {n} .binary file{}",
                merl_dir.display(),
                if n == 1 { "" } else { "s" }
            )));
        }
        let options = FitOptions {
            params,
            transform,
            precision,
        };
        let store_path = store_path_for(&out);
        let store_existed = store_path.exists();
        let progress: &dyn Progress = match &callback {
            Some(c) => c,
            None => &brdf_atlas_core::NoProgress,
        };
        let report = fit_dir(&merl_dir, &out, &options, progress).map_err(|e| {
            if !store_existed && !out.exists() {
                // Best effort, as the command-line tool: the error is what matters.
                let _ = std::fs::remove_file(&store_path);
            }
            Failure::from(e)
        })?;
        let t = Instant::now();
        let fields = if map_field && q == 2 {
            save_map_fields(&out, progress)?
        } else {
            None
        };
        Ok((report, fields, t.elapsed()))
    })?;
    let (report, fields, field_time) = report;
    if let Some(e) = callback.and_then(|c| c.error.into_inner().unwrap_or_else(|e| e.into_inner()))
    {
        return Err(e);
    }
    let d = PyDict::new(py);
    d.set_item("model", &report.model_path)?;
    d.set_item("store", &report.store_path)?;
    d.set_item("store_reused", report.store_reused)?;
    d.set_item("names", &report.names)?;
    let ignored: Vec<(PathBuf, String)> = report.ignored.clone();
    d.set_item("ignored", ignored)?;
    let outcome = &report.fit.outcome;
    d.set_item("cost", outcome.cost)?;
    d.set_item("initial_cost", outcome.initial_cost)?;
    d.set_item("iterations", outcome.iterations)?;
    d.set_item("evaluations", outcome.evaluations)?;
    let seconds = PyDict::new(py);
    seconds.set_item("scan", report.scan_time.as_secs_f64())?;
    seconds.set_item("store", report.store_time.as_secs_f64())?;
    seconds.set_item("optimise", report.optimise_time.as_secs_f64())?;
    seconds.set_item("save", report.save_time.as_secs_f64())?;
    seconds.set_item("map_field", field_time.as_secs_f64())?;
    d.set_item("seconds", seconds)?;
    d.set_item("fields", fields)?;
    Ok(d)
}

/// Build the map fields of the default view and of [-3, 3]^2 (a 1024 x
/// 1024 map's, of the default material) and save them beside the model, as
/// `brdf-atlas fit` does; the fields file, if one was written or was there.
fn save_map_fields(model: &Path, progress: &dyn Progress) -> Result<Option<PathBuf>> {
    let atlas = Atlas::new(Model::open(model)?);
    atlas.prepare_fit_fields(progress)?;
    let path = brdf_atlas_core::fields_path(model);
    Ok(path.exists().then_some(path))
}
