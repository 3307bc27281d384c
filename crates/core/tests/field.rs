//! The albedo field against an independent reference: the map's albedo at
//! random pixels of views a hundred times smaller than the default (and of
//! any view whose field fits its budget) against the dense rule applied to
//! the full reconstruction there (`Model::at` -> every bin ->
//! `Quadrature::integrate`), within 1% of the pixel's largest channel; its
//! variance against the exact variance map, within 0.01; the per-pixel rule
//! where the field would cost more; and the same bits whatever the thread
//! count.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use brdf_atlas_core::map_error::reference_albedo;
use brdf_atlas_core::{
    AlbedoMap, AlbedoMethod, BlendRule, CoreError, FitOptions, GplvmParams, Model, NoProgress,
    Precision, Progress, TransformKind, View, fit_dir,
};
use brdf_merl::{Dims, Quadrature, synth};

const DIMS: Dims = Dims {
    theta_h: 8,
    theta_d: 8,
    phi_d: 16,
};

fn fit(dir: &Path, count: usize, transform: TransformKind) -> PathBuf {
    let data = dir.join(format!("data-{count}"));
    synth::write_dir(&data, count, DIMS, 5).unwrap();
    let model = dir.join(format!("m-{count}-{}.atlas", transform.name()));
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform,
        precision: Precision::F32,
    };
    fit_dir(&data, &model, &options, &NoProgress).unwrap();
    model
}

/// `count` pixels of a `side x side` map from a seeded generator.
fn random_pixels(side: usize, count: usize, seed: u64) -> Vec<(usize, usize)> {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((s >> 33) as usize) % side
    };
    (0..count).map(|_| (next(), next())).collect()
}

/// Largest error of `map` at `pixels` against the dense reference, relative
/// to the reference's largest channel.
fn worst_error(model: &Model, map: &AlbedoMap, pixels: &[(usize, usize)]) -> f64 {
    let rule = model.albedo_rule();
    let mut worst = 0.0f64;
    for &(px, py) in pixels {
        let x = map
            .view
            .pixel_to_latent(px as f64, py as f64, map.width, map.height);
        let want = reference_albedo(model, &x, map.blend, rule).unwrap();
        let got = map.rgb[py * map.width + px];
        let scale = want.iter().fold(1e-9f64, |a, v| a.max(v.abs()));
        for c in 0..3 {
            worst = worst.max((f64::from(got[c]) - want[c]).abs() / scale);
        }
    }
    worst
}

/// Largest difference of the map's variance from the exact variance map.
fn variance_error(model: &brdf_atlas_core::Atlas, map: &AlbedoMap) -> f64 {
    let exact = model.variance_map(map.width, map.height, map.view).unwrap();
    exact
        .iter()
        .zip(&map.variance)
        .map(|(a, b)| f64::from((a - b).abs()))
        .fold(0.0, f64::max)
}

/// A view `1 / zoom` the default's side, centred at `c`.
fn zoomed(c: [f64; 2], zoom: f64) -> View {
    let h = View::default().x1 / zoom;
    View {
        x0: c[0] - h,
        x1: c[0] + h,
        y0: c[1] - h,
        y1: c[1] + h,
    }
}

#[test]
fn field_map_is_within_one_percent_of_the_dense_rule_at_every_zoom() {
    let tmp = tempfile::tempdir().unwrap();
    let model =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, TransformKind::Log)).unwrap());
    let side = 96;
    let latent = model.latent();
    let views = [
        View::default(),
        // A hundred times smaller, round a material and between materials.
        zoomed([latent[(3, 0)], latent[(3, 1)]], 100.0),
        zoomed([0.137, -0.291], 100.0),
        // Partly outside the default view: a domain of its own.
        View {
            x0: 0.6,
            x1: 1.9,
            y0: -1.5,
            y1: -0.2,
        },
    ];
    let mut fields = 0;
    for (k, view) in views.into_iter().enumerate() {
        let map = model
            .map(brdf_atlas_core::MapRequest::new(side, side).view(view))
            .unwrap();
        let worst = worst_error(&model, &map, &random_pixels(side, 40, 7 + k as u64));
        match map.method {
            AlbedoMethod::Field {
                nodes, estimate, ..
            } => {
                fields += 1;
                assert!(nodes >= 25, "{nodes}");
                assert!(
                    worst <= 0.01,
                    "view {view:?}: worst error {worst:.3e} (estimate {estimate:.2e})"
                );
                let verr = variance_error(&model, &map);
                assert!(verr <= 0.01, "view {view:?}: variance off by {verr:.3e}");
            }
            // A domain whose field would cost more than integrating every
            // pixel falls back to the per-pixel rule.
            AlbedoMethod::Quadrature { samples, .. } => {
                assert_eq!(samples, brdf_atlas_core::DEFAULT_SAMPLES);
                // Its error is several percent (docs/performance.md); only sane here.
                assert!(worst <= 0.25, "view {view:?}: worst error {worst:.3e}");
                assert_eq!(variance_error(&model, &map), 0.0);
            }
            // Exact nodes over budget: nodes of the sampled rule, whose
            // error is the per-pixel rule's kind (tested on its own below).
            AlbedoMethod::SampledField { samples, .. } => {
                assert_eq!(samples, brdf_atlas_core::FIELD_SAMPLES);
                assert!(worst <= 0.25, "view {view:?}: worst error {worst:.3e}");
                let verr = variance_error(&model, &map);
                assert!(verr <= 0.01, "view {view:?}: variance off by {verr:.3e}");
            }
            AlbedoMethod::Linear | AlbedoMethod::Lattice { .. } => {
                panic!("a log map without a prepared map is a field or per pixel")
            }
        }
        // The small views always get a field, within 0.1% of the dense rule.
        if k == 1 || k == 2 {
            assert!(matches!(map.method, AlbedoMethod::Field { .. }), "{view:?}");
            assert!(worst <= 1e-3, "view {view:?}: worst error {worst:.3e}");
        }
        eprintln!("view {view:?}: {:?}, worst {worst:.2e}", map.method);
    }
    assert!(fields >= 2);
}

#[test]
fn a_fresh_model_and_one_that_cached_the_field_draw_the_same_map() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 8, TransformKind::Log);
    let view = zoomed([0.3, 0.2], 100.0);
    let draw = |threads: usize| {
        let model = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            // The default view first (cached), then the zoomed one.
            model.map(brdf_atlas_core::MapRequest::new(32, 32)).unwrap();
            let a = model
                .map(brdf_atlas_core::MapRequest::new(40, 40).view(view))
                .unwrap();
            let b = model
                .map(brdf_atlas_core::MapRequest::new(40, 40).view(view))
                .unwrap();
            assert_eq!(a.rgb, b.rgb);
            a
        })
    };
    let (one, two) = (draw(1), draw(3));
    assert_eq!(one.rgb, two.rgb, "thread count changed the map");
    assert_eq!(one.variance, two.variance);
}

#[test]
fn exact_albedos_are_the_dense_rule_on_the_full_reconstruction() {
    let tmp = tempfile::tempdir().unwrap();
    let model =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 6, TransformKind::Log)).unwrap());
    let points = [[0.0, 0.0], [0.9, -0.4], [-1.05, 1.1], [2.0, 0.5]];
    let got = model
        .exact_albedos(&points, brdf_atlas_core::AlbedoRequest::new())
        .unwrap();
    for (x, g) in points.iter().zip(&got) {
        let want = reference_albedo(&model, x, BlendRule::default(), model.albedo_rule()).unwrap();
        for c in 0..3 {
            assert!(
                (g[c] - want[c]).abs() <= 1e-6 * want[c].abs().max(1e-3),
                "{x:?}: {g:?} against {want:?}"
            );
        }
    }
    assert!(
        model
            .exact_albedos(&[[f64::NAN, 0.0]], brdf_atlas_core::AlbedoRequest::new())
            .is_err()
    );
}

#[test]
fn exact_albedos_by_a_rule_are_its_reference_albedos() {
    let tmp = tempfile::tempdir().unwrap();
    let points = [[0.0, 0.0], [0.9, -0.4], [-1.05, 1.1], [2.0, 0.5]];
    for transform in [TransformKind::Log, TransformKind::Raw] {
        let model =
            brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 6, transform)).unwrap());
        let rule = Quadrature::dense(model.dims(), 1);
        for blend in [BlendRule::Floor, BlendRule::Gp] {
            let got = model
                .exact_albedos(
                    &points,
                    brdf_atlas_core::AlbedoRequest::new()
                        .rule(blend)
                        .integration(brdf_atlas_core::Integration::Rule(&rule)),
                )
                .unwrap();
            for (x, g) in points.iter().zip(&got) {
                let want = reference_albedo(&model, x, blend, &rule).unwrap();
                for c in 0..3 {
                    assert!(
                        (g[c] - want[c]).abs() <= 1e-12 * want[c].abs().max(1e-3),
                        "{transform:?} {blend:?} {x:?}: {g:?} against {want:?}"
                    );
                }
            }
        }
        let other = Quadrature::dense(Dims::new(4, 4, 8).unwrap(), 1);
        assert!(
            model
                .exact_albedos(
                    &points,
                    brdf_atlas_core::AlbedoRequest::new()
                        .rule(BlendRule::Gp)
                        .integration(brdf_atlas_core::Integration::Rule(&other))
                )
                .is_err()
        );
        assert!(
            model
                .exact_albedos(
                    &points,
                    brdf_atlas_core::AlbedoRequest::new()
                        .rule(BlendRule::Plausible)
                        .integration(brdf_atlas_core::Integration::Rule(&rule))
                )
                .is_err()
        );
    }
}

#[test]
fn a_raw_models_gp_map_is_the_exact_linear_one_and_its_floor_map_is_not() {
    let tmp = tempfile::tempdir().unwrap();
    let model =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 6, TransformKind::Raw)).unwrap());
    let (view, rule) = (View::default(), BlendRule::Gp);
    let gp = model
        .map(
            brdf_atlas_core::MapRequest::new(24, 24)
                .view(view)
                .rule(rule),
        )
        .unwrap();
    assert_eq!((gp.method, gp.blend), (AlbedoMethod::Linear, BlendRule::Gp));
    // The soft floor is not linear in the weights: the default map of a raw
    // model integrates its material; in a small view with a field, within
    // the field's accuracy.
    let floor = model
        .map(brdf_atlas_core::MapRequest::new(24, 24).view(view))
        .unwrap();
    assert_ne!(floor.method, AlbedoMethod::Linear);
    assert_eq!(floor.blend, BlendRule::Floor);
    let small = zoomed([0.137, -0.291], 100.0);
    let floor = model
        .map(brdf_atlas_core::MapRequest::new(24, 24).view(small))
        .unwrap();
    assert!(
        matches!(floor.method, AlbedoMethod::Field { .. }),
        "{:?}",
        floor.method
    );
    let worst = worst_error(&model, &floor, &random_pixels(24, 12, 5));
    assert!(worst <= 0.01, "{worst}");
}

#[test]
fn a_views_domain_holds_it_and_is_at_most_four_times_its_size() {
    use brdf_atlas_core::albedo_field::domain_of;
    let mut s = 99u64;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    assert_eq!(domain_of(View::default()), View::default());
    for _ in 0..2000 {
        let (c, d) = (4.0 * next() - 2.0, 4.0 * next() - 2.0);
        let w = 10f64.powf(-6.0 * next());
        let view = View {
            x0: c,
            x1: c + w,
            y0: d,
            y1: d + w * (0.5 + next()),
        };
        let dom = domain_of(view);
        assert!(dom.x0 <= view.x0 && dom.x1 >= view.x1, "{view:?} {dom:?}");
        assert!(dom.y0 <= view.y0 && dom.y1 >= view.y1, "{view:?} {dom:?}");
        assert!(dom.x1 - dom.x0 <= 4.0 * (view.x1 - view.x0) * (1.0 + 1e-9));
        assert!(dom.y1 - dom.y0 <= 4.0 * (view.y1 - view.y0) * (1.0 + 1e-9));
        // Panning within the domain keeps it.
        let e = 1e-3 * w;
        let moved = View {
            x0: view.x0 + e,
            x1: view.x1 + e,
            ..view
        };
        if moved.x1 <= dom.x1 && domain_of(moved).x1 - domain_of(moved).x0 == dom.x1 - dom.x0 {
            assert!(domain_of(moved).x0 <= moved.x0);
        }
    }
}

/// The plan of a field (its refinement run on the per-pixel rule's rows)
/// gives up only where the exact refinement would not fit its budget
/// either: over views from the default one down to a hundredth of it and
/// several budgets, every field the exact nodes build within budget is
/// planned, and some the budget cannot hold are given up by the plan alone.
#[test]
fn the_plan_gives_up_only_fields_the_budget_cannot_hold() {
    let tmp = tempfile::tempdir().unwrap();
    let model =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, TransformKind::Log)).unwrap());
    let latent = model.latent();
    let around = [latent[(3, 0)], latent[(3, 1)]];
    let mut views = vec![View::default()];
    for zoom in [2.0, 4.0, 8.0, 16.0, 100.0] {
        views.push(zoomed(around, zoom));
        views.push(zoomed([0.137, -0.291], zoom));
    }
    let (mut built, mut skipped) = (0, 0);
    for view in views {
        let domain = brdf_atlas_core::albedo_field::domain_of(view);
        for budget in [81, 300, 2000] {
            let plan = model.plan_field(domain, budget).unwrap();
            let exact = model.build_field(domain, budget).unwrap();
            match (plan, exact) {
                (None, Some(f)) => panic!(
                    "{view:?}, budget {budget}: planned out, but {} exact nodes build it",
                    f.nodes()
                ),
                (Some(_), Some(_)) => built += 1,
                (None, None) => skipped += 1,
                (Some(_), None) => {}
            }
        }
    }
    assert!(built > 0 && skipped > 0, "built {built}, skipped {skipped}");
}

/// Cancels once `after` rows (or field refinement steps) have been asked about.
struct CancelAfter {
    asked: AtomicUsize,
    after: usize,
}

impl Progress for CancelAfter {
    fn cancelled(&self) -> bool {
        self.asked.fetch_add(1, Ordering::Relaxed) >= self.after
    }
}

#[test]
fn a_cancelled_map_stops_caches_nothing_and_the_next_one_is_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 8, TransformKind::Log);
    // A field view (zoomed) and the per-pixel rule: cancelled at the start,
    // and part-way through the rows or the field's refinement.
    let view = zoomed([0.3, 0.2], 100.0);
    for (samples, side) in [(None, 40), (Some(16), 48)] {
        let reference = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap())
            .map(
                brdf_atlas_core::MapRequest::new(side, side)
                    .view(view)
                    .samples(samples),
            )
            .unwrap();
        if samples.is_none() {
            assert!(matches!(reference.method, AlbedoMethod::Field { .. }));
        }
        for after in [0, 1, 5] {
            let model = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
            let cancel = CancelAfter {
                asked: AtomicUsize::new(0),
                after,
            };
            let got = model.map(
                brdf_atlas_core::MapRequest::new(side, side)
                    .view(view)
                    .samples(samples)
                    .progress(&cancel),
            );
            assert!(
                matches!(got, Err(CoreError::Cancelled)),
                "{samples:?} after {after}: {:?}",
                got.map(|m| m.method)
            );
            // Nothing half-built was kept: the next map is the whole one.
            let next = model
                .map(
                    brdf_atlas_core::MapRequest::new(side, side)
                        .view(view)
                        .samples(samples),
                )
                .unwrap();
            assert_eq!(next.rgb, reference.rgb, "{samples:?} after {after}");
            assert_eq!(next.variance, reference.variance);
        }
    }
}

/// A sampled field holds its own rule's albedos: at random points of the
/// view, the field against that quadrature rule applied to the full
/// reconstruction at each point (an independent pass, point by point),
/// within the field's error estimate; a second request is answered from
/// the atlas's cache.
#[test]
fn a_sampled_field_holds_its_rules_albedos() {
    let tmp = tempfile::tempdir().unwrap();
    let model =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, TransformKind::Log)).unwrap());
    let samples = 64;
    let rule = Quadrature::with_samples_shaped(model.albedo_rule(), samples, model.shape());
    for view in [View::default(), View::wide()] {
        let request = brdf_atlas_core::FieldRequest::new(view, 1 << 20);
        let field = model.sampled_field(request, samples).unwrap().unwrap();
        assert!(field.nodes() >= 25, "{}", field.nodes());
        let mut rng = synth::SplitMix64::new(5);
        let mut worst = 0.0f64;
        for _ in 0..24 {
            let x = [rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)];
            let want = reference_albedo(&model, &x, BlendRule::Floor, &rule).unwrap();
            let (got, _) = field.at(x);
            let scale = want.iter().fold(1e-9f64, |a, v| a.max(v.abs()));
            for c in 0..3 {
                worst = worst.max((got[c] - want[c]).abs() / scale);
            }
        }
        // Chebyshev interpolation converges geometrically: well inside its
        // estimate where that met the tolerance.
        let bound = field
            .estimate()
            .max(brdf_atlas_core::albedo_field::ALBEDO_TOLERANCE);
        assert!(
            worst <= bound,
            "{view:?}: {worst:.2e} off its rule, estimate {:.2e}",
            field.estimate()
        );
        // The same request is answered from the cache.
        let again = model.sampled_field(request, samples).unwrap().unwrap();
        assert!(std::sync::Arc::ptr_eq(&field, &again));
    }
}
