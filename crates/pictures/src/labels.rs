//! Where the names of a map's materials go: every label beside its dot or,
//! when there is no room there, further out with a thin leader line; never
//! over another label, a dot, a leader or a reserved box (the colour key,
//! the axis ticks), never outside the image.
//!
//! Greedy, most isolated dot first (distance to its nearest neighbour), so
//! that when not every label fits, the ones left out are those in the
//! densest clusters, where a name would be unreadable anyway. Each dot tries
//! eight positions touching it (right, left, above, below, the diagonals),
//! then rings of sixteen positions at growing distances joined to the dot
//! by a leader; the first position that is free wins.

use crate::canvas::{Rect, overlaps};

/// A label that found room.
#[derive(Debug, Clone, PartialEq)]
pub struct Placed {
    /// Index of its dot in the input.
    pub index: usize,
    /// Its box.
    pub rect: Rect,
    /// The leader from the dot's edge to the box, if the box is not beside the dot.
    pub leader: Option<[[f32; 2]; 2]>,
}

/// Where the labels went.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Layout {
    /// The labels drawn, most isolated dot first.
    pub placed: Vec<Placed>,
    /// The indices of the dots left without a label.
    pub left_out: Vec<usize>,
}

/// Distances (pixels from the dot's centre) of the leader rings.
const RINGS: [f32; 6] = [16.0, 26.0, 38.0, 52.0, 70.0, 92.0];
/// Directions tried on each ring.
const DIRECTIONS: usize = 16;

/// The box a dot of radius `r` at `c` occupies (its outline and a pixel more).
pub fn dot_box(c: [f32; 2], r: f32) -> Rect {
    [
        c[0] - r - 1.0,
        c[1] - r - 1.0,
        c[0] + r + 1.0,
        c[1] + r + 1.0,
    ]
}

/// Place labels of `sizes` (width, height) for the dots at `dots` (pixel
/// coordinates, radius `radius`) inside `bounds`, avoiding `reserved`.
pub fn place(
    dots: &[[f32; 2]],
    sizes: &[[f32; 2]],
    radius: f32,
    bounds: Rect,
    reserved: &[Rect],
) -> Layout {
    let n = dots.len().min(sizes.len());
    let dot_boxes: Vec<Rect> = dots[..n].iter().map(|&c| dot_box(c, radius)).collect();
    let mut order: Vec<(f32, usize)> = (0..n)
        .map(|i| {
            let nearest = (0..n)
                .filter(|&j| j != i)
                .map(|j| dist(dots[i], dots[j]))
                .fold(f32::INFINITY, f32::min);
            (nearest, i)
        })
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut layout = Layout::default();
    for (_, i) in order {
        let free = |rect: &Rect, leader: Option<[[f32; 2]; 2]>, layout: &Layout| {
            let inside = rect[0] >= bounds[0]
                && rect[1] >= bounds[1]
                && rect[2] <= bounds[2]
                && rect[3] <= bounds[3];
            inside
                && !dot_boxes.iter().any(|d| overlaps(rect, d))
                && !reserved.iter().any(|r| overlaps(rect, r))
                && layout.placed.iter().all(|p| {
                    !overlaps(rect, &p.rect)
                        && p.leader.is_none_or(|[a, b]| !segment_hits_rect(a, b, rect))
                })
                && leader.is_none_or(|[a, b]| {
                    dot_boxes
                        .iter()
                        .enumerate()
                        .all(|(j, d)| j == i || !segment_hits_rect(a, b, d))
                        && !reserved.iter().any(|r| segment_hits_rect(a, b, r))
                        && layout.placed.iter().all(|p| {
                            !segment_hits_rect(a, b, &p.rect)
                                && p.leader.is_none_or(|[c, d]| !segments_cross(a, b, c, d))
                        })
                })
        };
        let found = candidates(dots[i], sizes[i], radius).find(|(rect, leader)| {
            rect.iter().all(|v| v.is_finite()) && free(rect, *leader, &layout)
        });
        match found {
            Some((rect, leader)) => layout.placed.push(Placed {
                index: i,
                rect,
                leader,
            }),
            None => layout.left_out.push(i),
        }
    }
    layout.left_out.sort_unstable();
    layout
}

/// Every position tried for a label of `size` at dot `c`, best first.
fn candidates(
    c: [f32; 2],
    size: [f32; 2],
    radius: f32,
) -> impl Iterator<Item = (Rect, Option<[[f32; 2]; 2]>)> {
    let [w, h] = size;
    let g = radius + 2.0;
    let d = g * 0.7;
    let beside = [
        [c[0] + g, c[1] - h / 2.0],
        [c[0] - g - w, c[1] - h / 2.0],
        [c[0] - w / 2.0, c[1] - g - h],
        [c[0] - w / 2.0, c[1] + g],
        [c[0] + d, c[1] - d - h],
        [c[0] + d, c[1] + d],
        [c[0] - d - w, c[1] - d - h],
        [c[0] - d - w, c[1] + d],
    ]
    .into_iter()
    .map(move |[x, y]| ([x, y, x + w, y + h], None));
    let ringed = RINGS.into_iter().flat_map(move |ring| {
        (0..DIRECTIONS).map(move |k| {
            let angle = std::f32::consts::TAU * k as f32 / DIRECTIONS as f32;
            let (cos, sin) = (angle.cos(), angle.sin());
            let p = [c[0] + ring * cos, c[1] + ring * sin];
            let align = |v: f32, t: f32, len: f32| {
                if t > 0.38 {
                    v
                } else if t < -0.38 {
                    v - len
                } else {
                    v - len / 2.0
                }
            };
            let (x, y) = (align(p[0], cos, w), align(p[1], sin, h));
            let rect = [x, y, x + w, y + h];
            // From the dot's edge to the nearest point of the box.
            let q = [c[0].clamp(rect[0], rect[2]), c[1].clamp(rect[1], rect[3])];
            let len = dist(c, q).max(1e-3);
            let start = [
                c[0] + (q[0] - c[0]) * (radius + 1.0) / len,
                c[1] + (q[1] - c[1]) * (radius + 1.0) / len,
            ];
            (rect, Some([start, q]))
        })
    });
    beside.chain(ringed)
}

fn dist(a: [f32; 2], b: [f32; 2]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// Does segment `a`-`b` pass through the interior of `r` (Liang-Barsky clip)?
pub fn segment_hits_rect(a: [f32; 2], b: [f32; 2], r: &Rect) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [
        (-dx, a[0] - r[0]),
        (dx, r[2] - a[0]),
        (-dy, a[1] - r[1]),
        (dy, r[3] - a[1]),
    ] {
        if p == 0.0 {
            if q <= 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t1 - t0 > 1e-4
}

/// Do segments `a`-`b` and `c`-`d` cross (touching ends do not count)?
fn segments_cross(a: [f32; 2], b: [f32; 2], c: [f32; 2], d: [f32; 2]) -> bool {
    let orient = |p: [f32; 2], q: [f32; 2], r: [f32; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    o1 * o2 < 0.0 && o3 * o4 < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A seeded scatter: a tight cluster and a loose spread.
    fn scatter(n: usize, seed: u64) -> Vec<[f32; 2]> {
        let mut s = seed;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|i| {
                if i % 3 == 0 {
                    [200.0 + 40.0 * next(), 200.0 + 40.0 * next()]
                } else {
                    [512.0 * next(), 512.0 * next()]
                }
            })
            .collect()
    }

    #[test]
    fn labels_never_overlap_dots_reserved_boxes_or_each_other() {
        let dots = scatter(120, 7);
        let sizes: Vec<[f32; 2]> = (0..dots.len())
            .map(|i| [40.0 + (i % 7) as f32 * 9.0, 15.0])
            .collect();
        let reserved = [[400.0, 0.0, 512.0, 120.0]];
        let bounds = [0.0, 0.0, 512.0, 512.0];
        let layout = place(&dots, &sizes, 4.0, bounds, &reserved);
        assert_eq!(layout.placed.len() + layout.left_out.len(), dots.len());
        assert!(layout.placed.len() > 40, "{} placed", layout.placed.len());
        assert!(!layout.left_out.is_empty(), "the cluster cannot all fit");
        for (k, p) in layout.placed.iter().enumerate() {
            let r = p.rect;
            assert!(r[0] >= 0.0 && r[1] >= 0.0 && r[2] <= 512.0 && r[3] <= 512.0);
            assert!((r[2] - r[0] - sizes[p.index][0]).abs() < 1e-3);
            assert!(!overlaps(&r, &reserved[0]));
            for d in &dots {
                assert!(!overlaps(&r, &dot_box(*d, 4.0)), "{r:?} over the dot {d:?}");
            }
            for q in &layout.placed[..k] {
                assert!(!overlaps(&r, &q.rect), "{r:?} and {:?}", q.rect);
            }
            // Beside its dot, or joined to it by a leader that ends on the box.
            let c = dots[p.index];
            match p.leader {
                None => {
                    let gap = (r[0] - c[0])
                        .max(c[0] - r[2])
                        .max(r[1] - c[1])
                        .max(c[1] - r[3]);
                    assert!(gap <= 6.1, "{gap}");
                }
                Some([a, b]) => {
                    assert!((dist(a, c) - 5.0).abs() < 1e-3);
                    assert!(b[0] >= r[0] && b[0] <= r[2] && b[1] >= r[1] && b[1] <= r[3]);
                }
            }
        }
        // The most isolated dot is labelled.
        let isolation = |i: usize| {
            (0..dots.len())
                .filter(|&j| j != i)
                .map(|j| dist(dots[i], dots[j]))
                .fold(f32::INFINITY, f32::min)
        };
        let loneliest = (0..dots.len())
            .max_by(|&a, &b| isolation(a).total_cmp(&isolation(b)))
            .unwrap();
        assert!(layout.placed.iter().any(|p| p.index == loneliest));
    }

    #[test]
    fn geometry_helpers() {
        let r = [0.0, 0.0, 10.0, 10.0];
        assert!(segment_hits_rect([-5.0, 5.0], [15.0, 5.0], &r));
        assert!(!segment_hits_rect([-5.0, 15.0], [15.0, 15.0], &r));
        assert!(!segment_hits_rect([-5.0, 5.0], [0.0, 5.0], &r));
        assert!(segments_cross(
            [0.0, 0.0],
            [2.0, 2.0],
            [0.0, 2.0],
            [2.0, 0.0]
        ));
        assert!(!segments_cross(
            [0.0, 0.0],
            [1.0, 1.0],
            [0.0, 2.0],
            [2.0, 3.0]
        ));
    }
}
