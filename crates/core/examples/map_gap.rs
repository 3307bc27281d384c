//! How far the map's albedo is from the plausible rule's materials: at random
//! points of the default view, the albedo of the GP's blend (what the map
//! draws) against the albedo of the material `reconstruct --blend plausible`
//! writes there, both by the dense rule over the full table.
//!
//! ```text
//! cargo run --release -p brdf-atlas-core --example map_gap -- MODEL [POINTS] [SEED]
//! ```
//!
//! Prints one line a point (the two RGB albedos and the largest channel's
//! difference relative to the plausible material's largest channel), then
//! the distribution of that difference.

use brdf_atlas_core::{Model, View};
use brdf_merl::synth::SplitMix64;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: map_gap MODEL [POINTS] [SEED]")?;
    let count: usize = args.next().map_or(Ok(100), |s| s.parse())?;
    let seed: u64 = args.next().map_or(Ok(1), |s| s.parse())?;
    let model = brdf_atlas_core::Atlas::new(Model::open(&path)?);
    let view = View::default();
    let mut rng = SplitMix64::new(seed);
    let points: Vec<Vec<f64>> = (0..count)
        .map(|_| vec![rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)])
        .collect();
    let t = std::time::Instant::now();
    let plausible = model.plausible_blends(&points)?;
    eprintln!(
        "the plausible rule at {count} points in one pass: {:.2} s",
        t.elapsed().as_secs_f64()
    );
    let rule = model.albedo_rule();
    let mut gaps = Vec::with_capacity(count);
    for (x, blend) in points.iter().zip(&plausible) {
        let gp_table = model.at(x, brdf_atlas_core::BlendRule::Gp)?.table()?;
        let table = blend.table()?;
        let gp = rule.integrate(|b| gp_table.rgb_or_zero(b));
        let pl = rule.integrate(|b| table.rgb_or_zero(b));
        let largest = pl.iter().copied().fold(0.0, f64::max);
        let gap = (0..3).map(|c| (gp[c] - pl[c]).abs()).fold(0.0, f64::max) / largest;
        println!(
            "({:.4}, {:.4})  map (GP) {:.4?}  plausible {:.4?}  gap {:.2}%",
            x[0],
            x[1],
            gp,
            pl,
            100.0 * gap
        );
        gaps.push(gap);
    }
    gaps.sort_by(f64::total_cmp);
    let q = |f: f64| 100.0 * gaps[((gaps.len() - 1) as f64 * f).round() as usize];
    println!(
        "gap: median {:.2}%, 90th percentile {:.2}%, 99th {:.2}%, worst {:.2}%",
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0)
    );
    Ok(())
}
