//! Map outputs: a tone-mapped sRGB PNG with contour lines, the materials'
//! dots and labels, axis ticks and a colour key, faded where the model knows
//! little; a linear float EXR with the predictive variance beside the
//! albedo; and a JSON sidecar ([`Sidecar`]) describing the pixel <-> latent
//! mapping, the reference points and the labels, so that other tools (the
//! BRDF Explorer plugin) can draw and hit-test without recomputing. Every
//! file is written atomically.

use std::io::Cursor;
use std::path::Path;

use brdf_atlas_core::{
    AlbedoMap, CoreError, LOW_CONFIDENCE_VARIANCE, Model, Result, Segment, contour_levels,
    contours, luminance,
};
use brdf_atomic::{PendingFile, stage};

use crate::canvas::{Canvas, srgb};
pub use crate::overlay::{Label, MIN_DECORATED_SIDE, Overlay, Style};
pub use crate::sidecar::{
    ConfidenceRule, LabelBox, MAX_SIDE, Reference, SIDECAR_VERSION, Sidecar, read_sidecar,
};

/// The grey (linear) low-confidence pixels are faded towards.
pub const FADE_GREY: f32 = 0.2;
/// How far a pixel of variance 1 is faded towards [`FADE_GREY`].
pub const FADE_MAX: f32 = 0.75;
/// The fade rule in words, as the sidecar states it.
pub const FADE_RULE: &str = "where the GP's predictive variance v = 1 - k(x)^T K^-1 k(x) exceeds low_above, the PNG's linear albedo c becomes c + t (0.2 - c), t = 0.75 (v - low_above) / (1 - low_above): faded towards grey, fully so where the data say nothing; elsewhere it is unchanged. The EXR keeps the unfaded albedo and v in channel V.";

/// How far a pixel of predictive variance `v` is faded: 0 up to
/// [`LOW_CONFIDENCE_VARIANCE`], rising linearly to [`FADE_MAX`] at 1.
pub fn fade(v: f32) -> f32 {
    let low = LOW_CONFIDENCE_VARIANCE as f32;
    if v > low {
        FADE_MAX * ((v - low) / (1.0 - low)).min(1.0)
    } else {
        0.0
    }
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
    /// Dots, labels, ticks and key, laid out.
    pub overlay: Overlay,
}

impl Picture {
    /// Contours at `contours` evenly spaced levels and the model's materials
    /// as references, labelled, with key and ticks ([`Style::default`]).
    pub fn new(model: &Model, map: AlbedoMap, contours_count: usize) -> Picture {
        Picture::styled(model, map, contours_count, Style::default())
    }

    /// [`Picture::new`] with what to draw besides the map.
    pub fn styled(model: &Model, map: AlbedoMap, contours_count: usize, style: Style) -> Picture {
        let levels = contour_levels(&map, contours_count);
        let segments = contours(&map, &levels);
        let latent = model.latent();
        let references: Vec<Reference> = model
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
        let overlay = Overlay::new(
            &map.view,
            map.width,
            map.height,
            &references,
            &levels,
            luminance_range(&map),
            style,
        );
        Picture {
            map,
            levels,
            segments,
            references,
            overlay,
        }
    }

    /// The sidecar describing this picture.
    pub fn sidecar(&self, model: &Path) -> Sidecar {
        Sidecar {
            format: "brdf-atlas-map".into(),
            version: SIDECAR_VERSION,
            width: self.map.width,
            height: self.map.height,
            view: self.map.view,
            pixel_to_latent: "x = x0 + (px + 0.5) (x1 - x0) / width, y = y1 - (py + 0.5) (y1 - y0) / height; row 0 at the top".into(),
            method: self.map.method,
            blend: Some(self.map.blend.name().to_string()),
            contour_levels: self.levels.clone(),
            luminance_range: luminance_range(&self.map),
            references: self.references.clone(),
            model: model.display().to_string(),
            labels: self.overlay.label_boxes(&self.references),
            unlabelled: self.overlay.unlabelled,
            confidence: Some(ConfidenceRule {
                rule: FADE_RULE.into(),
                low_above: LOW_CONFIDENCE_VARIANCE,
            }),
        }
    }

    /// The map's pixels as the PNG shows them before anything is drawn
    /// over them: linear albedo clamped to `[0, 1]`, faded by [`fade`],
    /// sRGB-encoded.
    pub fn base(&self) -> Vec<[f32; 3]> {
        self.map
            .rgb
            .iter()
            .zip(&self.map.variance)
            .map(|(c, &v)| {
                let t = fade(v);
                c.map(|x| {
                    let x = x.clamp(0.0, 1.0);
                    srgb(x + t * (FADE_GREY - x))
                })
            })
            .collect()
    }

    /// The picture as 8-bit sRGB, row-major RGB triples.
    pub fn rgb8(&self) -> Vec<u8> {
        let mut canvas = Canvas {
            width: self.map.width,
            height: self.map.height,
            px: self.base(),
        };
        for &(a, b, _) in &self.segments {
            canvas.line(a, b, [0.0; 3], 0.55);
        }
        self.overlay.draw(&mut canvas, &self.references);
        canvas.to_8bit()
    }
}

/// Smallest and largest luminance of a map.
fn luminance_range(map: &AlbedoMap) -> [f32; 2] {
    let lum = map.rgb.iter().map(|c| luminance(*c));
    let (lo, hi) = lum.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), l| {
        (a.min(l), b.max(l))
    });
    [lo, hi]
}

/// Write the picture as an 8-bit sRGB PNG (atomically).
pub fn write_png(path: &Path, picture: &Picture) -> Result<()> {
    commit(path, stage_png(path, picture)?)
}

/// Write the linear albedo as a float OpenEXR (atomically): channels R, G,
/// B, and V, the GP's predictive variance.
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
pub fn stage_png(path: &Path, picture: &Picture) -> Result<PendingFile> {
    let (w, h) = (picture.map.width as u32, picture.map.height as u32);
    let data = picture.rgb8();
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
    // R, G, B: the linear albedo; V: the GP's predictive variance.
    let channels = SpecificChannels::build()
        .with_channel("R")
        .with_channel("G")
        .with_channel("B")
        .with_channel("V")
        .with_pixel_fn(|Vec2(x, y): Vec2<usize>| {
            let c = map.rgb[y * w + x];
            (c[0], c[1], c[2], map.variance[y * w + x])
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
