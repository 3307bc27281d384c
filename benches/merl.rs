//! Benchmarks of the MERL format crate at full resolution (90 x 90 x 180):
//! read and validate a file, build the dense albedo rule, integrate one
//! table's albedo, tabulate a synthetic material. Inputs come from the
//! synthetic database, written to a temporary directory; after the first
//! iteration the file is in the page cache, so reads are warm.
//!
//! Run with `cargo bench --bench merl`; the performance table in docs/performance.md
//! quotes the medians criterion writes to `target/criterion/*/new/estimates.json`.

use std::hint::black_box;

use brdf_merl::synth::database;
use brdf_merl::{Dims, MerlFile, MerlTable, Quadrature};
use criterion::{Criterion, criterion_group, criterion_main};

fn merl(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temporary directory");
    let material = &database(1, 1)[0];
    let table = material.brdf.table(Dims::MERL);
    let path = dir.path().join(format!("{}.binary", material.name));
    table.write(&path).expect("write the input");

    let mut g = c.benchmark_group("merl_90x90x180");
    // MerlFile::open: map the file, check header and size, scan every value.
    g.bench_function("open_validate", |b| {
        b.iter(|| MerlFile::open(black_box(&path)).expect("valid"))
    });
    // MerlTable::read: the same, then copy the 4.4M values into memory.
    g.bench_function("read_table", |b| {
        b.iter(|| MerlTable::read(black_box(&path)).expect("valid"))
    });
    g.bench_function("quadrature_dense_sub2", |b| {
        b.iter(|| Quadrature::dense(black_box(Dims::MERL), 2))
    });
    let rule = Quadrature::dense(Dims::MERL, 2);
    g.bench_function("albedo", |b| b.iter(|| rule.albedo(black_box(&table))));
    g.bench_function("synth_table", |b| {
        b.iter(|| material.brdf.table(black_box(Dims::MERL)))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = merl
}
criterion_main!(benches);
