//! Benchmarks of a whole fit and its phases, as `brdf-atlas fit` runs them:
//! the store pass (read, check and transform every value, centre, write the
//! f32 store, accumulate the Gram matrix), the optimisation on that Gram
//! matrix (L-BFGS, the default, and Hooke-Jeeves), and the whole `fit_dir`
//! with the defaults (open, store pass, optimise, save) into a
//! fresh output. Before timing, one fit prints its peak heap (counted by
//! the allocator; the inputs and the store are mapped files, not heap).
//!
//! Data: the directory named by `BRDF_ATLAS_NBRDF_DIR` (e.g. the 100
//! NBRDF-derived materials from `brdf-atlas nbrdf`), or else 16
//! synthetic materials at 90 x 90 x 180. Page cache warm: every input has
//! been read by the fit before timing. Run with `cargo bench --bench fit`.

mod common;

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use brdf_atlas_core::{Dataset, build_store};
use brdf_atlas_core::{FitOptions, fit_dir, store_path_for};
use brdf_atlas_core::{GplvmParams, GramData, NoProgress, OptimizerKind, Precision};
use brdf_atlas_core::{TransformKind, heap};
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};

#[global_allocator]
static HEAP: heap::Counting = heap::Counting;

/// Remove a model and its store, so the next fit writes fresh files (a
/// re-fit over old files also pays for freeing the old store's pages).
fn remove_outputs(model: &Path) {
    let _ = std::fs::remove_file(model);
    let _ = std::fs::remove_file(store_path_for(model));
}

fn fit(c: &mut Criterion) {
    let tmp = tempfile::tempdir().expect("temporary directory");
    let data = common::data_dir(tmp.path());
    let model = tmp.path().join("bench.atlas");
    let options = FitOptions {
        params: GplvmParams::new(2).check().expect("defaults"),
        transform: TransformKind::Log,
        precision: Precision::F32,
    };
    let report = fit_dir(&data, &model, &options, &NoProgress).expect("fit");
    eprintln!(
        "fit of {} materials: peak heap {:.1} MB; scan {:.3} s, store+Gram {:.3} s, optimise {:.3} s, save {:.3} s",
        report.names.len(),
        report.peak_heap.unwrap_or(0) as f64 / 1e6,
        report.scan_time.as_secs_f64(),
        report.store_time.as_secs_f64(),
        report.optimise_time.as_secs_f64(),
        report.save_time.as_secs_f64(),
    );
    remove_outputs(&model);

    let mut g = c.benchmark_group("fit");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(30));
    let files = Dataset::map_dir(&data).expect("data");
    let store = tmp.path().join("bench.store");
    g.bench_function("store_pass_log_f32", |b| {
        b.iter_batched(
            || {
                let _ = std::fs::remove_file(&store);
            },
            |()| {
                build_store(
                    black_box(&files),
                    TransformKind::Log,
                    Precision::F32,
                    &store,
                    &NoProgress,
                )
                .expect("store")
            },
            BatchSize::PerIteration,
        )
    });
    let (_, y) = build_store(
        &files,
        TransformKind::Log,
        Precision::F32,
        &store,
        &NoProgress,
    )
    .expect("store");
    let gram = GramData::new(y, 3 * files.dims().bins()).expect("gram");
    let hooke_jeeves = GplvmParams::new(2)
        .optimizer(OptimizerKind::HookeJeeves)
        .check()
        .expect("defaults");
    for (name, params) in [
        ("optimise_lbfgs_log", &options.params),
        ("optimise_hooke_jeeves_log", &hooke_jeeves),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| params.fit(black_box(&gram), &NoProgress).expect("fit"))
        });
    }
    let _ = std::fs::remove_file(&store);
    g.bench_function("fit_dir_log_fresh_output", |b| {
        b.iter_batched(
            || remove_outputs(&model),
            |()| fit_dir(black_box(&data), &model, &options, &NoProgress).expect("fit"),
            BatchSize::PerIteration,
        )
    });
    g.finish();
    remove_outputs(&model);
}

criterion_group!(benches, fit);
criterion_main!(benches);
