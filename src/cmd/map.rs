//! `brdf-atlas map`: the albedo map of a 2-D latent space as a PNG (with
//! contours and labelled materials), optionally a float EXR, and always a
//! JSON sidecar describing the pixel <-> latent mapping.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use brdf_atlas_core::Model;
use brdf_atlas_core::limits::MAX_MAP_SIDE;
use brdf_atlas_core::{AlbedoMethod, BlendRule, DEFAULT_SAMPLES, LOW_CONFIDENCE_VARIANCE, View};
use brdf_atlas_pictures::map_picture::{self, Picture, Style};
use brdf_atomic::commit_all;

use crate::args;
use crate::error::Error;
use crate::format::secs;
use crate::progress::Bars;

/// `--contours` when not given.
pub const DEFAULT_CONTOURS: u32 = 12;
/// `--size` when not given.
pub const DEFAULT_SIZE: u32 = 1024;

/// Draw the albedo map of a 2-D latent space.
///
/// Each pixel is a latent point coloured by the albedo of the material
/// there, faded towards grey where the model knows little (the GP's
/// predictive variance above 0.5); luminance contour lines, the model's
/// materials (dots, names that never overlap, with leader lines where
/// needed), latent-axis ticks and a luminance key are drawn on top. Writes
/// an sRGB PNG, a JSON sidecar with the view window, the pixel <-> latent
/// mapping, the material points, the label boxes and the confidence rule,
/// and on request a linear float EXR (RGB and the variance in V). For a `raw` model the albedo is
/// blended exactly from the materials' albedos; for `log` it is the albedo
/// field: exact albedos at refined grids of nodes and the polynomial through
/// them (within 0.25% by its error estimate), where that costs less than
/// integrating every pixel from 256 quadrature samples (zoomed-in views get
/// one); else the sampled field, the same polynomial through albedos
/// integrated with 1024 quadrature samples at its nodes (several times
/// faster than integrating every pixel, and no less accurate: a few per
/// cent off at worst); else every pixel is integrated from 256 samples.
/// --samples S always integrates per pixel. `fit` saves the default view's
/// field beside the model (MODEL.fields) and `map` adds those it builds, so
/// that later maps, in any program, start from them; a view inside a saved
/// field's region is drawn from it. Once `brdf-atlas prepare
/// MODEL` has saved the prepared map (MODEL.lattice), every map's pixels
/// inside the default view are drawn from it: a fraction of a second,
/// within its tolerance of the exact albedos.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Model file written by `fit` (q = 2).
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// PNG to write (the path ends in .png).
    #[arg(short = 'o', long = "output", value_name = "PNG")]
    pub png: PathBuf,
    /// Also write the linear albedo as a float OpenEXR (the path ends in .exr).
    #[arg(long, value_name = "EXR")]
    pub exr: Option<PathBuf>,
    /// JSON sidecar to write [default: the PNG path with .json].
    #[arg(long, value_name = "JSON")]
    pub json: Option<PathBuf>,
    /// Width and height in pixels.
    #[arg(long, default_value_t = DEFAULT_SIZE, value_parser = clap::value_parser!(u32).range(1..=MAX_MAP_SIDE as i64))]
    pub size: u32,
    /// Number of luminance contour lines.
    #[arg(long, default_value_t = DEFAULT_CONTOURS, value_parser = clap::value_parser!(u32).range(0..=1000))]
    pub contours: u32,
    #[arg(long, value_name = "S", help = samples_help(), value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub samples: Option<u32>,
    #[arg(long, value_name = "X0,X1,Y0,Y1", help = view_help(), value_parser = args::view, allow_hyphen_values = true)]
    pub view: Option<View>,
    /// The material each pixel shows, as `reconstruct --blend`: `floor`
    /// (the default: the soft floor, never clamped) or `gp` (the GP's blend,
    /// clamped to >= 0; exact and fast for the raw transform). The plausible
    /// rule has no map: its steps need a pass over the store per point.
    #[arg(long, value_name = "RULE", default_value = "floor", value_parser = args::blend_rule)]
    pub blend: BlendRule,
    /// Do not write material names beside their points.
    #[arg(long)]
    pub no_labels: bool,
    /// Draw neither the colour key nor the latent-axis ticks (maps smaller
    /// than 200 pixels a side never have them).
    #[arg(long)]
    pub no_key: bool,
}

/// `--samples`' help, with the core's default.
fn samples_help() -> String {
    format!(
        "Integrate every pixel from S quadrature samples (any model); without it, raw is exact and log uses the prepared map (brdf-atlas prepare) inside the default view, else the albedo field where it is cheaper than {DEFAULT_SAMPLES} samples a pixel"
    )
}

/// `--view`'s help, with the core's default view.
fn view_help() -> String {
    format!(
        "Latent window x0,x1,y0,y1 [default: {}]",
        args::default_view()
    )
}

/// The sidecar path: as given, or the PNG's with `.json`.
pub fn json_path(args: &Args) -> PathBuf {
    args.json
        .clone()
        .unwrap_or_else(|| args.png.with_extension("json"))
}

/// Does `path` end in `.ext` (any case)?
fn has_extension(path: &Path, ext: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext))
}

/// The formats follow from the options, so each path must end as its
/// format does: `-o x.jpg` would otherwise be PNG bytes under a JPEG name.
fn check_extensions(args: &Args) -> Result<(), Error> {
    if !has_extension(&args.png, "png") {
        return Err(Error::Input(format!(
            "{}: map writes a PNG image, the output must end in .png (a float OpenEXR goes to --exr FILE.exr)",
            args.png.display()
        )));
    }
    if let Some(exr) = args.exr.as_ref().filter(|p| !has_extension(p, "exr")) {
        return Err(Error::Input(format!(
            "{}: --exr writes an OpenEXR image, the path must end in .exr",
            exr.display()
        )));
    }
    Ok(())
}

/// Compute the map and write every output; report what was done.
pub fn draw(
    model: &brdf_atlas_core::Atlas,
    args: &Args,
    report: &mut impl Write,
) -> Result<(), Error> {
    check_extensions(args)?;
    if model.q() != 2 {
        return Err(Error::Input(format!(
            "{}: a map needs a 2-D latent space, this model has q = {} (fit with --q 2)",
            model.path().display(),
            model.q()
        )));
    }
    let json = json_path(args);
    let mut outputs = vec![&args.png, &json];
    outputs.extend(&args.exr);
    for (k, a) in outputs.iter().enumerate() {
        if outputs[..k].contains(a) {
            return Err(Error::Input(format!(
                "{}: given for two outputs (PNG, JSON sidecar, EXR need different paths)",
                a.display()
            )));
        }
    }
    let view = args.view.unwrap_or_default();
    let samples = args.samples.map(|s| s as usize);
    let t0 = Instant::now();
    let bars = Bars::new("preparing the map");
    let size = args.size as usize;
    let map = model.map(
        brdf_atlas_core::MapRequest::new(size, size)
            .view(view)
            .samples(samples)
            .rule(args.blend)
            .progress(&bars),
    )?;
    drop(bars);
    let elapsed = t0.elapsed();
    let blend = match map.blend {
        BlendRule::Floor => String::new(),
        rule => format!(" ({} blend)", rule.name()),
    };
    let method = match map.method {
        AlbedoMethod::Linear => format!(
            "albedo blended from the {} materials' own albedos (exact: the {} transform is linear)",
            model.names().len(),
            model.file().transform.name()
        ),
        AlbedoMethod::Field {
            nodes,
            patches,
            estimate,
        } => format!(
            "albedo field of the {} transform: exact albedos at {nodes} nodes, a polynomial on {patches} patches (error estimate {:.2}%)",
            model.file().transform.name(),
            100.0 * estimate
        ),
        AlbedoMethod::SampledField {
            samples,
            nodes,
            patches,
            estimate,
            check,
        } => format!(
            "sampled albedo field of the {} transform: albedos integrated with {samples} quadrature samples at {nodes} nodes, a polynomial on {patches} patches{}; `brdf-atlas prepare` for exact albedos",
            model.file().transform.name(),
            // The refinement's estimate says how well the polynomial
            // follows the sampled rule, not how far that rule is from the
            // albedo: shown only where no check was made.
            match check {
                Some(_) => crate::format::field_check(check),
                None => format!(
                    " (error estimate against the nodes' own rule {:.2}%)",
                    100.0 * estimate
                ),
            }
        ),
        AlbedoMethod::Lattice {
            nodes,
            tolerance,
            share,
        } => format!(
            "prepared map {}: exact albedos at {nodes} lattice nodes, a cubic between them (tolerance {:.2}%){}",
            brdf_atlas_core::lattice_path(model.path()).display(),
            100.0 * tolerance,
            if share < 1.0 {
                format!(
                    ", for the {:.1}% of the pixels inside the default view",
                    100.0 * share
                )
            } else {
                String::new()
            }
        ),
        AlbedoMethod::Quadrature { samples, bins } => format!(
            "albedo integrated per pixel from {samples} quadrature samples ({bins} bins, {} transform)",
            model.file().transform.name()
        ),
    };
    let style = Style {
        labels: !args.no_labels,
        key: !args.no_key,
    };
    let picture = Picture::styled(model, map, args.contours as usize, style);
    let sidecar = picture.sidecar(model.path());
    // Every output is complete on disk before any replaces an old one.
    let mut staged = vec![map_picture::stage_png(&args.png, &picture)?];
    if let Some(exr) = &args.exr {
        staged.push(map_picture::stage_exr(exr, &picture.map)?);
    }
    staged.push(map_picture::stage_sidecar(&json, &sidecar)?);
    commit_all(staged)?;
    // The field the map was drawn from, for the next map in any program.
    let saved = match model.save_fields() {
        Ok(saved) => saved,
        Err(e) => {
            eprintln!("note: {e}; the map's field is not saved beside the model");
            None
        }
    };
    writeln!(
        report,
        "map {size}x{size} of {}{blend} over x {}..{}, y {}..{}: {method}, {}",
        model.path().display(),
        view.x0,
        view.x1,
        view.y0,
        view.y1,
        secs(elapsed)
    )?;
    let [lo, hi] = sidecar.luminance_range;
    writeln!(
        report,
        "  luminance {lo:.4} .. {hi:.4}, {} contour lines, {} materials marked, {} labelled",
        picture.levels.len(),
        picture.references.len(),
        sidecar.labels.len()
    )?;
    let variance = &picture.map.variance;
    let low = variance
        .iter()
        .filter(|&&v| f64::from(v) > LOW_CONFIDENCE_VARIANCE)
        .count();
    let (vlo, vhi) = variance
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    writeln!(
        report,
        "  predictive variance {vlo:.4} .. {vhi:.4}; above {LOW_CONFIDENCE_VARIANCE} (the model knows little, faded towards grey) on {:.1}% of the map",
        100.0 * low as f64 / variance.len().max(1) as f64
    )?;
    writeln!(report, "  wrote {} (sRGB)", args.png.display())?;
    if let Some(path) = saved {
        writeln!(
            report,
            "  saved the map's field in {} (later maps of the model start from it)",
            path.display()
        )?;
    }
    if let Some(exr) = &args.exr {
        writeln!(
            report,
            "  wrote {} (linear float RGB, predictive variance in V)",
            exr.display()
        )?;
    }
    writeln!(
        report,
        "  wrote {} (view, pixel <-> latent mapping, material points, label boxes, confidence rule)",
        json.display()
    )?;
    Ok(())
}

/// Run `map`.
pub fn run(args: &Args) -> Result<ExitCode, Error> {
    // Before the model is read: a misnamed output is quick to tell.
    check_extensions(args)?;
    let model = brdf_atlas_core::Atlas::new(Model::open(&args.model)?);
    if let Err(e) = model.prepared_map() {
        eprintln!("note: {e}; the map is drawn without it");
    }
    if let Err(e) = model.saved_fields() {
        eprintln!("note: {e}; the map builds its field anew");
    }
    draw(&model, args, &mut io::stdout().lock())?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default PNG sidecar next to `png`.
    fn default_json(png: &Path) -> PathBuf {
        json_path(&Args {
            model: PathBuf::new(),
            png: png.to_path_buf(),
            exr: None,
            json: None,
            size: 1,
            contours: 0,
            samples: None,
            view: None,
            blend: BlendRule::default(),
            no_labels: false,
            no_key: false,
        })
    }

    #[test]
    fn sidecar_defaults_to_the_png_with_json() {
        assert_eq!(
            default_json(Path::new("a/map.png")),
            Path::new("a/map.json")
        );
        assert_eq!(default_json(Path::new("map")), Path::new("map.json"));
    }
}
