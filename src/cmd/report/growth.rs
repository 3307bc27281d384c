//! How the fit grows with the number of materials (`report --growth`):
//! synthetic databases of each size at 16 x 16 x 32 bins (so the store pass
//! is cheap and the optimiser is what is timed), fitted with `fit`'s
//! settings by both optimisers.

use std::io::{self, Write};
use std::path::Path;
use std::time::Instant;

use brdf_atlas_core::{
    DEFAULT_TRANSFORM, Dataset, GplvmParams, GramData, NoProgress, OptimizerKind, Precision,
    build_scratch_store, default_kernel,
};
use brdf_merl::Dims;

use super::plot::{Axis, COLORS, Series, chart};
use super::results::{GrowthRow, Results};
use super::steps::Steps;
use super::write_file;
use crate::error::Error;
use crate::format::secs;

/// Bins of the synthetic materials: small, so the store pass and the
/// Gram product stay a small part of each fit.
const DIMS: Dims = Dims {
    theta_h: 16,
    theta_d: 16,
    phi_d: 32,
};

/// Seed of the synthetic databases (the same materials on every run).
const SEED: u64 = 1;

/// Fit a synthetic database of each of `sizes` materials with both
/// optimisers, in `work` (removed as it goes).
pub fn measure(
    sizes: &[usize],
    work: &Path,
    steps: &mut Steps,
    r: &mut Results,
) -> Result<(), Error> {
    for &n in sizes {
        steps.say(&format!(
            "growth: {n} synthetic materials at {DIMS}, both optimisers"
        ))?;
        let dir = work.join(format!("growth-{n}"));
        brdf_merl::synth::write_dir(&dir, n, DIMS, SEED)?;
        let data = Dataset::open_dir(&dir)?;
        let store = dir.join("default.store");
        let (_, y) = build_scratch_store(
            &data,
            DEFAULT_TRANSFORM,
            Precision::F32,
            &store,
            &NoProgress,
        )?;
        let gram = GramData::new(y, DIMS.values())?;
        let kernel = default_kernel(n);
        for optimizer in [OptimizerKind::HookeJeeves, OptimizerKind::Lbfgs] {
            let params = GplvmParams::new(2)
                .length_scale(kernel.length_scale)
                .noise(kernel.noise)
                .optimizer(optimizer)
                .check()?;
            let t = Instant::now();
            let fit = params.fit(&gram, &NoProgress)?;
            r.growth.push(GrowthRow {
                n,
                optimizer,
                time: t.elapsed(),
                cost: fit.outcome.cost,
                evaluations: fit.outcome.evaluations,
                refactorisations: fit.outcome.drift.refreshes,
            });
        }
        std::fs::remove_dir_all(&dir).map_err(|source| Error::Write { path: dir, source })?;
    }
    Ok(())
}

/// `growth.csv`.
pub fn csv(dir: &Path, r: &Results) -> Result<(), Error> {
    write_file(&dir.join("growth.csv"), |w| {
        writeln!(
            w,
            "materials,optimizer,seconds,cost,evaluations,refactorisations"
        )?;
        for g in &r.growth {
            writeln!(
                w,
                "{},{},{:.4},{},{},{}",
                g.n,
                g.optimizer.name(),
                g.time.as_secs_f64(),
                g.cost,
                g.evaluations,
                g.refactorisations
            )?;
        }
        Ok(())
    })
}

/// `growth.png`: optimiser time against the number of materials, log-log.
pub fn picture(dir: &Path, r: &Results) -> Result<(), Error> {
    let series: Vec<Series> = [OptimizerKind::HookeJeeves, OptimizerKind::Lbfgs]
        .into_iter()
        .enumerate()
        .map(|(k, o)| Series {
            name: o.name().to_string(),
            color: COLORS[k],
            points: r
                .growth
                .iter()
                .filter(|g| g.optimizer == o)
                .map(|g| (g.n as f64, g.time.as_secs_f64()))
                .collect(),
            markers_only: false,
        })
        .collect();
    chart(
        &dir.join("growth.png"),
        &format!("Fit time by number of materials ({DIMS} synthetic)"),
        Axis {
            label: "materials N",
            log: true,
            integer: false,
        },
        Axis {
            label: "optimiser time, s",
            log: true,
            integer: false,
        },
        &series,
    )
}

/// The growth section of `report.md`; nothing without `--growth`.
pub fn markdown(w: &mut dyn Write, r: &Results) -> io::Result<()> {
    if r.growth.is_empty() {
        return Ok(());
    }
    writeln!(w, "## Growth with the number of materials\n")?;
    writeln!(
        w,
        "Synthetic materials (`brdf-atlas synth`'s generator, seed {SEED}) at {DIMS} bins, log \
         transform, q = 2 and `fit`'s other defaults; the time is the optimiser's alone. The \
         exponent is the slope of log time against log N from the size before. Table: \
         `growth.csv`.\n"
    )?;
    writeln!(
        w,
        "| materials | optimiser | time | exponent | cost | evaluations | refactorisations |"
    )?;
    writeln!(w, "|---|---|---|---|---|---|---|")?;
    for (k, g) in r.growth.iter().enumerate() {
        let before = r.growth[..k]
            .iter()
            .rev()
            .find(|b| b.optimizer == g.optimizer && b.n < g.n);
        let exponent = before.map_or("".to_string(), |b| {
            let e =
                (g.time.as_secs_f64() / b.time.as_secs_f64()).ln() / (g.n as f64 / b.n as f64).ln();
            format!("{e:.1}")
        });
        writeln!(
            w,
            "| {} | {} | {} | {exponent} | {:.6e} | {} | {} |",
            g.n,
            g.optimizer.name(),
            secs(g.time),
            g.cost,
            g.evaluations,
            g.refactorisations
        )?;
    }
    writeln!(w, "\n![fit time by number of materials](growth.png)\n")
}
