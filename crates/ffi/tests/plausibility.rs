//! The plausibility, confidence and blend-rule calls of the C library,
//! against the core library they wrap.

use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};
use std::ptr::null_mut;

use brdf_atlas_c::*;
use brdf_atlas_core::{BlendRule, FitOptions, GplvmParams, Model, NoProgress, Precision};
use brdf_atlas_core::{TransformKind, fit_dir};
use brdf_merl::{Dims, synth};

fn open(path: &Path) -> *mut BrdfAtlasModel {
    let c = CString::new(path.to_str().unwrap()).unwrap();
    let mut h = null_mut();
    assert_eq!(
        unsafe { brdf_atlas_model_open(c.as_ptr(), &mut h) },
        BrdfAtlasStatus::Ok
    );
    h
}

/// A 2-D model of `count` synthetic 8x8x16 materials (seed `seed`) in `dir`.
fn fitted(dir: &Path, count: usize, seed: u64, transform: TransformKind) -> PathBuf {
    let data = dir.join("data");
    synth::write_dir(&data, count, Dims::new(8, 8, 16).unwrap(), seed).unwrap();
    let path = dir.join("m.atlas");
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform,
        precision: Precision::F64,
    };
    fit_dir(&data, &path, &options, &NoProgress).unwrap();
    path
}

#[test]
fn plausibility_confidence_and_rules_are_the_core_library_s() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fitted(tmp.path(), 9, 4, TransformKind::Log);
    let model = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let h = open(&path);
    let len = model.dims().values();
    for (x, y) in [(0.2, -0.3), (-1.0, 0.95), (20.0, 20.0)] {
        for (rule, c_rule) in [
            (BlendRule::Gp, BRDF_ATLAS_BLEND_GP),
            (BlendRule::Plausible, BRDF_ATLAS_BLEND_PLAUSIBLE),
            (BlendRule::Floor, BRDF_ATLAS_BLEND_FLOOR),
        ] {
            let blend = model.at(&[x, y], rule).unwrap();
            let (p, c) = (blend.plausibility().unwrap(), blend.confidence());
            let mut out = std::mem::MaybeUninit::<BrdfAtlasPlausibility>::zeroed();
            let status =
                unsafe { brdf_atlas_model_plausibility(h, x, y, c_rule, out.as_mut_ptr()) };
            assert_eq!(status, BrdfAtlasStatus::Ok);
            let out = unsafe { out.assume_init() };
            assert_eq!(out.clamped_reflectance, p.clamped_reflectance);
            assert_eq!(out.clamped_values, p.clamped_values);
            assert_eq!(out.max_albedo, p.max_albedo);
            assert_eq!(out.variance, c.variance);
            assert_eq!(out.weight_sum, c.weight_sum);
            assert_eq!(out.plausible, i32::from(p.is_plausible()));
            assert_eq!(out.low_confidence, i32::from(c.is_low()));
            let mut buf = vec![0.0f64; len];
            let status = unsafe {
                brdf_atlas_model_reconstruct_with(
                    h,
                    x,
                    y,
                    c_rule,
                    buf.as_mut_ptr(),
                    len,
                    null_mut(),
                )
            };
            assert_eq!(status, BrdfAtlasStatus::Ok);
            assert_eq!(buf, blend.table().unwrap().raw());
        }
        let (mut v, mut w) = (f64::NAN, f64::NAN);
        assert_eq!(
            unsafe { brdf_atlas_model_confidence(h, x, y, &mut v, &mut w) },
            BrdfAtlasStatus::Ok
        );
        let c = model
            .at(&[x, y], brdf_atlas_core::BlendRule::Gp)
            .unwrap()
            .confidence();
        assert_eq!((v, w), (c.variance, c.weight_sum));
    }
    // The floor rule (the default) gives the bits of the plain
    // reconstruction; here the GP's differ.
    let with = |rule: i32| {
        let mut b = vec![1.0f64; len];
        let status = unsafe {
            brdf_atlas_model_reconstruct_with(h, 0.4, 0.1, rule, b.as_mut_ptr(), len, null_mut())
        };
        assert_eq!(status, BrdfAtlasStatus::Ok);
        b
    };
    let mut a = vec![0.0f64; len];
    let status =
        unsafe { brdf_atlas_model_reconstruct(h, 0.4, 0.1, a.as_mut_ptr(), len, null_mut()) };
    assert_eq!(status, BrdfAtlasStatus::Ok);
    assert_eq!(a, with(BRDF_ATLAS_BLEND_FLOOR));
    assert_ne!(a, with(BRDF_ATLAS_BLEND_GP));
    // An unknown rule is refused with its message.
    let mut out = std::mem::MaybeUninit::<BrdfAtlasPlausibility>::zeroed();
    let status = unsafe { brdf_atlas_model_plausibility(h, 0.0, 0.0, 7, out.as_mut_ptr()) };
    assert_eq!(status, BrdfAtlasStatus::InvalidArgument);
    let msg = unsafe { CStr::from_ptr(brdf_atlas_last_error_message()) }
        .to_string_lossy()
        .into_owned();
    assert!(msg.contains("blend rule 7"), "{msg}");
    unsafe { brdf_atlas_model_free(h) };
}

#[test]
fn the_map_of_a_chosen_rule_is_the_core_library_s() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fitted(tmp.path(), 7, 6, TransformKind::Raw);
    let model = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let h = open(&path);
    let (w, ht) = (11, 9);
    let view = brdf_atlas_core::View::default();
    let map = |rule: i32, cancel: *const i32| {
        let mut rgb = vec![-1.0f32; w * ht * 3];
        let status = unsafe {
            let (buf, len) = (rgb.as_mut_ptr(), rgb.len());
            brdf_atlas_model_albedo_map_with(h, w, ht, std::ptr::null(), 0, rule, cancel, buf, len)
        };
        (status, rgb)
    };
    let core = |rule| -> Vec<f32> {
        let m = model.map(
            brdf_atlas_core::MapRequest::new(w, ht)
                .view(view)
                .rule(rule),
        );
        m.unwrap().rgb.into_iter().flatten().collect()
    };
    // The floor's map is the default one, bit for bit; the GP's map of a
    // raw model is its exact linear one.
    let mut plain = vec![0.0f32; w * ht * 3];
    let status = unsafe {
        let (buf, len) = (plain.as_mut_ptr(), plain.len());
        brdf_atlas_model_albedo_map(h, w, ht, std::ptr::null(), 0, buf, len)
    };
    assert_eq!(status, BrdfAtlasStatus::Ok);
    let none = std::ptr::null();
    assert_eq!(
        map(BRDF_ATLAS_BLEND_FLOOR, none),
        (BrdfAtlasStatus::Ok, plain.clone())
    );
    assert_eq!(plain, core(BlendRule::Floor));
    let (status, gp) = map(BRDF_ATLAS_BLEND_GP, none);
    assert_eq!(status, BrdfAtlasStatus::Ok);
    assert_eq!(gp, core(BlendRule::Gp));
    assert_ne!(gp, plain);
    // A raised flag cancels it and writes nothing.
    let flag = 1i32;
    let (status, rgb) = map(BRDF_ATLAS_BLEND_GP, &flag);
    assert_eq!(status, BrdfAtlasStatus::Cancelled);
    assert!(rgb.iter().all(|&v| v == -1.0));
    // The plausible rule has no map; an unknown rule is refused.
    for (rule, words) in [
        (BRDF_ATLAS_BLEND_PLAUSIBLE, "has no map"),
        (9, "blend rule 9"),
    ] {
        let (status, rgb) = map(rule, none);
        assert_eq!(status, BrdfAtlasStatus::InvalidArgument);
        assert!(rgb.iter().all(|&v| v == -1.0));
        let msg = unsafe { CStr::from_ptr(brdf_atlas_last_error_message()) };
        assert!(msg.to_string_lossy().contains(words), "{msg:?}");
    }
    unsafe { brdf_atlas_model_free(h) };
}
