//! The JSON sidecar of a map: the pixel <-> latent mapping, the materials
//! with their positions, the labels drawn (for hit-testing) and the
//! confidence rule, so that other tools (the BRDF Explorer plugin) can draw
//! and hit-test without recomputing; and its reader, which checks all of it.

use std::path::Path;

use brdf_atlas_core::limits::{LATENT_LIMIT, MAX_MATERIALS, MAX_SIDECAR_SIDE};
use brdf_atlas_core::{AlbedoMethod, CoreError, Result, View};
use serde::{Deserialize, Serialize};

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
    /// The blend rule of the material each pixel shows (`gp` or `floor`;
    /// absent from sidecars written before there was a choice: `gp`).
    #[serde(default)]
    pub blend: Option<String>,
    /// Luminance of each contour line.
    pub contour_levels: Vec<f32>,
    /// Smallest and largest luminance on the map.
    pub luminance_range: [f32; 2],
    /// The input materials.
    pub references: Vec<Reference>,
    /// The model file the map shows.
    pub model: String,
    /// Every label drawn on the PNG, with its box (version 2; empty in
    /// version 1 sidecars and when labels were not drawn).
    #[serde(default)]
    pub labels: Vec<LabelBox>,
    /// Materials inside the view left without a label for lack of room (version 2).
    #[serde(default)]
    pub unlabelled: usize,
    /// How the picture shows where the model knows little (version 2).
    #[serde(default)]
    pub confidence: Option<ConfidenceRule>,
}

/// A label on the PNG: the material's name and the box of its text,
/// `[x0, y0, x1, y1]` in pixels (y down, `x0 < x1`, `y0 < y1`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LabelBox {
    /// The material's name (one of the references).
    pub name: String,
    /// The box.
    #[serde(rename = "box")]
    pub rect: [f32; 4],
}

/// The confidence rule of a map: what the picture does where the GP's
/// predictive variance is high, and from which variance on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConfidenceRule {
    /// The rule, in words.
    pub rule: String,
    /// Pixels with a predictive variance above this are faded.
    pub low_above: f64,
}

/// The sidecar format version this build writes; it reads this one and
/// version 1 (without labels and confidence).
pub const SIDECAR_VERSION: u32 = 2;
/// Largest width or height a sidecar may give.
pub const MAX_SIDE: usize = MAX_SIDECAR_SIDE;

/// Read and check a sidecar.
pub fn read_sidecar(path: &Path) -> Result<Sidecar> {
    let bytes = brdf_mapguard::read_regular(path).map_err(|e| CoreError::io(path, e))?;
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
            Some(v) if (1..=SIDECAR_VERSION as u64).contains(&v) => {}
            Some(v) if v > SIDECAR_VERSION as u64 => {
                return Err(bad(format!(
                    "sidecar version {v} was written by a newer brdf-atlas (this build reads version {SIDECAR_VERSION}); upgrade brdf-atlas"
                )));
            }
            _ => {
                return Err(bad(format!(
                    "sidecar version {}, expected 1 to {SIDECAR_VERSION}",
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
        for (i, l) in self.labels.iter().enumerate() {
            let [x0, y0, x1, y1] = l.rect;
            let inside = x0.is_finite()
                && y0.is_finite()
                && 0.0 <= x0
                && x0 < x1
                && x1 <= w as f32
                && 0.0 <= y0
                && y0 < y1
                && y1 <= h as f32;
            if !inside {
                return Err(format!(
                    "label {i} ({}) has the box {:?}, expected x0 < x1 and y0 < y1 inside the {w}x{h} image",
                    l.name, l.rect
                ));
            }
            if !self.references.iter().any(|r| r.name == l.name) {
                return Err(format!(
                    "label {i} names {:?}, which is not one of the references",
                    l.name
                ));
            }
        }
        if self.labels.len() + self.unlabelled > self.references.len() {
            return Err(format!(
                "{} labels and {} unlabelled materials, but only {} references",
                self.labels.len(),
                self.unlabelled,
                self.references.len()
            ));
        }
        if let Some(c) = self
            .confidence
            .as_ref()
            .filter(|c| !(0.0..=1.0).contains(&c.low_above))
        {
            return Err(format!(
                "confidence threshold {}, expected a variance from 0 to 1",
                c.low_above
            ));
        }
        Ok(())
    }
}
