//! The one error type of the analytic crate.

/// What can go wrong fitting an analytic model to a table, or writing it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AnalyticError {
    /// Too few bins of the table are usable (measured in every channel,
    /// finite and non-negative, both directions above the horizon).
    #[error(
        "{what}: {usable} usable bin(s) of {dims} sampled, the fit needs at least {needed} (measured, finite, >= 0, both directions above the horizon)"
    )]
    TooFewBins {
        /// The material, as the caller names it.
        what: String,
        /// The table's dims.
        dims: brdf_merl::Dims,
        /// Usable bins found in the subsample.
        usable: usize,
        /// Bins the fit needs.
        needed: usize,
    },
    /// A file name (the stem of an export's files) with a directory in it,
    /// a leading dot, or nothing.
    #[error("{stem:?}: expected a file name without a directory or a leading dot")]
    Stem {
        /// The name given.
        stem: String,
    },
    /// The directory to write into is missing or not a directory.
    #[error("{}: is not a directory (it must exist)", path.display())]
    NotADirectory {
        /// The path given.
        path: std::path::PathBuf,
    },
    /// Writing a file, or putting it in place, failed.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: std::path::PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
}

/// Results of this crate.
pub type Result<T> = std::result::Result<T, AnalyticError>;
