//! Tensor Chebyshev patches of the plane: their refinement from values at
//! the nodes of successive grids, cut in four where a patch converges too
//! slowly ([`refine`]), and their evaluation at points and along pixel rows
//! ([`eval_row`]). What the values are (exact albedos, a sampled rule's,
//! the predictive variance) is the caller's: [`crate::maps::albedo_field`].

use crate::error::Result;
use crate::maps::view::View;
use crate::simd::dot;

/// How many times a domain may be cut in four.
pub const MAX_DEPTH: usize = 4;
/// A patch whose estimate is this many tolerances or more after a
/// refinement is cut in four rather than refined further.
pub const CUT_RATIO: f64 = 30.0;

/// A patch of the plane with a tensor grid of exact values, and the
/// polynomial through them.
#[derive(Debug, Clone)]
pub(crate) struct Patch {
    /// The patch's rectangle.
    pub(crate) rect: View,
    /// Grid abscissae, ascending.
    pub(crate) xs: Vec<f64>,
    /// Grid ordinates, ascending.
    pub(crate) ys: Vec<f64>,
    /// `channels` values per node, row `iy` after row `iy - 1`.
    pub(crate) values: Vec<f64>,
    /// The last refinement's error estimate.
    pub(crate) estimate: f64,
}

/// Exact values at a set of points, `channels` a point.
pub(crate) type Exact<'a> = dyn FnMut(&[[f64; 2]]) -> Result<Option<Vec<f64>>> + 'a;

/// Patches covering `rect` whose interpolants meet `tol` (or are the finest
/// grid at the deepest cut); `None` when `exact` refuses (its budget is spent).
///
/// Each patch starts from the grid of `levels[0]` points a side and takes
/// the next grid (which holds the previous one) until its interpolant,
/// compared with the values at the new nodes, is within `tol`; a patch
/// far off after a doubling, or at its finest grid, is cut in four (down to
/// [`MAX_DEPTH`] cuts). Every patch's decisions depend on its own values
/// alone, so the patches refine side by side: each round asks `exact` for
/// the nodes every patch still refining needs, in one call (one pass over
/// the store for all of them), and the patches come out in the order of
/// refining one patch after another (its quarters in place of a cut patch).
pub(crate) fn refine(
    rect: View,
    channels: usize,
    levels: &[usize],
    tol: f64,
    depth: usize,
    exact: &mut Exact<'_>,
) -> Result<Option<Vec<Patch>>> {
    /// A patch being refined: where it stands in the depth-first order,
    /// its depth, and its grid of `levels[level]` points a side (none yet
    /// before the first round).
    struct Open {
        key: Vec<u8>,
        depth: usize,
        rect: View,
        grid: Option<(usize, Patch)>,
    }
    let start = Open {
        key: Vec::new(),
        depth,
        rect,
        grid: None,
    };
    let mut open = vec![start];
    let mut done: Vec<(Vec<u8>, Patch)> = Vec::new();
    while !open.is_empty() {
        // The nodes each open patch needs next: its first grid, or the new
        // nodes of its next one (odd index on either axis).
        let asks: Vec<Vec<(usize, usize)>> = open
            .iter()
            .map(|o| {
                let side = o.grid.as_ref().map_or(levels[0], |(l, _)| levels[l + 1]);
                let first = o.grid.is_none();
                (0..side)
                    .flat_map(|iy| (0..side).map(move |ix| (ix, iy)))
                    .filter(|(ix, iy)| first || ix % 2 == 1 || iy % 2 == 1)
                    .collect()
            })
            .collect();
        let mut pts = Vec::new();
        for (o, ask) in open.iter().zip(&asks) {
            let side = o.grid.as_ref().map_or(levels[0], |(l, _)| levels[l + 1]);
            let xs = lobatto(o.rect.x0, o.rect.x1, side);
            let ys = lobatto(o.rect.y0, o.rect.y1, side);
            pts.extend(ask.iter().map(|&(ix, iy)| [xs[ix], ys[iy]]));
        }
        let Some(got) = exact(&pts)? else {
            return Ok(None);
        };
        let mut got = got.chunks_exact(channels);
        let mut next = Vec::new();
        for (o, ask) in open.into_iter().zip(asks) {
            let values: Vec<&[f64]> = got.by_ref().take(ask.len()).collect();
            let (level, patch) = match o.grid {
                None => {
                    let patch = Patch {
                        rect: o.rect,
                        xs: lobatto(o.rect.x0, o.rect.x1, levels[0]),
                        ys: lobatto(o.rect.y0, o.rect.y1, levels[0]),
                        values: values.concat(),
                        estimate: f64::INFINITY,
                    };
                    next.push(Open {
                        grid: Some((0, patch)),
                        ..o
                    });
                    continue;
                }
                Some((level, patch)) => (
                    level + 1,
                    refined(&patch, levels[level + 1], &ask, &values, channels),
                ),
            };
            let from = levels[level - 1];
            let estimate = patch.estimate;
            let last = level + 1 == levels.len();
            // Far off after a doubling: the patch is too large for its
            // function at these degrees; quarters converge faster than finer
            // grids. Not judged on the first doubling, from a grid of three
            // points a side, which only lets a nearly linear patch stop early.
            let cut_early = o.depth < MAX_DEPTH && from > 3 && estimate > CUT_RATIO * tol;
            if estimate <= tol || (last && o.depth >= MAX_DEPTH) {
                done.push((o.key, patch));
            } else if cut_early || last {
                let r = o.rect;
                let (xm, ym) = (0.5 * (r.x0 + r.x1), 0.5 * (r.y0 + r.y1));
                let quarters = [(r.x0, xm), (xm, r.x1)].into_iter().flat_map(|(x0, x1)| {
                    [(r.y0, ym), (ym, r.y1)].map(|(y0, y1)| View { x0, x1, y0, y1 })
                });
                for (q, rect) in quarters.enumerate() {
                    let mut key = o.key.clone();
                    key.push(q as u8);
                    next.push(Open {
                        key,
                        depth: o.depth + 1,
                        rect,
                        grid: None,
                    });
                }
            } else {
                next.push(Open {
                    grid: Some((level, patch)),
                    ..o
                });
            }
        }
        open = next;
    }
    done.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(Some(done.into_iter().map(|(_, p)| p).collect()))
}

/// `patch` on its next grid of `size` points a side: the new nodes `fresh`
/// (odd index on either axis) take `got`, the others the patch's values;
/// its estimate is the largest error of the patch's interpolant at the new
/// nodes, relative to the node's largest channel (with a floor,
/// [`node_scale`]; absolute for one channel).
fn refined(
    patch: &Patch,
    size: usize,
    fresh: &[(usize, usize)],
    got: &[&[f64]],
    channels: usize,
) -> Patch {
    let rect = patch.rect;
    let xs = lobatto(rect.x0, rect.x1, size);
    let ys = lobatto(rect.y0, rect.y1, size);
    let scale = node_scale(&patch.values, channels);
    let mut estimate = 0.0f64;
    for (&(ix, iy), v) in fresh.iter().zip(got) {
        let guess = eval_point(patch, [xs[ix], ys[iy]], channels);
        let s = if channels == 1 {
            1.0
        } else {
            v.iter().fold(scale, |a, b| a.max(b.abs()))
        };
        for (g, v) in guess.iter().zip(v.iter()) {
            estimate = estimate.max((g - v).abs() / s);
        }
    }
    let mut values = vec![0.0f64; xs.len() * ys.len() * channels];
    for iy in (0..ys.len()).step_by(2) {
        for ix in (0..xs.len()).step_by(2) {
            let (o, i) = (iy * xs.len() + ix, (iy / 2) * patch.xs.len() + ix / 2);
            values[o * channels..(o + 1) * channels]
                .copy_from_slice(&patch.values[i * channels..(i + 1) * channels]);
        }
    }
    for (&(ix, iy), v) in fresh.iter().zip(got) {
        let o = iy * xs.len() + ix;
        values[o * channels..(o + 1) * channels].copy_from_slice(v);
    }
    Patch {
        rect,
        xs,
        ys,
        values,
        estimate,
    }
}

/// A floor for the relative error's scale, a thousandth of the largest node
/// value: a nearly black node does not demand what nobody sees.
fn node_scale(values: &[f64], channels: usize) -> f64 {
    if channels == 1 {
        return 1.0;
    }
    1e-3 * values.iter().fold(1e-12f64, |a, v| a.max(v.abs()))
}

/// The points of a tensor grid, row `iy` after row `iy - 1`.
pub(crate) fn grid_points(xs: &[f64], ys: &[f64]) -> Vec<[f64; 2]> {
    ys.iter()
        .flat_map(|&y| xs.iter().map(move |&x| [x, y]))
        .collect()
}

/// `n` Chebyshev–Lobatto points of `[a, b]`, ascending, ends included.
pub(crate) fn lobatto(a: f64, b: f64, n: usize) -> Vec<f64> {
    let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
    (0..n)
        .map(|j| match j {
            0 => a,
            j if j == n - 1 => b,
            j => c - h * (std::f64::consts::PI * j as f64 / (n - 1) as f64).cos(),
        })
        .collect()
}

/// The Lagrange basis of the Lobatto grid `grid` at `x` (barycentric form,
/// weights `(-1)^j`, halved at the ends): `sum_j l_j f_j` is the interpolant.
fn lagrange(grid: &[f64], x: f64) -> Vec<f64> {
    let mut l = Vec::with_capacity(grid.len());
    lagrange_into(grid, x, &mut l);
    l
}

/// [`lagrange`] into `l` (its old contents dropped), allocating nothing
/// once `l` has the room: the per-pixel form.
fn lagrange_into(grid: &[f64], x: f64, l: &mut Vec<f64>) {
    let n = grid.len();
    l.clear();
    if let Some(j) = grid.iter().position(|&g| g == x) {
        l.resize(n, 0.0);
        l[j] = 1.0;
        return;
    }
    l.extend(grid.iter().enumerate().map(|(j, &g)| {
        let w = if j == 0 || j == n - 1 { 0.5 } else { 1.0 };
        let w = if j % 2 == 0 { w } else { -w };
        w / (x - g)
    }));
    let s: f64 = l.iter().sum();
    l.iter_mut().for_each(|v| *v /= s);
}

/// The patch holding `x`, or the nearest one (`x` just outside by rounding).
pub(crate) fn find(patches: &[Patch], x: [f64; 2]) -> &Patch {
    let outside = |p: &Patch| {
        let r = &p.rect;
        (r.x0 - x[0]).max(x[0] - r.x1).max(0.0) + (r.y0 - x[1]).max(x[1] - r.y1).max(0.0)
    };
    patches
        .iter()
        .min_by(|a, b| outside(a).total_cmp(&outside(b)))
        .expect("a field has patches")
}

/// The patch's interpolant at `x`, `channels` values.
pub(crate) fn eval_point(p: &Patch, x: [f64; 2], channels: usize) -> Vec<f64> {
    let (lx, ly) = (lagrange(&p.xs, x[0]), lagrange(&p.ys, x[1]));
    let mut out = vec![0.0; channels];
    for (iy, wy) in ly.iter().enumerate() {
        for (ix, wx) in lx.iter().enumerate() {
            let o = (iy * p.xs.len() + ix) * channels;
            for (c, oc) in out.iter_mut().enumerate() {
                *oc += wy * wx * p.values[o + c];
            }
        }
    }
    out
}

/// Evaluate patches at the pixels of one image row: `xs` the pixels'
/// abscissae, `y` the row's ordinate; `write(px, values)` per pixel.
pub(crate) fn eval_row(
    patches: &[Patch],
    xs: &[f64],
    y: f64,
    channels: usize,
    mut write: impl FnMut(usize, &[f64]),
) {
    let mut px = 0;
    let mut lx = Vec::new();
    // Pixels of a row fall in patches in runs (patches are rectangles).
    while px < xs.len() {
        let p = find(patches, [xs[px], y]);
        let ly = lagrange(&p.ys, y);
        // g_c(x_j) = sum_i l_i(y) f_c(x_j, y_i): the row's polynomial in x.
        let nx = p.xs.len();
        let mut g = vec![0.0f64; channels * nx];
        for (iy, wy) in ly.iter().enumerate() {
            for ix in 0..nx {
                let o = (iy * nx + ix) * channels;
                for c in 0..channels {
                    g[c * nx + ix] += wy * p.values[o + c];
                }
            }
        }
        let mut out = vec![0.0f64; channels];
        // The run goes on while the pixel is inside this patch (a pixel on
        // the border of two is in either: both interpolate the same nodes'
        // rule there), or while the nearest patch is still this one.
        let inside = |x: f64| p.rect.x0 <= x && x <= p.rect.x1 && p.rect.y0 <= y && y <= p.rect.y1;
        while px < xs.len() && (inside(xs[px]) || std::ptr::eq(find(patches, [xs[px], y]), p)) {
            lagrange_into(&p.xs, xs[px], &mut lx);
            for (c, o) in out.iter_mut().enumerate() {
                *o = dot::dot(&lx, &g[c * nx..(c + 1) * nx]);
            }
            write(px, &out);
            px += 1;
        }
    }
}
