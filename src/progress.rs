//! Progress bars on stderr. indicatif draws nothing when stderr is not a
//! terminal, so scripts and tests see only the report and the errors.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::Duration;

use indicatif::{
    HumanDuration, ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle, WeakProgressBar,
};

/// Every bar made here, so an interrupt can clear them ([`clear_all`]).
static LIVE: Mutex<Vec<WeakProgressBar>> = Mutex::new(Vec::new());

fn track(pb: ProgressBar) -> ProgressBar {
    let mut live = LIVE.lock().unwrap_or_else(PoisonError::into_inner);
    live.retain(|w| w.upgrade().is_some());
    live.push(pb.downgrade());
    pb
}

/// Clear every bar still on screen and draw none again: for an interrupt,
/// before its one line.
pub fn clear_all() {
    let live = LIVE.lock().unwrap_or_else(PoisonError::into_inner);
    for pb in live.iter().filter_map(WeakProgressBar::upgrade) {
        pb.finish_and_clear();
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
}

/// The estimate is shown once this much time has passed...
const ETA_AFTER: Duration = Duration::from_secs(1);
/// ...and this fraction of the work is done: before, it extrapolates from
/// the start-up of a pass (opening files, first pages) and can be minutes
/// off.
const ETA_FRACTION: f32 = 0.05;

/// The " (eta ...)" after a bar, empty until the estimate means something.
fn eta_text(elapsed: Duration, fraction: f32, eta: Duration) -> String {
    if elapsed < ETA_AFTER || !(ETA_FRACTION..1.0).contains(&fraction) {
        return String::new();
    }
    format!(" (eta {})", HumanDuration(eta))
}

/// A bar style from `template`, where `{eta_known}` stands for [`eta_text`].
fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template)
        .expect("valid template")
        .with_key(
            "eta_known",
            |state: &ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = w.write_str(&eta_text(state.elapsed(), state.fraction(), state.eta()));
            },
        )
        .progress_chars("=> ")
}

/// A bar of `len` steps with a message in front.
pub fn bar(len: usize, message: &'static str) -> ProgressBar {
    let style = style("{msg:>12} [{bar:32}] {pos}/{len} {elapsed_precise}{eta_known}");
    track(
        ProgressBar::new(len as u64)
            .with_style(style)
            .with_message(message),
    )
}

/// A spinner for a step of unknown length.
pub fn spinner(message: impl Into<String>) -> ProgressBar {
    let style =
        ProgressStyle::with_template("{spinner} {msg} {elapsed_precise}").expect("valid template");
    let pb = track(
        ProgressBar::new_spinner()
            .with_style(style)
            .with_message(message.into()),
    );
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
    stop: StopIn,
}

/// For the tests of files changed during a run: with
/// `BRDF_ATLAS_TEST_STOP_IN=PHASE` in its environment (a label of the core
/// library: `store`, `optimise`, ...) the process stops itself with SIGSTOP
/// at the first step of that phase, once, so that a test can change an
/// input at a known point of the work and then continue it with SIGCONT.
struct StopIn {
    phase: Option<String>,
    armed: AtomicBool,
    done: AtomicBool,
}

impl StopIn {
    fn from_env() -> StopIn {
        StopIn {
            phase: std::env::var("BRDF_ATLAS_TEST_STOP_IN").ok(),
            armed: AtomicBool::new(false),
            done: AtomicBool::new(false),
        }
    }

    fn start(&self, label: &str) {
        let armed = self.phase.as_deref() == Some(label);
        self.armed.store(armed, Ordering::SeqCst);
    }

    fn step(&self) {
        if self.armed.load(Ordering::SeqCst) && !self.done.swap(true, Ordering::SeqCst) {
            // SAFETY: raise has no memory-safety preconditions.
            unsafe { libc::raise(libc::SIGSTOP) };
        }
    }
}

impl Bars {
    /// Bars for one command; `waiting` is shown until the first phase starts.
    pub fn new(waiting: impl Into<String>) -> Bars {
        Bars {
            current: std::sync::Mutex::new(spinner(waiting)),
            stop: StopIn::from_env(),
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
    let style = style("{msg:>12} [{bar:32}] {percent:>3}% {elapsed_precise}{eta_known}");
    track(
        ProgressBar::new(total)
            .with_style(style)
            .with_message(message),
    )
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
        self.stop.start(label);
        self.with_bar(|pb| {
            pb.finish_and_clear();
            *pb = phase_bar(total, phase_message(label));
        });
    }

    fn advance(&self, delta: u64) {
        self.stop.step();
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eta_is_hidden_until_it_means_something() {
        let s = Duration::from_secs;
        // The first ticks of a 6 s pass extrapolate to minutes: not shown.
        assert_eq!(eta_text(Duration::from_millis(50), 0.001, s(180)), "");
        // Early work done fast, but too soon.
        assert_eq!(eta_text(Duration::from_millis(300), 0.2, s(1)), "");
        // Long enough, but too little work to extrapolate from.
        assert_eq!(eta_text(s(2), 0.01, s(198)), "");
        assert_eq!(eta_text(s(2), 0.4, s(3)), " (eta 3 seconds)");
        assert_eq!(eta_text(s(6), 1.0, s(0)), "");
    }
}
