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
    /// Parameters that cannot be fitted.
    #[error("invalid parameters: {0}")]
    InvalidParams(String),
    /// A kernel matrix was not positive definite where it had to be.
    #[error(
        "kernel matrix not positive definite ({context}); the noise term may be too small for these latent points"
    )]
    NotPositiveDefinite {
        /// Where the factorisation failed.
        context: String,
    },
    /// A query outside what the model can answer.
    #[error("{0}")]
    BadQuery(String),
}

impl CoreError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        CoreError::Io {
            path: path.into(),
            source,
        }
    }

    pub(crate) fn bad_file(path: impl Into<PathBuf>, why: impl Into<String>) -> Self {
        CoreError::BadFile {
            path: path.into(),
            why: why.into(),
        }
    }
}

/// Result with [`CoreError`].
pub type Result<T, E = CoreError> = std::result::Result<T, E>;
