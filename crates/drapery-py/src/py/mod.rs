//! The Python module `drapery._drapery`, re-exported by the package `drapery`
//! (python/drapery/__init__.py); its types are in python/drapery/_drapery.pyi.

mod arrays;
mod control;
mod dict;
mod errors;
mod report;
mod run;
mod scene;
mod sim;

/// Cloth simulation (linearized implicit Euler, Baraff & Witkin 1998) from Python.
#[pyo3::pymodule]
mod _drapery {
    #[pymodule_export]
    use super::dict::scene_toml;
    #[pymodule_export]
    use super::errors::{DraperyError, SceneError, SimulationError, StateError};
    #[pymodule_export]
    use super::run::run;
    #[pymodule_export]
    use super::scene::{PyScene, load_scene};
    #[pymodule_export]
    use super::sim::PySimulation;

    use pyo3::prelude::*;

    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        m.add("__version__", env!("CARGO_PKG_VERSION"))
    }
}
