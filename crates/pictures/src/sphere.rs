//! Lit spheres of materials: an orthographic camera looking down `-z` at a
//! unit sphere, directional lights, direct lighting only. Each pixel needs
//! the BRDF for one view direction and one direction a light, so a sphere
//! asks its material for exactly those pairs ([`Reflectance::eval_pairs`]):
//! a model's point queries ([`Blend::eval_batch`]) or a MERL table's
//! lookups, never a whole reconstructed table.
//!
//! Camera space: `x` right, `y` up, `z` towards the viewer. A pixel's
//! normal is `n = (u, v, sqrt(1 - u^2 - v^2))`; the shading frame is `n`
//! and any tangent (the materials are isotropic). The radiance of a pixel
//! is `sum over lights of f(wi, wo) pi E (n . l)`, so a light of intensity
//! `E = 1` makes a white Lambertian surface facing it exactly 1.

use brdf_atlas_core::Blend;
use brdf_merl::{MerlTable, Vec3};
use rayon::prelude::*;

/// A material a sphere can be rendered from.
pub trait Reflectance: Sync {
    /// RGB reflectance (1/sr) for each pair of directions `(wi, wo)` in the
    /// shading frame (normal `z`); `None` below the horizon or unmeasured.
    fn eval_pairs(&self, pairs: &[(Vec3, Vec3)]) -> Vec<Option<[f64; 3]>>;
}

impl Reflectance for Blend<'_> {
    fn eval_pairs(&self, pairs: &[(Vec3, Vec3)]) -> Vec<Option<[f64; 3]>> {
        self.eval_batch(pairs)
    }
}

impl Reflectance for MerlTable {
    fn eval_pairs(&self, pairs: &[(Vec3, Vec3)]) -> Vec<Option<[f64; 3]>> {
        pairs
            .par_iter()
            .with_min_len(1024)
            .map(|(wi, wo)| self.eval(*wi, *wo))
            .collect()
    }
}

/// A directional light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Direction towards the light, camera space (normalised on use).
    pub direction: Vec3,
    /// Intensity: 1 makes a white Lambertian surface facing the light 1.
    pub intensity: f64,
}

/// The default lights: a key light from the upper left and a dimmer fill
/// from the right.
pub const DEFAULT_LIGHTS: [Light; 2] = [
    Light {
        direction: [-0.45, 0.55, 0.70],
        intensity: 0.9,
    },
    Light {
        direction: [0.75, -0.1, 0.65],
        intensity: 0.3,
    },
];

fn normalise(v: Vec3) -> Option<Vec3> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (len.is_finite() && len > 0.0).then(|| v.map(|c| c / len))
}

fn dot3(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A rendered sphere: linear radiance and coverage per pixel, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Sphere {
    /// Side in pixels.
    pub size: usize,
    /// Linear RGB radiance, `size * size`.
    pub radiance: Vec<[f32; 3]>,
    /// Share of each pixel the sphere covers (its rim is antialiased).
    pub coverage: Vec<f32>,
}

/// The unit normal a pixel shows (its centre pulled inside the rim) and the
/// share of the pixel the sphere covers; `None` off the sphere.
pub fn pixel_normal(px: usize, py: usize, size: usize) -> Option<(Vec3, f32)> {
    let r = size as f64 / 2.0;
    let (dx, dy) = (px as f64 + 0.5 - r, r - (py as f64 + 0.5));
    let d = (dx * dx + dy * dy).sqrt();
    let coverage = (r - d + 0.5).clamp(0.0, 1.0);
    if coverage <= 0.0 {
        return None;
    }
    // Inside the rim: the pixel centre; on it, the point half a pixel in.
    let pull = if d > r - 0.5 { (r - 0.5) / d } else { 1.0 };
    let (u, v) = (dx * pull / r, dy * pull / r);
    let n = [u, v, (1.0 - u * u - v * v).max(0.0).sqrt()];
    Some((n, coverage as f32))
}

/// Render `material` on a sphere of `size` pixels under `lights`.
pub fn render(material: &dyn Reflectance, size: usize, lights: &[Light]) -> Sphere {
    let lights: Vec<(Vec3, f64)> = lights
        .iter()
        .filter_map(|l| Some((normalise(l.direction)?, l.intensity)))
        .collect();
    let view: Vec3 = [0.0, 0.0, 1.0];
    // The pairs every covered pixel needs, light by light.
    let mut pixels = Vec::new();
    let mut pairs = Vec::new();
    let mut weights = Vec::new();
    for py in 0..size {
        for px in 0..size {
            let Some((n, coverage)) = pixel_normal(px, py, size) else {
                continue;
            };
            let t = normalise(cross([0.0, 1.0, 0.0], n)).unwrap_or([1.0, 0.0, 0.0]);
            let b = cross(n, t);
            let local = |w: Vec3| [dot3(w, t), dot3(w, b), dot3(w, n)];
            pixels.push((py * size + px, coverage));
            for &(l, e) in &lights {
                let cos = dot3(l, n);
                if cos > 0.0 {
                    pairs.push((local(l), local(view)));
                    weights.push((pixels.len() - 1, std::f64::consts::PI * e * cos));
                }
            }
        }
    }
    let values = material.eval_pairs(&pairs);
    let mut sum = vec![[0.0f64; 3]; pixels.len()];
    for (&(k, w), v) in weights.iter().zip(&values) {
        if let Some(f) = v {
            for c in 0..3 {
                sum[k][c] += f[c] * w;
            }
        }
    }
    let mut radiance = vec![[0.0f32; 3]; size * size];
    let mut coverage = vec![0.0f32; size * size];
    for (&(p, cov), s) in pixels.iter().zip(&sum) {
        radiance[p] = s.map(|v| v as f32);
        coverage[p] = cov;
    }
    Sphere {
        size,
        radiance,
        coverage,
    }
}

/// The display value of a linear radiance: unchanged up to 0.8, then a soft
/// shoulder reaching 1 only at infinity (highlights keep their shape).
pub fn tone(v: f32) -> f32 {
    if v <= 0.8 {
        v.max(0.0)
    } else {
        0.8 + 0.2 * (1.0 - (-(v - 0.8) / 0.2).exp())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rim_is_covered_partly_and_normals_are_unit() {
        let size = 16;
        let mut area = 0.0;
        for py in 0..size {
            for px in 0..size {
                if let Some((n, c)) = pixel_normal(px, py, size) {
                    assert!((dot3(n, n) - 1.0).abs() < 1e-12);
                    area += c as f64;
                }
            }
        }
        let want = std::f64::consts::PI * 64.0;
        assert!((area - want).abs() < 0.02 * want, "{area} vs {want}");
        assert!(tone(0.5) == 0.5 && tone(100.0) <= 1.0 && tone(0.9) < 0.9);
    }
}
