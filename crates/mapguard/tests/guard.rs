//! Guarded maps of files truncated or rewritten while mapped: the process
//! lives, reads see zeros, and `changed` says so.

use std::fs::{File, OpenOptions};
use std::path::Path;
use std::time::{Duration, SystemTime};

use brdf_mapguard::{GuardedMap, Watch};

const LEN: usize = 1 << 20;

/// A file of `LEN` bytes of 1, dated an hour ago (so that a rewrite now
/// has another modification time whatever the timestamp granularity).
fn file_of_ones(path: &Path) {
    std::fs::write(path, vec![1u8; LEN]).unwrap();
    let hour_ago = SystemTime::now() - Duration::from_secs(3600);
    File::options()
        .write(true)
        .open(path)
        .unwrap()
        .set_modified(hour_ago)
        .unwrap();
}

fn sum(bytes: &[u8]) -> u64 {
    bytes.iter().map(|b| *b as u64).sum()
}

#[test]
fn a_truncated_file_reads_as_zeros_and_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f");
    file_of_ones(&path);
    for watch in [Watch::Descriptor, Watch::Path] {
        let map = GuardedMap::open(&path, watch).unwrap();
        assert_eq!(sum(&map), LEN as u64);
        assert!(!map.changed() && !map.poisoned());
        OpenOptions::new()
            .write(true)
            .open(&path)
            .unwrap()
            .set_len(4096)
            .unwrap();
        // Past the new end: SIGBUS, answered with zeros for the whole map.
        assert_eq!(map[LEN - 1], 0);
        assert!(map.poisoned() && map.changed());
        assert_eq!(sum(&map), 0);
        drop(map);
        file_of_ones(&path);
    }
}

#[test]
fn a_same_size_rewrite_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f");
    file_of_ones(&path);
    for watch in [Watch::Descriptor, Watch::Path] {
        let map = GuardedMap::open(&path, watch).unwrap();
        assert!(!map.changed());
        // In place, as `cp` does: truncate, then write the same length.
        std::fs::write(&path, vec![2u8; LEN]).unwrap();
        assert!(map.changed(), "{watch:?}");
        assert!(map.poisoned(), "sticky");
        drop(map);
        file_of_ones(&path);
    }
}

#[test]
fn a_file_replaced_by_rename_keeps_the_mapped_content() {
    let dir = tempfile::tempdir().unwrap();
    let (path, other) = (dir.path().join("f"), dir.path().join("g"));
    file_of_ones(&path);
    let by_path = GuardedMap::open(&path, Watch::Path).unwrap();
    let by_fd = GuardedMap::open(&path, Watch::Descriptor).unwrap();
    std::fs::write(&other, vec![3u8; 10]).unwrap();
    std::fs::rename(&other, &path).unwrap();
    for map in [&by_path, &by_fd] {
        assert_eq!(sum(map), LEN as u64);
        assert!(!map.changed());
    }
    std::fs::remove_file(&path).unwrap();
    assert!(!by_path.changed() && !by_fd.changed());
}

#[test]
fn readers_on_many_threads_survive_a_truncation() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f");
    file_of_ones(&path);
    let map = GuardedMap::open(&path, Watch::Descriptor).unwrap();
    let truncated = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                // Every pass reads all ones (before) or, once the
                // truncation is done, a map the handler has zeroed; a pass
                // that overlaps it may see a mix. None crashes.
                loop {
                    let done = truncated.load(std::sync::atomic::Ordering::Acquire);
                    let total = sum(&map);
                    assert!(total <= LEN as u64);
                    if done {
                        assert_eq!(total, 0);
                        break;
                    }
                }
            });
        }
        OpenOptions::new()
            .write(true)
            .open(&path)
            .unwrap()
            .set_len(0)
            .unwrap();
        // Make sure the pages go: the readers may not have faulted yet.
        assert_eq!(map[0], 0);
        truncated.store(true, std::sync::atomic::Ordering::Release);
    });
    assert!(map.changed());
}

#[test]
fn an_empty_file_maps_and_never_faults() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty");
    std::fs::write(&path, b"").unwrap();
    let map = GuardedMap::open(&path, Watch::Descriptor).unwrap();
    assert!(map.is_empty() && !map.changed());
}
