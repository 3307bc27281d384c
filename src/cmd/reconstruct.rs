//! `brdf-atlas reconstruct`: the material at a latent point, as a MERL file.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use brdf_atlas_core::{Blend, BlendRule, LOW_CONFIDENCE_VARIANCE, Model};
use brdf_merl::Dims;
use brdf_merl::table::HEADER_BYTES;
use serde_json::json;

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
    /// Print one JSON record on stdout instead of the report: the point,
    /// every material's weight, the transform's formula, the plausibility
    /// figures and the confidence.
    #[arg(long)]
    pub json: bool,
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
pub fn write(
    model: &Model,
    x: &[f64],
    rule: BlendRule,
    out: &Path,
    report: &mut impl Write,
) -> Result<(), Error> {
    let t0 = Instant::now();
    let blend = model.at(x, rule)?;
    // The table and its plausibility figures from one pass over the store.
    let (table, plausibility) = blend.table_and_plausibility()?;
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
    if let Some((_, steps)) = blend.steps() {
        let moved: Vec<f64> = steps.iter().copied().filter(|&t| t > 0.0).collect();
        writeln!(
            report,
            "  (the GP's weights: the {} rule moved them towards a convex blend in {} of {} theta_h bins, by steps up to {})",
            rule.name(),
            moved.len(),
            steps.len(),
            moved.iter().copied().fold(0.0, f64::max)
        )?;
    }
    if blend.floor().is_some() {
        writeln!(
            report,
            "  (the GP's weights: the {} rule lifts each value softly onto a floor at {} times a convex blend's)",
            rule.name(),
            brdf_atlas_core::soft_floor::FLOOR_SHARE
        )?;
    }
    let confidence = blend.confidence();
    writeln!(
        report,
        "  plausibility: the clamp to >= 0 removes {} of the cosine-weighted reflectance \
         ({} of the values); largest directional albedo {:.4} (at {} degrees){}",
        percent(plausibility.clamped_reflectance),
        percent(plausibility.clamped_values),
        plausibility.max_albedo,
        plausibility.max_albedo_incidence,
        if plausibility.is_plausible() {
            ""
        } else {
            ": NOT physically plausible"
        }
    )?;
    writeln!(
        report,
        "  confidence: predictive variance {:.4} of the prior's 1 ({} blend)",
        confidence.variance,
        rule.name()
    )?;
    warn(model, x, &blend)?;
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

/// A share as a percentage with enough digits to tell 0.001% from 0.
fn percent(share: f64) -> String {
    format!("{:.4}%", 100.0 * share)
}

/// Warn on stderr where the model knows little, or the weights no longer
/// sum to about one (the blend falls back towards the mean material).
pub fn warn(model: &Model, x: &[f64], blend: &Blend<'_>) -> Result<(), Error> {
    let c = blend.confidence();
    if c.is_low() || (c.weight_sum - 1.0).abs() > 0.25 {
        eprintln!(
            "warning: {} knows little at {}: predictive variance {:.3} (above {} is low), \
             weights sum to {:.3}; the material there is mostly the database's mean",
            model.path().display(),
            point(x),
            c.variance,
            LOW_CONFIDENCE_VARIANCE,
            c.weight_sum
        );
    }
    if let Some((i, judged)) = model.file().marker_at(x)
        && !judged.gives_back()
    {
        eprintln!(
            "warning: {} is {}'s marker, but the model does not give it back there: its point {}",
            point(x),
            model.names()[i],
            judged.describe()
        );
    }
    Ok(())
}

/// The JSON record of a blend: point, weights by name (and where the rule
/// moved them, the weights it moved them towards and the step of each
/// `theta_h` bin), transform, plausibility, confidence.
pub fn record(
    model: &Model,
    rule: BlendRule,
    blend: &Blend<'_>,
) -> Result<serde_json::Value, Error> {
    let by_name = |w: &[f64]| -> serde_json::Map<String, serde_json::Value> {
        model
            .names()
            .iter()
            .zip(w)
            .map(|(n, w)| (n.clone(), json!(w)))
            .collect()
    };
    let weights = by_name(blend.weights());
    let moved = blend.steps().map(|(towards, steps)| {
        json!({
            "rule": "in theta_h bin b the weights are w + t_b (towards - w), w the weights above",
            "towards": by_name(towards),
            "theta_h_steps": steps,
        })
    });
    let moved = moved.or_else(|| {
        blend.floor().map(|towards| {
            json!({
                "rule": "each value is c h(g / c), g its value under the weights above, c under towards, \
                         h(r) = s + d ln(1 + e^((r - s) / d))",
                "towards": by_name(towards),
                "s": brdf_atlas_core::soft_floor::FLOOR_SHARE,
                "d": brdf_atlas_core::soft_floor::FLOOR_SOFTNESS,
            })
        })
    });
    let transform = model.file().transform;
    let (p, c) = (blend.plausibility()?, blend.confidence());
    Ok(json!({
        "model": model.path().display().to_string(),
        "point": blend.point(),
        "blend": rule.name(),
        "weights": weights,
        "weight_sum": blend.weights().iter().sum::<f64>(),
        "moved": moved,
        "transform": { "name": transform.name(), "formula": transform.formula() },
        "plausibility": p,
        "plausible": p.is_plausible(),
        "confidence": c,
        "low_confidence": c.is_low(),
    }))
}

/// Run `reconstruct`.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let (model, x) = args.target.open()?;
    if args.json {
        let blend = model.at(x, args.target.blend)?;
        blend.table()?.write(&args.out)?;
        let mut rec = record(&model, args.target.blend, &blend)?;
        rec["output"] = json!(args.out.display().to_string());
        warn(&model, x, &blend)?;
        writeln!(io::stdout().lock(), "{rec}")?;
    } else {
        write(
            &model,
            x,
            args.target.blend,
            &args.out,
            &mut io::stdout().lock(),
        )?;
    }
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
