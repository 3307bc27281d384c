//! Luminance contours of an albedo map, by marching squares.

use super::albedo_map::AlbedoMap;

/// Luminance of linear RGB (Rec. 709 weights).
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// A contour segment in pixel coordinates, and its level index.
pub type Segment = ([f32; 2], [f32; 2], usize);

/// Marching squares on the luminance of `map` at `levels` (pixel centres
/// are grid nodes). Returns the segments of every level.
pub fn contours(map: &AlbedoMap, levels: &[f32]) -> Vec<Segment> {
    let (w, h) = (map.width, map.height);
    let lum: Vec<f32> = map.rgb.iter().map(|c| luminance(*c)).collect();
    let mut out = Vec::new();
    if w < 2 || h < 2 {
        return out;
    }
    for (li, &level) in levels.iter().enumerate() {
        for y in 0..h - 1 {
            for x in 0..w - 1 {
                // Corners: 0 top-left, 1 top-right, 2 bottom-right, 3 bottom-left.
                let v = [
                    lum[y * w + x],
                    lum[y * w + x + 1],
                    lum[(y + 1) * w + x + 1],
                    lum[(y + 1) * w + x],
                ];
                let p = [
                    [x as f32, y as f32],
                    [x as f32 + 1.0, y as f32],
                    [x as f32 + 1.0, y as f32 + 1.0],
                    [x as f32, y as f32 + 1.0],
                ];
                let above: Vec<bool> = v.iter().map(|&a| a >= level).collect();
                // Crossing points on the four edges (edge k joins corner k and k+1).
                let cross = |k: usize| -> Option<[f32; 2]> {
                    let (a, b) = (k, (k + 1) % 4);
                    if above[a] == above[b] {
                        return None;
                    }
                    let t = (level - v[a]) / (v[b] - v[a]);
                    Some([
                        p[a][0] + t * (p[b][0] - p[a][0]) + 0.5,
                        p[a][1] + t * (p[b][1] - p[a][1]) + 0.5,
                    ])
                };
                let pts: Vec<[f32; 2]> = (0..4).filter_map(cross).collect();
                match pts.len() {
                    2 => out.push((pts[0], pts[1], li)),
                    4 => {
                        // Saddle: decide by the centre value.
                        let centre = v.iter().sum::<f32>() / 4.0;
                        if (centre >= level) == above[0] {
                            out.push((pts[0], pts[3], li));
                            out.push((pts[1], pts[2], li));
                        } else {
                            out.push((pts[0], pts[1], li));
                            out.push((pts[2], pts[3], li));
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    out
}

/// `count` levels evenly spaced strictly inside the luminance range of `map`.
pub fn contour_levels(map: &AlbedoMap, count: usize) -> Vec<f32> {
    let (lo, hi) = map
        .rgb
        .iter()
        .map(|c| luminance(*c))
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), l| {
            (a.min(l), b.max(l))
        });
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    (1..=count)
        .map(|k| lo + (hi - lo) * k as f32 / (count + 1) as f32)
        .collect()
}
