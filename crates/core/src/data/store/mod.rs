//! The store: the transformed, centred data matrix `Z`, bin-major and
//! memory-mapped.
//!
//! `Z` has one row per table value (`d = 3 * bins` rows, channel-major like a
//! MERL file) and one column per material. Row `j` holds the `N` values of
//! value `j` for all materials, contiguous: a full reconstruction is one
//! streaming pass (`out_j = mean_j + w . Z_j`), a point query touches one
//! `N`-vector per value, and the Gram matrix `Y = Z Z^T = sum_j Z_j Z_j^T` is
//! a chunked matrix product. The store is the only copy of `Z`: it is built
//! by one pass over the input files, which also accumulates `Y`.
//!
//! File layout (little-endian):
//! ```text
//! 0   8  magic "BRDFSTOR"
//! 8   4  version (1)
//! 12  4  bytes per value (4 = f32, 8 = f64)
//! 16  4  N, materials
//! 20  4  transform (0 = raw, 1 = log)
//! 24 12  dims (theta_h, theta_d, phi_d)
//! 36 28  zero
//! 64     mean: d f64, the per-value mean in transformed space
//! ..     unmeasured: d bytes, 1 where no input material was measured
//! ..     zero padding to a multiple of 64
//! ..     Z: d rows of N values (f32 or f64)
//! ```
//!
//! The map is guarded ([`brdf_mapguard`]): if another program truncates or
//! rewrites the file while it is mapped, reads give zeros instead of
//! killing the process, and [`Store::verify`] reports the change. Every
//! operation that reads the store checks it before it returns a result.

use std::path::{Path, PathBuf};

use brdf_mapguard::{GuardedMap, Watch};
use brdf_merl::Dims;
use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::data::transform::TransformKind;
use crate::error::{CoreError, Result};
use crate::progress::Progress;

mod build;
mod energy;

pub(crate) use build::build_unnamed;
use build::gram_fold;
pub use build::{build_scratch_store, build_store};
pub(crate) use energy::EnergyBound;

use crate::dense::gram::syrk_lower_add;
use crate::dense::gram32::syrk_lower_add_f32;

const MAGIC: &[u8; 8] = b"BRDFSTOR";
const VERSION: u32 = 1;
const HEADER: usize = 64;
/// Rows per block of the streaming passes: 400 kB of f64 for N = 100, so a
/// block of the store pass stays in the L2 cache between its steps.
pub const BLOCK_ROWS: usize = 512;

/// Precision of the stored values. Sums are always accumulated in f64.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// 4 bytes a value: half the memory and bandwidth, about 7 significant digits.
    #[default]
    F32,
    /// 8 bytes a value.
    F64,
}

impl Precision {
    /// Bytes per value.
    pub fn bytes(self) -> usize {
        match self {
            Precision::F32 => 4,
            Precision::F64 => 8,
        }
    }

    /// `f32` or `f64`.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        }
    }

    /// Parse `f32` or `f64`.
    pub fn parse(s: &str) -> Option<Precision> {
        match s {
            "f32" => Some(Precision::F32),
            "f64" => Some(Precision::F64),
            _ => None,
        }
    }
}

/// Byte layout of a store with `n` materials over `rows` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Layout {
    rows: usize,
    n: usize,
    bytes: usize,
    mean: usize,
    unmeasured: usize,
    z: usize,
    len: usize,
}

impl Layout {
    /// The header of a store of `n` materials of `dims`.
    fn header(
        dims: Dims,
        n: usize,
        precision: Precision,
        transform: TransformKind,
    ) -> [u8; HEADER] {
        let mut header = [0u8; HEADER];
        header[..8].copy_from_slice(MAGIC);
        let fields = [
            VERSION,
            precision.bytes() as u32,
            n as u32,
            transform as u32,
        ];
        let dimv = [dims.theta_h as u32, dims.theta_d as u32, dims.phi_d as u32];
        for (k, v) in fields.iter().chain(&dimv).enumerate() {
            header[8 + 4 * k..12 + 4 * k].copy_from_slice(&v.to_le_bytes());
        }
        header
    }

    fn new(rows: usize, n: usize, precision: Precision) -> Layout {
        let mean = HEADER;
        let unmeasured = mean + 8 * rows;
        let z = (unmeasured + rows).div_ceil(64) * 64;
        let bytes = precision.bytes();
        Layout {
            rows,
            n,
            bytes,
            mean,
            unmeasured,
            z,
            len: z + rows * n * bytes,
        }
    }
}

/// A memory-mapped store (see the module docs). Cheap to share by reference.
pub struct Store {
    path: PathBuf,
    map: GuardedMap,
    dims: Dims,
    transform: TransformKind,
    precision: Precision,
    layout: Layout,
    /// What bounds the default rule's energy ([`energy`]), once asked for.
    energy: std::sync::OnceLock<EnergyBound>,
}

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Store")
            .field("path", &self.path)
            .field("n", &self.layout.n)
            .field("dims", &self.dims)
            .field("transform", &self.transform)
            .field("precision", &self.precision)
            .finish()
    }
}

/// Rows of the store, borrowed in their stored precision.
#[derive(Clone, Copy)]
pub enum Rows<'a> {
    /// f32 values, `rows * n`.
    F32(&'a [f32]),
    /// f64 values, `rows * n`.
    F64(&'a [f64]),
}

impl Store {
    /// Map a store file and check its header and size.
    pub fn open(path: impl AsRef<Path>) -> Result<Store> {
        let path = path.as_ref().to_path_buf();
        let map =
            GuardedMap::open(&path, Watch::Descriptor).map_err(|e| CoreError::io(&path, e))?;
        Self::from_map(map, path)
    }

    /// [`Store::open`] of an open file (one still without a name, as
    /// [`crate::fit_dir`] builds it); `path` names it in messages.
    pub(crate) fn from_file(file: std::fs::File, path: &Path) -> Result<Store> {
        let map = GuardedMap::from_file(file, path).map_err(|e| CoreError::io(path, e))?;
        Self::from_map(map, path.to_path_buf())
    }

    /// Another handle on the same store: the same file mapped again (by its
    /// descriptor, so a store without a name, [`build_scratch_store`]'s,
    /// can have several).
    ///
    /// [`build_scratch_store`]: crate::build_scratch_store
    pub fn try_clone(&self) -> Result<Store> {
        let map = self
            .map
            .try_clone()
            .map_err(|e| CoreError::io(&self.path, e))?;
        Self::from_map(map, self.path.clone())
    }

    fn from_map(map: GuardedMap, path: PathBuf) -> Result<Store> {
        let bad = |why: String| CoreError::bad_file(&path, why);
        if brdf_merl::table::is_lfs_pointer(&map) {
            return Err(bad(
                "is a Git LFS pointer file, not a brdf-atlas store (run `git lfs pull` to fetch the real file)".into(),
            ));
        }
        if map.len() < HEADER || &map[..8] != MAGIC {
            return Err(bad(
                "not a brdf-atlas store (missing BRDFSTOR header)".into()
            ));
        }
        let u32_at = |o: usize| u32::from_le_bytes(map[o..o + 4].try_into().expect("4 bytes"));
        let version = u32_at(8);
        if version > VERSION {
            return Err(bad(format!(
                "store format version {version} was written by a newer brdf-atlas (this build reads version {VERSION}); upgrade brdf-atlas"
            )));
        }
        if version != VERSION {
            return Err(bad(format!(
                "store format version {version}, this build reads version {VERSION}"
            )));
        }
        let precision = match u32_at(12) {
            4 => Precision::F32,
            8 => Precision::F64,
            b => return Err(bad(format!("{b} bytes per value, expected 4 or 8"))),
        };
        let n = u32_at(16) as usize;
        let transform = match TransformKind::ALL.get(u32_at(20) as usize) {
            Some(&t) => t,
            None => return Err(bad(format!("unknown transform code {}", u32_at(20)))),
        };
        let dims = Dims::new(
            u32_at(24) as usize,
            u32_at(28) as usize,
            u32_at(32) as usize,
        )
        .map_err(|e| bad(format!("header {e}")))?;
        if n == 0 || n > 1 << 20 {
            return Err(bad(format!(
                "header says {n} materials, expected 1 to 1048576"
            )));
        }
        let layout = Layout::new(dims.values(), n, precision);
        if map.len() != layout.len {
            return Err(bad(format!(
                "{} bytes, but {n} materials of {dims} in {} need {} (truncated or changed?)",
                map.len(),
                precision.name(),
                layout.len
            )));
        }
        Ok(Store {
            path,
            map,
            dims,
            transform,
            precision,
            layout,
            energy: std::sync::OnceLock::new(),
        })
    }

    /// What keeps the default rule's material under a directional albedo
    /// of 1 ([`energy`]): computed on first use (one pass over 4% of the
    /// store), then kept.
    pub(crate) fn energy_bound(&self) -> &EnergyBound {
        self.energy.get_or_init(|| EnergyBound::of(self))
    }

    /// Use `bound` (read from the model file the fit wrote beside this
    /// store) instead of computing it, if it fits the store and none is
    /// computed yet.
    pub(crate) fn keep_energy_bound(&self, bound: &EnergyBound) {
        if bound.fits(self.n()) {
            let _ = self.energy.set(bound.clone());
        }
    }

    /// The file behind the map.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `Ok` if the file is as it was when mapped; otherwise
    /// [`CoreError::FileChanged`]: it was truncated (reads of it gave zeros)
    /// or rewritten in place (its size or modification time moved). Once
    /// changed, always changed: the store must be reopened. One `fstat`.
    pub fn verify(&self) -> Result<()> {
        if self.map.changed() {
            return Err(CoreError::FileChanged {
                path: self.path.clone(),
            });
        }
        Ok(())
    }

    /// [`Store::verify`] without the `fstat`: only a change already seen
    /// (a truncation the SIGBUS handler answered, or an earlier check).
    pub fn verify_cheap(&self) -> Result<()> {
        if self.map.poisoned() {
            return Err(CoreError::FileChanged {
                path: self.path.clone(),
            });
        }
        Ok(())
    }

    /// Number of materials `N`.
    pub fn n(&self) -> usize {
        self.layout.n
    }

    /// Number of rows `d = 3 * bins`.
    pub fn rows(&self) -> usize {
        self.layout.rows
    }

    /// Table dims of the materials.
    pub fn dims(&self) -> Dims {
        self.dims
    }

    /// The data transform of the stored values.
    pub fn transform(&self) -> TransformKind {
        self.transform
    }

    /// Stored precision.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// Size of the file in bytes.
    pub fn len_bytes(&self) -> u64 {
        self.map.len() as u64
    }

    /// The mean of each row, in transformed space.
    pub fn mean(&self) -> &[f64] {
        bytemuck::cast_slice(&self.map[self.layout.mean..self.layout.unmeasured])
    }

    /// 1 for rows where no input material was measured.
    pub fn unmeasured(&self) -> &[u8] {
        &self.map[self.layout.unmeasured..self.layout.unmeasured + self.layout.rows]
    }

    /// The centred values, `rows * n`, row-major.
    pub fn z(&self) -> Rows<'_> {
        let bytes = &self.map.bytes()[self.layout.z..];
        match self.precision {
            Precision::F32 => Rows::F32(bytemuck::cast_slice(bytes)),
            Precision::F64 => Rows::F64(bytemuck::cast_slice(bytes)),
        }
    }

    /// Copy rows `r0..r0 + out.len() / n` into `out` as f64.
    #[inline]
    pub fn copy_rows(&self, r0: usize, out: &mut [f64]) {
        let (start, len) = (r0 * self.layout.n, out.len());
        match self.z() {
            Rows::F32(z) => out
                .iter_mut()
                .zip(&z[start..start + len])
                .for_each(|(o, v)| *o = *v as f64),
            Rows::F64(z) => out.copy_from_slice(&z[start..start + len]),
        }
    }

    /// Copy rows `r0..` into `out` as f64 (`None`), or the listed rows,
    /// one after another (`Some`): `out.len() / n` of them either way.
    pub(crate) fn copy_listed(&self, r0: usize, listed: Option<&[u32]>, out: &mut [f64]) {
        match listed {
            None => self.copy_rows(r0, out),
            Some(rows) => {
                let n = self.layout.n;
                for (o, &r) in out.chunks_exact_mut(n).zip(rows) {
                    self.copy_rows(r as usize, o);
                }
            }
        }
    }

    /// `Y = Z Z^T` from the stored values, with the kernel of the pass that
    /// built the store (f32 lanes within a block for an f32 store, see
    /// [`crate::dense::gram32`]; f64 throughout for an f64 one; the blocks'
    /// sums in f64), folded in a fixed order: the same bits as the pass's,
    /// whatever the thread count.
    pub fn gram(&self, progress: &dyn Progress) -> Mat<f64> {
        progress.start("gram", self.rows() as u64);
        let n = self.n();
        let y = gram_fold(
            self.rows(),
            n,
            progress,
            || vec![0.0f64; BLOCK_ROWS * n],
            |buf, range, acc| {
                let rows = range.len();
                let (start, len) = (range.start * n, rows * n);
                // Material-major: value r of material i at i * rows + r.
                match self.z() {
                    Rows::F32(z) => {
                        let narrow = &mut bytemuck::cast_slice_mut::<f64, f32>(buf)[..len];
                        material_major(&z[start..start + len], n, narrow);
                        syrk_lower_add_f32(narrow, rows, acc);
                    }
                    Rows::F64(z) => {
                        let block = &mut buf[..len];
                        material_major(&z[start..start + len], n, block);
                        syrk_lower_add(block, rows, acc);
                    }
                }
            },
        );
        progress.finish();
        y
    }

    /// The store file's identity when it was opened: which file on which
    /// device, its size and last modification, and the boot of the machine
    /// ([`StoreIdentity`]); `None` where the boot cannot be told (not Linux).
    pub fn identity(&self) -> Option<StoreIdentity> {
        let s = self.map.stamp();
        Some(StoreIdentity {
            boot: boot_id()?.to_owned(),
            device: s.dev,
            inode: s.ino,
            bytes: s.size,
            modified: [s.mtime.0, s.mtime.1],
        })
    }

    /// Checksum of the whole file (xxh3 of the xxh3 of each 8 MiB block, in order).
    pub fn checksum(&self) -> u64 {
        checksum_bytes(&self.map)
    }
}

/// A store file as the machine knows it: the same identity means the same
/// file, not written to since, and no restart of the machine in between (a
/// store is not synced: a crash may leave it with its size and times but
/// without its content). A model records its store's identity at the fit,
/// and opening the model checksums the store only when the identity differs.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StoreIdentity {
    /// The kernel's boot id (`/proc/sys/kernel/random/boot_id`).
    pub boot: String,
    /// Device of the file system.
    pub device: u64,
    /// Inode number.
    pub inode: u64,
    /// Size in bytes.
    pub bytes: u64,
    /// Last modification: seconds and nanoseconds since the epoch.
    pub modified: [i64; 2],
}

/// This boot of the machine's id, read once; `None` where there is none.
fn boot_id() -> Option<&'static str> {
    static BOOT: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();
    BOOT.get_or_init(|| {
        std::fs::read_to_string("/proc/sys/kernel/random/boot_id")
            .ok()
            .map(|s| s.trim().to_owned())
            .filter(|s| !s.is_empty())
    })
    .as_deref()
}

/// Checksum of a byte slice as [`Store::checksum`] defines it.
pub fn checksum_bytes(bytes: &[u8]) -> u64 {
    const BLOCK: usize = 8 << 20;
    let hashes: Vec<u8> = bytes
        .par_chunks(BLOCK)
        .map(xxhash_rust::xxh3::xxh3_64)
        .collect::<Vec<u64>>()
        .iter()
        .flat_map(|h| h.to_le_bytes())
        .collect();
    xxhash_rust::xxh3::xxh3_64(&hashes)
}

/// Bin-major rows of `n` values (`rows[r * n + i]`) laid out material-major
/// (`out[i * count + r]`, `count` rows), as the Gram kernels read them.
fn material_major<T: Copy>(rows: &[T], n: usize, out: &mut [T]) {
    let count = rows.len() / n;
    for (r, row) in rows.chunks_exact(n).enumerate() {
        for (i, v) in row.iter().enumerate() {
            out[i * count + r] = *v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::data::{Dataset, synth_dir};
    use crate::progress::NoProgress;

    #[test]
    fn bad_stores_are_refused_with_reasons() {
        let tmp = tempfile::tempdir().unwrap();
        let dims = Dims::new(4, 4, 8).unwrap();
        synth_dir(tmp.path(), 3, dims);
        let data = Dataset::open_dir(tmp.path()).unwrap();
        let path = tmp.path().join("x.store");
        build_store(
            &data,
            TransformKind::Raw,
            Precision::F64,
            &path,
            &NoProgress,
        )
        .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let cut = tmp.path().join("cut.store");
        std::fs::write(&cut, &bytes[..bytes.len() - 8]).unwrap();
        assert!(
            Store::open(&cut)
                .unwrap_err()
                .to_string()
                .contains("truncated")
        );
        let mut v2 = bytes.clone();
        v2[8] = 9;
        std::fs::write(&cut, &v2).unwrap();
        assert!(
            Store::open(&cut)
                .unwrap_err()
                .to_string()
                .contains("version 9")
        );
        std::fs::write(&cut, b"hello").unwrap();
        assert!(
            Store::open(&cut)
                .unwrap_err()
                .to_string()
                .contains("not a brdf-atlas store")
        );
    }
}
