//! What a fitted model answers: the material at a latent point, where a new
//! material lands, albedo maps with their contours, and their pictures.

pub mod contour;
pub mod locate;
pub mod map;
pub mod reconstruct;
pub mod render;

pub use contour::{Segment, contour_levels, contours, luminance};
pub use locate::Located;
pub use map::{AlbedoMap, AlbedoMethod, DEFAULT_SAMPLES, View};
pub use reconstruct::Blend;
