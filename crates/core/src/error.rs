//! The one error type of the core crate.

use std::path::PathBuf;

/// Everything that can go wrong building a store, fitting or loading a model.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CoreError {
    /// A MERL input was unreadable or invalid.
    #[error(transparent)]
    Merl(#[from] brdf_merl::MerlError),
    /// The operating system refused a file operation.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A data directory held no usable material.
    #[error("{}: no .binary MERL files found (expected a directory of MERL tables)", path.display())]
    EmptyDataset {
        /// The directory.
        path: PathBuf,
    },
    /// Materials of one dataset disagree in their table dims.
    #[error("{}: dims {found}, but {first} has {expected}; every material must share one grid", path.display())]
    DimsDiffer {
        /// The odd file.
        path: PathBuf,
        /// Its dims.
        found: String,
        /// The first file of the set.
        first: String,
        /// The first file's dims.
        expected: String,
    },
    /// A store or model file is malformed.
    #[error("{}: {why}", path.display())]
    BadFile {
        /// The file.
        path: PathBuf,
        /// What was expected and what was found.
        why: String,
    },
    /// A mapped file (a model's store) was truncated or rewritten in place
    /// by another program while open: nothing read from it is returned.
    #[error("{}: changed on disk while open (truncated or rewritten in place by another program); reopen the model to use the file as it is now", path.display())]
    FileChanged {
        /// The file.
        path: PathBuf,
    },
    /// Writing an output file, or putting it in place, failed.
    #[error("{}: {source}", path.display())]
    Write {
        /// The output file.
        path: PathBuf,
        /// What the OS (or the encoder) said.
        source: std::io::Error,
    },
    /// Parameters that cannot be fitted.
    #[error("invalid parameters: {0}")]
    InvalidParams(#[from] ParamError),
    /// A kernel matrix was not positive definite where it had to be.
    #[error(
        "kernel matrix not positive definite ({context}{}); the noise term may be too small for these latent points",
        pivot.map(|i| format!(", pivot {i}")).unwrap_or_default()
    )]
    NotPositiveDefinite {
        /// Where the factorisation failed.
        context: String,
        /// The first pivot of the Cholesky factorisation that was not
        /// positive, when the factorisation says.
        pivot: Option<usize>,
    },
    /// A symmetric eigen-decomposition did not converge.
    #[error("eigen-decomposition of {0} failed")]
    Eigen(&'static str),
    /// A query outside what the model can answer.
    #[error("{0}")]
    BadQuery(String),
    /// The caller cancelled the work ([`crate::Progress::cancelled`]).
    #[error("cancelled by the caller")]
    Cancelled,
}

impl CoreError {
    /// [`CoreError::Io`] of `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        CoreError::Io {
            path: path.into(),
            source,
        }
    }

    /// [`CoreError::Write`] of `path`.
    pub fn write(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        CoreError::Write {
            path: path.into(),
            source,
        }
    }

    /// [`CoreError::BadFile`] of `path`, saying `why`.
    pub fn bad_file(path: impl Into<PathBuf>, why: impl Into<String>) -> Self {
        CoreError::BadFile {
            path: path.into(),
            why: why.into(),
        }
    }
}

/// Result with [`CoreError`].
pub type Result<T, E = CoreError> = std::result::Result<T, E>;

/// Why parameters were refused, one variant a rule (as [`GplvmParams::check`],
/// [`GramData::new`] and the leave-one-out predictors check them).
///
/// [`GplvmParams::check`]: crate::GplvmParams::check
/// [`GramData::new`]: crate::GramData::new
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ParamError {
    /// The latent dimension is 0 or above [`crate::limits::MAX_Q`].
    #[error("q = {q} must be between 1 and {max}")]
    LatentDim {
        /// The dimension asked for.
        q: usize,
        /// The largest allowed.
        max: usize,
    },
    /// The latent dimension is not below the number of materials.
    #[error("latent dimension q = {q} needs 1 <= q < N = {n} (the number of materials)")]
    LatentDimForData {
        /// The dimension asked for.
        q: usize,
        /// The number of materials.
        n: usize,
    },
    /// The kernel's length scale is out of range.
    #[error("length scale {value:?} must lie in [{min:e}, {max:e}]")]
    LengthScale {
        /// The value given.
        value: f64,
        /// Smallest allowed.
        min: f64,
        /// Largest allowed.
        max: f64,
    },
    /// The kernel's noise is out of range.
    #[error("noise {value:?} must lie in [{min:e}, {max:e}] (it keeps K positive definite)")]
    Noise {
        /// The value given.
        value: f64,
        /// Smallest allowed.
        min: f64,
        /// Largest allowed.
        max: f64,
    },
    /// Hooke-Jeeves' steps are not ordered.
    #[error("steps must satisfy 0 < min step ({min_step}) <= initial step ({initial_step}) <= 2")]
    Steps {
        /// The smallest step.
        min_step: f64,
        /// The first step.
        initial_step: f64,
    },
    /// Learning the kernel was asked of an optimiser that cannot.
    #[error(
        "learning the kernel needs the L-BFGS optimiser (Hooke-Jeeves moves one point at a time)"
    )]
    LearnKernelNeedsLbfgs,
    /// Hooke-Jeeves' step reduction is not in (0, 1).
    #[error("step reduction {0} must lie in (0, 1)")]
    Reduction(f64),
    /// A Gram matrix that is not square, or of dimension 0.
    #[error("Gram matrix {rows}x{cols} of dimension {d}")]
    GramShape {
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
        /// The data dimension `d`.
        d: usize,
    },
    /// A Gram matrix with NaN or infinite entries.
    #[error("Gram matrix has non-finite entries")]
    GramNotFinite,
    /// Too few materials for a method.
    #[error("{method} needs at least {needs} materials, got {got}")]
    TooFewMaterials {
        /// The method.
        method: &'static str,
        /// How many it needs.
        needs: usize,
        /// How many there are.
        got: usize,
    },
    /// A leave-one-out predictor of the wrong shape.
    #[error("predictor is {rows}x{cols}, the store has {n} materials")]
    PredictorShape {
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
        /// Materials of the store.
        n: usize,
    },
}
