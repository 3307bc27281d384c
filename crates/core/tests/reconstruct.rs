//! Reconstruction, point queries, albedo maps and locate, against dense references.

use std::path::{Path, PathBuf};

use brdf_atlas_core::{BlendRule, GplvmParams, Model, NoProgress, Precision, TransformKind};
use brdf_atlas_core::{FitOptions, Rows, fit_dir};
use brdf_merl::synth::{self, Analytic, database};
use brdf_merl::{Dims, INVALID, MerlFile, MerlTable, Quadrature};
use faer::Mat;
use faer::linalg::solvers::DenseSolveCore;

const DIMS: Dims = Dims {
    theta_h: 12,
    theta_d: 12,
    phi_d: 24,
};

fn fit(dir: &Path, transform: TransformKind, precision: Precision) -> PathBuf {
    let data = dir.join("data");
    if !data.exists() {
        synth::write_dir(&data, 8, DIMS, 3).unwrap();
    }
    let model = dir.join(format!("{}-{}.atlas", transform.name(), precision.name()));
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform,
        precision,
    };
    fit_dir(&data, &model, &options, &NoProgress).unwrap();
    model
}

/// Weights by an explicit inverse (LU), independent of the model's Cholesky path.
fn dense_weights(m: &Model, x: &[f64]) -> Vec<f64> {
    let kernel = m.file().kernel;
    let k = kernel.matrix(m.latent().as_ref());
    let inv = k.partial_piv_lu().inverse();
    let kx = kernel.vector(m.latent().as_ref(), x);
    (0..kx.len())
        .map(|i| (0..kx.len()).map(|j| inv[(i, j)] * kx[j]).sum())
        .collect()
}

fn z(m: &Model, row: usize, i: usize) -> f64 {
    let n = m.store().n();
    match m.store().z() {
        Rows::F32(z) => z[row * n + i] as f64,
        Rows::F64(z) => z[row * n + i],
    }
}

#[test]
fn full_table_equals_the_dense_weighted_sum() {
    let tmp = tempfile::tempdir().unwrap();
    for transform in [TransformKind::Raw, TransformKind::Log] {
        let m = brdf_atlas_core::Atlas::new(
            Model::open(fit(tmp.path(), transform, Precision::F64)).unwrap(),
        );
        let x = [0.31, -0.42];
        let w = dense_weights(&m, &x);
        let table = m
            .at(&x, brdf_atlas_core::BlendRule::Gp)
            .unwrap()
            .table()
            .unwrap();
        let t = transform.build(DIMS);
        let bins = DIMS.bins();
        for row in 0..DIMS.values() {
            let (c, bin) = (row / bins, row % bins);
            let got = table.raw()[row];
            if m.store().unmeasured()[row] != 0 {
                assert_eq!(got, INVALID);
                continue;
            }
            let terms: Vec<f64> = (0..8).map(|i| w[i] * z(&m, row, i)).collect();
            let v: f64 = m.store().mean()[row] + terms.iter().sum::<f64>();
            // K is ill-conditioned: the two weight paths (Cholesky, LU) agree to
            // about cond(K) eps relative to the size of the terms summed.
            let size = m.store().mean()[row].abs() + terms.iter().map(|x| x.abs()).sum::<f64>();
            let want = brdf_merl::table::raw_from_physical(c, t.inverse(bin, v));
            let tol = brdf_merl::table::raw_from_physical(
                c,
                1e-8 * size * (1.0 + t.inverse(bin, v + size)),
            );
            assert!(got >= 0.0);
            assert!(
                (got - want).abs() <= tol,
                "{transform:?} row {row}: {got} vs {want} (tol {tol})"
            );
        }
    }
}

#[test]
fn training_points_reproduce_their_material() {
    let tmp = tempfile::tempdir().unwrap();
    let m = brdf_atlas_core::Atlas::new(
        Model::open(fit(tmp.path(), TransformKind::Log, Precision::F64)).unwrap(),
    );
    for i in 0..8 {
        let x: Vec<f64> = (0..2).map(|c| m.latent()[(i, c)]).collect();
        let b = m.at(&x, brdf_atlas_core::BlendRule::Gp).unwrap();
        // In transformed space the residual is mu (K^-1 Z)_i: tiny next to the data.
        let (mut err, mut norm) = (0.0, 0.0);
        for row in 0..DIMS.values() {
            let truth = m.store().mean()[row] + z(&m, row, i);
            err += (b.transformed(row) - truth).powi(2);
            norm += z(&m, row, i).powi(2);
        }
        assert!(
            err.sqrt() <= 0.05 * norm.sqrt(),
            "material {i}: residual {} of {}",
            err.sqrt(),
            norm.sqrt()
        );
    }
}

#[test]
fn point_queries_equal_the_full_table() {
    let tmp = tempfile::tempdir().unwrap();
    for precision in [Precision::F32, Precision::F64] {
        let m = brdf_atlas_core::Atlas::new(
            Model::open(fit(tmp.path(), TransformKind::Log, precision)).unwrap(),
        );
        let b = m.at(&[-0.2, 0.7], brdf_atlas_core::BlendRule::Gp).unwrap();
        let table = b.table().unwrap();
        for bin in (0..DIMS.bins()).step_by(7) {
            let from_table = table
                .value(0, bin)
                .zip(table.value(1, bin))
                .zip(table.value(2, bin));
            match (b.rgb(bin), from_table) {
                (Some(rgb), Some(((r, g), bb))) => {
                    // The table stores raw units: convert back exactly as the reader does.
                    for (got, want) in rgb.iter().zip([r, g, bb]) {
                        assert!(
                            (got - want).abs() <= 1e-15 * want.abs().max(1e-300),
                            "{bin}"
                        );
                    }
                }
                (None, None) => {}
                other => panic!("bin {bin}: {other:?}"),
            }
        }
        let wi = brdf_merl::angles::direction(0.5, 0.1);
        let wo = brdf_merl::angles::direction(0.3, 2.9);
        let pairs = vec![(wi, wo), (wo, wi), (wi, [0.0, 0.0, -1.0])];
        let batch = b.eval_batch(&pairs);
        assert_eq!(batch[0], b.eval(wi, wo));
        assert_eq!(
            batch[0].map(|v| v.map(|x| (x * 1e12).round())),
            table.eval(wi, wo).map(|v| v.map(|x| (x * 1e12).round()))
        );
        assert_eq!(batch[2], None);
    }
}

/// The memo: answers do not depend on query order, repetition or threads,
/// and match an independent dense computation of the same bins.
#[test]
fn remembered_point_queries_match_fresh_and_dense_ones() {
    let tmp = tempfile::tempdir().unwrap();
    let m = brdf_atlas_core::Atlas::new(
        Model::open(fit(tmp.path(), TransformKind::Raw, Precision::F64)).unwrap(),
    );
    let x = [0.4, -0.3];
    let w = dense_weights(&m, &x);
    let bins = DIMS.bins();
    let (forward, backward) = (
        m.at(&x, brdf_atlas_core::BlendRule::Gp).unwrap(),
        m.at(&x, brdf_atlas_core::BlendRule::Gp).unwrap(),
    );
    let cold: Vec<_> = (0..bins).map(|bin| forward.rgb(bin)).collect();
    for _ in 0..2 {
        for bin in (0..bins).rev() {
            let again = backward.rgb(bin);
            assert_eq!(
                again.map(|v| v.map(f64::to_bits)),
                cold[bin].map(|v| v.map(f64::to_bits)),
                "bin {bin}"
            );
        }
    }
    for (bin, got) in cold.iter().enumerate() {
        for c in 0..3 {
            let row = c * bins + bin;
            let got = got.map(|v| v[c]);
            if m.store().unmeasured()[row] != 0 {
                assert_eq!(forward.value(c, bin), None);
                continue;
            }
            let terms: Vec<f64> = (0..w.len()).map(|i| w[i] * z(&m, row, i)).collect();
            let mean = m.store().mean()[row];
            let want = (mean + terms.iter().sum::<f64>()).max(0.0);
            // The two weight solves differ by cond(K) eps; the sum may cancel.
            let scale = mean.abs() + terms.iter().map(|t| t.abs()).sum::<f64>();
            let v = forward.value(c, bin).unwrap();
            assert!((v - want).abs() <= 1e-8 * scale, "{row}: {v} vs {want}");
            if let Some(g) = got {
                assert_eq!(g.to_bits(), v.to_bits());
            }
        }
    }
    // A parallel batch on a fresh blend answers what a serial loop does.
    let pairs: Vec<_> = (0..20_000)
        .map(|k| {
            (
                brdf_merl::angles::direction(0.02 * (k % 70) as f64, 0.1),
                brdf_merl::angles::direction(0.3, 0.001 * k as f64),
            )
        })
        .collect();
    let batch = m
        .at(&x, brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .eval_batch(&pairs);
    for (p, got) in pairs.iter().zip(&batch) {
        assert_eq!(*got, forward.eval(p.0, p.1));
    }
}

#[test]
fn written_reconstruction_reads_back_with_the_merl_reader() {
    let tmp = tempfile::tempdir().unwrap();
    let m = brdf_atlas_core::Atlas::new(
        Model::open(fit(tmp.path(), TransformKind::Raw, Precision::F32)).unwrap(),
    );
    let out = tmp.path().join("new.binary");
    m.at(&[0.9, 0.9], brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .table()
        .unwrap()
        .write(&out)
        .unwrap();
    let f = MerlFile::open(&out).unwrap();
    assert_eq!(f.dims(), DIMS);
    let t = f.to_table();
    for (row, &v) in t.raw().iter().enumerate() {
        assert!(
            v >= 0.0 || (v == INVALID && m.store().unmeasured()[row] != 0),
            "row {row}: {v}"
        );
    }
}

#[test]
fn linear_map_equals_quadrature_of_the_reconstruction() {
    let tmp = tempfile::tempdir().unwrap();
    let m = brdf_atlas_core::Atlas::new(
        Model::open(fit(tmp.path(), TransformKind::Raw, Precision::F64)).unwrap(),
    );
    let view = brdf_atlas_core::View::default();
    let (w, h) = (16, 12);
    // The GP's material: the soft floor (the default) is not linear.
    let gp = |samples| {
        m.map(
            brdf_atlas_core::MapRequest::new(w, h)
                .view(view)
                .samples(samples)
                .rule(BlendRule::Gp),
        )
    };
    let map = gp(None).unwrap();
    let rule = Quadrature::dense(DIMS, 2);
    let bins = DIMS.bins();
    for &(px, py) in &[(0usize, 0usize), (5, 7), (15, 11), (8, 3)] {
        let x = view.pixel_to_latent(px as f64, py as f64, w, h);
        let b = m.at(&x, brdf_atlas_core::BlendRule::Gp).unwrap();
        // The blend before clamping, integrated bin by bin.
        let want = rule.integrate(|bin| {
            [0, 1, 2].map(|c| {
                let row = c * bins + bin;
                if m.store().unmeasured()[row] != 0 {
                    0.0
                } else {
                    b.transformed(row)
                }
            })
        });
        let got = map.rgb[py * w + px];
        for c in 0..3 {
            assert!(
                ((got[c] as f64) - want[c]).abs() <= 1e-6 * want[c].abs() + 1e-7,
                "({px},{py}) {c}: {} vs {}",
                got[c],
                want[c]
            );
        }
    }
    // The per-pixel quadrature path integrates the clamped reconstruction
    // (what a saved table holds) and converges to it as samples grow.
    let fine = gp(Some(200_000)).unwrap();
    let coarse = gp(Some(500)).unwrap();
    let (mut err_fine, mut err_coarse) = (0.0f64, 0.0f64);
    for &(px, py) in &[(2usize, 2usize), (9, 6), (14, 10)] {
        let b = m
            .at(
                &view.pixel_to_latent(px as f64, py as f64, w, h),
                brdf_atlas_core::BlendRule::Gp,
            )
            .unwrap();
        let want = rule.integrate(|bin| [0, 1, 2].map(|c| b.value(c, bin).unwrap_or(0.0)));
        let scale = want.iter().fold(1e-3f64, |a, v| a.max(v.abs()));
        let (f, k) = (fine.rgb[py * w + px], coarse.rgb[py * w + px]);
        for ((fc, kc), wc) in f.iter().zip(k).zip(want) {
            err_fine = err_fine.max((*fc as f64 - wc).abs() / scale);
            err_coarse = err_coarse.max((kc as f64 - wc).abs() / scale);
        }
    }
    assert!(err_fine < 0.02, "{err_fine}");
    assert!(err_fine < err_coarse, "{err_fine} !< {err_coarse}");
    // The log transform has no linear shortcut: without samples its map is
    // the albedo field (or the per-pixel rule where that is cheaper).
    let log = brdf_atlas_core::Atlas::new(
        Model::open(fit(tmp.path(), TransformKind::Log, Precision::F32)).unwrap(),
    );
    let map = log
        .map(brdf_atlas_core::MapRequest::new(4, 4).view(view))
        .unwrap();
    assert_ne!(map.method, brdf_atlas_core::AlbedoMethod::Linear);
    assert!(
        log.map(
            brdf_atlas_core::MapRequest::new(4, 4)
                .view(view)
                .samples(Some(1000))
        )
        .is_ok()
    );
}

#[test]
fn a_near_twin_lands_next_to_its_twin() {
    let tmp = tempfile::tempdir().unwrap();
    let model = fit(tmp.path(), TransformKind::Log, Precision::F32);
    let m = brdf_atlas_core::Atlas::new(Model::open(&model).unwrap());
    let mats = database(8, 3);
    for k in [1usize, 2, 5] {
        let src = &mats[k].brdf;
        let twin = Analytic {
            diffuse: src.diffuse.map(|v| v * 1.03),
            f0: src.f0,
            alpha: src.alpha * 1.03,
        };
        let path = tmp.path().join(format!("twin{k}.binary"));
        twin.table(DIMS).write(&path).unwrap();
        let found = brdf_atlas_core::Located::find(&m, &MerlFile::open(&path).unwrap()).unwrap();
        let name = &m.names()[found.nearest[0].0];
        assert_eq!(
            name, &mats[k].name,
            "twin of {} landed nearest {name}: {found:?}",
            mats[k].name
        );
        assert!(found.rmse < 0.5 * found.spread, "{found:?}");
        // The search covers the plane: the twin of a material on the box's
        // edge may land a little beyond it, but not out of the map's view.
        assert!(found.in_default_view(), "{found:?}");
    }
    // Wrong dims: a clear error.
    let odd = tmp.path().join("odd.binary");
    MerlTable::from_fn(Dims::new(4, 4, 8).unwrap(), |_| Some([0.1; 3]))
        .write(&odd)
        .unwrap();
    assert!(
        brdf_atlas_core::Located::find(&m, &MerlFile::open(&odd).unwrap())
            .unwrap_err()
            .to_string()
            .contains("odd.binary")
    );
    let _ = Mat::<f64>::zeros(1, 1);
}
