//! Directional albedo: the reflectance a BRDF returns for light from one
//! direction, `a(theta_i) = integral over the outgoing hemisphere of
//! f(wi, wo) cos(theta_o) dwo`. A physically plausible BRDF has
//! `a(theta_i) <= 1` at every incidence (it reflects no more than it
//! receives); a Lambertian `f = rho/pi` has `a = rho` everywhere.
//!
//! The integral is taken over the half vector `wh`, as the MERL grid is
//! (so narrow highlights, which the grid resolves near `theta_h = 0`, are
//! resolved by the rule too): `wo = 2 (wi.wh) wh - wi`, `dwo = 4 (wi.wh) dwh`,
//! `theta_h = u^2 pi/2` as in the table (`dtheta_h = pi u du`), midpoints in
//! `u` and in `phi_h`, and the mirror symmetry `phi_h -> -phi_h` of an
//! isotropic BRDF halves the azimuths. A [`DirectionalRule`] is that sum
//! discretised once for a table's dims, as `(bin, weight)` pairs per
//! incidence angle: linear in `f`, sequential, and it asks for exactly the
//! bins the integral needs.

use std::f64::consts::{FRAC_PI_2, PI};

use crate::angles::{Dims, Vec3};
use crate::table::MerlTable;

/// Incidence angles (degrees from the normal) the rule integrates at:
/// normal to grazing, where Fresnel-like materials reflect the most.
pub const INCIDENCE_DEGREES: [f64; 10] =
    [0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 85.0, 88.0];

/// Directional albedos of a MERL grid at [`INCIDENCE_DEGREES`].
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionalRule {
    dims: Dims,
    /// `starts[k] .. starts[k + 1]` are the entries of incidence `k`.
    starts: Vec<usize>,
    bins: Vec<u32>,
    weights: Vec<f64>,
}

impl DirectionalRule {
    /// The rule for tables of `dims`: `2 theta_h` samples along `u` and
    /// `theta_d` along `phi_h` in `[0, pi]` at each incidence, with the
    /// weights of samples that land in the same bin merged.
    pub fn new(dims: Dims) -> DirectionalRule {
        let (nu, nphi) = (2 * dims.theta_h, dims.theta_d.max(8));
        let (du, dphi) = (1.0 / nu as f64, PI / nphi as f64);
        let mut starts = vec![0];
        let (mut bins, mut weights) = (Vec::new(), Vec::new());
        let mut dense = vec![0.0f64; dims.bins()];
        let mut touched: Vec<u32> = Vec::new();
        for deg in INCIDENCE_DEGREES {
            let (si, ci) = deg.to_radians().sin_cos();
            let wi: Vec3 = [si, 0.0, ci];
            for k in 0..nu {
                let u = (k as f64 + 0.5) * du;
                let (sh, ch) = (u * u * FRAC_PI_2).sin_cos();
                for j in 0..nphi {
                    let (sp, cp) = ((j as f64 + 0.5) * dphi).sin_cos();
                    let wh = [sh * cp, sh * sp, ch];
                    let d = wi[0] * wh[0] + wi[2] * wh[2];
                    let wo = [
                        2.0 * d * wh[0] - wi[0],
                        2.0 * d * wh[1],
                        2.0 * d * wh[2] - wi[2],
                    ];
                    if d <= 0.0 || wo[2] <= 0.0 {
                        continue;
                    }
                    let Some(bin) = dims.bin_of_directions(wi, wo) else {
                        continue;
                    };
                    // cos(theta_o) * 4 (wi.wh) * sin(theta_h) dtheta_h dphi_h, both halves of phi_h.
                    let w = wo[2] * 4.0 * d * sh * (PI * u * du) * dphi * 2.0;
                    if dense[bin] == 0.0 {
                        touched.push(bin as u32);
                    }
                    dense[bin] += w;
                }
            }
            touched.sort_unstable();
            for &b in &touched {
                bins.push(b);
                weights.push(std::mem::take(&mut dense[b as usize]));
            }
            touched.clear();
            starts.push(bins.len());
        }
        DirectionalRule {
            dims,
            starts,
            bins,
            weights,
        }
    }

    /// The dims the rule was built for.
    pub fn dims(&self) -> Dims {
        self.dims
    }

    /// Every bin the rule reads (sorted within each incidence angle).
    pub fn bins(&self) -> &[u32] {
        &self.bins
    }

    /// The weight of each entry of [`DirectionalRule::bins`].
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The entries of incidence `k` (of [`INCIDENCE_DEGREES`]) in
    /// [`DirectionalRule::bins`] and [`DirectionalRule::weights`] are
    /// `start_of(k) .. start_of(k + 1)`.
    pub fn start_of(&self, k: usize) -> usize {
        self.starts[k.min(self.starts.len() - 1)]
    }

    /// The incidence (index into [`INCIDENCE_DEGREES`]) of each entry of
    /// [`DirectionalRule::bins`], in order.
    pub fn incidences(&self) -> impl Iterator<Item = usize> + '_ {
        self.starts
            .windows(2)
            .enumerate()
            .flat_map(|(k, r)| std::iter::repeat_n(k, r[1] - r[0]))
    }

    /// Directional albedo at each of [`INCIDENCE_DEGREES`] of any function of
    /// the bin (reflectance RGB), summed in a fixed order.
    pub fn integrate(&self, mut f: impl FnMut(usize) -> [f64; 3]) -> Vec<[f64; 3]> {
        self.starts
            .windows(2)
            .map(|r| {
                let mut acc = [0.0f64; 3];
                for (&b, &w) in self.bins[r[0]..r[1]].iter().zip(&self.weights[r[0]..r[1]]) {
                    let v = f(b as usize);
                    for c in 0..3 {
                        acc[c] += w * v[c];
                    }
                }
                acc
            })
            .collect()
    }

    /// The largest directional albedo of a table over channels and incidence
    /// angles, with the incidence (degrees) where it occurs; unmeasured bins
    /// count as 0. Panics if the table's dims differ from the rule's.
    pub fn max_albedo(&self, table: &MerlTable) -> (f64, f64) {
        assert_eq!(
            table.dims(),
            self.dims,
            "directional rule built for other dims"
        );
        largest(&self.integrate(|b| table.rgb_or_zero(b)))
    }
}

/// The largest value of per-incidence RGB albedos, and its incidence in degrees.
pub fn largest(albedos: &[[f64; 3]]) -> (f64, f64) {
    let mut best = (f64::NEG_INFINITY, 0.0);
    for (a, deg) in albedos.iter().zip(INCIDENCE_DEGREES) {
        for v in a {
            if *v > best.0 {
                best = (*v, deg);
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::Analytic;

    #[test]
    fn each_entry_knows_its_incidence() {
        let rule = DirectionalRule::new(Dims::new(8, 8, 16).unwrap());
        let k: Vec<usize> = rule.incidences().collect();
        assert_eq!(k.len(), rule.bins().len());
        for (e, &k) in k.iter().enumerate() {
            assert!(
                (rule.start_of(k)..rule.start_of(k + 1)).contains(&e),
                "entry {e}"
            );
        }
    }

    #[test]
    fn a_lambertian_table_reflects_its_albedo_at_every_incidence() {
        let dims = Dims::new(90, 90, 180).unwrap();
        let rho = [0.2, 0.5, 0.9];
        let table = MerlTable::from_fn(dims, |_| Some(rho.map(|r| r / PI)));
        let rule = DirectionalRule::new(dims);
        for (a, deg) in rule
            .integrate(|b| table.rgb_or_zero(b))
            .iter()
            .zip(INCIDENCE_DEGREES)
        {
            for c in 0..3 {
                assert!(
                    (a[c] - rho[c]).abs() <= 0.01 * rho[c],
                    "{deg} degrees, channel {c}: {} for {}",
                    a[c],
                    rho[c]
                );
            }
        }
        let (max, _) = rule.max_albedo(&table);
        assert!((max - 0.9).abs() <= 0.009);
    }

    /// The half-vector rule against a brute-force midpoint integral over the
    /// outgoing hemisphere (uniform in `cos theta_o` and `phi_o`, 1000 x 2000
    /// cells) of the same nearest-bin table, for a glossy material.
    #[test]
    fn a_glossy_table_matches_a_brute_force_integral_over_outgoing_directions() {
        let dims = Dims::new(90, 90, 180).unwrap();
        let analytic = Analytic {
            diffuse: [0.1, 0.05, 0.02],
            f0: [0.9, 0.6, 0.3],
            alpha: 0.15,
        };
        let table = analytic.table(dims);
        let rule = DirectionalRule::new(dims);
        let ours = rule.integrate(|b| table.rgb_or_zero(b));
        for (k, deg) in INCIDENCE_DEGREES
            .iter()
            .enumerate()
            .filter(|(k, _)| k % 3 == 0)
        {
            let (si, ci) = deg.to_radians().sin_cos();
            let wi = [si, 0.0, ci];
            let (nm, np) = (1000, 2000);
            let mut acc = [0.0f64; 3];
            for a in 0..nm {
                let mu = (a as f64 + 0.5) / nm as f64;
                let s = (1.0 - mu * mu).sqrt();
                for p in 0..np {
                    let (sp, cp) = ((p as f64 + 0.5) / np as f64 * 2.0 * PI).sin_cos();
                    if let Some(b) = dims.bin_of_directions(wi, [s * cp, s * sp, mu]) {
                        let v = table.rgb_or_zero(b);
                        for c in 0..3 {
                            acc[c] += v[c] * mu;
                        }
                    }
                }
            }
            let cell = (1.0 / nm as f64) * (2.0 * PI / np as f64);
            for c in 0..3 {
                let reference = acc[c] * cell;
                assert!(
                    (ours[k][c] - reference).abs() <= 0.02 * reference.max(0.01),
                    "{deg} degrees, channel {c}: {} against {reference}",
                    ours[k][c]
                );
            }
        }
    }
}
