//! End-to-end tests of the `brdf-atlas` binary on generated data.

mod common;

use std::path::{Path, PathBuf};

use common::{binaries, brdf_atlas, reported, texts};

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn help_documents_every_subcommand() {
    let out = brdf_atlas(["--help"]);
    assert!(out.status.success());
    let (stdout, _) = texts(&out);
    for word in ["info", "synth", "demo", "MERL", "BRDF Explorer"] {
        assert!(stdout.contains(word), "--help lacks {word}:\n{stdout}");
    }
    for sub in ["info", "synth", "demo"] {
        let out = brdf_atlas([sub, "--help"]);
        assert!(out.status.success(), "{sub} --help");
        assert!(texts(&out).0.contains("Usage: brdf-atlas"), "{sub} --help");
    }
}

#[test]
fn no_arguments_is_a_usage_error() {
    let out = brdf_atlas::<[&str; 0], &str>([]);
    assert!(!out.status.success());
    let out = brdf_atlas(["info"]);
    assert!(!out.status.success());
    assert!(texts(&out).1.starts_with("error:"), "{}", texts(&out).1);
}

#[test]
fn synth_then_info_reports_dims_and_a_plausible_albedo() {
    // 16x16x32, not smaller: on a very coarse grid the albedo rule is crude
    // and a sharp metal's albedo can come out above 1 (1.03 for a brass at
    // 8x8x16, seed 5).
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("db");
    let out = brdf_atlas([
        "synth",
        "--dims",
        "16,16,32",
        "--count",
        "3",
        "--seed",
        "5",
        out_dir.to_str().unwrap(),
    ]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("wrote 3 materials (16x16x32"), "{stdout}");
    let files = binaries(&out_dir);
    assert_eq!(files.len(), 3);
    for f in &files {
        assert_eq!(
            std::fs::metadata(f).unwrap().len(),
            12 + 8 * 3 * 16 * 16 * 32
        );
    }

    let out = brdf_atlas(std::iter::once(PathBuf::from("info")).chain(files.clone()));
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    for f in &files {
        let r = reported(&stdout, f);
        assert_eq!(r.dims, "16x16x32");
        // Below-horizon bins are marked unmeasured, the same in every channel.
        assert!(r.invalid[0] > 0 && r.invalid == [r.invalid[0]; 3], "{r:?}");
        for a in r.albedo {
            assert!(a > 0.0 && a < 1.5, "{}: albedo {a}", f.display());
        }
    }
    // Small dims are fine, but not for BRDF Explorer: one warning, no error.
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].starts_with("warning:") && lines[0].contains("BRDF Explorer needs 90x90x180"),
        "{stderr}"
    );
}

#[test]
fn synth_is_deterministic_in_its_seed() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, seed: &str| {
        let d = dir.path().join(name);
        let out = brdf_atlas([
            "synth",
            "--dims",
            "4,4,8",
            "--count",
            "2",
            "--seed",
            seed,
            d.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", texts(&out).1);
        binaries(&d)
            .iter()
            .map(|p| std::fs::read(p).unwrap())
            .collect::<Vec<_>>()
    };
    let a = run("a", "7");
    assert_eq!(a, run("b", "7"));
    assert_ne!(a, run("c", "8"));
}

#[test]
fn synth_rejects_bad_dims_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("never");
    for bad in [
        "8,8", "8,8,16,2", "a,b,c", "0,8,16", "-8,8,16", "8,8,5000", "",
    ] {
        let out = brdf_atlas(["synth", "--dims", bad, out_dir.to_str().unwrap()]);
        let (_, stderr) = texts(&out);
        assert!(!out.status.success(), "--dims {bad:?} accepted");
        let first = stderr.lines().next().unwrap_or_default();
        assert!(first.starts_with("error:"), "{bad:?}: {stderr}");
        assert!(
            first.contains("--dims expects three positive integers like 90,90,180"),
            "{bad:?}: {stderr}"
        );
        assert!(!out_dir.exists(), "nothing is written on bad input");
    }
}

#[test]
fn synth_into_a_file_fails_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let file = write(dir.path(), "occupied", b"x");
    let out = brdf_atlas([
        "synth",
        "--dims",
        "4,4,8",
        "--count",
        "1",
        file.to_str().unwrap(),
    ]);
    let (_, stderr) = texts(&out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: ") && stderr.contains("occupied"),
        "{stderr}"
    );
}

// Broken MERL files through `info`, `locate` and `fit`: tests/hostile.rs.

#[test]
fn constant_table_albedo_is_pi_times_the_value() {
    // f = 0.1 / pi everywhere in every channel is Lambertian with albedo 0.1,
    // whatever the dims; the quadrature weights sum to pi (to 1e-3).
    let dir = tempfile::tempdir().unwrap();
    let scales = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];
    let (a, b, c) = (16, 16, 32);
    let n = a * b * c;
    let mut bytes: Vec<u8> = [a, b, c]
        .iter()
        .flat_map(|d: &i32| d.to_le_bytes())
        .collect();
    for s in scales {
        let raw = 0.1 / std::f64::consts::PI / s;
        bytes.extend(std::iter::repeat_n(raw.to_le_bytes(), n as usize).flatten());
    }
    let path = write(dir.path(), "lambert.binary", &bytes);
    let out = brdf_atlas([Path::new("info"), &path]);
    assert!(out.status.success(), "{}", texts(&out).1);
    let r = reported(&texts(&out).0, &path);
    for albedo in r.albedo {
        assert!((albedo - 0.1).abs() <= 2e-4, "{r:?}");
    }
}

#[test]
fn demo_synthesises_summarises_fits_maps_reconstructs_and_reports() {
    let dir = tempfile::tempdir().unwrap();
    let demo_dir = dir.path().join("demo");
    let out = brdf_atlas(["demo", "--count", "3", "--dir", demo_dir.to_str().unwrap()]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.is_empty(),
        "full-size tables need no warning: {stderr}"
    );
    let files = binaries(&demo_dir.join("merl"));
    assert_eq!(files.len(), 3);
    for f in &files {
        assert_eq!(std::fs::metadata(f).unwrap().len(), 34_992_012, "90x90x180");
        let name = f.file_stem().unwrap().to_str().unwrap();
        let row = stdout
            .lines()
            .find(|l| l.starts_with(name))
            .unwrap_or_else(|| panic!("{name} in\n{stdout}"));
        let albedo: Vec<f64> = row
            .split_whitespace()
            .skip(1)
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(albedo.len(), 3, "{row}");
        assert!(albedo.iter().all(|a| *a > 0.0 && *a < 1.5), "{row}");
    }
    for step in 1..=6 {
        assert!(stdout.contains(&format!("[{step}/6]")), "{stdout}");
    }
    // Everything it made is there and said to be there.
    for made in [
        "model.atlas",
        "model.atlas.store",
        "model.fields",
        "map.png",
        "map.json",
        "map.exr",
        "reconstructed.binary",
        "report/report.md",
    ] {
        assert!(demo_dir.join(made).is_file(), "{made}");
        assert!(stdout.contains(made), "{made} in {stdout}");
    }
    assert!(demo_dir.join("report/loo.png").is_file());
    assert_eq!(
        std::fs::metadata(demo_dir.join("reconstructed.binary"))
            .unwrap()
            .len(),
        34_992_012,
        "90x90x180"
    );
    assert!(
        stdout.contains(&demo_dir.display().to_string()),
        "says where the files went: {stdout}"
    );
}

#[test]
fn demo_needs_three_materials_for_a_map() {
    let dir = tempfile::tempdir().unwrap();
    let demo_dir = dir.path().join("demo");
    let out = brdf_atlas(["demo", "--count", "2", "--dir", demo_dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(texts(&out).1.contains("--count"), "{}", texts(&out).1);
    assert!(!demo_dir.exists());
}

#[test]
fn nbrdf_writes_the_neural_fits_as_merl_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("merl");
    let o = brdf_atlas([
        "nbrdf",
        out.to_str().unwrap(),
        "--only",
        "black-fabric,gold-metallic-paint",
        "--dims",
        "16,16,32",
    ]);
    let (stdout, stderr) = texts(&o);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stdout.contains("wrote 2 NBRDF materials (16x16x32"),
        "{stdout}"
    );
    // Real MERL files, darker and brighter as the materials are.
    let albedo = |name: &str| {
        let t = brdf_merl::MerlTable::read(out.join(format!("{name}.binary"))).unwrap();
        assert_eq!(t.dims(), brdf_merl::Dims::new(16, 16, 32).unwrap());
        brdf_merl::Quadrature::dense(t.dims(), 2).albedo(&t)
    };
    let (black, gold) = (albedo("black-fabric"), albedo("gold-metallic-paint"));
    assert!(black.iter().all(|&a| a > 0.0 && a < 0.05), "{black:?}");
    // Gold: red above blue, and far above black fabric.
    assert!(
        gold[0] > 2.0 * gold[2] && gold[0] > 5.0 * black[0],
        "{gold:?}"
    );
    // --list names all 100; --count takes the first in that order.
    let o = brdf_atlas(["nbrdf", "--list"]);
    let (list, _) = texts(&o);
    assert_eq!(list.lines().count(), 100);
    let first = list.lines().next().unwrap().to_owned();
    let few = dir.path().join("few");
    let o = brdf_atlas([
        "nbrdf",
        few.to_str().unwrap(),
        "--count",
        "1",
        "--dims",
        "4,4,8",
    ]);
    assert!(o.status.success());
    assert!(few.join(format!("{first}.binary")).is_file());
    // An unknown name: one line, exit 1, nothing written.
    let none = dir.path().join("none");
    let o = brdf_atlas([
        "nbrdf",
        none.to_str().unwrap(),
        "--only",
        "teflon,unobtainium",
    ]);
    let (_, stderr) = texts(&o);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("\"unobtainium\" is not one of the 100 NBRDF materials"),
        "{stderr}"
    );
    assert!(!none.exists());
}
