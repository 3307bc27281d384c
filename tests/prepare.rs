//! `brdf-atlas prepare` end to end: the lattice it saves beside the model
//! draws the next `map` inside the default view (the report and the
//! sidecar say so), a damaged
//! lattice is named in one note and the map drawn without it, and bad
//! requests get one line.

mod common;

use common::{Fixture, assert_one_error_line, brdf_atlas, map, texts};

use brdf_atlas_core::Model;

#[test]
fn a_prepared_model_draws_its_maps_from_the_lattice() {
    let fx = Fixture::new(6, &[]);
    let out = brdf_atlas(["prepare".as_ref(), fx.model().as_os_str()]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("prepared the map of"), "{stdout}");
    let lattice = fx.path("model.lattice");
    assert!(lattice.exists(), "{stdout}");
    assert!(stdout.contains("model.lattice"), "{stdout}");

    // The map inside the default view is the lattice's (the core's tests
    // check it pixel for pixel).
    let png = fx.path("map.png");
    let out = map(&fx.model(), &png, &[&"--size", &"48"]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("prepared map"), "{stdout}");
    assert!(stderr.is_empty(), "{stderr}");
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fx.path("map.json")).unwrap()).unwrap();
    assert_eq!(sidecar["method"]["kind"], "lattice", "{sidecar}");
    assert_eq!(
        sidecar["method"]["nodes"],
        brdf_atlas_core::Atlas::new(Model::open(fx.model()).unwrap())
            .prepared_map()
            .unwrap()
            .expect("the lattice")
            .nodes(),
        "{sidecar}"
    );

    // A damaged lattice: one note, and the map without it.
    std::fs::write(&lattice, b"{\"format\": 3").unwrap();
    let out = map(&fx.model(), &png, &[&"--size", &"32"]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("note: ") && stderr.contains("model.lattice"),
        "{stderr}"
    );
    assert!(!stdout.contains("prepared map"), "{stdout}");
}

#[test]
fn bad_requests_get_one_line() {
    let fx = Fixture::new(4, &[]);
    let missing = fx.path("missing.atlas");
    let out = brdf_atlas(["prepare".as_ref(), missing.as_os_str()]);
    assert_one_error_line(&out, &["missing.atlas"]);
    assert!(!fx.path("missing.lattice").exists());
    for tolerance in ["0", "1.5", "soon"] {
        let out = brdf_atlas([
            "prepare".as_ref(),
            fx.model().as_os_str(),
            "--tolerance".as_ref(),
            tolerance.as_ref(),
        ]);
        let (_, stderr) = texts(&out);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("--tolerance"), "{stderr}");
    }
    let out = brdf_atlas([
        "prepare".as_ref(),
        fx.model().as_os_str(),
        "--blend".as_ref(),
        "plausible".as_ref(),
    ]);
    assert_one_error_line(&out, &["plausible"]);
    assert!(!fx.path("model.lattice").exists());
}
