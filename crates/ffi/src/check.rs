//! Turning what a C caller passes into safe Rust values, or a [`Failure`].

use std::ffi::{CStr, c_char};

use brdf_atlas_core::Model;

use crate::status::{BrdfAtlasStatus, Failure, Result};

fn null(name: &str) -> Failure {
    Failure::new(BrdfAtlasStatus::NullArgument, format!("`{name}` is NULL"))
}

fn aligned<T>(p: *const T, name: &str) -> Result<()> {
    if p.is_aligned() {
        Ok(())
    } else {
        Err(Failure::invalid(format!(
            "`{name}` ({p:p}) is not aligned to {} bytes",
            std::mem::align_of::<T>()
        )))
    }
}

/// A single input passed by pointer.
///
/// # Safety
/// `p` is NULL or valid for reading one `T`.
pub(crate) unsafe fn borrowed<'a, T>(p: *const T, name: &str) -> Result<&'a T> {
    if p.is_null() {
        return Err(null(name));
    }
    aligned(p, name)?;
    // SAFETY: non-NULL and aligned; the caller promises it is readable.
    Ok(unsafe { &*p })
}

/// A single out-parameter.
///
/// # Safety
/// `p` is NULL or valid for writing one `T`.
pub(crate) unsafe fn out<'a, T>(p: *mut T, name: &str) -> Result<&'a mut T> {
    if p.is_null() {
        return Err(null(name));
    }
    aligned(p, name)?;
    // SAFETY: non-NULL and aligned; the caller promises it is writable.
    Ok(unsafe { &mut *p })
}

/// An optional out-parameter (NULL allowed).
///
/// # Safety
/// `p` is NULL or valid for writing one `T`.
pub(crate) unsafe fn optional_out<'a, T>(p: *mut T, name: &str) -> Result<Option<&'a mut T>> {
    if p.is_null() {
        Ok(None)
    } else {
        // SAFETY: as the caller promises.
        unsafe { out(p, name) }.map(Some)
    }
}

/// The first `needed` elements of a caller buffer of `len` elements; NULL
/// is an error, `len < needed` is [`BrdfAtlasStatus::BufferTooSmall`].
///
/// # Safety
/// `p` is NULL or valid for writing `len` elements.
pub(crate) unsafe fn buffer<'a, T>(
    p: *mut T,
    len: usize,
    needed: usize,
    name: &str,
) -> Result<&'a mut [T]> {
    if p.is_null() {
        return Err(null(name));
    }
    aligned(p, name)?;
    if len < needed {
        return Err(Failure::new(
            BrdfAtlasStatus::BufferTooSmall,
            format!("`{name}` holds {len} elements, the output needs {needed}"),
        ));
    }
    // SAFETY: non-NULL, aligned, and the caller promises `len >= needed`
    // writable elements (so `needed` elements fit in the address space).
    Ok(unsafe { std::slice::from_raw_parts_mut(p, needed) })
}

/// An input array of `n` elements; NULL is allowed only when `n == 0`.
///
/// # Safety
/// `p` is NULL or valid for reading `n` elements.
pub(crate) unsafe fn input<'a, T>(p: *const T, n: usize, name: &str) -> Result<&'a [T]> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(null(name));
    }
    aligned(p, name)?;
    // SAFETY: as the caller promises.
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// A NUL-terminated UTF-8 path.
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string.
pub(crate) unsafe fn path<'a>(p: *const c_char, name: &str) -> Result<&'a str> {
    if p.is_null() {
        return Err(null(name));
    }
    // SAFETY: the caller promises a NUL-terminated string.
    let s = unsafe { CStr::from_ptr(p) };
    let s = s.to_str().map_err(|e| {
        Failure::invalid(format!(
            "`{name}` is not valid UTF-8 ({e}): {}",
            s.to_string_lossy()
        ))
    })?;
    if s.is_empty() {
        return Err(Failure::invalid(format!("`{name}` is empty")));
    }
    Ok(s)
}

/// The model has a 2-D latent space, as a point `(x, y)` or a map needs.
pub(crate) fn planar(model: &Model) -> Result<()> {
    if model.q() == 2 {
        return Ok(());
    }
    Err(Failure::new(
        BrdfAtlasStatus::Unsupported,
        format!(
            "{}: the latent space is {}-D, this call needs a 2-D one",
            model.path().display(),
            model.q()
        ),
    ))
}

/// A latent point `(x, y)` of a 2-D model: finite coordinates.
pub(crate) fn point(model: &Model, x: f64, y: f64) -> Result<[f64; 2]> {
    planar(model)?;
    if !(x.is_finite() && y.is_finite()) {
        return Err(Failure::invalid(format!(
            "latent point ({x}, {y}) must have finite coordinates"
        )));
    }
    Ok([x, y])
}

/// `a * b * c` without overflow.
pub(crate) fn product(factors: &[usize], what: &str) -> Result<usize> {
    factors
        .iter()
        .try_fold(1usize, |acc, f| acc.checked_mul(*f))
        .ok_or_else(|| Failure::invalid(format!("{what} {factors:?} overflows size_t")))
}
