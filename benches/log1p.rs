//! The log transform's hot loop: `log1p` of a reflectance times a cosine
//! product, over a buffer of 4096 values (in L1: the compute cost alone; a
//! fit does 437 million). `std` is `f64::ln_1p` for scale.
//!
//! Run with `cargo bench --bench log1p`.

use std::hint::black_box;

use brdf_atlas_core::TransformKind;
use brdf_atlas_core::fastlog;
use brdf_merl::Dims;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

const LEN: usize = 4096;

/// MERL-like raw values: log-uniform over 1e-3 .. 1e4, every 16th unmeasured (-1).
fn raw_values() -> Vec<f64> {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    (0..LEN)
        .map(|k| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let t = (s >> 11) as f64 / (1u64 << 53) as f64;
            if k % 16 == 0 {
                -1.0
            } else {
                10f64.powf(-3.0 + 7.0 * t)
            }
        })
        .collect()
}

fn log1p(c: &mut Criterion) {
    let raw = raw_values();
    // Cosine products of real MERL bins, so x = f cos_i cos_o spans what a fit sees.
    let transform = TransformKind::Log.build(Dims::MERL);
    let (channel, bin0) = (1, 700_000);
    let x: Vec<f64> = raw.iter().map(|&v| v.max(0.0) * 0.37).collect();
    let mut out = vec![0.0; LEN];

    let mut g = c.benchmark_group("log1p");
    g.throughput(Throughput::Elements(LEN as u64));
    g.bench_function("transform run (dispatched)", |b| {
        b.iter(|| {
            transform.forward_raw_run(channel, bin0, black_box(&raw), &mut out);
            black_box(&out);
        })
    });
    g.bench_function("fastlog::log1p (portable loop)", |b| {
        b.iter(|| {
            for (o, &v) in out.iter_mut().zip(black_box(&x)) {
                *o = fastlog::log1p(v);
            }
            black_box(&out);
        })
    });
    g.bench_function("std ln_1p", |b| {
        b.iter(|| {
            for (o, &v) in out.iter_mut().zip(black_box(&x)) {
                *o = v.ln_1p();
            }
            black_box(&out);
        })
    });
    g.finish();
}

criterion_group!(benches, log1p);
criterion_main!(benches);
