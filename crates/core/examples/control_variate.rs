//! Whether a sampled field's error is smooth enough to correct from a
//! coarse grid of exact albedos: at seeded random points of the default
//! view, the sampled field alone and the sampled field plus the tensor
//! cubic of (exact - sampled) at the nodes of a uniform grid, against the
//! dense rule. `cargo run --release -p brdf-atlas-core --example
//! control_variate -- MODEL [POINTS] [SAMPLES] [SIDE,...]`.

use brdf_atlas_core::lattice::cubic_stencil;
use brdf_atlas_core::map_error::albedo_error;
use brdf_atlas_core::{AlbedoRequest, Atlas, FieldRequest, Integration, Model, View};
use brdf_merl::synth::SplitMix64;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: control_variate MODEL [POINTS] [SAMPLES] [SIDE,...]")?;
    let count: usize = args.next().map_or(Ok(64), |s| s.parse())?;
    let samples: usize = args.next().map_or(Ok(256), |s| s.parse())?;
    let sides: Vec<usize> = match args.next() {
        Some(l) => l.split(',').map(str::parse).collect::<Result<_, _>>()?,
        None => vec![9, 17, 33],
    };
    let view = View::default();
    let atlas = Atlas::new(Model::open(&path)?);
    let mut rng = SplitMix64::new(7);
    let points: Vec<[f64; 2]> = (0..count)
        .map(|_| [rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)])
        .collect();
    let want = atlas.exact_albedos(&points, AlbedoRequest::new())?;
    let field = atlas
        .sampled_field(FieldRequest::new(view, 1 << 22), samples)?
        .ok_or("no field")?;
    let score = |got: &dyn Fn([f64; 2]) -> [f64; 3]| {
        let got: Vec<[f64; 3]> = points.iter().map(|p| got(*p)).collect();
        albedo_error(&got, &want)
    };
    let (w0, m0) = score(&|p| field.at(p).0);
    println!(
        "sampled field ({samples}): {} nodes, max {w0:.2e}, mean {m0:.2e}",
        field.nodes()
    );
    for side in sides {
        let cells = side - 1;
        let grid = |i: usize, a: f64, b: f64| a + (b - a) * i as f64 / cells as f64;
        let nodes: Vec<[f64; 2]> = (0..side * side)
            .map(|k| {
                [
                    grid(k % side, view.x0, view.x1),
                    grid(k / side, view.y0, view.y1),
                ]
            })
            .collect();
        let t = std::time::Instant::now();
        let exact =
            atlas.exact_albedos(&nodes, AlbedoRequest::new().integration(Integration::Nodes))?;
        let took = t.elapsed().as_secs_f64();
        let diff: Vec<[f64; 3]> = nodes
            .iter()
            .zip(&exact)
            .map(|(p, e)| {
                let s = field.at(*p).0;
                [e[0] - s[0], e[1] - s[1], e[2] - s[2]]
            })
            .collect();
        let corrected = |p: [f64; 2]| {
            let tx = (p[0] - view.x0) / (view.x1 - view.x0) * cells as f64;
            let ty = (p[1] - view.y0) / (view.y1 - view.y0) * cells as f64;
            let ([fx, ..], wx) = cubic_stencil(tx, cells);
            let ([fy, ..], wy) = cubic_stencil(ty, cells);
            let mut g = field.at(p).0;
            for (a, wa) in wy.iter().enumerate() {
                for (b, wb) in wx.iter().enumerate() {
                    let d = diff[(fy + a) * side + fx + b];
                    for c in 0..3 {
                        g[c] += wa * wb * d[c];
                    }
                }
            }
            g
        };
        let (w1, m1) = score(&corrected);
        println!(
            "  + correction from {side} x {side} exact nodes ({took:.2} s): max {w1:.2e}, mean {m1:.2e}"
        );
    }
    Ok(())
}
