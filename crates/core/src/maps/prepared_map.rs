//! What a model does with its prepared map ([`crate::maps::lattice`]):
//! build it ([`Atlas::prepare_map`]), read the one saved beside it
//! ([`Atlas::prepared_map`]), and draw maps with it, the pixels in its
//! window from its cubic and the strips outside as without it.

use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

use crate::error::{CoreError, Result};
use crate::maps::Atlas;
use crate::maps::albedo_map::{AlbedoMap, AlbedoMethod, Choice};
use crate::maps::exact_albedos::{AlbedoRequest, Integration};
use crate::maps::lattice::{
    AlbedoLattice, CHUNK, COARSEST, Drawn, FINEST, Key, Loaded, cubic, grids_of, lattice_path,
    relative_error, stencil_keys,
};
use crate::maps::view::View;
use crate::model::blend::pass_weights::floor_of;
use crate::model::blend::plausibility::BlendRule;
use crate::progress::Progress;

impl Atlas {
    /// A fingerprint of the fit (its model file's content, less which file
    /// its store is: a re-fit that builds the same store again keeps it): a
    /// lattice or saved fields of another fit are not used.
    pub fn fingerprint(&self) -> String {
        let mut file = serde_json::to_value(self.model.file()).unwrap_or_default();
        if let Some(store) = file.get_mut("store").and_then(|s| s.as_object_mut()) {
            store.remove("identity");
        }
        let text = serde_json::to_vec(&file).unwrap_or_default();
        format!("{:016x}", xxhash_rust::xxh3::xxh3_64(&text))
    }

    /// Build the prepared map of the default view of `rule`'s material
    /// (the gp or floor rule), refined until each cell's cubic is within
    /// `tolerance` of the exact albedos at the finer lattice's new nodes
    /// ([`crate::maps::lattice`]). Several minutes on two cores for 100 materials at full
    /// resolution (about ten thousand exact albedos). Cancelled through
    /// `progress` it returns [`CoreError::Cancelled`].
    pub fn prepare_map(
        &self,
        rule: BlendRule,
        tolerance: f64,
        progress: &dyn Progress,
    ) -> Result<AlbedoLattice> {
        floor_of(rule)?;
        let view = View::default();
        self.check_map_request(1, 1, view)?;
        if !(tolerance > 0.0 && tolerance.is_finite()) {
            return Err(CoreError::BadQuery(format!(
                "the lattice's tolerance must be positive, not {tolerance}"
            )));
        }
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
                    let albedos = self.exact_albedos(
                        &points,
                        AlbedoRequest::new()
                            .rule(rule)
                            .integration(Integration::Nodes),
                    )?;
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
        self.model.verify()?;
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
    /// its window from its cubic, the rest as [`Atlas::map`] draws them
    /// without it, as `choice` allows (a preview builds nothing). A
    /// lattice of another fit is refused.
    pub(crate) fn map_prepared(
        &self,
        lattice: &AlbedoLattice,
        (width, height, view): (usize, usize, View),
        choice: Choice,
        progress: &dyn Progress,
    ) -> Result<AlbedoMap> {
        if lattice.fingerprint != self.fingerprint() {
            return Err(CoreError::BadQuery(format!(
                "the lattice was built from another fit than {}",
                self.model.path().display()
            )));
        }
        self.check_map_request(width, height, view)?;
        match self.lattice_map(lattice, (width, height, view), choice, progress)? {
            Some(map) => Ok(map),
            None => self.draw(width, height, view, choice, lattice.rule, progress),
        }
    }

    /// [`Atlas::draw_prepared`] as a map; `None` if no pixel lies in the
    /// lattice's window.
    pub(crate) fn lattice_map(
        &self,
        lattice: &AlbedoLattice,
        (width, height, view): (usize, usize, View),
        choice: Choice,
        progress: &dyn Progress,
    ) -> Result<Option<AlbedoMap>> {
        let rule = lattice.rule;
        let Some((rgb, variance, share)) =
            self.draw_prepared(lattice, (width, height, view), (rule, choice), progress)?
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
    /// it, computed as `choice` allows. The albedo, the variance and the
    /// share of pixels from the lattice; `None` if no pixel lies in its
    /// window.
    pub(crate) fn draw_prepared(
        &self,
        lattice: &AlbedoLattice,
        (width, height, view): (usize, usize, View),
        (rule, choice): (BlendRule, Choice),
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
            let map = self.draw(sc.len(), sr.len(), strip, choice, rule, progress)?;
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
        let slot: &Loaded = self.lattice.get_or_init(|| {
            let path = lattice_path(self.model.path());
            let loaded: Loaded = if path.exists() {
                AlbedoLattice::load(&path, self)
                    .map(|l| Some(Arc::new(l)))
                    .map_err(|e| e.to_string())
            } else {
                Ok(None)
            };
            loaded
        });
        match slot {
            Ok(l) => Ok(l.clone()),
            Err(why) => Err(CoreError::BadQuery(why.clone())),
        }
    }
}
