//! The albedo field: exact albedos at a few latent points, a polynomial
//! between them.
//!
//! The albedo at a latent point `x` is a smooth function of `x`: every
//! reconstructed bin is `t_b(x) = mean_b + z_b . K^-1 k(x)`, a sum of
//! Gaussians of the kernel's length scale, and the albedo is a weighted sum
//! of the inverse transform of those bins. So instead of integrating every
//! pixel with a cheap rule (whose error does not shrink with the pixel
//! count), the map
//!
//! 1. picks a domain round the view (below);
//! 2. computes the **exact** albedo — the dense rule
//!    ([`Model::albedo_rule`]) over the full reconstruction — at the
//!    nodes of a tensor Chebyshev–Lobatto grid on the domain, all nodes of a
//!    grid in one pass over the store ([`Atlas::exact_albedos`]: one matrix
//!    product a block of rows, so the store is read once however many nodes);
//! 3. refines the grid (3, 5, 9, 17 points a side; each grid holds the
//!    previous one) until the interpolant of the coarser grid, compared with
//!    the exact values at the finer grid's new nodes, is off by at most
//!    [`ALBEDO_TOLERANCE`] of the node's largest channel, and keeps the finer
//!    grid's interpolant (Chebyshev interpolation of a smooth function
//!    converges geometrically, so its error is well below the estimate);
//! 4. evaluates that polynomial at every pixel: two small products a pixel
//!    row (barycentric Lagrange weights of the grid, per axis).
//!
//! A patch more than [`CUT_RATIO`] tolerances off after a refinement is cut
//! in four (down to [`MAX_DEPTH`] cuts, where the finest grid is kept and its
//! estimate reported). The predictive variance `1 - k^T K^-1 k` gets the
//! same with an absolute tolerance ([`VARIANCE_TOLERANCE`]) and its own,
//! cheap (`O(N^2)`), exact nodes.
//!
//! **Cost.** A node reads the rows of the nodes' rule (every 8th phi_d bin
//! of the dense rule: 0.43 million rows of 100 materials for MERL dims):
//! about 4 ms on two cores, when many nodes share a pass. Where
//! the albedo has detail at a finer scale than the domain (under a log
//! transform with the default kernel, blends of dissimilar neighbours clamp
//! and swing; on the 100-material model a patch a quarter of the default
//! view wide still misses the tolerance at 17 x 17 nodes) a field needs
//! thousands of nodes. So a map gives its field a budget
//! ([`Atlas::field_budget`]): as many nodes as cost what integrating every
//! pixel with the default quadrature would; a field that would need more is
//! abandoned and the map integrates every pixel. Before any exact node, the
//! field is planned ([`Atlas::plan_field`]): the same refinement on node
//! values from the per-pixel rule's few hundred rows, which have detail at
//! about the same scale; a plan past four times the budget gives the field
//! up at the cost of at most that many cheap nodes (a judgement, not a bound:
//! the plan's values come from another rule; measured to agree with the
//! exact refinement in docs/performance.md). Zoomed-in views, whose
//! albedo is nearly linear across them, get fields of a few dozen nodes.
//!
//! **Domains.** A view's domain is, per axis, the smallest interval of a
//! fixed lattice that holds the view: intervals of length `L 2^-k` (`L` the
//! default view's side) starting at multiples of half their length from the
//! default view's corner. So the domain is at most four times the view, a
//! zoomed view gets a small, nearly linear domain that needs few nodes, and
//! the domain depends on the view only. The model keeps the last fields it
//! built ([`FIELD_CACHE`]), and those saved beside it
//! ([`crate::maps::saved_fields`]), so a viewer that pans and zooms inside
//! one domain pays for its nodes once; a view inside the domain of a field
//! held is drawn from it (the exact field of the smallest such domain,
//! else the sampled one) instead of a field of its own domain
//! ([`Atlas::map_field`]). So a map depends on the fields held as well as
//! on (model, view, size), within the fields' accuracy: the same fields
//! give the same bits whatever the thread count.

use std::sync::Arc;

use crate::dense::product::matmul;
use crate::error::{CoreError, Result};
use crate::maps::Atlas;
use crate::maps::exact_albedos::RuleRows;
use crate::maps::field_check::FieldCheck;
use crate::maps::patches::{Patch, eval_point, find, grid_points, refine};
use crate::maps::view::View;
use crate::model::blend::pass_weights::floor_of;
use crate::model::blend::plausibility::BlendRule;
use crate::progress::{NoProgress, Progress};
use crate::simd::dot;

/// The largest error of the albedo interpolant allowed at a refinement's new
/// nodes, relative to the node's largest channel: 0.25%.
pub const ALBEDO_TOLERANCE: f64 = 2.5e-3;
/// The largest absolute error of the variance interpolant allowed at a
/// refinement's new nodes.
pub const VARIANCE_TOLERANCE: f64 = 2e-3;
/// Points a side of the successive grids of a patch (each holds the
/// previous). The 3 x 3 grid's nodes are among the 5 x 5's, so it costs
/// nothing where the patch goes on to 9 x 9; where its quadratic already
/// meets the tolerance at the 5 x 5 grid's new nodes (a deep zoom, nearly
/// linear across), the patch stops at 25 nodes instead of 81.
const LEVELS: [usize; 4] = [3, 5, 9, 17];
/// The variance's exact nodes are cheap (`O(N^2)` each): it may go finer.
const VARIANCE_LEVELS: [usize; 6] = [5, 9, 17, 33, 65, 129];
/// The smallest node budget of a map's field ([`Atlas::field_budget`]):
/// a 9 x 9 grid, enough for a view much smaller than the detail of its
/// albedo.
pub const MIN_NODES: usize = 81;
pub use crate::maps::patches::{CUT_RATIO, MAX_DEPTH};
pub use crate::maps::view::domain_of;
/// How many times its budget a field's plan ([`Atlas::plan_field`]) may
/// take in nodes before the field is given up without exact nodes. The
/// plan's values come from a coarser rule, whose albedo has more detail
/// than the exact one's (on a 12-material synthetic model, a plan of 613
/// nodes where the exact refinement took 289), and a plan's node reads a
/// few hundred rows against an exact node's millions, so the plan is given
/// room: at four times the budget it still costs less than one exact node.
pub const PLAN_FACTOR: usize = 4;
/// Samples of the rule a map's sampled field ([`Atlas::sampled_field`])
/// integrates at its nodes, where exact nodes would cost too much: on the
/// 100 NBRDF-derived materials a 1024 x 1024 map of the default view so
/// drawn is 5.3% off the dense rule at worst and 0.66% on average at 64
/// random points, where integrating every pixel with the default 256
/// samples is 7.9% and 0.92% off and takes three times as long
/// (docs/performance.md, "Sampled fields").
pub const FIELD_SAMPLES: usize = 1024;
/// Nodes of a sampled field integrated in one pass over its rule's rows.
const SAMPLED_CHUNK: usize = 1024;
/// Fields a model keeps for later maps.
pub const FIELD_CACHE: usize = 8;

/// The albedo and variance of a domain as piecewise tensor polynomials.
#[derive(Debug, Clone)]
pub struct AlbedoField {
    domain: View,
    albedo: Vec<Patch>,
    variance: Vec<Patch>,
    nodes: usize,
    /// A sampled field's error against exact albedos, measured when built.
    check: Option<FieldCheck>,
}

impl AlbedoField {
    /// The rectangle covered.
    pub fn domain(&self) -> View {
        self.domain
    }

    /// The largest albedo error estimate of its patches (relative to a
    /// node's largest channel): at most [`ALBEDO_TOLERANCE`] unless the
    /// finest grid of the deepest cut did not get there.
    pub fn estimate(&self) -> f64 {
        self.albedo.iter().map(|p| p.estimate).fold(0.0, f64::max)
    }

    /// The largest variance error estimate of its patches (absolute).
    pub fn variance_estimate(&self) -> f64 {
        self.variance.iter().map(|p| p.estimate).fold(0.0, f64::max)
    }

    /// A sampled field's error against exact albedos at a few points of
    /// its domain, measured when it was built ([`FieldCheck`]); `None` for
    /// an exact field (whose estimate says its error), or one saved before
    /// fields were checked.
    pub fn check(&self) -> Option<FieldCheck> {
        self.check
    }

    /// Exact albedos the field was built from.
    pub fn nodes(&self) -> usize {
        self.nodes
    }

    /// Patches of the albedo polynomial.
    pub fn patches(&self) -> usize {
        self.albedo.len()
    }

    /// Albedo (RGB, negative values clamped to 0) and variance at `x`
    /// (inside the domain).
    pub fn at(&self, x: [f64; 2]) -> ([f64; 3], f64) {
        let a = eval_point(find(&self.albedo, x), x, 3);
        let v = eval_point(find(&self.variance, x), x, 1);
        (
            [a[0].max(0.0), a[1].max(0.0), a[2].max(0.0)],
            v[0].clamp(0.0, 1.0),
        )
    }
}

/// What [`Atlas::field`] builds: the field of a view's domain within a
/// node budget, of the default rule's material ([`BlendRule::default`])
/// unless set, without progress reports unless given.
///
/// ```
/// use brdf_atlas_core::{BlendRule, FieldRequest, View};
///
/// let request = FieldRequest::new(View::default(), 4000).rule(BlendRule::Gp);
/// # let _ = request;
/// ```
#[derive(Clone, Copy)]
pub struct FieldRequest<'a> {
    /// The view whose domain ([`domain_of`]) the field covers.
    pub view: View,
    /// The most exact nodes the field may take.
    pub budget: usize,
    /// The material: the GP's blend or the soft floor's.
    pub rule: BlendRule,
    /// Told of the refinement, and asked whether to stop.
    pub progress: &'a dyn Progress,
}

impl<'a> FieldRequest<'a> {
    /// The field of `view`'s domain within `budget` nodes, of the default
    /// rule's material.
    pub fn new(view: View, budget: usize) -> FieldRequest<'a> {
        FieldRequest {
            view,
            budget,
            rule: BlendRule::default(),
            progress: &NoProgress,
        }
    }

    /// The material.
    pub fn rule(self, rule: BlendRule) -> FieldRequest<'a> {
        FieldRequest { rule, ..self }
    }

    /// Told of the refinement, and asked whether to stop.
    pub fn progress(self, progress: &'a dyn Progress) -> FieldRequest<'a> {
        FieldRequest { progress, ..self }
    }
}

impl Atlas {
    /// The exact predictive variance `1 - k^T K^-1 k` at each point.
    fn exact_variances(&self, points: &[[f64; 2]]) -> Vec<f64> {
        let (latent, kernel) = (self.model.latent(), self.model.file().kernel);
        let n = latent.nrows();
        let inv = self.model.k_inverse();
        let mut out = vec![0.0f32; points.len()];
        for (chunk, o) in points.chunks(256).zip(out.chunks_mut(256)) {
            let kx: Vec<f64> = chunk
                .iter()
                .flat_map(|p| {
                    (0..n).map(move |i| kernel.eval(&[latent[(i, 0)], latent[(i, 1)]], p))
                })
                .collect();
            variances(&inv, &kx, n, o);
        }
        // Computed in f64 and rounded to f32 only by `variances`' output.
        out.into_iter().map(f64::from).collect()
    }

    /// The field of `request.view`'s domain ([`domain_of`]) for the
    /// material `request.rule` forms (the GP's blend or the soft floor's;
    /// the plausible rule has no map), from the atlas's cache or built and
    /// kept; `None` when its albedo needs more than `request.budget` exact
    /// nodes (the map then integrates every pixel instead). A domain that
    /// failed is tried again only with a larger budget. Stopped between
    /// refinement steps with [`CoreError::Cancelled`] (nothing cached) once
    /// `request.progress` is [cancelled](Progress::cancelled).
    pub fn field(&self, request: FieldRequest<'_>) -> Result<Option<Arc<AlbedoField>>> {
        self.exact_field(request, PLAN_FACTOR)
    }

    /// [`Atlas::field`] with the plan given up past `plan_factor` times
    /// the budget.
    fn exact_field(
        &self,
        request: FieldRequest<'_>,
        plan_factor: usize,
    ) -> Result<Option<Arc<AlbedoField>>> {
        let FieldRequest {
            view,
            budget,
            rule,
            progress,
        } = request;
        self.cached_field(view, rule, None, budget, |domain, floor| {
            // Plan with the per-pixel rule's rows first: a field that would
            // need far more nodes than the budget is given up before any
            // exact node is paid for.
            let cap = plan_factor.saturating_mul(budget);
            match self.plan(domain, cap, floor, progress)? {
                Some(_) => self.build(domain, budget, floor, progress),
                None => Ok(None),
            }
        })
    }

    /// The field of `view`'s domain for `rule`'s material with nodes of
    /// `samples` samples (`None`: the nodes' rule) within `budget` nodes:
    /// from the atlas's cache (a field built, or a domain given up at this
    /// budget or a larger one), else from `build(domain, floor)`, kept.
    fn cached_field(
        &self,
        view: View,
        rule: BlendRule,
        samples: Option<usize>,
        budget: usize,
        build: impl FnOnce(View, bool) -> Result<Option<AlbedoField>>,
    ) -> Result<Option<Arc<AlbedoField>>> {
        view.check()?;
        let floor = floor_of(rule)?;
        let domain = domain_of(view);
        let same = |f: &Cached| f.is_for(domain, floor, samples);
        let cached = |f: &Cached| same(f) && (f.field.is_some() || f.budget >= budget);
        if let Some(f) = self.find_cached(cached) {
            return Ok(f.field.clone());
        }
        let field = build(domain, floor)?.map(Arc::new);
        let entry = Arc::new(Cached {
            domain,
            floor,
            samples,
            budget,
            field: field.clone(),
        });
        self.fields.keep(entry, FIELD_CACHE, cached, same);
        Ok(field)
    }

    /// The kept entry (built in this process, or saved beside the model,
    /// [`Atlas::saved_fields`]) for which `wanted` holds.
    fn find_cached(&self, wanted: impl Fn(&Cached) -> bool) -> Option<Arc<Cached>> {
        self.fields.find(&wanted).or_else(|| {
            let saved = self.loaded_fields().unwrap_or_default();
            saved.into_iter().find(|c| wanted(c))
        })
    }

    /// The kept field (exact if `samples` is `None`, else sampled with
    /// that many samples) of `rule`'s material whose domain holds `view`:
    /// the one of the smallest domain.
    fn covering_field(
        &self,
        view: View,
        floor: bool,
        samples: Option<usize>,
    ) -> Option<Arc<AlbedoField>> {
        let holds = |c: &Cached| c.floor == floor && c.samples == samples && c.domain.holds(view);
        let saved = self.loaded_fields().unwrap_or_default();
        self.fields
            .all()
            .iter()
            .chain(&saved)
            .filter(|c| holds(c))
            .filter_map(|c| c.field.clone())
            .min_by(|a, b| a.domain().area().total_cmp(&b.domain().area()))
    }

    /// A field the atlas holds (built in this process or saved beside the
    /// model) whose domain holds `view`, for `rule`'s material: an exact
    /// one if any, else a sampled one ([`FIELD_SAMPLES`]), each the one of
    /// the smallest domain; with the sample count of its nodes. What a
    /// preview draws from: nothing is built.
    pub(crate) fn held_field(
        &self,
        view: View,
        rule: BlendRule,
    ) -> Result<Option<(Arc<AlbedoField>, Option<usize>)>> {
        let floor = floor_of(rule)?;
        let sampled = Some(FIELD_SAMPLES);
        Ok(self
            .covering_field(view, floor, None)
            .map(|f| (f, None))
            .or_else(|| {
                self.covering_field(view, floor, sampled)
                    .map(|f| (f, sampled))
            }))
    }

    /// The field a `pixels`-pixel map of `view` of `rule`'s material draws
    /// from, with the sample count of its nodes (`None`: exact), or `None`
    /// when the map integrates every pixel. In this order: an exact field
    /// the atlas holds whose domain holds the view; the exact field of the
    /// view's domain within its budget ([`Atlas::field_budget`]; where a
    /// sampled field is held, only if its plan fits the budget too); a
    /// sampled field held whose domain holds the view (a zoom inside the
    /// default view after the default view's field was built or read from
    /// beside the model); the sampled field of the view's domain within
    /// its budget ([`Atlas::sampled_field_budget`]).
    pub(crate) fn map_field(
        &self,
        view: View,
        pixels: usize,
        rule: BlendRule,
        progress: &dyn Progress,
    ) -> Result<Option<(Arc<AlbedoField>, Option<usize>)>> {
        let floor = floor_of(rule)?;
        if let Some(field) = self.covering_field(view, floor, None) {
            return Ok(Some((field, None)));
        }
        let budget = self.field_budget(pixels, crate::DEFAULT_SAMPLES);
        let request = FieldRequest {
            view,
            budget,
            rule,
            progress,
        };
        // With a sampled field at hand the exact one is tried only where
        // its plan fits the budget itself: a plan that fits four times the
        // budget but an exact refinement that then does not costs several
        // passes over the store for nothing (1.5 s for a 256 x 256 map of
        // a sixteenth of the default view of 100 materials), where the
        // sampled field draws the map at once.
        let sampled = Some(FIELD_SAMPLES);
        let held = self.covering_field(view, floor, sampled);
        let plan_factor = if held.is_some() { 1 } else { PLAN_FACTOR };
        if let Some(field) = self.exact_field(request, plan_factor)? {
            return Ok(Some((field, None)));
        }
        if let Some(field) = held {
            return Ok(Some((field, sampled)));
        }
        let budget = self.sampled_field_budget(pixels);
        let request = FieldRequest { budget, ..request };
        Ok(self
            .sampled_field(request, FIELD_SAMPLES)?
            .map(|field| (field, sampled)))
    }

    /// The node budget of a `pixels`-pixel map's field: as many exact
    /// albedos as cost what integrating every pixel with `samples` samples
    /// would (a node reads every row of the nodes' rule, a pixel about
    /// three rows a sample), and at least [`MIN_NODES`].
    pub fn field_budget(&self, pixels: usize, samples: usize) -> usize {
        let rows = self.node_rows().rows.len().max(1) as f64;
        let per_pixel = 3.0 * samples as f64;
        ((pixels as f64 * per_pixel / rows) as usize).max(MIN_NODES)
    }

    /// The node budget of a `pixels`-pixel map's sampled field
    /// ([`Atlas::sampled_field`] with [`FIELD_SAMPLES`]): as many nodes as
    /// cost what integrating every pixel with
    /// [`DEFAULT_SAMPLES`](crate::DEFAULT_SAMPLES) would, and at least
    /// [`MIN_NODES`].
    pub fn sampled_field_budget(&self, pixels: usize) -> usize {
        let plan = self.pixel_rule(crate::DEFAULT_SAMPLES);
        let rows = plan.rows.rows.len() + self.pixel_rule(FIELD_SAMPLES).rows.rows.len();
        let per_pixel = 3.0 * crate::DEFAULT_SAMPLES as f64;
        ((pixels as f64 * per_pixel / rows.max(1) as f64) as usize).max(MIN_NODES)
    }

    /// Plan the field of `domain`: the same refinement as
    /// [`Atlas::build_field`], with node values from the map's per-pixel rule
    /// ([`DEFAULT_SAMPLES`](crate::DEFAULT_SAMPLES) samples: about 800 rows
    /// against 3.3 million, and like the exact albedo a sum of smooth
    /// functions of the point, so with detail at about the same scale). The
    /// nodes it took, or `None` past [`PLAN_FACTOR`] times `budget`: a domain
    /// whose albedo has detail much finer than itself, which the exact field
    /// is then judged not to fit in its budget either (the plan's values
    /// come from another rule, so this is a judgement, not a bound).
    pub fn plan_field(&self, domain: View, budget: usize) -> Result<Option<usize>> {
        let floor = floor_of(BlendRule::default())?;
        self.plan(
            domain,
            PLAN_FACTOR.saturating_mul(budget),
            floor,
            &NoProgress,
        )
    }

    /// The plan's nodes, `None` past `cap`.
    fn plan(
        &self,
        domain: View,
        cap: usize,
        floor: bool,
        progress: &dyn Progress,
    ) -> Result<Option<usize>> {
        let rows = &self.pixel_rule(crate::DEFAULT_SAMPLES).rows;
        let plan = self.albedo_patches(domain, cap, rows, floor, progress)?;
        Ok(plan.map(|(_, nodes)| nodes))
    }

    /// The sampled field of `request.view`'s domain: the albedo field
    /// with node values from a `samples`-sample quadrature rule (the
    /// per-pixel rule's kind, [`Quadrature::with_samples_shaped`]) instead
    /// of the nodes' rule, so as accurate as a map integrating every pixel
    /// with that rule (plus the field's tolerance) at a node's cost of a
    /// few pixels'. `None` past `request.budget` nodes. From the atlas's
    /// cache or built and kept, as [`Atlas::field`].
    ///
    /// [`Quadrature::with_samples_shaped`]: brdf_merl::Quadrature::with_samples_shaped
    pub fn sampled_field(
        &self,
        request: FieldRequest<'_>,
        samples: usize,
    ) -> Result<Option<Arc<AlbedoField>>> {
        let FieldRequest {
            view,
            budget,
            rule,
            progress,
        } = request;
        let samples = samples.max(1);
        self.cached_field(view, rule, Some(samples), budget, |domain, floor| {
            self.build_sampled(domain, budget, samples, floor, progress)
        })
    }

    /// The albedo's patches over `domain` with node values from `rows`, and
    /// the nodes they took; `None` past `budget` nodes. `floor`: every value
    /// on its soft floor.
    fn albedo_patches(
        &self,
        domain: View,
        budget: usize,
        rows: &RuleRows,
        floor: bool,
        progress: &dyn Progress,
    ) -> Result<Option<(Vec<Patch>, usize)>> {
        let mut nodes = 0;
        let patches = refine(domain, 3, &LEVELS, ALBEDO_TOLERANCE, 0, &mut |pts| {
            if progress.cancelled() {
                return Err(CoreError::Cancelled);
            }
            nodes += pts.len();
            if nodes > budget {
                return Ok(None);
            }
            Ok(Some(
                self.albedos_over(rows, pts, floor)?
                    .into_iter()
                    .flatten()
                    .collect(),
            ))
        })?;
        Ok(patches.map(|p| (p, nodes)))
    }

    /// Build the field of `domain` for the default rule's material (no
    /// cache), or `None` if its albedo would need more than `budget` exact
    /// nodes.
    pub fn build_field(&self, domain: View, budget: usize) -> Result<Option<AlbedoField>> {
        let floor = floor_of(BlendRule::default())?;
        self.build(domain, budget, floor, &NoProgress)
    }

    fn build(
        &self,
        domain: View,
        budget: usize,
        floor: bool,
        progress: &dyn Progress,
    ) -> Result<Option<AlbedoField>> {
        let rows = self.node_rows();
        let Some((albedo, nodes)) = self.albedo_patches(domain, budget, rows, floor, progress)?
        else {
            return Ok(None);
        };
        Ok(Some(self.with_variance(domain, albedo, nodes)?))
    }

    /// The sampled field of `domain` ([`Atlas::sampled_field`]): the
    /// patches and grids are those the plan's refinement (on the per-pixel
    /// rule's rows, [`DEFAULT_SAMPLES`](crate::DEFAULT_SAMPLES) samples,
    /// each node a fraction of a `samples`-sample node's cost) settles on,
    /// and their nodes then take the `samples`-sample rule's values, all
    /// in one pass; the estimate is the plan's. `None` if the plan needs
    /// more than `budget` nodes.
    fn build_sampled(
        &self,
        domain: View,
        budget: usize,
        samples: usize,
        floor: bool,
        progress: &dyn Progress,
    ) -> Result<Option<AlbedoField>> {
        let rows = &self.pixel_rule(crate::DEFAULT_SAMPLES).rows;
        let plan = self.albedo_patches(domain, budget, rows, floor, progress)?;
        let Some((mut albedo, nodes)) = plan else {
            return Ok(None);
        };
        if samples != crate::DEFAULT_SAMPLES {
            let points: Vec<[f64; 2]> = albedo
                .iter()
                .flat_map(|p| grid_points(&p.xs, &p.ys))
                .collect();
            // The per-pixel rule of that sample count holds its rows.
            let rule = self.pixel_rule(samples);
            // A few thousand points a pass: the rows are few, and a pass's
            // values at every point of a block of rows stay in cache.
            let mut values = Vec::with_capacity(points.len());
            for chunk in points.chunks(SAMPLED_CHUNK) {
                if progress.cancelled() {
                    return Err(CoreError::Cancelled);
                }
                values.extend(self.albedos_over(&rule.rows, chunk, floor)?);
            }
            let mut values = values.iter().flatten().copied();
            for p in &mut albedo {
                for v in &mut p.values {
                    *v = values.next().expect("a value a node");
                }
            }
        }
        let mut field = self.with_variance(domain, albedo, nodes)?;
        field.check = Some(self.check_field(domain, |x| field.at(x).0, floor)?);
        Ok(Some(field))
    }

    /// A field of `domain` from its albedo patches, with the variance's.
    fn with_variance(&self, domain: View, albedo: Vec<Patch>, nodes: usize) -> Result<AlbedoField> {
        let variance = refine(
            domain,
            1,
            &VARIANCE_LEVELS,
            VARIANCE_TOLERANCE,
            0,
            &mut |pts| Ok(Some(self.exact_variances(pts))),
        )?
        .expect("the variance has no budget");
        Ok(AlbedoField {
            domain,
            albedo,
            variance,
            nodes,
            check: None,
        })
    }
}

/// A domain's field, or that it has none within `budget` nodes, as the
/// model keeps it (and saves it beside the model,
/// [`crate::maps::saved_fields`]).
pub(crate) struct Cached {
    pub(crate) domain: View,
    /// Every value on its soft floor ([`BlendRule::Floor`]).
    pub(crate) floor: bool,
    /// The sample count of a sampled field's nodes; `None` for the nodes' rule.
    pub(crate) samples: Option<usize>,
    pub(crate) budget: usize,
    pub(crate) field: Option<Arc<AlbedoField>>,
}

impl Cached {
    /// The entry of `domain`, material `floor` and node rule `samples`.
    fn is_for(&self, domain: View, floor: bool, samples: Option<usize>) -> bool {
        self.domain == domain && self.floor == floor && self.samples == samples
    }

    /// The same domain, material and node rule as `other`.
    pub(crate) fn same(&self, other: &Cached) -> bool {
        self.is_for(other.domain, other.floor, other.samples)
    }
}

/// The predictive variance `1 - |L^-1 k|^2` (`K = L L^T`) of each column `k`
/// of `kx`, clamped to `[0, 1]`; `kx` is overwritten by `L^-1 kx`.
pub(crate) fn variances(inv: &[f64], kx: &[f64], n: usize, out: &mut [f32]) {
    // w = K^-1 k(x) for the whole row in one product, then k . w per pixel.
    let mut w = vec![0.0f64; kx.len()];
    matmul(&mut w, inv, kx, n);
    for ((o, k), w) in out
        .iter_mut()
        .zip(kx.chunks_exact(n))
        .zip(w.chunks_exact(n))
    {
        *o = (1.0 - dot::dot(k, w)).clamp(0.0, 1.0) as f32;
    }
}

impl AlbedoField {
    /// A field from its parts (as saved beside the model).
    pub(crate) fn from_parts(
        domain: View,
        albedo: Vec<Patch>,
        variance: Vec<Patch>,
        nodes: usize,
        check: Option<FieldCheck>,
    ) -> AlbedoField {
        AlbedoField {
            domain,
            albedo,
            variance,
            nodes,
            check,
        }
    }

    /// The albedo patches, for [`eval_row`].
    pub(crate) fn albedo_patches(&self) -> &[Patch] {
        &self.albedo
    }

    /// The variance patches, for [`eval_row`].
    pub(crate) fn variance_patches(&self) -> &[Patch] {
        &self.variance
    }
}
