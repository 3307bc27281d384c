//! What a reduced albedo rule costs in accuracy: the exact albedo (the
//! dense rule over the full reconstruction) against reduced rules
//! ([`Atlas::reduced_rule`], [`Quadrature::every_phi_d`]) and Monte Carlo
//! sampling ([`Quadrature::monte_carlo`]) at seeded random
//! points of the default view, of [-3, 3]^2 and at the materials' own
//! points, under the default material (the soft floor) and the GP's blend.
//! `cargo run --release -p brdf-atlas-core --example reduced_rule -- MODEL
//! [POINTS]`.

use std::time::Instant;

use brdf_atlas_core::{AlbedoRequest, Atlas, BlendRule, Integration, Model, View};
use brdf_merl::Quadrature;

/// Largest error of `got` against `want` relative to the reference's
/// largest channel, and relative per channel.
fn errors(got: &[[f64; 3]], want: &[[f64; 3]]) -> (f64, f64) {
    let (mut to_max, mut per) = (0.0f64, 0.0f64);
    for (g, w) in got.iter().zip(want) {
        let scale = w.iter().fold(1e-12f64, |a, v| a.max(v.abs()));
        for c in 0..3 {
            to_max = to_max.max((g[c] - w[c]).abs() / scale);
            per = per.max((g[c] - w[c]).abs() / w[c].abs().max(1e-12));
        }
    }
    (to_max, per)
}

fn points(count: usize, seed: u64, v: View) -> Vec<[f64; 2]> {
    let mut rng = brdf_merl::synth::SplitMix64::new(seed);
    (0..count)
        .map(|_| [rng.range(v.x0, v.x1), rng.range(v.y0, v.y1)])
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: reduced_rule MODEL [POINTS]")?;
    let count: usize = args.next().map_or(Ok(64), |s| s.parse())?;
    let atlas = Atlas::new(Model::open(&path)?);
    let dense = atlas.albedo_rule().clone();
    let latent = atlas.latent();
    let own: Vec<[f64; 2]> = (0..latent.nrows())
        .map(|i| [latent[(i, 0)], latent[(i, 1)]])
        .collect();
    let sets = [
        ("default view", points(count, 1, View::default())),
        ("[-3, 3]^2", points(count, 2, View::wide())),
        ("own points", own),
    ];
    let mut rules: Vec<(String, Quadrature)> =
        vec![("every 8th phi_d".into(), dense.every_phi_d(8))];
    for (d, p) in [(1, 8), (2, 1), (2, 4), (3, 6), (3, 12), (6, 12)] {
        for cubic in [false, true] {
            let name = format!("{} {d} x {p}", if cubic { "cubic" } else { "linear" });
            rules.push((name, atlas.reduced_rule(d, p, cubic)));
        }
    }
    for samples in [4096, 65536] {
        rules.push((
            format!("Monte Carlo {samples}"),
            dense.monte_carlo(samples, 5),
        ));
    }
    for rule in [BlendRule::Floor, BlendRule::Gp] {
        for (set, xs) in &sets {
            let t = Instant::now();
            let want = atlas.exact_albedos(xs, AlbedoRequest::new().rule(rule))?;
            println!(
                "{rule:?}, {set}, {} points: dense {} bins, {:.2} s",
                xs.len(),
                dense.len(),
                t.elapsed().as_secs_f64()
            );
            for (name, q) in &rules {
                let t = Instant::now();
                let got = atlas.exact_albedos(
                    xs,
                    AlbedoRequest::new()
                        .rule(rule)
                        .integration(Integration::Rule(q)),
                )?;
                let (to_max, per) = errors(&got, &want);
                println!(
                    "  {name:18} {:7} bins ({:5.2}%) {:.3} s  max err {:.4}% of largest channel, {:.4}% per channel",
                    q.len(),
                    100.0 * q.len() as f64 / dense.len() as f64,
                    t.elapsed().as_secs_f64(),
                    100.0 * to_max,
                    100.0 * per
                );
            }
        }
    }
    Ok(())
}
