//! The native part of the `brdf_atlas` Python package, over the core crate:
//! models and their point queries, materials and their sampling, fits,
//! MERL files. The package (`brdf_atlas/__init__.py`) re-exports it; its
//! errors are the classes of `brdf_atlas.errors`.
//!
//! Every call that may take long (opening, reconstructing, evaluating,
//! mapping, locating, fitting, reading and writing files) releases the GIL.

mod arrays;
mod errors;
mod fit;
mod material;
mod model;
mod sampler;

use std::path::PathBuf;

use brdf_merl::MerlTable;
use numpy::PyArray4;
use pyo3::prelude::*;

use crate::errors::Failure;

/// Read and validate a MERL `.binary` file: a (3, n_theta_h, n_theta_d,
/// n_phi_d) float64 array of reflectance in 1/sr (MERL's channel scales
/// applied), NaN where unmeasured. `raw=True` keeps the file's own values
/// (-1 where unmeasured).
#[pyfunction]
#[pyo3(signature = (path, raw = false))]
fn read_merl<'py>(
    py: Python<'py>,
    path: PathBuf,
    raw: bool,
) -> PyResult<Bound<'py, PyArray4<f64>>> {
    let t = py
        .detach(|| {
            let t = MerlTable::read(&path)?;
            Ok::<_, brdf_merl::MerlError>((t.dims(), arrays::table_values(&t, raw)))
        })
        .map_err(Failure::from)?;
    Ok(material::table_array(py, t))
}

/// Write a (3, n_theta_h, n_theta_d, n_phi_d) array of reflectance in
/// 1/sr (NaN where unmeasured) as a MERL `.binary` file, atomically: a
/// temporary file beside `path`, then a rename.
#[pyfunction]
fn write_merl(py: Python<'_>, path: PathBuf, table: &Bound<'_, PyAny>) -> PyResult<()> {
    let table = arrays::table_from_array(table, "table")?;
    py.detach(|| table.write(&path)).map_err(Failure::from)?;
    Ok(())
}

/// The native module `brdf_atlas._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<model::PyModel>()?;
    m.add_class::<model::Location>()?;
    m.add_class::<material::PyMaterial>()?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(read_merl, m)?)?;
    m.add_function(wrap_pyfunction!(write_merl, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("SAMPLER_COSINE_SHARE", sampler::COSINE_SHARE)?;
    Ok(())
}
