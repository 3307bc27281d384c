//! The prepared map (`Atlas::prepare_map`, the adaptive lattice of exact
//! albedos over the default view) against an independent reference: its
//! albedo at random points of the default view and of a view a hundred
//! times smaller against the dense rule applied to the full reconstruction
//! there (`Model::at` -> every bin -> `Quadrature::integrate`), within 1% of
//! the point's largest channel; the map drawn from it once saved beside the
//! model; and the lattices a map must not use (another rule, a view outside
//! it, another fit, a damaged file), each named in one line.

mod common;

use std::path::Path;

use brdf_atlas_core::map_error::reference_albedo;
use brdf_atlas_core::{
    AlbedoLattice, AlbedoMethod, BlendRule, LATTICE_TOLERANCE, Model, NoProgress, TransformKind,
    View, lattice_path,
};

/// `count` points of `view` from a seeded generator.
fn random_points(view: View, count: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..count)
        .map(|_| {
            [
                view.x0 + (view.x1 - view.x0) * next(),
                view.y0 + (view.y1 - view.y0) * next(),
            ]
        })
        .collect()
}

/// Largest error of `got` at `points` against the dense reference of
/// `rule`'s material, relative to the reference's largest channel.
fn worst_error(
    model: &Model,
    rule: BlendRule,
    points: &[[f64; 2]],
    got: impl Fn([f64; 2]) -> [f64; 3],
) -> f64 {
    let quadrature = model.albedo_rule();
    let mut worst = 0.0f64;
    for &x in points {
        let want = reference_albedo(model, &x, rule, quadrature).unwrap();
        let got = got(x);
        let scale = want.iter().fold(1e-12f64, |a, v| a.max(*v));
        for c in 0..3 {
            worst = worst.max((got[c] - want[c]).abs() / scale);
        }
    }
    worst
}

fn prepared(dir: &Path, count: usize, rule: BlendRule) -> (brdf_atlas_core::Atlas, AlbedoLattice) {
    let path = common::fit(dir, count, TransformKind::Log);
    let model = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let lattice = model
        .prepare_map(rule, LATTICE_TOLERANCE, &NoProgress)
        .unwrap();
    (model, lattice)
}

#[test]
fn the_lattice_follows_the_dense_rule_across_the_default_view_and_zoomed_in() {
    let dir = tempfile::tempdir().unwrap();
    for rule in [BlendRule::Floor, BlendRule::Gp] {
        let (model, lattice) = prepared(dir.path(), 8, rule);
        assert_eq!(lattice.rule(), rule);
        assert_eq!(lattice.view(), View::default());
        // More than the coarsest lattice's 17 x 17: the refinement ran.
        assert!(lattice.nodes() > 289, "{} nodes", lattice.nodes());
        for (view, seed) in [(View::default(), 1), (View::zoomed_hundredfold(), 2)] {
            let points = random_points(view, 24, seed);
            let worst = worst_error(&model, rule, &points, |x| lattice.albedo_at(x));
            assert!(
                worst <= 0.01,
                "{rule:?} over {view:?}: worst error {:.3}% of the largest channel",
                100.0 * worst
            );
        }
    }
}

#[test]
fn a_saved_lattice_draws_every_map_inside_the_default_view() {
    let dir = tempfile::tempdir().unwrap();
    let (model, lattice) = prepared(dir.path(), 6, BlendRule::Floor);
    let path = lattice_path(model.path());
    lattice.save(&path).unwrap();
    // A fresh model reads it on its first map.
    let model = brdf_atlas_core::Atlas::new(Model::open(model.path()).unwrap());
    let loaded = model
        .prepared_map()
        .unwrap()
        .expect("the lattice beside the model");
    assert_eq!(loaded.nodes(), lattice.nodes());
    for x in random_points(View::default(), 16, 3) {
        assert_eq!(loaded.albedo_at(x), lattice.albedo_at(x));
    }
    for view in [View::default(), View::zoomed_hundredfold()] {
        let (w, h) = (48, 40);
        let map = model
            .map(brdf_atlas_core::MapRequest::new(w, h).view(view))
            .unwrap();
        assert!(
            matches!(map.method, AlbedoMethod::Lattice { nodes, .. } if nodes == lattice.nodes()),
            "{:?}",
            map.method
        );
        // Each pixel is the lattice's value at its point, and the variance
        // the exact variance map's.
        let exact_variance = model.variance_map(w, h, view).unwrap();
        for (k, (rgb, v)) in map.rgb.iter().zip(&map.variance).enumerate() {
            let x = view.pixel_to_latent((k % w) as f64, (k / w) as f64, w, h);
            let want = lattice.albedo_at(x).map(|a| a.max(0.0) as f32);
            assert_eq!(*rgb, want, "pixel {k}");
            assert!(
                (v - exact_variance[k]).abs() < 1e-3,
                "pixel {k}: variance {v} against {}",
                exact_variance[k]
            );
        }
        let pixels: Vec<[f64; 2]> = [(3, 5), (40, 31), (24, 20), (47, 0)]
            .iter()
            .map(|&(px, py)| view.pixel_to_latent(px as f64, py as f64, w, h))
            .collect();
        let worst = worst_error(&model, BlendRule::Floor, &pixels, |x| {
            let (px, py) = {
                let p = view.latent_to_pixel(x, w, h);
                (p[0] as usize, p[1] as usize)
            };
            map.rgb[py * w + px].map(f64::from)
        });
        assert!(worst <= 0.01, "worst {:.3}%", 100.0 * worst);
    }
    // Not for another rule, a view beyond the default one, or a sample count.
    let gp = model
        .map(brdf_atlas_core::MapRequest::new(16, 16).rule(BlendRule::Gp))
        .unwrap();
    assert!(
        !matches!(gp.method, AlbedoMethod::Lattice { .. }),
        "{:?}",
        gp.method
    );
    let far = View {
        x0: 1.2,
        x1: 1.6,
        y0: -0.2,
        y1: 0.2,
    };
    let beyond = model
        .map(brdf_atlas_core::MapRequest::new(16, 16).view(far))
        .unwrap();
    assert!(
        !matches!(beyond.method, AlbedoMethod::Lattice { .. }),
        "{:?}",
        beyond.method
    );
    // A view reaching beyond the window (a panel wider than tall): the
    // pixels inside it from the lattice, the strips outside drawn without
    // it, and the variance the exact one's everywhere.
    let wide = View {
        x0: -1.5,
        x1: 1.5,
        y0: -1.2,
        y1: 1.0,
    };
    let (w, h) = (30, 22);
    let mixed = model
        .map(brdf_atlas_core::MapRequest::new(w, h).view(wide))
        .unwrap();
    let AlbedoMethod::Lattice { share, .. } = mixed.method else {
        panic!("{:?}", mixed.method)
    };
    let window = lattice.view();
    let exact_variance = model.variance_map(w, h, wide).unwrap();
    let mut inside = 0;
    for (k, rgb) in mixed.rgb.iter().enumerate() {
        let x = wide.pixel_to_latent((k % w) as f64, (k / w) as f64, w, h);
        let within =
            (window.x0..=window.x1).contains(&x[0]) && (window.y0..=window.y1).contains(&x[1]);
        if within {
            inside += 1;
            assert_eq!(
                *rgb,
                lattice.albedo_at(x).map(|a| a.max(0.0) as f32),
                "pixel {k}"
            );
        } else {
            let worst = worst_error(&model, BlendRule::Floor, &[x], |_| rgb.map(f64::from));
            assert!(worst < 0.1, "pixel {k} outside: {:.2}% off", 100.0 * worst);
        }
        let v = mixed.variance[k];
        assert!(
            (v - exact_variance[k]).abs() < 3e-3,
            "pixel {k}: variance {v} against {}",
            exact_variance[k]
        );
    }
    assert!(inside > 0 && inside < w * h, "{inside} pixels inside");
    assert_eq!(share, inside as f64 / (w * h) as f64);
    let sampled = model
        .map(brdf_atlas_core::MapRequest::new(16, 16).samples(Some(64)))
        .unwrap();
    assert!(
        matches!(sampled.method, AlbedoMethod::Quadrature { .. }),
        "{:?}",
        sampled.method
    );
}

#[test]
fn bad_requests_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let model = brdf_atlas_core::Atlas::new(
        Model::open(common::fit(dir.path(), 4, TransformKind::Log)).unwrap(),
    );
    for (rule, tolerance, want) in [
        (BlendRule::Plausible, LATTICE_TOLERANCE, "plausible"),
        (BlendRule::Floor, 0.0, "tolerance"),
        (BlendRule::Floor, f64::NAN, "tolerance"),
    ] {
        let why = model
            .prepare_map(rule, tolerance, &NoProgress)
            .err()
            .expect("refused")
            .to_string();
        assert!(why.contains(want) && !why.contains('\n'), "{why}");
    }
}

#[test]
fn a_lattice_of_another_fit_or_a_damaged_one_is_named_and_left_aside() {
    let dir = tempfile::tempdir().unwrap();
    let (model, lattice) = prepared(dir.path(), 6, BlendRule::Floor);
    let path = lattice_path(model.path());
    lattice.save(&path).unwrap();
    // Another fit (of other materials, its store beside it) in the model's place.
    let original = std::fs::read(model.path()).unwrap();
    let other = common::fit(dir.path(), 7, TransformKind::Log);
    std::fs::copy(&other, model.path()).unwrap();
    let refit = brdf_atlas_core::Atlas::new(Model::open(model.path()).unwrap());
    let why = refit
        .prepared_map()
        .err()
        .expect("a lattice of another fit")
        .to_string();
    assert!(
        why.contains(&path.display().to_string()) && why.contains("another fit"),
        "{why}"
    );
    assert!(!why.contains('\n'), "{why}");
    let handed = refit.map(brdf_atlas_core::MapRequest::new(8, 8).lattice(&lattice));
    let why = handed
        .expect_err("a lattice of another fit, handed over")
        .to_string();
    assert!(why.contains("another fit"), "{why}");
    let map = refit.map(brdf_atlas_core::MapRequest::new(16, 16)).unwrap();
    assert!(
        !matches!(map.method, AlbedoMethod::Lattice { .. }),
        "{:?}",
        map.method
    );

    // Damaged: cut short, and not JSON at all.
    std::fs::write(model.path(), original).unwrap();
    let text = std::fs::read(&path).unwrap();
    for damaged in [&text[..text.len() / 2], b"hello".as_slice()] {
        std::fs::write(&path, damaged).unwrap();
        let model = brdf_atlas_core::Atlas::new(Model::open(model.path()).unwrap());
        let why = model
            .prepared_map()
            .err()
            .expect("a damaged lattice")
            .to_string();
        assert!(why.contains(&path.display().to_string()), "{why}");
        assert!(!why.contains('\n'), "{why}");
    }
}
