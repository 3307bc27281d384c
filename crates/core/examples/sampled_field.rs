//! What a sampled field costs and buys: the albedo field of a view's
//! domain with node values from an `s`-sample quadrature rule
//! ([`Atlas::sampled_field`]) at several sample counts, its nodes, its
//! build time and its error at seeded random points of the view against
//! the dense rule over the full reconstruction of the default material,
//! relative to each point's largest channel; for the default view and
//! for [-3, 3]^2 (whose field's error at the default view's points is
//! shown too). `cargo run --release -p brdf-atlas-core --example
//! sampled_field -- MODEL [POINTS] [SAMPLES,...]`.

use brdf_atlas_core::map_error::albedo_error;
use brdf_atlas_core::{AlbedoRequest, Atlas, FieldRequest, Model, View};
use brdf_merl::synth::SplitMix64;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: sampled_field MODEL [POINTS] [SAMPLES,...]")?;
    let count: usize = args.next().map_or(Ok(64), |s| s.parse())?;
    let samples: Vec<usize> = match args.next() {
        Some(list) => list.split(',').map(str::parse).collect::<Result<_, _>>()?,
        None => vec![256, 1024, 4096],
    };
    let views = [("default", View::default()), ("[-3,3]^2", View::wide())];
    println!("view      samples    nodes  patches  estimate  build_s   max_err  mean_err");
    let points_of = |view: View| {
        let mut rng = SplitMix64::new(7);
        (0..count)
            .map(|_| [rng.range(view.x0, view.x1), rng.range(view.y0, view.y1)])
            .collect::<Vec<[f64; 2]>>()
    };
    let inner = points_of(View::default());
    let inner_want = Atlas::new(Model::open(&path)?).exact_albedos(&inner, AlbedoRequest::new())?;
    for (name, view) in views {
        let points = points_of(view);
        let want = Atlas::new(Model::open(&path)?).exact_albedos(&points, AlbedoRequest::new())?;
        for &s in &samples {
            // A fresh atlas a rule: its rows are part of the first map's time.
            let atlas = Atlas::new(Model::open(&path)?);
            let t = std::time::Instant::now();
            let field = atlas
                .sampled_field(FieldRequest::new(view, 1 << 22), s)?
                .ok_or("no field within 4 million nodes")?;
            let took = t.elapsed().as_secs_f64();
            let got: Vec<[f64; 3]> = points.iter().map(|p| field.at(*p).0).collect();
            let (worst, mean) = albedo_error(&got, &want);
            println!(
                "{name:9} {s:7} {:8} {:8} {:9.1e} {took:8.3} {worst:9.2e} {:9.2e}",
                field.nodes(),
                field.patches(),
                field.estimate(),
                mean
            );
            if view != View::default() {
                // What the larger field gives inside the default view.
                let got: Vec<[f64; 3]> = inner.iter().map(|p| field.at(*p).0).collect();
                let (worst, mean) = albedo_error(&got, &inner_want);
                println!("  its albedo at the default view's points: {worst:9.2e} {mean:9.2e}");
            }
        }
    }
    Ok(())
}
