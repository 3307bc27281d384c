//! The model loader: any bytes as a model file's JSON, beside the valid
//! store of the seed model (see brdf_atlas_hostile::fuzz::model).
#![no_main]

use std::sync::OnceLock;

use brdf_atlas_hostile::fuzz::{self, SeedModel};
use libfuzzer_sys::fuzz_target;

static SEED: OnceLock<(tempfile::TempDir, SeedModel)> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let (_, seed) = SEED.get_or_init(|| {
        let dir = tempfile::tempdir().expect("temp dir");
        let seed = SeedModel::new(dir.path());
        (dir, seed)
    });
    fuzz::model(seed, data);
});
