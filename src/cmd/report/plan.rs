//! What the report runs: the settings each part sweeps, from the command's
//! arguments and the number of materials.

use std::time::Duration;

use brdf_atlas_core::OptimizerKind;
use brdf_atlas_core::loo::Every;

use super::Args;

/// Default `--q-max`.
pub const DEFAULT_Q_MAX: usize = 8;
/// `--q-max` under `--quick` when not given.
pub const QUICK_Q_MAX: usize = 3;

/// `--q-max`'s help, with its defaults.
pub fn q_max_help() -> String {
    format!(
        "Largest latent dimension of the leave-one-out sweep [default: {DEFAULT_Q_MAX}, {QUICK_Q_MAX} with --quick]"
    )
}

/// The settings each part of the report sweeps.
pub struct Plan {
    /// Largest latent dimension of the leave-one-out sweep (below the
    /// number of materials).
    pub q_max: usize,
    /// Optimiser of the fits for q = 1..q_max (the other one fits q = 2 too).
    pub optimizer: OptimizerKind,
    /// Hooke-Jeeves' minimum steps of the sweep.
    pub min_steps: Vec<f64>,
    /// Quadrature sample counts of the log map.
    pub samples: Vec<usize>,
    /// Map sizes timed.
    pub sizes: Vec<usize>,
    /// Reference pixels per side of the map-accuracy grid.
    pub grid: usize,
    /// Size of the map timed for each sample count.
    pub timed_size: usize,
    /// Latent points reconstructed for the precision comparison.
    pub points: usize,
    /// Random points of the default view the exact-albedo rules are
    /// compared at.
    pub rule_points: usize,
    /// Time short runs three times and keep the median.
    pub repeat: bool,
    /// Points per side of the plausibility grid.
    pub plausibility_grid: usize,
    /// Measure the prepared map (its lattice takes minutes to build).
    pub prepare: bool,
    /// Judge the leave-one-out passes, the plausible rule's held-out steps
    /// and the plausibility grid on every 8th phi_d bin only.
    pub eighth: bool,
}

/// A run shorter than this is timed three times under `repeat` (the median kept).
pub const REPEAT_BELOW: Duration = Duration::from_millis(250);

/// The sample count `--thorough` adds to the sample sweep.
pub const THOROUGH_SAMPLES: usize = 4096;
/// The map size `--thorough` adds to the size sweep.
pub const THOROUGH_SIZE: usize = 1024;
/// The plausibility grid's side under `--quick`, by default and under
/// `--thorough`.
pub const PLAUSIBILITY_GRID: [usize; 3] = [2, 6, 10];

impl Plan {
    /// The plan for `args` on `n` materials.
    pub fn new(args: &Args, n: usize) -> Plan {
        let asked = args.q_max.map_or(
            if args.quick {
                QUICK_Q_MAX
            } else {
                DEFAULT_Q_MAX
            },
            |q| q as usize,
        );
        let q_max = asked.min(n.saturating_sub(1)).max(1);
        let optimizer = args.optimizer.into();
        if args.quick {
            return Plan {
                q_max,
                optimizer,
                min_steps: vec![1e-1, 1e-2, 1e-3],
                samples: vec![16, 64, 256],
                // A quarter of the pixels of the default plan's maps: the
                // time of a per-pixel map is proportional to its pixels,
                // which three sizes show as well as four.
                sizes: vec![32, 64, 128],
                grid: 2,
                timed_size: 64,
                points: 2,
                rule_points: 16,
                repeat: false,
                plausibility_grid: PLAUSIBILITY_GRID[0],
                prepare: args.prepare,
                eighth: true,
            };
        }
        let mut samples = vec![16, 64, 256, 1024];
        let mut sizes = vec![128, 256, 512];
        if args.thorough {
            samples.push(THOROUGH_SAMPLES);
            sizes.push(THOROUGH_SIZE);
        }
        Plan {
            q_max,
            optimizer,
            min_steps: vec![1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4],
            samples,
            sizes,
            grid: 4,
            timed_size: if args.thorough { 256 } else { 128 },
            points: 4,
            rule_points: 64,
            repeat: true,
            plausibility_grid: PLAUSIBILITY_GRID[1 + usize::from(args.thorough)],
            prepare: args.prepare || args.thorough,
            eighth: false,
        }
    }

    /// The bins the leave-one-out passes, the plausible rule's held-out
    /// steps and the plausibility grid are judged on.
    pub fn every(&self) -> Every {
        if self.eighth {
            Every::EIGHTH
        } else {
            Every::BIN
        }
    }

    /// The optimiser that is not the plan's.
    pub fn other_optimizer(&self) -> OptimizerKind {
        match self.optimizer {
            OptimizerKind::HookeJeeves => OptimizerKind::Lbfgs,
            OptimizerKind::Lbfgs => OptimizerKind::HookeJeeves,
        }
    }
}
