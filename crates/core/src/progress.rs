//! Progress of long work (the store pass, the fit, maps), reported to
//! whoever shows it: a terminal bar, a GUI, or nothing.

/// Reports progress of long work: `(done, total)` in the work's own units.
/// Called from worker threads.
pub trait Progress: Sync {
    /// Work `total` has begun under this `label`.
    fn start(&self, _label: &str, _total: u64) {}
    /// `delta` more units are done.
    fn advance(&self, _delta: u64) {}
    /// The work is finished.
    fn finish(&self) {}
    /// Whether the caller no longer wants the result. Work that asks (the
    /// albedo map) then stops soon and returns [`CoreError::Cancelled`]
    /// with nothing written and nothing cached.
    ///
    /// [`CoreError::Cancelled`]: crate::CoreError::Cancelled
    fn cancelled(&self) -> bool {
        false
    }
}

/// A [`Progress`] that shows nothing.
pub struct NoProgress;

impl Progress for NoProgress {}
