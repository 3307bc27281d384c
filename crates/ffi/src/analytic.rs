//! The analytic material of a latent point: the parameters
//! `brdf-atlas export` writes as glTF, MaterialX and Mitsuba 3.

use brdf_atlas_analytic::{SWATCH_LIGHTS, fit_as_exported};
use brdf_atlas_core::BlendRule;

use crate::check;
use crate::model::{self as handle, BrdfAtlasModel};
use crate::status::{BrdfAtlasStatus, Failure, run};

/// glTF 2.0 metallic-roughness parameters with `KHR_materials_specular` and
/// `KHR_materials_ior`, fitted to a material, and the fit's table errors.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrdfAtlasAnalytic {
    /// `baseColorFactor`, linear RGB in [0, 1].
    pub base_color: [f64; 3],
    /// `metallicFactor`, [0, 1].
    pub metallic: f64,
    /// `roughnessFactor` (GGX alpha = roughness^2), [0.02, 1].
    pub roughness: f64,
    /// `specularFactor`, [0, 1].
    pub specular: f64,
    /// `specularColorFactor`, linear RGB in [0, 1].
    pub specular_color: [f64; 3],
    /// `ior`, [1, 3].
    pub ior: f64,
    /// The fit's table error: RMS over a subsample of bins and RGB of
    /// ln((f_fit + 0.001) / (f + 0.001)), weighted by cos_i cos_o.
    pub table_error: f64,
    /// The same for one GGX lobe over a Lambertian base, fitted alike.
    pub single_lobe_table_error: f64,
    /// The same for the Lambertian of the material's albedo.
    pub lambertian_table_error: f64,
}

/// Fit the analytic material of latent point (x, y) (the default blend
/// rule's material, as `brdf_atlas_model_reconstruct`), as `brdf-atlas
/// export` does: reconstructs the whole table, then fits for one to a
/// few seconds on one thread. The result depends on the point only, never on
/// the thread count.
///
/// Ownership: `model` is borrowed; `out` (caller-owned) is written on
/// success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite; or
/// a material with too few measured bins to fit), UNSUPPORTED (the model is
/// not 2-D), BAD_FILE (the store changed on disk while the model was open).
///
/// # Safety
/// `model` is NULL or a live handle; `out` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_fit_analytic(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    out: *mut BrdfAtlasAnalytic,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_fit_analytic", || {
        let m = unsafe { handle::borrow(model) }?;
        let p = check::point(m, x, y)?;
        let out = unsafe { check::out(out, "out") }?;
        let table = m.at_with(&p, BlendRule::default())?.table()?;
        let what = format!("the material at ({x}, {y})");
        let fits = fit_as_exported(&table, &what, &SWATCH_LIGHTS)
            .map_err(|e| Failure::invalid(e.to_string()))?;
        let g = fits.principled.model;
        *out = BrdfAtlasAnalytic {
            base_color: g.base_color,
            metallic: g.metallic,
            roughness: g.roughness,
            specular: g.specular,
            specular_color: g.specular_color,
            ior: g.ior,
            table_error: fits.principled.error,
            single_lobe_table_error: fits.single_lobe.error,
            lambertian_table_error: fits.lambertian.error,
        };
        Ok(())
    })
}
