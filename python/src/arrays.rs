//! Arrays in and out: direction arrays of shape `(n, 3)` (float32 or
//! float64, read in place, whatever their strides), latent points, MERL
//! tables as `(3, n_theta_h, n_theta_d, n_phi_d)` arrays.

use brdf_merl::table::{physical, raw_from_physical};
use brdf_merl::{Dims, INVALID, MerlTable, Vec3};
use numpy::ndarray::{ArrayView2, ArrayView4};
use numpy::{PyReadonlyArray2, PyReadonlyArray4, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::errors::{Failure, Result};

/// A direction array borrowed from Python, in either precision.
pub enum Directions<'py> {
    /// float64.
    F64(PyReadonlyArray2<'py, f64>),
    /// float32.
    F32(PyReadonlyArray2<'py, f32>),
}

/// A view of a direction array, shareable with worker threads.
#[derive(Clone, Copy)]
pub enum DirView<'a> {
    /// float64.
    F64(ArrayView2<'a, f64>),
    /// float32.
    F32(ArrayView2<'a, f32>),
}

impl DirView<'_> {
    /// Number of directions.
    pub fn len(&self) -> usize {
        match self {
            DirView::F64(a) => a.nrows(),
            DirView::F32(a) => a.nrows(),
        }
    }

    /// Direction `k` in double precision.
    #[inline]
    pub fn get(&self, k: usize) -> Vec3 {
        match self {
            DirView::F64(a) => [a[(k, 0)], a[(k, 1)], a[(k, 2)]],
            DirView::F32(a) => [a[(k, 0)] as f64, a[(k, 1)] as f64, a[(k, 2)] as f64],
        }
    }

    /// Row `k`'s first two values (uniform numbers for sampling).
    #[inline]
    pub fn get2(&self, k: usize) -> [f64; 2] {
        match self {
            DirView::F64(a) => [a[(k, 0)], a[(k, 1)]],
            DirView::F32(a) => [a[(k, 0)] as f64, a[(k, 1)] as f64],
        }
    }

    /// The first direction with a NaN or infinite coordinate, as an error
    /// naming the array `name`.
    pub fn check_finite(&self, name: &str) -> Result<()> {
        for k in 0..self.len() {
            let v = self.get(k);
            if !v.iter().all(|c| c.is_finite()) {
                return Err(Failure::input(format!(
                    "{name}[{k}] = [{}, {}, {}]: expected finite direction vectors",
                    v[0], v[1], v[2]
                )));
            }
        }
        Ok(())
    }
}

impl<'py> Directions<'py> {
    /// Borrow `obj` as an `(n, 3)` array of float32 or float64; anything
    /// else that numpy reads as numbers (lists, other dtypes) is converted
    /// to float64 first.
    pub fn extract(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Directions<'py>> {
        Self::extract_cols(obj, name, 3)
    }

    /// [`Directions::extract`] for an `(n, cols)` array.
    pub fn extract_cols(
        obj: &Bound<'py, PyAny>,
        name: &str,
        cols: usize,
    ) -> PyResult<Directions<'py>> {
        if let Ok(a) = obj.extract::<PyReadonlyArray2<'py, f64>>() {
            return Self::checked(Directions::F64(a), name, cols);
        }
        if let Ok(a) = obj.extract::<PyReadonlyArray2<'py, f32>>() {
            return Self::checked(Directions::F32(a), name, cols);
        }
        let py = obj.py();
        let what = describe(obj);
        let converted = py
            .import("numpy")?
            .call_method1("asarray", (obj, "float64"))
            .map_err(|_| {
                Failure::input(format!(
                    "{name}: expected an array of shape (n, {cols}), got {what}"
                ))
            })?;
        match converted.extract::<PyReadonlyArray2<'py, f64>>() {
            Ok(a) => Self::checked(Directions::F64(a), name, cols),
            Err(_) => Err(Failure::input(format!(
                "{name}: expected an array of shape (n, {cols}), got {}",
                describe(&converted)
            ))
            .into()),
        }
    }

    fn checked(d: Directions<'py>, name: &str, cols: usize) -> PyResult<Directions<'py>> {
        let shape = match &d {
            Directions::F64(a) => a.shape().to_vec(),
            Directions::F32(a) => a.shape().to_vec(),
        };
        if shape[1] != cols {
            return Err(Failure::input(format!(
                "{name}: expected an array of shape (n, {cols}), got shape {shape:?}"
            ))
            .into());
        }
        Ok(d)
    }

    /// The view to compute on.
    pub fn view(&self) -> DirView<'_> {
        match self {
            Directions::F64(a) => DirView::F64(a.as_array()),
            Directions::F32(a) => DirView::F32(a.as_array()),
        }
    }
}

/// "an array of shape (2, 4) and dtype int64", "a list", for messages.
pub fn describe(obj: &Bound<'_, PyAny>) -> String {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        let dtype = a
            .dtype()
            .str()
            .map(|s| s.to_string())
            .unwrap_or_else(|_| "?".into());
        return format!("an array of shape {:?} and dtype {dtype}", a.shape());
    }
    match obj.get_type().name() {
        Ok(n) => format!("a {n}"),
        Err(_) => "an object".into(),
    }
}

/// A latent point: a number (q = 1) or a sequence of numbers.
pub fn point(obj: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(v) = obj.extract::<f64>() {
        return Ok(vec![v]);
    }
    obj.extract::<Vec<f64>>().map_err(|_| {
        Failure::input(format!(
            "latent point: expected a sequence of numbers, got {}",
            describe(obj)
        ))
        .into()
    })
}

/// Raw MERL values (channel-major, -1 for unmeasured) as reflectance in
/// 1/sr with NaN for unmeasured; `raw` keeps the file's units.
pub fn table_values(table: &MerlTable, raw: bool) -> Vec<f64> {
    let values = table.raw();
    if raw {
        return values.to_vec();
    }
    let bins = table.dims().bins();
    values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if v < 0.0 {
                f64::NAN
            } else {
                physical(i / bins, v)
            }
        })
        .collect()
}

/// A `(3, n_theta_h, n_theta_d, n_phi_d)` array of reflectance (1/sr, NaN
/// for unmeasured) as a MERL table; `what` names it in messages.
pub fn table_from_array(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<MerlTable> {
    let array: PyReadonlyArray4<'_, f64> = match obj.extract() {
        Ok(a) => a,
        Err(_) => {
            let converted = obj
                .py()
                .import("numpy")?
                .call_method1("asarray", (obj, "float64"));
            match converted
                .as_ref()
                .map(|c| c.extract::<PyReadonlyArray4<'_, f64>>())
            {
                Ok(Ok(a)) => a,
                _ => {
                    return Err(Failure::input(format!(
                        "{what}: expected a float array of shape (3, n_theta_h, n_theta_d, n_phi_d), got {}",
                        describe(obj)
                    ))
                    .into());
                }
            }
        }
    };
    let view: ArrayView4<'_, f64> = array.as_array();
    let s = view.shape();
    if s[0] != 3 {
        return Err(Failure::input(format!(
            "{what}: expected shape (3, n_theta_h, n_theta_d, n_phi_d), got {s:?}"
        ))
        .into());
    }
    let dims = Dims::new(s[1], s[2], s[3]).map_err(Failure::from)?;
    let bins = dims.bins();
    let mut values = Vec::with_capacity(dims.values());
    for (i, &v) in view.iter().enumerate() {
        let (c, bin) = (i / bins, i % bins);
        if v.is_nan() {
            values.push(INVALID);
        } else if v.is_finite() && v >= 0.0 {
            values.push(raw_from_physical(c, v));
        } else {
            let (ih, id, ip) = dims.unbin(bin);
            return Err(Failure::input(format!(
                "{what}[{c}, {ih}, {id}, {ip}] = {v}: expected reflectance >= 0 (1/sr), or NaN where unmeasured"
            ))
            .into());
        }
    }
    Ok(MerlTable::from_raw(dims, values).map_err(Failure::from)?)
}
