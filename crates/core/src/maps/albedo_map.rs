//! The albedo map of a 2-D latent space: every pixel is a latent point,
//! coloured by the albedo of the material reconstructed there.
//!
//! Three ways to compute it, chosen by what the transform allows:
//!
//! - **Linear** (raw transform): albedo is linear in the BRDF, so with the
//!   per-material albedos `A` (`N x 3`, integrated once from the store with
//!   the dense quadrature rule) the map is `albedo(x) = albedo(mean) + k(x)^T K^-1 A`:
//!   `N` exponentials and `3N` multiply-adds a pixel. This is the albedo of the
//!   blend before clamping negative values.
//! - **Field** (log transform): the inverse transform is not linear, but
//!   the albedo is a smooth function of the latent point: exact albedos at
//!   the nodes of refined grids, and the polynomial through them at every
//!   pixel, with an error estimate ([`crate::maps::albedo_field`]). The predictive
//!   variance is interpolated the same way.
//! - **Quadrature** (on request, `samples`): each pixel reconstructs exactly the bins of a quadrature
//!   rule with `samples` points and integrates them. The rows the rule needs
//!   are gathered once and premultiplied by `K^-1` (`C = Z_q K^-1`), so a row of
//!   pixels is one matrix product `C k(X_row)`. The sample count trades
//!   accuracy for time (docs/performance.md has the figures).

use brdf_merl::Quadrature;
use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::data::store::Rows;
use crate::dense::product::matmul;
use crate::error::{CoreError, Result};
use crate::maps::Atlas;
use crate::maps::albedo_field::variances;
use crate::maps::exact_albedos::pixel_terms;
use crate::maps::field_check::FieldCheck;
use crate::maps::lattice::AlbedoLattice;
use crate::maps::patches::eval_row;
use crate::maps::pixel_rule::PixelRule;
pub use crate::maps::view::View;
use crate::model::blend::pass_weights::floor_of;
use crate::model::blend::plausibility::BlendRule;
use crate::model::blend::plausible_budget::convex_weights_at;
use crate::model::blend::soft_floor::floor_rows;
use crate::progress::{NoProgress, Progress};
use crate::simd::dot;

pub use crate::maps::exact_albedos::DEFAULT_SAMPLES;

/// How a map's albedo was computed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", tag = "kind")]
pub enum AlbedoMethod {
    /// Blended per-material albedos (exact for the raw transform).
    Linear,
    /// A polynomial through exact albedos (the dense rule over the full
    /// reconstruction) at the nodes of grids on patches of the view's
    /// domain ([`crate::maps::albedo_field`]).
    Field {
        /// Exact albedos the field holds.
        nodes: usize,
        /// Patches of the albedo polynomial.
        patches: usize,
        /// The refinement's error estimate, relative to a node's largest channel.
        estimate: f64,
    },
    /// A polynomial through albedos integrated with a sampled quadrature
    /// rule (the per-pixel rule's kind, with more samples) at the nodes of
    /// grids on patches of the view's domain ([`Atlas::sampled_field`]):
    /// what a map takes when exact nodes would cost too much, as accurate
    /// as integrating every pixel with that rule and several times faster.
    #[serde(rename = "sampled-field")]
    SampledField {
        /// Samples of the nodes' rule.
        samples: usize,
        /// Nodes the field holds.
        nodes: usize,
        /// Patches of the albedo polynomial.
        patches: usize,
        /// The refinement's error estimate against the nodes' own rule,
        /// relative to a node's largest channel.
        estimate: f64,
        /// The field's error against exact albedos at a few points,
        /// measured when it was built (`None` for a field saved before
        /// fields were checked).
        check: Option<FieldCheck>,
    },
    /// The cubic of the prepared map's adaptive lattice of exact albedos
    /// ([`crate::maps::lattice`]), saved beside the model.
    Lattice {
        /// Exact albedos the lattice holds.
        nodes: usize,
        /// The refinement's tolerance, relative to a node's largest channel.
        tolerance: f64,
        /// The share of the pixels drawn from the lattice (those in its
        /// window, the default view); the rest were drawn as without it.
        share: f64,
    },
    /// Per-pixel quadrature over reconstructed bins.
    Quadrature {
        /// Requested sample count.
        samples: usize,
        /// Bins the rule reads.
        bins: usize,
    },
}

/// An albedo map: linear RGB albedo per pixel, row 0 at the top.
#[derive(Debug, Clone)]
pub struct AlbedoMap {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The latent window shown.
    pub view: View,
    /// Linear RGB albedo, `width * height`, row-major.
    pub rgb: Vec<[f32; 3]>,
    /// The GP's predictive variance `1 - k(x)^T K^-1 k(x)` of each pixel's
    /// latent point, `width * height`: 0 at an input material, 1 where the
    /// data say nothing (see [`crate::Confidence`]).
    pub variance: Vec<f32>,
    /// How it was computed.
    pub method: AlbedoMethod,
    /// The material each pixel shows: the GP's blend or the soft floor's.
    pub blend: BlendRule,
}

/// What [`Atlas::map`] draws: a `width x height` image of the default view,
/// of the default rule's material ([`BlendRule::default`], the soft floor),
/// the method chosen by the atlas, without a given prepared map and without
/// progress reports, unless set.
///
/// ```
/// use brdf_atlas_core::{BlendRule, MapRequest, View};
///
/// let request = MapRequest::new(256, 256)
///     .view(View::zoomed_hundredfold())
///     .rule(BlendRule::Gp)
///     .samples(Some(64));
/// # let _ = request;
/// ```
#[derive(Clone, Copy)]
pub struct MapRequest<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The latent window shown.
    pub view: View,
    /// `None`: the atlas chooses (prepared map, albedo field, per-pixel
    /// rule or the linear shortcut); `Some(s)`: each pixel integrated with
    /// an `s`-point rule.
    pub samples: Option<usize>,
    /// `Some(s)`: a preview, which builds nothing: drawn from what the
    /// atlas holds (the prepared map where it serves the view, else a
    /// field held or saved beside the model whose domain holds the view),
    /// else every pixel integrated with an `s`-point rule. Wherever the
    /// full map draws from the same held field or prepared map, the
    /// preview has its pixels (the full map may instead build the exact
    /// field of a small view that only a sampled field covers), and no
    /// preview waits for a field to be built. Not read when `samples` is
    /// `Some`: a sample count asks for per-pixel integration outright.
    pub preview: Option<usize>,
    /// The material at each pixel: the GP's blend or the soft floor's.
    pub rule: BlendRule,
    /// A prepared map to draw with, whether or not it is saved beside the
    /// model (its own rule is drawn).
    pub lattice: Option<&'a AlbedoLattice>,
    /// Told of the rows drawn, and asked whether to stop.
    pub progress: &'a dyn Progress,
}

impl<'a> MapRequest<'a> {
    /// A `width x height` map with the defaults.
    pub fn new(width: usize, height: usize) -> MapRequest<'a> {
        MapRequest {
            width,
            height,
            view: View::default(),
            samples: None,
            preview: None,
            rule: BlendRule::default(),
            lattice: None,
            progress: &NoProgress,
        }
    }

    /// The latent window shown.
    pub fn view(self, view: View) -> MapRequest<'a> {
        MapRequest { view, ..self }
    }

    /// Samples a pixel (`None`: the atlas chooses).
    pub fn samples(self, samples: Option<usize>) -> MapRequest<'a> {
        MapRequest { samples, ..self }
    }

    /// A preview: what the atlas holds, else `samples` samples a pixel
    /// ([`MapRequest::preview`](MapRequest#structfield.preview)).
    pub fn preview(self, samples: usize) -> MapRequest<'a> {
        MapRequest {
            preview: Some(samples),
            ..self
        }
    }

    /// The material at each pixel.
    pub fn rule(self, rule: BlendRule) -> MapRequest<'a> {
        MapRequest { rule, ..self }
    }

    /// A prepared map to draw with.
    pub fn lattice(self, lattice: &'a AlbedoLattice) -> MapRequest<'a> {
        MapRequest {
            lattice: Some(lattice),
            ..self
        }
    }

    /// Told of the rows drawn, and asked whether to stop.
    pub fn progress(self, progress: &'a dyn Progress) -> MapRequest<'a> {
        MapRequest { progress, ..self }
    }
}

/// How [`Atlas::draw`] may compute a map's albedo.
#[derive(Clone, Copy)]
pub(crate) enum Choice {
    /// As the atlas chooses: the prepared map, a field (built if need be),
    /// the per-pixel rule.
    Any,
    /// A preview: the prepared map or a field the atlas holds, else this
    /// many samples a pixel.
    Held(usize),
    /// This many samples a pixel.
    Samples(usize),
}

impl AlbedoMethod {
    /// The method of a map drawn from `field`, whose nodes are exact
    /// (`sampled` is `None`) or integrated with `sampled` samples.
    pub(crate) fn of_field(field: &crate::AlbedoField, sampled: Option<usize>) -> AlbedoMethod {
        match sampled {
            None => AlbedoMethod::Field {
                nodes: field.nodes(),
                patches: field.patches(),
                estimate: field.estimate(),
            },
            Some(samples) => AlbedoMethod::SampledField {
                samples,
                nodes: field.nodes(),
                patches: field.patches(),
                estimate: field.estimate(),
                check: field.check(),
            },
        }
    }
}

impl Atlas {
    /// Per-material albedos in transformed space (rows of `A`) and the albedo
    /// of the mean, with `rule`; linear transforms only make this an albedo.
    pub fn material_albedos(&self, rule: &Quadrature) -> (Vec<[f64; 3]>, [f64; 3]) {
        let store = self.model.store();
        let (n, bins) = (store.n(), store.dims().bins());
        let unmeasured = store.unmeasured();
        let mean = store.mean();
        let chunk = 16384;
        // Per chunk of the rule: one N-vector per channel, A_c += w z_row (an
        // AXPY on the stored row, no copy); chunks are folded in order.
        let partials: Vec<([Vec<f64>; 3], [f64; 3])> = rule
            .bins()
            .par_chunks(chunk)
            .zip(rule.weights().par_chunks(chunk))
            .map(|(bs, ws)| {
                let mut a: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0f64; n]);
                let mut m = [0.0f64; 3];
                for (&b, &w) in bs.iter().zip(ws) {
                    for (c, (ac, mc)) in a.iter_mut().zip(&mut m).enumerate() {
                        let row = c * bins + b as usize;
                        if unmeasured[row] != 0 {
                            continue;
                        }
                        match store.z() {
                            Rows::F32(z) => dot::axpy(w, &z[row * n..], ac),
                            Rows::F64(z) => dot::axpy(w, &z[row * n..], ac),
                        }
                        *mc += w * mean[row];
                    }
                }
                (a, m)
            })
            .collect();
        let mut a = vec![[0.0f64; 3]; n];
        let mut m = [0.0f64; 3];
        for (pa, pm) in partials {
            for (c, pc) in pa.iter().enumerate() {
                for (ai, p) in a.iter_mut().zip(pc) {
                    ai[c] += p;
                }
            }
            (0..3).for_each(|c| m[c] += pm[c]);
        }
        (a, m)
    }

    /// The model's mean material as reflectance per bin (channels averaged,
    /// unmeasured bins 0): the shape the map's quadrature rule assumes
    /// within each box of bins ([`Quadrature::with_samples_shaped`]). Built once.
    pub fn shape(&self) -> &[f64] {
        self.shape.get_or_init(|| {
            let store = self.model.store();
            let bins = self.model.dims().bins();
            let (mean, unmeasured) = (store.mean(), store.unmeasured());
            let mut shape = vec![0.0f64; bins];
            let mut value = vec![0.0f64; bins];
            for c in 0..3 {
                self.model
                    .transform()
                    .inverse_run(0, &mean[c * bins..(c + 1) * bins], &mut value);
                for ((s, v), &u) in shape.iter_mut().zip(&value).zip(&unmeasured[c * bins..]) {
                    if u == 0 {
                        *s += v / 3.0;
                    }
                }
            }
            shape
        })
    }

    /// The linear map's basis: `K^-1 A` per channel (`A` the per-material
    /// albedos of [`Atlas::material_albedos`] with [`Model::albedo_rule`])
    /// and the mean material's albedo. Built once.
    fn linear_basis(&self) -> &([Vec<f64>; 3], [f64; 3]) {
        self.linear.get_or_init(|| {
            let (a, m) = self.material_albedos(self.model.albedo_rule());
            let n = a.len();
            let b = self.model.llt_solve(&Mat::from_fn(n, 3, |i, c| a[i][c]));
            (
                std::array::from_fn(|c| (0..n).map(|i| b[(i, c)]).collect()),
                m,
            )
        })
    }

    /// The albedo map `request` asks for ([`MapRequest`]): a `width x
    /// height` image of its view, of the material its rule forms at each
    /// pixel, what `reconstruct` writes at each pixel's point.
    ///
    /// - With a prepared map ([`MapRequest::lattice`]; a lattice of another
    ///   fit is refused) the pixels in its window come from its cubic and the
    ///   rest are drawn as without it (a preview's as a preview's), of the
    ///   lattice's material; the request's rule and samples are not read.
    /// - Otherwise `samples` `None` uses the prepared map saved beside the
    ///   model where it serves the view and rule ([`Atlas::prepared_map`]),
    ///   else the albedo field ([`Atlas::field`]) where it fits its budget,
    ///   else the per-pixel rule with [`DEFAULT_SAMPLES`]; the GP's blend
    ///   of a linear transform uses the exact linear shortcut. `Some(s)`
    ///   integrates each pixel with an `s`-point rule. The soft floor's
    ///   material ([`BlendRule::Floor`]) is not linear in the weights, so
    ///   even a raw-transform map of it takes the field or the per-pixel
    ///   rule. The plausible rule has no map.
    /// - A preview ([`MapRequest::preview`], without `samples`) takes the
    ///   prepared map or a field the atlas holds, else its own sample count
    ///   a pixel, and builds nothing.
    ///
    /// Once the request's progress is [cancelled](Progress::cancelled) (it
    /// must then stay so) the map stops within a row or a field refinement
    /// step and returns [`CoreError::Cancelled`].
    pub fn map(&self, request: MapRequest<'_>) -> Result<AlbedoMap> {
        let MapRequest {
            width,
            height,
            view,
            samples,
            preview,
            rule,
            lattice,
            progress,
        } = request;
        let choice = match (samples, preview) {
            (Some(s), _) => Choice::Samples(s),
            (None, Some(s)) => Choice::Held(s),
            (None, None) => Choice::Any,
        };
        match lattice {
            Some(lattice) => {
                // A given prepared map reads no sample count; a preview
                // still builds nothing outside it.
                let choice = match choice {
                    Choice::Held(s) => Choice::Held(s),
                    _ => Choice::Any,
                };
                self.map_prepared(lattice, (width, height, view), choice, progress)
            }
            None => self.draw(width, height, view, choice, rule, progress),
        }
    }

    /// The map of `rule`'s material without a given lattice ([`Atlas::map`]).
    pub(crate) fn draw(
        &self,
        width: usize,
        height: usize,
        view: View,
        choice: Choice,
        rule: BlendRule,
        progress: &dyn Progress,
    ) -> Result<AlbedoMap> {
        self.check_map_request(width, height, view)?;
        let floor = floor_of(rule)?;
        self.model.store().verify_cheap()?;
        let n = self.model.latent().nrows();
        let (ex, ey) = self.kernel_factors(width, height, view);
        let mut rgb = vec![[0.0f32; 3]; width * height];
        let mut variance = vec![0.0f32; width * height];
        let inv = self.model.k_inverse();
        let kernel_row = |py: usize| kernel_row(&ex, &ey, n, py);
        progress.start("map", height as u64);
        let linear = self.model.file().transform.is_linear() && !floor;
        // A prepared map of this material draws the pixels in its window; a
        // damaged or stale one is left aside (`Atlas::prepared_map` says why).
        let lattice = match choice {
            Choice::Any | Choice::Held(_) if !linear => self
                .prepared_map()
                .ok()
                .flatten()
                .filter(|l| l.serves(view, rule)),
            _ => None,
        };
        if let Some(l) = lattice
            && let Some(map) = self.lattice_map(&l, (width, height, view), choice, progress)?
        {
            return Ok(map);
        }
        // The exact field where it fits its budget, else the sampled one
        // where that fits its own (a preview: only one held); else every
        // pixel is integrated.
        let field = match choice {
            Choice::Any if !linear => self.map_field(view, width * height, rule, progress)?,
            Choice::Held(_) if !linear => self.held_field(view, rule)?,
            _ => None,
        };
        let samples = match choice {
            Choice::Samples(s) => Some(s),
            _ if linear || field.is_some() => None,
            Choice::Held(s) => Some(s),
            Choice::Any => Some(DEFAULT_SAMPLES),
        };
        let method = match (field, samples) {
            (Some((field, sampled)), _) => {
                let xs: Vec<f64> = (0..width)
                    .map(|px| view.pixel_to_latent(px as f64, 0.0, width, height)[0])
                    .collect();
                rgb.par_chunks_mut(width)
                    .zip(variance.par_chunks_mut(width))
                    .enumerate()
                    .for_each(|(py, (row, var))| {
                        if progress.cancelled() {
                            return;
                        }
                        let y = view.pixel_to_latent(0.0, py as f64, width, height)[1];
                        eval_row(field.albedo_patches(), &xs, y, 3, |px, v| {
                            row[px] = [0, 1, 2].map(|c| v[c].max(0.0) as f32);
                        });
                        eval_row(field.variance_patches(), &xs, y, 1, |px, v| {
                            var[px] = v[0].clamp(0.0, 1.0) as f32;
                        });
                        progress.advance(1);
                    });
                AlbedoMethod::of_field(&field, sampled)
            }
            (None, None) => {
                let (cols, m) = self.linear_basis();
                // albedo(x, y)_c = m_c + sum_i ex_i(x) (ey_i(y) B_ic): per row, the
                // column factors meet one N-vector per channel.
                rgb.par_chunks_mut(width)
                    .zip(variance.par_chunks_mut(width))
                    .enumerate()
                    .for_each(|(py, (row, var))| {
                        if progress.cancelled() {
                            return;
                        }
                        variances(&inv, &kernel_row(py), n, var);
                        let ey = &ey[py * n..(py + 1) * n];
                        let v: Vec<Vec<f64>> = cols
                            .iter()
                            .map(|col| ey.iter().zip(col).map(|(e, b)| e * b).collect())
                            .collect();
                        for (out, ex) in row.iter_mut().zip(ex.chunks_exact(n)) {
                            for (o, (v, mc)) in out.iter_mut().zip(v.iter().zip(*m)) {
                                *o = (mc + dot::dot(v, ex)) as f32;
                            }
                        }
                        progress.advance(1);
                    });
                AlbedoMethod::Linear
            }
            (None, Some(s)) => {
                let rule = self.pixel_rule(s.max(1));
                let PixelRule {
                    rows,
                    ends,
                    c,
                    cv,
                    mean,
                    top,
                    ..
                } = &*rule;
                let r = rows.rows.len();
                let (weight, exponential) = (&rows.weight, rows.exponential);
                rgb.par_chunks_mut(width)
                    .zip(variance.par_chunks_mut(width))
                    .enumerate()
                    .for_each(|(py, (out, var))| {
                        if progress.cancelled() {
                            return;
                        }
                        let kx = kernel_row(py);
                        let mut vbuf = vec![0.0f64; r * width];
                        matmul(&mut vbuf, c, &kx, n);
                        if floor {
                            // The convex blend's values at every pixel of the
                            // row, and each value on its soft floor.
                            let y = view.pixel_to_latent(0.0, py as f64, width, height)[1];
                            let xs: Vec<[f64; 2]> = (0..width)
                                .map(|px| {
                                    [view.pixel_to_latent(px as f64, 0.0, width, height)[0], y]
                                })
                                .collect();
                            let convex = convex_weights_at(&self.model, &xs);
                            let vx: Vec<f64> = convex.concat();
                            let mut cbuf = vec![0.0f64; r * width];
                            matmul(&mut cbuf, cv, &vx, n);
                            // Each row's reach: its channel's at the pixel.
                            let bound = self.model.store().energy_bound();
                            let mut reach = vec![0.0f64; r];
                            let columns = vbuf.chunks_exact_mut(r).zip(cbuf.chunks_exact(r));
                            for ((col, cvals), v) in columns.zip(&convex) {
                                let at = bound.reach(v);
                                let mut start = 0;
                                for (ch, &end) in ends.iter().enumerate() {
                                    reach[start..end].fill(at[ch]);
                                    start = end;
                                }
                                floor_rows(col, cvals, mean, top, &reach);
                            }
                        }
                        let mut terms = vec![0.0f64; r];
                        for (px, o) in out.iter_mut().enumerate() {
                            let col = &vbuf[px * r..(px + 1) * r];
                            // Element-wise first (vectorises), then a fixed-order sum.
                            pixel_terms(&mut terms, mean, weight, col, exponential);
                            let mut start = 0;
                            for (ch, &end) in ends.iter().enumerate() {
                                o[ch] = sum4(&terms[start..end]) as f32;
                                start = end;
                            }
                        }
                        variances(&inv, &kx, n, var);
                        progress.advance(1);
                    });
                AlbedoMethod::Quadrature {
                    samples: s,
                    bins: rule.bins,
                }
            }
        };
        self.finish_map((width, height, view, rule), rgb, variance, method, progress)
    }

    /// The map of a finished pass: none if it was cancelled (rows skipped
    /// then hold zeros), an error if the store changed meanwhile.
    pub(crate) fn finish_map(
        &self,
        (width, height, view, rule): (usize, usize, View, BlendRule),
        rgb: Vec<[f32; 3]>,
        variance: Vec<f32>,
        method: AlbedoMethod,
        progress: &dyn Progress,
    ) -> Result<AlbedoMap> {
        progress.finish();
        if progress.cancelled() {
            return Err(CoreError::Cancelled);
        }
        self.model.verify()?;
        Ok(AlbedoMap {
            width,
            height,
            view,
            rgb,
            variance,
            method,
            blend: rule,
        })
    }
}

impl Atlas {
    /// The separable RBF's factors of a `width x height` image of `view`:
    /// `k(x, y)_i = e^(-(x - x_i)^2 / 2l^2) e^(-(y - y_i)^2 / 2l^2)`, so one
    /// factor per pixel column and one per pixel row (N each, column- and
    /// row-major) give every pixel's `k(x)` with N multiplications and no
    /// exponential.
    fn kernel_factors(&self, width: usize, height: usize, view: View) -> (Vec<f64>, Vec<f64>) {
        let kernel = self.model.file().kernel;
        let latent = self.model.latent();
        let n = latent.nrows();
        let inv2l2 = 1.0 / (2.0 * kernel.length_scale * kernel.length_scale);
        let factors = |count: usize, axis: usize, centre: &dyn Fn(usize) -> f64| -> Vec<f64> {
            let mut f = vec![0.0; count * n];
            for (k, out) in f.chunks_exact_mut(n).enumerate() {
                let c = centre(k);
                for (i, o) in out.iter_mut().enumerate() {
                    let d = latent[(i, axis)] - c;
                    *o = (-d * d * inv2l2).exp();
                }
            }
            f
        };
        let ex = factors(width, 0, &|px| {
            view.pixel_to_latent(px as f64, 0.0, width, height)[0]
        });
        let ey = factors(height, 1, &|py| {
            view.pixel_to_latent(0.0, py as f64, width, height)[1]
        });
        (ex, ey)
    }

    /// A map needs a 2-D model, a size within [`crate::limits::MAX_MAP_SIDE`]
    /// a side and a finite, non-empty view.
    pub(crate) fn check_map_request(&self, width: usize, height: usize, view: View) -> Result<()> {
        if self.model.q() != 2 {
            return Err(CoreError::BadQuery(format!(
                "a map needs a 2-D latent space, this model has q = {}",
                self.model.q()
            )));
        }
        let max = crate::limits::MAX_MAP_SIDE;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(CoreError::BadQuery(format!(
                "map size {width}x{height} must be between 1 and {max} a side"
            )));
        }
        view.check()
    }

    /// The GP's predictive variance of every pixel of a `width x height`
    /// image of `view` (row 0 at the top), as [`AlbedoMap::variance`] holds
    /// it, without the albedo: no pass over the store, O(N^2) a pixel.
    pub fn variance_map(&self, width: usize, height: usize, view: View) -> Result<Vec<f32>> {
        self.check_map_request(width, height, view)?;
        let n = self.model.latent().nrows();
        let (ex, ey) = self.kernel_factors(width, height, view);
        let inv = self.model.k_inverse();
        let mut variance = vec![0.0f32; width * height];
        variance
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(py, out)| variances(&inv, &kernel_row(&ex, &ey, n, py), n, out));
        Ok(variance)
    }
}

/// `k(x)` of every pixel of row `py`, one column a pixel, from the factors
/// of [`Atlas::kernel_factors`].
fn kernel_row(ex: &[f64], ey: &[f64], n: usize, py: usize) -> Vec<f64> {
    // Column-major n x width: one column a pixel.
    let mut kx = vec![0.0f64; ex.len()];
    let ey = &ey[py * n..(py + 1) * n];
    for (ex, col) in ex.chunks_exact(n).zip(kx.chunks_exact_mut(n)) {
        for ((o, a), b) in col.iter_mut().zip(ex).zip(ey) {
            *o = a * b;
        }
    }
    kx
}

/// Sum with four interleaved partial sums: vectorisable, and the same bits every time.
fn sum4(v: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let chunks = v.chunks_exact(4);
    let rest: f64 = chunks.remainder().iter().sum();
    for c in chunks {
        for k in 0..4 {
            acc[k] += c[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + rest
}
