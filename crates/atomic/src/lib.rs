//! Atomic file output for brdf-atlas: write a temporary file beside the
//! target, sync it, then rename it over the target. A failed or interrupted
//! write leaves the old file (if any) untouched and no partial file behind.
//!
//! # Nothing left behind
//!
//! Files are written without a name where the file system allows
//! (`O_TMPFILE`, Linux 3.11 and ext4, XFS, Btrfs, tmpfs among others): a
//! [`PendingFile`] is linked under a temporary name beside its target only
//! as it is put in place, and renamed over the target at once, so a process
//! killed while it writes (SIGKILL, the out-of-memory killer, a crash)
//! leaves nothing at all.
//!
//! What cannot be unnamed has a name (`.{name}.tmp-{pid}-{n}`, beside the
//! target) that a process-wide list keeps track of ([`temp_path_for`]): the
//! directories a report is built in ([`StagedDir`]), files on a file system
//! without `O_TMPFILE`, and the instant between a commit's link and its
//! rename. For those there are two ways out besides their own commit or
//! drop:
//!
//! - an interrupt the program can catch (SIGINT, SIGTERM): the program waits
//!   for the signal on an ordinary thread and calls [`remove_temporaries`],
//!   which waits for any output being put in place ([`critical`]: the renames
//!   of one commit happen whole or not at all), removes every temporary and
//!   stops all further commits, so the program exits with the old outputs
//!   untouched, or the complete new ones if it had finished;
//! - a kill nobody can catch: the next run that writes into the same
//!   directory removes the temporaries of processes that no longer exist
//!   ([`sweep`]).
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
mod scratch;
mod unnamed;

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

pub use cleanup::{
    committed, create_dir_all_owned, critical, remove_temporaries, sweep, temp_path_for,
};
use cleanup::{create_temp, create_unnamed, forget, mark_committed};
pub use scratch::scratch_file;

/// A new file at `path` (which must not exist), open for reading and writing.
fn open_new(path: &Path) -> io::Result<File> {
    File::options()
        .read(true)
        .write(true)
        .create_new(true)
        .open(path)
}

/// Write `path` atomically: `fill` writes the whole content into a buffered
/// temporary file, which is then synced and renamed over `path`.
pub fn write_atomic<F>(path: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let pending = PendingFile::create(path)?;
    let mut w = BufWriter::with_capacity(1 << 20, pending.file().try_clone()?);
    fill(&mut w)?;
    w.flush()?;
    drop(w);
    pending.commit(true)
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
    stop_in_stage();
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

/// A file being written beside its target, for writers that need random
/// access (positioned writes from several threads). Unnamed while it is
/// written where the file system allows (`O_TMPFILE`), so a killed process
/// leaves nothing; else under a registered temporary name. Dropped without
/// [`PendingFile::commit`], it removes itself.
pub struct PendingFile {
    /// The temporary's name: `None` while the file has none.
    tmp: Option<PathBuf>,
    target: PathBuf,
    file: Option<File>,
    /// Put in place or handed over ([`PendingFile::into_named`]): not
    /// removed on drop.
    done: bool,
}

impl PendingFile {
    /// Create the temporary file for `target`: unnamed where the file
    /// system allows, else named (`.{name}.tmp-{pid}-{n}`).
    pub fn create(target: &Path) -> io::Result<PendingFile> {
        if let Some(file) = create_unnamed(target, unnamed::open_unnamed)? {
            return Ok(PendingFile {
                tmp: None,
                target: target.to_path_buf(),
                file: Some(file),
                done: false,
            });
        }
        let (tmp, file) = create_temp(target, open_new)?;
        Ok(PendingFile {
            tmp: Some(tmp),
            target: target.to_path_buf(),
            file: Some(file),
            done: false,
        })
    }

    /// Does the file have no name yet (`O_TMPFILE`)?
    pub fn is_unnamed(&self) -> bool {
        self.tmp.is_none()
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

    /// The temporary's name, given now if it has none: a registered
    /// temporary beside the target.
    fn named(&mut self) -> io::Result<PathBuf> {
        if let Some(tmp) = &self.tmp {
            return Ok(tmp.clone());
        }
        let file = self.file.as_ref().expect("file present until commit");
        let (tmp, ()) = create_temp(&self.target, |tmp| unnamed::link(file, tmp))?;
        self.tmp = Some(tmp.clone());
        Ok(tmp)
    }

    /// Rename over the target; with `sync`, flush the data to disk first.
    /// An unnamed file is first linked under a temporary name beside the
    /// target, then renamed: the name exists only inside the commit.
    ///
    /// Without `sync` the rename is still atomic for every reader, but a
    /// power loss may leave a truncated file: right for large derived data
    /// that carries its own checksum (a store), not for a user's only copy.
    pub fn commit(mut self, sync: bool) -> io::Result<()> {
        if sync {
            self.file().sync_all()?;
        }
        critical(|| {
            stop_before_commit();
            let tmp = self.named()?;
            std::fs::rename(&tmp, &self.target)?;
            self.done = true;
            forget(&tmp);
            // Inside the commit: an interrupt waiting for it must see it.
            mark_committed(&self.target);
            Ok(())
        })
    }

    /// Give the file its temporary name (if it has none) and hand that name
    /// over: the file is no longer removed on drop, and the caller puts it
    /// in place or removes it. The name stays registered, so an interrupt
    /// still removes it. For a file that goes in by [`swap_in`]; call it
    /// inside [`critical`], just before.
    pub fn into_named(mut self) -> io::Result<PathBuf> {
        stop_before_commit();
        let tmp = self.named()?;
        self.done = true;
        Ok(tmp)
    }
}

/// For the tests of killed runs: with `BRDF_ATLAS_TEST_STOP_IN=commit` in
/// its environment the process stops itself (SIGSTOP), once, as its first
/// output is about to be named and put in place: every byte of it written,
/// nothing in place. A test then kills it at that moment, not after a guess
/// at a delay. (The command-line tool's progress stops at its phases on the
/// same variable.)
fn stop_before_commit() {
    #[cfg(unix)]
    {
        use std::sync::atomic::{AtomicBool, Ordering};
        static DONE: AtomicBool = AtomicBool::new(false);
        if std::env::var_os("BRDF_ATLAS_TEST_STOP_IN").is_some_and(|p| p == "commit")
            && !DONE.swap(true, Ordering::SeqCst)
        {
            // SAFETY: raise has no memory-safety preconditions.
            unsafe { libc::raise(libc::SIGSTOP) };
        }
    }
}

/// For the tests of interrupted runs: with `BRDF_ATLAS_TEST_STOP_IN=stage`
/// in its environment the process stops itself (SIGSTOP), once, as its
/// first staged output ([`stage`]) has been created and before anything is
/// written into it: the run's output directory exists, nothing is in place.
fn stop_in_stage() {
    #[cfg(unix)]
    {
        use std::sync::atomic::{AtomicBool, Ordering};
        static DONE: AtomicBool = AtomicBool::new(false);
        if std::env::var_os("BRDF_ATLAS_TEST_STOP_IN").is_some_and(|p| p == "stage")
            && !DONE.swap(true, Ordering::SeqCst)
        {
            // SAFETY: raise has no memory-safety preconditions.
            unsafe { libc::raise(libc::SIGSTOP) };
        }
    }
}

impl Drop for PendingFile {
    fn drop(&mut self) {
        self.file.take();
        if !self.done
            && let Some(tmp) = &self.tmp
        {
            let _ = std::fs::remove_file(tmp);
            forget(tmp);
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
            stop_before_commit();
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

    /// Does the file system of `dir` make unnamed files? (ext4, XFS, Btrfs
    /// and tmpfs do: the machines this is tested on.)
    fn makes_unnamed(dir: &Path) -> bool {
        unnamed::open_unnamed(dir).unwrap().is_some()
    }

    /// Are the tests run where temporary files cannot be unnamed (set
    /// `BRDF_ATOMIC_NAMED_ONLY=1`), so that the unnamed cases are skipped
    /// by request rather than passing silently?
    fn named_only() -> bool {
        !cfg!(target_os = "linux") || std::env::var_os("BRDF_ATOMIC_NAMED_ONLY").is_some()
    }

    #[test]
    fn an_unnamed_file_has_no_name_until_it_is_in_place() {
        let dir = tempfile::tempdir().unwrap();
        if !makes_unnamed(dir.path()) {
            assert!(named_only(), "{} has no O_TMPFILE", dir.path().display());
            return;
        }
        let path = dir.path().join("out.bin");
        let p = PendingFile::create(&path).unwrap();
        assert!(p.is_unnamed());
        p.file().write_all(b"abc").unwrap();
        // Written, and nothing in the directory.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        p.commit(false).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"abc");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // A new file's mode, as File::create gives one (the umask applies).
        use std::os::unix::fs::PermissionsExt;
        let plain = dir.path().join("plain");
        File::create(&plain).unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&path), mode(&plain));
        // Dropped unnamed: nothing to remove, nothing there.
        {
            let p = PendingFile::create(&dir.path().join("never")).unwrap();
            p.file().write_all(b"x").unwrap();
        }
        assert!(!dir.path().join("never").exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
        // Handed over by name: the caller's to move, not removed on drop.
        let p = PendingFile::create(&dir.path().join("swap")).unwrap();
        p.file().write_all(b"new").unwrap();
        let named = critical(|| p.into_named()).unwrap();
        assert_eq!(std::fs::read(&named).unwrap(), b"new");
        assert_eq!(swap_in(&named, &path).unwrap(), Swapped::Exchanged);
        assert_eq!(std::fs::read(&named).unwrap(), b"abc");
        std::fs::remove_file(&named).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
    }

    #[test]
    fn a_killed_writer_leaves_its_directory_as_it_was() {
        // A child process writes an unnamed file and is killed (SIGKILL)
        // before it commits: the directory is as before, hidden files
        // included. The child is this test binary, run again.
        if let Some(dir) = std::env::var_os("BRDF_ATOMIC_KILLED_CHILD") {
            let p = PendingFile::create(&Path::new(&dir).join("out.bin")).unwrap();
            p.allocate(1 << 20).unwrap();
            println!("writing");
            std::io::stdout().flush().unwrap();
            std::thread::sleep(std::time::Duration::from_secs(60));
            unreachable!("killed before");
        }
        let dir = tempfile::tempdir().unwrap();
        if !makes_unnamed(dir.path()) {
            assert!(named_only(), "{} has no O_TMPFILE", dir.path().display());
            return;
        }
        std::fs::write(dir.path().join(".hidden"), b"mine").unwrap();
        let before = listing(dir.path());
        let mut child = std::process::Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "tests::a_killed_writer_leaves_its_directory_as_it_was",
                "--nocapture",
            ])
            .env("BRDF_ATOMIC_KILLED_CHILD", dir.path())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // Wait until the child says it is writing, then kill it.
        let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        while !line.contains("writing") {
            line.clear();
            assert!(std::io::BufRead::read_line(&mut out, &mut line).unwrap() > 0);
        }
        child.kill().unwrap();
        let status = child.wait().unwrap();
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(status.signal(), Some(libc::SIGKILL), "killed mid-write");
        assert_eq!(listing(dir.path()), before);
    }

    fn listing(dir: &Path) -> Vec<(String, u64)> {
        let mut v: Vec<(String, u64)> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let len = e.metadata().unwrap().len();
                (e.file_name().to_string_lossy().into_owned(), len)
            })
            .collect();
        v.sort();
        v
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
