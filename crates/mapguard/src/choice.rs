//! Whether the process gets the SIGBUS handler: decided once, by the first
//! of a call to [`set_sigbus_guard`] and the first [`GuardedMap::open`]
//! (which reads [`NO_HANDLER_ENV`]).
//!
//! [`GuardedMap::open`]: crate::GuardedMap::open

use std::sync::OnceLock;

/// The environment variable that opts a process out of the SIGBUS handler:
/// set to `1` when the first map is opened (and no call to
/// [`set_sigbus_guard`] came first), no handler is installed.
pub const NO_HANDLER_ENV: &str = "BRDF_ATLAS_NO_SIGBUS_HANDLER";

static GUARDED: OnceLock<bool> = OnceLock::new();

/// Choose whether this process gets the SIGBUS handler, before the first
/// map is opened. `true` (the default) installs it with the first map;
/// `false` leaves SIGBUS's disposition as the process has it, so a file
/// truncated under a map is no longer turned into zeros and a change
/// report: the read past its new end raises SIGBUS, which the process's
/// own handler gets, or which kills the process (the default action).
/// A same-size rewrite, or a truncation seen before the read, is still
/// reported by [`GuardedMap::changed`](crate::GuardedMap::changed).
///
/// The choice is made once for the process, by the first of this call and
/// the first open: returns `true` if the process's choice is now
/// `enabled`, `false` if it had already been made the other way (a map was
/// opened first, or an earlier call chose otherwise). Calling it again
/// changes nothing; an installed handler stays.
pub fn set_sigbus_guard(enabled: bool) -> bool {
    *GUARDED.get_or_init(|| enabled) == enabled
}

/// Whether the process has chosen the handler, choosing now if it has not:
/// yes, unless [`set_sigbus_guard`] said no or [`NO_HANDLER_ENV`] is `1`.
pub fn sigbus_guarded() -> bool {
    *GUARDED.get_or_init(|| std::env::var_os(NO_HANDLER_ENV).is_none_or(|v| v != "1"))
}
