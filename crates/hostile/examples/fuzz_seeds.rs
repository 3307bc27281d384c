//! Write the seed corpora of the fuzz targets:
//!
//!     cargo run --release -p brdf-atlas-hostile --example fuzz_seeds -- fuzz/corpus
//!
//! Into `DIR/merl`, `DIR/model`, `DIR/store` and `DIR/sidecar`: small valid
//! inputs (the seed model of `small_model`, its store, MERL tables of a few
//! dims, a map sidecar) and every hostile case of this crate.

use std::path::{Path, PathBuf};

use brdf_atlas_core::store_path_for;
use brdf_atlas_hostile::{
    fuzz, merl_bytes, merl_cases, model_cases, sidecar_cases, small_model, small_sidecar,
};
use brdf_merl::Dims;
use brdf_merl::synth::database;

fn copy(from: &Path, to_dir: &Path, name: &str) {
    std::fs::create_dir_all(to_dir).unwrap();
    std::fs::copy(from, to_dir.join(name)).unwrap_or_else(|e| panic!("{}: {e}", from.display()));
}

fn main() {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .expect("usage: fuzz_seeds CORPUS_DIR"),
    );
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();

    let merl = out.join("merl");
    std::fs::create_dir_all(&merl).unwrap();
    std::fs::write(merl.join("valid-1x1x1"), merl_bytes(1, 1, 1, 0.5)).unwrap();
    for dims in [Dims::new(2, 2, 4).unwrap(), Dims::new(3, 2, 5).unwrap()] {
        let path = merl.join(format!("valid-{dims}"));
        database(1, 7)[0].brdf.table(dims).write(&path).unwrap();
    }
    let cases = t.join("merl-cases");
    std::fs::create_dir_all(&cases).unwrap();
    for c in merl_cases(&cases) {
        if c.path.is_file() {
            copy(&c.path, &merl, &c.label());
        }
    }

    let model = small_model(&t.join("seed"));
    // The store's checksum as the placeholder the model target fills in.
    let text = std::fs::read_to_string(&model).unwrap();
    let checksum = text
        .split("\"checksum\": \"")
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .expect("a checksum");
    let placeholder = std::str::from_utf8(fuzz::CHECKSUM_PLACEHOLDER).unwrap();
    std::fs::create_dir_all(out.join("model")).unwrap();
    std::fs::write(
        out.join("model").join("valid-small.atlas"),
        text.replace(checksum, placeholder),
    )
    .unwrap();
    copy(
        &store_path_for(&model),
        &out.join("store"),
        "valid-small.store",
    );
    let cases = t.join("model-cases");
    std::fs::create_dir_all(&cases).unwrap();
    for c in model_cases(&cases, &model) {
        copy(&c.path, &out.join("model"), &c.label());
        if c.names != c.path && c.names.is_file() {
            copy(
                &c.names,
                &out.join("store"),
                &c.label().replace(".atlas", ".store"),
            );
        }
    }

    let sidecar = small_sidecar(&model, &t.join("map.json"));
    copy(&sidecar, &out.join("sidecar"), "valid-map.json");
    let cases = t.join("sidecar-cases");
    std::fs::create_dir_all(&cases).unwrap();
    for c in sidecar_cases(&cases, &sidecar) {
        copy(&c.path, &out.join("sidecar"), &c.label());
    }
    println!("wrote seed corpora to {}", out.display());
}
