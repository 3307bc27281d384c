//! Albedo fields saved beside the model (`MODEL.fields`): a new atlas of
//! the model draws from them instead of building them again (shown by
//! altering the saved values and finding the alteration in the map), the
//! maps are the same bits as the atlas's that built them, a view inside a
//! saved field's domain is drawn from it, and a file that cannot be used
//! (truncated, of another fit, damaged, a directory) is named and left
//! aside, the map built anew and the file replaced by the next save. A
//! sampled field's check (its error against exact albedos) is what the
//! dense rule says at its points, and survives the file.

use std::path::{Path, PathBuf};

use brdf_atlas_core::field_check::check_points;
use brdf_atlas_core::map_error::{albedo_error, reference_albedo};
use brdf_atlas_core::{
    AlbedoMap, AlbedoMethod, Atlas, BlendRule, FIELD_SAMPLES, FieldRequest, FitOptions,
    GplvmParams, MapRequest, Model, NoProgress, Precision, TransformKind, View, fields_path,
    fit_dir,
};
use brdf_merl::{Dims, synth};

const DIMS: Dims = Dims {
    theta_h: 8,
    theta_d: 8,
    phi_d: 16,
};

fn fit(dir: &Path) -> PathBuf {
    let data = dir.join("data");
    synth::write_dir(&data, 10, DIMS, 7).unwrap();
    let model = dir.join("m.atlas");
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision: Precision::F32,
    };
    fit_dir(&data, &model, &options, &NoProgress).unwrap();
    model
}

fn atlas(path: &Path) -> Atlas {
    Atlas::new(Model::open(path).unwrap())
}

fn map(atlas: &Atlas, view: View) -> AlbedoMap {
    atlas.map(MapRequest::new(512, 400).view(view)).unwrap()
}

fn nodes(method: &AlbedoMethod) -> Option<usize> {
    match *method {
        AlbedoMethod::Field { nodes, .. } | AlbedoMethod::SampledField { nodes, .. } => Some(nodes),
        _ => None,
    }
}

/// The saved file's JSON, changed by `edit`, written back.
fn edit_file(model: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = fields_path(model);
    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    edit(&mut json);
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
}

/// Every saved albedo value (not the variance's), `f` applied.
fn each_albedo_value(json: &mut serde_json::Value, f: impl Fn(f64) -> f64) {
    for entry in json["entries"].as_array_mut().unwrap() {
        let Some(field) = entry.get_mut("field").filter(|f| !f.is_null()) else {
            continue;
        };
        for patch in field["albedo"].as_array_mut().unwrap() {
            for v in patch["values"].as_array_mut().unwrap() {
                *v = serde_json::json!(f(v.as_f64().unwrap()));
            }
        }
    }
}

#[test]
fn a_new_atlas_draws_from_the_saved_fields() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path());
    let first = atlas(&path);
    assert_eq!(first.saved_fields().unwrap(), 0, "no file yet");
    let default = map(&first, View::default());
    let built = nodes(&default.method).unwrap_or_else(|| panic!("{:?}", default.method));
    // A sampled field of a wide view too (the map's would be exact here).
    let sampled = first
        .sampled_field(FieldRequest::new(View::wide(), 1 << 20), FIELD_SAMPLES)
        .unwrap()
        .unwrap();
    let saved = first.save_fields().unwrap().expect("new fields are saved");
    assert_eq!(saved, fields_path(&path));
    assert_eq!(
        first.save_fields().unwrap(),
        None,
        "nothing new the second time"
    );

    // The same bits from the file, the same method.
    let second = atlas(&path);
    assert!(second.saved_fields().unwrap() >= 2);
    let again = map(&second, View::default());
    assert_eq!(again.rgb, default.rgb);
    assert_eq!(again.variance, default.variance);
    assert_eq!(nodes(&again.method), Some(built));
    let wide_again = second
        .sampled_field(FieldRequest::new(View::wide(), 1 << 20), FIELD_SAMPLES)
        .unwrap()
        .unwrap();
    let x = [2.1, -1.7];
    assert_eq!(wide_again.at(x), sampled.at(x));
    assert_eq!(second.save_fields().unwrap(), None, "read, not built");

    // Drawn from the file, not built again: doubling the saved albedos
    // doubles the map.
    edit_file(&path, |json| each_albedo_value(json, |v| 2.0 * v));
    let third = atlas(&path);
    let doubled = map(&third, View::default());
    for (d, a) in doubled.rgb.iter().zip(&default.rgb) {
        for c in 0..3 {
            assert!(
                (d[c] - 2.0 * a[c]).abs() <= 1e-6 * (1.0 + a[c].abs()),
                "{d:?} {a:?}"
            );
        }
    }
    // A view inside the default one is drawn from the default view's field
    // (the smallest saved domain that holds it): doubled too, and of its
    // node count.
    let inside = View {
        x0: -0.4,
        x1: 0.1,
        y0: 0.2,
        y1: 0.6,
    };
    let zoom_doubled = map(&third, inside);
    assert_eq!(nodes(&zoom_doubled.method), Some(built));
    let zoom = map(&first, inside);
    for (d, a) in zoom_doubled.rgb.iter().zip(&zoom.rgb) {
        for c in 0..3 {
            assert!(
                (d[c] - 2.0 * a[c]).abs() <= 1e-6 * (1.0 + a[c].abs()),
                "{d:?} {a:?}"
            );
        }
    }
}

#[test]
fn a_saved_fields_file_that_cannot_be_used_is_named_and_left_aside() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path());
    let first = atlas(&path);
    let want = map(&first, View::default());
    first.save_fields().unwrap().unwrap();
    let file = fields_path(&path);
    let whole = std::fs::read(&file).unwrap();
    type Damage<'a> = Box<dyn Fn() + 'a>;
    let damages: Vec<(&str, Damage)> = vec![
        (
            "not a brdf-atlas fields file",
            Box::new(|| std::fs::write(&file, &whole[..whole.len() / 2]).unwrap()),
        ),
        (
            "another fit",
            Box::new(|| edit_file(&path, |json| json["model"] = "0123456789abcdef".into())),
        ),
        (
            "damaged",
            Box::new(|| {
                edit_file(&path, |json| {
                    let entry = json["entries"]
                        .as_array_mut()
                        .unwrap()
                        .iter_mut()
                        .find(|e| !e["field"].is_null())
                        .unwrap();
                    entry["field"]["albedo"][0]["values"]
                        .as_array_mut()
                        .unwrap()
                        .pop();
                })
            }),
        ),
        (
            "m.fields",
            Box::new(|| {
                std::fs::remove_file(&file).unwrap();
                std::fs::create_dir(&file).unwrap();
            }),
        ),
    ];
    for (what, damage) in damages {
        std::fs::write(&file, &whole).ok();
        damage();
        let fresh = atlas(&path);
        let why = fresh.saved_fields().unwrap_err().to_string();
        assert!(why.contains("m.fields"), "{what}: {why}");
        assert!(why.contains(what), "{what}: {why}");
        // The map is built anew, the same as the first atlas's.
        let got = map(&fresh, View::default());
        assert_eq!(got.rgb, want.rgb, "{what}");
        if file.is_dir() {
            // Not replaced: a directory is the user's.
            assert!(fresh.save_fields().is_err());
            std::fs::remove_dir(&file).unwrap();
            continue;
        }
        // The next save replaces the file, which a new atlas then reads.
        assert_eq!(fresh.save_fields().unwrap(), Some(file.clone()), "{what}");
        assert!(atlas(&path).saved_fields().unwrap() >= 1, "{what}");
    }
}

/// A sampled field of the default view from a rule of `samples` samples
/// (few, so that its error is plain to see).
fn sampled(atlas: &Atlas, samples: usize) -> std::sync::Arc<brdf_atlas_core::AlbedoField> {
    atlas
        .sampled_field(FieldRequest::new(View::default(), 1 << 20), samples)
        .unwrap()
        .expect("a field within a million nodes")
}

#[test]
fn a_sampled_fields_check_is_its_error_against_the_dense_rule_at_its_points() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path());
    let atlas = atlas(&path);
    let field = sampled(&atlas, 16);
    let check = field
        .check()
        .expect("a sampled field is checked when built");
    let points = check_points(field.domain());
    assert_eq!(check.points, points.len());
    // Independently: the dense rule value by value through the blend (on
    // grids this coarse the nodes' rule is the dense rule itself).
    let model = atlas.model();
    let want: Vec<[f64; 3]> = points
        .iter()
        .map(|p| reference_albedo(model, p, BlendRule::Floor, model.albedo_rule()).unwrap())
        .collect();
    let got: Vec<[f64; 3]> = points.iter().map(|p| field.at(*p).0).collect();
    let (worst, mean) = albedo_error(&got, &want);
    assert!(
        (worst - check.worst).abs() <= 1e-9 && (mean - check.mean).abs() <= 1e-9,
        "check {check:?}, recomputed {worst} / {mean}"
    );
    assert!(check.worst > 1e-3, "16 samples are visibly off: {check:?}");
}

#[test]
fn a_fields_check_is_saved_and_a_file_without_one_still_serves() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path());
    let first = atlas(&path);
    let built = sampled(&first, 16);
    first.save_fields().unwrap();
    assert_eq!(sampled(&atlas(&path), 16).check(), built.check());
    // What the file says is what a new atlas reports (a field built anew
    // would carry its own, measured check).
    edit_file(&path, |json| {
        for entry in json["entries"].as_array_mut().unwrap() {
            if let Some(check) = entry["field"].get_mut("check").filter(|c| !c.is_null()) {
                check["worst"] = serde_json::json!(0.125);
            }
        }
    });
    let read = sampled(&atlas(&path), 16).check().expect("a check");
    assert_eq!(read.worst, 0.125);
    assert_eq!(read.mean, built.check().unwrap().mean);
    // A file written before fields were checked: no check, still used
    // (a field built anew would carry one).
    edit_file(&path, |json| {
        for entry in json["entries"].as_array_mut().unwrap() {
            if let Some(field) = entry["field"].as_object_mut() {
                field.remove("check");
            }
        }
    });
    let old = sampled(&atlas(&path), 16);
    assert_eq!(old.check(), None);
    assert_eq!(old.nodes(), built.nodes());
    assert_eq!(old.at([0.1, -0.2]), built.at([0.1, -0.2]));
}
