//! The whole fit: a directory of MERL files in, a model file and its store
//! out, each put in place only when both are complete.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use brdf_atomic::{Swapped, stage, swap_in};

use crate::data::store::build_unnamed;
use crate::data::{Dataset, Precision, Store, TransformKind};
use crate::error::{CoreError, Result};
use crate::eval::fidelity::Fidelity;
use crate::gplvm::Kernel;
use crate::gplvm::{CheckedParams, Fit, GramData};
use crate::model::file::{InputIdentity, ModelFile, StoreRef, store_path_for};
use crate::progress::Progress;

/// Settings of a whole fit from a directory of MERL files.
#[derive(Debug, Clone)]
pub struct FitOptions {
    /// GPLVM parameters.
    pub params: CheckedParams,
    /// Data transform.
    pub transform: TransformKind,
    /// Store precision.
    pub precision: Precision,
}

/// The data transform a fit uses unless told otherwise: `ln(1 + v / 1e-3)`,
/// under which dark materials are as far apart as they look.
pub const DEFAULT_TRANSFORM: TransformKind = TransformKind::RelLog;

/// The noise a fit uses unless told otherwise.
pub const DEFAULT_NOISE: f64 = 3e-5;

/// The kernel a fit of `materials` materials uses unless told otherwise:
/// `l = 3 / sqrt(N)` within `[0.3, 1]` (to a thousandth), `mu = 3e-5`. N materials spread
/// over the box `[-1, 1]^2` lie about `2 / sqrt(N)` apart, so the length
/// scale stays 1.5 times their spacing: short enough that every material's
/// own point gives it back, long enough that the model knows the whole map
/// between them. Chosen on the 100 NBRDF-derived materials (l = 0.3) by the
/// errors a person sees (docs/fidelity.md): every own point gives its
/// material back (albedo within 0.1% per channel at the median, 0.7% at
/// worst), each material predicted from the other 99 is 15% off at the
/// median, and the predictive variance is below 0.1 over all of the map's
/// default view; on 12 of them l = 0.3 would leave 84% of the view
/// unknown, l = 0.87 leaves 1%.
pub fn default_kernel(materials: usize) -> Kernel {
    Kernel {
        // To a thousandth, as a person would write it.
        length_scale: ((3.0 / (materials.max(1) as f64).sqrt()).clamp(0.3, 1.0) * 1e3).round()
            / 1e3,
        noise: DEFAULT_NOISE,
    }
}

/// The settings of Soler, Subr and Nowrouzezahrai 2018 with this tool's
/// earlier transform: `ln(1 + v)`, `l = 1`, `mu = 1e-4` (`fit --paper`).
pub const PAPER_TRANSFORM: TransformKind = TransformKind::Log;

/// The paper's kernel, `l = 1`, `mu = 1e-4` ([`Kernel::default`]).
pub const PAPER_KERNEL: Kernel = Kernel {
    length_scale: 1.0,
    noise: 1e-4,
};

/// What a fit did and how long each phase took.
#[derive(Debug)]
pub struct FitReport {
    /// The opened data set (materials, ignored entries).
    pub names: Vec<String>,
    /// Entries of the directory that were not used.
    pub ignored: Vec<(PathBuf, String)>,
    /// The fit.
    pub fit: Fit,
    /// The model file written.
    pub model_path: PathBuf,
    /// The store written.
    pub store_path: PathBuf,
    /// Opening the MERL files (mapping, header and size checks; their
    /// values are checked as the store pass reads them).
    pub scan_time: Duration,
    /// The one pass building the store and the Gram matrix (or checking
    /// that the store can be used again, [`FitReport::store_reused`]).
    pub store_time: Duration,
    /// The model's existing store was used again: the same input files,
    /// unchanged, with the same transform and precision, and the store as
    /// its fit left it. Nothing but the model file was written.
    pub store_reused: bool,
    /// The optimisation.
    pub optimise_time: Duration,
    /// Each material at its own point, judged against itself
    /// ([`crate::fidelity`]); the model file keeps it.
    pub fidelity: Fidelity,
    /// The pass over the store that judged them.
    pub fidelity_time: Duration,
    /// Writing the model and checksumming the store.
    pub save_time: Duration,
    /// Largest heap in use during the fit, when the binary counts it
    /// ([`crate::heap::Counting`]); the inputs and the store are mapped
    /// files, not heap.
    pub peak_heap: Option<usize>,
    /// Largest resident private memory of the process
    /// ([`crate::heap::resident_private`], `RssAnon`) during the fit,
    /// sampled every 5 ms and at the end; `None` where the system does not
    /// report it.
    pub peak_private: Option<u64>,
}

/// Whether a fit may use the model's existing store again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StorePolicy {
    /// Use it again when it holds exactly what this fit would build (the
    /// same input files, unchanged, with the same transform and precision;
    /// [`FitReport::store_reused`]): a re-fit with other settings of the
    /// GPLVM then skips the store pass.
    Reuse,
    /// Always build the store anew.
    Rebuild,
}

/// Fit a directory of MERL files and write `model` and `model.store`,
/// using the model's existing store again where it can
/// ([`StorePolicy::Reuse`]).
pub fn fit_dir(
    dir: &Path,
    model: &Path,
    options: &FitOptions,
    progress: &dyn Progress,
) -> Result<FitReport> {
    fit_dir_with(dir, model, options, StorePolicy::Reuse, progress)
}

/// [`fit_dir`] with the store's policy chosen.
pub fn fit_dir_with(
    dir: &Path,
    model: &Path,
    options: &FitOptions,
    policy: StorePolicy,
    progress: &dyn Progress,
) -> Result<FitReport> {
    let t0 = Instant::now();
    crate::heap::reset_peak();
    let private = PrivatePeak::default();
    private.start();
    let data = Dataset::map_dir(dir)?;
    let scan_time = t0.elapsed();
    let t1 = Instant::now();
    let store_path = store_path_for(model);
    fit_staged(
        &data,
        model,
        options,
        policy,
        progress,
        &store_path,
        scan_time,
        t1,
        &private,
    )
}

#[allow(clippy::too_many_arguments)]
fn fit_staged(
    data: &Dataset,
    model: &Path,
    options: &FitOptions,
    policy: StorePolicy,
    progress: &dyn Progress,
    store_path: &Path,
    scan_time: Duration,
    t1: Instant,
    private: &PrivatePeak,
) -> Result<FitReport> {
    let inputs = InputIdentity::of(data);
    let reused = match policy {
        StorePolicy::Reuse => reusable(model, store_path, options, &inputs),
        StorePolicy::Rebuild => None,
    };
    let store_reused = reused.is_some();
    // A new store is written without a name (where the file system
    // allows) and takes its place only once the fit has succeeded: a failed
    // or killed re-fit leaves the old pair intact and nothing beside it.
    let (store, y, old_ref, pending) = match reused {
        Some((store, y, old_ref)) => (store, y, Some(old_ref), None),
        None => {
            let (store, y, pending) = build_unnamed(
                data,
                options.transform,
                options.precision,
                store_path,
                progress,
            )?;
            (store, y, None, Some(pending))
        }
    };
    let store_time = t1.elapsed();
    let t2 = Instant::now();
    let file_y = y.clone();
    let gram = GramData::new(y, store.rows())?;
    let store_name = store_path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    // The optimisation runs on one core: meanwhile the other checksums the
    // new store (a read of all of it) and drops the old store's cached
    // pages (the file stays as it is until the new model is in place), so
    // removing it at the end is quick; unless it is the store this fit uses.
    let (fit, optimise_time, t3, store_ref) = std::thread::scope(|scope| {
        let checksum = match old_ref {
            Some(r) => Err(r),
            None => {
                scope.spawn(|| brdf_atomic::evict_cached(store_path));
                Ok(scope.spawn(|| StoreRef::of(&store, store_name)))
            }
        };
        let fit = options.params.fit(&gram, progress);
        let (optimise_time, t3) = (t2.elapsed(), Instant::now());
        let store_ref = match checksum {
            Err(old) => old,
            Ok(h) => h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)),
        };
        (fit, optimise_time, t3, store_ref)
    });
    let fit = fit?;
    let t4 = Instant::now();
    let fidelity = crate::eval::fidelity::fidelity(
        &store,
        fit.outcome.latent.as_ref(),
        &fit.kernel,
        false,
        crate::fidelity::JUDGED_BINS,
        progress,
    )?;
    let fidelity_time = t4.elapsed();
    let mut file = ModelFile::new(
        data.names.clone(),
        &fit,
        &store,
        file_y.as_ref(),
        &gram,
        store_ref,
    );
    file.inputs = Some(inputs);
    file.fidelity = Some(fidelity.clone());
    file.energy = Some(store.energy_bound().clone());
    // Both files are complete on disk before either takes its place.
    let json = file.to_json(model)?;
    let staged = stage(model, |w| std::io::Write::write_all(w, &json))
        .map_err(|e| CoreError::write(model, e))?;
    if model.is_dir() {
        return Err(CoreError::write(
            model,
            std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory"),
        ));
    }
    match pending {
        // The store stays where it is: only the model changes.
        None => brdf_atomic::critical(|| staged.commit(false))
            .map_err(|e| CoreError::write(model, e))?,
        // The store goes in by an exchange, so the old one (if any) is
        // still at hand until the model, the commit point, is in place. An
        // interrupt waits for the pair (`critical`), so it never sees one
        // without the other.
        Some(pending) => {
            let (swapped, staging) = brdf_atomic::critical(|| {
                let staging = pending
                    .into_named()
                    .map_err(|e| CoreError::write(store_path, e))?;
                let swapped = swap_in(&staging, store_path).map_err(|e| {
                    let _ = std::fs::remove_file(&staging);
                    CoreError::write(store_path, e)
                })?;
                if let Err(e) = staged.commit(false) {
                    if swapped == Swapped::Exchanged {
                        // Undo: the old store back beside the old model.
                        // Best effort; the commit's error is the one to
                        // report.
                        let _ = swap_in(&staging, store_path);
                    }
                    let _ = std::fs::remove_file(&staging);
                    return Err(CoreError::write(model, e));
                }
                Ok((swapped, staging))
            })?;
            if swapped == Swapped::Exchanged {
                // The old store. Freeing its cached pages is most of the
                // time a re-fit spends saving; failing to remove it loses
                // nothing.
                let _ = std::fs::remove_file(staging);
            }
        }
    }
    // From the end of the optimisation (the checksum's join among it), less
    // the own-point pass.
    let save_time = t3.elapsed().saturating_sub(fidelity_time);
    Ok(FitReport {
        names: data.names.clone(),
        ignored: data.ignored.clone(),
        fit,
        model_path: model.to_path_buf(),
        store_path: store_path.to_path_buf(),
        scan_time,
        store_time,
        store_reused,
        optimise_time,
        fidelity,
        fidelity_time,
        save_time,
        peak_heap: crate::heap::peak(),
        peak_private: private.peak(),
    })
}

/// The store of the model at `model`, with its Gram matrix and reference,
/// when a fit with `options` of the files `inputs` would build the same
/// store again: the model records the same inputs (names, files, sizes,
/// modification times), transform and precision, and the store is the file
/// its fit wrote ([`crate::data::StoreIdentity`]). Anything else (no model,
/// an older one without inputs, an unreadable one) builds anew.
fn reusable(
    model: &Path,
    store_path: &Path,
    options: &FitOptions,
    inputs: &[InputIdentity],
) -> Option<(Store, faer::Mat<f64>, StoreRef)> {
    let text = brdf_mapguard::read_regular(model).ok()?;
    let old = ModelFile::from_json(model, &text).ok()?;
    let same = old.inputs.as_deref() == Some(inputs)
        && old.transform == options.transform
        && old.precision == options.precision
        && store_path
            .file_name()
            .is_some_and(|n| *n == *old.store.path)
        && old.store.identity.is_some();
    if !same {
        return None;
    }
    let store = Store::open(store_path).ok()?;
    // The identity holds the size too.
    if store.identity() != old.store.identity {
        return None;
    }
    let n = old.names.len();
    let y = faer::Mat::from_fn(n, n, |i, j| old.gram[i][j]);
    Some((store, y, old.store))
}

/// The process's largest resident private memory
/// ([`crate::heap::resident_private`]) while
/// it is alive: a thread samples it every [`PrivatePeak::PERIOD`].
#[derive(Default)]
struct PrivatePeak {
    /// Bytes, 0 before the first sample.
    peak: Arc<AtomicU64>,
    stop: Arc<AtomicBool>,
}

impl PrivatePeak {
    const PERIOD: Duration = Duration::from_millis(5);

    /// Start sampling (if the system reports private memory).
    fn start(&self) {
        let Some(first) = crate::heap::resident_private() else {
            return;
        };
        self.peak.store(first, Ordering::Relaxed);
        let (peak, stop) = (self.peak.clone(), self.stop.clone());
        // Without a thread, one sample here and one at the end.
        let _ = std::thread::Builder::new()
            .name("memory sampler".into())
            .stack_size(64 << 10)
            .spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    if let Some(now) = crate::heap::resident_private() {
                        peak.fetch_max(now, Ordering::Relaxed);
                    }
                    std::thread::sleep(PrivatePeak::PERIOD);
                }
            });
    }

    /// The largest sample, with one taken now.
    fn peak(&self) -> Option<u64> {
        let now = crate::heap::resident_private()?;
        Some(self.peak.fetch_max(now, Ordering::Relaxed).max(now))
    }
}

impl Drop for PrivatePeak {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}
