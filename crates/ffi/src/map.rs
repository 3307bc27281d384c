//! The albedo map of a latent window, cancellable, under the default blend
//! rule or a chosen one; the predictive variance of every pixel.

use std::sync::atomic::{AtomicI32, Ordering};

use brdf_atlas_core::{BlendRule, NoProgress, Progress, View};

use crate::check;
use crate::consts::{BRDF_ATLAS_MAX_MAP_SIDE, BRDF_ATLAS_MAX_SAMPLES};
use crate::model::{self as handle, BrdfAtlasModel, BrdfAtlasView};
use crate::plausibility::rule;
use crate::status::{BrdfAtlasStatus, Failure, Result, run};

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
/// `brdf_atlas_model_reconstruct` gives at the pixel's centre (the default
/// blend rule, the soft floor; `brdf_atlas_model_albedo_map_with` takes
/// another). Row 0 is the top of the window
/// (largest y); pixel (px, py) is at `buf[3 * (py * width + px) + c]`, c =
/// 0, 1, 2 for red, green, blue.
///
/// `view` NULL means the model's default window (`brdf_atlas_model_view`).
/// `samples` is the quadrature sample count per pixel; 0 means the library
/// default: the albedo field (exact albedos at nodes, a polynomial between
/// them, within 0.25% by its estimate; kept by the model, so later maps of
/// the same region are fast) where it costs less than 256 samples a pixel;
/// else the sampled field (the same polynomial through albedos integrated
/// with 1024 samples at its nodes, a few per cent off at worst, also kept)
/// where that costs less; else 256 samples a pixel. A field the model holds
/// whose region holds the window is used first, the fields saved beside
/// the model among them (`brdf_atlas_model_saved_fields`: `brdf-atlas fit`
/// saves the default view's and [-3, 3]^2's), so such maps take a fraction
/// of a second. (The GP's map of a model in the raw transform
/// is exact instead: the per-material albedos blended.) At most `BRDF_ATLAS_MAX_SAMPLES`.
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
        let rule = BlendRule::default();
        albedo_map(
            model,
            width,
            height,
            view,
            samples,
            rule,
            &NoProgress,
            buf,
            len,
        )
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
        let flag = unsafe { cancel_flag(cancel) }?;
        let rule = BlendRule::default();
        unsafe { albedo_map(model, width, height, view, samples, rule, &flag, buf, len) }
    })
}

/// `brdf_atlas_model_albedo_map` of the material blend rule `blend` forms
/// at each pixel: `BRDF_ATLAS_BLEND_FLOOR` (the default's map, the same
/// bits) or `BRDF_ATLAS_BLEND_GP` (the GP's own blend, clamped to >= 0;
/// exact for a model in the raw transform). `BRDF_ATLAS_BLEND_PLAUSIBLE`
/// has no map: its steps need a pass over the store per point. `cancel` is
/// NULL (the call cannot be cancelled) or a flag as in
/// `brdf_atlas_model_albedo_map_cancellable`.
///
/// Returns what `brdf_atlas_model_albedo_map_cancellable` returns, and
/// INVALID_ARGUMENT for an unknown rule or the plausible rule.
///
/// # Safety
/// As `brdf_atlas_model_albedo_map_cancellable`, but `cancel` may be NULL.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_albedo_map_with(
    model: *const BrdfAtlasModel,
    width: usize,
    height: usize,
    view: *const BrdfAtlasView,
    samples: usize,
    blend: i32,
    cancel: *const i32,
    buf: *mut f32,
    len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_albedo_map_with", || {
        let rule = map_rule(blend)?;
        let progress = unsafe { optional_cancel(cancel) }?;
        unsafe {
            albedo_map(
                model, width, height, view, samples, rule, &*progress, buf, len,
            )
        }
    })
}

/// How many entries (fields, and regions whose exact field was found over
/// budget) the fields saved beside the model hold (`MODEL.fields`, written
/// by `brdf-atlas fit` for the default view and [-3, 3]^2, by
/// `brdf-atlas map` and by `brdf_atlas_model_prepare_map_fields`), into
/// `*count`: 0 when there is no file. The model reads the file on its
/// first map and draws every map it can from its fields: a view inside a
/// saved field's region in a fraction of a second.
///
/// Ownership: `model` is borrowed; `count` is caller-owned, written on
/// success only.
///
/// Returns OK, NULL_ARGUMENT, BAD_FILE (the file cannot be used: damaged,
/// written for another fit, or unreadable; maps then build what they need,
/// and the next save replaces it).
///
/// # Safety
/// `model` is NULL or a live handle; `count` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_saved_fields(
    model: *const BrdfAtlasModel,
    count: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_saved_fields", || {
        let m = unsafe { handle::borrow(model) }?;
        let out = unsafe { check::out(count, "count") }?;
        *out = m.saved_fields()?;
        Ok(())
    })
}

/// Build the fields a `width` x `height` map of `view` (NULL: the default
/// window) draws by default (`brdf_atlas_model_albedo_map`: the exact
/// albedo field where it fits its budget, else the sampled field), of the
/// default material, and save every field the model holds beside the model
/// (`MODEL.fields`, atomically), so that later maps, in this program and
/// in any other, start from them. What `brdf-atlas fit` does for the
/// default view and for [-3, 3]^2 (`brdf_atlas_model_prepare_fit_fields`
/// builds that pair). `cancel` is NULL (not cancellable) or a flag as in
/// `brdf_atlas_model_albedo_map_cancellable`.
///
/// Returns OK (also when no field fits the map's budget: such maps
/// integrate every pixel, and nothing new is saved), NULL_ARGUMENT,
/// INVALID_ARGUMENT (as `brdf_atlas_model_albedo_map`), UNSUPPORTED (the
/// model is not 2-D), CANCELLED (nothing saved), IO (the file could not be
/// written: the model keeps the fields for this program's maps).
///
/// # Safety
/// `model` is NULL or a live handle; `view` is NULL or valid for reading;
/// `cancel` as in `brdf_atlas_model_albedo_map_with`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_prepare_map_fields(
    model: *const BrdfAtlasModel,
    width: usize,
    height: usize,
    view: *const BrdfAtlasView,
    cancel: *const i32,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_prepare_map_fields", || {
        let m = unsafe { handle::borrow(model) }?;
        check::planar(m)?;
        let view = unsafe { map_window(view, width, height) }?;
        let progress = unsafe { optional_cancel(cancel) }?;
        m.prepare_fields((width, height, view), BlendRule::default(), &*progress)?;
        Ok(())
    })
}

/// The albedo map and the predictive variance of every pixel from one
/// call: `buf` as `brdf_atlas_model_albedo_map_with` writes it (the same
/// bits), and, unless `variance` is NULL, one float a pixel as
/// `brdf_atlas_model_variance_map` lays them out: where the map is drawn
/// from a field, the field's polynomial of the variance (within 0.002 of
/// the exact variance), else the exact variance. What a viewer that fades
/// its map where the model knows little needs for a frame, without a
/// second pass over the pixels (a map from a field costs tens of
/// milliseconds, the exact variance as much again). `blend` and `cancel`
/// as in `brdf_atlas_model_albedo_map_with`.
///
/// Ownership: `model` and `view` are borrowed; `buf` (`len` floats, at
/// least width * height * 3) and `variance` (`variance_len` floats, at
/// least width * height) are caller-owned, written on success only.
///
/// Returns what `brdf_atlas_model_albedo_map_with` returns, and
/// BUFFER_TOO_SMALL for either buffer.
///
/// # Safety
/// As `brdf_atlas_model_albedo_map_with`; `variance` is NULL or valid for
/// writing `variance_len` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_map(
    model: *const BrdfAtlasModel,
    width: usize,
    height: usize,
    view: *const BrdfAtlasView,
    samples: usize,
    blend: i32,
    cancel: *const i32,
    buf: *mut f32,
    len: usize,
    variance: *mut f32,
    variance_len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_map", || {
        let rule = map_rule(blend)?;
        let progress = unsafe { optional_cancel(cancel) }?;
        unsafe {
            map_into(
                model,
                (width, height, view, samples, rule),
                (&*progress, false),
                (buf, len),
                (variance, variance_len),
            )
        }
    })
}

/// What a viewer draws while its window moves: `brdf_atlas_model_map`
/// from what the model already holds, never building anything. Inside
/// the prepared map's window or a field the model holds (built by an
/// earlier map in this program, or saved beside the model: `fit` saves
/// those of the default window and of [-3, 3]^2) the pixels are that
/// map's or field's; elsewhere every pixel is integrated with `samples`
/// samples (1 to `BRDF_ATLAS_MAX_SAMPLES`). Wherever
/// `brdf_atlas_model_map` with `samples` 0 draws from the same field, the
/// two agree pixel for pixel (it may instead build the exact field of a
/// small window's region), and no preview waits for a field to be built:
/// a 54 x 27 preview of 100 materials from a field took 1 ms on two
/// cores, once the model had read its fields file.
///
/// Ownership and returns as `brdf_atlas_model_map` (INVALID_ARGUMENT for
/// `samples` 0).
///
/// # Safety
/// As `brdf_atlas_model_map`, without a cancel flag.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_map_preview(
    model: *const BrdfAtlasModel,
    width: usize,
    height: usize,
    view: *const BrdfAtlasView,
    samples: usize,
    blend: i32,
    buf: *mut f32,
    len: usize,
    variance: *mut f32,
    variance_len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_map_preview", || {
        let rule = map_rule(blend)?;
        if samples == 0 {
            return Err(Failure::invalid(
                "a preview's samples must be 1 or more: they integrate the pixels no held \
                 field covers",
            ));
        }
        unsafe {
            map_into(
                model,
                (width, height, view, samples, rule),
                (&NoProgress, true),
                (buf, len),
                (variance, variance_len),
            )
        }
    })
}

/// A map's blend rule: the floor's or the GP's (the plausible rule has no map).
fn map_rule(blend: i32) -> Result<BlendRule, Failure> {
    let rule = rule(blend)?;
    if rule == BlendRule::Plausible {
        return Err(Failure::invalid(
            "BRDF_ATLAS_BLEND_PLAUSIBLE has no map: its steps need a pass over the store \
             per point; map BRDF_ATLAS_BLEND_FLOOR or BRDF_ATLAS_BLEND_GP",
        ));
    }
    Ok(rule)
}

/// What `brdf-atlas fit` does after the fit: build the fields 1024 x 1024
/// maps of the default window and of [-3, 3]^2 draw from (whose region
/// holds a viewer's windows twice as wide as high) and save them beside
/// the model (`MODEL.fields`, atomically), as
/// `brdf_atlas_model_prepare_map_fields` does for one window. A viewer
/// that opens a model without them (`brdf_atlas_model_saved_fields` gives
/// 0 or BAD_FILE) builds them off its GUI thread once: about 3 s for 100
/// materials on two cores. `cancel` is NULL (not cancellable) or a flag as
/// in `brdf_atlas_model_albedo_map_cancellable`.
///
/// Returns OK, NULL_ARGUMENT, UNSUPPORTED (the model is not 2-D),
/// CANCELLED (nothing saved), IO (the file could not be written: the model
/// keeps the fields for this program's maps).
///
/// # Safety
/// `model` is NULL or a live handle; `cancel` as in
/// `brdf_atlas_model_albedo_map_with`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_prepare_fit_fields(
    model: *const BrdfAtlasModel,
    cancel: *const i32,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_prepare_fit_fields", || {
        let m = unsafe { handle::borrow(model) }?;
        check::planar(m)?;
        let progress = unsafe { optional_cancel(cancel) }?;
        m.prepare_fit_fields(&*progress)?;
        Ok(())
    })
}

/// A caller's non-NULL cancel flag, checked for alignment.
///
/// # Safety
/// `cancel` is NULL or points to an aligned 32-bit integer that every
/// thread accesses only atomically while the call runs.
unsafe fn cancel_flag<'a>(cancel: *const i32) -> Result<CancelFlag<'a>, Failure> {
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
    Ok(CancelFlag(unsafe {
        AtomicI32::from_ptr(cancel.cast_mut())
    }))
}

/// A caller's cancel flag, or none if `cancel` is NULL, as a [`Progress`].
///
/// # Safety
/// As [`cancel_flag`].
unsafe fn optional_cancel<'a>(cancel: *const i32) -> Result<Box<dyn Progress + 'a>, Failure> {
    Ok(if cancel.is_null() {
        Box::new(NoProgress)
    } else {
        Box::new(unsafe { cancel_flag(cancel) }?)
    })
}

/// A caller's cancel flag as the core's [`Progress`].
struct CancelFlag<'a>(&'a AtomicI32);

impl Progress for CancelFlag<'_> {
    fn cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed) != 0
    }
}

/// The body of the albedo map entry points: no variance wanted.
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
    rule: BlendRule,
    progress: &dyn Progress,
    buf: *mut f32,
    len: usize,
) -> Result<(), Failure> {
    let request = (width, height, view, samples, rule);
    let no_variance = (std::ptr::null_mut(), 0);
    unsafe { map_into(model, request, (progress, false), (buf, len), no_variance) }
}

/// A map's size, window, samples and blend rule, as the C calls give them.
type MapArgs = (usize, usize, *const BrdfAtlasView, usize, BlendRule);

/// The map of `request` into the caller's `buf`, and its variance
/// into `variance` unless its pointer is NULL; both written on success
/// only. With
/// `preview`, `samples` (non-zero) are the per-pixel rule's where the
/// model holds nothing to draw from ([`MapRequest::preview`]).
///
/// [`MapRequest::preview`]: brdf_atlas_core::MapRequest::preview
///
/// # Safety
/// As `brdf_atlas_model_map`.
unsafe fn map_into(
    model: *const BrdfAtlasModel,
    (width, height, view, samples, rule): MapArgs,
    (progress, preview): (&dyn Progress, bool),
    (buf, len): (*mut f32, usize),
    (variance, variance_len): (*mut f32, usize),
) -> Result<(), Failure> {
    let m = unsafe { handle::borrow(model) }?;
    check::planar(m)?;
    let view = unsafe { map_window(view, width, height) }?;
    let values = check::product(&[width, height, 3], "map size")?;
    let out = unsafe { check::buffer(buf, len, values, "buf") }?;
    let var_out = if variance.is_null() {
        None
    } else {
        Some(unsafe { check::buffer(variance, variance_len, width * height, "variance") }?)
    };
    let samples = map_samples(samples)?;
    let request = brdf_atlas_core::MapRequest::new(width, height)
        .view(view)
        .rule(rule)
        .progress(progress);
    let map = m.map(match (preview, samples) {
        (true, Some(s)) => request.preview(s),
        _ => request.samples(samples),
    })?;
    for (o, c) in out.chunks_exact_mut(3).zip(&map.rgb) {
        o.copy_from_slice(c);
    }
    if let Some(v) = var_out {
        v.copy_from_slice(&map.variance);
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
