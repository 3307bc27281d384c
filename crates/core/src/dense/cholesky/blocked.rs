//! The blocked kernels behind [`super::Cholesky`]: the factorisation
//! `K = L L^T`, `W = L^-T` (`M = L^-1` by rows) and `K^-1 = W W^T`, on
//! column-major buffers whose leading dimension `ld` is `n` rounded up to
//! [`PAD`].
//!
//! Every entry is one chain of fused multiply-adds in ascending `k`,
//! whatever the blocking: `L[i][j]` is `K[i][j] - L[i][0] L[j][0] - ... -
//! L[i][j-1] L[j][j-1]`, each step `fma(-a, b, acc)`, then a square root
//! (the pivot) or a product with `1 / L[j][j]`; `M[i][j]` (`i > j`) is `0 -
//! L[i][j] M[j][j] - ... - L[i][i-1] M[i-1][j]`, times `M[i][i] = 1 /
//! L[i][i]`; `K^-1[i][j]` (`i >= j`) is `M[i][i] M[i][j] + ... + M[n-1][i]
//! M[n-1][j]`. Blocking only changes when each step runs, never the steps,
//! so the AVX-512, AVX2 and portable paths (which vectorise across
//! outputs, never across `k`) give the same bits as the obvious loops, and
//! the first failing pivot is found at the same index.
//!
//! The work is `O(n^3)` products `C -= A B` over blocks of [`NB`] values
//! of `k` (factorisation: the trailing lower triangle; `W`: the columns
//! right of a block of columns; `W W^T`: the lower triangle), done by
//! register tiles that keep `C` in registers through the block's depth;
//! the `O(n^2 PAD)` rest is the groups of [`PAD`] columns on the diagonal,
//! in plain loops the compiler vectorises. Rows and columns past `n` (up to
//! `ld`) are zeros that the tiles may read and write freely, so tiles need
//! no masks.

/// Rows and columns are padded to a multiple of this: one AVX-512 register,
/// two AVX2 registers.
pub(super) const PAD: usize = 8;

/// Columns (rows) per block: the depth of the tiles' products. The block of
/// `A` a tile column streams (`n x NB`, 512 KiB at n = 1000) stays in L2;
/// a tile's sliver of `B` (`NB x 8`, 4 KiB) stays in L1.
const NB: usize = 64;

/// Which kernels run: chosen once per call from the CPU's features.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Path {
    #[cfg(target_arch = "x86_64")]
    Avx512,
    #[cfg(target_arch = "x86_64")]
    Avx2,
    Portable,
}

impl Path {
    /// The widest path this CPU runs.
    pub(super) fn detect() -> Path {
        #[cfg(target_arch = "x86_64")]
        {
            if crate::simd::has_avx512f() && crate::simd::has_avx2_fma() {
                return Path::Avx512;
            }
            if crate::simd::has_avx2_fma() {
                return Path::Avx2;
            }
        }
        Path::Portable
    }

    /// Every path this CPU can run (the tests compare their bits).
    #[cfg(test)]
    pub(super) fn available() -> Vec<Path> {
        let mut out = vec![Path::Portable];
        #[cfg(target_arch = "x86_64")]
        {
            if crate::simd::has_avx2_fma() {
                out.push(Path::Avx2);
            }
            if crate::simd::has_avx512f() && crate::simd::has_avx2_fma() {
                out.push(Path::Avx512);
            }
        }
        out
    }
}

/// `L` of the `n x n` matrix held in the lower triangle of `l` (column-major,
/// leading dimension `ld`; rows `n..ld` of the first `n` columns zero), in
/// place. `Err(j)`: pivot `j` is the first that is not positive and finite.
/// The strict upper triangle is scratch (left unspecified).
///
/// # Panics
/// When `l` is not `ld x ld` with `ld` the multiple of [`PAD`] at or above
/// `n` (a caller bug).
pub(super) fn factor(path: Path, l: &mut [f64], n: usize) -> Result<(), usize> {
    let ld = n.next_multiple_of(PAD);
    assert_eq!(l.len(), ld * ld);
    match path {
        // SAFETY: `detect` and `available` offer these paths only on CPUs
        // with their features.
        #[cfg(target_arch = "x86_64")]
        Path::Avx512 => unsafe { factor_avx512(l, n) },
        // SAFETY: as above.
        #[cfg(target_arch = "x86_64")]
        Path::Avx2 => unsafe { factor_avx2(l, n) },
        Path::Portable => factor_body::<Portable>(l, n),
    }
}

/// `W = L^-T` into `w` (zeroed here; `ld x ld` like `l`, upper triangle,
/// zero elsewhere) from the factor [`factor`] left in `l`.
///
/// # Panics
/// When `l` or `w` is not `ld x ld` (a caller bug).
pub(super) fn invert(path: Path, l: &[f64], w: &mut [f64], n: usize) {
    let ld = n.next_multiple_of(PAD);
    assert!(l.len() == ld * ld && w.len() == ld * ld);
    w.iter_mut().for_each(|v| *v = 0.0);
    match path {
        // SAFETY: as in `factor`.
        #[cfg(target_arch = "x86_64")]
        Path::Avx512 => unsafe { invert_avx512(l, w, n) },
        // SAFETY: as in `factor`.
        #[cfg(target_arch = "x86_64")]
        Path::Avx2 => unsafe { invert_avx2(l, w, n) },
        Path::Portable => invert_body::<Portable>(l, w, n),
    }
}

/// `-K^-1` (its lower triangle and some scratch above it) into `out`
/// (`ld x ld`) from `W = L^-T` ([`invert`]).
///
/// # Panics
/// When `w` or `out` is not `ld x ld` (a caller bug).
pub(super) fn gram(path: Path, w: &[f64], out: &mut [f64], n: usize) {
    let ld = n.next_multiple_of(PAD);
    assert!(w.len() == ld * ld && out.len() == ld * ld);
    match path {
        // SAFETY: as in `factor`.
        #[cfg(target_arch = "x86_64")]
        Path::Avx512 => unsafe { gram_avx512(w, out, n) },
        // SAFETY: as in `factor`.
        #[cfg(target_arch = "x86_64")]
        Path::Avx2 => unsafe { gram_avx2(w, out, n) },
        Path::Portable => gram_body::<Portable>(w, out, n),
    }
}

/// `C -= A B` on `m x p` outputs over `depth` terms, as offsets into the
/// operands' buffers: `C[i][j]` at `c + i + j ldc`, `A[i][k]` at `a + i + k
/// lda`, `B[k][j]` at `b + k bk + j bj`. `m` and `p` are multiples of
/// [`PAD`]; each output takes its terms in ascending `k`.
#[derive(Clone, Copy, Debug)]
struct Product {
    c: usize,
    ldc: usize,
    a: usize,
    lda: usize,
    b: usize,
    bk: usize,
    bj: usize,
    m: usize,
    p: usize,
    depth: usize,
}

impl Product {
    /// Whether every element the product touches lies inside buffers of
    /// these lengths.
    fn fits(&self, c_len: usize, a_len: usize, b_len: usize) -> bool {
        if self.m == 0 || self.p == 0 || self.depth == 0 {
            return true;
        }
        let last = |off: usize, s1: usize, n1: usize, s2: usize, n2: usize| {
            off + s1 * (n1 - 1) + s2 * (n2 - 1)
        };
        last(self.c, 1, self.m, self.ldc, self.p) < c_len
            && last(self.a, 1, self.m, self.lda, self.depth) < a_len
            && last(self.b, self.bk, self.depth, self.bj, self.p) < b_len
    }
}

/// One path's tiles.
trait Kernel {
    /// [`Product`] on the buffers at `c`, `a`, `b`.
    ///
    /// # Safety
    /// Every element the product touches is inside its buffer, `C`'s
    /// outputs do not overlap what `A` and `B` read, and the CPU has the
    /// path's features.
    unsafe fn sub_product(c: *mut f64, a: *const f64, b: *const f64, pr: &Product);
}

/// [`Kernel::sub_product`] with the bounds checked; `a` and `b` may be `c`'s
/// buffer (regions that do not overlap `C`'s).
#[inline(always)]
fn product<K: Kernel>(
    c: *mut f64,
    c_len: usize,
    a: (*const f64, usize),
    b: (*const f64, usize),
    pr: Product,
) {
    assert!(pr.fits(c_len, a.1, b.1) && pr.m.is_multiple_of(PAD) && pr.p.is_multiple_of(PAD));
    if pr.depth == 0 {
        return;
    }
    // SAFETY: bounds just checked; callers pass disjoint regions and only
    // run a path on a CPU that has it.
    unsafe { K::sub_product(c, a.0, b.0, &pr) }
}

/// The factorisation, blocked by [`NB`] columns: each block's columns take
/// their own earlier columns by groups of [`PAD`] (left-looking within the
/// panel), then the trailing lower triangle takes the whole block.
#[inline(always)]
fn factor_body<K: Kernel>(l: &mut [f64], n: usize) -> Result<(), usize> {
    let ld = n.next_multiple_of(PAD);
    let len = l.len();
    for k0 in (0..n).step_by(NB) {
        let k1 = (k0 + NB).min(n);
        for c0 in (k0..k1).step_by(PAD) {
            // Columns c0..c0 + 8, rows c0.., minus the panel's columns k0..c0.
            let p = l.as_mut_ptr();
            let from = k0 * ld + c0;
            let pr = Product {
                c: c0 * ld + c0,
                ldc: ld,
                a: from,
                lda: ld,
                b: from,
                bk: ld,
                bj: 1,
                m: ld - c0,
                p: PAD,
                depth: c0 - k0,
            };
            product::<K>(p, len, (p, len), (p, len), pr);
            for j in c0..(c0 + PAD).min(n) {
                column(l, ld, c0, j)?;
            }
        }
        if k1 < n {
            // The trailing lower triangle by columns of 8 from the diagonal
            // down, minus the block's columns k0..k1.
            for j0 in (k1..ld).step_by(PAD) {
                let p = l.as_mut_ptr();
                let from = k0 * ld + j0;
                let pr = Product {
                    c: j0 * ld + j0,
                    ldc: ld,
                    a: from,
                    lda: ld,
                    b: from,
                    bk: ld,
                    bj: 1,
                    m: ld - j0,
                    p: PAD,
                    depth: k1 - k0,
                };
                product::<K>(p, len, (p, len), (p, len), pr);
            }
        }
    }
    Ok(())
}

/// Column `j` of `L` from its group's earlier columns `c0..j`, then the pivot
/// and the scaling.
#[inline(always)]
fn column(l: &mut [f64], ld: usize, c0: usize, j: usize) -> Result<(), usize> {
    let (done, rest) = l.split_at_mut(j * ld);
    let col = &mut rest[j..ld];
    for k in c0..j {
        let lk = &done[k * ld + j..k * ld + ld];
        let ljk = lk[0];
        for (c, a) in col.iter_mut().zip(lk) {
            *c = (-a).mul_add(ljk, *c);
        }
    }
    let d = col[0];
    // Not `d <= 0.0`: a NaN pivot fails too.
    if !(d > 0.0 && d.is_finite()) {
        return Err(j);
    }
    let d = d.sqrt();
    col[0] = d;
    let r = 1.0 / d;
    col[1..].iter_mut().for_each(|v| *v *= r);
    Ok(())
}

/// `W = L^-T` (`W[j][i] = M[i][j]`) blocked by [`NB`] columns of `W`: each
/// block's columns take the block's earlier columns by groups of [`PAD`],
/// then finish in plain loops down the columns; the columns to the right
/// take the whole block. Terms `M[t][j]` with `t < j` are zeros met before
/// the chain's first term: the accumulator stays `+0` through them, so
/// including them (as the tiles do) leaves the bits alone.
#[inline(always)]
fn invert_body<K: Kernel>(l: &[f64], w: &mut [f64], n: usize) {
    let ld = n.next_multiple_of(PAD);
    let (llen, wlen) = (l.len(), w.len());
    for i in 0..n {
        w[i * ld + i] = 1.0 / l[i * ld + i];
    }
    for i0 in (0..n).step_by(NB) {
        let i1 = (i0 + NB).min(n);
        for r0 in (i0..i1).step_by(PAD) {
            // Columns r0..r0 + 8, rows ..r0, minus the block's columns i0..r0.
            let p = w.as_mut_ptr();
            let pr = Product {
                c: r0 * ld,
                ldc: ld,
                a: i0 * ld,
                lda: ld,
                b: i0 * ld + r0,
                bk: ld,
                bj: 1,
                m: r0,
                p: PAD,
                depth: r0 - i0,
            };
            product::<K>(p, wlen, (p, wlen), (l.as_ptr(), llen), pr);
            for k in r0..(r0 + PAD).min(n) {
                // Column k is complete: M[k][j] = acc * M[k][k]; then its
                // term in the group's later columns.
                let (left, right) = w.split_at_mut((k + 1) * ld);
                let wk = &mut left[k * ld..k * ld + k + 1];
                let mkk = wk[k];
                wk[..k].iter_mut().for_each(|v| *v *= mkk);
                for (i, wi) in (k + 1..r0 + PAD).zip(right.chunks_exact_mut(ld)) {
                    let lik = l[k * ld + i];
                    for (c, a) in wi[..=k].iter_mut().zip(wk.iter()) {
                        *c = (-lik).mul_add(*a, *c);
                    }
                }
            }
        }
        if i1 < n {
            let p = w.as_mut_ptr();
            let pr = Product {
                c: i1 * ld,
                ldc: ld,
                a: i0 * ld,
                lda: ld,
                b: i0 * ld + i1,
                bk: ld,
                bj: 1,
                m: i1,
                p: ld - i1,
                depth: i1 - i0,
            };
            product::<K>(p, wlen, (p, wlen), (l.as_ptr(), llen), pr);
        }
    }
}

/// `-K^-1 = -W W^T`, lower triangle, into `out`: output `(i, j)`, `i >= j`,
/// is the chain of `fma(-W[i][k], W[j][k], acc)` over `k = i..n` from zero.
/// Negating it gives the bits of the chain of `fma(W[i][k], W[j][k], acc)`,
/// rounding being symmetric. Blocked by [`NB`] values of `k` (the block's
/// columns of `W` stay in L2), in ascending order; within a block each tile
/// of rows from `i0` starts at `k = i0`: the terms before are zeros, met
/// while the accumulator is still `+0`, so leaving them out (or not, for
/// the tile's later rows) leaves the bits alone.
#[inline(always)]
fn gram_body<K: Kernel>(w: &[f64], out: &mut [f64], n: usize) {
    let ld = n.next_multiple_of(PAD);
    let (wlen, olen) = (w.len(), out.len());
    for (j, col) in out.chunks_exact_mut(ld).enumerate() {
        col[j / PAD * PAD..].iter_mut().for_each(|v| *v = 0.0);
    }
    for k0 in (0..n).step_by(NB) {
        let k1 = (k0 + NB).min(n);
        // Rows below k1 take no term from this block.
        let rows = k1.next_multiple_of(PAD);
        for j0 in (0..k1).step_by(PAD) {
            let mut i0 = j0;
            while i0 < rows {
                let m = (rows - i0).min(3 * PAD);
                let from = k0.max(i0);
                let pr = Product {
                    c: j0 * ld + i0,
                    ldc: ld,
                    a: from * ld + i0,
                    lda: ld,
                    b: from * ld + j0,
                    bk: ld,
                    bj: 1,
                    m,
                    p: PAD,
                    depth: k1 - from,
                };
                product::<K>(
                    out.as_mut_ptr(),
                    olen,
                    (w.as_ptr(), wlen),
                    (w.as_ptr(), wlen),
                    pr,
                );
                i0 += m;
            }
        }
    }
}

struct Portable;

impl Kernel for Portable {
    #[inline(always)]
    unsafe fn sub_product(c: *mut f64, a: *const f64, b: *const f64, pr: &Product) {
        for j in 0..pr.p {
            for k in 0..pr.depth {
                // SAFETY (all three): inside the buffers by the caller's
                // contract.
                let bkj = unsafe { *b.add(pr.b + k * pr.bk + j * pr.bj) };
                for i in 0..pr.m {
                    unsafe {
                        let cij = c.add(pr.c + i + j * pr.ldc);
                        let aik = *a.add(pr.a + i + k * pr.lda);
                        *cij = (-aik).mul_add(bkj, *cij);
                    }
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
struct Avx512;

#[cfg(target_arch = "x86_64")]
impl Kernel for Avx512 {
    #[inline(always)]
    unsafe fn sub_product(c: *mut f64, a: *const f64, b: *const f64, pr: &Product) {
        // SAFETY: the caller's contract.
        unsafe { tiles_avx512(c, a, b, pr) }
    }
}

#[cfg(target_arch = "x86_64")]
struct Avx2;

#[cfg(target_arch = "x86_64")]
impl Kernel for Avx2 {
    #[inline(always)]
    unsafe fn sub_product(c: *mut f64, a: *const f64, b: *const f64, pr: &Product) {
        // SAFETY: the caller's contract.
        unsafe { tiles_avx2(c, a, b, pr) }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn factor_avx512(l: &mut [f64], n: usize) -> Result<(), usize> {
    factor_body::<Avx512>(l, n)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn factor_avx2(l: &mut [f64], n: usize) -> Result<(), usize> {
    factor_body::<Avx2>(l, n)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn invert_avx512(l: &[f64], w: &mut [f64], n: usize) {
    invert_body::<Avx512>(l, w, n)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn invert_avx2(l: &[f64], w: &mut [f64], n: usize) {
    invert_body::<Avx2>(l, w, n)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn gram_avx512(w: &[f64], out: &mut [f64], n: usize) {
    gram_body::<Avx512>(w, out, n)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn gram_avx2(w: &[f64], out: &mut [f64], n: usize) {
    gram_body::<Avx2>(w, out, n)
}

/// Tiles of `8 V` rows (`V` registers) by 8 columns: `8 V` accumulators
/// loaded from `C`, one load of `A` per register and one broadcast of `B`
/// per column at each `k`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn tiles_avx512(c: *mut f64, a: *const f64, b: *const f64, pr: &Product) {
    for j0 in (0..pr.p).step_by(8) {
        let mut i0 = 0;
        while i0 < pr.m {
            let left = pr.m - i0;
            // SAFETY (the three): the tile lies inside the product, which
            // lies inside the buffers by the caller's contract.
            unsafe {
                if left >= 24 {
                    tile_avx512::<3>(c, a, b, pr, i0, j0);
                    i0 += 24;
                } else if left >= 16 {
                    tile_avx512::<2>(c, a, b, pr, i0, j0);
                    i0 += 16;
                } else {
                    tile_avx512::<1>(c, a, b, pr, i0, j0);
                    i0 += 8;
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline]
unsafe fn tile_avx512<const V: usize>(
    c: *mut f64,
    a: *const f64,
    b: *const f64,
    pr: &Product,
    i0: usize,
    j0: usize,
) {
    use std::arch::x86_64::*;
    // SAFETY (all loads and stores): rows i0..i0 + 8V and columns
    // j0..j0 + 8 lie inside the product (caller's contract).
    unsafe {
        let cp = c.add(pr.c + i0 + j0 * pr.ldc);
        let ap = a.add(pr.a + i0);
        let bp = b.add(pr.b + j0 * pr.bj);
        // acc[j][v]: column j, rows 8 v..8 v + 8 of the tile.
        let mut acc = [[_mm512_setzero_pd(); V]; 8];
        for (j, col) in acc.iter_mut().enumerate() {
            for (v, x) in col.iter_mut().enumerate() {
                *x = _mm512_loadu_pd(cp.add(8 * v + j * pr.ldc));
            }
        }
        for k in 0..pr.depth {
            let ak = ap.add(k * pr.lda);
            let x: [__m512d; V] = std::array::from_fn(|v| _mm512_loadu_pd(ak.add(8 * v)));
            let bk = bp.add(k * pr.bk);
            for (j, col) in acc.iter_mut().enumerate() {
                let y = _mm512_set1_pd(*bk.add(j * pr.bj));
                for (c, xv) in col.iter_mut().zip(&x) {
                    *c = _mm512_fnmadd_pd(*xv, y, *c);
                }
            }
        }
        for (j, col) in acc.iter().enumerate() {
            for (v, x) in col.iter().enumerate() {
                _mm512_storeu_pd(cp.add(8 * v + j * pr.ldc), *x);
            }
        }
    }
}

/// Tiles of `4 V` rows by 4 columns in AVX2 registers (12 accumulators in
/// the 16 registers), the same operations per output as the other paths.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn tiles_avx2(c: *mut f64, a: *const f64, b: *const f64, pr: &Product) {
    for j0 in (0..pr.p).step_by(4) {
        let mut i0 = 0;
        while i0 < pr.m {
            let left = pr.m - i0;
            // SAFETY: as in `tiles_avx512`.
            unsafe {
                if left >= 12 {
                    tile_avx2::<3>(c, a, b, pr, i0, j0);
                    i0 += 12;
                } else if left >= 8 {
                    tile_avx2::<2>(c, a, b, pr, i0, j0);
                    i0 += 8;
                } else {
                    tile_avx2::<1>(c, a, b, pr, i0, j0);
                    i0 += 4;
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
unsafe fn tile_avx2<const V: usize>(
    c: *mut f64,
    a: *const f64,
    b: *const f64,
    pr: &Product,
    i0: usize,
    j0: usize,
) {
    use std::arch::x86_64::*;
    // SAFETY (all loads and stores): rows i0..i0 + 4V and columns
    // j0..j0 + 4 lie inside the product (caller's contract).
    unsafe {
        let cp = c.add(pr.c + i0 + j0 * pr.ldc);
        let ap = a.add(pr.a + i0);
        let bp = b.add(pr.b + j0 * pr.bj);
        // acc[j][v]: column j, rows 4 v..4 v + 4 of the tile.
        let mut acc = [[_mm256_setzero_pd(); V]; 4];
        for (j, col) in acc.iter_mut().enumerate() {
            for (v, x) in col.iter_mut().enumerate() {
                *x = _mm256_loadu_pd(cp.add(4 * v + j * pr.ldc));
            }
        }
        for k in 0..pr.depth {
            let ak = ap.add(k * pr.lda);
            let x: [__m256d; V] = std::array::from_fn(|v| _mm256_loadu_pd(ak.add(4 * v)));
            let bk = bp.add(k * pr.bk);
            for (j, col) in acc.iter_mut().enumerate() {
                let y = _mm256_broadcast_sd(&*bk.add(j * pr.bj));
                for (c, xv) in col.iter_mut().zip(&x) {
                    *c = _mm256_fnmadd_pd(*xv, y, *c);
                }
            }
        }
        for (j, col) in acc.iter().enumerate() {
            for (v, x) in col.iter().enumerate() {
                _mm256_storeu_pd(cp.add(4 * v + j * pr.ldc), *x);
            }
        }
    }
}
