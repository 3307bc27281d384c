//! Read-only file maps that survive the file changing under them.
//!
//! Reading a memory-mapped file that another program truncates kills the
//! process with SIGBUS; one that is rewritten in place at the same size
//! silently changes under the reader. A [`GuardedMap`] turns both into an
//! answer the caller can act on:
//!
//! - **Shrunk or truncated:** the first read past the new end raises
//!   SIGBUS. A process-wide handler (installed once, in front of the
//!   process's own, which still gets every other SIGBUS) maps zero pages
//!   over the whole map and marks it poisoned; the read returns zeros, and
//!   [`GuardedMap::changed`] says so.
//! - **Rewritten, same size:** [`GuardedMap::changed`] also compares the
//!   file's size and modification time with those seen when it was mapped
//!   (one `fstat`, or one `stat` of the path for maps that do not keep
//!   their file open).
//!
//! So a reader maps, reads, then asks [`GuardedMap::changed`] before it
//! trusts what it read; once changed, a map stays changed.
//!
//! ## The process-wide handler, and how to opt out
//!
//! The first [`GuardedMap::open`] installs a `SA_SIGINFO` handler for
//! SIGBUS with `sigaction` (flags `SA_ONSTACK | SA_NODEFER`), once for the
//! process and never removed. It chains: a SIGBUS outside the library's
//! own maps goes to the action SIGBUS had before (its handler, called as it
//! asked to be, or the default action); a handler the host installs later
//! must pass SIGBUS on to the one it replaced, or a truncation kills the
//! process. A host that wants SIGBUS left alone (a JVM, a sanitizer, a
//! crash reporter) opts out before the first map is opened, with
//! [`set_sigbus_guard`]`(false)` or by setting [`NO_HANDLER_ENV`]
//! (`BRDF_ATLAS_NO_SIGBUS_HANDLER=1`); then a read past the end of a file
//! truncated under its map raises SIGBUS as it would without the library,
//! and [`GuardedMap::changed`] still reports a rewrite or a truncation it
//! sees before such a read.
//!
//! Reading with positioned reads into the library's own blocks instead of
//! a map would need no handler, but costs a pass over the store 24 to 97%
//! more for a reconstruction, 3 to 21% for the exact albedo pass and the
//! Gram matrix (docs/performance.md, "Reading the store: memory map or
//! positioned reads"), so the maps and their handler stay, with the
//! opt-out.
//!
//! ```
//! use brdf_mapguard::{GuardedMap, Watch};
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("data");
//! std::fs::write(&path, vec![7u8; 10_000]).unwrap();
//! let map = GuardedMap::open(&path, Watch::Descriptor).unwrap();
//! std::fs::OpenOptions::new().write(true).open(&path).unwrap().set_len(100).unwrap();
//! let sum: u64 = map.iter().map(|b| *b as u64).sum(); // no SIGBUS: zeros
//! assert!(map.changed());
//! # let _ = sum;
//! ```
#![warn(missing_docs)]

use std::fs::File;
use std::io;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use memmap2::Mmap;

mod choice;
#[cfg(target_os = "linux")]
mod handler;
mod regular;

pub use choice::{NO_HANDLER_ENV, set_sigbus_guard, sigbus_guarded};

pub use regular::{open_regular, read_regular, regular_file};
mod registry;

/// How [`GuardedMap::changed`] looks for a same-size rewrite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Watch {
    /// Keep the file open and `fstat` it: sees any write to the mapped file,
    /// even after it is renamed or unlinked. One descriptor per map.
    Descriptor,
    /// `stat` the path: no descriptor held (for the many inputs of a fit);
    /// a path that now names another file (replaced by a rename) leaves the
    /// mapped file as it was, so only a write to the same file counts.
    Path,
}

/// What a file's metadata says about its content: the file (device and
/// inode), its size and its modification time (seconds, nanoseconds).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stamp {
    /// Device of the file system.
    pub dev: u64,
    /// Inode number.
    pub ino: u64,
    /// Size in bytes.
    pub size: u64,
    /// Last modification: seconds and nanoseconds since the epoch.
    pub mtime: (i64, i64),
}

impl Stamp {
    fn of(m: &std::fs::Metadata) -> Stamp {
        Stamp {
            dev: m.dev(),
            ino: m.ino(),
            size: m.size(),
            mtime: (m.mtime(), m.mtime_nsec()),
        }
    }
}

/// A read-only map of a whole file, registered with the SIGBUS handler
/// while it lives (unless the process opted out, [`set_sigbus_guard`]).
/// Dereferences to its bytes.
pub struct GuardedMap {
    map: Mmap,
    path: PathBuf,
    file: Option<File>,
    seen: Stamp,
    slot: Option<registry::SlotId>,
    changed: AtomicBool,
}

impl std::fmt::Debug for GuardedMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GuardedMap")
            .field("path", &self.path)
            .field("len", &self.map.len())
            .finish()
    }
}

impl GuardedMap {
    /// Open and map the file at `path`, read-only. The first open of the
    /// process installs the SIGBUS handler, unless it opted out (see the
    /// crate docs).
    pub fn open(path: &Path, watch: Watch) -> io::Result<GuardedMap> {
        let file = open_regular(path)?;
        Self::map_file(file, path, watch)
    }

    /// Map an open file, read-only, watched by its descriptor; `path` names
    /// it in messages (a file written without a name, `O_TMPFILE`, is
    /// mapped this way before it takes its place at `path`).
    pub fn from_file(file: File, path: &Path) -> io::Result<GuardedMap> {
        if !file.metadata()?.is_file() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "is not a regular file",
            ));
        }
        Self::map_file(file, path, Watch::Descriptor)
    }

    fn map_file(file: File, path: &Path, watch: Watch) -> io::Result<GuardedMap> {
        let seen = Stamp::of(&file.metadata()?);
        let guarded = sigbus_guarded();
        #[cfg(target_os = "linux")]
        if guarded {
            handler::install();
        }
        // SAFETY: a read-only map. A file changed under it cannot make safe
        // Rust unsound here: its bytes are read as plain integers and
        // floats, and a truncation (SIGBUS) is answered with zero pages by
        // the handler, for as long as the range is registered (until drop).
        // A process that opted out of the handler gets SIGBUS then, as with
        // any map: a signal, not undefined behaviour in safe code.
        let map = unsafe { Mmap::map(&file) }?;
        let slot = if map.is_empty() || !guarded {
            None
        } else {
            Some(
                registry::register(map.as_ptr() as usize, map.len()).ok_or_else(|| {
                    io::Error::other(format!(
                        "more than {} files mapped at once",
                        registry::SLOTS
                    ))
                })?,
            )
        };
        Ok(GuardedMap {
            map,
            path: path.to_path_buf(),
            file: (watch == Watch::Descriptor).then_some(file),
            seen,
            slot,
            changed: AtomicBool::new(false),
        })
    }

    /// Another map of the same file, watched the same way: by a duplicate
    /// of its descriptor when it is watched by one (the file need have no
    /// name), else opened again by its path.
    pub fn try_clone(&self) -> io::Result<GuardedMap> {
        match &self.file {
            Some(file) => Self::map_file(file.try_clone()?, &self.path, Watch::Descriptor),
            None => Self::open(&self.path, Watch::Path),
        }
    }

    /// The mapped bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.map
    }

    /// The file's stamp when it was mapped.
    pub fn stamp(&self) -> Stamp {
        self.seen
    }

    /// Has the file been truncated under the map (its pages then read as
    /// zeros), or rewritten since it was mapped? Sticky: once true, always
    /// true. Costs an atomic load and one `fstat` (or `stat`).
    pub fn changed(&self) -> bool {
        if self.poisoned() {
            return true;
        }
        let now = match &self.file {
            Some(file) => file.metadata().map(|m| Stamp::of(&m)),
            None => std::fs::metadata(&self.path).map(|m| Stamp::of(&m)),
        };
        let changed = match now {
            // Another file at the path: the mapped one is as it was.
            Ok(now)
                if self.file.is_none() && (now.dev, now.ino) != (self.seen.dev, self.seen.ino) =>
            {
                false
            }
            Ok(now) => now != self.seen,
            // The descriptor always answers; a path may be gone (removed or
            // renamed), which leaves the mapped file as it was.
            Err(_) => self.file.is_some(),
        };
        if changed {
            self.changed.store(true, Ordering::Release);
        }
        changed
    }

    /// Has a change already been seen (by the SIGBUS handler or
    /// [`GuardedMap::changed`])? An atomic load, no system call.
    pub fn poisoned(&self) -> bool {
        self.changed.load(Ordering::Acquire) || self.slot.is_some_and(registry::poisoned)
    }
}

impl std::ops::Deref for GuardedMap {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        &self.map
    }
}

impl Drop for GuardedMap {
    fn drop(&mut self) {
        // Unregistered before the map goes, so the handler never touches
        // an address that is no longer ours.
        if let Some(slot) = self.slot.take() {
            registry::unregister(slot);
        }
    }
}
