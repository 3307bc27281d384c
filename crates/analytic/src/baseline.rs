//! The two baselines every fit is measured against, the same way: a
//! Lambertian of the material's albedo (not fitted: `f = albedo / pi`), and
//! one GGX lobe over a Lambertian base, fitted like the principled model.

use std::f64::consts::PI;

use crate::analytic::{Analytic, param};
use crate::geometry::Geometry;
use crate::principled::{MIN_ROUGHNESS, ggx_d, smith_v};

/// `f = albedo / pi`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lambertian {
    /// Linear RGB albedo, `[0, 1]`.
    pub albedo: [f64; 3],
}

impl Analytic for Lambertian {
    const NAME: &'static str = "Lambertian of the albedo";

    fn bounds() -> Vec<(f64, f64)> {
        vec![(0.0, 1.0); 3]
    }

    fn to_params(&self) -> Vec<f64> {
        self.albedo.to_vec()
    }

    fn from_params(p: &[f64]) -> Self {
        let b = Self::bounds();
        Lambertian {
            albedo: std::array::from_fn(|c| param(p, &b, c)),
        }
    }

    /// The albedo itself: the baseline is not fitted.
    fn starts(albedo: [f64; 3]) -> Vec<Self> {
        vec![Lambertian { albedo }]
    }

    fn eval_geometry(&self, _g: &Geometry) -> [f64; 3] {
        self.albedo.map(|a| a / PI)
    }
}

/// `f = diffuse / pi + specular D V`: one GGX lobe (the same `D` and Smith
/// `V` as [`crate::Principled`], no Fresnel) over a Lambertian base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GgxLambert {
    /// Lambertian albedo, linear RGB `[0, 1]`.
    pub diffuse: [f64; 3],
    /// Lobe weight per channel, `[0, 1]`.
    pub specular: [f64; 3],
    /// Perceptual roughness, `[MIN_ROUGHNESS, 1]` (`alpha = roughness^2`).
    pub roughness: f64,
}

impl Analytic for GgxLambert {
    const NAME: &'static str = "one GGX lobe + Lambertian";

    fn bounds() -> Vec<(f64, f64)> {
        let mut b = vec![(0.0, 1.0); 7];
        b[6] = (MIN_ROUGHNESS, 1.0);
        b
    }

    fn to_params(&self) -> Vec<f64> {
        let mut p = self.diffuse.to_vec();
        p.extend(self.specular);
        p.push(self.roughness);
        p
    }

    fn from_params(p: &[f64]) -> Self {
        let b = Self::bounds();
        let at = |k| param(p, &b, k);
        GgxLambert {
            diffuse: [at(0), at(1), at(2)],
            specular: [at(3), at(4), at(5)],
            roughness: at(6),
        }
    }

    /// The albedo as the base, a weak lobe, rough to glossy.
    fn starts(albedo: [f64; 3]) -> Vec<Self> {
        [0.5, 0.2, 0.08]
            .map(|roughness| GgxLambert {
                diffuse: albedo,
                specular: [0.1; 3],
                roughness,
            })
            .to_vec()
    }

    fn eval_geometry(&self, g: &Geometry) -> [f64; 3] {
        let a = self.roughness * self.roughness;
        let a2 = a * a;
        let dv = ggx_d(a2, g.nh) * smith_v(a2, g.nl, g.nv);
        std::array::from_fn(|c| self.diffuse[c] / PI + self.specular[c] * dv)
    }
}
