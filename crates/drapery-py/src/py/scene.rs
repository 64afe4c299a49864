//! `drapery.Scene` and `drapery.load_scene`: a loaded, validated scene (the library's
//! [`Scene`]) with its fingerprint, which saved states are checked against.

use super::dict::{DICT_PATH, scene_text};
use super::errors::scene_error;
use crate::messages::without_lines;
use drapery::fingerprint::fingerprint;
use drapery::scene::Scene;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A scene and what identifies it.
pub struct Loaded {
    /// The library's scene.
    pub scene: Scene,
    /// [`fingerprint`] of the scene text (the file's bytes, as the CLI takes it, or the TOML
    /// made from a dict) and meshes.
    pub fingerprint: u64,
}

/// A loaded and validated scene: its time span, step and cloths. Build simulations from it
/// with `Simulation(scene)`. Immutable.
#[pyclass(module = "drapery", name = "Scene", frozen)]
pub struct PyScene {
    pub loaded: Arc<Loaded>,
}

/// Reads a scene file (TOML) and every mesh it names (relative to the file's folder) and
/// checks everything; raises SceneError with the library's one-line message naming the file
/// and the field.
#[pyfunction]
pub fn load_scene(path: PathBuf) -> PyResult<PyScene> {
    let scene = Scene::load(&path).map_err(scene_error)?;
    // The fingerprint covers the file's bytes, as the CLI's does.
    let text =
        std::fs::read(&path).map_err(|e| scene_error(drapery::Error::io(path.display(), e)))?;
    let fingerprint = fingerprint(&scene, &text);
    Ok(PyScene::new(scene, fingerprint))
}

impl PyScene {
    pub fn new(scene: Scene, fingerprint: u64) -> PyScene {
        PyScene {
            loaded: Arc::new(Loaded { scene, fingerprint }),
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.loaded.scene
    }
}

#[pymethods]
impl PyScene {
    /// A scene from a dict with the scene file's keys, e.g.
    /// `{"simulation": {"duration": 1.0, "dt": 0.01, "frame_rate": 50},
    ///   "cloth": [{"name": "sheet", "grid": {...}, "density": 0.1}]}`.
    /// Checked as a file is (same messages, naming `<dict>`); mesh paths are relative to the
    /// current directory.
    #[staticmethod]
    fn from_dict(d: &Bound<'_, PyAny>) -> PyResult<PyScene> {
        let text = scene_text(d)?;
        let scene = Scene::from_str(&text, Path::new(DICT_PATH))
            .map_err(|e| scene_error(without_lines(&e.to_string(), &text)))?;
        let fingerprint = fingerprint(&scene, text.as_bytes());
        Ok(PyScene::new(scene, fingerprint))
    }

    /// The scene file as given, or `<dict>`.
    #[getter]
    fn path(&self) -> String {
        self.scene().path.display().to_string()
    }

    /// Simulated time span, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.scene().duration
    }

    /// Output frames per simulated second.
    #[getter]
    fn frame_rate(&self) -> f64 {
        self.scene().frame_rate
    }

    /// The step actually taken, s: 1/(frame_rate · steps_per_frame).
    #[getter]
    fn step_size(&self) -> f64 {
        self.scene().step_size()
    }

    /// Steps per output frame.
    #[getter]
    fn steps_per_frame(&self) -> usize {
        self.scene().steps_per_frame()
    }

    /// Frames after frame 0 (a run writes frame_count + 1 frames).
    #[getter]
    fn frame_count(&self) -> usize {
        self.scene().frame_count()
    }

    /// The cloths' names, in scene order.
    #[getter]
    fn cloths(&self) -> Vec<String> {
        self.scene().cloths.iter().map(|c| c.name.clone()).collect()
    }

    /// A 64-bit hash of the scene text and meshes (as `drapery run` computes it); saved
    /// states carry it.
    #[getter]
    fn fingerprint(&self) -> u64 {
        self.loaded.fingerprint
    }

    fn __repr__(&self) -> String {
        let s = self.scene();
        format!(
            "Scene({:?}: {} cloth(s), {} frames of {} step(s) of {} s)",
            self.path(),
            s.cloths.len(),
            s.frame_count(),
            s.steps_per_frame(),
            s.step_size()
        )
    }
}
