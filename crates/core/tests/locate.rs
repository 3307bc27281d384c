//! `locate` searches the whole latent plane: a material whose best match
//! lies beyond the fit's box lands there, not on the box's edge.

use brdf_atlas_core::fit_dir;
use brdf_atlas_core::{FitOptions, GplvmParams, Model, NoProgress, Precision, TransformKind};
use brdf_merl::{Dims, MerlFile, synth};

#[test]
fn a_material_beyond_the_box_lands_beyond_it() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    synth::write_dir(&data, 10, Dims::new(16, 16, 32).unwrap(), 6).unwrap();
    let path = dir.path().join("m.atlas");
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision: Precision::F64,
    };
    fit_dir(&data, &path, &options, &NoProgress).unwrap();
    let model = Model::open(&path).unwrap();
    let latent = model.latent();
    let inside = (0..latent.nrows()).all(|i| (0..2).all(|c| latent[(i, c)].abs() <= 1.0 + 1e-12));
    assert!(inside, "the fit keeps its materials in [-1, 1]");

    for target in [[1.6, 0.3], [-0.4, -1.45]] {
        let merl = dir.path().join("beyond.binary");
        model
            .at(&target, brdf_atlas_core::BlendRule::Gp)
            .unwrap()
            .table()
            .unwrap()
            .write(&merl)
            .unwrap();
        let l = brdf_atlas_core::Located::find(&model, &MerlFile::open(&merl).unwrap()).unwrap();
        let d = ((l.point[0] - target[0]).powi(2) + (l.point[1] - target[1]).powi(2)).sqrt();
        assert!(d < 0.02, "{target:?} located at {:?}", l.point);
        assert!(
            l.point.iter().any(|v| v.abs() > 1.05),
            "{:?} is off the edge",
            l.point
        );
        assert!(
            l.rmse < 0.05 * l.spread,
            "rmse {} spread {}",
            l.rmse,
            l.spread
        );
        assert!(!l.in_default_view(), "{:?}", l.point);
    }
    // A training material still lands on itself, inside the view.
    let first = std::fs::read_dir(&data)
        .unwrap()
        .map(|e| e.unwrap().path())
        .min()
        .unwrap();
    let l = brdf_atlas_core::Located::find(&model, &MerlFile::open(&first).unwrap()).unwrap();
    let name = first.file_stem().unwrap().to_str().unwrap();
    assert_eq!(model.names()[l.nearest[0].0], name);
    assert!(l.in_default_view());
}
