//! The module's exceptions and how library errors become them: the message is always the
//! library's one line.

use pyo3::exceptions::PyException;
use pyo3::prelude::*;

pyo3::create_exception!(
    drapery,
    DraperyError,
    PyException,
    "Base class of drapery's errors."
);
pyo3::create_exception!(
    drapery,
    SceneError,
    DraperyError,
    "A scene (file, dict, mesh) that cannot be loaded; the message names the file and the field."
);
pyo3::create_exception!(
    drapery,
    SimulationError,
    DraperyError,
    "A step that failed (non-finite state, solver failure, blow-up); the simulation is left as \
     it was before that step."
);
pyo3::create_exception!(
    drapery,
    StateError,
    DraperyError,
    "Saved state bytes that are damaged or belong to another scene."
);

/// A scene error.
pub fn scene_error(e: impl std::fmt::Display) -> PyErr {
    SceneError::new_err(e.to_string())
}

/// A simulation error.
pub fn simulation_error(e: impl std::fmt::Display) -> PyErr {
    SimulationError::new_err(e.to_string())
}

/// A state error.
pub fn state_error(e: impl std::fmt::Display) -> PyErr {
    StateError::new_err(e.to_string())
}
