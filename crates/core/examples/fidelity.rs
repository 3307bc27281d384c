//! Each material of a model at its own point and predicted from the others,
//! in the errors a person sees (relative albedo per channel, log-relative
//! table error) beside the `ln(1 + v)` RMSE; the materials whose point does
//! not give them back are named.
//!
//! ```sh
//! cargo run --release -p brdf-atlas-core --example fidelity -- MODEL
//! ```

use brdf_atlas_core::fidelity::{Judged, Summary, fidelity, known_share, spacing};
use brdf_atlas_core::loo::Every;
use brdf_atlas_core::{Model, NoProgress};

fn line(what: &str, judged: &[Judged]) {
    let s = Summary::of(judged);
    println!(
        "{what:<22} albedo {:>6.2}% / {:>6.2}% / {:>7.2}% (largest channel {:>6.2}% / {:>6.2}%)  log-rel {:.4} / {:.4} / {:.4}   ln(1+v) {:.4} / {:.4}",
        100.0 * s.albedo.median,
        100.0 * s.albedo.p90,
        100.0 * s.albedo.worst,
        100.0 * s.albedo_worst_channel.median,
        100.0 * s.albedo_worst_channel.p90,
        s.log_rel.median,
        s.log_rel.p90,
        s.log_rel.worst,
        s.log.median,
        s.log.worst,
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: fidelity MODEL")?;
    let model = Model::open(&path)?;
    let every = if std::env::var_os("FIDELITY_EVERY_BIN").is_some() {
        Every::BIN
    } else {
        Every::QUARTER
    };
    let t = std::time::Instant::now();
    let f = fidelity(
        model.store(),
        model.latent().as_ref(),
        &model.file().kernel,
        true,
        every,
        &NoProgress,
    )?;
    println!(
        "{} materials, one pass in {:.2} s; median / 90th percentile / worst",
        model.names().len(),
        t.elapsed().as_secs_f64()
    );
    line("own point (default)", &f.own);
    line("own point (GP blend)", &f.own_gp);
    let held = f.held_out.as_deref().unwrap_or_default();
    line("leave-one-out", held);
    line(
        "leave-one-out (GP)",
        f.held_out_gp.as_deref().unwrap_or_default(),
    );
    let x = model.latent();
    let edge = (0..x.nrows())
        .filter(|&i| x[(i, 0)].abs() > 0.999 || x[(i, 1)].abs() > 0.999)
        .count();
    let s = spacing(x.as_ref());
    println!(
        "nearest-neighbour latent distance: median {:.3}, smallest {:.4}; {} within 0.01 of another; {edge} on the box edge",
        s.median, s.smallest, s.close
    );
    println!(
        "predictive variance below 0.1 on {:.1}% of the default view (101 x 101 points)",
        100.0 * known_share(&model, 101)?
    );
    for (i, j) in f.own.iter().enumerate() {
        if !j.gives_back() {
            println!("  {}: its point {}", model.names()[i], j.describe());
        }
    }
    Ok(())
}
