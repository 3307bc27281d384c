//! The MERL measured-BRDF format.
//!
//! Read and validate `.binary` files ([`MerlFile`], memory-mapped; [`MerlTable`],
//! in memory), look up bins from angles or directions ([`Dims`], [`HalfDiff`]),
//! write tables atomically, integrate albedo ([`Quadrature`]), synthesise
//! analytic materials in the same layout ([`synth`]) and tabulate the 100
//! MERL materials as fitted by Neural BRDF ([`nbrdf`]).
//!
//! ```
//! use brdf_merl::{Dims, MerlTable, Quadrature};
//! // A small Lambertian table of albedo 0.5: f = 0.5 / pi everywhere.
//! let dims = Dims::new(16, 16, 32).unwrap();
//! let table = MerlTable::from_fn(dims, |_| Some([0.5 / std::f64::consts::PI; 3]));
//! let albedo = Quadrature::dense(dims, 4).albedo(&table);
//! assert!((albedo[0] - 0.5).abs() < 1e-2);
//! ```
#![warn(missing_docs)]

pub mod albedo;
pub mod angles;
pub mod directional;
pub mod error;
pub mod nbrdf;
pub mod sniff;
pub mod synth;
pub mod table;
pub mod values;

pub use albedo::Quadrature;
pub use angles::{Dims, HalfDiff, Vec3};
pub use directional::DirectionalRule;
pub use error::{MerlError, Result};
pub use table::{INVALID, MerlFile, MerlTable, SCALE};
