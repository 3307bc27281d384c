//! `brdf-atlas fit`: fit a latent space to a directory of MERL files and
//! write the model file and its store.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use brdf_atlas_core::limits::MAX_Q;
use brdf_atlas_core::{Dataset, GplvmParams, OptimizerKind, Store};
use brdf_atlas_core::{FitOptions, FitReport, StorePolicy, fit_dir_with, store_path_for};

use crate::args::{OptimizerArg, PrecisionArg, TransformArg};
use crate::error::Error;
use crate::format::{cost, secs, size};
use crate::progress::Bars;

/// `--length-scale` when not given.
pub const DEFAULT_LENGTH_SCALE: f64 = 1.0;
/// `--noise` when not given.
pub const DEFAULT_NOISE: f64 = 1e-4;
/// `--min-step` when not given.
pub const DEFAULT_MIN_STEP: f64 = 1e-3;

/// Fit a latent space to a directory of MERL files and write the model.
///
/// Every `.binary` file of MERL_DIR (sorted by name) becomes a material;
/// other entries are ignored with a warning, and an invalid MERL file
/// stops the fit with an error naming it. The data is transformed,
/// centred and packed into MODEL.store beside MODEL (memory-mapped later
/// by every other command); the latent points are fitted by minimising
/// the GPLVM negative log likelihood from a PCA start. Both files are
/// written atomically. Ends with a summary: cost, search, numerical
/// health and the time of each phase.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Directory of MERL `.binary` files.
    #[arg(value_name = "MERL_DIR")]
    pub dir: PathBuf,
    /// Model file to write (its data goes to MODEL.store beside it).
    #[arg(short = 'o', long = "output", value_name = "MODEL")]
    pub model: PathBuf,
    #[arg(long, default_value_t = 2, help = q_help())]
    pub q: usize,
    /// Space the model sees the values in: `log` compresses highlights
    /// (log(1 + f cos_i cos_o)), `raw` is the reflectance itself.
    #[arg(long, value_enum, default_value_t = TransformArg::Log)]
    pub transform: TransformArg,
    /// Optimiser of the latent points.
    #[arg(long, value_enum, default_value_t = OptimizerArg::Lbfgs)]
    pub optimizer: OptimizerArg,
    /// Precision of the stored data (sums are always in f64).
    #[arg(long, value_enum, default_value_t = PrecisionArg::F32)]
    pub store_precision: PrecisionArg,
    /// RBF kernel length scale.
    #[arg(long, default_value_t = DEFAULT_LENGTH_SCALE, allow_negative_numbers = true)]
    pub length_scale: f64,
    /// Noise added to the kernel diagonal.
    #[arg(long, default_value_t = DEFAULT_NOISE, allow_negative_numbers = true)]
    pub noise: f64,
    /// Learn the length scale and noise by maximum likelihood together with
    /// the latent points (needs `--optimizer lbfgs`); `--length-scale` and
    /// `--noise` are then where the search starts.
    #[arg(long)]
    pub learn_kernel: bool,
    /// Hooke-Jeeves stops when its step falls below this.
    #[arg(long, default_value_t = DEFAULT_MIN_STEP, allow_negative_numbers = true)]
    pub min_step: f64,
    /// Build the store anew even when the model's own can be used again. A
    /// re-fit into the same model of the same files, unchanged since, with
    /// the same `--transform` and `--store-precision`, otherwise skips the
    /// store pass (other settings, such as `--q` or `--optimizer`, only
    /// change the search).
    #[arg(long)]
    pub rebuild_store: bool,
}

/// `--q`'s help, with the bound the fit checks ([`MAX_Q`]).
fn q_help() -> String {
    format!(
        "Latent dimension, 1 to {MAX_Q} (a map needs 2); must be smaller than the number of materials"
    )
}

/// A finished fit: the library's report and what the summary adds.
pub struct Fitted {
    /// The library's report.
    pub report: FitReport,
    /// The store as written (dims, size).
    pub store: Store,
}

/// Fit and write the model; nothing is printed but progress bars.
///
/// Parameters are checked before any file is read, and `q` against the
/// number of `.binary` files before the long store pass (when there are too
/// few, an invalid one among them is named first). A fit that fails
/// after writing a new store removes it again, so a failed run leaves no
/// store without a model.
pub fn fit(args: &Args) -> Result<Fitted, Error> {
    let params = GplvmParams::new(args.q)
        .length_scale(args.length_scale)
        .noise(args.noise)
        .optimizer(args.optimizer.into())
        .learn_kernel(args.learn_kernel)
        .min_step(args.min_step)
        .check()?;
    let n = count_binaries(&args.dir).unwrap_or(0);
    if n > 0 && args.q >= n {
        // An invalid file is the first thing to fix (and the likelier
        // mistake): name it rather than the count. At most 16 files (q's
        // bound), so checking them all now is quick.
        Dataset::open_dir(&args.dir)?;
        return Err(Error::Input(format!(
            "{}: --q {} needs more materials than latent dimensions, found {n} .binary file{}",
            args.dir.display(),
            args.q,
            if n == 1 { "" } else { "s" }
        )));
    }
    let fit_options = FitOptions {
        params,
        transform: args.transform.into(),
        precision: args.store_precision.into(),
    };
    let store_path = store_path_for(&args.model);
    let store_existed = store_path.exists();
    let bars = Bars::new(format!("opening {}", args.dir.display()));
    let policy = if args.rebuild_store {
        StorePolicy::Rebuild
    } else {
        StorePolicy::Reuse
    };
    let result = fit_dir_with(&args.dir, &args.model, &fit_options, policy, &bars);
    drop(bars);
    let report = match result {
        Ok(report) => report,
        Err(e) => {
            if !store_existed && !args.model.exists() {
                // Best effort: the error below is what matters.
                let _ = std::fs::remove_file(&store_path);
            }
            return Err(e.into());
        }
    };
    let store = Store::open(&report.store_path)?;
    Ok(Fitted { report, store })
}

/// `.binary` files in `dir` as the library counts them, or `None` when the
/// directory cannot be listed (the library then says why).
fn count_binaries(dir: &Path) -> Option<usize> {
    let entries = std::fs::read_dir(dir).ok()?;
    Some(
        entries
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "binary") && p.is_file())
            .count(),
    )
}

/// Run `fit`: warnings for ignored entries, then the summary.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let fitted = fit(args)?;
    for (path, why) in &fitted.report.ignored {
        eprintln!("warning: {}: ignored ({why})", path.display());
    }
    write_summary(&mut io::stdout().lock(), args, &fitted)?;
    Ok(ExitCode::SUCCESS)
}

/// The closing summary: data, model, cost, search, numerics, times.
pub fn write_summary(out: &mut impl Write, args: &Args, fitted: &Fitted) -> io::Result<()> {
    let (r, store) = (&fitted.report, &fitted.store);
    let o = &r.fit.outcome;
    let k = r.fit.kernel;
    writeln!(
        out,
        "fitted {} materials ({}, d = {}) from {} into {}",
        r.names.len(),
        store.dims(),
        store.rows(),
        args.dir.display(),
        r.model_path.display()
    )?;
    writeln!(
        out,
        "  model      q = {}, {}, transform {}, optimiser {}",
        o.latent.ncols(),
        if r.fit.learned_kernel {
            format!(
                "length scale {:.4}, noise {:.3e} (learned)",
                k.length_scale, k.noise
            )
        } else {
            format!("length scale {}, noise {:e}", k.length_scale, k.noise)
        },
        store.transform().name(),
        r.fit.optimizer.name()
    )?;
    writeln!(
        out,
        "  store      {} ({}, {}){}",
        r.store_path.display(),
        store.precision().name(),
        size(store.len_bytes()),
        if r.store_reused {
            ", used again: the same input files, unchanged since the last fit"
        } else {
            ""
        }
    )?;
    writeln!(
        out,
        "  cost       {} -> {} (negative log likelihood, from the PCA start)",
        cost(o.initial_cost),
        cost(o.cost)
    )?;
    match r.fit.optimizer {
        OptimizerKind::HookeJeeves => {
            writeln!(
                out,
                "  search     {} iterations, {} evaluations, {} pattern moves",
                o.iterations, o.evaluations, o.pattern_moves
            )?;
            let d = o.drift;
            writeln!(
                out,
                "  numerics   {} rank-one updates, {} refactorisations, {} dense fallbacks, max drift {:.1e} (cost), {:.1e} (K^-1)",
                d.updates, d.refreshes, d.dense_fallbacks, d.max_cost_drift, d.max_inverse_drift
            )?;
        }
        OptimizerKind::Lbfgs => writeln!(
            out,
            "  search     {} iterations, {} evaluations (cost and gradient, each from a fresh factorisation)",
            o.iterations, o.evaluations
        )?,
    }
    let heap = r.peak_heap.map(|p| format!("peak heap {}", size(p as u64)));
    let private = r
        .peak_private
        .map(|p| format!("peak private {} (VmData)", size(p)));
    let parts: Vec<String> = heap.into_iter().chain(private).collect();
    if !parts.is_empty() {
        writeln!(
            out,
            "  memory     {} (the inputs and the store are memory-mapped files, in neither)",
            parts.join(", ")
        )?;
    }
    let total = r.scan_time + r.store_time + r.optimise_time + r.save_time;
    writeln!(
        out,
        "  time       scan {}, {} {}, optimise {}, save {}, total {}",
        secs(r.scan_time),
        if r.store_reused {
            "store check"
        } else {
            "store+Gram"
        },
        secs(r.store_time),
        secs(r.optimise_time),
        secs(r.save_time),
        secs(total)
    )
}
