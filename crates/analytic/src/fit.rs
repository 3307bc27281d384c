//! Levenberg-Marquardt in a box, from fixed starts: the fit of an
//! [`Analytic`] model to a table's [`Samples`].
//!
//! Every start runs a few iterations; the best (the first of equals) runs
//! on to convergence. The Jacobian is taken by forward differences (the
//! models are a few lines each and the step is small against every
//! parameter's range); a step that leaves the box is clamped onto it and
//! kept only if it lowers the error. Everything runs on one thread in a
//! fixed order, so a table always gives the same bits; callers fit many
//! tables in parallel.

use faer::prelude::*;
use faer::{Col, Mat, Side};

use crate::analytic::Analytic;
use crate::samples::Samples;

/// How a fit runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitParams {
    /// Iterations every start runs before the best is chosen.
    pub scout: usize,
    /// Most iterations of the chosen start, in all.
    pub iterations: usize,
    /// Stop when an accepted step lowers the squared error by less than
    /// this share of it.
    pub tolerance: f64,
}

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            scout: 12,
            iterations: 80,
            tolerance: 1e-7,
        }
    }
}

impl FitParams {
    /// Set [`FitParams::scout`].
    pub fn scout(mut self, scout: usize) -> Self {
        self.scout = scout;
        self
    }

    /// Set [`FitParams::iterations`].
    pub fn iterations(mut self, iterations: usize) -> Self {
        self.iterations = iterations;
        self
    }

    /// Fit `M` to `samples` from its own starts ([`Analytic::starts`]).
    pub fn fit<M: Analytic>(&self, samples: &Samples) -> Fitted<M> {
        self.fit_from(samples, M::starts(samples.albedo()))
    }

    /// Fit `M` to `samples` from `starts`, tried in order.
    pub fn fit_from<M: Analytic>(&self, samples: &Samples, starts: Vec<M>) -> Fitted<M> {
        let mut runs: Vec<Run<M>> = starts.into_iter().map(|m| Run::new(m, samples)).collect();
        for run in &mut runs {
            run.iterate(samples, self.scout, self.tolerance);
        }
        let Some(mut best) = runs
            .into_iter()
            .reduce(|a, b| if b.cost < a.cost { b } else { a })
        else {
            // No starts: the model at its lower bounds.
            let model = M::from_params(&[]);
            return Fitted {
                error: samples.error(&model),
                model,
                iterations: 0,
            };
        };
        let left = self.iterations.saturating_sub(best.iterations);
        best.iterate(samples, left, self.tolerance);
        let model = M::from_params(&best.p);
        Fitted {
            error: samples.error(&model),
            model,
            iterations: best.iterations,
        }
    }
}

/// A fitted model and its table error ([`Samples::error`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted<M> {
    /// The model.
    pub model: M,
    /// Its table error: RMS of the cosine-weighted log-relative error.
    pub error: f64,
    /// Iterations the chosen start ran.
    pub iterations: usize,
}

/// One start's state.
struct Run<M> {
    p: Vec<f64>,
    bounds: Vec<(f64, f64)>,
    r: Vec<f64>,
    cost: f64,
    lambda: f64,
    iterations: usize,
    done: bool,
    _model: std::marker::PhantomData<M>,
}

impl<M: Analytic> Run<M> {
    fn new(model: M, s: &Samples) -> Run<M> {
        let bounds = M::bounds();
        let p = M::from_params(&model.to_params()).to_params();
        let mut r = vec![0.0; s.residual_count()];
        s.residuals(&M::from_params(&p), &mut r);
        let cost = sum_sq(&r);
        Run {
            p,
            bounds,
            r,
            cost,
            lambda: 1e-3,
            iterations: 0,
            done: false,
            _model: std::marker::PhantomData,
        }
    }

    fn iterate(&mut self, s: &Samples, count: usize, tolerance: f64) {
        for _ in 0..count {
            if self.done {
                return;
            }
            self.step(s, tolerance);
        }
    }

    /// One Levenberg-Marquardt iteration: a Jacobian, then damped steps
    /// until one lowers the error (or the damping gives up).
    fn step(&mut self, s: &Samples, tolerance: f64) {
        self.iterations += 1;
        let n = self.p.len();
        let m = self.r.len();
        let mut jac = vec![vec![0.0; m]; n];
        let mut probe = vec![0.0; m];
        for (j, col) in jac.iter_mut().enumerate() {
            let (lo, hi) = self.bounds[j];
            let mut h = 1e-6 * (hi - lo).max(1e-12);
            if self.p[j] + h > hi {
                h = -h;
            }
            let mut q = self.p.clone();
            q[j] += h;
            s.residuals(&M::from_params(&q), &mut probe);
            for (c, (a, b)) in col.iter_mut().zip(probe.iter().zip(&self.r)) {
                *c = (a - b) / h;
            }
        }
        // J^T J: each pair once (it is symmetric).
        let mut a = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            for j in 0..=i {
                let v = dot(&jac[i], &jac[j]);
                a[(i, j)] = v;
                a[(j, i)] = v;
            }
        }
        let g = Col::<f64>::from_fn(n, |i| -dot(&jac[i], &self.r));
        let scale = (0..n).map(|i| a[(i, i)]).fold(0.0, f64::max).max(1e-300);
        for _ in 0..12 {
            let damped = Mat::<f64>::from_fn(n, n, |i, j| {
                if i == j {
                    a[(i, i)] + self.lambda * (a[(i, i)] + 1e-9 * scale)
                } else {
                    a[(i, j)]
                }
            });
            let Ok(llt) = damped.llt(Side::Lower) else {
                self.lambda *= 4.0;
                continue;
            };
            let delta = llt.solve(&g);
            let q: Vec<f64> = (0..n)
                .map(|i| {
                    let (lo, hi) = self.bounds[i];
                    (self.p[i] + delta[i]).clamp(lo, hi)
                })
                .collect();
            s.residuals(&M::from_params(&q), &mut probe);
            let cost = sum_sq(&probe);
            if cost.is_finite() && cost < self.cost {
                let gain = (self.cost - cost) / self.cost.max(1e-300);
                self.p = q;
                std::mem::swap(&mut self.r, &mut probe);
                self.cost = cost;
                self.lambda = (self.lambda / 3.0).max(1e-9);
                self.done = gain < tolerance;
                return;
            }
            self.lambda *= 4.0;
        }
        self.done = true;
    }
}

/// `a . b` in four interleaved partial sums (independent chains the
/// compiler can put in one vector register), added in a fixed order: the
/// same bits on every CPU.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

fn sum_sq(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}
