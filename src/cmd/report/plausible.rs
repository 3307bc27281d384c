//! The report's plausibility section: at a grid of latent points of each
//! transform's q = 2 model, how much reflectance the clamp to `>= 0` removes,
//! the largest directional albedo, and the confidence, under the GP's
//! weights and under the plausible rule; and the leave-one-out cost of the
//! rule. A table in report.md, `plausibility.csv`, and `plausibility.png`.

use std::io::{self, Write};
use std::path::Path;

use brdf_atlas_core::{BlendRule, TransformKind};

use super::csv::e;
use super::measure::{PlausibilityRow, Results};
use super::write_file;
use crate::error::Error;

/// Nearest-rank quantile of a sorted slice.
fn quantile(sorted: &[f64], p: f64) -> f64 {
    sorted[((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

/// The section of report.md.
pub fn markdown(w: &mut dyn Write, r: &Results) -> io::Result<()> {
    if r.plausibility.is_empty() {
        return Ok(());
    }
    writeln!(
        w,
        "## Plausibility: is every point of the map a physical material?\n"
    )?;
    writeln!(
        w,
        "![Clamped share of reflectance over the map](plausibility.png)\n\n\
         At the centres of a grid over the map's default view, each point's material \
         is reconstructed with the GP's weights (`gp`, the default) and with the \
         plausible rule (`--blend plausible`: in each theta_h bin of the table where \
         the clamp would remove more than 0.05% of that bin's reflectance, the GP's \
         weights moved towards a convex blend of the materials just far enough that it \
         does not). **Clamped**: the share of the cosine-weighted reflectance \
         that the clamp to >= 0 removes. **Albedo**: the largest directional albedo \
         (at most 1 for a physical material). **Low confidence**: predictive variance \
         above 0.5. The picture shows the clamped share per grid cell (log scale, white \
         at 0.001% and below, black at 10% and above).\n"
    )?;
    writeln!(
        w,
        "| transform | rule | points | clamped median | p99 | worst | over 1% | worst albedo | albedo over 1 | low confidence |"
    )?;
    writeln!(w, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for t in [TransformKind::Log, TransformKind::Raw] {
        for rule in [BlendRule::Gp, BlendRule::Plausible] {
            let rows: Vec<&PlausibilityRow> = r
                .plausibility
                .iter()
                .filter(|p| p.transform == t && p.rule == rule)
                .collect();
            if rows.is_empty() {
                continue;
            }
            let mut c: Vec<f64> = rows.iter().map(|p| p.clamped_reflectance).collect();
            c.sort_by(f64::total_cmp);
            let albedo = rows.iter().map(|p| p.max_albedo).fold(0.0, f64::max);
            writeln!(
                w,
                "| {} | {} | {} | {:.4}% | {:.4}% | {:.4}% | {} | {:.3} | {} | {} |",
                t.name(),
                rule.name(),
                rows.len(),
                100.0 * quantile(&c, 0.5),
                100.0 * quantile(&c, 0.99),
                100.0 * c[c.len() - 1],
                c.iter().filter(|&&v| v > 0.01).count(),
                albedo,
                rows.iter().filter(|p| p.max_albedo > 1.0).count(),
                rows.iter().filter(|p| p.variance > 0.5).count(),
            )?;
        }
    }
    writeln!(w)?;
    for t in [TransformKind::Log, TransformKind::Raw] {
        let gp = r.loo_row(t, "gplvm", 2);
        let pl = r.loo_row(t, "gplvm-plausible", 2);
        if let (Some(gp), Some(pl)) = (gp, pl) {
            writeln!(
                w,
                "Leave-one-out, {} transform, q = 2: cosine-weighted log RMSE {:.5} with the \
                 GP's weights, {:.5} with the plausible rule ({:+.1}%); reflectance RMSE {:.4} \
                 and {:.4} ({:+.1}%).\n",
                t.name(),
                gp.log,
                pl.log,
                100.0 * (pl.log / gp.log - 1.0),
                gp.raw,
                pl.raw,
                100.0 * (pl.raw / gp.raw - 1.0)
            )?;
        }
    }
    Ok(())
}

/// `plausibility.csv`.
pub fn csv(dir: &Path, r: &Results) -> Result<(), Error> {
    write_file(&dir.join("plausibility.csv"), |w| {
        writeln!(
            w,
            "transform,rule,x,y,clamped_reflectance,clamped_values,max_albedo,variance"
        )?;
        for p in &r.plausibility {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{}",
                p.transform.name(),
                p.rule.name(),
                p.x[0],
                p.x[1],
                e(p.clamped_reflectance),
                e(p.clamped_values),
                e(p.max_albedo),
                e(p.variance)
            )?;
        }
        Ok(())
    })
}

/// Cell size of `plausibility.png`, pixels.
const CELL: usize = 24;
/// Gap between panels, pixels.
const GAP: usize = 8;

/// `plausibility.png`: one panel per transform (rows: log, raw) and rule
/// (columns: gp, plausible), each cell grey by log10 of its clamped share.
pub fn picture(dir: &Path, r: &Results, grid: usize) -> Result<(), Error> {
    if r.plausibility.is_empty() || grid == 0 {
        return Ok(());
    }
    let side = grid * CELL;
    let (w, h) = (2 * side + 3 * GAP, 2 * side + 3 * GAP);
    let mut rgb = vec![255u8; w * h * 3];
    for (pi, t) in [TransformKind::Log, TransformKind::Raw].iter().enumerate() {
        for (ri, rule) in [BlendRule::Gp, BlendRule::Plausible].iter().enumerate() {
            let rows: Vec<&PlausibilityRow> = r
                .plausibility
                .iter()
                .filter(|p| p.transform == *t && p.rule == *rule)
                .collect();
            if rows.len() != grid * grid {
                continue;
            }
            let (ox, oy) = (GAP + ri * (side + GAP), GAP + pi * (side + GAP));
            for (k, p) in rows.iter().enumerate() {
                // 1e-5 (0.001%) -> white, 1e-1 (10%) -> black.
                let s = (p.clamped_reflectance.max(1e-12).log10() + 5.0) / 4.0;
                let v = (255.0 * (1.0 - s.clamp(0.0, 1.0))).round() as u8;
                let (cx, cy) = (k % grid, k / grid);
                for y in 0..CELL - 1 {
                    for x in 0..CELL - 1 {
                        let at = ((oy + cy * CELL + y) * w + ox + cx * CELL + x) * 3;
                        rgb[at..at + 3].copy_from_slice(&[v, v, v]);
                    }
                }
            }
        }
    }
    write_file(&dir.join("plausibility.png"), |file| {
        let mut enc = png::Encoder::new(file, w as u32, h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let encoding = |e: png::EncodingError| match e {
            png::EncodingError::IoError(e) => e,
            e => io::Error::other(e),
        };
        let mut wr = enc.write_header().map_err(encoding)?;
        wr.write_image_data(&rgb).map_err(encoding)?;
        wr.finish().map_err(encoding)
    })
}
