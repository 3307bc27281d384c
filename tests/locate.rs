//! End-to-end tests of `locate`: where a MERL file lands in a model's
//! latent plane, inside the fit's box and beyond it.

mod common;

use std::path::PathBuf;

use common::{Fixture, binaries, brdf_atlas, point_after_at, synth, texts};

#[test]
fn locate_puts_materials_inside_the_box_near_themselves() {
    let fx = Fixture::new(6, &["--transform", "raw"]);
    let files = binaries(&fx.data());
    let mut args = vec![PathBuf::from("locate"), fx.model()];
    args.extend(files.iter().take(3).cloned());
    let out = brdf_atlas(&args);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    let located: Vec<&str> = stdout.lines().filter(|l| l.contains(": at (")).collect();
    assert_eq!(located.len(), 3, "{stdout}");
    for (line, file) in located.iter().zip(&files) {
        assert!(line.starts_with(&file.display().to_string()), "{line}");
        let x = point_after_at(line);
        assert_eq!(x.len(), 2, "{line}");
        assert!(x.iter().all(|v| (-1.0..=1.0).contains(v)), "{line}");
    }
    assert!(
        stdout.contains("rmse") && stdout.contains("spread"),
        "{stdout}"
    );
    // A training material is its own nearest neighbour.
    for (block, file) in stdout.split(": at (").skip(1).zip(&files) {
        let nearest = block
            .lines()
            .find(|l| l.trim_start().starts_with("nearest"))
            .unwrap();
        let first = nearest.trim_start()["nearest".len()..].trim_start();
        let name = file.file_stem().unwrap().to_str().unwrap();
        assert!(first.starts_with(name), "{nearest} for {name}");
    }

    // Bad files get one line each; good ones are still reported.
    let wrong_dims = fx.path("other");
    synth(&wrong_dims, 1, "8,8,16", 2);
    let out = brdf_atlas([
        PathBuf::from("locate"),
        fx.model(),
        binaries(&wrong_dims)[0].clone(),
        files[0].clone(),
        fx.path("missing.binary"),
    ]);
    let (stdout, stderr) = texts(&out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stdout.lines().filter(|l| l.contains(": at (")).count(), 1);
    let errors: Vec<&str> = stderr.lines().collect();
    assert_eq!(errors.len(), 2, "{stderr}");
    assert!(
        errors[0].contains("8x8x16") && errors[0].contains("16x16x32"),
        "{stderr}"
    );
    assert!(errors[1].contains("missing.binary"), "{stderr}");
}

#[test]
fn locate_reaches_beyond_the_box_and_says_so() {
    let fx = Fixture::new(6, &[]);
    let beyond = fx.path("beyond.binary");
    let out = brdf_atlas([
        "reconstruct".as_ref(),
        fx.model().as_os_str(),
        "--at".as_ref(),
        "1.6,0.3".as_ref(),
        "-o".as_ref(),
        beyond.as_os_str(),
        // locate matches the GP's blend (what the latent space was fitted
        // on); so far out the soft floor lifts the values it matches.
        "--blend".as_ref(),
        "gp".as_ref(),
    ]);
    assert!(out.status.success(), "{}", texts(&out).1);
    let out = brdf_atlas([PathBuf::from("locate"), fx.model(), beyond]);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    let x = point_after_at(stdout.lines().next().unwrap());
    assert!(
        (x[0] - 1.6).abs() < 0.03 && (x[1] - 0.3).abs() < 0.03,
        "{stdout}"
    );
    assert!(
        stdout.contains("outside the map's default view") && stdout.contains("--view=-2,2,-2,2"),
        "{stdout}"
    );
}

#[test]
fn a_located_training_material_is_given_back_under_the_default_transform() {
    let fx = Fixture::new(6, &[]);
    let files = binaries(&fx.data());
    let mut args = vec![PathBuf::from("locate"), fx.model()];
    args.extend(files.iter().cloned());
    let out = brdf_atlas(&args);
    let (stdout, stderr) = texts(&out);
    assert!(out.status.success(), "{stderr}");
    // The nearest material (itself, at its own point) gives it back: the
    // albedo of every channel within 2%; so does the point it lands at.
    let percents = |line: &str| -> Vec<f64> {
        line.split('%')
            .filter_map(|p| p.rsplit([' ', ',', ':']).next()?.parse().ok())
            .take(3)
            .collect()
    };
    let mut judged = 0;
    for block in stdout.split(": at (").skip(1) {
        let lines: Vec<&str> = block.lines().collect();
        let at = lines
            .iter()
            .position(|l| l.trim_start().starts_with("there"))
            .unwrap();
        for line in [lines[at], lines[at + 1]] {
            let p = percents(line);
            assert_eq!(p.len(), 3, "{line}");
            assert!(p.iter().all(|&e| e < 2.0), "{line}");
            judged += 1;
        }
    }
    assert_eq!(judged, 2 * files.len(), "{stdout}");
}
