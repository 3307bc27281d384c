//! `brdf-atlas report`: what accuracy costs in time, measured on a directory
//! of MERL files and written up as `report.md` with CSV tables and PNG plots.
//!
//! The measurements come from the core library (stores, fits, the
//! leave-one-out pass of [`brdf_atlas_core::loo`], maps, reconstruction):
//! [`plan`] decides what to run, [`measure`] runs and times it, and
//! [`csv`], [`markdown`] and [`plot`] write the results. Everything is
//! written into a staged directory beside REPORT_DIR
//! ([`brdf_atomic::StagedDir`]), which takes REPORT_DIR's place only
//! when the whole report is done: a failed run leaves no partial report,
//! and an earlier report stays until the new one is complete.

mod analytic;
mod csv;
mod fidelity;
mod growth;
mod maps;
mod markdown;
mod measure;
mod plan;
mod plausible;
mod plot;
mod results;
mod steps;

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use brdf_atlas_core::Dataset;
use brdf_atlas_core::limits::MAX_Q;
use brdf_atomic::{StagedDir, write_atomic};

use self::plan::Plan;
use self::results::Results;
use self::steps::{SectionTime, Steps};
use crate::args::OptimizerArg;
use crate::error::Error;
use crate::format::secs;
use crate::machine;
use crate::progress::Bars;

/// Measure what accuracy costs in time and write a report with tables and plots.
///
/// On a directory of MERL files: the leave-one-out reconstruction error
/// of the GPLVM (closed form, no refit) for q = 1..Q and both transforms,
/// beside PCA with as many components; Hooke-Jeeves vs L-BFGS and
/// Hooke-Jeeves' minimum step (cost reached vs time); the albedo map's
/// error and time vs quadrature samples, the default method against the
/// per-pixel rule (and the prepared map, with --prepare or --thorough) and
/// its time vs size; the plausibility of a grid of map points; f32 vs f64
/// stores; the analytic (glTF) fit of every material against a Lambertian
/// and a single GGX lobe, as `export` makes it; how long each section took. Writes REPORT_DIR/report.md, CSV files and PNG plots. Needs
/// disk for the stores it builds (about 4 times the MERL files' size in
/// f32) in a staging directory beside REPORT_DIR, removed at the end;
/// REPORT_DIR appears (or replaces an earlier report) only when complete.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Directory of MERL `.binary` files.
    #[arg(value_name = "MERL_DIR")]
    pub dir: PathBuf,
    /// Report directory to write.
    #[arg(short = 'o', long = "output", value_name = "REPORT_DIR")]
    pub out: PathBuf,
    #[arg(long, help = plan::q_max_help(), value_parser = clap::value_parser!(u32).range(1..=MAX_Q as i64))]
    pub q_max: Option<u32>,
    /// Fewer settings (sample counts, maps of 32 to 128 pixels, steps, a 2 x 2 plausibility
    /// grid, leave-one-out errors, the plausible rule's held-out steps and
    /// the grid's clamped shares on every 8th phi_d bin): a report in
    /// seconds on small data. It leaves the prepared map out unless
    /// --prepare is given.
    #[arg(long, conflicts_with = "thorough")]
    pub quick: bool,
    /// Measure the prepared map (`brdf-atlas prepare`) beside the default
    /// method: preparing its lattice takes most of a minute for 12 small
    /// materials, minutes at full resolution (2.4 minutes for the demo's 16
    /// materials, 8 - 12 for 100).
    #[arg(long)]
    pub prepare: bool,
    /// The costliest sweeps too: the prepared map (as --prepare), 4096
    /// quadrature samples in the sample sweep, 256 x 256 maps instead of
    /// 128 x 128 for the sample sweep and the map methods, 1024 x 1024 maps
    /// in the size sweep and a 10 x 10 plausibility grid instead of 6 x 6;
    /// several times as long as the default, most of it the prepared map
    /// (135 s against 22 s for 12 materials at 45 x 45 x 90 on a loaded
    /// 2-core machine).
    #[arg(long)]
    pub thorough: bool,
    /// Optimiser of the fits for q = 1..Q (the other one fits q = 2 as well;
    /// maps and the precision comparison use the fit of `fit`'s default, L-BFGS).
    #[arg(long, value_enum, default_value_t = OptimizerArg::Lbfgs)]
    pub optimizer: OptimizerArg,
    /// Also time fits of synthetic databases of these sizes (16 x 16 x 32
    /// bins, both optimisers), e.g. `--growth 100,200,400,1000`: how the
    /// fit grows with the number of materials.
    #[arg(long, value_name = "N,N,...", value_delimiter = ',', value_parser = clap::value_parser!(u32).range(3..=MAX_GROWTH as i64))]
    pub growth: Vec<u32>,
}

/// Largest synthetic database `--growth` fits.
const MAX_GROWTH: usize = 5000;

/// What the demo and `run` print at the end.
pub struct Summary {
    /// The report file.
    pub report: PathBuf,
    /// Wall time of the whole run.
    pub total: Duration,
    /// Materials.
    pub materials: usize,
}

/// Run `report` and say where it went.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let mut out = io::stdout().lock();
    let summary = write(args, &mut out)?;
    writeln!(
        out,
        "wrote {} ({} materials) in {}",
        summary.report.display(),
        summary.materials,
        secs(summary.total)
    )?;
    Ok(ExitCode::SUCCESS)
}

/// Measure everything and write the report; progress lines go to `say`.
pub fn write(args: &Args, say: &mut dyn Write) -> Result<Summary, Error> {
    let start = Instant::now();
    let load_start = machine::load_average();
    check_output(&args.out)?;
    let staged = StagedDir::create(&args.out).map_err(|source| Error::CreateDir {
        path: args.out.clone(),
        source,
    })?;
    // Stores and model files: inside the staged directory, so that they go
    // with it whatever happens, and removed before it takes its place.
    let work = staged.path().join("work");
    std::fs::create_dir(&work).map_err(|source| Error::CreateDir {
        path: work.clone(),
        source,
    })?;
    let bars = Bars::new(format!("opening {}", args.dir.display()));
    let (t, cpu) = (Instant::now(), machine::cpu_time());
    let data = Dataset::open_dir(&args.dir)?;
    let n = data.len();
    if n < 3 {
        return Err(Error::Input(format!(
            "{}: a report needs at least 3 materials, found {n}",
            args.dir.display()
        )));
    }
    let mut r = Results {
        names: data.names.clone(),
        dims: data.dims().to_string(),
        d: data.dims().values(),
        scan: SectionTime {
            wall: t.elapsed(),
            cpu: cpu
                .zip(machine::cpu_time())
                .map(|(a, b)| b.saturating_sub(a)),
        },
        ..Default::default()
    };
    let plan = Plan::new(args, n);
    drop(bars);
    let mut steps = Steps::new(start, say);
    steps.section("Fidelity: the settings compared");
    let log = fidelity::measure(&data, &work, args.quick, &mut steps, &mut r)?;
    measure::measure(&data, &plan, &work, log, &mut steps, &mut r)?;
    let sizes: Vec<usize> = args.growth.iter().map(|&n| n as usize).collect();
    if !sizes.is_empty() {
        steps.section("Growth: fits of synthetic databases");
        growth::measure(&sizes, &work, &mut steps, &mut r)?;
    }
    std::fs::remove_dir_all(&work).map_err(|source| Error::Write { path: work, source })?;
    steps.section("Analytic fits: glTF against two baselines");
    analytic::measure(&data, args.quick, &mut steps, &mut r)?;

    steps.section("Tables and plots");
    steps.say("writing tables and plots")?;
    let dir = staged.path();
    csv::write_all(dir, &r)?;
    plausible::csv(dir, &r)?;
    analytic::csv(dir, &r)?;
    fidelity::csv(dir, &r)?;
    plot::all(dir, &r)?;
    fidelity::picture(dir, &r)?;
    plausible::picture(dir, &r, plan.plausibility_grid)?;
    if !r.growth.is_empty() {
        growth::csv(dir, &r)?;
        growth::picture(dir, &r)?;
    }
    r.times = steps.times();
    let total = start.elapsed();
    let load_end = machine::load_average();
    write_file(&dir.join("report.md"), |w| {
        markdown::write(w, args, &plan, &r, total, [&load_start, &load_end])
    })?;
    staged.commit()?;
    Ok(Summary {
        report: args.out.join("report.md"),
        total,
        materials: n,
    })
}

/// The report directory must have a name, and may replace only an earlier
/// report (or an empty directory).
fn check_output(out: &Path) -> Result<(), Error> {
    if out.file_name().is_none() {
        return Err(Error::Input(format!(
            "{}: not a directory name",
            out.display()
        )));
    }
    if out.exists() && !is_report(out) {
        return Err(Error::Input(format!(
            "{}: exists and is not a brdf-atlas report (no report.md); choose a new directory",
            out.display()
        )));
    }
    Ok(())
}

fn is_report(dir: &Path) -> bool {
    dir.is_dir()
        && (dir.join("report.md").is_file()
            || std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_none()))
}

/// Write one file of the report; a failure is a write error naming it.
pub(super) fn write_file(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), Error> {
    write_atomic(path, fill).map_err(|source| Error::Write {
        path: path.to_path_buf(),
        source,
    })
}

/// Median wall time of `f`: once, or three times when one run is short
/// (under [`plan::REPEAT_BELOW`]) and `repeat`.
pub(super) fn timed<T>(
    repeat: bool,
    mut f: impl FnMut() -> Result<T, Error>,
) -> Result<(T, Duration), Error> {
    let t = Instant::now();
    let v = f()?;
    let first = t.elapsed();
    if !repeat || first > plan::REPEAT_BELOW {
        return Ok((v, first));
    }
    let mut times = vec![first];
    for _ in 0..2 {
        let t = Instant::now();
        f()?;
        times.push(t.elapsed());
    }
    times.sort();
    Ok((v, times[1]))
}
