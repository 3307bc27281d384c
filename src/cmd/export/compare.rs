//! What an export loses: the fits of one table ([`brdf_atlas_analytic`])
//! and the rendered error of each, the measured material and the fit on
//! lit spheres under the same lights (the swatch renderer's), compared
//! pixel by pixel in linear radiance.
//!
//! The rendered error is `sum |L' - L| / sum L` over the sphere's pixels
//! (each weighted by the share of it the sphere covers) and the three
//! channels: the share of the measured picture's light the fit gets wrong.
//!
//! The fit's metric includes a coarser sphere under the same lights
//! ([`brdf_atlas_analytic::sphere`]),
//! so the rendered error is partly in-sample; the same error under two
//! other lights ([`HELD_OUT_LIGHTS`]), which the fit never sees, is
//! reported beside it.

use brdf_atlas_analytic::{Analytic, Fits, fit_as_exported};
use brdf_atlas_pictures::sphere::{Light, Reflectance, Sphere, render};
use brdf_merl::{MerlTable, Vec3};
use rayon::prelude::*;

use crate::error::Error;

/// Lights the fit never sees: from the upper right and from below left.
pub const HELD_OUT_LIGHTS: [Light; 2] = [
    Light {
        direction: [0.6, 0.6, 0.5],
        intensity: 0.8,
    },
    Light {
        direction: [-0.7, -0.35, 0.6],
        intensity: 0.4,
    },
];

/// An analytic model as a material the swatch renderer draws.
pub struct Drawn<'a, M>(pub &'a M);

impl<M: Analytic + Sync> Reflectance for Drawn<'_, M> {
    fn eval_pairs(&self, pairs: &[(Vec3, Vec3)]) -> Vec<Option<[f64; 3]>> {
        pairs
            .par_iter()
            .with_min_len(1024)
            .map(|(wi, wo)| Some(self.0.eval(*wi, *wo)))
            .collect()
    }
}

/// `sum |b - a| / sum a` over covered pixels and channels (coverage
/// weighted); 0 when `a` is black and `b` is too.
pub fn rendered_error(a: &Sphere, b: &Sphere) -> f64 {
    let (mut diff, mut total) = (0.0f64, 0.0f64);
    for ((x, y), &c) in a.radiance.iter().zip(&b.radiance).zip(&a.coverage) {
        for k in 0..3 {
            diff += c as f64 * (x[k] as f64 - y[k] as f64).abs();
            total += c as f64 * x[k] as f64;
        }
    }
    if total > 0.0 {
        diff / total
    } else if diff > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// `|b - a|` per pixel, times `gain`, as a sphere.
pub fn difference(a: &Sphere, b: &Sphere, gain: f32) -> Sphere {
    Sphere {
        size: a.size,
        radiance: a
            .radiance
            .iter()
            .zip(&b.radiance)
            .map(|(x, y)| std::array::from_fn(|k| gain * (x[k] - y[k]).abs()))
            .collect(),
        coverage: a.coverage.clone(),
    }
}

/// Rendered errors of the fit and of the two baselines.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rendered {
    /// The principled fit.
    pub principled: f64,
    /// One GGX lobe over a Lambertian base.
    pub single_lobe: f64,
    /// The Lambertian of the albedo.
    pub lambertian: f64,
    /// The principled fit under [`HELD_OUT_LIGHTS`].
    pub held_out: f64,
}

/// One table's fits, rendered.
pub struct Compared {
    /// The fits and their table errors.
    pub fits: Fits,
    /// Their rendered errors.
    pub rendered: Rendered,
    /// The measured material's sphere.
    pub measured: Sphere,
    /// The principled fit's sphere.
    pub fitted: Sphere,
    /// Wall time of the fits (the principled model and the single lobe).
    pub fit_time: std::time::Duration,
}

/// Fit `table` (named `what` in errors) and render it and the fits on
/// spheres of `size` pixels under `lights`.
pub fn compare(
    table: &MerlTable,
    what: &str,
    size: usize,
    lights: &[Light],
) -> Result<Compared, Error> {
    let t0 = std::time::Instant::now();
    let analytic_lights: Vec<brdf_atlas_analytic::Light> = lights
        .iter()
        .map(|l| brdf_atlas_analytic::Light {
            direction: l.direction,
            intensity: l.intensity,
        })
        .collect();
    let fits =
        fit_as_exported(table, what, &analytic_lights).map_err(|e| Error::Input(e.to_string()))?;
    let fit_time = t0.elapsed();
    let measured = render(table, size, lights);
    let fitted = render(&Drawn(&fits.principled.model), size, lights);
    let lobe = render(&Drawn(&fits.single_lobe.model), size, lights);
    let lambert = render(&Drawn(&fits.lambertian.model), size, lights);
    let rendered = Rendered {
        principled: rendered_error(&measured, &fitted),
        single_lobe: rendered_error(&measured, &lobe),
        lambertian: rendered_error(&measured, &lambert),
        held_out: rendered_error(
            &render(table, size, &HELD_OUT_LIGHTS),
            &render(&Drawn(&fits.principled.model), size, &HELD_OUT_LIGHTS),
        ),
    };
    Ok(Compared {
        fits,
        rendered,
        measured,
        fitted,
        fit_time,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_atlas_analytic::Lambertian;
    use brdf_atlas_pictures::sphere::DEFAULT_LIGHTS;

    #[test]
    fn a_white_lambertian_facing_a_unit_light_renders_one_and_errors_are_relative() {
        let white = Lambertian { albedo: [1.0; 3] };
        let head_on = [Light {
            direction: [0.0, 0.0, 1.0],
            intensity: 1.0,
        }];
        let s = render(&Drawn(&white), 33, &head_on);
        // The centre pixel faces the light: radiance 1 exactly.
        let c = s.radiance[16 * 33 + 16];
        assert!(c.iter().all(|v| (v - 1.0).abs() < 1e-3), "{c:?}");
        let grey = Lambertian { albedo: [0.9; 3] };
        let a = render(&Drawn(&white), 32, &DEFAULT_LIGHTS);
        let b = render(&Drawn(&grey), 32, &DEFAULT_LIGHTS);
        assert!((rendered_error(&a, &b) - 0.1).abs() < 1e-6);
        assert_eq!(rendered_error(&a, &a), 0.0);
    }

    #[test]
    fn the_fits_pixels_add_up_to_the_renderers_radiance() {
        let grey = Lambertian {
            albedo: [0.4, 0.5, 0.6],
        };
        let size = 20;
        let sphere = render(&Drawn(&grey), size, &DEFAULT_LIGHTS);
        let lights = brdf_atlas_analytic::SWATCH_LIGHTS;
        for (a, b) in lights.iter().zip(&DEFAULT_LIGHTS) {
            assert_eq!((a.direction, a.intensity), (b.direction, b.intensity));
        }
        let pixels = brdf_atlas_analytic::sphere_pixels(size, &lights);
        let covered: Vec<[f32; 3]> = sphere
            .radiance
            .iter()
            .zip(&sphere.coverage)
            .filter(|(_, c)| **c > 0.0)
            .map(|(r, _)| *r)
            .collect();
        assert_eq!(covered.len(), pixels.len());
        for (r, p) in covered.iter().zip(&pixels) {
            for (c, &want) in r.iter().enumerate() {
                let l: f64 = p.iter().map(|(wi, wo, w)| w * grey.eval(*wi, *wo)[c]).sum();
                assert!((l - want as f64).abs() < 1e-5, "{l} vs {want}");
            }
        }
    }
}
