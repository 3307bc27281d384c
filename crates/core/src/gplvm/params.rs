//! Parameters, checked parameters and the fit of a GPLVM.
//!
//! ```
//! use brdf_atlas_core::{GplvmParams, GramData};
//! use faer::Mat;
//! // Four materials of dimension 3 on a line: Y = Z Z^T.
//! let z = Mat::<f64>::from_fn(4, 3, |i, j| (i as f64 - 1.5) * (j as f64 + 1.0));
//! let data = GramData::new(&z * z.transpose(), 3).unwrap();
//! let fit = GplvmParams::new(1).length_scale(1.0).noise(1e-4).check().unwrap()
//!     .fit(&data, &brdf_atlas_core::NoProgress).unwrap();
//! assert!(fit.outcome.cost <= fit.outcome.initial_cost);
//! ```

use faer::Mat;

use crate::error::{ParamError, Result};
use crate::gplvm::kernel::Kernel;
use crate::gplvm::likelihood::GramData;
use crate::gplvm::optim::{BOX, HookeJeeves, Lbfgs, Optimizer, OptimizerKind, Outcome, Problem};
use crate::gplvm::pca::dual_pca;
use crate::progress::Progress;

/// GPLVM settings; `Default` gives the paper's kernel (q = 2, l = 1,
/// mu = 1e-4) with L-BFGS (the paper's Hooke-Jeeves is
/// [`OptimizerKind::HookeJeeves`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GplvmParams {
    q: usize,
    kernel: Kernel,
    optimizer: OptimizerKind,
    hooke_jeeves: HookeJeeves,
    lbfgs: Lbfgs,
}

impl Default for GplvmParams {
    fn default() -> Self {
        GplvmParams::new(2)
    }
}

impl GplvmParams {
    /// Defaults with latent dimension `q`.
    pub fn new(q: usize) -> Self {
        GplvmParams {
            q,
            kernel: Kernel::default(),
            optimizer: OptimizerKind::default(),
            hooke_jeeves: HookeJeeves::default(),
            lbfgs: Lbfgs::default(),
        }
    }

    /// Latent dimension.
    pub fn q(mut self, q: usize) -> Self {
        self.q = q;
        self
    }

    /// RBF length scale `l`.
    pub fn length_scale(mut self, l: f64) -> Self {
        self.kernel.length_scale = l;
        self
    }

    /// Noise `mu` on the kernel diagonal.
    pub fn noise(mut self, mu: f64) -> Self {
        self.kernel.noise = mu;
        self
    }

    /// Learn the kernel's length scale and noise by maximum likelihood with
    /// the latent points, starting from the kernel given (L-BFGS only).
    pub fn learn_kernel(mut self, learn: bool) -> Self {
        self.lbfgs.learn_kernel = learn;
        self
    }

    /// Which optimiser fits the latent points.
    pub fn optimizer(mut self, kind: OptimizerKind) -> Self {
        self.optimizer = kind;
        self
    }

    /// Hooke-Jeeves' stopping step.
    pub fn min_step(mut self, step: f64) -> Self {
        self.hooke_jeeves.min_step = step;
        self
    }

    /// Hooke-Jeeves' first step.
    pub fn initial_step(mut self, step: f64) -> Self {
        self.hooke_jeeves.initial_step = step;
        self
    }

    /// The longest Hooke-Jeeves' refactorisation interval (accepted moves;
    /// the interval adapts to the measured drift below it).
    pub fn refresh_every(mut self, moves: u64) -> Self {
        self.hooke_jeeves.refresh_every = moves;
        self
    }

    /// Check the values; only checked parameters can fit.
    pub fn check(self) -> Result<CheckedParams> {
        let max = crate::limits::MAX_Q;
        if self.q == 0 || self.q > max {
            return Err(ParamError::LatentDim { q: self.q, max }.into());
        }
        self.kernel.check()?;
        if self.lbfgs.learn_kernel && self.optimizer != OptimizerKind::Lbfgs {
            return Err(ParamError::LearnKernelNeedsLbfgs.into());
        }
        let hj = self.hooke_jeeves;
        if !(hj.min_step > 0.0 && hj.initial_step >= hj.min_step && hj.initial_step <= 2.0) {
            return Err(ParamError::Steps {
                min_step: hj.min_step,
                initial_step: hj.initial_step,
            }
            .into());
        }
        if !(hj.reduction > 0.0 && hj.reduction < 1.0) {
            return Err(ParamError::Reduction(hj.reduction).into());
        }
        Ok(CheckedParams(self))
    }
}

/// Parameters that passed [`GplvmParams::check`].
#[derive(Debug, Clone, PartialEq)]
pub struct CheckedParams(GplvmParams);

/// A fitted latent space.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The kernel of the fitted model: the one given, or the one learned.
    pub kernel: Kernel,
    /// Whether the kernel was learned with the latent points.
    pub learned_kernel: bool,
    /// The optimiser used.
    pub optimizer: OptimizerKind,
    /// The PCA start, `N x q`.
    pub start: Mat<f64>,
    /// Eigenvalues of the normalised Gram matrix, descending.
    pub eigenvalues: Vec<f64>,
    /// The optimiser's result (final latent points and cost among it).
    pub outcome: Outcome,
}

impl CheckedParams {
    /// The parameters.
    pub fn params(&self) -> &GplvmParams {
        &self.0
    }

    /// Fit latent points to the data: dual-PCA start, then the optimiser.
    pub fn fit(&self, data: &GramData, progress: &dyn Progress) -> Result<Fit> {
        let p = &self.0;
        let (start, eigenvalues) = dual_pca(data.y(), p.q)?;
        let problem = Problem {
            kernel: p.kernel,
            data,
        };
        let optimizer: &dyn Optimizer = match p.optimizer {
            OptimizerKind::HookeJeeves => &p.hooke_jeeves,
            OptimizerKind::Lbfgs => &p.lbfgs,
        };
        let mut outcome = optimizer.minimize(&problem, start.clone(), progress)?;
        let learned_kernel = p.optimizer == OptimizerKind::Lbfgs && p.lbfgs.learn_kernel;
        if learned_kernel {
            fill_the_box(&mut outcome);
        }
        Ok(Fit {
            kernel: outcome.kernel,
            learned_kernel,
            optimizer: p.optimizer,
            start,
            eigenvalues,
            outcome,
        })
    }
}

/// Rotate the latent points (when `q = 2`) to the angle whose bounding box
/// has the smallest larger half-width, translate them so that the box is
/// centred on the origin, and scale them and the length scale by one
/// factor so that the box's larger half-width is 1.
///
/// The kernel depends on `|x_i - x_j| / l` only, so the cost and every
/// reconstruction are unchanged; what changes is that the map's default
/// view, which frames `[-1, 1]^2`, frames the materials as large as it can.
/// A learned kernel needs this: with the length scale free, the likelihood
/// does not care how large the configuration is or how it is turned, and
/// the optimum found often fills a fraction of the box.
fn fill_the_box(outcome: &mut Outcome) {
    let x = &mut outcome.latent;
    let (n, q) = (x.nrows(), x.ncols());
    if q == 2 {
        let points: Vec<[f64; 2]> = (0..n).map(|i| [x[(i, 0)], x[(i, 1)]]).collect();
        // Quarter-degree steps over a quarter turn (a box turned by 90
        // degrees is the same box): the first smallest wins, so the angle
        // depends on the points only.
        let angle = (0..360)
            .map(|k| (k as f64 * 0.25).to_radians())
            .map(|a| (half_width(&turn(&points, a)), a))
            .fold(
                (f64::INFINITY, 0.0),
                |best, t| if t.0 < best.0 { t } else { best },
            )
            .1;
        for (i, p) in turn(&points, angle).iter().enumerate() {
            x[(i, 0)] = p[0];
            x[(i, 1)] = p[1];
        }
    }
    let mut half = 0.0f64;
    let mut centre = vec![0.0; q];
    for (c, m) in centre.iter_mut().enumerate() {
        let (lo, hi) = (0..n).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
            (lo.min(x[(i, c)]), hi.max(x[(i, c)]))
        });
        *m = 0.5 * (lo + hi);
        half = half.max(0.5 * (hi - lo));
    }
    if !(half > 0.0 && half.is_finite()) {
        return;
    }
    let s = 1.0 / half;
    for i in 0..n {
        for c in 0..q {
            // Clamped against rounding: the extreme points land on +-1.
            x[(i, c)] = ((x[(i, c)] - centre[c]) * s).clamp(BOX.0, BOX.1);
        }
    }
    outcome.kernel.length_scale *= s;
}

/// Points in the plane turned by angle `a`.
fn turn(points: &[[f64; 2]], a: f64) -> Vec<[f64; 2]> {
    let (s, c) = a.sin_cos();
    points
        .iter()
        .map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]])
        .collect()
}

/// The larger half-width of the bounding box of points in the plane.
fn half_width(points: &[[f64; 2]]) -> f64 {
    (0..2)
        .map(|d| {
            let (lo, hi) = points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[d]), hi.max(p[d]))
                });
            0.5 * (hi - lo)
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gplvm::likelihood::cost;
    use crate::progress::NoProgress;
    use brdf_merl::synth::SplitMix64;

    /// Materials along a curve in a 30-dimensional space, plus noise.
    fn curve(n: usize, seed: u64) -> GramData {
        let mut rng = SplitMix64::new(seed);
        let d = 30;
        let dirs: Vec<f64> = (0..3 * d).map(|_| rng.range(-1.0, 1.0)).collect();
        let mut z = Mat::<f64>::from_fn(n, d, |i, j| {
            let t = i as f64 / n as f64 * 3.0;
            t.sin() * dirs[j]
                + t.cos() * dirs[d + j]
                + 0.3 * t * dirs[2 * d + j]
                + 0.01 * rng.range(-1.0, 1.0)
        });
        for j in 0..d {
            let m: f64 = (0..n).map(|i| z[(i, j)]).sum::<f64>() / n as f64;
            (0..n).for_each(|i| z[(i, j)] -= m);
        }
        GramData::new(&z * z.transpose(), d).unwrap()
    }

    fn check_box_and_monotone(data: &GramData, kernel: &Kernel, o: &Outcome) {
        assert!(o.latent.as_ref().norm_max() <= 1.0 && o.latent.as_ref().norm_max().is_finite());
        for w in o.history.windows(2) {
            assert!(
                w[1] <= w[0] + 1e-9 * w[0].abs(),
                "cost rose: {} -> {}",
                w[0],
                w[1]
            );
        }
        let dense = cost(kernel, data, o.latent.as_ref()).unwrap();
        assert!((dense - o.cost).abs() <= 1e-9 * dense.abs());
        assert!(o.cost <= o.initial_cost);
    }

    #[test]
    fn hooke_jeeves_descends_inside_the_box_and_takes_pattern_moves() {
        let data = curve(25, 3);
        let fit = GplvmParams::new(2)
            .check()
            .unwrap()
            .fit(&data, &NoProgress)
            .unwrap();
        check_box_and_monotone(&data, &fit.kernel, &fit.outcome);
        assert!(fit.outcome.cost < fit.outcome.initial_cost);
        assert!(
            fit.outcome.drift.max_cost_drift < 1e-9,
            "{:?}",
            fit.outcome.drift
        );
        // From a start squeezed towards the origin, the search must expand the
        // configuration: consistent directions that pattern moves accelerate.
        let squeezed = &fit.start * faer::Scale(0.02);
        let problem = Problem {
            kernel: fit.kernel,
            data: &data,
        };
        let o = HookeJeeves::default()
            .minimize(&problem, squeezed, &NoProgress)
            .unwrap();
        check_box_and_monotone(&data, &fit.kernel, &o);
        assert!(o.pattern_moves > 0, "no pattern move taken: {o:?}");
    }

    #[test]
    fn lbfgs_descends_and_reaches_a_comparable_cost() {
        let data = curve(25, 3);
        let hj = GplvmParams::new(2)
            .check()
            .unwrap()
            .fit(&data, &NoProgress)
            .unwrap();
        let lb = GplvmParams::new(2)
            .optimizer(OptimizerKind::Lbfgs)
            .check()
            .unwrap()
            .fit(&data, &NoProgress)
            .unwrap();
        check_box_and_monotone(&data, &lb.kernel, &lb.outcome);
        assert!(lb.outcome.cost < lb.outcome.initial_cost);
        // Both are local searches from one start; the gradient method should
        // get at least most of the way that direct search does.
        let gain = hj.outcome.initial_cost - hj.outcome.cost;
        assert!(
            lb.outcome.cost < hj.outcome.cost + 0.2 * gain,
            "hj {} lbfgs {}",
            hj.outcome.cost,
            lb.outcome.cost
        );
    }

    #[test]
    fn hard_cases_stay_finite_and_inside() {
        let kernel_cases = [1e-4, 1e-10];
        // Two identical materials among others; all identical; N = 2.
        let mut rng = SplitMix64::new(8);
        let d = 20;
        let base: Vec<f64> = (0..d).map(|_| rng.range(-1.0, 1.0)).collect();
        let mut twins = Mat::<f64>::from_fn(6, d, |_, _| rng.range(-1.0, 1.0));
        for j in 0..d {
            twins[(0, j)] = base[j];
            twins[(1, j)] = base[j];
        }
        let same = Mat::<f64>::from_fn(5, d, |_, j| base[j]);
        let pair = Mat::<f64>::from_fn(2, d, |i, j| if i == 0 { base[j] } else { -base[j] });
        // A chrome-like material with values near 1e4 beside dark ones.
        let chrome = Mat::<f64>::from_fn(5, d, |i, j| {
            if i == 0 {
                1e4 * (j % 3) as f64
            } else {
                1e-3 * rng.range(0.0, 1.0)
            }
        });
        for (name, z, q) in [
            ("twins", twins, 2),
            ("same", same, 2),
            ("pair", pair, 1),
            ("chrome", chrome, 2),
        ] {
            let mut z = z;
            for j in 0..d {
                let m: f64 = (0..z.nrows()).map(|i| z[(i, j)]).sum::<f64>() / z.nrows() as f64;
                (0..z.nrows()).for_each(|i| z[(i, j)] -= m);
            }
            let data = GramData::new(&z * z.transpose(), d).unwrap();
            for &noise in &kernel_cases {
                for (kind, learn) in [
                    (OptimizerKind::HookeJeeves, false),
                    (OptimizerKind::Lbfgs, false),
                    (OptimizerKind::Lbfgs, true),
                ] {
                    let fit = GplvmParams::new(q)
                        .noise(noise)
                        .optimizer(kind)
                        .learn_kernel(learn)
                        .check()
                        .unwrap()
                        .fit(&data, &NoProgress);
                    let fit = fit.unwrap_or_else(|e| panic!("{name} mu={noise} {kind:?}: {e}"));
                    let o = &fit.outcome;
                    assert!(o.cost.is_finite(), "{name} {noise} {kind:?}");
                    assert!(
                        o.latent.as_ref().norm_max() <= 1.0,
                        "{name} {noise} {kind:?}"
                    );
                    let k = fit.kernel.matrix(o.latent.as_ref());
                    assert!(
                        k.llt(faer::Side::Lower).is_ok(),
                        "{name} {noise}: K not SPD"
                    );
                }
            }
        }
        // N = 1, or q >= N: a clear error, not a NaN.
        let one = GramData::new(Mat::from_fn(1, 1, |_, _| 1.0), 3).unwrap();
        let e = GplvmParams::new(1)
            .check()
            .unwrap()
            .fit(&one, &NoProgress)
            .unwrap_err()
            .to_string();
        assert!(e.contains("q = 1") && e.contains("N = 1"), "{e}");
    }

    /// Centre the columns of `z` and make its Gram data.
    fn gram_of(mut z: Mat<f64>) -> GramData {
        let (n, d) = (z.nrows(), z.ncols());
        for j in 0..d {
            let m: f64 = (0..n).map(|i| z[(i, j)]).sum::<f64>() / n as f64;
            (0..n).for_each(|i| z[(i, j)] -= m);
        }
        GramData::new(&z * z.transpose(), d).unwrap()
    }

    fn learned(data: &GramData, q: usize, noise: f64) -> Fit {
        GplvmParams::new(q)
            .noise(noise)
            .optimizer(OptimizerKind::Lbfgs)
            .learn_kernel(true)
            .check()
            .unwrap()
            .fit(data, &NoProgress)
            .unwrap()
    }

    #[test]
    fn a_learned_kernel_lowers_the_cost_and_is_its_own_optimum() {
        use crate::gplvm::kernel::{LEARNED_LENGTH_SCALE_RANGE, LEARNED_NOISE_RANGE};
        let data = curve(25, 3);
        let fixed = GplvmParams::new(2)
            .optimizer(OptimizerKind::Lbfgs)
            .check()
            .unwrap()
            .fit(&data, &NoProgress)
            .unwrap();
        let fit = learned(&data, 2, 1e-4);
        assert!(fit.learned_kernel && !fixed.learned_kernel);
        check_box_and_monotone(&data, &fit.kernel, &fit.outcome);
        assert!(fit.outcome.cost < fixed.outcome.cost, "{fit:?}");
        let k = fit.kernel;
        assert!(
            (LEARNED_LENGTH_SCALE_RANGE.0..=LEARNED_LENGTH_SCALE_RANGE.1).contains(&k.length_scale)
        );
        assert!((LEARNED_NOISE_RANGE.0..=LEARNED_NOISE_RANGE.1).contains(&k.noise));
        // At the learned kernel, the dense cost rises when either
        // hyperparameter moves by 1% in either direction (unless at a bound).
        let x = fit.outcome.latent.as_ref();
        let at = |l: f64, mu: f64| {
            let k = Kernel {
                length_scale: l,
                noise: mu,
            };
            cost(&k, &data, x).unwrap()
        };
        let best = at(k.length_scale, k.noise);
        // The points fill the box (the fit translated and scaled them with
        // the length scale), and the cost is the optimiser's own.
        let extent = |c: usize| {
            let v: Vec<f64> = (0..25).map(|i| x[(i, c)]).collect();
            (
                v.iter().cloned().fold(f64::INFINITY, f64::min),
                v.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            )
        };
        let (e0, e1) = (extent(0), extent(1));
        let half = (0.5 * (e0.1 - e0.0)).max(0.5 * (e1.1 - e1.0));
        assert!((half - 1.0).abs() < 1e-12, "{e0:?} {e1:?}");
        // Turned by any angle, the box is no smaller (to the search's step).
        for k in 0..90 {
            let (s, c) = (k as f64 * 2.0_f64.to_radians()).sin_cos();
            let r: Vec<[f64; 2]> = (0..25)
                .map(|i| [c * x[(i, 0)] - s * x[(i, 1)], s * x[(i, 0)] + c * x[(i, 1)]])
                .collect();
            let w = |d: usize| {
                let v = r.iter().map(|p| p[d]);
                0.5 * (v.clone().fold(f64::NEG_INFINITY, f64::max)
                    - v.fold(f64::INFINITY, f64::min))
            };
            assert!(
                w(0).max(w(1)) >= 1.0 - 1e-4,
                "turned by {}: {} {}",
                2 * k,
                w(0),
                w(1)
            );
        }
        assert!(((e0.0 + e0.1) / 2.0).abs() < 1e-12 && ((e1.0 + e1.1) / 2.0).abs() < 1e-12);
        for (dl, dm) in [(1.01, 1.0), (0.99, 1.0), (1.0, 1.01), (1.0, 0.99)] {
            let (l, mu) = (k.length_scale * dl, k.noise * dm);
            if l <= LEARNED_LENGTH_SCALE_RANGE.1
                && mu >= LEARNED_NOISE_RANGE.0
                && mu <= LEARNED_NOISE_RANGE.1
            {
                assert!(
                    at(l, mu) >= best - 1e-9 * best.abs(),
                    "{dl} {dm}: {} < {best}",
                    at(l, mu)
                );
            }
        }
    }

    #[test]
    fn learned_noise_driven_to_either_bound_stays_finite() {
        use crate::gplvm::kernel::LEARNED_NOISE_RANGE;
        let mut rng = SplitMix64::new(21);
        // Pure noise, no structure: the likelihood makes the materials
        // uncorrelated, by a noise as large as the signal or by a length
        // scale at its lower bound (with unit signal variance the two
        // explain independent data equally).
        let noise = gram_of(Mat::from_fn(12, 400, |_, _| rng.range(-1.0, 1.0)));
        let fit = learned(&noise, 2, 1e-4);
        let k = fit.kernel.matrix(fit.outcome.latent.as_ref());
        let most = (0..12)
            .flat_map(|i| (0..12).filter(move |&j| j != i).map(move |j| (i, j)))
            .fold(0.0f64, |m, (i, j)| m.max(k[(i, j)] / k[(i, i)]));
        assert!(most < 0.2, "correlation {most} with {:?}", fit.kernel);
        // Exactly on a smooth 1-D curve, with twins: the noise wants zero.
        let exact = gram_of(Mat::from_fn(14, 60, |i, j| {
            let t = (i / 2) as f64 * 0.4;
            (t * (1.0 + j as f64 * 0.05)).sin()
        }));
        let fit = learned(&exact, 1, 1e-4);
        assert!(fit.kernel.noise < 1e-6, "{:?}", fit.kernel);
        for f in [&fit, &learned(&noise, 2, 1.0)] {
            let o = &f.outcome;
            assert!(o.cost.is_finite() && o.latent.as_ref().norm_max() <= 1.0);
            assert!(f.kernel.noise >= LEARNED_NOISE_RANGE.0);
            let k = f.kernel.matrix(o.latent.as_ref());
            assert!(
                k.llt(faer::Side::Lower).is_ok(),
                "K not SPD: {:?}",
                f.kernel
            );
        }
    }

    #[test]
    fn parameters_are_checked() {
        assert!(GplvmParams::new(2).noise(0.0).check().is_err());
        // The defaults' optimiser is L-BFGS, which can learn the kernel;
        // Hooke-Jeeves cannot.
        assert_eq!(GplvmParams::new(2).optimizer, OptimizerKind::default());
        assert!(GplvmParams::new(2).learn_kernel(true).check().is_ok());
        let e = GplvmParams::new(2)
            .optimizer(OptimizerKind::HookeJeeves)
            .learn_kernel(true)
            .check()
            .unwrap_err();
        assert!(e.to_string().contains("L-BFGS"), "{e}");
        assert!(GplvmParams::new(2).length_scale(f64::NAN).check().is_err());
        assert!(GplvmParams::new(0).check().is_err());
        assert!(
            GplvmParams::new(2)
                .min_step(1.0)
                .initial_step(0.5)
                .check()
                .is_err()
        );
    }

    #[test]
    fn same_model_for_one_and_two_threads() {
        let data = curve(20, 5);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    GplvmParams::new(2)
                        .check()
                        .unwrap()
                        .fit(&data, &NoProgress)
                        .unwrap()
                        .outcome
                        .latent
                })
        };
        assert_eq!(run(1), run(2));
    }
}
