//! The model handle: open, free, and the facts of a model.

use std::ffi::{c_char, c_int};

use brdf_atlas_core::View;
use brdf_atlas_core::{Atlas, Model};

use crate::check;
use crate::status::{BrdfAtlasStatus, Failure, Result, run};

/// An opened model: the fitted latent space and its memory-mapped store.
///
/// Opaque. Created by `brdf_atlas_model_open`, released by
/// `brdf_atlas_model_free`. Immutable once open: one handle may serve
/// concurrent calls from any number of threads.
pub struct BrdfAtlasModel {
    /// The model, with what its maps keep between calls.
    pub(crate) atlas: Atlas,
}

// One handle serves many threads: the model must be shareable.
const _: () = {
    const fn shareable<T: Send + Sync>() {}
    shareable::<BrdfAtlasModel>()
};

/// The atlas behind a handle (its model through it).
///
/// # Safety
/// `p` is NULL or a handle from `brdf_atlas_model_open` not yet freed.
pub(crate) unsafe fn borrow<'a>(p: *const BrdfAtlasModel) -> Result<&'a Atlas> {
    // SAFETY: the caller promises a live handle.
    let atlas = unsafe { check::borrowed(p, "model") }.map(|h| &h.atlas)?;
    // A handle whose store was seen to change refuses every call.
    atlas.store().verify_cheap()?;
    Ok(atlas)
}

/// A window of the latent plane: x in [x0, x1], y in [y0, y1], y up.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrdfAtlasView {
    /// Left edge.
    pub x0: f64,
    /// Right edge.
    pub x1: f64,
    /// Bottom edge.
    pub y0: f64,
    /// Top edge.
    pub y1: f64,
}

impl From<View> for BrdfAtlasView {
    fn from(v: View) -> Self {
        BrdfAtlasView {
            x0: v.x0,
            x1: v.x1,
            y0: v.y0,
            y1: v.y1,
        }
    }
}

impl From<BrdfAtlasView> for View {
    fn from(v: BrdfAtlasView) -> Self {
        View {
            x0: v.x0,
            x1: v.x1,
            y0: v.y0,
            y1: v.y1,
        }
    }
}

/// The dims of a MERL table: bins along theta_h, theta_d and phi_d
/// (90, 90, 180 for MERL itself). A table holds 3 * bins doubles, bins =
/// theta_h * theta_d * phi_d.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BrdfAtlasDims {
    /// Bins along theta_h (square-root spaced).
    pub theta_h: usize,
    /// Bins along theta_d.
    pub theta_d: usize,
    /// Bins along phi_d, over [0, pi).
    pub phi_d: usize,
}

/// Choose, before the first `brdf_atlas_model_open`, whether the library
/// installs its process-wide SIGBUS handler (see `brdf_atlas_model_open`).
///
/// `enabled` nonzero: the first open installs it (the default). Zero: no
/// handler, SIGBUS's disposition stays the host's; a store truncated under
/// an open handle then raises SIGBUS in the call that reads past its new
/// end (the host's handler gets it, or the process dies), instead of
/// turning into BAD_FILE. The choice is made once for the process, by the
/// first of this call, the first open and the environment variable
/// `BRDF_ATLAS_NO_SIGBUS_HANDLER=1` (read at the first open, when no call
/// came first).
///
/// Ownership: nothing is passed or kept.
///
/// Returns OK when the process's choice is now `enabled`, INVALID_ARGUMENT
/// when it was already made the other way (a model was opened first, or an
/// earlier call chose otherwise): an installed handler stays installed.
#[unsafe(no_mangle)]
pub extern "C" fn brdf_atlas_set_sigbus_guard(enabled: c_int) -> BrdfAtlasStatus {
    run("brdf_atlas_set_sigbus_guard", || {
        let enabled = enabled != 0;
        if brdf_atlas_core::set_sigbus_guard(enabled) {
            return Ok(());
        }
        Err(Failure::invalid(if enabled {
            "the SIGBUS handler was already declined (an earlier call, or \
             BRDF_ATLAS_NO_SIGBUS_HANDLER=1 at the first open); it is installed only before \
             the first model is opened"
        } else {
            "the SIGBUS handler is already installed (a model was opened first): call \
             brdf_atlas_set_sigbus_guard(0) before the first brdf_atlas_model_open"
        }))
    })
}

/// Open the model file at `path` (its store, `path` + ".store", beside it)
/// and check it: format, version, the store's size and checksum.
///
/// Ownership: `path` is borrowed for the call. On success `*out` receives a
/// new handle that the caller owns and must release with
/// `brdf_atlas_model_free`; on failure `*out` is left untouched.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (path empty or not UTF-8),
/// IO (missing or unreadable file or store), BAD_FILE (not a model, another
/// version, store changed), NOT_POSITIVE_DEFINITE.
///
/// The store stays memory-mapped while the handle lives. If another
/// program truncates it or rewrites it in place meanwhile (`cp` or a shell
/// redirection over it), the process does not die: the call that reads the
/// store returns BAD_FILE with a message naming the store and saying it
/// changed on disk while open, and so does every later call on this
/// handle until it is freed and the model reopened. Replacing the store by
/// a rename (as `brdf-atlas fit` does) changes nothing for an open handle:
/// it keeps reading the file it opened.
///
/// Signals: for this, the first open installs a process-wide SIGBUS handler
/// (`sigaction` with `SA_SIGINFO | SA_ONSTACK | SA_NODEFER`), once, never
/// removed. It chains: a SIGBUS outside the library's own maps goes to the
/// action SIGBUS had before the first open (its handler, or the default
/// action); a handler installed after the first open must pass SIGBUS on
/// to the one it replaced, or truncations kill the process. To leave
/// SIGBUS alone (a JVM, a sanitizer, a crash reporter), opt out before the
/// first open: call `brdf_atlas_set_sigbus_guard(0)`, or set the
/// environment variable `BRDF_ATLAS_NO_SIGBUS_HANDLER=1`. Then a store
/// truncated under an open handle raises SIGBUS in the call that reads
/// past its new end, as any memory map does (the host's handler gets it, or
/// the process dies); a rewrite in place is still reported as above.
///
/// # Safety
/// `path` is NULL or a NUL-terminated string; `out` is NULL or valid for
/// writing one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_open(
    path: *const c_char,
    out: *mut *mut BrdfAtlasModel,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_open", || {
        let path = unsafe { check::path(path, "path") }?;
        let out = unsafe { check::out(out, "out") }?;
        let atlas = Atlas::new(Model::open(path)?);
        *out = Box::into_raw(Box::new(BrdfAtlasModel { atlas }));
        Ok(())
    })
}

/// Release a handle and everything it holds (the store's mapping).
///
/// Ownership: takes back a handle from `brdf_atlas_model_open`; NULL is
/// allowed and does nothing. The handle must not be used again, and no other
/// thread may be using it.
///
/// # Safety
/// `model` is NULL or a handle from `brdf_atlas_model_open` not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_free(model: *mut BrdfAtlasModel) {
    let _ = run("brdf_atlas_model_free", || {
        if !model.is_null() {
            // SAFETY: the caller gives back ownership of a live handle.
            drop(unsafe { Box::from_raw(model) });
        }
        Ok(())
    });
}

/// The latent dimension q of the model (2 for a map).
///
/// Ownership: `model` is borrowed; `*q` is written on success.
///
/// # Safety
/// `model` is NULL or a live handle; `q` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_latent_dim(
    model: *const BrdfAtlasModel,
    q: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_latent_dim", || {
        let m = unsafe { borrow(model) }?;
        let q = unsafe { check::out(q, "q") }?;
        *q = m.q();
        Ok(())
    })
}

/// The number N of materials the model was fitted to (the length of a
/// weights vector).
///
/// Ownership: `model` is borrowed; `*count` is written on success.
///
/// # Safety
/// `model` is NULL or a live handle; `count` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_material_count(
    model: *const BrdfAtlasModel,
    count: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_material_count", || {
        let m = unsafe { borrow(model) }?;
        let count = unsafe { check::out(count, "count") }?;
        *count = m.names().len();
        Ok(())
    })
}

/// The name of material `index` (0 <= index < N), UTF-8, copied into
/// `buf` with a terminating NUL.
///
/// Size query: with `buf` NULL and `len` 0, only `*name_len` is written.
/// Otherwise `buf` must hold `*name_len + 1` bytes.
///
/// Ownership: `model` is borrowed; `buf` (caller-owned, `len` bytes) and
/// `*name_len` (the name's length in bytes, without the NUL) are written on
/// success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (index out of range),
/// BUFFER_TOO_SMALL (len < name length + 1).
///
/// # Safety
/// `model` is NULL or a live handle; `buf` is NULL or valid for writing
/// `len` bytes; `name_len` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_material_name(
    model: *const BrdfAtlasModel,
    index: usize,
    buf: *mut c_char,
    len: usize,
    name_len: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_material_name", || {
        let m = unsafe { borrow(model) }?;
        let name_len = unsafe { check::out(name_len, "name_len") }?;
        let name = m.names().get(index).ok_or_else(|| {
            Failure::invalid(format!(
                "material {index} does not exist, the model has {}",
                m.names().len()
            ))
        })?;
        if !(buf.is_null() && len == 0) {
            let bytes = name.as_bytes();
            let out = unsafe { check::buffer(buf, len, bytes.len() + 1, "buf") }?;
            for (o, b) in out.iter_mut().zip(bytes.iter().chain([&0u8])) {
                *o = *b as c_char;
            }
        }
        *name_len = name.len();
        Ok(())
    })
}

/// The latent coordinates of material `index` (0 <= index < N): q doubles
/// into `buf`.
///
/// Ownership: `model` is borrowed; `buf` is caller-owned, `len` doubles,
/// written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (index out of range),
/// BUFFER_TOO_SMALL (len < q).
///
/// # Safety
/// `model` is NULL or a live handle; `buf` is NULL or valid for writing
/// `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_latent_point(
    model: *const BrdfAtlasModel,
    index: usize,
    buf: *mut f64,
    len: usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_latent_point", || {
        let m = unsafe { borrow(model) }?;
        let n = m.names().len();
        if index >= n {
            return Err(Failure::invalid(format!(
                "material {index} does not exist, the model has {n}"
            )));
        }
        let out = unsafe { check::buffer(buf, len, m.q(), "buf") }?;
        for (c, o) in out.iter_mut().enumerate() {
            *o = m.latent()[(index, c)];
        }
        Ok(())
    })
}

/// The window of the latent plane a map of this model shows by default: the
/// box [-1, 1]^2 the latent points live in, plus a 10% margin.
///
/// Ownership: `model` is borrowed; `*view` is written on success.
///
/// # Safety
/// `model` is NULL or a live handle; `view` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_view(
    model: *const BrdfAtlasModel,
    view: *mut BrdfAtlasView,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_view", || {
        let _ = unsafe { borrow(model) }?;
        let view = unsafe { check::out(view, "view") }?;
        *view = View::default().into();
        Ok(())
    })
}

/// The dims of the model's tables (those of the materials it was fitted to).
///
/// Ownership: `model` is borrowed; `*dims` is written on success.
///
/// # Safety
/// `model` is NULL or a live handle; `dims` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_dims(
    model: *const BrdfAtlasModel,
    dims: *mut BrdfAtlasDims,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_dims", || {
        let m = unsafe { borrow(model) }?;
        let dims = unsafe { check::out(dims, "dims") }?;
        let d = m.dims();
        *dims = BrdfAtlasDims {
            theta_h: d.theta_h,
            theta_d: d.theta_d,
            phi_d: d.phi_d,
        };
        Ok(())
    })
}

/// The length, in doubles, of a reconstructed table: 3 * bins.
///
/// Ownership: `model` is borrowed; `*len` is written on success.
///
/// # Safety
/// `model` is NULL or a live handle; `len` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_model_table_len(
    model: *const BrdfAtlasModel,
    len: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_model_table_len", || {
        let m = unsafe { borrow(model) }?;
        let len = unsafe { check::out(len, "len") }?;
        *len = m.dims().values();
        Ok(())
    })
}
