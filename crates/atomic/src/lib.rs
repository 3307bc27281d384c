//! Atomic file output for brdf-atlas: write a temporary file beside the target, sync it,
//! then rename it over the target. A failed or interrupted write leaves the
//! old file (if any) untouched and no partial file behind.
//!
//! # Nothing left behind
//!
//! Temporaries are named files (`.{name}.tmp-{pid}-{n}`, beside the target)
//! that a process-wide list keeps track of ([`temp_path_for`]), with two ways
//! out besides their own commit or drop:
//!
//! - an interrupt the program can catch (SIGINT, SIGTERM): the program waits
//!   for the signal on an ordinary thread and calls [`remove_temporaries`],
//!   which waits for any output being put in place ([`critical`]: the renames
//!   of one commit happen whole or not at all), removes every temporary and
//!   stops all further commits, so the program exits with the old outputs
//!   untouched, or the complete new ones if it had finished;
//! - a kill nobody can catch (SIGKILL, a crash, a power loss): the next run
//!   that writes into the same directory removes the temporaries of
//!   processes that no longer exist ([`sweep`]).
//!
//! Why not unnamed files (`O_TMPFILE`, linked in by `linkat` on commit)?
//! They would vanish with the process by themselves, but only files can be
//! unnamed and only on some file systems: a report is a directory built
//! under a temporary name, a fit's store goes in by an exchange
//! (`renameat2(RENAME_EXCHANGE)`, see [`swap_in`]) which needs both files
//! named and leaves the old one under the temporary name until the model is
//! in place, and a store on a file system without `O_TMPFILE` still needs
//! a name. Each of these still needs the list and the sweep, so names
//! everywhere, with one mechanism, is simpler and covers every case.
//!
//! ```
//! let dir = tempfile::tempdir()?;
//! let path = dir.path().join("out.txt");
//! brdf_atomic::write_atomic(&path, |w| std::io::Write::write_all(w, b"done"))?;
//! assert_eq!(std::fs::read(&path)?, b"done");
//! // Only the output: no temporary beside it.
//! assert_eq!(std::fs::read_dir(dir.path())?.count(), 1);
//! # Ok::<(), std::io::Error>(())
//! ```

#![warn(missing_docs)]

mod cleanup;

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

pub use cleanup::{committed, critical, remove_temporaries, sweep, temp_path_for};
use cleanup::{create_temp, forget, mark_committed};

/// Write `path` atomically: `fill` writes the whole content into a buffered
/// temporary file, which is then synced and renamed over `path`.
pub fn write_atomic<F>(path: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let (tmp, file) = create_temp(path, |p| File::create(p))?;
    let result = (|| {
        let mut w = BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        w.flush()?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        critical(|| {
            std::fs::rename(&tmp, path)?;
            mark_committed(path);
            Ok(())
        })
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    forget(&tmp);
    result
}

/// Write `fill`'s content to a temporary file beside `path` and sync it, but
/// do not put it in place: the returned [`PendingFile`] does that on
/// [`PendingFile::commit`] and removes the file if dropped. For outputs that
/// must all be replaced together or not at all ([`commit_all`]).
pub fn stage<F>(path: &Path, fill: F) -> io::Result<PendingFile>
where
    F: FnOnce(&mut BufWriter<&File>) -> io::Result<()>,
{
    let pending = PendingFile::create(path)?;
    {
        let mut w = BufWriter::with_capacity(1 << 20, pending.file());
        fill(&mut w)?;
        w.flush()?;
    }
    pending.file().sync_all()?;
    Ok(pending)
}

/// Put staged files in place, in order. Every target is checked first (an
/// existing directory cannot be replaced), so the renames, which do not
/// fail otherwise within one directory, either all happen or none does;
/// on an error every file not yet renamed is removed.
pub fn commit_all(files: Vec<PendingFile>) -> Result<(), (PathBuf, io::Error)> {
    for f in &files {
        if f.target.is_dir() {
            return Err((
                f.target.clone(),
                io::Error::new(io::ErrorKind::IsADirectory, "is a directory"),
            ));
        }
    }
    critical(|| {
        for f in files {
            let target = f.target.clone();
            f.commit(false).map_err(|e| (target, e))?;
        }
        Ok(())
    })
}

/// How [`swap_in`] put a file in place.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Swapped {
    /// There was no old file: a plain rename.
    Renamed,
    /// The old file now lives under the new file's former name (an atomic
    /// exchange): the caller removes it, or swaps back to undo.
    Exchanged,
    /// The file system cannot exchange: renamed over the old file.
    Replaced,
}

/// Put `from` in place at `to` atomically (readers see the old file or the
/// new one, never neither), keeping the old file under `from` when there is
/// one.
///
/// This is a rename for large files written without a sync: renaming over
/// an existing file makes ext4 (`auto_da_alloc`) flush the new file's data
/// inside the rename, which for a 1.75 GB store is seconds of writeback at
/// disk speed. An exchange (`renameat2(RENAME_EXCHANGE)`) does not; the
/// caller decides when the old file goes. Falls back to a rename where the
/// system or file system cannot exchange.
pub fn swap_in(from: &Path, to: &Path) -> io::Result<Swapped> {
    let swapped = critical(|| exchange(from, to))?;
    mark_committed(to);
    Ok(swapped)
}

fn exchange(from: &Path, to: &Path) -> io::Result<Swapped> {
    if std::fs::symlink_metadata(to).is_err() {
        std::fs::rename(from, to)?;
        return Ok(Swapped::Renamed);
    }
    #[cfg(target_os = "linux")]
    {
        use std::ffi::CString;
        use std::os::unix::ffi::OsStrExt;
        let c = |p: &Path| {
            CString::new(p.as_os_str().as_bytes()).map_err(|_| {
                io::Error::new(io::ErrorKind::InvalidInput, "path contains a NUL byte")
            })
        };
        let (cf, ct) = (c(from)?, c(to)?);
        // SAFETY: two valid NUL-terminated paths; renameat2 only reads them.
        let r = unsafe {
            libc::renameat2(
                libc::AT_FDCWD,
                cf.as_ptr(),
                libc::AT_FDCWD,
                ct.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        if r == 0 {
            return Ok(Swapped::Exchanged);
        }
        let e = io::Error::last_os_error();
        // Not supported here (old kernel, other file system): rename below.
        if !matches!(
            e.raw_os_error(),
            Some(libc::EINVAL | libc::ENOSYS | libc::EOPNOTSUPP)
        ) {
            return Err(e);
        }
    }
    std::fs::rename(from, to)?;
    Ok(Swapped::Replaced)
}

/// Ask the kernel to drop the cached pages of `path` (if it exists): best
/// effort, the file itself is untouched. Dirty pages are not dropped (the
/// kernel starts writing them back instead). For a large file that is about
/// to be replaced: freeing its pages is most of the cost of removing it.
pub fn evict_cached(path: &Path) {
    #[cfg(target_os = "linux")]
    if let Ok(file) = File::open(path) {
        use std::os::fd::AsRawFd;
        // SAFETY: a valid open file descriptor; plain integer arguments.
        unsafe { libc::posix_fadvise(file.as_raw_fd(), 0, 0, libc::POSIX_FADV_DONTNEED) };
    }
    #[cfg(not(target_os = "linux"))]
    let _ = path;
}

/// A file being written in place under a temporary name, for writers that
/// need random access (positioned writes from several threads). Dropped
/// without [`PendingFile::commit`], it removes itself.
pub struct PendingFile {
    tmp: PathBuf,
    target: PathBuf,
    file: Option<File>,
}

impl PendingFile {
    /// Create the temporary file for `target`.
    pub fn create(target: &Path) -> io::Result<PendingFile> {
        let (tmp, file) = create_temp(target, |tmp| {
            File::options()
                .read(true)
                .write(true)
                .create_new(true)
                .open(tmp)
        })?;
        Ok(PendingFile {
            tmp,
            target: target.to_path_buf(),
            file: Some(file),
        })
    }

    /// Size the file to `len` bytes and reserve its disk blocks up front
    /// (`fallocate`), where the file system can: a full disk is then an
    /// error here, before any work, and positioned writes into the reserved
    /// range are cheaper (no delayed-allocation bookkeeping page by page).
    pub fn allocate(&self, len: u64) -> io::Result<()> {
        let file = self.file();
        file.set_len(len)?;
        #[cfg(target_os = "linux")]
        if len > 0 {
            use std::os::fd::AsRawFd;
            let off = libc::off_t::try_from(len)
                .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "file too large"))?;
            // SAFETY: a valid open file descriptor; plain integer arguments.
            if unsafe { libc::fallocate(file.as_raw_fd(), 0, 0, off) } != 0 {
                let e = io::Error::last_os_error();
                // Not supported by this file system: stay sparse.
                if !matches!(e.raw_os_error(), Some(libc::EOPNOTSUPP | libc::ENOSYS)) {
                    return Err(e);
                }
            }
        }
        Ok(())
    }

    /// The path the file takes on commit.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The open temporary file.
    pub fn file(&self) -> &File {
        self.file.as_ref().expect("file present until commit")
    }

    /// Rename over the target; with `sync`, flush the data to disk first.
    ///
    /// Without `sync` the rename is still atomic for every reader, but a
    /// power loss may leave a truncated file: right for large derived data
    /// that carries its own checksum (a store), not for a user's only copy.
    pub fn commit(mut self, sync: bool) -> io::Result<()> {
        let file = self.file.take().expect("file present until commit");
        if sync {
            file.sync_all()?;
        }
        drop(file);
        critical(|| std::fs::rename(&self.tmp, &self.target))?;
        mark_committed(&self.target);
        forget(&self.tmp);
        self.tmp = PathBuf::new();
        Ok(())
    }
}

impl Drop for PendingFile {
    fn drop(&mut self) {
        if !self.tmp.as_os_str().is_empty() {
            self.file.take();
            let _ = std::fs::remove_file(&self.tmp);
            forget(&self.tmp);
        }
    }
}

/// A directory filled under a temporary name beside its target and put in
/// place as a whole by [`StagedDir::commit`]: readers see the old directory
/// (if any) or the complete new one, never a part. Dropped without a commit,
/// it removes itself and everything in it.
pub struct StagedDir {
    dir: PathBuf,
    target: PathBuf,
    committed: bool,
}

impl StagedDir {
    /// Create the temporary directory for `target` (and any missing parent).
    pub fn create(target: &Path) -> io::Result<StagedDir> {
        if let Some(parent) = target.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent)?;
        }
        let (dir, ()) = create_temp(target, |p| std::fs::create_dir(p))?;
        Ok(StagedDir {
            dir,
            target: target.to_path_buf(),
            committed: false,
        })
    }

    /// The temporary directory, to write into.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// The path the directory takes on commit.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Put the directory in place, replacing whatever is at the target: by
    /// an exchange where the file system can (the old one then leaves under
    /// the temporary name and is removed), else the old one is moved aside
    /// first (and moved back if the new one cannot take its place), then
    /// removed. The error names the path that failed.
    pub fn commit(mut self) -> Result<(), (PathBuf, io::Error)> {
        critical(|| {
            match swap_in(&self.dir, &self.target) {
                Ok(Swapped::Exchanged) => {
                    self.committed = true;
                    // The old directory, now under the temporary name.
                    let old = self.dir.clone();
                    std::fs::remove_dir_all(&old).map_err(|e| (old.clone(), e))?;
                    forget(&old);
                    return Ok(());
                }
                Ok(_) => {
                    self.committed = true;
                    forget(&self.dir);
                    return Ok(());
                }
                // Cannot exchange, and a directory cannot be renamed over a
                // non-empty one: move the old one aside below.
                Err(_) if std::fs::symlink_metadata(&self.target).is_ok() => {}
                Err(e) => return Err((self.target.clone(), e)),
            }
            let old = temp_path_for(&self.target);
            std::fs::rename(&self.target, &old).map_err(|e| (self.target.clone(), e))?;
            if let Err(e) = std::fs::rename(&self.dir, &self.target) {
                // Best effort: the error below is what matters.
                let _ = std::fs::rename(&old, &self.target);
                forget(&old);
                return Err((self.target.clone(), e));
            }
            self.committed = true;
            mark_committed(&self.target);
            forget(&self.dir);
            std::fs::remove_dir_all(&old).map_err(|e| (old.clone(), e))?;
            forget(&old);
            Ok(())
        })
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.dir);
            forget(&self.dir);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_keeps_old_content_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        write_atomic(&path, |w| w.write_all(b"good")).unwrap();
        let err = write_atomic(&path, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("boom"))
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"good");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn swap_in_keeps_the_old_file_until_asked() {
        let dir = tempfile::tempdir().unwrap();
        let (new, target) = (dir.path().join("new"), dir.path().join("target"));
        std::fs::write(&new, b"first").unwrap();
        assert_eq!(swap_in(&new, &target).unwrap(), Swapped::Renamed);
        assert_eq!(std::fs::read(&target).unwrap(), b"first");
        assert!(!new.exists());
        std::fs::write(&new, b"second").unwrap();
        match swap_in(&new, &target).unwrap() {
            Swapped::Exchanged => {
                assert_eq!(std::fs::read(&new).unwrap(), b"first");
                // Swapping back undoes it.
                assert_eq!(swap_in(&new, &target).unwrap(), Swapped::Exchanged);
                assert_eq!(std::fs::read(&target).unwrap(), b"first");
                assert_eq!(std::fs::read(&new).unwrap(), b"second");
            }
            Swapped::Replaced => assert!(!new.exists()),
            Swapped::Renamed => panic!("the target existed"),
        }
    }

    #[test]
    fn pending_file_removes_itself_unless_committed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("store");
        {
            let p = PendingFile::create(&path).unwrap();
            p.file().set_len(10).unwrap();
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        let p = PendingFile::create(&path).unwrap();
        p.allocate(10).unwrap();
        p.commit(true).unwrap();
        assert_eq!(std::fs::metadata(&path).unwrap().len(), 10);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn staged_dir_replaces_the_target_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("nested").join("report");
        let names = |p: &Path| {
            let mut v: Vec<String> = std::fs::read_dir(p)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        // Dropped: nothing left, the target never appears.
        {
            let staged = StagedDir::create(&target).unwrap();
            std::fs::write(staged.path().join("a.txt"), b"a").unwrap();
            assert_eq!(staged.target(), target);
        }
        assert_eq!(names(&dir.path().join("nested")), Vec::<String>::new());
        // Committed: in place with its content.
        let staged = StagedDir::create(&target).unwrap();
        std::fs::write(staged.path().join("a.txt"), b"first").unwrap();
        staged.commit().unwrap();
        assert_eq!(std::fs::read(target.join("a.txt")).unwrap(), b"first");
        // Committed again: the old directory is gone, not merged.
        let staged = StagedDir::create(&target).unwrap();
        std::fs::write(staged.path().join("b.txt"), b"second").unwrap();
        staged.commit().unwrap();
        assert_eq!(names(&target), ["b.txt"]);
        assert_eq!(names(&dir.path().join("nested")), ["report"]);
    }
}
