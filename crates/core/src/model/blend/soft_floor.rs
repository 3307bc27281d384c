//! The value of [`crate::BlendRule::Floor`]: the GP's blend, lifted softly
//! onto a floor under the convex blend, value by value.
//!
//! Row by row (one channel of one bin), `g` is the GP's blend `mean + w . z`
//! and `c` the convex blend `mean + v . z` in transformed space (`v` the
//! kernel's convex weights, [`crate::model::blend::plausible_budget::convex_weights`]). Both
//! transforms send reflectance `f >= 0` to values `>= 0`, so `c >= 0`: a
//! convex blend of materials is a material. The rule's value is
//!
//! ```text
//! c h(g / c),   h(r) = s + d ln(1 + e^((r - s) / d))
//! ```
//!
//! with the share `s` ([`FLOOR_SHARE`]) and softness `d`
//! ([`FLOOR_SOFTNESS`]). `h` is a smooth maximum of `r` and `s`: it is
//! above both, and within `d e^(-(r - s) / d)` of `r` once `r > s`. So a
//! value the GP puts well above `s c` is kept (at `g = c`, the most common
//! case, it moves by `d e^(-(1 - s) / d)`: 0.6% of it), and a value the GP
//! drives towards or below zero is lifted to at least `s` times the convex
//! blend's, never clamped. The weights move only where a value needs it, and
//! each value's move depends on the two blends at that row alone: no pass
//! over the store, and the rule is as cheap as the GP's blend twice.

use crate::simd::fastexp::exp;
use crate::simd::fastlog::log1p;

/// The floor's share `s` of the convex blend: the rule keeps every value
/// at or above `s` times the convex blend's. With the softness below, 0.3
/// gave the least leave-one-out error of 0.1, 0.2 and 0.3 on the 100
/// NBRDF-derived materials, 2.2% below the GP's (docs/plausibility.md).
pub const FLOOR_SHARE: f64 = 0.3;

/// The floor's softness `d`, in units of the convex blend's value: the
/// width of the bend between the GP's value and the floor.
pub const FLOOR_SOFTNESS: f64 = 0.05;

/// The rule's value of a row from its GP value `g` and convex value `c`
/// (transformed space), with [`FLOOR_SHARE`] and [`FLOOR_SOFTNESS`].
#[inline(always)]
pub fn soft_floor(g: f64, c: f64) -> f64 {
    soft_floor_with(g, c, FLOOR_SHARE, FLOOR_SOFTNESS)
}

/// [`soft_floor`] with share `s` and softness `d`. Where the convex value
/// is not positive (no material reflects anything there, or rounding left
/// it a hair below zero) the GP's value is kept, clamped at 0.
///
/// `ln(1 + e^u)` is formed as `max(u, 0) + ln(1 + e^-|u|)` with the crate's
/// vectorisable `exp` and `log1p` (within a few ulp of `std`'s): the same
/// bits in every path, and loops over rows ([`floor_rows`]) compile to SIMD.
#[inline(always)]
pub fn soft_floor_with(g: f64, c: f64, s: f64, d: f64) -> f64 {
    let u = (g / c - s) / d;
    let softplus = u.max(0.0) + log1p(exp(-u.abs()));
    let lifted = c * (s + d * softplus);
    // A select, not a branch: a zero convex value makes `u` infinite or NaN,
    // and its lane is replaced here.
    if c > 0.0 { lifted } else { g.max(0.0) }
}

/// The rule's value of a row: [`soft_floor`] of the GP value `g` and the
/// convex value `c`, capped at `cap` (transformed space; see [`reach_cap`]).
/// The cap is at or above `c`, so the floor stays under it, and a material
/// at its own point, where `c` is that material, is left as it is.
#[inline(always)]
pub fn floor_capped(g: f64, c: f64, cap: f64) -> f64 {
    soft_floor(g, c).min(cap)
}

/// The cap of a row whose convex value is `c` and brightest material's
/// value `top` (transformed space; every transform is increasing, so `top`
/// is the most any material reflects there), at reach `r` in `[0, 1]`:
/// `c + r (top - c)`. At reach 1 it is the brightest material's value, which
/// only values the GP drives above every material meet (it extrapolates so
/// beyond the materials' box); a smaller reach, near materials bright at
/// grazing incidence, keeps the material's directional albedo under 1
/// ([`crate::data::store::EnergyBound`] says why and how far).
#[inline(always)]
pub fn reach_cap(c: f64, top: f64, r: f64) -> f64 {
    c + r * (top - c)
}

/// The largest of a row's centred values (f32 or f64, as the store holds
/// them): [`floor_capped`]'s `top` less the mean; minus infinity for none.
/// Eight running maxima, so that the loop vectorises rather than waiting on
/// one chain of comparisons (it was a third of a reconstruction's time); a
/// maximum is exact, so the order does not change the result.
#[inline(always)]
pub(crate) fn top_of<T: Copy + PartialOrd + Into<f64>>(z: &[T]) -> f64 {
    let Some(&first) = z.first() else {
        return f64::NEG_INFINITY;
    };
    let mut acc = [first; 8];
    let mut chunks = z.chunks_exact(8);
    for c in &mut chunks {
        for (a, &v) in acc.iter_mut().zip(c) {
            if v > *a {
                *a = v;
            }
        }
    }
    let mut top = acc[0];
    for &v in acc[1..].iter().chain(chunks.remainder()) {
        if v > top {
            top = v;
        }
    }
    top.into()
}

/// `out[k] = mean[k] + top_of(row k of z)` for rows of `n` values each: the
/// caps of a run of store rows, in code compiled for AVX2 where the CPU
/// has it.
pub(crate) fn caps<T: Copy + PartialOrd + Into<f64>>(
    z: &[T],
    n: usize,
    mean: &[f64],
    out: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::has_avx512f() {
            // SAFETY: the CPU has AVX-512F (checked just above).
            return unsafe { caps_avx512(z, n, mean, out) };
        }
        if crate::simd::has_avx2() {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { caps_avx2(z, n, mean, out) };
        }
    }
    caps_portable(z, n, mean, out);
}

/// [`caps`] in AVX-512 code (a maximum is exact: the same values).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2")]
fn caps_avx512<T: Copy + PartialOrd + Into<f64>>(z: &[T], n: usize, mean: &[f64], out: &mut [f64]) {
    caps_portable(z, n, mean, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn caps_avx2<T: Copy + PartialOrd + Into<f64>>(z: &[T], n: usize, mean: &[f64], out: &mut [f64]) {
    caps_portable(z, n, mean, out);
}

#[inline(always)]
fn caps_portable<T: Copy + PartialOrd + Into<f64>>(
    z: &[T],
    n: usize,
    mean: &[f64],
    out: &mut [f64],
) {
    for ((o, &m), row) in out.iter_mut().zip(mean).zip(z.chunks_exact(n)) {
        *o = m + top_of(row);
    }
}

/// Every value of `g` on its soft floor and under its cap, in place, all
/// three in transformed space as they are (not centred): row `k` has GP
/// value `g[k]`, convex value `c[k]` and cap `top[k]` ([`floor_capped`],
/// the cap already [`reach_cap`]'s;
/// a reconstruction's rows). The same bits as [`floor_capped`] value by
/// value, in code compiled for FMA where the CPU has it (the crate's `exp`
/// and `log1p` use fused multiply-adds, which are calls to a software
/// routine otherwise).
pub(crate) fn floor_values(g: &mut [f64], c: &[f64], top: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::has_avx512f() && crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked just above).
            return unsafe { floor_values_avx512(g, c, top) };
        }
        if crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX2 and FMA (checked just above).
            return unsafe { floor_values_fma(g, c, top) };
        }
    }
    floor_values_portable(g, c, top);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn floor_values_fma(g: &mut [f64], c: &[f64], top: &[f64]) {
    floor_values_portable(g, c, top);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn floor_values_avx512(g: &mut [f64], c: &[f64], top: &[f64]) {
    floor_values_portable(g, c, top);
}

#[inline(always)]
fn floor_values_portable(g: &mut [f64], c: &[f64], top: &[f64]) {
    for ((g, &c), &u) in g.iter_mut().zip(c).zip(top) {
        *g = floor_capped(*g, c, u);
    }
}

/// Every value of `t` on its soft floor and under its cap, in place: row
/// `k` has mean `mean[k]`, GP value `mean[k] + t[k]`, convex value
/// `mean[k] + c[k]`, brightest value `mean[k] + top[k]` and reach `r[k]`
/// ([`reach_cap`]; the map's per-pixel rule: one row a quadrature bin).
pub(crate) fn floor_rows(t: &mut [f64], c: &[f64], mean: &[f64], top: &[f64], r: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::has_avx512f() && crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked just above).
            return unsafe { floor_rows_avx512(t, c, mean, top, r) };
        }
        if crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX2 and FMA (checked just above).
            return unsafe { floor_rows_fma(t, c, mean, top, r) };
        }
    }
    floor_rows_portable(t, c, mean, top, r);
}

/// [`floor_rows`] in eight lanes (the per-pixel map's floor); the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn floor_rows_avx512(t: &mut [f64], c: &[f64], mean: &[f64], top: &[f64], r: &[f64]) {
    floor_rows_portable(t, c, mean, top, r);
}

/// [`floor_rows`] with one mean and brightest value for every value, and a
/// reach for each (the exact pass: one store row at many points).
pub(crate) fn floor_points(t: &mut [f64], c: &[f64], mean: f64, top: f64, r: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        if crate::simd::has_avx512f() && crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked just above).
            return unsafe { floor_points_avx512(t, c, mean, top, r) };
        }
        if crate::simd::has_avx2_fma() {
            // SAFETY: the CPU has AVX2 and FMA (checked just above).
            return unsafe { floor_points_fma(t, c, mean, top, r) };
        }
    }
    floor_points_portable(t, c, mean, top, r);
}

/// [`floor_points`] in eight lanes (the exact pass's floor is as costly as
/// its products); the same bits as the other paths.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn floor_points_avx512(t: &mut [f64], c: &[f64], mean: f64, top: f64, r: &[f64]) {
    floor_points_portable(t, c, mean, top, r);
}

/// [`floor_points`] with a brightest value for each value (leave-one-out:
/// each material's is the brightest of the others').
pub(crate) fn floor_points_each(t: &mut [f64], c: &[f64], mean: f64, top: &[f64], r: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::has_avx2_fma() {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        return unsafe { floor_points_each_fma(t, c, mean, top, r) };
    }
    floor_points_each_portable(t, c, mean, top, r);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn floor_points_each_fma(t: &mut [f64], c: &[f64], mean: f64, top: &[f64], r: &[f64]) {
    floor_points_each_portable(t, c, mean, top, r);
}

#[inline(always)]
fn floor_points_each_portable(t: &mut [f64], c: &[f64], m: f64, top: &[f64], r: &[f64]) {
    for (((t, &c), &u), &r) in t.iter_mut().zip(c).zip(top).zip(r) {
        *t = floor_capped(m + *t, m + c, m + reach_cap(c, u, r)) - m;
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn floor_rows_fma(t: &mut [f64], c: &[f64], mean: &[f64], top: &[f64], r: &[f64]) {
    floor_rows_portable(t, c, mean, top, r);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn floor_points_fma(t: &mut [f64], c: &[f64], mean: f64, top: f64, r: &[f64]) {
    floor_points_portable(t, c, mean, top, r);
}

#[inline(always)]
fn floor_rows_portable(t: &mut [f64], c: &[f64], mean: &[f64], top: &[f64], r: &[f64]) {
    for ((((t, &c), &m), &u), &r) in t.iter_mut().zip(c).zip(mean).zip(top).zip(r) {
        *t = floor_capped(m + *t, m + c, m + reach_cap(c, u, r)) - m;
    }
}

#[inline(always)]
fn floor_points_portable(t: &mut [f64], c: &[f64], m: f64, top: f64, r: &[f64]) {
    for ((t, &c), &r) in t.iter_mut().zip(c).zip(r) {
        *t = floor_capped(m + *t, m + c, m + reach_cap(c, top, r)) - m;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_floor_is_above_both_the_gp_and_the_share() {
        for &c in &[1e-6, 0.01, 0.7, 3.0, 9.5] {
            for k in -400..=400 {
                let g = c * k as f64 / 40.0;
                let y = soft_floor(g, c);
                // Above g, to rounding.
                assert!(y >= g - 4.0 * f64::EPSILON * g.abs(), "g {g} c {c}: {y}");
                assert!(y >= FLOOR_SHARE * c, "g {g} c {c}: {y}");
                // Never more than the larger of the two by more than d ln 2.
                let hi = g.max(FLOOR_SHARE * c) + FLOOR_SOFTNESS * c * 2f64.ln();
                assert!(y <= hi * (1.0 + 1e-12), "g {g} c {c}: {y} > {hi}");
            }
        }
    }

    #[test]
    fn a_value_well_above_the_floor_is_kept() {
        // At g = c the move is d ln(1 + e^-u), u = (1 - s) / d: below
        // d e^-u, 0.6% of the value.
        let c = 2.0;
        let u = (1.0 - FLOOR_SHARE) / FLOOR_SOFTNESS;
        let want = FLOOR_SOFTNESS * (-u).exp().ln_1p();
        let got = soft_floor(c, c) / c - 1.0;
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        assert!(got < FLOOR_SOFTNESS * (-u).exp() && got < 0.006, "{got}");
        // Ten times the convex value: unchanged to rounding.
        assert_eq!(soft_floor(10.0 * c, c), 10.0 * c);
    }

    #[test]
    fn the_floor_rises_with_the_gp_and_is_smooth() {
        let c = 1.3;
        let (mut prev, mut prev_slope) = (f64::NEG_INFINITY, 0.0);
        let h = 1e-4;
        for k in -3000..3000 {
            let g = k as f64 * 1e-3;
            let y = soft_floor(g, c);
            // Strictly where the bend is more than rounding above the
            // floor's share, never falling anywhere.
            if g / c > FLOOR_SHARE - 30.0 * FLOOR_SOFTNESS {
                assert!(y > prev, "not increasing at {g}");
            } else {
                assert!(y >= prev && y >= FLOOR_SHARE * c, "falling at {g}");
            }
            prev = y;
            // The slope is the logistic function of u: in (0, 1), and it
            // changes by at most h / (4 d c) per step h (the second
            // derivative's bound).
            let slope = (soft_floor(g + h, c) - soft_floor(g - h, c)) / (2.0 * h);
            assert!((0.0..=1.0 + 1e-6).contains(&slope), "{slope} at {g}");
            if k > -3000 {
                let bound = 1e-3 / (4.0 * FLOOR_SOFTNESS * c) + 1e-6;
                assert!((slope - prev_slope).abs() <= bound, "kink at {g}");
            }
            prev_slope = slope;
        }
    }

    #[test]
    fn the_cap_changes_only_values_above_the_brightest_material() {
        let (c, top) = (0.8, 2.0);
        for k in -100..=300 {
            let g = k as f64 / 50.0;
            let y = floor_capped(g, c, top);
            assert!(y <= top && y >= FLOOR_SHARE * c, "{g}: {y}");
            if soft_floor(g, c) <= top {
                assert_eq!(y, soft_floor(g, c));
            } else {
                assert_eq!(y, top);
            }
        }
        assert_eq!(top_of(&[0.1, -3.0, 0.7, 0.2]), 0.7);
        // Against a plain fold, for every length around the eight lanes,
        // f32 and f64.
        let mut rng = brdf_merl::synth::SplitMix64::new(5);
        for len in 0..40 {
            let z: Vec<f64> = (0..len).map(|_| rng.range(-5.0, 5.0)).collect();
            let want = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(top_of(&z), want, "{len}");
            let z32: Vec<f32> = z.iter().map(|&v| v as f32).collect();
            let want = z32
                .iter()
                .fold(f64::NEG_INFINITY, |a, &b| a.max(f64::from(b)));
            assert_eq!(top_of(&z32), want, "{len}");
        }
        // The caps of a run of rows.
        let (n, rows) = (7, 9);
        let z: Vec<f32> = (0..n * rows).map(|_| rng.range(-5.0, 5.0) as f32).collect();
        let mean: Vec<f64> = (0..rows).map(|_| rng.range(0.0, 1.0)).collect();
        let mut out = vec![0.0; rows];
        caps(&z, n, &mean, &mut out);
        for k in 0..rows {
            assert_eq!(out[k], mean[k] + top_of(&z[k * n..(k + 1) * n]));
        }
        // The in-place rule is floor_capped value by value.
        let g: Vec<f64> = (0..50).map(|_| rng.range(-1.0, 4.0)).collect();
        let c: Vec<f64> = (0..50).map(|_| rng.range(0.0, 2.0)).collect();
        let top: Vec<f64> = (0..50).map(|_| rng.range(1.0, 3.0)).collect();
        let mut out = g.clone();
        floor_values(&mut out, &c, &top);
        for k in 0..50 {
            assert_eq!(out[k].to_bits(), floor_capped(g[k], c[k], top[k]).to_bits());
        }
        // The exact pass's rule (one mean and brightest value, a reach a
        // value) is floor_capped value by value, on whichever path the CPU
        // takes (eight lanes, four, or one).
        let (m, u) = (0.3, 2.5);
        let r: Vec<f64> = (0..50).map(|_| rng.range(0.0, 1.0)).collect();
        let mut out = g.clone();
        floor_points(&mut out, &c, m, u, &r);
        for k in 0..50 {
            let want = floor_capped(m + g[k], m + c[k], m + reach_cap(c[k], u, r[k])) - m;
            assert_eq!(out[k].to_bits(), want.to_bits(), "{k}");
        }
    }

    #[test]
    fn no_convex_value_keeps_the_gp_clamped() {
        assert_eq!(soft_floor(0.5, 0.0), 0.5);
        assert_eq!(soft_floor(-0.5, 0.0), 0.0);
        assert_eq!(soft_floor(-0.5, -1e-9), 0.0);
        assert_eq!(soft_floor(0.25, f64::NAN), 0.25);
    }
}
