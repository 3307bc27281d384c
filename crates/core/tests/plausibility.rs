//! Plausibility, confidence and the plausible blend rule, against dense
//! recomputations from the stored rows.

mod common;

use brdf_atlas_core::loo::{CLAMP_BUDGET, CONVEX_LENGTH_RATIO, Every, STEPS};
use brdf_atlas_core::{BlendRule, FitOptions, GplvmParams, Model, NoProgress, Precision};
use brdf_atlas_core::{DEFAULT_TRANSFORM, PAPER_KERNEL, TransformKind, default_kernel, fit_dir};
use brdf_merl::directional::largest;
use brdf_merl::{DirectionalRule, synth};
use common::{DIMS, POINTS, fit};
use faer::linalg::solvers::DenseSolveCore;

/// `(removed, total, negative values, measured values)` of weights `w`,
/// recomputed row by row in plain f64 from the stored rows.
fn dense_clamp(m: &Model, w: &[f64]) -> [f64; 4] {
    dense_clamp_by(m, |_| w, None)
}

/// Whether `every` keeps bin `bin`, by its documented rule: in each cell
/// of `step` indices the middle one (clipped to the last index).
fn kept(every: Every, bin: usize) -> bool {
    let (_, id, ip) = DIMS.unbin(bin);
    let keep = |i: usize, step: usize, len: usize| i == (i / step * step + step / 2).min(len - 1);
    keep(id, every.theta_d, DIMS.theta_d) && keep(ip, every.phi_d, DIMS.phi_d)
}

/// [`dense_clamp`] with the weights of each `theta_h` bin given by `w`,
/// over the rows of `theta_h` bin `only` (all rows if `None`).
fn dense_clamp_by<'a>(m: &Model, w: impl Fn(usize) -> &'a [f64], only: Option<usize>) -> [f64; 4] {
    dense_clamp_kept(m, w, only, Every::BIN)
}

/// [`dense_clamp_by`] over the bins `every` keeps.
fn dense_clamp_kept<'a>(
    m: &Model,
    w: impl Fn(usize) -> &'a [f64],
    only: Option<usize>,
    every: Every,
) -> [f64; 4] {
    let store = m.store();
    let (n, bins) = (store.n(), DIMS.bins());
    let kind = m.file().transform;
    let mut acc = [0.0; 4];
    let mut z = vec![0.0; n];
    for row in 0..store.rows() {
        let theta_h = DIMS.unbin(row % bins).0;
        if store.unmeasured()[row] != 0
            || only.is_some_and(|b| b != theta_h)
            || !kept(every, row % bins)
        {
            continue;
        }
        store.copy_rows(row, &mut z);
        let v = store.mean()[row] + w(theta_h).iter().zip(&z).map(|(a, b)| a * b).sum::<f64>();
        let bin = row % bins;
        let (ci, co) = DIMS.angles_of(bin).cosines();
        let c = (ci * co).max(0.0);
        // The inverse transforms before their clamp (TransformKind::formula).
        let f = match kind {
            TransformKind::Raw => v,
            TransformKind::Log | TransformKind::RelLog if c < 1e-6 => 0.0,
            TransformKind::Log => v.exp_m1() / c,
            TransformKind::RelLog => 1e-3 * v.exp_m1() / c,
        };
        acc[0] += (-f).max(0.0) * c;
        acc[1] += f.abs() * c;
        acc[2] += f64::from(u8::from(f < 0.0));
        acc[3] += 1.0;
    }
    acc
}

#[test]
fn clamp_figures_equal_a_dense_recomputation() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in [TransformKind::Raw, TransformKind::Log] {
        let m = brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, transform)).unwrap());
        let mut clamped_somewhere = false;
        for x in POINTS {
            let b = m.at(&x, brdf_atlas_core::BlendRule::Gp).unwrap();
            let p = b.plausibility().unwrap();
            let d = dense_clamp(&m, b.weights());
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-12);
            assert!(
                close(p.clamped_reflectance, d[0] / d[1]),
                "{transform:?} {x:?}: {p:?} {d:?}"
            );
            assert!(close(p.clamped_values, d[2] / d[3]), "{transform:?} {x:?}");
            clamped_somewhere |= d[0] > 0.0;
            // The largest directional albedo is the rule's on the written table.
            let rule = DirectionalRule::new(DIMS);
            let table = b.table().unwrap();
            let (a, deg) = largest(&rule.integrate(|bin| table.rgb_or_zero(bin)));
            assert!(
                close(p.max_albedo, a) && p.max_albedo_incidence == deg,
                "{x:?}"
            );
            // The table and its figures from one pass: the same bits, for
            // the GP's blend and the soft floor.
            for rule in [BlendRule::Gp, BlendRule::Floor] {
                let b = m.at(&x, rule).unwrap();
                let (t, q) = b.table_and_plausibility().unwrap();
                assert_eq!(t, b.table().unwrap(), "{transform:?} {x:?} {rule:?}");
                let p = b.plausibility().unwrap();
                assert_eq!(format!("{q:?}"), format!("{p:?}"), "{x:?} {rule:?}");
            }
        }
        assert!(
            clamped_somewhere,
            "{transform:?}: no test point exercises the clamp"
        );
    }
}

#[test]
fn confidence_is_the_predictive_variance() {
    let tmp = tempfile::tempdir().unwrap();
    let m =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, TransformKind::Log)).unwrap());
    let kernel = m.file().kernel;
    let latent = m.latent();
    // At an input material: the noise is all that is left.
    let xi: Vec<f64> = (0..2).map(|c| latent[(3, c)]).collect();
    let c = m
        .at(&xi, brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .confidence();
    assert!(c.variance < 1e-3 && !c.is_low(), "{c:?}");
    // Far away: nothing known, the weights vanish.
    let c = m
        .at(&[40.0, -40.0], brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .confidence();
    assert!(
        c.variance > 0.999 && c.is_low() && c.weight_sum.abs() < 1e-6,
        "{c:?}"
    );
    // In between: 1 - k^T K^-1 k with K^-1 from an LU inverse.
    let x = [0.37, -0.21];
    let inv = kernel.matrix(latent.as_ref()).partial_piv_lu().inverse();
    let k = kernel.vector(latent.as_ref(), &x);
    let n = k.len();
    let quad: f64 = (0..n)
        .map(|i| (0..n).map(|j| k[i] * inv[(i, j)] * k[j]).sum::<f64>())
        .sum();
    let c = m
        .at(&x, brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .confidence();
    assert!(
        (c.variance - (1.0 - quad).clamp(0.0, 1.0)).abs() < 1e-9,
        "{c:?} vs {quad}"
    );
}

#[test]
fn the_plausible_rule_keeps_every_theta_h_bin_within_budget_and_the_gp_where_it_already_is() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in [TransformKind::Raw, TransformKind::Log] {
        let m = brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, transform)).unwrap());
        let mut moved = 0;
        for x in POINTS {
            let gp = m.at(&x, BlendRule::Gp).unwrap();
            let pl = m.at(&x, BlendRule::Plausible).unwrap();
            assert_eq!(gp.weights(), pl.weights(), "the GP's weights are the base");
            let share_in = |b: usize, w: &[f64]| {
                let d = dense_clamp_by(&m, |_| w, Some(b));
                if d[1] > 0.0 { d[0] / d[1] } else { 0.0 }
            };
            let Some((convex, steps)) = pl.steps() else {
                // Not moved: every bin is already within budget.
                for b in 0..DIMS.theta_h {
                    assert!(share_in(b, gp.weights()) <= CLAMP_BUDGET * (1.0 + 1e-9));
                }
                continue;
            };
            moved += 1;
            // The convex weights of the narrower kernel, independently.
            let l = m.file().kernel.length_scale * CONVEX_LENGTH_RATIO;
            let k: Vec<f64> = (0..m.names().len())
                .map(|i| {
                    let d2 = (0..2)
                        .map(|c| (m.latent()[(i, c)] - x[c]).powi(2))
                        .sum::<f64>();
                    (-d2 / (2.0 * l * l)).exp() / d2
                })
                .collect();
            let sum: f64 = k.iter().sum();
            for (got, want) in convex.iter().zip(k.iter().map(|v| v / sum)) {
                assert!((got - want).abs() < 1e-12, "{x:?}: convex {got} vs {want}");
            }
            let at = |t: f64| -> Vec<f64> {
                gp.weights()
                    .iter()
                    .zip(convex)
                    .map(|(w, v)| w + t * (v - w))
                    .collect()
            };
            assert_eq!(steps.len(), DIMS.theta_h);
            // The albedo floor (see below) raises every bin to at least the
            // smallest step; above it each bin's step is its own.
            let floor = steps.iter().copied().fold(1.0, f64::min);
            for (b, &t) in steps.iter().enumerate() {
                let k = STEPS.iter().position(|&s| s == t).expect("a step of STEPS");
                assert_eq!(pl.weights_in(b), at(t).as_slice(), "{x:?} bin {b}");
                // Within budget, unless even the convex blend (t = 1) is not.
                let sp = share_in(b, &at(t));
                assert!(
                    sp <= CLAMP_BUDGET * (1.0 + 1e-9) || t == 1.0,
                    "{x:?} bin {b}: {sp} at {t}"
                );
                // The smallest such step: the one before it is over budget.
                if k > 0 && t > floor {
                    assert!(
                        share_in(b, &at(STEPS[k - 1])) > CLAMP_BUDGET,
                        "{x:?} bin {b}: smaller was enough"
                    );
                }
            }
            // The blend's own figures and values follow the bins' weights.
            let d = dense_clamp_by(&m, |b| pl.weights_in(b), None);
            let p = pl.plausibility().unwrap();
            assert!((p.clamped_reflectance - d[0] / d[1]).abs() <= 1e-9 * (d[0] / d[1]).max(1e-12));
            let table = pl.table().unwrap();
            for bin in (0..DIMS.bins()).step_by(97) {
                for c in 0..3 {
                    let (point, full) = (pl.value(c, bin), table.value(c, bin));
                    let same = match (point, full) {
                        (Some(a), Some(b)) => (a - b).abs() <= 1e-12 * b.abs().max(1e-300),
                        (a, b) => a == b,
                    };
                    assert!(same, "{x:?} bin {bin}: point {point:?}, table {full:?}");
                }
            }
        }
        assert!(moved > 0, "{transform:?}: no test point moved the weights");
    }
}

/// The largest directional albedo of the material a blend makes, from its
/// full table (independent of the point queries the rule uses).
fn table_albedo(b: &brdf_atlas_core::Blend<'_>) -> f64 {
    let rule = DirectionalRule::new(DIMS);
    let table = b.table().unwrap();
    largest(&rule.integrate(|bin| table.rgb_or_zero(bin))).0
}

#[test]
fn the_plausible_rule_brings_the_largest_albedo_to_one() {
    let tmp = tempfile::tempdir().unwrap();
    let m =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, TransformKind::Log)).unwrap());
    let mut raised = 0;
    for k in 0..49 {
        let x = [-2.4 + 0.8 * (k % 7) as f64, -2.4 + 0.8 * (k / 7) as f64];
        let gp = m.at(&x, BlendRule::Gp).unwrap();
        let pl = m.at(&x, BlendRule::Plausible).unwrap();
        let (a_gp, a_pl) = (table_albedo(&gp), table_albedo(&pl));
        // The ceiling: 1, or the convex blend's albedo where the materials
        // themselves exceed 1. The convex weights of the narrower kernel
        // and their blend's albedo are recomputed here, densely from the
        // stored rows, at every point (moved or not).
        let l = m.file().kernel.length_scale * CONVEX_LENGTH_RATIO;
        let d2: Vec<f64> = (0..m.names().len())
            .map(|i| (0..2).map(|c| (m.latent()[(i, c)] - x[c]).powi(2)).sum())
            .collect();
        let nearest = d2.iter().copied().fold(f64::INFINITY, f64::min);
        let k: Vec<f64> = d2
            .iter()
            .map(|d| (-(d - nearest) / (2.0 * l * l)).exp() * (nearest / d))
            .collect();
        let sum: f64 = k.iter().sum();
        let v: Vec<f64> = k.iter().map(|k| k / sum).collect();
        if let Some((convex, _)) = pl.steps() {
            for (got, want) in convex.iter().zip(&v) {
                assert!((got - want).abs() < 1e-12, "{x:?}: convex {got} vs {want}");
            }
        }
        let convex_blend_albedo = {
            let rule = DirectionalRule::new(DIMS);
            let values = |bin: usize| -> [f64; 3] {
                let mut rgb = [0.0; 3];
                let store = m.store();
                let n = store.n();
                let mut z = vec![0.0; n];
                for (ch, out) in rgb.iter_mut().enumerate() {
                    let row = ch * DIMS.bins() + bin;
                    if store.unmeasured()[row] != 0 {
                        continue;
                    }
                    store.copy_rows(row, &mut z);
                    let t = store.mean()[row] + v.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>();
                    let (ci, co) = DIMS.angles_of(bin).cosines();
                    let c = ci * co;
                    *out = if c < 1e-6 {
                        0.0
                    } else {
                        (t.exp_m1() / c).max(0.0)
                    };
                }
                rgb
            };
            largest(&rule.integrate(values)).0
        };
        let ceiling = convex_blend_albedo.max(1.0);
        assert!(
            a_pl <= ceiling * (1.0 + 1e-6),
            "{x:?}: albedo {a_gp} -> {a_pl}, ceiling {ceiling}"
        );
        if a_gp > ceiling {
            raised += 1;
            assert!(
                pl.steps().is_some(),
                "{x:?}: albedo {a_gp} left above {ceiling}"
            );
        }
    }
    assert!(raised > 0, "no point of the grid has a GP albedo above 1");
}

/// Hard cases: two materials, twins, and a point far away, stay finite
/// under both rules.
#[test]
fn hard_cases_stay_finite() {
    let tmp = tempfile::tempdir().unwrap();
    let twins = tmp.path().join("twins");
    synth::write_dir(&twins, 3, DIMS, 9).unwrap();
    let first = std::fs::read_dir(&twins)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    std::fs::copy(&first, twins.join("zz-twin.binary")).unwrap();
    let two = tmp.path().join("two");
    synth::write_dir(&two, 2, DIMS, 11).unwrap();
    // A chrome-like mirror (a highlight above 1e4 1/sr) beside the synthetic
    // materials, and a material with the outer third of the theta_h axis
    // unmeasured.
    let hard = tmp.path().join("hard");
    synth::write_dir(&hard, 4, DIMS, 13).unwrap();
    let chrome = brdf_merl::synth::Analytic {
        diffuse: [0.0; 3],
        f0: [0.95, 0.95, 0.95],
        alpha: 0.004,
    }
    .table(DIMS);
    let peak = (0..DIMS.bins())
        .filter_map(|b| chrome.value(0, b))
        .fold(0.0, f64::max);
    assert!(peak > 1e4, "the mirror's highlight is {peak}");
    chrome.write(hard.join("zz-chrome.binary")).unwrap();
    let holes = brdf_merl::MerlTable::from_fn(DIMS, |b| {
        let (ih, _, _) = DIMS.unbin(b);
        (ih * 90 < DIMS.theta_h * 60).then_some([0.1, 0.2, 0.3])
    });
    holes.write(hard.join("zz-holes.binary")).unwrap();
    // Two materials allow one latent dimension. Under the paper's settings
    // and under the default transform with the default kernel (shorter
    // for more materials).
    let sets = [
        (&twins, "twins", 2, 4),
        (&two, "two", 1, 2),
        (&hard, "hard", 2, 6),
    ];
    for ((dir, name, q, n), default) in sets.iter().flat_map(|s| [(s, false), (s, true)]) {
        let (name, q) = (*name, *q);
        let (transform, kernel) = if default {
            (DEFAULT_TRANSFORM, default_kernel(*n))
        } else {
            (TransformKind::Log, PAPER_KERNEL)
        };
        let model = tmp
            .path()
            .join(format!("{name}-{}.atlas", transform.name()));
        let options = FitOptions {
            params: GplvmParams::new(q)
                .length_scale(kernel.length_scale)
                .noise(kernel.noise)
                .check()
                .unwrap(),
            transform,
            precision: Precision::F64,
        };
        fit_dir(dir, &model, &options, &NoProgress).unwrap();
        let m = brdf_atlas_core::Atlas::new(Model::open(&model).unwrap());
        // Every material comes back at its own point, the twins and the
        // mirror among them, and the latent points stay in the box.
        let own = &m.file().fidelity.as_ref().unwrap().own;
        if default {
            for (j, name_j) in own.iter().zip(m.names()) {
                assert!(j.gives_back(), "{name} {name_j}: {}", j.describe());
            }
        }
        assert!(
            m.latent()
                .col_iter()
                .all(|c| c.iter().all(|v| v.abs() <= 1.0 + 1e-12))
        );
        // Far from every material the model knows nothing, and says so.
        let far = m
            .at(&[30.0, 30.0][..q], brdf_atlas_core::BlendRule::Gp)
            .unwrap()
            .confidence();
        assert!(far.is_low() && far.variance > 0.99, "{name}: {far:?}");
        for x in [[0.0, 0.0], [0.9, -0.9], [30.0, 30.0]] {
            for rule in [BlendRule::Gp, BlendRule::Plausible, BlendRule::Floor] {
                let b = m.at(&x[..q], rule).unwrap();
                let table = b.table().unwrap();
                assert!(
                    table.raw().iter().all(|v| v.is_finite()),
                    "{name} {x:?} {rule:?}"
                );
                let (p, c) = (b.plausibility().unwrap(), b.confidence());
                assert!(
                    [
                        p.clamped_reflectance,
                        p.clamped_values,
                        p.max_albedo,
                        c.variance,
                        c.weight_sum
                    ]
                    .iter()
                    .all(|v| v.is_finite()),
                    "{name} {x:?} {rule:?}: {p:?} {c:?}"
                );
                assert!(b.weights().iter().all(|w| w.is_finite()));
            }
        }
    }
}

#[test]
fn many_points_in_one_pass_take_the_steps_each_takes_alone() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in [TransformKind::Raw, TransformKind::Log] {
        let m = brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, transform)).unwrap());
        // Enough points for the pass's matrix product (8 weight vectors and
        // more), the test points among them.
        let mut points: Vec<Vec<f64>> = POINTS.iter().map(|p| p.to_vec()).collect();
        points.extend((0..11).map(|k| {
            let a = k as f64 * 0.57;
            vec![
                1.3 * a.cos() * (0.2 + 0.07 * k as f64),
                0.9 * (1.7 * a).sin(),
            ]
        }));
        let together = m.plausible_blends(&points).unwrap();
        assert_eq!(together.len(), points.len());
        let mut moved = 0;
        for (x, b) in points.iter().zip(&together) {
            let alone = m.at(x, BlendRule::Plausible).unwrap();
            assert_eq!(b.point(), x.as_slice());
            let (got, want) = (b.steps(), alone.steps());
            assert_eq!(
                got.map(|s| s.1.to_vec()),
                want.map(|s| s.1.to_vec()),
                "{transform:?} {x:?}"
            );
            moved += usize::from(got.is_some());
            for bin in (0..DIMS.bins()).step_by(89) {
                assert_eq!(b.rgb(bin), alone.rgb(bin), "{transform:?} {x:?} bin {bin}");
            }
        }
        assert!(moved > 0, "{transform:?}: no point moved the weights");
    }
}

#[test]
fn many_points_in_one_pass_have_the_figures_each_has_alone() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in [TransformKind::Raw, TransformKind::Log] {
        let m = brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, transform)).unwrap());
        // More points than a product's tile, the test points and one far
        // from every material among them.
        let mut points: Vec<[f64; 2]> = POINTS.iter().map(|p| [p[0], p[1]]).collect();
        points.push([4.0, -3.5]);
        points.extend((0..9).map(|k| {
            let a = k as f64 * 0.61;
            [1.2 * a.cos(), 0.8 * (1.9 * a).sin()]
        }));
        let mut clamped = 0;
        for rule in [BlendRule::Floor, BlendRule::Gp, BlendRule::Plausible] {
            let together = m.plausibilities(&points, rule, Every::BIN).unwrap();
            assert_eq!(together.len(), points.len());
            for (x, got) in points.iter().zip(&together) {
                let want = m.at(x, rule).unwrap().plausibility().unwrap();
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs() + 1e-12;
                assert!(
                    close(got.clamped_reflectance, want.clamped_reflectance)
                        && close(got.clamped_values, want.clamped_values),
                    "{transform:?} {rule:?} {x:?}: {got:?} against {want:?}"
                );
                // The albedos of every point from one read of each row of
                // the directional rule: the same sums, grouped otherwise.
                assert!(
                    (got.max_albedo - want.max_albedo).abs() <= 1e-12 * want.max_albedo.abs(),
                    "{transform:?} {rule:?} {x:?}: {got:?} against {want:?}"
                );
                assert_eq!(got.max_albedo_incidence, want.max_albedo_incidence);
                clamped += usize::from(want.clamped_reflectance > 0.0);
                if rule == BlendRule::Floor {
                    assert_eq!(got.clamped_reflectance, 0.0, "{transform:?} {x:?}");
                }
            }
        }
        // The GP clamps somewhere, so the sums were put to the test.
        assert!(clamped > 0, "{transform:?}: nothing clamped anywhere");
        // The GP's and the floor's figures from one pass are those of a
        // pass each, to the bit.
        let (gp, floor) = m.plausibilities_gp_and_floor(&points, Every::BIN).unwrap();
        let bits = |v: &[brdf_atlas_core::Plausibility]| {
            v.iter()
                .map(|p| [p.clamped_reflectance, p.clamped_values, p.max_albedo].map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(
            bits(&gp),
            bits(
                &m.plausibilities(&points, BlendRule::Gp, Every::BIN)
                    .unwrap()
            )
        );
        assert_eq!(
            bits(&floor),
            bits(
                &m.plausibilities(&points, BlendRule::Floor, Every::BIN)
                    .unwrap()
            )
        );
    }
    let m =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, TransformKind::Log)).unwrap());
    assert!(
        m.plausibilities(&[], BlendRule::Floor, Every::BIN)
            .unwrap()
            .is_empty()
    );
    assert!(
        m.plausibilities(&[[f64::NAN, 0.0]], BlendRule::Gp, Every::BIN)
            .is_err()
    );
}

/// The clamp's figures of many points summed over a subsample of the bins
/// (what the quick report asks for): a dense recomputation over the same
/// bins, for the GP's blend and the plausible rule's per-bin weights, the
/// largest albedo the model's whatever the subsample.
#[test]
fn many_points_on_a_subsample_of_the_bins_equal_a_recomputation_over_them() {
    let tmp = tempfile::tempdir().unwrap();
    let m =
        brdf_atlas_core::Atlas::new(Model::open(fit(tmp.path(), 12, TransformKind::Log)).unwrap());
    let points: Vec<[f64; 2]> = POINTS.iter().map(|p| [p[0], p[1]]).collect();
    let every = Every {
        theta_d: 2,
        phi_d: 4,
    };
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-12);
    let mut differs = false;
    for rule in [BlendRule::Gp, BlendRule::Plausible] {
        let sub = m.plausibilities(&points, rule, every).unwrap();
        let all = m.plausibilities(&points, rule, Every::BIN).unwrap();
        for ((x, got), whole) in points.iter().zip(&sub).zip(&all) {
            let b = m.at(x, rule).unwrap();
            let d = dense_clamp_kept(&m, |band| b.weights_in(band), None, every);
            assert!(
                close(got.clamped_reflectance, d[0] / d[1])
                    && close(got.clamped_values, d[2] / d[3]),
                "{rule:?} {x:?}: {got:?} against {d:?}"
            );
            assert_eq!(got.max_albedo.to_bits(), whole.max_albedo.to_bits());
            differs |= got.clamped_values != whole.clamped_values;
        }
    }
    assert!(
        differs,
        "the subsample gave every figure of the whole table: it tests nothing"
    );
}

#[test]
fn largest_albedos_of_many_points_are_each_points_alone_whatever_the_thread_count() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in [TransformKind::Raw, TransformKind::Log] {
        let path = fit(tmp.path(), 12, transform);
        let m = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
        let mut points: Vec<[f64; 2]> = POINTS.iter().map(|p| [p[0], p[1]]).collect();
        points.push([4.0, -3.5]);
        points.extend((0..9).map(|k| {
            let a = k as f64 * 0.43;
            [1.1 * a.cos(), 0.9 * (2.3 * a).sin()]
        }));
        for rule in [BlendRule::Floor, BlendRule::Gp] {
            let in_pool = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| m.largest_albedos(&points, rule).unwrap())
            };
            let together = in_pool(2);
            assert_eq!(together, in_pool(1), "{transform:?} {rule:?}");
            assert_eq!(together.len(), points.len());
            for (x, &(got, incidence)) in points.iter().zip(&together) {
                let (want, want_incidence) = m.at(x, rule).unwrap().largest_albedo();
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs() && want > 0.0,
                    "{transform:?} {rule:?} {x:?}: {got} against {want}"
                );
                assert_eq!(incidence, want_incidence, "{transform:?} {rule:?} {x:?}");
            }
        }
        assert!(m.largest_albedos(&points, BlendRule::Plausible).is_err());
        assert!(m.largest_albedos(&[], BlendRule::Gp).unwrap().is_empty());
        assert!(
            m.largest_albedos(&[[f64::NAN, 0.0]], BlendRule::Gp)
                .is_err()
        );
    }
}
