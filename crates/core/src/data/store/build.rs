//! Building a store: one streaming pass over the input files that
//! transforms, centres and writes `Z` block by block and accumulates the
//! Gram matrix `Y = Z Z^T` on the way.

use std::os::unix::fs::FileExt;
use std::path::Path;
use std::sync::Mutex;

use brdf_atomic::PendingFile;
use brdf_merl::table::{is_invalid, is_suspect};
use faer::Mat;

use crate::data::transform::TransformKind;
use crate::dense::gram::syrk_lower_add;
use crate::dense::gram32::syrk_lower_add_f32;
use crate::error::{CoreError, Result};
use crate::progress::Progress;
use crate::simd::fold::{GROUPS, ordered_blocks_then};

use super::{BLOCK_ROWS, Layout, Precision, Store};
use crate::data::Dataset;

/// Stream `rows` rows of `n` values in blocks of [`BLOCK_ROWS`] and
/// accumulate `sum_j z_j z_j^T`: `add(s, rows, acc)` makes the block of the
/// rows `rows` and adds its `Z_b^T Z_b` to `acc` (`n x n`, column-major,
/// lower triangle) with [`syrk_lower_add`] (f64 values) or
/// [`syrk_lower_add_f32`] (an f32 store's). Blocks are grouped into
/// [`GROUPS`] fixed ranges summed in order ([`ordered_blocks_then`]), so the
/// result does not depend on how rayon schedules them; each block's
/// products are summed in a fixed order by the kernel, on every CPU.
pub(super) fn gram_fold<S: Send>(
    rows: usize,
    n: usize,
    progress: &dyn Progress,
    scratch: impl Fn() -> S + Sync,
    add: impl Fn(&mut S, std::ops::Range<usize>, &mut [f64]) + Sync,
) -> Mat<f64> {
    let partials = ordered_blocks_then(
        rows,
        BLOCK_ROWS,
        gram_groups(n),
        || (vec![0.0f64; n * n], scratch()),
        |(acc, scratch), range| {
            let len = range.len();
            add(scratch, range, acc);
            progress.advance(len as u64);
        },
        |(acc, _)| acc,
    );
    let mut y = vec![0.0f64; n * n];
    for p in &partials {
        y.iter_mut().zip(p).for_each(|(a, b)| *a += b);
    }
    // Only the lower triangle was accumulated (half the flops): mirror it.
    Mat::from_fn(
        n,
        n,
        |i, j| if i >= j { y[j * n + i] } else { y[i * n + j] },
    )
}

/// Bytes of the Gram pass's partial sums kept until the ordered fold.
const PARTIALS_BUDGET: usize = 64 << 20;

/// Groups of the Gram pass for `n` materials: [`GROUPS`] while their `n x n`
/// partial sums fit [`PARTIALS_BUDGET`] (up to 362 materials), fewer above
/// (8 at 1000, never under 4), so the pass's memory stays bounded. It
/// depends on `n` only, never on the thread count.
fn gram_groups(n: usize) -> usize {
    (PARTIALS_BUDGET / (n * n * 8).max(1)).clamp(4, GROUPS)
}

/// Rows of a block centred and transposed together: one cache line of f64
/// per material, so the `N` lines a tile reads stay in the L1 cache.
const TILE_ROWS: usize = 8;

/// Centre a material-major block (`n` columns of `mean.len()` rows) by the
/// row means and round each value to the stored type (`to`); write it
/// material-major into `narrow` (the Gram kernel's input, exactly what the
/// file will hold) and bin-major, little-endian, into `out` (`rows * n`
/// values), ready to write.
fn centre_bin_major<T: bytemuck::Pod>(
    block: &[f64],
    mean: &[f64],
    out: &mut [T],
    narrow: &mut [T],
    to: impl Fn(f64) -> T,
) {
    let rows = mean.len();
    let n = block.len() / rows;
    for t0 in (0..rows).step_by(TILE_ROWS) {
        let t1 = (t0 + TILE_ROWS).min(rows);
        let tile = &mut out[t0 * n..t1 * n];
        for (col, (material, kept)) in block
            .chunks_exact(rows)
            .zip(narrow.chunks_exact_mut(rows))
            .enumerate()
        {
            for (((v, m), k), dst) in material[t0..t1]
                .iter()
                .zip(&mean[t0..t1])
                .zip(&mut kept[t0..t1])
                .zip(tile[col..].iter_mut().step_by(n))
            {
                let z = to(*v - m);
                *k = z;
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
fn centre_bin_major_f32(block: &[f64], mean: &[f64], out: &mut [f32], narrow: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        unsafe { centre_bin_major_f32_avx2(block, mean, out, narrow) };
        return;
    }
    centre_bin_major(block, mean, out, narrow, |v| v as f32);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn centre_bin_major_f32_avx2(block: &[f64], mean: &[f64], out: &mut [f32], narrow: &mut [f32]) {
    use std::arch::x86_64::*;
    let rows = mean.len();
    let n = block.len() / rows;
    assert!(out.len() == rows * n && block.len() == rows * n && narrow.len() == rows * n);
    // Eight rows (one cache line of each material's run) by four materials.
    let (rows8, n4) = (rows / 8 * 8, n / 4 * 4);
    let (b, o, w) = (block.as_ptr(), out.as_mut_ptr(), narrow.as_mut_ptr());
    for r0 in (0..rows8).step_by(8) {
        // SAFETY (all loads and stores below): r0 + 7 < rows and i + 3 < n,
        // so every index is inside `block` and `narrow` (n runs of rows) or
        // `out` (rows of n).
        unsafe {
            let m_lo = _mm256_loadu_pd(mean.as_ptr().add(r0));
            let m_hi = _mm256_loadu_pd(mean.as_ptr().add(r0 + 4));
            for i in (0..n4).step_by(4) {
                let mut lo = [_mm_setzero_ps(); 4];
                let mut hi = [_mm_setzero_ps(); 4];
                for k in 0..4 {
                    let at = (i + k) * rows + r0;
                    let p = b.add(at);
                    let z_lo = _mm256_cvtpd_ps(_mm256_sub_pd(_mm256_loadu_pd(p), m_lo));
                    let z_hi = _mm256_cvtpd_ps(_mm256_sub_pd(_mm256_loadu_pd(p.add(4)), m_hi));
                    _mm_storeu_ps(w.add(at), z_lo);
                    _mm_storeu_ps(w.add(at + 4), z_hi);
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
                centre_one(block, mean, (out, narrow), (r, i));
            }
        }
    }
    for r in rows8..rows {
        for i in 0..n {
            centre_one(block, mean, (out, narrow), (r, i));
        }
    }
}

/// The scalar step of [`centre_bin_major_f32_avx2`]'s remainders: value
/// `r` of material `i`.
#[inline(always)]
fn centre_one(
    block: &[f64],
    mean: &[f64],
    (out, narrow): (&mut [f32], &mut [f32]),
    (r, i): (usize, usize),
) {
    let (rows, n) = (mean.len(), block.len() / mean.len());
    let z = (block[i * rows + r] - mean[r]) as f32;
    narrow[i * rows + r] = z;
    out[r * n + i] = z;
}

/// Per-thread buffers of the store pass, reused block after block.
struct PassScratch {
    raw: Vec<f64>,
    mean: Vec<f64>,
    /// Materials measured at each row of the block (a count, as f64 so the
    /// tally vectorises).
    measured: Vec<f64>,
    unmeasured: Vec<u8>,
    /// The block's transformed values, material-major.
    block: Vec<f64>,
    /// The block bin-major in the stored type (f64-sized to hold either).
    out: Vec<f64>,
    /// The block material-major in the stored type (f64-sized to hold
    /// either): the Gram kernel's input.
    narrow: Vec<f64>,
    mean_bytes: Vec<u8>,
}

impl PassScratch {
    fn new(n: usize) -> PassScratch {
        PassScratch {
            raw: Vec::with_capacity(BLOCK_ROWS),
            mean: Vec::with_capacity(BLOCK_ROWS),
            measured: Vec::with_capacity(BLOCK_ROWS),
            unmeasured: Vec::with_capacity(BLOCK_ROWS),
            block: vec![0.0; BLOCK_ROWS * n],
            out: vec![0.0; BLOCK_ROWS * n],
            narrow: vec![0.0; BLOCK_ROWS * n],
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
/// and say whether any raw value may be out of range (the caller then
/// finds and names it). One loop, vectorised (AVX2 where the CPU has it; the same
/// bits either way: additions of the same values in the same order).
fn tally(raw: &[f64], col: &[f64], measured: &mut [f64], mean: &mut [f64]) -> bool {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { tally_avx2(raw, col, measured, mean) };
    }
    tally_portable(raw, col, measured, mean)
}

#[inline(always)]
fn tally_portable(raw: &[f64], col: &[f64], measured: &mut [f64], mean: &mut [f64]) -> bool {
    let mut suspect = 0u64;
    for (((v, t), c), m) in raw.iter().zip(col).zip(measured).zip(mean) {
        suspect |= is_suspect(*v) as u64;
        *c += if is_invalid(*v) { 0.0 } else { 1.0 };
        *m += t;
    }
    suspect != 0
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
    let (store, y, pending) = build_unnamed(data, transform, precision, out, progress)?;
    pending
        .commit(false)
        .map_err(|e| CoreError::write(out, e))?;
    Ok((store, y))
}

/// [`build_store`], but not put in place: the store is mapped from the file
/// as written (unnamed where the file system allows), and the returned
/// [`PendingFile`] puts it at `out` (which names it in errors meanwhile).
pub(crate) fn build_unnamed(
    data: &Dataset,
    transform: TransformKind,
    precision: Precision,
    out: &Path,
    progress: &dyn Progress,
) -> Result<(Store, Mat<f64>, PendingFile)> {
    let layout = Layout::new(data.dims().values(), data.len(), precision);
    let pending = PendingFile::create(out).map_err(|e| CoreError::write(out, e))?;
    pending
        .allocate(layout.len as u64)
        .map_err(|e| CoreError::write(out, e))?;
    let (store, y) = write_store(pending.file(), data, transform, precision, out, progress)?;
    Ok((store, y, pending))
}

/// [`build_store`] into a scratch file that has no name and is thrown away
/// with the last handle on the store ([`Store::try_clone`] makes more): in
/// memory where the kernel allows and it takes at most a quarter of the
/// memory available, never written back to a disk, and left behind by no
/// run however it ends ([`brdf_atomic::scratch_file`]; else unnamed in
/// `name`'s directory). `name` names the store in messages. For
/// work a run throws away, as the report's stores.
pub fn build_scratch_store(
    data: &Dataset,
    transform: TransformKind,
    precision: Precision,
    name: &Path,
    progress: &dyn Progress,
) -> Result<(Store, Mat<f64>)> {
    let layout = Layout::new(data.dims().values(), data.len(), precision);
    let dir = match name.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let label = name
        .file_name()
        .map_or_else(|| "store".into(), |f| f.to_string_lossy().into_owned());
    let file = brdf_atomic::scratch_file(dir, &label, layout.len as u64)
        .map_err(|e| CoreError::write(name, e))?;
    write_store(&file, data, transform, precision, name, progress)
}

/// The store pass into `file`, already `Layout::len` bytes long: header,
/// values, means and the unmeasured mask, and the Gram matrix summed on
/// the way; the store mapped from `file` (`out` names it in messages).
fn write_store(
    file: &std::fs::File,
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
    let header = Layout::header(dims, n, precision, transform);
    file.write_all_at(&header, 0)
        .map_err(|e| CoreError::write(out, e))?;

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
        |s, range, acc| {
            let (r0, rows) = (range.start, range.len());
            s.start(rows);
            let buf = &mut s.block[..rows * n];
            // Transform each material's run of rows into its column of the block.
            for (m, (f, col)) in data
                .files
                .iter()
                .zip(buf.chunks_exact_mut(rows))
                .enumerate()
            {
                f.copy_raw(r0, &mut s.raw);
                t.forward_raw_rows(bins, r0, &s.raw, col);
                if tally(&s.raw, col, &mut s.measured, &mut s.mean)
                    && let Err(e) = f.check_values(r0, &s.raw)
                {
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
            // the store holds), lay the block out bin-major for the file, and
            // add its products.
            let bytes: &[u8] = match precision {
                Precision::F32 => {
                    let out = &mut bytemuck::cast_slice_mut::<f64, f32>(&mut s.out)[..rows * n];
                    let narrow =
                        &mut bytemuck::cast_slice_mut::<f64, f32>(&mut s.narrow)[..rows * n];
                    centre_bin_major_f32(buf, &s.mean, out, narrow);
                    syrk_lower_add_f32(narrow, rows, acc);
                    bytemuck::cast_slice(out)
                }
                Precision::F64 => {
                    let out = &mut s.out[..rows * n];
                    let narrow = &mut s.narrow[..rows * n];
                    centre_bin_major(buf, &s.mean, out, narrow, |v| v);
                    syrk_lower_add(narrow, rows, acc);
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
    // An input truncated or rewritten during the pass (its reads gave
    // zeros, or a mix of old and new values) is the error, before anything
    // read from it.
    for f in &data.files {
        f.verify()?;
    }
    if let Some((_, e)) = bad_value.into_inner().expect("no panics while locked") {
        return Err(e);
    }
    if let Some(e) = write_error.into_inner().expect("no panics while locked") {
        return Err(CoreError::write(out, e));
    }
    // Dated a second before now: a later write to the store, however soon,
    // gives it another modification time, so the identity a model records
    // (`Store::identity`) is never that of a store changed since.
    let written = std::time::SystemTime::now() - std::time::Duration::from_secs(1);
    file.set_modified(written)
        .map_err(|e| CoreError::write(out, e))?;
    let mapped = file.try_clone().map_err(|e| CoreError::io(out, e))?;
    let store = Store::from_file(mapped, out)?;
    Ok((store, y))
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::data::synth_dir;
    use crate::progress::NoProgress;
    use brdf_merl::Dims;

    #[test]
    fn vector_centring_gives_the_scalar_bits() {
        let mut rng = brdf_merl::synth::SplitMix64::new(3);
        // Odd sizes exercise the remainders of the 4 x 4 tiles.
        for (rows, n) in [(37, 10), (8, 4), (3, 3), (1024, 100)] {
            let block: Vec<f64> = (0..rows * n).map(|_| rng.range(-5.0, 5.0) * 1e3).collect();
            let mean: Vec<f64> = (0..rows).map(|_| rng.range(-1.0, 1.0)).collect();
            let (mut oa, mut ob) = (vec![0f32; rows * n], vec![0f32; rows * n]);
            let (mut na, mut nb) = (vec![0f32; rows * n], vec![0f32; rows * n]);
            centre_bin_major_f32(&block, &mean, &mut oa, &mut na);
            centre_bin_major(&block, &mean, &mut ob, &mut nb, |v| v as f32);
            assert_eq!(oa, ob);
            assert_eq!(na, nb);
            // And the layouts: value r of material i at out[r * n + i] and
            // narrow[i * rows + r], both the centred value rounded.
            for (i, col) in block.chunks_exact(rows).enumerate() {
                for (r, v) in col.iter().enumerate() {
                    assert_eq!(oa[r * n + i], (v - mean[r]) as f32);
                    assert_eq!(na[i * rows + r], (v - mean[r]) as f32);
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
        for transform in TransformKind::ALL {
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
    fn a_scratch_store_is_the_named_store_and_leaves_no_file() {
        let tmp = tempfile::tempdir().unwrap();
        let dims = Dims::new(6, 6, 12).unwrap();
        synth_dir(tmp.path(), 4, dims);
        let data = Dataset::open_dir(tmp.path()).unwrap();
        let work = tmp.path().join("work");
        std::fs::create_dir(&work).unwrap();
        for precision in [Precision::F64, Precision::F32] {
            let named = tmp.path().join(format!("named-{}.store", precision.name()));
            let (a, ya) =
                build_store(&data, TransformKind::Log, precision, &named, &NoProgress).unwrap();
            let name = work.join("scratch.store");
            let (b, yb) =
                build_scratch_store(&data, TransformKind::Log, precision, &name, &NoProgress)
                    .unwrap();
            let c = b.try_clone().unwrap();
            drop(b);
            assert_eq!(ya, yb);
            assert_eq!(c.path(), name);
            assert_eq!(c.len_bytes(), a.len_bytes());
            assert_eq!(c.mean(), a.mean());
            assert_eq!(c.unmeasured(), a.unmeasured());
            let (mut ra, mut rc) = (vec![0.0; 4], vec![0.0; 4]);
            for row in 0..dims.values() {
                a.copy_rows(row, &mut ra);
                c.copy_rows(row, &mut rc);
                assert_eq!(ra, rc, "row {row}");
            }
            assert_eq!(c.gram(&NoProgress), ya);
            // Nothing in the directory it is named in, hidden files included.
            assert_eq!(std::fs::read_dir(&work).unwrap().count(), 0);
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
}
