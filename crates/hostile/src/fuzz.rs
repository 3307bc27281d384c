//! The bodies of the fuzz targets in `fuzz/fuzz_targets`, here so that the
//! regression test (`tests/fuzz_corpus.rs`) replays every saved input
//! through exactly the code the fuzzer ran. Each takes any bytes, returns
//! whether the reader accepted them, and panics only on a bug: a reader
//! that panics, or two paths to the same reader that disagree.

use std::path::{Path, PathBuf};

use brdf_atlas_core::{Model, NoProgress, Store};
use brdf_atlas_core::{ModelFile, store_path_for};
use brdf_atlas_pictures::map_picture::Sidecar;
use brdf_merl::{MerlFile, MerlTable};

/// The MERL reader: `data` as `dir/input.binary`, opened as the tools open
/// it (memory-mapped) and parsed from memory; both must agree.
pub fn merl(dir: &Path, data: &[u8]) -> bool {
    let path = dir.join("input.binary");
    std::fs::write(&path, data).expect("write input");
    let opened = MerlFile::open(&path);
    let parsed = MerlTable::from_bytes(&path, data);
    match (opened, parsed) {
        (Ok(file), Ok(table)) => {
            assert_eq!(file.to_table(), table);
            let _ = table.channel_stats();
            true
        }
        (Err(a), Err(b)) => {
            assert_eq!(a.to_string(), b.to_string());
            false
        }
        (a, b) => panic!("file and bytes disagree: {a:?} vs {b:?}"),
    }
}

/// The text a model input may hold in place of the seed store's checksum
/// (`"checksum": "@CHECKSUM@"`), so that the seed corpus stays valid when
/// the store's bytes change with the code that writes them.
pub const CHECKSUM_PLACEHOLDER: &[u8] = b"@CHECKSUM@";

/// The valid model the `model` target opens inputs beside: a
/// [`crate::small_model`] and its store's checksum.
pub struct SeedModel {
    /// The model file (each input is written here).
    pub path: PathBuf,
    checksum: String,
}

impl SeedModel {
    /// Fit the seed model into `dir`.
    pub fn new(dir: &Path) -> SeedModel {
        let path = crate::small_model(dir);
        let store = Store::open(store_path_for(&path)).expect("the seed store");
        SeedModel {
            path,
            checksum: format!("{:016x}", store.checksum()),
        }
    }
}

/// The model loader: `data` as the JSON of the seed model's file (its valid
/// store beside it; [`CHECKSUM_PLACEHOLDER`] stands for that store's
/// checksum): checked on its own and, when it passes, opened with its store
/// and asked for weights.
pub fn model(seed: &SeedModel, data: &[u8]) -> bool {
    let replaced;
    let data = match data
        .windows(CHECKSUM_PLACEHOLDER.len())
        .position(|w| w == CHECKSUM_PLACEHOLDER)
    {
        Some(at) => {
            replaced = [
                &data[..at],
                seed.checksum.as_bytes(),
                &data[at + CHECKSUM_PLACEHOLDER.len()..],
            ]
            .concat();
            &replaced[..]
        }
        None => data,
    };
    let model = &seed.path;
    let Ok(file) = ModelFile::from_json(model, data) else {
        return false;
    };
    std::fs::write(model, data).expect("write input");
    match Model::open(model) {
        Ok(m) => {
            assert_eq!(m.file(), &file);
            let w = m
                .weights_at(&vec![0.25; m.q()])
                .expect("weights at a finite point");
            assert_eq!(w.len(), m.names().len());
            true
        }
        Err(_) => false,
    }
}

/// The store reader: `data` as `dir/input.store`.
pub fn store(dir: &Path, data: &[u8]) -> bool {
    let path = dir.join("input.store");
    std::fs::write(&path, data).expect("write input");
    match Store::open(&path) {
        Ok(store) => {
            assert_eq!(store.len_bytes(), data.len() as u64);
            let _ = store.checksum();
            let _ = store.mean().iter().sum::<f64>();
            let _ = store.gram(&NoProgress);
            true
        }
        Err(_) => false,
    }
}

/// The map sidecar reader: `data` as a sidecar's JSON.
pub fn sidecar(data: &[u8]) -> bool {
    match Sidecar::from_json(Path::new("input.json"), data) {
        Ok(s) => {
            for r in &s.references {
                let p = s.view.latent_to_pixel(r.latent, s.width, s.height);
                assert!(p.iter().all(|v| v.is_finite()), "{p:?}");
            }
            true
        }
        Err(_) => false,
    }
}
