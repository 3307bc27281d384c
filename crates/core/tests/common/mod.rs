//! What the plausibility and soft-floor tests share: small synthetic
//! models fitted in a temporary directory, and points where their GP blend
//! overshoots.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};

use brdf_atlas_core::{FitOptions, GplvmParams, NoProgress, Precision, TransformKind, fit_dir};
use brdf_merl::{Dims, synth};

/// Dims of the synthetic materials.
pub const DIMS: Dims = Dims {
    theta_h: 12,
    theta_d: 12,
    phi_d: 24,
};

/// A q = 2 model of `count` synthetic materials in `transform`, fitted in
/// `dir` (the materials written once per count).
pub fn fit(dir: &Path, count: usize, transform: TransformKind) -> PathBuf {
    let data = dir.join(format!("data-{count}"));
    if !data.exists() {
        synth::write_dir(&data, count, DIMS, 5).unwrap();
    }
    let model = dir.join(format!("{}-{count}.atlas", transform.name()));
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform,
        precision: Precision::F64,
    };
    fit_dir(&data, &model, &options, &NoProgress).unwrap();
    model
}

/// Points where the GP blend of the small synthetic models overshoots.
pub const POINTS: [[f64; 2]; 5] = [
    [0.31, -0.42],
    [-0.9, 0.8],
    [1.05, 1.05],
    [-1.1, -0.2],
    [0.0, 0.0],
];
