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

/// An array-like of exactly `shape` (any real dtype, converted to float64), its numbers in C
/// order; a ValueError naming `what` when it is not numbers or has another shape.
pub fn floats(a: &Bound<'_, PyAny>, shape: &[usize], what: &str) -> PyResult<Vec<f64>> {
    let expected = shape_text(shape);
    let a: PyArrayLikeDyn<'_, f64, AllowTypeChange> = a.extract().map_err(|e| {
        PyValueError::new_err(format!(
            "{what}: expected an array of shape {expected} of numbers ({e})"
        ))
    })?;
    if a.shape() != shape {
        return Err(PyValueError::new_err(format!(
            "{what}: expected an array of shape {expected}, got shape {}",
            shape_text(a.shape())
        )));
    }
    Ok(a.as_array().iter().copied().collect())
}

/// A shape as Python writes it: `(3,)`, `(5, 3)`.
fn shape_text(shape: &[usize]) -> String {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    match dims.len() {
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    }
}

/// An array-like of shape `(n, 3)` (any real dtype, converted to float64) as vectors; a
/// ValueError naming `what` when the shape is not `(n, 3)`.
pub fn vec3s(a: &Bound<'_, PyAny>, n: usize, what: &str) -> PyResult<Vec<Vec3>> {
    Ok(floats(a, &[n, 3], what)?
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect())
}

/// Numbers as a new 1-D float64 array.
pub fn float_array<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// Indices as a new 1-D int64 array.
pub fn index_array<'py>(
    py: Python<'py>,
    v: impl IntoIterator<Item = i64>,
) -> Bound<'py, PyArray1<i64>> {
    PyArray1::from_iter(py, v)
}
