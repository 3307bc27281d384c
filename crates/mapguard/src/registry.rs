//! The process-wide table of the ranges this library has mapped, read by
//! the SIGBUS handler without locks or allocation.
//!
//! A slot holds one range (`start`, `len`) and its `poisoned` flag. Slots
//! are claimed with a compare-and-swap on `claimed`, and their range is
//! written under a sequence count (odd while it is written), so the handler
//! never acts on a half-written range: it skips a slot whose count is odd
//! or moved while it read it. Skipping is right: a range is registered
//! before its map is first read and unregistered after its last read, so
//! no fault in it can happen while its slot is being written.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering, fence};

/// Ranges mapped at once: Linux's default limit on a process's memory maps
/// (`vm.max_map_count`, 65530) is below it, so the table never fills
/// before the kernel refuses a map.
pub(crate) const SLOTS: usize = 1 << 16;

struct Slot {
    claimed: AtomicBool,
    seq: AtomicUsize,
    start: AtomicUsize,
    len: AtomicUsize,
    poisoned: AtomicBool,
}

#[allow(clippy::declare_interior_mutable_const)]
const FREE: Slot = Slot {
    claimed: AtomicBool::new(false),
    seq: AtomicUsize::new(0),
    start: AtomicUsize::new(0),
    len: AtomicUsize::new(0),
    poisoned: AtomicBool::new(false),
};

static TABLE: [Slot; SLOTS] = [FREE; SLOTS];
/// One past the highest slot ever claimed: the handler scans no further.
static HIGH: AtomicUsize = AtomicUsize::new(0);

/// A claimed slot; unregistered by [`unregister`], not by drop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SlotId(usize);

/// Record the range `start .. start + len`; `None` when every slot is taken.
pub(crate) fn register(start: usize, len: usize) -> Option<SlotId> {
    for (i, slot) in TABLE.iter().enumerate() {
        if slot
            .claimed
            .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            continue;
        }
        HIGH.fetch_max(i + 1, Ordering::AcqRel);
        write(slot, start, len);
        return Some(SlotId(i));
    }
    None
}

/// Forget a range (its map is about to be unmapped) and free its slot.
pub(crate) fn unregister(id: SlotId) {
    let slot = &TABLE[id.0];
    write(slot, 0, 0);
    slot.claimed.store(false, Ordering::Release);
}

fn write(slot: &Slot, start: usize, len: usize) {
    slot.seq.fetch_add(1, Ordering::AcqRel);
    fence(Ordering::Release);
    slot.start.store(start, Ordering::Relaxed);
    slot.len.store(len, Ordering::Relaxed);
    slot.poisoned.store(false, Ordering::Relaxed);
    slot.seq.fetch_add(1, Ordering::Release);
}

/// Has the handler replaced this range's pages?
pub(crate) fn poisoned(id: SlotId) -> bool {
    TABLE[id.0].poisoned.load(Ordering::Acquire)
}

/// The registered range holding `addr`, as `(start, len)`, after marking it
/// poisoned. Async-signal-safe: atomics only, no locks, no allocation.
pub(crate) fn poison_range_of(addr: usize) -> Option<(usize, usize)> {
    let high = HIGH.load(Ordering::Acquire).min(SLOTS);
    for slot in &TABLE[..high] {
        let before = slot.seq.load(Ordering::Acquire);
        if before % 2 == 1 {
            continue;
        }
        let start = slot.start.load(Ordering::Relaxed);
        let len = slot.len.load(Ordering::Relaxed);
        fence(Ordering::Acquire);
        if slot.seq.load(Ordering::Relaxed) != before || len == 0 {
            continue;
        }
        if addr >= start && addr - start < len {
            slot.poisoned.store(true, Ordering::SeqCst);
            return Some((start, len));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_found_poisoned_and_forgotten() {
        // Addresses far from anything this process maps for real.
        let a = register(0x7000_0000_0000, 8192).unwrap();
        let b = register(0x7000_0001_0000, 4096).unwrap();
        assert_ne!(a, b);
        assert_eq!(poison_range_of(0x7000_0000_0000 - 1), None);
        assert!(!poisoned(a) && !poisoned(b));
        assert_eq!(
            poison_range_of(0x7000_0000_1fff),
            Some((0x7000_0000_0000, 8192))
        );
        assert!(poisoned(a) && !poisoned(b));
        assert_eq!(poison_range_of(0x7000_0000_2000), None);
        unregister(a);
        assert_eq!(poison_range_of(0x7000_0000_1000), None);
        // A slot claimed again starts clean.
        let c = register(0x7000_0002_0000, 4096).unwrap();
        assert!(!poisoned(c));
        unregister(b);
        unregister(c);
    }
}
