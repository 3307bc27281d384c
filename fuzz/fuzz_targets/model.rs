//! The model loader: any bytes as a model file's JSON, beside the valid
//! store of the seed model (see brdf_atlas_hostile::fuzz::model).
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

static MODEL: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let (_, model) = MODEL.get_or_init(|| {
        let dir = tempfile::tempdir().expect("temp dir");
        let model = brdf_atlas_hostile::small_model(dir.path());
        (dir, model)
    });
    brdf_atlas_hostile::fuzz::model(model, data);
});
