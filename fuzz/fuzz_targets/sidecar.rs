//! The map sidecar reader: any bytes as a sidecar's JSON (see brdf_atlas_hostile::fuzz::sidecar).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    brdf_atlas_hostile::fuzz::sidecar(data);
});
