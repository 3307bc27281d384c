//! Files without a name (`O_TMPFILE`): made in a directory, written, and
//! given a name only when complete. A process killed before then leaves
//! nothing behind; the kernel frees the file with its last descriptor.

use std::fs::File;
use std::io;
use std::path::Path;

/// An unnamed file open for reading and writing in directory `dir`, with
/// the mode a new file gets (0666 less the umask); `None` where the kernel
/// or the file system cannot make one (the caller then names its file).
#[cfg(target_os = "linux")]
pub(crate) fn open_unnamed(dir: &Path) -> io::Result<Option<File>> {
    use std::os::unix::fs::OpenOptionsExt;
    match File::options()
        .read(true)
        .write(true)
        .custom_flags(libc::O_TMPFILE)
        .mode(0o666)
        .open(dir)
    {
        Ok(file) => Ok(Some(file)),
        // EOPNOTSUPP: a file system without unnamed files (NFS, FUSE, some
        // overlays); EISDIR: a kernel older than O_TMPFILE, which reads the
        // flag as O_DIRECTORY; ENOENT from a kernel or file system that
        // does not know it either. The named path then says what is wrong
        // with the directory itself, if anything is.
        Err(e)
            if matches!(
                e.raw_os_error(),
                Some(libc::EOPNOTSUPP | libc::EISDIR | libc::ENOENT | libc::EINVAL)
            ) =>
        {
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

#[cfg(not(target_os = "linux"))]
pub(crate) fn open_unnamed(_dir: &Path) -> io::Result<Option<File>> {
    Ok(None)
}

/// Give the unnamed `file` the name `to` (which must not exist). Through
/// `/proc/self/fd`, which any process may use for its own files; without
/// `/proc`, by the descriptor itself (`AT_EMPTY_PATH`, which needs
/// CAP_DAC_READ_SEARCH).
#[cfg(target_os = "linux")]
pub(crate) fn link(file: &File, to: &Path) -> io::Result<()> {
    use std::ffi::CString;
    use std::os::fd::AsRawFd;
    use std::os::unix::ffi::OsStrExt;
    let to = CString::new(to.as_os_str().as_bytes())
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "path contains a NUL byte"))?;
    let fd = file.as_raw_fd();
    let proc = CString::new(format!("/proc/self/fd/{fd}")).expect("no NUL in a number");
    // SAFETY: two valid NUL-terminated paths; linkat only reads them.
    let r = unsafe {
        libc::linkat(
            libc::AT_FDCWD,
            proc.as_ptr(),
            libc::AT_FDCWD,
            to.as_ptr(),
            libc::AT_SYMLINK_FOLLOW,
        )
    };
    if r == 0 {
        return Ok(());
    }
    let first = io::Error::last_os_error();
    if first.raw_os_error() != Some(libc::ENOENT) {
        return Err(first);
    }
    // SAFETY: a valid descriptor, an empty path and a NUL-terminated one.
    let r = unsafe {
        libc::linkat(
            fd,
            c"".as_ptr(),
            libc::AT_FDCWD,
            to.as_ptr(),
            libc::AT_EMPTY_PATH,
        )
    };
    if r == 0 { Ok(()) } else { Err(first) }
}

#[cfg(not(target_os = "linux"))]
pub(crate) fn link(_file: &File, _to: &Path) -> io::Result<()> {
    Err(io::Error::new(
        io::ErrorKind::Unsupported,
        "unnamed files need Linux",
    ))
}

/// A file that lives in memory only (`memfd_create`): it has no name in
/// any directory, is never written back to a disk, and is freed with its
/// last descriptor, so a process killed while it holds one leaves nothing.
/// `name` shows in `/proc/PID/fd` only. `None` where the kernel has no
/// such files.
#[cfg(target_os = "linux")]
pub(crate) fn open_in_memory(name: &str) -> io::Result<Option<File>> {
    use std::ffi::CString;
    use std::os::fd::FromRawFd;
    let name = CString::new(name.replace('\0', "?")).expect("NUL bytes replaced");
    // SAFETY: a valid NUL-terminated name; the flags are plain integers.
    let fd = unsafe { libc::memfd_create(name.as_ptr(), libc::MFD_CLOEXEC) };
    if fd < 0 {
        let e = io::Error::last_os_error();
        return match e.raw_os_error() {
            Some(libc::ENOSYS | libc::EINVAL) => Ok(None),
            _ => Err(e),
        };
    }
    // SAFETY: a new descriptor that nothing else owns.
    Ok(Some(unsafe { File::from_raw_fd(fd) }))
}

#[cfg(not(target_os = "linux"))]
pub(crate) fn open_in_memory(_name: &str) -> io::Result<Option<File>> {
    Ok(None)
}

/// The memory available for new work (`MemAvailable` of `/proc/meminfo`),
/// bytes; `None` where it is not known.
#[cfg(target_os = "linux")]
pub(crate) fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

#[cfg(not(target_os = "linux"))]
pub(crate) fn available_memory() -> Option<u64> {
    None
}
