//! `reconstruct --json`, `--blend`, and the confidence and plausibility
//! lines of `reconstruct` and `eval`, against the library.

mod common;

use std::path::Path;

use brdf_atlas_core::{BlendRule, Model};
use brdf_merl::MerlTable;
use common::{brdf_atlas, fit, synth, texts};

const DIMS: &str = "12,12,24";

fn fitted(dir: &Path) -> std::path::PathBuf {
    let data = dir.join("merl");
    synth(&data, 10, DIMS, 17);
    let model = dir.join("model.atlas");
    fit(&data, &model, &["--transform", "log"]);
    model
}

#[test]
fn reconstruct_json_is_the_blend_the_library_computes() {
    let tmp = tempfile::tempdir().unwrap();
    let model_path = fitted(tmp.path());
    let model = brdf_atlas_core::Atlas::new(Model::open(&model_path).unwrap());
    // For the plausible rule, the first point of a grid over (and beyond)
    // the map's box where the rule moves the weights.
    let moving = (0..81)
        .map(|k| [-2.0 + 0.5 * (k % 9) as f64, -2.0 + 0.5 * (k / 9) as f64])
        .find(|x| model.at(x, BlendRule::Plausible).unwrap().steps().is_some())
        .expect("a point where the plausible rule moves the weights");
    // `reconstruct` at `at` under `rule`, with `--json` or without; stdout.
    let reconstruct = |rule: BlendRule, at: [f64; 2], json: bool| {
        let out_path = tmp.path().join(format!("{}.binary", rule.name()));
        let at = format!("{},{}", at[0], at[1]);
        let mut args = vec!["reconstruct", model_path.to_str().unwrap(), "--at", &at];
        args.extend(["--blend", rule.name(), "-o", out_path.to_str().unwrap()]);
        if json {
            args.push("--json");
        }
        let out = brdf_atlas(args);
        let (stdout, stderr) = texts(&out);
        assert!(out.status.success(), "{stderr}");
        stdout
    };
    for (rule, at) in [
        (BlendRule::Gp, [0.3, -0.45]),
        (BlendRule::Plausible, moving),
        (BlendRule::Floor, moving),
    ] {
        let stdout = reconstruct(rule, at, true);
        assert_eq!(stdout.lines().count(), 1, "one record: {stdout}");
        let rec: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        let blend = model.at(&at, rule).unwrap();
        // Every weight by name, as the library has it, and they sum to the stated sum.
        let weights = rec["weights"].as_object().unwrap();
        assert_eq!(weights.len(), model.names().len());
        for (name, w) in model.names().iter().zip(blend.weights()) {
            assert_eq!(weights[name].as_f64().unwrap(), *w, "{name}");
        }
        let sum: f64 = blend.weights().iter().sum();
        assert_eq!(rec["weight_sum"].as_f64().unwrap(), sum);
        // Where the rule moved the weights: towards what, and by how much in
        // each theta_h bin; the weights of every bin follow from the record.
        match blend.steps() {
            None if rule == BlendRule::Floor => {
                // The floor's convex weights and constants, as the library has them.
                let moved = &rec["moved"];
                let towards = blend.floor().expect("the floor rule's convex weights");
                for (name, v) in model.names().iter().zip(towards) {
                    assert_eq!(moved["towards"][name].as_f64().unwrap(), *v, "{name}");
                }
                assert_eq!(
                    moved["s"].as_f64().unwrap(),
                    brdf_atlas_core::soft_floor::FLOOR_SHARE
                );
                assert_eq!(
                    moved["d"].as_f64().unwrap(),
                    brdf_atlas_core::soft_floor::FLOOR_SOFTNESS
                );
                let p = blend.plausibility().unwrap();
                assert_eq!(p.clamped_reflectance, 0.0, "the floor rule clamped {p:?}");
                let stdout = reconstruct(rule, at, false);
                assert!(stdout.contains("onto a floor at 0.3 times"), "{stdout}");
            }
            None => assert!(rec["moved"].is_null(), "{rule:?}: {}", rec["moved"]),
            Some((towards, steps)) => {
                let moved = &rec["moved"];
                let t: Vec<f64> = serde_json::from_value(moved["theta_h_steps"].clone()).unwrap();
                assert_eq!(t, steps);
                assert!(t.iter().any(|&t| t > 0.0), "moved nowhere");
                for (b, &tb) in t.iter().enumerate() {
                    for (i, name) in model.names().iter().enumerate() {
                        let (w, v) = (
                            weights[name].as_f64().unwrap(),
                            moved["towards"][name].as_f64().unwrap(),
                        );
                        assert_eq!(v, towards[i]);
                        assert_eq!(w + tb * (v - w), blend.weights_in(b)[i], "{name} bin {b}");
                    }
                }
            }
        }
        if rule == BlendRule::Plausible {
            assert!(
                !rec["moved"].is_null(),
                "the test point must move the weights"
            );
            // Without --json the report says the weights shown are the GP's
            // and in how many theta_h bins the rule moved them.
            let stdout = reconstruct(rule, at, false);
            let steps = blend.steps().unwrap().1;
            let moved = steps.iter().filter(|&&t| t > 0.0).count();
            let wanted = format!(
                "towards a convex blend in {moved} of {} theta_h bins",
                steps.len()
            );
            assert!(stdout.contains(&wanted), "{stdout}");
        }
        assert_eq!(rec["blend"], rule.name());
        assert_eq!(rec["point"], serde_json::json!(at));
        assert_eq!(rec["transform"]["name"], "log");
        assert!(
            rec["transform"]["formula"]
                .as_str()
                .unwrap()
                .contains("ln(1 + f c)")
        );
        let p = blend.plausibility().unwrap();
        assert_eq!(
            rec["plausibility"]["clamped_reflectance"].as_f64().unwrap(),
            p.clamped_reflectance
        );
        assert_eq!(
            rec["plausibility"]["max_albedo"].as_f64().unwrap(),
            p.max_albedo
        );
        assert_eq!(
            rec["confidence"]["variance"].as_f64().unwrap(),
            blend.confidence().variance
        );
        // The file is the blend's table.
        let written = MerlTable::read(tmp.path().join(format!("{}.binary", rule.name()))).unwrap();
        assert_eq!(written.raw(), blend.table().unwrap().raw());
    }
}

#[test]
fn far_from_the_data_the_tools_say_the_model_knows_little() {
    let tmp = tempfile::tempdir().unwrap();
    let model_path = fitted(tmp.path());
    let out_path = tmp.path().join("far.binary");
    let out = brdf_atlas([
        "reconstruct".as_ref(),
        model_path.as_os_str(),
        "--at".as_ref(),
        "25,-25".as_ref(),
        "-o".as_ref(),
        out_path.as_os_str(),
    ]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.contains("confidence: predictive variance 1.0000"),
        "{stdout}"
    );
    assert!(
        stdout.contains("plausibility: the clamp to >= 0 removes"),
        "{stdout}"
    );
    // One warning line about the point (and one about the test's small dims).
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("knows little"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(
        warnings[0].starts_with("warning: ") && warnings[0].contains("at (25.0000, -25.0000)"),
        "{stderr}"
    );
    // Near a material: no warning.
    let model = brdf_atlas_core::Atlas::new(Model::open(&model_path).unwrap());
    let x = [model.latent()[(0, 0)], model.latent()[(0, 1)]];
    let out = brdf_atlas([
        "eval".as_ref(),
        model_path.as_os_str(),
        "--at".as_ref(),
        format!("{},{}", x[0], x[1]).as_ref(),
        "--wi".as_ref(),
        "30,0".as_ref(),
        "--wo".as_ref(),
        "30,180".as_ref(),
        "--plausibility".as_ref(),
    ]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    let last: Vec<&str> = stdout.lines().rev().take(2).collect();
    assert!(
        last[0].starts_with("plausibility: the clamp removes"),
        "{stdout}"
    );
    assert!(
        last[1].starts_with("confidence: predictive variance 0.0"),
        "{stdout}"
    );
}

#[test]
fn an_unknown_blend_rule_is_one_clear_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = brdf_atlas([
        "reconstruct".as_ref(),
        tmp.path().join("m.atlas").as_os_str(),
        "--at".as_ref(),
        "0,0".as_ref(),
        "--blend".as_ref(),
        "convex".as_ref(),
        "-o".as_ref(),
        tmp.path().join("x.binary").as_os_str(),
    ]);
    let (_, stderr) = texts(&out);
    assert!(!out.status.success());
    assert!(
        stderr.contains("expected floor, gp or plausible, got \"convex\""),
        "{stderr}"
    );
}

#[test]
fn a_map_shows_the_floor_by_default_the_gp_on_request_and_the_plausible_rule_has_none() {
    let tmp = tempfile::tempdir().unwrap();
    let model_path = fitted(tmp.path());
    let model = brdf_atlas_core::Atlas::new(Model::open(&model_path).unwrap());
    let map = |blend: Option<&str>, png: &str| {
        let png = tmp.path().join(png);
        let mut args = vec!["map", model_path.to_str().unwrap(), "--size", "48"];
        args.extend(blend.map(|b| ["--blend", b]).into_iter().flatten());
        args.extend(["-o", png.to_str().unwrap()]);
        brdf_atlas(args)
    };
    let sidecar = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join(name)).unwrap()).unwrap()
    };
    let out = map(None, "floor.png");
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(!stdout.contains("blend)"), "{stdout}");
    let floor = sidecar("floor.json");
    assert_eq!(floor["blend"], "floor");
    // The map's pixels are the library's map of the floor rule.
    let want = |rule| {
        let view = brdf_atlas_core::View::default();
        let map = model.map(
            brdf_atlas_core::MapRequest::new(48, 48)
                .view(view)
                .rule(rule),
        );
        serde_json::to_value(map.unwrap().method).unwrap()
    };
    assert_eq!(want(BlendRule::Floor), floor["method"], "{floor}");
    let out = map(Some("gp"), "gp.png");
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("(gp blend)"), "{stdout}");
    let gp = sidecar("gp.json");
    assert_eq!(gp["blend"], "gp");
    assert_eq!(want(BlendRule::Gp), gp["method"], "{gp}");
    // The plausible rule: one line naming it, no picture.
    let out = map(Some("plausible"), "plausible.png");
    let (_, stderr) = texts(&out);
    assert!(!out.status.success());
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("plausible rule's albedo has no map"),
        "{stderr}"
    );
    assert!(!tmp.path().join("plausible.png").exists());
    assert!(!tmp.path().join("plausible.json").exists());
}
