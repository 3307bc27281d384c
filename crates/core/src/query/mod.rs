//! What a fitted model answers: the material at a latent point, where a new
//! material lands, albedo maps with their contours (their pictures are
//! drawn by the `brdf-atlas-pictures` crate).

pub(crate) mod budget;
pub mod contour;
pub(crate) mod every;
mod exact;
pub mod field;
pub mod floor;
pub mod lattice;
pub mod locate;
pub mod map;
pub mod measure;
pub mod plausibility;
mod prepared;
pub mod reconstruct;
mod steps;
mod sweep;
mod view;

pub use contour::{Segment, contour_levels, contours, luminance};
pub use exact::NODE_PHI_D_STEP;
pub use lattice::{AlbedoLattice, LATTICE_TOLERANCE, lattice_path};
pub use locate::Located;
pub use map::{AlbedoMap, AlbedoMethod, DEFAULT_SAMPLES, View};
pub use plausibility::{BlendRule, Confidence, LOW_CONFIDENCE_VARIANCE, Plausibility};
pub use reconstruct::Blend;
