//! `brdf-atlas export` end to end: a synthetic model's material and a MERL
//! file become a glTF binary, a MaterialX document, a Mitsuba dictionary,
//! a picture and a record whose errors are the ones printed; bad requests
//! fail with one line naming what is wrong and write nothing.

mod common;

use common::{Fixture, assert_one_error_line, binaries, brdf_atlas, fit, synth, texts};
use serde_json::Value;

fn record(dir: &std::path::Path, name: &str) -> Value {
    serde_json::from_slice(&std::fs::read(dir.join(format!("{name}.fit.json"))).unwrap()).unwrap()
}

#[test]
fn a_material_of_the_map_and_a_merl_file_are_exported_with_their_errors() {
    // Tables fine enough for their nearest-bin pictures to look like the
    // smooth materials they sample (at 16 x 16 x 32 a highlight is blocks).
    let dir = tempfile::tempdir().unwrap();
    let (data, model, out) = (
        dir.path().join("merl"),
        dir.path().join("m.atlas"),
        dir.path().join("out"),
    );
    synth(&data, 3, "45,45,90", 11);
    fit(&data, &model, &[]);
    let find = |kind: &str| {
        binaries(&data)
            .into_iter()
            .find(|p| p.to_string_lossy().contains(kind))
            .unwrap()
    };
    let (metal, plastic) = (find("metal"), find("plastic"));
    let name = plastic.file_stem().unwrap().to_string_lossy().into_owned();
    let run = brdf_atlas([
        "export".as_ref(),
        model.as_os_str(),
        "--materials".as_ref(),
        name.as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    let (stdout, stderr) = texts(&run);
    assert!(run.status.success(), "{stderr}");
    for ext in ["glb", "mtlx", "mitsuba.json", "fit.json", "png"] {
        assert!(
            out.join(format!("{name}.{ext}")).is_file(),
            "{ext}: {stdout}"
        );
    }
    // The record holds the printed error and the parameters the files carry.
    let rec = record(&out, &name);
    let err = rec["rendered_error"]["principled"].as_f64().unwrap();
    assert!(
        stdout.contains(&format!("rendered {:.2}%", 100.0 * err)),
        "{stdout}"
    );
    // A synthetic GGX plastic: the fit is close and beats both baselines.
    assert!(err < 0.04, "{err}");
    assert!(err < rec["rendered_error"]["lambertian"].as_f64().unwrap());
    let table = &rec["table_error"];
    assert!(
        table["principled"].as_f64() < table["single_lobe"].as_f64(),
        "{table}"
    );
    assert!(
        rec["parameters"]["metallic"].as_f64().unwrap() < 0.1,
        "{rec}"
    );
    let glb = std::fs::read(out.join(format!("{name}.glb"))).unwrap();
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let doc: Value = serde_json::from_slice(&glb[20..20 + len]).unwrap();
    let pbr = &doc["materials"][0]["pbrMetallicRoughness"];
    assert_eq!(pbr["metallicFactor"], rec["parameters"]["metallic"]);
    assert_eq!(pbr["roughnessFactor"], rec["parameters"]["roughness"]);
    let mitsuba: Value =
        serde_json::from_slice(&std::fs::read(out.join(format!("{name}.mitsuba.json"))).unwrap())
            .unwrap();
    assert_eq!(mitsuba["type"], "principled");
    assert_eq!(mitsuba["roughness"], rec["parameters"]["roughness"]);

    // A MERL file exports the same way: a synthetic GGX metal is a metal.
    let run = brdf_atlas([
        "export".as_ref(),
        metal.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--name".as_ref(),
        "file".as_ref(),
    ]);
    assert!(run.status.success(), "{}", texts(&run).1);
    let rec = record(&out, "file");
    let file_err = rec["rendered_error"]["principled"].as_f64().unwrap();
    // (Its highlight is quantised by the nearest-bin lookups: a few percent.)
    assert!(file_err < 0.12, "{file_err}");
    assert!(
        rec["parameters"]["metallic"].as_f64().unwrap() > 0.9,
        "{rec}"
    );

    // --at: a point between the materials, named after its coordinates.
    let run = brdf_atlas([
        "export".as_ref(),
        model.as_os_str(),
        "--at".as_ref(),
        "0.1,-0.2".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(run.status.success(), "{}", texts(&run).1);
    assert!(out.join("at_0.100_-0.200.glb").is_file());
}

#[test]
fn bad_requests_fail_with_one_line_and_write_nothing() {
    let fx = Fixture::new(3, &[]);
    let out = fx.path("out");
    let o = out.as_os_str();
    let m = fx.model();
    let m = m.as_os_str();
    let run = brdf_atlas([
        "export".as_ref(),
        m,
        "--materials".as_ref(),
        "nope".as_ref(),
        "-o".as_ref(),
        o,
    ]);
    assert_one_error_line(&run, &["model.atlas", "no material named \"nope\""]);
    let run = brdf_atlas([
        "export".as_ref(),
        m,
        "--at".as_ref(),
        "0.1".as_ref(),
        "-o".as_ref(),
        o,
    ]);
    assert_one_error_line(&run, &["--at expects two numbers"]);
    let missing = fx.path("missing.binary");
    let run = brdf_atlas(["export".as_ref(), missing.as_os_str(), "-o".as_ref(), o]);
    assert_one_error_line(&run, &["missing.binary"]);
    let run = brdf_atlas(["export".as_ref(), m, "-o".as_ref(), o]);
    assert_one_error_line(
        &run,
        &["model.atlas", "is a model", "--at X,Y or --materials"],
    );
    assert!(!out.exists());
    // Usage errors are clap's: status 2.
    let run = brdf_atlas([
        "export".as_ref(),
        m,
        "-o".as_ref(),
        o,
        "--at".as_ref(),
        "x".as_ref(),
    ]);
    assert_eq!(run.status.code(), Some(2));
}

#[test]
fn the_report_fits_every_material_and_names_the_worst() {
    let fx = Fixture::new(4, &[]);
    let out = fx.path("report");
    let run = brdf_atlas([
        "report".as_ref(),
        fx.data().as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--quick".as_ref(),
    ]);
    assert!(run.status.success(), "{}", texts(&run).1);
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    let section = &md[md.find("## Analytic fits").expect("the section")..];
    assert!(
        section.contains("| Lambertian of the albedo |"),
        "{section}"
    );
    assert!(section.contains("Worst fits"), "{section}");
    let csv = std::fs::read_to_string(out.join("analytic.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    for row in rows {
        let cells: Vec<f64> = row.split(',').skip(1).map(|c| c.parse().unwrap()).collect();
        // Every error is a finite, non-negative number; the glTF fit is
        // closer than the Lambertian on these synthetic materials.
        assert!(cells.iter().all(|c| c.is_finite() && *c >= 0.0), "{row}");
        assert!(cells[0] < cells[2], "{row}");
    }
}

#[test]
fn the_fit_is_the_same_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("merl");
    synth(&data, 2, "30,30,60", 5);
    let file = &binaries(&data)[0];
    let record_with = |threads: &str| {
        let out = dir.path().join(format!("out-{threads}"));
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_brdf-atlas"))
            .args([
                "export".as_ref(),
                file.as_os_str(),
                "-o".as_ref(),
                out.as_os_str(),
            ])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(run.status.success(), "{}", texts(&run).1);
        let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
        let mut rec = record(&out, &stem);
        rec.as_object_mut().unwrap().remove("source");
        rec
    };
    assert_eq!(record_with("1"), record_with("2"));
}
