//! Albedo fields saved beside the model (`MODEL.fields`), so that the
//! next process that draws a map of the model (the CLI, the C library,
//! Python, the BRDF Explorer panel) starts from the fields an earlier one
//! built instead of building them again.
//!
//! The file holds what the atlas's field cache holds: for each domain, rule
//! and node rule, the field built ([`AlbedoField`]: its patches' grids and
//! node values, and the variance's) or the budget at which it was given up
//! (so that a later map does not plan it again). `brdf-atlas fit` writes
//! the default view's and [`View::wide`]'s ([`Atlas::prepare_fields`]);
//! `brdf-atlas map` adds those it builds ([`Atlas::save_fields`]). It is read on first use
//! ([`Atlas::saved_fields`]); a file from another fit, or one that is not
//! whole, is left aside (the map builds what it needs, and the next save
//! replaces it).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::maps::albedo_field::{AlbedoField, Cached};
use crate::maps::field_check::FieldCheck;
use crate::maps::patches::Patch;
use crate::maps::view::View;
use crate::maps::{AlbedoMethod, Atlas};
use crate::model::blend::plausibility::BlendRule;
use crate::progress::Progress;

const FORMAT: &str = "brdf-atlas fields";
/// 1: sampled fields' nodes from the per-pixel rule's kind of rule
/// ([`crate::FIELD_SAMPLES`]), exact ones from the nodes' rule
/// ([`crate::NODE_PHI_D_STEP`]), planned on the
/// [`DEFAULT_SAMPLES`](crate::DEFAULT_SAMPLES)-sample rule. A sampled
/// field may carry its check ([`FieldCheck`]); files written before
/// fields were checked have none, and are read as they are.
const VERSION: u32 = 1;
/// The most nodes the file keeps over all its fields (the newest first): a
/// sampled field of the default view of 100 materials has about 50,000,
/// some 3 MB of the file.
const MAX_SAVED_NODES: usize = 400_000;

/// What reading the fields beside a model gave: its entries, or why they
/// cannot be used (what the file's error says after its name).
pub(crate) type Loaded = std::result::Result<Vec<Arc<Cached>>, String>;

/// The atlas's slot for the saved entries: unread, or what was read (or
/// last written).
pub(crate) type Slot = std::sync::Mutex<Option<Loaded>>;

/// The side, in pixels, of the maps whose fields `brdf-atlas fit` saves
/// ([`fit_field_views`]): their budget is a map of this size's.
pub const FIT_FIELD_SIZE: usize = 1024;

/// The views, named, whose maps' fields `brdf-atlas fit` (and Python's
/// `fit`) builds and saves beside the model: the default view, and
/// [`View::wide`], whose domain holds the map panel's windows (twice as
/// wide as high, so reaching outside the default view).
pub fn fit_field_views() -> [(&'static str, View); 2] {
    [
        ("the default view", View::default()),
        ("[-3, 3]^2", View::wide()),
    ]
}

/// The fields file of the model at `model_path`: `MODEL.fields` beside it.
pub fn fields_path(model_path: &Path) -> PathBuf {
    model_path.with_extension("fields")
}

#[derive(Serialize, Deserialize)]
struct FieldsFile {
    format: String,
    version: u32,
    /// The fit's fingerprint ([`Atlas::fingerprint`]).
    model: String,
    entries: Vec<Entry>,
}

#[derive(Serialize, Deserialize)]
struct Entry {
    domain: View,
    /// "floor" or "gp".
    rule: String,
    /// A sampled field's sample count; absent for the nodes' rule.
    samples: Option<usize>,
    /// The budget the field was built or given up at.
    budget: usize,
    field: Option<SavedField>,
}

#[derive(Serialize, Deserialize)]
struct SavedField {
    nodes: usize,
    /// A sampled field's check ([`crate::FieldCheck`]); absent for an
    /// exact field, and in files written before fields were checked.
    #[serde(default)]
    check: Option<FieldCheck>,
    albedo: Vec<SavedPatch>,
    variance: Vec<SavedPatch>,
}

#[derive(Serialize, Deserialize)]
struct SavedPatch {
    rect: View,
    xs: Vec<f64>,
    ys: Vec<f64>,
    values: Vec<f64>,
    estimate: f64,
}

impl SavedPatch {
    fn of(p: &Patch) -> SavedPatch {
        SavedPatch {
            rect: p.rect,
            xs: p.xs.clone(),
            ys: p.ys.clone(),
            values: p.values.clone(),
            estimate: p.estimate,
        }
    }

    /// The patch, if whole: a valid rectangle, ascending finite grids of at
    /// least two points inside it, `channels` finite values a node.
    fn patch(self, domain: View, channels: usize) -> std::result::Result<Patch, String> {
        let rect = self.rect;
        rect.check().map_err(|e| e.to_string())?;
        let grid_ok = |g: &[f64], lo: f64, hi: f64| {
            g.len() >= 2
                && g.iter().all(|v| v.is_finite() && lo <= *v && *v <= hi)
                && g.windows(2).all(|w| w[0] < w[1])
        };
        if !domain.holds(rect)
            || !grid_ok(&self.xs, rect.x0, rect.x1)
            || !grid_ok(&self.ys, rect.y0, rect.y1)
            || self.values.len() != self.xs.len() * self.ys.len() * channels
            || !self.values.iter().all(|v| v.is_finite())
            || !self.estimate.is_finite()
        {
            return Err(format!("a patch of the field of {domain:?} is damaged"));
        }
        Ok(Patch {
            rect,
            xs: self.xs,
            ys: self.ys,
            values: self.values,
            estimate: self.estimate,
        })
    }
}

/// Patches that cover `domain`: inside it (checked per patch), with areas
/// adding up to its own.
fn covers(domain: View, patches: &[Patch]) -> bool {
    let sum: f64 = patches.iter().map(|p| p.rect.area()).sum();
    !patches.is_empty() && (sum - domain.area()).abs() <= 1e-9 * domain.area()
}

fn rule_name(floor: bool) -> &'static str {
    if floor { "floor" } else { "gp" }
}

impl Entry {
    fn of(c: &Cached) -> Entry {
        Entry {
            domain: c.domain,
            rule: rule_name(c.floor).into(),
            samples: c.samples,
            budget: c.budget,
            field: c.field.as_ref().map(|f| SavedField {
                nodes: f.nodes(),
                // A check that is not a number would not read back.
                check: f
                    .check()
                    .filter(|c| c.worst.is_finite() && c.mean.is_finite()),
                albedo: f.albedo_patches().iter().map(SavedPatch::of).collect(),
                variance: f.variance_patches().iter().map(SavedPatch::of).collect(),
            }),
        }
    }

    fn cached(self) -> std::result::Result<Cached, String> {
        let domain = self.domain;
        domain.check().map_err(|e| e.to_string())?;
        let floor = match self.rule.as_str() {
            "floor" => true,
            "gp" => false,
            other => return Err(format!("rule \"{other}\", expected floor or gp")),
        };
        if self.samples == Some(0) {
            return Err("a sampled field of 0 samples".into());
        }
        let field = match self.field {
            None => None,
            Some(f) => {
                let patches = |saved: Vec<SavedPatch>, channels| {
                    saved
                        .into_iter()
                        .map(|p| p.patch(domain, channels))
                        .collect::<std::result::Result<Vec<Patch>, String>>()
                };
                let (albedo, variance) = (patches(f.albedo, 3)?, patches(f.variance, 1)?);
                if !covers(domain, &albedo) || !covers(domain, &variance) {
                    return Err(format!("the field of {domain:?} does not cover it"));
                }
                Some(Arc::new(AlbedoField::from_parts(
                    domain, albedo, variance, f.nodes, f.check,
                )))
            }
        };
        Ok(Cached {
            domain,
            floor,
            samples: self.samples,
            budget: self.budget,
            field,
        })
    }
}

impl Atlas {
    /// The fields saved beside the model ([`fields_path`]), read on first
    /// use: how many entries (fields, and domains given up) it holds, `0`
    /// when there is no file, [`CoreError::BadFile`] naming the file when it
    /// cannot be used (unreadable, damaged, or written for another fit);
    /// maps then build what they need, as without it.
    pub fn saved_fields(&self) -> Result<usize> {
        match self.loaded_fields() {
            Ok(entries) => Ok(entries.len()),
            Err(why) => Err(CoreError::bad_file(fields_path(self.model.path()), why)),
        }
    }

    /// The saved entries: read on first use, what this atlas last saved
    /// after that.
    pub(crate) fn loaded_fields(&self) -> Loaded {
        let mut slot = self.saved.lock().unwrap_or_else(|e| e.into_inner());
        slot.get_or_insert_with(|| {
            let path = fields_path(self.model.path());
            if !path.exists() {
                return Ok(Vec::new());
            }
            self.read_fields(&path).map_err(|e| match e {
                CoreError::BadFile { why, .. } => why,
                CoreError::Io { source, .. } => source.to_string(),
                e => e.to_string(),
            })
        })
        .clone()
    }

    fn read_fields(&self, path: &Path) -> Result<Vec<Arc<Cached>>> {
        let text = brdf_mapguard::read_regular(path).map_err(|e| CoreError::io(path, e))?;
        let bad = |why: String| CoreError::bad_file(path, why);
        let file: FieldsFile = serde_json::from_slice(&text)
            .map_err(|e| bad(format!("not a brdf-atlas fields file ({e})")))?;
        if file.format != FORMAT || file.version != VERSION {
            return Err(bad(format!(
                "format \"{}\" version {}, expected \"{FORMAT}\" version {VERSION}",
                file.format, file.version
            )));
        }
        if file.model != self.fingerprint() {
            return Err(bad(format!(
                "written for another fit than {} (the next map saved replaces it)",
                self.model.path().display()
            )));
        }
        file.entries
            .into_iter()
            .map(|e| e.cached().map(Arc::new).map_err(bad))
            .collect()
    }

    /// Save the fields the atlas holds (built in this process, or read from
    /// the file, newest first, at most some 400,000 nodes in all) beside
    /// the model ([`fields_path`]), atomically; `Ok(None)` when the file
    /// already holds them all. A file that could not be used is replaced.
    pub fn save_fields(&self) -> Result<Option<PathBuf>> {
        let saved = self.loaded_fields().unwrap_or_default();
        let fresh = self.fields.all();
        let new = |c: &Arc<Cached>| !saved.iter().any(|s| Arc::ptr_eq(s, c));
        if !fresh.iter().any(new) {
            return Ok(None);
        }
        // Newest first: this process's (newest last in the cache), then the
        // file's, each domain's entry once.
        let mut entries: Vec<&Arc<Cached>> = Vec::new();
        let mut nodes = 0;
        for c in fresh.iter().rev().chain(&saved) {
            if entries.iter().any(|e| e.same(c)) {
                continue;
            }
            let n = c.field.as_ref().map_or(0, |f| f.nodes());
            if nodes + n > MAX_SAVED_NODES {
                continue;
            }
            nodes += n;
            entries.push(c);
        }
        let file = FieldsFile {
            format: FORMAT.into(),
            version: VERSION,
            model: self.fingerprint(),
            entries: entries.iter().map(|c| Entry::of(c)).collect(),
        };
        let path = fields_path(self.model.path());
        let text =
            serde_json::to_vec(&file).map_err(|e| CoreError::bad_file(&path, e.to_string()))?;
        brdf_atomic::write_atomic(&path, |f| std::io::Write::write_all(f, &text))
            .map_err(|e| CoreError::write(&path, e))?;
        let written = entries.into_iter().cloned().collect();
        *self.saved.lock().unwrap_or_else(|e| e.into_inner()) = Some(Ok(written));
        Ok(Some(path))
    }

    /// Build what a `width x height` map of `view` of `rule`'s material
    /// draws from (the exact field where it fits its budget, else the
    /// sampled one, [`Atlas::map`]) and save it beside the model
    /// ([`Atlas::save_fields`]), so that such maps, in any process, only
    /// evaluate it. How such a map is then drawn (`None`: every pixel
    /// integrated, no field fits its budget), and the file written (`None`
    /// when it held the field already).
    pub fn prepare_fields(
        &self,
        (width, height, view): (usize, usize, View),
        rule: BlendRule,
        progress: &dyn Progress,
    ) -> Result<(Option<AlbedoMethod>, Option<PathBuf>)> {
        let method = self.build_map_field((width, height, view), rule, progress)?;
        Ok((method, self.save_fields()?))
    }

    /// What `brdf-atlas fit` does after the fit: [`Atlas::prepare_fields`]
    /// of each of [`fit_field_views`] at [`FIT_FIELD_SIZE`] pixels a side,
    /// of the default material, saved once. How each view's map is then
    /// drawn, in that order, and the file written.
    pub fn prepare_fit_fields(
        &self,
        progress: &dyn Progress,
    ) -> Result<(Vec<Option<AlbedoMethod>>, Option<PathBuf>)> {
        let size = FIT_FIELD_SIZE;
        let methods = fit_field_views()
            .into_iter()
            .map(|(_, view)| {
                self.build_map_field((size, size, view), BlendRule::default(), progress)
            })
            .collect::<Result<Vec<_>>>()?;
        Ok((methods, self.save_fields()?))
    }

    /// The field a `width x height` map of `view` draws from, built and
    /// kept; how the map is drawn from it (`None`: per pixel).
    fn build_map_field(
        &self,
        (width, height, view): (usize, usize, View),
        rule: BlendRule,
        progress: &dyn Progress,
    ) -> Result<Option<AlbedoMethod>> {
        self.check_map_request(width, height, view)?;
        Ok(self
            .map_field(view, width * height, rule, progress)?
            .map(|(field, sampled)| AlbedoMethod::of_field(&field, sampled)))
    }
}
