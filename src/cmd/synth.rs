//! `brdf-atlas synth`: write the synthetic database as MERL files.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use brdf_merl::Dims;
use brdf_merl::atomic::{PendingFile, commit_all};
use brdf_merl::synth::database;
use brdf_merl::table::HEADER_BYTES;
use rayon::prelude::*;

use crate::error::Error;
use crate::progress;

/// What to synthesise, and where.
#[derive(Debug, Clone)]
pub struct Options {
    /// Number of materials.
    pub count: usize,
    /// Table dims of every file.
    pub dims: Dims,
    /// Seed of the material generator.
    pub seed: u64,
    /// Output directory, created if missing.
    pub out_dir: PathBuf,
}

/// Tabulate and write every material of the database; returns the paths
/// written, in database order. Every file is written under a temporary name
/// first and all take their places only once all are written, so a failed
/// or interrupted run replaces no file and leaves no partial one.
pub fn write_database(options: &Options) -> Result<Vec<PathBuf>, Error> {
    let dir = &options.out_dir;
    std::fs::create_dir_all(dir).map_err(|source| Error::CreateDir {
        path: dir.clone(),
        source,
    })?;
    let materials = database(options.count, options.seed);
    let pb = progress::bar(materials.len(), "synthesising");
    let staged = materials
        .par_iter()
        .map(|m| {
            let path = dir.join(format!("{}.binary", m.name));
            let staged = m.brdf.table(options.dims).stage(&path)?;
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
pub fn run(options: &Options) -> Result<ExitCode, Error> {
    let paths = write_database(options)?;
    let mb = (HEADER_BYTES + 8 * options.dims.values()) as f64 / 1e6;
    writeln!(
        io::stdout(),
        "wrote {} materials ({}, {mb:.1} MB each, seed {}) to {}",
        paths.len(),
        options.dims,
        options.seed,
        options.out_dir.display()
    )?;
    Ok(ExitCode::SUCCESS)
}
