//! Fit a directory of MERL files and print the phases' times:
//! `cargo run --release -p brdf-atlas-core --example fit_dir -- DIR MODEL [raw|log] [hooke-jeeves|lbfgs]`.
//! With `FIT_HISTORY=FILE` the cost after each iteration goes to FILE, one a line.

use brdf_atlas_core::{FitOptions, fit_dir};
use brdf_atlas_core::{GplvmParams, NoProgress, OptimizerKind, Precision, TransformKind};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        return Err("usage: fit_dir DIR MODEL [raw|log] [hooke-jeeves|lbfgs]".into());
    }
    let transform = args
        .get(3)
        .and_then(|s| TransformKind::parse(s))
        .unwrap_or_default();
    let optimizer = args
        .get(4)
        .and_then(|s| OptimizerKind::parse(s))
        .unwrap_or_default();
    let options = FitOptions {
        params: GplvmParams::new(2).optimizer(optimizer).check()?,
        transform,
        precision: Precision::F32,
    };
    let r = fit_dir(args[1].as_ref(), args[2].as_ref(), &options, &NoProgress)?;
    let o = &r.fit.outcome;
    println!(
        "{} materials: scan {:?}, store+gram {:?}, optimise {:?} ({} iterations, {} evaluations, {} pattern moves), save {:?}",
        r.names.len(),
        r.scan_time,
        r.store_time,
        r.optimise_time,
        o.iterations,
        o.evaluations,
        o.pattern_moves,
        r.save_time
    );
    println!("cost {} -> {}; drift {:?}", o.initial_cost, o.cost, o.drift);
    if let Some(path) = std::env::var_os("FIT_HISTORY") {
        let lines: String = o.history.iter().map(|c| format!("{c:e}\n")).collect();
        std::fs::write(path, lines)?;
    }
    Ok(())
}
