//! How smooth the map's albedo is along a line across the default view,
//! for the GP's blend as the tools clamp it, for the same blend without the
//! clamp, and for the soft-floor rule: the error of the polynomial through
//! exact albedos (the dense rule over the full reconstruction) at
//! Chebyshev-Lobatto points of several degrees, at 256 evenly spaced points
//! of the line, relative to each point's largest channel. A function a
//! polynomial of low degree follows is one a map can draw from few exact
//! albedos. `cargo run --release -p brdf-atlas-core --example
//! map_smoothness -- MODEL [Y]` (the line `y = Y`, default -0.12, from
//! x = -1.1 to 1.1).

use std::f64::consts::PI;

use brdf_atlas_core::{BlendRule, Model, TransformKind, View};

/// Albedos (RGB) of the three variants at `x`: GP clamped, GP unclamped, floor.
fn albedos(model: &Model, x: [f64; 2]) -> Result<[[f64; 3]; 3], Box<dyn std::error::Error>> {
    let rule = model.albedo_rule();
    let store = model.store();
    let (bins, rows) = (model.dims().bins(), store.rows());
    let log = model.file().transform == TransformKind::Log;
    let mut out = [[0.0f64; 3]; 3];
    let mut values = vec![0.0f64; rows];
    for (k, blend_rule) in [BlendRule::Gp, BlendRule::Floor].into_iter().enumerate() {
        let blend = model.at(&x, blend_rule)?;
        blend.transformed_rows(0, &mut values);
        for (&b, &w) in rule.bins().iter().zip(rule.weights()) {
            let b = b as usize;
            // The inverse transform before its clamp (TransformKind::formula).
            let (ci, co) = model.dims().angles_of(b).cosines();
            let cc = (ci * co).max(0.0);
            let inverse = |t: f64| match (log, cc < 1e-6) {
                (false, _) => t,
                (true, true) => 0.0,
                (true, false) => t.exp_m1() / cc,
            };
            let channels = (0..3).map(|c| c * bins + b);
            for (c, row) in channels.enumerate() {
                if store.unmeasured()[row] != 0 {
                    continue;
                }
                let f = inverse(values[row]);
                let (clamped, unclamped) = if k == 0 { (0, Some(1)) } else { (2, None) };
                out[clamped][c] += w * f.max(0.0);
                if let Some(u) = unclamped {
                    out[u][c] += w * f;
                }
            }
        }
    }
    Ok(out)
}

/// The polynomial through `values` at the Chebyshev-Lobatto points
/// `cos(pi j / d)` of [-1, 1], at `t` (barycentric form).
fn interpolate(values: &[[f64; 3]], t: f64) -> [f64; 3] {
    let d = values.len() - 1;
    let (mut num, mut den) = ([0.0f64; 3], 0.0f64);
    for (j, v) in values.iter().enumerate() {
        let xj = (PI * j as f64 / d as f64).cos();
        if (t - xj).abs() < 1e-15 {
            return *v;
        }
        let mut w = if j % 2 == 0 { 1.0 } else { -1.0 };
        if j == 0 || j == d {
            w *= 0.5;
        }
        let q = w / (t - xj);
        den += q;
        (0..3).for_each(|c| num[c] += q * v[c]);
    }
    num.map(|n| n / den)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: map_smoothness MODEL [Y]")?;
    let y: f64 = args.next().map_or(Ok(-0.12), |s| s.parse())?;
    let model = Model::open(&path)?;
    let h = View::default().x1;
    let at = |t: f64| [h * t, y];
    let names = ["gp (clamped)", "gp without the clamp", "floor"];
    let checks: Vec<f64> = (0..256).map(|k| -1.0 + 2.0 * k as f64 / 255.0).collect();
    let truth: Vec<[[f64; 3]; 3]> = checks
        .iter()
        .map(|&t| albedos(&model, at(t)))
        .collect::<Result<_, _>>()?;
    println!(
        "line y = {y}, x from {} to {h}; error at 256 points, share of the largest channel",
        -h
    );
    println!(
        "{:24} {:>8} {:>8}  (max / median over the line)",
        "variant", "degree", "error"
    );
    let degrees = [8usize, 16, 32, 64, 128];
    let mut nodes: Vec<Vec<[[f64; 3]; 3]>> = Vec::new();
    for &d in &degrees {
        nodes.push(
            (0..=d)
                .map(|j| albedos(&model, at((PI * j as f64 / d as f64).cos())))
                .collect::<Result<_, _>>()?,
        );
    }
    for (v, name) in names.iter().enumerate() {
        for (d, values) in degrees.iter().zip(&nodes) {
            let values: Vec<[f64; 3]> = values.iter().map(|a| a[v]).collect();
            let mut errors: Vec<f64> = checks
                .iter()
                .zip(&truth)
                .map(|(&t, want)| {
                    let (got, want) = (interpolate(&values, t), want[v]);
                    let scale = want.iter().fold(1e-12f64, |a, w| a.max(w.abs()));
                    (0..3)
                        .map(|c| (got[c] - want[c]).abs() / scale)
                        .fold(0.0, f64::max)
                })
                .collect();
            errors.sort_by(f64::total_cmp);
            println!(
                "{name:24} {d:>8} {:>7.4}% {:>7.4}%",
                100.0 * errors[errors.len() - 1],
                100.0 * errors[errors.len() / 2]
            );
        }
    }
    let removed = truth
        .iter()
        .filter(|a| {
            let scale = a[0].iter().fold(1e-12f64, |m, w| m.max(*w));
            (0..3).any(|c| (a[0][c] - a[1][c]) > 0.01 * scale)
        })
        .count();
    println!("the clamp removes more than 1% of the largest channel at {removed} of 256 points");
    Ok(())
}
