//! Optimisers of the GPLVM cost over latent points in the box `[-1, 1]^q`.
//!
//! Both sit behind [`Optimizer`] so that they can be swapped and compared on
//! the cost they reach and the time they take.

mod hooke_jeeves;
mod lbfgs;

pub use hooke_jeeves::HookeJeeves;
pub use lbfgs::Lbfgs;

use faer::Mat;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::gplvm::incremental::DriftStats;
use crate::gplvm::kernel::Kernel;
use crate::gplvm::likelihood::GramData;
use crate::progress::Progress;

/// Lower and upper bound of every latent coordinate.
pub const BOX: (f64, f64) = (-1.0, 1.0);

/// What an optimiser minimises: the cost of latent points for this data and kernel.
pub struct Problem<'a> {
    /// Kernel hyperparameters (the start, when the optimiser learns them).
    pub kernel: Kernel,
    /// The normalised Gram matrix and `d`.
    pub data: &'a GramData,
}

/// The outcome of a minimisation.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Final latent points, `N x q`, inside the box.
    pub latent: Mat<f64>,
    /// The kernel at the end: the problem's, or the one learned with the points.
    pub kernel: Kernel,
    /// Cost at `latent`, recomputed densely.
    pub cost: f64,
    /// Cost at the start.
    pub initial_cost: f64,
    /// Iterations in the optimiser's own sense.
    pub iterations: u64,
    /// Cost evaluations (incremental or dense).
    pub evaluations: u64,
    /// Accepted pattern moves (Hooke-Jeeves only).
    pub pattern_moves: u64,
    /// Numerical health of the incremental updates (Hooke-Jeeves only).
    pub drift: DriftStats,
    /// The cost after each iteration.
    pub history: Vec<f64>,
}

/// A minimiser of the GPLVM cost.
pub trait Optimizer {
    /// Name for messages and files.
    fn name(&self) -> &'static str;
    /// Minimise from `start` (inside the box).
    fn minimize(
        &self,
        problem: &Problem<'_>,
        start: Mat<f64>,
        progress: &dyn Progress,
    ) -> Result<Outcome>;
}

/// The optimisers on offer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum OptimizerKind {
    /// Hooke-Jeeves direct search with O(N^2) rank-one updates (the paper's method).
    HookeJeeves,
    /// Projected L-BFGS on the analytic gradient, the default: it reaches a
    /// lower cost and a lower held-out error than Hooke-Jeeves in less time
    /// (docs/performance.md).
    #[default]
    Lbfgs,
}

impl OptimizerKind {
    /// `hooke-jeeves` or `lbfgs`.
    pub fn name(self) -> &'static str {
        match self {
            OptimizerKind::HookeJeeves => "hooke-jeeves",
            OptimizerKind::Lbfgs => "lbfgs",
        }
    }

    /// Parse a name given by [`OptimizerKind::name`].
    pub fn parse(s: &str) -> Option<OptimizerKind> {
        match s {
            "hooke-jeeves" | "hj" => Some(OptimizerKind::HookeJeeves),
            "lbfgs" | "l-bfgs" => Some(OptimizerKind::Lbfgs),
            _ => None,
        }
    }
}

pub(crate) fn in_box(v: f64) -> bool {
    (BOX.0..=BOX.1).contains(&v)
}
