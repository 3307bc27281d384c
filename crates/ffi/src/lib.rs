//! The C ABI of brdf-atlas: open a fitted model, reconstruct a material at
//! any latent point (as a MERL table in memory or a file), evaluate it for
//! direction pairs, read the blend weights and the albedo map (and trace its
//! luminance contours), locate a MERL file in the latent plane, and fit an
//! analytic (glTF) material to a point and write it as glTF, MaterialX and
//! Mitsuba 3 files (`brdf_atlas_model_export`).
//!
//! The header `include/brdf_atlas.h` is generated from this crate by
//! cbindgen (`tests/header.rs` checks it is current);
//! `include/brdf_atlas.hpp` wraps it for C++17. Conventions, as in
//! crates/ffi/README.md:
//!
//! - **Handles.** `brdf_atlas_model_open` gives a `BrdfAtlasModel *` the
//!   caller owns; `brdf_atlas_model_free` releases it (NULL is fine). A
//!   handle is immutable: any number of threads may use one at once.
//! - **Statuses.** Every fallible function returns a [`BrdfAtlasStatus`]
//!   (`BRDF_ATLAS_STATUS_OK` = 0); `brdf_atlas_last_error_message` gives the
//!   one-line message of the last call on the calling thread.
//! - **Outputs** go through out-parameters and caller-allocated buffers with
//!   an explicit length, written only on success; every variable size has a
//!   query (`brdf_atlas_model_table_len`, `brdf_atlas_model_material_count`,
//!   ...), and a short buffer gives `BRDF_ATLAS_STATUS_BUFFER_TOO_SMALL`.
//! - **Nothing a caller passes crashes the host** short of pointers to
//!   memory that is not there: every pointer is checked for NULL and
//!   alignment, every length and coordinate is checked, and every entry
//!   point catches panics (`BRDF_ATLAS_STATUS_PANIC`).
//! - **Files changed while open** do not crash the host either: a store
//!   truncated or rewritten in place under an open handle makes the call
//!   that reads it, and every later call on that handle, return
//!   `BRDF_ATLAS_STATUS_BAD_FILE` ("... changed on disk while open ...")
//!   until the model is reopened (`brdf_atlas_model_open`). For this the
//!   first open installs a process-wide SIGBUS handler that chains to the
//!   host's; `brdf_atlas_set_sigbus_guard(0)` before it (or
//!   `BRDF_ATLAS_NO_SIGBUS_HANDLER=1`) leaves SIGBUS alone.
//!
//! ```
//! use std::ffi::CStr;
//! use brdf_atlas_c::{BrdfAtlasStatus, brdf_atlas_last_error_message, brdf_atlas_model_open};
//!
//! let mut model = std::ptr::null_mut();
//! let status = unsafe { brdf_atlas_model_open(c"missing.atlas".as_ptr(), &mut model) };
//! assert_eq!(status, BrdfAtlasStatus::Io);
//! assert!(model.is_null()); // untouched on failure
//! let message = unsafe { CStr::from_ptr(brdf_atlas_last_error_message()) };
//! assert!(message.to_str().unwrap().starts_with("brdf_atlas_model_open: missing.atlas: "));
//! ```
#![warn(missing_docs)]

pub mod analytic;
mod check;
pub mod consts;
pub mod contour;
pub mod map;
pub mod model;
pub mod plausibility;
pub mod query;
pub mod status;

pub use analytic::{BrdfAtlasAnalytic, brdf_atlas_model_export, brdf_atlas_model_fit_analytic};
pub use consts::{
    BRDF_ATLAS_DEFAULT_VIEW_HALF_WIDTH, BRDF_ATLAS_GIVES_BACK, BRDF_ATLAS_LATENT_LIMIT,
    BRDF_ATLAS_LOW_CONFIDENCE_VARIANCE, BRDF_ATLAS_MARKER_RADIUS, BRDF_ATLAS_MAX_MAP_SIDE,
    BRDF_ATLAS_MAX_MATERIALS, BRDF_ATLAS_MAX_Q, BRDF_ATLAS_MAX_SAMPLES, BRDF_ATLAS_VERSION_MAJOR,
    BRDF_ATLAS_VERSION_MINOR, BRDF_ATLAS_VERSION_PATCH,
};
pub use contour::{BrdfAtlasSegment, brdf_atlas_contour_levels, brdf_atlas_contours};
pub use map::{
    brdf_atlas_model_albedo_map, brdf_atlas_model_albedo_map_cancellable,
    brdf_atlas_model_albedo_map_with, brdf_atlas_model_map, brdf_atlas_model_map_preview,
    brdf_atlas_model_prepare_fit_fields, brdf_atlas_model_prepare_map_fields,
    brdf_atlas_model_saved_fields, brdf_atlas_model_variance_map,
};
pub use model::{
    BrdfAtlasDims, BrdfAtlasModel, BrdfAtlasView, brdf_atlas_model_dims, brdf_atlas_model_free,
    brdf_atlas_model_latent_dim, brdf_atlas_model_latent_point, brdf_atlas_model_material_count,
    brdf_atlas_model_material_name, brdf_atlas_model_open, brdf_atlas_model_table_len,
    brdf_atlas_model_view, brdf_atlas_set_sigbus_guard,
};
pub use plausibility::{
    BRDF_ATLAS_BLEND_FLOOR, BRDF_ATLAS_BLEND_GP, BRDF_ATLAS_BLEND_PLAUSIBLE, BrdfAtlasPlausibility,
    brdf_atlas_model_confidence, brdf_atlas_model_marker, brdf_atlas_model_plausibility,
    brdf_atlas_model_reconstruct_with,
};
pub use query::{
    BrdfAtlasLocation, brdf_atlas_model_eval, brdf_atlas_model_eval_batch, brdf_atlas_model_locate,
    brdf_atlas_model_reconstruct, brdf_atlas_model_reconstruct_to_file, brdf_atlas_model_weights,
};
pub use status::{
    BrdfAtlasStatus, brdf_atlas_last_error_message, brdf_atlas_status_message, brdf_atlas_version,
};
