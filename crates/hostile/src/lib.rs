//! Hostile inputs for the tests of every reader of brdf-atlas (MERL files,
//! model files, stores, map sidecars), generated on the fly, never
//! committed: each [`Case`] is a broken file with the words its one-line
//! error must contain and the C ABI status it must give. Also the small
//! valid inputs the fuzzers start from ([`small_model`]).
//!
//! Used by `tests/hostile.rs` (through the command-line tool), by
//! `crates/ffi/tests` (through the C ABI, from Rust and from C), and by the
//! fuzzers' seed corpora (`fuzz/`).
#![warn(missing_docs)]

pub mod fuzz;

use std::path::{Path, PathBuf};

use brdf_atlas_core::{FitOptions, fit_dir, store_path_for};
use brdf_atlas_core::{GplvmParams, Model, NoProgress, Precision, TransformKind};
use brdf_atlas_pictures::map_picture::{Picture, read_sidecar, write_sidecar};
use brdf_merl::{Dims, synth};
use serde_json::{Value, json};

/// The C ABI status a case must give (`BRDF_ATLAS_STATUS_...`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// `IO` (5): the OS refused to open the file.
    Io = 5,
    /// `BAD_FILE` (6): a model or store file is malformed or changed.
    BadFile = 6,
    /// `BAD_MERL` (7): a MERL file is malformed.
    BadMerl = 7,
}

/// One broken file.
#[derive(Debug, Clone)]
pub struct Case {
    /// The file handed to the reader (a MERL file, a model or a sidecar).
    pub path: PathBuf,
    /// The file the error must name: `path`, or the store of a model.
    pub names: PathBuf,
    /// Words the one-line error must contain.
    pub want: String,
    /// The status the C ABI must return.
    pub status: Status,
}

impl Case {
    /// A case whose error must name the file handed to the reader.
    pub fn new(path: PathBuf, want: impl Into<String>, status: Status) -> Case {
        Case {
            names: path.clone(),
            path,
            want: want.into(),
            status,
        }
    }

    /// Check a one-line error message against the case: it names the file,
    /// contains [`Case::want`] and is one line. `Err` says what is wrong.
    pub fn check_message(&self, message: &str) -> Result<(), String> {
        let name = self
            .names
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !message.contains(&name) {
            return Err(format!(
                "{}: message does not name {name}: {message}",
                self.label()
            ));
        }
        if !message.contains(&self.want) {
            return Err(format!(
                "{}: expected {:?} in {message}",
                self.label(),
                self.want
            ));
        }
        if message.trim_end().contains('\n') {
            return Err(format!("{}: more than one line: {message}", self.label()));
        }
        Ok(())
    }

    /// The case's file name, for messages.
    pub fn label(&self) -> String {
        self.path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    path
}

/// `bytes` written to `dir/name`: a case whose error names that file.
fn written(dir: &Path, name: &str, bytes: &[u8], want: &str, status: Status) -> Case {
    Case::new(write(dir, name, bytes), want, status)
}

/// The 12-byte header of a MERL file of dims `a x b x c`.
pub fn merl_header(a: i32, b: i32, c: i32) -> Vec<u8> {
    [a, b, c].iter().flat_map(|d| d.to_le_bytes()).collect()
}

/// A valid MERL file of dims `a x b x c` with every raw value `v`.
pub fn merl_bytes(a: i32, b: i32, c: i32, v: f64) -> Vec<u8> {
    let mut bytes = merl_header(a, b, c);
    let n = 3 * (a * b * c) as usize;
    bytes.extend(std::iter::repeat_n(v.to_le_bytes(), n).flatten());
    bytes
}

/// A Git LFS pointer, as a repository holds it in place of a large file.
pub const LFS_POINTER: &[u8] = b"version https://git-lfs.github.com/spec/v1\noid sha256:4d7a214614ab2935c943f9e0ff69d22eadbb8f32b1258daaa5e2ca24d17e2393\nsize 34992012\n";

/// Broken MERL files (`.binary`) written into `dir` (which should hold
/// nothing else): every way a MERL reader must refuse a file. A valid
/// table for them to go with has dims 4x4x8.
pub fn merl_cases(dir: &Path) -> Vec<Case> {
    let good = merl_bytes(4, 4, 8, 750.0);
    let with = |index: usize, v: f64| {
        let mut b = good.clone();
        let at = 12 + 8 * index;
        b[at..at + 8].copy_from_slice(&v.to_le_bytes());
        b
    };
    let bins = 4 * 4 * 8;
    let mut tiny_1024 = merl_header(1024, 1024, 1024);
    tiny_1024.extend([0u8; 64]);
    let bad =
        |name: &str, bytes: &[u8], want: &str| written(dir, name, bytes, want, Status::BadMerl);
    vec![
        bad("empty.binary", b"", "0 bytes is too short for a MERL file"),
        bad("eleven-bytes.binary", &good[..11], "11 bytes is too short"),
        bad(
            "header-only.binary",
            &good[..12],
            "header says 4x4x8 (needs 3084 bytes) but the file has 12 bytes",
        ),
        bad(
            "truncated.binary",
            &good[..good.len() - 100],
            "(needs 3084 bytes) but the file has 2984 bytes",
        ),
        bad(
            "one-byte-too-many.binary",
            &[&good[..], &[0]].concat(),
            "but the file has 3085 bytes",
        ),
        bad(
            "dims-2^31.binary",
            &[&merl_header(i32::MIN, i32::MIN, i32::MIN)[..], &good[12..]].concat(),
            "header says -2147483648x-2147483648x-2147483648, expected three positive dims of at most 1024",
        ),
        bad(
            "dims-int-max.binary",
            &merl_header(i32::MAX, i32::MAX, i32::MAX),
            "expected three positive dims of at most 1024",
        ),
        bad(
            "dims-1024-cubed.binary",
            &tiny_1024,
            "header says 1024x1024x1024 (needs 25769803788 bytes) but the file has 76 bytes",
        ),
        bad(
            "zero-dim.binary",
            &merl_header(0, 90, 180),
            "header says 0x90x180, expected three positive dims",
        ),
        bad(
            "negative-dim.binary",
            &merl_header(-4, 4, 8),
            "header says -4x4x8, expected three positive dims",
        ),
        bad(
            "nan.binary",
            &with(bins + 7, f64::NAN),
            "value 135 (green channel, bin 7) is NaN, expected a finite number",
        ),
        bad(
            "inf.binary",
            &with(5, f64::INFINITY),
            "value 5 (red channel, bin 5) is inf",
        ),
        bad(
            "minus-inf.binary",
            &with(3 * bins - 1, f64::NEG_INFINITY),
            "value 383 (blue channel, bin 127) is -inf",
        ),
        bad(
            "absurd-everywhere.binary",
            &merl_bytes(4, 4, 8, 1e300),
            "value 0 (red channel, bin theta_h 0 theta_d 0 phi_d 0) is a reflectance of \
             6.667e296 per steradian, beyond any physical one; expected at most 1e8",
        ),
        bad(
            "absurd-one.binary",
            &with(bins + 37, 1e12),
            "value 165 (green channel, bin theta_h 1 theta_d 0 phi_d 5) is a reflectance \
             of 7.667e8 per steradian",
        ),
        bad(
            "lfs-pointer.binary",
            LFS_POINTER,
            "is a Git LFS pointer file, not MERL data",
        ),
        bad(
            "text.binary",
            b"this is a text file, not a table\n",
            "expected three positive dims",
        ),
        bad(
            "png.binary",
            b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x10\0\0\0\x10\x08\x02\0\0\0",
            "expected three positive dims",
        ),
        Case::new(
            dir.join("missing.binary"),
            "No such file or directory",
            Status::Io,
        ),
    ]
}

/// Fit a small model of `count` synthetic materials of `dims` into `dir`
/// (data in `dir/data`, model `dir/NAME`): the same bytes on every run.
pub fn fit_small(dir: &Path, name: &str, count: usize, dims: Dims) -> PathBuf {
    let data = dir.join("data");
    synth::write_dir(&data, count, dims, 3).expect("write the tables");
    let model = dir.join(name);
    let options = FitOptions {
        params: GplvmParams::new(2).check().expect("default parameters"),
        transform: TransformKind::Log,
        precision: Precision::F32,
    };
    fit_dir(&data, &model, &options, &NoProgress).expect("fit");
    model
}

/// The smallest useful model, the fuzzers' seed: 4 materials of 4x4x8,
/// `dir/small.atlas` and `dir/small.atlas.store` (10 kB).
pub fn small_model(dir: &Path) -> PathBuf {
    fit_small(dir, "small.atlas", 4, Dims::new(4, 4, 8).expect("dims"))
}

/// A map sidecar of `model` (2-D) at `path`: 6x5 pixels, as `map` writes it.
pub fn small_sidecar(model: &Path, path: &Path) -> PathBuf {
    let m = brdf_atlas_core::Atlas::new(Model::open(model).expect("a valid model"));
    let map = m
        .map(brdf_atlas_core::MapRequest::new(6, 5).samples(Some(16)))
        .expect("map");
    write_sidecar(path, &Picture::new(&m, map, 3).sidecar(model)).expect("write sidecar");
    path.to_path_buf()
}

/// A model file beside a copy of `model`'s store: `dir/NAME` with its store
/// at `dir/NAME.store`, the JSON edited by `edit`, the store bytes by
/// `edit_store`. The model's recorded store path is the new one.
fn model_variant(
    dir: &Path,
    model: &Path,
    name: &str,
    edit: impl FnOnce(&mut Value),
    edit_store: impl FnOnce(&mut Vec<u8>),
) -> PathBuf {
    let mut v: Value =
        serde_json::from_slice(&std::fs::read(model).expect("model")).expect("model JSON");
    let path = dir.join(name);
    let store = store_path_for(&path);
    v["store"]["path"] = json!(store.file_name().unwrap().to_string_lossy());
    edit(&mut v);
    let mut bytes = std::fs::read(store_path_for(model)).expect("store");
    edit_store(&mut bytes);
    std::fs::write(&store, bytes).expect("write store");
    write(dir, name, &serde_json::to_vec_pretty(&v).expect("JSON"))
}

/// Broken models written into `dir`, each derived from the valid `model`
/// (a 2-D model of at least 3 materials, fitted by this version): every way
/// opening a model and its store must fail.
pub fn model_cases(dir: &Path, model: &Path) -> Vec<Case> {
    let text = std::fs::read_to_string(model).expect("model");
    let n = brdf_atlas_core::Atlas::new(Model::open(model).expect("a valid model"))
        .names()
        .len();
    let raw =
        |name: &str, bytes: &[u8], want: &str| written(dir, name, bytes, want, Status::BadFile);
    let json = |name: &str, edit: &dyn Fn(&mut Value), want: &str| {
        let path = model_variant(dir, model, name, edit, |_| {});
        Case::new(path, want, Status::BadFile)
    };
    let store = |name: &str, edit: &dyn Fn(&mut Vec<u8>), want: &str| {
        let path = model_variant(dir, model, name, |_| {}, edit);
        Case {
            names: store_path_for(&path),
            path,
            want: want.to_string(),
            status: Status::BadFile,
        }
    };
    let u32_at =
        |o: usize, v: u32| move |b: &mut Vec<u8>| b[o..o + 4].copy_from_slice(&v.to_le_bytes());
    vec![
        raw(
            "empty.atlas",
            b"",
            "empty file, expected a brdf-atlas model",
        ),
        raw(
            "lfs-pointer.atlas",
            LFS_POINTER,
            "is a Git LFS pointer file, not a brdf-atlas model",
        ),
        raw(
            "truncated.atlas",
            &text.as_bytes()[..text.len() / 2],
            "not a brdf-atlas model (invalid JSON: EOF while parsing",
        ),
        raw(
            "binary.atlas",
            &merl_bytes(2, 2, 4, 1.0),
            "not a brdf-atlas model (invalid JSON",
        ),
        raw(
            "other-json.atlas",
            b"{\"hello\": [1, 2, 3]}",
            "not a brdf-atlas model (expected \"format\": \"brdf-atlas-model\")",
        ),
        raw(
            "number-overflow.atlas",
            text.replacen(
                "\"latent\": [\n    [\n      ",
                "\"latent\": [\n    [\n      1e999, ",
                1,
            )
            .as_bytes(),
            "invalid JSON: number out of range",
        ),
        json(
            "newer.atlas",
            &|v| v["version"] = json!(2),
            "model format version 2 was written by a newer brdf-atlas (this build reads version 1)",
        ),
        json(
            "version-0.atlas",
            &|v| v["version"] = json!(0),
            "model format version 0, this build reads version 1",
        ),
        json(
            "no-version.atlas",
            &|v| {
                v.as_object_mut().unwrap().remove("version");
            },
            "model has no version number",
        ),
        json(
            "no-names.atlas",
            &|v| v["names"] = json!([]),
            "0 materials, expected 1 to 1048576",
        ),
        json(
            "fewer-points.atlas",
            &|v| {
                v["latent"].as_array_mut().unwrap().pop();
            },
            &format!("{n} names but {} latent points", n - 1),
        ),
        json(
            "ragged-latent.atlas",
            &|v| v["latent"][1].as_array_mut().unwrap().push(json!(0.5)),
            "latent point 1 has 3 coordinates, the first has 2",
        ),
        json(
            "latent-null.atlas",
            &|v| v["latent"][0][1] = Value::Null,
            "malformed model: invalid type: null, expected f64",
        ),
        json(
            "latent-far.atlas",
            &|v| v["latent"][2][0] = json!(1e300),
            "has coordinate 1e300, expected finite numbers within +-1000",
        ),
        json(
            "latent-as-text.atlas",
            &|v| v["latent"][0][0] = json!("NaN"),
            "malformed model: invalid type: string \"NaN\", expected f64",
        ),
        json(
            "q-as-large-as-n.atlas",
            &|v| {
                for p in v["latent"].as_array_mut().unwrap() {
                    let p = p.as_array_mut().unwrap();
                    while p.len() < n {
                        p.push(json!(0.25));
                    }
                }
            },
            "latent dimension q = ",
        ),
        json(
            "negative-length-scale.atlas",
            &|v| v["kernel"]["length_scale"] = json!(-1.0),
            "kernel: length scale -1.0 must lie in [1e-6, 1e6]",
        ),
        json(
            "huge-length-scale.atlas",
            &|v| v["kernel"]["length_scale"] = json!(1e200),
            "kernel: length scale 1e200 must lie in",
        ),
        json(
            "zero-noise.atlas",
            &|v| v["kernel"]["noise"] = json!(0.0),
            "kernel: noise 0.0 must lie in",
        ),
        json(
            "dims-2^31.atlas",
            &|v| v["dims"] = json!([2147483648u64, 2147483648u64, 2147483648u64]),
            "\"dims\": dims 2147483648x2147483648x2147483648: a dimension is larger than 1024",
        ),
        json("wrong-d.atlas", &|v| v["d"] = json!(7), "d = 7, but dims "),
        json(
            "negative-variance.atlas",
            &|v| v["signal_variance"] = json!(-2.0),
            "signal variance -2.0 must be positive and finite",
        ),
        json(
            "gram-short.atlas",
            &|v| {
                v["gram"].as_array_mut().unwrap().pop();
            },
            "the Gram matrix must be",
        ),
        json(
            "gram-ragged.atlas",
            &|v| {
                v["gram"][0].as_array_mut().unwrap().pop();
            },
            "the Gram matrix must be",
        ),
        json(
            "absolute-store.atlas",
            &|v| v["store"]["path"] = json!("/tmp/elsewhere.store"),
            "expected a path relative to the model file",
        ),
        {
            let path = model_variant(
                dir,
                model,
                "missing-store.atlas",
                |v| v["store"]["path"] = json!("gone.store"),
                |_| {},
            );
            Case {
                names: dir.join("gone.store"),
                path,
                want: "No such file or directory".into(),
                status: Status::Io,
            }
        },
        json(
            "store-size-differs.atlas",
            &|v| v["store"]["bytes"] = json!(v["store"]["bytes"].as_u64().unwrap() + 8),
            "(the store was changed or replaced)",
        ),
        store(
            "changed-store.atlas",
            &|b| {
                let k = b.len() - 3;
                b[k] ^= 0x10;
            },
            "differs from",
        ),
        store(
            "truncated-store.atlas",
            &|b| {
                b.truncate(b.len() - 8);
            },
            "(truncated or changed?)",
        ),
        store(
            "empty-store.atlas",
            &|b| b.clear(),
            "not a brdf-atlas store (missing BRDFSTOR header)",
        ),
        store(
            "lfs-store.atlas",
            &|b| *b = LFS_POINTER.to_vec(),
            "is a Git LFS pointer file, not a brdf-atlas store",
        ),
        store(
            "newer-store.atlas",
            &u32_at(8, 2),
            "store format version 2 was written by a newer brdf-atlas",
        ),
        store(
            "store-huge-n.atlas",
            &u32_at(16, u32::MAX),
            "header says 4294967295 materials, expected 1 to 1048576",
        ),
        store(
            "store-dims-2^31.atlas",
            &u32_at(24, 1 << 31),
            "header dims 2147483648x",
        ),
        store(
            "store-bad-precision.atlas",
            &u32_at(12, 3),
            "3 bytes per value, expected 4 or 8",
        ),
    ]
}

/// Broken map sidecars written into `dir`, derived from the valid sidecar
/// `good` (of a map with at least one material). No command reads a
/// sidecar; the library's [`read_sidecar`] must refuse each.
pub fn sidecar_cases(dir: &Path, good: &Path) -> Vec<Case> {
    read_sidecar(good).expect("a valid sidecar");
    let v: Value = serde_json::from_slice(&std::fs::read(good).expect("sidecar")).expect("JSON");
    let edited = |name: &str, edit: &dyn Fn(&mut Value), want: &str| {
        let mut v = v.clone();
        edit(&mut v);
        let bytes = serde_json::to_vec_pretty(&v).expect("JSON");
        written(dir, name, &bytes, want, Status::BadFile)
    };
    let raw =
        |name: &str, bytes: &[u8], want: &str| written(dir, name, bytes, want, Status::BadFile);
    vec![
        raw(
            "empty.json",
            b"",
            "not a brdf-atlas map sidecar (invalid JSON: EOF while parsing",
        ),
        raw(
            "lfs-pointer.json",
            LFS_POINTER,
            "is a Git LFS pointer file, not a brdf-atlas map sidecar",
        ),
        raw(
            "model.json",
            b"{\"format\": \"brdf-atlas-model\", \"version\": 1}",
            "not a brdf-atlas map sidecar (expected \"format\": \"brdf-atlas-map\")",
        ),
        edited(
            "newer.json",
            &|v| v["version"] = json!(3),
            "sidecar version 3 was written by a newer brdf-atlas",
        ),
        edited("zero-width.json", &|v| v["width"] = json!(0), "image 0x"),
        edited(
            "huge-height.json",
            &|v| v["height"] = json!(1u64 << 40),
            "expected sides of 1 to 65536 pixels",
        ),
        edited(
            "negative-width.json",
            &|v| v["width"] = json!(-5),
            "malformed map sidecar: invalid value: integer `-5`",
        ),
        edited(
            "inverted-view.json",
            &|v| v["view"]["x0"] = json!(5.0),
            "view window",
        ),
        edited(
            "nan-level.json",
            &|v| v["contour_levels"][0] = Value::Null,
            "malformed map sidecar: invalid type: null, expected f32",
        ),
        edited(
            "luminance-reversed.json",
            &|v| v["luminance_range"] = json!([0.9, 0.1]),
            "luminance range [0.9, 0.1]",
        ),
        edited(
            "reference-far.json",
            &|v| v["references"][0]["latent"] = json!([1e300, 0.0]),
            "at [1e300, 0.0], expected finite coordinates within +-1000",
        ),
        edited(
            "reference-moved.json",
            &|v| v["references"][0]["pixel"][0] = json!(-7.0),
            "but the view puts its latent point",
        ),
        edited(
            "reference-short.json",
            &|v| {
                v["references"][0]["latent"].as_array_mut().unwrap().pop();
            },
            "malformed map sidecar: invalid length 1",
        ),
    ]
}
