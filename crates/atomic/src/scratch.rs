//! Scratch files: work a run throws away, with no name in any directory.

use std::fs::File;
use std::io;
use std::path::Path;

use crate::cleanup::{create_temp, forget};
use crate::open_new;
use crate::unnamed;

/// A scratch file of `len` bytes for work a run throws away (a report's
/// stores), gone with its last descriptor: held in memory
/// (`memfd_create`: never written back to the disk, and nothing left
/// behind by a killed run) where the kernel allows and `len` is at most a
/// quarter of the memory available (memory a file in it takes cannot be
/// reclaimed but to swap); else an unnamed file in `dir` (`O_TMPFILE`);
/// else a file in `dir` removed as soon as it is open. `name` labels it
/// (in `/proc/PID/fd` only).
pub fn scratch_file(dir: &Path, name: &str, len: u64) -> io::Result<File> {
    let fits = unnamed::available_memory().is_some_and(|a| len <= a / 4);
    scratch(dir, name, len, fits)
}

/// [`scratch_file`], in memory only if `in_memory`.
fn scratch(dir: &Path, name: &str, len: u64, in_memory: bool) -> io::Result<File> {
    if in_memory && let Some(file) = unnamed::open_in_memory(name)? {
        file.set_len(len)?;
        return Ok(file);
    }
    let file = match unnamed::open_unnamed(dir)? {
        Some(file) => file,
        None => {
            let (tmp, file) = create_temp(&dir.join(name), open_new)?;
            std::fs::remove_file(&tmp)?;
            forget(&tmp);
            file
        }
    };
    file.set_len(len)?;
    Ok(file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scratch_files_hold_what_is_written_and_have_no_name() {
        use std::os::unix::fs::FileExt;
        let dir = tempfile::tempdir().unwrap();
        for in_memory in [true, false] {
            let f = scratch(dir.path(), "work.store", 1 << 20, in_memory).unwrap();
            assert_eq!(f.metadata().unwrap().len(), 1 << 20);
            f.write_all_at(b"scratch", 1000).unwrap();
            let mut back = [0u8; 7];
            f.try_clone()
                .unwrap()
                .read_exact_at(&mut back, 1000)
                .unwrap();
            assert_eq!(&back, b"scratch");
            // Nothing in the directory, hidden files included.
            assert_eq!(
                std::fs::read_dir(dir.path()).unwrap().count(),
                0,
                "{in_memory}"
            );
        }
    }
}
