//! Interrupts (Ctrl-C, `kill`): the output stays as it was and nothing is
//! left behind.
//!
//! [`install`] blocks SIGINT, SIGTERM and SIGHUP in every thread (it runs
//! first in `main`, before any other thread exists, and threads inherit the
//! mask) and starts one thread that waits for them with `sigwait`. No
//! signal handler runs, so nothing has to be async-signal-safe: the thread
//! clears the progress bars, removes the temporaries through
//! [`brdf_atomic::remove_temporaries`] (which first waits for an output
//! being put in place), prints one line and exits with 128 + the signal.
//! A SIGKILL cannot be caught, and needs no cleaning up: files are written
//! without a name until they take their place; what must have one (a
//! report's directory) the next run writing beside it removes
//! ([`brdf_atomic::sweep`]).
//!
//! No signal-handling crate: `sigwait` on a thread of its own needs none of
//! the handler and self-pipe machinery such crates install, and leaves the
//! process's handlers as they were.

use crate::progress;

/// The signals that end a run cleanly.
#[cfg(unix)]
const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

/// Route SIGINT, SIGTERM and SIGHUP to a watcher thread. Call before any
/// other thread starts. Best effort: where it cannot be set up, the default
/// actions (end the process) stay.
pub fn install() {
    #[cfg(unix)]
    {
        // SAFETY: a zeroed sigset_t is initialised by sigemptyset before use;
        // the calls only read and write this local set.
        let mut set: libc::sigset_t = unsafe { std::mem::zeroed() };
        unsafe {
            libc::sigemptyset(&mut set);
            for s in SIGNALS {
                libc::sigaddset(&mut set, s);
            }
        }
        // SAFETY: a valid, initialised set; the old mask is not wanted.
        if unsafe { libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) } != 0 {
            return;
        }
        let spawned = std::thread::Builder::new()
            .name("interrupt".into())
            .spawn(move || {
                let mut sig: libc::c_int = 0;
                // SAFETY: a valid set and a valid place for the signal number.
                while unsafe { libc::sigwait(&set, &mut sig) } != 0 {}
                stop(sig);
            });
        if spawned.is_err() {
            // No watcher: give the signals back their default actions.
            // SAFETY: as above.
            unsafe { libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut()) };
        }
    }
}

/// What the watcher does once a signal came: never returns.
#[cfg(unix)]
fn stop(sig: libc::c_int) -> ! {
    progress::clear_all();
    brdf_atomic::remove_temporaries();
    if brdf_atomic::committed() {
        eprintln!("interrupted; the output written before the interrupt is complete");
    } else {
        eprintln!("interrupted; nothing was changed");
    }
    std::process::exit(128 + sig);
}
