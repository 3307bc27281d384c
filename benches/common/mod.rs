//! What the benchmarks share: their input data.

use std::path::{Path, PathBuf};

use brdf_merl::{Dims, synth};

/// The MERL directory named by `BRDF_ATLAS_NBRDF_DIR`, or else 16 synthetic
/// materials at 90 x 90 x 180 written under `tmp`.
pub fn data_dir(tmp: &Path) -> PathBuf {
    if let Some(dir) = std::env::var_os("BRDF_ATLAS_NBRDF_DIR") {
        return PathBuf::from(dir);
    }
    let dir = tmp.join("merl");
    synth::write_dir(&dir, 16, Dims::MERL, 1).expect("write the input");
    dir
}
