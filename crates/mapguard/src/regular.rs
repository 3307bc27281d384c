//! Only regular files are read: a named pipe, a socket, a device or a
//! directory given where a file is expected is refused at once, by its
//! kind, before anything opens it in a way that could block (opening a
//! pipe for reading waits for a writer; reading a terminal waits for a
//! line).

use std::fs::{File, FileType};
use std::io::{self, Read};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

/// What a file of type `t` is, in words: "a named pipe", "a directory".
fn kind(t: FileType) -> &'static str {
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a named pipe"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else {
        "not a regular file"
    }
}

/// The error of a path that is not a regular file: "is a named pipe, not a
/// regular file" (the caller names the path).
fn refused(t: FileType) -> io::Error {
    let what = kind(t);
    let text = if what.starts_with("not ") {
        format!("is {what}")
    } else {
        format!("is {what}, not a regular file")
    };
    let error_kind = if t.is_dir() {
        io::ErrorKind::IsADirectory
    } else {
        io::ErrorKind::InvalidInput
    };
    io::Error::new(error_kind, text)
}

/// `Ok` when `path` (links followed) is a regular file; otherwise an error
/// saying what it is. Only `stat`s the path: nothing is opened.
pub fn regular_file(path: &Path) -> io::Result<()> {
    let t = std::fs::metadata(path)?.file_type();
    if t.is_file() { Ok(()) } else { Err(refused(t)) }
}

/// Open `path` for reading when it is a regular file ([`regular_file`]),
/// checked again on the open descriptor (the path may have been replaced
/// in between). The open does not block whatever the path has become
/// (`O_NONBLOCK`, which regular files ignore), nor makes a terminal the
/// process's (`O_NOCTTY`).
pub fn open_regular(path: &Path) -> io::Result<File> {
    regular_file(path)?;
    let file = File::options()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)?;
    let t = file.metadata()?.file_type();
    if t.is_file() {
        Ok(file)
    } else {
        Err(refused(t))
    }
}

/// The whole of the regular file `path` ([`open_regular`]).
pub fn read_regular(path: &Path) -> io::Result<Vec<u8>> {
    let mut file = open_regular(path)?;
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::net::UnixListener;
    use std::time::{Duration, Instant};

    fn mkfifo(path: &Path) {
        let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
        // SAFETY: a valid C string; mkfifo only creates the node.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    }

    #[test]
    fn every_kind_of_file_that_is_not_regular_is_refused_at_once() {
        let tmp = tempfile::tempdir().unwrap();
        let fifo = tmp.path().join("pipe.binary");
        mkfifo(&fifo);
        let socket = tmp.path().join("socket.binary");
        let _listener = UnixListener::bind(&socket).unwrap();
        let dir = tmp.path().join("dir.binary");
        std::fs::create_dir(&dir).unwrap();
        let device = tmp.path().join("null.binary");
        std::os::unix::fs::symlink("/dev/null", &device).unwrap();
        let regular = tmp.path().join("file.binary");
        std::fs::write(&regular, b"twelve bytes").unwrap();
        for (path, want) in [
            (&fifo, "is a named pipe, not a regular file"),
            (&socket, "is a socket, not a regular file"),
            (&dir, "is a directory, not a regular file"),
            (&device, "is a character device, not a regular file"),
        ] {
            // A reader of the pipe with no writer would wait forever: the
            // answer comes at once instead.
            let t = Instant::now();
            for e in [
                regular_file(path).unwrap_err(),
                open_regular(path).unwrap_err(),
                read_regular(path).unwrap_err(),
            ] {
                assert_eq!(e.to_string(), want, "{}", path.display());
            }
            assert!(t.elapsed() < Duration::from_secs(5));
        }
        assert_eq!(read_regular(&regular).unwrap(), b"twelve bytes");
        assert_eq!(
            regular_file(&tmp.path().join("missing"))
                .unwrap_err()
                .kind(),
            io::ErrorKind::NotFound
        );
    }
}
