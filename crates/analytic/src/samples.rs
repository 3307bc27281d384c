//! The fit's metric: which bins of a table it looks at and how much each
//! counts.
//!
//! The error of a model `f'` against a table `f` is the log-relative
//! difference `ln((f' + e) / (f + e))`, `e = 0.001` (1/sr), per channel,
//! weighted by `cos(theta_i) cos(theta_o)` and averaged over a fixed
//! subsample of the table's bins; its square root (an RMS over bins and
//! channels) is the *table error*. The log makes a relative error count the
//! same in a dark grazing bin as in a bright highlight, `e` keeps bins near
//! zero from dominating, and the cosines weigh pairs of directions as a lit,
//! seen surface does (how much a pair shows in a picture).
//!
//! The bins are every `theta_h` bin (the MERL grid's square-root spacing
//! puts most of them near the highlight, so the highlight counts as much as
//! its bins: the importance of directions is the table's own spacing, not
//! solid angle) and an even subsample of about 18 `theta_d` and 12 `phi_d`
//! values; bins with a direction at or below the horizon, unmeasured,
//! negative or non-finite in any channel are left out.
//!
//! A caller may add a picture to the metric ([`Samples::with_radiance`]):
//! pixels whose radiance is a sum of BRDF values times weights (a lit
//! sphere: `pi E cos` per light), the measured radiance from the table's
//! own lookups. Each pixel's squared difference, relative to the mean
//! measured radiance, is added with a chosen share to the table term: the
//! fit then also matches the material as that picture shows it, where the
//! highlight carries the light. The table error stays the table term alone.

use brdf_merl::{MerlTable, Quadrature, Vec3};

use crate::analytic::Analytic;
use crate::error::{AnalyticError, Result};
use crate::geometry::Geometry;

/// `e` of the metric, 1/sr.
pub const EPSILON: f64 = 1e-3;
/// Subsampled values along `theta_d` and `phi_d` (at most).
pub const SUBSAMPLE: [usize; 2] = [18, 12];
/// Fewest usable bins a fit accepts.
pub const MIN_BINS: usize = 64;

/// The bins of one table the metric looks at.
#[derive(Debug, Clone)]
pub struct Samples {
    pub(crate) geometry: Vec<Geometry>,
    /// `ln(f + e)` per channel.
    pub(crate) target: Vec<[f64; 3]>,
    /// `sqrt(cos_i cos_o)`: the residuals' factor.
    pub(crate) weight: Vec<f64>,
    /// `3 * sum of cos_i cos_o`, the mean's denominator.
    pub(crate) norm: f64,
    /// The table's albedo (a Lambertian of it is the first baseline).
    pub(crate) albedo: [f64; 3],
    /// Picture terms: pixel, the pair's cosines, weight.
    pub(crate) terms: Vec<(usize, Geometry, f64)>,
    /// Measured radiance of each pixel.
    pub(crate) radiance: Vec<[f64; 3]>,
    /// Factor of each pixel's residual: `sqrt(share / (3 pixels)) / mean radiance`.
    pub(crate) pixel_scale: f64,
}

/// One pixel of a picture: `(wi, wo, weight)` for each term of its
/// radiance `sum weight f(wi, wo)`.
pub type Pixel = Vec<(Vec3, Vec3, f64)>;

impl Samples {
    /// The metric's bins of `table`; `what` names the material in errors.
    pub fn new(table: &MerlTable, what: &str) -> Result<Samples> {
        let dims = table.dims();
        let step_d = dims.theta_d.div_ceil(SUBSAMPLE[0]).max(1);
        let step_p = dims.phi_d.div_ceil(SUBSAMPLE[1]).max(1);
        let mut s = Samples {
            geometry: Vec::new(),
            target: Vec::new(),
            weight: Vec::new(),
            norm: 0.0,
            albedo: [0.0; 3],
            terms: Vec::new(),
            radiance: Vec::new(),
            pixel_scale: 0.0,
        };
        for ih in 0..dims.theta_h {
            for id in (0..dims.theta_d).step_by(step_d) {
                for ip in (0..dims.phi_d).step_by(step_p) {
                    let bin = dims.bin(ih, id, ip);
                    let Some(g) = Geometry::of_angles(&dims.angles_of(bin)) else {
                        continue;
                    };
                    let v = [0, 1, 2].map(|c| table.value(c, bin));
                    let [Some(r), Some(gr), Some(b)] = v else {
                        continue;
                    };
                    let f = [r, gr, b];
                    if f.iter().any(|x| !x.is_finite() || *x < 0.0) {
                        continue;
                    }
                    s.push(g, f);
                }
            }
        }
        if s.geometry.len() < MIN_BINS {
            return Err(AnalyticError::TooFewBins {
                what: what.to_string(),
                dims,
                usable: s.geometry.len(),
                needed: MIN_BINS,
            });
        }
        let albedo = Quadrature::dense(dims, 1).albedo(table);
        s.albedo = albedo.map(|a| {
            if a.is_finite() {
                a.clamp(0.0, 1.0)
            } else {
                0.0
            }
        });
        Ok(s)
    }

    /// Add `pixels` to the metric with weight `share` against the table
    /// term (see the module docs); the measured radiance is looked up in
    /// `table` (a pair it does not measure adds nothing, as in a picture
    /// of it). A black picture, or a share that is not positive, adds nothing.
    pub fn with_radiance(mut self, table: &MerlTable, pixels: &[Pixel], share: f64) -> Samples {
        let mut terms = Vec::new();
        let mut radiance = vec![[0.0; 3]; pixels.len()];
        for (k, pixel) in pixels.iter().enumerate() {
            for &(wi, wo, w) in pixel {
                let Some(g) = Geometry::new(wi, wo) else {
                    continue;
                };
                if let Some(f) = table.eval(wi, wo) {
                    for c in 0..3 {
                        radiance[k][c] += w * f[c];
                    }
                }
                terms.push((k, g, w));
            }
        }
        let mean = radiance.iter().flatten().sum::<f64>() / (3 * pixels.len().max(1)) as f64;
        if !(share > 0.0 && mean.is_finite() && mean > 0.0) {
            return self;
        }
        self.terms = terms;
        self.radiance = radiance;
        self.pixel_scale = (share / (3 * pixels.len()) as f64).sqrt() / mean;
        self
    }

    /// Residuals the metric has: three per bin, three per pixel.
    pub(crate) fn residual_count(&self) -> usize {
        3 * (self.geometry.len() + self.radiance.len())
    }

    fn push(&mut self, g: Geometry, f: [f64; 3]) {
        let w = g.nl * g.nv;
        self.geometry.push(g);
        self.target.push(f.map(|v| (v + EPSILON).ln()));
        self.weight.push(w.sqrt());
        self.norm += 3.0 * w;
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.geometry.len()
    }

    /// Whether there are none (never, for a [`Samples::new`]).
    pub fn is_empty(&self) -> bool {
        self.geometry.is_empty()
    }

    /// The table's albedo, clamped to `[0, 1]`.
    pub fn albedo(&self) -> [f64; 3] {
        self.albedo
    }

    /// The weighted residuals of `model` into `out`: three per bin (their
    /// squares sum to the squared table error), then three per pixel.
    pub(crate) fn residuals<M: Analytic>(&self, model: &M, out: &mut [f64]) {
        let scale = 1.0 / self.norm.sqrt();
        let (bins, pixels) = out.split_at_mut(3 * self.geometry.len());
        for (k, (g, (t, w))) in self
            .geometry
            .iter()
            .zip(self.target.iter().zip(&self.weight))
            .enumerate()
        {
            let f = model.eval_geometry(g);
            for c in 0..3 {
                bins[3 * k + c] = scale * w * ((f[c].max(0.0) + EPSILON).ln() - t[c]);
            }
        }
        if self.radiance.is_empty() {
            return;
        }
        let mut sum = vec![[0.0; 3]; self.radiance.len()];
        for (k, g, w) in &self.terms {
            let f = model.eval_geometry(g);
            for c in 0..3 {
                sum[*k][c] += w * f[c];
            }
        }
        for (k, (l, m)) in sum.iter().zip(&self.radiance).enumerate() {
            for c in 0..3 {
                pixels[3 * k + c] = self.pixel_scale * (l[c] - m[c]);
            }
        }
    }

    /// The table error of `model`: the RMS weighted log-relative error.
    pub fn error<M: Analytic>(&self, model: &M) -> f64 {
        let mut r = vec![0.0; self.residual_count()];
        self.residuals(model, &mut r);
        r[..3 * self.len()]
            .iter()
            .map(|r| r * r)
            .sum::<f64>()
            .sqrt()
    }
}
