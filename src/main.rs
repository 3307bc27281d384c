//! `brdf-atlas`: explore the space of measured BRDFs from the command line.
//!
//! Each subcommand lives in its own module; `main` parses the arguments,
//! runs one command and turns any error into one line on stderr and exit
//! status 1 (clap's own usage errors exit with status 2).
#![warn(missing_docs)]

mod coords;
mod demo;
mod dims;
mod error;
mod eval;
mod fit;
mod info;
mod locate;
mod map;
mod progress;
mod reconstruct;
mod report;
mod synth;

use std::path::PathBuf;
use std::process::ExitCode;

use brdf_atlas_core::View;
use brdf_atlas_core::{OptimizerKind, Precision, TransformKind};
use brdf_merl::Dims;
use clap::{Parser, Subcommand, ValueEnum};

use crate::coords::{Angles, Point};
use crate::error::Error;

/// Shown after the top-level help.
const EXAMPLES: &str = "Examples:
  brdf-atlas demo                                    synthesise materials, fit, map, reconstruct
  brdf-atlas synth --count 8 --seed 3 materials/     write 8 synthetic 90x90x180 MERL files
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
    /// Fit a latent space to a directory of MERL files and write the model.
    ///
    /// Every `.binary` file of MERL_DIR (sorted by name) becomes a material;
    /// other entries are ignored with a warning, and an invalid MERL file
    /// stops the fit with an error naming it. The data is transformed,
    /// centred and packed into MODEL.store beside MODEL (memory-mapped later
    /// by every other command); the latent points are fitted by minimising
    /// the GPLVM negative log likelihood from a PCA start. Both files are
    /// written atomically. Ends with a summary: cost, search, numerical
    /// health and the time of each phase.
    Fit {
        /// Directory of MERL `.binary` files.
        #[arg(value_name = "MERL_DIR")]
        dir: PathBuf,
        /// Model file to write (its data goes to MODEL.store beside it).
        #[arg(short = 'o', long = "output", value_name = "MODEL")]
        model: PathBuf,
        /// Latent dimension (a map needs 2); must be smaller than the number of materials.
        #[arg(long, default_value_t = 2)]
        q: usize,
        /// Space the model sees the values in: `log` compresses highlights
        /// (log(1 + f cos_i cos_o)), `raw` is the reflectance itself.
        #[arg(long, value_enum, default_value_t = TransformArg::Log)]
        transform: TransformArg,
        /// Optimiser of the latent points.
        #[arg(long, value_enum, default_value_t = OptimizerArg::HookeJeeves)]
        optimizer: OptimizerArg,
        /// Precision of the stored data (sums are always in f64).
        #[arg(long, value_enum, default_value_t = PrecisionArg::F32)]
        store_precision: PrecisionArg,
        /// RBF kernel length scale.
        #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
        length_scale: f64,
        /// Noise added to the kernel diagonal.
        #[arg(long, default_value_t = 1e-4, allow_negative_numbers = true)]
        noise: f64,
        /// Hooke-Jeeves stops when its step falls below this.
        #[arg(long, default_value_t = 1e-3, allow_negative_numbers = true)]
        min_step: f64,
    },
    /// Write the material at a latent point as a MERL file.
    ///
    /// The new material is the blend of the model's materials that the GPLVM
    /// predicts at the point (values clamped to >= 0; bins no input measured
    /// stay marked unmeasured). Prints the largest blend weights. The file
    /// has the model's dims (90x90x180 for MERL data) and opens in BRDF
    /// Explorer.
    Reconstruct {
        /// Model file written by `fit`.
        #[arg(value_name = "MODEL")]
        model: PathBuf,
        /// Latent point, x,y (q numbers for a q-dimensional model).
        #[arg(long, value_name = "X,Y", value_parser = coords::point, allow_hyphen_values = true)]
        at: Point,
        /// MERL `.binary` file to write.
        #[arg(short = 'o', long = "output", value_name = "OUT")]
        out: PathBuf,
    },
    /// Print the RGB reflectance of the material at a latent point for pairs of directions.
    ///
    /// Directions are angles in degrees: theta from the normal, phi around
    /// it. Give one incident direction and one or more outgoing ones
    /// (`--wi 30,0 --wo 30,180 --wo 45,180`), or a file of pairs. Only the
    /// bins asked for are reconstructed. A pair with a direction below the
    /// horizon, or in a bin no input material measured, has no value.
    Eval {
        /// Model file written by `fit`.
        #[arg(value_name = "MODEL")]
        model: PathBuf,
        /// Latent point, x,y (q numbers for a q-dimensional model).
        #[arg(long, value_name = "X,Y", value_parser = coords::point, allow_hyphen_values = true)]
        at: Point,
        /// Incident direction, theta,phi in degrees.
        #[arg(long, value_name = "THETA,PHI", value_parser = coords::angles, allow_hyphen_values = true,
              required_unless_present = "batch", conflicts_with = "batch")]
        wi: Option<Angles>,
        /// Outgoing direction, theta,phi in degrees; repeat for more.
        #[arg(long, value_name = "THETA,PHI", value_parser = coords::angles, allow_hyphen_values = true,
              required_unless_present = "batch", conflicts_with = "batch")]
        wo: Vec<Angles>,
        /// File of pairs, one a line: theta_i phi_i theta_o phi_o (degrees; `#` starts a comment).
        #[arg(long, value_name = "FILE")]
        batch: Option<PathBuf>,
    },
    /// Draw the albedo map of a 2-D latent space.
    ///
    /// Each pixel is a latent point coloured by the albedo of the material
    /// there; luminance contour lines and the model's materials (dots with
    /// names) are drawn on top. Writes an sRGB PNG, a JSON sidecar with the
    /// view window, the pixel <-> latent mapping and the material points,
    /// and on request a linear float EXR. For a `raw` model the albedo is
    /// blended exactly from the materials' albedos; for `log` each pixel is
    /// integrated from quadrature samples (--samples, default 256).
    Map {
        /// Model file written by `fit` (q = 2).
        #[arg(value_name = "MODEL")]
        model: PathBuf,
        /// PNG to write.
        #[arg(short = 'o', long = "output", value_name = "PNG")]
        png: PathBuf,
        /// Also write the linear albedo as a float OpenEXR.
        #[arg(long, value_name = "EXR")]
        exr: Option<PathBuf>,
        /// JSON sidecar to write [default: the PNG path with .json].
        #[arg(long, value_name = "JSON")]
        json: Option<PathBuf>,
        /// Width and height in pixels.
        #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=16384))]
        size: u32,
        /// Number of luminance contour lines.
        #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(0..=1000))]
        contours: u32,
        /// Quadrature samples per pixel (any model); without it, none for raw, 256 for log.
        #[arg(long, value_name = "S", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
        samples: Option<u32>,
        /// Latent window x0,x1,y0,y1 [default: -1.1,1.1,-1.1,1.1].
        #[arg(long, value_name = "X0,X1,Y0,Y1", value_parser = coords::view, allow_hyphen_values = true)]
        view: Option<View>,
        /// Do not write material names beside their points.
        #[arg(long)]
        no_labels: bool,
    },
    /// Find where MERL files land in a fitted latent space.
    ///
    /// For each file: the latent point whose reconstruction is closest to it,
    /// the error of that reconstruction against the material's own spread
    /// around the mean, and the three nearest materials of the model. The
    /// files must have the model's dims. A file that cannot be read gets one
    /// `error:` line; the others are still reported, and the exit status is 1.
    Locate {
        /// Model file written by `fit`.
        #[arg(value_name = "MODEL")]
        model: PathBuf,
        /// MERL `.binary` files.
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
    },
    /// Measure what accuracy costs in time and write a report with tables and plots.
    ///
    /// On a directory of MERL files: the leave-one-out reconstruction error
    /// of the GPLVM (closed form, no refit) for q = 1..Q and both transforms,
    /// beside PCA with as many components; Hooke-Jeeves vs L-BFGS and
    /// Hooke-Jeeves' minimum step (cost reached vs time); the albedo map's
    /// error and time vs quadrature samples and its time vs size; f32 vs f64
    /// stores. Writes REPORT_DIR/report.md, CSV files and PNG plots. Needs
    /// disk for the stores it builds (about 4 times the MERL files' size in
    /// f32) in a staging directory beside REPORT_DIR, removed at the end;
    /// REPORT_DIR appears (or replaces an earlier report) only when complete.
    Report {
        /// Directory of MERL `.binary` files.
        #[arg(value_name = "MERL_DIR")]
        dir: PathBuf,
        /// Report directory to write.
        #[arg(short = 'o', long = "output", value_name = "REPORT_DIR")]
        out: PathBuf,
        /// Largest latent dimension of the leave-one-out sweep [default: 8, 3 with --quick].
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16))]
        q_max: Option<u32>,
        /// Fewer settings (sample counts, map sizes, steps): a report in seconds on small data.
        #[arg(long)]
        quick: bool,
        /// Optimiser of the fits for q = 1..Q (the other one fits q = 2 as well;
        /// maps and the precision comparison use the Hooke-Jeeves fit, `fit`'s default).
        #[arg(long, value_enum, default_value_t = OptimizerArg::Lbfgs)]
        optimizer: OptimizerArg,
    },
    /// Show brdf-atlas at work on its embedded synthetic database, no download needed.
    ///
    /// Synthesises materials at the full MERL resolution into DIR/merl/,
    /// summarises them (name and albedo), fits a latent space to them
    /// (DIR/model.atlas), draws its map (DIR/map.png, .json, .exr) and
    /// writes a new material between the first two (DIR/reconstructed.binary).
    /// Needs about 35 MB of disk per material, and as much again for the model.
    Demo {
        /// Working directory for everything the demo writes.
        #[arg(long, default_value = "brdf-atlas-demo")]
        dir: PathBuf,
        /// Number of materials to synthesise (a 2-D map needs at least 3).
        #[arg(long, default_value_t = demo::DEFAULT_COUNT, value_parser = clap::value_parser!(u32).range(3..=10_000))]
        count: u32,
    },
}

/// `--transform` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum TransformArg {
    /// The reflectance itself (1/sr).
    Raw,
    /// log(1 + f cos_i cos_o): highlights weigh less.
    Log,
}

impl From<TransformArg> for TransformKind {
    fn from(t: TransformArg) -> Self {
        match t {
            TransformArg::Raw => TransformKind::Raw,
            TransformArg::Log => TransformKind::Log,
        }
    }
}

/// `--optimizer` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum OptimizerArg {
    /// Direct search with O(N^2) rank-one updates per trial.
    HookeJeeves,
    /// Projected L-BFGS on the analytic gradient.
    Lbfgs,
}

impl From<OptimizerArg> for OptimizerKind {
    fn from(o: OptimizerArg) -> Self {
        match o {
            OptimizerArg::HookeJeeves => OptimizerKind::HookeJeeves,
            OptimizerArg::Lbfgs => OptimizerKind::Lbfgs,
        }
    }
}

/// `--store-precision` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum PrecisionArg {
    /// 4 bytes a value.
    F32,
    /// 8 bytes a value.
    F64,
}

impl From<PrecisionArg> for Precision {
    fn from(p: PrecisionArg) -> Self {
        match p {
            PrecisionArg::F32 => Precision::F32,
            PrecisionArg::F64 => Precision::F64,
        }
    }
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
        Command::Fit {
            dir,
            model,
            q,
            transform,
            optimizer,
            store_precision,
            length_scale,
            noise,
            min_step,
        } => fit::run(&fit::Options {
            dir,
            model,
            q,
            transform: transform.into(),
            optimizer: optimizer.into(),
            precision: store_precision.into(),
            length_scale,
            noise,
            min_step,
        }),
        Command::Reconstruct { model, at, out } => {
            reconstruct::run(&reconstruct::Options { model, at, out })
        }
        Command::Eval {
            model,
            at,
            wi,
            wo,
            batch,
        } => eval::run(&eval::Options {
            model,
            at,
            wi,
            wo,
            batch,
        }),
        Command::Map {
            model,
            png,
            exr,
            json,
            size,
            contours,
            samples,
            view,
            no_labels,
        } => map::run(&map::Options {
            model,
            png,
            exr,
            json,
            size: size as usize,
            contours: contours as usize,
            samples: samples.map(|s| s as usize),
            view,
            labels: !no_labels,
        }),
        Command::Locate { model, files } => locate::run(&model, &files),
        Command::Report {
            dir,
            out,
            q_max,
            quick,
            optimizer,
        } => report::run(&report::Options {
            dir,
            out,
            q_max: q_max.map_or(
                if quick {
                    report::QUICK_Q_MAX
                } else {
                    report::DEFAULT_Q_MAX
                },
                |q| q as usize,
            ),
            quick,
            optimizer: optimizer.into(),
        }),
        Command::Demo { dir, count } => demo::run(&demo::Options {
            dir,
            count: count as usize,
        }),
    }
}

/// Heap accounting for `fit`'s summary (peak heap).
#[global_allocator]
static HEAP: brdf_atlas_core::heap::Counting = brdf_atlas_core::heap::Counting;

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
