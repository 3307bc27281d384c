//! Projected L-BFGS on the analytic gradient, within the box `[-1, 1]^q`.
//!
//! Variables at a bound whose gradient pushes outward are held fixed; the
//! two-loop recursion gives the direction on the free ones, and a
//! backtracking line search on the projected path `P(x + a p)` enforces
//! sufficient decrease, so the cost never rises.
//!
//! With [`Lbfgs::learn_kernel`] the kernel's length scale and noise are
//! variables too, as `ln l` and `ln mu` within
//! [`LEARNED_LENGTH_SCALE_RANGE`] and [`LEARNED_NOISE_RANGE`]: the maximum
//! likelihood estimate of the kernel together with the latent points, as
//! general GPLVM implementations fit it.

use std::collections::VecDeque;

use faer::Mat;

use super::{BOX, Optimizer, Outcome, Problem};
use crate::error::Result;
use crate::gplvm::incremental::DriftStats;
use crate::gplvm::kernel::{Kernel, LEARNED_LENGTH_SCALE_RANGE, LEARNED_NOISE_RANGE};
use crate::gplvm::likelihood::cost_and_full_gradient;
use crate::progress::Progress;

/// The default stall window: ten iterations.
pub const STALL_WINDOW: usize = 10;
/// The default stall tolerance: ten iterations that gain less than 0.1% of
/// the whole descent end it. On synthetic sets of 100, 200 and 400
/// materials (16x16x32) the search then stops after 183, 292 and 281
/// iterations, at or below the cost Hooke-Jeeves reaches (35% below, 0.2%
/// above, 26% below), where running to the iteration cap took 647, 1247
/// and 1449 (docs/performance.md).
pub const STALL_TOLERANCE: f64 = 1e-3;

/// L-BFGS settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lbfgs {
    /// Pairs of history kept.
    pub memory: usize,
    /// Iteration cap.
    pub max_iterations: u64,
    /// Stop when the projected gradient's max norm, relative to `d`, is below this.
    pub gradient_tolerance: f64,
    /// Stop when an iteration lowers the cost by less than this, relatively.
    pub cost_tolerance: f64,
    /// Stop when the last `stall_window` iterations together lowered the
    /// cost by at most `stall_tolerance` of all the search has lowered it
    /// (0 turns this off). Not with a learned kernel: learning the noise
    /// first lowers the cost by far more than the points' later moves, which
    /// would then look like a stall.
    pub stall_window: usize,
    /// See `stall_window`.
    pub stall_tolerance: f64,
    /// Learn the kernel's length scale and noise with the latent points
    /// (the problem's kernel is then the start).
    pub learn_kernel: bool,
}

impl Default for Lbfgs {
    fn default() -> Self {
        Lbfgs {
            memory: 10,
            max_iterations: 2000,
            gradient_tolerance: 1e-9,
            cost_tolerance: 1e-13,
            stall_window: STALL_WINDOW,
            stall_tolerance: STALL_TOLERANCE,
            learn_kernel: false,
        }
    }
}

fn flat(m: &Mat<f64>) -> Vec<f64> {
    (0..m.nrows())
        .flat_map(|i| (0..m.ncols()).map(move |c| (i, c)))
        .map(|(i, c)| m[(i, c)])
        .collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Is a variable pinned at a bound of `(lo, hi)` by a gradient pointing outward?
fn pinned(x: f64, g: f64, (lo, hi): (f64, f64)) -> bool {
    (x <= lo && g > 0.0) || (x >= hi && g < 0.0)
}

/// The variables: the latent points row by row, then `ln l` and `ln mu`
/// when the kernel is learned.
struct Layout {
    n: usize,
    q: usize,
    kernel: Kernel,
    learn: bool,
}

impl Layout {
    fn bounds(&self) -> Vec<(f64, f64)> {
        let mut b = vec![BOX; self.n * self.q];
        if self.learn {
            let ln = |(lo, hi): (f64, f64)| (lo.ln(), hi.ln());
            b.push(ln(LEARNED_LENGTH_SCALE_RANGE));
            b.push(ln(LEARNED_NOISE_RANGE));
        }
        b
    }

    fn pack(&self, latent: &Mat<f64>, kernel: &Kernel) -> Vec<f64> {
        let mut v = flat(latent);
        if self.learn {
            v.push(kernel.length_scale.ln());
            v.push(kernel.noise.ln());
        }
        v
    }

    fn latent(&self, v: &[f64]) -> Mat<f64> {
        Mat::from_fn(self.n, self.q, |i, c| v[i * self.q + c])
    }

    fn kernel(&self, v: &[f64]) -> Kernel {
        if self.learn {
            let m = self.n * self.q;
            // exp(ln(lo)) can round below lo (exp(ln(1e-8)) is
            // 9.999999999999982e-9): the kernel read back stays in its range.
            let back = |x: f64, (lo, hi): (f64, f64)| x.exp().clamp(lo, hi);
            Kernel {
                length_scale: back(v[m], LEARNED_LENGTH_SCALE_RANGE),
                noise: back(v[m + 1], LEARNED_NOISE_RANGE),
            }
        } else {
            self.kernel
        }
    }
}

impl Optimizer for Lbfgs {
    fn name(&self) -> &'static str {
        super::OptimizerKind::Lbfgs.name()
    }

    fn minimize(
        &self,
        problem: &Problem<'_>,
        start: Mat<f64>,
        progress: &dyn Progress,
    ) -> Result<Outcome> {
        let layout = Layout {
            n: start.nrows(),
            q: start.ncols(),
            kernel: problem.kernel,
            learn: self.learn_kernel,
        };
        let bounds = layout.bounds();
        let project = |v: f64, (lo, hi): (f64, f64)| v.clamp(lo, hi);
        let eval = |v: &[f64]| -> Result<(f64, Vec<f64>)> {
            let kernel = layout.kernel(v);
            let (c, g) = cost_and_full_gradient(&kernel, problem.data, layout.latent(v).as_ref())?;
            let mut flat_g = flat(&g.latent);
            if layout.learn {
                flat_g.extend([g.log_length_scale, g.log_noise]);
            }
            Ok((c, flat_g))
        };
        let mut x: Vec<f64> = layout
            .pack(&start, &problem.kernel)
            .iter()
            .zip(&bounds)
            .map(|(&v, &b)| project(v, b))
            .collect();
        let (mut f, mut g) = eval(&x)?;
        let initial_cost = f;
        let mut history = vec![f];
        let mut pairs: VecDeque<(Vec<f64>, Vec<f64>, f64)> = VecDeque::new();
        let (mut iterations, mut evaluations) = (0u64, 1u64);
        let scale = problem.data.d() as f64;
        progress.start("optimise", self.max_iterations);
        while iterations < self.max_iterations {
            let free: Vec<bool> = (0..x.len())
                .map(|k| !pinned(x[k], g[k], bounds[k]))
                .collect();
            let pg: Vec<f64> = g
                .iter()
                .zip(&free)
                .map(|(gi, &fr)| if fr { *gi } else { 0.0 })
                .collect();
            if pg.iter().fold(0.0f64, |a, v| a.max(v.abs())) <= self.gradient_tolerance * scale {
                break;
            }
            // Two-loop recursion on the free variables.
            let mut p = pg.clone();
            let mut alphas = Vec::with_capacity(pairs.len());
            for (s, y, rho) in pairs.iter().rev() {
                let a = rho * dot(s, &p);
                p.iter_mut().zip(y).for_each(|(pi, yi)| *pi -= a * yi);
                alphas.push(a);
            }
            if let Some((s, y, _)) = pairs.back() {
                let gamma = dot(s, y) / dot(y, y);
                p.iter_mut().for_each(|v| *v *= gamma);
            } else {
                let gmax = pg.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                p.iter_mut().for_each(|v| *v *= 0.1 / gmax);
            }
            for ((s, y, rho), a) in pairs.iter().zip(alphas.iter().rev()) {
                let b = rho * dot(y, &p);
                p.iter_mut().zip(s).for_each(|(pi, si)| *pi += (a - b) * si);
            }
            p.iter_mut()
                .zip(&free)
                .for_each(|(v, &fr)| *v = if fr { -*v } else { 0.0 });
            if dot(&p, &pg) >= 0.0 {
                // Not a descent direction: restart from steepest descent.
                pairs.clear();
                let gmax = pg.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                p = pg.iter().map(|v| -0.1 * v / gmax).collect();
            }
            // Backtracking Armijo search along the projected path.
            let mut step = 1.0;
            let mut accepted = None;
            for _ in 0..40 {
                let xn: Vec<f64> = (0..x.len())
                    .map(|k| project(x[k] + step * p[k], bounds[k]))
                    .collect();
                let moved: Vec<f64> = xn.iter().zip(&x).map(|(a, b)| a - b).collect();
                evaluations += 1;
                if let Ok((fn_, gn)) = eval(&xn)
                    && fn_.is_finite()
                    && fn_ <= f + 1e-4 * dot(&g, &moved)
                    && fn_ < f
                {
                    accepted = Some((xn, fn_, gn, moved));
                    break;
                }
                step *= 0.5;
            }
            let Some((xn, fn_, gn, s)) = accepted else {
                break;
            };
            let y: Vec<f64> = gn.iter().zip(&g).map(|(a, b)| a - b).collect();
            let sy = dot(&s, &y);
            if sy > 1e-12 * dot(&y, &y).sqrt() * dot(&s, &s).sqrt() {
                if pairs.len() == self.memory {
                    pairs.pop_front();
                }
                pairs.push_back((s, y, 1.0 / sy));
            }
            let decrease = f - fn_;
            (x, f, g) = (xn, fn_, gn);
            iterations += 1;
            history.push(f);
            progress.advance(1);
            if decrease <= self.cost_tolerance * f.abs().max(1.0) {
                break;
            }
            let w = if self.learn_kernel {
                0
            } else {
                self.stall_window
            };
            if w > 0 && history.len() > w {
                let recent = history[history.len() - 1 - w] - f;
                if recent <= self.stall_tolerance * (initial_cost - f) {
                    break;
                }
            }
        }
        progress.finish();
        Ok(Outcome {
            latent: layout.latent(&x),
            kernel: layout.kernel(&x),
            cost: f,
            initial_cost,
            iterations,
            evaluations,
            pattern_moves: 0,
            drift: DriftStats::default(),
            history,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kernel_at_its_bounds_reads_back_inside_them() {
        // ln and exp do not round-trip: exp(ln(1e-8)) < 1e-8.
        assert!(LEARNED_NOISE_RANGE.0.ln().exp() < LEARNED_NOISE_RANGE.0);
        let layout = Layout {
            n: 1,
            q: 1,
            kernel: Kernel::default(),
            learn: true,
        };
        let latent = Mat::zeros(1, 1);
        let ((l0, l1), (m0, m1)) = (LEARNED_LENGTH_SCALE_RANGE, LEARNED_NOISE_RANGE);
        for (l, mu) in [(l0, m0), (l0, m1), (l1, m0), (l1, m1)] {
            let k = Kernel {
                length_scale: l,
                noise: mu,
            };
            let back = layout.kernel(&layout.pack(&latent, &k));
            assert!(
                (LEARNED_LENGTH_SCALE_RANGE.0..=LEARNED_LENGTH_SCALE_RANGE.1)
                    .contains(&back.length_scale)
                    && (LEARNED_NOISE_RANGE.0..=LEARNED_NOISE_RANGE.1).contains(&back.noise),
                "{k:?} read back as {back:?}"
            );
        }
    }
}
