//! The contour entry points against maps whose contours are known in closed
//! form: a ramp (straight lines) and a cone (circles).

use std::ptr::{null, null_mut};

use brdf_atlas_c::*;

/// A grey map (r = g = b, so luminance = the value: the Rec. 709 weights
/// sum to 1) with value `f(px, py)` at pixel (px, py).
fn grey(width: usize, height: usize, f: impl Fn(f32, f32) -> f32) -> Vec<f32> {
    let mut rgb = Vec::with_capacity(width * height * 3);
    for py in 0..height {
        for px in 0..width {
            let v = f(px as f32, py as f32);
            rgb.extend_from_slice(&[v, v, v]);
        }
    }
    rgb
}

/// The segments at `levels`, through the size query then the real call.
fn segments(rgb: &[f32], width: usize, height: usize, levels: &[f32]) -> Vec<BrdfAtlasSegment> {
    let mut n = usize::MAX;
    let s = unsafe {
        brdf_atlas_contours(
            rgb.as_ptr(),
            width,
            height,
            levels.as_ptr(),
            levels.len(),
            null_mut(),
            0,
            &mut n,
        )
    };
    assert_eq!(s, BrdfAtlasStatus::Ok);
    let empty = BrdfAtlasSegment {
        x0: f32::NAN,
        y0: f32::NAN,
        x1: f32::NAN,
        y1: f32::NAN,
        level: usize::MAX,
    };
    let mut out = vec![empty; n];
    let mut m = 0;
    let s = unsafe {
        brdf_atlas_contours(
            rgb.as_ptr(),
            width,
            height,
            levels.as_ptr(),
            levels.len(),
            out.as_mut_ptr(),
            out.len(),
            &mut m,
        )
    };
    assert_eq!(s, BrdfAtlasStatus::Ok);
    assert_eq!(m, n);
    out
}

#[test]
fn a_ramp_gives_straight_lines_through_the_right_pixels() {
    // Value = px: level 2.5 lies half-way between pixel centres 2 and 3,
    // i.e. at x = 3.0 in pixel-edge coordinates, on every row pair.
    let (w, h) = (7, 5);
    let rgb = grey(w, h, |px, _| px);
    let segs = segments(&rgb, w, h, &[2.5, 4.25]);
    assert_eq!(segs.len(), 2 * (h - 1));
    for (k, s) in segs.iter().enumerate() {
        let (level, x) = if k < h - 1 { (0, 3.0) } else { (1, 4.75) };
        assert_eq!(s.level, level, "{s:?}");
        assert!((s.x0 - x).abs() < 1e-6 && (s.x1 - x).abs() < 1e-6, "{s:?}");
        let (ya, yb) = (s.y0.min(s.y1), s.y0.max(s.y1));
        assert!((yb - ya - 1.0).abs() < 1e-6, "{s:?}");
        assert!(ya >= 0.5 - 1e-6 && yb <= h as f32 - 0.5 + 1e-6, "{s:?}");
    }
    // Every row pair is covered once per level.
    let mut starts: Vec<i32> = segs[..h - 1]
        .iter()
        .map(|s| (s.y0.min(s.y1) - 0.5).round() as i32)
        .collect();
    starts.sort();
    assert_eq!(starts, (0..h as i32 - 1).collect::<Vec<_>>());
}

#[test]
fn a_cone_gives_circles() {
    // Value = distance from the centre (16, 16) of a 33 x 33 map: the
    // contour at r is the circle of radius r around pixel centre (16.5, 16.5).
    let n = 33;
    let rgb = grey(n, n, |px, py| {
        ((px - 16.0).powi(2) + (py - 16.0).powi(2)).sqrt()
    });
    for r in [3.3f32, 7.0, 12.6] {
        let segs = segments(&rgb, n, n, &[r]);
        // A closed polygon around a circle of radius r: about 2 pi r / ~0.8 segments.
        assert!(
            segs.len() as f32 > 4.0 * r,
            "{} segments at r = {r}",
            segs.len()
        );
        let mut length = 0.0;
        for s in &segs {
            for (x, y) in [(s.x0, s.y0), (s.x1, s.y1)] {
                let d = ((x - 16.5).powi(2) + (y - 16.5).powi(2)).sqrt();
                // Linear interpolation of a distance along a grid edge: off by
                // well under a tenth of a pixel at these radii.
                assert!((d - r).abs() < 0.1, "end ({x}, {y}) at {d}, level {r}");
            }
            length += ((s.x1 - s.x0).powi(2) + (s.y1 - s.y0).powi(2)).sqrt();
        }
        let circumference = 2.0 * std::f32::consts::PI * r;
        assert!(
            (length - circumference).abs() < 0.02 * circumference,
            "length {length} vs {circumference}"
        );
    }
}

#[test]
fn levels_are_evenly_spaced_inside_the_range() {
    let (w, h) = (4, 3);
    // Luminance from 0.2 to 1.4 (px * 0.1 + py * 0.5 ...): lo and hi known.
    let rgb = grey(w, h, |px, py| 0.2 + 0.1 * px + 0.45 * py);
    let (lo, hi) = (0.2f32, 0.2 + 0.3 + 0.9);
    let mut levels = [f32::NAN; 5];
    let mut written = 0;
    let s = unsafe {
        brdf_atlas_contour_levels(rgb.as_ptr(), w, h, 3, levels.as_mut_ptr(), 5, &mut written)
    };
    assert_eq!(s, BrdfAtlasStatus::Ok);
    assert_eq!(written, 3);
    for (k, l) in levels[..3].iter().enumerate() {
        let want = lo + (hi - lo) * (k + 1) as f32 / 4.0;
        assert!((l - want).abs() < 1e-5, "level {k}: {l} vs {want}");
    }
    assert!(levels[3].is_nan(), "only `count` levels are written");

    // A flat map has none.
    let flat = grey(w, h, |_, _| 0.3);
    let mut written = 9;
    let s = unsafe {
        brdf_atlas_contour_levels(flat.as_ptr(), w, h, 3, levels.as_mut_ptr(), 5, &mut written)
    };
    assert_eq!(s, BrdfAtlasStatus::Ok);
    assert_eq!(written, 0);
}

#[test]
fn bad_calls_are_refused_and_write_nothing() {
    let (w, h) = (5, 4);
    let rgb = grey(w, h, |px, _| px);
    let level = [1.5f32];
    let mut n = 77usize;
    let mut buf = [BrdfAtlasSegment {
        x0: 0.0,
        y0: 0.0,
        x1: 0.0,
        y1: 0.0,
        level: 9,
    }; 2];
    let call =
        |rgb: *const f32,
         w: usize,
         h: usize,
         lv: *const f32,
         nl: usize,
         b: *mut BrdfAtlasSegment,
         len: usize,
         n: *mut usize| unsafe { brdf_atlas_contours(rgb, w, h, lv, nl, b, len, n) };
    // Short buffer: 3 segments (h - 1) do not fit in 2.
    assert_eq!(
        call(
            rgb.as_ptr(),
            w,
            h,
            level.as_ptr(),
            1,
            buf.as_mut_ptr(),
            2,
            &mut n
        ),
        BrdfAtlasStatus::BufferTooSmall
    );
    assert_eq!(n, 77);
    assert!(buf.iter().all(|s| s.level == 9));
    // NULL map, NULL levels with a count, NULL count.
    assert_eq!(
        call(null(), w, h, level.as_ptr(), 1, null_mut(), 0, &mut n),
        BrdfAtlasStatus::NullArgument
    );
    assert_eq!(
        call(rgb.as_ptr(), w, h, null(), 1, null_mut(), 0, &mut n),
        BrdfAtlasStatus::NullArgument
    );
    assert_eq!(
        call(
            rgb.as_ptr(),
            w,
            h,
            level.as_ptr(),
            1,
            null_mut(),
            0,
            null_mut()
        ),
        BrdfAtlasStatus::NullArgument
    );
    // Zero size, NaN in the map, NaN level.
    assert_eq!(
        call(rgb.as_ptr(), 0, h, level.as_ptr(), 1, null_mut(), 0, &mut n),
        BrdfAtlasStatus::InvalidArgument
    );
    let mut nan = rgb.clone();
    nan[7] = f32::NAN;
    assert_eq!(
        call(nan.as_ptr(), w, h, level.as_ptr(), 1, null_mut(), 0, &mut n),
        BrdfAtlasStatus::InvalidArgument
    );
    let message = unsafe { std::ffi::CStr::from_ptr(brdf_atlas_last_error_message()) }
        .to_string_lossy()
        .into_owned();
    assert!(
        message.starts_with("brdf_atlas_contours: ") && message.contains("NaN"),
        "{message}"
    );
    assert_eq!(
        call(
            rgb.as_ptr(),
            w,
            h,
            [f32::INFINITY].as_ptr(),
            1,
            null_mut(),
            0,
            &mut n
        ),
        BrdfAtlasStatus::InvalidArgument
    );
    assert_eq!(n, 77);
    // No levels: no segments, levels may be NULL.
    assert_eq!(
        call(rgb.as_ptr(), w, h, null(), 0, null_mut(), 0, &mut n),
        BrdfAtlasStatus::Ok
    );
    assert_eq!(n, 0);
    // Levels: short buffer.
    let mut lv = [0.0f32; 2];
    let mut written = 5;
    let s = unsafe {
        brdf_atlas_contour_levels(rgb.as_ptr(), w, h, 3, lv.as_mut_ptr(), 2, &mut written)
    };
    assert_eq!(s, BrdfAtlasStatus::BufferTooSmall);
    assert_eq!((written, lv), (5, [0.0, 0.0]));
}
