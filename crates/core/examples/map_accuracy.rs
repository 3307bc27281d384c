//! What each way of drawing a log-transform map buys: the albedo error of
//! the per-pixel quadrature (at several sample counts; the map panel's
//! preview uses 64) and of the default
//! (the albedo field where it applies, [`brdf_atlas_core::field`]),
//! against the dense rule applied to the full reconstruction, at random
//! pixels of a 1024 x 1024 map of the default view and of a view a hundred
//! times smaller; and the time of the 1024 x 1024 map (the field's first
//! map of a domain builds it, later ones reuse it: both are shown).
//! `cargo run --release -p brdf-atlas-core --example map_accuracy -- MODEL
//! [PIXELS] [RULE]`: RULE is the material mapped, `floor` (the default) or
//! `gp`; the reference is the dense rule on that material's reconstruction.

use std::time::Instant;

use brdf_atlas_core::map_error::reference_albedo;
use brdf_atlas_core::{AlbedoMap, AlbedoMethod, BlendRule, Model, View};

const SIDE: usize = 1024;

/// Seeded random pixels of a `SIDE x SIDE` map.
fn pixels(count: usize, seed: u64) -> Vec<(usize, usize)> {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((s >> 33) as usize) % SIDE
    };
    (0..count).map(|_| (next(), next())).collect()
}

/// Largest and mean error of `got` against `want`, relative to the
/// reference's largest channel.
fn errors(got: &[[f64; 3]], want: &[[f64; 3]]) -> (f64, f64) {
    let (mut worst, mut sum) = (0.0f64, 0.0f64);
    for (g, w) in got.iter().zip(want) {
        let scale = w.iter().fold(1e-9f64, |a, v| a.max(v.abs()));
        for c in 0..3 {
            let e = (g[c] - w[c]).abs() / scale;
            worst = worst.max(e);
            sum += e;
        }
    }
    (worst, sum / (3 * got.len().max(1)) as f64)
}

fn at(map: &AlbedoMap, px: &[(usize, usize)]) -> Vec<[f64; 3]> {
    px.iter()
        .map(|&(x, y)| map.rgb[y * map.width + x].map(f64::from))
        .collect()
}

fn describe(method: &AlbedoMethod) -> String {
    match method {
        AlbedoMethod::Field {
            nodes,
            patches,
            estimate,
        } => format!("field: {nodes} nodes, {patches} patches, estimate {estimate:.1e}"),
        AlbedoMethod::SampledField {
            samples,
            nodes,
            patches,
            estimate,
            check,
        } => format!(
            "sampled field: {samples} samples, {nodes} nodes, {patches} patches, estimate {estimate:.1e}{}",
            check.map_or(String::new(), |c| format!(
                ", checked at {} points: {:.1e} / {:.1e}",
                c.points, c.worst, c.mean
            ))
        ),
        AlbedoMethod::Quadrature { samples, bins } => format!("quadrature {samples} ({bins} bins)"),
        AlbedoMethod::Lattice {
            nodes,
            tolerance,
            share,
        } => format!("prepared lattice: {nodes} nodes, tol {tolerance:.1e}, {share:.2} of it"),
        AlbedoMethod::Linear => "linear".into(),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: map_accuracy MODEL [PIXELS] [RULE]")?;
    let count: usize = std::env::args().nth(2).map_or(Ok(24), |s| s.parse())?;
    let rule = match std::env::args().nth(3) {
        Some(name) => BlendRule::parse(&name).ok_or("RULE: floor or gp")?,
        None => BlendRule::default(),
    };
    let model = brdf_atlas_core::Atlas::new(Model::open(&path)?);
    let views = [
        ("default", View::default()),
        ("1/100", View::zoomed_hundredfold()),
    ];
    println!(
        "view     method                                        max_err  mean_err  first_s  again_s"
    );
    for (k, (name, view)) in views.into_iter().enumerate() {
        let px = pixels(count, 11 + k as u64);
        let points: Vec<[f64; 2]> = px
            .iter()
            .map(|&(x, y)| view.pixel_to_latent(x as f64, y as f64, SIDE, SIDE))
            .collect();
        let want = points
            .iter()
            .map(|x| reference_albedo(&model, x, rule, model.albedo_rule()))
            .collect::<Result<Vec<_>, _>>()?;
        for samples in [Some(16), Some(64), Some(256), Some(1024), Some(4096), None] {
            // A fresh model for each, so that "first" includes what a map builds.
            let fresh = brdf_atlas_core::Atlas::new(Model::open(&path)?);
            // Full 1024 x 1024 maps for the default and the default sample count only.
            let timed = samples.is_none_or(|s| s == brdf_atlas_core::DEFAULT_SAMPLES);
            let (map, first, again) = if timed {
                let t = Instant::now();
                let map = fresh.map(
                    brdf_atlas_core::MapRequest::new(SIDE, SIDE)
                        .view(view)
                        .samples(samples)
                        .rule(rule),
                )?;
                let first = t.elapsed().as_secs_f64();
                let t = Instant::now();
                fresh.map(
                    brdf_atlas_core::MapRequest::new(SIDE, SIDE)
                        .view(view)
                        .samples(samples)
                        .rule(rule),
                )?;
                (map, first, t.elapsed().as_secs_f64())
            } else {
                // Each pixel's value under the per-pixel rule is the same at
                // any size: a 1 x 1 map round each pixel gives it.
                let got = points
                    .iter()
                    .map(|x| {
                        let d = 1e-9;
                        let v = View {
                            x0: x[0] - d,
                            x1: x[0] + d,
                            y0: x[1] - d,
                            y1: x[1] + d,
                        };
                        let m = fresh.map(
                            brdf_atlas_core::MapRequest::new(1, 1)
                                .view(v)
                                .samples(samples)
                                .rule(rule),
                        )?;
                        Ok(m.rgb[0].map(f64::from))
                    })
                    .collect::<Result<Vec<_>, Box<dyn std::error::Error>>>()?;
                let (worst, mean) = errors(&got, &want);
                println!(
                    "{name:8} {:45} {worst:8.2e} {mean:9.2e} {:>8} {:>8}",
                    format!("quadrature {}", samples.unwrap_or(0)),
                    "-",
                    "-"
                );
                continue;
            };
            let (worst, mean) = errors(&at(&map, &px), &want);
            println!(
                "{name:8} {:45} {worst:8.2e} {mean:9.2e} {first:8.3} {again:8.3}",
                describe(&map.method)
            );
        }
    }
    Ok(())
}
