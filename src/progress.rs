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
