//! How physical the material at a latent point is, and how much the model
//! knows there; the table under a chosen blend rule.

use brdf_atlas_core::BlendRule;

use crate::check;
use crate::model::{self as handle, BrdfAtlasModel};
use crate::status::{BrdfAtlasStatus, Failure, Result, run};

/// The GPLVM's own weights `K^-1 k(x)` (the paper's reconstruction): where
/// they take mixed signs the blend can go negative and is clamped to 0.
pub const BRDF_ATLAS_BLEND_GP: i32 = 0;
/// The GP's weights moved towards a kernel-weighted average of the materials,
/// in each theta_h bin of the table just far enough that the clamp to >= 0
/// removes at most 0.05% of that bin's cosine-weighted reflectance, then
/// everywhere far enough that no directional albedo exceeds 1 (one more
/// pass over the store).
pub const BRDF_ATLAS_BLEND_PLAUSIBLE: i32 = 1;
/// The GP's blend with every value lifted softly onto a floor at 0.3 times
/// a kernel-weighted average of the materials (never negative; no extra
/// pass over the store). The library's default: what
/// `brdf_atlas_model_reconstruct`, `brdf_atlas_model_eval` and
/// `brdf_atlas_model_albedo_map` use.
pub const BRDF_ATLAS_BLEND_FLOOR: i32 = 2;

/// What the model knows at a latent point and how physical its material is.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrdfAtlasPlausibility {
    /// Share (0..1) of the cosine-weighted reflectance that the clamp to
    /// >= 0 removes (values before the clamp, over measured bins).
    pub clamped_reflectance: f64,
    /// Share (0..1) of the measured values that are negative before the clamp.
    pub clamped_values: f64,
    /// Largest directional albedo of the material over channels and
    /// incidence angles (a physical material has at most 1).
    pub max_albedo: f64,
    /// Incidence of `max_albedo`, degrees from the normal.
    pub max_albedo_incidence: f64,
    /// The GP's predictive variance, 0 at an input material, 1 where the
    /// data say nothing.
    pub variance: f64,
    /// The sum of the blend weights (towards 0 far from the data).
    pub weight_sum: f64,
    /// 1 when `clamped_reflectance <= 0.01` and `max_albedo <= 1`, else 0.
    pub plausible: i32,
    /// 1 when `variance > 0.5`: the model knows little here.
    pub low_confidence: i32,
}

/// The blend rule of a C constant.
pub(crate) fn rule(value: i32) -> Result<BlendRule> {
    match value {
        BRDF_ATLAS_BLEND_GP => Ok(BlendRule::Gp),
        BRDF_ATLAS_BLEND_PLAUSIBLE => Ok(BlendRule::Plausible),
        BRDF_ATLAS_BLEND_FLOOR => Ok(BlendRule::Floor),
        v => Err(Failure::invalid(format!(
            "blend rule {v}: expected BRDF_ATLAS_BLEND_GP (0), BRDF_ATLAS_BLEND_PLAUSIBLE (1) \
             or BRDF_ATLAS_BLEND_FLOOR (2)"
        ))),
    }
}

/// Plausibility and confidence of the material at latent point (x, y) under
/// blend rule `blend` (`BRDF_ATLAS_BLEND_GP`, `BRDF_ATLAS_BLEND_PLAUSIBLE` or
/// `BRDF_ATLAS_BLEND_FLOOR`).
/// Reads the whole store once (about as long as a reconstruction).
///
/// Ownership: `model` is borrowed; `out` is caller-owned, written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite, an
/// unknown rule), UNSUPPORTED (the model is not 2-D).
///
/// # Safety
/// `model` is NULL or a live handle; `out` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_plausibility(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    blend: i32,
    out: *mut BrdfAtlasPlausibility,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_plausibility", || {
        let m = unsafe { handle::borrow(model) }?;
        let out = unsafe { check::out(out, "out") }?;
        let p = check::point(m, x, y)?;
        let b = m.at(&p, rule(blend)?)?;
        let (pl, c) = (b.plausibility()?, b.confidence());
        *out = BrdfAtlasPlausibility {
            clamped_reflectance: pl.clamped_reflectance,
            clamped_values: pl.clamped_values,
            max_albedo: pl.max_albedo,
            max_albedo_incidence: pl.max_albedo_incidence,
            variance: c.variance,
            weight_sum: c.weight_sum,
            plausible: i32::from(pl.is_plausible()),
            low_confidence: i32::from(c.is_low()),
        };
        Ok(())
    })
}

/// The GP's predictive variance at latent point (x, y) (0 at an input
/// material, 1 where the data say nothing; above 0.5 the model knows
/// little) and the sum of the blend weights. Costs as much as
/// `brdf_atlas_model_weights`: no pass over the store.
///
/// Ownership: `model` is borrowed; `variance` and `weight_sum` are
/// caller-owned (either may be NULL), written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite),
/// UNSUPPORTED (the model is not 2-D).
///
/// # Safety
/// `model` is NULL or a live handle; `variance` and `weight_sum` are NULL or
/// valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_confidence(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    variance: *mut f64,
    weight_sum: *mut f64,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_confidence", || {
        let m = unsafe { handle::borrow(model) }?;
        let variance = unsafe { check::optional_out(variance, "variance") }?;
        let weight_sum = unsafe { check::optional_out(weight_sum, "weight_sum") }?;
        let p = check::point(m, x, y)?;
        let c = m.at(&p, brdf_atlas_core::BlendRule::Gp)?.confidence();
        if let Some(v) = variance {
            *v = c.variance;
        }
        if let Some(w) = weight_sum {
            *w = c.weight_sum;
        }
        Ok(())
    })
}

/// Whether latent point (x, y) is a material's marker (within
/// `BRDF_ATLAS_MARKER_RADIUS` of its point), and how the model gives that
/// material back there, as its fit measured it: the largest relative
/// albedo error of the three channels, and the ratio of the model's albedo
/// to the material's in that channel (7.2 for black fabric under the
/// paper's settings, about 1 for a material given back). A material whose
/// error exceeds `BRDF_ATLAS_GIVES_BACK` is not given back: say so to the
/// user. No pass over the store.
///
/// Ownership: `model` is borrowed; `material`, `albedo_error` and
/// `albedo_ratio` are caller-owned (each may be NULL). On success
/// `material` is the material's index, or SIZE_MAX where (x, y) is no
/// marker or the model file records no figures (written before they were
/// measured); the figures are then NaN.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite),
/// UNSUPPORTED (the model is not 2-D).
///
/// # Safety
/// `model` is NULL or a live handle; the out-pointers are NULL or valid for
/// writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_marker(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    material: *mut usize,
    albedo_error: *mut f64,
    albedo_ratio: *mut f64,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_marker", || {
        let m = unsafe { handle::borrow(model) }?;
        let material = unsafe { check::optional_out(material, "material") }?;
        let albedo_error = unsafe { check::optional_out(albedo_error, "albedo_error") }?;
        let albedo_ratio = unsafe { check::optional_out(albedo_ratio, "albedo_ratio") }?;
        let p = check::point(m, x, y)?;
        let found = m.file().marker_at(&p);
        let (i, e, r) = match found {
            Some((i, j)) => (i, j.albedo_error(), j.worst_ratio()),
            None => (usize::MAX, f64::NAN, f64::NAN),
        };
        if let Some(o) = material {
            *o = i;
        }
        if let Some(o) = albedo_error {
            *o = e;
        }
        if let Some(o) = albedo_ratio {
            *o = r;
        }
        Ok(())
    })
}

/// Reconstruct the whole table at latent point (x, y) under blend rule
/// `blend`, as `brdf_atlas_model_reconstruct` does (same layout, units and
/// buffer rules); `BRDF_ATLAS_BLEND_FLOOR` (the default) gives the same bits
/// as it.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite, an
/// unknown rule), UNSUPPORTED (the model is not 2-D), BUFFER_TOO_SMALL.
///
/// # Safety
/// `model` is NULL or a live handle; `buf` is NULL or valid for writing
/// `len` doubles; `written` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_reconstruct_with(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    blend: i32,
    buf: *mut f64,
    len: usize,
    written: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_reconstruct_with", || {
        let m = unsafe { handle::borrow(model) }?;
        let p = check::point(m, x, y)?;
        let out = unsafe { check::buffer(buf, len, m.dims().values(), "buf") }?;
        let written = unsafe { check::optional_out(written, "written") }?;
        let table = m.at(&p, rule(blend)?)?.table()?;
        out.copy_from_slice(table.raw());
        if let Some(w) = written {
            *w = out.len();
        }
        Ok(())
    })
}
