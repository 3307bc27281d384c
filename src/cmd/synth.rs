//! `brdf-atlas synth`: write the synthetic database as MERL files.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use brdf_atomic::{PendingFile, commit_all};
use brdf_merl::Dims;
use brdf_merl::synth::database;
use brdf_merl::table::HEADER_BYTES;
use rayon::prelude::*;

use crate::args;
use crate::error::Error;
use crate::progress;

/// Largest number of materials `synth` and `demo` write.
pub const MAX_COUNT: i64 = 10_000;

/// Write a synthetic database of analytic materials as MERL files.
///
/// Each material is a Lambertian base plus a GGX microfacet lobe with
/// Fresnel, alternating metals and dielectrics, with colours and
/// roughness drawn from a seeded generator: the same count and seed always
/// give the same files. Files are named `NNN-kind-colour-rROUGHNESS.binary`
/// and written atomically.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Number of materials.
    #[arg(long, default_value_t = 24, value_parser = clap::value_parser!(u32).range(1..=MAX_COUNT))]
    pub count: u32,
    /// Table dims n_theta_h,n_theta_d,n_phi_d. BRDF Explorer needs 90,90,180.
    #[arg(long, default_value = "90,90,180", value_name = "A,B,C", value_parser = args::dims, allow_hyphen_values = true)]
    pub dims: Dims,
    /// Seed of the material generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Directory to write into (created if missing).
    #[arg(value_name = "OUT_DIR")]
    pub out_dir: PathBuf,
}

/// Tabulate and write every material of the database; returns the paths
/// written, in database order. Every file is written under a temporary name
/// first and all take their places only once all are written, so a failed
/// or interrupted run replaces no file and leaves no partial one (and an
/// interrupted run removes the directories it made, still empty).
pub fn write_database(args: &Args) -> Result<Vec<PathBuf>, Error> {
    let dir = &args.out_dir;
    brdf_atomic::create_dir_all_owned(dir).map_err(|source| Error::CreateDir {
        path: dir.clone(),
        source,
    })?;
    let materials = database(args.count as usize, args.seed);
    let pb = progress::bar(materials.len(), "synthesising");
    let staged = materials
        .par_iter()
        .map(|m| {
            let path = dir.join(format!("{}.binary", m.name));
            let staged = m.brdf.table(args.dims).stage(&path)?;
            pb.inc(1);
            Ok(staged)
        })
        .collect::<Result<Vec<PendingFile>, Error>>();
    pb.finish_and_clear();
    let staged = staged?;
    let paths = staged.iter().map(|f| f.target().to_path_buf()).collect();
    commit_all(staged)?;
    Ok(paths)
}

/// Run `synth`: write the files, then say what was written where.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let paths = write_database(args)?;
    let mb = (HEADER_BYTES + 8 * args.dims.values()) as f64 / 1e6;
    writeln!(
        io::stdout(),
        "wrote {} materials ({}, {mb:.1} MB each, seed {}) to {}",
        paths.len(),
        args.dims,
        args.seed,
        args.out_dir.display()
    )?;
    Ok(ExitCode::SUCCESS)
}
