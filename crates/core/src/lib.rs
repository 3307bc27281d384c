//! GPLVM latent spaces of measured BRDFs (Soler, Subr, Nowrouzezahrai 2018).
//!
//! The modules follow the pipeline:
//!
//! - [`data`](self#data): a directory of MERL files ([`Dataset`]) becomes a
//!   [`Store`] (the transformed, centred data `Z`, bin-major,
//!   memory-mapped) and its Gram matrix `Y = Z Z^T`, in one streaming pass;
//! - `gplvm`: [`GplvmParams`] fits latent points to `Y`, from a PCA start,
//!   with Hooke-Jeeves (O(N^2) per trial through Sherman-Morrison and
//!   determinant-lemma updates) or L-BFGS;
//! - `model`: a [`Model`] is the fitted latent space beside its store, as a
//!   versioned file ([`ModelFile`]) or in memory; it answers the material at
//!   a latent point under a rule (`model::blend`: [`Blend`], [`BlendRule`],
//!   [`Plausibility`], the [`soft_floor`]);
//! - `fit`: [`fit_dir`] runs the whole pipeline, from a directory of MERL
//!   files to a model on disk whose materials are judged at their own
//!   points ([`fidelity`]);
//! - `locate`: where a new material lands ([`Located`]);
//! - `maps`: albedo maps ([`AlbedoMap`]), the exact albedos and
//!   [`albedo_field`]s they are built from, the prepared map
//!   ([`AlbedoLattice`]) and contours ([`contours`]; their pictures are
//!   drawn by the `brdf-atlas-pictures` crate);
//! - `eval`: leave-one-out errors ([`loo`]) and how each material comes
//!   back at its own point and left out ([`fidelity`]);
//! - [`simd`]: the vectorised kernels the hot loops share (CPU features are
//!   detected once).
//!
//! ```no_run
//! use brdf_atlas_core::{Atlas, BlendRule, MapRequest, Model, View};
//!
//! let atlas = Atlas::new(Model::open("atlas.model")?);
//! let material = atlas.model().at(&[0.3, -0.5], BlendRule::Gp)?;
//! let table = material.table()?;
//! let map = atlas.map(MapRequest::new(256, 256).view(View::default()))?;
//! # let _ = (table, map);
//! # Ok::<(), brdf_atlas_core::CoreError>(())
//! ```
#![warn(missing_docs)]

mod data;
pub mod dense;
mod error;
mod eval;
mod fit;
mod gplvm;
pub mod heap;
pub mod limits;
mod locate;
mod maps;
mod model;
mod progress;
pub mod simd;

pub use data::{
    Dataset, Precision, Rows, Store, StoreIdentity, TransformKind, build_scratch_store, build_store,
};
pub use error::{CoreError, ParamError, Result};
pub use eval::{fidelity, loo};
pub use fit::{
    DEFAULT_NOISE, DEFAULT_TRANSFORM, FitOptions, FitReport, PAPER_KERNEL, PAPER_TRANSFORM,
    StorePolicy, default_kernel, fit_dir, fit_dir_with,
};
pub use gplvm::optim;
pub use gplvm::{CheckedParams, DriftStats, Fit, GplvmParams, GramData, Kernel, OptimizerKind};
pub use locate::Located;
pub use maps::{
    AlbedoField, AlbedoLattice, AlbedoMap, AlbedoMethod, AlbedoRequest, Atlas, DEFAULT_SAMPLES,
    FIELD_SAMPLES, FIT_FIELD_SIZE, FieldCheck, FieldRequest, Integration, LATTICE_TOLERANCE,
    MapRequest, NODE_PHI_D_STEP, Segment, View, contour_levels, contours, fields_path,
    fit_field_views, lattice_path, luminance,
};
pub use maps::{albedo_field, field_check, lattice, map_error};
pub use model::blend::soft_floor;
pub use model::blend::{Blend, BlendRule, Confidence, LOW_CONFIDENCE_VARIANCE, Plausibility};
pub use model::{FitRecord, InputIdentity, Model, ModelFile, StoreRef, store_path_for};
pub use progress::{NoProgress, Progress};
pub use simd::fastlog;

/// The SIGBUS handler that keeps a store truncated under its map from
/// killing the process, and how a host opts out of it before the first
/// model is opened ([`brdf_mapguard`]'s docs say what it installs).
pub use brdf_mapguard::{NO_HANDLER_ENV, set_sigbus_guard, sigbus_guarded};

// The unit tests run under the counting allocator, so `heap` is tested as a
// binary uses it.
#[cfg(test)]
#[global_allocator]
static HEAP: heap::Counting = heap::Counting;
