//! `brdf-atlas demo`: the tool at work on its embedded synthetic database,
//! as a list of steps run in order. Each step reads what earlier steps left
//! in [`State`] and adds its own results; growing the demo is adding a step.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use brdf_atlas_core::{Model, OptimizerKind, Precision, TransformKind};
use brdf_merl::Dims;

use crate::error::Error;
use crate::info::{self, Summary};
use crate::{fit, map, reconstruct, report, synth};

/// Where the demo works and how big it is.
#[derive(Debug, Clone)]
pub struct Options {
    /// Working directory; the MERL files go to `dir/merl/`.
    pub dir: PathBuf,
    /// Number of materials to synthesise.
    pub count: usize,
}

/// Seed of the demo's database: the demo always shows the same materials.
const SEED: u64 = 1;

/// Materials synthesised when `--count` is not given: enough for a map
/// with some structure, few enough that the demo takes seconds.
pub const DEFAULT_COUNT: u32 = 16;

/// Width and height of the demo's map.
const MAP_SIZE: usize = 512;

/// What the steps share.
struct State<'a> {
    options: &'a Options,
    /// MERL files of the database, in database order (set by [`synthesise`]).
    materials: Vec<PathBuf>,
    /// Their summaries (set by [`summarise`]).
    summaries: Vec<Summary>,
    /// The fitted model (set by [`fit_model`]).
    model: Option<Model>,
    /// The two materials the reconstruction lies between (set by [`reconstruct_between`]).
    between: Option<(String, String)>,
}

/// A step: a title for the user, and the work.
type Step = (&'static str, fn(&mut State) -> Result<(), Error>);

/// The demo, in order.
const STEPS: &[Step] = &[
    ("Synthesise the material database", synthesise),
    ("Summarise it", summarise),
    ("Fit a 2-D latent space to it (log transform)", fit_model),
    ("Draw the albedo map of the latent space", draw_map),
    (
        "Reconstruct a new material between the first two",
        reconstruct_between,
    ),
    ("Measure what accuracy costs (a quick report)", write_report),
];

/// Run every step, announcing each, then say where everything went.
pub fn run(options: &Options) -> Result<ExitCode, Error> {
    let mut state = State {
        options,
        materials: Vec::new(),
        summaries: Vec::new(),
        model: None,
        between: None,
    };
    for (i, (title, step)) in STEPS.iter().enumerate() {
        writeln!(io::stdout(), "[{}/{}] {title}", i + 1, STEPS.len())?;
        step(&mut state)?;
    }
    let dir = &options.dir;
    let mut out = io::stdout().lock();
    writeln!(out, "\nDone. In {}:", dir.display())?;
    writeln!(
        out,
        "  {:<22}{} MERL files ({}, the resolution BRDF Explorer opens)",
        "merl/",
        state.materials.len(),
        Dims::MERL,
    )?;
    if let Some(model) = &state.model {
        writeln!(
            out,
            "  {MODEL:<22}the fitted latent space (its data in {MODEL}.store, {})",
            fit::size(model.store().len_bytes())
        )?;
    }
    writeln!(
        out,
        "  {MAP_PNG:<22}its albedo map ({MAP_JSON} sidecar, {MAP_EXR} linear float)"
    )?;
    if let Some((a, b)) = &state.between {
        writeln!(
            out,
            "  {RECONSTRUCTED:<22}a new material halfway between {a} and {b}; open it in BRDF Explorer"
        )?;
    }
    writeln!(
        out,
        "  {:<22}what accuracy costs on this database: report.md, CSV tables, PNG plots",
        format!("{REPORT}/")
    )?;
    Ok(ExitCode::SUCCESS)
}

/// File names inside the demo directory.
const MODEL: &str = "model.atlas";
const MAP_PNG: &str = "map.png";
const MAP_JSON: &str = "map.json";
const MAP_EXR: &str = "map.exr";
const RECONSTRUCTED: &str = "reconstructed.binary";
const REPORT: &str = "report";

/// Run `write` into a buffer and print it indented under the step's title.
fn indented(write: impl FnOnce(&mut Vec<u8>) -> Result<(), Error>) -> Result<(), Error> {
    let mut buffer = Vec::new();
    write(&mut buffer)?;
    let mut out = io::stdout().lock();
    for line in String::from_utf8_lossy(&buffer).lines() {
        writeln!(out, "      {line}")?;
    }
    Ok(())
}

fn merl_dir(options: &Options) -> PathBuf {
    options.dir.join("merl")
}

/// Write the synthetic database at full MERL resolution.
fn synthesise(state: &mut State) -> Result<(), Error> {
    let options = synth::Options {
        count: state.options.count,
        dims: Dims::MERL,
        seed: SEED,
        out_dir: merl_dir(state.options),
    };
    state.materials = synth::write_database(&options)?;
    writeln!(
        io::stdout(),
        "      wrote {} materials to {}",
        state.materials.len(),
        options.out_dir.display()
    )?;
    Ok(())
}

/// Read the files back (validating them) and report each one's albedo.
fn summarise(state: &mut State) -> Result<(), Error> {
    state.summaries = info::summarise(&state.materials)
        .into_iter()
        .collect::<Result<_, _>>()?;
    let rows: Vec<&Summary> = state.summaries.iter().collect();
    info::write_albedo_table(&mut io::stdout().lock(), &rows)?;
    Ok(())
}

/// Fit the database with the default settings and the log transform.
fn fit_model(state: &mut State) -> Result<(), Error> {
    let options = fit::Options {
        dir: merl_dir(state.options),
        model: state.options.dir.join(MODEL),
        q: 2,
        transform: TransformKind::Log,
        optimizer: OptimizerKind::HookeJeeves,
        precision: Precision::F32,
        length_scale: 1.0,
        noise: 1e-4,
        min_step: 1e-3,
    };
    let fitted = fit::fit(&options)?;
    indented(|out| Ok(fit::write_summary(out, &options, &fitted)?))?;
    state.model = Some(Model::open(&options.model)?);
    Ok(())
}

/// The map, at a modest size, with every output.
fn draw_map(state: &mut State) -> Result<(), Error> {
    let model = state.model.as_ref().expect("the fit step ran");
    let dir = &state.options.dir;
    let options = map::Options {
        model: model.path().to_path_buf(),
        png: dir.join(MAP_PNG),
        exr: Some(dir.join(MAP_EXR)),
        json: Some(dir.join(MAP_JSON)),
        size: MAP_SIZE,
        contours: 12,
        samples: None,
        view: None,
        labels: true,
    };
    indented(|out| map::draw(model, &options, out))
}

/// A new material at the midpoint of the first two materials' latent points.
fn reconstruct_between(state: &mut State) -> Result<(), Error> {
    let model = state.model.as_ref().expect("the fit step ran");
    let latent = model.latent();
    let x: Vec<f64> = (0..model.q())
        .map(|c| 0.5 * (latent[(0, c)] + latent[(1, c)]))
        .collect();
    let out = state.options.dir.join(RECONSTRUCTED);
    indented(|report| reconstruct::write(model, &x, &out, report))?;
    state.between = Some((model.names()[0].clone(), model.names()[1].clone()));
    Ok(())
}

/// A quick report on the demo's database (leave-one-out errors for q = 1..3,
/// optimisers, map accuracy, store precision).
fn write_report(state: &mut State) -> Result<(), Error> {
    let options = report::Options {
        dir: merl_dir(state.options),
        out: state.options.dir.join(REPORT),
        q_max: report::QUICK_Q_MAX,
        quick: true,
        optimizer: OptimizerKind::Lbfgs,
    };
    let mut sink = Vec::new();
    let summary = report::write(&options, &mut sink)?;
    writeln!(
        io::stdout(),
        "      wrote {} in {}",
        summary.report.display(),
        fit::secs(summary.total)
    )?;
    Ok(())
}
