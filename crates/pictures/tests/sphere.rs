//! Lit spheres: a Lambertian table gives analytic cosine shading, and a
//! sphere rendered from a model's point queries equals the one rendered
//! from the MERL file of that point's reconstruction.

use brdf_atlas_core::{BlendRule, fit_dir};
use brdf_atlas_core::{FitOptions, GplvmParams, Model, NoProgress, Precision, TransformKind};
use brdf_atlas_pictures::sphere::{Light, render};
use brdf_atlas_pictures::swatch_sheet;
use brdf_merl::table::raw_from_physical;
use brdf_merl::{Dims, MerlTable, synth};

#[test]
fn a_lambertian_sphere_is_shaded_by_the_cosine() {
    let dims = Dims::new(16, 16, 32).unwrap();
    let rho = [0.8, 0.5, 0.2];
    let bins = dims.bins();
    let values: Vec<f64> = (0..3 * bins)
        .map(|i| raw_from_physical(i / bins, rho[i / bins] / std::f64::consts::PI))
        .collect();
    let table = MerlTable::from_raw(dims, values).unwrap();
    let lights = [
        Light {
            direction: [0.3, 0.4, 0.866],
            intensity: 0.7,
        },
        Light {
            direction: [-2.0, 0.0, 1.0],
            intensity: 0.2,
        },
    ];
    let size = 40;
    let sphere = render(&table, size, &lights);
    let mut lit = 0;
    for py in 0..size {
        for px in 0..size {
            let r = size as f64 / 2.0;
            let (u, v) = ((px as f64 + 0.5 - r) / r, (r - py as f64 - 0.5) / r);
            let p = py * size + px;
            if u * u + v * v > (1.0 - 1.0 / r).powi(2) {
                continue; // the rim, where coverage is partial
            }
            assert_eq!(sphere.coverage[p], 1.0);
            let n = [u, v, (1.0 - u * u - v * v).sqrt()];
            let shade: f64 = lights
                .iter()
                .map(|l| {
                    let d = l.direction;
                    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    l.intensity * ((n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / len).max(0.0)
                })
                .sum();
            for (c, r) in rho.iter().enumerate() {
                let want = r * shade;
                let got = sphere.radiance[p][c] as f64;
                assert!(
                    (got - want).abs() <= 1e-6 + 1e-6 * want,
                    "pixel ({px}, {py}) channel {c}: {got} vs {want}"
                );
            }
            lit += 1;
        }
    }
    assert!(lit > 1000, "{lit}");
    // Off the sphere: nothing.
    assert_eq!(sphere.coverage[0], 0.0);
    assert_eq!(sphere.radiance[0], [0.0; 3]);
}

/// A log-transform model of `count` synthetic materials (seed `seed`) fitted in `dir`.
fn fitted(
    dir: &std::path::Path,
    count: usize,
    dims: Dims,
    seed: u64,
    precision: Precision,
) -> brdf_atlas_core::Atlas {
    let data = dir.join("data");
    synth::write_dir(&data, count, dims, seed).unwrap();
    let path = dir.join("m.atlas");
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision,
    };
    fit_dir(&data, &path, &options, &NoProgress).unwrap();
    brdf_atlas_core::Atlas::new(Model::open(&path).unwrap())
}

#[test]
fn a_sphere_from_point_queries_equals_the_one_from_the_reconstructed_file() {
    let dir = tempfile::tempdir().unwrap();
    let model = fitted(
        dir.path(),
        8,
        Dims::new(16, 16, 32).unwrap(),
        4,
        Precision::F32,
    );
    let x = [0.31, -0.27];
    let blend = model.at(&x, brdf_atlas_core::BlendRule::Gp).unwrap();
    let lights = brdf_atlas_pictures::sphere::DEFAULT_LIGHTS;
    let from_model = render(&blend, 48, &lights);
    let merl = dir.path().join("there.binary");
    blend.table().unwrap().write(&merl).unwrap();
    let from_file = render(&MerlTable::read(&merl).unwrap(), 48, &lights);
    assert_eq!(from_model, from_file);
    assert!(from_model.radiance.iter().any(|c| c[0] > 0.0));

    // A sheet lays the grid out row by row from the top left of the view.
    let view = brdf_atlas_core::View::default();
    let points = swatch_sheet::grid_points(&view, 3);
    assert_eq!(points.len(), 9);
    assert!(points[0][0] < points[1][0] && points[0][1] > points[3][1]);
    let spheres =
        swatch_sheet::swatches(&model, &points[..2], None, 16, &lights, BlendRule::Gp).unwrap();
    assert_eq!(
        spheres[0].lines,
        [format!("({:.2}, {:.2})", points[0][0], points[0][1])]
    );
    let laid = swatch_sheet::compose(&spheres, 2);
    assert_eq!(laid.srgb8.len(), 3 * laid.width * laid.height);
    assert!(laid.width >= 32 && laid.height >= 16);
}

#[test]
fn plausible_swatches_are_the_spheres_of_the_plausible_reconstructions() {
    let dir = tempfile::tempdir().unwrap();
    let model = fitted(
        dir.path(),
        10,
        Dims::new(12, 12, 24).unwrap(),
        7,
        Precision::F64,
    );
    let lights = brdf_atlas_pictures::sphere::DEFAULT_LIGHTS;
    let points = swatch_sheet::grid_points(&brdf_atlas_core::View::default(), 3);
    let sheet =
        swatch_sheet::swatches(&model, &points, None, 24, &lights, BlendRule::Plausible).unwrap();
    let mut differ = 0;
    for (p, s) in points.iter().zip(&sheet) {
        let alone = model.at(p, BlendRule::Plausible).unwrap();
        let merl = dir.path().join("there.binary");
        alone.table().unwrap().write(&merl).unwrap();
        assert_eq!(
            s.sphere,
            render(&MerlTable::read(&merl).unwrap(), 24, &lights),
            "{p:?}"
        );
        differ += usize::from(
            s.sphere
                != render(
                    &model.at(p, brdf_atlas_core::BlendRule::Gp).unwrap(),
                    24,
                    &lights,
                ),
        );
    }
    // The rule changed some of the spheres (else this compared GP spheres).
    assert!(differ > 0);
}
