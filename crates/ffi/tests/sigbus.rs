//! What `brdf_atlas_model_open` does to the host's SIGBUS disposition: by
//! default the first open installs the library's handler; after
//! `brdf_atlas_set_sigbus_guard(0)`, or with BRDF_ATLAS_NO_SIGBUS_HANDLER=1,
//! it leaves the disposition as the host had it. The choice is made once a
//! process, so each case runs in a process of its own (this test binary
//! again, `CASE` naming the case and `MODEL` the model to open).

use std::ffi::CString;
use std::path::Path;
use std::process::Command;
use std::ptr::null_mut;

use brdf_atlas_c::*;
use brdf_atlas_core::{
    FitOptions, GplvmParams, NO_HANDLER_ENV, NoProgress, Precision, TransformKind, fit_dir,
};
use brdf_merl::{Dims, synth};

const CASE: &str = "BRDF_ATLAS_SIGBUS_CASE";
const MODEL: &str = "BRDF_ATLAS_SIGBUS_MODEL";

/// SIGBUS's handler now (or SIG_DFL / SIG_IGN).
fn sigbus_handler() -> usize {
    // SAFETY: a NULL new action only reads the current one into `old`.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        assert_eq!(libc::sigaction(libc::SIGBUS, std::ptr::null(), &mut old), 0);
        old.sa_sigaction
    }
}

/// The child: make the case's choice, open the model, check SIGBUS.
#[test]
fn case() {
    let (Ok(case), Ok(model)) = (std::env::var(CASE), std::env::var(MODEL)) else {
        return;
    };
    // Rust's runtime has its own SIGBUS handler (for stack overflows).
    let before = sigbus_handler();
    if case == "call" {
        assert_eq!(brdf_atlas_set_sigbus_guard(0), BrdfAtlasStatus::Ok);
    }
    let path = CString::new(model).unwrap();
    let mut h = null_mut();
    assert_eq!(
        unsafe { brdf_atlas_model_open(path.as_ptr(), &mut h) },
        BrdfAtlasStatus::Ok
    );
    let (installed, other) = (case == "default", i32::from(case != "default"));
    assert_eq!(sigbus_handler() != before, installed, "case {case}");
    // The choice is made: asking for the other one now is refused.
    assert_eq!(
        brdf_atlas_set_sigbus_guard(other),
        BrdfAtlasStatus::InvalidArgument
    );
    assert_eq!(brdf_atlas_set_sigbus_guard(1 - other), BrdfAtlasStatus::Ok);
    unsafe { brdf_atlas_model_free(h) };
}

fn run(model: &Path, case: &str, env: Option<&str>) {
    let mut child = Command::new(std::env::current_exe().unwrap());
    child.args(["--exact", "case", "--nocapture", "--test-threads=1"]);
    child
        .env(CASE, case)
        .env(MODEL, model)
        .env_remove(NO_HANDLER_ENV);
    if let Some(v) = env {
        child.env(NO_HANDLER_ENV, v);
    }
    let out = child.output().unwrap();
    assert!(
        out.status.success(),
        "case {case}: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn opening_a_model_installs_the_handler_unless_the_host_opted_out() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    synth::write_dir(&data, 5, Dims::new(6, 6, 12).unwrap(), 9).unwrap();
    let model = tmp.path().join("m.atlas");
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision: Precision::F64,
    };
    fit_dir(&data, &model, &options, &NoProgress).unwrap();
    run(&model, "default", None);
    run(&model, "call", None);
    run(&model, "env", Some("1"));
}
