//! Golden-image test of `map`, after resvg's harness: a small deterministic
//! map is compared with a committed reference, pixel by pixel, with a
//! threshold. On failure the actual image and a diff image are written under
//! the target directory and their paths are in the message. To accept a
//! deliberate change, regenerate the reference:
//!
//!     BRDF_ATLAS_UPDATE_GOLDEN=1 cargo test --release --test golden
//!
//! The map depends on the whole pipeline (synthesis, store, fit, quadrature,
//! contours, drawing), so a change anywhere shows here first.

mod common;

use std::path::{Path, PathBuf};

use common::{fit, map, synth, texts};

/// The committed reference.
const REFERENCE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/map-small.png");
/// Set to 1 to write the current output as the new reference.
const UPDATE: &str = "BRDF_ATLAS_UPDATE_GOLDEN";
/// A pixel differs when a channel differs by more than this (of 255).
const CHANNEL_TOLERANCE: u8 = 3;
/// The test fails when more than this fraction of pixels differ.
const MAX_DIFFERING: f64 = 0.005;

/// An 8-bit RGB image.
struct Image {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

fn decode(path: &Path) -> Result<Image, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let mut buf = vec![0; reader.output_buffer_size().expect("fits in memory")];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    if info.color_type != png::ColorType::Rgb || info.bit_depth != png::BitDepth::Eight {
        return Err(format!(
            "{}: {:?} {:?}, expected 8-bit RGB",
            path.display(),
            info.color_type,
            info.bit_depth
        ));
    }
    buf.truncate(info.buffer_size());
    Ok(Image {
        width: info.width,
        height: info.height,
        rgb: buf,
    })
}

fn encode(path: &Path, image: &Image) {
    let file = std::fs::File::create(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), image.width, image.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()
        .and_then(|mut w| w.write_image_data(&image.rgb))
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// Pixels whose largest channel difference exceeds the tolerance, and a
/// diff image: the reference greyed out, differing pixels in red (brighter
/// for larger differences).
fn compare(actual: &Image, reference: &Image) -> (usize, u8, Image) {
    let mut differing = 0;
    let mut worst = 0;
    let mut diff = Vec::with_capacity(reference.rgb.len());
    for (a, r) in actual.rgb.chunks(3).zip(reference.rgb.chunks(3)) {
        let d = (0..3).map(|c| a[c].abs_diff(r[c])).max().unwrap_or(0);
        worst = worst.max(d);
        if d > CHANNEL_TOLERANCE {
            differing += 1;
            diff.extend([128u8.saturating_add(d.saturating_mul(4).min(127)), 0, 0]);
        } else {
            let grey = ((r[0] as u32 + r[1] as u32 + r[2] as u32) / 6) as u8;
            diff.extend([grey; 3]);
        }
    }
    let image = Image {
        width: reference.width,
        height: reference.height,
        rgb: diff,
    };
    (differing, worst, image)
}

/// Draw the small map: six 12x12x24 materials (seed 3), log fit, 64x64, no labels.
fn draw_small_map(dir: &Path) -> PathBuf {
    let data = dir.join("merl");
    synth(&data, 6, "12,12,24", 3);
    let model = dir.join("small.atlas");
    fit(&data, &model, &[]);
    let png_path = dir.join("map-small.png");
    let out = map(&model, &png_path, &[&"--size", &"64", &"--no-labels"]);
    assert!(out.status.success(), "map: {}", texts(&out).1);
    png_path
}

#[test]
fn small_map_matches_its_reference() {
    let dir = tempfile::tempdir().unwrap();
    let made = draw_small_map(dir.path());
    let actual = decode(&made).unwrap();
    assert_eq!((actual.width, actual.height), (64, 64));

    if std::env::var_os(UPDATE).is_some_and(|v| v == "1") {
        std::fs::copy(&made, REFERENCE).unwrap();
        println!("{UPDATE}=1: wrote the reference {REFERENCE}");
        return;
    }
    let reference = decode(Path::new(REFERENCE)).unwrap_or_else(|e| {
        panic!("no usable reference ({e}); create it with {UPDATE}=1 cargo test --release --test golden")
    });
    assert_eq!(
        (actual.width, actual.height),
        (reference.width, reference.height),
        "size differs from {REFERENCE}"
    );
    let (differing, worst, diff) = compare(&actual, &reference);
    let pixels = (reference.width * reference.height) as usize;
    if differing as f64 > MAX_DIFFERING * pixels as f64 {
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("golden");
        std::fs::create_dir_all(&out).unwrap();
        let actual_path = out.join("map-small.actual.png");
        let diff_path = out.join("map-small.diff.png");
        std::fs::copy(&made, &actual_path).unwrap();
        encode(&diff_path, &diff);
        panic!(
            "{differing} of {pixels} pixels differ by more than {CHANNEL_TOLERANCE}/255 \
             (largest difference {worst}; at most {:.0} may): see {} (red: differing pixels) \
             and {}; if the change is intended, rerun with {UPDATE}=1",
            MAX_DIFFERING * pixels as f64,
            diff_path.display(),
            actual_path.display()
        );
    }
}

#[test]
fn the_comparison_catches_a_changed_image_and_tolerates_noise() {
    let image = |rgb: Vec<u8>| Image {
        width: 20,
        height: 20,
        rgb,
    };
    let base = image((0..1200).map(|i| (i % 251) as u8).collect());
    // Off by the tolerance everywhere: equal.
    let noisy = image(base.rgb.iter().map(|v| v.saturating_add(3)).collect());
    assert_eq!(compare(&noisy, &base).0, 0);
    // Four pixels changed a lot: counted, and red in the diff.
    let mut changed = base.rgb.clone();
    for p in [0, 7, 100, 399] {
        changed[3 * p] = changed[3 * p].wrapping_add(128);
    }
    let changed = image(changed);
    let (n, worst, diff) = compare(&changed, &base);
    assert_eq!(n, 4);
    assert!(worst > 100);
    assert_eq!(diff.rgb[3 * 7 + 1], 0);
    assert!(diff.rgb[3 * 7] >= 128);
}
