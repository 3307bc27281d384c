//! Benchmark of `brdf-atlas swatches`' work: an 8 x 8 sheet of 128-pixel
//! lit spheres over the map's default view (point queries, shading, layout),
//! with the GP's blend and with the plausible rule (whose steps for the 64
//! points take one pass over the store); and the plausible rule at one point.
//!
//! Model: the file named by `BRDF_ATLAS_BENCH_MODEL` (e.g. the 100
//! NBRDF-derived materials, log transform), or else one fitted before timing
//! to the data of `common::data_dir`. Run with `cargo bench --bench swatches`.

mod common;

use std::hint::black_box;

use brdf_atlas_core::{BlendRule, View, fit_dir};
use brdf_atlas_core::{FitOptions, GplvmParams, Model, NoProgress, Precision, TransformKind};
use brdf_atlas_pictures::sphere::DEFAULT_LIGHTS;
use brdf_atlas_pictures::swatch_sheet;
use criterion::{Criterion, criterion_group, criterion_main};

fn swatches(c: &mut Criterion) {
    let tmp = tempfile::tempdir().expect("temporary directory");
    let model = match std::env::var_os("BRDF_ATLAS_BENCH_MODEL") {
        Some(path) => {
            brdf_atlas_core::Atlas::new(Model::open(path).expect("open BRDF_ATLAS_BENCH_MODEL"))
        }
        None => {
            let data = common::data_dir(tmp.path());
            let out = tmp.path().join("log.atlas");
            let options = FitOptions {
                params: GplvmParams::new(2).check().expect("defaults"),
                transform: TransformKind::Log,
                precision: Precision::F32,
            };
            fit_dir(&data, &out, &options, &NoProgress).expect("fit");
            brdf_atlas_core::Atlas::new(Model::open(out).expect("open model"))
        }
    };
    let points = swatch_sheet::grid_points(&View::default(), 8);
    let mut g = c.benchmark_group("swatches");
    g.sample_size(10);
    for (name, rule) in [
        ("sheet_8x8_128px", BlendRule::Floor),
        ("sheet_8x8_128px_gp", BlendRule::Gp),
        ("sheet_8x8_128px_plausible", BlendRule::Plausible),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let s = swatch_sheet::swatches(
                    &model,
                    black_box(&points),
                    None,
                    128,
                    &DEFAULT_LIGHTS,
                    rule,
                )
                .expect("swatches");
                swatch_sheet::compose(&s, 8)
            })
        });
    }
    g.bench_function("plausible_rule_one_point", |b| {
        b.iter(|| {
            let blend = model.at(black_box(&points[9]), BlendRule::Plausible);
            blend.expect("plausible blend").steps().is_some()
        })
    });
    g.finish();
}

criterion_group!(benches, swatches);
criterion_main!(benches);
