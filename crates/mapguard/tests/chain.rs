//! The handler is installed in front of the process's own: a SIGBUS outside
//! the guarded maps still reaches the handler that was there before.
//! (Its own test binary: it installs a process-wide handler first.)

use std::ffi::{c_int, c_void};
use std::fs::OpenOptions;
use std::sync::atomic::{AtomicUsize, Ordering};

use brdf_mapguard::{GuardedMap, Watch};

static HOST_CALLS: AtomicUsize = AtomicUsize::new(0);

/// The host's handler: counts the fault and maps a zero page over it, so
/// the read that faulted can go on.
extern "C" fn host(_: c_int, info: *mut libc::siginfo_t, _: *mut c_void) {
    HOST_CALLS.fetch_add(1, Ordering::SeqCst);
    // SAFETY: a valid siginfo_t from the kernel; one page replaced at the
    // faulting address, which lies in the test's own map.
    unsafe {
        let size = libc::sysconf(libc::_SC_PAGESIZE) as usize;
        let page = (*info).si_addr() as usize & !(size - 1);
        libc::mmap(
            page as *mut c_void,
            size,
            libc::PROT_READ,
            libc::MAP_FIXED | libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
            -1,
            0,
        );
    }
}

#[test]
fn faults_outside_the_guarded_maps_reach_the_previous_handler() {
    // SAFETY: installs a valid SA_SIGINFO handler.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = host as *const () as usize;
        action.sa_flags = libc::SA_SIGINFO;
        assert_eq!(
            libc::sigaction(libc::SIGBUS, &action, std::ptr::null_mut()),
            0
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let (ours, theirs) = (dir.path().join("ours"), dir.path().join("theirs"));
    for p in [&ours, &theirs] {
        std::fs::write(p, vec![1u8; 1 << 16]).unwrap();
    }
    let guarded = GuardedMap::open(&ours, Watch::Descriptor).unwrap();
    let file = std::fs::File::open(&theirs).unwrap();
    // SAFETY: a read-only map the test truncates on purpose; the host
    // handler above answers its fault.
    let plain = unsafe { memmap2::Mmap::map(&file) }.unwrap();
    for p in [&ours, &theirs] {
        OpenOptions::new()
            .write(true)
            .open(p)
            .unwrap()
            .set_len(0)
            .unwrap();
    }
    // The guarded map's fault is ours: the host handler is not called.
    assert_eq!(guarded[100], 0);
    assert!(guarded.changed());
    assert_eq!(HOST_CALLS.load(Ordering::SeqCst), 0);
    // The plain map's fault is the host's.
    assert_eq!(plain[100], 0);
    assert_eq!(HOST_CALLS.load(Ordering::SeqCst), 1);
}
