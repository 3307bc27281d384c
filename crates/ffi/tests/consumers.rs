//! The C library as C and C++ programs see it: the programs under
//! `tests/c/` and the README's example `examples/merl_at.cpp` are compiled
//! with the system `cc` and `c++` against `include/` and the libraries cargo
//! built for this test run, then run against a model fitted here, and
//! checked against what the Rust library computes.
//!
//! Where the libraries are: a package whose lib is also a `staticlib` and a
//! `cdylib` gets all three built in one rustc run, and cargo names those
//! outputs without a hash (`libbrdf_atlas_c.a`, `libbrdf_atlas_c.so`) in the
//! `deps/` directory next to this test's executable. So the test links what
//! the same `cargo test` just built from the same sources: no second cargo
//! run, no install step, no stale copy from another build.
//!
//! The C consumer runs under valgrind in `.ci/run` (the ignored test
//! `c_consumer_under_valgrind`; `tests/valgrind.supp` says what it
//! suppresses: rayon's pool threads, alive at exit by design).

use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use brdf_atlas_core::{BlendRule, View};
use brdf_atlas_core::{FitOptions, fit_dir, store_path_for};
use brdf_atlas_core::{GplvmParams, Model, NoProgress, Precision, TransformKind};
use brdf_atlas_hostile::{merl_cases, model_cases};
use brdf_merl::angles::direction;
use brdf_merl::synth::{self, database};
use brdf_merl::{Dims, MerlFile, Vec3};

const DIMS: Dims = Dims {
    theta_h: 12,
    theta_d: 12,
    phi_d: 24,
};

/// Latent points the C and C++ programs reconstruct, serially and from threads.
const POINTS: [[f64; 2]; 4] = [[0.31, -0.42], [-0.5, 0.5], [0.8, -0.3], [-0.9, -0.95]];

/// Everything the consumers read: the model, the files for the bad calls,
/// and `expected.txt`, the Rust library's answers.
struct Fixture {
    dir: PathBuf,
    model: PathBuf,
    expected: PathBuf,
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `deps/` of this build: where `libbrdf_atlas_c.a` and `.so` are.
fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    let dir = exe
        .parent()
        .expect("the test is in a directory")
        .to_path_buf();
    for lib in ["libbrdf_atlas_c.a", "libbrdf_atlas_c.so"] {
        assert!(
            dir.join(lib).is_file(),
            "{lib} is not in {}: cargo builds the ffi crate's staticlib and cdylib there \
             when it builds this test (crate-type in crates/ffi/Cargo.toml)",
            dir.display()
        );
    }
    dir
}

fn fixture() -> &'static Fixture {
    static FIXTURE: OnceLock<Fixture> = OnceLock::new();
    FIXTURE.get_or_init(build_fixture)
}

fn line(out: &mut String, key: &str, values: &[f64], tail: Option<&Path>) {
    write!(out, "{key}").unwrap();
    for v in values {
        // `{:?}` is the shortest text that reads back as the same double (or "NaN").
        write!(out, " {v:?}").unwrap();
    }
    if let Some(p) = tail {
        write!(out, " {}", p.display()).unwrap();
    }
    out.push('\n');
}

fn write_map(path: &Path, rgb: &[[f32; 3]]) {
    let bytes: Vec<u8> = rgb.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

fn build_fixture() -> Fixture {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("ffi-consumers");
    let _ = std::fs::remove_dir_all(&dir);
    let data = dir.join("data");
    std::fs::create_dir_all(dir.join("out")).unwrap();
    synth::write_dir(&data, 6, DIMS, 5).unwrap();
    let model_path = dir.join("atlas.model");
    let options = FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision: Precision::F32,
    };
    fit_dir(&data, &model_path, &options, &NoProgress).unwrap();
    let m = brdf_atlas_core::Atlas::new(Model::open(&model_path).unwrap());

    // Files for the bad calls.
    let corrupt = dir.join("corrupt.model");
    std::fs::write(&corrupt, b"{\"format\": \"brdf-atlas-model\", \"vers").unwrap();
    let changed = dir.join("changed.model");
    let text = std::fs::read_to_string(&model_path).unwrap();
    std::fs::write(
        &changed,
        text.replace("atlas.model.store", "changed.model.store"),
    )
    .unwrap();
    let mut store = std::fs::read(store_path_for(&model_path)).unwrap();
    let last = store.len() - 1;
    store[last] ^= 0x40;
    std::fs::write(store_path_for(&changed), store).unwrap();
    let probe = dir.join("probe.binary");
    database(3, 11)[2].brdf.table(DIMS).write(&probe).unwrap();
    let bad_merl = dir.join("bad.binary");
    let mut bytes = std::fs::read(&probe).unwrap();
    bytes.truncate(1000);
    std::fs::write(&bad_merl, bytes).unwrap();
    let small = dir.join("small.binary");
    database(1, 11)[0]
        .brdf
        .table(Dims::new(8, 8, 16).unwrap())
        .write(&small)
        .unwrap();

    // What the Rust library answers.
    let mut e = String::new();
    writeln!(e, "version {}", env!("CARGO_PKG_VERSION")).unwrap();
    line(&mut e, "model", &[], Some(&model_path));
    line(&mut e, "corrupt", &[], Some(&corrupt));
    line(&mut e, "changed", &[], Some(&changed));
    line(&mut e, "missing", &[], Some(&dir.join("missing.model")));
    line(&mut e, "out_dir", &[], Some(&dir.join("out")));
    writeln!(e, "count {}", m.names().len()).unwrap();
    writeln!(e, "q {}", m.q()).unwrap();
    writeln!(e, "dims {} {} {}", DIMS.theta_h, DIMS.theta_d, DIMS.phi_d).unwrap();
    let v = View::default();
    line(&mut e, "view", &[v.x0, v.x1, v.y0, v.y1], None);
    for (i, name) in m.names().iter().enumerate() {
        writeln!(e, "name {i} {name}").unwrap();
        let p = [m.latent()[(i, 0)], m.latent()[(i, 1)]];
        line(&mut e, &format!("latent {i}"), &p, None);
    }
    for (k, p) in POINTS.iter().enumerate() {
        let file = dir.join(format!("point{k}.binary"));
        m.at(p, BlendRule::default())
            .unwrap()
            .table()
            .unwrap()
            .write(&file)
            .unwrap();
        line(&mut e, "point", p, Some(&file));
    }
    let far = [1e6, -1e300];
    let file = dir.join("far.binary");
    m.at(&far, BlendRule::default())
        .unwrap()
        .table()
        .unwrap()
        .write(&file)
        .unwrap();
    line(&mut e, "far", &far, Some(&file));
    let blend = m.at(&POINTS[0], BlendRule::default()).unwrap();
    line(&mut e, "weights", blend.weights(), None);
    let pairs: [(Vec3, Vec3); 8] = [
        (direction(0.3, 0.0), direction(0.5, 2.0)),
        (direction(1.2, 1.0), direction(0.1, 4.0)),
        ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
        ([1.0, 1.0, 3.0], [-2.0, 0.5, 4.0]),
        (direction(1.5, 0.2), direction(1.5, 3.3)),
        ([0.0, 0.0, -1.0], [0.0, 0.0, 1.0]),
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([f64::NAN, 0.0, 1.0], [0.0, 0.0, 1.0]),
    ];
    for (wi, wo) in pairs {
        let rgb = blend.eval(wi, wo).unwrap_or([f64::NAN; 3]);
        let values: Vec<f64> = wi.iter().chain(&wo).chain(&rgb).copied().collect();
        line(&mut e, "pair", &values, None);
    }
    assert_eq!(
        e.matches("NaN NaN NaN\n").count(),
        3,
        "three pairs have no value"
    );
    // The map of the default window with the default method (samples 0:
    // the model is in the log transform, so the albedo field where it fits
    // its budget), and one of another window.
    let map = m
        .map(brdf_atlas_core::MapRequest::new(16, 12).view(v))
        .unwrap();
    let file = dir.join("map.f32");
    write_map(&file, &map.rgb);
    line(&mut e, "map 16 12 0", &[], Some(&file));
    let view = View {
        x0: -0.5,
        x1: 0.7,
        y0: -0.3,
        y1: 0.9,
    };
    let map = m
        .map(
            brdf_atlas_core::MapRequest::new(9, 7)
                .view(view)
                .samples(Some(64)),
        )
        .unwrap();
    let file = dir.join("map2.f32");
    write_map(&file, &map.rgb);
    line(
        &mut e,
        "map_view 9 7 64",
        &[view.x0, view.x1, view.y0, view.y1],
        Some(&file),
    );
    let found = brdf_atlas_core::Located::find(&m, &MerlFile::open(&probe).unwrap()).unwrap();
    line(&mut e, "probe", &[], Some(&probe));
    line(
        &mut e,
        &format!("locate {}", found.nearest[0].0),
        &[found.point[0], found.point[1], found.rmse, found.spread],
        None,
    );
    line(&mut e, "bad_merl", &[], Some(&bad_merl));
    line(&mut e, "wrong_dims", &[], Some(&small));
    // The generated corpus of broken files.
    for (key, cases) in [
        (
            "hostile_open",
            model_cases(&mkdir(&dir.join("hostile-models")), &model_path),
        ),
        (
            "hostile_locate",
            merl_cases(&mkdir(&dir.join("hostile-merl"))),
        ),
    ] {
        for c in cases {
            let name = c.names.file_name().unwrap().to_str().unwrap();
            let status = c.status as i32;
            writeln!(
                e,
                "{key} {status}\t{}\t{name}\t{}",
                c.path.display(),
                c.want
            )
            .unwrap();
        }
    }
    let expected = dir.join("expected.txt");
    std::fs::write(&expected, e).unwrap();
    Fixture {
        dir,
        model: model_path,
        expected,
    }
}

fn mkdir(path: &Path) -> PathBuf {
    std::fs::create_dir_all(path).unwrap();
    path.to_path_buf()
}

fn run(cmd: &mut Command, what: &str) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot run {cmd:?}: {e}"));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{cmd:?}\n--- stdout\n{stdout}\n--- stderr\n{stderr}",
        out.status
    );
    stdout
}

fn compiler(var: &str, default: &str) -> String {
    std::env::var(var).unwrap_or_else(|_| default.to_string())
}

/// `source` compiled by `compiler` in language standard `std` against
/// include/, every warning an error, and linked with `link` into `exe`.
fn compile(compiler: String, std: &str, source: &Path, link: &[OsString], exe: &Path) {
    run(
        Command::new(compiler)
            .arg(std)
            .args([
                "-O1",
                "-g",
                "-Wall",
                "-Wextra",
                "-pedantic",
                "-Werror",
                "-I",
            ])
            .arg(repo().join("include"))
            .arg(source)
            .args(link)
            .arg("-o")
            .arg(exe),
        &format!("compiling {}", source.display()),
    );
}

/// The C consumer, linked with the static library.
fn build_c(f: &Fixture) -> PathBuf {
    let exe = f.dir.join("consumer-c");
    let link = [lib_dir().join("libbrdf_atlas_c.a").into_os_string()]
        .into_iter()
        .chain(["-lpthread", "-ldl", "-lm"].map(OsString::from));
    compile(
        compiler("CC", "cc"),
        "-std=c11",
        &repo().join("crates/ffi/tests/c/consumer.c"),
        &link.collect::<Vec<_>>(),
        &exe,
    );
    exe
}

/// A C++ program, linked with the shared library.
fn build_cpp(f: &Fixture, source: &Path, name: &str) -> PathBuf {
    let exe = f.dir.join(name);
    let libs = lib_dir();
    let link = [
        libs.join("libbrdf_atlas_c.so").into_os_string(),
        format!("-Wl,-rpath,{}", libs.display()).into(),
        "-pthread".into(),
    ];
    compile(compiler("CXX", "c++"), "-std=c++17", source, &link, &exe);
    exe
}

#[test]
fn c_consumer_agrees_with_rust_and_survives_bad_calls() {
    let f = fixture();
    let exe = build_c(f);
    let out = run(Command::new(&exe).arg(&f.expected), "the C consumer");
    assert!(out.contains("all checks passed"), "{out}");
}

#[test]
fn cpp_consumer_agrees_with_rust_through_the_raii_wrapper() {
    let f = fixture();
    let exe = build_cpp(
        f,
        &repo().join("crates/ffi/tests/c/consumer.cpp"),
        "consumer-cpp",
    );
    let out = run(Command::new(&exe).arg(&f.expected), "the C++ consumer");
    assert!(out.contains("all checks passed"), "{out}");
}

#[test]
fn readme_example_writes_the_reconstruction() {
    let source = repo().join("crates/ffi/examples/merl_at.cpp");
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let text = std::fs::read_to_string(&source).unwrap();
    assert!(
        readme.contains(&format!("```cpp\n{text}```")),
        "the README's C++ example is not crates/ffi/examples/merl_at.cpp: copy it over"
    );
    let f = fixture();
    let exe = build_cpp(f, &source, "merl_at");
    let out_file = f.dir.join("out/readme.binary");
    let [x, y] = POINTS[1];
    let stdout = run(
        Command::new(&exe)
            .arg(&f.model)
            .arg(x.to_string())
            .arg(y.to_string())
            .arg(&out_file),
        "the README example",
    );
    assert!(stdout.contains("wrote"), "{stdout}");
    let m = brdf_atlas_core::Atlas::new(Model::open(&f.model).unwrap());
    let want = f.dir.join("out/readme-rust.binary");
    m.at(&[x, y], BlendRule::default())
        .unwrap()
        .table()
        .unwrap()
        .write(&want)
        .unwrap();
    assert_eq!(
        std::fs::read(&out_file).unwrap(),
        std::fs::read(&want).unwrap(),
        "merl_at wrote other bytes than the Rust library"
    );
    // A bad argument is one line on stderr and exit status 1 or 2, no crash.
    for args in [
        vec!["0", "0"],
        vec!["nan", "0", "x.binary"],
        vec!["0", "zero", "x.binary"],
    ] {
        let out = Command::new(&exe)
            .arg(&f.model)
            .args(&args)
            .output()
            .unwrap();
        let code = out.status.code();
        assert!(matches!(code, Some(1 | 2)), "{args:?}: {:?}", out.status);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
    }
}

#[test]
fn install_script_and_pkg_config_build_the_example() {
    if Command::new("pkg-config")
        .arg("--version")
        .output()
        .is_err()
    {
        eprintln!("note: pkg-config is not installed; skipping the pkg-config check");
        return;
    }
    let f = fixture();
    let prefix = f.dir.join("prefix");
    let _ = std::fs::remove_dir_all(&prefix);
    run(
        Command::new("bash")
            .arg(repo().join("crates/ffi/install.sh"))
            .arg(&prefix)
            .arg(lib_dir()),
        "crates/ffi/install.sh",
    );
    let pc_dir = prefix.join("lib/pkgconfig");
    let pkg = |args: &[&str]| -> Vec<String> {
        let out = run(
            Command::new("pkg-config")
                .env("PKG_CONFIG_PATH", &pc_dir)
                .args(args)
                .arg("brdf_atlas"),
            "pkg-config",
        );
        out.split_whitespace().map(str::to_owned).collect()
    };
    assert_eq!(pkg(&["--modversion"]), [env!("CARGO_PKG_VERSION")]);
    let libdir = pkg(&["--variable=libdir"]).concat();
    let exe = f.dir.join("merl_at-pkg-config");
    run(
        Command::new(compiler("CXX", "c++"))
            .arg("-std=c++17")
            .args(pkg(&["--cflags"]))
            .arg(repo().join("crates/ffi/examples/merl_at.cpp"))
            .args(pkg(&["--libs"]))
            .arg(format!("-Wl,-rpath,{libdir}"))
            .arg("-o")
            .arg(&exe),
        "compiling the example with pkg-config",
    );
    let out_file = f.dir.join("out/pkg-config.binary");
    run(
        Command::new(&exe)
            .arg(&f.model)
            .args(["0.1", "0.2"])
            .arg(&out_file),
        "the example built with pkg-config",
    );
    assert_eq!(
        MerlFile::open(&out_file).unwrap().dims(),
        DIMS,
        "a MERL file of the model's dims"
    );
    // The static library links too, with the private libraries pkg-config names.
    let exe = f.dir.join("consumer-c-static-pkg-config");
    run(
        Command::new(compiler("CC", "cc"))
            .arg("-std=c11")
            .args(pkg(&["--cflags"]))
            .arg(repo().join("crates/ffi/tests/c/consumer.c"))
            .arg(prefix.join("lib/libbrdf_atlas_c.a"))
            .args(
                pkg(&["--libs-only-l", "--static"])
                    .iter()
                    .filter(|l| *l != "-lbrdf_atlas_c"),
            )
            .arg("-o")
            .arg(&exe),
        "linking the static library with pkg-config --static",
    );
}

#[test]
#[ignore = "slow under valgrind; .ci/run runs it as its own step"]
fn c_consumer_under_valgrind() {
    if Command::new("valgrind").arg("--version").output().is_err() {
        eprintln!("note: valgrind is not installed; skipping the valgrind run of the C consumer");
        return;
    }
    let f = fixture();
    let exe = build_c(f);
    let out = run(
        Command::new("valgrind")
            .args(["--error-exitcode=1", "--leak-check=full", "--quiet"])
            .arg("--num-callers=30")
            .arg(format!(
                "--suppressions={}",
                repo().join("crates/ffi/tests/valgrind.supp").display()
            ))
            .arg(&exe)
            .arg(&f.expected),
        "the C consumer under valgrind",
    );
    assert!(out.contains("all checks passed"), "{out}");
}
