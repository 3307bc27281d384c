//! Where the map's albedo has detail a lattice must follow: exact albedos
//! (the nodes' rule over the full reconstruction) on a grid of `2^L + 1`
//! nodes a side over the default view, for the GP's blend and for the soft
//! floor's (the default material); then, for each coarser grid of the
//! lattice (`2^level` cells a side), the error of its tensor cubic at the
//! next finer grid's new nodes, relative to each node's largest channel,
//! by where the node lies: well inside the materials' box (the latent
//! points' bounding box, shrunk by 0.1), near its edge (within 0.1 of it)
//! and outside it. A cell of the prepared lattice is cut where that error
//! exceeds 0.5%. `cargo run --release -p brdf-atlas-core --example
//! map_detail -- MODEL [L]` (L = 6 by default: 4,225 nodes a rule).

use brdf_atlas_core::lattice::cubic_stencil;
use brdf_atlas_core::{AlbedoRequest, Atlas, BlendRule, Integration, Model, View};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: map_detail MODEL [L]")?;
    let finest: u32 = args.next().map_or(Ok(6), |s| s.parse())?;
    if !(4..=8).contains(&finest) {
        return Err("L is 4 to 8".into());
    }
    let atlas = Atlas::new(Model::open(&path)?);
    let view = View::default();
    let side = (1usize << finest) + 1;
    let at = |r: usize, c: usize| {
        let f = |i: usize, a: f64, b: f64| a + (b - a) * i as f64 / (side - 1) as f64;
        [f(c, view.x0, view.x1), f(r, view.y0, view.y1)]
    };
    let points: Vec<[f64; 2]> = (0..side * side).map(|k| at(k / side, k % side)).collect();
    let latent = atlas.model().latent();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for i in 0..latent.nrows() {
        for d in 0..2 {
            lo[d] = lo[d].min(latent[(i, d)]);
            hi[d] = hi[d].max(latent[(i, d)]);
        }
    }
    // 0: inside the box shrunk by 0.1, 1: within 0.1 of its edge, 2: outside.
    let region = |x: [f64; 2]| {
        let outside = (0..2)
            .map(|d| (lo[d] - x[d]).max(x[d] - hi[d]))
            .fold(f64::MIN, f64::max);
        if outside > 0.0 {
            2
        } else if outside > -0.1 {
            1
        } else {
            0
        }
    };
    let names = ["inside", "edge", "outside"];
    println!(
        "{path}: {side} x {side} nodes over x {}..{}, y {}..{}; materials' box x {:.3}..{:.3}, y {:.3}..{:.3}",
        view.x0, view.x1, view.y0, view.y1, lo[0], hi[0], lo[1], hi[1]
    );
    for rule in [BlendRule::Gp, BlendRule::Floor] {
        let t = std::time::Instant::now();
        let request = AlbedoRequest::new()
            .rule(rule)
            .integration(Integration::Nodes);
        let albedo = atlas.exact_albedos(&points, request)?;
        println!(
            "{rule:?}: {} exact albedos in {:.1} s",
            points.len(),
            t.elapsed().as_secs_f64()
        );
        for level in 2..finest {
            let step = 1usize << (finest - level);
            let cells = 1usize << level;
            let mut errors: [Vec<f64>; 3] = Default::default();
            for r in (0..side).step_by(step / 2) {
                for c in (0..side).step_by(step / 2) {
                    if r % step == 0 && c % step == 0 {
                        continue;
                    }
                    let ([fy, ..], wy) = cubic_stencil(r as f64 / step as f64, cells);
                    let ([fx, ..], wx) = cubic_stencil(c as f64 / step as f64, cells);
                    let mut got = [0.0f64; 3];
                    for (a, wa) in wy.iter().enumerate() {
                        for (b, wb) in wx.iter().enumerate() {
                            let v = albedo[(fy + a) * step * side + (fx + b) * step];
                            for (g, v) in got.iter_mut().zip(v) {
                                *g += wa * wb * v;
                            }
                        }
                    }
                    let want = albedo[r * side + c];
                    let scale = want.iter().fold(1e-12f64, |a, v| a.max(*v));
                    let e = (0..3)
                        .map(|k| (got[k] - want[k]).abs() / scale)
                        .fold(0.0, f64::max);
                    errors[region(at(r, c))].push(e);
                }
            }
            for (name, e) in names.iter().zip(errors.iter_mut()) {
                if e.is_empty() {
                    continue;
                }
                e.sort_by(f64::total_cmp);
                let share = |bound: f64| {
                    100.0 * e.iter().filter(|&&v| v > bound).count() as f64 / e.len() as f64
                };
                println!(
                    "  cells 1/{cells} of the view, {name:>7}: {:5} nodes, error max {:.3}%, 99th percentile {:.3}%, median {:.4}%; over 0.5%: {:.1}% of them, over 0.1%: {:.1}%",
                    e.len(),
                    100.0 * e[e.len() - 1],
                    100.0 * e[e.len() * 99 / 100],
                    100.0 * e[e.len() / 2],
                    share(5e-3),
                    share(1e-3)
                );
            }
        }
    }
    Ok(())
}
