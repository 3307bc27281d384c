//! The soft-floor blend rule (`BlendRule::Floor`) against a dense
//! recomputation from the stored rows: its values, its plausibility, and
//! its held-out errors.

mod common;

use brdf_atlas_core::TransformKind;
use brdf_atlas_core::loo::{self, CONVEX_LENGTH_RATIO};
use brdf_atlas_core::soft_floor::{FLOOR_SHARE, FLOOR_SOFTNESS};
use brdf_atlas_core::{BlendRule, Model, NoProgress};
use brdf_merl::directional::INCIDENCE_DEGREES;
use brdf_merl::{DirectionalRule, MerlTable};
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

/// The cap's reach per channel at convex weights `v`, recomputed from the
/// stored rows as `soft_floor::reach_cap` and the store's energy bound
/// define it: the largest `r` in [0, 1] for which `(1 - r) sum_i v_i A_i +
/// r A_top` stays under `max(1, max_i A_i)` (less 1e-9 of it) at every
/// incidence, `A_i` each material's directional albedo and `A_top` that of
/// the table of brightest values.
fn dense_reach(m: &Model, transform: TransformKind, v: &[f64]) -> [f64; 3] {
    let store = m.store();
    let (n, bins) = (store.n(), DIMS.bins());
    let rule = DirectionalRule::new(DIMS);
    let mut z = vec![0.0; n];
    let mut reach = [1.0f64; 3];
    for k in 0..INCIDENCE_DEGREES.len() {
        let entries = rule.start_of(k)..rule.start_of(k + 1);
        for (c, r) in reach.iter_mut().enumerate() {
            let (mut each, mut top) = (vec![0.0; n], 0.0);
            for e in entries.clone() {
                let (bin, w) = (rule.bins()[e] as usize, rule.weights()[e]);
                let row = c * bins + bin;
                if store.unmeasured()[row] != 0 {
                    continue;
                }
                store.copy_rows(row, &mut z);
                let mean = store.mean()[row];
                let value = |t: f64| inverse(transform, bin, t).max(0.0);
                for (a, &zi) in each.iter_mut().zip(&z) {
                    *a += w * value(mean + zi);
                }
                top += w * value(mean + z.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            }
            let bound = each.iter().copied().fold(1.0, f64::max) * (1.0 - 1e-9);
            let blend: f64 = v.iter().zip(&each).map(|(v, a)| v * a).sum();
            if top > bound && top > blend {
                *r = r.min(((bound - blend) / (top - blend)).clamp(0.0, 1.0));
            }
        }
    }
    reach
}

#[test]
fn values_equal_a_dense_recomputation_and_are_never_clamped() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in TransformKind::ALL {
        let m = brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, transform)).unwrap());
        let store = m.store();
        let (n, bins) = (store.n(), DIMS.bins());
        let mut z = vec![0.0; n];
        let (mut gp_clamped, mut lifted, mut kept, mut capped, mut reached) = (0, 0, 0, 0, 0);
        for x in POINTS {
            let gp = m.at(&x, brdf_atlas_core::BlendRule::Gp).unwrap();
            let b = m.at(&x, BlendRule::Floor).unwrap();
            let v = convex(&m, &x);
            let got_v = b
                .floor()
                .expect("the floor rule records its convex weights");
            for (a, w) in got_v.iter().zip(&v) {
                assert!((a - w).abs() <= 1e-12, "{x:?}: convex {got_v:?} vs {v:?}");
            }
            let reach = dense_reach(&m, transform, &v);
            for (got, want) in b.reach().iter().zip(&reach) {
                assert!(
                    (got - want).abs() <= 1e-9,
                    "{x:?}: reach {:?} vs {reach:?}",
                    b.reach()
                );
            }
            reached += usize::from(reach.iter().any(|&r| r < 1.0));
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
                // The floor, capped on the way from the convex blend to the
                // brightest material's value.
                let (ch, bin) = (row / bins, row % bins);
                let top = store.mean()[row] + z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let cap = c + reach[ch] * (top - c);
                let lifted_value = floor(g, c);
                let want = lifted_value.min(cap);
                assert!(top >= c - 1e-12 * c.abs() && want >= FLOOR_SHARE * c.min(top));
                capped += usize::from(lifted_value > cap);
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
                if lifted_value > cap {
                    // The GP above the cap: capped there.
                    assert_eq!(want, cap);
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
        // And some lie near materials bright at grazing incidence, where
        // the cap stops short of the brightest material's value.
        assert!(reached > 0, "{transform:?}: every reach is 1");
    }
}

#[test]
fn held_out_errors_equal_a_dense_recomputation() {
    let tmp = tempfile::tempdir().unwrap();
    let m =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 10, TransformKind::Log)).unwrap());
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
    // Each material's reach, from the convex weights it is predicted with.
    let reach: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let v: Vec<f64> = (0..n).map(|j| cv[(i, j)]).collect();
            dense_reach(&m, TransformKind::Log, &v)
        })
        .collect();
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
            let (g, c) = (predict(&gp), predict(&cv));
            let y = floor(g, c).min(c + reach[i][row / bins] * (mean + top - c));
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
        let m = brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, transform)).unwrap());
        // The exact pass: every point's albedo is the dense rule over the
        // floor material's table.
        let points: Vec<[f64; 2]> = POINTS.to_vec();
        let got = m
            .exact_albedos(
                &points,
                brdf_atlas_core::AlbedoRequest::new().rule(BlendRule::Floor),
            )
            .unwrap();
        let gp = m
            .exact_albedos(
                &points,
                brdf_atlas_core::AlbedoRequest::new().rule(BlendRule::Gp),
            )
            .unwrap();
        let mut differs = false;
        for ((x, g), p) in points.iter().zip(&got).zip(&gp) {
            let want = dense_albedo(&m, &m.at(x, BlendRule::Floor).unwrap());
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
                .map(
                    brdf_atlas_core::MapRequest::new(w, h)
                        .view(view)
                        .samples(samples)
                        .rule(BlendRule::Floor),
                )
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
                let want = dense_albedo(&m, &m.at(&x, BlendRule::Floor).unwrap());
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
            m.map(brdf_atlas_core::MapRequest::new(4, 4).rule(BlendRule::Plausible))
                .is_err()
        );
    }
}

#[test]
fn the_default_material_reflects_no_more_than_one_nor_than_the_brightest() {
    let tmp = tempfile::tempdir().unwrap();
    let rule = DirectionalRule::new(DIMS);
    let albedos = |t: &MerlTable| rule.integrate(|b| t.rgb_or_zero(b));
    for transform in TransformKind::ALL {
        let m = brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, transform)).unwrap());
        // The bound from the material files themselves: at each incidence
        // and channel, 1 or the brightest material's albedo if it is more.
        let mut files: Vec<_> = std::fs::read_dir(tmp.path().join("data-12"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        let tables: Vec<MerlTable> = files.iter().map(|p| MerlTable::read(p).unwrap()).collect();
        let mut bound = vec![[1.0f64; 3]; INCIDENCE_DEGREES.len()];
        for t in &tables {
            for (b, a) in bound.iter_mut().zip(albedos(t)) {
                (0..3).for_each(|c| b[c] = b[c].max(a[c]));
            }
        }
        // The table of every bin's brightest value goes over it: a cap at
        // the brightest material alone would not hold a blend under it.
        let brightest = MerlTable::from_fn(DIMS, |bin| {
            let each = tables.iter().map(|t| t.rgb_or_zero(bin));
            Some(each.fold([0.0; 3], |a, v| [0, 1, 2].map(|c| a[c].max(v[c]))))
        });
        let over = |a: &[[f64; 3]]| {
            a.iter()
                .zip(&bound)
                .any(|(a, b)| (0..3).any(|c| a[c] > b[c] * (1.0 + 1e-6)))
        };
        assert!(
            over(&albedos(&brightest)),
            "{transform:?}: nothing to bound"
        );
        // Every point of the view and beyond it, and every material's own.
        let mut points: Vec<[f64; 2]> = (0..81)
            .map(|k| [-1.6 + 0.4 * (k / 9) as f64, -1.6 + 0.4 * (k % 9) as f64])
            .collect();
        let lat = m.latent();
        points.extend((0..lat.nrows()).map(|i| [lat[(i, 0)], lat[(i, 1)]]));
        let mut gp_over = 0;
        for x in &points {
            let table = m.at(x, BlendRule::Floor).unwrap().table().unwrap();
            let a = albedos(&table);
            assert!(!over(&a), "{transform:?} {x:?}: {a:?} over {bound:?}");
            let gp = m
                .at(x, brdf_atlas_core::BlendRule::Gp)
                .unwrap()
                .table()
                .unwrap();
            gp_over += usize::from(over(&albedos(&gp)));
        }
        // The GP's own blend goes over at some of these points: the
        // default rule's cap is what holds its material under the bound.
        assert!(gp_over > 0, "{transform:?}: the GP never goes over");
    }
}

#[test]
fn the_recorded_bound_is_the_one_the_store_gives() {
    // The fit records the energy bound in the model file; a model file
    // without it (written before it was recorded) computes it from the
    // store on first use, and both give every point the same reach.
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 12, TransformKind::RelLog);
    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    assert!(json.get("energy").is_some(), "the fit recorded no bound");
    json.as_object_mut().unwrap().remove("energy");
    let older = tmp.path().join("older.atlas");
    std::fs::write(&older, serde_json::to_vec(&json).unwrap()).unwrap();
    std::fs::copy(
        brdf_atlas_core::store_path_for(&path),
        brdf_atlas_core::store_path_for(&older),
    )
    .unwrap();
    let (recorded, computed) = (
        brdf_atlas_core::Atlas::new(Model::open(&path).unwrap()),
        brdf_atlas_core::Atlas::new(Model::open(&older).unwrap()),
    );
    let mut reached = false;
    for x in POINTS {
        let a = recorded.at(&x, BlendRule::Floor).unwrap().reach();
        let b = computed.at(&x, BlendRule::Floor).unwrap().reach();
        assert_eq!(a, b, "{x:?}");
        reached |= a.iter().any(|&r| r < 1.0);
    }
    assert!(reached, "every reach is 1");
}
