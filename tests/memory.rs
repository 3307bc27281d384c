//! The memory of a fit and of the model's queries stays under 512 MB of
//! resident memory, however large an L3 cache the CPU reports.
//!
//! Matrix libraries size per-thread scratch buffers from the L3 cache size
//! the system reports; on a virtual machine that reports 260 MiB of L3,
//! faer's x86 products reserve 520 MiB in every thread that runs one. This
//! test runs the real binary on 100 synthetic materials (enough for every
//! dense step, the factorisations included, to reach the sizes where faer
//! would use those products) and takes each child's peak resident set from
//! the kernel when it is reaped (`wait4`'s `ru_maxrss`: no sampling, so no
//! peak is missed), and checks the `fit` summary's own figure; then runs
//! the leave-one-out pass in this process on two threads and reads this
//! process's peak (`VmHWM`). The peak resident set counts the mapped inputs
//! and store too (a few tens of MB here), so it bounds the private memory
//! from above.
#![cfg(target_os = "linux")]

mod common;

use std::path::Path;
use std::process::{Command, Stdio};

use brdf_atlas_core::{Model, NoProgress, loo};
use common::{binaries, synth};

/// The bound, in bytes.
const LIMIT: u64 = 512_000_000;

/// The `field` (`VmHWM`, ...) of a `/proc/PID/status` text in bytes (read
/// here, not through the library, so the check does not trust the code it
/// checks).
fn status_bytes(status: &str, field: &str) -> Option<u64> {
    let line = status
        .lines()
        .find_map(|l| l.strip_prefix(field)?.strip_prefix(':'))?;
    let kib: u64 = line.trim().strip_suffix("kB")?.trim().parse().ok()?;
    Some(kib * 1024)
}

/// Run `brdf-atlas args` to success; its stdout and its peak resident set
/// in bytes, from the kernel as the child is reaped.
fn run_sampled(dir: &Path, args: &[&dyn AsRef<std::ffi::OsStr>]) -> (String, u64) {
    let out_path = dir.join("stdout.txt");
    let err_path = dir.join("stderr.txt");
    let child = Command::new(env!("CARGO_BIN_EXE_brdf-atlas"))
        .args(args.iter().map(|a| a.as_ref()))
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap())
        .stdin(Stdio::null())
        .spawn()
        .expect("the binary runs");
    let pid = libc::pid_t::try_from(child.id()).unwrap();
    let mut status = 0;
    // SAFETY: all-zero bytes are a valid rusage (plain integers).
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: our own child, not waited for by anything else (`child` is
    // only dropped, which does not wait); both pointers are valid to write.
    let reaped = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(reaped, pid, "wait4: {}", std::io::Error::last_os_error());
    drop(child);
    let stdout = std::fs::read_to_string(&out_path).unwrap();
    let stderr = std::fs::read_to_string(&err_path).unwrap();
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "{stderr}"
    );
    // ru_maxrss is in KiB on Linux.
    let peak = u64::try_from(usage.ru_maxrss).unwrap() * 1024;
    assert!(peak > 0, "no peak resident set");
    (stdout, peak)
}

/// `12.3 MB` or `1.05 GB` (the summary's sizes) in bytes.
fn parse_size(text: &str) -> u64 {
    let (value, unit) = text.trim().split_once(' ').expect("a value and a unit");
    let value: f64 = value.parse().expect("a number");
    let scale = match unit {
        "kB" => 1e3,
        "MB" => 1e6,
        "GB" => 1e9,
        _ => panic!("unit {unit:?}"),
    };
    (value * scale) as u64
}

#[test]
fn fit_and_queries_stay_under_512_mb_resident() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("merl");
    synth(&data, 100, "16,16,32", 7);
    let model = tmp.path().join("model.atlas");

    let (summary, fit_peak) = run_sampled(tmp.path(), &[&"fit", &data, &"-o", &model]);
    assert!(
        fit_peak <= LIMIT,
        "fit: resident set reached {fit_peak} bytes"
    );
    let line = summary
        .lines()
        .find(|l| l.trim_start().starts_with("memory"))
        .unwrap_or_else(|| panic!("a memory line in {summary}"));
    let reported = line
        .split("peak resident private ")
        .nth(1)
        .and_then(|s| s.split(" (RssAnon)").next())
        .unwrap_or_else(|| panic!("peak resident private in {line}"));
    let reported = parse_size(reported);
    assert!(reported > 0 && reported <= LIMIT, "{line}");

    let png = tmp.path().join("map.png");
    let new = tmp.path().join("new.binary");
    let files = binaries(&data);
    let lbfgs = tmp.path().join("lbfgs.atlas");
    let field = tmp.path().join("field.png");
    let runs: [Vec<&dyn AsRef<std::ffi::OsStr>>; 6] = [
        vec![
            &"map",
            &model,
            &"-o",
            &png,
            &"--size",
            &"48",
            &"--samples",
            &"16",
        ],
        vec![&"map", &model, &"-o", &field, &"--size", &"48"],
        vec![&"reconstruct", &model, &"--at", &"0.1,-0.2", &"-o", &new],
        vec![&"fit", &data, &"-o", &lbfgs, &"--optimizer", &"lbfgs"],
        vec![&"locate", &model, &files[0], &files[1]],
        vec![
            &"eval", &model, &"--at", &"0.3,0.3", &"--wi", &"0.5,0", &"--wo", &"0.5,3.1",
        ],
    ];
    for args in &runs {
        let (_, peak) = run_sampled(tmp.path(), args);
        assert!(
            peak <= LIMIT,
            "{:?}: resident set reached {peak} bytes",
            args[0].as_ref()
        );
    }

    // Leave-one-out in this process, on two threads: its predictors
    // (factorisation, inverse, eigen-decomposition) and its pass over the store.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.install(|| {
        let m = Model::open(&model).unwrap();
        let kernel = m.file().kernel;
        let predictors = vec![
            loo::gp_predictor(&kernel, m.latent().as_ref(), true).unwrap(),
            loo::pca_predictor(m.gram().as_ref(), 3).unwrap(),
        ];
        let ev = loo::evaluate(m.store(), &predictors, &NoProgress).unwrap();
        assert_eq!(ev.rows, m.store().rows());
    });
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let peak = status_bytes(&status, "VmHWM").unwrap();
    // No thread keeps faer's scratch (twice the reported L3, reserved in
    // each thread that runs its eigen-decomposition) after the call: the
    // pool's two threads are still alive here.
    let reserved = status_bytes(&status, "VmData").unwrap();
    assert!(
        reserved <= LIMIT,
        "leave-one-out: {reserved} bytes of private address space kept after it"
    );
    assert!(
        peak <= LIMIT,
        "leave-one-out: resident set peaked at {peak} bytes"
    );
}

/// A fit of 1000 materials (tiny tables, one Hooke-Jeeves step size) stays
/// under the bound too: the store pass's per-group `N x N` partial sums
/// (64 of 8 MB each at this size, with each group's buffers kept to the
/// end) once took it to 800 MB.
#[test]
fn a_fit_of_a_thousand_materials_stays_under_512_mb() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("merl");
    synth(&data, 1000, "2,2,4", 3);
    let model = tmp.path().join("model.atlas");
    let (summary, peak) = run_sampled(
        tmp.path(),
        &[&"fit", &data, &"-o", &model, &"--min-step", &"0.25"],
    );
    assert!(summary.contains("fitted 1000 materials"), "{summary}");
    assert!(
        peak <= LIMIT,
        "fit of 1000: resident set reached {peak} bytes"
    );
}
