//! Swatch sheets: lit spheres ([`crate::sphere`]) of the materials at a
//! grid of latent points (or at named materials), laid out in rows with
//! their latent coordinates under each, as a tone-mapped sRGB PNG (text in
//! the map's font) and a linear float EXR. Written atomically, like maps.

use std::io::Cursor;
use std::path::Path;

use brdf_atlas_core::{Atlas, BlendRule, CoreError, Result, View};
use brdf_atomic::{PendingFile, stage};

use crate::canvas::{Canvas, srgb, text_size};
use crate::sphere::{Light, Sphere, render, tone};

/// Space around a sphere, pixels.
const PAD: usize = 6;
/// Background (linear).
const BACKGROUND: f32 = 0.03;

/// One sphere of a sheet and the words under it.
#[derive(Debug, Clone, PartialEq)]
pub struct Swatch {
    /// The latent point.
    pub point: [f64; 2],
    /// Lines under the sphere (a name, the coordinates).
    pub lines: Vec<String>,
    /// The sphere.
    pub sphere: Sphere,
}

/// The centres of a `grid x grid` array of cells over `view`, row by row
/// from the top left (as the map's pixels run).
pub fn grid_points(view: &View, grid: usize) -> Vec<[f64; 2]> {
    (0..grid * grid)
        .map(|k| view.pixel_to_latent((k % grid) as f64, (k / grid) as f64, grid, grid))
        .collect()
}

/// Render the spheres of `atlas`'s model at `points` (labelled `names`, if given),
/// the material at each point formed by `rule` (the plausible rule's steps
/// for all points in one pass over the store).
/// [`CoreError::FileChanged`] if the store changed meanwhile.
pub fn swatches(
    atlas: &Atlas,
    points: &[[f64; 2]],
    names: Option<&[String]>,
    size: usize,
    lights: &[Light],
    rule: BlendRule,
) -> Result<Vec<Swatch>> {
    let model = atlas.model();
    let blends = match rule {
        BlendRule::Gp | BlendRule::Floor => points
            .iter()
            .map(|p| model.at(p, rule))
            .collect::<Result<Vec<_>>>()?,
        BlendRule::Plausible => {
            atlas.plausible_blends(&points.iter().map(|p| p.to_vec()).collect::<Vec<_>>())?
        }
    };
    let mut out = Vec::with_capacity(points.len());
    for (k, (p, blend)) in points.iter().zip(&blends).enumerate() {
        let sphere = render(blend, size, lights);
        let mut lines: Vec<String> = names.map(|n| vec![n[k].clone()]).unwrap_or_default();
        lines.push(format!("({:.2}, {:.2})", p[0], p[1]));
        out.push(Swatch {
            point: *p,
            lines,
            sphere,
        });
    }
    model.verify()?;
    Ok(out)
}

/// A laid-out sheet: linear radiance of the whole picture and its sRGB
/// version with the words.
pub struct Sheet {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Linear RGB, spheres on black (for the EXR).
    pub linear: Vec<[f32; 3]>,
    /// The PNG's pixels, 8-bit sRGB triples.
    pub srgb8: Vec<u8>,
}

/// Lay `swatches` out in `columns` columns.
pub fn compose(swatches: &[Swatch], columns: usize) -> Sheet {
    let columns = columns.max(1);
    let size = swatches.first().map_or(1, |s| s.sphere.size);
    let px = (size as f32 / 10.0).clamp(9.0, 13.0);
    let line_h = text_size("(0", px)[1].ceil() as usize + 1;
    let lines = swatches.iter().map(|s| s.lines.len()).max().unwrap_or(0);
    let (cell_w, cell_h) = (size + 2 * PAD, size + 2 * PAD + lines * line_h);
    let rows = swatches.len().div_ceil(columns);
    let (width, height) = (columns * cell_w, rows.max(1) * cell_h);
    let mut linear = vec![[0.0f32; 3]; width * height];
    let mut canvas = Canvas {
        width,
        height,
        px: vec![[srgb(BACKGROUND); 3]; width * height],
    };
    for (k, s) in swatches.iter().enumerate() {
        let (x0, y0) = ((k % columns) * cell_w + PAD, (k / columns) * cell_h + PAD);
        let sp = &s.sphere;
        for py in 0..sp.size {
            for px in 0..sp.size {
                let i = py * sp.size + px;
                let cov = sp.coverage[i];
                if cov > 0.0 {
                    let o = (y0 + py) * width + x0 + px;
                    linear[o] = sp.radiance[i].map(|v| v * cov);
                    let shown = sp.radiance[i].map(|v| srgb(tone(v)));
                    canvas.blend((x0 + px) as i64, (y0 + py) as i64, shown, cov);
                }
            }
        }
        for (j, line) in s.lines.iter().enumerate() {
            let text = fit(line, cell_w as f32 - 4.0, px);
            let w = text_size(&text, px)[0];
            let tx = (k % columns * cell_w) as f32 + (cell_w as f32 - w) / 2.0;
            let ty = (y0 + size + PAD / 2 + j * line_h) as f32;
            canvas.text(tx, ty, &text, px, [0.85; 3]);
        }
    }
    Sheet {
        width,
        height,
        linear,
        srgb8: canvas.to_8bit(),
    }
}

/// `s`, shortened with an ellipsis until it fits `width` pixels.
fn fit(s: &str, width: f32, px: f32) -> String {
    let mut chars: Vec<char> = s.chars().collect();
    let mut text = s.to_string();
    while text_size(&text, px)[0] > width && chars.len() > 1 {
        chars.pop();
        text = chars.iter().collect::<String>() + "\u{2026}";
    }
    text
}

fn write_error(path: &Path, e: impl std::fmt::Display) -> CoreError {
    CoreError::write(path, std::io::Error::other(e.to_string()))
}

fn stage_bytes(path: &Path, bytes: &[u8]) -> Result<PendingFile> {
    stage(path, |f| std::io::Write::write_all(f, bytes)).map_err(|e| CoreError::write(path, e))
}

/// The sheet as an 8-bit sRGB PNG, staged beside `path` until committed
/// ([`brdf_atomic::commit_all`]).
pub fn stage_png(path: &Path, sheet: &Sheet) -> Result<PendingFile> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, sheet.width as u32, sheet.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = enc.write_header().map_err(|e| write_error(path, e))?;
        writer
            .write_image_data(&sheet.srgb8)
            .map_err(|e| write_error(path, e))?;
    }
    stage_bytes(path, &bytes)
}

/// The sheet's linear radiance as a float RGB OpenEXR, staged like [`stage_png`].
pub fn stage_exr(path: &Path, sheet: &Sheet) -> Result<PendingFile> {
    use exr::prelude::*;
    let w = sheet.width;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let c = sheet.linear[y * w + x];
        (c[0], c[1], c[2])
    });
    let mut cursor = Cursor::new(Vec::new());
    Image::from_channels((sheet.width, sheet.height), channels)
        .write()
        .to_buffered(&mut cursor)
        .map_err(|e| write_error(path, e))?;
    stage_bytes(path, cursor.get_ref())
}
