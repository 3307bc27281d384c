//! What a model answers at a latent point: the full table, point
//! evaluations, the blend weights; where a MERL file lands.

use std::ffi::c_char;

use brdf_atlas_core::BlendRule;
use brdf_merl::{MerlFile, Vec3};

use crate::check;
use crate::model::{self as handle, BrdfAtlasModel};
use crate::status::{BrdfAtlasStatus, Failure, run};

/// Where a MERL file lands in a model's latent plane.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrdfAtlasLocation {
    /// Latent x of the best-matching point.
    pub x: f64,
    /// Latent y.
    pub y: f64,
    /// Root-mean-square error per value of the reconstruction there, in the
    /// model's transformed space.
    pub rmse: f64,
    /// RMS of the material itself around the model's mean material, in the
    /// same units: rmse / spread below 1 is better than the mean.
    pub spread: f64,
    /// Index of the input material nearest to (x, y) in the latent plane.
    pub nearest: usize,
}

/// Reconstruct the whole table at latent point (x, y) into `buf`, under the
/// library's default blend rule, the soft floor (`BRDF_ATLAS_BLEND_FLOOR`:
/// the material the albedo map shows; `brdf_atlas_model_reconstruct_with`
/// takes another rule), in the MERL layout and units: the red, green and blue blocks of `bins` doubles
/// each, each indexed `[theta_h][theta_d][phi_d]`, raw MERL values (a MERL
/// `.binary` file's data after its 12-byte header), -1 where no input
/// material was measured. `brdf_atlas_model_table_len` gives the length.
///
/// Points far outside the box [-1, 1]^2 are allowed: the blend tends to the
/// mean material there.
///
/// Ownership: `model` is borrowed; `buf` is caller-owned, `len` doubles,
/// written on success only; `*written` (optional, may be NULL) receives the
/// number of doubles written.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite),
/// UNSUPPORTED (the model is not 2-D), BUFFER_TOO_SMALL (len < 3 * bins),
/// BAD_FILE (the store changed on disk while the model was open; see
/// `brdf_atlas_model_open`).
///
/// # Safety
/// `model` is NULL or a live handle; `buf` is NULL or valid for writing
/// `len` doubles; `written` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_reconstruct(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    buf: *mut f64,
    len: usize,
    written: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_reconstruct", || {
        let m = unsafe { handle::borrow(model) }?;
        let p = check::point(m, x, y)?;
        let out = unsafe { check::buffer(buf, len, m.dims().values(), "buf") }?;
        let written = unsafe { check::optional_out(written, "written") }?;
        let table = m.at(&p, BlendRule::default())?.table()?;
        out.copy_from_slice(table.raw());
        if let Some(w) = written {
            *w = out.len();
        }
        Ok(())
    })
}

/// Reconstruct the table at latent point (x, y) under the default blend
/// rule (as `brdf_atlas_model_reconstruct`) and write it as a MERL
/// `.binary` file at `path`, atomically (a temporary file beside it, then a
/// rename: a failed call leaves no partial file). An existing file is
/// replaced.
///
/// Ownership: `model` and `path` are borrowed for the call.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite,
/// path empty or not UTF-8), UNSUPPORTED (the model is not 2-D), IO.
///
/// # Safety
/// `model` is NULL or a live handle; `path` is NULL or a NUL-terminated
/// string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_reconstruct_to_file(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    path: *const c_char,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_reconstruct_to_file", || {
        let m = unsafe { handle::borrow(model) }?;
        let path = unsafe { check::path(path, "path") }?;
        let p = check::point(m, x, y)?;
        m.at(&p, BlendRule::default())?.table()?.write(path)?;
        Ok(())
    })
}

/// RGB reflectance of one direction pair, or NaN.
fn eval_one(blend: &brdf_atlas_core::Blend<'_>, wi: &[f64], wo: &[f64]) -> [f64; 3] {
    let v = |s: &[f64]| -> Vec3 { [s[0], s[1], s[2]] };
    blend.eval(v(wi), v(wo)).unwrap_or([f64::NAN; 3])
}

/// Evaluate the material at latent point (x, y) (the default blend rule's,
/// as `brdf_atlas_model_reconstruct`) for one pair of directions: RGB
/// reflectance (1/sr, MERL's channel scales applied) of the nearest bin,
/// as MERL's own lookup does.
///
/// `wi` and `wo` are 3 doubles each, in the surface frame (z is the
/// normal), need not be normalised. A pair with no value, because a
/// direction is at or below the horizon (z <= 0), zero or not finite, or
/// because no input material measured its bin, gives NaN in all three
/// outputs with status OK.
///
/// Ownership: all pointers are borrowed; `rgb` (3 doubles, caller-owned) is
/// written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite),
/// UNSUPPORTED (the model is not 2-D).
///
/// # Safety
/// `model` is NULL or a live handle; `wi` and `wo` are NULL or valid for
/// reading 3 doubles; `rgb` is NULL or valid for writing 3 doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_eval(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    wi: *const f64,
    wo: *const f64,
    rgb: *mut f64,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_eval", || {
        let m = unsafe { handle::borrow(model) }?;
        let wi = unsafe { check::input(wi, 3, "wi") }?;
        let wo = unsafe { check::input(wo, 3, "wo") }?;
        let out = unsafe { check::buffer(rgb, 3, 3, "rgb") }?;
        let p = check::point(m, x, y)?;
        let blend = m.at(&p, BlendRule::default())?;
        let rgb = eval_one(&blend, wi, wo);
        m.verify()?;
        out.copy_from_slice(&rgb);
        Ok(())
    })
}

/// Evaluate the material at latent point (x, y) for `n` direction pairs:
/// pair k is `wi[3k..3k+3]`, `wo[3k..3k+3]`, its RGB goes to
/// `rgb[3k..3k+3]`. Each pair as in `brdf_atlas_model_eval`: NaN in all
/// three outputs where a pair has no value (below the horizon, degenerate,
/// unmeasured). The weights are computed once for the whole batch.
///
/// Ownership: all pointers are borrowed; `rgb` is caller-owned, `len`
/// doubles (at least 3 * n), written on success only. With n = 0 the
/// pointers may be NULL.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite,
/// 3 * n overflows), UNSUPPORTED (the model is not 2-D), BUFFER_TOO_SMALL
/// (len < 3 * n).
///
/// # Safety
/// `model` is NULL or a live handle; `wi` and `wo` are NULL or valid for
/// reading 3 * n doubles; `rgb` is NULL or valid for writing `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_eval_batch(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    wi: *const f64,
    wo: *const f64,
    n: usize,
    rgb: *mut f64,
    len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_eval_batch", || {
        let m = unsafe { handle::borrow(model) }?;
        let values = check::product(&[n, 3], "3 * n")?;
        let wi = unsafe { check::input(wi, values, "wi") }?;
        let wo = unsafe { check::input(wo, values, "wo") }?;
        if values == 0 {
            check::point(m, x, y)?;
            return Ok(());
        }
        let out = unsafe { check::buffer(rgb, len, values, "rgb") }?;
        let p = check::point(m, x, y)?;
        let blend = m.at(&p, BlendRule::default())?;
        // Computed in full before the caller's buffer is touched.
        let mut result = Vec::new();
        result.try_reserve_exact(values).map_err(|_| {
            Failure::new(
                BrdfAtlasStatus::Other,
                format!("out of memory for {values} values"),
            )
        })?;
        for (a, b) in wi.chunks_exact(3).zip(wo.chunks_exact(3)) {
            result.extend_from_slice(&eval_one(&blend, a, b));
        }
        m.verify()?;
        out.copy_from_slice(&result);
        Ok(())
    })
}

/// The N blend weights at latent point (x, y), the GP's `K^-1 k(x)`: the
/// GP's blend there is the mean material plus this weighted sum of the N
/// input materials (in the model's transformed space); the default rule,
/// the soft floor, then lifts each value of it onto a floor at 0.3 times a
/// kernel-weighted average's. Weight i belongs to material i.
///
/// Ownership: `model` is borrowed; `buf` is caller-owned, `len` doubles (at
/// least N), written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (x or y NaN or infinite),
/// UNSUPPORTED (the model is not 2-D), BUFFER_TOO_SMALL (len < N).
///
/// # Safety
/// `model` is NULL or a live handle; `buf` is NULL or valid for writing
/// `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_weights(
    model: *const BrdfAtlasModel,
    x: f64,
    y: f64,
    buf: *mut f64,
    len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_weights", || {
        let m = unsafe { handle::borrow(model) }?;
        let out = unsafe { check::buffer(buf, len, m.names().len(), "buf") }?;
        let p = check::point(m, x, y)?;
        let w = m.weights_at(&p)?;
        out.copy_from_slice(&w);
        Ok(())
    })
}

/// Find where the MERL file at `merl_path` lands in the model's latent
/// plane: the point whose reconstruction (the GP's blend, what the latent
/// space was fitted on) matches it best, searched over the
/// whole plane (it may lie outside the box [-1, 1]^2 the inputs were fitted
/// in, and outside the default view). The file must have the model's dims.
///
/// Ownership: `model` and `merl_path` are borrowed; `*location` is written
/// on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (path empty or not UTF-8,
/// dims differ from the model's), UNSUPPORTED (the model is not 2-D), IO,
/// BAD_MERL (not a valid MERL file).
///
/// # Safety
/// `model` is NULL or a live handle; `merl_path` is NULL or a
/// NUL-terminated string; `location` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_locate(
    model: *const BrdfAtlasModel,
    merl_path: *const c_char,
    location: *mut BrdfAtlasLocation,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_locate", || {
        let m = unsafe { handle::borrow(model) }?;
        let path = unsafe { check::path(merl_path, "merl_path") }?;
        let location = unsafe { check::out(location, "location") }?;
        check::planar(m)?;
        let file = MerlFile::open(path)?;
        let found = brdf_atlas_core::Located::find(m, &file)?;
        *location = BrdfAtlasLocation {
            x: found.point[0],
            y: found.point[1],
            rmse: found.rmse,
            spread: found.spread,
            nearest: found.nearest.first().map_or(0, |n| n.0),
        };
        Ok(())
    })
}
