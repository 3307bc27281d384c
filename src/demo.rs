//! `brdf-atlas demo`: the tool at work on its embedded synthetic database,
//! as a list of steps run in order. Each step reads what earlier steps left
//! in [`State`] and adds its own results; growing the demo is adding a step.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use brdf_merl::Dims;

use crate::error::Error;
use crate::info::{self, Summary};
use crate::synth;

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

/// What the steps share.
struct State<'a> {
    options: &'a Options,
    /// MERL files of the database, in database order (set by [`synthesise`]).
    materials: Vec<PathBuf>,
    /// Their summaries (set by [`summarise`]).
    summaries: Vec<Summary>,
}

/// A step: a title for the user, and the work.
type Step = (&'static str, fn(&mut State) -> Result<(), Error>);

/// The demo, in order.
const STEPS: &[Step] = &[
    ("Synthesise the material database", synthesise),
    ("Summarise it", summarise),
];

/// Run every step, announcing each, then say where everything went.
pub fn run(options: &Options) -> Result<ExitCode, Error> {
    let mut state = State {
        options,
        materials: Vec::new(),
        summaries: Vec::new(),
    };
    for (i, (title, step)) in STEPS.iter().enumerate() {
        writeln!(io::stdout(), "[{}/{}] {title}", i + 1, STEPS.len())?;
        step(&mut state)?;
    }
    writeln!(
        io::stdout(),
        "\nDone. {} MERL files ({}, the resolution BRDF Explorer opens) are in {}",
        state.materials.len(),
        Dims::MERL,
        merl_dir(options).display()
    )?;
    Ok(ExitCode::SUCCESS)
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
