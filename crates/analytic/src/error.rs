//! The one error type of the analytic crate.

/// What can go wrong fitting an analytic model to a table.
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
}

/// Results of this crate.
pub type Result<T> = std::result::Result<T, AnalyticError>;
