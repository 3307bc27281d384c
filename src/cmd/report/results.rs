//! The report's results: plain data, filled by the measurements
//! ([`super::measure`], [`super::maps`], [`super::plausible`],
//! [`super::fidelity`], [`super::growth`]) and read by the writers
//! ([`super::csv`], [`super::markdown`], [`super::plot`] and the sections'
//! own tables and pictures). It uses none of them.

use std::time::Duration;

use brdf_atlas_core::fidelity::{Judged, Spacing};
use brdf_atlas_core::{BlendRule, Kernel, OptimizerKind, Precision, TransformKind};

use super::steps::SectionTime;

/// One fit of the latent points.
pub struct FitRow {
    pub transform: TransformKind,
    pub q: usize,
    pub optimizer: OptimizerKind,
    pub min_step: f64,
    pub time: Duration,
    pub initial_cost: f64,
    pub cost: f64,
    pub evaluations: u64,
}

/// Leave-one-out errors of one method.
pub struct LooRow {
    pub transform: TransformKind,
    /// `gplvm`, `gplvm-other` (the other optimiser) or `pca`.
    pub method: &'static str,
    pub q: usize,
    /// Reflectance RMSE.
    pub raw: f64,
    /// Cosine-weighted log RMSE.
    pub log: f64,
    /// RMSE in the model's transformed space.
    pub transformed: f64,
    /// Per material: (reflectance RMSE, log RMSE).
    pub materials: Vec<(f64, f64)>,
    /// In-sample PCA RMSE in transformed space, from the discarded eigenvalues.
    pub in_sample: Option<f64>,
}

/// Building one store.
pub struct StoreRow {
    pub transform: TransformKind,
    pub precision: Precision,
    pub time: Duration,
    pub bytes: u64,
}

/// The f32 and f64 reconstruction of one latent point.
pub struct PrecisionRow {
    pub point: Vec<f64>,
    pub max_abs: f64,
    pub max_rel: f64,
    pub rms: f64,
    pub time32: Duration,
    pub time64: Duration,
}

/// One sample count of the log map.
pub struct SampleRow {
    pub samples: usize,
    pub bins: usize,
    pub max_err: f64,
    pub mean_err: f64,
    pub time: Duration,
}

/// A quadrature rule for the exact albedo, against the dense rule.
pub struct RuleRow {
    /// What the report calls it.
    pub rule: String,
    pub bins: usize,
    /// Wall time of one pass for all the points, divided by their count.
    pub per_point: Duration,
    pub max_err: f64,
    pub mean_err: f64,
}

/// A map method at a view: the default (the albedo field where it fits its
/// budget) or the per-pixel rule, its error and time.
#[derive(Clone)]
pub struct MethodRow {
    /// "default" or "1/100".
    pub view: &'static str,
    pub method: String,
    /// The method is the albedo field.
    pub field: bool,
    /// The method is the sampled field.
    pub sampled: bool,
    /// The method is the prepared map's lattice.
    pub prepared: bool,
    pub max_err: f64,
    pub mean_err: f64,
    /// The first map of the view (a field builds its nodes; the prepared
    /// map's row includes preparing the lattice), and the next.
    pub first: Duration,
    pub again: Duration,
}

/// One map size.
pub struct SizeRow {
    pub method: String,
    pub size: usize,
    pub time: Duration,
}

/// One latent point of the plausibility grid under one blend rule.
pub struct PlausibilityRow {
    pub transform: TransformKind,
    /// The model's kernel: `fixed` (l = 1, mu = 1e-4) or `learned`.
    pub kernel: &'static str,
    pub rule: BlendRule,
    pub x: [f64; 2],
    pub clamped_reflectance: f64,
    pub clamped_values: f64,
    pub max_albedo: f64,
    pub variance: f64,
}

/// Everything measured.
#[derive(Default)]
pub struct Results {
    pub names: Vec<String>,
    /// The settings compared on how their markers give materials back.
    pub fidelity: Vec<FidelityRow>,
    pub dims: String,
    /// Values per material.
    pub d: usize,
    /// Opening and validating the files.
    pub scan: SectionTime,
    pub stores: Vec<StoreRow>,
    pub fits: Vec<FitRow>,
    pub loo: Vec<LooRow>,
    /// Per transform: predictors of its leave-one-out pass, and its time.
    pub loo_times: Vec<(TransformKind, usize, Duration)>,
    pub scored_rows: usize,
    /// Hooke-Jeeves' minimum step sweep.
    pub sweep: Vec<FitRow>,
    pub precision: Vec<PrecisionRow>,
    pub gram_rel_diff: f64,
    pub samples: Vec<SampleRow>,
    pub reference_time: Duration,
    pub reference_pixels: usize,
    pub sizes: Vec<SizeRow>,
    /// Exact-albedo rules against the dense rule, the dense rule first
    /// (its error 0), at `rule_points` random points of the default view.
    pub rules: Vec<RuleRow>,
    pub rule_points: usize,
    /// The default map method against the per-pixel rule, by view.
    pub methods: Vec<MethodRow>,
    /// Side of the maps of `methods`.
    pub methods_size: usize,
    /// The plausibility grid of each transform's q = 2 model, row by row
    /// from the top, under each rule.
    pub plausibility: Vec<PlausibilityRow>,
    /// How spread each q = 2 model's map is: transform, kernel and the median
    /// distance from a material to its nearest neighbour in the latent plane.
    pub spread: Vec<(TransformKind, &'static str, f64)>,
    /// The leave-one-out label of the q = 2 Hooke-Jeeves fit, whose model
    /// the maps, the precision comparison and the plausible rule use.
    pub kept_label: &'static str,
    /// Fits of synthetic databases by size (`--growth`).
    pub growth: Vec<GrowthRow>,
    /// The analytic fit of each material fitted and its baselines.
    pub analytic: Vec<AnalyticRow>,
    /// Materials in the database the analytic fits were picked from.
    pub analytic_of: usize,
    /// Wall and CPU time of each section of the report, in the order run.
    pub times: Vec<(String, SectionTime)>,
}

impl Results {
    /// The leave-one-out row of `method` at `q` for transform `t`.
    pub fn loo_row(&self, t: TransformKind, method: &str, q: usize) -> Option<&LooRow> {
        self.loo
            .iter()
            .find(|l| l.transform == t && l.method == method && l.q == q)
    }
}

/// One setting compared.
#[derive(Debug, Clone, Copy)]
pub struct Setting {
    pub transform: TransformKind,
    pub kernel: Kernel,
    /// What the report calls it.
    pub label: &'static str,
}

/// What one setting gave.
#[derive(Debug, Clone)]
pub struct FidelityRow {
    pub setting: Setting,
    /// Each material at its own point (the default rule).
    pub own: Vec<Judged>,
    /// Each material predicted from the others (the default rule).
    pub held_out: Vec<Judged>,
    /// How far apart the materials land.
    pub spacing: Spacing,
    /// Share of a 41 x 41 grid of the default view with predictive variance below 0.1.
    pub known: f64,
    /// Largest directional albedo at random points of the default view: 90th percentile and worst.
    pub max_albedo: [f64; 2],
    /// The fit (store pass, optimisation, own-point pass) and the leave-one-out pass.
    pub fit_time: Duration,
}

/// One material's analytic fit (`brdf-atlas export`'s) and its baselines.
#[derive(Debug, Clone)]
pub struct AnalyticRow {
    pub name: String,
    /// Rendered errors: the fit, the single lobe, the Lambertian, the fit under held-out lights.
    pub rendered: [f64; 4],
    /// Table errors: the fit, the single lobe, the Lambertian.
    pub table: [f64; 3],
    /// The fits' wall time (both models).
    pub time: Duration,
    /// Side of the spheres the rendered errors come from, pixels.
    pub sphere: usize,
}

/// One fit of one size.
#[derive(Debug, Clone)]
pub struct GrowthRow {
    pub n: usize,
    pub optimizer: OptimizerKind,
    /// The optimiser alone (the store pass and the Gram product are not in it).
    pub time: Duration,
    pub cost: f64,
    pub evaluations: u64,
    pub refactorisations: u64,
}
