//! Progress bars on stderr. indicatif draws nothing when stderr is not a
//! terminal, so scripts and tests see only the report and the errors.

use indicatif::{ProgressBar, ProgressStyle};

/// A bar of `len` steps with a message in front.
pub fn bar(len: usize, message: &'static str) -> ProgressBar {
    let style = ProgressStyle::with_template(
        "{msg:>12} [{bar:32}] {pos}/{len} {elapsed_precise} (eta {eta})",
    )
    .expect("valid template")
    .progress_chars("=> ");
    ProgressBar::new(len as u64)
        .with_style(style)
        .with_message(message)
}

/// A spinner for a step of unknown length.
pub fn spinner(message: impl Into<String>) -> ProgressBar {
    let style =
        ProgressStyle::with_template("{spinner} {msg} {elapsed_precise}").expect("valid template");
    let pb = ProgressBar::new_spinner()
        .with_style(style)
        .with_message(message.into());
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    pb
}

/// The core library's long work ([`brdf_atlas_core::Progress`]: building the
/// store, optimising, drawing a map) shown as one bar per phase.
///
/// The library calls `advance` from worker threads; the current bar sits
/// behind a mutex that `start` swaps, and indicatif itself is thread-safe.
/// Before the first phase starts a spinner with `waiting` shows that
/// something is happening (a fit first opens every input file).
pub struct Bars {
    current: std::sync::Mutex<ProgressBar>,
}

impl Bars {
    /// Bars for one command; `waiting` is shown until the first phase starts.
    pub fn new(waiting: impl Into<String>) -> Bars {
        Bars {
            current: std::sync::Mutex::new(spinner(waiting)),
        }
    }

    fn with_bar(&self, f: impl FnOnce(&mut ProgressBar)) {
        // A panic elsewhere while the lock was held poisons it; progress is
        // cosmetic, so carry on with the bar as it is.
        let mut guard = self
            .current
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        f(&mut guard);
    }
}

/// A bar for a phase counted in the library's own units (store rows run to
/// millions), so it shows a percentage rather than counts.
fn phase_bar(total: u64, message: &'static str) -> ProgressBar {
    let style = ProgressStyle::with_template(
        "{msg:>12} [{bar:32}] {percent:>3}% {elapsed_precise} (eta {eta})",
    )
    .expect("valid template")
    .progress_chars("=> ");
    ProgressBar::new(total)
        .with_style(style)
        .with_message(message)
}

/// What the user reads for each phase label of the core library.
fn phase_message(label: &str) -> &'static str {
    match label {
        "store" => "store+Gram",
        "gram" => "Gram",
        "optimise" => "optimising",
        "map" => "map rows",
        "loo" => "leave-one-out",
        _ => "working",
    }
}

impl brdf_atlas_core::Progress for Bars {
    fn start(&self, label: &str, total: u64) {
        self.with_bar(|pb| {
            pb.finish_and_clear();
            *pb = phase_bar(total, phase_message(label));
        });
    }

    fn advance(&self, delta: u64) {
        self.with_bar(|pb| pb.inc(delta));
    }

    fn finish(&self) {
        self.with_bar(|pb| pb.finish_and_clear());
    }
}

impl Drop for Bars {
    fn drop(&mut self) {
        self.with_bar(|pb| pb.finish_and_clear());
    }
}
