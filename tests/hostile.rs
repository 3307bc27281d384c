//! Hostile input through the command-line tool: every broken file of the
//! generated corpus (`crates/hostile`: MERL files, models, stores) gives
//! exit status 1 and one `error:` line naming the file and what was wrong;
//! and every command that writes files, made to fail after it started,
//! leaves the old outputs byte for byte and no temporary file behind.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use brdf_atlas_hostile::{Case, merl_cases, model_cases};
use common::{binaries, brdf_atlas, fit, map, synth, texts};

/// Exit status 1 and one line, `error: ...`, that `case` accepts.
fn assert_refused(out: &Output, case: &Case, what: &str) {
    let (_, stderr) = texts(out);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{what} {}: {stderr}",
        case.label()
    );
    assert!(stderr.starts_with("error: "), "{what}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{what}: {stderr}");
    case.check_message(&stderr)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
}

/// A small fitted model (`model.atlas`, 4 materials of 8x8x16 in `merl/`).
fn fixture() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("merl");
    synth(&data, 4, "8,8,16", 5);
    let model = dir.path().join("model.atlas");
    fit(&data, &model, &[]);
    (dir, model)
}

#[test]
fn every_broken_merl_file_is_one_named_error_in_info_locate_and_fit() {
    let (dir, model) = fixture();
    let bad = dir.path().join("bad");
    std::fs::create_dir(&bad).unwrap();
    let cases = merl_cases(&bad);
    assert!(cases.len() >= 15);
    let good = binaries(&dir.path().join("merl"));
    // Good tables on the corpus's grid, so a fit meets each file's own
    // fault rather than a grid that differs from its neighbours'.
    synth(&dir.path().join("merl-4x4x8"), 3, "4,4,8", 5);
    let good_small = binaries(&dir.path().join("merl-4x4x8"));
    for case in &cases {
        let out = brdf_atlas([Path::new("info"), &case.path]);
        assert_refused(&out, case, "info");
        assert!(out.stdout.is_empty(), "no report for {}", case.label());
        let out = brdf_atlas([Path::new("locate"), &model, &case.path]);
        assert_refused(&out, case, "locate");
        // In a data directory beside good tables, the fit names it and
        // writes nothing.
        if case.path.is_file() {
            let data = dir.path().join(format!("data-{}", case.label()));
            std::fs::create_dir(&data).unwrap();
            for g in &good_small {
                std::fs::copy(g, data.join(g.file_name().unwrap())).unwrap();
            }
            let target = data.join(case.path.file_name().unwrap());
            std::fs::copy(&case.path, &target).unwrap();
            let out_model = dir.path().join("never.atlas");
            let out = brdf_atlas([Path::new("fit"), &data, Path::new("-o"), &out_model]);
            let case = Case {
                path: target.clone(),
                names: target,
                ..case.clone()
            };
            assert_refused(&out, &case, "fit");
            assert!(!out_model.exists() && !dir.path().join("never.atlas.store").exists());
            assert_eq!(leftovers(dir.path()), Vec::<String>::new());
        }
    }
    // All at once beside a good file: one error line each, in order, and the
    // good file is still reported.
    let mut args = vec![PathBuf::from("info"), good[0].clone()];
    args.extend(cases.iter().map(|c| c.path.clone()));
    let out = brdf_atlas(&args);
    let (stdout, stderr) = texts(&out);
    assert_eq!(out.status.code(), Some(1));
    assert!(stdout.contains(good[0].to_str().unwrap()), "{stdout}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("error: "))
        .collect();
    assert_eq!(errors.len(), cases.len(), "{stderr}");
    for (case, line) in cases.iter().zip(errors) {
        case.check_message(line).unwrap();
    }
}

#[test]
fn absurd_values_stop_every_transform_naming_the_file() {
    // Finite values whose squares overflow: the store pass names the file,
    // its first such value and the accepted range, before any Gram matrix
    // is formed, whatever the transform.
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("merl");
    synth(&data, 3, "4,4,8", 5);
    let absurd = data.join("absurd.binary");
    std::fs::write(&absurd, brdf_atlas_hostile::merl_bytes(4, 4, 8, 1e300)).unwrap();
    for transform in ["raw", "log", "rel-log"] {
        let model = dir.path().join("never.atlas");
        let out = brdf_atlas([
            Path::new("fit"),
            &data,
            Path::new("-o"),
            &model,
            Path::new("--transform"),
            Path::new(transform),
        ]);
        let (_, stderr) = texts(&out);
        assert_eq!(out.status.code(), Some(1), "{transform}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{transform}: {stderr}");
        assert!(
            stderr.starts_with(&format!(
                "error: {}: value 0 (red channel",
                absurd.display()
            )) && stderr.contains("beyond any physical one; expected at most 1e8")
                && !stderr.contains("invalid parameters"),
            "{transform}: {stderr}"
        );
        assert!(!model.exists());
        assert_eq!(leftovers(dir.path()), Vec::<String>::new());
    }
}

#[test]
fn a_directory_given_as_a_merl_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("a-directory.binary");
    std::fs::create_dir(&sub).unwrap();
    let out = brdf_atlas([Path::new("info"), &sub]);
    let case = Case::new(
        sub,
        "is a directory, expected a MERL .binary file",
        brdf_atlas_hostile::Status::Io,
    );
    assert_refused(&out, &case, "info");
}

#[test]
fn a_data_directory_names_what_it_leaves_out() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("merl");
    synth(&data, 3, "8,8,16", 2);
    std::fs::write(data.join("notes.txt"), "not a table").unwrap();
    std::fs::write(data.join(".DS_Store"), [0u8; 16]).unwrap();
    std::fs::create_dir(data.join("more.binary")).unwrap();
    let model = dir.path().join("m.atlas");
    let out = brdf_atlas([Path::new("fit"), &data, Path::new("-o"), &model]);
    let (_, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    let warnings: Vec<&str> = stderr.lines().collect();
    assert_eq!(warnings.len(), 3, "{stderr}");
    for (line, name, why) in [
        (warnings[0], ".DS_Store", "not a .binary file"),
        (warnings[1], "more.binary", "a directory"),
        (warnings[2], "notes.txt", "not a .binary file"),
    ] {
        assert!(line.starts_with("warning: "), "{line}");
        assert!(line.contains(name) && line.contains(why), "{line}");
    }
    // Nothing but such entries: an error naming the directory.
    let empty = dir.path().join("nothing");
    std::fs::create_dir(&empty).unwrap();
    std::fs::write(empty.join("notes.txt"), "not a table").unwrap();
    let out = brdf_atlas([Path::new("fit"), &empty, Path::new("-o"), &model]);
    let case = Case::new(
        empty,
        "no .binary MERL files found",
        brdf_atlas_hostile::Status::BadFile,
    );
    assert_refused(&out, &case, "fit");
}

#[test]
fn every_broken_model_or_store_is_one_named_error() {
    let (dir, model) = fixture();
    let bad = dir.path().join("bad");
    std::fs::create_dir(&bad).unwrap();
    let cases = model_cases(&bad, &model);
    assert!(cases.len() >= 30);
    let out_file = dir.path().join("never.binary");
    for (k, case) in cases.iter().enumerate() {
        let out = brdf_atlas([
            Path::new("reconstruct"),
            &case.path,
            Path::new("--at"),
            Path::new("0.1,0.2"),
            Path::new("-o"),
            &out_file,
        ]);
        assert_refused(&out, case, "reconstruct");
        assert!(!out_file.exists());
        // Every command opens a model the same way: the others on a few.
        if k % 8 == 0 {
            let png = dir.path().join("never.png");
            let out = map(&case.path, &png, &[]);
            assert_refused(&out, case, "map");
            assert!(!png.exists());
            let out = brdf_atlas([
                Path::new("eval"),
                &case.path,
                Path::new("--at"),
                Path::new("0,0"),
                Path::new("--wi"),
                Path::new("30,0"),
                Path::new("--wo"),
                Path::new("30,180"),
            ]);
            assert_refused(&out, case, "eval");
            let probe = &binaries(&dir.path().join("merl"))[0];
            let out = brdf_atlas([Path::new("locate"), &case.path, probe]);
            assert_refused(&out, case, "locate");
        }
    }
}

/// Temporary files (`.NAME.tmp-...`) anywhere under `dir`.
fn leftovers(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            found.extend(leftovers(&path));
        } else if path.to_string_lossy().contains(".tmp-") {
            found.push(path.display().to_string());
        }
    }
    found
}

/// Run `brdf-atlas args` with files limited to `kib` KiB: a write beyond
/// fails with "File too large" (SIGXFSZ ignored), in the middle of the run.
fn with_file_limit(kib: u64, args: &[&Path]) -> Output {
    Command::new("bash")
        .arg("-c")
        .arg(format!(r#"trap "" XFSZ; ulimit -f {kib}; exec "$0" "$@""#))
        .arg(env!("CARGO_BIN_EXE_brdf-atlas"))
        .args(args)
        .output()
        .expect("bash runs")
}

/// The bytes of `paths`, to compare before and after.
fn contents(paths: &[PathBuf]) -> Vec<Vec<u8>> {
    paths.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

fn assert_failed_writing(out: &Output, file: &str) {
    let (_, stderr) = texts(out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: ") && stderr.contains(file),
        "expected an error naming {file}: {stderr}"
    );
}

#[test]
fn a_failed_reconstruct_keeps_the_old_file() {
    let (dir, model) = fixture();
    let out_file = dir.path().join("new.binary");
    let ok = brdf_atlas([
        Path::new("reconstruct"),
        &model,
        Path::new("--at"),
        Path::new("0.3,0.3"),
        Path::new("-o"),
        &out_file,
    ]);
    assert!(ok.status.success(), "{}", texts(&ok).1);
    let before = contents(std::slice::from_ref(&out_file));
    // The table is 24 588 bytes: the limit stops it half way.
    let out = with_file_limit(
        12,
        &[
            Path::new("reconstruct"),
            &model,
            Path::new("--at"),
            Path::new("-0.5,0.2"),
            Path::new("-o"),
            &out_file,
        ],
    );
    assert_failed_writing(&out, "new.binary");
    assert!(
        texts(&out).1.contains("File too large"),
        "{}",
        texts(&out).1
    );
    assert_eq!(contents(std::slice::from_ref(&out_file)), before);
    assert_eq!(leftovers(dir.path()), Vec::<String>::new());
}

#[test]
fn a_failed_map_keeps_all_three_old_files() {
    let (dir, model) = fixture();
    let png = dir.path().join("map.png");
    let exr = dir.path().join("map.exr");
    let json = dir.path().join("map.json");
    let run = |size: &str, limit: Option<u64>| {
        let args = [
            Path::new("map"),
            &model,
            Path::new("-o"),
            &png,
            Path::new("--exr"),
            &exr,
            Path::new("--size"),
            Path::new(size),
            Path::new("--samples"),
            Path::new("16"),
        ];
        match limit {
            Some(kib) => with_file_limit(kib, &args),
            None => brdf_atlas(args),
        }
    };
    let ok = run("24", None);
    assert!(ok.status.success(), "{}", texts(&ok).1);
    let outputs = [png.clone(), exr.clone(), json.clone()];
    let before = contents(&outputs);
    // At 64x64 the PNG (a few KiB) and the sidecar fit under 12 KiB, the
    // EXR (48 KiB of floats) does not: it fails after the PNG is ready.
    let out = run("64", Some(12));
    assert_failed_writing(&out, "map.exr");
    assert_eq!(contents(&outputs), before, "no output replaced");
    assert_eq!(leftovers(dir.path()), Vec::<String>::new());
    // The sidecar's place is taken by a directory: everything is written,
    // nothing replaced.
    let side = dir.path().join("side.json");
    std::fs::create_dir(&side).unwrap();
    let out = map(
        &model,
        &png,
        &[
            &"--exr",
            &exr,
            &"--json",
            &side,
            &"--size",
            &"16",
            &"--samples",
            &"16",
        ],
    );
    assert_failed_writing(&out, "side.json");
    assert!(
        texts(&out).1.contains("is a directory"),
        "{}",
        texts(&out).1
    );
    assert_eq!(contents(&outputs), before, "no output replaced");
    assert_eq!(leftovers(dir.path()), Vec::<String>::new());
}

#[test]
fn a_failed_fit_keeps_the_old_model_and_store() {
    let (dir, model) = fixture();
    let pair = [model.clone(), dir.path().join("model.atlas.store")];
    let before = contents(&pair);
    // Another data set; the new store (f64, 4 materials: 98 KiB) exceeds
    // the limit while it is being built.
    let other = dir.path().join("other");
    synth(&other, 5, "8,8,16", 9);
    let out = with_file_limit(
        64,
        &[
            Path::new("fit"),
            &other,
            Path::new("-o"),
            &model,
            Path::new("--store-precision"),
            Path::new("f64"),
        ],
    );
    assert_failed_writing(&out, "model.atlas.store");
    assert_eq!(contents(&pair), before);
    assert_eq!(leftovers(dir.path()), Vec::<String>::new());
    // The model's place is taken by a directory: refused before either file
    // is replaced.
    let taken = dir.path().join("taken.atlas");
    std::fs::create_dir(&taken).unwrap();
    let out = brdf_atlas([Path::new("fit"), &other, Path::new("-o"), &taken]);
    assert_failed_writing(&out, "taken.atlas");
    assert!(!dir.path().join("taken.atlas.store").exists());
    assert_eq!(contents(&pair), before);
    assert_eq!(leftovers(dir.path()), Vec::<String>::new());
}

#[test]
fn a_failed_synth_replaces_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("db");
    synth(&db, 3, "4,4,8", 1);
    let files = binaries(&db);
    let before = contents(&files);
    // The same names at 8x8x16 (24 588 bytes each) under a 12 KiB limit.
    let args = |dims: &'static str| {
        [
            PathBuf::from("synth"),
            "--count".into(),
            "3".into(),
            "--dims".into(),
            dims.into(),
            db.clone(),
        ]
    };
    let a = args("8,8,16");
    let refs: Vec<&Path> = a.iter().map(PathBuf::as_path).collect();
    let out = with_file_limit(12, &refs);
    assert_failed_writing(&out, ".binary");
    assert_eq!(contents(&files), before);
    assert_eq!(leftovers(dir.path()), Vec::<String>::new());
    // One name taken by a directory: the others are written but not put
    // in place.
    let fourth = {
        synth(&dir.path().join("probe"), 4, "4,4,8", 1);
        binaries(&dir.path().join("probe"))[3]
            .file_name()
            .unwrap()
            .to_owned()
    };
    std::fs::create_dir(db.join(&fourth)).unwrap();
    let out = brdf_atlas([
        Path::new("synth"),
        Path::new("--count"),
        Path::new("4"),
        Path::new("--dims"),
        Path::new("8,8,16"),
        &db,
    ]);
    assert_failed_writing(&out, fourth.to_str().unwrap());
    assert_eq!(contents(&files), before);
    assert_eq!(leftovers(dir.path()), Vec::<String>::new());
}

/// Run the tool with `args`, killed if it takes longer than 20 s (a read of
/// a named pipe with no writer would wait forever).
fn within_seconds(args: &[&Path]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_brdf-atlas"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > std::time::Duration::from_secs(20) {
            child.kill().unwrap();
            panic!("brdf-atlas {args:?} did not finish in 20 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

#[test]
fn files_that_are_not_regular_files_are_named_at_once() {
    let (dir, model) = fixture();
    let fifo = dir.path().join("pipe.binary");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid C string; mkfifo only creates the node.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let socket = dir.path().join("socket.binary");
    let _listener = std::os::unix::net::UnixListener::bind(&socket).unwrap();
    let device = dir.path().join("zero.binary");
    std::os::unix::fs::symlink("/dev/zero", &device).unwrap();
    let kinds = [
        (&fifo, "a named pipe"),
        (&socket, "a socket"),
        (&device, "a character device"),
    ];
    for (path, kind) in kinds {
        let want = format!("{}: is {kind}, not a regular file", path.display());
        // As a MERL file, and as a model.
        for args in [
            vec![Path::new("info"), path.as_path()],
            vec![Path::new("locate"), model.as_path(), path.as_path()],
            vec![
                Path::new("map"),
                path.as_path(),
                Path::new("-o"),
                &dir.path().join("x.png"),
            ],
        ] {
            let out = within_seconds(&args);
            let (_, stderr) = texts(&out);
            assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
            assert_eq!(stderr.trim_end(), format!("error: {want}"), "{args:?}");
        }
        // Among a fit's inputs it stops the fit, named, as any invalid file does.
        let data = dir.path().join(format!("data-{}", kind.replace(' ', "-")));
        synth(&data, 3, "8,8,16", 7);
        let entry = data.join("zz.binary");
        std::os::unix::fs::symlink(path, &entry).unwrap();
        let out_model = dir.path().join("new.atlas");
        let out = within_seconds(&[Path::new("fit"), &data, Path::new("-o"), &out_model]);
        let (_, stderr) = texts(&out);
        assert_eq!(out.status.code(), Some(1), "fit: {stderr}");
        assert_eq!(
            stderr.trim_end(),
            format!("error: {}: is {kind}, not a regular file", entry.display()),
        );
        assert!(!out_model.exists());
        assert!(!dir.path().join("new.atlas.store").exists());
    }
    assert!(!dir.path().join("x.png").exists());
}
