//! Render a model's albedo map:
//! `cargo run --release -p brdf-atlas-pictures --example map_model -- MODEL OUT.png [SIZE] [SAMPLES]`.

use brdf_atlas_core::Model;
use brdf_atlas_pictures::map_picture::{Picture, write_png};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let model = brdf_atlas_core::Atlas::new(Model::open(&args[1])?);
    let size: usize = args.get(3).map_or(Ok(512), |s| s.parse())?;
    let samples: Option<usize> = args.get(4).map(|s| s.parse()).transpose()?;
    let t = std::time::Instant::now();
    let map = model.map(brdf_atlas_core::MapRequest::new(size, size).samples(samples))?;
    println!("map {:?}", t.elapsed());
    write_png(args[2].as_ref(), &Picture::new(&model, map, 12))?;
    Ok(())
}
