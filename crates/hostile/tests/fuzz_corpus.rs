//! Replays every input the fuzzers kept (`fuzz/corpus/TARGET/*`) and every
//! crash they found (`fuzz/artifacts/TARGET/*`) through the fuzz targets'
//! own code: each must give a clean accept or refuse, no panic. CI runs
//! this, not the fuzzers.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use brdf_atlas_hostile::{fuzz, small_model};

const TARGETS: [&str; 4] = ["merl", "model", "store", "sidecar"];

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz")
}

fn inputs(target: &str) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for kind in ["corpus", "artifacts"] {
        if let Ok(entries) = std::fs::read_dir(fuzz_dir().join(kind).join(target)) {
            files.extend(entries.map(|e| e.unwrap().path()).filter(|p| p.is_file()));
        }
    }
    files.sort();
    files
}

#[test]
fn every_saved_fuzz_input_is_accepted_or_refused_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let seed = fuzz::SeedModel::new(&tmp.path().join("seed"));
    let mut failures = Vec::new();
    for target in TARGETS {
        let files = inputs(target);
        assert!(
            files.len() >= 5,
            "fuzz/corpus/{target} holds {} inputs; write the seeds with \
             `cargo run --release -p brdf-atlas-hostile --example fuzz_seeds -- fuzz/corpus`",
            files.len()
        );
        let mut accepted = 0;
        for file in &files {
            let data = std::fs::read(file).unwrap();
            let run = || match target {
                "merl" => fuzz::merl(tmp.path(), &data),
                "model" => fuzz::model(&seed, &data),
                "store" => fuzz::store(tmp.path(), &data),
                _ => fuzz::sidecar(&data),
            };
            match catch_unwind(AssertUnwindSafe(run)) {
                Ok(ok) => accepted += ok as usize,
                Err(_) => failures.push(file.display().to_string()),
            }
        }
        // The corpus still reaches past the checks: some input is valid (a
        // seed the current code no longer accepts means stale seeds).
        assert!(
            accepted > 0,
            "no input of fuzz/corpus/{target} is accepted any more: regenerate the seeds"
        );
        println!("{target}: {} inputs, {accepted} accepted", files.len());
    }
    assert!(failures.is_empty(), "panicked on: {failures:#?}");
}

#[test]
fn every_broken_sidecar_is_refused_with_a_named_reason() {
    // No command reads a sidecar: the library's reader is the interface.
    let tmp = tempfile::tempdir().unwrap();
    let model = small_model(&tmp.path().join("seed"));
    let good = brdf_atlas_hostile::small_sidecar(&model, &tmp.path().join("map.json"));
    assert!(fuzz::sidecar(&std::fs::read(&good).unwrap()));
    let cases = tmp.path().join("cases");
    std::fs::create_dir_all(&cases).unwrap();
    let cases = brdf_atlas_hostile::sidecar_cases(&cases, &good);
    assert!(cases.len() >= 10);
    for c in cases {
        let e = brdf_atlas_pictures::map_picture::read_sidecar(&c.path)
            .expect_err(&c.label())
            .to_string();
        c.check_message(&e).unwrap();
        assert!(!fuzz::sidecar(&std::fs::read(&c.path).unwrap()));
    }
}
