//! MERL `.binary` files: a 12-byte header of three little-endian int32 dims
//! `(n_theta_h, n_theta_d, n_phi_d)`, then `3 * bins` little-endian doubles,
//! the red block, then green, then blue, each indexed `[theta_h][theta_d][phi_d]`.
//!
//! Values are stored in MERL's raw units; [`physical`] applies the per-channel
//! scales (1/1500, 1.15/1500, 1.66/1500), and is the only place that does.
//! Negative values mark samples that were not measured.

use std::io::Write;
use std::path::{Path, PathBuf};

use brdf_mapguard::{GuardedMap, Watch};

use crate::angles::{Dims, MAX_DIM, Vec3};
use crate::error::{MerlError, Result};
pub use crate::values::{
    CHANNELS, MAX_REFLECTANCE, SCALE, is_invalid, is_non_finite, is_suspect, physical,
    raw_from_physical,
};
use crate::values::{first_out_of_range, scan_values};
use brdf_atomic::{PendingFile, commit_all, stage};
use rayon::prelude::*;

/// Bytes of the header.
pub const HEADER_BYTES: usize = 12;

/// The value MERL writes where a sample was not measured.
pub const INVALID: f64 = -1.0;

/// Does `bytes` start like a Git LFS pointer file (the small text file a
/// repository holds in place of a large file until `git lfs pull` fetches it)?
pub fn is_lfs_pointer(bytes: &[u8]) -> bool {
    bytes.starts_with(b"version https://git-lfs")
}

/// A validated MERL file, memory-mapped: nothing is copied until asked.
///
/// If another program truncates or rewrites the file while it is mapped,
/// reads return zeros instead of killing the process, and
/// [`MerlFile::verify`] reports the change: a reader checks it before it
/// trusts what it read.
pub struct MerlFile {
    path: PathBuf,
    dims: Dims,
    map: GuardedMap,
    invalid: std::sync::OnceLock<[usize; 3]>,
}

impl std::fmt::Debug for MerlFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MerlFile")
            .field("path", &self.path)
            .field("dims", &self.dims)
            .finish()
    }
}

impl MerlFile {
    /// Map and validate a MERL file: header, size, finite values.
    pub fn open(path: impl AsRef<Path>) -> Result<MerlFile> {
        let path = path.as_ref().to_path_buf();
        let map = GuardedMap::open(&path, Watch::Path).map_err(|e| MerlError::io(&path, e))?;
        let dims = check_header(&path, &map, map.len() as u64)?;
        let scanned = scan_values(&path, dims, &map[HEADER_BYTES..]);
        let file = MerlFile {
            path,
            dims,
            map,
            invalid: std::sync::OnceLock::new(),
        };
        // A value error read from a file that changed meanwhile is the change.
        file.verify()?;
        let _ = file.invalid.set(scanned?);
        Ok(file)
    }

    /// Map a MERL file and check its header and size only: for a reader that
    /// streams every value anyway and checks each run with
    /// [`MerlFile::check_values`] (a fit's store pass), which saves a whole
    /// pass over the data.
    pub fn map(path: impl AsRef<Path>) -> Result<MerlFile> {
        let path = path.as_ref().to_path_buf();
        let map = GuardedMap::open(&path, Watch::Path).map_err(|e| MerlError::io(&path, e))?;
        let dims = check_header(&path, &map, map.len() as u64)?;
        let file = MerlFile {
            path,
            dims,
            map,
            invalid: std::sync::OnceLock::new(),
        };
        file.verify()?;
        Ok(file)
    }

    /// `Ok` if the file is as it was when mapped; otherwise the error
    /// saying it changed while being read (truncated, so that reads past
    /// its new end gave zeros, or rewritten in place). Once changed,
    /// always changed. One `stat` of the path.
    pub fn verify(&self) -> Result<()> {
        if self.map.changed() {
            return Err(MerlError::Changed {
                path: self.path.clone(),
            });
        }
        Ok(())
    }

    /// Check that raw values `start .. start + values.len()` (as read by
    /// [`MerlFile::copy_raw`]) are finite and within [`MAX_REFLECTANCE`];
    /// the error names the first one that is not, as [`MerlFile::open`]
    /// would.
    pub fn check_values(&self, start: usize, values: &[f64]) -> Result<()> {
        let suspect = values.iter().fold(0u64, |a, v| a | is_suspect(*v) as u64);
        if suspect == 0 {
            return Ok(());
        }
        match first_out_of_range(&self.path, self.dims, start, values.iter().copied()) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The file this was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Which file it was, its size and last modification, when it was mapped.
    pub fn stamp(&self) -> brdf_mapguard::Stamp {
        self.map.stamp()
    }

    /// Table dims from the header.
    pub fn dims(&self) -> Dims {
        self.dims
    }

    /// Count of unmeasured (negative) values, per channel.
    pub fn invalid_counts(&self) -> [usize; 3] {
        *self.invalid.get_or_init(|| {
            let bins = self.dims.bins();
            std::array::from_fn(|c| {
                let mut run = vec![0.0; bins];
                self.copy_raw(c * bins, &mut run);
                run.iter().filter(|v| is_invalid(**v)).count()
            })
        })
    }

    /// Raw value at flat index `i` (channel-major: `channel * bins + bin`).
    #[inline]
    pub fn raw(&self, i: usize) -> f64 {
        let o = HEADER_BYTES + 8 * i;
        f64::from_le_bytes(self.map[o..o + 8].try_into().expect("8 bytes"))
    }

    /// Copy raw values `start .. start + out.len()` into `out`.
    pub fn copy_raw(&self, start: usize, out: &mut [f64]) {
        let bytes = &self.map[HEADER_BYTES + 8 * start..HEADER_BYTES + 8 * (start + out.len())];
        for (o, b) in out.iter_mut().zip(bytes.chunks_exact(8)) {
            *o = f64::from_le_bytes(b.try_into().expect("8 bytes"));
        }
    }

    /// Copy the whole table to memory.
    pub fn to_table(&self) -> MerlTable {
        let mut values = vec![0.0; self.dims.values()];
        self.copy_raw(0, &mut values);
        MerlTable {
            dims: self.dims,
            values,
        }
    }
}

fn check_header(path: &Path, bytes: &[u8], len: u64) -> Result<Dims> {
    if is_lfs_pointer(bytes) {
        return Err(MerlError::LfsPointer {
            path: path.to_path_buf(),
        });
    }
    // Something else altogether (text, an image): say so first.
    let named = |e: MerlError| match crate::sniff::looks_like(bytes) {
        Some(looks_like) => MerlError::NotMerl {
            path: path.to_path_buf(),
            looks_like,
            detail: e
                .to_string()
                .strip_prefix(&format!("{}: ", path.display()))
                .unwrap_or_default()
                .to_string(),
        },
        None => e,
    };
    if len < HEADER_BYTES as u64 {
        return Err(named(MerlError::TooShort {
            path: path.to_path_buf(),
            len,
        }));
    }
    let dim = |k: usize| i32::from_le_bytes(bytes[4 * k..4 * k + 4].try_into().expect("4 bytes"));
    let (a, b, c) = (dim(0), dim(1), dim(2));
    let max = MAX_DIM as i32;
    if !(1..=max).contains(&a) || !(1..=max).contains(&b) || !(1..=max).contains(&c) {
        return Err(named(MerlError::BadDims {
            path: path.to_path_buf(),
            a,
            b,
            c,
            max,
        }));
    }
    let dims = Dims {
        theta_h: a as usize,
        theta_d: b as usize,
        phi_d: c as usize,
    };
    let expected = (HEADER_BYTES + 8 * dims.values()) as u64;
    if len != expected {
        return Err(MerlError::SizeMismatch {
            path: path.to_path_buf(),
            dims: dims.to_string(),
            expected,
            actual: len,
        });
    }
    Ok(dims)
}

/// A MERL table in memory, values in raw file units.
#[derive(Debug, Clone, PartialEq)]
pub struct MerlTable {
    dims: Dims,
    values: Vec<f64>,
}

/// Summary of one channel over its measured values, in reflectance units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelStats {
    /// Smallest measured value.
    pub min: f64,
    /// Largest measured value.
    pub max: f64,
    /// Mean over the measured bins.
    pub mean: f64,
    /// Unmeasured bins.
    pub invalid: usize,
}

impl MerlTable {
    /// A table from raw values (channel-major, `3 * dims.bins()` long).
    pub fn from_raw(dims: Dims, values: Vec<f64>) -> Result<MerlTable> {
        if values.len() != dims.values() {
            return Err(MerlError::BufferLength {
                what: "MERL table".into(),
                dims: dims.to_string(),
                expected: dims.values(),
                actual: values.len(),
            });
        }
        Ok(MerlTable { dims, values })
    }

    /// A table filled from reflectance values by `f(bin) -> Some([r, g, b])`,
    /// `None` for unmeasured bins.
    pub fn from_fn(dims: Dims, mut f: impl FnMut(usize) -> Option<[f64; 3]>) -> MerlTable {
        let n = dims.bins();
        let mut values = vec![0.0; dims.values()];
        for bin in 0..n {
            match f(bin) {
                Some(rgb) => {
                    (0..3).for_each(|c| values[c * n + bin] = raw_from_physical(c, rgb[c]))
                }
                None => (0..3).for_each(|c| values[c * n + bin] = INVALID),
            }
        }
        MerlTable { dims, values }
    }

    /// Read and validate a MERL file.
    pub fn read(path: impl AsRef<Path>) -> Result<MerlTable> {
        Ok(MerlFile::open(path)?.to_table())
    }

    /// Validate and copy the bytes of a whole MERL file already in memory,
    /// with the checks of [`MerlFile::open`]; `path` only names it in errors.
    pub fn from_bytes(path: impl AsRef<Path>, bytes: &[u8]) -> Result<MerlTable> {
        let path = path.as_ref();
        let dims = check_header(path, bytes, bytes.len() as u64)?;
        let data = &bytes[HEADER_BYTES..];
        scan_values(path, dims, data)?;
        let values = data
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
            .collect();
        Ok(MerlTable { dims, values })
    }

    /// Write in the MERL layout, atomically (temp file + rename).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.stage(path)?
            .commit(true)
            .map_err(|e| MerlError::io(path, e))
    }

    /// Write in the MERL layout under a temporary name beside `path`; the
    /// file takes its place on [`PendingFile::commit`] (see
    /// [`brdf_atomic::commit_all`] for several files at once) and is
    /// removed if dropped uncommitted.
    pub fn stage(&self, path: impl AsRef<Path>) -> Result<PendingFile> {
        let path = path.as_ref();
        stage(path, |w| {
            for d in [self.dims.theta_h, self.dims.theta_d, self.dims.phi_d] {
                w.write_all(&(d as i32).to_le_bytes())?;
            }
            let mut buf = Vec::with_capacity(8 * 4096);
            for chunk in self.values.chunks(4096) {
                buf.clear();
                chunk
                    .iter()
                    .for_each(|v| buf.extend_from_slice(&v.to_le_bytes()));
                w.write_all(&buf)?;
            }
            Ok(())
        })
        .map_err(|e| MerlError::io(path, e))
    }

    /// Table dims.
    pub fn dims(&self) -> Dims {
        self.dims
    }

    /// All raw values, channel-major.
    pub fn raw(&self) -> &[f64] {
        &self.values
    }

    /// Mutable raw values, channel-major.
    pub fn raw_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Reflectance of `channel` at `bin`, or `None` where it was not measured.
    #[inline]
    pub fn value(&self, channel: usize, bin: usize) -> Option<f64> {
        let raw = self.values[channel * self.dims.bins() + bin];
        (!is_invalid(raw)).then(|| physical(channel, raw))
    }

    /// Reflectance at `bin`, unmeasured channels read as 0 (for integrals).
    #[inline]
    pub fn rgb_or_zero(&self, bin: usize) -> [f64; 3] {
        [0, 1, 2].map(|c| self.value(c, bin).unwrap_or(0.0))
    }

    /// Evaluate at a pair of directions by nearest-bin lookup, as MERL's
    /// reference code does. `None` below the horizon or where the bin was not
    /// measured in some channel.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Option<[f64; 3]> {
        let bin = self.dims.bin_of_directions(wi, wo)?;
        Some([
            self.value(0, bin)?,
            self.value(1, bin)?,
            self.value(2, bin)?,
        ])
    }

    /// Number of unmeasured values over all channels.
    pub fn invalid_count(&self) -> usize {
        self.values.iter().filter(|v| is_invalid(**v)).count()
    }

    /// Min, max, mean and unmeasured count of each channel, in reflectance units.
    pub fn channel_stats(&self) -> [ChannelStats; 3] {
        let n = self.dims.bins();
        [0, 1, 2].map(|c| {
            let (mut min, mut max, mut sum, mut count) =
                (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
            for &raw in &self.values[c * n..(c + 1) * n] {
                if !is_invalid(raw) {
                    let v = physical(c, raw);
                    min = min.min(v);
                    max = max.max(v);
                    sum += v;
                    count += 1;
                }
            }
            let mean = if count > 0 {
                sum / count as f64
            } else {
                f64::NAN
            };
            ChannelStats {
                min,
                max,
                mean,
                invalid: n - count,
            }
        })
    }
}

/// Write `NAME.binary` into `dir` (created if missing) for each of
/// `items`, tabulated in parallel, all or none: every file is staged
/// first and all go in together ([`commit_all`]). The paths, in `items`'
/// order.
pub(crate) fn write_named<M: Sync>(
    dir: &Path,
    items: &[M],
    name: impl Fn(&M) -> &str + Sync,
    table: impl Fn(&M) -> MerlTable + Sync,
) -> Result<Vec<PathBuf>> {
    brdf_atomic::create_dir_all_owned(dir).map_err(|e| MerlError::io(dir, e))?;
    let staged = items
        .par_iter()
        .map(|m| table(m).stage(dir.join(format!("{}.binary", name(m)))))
        .collect::<Result<Vec<PendingFile>>>()?;
    let paths = staged.iter().map(|f| f.target().to_path_buf()).collect();
    commit_all(staged).map_err(|(path, e)| MerlError::io(path, e))?;
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> MerlTable {
        let dims = Dims::new(4, 3, 6).unwrap();
        MerlTable::from_fn(dims, |b| {
            if b % 7 == 3 {
                None
            } else {
                Some([b as f64 * 0.01, 0.5, 1.0 + b as f64])
            }
        })
    }

    #[test]
    fn round_trip_is_byte_identical() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.binary");
        let b = dir.path().join("b.binary");
        let t = small();
        t.write(&a).unwrap();
        let back = MerlTable::read(&a).unwrap();
        assert_eq!(back, t);
        back.write(&b).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let bytes = std::fs::read(&a).unwrap();
        assert_eq!(bytes.len(), 12 + 8 * 3 * 72);
        assert_eq!(&bytes[..12], &[4, 0, 0, 0, 3, 0, 0, 0, 6, 0, 0, 0]);
    }

    #[test]
    fn scales_apply_once_and_invalid_reads_as_none() {
        let t = small();
        let n = t.dims().bins();
        assert_eq!(t.raw()[5], 0.05 * 1500.0);
        assert!((t.value(0, 5).unwrap() - 0.05).abs() < 1e-15);
        assert!((t.value(1, 5).unwrap() - 0.5).abs() < 1e-15);
        assert!((t.raw()[n + 5] - 0.5 * 1500.0 / 1.15).abs() < 1e-9);
        assert_eq!(t.value(2, 3), None);
        assert_eq!(t.invalid_count(), 3 * (0..n).filter(|b| b % 7 == 3).count());
        let stats = t.channel_stats();
        assert_eq!(stats[1].min, 0.5);
        assert_eq!(stats[1].invalid, (0..n).filter(|b| b % 7 == 3).count());
    }

    fn write_bytes(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn header(a: i32, b: i32, c: i32) -> Vec<u8> {
        [a, b, c].iter().flat_map(|d| d.to_le_bytes()).collect()
    }

    #[test]
    fn hostile_files_get_named_errors() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let good = d.join("good.binary");
        small().write(&good).unwrap();
        let bytes = std::fs::read(&good).unwrap();

        let cases: Vec<(PathBuf, &str)> = vec![
            (write_bytes(d, "empty.binary", b""), "too short"),
            (
                write_bytes(d, "trunc.binary", &bytes[..bytes.len() - 5]),
                "but the file has",
            ),
            (
                write_bytes(
                    d,
                    "lfs.binary",
                    b"version https://git-lfs.github.com/spec/v1\noid sha256:ab\nsize 34992012\n",
                ),
                "Git LFS pointer",
            ),
            (
                write_bytes(d, "neg.binary", &header(-90, 90, 180)),
                "expected three positive dims",
            ),
            (
                write_bytes(d, "huge.binary", &header(90, 90, 1 << 30)),
                "expected three positive dims",
            ),
            (
                write_bytes(d, "zero.binary", &header(0, 90, 180)),
                "expected three positive dims",
            ),
            (
                write_bytes(d, "notes.binary", b"some notes\nabout materials\n"),
                "notes.binary: not a MERL file (it looks like text)",
            ),
            (
                write_bytes(d, "short.binary", "\u{e9}t\u{e9}\n".as_bytes()),
                "not a MERL file (it looks like text)",
            ),
            (
                write_bytes(d, "pic.binary", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"),
                "not a MERL file (it looks like a PNG image)",
            ),
            (
                write_bytes(d, "hdr-only.binary", &header(90, 90, 180)),
                "header says 90x90x180",
            ),
            (
                {
                    let mut b = bytes.clone();
                    let o = 12 + 8 * (72 + 10);
                    b[o..o + 8].copy_from_slice(&f64::NAN.to_le_bytes());
                    write_bytes(d, "nan.binary", &b)
                },
                "green channel, bin 10) is NaN",
            ),
            (
                {
                    let mut b = bytes.clone();
                    b[12..20].copy_from_slice(&f64::INFINITY.to_le_bytes());
                    write_bytes(d, "inf.binary", &b)
                },
                "is inf",
            ),
            (
                {
                    let mut b = bytes.clone();
                    let o = 12 + 8 * (2 * 72 + 13);
                    b[o..o + 8].copy_from_slice(&1e300f64.to_le_bytes());
                    write_bytes(d, "absurd.binary", &b)
                },
                "value 157 (blue channel, bin theta_h 0 theta_d 2 phi_d 1) is a \
                 reflectance of 1.107e297 per steradian, beyond any physical one; \
                 expected at most 1e8",
            ),
        ];
        for (path, want) in cases {
            let err = MerlFile::open(&path).unwrap_err().to_string();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            assert!(err.contains(&name), "{err}");
            assert!(err.contains(want), "{name}: {err}");
            assert!(!err.contains('\n'), "one line: {err}");
            // Mapped without the scan, the same values checked in runs (as a
            // fit's store pass does) give the same message, or the header's.
            let lazy = match MerlFile::map(&path) {
                Err(e) => e.to_string(),
                Ok(f) => {
                    let mut run = [0.0; 7];
                    (0..f.dims().values())
                        .step_by(7)
                        .find_map(|start| {
                            let run = &mut run[..7.min(f.dims().values() - start)];
                            f.copy_raw(start, run);
                            f.check_values(start, run).err()
                        })
                        .expect("an error")
                        .to_string()
                }
            };
            assert_eq!(lazy, err);
        }
        let missing = MerlFile::open(d.join("missing.binary"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("missing.binary"), "{missing}");
    }

    #[test]
    fn the_reflectance_limit_is_per_channel() {
        // Raw 1e11 is 6.7e7 per steradian in red (accepted) but 1.1e8 in
        // blue (refused): the cheap raw test flags both, the exact one
        // keeps the red.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bright.binary");
        let mut t = small();
        let bins = t.dims().bins();
        t.raw_mut()[3] = 1e11;
        t.write(&p).unwrap();
        let f = MerlFile::open(&p).unwrap();
        assert_eq!(f.raw(3), 1e11);
        assert!(physical(0, 1e11) < MAX_REFLECTANCE && is_suspect(1e11));
        let lazy = MerlFile::map(&p).unwrap();
        assert!(lazy.check_values(0, &t.raw()[..bins]).is_ok());
        t.raw_mut()[2 * bins + 3] = 1e11;
        t.write(&p).unwrap();
        let err = MerlFile::open(&p).unwrap_err().to_string();
        assert!(
            err.contains("blue channel") && err.contains("1.107e8"),
            "{err}"
        );
        assert!(
            err.contains("bright.binary") && !err.contains('\n'),
            "{err}"
        );
    }

    #[test]
    fn file_view_matches_table() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.binary");
        let t = small();
        t.write(&p).unwrap();
        let f = MerlFile::open(&p).unwrap();
        let lazy = MerlFile::map(&p).unwrap();
        assert_eq!(lazy.invalid_counts(), f.invalid_counts());
        assert_eq!(f.dims(), t.dims());
        let mut buf = vec![0.0; 10];
        f.copy_raw(50, &mut buf);
        assert_eq!(&buf[..], &t.raw()[50..60]);
        assert_eq!(f.raw(100), t.raw()[100]);
        let n = t.dims().bins();
        assert_eq!(f.invalid_counts().iter().sum::<usize>(), t.invalid_count());
        assert_eq!(f.invalid_counts()[0], (0..n).filter(|b| b % 7 == 3).count());
    }

    #[test]
    fn eval_looks_up_the_bin_of_the_directions() {
        let t = small();
        let dims = t.dims();
        let wi = crate::angles::direction(0.4, 0.0);
        let wo = crate::angles::direction(0.5, 2.5);
        let bin = dims.bin_of_directions(wi, wo).unwrap();
        match t.eval(wi, wo) {
            Some(rgb) => assert_eq!(rgb, t.rgb_or_zero(bin)),
            None => assert!(t.value(0, bin).is_none()),
        }
        assert!(t.eval(wi, [0.0, 0.0, -1.0]).is_none());
    }
}
