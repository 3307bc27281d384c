//! The model file: a fitted latent space beside its store.
//!
//! A model is two files: `NAME` (JSON, small, self-describing, versioned)
//! and `NAME.store` (the data, see [`crate::data::store`]). The JSON names the
//! store relative to itself and records its size and checksum, so a moved
//! pair still opens and a changed store is refused. Both are written
//! atomically.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use brdf_merl::Dims;
use brdf_merl::atomic::{Swapped, stage, swap_in, write_atomic};
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use serde::{Deserialize, Serialize};

use crate::data::transform::{Transform, TransformKind};
use crate::data::{Dataset, Precision, Store, build_store};
use crate::error::{CoreError, Result};
use crate::gplvm::incremental::DriftStats;
use crate::gplvm::kernel::Kernel;
use crate::gplvm::likelihood::GramData;
use crate::gplvm::optim::OptimizerKind;
use crate::gplvm::{CheckedParams, Fit};
use crate::progress::Progress;
use crate::query::map::MapBasis;

/// The `format` field of every model file.
pub const FORMAT: &str = "brdf-atlas-model";
/// The model format version this build writes and reads.
pub const VERSION: u32 = 1;

/// Where the store is and how to recognise it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoreRef {
    /// Path of the store, relative to the model file's directory.
    pub path: String,
    /// Its size in bytes.
    pub bytes: u64,
    /// Its checksum ([`Store::checksum`]), hex.
    pub checksum: String,
}

/// What the optimiser did, for the record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitRecord {
    /// Optimiser used.
    pub optimizer: OptimizerKind,
    /// Cost at the PCA start.
    pub initial_cost: f64,
    /// Final cost `d/2 log|K| + 1/2 tr(K^-1 Y)` (normalised `Y`).
    pub cost: f64,
    /// Optimiser iterations.
    pub iterations: u64,
    /// Cost evaluations.
    pub evaluations: u64,
    /// Accepted pattern moves.
    pub pattern_moves: u64,
    /// Incremental-update health.
    pub drift: DriftStats,
    /// Eigenvalues of the normalised Gram matrix, descending.
    pub eigenvalues: Vec<f64>,
}

/// The JSON content of a model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// Always [`FORMAT`].
    pub format: String,
    /// Format version ([`VERSION`]).
    pub version: u32,
    /// Material names, in store column order.
    pub names: Vec<String>,
    /// Latent points, one `q`-vector per material.
    pub latent: Vec<Vec<f64>>,
    /// Kernel hyperparameters.
    pub kernel: Kernel,
    /// Data transform of the store.
    pub transform: TransformKind,
    /// Store precision.
    pub precision: Precision,
    /// Table dims `[theta_h, theta_d, phi_d]`.
    pub dims: [usize; 3],
    /// Dimension `d` of each material (3 * bins).
    pub d: usize,
    /// The variance the Gram matrix was normalised by before fitting.
    pub signal_variance: f64,
    /// The fit.
    pub fit: FitRecord,
    /// The Gram matrix `Y = Z Z^T` of the centred data (not normalised),
    /// row by row: what locating a new material needs.
    pub gram: Vec<Vec<f64>>,
    /// The store.
    pub store: StoreRef,
}

impl ModelFile {
    /// The model file of `fit` on `store` (materials `names`, in store
    /// order; `gram_rows` the Gram matrix before normalisation, `gram` the
    /// fitted data; the store named `store_name` beside the model file).
    /// Checksums the store.
    pub fn new(
        names: Vec<String>,
        fit: &Fit,
        store: &Store,
        gram_rows: Vec<Vec<f64>>,
        gram: &GramData,
        store_name: String,
    ) -> ModelFile {
        let dims = store.dims();
        let o = &fit.outcome;
        ModelFile {
            format: FORMAT.into(),
            version: VERSION,
            names,
            latent: (0..o.latent.nrows())
                .map(|i| (0..o.latent.ncols()).map(|c| o.latent[(i, c)]).collect())
                .collect(),
            kernel: fit.kernel,
            transform: store.transform(),
            precision: store.precision(),
            dims: [dims.theta_h, dims.theta_d, dims.phi_d],
            d: store.rows(),
            signal_variance: gram.scale2(),
            fit: FitRecord {
                optimizer: fit.optimizer,
                initial_cost: o.initial_cost,
                cost: o.cost,
                iterations: o.iterations,
                evaluations: o.evaluations,
                pattern_moves: o.pattern_moves,
                drift: o.drift,
                eigenvalues: fit.eigenvalues.clone(),
            },
            gram: gram_rows,
            store: StoreRef {
                path: store_name,
                bytes: store.len_bytes(),
                checksum: format!("{:016x}", store.checksum()),
            },
        }
    }
}

/// An opened model: the file, its store mapped, `K` factorised.
pub struct Model {
    path: PathBuf,
    file: ModelFile,
    store: Store,
    latent: Mat<f64>,
    llt: faer::linalg::solvers::Llt<f64>,
    pub(crate) transform: Box<dyn Transform>,
    pub(crate) gram: Mat<f64>,
    /// What every map of this model shares, built on first use.
    pub(crate) map_basis: MapBasis,
}

impl std::fmt::Debug for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Model")
            .field("path", &self.path)
            .field("n", &self.file.names.len())
            .finish()
    }
}

/// The store file that goes with a model path: `NAME.store`.
pub fn store_path_for(model: &Path) -> PathBuf {
    let mut s = model.as_os_str().to_os_string();
    s.push(".store");
    PathBuf::from(s)
}

pub use crate::limits::{LATENT_LIMIT, MAX_MATERIALS, MAX_Q};

impl ModelFile {
    /// Parse and check the JSON of a model file without touching its store:
    /// format, version, the shapes of every array and the sanity of every
    /// number. `path` names the file in errors.
    pub fn from_json(path: &Path, bytes: &[u8]) -> Result<ModelFile> {
        let bad = |why: String| CoreError::bad_file(path, why);
        if brdf_merl::table::is_lfs_pointer(bytes) {
            return Err(bad(
                "is a Git LFS pointer file, not a brdf-atlas model (run `git lfs pull` to fetch the real file)".into(),
            ));
        }
        if bytes.iter().all(u8::is_ascii_whitespace) {
            return Err(bad("empty file, expected a brdf-atlas model (JSON)".into()));
        }
        let value: serde_json::Value = serde_json::from_slice(bytes)
            .map_err(|e| bad(format!("not a brdf-atlas model (invalid JSON: {e})")))?;
        if value.get("format").and_then(|v| v.as_str()) != Some(FORMAT) {
            return Err(bad(format!(
                "not a brdf-atlas model (expected \"format\": \"{FORMAT}\")"
            )));
        }
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if v == VERSION as u64 => {}
            Some(v) if v > VERSION as u64 => {
                return Err(bad(format!(
                    "model format version {v} was written by a newer brdf-atlas (this build reads version {VERSION}); upgrade brdf-atlas"
                )));
            }
            Some(v) => {
                return Err(bad(format!(
                    "model format version {v}, this build reads version {VERSION}"
                )));
            }
            None => {
                return Err(bad(
                    "model has no version number (expected \"version\": 1)".into()
                ));
            }
        }
        let file: ModelFile =
            serde_json::from_value(value).map_err(|e| bad(format!("malformed model: {e}")))?;
        file.check().map_err(bad)?;
        Ok(file)
    }

    /// Shapes and ranges of everything the JSON holds.
    fn check(&self) -> std::result::Result<(), String> {
        let n = self.names.len();
        if n == 0 || n > MAX_MATERIALS {
            return Err(format!("{n} materials, expected 1 to {MAX_MATERIALS}"));
        }
        if self.latent.len() != n {
            return Err(format!("{n} names but {} latent points", self.latent.len()));
        }
        let q = self.latent[0].len();
        if q == 0 || q > MAX_Q || q >= n {
            return Err(format!(
                "latent dimension q = {q}, expected 1 to {MAX_Q} and fewer than the {n} materials"
            ));
        }
        for (i, p) in self.latent.iter().enumerate() {
            if p.len() != q {
                return Err(format!(
                    "latent point {i} has {} coordinates, the first has {q}",
                    p.len()
                ));
            }
            if let Some(v) = p.iter().find(|v| v.is_nan() || v.abs() > LATENT_LIMIT) {
                return Err(format!(
                    "latent point {i} ({}) has coordinate {v:?}, expected finite numbers within +-{LATENT_LIMIT} (a fit keeps them in [-1, 1])",
                    self.names[i]
                ));
            }
        }
        self.kernel
            .check()
            .map_err(|why| format!("kernel: {why}"))?;
        let dims = Dims::new(self.dims[0], self.dims[1], self.dims[2])
            .map_err(|e| format!("\"dims\": {e}"))?;
        if self.d != dims.values() {
            return Err(format!(
                "d = {}, but dims {dims} have {} values",
                self.d,
                dims.values()
            ));
        }
        if !(self.signal_variance.is_finite() && self.signal_variance > 0.0) {
            return Err(format!(
                "signal variance {:?} must be positive and finite",
                self.signal_variance
            ));
        }
        if self.gram.len() != n
            || self
                .gram
                .iter()
                .any(|r| r.len() != n || r.iter().any(|v| !v.is_finite()))
        {
            return Err(format!("the Gram matrix must be {n}x{n} finite numbers"));
        }
        let name = Path::new(&self.store.path);
        if self.store.path.is_empty() || name.is_absolute() {
            return Err(format!(
                "store path {:?}: expected a path relative to the model file",
                self.store.path
            ));
        }
        Ok(())
    }
}

impl Model {
    /// Open a model file and its store; check format, version, shapes, the
    /// store's size and checksum, and factorise `K`.
    pub fn open(path: impl AsRef<Path>) -> Result<Model> {
        let path = path.as_ref().to_path_buf();
        let text = std::fs::read(&path).map_err(|e| CoreError::io(&path, e))?;
        let file = ModelFile::from_json(&path, &text)?;
        let n = file.names.len();
        let q = file.latent[0].len();
        let kernel = file.kernel;
        let dir = path.parent().unwrap_or(Path::new("."));
        let store_path = dir.join(&file.store.path);
        let store = Store::open(&store_path)?;
        let sbad = |why: String| CoreError::bad_file(&store_path, why);
        if store.len_bytes() != file.store.bytes {
            return Err(sbad(format!(
                "{} bytes, the model {} expects {} (the store was changed or replaced)",
                store.len_bytes(),
                path.display(),
                file.store.bytes
            )));
        }
        let dims = store.dims();
        if store.n() != n
            || [dims.theta_h, dims.theta_d, dims.phi_d] != file.dims
            || store.transform() != file.transform
        {
            return Err(sbad(format!(
                "holds {} materials of {dims} ({}), the model expects {n} of {:?} ({})",
                store.n(),
                store.transform().name(),
                file.dims,
                file.transform.name()
            )));
        }
        let checksum = format!("{:016x}", store.checksum());
        if checksum != file.store.checksum {
            return Err(sbad(format!(
                "checksum {checksum} differs from {} recorded in {} (the store was changed)",
                file.store.checksum,
                path.display()
            )));
        }
        let gram = Mat::from_fn(n, n, |i, j| file.gram[i][j]);
        let latent = Mat::from_fn(n, q, |i, c| file.latent[i][c]);
        let llt = kernel
            .matrix(latent.as_ref())
            .llt(Side::Lower)
            .map_err(|_| CoreError::NotPositiveDefinite {
                context: format!("opening {}", path.display()),
            })?;
        let transform = file.transform.build(dims);
        Ok(Model {
            path,
            file,
            store,
            latent,
            llt,
            transform,
            gram,
            map_basis: MapBasis::default(),
        })
    }

    /// Write the model file atomically (the store must already be in place).
    pub fn write_file(path: &Path, file: &ModelFile) -> Result<()> {
        let json = serde_json::to_vec_pretty(file)
            .map_err(|e| CoreError::bad_file(path, e.to_string()))?;
        write_atomic(path, |w| std::io::Write::write_all(w, &json))
            .map_err(|e| CoreError::io(path, e))
    }

    /// The model file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The model file's content.
    pub fn file(&self) -> &ModelFile {
        &self.file
    }

    /// The mapped store.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// Material names in order.
    pub fn names(&self) -> &[String] {
        &self.file.names
    }

    /// Latent points, `N x q`.
    pub fn latent(&self) -> &Mat<f64> {
        &self.latent
    }

    /// Latent dimension `q`.
    pub fn q(&self) -> usize {
        self.latent.ncols()
    }

    /// Table dims.
    pub fn dims(&self) -> Dims {
        self.store.dims()
    }

    /// `K^-1 B` for a right-hand side with `N` rows.
    pub fn llt_solve(&self, b: &Mat<f64>) -> Mat<f64> {
        self.llt.solve(b)
    }

    /// The Gram matrix `Y = Z Z^T` of the stored (centred, transformed) data.
    pub fn gram(&self) -> &Mat<f64> {
        &self.gram
    }

    /// The blend weights `w(x) = K^-1 k(x)` at a latent point.
    pub fn weights_at(&self, x: &[f64]) -> Result<Vec<f64>> {
        if x.len() != self.q() || x.iter().any(|v| !v.is_finite()) {
            return Err(CoreError::BadQuery(format!(
                "latent point {x:?}: expected {} finite coordinates",
                self.q()
            )));
        }
        let k = self.file.kernel.vector(self.latent.as_ref(), x);
        let col = faer::Col::from_fn(k.len(), |i| k[i]);
        let w = self.llt.solve(&col);
        Ok((0..w.nrows()).map(|i| w[i]).collect())
    }
}

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
    /// The one pass building the store and the Gram matrix.
    pub store_time: Duration,
    /// The optimisation.
    pub optimise_time: Duration,
    /// Writing the model and checksumming the store.
    pub save_time: Duration,
    /// Largest heap in use during the fit, when the binary counts it
    /// ([`crate::heap::Counting`]); the inputs and the store are mapped
    /// files, not heap.
    pub peak_heap: Option<usize>,
}

/// Fit a directory of MERL files and write `model` and `model.store`.
pub fn fit_dir(
    dir: &Path,
    model: &Path,
    options: &FitOptions,
    progress: &dyn Progress,
) -> Result<FitReport> {
    let t0 = Instant::now();
    crate::heap::reset_peak();
    let data = Dataset::map_dir(dir)?;
    let scan_time = t0.elapsed();
    let t1 = Instant::now();
    let store_path = store_path_for(model);
    // The store is built under a temporary name and takes its place only
    // once the fit has succeeded: a failed re-fit leaves the old pair intact.
    let staging = brdf_merl::atomic::temp_path_for(&store_path);
    let result = fit_staged(
        &data,
        model,
        options,
        progress,
        &store_path,
        &staging,
        scan_time,
        t1,
    );
    if result.is_err() {
        let _ = std::fs::remove_file(&staging);
    }
    // Name the store, not its temporary name, in errors.
    result.map_err(|e| match e {
        CoreError::Io { path, source } if path == staging => CoreError::Io {
            path: store_path,
            source,
        },
        e => e,
    })
}

#[allow(clippy::too_many_arguments)]
fn fit_staged(
    data: &Dataset,
    model: &Path,
    options: &FitOptions,
    progress: &dyn Progress,
    store_path: &Path,
    staging: &Path,
    scan_time: Duration,
    t1: Instant,
) -> Result<FitReport> {
    let (store, y) = build_store(
        data,
        options.transform,
        options.precision,
        staging,
        progress,
    )?;
    let store_time = t1.elapsed();
    let t2 = Instant::now();
    let gram_rows: Vec<Vec<f64>> = (0..y.nrows())
        .map(|i| (0..y.ncols()).map(|j| y[(i, j)]).collect())
        .collect();
    let gram = GramData::new(y, store.rows())?;
    // The optimisation runs on one core: meanwhile the other drops the old
    // store's cached pages (the file stays as it is until the new model is
    // in place), so removing it at the end is quick.
    let fit = std::thread::scope(|scope| {
        scope.spawn(|| brdf_merl::atomic::evict_cached(store_path));
        options.params.fit(&gram, progress)
    })?;
    let optimise_time = t2.elapsed();
    let t3 = Instant::now();
    let store_name = store_path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let file = ModelFile::new(
        data.names.clone(),
        &fit,
        &store,
        gram_rows,
        &gram,
        store_name,
    );
    // Both files are complete on disk before either takes its place.
    let json =
        serde_json::to_vec_pretty(&file).map_err(|e| CoreError::bad_file(model, e.to_string()))?;
    let staged = stage(model, |w| std::io::Write::write_all(w, &json))
        .map_err(|e| CoreError::io(model, e))?;
    if model.is_dir() {
        return Err(CoreError::io(
            model,
            std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory"),
        ));
    }
    // The store goes in by an exchange, so the old one (if any) is still at
    // hand until the model, the commit point, is in place.
    let swapped = swap_in(staging, store_path).map_err(|e| CoreError::io(store_path, e))?;
    if let Err(e) = staged.commit(false) {
        if swapped == Swapped::Exchanged {
            // Undo: the old store back beside the old model. Best effort; the
            // commit's error is the one to report.
            let _ = swap_in(staging, store_path);
        }
        return Err(CoreError::io(model, e));
    }
    if swapped == Swapped::Exchanged {
        // The old store. Freeing its cached pages is most of the time a
        // re-fit spends saving (about 0.4 s a GB here); failing to remove it
        // loses nothing.
        let _ = std::fs::remove_file(staging);
    }
    let save_time = t3.elapsed();
    Ok(FitReport {
        names: data.names.clone(),
        ignored: data.ignored.clone(),
        fit,
        model_path: model.to_path_buf(),
        store_path: store_path.to_path_buf(),
        scan_time,
        store_time,
        optimise_time,
        save_time,
        peak_heap: crate::heap::peak(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gplvm::GplvmParams;
    use crate::progress::NoProgress;

    fn fitted(dir: &Path) -> PathBuf {
        let dims = Dims::new(6, 6, 12).unwrap();
        for m in brdf_merl::synth::database(6, 2) {
            m.brdf
                .table(dims)
                .write(dir.join(format!("{}.binary", m.name)))
                .unwrap();
        }
        let model = dir.join("m.atlas");
        let options = FitOptions {
            params: GplvmParams::new(2).check().unwrap(),
            transform: TransformKind::Log,
            precision: Precision::F32,
        };
        fit_dir(dir, &model, &options, &NoProgress).unwrap();
        model
    }

    #[test]
    fn model_round_trips_and_answers() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let m = Model::open(&path).unwrap();
        assert_eq!(m.names().len(), 6);
        // Re-serialising the loaded content gives the same file.
        let again = tmp.path().join("again.atlas");
        Model::write_file(&again, m.file()).unwrap();
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&again).unwrap()
        );
        // Weights reproduce K^-1 k(x): at a training point, K w = k(x_i).
        let xi: Vec<f64> = (0..2).map(|c| m.latent()[(3, c)]).collect();
        let w = m.weights_at(&xi).unwrap();
        let k = m.file().kernel.matrix(m.latent().as_ref());
        let kx = m.file().kernel.vector(m.latent().as_ref(), &xi);
        for r in 0..6 {
            let kw: f64 = (0..6).map(|c| k[(r, c)] * w[c]).sum();
            assert!((kw - kx[r]).abs() < 1e-9);
        }
        assert!(m.weights_at(&[f64::NAN, 0.0]).is_err());
        assert!(m.weights_at(&[0.0]).is_err());
    }

    #[test]
    fn a_failed_refit_leaves_the_old_model_intact() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let before = std::fs::read(store_path_for(&path)).unwrap();
        // q = 6 passes the parameter check but not the fit of 6 materials.
        let options = FitOptions {
            params: GplvmParams::new(6).check().unwrap(),
            transform: TransformKind::Raw,
            precision: Precision::F64,
        };
        assert!(fit_dir(tmp.path(), &path, &options, &NoProgress).is_err());
        assert_eq!(std::fs::read(store_path_for(&path)).unwrap(), before);
        Model::open(&path).unwrap();
        let leftovers: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp-"))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");
    }

    #[test]
    fn changed_missing_or_newer_models_are_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let text = std::fs::read_to_string(&path).unwrap();
        let bad = tmp.path().join("bad.atlas");
        let check = |content: &str, want: &str| {
            std::fs::write(&bad, content).unwrap();
            let e = Model::open(&bad).unwrap_err().to_string();
            assert!(e.contains(want), "{want}: {e}");
            assert!(e.contains("bad.atlas") || e.contains(".store"), "{e}");
        };
        check(
            &text.replace("\"version\": 1", "\"version\": 7"),
            "written by a newer brdf-atlas",
        );
        check(&text[..text.len() / 2], "invalid JSON");
        check("{}", "not a brdf-atlas model");
        check(&text.replace("m.atlas.store", "gone.store"), "gone.store");
        // A store changed in one byte.
        let store = store_path_for(&path);
        let mut bytes = std::fs::read(&store).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(&store, &bytes).unwrap();
        let e = Model::open(&path).unwrap_err().to_string();
        assert!(e.contains("checksum") && e.contains("m.atlas.store"), "{e}");
    }
}
