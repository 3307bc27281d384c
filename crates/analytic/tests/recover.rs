//! Fitting tables made from known analytic materials gives the materials back.

use brdf_atlas_analytic::{Analytic, FitParams, GgxLambert, Principled, Samples, fit_table};
use brdf_merl::{Dims, MerlTable};

fn table_of(m: &impl Analytic, dims: Dims) -> MerlTable {
    MerlTable::from_fn(dims, |bin| {
        let (wi, wo) = dims.angles_of(bin).directions();
        (wi[2] > 0.0 && wo[2] > 0.0).then(|| m.eval(wi, wo))
    })
}

#[test]
fn a_principled_table_gives_its_parameters_back() {
    let dims = Dims::new(45, 45, 90).unwrap();
    for truth in [
        Principled {
            base_color: [0.6, 0.3, 0.1],
            metallic: 0.0,
            roughness: 0.25,
            specular: 0.8,
            specular_color: [1.0, 0.9, 0.8],
            ior: 1.6,
        },
        Principled {
            base_color: [0.9, 0.6, 0.3],
            metallic: 1.0,
            roughness: 0.4,
            specular: 1.0,
            specular_color: [1.0; 3],
            ior: 1.5,
        },
    ] {
        let fits = fit_table(
            &table_of(&truth, dims),
            "truth",
            &FitParams::default(),
            None,
        )
        .unwrap();
        let got = fits.principled.model;
        assert!(
            fits.principled.error < 1e-3,
            "{got:?}: {}",
            fits.principled.error
        );
        for c in 0..3 {
            assert!(
                (got.base_color[c] - truth.base_color[c]).abs() < 0.01,
                "{got:?}"
            );
        }
        assert!((got.metallic - truth.metallic).abs() < 0.01, "{got:?}");
        assert!((got.roughness - truth.roughness).abs() < 0.01, "{got:?}");
        if truth.metallic == 0.0 {
            // The dielectric's F0 and F90 are what the table determines.
            let f0 = |p: &Principled| ((p.ior - 1.0) / (p.ior + 1.0)).powi(2) * p.specular;
            assert!((f0(&got) - f0(&truth)).abs() < 0.002, "{got:?}");
            assert!((got.specular - truth.specular).abs() < 0.02, "{got:?}");
        }
        // The baselines are worse, the Lambertian most.
        assert!(fits.single_lobe.error > fits.principled.error);
        assert!(fits.lambertian.error > fits.single_lobe.error);
    }
}

#[test]
fn a_single_lobe_table_gives_its_lobe_back_and_the_fit_is_deterministic() {
    let dims = Dims::new(45, 45, 90).unwrap();
    let truth = GgxLambert {
        diffuse: [0.2, 0.3, 0.4],
        specular: [0.3, 0.3, 0.2],
        roughness: 0.2,
    };
    let table = table_of(&truth, dims);
    let samples = Samples::new(&table, "lobe").unwrap();
    let a = FitParams::default().fit::<GgxLambert>(&samples);
    assert!(a.error < 1e-3, "{a:?}");
    assert!((a.model.roughness - 0.2).abs() < 0.005, "{a:?}");
    let b = FitParams::default().fit::<GgxLambert>(&samples);
    assert_eq!(a, b);
}

#[test]
fn an_unmeasured_table_is_an_error_naming_it() {
    let dims = Dims::new(8, 8, 16).unwrap();
    let empty = MerlTable::from_fn(dims, |_| None);
    let e = Samples::new(&empty, "void.binary").unwrap_err().to_string();
    assert!(
        e.starts_with("void.binary: 0 usable bin(s) of 8x8x16"),
        "{e}"
    );
}
