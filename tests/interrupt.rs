//! Interrupted runs leave nothing behind: the real binary is stopped by
//! SIGINT, SIGTERM or SIGKILL, and the output directory, hidden files
//! included, must be exactly as before (or exactly the complete new
//! output). Each test signals the run at known moments first: the run stops
//! itself there (`BRDF_ATLAS_TEST_STOP_IN`: a phase of the work, or
//! `commit`, as its outputs are about to go in), the signal is sent while
//! it is stopped, and it goes on, so the signal certainly arrives before the
//! work is done and the run must say it was interrupted. Then the same at
//! delays (the store pass, the search, the save, or after it finished: all
//! are valid), for the moments between. After a SIGKILL the directory is
//! as before once the next run into it has finished.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::Duration;

use common::stopped_at;

const BIN: &str = env!("CARGO_BIN_EXE_brdf-atlas");

/// Materials enough that a fit lasts about half a second, split between
/// the store pass and the search (which grows with the count cubed).
const SYNTH: [&str; 5] = ["synth", "--count", "60", "--dims", "32,32,64"];

fn run(args: &[&str]) {
    let out = Command::new(BIN).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// One materials directory for every test (read only).
fn materials() -> &'static Path {
    static DIR: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    &DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let m = dir.path().join("m");
        run(&[&SYNTH[..], &[m.to_str().unwrap()]].concat());
        (dir, m)
    })
    .1
}

/// Every name in `dir` (hidden ones too) with its content's length and hash.
fn listing(dir: &Path) -> BTreeMap<String, (u64, u64)> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let mut bytes = if e.file_type().unwrap().is_file() {
                std::fs::read(e.path()).unwrap()
            } else {
                Vec::new()
            };
            // A model file records which file its store is (inode, times):
            // the one thing a finished re-fit writes differently.
            if e.path().extension().is_some_and(|x| x == "model") {
                let mut json: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                let identity = json["store"]
                    .as_object_mut()
                    .and_then(|s| s.remove("identity"));
                assert!(
                    identity.is_some(),
                    "{}: no store identity",
                    e.path().display()
                );
                bytes = serde_json::to_vec(&json).unwrap();
            }
            let hash = bytes.iter().fold(0xcbf29ce484222325u64, |h, &b| {
                (h ^ u64::from(b)).wrapping_mul(0x100000001b3)
            });
            (
                e.file_name().to_string_lossy().into_owned(),
                (bytes.len() as u64, hash),
            )
        })
        .collect()
}

fn names(l: &BTreeMap<String, (u64, u64)>) -> Vec<&String> {
    l.keys().collect()
}

fn spawn(args: &[&str]) -> Child {
    Command::new(BIN)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Send `signal` after `delay`; the exit code (None if killed) and stderr.
fn interrupt(child: Child, delay: Duration, signal: libc::c_int) -> (Option<i32>, String) {
    std::thread::sleep(delay);
    let pid = libc::pid_t::try_from(child.id()).unwrap();
    // SAFETY: our own child, not yet waited for, so the pid is still its.
    unsafe { libc::kill(pid, signal) };
    let out = child.wait_with_output().unwrap();
    eprintln!("signal {signal} after {delay:?}: {:?}", out.status);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Run `args` until it stops itself at `phase`, send `signal` while it is
/// stopped, then let it go on: the exit code and stderr. Panics if the run
/// ends before it reaches the phase (the signal would come too late).
fn interrupt_at(args: &[&str], phase: &str, signal: libc::c_int) -> (Option<i32>, String) {
    let child = stopped_at(args, phase, Stdio::piped());
    let pid = libc::pid_t::try_from(child.id()).unwrap();
    // SAFETY: our own child, stopped and not yet waited for.
    unsafe {
        libc::kill(pid, signal);
        libc::kill(pid, libc::SIGCONT);
    }
    let out = child.wait_with_output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Signalled at `phase` (see [`interrupt_at`]): the run must say it was
/// interrupted, and leave `before` (or, signalled as its outputs went in,
/// exactly `complete`).
#[allow(clippy::too_many_arguments)]
fn check_interrupted_at(
    args: &[&str],
    phase: &str,
    signal: libc::c_int,
    expected_code: i32,
    dir: &Path,
    before: &BTreeMap<String, (u64, u64)>,
    complete: &BTreeMap<String, (u64, u64)>,
) {
    let (code, stderr) = interrupt_at(args, phase, signal);
    let what = format!("{} signalled in {phase}", args[0]);
    if phase == "commit" {
        // The outputs go in whole first; the run may then end before the
        // signal is handled, which is right too: all of it is in place.
        assert!(
            matches!(code, Some(0)) || code == Some(expected_code),
            "{what}: {stderr}"
        );
        assert!(!stderr.contains("nothing was changed"), "{what}: {stderr}");
    } else {
        assert_eq!(code, Some(expected_code), "{what}: {stderr}");
    }
    check_interrupted(&what, code, &stderr, expected_code, dir, before, complete);
}

/// After an interrupt: either it finished first (exit 0, complete output)
/// or it was stopped with one line and the listing is exactly `before`.
fn check_interrupted(
    what: &str,
    code: Option<i32>,
    stderr: &str,
    expected_code: i32,
    dir: &Path,
    before: &BTreeMap<String, (u64, u64)>,
    complete: &BTreeMap<String, (u64, u64)>,
) {
    let after = listing(dir);
    match code {
        Some(0) => assert_eq!(names(&after), names(complete), "{what}: finished"),
        Some(c) if c == expected_code => {
            let lines: Vec<&str> = stderr.lines().collect();
            assert_eq!(lines.len(), 1, "{what}: one line on stderr: {stderr:?}");
            if lines[0] == "interrupted; nothing was changed" {
                assert_eq!(&after, before, "{what}: nothing was changed");
            } else {
                // Stopped after the outputs were in place.
                assert!(lines[0].starts_with("interrupted; "), "{what}: {stderr:?}");
                assert_eq!(names(&after), names(complete), "{what}: complete");
            }
        }
        other => panic!("{what}: exit {other:?}, stderr {stderr:?}"),
    }
}

fn delays() -> impl Iterator<Item = Duration> {
    [20, 100, 200, 300, 420]
        .into_iter()
        .map(Duration::from_millis)
}

/// A fit that builds its store every time (a re-fit of unchanged inputs
/// would use the last one's again, and be over before the signal).
fn fit_args<'a>(m: &'a Path, model: &'a Path) -> [&'a str; 5] {
    [
        "fit",
        m.to_str().unwrap(),
        "-o",
        model.to_str().unwrap(),
        "--rebuild-store",
    ]
}

#[test]
fn fit_interrupted_by_sigint_or_sigterm_changes_nothing() {
    let m = materials();
    let out = tempfile::tempdir().unwrap();
    let model = out.path().join("a.model");
    run(&fit_args(m, &model));
    let before = listing(out.path());
    assert_eq!(names(&before), ["a.fields", "a.model", "a.model.store"]);
    let args = fit_args(m, &model);
    for (phase, signal, code) in [
        ("store", libc::SIGINT, 130),
        ("optimise", libc::SIGTERM, 143),
        ("commit", libc::SIGINT, 130),
    ] {
        check_interrupted_at(&args, phase, signal, code, out.path(), &before, &before);
        assert_eq!(listing(out.path()), before, "fit signalled in {phase}");
    }
    for (i, delay) in delays().enumerate() {
        let (signal, code) = if i % 2 == 0 {
            (libc::SIGINT, 130)
        } else {
            (libc::SIGTERM, 143)
        };
        let (got, stderr) = interrupt(spawn(&fit_args(m, &model)), delay, signal);
        let what = format!("fit, signal {signal} after {delay:?}");
        check_interrupted(&what, got, &stderr, code, out.path(), &before, &before);
        // The fit is deterministic: a finished re-fit writes the same bytes
        // (but for the store's identity in the model file).
        assert_eq!(listing(out.path()), before, "{what}");
    }
}

#[test]
fn fit_killed_leaves_nothing_once_the_next_run_is_done() {
    let m = materials();
    let out = tempfile::tempdir().unwrap();
    let model = out.path().join("a.model");
    run(&fit_args(m, &model));
    let before = listing(out.path());
    // What killed runs left, whatever the moments below hit: a temporary
    // store of a process that is gone (no pid reaches 2^31 - 1000) and a
    // report's temporary directory. A user's file that only looks alike stays.
    let dead = out.path().join(".a.model.store.tmp-2147482647-0");
    std::fs::write(&dead, b"partial").unwrap();
    let dead_dir = out.path().join(".report.tmp-2147482647-1");
    std::fs::create_dir(&dead_dir).unwrap();
    std::fs::write(dead_dir.join("index.html"), b"partial").unwrap();
    let user = out.path().join(".a.model.tmp-mine");
    std::fs::write(&user, b"keep").unwrap();
    run(&fit_args(m, &model));
    assert!(!dead.exists() && !dead_dir.exists() && user.exists());
    std::fs::remove_file(&user).unwrap();
    assert_eq!(listing(out.path()), before);
    for delay in delays() {
        let (code, _) = interrupt(spawn(&fit_args(m, &model)), delay, libc::SIGKILL);
        assert!(matches!(code, None | Some(0)), "{delay:?}: {code:?}");
        // What was there stays usable: the old pair or the new one.
        let after = listing(out.path());
        assert!(after.contains_key("a.model") && after.contains_key("a.model.store"));
        run(&fit_args(m, &model));
        assert_eq!(listing(out.path()), before, "killed after {delay:?}");
    }
}

#[test]
fn synth_interrupted_writes_all_files_or_none() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("m");
    let dir_arg = dir.to_str().unwrap();
    let complete = listing(materials());
    std::fs::create_dir(&dir).unwrap();
    let empty = listing(&dir);
    let args = [&SYNTH[..], &[dir_arg]].concat();
    // Signalled as the files go in: they all do.
    check_interrupted_at(&args, "commit", libc::SIGINT, 130, &dir, &empty, &complete);
    assert_eq!(listing(&dir), complete);
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::create_dir(&dir).unwrap();
    for delay in [20, 150, 300].map(Duration::from_millis) {
        let (code, stderr) = interrupt(
            spawn(&[&SYNTH[..], &[dir_arg]].concat()),
            delay,
            libc::SIGINT,
        );
        let what = format!("synth after {delay:?}");
        check_interrupted(&what, code, &stderr, 130, &dir, &empty, &complete);
        if code == Some(0) {
            assert_eq!(listing(&dir), complete, "{what}");
            return;
        }
    }
}

#[test]
fn synth_and_nbrdf_interrupted_remove_only_the_empty_directories_they_made() {
    let out = tempfile::tempdir().unwrap();
    let nbrdf = ["nbrdf", "--count", "3", "--dims", "16,16,32"];
    for args in [&SYNTH[..], &nbrdf[..]] {
        // Two levels the run makes: stopped as its first file is staged,
        // it removes both.
        let made = out.path().join("new");
        let dir = made.join("m");
        let with_dir = [args, &[dir.to_str().unwrap()]].concat();
        let (code, stderr) = interrupt_at(&with_dir, "stage", libc::SIGINT);
        assert_eq!(code, Some(130), "{args:?}: {stderr}");
        assert_eq!(
            stderr.trim(),
            "interrupted; nothing was changed",
            "{args:?}"
        );
        assert!(!made.exists(), "{args:?} left {:?}", listing(out.path()));
        // A directory that was there stays, as it was.
        let kept = out.path().join("kept");
        std::fs::create_dir(&kept).unwrap();
        let into_kept = [args, &[kept.to_str().unwrap()]].concat();
        let (code, stderr) = interrupt_at(&into_kept, "stage", libc::SIGINT);
        assert_eq!(code, Some(130), "{args:?}: {stderr}");
        assert!(kept.is_dir() && listing(&kept).is_empty(), "{args:?}");
        std::fs::remove_dir(&kept).unwrap();
    }
}

#[test]
fn synth_killed_leaves_nothing_once_the_next_run_is_done() {
    let out = tempfile::tempdir().unwrap();
    let dir: PathBuf = out.path().join("m");
    let dir_arg = dir.to_str().unwrap();
    let args = [&SYNTH[..], &[dir_arg]].concat();
    let (code, _) = interrupt(spawn(&args), Duration::from_millis(300), libc::SIGKILL);
    assert!(matches!(code, None | Some(0)), "{code:?}");
    run(&args);
    assert_eq!(listing(&dir), listing(materials()));
}

#[test]
fn map_interrupted_changes_nothing() {
    let m = materials();
    let out = tempfile::tempdir().unwrap();
    let model = out.path().join("a.model");
    run(&fit_args(m, &model));
    let png = out.path().join("map.png");
    let args = [
        "map",
        model.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "256",
    ];
    run(&args);
    let before = listing(out.path());
    check_interrupted_at(
        &args,
        "map",
        libc::SIGINT,
        130,
        out.path(),
        &before,
        &before,
    );
    assert_eq!(listing(out.path()), before, "map signalled while drawing");
    for delay in [50, 300].map(Duration::from_millis) {
        let (code, stderr) = interrupt(spawn(&args), delay, libc::SIGINT);
        let what = format!("map after {delay:?}");
        check_interrupted(&what, code, &stderr, 130, out.path(), &before, &before);
        assert_eq!(listing(out.path()), before, "{what}");
    }
}

#[test]
fn prepare_interrupted_leaves_no_lattice() {
    let m = materials();
    let out = tempfile::tempdir().unwrap();
    let model = out.path().join("a.atlas");
    run(&fit_args(m, &model));
    let before = listing(out.path());
    let args = ["prepare", model.to_str().unwrap()];
    run(&args);
    let complete = listing(out.path());
    std::fs::remove_file(out.path().join("a.lattice")).unwrap();
    let phase = "lattice, the cells' last nodes";
    check_interrupted_at(
        &args,
        phase,
        libc::SIGINT,
        130,
        out.path(),
        &before,
        &complete,
    );
    assert_eq!(
        listing(out.path()),
        before,
        "prepare signalled while building"
    );
    check_interrupted_at(
        &args,
        "commit",
        libc::SIGINT,
        130,
        out.path(),
        &before,
        &complete,
    );
    assert_eq!(names(&listing(out.path())), names(&complete));
    std::fs::remove_file(out.path().join("a.lattice")).unwrap();
    for delay in [50, 300].map(Duration::from_millis) {
        let (code, stderr) = interrupt(spawn(&args), delay, libc::SIGINT);
        let what = format!("prepare after {delay:?}");
        check_interrupted(&what, code, &stderr, 130, out.path(), &before, &complete);
        let _ = std::fs::remove_file(out.path().join("a.lattice"));
    }
}

#[test]
fn report_interrupted_keeps_the_old_report_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let m = tmp.path().join("m");
    let m_arg = m.to_str().unwrap();
    run(&["synth", "--count", "6", "--dims", "12,12,24", m_arg]);
    let rep = tmp.path().join("rep");
    let args = ["report", m_arg, "-o", rep.to_str().unwrap(), "--quick"];
    run(&args);
    let (top, inside) = (listing(tmp.path()), listing(&rep));
    check_interrupted_at(&args, "loo", libc::SIGINT, 130, tmp.path(), &top, &top);
    assert_eq!(
        listing(&rep),
        inside,
        "report signalled in its leave-one-out pass"
    );
    for delay in [50, 400].map(Duration::from_millis) {
        let (code, stderr) = interrupt(spawn(&args), delay, libc::SIGINT);
        let what = format!("report after {delay:?}");
        check_interrupted(&what, code, &stderr, 130, tmp.path(), &top, &top);
        // The report has timings, so a finished one differs in content.
        if code == Some(0) || !stderr.contains("nothing was changed") {
            assert_eq!(names(&listing(&rep)), names(&inside), "{what}");
        } else {
            assert_eq!(listing(&rep), inside, "{what}");
        }
    }
}
