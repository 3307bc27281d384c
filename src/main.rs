//! `brdf-atlas`: explore the space of measured BRDFs from the command line.
//!
//! Each subcommand lives in its own module under `cmd/`, which owns its
//! arguments (`Args`, derived with clap) and its `run`; `main` parses the
//! command line, runs one command and turns any error into one line on
//! stderr and exit status 1 (clap's own usage errors exit with status 2).
//! An interrupt (Ctrl-C, `kill`) leaves the outputs as they were, prints one
//! line and exits with 128 + the signal (130 for Ctrl-C): see `interrupt`.
#![warn(missing_docs)]

mod args;
mod cmd;
mod error;
mod format;
mod interrupt;
mod machine;
mod progress;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::error::Error;

/// Shown after the top-level help.
const EXAMPLES: &str = "Examples:
  brdf-atlas demo                                    synthesise materials, fit, map, reconstruct
  brdf-atlas synth --count 8 --seed 3 materials/     write 8 synthetic 90x90x180 MERL files
  brdf-atlas nbrdf --count 8 merl/                   write 8 of the 100 MERL materials (neural fits)
  brdf-atlas info materials/*.binary                 check and summarise MERL files
  brdf-atlas fit materials/ -o atlas.model           fit a 2-D latent space to them
  brdf-atlas map atlas.model -o map.png              draw it, coloured by albedo
  brdf-atlas reconstruct atlas.model --at 0.3,-0.5 -o new.binary
                                                     a new material from a point of the map
  brdf-atlas eval atlas.model --at 0.3,-0.5 --wi 30,0 --wo 30,180
                                                     its reflectance for one pair of directions
  brdf-atlas locate atlas.model other.binary         where another material lands
  brdf-atlas report materials/ -o report/            measure what accuracy costs in time";

/// Explore the space of measured BRDFs.
///
/// brdf-atlas reads and writes BRDF tables in the MERL `.binary` layout
/// (90 x 90 x 180 bins over theta_h, theta_d, phi_d, RGB doubles), the format
/// Disney's BRDF Explorer opens. It checks and summarises such files, fits a
/// Gaussian Process Latent Variable Model that places them in a latent
/// space, draws that space as a map coloured by albedo, and turns any point
/// of it into a new MERL file. It also synthesises a database of analytic
/// materials in the same layout so that everything runs without the
/// (separately licensed) MERL measurements.
#[derive(Debug, Parser)]
#[command(
    name = "brdf-atlas",
    version,
    about,
    long_about,
    propagate_version = true,
    after_help = EXAMPLES
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// The commands, in the order `--help` lists them. Each one's help text is
// the doc comment of its `Args`.
#[derive(Debug, Subcommand)]
enum Command {
    Info(cmd::info::Args),
    Synth(cmd::synth::Args),
    Nbrdf(cmd::nbrdf::Args),
    Fit(cmd::fit::Args),
    Reconstruct(cmd::reconstruct::Args),
    Eval(cmd::eval::Args),
    Map(cmd::map::Args),
    Prepare(cmd::prepare::Args),
    Swatches(cmd::swatches::Args),
    Export(cmd::export::Args),
    Locate(cmd::locate::Args),
    Report(cmd::report::Args),
    Demo(cmd::demo::Args),
}

fn run(command: &Command) -> Result<ExitCode, Error> {
    match command {
        Command::Info(args) => cmd::info::run(args),
        Command::Synth(args) => cmd::synth::run(args),
        Command::Nbrdf(args) => cmd::nbrdf::run(args),
        Command::Fit(args) => cmd::fit::run(args),
        Command::Reconstruct(args) => cmd::reconstruct::run(args),
        Command::Eval(args) => cmd::eval::run(args),
        Command::Map(args) => cmd::map::run(args),
        Command::Prepare(args) => cmd::prepare::run(args),
        Command::Swatches(args) => cmd::swatches::run(args),
        Command::Export(args) => cmd::export::run(args),
        Command::Locate(args) => cmd::locate::run(args),
        Command::Report(args) => cmd::report::run(args),
        Command::Demo(args) => cmd::demo::run(args),
    }
}

/// Heap accounting for `fit`'s summary (peak heap).
#[global_allocator]
static HEAP: brdf_atlas_core::heap::Counting = brdf_atlas_core::heap::Counting;

fn main() -> ExitCode {
    // First, while this is the only thread: the mask is inherited.
    interrupt::install();
    let cli = Cli::parse();
    match run(&cli.command) {
        Ok(code) => code,
        // `brdf-atlas info ... | head`: the reader has all it wanted.
        Err(e) if e.is_broken_pipe() => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    use super::*;

    #[test]
    fn cli_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
