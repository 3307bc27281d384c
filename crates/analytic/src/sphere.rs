//! The picture the fit matches besides the table: a lit sphere as the
//! swatch renderer of `brdf-atlas-core` draws it (an orthographic camera on
//! `+z` looking at a unit sphere, directional lights, direct lighting
//! only), as the pairs of directions and weights of each pixel. The
//! command-line tool's tests check that these pixels add up to the
//! renderer's radiance.

use brdf_merl::Vec3;

use crate::samples::Pixel;

/// A directional light in camera space (`x` right, `y` up, `z` towards the viewer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Direction towards the light (normalised on use).
    pub direction: Vec3,
    /// Intensity: 1 makes a white Lambertian surface facing the light 1.
    pub intensity: f64,
}

/// The swatch renderer's default lights: a key light from the upper left
/// and a dimmer fill from the right.
pub const SWATCH_LIGHTS: [Light; 2] = [
    Light {
        direction: [-0.45, 0.55, 0.70],
        intensity: 0.9,
    },
    Light {
        direction: [0.75, -0.1, 0.65],
        intensity: 0.3,
    },
];

/// Side, pixels, of the sphere [`crate::fit_as_exported`] matches.
pub const FIT_PIXELS: usize = 48;

fn unit(v: Vec3) -> Option<Vec3> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (n.is_finite() && n > 0.0).then(|| v.map(|c| c / n))
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The normal a pixel of a sphere of `size` pixels shows (its centre, or
/// half a pixel inside the rim), `None` off the sphere.
fn normal(px: usize, py: usize, size: usize) -> Option<Vec3> {
    let r = size as f64 / 2.0;
    let (dx, dy) = (px as f64 + 0.5 - r, r - (py as f64 + 0.5));
    let d = (dx * dx + dy * dy).sqrt();
    if r - d + 0.5 <= 0.0 {
        return None;
    }
    let pull = if d > r - 0.5 { (r - 0.5) / d } else { 1.0 };
    let (u, v) = (dx * pull / r, dy * pull / r);
    Some([u, v, (1.0 - u * u - v * v).max(0.0).sqrt()])
}

/// The covered pixels of a sphere of `size` pixels under `lights`, row by
/// row from the top: per light facing the pixel's normal, the pair (light,
/// view) in the pixel's shading frame and the weight `pi E cos`.
pub fn sphere_pixels(size: usize, lights: &[Light]) -> Vec<Pixel> {
    let lights: Vec<(Vec3, f64)> = lights
        .iter()
        .filter_map(|l| Some((unit(l.direction)?, l.intensity)))
        .collect();
    let view = [0.0, 0.0, 1.0];
    let mut out = Vec::new();
    for py in 0..size {
        for px in 0..size {
            let Some(n) = normal(px, py, size) else {
                continue;
            };
            let t = unit(cross([0.0, 1.0, 0.0], n)).unwrap_or([1.0, 0.0, 0.0]);
            let b = cross(n, t);
            let local = |w: Vec3| [dot(w, t), dot(w, b), dot(w, n)];
            out.push(
                lights
                    .iter()
                    .filter(|(l, _)| dot(*l, n) > 0.0)
                    .map(|&(l, e)| (local(l), local(view), std::f64::consts::PI * e * dot(l, n)))
                    .collect(),
            );
        }
    }
    out
}
