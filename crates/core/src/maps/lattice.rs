//! The prepared map: exact albedos of the whole default view on an adaptive
//! lattice, built once ([`Atlas::prepare_map`], `brdf-atlas prepare`) and
//! kept beside the model, so that every later map inside that view is
//! drawn from it in a fraction of a second.
//!
//! Across the default view the albedo has detail a few hundredths of the
//! view wide (where neighbouring materials differ most, and where the soft
//! floor or the clamp bends many store rows along nearby curves), so no
//! polynomial of a few hundred nodes follows it (docs/performance.md, "Map
//! quadrature"); but the detail covers little of the view. The lattice
//! starts from cells a sixteenth of the view wide and, cell by cell,
//! compares the tensor cubic of its lattice with exact albedos (the dense
//! rule over the full reconstruction, [`Atlas::exact_albedos`]) at the
//! next finer lattice's new nodes in the cell. A cell within the tolerance
//! of each node's largest channel is drawn from the finer lattice (whose
//! error is well below the estimate); one that misses is cut in four, down
//! to cells of 1/256 of the view, which are drawn from the finest lattice
//! unchecked (docs/performance.md says how many and how far off).
//!
//! A pixel's albedo is the cubic of the lattice that draws its cell: 16
//! nodes, no pass over the store. The predictive variance (for the map's
//! fade) is the cubic of exact variances at every node of the finest
//! lattice, computed when the lattice is first used (`O(N^2)` a node).
//!
//! The lattice is saved as JSON beside the model (`MODEL.lattice` for
//! `MODEL.atlas`) with a fingerprint of the model it was built from; a
//! lattice of another fit, or of another rule, is not used.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::maps::Atlas;
use crate::maps::view::View;
use crate::model::blend::plausibility::BlendRule;
use crate::progress::Progress;

/// The largest error of a cell's cubic allowed at the finer lattice's new
/// nodes, relative to the node's largest channel: 0.5%.
pub const LATTICE_TOLERANCE: f64 = 5e-3;
/// The finest lattice has `2^FINEST` cells a side.
pub(super) const FINEST: u32 = 8;
/// The coarsest lattice checked has `2^COARSEST` cells a side.
pub(super) const COARSEST: u32 = 4;
/// Exact albedos a pass over the store computes at once (a pass is the
/// unit of progress and of cancellation).
pub(super) const CHUNK: usize = 256;
/// What the file says it is.
const FORMAT: &str = "brdf-atlas lattice";
/// 2: the floor's cap reaches only as far as keeps every directional
/// albedo under 1 (a lattice of version 1 holds albedos of the earlier cap).
/// 3: the nodes integrate the cubic interpolant of every 8th phi_d bin
/// (version 2's took each cell's weight on its middle bin).
const VERSION: u32 = 3;

/// What reading the lattice beside a model gave: the lattice, none, or why
/// it cannot be used.
pub(super) type Loaded = std::result::Result<Option<Arc<AlbedoLattice>>, String>;

/// A map drawn with the lattice: albedo, variance, and the share of the
/// pixels from the lattice.
pub(super) type Drawn = (Vec<[f32; 3]>, Vec<f32>, f64);

/// Node indices on the finest lattice: (row from the bottom, column).
pub(super) type Key = (usize, usize);

/// Exact albedos of a view on an adaptive lattice, and the cubic between them.
pub struct AlbedoLattice {
    pub(super) view: View,
    pub(super) rule: BlendRule,
    pub(super) tolerance: f64,
    pub(super) fingerprint: String,
    /// The level (cells a side `2^level`) that draws each finest cell,
    /// row-major from the bottom.
    pub(super) serve: Vec<u8>,
    /// Every exact albedo, by finest-lattice key.
    pub(super) nodes: HashMap<Key, [f64; 3]>,
    /// The same albedos laid out per level (`grids[level]`: `(2^level + 1)^2`
    /// nodes, row-major from the bottom, NaN where none was computed), for
    /// drawing.
    pub(super) grids: Vec<Vec<[f64; 3]>>,
    /// The finest cells whose cubic was not checked (cut at the last level).
    pub(super) unchecked: usize,
    /// Exact variances at every node of the finest lattice, once used.
    pub(super) variance: OnceLock<Vec<f64>>,
}

/// The lattice as saved.
#[derive(Serialize, Deserialize)]
struct LatticeFile {
    format: String,
    version: u32,
    model: String,
    rule: String,
    view: View,
    tolerance: f64,
    finest: u32,
    unchecked: usize,
    serve: Vec<u8>,
    nodes: Vec<(usize, usize, [f64; 3])>,
}

impl AlbedoLattice {
    /// The window the lattice covers (the default view).
    pub fn view(&self) -> View {
        self.view
    }

    /// The material it maps.
    pub fn rule(&self) -> BlendRule {
        self.rule
    }

    /// Its tolerance, relative to a node's largest channel.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// Exact albedos it holds.
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Share of the view in finest cells whose cubic was not checked.
    pub fn unchecked_share(&self) -> f64 {
        self.unchecked as f64 / self.serve.len() as f64
    }

    /// Whether it draws some of `view` of `rule`'s material: the rule is
    /// its own and the view overlaps its window.
    pub fn serves(&self, view: View, rule: BlendRule) -> bool {
        let v = self.view;
        rule == self.rule
            && view.x0 <= v.x1
            && view.x1 >= v.x0
            && view.y0 <= v.y1
            && view.y1 >= v.y0
    }

    /// Finest-lattice coordinates of a latent point (row from the bottom,
    /// column), continuous.
    fn coords(&self, x: [f64; 2]) -> (f64, f64) {
        let n = (1usize << FINEST) as f64;
        let v = self.view;
        (
            (x[1] - v.y0) / (v.y1 - v.y0) * n,
            (x[0] - v.x0) / (v.x1 - v.x0) * n,
        )
    }

    /// The albedo at `x` (inside the lattice's view): the cubic of the
    /// lattice that draws its cell.
    pub fn albedo_at(&self, x: [f64; 2]) -> [f64; 3] {
        let (y, x) = self.coords(x);
        let n = 1usize << FINEST;
        let cell = (y.max(0.0) as usize).min(n - 1) * n + (x.max(0.0) as usize).min(n - 1);
        let level = u32::from(self.serve[cell]);
        let (grid, side) = (&self.grids[level as usize], (1usize << level) + 1);
        let step = 1usize << (FINEST - level);
        let mut out = [0.0f64; 3];
        cubic(
            level,
            y,
            x,
            |(i, j)| Some(grid[(i / step) * side + j / step]),
            &mut out,
        );
        out
    }

    /// The predictive variance at `x`, from the finest lattice's exact
    /// variances (computed with `model` on first use).
    fn variance_at(&self, atlas: &Atlas, x: [f64; 2]) -> Result<f64> {
        let n = 1usize << FINEST;
        let grid = match self.variance.get() {
            Some(g) => g,
            None => {
                // Pixel centres of an (n+1)^2 image half a cell wider than
                // the view fall on the finest lattice's nodes.
                let v = self.view;
                let (hx, hy) = (
                    (v.x1 - v.x0) / n as f64 / 2.0,
                    (v.y1 - v.y0) / n as f64 / 2.0,
                );
                let wide = View {
                    x0: v.x0 - hx,
                    x1: v.x1 + hx,
                    y0: v.y0 - hy,
                    y1: v.y1 + hy,
                };
                let rows = atlas.variance_map(n + 1, n + 1, wide)?;
                // Image rows run from the top: turn them to rows from the bottom.
                let grid: Vec<f64> = (0..=n)
                    .flat_map(|i| rows[(n - i) * (n + 1)..(n - i + 1) * (n + 1)].iter())
                    .map(|&v| f64::from(v))
                    .collect();
                self.variance.get_or_init(|| grid)
            }
        };
        let (y, x) = self.coords(x);
        let mut out = [0.0f64; 3];
        cubic(
            FINEST,
            y,
            x,
            |(i, j)| Some([grid[i * (n + 1) + j]; 3]),
            &mut out,
        );
        Ok(out[0].clamp(0.0, 1.0))
    }

    /// The block of a `width x height` image of `view` whose pixel centres
    /// lie inside the lattice's window: columns and rows (row 0 at the
    /// top); `None` if no pixel does.
    pub(super) fn inside(
        &self,
        width: usize,
        height: usize,
        view: View,
    ) -> Option<(Range<usize>, Range<usize>)> {
        let w = self.view;
        let x = |px: usize| view.pixel_to_latent(px as f64, 0.0, width, height)[0];
        let y = |py: usize| view.pixel_to_latent(0.0, py as f64, width, height)[1];
        let mut cols = (0..width).filter(|&px| (w.x0..=w.x1).contains(&x(px)));
        let mut rows = (0..height).filter(|&py| (w.y0..=w.y1).contains(&y(py)));
        let (c0, c1) = (cols.clone().next()?, cols.next_back()? + 1);
        let (r0, r1) = (rows.clone().next()?, rows.next_back()? + 1);
        Some((c0..c1, r0..r1))
    }

    /// The albedo and variance of the pixels of `block` (columns, rows) of
    /// a `width x height` image of `view`, into `rgb` and `variance` (the
    /// whole image's, row 0 at the top).
    pub(super) fn draw_block(
        &self,
        atlas: &Atlas,
        (width, height, view): (usize, usize, View),
        (cols, rows): (Range<usize>, Range<usize>),
        (rgb, variance): (&mut [[f32; 3]], &mut [f32]),
        progress: &dyn Progress,
    ) -> Result<()> {
        self.variance_at(atlas, [self.view.x0, self.view.y0])?;
        rgb.par_chunks_mut(width)
            .zip(variance.par_chunks_mut(width))
            .enumerate()
            .filter(|(py, _)| rows.contains(py))
            .try_for_each(|(py, (row, var))| {
                if progress.cancelled() {
                    return Ok(());
                }
                for px in cols.clone() {
                    let x = view.pixel_to_latent(px as f64, py as f64, width, height);
                    row[px] = self.albedo_at(x).map(|a| a.max(0.0) as f32);
                    var[px] = self.variance_at(atlas, x)? as f32;
                }
                progress.advance(1);
                Ok::<(), CoreError>(())
            })
    }

    /// Save as JSON at `path`, atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        let mut nodes: Vec<(usize, usize, [f64; 3])> =
            self.nodes.iter().map(|(&(i, j), &v)| (i, j, v)).collect();
        nodes.sort_unstable_by_key(|&(i, j, _)| (i, j));
        let file = LatticeFile {
            format: FORMAT.into(),
            version: VERSION,
            model: self.fingerprint.clone(),
            rule: rule_name(self.rule).into(),
            view: self.view,
            tolerance: self.tolerance,
            finest: FINEST,
            unchecked: self.unchecked,
            serve: self.serve.clone(),
            nodes,
        };
        let text =
            serde_json::to_vec(&file).map_err(|e| CoreError::bad_file(path, e.to_string()))?;
        brdf_atomic::write_atomic(path, |f| std::io::Write::write_all(f, &text))
            .map_err(|e| CoreError::io(path, e))
    }

    /// The lattice saved at `path` for `model`: an error naming the file if
    /// it is not a lattice or not `model`'s.
    pub fn load(path: &Path, atlas: &Atlas) -> Result<AlbedoLattice> {
        let text = brdf_mapguard::read_regular(path).map_err(|e| CoreError::io(path, e))?;
        let bad = |why: String| CoreError::bad_file(path, why);
        let file: LatticeFile = serde_json::from_slice(&text)
            .map_err(|e| bad(format!("not a brdf-atlas lattice ({e})")))?;
        if file.format != FORMAT || file.version != VERSION {
            return Err(bad(format!(
                "format \"{}\" version {}, expected \"{FORMAT}\" version {VERSION}",
                file.format, file.version
            )));
        }
        if file.model != atlas.fingerprint() {
            return Err(bad(format!(
                "built from another fit than {} (run brdf-atlas prepare again)",
                atlas.model().path().display()
            )));
        }
        let n = 1usize << FINEST;
        let rule = match file.rule.as_str() {
            "floor" => BlendRule::Floor,
            "gp" => BlendRule::Gp,
            other => return Err(bad(format!("rule \"{other}\", expected floor or gp"))),
        };
        let levels_ok = file
            .serve
            .iter()
            .all(|&l| (COARSEST + 1..=FINEST).contains(&u32::from(l)));
        if file.finest != FINEST || file.serve.len() != n * n || !levels_ok {
            return Err(bad(format!(
                "its lattice is not {n} x {n} cells drawn from levels {} to {FINEST}",
                COARSEST + 1
            )));
        }
        file.view.check().map_err(|e| bad(e.to_string()))?;
        let nodes: HashMap<Key, [f64; 3]> = file
            .nodes
            .into_iter()
            .filter(|&(i, j, v)| i <= n && j <= n && v.iter().all(|a| a.is_finite()))
            .map(|(i, j, v)| ((i, j), v))
            .collect();
        let lattice = AlbedoLattice {
            view: file.view,
            rule,
            tolerance: file.tolerance,
            fingerprint: file.model,
            serve: file.serve,
            grids: grids_of(&nodes),
            nodes,
            unchecked: file.unchecked,
            variance: OnceLock::new(),
        };
        // Every cell's cubic must find its nodes.
        for cell in 0..n * n {
            let (i, j) = (cell / n, cell % n);
            let level = u32::from(lattice.serve[cell]);
            let mut out = [0.0; 3];
            let ok = cubic(
                level,
                i as f64 + 0.5,
                j as f64 + 0.5,
                |k| lattice.nodes.get(&k).copied(),
                &mut out,
            );
            if !ok {
                return Err(bad(
                    "a cell's nodes are missing (the file is damaged)".into()
                ));
            }
        }
        Ok(lattice)
    }
}

/// The nodes of `nodes` on each level's lattice (NaN where absent).
pub(super) fn grids_of(nodes: &HashMap<Key, [f64; 3]>) -> Vec<Vec<[f64; 3]>> {
    (0..=FINEST)
        .map(|level| {
            if level <= COARSEST {
                return Vec::new();
            }
            let (side, step) = ((1usize << level) + 1, 1usize << (FINEST - level));
            let mut grid = vec![[f64::NAN; 3]; side * side];
            for (&(i, j), &v) in nodes {
                if i % step == 0 && j % step == 0 {
                    grid[(i / step) * side + j / step] = v;
                }
            }
            grid
        })
        .collect()
}

/// The lattice file of the model at `model_path`: `MODEL.lattice` beside it.
pub fn lattice_path(model_path: &Path) -> PathBuf {
    model_path.with_extension("lattice")
}

fn rule_name(rule: BlendRule) -> &'static str {
    match rule {
        BlendRule::Gp => "gp",
        BlendRule::Floor => "floor",
        BlendRule::Plausible => "plausible",
    }
}

/// The four grid indices of the cubic stencil round `t` (in units of the
/// grid's step, within `0..=cells`, `cells >= 3`), kept on the grid, and
/// their Lagrange weights: `sum_q w_q f(i_q)` is the cubic through the four
/// nodes at `t`.
pub fn cubic_stencil(t: f64, cells: usize) -> ([usize; 4], [f64; 4]) {
    let cell = (t.max(0.0).floor() as usize).min(cells - 1);
    let first = cell.saturating_sub(1).min(cells - 3);
    let at: [f64; 4] = std::array::from_fn(|q| (first + q) as f64 - t);
    let weights = std::array::from_fn(|q| {
        (0..4)
            .filter(|&r| r != q)
            .map(|r| -at[r] / (at[q] - at[r]))
            .product()
    });
    (std::array::from_fn(|q| first + q), weights)
}

/// The finest-lattice keys of the cubic of `level` at `(y, x)`.
pub(super) fn stencil_keys(level: u32, y: f64, x: f64) -> impl Iterator<Item = Key> {
    let step = 1usize << (FINEST - level);
    let cells = 1usize << level;
    let (iy, _) = cubic_stencil(y / step as f64, cells);
    let (ix, _) = cubic_stencil(x / step as f64, cells);
    iy.into_iter()
        .flat_map(move |a| ix.into_iter().map(move |b| (a * step, b * step)))
}

/// The tensor cubic of `level`'s lattice at finest coordinates `(y, x)`,
/// added to `out`; false if `value` lacks a node.
pub(super) fn cubic(
    level: u32,
    y: f64,
    x: f64,
    value: impl Fn(Key) -> Option<[f64; 3]>,
    out: &mut [f64; 3],
) -> bool {
    let step = 1usize << (FINEST - level);
    let cells = 1usize << level;
    let (iy, wy) = cubic_stencil(y / step as f64, cells);
    let (ix, wx) = cubic_stencil(x / step as f64, cells);
    for (a, wa) in iy.iter().zip(wy) {
        for (b, wb) in ix.iter().zip(wx) {
            let Some(v) = value((a * step, b * step)) else {
                return false;
            };
            for c in 0..3 {
                out[c] += wa * wb * v[c];
            }
        }
    }
    true
}

/// The error of `got` against `want`, relative to `want`'s largest channel.
pub(super) fn relative_error(got: [f64; 3], want: [f64; 3]) -> f64 {
    let scale = want.iter().fold(1e-12f64, |a, v| a.max(*v));
    (0..3)
        .map(|c| (got[c] - want[c]).abs() / scale)
        .fold(0.0, f64::max)
}
