//! `drapery.run(scene, output, formats=["obj"], threads=None, on_frame=None)`: the CLI's
//! `drapery run` from Python (the frame loop of [`crate::frames`]), with the GIL released while
//! stepping and Ctrl-C checked between frames; `on_frame(k, positions)` sees every frame.

use super::arrays::vec3_array;
use super::errors::{scene_error, simulation_error};
use super::scene::{PyScene, load_scene};
use super::sim::pool;
use crate::frames::{FrameFormat, FrameRun, RunError};
use pyo3::exceptions::{PyOSError, PyRuntimeWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyString;
use std::ffi::CString;
use std::path::PathBuf;

/// Runs `f` in `pool`, or here.
fn in_pool<R: Send>(pool: &Option<rayon::ThreadPool>, f: impl FnOnce() -> R + Send) -> R {
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}

fn py_error(e: RunError) -> PyErr {
    match e {
        RunError::Build(_) => scene_error(&e),
        RunError::Step { .. } => simulation_error(&e),
        RunError::Write(_) => PyOSError::new_err(e.to_string()),
    }
}

/// Simulates `scene` (a Scene, or the path of a scene file) and writes every frame into the
/// folder `output` as `drapery run` does: frame_00000.obj (the initial state) to the last
/// frame, byte for byte the CLI's files. `formats`: "obj", "ply" and/or "pc2" (a point cache
/// `<cloth name>.pc2` per cloth, a sample per frame) as a list, or one string "obj,ply".
/// Existing files of the same names are replaced; no resume state is
/// written (use the drapery command for --resume, glb and usd). `on_frame(k, positions)`, when
/// given, is called after frame k is written with its positions (a new float64 array (n, 3),
/// every particle) — the data of the files without reading them back; with `formats=[]` no
/// file is written. Raises SceneError, SimulationError ("frame k: ...; frames 0 to k-1 are in
/// DIR"), OSError, or what `on_frame` raises (the run stops there). Warns (RuntimeWarning,
/// "<scene>: ...") where `drapery run` warns at frame 0: intersections the steps will not
/// untangle, and cloth pairs closer than `collision.thickness`.
#[pyfunction]
#[pyo3(signature = (scene, output, formats = None, threads = None, on_frame = None))]
pub fn run(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    output: PathBuf,
    formats: Option<&Bound<'_, PyAny>>,
    threads: Option<usize>,
    on_frame: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let names: Vec<String> = match formats {
        None => vec!["obj".into()],
        Some(f) if f.is_instance_of::<PyString>() => f
            .extract::<String>()?
            .split(',')
            .map(|s| s.trim().to_string())
            .collect(),
        Some(f) => f.extract()?,
    };
    let formats = if names.is_empty() && on_frame.is_some() {
        Vec::new()
    } else {
        FrameFormat::parse_list(&names).map_err(PyValueError::new_err)?
    };
    let scene: PyScene = match scene.cast::<PyScene>() {
        Ok(s) => PyScene {
            loaded: s.get().loaded.clone(),
        },
        Err(_) => load_scene(scene.extract()?)?,
    };
    let pool = pool(threads)?;
    let s = scene.scene();
    let mut frames = py
        .detach(|| in_pool(&pool, || FrameRun::start(s, &output, &formats)))
        .map_err(py_error)?;
    let seen = |k: usize, frames: &FrameRun| -> PyResult<()> {
        match on_frame {
            Some(f) => f
                .call1((k, vec3_array(py, frames.simulation().positions())?))
                .map(drop),
            None => Ok(()),
        }
    };
    let path = s.path.display().to_string();
    let checked = py.detach(|| in_pool(&pool, || frames.start_check()));
    for w in checked.map(|c| c.warnings()).unwrap_or_default() {
        // (the texts hold no NUL byte, but the path might)
        let text =
            CString::new(format!("{path}: {w}").replace('\0', "")).expect("NUL bytes removed");
        PyErr::warn(py, &py.get_type::<PyRuntimeWarning>(), &text, 1)?;
    }
    seen(0, &frames)?;
    loop {
        py.check_signals()?;
        let next = py
            .detach(|| in_pool(&pool, || frames.next_frame()))
            .map_err(py_error)?;
        match next {
            Some(k) => seen(k, &frames)?,
            None => return Ok(()),
        }
    }
}
