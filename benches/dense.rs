//! The library's dense kernels against faer's, at the sizes the fit uses:
//! the store pass's Gram update of one block (512 rows of 100 materials,
//! `Y += Z_b^T Z_b`, lower triangle; a 100-material fit does 8 544 of
//! them), and the optimiser's refactorisation (Cholesky and inverse of a
//! 100 x 100 kernel matrix; about 1 700 per fit). faer is here for scale
//! only: the library does not call it at run time (see the `dense`
//! module).
//!
//! Run with `cargo bench --bench dense`.

use std::hint::black_box;

use brdf_atlas_core::dense::Cholesky;
use brdf_atlas_core::dense::gram::syrk_lower_add;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
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

fn refactorise(c: &mut Criterion) {
    let x = random(2 * N);
    let k = Mat::from_fn(N, N, |i, j| {
        let d2 = (x[2 * i] - x[2 * j]).powi(2) + (x[2 * i + 1] - x[2 * j + 1]).powi(2);
        (-d2 / 2.0).exp() + if i == j { 1e-4 } else { 0.0 }
    });
    let kc: Vec<f64> = (0..N * N).map(|t| k[(t % N, t / N)]).collect();
    let mut g = c.benchmark_group("cholesky and inverse 100 x 100");
    g.bench_function("dense::Cholesky", |b| {
        let mut l = Cholesky::with_size(N);
        let (mut out, mut scratch) = (vec![0.0; N * N], Vec::new());
        b.iter(|| {
            l.factor_into(black_box(&kc)).unwrap();
            l.inverse_into(&mut out, &mut scratch);
            black_box(l.log_det())
        });
    });
    g.bench_function("faer llt", |b| {
        b.iter(|| black_box(black_box(&k).llt(Side::Lower).unwrap().inverse()));
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = gram, refactorise
}
criterion_main!(benches);
