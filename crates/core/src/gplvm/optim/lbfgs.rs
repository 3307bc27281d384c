//! Projected L-BFGS on the analytic gradient, within the box `[-1, 1]^q`.
//!
//! Variables at a bound whose gradient pushes outward are held fixed; the
//! two-loop recursion gives the direction on the free ones, and a
//! backtracking line search on the projected path `P(x + a p)` enforces
//! sufficient decrease, so the cost never rises.

use std::collections::VecDeque;

use faer::Mat;

use super::{BOX, Optimizer, Outcome, Problem};
use crate::error::Result;
use crate::gplvm::incremental::DriftStats;
use crate::gplvm::likelihood::cost_and_gradient;
use crate::progress::Progress;

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
}

impl Default for Lbfgs {
    fn default() -> Self {
        Lbfgs {
            memory: 10,
            max_iterations: 2000,
            gradient_tolerance: 1e-9,
            cost_tolerance: 1e-13,
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

/// Is coordinate `k` pinned at a bound by a gradient pointing outward?
fn pinned(x: f64, g: f64) -> bool {
    (x <= BOX.0 && g > 0.0) || (x >= BOX.1 && g < 0.0)
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
        let (n, q) = (start.nrows(), start.ncols());
        let shape = |v: &[f64]| Mat::from_fn(n, q, |i, c| v[i * q + c]);
        let eval = |v: &[f64]| -> Result<(f64, Vec<f64>)> {
            let (c, g) = cost_and_gradient(&problem.kernel, problem.data, shape(v).as_ref())?;
            Ok((c, flat(&g)))
        };
        let mut x: Vec<f64> = flat(&start).iter().map(|v| v.clamp(BOX.0, BOX.1)).collect();
        let (mut f, mut g) = eval(&x)?;
        let initial_cost = f;
        let mut history = vec![f];
        let mut pairs: VecDeque<(Vec<f64>, Vec<f64>, f64)> = VecDeque::new();
        let (mut iterations, mut evaluations) = (0u64, 1u64);
        let scale = problem.data.d() as f64;
        progress.start("optimise", self.max_iterations);
        while iterations < self.max_iterations {
            let free: Vec<bool> = x.iter().zip(&g).map(|(&xi, &gi)| !pinned(xi, gi)).collect();
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
                let xn: Vec<f64> = x
                    .iter()
                    .zip(&p)
                    .map(|(xi, pi)| (xi + step * pi).clamp(BOX.0, BOX.1))
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
        }
        progress.finish();
        Ok(Outcome {
            latent: shape(&x),
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
