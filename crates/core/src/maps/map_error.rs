//! Reference values for accuracy measurements: the albedo of the material
//! at a latent point integrated with a dense rule from its full
//! reconstruction, and a map's error against such references.

use brdf_merl::Quadrature;

use crate::error::Result;
use crate::maps::albedo_map::AlbedoMap;
use crate::model::Model;
use crate::model::blend::BlendRule;

/// Albedo of the reconstruction `blend` forms at `x`, integrated with
/// `rule` over every bin it names (unmeasured bins count as 0, negative
/// values as 0, as the table clamps them). Slow: every value one at a time
/// through [`crate::Blend::value`], an independent path from the map's.
pub fn reference_albedo(
    model: &Model,
    x: &[f64],
    blend: BlendRule,
    rule: &Quadrature,
) -> Result<[f64; 3]> {
    let blend = model.at(x, blend)?;
    let albedo = rule.integrate(|bin| [0, 1, 2].map(|c| blend.value(c, bin).unwrap_or(0.0)));
    model.verify()?;
    Ok(albedo)
}

/// Largest and mean error of `map` at `pixels` (`(px, py)`) against
/// `reference` albedos, each relative to the reference's largest channel.
pub fn map_error(map: &AlbedoMap, pixels: &[(usize, usize)], reference: &[[f64; 3]]) -> (f64, f64) {
    let got: Vec<[f64; 3]> = pixels
        .iter()
        .map(|&(px, py)| map.rgb[py * map.width + px].map(f64::from))
        .collect();
    albedo_error(&got, reference)
}

/// Largest and mean error of albedos `got` against `reference`, each
/// relative to the reference's largest channel (at least 1e-6).
pub fn albedo_error(got: &[[f64; 3]], reference: &[[f64; 3]]) -> (f64, f64) {
    let (mut worst, mut sum) = (0.0f64, 0.0f64);
    for (g, r) in got.iter().zip(reference) {
        let scale = r.iter().fold(1e-6f64, |a, v| a.max(v.abs()));
        for c in 0..3 {
            let e = (g[c] - r[c]).abs() / scale;
            worst = worst.max(e);
            sum += e;
        }
    }
    (worst, sum / (3 * got.len().max(1)) as f64)
}
