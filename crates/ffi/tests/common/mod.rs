//! What several of the C library's tests share.

use std::path::{Path, PathBuf};

use brdf_atlas_core::{FitOptions, GplvmParams, NoProgress, Precision, TransformKind, fit_dir};
use brdf_merl::{Dims, synth};

/// A model of 4 synthetic materials at 16 x 16 x 32 (log transform, f64
/// store), fitted in `dir`: small enough for a fit and an analytic fit of
/// its points in a test.
pub fn small_model(dir: &Path) -> PathBuf {
    let data = dir.join("data");
    synth::write_dir(&data, 4, Dims::new(16, 16, 32).unwrap(), 2).unwrap();
    let path = dir.join("m.atlas");
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision: Precision::F64,
    };
    fit_dir(&data, &path, &options, &NoProgress).unwrap();
    path
}
