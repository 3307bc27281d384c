//! The generated corpus of broken files (`crates/hostile`) through the C
//! ABI, called from Rust: every broken model or store refused by
//! `brdf_atlas_model_open`, every broken MERL file by
//! `brdf_atlas_model_locate`, each with its documented status, a one-line
//! message naming the file, and the out-parameter untouched. (The C
//! consumer runs the same corpus from C: tests/consumers.rs.)

use std::ffi::{CStr, CString};
use std::path::Path;
use std::ptr::null_mut;

use brdf_atlas_c::*;
use brdf_atlas_hostile::{Case, Status, merl_cases, model_cases, small_model};

fn status_of(s: Status) -> BrdfAtlasStatus {
    match s {
        Status::Io => BrdfAtlasStatus::Io,
        Status::BadFile => BrdfAtlasStatus::BadFile,
        Status::BadMerl => BrdfAtlasStatus::BadMerl,
    }
}

fn c_path(p: &Path) -> CString {
    CString::new(p.to_str().unwrap()).unwrap()
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(brdf_atlas_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

fn check(case: &Case, function: &str, got: BrdfAtlasStatus) {
    assert_eq!(
        got,
        status_of(case.status),
        "{}: {}",
        case.label(),
        last_error()
    );
    let message = last_error();
    assert!(
        message.starts_with(&format!("{function}: ")),
        "{}: {message}",
        case.label()
    );
    case.check_message(&message).unwrap();
}

#[test]
fn every_broken_model_and_store_is_refused_with_its_status() {
    let tmp = tempfile::tempdir().unwrap();
    let model = small_model(&tmp.path().join("seed"));
    let bad = tmp.path().join("bad");
    std::fs::create_dir(&bad).unwrap();
    let cases = model_cases(&bad, &model);
    assert!(cases.len() >= 30);
    for case in &cases {
        let sentinel = 0x5eed as *mut BrdfAtlasModel;
        let mut out = sentinel;
        let s = unsafe { brdf_atlas_model_open(c_path(&case.path).as_ptr(), &mut out) };
        check(case, "brdf_atlas_model_open", s);
        assert_eq!(out, sentinel, "{}: out-parameter written", case.label());
    }
    // The good model still opens, and the message is cleared.
    let mut h = null_mut();
    let s = unsafe { brdf_atlas_model_open(c_path(&model).as_ptr(), &mut h) };
    assert_eq!(s, BrdfAtlasStatus::Ok);
    assert_eq!(last_error(), "");
    unsafe { brdf_atlas_model_free(h) };
}

#[test]
fn every_broken_merl_file_is_refused_by_locate() {
    let tmp = tempfile::tempdir().unwrap();
    let model = small_model(&tmp.path().join("seed"));
    let mut h = null_mut();
    assert_eq!(
        unsafe { brdf_atlas_model_open(c_path(&model).as_ptr(), &mut h) },
        BrdfAtlasStatus::Ok
    );
    let bad = tmp.path().join("bad");
    std::fs::create_dir(&bad).unwrap();
    let cases = merl_cases(&bad);
    assert!(cases.len() >= 15);
    for case in &cases {
        let mut loc = BrdfAtlasLocation {
            x: 7.0,
            y: 7.0,
            rmse: 7.0,
            spread: 7.0,
            nearest: 7,
        };
        let s = unsafe { brdf_atlas_model_locate(h, c_path(&case.path).as_ptr(), &mut loc) };
        check(case, "brdf_atlas_model_locate", s);
        assert!(
            [loc.x, loc.y, loc.rmse, loc.spread] == [7.0; 4] && loc.nearest == 7,
            "{}: location written",
            case.label()
        );
    }
    unsafe { brdf_atlas_model_free(h) };
}
