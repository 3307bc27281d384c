//! `include/brdf_atlas.h` is what cbindgen generates from this crate, byte
//! for byte (with `BRDF_ATLAS_UPDATE_HEADER=1` the test rewrites it instead);
//! its version macros are the workspace version and its limits the core's.

use std::path::Path;

#[test]
fn header_is_current() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("crates/ffi/cbindgen.toml is valid");
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(crate_dir.join("src/lib.rs"))
        .generate()
        .expect("cbindgen parses the ffi crate");
    let mut generated = Vec::new();
    bindings.write(&mut generated);

    let header = crate_dir.join("../../include/brdf_atlas.h");
    if std::env::var_os("BRDF_ATLAS_UPDATE_HEADER").is_some_and(|v| v == "1") {
        std::fs::write(&header, &generated).expect("write include/brdf_atlas.h");
        eprintln!("rewrote {}", header.display());
        return;
    }
    let committed = std::fs::read(&header).unwrap_or_default();
    if committed != generated {
        let (old, new) = (
            String::from_utf8_lossy(&committed),
            String::from_utf8_lossy(&generated),
        );
        let first = old
            .lines()
            .zip(new.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(old.lines().count().min(new.lines().count()));
        panic!(
            "include/brdf_atlas.h is not what cbindgen generates from crates/ffi \
             (first difference at line {}:\n  committed: {:?}\n  generated: {:?}).\n\
             The header is generated, never edited: regenerate it with\n    \
             BRDF_ATLAS_UPDATE_HEADER=1 cargo test --release -p brdf-atlas-ffi --test header\n\
             and commit the result.",
            first + 1,
            old.lines().nth(first).unwrap_or("<end of file>"),
            new.lines().nth(first).unwrap_or("<end of file>"),
        );
    }
}

/// The value of `#define NAME value` in the committed header.
fn define(header: &str, name: &str) -> String {
    let prefix = format!("#define {name} ");
    header
        .lines()
        .find_map(|l| l.strip_prefix(&prefix))
        .unwrap_or_else(|| panic!("include/brdf_atlas.h defines no {name}"))
        .trim()
        .to_owned()
}

fn committed_header() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../include/brdf_atlas.h");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn version_macros_are_the_workspace_version() {
    // The version in the workspace's Cargo.toml, read from the file itself.
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../Cargo.toml");
    let manifest = std::fs::read_to_string(&manifest).expect("the workspace Cargo.toml");
    let version = manifest
        .split("[workspace.package]")
        .nth(1)
        .and_then(|s| s.lines().find_map(|l| l.strip_prefix("version = ")))
        .expect("a version in [workspace.package]")
        .trim_matches('"');
    assert_eq!(version, env!("CARGO_PKG_VERSION"));
    let numbers: Vec<&str> = version.split('.').collect();
    let header = committed_header();
    for (part, want) in ["MAJOR", "MINOR", "PATCH"].iter().zip(&numbers) {
        let name = format!("BRDF_ATLAS_VERSION_{part}");
        assert_eq!(
            &define(&header, &name),
            want,
            "{name} in include/brdf_atlas.h"
        );
    }
    use brdf_atlas_c::{
        BRDF_ATLAS_VERSION_MAJOR as MAJOR, BRDF_ATLAS_VERSION_MINOR as MINOR,
        BRDF_ATLAS_VERSION_PATCH as PATCH,
    };
    assert_eq!(format!("{MAJOR}.{MINOR}.{PATCH}"), version);
}

#[test]
fn limits_are_the_core_limits() {
    use brdf_atlas_core::limits;
    let header = committed_header();
    let int = |name: &str| -> usize {
        let v = define(&header, name);
        match v.strip_prefix("(1 << ").and_then(|s| s.strip_suffix(')')) {
            Some(shift) => 1 << shift.parse::<u32>().unwrap(),
            None => v.parse().unwrap_or_else(|e| panic!("{name} = {v}: {e}")),
        }
    };
    let float = |name: &str| -> f64 { define(&header, name).parse().unwrap() };
    assert_eq!(int("BRDF_ATLAS_MAX_Q"), limits::MAX_Q);
    assert_eq!(int("BRDF_ATLAS_MAX_MATERIALS"), limits::MAX_MATERIALS);
    assert_eq!(int("BRDF_ATLAS_MAX_MAP_SIDE"), limits::MAX_MAP_SIDE);
    assert_eq!(float("BRDF_ATLAS_LATENT_LIMIT"), limits::LATENT_LIMIT);
    assert_eq!(
        float("BRDF_ATLAS_DEFAULT_VIEW_HALF_WIDTH"),
        limits::DEFAULT_VIEW_HALF_WIDTH
    );
}
