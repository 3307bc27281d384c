//! What each quadrature sample count buys: albedo error of the per-pixel
//! quadrature against the dense rule applied to the full reconstruction, and
//! the time of a 256 x 256 map.
//! `cargo run --release -p brdf-atlas-core --example map_accuracy -- MODEL`.

use brdf_atlas_core::View;
use brdf_atlas_core::measure::{map_error, reference_albedo};
use brdf_atlas_core::{Model, NoProgress};
use brdf_merl::Quadrature;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: map_accuracy MODEL")?;
    let model = Model::open(&path)?;
    let (w, view) = (16usize, View::default());
    let dense = Quadrature::dense(model.dims(), 1);
    // Reference at a 4 x 4 grid of pixels of a 16 x 16 map.
    let pixels: Vec<(usize, usize)> = (0..4)
        .flat_map(|a| (0..4).map(move |b| (2 + 4 * a, 2 + 4 * b)))
        .collect();
    let reference = pixels
        .iter()
        .map(|&(px, py)| {
            let x = view.pixel_to_latent(px as f64, py as f64, w, w);
            reference_albedo(&model, &x, &dense)
        })
        .collect::<Result<Vec<_>, _>>()?;
    println!("samples  bins  max_rel_err  mean_rel_err  time_256x256_s");
    for s in [16usize, 64, 256, 1024, 4096, 16384] {
        let map = model.albedo_map(w, w, view, Some(s), &NoProgress)?;
        let (worst, sum) = map_error(&map, &pixels, &reference);
        let t = std::time::Instant::now();
        let big = model.albedo_map(256, 256, view, Some(s), &NoProgress)?;
        let bins = match big.method {
            brdf_atlas_core::AlbedoMethod::Quadrature { bins, .. } => bins,
            _ => 0,
        };
        println!(
            "{s:7} {bins:5} {worst:12.2e} {sum:13.2e} {:15.3}",
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
