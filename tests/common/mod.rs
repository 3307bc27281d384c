//! Helpers shared by the end-to-end tests: run the real binary, read its report.
#![allow(dead_code)] // each test file uses its own subset

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Run `brdf-atlas` with `args`, capturing everything.
pub fn brdf_atlas<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_brdf-atlas"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// stdout and stderr as text.
pub fn texts(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// One file's rows of the `info` table.
#[derive(Debug, Clone, PartialEq)]
pub struct Reported {
    /// The DIMS column, e.g. `90x90x180`.
    pub dims: String,
    /// INVALID per channel.
    pub invalid: [usize; 3],
    /// ALBEDO per channel.
    pub albedo: [f64; 3],
}

/// Find `path`'s three rows (R, G, B) in an `info` report.
pub fn reported(stdout: &str, path: &Path) -> Reported {
    let name = path.display().to_string();
    let lines: Vec<&str> = stdout.lines().collect();
    let at = lines
        .iter()
        .position(|l| {
            l.strip_prefix(&name)
                .is_some_and(|rest| rest.starts_with(' '))
        })
        .unwrap_or_else(|| panic!("no row for {name} in:\n{stdout}"));
    assert!(at + 2 < lines.len(), "three rows for {name} in:\n{stdout}");
    let first: Vec<&str> = lines[at][name.len()..].split_whitespace().collect();
    assert_eq!(first.len(), 7, "row {:?}", lines[at]);
    let dims = first[0].to_string();
    let mut invalid = [0; 3];
    let mut albedo = [0.0; 3];
    for (c, channel) in ["R", "G", "B"].iter().enumerate() {
        let cols: Vec<&str> = if c == 0 {
            first[1..].to_vec()
        } else {
            lines[at + c].split_whitespace().collect()
        };
        assert_eq!(
            cols.len(),
            6,
            "{channel} row of {name}: {:?}",
            lines[at + c]
        );
        assert_eq!(cols[0], *channel, "{name}: {:?}", lines[at + c]);
        invalid[c] = cols[1].parse().expect("INVALID is an integer");
        albedo[c] = cols[5].parse().expect("ALBEDO is a number");
    }
    Reported {
        dims,
        invalid,
        albedo,
    }
}

/// The dims in a MERL file's header, formatted like the report.
pub fn header_dims(path: &Path) -> String {
    let bytes = std::fs::read(path).expect("readable");
    let d = |k: usize| i32::from_le_bytes(bytes[4 * k..4 * k + 4].try_into().unwrap());
    format!("{}x{}x{}", d(0), d(1), d(2))
}

/// The `.binary` files in `dir`, sorted.
pub fn binaries(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "binary"))
        .collect();
    files.sort();
    files
}

/// Write `count` synthetic materials of `dims` (`"16,16,32"`) with `seed`
/// into `dir`: the files `brdf-atlas synth` writes with these arguments.
pub fn synth(dir: &Path, count: usize, dims: &str, seed: u64) {
    let n: Vec<usize> = dims
        .split(',')
        .map(|d| d.parse().expect("dims are numbers"))
        .collect();
    let dims = brdf_merl::Dims::new(n[0], n[1], n[2]).expect("valid dims");
    brdf_merl::synth::write_dir(dir, count, dims, seed).expect("synthesise");
}

/// Run `brdf-atlas map MODEL -o PNG` with `extra` arguments.
pub fn map(model: &Path, png: &Path, extra: &[&dyn AsRef<OsStr>]) -> Output {
    let head: [&dyn AsRef<OsStr>; 4] = [&"map", &model, &"-o", &png];
    brdf_atlas(head.iter().chain(extra).map(|a| a.as_ref()))
}

/// Fit the materials of `data` into `model` with `extra` arguments; returns stdout.
pub fn fit(data: &Path, model: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "fit".as_ref(),
        data.as_os_str(),
        "-o".as_ref(),
        model.as_os_str(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    let out = brdf_atlas(&args);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "fit: {stderr}");
    stdout
}

/// The latent point after `at` in a line like `name: at (0.1234, -0.5678)`.
pub fn point_after_at(line: &str) -> Vec<f64> {
    let inside = line
        .split(" at (")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .unwrap_or_else(|| panic!("no `at (...)` in {line:?}"));
    inside
        .split(',')
        .map(|v| v.trim().parse().expect("a coordinate"))
        .collect()
}

/// Dims of [`Fixture`]'s materials.
pub const FIXTURE_DIMS: &str = "16,16,32";

/// A temporary directory with `count` materials in `merl/` and a model
/// fitted with `extra` arguments at `model.atlas`.
pub struct Fixture {
    pub dir: tempfile::TempDir,
    pub count: usize,
    pub fit_stdout: String,
}

impl Fixture {
    pub fn new(count: usize, extra: &[&str]) -> Fixture {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("merl");
        synth(&data, count, FIXTURE_DIMS, 11);
        let fit_stdout = fit(&data, &dir.path().join("model.atlas"), extra);
        Fixture {
            dir,
            count,
            fit_stdout,
        }
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    pub fn model(&self) -> PathBuf {
        self.path("model.atlas")
    }

    pub fn data(&self) -> PathBuf {
        self.path("merl")
    }
}

/// Exit status 1 and exactly one line, `error: ...`, containing every word of `want`.
pub fn assert_one_error_line(out: &std::process::Output, want: &[&str]) {
    let (_, stderr) = texts(out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    for w in want {
        assert!(stderr.contains(w), "expected {w:?} in {stderr}");
    }
}

/// The state letter of process `pid` (`T` stopped, `Z` ended but not yet
/// waited for), from `/proc/PID/stat`.
fn process_state(pid: u32) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat.rsplit_once(") ")?.1.chars().next()
}

/// Start `brdf-atlas args` with `BRDF_ATLAS_TEST_STOP_IN=phase` and return
/// it once it has stopped itself there (SIGSTOP), not yet waited for, with
/// stdout discarded and stderr as given. Panics if it ends first (a signal
/// sent then would come after the work) or takes over two minutes.
pub fn stopped_at(args: &[&str], phase: &str, stderr: std::process::Stdio) -> std::process::Child {
    let child = Command::new(env!("CARGO_BIN_EXE_brdf-atlas"))
        .args(args)
        .env("BRDF_ATLAS_TEST_STOP_IN", phase)
        .stdout(std::process::Stdio::null())
        .stderr(stderr)
        .spawn()
        .expect("the binary runs");
    let start = std::time::Instant::now();
    loop {
        match process_state(child.id()) {
            Some('T') => return child,
            Some('Z') => panic!("{args:?} ended before it reached {phase}"),
            _ => {}
        }
        assert!(
            start.elapsed() < std::time::Duration::from_secs(120),
            "{args:?} never stopped in {phase}"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}
