//! A fitted model: the latent points and kernel of a model file, its store
//! mapped, and `K` factorised, ready for queries (`crate::maps`: the
//! material at a latent point, maps, locating a new material).
//!
//! - [`file`]: the model file's format (JSON beside the store);
//! - [`Model`]: opened from disk ([`Model::open`]) or assembled in memory
//!   ([`Model::new`]).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use brdf_merl::albedo::Quadrature;
use brdf_merl::{Dims, DirectionalRule};
use faer::Mat;

use crate::data::Store;
use crate::data::transform::Transform;
use crate::dense::Cholesky;
use crate::error::{CoreError, Result};
use crate::model::blend::plausible_budget::convex_weights_at;
use crate::model::blend::plausible_steps::plausible_blends;
use crate::model::blend::{Blend, BlendRule};

pub mod blend;
pub mod file;
pub mod judged;

pub use file::{FitRecord, InputIdentity, ModelFile, StoreRef, store_path_for};

/// An opened model: the file, its store mapped, `K` factorised.
pub struct Model {
    path: PathBuf,
    file: ModelFile,
    store: Store,
    latent: Mat<f64>,
    llt: Cholesky,
    transform: Box<dyn Transform>,
    gram: Mat<f64>,
    /// See [`Model::albedo_rule`].
    albedo_rule: OnceLock<Quadrature>,
    /// See [`Model::cosine_products`].
    cosines: OnceLock<Vec<f64>>,
    /// See [`Model::directional_rule`].
    directional: OnceLock<DirectionalRule>,
}

impl std::fmt::Debug for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Model")
            .field("path", &self.path)
            .field("n", &self.file.names.len())
            .finish()
    }
}

impl Model {
    /// Open a model file and its store; check format, version, shapes, the
    /// store's size and checksum, and factorise `K`. The checksum (a read of
    /// the whole store: about 0.25 s for 100 materials from the page cache,
    /// seconds from disk) is skipped while the store's identity is the one
    /// the fit recorded ([`StoreIdentity`]: the same file, not written since,
    /// no restart of the machine since); [`Model::open_verified`] always
    /// takes it.
    pub fn open(path: impl AsRef<Path>) -> Result<Model> {
        Model::open_with(path.as_ref(), false)
    }

    /// [`Model::open`] that checksums the store whatever its identity says:
    /// for a store that may have been damaged on the disk itself.
    pub fn open_verified(path: impl AsRef<Path>) -> Result<Model> {
        Model::open_with(path.as_ref(), true)
    }

    fn open_with(path: &Path, verify: bool) -> Result<Model> {
        let path = path.to_path_buf();
        let text = brdf_mapguard::read_regular(&path).map_err(|e| CoreError::io(&path, e))?;
        let file = ModelFile::from_json(&path, &text)?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let store_path = dir.join(&file.store.path);
        let store = Store::open(&store_path)?;
        let sbad = |why: String| CoreError::bad_file(&store_path, why);
        if store.len_bytes() != file.store.bytes {
            return Err(sbad(format!(
                "{} bytes, the model {} expects {} (the store was changed or replaced)",
                store.len_bytes(),
                path.display(),
                file.store.bytes
            )));
        }
        check_store(&file, &store)?;
        let known = file.store.identity.is_some() && file.store.identity == store.identity();
        if verify || !known {
            let checksum = format!("{:016x}", store.checksum());
            if checksum != file.store.checksum {
                return Err(sbad(format!(
                    "checksum {checksum} differs from {} recorded in {} (the store was changed)",
                    file.store.checksum,
                    path.display()
                )));
            }
        }
        // Changed while being checksummed: say so, not "checksum differs".
        store.verify()?;
        Model::assemble(path, file, store)
    }

    /// `Ok` while the store is as it was when opened; otherwise
    /// [`CoreError::FileChanged`] naming it, for this and every later call
    /// (reopen the model). Every query that reads the store calls this
    /// before it returns; a caller of the infallible point queries
    /// ([`Blend::value`](crate::Blend::value), [`Blend::eval`](crate::Blend::eval),
    /// ...) calls it after them, before it uses their answers. One `fstat`.
    pub fn verify(&self) -> Result<()> {
        self.store.verify()
    }

    /// A model from a model file's content and its store, held in memory:
    /// nothing is read from or written to `path`, which only names the model
    /// in messages and sidecars. Checks that the store holds what the file
    /// describes and factorises `K`; the store's checksum is taken as given.
    pub fn new(path: PathBuf, file: ModelFile, store: Store) -> Result<Model> {
        check_store(&file, &store)?;
        Model::assemble(path, file, store)
    }

    /// The model of a checked file and a store that matches it.
    fn assemble(path: PathBuf, file: ModelFile, store: Store) -> Result<Model> {
        if let Some(bound) = &file.energy {
            store.keep_energy_bound(bound);
        }
        let (n, q, dims) = (file.names.len(), file.latent[0].len(), store.dims());
        let gram = Mat::from_fn(n, n, |i, j| file.gram[i][j]);
        let latent = Mat::from_fn(n, q, |i, c| file.latent[i][c]);
        let llt = Cholesky::factor(file.kernel.matrix(latent.as_ref()).as_ref()).map_err(|e| {
            CoreError::NotPositiveDefinite {
                context: format!("opening {}", path.display()),
                pivot: Some(e.index),
            }
        })?;
        let transform = file.transform.build(dims);
        Ok(Model {
            path,
            file,
            store,
            latent,
            llt,
            transform,
            gram,
            albedo_rule: OnceLock::new(),
            cosines: OnceLock::new(),
            directional: OnceLock::new(),
        })
    }

    /// The model file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The model file's content.
    pub fn file(&self) -> &ModelFile {
        &self.file
    }

    /// The mapped store.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// Material names in order.
    pub fn names(&self) -> &[String] {
        &self.file.names
    }

    /// Latent points, `N x q`.
    pub fn latent(&self) -> &Mat<f64> {
        &self.latent
    }

    /// Latent dimension `q`.
    pub fn q(&self) -> usize {
        self.latent.ncols()
    }

    /// Table dims.
    pub fn dims(&self) -> Dims {
        self.store.dims()
    }

    /// `K^-1 B` for a right-hand side with `N` rows.
    pub(crate) fn llt_solve(&self, b: &Mat<f64>) -> Mat<f64> {
        self.llt.solve(b.as_ref())
    }

    /// `K^-1` (noise included), column-major `N x N`.
    pub(crate) fn k_inverse(&self) -> Vec<f64> {
        let inv = self.llt.inverse();
        let n = inv.nrows();
        (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .map(|(i, j)| inv[(i, j)])
            .collect()
    }

    /// The Gram matrix `Y = Z Z^T` of the stored (centred, transformed) data.
    pub fn gram(&self) -> &Mat<f64> {
        &self.gram
    }

    /// The blend weights `w(x) = K^-1 k(x)` at a latent point.
    pub fn weights_at(&self, x: &[f64]) -> Result<Vec<f64>> {
        Ok(self.kernel_and_weights_at(x)?.1)
    }

    /// `k(x)` and the GP's weights `K^-1 k(x)` at `x`, checked as [`Model::weights_at`].
    pub(crate) fn kernel_and_weights_at(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        self.check_point(x)?;
        let k = self.file.kernel.vector(self.latent.as_ref(), x);
        let mut w = k.clone();
        self.llt.solve_in_place(&mut w);
        Ok((k, w))
    }

    /// Whether `x` is a latent point of this model: `q` finite coordinates
    /// ([`CoreError::BadQuery`] if not).
    pub(crate) fn check_point(&self, x: &[f64]) -> Result<()> {
        if x.len() != self.q() || x.iter().any(|v| !v.is_finite()) {
            return Err(CoreError::BadQuery(format!(
                "latent point {x:?}: expected {} finite coordinates",
                self.q()
            )));
        }
        Ok(())
    }

    /// `cos(theta_i) cos(theta_o)` of every bin (at its representative
    /// angles, clamped at 0), built on first use.
    pub(crate) fn cosine_products(&self) -> &[f64] {
        self.cosines
            .get_or_init(|| crate::data::transform::cosine_products(self.dims()))
    }

    /// The directional-albedo rule for the model's dims, built on first use.
    pub(crate) fn directional_rule(&self) -> &DirectionalRule {
        self.directional
            .get_or_init(|| DirectionalRule::new(self.dims()))
    }

    /// The data transform of the store, built for its dims.
    pub(crate) fn transform(&self) -> &dyn Transform {
        self.transform.as_ref()
    }

    /// The dense albedo rule of the model's dims (2 sub-cells a bin), built once.
    pub fn albedo_rule(&self) -> &Quadrature {
        self.albedo_rule
            .get_or_init(|| Quadrature::dense(self.dims(), 2))
    }

    /// The material at latent point `x` (`q` finite coordinates) under
    /// `rule`: the GP's blend ([`BlendRule::Gp`]), every value on its soft
    /// floor ([`BlendRule::Floor`], the default), or the plausible rule's
    /// steps ([`BlendRule::Plausible`], a pass over the store).
    /// [`CoreError::FileChanged`] once the store is known to have changed
    /// (a model refuses every query then).
    pub fn at(&self, x: &[f64], rule: BlendRule) -> Result<Blend<'_>> {
        match rule {
            BlendRule::Gp => Blend::gp_at(self, x),
            BlendRule::Plausible => {
                let mut blends = plausible_blends(self, &[x.to_vec()])?;
                Ok(blends.pop().expect("one blend a point"))
            }
            BlendRule::Floor => {
                let gp = Blend::gp_at(self, x)?;
                let convex = convex_weights_at(self, &[x]).pop().expect("one point");
                Ok(gp.with_floor(convex))
            }
        }
    }
}

/// Check that `store` holds what `file` describes: as many materials, of
/// the same dims, in the same transform.
fn check_store(file: &ModelFile, store: &Store) -> Result<()> {
    let n = file.names.len();
    let dims = store.dims();
    if store.n() != n
        || [dims.theta_h, dims.theta_d, dims.phi_d] != file.dims
        || store.transform() != file.transform
    {
        return Err(CoreError::bad_file(
            store.path(),
            format!(
                "holds {} materials of {dims} ({}), the model expects {n} of {:?} ({})",
                store.n(),
                store.transform().name(),
                file.dims,
                file.transform.name()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{Dataset, Precision, TransformKind};
    use crate::fit::{FitOptions, StorePolicy, fit_dir, fit_dir_with};
    use crate::gplvm::GplvmParams;
    use crate::progress::NoProgress;

    fn fitted(dir: &Path) -> PathBuf {
        let dims = Dims::new(6, 6, 12).unwrap();
        for m in brdf_merl::synth::database(6, 2) {
            m.brdf
                .table(dims)
                .write(dir.join(format!("{}.binary", m.name)))
                .unwrap();
        }
        let model = dir.join("m.atlas");
        let options = FitOptions {
            params: GplvmParams::new(2).check().unwrap(),
            transform: TransformKind::Log,
            precision: Precision::F32,
        };
        fit_dir(dir, &model, &options, &NoProgress).unwrap();
        model
    }

    #[test]
    fn model_round_trips_and_answers() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let m = Model::open(&path).unwrap();
        assert_eq!(m.names().len(), 6);
        // Re-serialising the loaded content gives the same file.
        let again = tmp.path().join("again.atlas");
        m.file().write(&again).unwrap();
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&again).unwrap()
        );
        // Weights reproduce K^-1 k(x): at a training point, K w = k(x_i).
        let xi: Vec<f64> = (0..2).map(|c| m.latent()[(3, c)]).collect();
        let w = m.weights_at(&xi).unwrap();
        let k = m.file().kernel.matrix(m.latent().as_ref());
        let kx = m.file().kernel.vector(m.latent().as_ref(), &xi);
        for r in 0..6 {
            let kw: f64 = (0..6).map(|c| k[(r, c)] * w[c]).sum();
            assert!((kw - kx[r]).abs() < 1e-9);
        }
        assert!(m.weights_at(&[f64::NAN, 0.0]).is_err());
        assert!(m.weights_at(&[0.0]).is_err());
    }

    #[test]
    fn a_failed_refit_leaves_the_old_model_intact() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let before = std::fs::read(store_path_for(&path)).unwrap();
        // q = 6 passes the parameter check but not the fit of 6 materials.
        let options = FitOptions {
            params: GplvmParams::new(6).check().unwrap(),
            transform: TransformKind::Raw,
            precision: Precision::F64,
        };
        assert!(fit_dir(tmp.path(), &path, &options, &NoProgress).is_err());
        assert_eq!(std::fs::read(store_path_for(&path)).unwrap(), before);
        Model::open(&path).unwrap();
        let leftovers: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp-"))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");
    }

    #[test]
    fn changed_missing_or_newer_models_are_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let text = std::fs::read_to_string(&path).unwrap();
        let bad = tmp.path().join("bad.atlas");
        let check = |content: &str, want: &str| {
            std::fs::write(&bad, content).unwrap();
            let e = Model::open(&bad).unwrap_err().to_string();
            assert!(e.contains(want), "{want}: {e}");
            assert!(e.contains("bad.atlas") || e.contains(".store"), "{e}");
        };
        check(
            &text.replace("\"version\": 1", "\"version\": 7"),
            "written by a newer brdf-atlas",
        );
        check(&text[..text.len() / 2], "invalid JSON");
        check("{}", "not a brdf-atlas model");
        check(&text.replace("m.atlas.store", "gone.store"), "gone.store");
        // A store changed in one byte.
        let store = store_path_for(&path);
        let mut bytes = std::fs::read(&store).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(&store, &bytes).unwrap();
        let e = Model::open(&path).unwrap_err().to_string();
        assert!(e.contains("checksum") && e.contains("m.atlas.store"), "{e}");
    }

    #[test]
    fn a_store_known_by_its_identity_is_not_checksummed_again() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let store = store_path_for(&path);
        let file = Model::open(&path).unwrap().file().clone();
        let id = file
            .store
            .identity
            .clone()
            .expect("the fit records the store's identity");
        assert_eq!(Some(&id), Store::open(&store).unwrap().identity().as_ref());
        // Written by nothing since: dated before the fit ended.
        let modified = std::fs::metadata(&store).unwrap().modified().unwrap();
        assert!(modified < std::time::SystemTime::now());
        // A model whose recorded checksum no longer matches opens while the
        // store is the one it knows (the checksum is not taken)...
        let wrong = |mut f: ModelFile, edit: &dyn Fn(&mut ModelFile)| {
            f.store.checksum = "0123456789abcdef".into();
            edit(&mut f);
            let json = f.to_json(&path).unwrap();
            std::fs::write(&path, json).unwrap();
        };
        wrong(file.clone(), &|_| ());
        Model::open(&path).unwrap();
        // ... but not when asked to verify, nor once the identity differs:
        // another boot, another file, or the same file written again, even
        // with the same bytes at once.
        let e = Model::open_verified(&path).unwrap_err().to_string();
        assert!(e.contains("checksum") && e.contains("m.atlas.store"), "{e}");
        let refused = |why: &str| {
            let e = Model::open(&path).unwrap_err().to_string();
            assert!(e.contains("checksum"), "{why}: {e}");
        };
        wrong(file.clone(), &|f| {
            f.store.identity.as_mut().unwrap().boot = "another".into()
        });
        refused("another boot");
        wrong(file.clone(), &|f| {
            f.store.identity.as_mut().unwrap().inode += 1
        });
        refused("another file");
        wrong(file.clone(), &|_| ());
        Model::open(&path).unwrap();
        let bytes = std::fs::read(&store).unwrap();
        std::fs::write(&store, &bytes).unwrap();
        refused("written again");
        // With the right checksum the rewritten store opens (checksummed).
        std::fs::write(&path, file.to_json(&path).unwrap()).unwrap();
        Model::open(&path).unwrap();
        // A model without an identity (written before it was recorded) is
        // always checksummed.
        wrong(file, &|f| f.store.identity = None);
        refused("no identity");
    }

    #[test]
    fn a_refit_of_unchanged_inputs_uses_the_store_again() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let store = store_path_for(&path);
        let options = |q: usize, transform| FitOptions {
            params: GplvmParams::new(q).check().unwrap(),
            transform,
            precision: Precision::F32,
        };
        let refit = |q: usize, transform, policy| {
            fit_dir_with(
                tmp.path(),
                &path,
                &options(q, transform),
                policy,
                &NoProgress,
            )
            .unwrap()
            .store_reused
        };
        let (model_bytes, store_bytes) = (
            std::fs::read(&path).unwrap(),
            std::fs::read(&store).unwrap(),
        );
        let store_id = Model::open(&path).unwrap().file().store.identity.clone();
        // The same fit again: the same store file, untouched, and the same model.
        assert!(refit(2, TransformKind::Log, StorePolicy::Reuse));
        assert_eq!(std::fs::read(&path).unwrap(), model_bytes);
        assert_eq!(Store::open(&store).unwrap().identity(), store_id);
        // Another latent dimension on the store used again gives what a
        // fresh fit with a store of its own gives.
        assert!(refit(3, TransformKind::Log, StorePolicy::Reuse));
        let fresh = tmp.path().join("fresh.atlas");
        fit_dir(
            tmp.path(),
            &fresh,
            &options(3, TransformKind::Log),
            &NoProgress,
        )
        .unwrap();
        let (a, b) = (Model::open(&path).unwrap(), Model::open(&fresh).unwrap());
        assert_eq!(a.file().latent, b.file().latent);
        assert_eq!(a.file().gram, b.file().gram);
        assert_eq!(a.file().fit.cost, b.file().fit.cost);
        assert_eq!(std::fs::read(&store).unwrap(), store_bytes);
        // Built anew when asked, or when anything the store holds may differ.
        assert!(!refit(2, TransformKind::Log, StorePolicy::Rebuild));
        assert!(refit(2, TransformKind::Log, StorePolicy::Reuse));
        assert!(!refit(2, TransformKind::Raw, StorePolicy::Reuse));
        assert!(!refit(2, TransformKind::Log, StorePolicy::Reuse));
        let input = Dataset::map_dir(tmp.path()).unwrap().files[2]
            .path()
            .to_path_buf();
        let later = std::time::SystemTime::now() + std::time::Duration::from_secs(5);
        std::fs::File::options()
            .write(true)
            .open(&input)
            .unwrap()
            .set_modified(later)
            .unwrap();
        assert!(
            !refit(2, TransformKind::Log, StorePolicy::Reuse),
            "an input touched"
        );
        std::fs::write(&store, std::fs::read(&store).unwrap()).unwrap();
        assert!(
            !refit(2, TransformKind::Log, StorePolicy::Reuse),
            "the store written"
        );
        assert!(refit(2, TransformKind::Log, StorePolicy::Reuse));
        Model::open_verified(&path).unwrap();
    }

    #[test]
    fn a_model_in_memory_answers_as_the_one_opened_from_disk() {
        let tmp = tempfile::tempdir().unwrap();
        let path = fitted(tmp.path());
        let disk = Model::open(&path).unwrap();
        let store = Store::open(store_path_for(&path)).unwrap();
        let memory =
            Model::new(tmp.path().join("unsaved.atlas"), disk.file().clone(), store).unwrap();
        assert_eq!(memory.path(), tmp.path().join("unsaved.atlas"));
        for x in [[0.1, -0.3], [0.9, 0.9], [-2.0, 0.5]] {
            assert_eq!(disk.weights_at(&x).unwrap(), memory.weights_at(&x).unwrap());
            let (a, b) = (
                disk.at(&x, crate::BlendRule::Gp).unwrap().table().unwrap(),
                memory
                    .at(&x, crate::BlendRule::Gp)
                    .unwrap()
                    .table()
                    .unwrap(),
            );
            assert_eq!(a.raw(), b.raw());
        }
        // A store that does not hold what the file describes is refused.
        let mut other = disk.file().clone();
        other.names.pop();
        other.latent.pop();
        let store = Store::open(store_path_for(&path)).unwrap();
        let e = Model::new(path.clone(), other, store)
            .unwrap_err()
            .to_string();
        assert!(e.contains("the model expects 5"), "{e}");
    }
}
