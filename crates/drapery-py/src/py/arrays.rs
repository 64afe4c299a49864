//! numpy arrays in and out: `(n, 3)` float64 for positions and velocities, `(m, 3)` int64 for
//! triangles.

use drapery::Vec3;
use numpy::{
    AllowTypeChange, PyArray1, PyArray2, PyArrayLikeDyn, PyArrayMethods, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Vectors as a new `(n, 3)` float64 array.
pub fn vec3_array<'py>(py: Python<'py>, v: &[Vec3]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = v.iter().flat_map(|p| p.to_array()).collect();
    PyArray1::from_vec(py, flat).reshape([v.len(), 3])
}

/// Triangles as a new `(m, 3)` int64 array.
pub fn triangle_array<'py>(py: Python<'py>, t: &[[u32; 3]]) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let flat: Vec<i64> = t.iter().flatten().map(|&i| i as i64).collect();
    PyArray1::from_vec(py, flat).reshape([t.len(), 3])
}

/// An array-like of shape `(n, 3)` (any real dtype, converted to float64) as vectors; a
/// ValueError naming `what` when the shape is not `(n, 3)`.
pub fn vec3s(a: &Bound<'_, PyAny>, n: usize, what: &str) -> PyResult<Vec<Vec3>> {
    let a: PyArrayLikeDyn<'_, f64, AllowTypeChange> = a.extract().map_err(|e| {
        PyValueError::new_err(format!(
            "{what}: expected an array of shape ({n}, 3) of numbers ({e})"
        ))
    })?;
    let shape = a.shape().to_vec();
    if shape != [n, 3] {
        let shown: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
        let shown = match shown.len() {
            1 => format!("({},)", shown[0]),
            _ => format!("({})", shown.join(", ")),
        };
        return Err(PyValueError::new_err(format!(
            "{what}: expected an array of shape ({n}, 3), got shape {shown}"
        )));
    }
    let view = a.as_array();
    Ok((0..n)
        .map(|i| Vec3::new(view[[i, 0]], view[[i, 1]], view[[i, 2]]))
        .collect())
}
