//! Cheap albedo rules for a map's nodes, against the dense rule over the
//! full reconstruction of the default material at seeded random points of
//! the default view and of [-3, 3]^2: the per-pixel rule
//! ([`Quadrature::with_samples_shaped`], boxes along every axis) and the
//! banded rule ([`Quadrature::banded_shaped`]: every theta_h bin, boxes in
//! theta_d and phi_d), each with its rows and its time a point when many
//! points share a pass. `cargo run --release -p brdf-atlas-core --example
//! node_rules -- MODEL [POINTS]`.

use brdf_atlas_core::map_error::albedo_error;
use brdf_atlas_core::{AlbedoRequest, Atlas, Integration, Model, View};
use brdf_merl::Quadrature;
use brdf_merl::synth::SplitMix64;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: node_rules MODEL [POINTS]")?;
    let count: usize = args.next().map_or(Ok(64), |s| s.parse())?;
    let atlas = Atlas::new(Model::open(&path)?);
    let fine = atlas.albedo_rule().clone();
    let shape = atlas.shape().to_vec();
    let mut rules: Vec<(String, Quadrature)> = Vec::new();
    for s in [256, 1024, 4096] {
        rules.push((
            format!("shaped {s}"),
            Quadrature::with_samples_shaped(&fine, s, &shape),
        ));
    }
    for (d, p) in [(3, 2), (4, 4), (6, 6), (9, 9), (15, 15), (18, 30)] {
        rules.push((
            format!("banded {d} x {p}"),
            Quadrature::banded_shaped(&fine, d, p, &shape),
        ));
    }
    for (name, view) in [("default", View::default()), ("[-3,3]^2", View::wide())] {
        let mut rng = SplitMix64::new(7);
        let points: Vec<[f64; 2]> = (0..count)
            .map(|_| [rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)])
            .collect();
        let want = atlas.exact_albedos(&points, AlbedoRequest::new())?;
        for (rule_name, rule) in &rules {
            let t = std::time::Instant::now();
            let got = atlas.exact_albedos(
                &points,
                AlbedoRequest::new().integration(Integration::Rule(rule)),
            )?;
            let per_point = t.elapsed().as_secs_f64() / points.len() as f64;
            let (worst, mean) = albedo_error(&got, &want);
            println!(
                "{name:9} {rule_name:16} bins {:8}  max {worst:9.2e}  mean {:9.2e}  {:7.1} us/point",
                rule.len(),
                mean,
                1e6 * per_point
            );
        }
    }
    Ok(())
}
