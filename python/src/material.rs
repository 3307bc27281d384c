//! `brdf_atlas.Material`: one material ready for point queries and
//! sampling: the blend at a latent point of a model, or a MERL table.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use brdf_atlas_core::{Blend, CoreError, Model};
use brdf_merl::{Dims, MerlTable, Quadrature, Vec3};
use numpy::ndarray::{Array1, Array2, Array4};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray4};
use pyo3::prelude::*;
use rayon::prelude::*;
use self_cell::self_cell;

use crate::arrays::{DirView, Directions, table_values};
use crate::errors::{Failure, Result};
use crate::sampler::{self, Method, Tabulated};

type BlendOf<'a> = Blend<'a>;

/// An (n, 3) float64 array handed to Python.
type Rows<'py> = Bound<'py, PyArray2<f64>>;
/// An (n,) float64 array handed to Python.
type Column<'py> = Bound<'py, PyArray1<f64>>;

self_cell!(
    /// A blend together with the model it borrows.
    pub struct OwnedBlend {
        owner: Arc<Model>,
        #[covariant]
        dependent: BlendOf,
    }
);

/// What a material evaluates.
pub enum Source {
    /// The blend at a latent point of a model (its bins remembered once computed).
    Blend(OwnedBlend),
    /// A MERL table.
    Table(MerlTable),
}

impl Source {
    /// RGB reflectance (1/sr) at a pair of directions: `None` below the
    /// horizon or where unmeasured.
    #[inline]
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Option<[f64; 3]> {
        match self {
            Source::Blend(b) => b.borrow_dependent().eval(wi, wo),
            Source::Table(t) => t.eval(wi, wo),
        }
    }

    /// The whole table in MERL raw units; an error if the model's store
    /// changed on disk while open.
    pub fn table(&self) -> Result<MerlTable, CoreError> {
        match self {
            Source::Blend(b) => b.borrow_dependent().table(),
            Source::Table(t) => Ok(t.clone()),
        }
    }

    /// An error if the model's store changed on disk while open (point
    /// queries read zeros from a truncated store: check after them).
    pub fn verify(&self) -> Result<(), CoreError> {
        match self {
            Source::Blend(b) => b.borrow_owner().verify(),
            Source::Table(_) => Ok(()),
        }
    }

    fn dims(&self) -> Dims {
        match self {
            Source::Blend(b) => b.borrow_owner().dims(),
            Source::Table(t) => t.dims(),
        }
    }
}

/// Directions below which a batch is not split across threads.
const MIN_PARALLEL: usize = 4096;

/// RGB reflectance of every pair, zero where there is none (below the
/// horizon, unmeasured), as an `n x 3` row-major vector.
pub fn eval_pairs(source: &Source, wi: DirView<'_>, wo: DirView<'_>) -> Vec<f64> {
    let mut out = vec![0.0; 3 * wi.len()];
    out.par_chunks_mut(3)
        .with_min_len(MIN_PARALLEL)
        .enumerate()
        .for_each(|(k, o)| {
            if let Some(v) = source.eval(wi.get(k), wo.get(k)) {
                o.copy_from_slice(&v);
            }
        });
    out
}

/// Check two direction arrays for a pairwise call.
pub fn check_pairs(wi: DirView<'_>, wo: DirView<'_>) -> Result<()> {
    if wi.len() != wo.len() {
        return Err(Failure::input(format!(
            "wi and wo: expected arrays of the same shape (n, 3), got {} and {} directions",
            wi.len(),
            wo.len()
        )));
    }
    wi.check_finite("wi")?;
    wo.check_finite("wo")
}

/// An `n x 3` row-major vector as a float64 array.
pub fn rows3<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray2<f64>> {
    let n = v.len() / 3;
    Array2::from_shape_vec((n, 3), v)
        .expect("3 values a row")
        .into_pyarray(py)
}

/// A table's dims and values as [`table_values`] gives them (computed
/// without the GIL), as a `(3, n_theta_h, n_theta_d, n_phi_d)` float64 array.
pub fn table_array<'py>(
    py: Python<'py>,
    (d, values): (Dims, Vec<f64>),
) -> Bound<'py, PyArray4<f64>> {
    Array4::from_shape_vec((3, d.theta_h, d.theta_d, d.phi_d), values)
        .expect("length matches dims")
        .into_pyarray(py)
}

/// One material: the reconstruction at a latent point of a model
/// (`Model.material(x)`) or a MERL file (`Material.from_merl(path)`).
///
/// It evaluates reflectance for direction pairs (reconstructed bins are
/// remembered, so a renderer asking for the same bins again pays once), its
/// whole table, its albedo, and samples outgoing directions by its own lobe.
/// Thread-safe; every long call releases the GIL.
#[pyclass(module = "brdf_atlas", name = "Material", frozen)]
pub struct PyMaterial {
    pub(crate) source: Source,
    pub(crate) label: String,
    tabulated: OnceLock<Tabulated>,
}

impl PyMaterial {
    /// A material from its source; `label` names it in `repr`.
    pub fn new(source: Source, label: String) -> PyMaterial {
        PyMaterial {
            source,
            label,
            tabulated: OnceLock::new(),
        }
    }

    fn table_for(&self, method: Method) -> Option<&Tabulated> {
        match method {
            Method::Cosine => None,
            Method::Tabulated => Some(self.tabulated.get_or_init(|| {
                let source = &self.source;
                Tabulated::new(&|wi, wo| source.eval(wi, wo))
            })),
        }
    }
}

fn method(name: &str) -> Result<Method> {
    Method::parse(name).ok_or_else(|| {
        Failure::input(format!(
            "method {name:?}: expected \"tabulated\" or \"cosine\""
        ))
    })
}

#[pymethods]
impl PyMaterial {
    /// The material of a MERL `.binary` file.
    #[staticmethod]
    fn from_merl(py: Python<'_>, path: PathBuf) -> PyResult<PyMaterial> {
        let table = py
            .detach(|| MerlTable::read(&path))
            .map_err(Failure::from)?;
        Ok(PyMaterial::new(
            Source::Table(table),
            path.display().to_string(),
        ))
    }

    /// The table dims `(n_theta_h, n_theta_d, n_phi_d)`.
    #[getter]
    fn dims(&self) -> (usize, usize, usize) {
        let d = self.source.dims();
        (d.theta_h, d.theta_d, d.phi_d)
    }

    /// RGB reflectance (1/sr) for direction pairs: `wi`, `wo` arrays of
    /// shape (n, 3), float32 or float64, in the local frame (z is the
    /// normal; need not be normalised). Returns (n, 3) float64, zero where a
    /// direction is at or below the horizon or the bin was never measured.
    fn eval<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (wi, wo) = (
            Directions::extract(wi, "wi")?,
            Directions::extract(wo, "wo")?,
        );
        let (vi, vo) = (wi.view(), wo.view());
        let out = py.detach(|| {
            check_pairs(vi, vo)?;
            let out = eval_pairs(&self.source, vi, vo);
            self.source.verify()?;
            Ok::<_, Failure>(out)
        })?;
        Ok(rows3(py, out))
    }

    /// The whole table, shape (3, n_theta_h, n_theta_d, n_phi_d): reflectance
    /// in 1/sr with NaN where unmeasured, or with `raw=True` the values of a
    /// MERL file (MERL's channel scales not applied, -1 where unmeasured).
    #[pyo3(signature = (raw = false))]
    fn table<'py>(&self, py: Python<'py>, raw: bool) -> PyResult<Bound<'py, PyArray4<f64>>> {
        let t = py.detach(|| {
            let t = self.source.table()?;
            Ok::<_, Failure>((t.dims(), table_values(&t, raw)))
        })?;
        Ok(table_array(py, t))
    }

    /// Albedo per channel: `(1/pi)` times the integral of `f cos_i cos_o`
    /// over both hemispheres (a Lambertian `rho / pi` gives `rho`),
    /// integrated over the table's bins with 2 x 2 x 2 points a bin.
    fn albedo(&self, py: Python<'_>) -> PyResult<(f64, f64, f64)> {
        let a = py.detach(|| {
            let t = self.source.table()?;
            Ok::<_, Failure>(Quadrature::dense(t.dims(), 2).albedo(&t))
        })?;
        Ok((a[0], a[1], a[2]))
    }

    /// The analytic fit `brdf-atlas export` makes of this material: glTF's
    /// metallic-roughness BRDF with KHR_materials_specular and
    /// KHR_materials_ior, fitted in the cosine-weighted log-relative table
    /// error plus a lit sphere under the swatch lights (docs/export.md).
    /// Returns a dict of the parameters (`base_color`, `metallic`,
    /// `roughness`, `specular`, `specular_color`, `ior`) and the table
    /// errors of the fit and of the two baselines (`table_error`,
    /// `single_lobe_table_error`, `lambertian_table_error`).
    fn fit_analytic<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let label = self.label.clone();
        let fits = py.detach(|| {
            let t = self.source.table()?;
            brdf_atlas_analytic::fit_as_exported(&t, &label, &brdf_atlas_analytic::SWATCH_LIGHTS)
                .map_err(|e| Failure::input(e.to_string()))
        })?;
        let p = fits.principled.model;
        let d = pyo3::types::PyDict::new(py);
        d.set_item(
            "model",
            <brdf_atlas_analytic::Principled as brdf_atlas_analytic::Analytic>::NAME,
        )?;
        d.set_item(
            "base_color",
            (p.base_color[0], p.base_color[1], p.base_color[2]),
        )?;
        d.set_item("metallic", p.metallic)?;
        d.set_item("roughness", p.roughness)?;
        d.set_item("specular", p.specular)?;
        d.set_item(
            "specular_color",
            (
                p.specular_color[0],
                p.specular_color[1],
                p.specular_color[2],
            ),
        )?;
        d.set_item("ior", p.ior)?;
        d.set_item("table_error", fits.principled.error)?;
        d.set_item("single_lobe_table_error", fits.single_lobe.error)?;
        d.set_item("lambertian_table_error", fits.lambertian.error)?;
        Ok(d)
    }

    /// Draw outgoing directions: `wi` (n, 3), `u` (n, 2) uniform numbers in
    /// [0, 1). `method` is "tabulated" (the material's own lobe, mixed with
    /// 10% cosine sampling; built on first use) or "cosine". Returns `(wo,
    /// pdf, value)`: directions (n, 3), their density per solid angle (n,),
    /// and the reflectance there (n, 3), all zero where `wi` is at or
    /// below the horizon.
    #[pyo3(signature = (wi, u, method = "tabulated"))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
        method: &str,
    ) -> PyResult<(Rows<'py>, Column<'py>, Rows<'py>)> {
        let m = self::method(method)?;
        let wi = Directions::extract(wi, "wi")?;
        let u = Directions::extract_cols(u, "u", 2)?;
        let (vi, vu) = (wi.view(), u.view());
        let (dirs, pdfs, values) = py.detach(|| {
            vi.check_finite("wi")?;
            if vu.len() != vi.len() {
                return Err(Failure::input(format!(
                    "u: expected shape ({}, 2) to match wi, got {} rows",
                    vi.len(),
                    vu.len()
                )));
            }
            let table = self.table_for(m);
            let n = vi.len();
            let mut dirs = vec![0.0; 3 * n];
            let mut pdfs = vec![0.0; n];
            let mut values = vec![0.0; 3 * n];
            dirs.par_chunks_mut(3)
                .zip(pdfs.par_iter_mut())
                .zip(values.par_chunks_mut(3))
                .with_min_len(MIN_PARALLEL)
                .enumerate()
                .for_each(|(k, ((d, p), v))| {
                    let w = vi.get(k);
                    if let Some((wo, pdf)) = sampler::sample(table, w, vu.get2(k)) {
                        d.copy_from_slice(&wo);
                        *p = pdf;
                        if let Some(f) = self.source.eval(w, wo) {
                            v.copy_from_slice(&f);
                        }
                    }
                });
            Ok((dirs, pdfs, values))
        })?;
        Ok((
            rows3(py, dirs),
            Array1::from(pdfs).into_pyarray(py),
            rows3(py, values),
        ))
    }

    /// The density per solid angle (n,) with which `sample(wi, ..., method)`
    /// draws `wo`; zero at or below the horizon.
    #[pyo3(signature = (wi, wo, method = "tabulated"))]
    fn pdf<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        method: &str,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let m = self::method(method)?;
        let (wi, wo) = (
            Directions::extract(wi, "wi")?,
            Directions::extract(wo, "wo")?,
        );
        let (vi, vo) = (wi.view(), wo.view());
        let out = py.detach(|| {
            check_pairs(vi, vo)?;
            let table = self.table_for(m);
            Ok::<_, Failure>(
                (0..vi.len())
                    .into_par_iter()
                    .with_min_len(MIN_PARALLEL)
                    .map(|k| sampler::pdf(table, vi.get(k), vo.get(k)))
                    .collect::<Vec<f64>>(),
            )
        })?;
        Ok(Array1::from(out).into_pyarray(py))
    }

    /// `(eval(wi, wo), pdf(wi, wo, method))` in one call.
    #[pyo3(signature = (wi, wo, method = "tabulated"))]
    fn eval_pdf<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        method: &str,
    ) -> PyResult<(Rows<'py>, Column<'py>)> {
        let m = self::method(method)?;
        let (wi, wo) = (
            Directions::extract(wi, "wi")?,
            Directions::extract(wo, "wo")?,
        );
        let (vi, vo) = (wi.view(), wo.view());
        let (values, pdfs) = py.detach(|| {
            check_pairs(vi, vo)?;
            let table = self.table_for(m);
            let values = eval_pairs(&self.source, vi, vo);
            let pdfs: Vec<f64> = (0..vi.len())
                .into_par_iter()
                .with_min_len(MIN_PARALLEL)
                .map(|k| sampler::pdf(table, vi.get(k), vo.get(k)))
                .collect();
            self.source.verify()?;
            Ok::<_, Failure>((values, pdfs))
        })?;
        Ok((rows3(py, values), Array1::from(pdfs).into_pyarray(py)))
    }

    fn __repr__(&self) -> String {
        format!("<brdf_atlas.Material {}>", self.label)
    }
}
