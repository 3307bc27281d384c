//! Importance sampling of outgoing directions for an isotropic BRDF given
//! as a function of `(wi, wo)`: a table of the material's own lobe, mixed
//! with cosine-weighted sampling.
//!
//! The incident elevation is split into [`THETA_I`] slices. For each slice,
//! at its centre elevation (azimuth 0), the outgoing hemisphere is split
//! into [`THETA_O`] x [`PHI_O`] cells, uniform in elevation and in azimuth
//! relative to the incident direction, and each cell weighs
//! `mean(f) cos_o * solid angle`, `f`'s channel mean at 2 x 2 points of the
//! cell. A direction is drawn by picking a cell (a marginal over elevation
//! rows, then a conditional over azimuth) and a point uniform in solid angle
//! inside it, so the density is piecewise constant per cell:
//! `p = w_cell / (W * solid angle)`. A fraction [`COSINE_SHARE`] of the
//! samples is cosine-weighted instead, so that every direction the table
//! misses (a lobe narrower than a cell, a slice whose centre sees nothing)
//! keeps a density; the density of the mixture is what `pdf` returns, and
//! what `sample` returns with the direction.

use std::f64::consts::{FRAC_PI_2, PI};

use brdf_merl::Vec3;
use rayon::prelude::*;

/// Slices of incident elevation.
pub const THETA_I: usize = 16;
/// Rows of outgoing elevation per slice.
pub const THETA_O: usize = 64;
/// Columns of relative outgoing azimuth per row, over `[0, 2 pi)`.
pub const PHI_O: usize = 128;
/// Share of cosine-weighted samples in the mixture.
pub const COSINE_SHARE: f64 = 0.1;

/// How directions are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Cosine-weighted hemisphere sampling: `p = cos_o / pi`.
    Cosine,
    /// The tabulated lobe mixed with cosine sampling.
    Tabulated,
}

impl Method {
    /// Parse `cosine` or `tabulated`.
    pub fn parse(s: &str) -> Option<Method> {
        match s {
            "cosine" => Some(Method::Cosine),
            "tabulated" => Some(Method::Tabulated),
            _ => None,
        }
    }
}

/// The tabulated distribution of one material.
#[derive(Debug)]
pub struct Tabulated {
    /// Per slice: the cumulative row weights, `THETA_O + 1` values from 0 to 1.
    marginal: Vec<f64>,
    /// Per slice and row: the cumulative cell weights, `PHI_O + 1` values from 0 to 1.
    conditional: Vec<f64>,
    /// Per slice and cell: the density per solid angle.
    density: Vec<f64>,
    /// Per slice: false when the slice's lobe is zero everywhere (then only
    /// cosine sampling is used there).
    usable: Vec<bool>,
}

const D_THETA: f64 = FRAC_PI_2 / THETA_O as f64;
const D_PHI: f64 = 2.0 * PI / PHI_O as f64;

fn theta_edge(j: usize) -> f64 {
    j as f64 * D_THETA
}

fn cell_solid_angle(j: usize) -> f64 {
    (theta_edge(j).cos() - theta_edge(j + 1).cos()) * D_PHI
}

fn slice_of(cos_i: f64) -> usize {
    let theta = cos_i.clamp(-1.0, 1.0).acos();
    ((theta / FRAC_PI_2 * THETA_I as f64) as usize).min(THETA_I - 1)
}

fn normalize(v: Vec3) -> Option<Vec3> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (n > 0.0 && n.is_finite()).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

/// Prefix sums of `w` scaled to end at 1 (`None` when `w` sums to 0).
fn cdf(w: &[f64]) -> Option<Vec<f64>> {
    let mut c = Vec::with_capacity(w.len() + 1);
    let mut s = 0.0;
    c.push(0.0);
    for &v in w {
        s += v;
        c.push(s);
    }
    if s <= 0.0 || !s.is_finite() {
        return None;
    }
    c.iter_mut().for_each(|v| *v /= s);
    Some(c)
}

/// Index `k` with `c[k] <= u < c[k + 1]` and the position of `u` inside
/// that interval, in `[0, 1)`; intervals of zero width are never chosen.
fn pick(c: &[f64], u: f64) -> (usize, f64) {
    let n = c.len() - 1;
    let k = c.partition_point(|&v| v <= u).clamp(1, n) - 1;
    let w = c[k + 1] - c[k];
    let t = if w > 0.0 { (u - c[k]) / w } else { 0.0 };
    (k, t.clamp(0.0, 1.0 - f64::EPSILON / 2.0))
}

impl Tabulated {
    /// Tabulate the lobe of `f` (reflectance in 1/sr, `None` where it has no
    /// value), in parallel over slices.
    pub fn new(f: &(dyn Fn(Vec3, Vec3) -> Option<[f64; 3]> + Sync)) -> Tabulated {
        let slices: Vec<_> = (0..THETA_I)
            .into_par_iter()
            .map(|s| {
                let theta_i = (s as f64 + 0.5) / THETA_I as f64 * FRAC_PI_2;
                let wi = [theta_i.sin(), 0.0, theta_i.cos()];
                let mut weights = vec![0.0; THETA_O * PHI_O];
                for j in 0..THETA_O {
                    for l in 0..PHI_O {
                        let mut sum = 0.0;
                        for (a, b) in [(0.25, 0.25), (0.25, 0.75), (0.75, 0.25), (0.75, 0.75)] {
                            let t = (j as f64 + a) * D_THETA;
                            let p = (l as f64 + b) * D_PHI;
                            let wo = [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()];
                            if let Some(v) = f(wi, wo) {
                                sum += (v[0] + v[1] + v[2]) / 3.0 * t.cos();
                            }
                        }
                        let w = sum / 4.0 * cell_solid_angle(j);
                        weights[j * PHI_O + l] = if w.is_finite() && w > 0.0 { w } else { 0.0 };
                    }
                }
                let rows: Vec<f64> = weights.chunks(PHI_O).map(|r| r.iter().sum()).collect();
                let total: f64 = rows.iter().sum();
                match cdf(&rows) {
                    Some(marginal) => {
                        let mut conditional = Vec::with_capacity(THETA_O * (PHI_O + 1));
                        for r in weights.chunks(PHI_O) {
                            conditional.extend(cdf(r).unwrap_or_else(|| vec![0.0; PHI_O + 1]));
                        }
                        let density = weights
                            .iter()
                            .enumerate()
                            .map(|(k, w)| w / (total * cell_solid_angle(k / PHI_O)))
                            .collect();
                        (marginal, conditional, density, true)
                    }
                    None => (
                        vec![0.0; THETA_O + 1],
                        vec![0.0; THETA_O * (PHI_O + 1)],
                        vec![0.0; THETA_O * PHI_O],
                        false,
                    ),
                }
            })
            .collect();
        let mut t = Tabulated {
            marginal: Vec::new(),
            conditional: Vec::new(),
            density: Vec::new(),
            usable: Vec::new(),
        };
        for (m, c, d, u) in slices {
            t.marginal.extend(m);
            t.conditional.extend(c);
            t.density.extend(d);
            t.usable.push(u);
        }
        t
    }

    /// The tabulated density of `wo` given `wi` (both unit, above the horizon).
    fn table_pdf(&self, s: usize, wi: Vec3, wo: Vec3) -> f64 {
        if !self.usable[s] {
            return 0.0;
        }
        let theta_o = wo[2].clamp(-1.0, 1.0).acos();
        let j = ((theta_o / D_THETA) as usize).min(THETA_O - 1);
        let phi = (wo[1].atan2(wo[0]) - wi[1].atan2(wi[0])).rem_euclid(2.0 * PI);
        let l = ((phi / D_PHI) as usize).min(PHI_O - 1);
        self.density[(s * THETA_O + j) * PHI_O + l]
    }
}

/// The share of cosine samples in slice `s`.
fn cosine_share(table: Option<&Tabulated>, s: usize) -> f64 {
    match table {
        Some(t) if t.usable[s] => COSINE_SHARE,
        _ => 1.0,
    }
}

/// The density (per solid angle) of drawing `wo` given `wi`; 0 when either
/// is at or below the horizon or not a direction.
pub fn pdf(table: Option<&Tabulated>, wi: Vec3, wo: Vec3) -> f64 {
    let (Some(wi), Some(wo)) = (normalize(wi), normalize(wo)) else {
        return 0.0;
    };
    if wi[2] <= 0.0 || wo[2] <= 0.0 {
        return 0.0;
    }
    let s = slice_of(wi[2]);
    let c = cosine_share(table, s);
    let tab = match table {
        Some(t) if c < 1.0 => t.table_pdf(s, wi, wo),
        _ => 0.0,
    };
    c * wo[2] / PI + (1.0 - c) * tab
}

/// Draw `wo` given `wi` from two uniform numbers in `[0, 1)`; returns the
/// direction and its density, `None` when `wi` is at or below the horizon.
pub fn sample(table: Option<&Tabulated>, wi: Vec3, u: [f64; 2]) -> Option<(Vec3, f64)> {
    let wi = normalize(wi)?;
    if wi[2] <= 0.0 {
        return None;
    }
    let u = u.map(|v| {
        if v.is_finite() {
            v.clamp(0.0, 1.0 - f64::EPSILON / 2.0)
        } else {
            0.0
        }
    });
    let s = slice_of(wi[2]);
    let c = cosine_share(table, s);
    let wo = match table {
        Some(t) if u[0] >= c => {
            let u0 = ((u[0] - c) / (1.0 - c)).clamp(0.0, 1.0 - f64::EPSILON / 2.0);
            let (j, tj) = pick(&t.marginal[s * (THETA_O + 1)..(s + 1) * (THETA_O + 1)], u0);
            let row = (s * THETA_O + j) * (PHI_O + 1);
            let (l, tl) = pick(&t.conditional[row..row + PHI_O + 1], u[1]);
            let (c0, c1) = (theta_edge(j).cos(), theta_edge(j + 1).cos());
            let cos_o = c0 - tj * (c0 - c1);
            let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
            let phi = wi[1].atan2(wi[0]) + (l as f64 + tl) * D_PHI;
            [sin_o * phi.cos(), sin_o * phi.sin(), cos_o]
        }
        _ => {
            // Cosine-weighted: a uniform point of the unit disc lifted to the hemisphere.
            let u0 = if c < 1.0 { u[0] / c } else { u[0] };
            let r = u0.min(1.0).sqrt();
            let phi = 2.0 * PI * u[1];
            let z = (1.0 - r * r).max(0.0).sqrt();
            [r * phi.cos(), r * phi.sin(), z]
        }
    };
    let p = pdf(table, wi, wo);
    (p > 0.0).then_some((wo, p))
}
