//! Memory accounting for the figures a fit reports: the heap, counted by
//! an allocator wrapper a binary installs with `#[global_allocator]`, and
//! the process's private memory as the kernel reports it ([`private`]).
//!
//! Counts bytes, not calls: one relaxed atomic add per allocation and
//! free, and a compare loop only when a new peak is set. Memory-mapped
//! files (the inputs, the store) are not heap and are not counted.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static INSTALLED: AtomicBool = AtomicBool::new(false);

/// The system allocator, counting live and peak heap bytes.
pub struct Counting;

// SAFETY: every call is forwarded unchanged to the system allocator; the
// counters are only arithmetic on the sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: same contract as the caller's.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: same contract as the caller's.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: same contract as the caller's.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
            grow(new_size);
        }
        p
    }
}

fn grow(size: usize) {
    let live = LIVE.fetch_add(size, Ordering::Relaxed) + size;
    if live > PEAK.load(Ordering::Relaxed) {
        PEAK.fetch_max(live, Ordering::Relaxed);
        INSTALLED.store(true, Ordering::Relaxed);
    }
}

/// Largest live heap since the start or the last [`reset_peak`], in bytes;
/// `None` when [`Counting`] is not the global allocator.
pub fn peak() -> Option<usize> {
    INSTALLED
        .load(Ordering::Relaxed)
        .then(|| PEAK.load(Ordering::Relaxed))
}

/// Live heap now, in bytes (0 when [`Counting`] is not installed).
pub fn live() -> usize {
    LIVE.load(Ordering::Relaxed)
}

/// Start a new peak from the heap live now.
pub fn reset_peak() {
    PEAK.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
}

/// The process's resident private memory now, in bytes: `RssAnon` of
/// `/proc/self/status` (Linux; `None` elsewhere or when it cannot be read).
///
/// `RssAnon` counts the anonymous pages in memory: the heap, anonymous
/// maps and thread stacks, as far as they were touched. Address space
/// reserved and never touched is not in it (faer's products reserve twice
/// the reported L3 cache in a thread and touch little of it), nor are the
/// memory-mapped inputs and store, which are file mappings.
pub fn resident_private() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status_kib(&status, "RssAnon:").map(|k| k * 1024)
}

/// The value in KiB of the `key` line (`VmData:   1234 kB`) of a
/// `/proc/PID/status` text.
pub fn status_kib(status: &str, key: &str) -> Option<u64> {
    let line = status.lines().find_map(|l| l.strip_prefix(key))?;
    line.trim().strip_suffix("kB")?.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_what_is_allocated_and_freed() {
        // Other tests allocate concurrently: assert bounds, not equalities.
        reset_peak();
        let before = peak().expect("installed in the test binary");
        let big = vec![1u8; 64 << 20];
        let mut grown: Vec<u64> = Vec::with_capacity(1);
        grown.resize(8 << 20, 7);
        let top = peak().unwrap();
        assert!(top >= (128 << 20), "{before} -> {top}");
        assert!(live() >= (128 << 20));
        drop((big, grown));
        reset_peak();
        assert!(peak().unwrap() < top);
    }

    #[test]
    fn reads_resident_private_memory_from_the_status_text() {
        let text = "Name:\tx\nVmData:\t   5678 kB\nRssAnon:\t   1234 kB\nVmStk:\t 132 kB\n";
        assert_eq!(status_kib(text, "RssAnon:"), Some(1234));
        assert_eq!(status_kib(text, "VmSwap:"), None);
        assert_eq!(status_kib("RssAnon: lots", "RssAnon:"), None);
        if cfg!(target_os = "linux") {
            // At least the 64 MiB allocated and written here while it is alive.
            let held = vec![1u8; 64 << 20];
            assert!(resident_private().unwrap() >= held.len() as u64);
            std::hint::black_box(&held);
        }
    }
}
