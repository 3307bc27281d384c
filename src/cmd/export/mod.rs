//! `brdf-atlas export`: a material of the map (or a MERL file) as an
//! analytic material other tools read: glTF 2.0, MaterialX, Mitsuba 3,
//! with what the fit loses shown beside it.

pub mod compare;

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use brdf_atlas_analytic::export::{self, Export, RenderedErrors};
use brdf_atlas_core::{BlendRule, Model};
use brdf_atlas_pictures::sphere::{DEFAULT_LIGHTS, Light};
use brdf_atlas_pictures::swatch_sheet::{self, Swatch};
use brdf_atomic::{PendingFile, commit_all};
use brdf_merl::MerlTable;

use crate::args::{self, Point};
use crate::error::Error;
use crate::format::{point, secs};

use compare::{Compared, compare, difference};

/// Side of the comparison's spheres, pixels.
pub const SPHERE: usize = 128;
/// How much brighter the difference sphere is drawn than it is.
const DIFFERENCE_GAIN: f32 = 4.0;

/// Fit an analytic material to a point of the map and write it as glTF,
/// MaterialX and Mitsuba 3.
///
/// The material (at `--at`, at each of `--materials`, or the MERL file
/// SOURCE) is fitted with glTF 2.0's metallic-roughness BRDF and
/// KHR_materials_specular (base colour, metallic, roughness, specular
/// factor and colour) in the cosine-weighted log-relative error over a
/// subsample of its bins. For each material NAME the directory OUT gets
/// NAME.glb (a sphere carrying the material), NAME.mtlx (MaterialX,
/// Standard Surface), NAME.mitsuba.json (a Mitsuba 3 `principled`
/// dictionary), NAME.png (the measured material, the fit and their
/// difference times 4, lit spheres under the swatch lights) and
/// NAME.fit.json (the parameters and every error). Prints the rendered
/// error (sum |L' - L| / sum L over the sphere's pixels, linear radiance)
/// beside two baselines measured the same way: the Lambertian of the
/// material's albedo, and one GGX lobe over a Lambertian base.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Model file written by `fit` (with --at or --materials), or a MERL .binary file.
    #[arg(value_name = "SOURCE")]
    pub source: PathBuf,
    /// Latent point x,y of the model.
    #[arg(long, value_name = "X,Y", value_parser = args::point, allow_hyphen_values = true, conflicts_with = "materials")]
    pub at: Option<Point>,
    /// Named materials of the model, at their own points (comma-separated).
    #[arg(long, value_name = "A,B,C", value_delimiter = ',')]
    pub materials: Vec<String>,
    /// Directory to write into (created if missing).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub out: PathBuf,
    /// Base name of the files for --at or a MERL file [default: at_X_Y, or the file's stem].
    #[arg(long, value_name = "NAME", conflicts_with = "materials")]
    pub name: Option<String>,
    /// How a point's material is formed, as `reconstruct --blend`.
    #[arg(long, value_name = "RULE", default_value = "floor", value_parser = args::blend_rule)]
    pub blend: BlendRule,
}

/// A table to export and where it came from.
struct Source {
    name: String,
    origin: String,
    table: MerlTable,
}

/// Where the tables come from: a MERL file, or a model's points (each
/// reconstructed only when its turn comes, so one table is in memory).
enum Sources {
    /// Read at once (a bad file fails before anything is written), taken on use.
    File(PathBuf, Option<MerlTable>),
    Points(Box<Model>, Vec<(String, Vec<f64>)>),
}

impl Sources {
    fn len(&self) -> usize {
        match self {
            Sources::File(..) => 1,
            Sources::Points(_, points) => points.len(),
        }
    }

    fn get(&mut self, k: usize, args: &Args) -> Result<Source, Error> {
        match self {
            Sources::File(path, table) => {
                let table = table
                    .take()
                    .ok_or_else(|| Error::Input(format!("{}: asked for twice", path.display())))?;
                let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
                Ok(Source {
                    name: args
                        .name
                        .clone()
                        .or(stem)
                        .unwrap_or_else(|| "material".into()),
                    origin: path.display().to_string(),
                    table,
                })
            }
            Sources::Points(model, points) => {
                let (name, x) = &points[k];
                let table = model.at(x, args.blend)?.table()?;
                Ok(Source {
                    origin: format!(
                        "{} at {} ({} blend)",
                        model.path().display(),
                        point(x),
                        args.blend.name()
                    ),
                    name: name.clone(),
                    table,
                })
            }
        }
    }
}

fn sources(args: &Args) -> Result<Sources, Error> {
    if args.at.is_none() && args.materials.is_empty() {
        let table = MerlTable::read(&args.source).map_err(|e| {
            // A model given without a point: say what it needs.
            if Model::open(&args.source).is_ok() {
                Error::Input(format!(
                    "{}: is a model; export needs --at X,Y or --materials A,B with it",
                    args.source.display()
                ))
            } else {
                Error::from(e)
            }
        })?;
        return Ok(Sources::File(args.source.clone(), Some(table)));
    }
    let model = Model::open(&args.source)?;
    let mut points: Vec<(String, Vec<f64>)> = Vec::new();
    if let Some(at) = &args.at {
        let x = at.check(model.q(), &args.source)?.to_vec();
        let coords: Vec<String> = x.iter().map(|v| format!("{v:.3}")).collect();
        let name = args
            .name
            .clone()
            .unwrap_or_else(|| format!("at_{}", coords.join("_")));
        points.push((name, x));
    }
    let latent = model.latent();
    for name in &args.materials {
        let i = model
            .names()
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| {
                Error::Input(format!(
                    "{}: no material named {name:?} (see `brdf-atlas map`'s sidecar for the names)",
                    model.path().display()
                ))
            })?;
        points.push((
            name.clone(),
            (0..model.q()).map(|k| latent[(i, k)]).collect(),
        ));
    }
    for (k, (name, _)) in points.iter().enumerate() {
        if points[..k].iter().any(|(n, _)| n == name) {
            return Err(Error::Input(format!(
                "{}: {name:?} is asked for twice",
                args.source.display()
            )));
        }
    }
    Ok(Sources::Points(Box::new(model), points))
}

/// The lights as the analytic crate takes them.
fn analytic_lights(lights: &[Light]) -> Vec<brdf_atlas_analytic::Light> {
    lights
        .iter()
        .map(|l| brdf_atlas_analytic::Light {
            direction: l.direction,
            intensity: l.intensity,
        })
        .collect()
}

/// The rendered errors of `c`, measured under `lights` on spheres of [`SPHERE`] pixels.
fn rendered_errors(c: &Compared, lights: &[Light]) -> RenderedErrors {
    RenderedErrors {
        principled: c.rendered.principled,
        single_lobe: c.rendered.single_lobe,
        lambertian: c.rendered.lambertian,
        held_out: c.rendered.held_out,
        lights: analytic_lights(lights),
        held_out_lights: analytic_lights(&compare::HELD_OUT_LIGHTS),
        sphere_pixels: SPHERE,
    }
}

/// The side-by-side picture: measured, fit, difference.
fn picture(path: &Path, src: &Source, c: &Compared) -> Result<PendingFile, Error> {
    let diff = difference(&c.measured, &c.fitted, DIFFERENCE_GAIN);
    let cell = |lines: Vec<String>, sphere| Swatch {
        point: [0.0; 2],
        lines,
        sphere,
    };
    let sheet = swatch_sheet::compose(
        &[
            cell(
                vec![src.name.clone(), "measured".into()],
                c.measured.clone(),
            ),
            cell(
                vec![
                    "glTF fit".into(),
                    format!("{:.1}% off", 100.0 * c.rendered.principled),
                ],
                c.fitted.clone(),
            ),
            cell(
                vec!["|difference|".into(), format!("x{DIFFERENCE_GAIN}")],
                diff,
            ),
        ],
        3,
    );
    Ok(swatch_sheet::stage_png(path, &sheet)?)
}

/// Stage the five files of one material: the analytic crate's four
/// documents and the picture.
fn stage_all(
    dir: &Path,
    src: &Source,
    c: &Compared,
    lights: &[Light],
) -> Result<Vec<PendingFile>, Error> {
    let rendered = rendered_errors(c, lights);
    let e = Export {
        name: &src.name,
        source: &src.origin,
        fits: &c.fits,
        rendered: Some(&rendered),
    };
    let mut files = export::stage(dir, &e)?;
    files.push(picture(&dir.join(format!("{}.png", src.name)), src, c)?);
    Ok(files)
}

/// Run `export`.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    if let Some(name) = &args.name
        && !export::is_file_stem(name)
    {
        return Err(Error::Input(format!(
            "--name {name:?}: expected a file name without a directory or a leading dot"
        )));
    }
    let mut sources = sources(args)?;
    if args.out.exists() && !args.out.is_dir() {
        return Err(Error::Input(format!(
            "{}: is not a directory",
            args.out.display()
        )));
    }
    std::fs::create_dir_all(&args.out).map_err(|source| Error::CreateDir {
        path: args.out.clone(),
        source,
    })?;
    let lights: &[Light] = &DEFAULT_LIGHTS;
    let mut staged = Vec::new();
    let mut names = Vec::new();
    let mut out = io::stdout().lock();
    for k in 0..sources.len() {
        let t0 = Instant::now();
        let src = &sources.get(k, args)?;
        names.push(src.name.clone());
        let c = compare(&src.table, &src.name, SPHERE, lights)?;
        let elapsed = t0.elapsed();
        let p = &c.fits.principled.model;
        writeln!(
            out,
            "{}: {} (fit {}; with the table and the pictures {})",
            src.name,
            src.origin,
            secs(c.fit_time),
            secs(elapsed)
        )?;
        writeln!(
            out,
            "  glTF       base colour ({:.3}, {:.3}, {:.3}), metallic {:.3}, roughness {:.3}, specular {:.3} ({:.3}, {:.3}, {:.3}), ior {:.3}",
            p.base_color[0],
            p.base_color[1],
            p.base_color[2],
            p.metallic,
            p.roughness,
            p.specular,
            p.specular_color[0],
            p.specular_color[1],
            p.specular_color[2],
            p.ior
        )?;
        writeln!(
            out,
            "  error      rendered {:.2}% ({:.2}% under other lights; one GGX lobe + Lambertian {:.2}%, Lambertian of the albedo {:.2}%); table {:.4} ({:.4}, {:.4})",
            100.0 * c.rendered.principled,
            100.0 * c.rendered.held_out,
            100.0 * c.rendered.single_lobe,
            100.0 * c.rendered.lambertian,
            c.fits.principled.error,
            c.fits.single_lobe.error,
            c.fits.lambertian.error
        )?;
        staged.extend(stage_all(&args.out, src, &c, lights)?);
    }
    if let Sources::Points(model, _) = &sources {
        model.verify()?;
    }
    commit_all(staged)?;
    for name in &names {
        writeln!(
            out,
            "  wrote {}/{name}.{{glb,mtlx,mitsuba.json,fit.json,png}}",
            args.out.display(),
        )?;
    }
    Ok(ExitCode::SUCCESS)
}
