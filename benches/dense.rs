//! The library's dense kernels against faer's, at the sizes the fit uses:
//! the store pass's Gram update of one block (512 rows of 100 materials,
//! in f64 and, as an f32 store's pass runs it, in f32 lanes,
//! `Y += Z_b^T Z_b`, lower triangle; a 100-material fit does 8 544 of
//! them), the optimiser's refactorisation (Cholesky and inverse of an
//! N x N kernel matrix, N = 100 to 1000; about 1 700 per 100-material fit),
//! and the N x N product of L-BFGS's gradient (`K^-1 Y K^-1`, two a cost
//! evaluation) on one thread and on the default pool, and the symmetric
//! eigen-decomposition of PCA's Gram matrix (N = 100 to 1000). faer is here
//! for scale (its default, parallel, high-level call); the library calls
//! faer at run time only for the eigen-decomposition (see the `dense`
//! module).
//!
//! Run with `cargo bench --bench dense`.

use std::hint::black_box;

use brdf_atlas_core::dense::gram::syrk_lower_add;
use brdf_atlas_core::dense::gram32::syrk_lower_add_f32;
use brdf_atlas_core::dense::product::matmul;
use brdf_atlas_core::dense::{Cholesky, symmetric_eigen};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use faer::linalg::matmul::triangular::{self as tri, BlockStructure};
use faer::linalg::solvers::DenseSolveCore;
use faer::{Accum, Mat, MatRef, Par, Side};

const ROWS: usize = 512;
const N: usize = 100;

fn random(len: usize) -> Vec<f64> {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    (0..len)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}

fn gram(c: &mut Criterion) {
    let block = random(ROWS * N);
    let mut g = c.benchmark_group("gram block 512 x 100");
    g.throughput(Throughput::Elements((ROWS * N * (N + 1) / 2) as u64));
    g.bench_function("dense::gram", |b| {
        let mut acc = vec![0.0f64; N * N];
        b.iter(|| syrk_lower_add(black_box(&block), ROWS, &mut acc));
    });
    // An f32 store's kernel: the same block rounded to f32, summed in f32
    // lanes within the block.
    let narrow: Vec<f32> = block.iter().map(|&v| v as f32).collect();
    g.bench_function("dense::gram32", |b| {
        let mut acc = vec![0.0f64; N * N];
        b.iter(|| syrk_lower_add_f32(black_box(&narrow), ROWS, &mut acc));
    });
    g.bench_function("faer triangular matmul", |b| {
        let mut acc = Mat::<f64>::zeros(N, N);
        let zc = MatRef::from_column_major_slice(&block, ROWS, N);
        b.iter(|| {
            tri::matmul(
                acc.as_mut(),
                BlockStructure::TriangularLower,
                Accum::Add,
                black_box(zc).transpose(),
                BlockStructure::Rectangular,
                zc,
                BlockStructure::Rectangular,
                1.0,
                Par::Seq,
            )
        });
    });
    g.finish();
}

/// An RBF kernel matrix of `n` random points with the fit's noise, 1e-4:
/// condition number up to about `n / 1e-4`.
fn kernel(n: usize) -> Mat<f64> {
    let x = random(2 * n);
    Mat::from_fn(n, n, |i, j| {
        let d2 = (x[2 * i] - x[2 * j]).powi(2) + (x[2 * i + 1] - x[2 * j + 1]).powi(2);
        (-d2 / 2.0).exp() + if i == j { 1e-4 } else { 0.0 }
    })
}

fn refactorise(c: &mut Criterion) {
    let mut g = c.benchmark_group("cholesky and inverse");
    for n in [N, 200, 400, 1000] {
        let k = kernel(n);
        let kc: Vec<f64> = (0..n * n).map(|t| k[(t % n, t / n)]).collect();
        g.bench_with_input(BenchmarkId::new("dense::Cholesky", n), &n, |b, &n| {
            let mut l = Cholesky::with_size(n);
            let (mut out, mut scratch) = (vec![0.0; n * n], Vec::new());
            b.iter(|| {
                l.factor_into(black_box(&kc)).unwrap();
                l.inverse_into(&mut out, &mut scratch);
                black_box(l.log_det())
            });
        });
        g.bench_with_input(BenchmarkId::new("faer llt", n), &n, |b, _| {
            b.iter(|| black_box(black_box(&k).llt(Side::Lower).unwrap().inverse()));
        });
    }
    g.finish();
}

fn product(c: &mut Criterion) {
    let mut g = c.benchmark_group("product n x n");
    for n in [200, 400, 1000] {
        let (a, b) = (random(n * n), random(n * n));
        let mut out = vec![0.0; n * n];
        g.throughput(Throughput::Elements((n * n * n) as u64));
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        g.bench_with_input(
            BenchmarkId::new("dense::product one thread", n),
            &n,
            |bch, &n| {
                one.install(|| bch.iter(|| matmul(black_box(&mut out), &a, &b, n)));
            },
        );
        g.bench_with_input(
            BenchmarkId::new("dense::product default pool", n),
            &n,
            |bch, &n| {
                bch.iter(|| matmul(black_box(&mut out), &a, &b, n));
            },
        );
    }
    g.finish();
}

/// A Gram matrix `Z Z^T` of `n` random points in `2 n` dimensions, as
/// PCA decomposes.
fn gram_matrix(n: usize) -> Mat<f64> {
    let z = random(n * 2 * n);
    let z = MatRef::from_column_major_slice(&z, n, 2 * n);
    z * z.transpose()
}

fn eigen(c: &mut Criterion) {
    let mut g = c.benchmark_group("symmetric eigen");
    g.sample_size(10);
    for n in [N, 400, 1000] {
        let y = gram_matrix(n);
        g.bench_with_input(BenchmarkId::new("dense::symmetric_eigen", n), &n, |b, _| {
            b.iter(|| black_box(symmetric_eigen(black_box(y.as_ref())).unwrap()));
        });
        g.bench_with_input(
            BenchmarkId::new("faer self_adjoint_eigen", n),
            &n,
            |b, _| {
                b.iter(|| black_box(black_box(&y).self_adjoint_eigen(Side::Lower).unwrap()));
            },
        );
    }
    g.finish();
}

/// The shape of a reconstruction or clamp pass at a few latent points: the
/// points' weights (`m x 100`) times a block of 4096 store rows (`100 x
/// 4096`), on one thread.
fn few_points(c: &mut Criterion) {
    let mut g = c.benchmark_group("product of a few points, m x 100 by 100 x 4096");
    let (n, rows) = (100, 4096);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for m in [1, 4, 7] {
        let (a, b) = (random(m * n), random(n * rows));
        let mut out = vec![0.0; m * rows];
        g.throughput(Throughput::Elements((m * n * rows) as u64));
        g.bench_with_input(BenchmarkId::new("dense::product", m), &m, |bch, _| {
            one.install(|| bch.iter(|| matmul(black_box(&mut out), &a, &b, n)));
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = gram, refactorise, product, few_points, eigen
}
criterion_main!(benches);
