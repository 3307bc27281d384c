//! What a model answers at a latent point: the full table, point
//! evaluations, the blend weights; the albedo map; where a MERL file lands.

use std::ffi::c_char;
use std::sync::atomic::{AtomicI32, Ordering};

use brdf_atlas_core::View;
use brdf_atlas_core::{NoProgress, Progress};
use brdf_merl::{MerlFile, Vec3};

use crate::check;
use crate::consts::{BRDF_ATLAS_MAX_MAP_SIDE, BRDF_ATLAS_MAX_SAMPLES};
use crate::model::{self as handle, BrdfAtlasModel, BrdfAtlasView};
use crate::status::{BrdfAtlasStatus, Failure, Result, run};

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

/// Reconstruct the whole table at latent point (x, y) into `buf`, in the
/// MERL layout and units: the red, green and blue blocks of `bins` doubles
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
        let table = m.at(&p)?.table()?;
        out.copy_from_slice(table.raw());
        if let Some(w) = written {
            *w = out.len();
        }
        Ok(())
    })
}

/// Reconstruct the table at latent point (x, y) and write it as a MERL
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
        m.at(&p)?.table()?.write(path)?;
        Ok(())
    })
}

/// RGB reflectance of one direction pair, or NaN.
fn eval_one(blend: &brdf_atlas_core::Blend<'_>, wi: &[f64], wo: &[f64]) -> [f64; 3] {
    let v = |s: &[f64]| -> Vec3 { [s[0], s[1], s[2]] };
    blend.eval(v(wi), v(wo)).unwrap_or([f64::NAN; 3])
}

/// Evaluate the material at latent point (x, y) for one pair of directions:
/// RGB reflectance (1/sr, MERL's channel scales applied) of the nearest bin,
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
        let blend = m.at(&p)?;
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
        let blend = m.at(&p)?;
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

/// The N blend weights at latent point (x, y): every output of the model
/// there is the mean material plus this weighted sum of the N input
/// materials (in the model's transformed space). Weight i belongs to
/// material i.
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

/// The samples a map uses: 0 means none (the library's default: the exact
/// linear shortcut for a linear transform, the albedo field otherwise).
fn map_samples(samples: usize) -> Result<Option<usize>> {
    if samples > BRDF_ATLAS_MAX_SAMPLES {
        return Err(Failure::invalid(format!(
            "{samples} quadrature samples, at most {BRDF_ATLAS_MAX_SAMPLES} are accepted"
        )));
    }
    Ok(match samples {
        0 => None,
        s => Some(s),
    })
}

/// The albedo map of a `width` x `height` image of the latent window
/// `view`: for every pixel, the linear RGB albedo of the material
/// reconstructed at the pixel's centre. Row 0 is the top of the window
/// (largest y); pixel (px, py) is at `buf[3 * (py * width + px) + c]`, c =
/// 0, 1, 2 for red, green, blue.
///
/// `view` NULL means the model's default window (`brdf_atlas_model_view`).
/// `samples` is the quadrature sample count per pixel; 0 means the library
/// default: exact (the per-material albedos blended) for a model in the raw
/// transform; otherwise the albedo field (exact albedos at nodes, a
/// polynomial between them, within 0.25% by its estimate; kept by the model,
/// so later maps of the same region are fast) where it costs less than 256
/// samples a pixel, which are used otherwise. At most `BRDF_ATLAS_MAX_SAMPLES`.
///
/// Ownership: `model` and `view` are borrowed; `buf` is caller-owned, `len`
/// floats (at least width * height * 3), written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (zero size or more than
/// `BRDF_ATLAS_MAX_MAP_SIDE` a side, view not finite or empty, too many samples), UNSUPPORTED
/// (the model is not 2-D), BUFFER_TOO_SMALL.
///
/// # Safety
/// `model` is NULL or a live handle; `view` is NULL or valid for reading;
/// `buf` is NULL or valid for writing `len` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_albedo_map(
    model: *const BrdfAtlasModel,
    width: usize,
    height: usize,
    view: *const BrdfAtlasView,
    samples: usize,
    buf: *mut f32,
    len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_albedo_map", || unsafe {
        albedo_map(model, width, height, view, samples, &NoProgress, buf, len)
    })
}

/// `brdf_atlas_model_albedo_map` that its caller can cancel from another
/// thread: the call reads `*cancel` now and then (atomically, relaxed
/// order), and once it is non-zero stops within a map row or a step of the
/// albedo field's refinement, writes nothing and returns CANCELLED. `cancel`
/// is a `std::atomic<int32_t>` (C++) or `_Atomic int32_t` (C11) that stays
/// alive for the call; set it to 1 and never back to 0 during the call. A
/// viewer that moves on to another window cancels the stale map, so the
/// cores are free for the new one at once.
///
/// Returns what `brdf_atlas_model_albedo_map` returns, NULL_ARGUMENT when
/// `cancel` is NULL, and CANCELLED.
///
/// # Safety
/// As `brdf_atlas_model_albedo_map`; `cancel` is NULL or points to an
/// aligned 32-bit integer that every thread accesses only atomically while
/// the call runs.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_albedo_map_cancellable(
    model: *const BrdfAtlasModel,
    width: usize,
    height: usize,
    view: *const BrdfAtlasView,
    samples: usize,
    cancel: *const i32,
    buf: *mut f32,
    len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_albedo_map_cancellable", || {
        if cancel.is_null() {
            return Err(Failure::new(
                BrdfAtlasStatus::NullArgument,
                "cancel is NULL",
            ));
        }
        if !cancel.cast::<AtomicI32>().is_aligned() {
            return Err(Failure::invalid("cancel is not aligned to 4 bytes"));
        }
        // SAFETY: non-NULL and aligned (checked above); the caller keeps it
        // alive for the call and accesses it only atomically.
        let flag = CancelFlag(unsafe { AtomicI32::from_ptr(cancel.cast_mut()) });
        unsafe { albedo_map(model, width, height, view, samples, &flag, buf, len) }
    })
}

/// A caller's cancel flag as the core's [`Progress`].
struct CancelFlag<'a>(&'a AtomicI32);

impl Progress for CancelFlag<'_> {
    fn cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed) != 0
    }
}

/// The body of both albedo map entry points.
///
/// # Safety
/// As `brdf_atlas_model_albedo_map`.
#[allow(clippy::too_many_arguments)]
unsafe fn albedo_map(
    model: *const BrdfAtlasModel,
    width: usize,
    height: usize,
    view: *const BrdfAtlasView,
    samples: usize,
    progress: &dyn Progress,
    buf: *mut f32,
    len: usize,
) -> Result<(), Failure> {
    let m = unsafe { handle::borrow(model) }?;
    check::planar(m)?;
    let view = unsafe { map_window(view, width, height) }?;
    let values = check::product(&[width, height, 3], "map size")?;
    let out = unsafe { check::buffer(buf, len, values, "buf") }?;
    let samples = map_samples(samples)?;
    let map = m.albedo_map(width, height, view, samples, progress)?;
    for (o, c) in out.chunks_exact_mut(3).zip(&map.rgb) {
        o.copy_from_slice(c);
    }
    Ok(())
}

/// The window of a map request (`view` NULL: the default one), checked with
/// the map's size.
///
/// # Safety
/// `view` is NULL or valid for reading one `BrdfAtlasView`.
unsafe fn map_window(
    view: *const BrdfAtlasView,
    width: usize,
    height: usize,
) -> Result<View, Failure> {
    let view: View = match unsafe { check::input(view, 1, "view") } {
        Ok(v) => v[0].into(),
        Err(f) if f.status == BrdfAtlasStatus::NullArgument => View::default(),
        Err(f) => return Err(f),
    };
    view.check()?;
    let max = BRDF_ATLAS_MAX_MAP_SIDE;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(Failure::invalid(format!(
            "map size {width}x{height} must be between 1 and {max} a side"
        )));
    }
    Ok(view)
}

/// The GP's predictive variance (`1 - k(x)^T K^-1 k(x)`: 0 at an input
/// material, 1 where the data say nothing, above 0.5 the model knows
/// little) at every pixel of a `width` x `height` image of `view`, laid out
/// as `brdf_atlas_model_albedo_map` lays out its pixels, one float a pixel:
/// pixel (px, py) is at `buf[py * width + px]`. A map picture fades where it
/// is high. No pass over the store: much cheaper than the albedo map.
///
/// `view` NULL means the model's default window.
///
/// Ownership: `model` and `view` are borrowed; `buf` is caller-owned, `len`
/// floats (at least width * height), written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (zero size or more than
/// `BRDF_ATLAS_MAX_MAP_SIDE` a side, view not finite or empty), UNSUPPORTED
/// (the model is not 2-D), BUFFER_TOO_SMALL.
///
/// # Safety
/// `model` is NULL or a live handle; `view` is NULL or valid for reading;
/// `buf` is NULL or valid for writing `len` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_variance_map(
    model: *const BrdfAtlasModel,
    width: usize,
    height: usize,
    view: *const BrdfAtlasView,
    buf: *mut f32,
    len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_variance_map", || {
        let m = unsafe { handle::borrow(model) }?;
        check::planar(m)?;
        let view = unsafe { map_window(view, width, height) }?;
        let values = check::product(&[width, height], "map size")?;
        let out = unsafe { check::buffer(buf, len, values, "buf") }?;
        out.copy_from_slice(&m.variance_map(width, height, view)?);
        m.verify()?;
        Ok(())
    })
}

/// Find where the MERL file at `merl_path` lands in the model's latent
/// plane: the point whose reconstruction matches it best, searched over the
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
        let found = m.locate(&file)?;
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
