//! The prepared map: exact albedos of the whole default view on an adaptive
//! lattice, built once ([`Model::prepare_map`], `brdf-atlas prepare`) and
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
//! rule over the full reconstruction, [`Model::exact_albedos_with`]) at the
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
use crate::model::Model;
use crate::progress::Progress;
use crate::query::exact::floor_of;
use crate::query::map::{AlbedoMap, AlbedoMethod};
use crate::query::plausibility::BlendRule;
use crate::query::view::View;

/// The largest error of a cell's cubic allowed at the finer lattice's new
/// nodes, relative to the node's largest channel: 0.5%.
pub const LATTICE_TOLERANCE: f64 = 5e-3;
/// The finest lattice has `2^FINEST` cells a side.
const FINEST: u32 = 8;
/// The coarsest lattice checked has `2^COARSEST` cells a side.
const COARSEST: u32 = 4;
/// Exact albedos a pass over the store computes at once (a pass is the
/// unit of progress and of cancellation).
const CHUNK: usize = 256;
/// What the file says it is.
const FORMAT: &str = "brdf-atlas lattice";
const VERSION: u32 = 1;

/// What reading the lattice beside a model gave: the lattice, none, or why
/// it cannot be used.
type Loaded = std::result::Result<Option<Arc<AlbedoLattice>>, String>;

/// A map drawn with the lattice: albedo, variance, and the share of the
/// pixels from the lattice.
type Drawn = (Vec<[f32; 3]>, Vec<f32>, f64);

/// Node indices on the finest lattice: (row from the bottom, column).
type Key = (usize, usize);

/// Exact albedos of a view on an adaptive lattice, and the cubic between them.
pub struct AlbedoLattice {
    view: View,
    rule: BlendRule,
    tolerance: f64,
    fingerprint: String,
    /// The level (cells a side `2^level`) that draws each finest cell,
    /// row-major from the bottom.
    serve: Vec<u8>,
    /// Every exact albedo, by finest-lattice key.
    nodes: HashMap<Key, [f64; 3]>,
    /// The same albedos laid out per level (`grids[level]`: `(2^level + 1)^2`
    /// nodes, row-major from the bottom, NaN where none was computed), for
    /// drawing.
    grids: Vec<Vec<[f64; 3]>>,
    /// The finest cells whose cubic was not checked (cut at the last level).
    unchecked: usize,
    /// Exact variances at every node of the finest lattice, once used.
    variance: OnceLock<Vec<f64>>,
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
    fn variance_at(&self, model: &Model, x: [f64; 2]) -> Result<f64> {
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
                let rows = model.variance_map(n + 1, n + 1, wide)?;
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
    fn inside(
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
    fn draw_block(
        &self,
        model: &Model,
        (width, height, view): (usize, usize, View),
        (cols, rows): (Range<usize>, Range<usize>),
        (rgb, variance): (&mut [[f32; 3]], &mut [f32]),
        progress: &dyn Progress,
    ) -> Result<()> {
        self.variance_at(model, [self.view.x0, self.view.y0])?;
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
                    var[px] = self.variance_at(model, x)? as f32;
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
    pub fn load(path: &Path, model: &Model) -> Result<AlbedoLattice> {
        let text = std::fs::read(path).map_err(|e| CoreError::io(path, e))?;
        let bad = |why: String| CoreError::bad_file(path, why);
        let file: LatticeFile = serde_json::from_slice(&text)
            .map_err(|e| bad(format!("not a brdf-atlas lattice ({e})")))?;
        if file.format != FORMAT || file.version != VERSION {
            return Err(bad(format!(
                "format \"{}\" version {}, expected \"{FORMAT}\" version {VERSION}",
                file.format, file.version
            )));
        }
        if file.model != model.fingerprint() {
            return Err(bad(format!(
                "built from another fit than {} (run brdf-atlas prepare again)",
                model.path().display()
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
fn grids_of(nodes: &HashMap<Key, [f64; 3]>) -> Vec<Vec<[f64; 3]>> {
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

/// The four lattice indices of a cubic stencil round `t` (in units of the
/// level's step, within `0..=cells`), and their Lagrange weights.
fn stencil(t: f64, cells: usize) -> ([usize; 4], [f64; 4]) {
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
fn stencil_keys(level: u32, y: f64, x: f64) -> impl Iterator<Item = Key> {
    let step = 1usize << (FINEST - level);
    let cells = 1usize << level;
    let (iy, _) = stencil(y / step as f64, cells);
    let (ix, _) = stencil(x / step as f64, cells);
    iy.into_iter()
        .flat_map(move |a| ix.into_iter().map(move |b| (a * step, b * step)))
}

/// The tensor cubic of `level`'s lattice at finest coordinates `(y, x)`,
/// added to `out`; false if `value` lacks a node.
fn cubic(
    level: u32,
    y: f64,
    x: f64,
    value: impl Fn(Key) -> Option<[f64; 3]>,
    out: &mut [f64; 3],
) -> bool {
    let step = 1usize << (FINEST - level);
    let cells = 1usize << level;
    let (iy, wy) = stencil(y / step as f64, cells);
    let (ix, wx) = stencil(x / step as f64, cells);
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
fn relative_error(got: [f64; 3], want: [f64; 3]) -> f64 {
    let scale = want.iter().fold(1e-12f64, |a, v| a.max(*v));
    (0..3)
        .map(|c| (got[c] - want[c]).abs() / scale)
        .fold(0.0, f64::max)
}

impl Model {
    /// A fingerprint of the fit (its model file's content): a lattice built
    /// from another fit is not used.
    pub fn fingerprint(&self) -> String {
        let text = serde_json::to_vec(self.file()).unwrap_or_default();
        format!("{:016x}", xxhash_rust::xxh3::xxh3_64(&text))
    }

    /// Build the prepared map of the default view of `rule`'s material
    /// (the gp or floor rule), refined until each cell's cubic is within
    /// `tolerance` of the exact albedos at the finer lattice's new nodes
    /// (module docs). Several minutes on two cores for 100 materials at full
    /// resolution (about ten thousand exact albedos). Cancelled through
    /// `progress` it returns [`CoreError::Cancelled`].
    pub fn prepare_map(
        &self,
        rule: BlendRule,
        tolerance: f64,
        progress: &dyn Progress,
    ) -> Result<AlbedoLattice> {
        floor_of(rule)?;
        if self.q() != 2 {
            return Err(CoreError::BadQuery(format!(
                "a map needs a 2-D latent space, this model has q = {}",
                self.q()
            )));
        }
        if !(tolerance > 0.0 && tolerance.is_finite()) {
            return Err(CoreError::BadQuery(format!(
                "the lattice's tolerance must be positive, not {tolerance}"
            )));
        }
        let view = View::default();
        let n = 1usize << FINEST;
        let mut nodes: HashMap<Key, [f64; 3]> = HashMap::new();
        let point = |(i, j): Key| {
            [
                view.x0 + (view.x1 - view.x0) * j as f64 / n as f64,
                view.y0 + (view.y1 - view.y0) * i as f64 / n as f64,
            ]
        };
        let fill =
            |nodes: &mut HashMap<Key, [f64; 3]>, keys: Vec<Key>, label: &str| -> Result<()> {
                let mut missing: Vec<Key> = keys
                    .into_iter()
                    .filter(|k| !nodes.contains_key(k))
                    .collect();
                missing.sort_unstable();
                missing.dedup();
                progress.start(label, missing.len() as u64);
                for chunk in missing.chunks(CHUNK) {
                    if progress.cancelled() {
                        return Err(CoreError::Cancelled);
                    }
                    let points: Vec<[f64; 2]> = chunk.iter().map(|&k| point(k)).collect();
                    let albedos = self.exact_albedos_with(&points, rule)?;
                    nodes.extend(chunk.iter().copied().zip(albedos));
                    progress.advance(chunk.len() as u64);
                }
                progress.finish();
                Ok(())
            };
        let mut serve = vec![FINEST as u8; n * n];
        let cells0 = 1usize << COARSEST;
        let mut open: Vec<Key> = (0..cells0 * cells0)
            .map(|k| (k / cells0, k % cells0))
            .collect();
        for level in COARSEST..FINEST {
            let step = 1usize << (FINEST - level);
            let half = step / 2;
            // The finer lattice's new nodes in a cell.
            let news = |&(ci, cj): &Key| {
                (0..=2)
                    .flat_map(move |a| {
                        (0..=2).map(move |b| (ci * step + a * half, cj * step + b * half))
                    })
                    .filter(move |&(a, b)| a % step != 0 || b % step != 0)
            };
            let mut keys = Vec::new();
            for cell in &open {
                for (a, b) in news(cell) {
                    keys.push((a, b));
                    keys.extend(stencil_keys(level, a as f64, b as f64));
                }
            }
            let label = format!("lattice, cells of 1/{} of the view", 1usize << level);
            fill(&mut nodes, keys, &label)?;
            let mut next = Vec::new();
            for cell in &open {
                let worst = news(cell)
                    .map(|k| {
                        let mut got = [0.0; 3];
                        cubic(
                            level,
                            k.0 as f64,
                            k.1 as f64,
                            |q| nodes.get(&q).copied(),
                            &mut got,
                        );
                        relative_error(got, nodes[&k])
                    })
                    .fold(0.0, f64::max);
                let (ci, cj) = *cell;
                if worst <= tolerance {
                    for a in ci * step..(ci + 1) * step {
                        serve[a * n + cj * step..a * n + (cj + 1) * step].fill(level as u8 + 1);
                    }
                } else {
                    next.extend([
                        (2 * ci, 2 * cj),
                        (2 * ci, 2 * cj + 1),
                        (2 * ci + 1, 2 * cj),
                        (2 * ci + 1, 2 * cj + 1),
                    ]);
                }
            }
            open = next;
        }
        // Every cell's drawing lattice needs its stencils' nodes.
        let keys: Vec<Key> = (0..n * n)
            .flat_map(|cell| {
                let (i, j) = (cell / n, cell % n);
                stencil_keys(u32::from(serve[cell]), i as f64 + 0.5, j as f64 + 0.5)
            })
            .collect();
        fill(&mut nodes, keys, "lattice, the cells' last nodes")?;
        self.verify()?;
        Ok(AlbedoLattice {
            view,
            rule,
            tolerance,
            fingerprint: self.fingerprint(),
            serve,
            grids: grids_of(&nodes),
            nodes,
            unchecked: open.len(),
            variance: OnceLock::new(),
        })
    }

    /// A `width x height` map of `view` of `lattice`'s material, drawn with
    /// `lattice` whether or not it is saved beside the model: the pixels in
    /// its window from its cubic, the rest as [`Model::albedo_map_with`]
    /// draws them without it. A lattice of another fit is refused.
    pub fn albedo_map_prepared(
        &self,
        lattice: &AlbedoLattice,
        width: usize,
        height: usize,
        view: View,
        progress: &dyn Progress,
    ) -> Result<AlbedoMap> {
        if lattice.fingerprint != self.fingerprint() {
            return Err(CoreError::BadQuery(format!(
                "the lattice was built from another fit than {}",
                self.path().display()
            )));
        }
        self.check_map_request(width, height, view)?;
        match self.lattice_map(lattice, (width, height, view), progress)? {
            Some(map) => Ok(map),
            None => self.albedo_map_with(width, height, view, None, lattice.rule, progress),
        }
    }

    /// [`Model::draw_prepared`] as a map; `None` if no pixel lies in the
    /// lattice's window.
    pub(crate) fn lattice_map(
        &self,
        lattice: &AlbedoLattice,
        (width, height, view): (usize, usize, View),
        progress: &dyn Progress,
    ) -> Result<Option<AlbedoMap>> {
        let rule = lattice.rule;
        let Some((rgb, variance, share)) =
            self.draw_prepared(lattice, (width, height, view), rule, progress)?
        else {
            return Ok(None);
        };
        let method = AlbedoMethod::Lattice {
            nodes: lattice.nodes(),
            tolerance: lattice.tolerance,
            share,
        };
        self.finish_map((width, height, view, rule), rgb, variance, method, progress)
            .map(Some)
    }

    /// A `width x height` map of `view` drawn with the prepared map
    /// `lattice`: the pixels whose centres lie in its window from its
    /// cubic, the strips outside it (if any) as maps of their own without
    /// it. The albedo, the variance and the share of pixels from the
    /// lattice; `None` if no pixel lies in its window.
    pub(crate) fn draw_prepared(
        &self,
        lattice: &AlbedoLattice,
        (width, height, view): (usize, usize, View),
        rule: BlendRule,
        progress: &dyn Progress,
    ) -> Result<Option<Drawn>> {
        let Some((cols, rows)) = lattice.inside(width, height, view) else {
            return Ok(None);
        };
        let mut rgb = vec![[0.0f32; 3]; width * height];
        let mut variance = vec![0.0f32; width * height];
        progress.start("map", rows.len() as u64);
        lattice.draw_block(
            self,
            (width, height, view),
            (cols.clone(), rows.clone()),
            (&mut rgb, &mut variance),
            progress,
        )?;
        progress.finish();
        // The strips outside the window: left and right of full height,
        // above and below between them.
        let strips = [
            (0..cols.start, 0..height),
            (cols.end..width, 0..height),
            (cols.clone(), 0..rows.start),
            (cols.clone(), rows.end..height),
        ];
        for (sc, sr) in strips {
            if sc.is_empty() || sr.is_empty() {
                continue;
            }
            let (dx, dy) = (
                (view.x1 - view.x0) / width as f64,
                (view.y1 - view.y0) / height as f64,
            );
            let strip = View {
                x0: view.x0 + dx * sc.start as f64,
                x1: view.x0 + dx * sc.end as f64,
                y0: view.y1 - dy * sr.end as f64,
                y1: view.y1 - dy * sr.start as f64,
            };
            let map = self.albedo_map_with(sc.len(), sr.len(), strip, None, rule, progress)?;
            for (k, py) in sr.clone().enumerate() {
                let (from, to) = (
                    k * sc.len()..(k + 1) * sc.len(),
                    py * width + sc.start..py * width + sc.end,
                );
                rgb[to.clone()].copy_from_slice(&map.rgb[from.clone()]);
                variance[to].copy_from_slice(&map.variance[from]);
            }
        }
        let share = (cols.len() * rows.len()) as f64 / (width * height) as f64;
        Ok(Some((rgb, variance, share)))
    }

    /// The prepared map saved beside the model ([`lattice_path`]), read on
    /// first use: `Ok(None)` when there is none, an error naming the file
    /// when it cannot be used (damaged, or built from another fit).
    pub fn prepared_map(&self) -> Result<Option<Arc<AlbedoLattice>>> {
        let slot = self.map_basis().lattice.get_or_init(|| {
            let path = lattice_path(self.path());
            let loaded: Loaded = if path.exists() {
                AlbedoLattice::load(&path, self)
                    .map(|l| Some(Arc::new(l)))
                    .map_err(|e| e.to_string())
            } else {
                Ok(None)
            };
            Box::new(loaded)
        });
        let slot: &Loaded = slot
            .downcast_ref()
            .expect("the model's lattice slot holds Loaded");
        match slot {
            Ok(l) => Ok(l.clone()),
            Err(why) => Err(CoreError::BadQuery(why.clone())),
        }
    }
}
