//! `info` on realistic data: the MERL materials as fitted by a neural model,
//! written by `../shared/tools/nbrdf-to-merl` into the directory named by
//! `BRDF_ATLAS_NBRDF_DIR` (`.ci/run` sets it). Without the variable the test
//! says it is skipped; with it, it must find files and check every one.

mod common;

use std::path::{Path, PathBuf};

use common::{binaries, brdf_atlas, header_dims, reported, texts};

#[test]
fn info_reports_every_nbrdf_material() {
    let Some(dir) = std::env::var_os("BRDF_ATLAS_NBRDF_DIR") else {
        println!("skipped: BRDF_ATLAS_NBRDF_DIR not set");
        return;
    };
    let files = binaries(Path::new(&dir));
    assert!(
        !files.is_empty(),
        "BRDF_ATLAS_NBRDF_DIR={} holds no .binary files",
        PathBuf::from(&dir).display()
    );

    let out = brdf_atlas(std::iter::once(PathBuf::from("info")).chain(files.iter().cloned()));
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    for f in &files {
        let r = reported(&stdout, f);
        assert_eq!(r.dims, header_dims(f), "{}", f.display());
        // The tool marks bins with a direction below the horizon unmeasured:
        // some, the same in every channel.
        assert!(
            r.invalid[0] > 0 && r.invalid == [r.invalid[0]; 3],
            "{}: {r:?}",
            f.display()
        );
        for a in r.albedo {
            assert!(
                a > 0.0 && a < 1.5,
                "{}: albedo {a} out of (0, 1.5)",
                f.display()
            );
        }
    }
    println!(
        "checked {} materials in {}",
        files.len(),
        PathBuf::from(&dir).display()
    );
}
