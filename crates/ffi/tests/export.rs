//! `brdf_atlas_model_export`: the files it writes for a point of a small
//! synthetic model carry the parameters it returns (which are
//! `brdf_atlas_model_fit_analytic`'s), and every bad argument is refused
//! with its status and one line, before the fit, writing nothing.

use std::ffi::{CStr, CString, c_char};
use std::path::Path;
use std::ptr::{null, null_mut};

use brdf_atlas_c::*;
use common::small_model;
use serde_json::Value;

mod common;

fn c(s: &str) -> CString {
    CString::new(s).unwrap()
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(brdf_atlas_last_error_message()) }
        .to_str()
        .unwrap()
        .to_owned()
}

fn json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// The JSON chunk of a `.glb`.
fn glb_json(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(&bytes[16..20], b"JSON");
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn the_files_carry_the_fitted_parameters_and_bad_arguments_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let path = small_model(tmp.path());
    let mut h = null_mut();
    let model_path = c(path.to_str().unwrap());
    assert_eq!(
        unsafe { brdf_atlas_model_open(model_path.as_ptr(), &mut h) },
        BrdfAtlasStatus::Ok
    );
    let out_dir = tmp.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let dir = c(out_dir.to_str().unwrap());
    let stem = c("pick");
    let (x, y) = (0.2, -0.1);

    let mut got = std::mem::MaybeUninit::<BrdfAtlasAnalytic>::zeroed();
    let s =
        unsafe { brdf_atlas_model_export(h, x, y, dir.as_ptr(), stem.as_ptr(), got.as_mut_ptr()) };
    assert_eq!(s, BrdfAtlasStatus::Ok, "{}", last_error());
    let got = unsafe { got.assume_init() };
    // The parameters of brdf_atlas_model_fit_analytic, bit for bit.
    let mut fitted = std::mem::MaybeUninit::<BrdfAtlasAnalytic>::zeroed();
    let s = unsafe { brdf_atlas_model_fit_analytic(h, x, y, fitted.as_mut_ptr()) };
    assert_eq!(s, BrdfAtlasStatus::Ok);
    assert_eq!(got, unsafe { fitted.assume_init() });

    // The four files and nothing else (no temporaries).
    assert_eq!(
        names(&out_dir),
        [
            "pick.fit.json",
            "pick.glb",
            "pick.mitsuba.json",
            "pick.mtlx"
        ]
    );
    let gltf = glb_json(&out_dir.join("pick.glb"));
    let material = &gltf["materials"][0];
    assert_eq!(material["name"], "pick");
    let pbr = &material["pbrMetallicRoughness"];
    let [r, g, b] = got.base_color;
    assert_eq!(pbr["baseColorFactor"], serde_json::json!([r, g, b, 1.0]));
    assert_eq!(pbr["metallicFactor"].as_f64(), Some(got.metallic));
    assert_eq!(pbr["roughnessFactor"].as_f64(), Some(got.roughness));
    let specular = &material["extensions"]["KHR_materials_specular"];
    assert_eq!(specular["specularFactor"].as_f64(), Some(got.specular));
    assert_eq!(
        specular["specularColorFactor"],
        serde_json::json!(got.specular_color)
    );

    // The record, also in the glb's extras: the same numbers, no rendered error.
    let record = json(&out_dir.join("pick.fit.json"));
    assert_eq!(gltf["asset"]["extras"]["brdf_atlas"], record);
    let p = &record["parameters"];
    assert_eq!(p["base_color"], serde_json::json!(got.base_color));
    assert_eq!(p["metallic"].as_f64(), Some(got.metallic));
    assert_eq!(p["roughness"].as_f64(), Some(got.roughness));
    assert_eq!(p["specular"].as_f64(), Some(got.specular));
    assert_eq!(p["specular_color"], serde_json::json!(got.specular_color));
    assert_eq!(p["ior"].as_f64(), Some(got.ior));
    let errors = &record["table_error"];
    assert_eq!(errors["principled"].as_f64(), Some(got.table_error));
    assert_eq!(
        errors["single_lobe"].as_f64(),
        Some(got.single_lobe_table_error)
    );
    assert_eq!(
        errors["lambertian"].as_f64(),
        Some(got.lambertian_table_error)
    );
    assert!(record.get("rendered_error").is_none());
    assert_eq!(record["name"], "pick");
    let source = record["source"].as_str().unwrap();
    assert!(
        source.ends_with("m.atlas at (0.2000, -0.1000) (floor blend)"),
        "{source}"
    );

    let mitsuba = json(&out_dir.join("pick.mitsuba.json"));
    assert_eq!(mitsuba["type"], "principled");
    assert_eq!(mitsuba["roughness"].as_f64(), Some(got.roughness));
    assert_eq!(mitsuba["metallic"].as_f64(), Some(got.metallic));
    assert_eq!(
        mitsuba["base_color"]["value"],
        serde_json::json!(got.base_color)
    );
    let mtlx = std::fs::read_to_string(out_dir.join("pick.mtlx")).unwrap();
    assert!(
        mtlx.contains(r#"<standard_surface name="SR_pick""#),
        "{mtlx}"
    );
    assert!(mtlx.contains(&format!(
        r#"name="specular_roughness" type="float" value="{:.6}""#,
        got.roughness
    )));
    assert!(mtlx.contains(&format!("table error {:.4}", got.table_error)));

    // Bad arguments: a status, one line naming what is wrong, `out` and the
    // directory untouched.
    let before = names(&out_dir);
    let mut untouched = got;
    untouched.metallic = -7.0;
    let missing = c(tmp.path().join("missing").to_str().unwrap());
    let a_file = c(out_dir.join("pick.glb").to_str().unwrap());
    struct Case {
        what: &'static str,
        model: *const BrdfAtlasModel,
        x: f64,
        dir: *const c_char,
        stem: *const c_char,
        out: bool,
        status: BrdfAtlasStatus,
        says: &'static str,
    }
    let case = |what, model, x, dir, stem, status, says| Case {
        what,
        model,
        x,
        dir,
        stem,
        out: true,
        status,
        says,
    };
    use BrdfAtlasStatus::{InvalidArgument, Io, NullArgument};
    let (d, s) = (dir.as_ptr(), stem.as_ptr());
    let cases = [
        case("no model", null(), x, d, s, NullArgument, "`model` is NULL"),
        case("NaN", h, f64::NAN, d, s, InvalidArgument, "finite"),
        case(
            "infinite",
            h,
            f64::INFINITY,
            d,
            s,
            InvalidArgument,
            "finite",
        ),
        case("no dir", h, x, null(), s, NullArgument, "`dir` is NULL"),
        case("no stem", h, x, d, null(), NullArgument, "`stem` is NULL"),
        Case {
            out: false,
            ..case("no out", h, x, d, s, NullArgument, "`out` is NULL")
        },
        case(
            "missing dir",
            h,
            x,
            missing.as_ptr(),
            s,
            Io,
            "missing: is not a directory",
        ),
        case(
            "dir is a file",
            h,
            x,
            a_file.as_ptr(),
            s,
            Io,
            "pick.glb: is not a directory",
        ),
        case(
            "stem with a slash",
            h,
            x,
            d,
            c"../pick".as_ptr(),
            InvalidArgument,
            "\"../pick\": expected a file name",
        ),
        case(
            "hidden stem",
            h,
            x,
            d,
            c".pick".as_ptr(),
            InvalidArgument,
            "\".pick\": expected a file name",
        ),
        case(
            "empty stem",
            h,
            x,
            d,
            c"".as_ptr(),
            InvalidArgument,
            "`stem` is empty",
        ),
    ];
    for c in cases {
        let mut o = untouched;
        let out = if c.out { &raw mut o } else { null_mut() };
        let status = unsafe { brdf_atlas_model_export(c.model, c.x, y, c.dir, c.stem, out) };
        assert_eq!(status, c.status, "{}", c.what);
        let message = last_error();
        assert!(
            message.starts_with("brdf_atlas_model_export: ")
                && message.contains(c.says)
                && !message.contains('\n'),
            "{}: {message}",
            c.what
        );
        assert_eq!(o, untouched, "{}", c.what);
        assert_eq!(names(&out_dir), before, "{}", c.what);
    }
    unsafe { brdf_atlas_model_free(h) };
}
