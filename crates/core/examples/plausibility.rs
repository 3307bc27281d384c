//! Plausibility and confidence of a model's reconstructions at random points
//! of the map's default view, under each blend rule.
//!
//! ```text
//! cargo run --release -p brdf-atlas-core --example plausibility -- MODEL [POINTS] [SEED]
//! ```
//!
//! `PLAUSIBILITY_RULES=floor,gp` chooses the rules swept (by default all
//! three: floor, the default, gp and plausible). `PLAUSIBILITY_LOO=1` adds
//! the leave-one-out errors of the rules. Prints, per rule, the distribution (median, 90th, 99th percentile, worst)
//! of the clamped share of reflectance, the clamped share of values and the
//! largest directional albedo, and how many points are low-confidence.

use brdf_atlas_core::{BlendRule, Model, NoProgress, View, loo};
use brdf_merl::synth::SplitMix64;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: plausibility MODEL [POINTS] [SEED]")?;
    let points: usize = args.next().map_or(Ok(200), |s| s.parse())?;
    let seed: u64 = args.next().map_or(Ok(1), |s| s.parse())?;
    let model = brdf_atlas_core::Atlas::new(Model::open(&path)?);
    if points > 0 {
        sweep(&model, points, seed)?;
    }
    if std::env::var_os("PLAUSIBILITY_LOO").is_some() {
        leave_one_out(&model)?;
    }
    Ok(())
}

/// Leave-one-out errors of the GP, of its weights projected onto convex
/// ones, of the convex blend the plausible rule steps towards, for kernels of several length scales (each narrowed by
/// `CONVEX_LENGTH_RATIO`), and of the plausible rule towards each at several
/// budgets.
fn leave_one_out(model: &Model) -> Result<(), Box<dyn std::error::Error>> {
    let (kernel, latent) = (model.file().kernel, model.latent().as_ref());
    let gp = loo::gp_predictor(&kernel, latent, true)?;
    let scales = [1.0, 0.5];
    let budgets = [5e-4, 1e-3, 1e-2];
    // The GP's weights constrained instead of adapted: the nearest
    // non-negative weights summing to at most one.
    let projected = loo::projected_predictor(gp.as_ref())?;
    let mut predictors = vec![gp.clone(), projected];
    let mut names = vec!["gp".to_string(), "gp projected to convex".to_string()];
    let mut moved = vec![0, 0];
    let (mut mixes, mut mix_names, mut mix_moved) = (vec![], vec![], vec![]);
    for l in scales {
        let k = brdf_atlas_core::Kernel {
            length_scale: l * kernel.length_scale,
            ..kernel
        };
        let convex = loo::convex_predictor(&k, latent)?;
        let rules = loo::plausible_predictors(
            model.store(),
            gp.as_ref(),
            convex.as_ref(),
            &budgets,
            &NoProgress,
        )?;
        let banded = loo::banded_steps(
            model.store(),
            gp.as_ref(),
            convex.as_ref(),
            &budgets,
            loo::Every::BIN,
            &NoProgress,
        )?;
        let lc = k.length_scale * loo::CONVEX_LENGTH_RATIO;
        for (b, steps) in budgets.iter().zip(banded) {
            let n = model.names().len();
            let moved_materials = (0..n)
                .filter(|&i| steps.chunks_exact(n).any(|band| band[i] > 0.0))
                .count();
            mix_names.push(format!(
                "banded l={lc:.3} budget={}% ({} of {} bands moved)",
                100.0 * b,
                steps.iter().filter(|&&t| t > 0.0).count(),
                steps.len()
            ));
            mix_moved.push(moved_materials);
            mixes.push(loo::Mix {
                from: 0,
                towards: predictors.len(),
                how: loo::Mixing::Steps(steps),
            });
        }
        mix_names.push(format!("soft floor under convex l={lc:.3}"));
        mix_moved.push(0);
        mixes.push(loo::Mix {
            from: 0,
            towards: predictors.len(),
            how: loo::Mixing::Floor,
        });
        predictors.push(convex);
        names.push(format!("convex l={lc:.3}"));
        moved.push(0);
        for (b, (p, steps)) in budgets.iter().zip(rules) {
            predictors.push(p);
            names.push(format!("plausible l={lc:.3} budget={}%", 100.0 * b));
            moved.push(steps.iter().filter(|&&t| t > 0.0).count());
        }
    }
    let ev = loo::evaluate_mixed(model.store(), &predictors, &mixes, &NoProgress)?;
    names.extend(mix_names);
    moved.extend(mix_moved);
    let base = ev.errors[0].log_total(ev.scored_rows);
    for ((name, e), m) in names.iter().zip(&ev.errors).zip(&moved) {
        let err = e.log_total(ev.scored_rows);
        println!(
            "leave-one-out {name:34} ln(1 + f cos cos) RMSE {err:.5} ({:+.1}% against gp)  reflectance RMSE {:.3}  moved {m}",
            100.0 * (err / base - 1.0),
            e.raw_total(ev.scored_rows)
        );
    }
    Ok(())
}

/// Plausibility at `points` random points of the default view, per rule.
fn sweep(
    model: &brdf_atlas_core::Atlas,
    points: usize,
    seed: u64,
) -> Result<(), Box<dyn std::error::Error>> {
    let view = View::default();
    let mut rng = SplitMix64::new(seed);
    let xs: Vec<[f64; 2]> = (0..points)
        .map(|_| [rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)])
        .collect();
    // `PLAUSIBILITY_RULES=plausible` (a comma-separated list) to sweep fewer rules.
    let rules: Vec<BlendRule> = match std::env::var("PLAUSIBILITY_RULES") {
        Ok(list) => list.split(',').filter_map(BlendRule::parse).collect(),
        Err(_) => vec![BlendRule::Floor, BlendRule::Gp, BlendRule::Plausible],
    };
    for rule in rules {
        let start = std::time::Instant::now();
        let (mut refl, mut vals, mut alb, mut low) = (vec![], vec![], vec![], 0);
        // Every point's figures from one pass over the store (the plausible
        // rule: its steps from one pass, then a pass a point).
        for (x, p) in xs
            .iter()
            .zip(model.plausibilities(&xs, rule, loo::Every::BIN)?)
        {
            if p.max_albedo > 1.0 && std::env::var_os("PLAUSIBILITY_SHOW").is_some() {
                let b = model.at(x, brdf_atlas_core::BlendRule::Gp)?;
                let w = b.gp_weights();
                let mut idx: Vec<usize> = (0..w.len()).collect();
                idx.sort_by(|&a, &c| w[c].abs().total_cmp(&w[a].abs()));
                let top: Vec<String> = idx[..6]
                    .iter()
                    .map(|&i| format!("{} {:.3}", model.names()[i], w[i]))
                    .collect();
                println!(
                    "  ({:.4}, {:.4}): largest directional albedo {:.3} at {} deg; sum {:.3}; {}",
                    x[0],
                    x[1],
                    p.max_albedo,
                    p.max_albedo_incidence,
                    w.iter().sum::<f64>(),
                    top.join(", ")
                );
            }
            refl.push(p.clamped_reflectance);
            vals.push(p.clamped_values);
            alb.push(p.max_albedo);
            low += usize::from(
                model
                    .at(x, brdf_atlas_core::BlendRule::Gp)?
                    .confidence()
                    .is_low(),
            );
        }
        println!(
            "{} ({} points, {:.1} s):",
            rule.name(),
            points,
            start.elapsed().as_secs_f64()
        );
        for (what, v) in [
            ("clamped reflectance %", &mut refl),
            ("clamped values %", &mut vals),
        ] {
            let q = quantiles(v);
            println!(
                "  {what:22} median {:.4}  p90 {:.4}  p99 {:.4}  worst {:.4}  (>1%: {})",
                100.0 * q[0],
                100.0 * q[1],
                100.0 * q[2],
                100.0 * q[3],
                v.iter().filter(|&&s| s > 0.01).count()
            );
        }
        let q = quantiles(&mut alb);
        println!(
            "  {:22} median {:.4}  p90 {:.4}  p99 {:.4}  worst {:.4}  (>1: {})",
            "max directional albedo",
            q[0],
            q[1],
            q[2],
            q[3],
            alb.iter().filter(|&&a| a > 1.0).count()
        );
        println!("  low confidence at {low} of {points} points");
    }
    Ok(())
}

/// Median, 90th and 99th percentiles (nearest rank) and the largest value.
fn quantiles(v: &mut [f64]) -> [f64; 4] {
    v.sort_by(f64::total_cmp);
    let at = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    [at(0.5), at(0.9), at(0.99), v[v.len() - 1]]
}
