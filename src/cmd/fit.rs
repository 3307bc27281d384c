//! `brdf-atlas fit`: fit a latent space to a directory of MERL files and
//! write the model file and its store.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use brdf_atlas_core::fidelity::{Fidelity, GIVES_BACK, Summary};
use brdf_atlas_core::limits::MAX_Q;
use brdf_atlas_core::{
    DEFAULT_TRANSFORM, Dataset, GplvmParams, Kernel, OptimizerKind, PAPER_KERNEL, PAPER_TRANSFORM,
    Store, TransformKind,
};
use brdf_atlas_core::{
    FitOptions, FitReport, StorePolicy, default_kernel, fit_dir_with, store_path_for,
};

use std::time::{Duration, Instant};

use brdf_atlas_core::{AlbedoMethod, Atlas, Model, fit_field_views};

use crate::args::{OptimizerArg, PrecisionArg, TransformArg};
use crate::error::Error;
use crate::format::{cost, secs, size};
use crate::progress::Bars;

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
    /// Space the model sees the values in: `rel-log` (the default,
    /// ln(1 + f cos_i cos_o / 0.001)) weighs relative differences alike in
    /// dark and bright materials, `log` (ln(1 + f cos_i cos_o)) makes dark
    /// materials look alike, `raw` is the reflectance itself.
    #[arg(long, value_enum)]
    pub transform: Option<TransformArg>,
    /// The settings of Soler et al. 2018 with the earlier `log` transform:
    /// `--transform log --length-scale 1 --noise 1e-4`, each of which may
    /// still be given to change it.
    #[arg(long)]
    pub paper: bool,
    /// Optimiser of the latent points.
    #[arg(long, value_enum, default_value_t = OptimizerArg::Lbfgs)]
    pub optimizer: OptimizerArg,
    /// Precision of the stored data (sums are always in f64).
    #[arg(long, value_enum, default_value_t = PrecisionArg::F32)]
    pub store_precision: PrecisionArg,
    /// RBF kernel length scale [default: 3 / sqrt(materials) within [0.3, 1]
    /// (0.3 for 100 materials); 1 with --paper].
    #[arg(long, allow_negative_numbers = true)]
    pub length_scale: Option<f64>,
    /// Noise added to the kernel diagonal [default: 3e-5; 1e-4 with --paper].
    #[arg(long, allow_negative_numbers = true)]
    pub noise: Option<f64>,
    /// Learn the length scale and noise by maximum likelihood together with
    /// the latent points (needs `--optimizer lbfgs`); `--length-scale` and
    /// `--noise` are then where the search starts.
    #[arg(long)]
    pub learn_kernel: bool,
    /// Hooke-Jeeves stops when its step falls below this.
    #[arg(long, default_value_t = DEFAULT_MIN_STEP, allow_negative_numbers = true)]
    pub min_step: f64,
    /// Do not build the map's fields after the fit (by default those of
    /// the default view and of [-3, 3]^2 are built, about as long again as
    /// a fit of 100 materials, and saved beside the model as MODEL.fields,
    /// so that the first map of any view inside either, in any program,
    /// only evaluates them).
    #[arg(long)]
    pub no_map_field: bool,
    /// Build the store anew even when the model's own can be used again. A
    /// re-fit into the same model of the same files, unchanged since, with
    /// the same `--transform` and `--store-precision`, otherwise skips the
    /// store pass (other settings, such as `--q` or `--optimizer`, only
    /// change the search).
    #[arg(long)]
    pub rebuild_store: bool,
}

impl Args {
    /// The fit's settings as given, with the defaults (or `--paper`'s) for the rest.
    pub fn new(dir: PathBuf, model: PathBuf) -> Args {
        Args {
            dir,
            model,
            q: 2,
            transform: None,
            paper: false,
            optimizer: OptimizerArg::Lbfgs,
            store_precision: PrecisionArg::F32,
            length_scale: None,
            noise: None,
            learn_kernel: false,
            min_step: DEFAULT_MIN_STEP,
            no_map_field: false,
            rebuild_store: false,
        }
    }

    /// The transform: as given, else the paper's with `--paper`, else the default.
    pub fn transform(&self) -> TransformKind {
        match (self.transform, self.paper) {
            (Some(t), _) => t.into(),
            (None, true) => PAPER_TRANSFORM,
            (None, false) => DEFAULT_TRANSFORM,
        }
    }

    /// The kernel for `materials` materials: each value as given, else the
    /// paper's with `--paper`, else the default ([`default_kernel`]).
    pub fn kernel(&self, materials: usize) -> Kernel {
        let base = if self.paper {
            PAPER_KERNEL
        } else {
            default_kernel(materials)
        };
        Kernel {
            length_scale: self.length_scale.unwrap_or(base.length_scale),
            noise: self.noise.unwrap_or(base.noise),
        }
    }
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
    /// The map's field of the default view built after the fit, if it was.
    pub field: Option<MapField>,
}

/// The map's field `fit` built for the default view and saved beside the model.
pub struct MapField {
    /// What a [`brdf_atlas_core::FIT_FIELD_SIZE`] map of each of [`fit_field_views`] draws
    /// from: `Field` or `SampledField`; `None` when
    /// neither fits its budget (the map integrates every pixel).
    pub methods: Vec<(&'static str, Option<AlbedoMethod>)>,
    /// The file written (`MODEL.fields`), if any.
    pub saved: Option<PathBuf>,
    /// The time taken.
    pub time: Duration,
}

/// Fit and write the model; nothing is printed but progress bars.
///
/// Parameters are checked before any file is read, and `q` against the
/// number of `.binary` files before the long store pass (when there are too
/// few, an invalid one among them is named first). A fit that fails
/// after writing a new store removes it again, so a failed run leaves no
/// store without a model.
pub fn fit(args: &Args) -> Result<Fitted, Error> {
    // The default kernel depends on how many materials there are: the
    // directory's listing says, before any file is read.
    let n = count_binaries(&args.dir).unwrap_or(0);
    let kernel = args.kernel(n);
    let params = GplvmParams::new(args.q)
        .length_scale(kernel.length_scale)
        .noise(kernel.noise)
        .optimizer(args.optimizer.into())
        .learn_kernel(args.learn_kernel)
        .min_step(args.min_step)
        .check()?;
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
        transform: args.transform(),
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
    let field = if args.no_map_field || report.fit.outcome.latent.ncols() != 2 {
        None
    } else {
        Some(map_field(&report.model_path)?)
    };
    Ok(Fitted {
        report,
        store,
        field,
    })
}

/// Build the map's fields of [`fit_field_views`] and save them beside the
/// model ([`Atlas::prepare_fit_fields`]): every view inside either's domain
/// (the map panel's too) is then drawn from them.
fn map_field(model: &Path) -> Result<MapField, Error> {
    let t0 = Instant::now();
    let atlas = Atlas::new(Model::open(model)?);
    let bars = Bars::new("the map's fields");
    let prepared = atlas.prepare_fit_fields(&bars);
    drop(bars);
    let (methods, saved) = prepared?;
    let names = fit_field_views().map(|(name, _)| name);
    Ok(MapField {
        methods: names.into_iter().zip(methods).collect(),
        saved,
        time: t0.elapsed(),
    })
}

/// `.binary` files in `dir` as the library counts them, or `None` when the
/// directory cannot be listed (the library then says why).
fn count_binaries(dir: &Path) -> Option<usize> {
    let entries = std::fs::read_dir(dir).ok()?;
    Some(
        entries
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "binary") && !p.is_dir())
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
    let private = r
        .peak_private
        .map(|p| format!("peak resident private {} (RssAnon)", size(p)));
    let heap = r
        .peak_heap
        .map(|p| format!("peak heap {} allocated, touched or not", size(p as u64)));
    let parts: Vec<String> = private.into_iter().chain(heap).collect();
    if !parts.is_empty() {
        writeln!(
            out,
            "  memory     {}; the inputs and the store are memory-mapped files, in neither",
            parts.join(", ")
        )?;
    }
    write_fidelity(out, &r.fidelity, &r.names)?;
    if let Some(f) = &fitted.field {
        write_map_field(out, f)?;
    }
    let total = r.scan_time + r.store_time + r.optimise_time + r.fidelity_time + r.save_time;
    writeln!(
        out,
        "  time       scan {}, {} {}, optimise {}, own points {}, save {}, total {}",
        secs(r.scan_time),
        if r.store_reused {
            "store check"
        } else {
            "store+Gram"
        },
        secs(r.store_time),
        secs(r.optimise_time),
        secs(r.fidelity_time),
        secs(r.save_time),
        secs(total)
    )
}

/// The map's fields built after the fit, and where they went.
fn write_map_field(out: &mut impl Write, f: &MapField) -> io::Result<()> {
    let what: Vec<String> = f
        .methods
        .iter()
        .map(|(view, method)| match *method {
            Some(AlbedoMethod::Field { nodes, .. }) => {
                format!("{view}'s exact albedos at {nodes} nodes")
            }
            Some(AlbedoMethod::SampledField {
                samples,
                nodes,
                check,
                ..
            }) => format!(
                "{view}'s albedos integrated with {samples} samples at {nodes} nodes{}",
                crate::format::field_check(check)
            ),
            _ => format!("none for {view} within its budget (its maps integrate every pixel)"),
        })
        .collect();
    let saved = match &f.saved {
        Some(path) => format!("saved in {}", path.display()),
        None => "already saved beside the model".into(),
    };
    writeln!(
        out,
        "  map field  {}; {saved}, {} (the first maps only evaluate them)",
        what.join(", "),
        secs(f.time)
    )
}

/// How the materials come back at their own points, and which do not.
pub fn write_fidelity(out: &mut impl Write, f: &Fidelity, names: &[String]) -> io::Result<()> {
    let own = Summary::of(&f.own);
    let gp = Summary::of(&f.own_gp);
    writeln!(
        out,
        "  own points albedo off by {} per channel at the median, {} at worst (GP's own blend {}, {}); \
         log-relative table error {:.3} median, {:.3} worst",
        percent(own.albedo.median),
        percent(own.albedo.worst),
        percent(gp.albedo.median),
        percent(gp.albedo.worst),
        own.log_rel.median,
        own.log_rel.worst,
    )?;
    let missed: Vec<usize> = (0..f.own.len())
        .filter(|&i| !f.own[i].gives_back())
        .collect();
    if missed.is_empty() {
        return writeln!(
            out,
            "             every material's point gives it back (albedo within {} in every channel)",
            percent(GIVES_BACK)
        );
    }
    writeln!(
        out,
        "  warning    {} of {} materials are not given back at their own point (albedo off by more than {}):",
        missed.len(),
        f.own.len(),
        percent(GIVES_BACK)
    )?;
    for i in missed {
        writeln!(
            out,
            "             {}: its point {}",
            names[i],
            f.own[i].describe()
        )?;
    }
    Ok(())
}

/// A share as a percentage with two significant figures or so.
fn percent(x: f64) -> String {
    let p = 100.0 * x;
    if p >= 10.0 {
        format!("{p:.0}%")
    } else if p >= 1.0 {
        format!("{p:.1}%")
    } else {
        format!("{p:.2}%")
    }
}
