//! Killed runs leave nothing behind, with nothing run after them: every
//! command that writes files is stopped at a known moment of its writing
//! (`BRDF_ATLAS_TEST_STOP_IN`: the process stops itself there), killed with
//! SIGKILL, which no program can catch, and its output directory must be
//! exactly as before, hidden files included. The moments are the fit's
//! store pass (1.8 GB at full size) and, for every command, the instant
//! before its first output is named and put in place: every byte written,
//! nothing in place.
//!
//! A report is a directory, which cannot be made without a name: killed,
//! it leaves its temporary directory (`.NAME.tmp-PID-N`), which the next
//! run that writes beside it removes.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::stopped_at;

const BIN: &str = env!("CARGO_BIN_EXE_brdf-atlas");

fn run(args: &[&str]) {
    let out = Command::new(BIN).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Every name under `dir` (hidden ones too, recursively) with its length
/// and a hash of its content.
fn listing(dir: &Path) -> BTreeMap<PathBuf, (u64, u64)> {
    let mut all = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let e = e.unwrap();
            let rel = e.path().strip_prefix(dir).unwrap().to_path_buf();
            if e.file_type().unwrap().is_dir() {
                todo.push(e.path());
                all.insert(rel, (0, 0));
                continue;
            }
            let bytes = std::fs::read(e.path()).unwrap();
            let hash = bytes.iter().fold(0xcbf29ce484222325u64, |h, &b| {
                (h ^ u64::from(b)).wrapping_mul(0x100000001b3)
            });
            all.insert(rel, (bytes.len() as u64, hash));
        }
    }
    all
}

/// Run `args` until it stops itself at `phase`, then SIGKILL it. Panics if
/// it ends before reaching the phase: then nothing was killed mid-write.
fn kill_at(args: &[&str], phase: &str) {
    let mut child = stopped_at(args, phase, Stdio::null());
    child.kill().unwrap();
    let status = child.wait().unwrap();
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(status.signal(), Some(libc::SIGKILL), "{args:?}");
}

/// A directory with `materials` (small synthetic MERL files), a model of
/// them with its map, swatches and prepared lattice, a report, and a hidden
/// file of the user's: every output the commands below would replace.
struct Scene {
    dir: tempfile::TempDir,
}

impl Scene {
    fn new() -> Scene {
        let dir = tempfile::tempdir().unwrap();
        let scene = Scene { dir };
        run(&["synth", "--count", "8", "--dims", "16,16,32", &scene.p("m")]);
        run(&["fit", &scene.p("m"), "-o", &scene.p("a.atlas")]);
        run(&[
            "map",
            &scene.p("a.atlas"),
            "-o",
            &scene.p("map.png"),
            "--size",
            "64",
        ]);
        run(&["swatches", &scene.p("a.atlas"), "-o", &scene.p("sw.png")]);
        run(&["prepare", &scene.p("a.atlas")]);
        std::fs::write(scene.dir.path().join(".user"), b"mine").unwrap();
        scene
    }

    fn p(&self, name: &str) -> String {
        self.dir.path().join(name).to_str().unwrap().to_owned()
    }

    /// Kill `args` at `phase` and check that nothing changed.
    fn killed_changes_nothing(&self, args: &[&str], phase: &str) {
        let before = listing(self.dir.path());
        kill_at(args, phase);
        assert_eq!(
            listing(self.dir.path()),
            before,
            "{args:?} killed in {phase}"
        );
    }
}

#[test]
fn every_command_killed_while_writing_leaves_its_directory_as_it_was() {
    let s = Scene::new();
    let fit = ["fit", &s.p("m"), "-o", &s.p("a.atlas"), "--rebuild-store"];
    s.killed_changes_nothing(&fit, "store");
    s.killed_changes_nothing(&fit, "commit");
    let fresh = ["fit", &s.p("m"), "-o", &s.p("b.atlas")];
    s.killed_changes_nothing(&fresh, "store");
    s.killed_changes_nothing(&fresh, "commit");
    s.killed_changes_nothing(
        &["synth", "--count", "8", "--dims", "16,16,32", &s.p("m")],
        "commit",
    );
    s.killed_changes_nothing(
        &[
            "map",
            &s.p("a.atlas"),
            "-o",
            &s.p("map.png"),
            "--size",
            "64",
        ],
        "commit",
    );
    s.killed_changes_nothing(
        &["swatches", &s.p("a.atlas"), "-o", &s.p("sw.png")],
        "commit",
    );
    // The lattice would be rebuilt only without the current one.
    let lattice = s.dir.path().join("a.lattice");
    let kept = std::fs::read(&lattice).unwrap();
    std::fs::remove_file(&lattice).unwrap();
    s.killed_changes_nothing(&["prepare", &s.p("a.atlas")], "commit");
    std::fs::write(&lattice, kept).unwrap();
}

#[test]
fn a_killed_report_leaves_one_temporary_directory_the_next_run_removes() {
    let tmp = tempfile::tempdir().unwrap();
    let m = tmp.path().join("m");
    let m_arg = m.to_str().unwrap();
    run(&["synth", "--count", "6", "--dims", "12,12,24", m_arg]);
    let rep = tmp.path().join("rep");
    let args = ["report", m_arg, "-o", rep.to_str().unwrap(), "--quick"];
    run(&args);
    let before = listing(tmp.path());
    kill_at(&args, "commit");
    let after = listing(tmp.path());
    let new: Vec<&PathBuf> = after
        .keys()
        .filter(|p| !before.contains_key(*p) && p.components().count() == 1)
        .collect();
    assert_eq!(new.len(), 1, "{new:?}");
    let name = new[0].to_string_lossy();
    assert!(name.starts_with(".rep.tmp-"), "{name}");
    // Everything that was there is as it was.
    for (p, v) in &before {
        assert_eq!(after.get(p), Some(v), "{}", p.display());
    }
    // The next run beside it sweeps it away.
    run(&args);
    let swept = listing(tmp.path());
    assert!(swept.keys().all(|p| !p.starts_with(new[0])), "{swept:?}");
}
