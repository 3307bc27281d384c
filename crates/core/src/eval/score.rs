//! The scoring of [`super::loo::evaluate_some`]'s pass: what each block of
//! rows adds to the error and albedo sums of every output.

use crate::data::transform::{InverseForm, Transform};
use crate::simd::fastlog::log1p;

/// The offset `e` of the log-relative error
/// [`Errors::log_rel`](super::loo::Errors::log_rel).
pub const LOG_REL_OFFSET: f64 = 1e-3;

/// The store rows of a block: consecutive from a first, or listed.
#[derive(Clone, Copy)]
pub(super) enum RowIds<'a> {
    From(usize),
    List(&'a [u32]),
}

impl RowIds<'_> {
    #[inline(always)]
    pub(super) fn get(self, k: usize) -> usize {
        match self {
            RowIds::From(r0) => r0 + k,
            RowIds::List(list) => list[k] as usize,
        }
    }
}

/// What the error sums of [`evaluate`] read, for every block.
pub(super) struct Scoring<'a> {
    pub(super) n: usize,
    pub(super) bins: usize,
    pub(super) mean: &'a [f64],
    pub(super) unmeasured: &'a [u8],
    pub(super) grazing: &'a [bool],
    pub(super) cos: &'a [f64],
    /// Albedo weight of each bin.
    pub(super) weight: &'a [f64],
    /// Which outputs are scored.
    pub(super) scored: &'a [bool],
    pub(super) transform: &'a dyn Transform,
    pub(super) log_space: bool,
}

/// Sums per (output, material): squared errors (transformed, reflectance,
/// log, log-relative) and albedo per channel; and the true albedos.
pub(super) struct Sums {
    pub(super) transformed: Vec<f64>,
    pub(super) raw: Vec<f64>,
    pub(super) log: Vec<f64>,
    pub(super) log_rel: Vec<f64>,
    pub(super) albedo: [Vec<f64>; 3],
    pub(super) truth: [Vec<f64>; 3],
}

impl Sums {
    pub(super) fn zeros(mt: usize, n: usize) -> Sums {
        Sums {
            transformed: vec![0.0; mt],
            raw: vec![0.0; mt],
            log: vec![0.0; mt],
            log_rel: vec![0.0; mt],
            albedo: [0, 1, 2].map(|_| vec![0.0; mt]),
            truth: [0, 1, 2].map(|_| vec![0.0; n]),
        }
    }

    pub(super) fn add(&mut self, other: &Sums) {
        let pairs = [
            (&mut self.transformed, &other.transformed),
            (&mut self.raw, &other.raw),
            (&mut self.log, &other.log),
            (&mut self.log_rel, &other.log_rel),
        ];
        let channels = self.albedo.iter_mut().zip(&other.albedo);
        let truths = self.truth.iter_mut().zip(&other.truth);
        for (a, b) in pairs.into_iter().chain(channels).chain(truths) {
            a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
        }
    }
}

/// One row's true values: transformed, reflectance, cosine-weighted log,
/// and `ln(1 + f cos_i cos_o / e)`.
pub(super) struct RowScratch {
    pub(super) truth: Vec<f64>,
    pub(super) reflectance: Vec<f64>,
    pub(super) log: Vec<f64>,
    pub(super) rel: Vec<f64>,
    /// One output's predicted reflectance and cosine-weighted log.
    pub(super) predicted: Vec<f64>,
    pub(super) predicted_log: Vec<f64>,
}

/// Add the squared errors of the predictions `out` (`mn` per row) of the
/// rows `r0..` whose centred values are `z` (`n` per row) into `sums`;
/// returns the number of rows scored in reflectance and log.
///
/// `fastlog::log1p` is written with fused multiply-adds: where the CPU has
/// FMA this runs compiled for it (instructions, not library calls; the same
/// bits), as plain loops, so nothing falls back to code without it.
pub(super) fn score_block(
    s: &Scoring<'_>,
    ids: RowIds<'_>,
    z: &[f64],
    out: &[f64],
    sums: &mut Sums,
    row: &mut RowScratch,
) -> usize {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::has_avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        return unsafe { score_block_fma(s, ids, z, out, sums, row) };
    }
    score_block_portable(s, ids, z, out, sums, row)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn score_block_fma(
    s: &Scoring<'_>,
    ids: RowIds<'_>,
    z: &[f64],
    out: &[f64],
    sums: &mut Sums,
    row: &mut RowScratch,
) -> usize {
    score_block_portable(s, ids, z, out, sums, row)
}

#[inline(always)]
fn score_block_portable(
    s: &Scoring<'_>,
    ids: RowIds<'_>,
    z: &[f64],
    out: &[f64],
    sums: &mut Sums,
    row: &mut RowScratch,
) -> usize {
    let n = s.n;
    let mn = out.len() / (z.len() / n);
    let mut scored = 0;
    for (k, (zr, pred)) in z.chunks_exact(n).zip(out.chunks_exact(mn)).enumerate() {
        let r = ids.get(k);
        let (channel, bin) = (r / s.bins, r % s.bins);
        let m0 = s.mean[r];
        for (t, &zi) in row.truth.iter_mut().zip(zr) {
            *t = m0 + zi;
        }
        let outputs = pred
            .chunks_exact(n)
            .zip(sums.transformed.chunks_exact_mut(n))
            .zip(s.scored)
            .filter(|(_, on)| **on);
        for ((chunk, acc), _) in outputs {
            for ((a, &p), &t) in acc.iter_mut().zip(chunk).zip(&row.truth) {
                let d = m0 + p - t;
                *a += d * d;
            }
        }
        if s.unmeasured[r] != 0 {
            continue;
        }
        // Grazing bins count in the albedo (in the log spaces nothing is
        // recovered there, on either side) but not in the table errors.
        let grazing = s.grazing[bin];
        scored += usize::from(!grazing);
        let (c, w) = (s.cos[bin], s.weight[bin]);
        let form = s.transform.inverse_form(bin);
        // Reflectance and cosine-weighted log of the true values.
        let truth = row
            .reflectance
            .iter_mut()
            .zip(row.log.iter_mut())
            .zip(&row.truth);
        match form {
            InverseForm::Exp(sc) => {
                for ((f, l), &t) in truth {
                    *f = sc * (crate::simd::fastexp::exp(t) - 1.0).max(0.0);
                    *l = t.max(0.0);
                }
            }
            InverseForm::Linear(sc) => {
                for ((f, l), &t) in truth {
                    *f = (sc * t).max(0.0);
                    *l = log1p(*f * c);
                }
            }
        }
        if !s.log_space {
            // The log values above are t itself only in the log space.
            if let InverseForm::Exp(_) = form {
                for (l, &f) in row.log.iter_mut().zip(&row.reflectance) {
                    *l = log1p(f * c);
                }
            }
        }
        for (a, &f) in sums.truth[channel].iter_mut().zip(&row.reflectance) {
            *a += w * f;
        }
        // ln(1 + v / e) of the true values, for the log-relative error
        // ln((v' + e) / (v + e)) = ln(1 + v' / e) - ln(1 + v / e).
        let ce = c / LOG_REL_OFFSET;
        for (q, &f) in row.rel.iter_mut().zip(&row.reflectance) {
            *q = log1p(f * ce);
        }
        let per_output = pred
            .chunks_exact(n)
            .zip(sums.raw.chunks_exact_mut(n))
            .zip(sums.log.chunks_exact_mut(n))
            .zip(sums.log_rel.chunks_exact_mut(n))
            .zip(sums.albedo[channel].chunks_exact_mut(n))
            .zip(s.scored)
            .filter(|(_, on)| **on);
        for (((((chunk, ar), al), aq), aa), _) in per_output {
            // Plain loops over equal slices, one per form, so that each
            // compiles to straight-line SIMD.
            let fp = &mut row.predicted[..n];
            let lp = &mut row.predicted_log[..n];
            match form {
                InverseForm::Exp(sc) => {
                    for k in 0..n {
                        fp[k] = sc * (crate::simd::fastexp::exp(m0 + chunk[k]) - 1.0).max(0.0);
                    }
                    if s.log_space {
                        // log(1 + f c) of f = (e^t - 1) / c is t itself (for t >= 0).
                        for k in 0..n {
                            lp[k] = (m0 + chunk[k]).max(0.0);
                        }
                    } else {
                        for k in 0..n {
                            lp[k] = log1p(fp[k] * c);
                        }
                    }
                }
                InverseForm::Linear(sc) => {
                    for k in 0..n {
                        fp[k] = (sc * (m0 + chunk[k])).max(0.0);
                    }
                    for k in 0..n {
                        lp[k] = log1p(fp[k] * c);
                    }
                }
            }
            let (f, lv, rv) = (&row.reflectance[..n], &row.log[..n], &row.rel[..n]);
            let (ar, al, aq, aa) = (&mut ar[..n], &mut al[..n], &mut aq[..n], &mut aa[..n]);
            if grazing {
                for k in 0..n {
                    aa[k] += w * fp[k];
                }
                continue;
            }
            for k in 0..n {
                let e = fp[k] - f[k];
                let d = lp[k] - lv[k];
                // ln((v' + e) / (v + e)) = ln(1 + v' / e) - ln(1 + v / e).
                let q = log1p(fp[k] * ce) - rv[k];
                ar[k] += e * e;
                al[k] += d * d;
                aq[k] += q * q;
                aa[k] += w * fp[k];
            }
        }
    }
    scored
}
