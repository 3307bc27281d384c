//! `brdf-atlas locate`: where new materials land in a fitted latent space.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use brdf_atlas_core::Located;
use brdf_atlas_core::Model;
use brdf_atlas_core::fidelity::{self, Judged};
use brdf_merl::MerlFile;

use crate::error::Error;
use crate::format::point;

/// Find where MERL files land in a fitted latent space.
///
/// For each file: the latent point whose reconstruction is closest to it
/// (searched over the whole latent plane, not only the fit's box; a point
/// outside the map's default view is said to be),
/// the error of that reconstruction against the material's own spread
/// around the mean, and the three nearest materials of the model. The
/// files must have the model's dims. A file that cannot be read gets one
/// `error:` line; the others are still reported, and the exit status is 1.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file written by `fit`.
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// MERL `.binary` files.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
}

/// Where a file landed, and how the model's material there compares with it.
pub struct Found {
    /// The point and the search's figures.
    pub located: Located,
    /// The file against the model's material at the point.
    pub there: Judged,
    /// The file against the nearest of the model's materials (at its own
    /// point, where the model gives it back).
    pub nearest: Judged,
}

/// Locate one MERL file in `model`, and judge the material at its point.
pub fn locate(model: &Model, path: &Path) -> Result<Found, Error> {
    if path.is_dir() {
        return Err(Error::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let file = MerlFile::open(path)?;
    let located = brdf_atlas_core::Located::find(model, &file)?;
    let truth = file.to_table();
    let there = fidelity::judge_at(model, &located.point, &truth)?;
    let &(i, _) = located.nearest.first().expect("a model has materials");
    let xi: Vec<f64> = (0..model.q()).map(|c| model.latent()[(i, c)]).collect();
    let nearest = fidelity::judge_at(model, &xi, &truth)?;
    Ok(Found {
        located,
        there,
        nearest,
    })
}

/// One file's report: point, error against scale, how the material there
/// compares with the file, nearest inputs.
pub fn write_located(
    out: &mut impl Write,
    model: &Model,
    path: &Path,
    found: &Found,
) -> io::Result<()> {
    let l = &found.located;
    writeln!(out, "{}: at {}", path.display(), point(&l.point))?;
    writeln!(
        out,
        "  rmse {:.4e}, spread {:.4e}, rmse/spread {:.4} (transformed space; 1 is no better than the mean material)",
        l.rmse,
        l.spread,
        l.rmse / l.spread.max(f64::MIN_POSITIVE)
    )?;
    let nearest: Vec<String> = l
        .nearest
        .iter()
        .take(3)
        .map(|&(i, d)| format!("{} ({d:.4})", model.names()[i]))
        .collect();
    writeln!(out, "  nearest  {}", nearest.join(", "))?;
    let e = found.there.albedo_errors();
    writeln!(
        out,
        "  there    albedo off by {:.1}%, {:.1}%, {:.1}% (r, g, b); log-relative table error {:.3} (ln(1 + v) RMSE {:.4})",
        100.0 * e[0],
        100.0 * e[1],
        100.0 * e[2],
        found.there.log_rel,
        found.there.log
    )?;
    let e = found.nearest.albedo_errors();
    writeln!(
        out,
        "           the nearest material, {}: {:.1}%, {:.1}%, {:.1}%; {:.3} ({:.4})",
        model.names()[l.nearest[0].0],
        100.0 * e[0],
        100.0 * e[1],
        100.0 * e[2],
        found.nearest.log_rel,
        found.nearest.log
    )?;
    if !l.in_default_view() {
        let [x, y] = [l.point[0], l.point[1]];
        let w = 0.1 + x.abs().max(y.abs()).max(1.0);
        writeln!(
            out,
            "  outside the map's default view ({}): see it with `map --view={},{},{},{}`",
            crate::args::default_view(),
            -w.ceil(),
            w.ceil(),
            -w.ceil(),
            w.ceil()
        )?;
    }
    Ok(())
}

/// Run `locate`: a report per readable file, one `error:` line per other
/// file, status 1 if there was any.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let model = Model::open(&args.model)?;
    let mut failed = false;
    let mut out = io::stdout().lock();
    for path in &args.files {
        match locate(&model, path) {
            Ok(l) => write_located(&mut out, &model, path, &l)?,
            Err(e) => {
                out.flush()?;
                eprintln!("error: {e}");
                failed = true;
            }
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}
