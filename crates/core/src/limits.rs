//! The limits every reader and writer of brdf-atlas agrees on, in one place.
//!
//! The command-line tool, the C ABI (whose header exports them as
//! `BRDF_ATLAS_*` constants) and the Qt widget take their bounds from here.

/// Largest latent dimension `q` a fit accepts and a model file may hold.
/// Beyond it the latent space stops being something a person can explore, and
/// the optimisers' cost grows as `q N^2` per sweep.
pub const MAX_Q: usize = 16;

/// Largest number of materials of a model (as a store allows).
pub const MAX_MATERIALS: usize = 1 << 20;

/// Largest latent coordinate a model file may hold: a fit keeps its points
/// in `[-1, 1]^q`; far beyond, the kernel is 0 between any two points.
pub const LATENT_LIMIT: f64 = 1e3;

/// Largest side of an albedo map, in pixels.
pub const MAX_MAP_SIDE: usize = 16384;

/// Largest side of a picture a map sidecar may describe, in pixels.
pub const MAX_SIDECAR_SIDE: usize = 1 << 16;

/// Half-width of the default view of a map: the fit's box `[-1, 1]^2` plus
/// a 10% margin.
pub const DEFAULT_VIEW_HALF_WIDTH: f64 = 1.1;
