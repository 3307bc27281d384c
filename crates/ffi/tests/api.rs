//! The C functions called from Rust, for what the C and C++ consumers do
//! not reach: models that are not 2-D, a raw-transform model's exact map,
//! misaligned buffers, a map cancelled by its caller, the map's fields
//! built, saved beside the model and read by the next handle, a preview
//! drawn from the fields held and building none.

use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};
use std::ptr::{null, null_mut};
use std::sync::atomic::{AtomicI32, Ordering};

use brdf_atlas_c::*;
use brdf_atlas_core::View;
use brdf_atlas_core::{FitOptions, fit_dir};
use brdf_atlas_core::{GplvmParams, Model, NoProgress, Precision, TransformKind};
use brdf_merl::{Dims, synth};

fn fit(dir: &Path, q: usize, transform: TransformKind) -> PathBuf {
    let data = dir.join("data");
    if !data.exists() {
        synth::write_dir(&data, 5, Dims::new(6, 6, 12).unwrap(), 9).unwrap();
    }
    let model = dir.join(format!("q{q}-{}.model", transform.name()));
    let options = FitOptions {
        params: GplvmParams::new(q).check().unwrap(),
        transform,
        precision: Precision::F64,
    };
    fit_dir(&data, &model, &options, &NoProgress).unwrap();
    model
}

/// An open handle, freed on drop.
struct Handle(*mut BrdfAtlasModel);

impl Handle {
    fn open(path: &Path) -> Handle {
        let c = CString::new(path.to_str().unwrap()).unwrap();
        let mut h = null_mut();
        assert_eq!(
            unsafe { brdf_atlas_model_open(c.as_ptr(), &mut h) },
            BrdfAtlasStatus::Ok
        );
        Handle(h)
    }
}

impl Drop for Handle {
    fn drop(&mut self) {
        unsafe { brdf_atlas_model_free(self.0) }
    }
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(brdf_atlas_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

#[test]
fn a_three_dimensional_model_answers_facts_and_refuses_planar_calls() {
    let tmp = tempfile::tempdir().unwrap();
    let h = Handle::open(&fit(tmp.path(), 3, TransformKind::Log));
    let mut q = 0;
    assert_eq!(
        unsafe { brdf_atlas_model_latent_dim(h.0, &mut q) },
        BrdfAtlasStatus::Ok
    );
    assert_eq!(q, 3);
    let mut p = [0.0; 3];
    assert_eq!(
        unsafe { brdf_atlas_model_latent_point(h.0, 4, p.as_mut_ptr(), 3) },
        BrdfAtlasStatus::Ok
    );
    assert!(p.iter().all(|v| v.abs() <= 1.0) && p != [0.0; 3], "{p:?}");

    let mut len = 0;
    unsafe { brdf_atlas_model_table_len(h.0, &mut len) };
    let mut table = vec![0.0; len];
    let s =
        unsafe { brdf_atlas_model_reconstruct(h.0, 0.1, 0.2, table.as_mut_ptr(), len, null_mut()) };
    assert_eq!(s, BrdfAtlasStatus::Unsupported);
    assert!(last_error().contains("3-D"), "{}", last_error());
    let mut map = vec![0.0f32; 4 * 4 * 3];
    let s =
        unsafe { brdf_atlas_model_albedo_map(h.0, 4, 4, null(), 0, map.as_mut_ptr(), map.len()) };
    assert_eq!(s, BrdfAtlasStatus::Unsupported);
    let mut w = [0.0; 5];
    let s = unsafe { brdf_atlas_model_weights(h.0, 0.0, 0.0, w.as_mut_ptr(), 5) };
    assert_eq!(s, BrdfAtlasStatus::Unsupported);
}

#[test]
fn default_samples_of_a_raw_model_give_the_exact_linear_map() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 2, TransformKind::Raw);
    let h = Handle::open(&path);
    let (w, ht) = (7, 5);
    let mut map = vec![0.0f32; w * ht * 3];
    let s =
        unsafe { brdf_atlas_model_albedo_map(h.0, w, ht, null(), 0, map.as_mut_ptr(), map.len()) };
    assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
    let m = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let want = m.map(brdf_atlas_core::MapRequest::new(w, ht)).unwrap();
    let want: Vec<f32> = want.rgb.iter().flatten().copied().collect();
    assert_eq!(map, want);
}

#[test]
fn misaligned_buffers_are_refused_untouched() {
    let tmp = tempfile::tempdir().unwrap();
    let h = Handle::open(&fit(tmp.path(), 2, TransformKind::Log));
    let mut bytes = vec![7u8; 8 * 8];
    let misaligned = unsafe { bytes.as_mut_ptr().add(1) }.cast::<f64>();
    let s = unsafe { brdf_atlas_model_weights(h.0, 0.0, 0.0, misaligned, 5) };
    assert_eq!(s, BrdfAtlasStatus::InvalidArgument);
    assert!(last_error().contains("not aligned"), "{}", last_error());
    assert!(bytes.iter().all(|b| *b == 7));
    let s = unsafe {
        brdf_atlas_model_weights(misaligned.cast_const().cast(), 0.0, 0.0, misaligned, 5)
    };
    assert_eq!(s, BrdfAtlasStatus::InvalidArgument);
}

#[test]
fn the_variance_map_is_the_confidence_of_each_pixel() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 2, TransformKind::Log);
    let h = Handle::open(&path);
    let (w, ht) = (9, 6);
    let view = BrdfAtlasView {
        x0: -3.0,
        x1: 2.0,
        y0: -2.5,
        y1: 2.5,
    };
    let mut small = vec![0.0f32; w * ht - 1];
    let s = unsafe {
        brdf_atlas_model_variance_map(h.0, w, ht, &view, small.as_mut_ptr(), small.len())
    };
    assert_eq!(s, BrdfAtlasStatus::BufferTooSmall);
    let mut v = vec![0.0f32; w * ht];
    let s = unsafe { brdf_atlas_model_variance_map(h.0, w, ht, &view, v.as_mut_ptr(), v.len()) };
    assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
    let core_view: View = View {
        x0: view.x0,
        x1: view.x1,
        y0: view.y0,
        y1: view.y1,
    };
    for py in 0..ht {
        for px in 0..w {
            let [x, y] = core_view.pixel_to_latent(px as f64, py as f64, w, ht);
            let mut want = 0.0;
            let s = unsafe { brdf_atlas_model_confidence(h.0, x, y, &mut want, null_mut()) };
            assert_eq!(s, BrdfAtlasStatus::Ok);
            let got = v[py * w + px] as f64;
            assert!((got - want).abs() < 1e-6, "({px}, {py}): {got} vs {want}");
        }
    }
    assert!(v.iter().any(|&x| x > 0.5) && v.iter().any(|&x| x < 0.5));
}

#[test]
fn a_cancellable_map_is_the_map_or_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 2, TransformKind::Log);
    let h = Handle::open(&path);
    let (w, ht) = (24, 16);
    let plain = |samples: usize| {
        let mut map = vec![0.0f32; w * ht * 3];
        let s = unsafe {
            brdf_atlas_model_albedo_map(h.0, w, ht, null(), samples, map.as_mut_ptr(), map.len())
        };
        assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
        map
    };
    let cancellable = |samples: usize, flag: &AtomicI32, map: &mut [f32]| unsafe {
        brdf_atlas_model_albedo_map_cancellable(
            h.0,
            w,
            ht,
            null(),
            samples,
            flag.as_ptr(),
            map.as_mut_ptr(),
            map.len(),
        )
    };
    for samples in [0, 16] {
        let want = plain(samples);
        // Not cancelled: the plain map, bit for bit.
        let mut map = vec![0.0f32; w * ht * 3];
        let s = cancellable(samples, &AtomicI32::new(0), &mut map);
        assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
        assert_eq!(map, want);
        // Cancelled before the call: nothing written.
        let mut map = vec![-1.0f32; w * ht * 3];
        let s = cancellable(samples, &AtomicI32::new(1), &mut map);
        assert_eq!(s, BrdfAtlasStatus::Cancelled);
        assert!(last_error().contains("cancelled"), "{}", last_error());
        assert!(map.iter().all(|v| *v == -1.0));
        // Cancelled from another thread while it runs: the whole map or
        // nothing, never part of one.
        let flag = AtomicI32::new(0);
        let mut map = vec![-1.0f32; w * ht * 3];
        let s = std::thread::scope(|scope| {
            scope.spawn(|| flag.store(1, Ordering::Relaxed));
            cancellable(samples, &flag, &mut map)
        });
        match s {
            BrdfAtlasStatus::Ok => assert_eq!(map, want),
            BrdfAtlasStatus::Cancelled => assert!(map.iter().all(|v| *v == -1.0)),
            other => panic!("{other:?}: {}", last_error()),
        }
    }
    let mut map = vec![0.0f32; w * ht * 3];
    let s = unsafe {
        brdf_atlas_model_albedo_map_cancellable(
            h.0,
            w,
            ht,
            null(),
            0,
            null(),
            map.as_mut_ptr(),
            map.len(),
        )
    };
    assert_eq!(s, BrdfAtlasStatus::NullArgument);
    assert!(last_error().contains("cancel"), "{}", last_error());
}

#[test]
fn a_marker_reports_how_its_material_comes_back() {
    // The paper's kernel on five materials: markers the fit recorded, each
    // with the figures the model file holds (checked against an independent
    // reconstruction in the core's tests).
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 2, TransformKind::Log);
    let h = Handle::open(&path);
    let m = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let own = &m
        .file()
        .fidelity
        .as_ref()
        .expect("fit records the own points")
        .own;
    for (i, judged) in own.iter().enumerate() {
        let (x, y) = (m.latent()[(i, 0)], m.latent()[(i, 1)]);
        for (dx, hit) in [
            (0.0, true),
            (0.5 * BRDF_ATLAS_MARKER_RADIUS, true),
            (0.3, false),
        ] {
            let (mut index, mut error, mut ratio) = (0usize, 0.0, 0.0);
            let s = unsafe {
                brdf_atlas_model_marker(h.0, x + dx, y, &mut index, &mut error, &mut ratio)
            };
            assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
            // 0.3 away from a material may be another's marker: only the
            // hits are checked for who they are.
            if hit {
                assert_eq!(index, i);
                assert_eq!(error, judged.albedo_error());
                assert_eq!(ratio, judged.worst_ratio());
            } else if index == usize::MAX {
                assert!(error.is_nan() && ratio.is_nan());
            }
        }
    }
    // Every out-pointer may be NULL; a non-finite point is refused.
    let s = unsafe { brdf_atlas_model_marker(h.0, 0.0, 0.0, null_mut(), null_mut(), null_mut()) };
    assert_eq!(s, BrdfAtlasStatus::Ok);
    let s =
        unsafe { brdf_atlas_model_marker(h.0, f64::NAN, 0.0, null_mut(), null_mut(), null_mut()) };
    assert_eq!(s, BrdfAtlasStatus::InvalidArgument);
    let s =
        unsafe { brdf_atlas_model_marker(null(), 0.0, 0.0, null_mut(), null_mut(), null_mut()) };
    assert_eq!(s, BrdfAtlasStatus::NullArgument);
}

#[test]
fn map_fields_are_built_saved_and_read_by_the_next_handle() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 2, TransformKind::Log);
    let file = brdf_atlas_core::fields_path(&path);
    let saved = |h: &Handle| {
        let mut n = usize::MAX;
        let s = unsafe { brdf_atlas_model_saved_fields(h.0, &mut n) };
        (s, n)
    };
    let (w, ht) = (32, 24);
    let map = |h: &Handle| {
        let mut out = vec![0.0f32; w * ht * 3];
        let s = unsafe {
            brdf_atlas_model_albedo_map(h.0, w, ht, null(), 0, out.as_mut_ptr(), out.len())
        };
        assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
        out
    };
    // The map without fields (a map this small has too small a budget to
    // build them).
    let without = map(&Handle::open(&path));
    let h = Handle::open(&path);
    assert_eq!(
        saved(&h),
        (BrdfAtlasStatus::Ok, 0),
        "a library fit saves none"
    );
    let wide = BrdfAtlasView {
        x0: -3.0,
        x1: 3.0,
        y0: -3.0,
        y1: 3.0,
    };
    // Cancelled: nothing built, nothing saved.
    let flag = AtomicI32::new(1);
    let s = unsafe { brdf_atlas_model_prepare_map_fields(h.0, 512, 512, &wide, flag.as_ptr()) };
    assert_eq!(s, BrdfAtlasStatus::Cancelled, "{}", last_error());
    assert!(!file.exists());
    let s = unsafe { brdf_atlas_model_prepare_map_fields(h.0, 512, 512, null(), null()) };
    assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
    assert!(file.exists());
    // The map of the default window: from the field just built, the same
    // bits as a new handle's, which reads it from the file.
    let first = map(&h);
    assert_ne!(first, without, "drawn from the field");
    let again = Handle::open(&path);
    let (s, n) = saved(&again);
    assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
    assert!(n >= 1, "{n}");
    assert_eq!(map(&again), first);
    // The pair `fit` saves: [-3, 3]^2's field joins the file.
    let s = unsafe { brdf_atlas_model_prepare_fit_fields(again.0, null()) };
    assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
    let (s, more) = saved(&Handle::open(&path));
    assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
    assert!(more > n, "{more} after {n}");
    // A damaged file: BAD_FILE naming it, and maps as before.
    std::fs::write(&file, b"{\"format\": 3").unwrap();
    let damaged = Handle::open(&path);
    let (s, _) = saved(&damaged);
    assert_eq!(s, BrdfAtlasStatus::BadFile);
    assert!(last_error().contains(".fields"), "{}", last_error());
    assert_eq!(map(&damaged), without);
    // NULL arguments.
    let s = unsafe { brdf_atlas_model_saved_fields(h.0, null_mut()) };
    assert_eq!(s, BrdfAtlasStatus::NullArgument);
    let s = unsafe { brdf_atlas_model_prepare_map_fields(null(), 8, 8, null(), null()) };
    assert_eq!(s, BrdfAtlasStatus::NullArgument);
    let s = unsafe { brdf_atlas_model_prepare_fit_fields(null(), null()) };
    assert_eq!(s, BrdfAtlasStatus::NullArgument);
}

#[test]
fn one_call_gives_the_map_and_its_variance() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 2, TransformKind::Log);
    let h = Handle::open(&path);
    let view = BrdfAtlasView {
        x0: -1.5,
        x1: 0.5,
        y0: -0.8,
        y1: 1.2,
    };
    for (samples, (w, ht)) in [(0, (160, 120)), (16, (24, 18))] {
        let mut want = vec![0.0f32; w * ht * 3];
        let s = unsafe {
            brdf_atlas_model_albedo_map_with(
                h.0,
                w,
                ht,
                &view,
                samples,
                BRDF_ATLAS_BLEND_FLOOR,
                null(),
                want.as_mut_ptr(),
                want.len(),
            )
        };
        assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
        let mut exact = vec![0.0f32; w * ht];
        let s = unsafe {
            brdf_atlas_model_variance_map(h.0, w, ht, &view, exact.as_mut_ptr(), exact.len())
        };
        assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
        // The map into `rgb`, its variance into `var` unless None.
        let map = |rgb: &mut [f32], var: Option<&mut [f32]>| {
            let (vp, vn) = var.map_or((null_mut(), 0), |v| (v.as_mut_ptr(), v.len()));
            unsafe {
                brdf_atlas_model_map(
                    h.0,
                    w,
                    ht,
                    &view,
                    samples,
                    BRDF_ATLAS_BLEND_FLOOR,
                    null(),
                    rgb.as_mut_ptr(),
                    rgb.len(),
                    vp,
                    vn,
                )
            }
        };
        let (mut rgb, mut var) = (vec![0.0f32; w * ht * 3], vec![-1.0f32; w * ht]);
        let s = map(&mut rgb, Some(&mut var));
        assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
        // The albedo map's bits; the variance within the field's tolerance
        // of the exact one (the exact one itself per pixel).
        assert_eq!(rgb, want);
        for (v, e) in var.iter().zip(&exact) {
            assert!((v - e).abs() <= 2e-3, "{v} {e} ({samples} samples)");
        }
        if samples > 0 {
            assert_eq!(var, exact);
        }
        // No variance asked for: the same albedo.
        let mut alone = vec![0.0f32; w * ht * 3];
        assert_eq!(
            map(&mut alone, None),
            BrdfAtlasStatus::Ok,
            "{}",
            last_error()
        );
        assert_eq!(alone, want);
        // A variance buffer one short: refused, nothing written.
        let mut short = vec![-1.0f32; w * ht - 1];
        assert_eq!(
            map(&mut rgb, Some(&mut short)),
            BrdfAtlasStatus::BufferTooSmall
        );
        assert!(short.iter().all(|v| *v == -1.0));
    }
}

#[test]
fn a_preview_draws_from_held_fields_and_builds_none() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fit(tmp.path(), 2, TransformKind::Log);
    let (w, ht) = (30, 20);
    // A map of the default window by `call` (`brdf_atlas_model_map` or
    // `_preview`) with `samples`.
    type Call = unsafe extern "C" fn(
        *const BrdfAtlasModel,
        usize,
        usize,
        *const BrdfAtlasView,
        usize,
        i32,
        *mut f32,
        usize,
        *mut f32,
        usize,
    ) -> BrdfAtlasStatus;
    unsafe extern "C" fn full(
        m: *const BrdfAtlasModel,
        w: usize,
        h: usize,
        v: *const BrdfAtlasView,
        s: usize,
        b: i32,
        rgb: *mut f32,
        n: usize,
        var: *mut f32,
        vn: usize,
    ) -> BrdfAtlasStatus {
        unsafe { brdf_atlas_model_map(m, w, h, v, s, b, null(), rgb, n, var, vn) }
    }
    let run = |m: *const BrdfAtlasModel, call: Call, samples: usize| {
        let (mut rgb, mut var) = (vec![0.0f32; w * ht * 3], vec![0.0f32; w * ht]);
        let s = unsafe {
            call(
                m,
                w,
                ht,
                null(),
                samples,
                BRDF_ATLAS_BLEND_FLOOR,
                rgb.as_mut_ptr(),
                rgb.len(),
                var.as_mut_ptr(),
                var.len(),
            )
        };
        (s, rgb, var)
    };
    let draw = |h: &Handle, call: Call, samples: usize| {
        let (s, rgb, var) = run(h.0, call, samples);
        assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
        (rgb, var)
    };
    let h = Handle::open(&path);
    // Nothing held: every pixel from 16 samples, and nothing built.
    let per_pixel = draw(&h, full, 16);
    assert_eq!(draw(&h, brdf_atlas_model_map_preview, 16), per_pixel);
    assert_eq!(draw(&h, brdf_atlas_model_map_preview, 16), per_pixel);
    // With the default window's field held: the full map's pixels.
    let s = unsafe { brdf_atlas_model_prepare_map_fields(h.0, 512, 512, null(), null()) };
    assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
    let from_field = draw(&h, full, 0);
    assert_ne!(from_field.0, per_pixel.0);
    assert_eq!(draw(&h, brdf_atlas_model_map_preview, 16), from_field);
    // A new handle takes it from the file.
    let again = Handle::open(&path);
    assert_eq!(draw(&again, brdf_atlas_model_map_preview, 16), from_field);
    // Refused: no samples for the pixels nothing covers, no model.
    let preview = brdf_atlas_model_map_preview;
    assert_eq!(run(h.0, preview, 0).0, BrdfAtlasStatus::InvalidArgument);
    assert!(last_error().contains("samples"), "{}", last_error());
    assert_eq!(run(null(), preview, 16).0, BrdfAtlasStatus::NullArgument);
}
