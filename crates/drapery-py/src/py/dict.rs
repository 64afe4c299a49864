//! `Scene.from_dict`: a Python dict with the TOML's keys, turned into TOML text that the
//! library's loader reads ([`drapery::scene::Scene::from_str`]), so a dict scene is checked
//! exactly as a file and its errors are the same one-line messages.
//!
//! Values: `bool`, `int`, `float`, `str`, dicts (tables) and lists or tuples (arrays); numpy
//! arrays and scalars go through their `tolist()`. `None` is refused (leave the key out for its
//! default). The loader's messages point at lines of the TOML text made here, which the user
//! never sees, so [`crate::messages::without_lines`] takes the line numbers out.

use super::errors::scene_error;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

pub use crate::messages::DICT_PATH;

/// The TOML text of a scene dict: what `Scene.from_dict(d)` reads, to be saved as a scene file
/// (mesh paths are written as given: relative ones are then relative to that file's folder).
/// Raises SceneError as `from_dict` does for values a scene cannot hold; the scene itself is
/// not checked.
#[pyfunction]
pub fn scene_toml(d: &Bound<'_, PyAny>) -> PyResult<String> {
    scene_text(d)
}

/// The TOML text of a scene dict.
pub fn scene_text(d: &Bound<'_, PyAny>) -> PyResult<String> {
    let Ok(d) = d.cast::<PyDict>() else {
        return Err(PyTypeError::new_err(format!(
            "Scene.from_dict takes a dict (the scene file's tables as keys), not {}",
            type_name(d)
        )));
    };
    let table = table(d, "")?;
    toml::to_string(&toml::Value::Table(table))
        .map_err(|e| scene_error(format!("{DICT_PATH}: {e}")))
}

fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// `at.key`, or `key` at the top.
fn join(at: &str, key: &str) -> String {
    if at.is_empty() {
        key.to_string()
    } else {
        format!("{at}.{key}")
    }
}

fn table(d: &Bound<'_, PyDict>, at: &str) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let Ok(key) = k.extract::<String>() else {
            return Err(scene_error(format!(
                "{DICT_PATH}: {}: keys must be strings, got {} {}",
                if at.is_empty() { "top level" } else { at },
                type_name(&k),
                k.repr().map(|r| r.to_string()).unwrap_or_default()
            )));
        };
        let here = join(at, &key);
        t.insert(key, value(&v, &here)?);
    }
    Ok(t)
}

fn value(v: &Bound<'_, PyAny>, at: &str) -> PyResult<toml::Value> {
    use toml::Value;
    if v.is_none() {
        return Err(scene_error(format!(
            "{DICT_PATH}: {at}: None is not a value (leave the key out for its default)"
        )));
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().map(Value::Integer).map_err(|_| {
            scene_error(format!(
                "{DICT_PATH}: {at}: integer {v} does not fit in 64 bits"
            ))
        });
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(Value::Table(table(d, at)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, item) in v.try_iter()?.enumerate() {
            items.push(value(&item?, &format!("{at}[{i}]"))?);
        }
        return Ok(Value::Array(items));
    }
    // numpy arrays and scalars (and anything else that lists itself)
    if v.hasattr("tolist")? {
        let listed = v.call_method0("tolist")?;
        if !listed.is(v) {
            return value(&listed, at);
        }
    }
    Err(scene_error(format!(
        "{DICT_PATH}: {at}: a value of type {} cannot be written in a scene \
         (numbers, strings, booleans, lists and dicts can)",
        type_name(v)
    )))
}
