//! What opening a map does to SIGBUS's disposition: by default it installs
//! the library's handler; opted out (by a call or by the environment
//! variable) it leaves the disposition as it was. The choice is made once
//! a process, so each case runs in a process of its own: this test binary
//! again, with `CASE` naming the case.

use std::process::Command;

use brdf_mapguard::{GuardedMap, NO_HANDLER_ENV, Watch, set_sigbus_guard};

const CASE: &str = "BRDF_MAPGUARD_DISPOSITION_CASE";

/// SIGBUS's action now: its handler (or SIG_DFL / SIG_IGN) and flags.
fn sigbus_action() -> (usize, i32) {
    // SAFETY: a NULL new action only reads the current one into `old`.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        assert_eq!(libc::sigaction(libc::SIGBUS, std::ptr::null(), &mut old), 0);
        (old.sa_sigaction, old.sa_flags)
    }
}

/// The child: make the case's choice, open a map, and check the action.
#[test]
fn case() {
    let Ok(case) = std::env::var(CASE) else {
        return;
    };
    // Rust's runtime has its own SIGBUS handler (for stack overflows).
    let before = sigbus_action();
    match case.as_str() {
        "call" | "truncate" => assert!(set_sigbus_guard(false)),
        "env" | "default" => {}
        other => panic!("unknown case {other}"),
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f");
    std::fs::write(&path, vec![1u8; 1 << 16]).unwrap();
    let map = GuardedMap::open(&path, Watch::Descriptor).unwrap();
    assert_eq!(map[0], 1);
    let after = sigbus_action();
    if case == "truncate" {
        // Unguarded: a read past the new end raises SIGBUS, which kills.
        std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .unwrap()
            .set_len(0)
            .unwrap();
        let v = std::hint::black_box(&map[..])[(1 << 16) - 1];
        panic!("read {v} past the end of a truncated file");
    }
    if case == "default" {
        assert_ne!(after.0, before.0, "a handler is installed");
        assert_ne!(after.1 & libc::SA_SIGINFO, 0);
        // Too late to opt out now; opting in again is what was chosen.
        assert!(!set_sigbus_guard(false));
        assert!(set_sigbus_guard(true));
    } else {
        assert_eq!(after, before, "SIGBUS is left as it was");
        assert!(!set_sigbus_guard(true));
    }
}

fn child(case: &str, env: Option<&str>) -> std::process::Output {
    let mut child = Command::new(std::env::current_exe().unwrap());
    child.args(["--exact", "case", "--nocapture", "--test-threads=1"]);
    child.env(CASE, case).env_remove(NO_HANDLER_ENV);
    if let Some(v) = env {
        child.env(NO_HANDLER_ENV, v);
    }
    child.output().unwrap()
}

fn run(case: &str, env: Option<&str>) {
    let out = child(case, env);
    assert!(
        out.status.success(),
        "case {case}: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn opening_a_map_installs_the_handler_by_default() {
    run("default", None);
    // Any other value than 1 keeps the default.
    run("default", Some("0"));
}

#[test]
fn opting_out_leaves_sigbus_untouched() {
    run("call", None);
    run("env", Some("1"));
}

#[test]
fn opted_out_a_truncation_under_the_map_is_a_sigbus() {
    use std::os::unix::process::ExitStatusExt;
    let out = child("truncate", None);
    assert_eq!(
        out.status.signal(),
        Some(libc::SIGBUS),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
