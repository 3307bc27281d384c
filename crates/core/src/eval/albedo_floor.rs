//! The albedo floor of [`crate::BlendRule::Plausible`], held out: where the
//! leave-one-out prediction of a material, with its steps per `theta_h`
//! bin, has a largest directional albedo above 1 (or above the convex
//! blend's, where the materials themselves exceed 1), every bin's step is
//! raised to the smallest floor of [`STEPS`] that brings it down, as a
//! reconstruction at the material's latent point does.
//!
//! Only the bins the directional rule reads matter: the GP and convex
//! predictions of those rows, for every material, through one product per
//! block, summed into each material's albedo at each incidence for every
//! floor tried.

use brdf_merl::DirectionalRule;
use brdf_merl::directional::{INCIDENCE_DEGREES, largest};

use crate::data::store::Store;
use crate::dense::product::matmul;
use crate::error::Result;
use crate::model::blend::plausible_budget::STEPS;
use crate::simd::fold::{GROUPS, ordered_blocks_then};

/// Bins of the rule per block of the pass.
const BLOCK: usize = 512;

/// Albedo sums per material tried, floor tried, incidence and channel.
type Sums = Vec<[[f64; 3]; INCIDENCE_DEGREES.len()]>;

/// Raise `steps` (`theta_h` bin by bin, `N` per bin) where the held-out
/// prediction's largest directional albedo is too high. `stacked` is the
/// GP predictor above the convex one, column-major `2N x N`.
pub(crate) fn raise(store: &Store, stacked: &[f64], steps: &mut [f64]) -> Result<()> {
    let n = store.n();
    let all: Vec<usize> = (0..n).collect();
    let ends = albedos(store, stacked, steps, &all, &[0.0, 1.0]);
    let (mut needing, mut ceilings) = (Vec::new(), Vec::new());
    for i in 0..n {
        let ceiling = ends[2 * i + 1].max(1.0);
        if ends[2 * i] > ceiling {
            needing.push(i);
            ceilings.push(ceiling);
        }
    }
    if needing.is_empty() {
        return Ok(());
    }
    let floors = &STEPS[1..];
    let a = albedos(store, stacked, steps, &needing, floors);
    for (m, (&i, &ceiling)) in needing.iter().zip(&ceilings).enumerate() {
        let f = (0..floors.len())
            .find(|&f| a[m * floors.len() + f] <= ceiling)
            .map_or(1.0, |f| floors[f]);
        for band in steps.chunks_exact_mut(n) {
            band[i] = band[i].max(f);
        }
    }
    Ok(())
}

/// The largest directional albedo of the held-out prediction of each
/// material of `materials` with every bin's step at least each of
/// `floors`: `materials.len() x floors.len()` values, material by material.
fn albedos(
    store: &Store,
    stacked: &[f64],
    steps: &[f64],
    materials: &[usize],
    floors: &[f64],
) -> Vec<f64> {
    let (n, dims) = (store.n(), store.dims());
    let bins = dims.bins();
    let rule = DirectionalRule::new(dims);
    // The rule inverted: each bin it reads, with its (incidence, weight) pairs.
    let mut entries: Vec<(u32, usize, f64)> = (rule.bins().iter().zip(rule.weights()))
        .zip(rule.incidences())
        .map(|((&b, &w), k)| (b, k, w))
        .collect();
    entries.sort_by_key(|&(b, k, _)| (b, k));
    let mut read: Vec<(usize, Vec<(usize, f64)>)> = Vec::new();
    for (b, k, w) in entries {
        match read.last_mut() {
            Some((last, pairs)) if *last == b as usize => pairs.push((k, w)),
            _ => read.push((b as usize, vec![(k, w)])),
        }
    }
    let transform = store.transform().build(dims);
    let (mean, unmeasured) = (store.mean(), store.unmeasured());
    let (m, nf) = (materials.len(), floors.len());
    let parts = ordered_blocks_then(
        read.len(),
        BLOCK,
        GROUPS,
        || {
            (
                vec![[[0.0; 3]; INCIDENCE_DEGREES.len()]; m * nf],
                vec![0.0f64; 3 * BLOCK * n],
                vec![0.0f64; 3 * BLOCK * 2 * n],
            )
        },
        |(sums, z, out): &mut (Sums, Vec<f64>, Vec<f64>), range| {
            let cols = 3 * range.len();
            for (j, u) in range.clone().enumerate() {
                for ch in 0..3 {
                    let col = 3 * j + ch;
                    store.copy_rows(ch * bins + read[u].0, &mut z[col * n..(col + 1) * n]);
                }
            }
            matmul(&mut out[..cols * 2 * n], stacked, &z[..cols * n], n);
            for (j, u) in range.enumerate() {
                let (bin, pairs) = (read[u].0, &read[u].1);
                let band = dims.unbin(bin).0;
                let form = transform.inverse_form(bin);
                for ch in 0..3 {
                    let row = ch * bins + bin;
                    if unmeasured[row] != 0 {
                        continue;
                    }
                    let o = &out[(3 * j + ch) * 2 * n..(3 * j + ch + 1) * 2 * n];
                    for (mi, &i) in materials.iter().enumerate() {
                        let (g, c) = (mean[row] + o[i], mean[row] + o[n + i]);
                        for (fi, &f) in floors.iter().enumerate() {
                            let t = steps[band * n + i].max(f);
                            let y = g + t * (c - g);
                            let v = form.unclamped(y).max(0.0);
                            let acc = &mut sums[mi * nf + fi];
                            for &(k, w) in pairs {
                                acc[k][ch] += w * v;
                            }
                        }
                    }
                }
            }
        },
        |(sums, _, _)| sums,
    );
    let mut total: Sums = vec![[[0.0; 3]; INCIDENCE_DEGREES.len()]; m * nf];
    for p in &parts {
        for (t, s) in total.iter_mut().zip(p) {
            for k in 0..INCIDENCE_DEGREES.len() {
                for ch in 0..3 {
                    t[k][ch] += s[k][ch];
                }
            }
        }
    }
    total.iter().map(|a| largest(a).0).collect()
}
