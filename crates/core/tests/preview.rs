//! A preview ([`MapRequest::preview`]) builds nothing: with nothing held
//! it is the per-pixel map of its sample count, and the atlas has nothing
//! new to save afterwards; with a field held it is the full map's picture
//! (the full map drawing from the same field);
//! beside a given prepared map its strips are integrated per pixel, not
//! drawn from fields built for them.

mod common;

use brdf_atlas_core::{
    AlbedoMethod, Atlas, BlendRule, LATTICE_TOLERANCE, MapRequest, Model, NoProgress,
    TransformKind, View,
};

/// The atlas of a model of 10 synthetic materials, fitted in `dir`.
fn atlas(dir: &std::path::Path) -> Atlas {
    Atlas::new(Model::open(common::fit(dir, 10, TransformKind::Log)).unwrap())
}

#[test]
fn a_preview_draws_what_is_held_and_builds_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let atlas = atlas(tmp.path());
    let (w, h) = (40, 30);
    let request = || MapRequest::new(w, h).view(View::default());
    // Nothing held: the 16-sample map, and nothing new to save after it.
    let preview = atlas.map(request().preview(16)).unwrap();
    let per_pixel = atlas.map(request().samples(Some(16))).unwrap();
    assert_eq!(preview.rgb, per_pixel.rgb);
    assert_eq!(preview.method, per_pixel.method);
    assert!(matches!(
        preview.method,
        AlbedoMethod::Quadrature { samples: 16, .. }
    ));
    assert_eq!(
        atlas.save_fields().unwrap(),
        None,
        "a preview built a field"
    );
    // A sample count wins over a preview's.
    let both = atlas.map(request().preview(16).samples(Some(8))).unwrap();
    assert!(matches!(
        both.method,
        AlbedoMethod::Quadrature { samples: 8, .. }
    ));
    // A larger map's field held: the full map and the preview draw it.
    let large = (512, 512, View::default());
    let (method, _) = atlas
        .prepare_fields(large, BlendRule::Floor, &NoProgress)
        .unwrap();
    let method = method.expect("a field for the large map");
    let full = atlas.map(request()).unwrap();
    assert_ne!(full.rgb, per_pixel.rgb);
    // The small map draws from the large one's field (a sampled one here:
    // its domain's exact field is over the small map's budget).
    assert!(
        matches!(method, AlbedoMethod::SampledField { .. }),
        "{method:?}"
    );
    assert!(
        matches!(full.method, AlbedoMethod::SampledField { nodes, .. } if Some(nodes) == nodes_of(&method)),
        "{:?}",
        full.method
    );
    let preview = atlas.map(request().preview(16)).unwrap();
    assert_eq!(preview.rgb, full.rgb);
    assert_eq!(preview.method, full.method);
}

#[test]
fn a_preview_beside_a_given_prepared_map_builds_nothing_outside_it() {
    let tmp = tempfile::tempdir().unwrap();
    let atlas = atlas(tmp.path());
    let lattice = atlas
        .prepare_map(BlendRule::Floor, LATTICE_TOLERANCE, &NoProgress)
        .unwrap();
    // [-3, 3]^2: the lattice's window (the default view) in the middle,
    // strips round it.
    let (w, h) = (60, 60);
    let view = View::wide();
    let preview = atlas
        .map(
            MapRequest::new(w, h)
                .view(view)
                .lattice(&lattice)
                .preview(16),
        )
        .unwrap();
    assert!(matches!(preview.method, AlbedoMethod::Lattice { share, .. } if share < 0.5));
    assert_eq!(
        atlas.save_fields().unwrap(),
        None,
        "a preview built a field"
    );
    // The strips are the 16-sample map's pixels (drawn as maps of their
    // own, so equal to rounding in the pixels' latent points).
    let per_pixel = atlas
        .map(MapRequest::new(w, h).view(view).samples(Some(16)))
        .unwrap();
    let corner = [0, w - 1, (h - 1) * w, h * w - 1];
    for p in corner {
        for c in 0..3 {
            let (a, b) = (preview.rgb[p][c], per_pixel.rgb[p][c]);
            assert!(
                (a - b).abs() <= 1e-5 * b.abs().max(1e-3),
                "pixel {p}: {a} vs {b}"
            );
        }
    }
    // Without the preview the strips get fields of their own.
    let full = atlas
        .map(MapRequest::new(w, h).view(view).lattice(&lattice))
        .unwrap();
    assert!(matches!(full.method, AlbedoMethod::Lattice { .. }));
    assert!(
        atlas.save_fields().unwrap().is_some(),
        "the full map's strips built fields"
    );
}

/// The nodes of a field's method.
fn nodes_of(method: &AlbedoMethod) -> Option<usize> {
    match *method {
        AlbedoMethod::Field { nodes, .. } | AlbedoMethod::SampledField { nodes, .. } => Some(nodes),
        _ => None,
    }
}
