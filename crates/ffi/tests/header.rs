//! `include/brdf_atlas.h` is what cbindgen generates from this crate, byte
//! for byte. With `BRDF_ATLAS_UPDATE_HEADER=1` the test rewrites it instead.

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
