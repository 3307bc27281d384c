//! Map outputs: a tone-mapped sRGB PNG with contour lines and labelled
//! reference points, a linear float EXR, and a JSON sidecar describing the
//! pixel <-> latent mapping and the reference points so that other tools
//! (the BRDF Explorer plugin) can draw and hit-test without recomputing.
//! Every file is written atomically.

use std::io::Cursor;
use std::path::Path;

use brdf_atomic::{PendingFile, stage};
use font8x8::UnicodeFonts;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::limits::{LATENT_LIMIT, MAX_MATERIALS};
use crate::model::Model;
use crate::query::contour::{Segment, contour_levels, contours, luminance};
use crate::query::map::{AlbedoMap, AlbedoMethod, View};

/// An input material drawn on the map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// Material name.
    pub name: String,
    /// Latent coordinates.
    pub latent: [f64; 2],
    /// Pixel coordinates (continuous; pixel `k` spans `[k, k+1)`).
    pub pixel: [f64; 2],
}

/// The JSON sidecar of a map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sidecar {
    /// Always `brdf-atlas-map`.
    pub format: String,
    /// Sidecar version (1).
    pub version: u32,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// The latent window.
    pub view: View,
    /// How pixels map to latent points, in words.
    pub pixel_to_latent: String,
    /// How the albedo was computed.
    pub method: AlbedoMethod,
    /// Luminance of each contour line.
    pub contour_levels: Vec<f32>,
    /// Smallest and largest luminance on the map.
    pub luminance_range: [f32; 2],
    /// The input materials.
    pub references: Vec<Reference>,
    /// The model file the map shows.
    pub model: String,
}

/// Everything drawn on a map picture.
pub struct Picture {
    /// The map.
    pub map: AlbedoMap,
    /// Contour levels (luminance).
    pub levels: Vec<f32>,
    /// Contour segments, pixel coordinates.
    pub segments: Vec<Segment>,
    /// Reference points.
    pub references: Vec<Reference>,
}

impl Picture {
    /// Contours at `contours` evenly spaced levels and the model's materials as references.
    pub fn new(model: &Model, map: AlbedoMap, contours_count: usize) -> Picture {
        let levels = contour_levels(&map, contours_count);
        let segments = contours(&map, &levels);
        let latent = model.latent();
        let references = model
            .names()
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let x = [latent[(i, 0)], latent[(i, 1)]];
                Reference {
                    name: name.clone(),
                    latent: x,
                    pixel: map.view.latent_to_pixel(x, map.width, map.height),
                }
            })
            .collect();
        Picture {
            map,
            levels,
            segments,
            references,
        }
    }

    /// The sidecar describing this picture.
    pub fn sidecar(&self, model: &Path) -> Sidecar {
        let lum = self.map.rgb.iter().map(|c| luminance(*c));
        let (lo, hi) = lum.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), l| {
            (a.min(l), b.max(l))
        });
        Sidecar {
            format: "brdf-atlas-map".into(),
            version: SIDECAR_VERSION,
            width: self.map.width,
            height: self.map.height,
            view: self.map.view,
            pixel_to_latent: "x = x0 + (px + 0.5) (x1 - x0) / width, y = y1 - (py + 0.5) (y1 - y0) / height; row 0 at the top".into(),
            method: self.map.method,
            contour_levels: self.levels.clone(),
            luminance_range: [lo, hi],
            references: self.references.clone(),
            model: model.display().to_string(),
        }
    }

    /// The picture as 8-bit sRGB, row-major RGB triples.
    pub fn rgb8(&self, labels: bool) -> Vec<u8> {
        let (w, h) = (self.map.width, self.map.height);
        let mut img: Vec<[f32; 3]> = self
            .map
            .rgb
            .iter()
            .map(|c| c.map(|v| srgb(v.clamp(0.0, 1.0))))
            .collect();
        for &(a, b, _) in &self.segments {
            draw_line(&mut img, w, h, a, b, [0.0; 3], 0.55);
        }
        for r in &self.references {
            let (cx, cy) = (r.pixel[0] as f32, r.pixel[1] as f32);
            disc(&mut img, w, h, cx, cy, 3.6, [0.0; 3]);
            disc(&mut img, w, h, cx, cy, 2.2, [1.0; 3]);
            if labels {
                text(&mut img, w, h, cx as i64 + 5, cy as i64 - 4, &r.name);
            }
        }
        img.iter()
            .flat_map(|c| c.map(|v| (v * 255.0 + 0.5).clamp(0.0, 255.0) as u8))
            .collect()
    }
}

/// sRGB encoding of a linear value in `[0, 1]`.
fn srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

fn blend(img: &mut [[f32; 3]], w: usize, h: usize, x: i64, y: i64, colour: [f32; 3], alpha: f32) {
    if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 || alpha <= 0.0 {
        return;
    }
    let p = &mut img[y as usize * w + x as usize];
    for c in 0..3 {
        p[c] += alpha.min(1.0) * (colour[c] - p[c]);
    }
}

/// An anti-aliased line: samples every half pixel, splatted bilinearly.
fn draw_line(
    img: &mut [[f32; 3]],
    w: usize,
    h: usize,
    a: [f32; 2],
    b: [f32; 2],
    colour: [f32; 3],
    alpha: f32,
) {
    let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let steps = (len * 2.0).ceil().max(1.0) as usize;
    for s in 0..=steps {
        let t = s as f32 / steps as f32;
        let (x, y) = (
            a[0] + t * (b[0] - a[0]) - 0.5,
            a[1] + t * (b[1] - a[1]) - 0.5,
        );
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let k = alpha / (steps as f32 / len.max(0.5)).max(1.0) * 1.6;
        for (dx, dy, wgt) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            blend(img, w, h, x0 as i64 + dx, y0 as i64 + dy, colour, k * wgt);
        }
    }
}

/// A filled disc with a soft edge.
fn disc(img: &mut [[f32; 3]], w: usize, h: usize, cx: f32, cy: f32, r: f32, colour: [f32; 3]) {
    let (x0, x1) = ((cx - r - 1.0).floor() as i64, (cx + r + 1.0).ceil() as i64);
    let (y0, y1) = ((cy - r - 1.0).floor() as i64, (cy + r + 1.0).ceil() as i64);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let d = ((x as f32 + 0.5 - cx).powi(2) + (y as f32 + 0.5 - cy).powi(2)).sqrt();
            blend(img, w, h, x, y, colour, (r + 0.5 - d).clamp(0.0, 1.0));
        }
    }
}

/// 8x8 bitmap text, white with a dark outline, clipped to the image.
fn text(img: &mut [[f32; 3]], w: usize, h: usize, x: i64, y: i64, s: &str) {
    let x = x.min(w as i64 - 8 * s.chars().count() as i64).max(0);
    let glyphs: Vec<[u8; 8]> = s
        .chars()
        .map(|c| font8x8::BASIC_FONTS.get(c).unwrap_or([0; 8]))
        .collect();
    for pass in 0..2 {
        for (k, g) in glyphs.iter().enumerate() {
            for (row, bits) in g.iter().enumerate() {
                for col in 0..8 {
                    if bits >> col & 1 == 1 {
                        let (px, py) = (x + 8 * k as i64 + col, y + row as i64);
                        if pass == 0 {
                            for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
                                blend(img, w, h, px + dx, py + dy, [0.0; 3], 0.8);
                            }
                        } else {
                            blend(img, w, h, px, py, [1.0; 3], 1.0);
                        }
                    }
                }
            }
        }
    }
}

/// Write the picture as an 8-bit sRGB PNG (atomically).
pub fn write_png(path: &Path, picture: &Picture, labels: bool) -> Result<()> {
    commit(path, stage_png(path, picture, labels)?)
}

/// Write the linear albedo as a float RGB OpenEXR (atomically).
pub fn write_exr(path: &Path, map: &AlbedoMap) -> Result<()> {
    commit(path, stage_exr(path, map)?)
}

/// Write the sidecar as pretty JSON (atomically).
pub fn write_sidecar(path: &Path, sidecar: &Sidecar) -> Result<()> {
    commit(path, stage_sidecar(path, sidecar)?)
}

fn commit(path: &Path, staged: PendingFile) -> Result<()> {
    staged.commit(false).map_err(|e| CoreError::write(path, e))
}

fn stage_bytes(path: &Path, bytes: &[u8]) -> Result<PendingFile> {
    stage(path, |f| std::io::Write::write_all(f, bytes)).map_err(|e| CoreError::write(path, e))
}

/// The PNG of [`write_png`], complete on disk under a temporary name beside
/// `path` until committed (see [`brdf_atomic::commit_all`]).
pub fn stage_png(path: &Path, picture: &Picture, labels: bool) -> Result<PendingFile> {
    let (w, h) = (picture.map.width as u32, picture.map.height as u32);
    let data = picture.rgb8(labels);
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = enc
            .write_header()
            .map_err(|e| CoreError::write(path, std::io::Error::other(e.to_string())))?;
        writer
            .write_image_data(&data)
            .map_err(|e| CoreError::write(path, std::io::Error::other(e.to_string())))?;
    }
    stage_bytes(path, &bytes)
}

/// The EXR of [`write_exr`], staged like [`stage_png`].
pub fn stage_exr(path: &Path, map: &AlbedoMap) -> Result<PendingFile> {
    use exr::prelude::*;
    let w = map.width;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let c = map.rgb[y * w + x];
        (c[0], c[1], c[2])
    });
    let mut cursor = Cursor::new(Vec::new());
    Image::from_channels((map.width, map.height), channels)
        .write()
        .to_buffered(&mut cursor)
        .map_err(|e| CoreError::write(path, std::io::Error::other(e.to_string())))?;
    stage_bytes(path, cursor.get_ref())
}

/// The sidecar of [`write_sidecar`], staged like [`stage_png`].
pub fn stage_sidecar(path: &Path, sidecar: &Sidecar) -> Result<PendingFile> {
    let json = serde_json::to_vec_pretty(sidecar)
        .map_err(|e| CoreError::write(path, std::io::Error::other(e.to_string())))?;
    stage_bytes(path, &json)
}

/// The sidecar format version this build writes and reads.
pub const SIDECAR_VERSION: u32 = 1;
/// Largest width or height a sidecar may give.
pub const MAX_SIDE: usize = crate::limits::MAX_SIDECAR_SIDE;

/// Read and check a sidecar.
pub fn read_sidecar(path: &Path) -> Result<Sidecar> {
    let bytes = std::fs::read(path).map_err(|e| CoreError::io(path, e))?;
    Sidecar::from_json(path, &bytes)
}

impl Sidecar {
    /// Parse and check the JSON of a sidecar: format, version, image size,
    /// view, finite numbers, and every reference's pixel where the view puts
    /// its latent point. `path` names the file in errors.
    pub fn from_json(path: &Path, bytes: &[u8]) -> Result<Sidecar> {
        let bad = |why: String| CoreError::bad_file(path, why);
        if brdf_merl::table::is_lfs_pointer(bytes) {
            return Err(bad("is a Git LFS pointer file, not a brdf-atlas map sidecar (run `git lfs pull` to fetch the real file)".into()));
        }
        let value: serde_json::Value = serde_json::from_slice(bytes)
            .map_err(|e| bad(format!("not a brdf-atlas map sidecar (invalid JSON: {e})")))?;
        if value.get("format").and_then(|v| v.as_str()) != Some("brdf-atlas-map") {
            return Err(bad(
                "not a brdf-atlas map sidecar (expected \"format\": \"brdf-atlas-map\")".into(),
            ));
        }
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if v == SIDECAR_VERSION as u64 => {}
            Some(v) if v > SIDECAR_VERSION as u64 => {
                return Err(bad(format!(
                    "sidecar version {v} was written by a newer brdf-atlas (this build reads version {SIDECAR_VERSION}); upgrade brdf-atlas"
                )));
            }
            _ => {
                return Err(bad(format!(
                    "sidecar version {}, expected {SIDECAR_VERSION}",
                    value.get("version").unwrap_or(&serde_json::Value::Null)
                )));
            }
        }
        let s: Sidecar = serde_json::from_value(value)
            .map_err(|e| bad(format!("malformed map sidecar: {e}")))?;
        s.check().map_err(bad)?;
        Ok(s)
    }

    fn check(&self) -> std::result::Result<(), String> {
        let (w, h) = (self.width, self.height);
        if !(1..=MAX_SIDE).contains(&w) || !(1..=MAX_SIDE).contains(&h) {
            return Err(format!(
                "image {w}x{h}, expected sides of 1 to {MAX_SIDE} pixels"
            ));
        }
        self.view.check().map_err(|e| e.to_string())?;
        if let Some(v) = self.contour_levels.iter().find(|v| !v.is_finite()) {
            return Err(format!("contour level {v}, expected finite numbers"));
        }
        let [lo, hi] = self.luminance_range;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(format!(
                "luminance range [{lo}, {hi}], expected finite numbers, low <= high"
            ));
        }
        if self.references.len() > MAX_MATERIALS {
            return Err(format!(
                "{} references, expected at most {MAX_MATERIALS}",
                self.references.len()
            ));
        }
        for (i, r) in self.references.iter().enumerate() {
            if !r.latent.iter().all(|v| v.abs() <= LATENT_LIMIT) {
                return Err(format!(
                    "reference {i} ({}) at {:?}, expected finite coordinates within +-{LATENT_LIMIT}",
                    r.name, r.latent
                ));
            }
            let want = self.view.latent_to_pixel(r.latent, w, h);
            let tol = 1e-6 * w.max(h) as f64;
            if !(0..2).all(|c| (r.pixel[c] - want[c]).abs() <= tol) {
                return Err(format!(
                    "reference {i} ({}) at pixel {:?}, but the view puts its latent point {:?} at {want:?}",
                    r.name, r.pixel, r.latent
                ));
            }
        }
        Ok(())
    }
}
