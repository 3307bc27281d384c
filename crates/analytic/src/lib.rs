//! Analytic BRDFs fitted to MERL tables: the material a measured table
//! becomes in tools that only read analytic materials (glTF, MaterialX,
//! Mitsuba 3's `principled`), and what it loses on the way.
//!
//! [`Principled`] is glTF 2.0's metallic-roughness BRDF with
//! `KHR_materials_specular` and `KHR_materials_ior`, evaluated as the glTF specification writes
//! it. [`fit_table`] fits it, and the baseline [`GgxLambert`], to a table
//! in the metric of [`samples`] (cosine-weighted log-relative error over a
//! fixed subsample of bins), and states the baseline [`Lambertian`] of the
//! table's albedo in the same metric. [`export`] writes a fit as glTF 2.0,
//! MaterialX and Mitsuba 3 files, with its record.
//!
//! ```
//! use brdf_atlas_analytic::{Analytic, FitParams, Principled, Samples};
//! use brdf_merl::{Dims, MerlTable};
//! // A table of a known glTF material, fitted back.
//! let truth = Principled { base_color: [0.6, 0.3, 0.1], metallic: 0.0, roughness: 0.3,
//!                          specular: 1.0, specular_color: [1.0; 3], ior: 1.5 };
//! let dims = Dims::new(30, 30, 60).unwrap();
//! let table = MerlTable::from_fn(dims, |bin| {
//!     let (wi, wo) = dims.angles_of(bin).directions();
//!     Some(truth.eval(wi, wo))
//! });
//! let samples = Samples::new(&table, "truth").unwrap();
//! let fit = FitParams::default().fit::<Principled>(&samples);
//! assert!(fit.error < 1e-3, "{}", fit.error);
//! assert!((fit.model.roughness - 0.3).abs() < 0.01);
//! ```
#![warn(missing_docs)]

pub mod analytic;
pub mod baseline;
pub mod error;
pub mod export;
pub mod fit;
pub mod geometry;
pub mod principled;
pub mod samples;
pub mod sphere;

pub use analytic::Analytic;
pub use baseline::{GgxLambert, Lambertian};
pub use error::{AnalyticError, Result};
pub use fit::{FitParams, Fitted};
pub use geometry::Geometry;
pub use principled::Principled;
pub use samples::Samples;
pub use sphere::{Light, SWATCH_LIGHTS, sphere_pixels};

use brdf_merl::MerlTable;

/// Share of a picture's term against the table term in [`fit_table`].
pub const PICTURE_SHARE: f64 = 4.0;

/// The fit of a table and its two baselines, in one metric.
#[derive(Debug, Clone, PartialEq)]
pub struct Fits {
    /// The principled model.
    pub principled: Fitted<Principled>,
    /// One GGX lobe over a Lambertian base.
    pub single_lobe: Fitted<GgxLambert>,
    /// A Lambertian of the table's albedo (not fitted).
    pub lambertian: Fitted<Lambertian>,
}

/// The fit `brdf-atlas export` makes: [`fit_table`] with the default
/// parameters and a sphere of [`sphere::FIT_PIXELS`] under `lights`.
pub fn fit_as_exported(table: &MerlTable, what: &str, lights: &[Light]) -> Result<Fits> {
    let picture = sphere_pixels(sphere::FIT_PIXELS, lights);
    fit_table(table, what, &FitParams::default(), Some(&picture))
}

/// Fit [`Principled`] and [`GgxLambert`] to `table` with `params` (the
/// principled model from its own starts and from the lobe's fit), and
/// measure the [`Lambertian`] of its albedo; `what` names the table in
/// errors. With `picture`, the metric also matches those pixels
/// ([`Samples::with_radiance`], share [`PICTURE_SHARE`]).
pub fn fit_table(
    table: &MerlTable,
    what: &str,
    params: &FitParams,
    picture: Option<&[samples::Pixel]>,
) -> Result<Fits> {
    let mut samples = Samples::new(table, what)?;
    if let Some(pixels) = picture {
        samples = samples.with_radiance(table, pixels, PICTURE_SHARE);
    }
    let lambert = Lambertian {
        albedo: samples.albedo(),
    };
    let single_lobe = params.fit::<GgxLambert>(&samples);
    let mut starts = Principled::starts(samples.albedo());
    starts.push(Principled::from_lobe(&single_lobe.model));
    // The Lambertian baseline itself, which the model holds exactly.
    starts.push(Principled {
        base_color: samples.albedo(),
        metallic: 0.0,
        specular: 0.0,
        ..Principled::default()
    });
    Ok(Fits {
        principled: params.fit_from(&samples, starts),
        single_lobe,
        lambertian: Fitted {
            error: samples.error(&lambert),
            model: lambert,
            iterations: 0,
        },
    })
}
