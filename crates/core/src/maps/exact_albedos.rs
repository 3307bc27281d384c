//! Exact albedos at latent points: the dense rule (or another rule's rows)
//! over the full reconstruction, all the points in one pass over the store.
//!
//! The albedo field ([`crate::maps::albedo_field`]) takes its nodes from here,
//! and plans its refinement on the rows of the map's per-pixel rule, a few
//! hundred instead of millions, before paying for exact nodes.

use brdf_merl::Quadrature;

use crate::data::Store;
use crate::data::transform::InverseForm;
use crate::dense::product::matmul;
use crate::error::{CoreError, Result};
use crate::maps::Atlas;
use crate::model::blend::pass_weights::{PassWeights, floor_of, pass_weights};
use crate::model::blend::plausibility::BlendRule;
use crate::model::blend::soft_floor::{floor_points, top_of};
use crate::simd::fastexp;
use crate::simd::fold::{GROUPS, ordered_blocks, with_scratch};

/// Quadrature samples per pixel when a map needs them (non-linear transforms)
/// and the caller gives none; docs/performance.md says what it buys. Defined
/// here, beside the rows it plans fields with, and re-exported by the map.
pub const DEFAULT_SAMPLES: usize = 256;

/// The map's exact nodes read every this many phi_d bins, through the
/// cubic interpolant of those bins ([`Atlas::reduced_rule`], every theta_d
/// bin): at 256 random points of the default view of the 100
/// NBRDF-derived materials within 0.099% of the dense albedo at worst
/// (0.14% in [-3, 3]^2), where each cell's weight on its middle bin
/// ([`Quadrature::every_phi_d`]) was 0.165% (0.32%) off for a quarter fewer
/// rows (docs/performance.md, "Exact-albedo rules").
pub const NODE_PHI_D_STEP: usize = 8;

/// Rows of the store a step of the exact pass multiplies at once.
const BLOCK: usize = 256;
/// The most point weights (points times materials) a pass holds: 4 M, 32 MB
/// a matrix (a field's refinement asks tens of thousands of points at
/// once; with a thousand materials their weights alone once took a fit
/// past 1 GB).
const MAX_WEIGHTS: usize = 1 << 22;

/// The rows of the store a rule (the dense one, or a map's per-pixel one)
/// reads, with what turns a row's reconstructed value into its share of the
/// albedo.
pub(crate) struct RuleRows {
    /// Store rows (channel-major), ascending within each channel.
    pub(crate) rows: Vec<usize>,
    /// The channel of each row.
    pub(crate) channel: Vec<u8>,
    /// Quadrature weight times the inverse transform's scale.
    pub(crate) weight: Vec<f64>,
    /// `max(0, e^t - 1)` (log) rather than `max(0, t)` (raw).
    pub(crate) exponential: bool,
}

/// What [`Atlas::exact_albedos`] integrates: the material of a rule
/// ([`BlendRule::default`] unless set), with the rows of a quadrature rule
/// ([`Integration::Dense`] unless set).
///
/// ```
/// use brdf_atlas_core::{AlbedoRequest, BlendRule, Integration};
///
/// let request = AlbedoRequest::new().rule(BlendRule::Gp).integration(Integration::Nodes);
/// # let _ = request;
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct AlbedoRequest<'a> {
    /// The material at each point: the GP's blend or the soft floor's.
    pub rule: BlendRule,
    /// The quadrature rule the albedo is integrated with.
    pub integration: Integration<'a>,
}

impl<'a> AlbedoRequest<'a> {
    /// The default request: the default rule's material, the dense rule.
    pub fn new() -> AlbedoRequest<'a> {
        AlbedoRequest::default()
    }

    /// The material at each point.
    pub fn rule(self, rule: BlendRule) -> AlbedoRequest<'a> {
        AlbedoRequest { rule, ..self }
    }

    /// The quadrature rule the albedo is integrated with.
    pub fn integration(self, integration: Integration<'a>) -> AlbedoRequest<'a> {
        AlbedoRequest {
            integration,
            ..self
        }
    }
}

/// The quadrature rule exact albedos are integrated with.
#[derive(Debug, Clone, Copy, Default)]
pub enum Integration<'a> {
    /// The dense rule ([`Model::albedo_rule`](crate::Model::albedo_rule)).
    #[default]
    Dense,
    /// The rule of the map's nodes ([`NODE_PHI_D_STEP`]): what albedo
    /// fields and prepared lattices take at their nodes, at a sixth of
    /// the dense rule's cost at the MERL resolution.
    Nodes,
    /// Another quadrature rule of the model's dims: what
    /// [`reference_albedo`](crate::map_error::reference_albedo) gives point
    /// by point, for all the points in one pass over the rule's rows.
    Rule(&'a Quadrature),
}

impl Atlas {
    /// The rows of the dense rule, built once.
    pub(crate) fn rule_rows(&self) -> &RuleRows {
        self.rule_rows
            .get_or_init(|| self.rows_of(self.model.albedo_rule()))
    }

    /// The rows of the rule the map's exact nodes (albedo fields, prepared
    /// lattices) are integrated with: the cubic interpolant of every
    /// [`NODE_PHI_D_STEP`]-th phi_d bin where the grid has at least 90
    /// (a sixth of the rows at the MERL resolution, within 0.1% of the
    /// dense rule, see [`NODE_PHI_D_STEP`]), the dense rule itself on
    /// coarser grids; built once.
    pub(crate) fn node_rows(&self) -> &RuleRows {
        self.node_rows.get_or_init(|| {
            if self.model.dims().phi_d >= 90 {
                self.rows_of(&self.reduced_rule(1, NODE_PHI_D_STEP, true))
            } else {
                self.rows_of(self.model.albedo_rule())
            }
        })
    }

    /// The dense rule on every `theta_d`-th theta_d and `phi_d`-th phi_d
    /// bin, each bin's weight shared among the kept bins its linear or
    /// (`cubic`) cubic interpolant reads ([`Quadrature::reduced`]); bins
    /// whose interpolant would read a bin unmeasured in some channel are
    /// read themselves. What a reduced rule buys is measured by the report
    /// (its map section's table of rules) against the dense rule.
    pub fn reduced_rule(&self, theta_d: usize, phi_d: usize, cubic: bool) -> Quadrature {
        let (store, bins) = (self.model.store(), self.model.dims().bins());
        let unmeasured = store.unmeasured();
        self.model
            .albedo_rule()
            .reduced(theta_d, phi_d, cubic, |b| {
                (0..3).all(|c| unmeasured[c * bins + b] == 0)
            })
    }

    /// The store rows `rule` reads (measured ones only, channel-major), with
    /// the rule's weight times the inverse transform's scale.
    pub(crate) fn rows_of(&self, rule: &Quadrature) -> RuleRows {
        let store = self.model.store();
        let bins = store.dims().bins();
        let mut out = RuleRows {
            rows: Vec::new(),
            channel: Vec::new(),
            weight: Vec::new(),
            exponential: false,
        };
        for c in 0..3 {
            for (&b, &w) in rule.bins().iter().zip(rule.weights()) {
                let row = c * bins + b as usize;
                if store.unmeasured()[row] != 0 {
                    continue;
                }
                let scale = match self.model.transform().inverse_form(b as usize) {
                    InverseForm::Linear(s) => s,
                    InverseForm::Exp(s) => {
                        out.exponential = true;
                        s
                    }
                };
                out.rows.push(row);
                out.channel.push(c as u8);
                out.weight.push(w * scale);
            }
        }
        out
    }

    /// The albedo of the full reconstruction of the material
    /// `request.rule` forms at each point (the GP's blend or the soft
    /// floor's: a second product of each block, with the points' convex
    /// weights; the plausible rule's steps need a pass of their own per
    /// point, [`Atlas::plausible_blends`], so it is refused here),
    /// integrated as `request.integration` says ([`Integration`];
    /// negative reconstructed values count as 0, unmeasured bins are left
    /// out). One pass over the store for all points: each block of rows is
    /// one product with the points' weights `K^-1 k(x)`. The sums are
    /// formed in a fixed order: the answer does not depend on the thread
    /// count. [`CoreError::BadQuery`] for a quadrature rule of other dims.
    pub fn exact_albedos(
        &self,
        points: &[[f64; 2]],
        request: AlbedoRequest<'_>,
    ) -> Result<Vec<[f64; 3]>> {
        let floor = floor_of(request.rule)?;
        match request.integration {
            Integration::Dense => self.albedos_over(self.rule_rows(), points, floor),
            Integration::Nodes => self.albedos_over(self.node_rows(), points, floor),
            Integration::Rule(rule) => {
                if rule.dims() != self.model.dims() {
                    return Err(CoreError::BadQuery(format!(
                        "a quadrature rule for {} on a model of {}",
                        rule.dims(),
                        self.model.dims()
                    )));
                }
                self.albedos_over(&self.rows_of(rule), points, floor)
            }
        }
    }

    /// [`Atlas::exact_albedos`] with the rows of another rule, and with
    /// every value on its soft floor if `floor`.
    pub(crate) fn albedos_over(
        &self,
        rule: &RuleRows,
        points: &[[f64; 2]],
        floor: bool,
    ) -> Result<Vec<[f64; 3]>> {
        self.model.store().verify_cheap()?;
        let n = self.model.latent().nrows();
        // The points' weights are `m x n`: past `MAX_WEIGHTS` the points go
        // in chunks, a pass each (each point's sum is the same whatever
        // the chunks).
        let chunk = (MAX_WEIGHTS / n.max(1)).max(1);
        if points.len() > chunk {
            let mut out = Vec::with_capacity(points.len());
            for part in points.chunks(chunk) {
                out.extend(self.albedos_over(rule, part, floor)?);
            }
            return Ok(out);
        }
        let m = points.len();
        if m == 0 {
            return Ok(Vec::new());
        }
        let PassWeights {
            gp: a,
            convex: av,
            reach,
        } = pass_weights(&self.model, points, floor)?;
        let store = self.model.store();
        let mean = store.mean();
        // Products in f64 through the library's own kernel (faer's would
        // reserve twice the reported L3 cache in each thread).
        let parts = ordered_blocks(
            rule.rows.len(),
            BLOCK,
            GROUPS,
            || vec![0.0f64; 3 * m],
            |acc, range| {
                // The products can run in parallel: `with_scratch`, not a
                // borrow of the slot for the whole block.
                with_scratch(&SCRATCH, |s| {
                    let len = range.len();
                    s.t64.resize(m * len, 0.0);
                    s.z64.resize(n * len, 0.0);
                    s.top.resize(len, 0.0);
                    let tops = floor.then_some(&mut s.top[..]);
                    gather_rows(store, &rule.rows[range.clone()], &mut s.z64, tops);
                    matmul(&mut s.t64, &a, &s.z64, n);
                    if floor {
                        s.v64.resize(m * len, 0.0);
                        matmul(&mut s.v64, &av, &s.z64, n);
                    }
                    for (k, r) in range.enumerate() {
                        let (mu, wt) = (mean[rule.rows[r]], rule.weight[r]);
                        let c = rule.channel[r] as usize;
                        let acc = &mut acc[c * m..(c + 1) * m];
                        if floor {
                            let (t, v) =
                                (&mut s.t64[k * m..(k + 1) * m], &s.v64[k * m..(k + 1) * m]);
                            floor_points(t, v, mu, s.top[k], &reach[c]);
                        }
                        add_row(acc, &s.t64[k * m..(k + 1) * m], mu, wt, rule.exponential);
                    }
                })
            },
        );
        let mut out = vec![[0.0f64; 3]; m];
        for acc in parts {
            for (j, o) in out.iter_mut().enumerate() {
                for (c, oc) in o.iter_mut().enumerate() {
                    *oc += acc[c * m + j];
                }
            }
        }
        self.model.verify()?;
        Ok(out)
    }
}

/// The store's `rows` as f64, one after another in `z` (`n` values a
/// row), and with `tops` each row's largest value ([`top_of`]): per-row
/// work of the exact pass that does not depend on the points, in code
/// compiled for the widest vectors the CPU has (a conversion and a maximum
/// are exact: the same values on every path).
fn gather_rows(store: &Store, rows: &[usize], z: &mut [f64], tops: Option<&mut [f64]>) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::has_avx512f() {
            // SAFETY: the CPU has AVX-512F (checked just above).
            return unsafe { gather_rows_avx512(store, rows, z, tops) };
        }
        if crate::simd::has_avx2() {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { gather_rows_avx2(store, rows, z, tops) };
        }
    }
    gather_rows_portable(store, rows, z, tops);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2")]
fn gather_rows_avx512(store: &Store, rows: &[usize], z: &mut [f64], tops: Option<&mut [f64]>) {
    gather_rows_portable(store, rows, z, tops);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn gather_rows_avx2(store: &Store, rows: &[usize], z: &mut [f64], tops: Option<&mut [f64]>) {
    gather_rows_portable(store, rows, z, tops);
}

#[inline(always)]
fn gather_rows_portable(store: &Store, rows: &[usize], z: &mut [f64], tops: Option<&mut [f64]>) {
    let n = store.n();
    for (&row, out) in rows.iter().zip(z.chunks_exact_mut(n)) {
        store.copy_rows(row, out);
    }
    if let Some(tops) = tops {
        for (t, row) in tops.iter_mut().zip(z.chunks_exact(n)) {
            *t = top_of(row);
        }
    }
}

/// One row's share of each point's albedo: `acc[j] += wt * max(0, e^(mu +
/// t[j]) - 1)` under an exponential inverse transform, `wt * max(0, mu +
/// t[j])` under a linear one. In code compiled for the widest vectors the
/// CPU has: each point's sum takes the same terms in the same order on
/// every path, so the bits do not depend on the CPU's vector width.
fn add_row(acc: &mut [f64], t: &[f64], mu: f64, wt: f64, exponential: bool) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::has_avx512f() {
            // SAFETY: the CPU has AVX-512F (checked just above).
            return unsafe { add_row_avx512(acc, t, mu, wt, exponential) };
        }
        if crate::simd::has_avx2() {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { add_row_avx2(acc, t, mu, wt, exponential) };
        }
    }
    add_row_portable(acc, t, mu, wt, exponential);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2")]
fn add_row_avx512(acc: &mut [f64], t: &[f64], mu: f64, wt: f64, exponential: bool) {
    add_row_portable(acc, t, mu, wt, exponential);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn add_row_avx2(acc: &mut [f64], t: &[f64], mu: f64, wt: f64, exponential: bool) {
    add_row_portable(acc, t, mu, wt, exponential);
}

/// The reflectance of transformed value `t` (mean included), clamped at 0:
/// `max(0, e^t - 1)` under an exponential inverse transform, `max(0, t)`
/// under a linear one; the inverse transform's scale is in the weights.
#[inline(always)]
fn clamped(t: f64, exponential: bool) -> f64 {
    if exponential {
        (fastexp::exp(t) - 1.0).max(0.0)
    } else {
        t.max(0.0)
    }
}

#[inline(always)]
fn add_row_portable(acc: &mut [f64], t: &[f64], mu: f64, wt: f64, exponential: bool) {
    if exponential {
        for (o, t) in acc.iter_mut().zip(t) {
            *o += wt * clamped(mu + t, true);
        }
    } else {
        for (o, t) in acc.iter_mut().zip(t) {
            *o += wt * clamped(mu + t, false);
        }
    }
}

/// Each quadrature row's share of a pixel's albedo, element-wise:
/// `w * max(0, e^(m + t) - 1)` under an exponential inverse transform,
/// `w * max(0, m + t)` under a linear one; in code compiled for the widest
/// vectors the CPU has (the same bits on every path).
pub(crate) fn pixel_terms(
    terms: &mut [f64],
    mean: &[f64],
    weight: &[f64],
    col: &[f64],
    exponential: bool,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::has_avx512f() {
            // SAFETY: the CPU has AVX-512F (checked just above).
            return unsafe { pixel_terms_avx512(terms, mean, weight, col, exponential) };
        }
        if crate::simd::has_avx2() {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { pixel_terms_avx2(terms, mean, weight, col, exponential) };
        }
    }
    pixel_terms_portable(terms, mean, weight, col, exponential);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2")]
fn pixel_terms_avx512(t: &mut [f64], m: &[f64], w: &[f64], col: &[f64], exponential: bool) {
    pixel_terms_portable(t, m, w, col, exponential);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn pixel_terms_avx2(t: &mut [f64], m: &[f64], w: &[f64], col: &[f64], exponential: bool) {
    pixel_terms_portable(t, m, w, col, exponential);
}

#[inline(always)]
fn pixel_terms_portable(t: &mut [f64], m: &[f64], w: &[f64], col: &[f64], exponential: bool) {
    let it = t.iter_mut().zip(m).zip(w).zip(col);
    if exponential {
        it.for_each(|(((o, m), w), t)| *o = w * clamped(m + t, true));
    } else {
        it.for_each(|(((o, m), w), t)| *o = w * clamped(m + t, false));
    }
}

/// A worker's buffers for [`Atlas::exact_albedos`]: a block of rows and
/// its values at the nodes (kept between calls, so a pass allocates nothing).
#[derive(Default)]
struct Scratch {
    top: Vec<f64>,
    v64: Vec<f64>,
    z64: Vec<f64>,
    t64: Vec<f64>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pixels_terms_are_the_same_bits_on_every_path() {
        let mut rng = brdf_merl::synth::SplitMix64::new(11);
        for len in [1, 5, 16, 270] {
            let col: Vec<f64> = (0..len).map(|_| rng.range(-30.0, 8.0)).collect();
            let mean: Vec<f64> = (0..len).map(|_| rng.range(-2.0, 2.0)).collect();
            let weight: Vec<f64> = (0..len).map(|_| rng.range(0.0, 1e-3)).collect();
            for exponential in [true, false] {
                let want: Vec<u64> = (0..len)
                    .map(|k| {
                        let (m, t) = (mean[k], col[k]);
                        let v = if exponential {
                            (fastexp::exp(m + t) - 1.0).max(0.0)
                        } else {
                            (m + t).max(0.0)
                        };
                        (weight[k] * v).to_bits()
                    })
                    .collect();
                let mut got = vec![0.0; len];
                pixel_terms(&mut got, &mean, &weight, &col, exponential);
                let got: Vec<u64> = got.iter().map(|x| x.to_bits()).collect();
                assert_eq!(got, want, "{len} {exponential}");
            }
        }
    }

    #[test]
    fn a_row_adds_the_same_bits_on_every_path() {
        let mut rng = brdf_merl::synth::SplitMix64::new(9);
        for len in [1, 7, 8, 33, 256] {
            let t: Vec<f64> = (0..len).map(|_| rng.range(-30.0, 8.0)).collect();
            let start: Vec<f64> = (0..len).map(|_| rng.range(0.0, 2.0)).collect();
            for exponential in [true, false] {
                let (mu, wt) = (rng.range(-2.0, 2.0), rng.range(0.0, 1e-3));
                let mut want = start.clone();
                for (o, t) in want.iter_mut().zip(&t) {
                    *o += wt
                        * if exponential {
                            (fastexp::exp(mu + t) - 1.0).max(0.0)
                        } else {
                            (mu + t).max(0.0)
                        };
                }
                let mut got = start.clone();
                add_row(&mut got, &t, mu, wt, exponential);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&got), bits(&want), "{len} {exponential}");
            }
        }
    }
}
