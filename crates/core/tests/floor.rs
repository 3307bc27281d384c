//! The soft-floor blend rule (`BlendRule::Floor`) against a dense
//! recomputation from the stored rows: its values, its plausibility, and
//! its held-out errors.

mod common;

use brdf_atlas_core::TransformKind;
use brdf_atlas_core::floor::{FLOOR_SHARE, FLOOR_SOFTNESS};
use brdf_atlas_core::loo::{self, CONVEX_LENGTH_RATIO};
use brdf_atlas_core::{BlendRule, Model, NoProgress};
use common::{DIMS, POINTS, fit};

/// The rule written out: `c (s + d ln(1 + e^((g / c - s) / d)))`.
fn floor(g: f64, c: f64) -> f64 {
    if c <= 0.0 {
        return g.max(0.0);
    }
    let u = (g / c - FLOOR_SHARE) / FLOOR_SOFTNESS;
    // ln(1 + e^u), written as u + ln(1 + e^-u) where e^u would overflow.
    let softplus = if u < 30.0 {
        (1.0 + u.exp()).ln()
    } else {
        u + (-u).exp().ln_1p()
    };
    c * (FLOOR_SHARE + FLOOR_SOFTNESS * softplus)
}

/// The convex weights at `x`: Gaussians of width `CONVEX_LENGTH_RATIO l`
/// over the squared distance, normalised (a material's own point: it alone).
fn convex(m: &Model, x: &[f64; 2]) -> Vec<f64> {
    let l = m.file().kernel.length_scale * CONVEX_LENGTH_RATIO;
    let lat = m.latent();
    let d2: Vec<f64> = (0..lat.nrows())
        .map(|i| (lat[(i, 0)] - x[0]).powi(2) + (lat[(i, 1)] - x[1]).powi(2))
        .collect();
    if let Some(i) = d2.iter().position(|&d| d == 0.0) {
        return (0..d2.len()).map(|j| f64::from(u8::from(j == i))).collect();
    }
    let k: Vec<f64> = d2.iter().map(|&d| (-d / (2.0 * l * l)).exp() / d).collect();
    let sum: f64 = k.iter().sum();
    k.iter().map(|v| v / sum).collect()
}

/// A value in transformed space back to reflectance, before any clamp.
fn inverse(kind: TransformKind, bin: usize, v: f64) -> f64 {
    let (ci, co) = DIMS.angles_of(bin).cosines();
    let c = (ci * co).max(0.0);
    match kind {
        TransformKind::Raw => v,
        TransformKind::Log | TransformKind::RelLog if c < 1e-6 => 0.0,
        TransformKind::Log => v.exp_m1() / c,
        TransformKind::RelLog => 1e-3 * v.exp_m1() / c,
    }
}

#[test]
fn values_equal_a_dense_recomputation_and_are_never_clamped() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in TransformKind::ALL {
        let m = Model::open(fit(tmp.path(), 12, transform)).unwrap();
        let store = m.store();
        let (n, bins) = (store.n(), DIMS.bins());
        let mut z = vec![0.0; n];
        let (mut gp_clamped, mut lifted, mut kept, mut capped) = (0, 0, 0, 0);
        for x in POINTS {
            let gp = m.at(&x).unwrap();
            let b = m.at_with(&x, BlendRule::Floor).unwrap();
            let v = convex(&m, &x);
            let got_v = b
                .floor()
                .expect("the floor rule records its convex weights");
            for (a, w) in got_v.iter().zip(&v) {
                assert!((a - w).abs() <= 1e-12, "{x:?}: convex {got_v:?} vs {v:?}");
            }
            let table = b.table().unwrap();
            for row in 0..store.rows() {
                if store.unmeasured()[row] != 0 {
                    continue;
                }
                store.copy_rows(row, &mut z);
                let blend = |w: &[f64]| {
                    store.mean()[row] + w.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>()
                };
                let (g, c) = (blend(gp.gp_weights()), blend(&v));
                // The floor, capped at the brightest material's value.
                let top = store.mean()[row] + z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let lifted_value = floor(g, c);
                let want = lifted_value.min(top);
                assert!(top >= c - 1e-12 * c.abs() && want >= FLOOR_SHARE * c.min(top));
                capped += usize::from(lifted_value > top);
                let (ch, bin) = (row / bins, row % bins);
                let tol = 1e-9 * want.abs().max(1e-9);
                assert!(
                    (b.transformed(row) - want).abs() <= tol,
                    "{transform:?} {x:?} row {row}: {} vs {want}",
                    b.transformed(row)
                );
                let f = inverse(transform, bin, want);
                assert!(f >= 0.0, "{transform:?} {x:?} row {row}: {f}");
                let value = b.value(ch, bin).unwrap();
                assert!(
                    (value - f).abs() <= 1e-9 * f.abs().max(1e-9),
                    "{value} vs {f}"
                );
                let from_table = table.value(ch, bin).unwrap();
                assert!(
                    (from_table - f).abs() <= 1e-6 * f.abs().max(1e-6),
                    "{from_table} vs {f}"
                );
                gp_clamped += usize::from(g < 0.0);
                if lifted_value > top {
                    // The GP above every material: capped there.
                    assert_eq!(want, top);
                } else if c <= 0.0 {
                    // No material reflects anything here: the GP's value, clamped.
                    assert_eq!(want, g.max(0.0));
                } else if g < FLOOR_SHARE * c {
                    lifted += 1;
                    assert!(want >= FLOOR_SHARE * c);
                } else {
                    // Above the floor a value moves up by at most
                    // c d e^-u, u = (g / c - s) / d: the GP's is kept.
                    let u = (g / c - FLOOR_SHARE) / FLOOR_SOFTNESS;
                    let bound = c * FLOOR_SOFTNESS * (-u).exp();
                    assert!(
                        want >= g - 1e-14 * g.abs() && want - g <= bound * (1.0 + 1e-9) + 1e-14 * g,
                        "{g} moved to {want}, c {c} u {u}"
                    );
                    kept += usize::from(u > 5.0);
                }
            }
            let p = b.plausibility().unwrap();
            assert_eq!(p.clamped_reflectance, 0.0, "{transform:?} {x:?}: {p:?}");
            assert_eq!(p.clamped_values, 0.0, "{transform:?} {x:?}: {p:?}");
        }
        // In `rel-log` values sit far above 0 (ln(1 + v / 0.001)), and the
        // GP's blend undershoots without going negative.
        assert!(
            gp_clamped > 0 || transform == TransformKind::RelLog,
            "{transform:?}: the GP never goes negative here"
        );
        assert!(
            (lifted > 0 || transform == TransformKind::RelLog) && kept > 0,
            "{transform:?}: lifted {lifted}, kept {kept}"
        );
        // Some of these points lie beyond the materials, where the GP
        // overshoots the brightest of them.
        assert!(capped > 0, "{transform:?}: nothing capped");
    }
}

#[test]
fn held_out_errors_equal_a_dense_recomputation() {
    let tmp = tempfile::tempdir().unwrap();
    let m = Model::open(fit(tmp.path(), 10, TransformKind::Log)).unwrap();
    let (kernel, latent) = (m.file().kernel, m.latent().as_ref());
    let gp = loo::gp_predictor(&kernel, latent, true).unwrap();
    let cv = loo::convex_predictor(&kernel, latent).unwrap();
    let mix = loo::Mix {
        from: 0,
        towards: 1,
        how: loo::Mixing::Floor,
    };
    let ev =
        loo::evaluate_mixed(m.store(), &[gp.clone(), cv.clone()], &[mix], &NoProgress).unwrap();
    let store = m.store();
    let (n, bins) = (store.n(), DIMS.bins());
    let mut z = vec![0.0; n];
    let mut sums = vec![0.0; n];
    let mut scored = 0;
    for row in 0..store.rows() {
        let bin = row % bins;
        let (ci, co) = DIMS.angles_of(bin).cosines();
        if store.unmeasured()[row] != 0 || (ci * co).max(0.0) < 1e-6 {
            continue;
        }
        scored += 1;
        store.copy_rows(row, &mut z);
        let mean = store.mean()[row];
        for (i, s) in sums.iter_mut().enumerate() {
            let predict = |p: &faer::Mat<f64>| mean + (0..n).map(|j| p[(i, j)] * z[j]).sum::<f64>();
            // Capped at the brightest of the other materials.
            let top = (0..n)
                .filter(|&j| j != i)
                .map(|j| z[j])
                .fold(f64::NEG_INFINITY, f64::max);
            let y = floor(predict(&gp), predict(&cv)).min(mean + top);
            // ln(1 + f c) of the log transform's value is the value itself.
            let d = y.max(0.0) - (mean + z[i]).max(0.0);
            *s += d * d;
        }
    }
    assert_eq!(ev.scored_rows, scored);
    let got = &ev.errors[2].log;
    for i in 0..n {
        assert!(
            (got[i] - sums[i]).abs() <= 1e-9 * sums[i].max(1e-12),
            "material {i}: {} vs {}",
            got[i],
            sums[i]
        );
    }
    // The floor moved some held-out predictions: it is not the GP's.
    assert!((0..n).any(|i| (got[i] - ev.errors[0].log[i]).abs() > 1e-9 * got[i]));
}

/// The dense rule over a blend's clamped values.
fn dense_albedo(m: &Model, b: &brdf_atlas_core::Blend<'_>) -> [f64; 3] {
    m.albedo_rule()
        .integrate(|bin| [0, 1, 2].map(|c| b.value(c, bin).unwrap_or(0.0)))
}

#[test]
fn exact_albedos_and_maps_of_the_floor_are_the_floor_materials() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in [TransformKind::Raw, TransformKind::Log] {
        let m = Model::open(fit(tmp.path(), 12, transform)).unwrap();
        // The exact pass: every point's albedo is the dense rule over the
        // floor material's table.
        let points: Vec<[f64; 2]> = POINTS.to_vec();
        let got = m.exact_albedos_with(&points, BlendRule::Floor).unwrap();
        let gp = m.exact_albedos_with(&points, BlendRule::Gp).unwrap();
        let mut differs = false;
        for ((x, g), p) in points.iter().zip(&got).zip(&gp) {
            let want = dense_albedo(&m, &m.at_with(x, BlendRule::Floor).unwrap());
            for c in 0..3 {
                assert!(
                    (g[c] - want[c]).abs() <= 1e-9 * want[c].abs().max(1e-9),
                    "{transform:?} {x:?} {c}: {} vs {}",
                    g[c],
                    want[c]
                );
                differs |= (g[c] - p[c]).abs() > 1e-6 * p[c].abs();
            }
        }
        assert!(differs, "{transform:?}: the floor moved no albedo");
        // Maps: a zoomed view gets a field (within 1% of the dense rule
        // over the floor material), the default view with many samples a
        // per-pixel rule converging to it; neither is the linear shortcut.
        let (w, h) = (16usize, 12usize);
        for (view, samples) in [
            (
                brdf_atlas_core::View {
                    x0: 0.2,
                    x1: 0.24,
                    y0: -0.3,
                    y1: -0.26,
                },
                None,
            ),
            (brdf_atlas_core::View::default(), Some(200_000)),
        ] {
            let map = m
                .albedo_map_with(w, h, view, samples, BlendRule::Floor, &NoProgress)
                .unwrap();
            assert_ne!(map.method, brdf_atlas_core::AlbedoMethod::Linear);
            assert_eq!(map.blend, BlendRule::Floor);
            if samples.is_none() {
                assert!(
                    matches!(map.method, brdf_atlas_core::AlbedoMethod::Field { .. }),
                    "{:?}",
                    map.method
                );
            }
            for &(px, py) in &[(2usize, 2usize), (9, 6), (14, 10)] {
                let x = view.pixel_to_latent(px as f64, py as f64, w, h);
                let want = dense_albedo(&m, &m.at_with(&x, BlendRule::Floor).unwrap());
                let scale = want.iter().fold(1e-3f64, |a, v| a.max(v.abs()));
                for (c, (&got, want)) in map.rgb[py * w + px].iter().zip(want).enumerate() {
                    let err = (got as f64 - want).abs() / scale;
                    // The per-pixel rule is a quadrature of its own (within 2%
                    // for the GP's blend too: tests/reconstruct.rs).
                    let bound = if samples.is_some() { 0.02 } else { 0.01 };
                    assert!(err < bound, "{transform:?} {view:?} ({px},{py}) {c}: {err}");
                }
            }
        }
        // The plausible rule's steps are not a function of the point's
        // weights: it has no map.
        assert!(
            m.albedo_map_with(
                4,
                4,
                brdf_atlas_core::View::default(),
                None,
                BlendRule::Plausible,
                &NoProgress
            )
            .is_err()
        );
    }
}
