//! The report's plausibility section: at a grid of latent points of each
//! transform's q = 2 model, how much reflectance the clamp to `>= 0` removes,
//! the largest directional albedo, and the confidence, under each blend
//! rule ([`RULES`]); and the leave-one-out cost of each. A table in report.md, `plausibility.csv`, and `plausibility.png`.

use std::io::{self, Write};
use std::path::Path;

use brdf_atlas_core::{Atlas, BlendRule, TransformKind, View};

use super::csv::e;
use super::plan::Plan;
use super::results::{PlausibilityRow, Results};
use super::write_file;
use crate::error::Error;

/// Nearest-rank quantile of a sorted slice.
fn quantile(sorted: &[f64], p: f64) -> f64 {
    sorted[((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

/// The section of report.md.
pub fn markdown(w: &mut dyn Write, r: &Results, plan: &Plan) -> io::Result<()> {
    let grid = plan.plausibility_grid;
    if r.plausibility.is_empty() {
        return Ok(());
    }
    let [quick, default, thorough] = super::plan::PLAUSIBILITY_GRID;
    writeln!(
        w,
        "## Plausibility: is every point of the map a physical material?\n"
    )?;
    writeln!(
        w,
        "![Clamped share of reflectance over the map](plausibility.png)\n\n\
         At the centres of a {grid} x {grid} grid over the map's default view ({quick} x \
         {quick} with `--quick`, {default} x {default} by default, {thorough} x {thorough} \
         with `--thorough`), each point's material is reconstructed with the soft floor (`floor`, the default: the GP's blend with \
         each value lifted softly onto a floor at 0.3 times a convex blend's), with the \
         GP's weights as they are (`--blend gp`) and with the plausible rule (`--blend \
         plausible`: in each theta_h bin of the table where the clamp would remove more \
         than 0.05% of that bin's reflectance, the GP's weights moved towards a convex \
         blend of the materials just far enough that it does not). **Clamped**: the share of the cosine-weighted reflectance \
         that the clamp to >= 0 removes. **Albedo**: the largest directional albedo \
         (at most 1 for a physical material). **Low confidence**: predictive variance \
         above 0.5. The picture shows the clamped share per grid cell (log scale, white \
         at 0.001% and below, black at 10% and above).{}\n",
        if plan.eighth {
            " With `--quick` the clamped shares are summed over every 8th phi_d bin \
             (each kept bin weighted as every bin is otherwise); the largest albedo and \
             the plausible rule's steps are the model's own."
        } else {
            ""
        }
    )?;
    writeln!(
        w,
        "| transform | kernel | rule | points | clamped median | p99 | worst | over 1% | worst albedo | albedo over 1 | low confidence |"
    )?;
    writeln!(w, "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for (t, kernel) in MODELS {
        for rule in RULES {
            let rows: Vec<&PlausibilityRow> = r
                .plausibility
                .iter()
                .filter(|p| p.transform == t && p.kernel == kernel && p.rule == rule)
                .collect();
            if rows.is_empty() {
                continue;
            }
            let mut c: Vec<f64> = rows.iter().map(|p| p.clamped_reflectance).collect();
            c.sort_by(f64::total_cmp);
            let albedo = rows.iter().map(|p| p.max_albedo).fold(0.0, f64::max);
            writeln!(
                w,
                "| {} | {} | {} | {} | {:.4}% | {:.4}% | {:.4}% | {} | {:.3} | {} | {} |",
                t.name(),
                kernel,
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
    if !r.spread.is_empty() {
        let items: Vec<String> = r
            .spread
            .iter()
            .map(|(t, kernel, d)| format!("{} with the {kernel} kernel {d:.4}", t.name()))
            .collect();
        writeln!(
            w,
            "How spread the map is (the median distance from a material to its nearest \
             neighbour in the latent plane, whose default view is [-1.1, 1.1]^2): {}.\n",
            items.join(", ")
        )?;
    }
    // Held out, against the GP of the fixed kernel's Hooke-Jeeves fit
    // (`fit`'s default model).
    for (t, gp_label, pl_label, what) in [
        (
            TransformKind::Log,
            r.kept_label,
            "gplvm-plausible",
            "fixed kernel",
        ),
        (
            TransformKind::Log,
            "gplvm-learned",
            "gplvm-learned-plausible",
            "learned kernel",
        ),
        (
            TransformKind::Raw,
            r.kept_label,
            "gplvm-plausible",
            "fixed kernel",
        ),
    ] {
        let base = r.loo_row(t, r.kept_label, 2);
        let (gp, pl) = (r.loo_row(t, gp_label, 2), r.loo_row(t, pl_label, 2));
        if let (Some(base), Some(gp), Some(pl)) = (base, gp, pl) {
            let rel = |v: f64, b: f64| 100.0 * (v / b - 1.0);
            writeln!(
                w,
                "Leave-one-out, {} transform, q = 2, {what}: cosine-weighted log RMSE {:.5} \
                 with the GP's weights ({:+.1}% against the fixed kernel's GP), {:.5} with the \
                 plausible rule ({:+.1}%); reflectance RMSE {:.4} and {:.4} ({:+.1}% and \
                 {:+.1}%).\n",
                t.name(),
                gp.log,
                rel(gp.log, base.log),
                pl.log,
                rel(pl.log, base.log),
                gp.raw,
                pl.raw,
                rel(gp.raw, base.raw),
                rel(pl.raw, base.raw)
            )?;
        }
    }
    for t in [TransformKind::Log, TransformKind::Raw] {
        let base = r.loo_row(t, r.kept_label, 2);
        if let (Some(base), Some(fl)) = (base, r.loo_row(t, "gplvm-floor", 2)) {
            writeln!(
                w,
                "Leave-one-out, {} transform, q = 2, fixed kernel, the GP's values lifted \
                 softly onto a floor at {} times the convex blend's (never clamped, and a \
                 function of the point's weights only): log RMSE {:.5} ({:+.1}% against the \
                 GP's weights).\n",
                t.name(),
                brdf_atlas_core::soft_floor::FLOOR_SHARE,
                fl.log,
                100.0 * (fl.log / base.log - 1.0),
            )?;
        }
        if let (Some(base), Some(pr)) = (base, r.loo_row(t, "gplvm-projected", 2)) {
            writeln!(
                w,
                "Leave-one-out, {} transform, q = 2, fixed kernel, the GP's weights projected \
                 to the nearest convex ones (never clamped, and a function of the point \
                 only): log RMSE {:.5} ({:+.1}% against the GP's weights).\n",
                t.name(),
                pr.log,
                100.0 * (pr.log / base.log - 1.0),
            )?;
        }
    }
    Ok(())
}

/// The blend rules of the plausibility grid, in the order of the table and
/// of the picture's columns: the default first.
const RULES: [BlendRule; 3] = [BlendRule::Floor, BlendRule::Gp, BlendRule::Plausible];

/// The models of the plausibility grid: transform and kernel, in the order
/// of the table and of the picture's rows.
const MODELS: [(TransformKind, &str); 3] = [
    (TransformKind::Log, "fixed"),
    (TransformKind::Log, "learned"),
    (TransformKind::Raw, "fixed"),
];

/// The centres of a `grid x grid` partition of the map's default view, row
/// by row from the top.
fn grid_points(grid: usize) -> Vec<[f64; 2]> {
    let v = View::default();
    let at = |k: usize, a: f64, b: f64| a + (b - a) * (k as f64 + 0.5) / grid as f64;
    (0..grid)
        .flat_map(|j| (0..grid).map(move |i| [at(i, v.x0, v.x1), at(grid - 1 - j, v.y0, v.y1)]))
        .collect()
}

/// `model` (of `transform`) at the grid's points under every blend rule,
/// the clamp's figures on the plan's bins.
pub fn measure(
    model: &Atlas,
    transform: TransformKind,
    kernel: &'static str,
    plan: &Plan,
    r: &mut Results,
) -> Result<(), Error> {
    let (points, every) = (grid_points(plan.plausibility_grid), plan.every());
    // The predictive variance depends on the point, not on the rule.
    let variance = points
        .iter()
        .map(|x| {
            Ok(model
                .at(x, brdf_atlas_core::BlendRule::Gp)?
                .confidence()
                .variance)
        })
        .collect::<Result<Vec<f64>, Error>>()?;
    // The soft floor's and the GP's figures of every point from one pass
    // over the store, the plausible rule's from its own (its steps from one
    // pass, then one more for all the points).
    let (gp, floor) = model.plausibilities_gp_and_floor(&points, every)?;
    let plausible = model.plausibilities(&points, BlendRule::Plausible, every)?;
    for (rule, figures) in RULES.into_iter().zip([floor, gp, plausible]) {
        for ((&x, p), &variance) in points.iter().zip(figures).zip(&variance) {
            r.plausibility.push(PlausibilityRow {
                transform,
                kernel,
                rule,
                x,
                clamped_reflectance: p.clamped_reflectance,
                clamped_values: p.clamped_values,
                max_albedo: p.max_albedo,
                variance,
            });
        }
    }
    Ok(())
}

/// The median over the points of the distance to the nearest other point.
pub fn median_nearest(x: faer::MatRef<'_, f64>) -> f64 {
    let (n, q) = (x.nrows(), x.ncols());
    let mut d: Vec<f64> = (0..n)
        .map(|i| {
            (0..n)
                .filter(|&j| j != i)
                .map(|j| (0..q).map(|c| (x[(i, c)] - x[(j, c)]).powi(2)).sum::<f64>())
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
        .collect();
    d.sort_by(f64::total_cmp);
    if n < 2 { 0.0 } else { d[(n - 1) / 2] }
}

/// `plausibility.csv`.
pub fn csv(dir: &Path, r: &Results) -> Result<(), Error> {
    write_file(&dir.join("plausibility.csv"), |w| {
        writeln!(
            w,
            "transform,kernel,rule,x,y,clamped_reflectance,clamped_values,max_albedo,variance"
        )?;
        for p in &r.plausibility {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{}",
                p.transform.name(),
                p.kernel,
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

/// `plausibility.png`: one panel per model (rows: log with the fixed
/// kernel, log with the learned kernel, raw with the fixed kernel; a model
/// not measured leaves its row blank) and rule (columns: [`RULES`]),
/// each cell grey by log10 of its clamped share.
pub fn picture(dir: &Path, r: &Results, grid: usize) -> Result<(), Error> {
    if r.plausibility.is_empty() || grid == 0 {
        return Ok(());
    }
    let side = grid * CELL;
    let (w, h) = (
        RULES.len() * (side + GAP) + GAP,
        MODELS.len() * (side + GAP) + GAP,
    );
    let mut rgb = vec![255u8; w * h * 3];
    for (pi, (t, kernel)) in MODELS.iter().enumerate() {
        for (ri, rule) in RULES.iter().enumerate() {
            let rows: Vec<&PlausibilityRow> = r
                .plausibility
                .iter()
                .filter(|p| p.transform == *t && p.kernel == *kernel && p.rule == *rule)
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
