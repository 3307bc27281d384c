//! `brdf-atlas nbrdf`: write the 100 MERL materials as fitted by Neural
//! BRDF, as MERL files.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use brdf_merl::table::HEADER_BYTES;
use brdf_merl::{Dims, nbrdf};

use crate::args;
use crate::error::Error;

/// Write the 100 MERL materials as fitted by Neural BRDF, as MERL files.
///
/// A realistic stand-in for the measured MERL database: the published
/// neural fits of its 100 materials (Sztrajman, Rainer, Ritschel, Weyrich,
/// "Neural BRDF Representation and Importance Sampling", Computer Graphics
/// Forum 2021; weights under the MIT licence, derived from the MERL data of
/// Matusik et al. 2003, CC-BY-SA-4.0), shipped inside brdf-atlas and
/// evaluated on the MERL grid. Files are named `NAME.binary` (35 MB each at
/// 90x90x180, 3.5 GB for all) and go in all at once, or none. The values
/// are plausible materials, not measurements: the fits are smooth, and
/// poor near grazing angles.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Only the first N materials, in alphabetical order.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub count: Option<u32>,
    /// Only these materials (comma-separated names; `--list` gives them).
    #[arg(long, value_delimiter = ',', value_name = "A,B,...")]
    pub only: Vec<String>,
    /// Table dims n_theta_h,n_theta_d,n_phi_d. BRDF Explorer needs 90,90,180.
    #[arg(long, default_value = "90,90,180", value_name = "A,B,C", value_parser = args::dims, allow_hyphen_values = true)]
    pub dims: Dims,
    /// Print the 100 names and write nothing.
    #[arg(long)]
    pub list: bool,
    /// Directory to write into (created if missing).
    #[arg(value_name = "OUT_DIR", required_unless_present = "list")]
    pub out_dir: Option<PathBuf>,
}

/// Run `nbrdf`: write the files, then say what was written where.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let mut out = io::stdout().lock();
    if args.list {
        for name in nbrdf::names() {
            writeln!(out, "{name}")?;
        }
        return Ok(ExitCode::SUCCESS);
    }
    let dir = args
        .out_dir
        .as_ref()
        .expect("clap requires it without --list");
    let mut names: Vec<&str> = if args.only.is_empty() {
        nbrdf::names()
    } else {
        args.only.iter().map(String::as_str).collect()
    };
    if let Some(n) = args.count {
        names.truncate(n as usize);
    }
    let paths = nbrdf::write_dir(dir, &names, args.dims)?;
    let mb = (HEADER_BYTES + 8 * args.dims.values()) as f64 / 1e6;
    writeln!(
        out,
        "wrote {} NBRDF materials ({}, {mb:.1} MB each) to {}",
        paths.len(),
        args.dims,
        dir.display()
    )?;
    Ok(ExitCode::SUCCESS)
}
