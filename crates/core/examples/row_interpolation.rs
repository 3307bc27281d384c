//! Whether a map could take each store row's blended value at a point from
//! a grid instead of from the store: at random points of the default view,
//! the tensor cubic of the blend weights at the 4 x 4 grid nodes round the
//! point (grids of cells 1/16 to 1/256 of the view) against the weights at
//! the point itself, for the GP's weights and for the soft floor's convex
//! weights; and what the difference does to the rows' values in
//! transformed space (`|z . (w_cubic - w)|` over every 8th store row, the
//! largest and the 99.9th percentile; in a log transform a value's
//! relative error). The GP's blend of each row is smooth at the kernel's
//! length scale; the convex blend's narrow kernel and inverse square
//! distances vary faster. `cargo run --release -p brdf-atlas-core
//! --example row_interpolation -- MODEL [POINTS]` (16 points by default).

use brdf_atlas_core::lattice::cubic_stencil;
use brdf_atlas_core::{BlendRule, Model, Rows, View};

/// `|z . d|` for every `stride`-th store row.
fn row_errors(model: &Model, d: &[f64], stride: usize) -> Vec<f64> {
    let store = model.store();
    let n = store.n();
    let dot = |row: usize| -> f64 {
        match store.z() {
            Rows::F32(z) => z[row * n..(row + 1) * n]
                .iter()
                .zip(d)
                .map(|(&z, d)| f64::from(z) * d)
                .sum(),
            Rows::F64(z) => z[row * n..(row + 1) * n]
                .iter()
                .zip(d)
                .map(|(z, d)| z * d)
                .sum(),
        }
    };
    (0..store.rows())
        .step_by(stride)
        .filter(|&r| store.unmeasured()[r] == 0)
        .map(|r| dot(r).abs())
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: row_interpolation MODEL [POINTS]")?;
    let count: usize = args.next().map_or(Ok(16), |s| s.parse())?;
    let model = Model::open(&path)?;
    let view = View::default();
    let mut rng = brdf_merl::synth::SplitMix64::new(2024);
    let points: Vec<[f64; 2]> = (0..count)
        .map(|_| [rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)])
        .collect();
    let weights = |x: [f64; 2]| -> Result<(Vec<f64>, Vec<f64>), Box<dyn std::error::Error>> {
        let blend = model.at(&x, BlendRule::Floor)?;
        let convex = blend.floor().ok_or("no convex weights")?.to_vec();
        Ok((blend.gp_weights().to_vec(), convex))
    };
    println!(
        "{path}: {count} random points of the default view; |z . (cubic - exact weights)| over every 8th store row"
    );
    for level in [4u32, 5, 6, 7, 8] {
        let cells = 1usize << level;
        let (hx, hy) = (
            (view.x1 - view.x0) / cells as f64,
            (view.y1 - view.y0) / cells as f64,
        );
        let (mut gp, mut convex) = (Vec::new(), Vec::new());
        for &x in &points {
            let ([fx, ..], wx) = cubic_stencil((x[0] - view.x0) / hx, cells);
            let ([fy, ..], wy) = cubic_stencil((x[1] - view.y0) / hy, cells);
            let (want_g, want_c) = weights(x)?;
            let (mut got_g, mut got_c) = (vec![0.0; want_g.len()], vec![0.0; want_c.len()]);
            for (a, wa) in wy.iter().enumerate() {
                for (b, wb) in wx.iter().enumerate() {
                    let node = [
                        view.x0 + (fx + b) as f64 * hx,
                        view.y0 + (fy + a) as f64 * hy,
                    ];
                    let (g, c) = weights(node)?;
                    for (o, v) in got_g.iter_mut().zip(&g) {
                        *o += wa * wb * v;
                    }
                    for (o, v) in got_c.iter_mut().zip(&c) {
                        *o += wa * wb * v;
                    }
                }
            }
            let d: Vec<f64> = got_g.iter().zip(&want_g).map(|(a, b)| a - b).collect();
            gp.extend(row_errors(&model, &d, 8));
            let d: Vec<f64> = got_c.iter().zip(&want_c).map(|(a, b)| a - b).collect();
            convex.extend(row_errors(&model, &d, 8));
        }
        for (name, e) in [("GP", &mut gp), ("convex", &mut convex)] {
            e.sort_by(f64::total_cmp);
            println!(
                "  grid cells 1/{cells} of the view ({:.4} wide), {name:>6} blend: largest {:.2e}, 99.9th percentile {:.2e}, median {:.2e}",
                hx,
                e[e.len() - 1],
                e[e.len() * 999 / 1000],
                e[e.len() / 2]
            );
        }
    }
    Ok(())
}
