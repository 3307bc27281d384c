//! An input truncated while `fit` reads it: the real binary stops itself at
//! the first step of its store pass (`BRDF_ATLAS_TEST_STOP_IN=store`), the
//! test truncates one input and lets it go on. It must print one line
//! naming the file and saying it changed while being read, exit 1, and
//! leave the old model and store as they were, with no temporary file.

mod common;

use std::fs::OpenOptions;
use std::path::Path;
use std::process::{Command, Stdio};

use common::{brdf_atlas, texts};

fn run_ok(args: &[&Path]) {
    let out = brdf_atlas(args);
    assert!(out.status.success(), "{args:?}: {}", texts(&out).1);
}

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect()
}

#[test]
fn an_input_truncated_during_fit_is_one_named_error_and_the_old_model_stays() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    let model = tmp.path().join("m.atlas");
    let store = tmp.path().join("m.atlas.store");
    run_ok(&[
        Path::new("synth"),
        Path::new("--count"),
        Path::new("6"),
        Path::new("--dims"),
        Path::new("8,8,16"),
        &data,
    ]);
    run_ok(&[Path::new("fit"), &data, Path::new("-o"), &model]);
    let before = [
        std::fs::read(&model).unwrap(),
        std::fs::read(&store).unwrap(),
    ];
    let mut inputs: Vec<_> = std::fs::read_dir(&data)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    inputs.sort();
    let victim = &inputs[2];

    // `--rebuild-store`: unchanged inputs would otherwise reuse the store
    // and never enter the pass.
    let child = Command::new(env!("CARGO_BIN_EXE_brdf-atlas"))
        .args([
            Path::new("fit"),
            &data,
            Path::new("-o"),
            &model,
            Path::new("--rebuild-store"),
        ])
        .env("BRDF_ATLAS_TEST_STOP_IN", "store")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = libc::pid_t::try_from(child.id()).unwrap();
    let mut status = 0;
    // SAFETY: our own child, not yet reaped; WUNTRACED only reports a stop
    // and leaves the child to be waited for again.
    let waited = unsafe { libc::waitpid(pid, &mut status, libc::WUNTRACED) };
    assert_eq!(waited, pid);
    assert!(
        libc::WIFSTOPPED(status),
        "the fit did not stop in its store pass"
    );
    OpenOptions::new()
        .write(true)
        .open(victim)
        .unwrap()
        .set_len(100)
        .unwrap();
    // SAFETY: a signal to our own stopped child.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGCONT) }, 0);
    let out = child.wait_with_output().unwrap();
    let (stdout, stderr) = texts(&out);
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    let lines: Vec<_> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].starts_with("error: ")
            && lines[0].contains(&victim.display().to_string())
            && lines[0].contains("changed while being read"),
        "{stderr}"
    );
    assert_eq!(
        [
            std::fs::read(&model).unwrap(),
            std::fs::read(&store).unwrap()
        ],
        before
    );
    assert_eq!(leftovers(tmp.path()), Vec::<String>::new());
}
