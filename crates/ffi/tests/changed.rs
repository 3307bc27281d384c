//! A model's store changed on disk while a handle is open: through the C
//! functions from Rust, and from a C host with a SIGBUS handler of its own
//! (`tests/c/changed.c`, compiled here against `include/` and the static
//! library this test run built, as `tests/consumers.rs` does).

use std::ffi::{CStr, CString, OsString};
use std::fs::OpenOptions;
use std::path::{Path, PathBuf};
use std::process::Command;

use brdf_atlas_c::{
    BrdfAtlasStatus, brdf_atlas_last_error_message, brdf_atlas_model_free,
    brdf_atlas_model_latent_dim, brdf_atlas_model_open, brdf_atlas_model_reconstruct,
    brdf_atlas_model_table_len,
};
use brdf_atlas_core::{FitOptions, GplvmParams, NoProgress, Precision, TransformKind};
use brdf_atlas_core::{fit_dir, store_path_for};
use brdf_merl::{Dims, synth};

const DIMS: Dims = Dims {
    theta_h: 12,
    theta_d: 12,
    phi_d: 24,
};

/// A fitted model in a fresh directory named `name`.
fn fitted(name: &str) -> (PathBuf, PathBuf) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    let data = dir.join("data");
    synth::write_dir(&data, 6, DIMS, 5).unwrap();
    let model = dir.join("atlas.model");
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision: Precision::F32,
    };
    fit_dir(&data, &model, &options, &NoProgress).unwrap();
    (dir, model)
}

fn last_error() -> String {
    // SAFETY: the library's message is a valid NUL-terminated string.
    unsafe { CStr::from_ptr(brdf_atlas_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

#[test]
fn a_truncated_store_gives_bad_file_and_the_handle_refuses_until_reopened() {
    let (_, model) = fitted("ffi-changed-rust");
    let store = store_path_for(&model);
    let cpath = CString::new(model.to_str().unwrap()).unwrap();
    let mut m = std::ptr::null_mut();
    // SAFETY (all calls below): valid strings, out-pointers and buffers of
    // the lengths passed; `m` is a live handle until freed.
    unsafe {
        assert_eq!(
            brdf_atlas_model_open(cpath.as_ptr(), &mut m),
            BrdfAtlasStatus::Ok
        );
        let mut len = 0;
        assert_eq!(brdf_atlas_model_table_len(m, &mut len), BrdfAtlasStatus::Ok);
        let mut table = vec![0.0; len];
        let status = brdf_atlas_model_reconstruct(
            m,
            0.1,
            0.1,
            table.as_mut_ptr(),
            len,
            std::ptr::null_mut(),
        );
        assert_eq!(status, BrdfAtlasStatus::Ok);
        let want = table.clone();
        OpenOptions::new()
            .write(true)
            .open(&store)
            .unwrap()
            .set_len(64)
            .unwrap();
        table.fill(-5.0);
        let status = brdf_atlas_model_reconstruct(
            m,
            0.1,
            0.1,
            table.as_mut_ptr(),
            len,
            std::ptr::null_mut(),
        );
        assert_eq!(status, BrdfAtlasStatus::BadFile);
        let message = last_error();
        assert!(
            message.starts_with("brdf_atlas_model_reconstruct: ")
                && message.contains(store.to_str().unwrap())
                && message.contains("changed on disk while open"),
            "{message}"
        );
        assert!(
            table.iter().all(|v| *v == -5.0),
            "a failed call wrote the buffer"
        );
        let mut q = 0;
        assert_eq!(
            brdf_atlas_model_latent_dim(m, &mut q),
            BrdfAtlasStatus::BadFile
        );
        assert!(last_error().contains("changed on disk while open"));
        brdf_atlas_model_free(m);
        // Refitted (a new store put in place), the model opens and answers.
        let (_, again) = fitted("ffi-changed-rust");
        let cpath = CString::new(again.to_str().unwrap()).unwrap();
        assert_eq!(
            brdf_atlas_model_open(cpath.as_ptr(), &mut m),
            BrdfAtlasStatus::Ok
        );
        let status = brdf_atlas_model_reconstruct(
            m,
            0.1,
            0.1,
            table.as_mut_ptr(),
            len,
            std::ptr::null_mut(),
        );
        assert_eq!(status, BrdfAtlasStatus::Ok);
        assert_eq!(table, want);
        brdf_atlas_model_free(m);
    }
}

/// `deps/` of this build: where cargo put `libbrdf_atlas_c.a`.
fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    let dir = exe.parent().expect("a directory").to_path_buf();
    assert!(
        dir.join("libbrdf_atlas_c.a").is_file(),
        "libbrdf_atlas_c.a is not in {}",
        dir.display()
    );
    dir
}

#[test]
fn a_c_host_with_its_own_sigbus_handler_survives_every_change() {
    let (dir, model) = fitted("ffi-changed-c");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let exe = dir.join("changed-c");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let out = Command::new(&cc)
        .args([
            "-std=c11",
            "-O1",
            "-g",
            "-Wall",
            "-Wextra",
            "-pedantic",
            "-Werror",
            "-I",
        ])
        .arg(repo.join("include"))
        .arg(repo.join("crates/ffi/tests/c/changed.c"))
        .arg(lib_dir().join("libbrdf_atlas_c.a"))
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&exe)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cc}: {e}"));
    assert!(
        out.status.success(),
        "compiling changed.c:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let args: [OsString; 3] = [
        model.clone().into(),
        store_path_for(&model).into(),
        dir.into(),
    ];
    let out = Command::new(&exe).args(&args).output().unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(
        out.status.success() && stdout.contains("all checks passed"),
        "the C host ({}):\n--- stdout\n{stdout}\n--- stderr\n{stderr}",
        out.status
    );
}
