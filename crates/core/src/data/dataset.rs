//! The input of a fit: a directory of MERL files, opened and checked.

use std::path::{Path, PathBuf};

use brdf_merl::{Dims, MerlFile};
use rayon::prelude::*;

use crate::error::{CoreError, Result};

/// A directory of MERL files, validated and sorted by name.
pub struct Dataset {
    /// The directory.
    pub dir: PathBuf,
    /// Material names (file stems), sorted.
    pub names: Vec<String>,
    /// The mapped files, in the order of `names`.
    pub files: Vec<MerlFile>,
    /// Entries that were not used, with the reason (not a `.binary` file).
    pub ignored: Vec<(PathBuf, String)>,
}

impl Dataset {
    /// Open every `*.binary` file of `dir` (sorted by name). Any invalid MERL
    /// file is an error naming it; other entries are listed in `ignored`.
    pub fn open_dir(dir: impl AsRef<Path>) -> Result<Dataset> {
        Self::list_dir(dir.as_ref(), |p| MerlFile::open(p))
    }

    /// Like [`Dataset::open_dir`], but the files' values are not scanned:
    /// [`build_store`] checks every value as it streams them, which saves a
    /// pass over the data (the error is the same, found later).
    pub fn map_dir(dir: impl AsRef<Path>) -> Result<Dataset> {
        Self::list_dir(dir.as_ref(), |p| MerlFile::map(p))
    }

    fn list_dir(
        dir: &Path,
        open: impl Fn(&PathBuf) -> brdf_merl::Result<MerlFile> + Sync + Send,
    ) -> Result<Dataset> {
        let dir = dir.to_path_buf();
        let mut paths = Vec::new();
        let mut ignored = Vec::new();
        for entry in std::fs::read_dir(&dir).map_err(|e| CoreError::io(&dir, e))? {
            let path = entry.map_err(|e| CoreError::io(&dir, e))?.path();
            // Every `.binary` entry but a directory is a MERL file to open:
            // one that is not a regular file (a named pipe, a device) is
            // refused by name, as any other invalid file is.
            if path.extension().is_some_and(|e| e == "binary") && !path.is_dir() {
                paths.push(path);
            } else {
                let why = if path.is_dir() {
                    "a directory"
                } else {
                    "not a .binary file"
                };
                ignored.push((path, why.to_string()));
            }
        }
        if paths.is_empty() {
            return Err(CoreError::EmptyDataset { path: dir });
        }
        paths.sort();
        ignored.sort();
        let files = paths.par_iter().map(&open).collect::<Result<Vec<_>, _>>()?;
        Self::from_files(dir, files, ignored)
    }

    /// A dataset from already opened files (kept in the given order).
    pub fn from_files(
        dir: PathBuf,
        files: Vec<MerlFile>,
        ignored: Vec<(PathBuf, String)>,
    ) -> Result<Dataset> {
        let first = files
            .first()
            .ok_or_else(|| CoreError::EmptyDataset { path: dir.clone() })?;
        for f in &files {
            if f.dims() != first.dims() {
                return Err(CoreError::DimsDiffer {
                    path: f.path().to_path_buf(),
                    found: f.dims().to_string(),
                    first: first.path().display().to_string(),
                    expected: first.dims().to_string(),
                });
            }
        }
        let names = files
            .iter()
            .map(|f| {
                f.path()
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            })
            .collect();
        Ok(Dataset {
            dir,
            names,
            files,
            ignored,
        })
    }

    /// Table dims shared by all materials.
    pub fn dims(&self) -> Dims {
        self.files[0].dims()
    }

    /// Number of materials.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// True when there is no material (never, once opened).
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::data::{Precision, TransformKind, build_store, synth_dir};
    use crate::progress::NoProgress;
    use brdf_merl::synth;

    #[test]
    fn mixed_dims_and_bad_files_are_named() {
        let tmp = tempfile::tempdir().unwrap();
        synth_dir(tmp.path(), 2, Dims::new(4, 4, 8).unwrap());
        let odd = synth::database(3, 5).pop().unwrap();
        odd.brdf
            .table(Dims::new(4, 4, 6).unwrap())
            .write(tmp.path().join("zz.binary"))
            .unwrap();
        let e = Dataset::open_dir(tmp.path()).err().unwrap().to_string();
        assert!(e.contains("zz.binary") && e.contains("4x4x6"), "{e}");
        std::fs::write(
            tmp.path().join("zz.binary"),
            b"version https://git-lfs.github.com/spec/v1\n",
        )
        .unwrap();
        let e = Dataset::open_dir(tmp.path()).err().unwrap().to_string();
        assert!(e.contains("zz.binary") && e.contains("LFS"), "{e}");
        // Non-finite values found by the store pass (not by a scan on
        // opening): the first in file order is named, as a scan would.
        let dims = Dims::new(8, 8, 16).unwrap();
        let bad = tempfile::tempdir().unwrap();
        synth_dir(bad.path(), 5, dims);
        let mut names: Vec<_> = std::fs::read_dir(bad.path())
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        names.sort();
        for (path, index) in [(&names[3], 3 * dims.bins() - 1), (&names[1], 5)] {
            let mut bytes = std::fs::read(path).unwrap();
            let o = 12 + 8 * index;
            bytes[o..o + 8].copy_from_slice(&f64::NAN.to_le_bytes());
            std::fs::write(path, bytes).unwrap();
        }
        let want = MerlFile::open(&names[1]).err().unwrap().to_string();
        assert!(Dataset::open_dir(bad.path()).is_err());
        let data = Dataset::map_dir(bad.path()).unwrap();
        let out = bad.path().join("s.store");
        let e = build_store(&data, TransformKind::Log, Precision::F32, &out, &NoProgress)
            .err()
            .unwrap()
            .to_string();
        assert_eq!(e, want);
        assert!(!out.exists());
        let empty = tempfile::tempdir().unwrap();
        assert!(
            Dataset::open_dir(empty.path())
                .err()
                .unwrap()
                .to_string()
                .contains("no .binary")
        );
    }
}
