//! `brdf-atlas fit`: fit a latent space to a directory of MERL files and
//! write the model file and its store.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use brdf_atlas_core::{FitOptions, FitReport, fit_dir, store_path_for};
use brdf_atlas_core::{GplvmParams, OptimizerKind, Precision, Store, TransformKind};

use crate::error::Error;
use crate::progress::Bars;

/// What to fit, how, and where the model goes.
#[derive(Debug, Clone)]
pub struct Options {
    /// Directory of MERL `.binary` files.
    pub dir: PathBuf,
    /// Model file to write (`MODEL.store` goes beside it).
    pub model: PathBuf,
    /// Latent dimension.
    pub q: usize,
    /// Data transform.
    pub transform: TransformKind,
    /// Optimiser.
    pub optimizer: OptimizerKind,
    /// Store precision.
    pub precision: Precision,
    /// RBF length scale.
    pub length_scale: f64,
    /// Noise on the kernel diagonal.
    pub noise: f64,
    /// Hooke-Jeeves' stopping step.
    pub min_step: f64,
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
/// number of `.binary` files before the long store pass. A fit that fails
/// after writing a new store removes it again, so a failed run leaves no
/// store without a model.
pub fn fit(options: &Options) -> Result<Fitted, Error> {
    let params = GplvmParams::new(options.q)
        .length_scale(options.length_scale)
        .noise(options.noise)
        .optimizer(options.optimizer)
        .min_step(options.min_step)
        .check()?;
    let n = count_binaries(&options.dir).unwrap_or(0);
    if n > 0 && options.q >= n {
        return Err(Error::Input(format!(
            "{}: --q {} needs more materials than latent dimensions, found {n} .binary file{}",
            options.dir.display(),
            options.q,
            if n == 1 { "" } else { "s" }
        )));
    }
    let fit_options = FitOptions {
        params,
        transform: options.transform,
        precision: options.precision,
    };
    let store_path = store_path_for(&options.model);
    let store_existed = store_path.exists();
    let bars = Bars::new(format!("opening {}", options.dir.display()));
    let result = fit_dir(&options.dir, &options.model, &fit_options, &bars);
    drop(bars);
    let report = match result {
        Ok(report) => report,
        Err(e) => {
            if !store_existed && !options.model.exists() {
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
pub fn run(options: &Options) -> Result<ExitCode, Error> {
    let fitted = fit(options)?;
    for (path, why) in &fitted.report.ignored {
        eprintln!("warning: {}: ignored ({why})", path.display());
    }
    write_summary(&mut io::stdout().lock(), options, &fitted)?;
    Ok(ExitCode::SUCCESS)
}

/// The closing summary: data, model, cost, search, numerics, times.
pub fn write_summary(out: &mut impl Write, options: &Options, fitted: &Fitted) -> io::Result<()> {
    let (r, store) = (&fitted.report, &fitted.store);
    let o = &r.fit.outcome;
    let k = r.fit.kernel;
    writeln!(
        out,
        "fitted {} materials ({}, d = {}) from {} into {}",
        r.names.len(),
        store.dims(),
        store.rows(),
        options.dir.display(),
        r.model_path.display()
    )?;
    writeln!(
        out,
        "  model      q = {}, length scale {}, noise {:e}, transform {}, optimiser {}",
        o.latent.ncols(),
        k.length_scale,
        k.noise,
        store.transform().name(),
        r.fit.optimizer.name()
    )?;
    writeln!(
        out,
        "  store      {} ({}, {})",
        r.store_path.display(),
        store.precision().name(),
        size(store.len_bytes())
    )?;
    writeln!(
        out,
        "  cost       {} -> {} (negative log likelihood, from the PCA start)",
        cost(o.initial_cost),
        cost(o.cost)
    )?;
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
    if let Some(peak) = r.peak_heap {
        writeln!(
            out,
            "  memory     peak heap {} (the inputs and the store are memory-mapped files, not heap)",
            size(peak as u64)
        )?;
    }
    let total = r.scan_time + r.store_time + r.optimise_time + r.save_time;
    writeln!(
        out,
        "  time       scan {}, store+Gram {}, optimise {}, save {}, total {}",
        secs(r.scan_time),
        secs(r.store_time),
        secs(r.optimise_time),
        secs(r.save_time),
        secs(total)
    )
}

/// A cost in a fixed width of significant digits.
fn cost(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e7 || v.abs() < 1e-2) {
        format!("{v:.6e}")
    } else {
        format!("{v:.4}")
    }
}

/// `0.123 s`.
pub fn secs(t: Duration) -> String {
    format!("{:.3} s", t.as_secs_f64())
}

/// `35.0 MB`, `1.75 GB`.
pub fn size(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.2} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else {
        format!("{:.1} kB", b / 1e3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_costs_read_well() {
        assert_eq!(size(34_992_012), "35.0 MB");
        assert_eq!(size(1_749_600_064), "1.75 GB");
        assert_eq!(size(12_345), "12.3 kB");
        assert_eq!(cost(-1234.56789), "-1234.5679");
        assert_eq!(cost(-2.5e8), "-2.500000e8");
        assert_eq!(secs(Duration::from_millis(1500)), "1.500 s");
    }
}
