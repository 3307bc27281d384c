//! End-to-end tests of `brdf-atlas report` on small synthetic databases:
//! every file is written and readable, and a failing run leaves no partial
//! report and keeps an earlier one.

mod common;

use std::path::Path;

use common::{brdf_atlas, fit, synth, texts};

fn leftovers(parent: &Path) -> Vec<String> {
    std::fs::read_dir(parent)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-") || n.ends_with(".old"))
        .collect()
}

#[test]
fn report_writes_every_file_and_fails_atomically() {
    let tmp = tempfile::tempdir().unwrap();
    let merl = tmp.path().join("merl");
    let made = brdf_atlas([
        "synth".as_ref(),
        "--count".as_ref(),
        "6".as_ref(),
        "--dims".as_ref(),
        "12,12,24".as_ref(),
        merl.as_os_str(),
    ]);
    assert!(made.status.success(), "{:?}", texts(&made));
    let rep = tmp.path().join("rep");
    let run = brdf_atlas([
        "report".as_ref(),
        merl.as_os_str(),
        "-o".as_ref(),
        rep.as_os_str(),
        "--quick".as_ref(),
        "--prepare".as_ref(),
    ]);
    let (stdout, stderr) = texts(&run);
    assert!(run.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("report.md"), "{stdout}");
    let md = std::fs::read_to_string(rep.join("report.md")).unwrap();
    for want in [
        "Machine:",
        "6 materials",
        "12x12x24",
        "Leave-one-out",
        "L-BFGS",
        "f64",
        "on every 8th phi_d bin (`--quick`)",
        "a 2 x 2 grid over the map's default view",
    ] {
        assert!(md.contains(want), "report.md lacks {want:?}:\n{md}");
    }
    // How long each section took: a row per section, each with a time.
    let times = md
        .split("## Time by section")
        .nth(1)
        .unwrap_or_else(|| panic!("report.md lacks the section times:\n{md}"));
    for section in [
        "Opening and validating the files",
        "Fidelity: the settings compared",
        "Leave-one-out and fits, log transform",
        "Leave-one-out and fits, raw transform",
        "Fitting: Hooke-Jeeves' minimum step sweep",
        "Store precision",
        "Albedo map: sample count vs error vs time",
        "Albedo map: the default method and the prepared map",
        "Albedo map: size vs time",
        "Plausibility grid",
        "Tables and plots",
    ] {
        let line = times
            .lines()
            .find(|l| l.starts_with(&format!("| {section}")))
            .unwrap_or_else(|| panic!("no time for {section:?}:\n{times}"));
        // Wall and CPU time.
        let cells: Vec<f64> = line
            .split('|')
            .skip(2)
            .filter(|c| !c.trim().is_empty())
            .map(|c| {
                c.trim()
                    .trim_end_matches(" s")
                    .parse()
                    .unwrap_or_else(|_| panic!("{line}"))
            })
            .collect();
        assert!(
            cells.len() == 2 && cells.iter().all(|&s| s >= 0.0),
            "{line}"
        );
    }
    // Every image the report links is there and decodes.
    for png in [
        "loo.png",
        "loo-reflectance.png",
        "optimizers.png",
        "map-samples.png",
        "map-size.png",
    ] {
        assert!(md.contains(&format!("({png})")), "{png} not linked");
        let file = std::fs::File::open(rep.join(png)).unwrap();
        let reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap_or_else(|e| panic!("{png}: {e}"));
        assert_eq!((reader.info().width, reader.info().height), (720, 440));
    }
    // CSV tables: q = 1..3, two transforms, GPLVM, its L-BFGS twin, the
    // convex blend, the GP's weights projected to convex ones, the
    // plausible rule and the soft floor at q = 2, and PCA; for the log transform also the
    // learned kernel's GP, convex blend and plausible rule.
    let loo = std::fs::read_to_string(rep.join("loo.csv")).unwrap();
    assert_eq!(
        loo.lines().count(),
        1 + 2 * (3 + 1 + 1 + 1 + 1 + 1 + 3) + 3,
        "{loo}"
    );
    for t in ["log", "raw"] {
        assert!(
            loo.contains(&format!("{t},gplvm-projected,2,"))
                && loo.contains(&format!("{t},gplvm-floor,2,")),
            "{t}: {loo}"
        );
    }
    // The prepared map beside the field and the per-pixel rule, and the
    // answer to "in real time?" from its figures.
    assert_eq!(
        md.matches("| prepared lattice, ").count(),
        2,
        "report.md lacks the prepared map's rows:\n{md}"
    );
    assert!(
        md.contains("**Can the map be drawn in real time?** Yes, once the model's map is prepared"),
        "report.md lacks the answer from the prepared map:\n{md}"
    );
    assert!(
        md.contains("projected to the nearest convex ones"),
        "report.md lacks the projected weights' line"
    );
    assert!(
        md.contains("lifted softly onto a floor"),
        "report.md lacks the soft floor's line"
    );
    for method in ["gplvm-learned", "convex-learned", "gplvm-learned-plausible"] {
        assert!(loo.contains(&format!("log,{method},2,")), "{method}: {loo}");
    }
    for line in loo.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        for v in &cols[3..6] {
            let v: f64 = v.parse().unwrap_or_else(|_| panic!("{line}"));
            assert!(v.is_finite() && v >= 0.0, "{line}");
        }
    }
    let per = std::fs::read_to_string(rep.join("loo-materials.csv")).unwrap();
    assert_eq!(per.lines().count(), 1 + (2 * 11 + 3) * 6);
    // Plausibility: a 2 x 2 grid, three models (log with the fixed and the
    // learned kernel, raw), three rules; the plausible rule never clamps
    // more than the GP at the same point, and the soft floor (the default)
    // never clamps at all.
    assert!(md.contains("## Plausibility") && md.contains("(plausibility.png)"));
    assert!(md.contains("How spread the map is") && md.contains("log with the learned kernel"));
    let pl = std::fs::read_to_string(rep.join("plausibility.csv")).unwrap();
    let rows: Vec<Vec<String>> = pl
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 3 * 3 * 4, "{pl}");
    for r in &rows {
        let clamped: f64 = r[5].parse().unwrap();
        assert!((0.0..=1.0).contains(&clamped), "{r:?}");
        if r[2] == "floor" {
            assert_eq!(clamped, 0.0, "{r:?}");
        }
        if r[2] == "plausible" {
            let gp = rows
                .iter()
                .find(|g| g[..2] == r[..2] && g[2] == "gp" && g[3..5] == r[3..5])
                .unwrap();
            let gp_clamped: f64 = gp[5].parse().unwrap();
            assert!(
                clamped <= gp_clamped * (1.0 + 1e-9) + 1e-15,
                "{r:?} vs {gp:?}"
            );
        }
    }
    let file = std::fs::File::open(rep.join("plausibility.png")).unwrap();
    png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("plausibility.png decodes");
    for csv in [
        "fits.csv",
        "stores.csv",
        "precision.csv",
        "map-samples.csv",
        "map-size.csv",
    ] {
        let text = std::fs::read_to_string(rep.join(csv)).unwrap();
        assert!(text.lines().count() >= 2, "{csv}: {text}");
    }
    // Nothing but the report: no stores, no staging directories.
    let names: Vec<String> = std::fs::read_dir(&rep)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names.iter().all(|n| !n.ends_with(".store") && n != "work"),
        "{names:?}"
    );
    assert!(leftovers(tmp.path()).is_empty());

    // A failing run (a corrupt MERL file in the directory) names the file,
    // exits 1, keeps the earlier report as it was and leaves nothing behind.
    let before = std::fs::read(rep.join("report.md")).unwrap();
    std::fs::write(merl.join("zz-broken.binary"), b"not a table").unwrap();
    let fail = brdf_atlas([
        "report".as_ref(),
        merl.as_os_str(),
        "-o".as_ref(),
        rep.as_os_str(),
        "--quick".as_ref(),
    ]);
    let (_, stderr) = texts(&fail);
    assert_eq!(fail.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("zz-broken.binary"), "{stderr}");
    assert_eq!(std::fs::read(rep.join("report.md")).unwrap(), before);
    assert!(
        leftovers(tmp.path()).is_empty(),
        "{:?}",
        leftovers(tmp.path())
    );
    // Into a new directory: none is created.
    let fresh = tmp.path().join("fresh");
    let fail = brdf_atlas([
        "report".as_ref(),
        merl.as_os_str(),
        "-o".as_ref(),
        fresh.as_os_str(),
        "--quick".as_ref(),
    ]);
    assert_eq!(fail.status.code(), Some(1));
    assert!(!fresh.exists());
    assert!(leftovers(tmp.path()).is_empty());
    // A directory that is not a report is never replaced.
    let fail = brdf_atlas([
        "report".as_ref(),
        merl.as_os_str(),
        "-o".as_ref(),
        merl.as_os_str(),
    ]);
    let (_, stderr) = texts(&fail);
    assert_eq!(fail.status.code(), Some(1));
    assert!(stderr.contains("not a brdf-atlas report"), "{stderr}");
}

/// `--growth` fits synthetic databases of each size with both optimisers;
/// its L-BFGS cost (`fit`'s default) is the one `fit` reaches on the same materials
/// (`synth`'s generator, the same seed) written as files (a separate path:
/// files, the store pass, the CLI).
#[test]
fn growth_section_matches_fit_on_the_same_materials() {
    let tmp = tempfile::tempdir().unwrap();
    let merl = tmp.path().join("merl");
    synth(&merl, 4, "8,8,16", 1);
    let rep = tmp.path().join("rep");
    let run = brdf_atlas([
        "report".as_ref(),
        merl.as_os_str(),
        "-o".as_ref(),
        rep.as_os_str(),
        "--quick".as_ref(),
        "--growth".as_ref(),
        "12,30".as_ref(),
    ]);
    let (stdout, stderr) = texts(&run);
    assert!(run.status.success(), "{stdout}\n{stderr}");
    let md = std::fs::read_to_string(rep.join("report.md")).unwrap();
    assert!(
        md.contains("## Growth with the number of materials"),
        "{md}"
    );
    assert!(
        md.contains("| Growth: fits of synthetic databases | "),
        "the growth section's time: {md}"
    );
    assert!(rep.join("growth.png").is_file());
    let csv = std::fs::read_to_string(rep.join("growth.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let sizes: Vec<(&str, &str)> = rows.iter().map(|r| (r[0], r[1])).collect();
    assert_eq!(
        sizes,
        [
            ("12", "hooke-jeeves"),
            ("12", "lbfgs"),
            ("30", "hooke-jeeves"),
            ("30", "lbfgs")
        ]
    );
    // The 30-material L-BFGS fit again, from the same materials (seed 1)
    // written as files, through `fit` with its defaults.
    let same = tmp.path().join("same");
    synth(&same, 30, "16,16,32", 1);
    let stdout = fit(&same, &tmp.path().join("same.atlas"), &[]);
    // `cost   A -> B (...)`: B, printed with 7 significant digits or more.
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("cost"))
        .unwrap();
    let printed: f64 = line
        .split("->")
        .nth(1)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(rows[3][1], "lbfgs");
    let reported: f64 = rows[3][3].parse().unwrap();
    assert!(
        (printed - reported).abs() <= 1e-6 * reported.abs(),
        "fit printed {printed}, the report {reported}"
    );
    // Sizes out of range are refused with the option named.
    let bad = brdf_atlas([
        "report".as_ref(),
        merl.as_os_str(),
        "-o".as_ref(),
        tmp.path().join("bad").as_os_str(),
        "--growth".as_ref(),
        "2".as_ref(),
    ]);
    let (_, stderr) = texts(&bad);
    assert_eq!(bad.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--growth"), "{stderr}");
    // --quick and --thorough ask for opposite things.
    let both = brdf_atlas([
        "report".as_ref(),
        merl.as_os_str(),
        "-o".as_ref(),
        tmp.path().join("both").as_os_str(),
        "--quick".as_ref(),
        "--thorough".as_ref(),
    ]);
    let (_, stderr) = texts(&both);
    assert_eq!(both.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--thorough"), "{stderr}");
}
