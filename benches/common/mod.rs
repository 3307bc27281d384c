//! What the benchmarks share: their input data.

use std::path::{Path, PathBuf};

use brdf_merl::Dims;
use brdf_merl::synth::database;

/// The MERL directory named by `BRDF_ATLAS_NBRDF_DIR`, or else 16 synthetic
/// materials at 90 x 90 x 180 written under `tmp`.
pub fn data_dir(tmp: &Path) -> PathBuf {
    if let Some(dir) = std::env::var_os("BRDF_ATLAS_NBRDF_DIR") {
        return PathBuf::from(dir);
    }
    let dir = tmp.join("merl");
    std::fs::create_dir_all(&dir).expect("temporary directory");
    for m in database(16, 1) {
        m.brdf
            .table(Dims::MERL)
            .write(dir.join(format!("{}.binary", m.name)))
            .expect("write input");
    }
    dir
}
