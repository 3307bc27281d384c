//! The MERL reader: any bytes as a `.binary` file (see brdf_atlas_hostile::fuzz::merl).
#![no_main]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let dir = DIR.get_or_init(|| tempfile::tempdir().expect("temp dir"));
    brdf_atlas_hostile::fuzz::merl(dir.path(), data);
});
