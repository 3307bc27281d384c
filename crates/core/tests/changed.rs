//! A model whose store is truncated or rewritten while it is open, and a
//! fit whose input is truncated during the store pass: every call ends in
//! `CoreError::FileChanged` (or `MerlError::Changed`) naming the file, or
//! in the right answer, never in a crash or in numbers read from the
//! changed file.

use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, SystemTime};

use brdf_atlas_core::{
    CoreError, FitOptions, GplvmParams, Model, NoProgress, Precision, Progress, TransformKind,
    fit_dir, store_path_for,
};
use brdf_merl::{Dims, MerlError, synth};

const DIMS: Dims = Dims {
    theta_h: 12,
    theta_d: 12,
    phi_d: 24,
};

fn options() -> FitOptions {
    FitOptions {
        params: GplvmParams::new(2).check().unwrap(),
        transform: TransformKind::Log,
        precision: Precision::F32,
    }
}

/// A fitted model in `dir` whose store is dated an hour ago, so that any
/// write to it now moves its modification time.
fn fitted(dir: &Path) -> PathBuf {
    let data = dir.join("data");
    synth::write_dir(&data, 8, DIMS, 3).unwrap();
    let model = dir.join("m.atlas");
    fit_dir(&data, &model, &options(), &NoProgress).unwrap();
    File::options()
        .write(true)
        .open(store_path_for(&model))
        .unwrap()
        .set_modified(SystemTime::now() - Duration::from_secs(3600))
        .unwrap();
    model
}

fn truncate(path: &Path, len: u64) {
    OpenOptions::new()
        .write(true)
        .open(path)
        .unwrap()
        .set_len(len)
        .unwrap();
}

/// The error is the store's change, naming it.
fn is_changed(e: &CoreError, store: &Path) -> bool {
    matches!(e, CoreError::FileChanged { path } if path == store)
        && e.to_string().contains("changed on disk while open")
}

#[test]
fn a_store_truncated_after_open_gives_file_changed_until_reopened() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fitted(tmp.path());
    let store = store_path_for(&path);
    let bytes = std::fs::read(&store).unwrap();
    let m = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let x = [0.2, -0.4];
    let want = m
        .at(&x, brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .table()
        .unwrap();
    truncate(&store, 100);
    let e = m
        .at(&x, brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .table()
        .unwrap_err();
    assert!(is_changed(&e, &store), "{e}");
    // Every later query refuses, with the same error.
    for e in [
        m.at(&x, brdf_atlas_core::BlendRule::Gp).err().unwrap(),
        m.verify().unwrap_err(),
        m.map(brdf_atlas_core::MapRequest::new(8, 8).samples(Some(4)))
            .unwrap_err(),
    ] {
        assert!(is_changed(&e, &store), "{e}");
    }
    drop(m);
    // The file restored, a reopened model answers as before.
    std::fs::write(&store, &bytes).unwrap();
    let again = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    assert_eq!(
        again
            .at(&x, brdf_atlas_core::BlendRule::Gp)
            .unwrap()
            .table()
            .unwrap()
            .raw(),
        want.raw()
    );
}

#[test]
fn a_store_rewritten_at_the_same_size_gives_file_changed() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fitted(tmp.path());
    let store = store_path_for(&path);
    let m = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let x = [0.5, 0.1];
    let table = m
        .at(&x, brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .table()
        .unwrap();
    // `cp other m.atlas.store`: truncate and write the same length, in place.
    let mut bytes = std::fs::read(&store).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x40;
    std::fs::write(&store, &bytes).unwrap();
    let e = m
        .at(&x, brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .table()
        .unwrap_err();
    assert!(is_changed(&e, &store), "{e}");
    // Point queries return plain numbers; verify says they are not to be used.
    let blend_error = m.at(&x, brdf_atlas_core::BlendRule::Gp).err().unwrap();
    assert!(is_changed(&blend_error, &store), "{blend_error}");
    assert!(is_changed(&m.verify().unwrap_err(), &store));
    let _ = table;
}

#[test]
fn a_store_replaced_by_rename_leaves_the_open_model_answering() {
    // What `brdf-atlas fit` does to an existing model: the open handle keeps
    // the file it mapped, which nobody changed.
    let tmp = tempfile::tempdir().unwrap();
    let path = fitted(tmp.path());
    let store = store_path_for(&path);
    let m = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let x = [-0.3, 0.3];
    let want = m
        .at(&x, brdf_atlas_core::BlendRule::Gp)
        .unwrap()
        .table()
        .unwrap();
    let copy = tmp.path().join("copy");
    std::fs::write(&copy, b"something else").unwrap();
    std::fs::rename(&copy, &store).unwrap();
    assert_eq!(
        m.at(&x, brdf_atlas_core::BlendRule::Gp)
            .unwrap()
            .table()
            .unwrap()
            .raw(),
        want.raw()
    );
    m.verify().unwrap();
}

#[test]
fn a_truncation_during_reconstructions_on_other_threads_never_gives_garbage() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fitted(tmp.path());
    let store = store_path_for(&path);
    let m = brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
    let points = [[0.1, 0.2], [-0.7, 0.4], [0.9, -0.9]];
    let want: Vec<_> = points
        .iter()
        .map(|x| {
            m.at(x, brdf_atlas_core::BlendRule::Gp)
                .unwrap()
                .table()
                .unwrap()
        })
        .collect();
    let started = AtomicUsize::new(0);
    let truncated = AtomicBool::new(false);
    let stopped = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for (x, want) in points.iter().zip(&want) {
            let (m, store) = (&m, &store);
            let (started, truncated, stopped) = (&started, &truncated, &stopped);
            s.spawn(move || {
                let mut first = true;
                // Until a call fails: each is the right table or FileChanged.
                loop {
                    let after = truncated.load(Ordering::Acquire);
                    match m
                        .at(x, brdf_atlas_core::BlendRule::Gp)
                        .and_then(|b| b.table())
                    {
                        Ok(t) => assert_eq!(t.raw(), want.raw(), "garbage from a changed store"),
                        Err(e) => {
                            assert!(is_changed(&e, store), "{e}");
                            stopped.fetch_add(1, Ordering::SeqCst);
                            break;
                        }
                    }
                    if first {
                        started.fetch_add(1, Ordering::SeqCst);
                        first = false;
                    }
                    // A call that began after the truncation was complete
                    // cannot succeed.
                    assert!(!after, "a reconstruction after the truncation succeeded");
                }
            });
        }
        // Every thread has reconstructed once; now cut the store under them.
        while started.load(Ordering::SeqCst) < points.len() {
            std::thread::yield_now();
        }
        truncate(&store, 4096);
        truncated.store(true, Ordering::Release);
    });
    // Every thread ended on FileChanged, and the model says so from now on.
    assert_eq!(stopped.load(Ordering::SeqCst), points.len());
    assert!(is_changed(&m.verify().unwrap_err(), &store));
}

/// Truncates `victim` at the first block of the store pass: an input that
/// changes while the fit reads it, at a fixed point of the pass.
struct TruncateDuringStorePass {
    victim: PathBuf,
    in_store: AtomicBool,
    done: AtomicBool,
}

impl Progress for TruncateDuringStorePass {
    fn start(&self, label: &str, _: u64) {
        self.in_store.store(label == "store", Ordering::SeqCst);
    }

    fn advance(&self, _: u64) {
        if self.in_store.load(Ordering::SeqCst) && !self.done.swap(true, Ordering::SeqCst) {
            truncate(&self.victim, 20);
        }
    }
}

#[test]
fn an_input_truncated_during_a_fit_fails_it_and_keeps_the_old_model() {
    let tmp = tempfile::tempdir().unwrap();
    let path = fitted(tmp.path());
    let store = store_path_for(&path);
    let (model_before, store_before) = (
        std::fs::read(&path).unwrap(),
        std::fs::read(&store).unwrap(),
    );
    let data = tmp.path().join("data");
    let mut inputs: Vec<_> = std::fs::read_dir(&data)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    inputs.sort();
    let victim = inputs[3].clone();
    let progress = TruncateDuringStorePass {
        victim: victim.clone(),
        in_store: AtomicBool::new(false),
        done: AtomicBool::new(false),
    };
    let e = fit_dir(&data, &path, &options(), &progress).unwrap_err();
    assert!(
        progress.done.load(Ordering::SeqCst),
        "the pass never advanced"
    );
    assert!(
        matches!(&e, CoreError::Merl(MerlError::Changed { path }) if *path == victim),
        "{e}"
    );
    let message = e.to_string();
    assert!(message.contains("changed while being read"), "{message}");
    assert!(!message.contains('\n'));
    assert_eq!(std::fs::read(&path).unwrap(), model_before);
    assert_eq!(std::fs::read(&store).unwrap(), store_before);
    let leftovers: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    brdf_atlas_core::Atlas::new(Model::open(&path).unwrap());
}
