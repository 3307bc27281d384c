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
pub mod field_check;
pub mod lattice;
pub mod map_error;
mod patches;
mod pixel_rule;
mod prepared_map;
pub mod saved_fields;
mod view;

pub use albedo_map::{AlbedoMap, AlbedoMethod, DEFAULT_SAMPLES, View};
pub use contour::{Segment, contour_levels, contours, luminance};
pub use exact_albedos::NODE_PHI_D_STEP;
pub use lattice::{AlbedoLattice, LATTICE_TOLERANCE, lattice_path};
pub use saved_fields::{FIT_FIELD_SIZE, fields_path, fit_field_views};

use std::sync::{Arc, OnceLock};

use crate::error::Result;
use crate::model::Model;
use crate::model::blend::pass_bins::Every;
use crate::model::blend::{Blend, BlendRule, Plausibility, plausibility_sweep, plausible_steps};

mod recent;

use recent::Recent;

pub use albedo_field::{AlbedoField, FIELD_SAMPLES, FieldRequest};
pub use albedo_map::MapRequest;
pub use exact_albedos::{AlbedoRequest, Integration};
pub use field_check::FieldCheck;

/// The maps of one fitted model: a shared [`Model`] and what its maps
/// need and keep between them (the per-material albedos, the rows of the
/// albedo rules, the last albedo fields and per-pixel rules, the prepared
/// map saved beside the model). The model answers the material at a point
/// ([`Model::at`]); an atlas answers for many points at once: albedo maps
/// ([`Atlas::map`]), albedo fields ([`Atlas::field`]), exact albedos
/// ([`Atlas::exact_albedos`]), the prepared map ([`Atlas::prepare_map`])
/// and the plausibility at many points ([`Atlas::plausibilities`]).
///
/// Its caches are built by the first map that needs them and kept, so that
/// a viewer redrawing the map on every zoom or pan (the BRDF Explorer
/// plugin does) pays once for the passes over the store behind them.
///
/// ```no_run
/// use brdf_atlas_core::{Atlas, MapRequest, Model, View};
///
/// let atlas = Atlas::new(Model::open("atlas.model")?);
/// let map = atlas.map(MapRequest::new(256, 256).view(View::default()))?;
/// # let _ = map;
/// # Ok::<(), brdf_atlas_core::CoreError>(())
/// ```
pub struct Atlas {
    model: Arc<Model>,
    /// The linear map's `K^-1 A` (one N-vector per channel) and the mean's albedo.
    linear: OnceLock<([Vec<f64>; 3], [f64; 3])>,
    /// The mean material's shape inside each quadrature box.
    shape: OnceLock<Vec<f64>>,
    /// The dense rule's store rows and weights.
    rule_rows: OnceLock<exact_albedos::RuleRows>,
    /// The rows of the map's nodes: the dense rule on fewer phi_d bins.
    node_rows: OnceLock<exact_albedos::RuleRows>,
    /// The last albedo fields built, and domains given up.
    fields: Recent<albedo_field::Cached>,
    /// The map's last per-pixel rules, one a sample count.
    pixel_rules: Recent<pixel_rule::PixelRule>,
    /// The prepared map saved beside the model, read on first use.
    lattice: OnceLock<lattice::Loaded>,
    /// The fields saved beside the model, read on first use.
    saved: saved_fields::Slot,
}

impl std::fmt::Debug for Atlas {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Atlas").field("model", &self.model).finish()
    }
}

/// An atlas is a handle onto its shared model, as an `Arc` is: the model's
/// own questions ([`Model::at`], [`Model::names`], ...) are asked of it
/// directly.
impl std::ops::Deref for Atlas {
    type Target = Model;

    fn deref(&self) -> &Model {
        &self.model
    }
}

impl Atlas {
    /// The atlas of `model` (a [`Model`] or an `Arc` of one shared with
    /// others), its caches empty.
    pub fn new(model: impl Into<Arc<Model>>) -> Atlas {
        Atlas {
            model: model.into(),
            linear: OnceLock::new(),
            shape: OnceLock::new(),
            rule_rows: OnceLock::new(),
            node_rows: OnceLock::new(),
            fields: Recent::default(),
            pixel_rules: Recent::default(),
            lattice: OnceLock::new(),
            saved: saved_fields::Slot::default(),
        }
    }

    /// The model the maps are of.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// The plausibility of the material `rule` forms at each of `points`
    /// (2-D latent points), reading the bins `every` keeps: one pass over
    /// the store for all the points under the gp and floor rules, the
    /// plausible rule's steps first where asked.
    pub fn plausibilities(
        &self,
        points: &[[f64; 2]],
        rule: BlendRule,
        every: Every,
    ) -> Result<Vec<Plausibility>> {
        plausibility_sweep::plausibilities(&self.model, points, rule, every)
    }

    /// [`Atlas::plausibilities`] of the gp and the floor rules together, in
    /// one pass over the store.
    pub fn plausibilities_gp_and_floor(
        &self,
        points: &[[f64; 2]],
        every: Every,
    ) -> Result<(Vec<Plausibility>, Vec<Plausibility>)> {
        plausibility_sweep::plausibilities_gp_and_floor(&self.model, points, every)
    }

    /// The largest directional albedo of the material `rule` forms at each
    /// of `points`, with its incidence (degrees from the normal).
    pub fn largest_albedos(&self, points: &[[f64; 2]], rule: BlendRule) -> Result<Vec<(f64, f64)>> {
        plausibility_sweep::largest_albedos(&self.model, points, rule)
    }

    /// The plausible rule's blends at `points` ([`BlendRule::Plausible`]),
    /// their steps found together.
    pub fn plausible_blends(&self, points: &[Vec<f64>]) -> Result<Vec<Blend<'_>>> {
        plausible_steps::plausible_blends(&self.model, points)
    }
}
