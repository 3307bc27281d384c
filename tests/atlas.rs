//! End-to-end tests of the model commands (`fit`, `reconstruct`, `eval`,
//! `map`, `swatches`) on small synthetic databases: 16x16x32 tables fit in
//! milliseconds, so each test builds its own model in a temporary directory.

mod common;

use std::path::{Path, PathBuf};

use brdf_atlas_core::AlbedoMethod;
use brdf_atlas_core::{BlendRule, Model, OptimizerKind};
use brdf_atlas_pictures::map_picture::read_sidecar;
use brdf_merl::{MerlFile, angles::direction};
use common::{FIXTURE_DIMS as DIMS, Fixture, assert_one_error_line};
use common::{binaries, brdf_atlas, map, synth, texts};

#[test]
fn help_documents_the_model_commands() {
    let (stdout, _) = texts(&brdf_atlas(["--help"]));
    for sub in ["fit", "reconstruct", "eval", "map", "locate"] {
        assert!(stdout.contains(sub), "--help lacks {sub}:\n{stdout}");
        let out = brdf_atlas([sub, "--help"]);
        assert!(out.status.success(), "{sub} --help");
        assert!(texts(&out).0.contains("Usage: brdf-atlas"), "{sub} --help");
    }
}

#[test]
fn fit_writes_the_model_and_its_store_and_summarises() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("merl");
    synth(&data, 6, DIMS, 4);
    std::fs::write(data.join("README.txt"), "not a table").unwrap();
    let model = dir.path().join("m.atlas");
    let out = brdf_atlas([
        Path::new("fit"),
        &data,
        Path::new("-o"),
        &model,
        Path::new("--store-precision"),
        Path::new("f64"),
    ]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(model.is_file() && dir.path().join("m.atlas.store").is_file());
    // The stray file is named, as a warning.
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("warning: ") && stderr.contains("README.txt"),
        "{stderr}"
    );
    for want in [
        "fitted 6 materials (16x16x32, d = 24576)",
        "transform rel-log",
        "optimiser lbfgs",
        "(f64, ",
        "cost ",
        " -> ",
        "iterations",
        "evaluations (cost and gradient",
        "scan ",
        "store+Gram ",
        "optimise ",
        "save ",
        "total ",
    ] {
        assert!(stdout.contains(want), "{want:?} in\n{stdout}");
    }
    let m = Model::open(&model).unwrap();
    assert_eq!(m.names().len(), 6);
    assert_eq!(m.q(), 2);
    assert_eq!(m.file().fit.optimizer, OptimizerKind::Lbfgs);
    // Hooke-Jeeves says what its incremental updates did.
    let out = brdf_atlas([
        Path::new("fit"),
        &data,
        Path::new("-o"),
        &model,
        Path::new("--optimizer"),
        Path::new("hooke-jeeves"),
    ]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    for want in [
        "optimiser hooke-jeeves",
        "pattern moves",
        "refactorisations",
        "max drift",
    ] {
        assert!(stdout.contains(want), "{want:?} in\n{stdout}");
    }
    let m = Model::open(&model).unwrap();
    assert_eq!(m.file().fit.optimizer, OptimizerKind::HookeJeeves);
    // The same files again, another q: the store is used again, and said so.
    let out = brdf_atlas([
        Path::new("fit"),
        &data,
        Path::new("-o"),
        &model,
        Path::new("--q"),
        Path::new("3"),
    ]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    for want in ["(f32, ", "used again", "store check "] {
        assert!(stdout.contains(want), "{want:?} in\n{stdout}");
    }
    assert_eq!(Model::open(&model).unwrap().q(), 3);
}

#[test]
fn fit_with_as_many_dimensions_as_materials_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("merl");
    synth(&data, 3, "8,8,16", 1);
    let model = dir.path().join("m.atlas");
    for q in ["3", "5"] {
        let out = brdf_atlas([
            Path::new("fit"),
            &data,
            Path::new("-o"),
            &model,
            Path::new("--q"),
            Path::new(q),
        ]);
        assert_one_error_line(&out, &["--q", "found 3", "merl"]);
    }
    assert!(!model.exists() && !dir.path().join("m.atlas.store").exists());
}

#[test]
fn fit_names_a_broken_file_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("merl");
    synth(&data, 4, "8,8,16", 1);
    let victim = &binaries(&data)[2];
    let bytes = std::fs::read(victim).unwrap();
    std::fs::write(victim, &bytes[..bytes.len() - 64]).unwrap();
    let model = dir.path().join("m.atlas");
    let out = brdf_atlas([Path::new("fit"), &data, Path::new("-o"), &model]);
    let name = victim.file_name().unwrap().to_str().unwrap();
    assert_one_error_line(&out, &[name, "bytes"]);
    assert!(!model.exists() && !dir.path().join("m.atlas.store").exists());
}

#[test]
fn fit_rejects_bad_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("merl");
    synth(&data, 4, "8,8,16", 1);
    let model = dir.path().join("m.atlas");
    let run = |extra: &[&str]| {
        let mut args = vec!["fit", data.to_str().unwrap(), "-o", model.to_str().unwrap()];
        args.extend(extra);
        brdf_atlas(args)
    };
    // Values clap cannot parse are usage errors (status 2) naming the option.
    for (flag, value) in [
        ("--transform", "bogus"),
        ("--optimizer", "simplex"),
        ("--store-precision", "f16"),
        ("--noise", "tiny"),
    ] {
        let out = run(&[flag, value]);
        let (_, stderr) = texts(&out);
        assert_eq!(out.status.code(), Some(2), "{flag} {value}: {stderr}");
        assert!(
            stderr.starts_with("error: ") && stderr.contains(flag) && stderr.contains(value),
            "{stderr}"
        );
    }
    // Values the model cannot use are one line and status 1.
    for (flag, value, want) in [
        ("--noise", "-1", "noise"),
        ("--noise", "0", "noise"),
        ("--length-scale", "0", "length scale"),
        ("--min-step", "0", "step"),
        ("--q", "0", "q = 0"),
    ] {
        let out = run(&[flag, value]);
        assert_one_error_line(&out, &["invalid parameters", want]);
    }
    assert!(!model.exists());
    // A directory that is not there is named.
    let out = brdf_atlas([
        Path::new("fit"),
        &dir.path().join("nowhere"),
        Path::new("-o"),
        &model,
    ]);
    assert_one_error_line(&out, &["nowhere"]);
}

#[test]
fn reconstruct_writes_a_merl_file_of_the_model_dims() {
    let fx = Fixture::new(6, &[]);
    let out_path = fx.path("new.binary");
    let out = brdf_atlas([
        Path::new("reconstruct"),
        &fx.model(),
        Path::new("--at"),
        Path::new("-0.2,0.35"),
        Path::new("-o"),
        &out_path,
    ]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    // Small dims: a warning for BRDF Explorer, nothing else.
    assert!(
        stderr.starts_with("warning: ") && stderr.lines().count() == 1,
        "{stderr}"
    );
    assert!(stdout.contains("wrote"), "{stdout}");
    // The three largest weights, each with a material name.
    let names: Vec<String> = binaries(&fx.data())
        .iter()
        .map(|p| p.file_stem().unwrap().to_str().unwrap().to_string())
        .collect();
    let weight_lines = stdout
        .lines()
        .filter(|l| names.iter().any(|n| l.trim_end().ends_with(n.as_str())))
        .count();
    assert_eq!(weight_lines, 3, "{stdout}");

    let file = MerlFile::open(&out_path).unwrap();
    assert_eq!(file.dims().to_string(), "16x16x32");
    let mut raw = vec![0.0; 3 * file.dims().bins()];
    file.copy_raw(0, &mut raw);
    let invalid = raw.iter().filter(|&&v| v == -1.0).count();
    assert!(invalid > 0, "below-horizon bins stay unmeasured");
    assert!(
        raw.iter().all(|&v| v >= 0.0 || v == -1.0),
        "no negative value but the invalid marker"
    );
    assert!(raw.iter().any(|&v| v > 0.0));
}

#[test]
fn reconstruct_checks_the_point_against_the_model() {
    let fx = Fixture::new(5, &[]);
    let out_path = fx.path("never.binary");
    let run = |at: &str| {
        brdf_atlas([
            Path::new("reconstruct"),
            &fx.model(),
            Path::new("--at"),
            Path::new(at),
            Path::new("-o"),
            &out_path,
        ])
    };
    let out = run("0.1,0.2,0.3");
    assert_one_error_line(
        &out,
        &["--at expects two numbers like 0.3,-0.5", "model.atlas"],
    );
    for bad in ["0.1;0.2", "x,y", ""] {
        let out = run(bad);
        let (_, stderr) = texts(&out);
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {stderr}");
        assert!(
            stderr.contains("--at expects two numbers like 0.3,-0.5"),
            "{bad:?}: {stderr}"
        );
    }
    assert!(!out_path.exists());
    // A missing model is named.
    let out = brdf_atlas([
        Path::new("reconstruct"),
        &fx.path("missing.atlas"),
        Path::new("--at"),
        Path::new("0,0"),
        Path::new("-o"),
        &out_path,
    ]);
    assert_one_error_line(&out, &["missing.atlas"]);
}

#[test]
fn reconstruct_takes_q_coordinates_in_a_higher_dimensional_model() {
    let fx = Fixture::new(6, &["--q", "3"]);
    assert!(fx.fit_stdout.contains("q = 3"), "{}", fx.fit_stdout);
    let out_path = fx.path("q3.binary");
    let out = brdf_atlas([
        Path::new("reconstruct"),
        &fx.model(),
        Path::new("--at"),
        Path::new("0.1,-0.2,0.3"),
        Path::new("-o"),
        &out_path,
    ]);
    assert!(out.status.success(), "{}", texts(&out).1);
    assert!(MerlFile::open(&out_path).is_ok());
    let out = brdf_atlas([
        Path::new("reconstruct"),
        &fx.model(),
        Path::new("--at"),
        Path::new("0.1,-0.2"),
        Path::new("-o"),
        &out_path,
    ]);
    assert_one_error_line(&out, &["--at expects 3 numbers", "got 2"]);
}

/// The R, G, B values of each data row of `eval`'s report (after two
/// header lines, before the closing `confidence:` line), `None` for a pair
/// without value.
fn eval_rows(stdout: &str) -> Vec<Option<[f64; 3]>> {
    stdout
        .lines()
        .skip(2)
        // The table ends where the confidence (and plausibility) lines begin.
        .take_while(|l| !l.starts_with("confidence:"))
        .map(|l| {
            if l.ends_with("below horizon / unmeasured") {
                return None;
            }
            let cols: Vec<f64> = l
                .split_whitespace()
                .map(|v| v.parse().unwrap_or_else(|_| panic!("number in {l:?}")))
                .collect();
            assert_eq!(cols.len(), 7, "{l:?}");
            Some([cols[4], cols[5], cols[6]])
        })
        .collect()
}

#[test]
fn eval_prints_what_the_library_computes() {
    let fx = Fixture::new(6, &[]);
    let at = [0.25, -0.4];
    let pairs = [
        ((30.0, 0.0), (30.0, 180.0)),
        ((30.0, 0.0), (45.5, 90.0)),
        ((30.0, 0.0), (95.0, 0.0)),
        ((12.5, 40.0), (70.0, 300.0)),
        ((0.0, 0.0), (0.0, 0.0)),
    ];
    let model = Model::open(fx.model()).unwrap();
    let expect = |rule: BlendRule| -> Vec<Option<[f64; 3]>> {
        let blend = model.at(&at, rule).unwrap();
        pairs
            .iter()
            .map(|((ti, pi), (to, po))| {
                blend.eval(
                    direction(f64::to_radians(*ti), f64::to_radians(*pi)),
                    direction(f64::to_radians(*to), f64::to_radians(*po)),
                )
            })
            .collect()
    };
    // The default rule is the soft floor.
    let expected = expect(BlendRule::Floor);
    assert!(expected[2].is_none(), "95 degrees is below the horizon");
    assert!(expected.iter().filter(|v| v.is_some()).count() >= 3);
    let check = |stdout: &str, want: &[Option<[f64; 3]>]| {
        let got = eval_rows(stdout);
        assert_eq!(got.len(), want.len(), "{stdout}");
        for (g, w) in got.iter().zip(want) {
            match (g, w) {
                (Some(g), Some(w)) => {
                    for c in 0..3 {
                        assert!(
                            (g[c] - w[c]).abs() <= 1e-9 * w[c].abs().max(1e-300),
                            "{g:?} vs {w:?}\n{stdout}"
                        );
                    }
                }
                (None, None) => {}
                _ => panic!("{g:?} vs {w:?}\n{stdout}"),
            }
        }
    };

    // One incident direction, repeated --wo.
    let mut args = vec![
        "eval".to_string(),
        fx.model().display().to_string(),
        "--at".into(),
        "0.25,-0.4".into(),
        "--wi".into(),
        "30,0".into(),
    ];
    for (to, po) in pairs[..3].iter().map(|p| p.1) {
        args.push("--wo".into());
        args.push(format!("{to},{po}"));
    }
    let out = brdf_atlas(&args);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    check(&stdout, &expected[..3]);

    // Every pair from a batch file.
    let batch = fx.path("pairs.txt");
    let mut text = String::from("# theta_i phi_i theta_o phi_o\n");
    for ((ti, pi), (to, po)) in pairs {
        text.push_str(&format!("{ti} {pi} {to} {po}\n"));
    }
    std::fs::write(&batch, text).unwrap();
    let eval_batch = |extra: &[&str]| {
        let mut args = vec![
            "eval".into(),
            fx.model(),
            "--at".into(),
            "0.25,-0.4".into(),
            "--batch".into(),
            batch.clone(),
        ];
        args.extend(extra.iter().map(PathBuf::from));
        brdf_atlas(args)
    };
    let out = eval_batch(&[]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    check(&stdout, &expected);

    // The GP's own blend on request: here it differs from the floor's.
    let gp = expect(BlendRule::Gp);
    assert_ne!(gp, expected);
    let out = eval_batch(&["--blend", "gp"]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    check(&stdout, &gp);

    // A bad line is named with its number.
    std::fs::write(&batch, "30 0 30 180\n30 0 thirty 180\n").unwrap();
    let out = eval_batch(&[]);
    assert_one_error_line(&out, &["pairs.txt:2:", "theta_i phi_i theta_o phi_o"]);
}

/// PNG width and height, decoded.
fn png_size(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    (info.width, info.height)
}

#[test]
fn map_writes_png_exr_and_a_sidecar() {
    let fx = Fixture::new(6, &[]);
    let png_path = fx.path("map.png");
    let exr = fx.path("map.exr");
    let out = map(
        &fx.model(),
        &png_path,
        &[&"--exr", &exr, &"--size", &"48", &"--samples", &"64"],
    );
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("quadrature"), "{stdout}");
    assert_eq!(png_size(&png_path), (48, 48));
    let magic = std::fs::read(&exr).unwrap();
    assert_eq!(&magic[..4], &[0x76, 0x2f, 0x31, 0x01], "OpenEXR magic");
    // The sidecar defaults to the PNG path with .json.
    let sidecar = read_sidecar(&fx.path("map.json")).unwrap();
    assert_eq!((sidecar.width, sidecar.height), (48, 48));
    assert_eq!(sidecar.references.len(), fx.count);
    assert!(matches!(
        sidecar.method,
        AlbedoMethod::Quadrature { samples: 64, .. }
    ));
    for (r, name) in sidecar.references.iter().zip(binaries(&fx.data())) {
        assert_eq!(r.name, name.file_stem().unwrap().to_str().unwrap());
    }
    for want in ["map.png", "map.exr", "map.json"] {
        assert!(stdout.contains(want), "{want} in {stdout}");
    }
}

#[test]
fn map_of_a_raw_model_is_linear_and_honours_its_options() {
    let fx = Fixture::new(5, &["--transform", "raw"]);
    let png_path = fx.path("raw.png");
    let json = fx.path("side/car.json");
    std::fs::create_dir(fx.path("side")).unwrap();
    let out = map(
        &fx.model(),
        &png_path,
        &[
            &"--json",
            &json,
            &"--size",
            &"40",
            &"--contours",
            &"3",
            &"--view",
            &"-0.5,0.5,-1,0",
            &"--no-labels",
            // The GP's material is linear in the weights; the default
            // (the soft floor) is not.
            &"--blend",
            &"gp",
        ],
    );
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("linear"), "{stdout}");
    assert_eq!(png_size(&png_path), (40, 40));
    assert!(!fx.path("raw.json").exists());
    let sidecar = read_sidecar(&json).unwrap();
    assert_eq!(sidecar.method, AlbedoMethod::Linear);
    assert_eq!(
        [
            sidecar.view.x0,
            sidecar.view.x1,
            sidecar.view.y0,
            sidecar.view.y1
        ],
        [-0.5, 0.5, -1.0, 0.0]
    );
    assert!(sidecar.contour_levels.len() <= 3);

    let out = map(&fx.model(), &png_path, &[&"--view", &"1,-1,0,1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(texts(&out).1.contains("--view expects four numbers"));
}

#[test]
fn map_needs_a_two_dimensional_model() {
    let fx = Fixture::new(5, &["--q", "3", "--transform", "raw"]);
    let png_path = fx.path("map.png");
    let out = map(&fx.model(), &png_path, &[&"--size", &"16"]);
    assert_one_error_line(&out, &["model.atlas", "2-D latent space", "q = 3"]);
    assert!(!png_path.exists() && !fx.path("map.json").exists());
}

#[test]
fn swatches_writes_a_sheet_of_spheres_and_names_what_is_wrong() {
    let fx = Fixture::new(5, &[]);
    let sheet = fx.path("sheet.png");
    let exr = fx.path("sheet.exr");
    let out = brdf_atlas([
        "swatches".as_ref(),
        fx.model().as_os_str(),
        "-o".as_ref(),
        sheet.as_os_str(),
        "--exr".as_ref(),
        exr.as_os_str(),
        "--grid".as_ref(),
        "3".as_ref(),
        "--size".as_ref(),
        "20".as_ref(),
    ]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.starts_with("9 spheres of 20 px"), "{stdout}");
    let (w, h) = png_size(&sheet);
    // Three cells a row, each the sphere and 6 pixels around it, and a line of text under it.
    assert_eq!(w, 3 * (20 + 12));
    assert!(h > 3 * (20 + 12) && h < 3 * (20 + 12 + 20), "{h}");
    assert_eq!(
        &std::fs::read(&exr).unwrap()[..4],
        &[0x76, 0x2f, 0x31, 0x01]
    );

    let name = binaries(&fx.data())[1]
        .file_stem()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let named = fx.path("named.png");
    let out = brdf_atlas([
        "swatches".as_ref(),
        fx.model().as_os_str(),
        "-o".as_ref(),
        named.as_os_str(),
        "--materials".as_ref(),
        name.as_ref(),
        "--light".as_ref(),
        "0,0,1,1".as_ref(),
    ]);
    assert!(out.status.success(), "{}", texts(&out).1);
    assert_eq!(png_size(&named).0, 128 + 12);

    let out = brdf_atlas([
        "swatches".as_ref(),
        fx.model().as_os_str(),
        "-o".as_ref(),
        fx.path("none.png").as_os_str(),
        "--materials".as_ref(),
        "no-such-material".as_ref(),
    ]);
    assert_one_error_line(&out, &["model.atlas", "no-such-material"]);
    assert!(!fx.path("none.png").exists());
}
