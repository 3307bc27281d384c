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
