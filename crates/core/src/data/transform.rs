//! Data transforms: the space in which the GPLVM sees the BRDF values.
//!
//! A transform maps each measured reflectance value (per channel and bin) to
//! the number that enters `Z`, and back. `raw` is the paper's choice (the
//! values themselves); `log` is the cosine-weighted log of Sztrajman et al.
//! 2021, `log(1 + f cos(theta_i) cos(theta_o))`, which compresses the
//! dynamic range (1e-3 .. 1e4) so that highlights do not dominate the fit;
//! `rel-log` (the default) is `log(1 + f cos_i cos_o / e)` with
//! `e = `[`REL_LOG_OFFSET`], which is `ln(v + e)` up to a constant that
//! centring removes (Nielsen et al. 2015's mapping of measured BRDFs).
//!
//! `log` is linear where `v = f cos_i cos_o` is small, and most measured
//! materials (fabrics, paints, rubbers) have `v` between 1e-3 and 1e-2
//! almost everywhere: in it they are nearly one vector beside a metal's
//! highlight, and a model cannot tell them apart. `rel-log` makes a
//! relative difference count alike from `v = e` up, so that black fabric
//! and grey fabric are as far apart as they look.

use brdf_merl::Dims;
use brdf_merl::table::{is_invalid, physical};
use serde::{Deserialize, Serialize};

use crate::simd::fastlog;

/// Which transform a store and model use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum TransformKind {
    /// The reflectance itself (1/sr); unmeasured samples read as 0.
    #[default]
    Raw,
    /// `log(1 + f cos_i cos_o)`; unmeasured samples read as 0.
    Log,
    /// `log(1 + f cos_i cos_o / e)`, `e` = [`REL_LOG_OFFSET`]; unmeasured
    /// samples read as 0.
    #[serde(rename = "rel-log")]
    RelLog,
}

/// The offset `e` of [`TransformKind::RelLog`]: values of `v = f cos_i
/// cos_o` above it are compared relatively. Nielsen et al. 2015 use 1e-3;
/// it is below nearly every measured value of the dark MERL materials
/// (black fabric's albedo is about 0.01) and above the noise of their
/// measurement.
pub const REL_LOG_OFFSET: f64 = 1e-3;

impl TransformKind {
    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            TransformKind::Raw => "raw",
            TransformKind::Log => "log",
            TransformKind::RelLog => "rel-log",
        }
    }

    /// Every kind, in the order of their store codes.
    pub const ALL: [TransformKind; 3] = [
        TransformKind::Raw,
        TransformKind::Log,
        TransformKind::RelLog,
    ];

    /// The transform and its inverse as formulas, with their constants:
    /// what a record of a reconstruction states.
    pub fn formula(self) -> &'static str {
        match self {
            TransformKind::Raw => "t = f; f = max(0, t)",
            TransformKind::Log => {
                "t = ln(1 + f c), c = cos(theta_i) cos(theta_o) at the bin's representative angles; \
                 f = max(0, (e^t - 1) / c), and f = 0 where c < 1e-6"
            }
            TransformKind::RelLog => {
                "t = ln(1 + f c / 0.001), c = cos(theta_i) cos(theta_o) at the bin's representative angles; \
                 f = max(0, 0.001 (e^t - 1) / c), and f = 0 where c < 1e-6"
            }
        }
    }

    /// Parse `raw`, `log` or `rel-log`.
    pub fn parse(s: &str) -> Option<TransformKind> {
        TransformKind::ALL.into_iter().find(|k| k.name() == s)
    }

    /// Build the transform for tables of these dims.
    pub fn build(self, dims: Dims) -> Box<dyn Transform> {
        match self {
            TransformKind::Raw => Box::new(Raw),
            TransformKind::Log => Box::new(CosineLog::new(dims)),
            TransformKind::RelLog => Box::new(CosineLog::with_offset(dims, REL_LOG_OFFSET)),
        }
    }

    /// Is the transform linear (so that albedo can be blended from weights)?
    pub fn is_linear(self) -> bool {
        matches!(self, TransformKind::Raw)
    }
}

/// A per-value transform of reflectance. `bin` is the bin inside a channel.
pub trait Transform: Send + Sync {
    /// Reflectance (or `None` where not measured) -> latent-space value.
    fn forward(&self, bin: usize, value: Option<f64>) -> f64;
    /// Latent-space value -> reflectance, clamped to `>= 0`.
    fn inverse(&self, bin: usize, t: f64) -> f64;

    /// The inverse at `bin` as a formula, so bulk code can invert without a
    /// call per value: `max(0, scale * t)` or `max(0, scale * (e^t - 1))`.
    fn inverse_form(&self, bin: usize) -> InverseForm;

    /// [`Transform::inverse`] for bins `bin0 .. bin0 + t.len()` of one
    /// channel: the same bits, without a call per value.
    fn inverse_run(&self, bin0: usize, t: &[f64], out: &mut [f64]) {
        for (k, (o, &v)) in out.iter_mut().zip(t).enumerate() {
            *o = self.inverse(bin0 + k, v);
        }
    }

    /// Transform raw file values of rows `r0 .. r0 + raw.len()` (flat
    /// channel-major indices over tables of `bins` bins a channel) into `out`,
    /// split into per-channel runs where the range straddles two channels.
    fn forward_raw_rows(&self, bins: usize, r0: usize, raw: &[f64], out: &mut [f64]) {
        let mut k = 0;
        while k < raw.len() {
            let (c, bin0) = ((r0 + k) / bins, (r0 + k) % bins);
            let len = (raw.len() - k).min(bins - bin0);
            self.forward_raw_run(c, bin0, &raw[k..k + len], &mut out[k..k + len]);
            k += len;
        }
    }

    /// Transform a run of raw MERL file values of `channel`, bins
    /// `bin0 .. bin0 + raw.len()`, into `out`: the hot loop of a store build.
    fn forward_raw_run(&self, channel: usize, bin0: usize, raw: &[f64], out: &mut [f64]) {
        for (k, (o, &v)) in out.iter_mut().zip(raw).enumerate() {
            *o = self.forward(bin0 + k, (!is_invalid(v)).then(|| physical(channel, v)));
        }
    }
}

/// The inverse transform of one bin, as a formula (see [`Transform::inverse_form`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InverseForm {
    /// `max(0, scale * t)`.
    Linear(f64),
    /// `max(0, scale * (e^t - 1))`.
    Exp(f64),
}

impl InverseForm {
    /// The value of transformed `t` before the clamp to `>= 0`: negative
    /// exactly when `t` is (both scales are positive).
    #[inline]
    pub fn unclamped(self, t: f64) -> f64 {
        match self {
            InverseForm::Linear(s) => s * t,
            InverseForm::Exp(s) => s * t.exp_m1(),
        }
    }
}

/// `cos(theta_i) cos(theta_o)` of every bin of `dims`, at its representative
/// angles, clamped at 0. The last dims' products are kept (a pass, a
/// transform and a model of the same dims each ask for them, and the
/// trigonometry of 1.46 million bins costs tens of milliseconds where a
/// copy costs a few). Computed in parallel, bin by bin: the same values
/// on any number of threads.
pub(crate) fn cosine_products(dims: Dims) -> Vec<f64> {
    use std::sync::{Arc, Mutex};
    static LAST: Mutex<Option<(Dims, Arc<[f64]>)>> = Mutex::new(None);
    let kept = LAST.lock().ok().and_then(|last| {
        last.as_ref()
            .filter(|(d, _)| *d == dims)
            .map(|(_, c)| Arc::clone(c))
    });
    if let Some(c) = kept {
        return c.to_vec();
    }
    let c: Vec<f64> = {
        use rayon::prelude::*;
        // The sines and cosines of each axis once (`HalfDiff::cosines` of
        // `Dims::angles_of`, term for term: the same bits as bin by bin).
        let angles = |b: usize| dims.angles_of(b);
        let h: Vec<(f64, f64)> = (0..dims.theta_h)
            .map(|ih| angles(dims.bin(ih, 0, 0)).theta_h.sin_cos())
            .collect();
        let d: Vec<(f64, f64)> = (0..dims.theta_d)
            .map(|id| angles(dims.bin(0, id, 0)).theta_d.sin_cos())
            .collect();
        let p: Vec<f64> = (0..dims.phi_d)
            .map(|ip| angles(dims.bin(0, 0, ip)).phi_d.cos())
            .collect();
        let mut c = vec![0.0f64; dims.bins()];
        c.par_chunks_mut(dims.theta_d * dims.phi_d)
            .zip(&h)
            .for_each(|(band, &(sh, ch))| {
                for (row, &(sd, cd)) in band.chunks_exact_mut(dims.phi_d).zip(&d) {
                    for (o, &cp) in row.iter_mut().zip(&p) {
                        let x = sd * cp * sh;
                        *o = ((cd * ch - x) * (cd * ch + x)).max(0.0);
                    }
                }
            });
        c
    };
    let c: Arc<[f64]> = c.into();
    if let Ok(mut last) = LAST.lock() {
        *last = Some((dims, Arc::clone(&c)));
    }
    c.to_vec()
}

/// The identity on reflectance.
pub struct Raw;

impl Transform for Raw {
    #[inline]
    fn forward(&self, _bin: usize, value: Option<f64>) -> f64 {
        value.unwrap_or(0.0)
    }
    #[inline]
    fn inverse(&self, _bin: usize, t: f64) -> f64 {
        t.max(0.0)
    }

    fn inverse_form(&self, _bin: usize) -> InverseForm {
        InverseForm::Linear(1.0)
    }

    fn inverse_run(&self, _bin0: usize, t: &[f64], out: &mut [f64]) {
        for (o, &v) in out.iter_mut().zip(t) {
            *o = v.max(0.0);
        }
    }

    fn forward_raw_run(&self, channel: usize, _bin0: usize, raw: &[f64], out: &mut [f64]) {
        let scale = physical(channel, 1.0);
        for (o, &v) in out.iter_mut().zip(raw) {
            *o = if is_invalid(v) { 0.0 } else { v * scale };
        }
    }
}

/// `log(1 + f cos_i cos_o / e)` with the cosines of each bin's
/// representative angles: `e = 1` is [`TransformKind::Log`], `e =`
/// [`REL_LOG_OFFSET`] is [`TransformKind::RelLog`].
pub struct CosineLog {
    /// `cos_i cos_o / e` of every bin.
    cos: Vec<f64>,
    /// [`MIN_COS`]` / e`: below it a bin is grazing.
    min: f64,
}

/// Below this cosine product a bin is treated as grazing: nothing is recovered there.
const MIN_COS: f64 = 1e-6;

impl CosineLog {
    /// Precompute `cos_i cos_o` (clamped at 0) for every bin of `dims`.
    pub fn new(dims: Dims) -> CosineLog {
        CosineLog::with_offset(dims, 1.0)
    }

    /// `log(1 + f cos_i cos_o / offset)`: `cos_i cos_o / offset` for every bin.
    pub fn with_offset(dims: Dims, offset: f64) -> CosineLog {
        let cos = cosine_products(dims)
            .into_iter()
            .map(|c| c / offset)
            .collect();
        CosineLog {
            cos,
            min: MIN_COS / offset,
        }
    }
}

impl Transform for CosineLog {
    #[inline]
    fn forward(&self, bin: usize, value: Option<f64>) -> f64 {
        value.map_or(0.0, |f| fastlog::log1p(f.max(0.0) * self.cos[bin]))
    }
    #[inline]
    fn inverse(&self, bin: usize, t: f64) -> f64 {
        let c = self.cos[bin];
        if c < self.min {
            0.0
        } else {
            (t.exp_m1() / c).max(0.0)
        }
    }

    fn inverse_form(&self, bin: usize) -> InverseForm {
        let c = self.cos[bin];
        InverseForm::Exp(if c < self.min { 0.0 } else { 1.0 / c })
    }

    /// Branch-free: an unmeasured (negative) raw value clamps to 0, and
    /// `log1p(0) = 0` is what [`Transform::forward`] gives it.
    fn forward_raw_run(&self, channel: usize, bin0: usize, raw: &[f64], out: &mut [f64]) {
        let scale = physical(channel, 1.0);
        let cos = &self.cos[bin0..bin0 + raw.len()];
        #[cfg(target_arch = "x86_64")]
        if crate::simd::has_avx512f() {
            // SAFETY: the CPU has AVX-512F (checked just above).
            return unsafe { cosine_log_avx512(scale, raw, cos, out) };
        }
        #[cfg(target_arch = "x86_64")]
        if crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX2 and FMA (checked just above).
            return unsafe { cosine_log_avx2(scale, raw, cos, out) };
        }
        cosine_log(scale, raw, cos, out)
    }

    fn inverse_run(&self, bin0: usize, t: &[f64], out: &mut [f64]) {
        let cos = &self.cos[bin0..bin0 + t.len()];
        for ((o, &v), &c) in out.iter_mut().zip(t).zip(cos) {
            *o = if c < self.min {
                0.0
            } else {
                (v.exp_m1() / c).max(0.0)
            };
        }
    }
}

/// The loop of [`CosineLog::forward_raw_run`]: plain arithmetic and
/// [`fastlog::log1p`], which [`cosine_log_avx2`] and [`cosine_log_avx512`]
/// match bit for bit.
#[inline(always)]
fn cosine_log(scale: f64, raw: &[f64], cos: &[f64], out: &mut [f64]) {
    for ((o, &v), &c) in out.iter_mut().zip(raw).zip(cos) {
        *o = fastlog::log1p((v * scale).max(0.0) * c);
    }
}

/// [`cosine_log`] 4 values at a time with [`fastlog::log1p_avx2`] (its
/// table lookups are gathers, which the compiler would not emit itself).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn cosine_log_avx2(scale: f64, raw: &[f64], cos: &[f64], out: &mut [f64]) {
    use std::arch::x86_64::*;
    let n = out.len().min(raw.len()).min(cos.len());
    let split = n / 4 * 4;
    for ((o, v), c) in out[..split]
        .chunks_exact_mut(4)
        .zip(raw[..split].chunks_exact(4))
        .zip(cos[..split].chunks_exact(4))
    {
        // SAFETY: each chunk is exactly 4 elements; AVX2 and FMA by the caller.
        // max(NaN, 0) = 0 as in `f64::max`; the sign of a zero does not reach log1p's result.
        unsafe {
            let v = _mm256_mul_pd(_mm256_loadu_pd(v.as_ptr()), _mm256_set1_pd(scale));
            let x = _mm256_mul_pd(
                _mm256_max_pd(v, _mm256_setzero_pd()),
                _mm256_loadu_pd(c.as_ptr()),
            );
            _mm256_storeu_pd(o.as_mut_ptr(), fastlog::log1p_avx2(x));
        }
    }
    cosine_log(scale, &raw[split..n], &cos[split..n], &mut out[split..n]);
}

/// [`cosine_log`] 8 values at a time with [`fastlog::log1p_avx512`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn cosine_log_avx512(scale: f64, raw: &[f64], cos: &[f64], out: &mut [f64]) {
    use std::arch::x86_64::*;
    let n = out.len().min(raw.len()).min(cos.len());
    let split = n / 8 * 8;
    for ((o, v), c) in out[..split]
        .chunks_exact_mut(8)
        .zip(raw[..split].chunks_exact(8))
        .zip(cos[..split].chunks_exact(8))
    {
        // SAFETY: each chunk is exactly 8 elements; AVX-512F by the caller.
        // max(NaN, 0) = 0 as in `f64::max` (the NaN is the first operand);
        // the sign of a zero does not reach log1p's result.
        unsafe {
            let v = _mm512_mul_pd(_mm512_loadu_pd(v.as_ptr()), _mm512_set1_pd(scale));
            let x = _mm512_mul_pd(
                _mm512_max_pd(v, _mm512_setzero_pd()),
                _mm512_loadu_pd(c.as_ptr()),
            );
            _mm512_storeu_pd(o.as_mut_ptr(), fastlog::log1p_avx512(x));
        }
    }
    cosine_log(scale, &raw[split..n], &cos[split..n], &mut out[split..n]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_products_are_those_of_each_bin_s_angles_bit_for_bit() {
        for (h, d, p) in [(90, 90, 180), (7, 5, 12), (1, 1, 1)] {
            let dims = Dims::new(h, d, p).unwrap();
            let by_bin: Vec<f64> = (0..dims.bins())
                .map(|b| {
                    let (ci, co) = dims.angles_of(b).cosines();
                    (ci * co).max(0.0)
                })
                .collect();
            let got = cosine_products(dims);
            assert!(
                got.iter()
                    .zip(&by_bin)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{dims}"
            );
        }
    }

    #[test]
    fn forward_runs_match_forward_per_value() {
        let dims = Dims::new(10, 10, 20).unwrap();
        let raw: Vec<f64> = (0..dims.bins())
            .map(|b| {
                if b % 7 == 0 {
                    -1.0
                } else {
                    (b as f64 * 0.91).sin().abs() * 3000.0
                }
            })
            .collect();
        for kind in TransformKind::ALL {
            let t = kind.build(dims);
            for channel in 0..3 {
                let mut run = vec![0.0; dims.bins() - 5];
                t.forward_raw_run(channel, 5, &raw[5..], &mut run);
                for (k, v) in run.iter().enumerate() {
                    let bin = 5 + k;
                    let value = (!is_invalid(raw[bin])).then(|| physical(channel, raw[bin]));
                    assert_eq!(
                        v.to_bits(),
                        t.forward(bin, value).to_bits(),
                        "{kind:?} {bin}"
                    );
                }
            }
        }
    }

    #[test]
    fn inverse_run_is_inverse_per_value() {
        let dims = Dims::new(10, 10, 20).unwrap();
        let t_values: Vec<f64> = (0..dims.bins())
            .map(|b| (b as f64 * 0.37).sin() * 3.0)
            .collect();
        for kind in TransformKind::ALL {
            let t = kind.build(dims);
            let mut run = vec![0.0; dims.bins() - 13];
            t.inverse_run(13, &t_values[13..], &mut run);
            for (k, v) in run.iter().enumerate() {
                let bin = 13 + k;
                assert_eq!(
                    v.to_bits(),
                    t.inverse(bin, t_values[bin]).to_bits(),
                    "{kind:?} {bin}"
                );
            }
        }
    }

    #[test]
    fn transforms_invert() {
        let dims = Dims::new(10, 10, 20).unwrap();
        for kind in TransformKind::ALL {
            let t = kind.build(dims);
            for bin in [0, 37, 555, 1999] {
                let (ci, co) = dims.angles_of(bin).cosines();
                if ci * co < MIN_COS {
                    continue;
                }
                for f in [0.0, 1e-3, 0.5, 12.0, 1e4] {
                    let back = t.inverse(bin, t.forward(bin, Some(f)));
                    assert!(
                        (back - f).abs() <= 1e-12 * f.max(1.0),
                        "{kind:?} bin {bin}: {f} -> {back}"
                    );
                }
                assert_eq!(t.forward(bin, None), 0.0);
                for tv in [-0.3, 0.0, 0.7, 4.0] {
                    let via_form = match t.inverse_form(bin) {
                        InverseForm::Linear(s) => (s * tv).max(0.0),
                        InverseForm::Exp(s) => (s * tv.exp_m1()).max(0.0),
                    };
                    assert!((via_form - t.inverse(bin, tv)).abs() <= 1e-14 * via_form.max(1.0));
                }
                assert_eq!(t.inverse(bin, -5.0), 0.0);
            }
        }
    }
}
