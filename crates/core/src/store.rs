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

use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use brdf_merl::atomic::PendingFile;
use brdf_merl::table::{is_invalid, is_non_finite};
use brdf_merl::{Dims, MerlFile};
use faer::linalg::matmul::triangular::{self as tri, BlockStructure};
use faer::{Accum, Mat, MatRef, Par};
use memmap2::Mmap;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Progress, Result};
use crate::transform::TransformKind;

const MAGIC: &[u8; 8] = b"BRDFSTOR";
const VERSION: u32 = 1;
const HEADER: usize = 64;
/// Rows per block of the streaming passes: 400 kB of f64 for N = 100, so a
/// block of the store pass stays in the L2 cache between its steps.
pub const BLOCK_ROWS: usize = 512;
/// The Gram matrix is folded from this many fixed groups of blocks, in order,
/// so its bits do not depend on the thread count.
const GROUPS: usize = 64;

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
    map: Mmap,
    dims: Dims,
    transform: TransformKind,
    precision: Precision,
    layout: Layout,
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
        let file = std::fs::File::open(&path).map_err(|e| CoreError::io(&path, e))?;
        // SAFETY: read-only map of a file we do not modify; see MerlFile::open.
        let map = unsafe { Mmap::map(&file) }.map_err(|e| CoreError::io(&path, e))?;
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
        let transform = match u32_at(20) {
            0 => TransformKind::Raw,
            1 => TransformKind::Log,
            t => return Err(bad(format!("unknown transform code {t}"))),
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
        })
    }

    /// The file behind the map.
    pub fn path(&self) -> &Path {
        &self.path
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
        let bytes = &self.map[self.layout.z..];
        match self.precision {
            Precision::F32 => Rows::F32(bytemuck::cast_slice(bytes)),
            Precision::F64 => Rows::F64(bytemuck::cast_slice(bytes)),
        }
    }

    /// Copy rows `r0..r0 + out.len() / n` into `out` as f64.
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

    /// `Y = Z Z^T` from the stored values (f64 accumulation), folded in a
    /// fixed order: the same bits whatever the thread count.
    pub fn gram(&self, progress: &dyn Progress) -> Mat<f64> {
        progress.start("gram", self.rows() as u64);
        let n = self.n();
        let y = gram_fold(
            self.rows(),
            n,
            progress,
            || vec![0.0f64; n],
            |row, r0, buf| {
                let rows = buf.len() / n;
                for r in 0..rows {
                    self.copy_rows(r0 + r, row);
                    for (i, v) in row.iter().enumerate() {
                        buf[i * rows + r] = *v;
                    }
                }
            },
        );
        progress.finish();
        y
    }

    /// Checksum of the whole file (xxh3 of the xxh3 of each 8 MiB block, in order).
    pub fn checksum(&self) -> u64 {
        checksum_bytes(&self.map)
    }
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

/// Stream `rows` rows of `n` values through `fill(r0, buf)` in blocks of
/// [`BLOCK_ROWS`] and accumulate `sum_j z_j z_j^T`. `fill` writes a block
/// material by material: `buf[i * len + r]` is material `i` in row `r0 + r`,
/// with `len = buf.len() / n` rows in the block. Blocks are grouped into
/// [`GROUPS`] fixed ranges summed in order, so the result does not depend on
/// how rayon schedules them.
fn gram_fold<S>(
    rows: usize,
    n: usize,
    progress: &dyn Progress,
    scratch: impl Fn() -> S + Sync,
    fill: impl Fn(&mut S, usize, &mut [f64]) + Sync,
) -> Mat<f64> {
    let blocks = rows.div_ceil(BLOCK_ROWS);
    let groups = GROUPS.min(blocks.max(1));
    let partials: Vec<Mat<f64>> = (0..groups)
        .into_par_iter()
        .map(|g| {
            let mut acc = Mat::<f64>::zeros(n, n);
            let mut buf = vec![0.0f64; BLOCK_ROWS * n];
            let mut scratch = scratch();
            for b in (g * blocks / groups)..((g + 1) * blocks / groups) {
                let r0 = b * BLOCK_ROWS;
                let r1 = (r0 + BLOCK_ROWS).min(rows);
                let buf = &mut buf[..(r1 - r0) * n];
                fill(&mut scratch, r0, buf);
                // Material-major is column-major rows x n: Y += Z_b^T Z_b.
                let zc = MatRef::from_column_major_slice(buf, r1 - r0, n);
                tri::matmul(
                    acc.as_mut(),
                    BlockStructure::TriangularLower,
                    Accum::Add,
                    zc.transpose(),
                    BlockStructure::Rectangular,
                    zc,
                    BlockStructure::Rectangular,
                    1.0,
                    Par::Seq,
                );
                progress.advance((r1 - r0) as u64);
            }
            acc
        })
        .collect();
    let mut y = Mat::<f64>::zeros(n, n);
    for p in &partials {
        y += p;
    }
    // Only the lower triangle was accumulated (half the flops): mirror it.
    for i in 0..n {
        for j in 0..i {
            y[(j, i)] = y[(i, j)];
        }
    }
    y
}

/// Rows of a block centred and transposed together: one cache line of f64
/// per material, so the `N` lines a tile reads stay in the L1 cache.
const TILE_ROWS: usize = 8;

/// Centre a material-major block (`n` columns of `mean.len()` rows) by the
/// row means and round each value to the stored type (`to`, and `back` to
/// f64, so the block then holds exactly what the file will); write it
/// bin-major, little-endian, into `out` (`rows * n` values), ready to write.
fn centre_bin_major<T: bytemuck::Pod>(
    block: &mut [f64],
    mean: &[f64],
    out: &mut [T],
    to: impl Fn(f64) -> T,
    back: impl Fn(T) -> f64,
) {
    let rows = mean.len();
    let n = block.len() / rows;
    for t0 in (0..rows).step_by(TILE_ROWS) {
        let t1 = (t0 + TILE_ROWS).min(rows);
        let tile = &mut out[t0 * n..t1 * n];
        for (col, material) in block.chunks_exact_mut(rows).enumerate() {
            for ((v, m), dst) in material[t0..t1]
                .iter_mut()
                .zip(&mean[t0..t1])
                .zip(tile[col..].iter_mut().step_by(n))
            {
                let z = to(*v - m);
                *v = back(z);
                *dst = z;
            }
        }
    }
    // The file is little-endian; on a big-endian host swap each value.
    if cfg!(target_endian = "big") {
        for word in bytemuck::cast_slice_mut::<T, u8>(out).chunks_exact_mut(size_of::<T>()) {
            word.reverse();
        }
    }
}

/// [`centre_bin_major`] into f32: with AVX2, eight rows of four materials at
/// a time (subtract, round, two 4 x 4 transposes in registers); the same
/// operations as the scalar path, so the same bits.
fn centre_bin_major_f32(block: &mut [f64], mean: &[f64], out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        unsafe { centre_bin_major_f32_avx2(block, mean, out) };
        return;
    }
    centre_bin_major(block, mean, out, |v| v as f32, |z| z as f64);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn centre_bin_major_f32_avx2(block: &mut [f64], mean: &[f64], out: &mut [f32]) {
    use std::arch::x86_64::*;
    let rows = mean.len();
    let n = block.len() / rows;
    assert!(out.len() == rows * n && block.len() == rows * n);
    // Eight rows (one cache line of each material's run) by four materials.
    let (rows8, n4) = (rows / 8 * 8, n / 4 * 4);
    let (b, o) = (block.as_mut_ptr(), out.as_mut_ptr());
    for r0 in (0..rows8).step_by(8) {
        // SAFETY (all loads and stores below): r0 + 7 < rows and i + 3 < n,
        // so every index is inside `block` (n runs of rows) or `out` (rows of n).
        unsafe {
            let m_lo = _mm256_loadu_pd(mean.as_ptr().add(r0));
            let m_hi = _mm256_loadu_pd(mean.as_ptr().add(r0 + 4));
            for i in (0..n4).step_by(4) {
                let mut lo = [_mm_setzero_ps(); 4];
                let mut hi = [_mm_setzero_ps(); 4];
                for k in 0..4 {
                    let p = b.add((i + k) * rows + r0);
                    let z_lo = _mm256_cvtpd_ps(_mm256_sub_pd(_mm256_loadu_pd(p), m_lo));
                    let z_hi = _mm256_cvtpd_ps(_mm256_sub_pd(_mm256_loadu_pd(p.add(4)), m_hi));
                    _mm256_storeu_pd(p, _mm256_cvtps_pd(z_lo));
                    _mm256_storeu_pd(p.add(4), _mm256_cvtps_pd(z_hi));
                    lo[k] = z_lo;
                    hi[k] = z_hi;
                }
                for (half, x) in [lo, hi].iter().enumerate() {
                    let (t0, t1) = (_mm_unpacklo_ps(x[0], x[1]), _mm_unpacklo_ps(x[2], x[3]));
                    let (t2, t3) = (_mm_unpackhi_ps(x[0], x[1]), _mm_unpackhi_ps(x[2], x[3]));
                    let r = r0 + 4 * half;
                    _mm_storeu_ps(o.add(r * n + i), _mm_movelh_ps(t0, t1));
                    _mm_storeu_ps(o.add((r + 1) * n + i), _mm_movehl_ps(t1, t0));
                    _mm_storeu_ps(o.add((r + 2) * n + i), _mm_movelh_ps(t2, t3));
                    _mm_storeu_ps(o.add((r + 3) * n + i), _mm_movehl_ps(t3, t2));
                }
            }
        }
        for i in n4..n {
            for r in r0..r0 + 8 {
                centre_one(block, mean, out, (r, i));
            }
        }
    }
    for r in rows8..rows {
        for i in 0..n {
            centre_one(block, mean, out, (r, i));
        }
    }
}

/// The scalar step of [`centre_bin_major_f32_avx2`]'s remainders: value
/// `r` of material `i`.
#[inline(always)]
fn centre_one(block: &mut [f64], mean: &[f64], out: &mut [f32], (r, i): (usize, usize)) {
    let (rows, n) = (mean.len(), block.len() / mean.len());
    let z = (block[i * rows + r] - mean[r]) as f32;
    block[i * rows + r] = z as f64;
    out[r * n + i] = z;
}

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
            if path.extension().is_some_and(|e| e == "binary") && path.is_file() {
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

/// Per-thread buffers of the store pass, reused block after block.
struct PassScratch {
    raw: Vec<f64>,
    mean: Vec<f64>,
    /// Materials measured at each row of the block (a count, as f64 so the
    /// tally vectorises).
    measured: Vec<f64>,
    unmeasured: Vec<u8>,
    /// The block bin-major in the stored type (f64-sized to hold either).
    out: Vec<f64>,
    mean_bytes: Vec<u8>,
}

impl PassScratch {
    fn new(n: usize) -> PassScratch {
        PassScratch {
            raw: Vec::with_capacity(BLOCK_ROWS),
            mean: Vec::with_capacity(BLOCK_ROWS),
            measured: Vec::with_capacity(BLOCK_ROWS),
            unmeasured: Vec::with_capacity(BLOCK_ROWS),
            out: vec![0.0; BLOCK_ROWS * n],
            mean_bytes: Vec::with_capacity(8 * BLOCK_ROWS),
        }
    }

    /// Ready for a block of `rows` rows.
    fn start(&mut self, rows: usize) {
        self.raw.resize(rows, 0.0);
        self.mean.clear();
        self.mean.resize(rows, 0.0);
        self.measured.clear();
        self.measured.resize(rows, 0.0);
        self.unmeasured.resize(rows, 0);
    }
}

/// One material's run in a block of the store pass: count its measured
/// values into `measured`, add its transformed values `col` into `mean`,
/// and say whether any raw value is not finite (the caller then finds and
/// names it). One loop, vectorised (AVX2 where the CPU has it; the same
/// bits either way: additions of the same values in the same order).
fn tally(raw: &[f64], col: &[f64], measured: &mut [f64], mean: &mut [f64]) -> bool {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { tally_avx2(raw, col, measured, mean) };
    }
    tally_portable(raw, col, measured, mean)
}

#[inline(always)]
fn tally_portable(raw: &[f64], col: &[f64], measured: &mut [f64], mean: &mut [f64]) -> bool {
    let mut non_finite = 0u64;
    for (((v, t), c), m) in raw.iter().zip(col).zip(measured).zip(mean) {
        non_finite |= is_non_finite(*v) as u64;
        *c += if is_invalid(*v) { 0.0 } else { 1.0 };
        *m += t;
    }
    non_finite != 0
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn tally_avx2(raw: &[f64], col: &[f64], measured: &mut [f64], mean: &mut [f64]) -> bool {
    tally_portable(raw, col, measured, mean)
}

/// Build the store of a dataset at `out` (atomically) and return it with
/// the Gram matrix `Y = Z Z^T` accumulated in the same pass.
///
/// One streaming pass: for each block of rows, read the `N` materials'
/// values, transform, centre by the row mean, round to the stored precision,
/// add the block's `Z_b Z_b^T` to `Y` (f64) and write the block in place.
pub fn build_store(
    data: &Dataset,
    transform: TransformKind,
    precision: Precision,
    out: &Path,
    progress: &dyn Progress,
) -> Result<(Store, Mat<f64>)> {
    let dims = data.dims();
    let n = data.len();
    let bins = dims.bins();
    let layout = Layout::new(dims.values(), n, precision);
    let pending = PendingFile::create(out).map_err(|e| CoreError::io(out, e))?;
    let file = pending.file();
    pending
        .allocate(layout.len as u64)
        .map_err(|e| CoreError::io(out, e))?;
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
    file.write_all_at(&header, 0)
        .map_err(|e| CoreError::io(out, e))?;

    let t = transform.build(dims);
    // The first unreadable value in (material, value) order, whatever the
    // schedule; and the first write error.
    let bad_value: Mutex<Option<((usize, usize), CoreError)>> = Mutex::new(None);
    let write_error: Mutex<Option<std::io::Error>> = Mutex::new(None);
    // One writer at a time: concurrent writes to one file serialise on its
    // inode lock in the kernel anyway, where the waiter spins.
    let writing = Mutex::new(());
    progress.start("store", layout.rows as u64);
    let y = gram_fold(
        layout.rows,
        n,
        progress,
        || PassScratch::new(n),
        |s, r0, buf| {
            let rows = buf.len() / n;
            s.start(rows);
            // Transform each material's run of rows into its column of the block.
            for (m, (f, col)) in data
                .files
                .iter()
                .zip(buf.chunks_exact_mut(rows))
                .enumerate()
            {
                f.copy_raw(r0, &mut s.raw);
                t.forward_raw_rows(bins, r0, &s.raw, col);
                if tally(&s.raw, col, &mut s.measured, &mut s.mean) {
                    let e = f.check_finite(r0, &s.raw).expect_err("a non-finite value");
                    let mut first = bad_value.lock().expect("no panics while locked");
                    if first.as_ref().is_none_or(|(at, _)| (m, r0) < *at) {
                        *first = Some(((m, r0), e.into()));
                    }
                }
            }
            for (u, c) in s.unmeasured.iter_mut().zip(&s.measured) {
                *u = (*c == 0.0) as u8;
            }
            s.mean.iter_mut().for_each(|m| *m /= n as f64);
            // Centre, round to the stored precision (the Gram matrix sees what
            // the store holds), and lay the block out bin-major for the file.
            let bytes: &[u8] = match precision {
                Precision::F32 => {
                    let out = &mut bytemuck::cast_slice_mut::<f64, f32>(&mut s.out)[..rows * n];
                    centre_bin_major_f32(buf, &s.mean, out);
                    bytemuck::cast_slice(out)
                }
                Precision::F64 => {
                    let out = &mut s.out[..rows * n];
                    centre_bin_major(buf, &s.mean, out, |v| v, |z| z);
                    bytemuck::cast_slice(out)
                }
            };
            s.mean_bytes.clear();
            s.mean_bytes
                .extend(s.mean.iter().flat_map(|m| m.to_le_bytes()));
            let result = {
                let _one_writer = writing.lock().expect("no panics while locked");
                file.write_all_at(bytes, (layout.z + r0 * n * precision.bytes()) as u64)
                    .and_then(|_| file.write_all_at(&s.mean_bytes, (layout.mean + 8 * r0) as u64))
                    .and_then(|_| file.write_all_at(&s.unmeasured, (layout.unmeasured + r0) as u64))
            };
            if let Err(e) = result {
                write_error
                    .lock()
                    .expect("no panics while locked")
                    .get_or_insert(e);
            }
        },
    );
    progress.finish();
    if let Some((_, e)) = bad_value.into_inner().expect("no panics while locked") {
        return Err(e);
    }
    if let Some(e) = write_error.into_inner().expect("no panics while locked") {
        return Err(CoreError::io(out, e));
    }
    pending.commit(false).map_err(|e| CoreError::io(out, e))?;
    Ok((Store::open(out)?, y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::NoProgress;
    use brdf_merl::synth;

    pub(crate) fn synth_dir(dir: &Path, count: usize, dims: Dims) {
        for m in synth::database(count, 5) {
            m.brdf
                .table(dims)
                .write(dir.join(format!("{}.binary", m.name)))
                .unwrap();
        }
    }

    #[test]
    fn vector_centring_gives_the_scalar_bits() {
        let mut rng = brdf_merl::synth::SplitMix64::new(3);
        // Odd sizes exercise the remainders of the 4 x 4 tiles.
        for (rows, n) in [(37, 10), (8, 4), (3, 3), (1024, 100)] {
            let block: Vec<f64> = (0..rows * n).map(|_| rng.range(-5.0, 5.0) * 1e3).collect();
            let mean: Vec<f64> = (0..rows).map(|_| rng.range(-1.0, 1.0)).collect();
            let (mut a, mut b) = (block.clone(), block);
            let (mut oa, mut ob) = (vec![0f32; rows * n], vec![0f32; rows * n]);
            centre_bin_major_f32(&mut a, &mean, &mut oa);
            centre_bin_major(&mut b, &mean, &mut ob, |v| v as f32, |z| z as f64);
            assert_eq!(a, b);
            assert_eq!(oa, ob);
            // And the layout: value r of material i at out[r * n + i].
            for (i, col) in a.chunks_exact(rows).enumerate() {
                for (r, v) in col.iter().enumerate() {
                    assert_eq!(oa[r * n + i] as f64, *v);
                }
            }
        }
    }

    #[test]
    fn store_holds_centred_transformed_values_and_gram() {
        let tmp = tempfile::tempdir().unwrap();
        let dims = Dims::new(6, 6, 12).unwrap();
        synth_dir(tmp.path(), 5, dims);
        std::fs::write(tmp.path().join("notes.txt"), "hello").unwrap();
        let data = Dataset::open_dir(tmp.path()).unwrap();
        assert_eq!(data.len(), 5);
        assert_eq!(data.ignored.len(), 1);
        let tables: Vec<_> = data.files.iter().map(|f| f.to_table()).collect();
        for transform in [TransformKind::Raw, TransformKind::Log] {
            for precision in [Precision::F64, Precision::F32] {
                let out =
                    tmp.path()
                        .join(format!("s-{}-{}.store", transform.name(), precision.name()));
                let (store, y) =
                    build_store(&data, transform, precision, &out, &NoProgress).unwrap();
                assert_eq!(store.n(), 5);
                let t = transform.build(dims);
                // Dense reference: transform, centre, multiply.
                let d = dims.values();
                let mut z = Mat::<f64>::zeros(5, d);
                for (i, tab) in tables.iter().enumerate() {
                    for row in 0..d {
                        let (c, bin) = (row / dims.bins(), row % dims.bins());
                        z[(i, row)] = t.forward(bin, tab.value(c, bin));
                    }
                }
                let tol = if precision == Precision::F32 {
                    1e-6
                } else {
                    1e-12
                };
                for row in 0..d {
                    let m: f64 = (0..5).map(|i| z[(i, row)]).sum::<f64>() / 5.0;
                    assert!((store.mean()[row] - m).abs() <= 1e-12 * m.abs().max(1.0));
                    let all_invalid = tables
                        .iter()
                        .all(|tab| tab.value(row / dims.bins(), row % dims.bins()).is_none());
                    assert_eq!(store.unmeasured()[row] == 1, all_invalid);
                    let mut got = vec![0.0; 5];
                    store.copy_rows(row, &mut got);
                    for i in 0..5 {
                        z[(i, row)] -= m;
                        assert!(
                            (got[i] - z[(i, row)]).abs() <= tol * z[(i, row)].abs().max(1.0),
                            "{row} {i}"
                        );
                    }
                }
                let dense = &z * z.transpose();
                let scale = dense.norm_max();
                assert!(
                    (&y - &dense).norm_max() <= tol * scale * 10.0,
                    "{:?}",
                    (&y - &dense).norm_max()
                );
                // The stored-value Gram equals the one built in the same pass, bit for bit.
                assert_eq!(store.gram(&NoProgress), y);
            }
        }
    }

    #[test]
    fn gram_is_independent_of_thread_count() {
        let tmp = tempfile::tempdir().unwrap();
        let dims = Dims::new(20, 20, 40).unwrap();
        synth_dir(tmp.path(), 7, dims);
        let data = Dataset::open_dir(tmp.path()).unwrap();
        let (store, _) = build_store(
            &data,
            TransformKind::Raw,
            Precision::F32,
            &tmp.path().join("a.store"),
            &NoProgress,
        )
        .unwrap();
        let pool = |k| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(k)
                .build()
                .unwrap()
        };
        let one = pool(1).install(|| store.gram(&NoProgress));
        let three = pool(3).install(|| store.gram(&NoProgress));
        assert_eq!(one, three);
    }

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
