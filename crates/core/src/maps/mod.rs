//! Albedo maps of a 2-D latent space and what they are built from: the
//! latent window shown ([`view`]), exact albedos at many points
//! ([`exact_albedos`]), the albedo field that interpolates them
//! ([`albedo_field`]), the map itself ([`albedo_map`]), the prepared map's
//! lattice saved beside the model ([`lattice`], [`prepared_map`]), contours
//! ([`contour`]) and a map's error against reference albedos
//! ([`map_error`]). Their pictures are drawn by the `brdf-atlas-pictures`
//! crate.

pub mod albedo_field;
pub mod albedo_map;
pub mod contour;
mod exact_albedos;
pub mod lattice;
pub mod map_error;
mod prepared_map;
mod view;

pub use albedo_map::{AlbedoMap, AlbedoMethod, DEFAULT_SAMPLES, View};
pub use contour::{Segment, contour_levels, contours, luminance};
pub use exact_albedos::NODE_PHI_D_STEP;
pub use lattice::{AlbedoLattice, LATTICE_TOLERANCE, lattice_path};
