//! Benchmarks of the fitted model: optimisation on a real Gram matrix,
//! full reconstruction, point queries and albedo maps.
//!
//! Data: the directory named by `BRDF_ATLAS_NBRDF_DIR` (MERL files, e.g.
//! the 100 NBRDF-derived materials from `brdf-atlas nbrdf`),
//! or else 16 synthetic materials at 90 x 90 x 180. The models are fitted
//! once before timing starts (and the log model's map prepared, unless
//! `BRDF_ATLAS_PREPARED_MODEL` names a model prepared before). Run with `cargo bench --bench atlas`.

mod common;

use std::hint::black_box;
use std::path::Path;

use brdf_atlas_core::{BlendRule, View};
use brdf_atlas_core::{FitOptions, fit_dir};
use brdf_atlas_core::{
    GplvmParams, GramData, Model, NoProgress, OptimizerKind, Precision, TransformKind,
};
use brdf_merl::angles::direction;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

fn fit(data: &Path, out: &Path, transform: TransformKind) -> brdf_atlas_core::Atlas {
    let options = FitOptions {
        params: GplvmParams::new(2).check().expect("defaults"),
        transform,
        precision: Precision::F32,
    };
    fit_dir(data, out, &options, &NoProgress).expect("fit");
    brdf_atlas_core::Atlas::new(Model::open(out).expect("open model"))
}

fn atlas(c: &mut Criterion) {
    let tmp = tempfile::tempdir().expect("temporary directory");
    let data = common::data_dir(tmp.path());
    let raw = fit(&data, &tmp.path().join("raw.atlas"), TransformKind::Raw);
    let log = fit(&data, &tmp.path().join("log.atlas"), TransformKind::Log);

    let mut g = c.benchmark_group("optimise");
    g.sample_size(10);
    for (name, model) in [("raw", &raw), ("log", &log)] {
        let gram = GramData::new(model.gram().clone(), model.store().rows()).expect("gram");
        for kind in [OptimizerKind::HookeJeeves, OptimizerKind::Lbfgs] {
            let params = GplvmParams::new(2)
                .optimizer(kind)
                .check()
                .expect("defaults");
            g.bench_function(BenchmarkId::new(kind.name(), name), |b| {
                b.iter(|| params.fit(black_box(&gram), &NoProgress).expect("fit"))
            });
        }
    }
    g.finish();

    let mut g = c.benchmark_group("reconstruct");
    g.sample_size(10);
    let x = [0.1, -0.2];
    g.bench_function("full_table_log", |b| {
        b.iter(|| {
            log.at(black_box(&x), brdf_atlas_core::BlendRule::Gp)
                .expect("point")
                .table()
        })
    });
    let blend = log.at(&x, brdf_atlas_core::BlendRule::Gp).expect("point");
    let bins = log.dims().bins();
    let count = 100_000;
    g.throughput(Throughput::Elements(count as u64));
    // A fresh blend each time: every bin is computed (memory-bound).
    g.bench_function("point_bins_log_first_touch", |b| {
        b.iter(|| {
            let blend = log
                .at(black_box(&x), brdf_atlas_core::BlendRule::Gp)
                .expect("point");
            let mut s = 0.0;
            for k in 0..count {
                if let Some(v) = blend.rgb((k * 7919) % bins) {
                    s += v[0];
                }
            }
            s
        })
    });
    // The same blend again and again: bins asked before are remembered.
    g.bench_function("point_bins_log", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for k in 0..count {
                if let Some(v) = blend.rgb((k * 7919) % bins) {
                    s += v[0];
                }
            }
            s
        })
    });
    let pairs: Vec<_> = (0..count)
        .map(|k| {
            (
                direction(0.3 + (k % 50) as f64 * 0.02, 0.0),
                direction(0.5, 1.0 + (k % 97) as f64 * 0.05),
            )
        })
        .collect();
    g.bench_function("eval_directions_log", |b| {
        b.iter(|| blend.eval_batch(black_box(&pairs)))
    });
    g.finish();

    let mut g = c.benchmark_group("map");
    g.sample_size(10);
    // The GP blend's map of a raw model: exact and linear in the weights.
    g.bench_function("raw_linear_1024", |b| {
        b.iter(|| {
            raw.map(brdf_atlas_core::MapRequest::new(1024, 1024).rule(BlendRule::Gp))
                .expect("map")
        })
    });
    // The default log map (the soft floor's material) of 1024 x 1024 pixels: of the default view (an
    // exact field there would cost more than the per-pixel rule: the
    // sampled field, kept after the first), and of a view a hundred times smaller, the albedo field,
    // first as built from scratch (`build_field`: its exact nodes, the cost
    // of the first map of a region) and then as a map that reuses the
    // model's field (every later map of the region).
    g.bench_function("log_default_1024", |b| {
        b.iter(|| {
            log.map(brdf_atlas_core::MapRequest::new(1024, 1024))
                .expect("map")
        })
    });
    let small = View::zoomed_hundredfold();
    let budget = log.field_budget(1024 * 1024, brdf_atlas_core::DEFAULT_SAMPLES);
    g.bench_function("log_field_build_1/100", |b| {
        b.iter(|| {
            log.build_field(brdf_atlas_core::albedo_field::domain_of(small), budget)
                .expect("field")
        })
    });
    g.bench_function("log_field_1024_1/100", |b| {
        b.iter(|| {
            log.map(brdf_atlas_core::MapRequest::new(1024, 1024).view(small))
                .expect("map")
        })
    });
    for samples in [64usize, 256, 1024] {
        g.bench_function(BenchmarkId::new("log_quadrature_256", samples), |b| {
            b.iter(|| {
                log.map(brdf_atlas_core::MapRequest::new(256, 256).samples(Some(samples)))
                    .expect("map")
            })
        });
    }
    // The map's saved fields (`brdf-atlas fit` builds them): building the
    // default view's and [-3, 3]^2's on a fresh atlas and saving them
    // (what the fit adds), then the first map of a new process (a fresh
    // atlas: the file read, the polynomial evaluated) of the default view,
    // of [-3, 3]^2 and of the map panel's first window (322 x 160, twice
    // as wide as high).
    let fields = brdf_atlas_core::fields_path(log.path());
    let fresh = || brdf_atlas_core::Atlas::new(Model::open(log.path()).expect("open model"));
    let prepare = |atlas: &brdf_atlas_core::Atlas| {
        atlas.prepare_fit_fields(&NoProgress).expect("fields");
    };
    g.bench_function("log_fields_prepare", |b| {
        b.iter_batched(
            || {
                let _ = std::fs::remove_file(&fields);
                fresh()
            },
            |atlas| prepare(&atlas),
            criterion::BatchSize::PerIteration,
        )
    });
    prepare(&fresh());
    let d = View::default();
    let panel = View {
        x0: 2.0 * d.x0,
        x1: 2.0 * d.x1,
        ..d
    };
    for (name, view, (w, h)) in [
        ("default", d, (1024, 1024)),
        ("wide", View::wide(), (1024, 1024)),
        ("panel", panel, (322, 160)),
    ] {
        g.bench_function(BenchmarkId::new("log_saved_fields_first_map", name), |b| {
            b.iter_batched(
                fresh,
                |atlas| {
                    atlas
                        .map(brdf_atlas_core::MapRequest::new(w, h).view(view))
                        .expect("map")
                },
                criterion::BatchSize::PerIteration,
            )
        });
    }
    // The panel's preview of its first window (a sixth of its side) on an
    // atlas that has read the fields: drawn from the saved field, and, as
    // before previews took held fields, from 64 samples a pixel.
    let warm = fresh();
    let (pw, ph) = (322usize.div_ceil(6), 160usize.div_ceil(6));
    let request = || brdf_atlas_core::MapRequest::new(pw, ph).view(panel);
    warm.map(request().preview(64)).expect("the fields read");
    for (name, request) in [
        ("from_field", request().preview(64)),
        ("per_pixel_64", request().samples(Some(64))),
    ] {
        g.bench_function(BenchmarkId::new("log_panel_preview", name), |b| {
            b.iter(|| warm.map(request).expect("preview"))
        });
    }
    std::fs::remove_file(&fields).expect("the fields saved");
    // The prepared map: a 1024 x 1024 map of the default view and of a
    // view a hundred times smaller, each pixel the cubic of the lattice.
    // The lattice is `BRDF_ATLAS_PREPARED_MODEL`'s (a model with its
    // MODEL.lattice beside it, from `brdf-atlas prepare`: minutes for 100
    // materials), or else prepared here for the log model above.
    let prepared = match std::env::var_os("BRDF_ATLAS_PREPARED_MODEL") {
        Some(path) => {
            brdf_atlas_core::Atlas::new(Model::open(path).expect("open the prepared model"))
        }
        None => {
            log.prepare_map(
                BlendRule::Floor,
                brdf_atlas_core::LATTICE_TOLERANCE,
                &NoProgress,
            )
            .expect("prepare")
            .save(&brdf_atlas_core::lattice_path(log.path()))
            .expect("save the lattice");
            brdf_atlas_core::Atlas::new(Model::open(log.path()).expect("open model"))
        }
    };
    assert!(
        prepared.prepared_map().expect("the lattice").is_some(),
        "no lattice beside {}",
        prepared.path().display()
    );
    for (name, view) in [("default", View::default()), ("1/100", small)] {
        g.bench_function(BenchmarkId::new("log_prepared_1024", name), |b| {
            b.iter(|| {
                prepared
                    .map(brdf_atlas_core::MapRequest::new(1024, 1024).view(view))
                    .expect("map")
            })
        });
    }
    g.finish();
}

criterion_group!(benches, atlas);
criterion_main!(benches);
