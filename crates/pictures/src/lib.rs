//! The pictures of brdf-atlas, drawn from a fitted model
//! ([`brdf_atlas_core`]): albedo maps as PNG (contours, the materials' dots
//! and labels, axis ticks, a colour key, faded where the model knows
//! little) and EXR, with the JSON sidecar that describes them; lit spheres
//! of materials and sheets of them.
//!
//! - [`map_picture`]: a map's [`Picture`](map_picture::Picture), its PNG,
//!   EXR and sidecar, written atomically, and the sidecar's reader;
//! - [`sphere`]: one lit sphere of anything
//!   [`Reflectance`](sphere::Reflectance) (a model's point queries or a
//!   MERL table);
//! - [`swatch_sheet`]: spheres at a grid of latent points laid out with
//!   their coordinates, as PNG and EXR.
//!
//! Text is set in DejaVu Sans, embedded once ([`FONT`]). The core library,
//! and so the C library and the Python package built on it, carry none of
//! this: no font, no PNG or EXR encoder.
#![warn(missing_docs)]

mod canvas;
mod labels;
pub mod map_picture;
mod overlay;
mod sidecar;
pub mod sphere;
pub mod swatch_sheet;
mod ticks_and_key;

pub use canvas::FONT;
