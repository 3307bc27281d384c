//! The process's temporaries: every temporary name this crate hands out is
//! registered here, so an interrupted run can remove them all
//! ([`remove_temporaries`]), and the first write into a directory removes
//! the temporaries that a killed run left there ([`sweep`]).
//!
//! Two locks, always taken in this order: the commit lock ([`critical`]),
//! held while outputs take their places, and the registry. The interrupt
//! path takes both and never gives them back, so once it has started no
//! output is put in place and no temporary is created.

use std::cell::Cell;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

static COUNTER: AtomicU64 = AtomicU64::new(0);
static COMMITTED: AtomicBool = AtomicBool::new(false);
static COMMIT: Mutex<()> = Mutex::new(());
static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    paths: Vec::new(),
    swept: Vec::new(),
    made_dirs: Vec::new(),
    closed: false,
});

thread_local! {
    static DEPTH: Cell<usize> = const { Cell::new(0) };
}

struct Registry {
    /// Temporary names handed out and not yet known to be gone.
    paths: Vec<PathBuf>,
    /// Directories already swept by this process: a few, so a list (whose
    /// allocations a leak checker sees as reachable from the static, unlike
    /// a hash table's, which point into the middle of their blocks).
    swept: Vec<PathBuf>,
    /// Directories [`create_dir_all_owned`] made, outermost first.
    made_dirs: Vec<PathBuf>,
    /// Set by [`remove_temporaries`]: no new temporary after that.
    closed: bool,
}

fn registry() -> MutexGuard<'static, Registry> {
    // The registry holds no invariant a panic could break halfway.
    REGISTRY.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The marker between a target's name and the owner of a temporary.
const MARK: &str = ".tmp-";

fn name_for(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}{MARK}{}-{n}", std::process::id()))
}

fn interrupted() -> io::Error {
    io::Error::new(io::ErrorKind::Interrupted, "interrupted")
}

/// A fresh temporary name beside `path`, registered, after sweeping its
/// directory; `create` makes the file or directory under the registry lock,
/// so the interrupt path sees every temporary that exists.
pub(crate) fn create_temp<T>(
    path: &Path,
    create: impl FnOnce(&Path) -> io::Result<T>,
) -> io::Result<(PathBuf, T)> {
    let mut reg = registry();
    if reg.closed {
        return Err(interrupted());
    }
    sweep_locked(&mut reg, path);
    let tmp = name_for(path);
    let made = create(&tmp)?;
    reg.paths.push(tmp.clone());
    Ok((tmp, made))
}

/// Run `open` on `path`'s directory to make an unnamed temporary there
/// (`O_TMPFILE`), after sweeping the directory as [`create_temp`] does, and
/// unless an interrupt has closed the registry. Nothing is registered: an
/// unnamed file needs no removal, it goes with its last descriptor.
pub(crate) fn create_unnamed<T>(
    path: &Path,
    open: impl FnOnce(&Path) -> io::Result<Option<T>>,
) -> io::Result<Option<T>> {
    let mut reg = registry();
    if reg.closed {
        return Err(interrupted());
    }
    sweep_locked(&mut reg, path);
    open(&dir_of(path))
}

fn dir_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// A temporary path in the same directory as `path` (so the final rename
/// never crosses file systems), unique within this process and registered
/// for removal on an interrupt ([`remove_temporaries`]). Named
/// `.{name}.tmp-{pid}-{n}`; a later run removes it once this process is
/// gone ([`sweep`]).
pub fn temp_path_for(path: &Path) -> PathBuf {
    let mut reg = registry();
    sweep_locked(&mut reg, path);
    let tmp = name_for(path);
    reg.paths.push(tmp.clone());
    tmp
}

/// Forget a temporary that was renamed away or removed.
pub(crate) fn forget(tmp: &Path) {
    let mut reg = registry();
    if let Some(i) = reg.paths.iter().rposition(|p| p == tmp) {
        reg.paths.swap_remove(i);
    }
}

/// Run `f` (which puts outputs in place) so that an interrupt waits for it:
/// a set of renames inside one call happens whole or not at all. Calls nest.
pub fn critical<T>(f: impl FnOnce() -> T) -> T {
    let outer = DEPTH.with(|d| d.get()) == 0;
    let guard = outer.then(|| COMMIT.lock().unwrap_or_else(PoisonError::into_inner));
    DEPTH.with(|d| d.set(d.get() + 1));
    let out = f();
    DEPTH.with(|d| d.set(d.get() - 1));
    drop(guard);
    out
}

/// Note that an output took its place at `target` ([`committed`]), unless
/// `target` is itself a temporary or inside one (a file of a report's
/// temporary directory).
pub(crate) fn mark_committed(target: &Path) {
    if !registry().paths.iter().any(|t| target.starts_with(t)) {
        COMMITTED.store(true, Ordering::Relaxed);
    }
}

/// True when this process has put at least one output in place: after an
/// interrupt, the outputs are then the new ones, not the old.
pub fn committed() -> bool {
    COMMITTED.load(Ordering::Relaxed)
}

/// For an interrupt (SIGINT, SIGTERM): wait for any output being put in
/// place ([`critical`]), then remove every temporary of this process.
/// Returns with both locks held for good, so no output is put in place and
/// no temporary is created afterwards: the caller's next step is to exit.
///
/// Not for a signal handler (it locks and allocates): call it from an
/// ordinary thread that waits for the signal.
pub fn remove_temporaries() {
    std::mem::forget(COMMIT.lock().unwrap_or_else(PoisonError::into_inner));
    let mut reg = registry();
    reg.closed = true;
    for p in std::mem::take(&mut reg.paths) {
        remove_any(&p);
    }
    // Innermost first; a directory that holds anything (an output put in
    // place, a file of someone else's) stays.
    for d in std::mem::take(&mut reg.made_dirs).iter().rev() {
        let _ = std::fs::remove_dir(d);
    }
    std::mem::forget(reg);
}

/// Create `dir` and its missing parents, as [`std::fs::create_dir_all`]
/// does, and remember the ones this call made: an interrupt
/// ([`remove_temporaries`]) removes each of them that is empty by then, so
/// a run stopped before its outputs went in leaves no new, empty directory
/// behind. A directory that existed already is never removed.
pub fn create_dir_all_owned(dir: &Path) -> io::Result<()> {
    let mut missing = Vec::new();
    let mut at = Some(dir);
    while let Some(d) = at {
        if d.as_os_str().is_empty() || d.is_dir() {
            break;
        }
        missing.push(d.to_path_buf());
        at = d.parent();
    }
    let mut reg = registry();
    if reg.closed {
        return Err(interrupted());
    }
    for d in missing.into_iter().rev() {
        match std::fs::create_dir(&d) {
            Ok(()) => reg.made_dirs.push(d),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && d.is_dir() => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

fn remove_any(p: &Path) {
    match std::fs::symlink_metadata(p) {
        Ok(m) if m.is_dir() => {
            let _ = std::fs::remove_dir_all(p);
        }
        Ok(_) => {
            let _ = std::fs::remove_file(p);
        }
        Err(_) => {}
    }
}

/// Remove, from the directory `path` is in, the temporaries that earlier
/// processes left there: names `.{name}.tmp-{pid}-{n}` whose process is gone
/// (or is this one, under a reused pid, without having made them). Done
/// once a directory per process, by the first temporary made there; best
/// effort, an unreadable directory is left alone.
pub fn sweep(path: &Path) {
    sweep_locked(&mut registry(), path);
}

fn sweep_locked(reg: &mut Registry, path: &Path) {
    let dir = dir_of(path);
    if reg.swept.contains(&dir) {
        return;
    }
    reg.swept.push(dir.clone());
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return;
    };
    let me = std::process::id();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = owner(&name.to_string_lossy()) else {
            continue;
        };
        let p = entry.path();
        let stale = if pid == me {
            !reg.paths.contains(&p)
        } else {
            !alive(pid)
        };
        if stale {
            remove_any(&p);
        }
    }
}

/// The pid in a temporary's name `.{name}.tmp-{pid}-{n}`, if it is one.
fn owner(name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?;
    let (_, tail) = rest.rsplit_once(MARK)?;
    let (pid, n) = tail.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (digits(pid) && digits(n)).then(|| pid.parse().ok())?
}

/// Whether process `pid` exists (on this machine; a temporary on a shared
/// file system written by another machine's process looks stale).
fn alive(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else {
            return false;
        };
        if pid <= 0 {
            return false;
        }
        // SAFETY: signal 0 only checks that the process exists.
        if unsafe { libc::kill(pid, 0) } == 0 {
            return true;
        }
        io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owner_reads_the_pid_of_temporary_names_only() {
        assert_eq!(owner(".m.store.tmp-123-4"), Some(123));
        assert_eq!(owner("..m.store.tmp-1-2.tmp-77-0"), Some(77));
        assert_eq!(owner("m.store.tmp-123-4"), None);
        assert_eq!(owner(".m.tmp-12x-4"), None);
        assert_eq!(owner(".m.tmp-12-"), None);
        assert_eq!(owner(".notes.txt"), None);
    }

    #[test]
    #[cfg(unix)]
    fn sweep_removes_what_dead_processes_left_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        // A pid above the kernel's limit never exists.
        let dead = dir.path().join(".a.binary.tmp-2147483000-0");
        let dead_dir = dir.path().join(".report.tmp-2147483000-1");
        let live = dir.path().join(format!(
            ".a.binary.tmp-{}-0",
            std::os::unix::process::parent_id()
        ));
        let user = dir.path().join(".a.binary.tmp-keep");
        std::fs::write(&dead, b"x").unwrap();
        std::fs::create_dir(&dead_dir).unwrap();
        std::fs::write(dead_dir.join("f"), b"x").unwrap();
        std::fs::write(&live, b"x").unwrap();
        std::fs::write(&user, b"x").unwrap();
        let tmp = temp_path_for(&dir.path().join("a.binary"));
        assert!(!dead.exists() && !dead_dir.exists());
        assert!(live.exists() && user.exists());
        forget(&tmp);
    }
}
