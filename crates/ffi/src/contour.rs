//! Luminance contour lines of an albedo map, for a caller that draws the map
//! itself (the BRDF Explorer plugin): the same levels and marching squares as
//! the PNG maps of `brdf-atlas map`.

use brdf_atlas_core::{AlbedoMap, AlbedoMethod, BlendRule, View, contour_levels, contours};

use crate::check;
use crate::status::{BrdfAtlasStatus, Failure, Result, run};

/// One segment of a contour line of an albedo map, in the map's pixel
/// coordinates: pixel (px, py) covers [px, px + 1) x [py, py + 1), row 0 at
/// the top, so a pixel's centre is at (px + 0.5, py + 0.5).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrdfAtlasSegment {
    /// First end, x.
    pub x0: f32,
    /// First end, y.
    pub y0: f32,
    /// Second end, x.
    pub x1: f32,
    /// Second end, y.
    pub y1: f32,
    /// Index of the segment's level in the `levels` array it was traced for.
    pub level: usize,
}

/// The albedo map a caller passes, as the core's map type. Only the pixels
/// matter to contours; the window and method are placeholders.
///
/// # Safety
/// `rgb` is NULL or valid for reading `width * height * 3` floats.
unsafe fn map_from(rgb: *const f32, width: usize, height: usize) -> Result<AlbedoMap> {
    let max = crate::consts::BRDF_ATLAS_MAX_MAP_SIDE;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(Failure::invalid(format!(
            "map size {width}x{height} must be between 1 and {max} a side"
        )));
    }
    let values = check::product(&[width, height, 3], "map size")?;
    let rgb = unsafe { check::input(rgb, values, "rgb") }?;
    if let Some(bad) = rgb.iter().position(|v| !v.is_finite()) {
        return Err(Failure::invalid(format!(
            "`rgb` value {bad} is {}, a map holds finite albedos",
            rgb[bad]
        )));
    }
    Ok(AlbedoMap {
        width,
        height,
        view: View::default(),
        rgb: rgb.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        // Contours read the albedo only.
        variance: vec![0.0; width * height],
        method: AlbedoMethod::Linear,
        blend: BlendRule::default(),
    })
}

/// `count` luminance levels evenly spaced strictly inside the luminance
/// range (Rec. 709 weights) of a `width` x `height` albedo map laid out as
/// `brdf_atlas_model_albedo_map` writes it: level k (1-based) is
/// lo + (hi - lo) k / (count + 1). A map of one flat luminance has no
/// levels: `*written` is then 0.
///
/// Ownership: `rgb` is borrowed (`width * height * 3` floats); `levels` is
/// caller-owned, `len` floats (at least `count`), and `*written` (the
/// number of levels, `count` or 0) are written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (zero or too large size, a
/// non-finite value in `rgb`), BUFFER_TOO_SMALL (len < count).
///
/// # Safety
/// `rgb` is NULL or valid for reading `width * height * 3` floats; `levels`
/// is NULL or valid for writing `len` floats; `written` is NULL or valid
/// for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_contour_levels(
    rgb: *const f32,
    width: usize,
    height: usize,
    count: usize,
    levels: *mut f32,
    len: usize,
    written: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_contour_levels", || {
        let map = unsafe { map_from(rgb, width, height) }?;
        let written = unsafe { check::out(written, "written") }?;
        let found = contour_levels(&map, count);
        if count > 0 {
            let out = unsafe { check::buffer(levels, len, count, "levels") }?;
            out[..found.len()].copy_from_slice(&found);
        }
        *written = found.len();
        Ok(())
    })
}

/// The luminance contour lines of a `width` x `height` albedo map (laid out
/// as `brdf_atlas_model_albedo_map` writes it) at the `n_levels` luminance
/// values `levels`, by marching squares between pixel centres (saddles
/// decided by the cell's mean): the segments of every level, level by
/// level, in the map's pixel coordinates (see `BrdfAtlasSegment`).
///
/// Size query: with `buf` NULL and `len` 0, only `*count` (the number of
/// segments) is written. Otherwise `buf` must hold `*count` segments.
///
/// Ownership: `rgb` and `levels` are borrowed; `buf` is caller-owned, `len`
/// segments, and `*count` are written on success only.
///
/// Returns OK, NULL_ARGUMENT, INVALID_ARGUMENT (zero or too large size, a
/// non-finite value in `rgb` or `levels`), BUFFER_TOO_SMALL (len < the
/// segment count).
///
/// # Safety
/// `rgb` is NULL or valid for reading `width * height * 3` floats; `levels`
/// is NULL or valid for reading `n_levels` floats; `buf` is NULL or valid
/// for writing `len` segments; `count` is NULL or valid for writing.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdf_atlas_contours(
    rgb: *const f32,
    width: usize,
    height: usize,
    levels: *const f32,
    n_levels: usize,
    buf: *mut BrdfAtlasSegment,
    len: usize,
    count: *mut usize,
) -> BrdfAtlasStatus {
    run("brdf_atlas_contours", || {
        let map = unsafe { map_from(rgb, width, height) }?;
        let levels = unsafe { check::input(levels, n_levels, "levels") }?;
        if let Some(bad) = levels.iter().position(|v| !v.is_finite()) {
            return Err(Failure::invalid(format!(
                "level {bad} is {}, levels must be finite",
                levels[bad]
            )));
        }
        let count = unsafe { check::out(count, "count") }?;
        let segments = contours(&map, levels);
        if buf.is_null() && len == 0 {
            *count = segments.len();
            return Ok(());
        }
        let out = unsafe { check::buffer(buf, len, segments.len(), "buf") }?;
        for (o, (a, b, level)) in out.iter_mut().zip(segments) {
            *o = BrdfAtlasSegment {
                x0: a[0],
                y0: a[1],
                x1: b[0],
                y1: b[1],
                level,
            };
        }
        *count = out.len();
        Ok(())
    })
}
