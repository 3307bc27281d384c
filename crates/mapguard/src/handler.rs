//! The process-wide SIGBUS handler: installed once, before the first guarded
//! map, in front of whatever handler the process had.
//!
//! A SIGBUS whose address lies in a registered range (a file this library
//! mapped has been truncated under the map) is answered by mapping
//! anonymous zero pages over the whole range and marking it poisoned; the
//! handler returns, the interrupted read goes on and reads zeros, and the
//! operation that read them reports the file as changed instead of the
//! result. Every other SIGBUS goes to the handler that was there before
//! (called as it asked to be, with or without `SA_SIGINFO`), or gets the
//! default action (the process dies as it would have without us).
//!
//! `mmap` is not on POSIX's list of async-signal-safe functions, but on
//! Linux it is one system call with no user-space state (no lock, no
//! allocation), which is what the list guards against; the registry is
//! atomics only. The handler never unwinds or jumps: Rust frames are only
//! ever returned through.

use std::ffi::{c_int, c_void};
use std::sync::OnceLock;

use crate::registry;

/// The action SIGBUS had before ours (what faults outside our ranges get).
static PREVIOUS: OnceLock<libc::sigaction> = OnceLock::new();

/// Install the handler, once for the process. `false` when the system
/// refused (then faults are not caught, and maps still work).
pub(crate) fn install() -> bool {
    static INSTALLED: OnceLock<bool> = OnceLock::new();
    *INSTALLED.get_or_init(|| {
        // SAFETY: all-zero bytes are a valid sigaction (plain data).
        let mut old: libc::sigaction = unsafe { std::mem::zeroed() };
        // SAFETY: with a NULL new action, sigaction only writes the current
        // one into `old`, which is valid for writing.
        if unsafe { libc::sigaction(libc::SIGBUS, std::ptr::null(), &mut old) } != 0 {
            return false;
        }
        // Kept before ours goes in, so the handler always finds it.
        let old = *PREVIOUS.get_or_init(|| old);
        // SAFETY: a zeroed sigaction is a valid value; fields set below.
        let mut ours: libc::sigaction = unsafe { std::mem::zeroed() };
        ours.sa_sigaction = on_sigbus as *const () as usize;
        // SA_NODEFER: a previous handler that leaves by longjmp (not
        // siglongjmp) must not leave SIGBUS blocked; SA_ONSTACK: run on
        // the thread's alternate stack when it has one.
        ours.sa_flags = libc::SA_SIGINFO | libc::SA_ONSTACK | libc::SA_NODEFER;
        ours.sa_mask = old.sa_mask;
        // SAFETY: installs a valid action; `on_sigbus` is async-signal-safe
        // (see the module docs).
        unsafe { libc::sigaction(libc::SIGBUS, &ours, std::ptr::null_mut()) == 0 }
    })
}

extern "C" fn on_sigbus(sig: c_int, info: *mut libc::siginfo_t, context: *mut c_void) {
    // SAFETY: the kernel passes a valid siginfo_t to an SA_SIGINFO handler.
    let (code, addr) = unsafe { ((*info).si_code, (*info).si_addr() as usize) };
    // si_code > 0: raised by the kernel for a memory access (not kill()).
    if code > 0 && replace_with_zeros(addr) {
        return;
    }
    // SAFETY: passes on the arguments the kernel gave us.
    unsafe { chain(sig, info, context) };
}

/// Map zero pages over the registered range holding `addr`, if there is one.
fn replace_with_zeros(addr: usize) -> bool {
    let Some((start, len)) = registry::poison_range_of(addr) else {
        return false;
    };
    // SAFETY: `start .. start + len` is one of our read-only maps (page
    // aligned, as mmap returned it; the kernel rounds `len` up to whole
    // pages, as munmap of the same map does), still mapped because a read
    // of it just faulted. MAP_FIXED replaces its pages in one step.
    let p = unsafe {
        libc::mmap(
            start as *mut c_void,
            len,
            libc::PROT_READ,
            libc::MAP_FIXED | libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
            -1,
            0,
        )
    };
    p != libc::MAP_FAILED
}

/// Hand a SIGBUS that is not ours to the previous action.
///
/// # Safety
/// The arguments are those the kernel passed to [`on_sigbus`].
unsafe fn chain(sig: c_int, info: *mut libc::siginfo_t, context: *mut c_void) {
    let Some(previous) = PREVIOUS.get() else {
        // SAFETY: as in `die`.
        unsafe { die(sig) };
        return;
    };
    match previous.sa_sigaction {
        libc::SIG_DFL => {
            // SAFETY: as in `die`.
            unsafe { die(sig) }
        }
        libc::SIG_IGN => {
            // A fault cannot be ignored (returning would fault again
            // forever): the kernel kills the process then, and so do we.
            // SAFETY: a non-NULL `info` is the kernel's valid siginfo_t.
            if info.is_null() || unsafe { (*info).si_code } > 0 {
                // SAFETY: as in `die`.
                unsafe { die(sig) }
            }
        }
        f if previous.sa_flags & libc::SA_SIGINFO != 0 => {
            // SAFETY: the previous action asked for this signature.
            let f: extern "C" fn(c_int, *mut libc::siginfo_t, *mut c_void) =
                unsafe { std::mem::transmute(f) };
            f(sig, info, context);
        }
        f => {
            // SAFETY: the previous action asked for this signature.
            let f: extern "C" fn(c_int) = unsafe { std::mem::transmute(f) };
            f(sig);
        }
    }
}

/// The default action of `sig`, now: restore it and raise the signal
/// (SIGBUS is not blocked in our handler, so it is delivered at once).
///
/// # Safety
/// Called from the signal handler; sigaction and raise are async-signal-safe.
unsafe fn die(sig: c_int) {
    // SAFETY: a zeroed sigaction is SIG_DFL with no flags.
    unsafe {
        let mut dfl: libc::sigaction = std::mem::zeroed();
        dfl.sa_sigaction = libc::SIG_DFL;
        libc::sigaction(sig, &dfl, std::ptr::null_mut());
        libc::raise(sig);
    }
}
