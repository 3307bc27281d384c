//! `brdf-atlas reconstruct`: the material at a latent point, as a MERL file.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use brdf_atlas_core::Model;
use brdf_merl::Dims;
use brdf_merl::table::HEADER_BYTES;

use crate::args::ModelPoint;
use crate::error::Error;
use crate::format::{point, secs, size};

/// Write the material at a latent point as a MERL file.
///
/// The new material is the blend of the model's materials that the GPLVM
/// predicts at the point (values clamped to >= 0; bins no input measured
/// stay marked unmeasured). Prints the largest blend weights. The file
/// has the model's dims (90x90x180 for MERL data) and opens in BRDF
/// Explorer.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub target: ModelPoint,
    /// MERL `.binary` file to write.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub out: PathBuf,
}

/// Input materials by the size of their blend weight at `x`, largest
/// first: `(index, weight)`.
pub fn contributors(weights: &[f64]) -> Vec<(usize, f64)> {
    let mut order: Vec<(usize, f64)> = weights.iter().copied().enumerate().collect();
    order.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()).then(a.0.cmp(&b.0)));
    order
}

/// Reconstruct the full table at `x` and write it to `out` (atomically);
/// report the largest weights and the file.
pub fn write(model: &Model, x: &[f64], out: &Path, report: &mut impl Write) -> Result<(), Error> {
    let t0 = Instant::now();
    let blend = model.at(x)?;
    let table = blend.table()?;
    table.write(out)?;
    let elapsed = t0.elapsed();
    let weights = blend.weights();
    writeln!(
        report,
        "at {} in {}: largest blend weights",
        point(x),
        model.path().display()
    )?;
    for (i, w) in contributors(weights).into_iter().take(3) {
        writeln!(report, "  {w:>9.4}  {}", model.names()[i])?;
    }
    writeln!(
        report,
        "  (the {} weights sum to {:.4})",
        weights.len(),
        weights.iter().sum::<f64>()
    )?;
    let dims = table.dims();
    writeln!(
        report,
        "wrote {} ({dims}, {}) in {}",
        out.display(),
        size((HEADER_BYTES + 8 * dims.values()) as u64),
        secs(elapsed)
    )?;
    if dims != Dims::MERL {
        eprintln!(
            "warning: {} is {dims}, not {}: BRDF Explorer needs {}",
            out.display(),
            Dims::MERL,
            Dims::MERL
        );
    }
    Ok(())
}

/// Run `reconstruct`.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let (model, x) = args.target.open()?;
    write(&model, x, &args.out, &mut io::stdout().lock())?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contributors_rank_by_magnitude() {
        let order = contributors(&[0.1, -0.7, 0.5, 0.0]);
        let idx: Vec<usize> = order.iter().map(|p| p.0).collect();
        assert_eq!(idx, [1, 2, 0, 3]);
        assert_eq!(order[0].1, -0.7);
    }
}
