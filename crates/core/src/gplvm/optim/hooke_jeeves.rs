//! Hooke-Jeeves direct search, as Soler et al. describe and their C++
//! implementation runs it.
//!
//! 1. Exploratory move: for each point and each coordinate, try `+step`,
//!    else `-step`, and keep what lowers the cost; moves that would leave
//!    the box are not tried.
//! 2. Pattern move: after a successful exploration from `X_prev` to `X`, jump
//!    to `X + (X - X_prev)` (projected into the box), explore around it, and
//!    keep the result while it is lower than the cost at `X` (Hooke and
//!    Jeeves 1961; without the exploration around the jump, a move of all N
//!    points at once almost never pays).
//! 3. No improvement: `step *= reduction`; stop when `step < min_step`.
//!
//! Each exploratory trial is O(N^2) through [`IncrementalCost`]; pattern
//! moves change every point and are evaluated by a fresh factorisation.

use faer::Mat;

use super::{BOX, Optimizer, Outcome, Problem, in_box};
use crate::error::Result;
use crate::gplvm::incremental::IncrementalCost;
use crate::gplvm::likelihood::cost;
use crate::progress::Progress;

/// Hooke-Jeeves settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HookeJeeves {
    /// First step length.
    pub initial_step: f64,
    /// Stop once the step falls below this.
    pub min_step: f64,
    /// Step reduction factor when nothing improves (0.5 by default, as in the C++ implementation).
    pub reduction: f64,
    /// Refactorise `K` after this many accepted rank-one updates at most
    /// (1024 by default: the interval adapts below it to the drift each
    /// refactorisation measures, starting at 16).
    pub refresh_every: u64,
    /// Safety cap on exploratory sweeps.
    pub max_sweeps: u64,
}

impl Default for HookeJeeves {
    fn default() -> Self {
        HookeJeeves {
            initial_step: 0.25,
            min_step: 1e-3,
            reduction: 0.5,
            refresh_every: 1024,
            max_sweeps: 100_000,
        }
    }
}

/// An improvement must beat rounding noise of the cost to count.
fn improves(delta: f64, cost: f64) -> bool {
    delta < -1e-13 * cost.abs().max(1.0)
}

impl HookeJeeves {
    /// One exploratory sweep over every coordinate of every point; `true` if anything improved.
    ///
    /// `+step` is tried before `-step` and `-step` only counts when `+step`
    /// does not improve; when both stay in the box, both are evaluated in
    /// one pass ([`IncrementalCost::trial_pair`]), since `+step` rarely
    /// improves (about one trial in seven).
    fn explore(
        &self,
        s: &mut IncrementalCost<'_>,
        step: f64,
        evaluations: &mut u64,
    ) -> Result<bool> {
        let mut improved = false;
        let (mut plus, mut minus) = (vec![0.0; s.q()], vec![0.0; s.q()]);
        for i in 0..s.n() {
            for c in 0..s.q() {
                plus.copy_from_slice(s.point(i));
                minus.copy_from_slice(s.point(i));
                plus[c] += step;
                minus[c] -= step;
                let (pair, one);
                let trials: &[_] = match (in_box(plus[c]), in_box(minus[c])) {
                    (true, true) => {
                        pair = s.trial_pair(i, [&plus, &minus]);
                        &pair
                    }
                    (true, false) => {
                        one = [s.trial(i, &plus)];
                        &one
                    }
                    (false, true) => {
                        one = [s.trial(i, &minus)];
                        &one
                    }
                    (false, false) => &[],
                };
                *evaluations += trials.len() as u64;
                let cost = s.cost();
                if let Some(&t) = trials.iter().find(|t| improves(t.delta, cost)) {
                    s.accept(t)?;
                    improved = true;
                }
            }
        }
        Ok(improved)
    }
}

impl Optimizer for HookeJeeves {
    fn name(&self) -> &'static str {
        super::OptimizerKind::HookeJeeves.name()
    }

    fn minimize(
        &self,
        problem: &Problem<'_>,
        start: Mat<f64>,
        progress: &dyn Progress,
    ) -> Result<Outcome> {
        let mut s = IncrementalCost::new(
            problem.kernel,
            problem.data,
            start.as_ref(),
            self.refresh_every,
        )?;
        let initial_cost = s.cost();
        let levels = ((self.initial_step / self.min_step)
            .log(1.0 / self.reduction)
            .ceil()
            .max(0.0) as u64)
            + 1;
        progress.start("optimise", levels);
        let (mut step, mut evaluations, mut iterations, mut pattern_moves) =
            (self.initial_step, 0u64, 0u64, 0u64);
        let mut history = vec![initial_cost];
        while step >= self.min_step && iterations < self.max_sweeps {
            iterations += 1;
            let base = s.latent();
            if self.explore(&mut s, step, &mut evaluations)? {
                // Pattern moves: jump by the last change, explore around the
                // new base, and keep it only if that beats the current point.
                let (mut prev, mut cur, mut cur_cost) = (base, s.latent(), s.cost());
                loop {
                    let next = Mat::from_fn(cur.nrows(), cur.ncols(), |i, c| {
                        (2.0 * cur[(i, c)] - prev[(i, c)]).clamp(BOX.0, BOX.1)
                    });
                    evaluations += 1;
                    if s.set_all(next.as_ref()).is_ok() {
                        self.explore(&mut s, step, &mut evaluations)?;
                        if improves(s.cost() - cur_cost, cur_cost) {
                            pattern_moves += 1;
                            (prev, cur, cur_cost) = (cur, s.latent(), s.cost());
                            continue;
                        }
                    }
                    s.set_all(cur.as_ref())?;
                    break;
                }
            } else {
                step *= self.reduction;
                progress.advance(1);
            }
            history.push(s.cost());
        }
        progress.finish();
        s.refresh()?;
        let latent = s.latent();
        let final_cost = cost(&problem.kernel, problem.data, latent.as_ref())?;
        Ok(Outcome {
            latent,
            kernel: problem.kernel,
            cost: final_cost,
            initial_cost,
            iterations,
            evaluations,
            pattern_moves,
            drift: s.stats(),
            history,
        })
    }
}
