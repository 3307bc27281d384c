//! Map pictures: labels that never overlap (each other, the dots, the key
//! and ticks) and never leave the image, on a crowded map of 100 synthetic
//! materials and on one of 16; the predictive variance of every pixel
//! against a dense recomputation; the fade exactly where the rule says; the
//! EXR's variance channel.

use std::path::{Path, PathBuf};

use brdf_atlas_core::{
    FitOptions, GplvmParams, LOW_CONFIDENCE_VARIANCE, Model, NoProgress, Precision, TransformKind,
    View, fit_dir,
};
use brdf_atlas_pictures::map_picture::{self, FADE_GREY, Picture, Style, fade};
use brdf_merl::{Dims, synth};

const DIMS: Dims = Dims {
    theta_h: 8,
    theta_d: 8,
    phi_d: 16,
};

fn fit(dir: &Path, count: usize) -> PathBuf {
    let data = dir.join(format!("data-{count}"));
    synth::write_dir(&data, count, DIMS, 11).unwrap();
    let model = dir.join(format!("m-{count}.atlas"));
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision: Precision::F64,
    };
    fit_dir(&data, &model, &options, &NoProgress).unwrap();
    model
}

fn intersect(a: &[f32; 4], b: &[f32; 4]) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

/// Check every label of a `side`-pixel map of `model`; returns (labelled, left out).
fn check_labels(model: &brdf_atlas_core::Atlas, side: usize, dir: &Path) -> (usize, usize) {
    let map = model
        .map(brdf_atlas_core::MapRequest::new(side, side).samples(Some(32)))
        .unwrap();
    let picture = Picture::new(model, map, 8);
    let json = dir.join(format!("map-{side}.json"));
    map_picture::write_sidecar(&json, &picture.sidecar(model.path())).unwrap();
    let sidecar = map_picture::read_sidecar(&json).unwrap();
    let labels = &sidecar.labels;
    let visible: Vec<_> = sidecar
        .references
        .iter()
        .filter(|r| {
            (0.0..side as f64).contains(&r.pixel[0]) && (0.0..side as f64).contains(&r.pixel[1])
        })
        .collect();
    assert_eq!(sidecar.references.len(), model.names().len());
    assert_eq!(labels.len() + sidecar.unlabelled, visible.len());
    let rgb = picture.rgb8();
    for (k, l) in labels.iter().enumerate() {
        let [x0, y0, x1, y1] = l.rect;
        assert!(x0 < x1 && y0 < y1, "{l:?}");
        assert!(
            x0 >= 0.0 && y0 >= 0.0 && x1 <= side as f32 && y1 <= side as f32,
            "{l:?}"
        );
        for m in &labels[..k] {
            assert!(!intersect(&l.rect, &m.rect), "{l:?} meets {m:?}");
            assert_ne!(l.name, m.name);
        }
        for r in &visible {
            let (cx, cy) = (r.pixel[0] as f32, r.pixel[1] as f32);
            // The dot's outer disc, radius 3.6, with its antialiased rim.
            let dot = [cx - 4.1, cy - 4.1, cx + 4.1, cy + 4.1];
            assert!(
                !intersect(&l.rect, &dot),
                "{l:?} covers the dot of {}",
                r.name
            );
        }
        for t in &picture.overlay.ticks {
            assert!(!intersect(&l.rect, &t.rect), "{l:?} covers a tick");
        }
        if let Some(key) = &picture.overlay.key {
            assert!(!intersect(&l.rect, &key.rect), "{l:?} covers the key");
        }
        // The label is drawn: dark ink on light paper inside its box.
        let pixels: Vec<usize> = (y0.ceil() as usize..y1 as usize)
            .flat_map(|y| (x0.ceil() as usize..x1 as usize).map(move |x| y * side + x))
            .collect();
        let inked = pixels.iter().filter(|&&p| rgb[3 * p] < 60).count();
        let paper = pixels.iter().filter(|&&p| rgb[3 * p] > 150).count();
        assert!(
            inked > 5 && paper > 20,
            "{}: {inked} inked, {paper} paper",
            l.name
        );
    }
    if sidecar.unlabelled > 0 {
        assert!(
            picture.overlay.note.is_some(),
            "the map says how many were left out"
        );
    }
    (labels.len(), sidecar.unlabelled)
}

#[test]
fn labels_of_a_crowded_map_and_a_small_one_never_overlap() {
    let dir = tempfile::tempdir().unwrap();
    let crowded = brdf_atlas_core::Atlas::new(Model::open(fit(dir.path(), 100)).unwrap());
    let (placed, left) = check_labels(&crowded, 512, dir.path());
    assert!(placed >= 30, "{placed} labelled, {left} left out");
    assert!(left > 0, "100 names cannot all fit on 512 pixels");
    let small = brdf_atlas_core::Atlas::new(Model::open(fit(dir.path(), 16)).unwrap());
    let (placed, left) = check_labels(&small, 512, dir.path());
    assert_eq!((placed, left), (16, 0));
}

/// `1 - k^T K^-1 k` by Gaussian elimination on the dense `K` (with noise).
fn dense_variance(model: &Model, x: [f64; 2]) -> f64 {
    let latent = model.latent();
    let kernel = model.file().kernel;
    let n = latent.nrows();
    let k = |a: [f64; 2], b: [f64; 2]| {
        (-((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)) / (2.0 * kernel.length_scale.powi(2)))
            .exp()
    };
    let p = |i: usize| [latent[(i, 0)], latent[(i, 1)]];
    let mut a: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            let mut row: Vec<f64> = (0..n).map(|j| k(p(i), p(j))).collect();
            row[i] += kernel.noise;
            row.push(k(p(i), x));
            row
        })
        .collect();
    let kx: Vec<f64> = (0..n).map(|i| k(p(i), x)).collect();
    for c in 0..n {
        let pivot = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, pivot);
        let pivot_row = a[c].clone();
        for (r, row) in a.iter_mut().enumerate() {
            if r != c {
                let f = row[c] / pivot_row[c];
                for (v, p) in row[c..].iter_mut().zip(&pivot_row[c..]) {
                    *v -= f * p;
                }
            }
        }
    }
    let quad: f64 = (0..n).map(|i| kx[i] * a[i][n] / a[i][i]).sum();
    (1.0 - quad).clamp(0.0, 1.0)
}

#[test]
fn variance_matches_a_dense_recomputation_and_the_fade_follows_the_rule() {
    let dir = tempfile::tempdir().unwrap();
    let model = brdf_atlas_core::Atlas::new(Model::open(fit(dir.path(), 12)).unwrap());
    // Wide enough to reach far from the data, where the model knows little.
    let view = View {
        x0: -4.0,
        x1: 3.0,
        y0: -3.5,
        y1: 3.5,
    };
    let side = 96;
    let map = model
        .map(
            brdf_atlas_core::MapRequest::new(side, side)
                .view(view)
                .samples(Some(16)),
        )
        .unwrap();
    let mut seed = 12345u64;
    for _ in 0..60 {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
        let (px, py) = ((seed >> 33) as usize % side, (seed >> 13) as usize % side);
        let x = view.pixel_to_latent(px as f64, py as f64, side, side);
        let want = dense_variance(&model, x);
        let got = map.variance[py * side + px] as f64;
        assert!(
            (got - want).abs() < 1e-5,
            "pixel ({px}, {py}): {got} vs {want}"
        );
        let blend = model.at(&x, brdf_atlas_core::BlendRule::Gp).unwrap();
        assert!((blend.confidence().variance - want).abs() < 1e-6);
    }
    assert_eq!(model.variance_map(side, side, view).unwrap(), map.variance);
    let low = map
        .variance
        .iter()
        .filter(|&&v| v as f64 > LOW_CONFIDENCE_VARIANCE)
        .count();
    assert!(
        low > 100 && low < side * side - 100,
        "{low} low-confidence pixels"
    );

    // The PNG without contours, dots or words: the map itself, faded by the rule.
    let bare = Style {
        labels: false,
        key: false,
    };
    let picture = Picture::styled(&model, map.clone(), 0, bare);
    let rgb = picture.rgb8();
    let encode = |v: f32| {
        let s = if v <= 0.0031308 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5) as u8
    };
    let mut faded = 0;
    for p in 0..side * side {
        let v = map.variance[p];
        let t = if v as f64 > LOW_CONFIDENCE_VARIANCE {
            0.75 * ((v as f64 - 0.5) / 0.5) as f32
        } else {
            0.0
        };
        assert_eq!(fade(v), t);
        for c in 0..3 {
            let a = map.rgb[p][c].clamp(0.0, 1.0);
            let want = encode(a + t * (FADE_GREY - a));
            // Dots of materials inside the view are drawn over the map.
            let near_dot = picture.references.iter().any(|r| {
                let (x, y) = ((p % side) as f64 + 0.5, (p / side) as f64 + 0.5);
                (x - r.pixel[0]).abs() < 6.0 && (y - r.pixel[1]).abs() < 6.0
            });
            if !near_dot {
                assert!(rgb[3 * p + c].abs_diff(want) <= 1, "pixel {p} channel {c}");
                if t > 0.0 && (encode(a) as i32 - want as i32).abs() > 2 {
                    faded += 1;
                }
            }
        }
    }
    assert!(faded > 0, "some pixel visibly faded");

    // The EXR's fourth channel is the variance.
    let exr = dir.path().join("map.exr");
    map_picture::write_exr(&exr, &map).unwrap();
    let image = exr::prelude::read_first_flat_layer_from_file(&exr).unwrap();
    let channel = image
        .layer_data
        .channel_data
        .list
        .iter()
        .find(|c| c.name == *"V")
        .expect("a V channel");
    let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
    assert_eq!(values, map.variance);
}
