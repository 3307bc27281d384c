//! `brdf-atlas info`: check MERL files and summarise each one.

use std::collections::HashMap;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use brdf_merl::table::ChannelStats;
use brdf_merl::{Dims, MerlFile, MerlTable, Quadrature};
use rayon::prelude::*;

use crate::error::Error;
use crate::format::table_value;
use crate::progress;

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
#[derive(Debug, clap::Args)]
pub struct Args {
    /// MERL `.binary` files.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
}

/// Sub-cells per bin axis of the albedo rule: accurate to about 1e-4 on MERL dims.
const ALBEDO_SUBDIVISION: usize = 2;

/// What `info` reports about one readable file.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The file, as given.
    pub path: PathBuf,
    /// Its dims.
    pub dims: Dims,
    /// Per channel: unmeasured count, min, max, mean (reflectance, 1/sr).
    pub stats: [ChannelStats; 3],
    /// Albedo per channel.
    pub albedo: [f64; 3],
}

/// Read, validate and summarise `paths`, in order; a file that cannot be
/// read gives its error in its place.
///
/// Files are processed in parallel, each one sequentially, so every number
/// is the same whatever the thread count. The albedo rule is built once per
/// distinct dims.
pub fn summarise(paths: &[PathBuf]) -> Vec<Result<Summary, Error>> {
    let pb = progress::bar(paths.len(), "checking");
    let opened: Vec<Result<MerlFile, Error>> = paths
        .par_iter()
        .map(|path| {
            let file = open(path);
            pb.inc(1);
            file
        })
        .collect();
    pb.finish_and_clear();

    let mut rules: HashMap<Dims, Quadrature> = HashMap::new();
    for file in opened.iter().flatten() {
        let dims = file.dims();
        rules.entry(dims).or_insert_with(|| {
            let spinner = progress::spinner(format!("building the albedo rule for {dims}"));
            let rule = Quadrature::dense(dims, ALBEDO_SUBDIVISION);
            spinner.finish_and_clear();
            rule
        });
    }

    let pb = progress::bar(paths.len(), "integrating");
    let summaries = opened
        .into_par_iter()
        // A table buffer refilled file after file (rayon makes one per job,
        // a few per thread): a fresh 35 MB allocation per file, and its page
        // faults, made `info` on 100 files 2.5 times slower.
        .map_init(
            || None::<MerlTable>,
            |buffer, file| {
                let summary = file.map(|f| {
                    let table = match buffer {
                        Some(t) if t.dims() == f.dims() => {
                            f.copy_raw(0, t.raw_mut());
                            t
                        }
                        _ => buffer.insert(f.to_table()),
                    };
                    Summary {
                        path: f.path().to_path_buf(),
                        dims: f.dims(),
                        stats: table.channel_stats(),
                        albedo: rules[&f.dims()].albedo(table),
                    }
                });
                pb.inc(1);
                summary
            },
        )
        .collect();
    pb.finish_and_clear();
    summaries
}

fn open(path: &Path) -> Result<MerlFile, Error> {
    if path.is_dir() {
        return Err(Error::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    Ok(MerlFile::open(path)?)
}

/// Run `info`: the table on stdout, a warning for dims other than MERL's,
/// one `error:` line per unreadable file on stderr, status 1 if there was any
/// (even when stdout was closed early).
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    let results = summarise(&args.files);
    let good: Vec<&Summary> = results.iter().filter_map(|r| r.as_ref().ok()).collect();
    let report = if good.is_empty() {
        Ok(())
    } else {
        write_table(&mut io::stdout().lock(), &good).map_err(Error::from)
    };
    let odd: Vec<&&Summary> = good.iter().filter(|s| s.dims != Dims::MERL).collect();
    match odd[..] {
        [] => {}
        [one] => eprintln!(
            "warning: {} is {}, not {}: BRDF Explorer needs {}",
            one.path.display(),
            one.dims,
            Dims::MERL,
            Dims::MERL
        ),
        _ => eprintln!(
            "warning: {} of {} files are not {} (see DIMS): BRDF Explorer needs {}",
            odd.len(),
            good.len(),
            Dims::MERL,
            Dims::MERL
        ),
    }
    let mut failed = false;
    for e in results.iter().filter_map(|r| r.as_ref().err()) {
        eprintln!("error: {e}");
        failed = true;
    }
    match report {
        Ok(()) if !failed => Ok(ExitCode::SUCCESS),
        Err(e) if !failed => Err(e),
        Ok(()) => Ok(ExitCode::FAILURE),
        Err(e) => {
            if !e.is_broken_pipe() {
                eprintln!("error: {e}");
            }
            Ok(ExitCode::FAILURE)
        }
    }
}

/// The full report: one row per channel, the file and its dims on the first.
pub fn write_table(out: &mut impl Write, summaries: &[&Summary]) -> io::Result<()> {
    let name_width = summaries
        .iter()
        .map(|s| s.path.display().to_string().chars().count())
        .max()
        .unwrap_or(0)
        .max(4);
    let dims_width = summaries
        .iter()
        .map(|s| s.dims.to_string().len())
        .max()
        .unwrap_or(0)
        .max(4);
    writeln!(
        out,
        "{:<name_width$}  {:<dims_width$}  CH  {:>9}  {:>10}  {:>10}  {:>10}  {:>8}",
        "FILE", "DIMS", "INVALID", "MIN", "MAX", "MEAN", "ALBEDO"
    )?;
    for s in summaries {
        for (c, channel) in ["R", "G", "B"].iter().enumerate() {
            let (name, dims) = if c == 0 {
                (s.path.display().to_string(), s.dims.to_string())
            } else {
                (String::new(), String::new())
            };
            let st = &s.stats[c];
            writeln!(
                out,
                "{name:<name_width$}  {dims:<dims_width$}  {channel:<2}  {:>9}  {:>10}  {:>10}  {:>10}  {:>8.4}",
                st.invalid,
                table_value(st.min),
                table_value(st.max),
                table_value(st.mean),
                s.albedo[c],
            )?;
        }
    }
    Ok(())
}

/// A compact report: name (file stem) and albedo, for the demo.
pub fn write_albedo_table(out: &mut impl Write, summaries: &[&Summary]) -> io::Result<()> {
    let names: Vec<String> = summaries
        .iter()
        .map(|s| {
            s.path
                .file_stem()
                .unwrap_or(s.path.as_os_str())
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    let width = names
        .iter()
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(0)
        .max(8);
    writeln!(
        out,
        "{:<width$}  {:>8}  {:>8}  {:>8}",
        "MATERIAL", "ALBEDO R", "G", "B"
    )?;
    for (name, s) in names.iter().zip(summaries) {
        let [r, g, b] = s.albedo;
        writeln!(out, "{name:<width$}  {r:>8.4}  {g:>8.4}  {b:>8.4}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_rows_align() {
        let stats = ChannelStats {
            min: 0.001,
            max: 250.0,
            mean: 0.3,
            invalid: 12,
        };
        let summary = |name: &str, dims| Summary {
            path: PathBuf::from(name),
            dims,
            stats: [stats; 3],
            albedo: [0.5, 0.25, 0.125],
        };
        let a = summary("a.binary", Dims::MERL);
        let b = summary("longer-name.binary", Dims::new(8, 8, 16).unwrap());
        let mut out = Vec::new();
        write_table(&mut out, &[&a, &b]).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 7, "{text}");
        assert!(
            lines
                .iter()
                .all(|l| l.chars().count() == lines[0].chars().count()),
            "{text}"
        );
        assert!(
            lines[1].starts_with("a.binary            90x90x180  R"),
            "{text}"
        );
        assert!(
            lines[4].starts_with("longer-name.binary  8x8x16     R"),
            "{text}"
        );
        assert!(lines[5].ends_with("0.2500"), "{text}");
    }
}
