//! `brdf-atlas prepare`: the prepared map of a model, an adaptive lattice
//! of exact albedos over the default view saved beside the model, from
//! which every later map inside that view is drawn in a fraction of a
//! second.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use brdf_atlas_core::{BlendRule, LATTICE_TOLERANCE, Model, lattice_path};

use crate::args;
use crate::error::Error;
use crate::format::secs;
use crate::progress::Bars;

/// Prepare a model's map: exact albedos of the default view on an adaptive
/// lattice, saved beside the model as MODEL.lattice.
///
/// Across the default view the albedo of a log model has detail too fine
/// for a polynomial of few nodes, so `map` integrates every pixel there
/// (about 2% off at worst, tens of seconds at 1024 x 1024). Prepared once,
/// the map of any view inside the default one (by `map`, the C library,
/// Python and the BRDF Explorer panel) is the cubic of this lattice: a
/// fraction of a second, and within the tolerance of the exact albedos.
/// The lattice starts from cells a sixteenth of the view wide and cuts a
/// cell in four until its cubic, checked against exact albedos at the finer
/// lattice's new nodes, meets the tolerance. It takes minutes (about ten
/// thousand exact albedos for 100 materials at full resolution). A lattice
/// serves the fit it was built from and its material (`--blend`) only.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Model file written by `fit` (q = 2).
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// The material mapped, as `map --blend`: `floor` (the default) or `gp`.
    #[arg(long, value_name = "RULE", default_value = "floor", value_parser = args::blend_rule)]
    pub blend: BlendRule,
    /// The largest error of a cell's cubic at the finer lattice's new nodes,
    /// relative to the node's largest channel.
    #[arg(long, value_name = "T", default_value_t = LATTICE_TOLERANCE, value_parser = tolerance)]
    pub tolerance: f64,
}

/// `--tolerance`: a share in (0, 1).
fn tolerance(s: &str) -> Result<f64, String> {
    let t: f64 = s
        .parse()
        .map_err(|_| format!("'{s}' is not a number (a share such as 0.005)"))?;
    if t > 0.0 && t < 1.0 {
        Ok(t)
    } else {
        Err(format!(
            "{t} must lie between 0 and 1 (a share such as 0.005)"
        ))
    }
}

/// Run `prepare`.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let model = brdf_atlas_core::Atlas::new(Model::open(&args.model)?);
    let t0 = Instant::now();
    let bars = Bars::new("preparing the map");
    let lattice = model.prepare_map(args.blend, args.tolerance, &bars)?;
    let path = lattice_path(model.path());
    lattice.save(&path)?;
    drop(bars);
    let mut out = io::stdout().lock();
    writeln!(
        out,
        "prepared the map of {} ({} material): {} exact albedos within {:.2}%, {}",
        model.path().display(),
        args.blend.name(),
        lattice.nodes(),
        100.0 * args.tolerance,
        secs(t0.elapsed())
    )?;
    writeln!(
        out,
        "  wrote {}; {:.2}% of the view is drawn from its finest cells unchecked",
        path.display(),
        100.0 * lattice.unchecked_share()
    )?;
    Ok(ExitCode::SUCCESS)
}
