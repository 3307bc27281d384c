//! `brdf_atlas.Model`: an opened model and what it answers at latent
//! points.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

use brdf_atlas_core::{Atlas, BlendRule, Model, View};
use brdf_merl::MerlFile;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArray4};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{Directions, describe, point, table_from_array, table_values};
use crate::errors::{Failure, Result};
use crate::material::{
    OwnedBlend, PyMaterial, Source, check_pairs, eval_pairs, rows3, table_array,
};

/// Largest quadrature sample count of a map (as the C library's bound).
const MAX_SAMPLES: usize = 1 << 20;

/// A fitted latent space of materials, opened from its model file (and the
/// store beside it, memory-mapped).
///
/// Every query takes a latent point `x`: `latent_dim` numbers (a sequence,
/// or a number when `latent_dim` is 1). Thread-safe; every long call
/// releases the GIL.
#[pyclass(module = "brdf_atlas", name = "Model", frozen)]
pub struct PyModel {
    /// The model and what its maps keep between calls.
    inner: Atlas,
}

/// Where a material lands in a model's latent space (`Model.locate`).
#[pyclass(module = "brdf_atlas", name = "Location", frozen, get_all)]
pub struct Location {
    /// The latent point whose reconstruction matches the material best.
    pub point: Vec<f64>,
    /// Root-mean-square error per value of that reconstruction, in the
    /// model's transformed space.
    pub rmse: f64,
    /// RMS of the material around the model's mean material, same units:
    /// `rmse / spread` below 1 is better than the mean.
    pub spread: f64,
    /// The model's materials by latent distance from `point`, nearest
    /// first: `(name, distance)`.
    pub nearest: Vec<(String, f64)>,
}

#[pymethods]
impl Location {
    fn __repr__(&self) -> String {
        let nearest = self
            .nearest
            .first()
            .map_or_else(|| "None".to_string(), |n| format!("{:?}", n.0));
        format!(
            "Location(point={:?}, rmse={:.4e}, spread={:.4e}, nearest={nearest})",
            self.point, self.rmse, self.spread
        )
    }
}

impl PyModel {
    fn blend(&self, x: &[f64], rule: BlendRule) -> Result<OwnedBlend> {
        Ok(OwnedBlend::try_new(self.inner.model().clone(), |m| {
            m.at(x, rule)
        })?)
    }
}

/// The blend rule named `blend`: "floor" (the default), "gp" or "plausible".
fn rule_of(blend: &str) -> PyResult<BlendRule> {
    Ok(BlendRule::parse(blend).ok_or_else(|| {
        Failure::input(format!(
            "blend rule {blend:?}: expected \"floor\", \"gp\" or \"plausible\""
        ))
    })?)
}

/// Files made for `locate` from arrays, so that each has its own name.
static SCRATCH: AtomicU64 = AtomicU64::new(0);

/// A MERL file holding `table` in the system's temporary directory,
/// removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

#[pymethods]
impl PyModel {
    /// Open a model file (`brdf-atlas fit` or `brdf_atlas.fit` writes them)
    /// and its store; checks format, version, shapes and the store's
    /// checksum.
    ///
    /// The store stays memory-mapped while the model lives. So that a store
    /// truncated under the map raises an error (the store "changed on disk
    /// while open") instead of killing the interpreter, the first model
    /// opened installs a process-wide SIGBUS handler, once; it chains:
    /// every other SIGBUS goes to the handler the process had before
    /// (Python's `faulthandler`'s, for one). To leave SIGBUS alone, set
    /// `os.environ["BRDF_ATLAS_NO_SIGBUS_HANDLER"] = "1"` before the first
    /// model is opened; a store truncated under an open model then kills
    /// the process with SIGBUS when a query reads past its new end.
    #[new]
    fn new(py: Python<'_>, path: PathBuf) -> PyResult<PyModel> {
        let model = py.detach(|| Model::open(&path)).map_err(Failure::from)?;
        Ok(PyModel {
            inner: Atlas::new(model),
        })
    }

    /// The model file's path.
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.path().to_path_buf()
    }

    /// The materials' names, in order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.inner.names().to_vec()
    }

    /// The materials' latent points, an (N, latent_dim) float64 array.
    #[getter]
    fn latent<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let l = self.inner.latent();
        Array2::from_shape_fn((l.nrows(), l.ncols()), |(i, c)| l[(i, c)]).into_pyarray(py)
    }

    /// The latent dimension q.
    #[getter]
    fn latent_dim(&self) -> usize {
        self.inner.q()
    }

    /// The data transform: "rel-log", "log" or "raw".
    #[getter]
    fn transform(&self) -> &'static str {
        self.inner.file().transform.name()
    }

    /// The table dims `(n_theta_h, n_theta_d, n_phi_d)`.
    #[getter]
    fn dims(&self) -> (usize, usize, usize) {
        let d = self.inner.dims();
        (d.theta_h, d.theta_d, d.phi_d)
    }

    fn __len__(&self) -> usize {
        self.inner.names().len()
    }

    fn __repr__(&self) -> String {
        format!(
            "<brdf_atlas.Model {}: {} materials, q = {}, {} transform>",
            self.inner.path().display(),
            self.inner.names().len(),
            self.inner.q(),
            self.inner.file().transform.name()
        )
    }

    /// The GP's N blend weights at `x`: the GP's blend there is the mean
    /// material plus this weighted sum of the materials, in the transformed
    /// space (the default rule, "floor", then lifts each value of it softly
    /// onto a floor under a convex blend's).
    fn weights<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = point(x)?;
        let w = self.inner.weights_at(&x).map_err(Failure::from)?;
        Ok(Array1::from(w).into_pyarray(py))
    }

    /// What the model knows at `x`: a dict with `variance` (the GP's
    /// predictive variance, 0 at an input material, 1 far from all of them),
    /// `weight_sum`, and `low` (variance above 0.5: the material there is
    /// mostly the database's mean). Costs as much as `weights`.
    fn confidence<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let x = point(x)?;
        let c = self
            .inner
            .at(&x, BlendRule::Gp)
            .map_err(Failure::from)?
            .confidence();
        let d = PyDict::new(py);
        d.set_item("variance", c.variance)?;
        d.set_item("weight_sum", c.weight_sum)?;
        d.set_item("low", c.is_low())?;
        Ok(d)
    }

    /// How physical the material at `x` is, under blend rule `blend`
    /// ("floor", the default, "gp" or "plausible"): a dict with
    /// `clamped_reflectance` (share of the cosine-weighted reflectance the
    /// clamp to >= 0 removes), `clamped_values`, `max_albedo` (largest
    /// directional albedo; at most 1 for a physical material),
    /// `max_albedo_incidence` (degrees) and `plausible`. One pass over the
    /// store, without the GIL.
    #[pyo3(signature = (x, blend = "floor"))]
    fn plausibility<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        blend: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let x = point(x)?;
        let rule = rule_of(blend)?;
        let p = py.detach(|| {
            let b = self.inner.at(&x, rule)?;
            Ok::<_, Failure>(b.plausibility()?)
        })?;
        let d = PyDict::new(py);
        d.set_item("clamped_reflectance", p.clamped_reflectance)?;
        d.set_item("clamped_values", p.clamped_values)?;
        d.set_item("max_albedo", p.max_albedo)?;
        d.set_item("max_albedo_incidence", p.max_albedo_incidence)?;
        d.set_item("plausible", p.is_plausible())?;
        Ok(d)
    }

    /// The material at `x`, for repeated queries (it remembers the bins it
    /// has reconstructed) and sampling. `blend`: "floor" (the default: the
    /// GP's values lifted softly onto a floor at 0.3 times a convex blend's,
    /// never clamped; what the map shows), "gp" (the GP's own blend, clamped
    /// to >= 0) or "plausible" (the stepped rule's: one pass over the store
    /// when the material is made, none per query).
    #[pyo3(signature = (x, blend = "floor"))]
    fn material(&self, py: Python<'_>, x: &Bound<'_, PyAny>, blend: &str) -> PyResult<PyMaterial> {
        let (x, rule) = (point(x)?, rule_of(blend)?);
        let label = match rule {
            BlendRule::Floor => format!("at {x:?} of {}", self.inner.path().display()),
            rule => format!(
                "at {x:?} of {} ({} blend)",
                self.inner.path().display(),
                rule.name()
            ),
        };
        let b = py.detach(|| self.blend(&x, rule))?;
        Ok(PyMaterial::new(Source::Blend(b), label))
    }

    /// The whole table at `x`, shape (3, n_theta_h, n_theta_d, n_phi_d)
    /// (channel, then MERL's theta_h, theta_d, phi_d): reflectance in 1/sr
    /// with NaN where no material was measured, or with `raw=True` the
    /// values `brdf-atlas reconstruct` writes (MERL's channel scales not
    /// applied, -1 where unmeasured). `blend` as for `material`.
    #[pyo3(signature = (x, raw = false, blend = "floor"))]
    fn table<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        raw: bool,
        blend: &str,
    ) -> PyResult<Bound<'py, PyArray4<f64>>> {
        let (x, rule) = (point(x)?, rule_of(blend)?);
        let t = py.detach(|| {
            let t = self.inner.at(&x, rule)?.table()?;
            Ok::<_, Failure>((t.dims(), table_values(&t, raw)))
        })?;
        Ok(table_array(py, t))
    }

    /// RGB reflectance (1/sr) at `x` for direction pairs: `wi`, `wo` arrays
    /// of shape (n, 3), float32 or float64 (read in place), in the local
    /// frame (z is the normal; need not be normalised). Returns (n, 3)
    /// float64, zero where a direction is at or below the horizon or the bin
    /// was never measured; the nearest bin, as `brdf-atlas eval`. `blend`
    /// as for `material`.
    #[pyo3(signature = (x, wi, wo, blend = "floor"))]
    fn eval<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        blend: &str,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (x, rule) = (point(x)?, rule_of(blend)?);
        let (wi, wo) = (
            Directions::extract(wi, "wi")?,
            Directions::extract(wo, "wo")?,
        );
        let (vi, vo) = (wi.view(), wo.view());
        let out = py.detach(|| {
            check_pairs(vi, vo)?;
            let source = Source::Blend(self.blend(&x, rule)?);
            let out = eval_pairs(&source, vi, vo);
            source.verify()?;
            Ok::<_, Failure>(out)
        })?;
        Ok(rows3(py, out))
    }

    /// The albedo map of a `width` x `height` image of the latent window
    /// `view = (x0, x1, y0, y1)` (default: the box [-1, 1]^2 with a 10%
    /// margin): linear RGB albedo, (height, width, 3) float32, row 0 at the
    /// top (largest y). `samples`: quadrature points per pixel; None means
    /// the library's default, as the command-line `map` draws: the prepared
    /// lattice inside its window (`brdf-atlas prepare`), else a field the
    /// model holds or that was saved beside it (`fit` saves those of the
    /// default view and of [-3, 3]^2) whose domain holds the view, else the
    /// view's own exact or sampled field where it fits its budget, else
    /// 256 samples a pixel; exact, from blended per-material albedos, for
    /// a raw model's GP blend. `blend`: the material each pixel shows,
    /// "floor" (the default, what `material` gives) or "gp" (the plausible
    /// rule has no map). 2-D models only.
    #[pyo3(signature = (width = 256, height = 256, view = None, samples = None, blend = "floor"))]
    fn albedo_map<'py>(
        &self,
        py: Python<'py>,
        width: usize,
        height: usize,
        view: Option<(f64, f64, f64, f64)>,
        samples: Option<usize>,
        blend: &str,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let rule = rule_of(blend)?;
        let view = view.map_or_else(View::default, |(x0, x1, y0, y1)| View { x0, x1, y0, y1 });
        let samples = match samples {
            Some(s) if s == 0 || s > MAX_SAMPLES => {
                return Err(
                    Failure::input(format!("samples = {s}: expected 1 to {MAX_SAMPLES}")).into(),
                );
            }
            s => s,
        };
        let map = py
            .detach(|| {
                self.inner.map(
                    brdf_atlas_core::MapRequest::new(width, height)
                        .view(view)
                        .samples(samples)
                        .rule(rule),
                )
            })
            .map_err(Failure::from)?;
        let flat: Vec<f32> = map.rgb.iter().flatten().copied().collect();
        Ok(Array3::from_shape_vec((map.height, map.width, 3), flat)
            .expect("3 values a pixel")
            .into_pyarray(py))
    }

    /// Where a material lands: `material` is the path of a MERL `.binary`
    /// file of the model's dims, or a table array (3, n_theta_h, n_theta_d,
    /// n_phi_d) of reflectance in 1/sr (NaN where unmeasured), as
    /// `read_merl` returns.
    fn locate(&self, py: Python<'_>, material: &Bound<'_, PyAny>) -> PyResult<Location> {
        let (path, _scratch) = if let Ok(p) = material.extract::<PathBuf>() {
            (p, None)
        } else if material.hasattr("shape")? {
            let table = table_from_array(material, "material")?;
            let n = SCRATCH.fetch_add(1, Ordering::Relaxed);
            let path = std::env::temp_dir().join(format!(
                ".brdf-atlas-locate-{}-{n}.binary",
                std::process::id()
            ));
            py.detach(|| table.write(&path)).map_err(Failure::from)?;
            (path.clone(), Some(Scratch(path)))
        } else {
            return Err(Failure::input(format!(
                "material: expected a MERL file's path or a table array, got {}",
                describe(material)
            ))
            .into());
        };
        let located = py.detach(|| {
            let file = MerlFile::open(&path)?;
            Ok::<_, Failure>(brdf_atlas_core::Located::find(&self.inner, &file)?)
        })?;
        let names = self.inner.names();
        Ok(Location {
            point: located.point,
            rmse: located.rmse,
            spread: located.spread,
            nearest: located
                .nearest
                .iter()
                .map(|&(i, d)| (names[i].clone(), d))
                .collect(),
        })
    }
}
