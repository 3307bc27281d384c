//! `brdf-atlas swatches`: a sheet of lit spheres of the materials at a grid
//! of latent points, or at named materials.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use brdf_atlas_core::{BlendRule, Model, View};
use brdf_atlas_pictures::sphere::{DEFAULT_LIGHTS, Light};
use brdf_atlas_pictures::swatch_sheet;
use brdf_atomic::commit_all;

use crate::args;
use crate::error::Error;
use crate::format::secs;

/// Largest sphere side, pixels.
const MAX_SIZE: i64 = 1024;

/// Render a sheet of lit spheres from a 2-D model.
///
/// Each sphere is the material at one latent point, seen by an orthographic
/// camera under directional lights (direct lighting only: by default a key
/// light from the upper left and a dimmer fill from the right); the BRDF is
/// evaluated by point queries for exactly the direction pairs the pixels
/// need. By default the points are the centres of an 8 x 8 grid over the
/// map's default view, rows from the top as on the map; `--materials`
/// renders the named materials of the model instead. Writes a tone-mapped
/// sRGB PNG with the latent coordinates under each sphere and, on request,
/// the linear radiance as a float OpenEXR.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Model file written by `fit` (q = 2).
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// PNG to write (the path ends in .png).
    #[arg(short = 'o', long = "output", value_name = "PNG")]
    pub png: PathBuf,
    /// Also write the linear radiance as a float OpenEXR (the path ends in .exr).
    #[arg(long, value_name = "EXR")]
    pub exr: Option<PathBuf>,
    /// Spheres per row and per column of the grid.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub grid: u32,
    #[arg(long, value_name = "X0,X1,Y0,Y1", help = view_help(), value_parser = args::view, allow_hyphen_values = true)]
    pub view: Option<View>,
    /// Side of each sphere, pixels.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(8..=MAX_SIZE))]
    pub size: u32,
    /// One sphere per named material of the model, instead of the grid (comma-separated).
    #[arg(long, value_name = "A,B,C", value_delimiter = ',')]
    pub materials: Vec<String>,
    /// A directional light X,Y,Z,E: direction towards it in camera space (x
    /// right, y up, z towards the viewer) and intensity (1 makes a white
    /// diffuse surface facing it 1); repeat for more. Replaces the default
    /// key (-0.45,0.55,0.7,0.9) and fill (0.75,-0.1,0.65,0.3).
    #[arg(long = "light", value_name = "X,Y,Z,E", value_parser = light, allow_hyphen_values = true)]
    pub lights: Vec<Light>,
    /// How each sphere's material is formed, as `reconstruct --blend`:
    /// `floor` (the default), `gp` or `plausible` (the plausible rule's
    /// steps for every sphere in one pass over the store).
    #[arg(long, value_name = "RULE", default_value = "floor", value_parser = args::blend_rule)]
    pub blend: BlendRule,
}

/// `--view`'s help, with the core's default view.
fn view_help() -> String {
    format!(
        "Latent window x0,x1,y0,y1 of the grid [default: {}]",
        args::default_view()
    )
}

/// Parse `x,y,z,e` into a [`Light`].
fn light(text: &str) -> Result<Light, String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--light expects four numbers X,Y,Z,E, got {text:?}"))?;
    match v[..] {
        [x, y, z, e]
            if v.iter().all(|c| c.is_finite())
                && (x, y, z) != (0.0, 0.0, 0.0)
                && (0.0..=1e6).contains(&e) =>
        {
            Ok(Light {
                direction: [x, y, z],
                intensity: e,
            })
        }
        _ => Err(format!(
            "--light expects X,Y,Z,E: a direction that is not zero and an intensity from 0 to 1e6, got {text:?}"
        )),
    }
}

/// Run `swatches`.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    for (path, ext, what) in [
        (Some(&args.png), "png", "-o"),
        (args.exr.as_ref(), "exr", "--exr"),
    ] {
        if let Some(p) = path.filter(|p| {
            !p.extension()
                .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext))
        }) {
            return Err(Error::Input(format!(
                "{}: {what} writes {} image, the path must end in .{ext}",
                p.display(),
                if ext == "png" { "a PNG" } else { "an OpenEXR" }
            )));
        }
    }
    if args.exr.as_ref() == Some(&args.png) {
        return Err(Error::Input(format!(
            "{}: given for both outputs",
            args.png.display()
        )));
    }
    let model = brdf_atlas_core::Atlas::new(Model::open(&args.model)?);
    if model.q() != 2 {
        return Err(Error::Input(format!(
            "{}: swatches need a 2-D latent space, this model has q = {} (fit with --q 2)",
            model.path().display(),
            model.q()
        )));
    }
    let (points, names, columns) = if args.materials.is_empty() {
        let grid = args.grid as usize;
        let view = args.view.unwrap_or_default();
        (swatch_sheet::grid_points(&view, grid), None, grid)
    } else {
        let latent = model.latent();
        let mut points = Vec::new();
        for name in &args.materials {
            let i = model.names().iter().position(|n| n == name).ok_or_else(|| {
                Error::Input(format!(
                    "{}: no material named {name:?} (see `brdf-atlas map`'s sidecar for the names)",
                    model.path().display()
                ))
            })?;
            points.push([latent[(i, 0)], latent[(i, 1)]]);
        }
        let columns = (points.len() as f64).sqrt().ceil() as usize;
        (points, Some(args.materials.clone()), columns)
    };
    let lights: &[Light] = if args.lights.is_empty() {
        &DEFAULT_LIGHTS
    } else {
        &args.lights
    };
    let t0 = Instant::now();
    let size = args.size as usize;
    let spheres =
        swatch_sheet::swatches(&model, &points, names.as_deref(), size, lights, args.blend)?;
    let laid = swatch_sheet::compose(&spheres, columns);
    let elapsed = t0.elapsed();
    let mut staged = vec![swatch_sheet::stage_png(&args.png, &laid)?];
    if let Some(exr) = &args.exr {
        staged.push(swatch_sheet::stage_exr(exr, &laid)?);
    }
    commit_all(staged)?;
    let mut out = io::stdout().lock();
    writeln!(
        out,
        "{} spheres of {size} px ({} blend) from {} under {} light(s), {}",
        points.len(),
        args.blend.name(),
        model.path().display(),
        lights.len(),
        secs(elapsed)
    )?;
    writeln!(
        out,
        "  wrote {} ({}x{}, sRGB)",
        args.png.display(),
        laid.width,
        laid.height
    )?;
    if let Some(exr) = &args.exr {
        writeln!(out, "  wrote {} (linear float RGB radiance)", exr.display())?;
    }
    Ok(ExitCode::SUCCESS)
}
