//! `brdf-atlas map`: the albedo map of a 2-D latent space as a PNG (with
//! contours and labelled materials), optionally a float EXR, and always a
//! JSON sidecar describing the pixel <-> latent mapping.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use brdf_atlas_core::Model;
use brdf_atlas_core::render::{self, Picture};
use brdf_atlas_core::{AlbedoMethod, DEFAULT_SAMPLES, View};
use brdf_merl::atomic::commit_all;

use crate::error::Error;
use crate::fit::secs;
use crate::progress::Bars;

/// What to draw and where.
#[derive(Debug, Clone)]
pub struct Options {
    /// Model file.
    pub model: PathBuf,
    /// PNG to write.
    pub png: PathBuf,
    /// Float EXR to write, if any.
    pub exr: Option<PathBuf>,
    /// Sidecar; `None` means the PNG path with `.json`.
    pub json: Option<PathBuf>,
    /// Width and height in pixels.
    pub size: usize,
    /// Number of luminance contour lines.
    pub contours: usize,
    /// Quadrature samples per pixel; `None` picks by the model's transform.
    pub samples: Option<usize>,
    /// Latent window; `None` is the box `[-1, 1]^2` plus a margin.
    pub view: Option<View>,
    /// Write material names beside their points.
    pub labels: bool,
}

/// The sidecar path: as given, or the PNG's with `.json`.
pub fn json_path(options: &Options) -> PathBuf {
    options
        .json
        .clone()
        .unwrap_or_else(|| options.png.with_extension("json"))
}

/// The samples to use: as asked; else none (the exact linear shortcut) for
/// a linear transform, [`DEFAULT_SAMPLES`] for a non-linear one.
pub fn samples_for(model: &Model, asked: Option<usize>) -> Option<usize> {
    asked.or(if model.file().transform.is_linear() {
        None
    } else {
        Some(DEFAULT_SAMPLES)
    })
}

/// Compute the map and write every output; report what was done.
pub fn draw(model: &Model, options: &Options, report: &mut impl Write) -> Result<(), Error> {
    if model.q() != 2 {
        return Err(Error::Input(format!(
            "{}: a map needs a 2-D latent space, this model has q = {} (fit with --q 2)",
            model.path().display(),
            model.q()
        )));
    }
    let json = json_path(options);
    let mut outputs = vec![&options.png, &json];
    outputs.extend(&options.exr);
    for (k, a) in outputs.iter().enumerate() {
        if outputs[..k].contains(a) {
            return Err(Error::Input(format!(
                "{}: given for two outputs (PNG, JSON sidecar, EXR need different paths)",
                a.display()
            )));
        }
    }
    let view = options.view.unwrap_or_default();
    let samples = samples_for(model, options.samples);
    let t0 = Instant::now();
    let bars = Bars::new("preparing the map");
    let map = model.albedo_map(options.size, options.size, view, samples, &bars)?;
    drop(bars);
    let elapsed = t0.elapsed();
    let method = match map.method {
        AlbedoMethod::Linear => format!(
            "albedo blended from the {} materials' own albedos (exact: the {} transform is linear)",
            model.names().len(),
            model.file().transform.name()
        ),
        AlbedoMethod::Quadrature { samples, bins } => format!(
            "albedo integrated per pixel from {samples} quadrature samples ({bins} bins, {} transform)",
            model.file().transform.name()
        ),
    };
    let picture = Picture::new(model, map, options.contours);
    let sidecar = picture.sidecar(model.path());
    // Every output is complete on disk before any replaces an old one.
    let mut staged = vec![render::stage_png(&options.png, &picture, options.labels)?];
    if let Some(exr) = &options.exr {
        staged.push(render::stage_exr(exr, &picture.map)?);
    }
    staged.push(render::stage_sidecar(&json, &sidecar)?);
    commit_all(staged)?;
    writeln!(
        report,
        "map {}x{} of {} over x {}..{}, y {}..{}: {method}, {}",
        options.size,
        options.size,
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
        "  luminance {lo:.4} .. {hi:.4}, {} contour lines, {} materials marked",
        picture.levels.len(),
        picture.references.len()
    )?;
    writeln!(report, "  wrote {} (sRGB)", options.png.display())?;
    if let Some(exr) = &options.exr {
        writeln!(report, "  wrote {} (linear float RGB)", exr.display())?;
    }
    writeln!(
        report,
        "  wrote {} (view, pixel <-> latent mapping, material points)",
        json.display()
    )?;
    Ok(())
}

/// Run `map`.
pub fn run(options: &Options) -> Result<ExitCode, Error> {
    let model = Model::open(&options.model)?;
    draw(&model, options, &mut io::stdout().lock())?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// The default PNG sidecar next to `png`.
    fn default_json(png: &Path) -> PathBuf {
        json_path(&Options {
            model: PathBuf::new(),
            png: png.to_path_buf(),
            exr: None,
            json: None,
            size: 1,
            contours: 0,
            samples: None,
            view: None,
            labels: true,
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
