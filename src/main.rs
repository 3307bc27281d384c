//! `brdf-atlas`: explore the space of measured BRDFs from the command line.
//!
//! Each subcommand lives in its own module; `main` parses the arguments,
//! runs one command and turns any error into one line on stderr and exit
//! status 1 (clap's own usage errors exit with status 2).
#![warn(missing_docs)]

mod demo;
mod dims;
mod error;
mod info;
mod progress;
mod synth;

use std::path::PathBuf;
use std::process::ExitCode;

use brdf_merl::Dims;
use clap::{Parser, Subcommand};

use crate::error::Error;

/// Shown after the top-level help.
const EXAMPLES: &str = "Examples:
  brdf-atlas demo                                  synthesise 16 materials and summarise them
  brdf-atlas synth --count 8 --seed 3 materials/   write 8 synthetic 90x90x180 MERL files
  brdf-atlas info materials/*.binary               check and summarise MERL files";

/// Explore the space of measured BRDFs.
///
/// brdf-atlas reads and writes BRDF tables in the MERL `.binary` layout
/// (90 x 90 x 180 bins over theta_h, theta_d, phi_d, RGB doubles), the format
/// Disney's BRDF Explorer opens. It checks and summarises such files, and
/// synthesises a database of analytic materials in the same layout so that
/// everything runs without the (separately licensed) MERL measurements.
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

#[derive(Debug, Subcommand)]
enum Command {
    /// Check MERL files and summarise them: dims, unmeasured values, range, albedo.
    ///
    /// For each file: its dims, and per colour channel the number of
    /// unmeasured (negative) values, the min, max and mean of the measured
    /// values in reflectance units (1/sr, MERL's scales applied), and the
    /// albedo (directional-hemispherical reflectance averaged over incident
    /// directions; a Lambertian BRDF of reflectance rho gives rho).
    ///
    /// A file that cannot be read gets one `error:` line on stderr naming it;
    /// the other files are still reported, and the exit status is 1.
    Info {
        /// MERL `.binary` files.
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
    },
    /// Write a synthetic database of analytic materials as MERL files.
    ///
    /// Each material is a Lambertian base plus a GGX microfacet lobe with
    /// Fresnel, alternating metals and dielectrics, with colours and
    /// roughness drawn from a seeded generator: the same count and seed always
    /// give the same files. Files are named `NNN-kind-colour-rROUGHNESS.binary`
    /// and written atomically.
    Synth {
        /// Number of materials.
        #[arg(long, default_value_t = 24, value_parser = clap::value_parser!(u32).range(1..=10_000))]
        count: u32,
        /// Table dims n_theta_h,n_theta_d,n_phi_d. BRDF Explorer needs 90,90,180.
        #[arg(long, default_value = "90,90,180", value_name = "A,B,C", value_parser = dims::parse, allow_hyphen_values = true)]
        dims: Dims,
        /// Seed of the material generator.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Directory to write into (created if missing).
        #[arg(value_name = "OUT_DIR")]
        out_dir: PathBuf,
    },
    /// Show brdf-atlas at work on its embedded synthetic database, no download needed.
    ///
    /// Synthesises materials at the full MERL resolution into DIR/merl/,
    /// reads them back and summarises them (name and albedo). Needs about
    /// 35 MB of disk per material.
    Demo {
        /// Working directory for everything the demo writes.
        #[arg(long, default_value = "brdf-atlas-demo")]
        dir: PathBuf,
        /// Number of materials to synthesise.
        #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=10_000))]
        count: u32,
    },
}

fn run(cli: Cli) -> Result<ExitCode, Error> {
    match cli.command {
        Command::Info { files } => info::run(&files),
        Command::Synth {
            count,
            dims,
            seed,
            out_dir,
        } => synth::run(&synth::Options {
            count: count as usize,
            dims,
            seed,
            out_dir,
        }),
        Command::Demo { dir, count } => demo::run(&demo::Options {
            dir,
            count: count as usize,
        }),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
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
