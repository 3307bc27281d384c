//! What a fitted model answers: the material at a latent point, where a new
//! material lands, albedo maps with their contours, and their pictures;
//! lit spheres of materials and sheets of them.

pub(crate) mod budget;
pub mod contour;
mod decor;
pub(crate) mod every;
mod exact;
pub mod field;
pub mod floor;
mod labels;
pub mod lattice;
pub mod locate;
pub mod map;
pub mod measure;
mod overlay;
mod paint;
pub mod plausibility;
mod prepared;
pub mod reconstruct;
pub mod render;
pub mod sheet;
mod sidecar;
mod steps;
pub mod swatch;
mod sweep;
mod view;

pub use contour::{Segment, contour_levels, contours, luminance};
pub use exact::NODE_PHI_D_STEP;
pub use lattice::{AlbedoLattice, LATTICE_TOLERANCE, lattice_path};
pub use locate::Located;
pub use map::{AlbedoMap, AlbedoMethod, DEFAULT_SAMPLES, View};
pub use plausibility::{BlendRule, Confidence, LOW_CONFIDENCE_VARIANCE, Plausibility};
pub use reconstruct::Blend;
