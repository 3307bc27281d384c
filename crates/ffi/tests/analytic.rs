//! `brdf_atlas_model_fit_analytic` against the analytic crate it wraps, and
//! its checks.

use std::ffi::CString;
use std::ptr::null_mut;

use brdf_atlas_analytic::{SWATCH_LIGHTS, fit_as_exported};
use brdf_atlas_c::*;
use brdf_atlas_core::{BlendRule, Model};
use common::small_model;

mod common;

#[test]
fn the_parameters_are_the_fit_of_the_points_material() {
    let tmp = tempfile::tempdir().unwrap();
    let path = small_model(tmp.path());
    let c = CString::new(path.to_str().unwrap()).unwrap();
    let mut h = null_mut();
    assert_eq!(
        unsafe { brdf_atlas_model_open(c.as_ptr(), &mut h) },
        BrdfAtlasStatus::Ok
    );
    let (x, y) = (0.2, -0.1);
    let mut out = std::mem::MaybeUninit::<BrdfAtlasAnalytic>::zeroed();
    let s = unsafe { brdf_atlas_model_fit_analytic(h, x, y, out.as_mut_ptr()) };
    assert_eq!(s, BrdfAtlasStatus::Ok);
    let got = unsafe { out.assume_init() };
    // The same numbers as the analytic crate's fit of the same material.
    let model = Model::open(&path).unwrap();
    let table = model
        .at(&[x, y], BlendRule::default())
        .unwrap()
        .table()
        .unwrap();
    let fits = fit_as_exported(&table, "m", &SWATCH_LIGHTS).unwrap();
    assert_eq!(got.base_color, fits.principled.model.base_color);
    assert_eq!(got.roughness, fits.principled.model.roughness);
    assert_eq!(got.ior, fits.principled.model.ior);
    assert_eq!(got.table_error, fits.principled.error);
    assert!(got.table_error < got.lambertian_table_error);
    // Bad arguments: statuses, and the output left alone.
    let mut untouched = got;
    untouched.metallic = -7.0;
    let mut o = untouched;
    let s = unsafe { brdf_atlas_model_fit_analytic(h, f64::NAN, y, &mut o) };
    assert_eq!(s, BrdfAtlasStatus::InvalidArgument);
    assert_eq!(o, untouched);
    let s = unsafe { brdf_atlas_model_fit_analytic(h, x, y, std::ptr::null_mut()) };
    assert_eq!(s, BrdfAtlasStatus::NullArgument);
    let s = unsafe { brdf_atlas_model_fit_analytic(std::ptr::null(), x, y, &mut o) };
    assert_eq!(s, BrdfAtlasStatus::NullArgument);
    unsafe { brdf_atlas_model_free(h) };
}
