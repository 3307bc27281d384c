//! `brdf-atlas demo`: the tool at work on its embedded synthetic database,
//! as a list of steps run in order. Each step reads what earlier steps left
//! in [`State`] and adds its own results; growing the demo is adding a step.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use brdf_atlas_core::Model;
use brdf_merl::Dims;

use super::info::{self, Summary};
use super::{fit, map, reconstruct, report, synth};
use crate::args::OptimizerArg;
use crate::error::Error;
use crate::format::{secs, size};

/// Materials synthesised when `--count` is not given: enough for a map
/// with some structure, few enough that the demo takes seconds.
pub const DEFAULT_COUNT: u32 = 16;

/// Show brdf-atlas at work on its embedded synthetic database, no download needed.
///
/// Synthesises materials at the full MERL resolution into DIR/merl/,
/// summarises them (name and albedo), fits a latent space to them
/// (DIR/model.atlas), draws its map (DIR/map.png, .json, .exr) and
/// writes a new material between the two nearest each other on the map
/// (DIR/reconstructed.binary).
/// Needs about 35 MB of disk per material, and as much again for the model.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Working directory for everything the demo writes.
    #[arg(long, default_value = "brdf-atlas-demo")]
    pub dir: PathBuf,
    /// Number of materials to synthesise (a 2-D map needs at least 3).
    #[arg(long, default_value_t = DEFAULT_COUNT, value_parser = clap::value_parser!(u32).range(3..=synth::MAX_COUNT))]
    pub count: u32,
}

/// Seed of the demo's database: the demo always shows the same materials.
const SEED: u64 = 1;

/// Width and height of the demo's map.
const MAP_SIZE: u32 = 512;

/// What the steps share.
struct State<'a> {
    args: &'a Args,
    /// MERL files of the database, in database order (set by [`synthesise`]).
    materials: Vec<PathBuf>,
    /// Their summaries (set by [`summarise`]).
    summaries: Vec<Summary>,
    /// The fitted model (set by [`fit_model`]).
    model: Option<brdf_atlas_core::Atlas>,
    /// The two materials the reconstruction lies between (set by [`reconstruct_between`]).
    between: Option<(String, String)>,
}

/// A step: a title for the user, and the work.
type Step = (&'static str, fn(&mut State) -> Result<(), Error>);

/// The demo, in order.
const STEPS: &[Step] = &[
    ("Synthesise the material database", synthesise),
    ("Summarise it", summarise),
    ("Fit a 2-D latent space to it", fit_model),
    ("Draw the albedo map of the latent space", draw_map),
    (
        "Reconstruct a new material between the two nearest",
        reconstruct_between,
    ),
    ("Measure what accuracy costs (a quick report)", write_report),
];

/// Run every step, announcing each, then say where everything went.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let mut state = State {
        args,
        materials: Vec::new(),
        summaries: Vec::new(),
        model: None,
        between: None,
    };
    for (i, (title, step)) in STEPS.iter().enumerate() {
        writeln!(io::stdout(), "[{}/{}] {title}", i + 1, STEPS.len())?;
        step(&mut state)?;
    }
    let dir = &args.dir;
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
            size(model.store().len_bytes())
        )?;
    }
    if let Some(model) = &state.model
        && brdf_atlas_core::fields_path(model.path()).exists()
    {
        writeln!(
            out,
            "  {FIELDS:<22}the map's fields the fit saved: maps inside them take a fraction of a second"
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
/// The model's saved map fields (`MODEL.fields`, written by the fit).
const FIELDS: &str = "model.fields";
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

fn merl_dir(args: &Args) -> PathBuf {
    args.dir.join("merl")
}

/// Write the synthetic database at full MERL resolution.
fn synthesise(state: &mut State) -> Result<(), Error> {
    let args = synth::Args {
        count: state.args.count,
        dims: Dims::MERL,
        seed: SEED,
        out_dir: merl_dir(state.args),
    };
    state.materials = synth::write_database(&args)?;
    writeln!(
        io::stdout(),
        "      wrote {} materials to {}",
        state.materials.len(),
        args.out_dir.display()
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

/// Fit the database with the default settings.
fn fit_model(state: &mut State) -> Result<(), Error> {
    let args = fit::Args::new(merl_dir(state.args), state.args.dir.join(MODEL));
    let fitted = fit::fit(&args)?;
    indented(|out| Ok(fit::write_summary(out, &args, &fitted)?))?;
    state.model = Some(brdf_atlas_core::Atlas::new(Model::open(&args.model)?));
    Ok(())
}

/// The map, at a modest size, with every output.
fn draw_map(state: &mut State) -> Result<(), Error> {
    let model = state.model.as_ref().expect("the fit step ran");
    let dir = &state.args.dir;
    let args = map::Args {
        model: model.path().to_path_buf(),
        png: dir.join(MAP_PNG),
        exr: Some(dir.join(MAP_EXR)),
        json: Some(dir.join(MAP_JSON)),
        size: MAP_SIZE,
        contours: map::DEFAULT_CONTOURS,
        samples: None,
        view: None,
        blend: brdf_atlas_core::BlendRule::default(),
        no_labels: false,
        no_key: false,
    };
    indented(|out| map::draw(model, &args, out))
}

/// A new material at the midpoint of the two materials nearest each other
/// on the map (a blend the model knows: far from every material it fades
/// towards the database's mean).
fn reconstruct_between(state: &mut State) -> Result<(), Error> {
    let model = state.model.as_ref().expect("the fit step ran");
    let latent = model.latent();
    let (n, q) = (latent.nrows(), model.q());
    let d2 = |a: usize, b: usize| {
        (0..q)
            .map(|c| (latent[(a, c)] - latent[(b, c)]).powi(2))
            .sum::<f64>()
    };
    let (a, b) = (0..n)
        .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
        .min_by(|&(a, b), &(c, d)| d2(a, b).total_cmp(&d2(c, d)))
        .expect("the fit needs three materials");
    let x: Vec<f64> = (0..q)
        .map(|c| 0.5 * (latent[(a, c)] + latent[(b, c)]))
        .collect();
    let out = state.args.dir.join(RECONSTRUCTED);
    indented(|report| {
        reconstruct::write(
            model,
            &x,
            brdf_atlas_core::BlendRule::default(),
            &out,
            report,
        )
    })?;
    state.between = Some((model.names()[a].clone(), model.names()[b].clone()));
    Ok(())
}

/// A quick report on the demo's database (leave-one-out errors for q = 1..3,
/// optimisers, map accuracy, store precision).
fn write_report(state: &mut State) -> Result<(), Error> {
    let args = report::Args {
        dir: merl_dir(state.args),
        out: state.args.dir.join(REPORT),
        q_max: None,
        quick: true,
        prepare: false,
        thorough: false,
        optimizer: OptimizerArg::Lbfgs,
        growth: Vec::new(),
    };
    let mut sink = Vec::new();
    let summary = report::write(&args, &mut sink)?;
    writeln!(
        io::stdout(),
        "      wrote {} in {}",
        summary.report.display(),
        secs(summary.total)
    )?;
    Ok(())
}
