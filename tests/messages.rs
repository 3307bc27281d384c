//! The messages a user reads when something is off: one line on stderr,
//! exit 1, naming the file and what was expected.

use std::path::Path;
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_brdf-atlas");

fn brdf_atlas(args: &[&Path]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// The one line on stderr of a refused run.
fn refused(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    stderr.trim_end().to_string()
}

fn p(s: &str) -> &Path {
    Path::new(s)
}

/// A small fitted model in `dir`: `dir/a.model`.
fn small_model(dir: &Path) -> std::path::PathBuf {
    let m = dir.join("m");
    let out = brdf_atlas(&[
        p("synth"),
        p("--count"),
        p("4"),
        p("--dims"),
        p("8,8,16"),
        &m,
    ]);
    assert!(out.status.success());
    let model = dir.join("a.model");
    let out = brdf_atlas(&[p("fit"), &m, p("-o"), &model]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    model
}

#[test]
fn map_refuses_an_output_whose_extension_is_not_its_format() {
    let dir = tempfile::tempdir().unwrap();
    let model = small_model(dir.path());
    let before: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    let jpg = dir.path().join("x.jpg");
    let msg = refused(&brdf_atlas(&[p("map"), &model, p("-o"), &jpg]));
    assert!(
        msg.starts_with(&format!("error: {}: ", jpg.display())) && msg.contains(".png"),
        "{msg}"
    );
    let tif = dir.path().join("x.tif");
    let png = dir.path().join("x.png");
    let msg = refused(&brdf_atlas(&[
        p("map"),
        &model,
        p("-o"),
        &png,
        p("--exr"),
        &tif,
    ]));
    assert!(
        msg.starts_with(&format!("error: {}: ", tif.display())) && msg.contains(".exr"),
        "{msg}"
    );
    // Nothing written.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), before.len());
    // Any case of the right extension is fine.
    let upper = dir.path().join("X.PNG");
    let out = brdf_atlas(&[p("map"), &model, p("-o"), &upper, p("--size"), p("16")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_text_file_named_binary_is_called_text() {
    let dir = tempfile::tempdir().unwrap();
    let notes = dir.path().join("notes.binary");
    std::fs::write(&notes, "measured on 2024-03-01\nsee README\n").unwrap();
    let msg = refused(&brdf_atlas(&[p("info"), &notes]));
    assert!(
        msg.starts_with(&format!(
            "error: {}: not a MERL file (it looks like text)",
            notes.display()
        )),
        "{msg}"
    );
}

#[test]
fn an_invalid_file_is_named_even_when_too_few_materials_remain() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m");
    std::fs::create_dir(&m).unwrap();
    let bad = m.join("bad.binary");
    std::fs::write(&bad, b"\x04\0\0\0\x04\0\0\0\x08\0\0\0 too short").unwrap();
    let model = dir.path().join("a.model");
    let msg = refused(&brdf_atlas(&[p("fit"), &m, p("-o"), &model]));
    assert!(
        msg.starts_with(&format!("error: {}: ", bad.display())),
        "{msg}"
    );
    // With the invalid file gone, the count is what is wrong.
    std::fs::remove_file(&bad).unwrap();
    let out = brdf_atlas(&[
        p("synth"),
        p("--count"),
        p("2"),
        p("--dims"),
        p("8,8,16"),
        &m,
    ]);
    assert!(out.status.success());
    let msg = refused(&brdf_atlas(&[p("fit"), &m, p("-o"), &model]));
    assert!(
        msg.contains("needs more materials than latent dimensions"),
        "{msg}"
    );
    assert!(!model.exists());
}
