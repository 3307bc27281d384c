//! `brdf-atlas eval`: RGB reflectance of the material at a latent point for
//! given pairs of directions, without building its table.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::args::{self, Angles, ModelPoint};
use crate::error::Error;
use crate::format::point;

/// Print the RGB reflectance of the material at a latent point for pairs of directions.
///
/// Directions are angles in degrees: theta from the normal, phi around
/// it. Give one incident direction and one or more outgoing ones
/// (`--wi 30,0 --wo 30,180 --wo 45,180`), or a file of pairs. Only the
/// bins asked for are reconstructed. A pair with a direction below the
/// horizon, or in a bin no input material measured, has no value.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub target: ModelPoint,
    /// Incident direction, theta,phi in degrees.
    #[arg(long, value_name = "THETA,PHI", value_parser = args::angles, allow_hyphen_values = true,
          required_unless_present = "batch", conflicts_with = "batch")]
    pub wi: Option<Angles>,
    /// Outgoing direction, theta,phi in degrees; repeat for more.
    #[arg(long, value_name = "THETA,PHI", value_parser = args::angles, allow_hyphen_values = true,
          required_unless_present = "batch", conflicts_with = "batch")]
    pub wo: Vec<Angles>,
    /// File of pairs, one a line: theta_i phi_i theta_o phi_o (degrees; `#` starts a comment).
    #[arg(long, value_name = "FILE")]
    pub batch: Option<PathBuf>,
    /// Also print the material's plausibility (clamped share of reflectance,
    /// largest directional albedo): one pass over the whole store.
    #[arg(long)]
    pub plausibility: bool,
}

/// What every bad batch line is told.
const BATCH_EXPECTED: &str = "expected four angles in degrees: theta_i phi_i theta_o phi_o";

/// Read a batch file: one pair a line, `theta_i phi_i theta_o phi_o` in
/// degrees, separated by blanks; empty lines and `#` comments are skipped.
pub fn read_batch(path: &Path) -> Result<Vec<(Angles, Angles)>, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let mut pairs = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let values: Option<Vec<f64>> = line
            .split_whitespace()
            .map(|s| s.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect();
        match values.as_deref() {
            Some(&[ti, pi, to, po]) => {
                pairs.push((Angles { theta: ti, phi: pi }, Angles { theta: to, phi: po }))
            }
            _ => {
                return Err(Error::Input(format!(
                    "{}:{}: {BATCH_EXPECTED}, got {line:?}",
                    path.display(),
                    k + 1
                )));
            }
        }
    }
    if pairs.is_empty() {
        return Err(Error::Input(format!(
            "{}: no direction pairs ({BATCH_EXPECTED}, one pair a line)",
            path.display()
        )));
    }
    Ok(pairs)
}

/// Run `eval`: one row per pair, reflectance or why there is none.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let pairs: Vec<(Angles, Angles)> = match (&args.batch, args.wi) {
        (Some(path), _) => read_batch(path)?,
        (None, Some(wi)) => args.wo.iter().map(|&wo| (wi, wo)).collect(),
        (None, None) => {
            return Err(Error::Input(
                "eval needs --wi and --wo, or --batch FILE".into(),
            ));
        }
    };
    let (model, x) = args.target.open()?;
    let blend = args.target.blend(&model, x)?;
    let directions: Vec<_> = pairs
        .iter()
        .map(|(wi, wo)| (wi.direction(), wo.direction()))
        .collect();
    let values = blend.eval_batch(&directions);
    model.verify()?;
    let mut out = io::stdout().lock();
    writeln!(
        out,
        "{} at {}: RGB reflectance (1/sr)",
        args.target.model.display(),
        point(x)
    )?;
    writeln!(
        out,
        "{:>8} {:>8} {:>8} {:>8}  {:>16} {:>16} {:>16}",
        "THETA_I", "PHI_I", "THETA_O", "PHI_O", "R", "G", "B"
    )?;
    for ((wi, wo), value) in pairs.iter().zip(values) {
        write!(
            out,
            "{:>8} {:>8} {:>8} {:>8}  ",
            wi.theta, wi.phi, wo.theta, wo.phi
        )?;
        match value {
            Some([r, g, b]) => writeln!(out, "{r:>16.9e} {g:>16.9e} {b:>16.9e}")?,
            None => writeln!(out, "below horizon / unmeasured")?,
        }
    }
    let c = blend.confidence();
    writeln!(
        out,
        "confidence: predictive variance {:.4} of the prior's 1; weights sum to {:.4} ({} blend)",
        c.variance,
        c.weight_sum,
        args.target.blend.name()
    )?;
    if args.plausibility {
        let p = blend.plausibility()?;
        writeln!(
            out,
            "plausibility: the clamp removes {:.4}% of the cosine-weighted reflectance ({:.4}% of the values); \
             largest directional albedo {:.4} (at {} degrees)",
            100.0 * p.clamped_reflectance,
            100.0 * p.clamped_values,
            p.max_albedo,
            p.max_albedo_incidence
        )?;
    }
    crate::cmd::reconstruct::warn(&model, x, &blend)?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batch_files_name_the_bad_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pairs.txt");
        std::fs::write(&path, "# wi wo\n30 0 30 180\n\n10 20 30 40 # ok\n").unwrap();
        let pairs = read_batch(&path).unwrap();
        assert_eq!(pairs.len(), 2);
        assert_eq!(
            pairs[1].1,
            Angles {
                theta: 30.0,
                phi: 40.0
            }
        );
        std::fs::write(&path, "30 0 30 180\n30 0 30\n").unwrap();
        let e = read_batch(&path).unwrap_err().to_string();
        assert!(
            e.contains("pairs.txt:2:") && e.contains(BATCH_EXPECTED),
            "{e}"
        );
        std::fs::write(&path, "# nothing\n").unwrap();
        let e = read_batch(&path).unwrap_err().to_string();
        assert!(e.contains("no direction pairs"), "{e}");
        let e = read_batch(&dir.path().join("missing.txt"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.txt"), "{e}");
    }
}
