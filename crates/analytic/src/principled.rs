//! The fitted model: glTF 2.0's metallic-roughness BRDF with the
//! `KHR_materials_specular` extension, evaluated as the glTF specification's
//! Appendix B writes it (its "suggested simplification", with the
//! extension's Fresnel term and `KHR_materials_ior`'s index of refraction):
//!
//! ```text
//! a        = roughness^2
//! D        = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2)                 (GGX)
//! V        = 1 / ((n.l + sqrt(a^2 + (1 - a^2)(n.l)^2))
//!                 (n.v + sqrt(a^2 + (1 - a^2)(n.v)^2)))            (Smith, separable: G / (4 n.l n.v))
//! F0       = lerp(((ior - 1) / (ior + 1))^2 specular specular_color, base_color, metallic)
//! F90      = lerp(specular, 1, metallic)
//! F        = F0 + (F90 - F0) (1 - v.h)^5                           (per channel)
//! c_diff   = lerp(base_color, 0, metallic)
//! f        = (1 - F) c_diff / pi + F D V
//! ```
//!
//! Its parameters are the ones glTF (`baseColorFactor`, `metallicFactor`,
//! `roughnessFactor`, `KHR_materials_specular`'s `specularFactor` and
//! `specularColorFactor`, `KHR_materials_ior`'s `ior`), MaterialX's
//! Standard Surface (`base_color`, `metalness`, `specular_roughness`,
//! `specular`, `specular_color`, `specular_IOR`) and Mitsuba 3's
//! `principled` (`base_color`, `metallic`, `roughness`, `eta`) share; each of those renderers evaluates them in
//! its own way (Standard Surface's dielectric Fresnel and energy-preserving
//! layering, Mitsuba's Disney diffuse), so the error this crate reports is
//! the error of the glTF evaluation.

use crate::analytic::{Analytic, param};
use crate::geometry::Geometry;
use std::f64::consts::PI;

/// Smallest roughness the fit uses: the MERL grid's first `theta_h` bin is
/// 0.0002 rad wide, narrower highlights than this are not measured.
pub const MIN_ROUGHNESS: f64 = 0.02;

/// Largest index of refraction the fit uses (F0 = 0.25 at specular 1).
pub const MAX_IOR: f64 = 3.0;

/// glTF metallic-roughness with `KHR_materials_specular` and `KHR_materials_ior`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Principled {
    /// Linear RGB base colour, `[0, 1]`.
    pub base_color: [f64; 3],
    /// Metalness, `[0, 1]`.
    pub metallic: f64,
    /// Perceptual roughness, `[MIN_ROUGHNESS, 1]` (GGX `alpha = roughness^2`).
    pub roughness: f64,
    /// Specular level (`specularFactor`), `[0, 1]`: scales the dielectric
    /// Fresnel at normal and grazing incidence.
    pub specular: f64,
    /// Specular tint (`specularColorFactor`), linear RGB `[0, 1]`: colours
    /// the dielectric Fresnel at normal incidence.
    pub specular_color: [f64; 3],
    /// Index of refraction of the dielectric, `[1, MAX_IOR]`: its F0 at
    /// specular 1 and a white tint is `((ior - 1) / (ior + 1))^2`.
    pub ior: f64,
}

impl Default for Principled {
    /// glTF's defaults: white, fully metallic, fully rough, specular 1, white tint, ior 1.5.
    fn default() -> Self {
        Principled {
            base_color: [1.0; 3],
            metallic: 1.0,
            roughness: 1.0,
            specular: 1.0,
            specular_color: [1.0; 3],
            ior: 1.5,
        }
    }
}

impl Principled {
    /// The dielectric closest to a single GGX lobe over a Lambertian base:
    /// its base as the base colour, its roughness, and the lobe's weight as
    /// F0 (its largest channel through `ior`, capped at [`MAX_IOR`], the
    /// channels' ratios as the specular colour).
    pub fn from_lobe(lobe: &crate::GgxLambert) -> Principled {
        let top = lobe.specular.iter().copied().fold(0.0, f64::max);
        let r = top.clamp(0.0, 0.25).sqrt();
        Principled {
            base_color: lobe.diffuse,
            metallic: 0.0,
            roughness: lobe.roughness,
            specular: 1.0,
            specular_color: if top > 0.0 {
                lobe.specular.map(|s| s / top)
            } else {
                [1.0; 3]
            },
            ior: ((1.0 + r) / (1.0 - r)).clamp(1.0, MAX_IOR),
        }
    }
}

/// GGX normal distribution for `alpha^2 = a2`.
pub(crate) fn ggx_d(a2: f64, nh: f64) -> f64 {
    let t = nh * nh * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Separable Smith visibility `G / (4 n.l n.v)` for `alpha^2 = a2`.
pub(crate) fn smith_v(a2: f64, nl: f64, nv: f64) -> f64 {
    let gl = nl + (a2 + (1.0 - a2) * nl * nl).sqrt();
    let gv = nv + (a2 + (1.0 - a2) * nv * nv).sqrt();
    1.0 / (gl * gv)
}

impl Analytic for Principled {
    const NAME: &'static str =
        "glTF metallic-roughness + KHR_materials_specular + KHR_materials_ior";

    fn bounds() -> Vec<(f64, f64)> {
        let mut b = vec![(0.0, 1.0); 10];
        b[4] = (MIN_ROUGHNESS, 1.0);
        b[9] = (1.0, MAX_IOR);
        b
    }

    fn to_params(&self) -> Vec<f64> {
        let [r, g, b] = self.base_color;
        let [sr, sg, sb] = self.specular_color;
        vec![
            r,
            g,
            b,
            self.metallic,
            self.roughness,
            self.specular,
            sr,
            sg,
            sb,
            self.ior,
        ]
    }

    fn from_params(p: &[f64]) -> Self {
        let b = Self::bounds();
        let at = |k| param(p, &b, k);
        Principled {
            base_color: [at(0), at(1), at(2)],
            metallic: at(3),
            roughness: at(4),
            specular: at(5),
            specular_color: [at(6), at(7), at(8)],
            ior: at(9),
        }
    }

    /// Dielectrics and metals, rough to glossy, coloured by the albedo.
    fn starts(albedo: [f64; 3]) -> Vec<Self> {
        let start = |metallic, roughness| Principled {
            base_color: albedo,
            metallic,
            roughness,
            specular: 1.0,
            specular_color: [1.0; 3],
            ior: 1.5,
        };
        vec![
            start(0.0, 0.5),
            start(0.0, 0.2),
            start(0.0, 0.08),
            start(1.0, 0.3),
            start(1.0, 0.1),
        ]
    }

    fn eval_geometry(&self, g: &Geometry) -> [f64; 3] {
        let a = self.roughness * self.roughness;
        let a2 = a * a;
        let dv = ggx_d(a2, g.nh) * smith_v(a2, g.nl, g.nv);
        let m = self.metallic;
        let s = self.specular;
        let f90 = s + (1.0 - s) * m;
        let w = (1.0 - g.vh).powi(5);
        let r0 = ((self.ior - 1.0) / (self.ior + 1.0)).powi(2);
        std::array::from_fn(|c| {
            let base = self.base_color[c];
            let f0 = (1.0 - m) * r0 * s * self.specular_color[c] + m * base;
            let f = f0 + (f90 - f0) * w;
            (1.0 - f) * (1.0 - m) * base / PI + f * dv
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_round_trip_and_are_clamped() {
        let p = Principled {
            base_color: [0.2, 0.5, 0.8],
            metallic: 0.3,
            roughness: 0.4,
            specular: 0.6,
            specular_color: [1.0, 0.9, 0.8],
            ior: 1.7,
        };
        assert_eq!(Principled::from_params(&p.to_params()), p);
        let q = Principled::from_params(&[2.0, -1.0, f64::NAN, 0.5, 0.0]);
        assert_eq!(q.base_color, [1.0, 0.0, 0.0]);
        assert_eq!(q.roughness, MIN_ROUGHNESS);
        assert_eq!(q.specular, 0.0);
    }

    #[test]
    fn a_rough_dielectric_at_normal_incidence_is_its_formula() {
        // n.l = n.v = n.h = v.h = 1: F = 0.04 s c, D = 1 / (pi a^2), V = 1 / 4.
        let p = Principled {
            base_color: [0.5; 3],
            metallic: 0.0,
            roughness: 1.0,
            specular: 1.0,
            specular_color: [1.0; 3],
            ior: 1.5,
        };
        let g = Geometry {
            nl: 1.0,
            nv: 1.0,
            nh: 1.0,
            vh: 1.0,
        };
        let want = 0.96 * 0.5 / PI + 0.04 / PI / 4.0;
        for v in p.eval_geometry(&g) {
            assert!((v - want).abs() < 1e-15, "{v} vs {want}");
        }
    }
}
