//! The analytic material of a latent point: the parameters
//! `brdf-atlas export` writes as glTF, MaterialX and Mitsuba 3, and those
//! files.

use std::ffi::c_char;
use std::path::Path;

use brdf_atlas_analytic::export::{self, Export};
use brdf_atlas_analytic::{AnalyticError, Fits, SWATCH_LIGHTS, fit_as_exported};
use brdf_atlas_core::{BlendRule, Model};

use crate::check;
use crate::model::{self as handle, BrdfAtlasModel};
use crate::status::{BrdfAtlasStatus, Result, run};

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
        *out = BrdfAtlasAnalytic::of(&fit(m, p)?);
        Ok(())
    })
}

impl BrdfAtlasAnalytic {
    fn of(fits: &Fits) -> BrdfAtlasAnalytic {
        let g = &fits.principled.model;
        BrdfAtlasAnalytic {
            base_color: g.base_color,
            metallic: g.metallic,
            roughness: g.roughness,
            specular: g.specular,
            specular_color: g.specular_color,
            ior: g.ior,
            table_error: fits.principled.error,
            single_lobe_table_error: fits.single_lobe.error,
            lambertian_table_error: fits.lambertian.error,
        }
    }
}

/// The fits of the default rule's material at `p`, as `brdf-atlas export` makes them.
fn fit(m: &Model, p: [f64; 2]) -> Result<Fits> {
    let table = m.at(&p, BlendRule::default())?.table()?;
    let what = format!("the material at ({}, {})", p[0], p[1]);
    Ok(fit_as_exported(&table, &what, &SWATCH_LIGHTS)?)
}

/// Fit the analytic material of latent point (x, y) as
/// `brdf_atlas_model_fit_analytic` does and write it into the directory
/// `dir` as `STEM.glb` (glTF 2.0 binary: a sphere with the material),
/// `STEM.mtlx` (MaterialX, Standard Surface), `STEM.mitsuba.json` (a
/// Mitsuba 3 `principled` dictionary) and `STEM.fit.json` (the parameters,
/// the table errors and how they were measured): what `brdf-atlas export
/// --at X,Y --name STEM` writes but its picture (`STEM.png`), with the
/// table errors only (the rendered errors are the command-line tool's
/// comparison). The four are put in place together, atomically: a failed
/// call leaves none of them; existing files of those names are replaced.
/// Takes as long as the fit, one to a few seconds: call it off a GUI
/// thread.
///
/// Ownership: `model`, `dir` and `stem` are borrowed for the call; `out`
/// (caller-owned) receives the parameters and table errors written to the
/// files, on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite;
/// `dir` or `stem` empty or not UTF-8; `stem` with a `/` or `\`, or a
/// leading `.`; a material with too few measured bins to fit), UNSUPPORTED
/// (the model is not 2-D), IO (`dir` is missing or not a directory; a file
/// could not be written), BAD_FILE (the store changed on disk while the
/// model was open).
///
/// # Safety
/// `model` is NULL or a live handle; `dir` and `stem` are NULL or
/// NUL-terminated strings; `out` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_export(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    dir: *const c_char,
    stem: *const c_char,
    out: *mut BrdfAtlasAnalytic,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_export", || {
        let m = unsafe { handle::borrow(model) }?;
        let p = check::point(m, x, y)?;
        let dir = Path::new(unsafe { check::path(dir, "dir") }?);
        let stem = unsafe { check::path(stem, "stem") }?;
        let out = unsafe { check::out(out, "out") }?;
        // Everything the caller can get wrong is refused before the fit.
        if !export::is_file_stem(stem) {
            return Err(AnalyticError::Stem { stem: stem.into() }.into());
        }
        if !dir.is_dir() {
            return Err(AnalyticError::NotADirectory { path: dir.into() }.into());
        }
        let fits = fit(m, p)?;
        let source = format!(
            "{} at ({:.4}, {:.4}) ({} blend)",
            m.path().display(),
            p[0],
            p[1],
            BlendRule::default().name()
        );
        let e = Export {
            name: stem,
            source: &source,
            fits: &fits,
            rendered: None,
        };
        let files = export::stage(dir, &e)?;
        m.verify()?;
        brdf_atomic::commit_all(files)
            .map_err(|(path, source)| AnalyticError::Write { path, source })?;
        *out = BrdfAtlasAnalytic::of(&fits);
        Ok(())
    })
}
