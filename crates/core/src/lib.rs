//! GPLVM latent spaces of measured BRDFs (Soler, Subr, Nowrouzezahrai 2018).
//!
//! The pipeline: a directory of MERL files becomes a [`store::Store`] (the
//! transformed, centred data `Z`, bin-major, memory-mapped) and its Gram
//! matrix `Y = Z Z^T` in one streaming pass; [`GplvmParams`] fits latent
//! points to `Y` with Hooke-Jeeves ([`optim::HookeJeeves`], O(N^2) per trial
//! through [`incremental::IncrementalCost`]) or L-BFGS; a [`model::Model`]
//! file records the result beside its store.
#![warn(missing_docs)]

pub mod dot;
pub mod error;
pub mod fastexp;
pub mod fastlog;
pub mod gplvm;
pub mod heap;
pub mod incremental;
pub mod kernel;
pub mod likelihood;
pub mod limits;
pub mod locate;
pub mod loo;
pub mod map;
pub mod measure;
pub mod model;
pub mod optim;
pub mod pca;
pub mod reconstruct;
pub mod render;
pub mod store;
pub mod symmetric;
pub mod transform;

pub use error::{CoreError, NoProgress, Progress, Result};
pub use gplvm::{CheckedParams, Fit, GplvmParams};
pub use kernel::Kernel;
pub use likelihood::GramData;
pub use locate::Located;
pub use map::{
    AlbedoMap, AlbedoMethod, DEFAULT_SAMPLES, Segment, View, contour_levels, contours, luminance,
};
pub use model::{FitOptions, FitReport, Model, ModelFile, fit_dir, store_path_for};
pub use optim::OptimizerKind;
pub use reconstruct::Blend;
pub use store::{Dataset, Precision, Store, build_store};
pub use transform::TransformKind;

// The unit tests run under the counting allocator, so `heap` is tested as a
// binary uses it.
#[cfg(test)]
#[global_allocator]
static HEAP: heap::Counting = heap::Counting;
