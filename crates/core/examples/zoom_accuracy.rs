//! The first map of zoomed-in views, as a viewer's zoom draws it: the
//! default map (the albedo field) of 1024 x 1024 pixels of views a hundred
//! and a thousand times smaller than the default view, each its time in a
//! process that opened the model (the first includes the rules' rows) and
//! its worst error at 64 seeded random pixels against the dense rule on
//! the full reconstruction of the default material, relative to the
//! pixel's largest channel. `cargo run --release -p brdf-atlas-core
//! --example zoom_accuracy -- MODEL` (a model without a prepared lattice
//! beside it, or the map is drawn from the lattice).

use std::time::Instant;

use brdf_atlas_core::map_error::{map_error, reference_albedo};
use brdf_atlas_core::{Atlas, BlendRule, MapRequest, Model, View};

const SIDE: usize = 1024;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: zoom_accuracy MODEL")?;
    let atlas = Atlas::new(Model::open(&path)?);
    let views = [
        ([0.137, -0.291], 100.0),
        ([0.137, -0.291], 1000.0),
        ([-0.5, 0.4], 100.0),
        ([0.6, 0.7], 1000.0),
    ];
    for (c, zoom) in views {
        let d = View::default();
        let half = 0.5 * (d.x1 - d.x0) / zoom;
        let view = View {
            x0: c[0] - half,
            x1: c[0] + half,
            y0: c[1] - half,
            y1: c[1] + half,
        };
        let t = Instant::now();
        let map = atlas.map(MapRequest::new(SIDE, SIDE).view(view))?;
        let first = t.elapsed().as_secs_f64();
        let t = Instant::now();
        atlas.map(MapRequest::new(SIDE, SIDE).view(view))?;
        let again = t.elapsed().as_secs_f64();
        let mut rng = brdf_merl::synth::SplitMix64::new(12_345);
        let pixels: Vec<(usize, usize)> = (0..64)
            .map(|_| {
                let mut side = || (rng.next_u64() % SIDE as u64) as usize;
                (side(), side())
            })
            .collect();
        let reference = pixels
            .iter()
            .map(|&(x, y)| {
                let at = view.pixel_to_latent(x as f64, y as f64, SIDE, SIDE);
                reference_albedo(&atlas, &at, BlendRule::Floor, atlas.albedo_rule())
            })
            .collect::<Result<Vec<_>, _>>()?;
        let (worst, _) = map_error(&map, &pixels, &reference);
        println!(
            "1/{zoom} of the view at ({}, {}): {:?}; first map {first:.3} s, again {again:.3} s; worst of 64 pixels {:.4}%",
            c[0],
            c[1],
            map.method,
            100.0 * worst
        );
    }
    Ok(())
}
