//! Albedo by quadrature over the MERL bins.
//!
//! The albedo of a BRDF `f` is
//! `(1/pi) * integral over both hemispheres of f(wi, wo) cos(theta_i) cos(theta_o) dwi dwo`,
//! so that a Lambertian `f = rho/pi` gives exactly `rho`.
//!
//! The integral is taken in the table's own coordinates. The change of
//! variables from `(wi, wo)` to the half and difference directions has
//! Jacobian `dwi dwo = 4 cos(theta_d) dwh dwd`; `phi_h` integrates to `2 pi`
//! for an isotropic BRDF, reciprocity doubles the `[0, pi)` range of `phi_d`,
//! and the square-root map of `theta_h = u^2 pi/2` adds `dtheta_h = pi u du`.
//! Altogether, with `(u, theta_d, phi_d)` over `[0,1) x [0,pi/2) x [0,pi)`:
//!
//! `albedo = 16 pi * integral of f * u sin(theta_h) cos(theta_d) sin(theta_d) cos(theta_i) cos(theta_o) du dtheta_d dphi_d`
//!
//! over the region where both directions are above the horizon.
//!
//! A [`Quadrature`] is that integral discretised once for a table's dims:
//! a list of `(bin, weight)` with `albedo = sum weight * f[bin]`. It is linear
//! in `f`, deterministic and sequential in bin order, so the same table always
//! gives the same bits whatever the thread count. Its bins are also exactly the
//! bins a consumer needs to reconstruct to integrate a new material, and no others.

use std::f64::consts::{FRAC_PI_2, PI};

use rayon::prelude::*;

use crate::angles::Dims;
use crate::table::MerlTable;

/// Relative numbers of boxes along theta_h, theta_d and phi_d in
/// [`Quadrature::with_samples_shaped`] (product 1): highlights vary fastest
/// along theta_h, measured BRDFs slowest along phi_d.
const SHAPED_SPLIT: [f64; 3] = [4.0, 1.0, 0.25];

/// A quadrature rule for the albedo integral on a MERL grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Quadrature {
    dims: Dims,
    bins: Vec<u32>,
    weights: Vec<f64>,
}

/// Integrand weight at a point of `(u, theta_d, phi_d)` space, per unit
/// volume, from the sines and cosines of `theta_h = u^2 pi / 2` and
/// `theta_d`, and `cos phi_d`: arithmetic only, for the rules' triple loops.
/// With `a = cos theta_h cos theta_d` and `b = sin theta_h sin theta_d cos phi_d`,
/// `cos theta_i = a - b` and `cos theta_o = a + b` ([`HalfDiff::cosines`](crate::angles::HalfDiff::cosines)),
/// so both are positive exactly when `a > |b|`, and their product is `a^2 - b^2`.
#[inline]
fn density_from(u: f64, (sh, ch): (f64, f64), (sd, cd): (f64, f64), cos_phi_d: f64) -> f64 {
    let a = ch * cd;
    let b = sh * sd * cos_phi_d;
    if a - b <= 0.0 || a + b <= 0.0 {
        return 0.0;
    }
    16.0 * PI * u * sh * cd * sd * ((a - b) * (a + b))
}

impl Quadrature {
    /// The reference rule: every bin's cell split into `sub^3` sub-cells,
    /// midpoint rule in each. The table is piecewise constant on bins (it is
    /// looked up by nearest bin), so this converges to the exact integral of
    /// the table as `sub` grows. `sub = 2` is accurate to about 1e-4 on MERL dims.
    pub fn dense(dims: Dims, sub: usize) -> Quadrature {
        let sub = sub.max(1);
        let (nu, nt, np) = (dims.theta_h * sub, dims.theta_d * sub, dims.phi_d * sub);
        let (du, dt, dp) = (1.0 / nu as f64, FRAC_PI_2 / nt as f64, PI / np as f64);
        let row = dims.theta_d * dims.phi_d;
        let mut dense = vec![0.0f64; dims.bins()];
        let theta_d: Vec<(f64, f64)> = (0..nt)
            .map(|it| ((it as f64 + 0.5) * dt).sin_cos())
            .collect();
        let cos_phi_d: Vec<f64> = (0..np).map(|ip| ((ip as f64 + 0.5) * dp).cos()).collect();
        let volume = du * dt * dp;
        dense.par_chunks_mut(row).enumerate().for_each(|(ih, out)| {
            for su in 0..sub {
                let u = ((ih * sub + su) as f64 + 0.5) * du;
                let h = (u * u * FRAC_PI_2).sin_cos();
                for (it, &d) in theta_d.iter().enumerate() {
                    let out = &mut out[(it / sub) * dims.phi_d..][..dims.phi_d];
                    for (ip, &cp) in cos_phi_d.iter().enumerate() {
                        out[ip / sub] += density_from(u, h, d, cp) * volume;
                    }
                }
            }
        });
        Quadrature::compact(dims, dense)
    }

    /// A cheaper rule with about `samples` points for tables shaped like
    /// `shape` (one positive value per bin, e.g. the mean of the materials a
    /// table is blended from): the accuracy/time trade of the albedo map.
    /// The bin grid is cut into about `samples` boxes of whole bins (boxes
    /// align with bins: no aliasing); in each box the table is assumed
    /// proportional to `shape`, so one bin `b` stands for the box with
    /// weight `sum_box(w shape) / shape(b)`, `w` the weights of the `fine`
    /// rule (normally [`Quadrature::dense`] with 2 sub-cells): exact when the
    /// table is a multiple of `shape` on every box, and `fine` at one bin a
    /// box. `b` is the box's bin nearest the centroid of `w shape`. From one
    /// sample per bin up, the rule is [`Quadrature::dense`] with as many
    /// sub-cells per bin as the budget allows.
    pub fn with_samples_shaped(fine: &Quadrature, samples: usize, shape: &[f64]) -> Quadrature {
        let dims = fine.dims;
        if samples >= dims.bins() {
            let sub = ((samples / dims.bins()) as f64).cbrt().floor() as usize;
            return Quadrature::dense(dims, sub.max(1));
        }
        if shape.len() != dims.bins() {
            return fine.clone();
        }
        let side = (dims.bins() as f64 / samples.max(1) as f64).cbrt();
        let cuts = |n: usize, more: f64| -> Vec<usize> {
            let boxes = ((n as f64 * more / side).round() as usize).clamp(1, n);
            (0..=boxes).map(|j| j * n / boxes).collect()
        };
        let (ch, cd, cp) = (
            cuts(dims.theta_h, SHAPED_SPLIT[0]),
            cuts(dims.theta_d, SHAPED_SPLIT[1]),
            cuts(dims.phi_d, SHAPED_SPLIT[2]),
        );
        Quadrature::shaped_boxes(fine, shape, [&ch, &cd, &cp])
    }

    /// [`Quadrature::with_samples_shaped`] on every theta_h bin (where
    /// highlights live), with `theta_d` x `phi_d` boxes in each theta_h
    /// band: `dims.theta_h * theta_d * phi_d` samples.
    pub fn banded_shaped(
        fine: &Quadrature,
        theta_d: usize,
        phi_d: usize,
        shape: &[f64],
    ) -> Quadrature {
        let dims = fine.dims;
        if shape.len() != dims.bins() {
            return fine.clone();
        }
        let cuts = |n: usize, boxes: usize| -> Vec<usize> {
            let boxes = boxes.clamp(1, n);
            (0..=boxes).map(|j| j * n / boxes).collect()
        };
        let ch: Vec<usize> = (0..=dims.theta_h).collect();
        let (cd, cp) = (cuts(dims.theta_d, theta_d), cuts(dims.phi_d, phi_d));
        Quadrature::shaped_boxes(fine, shape, [&ch, &cd, &cp])
    }

    /// One bin a box of the grid `cuts` (theta_h, theta_d, phi_d) standing
    /// for the box's mass (the `fine` rule's weight times `shape`), with
    /// weight `mass / shape` there ([`Quadrature::with_samples_shaped`]).
    fn shaped_boxes(fine: &Quadrature, shape: &[f64], cuts: [&[usize]; 3]) -> Quadrature {
        let [ch, cd, cp] = cuts;
        let dims = fine.dims;
        let mut mass = vec![0.0f64; dims.bins()];
        for (&b, &w) in fine.bins.iter().zip(&fine.weights) {
            let f = shape[b as usize];
            mass[b as usize] = if f.is_finite() && f > 0.0 { w * f } else { 0.0 };
        }
        let mut rule = vec![0.0f64; dims.bins()];
        for h in ch.windows(2) {
            for d in cd.windows(2) {
                for p in cp.windows(2) {
                    let (mut total, mut centroid, mut heaviest) = (0.0, [0.0f64; 3], (0.0, 0));
                    for ih in h[0]..h[1] {
                        for id in d[0]..d[1] {
                            for ip in p[0]..p[1] {
                                let bin = dims.bin(ih, id, ip);
                                let m = mass[bin];
                                total += m;
                                for (c, i) in centroid.iter_mut().zip([ih, id, ip]) {
                                    *c += m * i as f64;
                                }
                                if m > heaviest.0 {
                                    heaviest = (m, bin);
                                }
                            }
                        }
                    }
                    if total <= 0.0 {
                        continue;
                    }
                    let [ih, id, ip] = centroid.map(|c| (c / total).round() as usize);
                    let at = dims.bin(ih, id, ip);
                    let at = if mass[at] > 0.0 { at } else { heaviest.1 };
                    rule[at] += total / shape[at];
                }
            }
        }
        Quadrature::compact(dims, rule)
    }

    /// The rule of a weight per bin: the bins of nonzero weight (a reduced
    /// rule's can be negative).
    fn compact(dims: Dims, dense: Vec<f64>) -> Quadrature {
        let (bins, weights) = dense
            .iter()
            .enumerate()
            .filter(|(_, w)| **w != 0.0)
            .map(|(b, w)| (b as u32, *w))
            .unzip();
        Quadrature {
            dims,
            bins,
            weights,
        }
    }

    /// This rule on every `step`-th phi_d bin: each run of `step` phi_d bins
    /// (the last one shorter) is read at its middle bin, which carries the
    /// run's summed weight, so the rule stays an integral over the whole
    /// table of a piecewise-constant surrogate. The albedo integrand is
    /// smooth in phi_d: at the MERL resolution every 8th bin is within
    /// 0.05% of this rule on sharp synthetic metals, dielectrics and their
    /// blends (tested), with an eighth of the bins. `step` 0 or 1 gives the
    /// rule back.
    pub fn every_phi_d(&self, step: usize) -> Quadrature {
        let (dims, step) = (self.dims, step.max(1));
        let mut dense = vec![0.0f64; dims.bins()];
        for (&b, &w) in self.bins.iter().zip(&self.weights) {
            let (ih, id, ip) = dims.unbin(b as usize);
            let kept = (ip / step * step + step / 2).min(dims.phi_d - 1);
            dense[dims.bin(ih, id, kept)] += w;
        }
        Quadrature::compact(dims, dense)
    }

    /// This rule on every `theta_d_step`-th theta_d bin and every
    /// `phi_d_step`-th phi_d bin (all of theta_h, where highlights live):
    /// the rule's integral of the table's interpolant through the kept
    /// bins, linear or (`cubic`) cubic Lagrange in theta_d and in phi_d,
    /// periodic in phi_d (an isotropic, reciprocal BRDF repeats with period
    /// pi there). So each bin's weight is shared among the kept bins whose
    /// interpolant reaches it, in the interpolant's proportions. The first
    /// and last theta_d bins are always kept. A bin whose interpolant
    /// would read a bin `readable` refuses (one unmeasured in the tables
    /// integrated: its value need not belong to the same smooth surface)
    /// keeps its own weight and is read itself. Cubic weights can be negative; the rule
    /// stays exact for any table that is cubic between the kept bins.
    /// Steps of 0 or 1 keep every bin along their axis.
    pub fn reduced(
        &self,
        theta_d_step: usize,
        phi_d_step: usize,
        cubic: bool,
        readable: impl Fn(usize) -> bool,
    ) -> Quadrature {
        let dims = self.dims;
        let along_d = Stencils::new(dims.theta_d, theta_d_step, false, cubic);
        let along_p = Stencils::new(dims.phi_d, phi_d_step, true, cubic);
        let mut rule = vec![0.0f64; dims.bins()];
        for (&b, &w) in self.bins.iter().zip(&self.weights) {
            let (ih, id, ip) = dims.unbin(b as usize);
            let (sd, sp) = (along_d.at(id), along_p.at(ip));
            let readable = sd
                .iter()
                .all(|&(nd, _)| sp.iter().all(|&(np, _)| readable(dims.bin(ih, nd, np))));
            if !readable {
                rule[b as usize] += w;
                continue;
            }
            for &(nd, wd) in sd {
                for &(np, wp) in sp {
                    rule[dims.bin(ih, nd, np)] += w * wd * wp;
                }
            }
        }
        Quadrature::compact(dims, rule)
    }

    /// Monte Carlo sampling of this rule: `samples` bins drawn at random
    /// (seeded, so the same rule every time) with probability proportional
    /// to their weight, each draw weighing the total weight over
    /// `samples`, so the estimate is unbiased and exact for a constant
    /// table; its error falls as one over the square root of `samples`.
    pub fn monte_carlo(&self, samples: usize, seed: u64) -> Quadrature {
        let dims = self.dims;
        let mut cumulative = Vec::with_capacity(self.weights.len());
        let mut total = 0.0f64;
        for &w in &self.weights {
            total += w.max(0.0);
            cumulative.push(total);
        }
        let mut rule = vec![0.0f64; dims.bins()];
        if samples == 0 || total <= 0.0 {
            return Quadrature::compact(dims, rule);
        }
        let share = total / samples as f64;
        let mut rng = crate::synth::SplitMix64::new(seed);
        for _ in 0..samples {
            let u = rng.next_f64() * total;
            let k = cumulative
                .partition_point(|&c| c <= u)
                .min(self.bins.len() - 1);
            rule[self.bins[k] as usize] += share;
        }
        Quadrature::compact(dims, rule)
    }

    /// The grid this rule is for.
    pub fn dims(&self) -> Dims {
        self.dims
    }

    /// Number of bins the rule reads.
    pub fn len(&self) -> usize {
        self.bins.len()
    }

    /// True when the rule reads no bin (never for valid dims).
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// The bins the rule reads, ascending.
    pub fn bins(&self) -> &[u32] {
        &self.bins
    }

    /// The weight of each bin in [`Quadrature::bins`].
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Albedo of any function of the bin (reflectance RGB), summed in bin order.
    pub fn integrate(&self, mut f: impl FnMut(usize) -> [f64; 3]) -> [f64; 3] {
        let mut acc = [0.0f64; 3];
        for (&b, &w) in self.bins.iter().zip(&self.weights) {
            let v = f(b as usize);
            for c in 0..3 {
                acc[c] += w * v[c];
            }
        }
        acc
    }

    /// Albedo of a table (unmeasured bins count as 0). Panics if the table's
    /// dims differ from the rule's; see [`Quadrature::dims`].
    pub fn albedo(&self, table: &MerlTable) -> [f64; 3] {
        assert_eq!(
            table.dims(),
            self.dims,
            "quadrature rule built for other dims"
        );
        self.integrate(|b| table.rgb_or_zero(b))
    }
}

/// The interpolation stencils of one axis of a reduced rule
/// ([`Quadrature::reduced`]): for each bin index, the kept indices its
/// interpolant reads and their weights.
struct Stencils {
    at: Vec<Vec<(usize, f64)>>,
}

impl Stencils {
    /// Kept indices `0, step, 2 step, ...` of `len` (and `len - 1` unless
    /// `periodic`, where the axis wraps round with period `len`), linear
    /// or cubic Lagrange stencils.
    fn new(len: usize, step: usize, periodic: bool, cubic: bool) -> Stencils {
        let step = step.max(1);
        let mut nodes: Vec<usize> = (0..len).step_by(step).collect();
        if !periodic && nodes.last() != Some(&(len - 1)) {
            nodes.push(len - 1);
        }
        let k = nodes.len();
        // The coordinate of node j, for j past either end of a periodic axis.
        let coord = |j: isize| -> f64 {
            let kk = k as isize;
            let wraps = j.div_euclid(kk);
            nodes[j.rem_euclid(kk) as usize] as f64 + (wraps * len as isize) as f64
        };
        let index = |j: isize| nodes[j.rem_euclid(k as isize) as usize];
        let at = (0..len)
            .map(|i| {
                // The last node at or before i.
                let j = nodes.partition_point(|&n| n <= i) as isize - 1;
                if nodes[j as usize] == i || k == 1 {
                    return vec![(nodes[j as usize], 1.0)];
                }
                let first = if !cubic {
                    j
                } else if periodic {
                    j - 1
                } else {
                    (j - 1).clamp(0, (k as isize - 4).max(0))
                };
                let count = if cubic {
                    4.min(if periodic { 4 } else { k })
                } else {
                    2
                };
                let xs: Vec<f64> = (first..first + count as isize).map(coord).collect();
                let x = i as f64;
                (0..count)
                    .map(|a| {
                        let weight: f64 = (0..count)
                            .filter(|&c| c != a)
                            .map(|c| (x - xs[c]) / (xs[a] - xs[c]))
                            .product();
                        (index(first + a as isize), weight)
                    })
                    .collect()
            })
            .collect();
        Stencils { at }
    }

    fn at(&self, i: usize) -> &[(usize, f64)] {
        &self.at[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::angles::HalfDiff;

    /// Integrand weight at a point of `(u, theta_d, phi_d)` space, per unit volume.
    fn density(u: f64, theta_d: f64, phi_d: f64) -> f64 {
        let (sh, ch) = (u * u * FRAC_PI_2).sin_cos();
        let (sd, cd) = theta_d.sin_cos();
        density_from(u, (sh, ch), (sd, cd), phi_d.cos())
    }

    fn lambert(dims: Dims, rho: [f64; 3]) -> MerlTable {
        MerlTable::from_fn(dims, |_| Some(rho.map(|r| r / PI)))
    }

    #[test]
    fn every_8th_phi_d_bin_gives_the_dense_albedo_of_sharp_materials_and_blends() {
        // Metals from mirror-like (alpha 0.03) to rough and dielectrics, at
        // the MERL resolution, and the average of each neighbouring pair.
        let dims = Dims::MERL;
        let dense = Quadrature::dense(dims, 2);
        let reduced = dense.every_phi_d(8);
        assert!(
            reduced.len() * 7 < dense.len(),
            "{} of {}",
            reduced.len(),
            dense.len()
        );
        let sum = |q: &Quadrature| q.weights().iter().sum::<f64>();
        assert!((sum(&reduced) - sum(&dense)).abs() < 1e-12 * sum(&dense));
        let tables: Vec<MerlTable> = crate::synth::database(6, 11)
            .iter()
            .map(|m| m.brdf.table(dims))
            .collect();
        let mut worst = 0.0f64;
        for (k, t) in tables.iter().enumerate() {
            let next = &tables[(k + 1) % tables.len()];
            let blend = |b: usize| {
                let (a, c) = (t.rgb_or_zero(b), next.rgb_or_zero(b));
                [0, 1, 2].map(|i| 0.5 * (a[i] + c[i]))
            };
            for (want, got) in [
                (dense.albedo(t), reduced.albedo(t)),
                (dense.integrate(blend), reduced.integrate(blend)),
            ] {
                for c in 0..3 {
                    worst = worst.max((got[c] - want[c]).abs() / want[c]);
                }
            }
        }
        assert!(worst <= 5e-4, "worst {worst}");
        // A step of 1 is the rule itself.
        assert_eq!(dense.every_phi_d(1), dense);
    }

    #[test]
    fn density_matches_the_cosines_of_the_half_diff_pair() {
        for k in 0..20_000 {
            let (u, td, pd) = (
                (k as f64 * 0.618_034).fract(),
                (k as f64 * 0.414_214).fract() * FRAC_PI_2,
                (k as f64 * 0.732_051).fract() * PI,
            );
            let theta_h = u * u * FRAC_PI_2;
            let (ci, co) = HalfDiff {
                theta_h,
                phi_h: 0.0,
                theta_d: td,
                phi_d: pd,
            }
            .cosines();
            let want = if ci <= 0.0 || co <= 0.0 {
                0.0
            } else {
                16.0 * PI * u * theta_h.sin() * td.cos() * td.sin() * ci * co
            };
            let got = density(u, td, pd);
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1e-3),
                "{k}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn reduced_rules_integrate_their_interpolants_exactly() {
        let dims = Dims::new(12, 30, 36).unwrap();
        let dense = Quadrature::dense(dims, 2);
        let everywhere = |_| true;
        assert_eq!(dense.reduced(1, 1, true, everywhere), dense);
        // A table cubic in theta_d's index (and of any shape in theta_h):
        // the cubic rule's interpolant is the table itself.
        let cubic = MerlTable::from_fn(dims, |b| {
            let (ih, id, _) = dims.unbin(b);
            let t = id as f64;
            let v = 0.1 + 0.02 * ih as f64 + 1e-3 * t - 2e-4 * t * t + 9e-6 * t * t * t;
            Some([v, 0.5 * v, 2.0 * v])
        });
        // A table periodic and smooth in phi_d, linear in theta_d.
        let periodic = MerlTable::from_fn(dims, |b| {
            let (_, id, ip) = dims.unbin(b);
            let phi = (ip as f64) / dims.phi_d as f64 * 2.0 * PI;
            let v = 0.3 + 0.01 * id as f64 + 0.05 * phi.cos();
            Some([v, v, v])
        });
        let want = dense.albedo(&cubic);
        for step in [2, 3, 4, 7] {
            let got = dense.reduced(step, 1, true, everywhere).albedo(&cubic);
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() <= 1e-12 * want[c],
                    "step {step}: {got:?} {want:?}"
                );
            }
            // Fewer bins, and a linear interpolant is not exact for a cubic.
            let linear = dense.reduced(step, 1, false, everywhere);
            assert!(
                linear.len() < dense.len(),
                "{} {}",
                linear.len(),
                dense.len()
            );
            assert!((linear.albedo(&cubic)[0] - want[0]).abs() > 1e-9 * want[0]);
        }
        // Along phi_d a cubic interpolant of a cosine is close, not exact;
        // closer as the step shrinks.
        let want = dense.albedo(&periodic)[0];
        let err = |step| {
            (dense.reduced(1, step, true, everywhere).albedo(&periodic)[0] - want).abs() / want
        };
        assert!(
            err(2) < 1e-5 && err(6) < 1e-3 && err(2) < err(6),
            "{} {}",
            err(2),
            err(6)
        );
        // A bin whose interpolant would read an unreadable bin is read itself.
        let unreadable = dims.bin(3, 8, 5);
        let guarded = dense.reduced(4, 6, true, |b| b != unreadable);
        assert!(!guarded.bins().contains(&(unreadable as u32)));
        let both = guarded.albedo(&cubic)[0];
        assert!((both - dense.albedo(&cubic)[0]).abs() <= 1e-3 * both);
    }

    #[test]
    fn monte_carlo_rules_are_unbiased_and_converge() {
        let dims = Dims::new(30, 30, 60).unwrap();
        let dense = Quadrature::dense(dims, 2);
        let rho = [0.8, 0.5, 0.05];
        // Exact for a constant table: every draw weighs the same.
        let a = dense.monte_carlo(1000, 7).albedo(&lambert(dims, rho));
        let want = dense.albedo(&lambert(dims, rho));
        for c in 0..3 {
            assert!((a[c] - want[c]).abs() <= 1e-12, "{a:?} {want:?}");
        }
        // A sharp table: the error of many seeds shrinks with the samples.
        let sharp = MerlTable::from_fn(dims, |b| {
            let (ih, _, _) = dims.unbin(b);
            let v = (-(ih as f64) / 3.0).exp() * 10.0 + 0.05;
            Some([v, v, v])
        });
        let want = dense.albedo(&sharp)[0];
        let rms = |samples| {
            let sum: f64 = (0..16)
                .map(|seed| (dense.monte_carlo(samples, seed).albedo(&sharp)[0] - want).powi(2))
                .sum();
            (sum / 16.0).sqrt() / want
        };
        let (few, many) = (rms(256), rms(16384));
        assert!(many < few / 4.0 && many < 0.05, "{few} {many}");
        // The same seed gives the same rule.
        assert_eq!(dense.monte_carlo(100, 3), dense.monte_carlo(100, 3));
    }

    #[test]
    fn weights_sum_to_pi_so_lambertian_gives_rho() {
        let q = Quadrature::dense(Dims::MERL, 2);
        let sum: f64 = q.weights().iter().sum();
        assert!((sum - PI).abs() < 1e-3 * PI, "sum of weights {sum}");
        let rho = [0.8, 0.5, 0.05];
        let a = q.albedo(&lambert(Dims::MERL, rho));
        for c in 0..3 {
            assert!((a[c] - rho[c]).abs() < 1e-3 * rho[c], "{a:?}");
        }
    }

    /// The dense rule, a shape (a glossy synthetic material's mean over
    /// channels, 0 where unmeasured), a table proportional to it and another
    /// material's table.
    fn shape_and_tables() -> (Quadrature, Vec<f64>, [MerlTable; 2]) {
        let dims = Dims::MERL;
        let materials = crate::synth::database(4, 5);
        let glossy = materials[1].brdf.table(dims);
        let shape: Vec<f64> = (0..dims.bins())
            .map(|b| glossy.rgb_or_zero(b).iter().sum::<f64>() / 3.0)
            .collect();
        let proportional =
            MerlTable::from_fn(dims, |b| Some([0.5, 1.0, 2.0].map(|k| k * shape[b])));
        let other = materials[0].brdf.table(dims);
        (Quadrature::dense(dims, 2), shape, [proportional, other])
    }

    /// `rules` (fewer bins to more) are exact for a table proportional to
    /// their shape, and converge on another table, to within 1% at the last.
    fn assert_exact_for_the_shape_and_converging(
        dense: &Quadrature,
        rules: &[Quadrature],
        [proportional, other]: &[MerlTable; 2],
    ) {
        for (table, exact) in [(proportional, true), (other, false)] {
            let want = dense.albedo(table);
            let errors: Vec<f64> = rules
                .iter()
                .map(|rule| {
                    let got = rule.albedo(table);
                    (0..3).fold(0.0f64, |e, c| e.max((got[c] - want[c]).abs() / want[c]))
                })
                .collect();
            if exact {
                assert!(errors.iter().all(|e| *e < 1e-12), "{errors:?}");
            } else {
                assert!(
                    errors.windows(2).all(|e| e[1] < e[0]) && errors[2] < 1e-2,
                    "{errors:?}"
                );
            }
        }
    }

    #[test]
    fn shaped_rules_are_exact_for_the_shape_and_converge_otherwise() {
        let (dense, shape, tables) = shape_and_tables();
        let rules = [64, 1024, 65_536].map(|s| Quadrature::with_samples_shaped(&dense, s, &shape));
        assert_exact_for_the_shape_and_converging(&dense, &rules, &tables);
    }

    #[test]
    fn banded_rules_keep_every_theta_h_bin_are_exact_for_the_shape_and_converge() {
        let (dense, shape, tables) = shape_and_tables();
        let dims = dense.dims();
        let rule = Quadrature::banded_shaped(&dense, 3, 4, &shape);
        // One bin a box: at most 3 x 4 a theta_h band, and every band read.
        let mut per_band = vec![0usize; dims.theta_h];
        for &b in rule.bins() {
            per_band[dims.unbin(b as usize).0] += 1;
        }
        assert!(
            per_band.iter().all(|&n| (1..=12).contains(&n)),
            "{per_band:?}"
        );
        let rules = [(2, 2), (6, 6), (30, 60)]
            .map(|(d, p)| Quadrature::banded_shaped(&dense, d, p, &shape));
        assert_exact_for_the_shape_and_converging(&dense, &rules, &tables);
    }

    #[test]
    fn same_bits_whatever_the_thread_count() {
        let dims = Dims::new(30, 30, 60).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| Quadrature::dense(dims, 2));
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
            .install(|| Quadrature::dense(dims, 2));
        assert_eq!(one, two);
    }
}
