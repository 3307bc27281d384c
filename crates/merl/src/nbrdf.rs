//! The 100 MERL materials as fitted by Neural BRDF (Sztrajman, Rainer,
//! Ritschel, Weyrich, "Neural BRDF Representation and Importance Sampling",
//! Computer Graphics Forum 2021): a realistic stand-in for the measured
//! database, which is 3.5 GB and not redistributable here, in 270 KB of
//! network weights (`data/nbrdf/`, with their licences).
//!
//! Each material is a 6-21-21-3 network with ReLU hidden layers. Its input
//! is the Rusinkiewicz half vector `(sin theta_h, 0, cos theta_h)` and
//! difference vector `(sin theta_d cos phi_d, sin theta_d sin phi_d,
//! cos theta_d)`; its output `y` gives the reflectance `e^y - 1` (1/sr).
//! Evaluated at the lower corner of every MERL bin, as the fits were made,
//! with bins whose incident or outgoing direction is at or below the
//! horizon unmeasured (MERL's -1). The values are plausible materials, not
//! ground truth: the fits are smooth, and poor near grazing angles.
//!
//! ```
//! use brdf_merl::{Dims, Quadrature, nbrdf};
//! let names = nbrdf::names();
//! assert_eq!(names.len(), 100);
//! let fabric = nbrdf::material("black-fabric").unwrap();
//! let table = fabric.table(Dims::new(16, 16, 32).unwrap());
//! let albedo = Quadrature::dense(table.dims(), 2).albedo(&table);
//! assert!(albedo.iter().all(|&a| a > 0.0 && a < 0.1), "{albedo:?}");
//! ```

use std::path::{Path, PathBuf};

use crate::angles::Dims;
use crate::error::{MerlError, Result};
use crate::table::{MerlTable, write_named};

/// The materials' names, one a line, in the order of [`WEIGHTS`].
const NAMES: &str = include_str!("../data/nbrdf/materials.txt");

/// Little-endian f32, one row of [`PER_MATERIAL`] values a material: the
/// layers' kernels (row-major, inputs by outputs) and biases in turn.
static WEIGHTS: &[u8] = include_bytes!("../data/nbrdf/weights.f32");

/// Layer widths of every network: 6 inputs, two hidden layers, RGB out.
const WIDTHS: [usize; 4] = [6, 21, 21, 3];

/// Weights a material: 6 x 21 + 21 + 21 x 21 + 21 + 21 x 3 + 3.
const PER_MATERIAL: usize = 675;

/// The 100 names, in the database's (alphabetical) order.
pub fn names() -> Vec<&'static str> {
    NAMES.split_whitespace().collect()
}

/// One material's network.
#[derive(Debug, Clone)]
pub struct Network {
    name: &'static str,
    weights: Vec<f64>,
}

/// The network of material `name`, if the database has it.
pub fn material(name: &str) -> Option<Network> {
    let index = names().iter().position(|n| *n == name)?;
    let name = names()[index];
    let bytes = &WEIGHTS[4 * PER_MATERIAL * index..4 * PER_MATERIAL * (index + 1)];
    let weights = bytes
        .chunks_exact(4)
        .map(|b| f64::from(f32::from_le_bytes(b.try_into().expect("4 bytes"))))
        .collect();
    Some(Network { name, weights })
}

impl Network {
    /// The material's name.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// The reflectance (1/sr, RGB) at half vector `half` and difference
    /// vector `diff`, clamped at 0.
    pub fn eval(&self, half: [f64; 3], diff: [f64; 3]) -> [f64; 3] {
        let mut input = [0.0; 21];
        input[..3].copy_from_slice(&half);
        input[3..6].copy_from_slice(&diff);
        let (mut a, mut b) = (input, [0.0; 21]);
        let mut at = 0;
        for (layer, w) in WIDTHS.windows(2).enumerate() {
            let (n_in, n_out) = (w[0], w[1]);
            let kernel = &self.weights[at..at + n_in * n_out];
            let bias = &self.weights[at + n_in * n_out..at + n_in * n_out + n_out];
            at += n_in * n_out + n_out;
            b[..n_out].copy_from_slice(bias);
            for (i, &x) in a[..n_in].iter().enumerate() {
                for (o, k) in b[..n_out]
                    .iter_mut()
                    .zip(&kernel[i * n_out..(i + 1) * n_out])
                {
                    *o += x * k;
                }
            }
            if layer + 2 < WIDTHS.len() {
                b[..n_out].iter_mut().for_each(|v| *v = v.max(0.0));
            }
            std::mem::swap(&mut a, &mut b);
        }
        [0, 1, 2].map(|c| a[c].exp_m1().max(0.0))
    }

    /// The material tabulated on the MERL grid of `dims`.
    pub fn table(&self, dims: Dims) -> MerlTable {
        let (n_th, n_td, n_pd) = (dims.theta_h, dims.theta_d, dims.phi_d);
        let quarter = std::f64::consts::FRAC_PI_2;
        MerlTable::from_fn(dims, |bin| {
            let (i_th, rest) = (bin / (n_td * n_pd), bin % (n_td * n_pd));
            let (i_td, i_pd) = (rest / n_pd, rest % n_pd);
            let th = (i_th as f64 / n_th as f64).powi(2) * quarter;
            let td = i_td as f64 / n_td as f64 * quarter;
            let pd = i_pd as f64 / n_pd as f64 * std::f64::consts::PI;
            let (sh, ch) = th.sin_cos();
            let (sd, cd) = td.sin_cos();
            let (sp, cp) = pd.sin_cos();
            // The two directions' heights above the surface.
            let wi_z = cd * ch - sd * cp * sh;
            let wo_z = cd * ch + sd * cp * sh;
            (wi_z > 0.0 && wo_z > 0.0).then(|| self.eval([sh, 0.0, ch], [sd * cp, sd * sp, cd]))
        })
    }
}

/// Write the materials `names` (every one if empty) tabulated on `dims` as
/// `NAME.binary` in `dir` (created if missing), all or none; the paths, in
/// the order given. An unknown name is an error before anything is written.
pub fn write_dir(dir: &Path, names: &[&str], dims: Dims) -> Result<Vec<PathBuf>> {
    let all = self::names();
    let chosen: Vec<&str> = if names.is_empty() {
        all
    } else {
        names.to_vec()
    };
    let networks = chosen
        .iter()
        .map(|n| {
            material(n).ok_or_else(|| MerlError::UnknownMaterial {
                name: n.to_string(),
            })
        })
        .collect::<Result<Vec<Network>>>()?;
    write_named(dir, &networks, |m| m.name, |m| m.table(dims))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::angles::{HalfDiff, direction};

    #[test]
    fn the_weights_are_whole() {
        assert_eq!(names().len(), 100);
        assert_eq!(WEIGHTS.len(), 4 * PER_MATERIAL * names().len());
        let widths: usize = WIDTHS.windows(2).map(|w| w[0] * w[1] + w[1]).sum();
        assert_eq!(widths, PER_MATERIAL);
        assert!(material("no-such-material").is_none());
    }

    /// The network as its definition reads, with matrices: an independent
    /// forward pass.
    fn by_matrices(net: &Network, x: [f64; 6]) -> [f64; 3] {
        let mut v: Vec<f64> = x.to_vec();
        let mut at = 0;
        for (layer, w) in WIDTHS.windows(2).enumerate() {
            let (n_in, n_out) = (w[0], w[1]);
            let k = |i: usize, o: usize| net.weights[at + i * n_out + o];
            let out: Vec<f64> = (0..n_out)
                .map(|o| {
                    let s = net.weights[at + n_in * n_out + o]
                        + (0..n_in).map(|i| v[i] * k(i, o)).sum::<f64>();
                    if layer < 2 { s.max(0.0) } else { s }
                })
                .collect();
            at += n_in * n_out + n_out;
            v = out;
        }
        [
            v[0].exp_m1().max(0.0),
            v[1].exp_m1().max(0.0),
            v[2].exp_m1().max(0.0),
        ]
    }

    #[test]
    fn the_table_holds_the_network_at_each_bins_lower_corner() {
        let dims = Dims::new(12, 10, 16).unwrap();
        for name in ["gold-metallic-paint", "black-fabric", "teflon"] {
            let net = material(name).unwrap();
            let table = net.table(dims);
            let n = dims.bins();
            let mut measured = 0;
            for bin in (0..n).step_by(7) {
                let (i_th, i_td, i_pd) = (bin / 160, bin / 16 % 10, bin % 16);
                let hd = HalfDiff {
                    phi_h: 0.0,
                    theta_h: (i_th as f64 / 12.0).powi(2) * std::f64::consts::FRAC_PI_2,
                    theta_d: i_td as f64 / 10.0 * std::f64::consts::FRAC_PI_2,
                    phi_d: i_pd as f64 / 16.0 * std::f64::consts::PI,
                };
                // Both directions from the angles module's own conversion.
                let (wi, wo) = hd.directions();
                let h = direction(hd.theta_h, 0.0);
                let d = direction(hd.theta_d, hd.phi_d);
                let want = by_matrices(&net, [h[0], h[1], h[2], d[0], d[1], d[2]]);
                let got = table.value(0, bin);
                if wi[2] > 1e-9 && wo[2] > 1e-9 {
                    measured += 1;
                    for (c, &w) in want.iter().enumerate() {
                        let v = table.value(c, bin).expect("measured");
                        assert!((v - w).abs() <= 1e-12 * w.max(1.0), "{name} {bin}");
                    }
                } else if wi[2] < -1e-9 || wo[2] < -1e-9 {
                    assert_eq!(got, None, "{name} {bin}: below the horizon");
                }
            }
            assert!(measured > 100, "{name}: {measured}");
        }
    }
}
