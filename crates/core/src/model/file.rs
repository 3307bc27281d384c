//! The model file: a fitted latent space beside its store.
//!
//! A model is two files: `NAME` (JSON, small, self-describing, versioned)
//! and `NAME.store` (the data, see [`crate::data::store`]). The JSON names the
//! store relative to itself and records its size and checksum, so a moved
//! pair still opens and a changed store is refused. Both are written
//! atomically.

use std::path::{Path, PathBuf};

use brdf_atomic::write_atomic;
use brdf_merl::Dims;
use faer::MatRef;
use serde::{Deserialize, Serialize};

use crate::data::store::EnergyBound;
use crate::data::{Dataset, Precision, Store, StoreIdentity, TransformKind};
use crate::error::{CoreError, Result};
use crate::gplvm::kernel::{Kernel, rows_of};
use crate::gplvm::{DriftStats, Fit, GramData, OptimizerKind};
use crate::limits::{LATENT_LIMIT, MAX_MATERIALS, MAX_Q};
use crate::model::judged::{Fidelity, Judged, MARKER_RADIUS};

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
    /// Its identity at the fit ([`Store::identity`]): while it is the same,
    /// opening the model does not checksum the store again. Absent in
    /// models written before it was recorded, or where the boot cannot be
    /// told.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identity: Option<StoreIdentity>,
}

/// What the optimiser did, for the record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitRecord {
    /// Optimiser used.
    pub optimizer: OptimizerKind,
    /// Whether the kernel was learned with the latent points (absent in
    /// models written before it could be: false).
    #[serde(default)]
    pub learned_kernel: bool,
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
    /// The input files the store was built from, as the fit saw them: a
    /// re-fit of the same files into the same model, with the same
    /// transform and precision, uses the store again instead of building
    /// it anew. Absent in models written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inputs: Option<Vec<InputIdentity>>,
    /// Each material at its own point judged against itself, as the fit
    /// measured it ([`crate::fidelity`]). Absent in models written before
    /// it was measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fidelity: Option<Fidelity>,
    /// What bounds the default rule's energy, as the fit computed it from
    /// the store (`data::store::EnergyBound`), so that opening the model
    /// does not read the store for it. Absent in models written before:
    /// then it is computed on first use.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) energy: Option<EnergyBound>,
}

impl ModelFile {
    /// The material whose marker `x` is (the nearest within
    /// [`MARKER_RADIUS`]) and how its own point gives it back, as the fit
    /// recorded it (models written before it was recorded: `None`).
    pub fn marker_at(&self, x: &[f64]) -> Option<(usize, &Judged)> {
        let own = &self.fidelity.as_ref()?.own;
        let d2 = |p: &[f64]| p.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum::<f64>();
        let (i, d) = self
            .latent
            .iter()
            .map(|p| d2(p))
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        if d > MARKER_RADIUS * MARKER_RADIUS {
            return None;
        }
        own.get(i).map(|j| (i, j))
    }
}

/// An input file of a fit as the fit saw it: its name in the data
/// directory, which file it was, its size and last modification.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputIdentity {
    /// File name in the data directory.
    pub name: String,
    /// Device of the file system.
    pub device: u64,
    /// Inode number.
    pub inode: u64,
    /// Size in bytes.
    pub bytes: u64,
    /// Last modification: seconds and nanoseconds since the epoch.
    pub modified: [i64; 2],
}

impl InputIdentity {
    /// The identities of a dataset's files, in its order.
    pub fn of(data: &Dataset) -> Vec<InputIdentity> {
        data.files
            .iter()
            .map(|f| {
                let s = f.stamp();
                InputIdentity {
                    name: f
                        .path()
                        .file_name()
                        .map(|n| n.to_string_lossy().into_owned())
                        .unwrap_or_default(),
                    device: s.dev,
                    inode: s.ino,
                    bytes: s.size,
                    modified: [s.mtime.0, s.mtime.1],
                }
            })
            .collect()
    }
}

impl StoreRef {
    /// The reference to `store`, named `path` beside its model file:
    /// size, checksum (a read of the whole store) and identity.
    pub fn of(store: &Store, path: String) -> StoreRef {
        StoreRef {
            path,
            bytes: store.len_bytes(),
            checksum: format!("{:016x}", store.checksum()),
            identity: store.identity(),
        }
    }
}

impl ModelFile {
    /// The model file of `fit` on `store` (materials `names`, in store
    /// order; `y` the Gram matrix before normalisation, `gram` the fitted
    /// data; `store_ref` the store's reference, [`StoreRef::of`]).
    pub fn new(
        names: Vec<String>,
        fit: &Fit,
        store: &Store,
        y: MatRef<'_, f64>,
        gram: &GramData,
        store_ref: StoreRef,
    ) -> ModelFile {
        let dims = store.dims();
        let o = &fit.outcome;
        ModelFile {
            format: FORMAT.into(),
            version: VERSION,
            names,
            latent: rows_of(o.latent.as_ref()),
            kernel: fit.kernel,
            transform: store.transform(),
            precision: store.precision(),
            dims: [dims.theta_h, dims.theta_d, dims.phi_d],
            d: store.rows(),
            signal_variance: gram.scale2(),
            fit: FitRecord {
                optimizer: fit.optimizer,
                learned_kernel: fit.learned_kernel,
                initial_cost: o.initial_cost,
                cost: o.cost,
                iterations: o.iterations,
                evaluations: o.evaluations,
                pattern_moves: o.pattern_moves,
                drift: o.drift,
                eigenvalues: fit.eigenvalues.clone(),
            },
            gram: rows_of(y),
            store: store_ref,
            inputs: None,
            fidelity: None,
            energy: None,
        }
    }
}

/// The store file that goes with a model path: `NAME.store`.
pub fn store_path_for(model: &Path) -> PathBuf {
    let mut s = model.as_os_str().to_os_string();
    s.push(".store");
    PathBuf::from(s)
}

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

    /// The JSON text of the model file (what [`ModelFile::from_json`] reads
    /// back); `path` names the file in errors.
    pub fn to_json(&self, path: &Path) -> Result<Vec<u8>> {
        serde_json::to_vec_pretty(self).map_err(|e| CoreError::write(path, e.into()))
    }

    /// Write the model file atomically (the store must already be in place).
    pub fn write(&self, path: &Path) -> Result<()> {
        let json = self.to_json(path)?;
        write_atomic(path, |w| std::io::Write::write_all(w, &json))
            .map_err(|e| CoreError::write(path, e))
    }
}
