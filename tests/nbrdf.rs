//! The tool on realistic data: the MERL materials as fitted by a neural
//! model, written by `brdf-atlas nbrdf` into the directory named by
//! `BRDF_ATLAS_NBRDF_DIR`.
//!
//! The tests are ignored by default, so a plain `cargo test` lists them as
//! ignored with the reason instead of passing them. Under continuous
//! integration (`CI=true` when the tests are built, see build.rs) they are
//! ordinary tests, and `.ci/run` writes the data they need. By hand:
//!
//! ```text
//! BRDF_ATLAS_NBRDF_DIR=DIR cargo test --release --test nbrdf -- --ignored
//! ```
//!
//! Run without the variable (or under `CI=true` without it), or with a
//! directory without MERL files, they fail.

mod common;

use std::path::{Path, PathBuf};

use brdf_atlas_pictures::map_picture::read_sidecar;
use brdf_merl::MerlFile;
use common::{binaries, brdf_atlas, fit, header_dims, map, point_after_at, reported, texts};

/// The data directory and its `.binary` files, at least `min` of them; a
/// test failure when the variable is unset or the directory has too few.
fn nbrdf_files(min: usize) -> (PathBuf, Vec<PathBuf>) {
    let Some(dir) = std::env::var_os("BRDF_ATLAS_NBRDF_DIR").filter(|d| !d.is_empty()) else {
        panic!(
            "BRDF_ATLAS_NBRDF_DIR is not set: these tests need realistic MERL data \
             (brdf-atlas nbrdf DIR --count 8, then \
             BRDF_ATLAS_NBRDF_DIR=DIR)"
        );
    };
    let dir = PathBuf::from(dir);
    let files = binaries(&dir);
    assert!(
        files.len() >= min,
        "BRDF_ATLAS_NBRDF_DIR={} holds {} .binary files, this test needs at least {min}",
        dir.display(),
        files.len()
    );
    (dir, files)
}

#[test]
#[cfg_attr(
    not(ci),
    ignore = "needs BRDF_ATLAS_NBRDF_DIR (realistic MERL data, see tests/nbrdf.rs)"
)]
fn info_reports_every_nbrdf_material() {
    let (dir, files) = nbrdf_files(1);

    let out = brdf_atlas(std::iter::once(PathBuf::from("info")).chain(files.iter().cloned()));
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    for f in &files {
        let r = reported(&stdout, f);
        assert_eq!(r.dims, header_dims(f), "{}", f.display());
        // The tool marks bins with a direction below the horizon unmeasured:
        // some, the same in every channel.
        assert!(
            r.invalid[0] > 0 && r.invalid == [r.invalid[0]; 3],
            "{}: {r:?}",
            f.display()
        );
        for a in r.albedo {
            assert!(
                a > 0.0 && a < 1.5,
                "{}: albedo {a} out of (0, 1.5)",
                f.display()
            );
        }
    }
    println!("checked {} materials in {}", files.len(), dir.display());
}

#[test]
#[cfg_attr(
    not(ci),
    ignore = "needs BRDF_ATLAS_NBRDF_DIR (realistic MERL data, see tests/nbrdf.rs)"
)]
fn fit_map_reconstruct_and_locate_nbrdf_materials() {
    // A 2-D fit needs at least 3 materials.
    let (dir, files) = nbrdf_files(3);
    let work = tempfile::tempdir().unwrap();
    let model = work.path().join("nbrdf.atlas");
    let summary = fit(&dir, &model, &["--transform", "log"]);
    assert!(
        summary.contains(&format!("fitted {} materials", files.len())),
        "{summary}"
    );
    assert!(summary.contains("transform log"), "{summary}");

    // A small map: PNG, sidecar with every material.
    let png_path = work.path().join("map.png");
    let out = map(&model, &png_path, &[&"--size", &"64"]);
    assert!(out.status.success(), "map: {}", texts(&out).1);
    let sidecar = read_sidecar(&work.path().join("map.json")).unwrap();
    assert_eq!((sidecar.width, sidecar.height), (64, 64));
    assert_eq!(sidecar.references.len(), files.len());
    assert!(png_path.is_file());

    // A new material halfway between the first two.
    let (a, b) = (sidecar.references[0].latent, sidecar.references[1].latent);
    let at = format!("{},{}", 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]));
    let new = work.path().join("between.binary");
    let out = brdf_atlas([
        Path::new("reconstruct"),
        &model,
        Path::new("--at"),
        Path::new(&at),
        Path::new("-o"),
        &new,
    ]);
    assert!(out.status.success(), "reconstruct: {}", texts(&out).1);
    let table = MerlFile::open(&new).unwrap();
    assert_eq!(table.dims().to_string(), header_dims(&files[0]));
    let mut raw = vec![0.0; 3 * table.dims().bins()];
    table.copy_raw(0, &mut raw);
    assert!(raw.iter().all(|&v| v >= 0.0 || v == -1.0));

    // An input material lands next to itself: in the default view (the
    // search covers the whole plane, so one on the box's edge may land a
    // hair beyond it), nearest to itself.
    let out = brdf_atlas([Path::new("locate"), &model, &files[0]]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "locate: {stderr}");
    let x = point_after_at(stdout.lines().next().unwrap());
    assert!(x.iter().all(|v| (-1.1..=1.1).contains(v)), "{stdout}");
    assert!(
        !stdout.contains("outside the map's default view"),
        "{stdout}"
    );
    let name = files[0].file_stem().unwrap().to_str().unwrap();
    let nearest = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("nearest"))
        .unwrap();
    assert!(nearest.contains(name), "{name} near itself: {stdout}");
    println!("{summary}");
}

#[test]
#[cfg_attr(
    not(ci),
    ignore = "needs BRDF_ATLAS_NBRDF_DIR (realistic MERL data, see tests/nbrdf.rs)"
)]
fn the_default_material_never_reflects_more_than_it_receives_and_its_nodes_are_exact() {
    // Measured materials reflect less than they receive at every incidence;
    // so does the default rule's material, at every point of the default
    // view and beyond it (out to 0.3 past the box), at grazing incidence too.
    // (A few materials fit with a long length scale stay under 1 with a cap
    // at the brightest material alone; where the envelope of several goes
    // over, on the 100 materials beyond the box and in the synthetic sets
    // of crates/core/tests/floor.rs, the cap's reach is what holds it.)
    let (dir, files) = nbrdf_files(3);
    let work = tempfile::tempdir().unwrap();
    let path = work.path().join("nbrdf.atlas");
    fit(&dir, &path, &[]);
    let rule = brdf_merl::DirectionalRule::new(brdf_merl::Dims::MERL);
    for f in &files {
        let (a, deg) = rule.max_albedo(&brdf_merl::MerlTable::read(f).unwrap());
        assert!(a < 1.0, "{}: {a} at {deg} degrees", f.display());
    }
    let model = brdf_atlas_core::Atlas::new(brdf_atlas_core::Model::open(&path).unwrap());
    for k in 0..49 {
        let x = [
            -1.3 + 2.6 * (k / 7) as f64 / 6.0,
            -1.3 + 2.6 * (k % 7) as f64 / 6.0,
        ];
        let blend = model.at(&x, brdf_atlas_core::BlendRule::Floor).unwrap();
        let (a, deg) = blend.largest_albedo();
        assert!(
            a <= 1.0,
            "at {x:?}: largest directional albedo {a} at {deg} degrees"
        );
    }
    // The map's nodes integrate the cubic interpolant of every 8th phi_d
    // bin: within 0.05% of the dense rule per channel for these 8
    // materials' default material, over the view (0.1% of the largest
    // channel at worst on the 100 materials, docs/performance.md).
    let points: Vec<[f64; 2]> = (0..16)
        .map(|k| [-1.05 + 0.7 * (k / 4) as f64, -1.05 + 0.7 * (k % 4) as f64])
        .collect();
    let rule = brdf_atlas_core::BlendRule::Floor;
    let dense = model
        .exact_albedos(&points, brdf_atlas_core::AlbedoRequest::new().rule(rule))
        .unwrap();
    let nodes = model
        .exact_albedos(
            &points,
            brdf_atlas_core::AlbedoRequest::new()
                .rule(rule)
                .integration(brdf_atlas_core::Integration::Nodes),
        )
        .unwrap();
    for ((x, d), n) in points.iter().zip(&dense).zip(&nodes) {
        for c in 0..3 {
            assert!(
                (n[c] - d[c]).abs() <= 5e-4 * d[c],
                "at {x:?}: {n:?} vs {d:?}"
            );
        }
    }
}
